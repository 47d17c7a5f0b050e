// The periodic space: images across every face on every backend (bitwise equal answers), a ball
// wrapped across a face keeps its contacts and their history, the cell-size rule, STRAIN and SERVO
// through the interpreter, PRINT stress over the cell volume.
#include <catch2/catch.hpp>

#include <cmath>
#include <memory>
#include <stdexcept>

#include <fmt/format.h>

#include "model/periodic_cell.hpp"
#include "backends_scenes.hpp"
#include "fcc_lattice.hpp"
#include "interp_support.hpp"
#include "physics/cell.hpp"
#include "physics/measure.hpp"
#include "physics/measure_sphere.hpp"

using namespace trubal;
using namespace trubal::test;

namespace {

// A dense FCC block filling a periodic cell of n x n x n unit cells (4 n^3 balls, R = 20, every ball
// touching its 12 neighbours, some across the faces), jittered, and compressed by the cell.
Model periodic_fcc(int n, double jitter_size, double rate) {
  Model m;
  const double r = 20, a = 0.99 * 2 * r * std::sqrt(2.0);
  m.space.periodic = true;
  m.space.lo = {0, 0, 0};
  m.space.hi = {n * a, n * a, n * a};
  m.started = true;
  m.materials[1] = scene_linear(1.5e9, 1.5e9, 0.3, 2000);
  m.settings.fixed_dt = 0.02;
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> jitter(-jitter_size, jitter_size);
  for_each_fcc_site(n, n, n, a, 0, [&](const FccSite& site) {
    add_ball(m, 0, 1, site.x + jitter(rng), site.y + jitter(rng), site.z + jitter(rng), r);
  });
  update_mass(m);
  if (rate != 0) set_strain_rates(m, {0.5 * rate, 0.25 * rate, rate});
  return m;
}

Model run(const Model& start, const std::string& backend_name, int threads, int cycles) {
  Model model = start;
  auto backend = make_pipeline(backend_name, threads);
  const CycleResult r = run_cycles(model, *backend, cycles, {});
  INFO(r.message);
  REQUIRE_FALSE(r.unstable);
  REQUIRE(r.done == cycles);
  return model;
}

}  // namespace

TEST_CASE("periodic: a dense FCC block in a periodic cell has exactly 6N contacts on every backend", "[periodic][threads]") {
  const Model start = periodic_fcc(4, 0, 0);   // 256 balls, the ones at the faces touch images
  for (const char* name : {"serial", "threaded", "allpairs"}) {
    INFO(name);
    const Model m = run(start, name, std::string(name) == "serial" ? 1 : 2, 1);
    CHECK(contact_count(m) == 6 * m.balls.size());
  }
}

TEST_CASE("periodic: images and a straining cell give bitwise equal answers on every backend", "[periodic][backends][threads]") {
  const Model start = periodic_fcc(5, 0.05, 2e-3);   // 500 balls, balls cross faces as the cell shrinks
  const int cycles = 400;
  const Model reference = run(start, "serial", 1, cycles);
  const Picture expected = picture(reference);
  REQUIRE(expected.contacts.size() > 2000);
  CHECK(reference.space.strain[2] > 0);
  struct Variant { const char* backend; int threads; };
  for (const Variant v : {Variant{"threaded", 1}, {"threaded", 2}, {"threaded", 3}, {"threaded", 4},
                          {"allpairs", 1}, {"allpairs", 2}, {"allpairs", 3}}) {
    INFO(v.backend << " on " << v.threads << " threads");
    const Model m = run(start, v.backend, v.threads, cycles);
    CHECK(difference(expected, picture(m)) == "");
    CHECK(std::memcmp(m.space.lo.data(), reference.space.lo.data(), sizeof(double) * 3) == 0);
    CHECK(std::memcmp(m.space.hi.data(), reference.space.hi.data(), sizeof(double) * 3) == 0);
  }
}

