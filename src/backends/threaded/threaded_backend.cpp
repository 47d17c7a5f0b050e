#include "backends/threaded/threaded_backend.hpp"

#include "backends/periodic_pairs.hpp"
#include "backends/threaded/cell_pairs.hpp"
#include "support/format_number.hpp"

namespace trubal {
namespace {

class ThreadedBackend final : public Backend {
 public:
  std::string name() const override { return "threaded"; }

  void find_pairs(const Model& model, double skin, ThreadPool& pool, PairCandidates& out) override {
    const Balls& b = model.balls;
    periodic_bins_ = {};
    if (model.space.periodic) {
      find_periodic_pairs(model, skin, out, &pool);
      periodic_bins_ = out.periodic_bins;
      return;
    }
    grid_.find(pool, b, 2 * b.max_radius() + skin, model.space.boxes, skin, out);
  }

  std::vector<std::pair<std::string, std::string>> info() const override { return box_info(grid_.grid().dims(), grid_.grid().cell_size(), periodic_bins_); }

 private:
  CellPairs grid_;
  std::array<int, 3> periodic_bins_{};   // of the last search, where it was the periodic one
};

}  // namespace

std::unique_ptr<Backend> make_threaded_backend() { return std::make_unique<ThreadedBackend>(); }

}  // namespace trubal
