#include "model/bond_table.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <numeric>
#include <utility>

#include "model/edit.hpp"
#include "model/periodic_cell.hpp"

namespace trubal {

std::uint64_t next_bonds_edition() {
  static std::atomic<std::uint64_t> last{0};
  return ++last;
}

namespace {

// Keeps the rows whose flag is set, in order.
void keep_rows(Bonds& bonds, const std::vector<bool>& keep) {
  bonds.for_each_array([&](auto& v) {
    std::size_t w = 0;
    for (std::size_t k = 0; k < v.size() && k < keep.size(); ++k)
      if (keep[k]) v[w++] = v[k];
    v.resize(w);
  });
  bonds.changed();
}

}  // namespace

std::vector<std::size_t> bond_rows_by_id(const Bonds& bonds) {
  const std::size_t n = bonds.size();
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), std::size_t{0});
  auto before = [&](std::size_t a, std::size_t b) {
    return bonds.id_i[a] != bonds.id_i[b] ? bonds.id_i[a] < bonds.id_i[b] : bonds.id_j[a] < bonds.id_j[b];
  };
  if (!std::is_sorted(order.begin(), order.end(), before)) std::stable_sort(order.begin(), order.end(), before);
  return order;
}

void sort_bonds(Bonds& bonds) {
  const std::size_t n = bonds.size();
  const std::vector<std::size_t> order = bond_rows_by_id(bonds);
  bonds.for_each_array([&](auto& v) {
    if (v.size() != n) return;
    std::decay_t<decltype(v)> out(n);
    for (std::size_t k = 0; k < n; ++k) out[k] = v[order[k]];
    v.swap(out);
  });
  bonds.changed();
}

std::size_t add_bonds(Model& model, const std::vector<std::size_t>& selected, const BondSpec& spec) {
  const Balls& b = model.balls;
  if (selected.size() < 2) return 0;
  const CellFrame frame = cell_frame(model.space);
  const bool periodic = model.space.periodic;
  double rmax = 0;
  for (std::size_t k : selected) rmax = std::max(rmax, b.rad[k]);
  // A sweep along x: the selected balls by x, each against those ahead of it within reach (across
  // the x faces of a periodic cell too, the tilts widening the window).
  const double reach = 2 * rmax + std::max(spec.gap, 0.0);
  const bool wrap_x = model.space.wraps(0);
  const double lx = frame.lx, slack = periodic ? std::abs(frame.xy) + std::abs(frame.xz) : 0.0;
  std::vector<std::size_t> order(selected);
  std::sort(order.begin(), order.end(), [&](std::size_t p, std::size_t q) { return b.x[p] != b.x[q] ? b.x[p] < b.x[q] : p < q; });
  std::vector<std::pair<std::int64_t, std::int64_t>> found;
  const std::size_t n = order.size();
  for (std::size_t a = 0; a < n; ++a) {
    const std::size_t i = order[a];
    for (std::size_t step = 1; step < n; ++step) {
      const std::size_t c = a + step;
      if (c >= n && !wrap_x) break;
      const std::size_t j = order[c % n];
      const double ahead = b.x[j] - b.x[i] + (c >= n ? lx : 0.0);
      if (ahead > reach + slack) break;
      std::int8_t ix, iy, iz;
      const auto [dx, dy, dz] = nearest_separation(frame, periodic, b, i, j, ix, iy, iz);
      const double gap = std::sqrt(dx * dx + dy * dy + dz * dz) - b.rad[i] - b.rad[j];
      if (!(gap <= spec.gap)) continue;
      const std::int64_t lo = std::min(b.id[i], b.id[j]), hi = std::max(b.id[i], b.id[j]);
      if (lo != hi) found.emplace_back(lo, hi);
    }
  }
  std::sort(found.begin(), found.end());
  found.erase(std::unique(found.begin(), found.end()), found.end());
  Bonds& t = model.bonds;
  std::vector<std::pair<std::int64_t, std::int64_t>> have(t.size());
  for (std::size_t k = 0; k < t.size(); ++k) have[k] = {t.id_i[k], t.id_j[k]};
  std::sort(have.begin(), have.end());
  std::size_t made = 0;
  for (const auto& [lo, hi] : found) {
    if (std::binary_search(have.begin(), have.end(), std::make_pair(lo, hi))) continue;
    const double ri = b.rad[static_cast<std::size_t>(find_ball(model, lo))];
    const double rj = b.rad[static_cast<std::size_t>(find_ball(model, hi))];
    t.id_i.push_back(lo); t.id_j.push_back(hi);
    t.kn.push_back(spec.kn); t.ks.push_back(spec.ks); t.tension.push_back(spec.tension);
    t.cohesion.push_back(spec.cohesion); t.tan_friction.push_back(spec.tan_friction);
    t.radius.push_back(spec.rmul * std::min(ri, rj)); t.mcf.push_back(spec.mcf);
    for (auto* v : {&t.fn, &t.fsx, &t.fsy, &t.fsz, &t.mt, &t.mbx, &t.mby, &t.mbz}) v->push_back(0.0);
    t.fate.push_back(0);
    ++made;
  }
  if (made) sort_bonds(t);
  return made;
}

