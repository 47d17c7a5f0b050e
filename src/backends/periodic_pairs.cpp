#include "backends/periodic_pairs.hpp"

#include <algorithm>
#include <cmath>
#include <span>

#include "backends/bin_index.hpp"
#include "model/periodic_cell.hpp"

namespace trubal {
namespace {

// Fewer balls than this are searched on one thread: waking the others costs more.
constexpr std::size_t kParallelSearch = 4096;

}  // namespace

void find_periodic_pairs(const Model& model, double skin, PairCandidates& out, ThreadPool* pool, std::size_t i_begin,
                         std::size_t i_end) {
  out.clear();
  const Balls& b = model.balls;
  const Space& s = model.space;
  const std::size_t n = b.size();
  const CellFrame f = cell_frame(s);
  const auto L = s.length();
  const auto w = cell_widths(s);
  const double reach_max = 2 * b.max_radius() + skin;
  // Bins in the cell's fractional coordinates (parallelepipeds like the cell), at least reach_max
  // wide across, up to 1000 a side; fewer than 3 per axis: all are neighbours. Where they outnumber
  // the balls, only those holding a ball are kept (BinIndex), so balls crowded into a corner of a
  // large cell meet bins as fine as where they fill it.
  std::array<int, 3> dims{};
  for (int a = 0; a < 3; ++a) {
    const double d = reach_max > 0 ? std::floor(w[a] / reach_max) : 1.0;
    dims[a] = static_cast<int>(std::clamp(std::isfinite(d) ? d : 1.0, 1.0, 1000.0));
    if (s.boxes[a] > 0) dims[a] = std::min(dims[a], s.boxes[a]);   // START x y z nbx nby nbz: at most these
  }
  const std::uint64_t cells = static_cast<std::uint64_t>(dims[0]) * static_cast<std::uint64_t>(dims[1]) *
                              static_cast<std::uint64_t>(dims[2]);
  std::vector<std::uint64_t> cell(n);
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
    cell[k] = static_cast<std::uint64_t>((where[k][2] * dims[1] + where[k][1]) * dims[0] + where[k][0]);
  }
  BinIndex bins;
  bins.build(cell, cells);
  const std::vector<std::uint32_t>& order = bins.order();
  struct Hit { std::uint32_t j; std::int8_t ix, iy, iz; };
  const bool few_cells = dims[0] < 3 || dims[1] < 3 || dims[2] < 3;
  // Ball i's pairs, in ascending j.
  auto emit = [](std::size_t i, Hit* near, std::size_t count, PairCandidates& mine) {
    std::sort(near, near + count, [](const Hit& p, const Hit& q) { return p.j < q.j; });
    for (const Hit& h : std::span<const Hit>(near, count)) {
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
        for (auto [e, e1] = bins.run(q, q); e < e1; ++e) {
          const std::uint32_t j = order[e];
          if (j <= i) continue;
          std::int8_t ix, iy, iz;
          if (nearest_image_within(f, b, i, j, b.rad[i] + b.rad[j] + skin, ix, iy, iz)) near.push_back({j, ix, iy, iz});
        }
      emit(i, near.data(), near.size(), mine);
    }
  };
  // With 3 or more bins on every axis, the 27 bins around a ball's are distinct, and the image of
  // a ball in one of them is the bin's: -1 across the upper face, +1 across the lower one. Within
  // reach (less than half of every width) only one image of j can be, and it is that one, the one
  // nearest_image() finds; so the test below takes the image from the bin and skips the rounding,
  // with the same arithmetic from there on (same pairs, same images, same bits).
  // A bounded axis of a mixed space has no image: its bins do not wrap.
  const std::array<bool, 3> wraps{s.periodic_axis[0], s.periodic_axis[1], s.periodic_axis[2]};
  auto search_bins = [&](std::size_t begin, std::size_t end, PairCandidates& mine) {
    // Each candidate is written to the next slot, which counts only where it is a pair: no branch
    // on the test, whose outcome (about one candidate in ten) a branch would mispredict.
    std::vector<Hit> near(64);
    for (std::size_t i = begin; i < end; ++i) {
      std::size_t hits = 0;
      const double xi = b.x[i], yi = b.y[i], zi = b.z[i], ri = b.rad[i];
      for (int dz = -1; dz <= 1; ++dz) {
        int cz = where[i][2] + dz;
        if (!wraps[2] && (cz < 0 || cz >= dims[2])) continue;
        const std::int8_t iz = cz < 0 ? std::int8_t{-1} : (cz >= dims[2] ? std::int8_t{1} : std::int8_t{0});
        cz -= iz * dims[2];
        for (int dy = -1; dy <= 1; ++dy) {
          int cy = where[i][1] + dy;
          if (!wraps[1] && (cy < 0 || cy >= dims[1])) continue;
          const std::int8_t iy = cy < 0 ? std::int8_t{-1} : (cy >= dims[1] ? std::int8_t{1} : std::int8_t{0});
          cy -= iy * dims[1];
          const std::size_t row = (static_cast<std::size_t>(cz) * dims[1] + cy) * dims[0];
          // The candidates of bins [q0, q1] of this row, all with image (ix, iy, iz).
          auto scan = [&](std::size_t q0, std::size_t q1, std::int8_t ix) {
            double ox, oy, oz;
            image_offset(f, ix, iy, iz, ox, oy, oz);
            const auto [e0, e1] = bins.run(q0, q1);
            if (near.size() < hits + (e1 - e0)) near.resize(2 * (hits + (e1 - e0)));
            for (std::uint32_t e = e0; e < e1; ++e) {
              const std::uint32_t j = order[e];
              const double ddx = image_delta(b.x[j], xi, ox), ddy = image_delta(b.y[j], yi, oy),
                           ddz = image_delta(b.z[j], zi, oz);
              const double reach = ri + b.rad[j] + skin;
              near[hits] = {j, ix, iy, iz};
              hits += static_cast<std::size_t>((j > i) & (ddx * ddx + ddy * ddy + ddz * ddz < reach * reach));
            }
          };
          const int cx0 = where[i][0];
          if (cx0 >= 1 && cx0 + 1 < dims[0]) {   // the three bins along x are one run of the bin order
            scan(row + static_cast<std::size_t>(cx0 - 1), row + static_cast<std::size_t>(cx0 + 1), 0);
            continue;
          }
          for (int dx = -1; dx <= 1; ++dx) {
            int cx = cx0 + dx;
            if (!wraps[0] && (cx < 0 || cx >= dims[0])) continue;
            const std::int8_t ix = cx < 0 ? std::int8_t{-1} : (cx >= dims[0] ? std::int8_t{1} : std::int8_t{0});
            cx -= ix * dims[0];
            scan(row + static_cast<std::size_t>(cx), row + static_cast<std::size_t>(cx), ix);
          }
        }
      }
      emit(i, near.data(), hits, mine);
    }
  };
  auto search_any = [&](std::size_t begin, std::size_t end, PairCandidates& mine) {
    if (few_cells) search(begin, end, mine);
    else search_bins(begin, end, mine);
  };
  const std::size_t first = std::min(i_begin, n), last = std::clamp(i_end, first, n), count = last - first;
  const int parts = pool && count >= kParallelSearch ? pool->size() : 1;
  out.periodic_bins = dims;
  if (parts == 1) { search_any(first, last, out); return; }
  std::vector<PairCandidates> lists(parts);
  pool->run([&](int t) {
    search_any(first + split_point(count, parts, t), first + split_point(count, parts, t + 1), lists[t]);
  });
  for (const PairCandidates& part : lists) out.append(part);
}

}  // namespace trubal
