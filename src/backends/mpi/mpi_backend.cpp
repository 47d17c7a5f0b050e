#include "backends/mpi/mpi_backend.hpp"

#include <cstring>
#include <new>
#include <string>

#include "backends/serial/serial_backend.hpp"
#include "support/comm.hpp"
#include "support/format_number.hpp"
#include "support/thread_pool.hpp"

namespace trubal {
namespace {

// The distributed backend (BACKEND mpi, doc/distributed.md): every rank holds the whole model between steps that need it;
// the step itself is shared by a spatial decomposition (cycle/brick_step.hpp), whose parts rebuild
// their own lists (Backend::find_part_pairs). A search through the whole model is the serial one, shared: each rank searches the pairs whose lower ball i is in its range of indices
// (consecutive ranges, ascending by rank), and every rank joins the ranks' lists in rank order,
// which is the serial list, pair for pair, as the threads' lists are joined in the threaded search.
// The answer is the serial one, bit for bit, for any rank count.
class MpiBackend final : public Backend {
 public:
  explicit MpiBackend(int* fail_search) : fail_search_(fail_search) {}
  std::string name() const override { return "mpi"; }
  void find_pairs(const Model& model, double skin, ThreadPool&, PairCandidates& out) override {
    const int ranks = comm::size(), rank = comm::rank();
    const std::size_t n = model.balls.size();
    PairCandidates& mine = ranks > 1 ? mine_ : out;
    mine.periodic_bins = {};
    auto search = [&] {
      if (fail_search_ && rank == *fail_search_) {   // (a rank's test fault)
        *fail_search_ = -1;
        throw std::bad_alloc();
      }
      find_serial_pairs(model, skin, grid_, mine, split_point(n, ranks, rank), split_point(n, ranks, rank + 1));
    };
    if (ranks == 1) {
      search();
      periodic_bins_ = mine.periodic_bins;
      return;
    }
    // (A rank that fails its share alone must not leave the others waiting in the gather below.)
    comm::together([&] {
      search();
      send_.resize(mine.i.size() * kPairRecord);
    }, "searching its share of the pairs");
    periodic_bins_ = mine.periodic_bins;
    // Every rank's pairs, as records, in rank order.
    const std::size_t m = mine.i.size();
    for (std::size_t p = 0; p < m; ++p)
      write_pair_record(send_.data() + p * kPairRecord, mine.i[p], mine.j[p], mine.image_x[p], mine.image_y[p], mine.image_z[p]);
    mine.clear();
    comm::allgather(send_, recv_);
    read_pair_records(recv_, out);
    // (Searches through the whole model are rare where the parts rebuild their lists: the
    // buffers' memory goes back rather than stand beside the parts.)
    for (auto* v : {&send_, &recv_}) std::vector<std::uint8_t>().swap(*v);
    mine_ = PairCandidates{};
  }
  bool distributed() const override { return true; }
  std::vector<std::pair<std::string, std::string>> info() const override {
    auto lines = box_info(grid_.dims(), grid_.cell_size(), periodic_bins_);
    lines.emplace_back("pair search", "a stale list on each rank's part (its own balls and the others' within reach "
                                      "of them); through the whole model, shared: each rank searches the pairs of its "
                                      "range of ball indices, and every rank joins the ranks' lists in order (the serial list)");
    lines.emplace_back("decomposition",
                       "recursive bisection of the balls, each rank's share in proportion to its speed; each rank steps "
                       "its own balls with ghost copies of their partners, and keeps them, between CYCLEs too, until the "
                       "whole model is stepped through or handed to every rank (an edit, a START box's escape, balls "
                       "spread far from their parts, the ranks' speeds drifting from their shares, the balls put in "
                       "space order)");
    return lines;
  }

 private:
  int* fail_search_;
  BoxGrid grid_;
  std::array<int, 3> periodic_bins_{};   // of the last search, where it was the periodic one
  PairCandidates mine_;
  std::vector<std::uint8_t> send_, recv_;
};

}  // namespace

std::unique_ptr<Backend> make_mpi_backend(int* fail_search) { return std::make_unique<MpiBackend>(fail_search); }

}  // namespace trubal
