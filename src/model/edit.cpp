#include "model/edit.hpp"

#include <algorithm>
#include <limits>
#include <stdexcept>
#include <string>

namespace trubal {

std::int64_t find_ball(const Model& model, std::int64_t id) {
  const auto& ids = model.balls.id;
  auto it = std::lower_bound(ids.begin(), ids.end(), id);
  return (it != ids.end() && *it == id) ? it - ids.begin() : -1;
}

std::size_t add_ball(Model& model, std::int64_t id, int type, double x, double y, double z, double rad) {
  Balls& b = model.balls;
  if (!(rad > 0)) throw std::invalid_argument("ball radius must be positive");
  if (id <= 0) {
    if (b.size() && b.id.back() == std::numeric_limits<std::int64_t>::max())
      throw std::invalid_argument("no ball id is left after " + std::to_string(b.id.back()) +
                                  ": give the new ball its id (BALL ... id n)");
    id = b.size() ? b.id.back() + 1 : 1;
  }
  auto pos = std::lower_bound(b.id.begin(), b.id.end(), id) - b.id.begin();
  if (static_cast<std::size_t>(pos) < b.size() && b.id[pos] == id)
    throw std::invalid_argument("ball id " + std::to_string(id) + " is taken");
  // Contact pairs refer to indices: inserting in the middle shifts them.
  if (static_cast<std::size_t>(pos) < b.size()) {
    for (auto& v : model.contacts.i) v += (v >= pos);
    for (auto& v : model.contacts.j) v += (v >= pos);
    model.contacts.list_version = 0;   // a list nobody has indexed
    for (auto& v : model.wall_contacts.ball) v += (v >= pos);
    model.wall_contacts.list_version = 0;
  }
  model.critical_dt = 0;   // the new ball may be stiffer or lighter than any before
  b.for_each_array([&](auto& v) { v.insert(v.begin() + pos, typename std::decay_t<decltype(v)>::value_type{}); });
  b.id[pos] = id;
  b.type[pos] = type;
  b.x[pos] = x; b.y[pos] = y; b.z[pos] = z;
  b.rad[pos] = rad;
  return pos;
}

void reindex_wall_contacts(Model& model) {
  WallContacts& w = model.wall_contacts;
  std::vector<bool> keep(w.size(), false);
  std::vector<std::uint32_t> index(w.size(), 0);
  for (std::size_t p = 0; p < w.size(); ++p) {
    const auto it = std::lower_bound(model.walls.begin(), model.walls.end(), w.wall_id[p],
                                     [](const Wall& wall, std::int64_t id) { return wall.id < id; });
    keep[p] = it != model.walls.end() && it->id == w.wall_id[p];
    if (keep[p]) index[p] = static_cast<std::uint32_t>(it - model.walls.begin());
  }
  w.wall = index;
  w.for_each_array([&](auto& v) {
    if (v.size() != keep.size()) { v.clear(); return; }
    std::size_t k = 0;
    for (std::size_t p = 0; p < v.size(); ++p)
      if (keep[p]) v[k++] = v[p];
    v.resize(k);
  });
  w.list_version = 0;   // a list nobody has indexed
}

std::size_t remove_balls(Model& model, const std::vector<bool>& remove) {
  Balls& b = model.balls;
  std::vector<std::int64_t> new_index(b.size(), -1);
  std::size_t kept = 0;
  for (std::size_t k = 0; k < b.size(); ++k)
    if (!remove[k]) new_index[k] = kept++;
  const std::size_t removed = b.size() - kept;
  if (removed == 0) return 0;
  model.critical_dt = 0;
  b.for_each_array([&](auto& v) {
    std::size_t w = 0;
    for (std::size_t k = 0; k < v.size(); ++k)
      if (!remove[k]) v[w++] = v[k];
    v.resize(w);
  });
  ContactTable& c = model.contacts;
  std::vector<bool> keep_pair(c.size());
  for (std::size_t p = 0; p < c.size(); ++p) keep_pair[p] = new_index[c.i[p]] >= 0 && new_index[c.j[p]] >= 0;
  c.for_each_pair_array([&](auto& v) {
    if (v.size() != keep_pair.size()) { v.clear(); return; }
    std::size_t w = 0;
    for (std::size_t k = 0; k < v.size(); ++k)
      if (keep_pair[k]) v[w++] = v[k];
    v.resize(w);
  });
  for (auto& v : c.i) v = static_cast<std::uint32_t>(new_index[v]);
  for (auto& v : c.j) v = static_cast<std::uint32_t>(new_index[v]);
  c.list_version = 0;   // a list nobody has indexed
  WallContacts& w = model.wall_contacts;
  std::vector<bool> keep_wall(w.size());
  for (std::size_t p = 0; p < w.size(); ++p) keep_wall[p] = w.ball[p] < new_index.size() && new_index[w.ball[p]] >= 0;
  w.for_each_array([&](auto& v) {
    if (v.size() != keep_wall.size()) { v.clear(); return; }
    std::size_t k = 0;
    for (std::size_t p = 0; p < v.size(); ++p)
      if (keep_wall[p]) v[k++] = v[p];
    v.resize(k);
  });
  for (auto& v : w.ball) v = static_cast<std::uint32_t>(new_index[v]);
  w.list_version = 0;
  for (auto& [name, ids] : model.groups)
    std::erase_if(ids, [&](std::int64_t id) { return find_ball(model, id) < 0; });
  return removed;
}

}  // namespace trubal
