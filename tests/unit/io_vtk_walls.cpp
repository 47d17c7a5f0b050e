// DUMP vtk with walls: the walls file is read back with VTK's own XML reader (python3-vtk9), as
// the ball and contact files are in io_vtk.cpp, so what ParaView sees is checked.
#include <cmath>
#include <map>

#include <fmt/format.h>

#include "io/vtk.hpp"
#include "io_support.hpp"

using namespace trubal;
using namespace trubal::test;

namespace {



Fields read_walls_vtp(const TempDir& dir, const std::string& file) { return read_vtp(dir, file); }

// An array's values (the component count that leads the line dropped).
std::vector<double> cell_array(const Fields& f, const std::string& name) {
  auto it = f.find(name);
  if (it == f.end()) FAIL("no cell array " << name);
  REQUIRE_FALSE(it->second.empty());
  return std::vector<double>(it->second.begin() + 1, it->second.end());
}

const std::vector<double>& field(const Fields& f, const std::string& name) {
  auto it = f.find(name);
  if (it == f.end()) FAIL("no line " << name << " in the reader's output");
  return it->second;
}

using V = std::array<double, 3>;
V sub(const V& a, const V& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
double dot(const V& a, const V& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
double norm(const V& a) { return std::sqrt(dot(a, a)); }
V point_of(const Fields& f, std::size_t k) {
  const auto& p = field(f, fmt::format("p{}", k));
  REQUIRE(p.size() == 3);
  return {p[0], p[1], p[2]};
}

// A ball pressed 0.1 into a floor (wall 3), a pentagon (wall 7) and a tilted cylinder (wall 12)
// that no ball touches, in a box of diagonal sqrt(3 * 20^2).
const char* kWalledScene =
    "start box -10 10 -10 10 -10 10\n"
    "prop kn 1e6 ks 1e6 fric 30 dens 1000\n"
    "ball 0 0 -0.1 1 id 1\n"
    "wall id 3 plane 0 0 -1 0 0 1\n"
    "wall id 7 polygon 2 0 5  0.6180339887498949 1.902113032590307 5  -1.618033988749895 1.1755705045849463 5 "
    "-1.618033988749895 -1.1755705045849463 5  0.6180339887498949 -1.902113032590307 5\n"
    "wall id 12 cylinder 1 2 3 1 1 0.5 radius 2.5 length 4 outside\n";

}  // namespace

TEST_CASE("vtk walls: a plane, a polygon and a cylinder read back with VTK's reader", "[io][vtk][walls]") {
  TempDir dir;
  WorkingDir wd(dir.path());
  Harness h;
  REQUIRE(h.deck(std::string(kWalledScene) + "cycle 2\ndump vtk snap\n"));
  INFO(h.err.str());
  CHECK_THAT(h.out.str(), Catch::Contains("snap_walls_000002.vtp"));
  const Model& m = h.session.model();
  REQUIRE(m.walls.size() == 3);
  const Wall& plane = m.walls[0];
  const Wall& polygon = m.walls[1];
  const Wall& cylinder = m.walls[2];
  REQUIRE(plane.id == 3);
  REQUIRE(polygon.id == 7);
  REQUIRE(cylinder.id == 12);

  const Fields f = read_walls_vtp(dir, (dir.path() / "snap_walls_000002.vtp").string());
  // Points: 4 for the plane's square, 5 vertices, 2 rings of 48; cells: 1 + 1 + 48 polygons only.
  constexpr int kSeg = kCylinderSegments;
  CHECK(kSeg == 48);
  CHECK(field(f, "points") == std::vector<double>{4 + 5 + 2 * kSeg});
  CHECK(field(f, "cells") == std::vector<double>{1 + 1 + kSeg});
  CHECK(field(f, "polys") == std::vector<double>{1 + 1 + kSeg});
  CHECK(field(f, "verts") == std::vector<double>{0});
  CHECK(field(f, "lines") == std::vector<double>{0});

  // The wall ids, a cell each (the cylinder's 48 quads all its id).
  const auto id = cell_array(f, "cd:id");
  REQUIRE(id.size() == 2 + kSeg);
  CHECK(id[0] == 3);
  CHECK(id[1] == 7);
  for (int s = 0; s < kSeg; ++s) CHECK(id[2 + s] == 12);

  // The force on each wall, per cell; the floor carries the ball (pushed down, -z), the others nothing.
  const auto force = cell_array(f, "cd:force");
  REQUIRE(force.size() == 3 * (2 + kSeg));
  CHECK(plane.force[2] < -1e4);
  for (int c = 0; c < 3; ++c) {
    CHECK(force[c] == plane.force[c]);
    CHECK(force[3 + c] == polygon.force[c]);
    for (int s = 0; s < kSeg; ++s) CHECK(force[3 * (2 + s) + c] == cylinder.force[c]);
  }

  // The plane: a square in the plane, centred on its point, of side the box's diagonal, turning
  // counter-clockwise about the normal (the balls' side).
  const double side = std::sqrt(3.0) * 20;
  CHECK(field(f, "poly0") == std::vector<double>{0, 1, 2, 3});
  V centre{0, 0, 0};
  for (std::size_t k = 0; k < 4; ++k) {
    const V p = point_of(f, k);
    CHECK(std::abs(dot(sub(p, plane.point), plane.normal)) < 1e-12);
    CHECK(std::abs(norm(sub(p, plane.point)) - side / std::sqrt(2.0)) < 1e-9 * side);
    const V next = point_of(f, (k + 1) % 4);
    CHECK(std::abs(norm(sub(next, p)) - side) < 1e-9 * side);
    for (int c = 0; c < 3; ++c) centre[c] += p[c] / 4;
  }
  CHECK(norm(sub(centre, plane.point)) < 1e-9 * side);
  {
    const V a = sub(point_of(f, 1), point_of(f, 0)), b = sub(point_of(f, 2), point_of(f, 1));
    const V n{a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
    CHECK(dot(n, plane.normal) > 0);
  }

  // The polygon: one cell of its vertices, in their order, exact.
  CHECK(field(f, "poly1") == std::vector<double>{4, 5, 6, 7, 8});
  REQUIRE(polygon.vertices.size() == 5);
  for (std::size_t k = 0; k < 5; ++k) {
    const V p = point_of(f, 4 + k);
    CHECK(p[0] == polygon.vertices[k][0]);
    CHECK(p[1] == polygon.vertices[k][1]);
    CHECK(p[2] == polygon.vertices[k][2]);
  }
  CHECK(polygon.vertices[0] == V{2, 0, 5});

  // The cylinder: two rings of 48 points at the radius from the axis, at its two ends; each quad
  // two neighbours on one ring and the same two on the other.
  const V axis = cylinder.normal;
  CHECK(std::abs(norm(axis) - 1) < 1e-15);
  for (int k = 0; k < 2 * kSeg; ++k) {
    const V d = sub(point_of(f, 9 + k), cylinder.point);
    const double along = dot(d, axis);
    const V radial{d[0] - along * axis[0], d[1] - along * axis[1], d[2] - along * axis[2]};
    CHECK(std::abs(norm(radial) - 2.5) <= 1e-9 * 2.5);
    CHECK(std::abs(along - (k < kSeg ? 0.0 : 4.0)) <= 1e-9 * 4.0);
  }
  for (int s = 0; s < kSeg; ++s) {
    const double a = 9 + s, b = 9 + (s + 1) % kSeg;
    CHECK(field(f, fmt::format("poly{}", 2 + s)) == std::vector<double>{a, b, b + kSeg, a + kSeg});
  }
  // The quads face out: the first quad's normal points away from the axis.
  {
    const V p0 = point_of(f, 9), p1 = point_of(f, 10), p2 = point_of(f, 10 + kSeg);
    const V e1 = sub(p1, p0), e2 = sub(p2, p1);
    const V n{e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
    const V out = sub(p0, cylinder.point);
    CHECK(dot(n, sub(out, V{dot(out, axis) * axis[0], dot(out, axis) * axis[1], dot(out, axis) * axis[2]})) > 0);
  }
}

TEST_CASE("vtk walls: the collection names the walls as part 2, only in dumps with walls", "[io][vtk][walls][system]") {
  TempDir dir;
  WorkingDir wd(dir.path());
  fs::create_directory(dir.path() / "out");
  Harness h;
  REQUIRE(h.deck(std::string(kWalledScene) + "dump vtk out/run every 5\ncycle 10\nwall delete all\ncycle 5\n"));
  INFO(h.err.str());
  for (const char* f : {"out/run_walls_000000.vtp", "out/run_walls_000005.vtp", "out/run_walls_000010.vtp",
                        "out/run_000015.vtp", "out/run_contacts_000015.vtp"})
    CHECK(fs::exists(dir.path() / f));
  CHECK_FALSE(fs::exists(dir.path() / "out/run_walls_000015.vtp"));   // the walls were gone by then
  for (const auto& e : fs::directory_iterator(dir.path() / "out")) CHECK(e.path().string().find(".tmp") == std::string::npos);

  const std::string pvd = slurp(dir.path() / "out/run.pvd");
  CHECK_THAT(pvd, Catch::Contains("<DataSet timestep=\"0\" part=\"2\" file=\"run_walls_000000.vtp\"/>"));
  CHECK_THAT(pvd, Catch::Contains("part=\"2\" file=\"run_walls_000010.vtp\"/>"));
  CHECK_THAT(pvd, !Catch::Contains("run_walls_000015.vtp"));
  std::size_t datasets = 0, walls = 0;
  for (std::size_t at = 0; (at = pvd.find("<DataSet", at)) != std::string::npos; ++at) ++datasets;
  for (std::size_t at = 0; (at = pvd.find("part=\"2\"", at)) != std::string::npos; ++at) ++walls;
  CHECK(datasets == 4 * 3 + 3);   // balls, contacts and domain of four dumps, walls of three
  CHECK(walls == 3);

  // Every file the collection names reads with VTK; a walls file has the three walls' 50 cells.
  std::string walls_files;
  for (const auto& line : lines_of(read_pvd(dir, "out/run.pvd")))
    if (line.rfind("2 ", 0) == 0) walls_files += line + "\n";
  CHECK(walls_files ==
        "2 run_walls_000000.vtp 105 50\n2 run_walls_000005.vtp 105 50\n2 run_walls_000010.vtp 105 50\n");
}

TEST_CASE("vtk walls: no walls, no walls file", "[io][vtk][walls]") {
  TempDir dir;
  WorkingDir wd(dir.path());
  Harness h;
  REQUIRE(h.deck(std::string(kPressedRow) + "dump vtk snap\n"));
  INFO(h.err.str());
  CHECK(fs::exists(dir.path() / "snap_000000.vtp"));
  CHECK_FALSE(fs::exists(dir.path() / "snap_walls_000000.vtp"));
  CHECK_THAT(h.out.str(), !Catch::Contains("walls"));
  CHECK_THAT(slurp(dir.path() / "snap.pvd"), !Catch::Contains("part=\"2\""));
}

TEST_CASE("vtk walls: a walls file that cannot be written is an error naming it", "[io][vtk][walls]") {
  TempDir dir;
  WorkingDir wd(dir.path());
  fs::create_directory(dir.path() / "snap_walls_000000.vtp");   // a directory where the file goes
  Harness h;
  CHECK_FALSE(h.deck(std::string(kWalledScene) + "dump vtk snap\n"));
  CHECK_THAT(h.first_error_line(), Catch::Contains("snap_walls_000000.vtp"));
  CHECK_THAT(h.first_error_line(), Catch::Contains("directory"));
  CHECK(fs::is_directory(dir.path() / "snap_walls_000000.vtp"));
  for (const auto& e : fs::directory_iterator(dir.path())) CHECK(e.path().string().find(".tmp") == std::string::npos);
}

TEST_CASE("vtk: DUMP makes the folder its files go in", "[io][vtk]") {
  TempDir dir;
  WorkingDir wd(dir.path());
  Harness h;
  REQUIRE(h.deck(std::string(kPressedRow) + "dump vtk out/deep/tri\n"));
  CHECK(fs::exists(dir.path() / "out/deep/tri_000000.vtp"));
  CHECK(fs::exists(dir.path() / "out/deep/tri.pvd"));
  // A folder that cannot be made (a file is in the way) is an error with the system's reason.
  dir.write("blocked", "x");
  CHECK_FALSE(h.deck("dump vtk blocked/tri\n"));
  CHECK_THAT(h.first_error_line(), Catch::Contains("cannot make the folder 'blocked'"));
}
