// Measurements in a region, after PFC's measurement spheres, and the porosity and volumetric strain
// of the whole space (man page, CONVENTIONS).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>
#include <string>

#include "model/model.hpp"
#include "physics/measure.hpp"

namespace trubal {

struct MeasureSphere {
  std::array<double, 3> centre{};
  double radius = 0;
};

struct SphereMeasurement {
  double volume = 0;               // the sphere's, 4/3 pi r^3
  double solid = 0;                // the volume of the parts of balls inside it
  double porosity = 0;             // 1 - solid / volume
  double void_ratio = 0;           // porosity / (1 - porosity)
  std::size_t balls = 0;           // balls whose centres are inside
  std::size_t contacts = 0;        // touching ball pairs with a ball inside
  Sym6 stress{};                   // compression positive
  double coordination = 0;         // ball-pair contacts per ball inside
  double sliding = 0;              // fraction of those contacts that slide
  Sym6 fabric{};                   // mean n (x) n over them
};

// What a sphere's measurement is made of, over any share of the balls, pairs and wall contacts:
// exact sums, counts and a largest, so that merged over the shares (the ranks' parts) they are the
// whole model's, bit for bit, whatever the order.
struct SphereSums {
  ExactSum solid;                        // the parts of balls inside the sphere
  ExactSum inside_volume;                // the balls whose centres are inside, whole
  std::array<ExactSum, 6> moment;        // (contact point - centre) (x) force, compression positive
  std::array<ExactSum, 6> fabric;        // n (x) n over the touching pairs with a ball inside
  double balls = 0, ball_contacts = 0, contacts = 0, sliding = 0;   // counts
  double largest = 0;                    // the largest ball radius (the periodic cell's check)
  void add(const SphereSums& o);
  template <class F> void each_sum(F&& f) {
    f(solid);
    f(inside_volume);
    for (ExactSum& e : moment) f(e);
    for (ExactSum& e : fabric) f(e);
  }
  template <class F> void each_count(F&& f) {
    for (double* v : {&balls, &ball_contacts, &contacts, &sliding, &largest}) f(*v);
  }
};
// `balls`, `pairs`, `walls`: the rows taken (every one where null). A pair or wall contact is read
// where one of its balls lies inside, whether or not that ball is among `balls` (a rank's part: its
// own pairs, whose second ball may be a copy of another rank's).
SphereSums sphere_sums(const Model& model, const MeasureSphere& sphere, const std::vector<std::uint32_t>* balls = nullptr,
                       const std::vector<std::uint32_t>* pairs = nullptr, const std::vector<std::uint32_t>* walls = nullptr);
// The measurement from the sums over the whole model. Throws std::runtime_error for a sphere a
// periodic cell cannot hold (a ball could meet it as two images: its radius plus the largest ball
// radius must not pass half the cell's narrowest width) or a radius that is not positive.
SphereMeasurement sphere_measurement(const Space& space, const MeasureSphere& sphere, const SphereSums& sums);
// Throws as sphere_measurement for a sphere `space` cannot hold with balls of that largest radius.
void check_measure_sphere(const Space& space, const MeasureSphere& sphere, double largest_radius);
// sphere_measurement of the whole model's sums.
SphereMeasurement measure_sphere(const Model& model, const MeasureSphere& sphere);

// The volume common to a ball of radius r and a sphere of radius R whose centres are d apart.
double ball_sphere_overlap(double r, double R, double d);

struct Porosity {
  double volume = 0, solid = 0, porosity = 0, void_ratio = 0;
};
// The whole space: the balls' volumes over `volume` (the periodic cell, the START box or SET volume).
Porosity space_porosity(const Model& model, double volume);

// The periodic cell's volumetric strain since START or STRAIN reset, compression positive:
// 1 - V / V0 (a strain, 0.02 for a 2% loss of volume, however large the accumulated strains).
double volumetric_strain(const Model& model);

}  // namespace trubal
