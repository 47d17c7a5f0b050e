// Walls against closed forms: a ball at rest on a plane, restitution and Hertz against a wall (a
// partner of infinite mass and radius), sliding down an incline, the nearest point of each kind,
// the energy a moving wall puts in, the servo holding a platen's stress, and bad input.
#include <catch2/catch.hpp>

#include <cmath>
#include <numbers>

#include <fmt/format.h>

#include "interp_support.hpp"
#include "scene_decks.hpp"
#include "model/wall_shape.hpp"
#include "physics/measure.hpp"
#include "physics/walls.hpp"

using namespace trubal;
using namespace trubal::test;

namespace {

const double kPi = std::numbers::pi;

double ball_mass(double density, double r) { return density * 4.0 / 3.0 * kPi * r * r * r; }

}  // namespace

TEST_CASE("walls: a ball comes to rest on a plane at R - mg/kn, and the plane carries its weight", "[walls]") {
  Harness h;
  REQUIRE(h.deck("start box -1 1 -1 1 -1 2\nprop kn 1e6 ks 1e6 fric 0.5 dens 1000 rest 0.3\n"
                 "ball 0 0 0.2 0.1\nwall plane 0 0 0 0 0 1\ngrav 0 0 -10\ncycle 20000\n"));
  const Model& m = h.session.model();
  const double weight = ball_mass(1000, 0.1) * 10;
  // The static overlap of a linear spring: U = W / kn (same type: the mixed kn is the type's).
  CHECK(m.balls.z[0] == Approx(0.1 - weight / 1e6).epsilon(1e-9));
  REQUIRE(m.walls.size() == 1);
  CHECK(m.walls[0].force[2] == Approx(-weight).epsilon(1e-9));   // the ball pushes the floor down
  CHECK(m.walls[0].contacts == 1);
  CHECK(m.walls[0].normal_force == Approx(weight).epsilon(1e-9));
}

TEST_CASE("walls: a ball bounces off a wall with the material's restitution (the wall has infinite mass)", "[walls]") {
  // Head-on, no gravity, a small step: the linear dashpot gives e exactly (pair_laws.cpp), with
  // m* = m. Were the wall given the ball's mass (m* = m/2), e would come out near 0.61.
  for (const char* wall : {"wall plane 0 0 0 0 0 1", "wall polygon -1 -1 0 1 -1 0 1 1 0 -1 1 0",
                           "wall cylinder 0 0 -1 1 0 0 radius 0.3 length 2 outside"}) {
    INFO(wall);
    Harness h;
    const double z0 = std::string(wall).find("cylinder") != std::string::npos ? 0.5 : 0.2;
    REQUIRE(h.deck(fmt::format("start box -1 1 -1 1 -2 2\nprop kn 1e6 ks 1e6 dens 1000 rest 0.5\n"
                               "ball 0 0 {} 0.1\ninit zvel -1\nfrac 0.02\n{}\ncycle 60000\n",
                               z0, wall)));
    const Balls& b = h.session.model().balls;
    CHECK(b.vz[0] == Approx(0.5).epsilon(0.005));
  }
}

TEST_CASE("walls: Hertz-Mindlin against a plane is a sphere on a flat, R* = R", "[walls]") {
  Harness h;
  REQUIRE(h.deck("start box -1 1 -1 1 -1 2\nprop shear 1e7 poisson 0.25 dens 1000 fric 0.3 rest 0.2\n"
                 "ball 0 0 0.2 0.1\nwall plane 0 0 0 0 0 1\ngrav 0 0 -10\ncycle 40000\n"));
  const Model& m = h.session.model();
  const double weight = ball_mass(1000, 0.1) * 10;
  // F = 4/3 E* sqrt(R) U^1.5, 1/E* = 2 (1 - nu) / (2 G): two bodies of the same material.
  const double estar = 1e7 / (1 - 0.25);
  const double u = std::pow(weight / (4.0 / 3.0 * estar * std::sqrt(0.1)), 2.0 / 3.0);
  CHECK(m.balls.z[0] == Approx(0.1 - u).epsilon(1e-8));
  CHECK(-m.walls[0].force[2] == Approx(weight).epsilon(1e-6));
}

