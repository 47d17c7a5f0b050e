// The owners of a decomposition and a member's part: the recursive bisection by the members'
// shares, the shares by the speed each member stepped at, the part made from the whole model, and
// at a rebuild on the parts, the brick that holds a ball that moved (its owner from then on).
#include "cycle/brick_step_parts.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <new>
#include <numeric>

#include <fmt/format.h>

#include "model/bond_table.hpp"
#include "model/edit.hpp"
#include "physics/pair_laws.hpp"

namespace trubal {
namespace {

// Owners by recursive coordinate bisection: the balls of a box are cut across its longest extent
// at the count that gives each side the sum of its ranks' shares. Ties and non-finite coordinates
// are ordered by index, so every rank computes the same owners (from the same shares).
// `cuts` records the planes (BrickStep::Cut), so that a ball that moved finds the rank whose brick
// holds it now (BrickStep::owner_at); returns the node made.
std::int32_t bisect(const Balls& b, std::vector<std::uint32_t>& order, std::size_t lo, std::size_t hi, int parts,
                    int first, const std::vector<double>& shares, std::vector<int>& owner,
                    std::vector<BrickStep::Cut>& cuts) {
  const auto node = static_cast<std::int32_t>(cuts.size());
  cuts.push_back({});
  cuts[node].owner = first;
  if (parts <= 1 || hi - lo <= 1) {
    for (std::size_t q = lo; q < hi; ++q) owner[order[q]] = first;
    return node;
  }
  const std::vector<double>* pos[3] = {&b.x, &b.y, &b.z};
  double extent[3];
  for (int a = 0; a < 3; ++a) {
    double least = std::numeric_limits<double>::infinity(), most = -least;
    for (std::size_t q = lo; q < hi; ++q) {
      const double x = (*pos[a])[order[q]];
      if (!std::isfinite(x)) continue;
      least = std::min(least, x);
      most = std::max(most, x);
    }
    extent[a] = most > least ? most - least : 0;
  }
  const int axis = extent[0] >= extent[1] && extent[0] >= extent[2] ? 0 : (extent[1] >= extent[2] ? 1 : 2);
  const std::vector<double>& x = *pos[axis];
  const int left = parts / 2;
  double left_share = 0, all_share = 0;
  for (int r = first; r < first + parts; ++r) (r < first + left ? left_share : all_share) += shares[r];
  all_share += left_share;
  const auto count = static_cast<double>(hi - lo);
  const std::size_t cut = lo + static_cast<std::size_t>(std::clamp(std::round(count * left_share / all_share), 1.0, count - 1));
  auto key = [&](std::uint32_t k) { return std::isfinite(x[k]) ? x[k] : std::numeric_limits<double>::infinity(); };
  std::nth_element(order.begin() + lo, order.begin() + cut, order.begin() + hi, [&](std::uint32_t p, std::uint32_t q) {
    const double kp = key(p), kq = key(q);
    return kp < kq || (kp == kq && p < q);
  });
  // The plane: the first ball of the right side, by (coordinate, index) as the cut orders them.
  cuts[node].axis = axis;
  cuts[node].at = key(order[cut]);
  cuts[node].at_ball = order[cut];
  const std::int32_t l = bisect(b, order, lo, cut, left, first, shares, owner, cuts);
  const std::int32_t r = bisect(b, order, cut, hi, parts - left, first + left, shares, owner, cuts);
  cuts[node].left = l;
  cuts[node].right = r;
  return node;
}

}  // namespace

std::uint64_t next_part_version() {
  // Far above the versions install_pairs and the wall list hand out, so a part's never equals one.
  // (Atomic: the threads of one process make their parts at once.)
  static std::atomic<std::uint64_t> versions{std::uint64_t{1} << 62};
  return ++versions;
}

std::vector<double> BrickStep::proposed_shares() {
  // Every member's speed since the last split (its own balls' forces and motion, not the waits):
  // the next shares are halfway between the last ones and the speeds' proportions, each clamped
  // between half and twice an equal share (then normalised), so that one noisy interval moves
  // them little. A core slowed by the machine, or a part where the contacts crowd, gets fewer
  // balls.
  const int ranks = team_->size();
  if (shares_.size() != static_cast<std::size_t>(ranks)) shares_.assign(ranks, 1.0 / ranks);
  if (!policy_->follow_speeds) return {};   // (the shares stay equal)
  const double seconds = work_seconds_ * (team_->rank() == policy_->slow_member ? StepPolicy::kSlowFactor : 1);
  std::vector<double> mine{seconds, work_ball_steps_}, all;
  team_->allgather(mine, all);   // (a collective call: every member asks at once)
  std::vector<double> speed(ranks, 0.0), next(ranks, 0.0);
  double total = 0;
  for (int r = 0; r < ranks; ++r) {
    const double member_seconds = all[2 * r], ball_steps = all[2 * r + 1];
    if (!(member_seconds > 1e-4 && ball_steps > 0)) return {};   // too little to go by: the shares stay
    speed[r] = ball_steps / member_seconds;
    total += speed[r];
  }
  double sum = 0;
  for (int r = 0; r < ranks; ++r) {
    next[r] = std::clamp(0.5 * shares_[r] + 0.5 * speed[r] / total, 0.5 / ranks, 2.0 / ranks);
    sum += next[r];
  }
  for (double& v : next) v /= sum;
  return next;
}

void BrickStep::update_shares() {
  std::vector<double> next = proposed_shares();   // (a collective call)
  work_seconds_ = work_ball_steps_ = 0;
  if (!next.empty()) shares_ = std::move(next);
}

void BrickStep::split_fault() {
  if (!team_->shares_whole() && team_->rank() == policy_->fail_split) {   // (a rank's test fault)
    policy_->fail_split = -1;
    throw std::bad_alloc();
  }
}

void BrickStep::split(const Model& full, const VerletReference& ref) {
  ++edition_;
  update_shares();   // (a collective call)
  const std::string doing = fmt::format("making its part of the decomposition ({} balls in the whole model)", full.balls.size());
  // A rank that cannot make its part (out of memory) must not leave the others stepping theirs and
  // waiting for its ghosts: the ranks agree here, and every one stops with that rank's message.
  auto fault = [&] { split_fault(); };
  if (!scatters()) {
    together([&] {
      fault();
      decompose(full);
      cut_part(full, ref, team_->rank());
    }, doing);
  } else {
    scatter_parts(full, ref, fault, doing);   // (cycle/brick_scatter.cpp)
  }
  finish_part(full);
}

void BrickStep::decompose(const Model& full) {
  // Every rank's balls, pairs (by ball i), wall contacts and intact bonds (by ball i) in the whole
  // model's order: what sync() gathers, and where a rebuild on the parts finds a ball's owner.
  const int ranks = team_->size();
  const Balls& b = full.balls;
  const std::size_t n = b.size();
  const ContactTable& c = full.contacts;
  const WallContacts& wc = full.wall_contacts;
  owner_.assign(n, 0);
  {
    std::vector<std::uint32_t> order(n);
    std::iota(order.begin(), order.end(), 0u);
    cuts_.clear();
    bisect(b, order, 0, n, ranks, 0, shares_, owner_, cuts_);
  }
  rank_pairs_.assign(ranks, {});
  for (std::size_t p = 0; p < c.size(); ++p) rank_pairs_[owner_[c.i[p]]].push_back(static_cast<std::uint32_t>(p));
  const Bonds& bt = full.bonds;
  rank_bonds_.assign(ranks, {});
  split_bond_rows_.clear();
  split_bond_ball_i_.clear();
  bonded_ = false;
  bonds_across_ = 0;
  split_off_ = BondCounts{};
  for (std::size_t q : bt.empty() ? std::vector<std::size_t>{} : bond_rows_by_id(bt)) {
    // (The bonds no part holds, counted as count_bonds counts them: own_bond_counts adds them.)
    if (bt.fate[q] == static_cast<std::uint8_t>(BondFate::Tension)) ++split_off_.tension;
    else if (bt.fate[q] == static_cast<std::uint8_t>(BondFate::Shear)) ++split_off_.shear;
    if (bt.fate[q] != 0) continue;
    const std::int64_t bi = find_ball(full, bt.id_i[q]), bj = find_ball(full, bt.id_j[q]);
    if (bi < 0 || bj < 0) {
      ++split_off_.intact;
      continue;
    }
    const int oi = owner_[static_cast<std::size_t>(bi)], oj = owner_[static_cast<std::size_t>(bj)];
    bonded_ = true;
    rank_bonds_[oi].push_back(static_cast<std::uint32_t>(q));
    split_bond_rows_.push_back(static_cast<std::uint32_t>(q));
    split_bond_ball_i_.push_back(static_cast<std::uint32_t>(bi));
    bonds_across_ += oi != oj;
  }
  rank_balls_.assign(ranks, {});
  for (std::size_t k = 0; k < n; ++k) rank_balls_[owner_[k]].push_back(static_cast<std::uint32_t>(k));
  rank_walls_.assign(ranks, {});
  for (std::size_t q = 0; q < wc.size(); ++q) rank_walls_[owner_[wc.ball[q]]].push_back(static_cast<std::uint32_t>(q));
  max_radius_ = b.max_radius();
  full_balls_ = n;
  walls_any_ = !full.walls.empty() || wc.size() > 0;
  split_laws_ = c.history_laws;
}

void BrickStep::cut_part(const Model& full, const VerletReference& ref, int me) {
  // Member `me`'s part: its owned balls (1) and their partners owned elsewhere (2, ghosts); the
  // pairs touching an owned ball; for each other member, the owned balls that are its ghosts.
  const int ranks = team_->size();
  const std::size_t n = full.balls.size();
  const ContactTable& c = full.contacts;
  const WallContacts& wc = full.wall_contacts;
  std::vector<std::uint8_t> in_part(n, 0);
  for (std::uint32_t k : rank_balls_[me]) in_part[k] = 1;
  std::vector<std::uint32_t> pairs;
  std::vector<std::vector<std::uint32_t>> sends(ranks);
  auto touch = [&](std::uint32_t i, std::uint32_t j) {   // (i's or j's owner is me)
    const int oi = owner_[i], oj = owner_[j];
    if (oi == oj) return;
    if (oi == me) { in_part[j] = 2; sends[oj].push_back(i); }
    else { in_part[i] = 2; sends[oi].push_back(j); }
  };
  for (std::size_t p = 0; p < c.size(); ++p) {
    const std::uint32_t i = c.i[p], j = c.j[p];
    if (owner_[i] != me && owner_[j] != me) continue;
    pairs.push_back(static_cast<std::uint32_t>(p));
    touch(i, j);
  }
  // The intact bonds of the owned balls, by (id_i, id_j), and their other balls as ghosts.
  std::vector<std::uint32_t> bonds;
  for (std::size_t t = 0; t < split_bond_rows_.size(); ++t) {
    const std::uint32_t q = split_bond_rows_[t], i = split_bond_ball_i_[t];
    const auto j = static_cast<std::uint32_t>(find_ball(full, full.bonds.id_j[q]));
    if (owner_[i] != me && owner_[j] != me) continue;
    bonds.push_back(q);
    touch(i, j);
  }
  global_ball_.clear();
  std::vector<std::uint32_t> local(n, kAbsent);
  for (std::size_t k = 0; k < n; ++k) {
    if (!in_part[k]) continue;
    local[k] = static_cast<std::uint32_t>(global_ball_.size());
    global_ball_.push_back(static_cast<std::uint32_t>(k));
  }
  const std::size_t m = global_ball_.size();

  // The part's model: its balls, pairs, bonds and wall contacts.
  gather(visit_balls, &full.balls, &part_.balls, global_ball_);
  part_.contacts.set_history_laws(full.contacts.history_laws);   // (the same parts: visit_pairs)
  // (Bonds name their balls by id: the step finds them by the part's index of ids.)
  gather([](void* p, auto&& f) { static_cast<Bonds*>(p)->for_each_array(f); }, &full.bonds, &part_.bonds, bonds);
  gather(visit_pairs, &full.contacts, &part_.contacts, pairs);
  for (std::size_t q = 0; q < pairs.size(); ++q) {
    part_.contacts.i[q] = local[part_.contacts.i[q]];
    part_.contacts.j[q] = local[part_.contacts.j[q]];
  }
  std::vector<std::uint32_t> walls;
  for (std::size_t q = 0; q < wc.size(); ++q)
    if (owner_[wc.ball[q]] == me) walls.push_back(static_cast<std::uint32_t>(q));
  gather(visit_walls, &full.wall_contacts, &part_.wall_contacts, walls);
  for (std::size_t q = 0; q < walls.size(); ++q) part_.wall_contacts.ball[q] = local[part_.wall_contacts.ball[q]];

  // What this member reports to sync(), as part indices, in the order of rank_balls_ etc.
  owned_.clear();
  for (std::uint32_t k : rank_balls_[me]) owned_.push_back(local[k]);
  owned_pairs_.clear();
  {
    std::size_t q = 0;
    for (std::uint32_t p : rank_pairs_[me]) {   // both lists ascend
      while (pairs[q] != p) ++q;
      owned_pairs_.push_back(static_cast<std::uint32_t>(q));
    }
  }
  owned_walls_.resize(walls.size());
  std::iota(owned_walls_.begin(), owned_walls_.end(), 0u);

  // The ghost exchange: to each member, its ghosts this member owns; from each, the ghosts it owns.
  send_.assign(ranks, {});
  recv_.assign(ranks, {});
  for (int r = 0; r < ranks; ++r) {
    auto& s = sends[r];
    std::sort(s.begin(), s.end());
    s.erase(std::unique(s.begin(), s.end()), s.end());
    for (std::uint32_t k : s) send_[r].push_back(local[k]);
  }
  scratch_.ghost.assign(m, 0);
  ghosts_ = 0;
  for (std::size_t q = 0; q < m; ++q) {
    const std::uint32_t k = global_ball_[q];
    if (in_part[k] != 2) continue;
    scratch_.ghost[q] = 1;
    recv_[owner_[k]].push_back(static_cast<std::uint32_t>(q));
    ++ghosts_;
  }

  // The list's reference positions, for the part's displacement test.
  ref_.x.clear(); ref_.y.clear(); ref_.z.clear();
  if (ref.x.size() == n)
    for (std::uint32_t k : global_ball_) {
      ref_.x.push_back(ref.x[k]);
      ref_.y.push_back(ref.y[k]);
      ref_.z.push_back(ref.z[k]);
    }
}

void BrickStep::finish_part(const Model& full) {
  // What the step reads of the rest: the whole model's (every member holds it, hollow or not).
  const int ranks = team_->size();
  const std::size_t m = part_.balls.size();
  part_.space = full.space;
  part_.materials = full.materials;
  part_.walls = full.walls;
  part_.settings = full.settings;
  part_.started = full.started;
  part_.bonds.changed();
  if (bonded_) part_.balls.index_ids();
  part_.contacts.drop_results();   // (a step that writes them makes them: Travels<ContactTable>)
  results_written_ = false;
  results_left_ = false;
  part_.contacts.list_version = next_part_version();
  part_.wall_contacts.list_version = next_part_version();
  send_buf_.assign(ranks, {});
  recv_buf_.assign(ranks, {});
  for (int r = 0; r < ranks; ++r) {
    send_buf_[r].resize(kHalo * send_[r].size());
    recv_buf_[r].resize(kHalo * recv_[r].size());
  }
  scratch_.index(part_.contacts, m);
  scratch_.index_walls(part_.wall_contacts, m);
  kernels_.laws = make_pair_laws(part_);
  step_.set_part_only(true);

  rank_counts_.assign(ranks, 0);
  for (int r = 0; r < ranks; ++r) rank_counts_[r] = rank_balls_[r].size();
  most_balls_ = *std::max_element(rank_counts_.begin(), rank_counts_.end());
  least_balls_ = *std::min_element(rank_counts_.begin(), rank_counts_.end());
  // A rank of a run other than 0 keeps its own row of the split's lists alone (rank 0 places what
  // the others send at a sync): each ball's owner and the other ranks' balls go, 8 bytes a ball.
  if (scatters() && team_->rank() != 0) let_go_of_others_lists();
  ++splits_;
  shell_base_ = 0;
  list_local_ = false;
  moved2_ = 0;
  outside_box_ = false;
  model_ = &full;
  // (This member's own: a rank's whole model takes versions of its own.)
  list_version_ = full.contacts.list_version;
  wall_version_ = full.wall_contacts.list_version;
  live_ = true;
  current_ = true;
  whole_hollow_ = false;
  // (Scattered: the ranks other than 0 freed their whole model's arrays first.)
  shared_ = !scatters();
}

void BrickStep::let_go_of_others_lists() {
  const auto me = static_cast<std::size_t>(team_->rank());
  std::vector<int>().swap(owner_);
  for (std::size_t r = 0; r < rank_balls_.size(); ++r)
    if (r != me) std::vector<std::uint32_t>().swap(rank_balls_[r]);
}

void BrickStep::remake_rows() {
  if (owner_.empty()) return own_rows_from_part();
  // Every rank's balls and bonds (by their balls i's owners, in the split's order) from the owners.
  for (auto& v : rank_balls_) v.clear();
  for (std::size_t k = 0; k < owner_.size(); ++k) rank_balls_[owner_[k]].push_back(static_cast<std::uint32_t>(k));
  for (auto& v : rank_bonds_) v.clear();
  for (std::size_t t = 0; t < split_bond_rows_.size(); ++t)
    rank_bonds_[owner_[split_bond_ball_i_[t]]].push_back(split_bond_rows_[t]);
}

void BrickStep::own_rows_from_part() {
  // This rank's balls in the whole model's order (a part is numbered in it), and the split's
  // intact bonds whose ball i is one of them, in the split's order.
  const auto me = static_cast<std::size_t>(team_->rank());
  std::vector<std::uint32_t>& mine = rank_balls_[me];
  mine.clear();
  for (std::uint32_t q : owned_) mine.push_back(global_ball_[q]);
  std::sort(mine.begin(), mine.end());
  if (rank_bonds_.size() <= me) return;
  rank_bonds_[me].clear();
  for (std::size_t t = 0; t < split_bond_rows_.size(); ++t)
    if (std::binary_search(mine.begin(), mine.end(), split_bond_ball_i_[t]))
      rank_bonds_[me].push_back(split_bond_rows_[t]);
}

int BrickStep::owner_at(double x, double y, double z, std::uint32_t k) const {
  const double p[3] = {x, y, z};
  std::int32_t node = 0;
  while (cuts_[node].left >= 0) {
    const Cut& c = cuts_[node];
    const double v = std::isfinite(p[c.axis]) ? p[c.axis] : std::numeric_limits<double>::infinity();
    node = v < c.at || (v == c.at && k < c.at_ball) ? c.left : c.right;
  }
  return cuts_[node].owner;
}

void BrickStep::find_moves(Rebuild& r) const {
  // The owners follow the balls: a ball of this rank's now in another rank's brick of the split goes
  // to that rank, with the history of its pairs and wall contacts. Every rank learns every move (its
  // ball, new owner and bin), so every rank knows every ball's owner and marks the bins of the balls
  // it will own.
  const Balls& b = part_.balls;
  r.dest.assign(owned_.size(), r.me);
  r.bin_of.resize(owned_.size());
  for (std::size_t q = 0; q < owned_.size(); ++q) {
    const std::uint32_t k = owned_[q];
    r.bin_of[q] = r.bins.bin_of(b.x[k], b.y[k], b.z[k]);
    if (r.bin_of[q] == ShellBins::kNone) continue;   // (a ball at no finite place stays where it is)
    r.dest[q] = owner_at(b.x[k], b.y[k], b.z[k], global_ball_[k]);
    if (r.dest[q] == r.me) continue;
    r.moves.push_back(global_ball_[k]);
    r.moves.push_back(r.dest[q]);
    r.moves.push_back(r.bin_of[q]);
    r.moves.push_back(r.me);
  }
}

bool BrickStep::balanced_after_moves(Rebuild& r) const {
  // The counts after the moves, against the shares: a tenth off (and two balls), and the parts are
  // made afresh from the whole model, balanced again.
  r.count = rank_counts_;
  for (std::size_t t = 0; t < r.moved; ++t) {
    --r.count[static_cast<std::size_t>(r.all_moves[Rebuild::kMove * t + 3])];
    ++r.count[static_cast<std::size_t>(r.all_moves[Rebuild::kMove * t + 1])];
  }
  const double total = std::accumulate(shares_.begin(), shares_.end(), 0.0);
  for (int q = 0; q < r.ranks; ++q) {
    const double want = shares_[q] / total * static_cast<double>(full_balls_);
    if (std::abs(static_cast<double>(r.count[q]) - want) > 0.1 * want + 2) return false;
  }
  return true;
}

}  // namespace trubal
