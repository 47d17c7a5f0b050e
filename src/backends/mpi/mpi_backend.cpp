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

// One candidate pair as the ranks send it: i, j, then j's image.
constexpr std::size_t kRecord = 2 * sizeof(std::uint32_t) + 3;

// The distributed backend (issue 17): every rank holds the whole model between steps that need it;
// the step itself is shared by a spatial decomposition (cycle/brick_step.hpp). The search is the
// serial one, shared: each rank searches the pairs whose lower ball i is in its range of indices
// (consecutive ranges, ascending by rank), and every rank joins the ranks' lists in rank order,
// which is the serial list, pair for pair, as the threads' lists are joined in the threaded search.
// The answer is the serial one, bit for bit, for any rank count.
class MpiBackend final : public Backend {
 public:
  std::string name() const override { return "mpi"; }
  void find_pairs(const Model& model, double skin, ThreadPool&, PairCandidates& out) override {
    const int ranks = comm::size(), rank = comm::rank();
    const std::size_t n = model.balls.size();
    PairCandidates& mine = ranks > 1 ? mine_ : out;
    mine.periodic_bins = {};
    auto search = [&] {
      if (rank == fail_search_for_test.load()) {
        fail_search_for_test = -1;
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
      send_.resize(mine.i.size() * kRecord);
    }, "searching its share of the pairs");
    periodic_bins_ = mine.periodic_bins;
    // Every rank's pairs, as records, in rank order.
    const std::size_t m = mine.i.size();
    for (std::size_t p = 0; p < m; ++p) {
      std::uint8_t* r = send_.data() + p * kRecord;
      std::memcpy(r, &mine.i[p], 4);
      std::memcpy(r + 4, &mine.j[p], 4);
      std::memcpy(r + 8, &mine.image_x[p], 1);
      std::memcpy(r + 9, &mine.image_y[p], 1);
      std::memcpy(r + 10, &mine.image_z[p], 1);
    }
    mine.clear();
    comm::allgather(send_, recv_);
    const std::size_t total = recv_.size() / kRecord;
    out.clear();
    out.i.resize(total); out.j.resize(total);
    out.image_x.resize(total); out.image_y.resize(total); out.image_z.resize(total);
    for (std::size_t p = 0; p < total; ++p) {
      const std::uint8_t* r = recv_.data() + p * kRecord;
      std::memcpy(&out.i[p], r, 4);
      std::memcpy(&out.j[p], r + 4, 4);
      std::memcpy(&out.image_x[p], r + 8, 1);
      std::memcpy(&out.image_y[p], r + 9, 1);
      std::memcpy(&out.image_z[p], r + 10, 1);
    }
  }
  bool distributed() const override { return true; }
  std::vector<std::pair<std::string, std::string>> info() const override {
    auto lines = box_info(grid_.dims(), grid_.cell_size(), periodic_bins_);
    lines.emplace_back("pair search", "a stale list on each rank's part (its own balls and the others' within reach "
                                      "of them); through the whole model, shared: each rank searches the pairs of its "
                                      "range of ball indices, and every rank joins the ranks' lists in order (the serial list)");
    lines.emplace_back("decomposition",
                       "recursive bisection of the balls, each rank's share in proportion to its speed; each rank steps "
                       "its own balls with ghost copies of their partners, and keeps them until the whole model is "
                       "stepped through (a ball crossing a periodic face, walls, balls spread far from their part)");
    return lines;
  }

 private:
  BoxGrid grid_;
  std::array<int, 3> periodic_bins_{};   // of the last search, where it was the periodic one
  PairCandidates mine_;
  std::vector<std::uint8_t> send_, recv_;
};

}  // namespace

std::unique_ptr<Backend> make_mpi_backend() { return std::make_unique<MpiBackend>(); }

}  // namespace trubal
