// Normal part, linear (doc/physics.md "Contacts"): F_n = k_n U, with the pair's k_n and k_s.
#pragma once

#include "physics/contact/lane_law.hpp"

namespace trubal {

struct LinearNormal {
  static constexpr double kEnergy = 0.5;         // spring energy = kEnergy F_n U
  static constexpr double kDashpotFactor = 2.0;  // c = factor xi sqrt(k m*): exact restitution head-on
  // The spring force of a contact of tangent stiffness kn at overlap U (for measurements).
  static double spring_force(double kn, double u) { return kn * u; }
  [[gnu::always_inline]] static Springs springs(const LaneLaw& law, double, double, double, double u, bool) {
    return {law.kn, law.ks, law.kn * u};
  }
};

}  // namespace trubal
