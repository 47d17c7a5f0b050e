#include "backends/grid_shape.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace trubal {

void GridShape::fit(const Balls& balls, double min_size, const std::array<int, 3>& asked) {
  const std::size_t n = balls.size();
  const std::vector<double>* coord[3] = {&balls.x, &balls.y, &balls.z};
  std::array<double, 3> hi{};
  for (int a = 0; a < 3; ++a) {
    const auto& c = *coord[a];
    lo[a] = n ? *std::min_element(c.begin(), c.end()) : 0;
    hi[a] = n ? *std::max_element(c.begin(), c.end()) : 0;
  }
  double side = std::max(min_size, std::numeric_limits<double>::min());
  const double most = 2.0 * static_cast<double>(n) + 27;
  for (;;) {
    double boxes = 1;
    for (int a = 0; a < 3; ++a) {
      double d = std::max(1.0, std::floor((hi[a] - lo[a]) / side));
      if (asked[a] > 0) d = std::min(d, static_cast<double>(asked[a]));
      dims[a] = static_cast<int>(std::min(d, 1e6));
      boxes *= dims[a];
    }
    if (!(boxes > most)) break;
    side *= std::cbrt(boxes / most) * 1.01;
  }
  for (int a = 0; a < 3; ++a) size[a] = std::max(side, (hi[a] - lo[a]) / dims[a]);
}

int GridShape::cell_of(double x, int axis) const {
  const double c = std::floor((x - lo[axis]) / size[axis]);
  return !(c >= 0) ? 0 : (c >= dims[axis] ? dims[axis] - 1 : static_cast<int>(c));
}

}  // namespace trubal
