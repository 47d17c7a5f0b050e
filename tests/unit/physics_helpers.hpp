// Small builders shared by the physics tests: models made directly in C++, run on a backend.
#pragma once

#include <cmath>
#include <memory>
#include <random>

#include "ball_at.hpp"
#include "fcc_lattice.hpp"
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

// A dense FCC block of n x n x n cells (overlap 1% of d, positions jittered by 0.1% of d), the outer
// cells held, the inside free to vibrate: the guard's and the step's tests (physics_stability.cpp,
// physics_guard_checks.cpp).
inline Model held_fcc_block(int n, double ks = 1e8) {
  Model model;
  model.materials[1] = linear_material(1e8, ks, 0.3, 2500);
  const double r = 0.01, a = 0.99 * 2 * r * std::sqrt(2.0);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> jitter(-2e-5, 2e-5);
  for_each_fcc_site(n, n, n, a, 0, [&](const FccSite& site) {
    const std::size_t ball = add_ball(model, 0, 1, site.x + jitter(rng), site.y + jitter(rng), site.z + jitter(rng), r);
    if (site.on_surface) model.balls.fixed[ball] = kVel | kSpin;
  });
  return model;
}

}  // namespace trubal::test
