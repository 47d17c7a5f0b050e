// The force at one contact (doc/physics.md "Contacts" and "Damping"). Every backend calls this one
// function, so the arithmetic, and therefore the answer, is the same whichever pairs a backend
// visits and however it spreads them over threads.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>

namespace trubal {

// Feature bits of the contact kernel; each bit off removes work (chosen once per CYCLE).
namespace contact_bits {
inline constexpr unsigned kRotation = 1;   // spins enter the relative velocity
inline constexpr unsigned kShear = 2;      // shear springs, friction (some ks > 0)
inline constexpr unsigned kHertz = 4;      // Hertz-Mindlin instead of linear springs
inline constexpr unsigned kDashpot = 8;    // Rayleigh stiffness dashpots or restitution dashpots
inline constexpr unsigned kCount = 16;
}  // namespace contact_bits

// Properties of a pair of ball types, already mixed (doc/physics.md: springs in series, mu = min).
struct PairLaw {
  double kn = 0, ks = 0;          // linear springs
  double friction = 0, cohesion = 0;
  double hertz_n = 0;             // Hertz: F_n = hertz_n sqrt(R*) U^1.5, hertz_n = 4/3 E*
  double hertz_s = 0;             // Mindlin: k_s = hertz_s sqrt(R* U), hertz_s = 8 G*
  double rest_xi = 0;             // restitution dashpot damping ratio (0: none)
};

// Linear law: c = 2 xi sqrt(k m*), exact restitution for a head-on impact. Hertz (Tsuji-type, as
// LIGGGHTS and Antypov & Elliott 2011): c = 2 sqrt(5/6) xi sqrt(k_tangent m*).
inline constexpr double kHertzDashpotFactor = 1.8257418583505538;   // 2 sqrt(5/6)

// What the kernel needs of one pair, gathered from the ball arrays.
struct ContactInput {
  double dx, dy, dz;              // x_j - x_i (periodic image included)
  double ri, rj;
  double vx, vy, vz;              // v_j - v_i
  double sx, sy, sz;              // R_i w_i + R_j w_j (kRotation only)
  double mstar;                   // m_i m_j / (m_i + m_j) (restitution only)
  double fsx, fsy, fsz;           // shear force on j from the last step (history)
};

struct ContactResult {
  double nx = 0, ny = 0, nz = 0;  // unit normal i -> j
  double overlap = 0, fn = 0;     // U, normal force (spring + dashpot)
  double fx = 0, fy = 0, fz = 0;  // total force on j
  double tx = 0, ty = 0, tz = 0;  // n x (total shear force): moment on ball b is -R_b t
  double kn = 0, ks = 0, cn = 0;  // stiffness and restitution dashpot now (time step)
  double fsx = 0, fsy = 0, fsz = 0;   // shear spring force, the new history
  double work_friction = 0, work_damping = 0, strain = 0;
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
  alignas(64) double ivx[kBatch], ivy[kBatch], ivz[kBatch];   // periodic: velocity of j's image offset
  // The pair law per lane (only when the scene has several materials).
  alignas(64) double kn_law[kBatch], ks_law[kBatch], friction[kBatch], cohesion[kBatch];
  alignas(64) double hertz_n[kBatch], hertz_s[kBatch], rest_xi[kBatch];
  // Results (as ContactResult; state 0, 1, 2 as a double).
  alignas(64) double nx[kBatch], ny[kBatch], nz[kBatch], overlap[kBatch], fn[kBatch];
  alignas(64) double fx[kBatch], fy[kBatch], fz[kBatch], tx[kBatch], ty[kBatch], tz[kBatch];
  alignas(64) double kn[kBatch], ks[kBatch], cn[kBatch];
  alignas(64) double work_friction[kBatch], work_damping[kBatch], strain[kBatch], state[kBatch];

