// The guard's checks every few cycles and the energy terms formed only where read
// (doc/physics.md "Instability guard"): an unstable step is still caught within a check's spacing,
// and the energies a reader takes are the same bits however the run is cut or observed.
#include <catch2/catch.hpp>

#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "cycle/energy_guard.hpp"
#include "fcc_lattice.hpp"
#include "physics/measure.hpp"
#include "interp_support.hpp"
#include "physics_helpers.hpp"

using namespace trubal;

namespace {

// The cycle an "unstable at cycle N" message names.
std::int64_t unstable_cycle(const std::string& message) {
  const std::string key = "unstable at cycle ";
  const auto at = message.find(key);
  REQUIRE(at != std::string::npos);
  return std::stoll(message.substr(at + key.size()));
}

// The block squeezed 1%, released but for its bottom layer: it springs apart and falls under
// gravity, with friction and local damping, so every work and energy term moves.
Model falling_heap() {
  Model model = test::held_fcc_block(3);
  model.materials[1] = test::linear_material(1e6, 5e5, 0.4, 2500);
  model.settings.gravity = {0, 0, -9.81};
  model.settings.damping.kind = DampKind::Local;
  model.settings.damping.local = 0.1;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-0.05, 0.05);
  Balls& b = model.balls;
  for (std::size_t k = 0; k < b.size(); ++k) {
    if (b.fixed[k] != 0 && b.z[k] > 0.01) b.fixed[k] = 0;   // only the bottom layer held
    if (b.fixed[k] != 0) continue;
    b.vx[k] = u(rng); b.vy[k] = u(rng); b.vz[k] = u(rng);
  }
  return model;
}

struct EnergyRow {
  std::int64_t cycle = 0;
  EnergyReport e;
};
bool same_bits(const EnergyRow& a, const EnergyRow& b) {
  const double x[] = {a.e.kinetic_translation, a.e.kinetic_rotation, a.e.strain, a.e.potential,
                      a.e.friction_work,       a.e.damping_work,     a.e.boundary_work};
  const double y[] = {b.e.kinetic_translation, b.e.kinetic_rotation, b.e.strain, b.e.potential,
                      b.e.friction_work,       b.e.damping_work,     b.e.boundary_work};
  return a.cycle == b.cycle && a.e.at_step && b.e.at_step && std::memcmp(x, y, sizeof x) == 0;
}

// Runs `cuts` CYCLEs on a fresh heap, recording the energies at every 7th cycle; every_step: the
// observer reads every step (so every step forms the energy terms), else the 7th cycles only.
std::vector<EnergyRow> energies_every_7(const std::vector<std::int64_t>& cuts, bool every_step, Model& model) {
  model = falling_heap();
  auto backend = make_pipeline("serial", 1);
  std::vector<EnergyRow> rows;
  CycleControl control;
  control.after_step = [&](const Model& m) {
    if (m.cycle % 7 == 0) rows.push_back({m.cycle, energy(m)});
  };
  if (!every_step) control.reads_contacts = [](std::int64_t cycle) { return cycle % 7 == 0; };
  for (const std::int64_t n : cuts) {
    const CycleResult r = run_cycles(model, *backend, n, control);
    INFO(r.message);
    REQUIRE_FALSE(r.unstable);
  }
  return rows;
}

}  // namespace

