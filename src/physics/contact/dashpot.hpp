// Damping part, contact dashpots (doc/physics.md "Damping"): Rayleigh's stiffness-proportional one,
// beta k on the normal and tangential relative velocity, and the restitution dashpot,
// c = factor xi sqrt(k_n m*) on the normal one, which never pulls (Schwager & Poeschel 2007).
#pragma once

#include <cmath>

namespace trubal {

// Whether a lane's law has a restitution dashpot: tested on each lane (rest_xi > 0), or known for
// the whole loop (every pair of one law: contact_lanes tests it once). Known, the loop holds no
// test of a value that is the same on every lane, which g++ 12 turned into a select it does not
// vectorise with AVX2. The same numbers each way: without, c is 0 and nothing is clamped.
inline constexpr int kRestPerLane = 0, kRestOn = 1, kRestOff = 2;

struct ContactDashpot {
  // F_n = F_spring + (beta k_n + c) (-V.n), clamped at 0 where c > 0; sets c, the dashpot's part of
  // F_n and its work over dt at V (the relative velocity the force was made from).
  template <class Normal, int kRest = kRestPerLane>
  [[gnu::always_inline]] static double normal(double fn_spring, double kn, double mstar, double rest_xi, double beta, double vn,
                       double dt, double& cn, double& work, double& dashpot) {
    const double km = kn * mstar;
    if constexpr (kRest == kRestOff) cn = 0.0;
    else if constexpr (kRest == kRestOn) cn = Normal::kDashpotFactor * rest_xi * std::sqrt(km > 0 ? km : 0.0);
    else cn = rest_xi > 0 ? Normal::kDashpotFactor * rest_xi * std::sqrt(km > 0 ? km : 0.0) : 0.0;
    double f_dash = (beta * kn + cn) * -vn;                              // dU/dt = -V.n
    f_dash = cn > 0 && fn_spring + f_dash < 0 ? -fn_spring : f_dash;   // a restitution dashpot never pulls
    work = f_dash * -vn * dt;
    dashpot = f_dash;
    return fn_spring + f_dash;
  }
  // The tangential dashpot beta k_s on the sliding velocity vs, beside the Coulomb spring.
  [[gnu::always_inline]] static void shear(double beta, double ks, double vsx, double vsy, double vsz, double& sx, double& sy, double& sz,
                    double& work, double dt) {
    const double c = beta * ks;
    sx -= c * vsx; sy -= c * vsy; sz -= c * vsz;
    work += c * (vsx * vsx + vsy * vsy + vsz * vsz) * dt;
  }
};

}  // namespace trubal
