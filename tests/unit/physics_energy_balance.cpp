// The energy balance at the step's force pass (doc/physics.md "Energy"): every term taken at the
// same time, the works up to that time, so that what is left is the integration's error, which
// falls with the step; and the warning a CYCLE gives when that error is large.
#include "paths.hpp"
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "interp_support.hpp"
#include "physics/measure.hpp"

using namespace trubal;
using namespace trubal::test;

namespace {

// From a history of `energy` recorded every cycle: the largest distance of the balance from its
// first row over the largest energy in play so far (kinetic, strain, and the magnitudes of the
// changes of the potential and of the works since the first row), the largest over the rows
// (`so_far`); and the largest distance over the largest energy in play of all rows (`moved`, what
// CYCLE's warning reads).
struct Drift {
  double so_far = 0, moved = 0;
};
Drift balance_drift(const HistoryTable& t) {
  auto col = [&](const char* name) {
    const auto it = std::find(t.columns.begin(), t.columns.end(), name);
    REQUIRE(it != t.columns.end());
    return static_cast<std::size_t>(it - t.columns.begin());
  };
  const std::size_t ke = col("ke"), se = col("strain_energy"), fw = col("friction_work"), dw = col("damping_work"),
                    bw = col("boundary_work"), pe = col("potential");
  REQUIRE(!t.rows.empty());
  const auto& r0 = t.rows.front();
  auto balance = [&](const std::vector<double>& r) { return r[ke] + r[se] + r[fw] + r[dw] + r[pe] - r[bw]; };
  double in_play = 0, error = 0;
  Drift d;
  for (const auto& r : t.rows) {
    in_play = std::max(in_play, r[ke] + r[se] + std::abs(r[pe] - r0[pe]) +
                                    std::abs(r[fw] + r[dw] - r0[fw] - r0[dw]) + std::abs(r[bw] - r0[bw]));
    const double e = std::abs(balance(r) - balance(r0));
    error = std::max(error, e);
    if (in_play > 0) d.so_far = std::max(d.so_far, e / in_play);
  }
  d.moved = in_play > 0 ? error / in_play : 0;
  return d;
}

// Two balls that just touch, pressed together by APPLY (as Rowe's platens are), head-on: a linear
// spring with the damping given, no shear, so the balance has only the step's own error left (and
// where undamped they part for a moment at the top of each swing, that contact's).
Drift pressed_pair_drift(double frac, const std::string& damp) {
  Harness h;
  REQUIRE(h.deck("start box -1 1 -1 1 -1 1\nprop kn 1e5 ks 1e5 fric 0.5 dens 2650\n"
                 "ball -0.01 0 0 0.01 id 1\nball 0.01 0 0 0.01 id 2\n"
                 "apply xforce 1 range id 1\napply xforce -1 range id 2\n" +
                 damp + "\nfrac " + std::to_string(frac) + "\nhist energy every 1\ncycle " +
                 std::to_string(static_cast<int>(240 / frac)) + "\n"));
  return balance_drift(*h.session.history().tables().front());
}

}  // namespace

TEST_CASE("energy: a pressed, damped pair balances to the step's error, which falls with FRAC", "[physics][energy]") {
  // Each step's work of the applied loads and of the damping in the law of motion, F(t).v(t) dt,
  // lies half after t (the velocity v(t + dt/2) moves the balls on): counted whole, the balance at
  // the step's force pass was off by that half step, a fixed fraction of the energy of the first
  // steps whatever the step (12% to 16% on Rowe's consolidation from FRAC 0.8 to 0.1; here, with
  // the staggered terms PRINT energy took, 20% at FRAC 0.8 and 1.5% to 2.6% at FRAC 0.1).
  for (const std::string damp : {"damp mass 20", "damp local 0.7", "damp off"}) {
    INFO(damp);
    const Drift coarse = pressed_pair_drift(0.8, damp), fine = pressed_pair_drift(0.1, damp);
    CAPTURE(coarse.so_far, fine.so_far);
    CHECK(coarse.so_far < 0.01);   // measured 0.4%, 1e-12 and 0.6% (the parting at the top of a swing)
    CHECK(fine.so_far < 1e-5);     // measured 9e-13, 1e-11 and 1.7e-6
  }
  // With the stiffness dashpot (moderate, and Rowe's DAMP 0.05 0.5, here 34 times critical) the law
  // of motion charges the dashpots as it charges every force, so the balance closes to rounding too
  // (charged with V(t - dt/2)^2 dt, a quarter of the last step's taken as after t, it was off by
  // 2.4% and 5.4% at FRAC 0.8, an error that fell only as the step).
  for (const std::string damp : {"damp mass 20 stiff 2e-5", "damp 0.05 0.5"}) {
    INFO(damp);
    const Drift coarse = pressed_pair_drift(0.8, damp), fine = pressed_pair_drift(0.1, damp);
    CAPTURE(coarse.so_far, fine.so_far);
    CHECK(coarse.so_far < 1e-9);
    CHECK(fine.so_far < 1e-9);
  }
}

