// The loop over steps, its time step and its guard (cycle/run.hpp).
#include "cycle/run.hpp"

#include <chrono>
#include <cmath>
#include <exception>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>

#include "cycle/kernels.hpp"
#include "cycle/pair_list.hpp"
#include "cycle/pipeline.hpp"
#include "model/edit.hpp"
#include "physics/cell.hpp"
#include "physics/membrane.hpp"
#include "physics/scene.hpp"
#include "physics/timestep.hpp"
#include "physics/walls.hpp"
#include "support/comm.hpp"

namespace trubal {
namespace {

constexpr std::int64_t kSnapshotEvery = 500;   // a copy costs less than one step's memory traffic
constexpr int kGrowthSteps = 32;    // steps the guard looks back over to measure the energy's growth
constexpr int kFlippingSteps = 20;   // steps running with a negative kinetic term that stop the run (below)
constexpr double kProgressSeconds = 0.2;
constexpr std::int64_t kAgreeEvery = 16;   // steps between the ranks' checks of an interrupt

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

// START box (its bounded axes, in a mixed space): the first ball (by index) whose centre is outside
// across a `stop` face, and every ball outside across a `destroy` face (marked). A NaN centre is
// the guard's, not this.
struct Escapes {
  std::size_t stop_ball = ~std::size_t{0};
  int stop_axis = 0;
  std::vector<bool> destroy;
  std::size_t destroy_count = 0;
};
Escapes find_escapes(const Model& model) {
  Escapes e;
  const Space& s = model.space;
  const Balls& b = model.balls;
  const std::vector<double>* pos[3] = {&b.x, &b.y, &b.z};
  // Every step: first whether any ball is out at all, axis by axis as a loop the compiler
  // vectorises (a NaN is out of neither side, as below).
  unsigned any = 0;
  for (int a = 0; a < 3; ++a) {
    if (s.wraps(a)) continue;
    const double* x = pos[a]->data();
    const double lo = s.lo[a], hi = s.hi[a];
    for (std::size_t k = 0; k < b.size(); ++k) any |= static_cast<unsigned>((x[k] < lo) | (x[k] > hi));
  }
  if (any == 0) return e;
  for (std::size_t k = 0; k < b.size(); ++k)
    for (int a = 0; a < 3; ++a) {
      if (s.wraps(a)) continue;   // a periodic axis wraps the ball instead
      const double x = (*pos[a])[k];
      if (!(x < s.lo[a] || x > s.hi[a])) continue;
      if (s.outside[a] == Outside::Stop) {
        if (e.stop_ball == ~std::size_t{0}) { e.stop_ball = k; e.stop_axis = a; }
      } else {
        if (e.destroy.empty()) e.destroy.assign(b.size(), false);
        e.destroy_count += !e.destroy[k];
        e.destroy[k] = true;
      }
    }
  return e;
}

// The CYCLE's balance error against the energy that moved (CycleResult::energy_warning): above
// kBalanceWarning of it, the step is too coarse for what happened, mostly contacts that formed and
// broke within a few steps (impacts). The error of a collision falls as the step squared (doc/
// physics.md "Energy"), so the FRAC that would have held it is about FRAC sqrt(kBalanceWarning /
// error), taken at half that error for the scatter a collision's phase against the steps gives.
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

// How fast the balance grew over the last steps before the guard stopped step s (`recent`, a ring
// of its distances from the start; `now`, step s's): an unstable mode of central differences grows
// by a factor mu a step in amplitude, mu^2 in energy, where (omega dt)^2 = 2 + mu + 1/mu, so the
// step was omega dt / 2 times the stable one (`over`; 1 where no growth is seen).
struct Growth {
  int steps = 0;
  double grew = 0, factor = 1, over = 1;
};
Growth energy_growth(const std::array<double, kGrowthSteps>& recent, std::int64_t s, double now, double floor) {
  Growth g;
  if (!std::isfinite(now) || !(now > floor)) return g;
  // The earliest of the ring's steps whose distance was above the floor (and a trillionth of now).
  for (int back = static_cast<int>(std::min<std::int64_t>(s - 1, kGrowthSteps - 1)); back >= 1; --back) {
    const double then = recent[static_cast<std::size_t>(s - back) % kGrowthSteps];
    if (!(then > floor) || !(then > 1e-12 * now) || !(then < now)) continue;
    g.steps = back;
    g.grew = now - then;
    g.factor = std::pow(now / then, 1.0 / back);
    const double mu = std::sqrt(g.factor);
    g.over = std::max(1.0, 0.5 * std::sqrt(2 + mu + 1 / mu));
    return g;
  }
  return g;
}

}  // namespace

CycleResult run_cycles(Model& model, Pipeline& pipeline, std::int64_t n, const CycleControl& control) {
  CycleResult result;
  if (n <= 0) return result;
  if (model.balls.size() == 0)
    throw std::runtime_error("there are no balls to cycle (GEN, BALL or LATTICE first)");
  check_ready(model);
  update_mass(model);
  for (std::size_t k = 0; k < model.balls.size(); ++k)
    if (!(model.balls.mass[k] > 0 && std::isfinite(1 / model.balls.mass[k]) && model.balls.inertia[k] > 0))
      throw std::runtime_error(fmt::format(
          "ball {} has mass {:.3g} (radius {:.3g}): too small for a step to move it; give it a larger radius or "
          "density", model.balls.id[k], model.balls.mass[k], model.balls.rad[k]));
  StepKernels kernels = make_kernels(model);
  const double cap = hertz_step_cap(model);
  // The estimate between contact episodes, below which the held critical step is kept (the whole
  // model's, before a distributed run's parts take their balls).
  const double free_step = contact_free_step(model, kernels.features, cap);
  // A servo not yet run reads its first stress from the contact table (cell_before_step): the whole
  // model's list is then searched before the first step, where a distributed run's parts would
  // search it at their split.
  const Space& cell = model.space;
  const bool servo_reads_table =
      cell.periodic && (cell.servo_on[0] || cell.servo_on[1] || cell.servo_on[2]) && !cell.servo_measured_valid;
  pipeline.prepare(model, !servo_reads_table);
  // (Before the critical step, which may leave the ranks other than 0 with their parts alone.)
  const double energy_floor = resting_energy_floor(model);
  if (!(model.critical_dt > 0)) {
    try {
      model.critical_dt = pipeline.critical_timestep(model, kernels.features, cap);
    } catch (...) {   // (its search on the parts failed on a rank: the others' whole models come back)
      pipeline.sync_all(model);
      throw;
    }
  }
  // The guard: energy in must balance energy out. A step beyond the stability limit creates
  // energy from nothing; when that is half of all the energy in play, the run stops. The balance
  // alone cannot see an instability of the linear springs: central differences keep
  // m v(t-dt/2).v(t+dt/2)/2 plus the springs' energy even as the velocities flip sign and grow,
  // the kinetic term going negative, and sliding contacts can hold such a flipping motion at a
  // bounded size. So the run also stops where the kinetic term stays negative for kFlippingSteps
  // steps running (for a stable step it is negative only near the turning points of the fastest
  // vibrations, a few steps of each period).
  const double friction0 = model.energy.friction_work + model.energy.rolling_work, damping0 = model.energy.damping_work;
  const double boundary0 = model.energy.boundary_work, gross0 = model.space.gross_work;
  double balance_ref = 0, potential_ref = 0, scale_max = 0;
  double in_play_max = 0;   // scale_max and the balls' kinetic energy relative to moving walls (below)
  int flipping = 0;   // steps running with the kinetic term negative
  // The balance's distance from its start over the last kGrowthSteps steps (a ring): how fast the
  // energy grows when the guard stops the run.
  std::array<double, kGrowthSteps> recent{};
  // A scene at rest has almost no energy, and rounding alone then looks like a large relative
  // imbalance. Below the energy of springs compressed by 1e-6 of a radius nothing is reported;
  // an unstable step grows exponentially and passes this within a few steps.
  if (servo_reads_table) make_results(model, pipeline);
  const Snapshot& snapshot = pipeline.rescue();
  // The rescue copy of the state now (a distributed run's gathered from the ranks' parts to rank 0
  // first, which alone keeps its balls and pairs).
  auto take_copy = [&] {
    pipeline.sync(model);
    pipeline.take_rescue(model);
  };
  // A distributed run's output steps gather to rank 0 alone, which alone runs the observers.
  const bool output_on_root = pipeline.distributed() && comm::size() > 1;
  const bool observes = !output_on_root || comm::root();
  // A CYCLE right after one that deferred its last step's results: the rescue copy, of the step
  // before, is kept as this run's copy (the rescue takes that step again).
  if (!pipeline.results_deferred(model)) take_copy();
  pipeline.clear_deferred();
  const bool defer = control.defer_results;
  if (defer) {
    // Results not of this state are of no use (the servo has read them already).
    if (model.contacts.results_cycle != model.cycle && !servo_reads_table) model.contacts.drop_results();
  } else {
    model.contacts.keep_results();
  }
  using Clock = std::chrono::steady_clock;
  const auto loop_start = Clock::now();
  auto last_progress = loop_start;
  const std::int64_t start_cycle = model.cycle;
  PhaseTimes& timing = pipeline.times();
  timing = PhaseTimes{};
  // Copies the timings into the result whichever way the loop ends.
  auto finish = [&]() -> CycleResult& {
    pipeline.end_cycle(model);   // a distributed run's last step, on every rank
    result.seconds = std::chrono::duration<double>(Clock::now() - loop_start).count();
    result.times = timing;
    if (!result.unstable) result.energy_warning = balance_warning(model, result, energy_floor);
    return result;
  };

  // One step: the cell and the walls before it, the pipeline's step, and what follows it (the
  // cell's strain and tilt, the clock, the works, the next critical step, the energy terms at t).
  // details: the step writes the per-pair results (CycleControl::reads_contacts).
  auto advance = [&](bool details) -> StepTotals {
    const double dt = model.settings.fixed_dt > 0 ? model.settings.fixed_dt : model.settings.frac * model.critical_dt;
    // Before anything moves: a step that would shear or squash the periodic cell by more than half an
    // edge is refused (no tilt reduction could follow it; the run stays at its last step).
    check_cell_step(model.space, dt);
    kernels.dt = dt;
    // The step before, which moved the balls to where this step's forces are computed (Model::dt;
    // none before a model's first step).
    kernels.dt_prev = model.dt > 0 ? model.dt : dt;
    kernels.dt_mean = 0.5 * (kernels.dt_prev + dt);
    const Space& space = model.space;
    // A servo reads the stress and stiffness of each force pass: the contact loops sum them.
    kernels.moments = space.periodic && (space.servo_on[0] || space.servo_on[1] || space.servo_on[2]);
    kernels.contacts = details ? kernels.contacts_full : kernels.contacts_lean;
    kernels.motion = details ? kernels.motion_full : kernels.motion_lean;
    kernels.walls = details ? kernels.walls_full : kernels.walls_lean;
    StepSums step_sums;
    const auto step_start = Clock::now();
    // MEMBRANE follow: the perimeter forces from the positions now, on cycles of the absolute count
    // (the same steps however the run is cut).
    if (model.membrane.follow_every > 0 && model.cycle % model.membrane.follow_every == 0) {
      pipeline.sync_all(model);
      follow_membrane(model);
      pipeline.loads_changed(model);
    }
    // Periodic space: the servo's rates, from the last force pass (Space::servo_measured).
    FieldChange field;   // the servo's new rates change the balls' velocities: where the pipeline holds them
    cell_before_step(model, dt, space.servo_measured_valid ? &space.servo_measured : nullptr, &field);
    pipeline.apply_field(model, field);
    if (!model.walls.empty()) walls_before_step(model, dt);
    pipeline.step(model, kernels, step_sums);
    // A distributed run's ranks step their parts: the model is made current where it is read.
    if (details) pipeline.sync(model);
    const StepTotals sums(step_sums);
    model.space.servo_measured_valid = kernels.moments;
    if (kernels.moments) model.space.servo_measured = {sums.force_moment, sums.stiffness_moment};
    cell_after_step(model, dt, kernels.dt_mean, sums.image_power, false);   // periodic space: the cell's work, its new edges, the strain
    pipeline.reduce_cell_tilt(model);                     // and its tilts, on every copy of the pairs
    timing.step += std::chrono::duration<double>(Clock::now() - step_start).count();
    model.cycle += 1;
    if (details) model.contacts.results_cycle = model.cycle;
    model.time += dt;
    model.dt = dt;
    model.energy.friction_work += sums.friction_work;
    model.energy.rolling_work += sums.rolling_work;
    model.energy.damping_work += sums.damping_work;
    model.energy.boundary_work += sums.boundary_work;
    if (kernels.estimate != StepEstimate::None) {
      const double estimate = std::min(sums.critical_dt, cap);
      if (std::isfinite(estimate))
        model.critical_dt = next_critical_step(model.critical_dt, estimate, model.settings.frac, free_step,
                                               kernels.features.hertz);
    }
    // The energy terms at t, the time of this step's force pass: every term there (the works less
    // their parts after t; the cell moves on with the balls, so half its step's work is after t).
    EnergyAtStep& now = model.energy_at_step;
    now.valid = true;
    now.kinetic_translation = sums.kinetic_translation;
    now.kinetic_rotation = sums.kinetic_rotation;
    now.strain = sums.strain;
    now.potential = sums.potential;
    now.damping_ahead = sums.damping_ahead;
    now.boundary_ahead = sums.boundary_ahead + (model.space.periodic ? 0.5 * sums.image_power * kernels.dt_mean : 0.0);
    return sums;
  };

  // START box: balls outside a bounded axis's faces after a step are destroyed (`destroy`) or stop
  // the run (`stop`: true, with the message). replay: a step the rescue takes again (it was
  // reported the first time).
  auto escapes = [&](bool replay) -> bool {
    if (!(model.started && (!model.space.periodic || model.space.mixed()) && pipeline.may_be_outside_box(model)))
      return false;
    pipeline.sync_all(model);
    Escapes escaped = find_escapes(model);
    if (escaped.destroy_count > 0) {
      // What the leaving balls carry out is boundary work, so the balance stays closed.
      const Balls& b = model.balls;
      const auto& g = model.settings.gravity;
      for (std::size_t k = 0; k < b.size(); ++k)
        if (escaped.destroy[k])
          model.energy.boundary_work -=
              0.5 * b.mass[k] * (b.vx[k] * b.vx[k] + b.vy[k] * b.vy[k] + b.vz[k] * b.vz[k]) +
              0.5 * b.inertia[k] * (b.wx[k] * b.wx[k] + b.wy[k] * b.wy[k] + b.wz[k] * b.wz[k]) -
              b.mass[k] * (g[0] * b.x[k] + g[1] * b.y[k] + g[2] * b.z[k]);
      if (escaped.stop_ball != ~std::size_t{0} && escaped.destroy[escaped.stop_ball]) escaped.stop_ball = ~std::size_t{0};
      const double held = model.critical_dt;   // fewer balls make no contact stiffer: keep the step
      remove_balls(model, escaped.destroy);
      model.critical_dt = held;
      model.space.destroyed += static_cast<std::int64_t>(escaped.destroy_count);
      if (!replay) result.destroyed += escaped.destroy_count;
      pipeline.invalidate();
      kernels.laws = make_pair_laws(model);   // per-ball type indices
      if (escaped.stop_ball != ~std::size_t{0}) escaped = find_escapes(model);
    }
    if (escaped.stop_ball == ~std::size_t{0}) return false;
    const std::size_t k = escaped.stop_ball;
    const int a = escaped.stop_axis;
    const double x = (a == 0 ? model.balls.x : a == 1 ? model.balls.y : model.balls.z)[k];
    result.left_box = true;
    result.message = fmt::format(
        "ball {} left the box through {} = {:.6g} at cycle {} (it is at {} = {:.9g}); the model is kept at that "
        "cycle: DELETE the ball, make the box larger, or let such balls go with START box ... destroy",
        model.balls.id[k], "xyz"[a], x < model.space.lo[a] ? model.space.lo[a] : model.space.hi[a], model.cycle,
        "xyz"[a], x);
    return true;
  };

  // The rescue from a failed step at bad_cycle: back to the copy. The copy of the CYCLE's start is
  // its last good state as it is. The later copies are of the state a step before a multiple of
  // kSnapshotEvery steps: the rescue takes that step again, writing the results, so the model is at
  // the multiple and prints as it was then. The same bits as the first time: nothing in a step
  // depends on when the pair list was made (the cut tests hold this), and the observers do not run
  // again; so is a copy kept from the CYCLE before, of its last step's step before (defer_results).
  // (Where the failing step is that step, the model stays at the copy.) Returns whether the
  // results are those of the state it is left in (false only where a step after the copy
  // overwrote them: Snapshot::restore).
  auto rescue = [&](std::int64_t bad_cycle) -> bool {
    bool current = pipeline.restore_rescue(model);
    pipeline.invalidate();
    kernels.laws = make_pair_laws(model);   // the balls destroyed since the copy are back
    if (model.cycle != start_cycle && model.cycle + 1 < bad_cycle) {
      advance(true);
      escapes(true);
      current = true;
    }
    pipeline.sync_all(model);
    return current;
  };

  // An error mid-run (every rank meets it at the same step) leaves the model as the last step made it.
  try {
  for (std::int64_t s = 1; s <= n; ++s) {
    // The per-pair results measurements read are written only where someone will read them: the
    // last step (PRINT, SOLVE; CYCLE's defers it: make_results), a step Ctrl-C ends, snapshot steps
    // (Snapshot::restore finds them current where the next step fails; not where results are
    // deferred, as the rescue takes the step again) and the cycles history and dumps record.
    bool stopping = control.interrupt && control.interrupt->load(std::memory_order_relaxed);
    // Under mpirun every rank takes the same steps: they stop together, agreeing every
    // kAgreeEvery steps (a rank that stopped alone would leave the others waiting for its part).
    if (control.interrupt && comm::size() > 1) stopping = s % kAgreeEvery == 0 && comm::any_all(control.interrupt->load());
    const bool observed = control.after_step && (!control.reads_contacts || control.reads_contacts(model.cycle + 1));
    // defer: the last step's results are made when read, from a copy of the step before.
    const bool deferred = defer && s == n && !stopping && !observed;
    const bool details = (s == n && !deferred) || stopping || (!defer && (s + 1) % kSnapshotEvery == 0) || observed;
    if (deferred && snapshot.cycle != model.cycle) take_copy();
    const StepTotals sums = advance(details);

    // The balance at t, the time of this step's force pass.
    const EnergyAtStep& now = model.energy_at_step;
    const double kinetic = now.kinetic_translation + now.kinetic_rotation;
    const double dissipated =
        model.energy.friction_work + model.energy.rolling_work - friction0 + model.energy.damping_work - damping0 -
        now.damping_ahead;
    const double boundary = model.energy.boundary_work - boundary0 - now.boundary_ahead;
    if (s == 1) potential_ref = sums.potential;
    const double potential = sums.potential - potential_ref;
    const double balance = kinetic + sums.strain + potential + dissipated - boundary;
    if (s == 1) balance_ref = balance;
    // (|kinetic|: the kinetic term is negative in a step where the velocities turn.)
    const double scale = std::abs(kinetic) + sums.strain + std::abs(potential) + std::abs(dissipated) +
                         std::abs(boundary) + (model.space.gross_work - gross0);
    // Against the most energy in play so far: a bouncing ball at the top of its flight has little
    // energy, while the contact it left (a few coarse steps) may have shifted the balance a little.
    scale_max = std::max(scale_max, scale);
    result.balance_error = std::max(result.balance_error, std::abs(balance - balance_ref));
    result.energy_scale = scale_max;
    // A contact that forms between two steps makes an error of up to (omega dt)^2 / 4 of the
    // kinetic energy of the approach (doc/physics.md "Energy"). The lab frame holds that energy where
    // the ball moves, but not where a wall moves into balls at rest: the same collision seen from
    // the wall, whose infinite mass carries the energy no term above counts. So the guard also
    // counts the touching balls' kinetic energy in the frame of each moving wall.
    double wall_relative = 0;
    for (const Wall& w : model.walls) wall_relative += w.relative_kinetic;
    in_play_max = std::max(in_play_max, scale + wall_relative);
    flipping = kinetic < -energy_floor ? flipping + 1 : 0;
    const double drift = std::abs(balance - balance_ref);
    recent[static_cast<std::size_t>(s) % kGrowthSteps] = drift;
    if (!std::isfinite(balance) || drift > 0.5 * in_play_max + energy_floor || flipping >= kFlippingSteps) {
      const std::size_t ball = sums.fastest_ball < model.balls.size() ? sums.fastest_ball : 0;
      const std::int64_t id = model.balls.size() ? model.balls.id[ball] : 0;
      const double speed = std::sqrt(sums.fastest_speed2);
      const std::int64_t bad_cycle = model.cycle;
      const Growth growth = energy_growth(recent, s, drift, energy_floor);
      const double in_play = in_play_max;
      const bool results_current = rescue(bad_cycle);
      const double frac = model.settings.frac;
      // The step to take: beyond the stable step by growth.over, and by half again (0.5 at most).
      const double shrink = std::min(0.5, 0.8 / growth.over);
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
      std::string what;
      if (growth.steps > 0 && growth.factor > 1.001) {
        what = fmt::format("energy was created: the balance grew by {:.3g} ({:.3g}% of the energy in play) over the "
                           "last {} cycles",
                           growth.grew, in_play > 0 ? 100 * growth.grew / in_play : 0.0, growth.steps);
        if (growth.factor > 1.05)   // a clear exponential: a mode beyond the stable step
          what += fmt::format(", {:.3g} times a cycle, as a step about {:.2g} times the stable one makes it",
                              growth.factor, growth.over);
      }
      else if (flipping >= kFlippingSteps)
        what = fmt::format("the velocities flip sign every cycle (the kinetic term m v(t-dt/2).v(t+dt/2)/2 stayed "
                           "negative for {} cycles), as a step beyond the stable one makes them",
                           kFlippingSteps);
      else
        what = "energy was created";
      what += fmt::format(" (the fastest ball is {}, at {:.3g})", id, speed);
      result.unstable = true;
      result.done = model.cycle - start_cycle;
      result.message = fmt::format("unstable at cycle {}: {}; the model is back at cycle {}, its last good state{}; {}",
                                   bad_cycle, what, model.cycle,
                                   results_current ? "" : " (its contact forces were not kept: CYCLE computes them)",
                                   advice);
      return finish();
    }
    result.done = s;
    if (escapes(false)) return finish();
    if (control.after_step) {
      const auto output_start = Clock::now();
      // Rank 0 alone writes what an observer records (a history's rows, a dump's files): its failure
      // (a full disk) is every rank's, agreed before the next step, so that no rank goes on alone
      // into the next step's collective calls and waits there for ever.
      if (comm::size() > 1 && observed)
        comm::together([&] { if (observes) control.after_step(model); }, "recording the output");
      else if (observes) control.after_step(model);
      if (output_on_root && observed && control.share_output) control.share_output();
      timing.output += std::chrono::duration<double>(Clock::now() - output_start).count();
    }
    // The rescue steps on to cycles on kSnapshotEvery. Not after the last step: the next CYCLE takes
    // its own copy at its start, and a deferred last step needs the copy of the step before it.
    if (s < n && (s + 1) % kSnapshotEvery == 0) take_copy();
    if (control.progress && (s & 7) == 0) {
      const auto now = std::chrono::steady_clock::now();
      if (std::chrono::duration<double>(now - last_progress).count() > kProgressSeconds) {
        control.progress(s, n);
        last_progress = now;
      }
    }
    if (stopping) {   // seen before this step, which therefore wrote the details
      result.interrupted = s < n;
      break;
    }
    if (deferred) {
      // The results can be made again only from a copy of the step before (results_deferred).
      if (pipeline.rescue().cycle + 1 != model.cycle)
        throw std::logic_error(fmt::format(
            "internal error: the rescue copy is of cycle {}, not the step before cycle {} whose contact results it "
            "is to make", pipeline.rescue().cycle, model.cycle));
      model.contacts.drop_results();
      pipeline.defer_results(model);
    }
  }
  } catch (...) {
    pipeline.sync_all(model);
    throw;
  }
  return finish();
}

void make_results(Model& model, Pipeline& pipeline) {
  if (pipeline.results_deferred(model)) {
    const Pipeline::Deferred left = pipeline.deferred();
    pipeline.clear_deferred();
    // The list as that step had it: the same search, or none (the SAVE that follows writes it).
    pipeline.restore_rescue(model);
    pipeline.rewind_step();
    const CycleResult r = run_cycles(model, pipeline, 1, {});   // its one step writes the results
    pipeline.count_results_made();
    if (r.unstable || r.left_box || !Pipeline::Deferred::of(model).same(left))
      throw std::logic_error(fmt::format(
          "internal error: cycle {} taken again to make its contact results did not give the same state", left.cycle));
    return;
  }
  model.contacts.keep_results();
}

void make_results_to_read(Model& model, Pipeline& pipeline) {
  if (!pipeline.distributed() || comm::size() < 2) return make_results(model, pipeline);
  if (!pipeline.results_deferred(model)) {   // (the same answer on every rank)
    if (comm::root()) model.contacts.keep_results();
    return;
  }
  std::exception_ptr failure;
  try {
    comm::together([&] {
      if (!comm::root()) return;
      // The list every rank holds (rank 0's, handed over at the CYCLE's end): the step taken again
      // searches on its own and may keep other candidates beside the same touching pairs.
      const PairCandidates held = pair_list_of(model.contacts);
      {
        comm::Alone alone;
        Pipeline::Alone serial(pipeline);
        make_results(model, pipeline);
      }
      if (!holds_pairs(model.contacts, held)) install_pairs(model.contacts, held);
    }, "making the contact results");
  } catch (...) {
    failure = std::current_exception();
  }
  pipeline.clear_deferred();
  pipeline.invalidate();
  if (!failure) return;
  // Rank 0 may have put its model back to the step before, or be part way through it: every rank
  // goes back to rank 0's rescue copy (a collective call), then the failure is every rank's.
  pipeline.restore_rescue(model);
  pipeline.invalidate();
  std::rethrow_exception(failure);
}

}  // namespace trubal
