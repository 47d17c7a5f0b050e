#include "io/vtk.hpp"

#include "model/bond_table.hpp"
#include "model/edit.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <exception>
#include <map>
#include <memory>
#include <stdexcept>

#include <unistd.h>

#include <fmt/format.h>

#include "model/periodic_cell.hpp"
#include "model/wall_shape.hpp"
#include "io/atomic_file.hpp"

namespace trubal {
namespace {

static_assert(std::endian::native == std::endian::little, "the VTK files are declared LittleEndian");

// The appended arrays of a PolyData piece and its XML: each array's place in the appended block
// (its UInt64 byte count, then its bytes), in the order they are declared.
class PolyDataLayout {
 public:
  // The array's place in the appended block.
  std::uint64_t array(std::string_view section, std::string_view type, std::string_view name, int components,
                      std::uint64_t bytes) {
    std::string& xml = sections_[std::string(section)];
    xml += fmt::format("        <DataArray type=\"{}\" Name=\"{}\" NumberOfComponents=\"{}\" format=\"appended\" "
                       "offset=\"{}\"/>\n",
                       type, name, components, size_);
    const std::uint64_t at = size_;
    size_ += sizeof(std::uint64_t) + bytes;
    return at;
  }
  // The file up to the appended block, and after it.
  std::string head(std::uint64_t points, std::uint64_t verts, std::uint64_t lines, std::uint64_t polys) const {
    std::string out =
        "<?xml version=\"1.0\"?>\n"
        "<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n"
        "  <PolyData>\n";
    out += fmt::format("    <Piece NumberOfPoints=\"{}\" NumberOfVerts=\"{}\" NumberOfLines=\"{}\" "
                       "NumberOfStrips=\"0\" NumberOfPolys=\"{}\">\n",
                       points, verts, lines, polys);
    for (const char* s : {"PointData", "CellData", "Points", "Verts", "Lines", "Polys"}) {
      auto it = sections_.find(s);
      if (it == sections_.end()) continue;
      out += fmt::format("      <{}>\n{}      </{}>\n", s, it->second, s);
    }
    return out + "    </Piece>\n  </PolyData>\n  <AppendedData encoding=\"raw\">\n   _";
  }
  static constexpr std::string_view kTail = "\n  </AppendedData>\n</VTKFile>\n";
  std::uint64_t size() const { return size_; }

 private:
  std::map<std::string, std::string> sections_;
  std::uint64_t size_ = 0;
};

// A PolyData piece built in memory (the small files: walls, domain, bonds).
class PolyDataWriter {
 public:
  void array(std::string_view section, std::string_view type, std::string_view name, int components,
             const void* data, std::size_t bytes) {
    layout_.array(section, type, name, components, bytes);
    const std::uint64_t count = bytes;
    appended_.append(reinterpret_cast<const char*>(&count), sizeof count);
    if (bytes) appended_.append(static_cast<const char*>(data), bytes);
  }
  template <class T>
  void array(std::string_view section, std::string_view type, std::string_view name, const std::vector<T>& v,
             int components = 1) {
    array(section, type, name, components, v.data(), v.size() * sizeof(T));
  }

  void write(const std::string& path, std::size_t points, std::size_t verts, std::size_t lines, std::size_t polys = 0) {
    write_file_atomically(path, [&](std::ostream& out) {
      out << layout_.head(points, verts, lines, polys);
      out.write(appended_.data(), static_cast<std::streamsize>(appended_.size()));
      out << PolyDataLayout::kTail;
    });
  }

