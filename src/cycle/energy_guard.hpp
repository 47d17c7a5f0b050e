// The instability guard of a CYCLE (doc/physics.md "Instability guard"): the energy balance at the
// force pass of the steps it checks against the energy in play, the stop where energy is created,
// its message and the advice that comes with it, and the warning a CYCLE ends with where the
// balance drifted.
#pragma once

#include <array>
#include <cstdint>
#include <string>

#include "cycle/kernels.hpp"
#include "cycle/run.hpp"
#include "model/model.hpp"

namespace trubal {

// What the guard saw at the step it stopped: read before the rescue puts the model back.
struct GuardStop {
  std::int64_t bad_cycle = 0;   // the cycle the failed step reached
  std::int64_t fastest_id = 0;  // the fastest ball's id, and its speed
  double fastest_speed = 0;
  std::string what;             // what grew, and how fast
  double over = 1;              // how far beyond the stable step the growth says the step was
};

class EnergyGuard {
 public:
  // The regular checks: the steps that reach a cycle of the model's count on kCheckEvery (the same
  // steps however a run is cut). The CYCLE's run also has the guard check its first step and each
  // step whose state is written or kept (cycle/run.cpp, StepPlan::energies).
  static constexpr std::int64_t kCheckEvery = 8;
  // One check: the CYCLE's step and the balance's distance from its start there.
  struct Check {
    std::int64_t s = 0;
    double drift = 0;
  };
  // The works at the CYCLE's start, and the floor below which nothing is reported (the energy of
  // springs compressed by 1e-6 of a radius: a scene at rest has almost no energy, and rounding
  // alone then looks like a large relative imbalance; an unstable step passes it within a few
  // steps).
  explicit EnergyGuard(const Model& model);
  double floor() const { return floor_; }
  // After the CYCLE's step s (from 1), one that formed the energy terms (the first step always
  // does): books the balance's largest distance from the first step's and the energy in play in
  // `result`; true where the run must stop.
  bool failed(const Model& model, const StepTotals& sums, std::int64_t s, CycleResult& result);
  // After a step that formed the kinetic terms alone (the one before a regular check), which
  // reached `cycle`.
  void note_kinetic(const StepTotals& sums, std::int64_t cycle) {
    last_kinetic_ = sums.kinetic_translation + sums.kinetic_rotation;
    last_kinetic_cycle_ = cycle;
  }
  // The stop failed() called for (model and sums of that step).
  GuardStop stop(const Model& model, const StepTotals& sums, std::int64_t s) const;
  // The message of the stop, once the rescue has put the model back (results_current: its contact
  // results are those of the state it is in), with the FRAC or TSTEP to try.
  std::string message(const GuardStop& stop, const Model& model, bool results_current) const;

 private:
  static constexpr int kGrowthSteps = 32;     // steps looked back over to measure the energy's growth
  // Regular checks running at which the kinetic term was negative, and at the step before each,
  // that stop the run (over 26 steps: a stable step's kinetic term is negative at one step of each
  // turn of a vibration, never two running).
  static constexpr int kFlippingChecks = 4;
  double floor_ = 0;
  double friction0_ = 0, damping0_ = 0, boundary0_ = 0, capillary0_ = 0, bond_break0_ = 0, gross0_ = 0;   // the works at the start
  double balance_ref_ = 0, potential_ref_ = 0;   // the first step's balance and potential
  double scale_max_ = 0;    // the most energy in play so far
  double in_play_max_ = 0;  // and with the balls' kinetic energy relative to moving walls
  double drift_ = 0;        // the last step's distance from the first step's balance
  int flipping_ = 0;        // regular checks running with a negative kinetic term (and the step before)
  double last_kinetic_ = 0;             // the kinetic term of the last step that formed it
  std::int64_t last_kinetic_cycle_ = -1;   // and the cycle that step reached
  // The last checks (a ring; every step may be one), over the last kGrowthSteps steps: how fast the
  // energy grows when the guard stops the run.
  std::array<Check, kGrowthSteps> recent_{};
  std::size_t checks_ = 0;   // checks so far
};

// The CYCLE's balance error against the energy that moved (CycleResult::energy_warning): empty
// where it stayed below kBalanceWarning of it (or below the floor).
std::string balance_warning(const Model& model, const CycleResult& r, double energy_floor);

}  // namespace trubal
