// Boxes (cells) over the balls' bounding box, and the candidate pairs they give. TRUBAL hung the
// balls of a box on a linked list (head/next); here they are sorted by box (BinIndex: each box's
// balls in ascending index), so that the three boxes along x around a ball are one run of that
// order, read in one loop. (Copies of the places in that order gained nothing measurable and cost
// 32 bytes a ball: not kept.)
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "backends/bin_index.hpp"
#include "backends/grid_shape.hpp"
#include "backends/pair_candidates.hpp"
#include "model/model.hpp"

namespace trubal {

class BoxGrid {
 public:
  // Hangs every ball on its box. Boxes are at least min_size wide so that touching candidates lie
  // in neighbouring boxes; `asked` (Space::boxes, 0: automatic) caps the count per axis.
  void fill(const Balls& balls, double min_size, const std::array<int, 3>& asked);
  // Pairs i < j closer than R_i + R_j + skin, sorted by (i, j); with i_begin, i_end: only those
  // whose ball i is in [i_begin, i_end). Threads may search ranges of one filled grid at once.
  void find_pairs(const Balls& balls, double skin, PairCandidates& out, std::size_t i_begin = 0,
                  std::size_t i_end = ~std::size_t{0}) const;

  const std::array<int, 3>& dims() const { return shape_.dims; }
  double cell_size() const { return shape_.size[0]; }

 private:
  GridShape shape_;
  std::vector<std::uint64_t> cell_;   // each ball's box
  BinIndex bins_;
};

}  // namespace trubal
