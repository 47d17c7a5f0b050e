// The contact law of every pair of ball types, mixed once per CYCLE from the materials
// (doc/physics.md "Mixed materials"), and what a ball without contacts counts as touching.
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include "model/model.hpp"
#include "physics/bridge.hpp"
#include "physics/contact_law.hpp"

namespace trubal {

struct PairLaws {
  int type_count = 1;                       // materials, by compact index in type-number order
  std::vector<std::uint16_t> ball_type;     // compact type index per ball
  std::vector<std::uint16_t> wall_type;     // compact type index per wall (Model::walls order)
  std::vector<PairLaw> table;               // by pair of compact indices (type_count^2 entries)
  // A ball without contacts counts as touching one ball of its own kind (per compact type).
  std::vector<double> alone_kn, alone_ks, alone_xi;
  // Where every ball is of one type (walls may be of others): the index in `table` of the law of
  // every ball pair, which the contact loops then take once instead of per pair; -1 otherwise.
  int ball_pair_law = -1;
  bool one_ball_law() const { return ball_pair_law >= 0; }
  // That law (with one_ball_law(); else the table's first, which the per-pair loops do not read).
  const PairLaw& ball_law() const { return table[ball_pair_law >= 0 ? ball_pair_law : 0]; }

  const PairLaw& law(std::size_t i, std::size_t j) const {
    return type_count == 1 ? table[0] : table[ball_type[i] * type_count + ball_type[j]];
  }
  // Ball `ball` against wall `wall` (an index into Model::walls).
  const PairLaw& wall_law(std::size_t ball, std::size_t wall) const {
    return type_count == 1 ? table[0] : table[ball_type[ball] * type_count + wall_type[wall]];
  }
  // The capillary bridges by pair of compact indices (as `table`), where some pair has one; else empty.
  std::vector<BridgeLaw> bridges;
  const BridgeLaw& bridge(std::size_t i, std::size_t j) const {
    return type_count == 1 ? bridges[0] : bridges[ball_type[i] * type_count + ball_type[j]];
  }
  const BridgeLaw& wall_bridge(std::size_t ball, std::size_t wall) const {
    return type_count == 1 ? bridges[0] : bridges[ball_type[ball] * type_count + wall_type[wall]];
  }
};

PairLaws make_pair_laws(const Model& model);

// The stiffness sums of a ball with no contact (sum_kmax 0): those of one contact with a ball of
// its own kind; its dashpot sum only where `sum_cn` is given.
inline void alone_sums(const PairLaws& laws, std::size_t ball, double mass, double& sum_kmax, double& sum_ks,
                       double* sum_cn) {
  const std::uint16_t t = laws.type_count == 1 ? 0 : laws.ball_type[ball];
  const double kn = laws.alone_kn[t];
  sum_kmax = kn > laws.alone_ks[t] ? kn : laws.alone_ks[t];
  sum_ks = laws.alone_ks[t];
  if (sum_cn) *sum_cn = 2 * laws.alone_xi[t] * std::sqrt(kn * 0.5 * mass);
}

// m* of a pair for its dashpot. A ball whose velocity is held in every component (FIX vel) is a
// partner of infinite mass, as a wall is: m* is then the other ball's mass (both held: the plain
// m_i m_j / (m_i + m_j)), so that PROP rest e holds against a fixed ball too.
inline bool velocity_held(std::uint8_t fixed) { return (fixed & kVel) == kVel; }
inline double pair_mstar(double mi, double mj, bool held_i, bool held_j) {
  return held_j && !held_i ? mi : (held_i && !held_j ? mj : mi * mj / (mi + mj));
}

// The damping ratio that gives restitution e in a head-on impact (linear law with the no-pull
// clamp: exact; Hertz: the usual -ln e / sqrt(pi^2 + ln^2 e)).
double restitution_xi(double e, bool hertz);

}  // namespace trubal
