// Overlap tests for GEN: balls hashed into a grid of cells, so that a test looks at the balls of
// the nearby cells only (no O(N^2) step). In periodic space a candidate meets the images of the
// balls across the faces it is near.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "model/model.hpp"

namespace trubal {

class PlacementGrid {
 public:
  // rmax: the largest radius any ball inserted or tested will have; expected: about how many balls
  // the grid will hold (it sizes the cell array).
  PlacementGrid(const Space& space, double rmax, std::size_t expected);
  void insert(double x, double y, double z, double r);
  // Whether a ball of radius r at (x, y, z) overlaps (strictly) a ball held.
  bool overlaps(double x, double y, double z, double r) const;
  std::size_t size() const { return pts_.size(); }

  // Calls f(q, dx, dy, dz) for every ball q held within `reach` cells' distance of (x, y, z), the
  // separation taken to q's image nearest through the grid (dx = x_q - x...); f returns true to stop.
  // Returns whether f stopped it. Dense grid only (not in a sheared cell).
  template <class F> bool visit(double x, double y, double z, double reach, F&& f) const;
  bool dense() const { return dense_; }

 private:
  bool overlaps_hashed(double x, double y, double z, double r) const;
  bool overlaps_hashed_here(double x, double y, double z, double r) const;
  long hashed_cell_of(double v) const;
  static std::uint64_t hashed_key(long x, long y, long z);
  // Cell index along axis a (wrapped on a periodic axis, clamped on a bounded one), and how many
  // periods the raw position lies beyond the wrapped cell.
  void cell_of(int a, double v, long& cell, long& wraps) const;

  const Space& space_;
  bool dense_;
  std::array<double, 3> length_{}, cell_{};
  std::array<long, 3> cells_{};
  std::array<bool, 3> wraps_{};
  std::vector<std::array<double, 4>> pts_;
  std::vector<std::array<std::int32_t, 3>> wrap_of_;   // periods of each ball beyond its cell
  std::vector<std::int32_t> head_, next_;              // dense: linked list per cell
  // A sheared cell: cubes of edge 2 rmax in a hash, images along the edge vectors two deep.
  double hashed_cell_ = 0;
  std::unordered_map<std::uint64_t, std::vector<std::size_t>> hashed_;
};

template <class F> bool PlacementGrid::visit(double x, double y, double z, double reach, F&& f) const {
  const double p[3] = {x, y, z};
  long c[3], w[3], k[3];
  for (int a = 0; a < 3; ++a) {
    cell_of(a, p[a], c[a], w[a]);
    // Cells each way, at most the grid (a bounded axis) or one period and a cell (a periodic one,
    // where GEN keeps reach within half an edge): a reach of 1e308 made it overflow a long.
    const double need = std::ceil(reach / cell_[a]);
    const double most = static_cast<double>(cells_[a]) + (wraps_[a] ? 1 : 0);
    k[a] = need <= most ? static_cast<long>(need) : static_cast<long>(most);
  }
  for (long i = -k[2]; i <= k[2]; ++i) {
    long cz = c[2] + i, sz = 0;
    if (wraps_[2]) { sz = cz >= 0 ? cz / cells_[2] : -((-cz + cells_[2] - 1) / cells_[2]); cz -= sz * cells_[2]; }
    else if (cz < 0 || cz >= cells_[2]) continue;
    for (long j = -k[1]; j <= k[1]; ++j) {
      long cy = c[1] + j, sy = 0;
      if (wraps_[1]) { sy = cy >= 0 ? cy / cells_[1] : -((-cy + cells_[1] - 1) / cells_[1]); cy -= sy * cells_[1]; }
      else if (cy < 0 || cy >= cells_[1]) continue;
      for (long l = -k[0]; l <= k[0]; ++l) {
        long cx = c[0] + l, sx = 0;
        if (wraps_[0]) { sx = cx >= 0 ? cx / cells_[0] : -((-cx + cells_[0] - 1) / cells_[0]); cx -= sx * cells_[0]; }
        else if (cx < 0 || cx >= cells_[0]) continue;
        for (std::int32_t q = head_[(cz * cells_[1] + cy) * cells_[0] + cx]; q >= 0; q = next_[q]) {
          const auto& b = pts_[q];
          const auto& m = wrap_of_[q];
          // The candidate's image next to q: x + i L, i the periods between them (as the hashed
          // grid's arithmetic, so both give the same answers).
          const double ix = static_cast<double>(m[0] - sx - w[0]), iy = static_cast<double>(m[1] - sy - w[1]),
                       iz = static_cast<double>(m[2] - sz - w[2]);
          const double dx = wraps_[0] ? b[0] - (x + ix * length_[0]) : b[0] - x;
          const double dy = wraps_[1] ? b[1] - (y + iy * length_[1]) : b[1] - y;
          const double dz = wraps_[2] ? b[2] - (z + iz * length_[2]) : b[2] - z;
          if (f(static_cast<std::size_t>(q), dx, dy, dz)) return true;
        }
      }
    }
  }
  return false;
}

}  // namespace trubal
