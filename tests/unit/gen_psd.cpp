// GEN with size distributions and a target porosity: the sample's grading against the one asked
// for, the porosity reached, the overlaps left, the same sample on every backend, and bad input.
#include <catch2/catch.hpp>

#include <fmt/format.h>

#include <cmath>
#include <numbers>

#include "gen/size_distribution.hpp"
#include "interp_support.hpp"

using namespace trubal;
using trubal::test::Harness;
using trubal::test::TempDir;

namespace {

std::vector<double> generated_radii(const Session& s) {
  std::vector<double> r;
  const Balls& b = s.model().balls;
  for (auto id : s.last_generated())
    for (std::size_t k = 0; k < b.size(); ++k)
      if (b.id[k] == id) { r.push_back(b.rad[k]); break; }
  return r;
}

double largest_grading_difference(const Session& s) {
  double worst = 0;
  for (const auto& row : compare_grading(*s.last_sizes(), generated_radii(s)))
    worst = std::max(worst, std::abs(row.sample - row.asked));
  return worst;
}

double porosity_of(const Session& s, double volume) {
  double solid = 0;
  for (double r : s.model().balls.rad) solid += 4.0 / 3.0 * std::numbers::pi * r * r * r;
  return 1 - solid / volume;
}

// The largest overlap of any pair over the smaller radius, every pair tried (periodic: nearest image).
double worst_overlap_every_pair(const Model& m) {
  const Balls& b = m.balls;
  const auto L = m.space.length();
  double worst = 0;
  for (std::size_t i = 0; i < b.size(); ++i)
    for (std::size_t j = i + 1; j < b.size(); ++j) {
      double d[3] = {b.x[j] - b.x[i], b.y[j] - b.y[i], b.z[j] - b.z[i]};
      for (int a = 0; a < 3; ++a)
        if (m.space.wraps(a)) d[a] -= L[a] * std::round(d[a] / L[a]);
      const double dist = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
      worst = std::max(worst, (b.rad[i] + b.rad[j] - dist) / std::min(b.rad[i], b.rad[j]));
    }
  return worst;
}

// Runs a deck that must fail; returns the error stream's first error line.
std::string deck_error(const std::string& deck) {
  Harness h;
  INFO("deck:\n" << deck);
  CHECK_FALSE(h.deck(deck));
  return h.first_error_line();
}

}  // namespace

TEST_CASE("gen psd: a sieve curve to a porosity in the periodic cell", "[gen]") {
  Harness h;
  REQUIRE(h.deck("start 0.012 0.012 0.012\n"
                 "gen porosity 0.4 psd sieve 0.0005 0 0.0008 20 0.001 50 0.0015 100 seed 3\n"));
  const Session& s = h.session;
  const std::size_t n = s.model().balls.size();
  INFO(h.out.str());
  REQUIRE(n > 2000);
  // The radii are scaled to the solid volume the porosity asks, so it is met to rounding.
  CHECK(porosity_of(s, std::pow(0.012, 3)) == Approx(0.4).margin(1e-9));
  CHECK_THAT(h.out.str(), Catch::Contains("porosity 0.4000"));
  // Stratified radii (one per 1/n slice of the distribution): the percent passing at a sieve is off
  // by about the mass share of the balls at a slice's edge, ~5/n (0.2% here), plus the common radius
  // scale (1 +- 1e-3) moving the curve by its slope times 1e-3 (~0.3%): 0.5 percent passing holds that,
  // and independent draws (~2% at this n) or a wrong density in an interval (~10%) fail it.
  CHECK(largest_grading_difference(s) < 0.5);
  // Every stage relaxed to overlaps within 1% of the smaller radius (pack.hpp).
  CHECK(worst_overlap_every_pair(s.model()) <= 0.0101);
  // Every centre in the cell.
  for (std::size_t k = 0; k < n; ++k) {
    CHECK(s.model().balls.x[k] >= 0);
    CHECK(s.model().balls.x[k] < 0.012);
  }
}

