#include "io/history.hpp"

#include "physics/bond.hpp"
#include "physics/bridge.hpp"
#include "support/comm.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <fstream>
#include <optional>
#include <filesystem>
#include <sstream>
#include <stdexcept>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "io/atomic_file.hpp"
#include "io/history_files.hpp"

#include "io/csv.hpp"
#include "model/edit.hpp"
#include "physics/measure.hpp"
#include "physics/measure_sphere.hpp"
#include "physics/sample.hpp"
#include "physics/walls.hpp"

namespace trubal {

using namespace history_files;

const std::vector<std::string_view>& History::item_names() {
  static const std::vector<std::string_view> names = {"stress", "pq", "strain", "volumetric", "ratio", "sratio", "axial",
                                                      "platen", "energy", "rolling", "unbal", "contacts", "time", "wall",
                                                      "porosity", "measure", "ball", "sample", "bridges", "bonds"};
  return names;
}

const std::vector<std::string_view>& History::ball_quantities() {
  static const std::vector<std::string_view> names = {"x",  "y",  "z",  "vx", "vy", "vz",
                                                      "wx", "wy", "wz", "fx", "fy", "fz"};
  return names;
}

namespace {

// A ball item's id and quantities ("ball <id> <q>..."), as words.
struct BallItem {
  std::int64_t id = 0;
  std::vector<std::string> quantities;
};

BallItem ball_item(const std::string& item) {
  std::istringstream in(item.size() > 5 ? item.substr(5) : std::string());
  BallItem b;
  in >> b.id;
  for (std::string q; in >> q;) b.quantities.push_back(q);
  return b;
}

// The array of Balls a quantity names (one of History::ball_quantities).
const std::vector<double>& ball_array(const Balls& b, const std::string& quantity) {
  const std::vector<double>* arrays[] = {&b.x, &b.y, &b.z, &b.vx, &b.vy, &b.vz, &b.wx, &b.wy, &b.wz, &b.fx, &b.fy, &b.fz};
  const auto& names = History::ball_quantities();
  return *arrays[std::find(names.begin(), names.end(), quantity) - names.begin()];
}

}  // namespace

static std::vector<std::string> columns_of(const std::string& item) {
  if (item == "stress") return {"s11", "s22", "s33", "s12", "s13", "s23"};
  if (item == "pq") return {"p", "q"};
  if (item == "sample") return {"ea", "ev", "sig1", "sig3", "q", "p"};
  if (item == "strain") return {"e11", "e22", "e33", "e12", "e13", "e23"};
  if (item == "volumetric") return {"evol"};
  if (item == "energy") return {"ke", "strain_energy", "friction_work", "damping_work", "boundary_work", "potential"};
  if (item == "rolling") return {"rolling_work"};
  if (item == "bridges") return {"bridges", "capillary_work"};
  if (item == "bonds") return {"bonds_intact", "bonds_broken", "broken_tension", "broken_shear"};
  if (item == "porosity") return {"porosity", "void_ratio"};
  if (item == "contacts") return {"contacts", "sliding", "coordination"};
  if (item == "time") return {};   // cycle and time lead every row
  if (item.rfind("wall ", 0) == 0) {   // "wall <id>": its force, stress and place
    const std::string id = item.substr(5);
    std::vector<std::string> out;
    for (const char* what : {"fx", "fy", "fz", "stress", "pos"}) out.push_back(fmt::format("w{}_{}", id, what));
    return out;
  }
  if (item.rfind("ball ", 0) == 0) {   // "ball <id> <q>...": one ball's quantities, b<id>_<q>
    const BallItem b = ball_item(item);
    std::vector<std::string> out;
    for (const auto& q : b.quantities) out.push_back(fmt::format("b{}_{}", b.id, q));
    return out;
  }
  if (item.rfind("measure ", 0) == 0) {   // "measure <id> x y z r": a measurement sphere
    const std::string id = item.substr(8, item.find(' ', 8) - 8);
    std::vector<std::string> out;
    for (const char* what : {"s11", "s22", "s33", "s12", "s13", "s23", "porosity", "void_ratio", "coordination",
                             "sliding", "f11", "f22", "f33", "f12", "f13", "f23"})
      out.push_back(fmt::format("m{}_{}", id, what));
    return out;
  }
  return {item};
}

std::string measure_item(std::int64_t id, const MeasureSphere& s) {
  return fmt::format("measure {} {} {} {} {}", id, csv_real(s.centre[0]), csv_real(s.centre[1]), csv_real(s.centre[2]),
                     csv_real(s.radius));
}

MeasureSphere measure_item_sphere(const std::string& item) {
  std::istringstream in(item.substr(8));
  std::int64_t id = 0;
  MeasureSphere s;
  in >> id >> s.centre[0] >> s.centre[1] >> s.centre[2] >> s.radius;
  return s;
}

HistoryAdded History::add(std::vector<std::string> items, std::int64_t every, const std::string& file,
                          Range platen_range, HistoryFileMode mode, std::int64_t cycle) {
  auto t = std::make_unique<HistoryTable>();
  t->columns = {"cycle", "time"};
  for (const auto& item : items)
    for (auto& c : columns_of(item)) t->columns.push_back(c);
  t->items = std::move(items);
  t->every = every;
  t->file = file;
  t->platen_range = std::move(platen_range);
  if (!file.empty())
    for (auto& live : tables_) {
      if (live->file != file) continue;
      // The same history again (a deck that repeats its HIST after RESTART resumed it): it goes on.
      if (live->columns == t->columns && live->every == every && mode != HistoryFileMode::New)
        return {*live, true, fmt::format("{}: the history already recording to it goes on", file)};
      throw std::runtime_error(fmt::format("'{}' is the file of a history already recording ({} every {}): give "
                                           "another file, or HIST reset first",
                                           file, fmt::join(live->columns, ","), live->every));
    }
  std::string note;
  // A distributed run's files are rank 0's to write, and its failure is every rank's: a table kept
  // on the others alone would make their CYCLEs record (and wait for each other) on steps rank 0
  // does not (the shell goes on after an error).
  if (!file.empty()) comm::together([&] {
    if (!comm::root()) return;
    if (mode == HistoryFileMode::Append) {
      note = append_to_file(*t, cycle, false);
    } else {
      if (mode == HistoryFileMode::Default) {
        std::optional<FileRows> old;
        try { old = existing(file); } catch (const std::runtime_error&) {}
        if (old && old->kept > 0)
          note = fmt::format("{}: replaced its {} rows{} of an earlier run (HIST ... append keeps them; `new` replaces them without this note)", file,
                             old->kept, old->kept_cycles());
      }
      // Written in place, row by row: a link would be followed (its target replaced), a FIFO
      // with no reader would block for ever. A device (/dev/null, /dev/full) is written to.
      check_replaceable(file, true);
      t->out = std::make_unique<std::ofstream>(file, std::ios::trunc);
      if (!*t->out)
        throw std::runtime_error(fmt::format("cannot write the history file '{}' ({})", file, std::strerror(errno)));
      write_header(*t->out, *t);
    }
  }, "opening the history file");
  tables_.push_back(std::move(t));
  return {*tables_.back(), false, note};
}


bool History::valid_table(const HistoryTable& t) {
  std::vector<std::string> columns = {"cycle", "time"};
  const auto& names = item_names();
  for (const auto& item : t.items) {
    std::istringstream in(item);
    std::string word;
    in >> word;
    if (std::find(names.begin(), names.end(), word) == names.end()) return false;
    if (word == "wall" || word == "measure") {
      std::int64_t id = 0;
      if (!(in >> id) || id < 1) return false;
      if (word == "measure") {
        const MeasureSphere s = measure_item_sphere(item);
        if (!(s.radius > 0) || !std::isfinite(s.radius)) return false;
      }
    } else if (word == "ball") {
      const BallItem b = ball_item(item);
      const auto& quantities = ball_quantities();
      if (b.id < 1 || b.quantities.empty()) return false;
      for (std::size_t k = 0; k < b.quantities.size(); ++k)
        if (std::find(quantities.begin(), quantities.end(), b.quantities[k]) == quantities.end() ||
            std::find(b.quantities.begin(), b.quantities.begin() + static_cast<std::ptrdiff_t>(k), b.quantities[k]) !=
                b.quantities.begin() + static_cast<std::ptrdiff_t>(k))
          return false;
    } else if (item != word) {
      return false;
    }
    for (auto& c : columns_of(item)) columns.push_back(c);
  }
  return columns == t.columns;
}

std::vector<std::size_t> History::platen_balls(const Model& model, const HistoryTable& t) {
  std::vector<std::size_t> out;
  for (std::int64_t id : t.platen_ids)
    if (const std::int64_t k = find_ball(model, id); k >= 0) out.push_back(static_cast<std::size_t>(k));
  std::sort(out.begin(), out.end());   // (the model's order: the sums over them in that order)
  return out;
}

void History::record(HistoryTable& t, const Model& model, double volume) {
  std::vector<double> row = row_of(t, model, volume, nullptr);
  write_row(t, row, model.cycle);
  keep_row(t, std::move(row));
}

bool History::recorded_on_parts() const {
  for (const auto& t : tables_)
    for (const auto& item : t->items) {
      const bool platens = !t->platen_ids.empty();
      const bool from_sums = item == "stress" || item == "pq" || item == "sratio" || item == "unbal" || item == "contacts" ||
                             item == "bridges" || item == "bonds";
      const bool light = item == "strain" || item == "volumetric" || item == "energy" || item == "rolling" ||
                         item == "time" || item == "porosity" || item == "sample" || item.rfind("wall ", 0) == 0 ||
                         item.rfind("ball ", 0) == 0 ||   // (a ball's: from its owner, HistorySums::ball)
                         item.rfind("measure ", 0) == 0;  // (a sphere's: its sums merged, HistorySums::sphere)
      // (ratio, axial and platen of platen balls: their rows from the parts, HistorySums::platens;
      // `platen` of every ball, with no range, reads the whole model.)
      const bool platen_rows = (item == "ratio" || item == "axial" || item == "platen") && platens;
      if (!(from_sums || light || platen_rows || ((item == "ratio" || item == "axial") && !platens))) return false;
    }
  return true;
}

void History::sample_on_parts(const Model& model, double volume, const HistorySums& sums) {
  for (auto& t : tables_) {
    if (model.cycle % t->every != 0) continue;
    std::vector<double> row = row_of(*t, model, volume, &sums);   // (every rank: the sums are merged)
    comm::on_root([&] { write_row(*t, row, model.cycle); }, "writing a history row");
    keep_row(*t, std::move(row));
  }
}

std::vector<double> History::row_of(const HistoryTable& t, const Model& model, double volume, const HistorySums* from) {
  std::vector<double> row = {static_cast<double>(model.cycle), model.time};
  std::optional<StressSums> stress_sums_now;   // (stress, pq, ratio and sratio: one pass)
  auto get_stress_sums = [&]() -> const StressSums& {
    if (!stress_sums_now) stress_sums_now = from ? from->stress() : stress_sums(model);
    return *stress_sums_now;
  };
  Sym6 stress{};
  bool have_stress = false;
  auto get_stress = [&]() -> const Sym6& {
    if (!have_stress) stress = volume > 0 ? get_stress_sums().over(volume) : Sym6{}, have_stress = true;
    return stress;
  };
  std::optional<PlatenBalls> platen_rows;   // (ratio, axial and platen: one reading)
  auto get_platens = [&]() -> const PlatenBalls& {
    if (!platen_rows)
      platen_rows = from && from->platens ? from->platens(t.platen_ids) : platen_balls_of(model, platen_balls(model, t));
    return *platen_rows;
  };
  std::optional<ContactSums> sums;   // (unbal and contacts: one pass)
  auto get_sums = [&]() -> const ContactSums& {
    if (!sums) sums = from ? from->contacts() : contact_sums(model);
    return *sums;
  };
  for (const auto& item : t.items) {
    if (item == "stress") {
      for (double s : get_stress()) row.push_back(s);
    } else if (item == "pq") {   // mean stress and deviator, z axial (a triaxial test's p and q)
      const TriaxialStress t = triaxial_stress(get_stress());
      row.push_back(t.p);
      row.push_back(t.q);
    } else if (item == "sample") {   // the sample between walls (physics/sample.hpp), NaN without one
      const SampleMeasures m = sample_measures(model);
      for (double v : {m.axial, m.volumetric, m.sigma1, m.sigma3, m.q, m.p}) row.push_back(v);
    } else if (item == "strain") {
      for (int a = 0; a < 6; ++a) row.push_back(model.space.strain[a]);
    } else if (item == "volumetric") {   // 1 - V / V0 since START or STRAIN reset, compression positive
      row.push_back(volumetric_strain(model));
    } else if (item == "ratio" && !t.platen_ids.empty()) {
      // Rowe's R = sigma1 / sigma2 = F1 / (A sigma2).
      const double load = (t.membrane_area ? model.membrane.area : t.area) * t.pressure;
      row.push_back(load > 0 ? platens(get_platens()).force / load
                             : std::numeric_limits<double>::quiet_NaN());
    } else if (item == "ratio") {
      const Sym6& s = get_stress();
      double lateral = 0.5 * (s[0] + s[1]);
      row.push_back(lateral != 0 ? s[2] / lateral : 0.0);
    } else if (item == "sratio") {
      // sigma1 / sigma3 of the assembly's own average stress, from the contact forces (Love: the sum
      // of f (x) l over the contacts; the volume cancels): s33 over the mean of s11 and s22.
      const Sym6 s = get_stress_sums().over(1.0);
      const double lateral = 0.5 * (s[0] + s[1]);
      row.push_back(lateral != 0 ? s[2] / lateral : std::numeric_limits<double>::quiet_NaN());
    } else if (item == "axial" && !t.platen_ids.empty()) {
      // eps1 = 2 delta / dh: the platens' approach over their first distance apart.
      const Platens p = platens(get_platens());
      row.push_back(t.platen_gap0 > 0 && p.two ? (t.platen_gap0 - p.gap) / t.platen_gap0
                                               : std::numeric_limits<double>::quiet_NaN());
    } else if (item == "axial") {
      row.push_back(model.space.strain[2]);
    } else if (item == "platen") {
      row.push_back((t.platen_ids.empty() ? reaction_force(model, select(model, t.platen_range))
                                          : reaction_force(get_platens()))[2]);
    } else if (item == "energy") {
      EnergyReport e = energy(model);
      for (double v : {e.kinetic_translation + e.kinetic_rotation, e.strain, e.friction_work, e.damping_work,
                       e.boundary_work, e.potential})
        row.push_back(v);
    } else if (item == "rolling") {
      row.push_back(energy(model).rolling_work);
    } else if (item == "bridges") {
      row.push_back(static_cast<double>(from && from->bridges ? from->bridges()
                                                               : count_bridges(model.contacts) + count_bridges(model.wall_contacts)));
      row.push_back(energy(model).capillary_work);
    } else if (item == "bonds") {
      const BondCounts n = from && from->bonds ? from->bonds() : count_bonds(model.bonds);
      for (std::size_t v : {n.intact, n.broken(), n.tension, n.shear}) row.push_back(static_cast<double>(v));
    } else if (item == "porosity") {
      const Porosity p = space_porosity(model, volume);
      row.push_back(p.porosity);
      row.push_back(p.void_ratio);
    } else if (item.rfind("measure ", 0) == 0) {
      try {
        const MeasureSphere sphere = measure_item_sphere(item);
        const SphereMeasurement m = from && from->sphere ? from->sphere(sphere) : measure_sphere(model, sphere);
        for (double v : m.stress) row.push_back(v);
        for (double v : {m.porosity, m.void_ratio, m.coordination, m.sliding}) row.push_back(v);
        for (double v : m.fabric) row.push_back(v);
      } catch (const std::runtime_error&) {
        // A cell that has shrunk until it cannot hold the sphere: the row says so rather than stopping.
        for (int k = 0; k < 16; ++k) row.push_back(std::numeric_limits<double>::quiet_NaN());
      }
    } else if (item.rfind("ball ", 0) == 0) {
      const BallItem b = ball_item(item);
      auto read = [&](const Balls& balls, std::size_t k) {
        std::vector<double> values;
        for (const auto& q : b.quantities) values.push_back(ball_array(balls, q)[k]);
        return values;
      };
      std::vector<double> values;
      if (from && from->ball) {
        values = from->ball(b.id, b.quantities.size(), read);
      } else if (const std::int64_t k = find_ball(model, b.id); k >= 0) {
        values = read(model.balls, static_cast<std::size_t>(k));
      } else {   // a ball deleted since: NaN, the row says so rather than stopping
        values.assign(b.quantities.size(), std::numeric_limits<double>::quiet_NaN());
      }
      row.insert(row.end(), values.begin(), values.end());
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
      row.push_back(get_sums().unbalanced_ratio().mean_ratio);
    } else if (item == "contacts") {
      row.push_back(get_sums().touching);
      row.push_back(get_sums().sliding_fraction());
      row.push_back(get_sums().coordination(model.balls.size()));
    }
  }
  return row;
}

void History::write_row(HistoryTable& t, const std::vector<double>& row, std::int64_t cycle) {
  if (t.out) {
    errno = 0;
    for (std::size_t k = 0; k < row.size(); ++k) *t.out << (k ? "," : "") << csv_real(row[k]);
    *t.out << '\n' << std::flush;
    if (!*t.out)
      throw std::runtime_error(fmt::format("cannot write the history file '{}' ({}): the rows from cycle {} on are "
                                           "not in it", t.file, errno ? std::strerror(errno) : "write failed",
                                           cycle));
  }
}

void History::keep_row(HistoryTable& t, std::vector<double> row) {
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

std::vector<std::size_t> History::recorded() const {
  std::vector<std::size_t> counts;
  for (const auto& t : tables_) counts.push_back(t->recorded);
  return counts;
}

void History::share_rows(std::vector<std::size_t>& marks) {
  marks.resize(tables_.size(), 0);
  // Per table: the number of new rows, then each row's length and values.
  std::vector<double> packed;
  if (comm::root())
    for (std::size_t k = 0; k < tables_.size(); ++k) {
      const HistoryTable& t = *tables_[k];
      const std::size_t fresh = std::min(t.recorded - std::min(marks[k], t.recorded), t.rows.size());
      packed.push_back(static_cast<double>(fresh));
      for (std::size_t r = t.rows.size() - fresh; r < t.rows.size(); ++r) {
        packed.push_back(static_cast<double>(t.rows[r].size()));
        packed.insert(packed.end(), t.rows[r].begin(), t.rows[r].end());
      }
    }
  comm::broadcast(packed);
  if (!comm::root()) {
    std::size_t at = 0;
    for (auto& table : tables_) {
      HistoryTable& t = *table;
      if (at >= packed.size()) break;
      const auto fresh = static_cast<std::size_t>(packed[at++]);
      for (std::size_t r = 0; r < fresh; ++r) {
        const auto length = static_cast<std::size_t>(packed[at++]);
        keep_row(t, std::vector<double>(packed.begin() + static_cast<std::ptrdiff_t>(at),
                                        packed.begin() + static_cast<std::ptrdiff_t>(at + length)));
        at += length;
      }
    }
  }
  marks = recorded();
}

void History::clear() { tables_.clear(); }

std::pair<const HistoryTable*, std::size_t> History::find_column(const std::string& name) const {
  for (const auto& t : tables_)
    for (std::size_t k = 0; k < t->columns.size(); ++k)
      if (t->columns[k] == name) return {t.get(), k};
  return {nullptr, 0};
}

}  // namespace trubal
