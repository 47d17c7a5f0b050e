#include "backends/periodic.hpp"

#include <algorithm>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>

#include "backends/threaded/parallel_step.hpp"
#include "backends/threaded/thread_pool.hpp"

namespace trubal {
namespace {

// Fewer balls than this are searched on one thread: waking the others costs more.
constexpr std::size_t kParallelSearch = 4096;

double largest_radius(const Balls& b) {
  double r = 0;
  for (double v : b.rad) r = std::max(r, v);
  return r;
}

}  // namespace

CellFrame cell_frame(const Space& s) {
  CellFrame f;
  if (!s.periodic) return f;
  const auto L = s.length();
  f.lx = L[0]; f.ly = L[1]; f.lz = L[2];
  f.xy = s.tilt[0]; f.xz = s.tilt[1]; f.yz = s.tilt[2];
  const auto g = velocity_gradient(s.strain_rate);
  // dH/dt = L H, both upper triangular.
  f.vlx = g[0][0] * f.lx;
  f.vxy = g[0][0] * f.xy + g[0][1] * f.ly;
  f.vxz = g[0][0] * f.xz + g[0][1] * f.yz + g[0][2] * f.lz;
  f.vly = g[1][1] * f.ly;
  f.vyz = g[1][1] * f.yz + g[1][2] * f.lz;
  f.vlz = g[2][2] * f.lz;
  return f;
}

std::array<std::array<double, 3>, 3> velocity_gradient(const std::array<double, 6>& r) {
  return {{{-r[0], -2 * r[3], -2 * r[4]}, {0.0, -r[1], -2 * r[5]}, {0.0, 0.0, -r[2]}}};
}

std::array<double, 3> cell_widths(const Space& s) {
  const auto L = s.length();
  const double xy = s.tilt[0], xz = s.tilt[1], yz = s.tilt[2];
  // Face normals: b x c, c x a, a x b; width = volume / face area.
  const double q = (xy * yz - L[1] * xz) / (L[1] * L[2]);
  return {L[0] / std::sqrt(1 + (xy / L[1]) * (xy / L[1]) + q * q), L[1] / std::sqrt(1 + (yz / L[2]) * (yz / L[2])),
          L[2]};
}

void check_periodic_cell(const Model& model) {
  if (!model.space.periodic) return;
  const double d = 2 * largest_radius(model.balls);
  const auto w = cell_widths(model.space);
  for (int a = 0; a < 3; ++a)
    if (!(w[a] >= 2 * d))
      throw std::runtime_error(fmt::format(
          "periodic cell too small: {} {} is {:.6g}, less than twice the largest ball diameter ({:.6g}); "
          "a ball could touch two images of another. Use a larger cell (START x y z) or smaller balls",
          model.space.tilt == std::array<double, 3>{0, 0, 0} ? "edge" : "width across", "xyz"[a], w[a], d));
}

double periodic_skin(const Model& model, double skin) {
  const auto w = cell_widths(model.space);
  const double reach = 2 * largest_radius(model.balls);
  double most = skin;
  for (int a = 0; a < 3; ++a) most = std::min(most, 0.5 * (0.5 * w[a] - reach));
  return std::max(0.0, most);
}

namespace {

// The part of ball k's coordinate a that the tilts contribute (0 in an unsheared cell): the
// coordinate less it is lo[a] + edge length * the fractional coordinate along edge a.
double tilt_terms(const Space& s, const CellFrame& f, const Balls& b, std::size_t k, int a) {
  if (a == 2 || (f.xy == 0 && f.xz == 0 && f.yz == 0)) return 0;
  const double sz = (b.z[k] - s.lo[2]) / f.lz;
  if (a == 1) return f.yz * sz;
  const double sy = (b.y[k] - s.lo[1] - f.yz * sz) / f.ly;
  return f.xy * sy + f.xz * sz;
}

}  // namespace

bool outside_cell(const Model& model, std::size_t begin, std::size_t end) {
  const Space& s = model.space;
  if (!s.periodic) return false;
  const Balls& b = model.balls;
  const CellFrame f = cell_frame(s);
  const std::vector<double>* pos[3] = {&b.x, &b.y, &b.z};
  for (std::size_t k = begin; k < end; ++k)
    for (int a = 2; a >= 0; --a) {   // the test wrap_into_cell makes, on unmoved coordinates
      const double x = (*pos[a])[k];
      if (!std::isfinite(x)) continue;
      const double t = x - tilt_terms(s, f, b, k, a);
      if (!(t >= s.lo[a] && t < s.hi[a])) return true;
    }
  return false;
}

bool wrap_into_cell(Model& model, std::vector<double>* ref_x, std::vector<double>* ref_y, std::vector<double>* ref_z) {
  const Space& s = model.space;
  if (!s.periodic) return false;
  Balls& b = model.balls;
  ContactTable& c = model.contacts;
  const std::size_t n = b.size();
  const CellFrame f = cell_frame(s);
  // Edge vectors and their velocities, by axis (columns of H and dH/dt).
  const double edge[3][3] = {{f.lx, 0, 0}, {f.xy, f.ly, 0}, {f.xz, f.yz, f.lz}};
  const double edge_velocity[3][3] = {{f.vlx, 0, 0}, {f.vxy, f.vly, 0}, {f.vxz, f.vyz, f.vlz}};
  std::vector<double>* pos[3] = {&b.x, &b.y, &b.z};
  std::vector<double>* vel[3] = {&b.vx, &b.vy, &b.vz};
  std::vector<double>* ref[3] = {ref_x, ref_y, ref_z};
  const bool table_ok = c.gather_begin.size() == n + 1 && c.image_x.size() == c.size() &&
                        c.gather_pair.size() == 2 * c.size();
  std::int8_t* image[3] = {c.image_x.data(), c.image_y.data(), c.image_z.data()};
  bool any = false;
  double work = 0;
  for (std::size_t k = 0; k < n; ++k) {
    // z first: moving along c shifts y and x; then y (b shifts x); then x.
    for (int a = 2; a >= 0; --a) {
      double& x = (*pos[a])[k];
      if (!std::isfinite(x)) continue;   // the guard reports it
      const double tilt = tilt_terms(s, f, b, k, a);
      const double t = x - tilt;
      if (t >= s.lo[a] && t < s.hi[a]) continue;
      // The ball moves to its own image inside the cell: minus shift edge vectors.
      const double shift = std::floor((t - s.lo[a]) / edge[a][a]);
      if (shift == 0) continue;   // rounding at the upper face
      for (int e = 0; e <= a; ++e) (*pos[e])[k] -= shift * edge[a][e];
      // Rounding can land a tiny negative offset on hi: keep the shift, stay inside.
      if (x - tilt >= s.hi[a]) x = std::nextafter(s.hi[a], s.lo[a]) + tilt;
      if (x - tilt < s.lo[a]) x = s.lo[a] + tilt;
      const auto step = static_cast<int>(shift);
      for (int e = 0; e <= a; ++e)
        if (ref[e] && ref[e]->size() == n) (*ref[e])[k] -= shift * edge[a][e];
      for (int e = 0; e <= a; ++e) {
        if (edge_velocity[a][e] == 0) continue;
        double& v = (*vel[e])[k];
        const double v_old = v;
        v -= shift * edge_velocity[a][e];
        work += 0.5 * b.mass[k] * (v * v - v_old * v_old);
        model.space.gross_work += 0.5 * b.mass[k] * std::abs(v * v - v_old * v_old);
      }
      // Image of j seen from i: x_j + H img - x_i. Moving j by -shift along edge a adds shift to
      // img_a; moving i takes it off.
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

bool reduce_cell_tilt(Model& model) {
  Space& s = model.space;
  if (!s.periodic) return false;
  ContactTable& c = model.contacts;
  const auto L = s.length();
  // Replacing edge `from` by itself less `by` edges `other`: image n becomes n' with
  // n'_other = n_other + by n_from (the same offset H n).
  auto renumber = [&](std::vector<std::int8_t>& other, const std::vector<std::int8_t>& from, int by) {
    for (std::size_t p = 0; p < other.size() && p < from.size(); ++p)
      other[p] = static_cast<std::int8_t>(other[p] + by * from[p]);
  };
  bool any = false;
  while (std::abs(s.tilt[2]) > 0.5 * L[1]) {   // yz: c -/+ b
    const int by = s.tilt[2] > 0 ? 1 : -1;
    s.tilt[2] -= by * L[1];
    s.tilt[1] -= by * s.tilt[0];
    renumber(c.image_y, c.image_z, by);
    any = true;
  }
  while (std::abs(s.tilt[1]) > 0.5 * L[0]) {   // xz: c -/+ a
    const int by = s.tilt[1] > 0 ? 1 : -1;
    s.tilt[1] -= by * L[0];
    renumber(c.image_x, c.image_z, by);
    any = true;
  }
  while (std::abs(s.tilt[0]) > 0.5 * L[0]) {   // xy: b -/+ a
    const int by = s.tilt[0] > 0 ? 1 : -1;
    s.tilt[0] -= by * L[0];
    renumber(c.image_x, c.image_y, by);
    any = true;
  }
  return any;
}

void find_periodic_pairs(const Model& model, double skin, PairCandidates& out, ThreadPool* pool) {
  out.clear();
  const Balls& b = model.balls;
  const Space& s = model.space;
  const std::size_t n = b.size();
  const CellFrame f = cell_frame(s);
  const auto L = s.length();
  const auto w = cell_widths(s);
  const double reach_max = 2 * largest_radius(b) + skin;
  // Bins in the cell's fractional coordinates (parallelepipeds like the cell), at least reach_max
  // wide across; fewer than 3 per axis: all are neighbours.
  std::array<int, 3> dims{};
  for (int a = 0; a < 3; ++a) {
    const double d = reach_max > 0 ? std::floor(w[a] / reach_max) : 1.0;
    dims[a] = static_cast<int>(std::clamp(d, 1.0, 1000.0));
    if (s.boxes[a] > 0) dims[a] = std::min(dims[a], s.boxes[a]);   // START x y z nbx nby nbz: at most these
  }
  while (static_cast<double>(dims[0]) * dims[1] * dims[2] > 2.0 * static_cast<double>(n) + 27)
    for (int a = 0; a < 3; ++a) dims[a] = std::max(1, dims[a] / 2);
  const std::size_t cells = static_cast<std::size_t>(dims[0]) * dims[1] * dims[2];
  std::vector<std::uint32_t> cell(n), start(cells + 1, 0), order(n);
  std::vector<std::array<int, 3>> where(n);
  for (std::size_t k = 0; k < n; ++k) {
    const double sz = (b.z[k] - s.lo[2]) / f.lz;
    const double ty = b.y[k] - f.yz * sz;
    const double tx = b.x[k] - f.xy * ((ty - s.lo[1]) / f.ly) - f.xz * sz;
    const double t[3] = {tx, ty, b.z[k]};   // the coordinates less their tilt terms
    for (int a = 0; a < 3; ++a) {
      const double q = std::floor((t[a] - s.lo[a]) / L[a] * dims[a]);
      where[k][a] = !(q >= 0) ? 0 : (q >= dims[a] ? dims[a] - 1 : static_cast<int>(q));
    }
    cell[k] = static_cast<std::uint32_t>((where[k][2] * dims[1] + where[k][1]) * dims[0] + where[k][0]);
    ++start[cell[k] + 1];
  }
  for (std::size_t q = 0; q < cells; ++q) start[q + 1] += start[q];
  {
    std::vector<std::uint32_t> next(start.begin(), start.end() - 1);
    for (std::size_t k = 0; k < n; ++k) order[next[cell[k]]++] = static_cast<std::uint32_t>(k);
  }
  struct Hit { std::uint32_t j; std::int8_t ix, iy, iz; };
  const bool few_cells = dims[0] < 3 || dims[1] < 3 || dims[2] < 3;
  // Ball i's pairs, in ascending j.
  auto emit = [](std::size_t i, std::vector<Hit>& near, PairCandidates& mine) {
    std::sort(near.begin(), near.end(), [](const Hit& p, const Hit& q) { return p.j < q.j; });
    for (const Hit& h : near) {
      mine.i.push_back(static_cast<std::uint32_t>(i));
      mine.j.push_back(h.j);
      mine.image_x.push_back(h.ix);
      mine.image_y.push_back(h.iy);
      mine.image_z.push_back(h.iz);
    }
  };
  auto search = [&](std::size_t begin, std::size_t end, PairCandidates& mine) {
    std::vector<std::uint32_t> near_cells;
    std::vector<Hit> near;
    for (std::size_t i = begin; i < end; ++i) {
      near_cells.clear();
      for (int dz = -1; dz <= 1; ++dz)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const int cx = (where[i][0] + dx + dims[0]) % dims[0], cy = (where[i][1] + dy + dims[1]) % dims[1],
                      cz = (where[i][2] + dz + dims[2]) % dims[2];
            near_cells.push_back(static_cast<std::uint32_t>((cz * dims[1] + cy) * dims[0] + cx));
          }
      std::sort(near_cells.begin(), near_cells.end());   // fewer than 3 bins on some axis: the 27 repeat some
      near_cells.erase(std::unique(near_cells.begin(), near_cells.end()), near_cells.end());
      near.clear();
      for (std::uint32_t q : near_cells)
        for (std::uint32_t e = start[q]; e < start[q + 1]; ++e) {
          const std::uint32_t j = order[e];
          if (j <= i) continue;
          std::int8_t ix, iy, iz;
          if (nearest_image_within(f, b, i, j, b.rad[i] + b.rad[j] + skin, ix, iy, iz)) near.push_back({j, ix, iy, iz});
        }
      emit(i, near, mine);
    }
  };
  // With 3 or more bins on every axis, the 27 bins around a ball's are distinct, and the image of
  // a ball in one of them is the bin's: -1 across the upper face, +1 across the lower one. Within
  // reach (less than half of every width) only one image of j can be, and it is that one, the one
  // nearest_image() finds; so the test below takes the image from the bin and skips the rounding,
  // with the same arithmetic from there on (same pairs, same images, same bits).
  auto search_bins = [&](std::size_t begin, std::size_t end, PairCandidates& mine) {
    std::vector<Hit> near;
    for (std::size_t i = begin; i < end; ++i) {
      near.clear();
      for (int dz = -1; dz <= 1; ++dz) {
        int cz = where[i][2] + dz;
        const std::int8_t iz = cz < 0 ? std::int8_t{-1} : (cz >= dims[2] ? std::int8_t{1} : std::int8_t{0});
        cz -= iz * dims[2];
        for (int dy = -1; dy <= 1; ++dy) {
          int cy = where[i][1] + dy;
          const std::int8_t iy = cy < 0 ? std::int8_t{-1} : (cy >= dims[1] ? std::int8_t{1} : std::int8_t{0});
          cy -= iy * dims[1];
          for (int dx = -1; dx <= 1; ++dx) {
            int cx = where[i][0] + dx;
            const std::int8_t ix = cx < 0 ? std::int8_t{-1} : (cx >= dims[0] ? std::int8_t{1} : std::int8_t{0});
            cx -= ix * dims[0];
            double ox, oy, oz;
            image_offset(f, ix, iy, iz, ox, oy, oz);
            const std::size_t q = (static_cast<std::size_t>(cz) * dims[1] + cy) * dims[0] + cx;
            for (std::uint32_t e = start[q]; e < start[q + 1]; ++e) {
              const std::uint32_t j = order[e];
              if (j <= i) continue;
              const double ddx = image_delta(b.x[j], b.x[i], ox), ddy = image_delta(b.y[j], b.y[i], oy),
                           ddz = image_delta(b.z[j], b.z[i], oz);
              const double reach = b.rad[i] + b.rad[j] + skin;
              if (ddx * ddx + ddy * ddy + ddz * ddz < reach * reach) near.push_back({j, ix, iy, iz});
            }
          }
        }
      }
      emit(i, near, mine);
    }
  };
  auto search_any = [&](std::size_t begin, std::size_t end, PairCandidates& mine) {
    if (few_cells) search(begin, end, mine);
    else search_bins(begin, end, mine);
  };
  const int parts = pool && n >= kParallelSearch ? pool->size() : 1;
  if (parts == 1) { search_any(0, n, out); return; }
  std::vector<PairCandidates> lists(parts);
  pool->run([&](int t) { search_any(split_point(n, parts, t), split_point(n, parts, t + 1), lists[t]); });
  for (const PairCandidates& part : lists) out.append(part);
}

}  // namespace trubal
