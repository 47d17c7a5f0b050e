// A new pair list on the parts (BrickStep::rebuild_local) as its stages in order, and the stages
// that make the new part: the search, the history carried over, the balls and ghosts, the walls.
#include "cycle/brick_step_parts.hpp"

#include <algorithm>
#include <cmath>
#include <new>
#include <numeric>

#include "cycle/pair_list.hpp"
#include "cycle/wall_list.hpp"
#include "physics/pair_laws.hpp"

namespace trubal {

bool BrickStep::rebuild_local(const Model& full, double skin, Backend& search, ThreadPool& pool) {
  // (Every test below reads what is the same on every rank, or is agreed on: every rank returns
  // alike. The calls on team_ and the stages said to be collective are made by every member.)
  if (!may_rebuild_local(full)) return false;
  Rebuild r;
  r.ranks = team_->size();
  r.me = team_->rank();
  r.skin = skin;
  r.reach = 2 * max_radius_ + skin;   // the farthest any pair's balls may be apart

  // Who owns each ball from now on: the brick of the split that holds it (brick_split.cpp).
  fit_shell_bins(r, full.space);   // (collective)
  together([&] { find_moves(r); }, "finding the balls that change owner");
  team_->allgather(r.moves, r.all_moves);
  r.moved = r.all_moves.size() / 3;
  if (!balanced_after_moves(r)) return false;
  // The halo, which of this member's balls each other needs (brick_halo.cpp), and what leaves with
  // a moving ball (brick_migrate.cpp).
  together([&] { mark_bins(r); }, "finding the balls its neighbours need for a new pair list");
  team_->allgather(r.marks, r.all_marks);
  together([&] {
    find_shells(r);
    find_leaving(r);
    announce_counts(r);
  }, "finding the balls its neighbours need for a new pair list");
  // The exchange: the counts, then the records (brick_migrate.cpp).
  team_->exchange(r.out, r.in);
  if (!shells_within_bounds(r)) return false;   // (collective)
  together([&] { pack_messages(r); }, "sending the balls its neighbours need for a new pair list");
  team_->exchange(r.out, r.in);
  // What arrived, and the new part made from it beside the old one: the search, the history
  // carried over, the balls and ghosts.
  together([&] {
    if (!team_->shares_whole() && team_->rank() == policy_->fail_part_search) {   // (a rank's test fault)
      policy_->fail_part_search = -1;
      throw std::bad_alloc();
    }
    list_entries(r);
    unpack_arrivals(r);
    search_part(r, full.space, search);
    carry_history(r);
    make_next_balls(r);
  }, "making a new pair list for its part");
  // (Threads: no member commits where another failed; ranks agreed in together.)
  if (team_->shares_whole()) team_->barrier();
  // The new part in the old one's place, then what is made from it.
  commit_rebuild(r);
  together([&] { index_part(); }, "indexing its new pair list");
  if (!full.walls.empty() || part_.wall_contacts.size() > 0)
    together([&] { find_part_walls(r, full, pool); }, "finding the wall contacts of its part");
  return true;
}

bool BrickStep::may_rebuild_local(const Model& full) {
  if (policy_->local_rule < 0 || !live_ || model_ != &full) return false;
  if (results_written_ && !current_) return false;   // (the parts hold results the whole model has not)
  // A bonded scene's ghosts include its bonds' other balls, which a search within the list's reach
  // need not find: its parts are made afresh from the whole model, whose bonds every member reads.
  if (bonded_) return false;
  // The members' speeds have moved the shares by a tenth since the split (a core slowed, contacts
  // crowding in a part): the parts are made afresh, balanced by them.
  const std::vector<double> next = proposed_shares();   // (a collective call; the same on every member)
  for (std::size_t r = 0; r < next.size(); ++r)
    if (std::abs(next[r] - shares_[r]) > 0.1 * shares_[r]) return false;
  return true;
}

void BrickStep::search_part(Rebuild& r, const Space& space, Backend& search) const {
  // The serial test on the entries (a pair's result depends on its two balls alone), keeping the
  // pairs of this rank's balls; their partners from elsewhere are the ghosts. The search reads the
  // count (ids), the places and the radii.
  Model scan;
  scan.space = space;
  r.fill(part_.balls, scan.balls, nullptr, [](const Balls& to, const void* v) {
    return v == &to.id || v == &to.x || v == &to.y || v == &to.z || v == &to.rad;
  });
  search.find_part_pairs(scan, r.skin, r.found);
  const std::size_t count = r.entries.size();
  std::vector<std::uint8_t> kind(count, 0);   // 1 this rank's, 2 a ghost
  for (std::size_t q = 0; q < count; ++q)
    if (r.entries[q].owner == r.me) kind[q] = 1;
  const PairCandidates& found = r.found;
  for (std::size_t p = 0; p < found.i.size(); ++p) {
    const std::uint32_t i = found.i[p], j = found.j[p];
    if (kind[i] != 1 && kind[j] != 1) continue;
    r.pairs.push_back(static_cast<std::uint32_t>(p));
    if (kind[i] != 1) kind[i] = 2;
    if (kind[j] != 1) kind[j] = 2;
  }
  r.local.assign(count, kAbsent);
  for (std::size_t q = 0; q < count; ++q)
    if (kind[q]) {
      r.local[q] = static_cast<std::uint32_t>(r.keep.size());
      r.keep.push_back(static_cast<std::uint32_t>(q));
    }
}

void BrickStep::carry_history(Rebuild& r) const {
  // The history carried over by the pair (the old list holds every pair of this rank's balls),
  // matched in the whole model's numbers.
  r.next_table = part_.contacts;
  ContactTable& c = r.next_table;
  for (std::size_t p = 0; p < c.size(); ++p) {
    c.i[p] = global_ball_[c.i[p]];
    c.j[p] = global_ball_[c.j[p]];
  }
  // With the pairs of the balls that moved here, in the list's order (a pair this rank held too
  // has the same history in both: either serves).
  if (r.arrived_pairs.size() > 0) {
    c.drop_results();
    merge_in_order(visit_pairs, c, c.size(), r.arrived_pairs,
                   [&](std::uint32_t p, std::uint32_t q) { return pair_before(c, p, c, q); });
    r.arrived_pairs = ContactTable{};
  }
  const PairCandidates& found = r.found;
  PairCandidates next;
  for (std::uint32_t p : r.pairs) {
    next.i.push_back(r.entries[found.i[p]].global);
    next.j.push_back(r.entries[found.j[p]].global);
    next.image_x.push_back(found.image_x[p]);
    next.image_y.push_back(found.image_y[p]);
    next.image_z.push_back(found.image_z[p]);
  }
  install_pairs(c, next);
  for (std::size_t q = 0; q < r.pairs.size(); ++q) {
    c.i[q] = r.local[found.i[r.pairs[q]]];
    c.j[q] = r.local[found.j[r.pairs[q]]];
  }
  r.found = PairCandidates{};   // (what follows is the part's largest: its balls)
  c.list_version = next_part_version();
}

void BrickStep::make_next_balls(Rebuild& r) const {
  // The part's balls, and what it sends and receives each step.
  const std::size_t m = r.keep.size();
  r.fill(part_.balls, r.next_balls, &r.keep, [](const Balls&, const void*) { return true; });
  for (auto& v : r.in) std::vector<double>().swap(v);
  r.next_ref.x = r.next_balls.x;
  r.next_ref.y = r.next_balls.y;
  r.next_ref.z = r.next_balls.z;
  r.next_global.resize(m);
  r.next_ghost.assign(m, 0);
  r.next_send.assign(r.ranks, {});
  r.next_recv.assign(r.ranks, {});
  std::vector<int> owner(m, r.me);
  for (std::size_t q = 0; q < m; ++q) {
    const Rebuild::Entry& e = r.entries[r.keep[q]];
    r.next_global[q] = e.global;
    if (e.owner == r.me) {
      r.next_owned.push_back(static_cast<std::uint32_t>(q));
      continue;
    }
    owner[q] = e.owner;
    r.next_ghost[q] = 1;
    r.next_recv[e.owner].push_back(static_cast<std::uint32_t>(q));
    ++r.next_ghosts;
  }
  const ContactTable& c = r.next_table;
  for (std::size_t q = 0; q < c.size(); ++q) {
    const std::uint32_t i = c.i[q], j = c.j[q];
    if (!r.next_ghost[i]) r.next_owned_pairs.push_back(static_cast<std::uint32_t>(q));
    if (r.next_ghost[i] != r.next_ghost[j]) {
      if (r.next_ghost[j]) r.next_send[owner[j]].push_back(i);
      else r.next_send[owner[i]].push_back(j);
    }
  }
  for (auto& v : r.next_send) {
    std::sort(v.begin(), v.end());
    v.erase(std::unique(v.begin(), v.end()), v.end());
  }
}

void BrickStep::commit_rebuild(Rebuild& r) {
  // The new part in the old one's place, every rank's record of the owners following the moves.
  // (Nothing here fails: the index and the laws, which a sync does not read, come after.)
  std::swap(part_.balls, r.next_balls);
  std::swap(part_.contacts, r.next_table);
  global_ball_.swap(r.next_global);
  owned_.swap(r.next_owned);
  owned_pairs_.swap(r.next_owned_pairs);
  send_.swap(r.next_send);
  recv_.swap(r.next_recv);
  scratch_.ghost.swap(r.next_ghost);
  ghosts_ = r.next_ghosts;
  ref_.x.swap(r.next_ref.x);
  ref_.y.swap(r.next_ref.y);
  ref_.z.swap(r.next_ref.z);
  if (r.moved > 0) {   // every rank's record of the owners (sync gathers each rank's balls by it)
    for (std::size_t t = 0; t < r.moved; ++t)
      owner_[static_cast<std::size_t>(r.all_moves[3 * t])] = static_cast<int>(r.all_moves[3 * t + 1]);
    for (auto& v : rank_balls_) v.clear();
    for (std::size_t k = 0; k < owner_.size(); ++k) rank_balls_[owner_[k]].push_back(static_cast<std::uint32_t>(k));
    most_balls_ = *std::max_element(r.count.begin(), r.count.end());
    least_balls_ = *std::min_element(r.count.begin(), r.count.end());
    migrations_ += r.moved;
  }
  ++local_rebuilds_;
  list_local_ = true;
  current_ = false;
  shared_ = false;
  moved2_ = 0;
  outside_box_ = false;
}

void BrickStep::index_part() {
  // The ghost exchange's buffers, the step's index of the new list, the part's pair laws.
  const int ranks = team_->size();
  const std::size_t m = part_.balls.size();
  send_buf_.assign(ranks, {});
  recv_buf_.assign(ranks, {});
  for (int r = 0; r < ranks; ++r) {
    send_buf_[r].resize(kHalo * send_[r].size());
    recv_buf_[r].resize(kHalo * recv_[r].size());
  }
  scratch_.index(part_.contacts, m);
  scratch_.index_walls(part_.wall_contacts, m);
  kernels_.laws = make_pair_laws(part_);
}

void BrickStep::find_part_walls(Rebuild& r, const Model& full, ThreadPool& pool) {
  // The walls' contacts of this rank's balls, their history carried by (ball id, wall id) from
  // the part's old ones (which hold every contact of these balls).
  const std::size_t m = part_.balls.size();
  part_.walls = full.walls;
  if (r.arrived_walls.size() > 0) {
    // The part's old contacts (the history find_wall_contacts carries over, by ball id and
    // wall id) with those of the balls that moved here, in that order.
    WallContacts& w = part_.wall_contacts;
    merge_in_order(visit_walls, w, w.size(), r.arrived_walls, [&](std::uint32_t p, std::uint32_t q) {
      return w.ball_id[p] < w.ball_id[q] || (w.ball_id[p] == w.ball_id[q] && w.wall_id[p] < w.wall_id[q]);
    });
  }
  find_wall_contacts(part_, r.skin, pool);
  WallContacts& w = part_.wall_contacts;
  std::vector<std::uint32_t> mine;
  for (std::size_t q = 0; q < w.size(); ++q)
    if (!scratch_.ghost[w.ball[q]]) mine.push_back(static_cast<std::uint32_t>(q));
  if (mine.size() != w.size()) {
    WallContacts kept;
    gather(visit_walls, &w, &kept, mine);
    kept.list_version = w.list_version;
    w = std::move(kept);
  }
  owned_walls_.resize(w.size());
  std::iota(owned_walls_.begin(), owned_walls_.end(), 0u);
  scratch_.index_walls(w, m);
}

}  // namespace trubal
