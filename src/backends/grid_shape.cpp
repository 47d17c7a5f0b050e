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
  const double side = std::max(min_size, std::numeric_limits<double>::min());
  for (int a = 0; a < 3; ++a) {
    double d = std::floor((hi[a] - lo[a]) / side);
    d = std::clamp(std::isfinite(d) ? d : 1.0, 1.0, 1e6);
    if (asked[a] > 0) d = std::min(d, static_cast<double>(asked[a]));
    dims[a] = static_cast<int>(d);
    size[a] = std::max(side, (hi[a] - lo[a]) / dims[a]);
  }
}

int GridShape::cell_of(double x, int axis) const {
  const double c = std::floor((x - lo[axis]) / size[axis]);
  return !(c >= 0) ? 0 : (c >= dims[axis] ? dims[axis] - 1 : static_cast<int>(c));
}

}  // namespace trubal
