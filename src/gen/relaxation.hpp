// Radius expansion's relaxation (GEN porosity, gen/pack.cpp): the balls being grown are moved
// apart until their overlaps are small, the model's balls held fixed.
#pragma once

#include <array>
#include <memory>
#include <vector>

#include "model/model.hpp"

namespace trubal {

// Where the balls go: the START box or periodic space cut by the range's x, y, z intervals. On a
// bounded axis (the box's, or one the range cuts) balls lie wholly inside; on a periodic one the
// centres anywhere in the period.
struct Region {
  std::array<double, 3> lo{}, hi{};
  std::array<bool, 3> bounded{};
  double volume() const { return (hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]); }
};

// Relaxation limits: a stage's overlaps must fall to this fraction of the smaller radius.
constexpr double kOverlapTolerance = 0.01;

// Radius expansion's relaxation: the new balls (radii scale * r) are moved apart, pair by pair in a
// fixed order (Gauss-Seidel: each pair's overlap removed, shared in inverse proportion to the
// balls' volumes; the model's balls do not move), until no overlap is more than kOverlapTolerance
// of the smaller radius. Returns the sweeps taken, or -1 if the stage did not relax in `most`.
class Relaxation {
 public:
  // balls: x y z r (r the final radius), moved in place; g and model outlive this.
  Relaxation(const Model& model, const Region& g, std::vector<std::array<double, 4>>& balls);
  ~Relaxation();
  Relaxation(const Relaxation&) = delete;
  Relaxation& operator=(const Relaxation&) = delete;
  // Relaxes the balls at radii scale * r in at most `most` sweeps: the sweeps taken, or -1.
  int relax(double scale, int most);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace trubal
