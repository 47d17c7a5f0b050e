#include "backends/periodic.hpp"

#include <algorithm>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>

namespace trubal {
namespace {

double largest_radius(const Balls& b) {
  double r = 0;
  for (double v : b.rad) r = std::max(r, v);
  return r;
}

}  // namespace

void check_periodic_cell(const Model& model) {
  if (!model.space.periodic) return;
  const double d = 2 * largest_radius(model.balls);
  const auto L = model.space.length();
  for (int a = 0; a < 3; ++a)
    if (!(L[a] >= 2 * d))
      throw std::runtime_error(fmt::format(
          "periodic cell too small: edge {} is {:.6g}, less than twice the largest ball diameter ({:.6g}); "
          "a ball could touch two images of another. Use a larger cell (START x y z) or smaller balls",
          "xyz"[a], L[a], d));
}

double periodic_skin(const Model& model, double skin) {
  const auto L = model.space.length();
  const double reach = 2 * largest_radius(model.balls);
  double most = skin;
  for (int a = 0; a < 3; ++a) most = std::min(most, 0.5 * (0.5 * L[a] - reach));
  return std::max(0.0, most);
}

bool wrap_into_cell(Model& model, std::vector<double>* ref_x, std::vector<double>* ref_y, std::vector<double>* ref_z) {
  const Space& s = model.space;
  if (!s.periodic) return false;
  Balls& b = model.balls;
  ContactTable& c = model.contacts;
  const std::size_t n = b.size();
  const auto L = s.length();
  const auto rate = image_rates(s);
  std::vector<double>* pos[3] = {&b.x, &b.y, &b.z};
  std::vector<double>* vel[3] = {&b.vx, &b.vy, &b.vz};
  std::vector<double>* ref[3] = {ref_x, ref_y, ref_z};
  const bool table_ok = c.gather_begin.size() == n + 1 && c.image_x.size() == c.size() &&
                        c.gather_pair.size() == 2 * c.size();
  std::int8_t* image[3] = {c.image_x.data(), c.image_y.data(), c.image_z.data()};
  bool any = false;
  double work = 0;
  for (std::size_t k = 0; k < n; ++k) {
    for (int a = 0; a < 3; ++a) {
      double& x = (*pos[a])[k];
      if (x >= s.lo[a] && x < s.hi[a]) continue;
      if (!std::isfinite(x)) continue;   // the guard reports it
      // x' = x - shift L: the ball moves to its own image inside the cell.
      const double shift = std::floor((x - s.lo[a]) / L[a]);
      if (shift == 0) continue;   // rounding at the upper face
      x -= shift * L[a];
      // Rounding can land a tiny negative offset on hi: keep the shift, stay inside.
      if (x >= s.hi[a]) x = std::nextafter(s.hi[a], s.lo[a]);
      if (x < s.lo[a]) x = s.lo[a];
      const auto step = static_cast<int>(shift);
      if (ref[a] && ref[a]->size() == n) (*ref[a])[k] -= shift * L[a];
      double& v = (*vel[a])[k];
      const double v_old = v;
      v -= shift * rate[a];
      work += 0.5 * b.mass[k] * (v * v - v_old * v_old);
      model.space.gross_work += 0.5 * b.mass[k] * std::abs(v * v - v_old * v_old);
      // Image of j seen from i: x_j + img L - x_i. Moving j by -shift L adds shift to img; moving i
      // takes it off.
      if (table_ok)
        for (std::uint32_t q = c.gather_begin[k]; q < c.gather_begin[k + 1]; ++q) {
          const std::uint32_t p = c.gather_pair[q];
          image[a][p] = static_cast<std::int8_t>(image[a][p] + (c.gather_sign[q] > 0 ? step : -step));
        }
      any = true;
    }
  }
  model.energy.boundary_work += work;
  return any;
}

void find_periodic_pairs(const Model& model, double skin, PairCandidates& out) {
  out.clear();
  const Balls& b = model.balls;
  const Space& s = model.space;
  const std::size_t n = b.size();
  const auto L = s.length();
  const double reach_max = 2 * largest_radius(b) + skin;
  // Cells across the periodic cell, at least reach_max wide; fewer than 3 per axis: all are neighbours.
  std::array<int, 3> dims{};
  for (int a = 0; a < 3; ++a) {
    const double d = reach_max > 0 ? std::floor(L[a] / reach_max) : 1.0;
    dims[a] = static_cast<int>(std::clamp(d, 1.0, 1000.0));
    if (s.boxes[a] > 0) dims[a] = std::min(dims[a], s.boxes[a]);   // START x y z nbx nby nbz: at most these
  }
  while (static_cast<double>(dims[0]) * dims[1] * dims[2] > 2.0 * static_cast<double>(n) + 27)
    for (int a = 0; a < 3; ++a) dims[a] = std::max(1, dims[a] / 2);
  const std::size_t cells = static_cast<std::size_t>(dims[0]) * dims[1] * dims[2];
  const std::vector<double>* pos[3] = {&b.x, &b.y, &b.z};
  std::vector<std::uint32_t> cell(n), start(cells + 1, 0), order(n);
  std::vector<std::array<int, 3>> where(n);
  for (std::size_t k = 0; k < n; ++k) {
    for (int a = 0; a < 3; ++a) {
      const double f = std::floor(((*pos[a])[k] - s.lo[a]) / L[a] * dims[a]);
      where[k][a] = !(f >= 0) ? 0 : (f >= dims[a] ? dims[a] - 1 : static_cast<int>(f));
    }
    cell[k] = static_cast<std::uint32_t>((where[k][2] * dims[1] + where[k][1]) * dims[0] + where[k][0]);
    ++start[cell[k] + 1];
  }
  for (std::size_t q = 0; q < cells; ++q) start[q + 1] += start[q];
  {
    std::vector<std::uint32_t> next(start.begin(), start.end() - 1);
    for (std::size_t k = 0; k < n; ++k) order[next[cell[k]]++] = static_cast<std::uint32_t>(k);
  }
  std::vector<std::uint32_t> near_cells;
  struct Hit { std::uint32_t j; std::int8_t ix, iy, iz; };
  std::vector<Hit> near;
  for (std::size_t i = 0; i < n; ++i) {
    near_cells.clear();
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int cx = (where[i][0] + dx + dims[0]) % dims[0], cy = (where[i][1] + dy + dims[1]) % dims[1],
                    cz = (where[i][2] + dz + dims[2]) % dims[2];
          near_cells.push_back(static_cast<std::uint32_t>((cz * dims[1] + cy) * dims[0] + cx));
        }
    std::sort(near_cells.begin(), near_cells.end());
    near_cells.erase(std::unique(near_cells.begin(), near_cells.end()), near_cells.end());
    near.clear();
    for (std::uint32_t q : near_cells)
      for (std::uint32_t e = start[q]; e < start[q + 1]; ++e) {
        const std::uint32_t j = order[e];
        if (j <= i) continue;
        const std::int8_t ix = nearest_image(b.x[j] - b.x[i], L[0]), iy = nearest_image(b.y[j] - b.y[i], L[1]),
                          iz = nearest_image(b.z[j] - b.z[i], L[2]);
        const double dx = image_delta(b.x[j], b.x[i], ix, L[0]), dy = image_delta(b.y[j], b.y[i], iy, L[1]),
                     dz = image_delta(b.z[j], b.z[i], iz, L[2]);
        const double reach = b.rad[i] + b.rad[j] + skin;
        if (dx * dx + dy * dy + dz * dz < reach * reach) near.push_back({j, ix, iy, iz});
      }
    std::sort(near.begin(), near.end(), [](const Hit& p, const Hit& q) { return p.j < q.j; });
    for (const Hit& h : near) {
      out.i.push_back(static_cast<std::uint32_t>(i));
      out.j.push_back(h.j);
      out.image_x.push_back(h.ix);
      out.image_y.push_back(h.iy);
      out.image_z.push_back(h.iz);
    }
  }
}

}  // namespace trubal
