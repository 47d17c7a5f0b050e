// Central differences with a step that changes (doc/physics.md "Law of motion", "Time step"): the
// automatic step (FRAC times the stable step) is held through contact episodes, so a collision's
// rebound does not depend on collisions elsewhere and an elastic gas keeps its energy as at the
// same step held by TSTEP; where the step does change (stability, TSTEP), the velocities move by F/m
// times the mean of the step before and this one, so a collision in progress keeps second order.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <string>

#include <fmt/format.h>

#include "interp_support.hpp"
#include "physics/measure.hpp"

using namespace trubal;
using namespace trubal::test;

namespace {

// Two equal balls meeting head-on at 0.5 m/s, FRAC 0.1 (16 steps in contact); with `others`, three
// more balls 1 m away in a line, the outer two closing on the middle one, which touches both from
// the middle of the pair's contact on: its estimate is sqrt(2) shorter while it does.
struct Rebound {
  double speed = 0, dt_min = 1e300, dt_max = 0;
};
Rebound pair_rebound(bool others, const std::string& backend = "serial") {
  Harness h;
  std::string deck =
      "backend " + backend + "\nstart box -10 10 -10 10 -10 10\nprop kn 1e6 dens 1000\nfrac 0.1\n"
      "ball -1.0002 0 0 1 id 1\nball 1.0002 0 0 1 id 2\ninit xvel 0.25 range id 1\ninit xvel -0.25 range id 2\n";
  if (others)
    deck += "ball -2.01 3 0 1 id 3\nball 0 3 0 1 id 4\nball 2.01 3 0 1 id 5\n"
            "init xvel 0.25 range id 3\ninit xvel -0.25 range id 5\n";
  REQUIRE(h.deck(deck));
  Rebound r;
  for (int k = 0; k < 40; ++k) {   // 400 steps: both collisions over, cut into CYCLEs of 10
    REQUIRE(h.deck("cycle 10\n"));
    r.dt_min = std::min(r.dt_min, h.session.model().dt);
    r.dt_max = std::max(r.dt_max, h.session.model().dt);
  }
  const Balls& b = h.session.model().balls;
  REQUIRE(b.x[1] - b.x[0] > 2.1);   // apart
  r.speed = b.vx[1] - b.vx[0];
  return r;
}

}  // namespace

TEST_CASE("step: a collision's rebound does not depend on an unrelated collision elsewhere", "[physics][cycle]") {
  const Rebound alone = pair_rebound(false), beside = pair_rebound(true);
  // Alone, every ball's step estimate is that of one contact, touching or not: the step holds.
  CHECK(alone.dt_min == alone.dt_max);
  // Beside, the middle ball of the other collision has two contacts, and its estimate is sqrt(2)
  // shorter while it does; at FRAC 0.1 stability needs no shorter step, so the held step stays.
  // (When the step followed the estimate, it shrank and grew again in the pair's contact, and the
  // rebound came out 0.501022 against 0.500990 alone: 6.4e-5 apart.)
  CHECK(beside.dt_min == beside.dt_max);
  CHECK(beside.dt_min == alone.dt_min);
  CAPTURE(alone.speed, beside.speed);
  CHECK(beside.speed == alone.speed);   // to the bit
  CHECK(alone.speed == Approx(0.5).epsilon(2e-3));   // elastic, to the step's own second-order error
  // The same bits on the other backends (the step before travels with the model).
  const Rebound threaded = pair_rebound(true, "threaded threads 2"), allpairs = pair_rebound(true, "allpairs");
  CHECK(threaded.speed == beside.speed);
  CHECK(allpairs.speed == beside.speed);
}

TEST_CASE("step: an elastic gas in a box keeps its energy at an automatic step as at the same step held",
          "[physics][cycle]") {
  // 125 balls in a box of six planes, no damping, no friction: a ball touching two others, or a wall
  // and a ball, has a shorter estimate, which used to change the automatic step all the time (the
  // drift was then 5.8e-4 against 4.1e-4 at the step held). Held through contact episodes, the
  // automatic step is the base step throughout: the same bits as TSTEP, whose drift is each
  // collision's own second-order error, random in sign.
  auto drift = [](const std::string& step) {
    Harness h;
    std::string deck = "start box -1.2 1.2 -1.2 1.2 -1.2 1.2\nprop kn 1e6 dens 1000\n";
    const char* planes[] = {"-1 0 0 1 0 0", "1 0 0 -1 0 0", "0 -1 0 0 1 0", "0 1 0 0 -1 0", "0 0 -1 0 0 1", "0 0 1 0 0 -1"};
    for (const char* p : planes) deck += std::string("wall plane ") + p + "\n";
    // A 5 x 5 x 5 lattice of balls, r 0.05, 0.4 apart, each with its own velocity (a fixed pattern).
    int id = 0;
    for (int i = 0; i < 5; ++i)
      for (int j = 0; j < 5; ++j)
        for (int k = 0; k < 5; ++k) {
          ++id;
          deck += fmt::format("ball {} {} {} 0.05 id {}\ninit xvel {} yvel {} zvel {} range id {}\n", -0.8 + 0.4 * i,
                              -0.8 + 0.4 * j, -0.8 + 0.4 * k, id, std::sin(1.3 * id), std::cos(2.1 * id),
                              std::sin(0.7 * id + 1), id);
        }
    deck += step + "\ncycle 1\n";
    REQUIRE(h.deck(deck));
    const double e0 = energy(h.session.model()).kinetic_translation + energy(h.session.model()).strain;
    REQUIRE(h.deck("cycle 20000\n"));
    const EnergyReport e = energy(h.session.model());
    return (e.kinetic_translation + e.strain) / e0 - 1;
  };
  Harness probe;
  REQUIRE(probe.deck("start box -1 1 -1 1 -1 1\nprop kn 1e6 dens 1000\nball 0 0 0 0.05\nfrac 0.1\ncycle 1\n"));
  const double base = probe.session.model().dt;   // FRAC 0.1 of one contact's stable step
  const double automatic = drift("frac 0.1"), held = drift(fmt::format("tstep {:.17g}", base));
  CAPTURE(automatic, held);
  CHECK(std::abs(automatic) <= std::abs(held));
  CHECK(automatic == held);
}
