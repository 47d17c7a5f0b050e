// The contact loops of one step (kernel_loops.hpp says how the step's loops are laid out): the
// pairs of a block of balls, and the cross pairs a thread adds first.
#pragma once

#include "cycle/kernel_loops.hpp"

namespace trubal::loops {

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
  TRUBAL_PTR(mrx, c.mrx); TRUBAL_PTR(mry, c.mry); TRUBAL_PTR(mrz, c.mrz);
  TRUBAL_PTR(state, c.state);
  TRUBAL_PTR(ball_sum, scratch.ball_force); TRUBAL_PTR(cn_sum, scratch.ball_cn);
  DashpotForce* __restrict dash_sum = kLaw.dashpot ? scratch.ball_dashpot.data() : nullptr;
  RollingMoment* __restrict roll_sum = kLaw.rolling ? scratch.ball_rolling.data() : nullptr;
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
  alignas(64) double rx[kBatch], ry[kBatch], rz[kBatch];   // (F.rolling: the rolling moments)
  // The running sum of the ball whose pairs the list is on.
  constexpr std::size_t kNone = ~std::size_t{0};
  std::size_t acc_ball = kNone;
  PairForce acc{};
  double acc_cn = 0;
  DashpotForce acc_dash{};
  RollingMoment acc_roll{};
  auto flush = [&] {
    if (acc_ball == kNone) return;
    ball_sum[acc_ball] = acc;
    if constexpr (kLaw.dashpot) { cn_sum[acc_ball] = acc_cn; dash_sum[acc_ball] = acc_dash; }
    if constexpr (kLaw.rolling) roll_sum[acc_ball] = acc_roll;
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
    const RollingLanes roll{{mrx + p0, mry + p0, mrz + p0}, {rx, ry, rz}};
    contact_forces<kLaw, kOneLaw>(B, count, one_law, dt, dt_work, beta, fsx + p0, fsy + p0, fsz + p0, hx, hy, hz, &clean_run,
                                  &roll);
    if constexpr (kLaw.shear) {   // the batch's new history goes back where it was read
      std::copy(hx, hx + count, fsx + p0);
      std::copy(hy, hy + count, fsy + p0);
      std::copy(hz, hz + count, fsz + p0);
    }
    if constexpr (kLaw.rolling) {
      std::copy(rx, rx + count, mrx + p0);
      std::copy(ry, ry + count, mry + p0);
      std::copy(rz, rz + count, mrz + p0);
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
        if constexpr (kLaw.rolling) acc_roll = roll_sum[acc_ball];
      }
      acc.fx -= B.fx[q]; acc.fy -= B.fy[q]; acc.fz -= B.fz[q];
      if constexpr (kLaw.rotation) { acc.tx += B.tx[q]; acc.ty += B.ty[q]; acc.tz += B.tz[q]; }
      if (sum_stiffness) {
        acc.kmax += kmax; acc.ks += B.ks[q];
        if constexpr (kLaw.rolling) acc.ks += rolling_ks(B.ks[q], B.rj[q] / (B.ri[q] + B.rj[q]));
      }
      if constexpr (kLaw.dashpot) {
        acc_cn += B.cn[q];
        acc_dash.fx -= B.dfx[q]; acc_dash.fy -= B.dfy[q]; acc_dash.fz -= B.dfz[q];
        acc_dash.tx += B.dtx[q]; acc_dash.ty += B.dty[q]; acc_dash.tz += B.dtz[q];
      }
      if constexpr (kLaw.rolling) {
        acc_roll.mx -= rx[q]; acc_roll.my -= ry[q]; acc_roll.mz -= rz[q];
        acc_roll.work += B.work_rolling[q];
      }
      if (pj[p] < own_end) {
        PairForce& fj = ball_sum[pj[p]];
        fj.fx += B.fx[q]; fj.fy += B.fy[q]; fj.fz += B.fz[q];
        if constexpr (kLaw.rotation) { fj.tx += B.tx[q]; fj.ty += B.ty[q]; fj.tz += B.tz[q]; }
        if (sum_stiffness) {
          fj.kmax += kmax; fj.ks += B.ks[q];
          if constexpr (kLaw.rolling) fj.ks += rolling_ks(B.ks[q], B.ri[q] / (B.ri[q] + B.rj[q]));
        }
        if constexpr (kLaw.dashpot) {
          cn_sum[pj[p]] += B.cn[q];
          add_dashpot(dash_sum[pj[p]], B, q);
        }
        if constexpr (kLaw.rolling) {
          RollingMoment& mj = roll_sum[pj[p]];
          mj.mx += rx[q]; mj.my += ry[q]; mj.mz += rz[q];
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
  if constexpr (F.rolling)
    std::fill(scratch.ball_rolling.begin() + ball_begin, scratch.ball_rolling.begin() + ball_end, RollingMoment{});
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
  alignas(64) double rx[kBatch], ry[kBatch], rz[kBatch], mx[kBatch], my[kBatch], mz[kBatch];
  const RollingLanes roll{{rx, ry, rz}, {mx, my, mz}};
  const double* rolling_history = history + ContactTable::rolling_history_at() * pair_count;
  for (std::size_t q0 = 0; q0 < pair_count; q0 += kBatch) {
    const std::size_t count = std::min(kBatch, pair_count - q0);
    for (std::size_t q = 0; q < count; ++q) {
      const std::size_t p = pairs[q0 + q];
      if (one_law) in.gather<F, true>(B, q, k, p, pi[p], pj[p]);
      else in.gather<F, false>(B, q, k, p, pi[p], pj[p]);
      if constexpr (F.shear) {
        hx[q] = history[q0 + q]; hy[q] = history[pair_count + q0 + q]; hz[q] = history[2 * pair_count + q0 + q];
      }
      if constexpr (F.rolling) {
        rx[q] = rolling_history[q0 + q]; ry[q] = rolling_history[pair_count + q0 + q];
        rz[q] = rolling_history[2 * pair_count + q0 + q];
      }
    }
    // The new history is the owner's to write: here it goes to a scratch copy, unread.
    if (one_law) contact_forces<F, true>(B, count, law, k.dt_prev, k.dt_mean, k.beta, hx, hy, hz, ox, oy, oz, &clean_run, &roll);
    else contact_forces<F, false>(B, count, law, k.dt_prev, k.dt_mean, k.beta, hx, hy, hz, ox, oy, oz, &clean_run, &roll);
    for (std::size_t q = 0; q < count; ++q) {
      const std::size_t j = pj[pairs[q0 + q]];
      PairForce& fj = scratch.ball_force[j];
      fj.fx += B.fx[q]; fj.fy += B.fy[q]; fj.fz += B.fz[q];
      if constexpr (F.rotation) { fj.tx += B.tx[q]; fj.ty += B.ty[q]; fj.tz += B.tz[q]; }
      if (k.sums_stiffness()) {
        fj.kmax += std::max(B.kn[q], B.ks[q]); fj.ks += B.ks[q];
        if constexpr (F.rolling) fj.ks += rolling_ks(B.ks[q], B.ri[q] / (B.ri[q] + B.rj[q]));
      }
      if constexpr (F.dashpot) {
        scratch.ball_cn[j] += B.cn[q];
        add_dashpot(scratch.ball_dashpot[j], B, q);
      }
      if constexpr (F.rolling) {
        RollingMoment& mj = scratch.ball_rolling[j];
        mj.mx += mx[q]; mj.my += my[q]; mj.mz += mz[q];
      }
    }
  }
}

}  // namespace trubal::loops