TEST_CASE("gen psd: normal, lognormal, uniform by volume by count, with their cut-offs", "[gen]") {
  for (const char* dist : {"normal 0.01 0.002", "lognormal 0.01 0.2", "volume 0.006 0.014",
                           "normal 0.01 0.004 cut 0.005 0.02"}) {
    Harness h;
    INFO(dist);
    REQUIRE(h.deck(fmt::format("start box 0 1 0 1 0 1\ngen 3000 psd {} seed 11\n", dist)));
    const Session& s = h.session;
    REQUIRE(s.model().balls.size() == 3000);
    const SizeDistribution& d = *s.last_sizes();
    for (double r : s.model().balls.rad) {
      CHECK(r >= d.lo);
      CHECK(r <= d.hi);
    }
    // As above: stratified radii, no rescaling (count mode): within 0.5 percent passing.
    CHECK(largest_grading_difference(s) < 0.5);
    // Whole balls inside the box.
    for (std::size_t k = 0; k < 3000; ++k) CHECK(s.model().balls.z[k] - s.model().balls.rad[k] >= 0);
  }
  // The defaults: mean -+ 3 sd, median e^-+3 sigma.
  Harness h;
  REQUIRE(h.deck("start box 0 1 0 1 0 1\ngen 10 psd lognormal 0.01 0.2\n"));
  CHECK(h.session.last_sizes()->lo == Approx(0.01 * std::exp(-0.6)).epsilon(1e-12));
}

TEST_CASE("gen psd: types share the mass as asked, each with the sample's grading", "[gen]") {
  Harness h;
  REQUIRE(h.deck("start box 0 1 0 1 0 1\ngen 4000 psd volume 0.005 0.015 types 1 0.7 2 0.3 seed 5\n"));
  const Balls& b = h.session.model().balls;
  double mass[3] = {0, 0, 0};
  for (std::size_t k = 0; k < b.size(); ++k) mass[b.type[k]] += std::pow(b.rad[k], 3);
  // Each ball goes to the type furthest below its share: a share is off by at most about one ball,
  // the largest 0.015^3 against a total of 4000 * ~0.01^3 (0.1%); 0.5% allows for the order.
  CHECK(mass[2] / (mass[1] + mass[2]) == Approx(0.3).margin(0.005));
}

TEST_CASE("gen psd: the same seed gives the same sample on every backend and thread count", "[gen][threads]") {
  TempDir dir;
  std::string first;
  for (const char* backend : {"serial", "threaded threads 2", "allpairs"}) {
    Harness h;
    const std::string file = fmt::format("{}/b.csv", dir.str());
    REQUIRE(h.deck(fmt::format("backend {}\nstart 0.008 0.008 0.008\n"
                               "gen porosity 0.42 psd uniform 0.0003 0.0005 seed 9\nprint balls file {}\n", backend, file)));
    const std::string text = trubal::test::slurp(file);
    REQUIRE(text.size() > 1000);
    if (first.empty()) first = text;
    else CHECK(text == first);   // byte for byte
  }
}

TEST_CASE("gen psd: PRINT psd shows both gradings and writes them as CSV", "[gen]") {
  TempDir dir;
  Harness h;
  const std::string file = dir.str() + "/psd.csv";
  REQUIRE(h.deck(fmt::format("start box 0 0.25 0 0.25 0 0.25\ngen porosity 0.55 psd sieve 0.01 0 0.02 40 0.03 100\n"
                             "print psd\nprint psd file {}\n", file)));
  CHECK_THAT(h.out.str(), Catch::Contains("largest difference:"));
  const auto lines = trubal::test::lines_of(trubal::test::slurp(file));
  REQUIRE(lines.size() == 4);
  CHECK(lines[0] == "diameter,passing_asked,passing_sample");
  CHECK(lines[2].starts_with("0.02,40,"));
}