 private:
  PolyDataLayout layout_;
  std::string appended_;
};

// An array of a file written a row at a time: per row, `per_row` values of `kind`: Real, the row's
// values from `first` on (Float64); Bits, the row's value at `first` as an Int64's bits; Int32, that
// value as an Int32; Count, an Int64 counter: the row's number times `step`, plus `add`, plus the
// value's place in the row.
struct RowField {
  enum Kind { Real, Bits, Int32, Count };
  const char* section;
  const char* name;
  int components;
  std::size_t per_row;
  Kind kind;
  std::size_t first = 0;
  std::int64_t step = 0, add = 0;
  std::size_t value_bytes() const { return kind == Int32 ? 4 : 8; }
  const char* type() const { return kind == Real ? "Float64" : kind == Int32 ? "Int32" : "Int64"; }
};

// A PolyData file written a row at a time into a temporary beside it: each array's values go to
// its place in the file through a buffer of its own. finish() renames it over the target.
class RowsFile {
 public:
  RowsFile(const std::string& path, const std::vector<RowField>& fields, std::uint64_t rows, std::uint64_t points,
           std::uint64_t verts, std::uint64_t lines)
      : path_(path), fields_(fields) {
    check_replaceable(path);
    tmp_ = std::make_unique<TemporaryFile>(path);
    PolyDataLayout layout;
    std::vector<std::uint64_t> at, bytes;
    for (const RowField& f : fields) {
      bytes.push_back(rows * f.per_row * f.value_bytes());
      at.push_back(layout.array(f.section, f.type(), f.name, f.components, bytes.back()));
    }
    const std::string head = layout.head(points, verts, lines, 0);
    place(0, head.data(), head.size());
    for (std::size_t a = 0; a < fields.size(); ++a) {
      place(head.size() + at[a], &bytes[a], sizeof bytes[a]);
      columns_.push_back({head.size() + at[a] + sizeof(std::uint64_t), {}});
      columns_.back().buffer.reserve(kBuffer);
    }
    place(head.size() + layout.size(), PolyDataLayout::kTail.data(), PolyDataLayout::kTail.size());
  }

  void row(const double* r) {
    for (std::size_t a = 0; a < fields_.size(); ++a) {
      const RowField& f = fields_[a];
      std::string& out = columns_[a].buffer;
      for (std::size_t v = 0; v < f.per_row; ++v) {
        switch (f.kind) {
          case RowField::Real: append(out, r[f.first + v]); break;
          case RowField::Bits: append(out, std::bit_cast<std::int64_t>(r[f.first])); break;
          case RowField::Int32: append(out, static_cast<std::int32_t>(r[f.first])); break;
          case RowField::Count: append(out, static_cast<std::int64_t>(rows_) * f.step + f.add + static_cast<std::int64_t>(v)); break;
        }
      }
      if (out.size() >= kBuffer) flush(columns_[a]);
    }
    ++rows_;
  }

  void finish(std::uint64_t rows) {
    if (rows_ != rows) throw std::logic_error("internal error: a dump's rows came short");
    for (Column& c : columns_) flush(c);
    if (!tmp_->close() && !error_) error_ = errno ? errno : EIO;
    if (error_) throw std::runtime_error(fmt::format("cannot write '{}': {}", path_, std::strerror(error_)));
    tmp_->rename_over_target();
  }

 private:
  static constexpr std::size_t kBuffer = std::size_t{1} << 16;
  struct Column {
    std::uint64_t at;
    std::string buffer;
  };
  template <class T> static void append(std::string& out, T v) { out.append(reinterpret_cast<const char*>(&v), sizeof v); }
  void place(std::uint64_t at, const void* data, std::size_t bytes) {
    const char* p = static_cast<const char*>(data);
    while (bytes > 0 && !error_) {
      const ssize_t n = ::pwrite(tmp_->fd(), p, bytes, static_cast<off_t>(at));
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) {
        error_ = n < 0 && errno ? errno : EIO;
        break;
      }
      p += n, at += static_cast<std::uint64_t>(n), bytes -= static_cast<std::size_t>(n);
    }
    if (error_) throw std::runtime_error(fmt::format("cannot write '{}': {}", path_, std::strerror(error_)));
  }
  void flush(Column& c) {
    place(c.at, c.buffer.data(), c.buffer.size());
    c.at += c.buffer.size();
    c.buffer.clear();
  }

