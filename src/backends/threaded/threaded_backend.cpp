#include "backends/threaded/threaded_backend.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>

#include "backends/pair_list.hpp"
#include "backends/periodic.hpp"
#include "backends/threaded/cell_pairs.hpp"
#include "backends/threaded/parallel_step.hpp"
#include "backends/threaded/thread_pool.hpp"
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
    if (model.space.periodic) wrap_into_cell(model, &ref_x_, &ref_y_, &ref_z_);
    if (needs_rebuild(model)) rebuild(model);
  }

  void step(Model& model, const StepKernels& kernels, StepSums& sums) override {
    prepare(model);
    step_.run(pool_, model, kernels, sums);
  }

  void invalidate() override { valid_ = false; }

  std::vector<std::pair<std::string, std::string>> info() const override {
    const auto& d = grid_.dims();
    return {{"contact boxes", std::to_string(d[0]) + " x " + std::to_string(d[1]) + " x " + std::to_string(d[2])},
            {"box size", fmt_number(grid_.cell_size())},
            {"pair list skin", fmt_number(skin_)},
            {"pair list rebuilds", std::to_string(rebuilds_)}};
  }

 private:
  static std::string fmt_number(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.4g", v);
    return buf;
  }

  // The serial backend's test, with the largest displacement found in parallel (a max is exact in
  // any order; NaN is skipped by std::max in both).
  bool needs_rebuild(Model& model) {
    const Balls& b = model.balls;
    const std::size_t n = b.size();
    if (!valid_ || ref_x_.size() != n || model.contacts.gather_begin.size() != n + 1) return true;
    if (n && std::memcmp(ref_rad_.data(), b.rad.data(), n * sizeof(double)) != 0) return true;
    // Periodic space: an image pair also closes by the change of the cell edge.
    double cell_change = 0;
    if (model.space.periodic) {
      const auto L = model.space.length();
      for (int a = 0; a < 3; ++a) cell_change = std::max(cell_change, std::abs(L[a] - ref_cell_[a]));
      if (!(cell_change < skin_)) return true;
    }
    const double limit2 = 0.25 * (skin_ - cell_change) * (skin_ - cell_change);
    moved_.assign(pool_.size(), 0.0);
    pool_.run([&](int t) {
      double moved2 = 0;
      for (std::size_t i = split_point(n, pool_.size(), t), e = split_point(n, pool_.size(), t + 1); i < e; ++i) {
        const double dx = b.x[i] - ref_x_[i], dy = b.y[i] - ref_y_[i], dz = b.z[i] - ref_z_[i];
        moved2 = std::max(moved2, dx * dx + dy * dy + dz * dz);
      }
      moved_[t] = moved2;
    }, n >= kParallelBalls);
    double moved2 = 0;
    for (double m : moved_) moved2 = std::max(moved2, m);
    return !(moved2 <= limit2);
  }

  void rebuild(Model& model) {
    const Balls& b = model.balls;
    const std::size_t n = b.size();
    double rad_sum = 0, rad_max = 0;
    for (double r : b.rad) { rad_sum += r; rad_max = std::max(rad_max, r); }
    skin_ = n ? 0.2 * rad_sum / static_cast<double>(n) : 0;
    if (model.space.periodic) {   // the serial backend's periodic search (backends/periodic.hpp)
      check_periodic_cell(model);
      skin_ = periodic_skin(model, skin_);
      find_periodic_pairs(model, skin_, pairs_);
      ref_cell_ = model.space.length();
    } else {
      grid_.find(pool_, b, 2 * rad_max + skin_, skin_, pairs_);
    }
    install_pairs(model.contacts, pairs_, n);
    ref_x_ = b.x; ref_y_ = b.y; ref_z_ = b.z; ref_rad_ = b.rad;
    valid_ = true;
    ++rebuilds_;
  }

  ThreadPool pool_;
  ParallelStep step_;
  CellPairs grid_;
  PairCandidates pairs_;
  std::vector<double> ref_x_, ref_y_, ref_z_, ref_rad_, moved_;
  std::array<double, 3> ref_cell_{0, 0, 0};   // periodic cell edges at the last rebuild
  double skin_ = 0;
  bool valid_ = false;
  std::size_t rebuilds_ = 0;
};

}  // namespace

std::unique_ptr<Backend> make_threaded_backend(int threads) { return std::make_unique<ThreadedBackend>(threads); }

}  // namespace trubal
