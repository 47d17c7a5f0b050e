#include "backends/threaded/cell_pairs.hpp"

namespace trubal {

void CellPairs::find(ThreadPool& pool, const Balls& balls, double min_size, const std::array<int, 3>& asked,
                     double skin, PairCandidates& out) {
  const std::size_t n = balls.size();
  grid_.fill(balls, min_size, asked);
  const int parts = pool.size();
  parts_.resize(parts);
  pool.run([&](int t) { grid_.find_pairs(balls, skin, parts_[t], split_point(n, parts, t), split_point(n, parts, t + 1)); },
           n >= 4096);
  out.clear();
  for (const PairCandidates& part : parts_) out.append(part);
}

}  // namespace trubal