  void set_law(std::size_t q, const PairLaw& law) {
    kn_law[q] = law.kn; ks_law[q] = law.ks; friction[q] = law.friction; cohesion[q] = law.cohesion;
    hertz_n[q] = law.hertz_n; hertz_s[q] = law.hertz_s; rest_xi[q] = law.rest_xi;
  }
};

// The forces of lanes [0, count) of a batch. one_law: every pair has `law` (a scene of one
// material, or all pairs of one pair of types); else each lane's law is in the batch.
// beta: Rayleigh stiffness-proportional coefficient (0 without). dt: this step.
// (kShear) h*_in: the lanes' shear force history; h*_out: where the new history goes.
template <unsigned F, bool kOneLaw>
inline void contact_forces(ContactBatch& B, std::size_t count, const PairLaw& law, double dt, double beta,
                           const double* __restrict hx_in, const double* __restrict hy_in,
                           const double* __restrict hz_in, double* __restrict hx_out, double* __restrict hy_out,
                           double* __restrict hz_out) {
  using namespace contact_bits;
  for (std::size_t q = 0; q < count; ++q) {
    const double law_kn = kOneLaw ? law.kn : B.kn_law[q], law_ks = kOneLaw ? law.ks : B.ks_law[q];
    const double law_friction = kOneLaw ? law.friction : B.friction[q];
    const double law_cohesion = kOneLaw ? law.cohesion : B.cohesion[q];
    const double law_hertz_n = kOneLaw ? law.hertz_n : B.hertz_n[q];
    const double law_hertz_s = kOneLaw ? law.hertz_s : B.hertz_s[q];
    const double law_rest_xi = kOneLaw ? law.rest_xi : B.rest_xi[q];
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
    if constexpr ((F & kRotation) != 0) {
      const double sx = B.sx[q], sy = B.sy[q], sz = B.sz[q];
      vx -= sy * nz - sz * ny;
      vy -= sz * nx - sx * nz;
      vz -= sx * ny - sy * nx;
    }
    const double vn = vx * nx + vy * ny + vz * nz;

    double kn, ks, fn_spring;
    if constexpr ((F & kHertz) != 0) {
      const double root = std::sqrt(touching ? ri * rj / rsum * u : 0.0);   // sqrt(R* U)
      fn_spring = law_hertz_n * root * u;
      kn = 1.5 * law_hertz_n * root;                                        // dF_n/dU
      ks = law_hertz_s * root;
    } else {
      kn = law_kn;
      ks = law_ks;
      fn_spring = kn * u;
    }

    double fn = fn_spring;
    double work_damping = 0;
    double cn = 0;
    if constexpr ((F & kDashpot) != 0) {
      const double factor = (F & kHertz) != 0 ? kHertzDashpotFactor : 2.0;
      const double km = kn * B.mstar[q];
      cn = law_rest_xi > 0 ? factor * law_rest_xi * std::sqrt(km > 0 ? km : 0.0) : 0.0;
      double f_dash = (beta * kn + cn) * -vn;                         // dU/dt = -V.n
      f_dash = cn > 0 && fn_spring + f_dash < 0 ? -fn_spring : f_dash;   // a restitution dashpot never pulls
      fn = fn_spring + f_dash;
      work_damping = f_dash * -vn * dt;
    }

    double fsx = 0, fsy = 0, fsz = 0, sx = 0, sy = 0, sz = 0;
    double work_friction = 0, strain_shear = 0;
    double state = 1;
    if constexpr ((F & kShear) != 0) {
      // Last step's shear force, turned onto the new contact plane at its old length.
      const double hx = hx_in[q], hy = hy_in[q], hz = hz_in[q];
      const double old2 = hx * hx + hy * hy + hz * hz;
      const double h_n = hx * nx + hy * ny + hz * nz;
      const double px = hx - h_n * nx, py = hy - h_n * ny, pz = hz - h_n * nz;
      const double new2 = px * px + py * py + pz * pz;
      const bool turn = old2 > 0, rescale = turn && new2 > 0;
      const double scale = rescale ? std::sqrt(old2 / (rescale ? new2 : 1.0)) : 1.0;
      fsx = turn ? (rescale ? px * scale : px) : hx;
      fsy = turn ? (rescale ? py * scale : py) : hy;
      fsz = turn ? (rescale ? pz * scale : pz) : hz;
      const double vsx = vx - vn * nx, vsy = vy - vn * ny, vsz = vz - vn * nz;
      const double kdt = ks * dt;
      fsx -= kdt * vsx; fsy -= kdt * vsy; fsz -= kdt * vsz;
      // Coulomb limit on the spring force (the dashpots act beside it).
      const double limit = law_friction * fn_spring + law_cohesion;
      const double fs2 = fsx * fsx + fsy * fsy + fsz * fsz;
      const bool slide = fs2 > limit * limit;
      const double fs = std::sqrt(fs2);
      const double cut = slide ? limit / (slide ? fs : 1.0) : 1.0;
      fsx = slide ? fsx * cut : fsx; fsy = slide ? fsy * cut : fsy; fsz = slide ? fsz * cut : fsz;
      const double ks_safe = ks > 0 ? ks : 1.0;
      work_friction = slide && ks > 0 ? limit * (fs - limit) / ks_safe : 0.0;   // force times plastic slip
      state = slide ? 2 : 1;
      strain_shear = ks > 0 ? (fsx * fsx + fsy * fsy + fsz * fsz) / (2 * ks_safe) : 0.0;
      sx = fsx; sy = fsy; sz = fsz;
      if constexpr ((F & kDashpot) != 0) {
        const double c = beta * ks;
        sx -= c * vsx; sy -= c * vsy; sz -= c * vsz;
        work_damping += c * (vsx * vsx + vsy * vsy + vsz * vsz) * dt;
      }
    }

    // Spring energy: linear 1/2 F_n U, Hertz 2/5 F_n U; shear |F_s|^2 / (2 k_s).
    const double strain = ((F & kHertz) != 0 ? 0.4 : 0.5) * fn_spring * u + strain_shear;
    B.nx[q] = touching ? nx : 0.0; B.ny[q] = touching ? ny : 0.0; B.nz[q] = touching ? nz : 0.0;
    B.overlap[q] = touching ? u : 0.0;
    B.fn[q] = touching ? fn : 0.0;
    B.fx[q] = touching ? fn * nx + sx : 0.0;
    B.fy[q] = touching ? fn * ny + sy : 0.0;
    B.fz[q] = touching ? fn * nz + sz : 0.0;
    B.tx[q] = touching ? ny * sz - nz * sy : 0.0;
    B.ty[q] = touching ? nz * sx - nx * sz : 0.0;
    B.tz[q] = touching ? nx * sy - ny * sx : 0.0;
    B.kn[q] = touching ? kn : 0.0; B.ks[q] = touching ? ks : 0.0; B.cn[q] = touching ? cn : 0.0;
    if constexpr ((F & kShear) != 0) {
      hx_out[q] = touching ? fsx : 0.0; hy_out[q] = touching ? fsy : 0.0; hz_out[q] = touching ? fsz : 0.0;
    }
    B.work_friction[q] = touching ? work_friction : 0.0;
    B.work_damping[q] = touching ? work_damping : 0.0;
    B.strain[q] = touching ? strain : 0.0;
    B.state[q] = touching ? state : 0.0;
  }
}

// The force at one contact: the batch kernel on one lane (for the time-step estimate and tests).
template <unsigned F>
inline ContactResult contact_force(const PairLaw& law, const ContactInput& in, double dt, double beta) {
  ContactBatch B;
  B.dx[0] = in.dx; B.dy[0] = in.dy; B.dz[0] = in.dz; B.ri[0] = in.ri; B.rj[0] = in.rj;
  B.vx[0] = in.vx; B.vy[0] = in.vy; B.vz[0] = in.vz; B.sx[0] = in.sx; B.sy[0] = in.sy; B.sz[0] = in.sz;
  B.mstar[0] = in.mstar;
  double hx = 0, hy = 0, hz = 0;
  contact_forces<F, true>(B, 1, law, dt, beta, &in.fsx, &in.fsy, &in.fsz, &hx, &hy, &hz);
  ContactResult r;
  r.nx = B.nx[0]; r.ny = B.ny[0]; r.nz = B.nz[0]; r.overlap = B.overlap[0]; r.fn = B.fn[0];
  r.fx = B.fx[0]; r.fy = B.fy[0]; r.fz = B.fz[0]; r.tx = B.tx[0]; r.ty = B.ty[0]; r.tz = B.tz[0];
  r.kn = B.kn[0]; r.ks = B.ks[0]; r.cn = B.cn[0];
  if constexpr ((F & contact_bits::kShear) != 0) { r.fsx = hx; r.fsy = hy; r.fsz = hz; }
  r.work_friction = B.work_friction[0]; r.work_damping = B.work_damping[0]; r.strain = B.strain[0];
  r.state = static_cast<std::uint8_t>(B.state[0]);
  return r;
}

}  // namespace trubal
