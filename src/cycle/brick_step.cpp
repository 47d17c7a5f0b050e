#include "cycle/brick_step.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <iterator>
#include <limits>
#include <new>
#include <numeric>
#include <type_traits>

#include <fmt/format.h>

#include "cycle/sum_exchange.hpp"
#include "support/comm.hpp"
#include "model/periodic_cell.hpp"

namespace trubal {
namespace {

constexpr std::uint32_t kAbsent = ~std::uint32_t{0};
constexpr std::size_t kHalo = 9;   // a ghost's state each step: position, velocity, spin

// Owners by recursive coordinate bisection: the balls of a box are cut across its longest extent
// at the count that gives each side the sum of its ranks' shares. Ties and non-finite coordinates
// are ordered by index, so every rank computes the same owners (from the same shares).
void bisect(const Balls& b, std::vector<std::uint32_t>& order, std::size_t lo, std::size_t hi, int parts, int first,
            const std::vector<double>& shares, std::vector<int>& owner) {
  if (parts <= 1 || hi - lo <= 1) {
    for (std::size_t q = lo; q < hi; ++q) owner[order[q]] = first;
    return;
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
  bisect(b, order, lo, cut, left, first, shares, owner);
  bisect(b, order, cut, hi, parts - left, first + left, shares, owner);
}

// `to`'s arrays are `from`'s at the picked indices (the visitor lists a struct's arrays in one order).
template <class Visit>
void gather(Visit&& visit, const void* from, void* to, const std::vector<std::uint32_t>& pick) {
  std::vector<const void*> source;
  visit(const_cast<void*>(from), [&](auto& v) { source.push_back(&v); });
  std::size_t n = 0;
  visit(to, [&](auto& v) {
    using V = std::decay_t<decltype(v)>;
    const V& s = *static_cast<const V*>(source[n++]);
    v.resize(pick.size());
    for (std::size_t q = 0; q < pick.size(); ++q) v[q] = s[pick[q]];
  });
}
const auto visit_balls = [](void* p, auto&& f) { static_cast<Balls*>(p)->for_each_array(f); };
// A part takes the pair list and the shear history; its results are written by the steps that
// write them (ParallelStep::run keeps them there), so a whole table without results cuts alike.
const auto visit_pairs = [](void* p, auto&& f) {
  ContactTable& c = *static_cast<ContactTable*>(p);
  f(c.i); f(c.j); f(c.image_x); f(c.image_y); f(c.image_z); f(c.fsx); f(c.fsy); f(c.fsz);
};
const auto visit_walls = [](void* p, auto&& f) { static_cast<WallContacts*>(p)->for_each_array(f); };

// What a step changes, the arrays sync() gathers: the balls' motion and unbalanced forces, every
// pair's and wall contact's history, and the pairs' results where the last step wrote them (not
// their structure: balls, images).
template <class F> void each_moving_ball_array(Balls& b, F&& f) {
  for (auto* v : {&b.x, &b.y, &b.z, &b.vx, &b.vy, &b.vz, &b.wx, &b.wy, &b.wz, &b.fx, &b.fy, &b.fz, &b.mx, &b.my, &b.mz})
    f(*v);
}
template <class F> void each_history_array(ContactTable& c, F&& f) {
  for (auto* v : {&c.fsx, &c.fsy, &c.fsz}) f(*v);
}
template <class F> void each_moving_wall_array(WallContacts& w, F&& f) {
  f(w.state);
  for (auto* v : {&w.fsx, &w.fsy, &w.fsz, &w.nx, &w.ny, &w.nz, &w.overlap, &w.fn, &w.fx, &w.fy, &w.fz, &w.kn_eff,
                  &w.ks_eff})
    f(*v);
}

// The cycle's kernels with the part's own pair laws (per ball of the part): every field but `laws`.
void take_kernels(const StepKernels& from, StepKernels& to) {
  to.features = from.features;
  to.estimate = from.estimate;
  to.moments = from.moments;
  to.dt = from.dt;
  to.beta = from.beta;
  to.alpha = from.alpha;
  to.local = from.local;
  to.gravity = from.gravity;
  to.contacts = from.contacts; to.contacts_full = from.contacts_full; to.contacts_lean = from.contacts_lean;
  to.cross = from.cross;
  to.walls = from.walls; to.walls_full = from.walls_full; to.walls_lean = from.walls_lean;
  to.motion = from.motion; to.motion_full = from.motion_full; to.motion_lean = from.motion_lean;
}

std::uint64_t next_part_version() {
  // Far above the versions install_pairs and the wall list hand out, so a part's never equals one.
  // (Atomic: the threads of one process make their parts at once.)
  static std::atomic<std::uint64_t> versions{std::uint64_t{1} << 62};
  return ++versions;
}

}  // namespace

void apply_field_change(Balls& balls, const FieldChange& change, std::size_t begin, std::size_t end,
                        const std::uint8_t* skip, ExactSum& work, ExactSum& gross) {
  for (std::size_t k = begin; k < end; ++k) {
    double ball_work, ball_gross;
    apply_field_change(balls, change, k, ball_work, ball_gross);
    if (skip && skip[k]) continue;
    work.add(ball_work);
    gross.add(ball_gross);
  }
}

void BrickStep::apply_field(Model& full, const FieldChange& change) {
  ExactSum work, gross;
  apply_field_change(part_.balls, change, 0, part_.balls.size(), scratch_.ghost.data(), work, gross);
  current_ = false;   // the parts' velocities are newer than full's now
  std::vector<double> out, in;
  pack(work, out);
  pack(gross, out);
  team_->allgather(out, in);
  if (team_->shares_whole() && team_->rank() != 0) return;   // member 0 adds to the one whole model
  ExactSum all_work, all_gross;
  const double* p = in.data();
  for (int r = 0; r < team_->size(); ++r) {
    ExactSum w, g;
    unpack(w, p);
    unpack(g, p);
    all_work.add(w);
    all_gross.add(g);
  }
  full.energy.boundary_work += all_work.value();
  full.space.gross_work += all_gross.value();
}

void BrickStep::reduce_tilt(const Space& before) {
  part_.space = before;
  reduce_cell_tilt(part_);
}

bool BrickStep::live_for(const Model& full) const {
  return live_ && model_ == &full && full.balls.size() == full_balls_ && full.contacts.list_version == list_version_ &&
         full.wall_contacts.list_version == wall_version_;
}

void BrickStep::update_shares() {
  // Every member's speed since the last split (its own balls' forces and motion, not the waits):
  // the next shares are halfway between the last ones and the speeds' proportions, each clamped
  // between half and twice an equal share (then normalised), so that one noisy interval moves
  // them little. A core slowed by the machine, or a part where the contacts crowd, gets fewer
  // balls.
  const int ranks = team_->size();
  if (shares_.size() != static_cast<std::size_t>(ranks)) shares_.assign(ranks, 1.0 / ranks);
  if (team_->rank() == slow_member_for_test.load(std::memory_order_relaxed)) work_seconds_ *= 3;
  std::vector<double> mine{work_seconds_, work_ball_steps_}, all;
  team_->allgather(mine, all);   // (a collective call: every member splits at once)
  work_seconds_ = work_ball_steps_ = 0;
  std::vector<double> speed(ranks, 0.0);
  double total = 0;
  for (int r = 0; r < ranks; ++r) {
    const double seconds = all[2 * r], ball_steps = all[2 * r + 1];
    if (!(seconds > 1e-4 && ball_steps > 0)) return;   // too little to go by: the shares stay
    speed[r] = ball_steps / seconds;
    total += speed[r];
  }
  double sum = 0;
  for (int r = 0; r < ranks; ++r) {
    shares_[r] = std::clamp(0.5 * shares_[r] + 0.5 * speed[r] / total, 0.5 / ranks, 2.0 / ranks);
    sum += shares_[r];
  }
  for (double& s : shares_) s /= sum;
}

void BrickStep::split(const Model& full, const VerletReference& ref) {
  update_shares();   // (a collective call)
  if (team_->shares_whole()) return make_part(full, ref);   // (threads: Pipeline::each_part's abort)
  // A rank that cannot make its part (out of memory) must not leave the others stepping theirs and
  // waiting for its ghosts: the ranks agree here, and every one stops with that rank's message.
  comm::together([&] {
    if (team_->rank() == fail_split_for_test.load()) {
      fail_split_for_test = -1;
      throw std::bad_alloc();
    }
    make_part(full, ref);
  }, fmt::format("making its part of the decomposition ({} balls in the whole model)", full.balls.size()));
}

void BrickStep::make_part(const Model& full, const VerletReference& ref) {
  const int ranks = team_->size(), me = team_->rank();
  const Balls& b = full.balls;
  const std::size_t n = b.size();
  const ContactTable& c = full.contacts;
  const WallContacts& wc = full.wall_contacts;
  owner_.assign(n, 0);
  {
    std::vector<std::uint32_t> order(n);
    std::iota(order.begin(), order.end(), 0u);
    bisect(b, order, 0, n, ranks, 0, shares_, owner_);
  }
  // The part: owned balls (1) and their partners owned elsewhere (2, ghosts); the pairs touching
  // an owned ball; for each other rank, the owned balls that are its ghosts.
  std::vector<std::uint8_t> in_part(n, 0);
  for (std::size_t k = 0; k < n; ++k)
    if (owner_[k] == me) in_part[k] = 1;
  std::vector<std::uint32_t> pairs;
  std::vector<std::vector<std::uint32_t>> sends(ranks);
  rank_pairs_.assign(ranks, {});
  for (std::size_t p = 0; p < c.size(); ++p) {
    const std::uint32_t i = c.i[p], j = c.j[p];
    const int oi = owner_[i], oj = owner_[j];
    rank_pairs_[oi].push_back(static_cast<std::uint32_t>(p));
    if (oi != me && oj != me) continue;
    pairs.push_back(static_cast<std::uint32_t>(p));
    if (oi == oj) continue;
    if (oi == me) { in_part[j] = 2; sends[oj].push_back(i); }
    else { in_part[i] = 2; sends[oi].push_back(j); }
  }
  global_ball_.clear();
  std::vector<std::uint32_t> local(n, kAbsent);
  rank_balls_.assign(ranks, {});
  for (std::size_t k = 0; k < n; ++k) {
    rank_balls_[owner_[k]].push_back(static_cast<std::uint32_t>(k));
    if (!in_part[k]) continue;
    local[k] = static_cast<std::uint32_t>(global_ball_.size());
    global_ball_.push_back(static_cast<std::uint32_t>(k));
  }
  const std::size_t m = global_ball_.size();

  // The part's model: its balls, pairs and wall contacts, and what the step reads of the rest.
  part_.space = full.space;
  part_.materials = full.materials;
  part_.walls = full.walls;
  part_.settings = full.settings;
  part_.started = full.started;
  gather(visit_balls, &full.balls, &part_.balls, global_ball_);
  gather(visit_pairs, &full.contacts, &part_.contacts, pairs);
  for (std::size_t q = 0; q < pairs.size(); ++q) {
    part_.contacts.i[q] = local[part_.contacts.i[q]];
    part_.contacts.j[q] = local[part_.contacts.j[q]];
  }
  part_.contacts.drop_results();   // (a step that writes them makes them: visit_pairs)
  results_written_ = false;
  part_.contacts.list_version = next_part_version();
  std::vector<std::uint32_t> walls;
  rank_walls_.assign(ranks, {});
  for (std::size_t q = 0; q < wc.size(); ++q) {
    rank_walls_[owner_[wc.ball[q]]].push_back(static_cast<std::uint32_t>(q));
    if (owner_[wc.ball[q]] == me) walls.push_back(static_cast<std::uint32_t>(q));
  }
  gather(visit_walls, &full.wall_contacts, &part_.wall_contacts, walls);
  for (std::size_t q = 0; q < walls.size(); ++q) part_.wall_contacts.ball[q] = local[part_.wall_contacts.ball[q]];
  part_.wall_contacts.list_version = next_part_version();

  // What this rank reports to sync(), as part indices, in the order of rank_balls_ etc.
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

  // The ghost exchange: to each rank, its ghosts this rank owns; from each, the ghosts it owns.
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
  send_buf_.assign(ranks, {});
  recv_buf_.assign(ranks, {});
  for (int r = 0; r < ranks; ++r) {
    send_buf_[r].resize(kHalo * send_[r].size());
    recv_buf_[r].resize(kHalo * recv_[r].size());
  }

  // The list's reference positions, for the part's displacement test.
  ref_.x.clear(); ref_.y.clear(); ref_.z.clear();
  if (ref.x.size() == n)
    for (std::uint32_t k : global_ball_) {
      ref_.x.push_back(ref.x[k]);
      ref_.y.push_back(ref.y[k]);
      ref_.z.push_back(ref.z[k]);
    }
  scratch_.index(part_.contacts, m);
  scratch_.index_walls(part_.wall_contacts, m);
  kernels_.laws = make_pair_laws(part_);
  step_.set_part_only(true);

  most_balls_ = 0;
  least_balls_ = n;
  for (int r = 0; r < ranks; ++r) {
    most_balls_ = std::max(most_balls_, rank_balls_[r].size());
    least_balls_ = std::min(least_balls_, rank_balls_[r].size());
  }
  ++splits_;
  moved2_ = 0;
  outside_box_ = false;
  model_ = &full;
  full_balls_ = n;
  list_version_ = c.list_version;
  wall_version_ = wc.list_version;
  live_ = true;
  current_ = true;
}

void BrickStep::step(ThreadPool& pool, Model& full, const StepKernels& kernels, StepSums& sums, PhaseTimes& times) {
  // (Members sharing one whole model read its space and walls here, before the exchange below;
  // member 0 writes its walls' loads after it.)
  // The space and the walls are the whole model's (the cell's strain and the walls' motion and
  // servos act on it between steps).
  part_.space = full.space;
  part_.walls = full.walls;
  take_kernels(kernels, kernels_);
  Balls& b = part_.balls;
  const std::size_t m = b.size();
  if (kernels_.moments) scratch_.ball_moments.resize(m);
  StepSums mine;
  const auto t0 = std::chrono::steady_clock::now();
  step_.run(pool, part_, scratch_, kernels_, mine, times, ref_.x.size() == m ? &ref_ : nullptr);
  work_seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  work_ball_steps_ += static_cast<double>(owned_.size());
  current_ = false;
  results_written_ = kernels.writes_results();

  // The ghosts' new state, from their owners.
  const int ranks = team_->size();
  for (int r = 0; r < ranks; ++r) {
    double* out = send_buf_[r].data();
    for (std::uint32_t k : send_[r]) {
      for (double v : {b.x[k], b.y[k], b.z[k], b.vx[k], b.vy[k], b.vz[k], b.wx[k], b.wy[k], b.wz[k]}) *out++ = v;
    }
  }
  team_->exchange(send_buf_, recv_buf_);
  for (int r = 0; r < ranks; ++r) {
    const double* in = recv_buf_[r].data();
    for (std::uint32_t k : recv_[r]) {
      for (double* v : {&b.x[k], &b.y[k], &b.z[k], &b.vx[k], &b.vy[k], &b.vz[k], &b.wx[k], &b.wy[k], &b.wz[k]}) *v = *in++;
    }
  }

  // What decides whether the next step needs the whole model (the largest over the ranks, sent
  // with the sums): the displacement since the list was made, a ball outside the box.
  const Space& s = part_.space;
  const double moved2 = ref_.x.size() == m ? step_.moved2() : std::numeric_limits<double>::infinity();
  bool outside = false;
  const std::vector<double>* pos[3] = {&b.x, &b.y, &b.z};
  for (int a = 0; a < 3 && !outside; ++a) {
    if (s.wraps(a)) continue;
    for (std::size_t k = 0; k < m && !outside; ++k) {
      const double x = (*pos[a])[k];
      outside = x < s.lo[a] || x > s.hi[a];
    }
  }

  // The global sums: every rank's exact sums, merged (in any order, the same bits).
  if (mine.fastest_ball < global_ball_.size()) mine.fastest_ball = global_ball_[mine.fastest_ball];
  const std::size_t wall_count = full.walls.size();
  std::vector<WallLoad>& loads = step_.wall_totals();
  if (loads.size() != wall_count) loads.assign(wall_count, WallLoad{});
  sums_out_.clear();
  pack(mine, sums_out_);
  for (std::size_t w = 0; w < wall_count; ++w) pack(loads[w], sums_out_);
  sums_out_.push_back(moved2);
  sums_out_.push_back(outside ? 1.0 : 0.0);
  team_->allgather(sums_out_, sums_in_);
  const bool adds = !team_->shares_whole() || team_->rank() == 0;   // to the one whole model, once
  moved2_ = 0;
  double outside_any = 0;
  std::vector<WallLoad> totals(wall_count);
  const double* in = sums_in_.data();
  for (int r = 0; r < ranks; ++r) {
    StepSums part = unpack_sums(in);
    if (adds) sums.add(part);
    for (std::size_t w = 0; w < wall_count; ++w) {
      WallLoad load = unpack_load(in);
      totals[w].add(load);
    }
    moved2_ = std::max(moved2_, *in++);
    outside_any = std::max(outside_any, *in++);
  }
  outside_box_ = outside_any != 0;
  if (wall_count && adds) set_wall_loads(full.walls, totals);
}

bool BrickStep::outside_cell(const Model& full) {
  if (!full.space.periodic) return false;
  part_.space = full.space;
  // The part's ghosts are current, and each is some rank's own ball: the same answer as the owned
  // balls' alone.
  std::vector<double> any{trubal::outside_cell(part_, 0, part_.balls.size()) ? 1.0 : 0.0};
  team_->max_all(any);
  return any[0] != 0;
}

namespace {

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
  out.clear();
  for (std::uint32_t q : mine) out.push_back(static_cast<double>(part[q]));
  team.allgather(out, in);
  const double* p = in.data();
  for (const auto& ranks_own : by_rank)
    for (std::uint32_t k : ranks_own) whole[k] = static_cast<T>(*p++);
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

void BrickStep::sync(Model& full) {
  if (!live_ || current_ || model_ != &full) return;
  std::vector<double> out, in;
  gather_set(*team_, [](Balls& b, auto&& f) { each_moving_ball_array(b, f); }, part_.balls, full.balls, owned_, rank_balls_,
             out, in);
  gather_set(*team_, [](ContactTable& c, auto&& f) { each_history_array(c, f); }, part_.contacts, full.contacts, owned_pairs_,
             rank_pairs_, out, in);
  // The results only where the parts' last step wrote them (the same on every rank): a lean step's
  // table holds none worth reading, and a whole table that dropped its results stays without. The
  // part's go once gathered: nothing reads them there, and the next step that writes results
  // makes them again (ParallelStep::run).
  if (results_written_) {
    // (Members sharing one whole model: member 0 makes its arrays, then every member writes its own.)
    // (Ranks: the results are the largest arrays a sync makes; a rank out of memory here alone
    // must not leave the others in the gathers below.)
    if (!team_->shares_whole()) {
      comm::together([&] { full.contacts.keep_results(); }, "keeping the contact results");
    } else {
      if (team_->rank() == 0) full.contacts.keep_results();
      team_->barrier();
    }
    gather_set(*team_, [](ContactTable& c, auto&& f) { c.for_each_result_array(f); }, part_.contacts, full.contacts,
               owned_pairs_, rank_pairs_, out, in, true);
    results_written_ = false;
  }
  gather_set(*team_, [](WallContacts& w, auto&& f) { each_moving_wall_array(w, f); }, part_.wall_contacts,
             full.wall_contacts, owned_walls_, rank_walls_, out, in);
  current_ = true;
}

void BrickStep::loads_changed(const Model& full) {
  const Balls& from = full.balls;
  Balls& to = part_.balls;
  for (std::size_t q = 0; q < to.size(); ++q) {
    const std::size_t k = global_ball_[q];
    to.ax[q] = from.ax[k]; to.ay[q] = from.ay[k]; to.az[q] = from.az[k];
    to.amx[q] = from.amx[k]; to.amy[q] = from.amy[k]; to.amz[q] = from.amz[k];
  }
}

void BrickStep::release() {
  live_ = false;
  auto free = [](auto& v) { std::decay_t<decltype(v)>().swap(v); };
  part_ = Model{};
  scratch_ = StepScratch{};
  step_ = ParallelStep{};
  ref_ = VerletReference{};
  free(owner_); free(global_ball_); free(owned_); free(owned_pairs_); free(owned_walls_);
  free(rank_balls_); free(rank_pairs_); free(rank_walls_); free(send_); free(recv_); free(send_buf_); free(recv_buf_);
  free(sums_out_); free(sums_in_);
}

std::vector<std::pair<std::string, std::string>> BrickStep::info() const {
  std::vector<std::pair<std::string, std::string>> lines;
  if (splits_ == 0) return lines;
  const std::string member = team_->shares_whole() ? "thread" : "rank";
  lines.emplace_back("balls per " + member, std::to_string(least_balls_) + " to " + std::to_string(most_balls_) +
                                                " (" + member + " 0 also holds " + std::to_string(ghosts_) + " ghosts)");
  std::string shares;
  for (double share : shares_) fmt::format_to(std::back_inserter(shares), "{}{:.2f}", shares.empty() ? "" : " ", share);
  lines.emplace_back("shares of the balls", shares + " (by " + member + ", in proportion to the speed each stepped its own balls at)");
  lines.emplace_back("decompositions made", std::to_string(splits_));
  return lines;
}

}  // namespace trubal
