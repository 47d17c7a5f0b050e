#include "backends/mpi/mpi_backend.hpp"

#include <string>

#include "backends/serial/serial_backend.hpp"

namespace trubal {
namespace {

// The distributed backend (issue 17): every rank holds the whole model between steps that need it
// and finds every pair (the serial search); the step itself is shared by a spatial decomposition
// (cycle/brick_step.hpp). The answer is the serial one, bit for bit, for any rank count.
class MpiBackend final : public Backend {
 public:
  std::string name() const override { return "mpi"; }
  void find_pairs(const Model& model, double skin, ThreadPool& pool, PairCandidates& out) override {
    search_->find_pairs(model, skin, pool, out);
  }
  bool distributed() const override { return true; }
  std::vector<std::pair<std::string, std::string>> info() const override {
    auto lines = search_->info();
    lines.emplace_back("decomposition",
                       "recursive bisection of the balls by count, made again at every pair-list rebuild; each rank "
                       "steps its own balls with ghost copies of their partners");
    return lines;
  }

 private:
  std::unique_ptr<Backend> search_ = make_serial_backend();
};

}  // namespace

std::unique_ptr<Backend> make_mpi_backend() { return std::make_unique<MpiBackend>(); }

}  // namespace trubal
