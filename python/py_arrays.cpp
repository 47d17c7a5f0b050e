// The model as numpy arrays. The rule (doc/python.md): every read returns a new array that owns
// its numbers, a snapshot that later cycles do not change, marked read-only so that writing into
// it is an error instead of a change silently lost; a write assigns a whole array, which is checked
// and copied in through Session::edit(), as INIT and BALL change balls (the pair lists are rebuilt
// and the time step estimated afresh at the next step).
#include <cmath>
#include <limits>
#include <unordered_set>

#include <fmt/format.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include "io/history.hpp"
#include "model/bond_table.hpp"
#include "model/edit.hpp"
#include "physics/bond.hpp"
#include "physics/measure.hpp"
#include "physics/walls.hpp"
#include "py_session.hpp"

namespace trubal::python {

namespace {

using Column = std::vector<double>;

PyObject* g_masked_array_type = nullptr;   // numpy.ma.MaskedArray, found at import; lives as long as numpy

template <class T> py::array_t<T> read_only(py::array_t<T> a) {
  a.attr("flags").attr("writeable") = false;
  return a;
}

// An (n, 3) array from three columns, rows picked by `rows` (all rows where it is null).
py::array_t<double> columns3(const Column& a, const Column& b, const Column& c,
                             const std::vector<std::size_t>* rows = nullptr) {
  const std::size_t n = rows ? rows->size() : a.size();
  py::array_t<double> out({static_cast<py::ssize_t>(n), py::ssize_t{3}});
  auto o = out.mutable_unchecked<2>();
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t r = rows ? (*rows)[k] : k;
    o(k, 0) = a[r];
    o(k, 1) = b[r];
    o(k, 2) = c[r];
  }
  return read_only(out);
}

template <class T, class From> py::array_t<T> column(const std::vector<From>& v,
                                                     const std::vector<std::size_t>* rows = nullptr) {
  const std::size_t n = rows ? rows->size() : v.size();
  py::array_t<T> out(static_cast<py::ssize_t>(n));
  auto o = out.template mutable_unchecked<1>();
  for (std::size_t k = 0; k < n; ++k) o(k) = static_cast<T>(v[rows ? (*rows)[k] : k]);
  return read_only(out);
}

// The balls' indices in ascending order of id: the row order of every ball array (the model keeps
// its balls in its own order in memory, model/model.hpp).
std::vector<std::size_t> id_rows(const Balls& b) { return {b.by_id.begin(), b.by_id.end()}; }

py::array_t<double> sym_matrix(const std::array<double, 6>& s) {   // xx yy zz xy xz yz
  py::array_t<double> out({py::ssize_t{3}, py::ssize_t{3}});
  auto o = out.mutable_unchecked<2>();
  const int at[3][3] = {{0, 3, 4}, {3, 1, 5}, {4, 5, 2}};
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) o(a, b) = s[at[a][b]];
  return read_only(out);
}

using InArray = py::array_t<double, py::array::c_style | py::array::forcecast>;

// A new (n, 3) or (n,) array for the balls, its numbers real and finite: the message names what
// was wrong. What numpy's cast would lose silently is refused before it: a mask (numpy.asarray
// drops it, the masked entries' numbers would go in) and imaginary parts (a ComplexWarning only).
InArray checked(const py::object& value, const Model& m, int width, const char* what) {
  const auto wrong_type = [what] {
    return py::type_error(fmt::format("{}: a numpy array (or nested lists) of numbers is needed", what));
  };
  const int masked = PyObject_IsInstance(value.ptr(), g_masked_array_type);
  if (masked < 0) throw py::error_already_set();
  if (masked)
    throw py::type_error(fmt::format("{}: a masked array is refused (its mask would be ignored): give a plain array, "
                                     "such as a.filled(x) with the number x meant for the masked entries",
                                     what));
  const py::array given = py::array::ensure(value);   // numpy's own dtype for it, nothing cast yet
  if (!given) throw wrong_type();
  const char kind = given.dtype().kind();
  if (kind == 'c')
    throw py::type_error(fmt::format("{}: complex numbers given (dtype {}): real numbers are needed (the imaginary "
                                     "parts would be dropped)",
                                     what, py::str(given.dtype()).cast<std::string>()));
  if (std::string_view("biufO").find(kind) == std::string_view::npos)   // strings, dates, records
    throw py::type_error(fmt::format("{}: numbers are needed, dtype {} given", what,
                                     py::str(given.dtype()).cast<std::string>()));
  InArray a = InArray::ensure(given);
  if (!a) throw wrong_type();
  const auto n = static_cast<py::ssize_t>(m.balls.size());
  const bool ok =
      width == 1 ? a.ndim() == 1 && a.shape(0) == n : a.ndim() == 2 && a.shape(0) == n && a.shape(1) == width;
  if (!ok) {
    std::string shape;
    for (py::ssize_t d = 0; d < a.ndim(); ++d) shape += fmt::format("{}{}", d ? ", " : "", a.shape(d));
    throw py::value_error(fmt::format("{}: shape ({}) given, ({}{}) needed: one row per ball, ordered by id", what,
                                      shape, n, width == 1 ? "," : fmt::format(", {}", width)));
  }
  const double* p = a.data();
  for (py::ssize_t k = 0; k < a.size(); ++k)
    if (!std::isfinite(p[k]))
      throw py::value_error(fmt::format("{}: row {} holds {} (ball {}): only finite numbers", what, k / width, p[k],
                                        m.balls.id[m.balls.by_id[static_cast<std::size_t>(k / width)]]));
  return a;
}

