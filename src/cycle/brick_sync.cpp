// The whole model made current from the parts: each member's balls, pairs and wall contacts
// gathered into it (sync), a list rebuilt on the parts made the whole model's, and rank 0's whole
// model handed to the other ranks (share).
#include "cycle/brick_step_parts.hpp"

#include <algorithm>
#include <cstring>
#include <new>
#include <numeric>
#include <stdexcept>

#include "cycle/pair_list.hpp"
#include "model/bond_table.hpp"
#include "model/edit.hpp"
#include "physics/overlap.hpp"
#include "support/comm.hpp"
#include "support/peak_memory.hpp"

namespace trubal {
namespace {

// What a step changes, the arrays sync() gathers: the balls' motion and unbalanced forces, every
// pair's and wall contact's history, and the pairs' results where the last step wrote them (not
// their structure: balls, images).
template <class F> void each_moving_ball_array(Balls& b, F&& f) {
  for (auto* v : {&b.x, &b.y, &b.z, &b.vx, &b.vy, &b.vz, &b.wx, &b.wy, &b.wz, &b.fx, &b.fy, &b.fz, &b.mx, &b.my, &b.mz})
    f(*v);
}
// What else rank 0's hollow whole model lets go (BrickStep::hollow_whole), which the parts hold:
// the balls' masses and applied loads (a CYCLE going on from the parts reads them there).
template <class F> void each_held_ball_array(Balls& b, F&& f) {
  for (auto* v : {&b.mass, &b.inertia, &b.ax, &b.ay, &b.az, &b.amx, &b.amy, &b.amz}) f(*v);
}
template <class F> void each_history_array(ContactTable& c, F&& f) {
  c.for_each_history([&](auto& v, const HistoryPart&) { f(v); });
}
template <class F> void each_moving_bond_array(Bonds& t, F&& f) {
  for (auto* v : {&t.fn, &t.fsx, &t.fsy, &t.fsz, &t.mt, &t.mbx, &t.mby, &t.mbz}) f(*v);
  f(t.fate);
}
template <class F> void each_moving_wall_array(WallContacts& w, F&& f) {
  w.for_each_history([&](auto& v, const HistoryPart&) { f(v); });
  w.for_each_result_array(f);
}

// Each array's values at this rank's `mine` (part indices) to every rank, written into the whole
// model's copy at each rank's `by_rank` (whole-model indices): one array at a time, so the buffers
// hold one array's values, not the whole state.
// Members sharing one whole model write only their own values into it (disjoint elements).
template <class T>
void gather_array(Team& team, const std::vector<T>& part, std::vector<T>& whole, const std::vector<std::uint32_t>& mine,
                  const std::vector<std::vector<std::uint32_t>>& by_rank, std::vector<double>& out,
                  std::vector<double>& in) {
  if (team.shares_whole()) {
    const std::vector<std::uint32_t>& at = by_rank[team.rank()];
    for (std::size_t q = 0; q < mine.size(); ++q) whole[at[q]] = part[mine[q]];
    return;
  }
  // Ranks: to rank 0's whole model alone (BrickStep::share hands it to the others where they need it).
  // Bytes go as bytes (an eighth of the reals' buffers), the rest as reals.
  auto gather = [&](auto& to_send, auto& received) {
    to_send.clear();
    for (std::uint32_t q : mine) to_send.push_back(static_cast<typename std::decay_t<decltype(to_send)>::value_type>(part[q]));
    comm::gather_to_root(to_send, received);
    if (!comm::root()) return;
    auto p = received.begin();
    for (const auto& ranks_own : by_rank)
      for (std::uint32_t k : ranks_own) whole[k] = static_cast<T>(*p++);
  };
  if constexpr (std::is_same_v<T, std::uint8_t>) {
    std::vector<std::uint8_t> bytes_out, bytes_in;
    gather(bytes_out, bytes_in);
  } else {
    gather(out, in);
  }
}

// The arrays an each_moving_* lists, as pointers by element type (the same order for every object).
struct ArrayList {
  std::vector<std::vector<double>*> reals;
  std::vector<std::vector<std::uint8_t>*> bytes;
  void operator()(std::vector<double>& v) { reals.push_back(&v); }
  void operator()(std::vector<std::uint8_t>& v) { bytes.push_back(&v); }
};

// release: each of the part's arrays is freed once gathered (so the peak holds one of them beside
// the whole model's).
template <class Each, class S>
void gather_set(Team& team, Each&& each, S& part, S& whole, const std::vector<std::uint32_t>& mine,
                const std::vector<std::vector<std::uint32_t>>& by_rank, std::vector<double>& out,
                std::vector<double>& in, bool release = false) {
  ArrayList from, to;
  each(part, [&](auto& v) { from(v); });
  each(whole, [&](auto& v) { to(v); });
  for (std::size_t a = 0; a < from.reals.size(); ++a) {
    gather_array(team, *from.reals[a], *to.reals[a], mine, by_rank, out, in);
    if (release) std::vector<double>().swap(*from.reals[a]);
  }
  for (std::size_t a = 0; a < from.bytes.size(); ++a) {
    gather_array(team, *from.bytes[a], *to.bytes[a], mine, by_rank, out, in);
    if (release) std::vector<std::uint8_t>().swap(*from.bytes[a]);
  }
}

}  // namespace

void BrickStep::install_local_list(Model& full, VerletReference* whole_ref) {
  // The whole model's list is every rank's pairs whose ball i it owns, in the serial order (by i,
  // j, image): each rank's are in that order already, so they are merged by a sort of positions.
  // One record per pair: i, j (the whole model's), then j's image.
  const int ranks = team_->size();
  const ContactTable& c = part_.contacts;
  std::vector<std::uint8_t> mine, all;
  together([&] {
    mine.resize(owned_pairs_.size() * kPairRecord);
    std::uint8_t* r = mine.data();
    for (std::uint32_t q : owned_pairs_) {
      write_pair_record(r, global_ball_[c.i[q]], global_ball_[c.j[q]], c.image_x[q], c.image_y[q], c.image_z[q]);
      r += kPairRecord;
    }
  }, "gathering the pair list of its part");
  // Every rank's count, to know whose records are whose (to every thread; to rank 0 of the ranks,
  // whose whole model alone is made current: share hands it on).
  std::vector<double> count{static_cast<double>(owned_pairs_.size())}, counts;
  gather_whole(count, counts);
  gather_whole(mine, all);
  together([&] {
    std::vector<std::uint8_t>().swap(mine);
    if (!team_->shares_whole() && !comm::root()) return;
    // Ranks: rank 0 merges the runs straight into the table where each is in order (no copy of the
    // list, nor its permutation, beside the records: a million balls' list is 70 MB).
    if (!team_->shares_whole() && merge_pair_runs(full, all, counts)) return;
    PairCandidates list;
    read_pair_records(all, list);
    const std::size_t total = list.i.size();
    std::vector<std::uint8_t>().swap(all);
    std::vector<std::uint32_t> order(total);
    std::iota(order.begin(), order.end(), 0u);
    std::sort(order.begin(), order.end(), [&](std::uint32_t p, std::uint32_t q) { return pair_before(list, p, list, q); });
    PairCandidates sorted;
    gather([](void* p, auto&& f) {
      PairCandidates& l = *static_cast<PairCandidates*>(p);
      f(l.i); f(l.j); f(l.image_x); f(l.image_y); f(l.image_z);
    }, &list, &sorted, order);
    list = PairCandidates{};
    // Each rank's pairs' places in the whole list (sync's gathers write there).
    std::size_t first = 0;
    for (int r = 0; r < ranks; ++r) {
      rank_pairs_[r].resize(static_cast<std::size_t>(counts[r]));
      first += rank_pairs_[r].size();
    }
    std::vector<std::uint32_t> at(total);
    for (std::size_t q = 0; q < total; ++q) at[order[q]] = static_cast<std::uint32_t>(q);
    first = 0;
    for (int r = 0; r < ranks; ++r) {
      for (std::size_t t = 0; t < rank_pairs_[r].size(); ++t) rank_pairs_[r][t] = at[first + t];
      first += rank_pairs_[r].size();
    }
    // The results go: a sync that has them (results_written_) makes them again, of the new list.
    // (Threads: member 0 installs it in the one whole model; every member made the same list.)
    if (team_->shares_whole() && team_->rank() != 0) return;
    full.contacts.drop_results();
    install_pairs(full.contacts, sorted);   // (its history is then every rank's, gathered by sync)
  }, "installing the whole model's pair list");
  if (team_->shares_whole()) team_->barrier();
  list_version_ = full.contacts.list_version;   // (ranks other than 0: unchanged, until share)
  if (walls_any_) install_local_walls(full);
  if (whole_ref && whole_ref->balls() == full.balls.size()) {
    // (Rank 0's positions let go while its whole model was hollow: Pipeline::hollow_whole.)
    if (comm::root() && !team_->shares_whole())
      for (auto* v : {&whole_ref->x, &whole_ref->y, &whole_ref->z}) v->resize(full.balls.size());
    std::vector<double> out, in;
    gather_array(*team_, ref_.x, whole_ref->x, owned_, rank_balls_, out, in);
    gather_array(*team_, ref_.y, whole_ref->y, owned_, rank_balls_, out, in);
    gather_array(*team_, ref_.z, whole_ref->z, owned_, rank_balls_, out, in);
  }
  list_local_ = false;
}

bool BrickStep::merge_pair_runs(Model& full, std::vector<std::uint8_t>& all, const std::vector<double>& counts) {
  const int ranks = team_->size();
  auto key = [&](std::size_t q) {   // (a record's place in the list's order: pair_before's)
    const std::uint8_t* r = all.data() + q * kPairRecord;
    PairKey k;
    std::memcpy(&k.i, r, 4);
    std::memcpy(&k.j, r + 4, 4);
    std::memcpy(&k.x, r + 8, 1);
    std::memcpy(&k.y, r + 9, 1);
    std::memcpy(&k.z, r + 10, 1);
    return k;
  };
  // Each rank's run: [begin, end) of the records, in order (else the caller sorts them all).
  std::vector<std::size_t> at(static_cast<std::size_t>(ranks) + 1, 0);
  for (int r = 0; r < ranks; ++r) at[r + 1] = at[r] + static_cast<std::size_t>(counts[r]);
  const std::size_t total = at[ranks];
  if (total * kPairRecord != all.size()) return false;
  for (int r = 0; r < ranks; ++r)
    for (std::size_t q = at[r] + 1; q < at[r + 1]; ++q)
      if (!(key(q - 1) < key(q))) return false;
  // The merge, by the least head of the runs (a few ranks: a scan of the heads).
  PairCandidates sorted;
  sorted.i.resize(total); sorted.j.resize(total);
  sorted.image_x.resize(total); sorted.image_y.resize(total); sorted.image_z.resize(total);
  std::vector<std::size_t> head(at.begin(), at.end() - 1);
  for (int r = 0; r < ranks; ++r) rank_pairs_[r].resize(static_cast<std::size_t>(counts[r]));
  for (std::size_t out = 0; out < total; ++out) {
    int least = -1;
    PairKey best{};
    for (int r = 0; r < ranks; ++r) {
      if (head[r] == at[r + 1]) continue;
      const PairKey k = key(head[r]);
      if (least < 0 || k < best) least = r, best = k;
    }
    sorted.i[out] = best.i; sorted.j[out] = best.j;
    sorted.image_x[out] = best.x; sorted.image_y[out] = best.y; sorted.image_z[out] = best.z;
    rank_pairs_[least][head[least] - at[least]] = static_cast<std::uint32_t>(out);
    ++head[least];
  }
  std::vector<std::uint8_t>().swap(all);
  // (Its history is every rank's, gathered by sync whole: none is carried over.)
  install_pairs_zeroed(full.contacts, std::move(sorted));
  return true;
}

void BrickStep::install_local_walls(Model& full) {
  // As the pairs: every rank's walls' contacts (of its own balls, by ball then wall), merged into
  // the whole model's order; sync's gathers then write their state where each went.
  const int ranks = team_->size();
  const WallContacts& w = part_.wall_contacts;
  std::vector<double> mine, all;
  together([&] {
    for (std::size_t q = 0; q < w.size(); ++q) {
      mine.push_back(global_ball_[w.ball[q]]);
      mine.push_back(w.wall[q]);
    }
  }, "gathering the wall contacts of its part");
  std::vector<double> count{static_cast<double>(w.size())}, counts;
  gather_whole(count, counts);
  gather_whole(mine, all);
  together([&] {
    if (!team_->shares_whole() && !comm::root()) return;
    const std::size_t total = all.size() / 2;
    std::vector<std::uint32_t> order(total);
    std::iota(order.begin(), order.end(), 0u);
    std::sort(order.begin(), order.end(), [&](std::uint32_t p, std::uint32_t q) {
      return all[2 * p] < all[2 * q] || (all[2 * p] == all[2 * q] && all[2 * p + 1] < all[2 * q + 1]);
    });
    WallContacts next;
    for (std::uint32_t p : order) {
      const auto ball = static_cast<std::uint32_t>(all[2 * p]), wall = static_cast<std::uint32_t>(all[2 * p + 1]);
      next.ball.push_back(ball);
      next.wall.push_back(wall);
      next.ball_id.push_back(full.balls.id[ball]);
      next.wall_id.push_back(full.walls[wall].id);
    }
    each_moving_wall_array(next, [&](auto& v) { v.assign(total, {}); });
    std::vector<std::uint32_t> at(total);
    for (std::size_t q = 0; q < total; ++q) at[order[q]] = static_cast<std::uint32_t>(q);
    std::size_t first = 0;
    for (int r = 0; r < ranks; ++r) {
      rank_walls_[r].resize(static_cast<std::size_t>(counts[r]));
      for (std::size_t t = 0; t < rank_walls_[r].size(); ++t) rank_walls_[r][t] = at[first + t];
      first += rank_walls_[r].size();
    }
    next.list_version = next_part_version();
    if (!team_->shares_whole() || team_->rank() == 0) full.wall_contacts = std::move(next);
  }, "installing the whole model's wall contacts");
  if (team_->shares_whole()) team_->barrier();
  wall_version_ = full.wall_contacts.list_version;
}

void BrickStep::hollow_whole(Model& full) {
  if (!live_ || !scatters() || model_ != &full || whole_hollow_) return;   // (the same answer on every rank)
  if (comm::root()) {
    auto free = [](auto& v) { std::decay_t<decltype(v)>().swap(v); };
    each_moving_ball_array(full.balls, free);
    each_held_ball_array(full.balls, free);
    full.contacts.for_each_pair_array(free);   // (their list versions stay: live_for)
    full.wall_contacts.for_each_array(free);
    // (Each rank's places in the whole list and wall contacts: made again with them, install_local_list.)
    for (auto& v : rank_pairs_) free(v);
    for (auto& v : rank_walls_) free(v);
  }
  whole_hollow_ = true;
  current_ = false;
  whole_list_kept_ = false;
  return_free_memory();
}

void BrickStep::end_on_parts(Model& full) {
  if (!live_ || model_ != &full) return;
  if (results_written_) {
    results_written_ = false;
    results_left_ = true;
  }
  hollow_whole(full);
}

std::vector<double> BrickStep::own_counts() const {
  const ContactTable& c = part_.contacts;
  const WallContacts& w = part_.wall_contacts;
  const Balls& b = part_.balls;
  double touching = 0, wall_touching = 0, bridges = 0, wall_bridges = 0, spinning = 0;
  if (c.results_kept())
    for (std::uint32_t q : owned_pairs_) touching += c.state[q] != 0;
  if (c.bridge.size() == c.size())
    for (std::uint32_t q : owned_pairs_) bridges += c.bridge[q] != 0;
  if (w.state.size() == w.size())
    for (std::uint32_t q : owned_walls_) wall_touching += w.state[q] != 0;
  if (w.bridge.size() == w.size())
    for (std::uint32_t q : owned_walls_) wall_bridges += w.bridge[q] != 0;
  double applied = 0, moments = 0;
  for (std::uint32_t k : owned_) {
    spinning += b.wx[k] != 0 || b.wy[k] != 0 || b.wz[k] != 0;
    applied += b.ax[k] != 0 || b.ay[k] != 0 || b.az[k] != 0;
    moments += b.amx[k] != 0 || b.amy[k] != 0 || b.amz[k] != 0;
  }
  return {touching, wall_touching, bridges, wall_bridges, spinning, applied, moments};
}

StressSums BrickStep::own_stress(const Model& full) {
  part_.space = full.space;   // (as own_largest_overlap: the cell and the walls as they are now)
  part_.walls = full.walls;
  return stress_sums(part_, &owned_pairs_, &owned_walls_);
}

std::array<ExactSum, 3> BrickStep::own_servo_stiffness() const { return servo_stiffness_sums(part_, &owned_pairs_); }

SphereSums BrickStep::own_sphere_sums(const Model& full, const MeasureSphere& sphere) {
  part_.space = full.space;   // (as own_stress)
  part_.walls = full.walls;
  return sphere_sums(part_, sphere, &owned_, &owned_pairs_, &owned_walls_);
}

std::vector<double> BrickStep::own_largest_overlap(const Model& full, double threshold) {
  part_.space = full.space;   // (a step since the part's last: the cell and the walls moved on)
  part_.walls = full.walls;
  const LargestOverlap big = largest_overlap(part_, threshold, &owned_pairs_, &owned_walls_);
  double a = 0, b = 0, image = 0;
  if (big.beyond > 0 && !big.wall) {
    const ContactTable& c = part_.contacts;
    a = global_ball_[c.i[big.at]];
    b = global_ball_[c.j[big.at]];
    image = ((c.image_x[big.at] + 128) * 256.0 + (c.image_y[big.at] + 128)) * 256.0 + (c.image_z[big.at] + 128);
  } else if (big.beyond > 0) {
    a = global_ball_[part_.wall_contacts.ball[big.at]];
    b = part_.wall_contacts.wall[big.at];
  }
  return {big.ratio, static_cast<double>(big.ball), static_cast<double>(big.other), big.wall ? 1.0 : 0.0,
          static_cast<double>(big.beyond), big.wall ? 1.0 : 0.0, a, b, image};
}

void BrickStep::sync(Model& full, VerletReference* whole_ref, bool leave_results) {
  if (!live_ || current_ || model_ != &full) return;
  ++gathers_;
  std::vector<double> out, in;
  const bool hollow = whole_hollow_;
  if (hollow) {
    // Every array of the state gathered, the lists made afresh from the parts' (install_local_list).
    together([&] {
      if (!comm::root()) return;
      each_moving_ball_array(full.balls, [&](std::vector<double>& v) { v.assign(full_balls_, 0.0); });
      each_held_ball_array(full.balls, [&](std::vector<double>& v) { v.assign(full_balls_, 0.0); });
      full.contacts.set_history_laws(part_.contacts.history_laws);
    }, "gathering the model from the parts");
    list_local_ = true;
    whole_list_kept_ = false;
    gather_set(*team_, [](Balls& b, auto&& f) { each_held_ball_array(b, f); }, part_.balls, full.balls, owned_, rank_balls_,
               out, in);
  }
  // (After a step taken again from the copies in place, the parts' list is the one the whole
  // model was given at the CYCLE's end, wraps and all: restore_copy_in_place.)
  if (list_local_ && whole_list_kept_ && kept_edition_ == edition_) list_local_ = false;
  whole_list_kept_ = false;
  if (list_local_) install_local_list(full, whole_ref);
  gather_set(*team_, [](Balls& b, auto&& f) { each_moving_ball_array(b, f); }, part_.balls, full.balls, owned_, rank_balls_,
             out, in);
  gather_set(*team_, [](ContactTable& c, auto&& f) { each_history_array(c, f); }, part_.contacts, full.contacts, owned_pairs_,
             rank_pairs_, out, in);
  // The results only where the parts' last step wrote them (the same on every rank): a lean step's
  // table holds none worth reading, and a whole table that dropped its results stays without. The
  // part's go once gathered: nothing reads them there, and the next step that writes results
  // makes them again (ParallelStep::run).
  if (results_written_) {
    results_written_ = false;
    // (Left: where the whole model is the state of a CYCLE's end, which the next CYCLE may go on
    // from without a command reading them, so that rank 0 need not hold them.)
    if (leave_results) results_left_ = true;
    else gather_result_arrays(full, out, in);
  }
  gather_set(*team_, [](WallContacts& w, auto&& f) { each_moving_wall_array(w, f); }, part_.wall_contacts,
             full.wall_contacts, owned_walls_, rank_walls_, out, in);
  if (bonded_) gather_bonds(full, out, in);
  current_ = true;
  whole_hollow_ = false;
}

void BrickStep::whole_from_copy(Model& full) {
  if (team_->shares_whole() || !copy_.held)
    throw std::logic_error("internal error: the whole model asked of the parts' rescue copies where none is held");
  // The copy's part and what the gathers read, as a split would have left them; the list and the
  // wall contacts made the whole model's as sync makes them after a rebuild on the parts.
  bool results_were_kept = false;   // (rank 0's: kept, they come back zero, as Snapshot::restore leaves them)
  together([&] {
    results_were_kept = full.contacts.results_kept() && full.contacts.size() > 0;
    copy_.part.restore(part_);
    global_ball_ = copy_.global_ball;
    owned_ = copy_.owned;
    owned_pairs_ = copy_.owned_pairs;
    owned_walls_ = copy_.owned_walls;
    rank_balls_ = copy_.rank_balls;
    rank_bonds_ = copy_.rank_bonds;
    rank_pairs_.assign(rank_balls_.size(), {});
    rank_walls_.assign(rank_balls_.size(), {});
    scratch_.ghost = copy_.ghost;
    full_balls_ = copy_.full_balls;
    bonded_ = copy_.bonded;
    walls_any_ = copy_.walls_any;
    if (comm::root()) {
      full.balls.for_each_array([&](auto& v) { v.resize(full_balls_); });
      full.contacts.set_history_laws(part_.contacts.history_laws);
      if (!walls_any_) full.wall_contacts = WallContacts{};
    }
  }, "putting back the rescue copy of its part");
  live_ = true;
  model_ = &full;
  current_ = false;
  whole_hollow_ = false;   // (every array of it gathered below)
  results_written_ = results_left_ = false;
  list_local_ = true;
  std::vector<double> out, in;
  // Every array of the balls (a sort or a destroyed ball since leaves none of rank 0's of use).
  std::vector<void*> wholes;
  full.balls.for_each_array([&](auto& v) { wholes.push_back(&v); });
  std::size_t a = 0;
  part_.balls.for_each_array([&](auto& v) {
    using V = std::decay_t<decltype(v)>;
    gather_array(*team_, v, *static_cast<V*>(wholes[a++]), owned_, rank_balls_, out, in);
  });
  install_local_list(full, nullptr);   // (its results dropped; install_local_walls too, where walls_any_)
  gather_set(*team_, [](ContactTable& c, auto&& f) { each_history_array(c, f); }, part_.contacts, full.contacts, owned_pairs_,
             rank_pairs_, out, in);
  if (walls_any_)
    gather_set(*team_, [](WallContacts& w, auto&& f) { each_moving_wall_array(w, f); }, part_.wall_contacts,
               full.wall_contacts, owned_walls_, rank_walls_, out, in);
  if (bonded_) gather_bonds(full, out, in);
  if (comm::root()) {
    for (auto* v : {&full.balls.fx, &full.balls.fy, &full.balls.fz, &full.balls.mx, &full.balls.my, &full.balls.mz})
      std::fill(v->begin(), v->end(), 0.0);
    full.balls.index_ids();
    full.contacts.drop_results();
    if (results_were_kept) full.contacts.keep_results();
  }
  current_ = true;
  release();
}

void BrickStep::gather_result_arrays(Model& full, std::vector<double>& out, std::vector<double>& in, bool free_each) {
  // (Members sharing one whole model: member 0 makes its arrays, then every member writes its own.)
  // (Ranks: the results are the largest arrays a sync makes; a rank out of memory here alone
  // must not leave the others in the gathers below.)
  if (team_->shares_whole()) {
    if (team_->rank() == 0) full.contacts.keep_results();
    team_->barrier();
    gather_set(*team_, [](ContactTable& c, auto&& f) { c.for_each_result_array(f); }, part_.contacts, full.contacts,
               owned_pairs_, rank_pairs_, out, in, true);
    return;
  }
  // Ranks: rank 0 makes each of the whole table's arrays as the parts' array comes, which each
  // rank then frees, so that it holds its part's results and the whole table's together one array
  // at a time, not all.
  ArrayList from, to;
  part_.contacts.for_each_result_array(from);
  full.contacts.for_each_result_array(to);
  const std::size_t n = full.contacts.size();
  if (comm::root()) full.contacts.results_cycle = -1;
  auto each = [&](auto& parts, auto& wholes) {
    for (std::size_t a = 0; a < parts.size(); ++a) {
      comm::together([&] { if (comm::root()) wholes[a]->assign(n, {}); }, "keeping the contact results");
      gather_array(*team_, *parts[a], *wholes[a], owned_pairs_, rank_pairs_, out, in);
      if (free_each) std::decay_t<decltype(*parts[a])>().swap(*parts[a]);
    }
  };
  each(from.bytes, to.bytes);
  each(from.reals, to.reals);
  if (!free_each) part_.contacts.drop_results();
}

void BrickStep::results_fault() {
  if (policy_->fail_results != team_->rank()) return;   // (a test's fault: TRUBAL_TEST_FAIL_AT "R results")
  policy_->fail_results = -1;
  throw std::bad_alloc();
}

void BrickStep::gather_results(Model& full) {
  if (!results_left() || model_ != &full) return;
  // (The parts are where they are: each keeps its arrays until every array came whole, so that a
  // member failing part way leaves them there, to be read again.)
  together([&] { results_fault(); }, "gathering the contact results from the parts");
  std::vector<double> out, in;
  try {
    gather_result_arrays(full, out, in, team_->shares_whole());
  } catch (...) {
    if (team_->shares_whole() ? team_->rank() == 0 : comm::root()) full.contacts.drop_results();
    throw;
  }
  results_left_ = false;
  // (keep_results marked the table's fresh arrays as of no step: they are of this state's.)
  if (team_->shares_whole() ? team_->rank() == 0 : comm::root()) full.contacts.results_cycle = full.cycle;
}

void BrickStep::gather_result_array(const Model& full, std::size_t k, std::vector<double>* reals,
                                    std::vector<std::uint8_t>* bytes) {
  if (!results_left() || model_ != &full || team_->shares_whole())
    throw std::logic_error("internal error: a result array asked of parts that hold none");
  std::vector<double> out, in;
  std::size_t at = 0;
  part_.contacts.for_each_result_array([&](auto& v) {
    if (at++ != k) return;
    using T = typename std::decay_t<decltype(v)>::value_type;
    std::vector<T> whole;
    together([&] {
      results_fault();
      if (comm::root()) whole.assign(full.contacts.size(), T{});
    }, "gathering the contact results from the parts");
    gather_array(*team_, v, whole, owned_pairs_, rank_pairs_, out, in);
    if constexpr (std::is_same_v<T, double>) {
      if (reals) *reals = std::move(whole);
    } else {
      if (bytes) *bytes = std::move(whole);
    }
  });
  if (at <= k) throw std::logic_error("internal error: a result array the table does not have");
}

void BrickStep::gather_bonds(Model& full, std::vector<double>& out, std::vector<double>& in) {
  // The bonds this member owns (its ball i's), by (id_i, id_j) as rank_bonds_ lists them: the
  // step keeps the part's rows in an order of its own (cycle/bond_pass.hpp), found again by ids.
  std::vector<std::uint32_t> mine;
  together([&] {
    const Bonds& t = part_.bonds;
    for (std::size_t q : bond_rows_by_id(t)) {
      const std::int64_t i = find_ball(part_, t.id_i[q]);
      if (i >= 0 && !scratch_.ghost[static_cast<std::size_t>(i)]) mine.push_back(static_cast<std::uint32_t>(q));
    }
    if (mine.size() != rank_bonds_[team_->rank()].size())
      throw std::logic_error("its part holds other bonds than the split gave it");
  }, "gathering the bonds of its part");
  gather_set(*team_, [](Bonds& t, auto&& f) { each_moving_bond_array(t, f); }, part_.bonds, full.bonds, mine,
             rank_bonds_, out, in);
  // (The whole model's index of its bonds holds which broke: the table is a new edition.)
  if (team_->shares_whole() ? team_->rank() == 0 : comm::root()) full.bonds.changed();
}

template <class T> void BrickStep::gather_whole(const std::vector<T>& mine, std::vector<T>& all) {
  if (team_->shares_whole()) team_->allgather(mine, all);
  else comm::gather_to_root(mine, all);
}

void BrickStep::centres_to_root(Model& full) {
  if (!live_ || team_->shares_whole() || model_ != &full) throw std::logic_error("internal error: centres gathered from parts where none is live");
  Balls& b = full.balls;
  comm::together([&] {
    if (!comm::root()) return;
    for (auto* v : {&b.x, &b.y, &b.z}) v->assign(b.size(), 0.0);
  }, "gathering the balls' centres");
  std::vector<double> out, in;
  for (auto [from, to] : {std::pair{&part_.balls.x, &b.x}, std::pair{&part_.balls.y, &b.y}, std::pair{&part_.balls.z, &b.z}})
    gather_array(*team_, *from, *to, owned_, rank_balls_, out, in);
}

void BrickStep::share(Model& full, VerletReference* whole_ref, bool release_parts) {
  if (!live_ || model_ != &full) return;
  sync(full, whole_ref);
  const bool done = shared_ || team_->shares_whole() || team_->size() < 2;
  shared_ = true;
  if (release_parts) {   // (before the whole model comes: the two are never held together)
    release();
    return_free_memory();
  }
  if (done) return;
  // Rank 0's whole model, current, to the others, and the list's reference positions; not the
  // contact results, which rank 0 alone reads (it alone prints and writes).
  broadcast_whole(full, whole_ref);
  list_version_ = full.contacts.list_version;
  wall_version_ = full.wall_contacts.list_version;
}

void broadcast_whole(Model& m, VerletReference* ref) {
  broadcast_arrays(m, false);
  if (ref && ref->balls() == m.balls.size()) {
    comm::broadcast(ref->x);
    comm::broadcast(ref->y);
    comm::broadcast(ref->z);
  }
}

void broadcast_ball_names(Balls& b) {
  comm::broadcast(b.id);
  comm::broadcast(b.type);
  comm::broadcast(b.rad);
  comm::together([&] { if (!comm::root()) b.index_ids(); }, "indexing rank 0's balls");
}

void broadcast_results(Model& m) {
  ContactTable& c = m.contacts;
  if (comm::root()) c.keep_results();
  c.for_each_result_array([](auto& v) { comm::broadcast(v); });
  comm::broadcast(c.results_cycle);
}

void broadcast_arrays(Model& m, bool with_results) {
  m.balls.for_each_array([](auto& v) { comm::broadcast(v); });
  // (The history parts in use first: the arrays that follow are those.)
  std::int64_t laws = (m.contacts.history_laws.rolling ? 1 : 0) + (m.contacts.history_laws.bridge ? 2 : 0);
  comm::broadcast(laws);
  m.contacts.set_history_laws(HistoryLaws{(laws & 1) != 0, (laws & 2) != 0});
  std::int64_t results = with_results ? 1 : 0;   // (rank 0's word)
  comm::broadcast(results);
  if (results != 0) {
    m.contacts.for_each_pair_array([](auto& v) { comm::broadcast(v); });
  } else {
    m.contacts.for_each_list_array([](auto& v) { comm::broadcast(v); });
    m.contacts.for_each_history([](auto& v, const HistoryPart&) { comm::broadcast(v); });
    if (!comm::root()) m.contacts.drop_results();
  }
  comm::broadcast(m.contacts.results_cycle);
  m.wall_contacts.for_each_array([](auto& v) { comm::broadcast(v); });
  m.bonds.for_each_array([](auto& v) { comm::broadcast(v); });
  // What came from rank 0 is new here: new versions, so that no index of the old arrays passes for
  // one of these (Pipeline::prepare has rank 0 decide whether to search).
  if (!comm::root()) {
    m.contacts.list_version = fresh_list_version();
    m.wall_contacts.list_version = fresh_list_version();
    m.bonds.changed();
    m.balls.index_ids();
  }
}

}  // namespace trubal
