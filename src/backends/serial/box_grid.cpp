#include "backends/serial/box_grid.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace trubal {

void BoxGrid::fill(const Balls& balls, double min_size, const std::array<int, 3>& asked) {
  const std::size_t n = balls.size();
  shape_.fit(balls, min_size, asked);
  head_.assign(shape_.count(), -1);
  next_.assign(n, -1);
  cell_.assign(n, 0);
  // Hang balls in descending order so each list runs in ascending index order.
  for (std::size_t k = n; k-- > 0;) {
    const int c = shape_.box_of(balls, k);
    cell_[k] = c;
    next_[k] = head_[c];
    head_[c] = static_cast<int>(k);
  }
}

void BoxGrid::find_pairs(const Balls& balls, double skin, PairCandidates& out, std::size_t i_begin,
                         std::size_t i_end) const {
  out.clear();
  std::vector<std::uint32_t> near;
  for (std::size_t i = i_begin; i < std::min(i_end, balls.size()); ++i) {
    const auto& dims = shape_.dims;
    const int c = cell_[i];
    const int cx = c % dims[0], cy = (c / dims[0]) % dims[1], cz = c / (dims[0] * dims[1]);
    near.clear();
    for (int z = std::max(0, cz - 1); z <= std::min(dims[2] - 1, cz + 1); ++z)
      for (int y = std::max(0, cy - 1); y <= std::min(dims[1] - 1, cy + 1); ++y)
        for (int x = std::max(0, cx - 1); x <= std::min(dims[0] - 1, cx + 1); ++x)
          for (int j = head_[(z * dims[1] + y) * dims[0] + x]; j >= 0; j = next_[j]) {
            if (static_cast<std::size_t>(j) <= i) continue;
            const double dx = balls.x[j] - balls.x[i], dy = balls.y[j] - balls.y[i], dz = balls.z[j] - balls.z[i];
            const double reach = balls.rad[i] + balls.rad[j] + skin;
            if (dx * dx + dy * dy + dz * dz < reach * reach) near.push_back(static_cast<std::uint32_t>(j));
          }
    std::sort(near.begin(), near.end());
    for (std::uint32_t j : near) out.push(static_cast<std::uint32_t>(i), j);
  }
}

}  // namespace trubal
