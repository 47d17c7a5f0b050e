// A new pair list on the parts (BrickStep::rebuild_local) as its stages in order, and the stages
// that make the new part: the search, the history carried over, the balls and ghosts, the walls.
#include "cycle/brick_step_parts.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <new>
#include <numeric>
#include <stdexcept>

#include "cycle/pair_list.hpp"
#include "cycle/wall_list.hpp"
#include "model/edit.hpp"
#include "physics/pair_laws.hpp"

namespace trubal {

bool BrickStep::rebuild_local(const Model& full, double skin, Backend& search, ThreadPool& pool) {
  results_left_ = false;   // (the list changes: rank 0's copy makes the results where read, make_results)
  // (Every test below reads what is the same on every rank, or is agreed on: every rank returns
  // alike. The calls on team_ and the stages said to be collective are made by every member.)
  if (!may_rebuild_local(full)) return false;
  Rebuild r;
  r.ranks = team_->size();
  r.me = team_->rank();
  r.skin = skin;
  r.reach = 2 * max_radius_ + skin;   // the farthest any pair's balls may be apart
  // A bonded scene: its bonds' other balls come in the halo where no intact bond is longer than
  // a pair may be; else the parts are made afresh from the whole model. (collective)
  if (bonded_ && !bonds_within(full.space, r.reach)) return false;
  if (from_file_) {
    r.from_file = true;
    r.file_pairs = std::move(file_pairs_);
    r.file_walls = std::move(file_walls_);
    from_file_ = false;
  }

  // Who owns each ball from now on: the brick of the split that holds it (brick_split.cpp).
  fit_shell_bins(r, full.space);   // (collective)
  together([&] { find_moves(r); }, "finding the balls that change owner");
  team_->allgather(r.moves, r.all_moves);
  r.moved = r.all_moves.size() / Rebuild::kMove;
  // (A split's owners are those of its bricks: parts just made from a save keep their balls, and
  // the pairs and wall contacts that came with them stay where they came.)
  if (r.from_file && r.moved > 0) throw std::logic_error("internal error: a ball changed owner at the first list of parts made from a save");
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
  // (The wall contacts are still the old part's, numbered by its balls: found afresh, then indexed.
  // A part made from a save: those that came with its balls, their history and results carried.)
  if (r.from_file) together([&] { install_file_walls(r.file_walls); }, "taking the wall contacts of its part from the save");
  else if (!full.walls.empty() || part_.wall_contacts.size() > 0)
    together([&] { find_part_walls(r, full, pool); }, "finding the wall contacts of its part");
  else
    scratch_.index_walls(part_.wall_contacts, part_.balls.size());
  if (r.from_file && from_file_results_) {
    // The save's contact results, the model's state's, carried into the new list (zero for a pair
    // it did not hold: one apart): the parts hold them, rank 0's table none.
    part_.contacts.keep_results();
    results_left_ = true;
  }
  return true;
}

bool BrickStep::may_rebuild_local(const Model& full) {
  if (policy_->local_rule < 0 || !live_ || model_ != &full) return false;
  if (results_written_ && !current_) return false;   // (the parts hold results the whole model has not)
  // The members' speeds have moved the shares by a tenth since the split (a core slowed, contacts
  // crowding in a part): the parts are made afresh, balanced by them.
  const std::vector<double> next = proposed_shares();   // (a collective call; the same on every member)
  for (std::size_t r = 0; r < next.size(); ++r)
    if (std::abs(next[r] - shares_[r]) > 0.1 * shares_[r]) return false;
  return true;
}

bool BrickStep::bonds_within(const Space& space, double reach) {
  // The longest intact bond of this member's part, at its balls' nearest images; over every member.
  std::vector<double> longest{0.0};
  together([&] {
    const Balls& b = part_.balls;
    const Bonds& t = part_.bonds;
    const CellFrame frame = cell_frame(space);
    for (std::size_t q = 0; q < t.size(); ++q) {
      if (t.fate[q] != 0) continue;
      const std::int64_t i = find_ball(part_, t.id_i[q]), j = find_ball(part_, t.id_j[q]);
      if (i < 0 || j < 0) throw std::logic_error("a bond's ball is not in its part");
      std::int8_t ix, iy, iz;
      const auto [dx, dy, dz] = nearest_separation(frame, space.periodic, b, static_cast<std::size_t>(i),
                                                   static_cast<std::size_t>(j), ix, iy, iz);
      const double d = std::sqrt(dx * dx + dy * dy + dz * dz);
      longest[0] = std::max(longest[0], std::isfinite(d) ? d : std::numeric_limits<double>::infinity());
    }
  }, "measuring the bonds of its part");
  team_->max_all(longest);
  return longest[0] <= reach;
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
  if (bonded_) {
    // The bonds of the balls this member owns from now on: its part's and those that came with the
    // balls that move here, each once (a bond held by two members has the same state on both),
    // broken or not; the other balls of the intact ones are ghosts.
    Bonds all = part_.bonds;
    const std::size_t held = all.size();
    merge_in_order(visit_bonds, all, held, r.arrived_bonds, [&](std::uint32_t p, std::uint32_t q) {
      return all.id_i[p] < all.id_i[q] || (all.id_i[p] == all.id_i[q] && all.id_j[p] < all.id_j[q]);
    });
    r.arrived_bonds = Bonds{};
    const std::vector<std::int64_t>& id = scan.balls.id;
    std::vector<std::uint32_t> by_id(count);
    std::iota(by_id.begin(), by_id.end(), 0u);
    std::sort(by_id.begin(), by_id.end(), [&](std::uint32_t p, std::uint32_t q) { return id[p] < id[q]; });
    auto entry_of = [&](std::int64_t want) {
      const auto at = std::lower_bound(by_id.begin(), by_id.end(), want, [&](std::uint32_t q, std::int64_t v) { return id[q] < v; });
      return at != by_id.end() && id[*at] == want ? *at : kAbsent;
    };
    std::vector<std::uint32_t> rows;
    for (std::size_t q = 0; q < all.size(); ++q) {
      if (q > 0 && all.id_i[q] == all.id_i[q - 1] && all.id_j[q] == all.id_j[q - 1]) continue;
      const std::uint32_t ei = entry_of(all.id_i[q]), ej = entry_of(all.id_j[q]);
      const bool own_i = ei != kAbsent && kind[ei] == 1, own_j = ej != kAbsent && kind[ej] == 1;
      if (!own_i && !own_j) continue;
      rows.push_back(static_cast<std::uint32_t>(q));
      if (all.fate[q] != 0) continue;
      if (ei == kAbsent || ej == kAbsent) throw std::logic_error("a bond's other ball is not within its halo");
      if (!own_i) kind[ei] = 2;
      if (!own_j) kind[ej] = 2;
      r.bond_ends.push_back(ei);
      r.bond_ends.push_back(ej);
    }
    gather(visit_bonds, &all, &r.next_bonds, rows);
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
  if (r.from_file) {   // (a part made from a save: its pairs came in the whole model's numbers)
    r.next_table = std::move(r.file_pairs);
  } else {
    r.next_table = part_.contacts;
    for (std::size_t p = 0; p < r.next_table.size(); ++p) {
      r.next_table.i[p] = global_ball_[r.next_table.i[p]];
      r.next_table.j[p] = global_ball_[r.next_table.j[p]];
    }
  }
  ContactTable& c = r.next_table;
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
  for (std::size_t q = 0; q + 1 < r.bond_ends.size(); q += 2) {   // (a bonded scene's)
    const std::uint32_t i = r.local[r.bond_ends[q]], j = r.local[r.bond_ends[q + 1]];
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
  ++edition_;
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
  if (bonded_) {
    std::swap(part_.bonds, r.next_bonds);
    part_.bonds.changed();
    part_.balls.index_ids();
  }
  if (r.moved > 0) {   // the records of the owners (sync gathers each rank's balls by them)
    for (std::size_t t = 0; !owner_.empty() && t < r.moved; ++t)
      owner_[static_cast<std::size_t>(r.all_moves[Rebuild::kMove * t])] =
          static_cast<int>(r.all_moves[Rebuild::kMove * t + 1]);
    remake_rows();
    rank_counts_ = r.count;
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
  kernels_.laws = make_pair_laws(part_);
}

void BrickStep::find_walls_again(const Model& full, double reach, ThreadPool& pool) {
  Rebuild r;
  r.skin = reach;
  together([&] { find_part_walls(r, full, pool); }, "finding the wall contacts of its part");
  ++edition_;   // (a copy taken before is not put back in place: its wall contacts are another list)
  list_local_ = true;
  current_ = false;
  shared_ = false;
}

void BrickStep::install_file_walls(WallContacts& w) {
  // The save's wall contacts of this rank's balls, as the file holds them (serial's RESTART keeps
  // its table until the next step searches: Pipeline::parts_from_file has the parts search then
  // too), each ball renumbered the part's (whose balls are in the whole model's order).
  for (std::size_t q = 0; q < w.size(); ++q) {
    const auto at = std::lower_bound(global_ball_.begin(), global_ball_.end(), w.ball[q]);
    if (at == global_ball_.end() || *at != w.ball[q] || scratch_.ghost[static_cast<std::size_t>(at - global_ball_.begin())])
      throw std::logic_error("internal error: a wall contact of the save came to a rank that does not own its ball");
    w.ball[q] = static_cast<std::uint32_t>(at - global_ball_.begin());
  }
  w.list_version = next_part_version();
  part_.wall_contacts = std::move(w);
  owned_walls_.resize(part_.wall_contacts.size());
  std::iota(owned_walls_.begin(), owned_walls_.end(), 0u);
  scratch_.index_walls(part_.wall_contacts, part_.balls.size());
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
