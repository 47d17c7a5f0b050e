// SAMPLE: the measures of a sample held by walls (physics/sample.hpp) against their closed forms,
// CYCLE ... until, and the sample's place in SAVE, RESTART and WALL delete.
#include <catch2/catch.hpp>

#include <cmath>
#include <numbers>
#include <string>

#include <fmt/format.h>

#include "interp_support.hpp"
#include "io/save.hpp"
#include "physics/sample.hpp"
#include "physics/walls.hpp"

using namespace trubal;
using namespace trubal::test;

namespace {

constexpr double kPi = std::numbers::pi;

// One ball of radius 0.26 held at the middle of a sample 0.5 high in a cylinder of radius 0.25:
// it presses each platen and the cylinder by 0.01.
const char* kPressed =
    "start box -1 1 -1 1 -1 1\n"
    "prop kn 1e6 ks 1e6 fric 0 dens 1000\n"
    "wall id 1 plane 0 0 0 0 0 1\n"
    "wall id 2 plane 0 0 0.5 0 0 -1\n"
    "wall id 3 cylinder 0 0 -0.1 0 0 1 radius 0.25 length 0.7\n"
    "ball 0 0 0.25 0.26\n"
    "fix xvel yvel zvel xspin yspin zspin\n"
    "tstep 1e-4\n";

}  // namespace

TEST_CASE("sample: sigma1, sigma3, q and p of a ball pressing the platens and the cylinder are the closed forms", "[commands][sample]") {
  Harness h;
  REQUIRE(h.deck(std::string(kPressed) + "sample platens 1 2 cylinder 3\ncycle 1\n"));
  const Model& m = h.session.model();
  // A linear contact with a wall has the ball's kn (same type): each carries kn 0.01 = 1e4 N.
  const double force = 1e6 * 0.01;
  REQUIRE(m.walls[0].normal_force == Approx(force).epsilon(1e-12));
  const SampleMeasures s = sample_measures(m);
  // sigma1: the platens' force over pi r^2; sigma3: the cylinder's over 2 pi r h. The relative
  // tolerance is rounding (the overlap 0.01 is the difference of numbers near 0.25).
  const double sigma1 = force / (kPi * 0.25 * 0.25), sigma3 = force / (2 * kPi * 0.25 * 0.5);
  CHECK(s.height == Approx(0.5).epsilon(1e-15));
  CHECK(s.area == Approx(kPi * 0.0625).epsilon(1e-15));
  CHECK(s.sigma1 == Approx(sigma1).epsilon(1e-12));
  CHECK(s.sigma3 == Approx(sigma3).epsilon(1e-12));
  CHECK(s.q == Approx(sigma1 - sigma3).epsilon(1e-12));
  CHECK(s.p == Approx((sigma1 + 2 * sigma3) / 3).epsilon(1e-12));
  CHECK(s.axial == 0);
  CHECK(s.volumetric == 0);
  // PRINT sample says the same.
  h.out.str("");
  REQUIRE(h.deck("print sample\n"));
  CHECK_THAT(h.out.str(), Catch::Contains(fmt::format("sigma1 {:.6g}, sigma3 {:.6g}", sigma1, sigma3)));
}

TEST_CASE("sample: four sides give sigma3 as the mean of the two pairs' stresses", "[commands][sample]") {
  // The ball of radius 0.26 in a box of sides 0.5 (x) by 0.6 (y), 0.5 high: it presses the platens
  // and the x sides by 0.01 and misses the y sides (0.3 away).
  Harness h;
  REQUIRE(h.deck("start box -1 1 -1 1 -1 1\nprop kn 1e6 ks 1e6 fric 0 dens 1000\n"
                 "wall id 1 plane 0 0 0 0 0 1\nwall id 2 plane 0 0 0.5 0 0 -1\n"
                 "wall id 3 plane -0.25 0 0 1 0 0\nwall id 4 plane 0.25 0 0 -1 0 0\n"
                 "wall id 5 plane 0 -0.3 0 0 1 0\nwall id 6 plane 0 0.3 0 0 -1 0\n"
                 "ball 0 0 0.25 0.26\nfix xvel yvel zvel xspin yspin zspin\n"
                 "sample platens 1 2 sides 3 4 5 6\ncycle 1\n"));
  const SampleMeasures s = sample_measures(h.session.model());
  const double force = 1e4;
  CHECK(s.area == Approx(0.5 * 0.6).epsilon(1e-15));
  CHECK(s.sigma1 == Approx(force / 0.3).epsilon(1e-12));
  // x sides: their force over 0.6 x 0.5; y sides: nothing. sigma3 their mean.
  CHECK(s.sigma3 == Approx(0.5 * force / (0.6 * 0.5)).epsilon(1e-12));
}

