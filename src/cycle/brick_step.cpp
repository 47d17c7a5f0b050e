#include "cycle/brick_step.hpp"

#include "physics/timestep.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <functional>
#include <iterator>
#include <limits>
#include <new>
#include <numeric>
#include <type_traits>

#include <fmt/format.h>

#include "cycle/pair_list.hpp"
#include "cycle/sum_exchange.hpp"
#include "cycle/wall_list.hpp"
#include "support/comm.hpp"
#include "model/periodic_cell.hpp"

namespace trubal {
namespace {

constexpr std::uint32_t kAbsent = ~std::uint32_t{0};
constexpr std::size_t kHalo = 9;   // a ghost's state each step: position, velocity, spin

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

// `to`'s first `size` entries (each array cut or padded to that) and `add`'s after them, put in the
// order `before` gives (stable: of entries that compare equal, `to`'s first), every array alike.
template <class Visit, class T, class Less>
void merge_in_order(Visit&& visit, T& to, std::size_t size, T& add, Less&& before) {
  std::vector<const void*> from;
  visit(&add, [&](auto& v) { from.push_back(&v); });
  std::size_t a = 0;
  visit(&to, [&](auto& v) {
    const auto& more = *static_cast<const std::decay_t<decltype(v)>*>(from[a++]);
    v.resize(size);
    v.insert(v.end(), more.begin(), more.end());
  });
  std::vector<std::uint32_t> order(to.size());
  std::iota(order.begin(), order.end(), 0u);
  std::stable_sort(order.begin(), order.end(), before);
  T sorted;
  gather(visit, &to, &sorted, order);
  to = std::move(sorted);
}

// What a step changes, the arrays sync() gathers: the balls' motion and unbalanced forces, every
// pair's and wall contact's history, and the pairs' results where the last step wrote them (not
// their structure: balls, images).
template <class F> void each_moving_ball_array(Balls& b, F&& f) {
  for (auto* v : {&b.x, &b.y, &b.z, &b.vx, &b.vy, &b.vz, &b.wx, &b.wy, &b.wz, &b.fx, &b.fy, &b.fz, &b.mx, &b.my, &b.mz})
    f(*v);
}
template <class F> void each_history_array(ContactTable& c, F&& f) {
  c.for_each_history([&](auto& v, const HistoryPart&) { f(v); });
}
template <class F> void each_moving_wall_array(WallContacts& w, F&& f) {
  w.for_each_history([&](auto& v, const HistoryPart&) { f(v); });
  w.for_each_result_array(f);
}

// The cycle's kernels with the part's own pair laws (per ball of the part): every field but `laws`.
void take_kernels(const StepKernels& from, StepKernels& to) {
  to.features = from.features;
  to.estimate = from.estimate;
  to.moments = from.moments;
  to.dt = from.dt;
  to.dt_prev = from.dt_prev;
  to.dt_mean = from.dt_mean;
  to.beta = from.beta;
  to.alpha = from.alpha;
  to.local = from.local;
  to.gravity = from.gravity;
  to.contacts = from.contacts; to.contacts_full = from.contacts_full; to.contacts_lean = from.contacts_lean;
  to.cross = from.cross;
  to.walls = from.walls; to.walls_full = from.walls_full; to.walls_lean = from.walls_lean;
  to.motion = from.motion; to.motion_full = from.motion_full; to.motion_lean = from.motion_lean;
}

// A value as a word of a rebuild_local message: 64-bit integers (ids) by their bits, narrower ones
// by value (exact in a double).
template <class T> double to_word(T v) {
  if constexpr (std::is_integral_v<T> && sizeof(T) == 8) return std::bit_cast<double>(v);
  else return static_cast<double>(v);
}
template <class T> T from_word(double w) {
  if constexpr (std::is_integral_v<T> && sizeof(T) == 8) return std::bit_cast<T>(w);
  else return static_cast<T>(w);
}

// What travels between the members at a rebuild on the parts, as records of words: a ball (to
// each rank whose shell holds it, to its new owner where it moves), and the pairs and wall
// contacts of a ball that changes owner, with their history. Each kind lists its arrays once,
// from the model's own declarations, and every side walks that one list: pack_records sends,
// unpack_record and Rebuild::fill read, and a part's tables are cut (gather) and merged
// (merge_in_order) by it. So an array added to Balls::for_each_array, ContactTable's list or
// for_each_history, or WallContacts::for_each_array travels with its ball, and cannot be sent on
// one side and forgotten on the other. (LAMMPS keeps one such list per atom style:
// AtomVec::pack_exchange and unpack_exchange.)
//
// Travels<T>::each(t, f) calls f(array, ball) for each array in the record's order; `ball` says
// the array holds ball indices, which travel as the whole model's (a part's own numbers mean
// nothing to another member). kHead words come first, written and read by the caller.
template <class T> struct Travels;
template <class A, class B> bool same_array(const A& a, const B& b) {
  return static_cast<const void*>(&a) == static_cast<const void*>(&b);
}
// A ball: the whole model's index and the rank that owns it from now on, then every per-ball array.
template <> struct Travels<Balls> {
  static constexpr std::size_t kIndex = 0, kOwner = 1, kHead = 2;
  template <class F> static void each(Balls& b, F&& f) { b.for_each_array([&](auto& v) { f(v, false); }); }
};
// A pair: the list's arrays (i, j, j's image), then its history. A part's pairs hold no results but
// those its steps write (ParallelStep::run keeps them there), so a whole table without results
// cuts alike, and none travel.
template <> struct Travels<ContactTable> {
  static constexpr std::size_t kHead = 0;
  template <class F> static void each(ContactTable& c, F&& f) {
    c.for_each_list_array([&](auto& v) { f(v, same_array(v, c.i) || same_array(v, c.j)); });
    c.for_each_history([&](auto& v, const HistoryPart&) { f(v, false); });
  }
};
// A wall contact: every array, its last results too (find_wall_contacts keeps them readable until
// the next force pass).
template <> struct Travels<WallContacts> {
  static constexpr std::size_t kHead = 0;
  template <class F> static void each(WallContacts& w, F&& f) {
    w.for_each_array([&](auto& v) { f(v, same_array(v, w.ball)); });
  }
};

// f(array, word, ball) for each array of T's record, with the word it takes there.
template <class T, class F> void each_field(T& t, F&& f) {
  std::size_t word = Travels<T>::kHead;
  Travels<T>::each(t, [&](auto& v, bool ball) { f(v, word++, ball); });
}
template <class T> std::size_t record_words() {
  static const std::size_t words = [] {
    T t;
    std::size_t n = Travels<T>::kHead;
    Travels<T>::each(t, [&](auto&, bool) { ++n; });
    return n;
  }();
  return words;
}
// The records of `from`'s entries `rows`, one after another from `out` (their head words left to
// the caller): ball indices as the whole model's (`global`), an array not kept (a part's contact
// results) as zeros.
template <class T>
void pack_records(const T& from, const std::vector<std::uint32_t>& rows, const std::vector<std::uint32_t>& global,
                  double* out) {
  const std::size_t words = record_words<T>();
  each_field(const_cast<T&>(from), [&](const auto& v, std::size_t word, bool ball) {   // (it only reads)
    for (std::size_t q = 0; q < rows.size(); ++q) {
      const std::uint32_t row = rows[q];
      out[q * words + word] = row >= v.size() ? 0.0
                              : ball          ? static_cast<double>(global[static_cast<std::size_t>(v[row])])
                                              : to_word(v[row]);
    }
  });
}
// The record at `in` appended to `to` (its ball indices stay the whole model's).
template <class T> void unpack_record(const double* in, T& to) {
  each_field(to, [&](auto& v, std::size_t word, bool) {
    using E = typename std::decay_t<decltype(v)>::value_type;
    v.push_back(from_word<E>(in[word]));
  });
}
// The same lists as visitors of gather and merge_in_order: what a part holds of each.
const auto visit_balls = [](void* p, auto&& f) { Travels<Balls>::each(*static_cast<Balls*>(p), [&](auto& v, bool) { f(v); }); };
const auto visit_pairs = [](void* p, auto&& f) {
  Travels<ContactTable>::each(*static_cast<ContactTable*>(p), [&](auto& v, bool) { f(v); });
};
const auto visit_walls = [](void* p, auto&& f) {
  Travels<WallContacts>::each(*static_cast<WallContacts*>(p), [&](auto& v, bool) { f(v); });
};

// The bins rebuild_local finds each rank's neighbours by: at least `reach` wide across, so the balls
// of a pair lie in the same or neighbouring bins (through the periodic faces where the space wraps).
// A periodic space: the periodic search's bins (backends/periodic_pairs.cpp), in the cell's
// fractional coordinates; a box: over `box` (the least and largest coordinates of every ball). At
// most about two bins per ball of the whole model, as the periodic search.
class ShellBins {
 public:
  static constexpr std::uint32_t kNone = ~std::uint32_t{0};
  void fit(const Space& s, const std::vector<double>& box, double reach, std::size_t balls) {
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
  std::size_t count() const { return static_cast<std::size_t>(dims_[0]) * dims_[1] * dims_[2]; }
  // kNone for a ball not at a finite place (it touches nothing).
  std::uint32_t bin_of(double x, double y, double z) const {
    if (!(std::isfinite(x) && std::isfinite(y) && std::isfinite(z))) return kNone;
    double t[3] = {x, y, z};
    if (periodic_) {   // the coordinates less their tilt terms, as the periodic search takes them
      const Space& s = *s_;
      const double sz = (z - s.lo[2]) / frame_.lz;
      const double ty = y - frame_.yz * sz;
      t[0] = x - frame_.xy * ((ty - s.lo[1]) / frame_.ly) - frame_.xz * sz;
      t[1] = ty;
    }
    int w[3];
    for (int a = 0; a < 3; ++a) {
      const double q = extent_[a] > 0 ? std::floor((t[a] - lo_[a]) / extent_[a] * dims_[a]) : 0.0;
      w[a] = !(q >= 0) ? 0 : (q >= dims_[a] ? dims_[a] - 1 : static_cast<int>(q));
    }
    return static_cast<std::uint32_t>((w[2] * dims_[1] + w[1]) * dims_[0] + w[0]);
  }
  // The bin and those around it (wrapped across the periodic faces; fewer at a bounded edge).
  void neighbours(std::uint32_t bin, std::vector<std::uint32_t>& out) const {
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
  // The OR of `mask` over the bin and those around it (as neighbours() lists them).
  std::uint64_t around(std::uint32_t bin, const std::uint64_t* mask, std::vector<std::uint32_t>& scratch) const {
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

 private:
  const Space* s_ = nullptr;
  bool periodic_ = false;
  std::array<bool, 3> wraps_{};
  std::array<double, 3> lo_{}, extent_{};
  std::array<int, 3> dims_{1, 1, 1};
  CellFrame frame_;
};

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
  shared_ = false;
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

std::vector<double> BrickStep::proposed_shares() {
  // Every member's speed since the last split (its own balls' forces and motion, not the waits):
  // the next shares are halfway between the last ones and the speeds' proportions, each clamped
  // between half and twice an equal share (then normalised), so that one noisy interval moves
  // them little. A core slowed by the machine, or a part where the contacts crowd, gets fewer
  // balls.
  const int ranks = team_->size();
  if (shares_.size() != static_cast<std::size_t>(ranks)) shares_.assign(ranks, 1.0 / ranks);
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

void BrickStep::together(const std::function<void()>& work, const std::string& doing) {
  if (team_->shares_whole()) work();   // (threads: Pipeline::each_part's abort releases the others)
  else comm::together(work, doing);
}

void BrickStep::split(const Model& full, const VerletReference& ref) {
  update_shares();   // (a collective call)
  // A rank that cannot make its part (out of memory) must not leave the others stepping theirs and
  // waiting for its ghosts: the ranks agree here, and every one stops with that rank's message.
  together([&] {
    if (!team_->shares_whole() && team_->rank() == policy_->fail_split) {   // (a rank's test fault)
      policy_->fail_split = -1;
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
    cuts_.clear();
    bisect(b, order, 0, n, ranks, 0, shares_, owner_, cuts_);
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
  part_.contacts.drop_results();   // (a step that writes them makes them: Travels<ContactTable>)
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
  max_radius_ = b.max_radius();
  shell_base_ = 0;
  list_local_ = false;
  moved2_ = 0;
  outside_box_ = false;
  model_ = &full;
  full_balls_ = n;
  list_version_ = c.list_version;
  wall_version_ = wc.list_version;
  walls_any_ = !full.walls.empty() || wc.size() > 0;
  live_ = true;
  current_ = true;
  shared_ = true;
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

// One rebuild of the pair list on the parts, handed from stage to stage (rebuild_local): each
// stage reads what the ones before it left here. The new part is made beside the old one, which
// stays whole for a sync where a stage fails, and takes its place at commit_rebuild.
struct BrickStep::Rebuild {
  int ranks = 0, me = 0;
  double skin = 0;
  double reach = 0;   // the farthest any pair's balls may be apart
  // fit_shell_bins:
  ShellBins bins;
  // find_moves: per owned ball (in owned_'s order), the rank that owns it from now on and its bin;
  // the balls that change owner, this rank's and every rank's (whole-model index, new owner, bin).
  std::vector<int> dest;
  std::vector<std::uint32_t> bin_of;
  std::vector<double> moves, all_moves;
  std::size_t moved = 0;
  // balanced_after_moves: each rank's count of balls after the moves.
  std::vector<std::size_t> count;
  // mark_bins: the bins of the balls this rank will own, a bit each; every rank's, one row each.
  std::vector<std::uint8_t> marks, all_marks;
  // find_shells: per rank, the balls of this part it sends there (in the part's order).
  std::vector<std::vector<std::uint32_t>> shell;
  // find_leaving: per ball of the part, the rank it moves to (-1: none; empty: no moves); per rank,
  // the moving balls' pairs and wall contacts it is sent (in the part's order).
  std::vector<int> part_dest;
  std::vector<std::vector<std::uint32_t>> pair_rows, wall_rows;
  // The messages, and what each rank sends this one (shells_within_bounds): its balls, the moving
  // balls' pairs and wall contacts; the balls received over every rank.
  std::vector<std::vector<double>> out, in;
  std::vector<std::size_t> shell_in, in_pairs, in_walls;
  double received = 0;
  // list_entries: this rank's balls and those received, in the whole model's order. from: -1 this
  // rank's (at: part index), else the rank whose message holds it (at: its record there); owner:
  // the rank that owns it from now on.
  struct Entry { std::uint32_t global; int from; std::uint32_t at; int owner; };
  std::vector<Entry> entries;
  // unpack_arrivals: the pairs of the balls that move to this rank, with their history (in the
  // whole model's numbers), and their wall contacts.
  ContactTable arrived_pairs;
  WallContacts arrived_walls;
  // search_part: the pairs found among the entries, those kept (touching a ball of this rank), the
  // entries the part keeps and each entry's index in it (kAbsent: not kept).
  PairCandidates found;
  std::vector<std::uint32_t> pairs, keep, local;
  // carry_history and make_next_balls: the new part.
  Balls next_balls;
  ContactTable next_table;
  std::vector<std::uint32_t> next_global, next_owned, next_owned_pairs;
  std::vector<std::vector<std::uint32_t>> next_send, next_recv;
  std::vector<std::uint8_t> next_ghost;
  std::size_t next_ghosts = 0;
  VerletReference next_ref;

  // Ball arrays of the entries `pick` (all where null), from this rank's `part` and the records
  // received (a ball's record read as it was packed, but column by column); `only` says which
  // arrays (by the Balls they belong to), the others stay empty.
  template <class Only>
  void fill(const Balls& part, Balls& to, const std::vector<std::uint32_t>* pick, Only&& only) const {
    const std::size_t words = record_words<Balls>();
    std::vector<const void*> source;
    each_field(const_cast<Balls&>(part), [&](auto& v, std::size_t, bool) { source.push_back(&v); });
    std::size_t array = 0;
    each_field(to, [&](auto& v, std::size_t word, bool) {
      using V = std::decay_t<decltype(v)>;
      using T = typename V::value_type;
      const V& mine = *static_cast<const V*>(source[array++]);
      if (!only(to, static_cast<const void*>(&v))) return;
      const std::size_t size = pick ? pick->size() : entries.size();
      v.resize(size);
      for (std::size_t q = 0; q < size; ++q) {
        const Entry& e = entries[pick ? (*pick)[q] : q];
        v[q] = e.from < 0 ? mine[e.at] : from_word<T>(in[e.from][e.at * words + word]);
      }
    });
  }
};

bool BrickStep::rebuild_local(const Model& full, double skin, Backend& search, ThreadPool& pool) {
  // (Every test below reads what is the same on every rank, or is agreed on: every rank returns
  // alike. The calls on team_ and the stages said to be collective are made by every member.)
  if (!may_rebuild_local(full)) return false;
  Rebuild r;
  r.ranks = team_->size();
  r.me = team_->rank();
  r.skin = skin;
  r.reach = 2 * max_radius_ + skin;

  fit_shell_bins(r, full.space);   // (collective)
  together([&] { find_moves(r); }, "finding the balls that change owner");
  team_->allgather(r.moves, r.all_moves);
  r.moved = r.all_moves.size() / 3;
  if (!balanced_after_moves(r)) return false;
  together([&] { mark_bins(r); }, "finding the balls its neighbours need for a new pair list");
  team_->allgather(r.marks, r.all_marks);
  together([&] {
    find_shells(r);
    find_leaving(r);
    announce_counts(r);
  }, "finding the balls its neighbours need for a new pair list");
  team_->exchange(r.out, r.in);
  if (!shells_within_bounds(r)) return false;   // (collective)
  together([&] { pack_messages(r); }, "sending the balls its neighbours need for a new pair list");
  team_->exchange(r.out, r.in);
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
  commit_rebuild(r);
  together([&] { index_part(); }, "indexing its new pair list");
  if (!full.walls.empty() || part_.wall_contacts.size() > 0)
    together([&] { find_part_walls(r, full, pool); }, "finding the wall contacts of its part");
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
  }
}

bool BrickStep::balanced_after_moves(Rebuild& r) const {
  // The counts after the moves, against the shares: a tenth off (and two balls), and the parts are
  // made afresh from the whole model, balanced again.
  r.count.resize(r.ranks);
  for (int q = 0; q < r.ranks; ++q) r.count[q] = rank_balls_[q].size();
  for (std::size_t t = 0; t < r.moved; ++t) {
    --r.count[owner_[static_cast<std::size_t>(r.all_moves[3 * t])]];
    ++r.count[static_cast<std::size_t>(r.all_moves[3 * t + 1])];
  }
  const double total = std::accumulate(shares_.begin(), shares_.end(), 0.0);
  for (int q = 0; q < r.ranks; ++q) {
    const double want = shares_[q] / total * static_cast<double>(full_balls_);
    if (std::abs(static_cast<double>(r.count[q]) - want) > 0.1 * want + 2) return false;
  }
  return true;
}

void BrickStep::mark_bins(Rebuild& r) const {
  r.marks.assign((r.bins.count() + 7) / 8, 0);
  auto mark = [&](std::uint32_t bin) { r.marks[bin / 8] |= static_cast<std::uint8_t>(1u << (bin % 8)); };
  for (std::size_t q = 0; q < owned_.size(); ++q)
    if (r.dest[q] == r.me && r.bin_of[q] != ShellBins::kNone) mark(r.bin_of[q]);
  for (std::size_t t = 0; t < r.moved; ++t)
    if (static_cast<int>(r.all_moves[3 * t + 1]) == r.me) mark(static_cast<std::uint32_t>(r.all_moves[3 * t + 2]));
}

void BrickStep::find_shells(Rebuild& r) const {
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

void BrickStep::find_leaving(Rebuild& r) const {
  // A moving ball's pairs and wall contacts (this rank's part holds all of them), to its new owner;
  // a pair of two balls moving to two ranks, to both.
  r.pair_rows.assign(r.ranks, {});
  r.wall_rows.assign(r.ranks, {});
  if (r.moved == 0) return;
  r.part_dest.assign(part_.balls.size(), -1);
  for (std::size_t q = 0; q < owned_.size(); ++q)
    if (r.dest[q] != r.me) r.part_dest[owned_[q]] = r.dest[q];
  const ContactTable& c = part_.contacts;
  for (std::size_t p = 0; p < c.size(); ++p) {
    const int di = r.part_dest[c.i[p]], dj = r.part_dest[c.j[p]];
    for (int d : {di, dj != di ? dj : -1})
      if (d >= 0) r.pair_rows[d].push_back(static_cast<std::uint32_t>(p));
  }
  const WallContacts& w = part_.wall_contacts;
  for (std::size_t q = 0; q < w.size(); ++q) {
    const int d = r.part_dest[w.ball[q]];
    if (d >= 0) r.wall_rows[d].push_back(static_cast<std::uint32_t>(q));
  }
}

void BrickStep::announce_counts(Rebuild& r) const {
  // To each rank, how many balls, pairs and wall contacts this one sends it.
  r.out.assign(r.ranks, {});
  r.in.assign(r.ranks, {});
  for (int q = 0; q < r.ranks; ++q) {
    r.out[q] = {static_cast<double>(r.shell[q].size()), static_cast<double>(r.pair_rows[q].size()),
                static_cast<double>(r.wall_rows[q].size())};
    r.in[q].assign(3, 0.0);
  }
}

bool BrickStep::shells_within_bounds(Rebuild& r) {
  r.shell_in.assign(r.ranks, 0);
  r.in_pairs.assign(r.ranks, 0);
  r.in_walls.assign(r.ranks, 0);
  for (int q = 0; q < r.ranks; ++q) {
    r.received += r.in[q][0];
    r.shell_in[q] = static_cast<std::size_t>(r.in[q][0]);
    r.in_pairs[q] = static_cast<std::size_t>(r.in[q][1]);
    r.in_walls[q] = static_cast<std::size_t>(r.in[q][2]);
  }
  // The balls have spread where the largest shell has grown past twice what it was at the first
  // rebuild after the split: the parts are made afresh (and balanced) from the whole model.
  std::vector<double> most{r.received};
  team_->max_all(most);
  if (shell_base_ == 0) shell_base_ = std::max(most[0], 1.0);
  else if (most[0] > 2 * shell_base_) return false;
  return true;
}

void BrickStep::pack_messages(Rebuild& r) const {
  // To each rank, the records of the balls of its shell, then those of the moving balls' pairs and
  // wall contacts (Travels); and room for what it sends here.
  const std::size_t words = record_words<Balls>(), pair_words = record_words<ContactTable>(),
                    wall_words = record_words<WallContacts>();
  for (int q = 0; q < r.ranks; ++q) {
    const std::vector<std::uint32_t>& shell = r.shell[q];
    std::vector<double>& out = r.out[q];
    const std::size_t count = shell.size(), pairs = r.pair_rows[q].size(), walls = r.wall_rows[q].size();
    out.assign(words * count + pair_words * pairs + wall_words * walls, 0.0);
    for (std::size_t t = 0; t < count; ++t) {
      const std::uint32_t k = shell[t];
      out[t * words + Travels<Balls>::kIndex] = global_ball_[k];
      out[t * words + Travels<Balls>::kOwner] = r.part_dest.empty() || r.part_dest[k] < 0 ? r.me : r.part_dest[k];
    }
    double* const pairs_at = out.data() + words * count;
    pack_records(part_.balls, shell, global_ball_, out.data());
    pack_records(part_.contacts, r.pair_rows[q], global_ball_, pairs_at);
    pack_records(part_.wall_contacts, r.wall_rows[q], global_ball_, pairs_at + pair_words * pairs);
    std::vector<std::uint32_t>().swap(r.pair_rows[q]);
    std::vector<std::uint32_t>().swap(r.wall_rows[q]);
    r.in[q].assign(words * r.shell_in[q] + pair_words * r.in_pairs[q] + wall_words * r.in_walls[q], 0.0);
  }
}

void BrickStep::list_entries(Rebuild& r) const {
  const std::size_t words = record_words<Balls>();
  r.entries.reserve(owned_.size() + static_cast<std::size_t>(r.received));
  for (std::size_t q = 0; q < owned_.size(); ++q) r.entries.push_back({global_ball_[owned_[q]], -1, owned_[q], r.dest[q]});
  for (int q = 0; q < r.ranks; ++q)
    for (std::size_t t = 0; t < r.shell_in[q]; ++t) {
      const double* head = r.in[q].data() + t * words;
      r.entries.push_back({static_cast<std::uint32_t>(head[Travels<Balls>::kIndex]), q, static_cast<std::uint32_t>(t),
                           static_cast<int>(head[Travels<Balls>::kOwner])});
    }
  std::sort(r.entries.begin(), r.entries.end(),
            [](const Rebuild::Entry& p, const Rebuild::Entry& q) { return p.global < q.global; });
}

void BrickStep::unpack_arrivals(Rebuild& r) const {
  // The history records of the balls that move to this rank: their pairs (in the whole model's
  // numbers) and their wall contacts, after the balls in each rank's message.
  const std::size_t words = record_words<Balls>(), pair_words = record_words<ContactTable>(),
                    wall_words = record_words<WallContacts>();
  for (int q = 0; q < r.ranks; ++q) {
    const double* rec = r.in[q].data() + words * r.shell_in[q];
    for (std::size_t t = 0; t < r.in_pairs[q]; ++t, rec += pair_words) unpack_record(rec, r.arrived_pairs);
    for (std::size_t t = 0; t < r.in_walls[q]; ++t, rec += wall_words) unpack_record(rec, r.arrived_walls);
  }
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
  if (kernels_.features.stiffness_damping) scratch_.ball_dashpot.resize(m);
  if (kernels_.features.rolling) scratch_.ball_rolling.resize(m);
  StepSums mine;
  const auto t0 = std::chrono::steady_clock::now();
  step_.run(pool, part_, scratch_, kernels_, mine, times, ref_.x.size() == m ? &ref_ : nullptr);
  work_seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  work_ball_steps_ += static_cast<double>(owned_.size());
  current_ = false;
  shared_ = false;
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

bool BrickStep::wrap(Model& full) {
  if (policy_->local_rule < 0 || !live_ || model_ != &full) return false;
  if (results_written_ && !current_) return false;
  part_.space = full.space;
  // (Set first: where a member fails below, the others' parts may be wrapped, and every member
  // must then make the whole list from the parts alike.)
  list_local_ = true;
  current_ = false;
  shared_ = false;
  std::vector<WrapTerm> terms;
  // (A ball a million cells away fails the wrap on each rank that holds a copy of it, not on all.)
  together([&] { wrap_into_cell(part_, &ref_.x, &ref_.y, &ref_.z, &terms); },
                 "wrapping its balls into the periodic cell");
  // Every rank's own balls' terms, in the whole model's order (a ball's own terms stay in theirs).
  std::vector<double> mine, all;
  for (const WrapTerm& t : terms)
    if (!scratch_.ghost[t.ball]) {
      mine.push_back(static_cast<double>(global_ball_[t.ball]));
      mine.push_back(t.work);
      mine.push_back(t.gross);
    }
  team_->allgather(mine, all);
  std::vector<WrapTerm> merged(all.size() / 3);
  for (std::size_t q = 0; q < merged.size(); ++q)
    merged[q] = {static_cast<std::size_t>(all[3 * q]), all[3 * q + 1], all[3 * q + 2]};
  std::stable_sort(merged.begin(), merged.end(), [](const WrapTerm& p, const WrapTerm& q) { return p.ball < q.ball; });
  if (!team_->shares_whole() || team_->rank() == 0) add_wrap_terms(full, merged);   // (once to the one whole model)
  ++local_wraps_;
  return true;
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
  // Ranks: to rank 0's whole model alone (BrickStep::share hands it to the others where they need it).
  out.clear();
  for (std::uint32_t q : mine) out.push_back(static_cast<double>(part[q]));
  comm::gather_to_root(out, in);
  if (!comm::root()) return;
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
  if (whole_ref && whole_ref->x.size() == full.balls.size()) {
    std::vector<double> out, in;
    gather_array(*team_, ref_.x, whole_ref->x, owned_, rank_balls_, out, in);
    gather_array(*team_, ref_.y, whole_ref->y, owned_, rank_balls_, out, in);
    gather_array(*team_, ref_.z, whole_ref->z, owned_, rank_balls_, out, in);
  }
  list_local_ = false;
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

void BrickStep::sync(Model& full, VerletReference* whole_ref) {
  if (!live_ || current_ || model_ != &full) return;
  std::vector<double> out, in;
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
    // (Members sharing one whole model: member 0 makes its arrays, then every member writes its own.)
    // (Ranks: the results are the largest arrays a sync makes; a rank out of memory here alone
    // must not leave the others in the gathers below.)
    if (!team_->shares_whole()) {
      comm::together([&] { if (comm::root()) full.contacts.keep_results(); }, "keeping the contact results");
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

template <class T> void BrickStep::gather_whole(const std::vector<T>& mine, std::vector<T>& all) {
  if (team_->shares_whole()) team_->allgather(mine, all);
  else comm::gather_to_root(mine, all);
}

void BrickStep::share(Model& full, VerletReference* whole_ref, bool release_parts) {
  if (!live_ || model_ != &full) return;
  sync(full, whole_ref);
  const bool done = shared_ || team_->shares_whole() || team_->size() < 2;
  shared_ = true;
  if (release_parts) release();   // (before the whole model comes: the two are never held together)
  if (done) return;
  // Rank 0's whole model, current, to the others, and the list's reference positions.
  broadcast_arrays(full);
  if (whole_ref && whole_ref->x.size() == full.balls.size()) {
    comm::broadcast(whole_ref->x);
    comm::broadcast(whole_ref->y);
    comm::broadcast(whole_ref->z);
  }
  list_version_ = full.contacts.list_version;
  wall_version_ = full.wall_contacts.list_version;
}

void broadcast_arrays(Model& m) {
  m.balls.for_each_array([](auto& v) { comm::broadcast(v); });
  m.contacts.for_each_pair_array([](auto& v) { comm::broadcast(v); });
  comm::broadcast(m.contacts.results_cycle);
  m.wall_contacts.for_each_array([](auto& v) { comm::broadcast(v); });
  // What came from rank 0 is new here: new versions, so that no index of the old arrays passes for
  // one of these (Pipeline::prepare has rank 0 decide whether to search).
  if (!comm::root()) {
    m.contacts.list_version = fresh_list_version();
    m.wall_contacts.list_version = fresh_list_version();
  }
}

double BrickStep::critical_step(const Features& features) {
  const std::uint8_t* ghost = scratch_.ghost.size() == part_.balls.size() ? scratch_.ghost.data() : nullptr;
  std::vector<double> any{any_ball_free(part_, features.rotation, ghost) ? 1.0 : 0.0};
  team_->max_all(any);
  std::vector<double> least{-balls_critical_step(part_, features, any[0] != 0, ghost)};
  team_->max_all(least);   // (the smallest step: a max of the negatives, exact)
  return -least[0];
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
  step_ = ParallelStep{*policy_};
  ref_ = VerletReference{};
  free(owner_); free(global_ball_); free(owned_); free(owned_pairs_); free(owned_walls_);
  free(rank_balls_); free(rank_pairs_); free(rank_walls_); free(send_); free(recv_); free(send_buf_); free(recv_buf_);
  free(sums_out_); free(sums_in_);
}

std::size_t array_bytes(const Model& m) {
  std::size_t bytes = 0;
  auto add = [&](const auto& v) { bytes += v.capacity() * sizeof(typename std::decay_t<decltype(v)>::value_type); };
  m.balls.for_each_array(add);
  m.contacts.for_each_pair_array(add);
  const_cast<WallContacts&>(m.wall_contacts).for_each_array(add);   // (it has no const visitor; it only reads)
  return bytes;
}

std::size_t BrickStep::part_bytes() const { return array_bytes(part_); }

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
  {
    lines.emplace_back("pair lists rebuilt on the parts",
                       std::to_string(local_rebuilds_) + " (each rank searching its own balls and those within reach of them)");
    lines.emplace_back("wraps on the parts", std::to_string(local_wraps_) + " (balls moved across the periodic faces by their ranks)");
    lines.emplace_back("balls that changed rank", std::to_string(migrations_) +
                                                      " (at the rebuilds on the parts: a ball goes to the " + member +
                                                      " whose brick of the split holds it now, with its history)");
  }
  return lines;
}

}  // namespace trubal
