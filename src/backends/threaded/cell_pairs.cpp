#include "backends/threaded/cell_pairs.hpp"

#include <algorithm>
#include <cmath>
#include <limits>


namespace trubal {

void CellPairs::find(ThreadPool& pool, const Balls& balls, double min_size, const std::array<int, 3>& asked,
                     double skin, PairCandidates& out) {
  const std::size_t n = balls.size();
  shape_.fit(balls, min_size, asked);
  const auto& dims = shape_.dims;
  const std::size_t cells = shape_.count();
  // Counting sort: each cell's balls in ascending index order.
  cell_.resize(n);
  start_.assign(cells + 1, 0);
  for (std::size_t k = 0; k < n; ++k) {
    cell_[k] = static_cast<std::uint32_t>(shape_.box_of(balls, k));
    ++start_[cell_[k] + 1];
  }
  for (std::size_t c = 0; c < cells; ++c) start_[c + 1] += start_[c];
  order_.resize(n);
  {
    std::vector<std::uint32_t> next(start_.begin(), start_.end() - 1);
    for (std::size_t k = 0; k < n; ++k) order_[next[cell_[k]]++] = static_cast<std::uint32_t>(k);
  }
  const int parts = pool.size();
  parts_.resize(parts);
  pool.run([&](int t) {
    PairCandidates& mine = parts_[t];
    mine.clear();
    std::vector<std::uint32_t> near;
    for (std::size_t i = split_point(n, parts, t), e = split_point(n, parts, t + 1); i < e; ++i) {
      const int c = static_cast<int>(cell_[i]);
      const int cx = c % dims[0], cy = (c / dims[0]) % dims[1], cz = c / (dims[0] * dims[1]);
      near.clear();
      for (int z = std::max(0, cz - 1); z <= std::min(dims[2] - 1, cz + 1); ++z)
        for (int y = std::max(0, cy - 1); y <= std::min(dims[1] - 1, cy + 1); ++y)
          for (int x = std::max(0, cx - 1); x <= std::min(dims[0] - 1, cx + 1); ++x) {
            const std::size_t cell = (static_cast<std::size_t>(z) * dims[1] + y) * dims[0] + x;
            for (std::uint32_t q = start_[cell]; q < start_[cell + 1]; ++q) {
              const std::uint32_t j = order_[q];
              if (j <= i) continue;
              // The serial backend's test, term for term.
              const double dx = balls.x[j] - balls.x[i], dy = balls.y[j] - balls.y[i], dz = balls.z[j] - balls.z[i];
              const double reach = balls.rad[i] + balls.rad[j] + skin;
              if (dx * dx + dy * dy + dz * dz < reach * reach) near.push_back(j);
            }
          }
      std::sort(near.begin(), near.end());
      for (std::uint32_t j : near) mine.push(static_cast<std::uint32_t>(i), j);
    }
  }, n >= 4096);
  out.clear();
  for (const PairCandidates& part : parts_) out.append(part);
}

}  // namespace trubal