TEST_CASE("walls: a block-like ball slides down a rough incline at g (sin a - mu cos a)", "[walls]") {
  // Spin held, so the ball slides; the plane through the origin tilted by a about y.
  const double a = 30 * kPi / 180, mu = 0.3;
  Harness h;
  REQUIRE(h.deck(fmt::format("start box -1000 1000 -1000 1000 -1000 1000\nprop kn 1e7 ks 1e7 fric {} dens 1000 rest 0.2\n"
                             "wall plane 0 0 0 {} 0 {}\nball {} 0 {} 0.1\nfix spin\ngrav 0 0 -10\n"
                             "cycle 2000\n",
                             std::atan(mu) * 180 / kPi, -std::sin(a), std::cos(a), -0.1 * std::sin(a), 0.1 * std::cos(a))));
  const Model& m = h.session.model();
  const double v0 = std::hypot(m.balls.vx[0], m.balls.vz[0]);
  const double t0 = m.time;
  REQUIRE(h.deck("cycle 20000\n"));
  const double v1 = std::hypot(m.balls.vx[0], m.balls.vz[0]);
  const double accel = (v1 - v0) / (m.time - t0);
  CHECK(accel == Approx(10 * (std::sin(a) - mu * std::cos(a))).epsilon(0.003));
  CHECK(m.walls[0].contacts == 1);
}

TEST_CASE("walls: the nearest point of a plane, a polygon and a cylinder", "[walls]") {
  Wall square;
  square.kind = WallKind::Polygon;
  square.vertices = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  REQUIRE(complete_wall(square) == "");
  CHECK(square.normal[2] == Approx(1));
  CHECK(wall_area(square) == Approx(1));
  auto touch = wall_touch(square, {0.5, 0.5, 0.3});   // above the inside
  CHECK(touch.gap == Approx(0.3));
  CHECK(touch.dir[2] == Approx(-1));
  touch = wall_touch(square, {0.5, 0.5, -0.2});       // below: two-sided
  CHECK(touch.gap == Approx(0.2));
  CHECK(touch.dir[2] == Approx(1));
  touch = wall_touch(square, {1.3, 0.5, 0.4});        // beyond an edge: the edge is nearest
  CHECK(touch.gap == Approx(0.5));
  CHECK(touch.dir[0] == Approx(-0.6));
  touch = wall_touch(square, {-0.3, -0.4, 0});        // beyond a corner
  CHECK(touch.gap == Approx(0.5));

  Wall cup;
  cup.kind = WallKind::Cylinder;
  cup.point = {0, 0, 0};
  cup.normal = {0, 0, 2};
  cup.radius = 1;
  cup.length = 2;
  REQUIRE(complete_wall(cup) == "");
  CHECK(cup.normal[2] == Approx(1));
  CHECK(wall_area(cup) == Approx(4 * kPi));
  touch = wall_touch(cup, {0.6, 0.8 * 0.5, 1});       // inside: gap to the surface, outward
  CHECK(touch.gap == Approx(1 - std::hypot(0.6, 0.4)));
  CHECK(touch.dir[0] > 0);
  touch = wall_touch(cup, {0, 1, 2.5});               // above the open top, over the rim
  CHECK(touch.gap == Approx(0.5));
  cup.inside = false;
  touch = wall_touch(cup, {0, 1.5, 1});               // outside: gap to the surface, inward
  CHECK(touch.gap == Approx(0.5));
  CHECK(touch.dir[1] == Approx(-1));

  Wall plane;
  plane.point = {0, 0, 1};
  plane.normal = {0, 0, -3};
  REQUIRE(complete_wall(plane) == "");
  touch = wall_touch(plane, {5, 5, 0.25});            // one-sided, signed
  CHECK(touch.gap == Approx(0.75));
  touch = wall_touch(plane, {5, 5, 1.25});
  CHECK(touch.gap == Approx(-0.25));

  Wall line;
  line.kind = WallKind::Polygon;
  line.vertices = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}};
  CHECK(complete_wall(line).find("line") != std::string::npos);
  Wall bent;
  bent.kind = WallKind::Polygon;
  bent.vertices = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0.5}};
  CHECK(complete_wall(bent).find("planar") != std::string::npos);
}

