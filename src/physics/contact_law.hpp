// The force at one contact (PHYSICS.md "Contacts" and "Damping"). Every backend calls this one
// function, so the arithmetic, and therefore the answer, is the same whichever pairs a backend
// visits and however it spreads them over threads.
#pragma once

#include <cmath>
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

// Properties of a pair of ball types, already mixed (PHYSICS.md: springs in series, mu = min).
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

// beta: Rayleigh stiffness-proportional coefficient (0 without). dt: this step.
template <unsigned F>
inline ContactResult contact_force(const PairLaw& law, const ContactInput& in, double dt, double beta) {
  using namespace contact_bits;
  ContactResult r;
  const double d2 = in.dx * in.dx + in.dy * in.dy + in.dz * in.dz;
  const double rsum = in.ri + in.rj;
  if (!(d2 < rsum * rsum)) return r;   // U <= 0: no force, and the history is forgotten
  const double d = std::sqrt(d2);
  const double u = rsum - d;
  // Coincident centres (a ball launched onto another) have no direction: push along +z rather than
  // make NaN, and let the energy guard judge the outcome.
  const double inv_d = d > 0 ? 1.0 / d : 0.0;
  const double nx = in.dx * inv_d, ny = in.dy * inv_d, nz = d > 0 ? in.dz * inv_d : 1.0;

  // Relative velocity of j's contact point against i's: V = v_j - v_i - (R_i w_i + R_j w_j) x n.
  double vx = in.vx, vy = in.vy, vz = in.vz;
  if constexpr ((F & kRotation) != 0) {
    vx -= in.sy * nz - in.sz * ny;
    vy -= in.sz * nx - in.sx * nz;
    vz -= in.sx * ny - in.sy * nx;
  }
  const double vn = vx * nx + vy * ny + vz * nz;

  double kn, ks, fn_spring;
  if constexpr ((F & kHertz) != 0) {
    const double root = std::sqrt(in.ri * in.rj / rsum * u);   // sqrt(R* U)
    fn_spring = law.hertz_n * root * u;
    kn = 1.5 * law.hertz_n * root;                              // dF_n/dU
    ks = law.hertz_s * root;
  } else {
    kn = law.kn;
    ks = law.ks;
    fn_spring = kn * u;
  }

  double fn = fn_spring;
  double work_damping = 0;
  double cn = 0;
  if constexpr ((F & kDashpot) != 0) {
    if (law.rest_xi > 0) {
      const double factor = (F & kHertz) != 0 ? kHertzDashpotFactor : 2.0;
      cn = factor * law.rest_xi * std::sqrt(kn * in.mstar);
    }
    double f_dash = (beta * kn + cn) * -vn;                     // dU/dt = -V.n
    if (cn > 0 && fn_spring + f_dash < 0) f_dash = -fn_spring;  // a restitution dashpot never pulls
    fn = fn_spring + f_dash;
    work_damping = f_dash * -vn * dt;
  }

  double fsx = 0, fsy = 0, fsz = 0, sx = 0, sy = 0, sz = 0;
  double work_friction = 0, strain_shear = 0;
  std::uint8_t state = 1;
  if constexpr ((F & kShear) != 0) {
    // Last step's shear force, turned onto the new contact plane at its old length.
    fsx = in.fsx; fsy = in.fsy; fsz = in.fsz;
    const double old2 = fsx * fsx + fsy * fsy + fsz * fsz;
    if (old2 > 0) {
      const double fs_n = fsx * nx + fsy * ny + fsz * nz;
      fsx -= fs_n * nx; fsy -= fs_n * ny; fsz -= fs_n * nz;
      const double new2 = fsx * fsx + fsy * fsy + fsz * fsz;
      if (new2 > 0) {
        const double scale = std::sqrt(old2 / new2);
        fsx *= scale; fsy *= scale; fsz *= scale;
      }
    }
    const double vsx = vx - vn * nx, vsy = vy - vn * ny, vsz = vz - vn * nz;
    const double kdt = ks * dt;
    fsx -= kdt * vsx; fsy -= kdt * vsy; fsz -= kdt * vsz;
    // Coulomb limit on the spring force (the dashpots act beside it).
    const double limit = law.friction * fn_spring + law.cohesion;
    const double fs2 = fsx * fsx + fsy * fsy + fsz * fsz;
    if (fs2 > limit * limit) {
      const double fs = std::sqrt(fs2);
      const double scale = limit / fs;
      fsx *= scale; fsy *= scale; fsz *= scale;
      if (ks > 0) work_friction = limit * (fs - limit) / ks;   // force times plastic slip
      state = 2;
    }
    if (ks > 0) strain_shear = (fsx * fsx + fsy * fsy + fsz * fsz) / (2 * ks);
    sx = fsx; sy = fsy; sz = fsz;
    if constexpr ((F & kDashpot) != 0) {
      const double c = beta * ks;
      sx -= c * vsx; sy -= c * vsy; sz -= c * vsz;
      work_damping += c * (vsx * vsx + vsy * vsy + vsz * vsz) * dt;
    }
  }

  r.nx = nx; r.ny = ny; r.nz = nz;
  r.overlap = u;
  r.fn = fn;
  r.fx = fn * nx + sx; r.fy = fn * ny + sy; r.fz = fn * nz + sz;
  r.tx = ny * sz - nz * sy; r.ty = nz * sx - nx * sz; r.tz = nx * sy - ny * sx;
  r.kn = kn; r.ks = ks; r.cn = cn;
  r.fsx = fsx; r.fsy = fsy; r.fsz = fsz;
  r.work_friction = work_friction;
  r.work_damping = work_damping;
  // Spring energy: linear 1/2 F_n U, Hertz 2/5 F_n U; shear |F_s|^2 / (2 k_s).
  r.strain = ((F & kHertz) != 0 ? 0.4 : 0.5) * fn_spring * u + strain_shear;
  r.state = state;
  return r;
}

}  // namespace trubal