void set_columns3(PySession& s, const InArray& in, Column Balls::*a, Column Balls::*b, Column Balls::*c) {
  auto v = in.unchecked<2>();
  Balls& balls = s.session().edit().balls;
  for (std::size_t k = 0; k < balls.size(); ++k) {   // (row k: the ball of the k-th id)
    const std::size_t at = balls.by_id[k];
    (balls.*a)[at] = v(k, 0);
    (balls.*b)[at] = v(k, 1);
    (balls.*c)[at] = v(k, 2);
  }
}

// As BALL checks a centre: inside the START box on its bounded axes, and no two balls at one
// centre (they would have no normal between them and fly apart).
void set_positions(PySession& s, const py::object& value) {
  const Model& m = s.session().model();
  const InArray in = checked(value, m, 3, "positions");
  auto v = in.unchecked<2>();
  const Space& space = m.space;
  struct Hash {
    std::size_t operator()(const std::array<double, 3>& c) const {
      return std::hash<double>()(c[0]) ^ (std::hash<double>()(c[1]) * 31) ^ (std::hash<double>()(c[2]) * 1000003);
    }
  };
  std::unordered_set<std::array<double, 3>, Hash> centres;
  for (std::size_t k = 0; k < m.balls.size(); ++k) {
    const std::int64_t id = m.balls.id[m.balls.by_id[k]];
    for (int a = 0; a < 3; ++a)
      if (!space.wraps(a) && (v(k, a) < space.lo[a] || v(k, a) > space.hi[a]))
        raise_error("", 0, fmt::format("positions: ball {}'s centre {} = {} is outside the START box [{}, {}]",
                                       id, "xyz"[a], v(k, a), space.lo[a], space.hi[a]));
    auto zero = [](double x) { return x == 0 ? 0.0 : x; };   // -0 and 0 are the same place
    if (!centres.insert({zero(v(k, 0)), zero(v(k, 1)), zero(v(k, 2))}).second)
      raise_error("", 0, fmt::format("positions: ball {} is given the centre of another ball ({}, {}, {}): two balls "
                                     "at one centre would fly apart", id, v(k, 0), v(k, 1), v(k, 2)));
  }
  set_columns3(s, in, &Balls::x, &Balls::y, &Balls::z);
  s.session().edit().order.pending = true;   // (in space order at the next step, as balls BALL adds)
}

void set_radii(PySession& s, const py::object& value) {
  const Model& m = s.session().model();
  const InArray in = checked(value, m, 1, "radii");
  auto v = in.unchecked<1>();
  for (std::size_t k = 0; k < m.balls.size(); ++k)   // BALL's rule
    if (const std::string why = ball_radius_problem(m.space, v(k)); !why.empty())
      raise_error("", 0, fmt::format("radii: ball {} is given radius {}: {}", m.balls.id[m.balls.by_id[k]], v(k), why));
  Balls& balls = s.session().edit().balls;   // masses follow at the next step (update_mass)
  for (std::size_t k = 0; k < balls.size(); ++k) balls.rad[balls.by_id[k]] = v(k);
  s.session().edit().order.pending = true;   // (the space order's cells are one largest diameter wide)
}

