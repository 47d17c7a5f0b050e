#include "backends/mpi/mpi_backend.hpp"

#include <string>

#include "backends/serial/serial_backend.hpp"

namespace trubal {
namespace {

// Step 1 of the distributed backend (issue 17): every rank holds the whole model (replicated
// data) and finds every pair; each rank computes the contacts and motion of its own range of
// balls, and the ranks exchange the results after every step. The answer is the serial one, bit
// for bit, for any rank count. Not yet: a spatial decomposition with ghosts (memory per rank).
class MpiBackend final : public Backend {
 public:
  std::string name() const override { return "mpi"; }
  void find_pairs(const Model& model, double skin, ThreadPool& pool, PairCandidates& out) override {
    search_->find_pairs(model, skin, pool, out);
  }
  bool distributed() const override { return true; }
  std::vector<std::pair<std::string, std::string>> info() const override {
    auto lines = search_->info();
    lines.emplace_back("decomposition", "contiguous ranges of balls (by id), balanced by pair count; every rank holds "
                                        "the whole model and finds every pair (replicated data)");
    return lines;
  }

 private:
  std::unique_ptr<Backend> search_ = make_serial_backend();
};

}  // namespace

std::unique_ptr<Backend> make_mpi_backend() { return std::make_unique<MpiBackend>(); }

}  // namespace trubal
