// The balls put in space order on the ranks' parts (BrickStep::sort_in_space): the ranks agree on
// the new order from their own balls' keys, and every copy of the numbering follows it, with no
// rank holding more of the whole model than the light arrays it holds already.
#include "cycle/brick_step_parts.hpp"

#include <algorithm>
#include <bit>
#include <numeric>
#include <stdexcept>

#include "model/edit.hpp"

namespace trubal {
namespace {

// A list of part indices renumbered by `local` (old index -> new), ascending again.
void renumber(std::vector<std::uint32_t>& list, const std::vector<std::uint32_t>& local) {
  for (auto& q : list) q = local[q];
  std::sort(list.begin(), list.end());
}

}  // namespace

std::vector<std::uint32_t> BrickStep::sort_in_space(Model& full) {
  if (!live_ || !scatters() || model_ != &full)
    throw std::logic_error("internal error: the balls sorted on the ranks' parts where none is live");
  // Rank 0's whole model lets go of what the parts step (if a sync gathered it since): what is
  // left of it on every rank is the light arrays, which follow the order below.
  hollow_whole(full);
  const std::size_t n = full_balls_;
  if (full.balls.size() != n) throw std::logic_error("internal error: the whole model's count is not the parts'");

  // The keys of this rank's own balls, from the corner of every rank's (serial's space_order: the
  // least finite coordinate of all the balls), with their whole-model indices; every rank's to
  // every rank, which puts them in order by key, then id (every rank holds the ids), as serial
  // does: the order is a function of the centres and ids alone.
  const double cell = order_cell(full.balls);
  std::vector<double> keys;
  together([&] {
    const std::array<double, 3> lo = space_corner(part_.balls, &owned_);
    keys = {-lo[0], -lo[1], -lo[2]};
  }, "putting the balls in space order");
  team_->max_all(keys);
  const std::array<double, 3> lo{-keys[0], -keys[1], -keys[2]};
  std::vector<double> mine, all;
  together([&] {
    const Balls& b = part_.balls;
    mine.resize(2 * owned_.size());
    for (std::size_t t = 0; t < owned_.size(); ++t) {
      const std::uint32_t q = owned_[t];
      mine[2 * t] = global_ball_[q];
      mine[2 * t + 1] = std::bit_cast<double>(space_key(b.x[q], b.y[q], b.z[q], lo, cell));
    }
  }, "putting the balls in space order");
  team_->allgather(mine, all);
  std::vector<double>().swap(mine);
  std::vector<std::uint32_t> order;
  together([&] {
    if (all.size() != 2 * n) throw std::logic_error("internal error: the ranks' balls are not the whole model's");
    order.resize(n);
    std::iota(order.begin(), order.end(), 0u);
    const std::vector<std::int64_t>& id = full.balls.id;
    auto key = [&](std::uint32_t p) { return std::bit_cast<std::uint64_t>(all[2 * p + 1]); };
    auto ball = [&](std::uint32_t p) { return static_cast<std::uint32_t>(all[2 * p]); };
    std::sort(order.begin(), order.end(), [&](std::uint32_t p, std::uint32_t q) {
      const std::uint64_t kp = key(p), kq = key(q);
      return kp != kq ? kp < kq : id[ball(p)] < id[ball(q)];
    });
    for (auto& p : order) p = ball(p);
  }, "putting the balls in space order");
  std::vector<double>().swap(all);
  ++sorts_;
  bool moved = false;
  for (std::size_t k = 0; k < n && !moved; ++k) moved = order[k] != k;
  if (!moved) return {};   // (the same answer on every rank: every rank made the one order)

  together([&] {
    std::vector<std::uint32_t> new_index(n);
    for (std::size_t k = 0; k < n; ++k) new_index[order[k]] = static_cast<std::uint32_t>(k);
    // What every rank holds by whole-model index: the light arrays, each ball's owner and each
    // rank's balls, the split's cuts (their ties broken by index: a ball on a cut may fall on its
    // other side now, and moves at the next rebuild on the parts), the split's bonds.
    permute_arrays([&](auto&& f) { full.balls.for_each_array(f); }, order);
    full.balls.index_ids();
    for (Cut& c : cuts_)
      if (c.left >= 0) c.at_ball = c.at_ball < n ? new_index[c.at_ball] : c.at_ball;
    for (auto& k : split_bond_ball_i_) k = new_index[k];
    permute_arrays([&](auto&& f) { f(owner_); }, order);   // (rank 0's; the others keep none)
    for (auto& v : rank_pairs_) std::vector<std::uint32_t>().swap(v);   // (the whole list's: made at the next sync)
    for (auto& v : rank_walls_) std::vector<std::uint32_t>().swap(v);

    // The part: its balls in their new whole order (a part is numbered in the whole model's
    // order), its pairs and wall contacts renumbered and sorted as serial's table is
    // (reorder_balls: a pair whose balls change order is turned round), its list kept (a step
    // does not depend on when its list was made, only that it holds every pair in reach).
    const std::size_t m = part_.balls.size();
    for (auto& k : global_ball_) k = new_index[k];
    std::vector<std::uint32_t>().swap(new_index);
    std::vector<std::size_t> local_order(m);
    std::iota(local_order.begin(), local_order.end(), std::size_t{0});
    std::sort(local_order.begin(), local_order.end(),
              [&](std::size_t p, std::size_t q) { return global_ball_[p] < global_ball_[q]; });
    std::vector<std::uint32_t> local(m);
    for (std::size_t k = 0; k < m; ++k) local[local_order[k]] = static_cast<std::uint32_t>(k);
    reorder_balls(part_, local_order);
    std::sort(global_ball_.begin(), global_ball_.end());
    std::vector<std::uint32_t> part_order(local_order.begin(), local_order.end());
    std::vector<std::size_t>().swap(local_order);
    ref_.reorder(part_order);
    permute_arrays([&](auto&& f) { f(scratch_.ghost); }, part_order);
    renumber(owned_, local);
    remake_rows();
    for (auto& v : send_) renumber(v, local);   // (both sides of an exchange in the whole order)
    for (auto& v : recv_) renumber(v, local);
    // The pairs each rank reports are those whose ball i it owns, which may be the other ball now.
    const ContactTable& c = part_.contacts;
    owned_pairs_.clear();
    for (std::size_t p = 0; p < c.size(); ++p)
      if (!scratch_.ghost[c.i[p]]) owned_pairs_.push_back(static_cast<std::uint32_t>(p));
    owned_walls_.resize(part_.wall_contacts.size());   // (a part's wall contacts are its own balls')
    std::iota(owned_walls_.begin(), owned_walls_.end(), 0u);
    part_.contacts.list_version = next_part_version();
    part_.wall_contacts.list_version = next_part_version();
    part_.bonds.changed();
    index_part();
    scratch_.index_walls(part_.wall_contacts, m);
  }, "putting the balls in space order");
  free_saved();
  ++edition_;
  // The whole model's list is made from the parts' at the next sync; the results the parts held
  // are of the state before (the step about to be taken writes its own).
  list_local_ = true;
  whole_list_kept_ = false;
  current_ = false;
  shared_ = false;
  results_written_ = results_left_ = false;
  return order;
}

}  // namespace trubal
