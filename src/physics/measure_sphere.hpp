// Measurements in a region, after PFC's measurement spheres, and the porosity and volumetric strain
// of the whole space (man page, CONVENTIONS).
#pragma once

#include <array>
#include <cstddef>
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

// Throws std::runtime_error for a sphere a periodic cell cannot hold (a ball could meet it as two
// images: its radius plus the largest ball radius must not pass half the cell's narrowest width)
// or a radius that is not positive.
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