  std::string path_;
  std::vector<RowField> fields_;
  std::unique_ptr<TemporaryFile> tmp_;
  std::vector<Column> columns_;
  std::uint64_t rows_ = 0;
  int error_ = 0;
};

// A rows file where `writes`, from one pass of the rows (run in any case: under mpirun a collective
// call); the first failure thrown once the pass is over.
void write_rows(const std::string& path, const std::vector<RowField>& fields, std::uint64_t rows, std::uint64_t points,
                std::uint64_t verts, std::uint64_t lines, bool writes,
                const std::function<void(const VtkRows::Take&)>& pass) {
  std::unique_ptr<RowsFile> file;
  std::exception_ptr failed;
  if (writes) {
    try {
      file = std::make_unique<RowsFile>(path, fields, rows, points, verts, lines);
    } catch (...) {
      failed = std::current_exception();
    }
  }
  if (!writes) {
    pass(nullptr);
  } else {
    pass([&](const double* row) {
      if (failed) return;
      try {
        file->row(row);
      } catch (...) {
        failed = std::current_exception();
      }
    });
  }
  if (failed) std::rethrow_exception(failed);
  if (file) file->finish(rows);
}

const std::vector<RowField> kBallFields = {
    {"Points", "Points", 3, 3, RowField::Real, 1},
    {"Verts", "connectivity", 1, 1, RowField::Count, 0, 1, 0},
    {"Verts", "offsets", 1, 1, RowField::Count, 0, 1, 1},
    {"PointData", "id", 1, 1, RowField::Bits, 4},
    {"PointData", "type", 1, 1, RowField::Int32, 5},
    {"PointData", "radius", 1, 1, RowField::Real, 6},
    {"PointData", "velocity", 3, 3, RowField::Real, 7},
    {"PointData", "spin", 3, 3, RowField::Real, 10},
    {"PointData", "force", 3, 3, RowField::Real, 13},
};

const std::vector<RowField> kLineFields = {
    {"Points", "Points", 3, 6, RowField::Real, 1},
    {"Lines", "connectivity", 1, 2, RowField::Count, 0, 2, 0},
    {"Lines", "offsets", 1, 1, RowField::Count, 0, 2, 2},
    {"CellData", "normal_force", 1, 1, RowField::Real, 7},
    {"CellData", "force", 3, 3, RowField::Real, 8},
    {"CellData", "id_i", 1, 1, RowField::Bits, 11},
    {"CellData", "id_j", 1, 1, RowField::Bits, 12},
};

// 0 .. n-1 and 1 .. n (or 2, 4, .. 2n): a cell per point, or a line per pair of points.
std::vector<std::int64_t> iota64(std::size_t n, std::int64_t step, std::int64_t first) {
  std::vector<std::int64_t> v(n);
  for (std::size_t k = 0; k < n; ++k) v[k] = first + static_cast<std::int64_t>(k) * step;
  return v;
}

// Two unit vectors perpendicular to the unit vector n and to each other, with u x v = n: u from
// the coordinate axis least aligned with n.
void perpendicular_pair(const Vec3& n, Vec3& u, Vec3& v) {
  const double ax = std::abs(n[0]), ay = std::abs(n[1]), az = std::abs(n[2]);
  const Vec3 e = ax <= ay && ax <= az ? Vec3{1, 0, 0} : ay <= az ? Vec3{0, 1, 0} : Vec3{0, 0, 1};
  // u = e - (e.n) n, normalised
  const double en = e[0] * n[0] + e[1] * n[1] + e[2] * n[2];
  u = {e[0] - en * n[0], e[1] - en * n[1], e[2] - en * n[2]};
  const double lu = std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
  for (double& c : u) c /= lu;
  v = {n[1] * u[2] - n[2] * u[1], n[2] * u[0] - n[0] * u[2], n[0] * u[1] - n[1] * u[0]};   // n x u
}

}  // namespace

std::uint64_t ModelRows::lines() {
  std::uint64_t n = 0;
  for (std::size_t p = 0; p < model_.contacts.size(); ++p) n += vtk_line(model_, p);
  return n;
}

void ModelRows::ball_rows(const Take& take) {
  double row[kVtkBallRow];
  for (std::size_t k = 0; k < model_.balls.size(); ++k) {
    vtk_ball_row(model_.balls, k, row);
    row[0] = static_cast<double>(k);
    take(row);
  }
}

void ModelRows::line_rows(const Take& take) {
  const CellFrame frame = cell_frame(model_.space);
  const ContactTable& c = model_.contacts;
  double row[kVtkLineRow];
  for (std::size_t p = 0; p < c.size(); ++p)
    if (vtk_line_row(model_, frame, p, row)) {
      row[0] = static_cast<double>(c.i[p]);
      take(row);
    }
}

