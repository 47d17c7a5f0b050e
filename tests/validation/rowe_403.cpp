// Rowe's triaxial test (doc/validation.md section 5), Cundall's 403-ball sample, run from the example
// deck as a user would, with Cundall's damping (lambda_min 0.05, f_min 0.5).
//
// What the peak must be. With all the inclined contacts sliding and the in-plane ones open, each
// contact force is N (n - f t): vertical N (1 + f) / sqrt 2, horizontal N (1 - f) / 2 per axis.
// The virial of the forces on the sample (sum F x over the membrane and platen forces, applied at
// ball centres) equals that of the contact forces; it gives F1 = 2 (1 + f) / (1 - f) p S d^2,
// S d^2 = sum over the membrane's cell faces normal to x of |x_ball - x_centre| (30 d^2 for the
// layer of 37, 66 d^2 for 76). So R = F1 / (A p) peaks at 2.56 S d^2 / A with A = 37 d^2, the union
// of the cells (the cross section MEMBRANE's forces load at exactly p): 2.56 x 30/37 = 2.076. Put
// another way, F1 / (S d^2 p) -- the ratio of the assembly's average vertical and lateral stresses,
// both from the virial -- peaks at Rowe's 2 tan(45 + phi_mu) = 2.56. The forces of a membrane act
// through the balls' centres whatever the area, so the smaller value is what this sample gives; a
// slower loading only removes the dashpots' share (see README, "Rowe's triaxial test").
#include "paths.hpp"
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include "../unit/interp_support.hpp"

using namespace trubal;
using namespace trubal::test;

TEST_CASE("validation: Rowe's triaxial test, 403 balls, peak stress ratio and a stable run", "[validation][rowe]") {
  TempDir dir;
  WorkingDir here(dir.path());
  std::string deck = slurp(std::string(TRUBAL_SOURCE_DIR) + "/examples/rowe403.dat");
  // Record often, so that the first row is at eps1 ~ 0 (the deck records every 10 cycles), and the
  // stress too: the average stress tensor of the contact forces (the virial, over the START box).
  const std::string recorded = "contacts sratio every 10 ";
  const auto at = deck.find(recorded);
  REQUIRE(at != std::string::npos);
  deck.replace(at, recorded.size(), "contacts sratio stress every 5 ");
  const auto plot = deck.find("\nplot ");
  if (plot != std::string::npos) deck.erase(plot + 1, deck.find('\n', plot + 1) - plot);
  Harness h;
  const bool ok = h.deck(deck, "rowe403.dat");
  INFO(h.err.str());
  REQUIRE(ok);   // a run that goes unstable stops the deck with an error
  CHECK(h.err.str().find("unstable") == std::string::npos);

  const auto& table = *h.session.history().tables().front();
  REQUIRE(table.columns[2] == "ratio");
  REQUIRE(table.columns[3] == "axial");
  auto column = [&](const std::string& name) {
    const auto c = std::find(table.columns.begin(), table.columns.end(), name);
    REQUIRE(c != table.columns.end());
    return static_cast<std::size_t>(c - table.columns.begin());
  };
  const std::size_t s11 = column("s11"), s22 = column("s22"), s33 = column("s33"), sratio = column("sratio");
  double peak = 0, eps_peak = 0, eps_last = 0, max_unbal = 0, virial_peak = 0;
  for (const auto& row : table.rows) {
    REQUIRE(std::isfinite(row[2]));
    if (row[2] > peak) peak = row[2], eps_peak = row[3];
    virial_peak = std::max(virial_peak, row[s33] / (0.5 * (row[s11] + row[s22])));
    // HIST sratio is that ratio (the contact stress over a volume of 1: the volume cancels).
    CHECK(row[sratio] == Approx(row[s33] / (0.5 * (row[s11] + row[s22]))).epsilon(1e-12));
    eps_last = row[3];
    if (row[3] > 0.002) max_unbal = std::max(max_unbal, row[4]);   // past the start-up wave
  }
  // The loading starts from the isotropic state: R ~ 1 at eps1 ~ 0. The first row is 5 cycles in
  // (eps1 ~ 4e-5): the platens start at full speed, and the wave that sends into the pack, about
  // sqrt(k m) v per contact, adds ~20% at once (it halves with the speed).
  CHECK(table.rows.front()[3] < 1e-4);
  CHECK(table.rows.front()[2] > 0.95);
  CHECK(table.rows.front()[2] < 1.3);
  // The deck goes to 10% axial strain.
  CHECK(eps_last == Approx(0.10).margin(0.005));
  // Rowe's 2 tan(45 + phi_mu) = 2 (1 + f) / (1 - f) = 2.5599 for f = tan 7 deg (his 2.56).
  const double closed_form = 2 * (1 + std::tan(7 * M_PI / 180)) / (1 - std::tan(7 * M_PI / 180));
  INFO("peak R " << peak << " at eps1 " << eps_peak << "; peak s33 / mean(s11, s22) " << virial_peak);
  // The peak, at small strain, within 3% of the closed form for this sample (2.56 x 30/37); measured
  // 2.057, -0.9%, the dashpots' share at this platen speed (README, "Rowe's triaxial test").
  CHECK(peak == Approx(closed_form * 30 / 37).epsilon(0.03));
  // The stress tensor trubal sums from the contact forces (HIST stress: sum of f (x) l over the
  // contacts; no area, no membrane cell, so the ratio needs no 30/37): with every inclined contact
  // sliding and the in-plane ones open, each contact alone has s33 / s11 = 2 (1 + f) / (1 - f), so its
  // s33 / mean(s11, s22) peaks at Rowe's 2.56. 5%: the sample is not wholly in that state at the
  // peak (2% of the contacts still stick there, and the platen balls, moved at a fixed speed, and
  // the membrane balls, with their spins fixed, are the pattern's edges); measured 2.475, -3.3%.
  CHECK(virial_peak == Approx(closed_form).epsilon(0.05));
  CHECK(eps_peak > 0.002);
  CHECK(eps_peak < 0.03);
  // Stable and quasi-static: past the start-up the balls stay near equilibrium (mean unbalanced
  // force ratio ~0.005).
  CHECK(max_unbal < 0.02);
}
