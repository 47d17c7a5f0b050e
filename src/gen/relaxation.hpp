// Radius expansion's relaxation (GEN porosity, gen/pack.cpp): the balls being grown are moved
// apart until their overlaps are small, the model's balls held fixed.
#pragma once

#include <array>
#include <memory>
#include <vector>

#include "gen/region.hpp"
#include "model/model.hpp"

namespace trubal {

// Relaxation limits: a stage's overlaps must fall to this fraction of the smaller radius.
constexpr double kOverlapTolerance = 0.01;

// Radius expansion's relaxation: the new balls (radii scale * r) are moved apart, pair by pair in a
// fixed order (Gauss-Seidel: each pair's overlap removed, shared in inverse proportion to the
// balls' volumes; the model's balls do not move), each ball then moved back inside the region (its
// faces, cylinders and walls), until no overlap is more than kOverlapTolerance of the smaller radius
// and no ball crosses the region's bounds by more than that of its radius. Returns the sweeps taken, or -1 if the stage did not relax in `most`.
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
