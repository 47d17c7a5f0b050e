// Normal part, Hertz with Mindlin's no-slip tangential stiffness (doc/physics.md "Contacts"):
// F_n = 4/3 E* sqrt(R*) U^1.5, tangent k_n = dF_n/dU, k_s = 8 G* sqrt(R* U).
#pragma once

#include <cmath>

#include "physics/contact/lane_law.hpp"

namespace trubal {

struct HertzNormal {
  static constexpr double kEnergy = 0.4;
  // Tsuji-type dashpot (as LIGGGHTS and Antypov & Elliott 2011): c = 2 sqrt(5/6) xi sqrt(k m*).
  static constexpr double kDashpotFactor = 1.8257418583505538;
  // The spring force of a contact of tangent stiffness kn at overlap U (for measurements).
  static double spring_force(double kn, double u) { return 2.0 / 3.0 * kn * u; }
  [[gnu::always_inline]] static Springs springs(const LaneLaw& law, double ri, double rj, double rsum, double u, bool touching) {
    const double root = std::sqrt(touching ? ri * rj / rsum * u : 0.0);   // sqrt(R* U)
    return {1.5 * law.hertz_n * root, law.hertz_s * root, law.hertz_n * root * u};
  }
};

}  // namespace trubal