// The pairs touching at the last force pass, as PRINT contacts lists them.
py::dict contacts(PySession& s) {
  const Model& m = s.session().model();
  const ContactTable& c = m.contacts;
  const auto& id = m.balls.id;
  std::vector<std::size_t> rows;
  for (std::size_t p = 0; p < c.size() && p < c.state.size(); ++p)
    if (c.state[p] != 0) rows.push_back(p);
  // Each pair as (smaller id, larger id), sorted so: a pair the model lists the other way round
  // (its order in memory is not id order) has its vectors on j turned round.
  const auto low = [&](std::size_t p) { return std::min(id[c.i[p]], id[c.j[p]]); };
  const auto high = [&](std::size_t p) { return std::max(id[c.i[p]], id[c.j[p]]); };
  std::stable_sort(rows.begin(), rows.end(), [&](std::size_t p, std::size_t q) {
    return low(p) != low(q) ? low(p) < low(q) : high(p) < high(q);
  });
  std::vector<double> sign(rows.size());
  std::vector<std::int64_t> i(rows.size()), j(rows.size());
  std::vector<bool> sliding(rows.size());
  for (std::size_t k = 0; k < rows.size(); ++k) {
    i[k] = low(rows[k]);
    j[k] = high(rows[k]);
    sign[k] = id[c.i[rows[k]]] < id[c.j[rows[k]]] ? 1.0 : -1.0;
    sliding[k] = c.state[rows[k]] == 2;
  }
  const auto on_j = [&](const Column& a, const Column& b, const Column& cc) {
    py::array_t<double> out = columns3(a, b, cc, &rows);
    out.attr("flags").attr("writeable") = true;
    auto o = out.mutable_unchecked<2>();
    for (std::size_t k = 0; k < rows.size(); ++k)
      for (int d = 0; d < 3; ++d) o(k, d) *= sign[k];
    return read_only(out);
  };
  py::dict d;
  d["i"] = column<std::int64_t>(i);
  d["j"] = column<std::int64_t>(j);
  d["normal"] = on_j(c.nx, c.ny, c.nz);
  d["overlap"] = column<double>(c.overlap, &rows);
  d["normal_force"] = column<double>(c.fn, &rows);
  d["shear_force"] = on_j(c.fsx, c.fsy, c.fsz);
  d["force"] = on_j(c.fx, c.fy, c.fz);
  d["sliding"] = column<bool>(sliding);
  // Every part of the contacts' history the contact laws declare (ContactTable::for_each_declared_history),
  // by the name SAVE gives it, as seen from the pair (i, j) above: zero where the table keeps no
  // such part (no law of the scene uses it).
  py::dict history;
  const std::vector<double> zeros(c.size(), 0.0);
  c.for_each_declared_history([&](const auto& v, const HistoryPart& part, bool used) {
    py::array_t<double> a = column<double>(used ? v : zeros, &rows);
    if (part.swap == OnSwap::Negate) {
      a.attr("flags").attr("writeable") = true;
      auto o = a.mutable_unchecked<1>();
      for (std::size_t k = 0; k < rows.size(); ++k) o(k) *= sign[k];
      a.attr("flags").attr("writeable") = false;
    }
    history[part.name] = a;
  });
  d["history"] = history;
  d["cycle"] = c.results_cycle;
  return d;
}

// The parallel bonds (BOND), intact and broken, as PRINT bonds lists them: by their balls' ids.
py::dict bonds(PySession& s) {
  const Model& m = s.session().model();
  Bonds t = m.bonds;
  sort_bonds(t);
  const std::size_t n = t.size();
  std::vector<double> sigma(n), tau(n);
  std::vector<std::int32_t> state(t.fate.begin(), t.fate.end());
  std::vector<bool> intact(n);
  for (std::size_t q = 0; q < n; ++q) {
    const BondStress st = bond_stress(bond_law(t, q), bond_state(t, q));
    sigma[q] = st.sigma;
    tau[q] = st.tau;
    intact[q] = t.fate[q] == 0;
  }
  py::dict d;
  d["i"] = column<std::int64_t>(t.id_i);
  d["j"] = column<std::int64_t>(t.id_j);
  d["radius"] = column<double>(t.radius);
  d["normal_force"] = column<double>(t.fn);
  d["shear_force"] = columns3(t.fsx, t.fsy, t.fsz);
  d["twisting_moment"] = column<double>(t.mt);
  d["bending_moment"] = columns3(t.mbx, t.mby, t.mbz);
  d["sigma"] = column<double>(sigma);
  d["tau"] = column<double>(tau);
  d["intact"] = column<bool>(intact);
  d["state"] = column<std::int32_t>(state);
  return d;
}