TEST_CASE("sample: the axial and volumetric strains follow the platens and the cylinder's radius", "[commands][sample]") {
  // The top platen moves down at 0.1 m/s and the cylinder's radius grows at 0.02 m/s, for 1000 steps
  // of 1e-4 s: h = 0.5 - 0.01, r = 0.2 + 0.002. (A small ball sits free in the middle.)
  Harness h;
  REQUIRE(h.deck("start box -1 1 -1 1 -1 1\nprop kn 1e6 ks 1e6 fric 0 dens 1000\n"
                 "wall id 1 plane 0 0 0 0 0 1\nwall id 2 plane 0 0 0.5 0 0 -1\n"
                 "wall id 3 cylinder 0 0 -0.1 0 0 1 radius 0.2 length 0.7\n"
                 "ball 0 0 0.25 0.01\ntstep 1e-4\n"
                 "sample platens 1 2 cylinder 3\n"
                 "wall id 2 velocity 0 0 -0.1\nwall id 3 rrate 0.02\n"
                 "hist sample every 500\ncycle 1000\n"));
  const SampleMeasures s = sample_measures(h.session.model());
  const double h1 = 0.49, r1 = 0.202;
  // Tolerance: the walls' positions are sums of 1000 steps' moves (rounding, about 1e-16 each).
  CHECK(s.axial == Approx(1 - h1 / 0.5).epsilon(1e-10));
  CHECK(s.volumetric == Approx(1 - (r1 * r1 * h1) / (0.2 * 0.2 * 0.5)).epsilon(1e-10));
  // HIST sample recorded the same numbers at cycle 1000 (its columns ea ev sig1 sig3 q p).
  const auto& t = *h.session.history().tables().at(0);
  REQUIRE(t.columns == std::vector<std::string>{"cycle", "time", "ea", "ev", "sig1", "sig3", "q", "p"});
  REQUIRE(t.rows.size() == 2);   // cycles 500 and 1000
  CHECK(t.rows[1][2] == s.axial);
  CHECK(t.rows[1][3] == s.volumetric);
  // SAMPLE reset takes the present as the reference.
  REQUIRE(h.deck("sample reset\n"));
  CHECK(sample_measures(h.session.model()).axial == 0);
  CHECK(sample_measures(h.session.model()).volumetric == 0);
}

TEST_CASE("sample: CYCLE until axial stops at the first check past the target, with the bits of a plain CYCLE", "[commands][sample]") {
  // The top platen approaches at 0.1 m/s, 1e-4 s a step: the axial strain is 2e-5 a step, so 0.1001
  // is passed at step 5005 and found at the first check after it, every 10 cycles: 5010.
  const std::string scene =
      "start box -1 1 -1 1 -1 1\nprop kn 1e6 ks 1e6 fric 0.3 dens 1000\n"
      "wall id 1 plane 0 0 0 0 0 1\nwall id 2 plane 0 0 0.5 0 0 -1\n"
      "wall id 3 cylinder 0 0 -0.1 0 0 1 radius 0.2 length 0.7\n"
      "gen 20 0.02 0.03 seed 3 range cylinder 0 0 0.15 z 0.05 0.45\n"
      "init xvel 0.5 yvel -0.3 zvel 0.2\ntstep 1e-4\n"
      "sample platens 1 2 cylinder 3\nwall id 2 velocity 0 0 -0.1\n";
  Harness until, plain;
  REQUIRE(until.deck(scene + "cycle 20000 until axial 0.1001 every 10\n"));
  CHECK(until.session.state().cycle == 5010);
  CHECK_THAT(until.out.str(), Catch::Contains("reached axial 0.1002"));
  REQUIRE(plain.deck(scene + "cycle 5010\n"));
  const Balls& a = until.session.model().balls;
  const Balls& b = plain.session.model().balls;
  CHECK(a.x == b.x);
  CHECK(a.vz == b.vz);
  CHECK(a.wy == b.wy);
  // Already there (a positive target is reached at or above it): no cycle.
  REQUIRE(until.deck("cycle until axial 0.05\n"));
  CHECK(until.session.state().cycle == 5010);
  CHECK_THAT(until.out.str(), Catch::Contains("reached axial 0.1002 (target 0.05"));
}

