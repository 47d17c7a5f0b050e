#include "cycle/pair_list.hpp"

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <type_traits>

namespace trubal {
namespace {

bool same(const ContactTable& t, std::size_t p, const PairCandidates& c, std::size_t q) {
  return t.i[p] == c.i[q] && t.j[p] == c.j[q] && t.image_x[p] == c.image_x[q] && t.image_y[p] == c.image_y[q] &&
         t.image_z[p] == c.image_z[q];
}

// The arrays of the list and its history (for_each_pair_array's less the results).
template <class F> void for_each_state_array(ContactTable& t, F&& f) {
  f(t.i); f(t.j); f(t.image_x); f(t.image_y); f(t.image_z);
  t.for_each_history([&](auto& v, const HistoryPart&) { f(v); });
}

}  // namespace

void install_pairs(ContactTable& table, const PairCandidates& pairs) {
  const std::size_t old_size = table.size(), new_size = pairs.i.size();
  // A table whose arrays disagree in length (cleared by an edit) has nothing worth keeping. Results
  // not kept (empty arrays) stay so: a fresh list has none to move either.
  const bool results = old_size > 0 && table.results_kept();
  bool consistent = true;
  for_each_state_array(table, [&](auto& v) { consistent = consistent && v.size() == old_size; });
  // Where each new pair was in the old list (kNew: not there). 32 bits: the lists index balls by
  // 32 bits, and this array is much of a rebuild's peak memory.
  constexpr std::uint32_t kNew = ~std::uint32_t{0};
  std::vector<std::uint32_t> source(new_size, kNew);
  if (consistent) {
    std::size_t p = 0;
    for (std::size_t q = 0; q < new_size; ++q) {
      while (p < old_size && pair_before(table, p, pairs, q)) ++p;
      if (p < old_size && same(table, p, pairs, q)) source[q] = static_cast<std::uint32_t>(p);
    }
  }
  auto move = [&](auto& v) {
    using T = typename std::decay_t<decltype(v)>::value_type;
    std::vector<T> moved(new_size, T{});
    if (consistent)
      for (std::size_t q = 0; q < new_size; ++q)
        if (source[q] != kNew) moved[q] = v[source[q]];
    v.swap(moved);
  };
  for_each_state_array(table, move);
  if (results) table.for_each_result_array(move);
  else table.drop_results();
  table.i = pairs.i;
  table.j = pairs.j;
  table.image_x = pairs.image_x;
  table.image_y = pairs.image_y;
  table.image_z = pairs.image_z;
  table.list_version = fresh_list_version();
}

void install_pairs_zeroed(ContactTable& table, PairCandidates&& pairs) {
  const std::size_t n = pairs.i.size();
  table.drop_results();
  table.for_each_history([](auto& v, const HistoryPart&) { std::decay_t<decltype(v)>().swap(v); });
  table.i.swap(pairs.i);
  table.j.swap(pairs.j);
  table.image_x.swap(pairs.image_x);
  table.image_y.swap(pairs.image_y);
  table.image_z.swap(pairs.image_z);
  pairs = PairCandidates{};
  table.for_each_history([&](auto& v, const HistoryPart&) { v.assign(n, {}); });
  table.list_version = fresh_list_version();
}

std::uint64_t fresh_list_version() {
  static std::atomic<std::uint64_t> versions{0};   // unique across tables (a restored copy keeps its own)
  return ++versions;
}

PairCandidates pair_list_of(const ContactTable& table) {
  PairCandidates list;
  list.i = table.i; list.j = table.j;
  list.image_x = table.image_x; list.image_y = table.image_y; list.image_z = table.image_z;
  return list;
}

bool holds_pairs(const ContactTable& table, const PairCandidates& pairs) {
  const std::size_t size = pairs.i.size();
  bool consistent = true;
  for_each_state_array(const_cast<ContactTable&>(table), [&](const auto& v) { consistent = consistent && v.size() == size; });
  return consistent && table.i == pairs.i && table.j == pairs.j && table.image_x == pairs.image_x &&
         table.image_y == pairs.image_y && table.image_z == pairs.image_z;
}

}  // namespace trubal
