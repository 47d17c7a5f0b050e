// The loops of one time step as templates over the features a scene uses (doc/physics.md "Law of
// motion"): the per-contact loop (adding each pair to its balls' sums), the cross pairs, the wall
// contacts and the per-ball law of motion. Included only by the files that instantiate their tables
// (kernels_*.cpp, a few tables each, so that a parallel build compiles them side by side);
// make_kernels (kernels.cpp) picks one entry of each per CYCLE.
#pragma once

#include "cycle/kernel_tables.hpp"
#include "model/periodic_cell.hpp"
#include "physics/timestep.hpp"
#include "physics/walls.hpp"

#include <bit>
#include <utility>

namespace trubal::loops {

// Raw pointers, so that the compiler knows the stores into one array cannot move another's data.
#define TRUBAL_PTR(name, vec) auto* __restrict name = (vec).data()

// The ball data the contact loops read, and the one gather of a pair's inputs into a batch lane.
struct PairInputs {
  const double *x, *y, *z, *rad, *mass, *vx, *vy, *vz, *wx, *wy, *wz;
  const std::uint8_t* fixed;
  const std::int8_t *img_x, *img_y, *img_z;
  bool periodic;
  CellFrame cell;   // periodic space: j's image is x_j + H image, moving at v_j + (dH/dt) image
  // CellFrame::moving. (In a still cell every image velocity is +-0: the gather leaves it out, and
  // the batch's ivx, ivy, ivz are not written.)
  bool cell_moving;
  PairInputs(const Model& model)
      : x(model.balls.x.data()), y(model.balls.y.data()), z(model.balls.z.data()), rad(model.balls.rad.data()),
        mass(model.balls.mass.data()), vx(model.balls.vx.data()), vy(model.balls.vy.data()), vz(model.balls.vz.data()),
        wx(model.balls.wx.data()), wy(model.balls.wy.data()), wz(model.balls.wz.data()), fixed(model.balls.fixed.data()),
        img_x(model.contacts.image_x.data()), img_y(model.contacts.image_y.data()), img_z(model.contacts.image_z.data()),
        periodic(model.space.periodic), cell(cell_frame(model.space)),
        cell_moving(periodic && cell.moving()) {}