TEST_CASE("walls: a moving piston's work is counted, and the energy balances", "[walls]") {
  // Elastic balls with no damping in a closed box of six planes; the top plane moves down, then up.
  // Whatever the balls gain is the piston's work (boundary work), to the step's accuracy.
  Harness h;
  REQUIRE(h.deck("start box -0.1 0.1 -0.1 0.1 -0.1 0.3\nprop kn 1e5 ks 5e4 fric 20 dens 1000\n"
                 "wall plane 0 0 0 0 0 1\nwall plane 0 0 0.2 0 0 -1\n"
                 "wall plane -0.05 0 0 1 0 0\nwall plane 0.05 0 0 -1 0 0\n"
                 "wall plane 0 -0.05 0 0 1 0\nwall plane 0 0.05 0 0 -1 0\n"
                 "gen 60 0.008 0.01 seed 4 range x -0.04 0.04 y -0.04 0.04 z 0.01 0.19\n"
                 "init xvel 0.3 yvel -0.2 zvel 0.1\nfrac 0.2\ncycle 200\n"));
  const double e0 = energy(h.session.model()).total();
  REQUIRE(h.deck("wall id 2 velocity 0 0 -0.5\ncycle 4000\nwall id 2 velocity 0 0 0.3\ncycle 3000\n"));
  const Model& m = h.session.model();
  const EnergyReport e = energy(m);
  const double kinetic = e.kinetic_translation + e.kinetic_rotation;
  INFO("kinetic " << kinetic << " boundary " << e.boundary_work << " balance " << e.total() << " from " << e0);
  CHECK(std::abs(e.boundary_work) > 0.2 * kinetic);                       // the piston did real work
  // To 1.5%: measured 1.01%, the bits of the same step held by TSTEP (no ball is ever stiffer than a
  // lone one at FRAC 0.2, so the automatic step holds); 0.94% when it followed the estimate.
  CHECK(std::abs(e.total() - e0) < 0.015 * (kinetic + std::abs(e.boundary_work)));
  CHECK(m.walls[1].work == Approx(e.boundary_work).epsilon(1e-9));        // all of it the piston's
}

TEST_CASE("walls: the servo holds a platen's stress on a sample in a cylinder", "[walls]") {
  // Balls settle under gravity in a container cylinder on a floor; a servo platen comes down on them.
  Harness h;
  REQUIRE(h.deck("start box -0.05 0.05 -0.05 0.05 -0.01 0.1\nprop kn 1e5 ks 1e5 fric 20 dens 2650\n"
                 "wall plane 0 0 0 0 0 1\nwall cylinder 0 0 0 0 0 1 radius 0.02 length 0.08\n"
                 "gen 150 0.002 0.0025 seed 2 range cylinder 0 0 0.017 z 0.003 0.04\n"
                 "damp local 0.7\ngrav 0 0 -9.81\ncycle 20000\nwall id 3 plane 0 0 0.02 0 0 -1\n"
                 "servo wall 3 stress 5000 area 0.0012566 max 0.05\ncycle 40000\n"
                 "hist wall 3 every 100\ncycle 5000\n"));
  const Model& m = h.session.model();
  const Wall& platen = m.walls[2];
  CHECK(platen.contacts > 5);
  // Over the last 5000 cycles the stress stays within 1% of the target on average, 3% at most
  // (measured: 0.2% and 1%).
  const auto& rows = h.session.history().tables().at(0)->rows;
  REQUIRE(rows.size() == 50);
  double sum = 0, worst = 0;
  for (const auto& r : rows) {
    sum += r[5];
    worst = std::max(worst, std::abs(r[5] - 5000));
  }
  CHECK(sum / rows.size() == Approx(5000).epsilon(0.01));
  CHECK(worst < 0.03 * 5000);
  // The floor carries the platen's load and the weight, less what friction hangs on the cylinder
  // (its share depends on the packing: 3% to 6% measured): the balls at rest balance the three walls'
  // forces and their weight, to 1% (their accelerations under the servo; measured 0.1%).
  double weight = 0;
  for (double mass : m.balls.mass) weight += mass * 9.81;
  CHECK(-m.walls[0].force[2] < platen.force[2] + weight);
  CHECK(-m.walls[0].force[2] == Approx(platen.force[2] + m.walls[1].force[2] + weight).epsilon(0.01));
}

