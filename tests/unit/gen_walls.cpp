// GEN and BALL against walls: GEN places balls only where they touch no wall and lie on its side
// (every mode: n balls, a size distribution, a porosity), a porosity in a cylinder region is met
// against the cylinder's volume, the region's volume is integrated to its stated accuracy, and BALL
// across a wall warns.
#include <catch2/catch.hpp>

#include <fmt/format.h>

#include <cmath>
#include <numbers>

#include "gen/region.hpp"
#include "interp_support.hpp"
#include "model/wall_shape.hpp"

using namespace trubal;
using trubal::test::Harness;

namespace {

constexpr double kPi = std::numbers::pi;

double solid_volume(const Model& m) {
  double v = 0;
  for (double r : m.balls.rad) v += 4.0 / 3.0 * kPi * r * r * r;
  return v;
}

// The smallest gap from a ball's surface to a wall over every ball and wall (negative: one crosses a
// wall or lies on its wrong side), with the ball that has it.
struct Worst { double gap = INFINITY; std::int64_t ball = 0, wall = 0; };
Worst worst_wall_gap(const Model& m) {
  Worst w;
  const Balls& b = m.balls;
  for (std::size_t k = 0; k < b.size(); ++k)
    for (const Wall& wall : m.walls) {
      const double gap = wall_clearance(wall, {b.x[k], b.y[k], b.z[k]}, b.rad[k]).gap;
      if (gap < w.gap) w = {gap, b.id[k], wall.id};
    }
  return w;
}

// A box of 0.1 with a floor plane at z = 0; the box reaches 0.01 below it (the scene).
const char* kFloorBox = "start box -0.05 0.05 -0.05 0.05 -0.01 0.1\nprop kn 1e5 ks 1e5 fric 20 dens 2650\n"
                        "wall id 1 plane 0 0 0 0 0 1\n";

// A container cylinder of radius 0.02 from z = -0.005 to 0.105 between a floor at 0 and a lid at 0.1,
// in a box far wider than it (as examples/triaxial_walls.dat).
const char* kContainer = "start box -0.05 0.05 -0.05 0.05 -0.01 0.11\nprop kn 1e5 ks 1e5 fric 20 dens 2650\n"
                         "wall id 1 plane 0 0 0 0 0 1\nwall id 2 plane 0 0 0.1 0 0 -1\n"
                         "wall id 3 cylinder 0 0 -0.005 0 0 1 radius 0.02 length 0.11\n";

}  // namespace

TEST_CASE("gen walls: GEN in a box with a floor plane puts no ball across it, and CYCLE loses none", "[gen][walls]") {
  for (const char* gen : {"gen 100 0.004 0.006 seed 1", "gen 100 psd uniform 0.004 0.006 seed 1",
                          "gen porosity 0.6 0.004 0.006 seed 1"}) {
    INFO(gen);
    Harness h;
    REQUIRE(h.deck(std::string(kFloorBox) + gen + "\n"));
    const Model& m = h.session.model();
    REQUIRE(m.balls.size() >= 100);
    // Every ball above the floor by at least its radius (the old GEN put about one in ten below it:
    // the box starts 0.01 under the floor).
    const Worst w = worst_wall_gap(m);
    INFO("ball " << w.ball << " gap " << w.gap);
    CHECK(w.gap >= 0);
    // Under gravity none goes through the floor and out of the box (the old GEN's balls behind the
    // floor fell out of it: "ball .. left the box through z = -0.01").
    REQUIRE(h.deck("grav 0 0 -9.81\ndamp local 0.7\ncycle 500\n"));
    CHECK(h.err.str().find("left the box") == std::string::npos);
    CHECK(h.session.model().balls.size() == m.balls.size());
  }
}