TEST_CASE("periodic: a ball wrapped across a face keeps its contact and shear history", "[periodic][threads]") {
  for (const char* name : {"serial", "allpairs", "threaded"}) {
    INFO(name);
    Model m;
    m.space.periodic = true;
    m.space.hi = {10, 10, 10};
    m.started = true;
    m.materials[1] = scene_linear(1e4, 1e4, 10, 1000);
    m.settings.fixed_dt = 1e-3;
    // Touching across the x face: 1 near x = 0, 2 near x = 10, overlap 0.05.
    add_ball(m, 1, 1, 0.5, 5, 5, 0.5);
    add_ball(m, 2, 1, 9.55, 5, 5, 0.5);
    m.balls.vx = {-1.0, -1.0};                  // both drift across the face at x = 0
    m.balls.vy = {0.01, -0.01};                 // and shear: the history grows steadily
    m.balls.fixed = {kVel | kSpin, kVel | kSpin};
    auto backend = make_pipeline(name, std::string(name) == "serial" ? 1 : 1);
    double last_shear = 0;
    bool wrapped = false;
    for (int step = 0; step < 60; ++step) {
      REQUIRE(run_cycles(m, *backend, 10, {}).done == 10);
      REQUIRE(contact_count(m) == 1);
      std::size_t p = 0;
      while (m.contacts.state[p] == 0) ++p;
      const double shear = std::hypot(m.contacts.fsy[p], m.contacts.fsz[p]);
      CHECK(shear > last_shear);   // never reset to zero
      last_shear = shear;
      CHECK(m.contacts.overlap[p] == Approx(0.05).epsilon(1e-2));
      wrapped = wrapped || m.balls.x[0] > 5;
      CHECK(m.balls.x[0] > -0.02);   // wrapped at the start of each step, then moved
      CHECK(m.balls.x[0] < 10.02);
    }
    CHECK(wrapped);
  }
}

TEST_CASE("periodic: a cell shorter than twice the largest diameter is refused", "[periodic]") {
  Model m;
  m.space.periodic = true;
  m.space.hi = {10, 10, 3.9};
  m.started = true;
  m.materials[1] = scene_linear(1e4, 1e4, 0.3, 1000);
  add_ball(m, 1, 1, 5, 5, 1, 1);
  auto backend = make_pipeline("serial", 1);
  CHECK_THROWS_WITH(run_cycles(m, *backend, 1, {}), Catch::Contains("periodic cell too small"));
}

