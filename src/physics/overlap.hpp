// The largest overlap of the model as it is, as a fraction of the smaller radius: CYCLE's warning
// of overlaps the contact laws were not made for (man page, CONVENTIONS, "Overlaps").
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "model/model.hpp"

namespace trubal {

// Soft-sphere contact laws hold for overlaps small against the radii: Hertz's theory for a contact
// radius sqrt(R* U) much smaller than R, the linear spring for a contact that stays near a point.
// Past a tenth of the smaller radius (a contact radius of 0.2 to 0.3 R, ten times the overlap of a
// quasi-static granular test, whose stiffness is usually chosen to keep the mean overlap below 1% of
// the radius) the numbers describe balls passing into each other rather than a stiff grain.
inline constexpr double kOverlapWarning = 0.1;

struct LargestOverlap {
  double ratio = 0;             // overlap / smaller radius (a wall contact: over the ball's radius)
  std::int64_t ball = 0;        // the ball of the smaller radius (the ball, for a wall contact)
  std::int64_t other = 0;       // the other ball's id, or the wall's id
  bool wall = false;
  std::size_t beyond = 0;       // contacts whose ratio is above `threshold`
  std::size_t at = 0;           // the largest's place: its pair, or its wall contact (wall)
};

// Over the pair list and the wall contacts, at the positions now (a read of the state: nothing is
// written, so no result changes). Ties go to the first in the tables' order. pairs, walls: those of
// the tables alone (a distributed run's part: the pairs and wall contacts it owns), in order.
LargestOverlap largest_overlap(const Model& model, double threshold = kOverlapWarning,
                               const std::vector<std::uint32_t>* pairs = nullptr,
                               const std::vector<std::uint32_t>* walls = nullptr);

}  // namespace trubal
