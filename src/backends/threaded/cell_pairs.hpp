// The threaded backend's pair list build: balls sorted into cells (counting sort, one pass), then
// each thread searches the neighbouring cells for its own range of balls. The list is every pair
// i < j closer than R_i + R_j + skin, sorted by (i, j), with the same distance test as the serial
// backend's boxes, so it is the serial list exactly whatever the cells.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "backends/grid_shape.hpp"
#include "backends/pair_candidates.hpp"
#include "support/thread_pool.hpp"
#include "model/model.hpp"

namespace trubal {

class CellPairs {
 public:
  void find(ThreadPool& pool, const Balls& balls, double min_size, const std::array<int, 3>& asked, double skin,
            PairCandidates& out);
  const std::array<int, 3>& dims() const { return shape_.dims; }
  double cell_size() const { return shape_.size[0]; }

 private:
  GridShape shape_;
  std::vector<std::uint32_t> cell_, start_, order_;   // cell of each ball; balls of cell c: order_[start_[c] ..]
  std::vector<PairCandidates> parts_;                 // per thread
};

}  // namespace trubal
