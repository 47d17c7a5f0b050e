#include "backends/serial/box_grid.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace trubal {

void BoxGrid::fill(const Balls& balls, double min_size, const std::array<int, 3>& asked) {
  const std::size_t n = balls.size();
  shape_.fit(balls, min_size, asked);
  cell_.resize(n);
  for (std::size_t k = 0; k < n; ++k) cell_[k] = shape_.box_of(balls, k);
  bins_.build(cell_, shape_.count());
}

void BoxGrid::find_pairs(const Balls& balls, double skin, PairCandidates& out, std::size_t i_begin,
                         std::size_t i_end) const {
  out.clear();
  // Each candidate goes to the next slot, which counts only where it is a pair (no branch on the
  // test); then the pairs of ball i in ascending j.
  std::vector<std::uint32_t> near(64);
  const auto& dims = shape_.dims;
  const auto& order = bins_.order();
  for (std::size_t i = i_begin; i < std::min(i_end, balls.size()); ++i) {
    const std::uint64_t c = cell_[i], d0 = static_cast<std::uint64_t>(dims[0]), d1 = static_cast<std::uint64_t>(dims[1]);
    const int cx = static_cast<int>(c % d0), cy = static_cast<int>((c / d0) % d1), cz = static_cast<int>(c / (d0 * d1));
    const double xi = balls.x[i], yi = balls.y[i], zi = balls.z[i], ri = balls.rad[i];
    const int x0 = std::max(0, cx - 1), x1 = std::min(dims[0] - 1, cx + 1);
    std::size_t hits = 0;
    for (int z = std::max(0, cz - 1); z <= std::min(dims[2] - 1, cz + 1); ++z)
      for (int y = std::max(0, cy - 1); y <= std::min(dims[1] - 1, cy + 1); ++y) {
        const std::uint64_t row = (static_cast<std::uint64_t>(z) * d1 + static_cast<std::uint64_t>(y)) * d0;
        const auto [e0, e1] = bins_.run(row + static_cast<std::uint64_t>(x0), row + static_cast<std::uint64_t>(x1));
        if (near.size() < hits + (e1 - e0)) near.resize(2 * (hits + (e1 - e0)));
        for (std::uint32_t e = e0; e < e1; ++e) {
          const std::uint32_t j = order[e];
          const double dx = balls.x[j] - xi, dy = balls.y[j] - yi, dz = balls.z[j] - zi;
          const double reach = ri + balls.rad[j] + skin;
          near[hits] = j;
          hits += static_cast<std::size_t>((j > i) & (dx * dx + dy * dy + dz * dz < reach * reach));
        }
      }
    std::sort(near.begin(), near.begin() + static_cast<std::ptrdiff_t>(hits));
    for (std::size_t h = 0; h < hits; ++h) out.push(static_cast<std::uint32_t>(i), near[h]);
  }
}

}  // namespace trubal