py::dict energy(PySession& s) {
  const EnergyReport e = trubal::energy(s.session().model());
  py::dict d;
  d["kinetic_translation"] = e.kinetic_translation;
  d["kinetic_rotation"] = e.kinetic_rotation;
  d["strain"] = e.strain;
  d["potential"] = e.potential;
  d["friction_work"] = e.friction_work;
  d["rolling_work"] = e.rolling_work;
  d["capillary_work"] = e.capillary_work;
  d["bond_break_work"] = e.bond_break_work;
  d["damping_work"] = e.damping_work;
  d["boundary_work"] = e.boundary_work;
  d["balance"] = e.total();
  d["at_step"] = e.at_step;   // all at the last force pass (else the state as it is)
  return d;
}

// Each HIST table as {column: array}: every row recorded (read back from its file when the rows
// kept in memory are only the latest window).
py::list histories(PySession& s) {
  py::list out;
  for (const auto& t : s.session().history().tables()) {
    const HistoryTable* table = t.get();
    std::unique_ptr<HistoryTable> from_file;
    if (!table->file.empty() && table->recorded > table->rows.size()) {
      s.flush();
      from_file = engine_call([&] { return read_history_csv(table->file); });
      table = from_file.get();
    }
    py::dict d;
    for (std::size_t col = 0; col < table->columns.size(); ++col) {
      std::vector<double> v(table->rows.size());
      for (std::size_t r = 0; r < v.size(); ++r) v[r] = col < table->rows[r].size() ? table->rows[r][col] : NAN;
      d[py::str(table->columns[col])] = column<double>(v);
    }
    out.append(d);
  }
  return out;
}

py::list walls(PySession& s) {
  const Model& m = s.session().model();
  py::list out;
  auto vec = [](const std::array<double, 3>& v) { return read_only(py::array_t<double>(3, v.data())); };
  for (const Wall& w : m.walls) {
    py::dict d;
    d["id"] = w.id;
    d["kind"] = w.kind == WallKind::Plane ? "plane" : w.kind == WallKind::Polygon ? "polygon" : "cylinder";
    d["position"] = wall_position(w);
    d["force"] = vec(w.force);
    d["moment"] = vec(w.moment);
    d["normal_force"] = w.normal_force;
    d["stress"] = wall_servo_area(m, w) > 0 ? wall_stress(m, w) : std::numeric_limits<double>::quiet_NaN();
    d["contacts"] = w.contacts;
    d["work"] = w.work;
    d["velocity"] = vec(w.velocity);
    if (w.kind == WallKind::Cylinder) d["radius"] = w.radius;
    out.append(d);
  }
  return out;
}

}  // namespace

void load_numpy() {
  // pybind11 finds numpy's C API on first use, inside a C++ function-local static whose import of
  // numpy can hand the GIL to another thread: a second thread making an array then waits for the
  // static with the GIL held, and neither goes on. Found here, while Python imports trubal (one
  // thread), no array call ever waits.
  py::detail::npy_api::get();
  g_masked_array_type = py::object(py::module_::import("numpy.ma").attr("MaskedArray")).release().ptr();
}

