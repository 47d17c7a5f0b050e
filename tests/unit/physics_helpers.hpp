// Small builders shared by the physics tests: models made directly in C++, run on a backend.
#pragma once

#include <cmath>
#include <memory>

#include "ball_at.hpp"
#include "cycle/pipeline.hpp"
#include "model/edit.hpp"
#include "model/model.hpp"
#include "cycle/run.hpp"
#include "physics/scene.hpp"
#include "physics/timestep.hpp"

namespace trubal::test {

inline Material linear_material(double kn, double ks, double mu, double density) {
  Material m;
  m.kn = kn; m.ks = ks; m.friction = mu; m.density = density;
  return m;
}

inline Material hertz_material(double young, double poisson, double density, double mu = 0) {
  Material m;
  m.shear_modulus = young / (2 * (1 + poisson));
  m.poisson = poisson; m.density = density; m.friction = mu;
  return m;
}

inline double sphere_mass(double density, double r) { return density * 4.0 / 3.0 * M_PI * r * r * r; }

// Runs n cycles, failing the test on instability.
inline CycleResult cycle(Model& model, Pipeline& backend, std::int64_t n, const CycleControl& control = {}) {
  return run_cycles(model, backend, n, control);
}

}  // namespace trubal::test
