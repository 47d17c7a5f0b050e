#include "io/save.hpp"
#include "support/comm.hpp"

#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <array>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <numbers>
#include <stdexcept>
#include <type_traits>

#include <fmt/format.h>

#include "model/bond_table.hpp"
#include "model/wall_shape.hpp"

#include "io/atomic_file.hpp"
#include "io/model_checks.hpp"
#include "io/save_format.hpp"
#include "physics/sample.hpp"
#include "physics/scene.hpp"
#include "physics/walls.hpp"

namespace trubal {

namespace {

using namespace save_bytes;

constexpr std::size_t kHeaderSize = sizeof kMagic + sizeof kVersion + 2 * sizeof(std::uint64_t);

// A contact table's arrays: its list, its history and its results. From format 9 the history goes
// by name (the table's for_each_history), so that a law part added later reads older saves (its
// history starting at zero) and a save holding a part this build lacks is refused by name; before,
// the shear spring's three arrays stood after the state, in place. `put` writes or reads one array.
template <class IO, class Table, class Put>
void transfer_contacts(IO& io, Table& t, std::uint32_t version, Put&& put) {
  constexpr bool kReading = std::is_same_v<IO, Reader>;
  std::vector<std::string> read;   // the parts the file held
  t.for_each_list_array(put);
  if (version < 9) {
    put(t.state);
    for (const char* name : {"fsx", "fsy", "fsz"})
      t.for_each_history([&](auto& v, const HistoryPart& part) {
        if (name == std::string(part.name)) {
          put(v);
          read.emplace_back(name);
        }
      });
    t.for_each_result_array([&](auto& v) {
      if (static_cast<const void*>(&v) != static_cast<const void*>(&t.state)) put(v);
    });
  } else {
    std::uint64_t parts = 0;
    // Every part a law declares is written, one not in use as zeros, so that a save's bytes do not
    // depend on which parts a table keeps; on reading each part named is taken into use (load_model
    // drops those all zero that no law of the model needs).
    if constexpr (!kReading) t.for_each_declared_history([&](const auto&, const HistoryPart&, bool) { ++parts; });
    io.pod(parts);
    if constexpr (kReading) {
      if (parts > 64) io.corrupt();
      for (std::uint64_t k = 0; k < parts; ++k) {
        std::string name;
        io.str(name);
        // A name is a few letters and digits, said once.
        if (name.empty() || name.size() > 32 || std::find(read.begin(), read.end(), name) != read.end() ||
            name.find_first_not_of("abcdefghijklmnopqrstuvwxyz0123456789_") != std::string::npos)
          io.corrupt();
        bool known = false;
        if constexpr (std::is_same_v<Table, ContactTable>) {
          HistoryLaws laws = t.history_laws;
          laws.rolling = laws.rolling || name == "mrx" || name == "mry" || name == "mrz";
          laws.bridge = laws.bridge || name == "bridge";
          t.use_history(laws);
        }
        t.for_each_history([&](auto& v, const HistoryPart& part) {
          if (!known && name == part.name) {
            known = true;
            put(v);
          }
        });
        if (!known)
          throw std::runtime_error(fmt::format("'{}' holds a contact history '{}' that this trubal does not know "
                                               "(saved by a later version?): not restarted", io.path(), name));
        read.push_back(name);
      }
    } else {
      t.for_each_declared_history([&](auto& v, const HistoryPart& part, bool) {
        io.str(std::string(part.name));
        put(v);
      });
    }
    t.for_each_result_array(put);
  }
  if constexpr (kReading)   // a part the save did not know starts with no history
    t.for_each_history([&](auto& v, const HistoryPart& part) {
      if (std::find(read.begin(), read.end(), part.name) == read.end()) v.assign(t.size(), 0.0);
    });
}

// The pair table: on writing, only the pairs that carry something (touching, or a history): the
// others are the search's spare candidates, all zero, which depend on when the list was last made
// (a cut run, a rank count, results made again when read) while the state does not. The next step
// finds them. (Results not kept, ContactTable::results_kept, are written as zero.)
// `source`: the results, where the table holds none (ResultSource), each array fetched as it is
// written.
template <class IO> void transfer_pairs(IO& io, ContactTable& c, std::uint32_t version, ResultSource* source = nullptr) {
  if constexpr (std::is_same_v<IO, Reader>) {
    transfer_contacts(io, c, version, [&](auto& v) { io.vec(v); });
  } else {
    source = c.results_kept() ? nullptr : source;
    std::vector<std::uint8_t> state;
    if (source) source->fetch(0, state);
    const std::vector<std::uint8_t>& touched = source ? state : c.state;
    const bool results = c.results_kept() || source;
    std::vector<std::uint8_t> keep(c.size(), 1);
    std::size_t count = 0;
    for (std::size_t p = 0; p < c.size(); ++p) {
      keep[p] = (results && touched[p] != 0) || c.has_history(p);
      count += keep[p];
    }
    auto write_kept = [&](const auto& v) {
      if (count == c.size() && v.size() == c.size()) return io.vec(v);
      std::decay_t<decltype(v)> kept(count);
      if (v.size() == c.size())
        for (std::size_t p = 0, q = 0; p < v.size(); ++p)
          if (keep[p]) kept[q++] = v[p];
      io.vec(kept);
    };
    transfer_contacts(io, c, version, [&](const auto& v) {
      using Array = std::decay_t<decltype(v)>;
      const int k = source ? c.result_index(&v) : -1;   // (those a source holds, fetched in turn)
      if (k == 0) return write_kept(state);
      if constexpr (std::is_same_v<Array, std::vector<double>>) {
        if (k > 0) {
          Array fetched;
          source->fetch(static_cast<std::size_t>(k), fetched);
          return write_kept(fetched);
        }
      }
      write_kept(v);
    });
  }
}

// Array k of a source's table, of n elements of type T, as vec writes it.
template <class T> void write_streamed(Writer& w, std::uint64_t n, StateSource& source, StateSource::Table table, std::size_t k) {
  w.pod(n);
  std::vector<T> piece;
  std::uint64_t written = 0;
  source.stream(table, k, [&](const std::vector<double>& chunk) {
    piece.resize(chunk.size());
    for (std::size_t e = 0; e < chunk.size(); ++e) {
      if constexpr (sizeof(T) == 8 && std::is_integral_v<T>) piece[e] = std::bit_cast<T>(chunk[e]);
      else piece[e] = static_cast<T>(chunk[e]);
    }
    w.piece(piece);
    written += piece.size();
  });
  if (written != n) throw std::logic_error("internal error: a table streamed to SAVE came short");
}

// A contact table's arrays from a source, in transfer_contacts' order (format 9 on: the list, each
// declared history part by name, the results), n of each.
template <class Table>
void write_contacts_streamed(Writer& w, Table& t, std::uint64_t n, StateSource& source, StateSource::Table table) {
  std::size_t k = 0;
  auto put = [&](const auto& v) { write_streamed<typename std::decay_t<decltype(v)>::value_type>(w, n, source, table, k++); };
  t.for_each_list_array(put);
  std::uint64_t parts = 0;
  t.for_each_declared_history([&](const auto&, const HistoryPart&, bool) { ++parts; });
  w.pod(parts);
  t.for_each_declared_history([&](auto& v, const HistoryPart& part, bool) {
    w.str(std::string(part.name));
    put(v);
  });
  t.for_each_result_array(put);
}

// One description of the layout serves both directions, so save and load cannot drift apart.
// `state` (writing the current format): where the balls' moving arrays, the pairs and the wall
// contacts are, the model's arrays of them empty.
// `spans` (reading): the bulk passed over, but the balls' ids, types, fixities, radii and centres,
// where each array lies recorded (SavedTables).
template <class IO> void transfer(IO& io, Model& m, std::uint32_t version, ResultSource* results = nullptr,
                                  StateSource* state = nullptr, [[maybe_unused]] std::vector<Reader::Span>* spans = nullptr) {
  io.pod(m.space.periodic);
  io.pod(m.space.lo); io.pod(m.space.hi); io.pod(m.space.boxes);
  if (version >= 3) io.pod(m.space.tilt);
  io.pod(m.space.strain_rate); io.pod(m.space.strain);
  io.pod(m.space.servo_on); io.pod(m.space.servo_target);
  io.pod(m.space.servo_gain); io.pod(m.space.servo_max_rate);
  if (version >= 4) {
    io.pod(m.space.servo_measured); io.pod(m.space.servo_measured_valid); io.pod(m.space.servo_integral);
    io.pod(m.space.outside); io.pod(m.space.destroyed);
  }
  std::uint64_t nmat = m.materials.size();
  io.pod(nmat);
  if constexpr (std::is_same_v<IO, Reader>) {
    m.materials.clear();
    for (std::uint64_t k = 0; k < nmat; ++k) {
      int type = 0;
      Material mat;
      io.pod(type);
      if (version >= 11) {
        io.pod(mat);
      } else if (version == 10) {
        MaterialV10 old{};
        io.pod(old);
        mat.kn = old.kn; mat.ks = old.ks; mat.friction = old.friction; mat.cohesion = old.cohesion;
        mat.density = old.density; mat.shear_modulus = old.shear_modulus; mat.poisson = old.poisson;
        mat.restitution = old.restitution; mat.rolling_friction = old.rolling_friction;
        if (old.has_restitution > 1) io.corrupt();
        mat.has_restitution = old.has_restitution != 0;
      } else {
        MaterialV9 old{};
        io.pod(old);
        mat.kn = old.kn; mat.ks = old.ks; mat.friction = old.friction; mat.cohesion = old.cohesion;
        mat.density = old.density; mat.shear_modulus = old.shear_modulus; mat.poisson = old.poisson;
        mat.restitution = old.restitution;
        if (old.has_restitution > 1) io.corrupt();
        mat.has_restitution = old.has_restitution != 0;
      }
      m.materials[type] = mat;
    }
  } else {
    for (auto& [type, mat] : m.materials) {
      int t = type;
      io.pod(t);
      if (version >= 11) {
        io.pod(mat);
      } else if (version == 10) {   // (an older format asked for: its layout, without the bridges)
        const MaterialV10 old{mat.kn, mat.ks, mat.friction, mat.cohesion, mat.density, mat.shear_modulus, mat.poisson,
                              mat.restitution, mat.rolling_friction, static_cast<std::uint8_t>(mat.has_restitution ? 1 : 0),
                              {}};
        io.pod(old);
      } else {   // (its layout, without the rolling resistance)
        const MaterialV9 old{mat.kn, mat.ks, mat.friction, mat.cohesion, mat.density, mat.shear_modulus, mat.poisson,
                             mat.restitution, static_cast<std::uint8_t>(mat.has_restitution ? 1 : 0), {}};
        io.pod(old);
      }
    }
  }
  if constexpr (!std::is_same_v<IO, Reader>) {
    if (state) {
      // (The arrays the model holds are current: those it lets go, the source's.)
      const std::size_t n = m.balls.size();
      std::size_t k = 0;
      m.balls.for_each_array([&](auto& v) {
        const std::size_t at = k++;
        if (v.size() == n) return io.vec(v);
        write_streamed<typename std::decay_t<decltype(v)>::value_type>(io, n, *state, StateSource::Table::Balls, at);
      });
      write_contacts_streamed(io, m.contacts, state->place_pairs(), *state, StateSource::Table::Pairs);
      io.pod(state->results_cycle());
    }
  }
  bool indexed = false;
  if constexpr (std::is_same_v<IO, Reader>) {
    if (spans) {
      Balls& b = m.balls;
      b.for_each_array([&](auto& v) {
        const void* a = &v;
        io.vec_at(v, *spans, a == &b.id || a == &b.type || a == &b.fixed || a == &b.rad || a == &b.x || a == &b.y || a == &b.z);
      });
      transfer_contacts(io, m.contacts, version, [&](auto& v) { io.vec_at(v, *spans, false); });
      indexed = true;
    }
  }
  if (!state && !indexed) {
    m.balls.for_each_array([&](auto& v) { io.vec(v); });
    transfer_pairs(io, m.contacts, version, results);
  }
  if (!state) {
    if (version >= 4) {
      if constexpr (std::is_same_v<IO, Reader>) {
        io.pod(m.contacts.results_cycle);
      } else {
        const std::int64_t of = results && !m.contacts.results_kept() ? results->cycle() : m.contacts.results_cycle;
        io.pod(of);
      }
    }
  }
  io.pod(m.settings.frac); io.pod(m.settings.fixed_dt); io.pod(m.settings.gravity);
  io.pod(m.settings.damping);
  io.pod(m.energy.friction_work); io.pod(m.energy.damping_work); io.pod(m.energy.boundary_work);
  if (version >= 10) io.pod(m.energy.rolling_work);
  if (version >= 11) io.pod(m.energy.capillary_work);
  io.pod(m.membrane.pressure); io.pod(m.membrane.area);
  if (version >= 4) {
    io.pod(m.membrane.follow_every); io.pod(m.membrane.cell);
    io.vec(m.membrane.ids); io.vec(m.membrane.face_x); io.vec(m.membrane.face_y); io.vec(m.membrane.layer);
    io.vec(m.membrane.extent_x); io.vec(m.membrane.extent_y); io.vec(m.membrane.layer_cells);
  }
  std::uint64_t ngroups = m.groups.size();
  io.pod(ngroups);
  if constexpr (std::is_same_v<IO, Reader>) {
    m.groups.clear();
    for (std::uint64_t k = 0; k < ngroups; ++k) {
      std::string name;
      io.str(name);
      io.vec(m.groups[name]);
    }
  } else {
    for (auto& [name, ids] : m.groups) {
      std::string n = name;
      io.str(n);
      io.vec(ids);
    }
  }
  io.pod(m.cycle); io.pod(m.time); io.pod(m.dt); io.pod(m.critical_dt);
  io.str(m.title);
  io.pod(m.started);
  if (version >= 5) {
    std::uint64_t nwalls = m.walls.size();
    io.pod(nwalls);
    if constexpr (std::is_same_v<IO, Reader>) {
      if (nwalls > 1000000) io.corrupt();
      m.walls.assign(nwalls, Wall{});
    }
    for (Wall& w : m.walls) {
      io.pod(w.id); io.pod(w.type); io.pod(w.kind); io.pod(w.point); io.pod(w.normal); io.vec(w.vertices);
      io.pod(w.radius); io.pod(w.length); io.pod(w.inside);
      io.pod(w.velocity); io.pod(w.spin); io.pod(w.spin_point); io.pod(w.radius_rate);
      io.pod(w.servo_on); io.pod(w.servo_target); io.pod(w.servo_gain); io.pod(w.servo_max_speed);
      io.pod(w.servo_integral); io.pod(w.servo_area);
      io.pod(w.force); io.pod(w.moment); io.pod(w.normal_force); io.pod(w.stiffness); io.pod(w.contacts);
      io.pod(w.work);
    }
    bool streamed = false;
    if constexpr (!std::is_same_v<IO, Reader>) {
      if (state) {
        write_contacts_streamed(io, m.wall_contacts, state->place_walls(), *state, StateSource::Table::Walls);
        streamed = true;
      }
    }
    if constexpr (std::is_same_v<IO, Reader>) {
      if (spans) {
        transfer_contacts(io, m.wall_contacts, version, [&](auto& v) { io.vec_at(v, *spans, false); });
        streamed = true;
      }
    }
    if (!streamed) transfer_contacts(io, m.wall_contacts, version, [&](auto& v) { io.vec(v); });
    io.pod(m.space.periodic_axis);
  }
  if (version >= 6) io.pod(m.space.reference_volume);
  if (version >= 7) {   // field by field: the struct's padding is no part of the state
    EnergyAtStep& e = m.energy_at_step;
    io.pod(e.valid);
    for (double* v : {&e.kinetic_translation, &e.kinetic_rotation, &e.strain, &e.potential, &e.damping_ahead,
                      &e.boundary_ahead})
      io.pod(*v);
    if (version >= 11) io.pod(e.capillary_ahead);
  }
  if (version >= 8) {
    for (Wall& w : m.walls) io.pod(w.area_walls);
    Sample& s = m.sample;
    io.pod(s.platens); io.pod(s.sides); io.pod(s.height0); io.pod(s.area0);
  }
  if (version >= 12) {   // (older files: the balls in id order, sorted at the next multiple of 1000)
    io.pod(m.order.every);
    io.pod(m.order.pending);
  }
  if (version >= 13) {   // the parallel bonds, array by array (Bonds::for_each_array), and what broke
    io.pod(m.energy.bond_break_work);
    std::uint64_t nbonds = m.bonds.size();
    io.pod(nbonds);
    if constexpr (std::is_same_v<IO, Reader>)
      if (nbonds > (std::uint64_t{1} << 34)) io.corrupt();
    Bonds by_id;   // written by the balls' ids, whatever order the step keeps them in
    if constexpr (!std::is_same_v<IO, Reader>) {
      by_id = m.bonds;
      sort_bonds(by_id);
    }
    (std::is_same_v<IO, Reader> ? m.bonds : by_id).for_each_array([&](auto& v) {
      io.vec(v);
      if constexpr (std::is_same_v<IO, Reader>)
        if (v.size() != nbonds) io.corrupt();
    });
    if constexpr (std::is_same_v<IO, Reader>) m.bonds.changed();
  }
}

// The histories: what each HIST asked for and the rows it holds (a file's window; every row of a
// table in memory only). The file itself is reopened by History::resume_files.
template <class IO> void transfer_histories(IO& io, History& history) {
  constexpr bool reading = std::is_same_v<IO, Reader>;
  std::uint64_t ntables = history.tables().size();
  io.pod(ntables);
  if constexpr (reading) {
    if (ntables > 100000) io.corrupt();
    for (std::uint64_t k = 0; k < ntables; ++k) history.adopt(std::make_unique<HistoryTable>());
  }
  auto strings = [&](std::vector<std::string>& v) {
    std::uint64_t n = v.size();
    io.pod(n);
    if constexpr (reading) {
      if (n > 1000000) io.corrupt();
      v.assign(n, std::string());
    }
    for (auto& x : v) io.str(x);
  };
  for (const auto& t : history.tables()) {
    strings(t->items);
    strings(t->columns);
    io.pod(t->every);
    io.str(t->file);
    std::uint64_t nrange = t->platen_range.size();
    io.pod(nrange);
    if constexpr (reading) {
      if (nrange > 1000) io.corrupt();
      t->platen_range.assign(nrange, RangeElement{});
    }
    for (RangeElement& e : t->platen_range) {
      std::int32_t kind = static_cast<std::int32_t>(e.kind);
      io.pod(kind);
      if constexpr (reading) {
        if (kind < 0 || kind > static_cast<std::int32_t>(RangeElement::Kind::Octagon)) io.corrupt();
        e.kind = static_cast<RangeElement::Kind>(kind);
      }
      io.pod(e.negate); io.pod(e.v); io.str(e.group);
    }
    io.vec(t->platen_ids);
    io.pod(t->platen_gap0); io.pod(t->area); io.pod(t->pressure); io.pod(t->membrane_area);
    std::uint64_t recorded = t->recorded, nrows = t->rows.size();
    io.pod(recorded);
    io.pod(nrows);
    if constexpr (reading) {
      if (nrows > recorded) io.corrupt();
      t->recorded = recorded;
      if (nrows > 100000000) io.corrupt();
      t->rows.assign(nrows, {});
    }
    for (auto& row : t->rows) {
      io.vec(row);
      if constexpr (reading)
        if (row.size() != t->columns.size()) io.corrupt();
    }
    if constexpr (reading)
      if (t->every < 1 || !History::valid_table(*t)) io.corrupt();
  }
}

}  // namespace

void save_model(const Model& model, const std::string& path, const History* history, std::uint32_t version,
                ResultSource* results, StateSource* state) {
  if (!comm::root()) return;   // a distributed run's files are rank 0's to write
  if (version == 0) version = kVersion;
  if (state && version != kVersion) throw std::logic_error("internal error: a streamed SAVE of an older format");
  if (version < kOldestVersion || version > kVersion)
    throw std::invalid_argument(fmt::format("save format {} is not one this trubal writes", version));
  check_replaceable(path);
  TemporaryFile tmp(path);   // (the stale temporaries of killed SAVEs go first)
  const int fd = tmp.fd();
  // The header's length and checksum are written last, in place, once the body has been streamed.
  std::string header(kMagic, sizeof kMagic);
  header.append(reinterpret_cast<const char*>(&version), sizeof version);
  const std::size_t sums_at = header.size();
  header.append(2 * sizeof(std::uint64_t), '\0');
  Writer w(fd);
  bool ok = ::pwrite(fd, header.data(), header.size(), 0) == static_cast<ssize_t>(header.size()) &&
            ::lseek(fd, static_cast<off_t>(header.size()), SEEK_SET) >= 0;
  int err = ok ? 0 : errno;
  if (ok) {
    transfer(w, const_cast<Model&>(model), version, results, state);
    History none;
    if (version >= 6) transfer_histories(w, const_cast<History&>(history ? *history : none));
    ok = w.flush();
    err = w.error();
  }
  if (ok) {
    const std::uint64_t sums[2] = {w.size(), w.sum()};
    ok = ::pwrite(fd, sums, sizeof sums, static_cast<off_t>(sums_at)) == static_cast<ssize_t>(sizeof sums) &&
         ::fsync(fd) == 0;
    err = errno;
  }
  if (!tmp.close() && ok) {
    ok = false;
    err = errno;
  }
  if (!ok) throw std::runtime_error(fmt::format("cannot write '{}': {} (nothing was replaced)", path, std::strerror(err)));
  tmp.rename_over_target(" (nothing was replaced)");
}

std::string light_state(const Model& model) {
  Model& m = const_cast<Model&>(model);
  Balls balls = std::move(m.balls);
  ContactTable contacts = std::move(m.contacts);
  WallContacts walls = std::move(m.wall_contacts);
  Bonds bonds = std::move(m.bonds);
  auto put_back = [&] {
    m.balls = std::move(balls);
    m.contacts = std::move(contacts);
    m.wall_contacts = std::move(walls);
    m.bonds = std::move(bonds);
  };
  std::string bytes;
  try {
    m.balls = Balls{};
    m.contacts = ContactTable{};
    m.contacts.history_laws = contacts.history_laws;
    m.contacts.results_cycle = contacts.results_cycle;
    m.wall_contacts = WallContacts{};
    m.bonds = Bonds{};
    Writer w(&bytes);
    transfer(w, m, kVersion);
    w.flush();
  } catch (...) {
    put_back();
    throw;
  }
  put_back();
  return bytes;
}

std::string history_bytes(const History& history) {
  std::string bytes;
  Writer w(&bytes);
  transfer_histories(w, const_cast<History&>(history));
  w.flush();
  return bytes;
}

void take_history_bytes(History& history, const std::string& bytes) {
  History taken;
  Reader r(bytes, "rank 0's histories");
  transfer_histories(r, taken);
  if (!r.at_end()) r.corrupt();
  history = std::move(taken);
}

void take_light_state(Model& model, const std::string& bytes) {
  Model light;
  Reader r(bytes, "rank 0's model");
  transfer(r, light, kVersion);
  if (!r.at_end()) r.corrupt();
  light.contacts.set_history_laws(laws_with_history(light));
  model = std::move(light);
}

namespace {

using File = std::unique_ptr<std::FILE, int (*)(std::FILE*)>;

// A save file opened and checked whole (its magic, version, length and checksum), read a buffer at
// a time; left at its body, `version` and `size` (the body's length) set. Throws as load_model.
File open_save(const std::string& path, std::uint32_t& version, std::uint64_t& size) {
  // Looked at before it is opened (through a link: a link to a save is a save): opening a FIFO
  // waits for a writer for ever, and a device such as /dev/zero never ends.
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::file_type kind = fs::status(path, ec).type();
  if (kind == fs::file_type::directory) throw std::runtime_error(fmt::format("'{}' is a directory, not a save file", path));
  if (kind == fs::file_type::fifo || kind == fs::file_type::character || kind == fs::file_type::block ||
      kind == fs::file_type::socket)
    throw std::runtime_error(fmt::format("'{}' is {}, not a save file", path,
                                         kind == fs::file_type::fifo ? "a FIFO (a named pipe: reading it waits for a writer)"
                                                                     : "a device or a socket"));
  // The file is read twice, a buffer at a time: its checksum, then the model (never the file's
  // bytes whole beside the model made of them).
  File file(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!file) throw std::runtime_error(fmt::format("cannot open the save file '{}'", path));
  std::FILE* f = file.get();
  const auto read_error = [&] {
    return std::runtime_error(fmt::format("cannot read '{}': {} (not restarted)", path, std::strerror(errno)));
  };
  char header[kHeaderSize];
  const std::size_t got = std::fread(header, 1, kHeaderSize, f);
  if (got < kHeaderSize && std::ferror(f)) throw read_error();
  if (got < sizeof kMagic || std::memcmp(header, kMagic, sizeof kMagic) != 0)
    throw std::runtime_error(fmt::format("'{}' is not a trubal save file", path));
  if (got < kHeaderSize) throw std::runtime_error(fmt::format("'{}' is truncated (not restarted)", path));
  std::uint64_t sum = 0;
  std::memcpy(&version, header + sizeof kMagic, sizeof version);
  std::memcpy(&size, header + sizeof kMagic + sizeof version, sizeof size);
  std::memcpy(&sum, header + sizeof kMagic + sizeof version + sizeof size, sizeof sum);
  if (version < kOldestVersion || version > kVersion)
    throw std::runtime_error(fmt::format("'{}' was saved by save format version {}; this trubal reads versions {} to {}",
                                         path, version, kOldestVersion, kVersion));
  std::uint64_t body = 0, body_sum = kFnvStart;
  {
    std::vector<char> buf(std::size_t{1} << 20);
    for (;;) {
      const std::size_t n = std::fread(buf.data(), 1, buf.size(), f);
      if (n == 0) break;
      body += n;
      if (body <= size) body_sum = fnv1a_more(body_sum, buf.data(), n);
    }
    if (std::ferror(f)) throw read_error();
  }
  if (body < size)
    throw std::runtime_error(fmt::format("'{}' is truncated: {} of {} bytes (not restarted)", path, body, size));
  if (body > size || body_sum != sum)
    throw std::runtime_error(fmt::format("'{}' is corrupted: its checksum does not match (not restarted)", path));
  if (std::fseek(f, static_cast<long>(kHeaderSize), SEEK_SET) != 0) throw read_error();
  return file;
}

}  // namespace

Model load_model(const std::string& path, History* history) {
  std::uint32_t version = 0;
  std::uint64_t size = 0;
  File file = open_save(path, version, size);
  std::FILE* f = file.get();
  Model m;
  Reader r(f, size, path);
  transfer(r, m, version);
  History histories;
  if (version >= 6) transfer_histories(r, histories);
  if (!r.at_end()) r.corrupt();
  // Cross-checks that a checksum collision or a bug could not hide.
  const std::size_t n = m.balls.id.size();
  bool consistent = true;
  m.balls.for_each_array([&](const auto& v) { consistent = consistent && v.size() == n; });
  for (std::size_t p = 0; p < m.contacts.i.size(); ++p)
    consistent = consistent && m.contacts.i[p] < n && m.contacts.j[p] < n;
  m.contacts.for_each_pair_array([&](const auto& v) { consistent = consistent && v.size() == m.contacts.i.size(); });
  if (!consistent) r.corrupt();
  // The history parts the model's laws use, and those the save holds values of (a part all zero
  // that no law uses is not kept: the same as one never in use).
  m.contacts.drop_zero_history(laws_with_history(m));
  m.contacts.use_history(laws_with_history(m));
  m.balls.index_ids();
  const std::string wrong = invalid_model(m);
  if (!wrong.empty())
    throw std::runtime_error(fmt::format("'{}' holds no valid model: {} (not restarted)", path, wrong));
  if (history) *history = std::move(histories);
  return m;
}

SavedTables::SavedTables(const std::string& path, History* history) : path_(path) {
  std::uint32_t version = 0;
  std::uint64_t size = 0;
  File file = open_save(path, version, size);
  Reader r(file.get(), size, path);
  std::vector<Reader::Span> spans;
  transfer(r, model_, version, nullptr, nullptr, &spans);
  History histories;
  if (version >= 6) transfer_histories(r, histories);
  if (!r.at_end()) r.corrupt();
  // Each bulk array's place, numbered as the pieces are (each_piece_array): found by the vector
  // it was read for.
  const auto place = [&](PieceTable table, const void* array, std::size_t k) {
    auto& to = spans_[static_cast<int>(table)];
    if (to.size() <= k) to.resize(k + 1);
    for (const Reader::Span& s : spans)
      if (s.array == array) to[k] = {s.at, s.n, s.size};
  };
  each_piece_array(model_.balls, [&](auto& v, std::size_t k, bool) { place(PieceTable::Balls, &v, k); });
  each_piece_array(model_.contacts, [&](auto& v, std::size_t k, bool) { place(PieceTable::Pairs, &v, k); });
  each_piece_array(model_.wall_contacts, [&](auto& v, std::size_t k, bool) { place(PieceTable::Walls, &v, k); });
  // Every array of a table of its count of rows (the balls' from their ids, the pairs' from the
  // first of the list's arrays; an array the file lacks is a history part, zero).
  const std::size_t n = model_.balls.id.size();
  bool consistent = true;
  for (const auto& table : spans_)
    for (const Span& s : table) consistent = consistent && (s.size == 0 || s.n == table[0].n);
  consistent = consistent && !spans_[0].empty() && spans_[0][0].n == n;
  for (const Span& s : spans_[0]) consistent = consistent && s.size != 0;
  if (!consistent) r.corrupt();
  // Why the ranks' parts cannot be made from it (the file is then read whole, as serially).
  const Model& m = model_;
  if (version < 12) why_whole_ = "saved by an older format";
  else if (n == 0) why_whole_ = "no ball";
  else if (!m.bonds.empty()) why_whole_ = "bonds";
  else if (rows(PieceTable::Pairs) > 0 && m.contacts.results_cycle != m.cycle)
    why_whole_ = "contact results of another cycle";
  if (history) *history = std::move(histories);
  body_at_ = kHeaderSize;
  file_ = file.release();
}

SavedTables::~SavedTables() {
  if (file_) std::fclose(file_);
}

std::uint64_t SavedTables::rows(PieceTable table) const {
  const auto& t = spans_[static_cast<int>(table)];
  return t.empty() ? 0 : t[0].n;
}

void SavedTables::read(PieceTable table, std::size_t k, std::uint64_t from, std::uint64_t n, void* out, std::size_t size) {
  if (n == 0) return;   // (an empty piece: `out` may be no buffer at all)
  const auto& t = spans_[static_cast<int>(table)];
  const Span s = k < t.size() ? t[k] : Span{};
  if (s.size == 0) {   // (a history part the save did not know: zero)
    std::memset(out, 0, n * size);
    return;
  }
  if (s.size != size || from > s.n || n > s.n - from)
    throw std::logic_error("internal error: a piece of a save's array asked for outside it");
  const std::uint64_t at = body_at_ + s.at + from * size;
  if (std::fseek(file_, static_cast<long>(at), SEEK_SET) != 0 || std::fread(out, size, n, file_) != n)
    throw std::runtime_error(fmt::format("cannot read '{}': {} (not restarted)", path_,
                                         std::ferror(file_) ? std::strerror(errno) : "it was cut short since it was checked"));
}

void SavedTables::check(std::uint64_t piece_rows) {
  Model& m = model_;
  const std::size_t n = m.balls.id.size();
  const std::uint64_t kPiece = std::max<std::uint64_t>(1, piece_rows);
  const auto fail = [&](const std::string& wrong) {
    throw std::runtime_error(fmt::format("'{}' holds no valid model: {} (not restarted)", path_, wrong));
  };
  // A piece [from, from + count) of the table's arrays into `into`, each array as each_piece_array
  // numbers it (those `want` names; the others left empty).
  const auto piece = [&](PieceTable table, auto& into, std::uint64_t from, std::uint64_t count, auto&& want) {
    each_piece_array(into, [&](auto& v, std::size_t k, bool) {
      if (!want(k)) return std::decay_t<decltype(v)>().swap(v);
      v.resize(count);
      read(table, k, from, count, v.data(), sizeof(v[0]));
    });
  };
  m.balls.index_ids();
  if (std::string p = ids_problem(m.balls); !p.empty()) fail(p);
  {
    Balls b;
    for (std::uint64_t from = 0; from < n; from += kPiece) {
      const std::uint64_t count = std::min(kPiece, n - from);
      piece(PieceTable::Balls, b, from, count, [](std::size_t) { return true; });
      for (std::size_t q = 0; q < count; ++q)
        if (std::string p = ball_problem(b, q, from + q); !p.empty()) fail(p);
    }
  }
  // The pairs, each piece with the pair before it (the order is checked against it); whether the
  // rolling and bridge parts hold any value other than zero (load_model keeps those that do).
  bool rolling = false, bridge = false;
  {
    const std::uint64_t pairs = rows(PieceTable::Pairs);
    ContactTable c;
    c.set_history_laws({true, true});
    std::size_t at_i = 0, at_j = 0, at_state = 0;
    std::vector<std::size_t> at_rolling, at_bridge;
    each_piece_array(c, [&](auto& v, std::size_t k, bool) {
      const void* a = &v;
      if (a == &c.i) at_i = k;
      if (a == &c.j) at_j = k;
      if (a == &c.state) at_state = k;
      if (a == &c.mrx || a == &c.mry || a == &c.mrz) at_rolling.push_back(k);
      if (a == &c.bridge) at_bridge.push_back(k);
    });
    const auto nonzero = [](const std::vector<double>& v) {
      for (double x : v)
        if (x != 0 || std::signbit(x)) return true;
      return false;
    };
    for (std::uint64_t from = 0; from < pairs; from += kPiece) {
      const std::uint64_t first = from > 0 ? from - 1 : 0, count = std::min(kPiece, pairs - from) + (from - first);
      piece(PieceTable::Pairs, c, first, count, [&](std::size_t k) {
        return k == at_i || k == at_j || k == at_state || std::count(at_rolling.begin(), at_rolling.end(), k) ||
               std::count(at_bridge.begin(), at_bridge.end(), k);
      });
      for (std::size_t p = 0; p < count; ++p)
        if (!(c.i[p] < n && c.j[p] < n)) damaged(path_);   // (load_model's cross-check, before the rest)
      for (std::size_t p = from - first; p < count; ++p)
        if (std::string q = pair_problem(c, p, first + p); !q.empty()) fail(q);
      rolling = rolling || nonzero(c.mrx) || nonzero(c.mry) || nonzero(c.mrz);
      bridge = bridge || nonzero(c.bridge);
    }
  }
  // The parts the model's laws use, and those holding values (load_model's drop_zero_history).
  const HistoryLaws keep = laws_with_history(m);
  HistoryLaws held = m.contacts.history_laws;
  held.rolling = held.rolling && (keep.rolling || rolling);
  held.bridge = held.bridge && (keep.bridge || bridge);
  m.contacts.set_history_laws(held);
  m.contacts.use_history(keep);
  if (std::string p = light_problem(m); !p.empty()) fail(p);
  {
    const std::uint64_t walls = rows(PieceTable::Walls);
    WallContacts w;
    for (std::uint64_t from = 0; from < walls; from += kPiece) {
      const std::uint64_t count = std::min(kPiece, walls - from);
      piece(PieceTable::Walls, w, from, count, [](std::size_t) { return true; });
      for (std::size_t p = 0; p < count; ++p)
        if (std::string q = wall_contact_problem(w, p, from + p, m); !q.empty()) fail(q);
    }
  }
  if (const std::string bonds = bond_table_problem(m); !bonds.empty()) fail(bonds);
}

Model SavedTables::take_model() { return std::move(model_); }

}  // namespace trubal
