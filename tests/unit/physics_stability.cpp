// Time step and the instability guard (doc/validation.md 6), energy conservation.
#include <catch2/catch.hpp>

#include <random>

#include "physics/measure.hpp"
#include "fcc_lattice.hpp"
#include "physics_helpers.hpp"

using namespace trubal;

namespace {

void cundall_damping(Model& model) {
  // DAMP 0.05 0.5: alpha = lambda omega, beta = lambda / omega, omega = 2 pi f.
  const double omega = 2 * M_PI * 0.5;
  model.settings.damping.kind = DampKind::Rayleigh;
  model.settings.damping.alpha = 0.05 * omega;
  model.settings.damping.beta = 0.05 / omega;
}

}  // namespace

TEST_CASE("physics: Cundall's Rayleigh damping runs stably with the automatic step", "[physics]") {
  Model model = test::held_fcc_block(4, 1e8);
  cundall_damping(model);
  auto backend = make_pipeline("serial", 1);
  const CycleResult r = run_cycles(model, *backend, 3000, {});
  INFO(r.message);
  REQUIRE_FALSE(r.unstable);
  // Heavily over-damped high modes: the step is far below the undamped one, yet not zero.
  CHECK(model.dt > 0);
  const EnergyReport e = energy(model);
  CHECK(std::isfinite(e.total()));
  CHECK(e.kinetic_translation + e.kinetic_rotation < 1e-3 * e.strain);
}

TEST_CASE("physics: an unstable step is caught by the guard and the model is left finite", "[physics]") {
  // The step bound is Gershgorin's, conservative by about 1.75 in frequency on this pack: measured
  // limits are FRAC 1.5-2 undamped and FRAC 3-4 with Cundall's damping (over-damped: squared).
  const bool damped = GENERATE(false, true);
  Model model = test::held_fcc_block(4, 1e8);
  if (damped) cundall_damping(model);
  model.settings.frac = damped ? 5 : 2;
  auto backend = make_pipeline("serial", 1);
  const CycleResult r = run_cycles(model, *backend, 5000, {});
  REQUIRE(r.unstable);
  INFO(r.message);
  CHECK(r.message.find("cycle") != std::string::npos);
  CHECK(r.message.find("ball") != std::string::npos);
  CHECK(r.message.find("FRAC 0.8") != std::string::npos);
  CHECK(model.cycle == r.done);
  for (std::size_t i = 0; i < model.balls.size(); ++i)
    REQUIRE((std::isfinite(model.balls.x[i]) && std::isfinite(model.balls.vx[i]) && std::isfinite(model.balls.wz[i])));
  // And the state it went back to cycles on at a sane step.
  model.settings.frac = 0.8;
  CHECK_FALSE(run_cycles(model, *backend, 200, {}).unstable);
}

TEST_CASE("physics: an undamped frictionless gas keeps its energy", "[physics]") {
  // Balls bouncing on a fixed ball 1000 times larger (a floor) under gravity, and on each other.
  Model model;
  model.materials[1] = test::linear_material(1e5, 0, 0, 1000);
  model.settings.gravity = {0, 0, -9.81};
  model.settings.frac = 0.02;
  const double r = 0.01, big = 1000 * r;
  add_ball(model, 1, 1, 0, 0, -big, big);
  model.balls.fixed[0] = kVel | kSpin;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int k = 0; k < 40; ++k) {
    const std::size_t b = add_ball(model, 0, 1, 0.03 * (k % 6) - 0.075, 0.03 * ((k / 6) % 2), 0.02 + 0.03 * (k / 12), r);
    model.balls.vx[b] = 0.2 * u(rng); model.balls.vy[b] = 0.2 * u(rng); model.balls.vz[b] = 0.2 * u(rng);
  }
  auto backend = make_pipeline("serial", 1);
  REQUIRE_FALSE(run_cycles(model, *backend, 1, {}).unstable);
  const double e0 = energy(model).total();
  const double k0 = energy(model).kinetic_translation;
  std::size_t collisions = 0;
  CycleControl control;
  control.after_step = [&](const Model& m) { collisions += contact_count(m); };
  REQUIRE_FALSE(run_cycles(model, *backend, 100000, control).unstable);
  const EnergyReport e = energy(model);
  INFO("contact-steps " << collisions << " kinetic " << e.kinetic_translation << " from " << k0);
  CHECK(collisions > 10000);
  CHECK(e.total() == Approx(e0).epsilon(1e-4));
}