TEST_CASE("periodic: STRAIN deforms the cell, PRINT strain and stress use the cell", "[periodic][commands]") {
  Harness h;
  REQUIRE(h.deck(R"(
start 200 200 200
prop kn 1e6 ks 1e6 fric 0.3 dens 2000
gen 100 8 10 seed 3
tstep 0.01
strain 1e-3 0 2e-3
cycle 100
print strain
)"));
  const Model& m = h.session.model();
  const double dt = 0.01;
  CHECK(m.space.strain[0] == Approx(100 * 1e-3 * dt));
  CHECK(m.space.strain[2] == Approx(100 * 2e-3 * dt));
  CHECK(m.space.strain[1] == 0);
  CHECK(m.space.length()[2] == Approx(200 * std::exp(-100 * 2e-3 * dt)).epsilon(1e-13));   // L0 exp(-sum e dt)
  CHECK(h.out.str().find("strain: xx 0.001") != std::string::npos);
  const auto L = m.space.length();
  CHECK(h.session.stress_volume() == Approx(L[0] * L[1] * L[2]));
  REQUIRE(h.deck("strain zz 0\nprint strain\nstrain off\n"));
  CHECK(h.session.model().space.strain_rate[0] == 0);
  // Shear rates are taken (tests/unit/periodic_shear.cpp tests what they do).
  REQUIRE(h.deck("strain 0 0 1e-3 5e-4 0 0\n"));
  CHECK(h.session.model().space.strain_rate[3] == 5e-4);
}

TEST_CASE("periodic: STRAIN and SERVO need the periodic space", "[periodic][commands]") {
  Harness h;
  REQUIRE(h.deck("start box 0 10 0 10 0 10\n"));
  CHECK_FALSE(h.deck("strain 0 0 1e-3\n"));
  CHECK(h.first_error_line().find("periodic space") != std::string::npos);
}

TEST_CASE("periodic: SERVO brings the cell's stress to the targets, each axis on its own", "[periodic][commands]") {
  Harness h;
  REQUIRE(h.deck(R"(
start 200 200 200
prop kn 1e6 ks 1e6 fric 0.3 dens 2000
gen 400 9 11 seed 5
damp local 0.7
servo 1000 1100 1200
cycle 16000
)"));
  const Model& m = h.session.model();
  const auto L = m.space.length();
  const Sym6 s = average_stress(m, L[0] * L[1] * L[2]);
  CHECK(s[0] == Approx(1000).epsilon(0.01));
  CHECK(s[1] == Approx(1100).epsilon(0.01));
  CHECK(s[2] == Approx(1200).epsilon(0.01));
  // The energy balance holds with the cell's work counted.
  const EnergyReport e = energy(m);
  CHECK(std::abs(e.total()) < 0.02 * std::abs(e.boundary_work));
}

TEST_CASE("periodic: a loose assembly under the servo is bitwise equal on every backend", "[periodic][backends][threads]") {
  auto run_deck = [](const std::string& backend) {
    auto h = std::make_unique<Harness>();
    REQUIRE(h->deck("start 200 200 200\nprop kn 1e6 ks 1e6 fric 0.3 dens 2000\ngen 300 9 11 seed 9\n"
                    "damp local 0.7\nbackend " + backend + "\nservo 1000 1100 1200\ncycle 6000\n"));
    return picture(h->session.model());
  };
  const Picture expected = run_deck("serial");
  REQUIRE(expected.contacts.size() > 300);
  for (const char* b : {"threaded threads 3", "allpairs threads 2"}) {
    INFO(b);
    CHECK(difference(expected, run_deck(b)) == "");
  }
}

TEST_CASE("periodic: SERVO holds its targets through simple shear (the integral term)", "[long][periodic][servo]") {
  // examples/periodic_simple_shear.dat, shortened: 400 loose balls compressed to 100 kPa, then
  // sheared at e12 rate 8 /s with all three normal stresses servoed. Shear dilates the assembly, so
  // the servo must keep expanding the cell: a proportional servo needs an error to drive that rate
  // (s33 fell 14.8% below target with the old 0.01 gain, tools/servo_hold.py), the integral term
  // learns it. Bound: 1% on every record past e12 = 0.02 (the issue's target; measured 0.4% on the
  // full example), mean within 0.2%.
  test::TempDir dir;
  test::WorkingDir cd(dir.path());
  test::Harness h;
  REQUIRE(h.deck("start 0.01 0.01 0.01\nprop kn 1e5 ks 1e5 fric 26.57 dens 2650\ngen 400 0.0004 0.0006 seed 7\n"
                 "damp local 0.7\nservo 1e5 1e5 1e5\ncycle 20000\nstrain xy 8\n"
                 "hist stress strain every 50 file h.csv\ncycle 15000\n"));
  const auto lines = test::lines_of(test::slurp(dir.path() / "h.csv"));
  REQUIRE(lines.size() > 100);
  // columns: cycle,time,s11,s22,s33,s12,s13,s23,e11,e22,e33,e12,...
  std::size_t held = 0;
  double worst = 0, sum[3] = {0, 0, 0};
  for (std::size_t l = 1; l < lines.size(); ++l) {
    std::vector<double> v;
    std::stringstream row(lines[l]);
    for (std::string c; std::getline(row, c, ',');) v.push_back(std::stod(c));
    REQUIRE(v.size() >= 12);
    if (v[11] < 0.02) continue;
    ++held;
    for (int a = 0; a < 3; ++a) {
      const double error = (v[2 + a] - 1e5) / 1e5;
      worst = std::max(worst, std::abs(error));
      sum[a] += error;
    }
  }
  REQUIRE(held > 50);
  CHECK(worst < 0.01);
  for (int a = 0; a < 3; ++a) CHECK(std::abs(sum[a] / held) < 0.002);
  // What the integral learnt is a rate of the order of the shear's volume change (this loose sample
  // contracts as it shears: positive, compression positive).
  CHECK(std::abs(h.session.model().space.servo_integral[2]) > 0.1);
}

TEST_CASE("periodic: STRAIN reset starts the accumulated strain again, the rates stay", "[periodic]") {
  trubal::test::Harness h;
  REQUIRE(h.deck("start 1 1 1\nprop kn 1e5 dens 1000\nball 0.5 0.5 0.5 0.1\nstrain 0 0 0.01\ntstep 0.01\ncycle 100\n"));
  const auto& s = h.session.model().space;
  CHECK(s.strain[2] == Approx(0.01).epsilon(1e-9));
  REQUIRE(h.deck("strain reset\ncycle 50\n"));
  CHECK(s.strain[2] == Approx(0.005).epsilon(1e-9));
  CHECK(s.strain_rate[2] == 0.01);
}

TEST_CASE("periodic: the volumetric strain is 1 - V/V0 from START or STRAIN reset, through SAVE and RESTART",
          "[periodic]") {
  trubal::test::TempDir dir;
  trubal::test::WorkingDir cd(dir.path());
  trubal::test::Harness h;
  // 3000 steps at 1e-4 per step on every axis: accumulated (natural) strains of 0.3 each, 0.9 in
  // all, where the cell has lost 1 - exp(-0.9) = 59.3% of its volume: a strain below 1, as a strain is.
  REQUIRE(h.deck("start 10 10 10\nprop kn 1e5 dens 1000\nball 5 5 5 0.1\nstrain 1 1 1\ntstep 1e-4\ncycle 3000\n"
                 "print strain\n"));
  const auto& s = h.session.model().space;
  CHECK(s.strain[0] + s.strain[1] + s.strain[2] == Approx(0.9).epsilon(1e-9));
  const double evol = trubal::volumetric_strain(h.session.model());
  CHECK(evol == Approx(1 - std::exp(-0.9)).epsilon(1e-9));   // ((1 - 1e-4)^9000, the edges' old update, is 3e-5 off)
  CHECK_THAT(h.out.str(), Catch::Contains(fmt::format("volumetric strain: {:.6g} (1 - V/V0", evol)));
  // A new stage: measured from its own start. 100 more steps shrink the volume by 1 - exp(-0.03).
  REQUIRE(h.deck("strain reset\ncycle 100\nsave s.sav\n"));
  CHECK(trubal::volumetric_strain(h.session.model()) == Approx(1 - std::exp(-0.03)).epsilon(1e-9));
  trubal::test::Harness restarted;
  REQUIRE(restarted.deck("restart s.sav\n"));
  CHECK(trubal::volumetric_strain(restarted.session.model()) == trubal::volumetric_strain(h.session.model()));
}

TEST_CASE("periodic: rates whose trace is zero keep the cell's volume to rounding, and the strain is natural",
          "[periodic]") {
  // An undrained (constant-volume) triaxial test, as CONBAL-2 ran them (Ng and Dobry 1992): STRAIN
  // -0.25 -0.25 0.5 to 10% axial strain. Each edge advanced as L (1 - e dt) lost (3/4)(e dt)^2 of the
  // volume a step: 1.9e-4 over these 1000 steps of e dt = 5e-4; as L exp(-e dt), none.
  for (const char* rates : {"-0.25 -0.25 0.5", "0.3 -0.1 -0.2", "-0.25 -0.25 0.5 0.1 0 0"}) {
    INFO(rates);
    Harness h;
    REQUIRE(h.deck(std::string("start 10 10 10\nprop kn 1e5 dens 1000\nball 5 5 5 0.1\ntstep 1e-3\nstrain ") + rates +
                   "\ncycle 200\n"));
    for (int k = 0; k < 4; ++k) REQUIRE(h.deck("cycle 200\n"));   // cut into CYCLEs: the same
    const Model& m = h.session.model();
    const auto L = m.space.length();
    CHECK(std::abs(1 - L[0] * L[1] * L[2] / 1000) < 1e-12);
    CHECK(std::abs(volumetric_strain(m)) < 1e-12);
    // The strain summed is -ln(L / L0) on each axis (0.5 * 1e-3 * 1000 = 0.5 on z for the first).
    for (int a = 0; a < 3; ++a) CHECK(m.space.strain[a] == Approx(-std::log(L[a] / 10)).margin(1e-12));
  }
}

TEST_CASE("periodic: HIST pq records a triaxial test's mean stress and deviator, z axial", "[periodic][commands]") {
  Harness h;
  // A dense packing (GEN porosity leaves small overlaps: a stress at once), compressed along z.
  REQUIRE(h.deck("start 100 100 100\nprop kn 1e6 ks 1e6 fric 0.3 dens 2000\ngen porosity 0.4 8 10 seed 3\n"
                 "tstep 0.01\nstrain 1e-3 0 2e-3\nhist stress pq every 50\ncycle 200\n"));
  const HistoryTable& t = *h.session.history().tables().front();
  REQUIRE(t.columns == std::vector<std::string>{"cycle", "time", "s11", "s22", "s33", "s12", "s13", "s23", "p", "q"});
  REQUIRE(t.rows.size() == 4);
  const auto& r = t.rows.back();
  REQUIRE(r[4] > 0);   // compressed along z: the balls touch
  CHECK(r[8] == Approx((r[2] + r[3] + r[4]) / 3).epsilon(1e-14));
  CHECK(r[9] == Approx(r[4] - 0.5 * (r[2] + r[3])).epsilon(1e-14));
}
