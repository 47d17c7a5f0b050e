// The instability guard (cycle/energy_guard.hpp).
#include "cycle/energy_guard.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "physics/timestep.hpp"

namespace trubal {
namespace {

double resting_energy_floor(const Model& model) {
  double sum = 0;
  const Balls& b = model.balls;
  for (std::size_t k = 0; k < b.size(); ++k) {
    auto it = model.materials.find(b.type[k]);
    if (it == model.materials.end()) continue;
    const Material& m = it->second;
    const double stiffness = m.hertz() ? m.shear_modulus * b.rad[k] : m.kn;   // force per length
    const double u = 1e-6 * b.rad[k];
    sum += 0.5 * stiffness * u * u;
  }
  return sum;
}

// How fast the balance grew over the last steps before the guard stopped step s (`recent`, a ring
// of its distances from the start at the last `count` checks; `now`, step s's): an unstable mode
// of central differences grows by a factor mu a step in amplitude, mu^2 in energy, where
// (omega dt)^2 = 2 + mu + 1/mu, so the step was omega dt / 2 times the stable one (`over`; 1
// where no growth is seen).
struct Growth {
  int steps = 0;
  double grew = 0, factor = 1, over = 1;
};
template <std::size_t N>
Growth energy_growth(const std::array<EnergyGuard::Check, N>& recent, std::size_t count, std::int64_t s, double now,
                     double floor) {
  Growth g;
  if (!std::isfinite(now) || !(now > floor)) return g;
  // The earliest of the checks in the last N steps whose distance was above the floor (and a
  // trillionth of now).
  for (std::size_t c = count > N ? count - N : 0; c < count; ++c) {
    const EnergyGuard::Check& check = recent[c % N];
    const std::int64_t back = s - check.s;
    if (back < 1 || back >= static_cast<std::int64_t>(N)) continue;
    const double then = check.drift;
    if (!(then > floor) || !(then > 1e-12 * now) || !(then < now)) continue;
    g.steps = static_cast<int>(back);
    g.grew = now - then;
    g.factor = std::pow(now / then, 1.0 / static_cast<double>(back));
    const double mu = std::sqrt(g.factor);
    g.over = std::max(1.0, 0.5 * std::sqrt(2 + mu + 1 / mu));
    return g;
  }
  return g;
}

}  // namespace

EnergyGuard::EnergyGuard(const Model& model)
    : floor_(resting_energy_floor(model)),
      friction0_(model.energy.friction_work + model.energy.rolling_work),
      damping0_(model.energy.damping_work),
      boundary0_(model.energy.boundary_work),
      capillary0_(model.energy.capillary_work),
      bond_break0_(model.energy.bond_break_work),
      gross0_(model.space.gross_work) {}

// Energy in must balance energy out. A step beyond the stability limit creates energy from
// nothing; when that is half of all the energy in play, the run stops. The balance alone cannot see
// an instability of the linear springs: central differences keep m v(t-dt/2).v(t+dt/2)/2 plus the
// springs' energy even as the velocities flip sign and grow, the kinetic term going negative, and
// sliding contacts can hold such a flipping motion at a bounded size. So the run also stops where
// the kinetic term stays negative: at kFlippingChecks regular checks running, and at the step
// before each (for a stable step it is negative only at the step that straddles a turning point of
// a vibration, one step of each half period, so never at two steps running for one vibration; a
// check alone, every kCheckEvery steps, would see the same phase of a vibration whose period
// divides kCheckEvery steps at every check).
// The guard checks only the steps that formed the energy terms (cycle/run.cpp, StepPlan::energies):
// an unstable step, whose energy grows by a factor a step, is seen at most kCheckEvery - 1 steps
// later than at a check of every step.
bool EnergyGuard::failed(const Model& model, const StepTotals& sums, std::int64_t s, CycleResult& result) {
  // The balance at t, the time of this step's force pass.
  const EnergyAtStep& now = model.energy_at_step;
  const double kinetic = now.kinetic_translation + now.kinetic_rotation;
  const double dissipated = model.energy.friction_work + model.energy.rolling_work - friction0_ +
                            model.energy.damping_work - damping0_ - now.damping_ahead +
                            model.energy.bond_break_work - bond_break0_;
  // (The bridges' work is energy in, as the boundary's.)
  const double boundary = model.energy.boundary_work - boundary0_ - now.boundary_ahead +
                          (model.energy.capillary_work - capillary0_ - now.capillary_ahead);
  if (s == 1) potential_ref_ = sums.potential;
  const double potential = sums.potential - potential_ref_;
  const double balance = kinetic + sums.strain + potential + dissipated - boundary;
  if (s == 1) balance_ref_ = balance;
  // (|kinetic|: the kinetic term is negative in a step where the velocities turn.)
  const double scale = std::abs(kinetic) + sums.strain + std::abs(potential) + std::abs(dissipated) +
                       std::abs(boundary) + (model.space.gross_work - gross0_);
  // Against the most energy in play so far: a bouncing ball at the top of its flight has little
  // energy, while the contact it left (a few coarse steps) may have shifted the balance a little.
  scale_max_ = std::max(scale_max_, scale);
  result.balance_error = std::max(result.balance_error, std::abs(balance - balance_ref_));
  result.energy_scale = scale_max_;
  // A contact that forms between two steps makes an error of up to (omega dt)^2 / 4 of the
  // kinetic energy of the approach (doc/physics.md "Energy"). The lab frame holds that energy where
  // the ball moves, but not where a wall moves into balls at rest: the same collision seen from
  // the wall, whose infinite mass carries the energy no term above counts. So the guard also
  // counts the touching balls' kinetic energy in the frame of each moving wall.
  double wall_relative = 0;
  for (const Wall& w : model.walls) wall_relative += w.relative_kinetic;
  in_play_max_ = std::max(in_play_max_, scale + wall_relative);
  if (model.cycle % kCheckEvery == 0) {
    const bool flipped = kinetic < -floor_ && last_kinetic_cycle_ == model.cycle - 1 && last_kinetic_ < -floor_;
    flipping_ = flipped ? flipping_ + 1 : 0;
  }
  note_kinetic(sums, model.cycle);
  drift_ = std::abs(balance - balance_ref_);
  recent_[checks_ % kGrowthSteps] = {s, drift_};
  ++checks_;
  return !std::isfinite(balance) || drift_ > 0.5 * in_play_max_ + floor_ || flipping_ >= kFlippingChecks;
}

GuardStop EnergyGuard::stop(const Model& model, const StepTotals& sums, std::int64_t s) const {
  GuardStop g;
  const std::size_t ball = sums.fastest_ball < model.balls.size() ? sums.fastest_ball : 0;
  g.fastest_id = model.balls.size() ? model.balls.id[ball] : 0;
  g.fastest_speed = std::sqrt(sums.fastest_speed2);
  g.bad_cycle = model.cycle;
  const Growth growth = energy_growth(recent_, checks_, s, drift_, floor_);
  g.over = growth.over;
  if (growth.steps > 0 && growth.factor > 1.001) {
    g.what = fmt::format("energy was created: the balance grew by {:.3g} ({:.3g}% of the energy in play) over the "
                         "last {} cycles",
                         growth.grew, in_play_max_ > 0 ? 100 * growth.grew / in_play_max_ : 0.0, growth.steps);
    if (growth.factor > 1.05)   // a clear exponential: a mode beyond the stable step
      g.what += fmt::format(", {:.3g} times a cycle, as a step about {:.2g} times the stable one makes it",
                            growth.factor, growth.over);
  } else if (flipping_ >= kFlippingChecks) {
    g.what = fmt::format("the velocities flip sign every cycle (the kinetic term m v(t-dt/2).v(t+dt/2)/2 was "
                         "negative at two cycles running, {} times over {} cycles), as a step beyond the stable "
                         "one makes them",
                         kFlippingChecks, (kFlippingChecks - 1) * kCheckEvery + 2);
  } else {
    g.what = "energy was created";
  }
  g.what += fmt::format(" (the fastest ball is {}, at {:.3g})", g.fastest_id, g.fastest_speed);
  return g;
}

std::string EnergyGuard::message(const GuardStop& stop, const Model& model, bool results_current) const {
  const double frac = model.settings.frac;
  // The step to take: beyond the stable step by stop.over, and by half again (0.5 at most).
  const double shrink = std::min(0.5, 0.8 / stop.over);
  std::string advice;
  if (model.settings.fixed_dt > 0)
    advice = fmt::format("try TSTEP {:.3g} (now {:.3g}; critical step about {:.3g})",
                         std::min(0.5 * critical_timestep(model), shrink * model.settings.fixed_dt),
                         model.settings.fixed_dt, critical_timestep(model));
  else
    advice = frac < 1e-3
                 ? fmt::format("FRAC is {:.3g} already, so the step is not the cause: look at the loads, "
                               "velocities, properties and the servo's rates", frac)
                 : fmt::format("try FRAC {:.2g} (now {:.3g})", std::min(0.8, shrink * frac), frac);
  return fmt::format("unstable at cycle {}: {}; the model is back at cycle {}, its last good state{}; {}",
                     stop.bad_cycle, stop.what, model.cycle,
                     results_current ? "" : " (its contact forces were not kept: CYCLE computes them)", advice);
}

// Above kBalanceWarning of the energy that moved, the step is too coarse for what happened, mostly
// contacts that formed and broke within a few steps (impacts). The error of a collision falls as
// the step squared (doc/physics.md "Energy"), so the FRAC that would have held it is about
// FRAC sqrt(kBalanceWarning / error), taken at half that error for the scatter a collision's phase
// against the steps gives.
std::string balance_warning(const Model& model, const CycleResult& r, double energy_floor) {
  if (!(r.energy_scale > 0) || !(r.balance_error > kBalanceWarning * r.energy_scale) ||
      !(r.balance_error > energy_floor))
    return {};
  const double error = r.balance_error / r.energy_scale;
  const double shrink = std::sqrt(0.5 * kBalanceWarning / error);
  const std::string advice =
      model.settings.fixed_dt > 0
          ? fmt::format("TSTEP {:.2g} (now {:.3g})", model.settings.fixed_dt * shrink, model.settings.fixed_dt)
          : fmt::format("FRAC {:.2g} (now {:.3g})", model.settings.frac * shrink, model.settings.frac);
  return fmt::format(
      "the energy balance of this CYCLE was off by {:.3g}% of the energy that moved ({:.3g} of {:.3g}): the step is "
      "too coarse for contacts that form and break within a few steps (impacts); {} would hold it to {:.3g}%",
      100 * error, r.balance_error, r.energy_scale, advice, 100 * kBalanceWarning);
}

}  // namespace trubal
