#include "backends/serial/serial_backend.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstring>
#include <string>

#include "backends/pair_list.hpp"
#include "backends/periodic.hpp"
#include "backends/serial/box_grid.hpp"
#include "physics/kernels.hpp"

namespace trubal {
namespace {

class SerialBackend final : public Backend {
 public:
  std::string name() const override { return "serial"; }

  void prepare(Model& model) override {
    if (model.space.periodic) wrap_into_cell(model, &ref_x_, &ref_y_, &ref_z_);
    if (needs_rebuild(model)) rebuild(model);
  }

  void step(Model& model, const StepKernels& kernels, StepSums& sums) override {
    using Clock = std::chrono::steady_clock;
    const auto t0 = Clock::now();
    prepare(model);
    const auto t1 = Clock::now();
    const std::size_t pairs = model.contacts.size(), balls = model.balls.size();
    for (std::size_t begin = 0; begin < pairs; begin += kReduceBlock) {
      StepSums block;
      kernels.contacts(model, kernels, begin, std::min(pairs, begin + kReduceBlock), block);
      sums.add(block);
    }
    const auto t2 = Clock::now();
    for (std::size_t begin = 0; begin < balls; begin += kReduceBlock) {
      StepSums block;
      kernels.motion(model, kernels, begin, std::min(balls, begin + kReduceBlock), block);
      sums.add(block);
    }
    const auto t3 = Clock::now();
    model.timing.detect += std::chrono::duration<double>(t1 - t0).count();
    model.timing.forces += std::chrono::duration<double>(t2 - t1).count();
    model.timing.motion += std::chrono::duration<double>(t3 - t2).count();
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

  bool needs_rebuild(const Model& model) const {
    const Balls& b = model.balls;
    const std::size_t n = b.size();
    if (!valid_ || ref_x_.size() != n || model.contacts.gather_begin.size() != n + 1) return true;
    if (n && std::memcmp(ref_rad_.data(), b.rad.data(), n * sizeof(double)) != 0) return true;
    // Two balls each moving half the skin can just close it.
    // Periodic space: an image pair also closes by the change of the cell edge.
    double cell_change = 0;
    if (model.space.periodic) {
      const auto L = model.space.length();
      for (int a = 0; a < 3; ++a) cell_change = std::max(cell_change, std::abs(L[a] - ref_cell_[a]));
      if (!(cell_change < skin_)) return true;
    }
    const double limit2 = 0.25 * (skin_ - cell_change) * (skin_ - cell_change);
    double moved2 = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const double dx = b.x[i] - ref_x_[i], dy = b.y[i] - ref_y_[i], dz = b.z[i] - ref_z_[i];
      moved2 = std::max(moved2, dx * dx + dy * dy + dz * dz);
    }
    return !(moved2 <= limit2);   // NaN positions rebuild too (and then fail loudly in the guard)
  }

  void rebuild(Model& model) {
    const Balls& b = model.balls;
    const std::size_t n = b.size();
    double rad_sum = 0, rad_max = 0;
    for (double r : b.rad) { rad_sum += r; rad_max = std::max(rad_max, r); }
    skin_ = n ? 0.2 * rad_sum / static_cast<double>(n) : 0;
    if (model.space.periodic) {
      check_periodic_cell(model);
      skin_ = periodic_skin(model, skin_);
      find_periodic_pairs(model, skin_, pairs_);
      ref_cell_ = model.space.length();
    } else {
      grid_.fill(b, 2 * rad_max + skin_, model.space.boxes);
      grid_.find_pairs(b, skin_, pairs_);
    }
    install_pairs(model.contacts, pairs_, n);
    ref_x_ = b.x; ref_y_ = b.y; ref_z_ = b.z; ref_rad_ = b.rad;
    valid_ = true;
    ++rebuilds_;
  }

  BoxGrid grid_;
  PairCandidates pairs_;
  std::vector<double> ref_x_, ref_y_, ref_z_, ref_rad_;
  std::array<double, 3> ref_cell_{0, 0, 0};   // periodic cell edges at the last rebuild
  double skin_ = 0;
  bool valid_ = false;
  std::size_t rebuilds_ = 0;
};

}  // namespace

std::unique_ptr<Backend> make_serial_backend() { return std::make_unique<SerialBackend>(); }

}  // namespace trubal
