// The table of contact laws: which parts a set of features composes. A new law is a part's file
// and an entry here (the loops instantiate every entry, physics/contact_law.hpp composes it).
// Every part's functions are always inlined: they run inside the batch loop the compiler turns
// into SIMD code, and g++ 12 gave wrong forces (an unstable run) for the vectorised loop with the
// shear spring's function left out of line, while the same code inlined (or not vectorised) gives
// the bits of the law written in one piece (tests/reference/*.ref).
#pragma once

#include <type_traits>

#include "physics/contact/dashpot.hpp"
#include "physics/contact/dashpot_off.hpp"
#include "physics/contact/features.hpp"
#include "physics/contact/normal_hertz.hpp"
#include "physics/contact/normal_linear.hpp"
#include "physics/contact/tangential_off.hpp"
#include "physics/contact/tangential_spring.hpp"

namespace trubal {

template <ContactFeatures F>
struct ContactModel {
  using Normal = std::conditional_t<F.hertz, HertzNormal, LinearNormal>;
  using Tangential = std::conditional_t<F.shear, CoulombSpring, TangentialOff>;
  using Damping = std::conditional_t<F.dashpot, ContactDashpot, NoDashpot>;
  static constexpr bool kRotation = F.rotation;
};

}  // namespace trubal