TEST_CASE("walls: bad WALL and SERVO wall input is an error that says what is wrong", "[walls][hard]") {
  struct Case { const char* lines; const char* expected; };
  const Case cases[] = {
      {"start 1 1 1\nwall plane 0 0 0 0 0 1\n", "walls need a free region"},
      {"wall polygon 0 0 0 1 0 0 2 0 0\n", "on a line"},
      {"wall polygon 0 0 0 1 0 0\n", "at least 3 vertices"},
      {"wall polygon 0 0 0 1 0 0 1 1 0 0 1\n", "vertex"},
      {"wall plane 0 0 0 0 0 0\n", "normal is zero"},
      {"wall cylinder 0 0 0 0 0 1 radius 0 length 1\n", "radius must be positive"},
      {"wall cylinder 0 0 0 0 0 1 radius 1\n", "length"},
      {"wall plane 0 0 0 0 0 1\nwall id 1 plane 0 0 1 0 0 -1\n", "wall id 1 is taken"},
      {"wall id 4 velocity 1 0 0\n", "there is no wall 4"},
      {"wall plane 0 0 0 0 0 1 rrate 1\n", "for cylinders"},
      {"wall plane 0 0 0 0 0 1 velocity 1e999 0 0\n", "out of range"},
      {"wall polygon 0 0 0 1e999 0 0 1 1 0\n", "vertex x is out of range"},
      {"wall plane 0 0 0 0 0 1\nservo wall 1 stress 100\n", "give `area a`"},
      {"servo wall 2 stress 100\n", "there is no wall 2"},
      {"wall plane 0 0 0 0 0 1\nhist wall 7\n", "there is no wall 7"},
  };
  for (const Case& c : cases) {
    INFO(c.lines);
    Harness h;
    CHECK_FALSE(h.deck(std::string("start box -1 1 -1 1 -1 1\nprop kn 1 dens 1\n") + c.lines));
    CHECK_THAT(h.first_error_line(), Catch::Contains(c.expected));
    CHECK_THAT(h.first_error_line(), Catch::StartsWith("deck.dat:"));
  }
}

TEST_CASE("walls: a platen's area is its cylinder's cross-section, the cylinder's its radius times the platens' gap", "[walls]") {
  Harness h;
  REQUIRE(h.deck("start box -1 1 -1 1 -1 1\nprop kn 1 dens 1\nwall id 1 plane 0 0 0 0 0 1\n"
                 "wall id 2 plane 0 0 0.3 0 0 -1\nwall id 3 cylinder 0 0 -0.1 0 0 1 radius 0.2 length 0.5\n"
                 "servo wall 1 stress 10 in 3\nservo wall 3 stress 10 between 1 2\n"));
  const Model& m = h.session.model();
  CHECK(wall_servo_area(m, m.walls[0]) == Approx(kPi * 0.04));
  CHECK(wall_servo_area(m, m.walls[2]) == Approx(2 * kPi * 0.2 * 0.3));
  // The areas follow the walls: the platen moves, the cylinder's radius changes.
  REQUIRE(h.deck("servo wall 1 off\nservo wall 3 off\nwall id 2 velocity 0 0 -1\nwall id 3 rrate 0.5\n"
                 "ball 0 0 0.5 0.01\ntstep 0.01\ncycle 10\n"));
  CHECK(wall_servo_area(m, m.walls[0]) == Approx(kPi * 0.25 * 0.25));
  CHECK(wall_servo_area(m, m.walls[2]) == Approx(2 * kPi * 0.25 * 0.2));
  Harness bad;
  CHECK_FALSE(bad.deck("start box -1 1 -1 1 -1 1\nprop kn 1 dens 1\nwall id 1 plane 0 0 0 0 0 1\n"
                       "wall id 2 plane 0 0 0.3 0 0 -1\nservo wall 1 stress 10 in 2\n"));
  CHECK_THAT(bad.first_error_line(), Catch::Contains("names a cylinder"));
}

