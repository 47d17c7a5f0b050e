// The sizes GEN draws: a distribution of radii by number (uniform, normal, lognormal), by mass
// (uniform by volume), or a sieve curve (diameter against percent passing by mass, a lab report's
// grading). Mass means solid volume: one grain density.
#pragma once

#include <array>
#include <string>
#include <vector>

namespace trubal {

struct SizeDistribution {
  enum class Kind { Uniform, Volume, Normal, Lognormal, Sieve };
  Kind kind = Kind::Uniform;
  // uniform, volume: a = rlo, b = rhi. normal: a = mean radius, b = standard deviation.
  // lognormal: a = median radius, b = standard deviation of ln r.
  double a = 0, b = 0;
  double lo = 0, hi = 0;              // radius cut-offs (set by check() where not given)
  std::vector<double> diameter, passing;   // sieve: ascending diameters, percent passing (0..100)
  std::string describe() const;
};

// Fills in default cut-offs and checks the numbers; throws std::runtime_error saying what is
// wrong (a sieve curve that falls, percentages outside 0..100, ...).
void check(SizeDistribution& d);

// The distribution tabulated for drawing: the number and mass fractions below each of a fine grid
// of radii (nodes at every sieve diameter), so that drawing is one search and one interpolation.
class SizeTable {
 public:
  explicit SizeTable(const SizeDistribution& d);
  // The radius with a fraction u in [0, 1) of the balls (by number) below it.
  double radius(double u) const;
  // Percent passing by mass of a sieve of diameter d, as asked.
  double passing(double diameter) const;
  double mean_volume() const { return mean_volume_; }   // of one ball, 4/3 pi E[r^3]
  double smallest() const { return r_.front(); }
  double largest() const { return r_.back(); }

 private:
  std::vector<double> r_, number_, mass_;   // number_, mass_: fractions below r_[k], 0 .. 1
  double mean_volume_ = 0;
};

// The grading of a set of balls: percent passing by mass (solid volume) of a sieve of diameter d,
// a ball passing when its diameter is at most d.
class Grading {
 public:
  explicit Grading(std::vector<double> radii);
  double passing(double diameter) const;
  bool empty() const { return r_.empty(); }

 private:
  std::vector<double> r_, below_;   // sorted radii; volume fraction of balls up to each
};

// The diameters PRINT psd compares at: the sieves, or 21 spaced evenly in log d over the range.
std::vector<double> grading_diameters(const SizeDistribution& d);

// The two gradings side by side at those diameters: percent passing asked and of the balls.
struct GradingRow { double diameter, asked, sample; };
std::vector<GradingRow> compare_grading(const SizeDistribution& d, const std::vector<double>& radii);

// GEN's hint where the radii are larger than the space they are to fill (`extent`: its edges): the
// sizes were likely typed in another unit (millimetres) than the space's (metres). "" otherwise.
std::string radius_unit_hint(double rlo, double rhi, const std::array<double, 3>& extent);

}  // namespace trubal
