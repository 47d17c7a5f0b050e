// Commands that drive a run, through the real interpreter: SOLVE reaches equilibrium, APPLY and
// GRAV give the accelerations they should, TSTEP/FRAC set the step, DAMP sets its coefficients.
#include <catch2/catch.hpp>

#include <cmath>
#include <numbers>

#include "cycle/pipeline.hpp"
#include "counters.hpp"
#include "interp_support.hpp"
#include "physics/measure.hpp"

using namespace trubal;
using namespace trubal::test;

TEST_CASE("commands: SOLVE cycles until the unbalanced-force ratio is below its target", "[commands]") {
  // A column of three balls resting on a fixed one under gravity, locally damped.
  Harness h;
  REQUIRE(h.deck("start box -1 1 -1 1 -1 10\nprop kn 1e6 ks 1e6 fric 20 dens 1000\n"
                 "ball 0 0 0 0.5 id 1\nball 0 0 1.0 0.5 id 2\nball 0 0 2.0 0.5 id 3\nball 0 0 3.0 0.5 id 4\n"
                 "fix vel spin range id 1\ngrav 0 0 -10\ndamp local 0.7\nsolve ratio 1e-4 limit 200000\n"));
  CHECK_THAT(h.out.str(), Catch::Contains("solved"));
  CHECK(unbalanced_force(h.session.model()).mean_ratio < 1e-4);
  // At equilibrium the fixed ball's unbalanced force (its reaction) is the weight of the three
  // above it plus its own.
  const auto& b = h.session.model().balls;
  const double weight = 4 * 1000 * 4.0 / 3.0 * std::numbers::pi * 0.125 * 10;
  CHECK(b.fz[0] == Approx(-weight).epsilon(1e-3));   // 1e-3: the residual of ratio 1e-4 and rounding
  // A limit too small to converge is a warning, not an error. The ball drops 0.2 onto the fixed one
  // and bounces (undamped): the coarse contact must not look like an instability either.
  Harness g;
  REQUIRE(g.deck("start box -1 1 -1 1 -1 10\nprop kn 1e6 ks 1e6 dens 1000\nball 0 0 0 0.5 id 1\n"
                 "ball 0 0 1.2 0.5 id 2\nfix vel range id 1\ngrav 0 0 -10\nsolve ratio 1e-6 limit 100\n"));
  CHECK_THAT(g.err.str(), Catch::Contains("SOLVE stopped at the limit"));
}

TEST_CASE("commands: APPLY and GRAV accelerate a free ball exactly as F/m and g", "[commands]") {
  Harness h;
  REQUIRE(h.deck("start box -100 100 -100 100 -100 100\nprop kn 1e6 ks 1e6 dens 1000\n"
                 "ball 0 0 0 1 id 1\nball 50 0 0 1 id 2\napply xforce 10 range id 1\ngrav 0 0 -2\n"
                 "tstep 0.01\ncycle 100\n"));
  const auto& b = h.session.model().balls;
  const double m = 1000 * 4.0 / 3.0 * std::numbers::pi;
  // Central differences with a constant force: v after n steps is exactly n a dt (to rounding).
  CHECK(b.vx[0] == Approx(100 * 10 / m * 0.01).epsilon(1e-12));
  CHECK(b.vz[0] == Approx(-2.0).epsilon(1e-12));
  CHECK(b.vx[1] == 0);                                        // APPLY acted on id 1 only
  CHECK(h.session.model().dt == 0.01);
  REQUIRE(h.deck("apply off\nfrac 0.5\ncycle 1\n"));
  CHECK(b.vx[0] == Approx(100 * 10 / m * 0.01).epsilon(1e-12));   // no more applied force
  CHECK(h.session.model().dt != 0.01);                            // FRAC cancels TSTEP
}

TEST_CASE("commands: DAMP sets Rayleigh coefficients from lambda and f, or directly", "[commands]") {
  Harness h;
  REQUIRE(h.deck("damp 0.05 0.5\n"));
  const auto& d = h.session.model().settings.damping;
  CHECK(d.kind == DampKind::Rayleigh);
  CHECK(d.alpha == Approx(0.05 * 2 * std::numbers::pi * 0.5));   // doc/physics.md: alpha = lambda omega
  CHECK(d.beta == Approx(0.05 / (2 * std::numbers::pi * 0.5)));   // beta = lambda / omega
  REQUIRE(h.deck("damp mass 2 stiff 3e-4\n"));
  CHECK(h.session.model().settings.damping.alpha == 2);
  CHECK(h.session.model().settings.damping.beta == 3e-4);
  REQUIRE(h.deck("damp local 0.7\n"));
  CHECK(h.session.model().settings.damping.kind == DampKind::Local);
  REQUIRE(h.deck("damp off\n"));
  CHECK(h.session.model().settings.damping.kind == DampKind::None);
  CHECK_FALSE(h.deck("damp local 1.5\n"));
  CHECK_FALSE(h.deck("damp 0.05 0\n"));
}

