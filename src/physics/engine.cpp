// Cycling: what a scene needs, readiness checks, the time step, and the loop with its guard.
#include "physics/engine.hpp"

#include <chrono>
#include <cmath>
#include <limits>
#include <set>
#include <stdexcept>

#include <fmt/format.h>

#include "model/periodic_cell.hpp"
#include "physics/cell.hpp"
#include "physics/kernels.hpp"

namespace trubal {
namespace {

std::set<int> used_types(const Model& model) {
  return std::set<int>(model.balls.type.begin(), model.balls.type.end());
}

// PHYSICS.md "Time step": a Hertz contact has no stiffness at first touch, so the step is capped
// by the Rayleigh-wave time of the smallest Hertz ball, pi R sqrt(rho/G) / (0.1631 nu + 0.8766).
double hertz_step_cap(const Model& model) {
  double cap = std::numeric_limits<double>::infinity();
  const Balls& b = model.balls;
  for (std::size_t i = 0; i < b.size(); ++i) {
    const auto it = model.materials.find(b.type[i]);
    if (it == model.materials.end() || !it->second.hertz()) continue;
    const Material& m = it->second;
    cap = std::min(cap, M_PI * b.rad[i] * std::sqrt(m.density / m.shear_modulus) / (0.1631 * m.poisson + 0.8766));
  }
  return cap;
}

// Everything a failed step must be able to go back to.
struct Snapshot {
  Balls balls;
  ContactTable contacts;
  Energy energy;
  Space space;
  std::int64_t cycle = 0;
  double time = 0, dt = 0, critical_dt = 0;
  void take(const Model& m) {
    balls = m.balls; contacts = m.contacts; energy = m.energy; space = m.space;
    cycle = m.cycle; time = m.time; dt = m.dt; critical_dt = m.critical_dt;
  }
  void restore(Model& m) const {
    m.balls = balls; m.contacts = contacts; m.energy = energy; m.space = space;
    m.cycle = cycle; m.time = time; m.dt = dt; m.critical_dt = critical_dt;
  }
};

// The held critical step of a Hertz scene (see next_critical_step): shrunk only when the step would
// exceed this fraction of the critical estimate (or FRAC itself, when FRAC is larger), and grown
// within a contact episode only when the estimate has risen this many times above it.
constexpr double kHeldStability = 0.9;
constexpr double kHeldGrowth = 2.0;

constexpr std::int64_t kSnapshotEvery = 500;   // a copy costs about one step's memory traffic
constexpr double kProgressSeconds = 0.2;

}  // namespace

double next_critical_step(double held, double estimate, double frac, double cap, bool hertz) {
  if (!hertz || !(held > 0)) return estimate;
  // Between contact episodes (nothing stiffer than a lone Hertz ball's cap) the step is free.
  if (!(estimate < cap)) return estimate;
  // Stability: the step frac * held must stay below kHeldStability (or frac) times the estimate.
  if (frac * held > std::max(kHeldStability, frac) * estimate) return estimate;
  // A much softer state (contacts unloaded): take the longer step, a bounded number of jumps.
  if (estimate > kHeldGrowth * held) return estimate;
  return held;
}

std::string Features::describe() const {
  std::string s = hertz ? "hertz-mindlin" : "linear";
  if (friction) s += " shear";
  if (rotation) s += " rotation";
  if (stiffness_damping) s += " dashpots";
  if (mass_damping == DampKind::Rayleigh) s += " mass-damping";
  if (mass_damping == DampKind::Local) s += " local-damping";
  if (gravity) s += " gravity";
  if (applied) s += " applied-loads";
  if (periodic) s += " periodic";
  return s;
}

Features scene_features(const Model& model) {
  Features f;
  const Balls& b = model.balls;
  const Damping& damping = model.settings.damping;
  bool restitution = false;
  f.friction = f.hertz = false;
  for (int type : used_types(model)) {
    const auto it = model.materials.find(type);
    if (it == model.materials.end()) continue;
    const Material& m = it->second;
    f.hertz = f.hertz || m.hertz();
    f.friction = f.friction || m.ks > 0 || m.hertz();
    restitution = restitution || m.has_restitution;
  }
  f.stiffness_damping = restitution || (damping.kind == DampKind::Rayleigh && damping.beta > 0);
  if (damping.kind == DampKind::Rayleigh && damping.alpha > 0) f.mass_damping = DampKind::Rayleigh;
  else if (damping.kind == DampKind::Local && damping.local > 0) f.mass_damping = DampKind::Local;
  const auto& g = model.settings.gravity;
  f.gravity = g[0] != 0 || g[1] != 0 || g[2] != 0;
  bool free_spin = false, spinning = false, moments = false;
  f.applied = false;
  for (std::size_t i = 0; i < b.size(); ++i) {
    free_spin = free_spin || (b.fixed[i] & kSpin) != kSpin;
    spinning = spinning || b.wx[i] != 0 || b.wy[i] != 0 || b.wz[i] != 0;
    moments = moments || b.amx[i] != 0 || b.amy[i] != 0 || b.amz[i] != 0;
    f.applied = f.applied || moments || b.ax[i] != 0 || b.ay[i] != 0 || b.az[i] != 0;
  }
  f.rotation = (f.friction && free_spin) || spinning || moments;
  f.periodic = model.space.periodic;
  return f;
}

void check_ready(const Model& model) {
  check_periodic_cell(model);
  bool hertz = false, linear = false;
  for (int type : used_types(model)) {
    const auto it = model.materials.find(type);
    if (it == model.materials.end())
      throw std::runtime_error(fmt::format("type {0} has no properties (PROP type {0} kn ... ks ... dens ...)", type));
    const Material& m = it->second;
    if (!(m.density > 0))
      throw std::runtime_error(fmt::format("type {0} has no density (PROP type {0} dens ...)", type));
    if (m.hertz()) {
      if (!(m.poisson >= 0 && m.poisson < 0.5))
        throw std::runtime_error(fmt::format("type {0} needs a Poisson ratio in [0, 0.5) (PROP type {0} poisson ...)", type));
      hertz = true;
    } else if (!(m.kn > 0)) {
      throw std::runtime_error(fmt::format(
          "type {0} has no stiffness (PROP type {0} kn ... ks ..., or shear ... poisson ...)", type));
    } else {
      linear = true;
    }
    if (m.has_restitution && !(m.restitution > 0 && m.restitution <= 1))
      throw std::runtime_error(fmt::format("type {0}: restitution must be in (0, 1] (PROP type {0} rest ...)", type));
  }
  if (hertz && linear)
    throw std::runtime_error("the balls mix Hertz-Mindlin and linear types; give every type the same law");
}

void update_mass(Model& model) {
  Balls& b = model.balls;
  for (std::size_t i = 0; i < b.size(); ++i) {
    const auto it = model.materials.find(b.type[i]);
    const double density = it == model.materials.end() ? 0 : it->second.density;
    const double r = b.rad[i];
    b.mass[i] = density * 4.0 / 3.0 * M_PI * r * r * r;
    b.inertia[i] = 0.4 * b.mass[i] * r * r;
  }
}

double critical_timestep(const Model& model) {
  const StepKernels k = make_kernels(model);
  const Balls& b = model.balls;
  const ContactTable& c = model.contacts;
  const std::size_t n = b.size();
  // Per-ball sums over the touching pairs, added in list order: ascending partner, as the gather.
  std::vector<double> kmax(n, 0), ks(n, 0), cn(n, 0);
  for (std::size_t p = 0; p < c.size(); ++p) {
    const std::size_t i = c.i[p], j = c.j[p];
    if (i >= n || j >= n) continue;   // a stale list: count what is still valid
    const PairLaw& law = k.law(i, j);
    ContactInput in{};
    in.dx = b.x[j] - b.x[i]; in.dy = b.y[j] - b.y[i]; in.dz = b.z[j] - b.z[i];
    if (model.space.periodic && p < c.image_x.size()) {
      double ox, oy, oz;
      image_offset(cell_frame(model.space), c.image_x[p], c.image_y[p], c.image_z[p], ox, oy, oz);
      in.dx = image_delta(b.x[j], b.x[i], ox);
      in.dy = image_delta(b.y[j], b.y[i], oy);
      in.dz = image_delta(b.z[j], b.z[i], oz);
    }
    in.ri = b.rad[i]; in.rj = b.rad[j];
    if (law.rest_xi > 0) in.mstar = b.mass[i] * b.mass[j] / (b.mass[i] + b.mass[j]);
    using namespace contact_bits;
    const ContactResult r = k.features.hertz ? contact_force<kHertz | kDashpot>(law, in, 0, 0)
                                             : contact_force<kDashpot>(law, in, 0, 0);
    if (r.state == 0) continue;
    for (std::size_t ball : {i, j}) {
      kmax[ball] += std::max(r.kn, r.ks);
      ks[ball] += r.ks;
      cn[ball] += r.cn;
    }
  }
  const bool rotation = k.features.rotation;
  double step = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < n; ++i) {
    const bool held = (b.fixed[i] & kVel) == kVel && (!rotation || (b.fixed[i] & kSpin) == kSpin);
    if (held) continue;
    double sum_kmax = kmax[i], sum_ks = ks[i], sum_cn = cn[i];
    if (sum_kmax == 0) {
      const std::uint16_t t = k.type_count == 1 ? 0 : k.ball_type[i];
      sum_kmax = std::max(k.alone_kn[t], k.alone_ks[t]);
      sum_ks = k.alone_ks[t];
      sum_cn = 2 * k.alone_xi[t] * std::sqrt(k.alone_kn[t] * 0.5 * b.mass[i]);
    }
    const double omega2 = ball_omega2(b.mass[i], sum_kmax, sum_ks, rotation);
    if (!(omega2 > 0)) continue;
    const double omega = std::sqrt(omega2);
    step = std::min(step, damped_critical_step(omega, 0.5 * k.beta * omega + sum_cn / (b.mass[i] * omega)));
  }
  return std::min(step, hertz_step_cap(model));
}