TEST_CASE("walls: a ball held still by FIX is a partner of infinite mass, as a wall is", "[walls]") {
  // PROP rest 0.5 against a ball fixed in every velocity component rebounds at 0.5 (it was 0.601
  // while m* took the fixed ball's mass), and at the same speed as off a plane.
  double rebound[2] = {0, 0};
  for (int k = 0; k < 2; ++k) {
    Harness h;
    const std::string target = k == 0 ? "ball 0 0 0 0.1 id 2\nfix vel spin range id 2\n" : "wall plane 0 0 0.1 0 0 1\n";
    REQUIRE(h.deck("start box -1 1 -1 1 -1 2\nprop kn 1e6 ks 1e6 dens 1000 rest 0.5\nball 0 0 0.25 0.1 id 1\n" + target +
                   "init zvel -1 range id 1\nfrac 0.02\ncycle 20000\n"));
    rebound[k] = h.session.model().balls.vz[trubal::test::at(h.session.model(), 1)];
  }
  CHECK(rebound[0] == Approx(0.5).epsilon(0.005));
  CHECK(rebound[0] == Approx(rebound[1]).epsilon(1e-6));
}

TEST_CASE("walls: adding or deleting a wall keeps the wall contacts consistent, so SAVE and RESTART work", "[walls]") {
  // A wall of a lower id inserted before one with contacts (its index moves up), then that wall
  // deleted: each state saves and restarts, and the contact's history is the wall's, not another's.
  TempDir dir;
  WorkingDir wd(dir.path());
  Harness h;
  REQUIRE(h.deck("start box -1 1 -1 1 -1 2\nprop kn 1e6 ks 1e6 dens 1000 fric 0.5\nball 0 0 0.0999 0.1\n"
                 "init xvel 0.01\nwall id 5 plane 0 0 0 0 0 1\ngrav 0 0 -10\ncycle 10\n"
                 "wall id 1 plane 0 0 1.5 0 0 -1\nsave a.sav\nrestart a.sav\n"));
  const WallContacts& c = h.session.model().wall_contacts;
  REQUIRE(c.size() == 1);
  CHECK(c.wall_id[0] == 5);
  CHECK(h.session.model().walls[c.wall[0]].id == 5);
  CHECK(c.fsx[0] != 0);   // the sliding ball's shear history came through
  REQUIRE(h.deck("cycle 5\nwall id 1 delete\nsave b.sav\nrestart b.sav\nwall id 5 delete\nsave c.sav\nrestart c.sav\n"));
  CHECK(h.session.model().wall_contacts.size() == 0);
}

TEST_CASE("walls: balls of one type beside walls of another take the one-law kernel with the same bits", "[walls]") {
  // Where every ball is of one type the contact loops take the ball pairs' law once
  // (PairLaws::ball_pair_law) rather than per pair; a second type among the balls (one held ball far
  // from the rest, touching nothing) sends the same pairs through the per-pair lookup. The two must
  // agree to the bit: the same law, the same arithmetic.
  auto run = [](const std::string& extra) {
    TempDir dir;
    WorkingDir cd(dir.path());
    Harness h;
    // The balls of type 3 (the third law of the table's row and column), of their own friction.
    std::string deck = test::scrambled_settle_deck();
    for (std::size_t at = 0; (at = deck.find(" 20 id ", at)) != std::string::npos; at += 10) deck.replace(at, 7, " 20 type 3 id ");
    const bool ok = h.deck(deck + "prop type 3 kn 1.5e9 ks 1.2e9 fric 25 dens 2000\ntstep 0.02\n" + extra +
                           "cycle 400\nprint balls file balls.csv range id 1 384\nprint contacts file contacts.csv\n");
    INFO(h.err.str());
    REQUIRE(ok);
    return std::pair{slurp("balls.csv"), slurp("contacts.csv")};
  };
  const auto one = run("");
  const auto two = run("ball 150 150 390 5 id 1000 type 1\nfix vel spin range id 1000\n");
  REQUIRE(lines_of(one.second).size() > 500);
  CHECK(one.first == two.first);
  CHECK(one.second == two.second);
}