  // Lane q of B gets pair p (balls i < j): separation, radii, relative velocity (image included),
  // the spin term, m*, and the pair's law where the scene has several.
  template <ContactFeatures F, bool kOneLaw>
  void gather(ContactBatch& B, std::size_t q, const StepKernels& k, std::size_t p, std::size_t i, std::size_t j) const {
    if constexpr (!kOneLaw) B.set_law(q, k.laws.law(i, j));
    B.dx[q] = x[j] - x[i]; B.dy[q] = y[j] - y[i]; B.dz[q] = z[j] - z[i];
    B.ri[q] = rad[i]; B.rj[q] = rad[j];
    B.vx[q] = vx[j] - vx[i]; B.vy[q] = vy[j] - vy[i]; B.vz[q] = vz[j] - vz[i];
    if (periodic) {
      double ox, oy, oz;
      image_offset(cell, img_x[p], img_y[p], img_z[p], ox, oy, oz);
      B.dx[q] = image_delta(x[j], x[i], ox);
      B.dy[q] = image_delta(y[j], y[i], oy);
      B.dz[q] = image_delta(z[j], z[i], oz);
      if (cell_moving) {
        image_velocity(cell, img_x[p], img_y[p], img_z[p], B.ivx[q], B.ivy[q], B.ivz[q]);
        B.vx[q] += B.ivx[q]; B.vy[q] += B.ivy[q]; B.vz[q] += B.ivz[q];
      }
    }
    if constexpr (F.rotation) {
      B.sx[q] = rad[i] * wx[i] + rad[j] * wx[j];
      B.sy[q] = rad[i] * wy[i] + rad[j] * wy[j];
      B.sz[q] = rad[i] * wz[i] + rad[j] * wz[j];
    }
    if constexpr (F.dashpot) B.mstar[q] = pair_mstar(mass[i], mass[j], velocity_held(fixed[i]), velocity_held(fixed[j]));
  }
};

// The dashpots' work (doc/physics.md "Energy"). The law of motion charges every force F(t) with
// F(t) . (v(t - dt/2) + v(t + dt/2)) / 2 dt_mean, half of it after t: the dashpots too, however
// their force jumps where a contact starts or ends. A contact's loop knows the relative velocity
// before the step: it books F(t) . V(t - dt/2) dt_mean (half of it after t), as if the velocity
// stayed; the law of motion adds, per ball, the dashpot force (DashpotForce) times the change of
// the ball's velocity over the step, half of dt_mean, to the work and to its part after t.
constexpr double kDashpotAhead = 0.5;

// Lane q's dashpot part to ball j's sums (as PairForce's: +F on j, and t).
[[gnu::always_inline]] inline void add_dashpot(DashpotForce& d, const ContactBatch& B, std::size_t q) {
  d.fx += B.dfx[q]; d.fy += B.dfy[q]; d.fz += B.dfz[q];
  d.tx += B.dtx[q]; d.ty += B.dty[q]; d.tz += B.dtz[q];
}

// The pairs of [begin, end), by the law F composes; F.details: also write what measurements read
// (normal, overlap, forces, stiffness, dashpot coefficient, work, state). Without it a step writes
// only the new shear history and the sums per ball (StepScratch::ball_force, ball_cn).
template <ContactFeatures F, bool kOneLaw>
void contact_range(Model& model, StepScratch& scratch, const StepKernels& k, std::size_t begin, std::size_t end, std::size_t own_end) {
  constexpr ContactFeatures kLaw = F.law();
  constexpr bool kFull = F.details;
  ContactTable& c = model.contacts;
  TRUBAL_PTR(pi, c.i); TRUBAL_PTR(pj, c.j);
  TRUBAL_PTR(fsx, c.fsx); TRUBAL_PTR(fsy, c.fsy); TRUBAL_PTR(fsz, c.fsz);
  TRUBAL_PTR(state, c.state);
  TRUBAL_PTR(ball_sum, scratch.ball_force); TRUBAL_PTR(cn_sum, scratch.ball_cn);
  DashpotForce* __restrict dash_sum = kLaw.dashpot ? scratch.ball_dashpot.data() : nullptr;
  const PairInputs in(model);
  const double dt = k.dt_prev, dt_work = k.dt_mean, beta = k.beta;
  const PairLaw& one_law = k.laws.ball_law();
  const bool sum_stiffness = k.sums_stiffness();
  // A periodic cell that does not move gives every image a velocity of +-0 and the image power
  // sum stays +0: the products are left out. (Without a dashpot, every work_damping is +0 too.)
  const bool cell_moving = in.cell_moving;
  // The global sums of the ball whose run of pairs the list is on (in list order), kept as the
  // ball's parts when the run ends (StepScratch::ball_parts): the motion loop hands them on.
  double work_friction = 0, work_damping = 0, strain = 0, image_power = 0;
  std::array<double, 9> moments{};   // force_moment (6), then stiffness_moment (3)
  BallParts* __restrict parts = scratch.ball_parts.data();
  ContactBatch B;
  int clean_run = 0;   // batches in a row without a sliding contact (contact_forces)
  // The new history of a batch is made here, then copied over the old (the cross pairs another
  // thread computes read a copy of it: CrossLoop).
  alignas(64) double hx[kBatch], hy[kBatch], hz[kBatch];
  // The running sum of the ball whose pairs the list is on.
  constexpr std::size_t kNone = ~std::size_t{0};
  std::size_t acc_ball = kNone;
  PairForce acc{};
  double acc_cn = 0;
  DashpotForce acc_dash{};
  auto flush = [&] {
    if (acc_ball == kNone) return;
    ball_sum[acc_ball] = acc;
    if constexpr (kLaw.dashpot) { cn_sum[acc_ball] = acc_cn; dash_sum[acc_ball] = acc_dash; }
    parts[acc_ball] = {work_friction, work_damping, strain, image_power, 0.0, kDashpotAhead * work_damping, 0.0};
    work_friction = work_damping = strain = image_power = 0;
    if (k.moments) [[unlikely]] {
      scratch.ball_moments[acc_ball] = moments;
      moments = {};
    }
  };
  for (std::size_t p0 = begin; p0 < end; p0 += kBatch) {
    const std::size_t count = std::min(kBatch, end - p0);
    for (std::size_t q = 0; q < count; ++q) {
      const std::size_t p = p0 + q;
      in.gather<kLaw, kOneLaw>(B, q, k, p, pi[p], pj[p]);
    }
    contact_forces<kLaw, kOneLaw>(B, count, one_law, dt, dt_work, beta, fsx + p0, fsy + p0, fsz + p0, hx, hy, hz, &clean_run);
    if constexpr (kLaw.shear) {   // the batch's new history goes back where it was read
      std::copy(hx, hx + count, fsx + p0);
      std::copy(hy, hy + count, fsy + p0);
      std::copy(hz, hz + count, fsz + p0);
    }
    for (std::size_t q = 0; q < count; ++q) {
      const std::size_t p = p0 + q;
      const double kmax = std::max(B.kn[q], B.ks[q]);
      // Ball j gets +F, ball i -F; both get the moment term and the stiffness. In list order a
      // ball first meets its pairs with lower partners, ascending, then those with higher ones:
      // the order of the gather index (build_gather). Ball i's sum stays in registers while the
      // list stays on i (its run of pairs). A j beyond own_end belongs to a later thread, which
      // adds this pair itself (cross_loop).
      if (pi[p] != acc_ball) {
        flush();
        acc_ball = pi[p];
        acc = ball_sum[acc_ball];
        if constexpr (kLaw.dashpot) { acc_cn = cn_sum[acc_ball]; acc_dash = dash_sum[acc_ball]; }
      }
      acc.fx -= B.fx[q]; acc.fy -= B.fy[q]; acc.fz -= B.fz[q];
      if constexpr (kLaw.rotation) { acc.tx += B.tx[q]; acc.ty += B.ty[q]; acc.tz += B.tz[q]; }
      if (sum_stiffness) { acc.kmax += kmax; acc.ks += B.ks[q]; }
      if constexpr (kLaw.dashpot) {
        acc_cn += B.cn[q];
        acc_dash.fx -= B.dfx[q]; acc_dash.fy -= B.dfy[q]; acc_dash.fz -= B.dfz[q];
        acc_dash.tx += B.dtx[q]; acc_dash.ty += B.dty[q]; acc_dash.tz += B.dtz[q];
      }
      if (pj[p] < own_end) {
        PairForce& fj = ball_sum[pj[p]];
        fj.fx += B.fx[q]; fj.fy += B.fy[q]; fj.fz += B.fz[q];
        if constexpr (kLaw.rotation) { fj.tx += B.tx[q]; fj.ty += B.ty[q]; fj.tz += B.tz[q]; }
        if (sum_stiffness) { fj.kmax += kmax; fj.ks += B.ks[q]; }
        if constexpr (kLaw.dashpot) {
          cn_sum[pj[p]] += B.cn[q];
          add_dashpot(dash_sum[pj[p]], B, q);
        }
      }
      if (cell_moving) image_power -= B.fx[q] * B.ivx[q] + B.fy[q] * B.ivy[q] + B.fz[q] * B.ivz[q];
      if (k.moments) {   // force on j times the branch vector i -> j (zero where apart)
        const double fx = B.fx[q], fy = B.fy[q], fz = B.fz[q], lx = B.dx[q], ly = B.dy[q], lz = B.dz[q];
        moments[0] += fx * lx; moments[1] += fy * ly; moments[2] += fz * lz;
        moments[3] += 0.5 * (fx * ly + fy * lx);
        moments[4] += 0.5 * (fx * lz + fz * lx);
        moments[5] += 0.5 * (fy * lz + fz * ly);
        moments[6] += B.kn[q] * lx * lx;
        moments[7] += B.kn[q] * ly * ly;
        moments[8] += B.kn[q] * lz * lz;
      }
      work_friction += B.work_friction[q];
      if constexpr (kLaw.dashpot) work_damping += B.work_damping[q];
      strain += B.strain[q];
    }
    if constexpr (kFull) {
      // One array at a time: writing ~15 arrays element by element thrashes the cache when their
      // starts share a page offset, as large std::vector allocations do.
      auto put = [&](std::vector<double>& to, const double* from) { std::copy(from, from + count, to.data() + p0); };
      put(c.nx, B.nx); put(c.ny, B.ny); put(c.nz, B.nz); put(c.overlap, B.overlap); put(c.fn, B.fn);
      put(c.fx, B.fx); put(c.fy, B.fy); put(c.fz, B.fz); put(c.tx, B.tx); put(c.ty, B.ty); put(c.tz, B.tz);
      put(c.kn_eff, B.kn); put(c.ks_eff, B.ks); put(c.work_friction, B.work_friction);
      put(c.work_damping, B.work_damping); put(c.cn_eff, B.cn);
      for (std::size_t q = 0; q < count; ++q) state[p0 + q] = static_cast<std::uint8_t>(B.state[q]);
    }
  }
  flush();
}

template <ContactFeatures F>
void contact_loop(Model& model, StepScratch& scratch, const StepKernels& k, std::size_t begin, std::size_t end,
                  std::size_t own_end) {
  if (k.laws.one_ball_law()) contact_range<F, true>(model, scratch, k, begin, end, own_end);
  else contact_range<F, false>(model, scratch, k, begin, end, own_end);
}

// Pairs (i, j) with i below ball_begin and j in [ball_begin, ball_end), given in list order (so
// ascending i for each j, and the owner's data read in order): their forces on j, added first
// (lower partners come first in j's order), from the history before this step (`history`, a copy:
// CrossLoop). The thread that owns i computes the same pairs with the same arithmetic.
template <ContactFeatures F>
void cross_loop(Model& model, StepScratch& scratch, const StepKernels& k, std::size_t ball_begin, std::size_t ball_end,
                const std::uint32_t* pairs, std::size_t pair_count, const double* history) {
  ContactTable& c = model.contacts;
  std::fill(scratch.ball_force.begin() + ball_begin, scratch.ball_force.begin() + ball_end, PairForce{});
  std::fill(scratch.ball_cn.begin() + ball_begin, scratch.ball_cn.begin() + ball_end, 0.0);
  if constexpr (F.dashpot)
    std::fill(scratch.ball_dashpot.begin() + ball_begin, scratch.ball_dashpot.begin() + ball_end, DashpotForce{});
  std::fill(scratch.ball_parts.begin() + ball_begin, scratch.ball_parts.begin() + ball_end, BallParts{});
  if (k.moments) std::fill(scratch.ball_moments.begin() + ball_begin, scratch.ball_moments.begin() + ball_end, std::array<double, 9>{});
  if (pair_count == 0) return;
  TRUBAL_PTR(pi, c.i); TRUBAL_PTR(pj, c.j);
  const PairInputs in(model);
  const bool one_law = k.laws.one_ball_law();
  const PairLaw& law = k.laws.ball_law();
  ContactBatch B;
  int clean_run = 0;   // batches in a row without a sliding contact (contact_forces)
  alignas(64) double hx[kBatch], hy[kBatch], hz[kBatch], ox[kBatch], oy[kBatch], oz[kBatch];
  for (std::size_t q0 = 0; q0 < pair_count; q0 += kBatch) {
    const std::size_t count = std::min(kBatch, pair_count - q0);
    for (std::size_t q = 0; q < count; ++q) {
      const std::size_t p = pairs[q0 + q];
      if (one_law) in.gather<F, true>(B, q, k, p, pi[p], pj[p]);
      else in.gather<F, false>(B, q, k, p, pi[p], pj[p]);
      if constexpr (F.shear) {
        hx[q] = history[q0 + q]; hy[q] = history[pair_count + q0 + q]; hz[q] = history[2 * pair_count + q0 + q];
      }
    }
    // The new history is the owner's to write: here it goes to a scratch copy, unread.
    if (one_law) contact_forces<F, true>(B, count, law, k.dt_prev, k.dt_mean, k.beta, hx, hy, hz, ox, oy, oz, &clean_run);
    else contact_forces<F, false>(B, count, law, k.dt_prev, k.dt_mean, k.beta, hx, hy, hz, ox, oy, oz, &clean_run);
    for (std::size_t q = 0; q < count; ++q) {
      const std::size_t j = pj[pairs[q0 + q]];
      PairForce& fj = scratch.ball_force[j];
      fj.fx += B.fx[q]; fj.fy += B.fy[q]; fj.fz += B.fz[q];
      if constexpr (F.rotation) { fj.tx += B.tx[q]; fj.ty += B.ty[q]; fj.tz += B.tz[q]; }
      if (k.sums_stiffness()) { fj.kmax += std::max(B.kn[q], B.ks[q]); fj.ks += B.ks[q]; }
      if constexpr (F.dashpot) {
        scratch.ball_cn[j] += B.cn[q];
        add_dashpot(scratch.ball_dashpot[j], B, q);
      }
    }
  }
}


// The ball-wall contacts [begin, end) by the pair law (physics/walls.hpp: the wall as a partner j of
// radius 2R), each added to its ball's sum after the ball's pairs (so in wall order) and to its
// wall's load; the wall's work on the balls is boundary work.
template <ContactFeatures F>
void wall_loop(Model& model, StepScratch& scratch, const StepKernels& k, std::size_t begin, std::size_t end,
               WallLoad* loads) {
  constexpr ContactFeatures kLaw = F.law();
  if (begin >= end) return;
  WallContacts& c = model.wall_contacts;
  const Balls& b = model.balls;
  const std::vector<Wall>& walls = model.walls;
  ContactBatch B;
  alignas(64) double hx[kBatch], hy[kBatch], hz[kBatch];
  Vec3 point[kBatch], surface[kBatch];
  for (std::size_t p0 = begin; p0 < end; p0 += kBatch) {
    const std::size_t count = std::min(kBatch, end - p0);
    for (std::size_t q = 0; q < count; ++q) {
      const std::size_t p = p0 + q, i = c.ball[p];
      const WallLane lane = wall_lane(walls[c.wall[p]], {b.x[i], b.y[i], b.z[i]}, b.rad[i]);
      B.set_law(q, k.laws.wall_law(i, c.wall[p]));
      B.dx[q] = lane.dx; B.dy[q] = lane.dy; B.dz[q] = lane.dz;
      B.ri[q] = lane.r; B.rj[q] = lane.r;
      B.vx[q] = lane.velocity[0] - b.vx[i]; B.vy[q] = lane.velocity[1] - b.vy[i]; B.vz[q] = lane.velocity[2] - b.vz[i];
      if constexpr (kLaw.rotation) {
        B.sx[q] = b.rad[i] * b.wx[i]; B.sy[q] = b.rad[i] * b.wy[i]; B.sz[q] = b.rad[i] * b.wz[i];
      }
      if constexpr (kLaw.dashpot) B.mstar[q] = b.mass[i];
      point[q] = lane.point;
      surface[q] = lane.velocity;
    }
    contact_forces<kLaw, false>(B, count, k.laws.table[0], k.dt_prev, k.dt_mean, k.beta, c.fsx.data() + p0, c.fsy.data() + p0,
                                c.fsz.data() + p0, hx, hy, hz);
    for (std::size_t q = 0; q < count; ++q) {
      const std::size_t p = p0 + q, i = c.ball[p];
      if constexpr (kLaw.shear) { c.fsx[p] = hx[q]; c.fsy[p] = hy[q]; c.fsz[p] = hz[q]; }
      PairForce& fi = scratch.ball_force[i];
      fi.fx -= B.fx[q]; fi.fy -= B.fy[q]; fi.fz -= B.fz[q];
      if constexpr (kLaw.rotation) { fi.tx += B.tx[q]; fi.ty += B.ty[q]; fi.tz += B.tz[q]; }
      if (k.sums_stiffness()) { fi.kmax += std::max(B.kn[q], B.ks[q]); fi.ks += B.ks[q]; }
      if constexpr (kLaw.dashpot) {
        scratch.ball_cn[i] += B.cn[q];
        DashpotForce& d = scratch.ball_dashpot[i];
        d.fx -= B.dfx[q]; d.fy -= B.dfy[q]; d.fz -= B.dfz[q];
        d.tx += B.dtx[q]; d.ty += B.dty[q]; d.tz += B.dtz[q];
      }
      const Wall& w = walls[c.wall[p]];
      WallLoad& load = loads[c.wall[p]];
      const double fx = B.fx[q], fy = B.fy[q], fz = B.fz[q];
      const double ax = point[q][0] - w.spin_point[0], ay = point[q][1] - w.spin_point[1], az = point[q][2] - w.spin_point[2];
      const double power = -(fx * surface[q][0] + fy * surface[q][1] + fz * surface[q][2]);   // the wall's on the ball
      // Each contact goes to the exact sums on its own (the same additions wherever it is computed).
      load.fx.add(fx); load.fy.add(fy); load.fz.add(fz);
      load.mx.add(ay * fz - az * fy); load.my.add(az * fx - ax * fz); load.mz.add(ax * fy - ay * fx);
      load.normal_force.add(B.fn[q]);
      load.stiffness.add(B.kn[q]);
      load.work.add(power * k.dt_mean);
      load.contacts += B.state[q] != 0;
      // A moving surface: the touching ball's kinetic energy in the wall's frame (Wall::relative_kinetic).
      const double rx = surface[q][0] - b.vx[i], ry = surface[q][1] - b.vy[i], rz = surface[q][2] - b.vz[i];
      if (B.state[q] != 0 && (surface[q][0] != 0 || surface[q][1] != 0 || surface[q][2] != 0))
        load.relative_kinetic.add(0.5 * b.mass[i] * (rx * rx + ry * ry + rz * rz));
      BallParts& part = scratch.ball_parts[i];
      part.boundary += power * k.dt_mean;
      part.boundary_ahead += power * (0.5 * k.dt_mean);   // the wall moves on with the balls: half after t
      part.friction += B.work_friction[q];
      part.damping += B.work_damping[q];
      part.damping_ahead += kDashpotAhead * B.work_damping[q];
      part.strain += B.strain[q];
    }
    if constexpr (F.details) {
      for (std::size_t q = 0; q < count; ++q) {
        const std::size_t p = p0 + q;
        c.nx[p] = B.nx[q]; c.ny[p] = B.ny[q]; c.nz[p] = B.nz[q]; c.overlap[p] = B.overlap[q]; c.fn[p] = B.fn[q];
        c.fx[p] = B.fx[q]; c.fy[p] = B.fy[q]; c.fz[p] = B.fz[q];
        c.kn_eff[p] = B.kn[q]; c.ks_eff[p] = B.ks[q];
        c.state[p] = static_cast<std::uint8_t>(B.state[q]);
      }
    }
  }
}

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
  for (std::size_t b0 = begin; b0 < end; b0 += kTermBlock) {
    const std::size_t n = std::min(kTermBlock, end - b0);
    if (ghosts) motion_block<M, true>(b, scratch, k, b0, n, terms, speed2);
    else motion_block<M, false>(b, scratch, k, b0, n, terms, speed2);
    if (k.moments) [[unlikely]]
      for (std::size_t q = 0; q < n; ++q)
        if (!ghosts || !scratch.ghost[b0 + q]) add_moments(sums, scratch.ball_moments[b0 + q]);
    friction_sum.add_block(terms[kFriction], n);
    strain_sum.add_block(terms[kStrain], n);
    if (periodic) image_sum.add_block(terms[kImage], n);
    kinetic_sum.add_block(terms[kKinetic], n);
    if constexpr (kRot) spin_sum.add_block(terms[kSpin], n);
    boundary_sum.add_block(terms[kBoundary], n);
    if constexpr (kLoads) potential_sum.add_block(terms[kPotential], n);
    damping_sum.add_block(terms[kDamping], n);
    boundary_ahead_sum.add_block(terms[kBoundaryAhead], n);
    damping_ahead_sum.add_block(terms[kDampingAhead], n);
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

#undef TRUBAL_PTR

}  // namespace trubal::loops
