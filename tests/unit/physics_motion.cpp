// Law of motion: free fall, fixed balls' reactions, oblique impact with friction (doc/validation.md 3).
#include <catch2/catch.hpp>

#include "physics/measure.hpp"
#include "physics_helpers.hpp"

using namespace trubal;

TEST_CASE("physics: free fall is the central-difference closed form to round-off", "[physics]") {
  Model model;
  model.materials[1] = test::linear_material(1e6, 1e6, 0.5, 1000);
  model.settings.gravity = {0, 0, -9.81};
  model.settings.fixed_dt = 1e-3;
  add_ball(model, 1, 1, 0, 0, 10, 0.1);
  model.balls.vz[0] = 2.0;   // v(-dt/2)
  auto backend = make_pipeline("serial", 1);
  const int n = 1000;
  REQUIRE_FALSE(run_cycles(model, *backend, n, {}).unstable);
  const double dt = 1e-3, g = -9.81;
  // v(n - 1/2) = v(-1/2) + n g dt;  z(n) = z(0) + n v(-1/2) dt + g dt^2 n (n + 1) / 2.
  CHECK(model.balls.vz[0] == Approx(2.0 + n * g * dt).epsilon(1e-13));
  CHECK(model.balls.z[0] == Approx(10 + n * 2.0 * dt + g * dt * dt * n * (n + 1) / 2).epsilon(1e-13));
  // The potential is taken at the half step, so kinetic + potential balances exactly.
  const EnergyReport e = energy(model);
  const double m = model.balls.mass[0];
  CHECK(e.total() == Approx(0.5 * m * 4.0 - m * g * (10 - 0.5 * dt * 2.0)).epsilon(1e-12));
}

TEST_CASE("physics: a fixed ball's reaction is the force it carries", "[physics]") {
  Model model;
  model.materials[1] = test::linear_material(1e6, 1e6, 0.5, 1000);
  model.settings.gravity = {0, 0, -9.81};
  model.settings.damping.kind = DampKind::Local;
  model.settings.damping.local = 0.7;
  add_ball(model, 1, 1, 0, 0, 0, 0.1);
  add_ball(model, 2, 1, 0, 0, 0.2, 0.1);
  model.balls.fixed[0] = kVel | kSpin;
  auto backend = make_pipeline("serial", 1);
  REQUIRE_FALSE(run_cycles(model, *backend, 20000, {}).unstable);
  const double m = model.balls.mass[0];
  // Settled: the bottom ball holds the top one's weight and its own; it has not moved.
  const auto r = reaction_force(model, {0});
  CHECK(r[2] == Approx(-2 * m * 9.81).epsilon(1e-6));
  CHECK(std::abs(r[0]) < 1e-9 * m);
  CHECK(model.balls.z[0] == 0);
  CHECK(model.balls.z[1] == Approx(0.2 - m * 9.81 / 1e6).epsilon(1e-6));
  CHECK(unbalanced_force(model).max_ratio < 1e-6);
}

namespace {

struct Oblique { double vt, vn, spin; bool slid = false, stuck_after_sliding = false; };

// A ball hits a fixed ball 1e4 times larger (a plane) with normal speed vn and tangential vt.
Oblique oblique(double vn, double vt, double mu) {
  const double r = 0.01;
  Model model;
  model.materials[1] = test::linear_material(1e7, 1e7, mu, 2700);
  model.settings.frac = 0.05;
  const double big = 1e4 * r;
  add_ball(model, 1, 1, 0, 0, -big, big);
  add_ball(model, 2, 1, 0, 0, r * 1.0001, r);
  model.balls.fixed[0] = kVel | kSpin;
  model.balls.vz[1] = -vn;
  model.balls.vx[1] = vt;
  auto backend = make_pipeline("serial", 1);
  Oblique out;
  int last_state = 0;
  CycleControl control;
  control.after_step = [&](const Model& m) {
    const int s = m.contacts.size() ? m.contacts.state[0] : 0;
    out.slid = out.slid || s == 2;
    if (last_state == 2 && s == 1) out.stuck_after_sliding = true;
    last_state = s;
  };
  bool touched = false;
  for (int k = 0; k < 200000; ++k) {
    REQUIRE_FALSE(run_cycles(model, *backend, 1, control).unstable);
    const bool now = model.contacts.size() && model.contacts.state[0] != 0;
    if (touched && !now) break;
    touched = touched || now;
  }
  out.vt = model.balls.vx[1];
  out.vn = model.balls.vz[1];
  out.spin = model.balls.wy[1];
  return out;
}

}  // namespace

TEST_CASE("physics: oblique impact with friction: gross sliding, then sticking", "[physics]") {
  const double mu = 0.1, vn = 1.0, r = 0.01;
  // tan(theta) = 2 > 3.5 mu (1 + e) = 0.7: sliding throughout. Rigid-body limits: the tangential
  // speed drops by mu (1 + e) vn, the spin becomes 2.5 mu (1 + e) vn / R (sense: rolling, +y).
  const Oblique slide = oblique(vn, 2.0, mu);
  CHECK(slide.slid);
  CHECK(slide.vn == Approx(vn).epsilon(0.01));
  CHECK(slide.vt == Approx(2.0 - 2 * mu * vn).epsilon(0.01));
  CHECK(slide.spin == Approx(2.5 * 2 * mu * vn / r).epsilon(0.01));
  // tan(theta) = 0.3 < 0.7: slides, then sticks. The tangential spring's own oscillation decides the
  // exit (Maw, Barber & Fawcett 1976), not the rolling limit; but angular momentum about the contact
  // point is kept whatever friction does: v_t + 2/5 R w = v_t0.
  const Oblique stick = oblique(vn, 0.3, mu);
  CHECK(stick.slid);
  CHECK(stick.stuck_after_sliding);
  CHECK(stick.spin > 0);
  CHECK(stick.vt + 0.4 * r * stick.spin == Approx(0.3).epsilon(1e-3));
  CHECK(slide.vt + 0.4 * r * slide.spin == Approx(2.0).epsilon(1e-3));
}
