// The periodic cell as the backends see it (PHYSICS.md "Periodic space"): balls are wrapped into
// the cell at the start of every step, each pair carries the image of j that i sees (int8 per
// axis), and every backend finds the same pairs with the same arithmetic, so that their answers
// stay bitwise equal. The rule that keeps one image per pair: every edge at least twice the
// largest diameter (then only the nearest image of a ball can touch it).
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "backends/pair_list.hpp"
#include "model/model.hpp"

namespace trubal {

// x_j - x_i for j's image `image` across a cell of edge L: (x_j - x_i) + image * L, in this order
// everywhere (detection, contact kernel, time step), so that every backend rounds alike. Outside
// a periodic space image is 0 and L is 0: the plain difference.
inline double image_delta(double xj, double xi, std::int8_t image, double length) {
  return (xj - xi) + static_cast<double>(image) * length;
}

// The image (-1, 0, +1) of j nearest to i along an axis, for wrapped positions (|d| < L).
inline std::int8_t nearest_image(double d, double length) {
  return d > 0.5 * length ? std::int8_t{-1} : (d < -0.5 * length ? std::int8_t{1} : std::int8_t{0});
}

// Edge lengths the kernels use: the cell's in periodic space, zeros outside.
inline std::array<double, 3> image_lengths(const Space& s) {
  return s.periodic ? s.length() : std::array<double, 3>{0, 0, 0};
}
// Rate of change of the edge lengths (compression positive strain rates: dL/dt = -rate L).
inline std::array<double, 3> image_rates(const Space& s) {
  if (!s.periodic) return {0, 0, 0};
  const auto L = s.length();
  return {-s.strain_rate[0] * L[0], -s.strain_rate[1] * L[1], -s.strain_rate[2] * L[2]};
}

// Throws std::runtime_error when some edge is shorter than twice the largest ball diameter.
void check_periodic_cell(const Model& model);

// The pair-list skin to use in the periodic cell: the given one, cut down so that a ball's reach
// (its diameter plus the skin) stays below half of every edge (one image per pair).
double periodic_skin(const Model& model, double skin);

// Wraps every ball centre into [lo, hi) of the periodic cell. A wrapped ball's velocity changes by
// the cell's edge velocity; the images of its pairs in model.contacts change so that each pair
// keeps the same partner image (and its history); ref (the backend's reference positions, if the
// same size) moves with the ball. The kinetic energy that the velocity change adds is counted as
// boundary work. Returns whether any ball moved.
bool wrap_into_cell(Model& model, std::vector<double>* ref_x, std::vector<double>* ref_y, std::vector<double>* ref_z);

// Every pair i < j (wrapped positions) with j's nearest image closer than R_i + R_j + skin, sorted by
// (i, j), with that image. skin 0 gives exactly the pairs the contact kernel gives a force.
void find_periodic_pairs(const Model& model, double skin, PairCandidates& out);

}  // namespace trubal
