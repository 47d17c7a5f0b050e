// Contact detection: the serial backend finds exactly the touching pairs a brute-force check finds.
#include <catch2/catch.hpp>

#include <algorithm>
#include <random>
#include <set>
#include <utility>

#include "physics/measure.hpp"
#include "physics_helpers.hpp"

using namespace trubal;

namespace {

// Pairs of ids, the smaller first (the model's order in memory is not id order).
using PairSet = std::set<std::pair<std::int64_t, std::int64_t>>;
std::pair<std::int64_t, std::int64_t> ids(std::int64_t a, std::int64_t b) { return {std::min(a, b), std::max(a, b)}; }

PairSet brute_force(const Balls& b) {
  PairSet s;
  for (std::size_t i = 0; i < b.size(); ++i)
    for (std::size_t j = i + 1; j < b.size(); ++j) {
      const double dx = b.x[j] - b.x[i], dy = b.y[j] - b.y[i], dz = b.z[j] - b.z[i];
      const double reach = b.rad[i] + b.rad[j];
      if (dx * dx + dy * dy + dz * dz < reach * reach) s.insert(ids(b.id[i], b.id[j]));
    }
  return s;
}

PairSet touching(const Model& m) {
  PairSet s;
  for (std::size_t p = 0; p < m.contacts.size(); ++p)
    if (m.contacts.state[p]) s.insert(ids(m.balls.id[m.contacts.i[p]], m.balls.id[m.contacts.j[p]]));
  return s;
}

}  // namespace

TEST_CASE("physics: serial contact detection equals brute force on polydisperse packings", "[physics]") {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0, 1);
  Model model;
  model.materials[1] = test::linear_material(1e4, 1e4, 0.3, 1000);
  model.settings.fixed_dt = 1e-4;
  // Radii 0.1 to 1 (1:10), dense enough that many touch; random velocities move them around.
  for (int k = 0; k < 600; ++k) {
    const std::size_t b = add_ball(model, 0, 1, 12 * u(rng), 12 * u(rng), 12 * u(rng), 0.1 + 0.9 * u(rng) * u(rng));
    model.balls.vx[b] = 40 * (u(rng) - 0.5); model.balls.vy[b] = 40 * (u(rng) - 0.5); model.balls.vz[b] = 40 * (u(rng) - 0.5);
  }
  auto backend = make_pipeline("serial", 1);
  std::size_t checked = 0;
  for (int round = 0; round < 6; ++round) {
    // The states of a step describe the positions it started from.
    const Balls before = model.balls;
    REQUIRE_FALSE(run_cycles(model, *backend, 1, {}).unstable);
    const PairSet expected = brute_force(before);
    CHECK(touching(model) == expected);
    checked += expected.size();
    REQUIRE_FALSE(run_cycles(model, *backend, 400, {}).unstable);   // move on (rebuilds on the way)
  }
  CHECK(checked > 300);
  CHECK(backend->counters().rebuilds > 6);   // rebuilt on the way, not only once per CYCLE
}

TEST_CASE("physics: shear history survives pair-list rebuilds and ball insertion", "[physics]") {
  Model model;
  model.materials[1] = test::linear_material(1e6, 1e6, 0.5, 1000);
  model.settings.fixed_dt = 1e-4;
  add_ball(model, 10, 1, 0, 0, 0, 1);
  add_ball(model, 20, 1, 1.99, 0, 0, 1);
  model.balls.vy[1] = 0.01;   // shears the contact
  auto backend = make_pipeline("serial", 1);
  REQUIRE_FALSE(run_cycles(model, *backend, 50, {}).unstable);
  const double fs = model.contacts.fsy[0];
  REQUIRE(fs < 0);
  add_ball(model, 15, 1, 50, 50, 50, 1);   // shifts indices; the history must follow the ids
  backend->invalidate();
  REQUIRE_FALSE(run_cycles(model, *backend, 1, {}).unstable);
  std::size_t p = 0;
  while (p < model.contacts.size() && model.contacts.state[p] == 0) ++p;
  REQUIRE(p < model.contacts.size());
  CHECK(model.balls.id[model.contacts.j[p]] == 20);
  CHECK(model.contacts.fsy[p] < fs);   // one more increment on top of the carried force
  CHECK(model.contacts.fsy[p] == Approx(fs * 51.0 / 50.0).epsilon(0.01));
}