void write_bonds_vtp(const Model& model, const std::string& path) {
  const Balls& b = model.balls;
  const Bonds& t = model.bonds;
  const CellFrame frame = cell_frame(model.space);
  // Cracks (broken bonds) first, as vertex cells, then intact bonds as lines: VTK orders the cell
  // data verts before lines.
  std::vector<double> crack_points, bond_points;
  std::vector<std::int64_t> crack_i, crack_j, bond_i, bond_j;
  std::vector<std::int32_t> crack_state;
  std::vector<double> crack_fn, bond_fn;
  for (std::size_t q : bond_rows_by_id(t)) {
    const std::int64_t fi = find_ball(model, t.id_i[q]), fj = find_ball(model, t.id_j[q]);
    if (fi < 0 || fj < 0) continue;
    const std::size_t i = static_cast<std::size_t>(fi), j = static_cast<std::size_t>(fj);
    // j at its image nearest i (the one the bond acts across).
    double d[3] = {b.x[j] - b.x[i], b.y[j] - b.y[i], b.z[j] - b.z[i]};
    if (model.space.periodic) {
      std::int8_t ix, iy, iz;
      nearest_image(frame, d[0], d[1], d[2], ix, iy, iz);
      double o[3];
      image_offset(frame, ix, iy, iz, o[0], o[1], o[2]);
      d[0] = image_delta(b.x[j], b.x[i], o[0]); d[1] = image_delta(b.y[j], b.y[i], o[1]); d[2] = image_delta(b.z[j], b.z[i], o[2]);
    }
    if (t.fate[q] == 0) {
      bond_points.insert(bond_points.end(), {b.x[i], b.y[i], b.z[i], b.x[i] + d[0], b.y[i] + d[1], b.z[i] + d[2]});
      bond_fn.push_back(t.fn[q]);
      bond_i.push_back(t.id_i[q]);
      bond_j.push_back(t.id_j[q]);
      continue;
    }
    // A crack where the bond was: the middle of the gap between the surfaces.
    const double len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    const double at = len > 0 ? (b.rad[i] + 0.5 * (len - b.rad[i] - b.rad[j])) / len : 0.5;
    crack_points.insert(crack_points.end(), {b.x[i] + at * d[0], b.y[i] + at * d[1], b.z[i] + at * d[2]});
    crack_fn.push_back(t.fn[q]);
    crack_state.push_back(t.fate[q]);
    crack_i.push_back(t.id_i[q]);
    crack_j.push_back(t.id_j[q]);
  }
  const std::size_t cracks = crack_fn.size(), lines = bond_fn.size();
  std::vector<double> points = crack_points;
  points.insert(points.end(), bond_points.begin(), bond_points.end());
  auto joined = [](auto a, const auto& b) { a.insert(a.end(), b.begin(), b.end()); return a; };
  std::vector<std::int32_t> state = crack_state;
  state.resize(cracks + lines, 0);
  PolyDataWriter w;
  w.array("Points", "Float64", "Points", points, 3);
  w.array("Verts", "Int64", "connectivity", iota64(cracks, 1, 0));
  w.array("Verts", "Int64", "offsets", iota64(cracks, 1, 1));
  w.array("Lines", "Int64", "connectivity", iota64(2 * lines, 1, static_cast<std::int64_t>(cracks)));
  w.array("Lines", "Int64", "offsets", iota64(lines, 2, 2));
  w.array("CellData", "Int32", "state", state);
  w.array("CellData", "Float64", "normal_force", joined(crack_fn, bond_fn));
  w.array("CellData", "Int64", "id_i", joined(crack_i, bond_i));
  w.array("CellData", "Int64", "id_j", joined(crack_j, bond_j));
  w.write(path, cracks + 2 * lines, cracks, lines);
}

