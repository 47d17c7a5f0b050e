// The law of motion of one step, ball by ball (kernel_loops.hpp says how the step's loops are
// laid out).
#pragma once

#include "cycle/kernel_loops.hpp"

namespace trubal::loops {

// A ball's run's moments to the servo's exact sums (out of line: only servo steps need them).
[[gnu::noinline]] inline void add_moments(StepSums& sums, const std::array<double, 9>& m) {
  for (int a = 0; a < 6; ++a) sums.force_moment[a].add(m[a]);
  for (int a = 0; a < 3; ++a) sums.stiffness_moment[a].add(m[6 + a]);
}

// `a` where `take`, else `b`, as bits: both are made, so g++ cannot sink either's arithmetic into a
// branch (which it did with ?:, and which keeps the loop below from vectorising).
[[gnu::always_inline]] inline double pick(bool take, double a, double b) {
  const std::uint64_t mask = take ? ~std::uint64_t{0} : std::uint64_t{0};
  return std::bit_cast<double>((std::bit_cast<std::uint64_t>(a) & mask) | (std::bit_cast<std::uint64_t>(b) & ~mask));
}
// One ball's sums of the law of motion, over its components.
struct MotionSums {
  double boundary, boundary_ahead, damping, damping_ahead, kinetic;
};
// The step's constants a lane reads, copied out of StepKernels (read through a reference, they were
// loaded again after every store of the loop, which kept it from vectorising).
struct LaneConstants {
  double dt, half_dt, local, alpha;
  double keep, shrink;   // mass-proportional damping, factor form: v' = (v keep + F/m dt) shrink
};
// One velocity component by the law of motion, for a block of balls at once: written with selects
// rather than branches, so that the compiler vectorises the block's loop; each lane does the
// arithmetic the ball always had (a fixed component keeps its velocity and charges the boundary with
// its force's work; a free one moves, damped as the scene says). `fixed` selects per lane.
// The velocity moves by F/m times dt_mean, the mean of the step before and this one (central
// differences with a step that changes: LaneConstants::dt is dt_mean).
// Kinetic energy at t as m v(t - dt/2) v(t + dt/2) / 2: with the spring energy and the potential at
// t this is the quantity central differences conserve exactly for a linear spring (and free fall)
// at a fixed step, so the guard sees no false imbalance from a stable step however coarse it is.
// Its change from the step before is F(t) . v(t - dt/2) dt_mean / 2 plus the step before's
// F . v(t - dt/2) dt_mean / 2, so a force F(t) other than the springs' does the work F(t) . v(t)
// dt_mean, v(t) = (v(t - dt/2) + v(t + dt/2)) / 2, of which the part F(t) . v(t + dt/2) dt_mean / 2
// lies after t (the aheads).
template <MotionFeatures M>
[[gnu::always_inline]] inline double advance_lane(double force, double applied, double v, double inv_m, double m,
                                                  bool fixed, const LaneConstants c, MotionSums& s) {
  constexpr DampKind kDamp = M.damping;
  const double dt = c.dt, half_dt = c.half_dt, keep = c.keep, shrink = c.shrink;
  double f = force;
  if constexpr (kDamp == DampKind::Local) {
    const double reduce = c.local * std::abs(force);
    const double less = force - reduce, more = force + reduce;   // (both made: selects, no branches)
    f = pick(v > 0, less, pick(v < 0, more, force));
  }
  const double v_free = kDamp == DampKind::Rayleigh ? (v * keep + f * inv_m * dt) * shrink : v + f * inv_m * dt;
  const double v_mid = 0.5 * (v + v_free);
  // Fixed: the force's work (less the applied load's) is the boundary's, the velocity kept.
  const double work = -(force - applied) * v * dt;
  double boundary = s.boundary, boundary_ahead = s.boundary_ahead;
  if constexpr (M.loads) {
    boundary += applied * v_mid * dt;
    boundary_ahead += applied * v_free * half_dt;
  }
  const double boundary_fixed = s.boundary + work, boundary_ahead_fixed = s.boundary_ahead + 0.5 * work;
  s.boundary = pick(fixed, boundary_fixed, boundary);
  s.boundary_ahead = pick(fixed, boundary_ahead_fixed, boundary_ahead);
  if constexpr (kDamp != DampKind::None) {
    const double drag = kDamp == DampKind::Local ? force - f : c.alpha * m * v_mid;
    const double damping = s.damping + drag * v_mid * dt, damping_ahead = s.damping_ahead + drag * v_free * half_dt;
    s.damping = pick(fixed, s.damping, damping);
    s.damping_ahead = pick(fixed, s.damping_ahead, damping_ahead);
  }
  const double v_new = pick(fixed, v, v_free);
  s.kinetic += 0.5 * m * v * v_new;
  return v_new;
}

// Balls [b0, b0 + n) of a motion loop: moves them and writes each one's terms of the global sums
// (terms[t][q], MotionTerm order) and its speed^2 (|v|^2 + |R w|^2) for the fastest ball. A ghost (a
// ball another rank or thread moves, kGhosts) is left as it is, its terms 0 and its speed -1.
// Balls [b0, b0 + n)'s dashpot power F_d . v + M_d . w at their velocities now (M_d = -R t_d).
template <bool kRot>
inline void dashpot_power(const Balls& b, std::size_t b0, std::size_t n, const DashpotForce* dash, double* out) {
  for (std::size_t q = 0; q < n; ++q) {
    const std::size_t i = b0 + q;
    const DashpotForce& d = dash[q];
    double p = d.fx * b.vx[i] + d.fy * b.vy[i] + d.fz * b.vz[i];
    if constexpr (kRot) p -= b.rad[i] * (d.tx * b.wx[i] + d.ty * b.wy[i] + d.tz * b.wz[i]);
    out[q] = p;
  }
}

enum MotionTerm { kFriction, kStrain, kImage, kKinetic, kSpin, kBoundary, kPotential, kDamping, kBoundaryAhead,
                  kDampingAhead, kTerms };
inline constexpr std::size_t kTermBlock = 128;
template <MotionFeatures M, bool kGhosts>
void motion_block(Balls& b, const StepScratch& scratch, const StepKernels& k, std::size_t b0, std::size_t n,
                  double (*__restrict terms)[kTermBlock], double* __restrict speed2) {
  constexpr bool kRot = M.rotation, kLoads = M.loads, kWriteForces = M.write_forces;
  const double dt = k.dt, dt_mean = k.dt_mean;
  // Mass-proportional damping, factor form: v' = (v (1 - a dt/2) + F/m dt) / (1 + a dt/2), dt_mean.
  const LaneConstants c{dt_mean, 0.5 * dt_mean, k.local, k.alpha, 1 - 0.5 * k.alpha * dt_mean,
                        1 / (1 + 0.5 * k.alpha * dt_mean)};
  const double gx = k.gravity[0], gy = k.gravity[1], gz = k.gravity[2];
  // The block's contact sums and parts, one array each (the structs' fields apart, so that the
  // loop below reads contiguous lanes): cf fx fy fz tx ty tz, pt by Part.
  enum Part { kPFriction, kPDamping, kPStrain, kPImage, kPBoundary, kPDampingAhead, kPBoundaryAhead, kParts };
  alignas(64) double cf[6][kTermBlock], pt[kParts][kTermBlock];
  // The fixities and ghost flags as 64-bit lanes, the width of the doubles they select between (a
  // byte beside doubles keeps g++ 12 from vectorising the loop).
  alignas(64) std::int64_t fixed[kTermBlock], ghost[kTermBlock];
  const std::uint8_t* __restrict fixed_bytes = b.fixed.data() + b0;
  const std::uint8_t* __restrict ghost_bytes = kGhosts ? scratch.ghost.data() + b0 : nullptr;
  const PairForce* __restrict force = scratch.ball_force.data() + b0;
  const BallParts* __restrict part = scratch.ball_parts.data() + b0;
  for (std::size_t q = 0; q < n; ++q) {
    cf[0][q] = force[q].fx; cf[1][q] = force[q].fy; cf[2][q] = force[q].fz;
    cf[3][q] = force[q].tx; cf[4][q] = force[q].ty; cf[5][q] = force[q].tz;
    pt[kPFriction][q] = part[q].friction; pt[kPDamping][q] = part[q].damping; pt[kPStrain][q] = part[q].strain;
    pt[kPImage][q] = part[q].image; pt[kPBoundary][q] = part[q].boundary;
    pt[kPDampingAhead][q] = part[q].damping_ahead; pt[kPBoundaryAhead][q] = part[q].boundary_ahead;
    fixed[q] = fixed_bytes[q];
    if constexpr (kGhosts) ghost[q] = ghost_bytes[q];
  }
  // Scenes with dashpots: each ball's dashpot power at v(t - dt/2), to take from the same at
  // v(t + dt/2) after the step (kDashpotAhead).
  const DashpotForce* __restrict dash = k.features.stiffness_damping ? scratch.ball_dashpot.data() + b0 : nullptr;
  alignas(64) double dash_power[kTermBlock];
  if (dash) dashpot_power<kRot>(b, b0, n, dash, dash_power);
  auto* __restrict x = b.x.data() + b0; auto* __restrict y = b.y.data() + b0; auto* __restrict z = b.z.data() + b0;
  auto* __restrict vx = b.vx.data() + b0; auto* __restrict vy = b.vy.data() + b0; auto* __restrict vz = b.vz.data() + b0;
  auto* __restrict wx = b.wx.data() + b0; auto* __restrict wy = b.wy.data() + b0; auto* __restrict wz = b.wz.data() + b0;
  const double* __restrict mass = b.mass.data() + b0;
  const double* __restrict inertia = b.inertia.data() + b0;
  const double* __restrict rad = b.rad.data() + b0;
  const double* __restrict ax = b.ax.data() + b0; const double* __restrict ay = b.ay.data() + b0;
  const double* __restrict az = b.az.data() + b0;
  const double* __restrict amx = b.amx.data() + b0; const double* __restrict amy = b.amy.data() + b0;
  const double* __restrict amz = b.amz.data() + b0;
  auto* __restrict ofx = b.fx.data() + b0; auto* __restrict ofy = b.fy.data() + b0; auto* __restrict ofz = b.fz.data() + b0;
  auto* __restrict omx = b.mx.data() + b0; auto* __restrict omy = b.my.data() + b0; auto* __restrict omz = b.mz.data() + b0;
  // (g++ takes no restrict from local pointers: without ivdep it would test every pair of arrays
  // for overlap at run time, more tests than it makes, and not vectorise.)
#pragma GCC ivdep
  for (std::size_t q = 0; q < n; ++q) {
    const bool g = kGhosts && ghost[q] != 0;
    double fx = cf[0][q], fy = cf[1][q], fz = cf[2][q];
    const double m = mass[q], inv_m = 1 / m;
    const std::int64_t fix = fixed[q];
    MotionSums s{pt[kPBoundary][q], pt[kPBoundaryAhead][q], pt[kPDamping][q], pt[kPDampingAhead][q], 0};
    double potential = 0;
    if constexpr (kLoads) {
      fx += ax[q] + m * gx; fy += ay[q] + m * gy; fz += az[q] + m * gz;
      potential -= m * (gx * x[q] + gy * y[q] + gz * z[q]);   // at t, where the forces were computed
    }
    const double nvx = advance_lane<M>(fx, kLoads ? ax[q] : 0.0, vx[q], inv_m, m, (fix & kXVel) != 0, c, s);
    const double nvy = advance_lane<M>(fy, kLoads ? ay[q] : 0.0, vy[q], inv_m, m, (fix & kYVel) != 0, c, s);
    const double nvz = advance_lane<M>(fz, kLoads ? az[q] : 0.0, vz[q], inv_m, m, (fix & kZVel) != 0, c, s);
    const double kinetic = s.kinetic;
    s.kinetic = 0;
    double sp2 = nvx * nvx + nvy * nvy + nvz * nvz;
    if constexpr (kWriteForces) {
      ofx[q] = pick(g, ofx[q], fx); ofy[q] = pick(g, ofy[q], fy); ofz[q] = pick(g, ofz[q], fz);
    }
    const double nx = x[q] + nvx * dt, ny = y[q] + nvy * dt, nz = z[q] + nvz * dt;
    x[q] = pick(g, x[q], nx); y[q] = pick(g, y[q], ny); z[q] = pick(g, z[q], nz);
    vx[q] = pick(g, vx[q], nvx); vy[q] = pick(g, vy[q], nvy); vz[q] = pick(g, vz[q], nvz);
    double spin = 0;
    if constexpr (kRot) {
      const double r = rad[q], in = inertia[q], inv_i = 1 / in;
      double mx = -r * cf[3][q], my = -r * cf[4][q], mz = -r * cf[5][q];
      if constexpr (kLoads) { mx += amx[q]; my += amy[q]; mz += amz[q]; }
      const double nwx = advance_lane<M>(mx, kLoads ? amx[q] : 0.0, wx[q], inv_i, in, (fix & kXSpin) != 0, c, s);
      const double nwy = advance_lane<M>(my, kLoads ? amy[q] : 0.0, wy[q], inv_i, in, (fix & kYSpin) != 0, c, s);
      const double nwz = advance_lane<M>(mz, kLoads ? amz[q] : 0.0, wz[q], inv_i, in, (fix & kZSpin) != 0, c, s);
      if constexpr (kWriteForces) {
        omx[q] = pick(g, omx[q], mx); omy[q] = pick(g, omy[q], my); omz[q] = pick(g, omz[q], mz);
      }
      wx[q] = pick(g, wx[q], nwx); wy[q] = pick(g, wy[q], nwy); wz[q] = pick(g, wz[q], nwz);
      sp2 += r * r * (nwx * nwx + nwy * nwy + nwz * nwz);
      spin = s.kinetic;
    }
    speed2[q] = pick(g, -1.0, sp2);
    terms[kFriction][q] = pick(g, 0.0, pt[kPFriction][q]);
    terms[kStrain][q] = pick(g, 0.0, pt[kPStrain][q]);
    terms[kImage][q] = pick(g, 0.0, pt[kPImage][q]);
    terms[kKinetic][q] = pick(g, 0.0, kinetic);
    terms[kSpin][q] = pick(g, 0.0, spin);
    terms[kBoundary][q] = pick(g, 0.0, s.boundary);
    terms[kPotential][q] = pick(g, 0.0, potential);
    terms[kDamping][q] = pick(g, 0.0, s.damping);
    terms[kBoundaryAhead][q] = pick(g, 0.0, s.boundary_ahead);
    terms[kDampingAhead][q] = pick(g, 0.0, s.damping_ahead);
  }
  if (dash) {
    alignas(64) double after[kTermBlock];
    dashpot_power<kRot>(b, b0, n, dash, after);
    for (std::size_t q = 0; q < n; ++q) {
      const double more = (kGhosts && ghost[q] != 0) ? 0.0 : (dash_power[q] - after[q]) * (0.5 * dt_mean);
      terms[kDamping][q] += more;
      terms[kDampingAhead][q] += more;
    }
  }
}

template <MotionFeatures M>
void motion_loop(Model& model, const StepScratch& scratch, const StepKernels& k, std::size_t begin, std::size_t end,
                 StepSums& sums) {
  constexpr bool kRot = M.rotation;
  constexpr bool kLoads = M.loads;
  constexpr StepEstimate kEstimate = M.estimate;
  Balls& b = model.balls;
  double omega2_max = 0, step_min = std::numeric_limits<double>::infinity();
  double fastest2 = -1;
  std::size_t fastest = begin;
  ExactSum::Stream kinetic_sum(sums.kinetic_translation), spin_sum(sums.kinetic_rotation),
      boundary_sum(sums.boundary_work), potential_sum(sums.potential), damping_sum(sums.damping_work),
      friction_sum(sums.friction_work), strain_sum(sums.strain), image_sum(sums.image_power),
      boundary_ahead_sum(sums.boundary_ahead), damping_ahead_sum(sums.damping_ahead);
  // Each block's terms go to the streams a block at a time (ExactSum::Stream::add_block: vector
  // arithmetic where the block fits the window). The sums are exact, so when a term goes in (and
  // the ghosts' zeros) changes no bit.
  alignas(64) double terms[kTerms][kTermBlock];
  alignas(64) double speed2[kTermBlock];
  const bool periodic = model.space.periodic;
  const bool ghosts = !scratch.ghost.empty();
  const bool energies = k.energies, kinetic = k.energies || k.kinetic;
  for (std::size_t b0 = begin; b0 < end; b0 += kTermBlock) {
    const std::size_t n = std::min(kTermBlock, end - b0);
    if (ghosts) motion_block<M, true>(b, scratch, k, b0, n, terms, speed2);
    else motion_block<M, false>(b, scratch, k, b0, n, terms, speed2);
    if (k.moments) [[unlikely]]
      for (std::size_t q = 0; q < n; ++q)
        if (!ghosts || !scratch.ghost[b0 + q]) add_moments(sums, scratch.ball_moments[b0 + q]);
    // The works every step; the energy terms at t where the step forms them (StepKernels::energies).
    friction_sum.add_block(terms[kFriction], n);
    if (periodic) image_sum.add_block(terms[kImage], n);
    boundary_sum.add_block(terms[kBoundary], n);
    damping_sum.add_block(terms[kDamping], n);
    if (kinetic) {
      kinetic_sum.add_block(terms[kKinetic], n);
      if constexpr (kRot) spin_sum.add_block(terms[kSpin], n);
    }
    if (energies) {
      strain_sum.add_block(terms[kStrain], n);
      if constexpr (kLoads) potential_sum.add_block(terms[kPotential], n);
      boundary_ahead_sum.add_block(terms[kBoundaryAhead], n);
      damping_ahead_sum.add_block(terms[kDampingAhead], n);
    }
    // The fastest ball: the first of the largest, a NaN before any number.
    for (std::size_t q = 0; q < n; ++q)
      if (speed2[q] > fastest2 || (std::isnan(speed2[q]) && !std::isnan(fastest2))) { fastest2 = speed2[q]; fastest = b0 + q; }
    if constexpr (kEstimate != StepEstimate::None) {
      for (std::size_t q = 0; q < n; ++q) {
        const std::size_t ball = b0 + q;
        if (ghosts && scratch.ghost[ball]) continue;
        // A ball held in every component sets no step of its own.
        if (ball_held(b.fixed[ball], kRot)) continue;
        const PairForce& pf = scratch.ball_force[ball];
        const double m = b.mass[ball];
        double sum_kmax = pf.kmax, sum_ks = pf.ks, sum_cn = kEstimate == StepEstimate::Damped ? scratch.ball_cn[ball] : 0;
        if (sum_kmax == 0)   // no contact: as if touching one ball of its own type
          alone_sums(k.laws, ball, m, sum_kmax, sum_ks, kEstimate == StepEstimate::Damped ? &sum_cn : nullptr);
        const double omega2 = ball_omega2(m, sum_kmax, sum_ks, kRot);
        if constexpr (kEstimate == StepEstimate::Undamped) {
          omega2_max = std::max(omega2_max, omega2);
        } else if (omega2 > 0) {
          const double omega = std::sqrt(omega2);
          step_min = std::min(step_min, damped_critical_step(omega, 0.5 * k.beta * omega + sum_cn / (m * omega)));
        }
      }
    }
  }
  if constexpr (kEstimate == StepEstimate::Undamped)
    if (omega2_max > 0) step_min = 2 / std::sqrt(omega2_max);
  sums.take_step(step_min);
  if (begin < end) sums.take_fastest(fastest2, fastest);
}

}  // namespace trubal::loops
