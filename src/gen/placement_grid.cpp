#include "gen/placement_grid.hpp"

#include <algorithm>
#include <cmath>

namespace trubal {

namespace {
// Cells of a little more than the largest diameter, so that rounding in the cell index cannot hide
// a pair that touches across a cell boundary.
constexpr double kCellMargin = 1 + 1e-9;
}  // namespace

PlacementGrid::PlacementGrid(const Space& space, double rmax, std::size_t expected) : space_(space) {
  const auto& t = space.tilt;
  dense_ = !(space.periodic && (t[0] != 0 || t[1] != 0 || t[2] != 0));
  hashed_cell_ = 2 * rmax;
  if (!dense_) return;
  length_ = space.length();
  double edge = 2 * rmax * kCellMargin;
  // Not more cells than a few per ball: a box far larger than its balls costs distance tests, not
  // memory.
  const double most_cells = std::min(4.0 * static_cast<double>(expected) + 4096, 6.7e7);
  for (;;) {
    double cells = 1;
    for (int a = 0; a < 3; ++a) cells *= std::max(1.0, std::floor(length_[a] / edge) + 1);
    if (cells <= most_cells) break;
    edge *= std::cbrt(cells / most_cells) * 1.01;
  }
  for (int a = 0; a < 3; ++a) {
    wraps_[a] = space.wraps(a);
    if (wraps_[a]) {   // whole cells along the period, each at least `edge`
      cells_[a] = std::max(1L, static_cast<long>(std::floor(length_[a] / edge)));
      cell_[a] = length_[a] / static_cast<double>(cells_[a]);
    } else {
      cells_[a] = std::max(1L, static_cast<long>(std::floor(length_[a] / edge)) + 1);
      cell_[a] = edge;
    }
  }
  head_.assign(static_cast<std::size_t>(cells_[0] * cells_[1] * cells_[2]), -1);
  const std::size_t ahead = std::min<std::size_t>(expected, std::size_t{1} << 22);
  pts_.reserve(ahead);
  next_.reserve(ahead);
  wrap_of_.reserve(ahead);
}

void PlacementGrid::cell_of(int a, double v, long& cell, long& wraps) const {
  const double f = std::floor((v - space_.lo[a]) / cell_[a]);
  wraps = 0;
  if (wraps_[a]) {
    const double periods = std::floor(f / static_cast<double>(cells_[a]));
    wraps = static_cast<long>(std::clamp(periods, -1e9, 1e9));
    // (clamped as a double: far from the cell the difference is rounding, and may pass a long)
    cell = static_cast<long>(std::clamp(f - periods * static_cast<double>(cells_[a]), 0.0,
                                        static_cast<double>(cells_[a] - 1)));
  } else {
    cell = static_cast<long>(std::clamp(f, 0.0, static_cast<double>(cells_[a] - 1)));
  }
}

void PlacementGrid::insert(double x, double y, double z, double r) {
  pts_.push_back({x, y, z, r});
  if (!dense_) {
    hashed_[hashed_key(hashed_cell_of(x), hashed_cell_of(y), hashed_cell_of(z))].push_back(pts_.size() - 1);
    return;
  }
  long c[3], w[3];
  const double p[3] = {x, y, z};
  for (int a = 0; a < 3; ++a) cell_of(a, p[a], c[a], w[a]);
  wrap_of_.push_back({static_cast<std::int32_t>(w[0]), static_cast<std::int32_t>(w[1]), static_cast<std::int32_t>(w[2])});
  const auto slot = static_cast<std::size_t>((c[2] * cells_[1] + c[1]) * cells_[0] + c[0]);
  next_.push_back(head_[slot]);
  head_[slot] = static_cast<std::int32_t>(pts_.size() - 1);
}

bool PlacementGrid::overlaps(double x, double y, double z, double r) const {
  if (!dense_) return overlaps_hashed(x, y, z, r);
  // Every ball held has radius <= rmax, so the cells within r + rmax hold every ball it could touch.
  return visit(x, y, z, r + 0.5 * hashed_cell_, [&](std::size_t q, double dx, double dy, double dz) {
    const double reach = pts_[q][3] + r;
    return dx * dx + dy * dy + dz * dz < reach * reach;
  });
}

// The sheared cell (GEN after STRAIN with shear rates): cubes in a hash, images two deep.
bool PlacementGrid::overlaps_hashed(double x, double y, double z, double r) const {
  if (!space_.periodic) return overlaps_hashed_here(x, y, z, r);
  auto L = space_.length();
  const auto& t = space_.tilt;
  int most[3];
  for (int a = 0; a < 3; ++a) most[a] = space_.wraps(a) ? 2 : 0;
  for (int i = -most[0]; i <= most[0]; ++i)
    for (int j = -most[1]; j <= most[1]; ++j)
      for (int k = -most[2]; k <= most[2]; ++k)
        if (overlaps_hashed_here(x + i * L[0] + j * t[0] + k * t[1], y + j * L[1] + k * t[2], z + k * L[2], r))
          return true;
  return false;
}

bool PlacementGrid::overlaps_hashed_here(double x, double y, double z, double r) const {
  long cx = hashed_cell_of(x), cy = hashed_cell_of(y), cz = hashed_cell_of(z);
  for (long i = -1; i <= 1; ++i)
    for (long j = -1; j <= 1; ++j)
      for (long k = -1; k <= 1; ++k) {
        auto it = hashed_.find(hashed_key(cx + i, cy + j, cz + k));
        if (it == hashed_.end()) continue;
        for (auto q : it->second) {
          double dx = pts_[q][0] - x, dy = pts_[q][1] - y, dz = pts_[q][2] - z, reach = pts_[q][3] + r;
          if (dx * dx + dy * dy + dz * dz < reach * reach) return true;
        }
      }
  return false;
}

// Clamped: in a box far larger than the balls the quotient passes what a long holds (the keys wrap
// anyway; a clamped cell only costs distance tests).
long PlacementGrid::hashed_cell_of(double v) const {
  return static_cast<long>(std::clamp(std::floor(v / hashed_cell_), -1e18, 1e18));
}

std::uint64_t PlacementGrid::hashed_key(long x, long y, long z) {
  return (static_cast<std::uint64_t>(x & 0x1FFFFF) << 42) | (static_cast<std::uint64_t>(y & 0x1FFFFF) << 21) |
         static_cast<std::uint64_t>(z & 0x1FFFFF);
}

}  // namespace trubal
