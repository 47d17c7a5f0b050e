// The force at one contact (doc/physics.md "Contacts" and "Damping"). Every backend calls this one
// function, so the arithmetic, and therefore the answer, is the same whichever pairs a backend
// visits and however it spreads them over threads.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>

#include "physics/contact/energy.hpp"
#include "physics/contact/models.hpp"

namespace trubal {

// Properties of a pair of ball types, already mixed (doc/physics.md: springs in series, mu = min).
struct PairLaw {
  double kn = 0, ks = 0;          // linear springs
  double friction = 0, cohesion = 0;
  double hertz_n = 0;             // Hertz: F_n = hertz_n sqrt(R*) U^1.5, hertz_n = 4/3 E*
  double hertz_s = 0;             // Mindlin: k_s = hertz_s sqrt(R* U), hertz_s = 8 G*
  double rest_xi = 0;             // restitution dashpot damping ratio (0: none)
  double rolling = 0;             // rolling resistance coefficient mu_r (0: none)
};

// What the kernel needs of one pair, gathered from the ball arrays.
struct ContactInput {
  double dx, dy, dz;              // x_j - x_i (periodic image included)
  double ri, rj;
  double vx, vy, vz;              // v_j - v_i
  double sx, sy, sz;              // R_i w_i + R_j w_j (kRotation only)
  double mstar;                   // pair_mstar (restitution only)
  double fsx, fsy, fsz;           // shear force on j from the last step (history)
  double wx = 0, wy = 0, wz = 0;  // w_j - w_i (rolling only)
  double mrx = 0, mry = 0, mrz = 0;   // rolling moment on j from the last step (history)
};

struct ContactResult {
  double nx = 0, ny = 0, nz = 0;  // unit normal i -> j
  double overlap = 0, fn = 0;     // U, normal force (spring + dashpot)
  double fx = 0, fy = 0, fz = 0;  // total force on j
  double tx = 0, ty = 0, tz = 0;  // n x (total shear force): moment on ball b is -R_b t
  double kn = 0, ks = 0, cn = 0;  // stiffness and restitution dashpot now (time step)
  double fsx = 0, fsy = 0, fsz = 0;   // shear spring force, the new history
  double mrx = 0, mry = 0, mrz = 0;   // rolling moment on j (on i: minus this), the new history
  double work_friction = 0, work_damping = 0, work_rolling = 0, strain = 0;
  std::uint8_t state = 0;         // 0 apart, 1 touching, 2 sliding
};

// A batch of pairs as structure of arrays: the kernel below is one loop over it without branches
// (every condition a select), which the compiler turns into SIMD code. Each lane does exactly the
// arithmetic of one pair, in the same order whatever the batch, so a pair's force does not depend
// on which batch, backend or thread computed it.
inline constexpr std::size_t kBatch = 32;

struct ContactBatch {
  // Inputs (as ContactInput).
  alignas(64) double dx[kBatch], dy[kBatch], dz[kBatch], ri[kBatch], rj[kBatch];
  alignas(64) double vx[kBatch], vy[kBatch], vz[kBatch], sx[kBatch], sy[kBatch], sz[kBatch];
  alignas(64) double mstar[kBatch];
  alignas(64) double wx[kBatch], wy[kBatch], wz[kBatch];      // F.rolling only: w_j - w_i
  alignas(64) double ivx[kBatch], ivy[kBatch], ivz[kBatch];   // periodic: velocity of j's image offset
  // The pair law per lane (only when the scene has several materials).
  alignas(64) double kn_law[kBatch], ks_law[kBatch], friction[kBatch], cohesion[kBatch];
  alignas(64) double hertz_n[kBatch], hertz_s[kBatch], rest_xi[kBatch], rolling[kBatch];
  // Results (as ContactResult; state 0, 1, 2 as a double).
  alignas(64) double nx[kBatch], ny[kBatch], nz[kBatch], overlap[kBatch], fn[kBatch];
  alignas(64) double fx[kBatch], fy[kBatch], fz[kBatch], tx[kBatch], ty[kBatch], tz[kBatch];
  alignas(64) double kn[kBatch], ks[kBatch], cn[kBatch];
  alignas(64) double work_friction[kBatch], work_damping[kBatch], strain[kBatch], state[kBatch];
  alignas(64) double work_rolling[kBatch];   // F.rolling only
  // F.dashpot only: the dashpots' part of the force on j and of t (the law of motion books their
  // work per ball: cycle/kernel_motion.hpp, DashpotForce).
  alignas(64) double dfx[kBatch], dfy[kBatch], dfz[kBatch], dtx[kBatch], dty[kBatch], dtz[kBatch];
  alignas(64) double fn_spring[kBatch];   // F.dashpot only: the normal spring's force (the rolling cap's)

