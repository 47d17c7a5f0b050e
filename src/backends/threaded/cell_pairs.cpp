#include "backends/threaded/cell_pairs.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "backends/threaded/parallel_step.hpp"

namespace trubal {

int CellPairs::cell_of(double x, int axis) const {
  const double c = std::floor((x - lo_[axis]) / size_[axis]);
  return !(c >= 0) ? 0 : (c >= dims_[axis] ? dims_[axis] - 1 : static_cast<int>(c));
}

void CellPairs::find(ThreadPool& pool, const Balls& balls, double min_size, double skin, PairCandidates& out) {
  const std::size_t n = balls.size();
  const std::vector<double>* coord[3] = {&balls.x, &balls.y, &balls.z};
  std::array<double, 3> hi{};
  for (int a = 0; a < 3; ++a) {
    const auto& c = *coord[a];
    lo_[a] = n ? *std::min_element(c.begin(), c.end()) : 0;
    hi[a] = n ? *std::max_element(c.begin(), c.end()) : 0;
  }
  // Cells at least min_size wide (touching candidates lie in neighbouring cells), about two per
  // ball at most so that one far ball cannot make the grid huge.
  double size = std::max(min_size, std::numeric_limits<double>::min());
  const double most = 2.0 * static_cast<double>(n) + 27;
  for (;;) {
    double count = 1;
    for (int a = 0; a < 3; ++a) {
      const double d = std::max(1.0, std::floor((hi[a] - lo_[a]) / size));
      dims_[a] = static_cast<int>(std::min(d, 1e6));
      count *= dims_[a];
    }
    if (!(count > most)) break;
    size *= std::cbrt(count / most) * 1.01;
  }
  for (int a = 0; a < 3; ++a) size_[a] = std::max(size, (hi[a] - lo_[a]) / dims_[a]);
  const std::size_t cells = static_cast<std::size_t>(dims_[0]) * dims_[1] * dims_[2];
  // Counting sort: each cell's balls in ascending index order.
  cell_.resize(n);
  start_.assign(cells + 1, 0);
  for (std::size_t k = 0; k < n; ++k) {
    cell_[k] = static_cast<std::uint32_t>((cell_of(balls.z[k], 2) * dims_[1] + cell_of(balls.y[k], 1)) * dims_[0] +
                                          cell_of(balls.x[k], 0));
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
      const int cx = c % dims_[0], cy = (c / dims_[0]) % dims_[1], cz = c / (dims_[0] * dims_[1]);
      near.clear();
      for (int z = std::max(0, cz - 1); z <= std::min(dims_[2] - 1, cz + 1); ++z)
        for (int y = std::max(0, cy - 1); y <= std::min(dims_[1] - 1, cy + 1); ++y)
          for (int x = std::max(0, cx - 1); x <= std::min(dims_[0] - 1, cx + 1); ++x) {
            const std::size_t cell = (static_cast<std::size_t>(z) * dims_[1] + y) * dims_[0] + x;
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
  for (const PairCandidates& part : parts_) {
    out.i.insert(out.i.end(), part.i.begin(), part.i.end());
    out.j.insert(out.j.end(), part.j.begin(), part.j.end());
    out.image_x.insert(out.image_x.end(), part.image_x.begin(), part.image_x.end());
    out.image_y.insert(out.image_y.end(), part.image_y.begin(), part.image_y.end());
    out.image_z.insert(out.image_z.end(), part.image_z.begin(), part.image_z.end());
  }
}

}  // namespace trubal
