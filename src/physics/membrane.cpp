#include "physics/membrane.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <set>
#include <stdexcept>
#include <utility>

#include <fmt/format.h>

#include "model/edit.hpp"

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

  struct Loaded {
    std::size_t ball;
    std::array<double, 2> force;
    std::int8_t face_x, face_y;
    std::int32_t layer;
  };
  std::vector<Loaded> forces;
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
    double xmin = b.x[layer.front()], xmax = xmin, ymin = b.y[layer.front()], ymax = ymin;
    for (std::size_t i : layer) {
      xmin = std::min(xmin, b.x[i]); xmax = std::max(xmax, b.x[i]);
      ymin = std::min(ymin, b.y[i]); ymax = std::max(ymax, b.y[i]);
    }
    out.extent_x.push_back(xmax - xmin);
    out.extent_y.push_back(ymax - ymin);
    out.layer_cells.push_back(static_cast<double>(cells.size()));
    for (std::size_t q = 0; q < layer.size(); ++q) {
      const auto [ix, iy] = cell_of[q];
      auto open = [&](long dx, long dy) { return cells.count({ix + dx, iy + dy}) == 0 ? 1 : 0; };
      const int face_x = open(-1, 0) - open(1, 0), face_y = open(0, -1) - open(0, 1);
      if (open(-1, 0) + open(1, 0) + open(0, -1) + open(0, 1) > 0)
        forces.push_back({layer[q], {face * face_x, face * face_y}, static_cast<std::int8_t>(face_x),
                          static_cast<std::int8_t>(face_y), static_cast<std::int32_t>(n)});
    }
  }
  std::sort(forces.begin(), forces.end(), [](const Loaded& a, const Loaded& c) { return a.ball < c.ball; });
  for (const Loaded& f : forces) {
    out.balls.push_back(f.ball);
    out.fx.push_back(f.force[0]);
    out.fy.push_back(f.force[1]);
    out.face_x.push_back(f.face_x);
    out.face_y.push_back(f.face_y);
    out.layer.push_back(f.layer);
  }
  out.area = static_cast<double>(most_cells) * d * d;
  return out;
}

void follow_membrane(Model& model) {
  Membrane& m = model.membrane;
  Balls& b = model.balls;
  if (!(m.pressure > 0) || m.extent_x.empty()) return;
  // The loaded balls now (a deleted one no longer carries a load).
  MembraneCentres at;
  std::vector<std::int64_t> index(m.ids.size(), -1);
  for (std::size_t q = 0; q < m.ids.size(); ++q) {
    const std::int64_t k = find_ball(model, m.ids[q]);
    index[q] = k;
    at.present.push_back(k >= 0);
    at.x.push_back(k >= 0 ? b.x[k] : 0);
    at.y.push_back(k >= 0 ? b.y[k] : 0);
    at.z.push_back(k >= 0 ? b.z[k] : 0);
  }
  const MembraneFollow loads = follow_loads(m, at);
  for (std::size_t q = 0; q < m.ids.size(); ++q) {
    if (index[q] < 0) continue;
    b.ax[index[q]] = loads.ax[q];
    b.ay[index[q]] = loads.ay[q];
  }
  m.area = loads.area;
}

MembraneFollow follow_loads(const Membrane& m, const MembraneCentres& at) {
  MembraneFollow out;
  const std::size_t layers = m.extent_x.size();
  out.ax.assign(m.ids.size(), 0);
  out.ay.assign(m.ids.size(), 0);
  out.area = m.area;
  if (!(m.pressure > 0) || layers == 0) return out;
  // The loaded balls' layers' heights and extents now.
  std::vector<double> z_sum(layers, 0), count(layers, 0);
  std::vector<double> xmin(layers, 0), xmax(layers, 0), ymin(layers, 0), ymax(layers, 0);
  for (std::size_t q = 0; q < m.ids.size(); ++q) {
    if (!at.present[q]) continue;
    const std::size_t L = static_cast<std::size_t>(m.layer[q]);
    const double x = at.x[q], y = at.y[q];
    if (count[L] == 0) { xmin[L] = xmax[L] = x; ymin[L] = ymax[L] = y; }
    xmin[L] = std::min(xmin[L], x); xmax[L] = std::max(xmax[L], x);
    ymin[L] = std::min(ymin[L], y); ymax[L] = std::max(ymax[L], y);
    z_sum[L] += at.z[q];
    count[L] += 1;
  }
  std::vector<double> z(layers, 0), stretch_x(layers, 1), stretch_y(layers, 1);
  for (std::size_t L = 0; L < layers; ++L) {
    z[L] = count[L] > 0 ? z_sum[L] / count[L] : 0;
    if (m.extent_x[L] > 0 && count[L] > 0) stretch_x[L] = (xmax[L] - xmin[L]) / m.extent_x[L];
    if (m.extent_y[L] > 0 && count[L] > 0) stretch_y[L] = (ymax[L] - ymin[L]) / m.extent_y[L];
  }
  std::size_t widest = 0;
  for (std::size_t L = 0; L < layers; ++L) {
    const double height = layers > 1 ? 0.5 * (z[L + 1 < layers ? L + 1 : L] - z[L > 0 ? L - 1 : L]) : m.cell;
    const double face = m.pressure * m.cell * height;
    for (std::size_t q = 0; q < m.ids.size(); ++q) {
      if (!at.present[q] || static_cast<std::size_t>(m.layer[q]) != L) continue;
      out.ax[q] = face * stretch_y[L] * m.face_x[q];   // a face normal to x spans y
      out.ay[q] = face * stretch_x[L] * m.face_y[q];
    }
    if (m.layer_cells[L] > m.layer_cells[widest]) widest = L;
  }
  out.area = m.layer_cells[widest] * m.cell * m.cell * stretch_x[widest] * stretch_y[widest];
  return out;
}

}  // namespace trubal
