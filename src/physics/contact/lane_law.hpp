// The pair law one lane of a contact batch uses (physics/pair_laws.hpp mixes them), as values the
// parts of the contact law read.
#pragma once

namespace trubal {

struct LaneLaw {
  double kn, ks;             // linear springs
  double friction, cohesion;
  double hertz_n, hertz_s;   // Hertz: F_n = hertz_n sqrt(R*) U^1.5; Mindlin: k_s = hertz_s sqrt(R* U)
  double rest_xi;            // restitution dashpot damping ratio (0: none)
  double rolling;            // rolling resistance coefficient mu_r (0: none)
};

// The springs of a touching pair now: normal and tangential stiffness, the normal spring force.
struct Springs {
  double kn, ks, fn;
};

}  // namespace trubal
