// Limits a deck from someone else cannot pass (issue 50): the servo's max rate and a radius beyond
// the periodic cell. Each case hung before.
#include "paths.hpp"
#include <catch2/catch.hpp>

#include <fmt/format.h>

#include "gen/placement_grid.hpp"
#include "interp_support.hpp"
#include "model/periodic_cell.hpp"

using namespace trubal;
using namespace trubal::test;

namespace {

std::string deck_error(const std::string& deck) {
  Harness h;
  const bool ok = h.deck(deck);
  INFO("stderr:\n" << h.err.str().substr(0, 2000));
  CHECK_FALSE(ok);
  return h.first_error_line();
}

}  // namespace

TEST_CASE("limits: the tilt reduction takes any number of edges off at once", "[limits]") {
  // A tilt of 1e30 edges: one edge at a time, tilt - L rounds to tilt and the loop never ended.
  Model m;
  m.space.periodic = true;
  m.space.lo = {0, 0, 0};
  m.space.hi = {1, 1, 1};
  m.space.tilt = {1e30, -3.7e20, 2.25};
  CHECK(reduce_cell_tilt(m));
  for (double t : m.space.tilt) CHECK(std::abs(t) <= 0.5);
  // One edge, as the old loop took it, to the bit: 0.75 - 1 = -0.25.
  m.space.tilt = {0.75, 0, 0};
  CHECK(reduce_cell_tilt(m));
  CHECK(m.space.tilt[0] == -0.25);
  // A cell of no length reduces nothing (CYCLE refuses such a cell elsewhere), and returns.
  m.space.hi = {0, 1, 1};
  m.space.tilt = {1, 1, 0};
  CHECK_FALSE(reduce_cell_tilt(m));
}

TEST_CASE("limits: SERVO refuses a max rate beyond STRAIN's half an edge a step", "[limits]") {
  const std::string scene = "start 0.01 0.01 0.01\nprop kn 1e5 ks 1e5 fric 26.57 dens 2650\ngen 60 0.0008 0.0012 seed 7\n"
                            "damp local 0.7\nservo 1e4 1e4 1e4\n";
  // The step is not known yet: CYCLE refuses before its first step, the model as it was.
  const auto before = deck_error(scene + "servo 1e4 1e4 1e4 max 1e9\ncycle 3\n");
  CHECK(before.starts_with("deck.dat:7: error: SERVO max rate 1e+09 would change a cell edge by "));
  CHECK(before.find("lower SERVO max (at most ") != std::string::npos);
  // After a CYCLE the step is known: SERVO itself refuses (this deck, sheared, hung in the tilt reduction).
  const auto after = deck_error(scene + "cycle 20\nstrain zz 2 xy 1\nservo xx 1e4 yy 1e4 max 1e9\ncycle 3\n");
  CHECK(after.starts_with("deck.dat:8: error: max rate 1e+09 would change a cell edge by "));
  CHECK(after.find("(at most 0.5): give at most ") != std::string::npos);
  // A max rate within the bound runs.
  Harness h;
  REQUIRE(h.deck(scene + "cycle 20\nservo 1e4 1e4 1e4 max 100\ncycle 3\n"));
}

TEST_CASE("limits: GEN refuses balls the periodic cell cannot hold, and its grid has no overflow", "[limits]") {
  // 1000 in a 0.01 cell searched for ever; 1e308 overflowed the grid's cell count (UB).
  for (const char* radius : {"1000", "1e308", "0.003"}) {
    const auto e = deck_error(fmt::format("start 0.01 0.01 0.01\ngen 400 0.0004 {}\n", radius));
    CHECK(e.starts_with("deck.dat:2: error: GEN: the periodic edge x = 0.01 is less than twice the largest diameter"));
  }
  const auto psd = deck_error("start 0.01 0.01 0.01\ngen 1 psd uniform 0.003 0.004\n");
  CHECK(psd.find("less than twice the largest diameter") != std::string::npos);
  // The grid itself, asked about any finite reach, answers at once.
  Space s;
  s.periodic = true;
  s.lo = {0, 0, 0};
  s.hi = {0.01, 0.01, 0.01};
  PlacementGrid grid(s, 0.0006, 10);
  grid.insert(0.005, 0.005, 0.005, 0.0005);
  CHECK(grid.overlaps(0.0051, 0.005, 0.005, 1e308));
  CHECK(grid.overlaps(0.0051, 0.005, 0.005, 1000));
  CHECK_FALSE(grid.overlaps(0.001, 0.001, 0.001, 0.0001));
}
