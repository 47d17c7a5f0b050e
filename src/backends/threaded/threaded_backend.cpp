#include "backends/threaded/threaded_backend.hpp"

#include <algorithm>
#include <chrono>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>

#include "backends/pair_list.hpp"
#include "backends/periodic_pairs.hpp"
#include "model/periodic_cell.hpp"
#include "backends/threaded/cell_pairs.hpp"
#include "backends/threaded/parallel_step.hpp"
#include "support/thread_pool.hpp"
#include "backends/verlet.hpp"
#include "physics/kernels.hpp"

namespace trubal {
namespace {

// Fewer balls than this are checked for displacement on one thread: waking workers costs more.
constexpr std::size_t kParallelBalls = 8192;

class ThreadedBackend final : public Backend {
 public:
  explicit ThreadedBackend(int threads) : pool_(threads > 0 ? threads : ThreadPool::hardware_threads()) {}

  std::string name() const override { return "threaded"; }
  int threads() const override { return pool_.size(); }

  void prepare(Model& model) override {
    if (model.space.periodic && any_outside(model)) wrap_into_cell(model, &ref_.x, &ref_.y, &ref_.z);
    if (needs_rebuild(model)) rebuild(model);
  }

  void step(Model& model, const StepKernels& kernels, StepSums& sums) override {
    const auto t0 = std::chrono::steady_clock::now();
    prepare(model);
    model.timing.detect += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const bool measure = ref_.x.size() == model.balls.size();
    step_.run(pool_, model, kernels, sums, measure ? &ref_ : nullptr);
    moved_known_ = measure;
  }

  void invalidate() override { ref_.invalidate(); moved_known_ = false; }

  std::vector<std::pair<std::string, std::string>> info() const override {
    auto lines = ref_.info(grid_.dims(), grid_.cell_size());
    const int used = step_.active();
    if (used > 0 && used < pool_.size())
      lines.emplace_back("threads used", std::to_string(used) +
                                             (used > 1 ? " (one per block of 256 balls)"
                                                       : " (the balls fill one block of 256, or sharing the step was "
                                                         "timed no faster: a small scene, or balls near in space far "
                                                         "apart in numbering)"));
    return lines;
  }

 private:
  // Whether a ball left the periodic cell (the test in parallel; the rare wrap itself serial).
  bool any_outside(const Model& model) {
    const std::size_t n = model.balls.size();
    moved_.assign(pool_.size(), 0.0);
    pool_.run([&](int t) {
      moved_[t] = outside_cell(model, split_point(n, pool_.size(), t), split_point(n, pool_.size(), t + 1)) ? 1.0 : 0.0;
    }, n >= kParallelBalls);
    for (double m : moved_)
      if (m != 0) return true;
    return false;
  }

  // The serial backend's rule (backends/verlet.hpp), the largest displacement found in parallel
  // (a max is exact in any order).
  bool needs_rebuild(const Model& model) {
    const double limit2 = ref_.displacement_limit2(model);
    const bool known = moved_known_;   // the last step measured the displacements as it moved the balls
    moved_known_ = false;
    if (!(limit2 >= 0)) return true;
    if (known) return !(step_.moved2() <= limit2);
    const Balls& b = model.balls;
    const std::size_t n = b.size();
    moved_.assign(pool_.size(), 0.0);
    pool_.run([&](int t) {
      moved_[t] = ref_.max_displacement2(b, split_point(n, pool_.size(), t), split_point(n, pool_.size(), t + 1));
    }, n >= kParallelBalls);
    double moved2 = 0;
    for (double m : moved_) moved2 = std::max(moved2, m);
    return !(moved2 <= limit2);
  }

  void rebuild(Model& model) {
    const Balls& b = model.balls;
    double skin = VerletReference::skin_for(b), rad_max = 0;
    for (double r : b.rad) rad_max = std::max(rad_max, r);
    if (model.space.periodic) {   // the serial backend's periodic search (backends/periodic.hpp)
      check_periodic_cell(model);
      skin = periodic_skin(model, skin);
      find_periodic_pairs(model, skin, pairs_, &pool_);
    } else {
      grid_.find(pool_, b, 2 * rad_max + skin, model.space.boxes, skin, pairs_);
    }
    install_pairs(model.contacts, pairs_, b.size());
    ref_.record(model, skin);
  }

  ThreadPool pool_;
  ParallelStep step_;
  CellPairs grid_;
  PairCandidates pairs_;
  VerletReference ref_;
  std::vector<double> moved_;
  bool moved_known_ = false;   // step_.moved2() holds the displacements of the current positions
};
}  // namespace

std::unique_ptr<Backend> make_threaded_backend(int threads) { return std::make_unique<ThreadedBackend>(threads); }

}  // namespace trubal