static double resting_energy_floor(const Model& model) {
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

CycleResult run_cycles(Model& model, Backend& backend, std::int64_t n, const CycleControl& control) {
  CycleResult result;
  if (n <= 0) return result;
  check_ready(model);
  update_mass(model);
  StepKernels kernels = make_kernels(model);
  const double cap = hertz_step_cap(model);
  backend.prepare(model);
  if (!(model.critical_dt > 0)) model.critical_dt = critical_timestep(model);
  // The guard: energy in must balance energy out. A step beyond the stability limit creates
  // energy from nothing; when that is half of all the energy in play, the run stops.
  const double friction0 = model.energy.friction_work, damping0 = model.energy.damping_work;
  const double boundary0 = model.energy.boundary_work, gross0 = model.space.gross_work;
  double balance_ref = 0, potential_ref = 0, scale_max = 0;
  // A scene at rest has almost no energy, and rounding alone then looks like a large relative
  // imbalance. Below the energy of springs compressed by 1e-6 of a radius nothing is reported;
  // an unstable step grows exponentially and passes this within a few steps.
  const double energy_floor = resting_energy_floor(model);
  if (!model.scratch.data) model.scratch.data = std::make_shared<Snapshot>();
  Snapshot& snapshot = *std::static_pointer_cast<Snapshot>(model.scratch.data);
  snapshot.take(model);
  using Clock = std::chrono::steady_clock;
  const auto loop_start = Clock::now();
  auto last_progress = loop_start;
  const std::int64_t start_cycle = model.cycle;
  model.timing = PhaseTimes{};
  // Copies the timings into the result whichever way the loop ends.
  auto finish = [&]() -> CycleResult& {
    result.seconds = std::chrono::duration<double>(Clock::now() - loop_start).count();
    result.times = model.timing;
    return result;
  };

  for (std::int64_t s = 1; s <= n; ++s) {
    const double dt = model.settings.fixed_dt > 0 ? model.settings.fixed_dt : model.settings.frac * model.critical_dt;
    kernels.dt = dt;
    // The per-pair results measurements read are written only where someone will read them: the
    // last step (PRINT, SOLVE), a step Ctrl-C ends, snapshot steps (a restored model prints
    // right) and the cycles history and dumps record.
    const bool stopping = control.interrupt && control.interrupt->load(std::memory_order_relaxed);
    const Space& space = model.space;
    const bool details = s == n || stopping || s % kSnapshotEvery == 0 ||
                         (control.after_step && (!control.reads_contacts || control.reads_contacts(model.cycle + 1)));
    // A servo reads the stress and stiffness of each force pass: the contact loops sum them.
    kernels.moments = space.periodic && (space.servo_on[0] || space.servo_on[1] || space.servo_on[2]);
    kernels.contacts = details ? kernels.contacts_full : kernels.contacts_lean;
    kernels.motion = details ? kernels.motion_full : kernels.motion_lean;
    StepSums sums;
    const auto step_start = Clock::now();
    // Periodic space: the servo's rates, from the last force pass (Space::servo_measured).
    cell_before_step(model, dt, space.servo_measured_valid ? &space.servo_measured : nullptr);
    backend.step(model, kernels, sums);
    model.space.servo_measured_valid = kernels.moments;
    if (kernels.moments) model.space.servo_measured = {sums.force_moment, sums.stiffness_moment};
    cell_after_step(model, dt, sums.image_power);    // periodic space: the cell's work, its new edges, the strain
    model.timing.step += std::chrono::duration<double>(Clock::now() - step_start).count();
    model.cycle += 1;
    model.time += dt;
    model.dt = dt;
    model.energy.friction_work += sums.friction_work;
    model.energy.damping_work += sums.damping_work;
    model.energy.boundary_work += sums.boundary_work;
    if (kernels.estimate != StepEstimate::None) {
      const double estimate = std::min(sums.critical_dt, cap);
      if (std::isfinite(estimate))
        model.critical_dt = next_critical_step(model.critical_dt, estimate, model.settings.frac, cap, kernels.features.hertz);
    }

    const double dissipated = model.energy.friction_work - friction0 + model.energy.damping_work - damping0;
    const double boundary = model.energy.boundary_work - boundary0;
    if (s == 1) potential_ref = sums.potential;
    const double potential = sums.potential - potential_ref;
    const double balance = sums.kinetic + sums.strain + potential + dissipated - boundary;
    if (s == 1) balance_ref = balance;
    const double scale = sums.kinetic + sums.strain + std::abs(potential) + std::abs(dissipated) + std::abs(boundary) +
                         (model.space.gross_work - gross0);
    // Against the most energy in play so far: a bouncing ball at the top of its flight has little
    // energy, while the contact it left (a few coarse steps) may have shifted the balance a little.
    scale_max = std::max(scale_max, scale);
    if (!std::isfinite(balance) || std::abs(balance - balance_ref) > 0.5 * scale_max + energy_floor) {
      const std::size_t ball = sums.fastest_ball < model.balls.size() ? sums.fastest_ball : 0;
      const std::int64_t id = model.balls.size() ? model.balls.id[ball] : 0;
      const double speed = std::sqrt(sums.fastest_speed2);
      const std::int64_t bad_cycle = model.cycle;
      snapshot.restore(model);
      backend.invalidate();
      const double frac = model.settings.frac;
      std::string advice;
      if (model.settings.fixed_dt > 0)
        advice = fmt::format("try TSTEP {:.3g} (now {:.3g}; critical step about {:.3g})", 0.5 * critical_timestep(model),
                             model.settings.fixed_dt, critical_timestep(model));
      else
        advice = fmt::format("try FRAC {:.3g} (now {:.3g})", std::min(0.8, 0.5 * frac), frac);
      result.unstable = true;
      result.done = model.cycle - start_cycle;
      result.message = fmt::format(
          "unstable at cycle {}: ball {} moved at {:.3g} and energy was created; the model is back at cycle {}, "
          "its last good state; {}",
          bad_cycle, id, speed, model.cycle, advice);
      return finish();
    }
    result.done = s;
    if (control.after_step) {
      const auto output_start = Clock::now();
      control.after_step(model);
      model.timing.output += std::chrono::duration<double>(Clock::now() - output_start).count();
    }
    if (s % kSnapshotEvery == 0) snapshot.take(model);
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
  }
  return finish();
}

}  // namespace trubal
