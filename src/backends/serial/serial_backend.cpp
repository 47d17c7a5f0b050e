#include "backends/serial/serial_backend.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstring>
#include <string>

#include "backends/pair_list.hpp"
#include "backends/periodic_pairs.hpp"
#include "model/periodic_cell.hpp"
#include "backends/serial/box_grid.hpp"
#include "backends/threaded/parallel_step.hpp"
#include "support/thread_pool.hpp"
#include "backends/verlet.hpp"
#include "physics/kernels.hpp"

namespace trubal {
namespace {

class SerialBackend final : public Backend {
 public:
  std::string name() const override { return "serial"; }

  void prepare(Model& model) override {
    if (model.space.periodic) wrap_into_cell(model, &ref_.x, &ref_.y, &ref_.z);
    const double limit2 = ref_.displacement_limit2(model);
    // The last step measured the displacements as it moved the balls (ParallelStep::moved2).
    const bool known = moved_known_;
    moved_known_ = false;
    if (!(limit2 >= 0)) { rebuild(model); return; }
    const double moved2 = known ? step_.moved2() : ref_.max_displacement2(model.balls, 0, model.balls.size());
    if (!(moved2 <= limit2)) rebuild(model);
  }

  void step(Model& model, const StepKernels& kernels, StepSums& sums) override {
    const auto t0 = std::chrono::steady_clock::now();
    prepare(model);
    model.timing.detect += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const bool measure = ref_.x.size() == model.balls.size();
    step_.run(pool_, model, kernels, sums, measure ? &ref_ : nullptr);   // one thread: pairs in list order, then balls
    moved_known_ = measure;
  }

  void invalidate() override { ref_.invalidate(); moved_known_ = false; }

  std::vector<std::pair<std::string, std::string>> info() const override {
    return ref_.info(grid_.dims(), grid_.cell_size());
  }

 private:
  void rebuild(Model& model) {
    const Balls& b = model.balls;
    double skin = VerletReference::skin_for(b), rad_max = 0;
    for (double r : b.rad) rad_max = std::max(rad_max, r);
    if (model.space.periodic) {
      check_periodic_cell(model);
      skin = periodic_skin(model, skin);
      find_periodic_pairs(model, skin, pairs_);
    } else {
      grid_.fill(b, 2 * rad_max + skin, model.space.boxes);
      grid_.find_pairs(b, skin, pairs_);
    }
    install_pairs(model.contacts, pairs_, b.size());
    ref_.record(model, skin);
  }

  ThreadPool pool_{1};
  bool moved_known_ = false;   // step_.moved2() holds the displacements of the current positions
  ParallelStep step_;
  BoxGrid grid_;
  PairCandidates pairs_;
  VerletReference ref_;
};

}  // namespace

std::unique_ptr<Backend> make_serial_backend() { return std::make_unique<SerialBackend>(); }

}  // namespace trubal
