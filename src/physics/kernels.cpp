// The per-contact loop and the per-ball gather + law of motion (PHYSICS.md "Law of motion"),
// instantiated for every combination of features and picked once per CYCLE by make_kernels.
#include "physics/kernels.hpp"

#include "backends/periodic.hpp"

#include <utility>

namespace trubal {
namespace {

// Raw pointers, so that the compiler knows the stores into one array cannot move another's data.
#define TRUBAL_PTR(name, vec) auto* __restrict name = (vec).data()

// Results are staged per chunk of contacts and then copied one array at a time: writing the ~20
// result arrays element by element thrashes the cache when their starts share a page offset, as
// large std::vector allocations do (measured 8x slower at 76,000 contacts).
inline constexpr std::size_t kChunk = 64;
enum Field { kNx, kNy, kNz, kOverlap, kFn, kFx, kFy, kFz, kTx, kTy, kTz, kKn, kKs, kCn, kFsx, kFsy, kFsz,
             kWorkFriction, kWorkDamping, kFieldCount };

template <unsigned F>
void contact_loop(Model& model, const StepKernels& k, std::size_t begin, std::size_t end, StepSums& sums) {
  using namespace contact_bits;
  const Balls& b = model.balls;
  ContactTable& c = model.contacts;
  TRUBAL_PTR(pi, c.i); TRUBAL_PTR(pj, c.j);
  TRUBAL_PTR(x, b.x); TRUBAL_PTR(y, b.y); TRUBAL_PTR(z, b.z); TRUBAL_PTR(rad, b.rad); TRUBAL_PTR(mass, b.mass);
  TRUBAL_PTR(vx, b.vx); TRUBAL_PTR(vy, b.vy); TRUBAL_PTR(vz, b.vz);
  TRUBAL_PTR(wx, b.wx); TRUBAL_PTR(wy, b.wy); TRUBAL_PTR(wz, b.wz);
  TRUBAL_PTR(fsx, c.fsx); TRUBAL_PTR(fsy, c.fsy); TRUBAL_PTR(fsz, c.fsz);
  // Periodic space: j's image is x_j + H image, moving at v_j + (dH/dt) image (backends/periodic.hpp).
  const bool periodic = model.space.periodic;
  const CellFrame cell = cell_frame(model.space);
  const std::int8_t* const img_x = c.image_x.data();
  const std::int8_t* const img_y = c.image_y.data();
  const std::int8_t* const img_z = c.image_z.data();
  double* const out[kFieldCount] = {c.nx.data(), c.ny.data(), c.nz.data(), c.overlap.data(), c.fn.data(),
                                    c.fx.data(), c.fy.data(), c.fz.data(), c.tx.data(), c.ty.data(), c.tz.data(),
                                    c.kn_eff.data(), c.ks_eff.data(), c.cn_eff.data(), c.fsx.data(), c.fsy.data(),
                                    c.fsz.data(), c.work_friction.data(), c.work_damping.data()};
  const double dt = k.dt, beta = k.beta;
  double work_friction = 0, work_damping = 0, strain = 0;
  alignas(64) double stage[kFieldCount][kChunk];
  for (std::size_t p0 = begin; p0 < end; p0 += kChunk) {
    const std::size_t count = std::min(kChunk, end - p0);
    for (std::size_t q = 0; q < count; ++q) {
      const std::size_t p = p0 + q, i = pi[p], j = pj[p];
      const PairLaw& law = k.law(i, j);
      ContactInput in{};
      in.dx = x[j] - x[i]; in.dy = y[j] - y[i]; in.dz = z[j] - z[i];
      in.ri = rad[i]; in.rj = rad[j];
      in.vx = vx[j] - vx[i]; in.vy = vy[j] - vy[i]; in.vz = vz[j] - vz[i];
      if (periodic) {
        double ox, oy, oz, ux, uy, uz;
        image_offset(cell, img_x[p], img_y[p], img_z[p], ox, oy, oz);
        image_velocity(cell, img_x[p], img_y[p], img_z[p], ux, uy, uz);
        in.dx = image_delta(x[j], x[i], ox);
        in.dy = image_delta(y[j], y[i], oy);
        in.dz = image_delta(z[j], z[i], oz);
        in.vx += ux;
        in.vy += uy;
        in.vz += uz;
      }
      if constexpr ((F & kRotation) != 0) {
        in.sx = in.ri * wx[i] + in.rj * wx[j];
        in.sy = in.ri * wy[i] + in.rj * wy[j];
        in.sz = in.ri * wz[i] + in.rj * wz[j];
      }
      if constexpr ((F & kDashpot) != 0)
        if (law.rest_xi > 0) in.mstar = mass[i] * mass[j] / (mass[i] + mass[j]);
      if constexpr ((F & kShear) != 0) { in.fsx = fsx[p]; in.fsy = fsy[p]; in.fsz = fsz[p]; }
      const ContactResult r = contact_force<F>(law, in, dt, beta);
      stage[kNx][q] = r.nx; stage[kNy][q] = r.ny; stage[kNz][q] = r.nz;
      stage[kOverlap][q] = r.overlap; stage[kFn][q] = r.fn;
      stage[kFx][q] = r.fx; stage[kFy][q] = r.fy; stage[kFz][q] = r.fz;
      stage[kTx][q] = r.tx; stage[kTy][q] = r.ty; stage[kTz][q] = r.tz;
      stage[kKn][q] = r.kn; stage[kKs][q] = r.ks; stage[kCn][q] = r.cn;
      stage[kFsx][q] = r.fsx; stage[kFsy][q] = r.fsy; stage[kFsz][q] = r.fsz;
      stage[kWorkFriction][q] = r.work_friction; stage[kWorkDamping][q] = r.work_damping;
      c.state[p] = r.state;
      work_friction += r.work_friction;
      work_damping += r.work_damping;
      strain += r.strain;
    }
    for (int f = 0; f < kFieldCount; ++f) std::copy(stage[f], stage[f] + count, out[f] + p0);
  }
  sums.friction_work += work_friction;
  sums.damping_work += work_damping;
  sums.strain += strain;
}

// Motion variant index: rotation + 2 loads + 4 damping kind (0..2) + 12 estimate (0..2).
inline constexpr unsigned kMotionCount = 36;

template <unsigned M>
void motion_loop(Model& model, const StepKernels& k, std::size_t begin, std::size_t end, StepSums& sums) {
  constexpr bool kRot = (M & 1) != 0;
  constexpr bool kLoads = (M & 2) != 0;
  constexpr auto kDamp = static_cast<DampKind>((M / 4) % 3);
  constexpr auto kEstimate = static_cast<StepEstimate>(M / 12);
  Balls& b = model.balls;
  const ContactTable& c = model.contacts;
  const double dt = k.dt;
  // Mass-proportional damping, factor form: v' = (v (1 - a dt/2) + F/m dt) / (1 + a dt/2).
  const double keep = 1 - 0.5 * k.alpha * dt, shrink = 1 / (1 + 0.5 * k.alpha * dt);
  const auto [gx, gy, gz] = k.gravity;
  double boundary_work = 0, damping_work = 0, kinetic = 0, potential = 0;
  double omega2_max = 0, step_min = std::numeric_limits<double>::infinity();
  double fastest2 = -1;
  std::size_t fastest = begin;

  // One velocity component: fixed ones keep their velocity (the force is their reaction).
  // Kinetic energy at t as m v(t - dt/2) v(t + dt/2) / 2: with the spring energy and the potential at
  // t this is the quantity central differences conserve exactly for a linear spring (and free
  // fall), so the guard sees no false imbalance from a stable step however coarse it is.
  auto advance = [&](double force, double applied, double& v, double inv_m, double m, bool fixed) {
    if (fixed) {
      boundary_work -= (force - applied) * v * dt;
      kinetic += 0.5 * m * v * v;
      return;
    }
    double f = force;
    if constexpr (kDamp == DampKind::Local) {
      const double reduce = k.local * std::abs(force);
      f = v > 0 ? force - reduce : (v < 0 ? force + reduce : force);
    }
    const double v_old = v;
    const double v_new = kDamp == DampKind::Rayleigh ? (v_old * keep + f * inv_m * dt) * shrink : v_old + f * inv_m * dt;
    const double v_mid = 0.5 * (v_old + v_new);
    if constexpr (kLoads) boundary_work += applied * v_mid * dt;
    if constexpr (kDamp == DampKind::Local) damping_work += (force - f) * v_mid * dt;
    if constexpr (kDamp == DampKind::Rayleigh) damping_work += k.alpha * m * v_mid * v_mid * dt;
    kinetic += 0.5 * m * v_old * v_new;
    v = v_new;
  };

  for (std::size_t ball = begin; ball < end; ++ball) {
    double fx = 0, fy = 0, fz = 0, tx = 0, ty = 0, tz = 0;
    double sum_kmax = 0, sum_ks = 0, sum_cn = 0;
    for (std::uint32_t q = c.gather_begin[ball], e = c.gather_begin[ball + 1]; q < e; ++q) {
      const std::uint32_t p = c.gather_pair[q];
      if (c.gather_sign[q] > 0) { fx += c.fx[p]; fy += c.fy[p]; fz += c.fz[p]; }
      else { fx -= c.fx[p]; fy -= c.fy[p]; fz -= c.fz[p]; }
      if constexpr (kRot) { tx += c.tx[p]; ty += c.ty[p]; tz += c.tz[p]; }
      if constexpr (kEstimate != StepEstimate::None) {
        sum_kmax += std::max(c.kn_eff[p], c.ks_eff[p]);
        sum_ks += c.ks_eff[p];
        if constexpr (kEstimate == StepEstimate::Damped) sum_cn += c.cn_eff[p];
      }
    }
    const double m = b.mass[ball], inv_m = 1 / m;
    const std::uint8_t fixed = b.fixed[ball];
    if constexpr (kLoads) {
      fx += b.ax[ball] + m * gx; fy += b.ay[ball] + m * gy; fz += b.az[ball] + m * gz;
    }
    if constexpr (kLoads)   // at t, where the forces were computed
      potential -= m * (gx * b.x[ball] + gy * b.y[ball] + gz * b.z[ball]);
    advance(fx, kLoads ? b.ax[ball] : 0.0, b.vx[ball], inv_m, m, fixed & kXVel);
    advance(fy, kLoads ? b.ay[ball] : 0.0, b.vy[ball], inv_m, m, fixed & kYVel);
    advance(fz, kLoads ? b.az[ball] : 0.0, b.vz[ball], inv_m, m, fixed & kZVel);
    b.fx[ball] = fx; b.fy[ball] = fy; b.fz[ball] = fz;
    const double vx = b.vx[ball], vy = b.vy[ball], vz = b.vz[ball];
    b.x[ball] += vx * dt; b.y[ball] += vy * dt; b.z[ball] += vz * dt;
    double speed2 = vx * vx + vy * vy + vz * vz;
    if constexpr (kRot) {
      const double r = b.rad[ball], inertia = b.inertia[ball], inv_i = 1 / inertia;
      double mx = -r * tx, my = -r * ty, mz = -r * tz;
      if constexpr (kLoads) { mx += b.amx[ball]; my += b.amy[ball]; mz += b.amz[ball]; }
      advance(mx, kLoads ? b.amx[ball] : 0.0, b.wx[ball], inv_i, inertia, fixed & kXSpin);
      advance(my, kLoads ? b.amy[ball] : 0.0, b.wy[ball], inv_i, inertia, fixed & kYSpin);
      advance(mz, kLoads ? b.amz[ball] : 0.0, b.wz[ball], inv_i, inertia, fixed & kZSpin);
      b.mx[ball] = mx; b.my[ball] = my; b.mz[ball] = mz;
      const double wx = b.wx[ball], wy = b.wy[ball], wz = b.wz[ball];
      const double spin2 = wx * wx + wy * wy + wz * wz;
      speed2 += r * r * spin2;
    }
    if (!(speed2 <= fastest2)) { fastest2 = speed2; fastest = ball; }
    if constexpr (kEstimate != StepEstimate::None) {
      // A ball held in every component sets no step of its own.
      const bool held = (fixed & kVel) == kVel && (!kRot || (fixed & kSpin) == kSpin);
      if (!held) {
        if (sum_kmax == 0) {   // no contact: as if touching one ball of its own type
          const std::uint16_t t = k.type_count == 1 ? 0 : k.ball_type[ball];
          const double kn = k.alone_kn[t];
          sum_kmax = std::max(kn, k.alone_ks[t]);
          sum_ks = k.alone_ks[t];
          if constexpr (kEstimate == StepEstimate::Damped) sum_cn = 2 * k.alone_xi[t] * std::sqrt(kn * 0.5 * m);
        }
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
  sums.boundary_work += boundary_work;
  sums.damping_work += damping_work;
  sums.kinetic += kinetic;
  sums.potential += potential;
  sums.critical_dt = std::min(sums.critical_dt, step_min);
  if (!(fastest2 <= sums.fastest_speed2)) { sums.fastest_speed2 = fastest2; sums.fastest_ball = fastest; }
}

template <std::size_t... I>
constexpr std::array<ContactLoop, sizeof...(I)> contact_loops(std::index_sequence<I...>) {
  return {&contact_loop<I>...};
}
template <std::size_t... I>
constexpr std::array<MotionLoop, sizeof...(I)> motion_loops(std::index_sequence<I...>) {
  return {&motion_loop<I>...};
}
constexpr auto kContactLoops = contact_loops(std::make_index_sequence<contact_bits::kCount>{});
constexpr auto kMotionLoops = motion_loops(std::make_index_sequence<kMotionCount>{});

double series(double a, double b) { return a + b > 0 ? a * b / (a + b) : 0; }

// Restitution of a linear spring-dashpot whose dashpot may not pull (Schwager & Poeschel,
// Granular Matter 9:465, 2007): the contact ends when the force reaches zero, at phase
// theta = atan2(2 xi s, 2 xi^2 - 1), s = sqrt(1 - xi^2); e = exp(-xi theta / s), continued
// analytically past critical damping.
double clamped_restitution(double xi) {
  if (xi < 1) {
    const double s = std::sqrt(1 - xi * xi);
    return std::exp(-xi * std::atan2(2 * xi * s, 2 * xi * xi - 1) / s);
  }
  if (xi == 1) return std::exp(-2.0);
  const double q = std::sqrt(xi * xi - 1);
  return std::exp(-xi / q * std::atanh(2 * xi * q / (2 * xi * xi - 1)));
}

// The damping ratio that gives restitution e: for the linear law with the no-pull clamp (so that e
// is exact, as PHYSICS.md intends); for Hertz the usual -ln e / sqrt(pi^2 + ln^2 e).
double restitution_xi(double e, bool hertz) {
  if (!(e < 1)) return 0;
  const double log_e = std::log(e);
  if (hertz) return -log_e / std::sqrt(M_PI * M_PI + log_e * log_e);
  double lo = 0, hi = 1e3;   // clamped_restitution falls monotonically from 1
  for (int k = 0; k < 200 && hi - lo > 1e-15 * hi; ++k) {
    const double mid = 0.5 * (lo + hi);
    (clamped_restitution(mid) > e ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

// Mixes two materials (PHYSICS.md "mixed materials"); equal materials give their own values.
PairLaw mix(const Material& a, const Material& b) {
  PairLaw law;
  law.kn = 2 * series(a.kn, b.kn);
  law.ks = 2 * series(a.ks, b.ks);
  law.friction = std::min(a.friction, b.friction);
  law.cohesion = std::min(a.cohesion, b.cohesion);
  if (a.hertz() && b.hertz()) {
    // 1/E* = (1 - nu_a)/(2 G_a) + (1 - nu_b)/(2 G_b);  1/G* = (2 - nu_a)/G_a + (2 - nu_b)/G_b.
    law.hertz_n = 4.0 / 3.0 * series(2 * a.shear_modulus / (1 - a.poisson), 2 * b.shear_modulus / (1 - b.poisson));
    law.hertz_s = 8 * series(a.shear_modulus / (2 - a.poisson), b.shear_modulus / (2 - b.poisson));
  }
  if (a.has_restitution || b.has_restitution) {
    const double e = std::min(a.has_restitution ? a.restitution : 1.0, b.has_restitution ? b.restitution : 1.0);
    law.rest_xi = restitution_xi(e, law.hertz_n > 0);
  }
  return law;
}

}  // namespace

StepKernels make_kernels(const Model& model) {
  StepKernels k;
  k.features = scene_features(model);
  const Features& f = k.features;
  const Damping& damping = model.settings.damping;
  if (damping.kind == DampKind::Rayleigh) { k.alpha = damping.alpha; k.beta = damping.beta; }
  if (damping.kind == DampKind::Local) k.local = damping.local;
  if (f.gravity) k.gravity = model.settings.gravity;

  // Compact type indices, in type-number order.
  std::vector<int> types;
  for (const auto& [type, material] : model.materials) types.push_back(type);
  k.type_count = static_cast<int>(types.size());
  k.ball_type.resize(model.balls.size());
  for (std::size_t b = 0; b < model.balls.size(); ++b)
    k.ball_type[b] = static_cast<std::uint16_t>(std::lower_bound(types.begin(), types.end(), model.balls.type[b]) - types.begin());
  for (int ta : types)
    for (int tb : types) k.laws.push_back(mix(model.materials.at(ta), model.materials.at(tb)));
  for (int t : types) {
    const Material& m = model.materials.at(t);
    k.alone_kn.push_back(m.hertz() ? 0 : m.kn);
    k.alone_ks.push_back(m.hertz() ? 0 : m.ks);
    k.alone_xi.push_back(k.laws[k.alone_xi.size() * (types.size() + 1)].rest_xi);
  }

  if (model.settings.fixed_dt > 0) k.estimate = StepEstimate::None;
  else k.estimate = f.stiffness_damping ? StepEstimate::Damped : StepEstimate::Undamped;

  using namespace contact_bits;
  const unsigned contact = (f.rotation ? kRotation : 0) | (f.friction ? kShear : 0) | (f.hertz ? kHertz : 0) |
                           (f.stiffness_damping ? kDashpot : 0);
  k.contacts = kContactLoops[contact];
  const unsigned motion = (f.rotation ? 1 : 0) + (f.gravity || f.applied ? 2 : 0) +
                          4 * static_cast<unsigned>(f.mass_damping) + 12 * static_cast<unsigned>(k.estimate);
  k.motion = kMotionLoops[motion];
  return k;
}

}  // namespace trubal