std::size_t delete_bonds(Model& model, const std::vector<std::size_t>& selected) {
  std::vector<std::int64_t> ids;
  ids.reserve(selected.size());
  for (std::size_t k : selected) ids.push_back(model.balls.id[k]);
  std::sort(ids.begin(), ids.end());
  Bonds& t = model.bonds;
  std::vector<bool> keep(t.size());
  std::size_t removed = 0;
  for (std::size_t k = 0; k < t.size(); ++k) {
    keep[k] = !std::binary_search(ids.begin(), ids.end(), t.id_i[k]) && !std::binary_search(ids.begin(), ids.end(), t.id_j[k]);
    removed += !keep[k];
  }
  if (removed) keep_rows(t, keep);
  return removed;
}

void drop_bonds_of_missing_balls(Model& model) {
  Bonds& t = model.bonds;
  std::vector<bool> keep(t.size());
  bool any = false;
  for (std::size_t k = 0; k < t.size(); ++k) {
    keep[k] = find_ball(model, t.id_i[k]) >= 0 && find_ball(model, t.id_j[k]) >= 0;
    any = any || !keep[k];
  }
  if (any) keep_rows(t, keep);
}

void renumber_bonds(Bonds& t, const std::function<std::int64_t(std::int64_t)>& map) {
  for (std::size_t k = 0; k < t.size(); ++k) {
    std::int64_t i = map(t.id_i[k]), j = map(t.id_j[k]);
    if (i > j) {
      std::swap(i, j);
      t.for_each_swapped([&](std::vector<double>& v) { v[k] = -v[k]; });
    }
    t.id_i[k] = i;
    t.id_j[k] = j;
  }
  sort_bonds(t);
}

std::string bond_table_problem(const Model& model) {
  Bonds& t = const_cast<Bonds&>(model.bonds);
  const std::size_t n = t.size();
  bool lengths = true;
  t.for_each_array([&](const auto& v) { lengths = lengths && v.size() == n; });
  if (!lengths) return "the bond table's arrays differ in length";
  const std::vector<std::size_t> by_id = bond_rows_by_id(t);
  for (std::size_t a = 1; a < n; ++a)
    if (t.id_i[by_id[a - 1]] == t.id_i[by_id[a]] && t.id_j[by_id[a - 1]] == t.id_j[by_id[a]]) return "a bond is given twice";
  for (std::size_t k = 0; k < n; ++k) {
    if (!(t.id_i[k] < t.id_j[k])) return "a bond's first ball id is not below its second";
    if (find_ball(model, t.id_i[k]) < 0 || find_ball(model, t.id_j[k]) < 0) return "a bond names a ball that is not there";
    if (!(t.kn[k] > 0) || !(t.ks[k] > 0) || !(t.radius[k] > 0) || !std::isfinite(t.kn[k]) || !std::isfinite(t.ks[k]) ||
        !std::isfinite(t.radius[k]))
      return "a bond's stiffness or radius is not a positive number";
    for (const auto* v : {&t.tension, &t.cohesion, &t.tan_friction, &t.mcf, &t.fn, &t.fsx, &t.fsy, &t.fsz, &t.mt,
                          &t.mbx, &t.mby, &t.mbz})
      if (!std::isfinite((*v)[k])) return "a bond's strength, force or moment is not a finite number";
    if (t.fate[k] > 2) return "a bond's state is not intact, broken in tension or broken in shear";
  }
  return "";
}

}  // namespace trubal