TEST_CASE("gen walls: every ball GEN puts in a container cylinder lies within its radius less the ball's of the axis",
          "[gen][walls]") {
  for (const char* gen : {"gen 300 0.002 0.003 seed 4", "gen 300 psd volume 0.002 0.003 seed 4",
                          "gen porosity 0.5 0.002 0.003 seed 4"}) {
    INFO(gen);
    Harness h;
    REQUIRE(h.deck(std::string(kContainer) + gen + "\n"));
    INFO(h.out.str());
    const Balls& b = h.session.model().balls;
    REQUIRE(b.size() >= 300);
    for (std::size_t k = 0; k < b.size(); ++k) {
      const double rho = std::hypot(b.x[k], b.y[k]);
      INFO("ball " << b.id[k] << " at (" << b.x[k] << ", " << b.y[k] << ", " << b.z[k] << ") radius " << b.rad[k]);
      CHECK(rho <= 0.02 - b.rad[k]);
      CHECK(b.z[k] >= b.rad[k]);
      CHECK(b.z[k] <= 0.1 - b.rad[k]);
    }
    CHECK(worst_wall_gap(h.session.model()).gap >= 0);
  }
  // The porosity is that of the cylinder between the floor and the lid, pi r^2 h, not of the box: to
  // 3e-4, the volume's integration (1e-4 of it, region.hpp) and the print's four digits.
  Harness h;
  REQUIRE(h.deck(std::string(kContainer) + "gen porosity 0.5 0.002 0.003 seed 4\n"));
  const double cylinder = kPi * 0.02 * 0.02 * 0.1;
  CHECK(1 - solid_volume(h.session.model()) / cylinder == Approx(0.5).margin(3e-4));
  CHECK_THAT(h.out.str(), Catch::Contains("porosity 0.5000"));
}

TEST_CASE("gen walls: GEN porosity in a cylinder region reaches the porosity asked", "[gen][walls]") {
  // `range cylinder x y r z z0 z1`: whole balls within r of the line (0.01, 0) and between z0 and z1
  // (a cylinder ten diameters across reaches about 0.43 here, a box of its size 0.42).
  Harness h;
  REQUIRE(h.deck("start box -0.05 0.05 -0.05 0.05 0 0.1\n"
                 "gen porosity 0.45 psd uniform 0.0015 0.0025 seed 6 range cylinder 0.01 0 0.02 z 0.01 0.05\n"));
  INFO(h.out.str());
  const Balls& b = h.session.model().balls;
  REQUIRE(b.size() > 300);
  // The solid volume is scaled to the porosity of the cylinder's volume as integrated (to 1e-4 of it,
  // region.hpp): against the exact pi r^2 h, 1e-4 of the porosity's 1 - p (6e-5) and rounding.
  const double cylinder = kPi * 0.02 * 0.02 * 0.04;
  CHECK(1 - solid_volume(h.session.model()) / cylinder == Approx(0.45).margin(1e-4));
  CHECK_THAT(h.out.str(), Catch::Contains("porosity 0.4500"));
  for (std::size_t k = 0; k < b.size(); ++k) {
    CHECK(std::hypot(b.x[k] - 0.01, b.y[k]) <= 0.02 - b.rad[k]);
    CHECK(b.z[k] - b.rad[k] >= 0.01);
    CHECK(b.z[k] + b.rad[k] <= 0.05);
  }
}

TEST_CASE("gen walls: the region's volume, integrated, against closed forms", "[gen][walls]") {
  Region g;
  g.lo = {-0.05, -0.05, -0.01};
  g.hi = {0.05, 0.05, 0.11};
  g.bounded = {true, true, true};
  Wall floor, lid, tube;
  floor.point = {0, 0, 0};
  floor.normal = {0, 0, 1};
  lid.point = {0, 0, 0.1};
  lid.normal = {0, 0, -1};
  tube.kind = WallKind::Cylinder;
  tube.point = {0.003, -0.002, -0.005};
  tube.normal = {0, 0, 1};
  tube.radius = 0.02;
  tube.length = 0.11;
  // Planes across an axis cut the box exactly.
  g.walls = {floor, lid};
  CHECK(g.volume() == Approx(0.1 * 0.1 * 0.1).epsilon(1e-15));
  // A container between them: pi r^2 h to 1e-4 (region.hpp; measured 1e-6).
  g.walls = {floor, lid, tube};
  CHECK(g.volume() == Approx(kPi * 0.0004 * 0.1).epsilon(1e-4));
  // The same tube holding balls outside: the box less it.
  g.walls[2].inside = false;
  CHECK(g.volume() == Approx(0.1 * 0.1 * 0.1 - kPi * 0.0004 * 0.1).epsilon(1e-4));
  // A tilted container (axis along (1, 0, 1)) wholly in the box: pi r^2 l. Its ends are cut across the
  // lines, so this one is cut along both its ends and its side (measured 3e-6).
  Region t;
  t.lo = {-1, -1, -1};
  t.hi = {1, 1, 1};
  t.bounded = {true, true, true};
  Wall tilted = tube;
  tilted.point = {-0.3, 0.1, -0.3};
  tilted.normal = {std::sqrt(0.5), 0, std::sqrt(0.5)};
  tilted.radius = 0.2;
  tilted.length = 0.8;
  t.walls = {tilted};
  CHECK(t.volume() == Approx(kPi * 0.04 * 0.8).epsilon(1e-4));
  // A tilted plane through the box's centre halves it.
  Wall slope;
  slope.point = {0, 0, 0};
  slope.normal = {std::sqrt(0.5), 0, std::sqrt(0.5)};
  t.walls = {slope};
  CHECK(t.volume() == Approx(4.0).epsilon(1e-6));
  // The range's cylinder (about a line along z) cut by the box's faces.
  Region c;
  c.lo = {0, -1, 0};
  c.hi = {1, 1, 2};
  c.bounded = {true, true, true};
  c.cylinders = {{0, 0, 0.5}};   // half of it in the box
  CHECK(c.volume() == Approx(0.5 * kPi * 0.25 * 2).epsilon(1e-4));
}

