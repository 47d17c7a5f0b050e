// What a contact kernel computes, as a type: the template parameter of the contact law and of the
// contact loops, chosen once per CYCLE. One encoding to a table index (index / from_index), used by
// the loops' table and by the code that picks from it, so the two cannot disagree.
//
// The table holds only the laws a scene can ask for, so that it grows with the parts a law is made
// of, not with every combination of bits: Hertz-Mindlin always has its shear spring, and a rolling
// spring needs the shear spring and the spins. The law's parts are one of kLaws rows (kLawRows);
// with the dashpot and details bits that makes kCount entries.
#pragma once

namespace trubal {

struct ContactFeatures {
  bool rotation = false;   // spins enter the relative velocity (and the moments)
  bool shear = false;      // tangential springs with the Coulomb limit (some ks > 0, or Hertz-Mindlin)
  bool hertz = false;      // Hertz-Mindlin springs instead of linear ones
  bool dashpot = false;    // Rayleigh stiffness dashpots or restitution dashpots
  bool details = false;    // the loop also writes the per-contact results measurements read
  bool rolling = false;    // rolling springs with their limit (some PROP rr_fric > 0)

  // The rows of law parts a scene can ask for: rotation, shear, hertz, rolling.
  static constexpr unsigned kLaws = 8;
  static constexpr bool kLawRows[kLaws][4] = {
      {false, false, false, false}, {true, false, false, false}, {false, true, false, false},
      {true, true, false, false},   {false, true, true, false},  {true, true, true, false},
      {true, true, false, true},    {true, true, true, true}};
  static constexpr unsigned kCount = kLaws * 4;   // with the dashpot and details bits

  constexpr unsigned law_row() const {
    for (unsigned r = 0; r < kLaws; ++r)
      if (kLawRows[r][0] == rotation && kLawRows[r][1] == shear && kLawRows[r][2] == hertz && kLawRows[r][3] == rolling)
        return r;
    return kLaws;   // not a law of the table (valid() is false)
  }
  // Whether the features are a law of the table (make_kernels asks only for those).
  constexpr bool valid() const { return law_row() < kLaws; }
  // Details last, so that the first half of the table is the loops without them.
  constexpr unsigned index() const { return law_row() + kLaws * (dashpot ? 1u : 0u) + 2 * kLaws * (details ? 1u : 0u); }
  static constexpr ContactFeatures from_index(unsigned i) {
    const bool* row = kLawRows[i % kLaws];
    return {row[0], row[1], row[2], (i / kLaws) % 2 != 0, i >= 2 * kLaws, row[3]};
  }
  // The same law without the details (what the law itself computes does not depend on them).
  constexpr ContactFeatures law() const { return {rotation, shear, hertz, dashpot, false, rolling}; }
  // The parts one loop over a batch makes (contact_lanes, physics/contact_law.hpp): all but the
  // rolling springs, which a pass of their own adds (rolling_lanes). A law with rolling thus shares
  // the loop of its row without it (kLawRows: shear, spins, and Hertz or not, either way).
  constexpr ContactFeatures without_rolling() const { return {rotation, shear, hertz, dashpot, details, false}; }
};

// Every entry decodes to itself.
consteval bool contact_features_round_trip() {
  for (unsigned i = 0; i < ContactFeatures::kCount; ++i)
    if (ContactFeatures::from_index(i).index() != i) return false;
  return true;
}
static_assert(contact_features_round_trip());

}  // namespace trubal
