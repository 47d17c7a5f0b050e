#include "backends/allpairs/pair_test.hpp"

namespace trubal {

std::size_t test_row(double xi, double yi, double zi, double ri, const double* __restrict xj,
                     const double* __restrict yj, const double* __restrict zj, const double* __restrict rj,
                     std::size_t count, std::uint8_t* __restrict slot) {
  std::size_t touching = 0;
  for (std::size_t k = 0; k < count; ++k) {
    const double dx = xj[k] - xi, dy = yj[k] - yi, dz = zj[k] - zi;
    const double rsum = ri + rj[k];
    const bool overlap = dx * dx + dy * dy + dz * dz < rsum * rsum;
    slot[k] = overlap;
    touching += overlap;
  }
  return touching;
}

}  // namespace trubal