TEST_CASE("sample: CYCLE until stops where nothing moves the measure, or it moves away, with a warning", "[commands][sample]") {
  const std::string scene = std::string(kPressed) + "sample platens 1 2 cylinder 3\n";
  Harness still;
  REQUIRE(still.deck(scene + "cycle until axial 0.1\n"));
  // Ten checks, 100 cycles apart, with the platens still.
  CHECK(still.session.state().cycle == 1000);
  CHECK_THAT(still.err.str(), Catch::Contains("axial stayed at 0") && Catch::Contains("nothing moves it"));
  Harness away;
  REQUIRE(away.deck(scene + "wall id 2 velocity 0 0 -0.01\ncycle until axial -0.1\n"));
  CHECK(away.session.state().cycle == 1000);
  CHECK_THAT(away.err.str(), Catch::Contains("away from the target -0.1"));
  // A limit that comes first says so.
  Harness limit;
  REQUIRE(limit.deck(scene + "wall id 2 velocity 0 0 -0.01\ncycle 300 until axial 0.1\n"));
  CHECK(limit.session.state().cycle == 300);
  CHECK_THAT(limit.err.str(), Catch::Contains("limit of 300 cycles"));
}

TEST_CASE("sample: CYCLE until in a periodic cell reads the cell's strain", "[commands][sample]") {
  Harness h;
  REQUIRE(h.deck("start 1 1 1\nprop kn 1e6 ks 1e6 fric 0.3 dens 1000\nball 0.5 0.5 0.5 0.1\ntstep 1e-3\n"
                 "strain 0 0 1\ncycle until axial 0.05 every 1\n"));
  // The rate 1 /s over 1e-3 s steps: 0.05 after 50 steps (the first check at or past it).
  CHECK(std::abs(h.session.state().cycle - 50) <= 1);
  CHECK(h.session.state().space.strain[2] >= 0.05);
}

TEST_CASE("sample: bad SAMPLE and HIST sample lines are errors that say what is wrong", "[commands][sample]") {
  Harness h;
  REQUIRE(h.deck(kPressed));
  CHECK_FALSE(h.deck("sample platens 1 1 cylinder 3\n"));
  CHECK_THAT(h.err.str(), Catch::Contains("one wall"));
  CHECK_FALSE(h.deck("sample platens 1 3 cylinder 2\n"));
  CHECK_THAT(h.err.str(), Catch::Contains("not a cylinder"));
  CHECK_FALSE(h.deck("sample platens 1 2 cylinder 7\n"));
  CHECK_THAT(h.err.str(), Catch::Contains("there is no wall 7"));
  CHECK_FALSE(h.deck("hist sample\n"));
  CHECK_THAT(h.err.str(), Catch::Contains("declare it first"));
  CHECK_FALSE(h.deck("cycle until q 100\n"));
  CHECK_THAT(h.err.str(), Catch::Contains("declare it first"));
  CHECK_FALSE(h.deck("sample reset\n"));
  // Tilted platens do not face each other.
  Harness tilted;
  REQUIRE(tilted.deck("start box -1 1 -1 1 -1 1\nwall id 1 plane 0 0 0 0 0 1\nwall id 2 plane 0 0 0.5 0 0.1 -1\n"
                      "wall id 3 cylinder 0 0 -0.1 0 0 1 radius 0.25 length 0.7\n"));
  CHECK_FALSE(tilted.deck("sample platens 1 2 cylinder 3\n"));
  CHECK_THAT(tilted.err.str(), Catch::Contains("do not face each other"));
}

