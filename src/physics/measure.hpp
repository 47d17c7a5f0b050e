// Measurements of the current state: stress, energy, fabric, coordination, unbalanced force.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "model/model.hpp"
#include "support/exact_sum.hpp"

namespace trubal {

using Sym6 = std::array<double, 6>;   // xx yy zz xy xz yz

// Adds the symmetric part of a (x) b to s, in Sym6 order.
void add_dyad(Sym6& s, double ax, double ay, double az, double bx, double by, double bz);
// The symmetric part of a (x) b, in Sym6 order, into six exact sums (each term as add_dyad's).
struct DyadSums {
  explicit DyadSums(std::array<ExactSum, 6>& s) : xx(s[0]), yy(s[1]), zz(s[2]), xy(s[3]), xz(s[4]), yz(s[5]) {}
  void add(double ax, double ay, double az, double bx, double by, double bz) {
    xx.add(ax * bx); yy.add(ay * by); zz.add(az * bz);
    xy.add(0.5 * (ax * by + ay * bx));
    xz.add(0.5 * (ax * bz + az * bx));
    yz.add(0.5 * (ay * bz + az * by));
  }
  ExactSum::Stream xx, yy, zz, xy, xz, yz;
};

// f(p) for the rows given (every row of n where null): the share of a table a sum is taken over.
template <class F> void each_row(const std::vector<std::uint32_t>* rows, std::size_t n, F&& f) {
  if (!rows) {
    for (std::size_t p = 0; p < n; ++p) f(p);
    return;
  }
  for (std::uint32_t p : *rows)
    if (p < n) f(p);
}

// Love's formula's sums over the contacts, sum_c f_a l_b (the force on j by the branch vector i ->
// j; a wall contact's force on the wall by the branch from the ball's centre to the contact point;
// the capillary bridges' forces likewise), each component an exact sum (support/exact_sum.hpp), so
// that the total depends neither on the contacts' order nor on how they are shared among ranks.
// `pairs`, `walls`: the rows summed (every one where null): a rank's own on its part.
struct StressSums {
  std::array<ExactSum, 6> s;
  Sym6 over(double volume) const;   // the average stress in that volume (compression positive)
  void add(const StressSums& o);
};
StressSums stress_sums(const Model& model, const std::vector<std::uint32_t>* pairs = nullptr,
                       const std::vector<std::uint32_t>* walls = nullptr);
// Average stress (1/V) sum_c f_a l_b over the contacts (compression positive).
Sym6 average_stress(const Model& model, double volume);

// A triaxial test's stresses, compression positive: the deviator q = sigma1 - sigma3 and the mean
// stress p = (sigma1 + 2 sigma3) / 3; from a stress tensor with z axial, sigma1 = s33 and sigma3 =
// (s11 + s22) / 2 (then p is the trace over 3).
struct TriaxialStress {
  double sigma1 = 0, sigma3 = 0, q = 0, p = 0;
};
inline TriaxialStress triaxial_stress(double sigma1, double sigma3) {
  return {sigma1, sigma3, sigma1 - sigma3, (sigma1 + 2 * sigma3) / 3};
}
inline TriaxialStress triaxial_stress(const Sym6& s) { return triaxial_stress(s[2], 0.5 * (s[0] + s[1])); }

// The energy terms, all at one time: where the balls are as the last step left them, at t, the
// time of its force pass (Model::energy_at_step: kinetic m v(t - dt/2).v(t + dt/2)/2, the springs
// and gravity at x(t), the works up to t); otherwise (before the first step, after an edit of the
// balls) from the state as it is, the strain from the contact table's last force pass.
struct EnergyReport {
  double kinetic_translation = 0, kinetic_rotation = 0, strain = 0;
  double friction_work = 0, damping_work = 0, boundary_work = 0;
  double rolling_work = 0;         // dissipated by the rolling springs' limit
  double capillary_work = 0;       // done on the balls by the capillary bridges (energy in)
  double bond_break_work = 0;      // the strain energy the parallel bonds held when they broke (lost)
  double potential = 0;            // gravity, relative to x = 0
  bool at_step = false;            // taken at the last step's t (else from the state as it is)
  double total() const;            // kinetic + strain + potential + dissipated (bonds broken too) - boundary - capillary
};
EnergyReport energy(const Model& model);

double coordination_number(const Model& model);   // 2 * contacts / balls
double sliding_fraction(const Model& model);
Sym6 fabric_tensor(const Model& model);
std::size_t contact_count(const Model& model);

struct Unbalanced { double mean_ratio = 0, max_ratio = 0; };
Unbalanced unbalanced_force(const Model& model);

// What the whole space's contact measures are made of (the fabric, the coordination, the sliding
// fraction, the unbalanced-force ratio), over any share of the pairs, wall contacts and balls: exact
// sums, counts and a largest, so that merged over the shares (the ranks' parts) they are the whole
// model's, bit for bit. `pairs`, `walls`, `balls`: the rows taken (every one where null).
struct ContactSums {
  std::array<ExactSum, 6> fabric;   // n (x) n over the touching pairs
  ExactSum contact_force;           // |f| over the touching pairs and wall contacts
  ExactSum unbalanced;              // |F| over the balls not fixed in every velocity (their free components)
  double unbalanced_max = 0;        // the largest of those
  double touching = 0, sliding = 0, contacts = 0, free_balls = 0;   // counts (touching pairs; and wall contacts)
  void add(const ContactSums& o);
  template <class F> void each_sum(F&& f) {
    for (ExactSum& e : fabric) f(e);
    f(contact_force);
    f(unbalanced);
  }
  Sym6 fabric_tensor() const;
  double sliding_fraction() const;
  double coordination(std::size_t balls) const { return balls ? 2.0 * touching / static_cast<double>(balls) : 0.0; }
  Unbalanced unbalanced_ratio() const;
};
ContactSums contact_sums(const Model& model, const std::vector<std::uint32_t>* pairs = nullptr,
                         const std::vector<std::uint32_t>* walls = nullptr, const std::vector<std::uint32_t>* balls = nullptr);

// Sum of the unbalanced force on the given balls (for fixed balls: the reaction force they carry).
std::array<double, 3> reaction_force(const Model& model, const std::vector<std::size_t>& balls);
// The platen balls' heights and unbalanced forces in the model's order (the order their sums are
// made in): from the model's balls, or from the ranks' parts (Pipeline::platens_on_parts).
struct PlatenBalls {
  std::vector<double> z, fx, fy, fz;
};
PlatenBalls platen_balls_of(const Model& model, const std::vector<std::size_t>& balls);
std::array<double, 3> reaction_force(const PlatenBalls& balls);

// Two platens among the given balls (Rowe's triaxial test): the balls above and below the middle of
// their z extent. force: the axial force F1 they carry, (Fz_upper - Fz_lower) / 2 from their
// reactions, compression positive; gap: mean z of the upper minus mean z of the lower.
struct Platens {
  double force = 0, gap = 0;
  bool two = false;                // both platens hold balls and are apart
};
Platens platens(const Model& model, const std::vector<std::size_t>& balls);
Platens platens(const PlatenBalls& balls);

}  // namespace trubal
