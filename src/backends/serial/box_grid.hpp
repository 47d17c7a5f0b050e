// Boxes (cells) over the balls' bounding box, with a linked list of balls per box (head/next, as
// TRUBAL kept them), and the candidate pairs they give.
#pragma once

#include <array>
#include <vector>

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
  // whose ball i is in [i_begin, i_end).
  void find_pairs(const Balls& balls, double skin, PairCandidates& out, std::size_t i_begin = 0,
                  std::size_t i_end = ~std::size_t{0}) const;

  const std::array<int, 3>& dims() const { return shape_.dims; }
  double cell_size() const { return shape_.size[0]; }

 private:
  GridShape shape_;
  std::vector<int> head_, next_, cell_;   // first ball of each box; next ball in the same box
};

}  // namespace trubal
