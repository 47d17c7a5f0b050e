// The time step, in one place (doc/physics.md "Time step"): the critical step of a state, the
// per-ball frequency bound the motion loop also uses, the Hertz cap, and the rule that holds the
// step through contact episodes.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "model/model.hpp"
#include "physics/scene.hpp"

namespace trubal {

// Whether a ball is held in every component the step moves (its velocity, and its spin where
// the scene rotates): such a ball sets no step of its own.
inline bool ball_held(std::uint8_t fixed, bool rotation) {
  return (fixed & kVel) == kVel && (!rotation || (fixed & kSpin) == kSpin);
}

// Critical time step of the current state (before FRAC), see doc/physics.md "Time step".
double critical_timestep(const Model& model);
// Its pieces, for a model stepped in parts (BACKEND mpi: each rank's own balls, the ghosts skipped):
// whether a ball not skipped is free in what the step moves; the smallest critical step of the
// balls not skipped, without the Hertz cap, with the whole model's features and whether any of its
// balls is free. The smallest over the parts is the whole model's (a min is exact in any order).
bool any_ball_free(const Model& model, bool rotation, const std::uint8_t* skip);
double balls_critical_step(const Model& model, const Features& features, bool any_free, const std::uint8_t* skip);
// The critical step of the same balls with no contact, each as if touching one ball of its own type
// (as a ball without contacts counts), capped by `cap`: the estimate between contact episodes. A
// linear scene's own step before its first contact; a Hertz scene's, the cap (a lone Hertz ball
// sets none).
double contact_free_step(const Model& model, const Features& features, double cap);
// Its pieces, as balls_critical_step's (a distributed run's parts: each rank's own balls).
double contact_free_step(const Model& model, const Features& features, double cap, bool any_free,
                         const std::uint8_t* skip);
// The critical step the next cycle uses (its step is FRAC times this), from the one held now and
// the estimate of the state just computed (both capped by the Rayleigh step of the Hertz balls).
// Each change of the step while a collision is in progress leaves it an error (the two steps keep
// different modified energies; a step that changed at every step of a contact, as a Hertz estimate
// does with the tangent stiffness, would make impacts first order), and in a scene of many balls
// the estimate changes whenever a ball anywhere gains or loses a contact. So the held step is kept
// through contact episodes and replaced by the estimate only (1) between episodes, when the
// estimate is no shorter than `free_step` (contact_free_step: no ball stiffer than a lone ball);
// (2) when stability needs it: FRAC times the held step above max(0.9, FRAC) times the estimate;
// (3) when the estimate has grown held_growth times above the held step. The step then changes a
// bounded number of times per contact, whatever FRAC, and a collision's rebound does not depend on
// contacts elsewhere unless stability does.
double next_critical_step(double held, double estimate, double frac, double free_step, bool hertz);
// The growth of the estimate over the held step that renews it: 2 for Hertz (its estimate follows
// the tangent stiffness through every contact); in a linear scene, whose estimate moves only as
// contacts form and break, also no more than max(0.9, FRAC) / FRAC, the stability rule's band, so
// that at FRAC 0.8 the step stays between 0.71 and 0.9 of the estimate as a sample dilates (1.125;
// at FRAC 0.45 and below, 2).
double held_growth(double frac, bool hertz);
// The Rayleigh-wave time of the smallest Hertz ball: a Hertz contact has no stiffness at first
// touch, so this caps the step (infinite without Hertz balls).
double hertz_step_cap(const Model& model);

// Upper bound on the squared highest frequency of the modes that involve one ball: block
// Gershgorin row sums of M^-1 K over the ball's contacts, spins measured as c R w with inertia
// 2/5 m / c^2. Each contact couples a translation to its own and its partner's translation
// (norm max(k_n, k_s)) and spin (k_s each, times c), and a spin to its own and its partner's spin
// (k_s) and translation (k_s each, over c): translation row 2 sum max(k_n, k_s) + 2 c sum k_s, spin
// row (2 + 2 / c) sum k_s / (2/5). Any c > 0 gives a bound (a diagonal similarity leaves the
// eigenvalues alone); c = 2.5 balances the rows when k_n = k_s: 7 sum k / m, exact for the slip mode
// of two equal balls (7 k_s / m), against 10 sum k / m with c = 1.
inline constexpr double kSpinScale = 2.5;
// Rolling springs (PROP rr_fric) couple spins too: k_r = k_s Rbar^2 on a ball of radius R_b and its
// partner's spin gives the spin row k_s (Rbar / R_b) / (2/5) per contact (Rbar / R_b = R_p / (R_b + R_p);
// 1 at a wall). The contact loops add it to the ball's k_s sum divided by the spin row's (2 + 2 / c)
// (which over-counts it in the translation row: a step a little smaller, on the safe side).
inline constexpr double kRollingSpinShare = 1.0 / (2 + 2 / kSpinScale);
inline double rolling_ks(double ks, double partner_share) { return ks * partner_share * kRollingSpinShare; }
inline double ball_omega2(double mass, double sum_kmax, double sum_ks, bool rotation) {
  const double row = rotation ? std::max(2 * sum_kmax + 2 * kSpinScale * sum_ks, (2 + 2 / kSpinScale) / 0.4 * sum_ks)
                              : 2 * sum_kmax;
  return row / mass;
}

// Critical step of a mode with frequency omega and damping ratio xi under central differences
// with a lagged dashpot: (2 / omega)(sqrt(1 + xi^2) - xi).
inline double damped_critical_step(double omega, double xi) {
  return 2.0 / omega * (std::sqrt(1 + xi * xi) - xi);
}

}  // namespace trubal
