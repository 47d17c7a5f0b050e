#include "io/history.hpp"
#include "support/comm.hpp"

#include <algorithm>
#include <limits>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <stdexcept>

#include <fmt/format.h>

#include "io/csv.hpp"
#include "physics/measure.hpp"
#include "physics/walls.hpp"

namespace trubal {

const std::vector<std::string_view>& History::item_names() {
  static const std::vector<std::string_view> names = {"stress", "strain", "volumetric", "ratio", "sratio", "axial",
                                                      "platen", "energy", "unbal", "contacts", "time", "wall"};
  return names;
}

static std::vector<std::string> columns_of(const std::string& item) {
  if (item == "stress") return {"s11", "s22", "s33", "s12", "s13", "s23"};
  if (item == "strain") return {"e11", "e22", "e33", "e12", "e13", "e23"};
  if (item == "volumetric") return {"evol"};
  if (item == "energy") return {"ke", "strain_energy", "friction_work", "damping_work", "boundary_work"};
  if (item == "contacts") return {"contacts", "sliding", "coordination"};
  if (item == "time") return {};   // cycle and time lead every row
  if (item.rfind("wall ", 0) == 0) {   // "wall <id>": its force, stress and place
    const std::string id = item.substr(5);
    std::vector<std::string> out;
    for (const char* what : {"fx", "fy", "fz", "stress", "pos"}) out.push_back(fmt::format("w{}_{}", id, what));
    return out;
  }
  return {item};
}

HistoryTable& History::add(std::vector<std::string> items, std::int64_t every, const std::string& file,
                           Range platen_range) {
  auto t = std::make_unique<HistoryTable>();
  t->columns = {"cycle", "time"};
  for (const auto& item : items)
    for (auto& c : columns_of(item)) t->columns.push_back(c);
  t->items = std::move(items);
  t->every = every;
  t->file = file;
  t->platen_range = std::move(platen_range);
  if (!file.empty() && comm::root()) {   // a distributed run's files are rank 0's to write
    t->out = std::make_unique<std::ofstream>(file, std::ios::trunc);
    if (!*t->out) throw std::runtime_error(fmt::format("cannot write the history file '{}'", file));
    errno = 0;
    for (std::size_t k = 0; k < t->columns.size(); ++k) *t->out << (k ? "," : "") << t->columns[k];
    *t->out << '\n' << std::flush;
    if (!*t->out)
      throw std::runtime_error(fmt::format("cannot write the history file '{}' ({})", file,
                                           errno ? std::strerror(errno) : "write failed"));
  }
  tables_.push_back(std::move(t));
  return *tables_.back();
}

std::vector<std::size_t> History::platen_balls(const Model& model, const HistoryTable& t) {
  const auto& ids = model.balls.id;   // sorted: index order is id order
  std::vector<std::size_t> out;
  for (std::int64_t id : t.platen_ids) {
    auto it = std::lower_bound(ids.begin(), ids.end(), id);
    if (it != ids.end() && *it == id) out.push_back(static_cast<std::size_t>(it - ids.begin()));
  }
  return out;
}

void History::record(HistoryTable& t, const Model& model, double volume) {
  std::vector<double> row = {static_cast<double>(model.cycle), model.time};
  Sym6 stress{};
  bool have_stress = false;
  auto get_stress = [&]() -> const Sym6& {
    if (!have_stress) stress = volume > 0 ? average_stress(model, volume) : Sym6{}, have_stress = true;
    return stress;
  };
  for (const auto& item : t.items) {
    if (item == "stress") {
      for (double s : get_stress()) row.push_back(s);
    } else if (item == "strain") {
      for (int a = 0; a < 6; ++a) row.push_back(model.space.strain[a]);
    } else if (item == "volumetric") {   // e11 + e22 + e33, compression positive
      row.push_back(model.space.strain[0] + model.space.strain[1] + model.space.strain[2]);
    } else if (item == "ratio" && !t.platen_ids.empty()) {
      // Rowe's R = sigma1 / sigma2 = F1 / (A sigma2).
      const double load = (t.membrane_area ? model.membrane.area : t.area) * t.pressure;
      row.push_back(load > 0 ? platens(model, platen_balls(model, t)).force / load
                             : std::numeric_limits<double>::quiet_NaN());
    } else if (item == "ratio") {
      const Sym6& s = get_stress();
      double lateral = 0.5 * (s[0] + s[1]);
      row.push_back(lateral != 0 ? s[2] / lateral : 0.0);
    } else if (item == "sratio") {
      // sigma1 / sigma3 of the assembly's own average stress, from the contact forces (Love: the sum
      // of f (x) l over the contacts; the volume cancels): s33 over the mean of s11 and s22.
      const Sym6 s = average_stress(model, 1.0);
      const double lateral = 0.5 * (s[0] + s[1]);
      row.push_back(lateral != 0 ? s[2] / lateral : std::numeric_limits<double>::quiet_NaN());
    } else if (item == "axial" && !t.platen_ids.empty()) {
      // eps1 = 2 delta / dh: the platens' approach over their first distance apart.
      const Platens p = platens(model, platen_balls(model, t));
      row.push_back(t.platen_gap0 > 0 && p.two ? (t.platen_gap0 - p.gap) / t.platen_gap0
                                               : std::numeric_limits<double>::quiet_NaN());
    } else if (item == "axial") {
      row.push_back(model.space.strain[2]);
    } else if (item == "platen") {
      row.push_back(reaction_force(model, t.platen_ids.empty() ? select(model, t.platen_range)
                                                               : platen_balls(model, t))[2]);
    } else if (item == "energy") {
      EnergyReport e = energy(model);
      for (double v : {e.kinetic_translation + e.kinetic_rotation, e.strain, e.friction_work, e.damping_work,
                       e.boundary_work})
        row.push_back(v);
    } else if (item.rfind("wall ", 0) == 0) {
      const Wall* it = find_wall(model, std::stoll(item.substr(5)));
      if (!it) {   // deleted since: the row says so rather than stopping
        for (int k = 0; k < 5; ++k) row.push_back(std::numeric_limits<double>::quiet_NaN());
      } else {
        row.push_back(it->force[0]); row.push_back(it->force[1]); row.push_back(it->force[2]);
        row.push_back(wall_servo_area(model, *it) > 0 ? wall_stress(model, *it) : std::numeric_limits<double>::quiet_NaN());
        row.push_back(wall_position(*it));
      }
    } else if (item == "unbal") {
      row.push_back(unbalanced_force(model).mean_ratio);
    } else if (item == "contacts") {
      row.push_back(static_cast<double>(contact_count(model)));
      row.push_back(sliding_fraction(model));
      row.push_back(coordination_number(model));
    }
  }
  if (t.out) {
    errno = 0;
    for (std::size_t k = 0; k < row.size(); ++k) *t.out << (k ? "," : "") << csv_real(row[k]);
    *t.out << '\n' << std::flush;
    if (!*t.out)
      throw std::runtime_error(fmt::format("cannot write the history file '{}' ({}): the rows from cycle {} on are "
                                           "not in it", t.file, errno ? std::strerror(errno) : "write failed",
                                           model.cycle));
  }
  t.rows.push_back(std::move(row));
  ++t.recorded;
  // A file holds every row: keep a window of the last ones (dropped a window at a time, so that a
  // row is moved once per kWindow records).
  if (!t.file.empty() && t.rows.size() >= 2 * HistoryTable::kWindow)
    t.rows.erase(t.rows.begin(), t.rows.begin() + static_cast<std::ptrdiff_t>(t.rows.size() - HistoryTable::kWindow));
}

void History::sample(const Model& model, double volume) {
  for (auto& t : tables_)
    if (model.cycle % t->every == 0) record(*t, model, volume);
}

void History::sample_all(const Model& model, double volume) {
  for (auto& t : tables_) record(*t, model, volume);
}

void History::clear() { tables_.clear(); }

std::pair<const HistoryTable*, std::size_t> History::find_column(const std::string& name) const {
  for (const auto& t : tables_)
    for (std::size_t k = 0; k < t->columns.size(); ++k)
      if (t->columns[k] == name) return {t.get(), k};
  return {nullptr, 0};
}

std::unique_ptr<HistoryTable> read_history_csv(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(fmt::format("cannot open the history file '{}'", path));
  auto table = std::make_unique<HistoryTable>();
  table->file = path;
  auto split = [](const std::string& line) {
    std::vector<std::string> cells;
    std::size_t start = 0;
    for (;;) {
      auto comma = line.find(',', start);
      cells.push_back(line.substr(start, comma == std::string::npos ? std::string::npos : comma - start));
      if (comma == std::string::npos) return cells;
      start = comma + 1;
    }
  };
  std::string line;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty()) continue;
    auto cells = split(line);
    if (table->columns.empty()) {
      table->columns = std::move(cells);
      continue;
    }
    if (cells.size() != table->columns.size())
      throw std::runtime_error(fmt::format("{}:{}: {} values where the header has {} columns", path, line_no,
                                           cells.size(), table->columns.size()));
    std::vector<double> row;
    for (const auto& c : cells) {
      char* end = nullptr;
      double v = std::strtod(c.c_str(), &end);
      if (c.empty() || end != c.c_str() + c.size())
        throw std::runtime_error(fmt::format("{}:{}: '{}' is not a number", path, line_no, c));
      row.push_back(v);
    }
    table->rows.push_back(std::move(row));
  }
  if (table->columns.empty()) throw std::runtime_error(fmt::format("'{}' is empty: no header row", path));
  table->recorded = table->rows.size();
  return table;
}

}  // namespace trubal
