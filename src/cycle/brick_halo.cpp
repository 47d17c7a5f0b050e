// The halo of a rebuild on the parts: bins as wide as the farthest reach of a pair, each member's
// balls marked in them, and the balls each member sends each other, those next to a bin the other
// marked (its shell).
#include "cycle/brick_step_parts.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>

namespace trubal {

void ShellBins::fit(const Space& s, const std::vector<double>& box, double reach, std::size_t balls) {
  s_ = &s;
  periodic_ = s.periodic;
  const double across = reach * (1 + 1e-9) + 1e-300;   // (a margin against rounding at a bin's edge)
  for (int a = 0; a < 3; ++a) {
    wraps_[a] = s.wraps(a);
    double width;
    if (periodic_) {
      width = cell_widths(s)[a];
      lo_[a] = s.lo[a];
      extent_[a] = s.length()[a];
    } else {
      lo_[a] = box[a];
      width = extent_[a] = box[3 + a] > box[a] ? box[3 + a] - box[a] : 0.0;
    }
    const double d = std::floor(width / across);
    dims_[a] = static_cast<int>(std::clamp(std::isfinite(d) ? d : 1.0, 1.0, 1000.0));
  }
  while (static_cast<double>(dims_[0]) * dims_[1] * dims_[2] > 2.0 * static_cast<double>(balls) + 27)
    for (int& d : dims_) d = std::max(1, d / 2);
  if (periodic_) frame_ = cell_frame(s);
}

void ShellBins::neighbours(std::uint32_t bin, std::vector<std::uint32_t>& out) const {
  out.clear();
  const int w[3] = {static_cast<int>(bin % dims_[0]), static_cast<int>((bin / dims_[0]) % dims_[1]),
                    static_cast<int>(bin / (static_cast<std::uint32_t>(dims_[0]) * dims_[1]))};
  for (int dz = -1; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        int c[3] = {w[0] + dx, w[1] + dy, w[2] + dz};
        bool inside = true;
        for (int a = 0; a < 3; ++a) {
          if (c[a] >= 0 && c[a] < dims_[a]) continue;
          if (wraps_[a]) c[a] = (c[a] + dims_[a]) % dims_[a];
          else inside = false;
        }
        if (inside) out.push_back(static_cast<std::uint32_t>((c[2] * dims_[1] + c[1]) * dims_[0] + c[0]));
      }
}

std::uint64_t ShellBins::around(std::uint32_t bin, const std::uint64_t* mask,
                                std::vector<std::uint32_t>& scratch) const {
  const int w[3] = {static_cast<int>(bin % dims_[0]), static_cast<int>((bin / dims_[0]) % dims_[1]),
                    static_cast<int>(bin / (static_cast<std::uint32_t>(dims_[0]) * dims_[1]))};
  std::uint64_t m = 0;
  if (w[0] >= 1 && w[0] + 1 < dims_[0] && w[1] >= 1 && w[1] + 1 < dims_[1] && w[2] >= 1 && w[2] + 1 < dims_[2]) {
    const std::size_t row = static_cast<std::size_t>(dims_[0]), plane = row * static_cast<std::size_t>(dims_[1]);
    const std::uint64_t* centre = mask + bin;
    for (std::size_t z = 0; z < 3; ++z)   // (the bin is inside: all 27 are distinct and in range)
      for (std::size_t y = 0; y < 3; ++y) {
        const std::uint64_t* r = centre + z * plane + y * row - plane - row;
        m |= r[-1] | r[0] | r[1];
      }
    return m;
  }
  neighbours(bin, scratch);
  for (std::uint32_t c : scratch) m |= mask[c];
  return m;
}

void BrickStep::fit_shell_bins(Rebuild& r, const Space& space) const {
  // Bins at least `reach` wide across (the periodic search's, in the cell's fractional coordinates;
  // in a box, over the extent of every rank's balls): a pair's balls lie in neighbouring bins. Each
  // rank marks the bins its balls are in, and sends a rank its balls next to a bin that rank marked.
  const Balls& b = part_.balls;
  constexpr double kInf = std::numeric_limits<double>::infinity();
  std::vector<double> box{kInf, kInf, kInf, -kInf, -kInf, -kInf}, boxes;
  if (!space.periodic)
    for (std::uint32_t k : owned_) {
      const double p[3] = {b.x[k], b.y[k], b.z[k]};
      for (int a = 0; a < 3; ++a) {
        if (!std::isfinite(p[a])) continue;   // (a ball at NaN touches nothing, in the serial search too)
        box[a] = std::min(box[a], p[a]);
        box[3 + a] = std::max(box[3 + a], p[a]);
      }
    }
  team_->allgather(box, boxes);   // (a collective call either way)
  for (int q = 0; q < r.ranks; ++q)
    for (int a = 0; a < 3; ++a) {
      box[a] = std::min(box[a], boxes[6 * q + a]);
      box[3 + a] = std::max(box[3 + a], boxes[6 * q + 3 + a]);
    }
  r.bins.fit(space, box, r.reach, full_balls_);
}

void BrickStep::mark_bins(Rebuild& r) const {
  // The bins of the balls this rank will own (its own that stay and those that move here), a bit
  // each, for every rank to read.
  r.marks.assign((r.bins.count() + 7) / 8, 0);
  auto mark = [&](std::uint32_t bin) { r.marks[bin / 8] |= static_cast<std::uint8_t>(1u << (bin % 8)); };
  for (std::size_t q = 0; q < owned_.size(); ++q)
    if (r.dest[q] == r.me && r.bin_of[q] != ShellBins::kNone) mark(r.bin_of[q]);
  for (std::size_t t = 0; t < r.moved; ++t)
    if (static_cast<int>(r.all_moves[Rebuild::kMove * t + 1]) == r.me)
      mark(static_cast<std::uint32_t>(r.all_moves[Rebuild::kMove * t + 2]));
}

void BrickStep::find_shells(Rebuild& r) const {
  // Each rank's shell: this rank's balls in a bin next to one that rank marked, and those that move
  // to it.
  const int ranks = r.ranks, me = r.me;
  r.shell.assign(ranks, {});
  const std::size_t stride = r.marks.size();
  std::vector<std::uint32_t> near;
  // The ranks 64 at a time (one chunk up to 64 ranks): each bin's other ranks of the chunk as the
  // bits of a word, and a ball's as the OR of the words of its bins around, with its new owner's
  // (which marked its bin). Each rank's shell lists its balls in this rank's order.
  std::vector<std::uint64_t> others(r.bins.count());
  for (int first = 0; first < ranks; first += 64) {
    const int last = std::min(ranks, first + 64);
    auto bit = [first](int q) { return std::uint64_t{1} << (q - first); };
    std::fill(others.begin(), others.end(), 0);
    for (int q = first; q < last; ++q) {
      if (q == me) continue;
      const std::uint8_t* row = r.all_marks.data() + static_cast<std::size_t>(q) * stride;
      for (std::size_t byte = 0; byte < stride; ++byte)
        for (unsigned set = row[byte]; set != 0; set &= set - 1) others[8 * byte + std::countr_zero(set)] |= bit(q);
    }
    for (std::size_t q = 0; q < owned_.size(); ++q) {
      if (r.bin_of[q] == ShellBins::kNone) continue;
      std::uint64_t m = r.bins.around(r.bin_of[q], others.data(), near);
      if (r.dest[q] >= first && r.dest[q] < last && r.dest[q] != me) m |= bit(r.dest[q]);
      for (; m != 0; m &= m - 1) r.shell[static_cast<std::size_t>(first + std::countr_zero(m))].push_back(owned_[q]);
    }
  }
}

}  // namespace trubal