  void set_law(std::size_t q, const PairLaw& law) {
    kn_law[q] = law.kn; ks_law[q] = law.ks; friction[q] = law.friction; cohesion[q] = law.cohesion;
    hertz_n[q] = law.hertz_n; hertz_s[q] = law.hertz_s; rest_xi[q] = law.rest_xi; rolling[q] = law.rolling;
  }
};

// The rolling springs' history of a batch's lanes (F.rolling): the moment on j from the last step,
// and where the new one goes, per component.
struct RollingLanes {
  const double* in[3];
  double* out[3];
};

// The lanes of a batch (contact_forces below): [0, count), or lane `lane` alone (kOne), by every
// part of the law but the rolling spring (rolling_lanes). kCap false makes each shear spring as if
// it held (CoulombSpring::force): a lane whose spring would slide is then marked state 2 and is to
// be made again with kCap. (Out of line: inlined into contact_forces twice, g++ 12 lost the
// restrict of the history pointers and no longer vectorised the loop.) kRest: with one law and
// dashpots, whether it has a restitution dashpot, tested here once (dashpot.hpp, kRestPerLane).
template <ContactFeatures F, bool kOneLaw, bool kCap, bool kOne, int kRest = kRestPerLane>
[[gnu::noinline]] void contact_lanes(ContactBatch& B, std::size_t lane, std::size_t count, const PairLaw& law, double dt,
                                     double dt_work, double beta, const double* __restrict hx_in, const double* __restrict hy_in,
                                     const double* __restrict hz_in, double* __restrict hx_out,
                                     double* __restrict hy_out, double* __restrict hz_out) {
  static_assert(!F.rolling, "the rolling springs are rolling_lanes' pass");
  if constexpr (F.dashpot && kOneLaw && kRest == kRestPerLane) {
    if (law.rest_xi > 0)
      return contact_lanes<F, kOneLaw, kCap, kOne, kRestOn>(B, lane, count, law, dt, dt_work, beta, hx_in, hy_in, hz_in, hx_out,
                                                            hy_out, hz_out);
    return contact_lanes<F, kOneLaw, kCap, kOne, kRestOff>(B, lane, count, law, dt, dt_work, beta, hx_in, hy_in, hz_in, hx_out,
                                                           hy_out, hz_out);
  }
  using Model = ContactModel<F.law()>;
  using Normal = typename Model::Normal;
  using Tangential = typename Model::Tangential;
  using Damping = typename Model::Damping;
  const std::size_t first = kOne ? lane : 0, last = kOne ? lane + 1 : count;
  for (std::size_t q = first; q < last; ++q) {
    const LaneLaw L = kOneLaw ? LaneLaw{law.kn, law.ks, law.friction, law.cohesion, law.hertz_n, law.hertz_s, law.rest_xi,
                                        law.rolling}
                              : LaneLaw{B.kn_law[q], B.ks_law[q], B.friction[q], B.cohesion[q], B.hertz_n[q],
                                        B.hertz_s[q], B.rest_xi[q], 0.0};
    const double dx = B.dx[q], dy = B.dy[q], dz = B.dz[q], ri = B.ri[q], rj = B.rj[q];
    const double d2 = dx * dx + dy * dy + dz * dz;
    const double rsum = ri + rj;
    const bool touching = d2 < rsum * rsum;   // U <= 0: no force, and the history is forgotten
    const double d = std::sqrt(d2);
    const double u = rsum - d;
    // Coincident centres (a ball launched onto another) have no direction: push along +z rather
    // than make NaN, and let the energy guard judge the outcome.
    const double inv_d = d > 0 ? 1.0 / (d > 0 ? d : 1.0) : 0.0;
    const double nx = dx * inv_d, ny = dy * inv_d, nz = d > 0 ? dz * inv_d : 1.0;

    // Relative velocity of j's contact point against i's: V = v_j - v_i - (R_i w_i + R_j w_j) x n.
    double vx = B.vx[q], vy = B.vy[q], vz = B.vz[q];
    if constexpr (Model::kRotation) {
      const double sx = B.sx[q], sy = B.sy[q], sz = B.sz[q];
      vx -= sy * nz - sz * ny;
      vy -= sz * nx - sx * nz;
      vz -= sx * ny - sy * nx;
    }
    const double vn = vx * nx + vy * ny + vz * nz;

    const Springs k = Normal::springs(L, ri, rj, rsum, u, touching);
    double work_damping = 0, cn = 0, fn_dash = 0;
    const double fn = Damping::template normal<Normal, kRest>(k.fn, k.kn, F.dashpot ? B.mstar[q] : 0.0, L.rest_xi, beta, vn,
                                                              dt_work, cn, work_damping, fn_dash);

    double sx = 0, sy = 0, sz = 0, work_friction = 0, strain_shear = 0, state = 1;
    double fsx = 0, fsy = 0, fsz = 0;
    if constexpr (Tangential::kOn) {
      ShearState s;
      Tangential::template force<kCap>(hx_in[q], hy_in[q], hz_in[q], nx, ny, nz, vx, vy, vz, vn, k.ks, dt,
                                       L.friction * k.fn + L.cohesion, s);
      fsx = s.fsx; fsy = s.fsy; fsz = s.fsz;
      work_friction = s.work_friction;
      strain_shear = s.strain;
      state = s.slide ? 2 : 1;
      sx = fsx; sy = fsy; sz = fsz;
      Damping::shear(beta, k.ks, s.vsx, s.vsy, s.vsz, sx, sy, sz, work_damping, dt_work);
    }

    const double strain = normal_spring_energy<Normal>(k.fn, u) + strain_shear;
    B.nx[q] = touching ? nx : 0.0; B.ny[q] = touching ? ny : 0.0; B.nz[q] = touching ? nz : 0.0;
    B.overlap[q] = touching ? u : 0.0;
    B.fn[q] = touching ? fn : 0.0;
    B.fx[q] = touching ? fn * nx + sx : 0.0;
    B.fy[q] = touching ? fn * ny + sy : 0.0;
    B.fz[q] = touching ? fn * nz + sz : 0.0;
    B.tx[q] = touching ? ny * sz - nz * sy : 0.0;
    B.ty[q] = touching ? nz * sx - nx * sz : 0.0;
    B.tz[q] = touching ? nx * sy - ny * sx : 0.0;
    B.kn[q] = touching ? k.kn : 0.0; B.ks[q] = touching ? k.ks : 0.0; B.cn[q] = touching ? cn : 0.0;
    if constexpr (Tangential::kOn) {
      hx_out[q] = touching ? fsx : 0.0; hy_out[q] = touching ? fsy : 0.0; hz_out[q] = touching ? fsz : 0.0;
    }
    B.work_friction[q] = touching ? work_friction : 0.0;
    B.work_damping[q] = touching ? work_damping : 0.0;
    B.strain[q] = touching ? strain : 0.0;
    B.state[q] = touching ? state : 0.0;
    if constexpr (F.dashpot) {   // the dashpots' part: normal, and the shear force's beyond the spring's
      B.fn_spring[q] = k.fn;
      const double dsx = sx - fsx, dsy = sy - fsy, dsz = sz - fsz;
      B.dfx[q] = touching ? fn_dash * nx + dsx : 0.0;
      B.dfy[q] = touching ? fn_dash * ny + dsy : 0.0;
      B.dfz[q] = touching ? fn_dash * nz + dsz : 0.0;
      B.dtx[q] = touching ? ny * dsz - nz * dsy : 0.0;
      B.dty[q] = touching ? nz * dsx - nx * dsz : 0.0;
      B.dtz[q] = touching ? nx * dsy - ny * dsx : 0.0;
    }
  }
}

// The rolling springs of lanes [0, count) (PROP rr_fric, doc/physics.md "Rolling resistance"),
// once contact_lanes has made the rest of the law: the shear spring's arithmetic on the relative
// rotation, a moment on j of stiffness k_r = k_s Rbar^2 against the rolling (bending) part of
// w_j - w_i, capped at mu_r Rbar F_n, Rbar = R_i R_j / (R_i + R_j). A pass of its own, reading what
// contact_lanes left in the batch (the normal, k_s, the normal spring's force, the state), so that
// a law with rolling runs the loop of the same law without it: the kernel tables make one
// contact_lanes for each law without rolling, and this loop once for each kOneLaw and kDashpot,
// rather than the law's whole loop again for every rolling law. A touching lane does the arithmetic
// it would inside the law's loop (its normal, k_s and F_n are the same numbers; the strain adds the
// rolling spring's energy to the normal's and the shear's in the same order); an apart one gets
// zeros, as there.
template <bool kOneLaw, bool kDashpot>
[[gnu::noinline]] void rolling_lanes(ContactBatch& B, std::size_t count, const PairLaw& law, double dt,
                                     const double* __restrict rx_in, const double* __restrict ry_in,
                                     const double* __restrict rz_in, double* __restrict rx_out, double* __restrict ry_out,
                                     double* __restrict rz_out) {
  for (std::size_t q = 0; q < count; ++q) {
    const bool touching = B.state[q] != 0;   // (0 apart, 1 touching, 2 sliding)
    const double ri = B.ri[q], rj = B.rj[q];
    const double rbar = ri * rj / (ri + rj);
    const double nx = B.nx[q], ny = B.ny[q], nz = B.nz[q];
    const double wx = B.wx[q], wy = B.wy[q], wz = B.wz[q];
    const double wn = wx * nx + wy * ny + wz * nz;
    const double mu = kOneLaw ? law.rolling : B.rolling[q];
    const double fn_spring = kDashpot ? B.fn_spring[q] : B.fn[q];   // (without a dashpot fn is the spring's)
    ShearState r;
    CoulombSpring::force<true>(rx_in[q], ry_in[q], rz_in[q], nx, ny, nz, wx, wy, wz, wn, B.ks[q] * rbar * rbar, dt,
                               mu * rbar * fn_spring, r);
    rx_out[q] = touching ? r.fsx : 0.0;
    ry_out[q] = touching ? r.fsy : 0.0;
    rz_out[q] = touching ? r.fsz : 0.0;
    B.work_rolling[q] = touching ? r.work_friction : 0.0;
    B.strain[q] = touching ? B.strain[q] + r.strain : 0.0;
  }
}

// Whether lane q slides (state 2, kept as a double in the batch).
inline bool lane_slides(const ContactBatch& B, std::size_t q) { return B.state[q] > 1.5; }
// How many of lanes [0, count) slide. (Counted after the lanes' loop: a reduction inside it kept
// g++ 12 from vectorising the loop where the law has a dashpot.)
inline std::size_t sliding_lanes(const ContactBatch& B, std::size_t count) {
  std::size_t n = 0;
  for (std::size_t q = 0; q < count; ++q) n += lane_slides(B, q) ? 1 : 0;
  return n;
}

// The forces of lanes [0, count) of a batch, by the law the features compose (contact/models.hpp).
// one_law: every pair has `law` (a scene of one material, or all pairs of one pair of types); else
// each lane's law is in the batch. beta: Rayleigh stiffness-proportional coefficient (0 without).
// dt: the step the relative velocity moved the pair by (the shear spring's increment); dt_work: the
// step the dashpots' work is charged over (StepKernels::dt_mean). (F.shear) h*_in: the lanes' shear force history; h*_out: where the new history goes.
// clean_run (a loop's, over its batches; null: every batch with the cap): how many batches in a
// row had no sliding lane. After kCleanRun of them a batch is first made as if every spring held,
// which skips the cap's square root and two divisions a lane; a lane that would slide is then made
// again with the cap on its own where it is the only one, else the whole batch is. A dense packing
// at rest has no sliding contact, so each batch is made once without the cap; in a settled heap
// most contacts slide and each batch is made once with it. Either way each lane gets the bits of
// the law with the cap: the arithmetic of a lane does not depend on its neighbours, nor on whether
// the loop ran as vectors.
inline constexpr int kCleanRun = 2;
template <ContactFeatures F, bool kOneLaw>
inline void contact_forces(ContactBatch& B, std::size_t count, const PairLaw& law, double dt, double dt_work, double beta,
                           const double* __restrict hx_in, const double* __restrict hy_in,
                           const double* __restrict hz_in, double* __restrict hx_out, double* __restrict hy_out,
                           double* __restrict hz_out, int* clean_run = nullptr, const RollingLanes* roll = nullptr) {
  auto lanes = [&]<bool kCap, bool kOne>(std::size_t lane) {
    contact_lanes<F.without_rolling(), kOneLaw, kCap, kOne>(B, lane, count, law, dt, dt_work, beta, hx_in, hy_in, hz_in,
                                                            hx_out, hy_out, hz_out);
  };
  // Every part but the rolling spring, then (F.rolling) the rolling spring's pass over the lanes.
  // (Its history as plain restrict arguments, as the shear spring's: read through a struct, g++ 12
  // could not tell them from the batch and did not vectorise the loop.)
  auto rolling = [&] {
    if constexpr (F.rolling)
      rolling_lanes<kOneLaw, F.dashpot>(B, count, law, dt, roll->in[0], roll->in[1], roll->in[2], roll->out[0], roll->out[1],
                                        roll->out[2]);
  };
  if constexpr (ContactModel<F.law()>::Tangential::kOn) {
    if (clean_run && *clean_run >= kCleanRun) {
      lanes.template operator()<false, false>(0);
      const std::size_t sliding = sliding_lanes(B, count);
      if (sliding == 0) return rolling();
      if (sliding == 1) {
        std::size_t q = 0;
        while (!lane_slides(B, q)) ++q;
        lanes.template operator()<true, true>(q);
        return rolling();
      }
    }
    lanes.template operator()<true, false>(0);
    if (clean_run) *clean_run = sliding_lanes(B, count) == 0 ? *clean_run + 1 : 0;
  } else {
    lanes.template operator()<true, false>(0);
  }
  rolling();
}

// The force at one contact: the batch kernel on one lane (for the time-step estimate and tests).
template <ContactFeatures F>
inline ContactResult contact_force(const PairLaw& law, const ContactInput& in, double dt, double beta) {
  ContactBatch B;
  B.dx[0] = in.dx; B.dy[0] = in.dy; B.dz[0] = in.dz; B.ri[0] = in.ri; B.rj[0] = in.rj;
  B.vx[0] = in.vx; B.vy[0] = in.vy; B.vz[0] = in.vz; B.sx[0] = in.sx; B.sy[0] = in.sy; B.sz[0] = in.sz;
  B.mstar[0] = in.mstar;
  B.wx[0] = in.wx; B.wy[0] = in.wy; B.wz[0] = in.wz;
  double hx = 0, hy = 0, hz = 0;
  ContactResult r;
  const RollingLanes roll{{&in.mrx, &in.mry, &in.mrz}, {&r.mrx, &r.mry, &r.mrz}};
  contact_forces<F, true>(B, 1, law, dt, dt, beta, &in.fsx, &in.fsy, &in.fsz, &hx, &hy, &hz, nullptr, &roll);
  r.nx = B.nx[0]; r.ny = B.ny[0]; r.nz = B.nz[0]; r.overlap = B.overlap[0]; r.fn = B.fn[0];
  r.fx = B.fx[0]; r.fy = B.fy[0]; r.fz = B.fz[0]; r.tx = B.tx[0]; r.ty = B.ty[0]; r.tz = B.tz[0];
  r.kn = B.kn[0]; r.ks = B.ks[0]; r.cn = B.cn[0];
  if constexpr (F.shear) { r.fsx = hx; r.fsy = hy; r.fsz = hz; }
  r.work_friction = B.work_friction[0]; r.work_damping = B.work_damping[0]; r.strain = B.strain[0];
  if constexpr (F.rolling) r.work_rolling = B.work_rolling[0];
  r.state = static_cast<std::uint8_t>(B.state[0]);
  return r;
}

}  // namespace trubal