TEST_CASE("energy: PRINT energy and the step's guard take every term at the force pass", "[physics][energy]") {
  // A free fall: kinetic m v(t-dt/2).v(t+dt/2)/2 and -m g z(t) balance exactly (central differences
  // conserve that sum for a constant force), however coarse the step; the staggered terms (kinetic
  // at t - dt/2, the potential at the mid-point) were off by m g^2 dt^2 / 8 each step's sample.
  Harness h;
  REQUIRE(h.deck("start box -10 10 -10 10 -100 10\nprop kn 1e5 dens 1000\nball 0 0 0 0.1 id 1\n"
                 "grav 0 0 -10\ntstep 0.05\ncycle 37\n"));
  const EnergyReport e = energy(h.session.model());
  CHECK(e.at_step);
  const Balls& b = h.session.model().balls;
  const double m = b.mass[0], dt = 0.05, v_after = b.vz[0], v_before = v_after + 10 * dt;
  CHECK(e.kinetic_translation == Approx(0.5 * m * v_before * v_after).epsilon(1e-12));
  CHECK(e.potential == Approx(m * 10 * (b.z[0] - v_after * dt)).epsilon(1e-12));   // at z(t) = z now - v dt
  // The first cycle's balance (at rest, z = 0) is 0: it must stay 0 to rounding.
  CHECK(std::abs(e.total()) < 1e-12 * m * 10 * std::abs(b.z[0]));
  // An edit of the balls leaves the state as it is: kinetic from the velocities now.
  REQUIRE(h.deck("init zvel -1 range id 1\n"));
  const EnergyReport edited = energy(h.session.model());
  CHECK_FALSE(edited.at_step);
  CHECK(edited.kinetic_translation == Approx(0.5 * m).epsilon(1e-12));
  CHECK(edited.potential == Approx(m * 10 * b.z[0]).epsilon(1e-12));
}

TEST_CASE("energy: the friction work closes the balance of a sliding contact", "[physics][energy]") {
  // A ball pressed onto a plane wall and pushed along it harder than friction holds, its spin
  // fixed, no damping: it slides. The friction work is the slip times the mean of the shear force
  // before and after the step, the trapezoid rule of the law of motion, so the balance closes to
  // rounding; as the cap times the slip it over-counted each step that entered sliding by
  // (cap - force before)(trial - cap) / (2 k_s): 7.7e-4 of the energy in play here.
  for (const char* push : {"700", "900"}) {
    INFO(push);
    Harness h;
    REQUIRE(h.deck(std::string("start box -100 100 -10 10 -10 10\nprop kn 1e6 ks 1e6 fric 0.3 dens 1000\n"
                               "wall id 1 plane 0 0 0 0 0 1\nball 0 0 0.999 1 id 2\nfix spin range id 2\n"
                               "apply zforce -2000 xforce ") +
                   push + " range id 2\nhist energy every 1\ncycle 300\n"));
    const HistoryTable& t = *h.session.history().tables().front();
    REQUIRE(t.rows.back()[4] > 100);   // friction_work: it slid (about 400 and 500 J)
    const double drift = balance_drift(t).so_far;
    CAPTURE(drift);
    CHECK(drift < 1e-10);   // measured 6e-14
  }
}

