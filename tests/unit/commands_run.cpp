// Commands that drive a run, through the real interpreter: SOLVE reaches equilibrium, APPLY and
// GRAV give the accelerations they should, TSTEP/FRAC set the step, DAMP sets its coefficients.
#include <catch2/catch.hpp>

#include <cmath>
#include <numbers>

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
