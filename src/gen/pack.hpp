// GEN's samples from a size distribution: n balls placed at random without overlap, or as many as
// a target porosity needs, by radius expansion (placed small, grown in stages, each relaxed by
// moving the balls apart until no overlap is more than a tolerance).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "gen/relaxation.hpp"
#include "gen/size_distribution.hpp"
#include "model/model.hpp"
#include "model/range.hpp"

namespace trubal {

struct PackRequest {
  SizeDistribution sizes;        // checked
  std::size_t count = 0;         // n balls; 0: as many as the porosity needs
  double porosity = -1;          // target, with count 0
  std::uint64_t seed = 0;
  Range range;
  int type = 1;                  // the type ranges see (the balls' own types are assigned after)
};

struct PackResult {
  std::vector<std::array<double, 4>> balls;   // x y z r, largest first
  std::size_t asked = 0;          // balls the request needs
  double volume = 0;              // of the region (porosity only)
  double porosity = -1;           // reached (porosity only)
  bool reached = true;            // the target porosity was reached
  bool interrupted = false;       // Ctrl-C
  int stages = 0;
  std::int64_t sweeps = 0;
};

// Radius expansion's limits: a stage must relax (gen/relaxation.hpp) within kStageSweeps sweeps;
// all stages together may take kTotalSweeps.
constexpr int kStageSweeps = 150;
constexpr std::int64_t kTotalSweeps = 2000;

// Throws std::runtime_error for a request that cannot be met at all (a porosity outside (0, 1),
// a region too small for one ball, balls too large for the region).
PackResult pack(const Model& model, const PackRequest& request);

}  // namespace trubal
