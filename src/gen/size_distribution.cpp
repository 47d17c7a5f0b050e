#include "gen/size_distribution.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include <fmt/format.h>

namespace trubal {

namespace {

[[noreturn]] void bad(const std::string& what) { throw std::runtime_error(fmt::format("GEN psd: {}", what)); }

// Nodes per piece of the table (a sieve curve: per interval between sieves). Drawn radii are
// linear interpolation between nodes a ratio (hi/lo)^(1/2048) apart: far finer than any grading.
constexpr int kNodes = 2048;

}  // namespace

std::string SizeDistribution::describe() const {
  switch (kind) {
    case Kind::Uniform: return fmt::format("radius uniform in [{:g}, {:g}]", lo, hi);
    case Kind::Volume: return fmt::format("uniform by volume, radius [{:g}, {:g}]", lo, hi);
    case Kind::Normal: return fmt::format("normal radius, mean {:g} sd {:g}, cut [{:g}, {:g}]", a, b, lo, hi);
    case Kind::Lognormal: return fmt::format("lognormal radius, median {:g} sigma {:g}, cut [{:g}, {:g}]", a, b, lo, hi);
    case Kind::Sieve: return fmt::format("sieve curve of {} points, diameter {:g} to {:g}", diameter.size(), 2 * lo, 2 * hi);
  }
  return {};
}

void check(SizeDistribution& d) {
  using K = SizeDistribution::Kind;
  const bool cut = d.lo != 0 || d.hi != 0;
  switch (d.kind) {
    case K::Uniform:
    case K::Volume:
      if (!(d.a > 0) || d.b < d.a) bad(fmt::format("the radii must satisfy 0 < rlo <= rhi, got {:g} and {:g}", d.a, d.b));
      d.lo = d.a;
      d.hi = d.b;
      return;
    case K::Normal:
      if (!(d.a > 0) || !(d.b > 0)) bad(fmt::format("normal needs a positive mean and sd, got {:g} and {:g}", d.a, d.b));
      if (!cut) {
        d.lo = d.a - 3 * d.b;
        d.hi = d.a + 3 * d.b;
        if (!(d.lo > 0))
          bad(fmt::format("the default lower cut-off, mean - 3 sd = {:g}, is not a radius: give `cut rlo rhi`", d.lo));
      }
      break;
    case K::Lognormal:
      if (!(d.a > 0) || !(d.b > 0)) bad(fmt::format("lognormal needs a positive median and sigma, got {:g} and {:g}", d.a, d.b));
      if (!cut) {
        d.lo = d.a * std::exp(-3 * d.b);
        d.hi = d.a * std::exp(3 * d.b);
      }
      break;
    case K::Sieve: {
      const auto& D = d.diameter;
      const auto& P = d.passing;
      if (D.size() < 2 || D.size() != P.size()) bad("a sieve curve needs at least two points (diameter, percent passing)");
      for (std::size_t k = 0; k < D.size(); ++k) {
        if (!(D[k] > 0)) bad(fmt::format("sieve diameter {:g} (point {}) is not positive", D[k], k + 1));
        if (!(P[k] >= 0 && P[k] <= 100))
          bad(fmt::format("percent passing {:g} at diameter {:g} is outside 0..100", P[k], D[k]));
        if (k > 0 && !(D[k] > D[k - 1]))
          bad(fmt::format("sieve diameters must increase: {:g} (point {}) follows {:g}", D[k], k + 1, D[k - 1]));
        if (k > 0 && P[k] < P[k - 1])
          bad(fmt::format("the sieve curve is not monotone: {:g}% passes {:g} but {:g}% the smaller {:g}", P[k], D[k],
                          P[k - 1], D[k - 1]));
      }
      if (P.front() != 0)
        bad(fmt::format("the curve must start at 0% passing (the smallest size), it starts at {:g}% at {:g}: add a "
                        "point below it",
                        P.front(), D.front()));
      if (P.back() != 100)
        bad(fmt::format("the curve must end at 100% passing (the largest size), it ends at {:g}% at {:g}", P.back(),
                        D.back()));
      std::size_t first = 0, last = D.size() - 1;
      while (P[first + 1] == 0) ++first;
      while (P[last - 1] == 100) --last;
      d.lo = D[first] / 2;
      d.hi = D[last] / 2;
      return;
    }
  }
  if (!(d.lo > 0) || !(d.hi > d.lo)) bad(fmt::format("the cut-offs must satisfy 0 < rlo < rhi, got {:g} and {:g}", d.lo, d.hi));
}

SizeTable::SizeTable(const SizeDistribution& d) {
  using K = SizeDistribution::Kind;
  if (d.hi == d.lo) {   // one size
    r_ = {d.lo, d.lo};
    number_ = {0, 1};
    mass_ = {0, 1};
    mean_volume_ = 4.0 / 3.0 * std::numbers::pi * d.lo * d.lo * d.lo;
    return;
  }
  // Pieces [r0, r1] with a number density on each: one for the analytic kinds, one per sieve interval.
  struct Piece { double r0, r1, weight; };
  std::vector<Piece> pieces;
  if (d.kind == K::Sieve) {
    for (std::size_t k = 0; k + 1 < d.diameter.size(); ++k) {
      const double r0 = d.diameter[k] / 2, r1 = d.diameter[k + 1] / 2;
      if (r1 <= d.lo || r0 >= d.hi) continue;
      // Mass uniform in log d within the interval (percent passing linear in log d, as a grading is
      // drawn): mass density dp / (ln(r1/r0) r), number density that over r^3.
      pieces.push_back({r0, r1, (d.passing[k + 1] - d.passing[k]) / std::log(r1 / r0)});
    }
  } else {
    pieces.push_back({d.lo, d.hi, 1});
  }
  auto density = [&](double r, double weight) {
    switch (d.kind) {
      case K::Uniform: return 1.0;
      case K::Volume: return 1 / (r * r * r);   // mass uniform in r
      case K::Normal: { const double z = (r - d.a) / d.b; return std::exp(-0.5 * z * z); }
      case K::Lognormal: { const double z = std::log(r / d.a) / d.b; return std::exp(-0.5 * z * z) / r; }
      case K::Sieve: return weight / (r * r * r * r);
    }
    return 0.0;
  };
  for (const auto& p : pieces) {
    for (int k = r_.empty() ? 0 : 1; k <= kNodes; ++k) {
      // Log-spaced nodes; the ends exactly the piece's.
      const double r = k == kNodes ? p.r1 : p.r0 * std::pow(p.r1 / p.r0, static_cast<double>(k) / kNodes);
      r_.push_back(r);
    }
  }
  // Trapezoid sums of the number and mass densities, cell by cell; a sieve cell takes the density of
  // the piece it lies in (its left node may be the previous piece's end).
  number_.assign(r_.size(), 0);
  mass_.assign(r_.size(), 0);
  std::size_t piece = 0;
  for (std::size_t k = 1; k < r_.size(); ++k) {
    while (piece + 1 < pieces.size() && r_[k - 1] >= pieces[piece].r1) ++piece;
    const double w = pieces[piece].weight;
    const double f0 = density(r_[k - 1], w), f1 = density(r_[k], w), h = r_[k] - r_[k - 1];
    const double r0 = r_[k - 1], r1 = r_[k];
    number_[k] = number_[k - 1] + 0.5 * h * (f0 + f1);
    mass_[k] = mass_[k - 1] + 0.5 * h * (f0 * r0 * r0 * r0 + f1 * r1 * r1 * r1);
  }
  const double n = number_.back(), m = mass_.back();
  if (!(n > 0) || !(m > 0)) bad("the distribution holds no balls between its cut-offs");
  for (auto& v : number_) v /= n;
  for (auto& v : mass_) v /= m;
  mean_volume_ = 4.0 / 3.0 * std::numbers::pi * m / n;
}

double SizeTable::radius(double u) const {
  auto it = std::upper_bound(number_.begin(), number_.end(), u);
  if (it == number_.end()) return r_.back();
  const std::size_t k = static_cast<std::size_t>(it - number_.begin());
  if (k == 0) return r_.front();
  const double f0 = number_[k - 1], f1 = number_[k];
  return r_[k - 1] + (r_[k] - r_[k - 1]) * (u - f0) / (f1 - f0);
}

double SizeTable::passing(double diameter) const {
  const double r = diameter / 2;
  if (r >= r_.back()) return 100;   // first: balls of one size pass a sieve of their diameter
  if (r <= r_.front()) return 0;
  auto it = std::upper_bound(r_.begin(), r_.end(), r);
  const std::size_t k = static_cast<std::size_t>(it - r_.begin());
  return 100 * (mass_[k - 1] + (mass_[k] - mass_[k - 1]) * (r - r_[k - 1]) / (r_[k] - r_[k - 1]));
}

Grading::Grading(std::vector<double> radii) : r_(std::move(radii)) {
  std::sort(r_.begin(), r_.end());
  below_.resize(r_.size());
  double sum = 0;
  for (std::size_t k = 0; k < r_.size(); ++k) below_[k] = sum += r_[k] * r_[k] * r_[k];
  for (auto& v : below_) v /= sum;
}

double Grading::passing(double diameter) const {
  auto it = std::upper_bound(r_.begin(), r_.end(), diameter / 2);
  if (it == r_.begin()) return 0;
  return 100 * below_[static_cast<std::size_t>(it - r_.begin()) - 1];
}

std::vector<double> grading_diameters(const SizeDistribution& d) {
  if (d.kind == SizeDistribution::Kind::Sieve) return d.diameter;
  std::vector<double> out;
  if (d.hi == d.lo) return {2 * d.lo};
  for (int k = 0; k <= 20; ++k) out.push_back(2 * d.lo * std::pow(d.hi / d.lo, k / 20.0));
  return out;
}

std::vector<GradingRow> compare_grading(const SizeDistribution& d, const std::vector<double>& radii) {
  const SizeTable table(d);
  const Grading sample(radii);
  std::vector<GradingRow> rows;
  for (double D : grading_diameters(d))
    rows.push_back({D, d.kind == SizeDistribution::Kind::Sieve ? d.passing[rows.size()] : table.passing(D),
                    sample.passing(D)});
  return rows;
}

std::string radius_unit_hint(double rlo, double rhi, const std::array<double, 3>& extent) {
  const double narrowest = std::min({extent[0], extent[1], extent[2]});
  if (!(rlo > narrowest)) return {};
  const std::string radii = rlo == rhi ? fmt::format("{:g}", rlo) : fmt::format("{:g} to {:g}", rlo, rhi);
  return fmt::format("; the radii ({}) are larger than the space ({:g} wide): sizes in another unit? trubal "
                     "has no units of its own; in SI, as in the examples, a radius of 2 mm is 0.002",
                     radii, narrowest);
}

}  // namespace trubal
