#include "backends/allpairs/pair_test.hpp"

#include <algorithm>
#include <cmath>

namespace trubal {

std::size_t test_row(double xi, double yi, double zi, double ri, const double* __restrict xj,
                     const double* __restrict yj, const double* __restrict zj, const double* __restrict rj,
                     std::size_t count, std::uint8_t* __restrict slot, double reach) {
  std::size_t touching = 0;
  for (std::size_t k = 0; k < count; ++k) {
    const double dx = xj[k] - xi, dy = yj[k] - yi, dz = zj[k] - zi;
    const double rsum = ri + rj[k] + reach;   // (+ 0.0 changes no bit)
    const bool overlap = dx * dx + dy * dy + dz * dz < rsum * rsum;
    slot[k] = overlap;
    touching += overlap;
  }
  return touching;
}

namespace {

// nearest_image(t, length) as a double (-1, 0, +1), by selection.
inline double image_number(double t, double half) { return t > half ? -1.0 : (t < -half ? 1.0 : 0.0); }

template <bool kTilted>
std::size_t periodic_row(const CellFrame& f, double xi, double yi, double zi, double ri, const double* __restrict xj,
                         const double* __restrict yj, const double* __restrict zj, const double* __restrict rj,
                         std::size_t count, std::uint8_t* __restrict slot, double skin) {
  // The frame in locals: the slot stores (bytes) may alias anything, so f's fields would be read
  // again every pair.
  const double lx = f.lx, ly = f.ly, lz = f.lz, xy = f.xy, xz = f.xz, yz = f.yz;
  const double hx = 0.5 * lx, hy = 0.5 * ly, hz = 0.5 * lz;   // nearest_image's 0.5 * length
  std::size_t touching = 0;
  for (std::size_t k = 0; k < count; ++k) {
    const double dx = xj[k] - xi, dy = yj[k] - yi, dz = zj[k] - zi;
    double ex, ey, ez;   // image_delta at the image nearest_image chooses, with image_offset's offset
    if constexpr (kTilted) {
      const double sz = dz / lz;   // nearest_image(f, ...)
      const double ty = dy - yz * sz;
      const double tx = dx - xy * (ty / ly) - xz * sz;
      const double nx = image_number(tx, hx), ny = image_number(ty, hy), nz = image_number(dz, hz);
      ex = dx + (nx * lx + ny * xy + nz * xz);
      ey = dy + (ny * ly + nz * yz);
      ez = dz + nz * lz;
    } else {
      // No tilt: the tilt terms are (signed) zeros, so the image along an axis follows from that
      // axis alone: -1 where d > l/2, +1 where d < -l/2. Its difference d - l or d + l is, up to
      // its sign, l - |d| (IEEE subtraction is exact under negation), and d plus a zero offset is
      // d but for the sign of a zero; no square sees a sign. And l - |d| < |d| exactly where
      // |d| > l/2 (l - |d| is exact for l/2 <= |d| <= 2 l, and rounds to no less than l/2 below),
      // so the choice is a min (NaN stays |d| either way).
      ex = std::min(std::fabs(dx), lx - std::fabs(dx));
      ey = std::min(std::fabs(dy), ly - std::fabs(dy));
      ez = std::min(std::fabs(dz), lz - std::fabs(dz));
    }
    const double reach = ri + rj[k] + skin;
    const bool overlap = ex * ex + ey * ey + ez * ez < reach * reach;
    slot[k] = overlap;
    touching += overlap;
  }
  return touching;
}

}  // namespace

std::size_t test_row_periodic(const CellFrame& f, bool tilted, double xi, double yi, double zi, double ri,
                              const double* __restrict xj, const double* __restrict yj, const double* __restrict zj,
                              const double* __restrict rj, std::size_t count, std::uint8_t* __restrict slot,
                              double reach) {
  return tilted ? periodic_row<true>(f, xi, yi, zi, ri, xj, yj, zj, rj, count, slot, reach)
                : periodic_row<false>(f, xi, yi, zi, ri, xj, yj, zj, rj, count, slot, reach);
}

}  // namespace trubal
