#include "model/edit.hpp"

#include "model/bond_table.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <string>

#include <fmt/format.h>

namespace trubal {

void Balls::index_ids() {
  by_id.resize(size());
  std::iota(by_id.begin(), by_id.end(), std::uint32_t{0});
  std::sort(by_id.begin(), by_id.end(), [&](std::uint32_t p, std::uint32_t q) { return id[p] < id[q]; });
}

bool Balls::ids_indexed() const {
  if (by_id.size() != size()) return false;
  std::vector<bool> seen(size(), false);
  for (std::size_t r = 0; r < by_id.size(); ++r) {
    const std::uint32_t k = by_id[r];
    if (k >= size() || seen[k] || (r > 0 && !(id[by_id[r - 1]] < id[k]))) return false;
    seen[k] = true;
  }
  return true;
}

namespace {
// Where `id` stands or would stand in by_id.
std::vector<std::uint32_t>::const_iterator id_slot(const Balls& b, std::int64_t id) {
  return std::lower_bound(b.by_id.begin(), b.by_id.end(), id, [&](std::uint32_t k, std::int64_t v) { return b.id[k] < v; });
}
}  // namespace

std::int64_t find_ball(const Model& model, std::int64_t id) {
  const Balls& b = model.balls;
  const auto it = id_slot(b, id);
  return (it != b.by_id.end() && b.id[*it] == id) ? static_cast<std::int64_t>(*it) : -1;
}

std::string ball_radius_problem(const Space& space, double rad) {
  if (!(rad > 0)) return "the radius must be positive";
  const auto L = space.length();
  const double diagonal = std::hypot(L[0], L[1], L[2]);
  if (!(rad <= diagonal))
    return fmt::format("the radius must be at most the START space's diagonal, {:.6g} (a larger ball would cover all "
                       "of it)", diagonal);
  return "";
}

std::size_t add_ball(Model& model, std::int64_t id, int type, double x, double y, double z, double rad) {
  Balls& b = model.balls;
  if (!(rad > 0)) throw std::invalid_argument("ball radius must be positive");
  if (id <= 0) {
    if (!b.by_id.empty() && b.id[b.by_id.back()] == std::numeric_limits<std::int64_t>::max())
      throw std::invalid_argument("no ball id is left after " + std::to_string(b.id[b.by_id.back()]) +
                                  ": give the new ball its id (BALL ... id n)");
    id = b.by_id.empty() ? 1 : b.id[b.by_id.back()] + 1;
  }
  // The new ball goes last in memory; by_id takes it at its id's place (at its end for a new
  // largest id, as BALL and GEN give).
  const auto at = id_slot(b, id);
  if (at != b.by_id.end() && b.id[*at] == id) throw std::invalid_argument("ball id " + std::to_string(id) + " is taken");
  if (b.size() >= std::numeric_limits<std::uint32_t>::max())
    throw std::invalid_argument("a model holds at most " + std::to_string(std::numeric_limits<std::uint32_t>::max()) +
                                " balls");
  const std::size_t pos = b.size();
  b.by_id.insert(at, static_cast<std::uint32_t>(pos));
  model.critical_dt = 0;   // the new ball may be stiffer or lighter than any before
  model.order.pending = true;   // put in space order at the next step
  b.for_each_array([&](auto& v) { v.emplace_back(); });
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
  b.index_ids();
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
  drop_bonds_of_missing_balls(model);
  return removed;
}

namespace {

// Spreads the low 21 bits of v to every third bit (bit b to bit 3b): one axis of a Morton code.
std::uint64_t spread3(std::uint64_t v) {
  v &= 0x1fffff;
  v = (v | v << 32) & 0x1f00000000ffffull;
  v = (v | v << 16) & 0x1f0000ff0000ffull;
  v = (v | v << 8) & 0x100f00f00f00f00full;
  v = (v | v << 4) & 0x10c30c30c30c30c3ull;
  v = (v | v << 2) & 0x1249249249249249ull;
  return v;
}

}  // namespace

std::array<double, 3> space_corner(const Balls& b, const std::vector<std::uint32_t>* pick) {
  std::array<double, 3> lo{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
                           std::numeric_limits<double>::infinity()};
  const std::vector<double>* axes[3] = {&b.x, &b.y, &b.z};
  const std::size_t n = pick ? pick->size() : b.size();
  for (int a = 0; a < 3; ++a)
    for (std::size_t q = 0; q < n; ++q) {
      const double v = (*axes[a])[pick ? (*pick)[q] : q];
      if (std::isfinite(v)) lo[a] = std::min(lo[a], v);
    }
  return lo;
}

std::uint64_t space_key(double x, double y, double z, const std::array<double, 3>& lo, double cell) {
  constexpr double kTop = 0x1fffff;   // 21 bits an axis
  const double at[3] = {x, y, z};
  std::uint64_t code = 0;
  for (int a = 0; a < 3; ++a) {
    if (!std::isfinite(at[a])) return ~std::uint64_t{0};
    const double c = std::min(std::floor((at[a] - lo[a]) / cell), kTop);
    code |= spread3(static_cast<std::uint64_t>(c)) << a;
  }
  return code;
}

namespace {

// The order of the balls in space: Morton order of cells `cell` wide from the lowest centre, ties
// (one cell) by id, so that the order is a function of the centres and ids alone; a ball with a
// centre not finite goes last.
std::vector<std::size_t> space_order(const Balls& b, double cell) {
  const std::size_t n = b.size();
  const std::array<double, 3> lo = space_corner(b);
  std::vector<std::uint64_t> key(n);
  for (std::size_t k = 0; k < n; ++k) key[k] = space_key(b.x[k], b.y[k], b.z[k], lo, cell);
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::sort(order.begin(), order.end(),
            [&](std::size_t p, std::size_t q) { return key[p] != key[q] ? key[p] < key[q] : b.id[p] < b.id[q]; });
  return order;
}

}  // namespace

std::int64_t Renumbering::map(std::int64_t old) const {
  const auto it = std::lower_bound(old_ids.begin(), old_ids.end(), old);
  return it != old_ids.end() && *it == old ? new_ids[it - old_ids.begin()] : 0;
}

void reorder_balls(Model& model, const std::vector<std::size_t>& order) {
  Balls& b = model.balls;
  const std::size_t n = b.size();
  std::vector<std::uint32_t> new_index(n);
  for (std::size_t k = 0; k < n; ++k) new_index[order[k]] = static_cast<std::uint32_t>(k);
  permute_arrays([&](auto&& f) { b.for_each_array(f); }, order);
  b.index_ids();

  // The pair list: each pair in the new indices, turned round where its balls changed order (the
  // history as each part declares (OnSwap: the shear force on j changes sign), the normal from i to
  // j, the force on j and j's image change sign; the moment term n x shear force does not), then
  // sorted as a list is (pair_before's order).
  ContactTable& c = model.contacts;
  const bool results = c.results_kept();
  for (std::size_t p = 0; p < c.size(); ++p) {
    std::uint32_t i = new_index[c.i[p]], j = new_index[c.j[p]];
    if (i > j) {
      std::swap(i, j);
      for (auto* v : {&c.image_x, &c.image_y, &c.image_z}) (*v)[p] = static_cast<std::int8_t>(-(*v)[p]);
      c.for_each_history([&](auto& v, const HistoryPart& part) {
        if (part.swap == OnSwap::Negate) v[p] = -v[p];
      });
      if (results)
        for (auto* v : {&c.nx, &c.ny, &c.nz, &c.fx, &c.fy, &c.fz}) (*v)[p] = -(*v)[p];
    }
    c.i[p] = i;
    c.j[p] = j;
  }
  std::vector<std::size_t> pairs(c.size());
  std::iota(pairs.begin(), pairs.end(), std::size_t{0});
  std::stable_sort(pairs.begin(), pairs.end(), [&](std::size_t p, std::size_t q) { return pair_before(c, p, c, q); });
  permute_arrays([&](auto&& f) { c.for_each_pair_array(f); }, pairs);
  c.list_version = 0;   // a list nobody has indexed

  WallContacts& w = model.wall_contacts;
  for (std::size_t p = 0; p < w.size(); ++p) w.ball[p] = new_index[w.ball[p]];
  std::vector<std::size_t> walls(w.size());
  std::iota(walls.begin(), walls.end(), std::size_t{0});
  std::stable_sort(walls.begin(), walls.end(), [&](std::size_t p, std::size_t q) {
    return w.ball[p] != w.ball[q] ? w.ball[p] < w.ball[q] : w.wall[p] < w.wall[q];
  });
  permute_arrays([&](auto&& f) { w.for_each_array(f); }, walls);
  w.list_version = 0;
}

double order_cell(const Balls& b) {
  const double diameter = 2 * b.max_radius();
  return std::isfinite(diameter) && diameter > 0 ? diameter : 1.0;
}

std::vector<std::size_t> sort_in_space_order(Model& model) {
  model.order.pending = false;
  std::vector<std::size_t> order = space_order(model.balls, order_cell(model.balls));
  bool moved = false;
  for (std::size_t k = 0; k < order.size() && !moved; ++k) moved = order[k] != k;
  if (!moved) return {};
  reorder_balls(model, order);
  return order;
}

bool sort_in_space(Model& model) { return !sort_in_space_order(model).empty(); }

Renumbering renumber_balls(Model& model, RenumberOrder how) {
  Balls& b = model.balls;
  const std::size_t n = b.size();
  Renumbering r;
  if (how == RenumberOrder::Space) {
    r.cell = order_cell(b);
    reorder_balls(model, space_order(b, r.cell));
  }
  // Space: the ids follow the new order in memory; present: the order of the ids.
  r.old_ids.resize(n);
  r.new_ids.resize(n);
  for (std::size_t rank = 0; rank < n; ++rank) {
    const std::uint32_t k = b.by_id[rank];
    r.old_ids[rank] = b.id[k];
    r.new_ids[rank] = static_cast<std::int64_t>(how == RenumberOrder::Space ? k : rank) + 1;
  }
  for (std::size_t rank = 0; rank < n; ++rank) b.id[b.by_id[rank]] = r.new_ids[rank];
  b.index_ids();
  WallContacts& w = model.wall_contacts;
  for (std::size_t p = 0; p < w.size(); ++p) w.ball_id[p] = b.id[w.ball[p]];
  for (auto& [name, ids] : model.groups) {
    for (auto& id : ids) id = r.map(id);
    std::sort(ids.begin(), ids.end());
  }
  for (auto& id : model.membrane.ids) id = r.map(id);
  renumber_bonds(model.bonds, [&](std::int64_t id) { return r.map(id); });
  return r;
}

}  // namespace trubal