void bind_arrays(py::class_<PySession>& cls) {
  const auto& B = [](PySession& s) -> const Balls& { return s.session().model().balls; };
  cls.def_property_readonly("num_balls", [B](PySession& s) { return B(s).size(); }, "How many balls there are.")
      .def_property_readonly("ids", [B](PySession& s) { const auto r = id_rows(B(s)); return column<std::int64_t>(B(s).id, &r); },
                             "Ball ids, ascending: the order of every ball array.")
      .def_property_readonly("types", [B](PySession& s) { const auto r = id_rows(B(s)); return column<std::int32_t>(B(s).type, &r); },
                             "Each ball's type (PROP type).")
      .def_property_readonly(
          "fixed",
          [B](PySession& s) {
            const Balls& b = B(s);
            py::array_t<bool> out({static_cast<py::ssize_t>(b.size()), py::ssize_t{6}});
            auto o = out.mutable_unchecked<2>();
            for (std::size_t k = 0; k < b.size(); ++k)
              for (int d = 0; d < 6; ++d) o(k, d) = (b.fixed[b.by_id[k]] >> d) & 1;
            return read_only(out);
          },
          "(n, 6) bools: which of xvel yvel zvel xspin yspin zspin FIX holds.")
      .def_property(
          "positions", [B](PySession& s) { const auto r = id_rows(B(s)); return columns3(B(s).x, B(s).y, B(s).z, &r); }, set_positions,
          "(n, 3) ball centres. Setting one moves the balls (checked as BALL checks a centre).")
      .def_property(
          "velocities", [B](PySession& s) { const auto r = id_rows(B(s)); return columns3(B(s).vx, B(s).vy, B(s).vz, &r); },
          [](PySession& s, const py::object& v) {
            set_columns3(s, checked(v, s.session().model(), 3, "velocities"), &Balls::vx, &Balls::vy, &Balls::vz);
          },
          "(n, 3) velocities (at t - dt/2 after a cycle, as INIT sets them; a fixed component keeps what is set).")
      .def_property(
          "spins", [B](PySession& s) { const auto r = id_rows(B(s)); return columns3(B(s).wx, B(s).wy, B(s).wz, &r); },
          [](PySession& s, const py::object& v) {
            set_columns3(s, checked(v, s.session().model(), 3, "spins"), &Balls::wx, &Balls::wy, &Balls::wz);
          },
          "(n, 3) angular velocities (rad/s, at t - dt/2).")
      .def_property(
          "radii", [B](PySession& s) { const auto r = id_rows(B(s)); return column<double>(B(s).rad, &r); }, set_radii,
          "(n,) radii; setting them changes the masses from the next step.")
      .def_property_readonly("forces", [B](PySession& s) { const auto r = id_rows(B(s)); return columns3(B(s).fx, B(s).fy, B(s).fz, &r); },
                             "(n, 3) unbalanced forces of the last step (a fixed ball's: its reaction).")
      .def_property_readonly("moments", [B](PySession& s) { const auto r = id_rows(B(s)); return columns3(B(s).mx, B(s).my, B(s).mz, &r); },
                             "(n, 3) unbalanced moments of the last step.")
      .def("contacts", contacts,
           "The ball pairs touching at the last force pass (PRINT contacts): a dict of arrays, one row per "
           "contact sorted by (i, j): i, j (ball ids, i < j), normal (n, 3; unit, from i to j), overlap, "
           "normal_force, shear_force (n, 3; on j), force (n, 3; total on j, on i minus it), sliding (bools); and "
           "cycle, the cycle whose force pass these are (-1: none yet).")
      .def("bonds", bonds,
           "The parallel bonds (BOND), intact and broken, as PRINT bonds lists them: a dict of arrays, one row "
           "per bond sorted by (i, j): i, j (ball ids, i < j), radius, normal_force (compression positive), "
           "shear_force (n, 3; on j), twisting_moment (about the normal, on j), bending_moment (n, 3; on j), "
           "sigma and tau (the largest tensile and shear stresses on the section), intact (bools) and state (0 "
           "intact, 1 broken in tension, 2 in shear; a broken bond keeps the forces that broke it).")
      .def("stress",
           [](PySession& s) {
             return engine_call([&] {
               s.session().require_started();
               return sym_matrix(average_stress(s.session().model(), s.session().stress_volume()));
             });
           },
           "The average stress tensor (3, 3) over SET volume, the periodic cell or the START box, compression "
           "positive (PRINT stress).")
      .def("strain", [](PySession& s) { return sym_matrix(s.session().model().space.strain); },
           "The periodic space's accumulated strain (3, 3), compression positive (PRINT strain): the sum of "
           "rate times step, a logarithmic strain (an edge is about its START length times exp(-strain)).")
      .def("energy", energy,
           "The energy terms (PRINT energy) as a dict: kinetic_translation, kinetic_rotation, strain, potential, "
           "friction_work, rolling_work, damping_work, boundary_work, capillary_work, bond_break_work (the energy the broken bonds held), balance.")
      .def("history", histories,
           "The HIST tables, in the order given: a list with one dict per table, column name -> array "
           "(cycle, time, then the items' columns, as PRINT history names them).")
      .def("walls", walls,
           "The walls (PRINT walls), one dict each: id, kind, position (HIST wall's pos), force, moment, "
           "normal_force, stress (nan without an area), contacts, work, velocity (and radius for a cylinder).")
      .def_property_readonly("step", [](PySession& s) { return s.session().model().cycle; },
                             "Cycles done since START (the cycle number).")
      .def_property_readonly("time", [](PySession& s) { return s.session().model().time; }, "Model time.")
      .def_property_readonly("timestep", [](PySession& s) { return s.session().model().dt; },
                             "The step of the last cycle (0 before the first).");
}

}  // namespace trubal::python
