#include "cycle/pair_list.hpp"

#include <algorithm>
#include <atomic>
#include <type_traits>

namespace trubal {
namespace {

// Order of pairs in a list: by i, then j, then image (the same two balls may touch across
// several periodic faces in a small cell).
bool before(const ContactTable& t, std::size_t p, const PairCandidates& c, std::size_t q) {
  if (t.i[p] != c.i[q]) return t.i[p] < c.i[q];
  if (t.j[p] != c.j[q]) return t.j[p] < c.j[q];
  if (t.image_x[p] != c.image_x[q]) return t.image_x[p] < c.image_x[q];
  if (t.image_y[p] != c.image_y[q]) return t.image_y[p] < c.image_y[q];
  return t.image_z[p] < c.image_z[q];
}

bool same(const ContactTable& t, std::size_t p, const PairCandidates& c, std::size_t q) {
  return t.i[p] == c.i[q] && t.j[p] == c.j[q] && t.image_x[p] == c.image_x[q] && t.image_y[p] == c.image_y[q] &&
         t.image_z[p] == c.image_z[q];
}

}  // namespace

void install_pairs(ContactTable& table, const PairCandidates& pairs) {
  const std::size_t old_size = table.size(), new_size = pairs.i.size();
  // A table whose arrays disagree in length (cleared by an edit) has nothing worth keeping.
  bool consistent = true;
  table.for_each_pair_array([&](auto& v) { consistent = consistent && v.size() == old_size; });
  std::vector<std::int64_t> source(new_size, -1);
  if (consistent) {
    std::size_t p = 0;
    for (std::size_t q = 0; q < new_size; ++q) {
      while (p < old_size && before(table, p, pairs, q)) ++p;
      if (p < old_size && same(table, p, pairs, q)) source[q] = static_cast<std::int64_t>(p);
    }
  }
  table.for_each_pair_array([&](auto& v) {
    using T = typename std::decay_t<decltype(v)>::value_type;
    std::vector<T> moved(new_size, T{});
    if (consistent)
      for (std::size_t q = 0; q < new_size; ++q)
        if (source[q] >= 0) moved[q] = v[source[q]];
    v.swap(moved);
  });
  table.i = pairs.i;
  table.j = pairs.j;
  table.image_x = pairs.image_x;
  table.image_y = pairs.image_y;
  table.image_z = pairs.image_z;
  static std::atomic<std::uint64_t> versions{0};   // unique across tables (a restored copy keeps its own)
  table.list_version = ++versions;
}

bool holds_pairs(const ContactTable& table, const PairCandidates& pairs) {
  const std::size_t size = pairs.i.size();
  bool consistent = true;
  table.for_each_pair_array([&](const auto& v) { consistent = consistent && v.size() == size; });
  return consistent && table.i == pairs.i && table.j == pairs.j && table.image_x == pairs.image_x &&
         table.image_y == pairs.image_y && table.image_z == pairs.image_z;
}

}  // namespace trubal
