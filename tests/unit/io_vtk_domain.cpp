// DUMP vtk writes the domain (the START box or the periodic cell) as its own file, part 3 of the
// collection; read back with VTK's XML reader (python3-vtk9), as io_vtk_walls.cpp reads the walls.
#include <array>
#include <cmath>
#include <set>

#include <fmt/format.h>

#include "io/vtk.hpp"
#include "io_support.hpp"

using namespace trubal;
using namespace trubal::test;

namespace {

const std::vector<double>& field(const Fields& f, const std::string& name) {
  auto it = f.find(name);
  if (it == f.end()) FAIL("no line " << name << " in the reader's output");
  return it->second;
}

// The corner lo + H s of a domain for s in {0, 1}^3 given as bits (x 1, y 2, z 4).
std::array<double, 3> corner(const Space& s, int bits) {
  const auto L = s.length();
  const double edge[3][3] = {{L[0], 0, 0}, {s.tilt[0], L[1], 0}, {s.tilt[1], s.tilt[2], L[2]}};
  std::array<double, 3> p = s.lo;
  for (int a = 0; a < 3; ++a)
    if (bits >> a & 1)
      for (int c = 0; c < 3; ++c) p[c] += edge[a][c];
  return p;
}

// Checks the file against the domain: 8 corners, 12 edges each joining two corners that differ
// along its axis alone, and the periodic flag of that axis.
void check_domain(const TempDir& dir, const std::string& file, const Space& space) {
  const Fields f = read_vtp(dir, file);
  REQUIRE(field(f, "points") == std::vector<double>{8});
  CHECK(field(f, "lines") == std::vector<double>{12});
  CHECK(field(f, "polys") == std::vector<double>{0});
  CHECK(field(f, "verts") == std::vector<double>{0});
  // The points are the corners, exactly: the file holds the doubles themselves.
  std::vector<std::array<double, 3>> points;
  for (int k = 0; k < 8; ++k) {
    const auto& p = field(f, fmt::format("p{}", k));
    REQUIRE(p.size() == 3);
    points.push_back({p[0], p[1], p[2]});
    const auto want = corner(space, k);
    for (int c = 0; c < 3; ++c) CHECK(p[c] == want[c]);
  }
  const auto& axis = field(f, "cd:axis");
  const auto& periodic = field(f, "cd:periodic");
  REQUIRE(axis.size() == 1 + 12);   // the component count, then the values
  REQUIRE(periodic.size() == 1 + 12);
  std::set<std::pair<std::int64_t, std::int64_t>> edges;
  for (int n = 0; n < 12; ++n) {
    const auto& ids = field(f, fmt::format("line{}", n));
    REQUIRE(ids.size() == 2);
    const auto a = static_cast<std::int64_t>(ids[0]), b = static_cast<std::int64_t>(ids[1]);
    const int along = static_cast<int>(axis[1 + n]);
    CHECK((a ^ b) == (1 << along));   // the two corners differ in that axis's bit alone
    CHECK(periodic[1 + n] == (space.wraps(along) ? 1 : 0));
    edges.insert({std::min(a, b), std::max(a, b)});
  }
  CHECK(edges.size() == 12);   // every edge of the box once
}

}  // namespace

TEST_CASE("vtk domain: a sheared periodic cell is written as its parallelepiped", "[io][vtk]") {
  TempDir dir;
  WorkingDir wd(dir.path());
  Harness h;
  REQUIRE(h.deck("start 10 12 14\nprop kn 1e6 ks 1e6 dens 1000\nball 5 5 5 1\ntstep 0.01\n"
                 "strain 1e-3 0 -2e-3 1e-3 5e-4 -1e-3\ncycle 100\ndump vtk snap\n"));
  INFO(h.err.str());
  CHECK_THAT(h.out.str(), Catch::Contains("snap_domain_000100.vtp"));
  const Space& s = h.session.model().space;
  // The cell has tilted and changed size, so the corners are not the START values.
  REQUIRE(s.tilt[0] != 0);
  REQUIRE(s.tilt[1] != 0);
  REQUIRE(s.tilt[2] != 0);
  REQUIRE(s.length()[0] != 10);
  check_domain(dir, (dir.path() / "snap_domain_000100.vtp").string(), s);
}

TEST_CASE("vtk domain: a box periodic along x only, and the collection's part 3", "[io][vtk][system]") {
  TempDir dir;
  WorkingDir wd(dir.path());
  Harness h;
  REQUIRE(h.deck("start box -1 3 0 2 -5 5 x periodic\nprop kn 1e6 ks 1e6 dens 1000\nball 0 1 0 0.5\n"
                 "dump vtk out/run every 5\ncycle 10\n"));
  INFO(h.err.str());
  check_domain(dir, (dir.path() / "out/run_domain_000010.vtp").string(), h.session.model().space);
  const std::string pvd = slurp(dir.path() / "out/run.pvd");
  for (const char* cycle : {"000000", "000005", "000010"})
    CHECK_THAT(pvd, Catch::Contains(fmt::format("part=\"3\" file=\"run_domain_{}.vtp\"/>", cycle)));
  // Every file the collection names reads with VTK; the domains have 8 points and no polygons.
  std::string domains;
  for (const auto& line : lines_of(read_pvd(dir, "out/run.pvd")))
    if (line.rfind("3 ", 0) == 0) domains += line + "\n";
  CHECK(domains == "3 run_domain_000000.vtp 8 0\n3 run_domain_000005.vtp 8 0\n3 run_domain_000010.vtp 8 0\n");
}
