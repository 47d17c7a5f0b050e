// DELETE on the ranks' live parts (BrickStep::delete_balls): every rank reads the range on its own
// balls, the deleted balls' whole-model places go to every rank, and each takes them out of what
// it holds by whole-model index (the light arrays, the split's lists and cuts) and out of its part
// (the balls, own and copies, their pairs and wall contacts, the exchange lists), everything
// numbered again in the same order: what remove_balls does to a whole model (model/edit.hpp).
#include "cycle/brick_step_parts.hpp"

#include <algorithm>
#include <limits>
#include <numeric>
#include <stdexcept>

#include "model/edit.hpp"

namespace trubal {
namespace {

constexpr std::uint32_t kGone = std::numeric_limits<std::uint32_t>::max();

// A list of indices, those gone dropped and the rest numbered by `next` (ascending stays ascending).
void renumber_kept(std::vector<std::uint32_t>& list, const std::vector<std::uint32_t>& next) {
  std::size_t w = 0;
  for (std::uint32_t q : list)
    if (next[q] != kGone) list[w++] = next[q];
  list.resize(w);
}

}  // namespace

std::size_t BrickStep::delete_balls(Model& full, const Range& range) {
  if (!live_ || team_->shares_whole() || model_ != &full || bonded_)
    throw std::logic_error("internal error: balls deleted on parts that cannot take it");
  hollow_whole(full);   // (rank 0's whole model keeps the light arrays alone, as after a sort)
  const std::size_t n = full_balls_;
  if (full.balls.size() != n) throw std::logic_error("internal error: the whole model's count is not the parts'");
  // This rank's own balls where the range holds (read on its part, with the groups every rank
  // holds), their whole-model places to every rank.
  std::vector<double> mine, all;
  together([&] {
    for (std::uint32_t k : owned_)
      if (holds(full, range, view_of(part_, k))) mine.push_back(static_cast<double>(global_ball_[k]));
  }, "deleting its balls");
  team_->allgather(mine, all);
  if (all.empty()) return 0;   // (the same answer on every rank)
  const std::size_t removed = all.size();

  together([&] {
    // The whole model's new numbering: the balls kept, in their order.
    std::vector<std::uint32_t> next(n, 0);
    for (double v : all) next[static_cast<std::size_t>(v)] = kGone;
    std::vector<std::uint32_t> kept;
    kept.reserve(n - removed);
    std::vector<std::int64_t> gone_ids;
    for (std::size_t k = 0; k < n; ++k) {
      if (next[k] == kGone) {
        gone_ids.push_back(full.balls.id[k]);
        continue;
      }
      next[k] = static_cast<std::uint32_t>(kept.size());
      kept.push_back(static_cast<std::uint32_t>(k));
    }
    std::sort(gone_ids.begin(), gone_ids.end());
    // What every rank holds by whole-model index: the light arrays (rank 0's hollow model's
    // others too: fixities, masses, applied loads), each ball's owner (rank 0's), the split's
    // cuts (a cut's tie goes to the next ball kept), the groups.
    keep_rows([&](auto&& f) { full.balls.for_each_array(f); }, kept, n);
    full.balls.index_ids();
    for (Cut& c : cuts_)
      if (c.left >= 0 && c.at_ball < n) {
        const auto at = std::lower_bound(kept.begin(), kept.end(), c.at_ball);
        c.at_ball = static_cast<std::uint32_t>(at - kept.begin());
      }
    keep_rows([&](auto&& f) { f(owner_); }, kept, n);
    for (auto& [name, ids] : full.groups)
      std::erase_if(ids, [&](std::int64_t id) { return std::binary_search(gone_ids.begin(), gone_ids.end(), id); });
    for (auto& v : rank_pairs_) std::vector<std::uint32_t>().swap(v);   // (the whole list's: made at the next sync)
    for (auto& v : rank_walls_) std::vector<std::uint32_t>().swap(v);

    // The part: its balls kept (own and copies) in their order, their pairs and wall contacts
    // renumbered, as remove_balls leaves a whole model's.
    const std::size_t m = part_.balls.size();
    std::vector<std::uint32_t> local(m, kGone), part_kept;
    for (std::size_t q = 0; q < m; ++q)
      if (next[global_ball_[q]] != kGone) {
        local[q] = static_cast<std::uint32_t>(part_kept.size());
        part_kept.push_back(static_cast<std::uint32_t>(q));
      }
    keep_rows([&](auto&& f) { part_.balls.for_each_array(f); }, part_kept, m);
    part_.balls.index_ids();
    std::vector<std::uint32_t> globals(part_kept.size());
    for (std::size_t k = 0; k < part_kept.size(); ++k) globals[k] = next[global_ball_[part_kept[k]]];
    global_ball_.swap(globals);
    keep_rows([&](auto&& f) { f(scratch_.ghost); }, part_kept, m);
    ref_.keep_rows(part_kept, m);
    renumber_kept(owned_, local);
    for (auto& v : send_) renumber_kept(v, local);   // (both sides of an exchange alike)
    for (auto& v : recv_) renumber_kept(v, local);
    ContactTable& c = part_.contacts;
    const std::size_t pairs = c.size();
    std::vector<std::uint32_t> pairs_kept;
    for (std::size_t p = 0; p < pairs; ++p)
      if (local[c.i[p]] != kGone && local[c.j[p]] != kGone) pairs_kept.push_back(static_cast<std::uint32_t>(p));
    keep_rows([&](auto&& f) { c.for_each_pair_array(f); }, pairs_kept, pairs);
    for (auto& v : c.i) v = local[v];
    for (auto& v : c.j) v = local[v];
    WallContacts& w = part_.wall_contacts;
    const std::size_t touching = w.size();
    std::vector<std::uint32_t> walls_kept;
    for (std::size_t p = 0; p < touching; ++p)
      if (local[w.ball[p]] != kGone) walls_kept.push_back(static_cast<std::uint32_t>(p));
    keep_rows([&](auto&& f) { w.for_each_array(f); }, walls_kept, touching);
    for (auto& v : w.ball) v = local[v];
    owned_pairs_.clear();
    for (std::size_t p = 0; p < c.size(); ++p)
      if (!scratch_.ghost[c.i[p]]) owned_pairs_.push_back(static_cast<std::uint32_t>(p));
    owned_walls_.resize(w.size());   // (a part's wall contacts are its own balls')
    std::iota(owned_walls_.begin(), owned_walls_.end(), 0u);
    c.list_version = next_part_version();
    w.list_version = next_part_version();
    index_part();
    scratch_.index_walls(w, part_.balls.size());
    ghosts_ = static_cast<std::size_t>(std::count(scratch_.ghost.begin(), scratch_.ghost.end(), 1));
  }, "deleting its balls");
  // Each member's count of balls, less those it deleted (balanced_after_moves reads them).
  std::vector<double> own{static_cast<double>(mine.size())}, counts;
  team_->allgather(own, counts);
  for (std::size_t r = 0; r < rank_counts_.size() && r < counts.size(); ++r)
    rank_counts_[r] -= static_cast<std::size_t>(counts[r]);
  full_balls_ = n - removed;
  max_radius_ = full.balls.max_radius();   // (a pair's reach, as serial's list after DELETE)
  remake_rows();
  free_saved();
  free_copy();   // (of the parts before: the next CYCLE takes its own)
  ++edition_;
  // The whole model's list is made from the parts' at the next sync; the results the parts hold
  // are the pairs kept's, as remove_balls keeps a whole table's.
  list_local_ = true;
  whole_list_kept_ = false;
  current_ = false;
  shared_ = false;
  return removed;
}

}  // namespace trubal
