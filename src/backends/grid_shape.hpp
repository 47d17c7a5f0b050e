// The boxes of a contact-detection grid (TRUBAL's boxes) over the balls' extent, shared by the
// backends that hang balls on boxes.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "model/model.hpp"

namespace trubal {

struct GridShape {
  std::array<double, 3> lo{0, 0, 0}, size{1, 1, 1};
  std::array<int, 3> dims{1, 1, 1};

  // Boxes at least min_size wide, so touching candidates lie in neighbouring boxes, and as fine as
  // that over the balls' extent, up to a million a side (BinIndex keeps only the boxes that hold
  // a ball where they outnumber the balls); `asked` (Space::boxes, 0: automatic) caps the count
  // per axis.
  void fit(const Balls& balls, double min_size, const std::array<int, 3>& asked);
  // The box index along one axis (outside or NaN: the nearest end).
  int cell_of(double x, int axis) const;
  // The linear box index of ball k (x fastest).
  std::uint64_t box_of(const Balls& balls, std::size_t k) const {
    return (static_cast<std::uint64_t>(cell_of(balls.z[k], 2)) * static_cast<std::uint64_t>(dims[1]) +
            static_cast<std::uint64_t>(cell_of(balls.y[k], 1))) * static_cast<std::uint64_t>(dims[0]) +
           static_cast<std::uint64_t>(cell_of(balls.x[k], 0));
  }
  std::uint64_t count() const {
    return static_cast<std::uint64_t>(dims[0]) * static_cast<std::uint64_t>(dims[1]) * static_cast<std::uint64_t>(dims[2]);
  }
};

}  // namespace trubal
