// The spring energy a contact stores (doc/physics.md "Energy"), one formula for the contact law and
// the measurements: normal kEnergy F_n U (linear 1/2, Hertz 2/5), shear |F_s|^2 / (2 k_s).
#pragma once

namespace trubal {

template <class Normal>
inline double normal_spring_energy(double fn_spring, double u) {
  return Normal::kEnergy * fn_spring * u;
}

inline double shear_spring_energy(double fs2, double ks) { return ks > 0 ? fs2 / (2 * (ks > 0 ? ks : 1.0)) : 0.0; }

}  // namespace trubal