TEST_CASE("energy: a CYCLE whose balance is off by more than 1% says so once, with a FRAC that holds it",
          "[physics][energy]") {
  const std::string examples = std::string(TRUBAL_TEST_DIR) + "/../examples/";
  TempDir dir;
  WorkingDir here(dir.path());
  // Two balls meeting head-on at the default FRAC 0.8: about four steps in contact, and they part
  // 9% faster than they met (the balance is off by 15% of the energy that moved, which counts the
  // kinetic term's magnitude: it is negative in the step the velocities turn).
  const std::string impact =
      "start box -1 1 -1 1 -1 1\nprop kn 1e5 ks 1e5 fric 20 dens 2650\nball -0.0105 0 0 0.01 id 1\n"
      "ball 0.0105 0 0 0.01 id 2\ninit xvel 0.5 range id 1\ninit xvel -0.5 range id 2\n";
  {
    Harness h;
    REQUIRE(h.deck(impact + "cycle 400\n"));
    const std::string err = h.err.str();
    CHECK_THAT(err, Catch::Contains("energy balance of this CYCLE was off by 14.8% of the energy that moved"));
    CHECK_THAT(err, Catch::Contains("FRAC 0.15 (now 0.8) would hold it to 1%"));
    const auto first = err.find("energy balance"), second = err.find("energy balance", first + 1);
    CHECK(second == std::string::npos);   // once for the CYCLE
    // And the FRAC it names does hold it (error measured 0.64%): no warning, the balls part at
    // the speed they met with to 0.5% (measured 0.27%).
    Harness g;
    REQUIRE(g.deck(impact + "frac 0.15\ncycle 2133\n"));
    CHECK(g.err.str().find("energy balance") == std::string::npos);
    CHECK(g.session.model().balls.vx[1] == Approx(0.5).epsilon(5e-3));
  }
  {
    // The example itself holds its claim.
    Harness h;
    REQUIRE(h.deck("call " + examples + "impact.dat\n"));
    CHECK(h.err.str().find("energy balance") == std::string::npos);
    CHECK(h.session.model().balls.vx[1] == Approx(0.5).epsilon(1e-3));
    CHECK(h.session.model().balls.vx[0] == Approx(-0.5).epsilon(1e-3));
  }
  // Quasi-static decks at the default FRAC stay well inside it (measured 0.4%, 0.28%, 0.19% of the
  // energy that moved): no warning.
  for (const char* deck : {"rowe403.dat", "fcc_axisymmetric.dat", "fcc_plane_strain.dat"}) {
    INFO(deck);
    Harness h;
    REQUIRE(h.deck(std::string("call ") + examples + deck + "\n"));
    CHECK(h.err.str().find("energy balance") == std::string::npos);
  }
}

TEST_CASE("energy: a dashpot's work is booked to second order where a contact starts and ends",
          "[physics][energy]") {
  // When a contact forms, its dashpot force jumps to c V. Booked as c V(t - dt/2)^2 dt for the whole
  // step, with a fixed quarter of it after t, the balance was off after each impact by a fraction
  // of the step (3.9e-3 at FRAC 0.02, 1.9e-3 at FRAC 0.01: first order). Now the law of motion
  // charges the dashpots with their force times the balls' velocities, as every force.
  auto impact_error = [](double frac, const std::string& scene) {
    Harness h;
    REQUIRE(h.deck(scene + "frac " + std::to_string(frac) + "\nhist energy every 1\ncycle " +
                   std::to_string(static_cast<int>(8 / frac)) + "\n"));
    return balance_drift(*h.session.history().tables().front()).moved;
  };
  const std::string pair =
      "start box -1 1 -1 1 -1 1\nprop kn 1e5 ks 1e5 fric 20 dens 2650 rest 0.5\nball -0.0105 0 0 0.01 id 1\n"
      "ball 0.0105 0 0 0.01 id 2\ninit xvel 0.5 yvel 0.2 range id 1\ninit xvel -0.5 range id 2\n";
  const std::string wall =
      "start box -1 1 -1 1 -1 1\nprop kn 1e5 ks 1e5 fric 20 dens 2650 rest 0.5\nwall plane 0 0 0 0 0 1\n"
      "ball 0 0 0.0105 0.01 id 1\ninit zvel -0.5 xvel 0.3 range id 1\n";
  for (const std::string& scene : {pair, wall}) {
    INFO(scene);
    const double coarse = impact_error(0.02, scene), fine = impact_error(0.01, scene);
    CAPTURE(coarse, fine);
    CHECK(coarse / fine > 3.5);   // second order: 4 (measured 3.7 and 12.6; before, 2.0 and 2.0)
    CHECK(fine < 3e-5);           // measured 1.9e-5 and 2.5e-6 (before, 2.2e-3 and 1.2e-3)
  }
  // The FRAC CYCLE names assumes the balance's error falls as the step squared: it now holds. (At
  // FRAC 0.8 it named 0.14, where the balance was still 3% off; at FRAC 0.1 it named 0.048: 1.07%.)
  for (const char* frac : {"0.8", "0.3"}) {
    INFO(frac);
    Harness h;
    REQUIRE(h.deck(pair + "frac " + frac + "\ncycle " + std::to_string(static_cast<int>(8 / std::stod(frac))) + "\n"));
    const std::string err = h.err.str();
    const auto at = err.find("; FRAC ");
    REQUIRE(at != std::string::npos);
    const double named = std::stod(err.substr(at + 7));
    CAPTURE(err, named);
    Harness g;
    REQUIRE(g.deck(pair + "frac " + std::to_string(named) + "\ncycle " + std::to_string(static_cast<int>(8 / named)) + "\n"));
    CHECK(g.err.str().find("energy balance") == std::string::npos);
    CHECK(impact_error(named, pair) < 0.01);
  }
}
