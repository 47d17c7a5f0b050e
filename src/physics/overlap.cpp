#include "physics/overlap.hpp"

#include <algorithm>
#include <cmath>

#include "model/periodic_cell.hpp"
#include "model/wall_shape.hpp"

namespace trubal {

LargestOverlap largest_overlap(const Model& model, double threshold, const std::vector<std::uint32_t>* pairs,
                               const std::vector<std::uint32_t>* walls) {
  LargestOverlap out;
  const Balls& b = model.balls;
  const ContactTable& c = model.contacts;
  const CellFrame frame = cell_frame(model.space);
  const bool periodic = model.space.periodic && c.image_x.size() == c.size();
  auto take = [&](double ratio, std::int64_t ball, std::int64_t other, bool wall, std::size_t at) {
    if (!(ratio > threshold)) return;   // (a NaN position is the instability guard's)
    ++out.beyond;
    if (ratio > out.ratio) out = {ratio, ball, other, wall, out.beyond, at};
  };
  // f(p) on each entry of `subset`, or of [0, n) where there is none.
  auto each = [](const std::vector<std::uint32_t>* subset, std::size_t n, auto&& f) {
    if (!subset) {
      for (std::size_t p = 0; p < n; ++p) f(p);
      return;
    }
    for (std::uint32_t p : *subset)
      if (p < n) f(p);
  };
  each(pairs, c.size(), [&](std::size_t p) {
    const std::size_t i = c.i[p], j = c.j[p];
    if (i >= b.size() || j >= b.size()) return;
    const auto [dx, dy, dz] = pair_separation(frame, periodic, b, c, p);
    const double overlap = b.rad[i] + b.rad[j] - std::sqrt(dx * dx + dy * dy + dz * dz);
    const std::size_t small = b.rad[j] < b.rad[i] ? j : i;
    take(overlap / b.rad[small], b.id[small], b.id[small == i ? j : i], false, p);
  });
  const WallContacts& w = model.wall_contacts;
  each(walls, w.ball.size(), [&](std::size_t p) {
    const std::size_t k = w.ball[p], wall = w.wall[p];
    // (The list of the last search: a ball deleted since is skipped.)
    if (k >= b.size() || wall >= model.walls.size() || p >= w.ball_id.size() || b.id[k] != w.ball_id[p]) return;
    const WallTouch t = wall_touch(model.walls[wall], {b.x[k], b.y[k], b.z[k]});
    if (!(t.gap > -b.rad[k])) return;   // past a one-sided wall: no contact (physics/walls.hpp wall_lane)
    take((b.rad[k] - t.gap) / b.rad[k], b.id[k], model.walls[wall].id, true, p);
  });
  return out;
}

}  // namespace trubal