TEST_CASE("gen walls: BALL across a wall or on its wrong side is placed with a warning naming the ball, wall and gap",
          "[gen][walls]") {
  Harness h;
  REQUIRE(h.deck(std::string(kContainer) +
                 "ball 0 0 0.005 0.004 id 1\n"          // clear: resting 0.001 above the floor
                 "ball 0.005 0 0.002 0.004 id 2\n"      // across the floor
                 "ball 0 0.005 -0.006 0.004 id 3\n"     // behind the floor
                 "ball 0.019 0 0.05 0.002 id 4\n"       // across the cylinder
                 "ball 0.03 0 0.05 0.002 id 5\n"        // outside the cylinder
                 "ball 0 0 0.107 0.001 id 6\n"));       // past the cylinder's top end (and behind the lid)
  CHECK(h.session.model().balls.size() == 6);            // all placed as asked
  const std::string err = h.err.str();
  INFO(err);
  CHECK(err.find("ball 1 ") == std::string::npos);
  CHECK_THAT(err, Catch::Contains("deck.dat:7: warning: BALL: ball 2 crosses wall 1 (plane): the gap from its surface "
                                  "to the wall is -0.002 (radius 0.004); placed as asked"));
  CHECK_THAT(err, Catch::Contains("deck.dat:8: warning: BALL: ball 3 lies behind wall 1 (plane; balls belong on the "
                                  "side its normal points to): the gap from its surface to the wall is -0.01 (radius "
                                  "0.004); placed as asked"));
  CHECK_THAT(err, Catch::Contains("BALL: ball 4 crosses wall 3 (cylinder): the gap from its surface to the wall is "
                                  "-0.001 (radius 0.002)"));
  CHECK_THAT(err, Catch::Contains("BALL: ball 5 lies outside wall 3 (cylinder, balls inside): the gap from its "
                                  "surface to the wall is -0.012 (radius 0.002)"));
  CHECK_THAT(err, Catch::Contains("BALL: ball 6 lies behind wall 2 (plane"));
  CHECK_THAT(err, Catch::Contains("BALL: ball 6 lies beyond an end of wall 3 (cylinder, balls inside), its centre "
                                  "0.002 past it"));
}

TEST_CASE("gen walls: GEN between walls gives the same balls on every backend and thread count", "[gen][walls][threads]") {
  trubal::test::TempDir dir;
  std::string first;
  for (const char* backend : {"serial", "threaded threads 2", "allpairs"}) {
    Harness h;
    const std::string file = fmt::format("{}/b.csv", dir.str());
    REQUIRE(h.deck(fmt::format("backend {}\n{}gen porosity 0.5 psd uniform 0.003 0.004 seed 2\nprint balls file {}\n",
                               backend, kContainer, file)));
    const std::string text = trubal::test::slurp(file);
    REQUIRE(text.size() > 1000);
    if (first.empty()) first = text;
    else CHECK(text == first);   // byte for byte
  }
}
