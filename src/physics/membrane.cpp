#include "physics/membrane.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <set>
#include <stdexcept>
#include <utility>

#include <fmt/format.h>

namespace trubal {

MembraneLoads membrane_loads(const Model& model, const std::vector<std::size_t>& selection, double pressure) {
  const Balls& b = model.balls;
  if (selection.empty()) throw std::runtime_error("MEMBRANE: the range holds for no ball");
  const double r = b.rad[selection[0]];
  for (std::size_t i : selection)
    if (std::abs(b.rad[i] - r) > 1e-9 * r)
      throw std::runtime_error("MEMBRANE needs balls of one size (each owns a square cell one diameter wide)");
  MembraneLoads out;
  const double d = 2 * r;
  out.cell = d;

  // Layers: balls by height, a new layer where z jumps by more than a quarter radius.
  std::vector<std::size_t> by_z = selection;
  std::stable_sort(by_z.begin(), by_z.end(), [&](std::size_t a, std::size_t c) { return b.z[a] < b.z[c]; });
  std::vector<std::vector<std::size_t>> layers;
  for (std::size_t i : by_z) {
    if (layers.empty() || b.z[i] - b.z[layers.back().front()] > 0.25 * r) layers.emplace_back();
    layers.back().push_back(i);
  }
  out.layers = layers.size();

  // The centre of the selection's plan, and each layer's reach from it (square norm).
  double xlo = b.x[selection[0]], xhi = xlo, ylo = b.y[selection[0]], yhi = ylo;
  for (std::size_t i : selection) {
    xlo = std::min(xlo, b.x[i]); xhi = std::max(xhi, b.x[i]);
    ylo = std::min(ylo, b.y[i]); yhi = std::max(yhi, b.y[i]);
  }
  const double cx = 0.5 * (xlo + xhi), cy = 0.5 * (ylo + yhi);
  std::vector<double> reach(layers.size(), 0);
  for (std::size_t k = 0; k < layers.size(); ++k)
    for (std::size_t i : layers[k]) reach[k] = std::max({reach[k], std::abs(b.x[i] - cx), std::abs(b.y[i] - cy)});
  const double widest = *std::max_element(reach.begin(), reach.end());
  std::vector<std::size_t> loaded;
  for (std::size_t k = 0; k < layers.size(); ++k)
    if (reach[k] >= widest - 0.5 * r) loaded.push_back(k);
  out.loaded_layers = loaded.size();

  std::vector<std::pair<std::size_t, std::array<double, 2>>> forces;
  std::size_t most_cells = 0;
  for (std::size_t n = 0; n < loaded.size(); ++n) {
    const auto& layer = layers[loaded[n]];
    auto z_of = [&](std::size_t m) { return b.z[layers[loaded[m]].front()]; };
    const double below = n > 0 ? z_of(n - 1) : z_of(n), above = n + 1 < loaded.size() ? z_of(n + 1) : z_of(n);
    const double height = loaded.size() > 1 ? 0.5 * (above - below) : d;
    const double face = pressure * d * height;
    // Cells on the square grid of this layer.
    const double x0 = b.x[layer.front()], y0 = b.y[layer.front()];
    std::set<std::pair<long, long>> cells;
    std::vector<std::pair<long, long>> cell_of;
    for (std::size_t i : layer) {
      const long ix = std::lround((b.x[i] - x0) / d), iy = std::lround((b.y[i] - y0) / d);
      if (std::abs(b.x[i] - x0 - ix * d) > 0.25 * r || std::abs(b.y[i] - y0 - iy * d) > 0.25 * r ||
          !cells.insert({ix, iy}).second)
        throw std::runtime_error(fmt::format(
            "MEMBRANE: the layer at z = {:.6g} is not a square grid of spacing {:.6g} (one ball per cell)", b.z[i], d));
      cell_of.push_back({ix, iy});
    }
    most_cells = std::max(most_cells, cells.size());
    for (std::size_t q = 0; q < layer.size(); ++q) {
      const auto [ix, iy] = cell_of[q];
      auto open = [&](long dx, long dy) { return cells.count({ix + dx, iy + dy}) == 0 ? 1.0 : 0.0; };
      const double fx = face * (open(-1, 0) - open(1, 0)), fy = face * (open(0, -1) - open(0, 1));
      if (open(-1, 0) + open(1, 0) + open(0, -1) + open(0, 1) > 0) forces.push_back({layer[q], {fx, fy}});
    }
  }
  std::sort(forces.begin(), forces.end(), [](const auto& a, const auto& c) { return a.first < c.first; });
  for (const auto& [i, f] : forces) {
    out.balls.push_back(i);
    out.fx.push_back(f[0]);
    out.fy.push_back(f[1]);
  }
  out.area = static_cast<double>(most_cells) * d * d;
  return out;
}

}  // namespace trubal