void write_walls_vtp(const Model& model, const std::string& path) {
  const auto box = model.space.length();
  const double side = std::sqrt(box[0] * box[0] + box[1] * box[1] + box[2] * box[2]);
  std::vector<double> points, force;
  std::vector<std::int64_t> connectivity, offsets, id;
  auto point = [&](const Vec3& p) {
    points.insert(points.end(), {p[0], p[1], p[2]});
    return static_cast<std::int64_t>(points.size() / 3 - 1);
  };
  auto cell = [&](const Wall& w, const std::vector<std::int64_t>& corners) {
    connectivity.insert(connectivity.end(), corners.begin(), corners.end());
    offsets.push_back(static_cast<std::int64_t>(connectivity.size()));
    id.push_back(w.id);
    force.insert(force.end(), {w.force[0], w.force[1], w.force[2]});
  };
  for (const Wall& w : model.walls) {
    switch (w.kind) {
      case WallKind::Plane: {   // a square of side `side` centred on the point, counter-clockwise about n
        Vec3 u, v;
        perpendicular_pair(w.normal, u, v);
        const double h = side / 2;
        std::int64_t k[4];
        const double su[4] = {-h, h, h, -h}, sv[4] = {-h, -h, h, h};
        for (int c = 0; c < 4; ++c)
          k[c] = point({w.point[0] + su[c] * u[0] + sv[c] * v[0], w.point[1] + su[c] * u[1] + sv[c] * v[1],
                        w.point[2] + su[c] * u[2] + sv[c] * v[2]});
        cell(w, {k[0], k[1], k[2], k[3]});
        break;
      }
      case WallKind::Polygon: {   // one cell, the vertices in their order
        std::vector<std::int64_t> corners;
        for (const Vec3& p : w.vertices) corners.push_back(point(p));
        if (!corners.empty()) cell(w, corners);   // complete_wall rejects fewer than three
        break;
      }
      case WallKind::Cylinder: {   // kCylinderSegments quads around, one band along the axis, facing out
        Vec3 u, v;
        perpendicular_pair(w.normal, u, v);
        const std::int64_t first = static_cast<std::int64_t>(points.size() / 3);
        for (int end = 0; end < 2; ++end) {
          const double along = end ? w.length : 0.0;
          for (int s = 0; s < kCylinderSegments; ++s) {
            const double a = 2 * M_PI * s / kCylinderSegments, cu = w.radius * std::cos(a), sv = w.radius * std::sin(a);
            point({w.point[0] + along * w.normal[0] + cu * u[0] + sv * v[0],
                   w.point[1] + along * w.normal[1] + cu * u[1] + sv * v[1],
                   w.point[2] + along * w.normal[2] + cu * u[2] + sv * v[2]});
          }
        }
        for (int s = 0; s < kCylinderSegments; ++s) {
          const std::int64_t a = first + s, b = first + (s + 1) % kCylinderSegments;
          cell(w, {a, b, b + kCylinderSegments, a + kCylinderSegments});
        }
        break;
      }
    }
  }
  const std::size_t polys = offsets.size();
  PolyDataWriter wr;
  wr.array("Points", "Float64", "Points", points, 3);
  wr.array("Polys", "Int64", "connectivity", connectivity);
  wr.array("Polys", "Int64", "offsets", offsets);
  wr.array("CellData", "Int64", "id", id);
  wr.array("CellData", "Float64", "force", force, 3);
  wr.write(path, points.size() / 3, 0, 0, polys);
}

void write_domain_vtp(const Model& model, const std::string& path) {
  // The corners lo + H s, s in {0, 1}^3, H's columns the edge vectors (tilted in a sheared cell).
  const Space& s = model.space;
  const auto L = s.length();
  const Vec3 edge[3] = {{L[0], 0, 0}, {s.tilt[0], L[1], 0}, {s.tilt[1], s.tilt[2], L[2]}};
  std::vector<double> points;
  for (int k = 0; k < 8; ++k) {
    Vec3 p = s.lo;
    for (int a = 0; a < 3; ++a)
      if (k >> a & 1)
        for (int c = 0; c < 3; ++c) p[c] += edge[a][c];
    points.insert(points.end(), {p[0], p[1], p[2]});
  }
  // The 12 edges: from each corner without bit a to the corner with it.
  std::vector<std::int64_t> connectivity;
  std::vector<std::int32_t> axis, periodic;
  for (int a = 0; a < 3; ++a)
    for (int k = 0; k < 8; ++k)
      if (!(k >> a & 1)) {
        connectivity.insert(connectivity.end(), {k, k | 1 << a});
        axis.push_back(a);
        periodic.push_back(s.wraps(a) ? 1 : 0);
      }
  PolyDataWriter w;
  w.array("Points", "Float64", "Points", points, 3);
  w.array("Lines", "Int64", "connectivity", connectivity);
  w.array("Lines", "Int64", "offsets", iota64(axis.size(), 2, 2));
  w.array("CellData", "Int32", "axis", axis);
  w.array("CellData", "Int32", "periodic", periodic);
  w.write(path, 8, 0, axis.size());
}

VtkSeries::VtkSeries(std::string base, std::int64_t every) : base_(std::move(base)), every_(every) {
  for (const char* ext : {".vtp", ".pvd", ".VTP", ".PVD"})
    if (base_.size() > 4 && base_.ends_with(ext)) base_.resize(base_.size() - 4);
  if (base_.empty()) throw std::runtime_error("DUMP needs a file name");
}

