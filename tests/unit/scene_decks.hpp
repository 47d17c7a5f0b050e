// Decks that more than one test file runs.
#pragma once

namespace trubal::test {

// A loose periodic assembly compressed by the servo, then loaded under the mixed servo (xx, yy held)
// with an axial strain rate and a shear rate: servo, strain, shear strain (Lees-Edwards images),
// local damping. The cycling under test follows (cycle_cuts.cpp, distributed_runs.cpp).
inline constexpr const char* kServoShearDeck = R"(start 0.01 0.01 0.01
prop kn 1e5 ks 1e5 fric 26.57 dens 2650
gen 300 0.0004 0.0006 seed 7
damp local 0.7
servo 1e5 1e5 1e5
cycle 3000
servo xx 1e5 yy 1e5
strain zz 2 xy 1
)";

}  // namespace trubal::test
