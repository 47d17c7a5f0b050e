#include "cycle/wall_list.hpp"

#include <algorithm>
#include <numeric>

#include "cycle/pair_list.hpp"

#include <atomic>
#include <type_traits>

#include "model/wall_shape.hpp"

namespace trubal {
namespace {

// Fewer balls than this are searched on one thread.
constexpr std::size_t kParallelBalls = 8192;

}  // namespace

void find_wall_contacts(Model& model, double reach, ThreadPool& pool) {
  WallContacts& table = model.wall_contacts;
  const Balls& b = model.balls;
  const std::size_t n = b.size(), walls = model.walls.size();
  // Per thread, the candidates of its share of the balls, then joined in ball order.
  const int parts = n >= kParallelBalls ? pool.size() : 1;
  std::vector<std::vector<std::uint32_t>> found(parts);
  pool.run([&](int t) {
    if (t >= parts) return;
    std::vector<std::uint32_t>& out = found[t];
    for (std::size_t i = split_point(n, parts, t); i < split_point(n, parts, t + 1); ++i)
      for (std::size_t w = 0; w < walls; ++w) {
        const WallTouch touch = wall_touch(model.walls[w], {b.x[i], b.y[i], b.z[i]});
        // A one-sided wall touches a centre up to R past its surface (physics/walls.hpp), so a
        // centre may come into contact from behind too: the skin on both sides.
        if (touch.gap < b.rad[i] + reach && touch.gap > -b.rad[i] - reach) {
          out.push_back(static_cast<std::uint32_t>(i));
          out.push_back(static_cast<std::uint32_t>(w));
        }
      }
  }, parts > 1);
  WallContacts next;
  for (const auto& part : found)
    for (std::size_t k = 0; k < part.size(); k += 2) {
      next.ball.push_back(part[k]);
      next.wall.push_back(part[k + 1]);
      next.ball_id.push_back(b.id[part[k]]);
      next.wall_id.push_back(model.walls[part[k + 1]].id);
    }
  const std::size_t size = next.ball.size();
  next.for_each_history([&](auto& v, const HistoryPart&) { v.assign(size, 0.0); });
  next.for_each_result_array([&](auto& v) { v.assign(size, {}); });
  // The history by (ball id, wall id). The lists are in (ball index, wall) order, and the old one's
  // indices may be another numbering's (a part's, before balls moved between parts): each is read
  // in (ball id, wall id) order to match them.
  const std::size_t old = table.ball_id.size();
  bool consistent = table.wall_id.size() == old && table.state.size() == old;
  table.for_each_history([&](const auto& v, const HistoryPart&) { consistent = consistent && v.size() == old; });
  // The arrays of the old table, in the order the new one lists them (to copy an entry across).
  std::vector<const std::vector<double>*> old_history;
  table.for_each_history([&](const auto& v, const HistoryPart&) { old_history.push_back(&v); });
  if (consistent && old > 0) {
    const auto by_ids = [](const WallContacts& t) {
      std::vector<std::size_t> at(t.ball_id.size());
      std::iota(at.begin(), at.end(), std::size_t{0});
      std::sort(at.begin(), at.end(), [&](std::size_t p, std::size_t q) {
        return t.ball_id[p] != t.ball_id[q] ? t.ball_id[p] < t.ball_id[q] : t.wall_id[p] < t.wall_id[q];
      });
      return at;
    };
    const std::vector<std::size_t> olds = by_ids(table), news = by_ids(next);
    std::size_t o = 0;
    for (const std::size_t q : news) {
      while (o < old && (table.ball_id[olds[o]] < next.ball_id[q] ||
                         (table.ball_id[olds[o]] == next.ball_id[q] && table.wall_id[olds[o]] < next.wall_id[q])))
        ++o;
      if (o == old) break;
      const std::size_t p = olds[o];
      if (table.ball_id[p] == next.ball_id[q] && table.wall_id[p] == next.wall_id[q]) {
        std::size_t h = 0;
        next.for_each_history([&](auto& v, const HistoryPart&) { v[q] = (*old_history[h++])[p]; });
        if (table.nx.size() == old) {   // the last results stay readable until the next pass
          next.nx[q] = table.nx[p]; next.ny[q] = table.ny[p]; next.nz[q] = table.nz[p];
          next.overlap[q] = table.overlap[p]; next.fn[q] = table.fn[p];
          next.fx[q] = table.fx[p]; next.fy[q] = table.fy[p]; next.fz[q] = table.fz[p];
        }
        if (table.kn_eff.size() == old) { next.kn_eff[q] = table.kn_eff[p]; next.ks_eff[q] = table.ks_eff[p]; }
        next.state[q] = table.state[p];
      }
    }
  }
  next.list_version = fresh_list_version();   // (one counter with the pair lists': never one of theirs)
  table = std::move(next);
}

}  // namespace trubal