TEST_CASE("commands: a ball leaving the START box stops CYCLE, or is destroyed and counted", "[commands][domain]") {
  // One ball flying along +x at 9.9 m/s from x = 0.5 in a unit box, and one at rest: it crosses x = 1
  // in the 51st step (x = 0.995 after 50, 1.0049 after 51).
  const std::string scene = "prop kn 1e4 ks 1e4 dens 1000\nball 0.5 0.5 0.5 0.05\nball 0.2 0.2 0.2 0.05\n"
                            "init xvel 9.9 range id 1\ntstep 1e-3\n";
  {
    Harness h;   // the default: stop, with the ball, the face and the cycle; the model kept
    CHECK_FALSE(h.deck("start box 0 1 0 1 0 1\n" + scene + "cycle 100\n"));
    const std::string e = h.first_error_line();
    INFO(e);
    CHECK(e.starts_with("deck.dat:7: error: ball 1 left the box through x = 1 at cycle 51"));
    CHECK(e.find("START box ... destroy") != std::string::npos);
    CHECK(h.session.model().cycle == 51);
    CHECK(h.session.model().balls.size() == 2);
    CHECK(h.session.model().balls.x[trubal::test::at(h.session.model(), 1)] > 1);
  }
  {
    Harness h;   // destroy: deleted after the step it left in, counted, the energy carried out booked
    REQUIRE(h.deck("start box 0 1 0 1 0 1 destroy\n" + scene + "cycle 100\nprint info\n"));
    CHECK(h.out.str().find("1 ball left the box and was destroyed (1 since START)") != std::string::npos);
    CHECK(h.out.str().find("balls destroyed: 1 (they left the box)") != std::string::npos);
    const Model& m = h.session.model();
    CHECK(m.cycle == 100);
    REQUIRE(m.balls.size() == 1);
    CHECK(m.balls.id[0] == 2);
    CHECK(m.space.destroyed == 1);
    // Its kinetic energy, 1/2 m v^2, left as boundary work (nothing else did any).
    const double mass = 1000 * 4.0 / 3.0 * M_PI * 0.05 * 0.05 * 0.05;
    CHECK(m.energy.boundary_work == Approx(-0.5 * mass * 9.9 * 9.9).epsilon(1e-12));
  }
  {
    Harness h;   // per axis: y and z stop, x destroys
    REQUIRE(h.deck("start box 0 1 0 1 0 1 stop x destroy\n" + scene + "cycle 100\n"));
    CHECK(h.session.model().space.destroyed == 1);
    CHECK_FALSE(h.deck("start box 0 1 0 1 0 1 destroy y stop\n" + scene + "init xvel 0 yvel 9.9 range id 1\ncycle 100\n"));
    CHECK(h.first_error_line().find("left the box through y = 1 at cycle 51") != std::string::npos);
    Harness bad;
    CHECK_FALSE(bad.deck("start box 0 1 0 1 0 1 vanish\n"));
    CHECK(bad.first_error_line().starts_with("deck.dat:1: error: "));
  }
}

TEST_CASE("commands: PRINT counters gives one `name value` line per count, on the screen or in a file", "[commands]") {
  // An FCC block at rest, its balls just touching (no contact), a held pair pressed together (one
  // contact), and a fast ball leaving the box.
  TempDir dir;
  WorkingDir wd(dir.path());
  Harness h;
  REQUIRE(h.deck("start box -2 6 -2 6 -2 6 destroy\nprop kn 1e5 ks 1e5 fric 0.5 dens 1000\n"
                 "lattice fcc 1.0 4 4 4 origin 0 0 0\nball -1.5 -1.5 5 0.4 id 601\nball -1.5 -0.8 5 0.4 id 602\n"
                 "fix vel spin range id 601 602\n"
                 "ball 5.5 5.5 5.5 0.3 id 500\ninit zvel 50 range id 500\ncycle 300\nprint counters file c.txt\n"));
  const Counters c = read_counters(dir.path() / "c.txt");
  const Model& m = h.session.model();
  const PipelineCounters p = h.session.pipeline().counters();
  CHECK(counter(c, "cycle") == 300);
  CHECK(counter(c, "balls") == static_cast<double>(m.balls.size()));
  CHECK(counter(c, "balls_destroyed") == 1);   // ball 500 left through the top
  CHECK(counter(c, "contacts") == static_cast<double>(contact_count(m)));
  CHECK(counter(c, "contacts") == 1);   // the held pair
  CHECK(counter(c, "pair_list_rebuilds") == static_cast<double>(p.rebuilds));
  CHECK(counter(c, "pair_list_rebuilds") >= 1);
  CHECK(counter(c, "ranks") == 1);
  CHECK(counter(c, "threads") == 1);
  CHECK(counter(c, "decompositions") == 0);   // one serial thread: no decomposition
  CHECK(counter(c, "peak_mib") > 1);           // (the process's peak: its code alone is more than a MiB)
  // On the screen, the same lines; the file is said to be written.
  CHECK_THAT(h.out.str(), Catch::Contains("counters written to c.txt"));
  const std::size_t before = h.out.str().size();
  REQUIRE(h.deck("print counters\n"));
  // (But the peak memory, which the first PRINT may have raised.)
  Counters again = parse_counters(h.out.str().substr(before)), first = c;
  again.erase("peak_mib");
  first.erase("peak_mib");
  CHECK(again == first);
  // Bad input: the file and line of the command.
  CHECK_FALSE(h.deck("print counters now\n", "bad.dat"));
  CHECK_THAT(h.first_error_line(), Catch::StartsWith("bad.dat:1: error:"));
  Harness h2;
  CHECK_FALSE(h2.deck("start box 0 1 0 1 0 1\n\nprint counters file no/such/folder/c.txt\n", "bad.dat"));
  CHECK_THAT(h2.first_error_line(), Catch::StartsWith("bad.dat:3: error:"));
  CHECK_THAT(h2.first_error_line(), Catch::Contains("no/such/folder/c.txt"));
}
