// Capillary bridges (PROP bridge; doc/physics.md "Capillary bridges"): a pendular liquid bridge
// between two balls, or a ball and a wall, pulling them together. The force is the closed form of
// Willett, Adams, Johnson and Seville (2000, Langmuir 16:9396) for a bridge of volume V between
// spheres at a gap s,
//   F = 2 pi R gamma cos(theta) / (1 + 2.1 S + 10 S^2),  S = (s / 2) sqrt(R / V),
// R = 2 R* (Derjaguin: R* = R1 R2 / (R1 + R2), a ball's radius at a wall), and F at contact for
// s <= 0. A bridge forms when the pair touches (s <= 0) and breaks beyond the rupture gap of Lian,
// Thornton and Adams (1993, J. Colloid Interface Sci. 161:138), s_c = (1 + theta / 2) V^(1/3)
// (theta in radians); once broken it stays so until the pair touches again.
#pragma once

#include <cmath>
#include <numbers>

#include "model/model.hpp"

namespace trubal {

// The bridge of a pair of types, mixed from their materials (mix_bridge). volume 0: no bridge.
struct BridgeLaw {
  double volume = 0;        // V
  double pull = 0;          // 2 pi gamma cos(theta): the force at contact per unit of R
  double rupture = 0;       // s_c
  bool on() const { return volume > 0; }
};

// Two types meet with a bridge where both have one; its volume, surface tension and contact angle
// are the means of theirs (the liquid of a bridge comes from both grains).
BridgeLaw mix_bridge(const Material& a, const Material& b);

// The bridge's pull on a pair of radii ri, rj at gap s (>= 0 apart, <= 0 touching): F > 0 draws
// the pair together. The one arithmetic of the step, the output and the tests.
inline double bridge_force(const BridgeLaw& law, double ri, double rj, double gap) {
  const double r = 2 * (ri * rj / (ri + rj));
  const double s = gap > 0 ? gap : 0.0;
  const double S = 0.5 * s * std::sqrt(r / law.volume);
  return law.pull * r / (1 + 2.1 * S + 10 * S * S);
}

// The work a bridge does from contact to rupture, the integral of F from s = 0 to s_c, in closed
// form (S = a s, a = sqrt(R / V) / 2; 1 + 2.1 S + 10 S^2 has no real roots).
inline double bridge_work_to_rupture(const BridgeLaw& law, double ri, double rj) {
  const double r = 2 * (ri * rj / (ri + rj));
  const double a = 0.5 * std::sqrt(r / law.volume), root = std::sqrt(40 - 2.1 * 2.1);
  auto primitive = [&](double S) { return 2 / root * std::atan((20 * S + 2.1) / root); };
  return law.pull * r / a * (primitive(a * law.rupture) - primitive(0));
}

// The farthest gap at which some pair of the model's types can hold a bridge (0: none): how far
// beyond the pair list's skin the search must reach.
double bridge_reach(const Model& model);
// Whether some material has a bridge (PROP bridge): output then shows the bridges.
bool has_bridges(const Model& model);
// The law of the pair of balls' types, and of a ball against a wall (the wall's type).
BridgeLaw pair_bridge(const Model& model, std::size_t i, std::size_t j);
BridgeLaw wall_bridge(const Model& model, std::size_t ball, std::size_t wall);
// Bridges intact now: between balls, and between balls and walls.
std::size_t count_bridges(const ContactTable& c);
std::size_t count_bridges(const WallContacts& w);

}  // namespace trubal
