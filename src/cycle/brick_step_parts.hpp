// The spatial decomposition's own parts (cycle/brick_step.hpp), shared by its files and included by
// them alone:
// - brick_step.cpp: the step on a part, the cell's field and wraps on the parts, what the members
//   report (counts, memory, the critical step);
// - brick_split.cpp: the owners (the recursive bisection, the shares by speed, the brick that holds
//   a ball that moved) and a member's part made from the whole model;
// - brick_rebuild.cpp: rebuild_local, a new pair list on the parts, as its stages in order, and the
//   stages that search the part and carry its history over;
// - brick_halo.cpp: the bins by which a rebuild finds the balls each member needs from the others;
// - brick_migrate.cpp: what a ball takes with it (the records below) and the messages of a rebuild;
// - brick_sync.cpp: the whole model made current from the parts (sync, share), rank 0's let go
//   (hollow_whole), what the parts count and hold between CYCLEs;
// - brick_stream.cpp: the parts' state streamed to rank 0 in the whole model's order (SAVE, PRINT).
// - brick_sort.cpp: the balls put in space order on the parts (sort_in_space).
#pragma once

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <stdexcept>
#include <type_traits>
#include <vector>

#include "backends/pair_candidates.hpp"
#include "cycle/brick_step.hpp"
#include "model/model.hpp"
#include "model/periodic_cell.hpp"

namespace trubal {

constexpr std::uint32_t kAbsent = ~std::uint32_t{0};
constexpr std::size_t kHalo = 9;   // a ghost's state each step: position, velocity, spin

// `to`'s arrays are `from`'s at the picked indices (the visitor lists a struct's arrays in one order).
template <class Visit>
void gather(Visit&& visit, const void* from, void* to, const std::vector<std::uint32_t>& pick) {
  std::vector<const void*> source;
  visit(const_cast<void*>(from), [&](auto& v) { source.push_back(&v); });
  std::size_t n = 0;
  visit(to, [&](auto& v) {
    using V = std::decay_t<decltype(v)>;
    if (n >= source.size()) throw std::logic_error("internal error: a part's table gathered into one of other arrays");
    const V& s = *static_cast<const V*>(source[n++]);
    v.resize(pick.size());
    for (std::size_t q = 0; q < pick.size(); ++q) v[q] = s[pick[q]];
  });
  if (n != source.size()) throw std::logic_error("internal error: a part's table gathered into one of other arrays");
}

// An empty table to gather `t`'s entries into: one that visits the same arrays (a contact table:
// the same history parts in use).
template <class T> T empty_like(const T&) { return T{}; }
inline ContactTable empty_like(const ContactTable& t) {
  ContactTable empty;
  empty.history_laws = t.history_laws;
  return empty;
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
  T sorted = empty_like(to);
  gather(visit, &to, &sorted, order);
  to = std::move(sorted);
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
// each rank whose shell holds it, to its new owner where it moves), and the pairs, wall contacts
// and bonds of a ball that changes owner, with their history and state. Each kind lists its arrays once,
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

// A bond (model/bonds.hpp): every array, its state and fate too. Its balls are named by their ids,
// which mean the same on every member.
template <> struct Travels<Bonds> {
  static constexpr std::size_t kHead = 0;
  template <class F> static void each(Bonds& t, F&& f) { t.for_each_array([&](auto& v) { f(v, false); }); }
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
// A pair's record: as long as the history parts in use of the table (ContactTable::history_laws;
// every rank's part keeps the same).
inline std::size_t record_words(const ContactTable& c) {
  std::size_t n = Travels<ContactTable>::kHead;
  Travels<ContactTable>::each(const_cast<ContactTable&>(c), [&](auto&, bool) { ++n; });
  return n;
}
template <class T> std::size_t record_words(const T&) { return record_words<T>(); }

// The records of `from`'s entries `rows`, one after another from `out` (their head words left to
// the caller): ball indices as the whole model's (`global`), an array not kept (a part's contact
// results) as zeros.
template <class T>
void pack_records(const T& from, const std::vector<std::uint32_t>& rows, const std::vector<std::uint32_t>& global,
                  double* out) {
  const std::size_t words = record_words(from);
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
const auto visit_balls = [](void* p, auto&& f) {
  Travels<Balls>::each(*static_cast<Balls*>(p), [&](auto& v, bool) { f(v); });
};
const auto visit_pairs = [](void* p, auto&& f) {
  Travels<ContactTable>::each(*static_cast<ContactTable*>(p), [&](auto& v, bool) { f(v); });
};
const auto visit_bonds = [](void* p, auto&& f) {
  Travels<Bonds>::each(*static_cast<Bonds*>(p), [&](auto& v, bool) { f(v); });
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
  void fit(const Space& s, const std::vector<double>& box, double reach, std::size_t balls);
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
  void neighbours(std::uint32_t bin, std::vector<std::uint32_t>& out) const;
  // The OR of `mask` over the bin and those around it (as neighbours() lists them).
  std::uint64_t around(std::uint32_t bin, const std::uint64_t* mask, std::vector<std::uint32_t>& scratch) const;

 private:
  const Space* s_ = nullptr;
  bool periodic_ = false;
  std::array<bool, 3> wraps_{};
  std::array<double, 3> lo_{}, extent_{};
  std::array<int, 3> dims_{1, 1, 1};
  CellFrame frame_;
};

// A new version for a part's pair list or wall contacts (brick_split.cpp).
std::uint64_t next_part_version();

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
  // the balls that change owner, this rank's and every rank's (kMove numbers each: whole-model
  // index, new owner, bin, old owner).
  static constexpr std::size_t kMove = 4;
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
  std::vector<std::vector<std::uint32_t>> pair_rows, wall_rows, bond_rows;
  // The messages, and what each rank sends this one (shells_within_bounds): its balls, the moving
  // balls' pairs and wall contacts; the balls received over every rank.
  std::vector<std::vector<double>> out, in;
  std::vector<std::size_t> shell_in, in_pairs, in_walls, in_bonds;
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
  Bonds arrived_bonds;
  // The first list of parts made from a save (split_from_file): its pairs and wall contacts (in
  // the whole model's numbers), which the new list takes in.
  bool from_file = false;
  ContactTable file_pairs;
  WallContacts file_walls;
  // search_part: the pairs found among the entries, those kept (touching a ball of this rank), the
  // entries the part keeps and each entry's index in it (kAbsent: not kept).
  PairCandidates found;
  std::vector<std::uint32_t> pairs, keep, local;
  // A bonded scene's: the entries of each intact bond of the new part, two by two.
  std::vector<std::uint32_t> bond_ends;
  // carry_history and make_next_balls: the new part.
  Balls next_balls;
  ContactTable next_table;
  Bonds next_bonds;   // a bonded scene's: the bonds of the balls this member owns from now on
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

}  // namespace trubal
