// allpairs in a periodic cell: the branch-free row test (test_row_periodic) sets a slot exactly
// where nearest_image_within says a pair touches, in a cubic cell, a tilted one and a mixed one,
// on random pairs and on pairs placed at the edges of its choices (half an edge apart, zeros of
// either sign, just inside and outside reach); and the backend finds the same pairs and images.
#include <catch2/catch.hpp>

#include <cmath>
#include <random>
#include <vector>

#include "backends/allpairs/pair_test.hpp"
#include "model/periodic_cell.hpp"
#include "backends_scenes.hpp"

using namespace trubal;
using namespace trubal::test;

namespace {

// Every row i of the triangle against nearest_image_within at skin 0; returns the touching pairs.
std::size_t check_rows(const Model& m) {
  const Balls& b = m.balls;
  const CellFrame f = cell_frame(m.space);
  const bool tilted = f.xy != 0 || f.xz != 0 || f.yz != 0;
  std::vector<std::uint8_t> slot(b.size());
  std::size_t touching = 0, wrong = 0;
  for (std::size_t i = 0; i + 1 < b.size(); ++i) {
    const std::size_t count = b.size() - 1 - i;
    const std::size_t set = test_row_periodic(f, tilted, b.x[i], b.y[i], b.z[i], b.rad[i], b.x.data() + i + 1,
                                              b.y.data() + i + 1, b.z.data() + i + 1, b.rad.data() + i + 1, count,
                                              slot.data());
    std::size_t expected = 0;
    for (std::size_t k = 0; k < count; ++k) {
      std::int8_t ix, iy, iz;
      const bool near = nearest_image_within(f, b, i, i + 1 + k, b.rad[i] + b.rad[i + 1 + k] + 0.0, ix, iy, iz);
      expected += near;
      wrong += (slot[k] != 0) != near;
    }
    wrong += set != expected;
    touching += expected;
  }
  CHECK(wrong == 0);
  return touching;
}

// Random balls in the cell (wrapped), and pairs placed on the edges of the image choice.
Model cell_with_balls(const std::array<double, 3>& tilt, const std::array<bool, 3>& axes, std::uint64_t seed) {
  Model m;
  m.space.periodic = true;
  m.space.periodic_axis = axes;
  m.space.lo = {0, 0, 0};
  m.space.hi = {8, 6, 7};
  m.space.tilt = tilt;
  m.started = true;
  m.materials[1] = scene_linear(1e6, 1e6, 0.3, 1000);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 1), rad(0.3, 1.0);
  for (int k = 0; k < 600; ++k)
    add_ball(m, 0, 1, 8 * u(rng), 6 * u(rng), 7 * u(rng), rad(rng));
  // Separations of exactly half an edge, a zero and a negative zero, and reach +- an ulp.
  const double r = 1.0;
  for (double x : {0.0, 4.0, 8.0 - 1e-12})
    for (double d : {4.0, -4.0, 2 * r, std::nextafter(2 * r, 0.0), std::nextafter(2 * r, 3.0)}) {
      add_ball(m, 0, 1, x, 3.0, -0.0, r);
      add_ball(m, 0, 1, std::fmod(x + d + 8.0, 8.0), 3.0, 0.0, r);
    }
  add_ball(m, 0, 1, 0.5, 0.0, 3.0, r);
  add_ball(m, 0, 1, 0.5, 3.0, 3.0, r);   // exactly half the y edge
  update_mass(m);
  wrap_into_cell(m, nullptr, nullptr, nullptr);
  return m;
}

}  // namespace

TEST_CASE("allpairs periodic: the row test is nearest_image_within, slot for slot", "[backends][periodic]") {
  SECTION("cubic cell") { CHECK(check_rows(cell_with_balls({0, 0, 0}, {true, true, true}, 3)) > 100); }
  SECTION("zero tilts of either sign") { CHECK(check_rows(cell_with_balls({-0.0, 0.0, -0.0}, {true, true, true}, 4)) > 100); }
  SECTION("tilted cell") { CHECK(check_rows(cell_with_balls({3.9, -1.2, 2.5}, {true, true, true}, 5)) > 100); }
  SECTION("x and y periodic, z bounded") { CHECK(check_rows(cell_with_balls({0, 0, 0}, {true, true, false}, 6)) > 100); }
}

TEST_CASE("allpairs periodic: the backend lists every touching pair at its nearest image", "[backends][periodic]") {
  for (const Scene& scene : {sheared_periodic(10, 0), fcc_compression(4, 4, 5)}) {
    INFO(scene.name);
    Model m = scene.model;
    if (m.space.periodic) {   // sheared until the cell is tilted past half an edge and the balls touch
      auto serial = make_pipeline("serial", 1);
      REQUIRE(run_cycles(m, *serial, 300, {}).done == 300);
      REQUIRE(m.space.tilt[0] < 0);
    } else {   // the free FCC block in a periodic cell of its own extent plus a gap
      m.space.periodic = true;
      m.space.lo = {-100, -100, -100};
      m.space.hi = {400, 400, 400};
    }
    wrap_into_cell(m, nullptr, nullptr, nullptr);
    auto backend = make_pipeline("allpairs", 2);
    backend->prepare(m);
    const Balls& b = m.balls;
    const CellFrame f = cell_frame(m.space);
    std::size_t touching = 0;
    for (std::size_t i = 0; i < b.size(); ++i)
      for (std::size_t j = i + 1; j < b.size(); ++j) {
        std::int8_t ix, iy, iz;
        touching += nearest_image_within(f, b, i, j, b.rad[i] + b.rad[j] + 0.0, ix, iy, iz);
      }
    CHECK(m.contacts.size() == touching);
    CHECK(touching > (m.space.tilt[0] != 0 ? 50u : 500u));
  }
}