TEST_CASE("gen psd: bad sizes and porosities are FILE:LINE errors that say what is wrong", "[gen][errors]") {
  CHECK_THAT(deck_error("start 1 1 1\ngen porosity 0.4 psd sieve 0.1 0 0.2 60 0.3 50 0.4 100\n"),
             Catch::StartsWith("deck.dat:2: error: GEN psd: the sieve curve is not monotone: 50% passes 0.3 but 60% "
                               "the smaller 0.2"));
  CHECK_THAT(deck_error("start 1 1 1\ngen porosity 0.4 psd sieve 0.1 0 0.2 120\n"),
             Catch::StartsWith("deck.dat:2: error: GEN psd: percent passing 120 at diameter 0.2 is outside 0..100"));
  CHECK_THAT(deck_error("start 1 1 1\ngen porosity 0.4 psd sieve 0.1 -5 0.2 100\n"),
             Catch::Contains("percent passing -5 at diameter 0.1 is outside 0..100"));
  CHECK_THAT(deck_error("start 1 1 1\ngen porosity 0.4 psd sieve 0.1 10 0.2 100\n"),
             Catch::Contains("must start at 0% passing"));
  CHECK_THAT(deck_error("start 1 1 1\ngen porosity 0.4 psd sieve 0.2 0 0.1 100\n"),
             Catch::Contains("sieve diameters must increase"));
  CHECK_THAT(deck_error("start 1 1 1\ngen porosity 1.2 0.01 0.02\n"),
             Catch::StartsWith("deck.dat:2: error: GEN: porosity 1.2 is not between 0 and 1"));
  CHECK_THAT(deck_error("start 1 1 1\ngen porosity 0.2 0.01 0.01\n"),
             Catch::Contains("cannot be reached with balls of one size"));
  CHECK_THAT(deck_error("start box 0 1 0 1 0 1\ngen porosity 0.4 0.6 0.7\n"),
             Catch::Contains("does not fit in the region"));
  CHECK_THAT(deck_error("start box 0 1 0 1 0 1\ngen porosity 0.9999 0.3 0.4\n"),
             Catch::Contains("too small for porosity"));
  CHECK_THAT(deck_error("start 1 1 1\ngen porosity 0.4 psd normal 0.01 0.005\n"),
             Catch::Contains("give `cut rlo rhi`"));
  CHECK_THAT(deck_error("start 1 1 1\ngen 10 0.01 0.02 types 1 0.5 2 0.6\n"),
             Catch::Contains("must add up to 1"));
  CHECK_THAT(deck_error("start 1 1 1\ngen porosity 0.4 0.01 0.02 range sphere 0.5 0.5 0.5 0.3\n"),
             Catch::Contains("the region must be a box"));
}

TEST_CASE("gen psd: a porosity beyond reach stops with the porosity reached, the balls kept", "[gen][errors]") {
  // Balls of nearly one size cannot be packed to porosity 0.28 by moving them apart (random close
  // packing of equal spheres is near 0.36): GEN stops where the growth no longer relaxes.
  Harness h;
  CHECK_FALSE(h.deck("start 0.006 0.006 0.006\ngen porosity 0.28 psd uniform 0.0005 0.00052 seed 2\n"));
  const std::string e = h.first_error_line();
  INFO(e);
  CHECK(e.starts_with("deck.dat:2: error: GEN: porosity 0.28 not reached: the balls stopped at porosity"));
  const double reached = porosity_of(h.session, std::pow(0.006, 3));
  CHECK(reached > 0.30);   // well short of the target
  CHECK(reached < 0.50);   // but grown well past the start (0.75)
  CHECK_THAT(e, Catch::Contains(fmt::format("the balls are kept at {:.4f}", reached)));
  CHECK(worst_overlap_every_pair(h.session.model()) <= 0.0101);
}

TEST_CASE("gen psd: balls of one size pass a sieve of their diameter, as asked", "[gen]") {
  Harness h;
  REQUIRE(h.deck("start 0.01 0.01 0.01\ngen porosity 0.6 0.0005 0.0005\nprint psd\n"));
  // One size: the asked curve and the sample's are both 100% at d = 2 r (a step); a table that put
  // the step just after the sieve would show a difference of 100.
  CHECK(largest_grading_difference(h.session) == Approx(0).margin(1e-9));
  CHECK_THAT(h.out.str(), Catch::Contains("largest difference: 0.000 percent passing"));
}
