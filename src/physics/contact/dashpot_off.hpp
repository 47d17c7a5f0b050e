// Damping part, off: no contact dashpot (mass and local damping act in the law of motion).
#pragma once

#include "physics/contact/dashpot.hpp"   // (kRestPerLane)

namespace trubal {

struct NoDashpot {
  // Normal force with the dashpot, its coefficient (time step), the work it dissipates and its part.
  template <class Normal, int kRest = kRestPerLane>
  [[gnu::always_inline]] static double normal(double fn_spring, double, double, double, double, double, double, double&, double&,
                                              double&) {
    return fn_spring;
  }
  [[gnu::always_inline]] static void shear(double, double, double, double, double, double&, double&, double&, double&, double) {}
};

}  // namespace trubal
