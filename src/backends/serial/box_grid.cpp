#include "backends/serial/box_grid.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace trubal {

void BoxGrid::fill(const Balls& balls, double min_size, const std::array<int, 3>& asked) {
  const std::size_t n = balls.size();
  const std::vector<double>* coord[3] = {&balls.x, &balls.y, &balls.z};
  std::array<double, 3> hi{};
  for (int a = 0; a < 3; ++a) {
    const auto& c = *coord[a];
    lo_[a] = n ? *std::min_element(c.begin(), c.end()) : 0;
    hi[a] = n ? *std::max_element(c.begin(), c.end()) : 0;
  }
  // No more boxes than about two per ball: a ball far away must not make the grid huge.
  double size = std::max(min_size, std::numeric_limits<double>::min());
  const double most = 2.0 * static_cast<double>(n) + 27;
  for (;;) {
    double count = 1;
    for (int a = 0; a < 3; ++a) {
      double d = std::max(1.0, std::floor((hi[a] - lo_[a]) / size));
      if (asked[a] > 0) d = std::min(d, static_cast<double>(asked[a]));
      dims_[a] = static_cast<int>(std::min(d, 1e6));
      count *= dims_[a];
    }
    if (count <= most) break;
    size *= std::cbrt(count / most) * 1.01;
  }
  for (int a = 0; a < 3; ++a) size_[a] = std::max(size, (hi[a] - lo_[a]) / dims_[a]);
  head_.assign(static_cast<std::size_t>(dims_[0]) * dims_[1] * dims_[2], -1);
  next_.assign(n, -1);
  cell_.assign(n, 0);
  // Hang balls in descending order so each list runs in ascending index order.
  for (std::size_t k = n; k-- > 0;) {
    const int c = (cell_of(balls.z[k], 2) * dims_[1] + cell_of(balls.y[k], 1)) * dims_[0] + cell_of(balls.x[k], 0);
    cell_[k] = c;
    next_[k] = head_[c];
    head_[c] = static_cast<int>(k);
  }
}

int BoxGrid::cell_of(double x, int axis) const {
  const double c = std::floor((x - lo_[axis]) / size_[axis]);
  return c < 0 ? 0 : (c >= dims_[axis] ? dims_[axis] - 1 : static_cast<int>(c));
}

void BoxGrid::find_pairs(const Balls& balls, double skin, PairCandidates& out) const {
  out.clear();
  std::vector<std::uint32_t> near;
  for (std::size_t i = 0; i < balls.size(); ++i) {
    const int c = cell_[i];
    const int cx = c % dims_[0], cy = (c / dims_[0]) % dims_[1], cz = c / (dims_[0] * dims_[1]);
    near.clear();
    for (int z = std::max(0, cz - 1); z <= std::min(dims_[2] - 1, cz + 1); ++z)
      for (int y = std::max(0, cy - 1); y <= std::min(dims_[1] - 1, cy + 1); ++y)
        for (int x = std::max(0, cx - 1); x <= std::min(dims_[0] - 1, cx + 1); ++x)
          for (int j = head_[(z * dims_[1] + y) * dims_[0] + x]; j >= 0; j = next_[j]) {
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
