// The instability guard (doc/physics.md "Time step") where a moving wall meets balls at rest: the
// wall's work is booked as a ball driven into a still wall books its kinetic energy, so a contact
// that forms between two steps makes the same error either way; the guard weighs that error
// against the energy of the approach in the wall's frame, and still stops a step that is unstable.
#include <catch2/catch.hpp>

#include <cmath>
#include <string>

#include <fmt/format.h>

#include "interp_support.hpp"
#include "physics/measure.hpp"

using namespace trubal;
using namespace trubal::test;

namespace {

constexpr double kRadius = 0.01, kStep = 1e-4;   // TSTEP: 0.4 of the lone ball's critical step
const std::string kMaterial = "start box -1 1 -1 1 -1 1\nprop kn 1e5 ks 1e5 mu 0.5 dens 2650\n";

// A plane wall at `speed` along +x toward a ball at rest at the origin, placed so that the contact
// forms 21 steps in with the overlap (1 - phase) speed dt: the wall starts (20 + phase) speed dt
// short of touching. With phase 0.9 the first overlap is a tenth of the step's travel, and the
// contact's error, k u g / 2 (doc/physics.md "Energy"), is 0.9/1.1 of the strain and the wall's
// work booked so far, which are all the lab frame sees of the collision at that step.
std::string wall_toward(double speed, double phase) {
  return fmt::format("wall plane {:.17g} 0 0 1 0 0 velocity {:.17g} 0 0\n",
                     -kRadius - (20 + phase) * speed * kStep, speed);
}

}  // namespace

TEST_CASE("walls: a wall driven into a ball at rest makes the energy error of the ball driven into the wall",
          "[walls][energy]") {
  // Seen from the wall the two are one collision, so the balance must move by the same amount: the
  // moving wall's work F . v_wall h (half of it after t) is booked right, and what is left is the
  // integration's own error at the contact's first and last steps.
  for (const double speed : {0.002, 0.2}) {
    INFO("speed " << speed);
    Harness wall_moves, ball_moves;
    const std::string ball = fmt::format("ball 0 0 0 {} id 1\ntstep {}\n", kRadius, kStep);
    REQUIRE(wall_moves.deck(kMaterial + ball + wall_toward(speed, 0.9)));
    REQUIRE(ball_moves.deck(kMaterial + ball + wall_toward(speed, 0.9) +
                            fmt::format("wall id 1 velocity 0 0 0\ninit xvel {:.17g}\n", -speed)));
    const CycleResult moved = wall_moves.session.cycle(60), driven = ball_moves.session.cycle(60);
    INFO(moved.message << driven.message);
    REQUIRE_FALSE(moved.unstable);
    REQUIRE_FALSE(driven.unstable);
    // (The ball-driven balance starts at its kinetic energy, the wall-driven one at 0.)
    const double m = ball_moves.session.model().balls.mass[0], approach = 0.5 * m * speed * speed;
    const double wall_error = energy(wall_moves.session.model()).total();
    const double ball_error = energy(ball_moves.session.model()).total() - approach;
    CAPTURE(wall_error, ball_error, approach);
    CHECK(std::abs(wall_error) > 1e-4 * approach);   // a real error (measured 1.2e-2 of it) ...
    CHECK(wall_error == Approx(ball_error).epsilon(1e-6));   // ... and the same (measured 5e-10 apart)
    CHECK(moved.balance_error == Approx(driven.balance_error).epsilon(1e-6));
    // The ball leaves at twice the wall's speed, less the step's error.
    CHECK(wall_moves.session.model().balls.vx[0] == Approx(2 * speed).epsilon(0.01));
  }
}

TEST_CASE("walls: the guard lets a wall driven into balls at rest run, at 0.002 to 0.2 m/s", "[walls][energy]") {
  // The error of the first contact is up to (omega dt)^2 / 4 of the approach's kinetic energy, which
  // the lab frame holds when the ball moves and not when the wall does: the guard counts the balls'
  // kinetic energy in the moving wall's frame. Before, each of these stopped at the first contact
  // with "unstable at cycle 22: energy was created ... try TSTEP".
  for (const double speed : {0.002, 0.02, 0.2}) {
    INFO("speed " << speed);
    Harness h;
    // A row of three balls at rest, the middle one off the axis (a glancing contact: friction and
    // spin), 1e-4 apart.
    REQUIRE(h.deck(kMaterial + fmt::format("ball 0 0 0 {0} id 1\nball 0.0201 0.003 0 {0} id 2\n"
                                           "ball 0.0402 0 0 {0} id 3\ntstep {1}\n", kRadius, kStep) +
                   wall_toward(speed, 0.9)));
    const CycleResult r = h.session.cycle(3000);
    INFO(r.message);
    CHECK_FALSE(r.unstable);
    CHECK(r.done == 3000);
    const EnergyReport e = energy(h.session.model());
    CAPTURE(r.balance_error, r.energy_scale, e.total(), e.boundary_work);
    CHECK(e.boundary_work > 0);
    // The balance closes to the contacts' own errors, within 1% (CYCLE's warning): at the end, of the
    // wall's work (measured 0.12% to 0.40%), and at every step, of the energy that moved (0.27% to 0.48%).
    CHECK(std::abs(e.total()) < 0.01 * e.boundary_work);
    CHECK(r.balance_error < 0.01 * r.energy_scale);
    CHECK(r.energy_warning.empty());
  }
  // The deck it was found with: a ball about 1 mm from the wall, the automatic step (FRAC 0.8);
  // it stopped at cycle 26 with "try FRAC 0.4".
  Harness h;
  REQUIRE(h.deck(kMaterial + "ball 0 0 0 0.01 id 1\nwall plane -0.011 0 0 1 0 0 velocity 0.2 0 0\n"));
  const CycleResult r = h.session.cycle(400);
  INFO(r.message);
  CHECK_FALSE(r.unstable);
  CAPTURE(r.balance_error, r.energy_scale);
  CHECK(r.balance_error < 0.01 * r.energy_scale);   // measured 0.69%: the first contact's 1.2e-5 J
}

TEST_CASE("walls: the guard still stops a wall driven into balls at a step beyond the stable one", "[walls][energy]") {
  // Three balls at rest between a fixed wall and one moving in: pressed together they vibrate at up
  // to 1.85 sqrt(kn / m), stable below TSTEP 3.6e-4. Beyond it the run stops, at either speed,
  // and the model is back at a finite state.
  for (const double speed : {0.002, 0.2}) {
    for (const double step : {6e-4, 2e-3}) {
      INFO("speed " << speed << " TSTEP " << step);
      Harness h;
      REQUIRE(h.deck(kMaterial + fmt::format("ball 0 0 0 {0} id 1\nball 0.0201 0 0 {0} id 2\n"
                                             "ball 0.0402 0 0 {0} id 3\nwall plane 0.0503 0 0 -1 0 0\n"
                                             "wall plane -0.0101 0 0 1 0 0 velocity {1} 0 0\ntstep {2}\n",
                                             kRadius, speed, step)));
      const CycleResult r = h.session.cycle(3000);
      INFO(r.message);
      CHECK(r.unstable);
      CHECK(r.message.find("unstable at cycle") != std::string::npos);
      CHECK(r.message.find("try TSTEP") != std::string::npos);
      const Balls& b = h.session.model().balls;
      for (std::size_t i = 0; i < b.size(); ++i) CHECK((std::isfinite(b.x[i]) && std::isfinite(b.vx[i])));
    }
  }
}