TEST_CASE("guard: checking every 8th cycle still stops an unstable block within a check of the step-by-step guard",
          "[physics][energy]") {
  // An observer that reads every step makes the guard check every step: the regular checks alone
  // see the same growth at most kCheckEvery - 1 cycles later. Three scenes beyond their stable
  // step: the held block undamped at FRAC 2 and with Cundall's damping at FRAC 5 (over-damped:
  // its limit squared; physics_stability.cpp), where the velocities' flipping stops both guards
  // at their fourth regular check, and a chain of three balls, one held, at FRAC 3, whose balance
  // trips within a few cycles.
  const int scene = GENERATE(0, 1, 2);
  const bool damped = scene == 1;
  auto run = [scene, damped](bool every_step) {
    Model model;
    if (scene == 2) {
      model.materials[1] = test::linear_material(1e6, 1e6, 0.3, 1000);
      for (const double x : {-0.0099, 0.0099, 0.0297}) add_ball(model, 0, 1, x, 0, 0, 0.01);
      model.balls.fixed[0] = kVel | kSpin;
      model.settings.frac = 3;
    } else {
      model = test::held_fcc_block(4);
      model.settings.frac = damped ? 5 : 2;
    }
    if (damped) {   // DAMP 0.05 0.5: alpha = lambda omega, beta = lambda / omega, omega = 2 pi f
      const double omega = 2 * M_PI * 0.5;
      model.settings.damping.kind = DampKind::Rayleigh;
      model.settings.damping.alpha = 0.05 * omega;
      model.settings.damping.beta = 0.05 / omega;
    }
    auto backend = make_pipeline("serial", 1);
    CycleControl control;
    if (every_step) control.after_step = [](const Model&) {};
    const CycleResult r = run_cycles(model, *backend, 5000, control);
    INFO(r.message);
    REQUIRE(r.unstable);
    return std::make_pair(unstable_cycle(r.message), r.message);
  };
  const auto [each, each_message] = run(true);
  const auto [checks, checks_message] = run(false);
  CAPTURE(each, checks, each_message, checks_message);
  CHECK(each_message.find("energy was created") != std::string::npos);
  CHECK(checks_message.find("energy was created") != std::string::npos);
  CHECK(each <= (scene == 2 ? 4 : 32));   // (measured: 3 and 32)
  CHECK(checks >= 1);
  CHECK(checks <= each + EnergyGuard::kCheckEvery - 1);
  CHECK(checks % EnergyGuard::kCheckEvery == 0);   // found at a regular check
}

TEST_CASE("guard: a stable vibrating block is not stopped by checks that see its vibration's phase",
          "[physics][energy]") {
  // The held block at FRAC 0.8, undamped: its kinetic term goes negative at the turning points of
  // each vibration, which checks 8 cycles apart could see at every check; the test of velocities
  // that flip sign asks for the step before each check too.
  Model model = test::held_fcc_block(4);
  model.settings.frac = 0.8;
  auto backend = make_pipeline("serial", 1);
  const CycleResult r = run_cycles(model, *backend, 4000, {});
  INFO(r.message);
  CHECK_FALSE(r.unstable);
  CHECK(r.done == 4000);
}

TEST_CASE("guard: energies read every 7 cycles are the same bits however the run is cut or observed",
          "[physics][energy]") {
  // The regular checks fall on the model's count (every 8th cycle), the reads on every 7th: the
  // terms formed at a read are the same whether or not the step before was formed, the CYCLE
  // started there, or every step formed them.
  Model whole, cut, observed;
  const auto a = energies_every_7({210}, false, whole);
  const auto b = energies_every_7({13, 101, 96}, false, cut);
  const auto c = energies_every_7({210}, true, observed);
  REQUIRE(a.size() == 30);
  REQUIRE(b.size() == a.size());
  REQUIRE(c.size() == a.size());
  for (std::size_t k = 0; k < a.size(); ++k) {
    CAPTURE(a[k].cycle, a[k].e.kinetic_translation, b[k].e.kinetic_translation, c[k].e.kinetic_translation);
    CHECK(same_bits(a[k], b[k]));
    CHECK(same_bits(a[k], c[k]));
  }
  // Something moved: the block sprang apart and rubbed (a test of zeros would pass on anything).
  CHECK(a.back().e.potential != a.front().e.potential);
  CHECK(a.back().e.friction_work > 0);
  CHECK(a.back().e.damping_work > 0);
  CHECK(a.back().e.strain > 0);
  // And the final states are the same bits.
  for (std::size_t k = 0; k < whole.balls.size(); ++k) {
    CHECK(whole.balls.z[k] == cut.balls.z[k]);
    CHECK(whole.balls.vz[k] == observed.balls.vz[k]);
  }
}

TEST_CASE("guard: a step that forms no energy terms marks them as not the state's", "[physics][energy]") {
  // Between the checks the terms are not formed: a reader there (a run that ends early, say) must
  // not take an older step's terms for the state's. The CYCLE's last step forms them.
  Model model = falling_heap();
  auto backend = make_pipeline("serial", 1);
  std::vector<std::int64_t> valid_cycles;
  CycleControl control;
  control.after_step = [&](const Model& m) {
    if (m.energy_at_step.valid) valid_cycles.push_back(m.cycle);
  };
  control.reads_contacts = [](std::int64_t) { return false; };
  REQUIRE_FALSE(run_cycles(model, *backend, 40, control).unstable);
  // The first step, the regular checks (8, 16, 24, 32, 40: the last is also the CYCLE's last).
  CHECK(valid_cycles == std::vector<std::int64_t>{1, 8, 16, 24, 32, 40});
  CHECK(model.energy_at_step.valid);
  const EnergyReport e = energy(model);
  CHECK(e.at_step);
}

