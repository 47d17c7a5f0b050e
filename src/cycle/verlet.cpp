#include "cycle/verlet.hpp"

#include "model/edit.hpp"
#include "model/periodic_cell.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace trubal {

double VerletReference::displacement_limit2(const Model& model) const {
  const Balls& b = model.balls;
  const std::size_t n = b.size();
  if (!valid_ || count_ != n) return -1;
  if (radii_kept_ && n && std::memcmp(rad_.data(), b.rad.data(), n * sizeof(double)) != 0) return -1;
  // Periodic space: an image pair also closes by the change of the cell's edge vectors (per axis,
  // the change of the edge length plus those of the tilts that shift that axis).
  double cell_change = 0;
  if (model.space.periodic) {
    const auto L = model.space.length();
    const auto& t = model.space.tilt;
    const double change[3] = {std::abs(L[0] - cell_[0]) + std::abs(t[0] - tilt_[0]) + std::abs(t[1] - tilt_[1]),
                              std::abs(L[1] - cell_[1]) + std::abs(t[2] - tilt_[2]), std::abs(L[2] - cell_[2])};
    for (int a = 0; a < 3; ++a) cell_change = std::max(cell_change, change[a]);
    if (!(cell_change < skin_)) return -1;
  }
  return 0.25 * (skin_ - cell_change) * (skin_ - cell_change);
}

double VerletReference::max_displacement2(const Balls& b, std::size_t begin, std::size_t end) const {
  double moved2 = 0;
  for (std::size_t i = begin; i < end; ++i) {
    const double dx = b.x[i] - x[i], dy = b.y[i] - y[i], dz = b.z[i] - z[i];
    const double d2 = dx * dx + dy * dy + dz * dz;
    moved2 = std::max(moved2, d2);   // exact in any order; a NaN is skipped (the guard catches it)
  }
  return moved2;
}

double VerletReference::skin_for(const Balls& b) {
  double rad_sum = 0;
  for (double r : b.rad) rad_sum += r;
  return b.size() ? 0.2 * rad_sum / static_cast<double>(b.size()) : 0;
}

void VerletReference::record(const Model& model, double skin) {
  const Balls& b = model.balls;
  x = b.x; y = b.y; z = b.z; rad_ = b.rad;
  radii_kept_ = true;
  count_ = b.size();
  cell_ = model.space.length();
  tilt_ = model.space.tilt;
  skin_ = skin;
  valid_ = true;
  ++rebuilds_;
}

void VerletReference::reorder(const std::vector<std::uint32_t>& order) { keep_rows(order, order.size()); }

void VerletReference::keep_rows(const std::vector<std::uint32_t>& rows, std::size_t n) {
  trubal::keep_rows([&](auto&& f) {
    for (auto* v : {&x, &y, &z, &rad_}) f(*v);
  }, rows, n);
  if (count_ == n) count_ = rows.size();
}

void VerletReference::record_cell(const Model& model, double skin) {
  cell_ = model.space.length();
  tilt_ = model.space.tilt;
  skin_ = skin;
  ++rebuilds_;
}

double periodic_skin(const Model& model, double skin) {
  const auto w = cell_widths(model.space);
  const double reach = 2 * model.balls.max_radius();
  double most = skin;
  for (int a = 0; a < 3; ++a)
    if (model.space.periodic_axis[a]) most = std::min(most, 0.5 * (0.5 * w[a] - reach));
  return std::max(0.0, most);
}


}  // namespace trubal