std::string VtkSeries::balls_path(std::int64_t cycle) const { return fmt::format("{}_{:06d}.vtp", base_, cycle); }

std::string VtkSeries::contacts_path(std::int64_t cycle) const {
  return fmt::format("{}_contacts_{:06d}.vtp", base_, cycle);
}

std::string VtkSeries::walls_path(std::int64_t cycle) const { return fmt::format("{}_walls_{:06d}.vtp", base_, cycle); }

std::string VtkSeries::bonds_path(std::int64_t cycle) const { return fmt::format("{}_bonds_{:06d}.vtp", base_, cycle); }

std::string VtkSeries::domain_path(std::int64_t cycle) const {
  return fmt::format("{}_domain_{:06d}.vtp", base_, cycle);
}

void VtkSeries::write(const Model& model, VtkRows* rows) {
  ModelRows own(model);
  VtkRows& from = rows ? *rows : own;
  const bool writes = from.writes();
  // (Every pass runs whatever failed before it: under mpirun each is a collective call.)
  std::exception_ptr failed;
  auto attempt = [&](const std::function<void()>& work) {
    try {
      work();
    } catch (...) {
      if (!failed) failed = std::current_exception();
    }
  };
  const std::uint64_t n = model.balls.size();
  attempt([&] {
    write_rows(balls_path(model.cycle), kBallFields, n, n, n, 0, writes, [&](const VtkRows::Take& take) { from.ball_rows(take); });
  });
  attempt([&] {
    const std::uint64_t lines = from.lines();
    write_rows(contacts_path(model.cycle), kLineFields, lines, 2 * lines, 0, lines, writes,
               [&](const VtkRows::Take& take) { from.line_rows(take); });
  });
  const bool walls = !model.walls.empty();
  const bool bonds = !model.bonds.empty();
  if (writes) {
    if (walls) attempt([&] { write_walls_vtp(model, walls_path(model.cycle)); });
    attempt([&] { write_domain_vtp(model, domain_path(model.cycle)); });
    if (bonds) attempt([&] { write_bonds_vtp(model, bonds_path(model.cycle)); });
  }
  if (failed) std::rethrow_exception(failed);
  // A second dump at the same cycle replaces the first.
  if (!entries_.empty() && entries_.back().cycle == model.cycle) entries_.pop_back();
  entries_.push_back({model.cycle, model.time, walls, bonds});
  if (writes) write_pvd();
}

void VtkSeries::write_pvd() const {
  // The collection names the dumps relative to its own folder.
  auto leaf = [](const std::string& p) {
    auto slash = p.find_last_of('/');
    std::string name = slash == std::string::npos ? p : p.substr(slash + 1), xml;
    for (char ch : name) {
      switch (ch) {
        case '&': xml += "&amp;"; break;
        case '<': xml += "&lt;"; break;
        case '>': xml += "&gt;"; break;
        case '"': xml += "&quot;"; break;
        default: xml += ch;
      }
    }
    return xml;
  };
  std::string xml =
      "<?xml version=\"1.0\"?>\n"
      "<VTKFile type=\"Collection\" version=\"1.0\" byte_order=\"LittleEndian\">\n"
      "  <Collection>\n";
  for (const Entry& e : entries_) {
    xml += fmt::format("    <DataSet timestep=\"{}\" part=\"0\" file=\"{}\"/>\n", e.time, leaf(balls_path(e.cycle)));
    xml += fmt::format("    <DataSet timestep=\"{}\" part=\"1\" file=\"{}\"/>\n", e.time,
                       leaf(contacts_path(e.cycle)));
    if (e.walls)
      xml += fmt::format("    <DataSet timestep=\"{}\" part=\"2\" file=\"{}\"/>\n", e.time, leaf(walls_path(e.cycle)));
    xml += fmt::format("    <DataSet timestep=\"{}\" part=\"3\" file=\"{}\"/>\n", e.time, leaf(domain_path(e.cycle)));
    if (e.bonds)
      xml += fmt::format("    <DataSet timestep=\"{}\" part=\"4\" file=\"{}\"/>\n", e.time, leaf(bonds_path(e.cycle)));
  }
  xml += "  </Collection>\n</VTKFile>\n";
  write_file_atomically(pvd_path(), xml);
}

}  // namespace trubal
