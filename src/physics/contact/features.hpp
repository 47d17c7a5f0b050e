// What a contact kernel computes, as a type: the template parameter of the contact law and of the
// contact loops, chosen once per CYCLE. One encoding to a table index (index / from_index), used by
// the loops' table and by the code that picks from it, so the two cannot disagree.
#pragma once

namespace trubal {

struct ContactFeatures {
  bool rotation = false;   // spins enter the relative velocity (and the moments)
  bool shear = false;      // tangential springs with the Coulomb limit (some ks > 0, or Hertz-Mindlin)
  bool hertz = false;      // Hertz-Mindlin springs instead of linear ones
  bool dashpot = false;    // Rayleigh stiffness dashpots or restitution dashpots
  bool details = false;    // the loop also writes the per-contact results measurements read

  static constexpr unsigned kCount = 32;
  constexpr unsigned index() const {
    return (rotation ? 1u : 0u) | (shear ? 2u : 0u) | (hertz ? 4u : 0u) | (dashpot ? 8u : 0u) | (details ? 16u : 0u);
  }
  static constexpr ContactFeatures from_index(unsigned i) {
    return {(i & 1u) != 0, (i & 2u) != 0, (i & 4u) != 0, (i & 8u) != 0, (i & 16u) != 0};
  }
  // The same law without the details (what the law itself computes does not depend on them).
  constexpr ContactFeatures law() const { return {rotation, shear, hertz, dashpot, false}; }
};

}  // namespace trubal
