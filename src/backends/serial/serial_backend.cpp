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
    if (!(limit2 >= 0) || !(ref_.max_displacement2(model.balls, 0, model.balls.size()) <= limit2)) rebuild(model);
  }

  void step(Model& model, const StepKernels& kernels, StepSums& sums) override {
    using Clock = std::chrono::steady_clock;
    const auto t0 = Clock::now();
    prepare(model);
    const auto t1 = Clock::now();
    const std::size_t pairs = model.contacts.size(), balls = model.balls.size();
    // One thread, pairs in list order: each pair adds itself to its balls' sums as it goes.
    ContactTable& c = model.contacts;
    std::fill(c.ball_force.begin(), c.ball_force.end(), PairForce{});
    std::fill(c.ball_cn.begin(), c.ball_cn.end(), 0.0);
    for (std::size_t begin = 0; begin < pairs; begin += kReduceBlock) {
      StepSums block;
      kernels.contacts_sum(model, kernels, begin, std::min(pairs, begin + kReduceBlock), block);
      sums.add(block);
    }
    const auto t2 = Clock::now();
    for (std::size_t begin = 0; begin < balls; begin += kReduceBlock) {
      StepSums block;
      kernels.motion_summed(model, kernels, begin, std::min(balls, begin + kReduceBlock), block);
      sums.add(block);
    }
    const auto t3 = Clock::now();
    model.timing.detect += std::chrono::duration<double>(t1 - t0).count();
    model.timing.forces += std::chrono::duration<double>(t2 - t1).count();
    model.timing.motion += std::chrono::duration<double>(t3 - t2).count();
  }

  void invalidate() override { ref_.invalidate(); }

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

  BoxGrid grid_;
  PairCandidates pairs_;
  VerletReference ref_;
};

}  // namespace

std::unique_ptr<Backend> make_serial_backend() { return std::make_unique<SerialBackend>(); }

}  // namespace trubal