TEST_CASE("guard: a ball leaving a stop face between checks is checked by taking the steps again, to the same bits",
          "[physics][energy][domain]") {
  // A fast ball bouncing on a rough, damped pack in a box, crossing x = 1 in the 51st step (not a
  // check: the steps from the CYCLE's start are taken again, that one checked), against the same
  // run cut at cycle 50, where the crossing is the next CYCLE's first step (always checked).
  const std::string scene =
      "start box 0 1 0 1 0 1\nprop kn 1e4 ks 1e4 fric 0.5 dens 1000\ndamp local 0.1\ngrav 0 0 -9.81\n"
      "ball 0.5 0.5 0.5 0.05\nball 0.2 0.2 0.06 0.05\nball 0.3 0.2 0.06 0.05\nball 0.25 0.28 0.06 0.05\n"
      "fix xvel yvel zvel range id 2\ninit xvel 9.9 range id 1\ninit xvel 0.3 zvel -0.2 range id 3\ntstep 1e-3\n";
  test::Harness whole, cut;
  CHECK_FALSE(whole.deck(scene + "cycle 100\n"));
  CHECK_FALSE(cut.deck(scene + "cycle 50\ncycle 100\n"));
  INFO(whole.first_error_line());
  CHECK(whole.first_error_line().find("ball 1 left the box through x = 1 at cycle 51") != std::string::npos);
  CHECK(cut.first_error_line().find("ball 1 left the box through x = 1 at cycle 51") != std::string::npos);
  const Model& a = whole.session.model();
  const Model& b = cut.session.model();
  REQUIRE(a.cycle == 51);
  REQUIRE(b.cycle == 51);
  REQUIRE(a.balls.size() == b.balls.size());
  for (std::size_t k = 0; k < a.balls.size(); ++k) {
    CHECK(a.balls.x[k] == b.balls.x[k]);
    CHECK(a.balls.z[k] == b.balls.z[k]);
    CHECK(a.balls.vx[k] == b.balls.vx[k]);
    CHECK(a.balls.wy[k] == b.balls.wy[k]);
  }
  CHECK(a.energy.friction_work == b.energy.friction_work);
  CHECK(a.energy.damping_work == b.energy.damping_work);
  const EnergyReport ea = energy(a), eb = energy(b);
  CHECK(ea.at_step);
  CHECK(ea.kinetic_translation == eb.kinetic_translation);
  CHECK(ea.strain == eb.strain);
  CHECK(ea.damping_work > 0);   // (the pack moved: a test of a still scene would pass on anything)
}

TEST_CASE("guard: a ball vibrating on a spring with a half period of 8 steps, the checks' spacing, runs on",
          "[physics][energy]") {
  // One ball on a held one under gravity, vibrating at omega = sqrt(kn / m) about its resting
  // overlap with an amplitude of half of it (the contact never opens). The step is the half period
  // over 8 (omega dt = pi / 8, well inside the stable step): the kinetic term is negative at the
  // step that straddles each turning point, every 8th step, so at the same phase at every regular
  // check; at some phases every check sees it negative (a test of the checks alone stopped this
  // run at cycle 32 as "velocities flip sign"). Each phase of the half period is tried.
  const int phase = GENERATE(range(0, 8));
  Model model;
  model.materials[1] = test::linear_material(1e3, 1e3, 0, 1000);
  const double r = 0.01, m = test::sphere_mass(1000, r), g = 9.81;
  const double settle = m * g / 1e3, omega = std::sqrt(1e3 / m);
  add_ball(model, 0, 1, 0, 0, 0, r);
  model.balls.fixed[0] = kVel | kSpin;
  const double angle = phase * M_PI / 8, amplitude = 0.5 * settle;
  const std::size_t top = add_ball(model, 0, 1, 0, 0, 2 * r - settle + amplitude * std::cos(angle), r);
  model.balls.vz[top] = -amplitude * omega * std::sin(angle);
  model.settings.gravity = {0, 0, -g};
  model.settings.fixed_dt = M_PI / omega / 8;
  auto backend = make_pipeline("serial", 1);
  const CycleResult r1 = run_cycles(model, *backend, 2000, {});
  INFO("phase " << phase << ": " << r1.message);
  CHECK_FALSE(r1.unstable);
  CHECK(r1.done == 2000);
}