TEST_CASE("sample: SAVE and RESTART keep the sample and the walls a servo's area comes from", "[commands][sample]") {
  TempDir dir;
  const std::string path = (dir.path() / "s.sav").string();
  // A servo on the top platen `in 3` (its area pi r^2 of the cylinder): the run cut by SAVE and
  // RESTART gives the uncut run's bits, which needs the area after RESTART.
  const std::string scene =
      "start box -1 1 -1 1 -1 1\nprop kn 1e6 ks 1e6 fric 0.3 dens 1000\n"
      "wall id 1 plane 0 0 0 0 0 1\nwall id 2 plane 0 0 0.3 0 0 -1\n"
      "wall id 3 cylinder 0 0 -0.1 0 0 1 radius 0.2 length 0.7\n"
      "gen 30 0.03 0.04 seed 5 range cylinder 0 0 0.15 z 0.05 0.25\n"
      "sample platens 1 2 cylinder 3\nservo wall 2 stress 1e4 in 3 max 0.05\n";
  Harness cut, whole;
  REQUIRE(cut.deck(scene + "cycle 500\nsave " + path + "\nstart box 0 1 0 1 0 1\nrestart " + path + "\ncycle 500\n"));
  REQUIRE(whole.deck(scene + "cycle 1000\n"));
  const Model& a = cut.session.model();
  const Model& b = whole.session.model();
  CHECK(a.sample.platens == b.sample.platens);
  CHECK(a.sample.sides == b.sample.sides);
  CHECK(a.sample.height0 == b.sample.height0);
  CHECK(a.walls[1].area_walls == b.walls[1].area_walls);
  CHECK(a.walls[1].point == b.walls[1].point);
  CHECK(a.balls.z == b.balls.z);
  CHECK(sample_measures(a).sigma1 == sample_measures(b).sigma1);
}

TEST_CASE("sample: WALL delete drops the sample it belonged to, and refuses a wall a servo's area comes from", "[commands][sample]") {
  Harness h;
  REQUIRE(h.deck(std::string(kPressed) + "sample platens 1 2 cylinder 3\nservo wall 2 stress 1e4 in 3\n"));
  CHECK_FALSE(h.deck("wall id 3 delete\n"));
  CHECK_THAT(h.err.str(), Catch::Contains("SERVO wall 2 off first"));
  REQUIRE(h.deck("servo wall 2 off\nwall id 3 delete\n"));
  CHECK_THAT(h.out.str(), Catch::Contains("the sample (SAMPLE) is gone"));
  CHECK_FALSE(h.session.model().sample.declared());
  CHECK(h.session.model().walls[1].area_walls[0] == 0);
}

TEST_CASE("sample: a save of format 7 restarts without the sample, and a servo whose area it lost stands still", "[commands][sample]") {
  TempDir dir;
  WorkingDir cd(dir.path());
  Harness h;
  REQUIRE(h.deck("start box -1 1 -1 1 -1 1\nprop kn 1e6 ks 1e6 fric 0.3 dens 1000\n"
                 "wall id 1 plane 0 0 0 0 0 1\nwall id 2 plane 0 0 0.3 0 0 -1\n"
                 "wall id 3 cylinder 0 0 -0.1 0 0 1 radius 0.2 length 0.7\n"
                 "gen 30 0.03 0.04 seed 5 range cylinder 0 0 0.15 z 0.05 0.25\n"
                 "sample platens 1 2 cylinder 3\nservo wall 2 stress 1e4 in 3 max 0.05\ncycle 200\n"));
  save_model(h.session.model(), "old.sav", &h.session.history(), 7);
  Harness old;
  REQUIRE(old.deck("start box -1 1 -1 1 -1 1\nrestart old.sav\n"));
  CHECK_FALSE(old.session.model().sample.declared());
  CHECK(old.session.model().walls[1].area_walls[0] == 0);
  const double before = old.session.model().walls[1].point[2];
  // The servo cannot measure a stress without its area: the platen stands (no NaN, no drift).
  REQUIRE(old.deck("cycle 100\n"));
  CHECK(old.session.model().walls[1].point[2] == before);
}
