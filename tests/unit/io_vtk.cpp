// DUMP vtk: the files are read back with VTK's own XML reader (python3-vtk9), so what ParaView
// sees is checked, not just that a file exists.
#include <cmath>
#include <map>
#include <set>

#include <fmt/format.h>

#include "io_support.hpp"

using namespace trubal;
using namespace trubal::test;

namespace {




// An array's values (the component count that leads the line dropped).
std::vector<double> array_of(const Fields& f, const std::string& name) {
  auto it = f.find(name);
  if (it == f.end()) FAIL("no array " << name);
  return std::vector<double>(it->second.begin() + 1, it->second.end());
}

}  // namespace

TEST_CASE("io_vtk: balls and force chains read back with VTK's reader", "[io][vtk]") {
  TempDir dir;
  WorkingDir wd(dir.path());
  Harness h;
  REQUIRE(h.deck(std::string(kPressedRow) + "cycle 3\ndump vtk snap\n"));
  INFO(h.err.str());
  const Model& m = h.session.model();
  REQUIRE(m.cycle == 3);

  // The balls: one point and one vertex each, every array exact (binary, 64-bit).
  Fields balls = read_vtp(dir, (dir.path() / "snap_000003.vtp").string());
  CHECK(balls["points"] == std::vector<double>{4});
  CHECK(balls["verts"] == std::vector<double>{4});
  CHECK(balls["lines"] == std::vector<double>{0});
  const auto id = array_of(balls, "pd:id"), type = array_of(balls, "pd:type"), rad = array_of(balls, "pd:radius");
  const auto vel = array_of(balls, "pd:velocity"), spin = array_of(balls, "pd:spin");
  REQUIRE(vel.size() == 12);
  REQUIRE(spin.size() == 12);
  CHECK(array_of(balls, "pd:force").size() == 12);
  for (std::size_t k = 0; k < 4; ++k) {
    const std::string point = fmt::format("p{}", k);
    CHECK(balls[point] == std::vector<double>{m.balls.x[k], m.balls.y[k], m.balls.z[k]});
    CHECK(id[k] == static_cast<double>(m.balls.id[k]));
    CHECK(type[k] == m.balls.type[k]);
    CHECK(rad[k] == m.balls.rad[k]);
    CHECK(vel[3 * k] == m.balls.vx[k]);
    CHECK(vel[3 * k + 2] == m.balls.vz[k]);
    CHECK(spin[3 * k + 1] == m.balls.wy[k]);
  }
  // (The points in the model's order in memory: found by id.)
  CHECK(type[trubal::test::at(m, 3)] == 2);
  CHECK(vel[3 * trubal::test::at(m, 4) + 2] == 0.25);   // ball 4 moves freely at its initial speed (no gravity, no contact)
  CHECK(vel[3 * trubal::test::at(m, 1)] < 0);           // ball 1 is pushed away from ball 2

  // The force chains: a line per touching pair (1-2, 2-3; ball 4 touches nothing) between the
  // centres, normal force as cell data equal to the contact table's.
  Fields chains = read_vtp(dir, (dir.path() / "snap_contacts_000003.vtp").string());
  CHECK(chains["points"] == std::vector<double>{4});
  CHECK(chains["lines"] == std::vector<double>{2});
  CHECK(chains["line0"] == std::vector<double>{0, 1});
  CHECK(chains["line1"] == std::vector<double>{2, 3});
  // Each line between its pair's centres: the pairs 1-2 and 2-3, in the contact table's order.
  const auto id_i = array_of(chains, "cd:id_i"), id_j = array_of(chains, "cd:id_j");
  REQUIRE(id_i.size() == 2);
  REQUIRE(id_j.size() == 2);
  std::set<std::pair<double, double>> pairs;
  for (std::size_t l = 0; l < 2; ++l) {
    pairs.insert({std::min(id_i[l], id_j[l]), std::max(id_i[l], id_j[l])});
    for (int end = 0; end < 2; ++end) {
      const std::size_t k = trubal::test::at(m, static_cast<std::int64_t>(end == 0 ? id_i[l] : id_j[l]));
      CHECK(chains[fmt::format("p{}", 2 * l + end)] == std::vector<double>{m.balls.x[k], m.balls.y[k], m.balls.z[k]});
    }
  }
  CHECK(pairs == std::set<std::pair<double, double>>{{1, 2}, {2, 3}});
  const auto fn = array_of(chains, "cd:normal_force");
  REQUIRE(fn.size() == 2);
  std::vector<double> expected;
  for (std::size_t p = 0; p < m.contacts.size(); ++p)
    if (m.contacts.state[p] != 0) expected.push_back(std::abs(m.contacts.fn[p]));
  CHECK(fn == expected);
  // kn x overlap, below 1e6 x 0.1: the pressed balls spring apart (no damping), so the overlap
  // has shrunk a little in three steps, but the contact is far from open.
  CHECK(fn[0] > 0.8e5);
  CHECK(fn[0] < 1e5);
  CHECK(array_of(chains, "cd:force").size() == 6);
}

TEST_CASE("io_vtk: periodic dumps, DUMP off, and the .pvd collection with the times", "[io][vtk][system]") {
  TempDir dir;
  WorkingDir wd(dir.path());
  fs::create_directory(dir.path() / "out");
  Harness h;
  REQUIRE(h.deck(std::string(kPressedRow) + "hist time every 5\ndump vtk out/run.vtp every 5\n"));
  INFO(h.err.str());
  REQUIRE(h.deck("cycle 12\ndump off\ncycle 10\n"));
  for (const char* f : {"out/run_000000.vtp", "out/run_000005.vtp", "out/run_000010.vtp", "out/run_contacts_000010.vtp",
                        "out/run.pvd"})
    CHECK(fs::exists(dir.path() / f));
  CHECK_FALSE(fs::exists(dir.path() / "out/run_000015.vtp"));   // dumps were off by then
  CHECK_FALSE(fs::exists(dir.path() / "out/run_000020.vtp"));
  for (const auto& e : fs::directory_iterator(dir.path() / "out")) CHECK(e.path().string().find(".tmp") == std::string::npos);

  // The collection: three parts per dump, times those of HIST time at the same cycles.
  const std::string pvd = slurp(dir.path() / "out/run.pvd");
  const auto& rows = h.session.history().tables().front()->rows;   // cycles 5, 10, 15, 20
  REQUIRE(rows.size() >= 2);
  CHECK_THAT(pvd, Catch::Contains("type=\"Collection\""));
  CHECK_THAT(pvd, Catch::Contains("<DataSet timestep=\"0\" part=\"0\" file=\"run_000000.vtp\"/>"));
  CHECK_THAT(pvd, Catch::Contains(fmt::format("<DataSet timestep=\"{}\" part=\"1\" file=\"run_contacts_000005.vtp\"/>",
                                              rows[0][1])));
  CHECK_THAT(pvd, Catch::Contains(fmt::format("<DataSet timestep=\"{}\" part=\"0\" file=\"run_000010.vtp\"/>",
                                              rows[1][1])));
  std::size_t datasets = 0;
  for (std::size_t at = 0; (at = pvd.find("<DataSet", at)) != std::string::npos; ++at) ++datasets;
  CHECK(datasets == 9);   // balls, contacts and the domain (part 3) of three dumps

  // The collection parses as XML and every file it names reads with VTK. Chains: none before the
  // first step computed forces (cycle 0), two lines at cycle 5, none at cycle 10 (the pressed balls,
  // undamped, have sprung apart).
  CHECK(read_pvd(dir, "out/run.pvd") ==
        "0 run_000000.vtp 4 0\n1 run_contacts_000000.vtp 0 0\n3 run_domain_000000.vtp 8 0\n0 run_000005.vtp 4 0\n"
        "1 run_contacts_000005.vtp 4 0\n3 run_domain_000005.vtp 8 0\n"
        "0 run_000010.vtp 4 0\n1 run_contacts_000010.vtp 0 0\n3 run_domain_000010.vtp 8 0\n");
}

TEST_CASE("io_vtk: DUMP errors say what is wrong", "[io][vtk]") {
  TempDir dir;
  WorkingDir wd(dir.path());
  Harness h;
  CHECK_FALSE(h.deck("dump vtk x\n"));
  CHECK_THAT(h.first_error_line(), Catch::Contains("no model yet"));
  Harness g;   // a folder where the file goes: the system's reason ("dump vtk out/x" makes out/ itself)
  fs::create_directory(dir.path() / "x_000000.vtp");
  CHECK_FALSE(g.deck(std::string(kPressedRow) + "dump vtk x\n"));
  CHECK_THAT(g.first_error_line(), Catch::Contains("'x_000000.vtp'"));
  CHECK_THAT(g.first_error_line(), Catch::Contains("directory"));
  Harness k;
  CHECK_FALSE(k.deck(std::string(kPressedRow) + "dump vtk x every 0\n"));
  CHECK_THAT(k.first_error_line(), Catch::Contains("every"));
  Harness f;
  CHECK_FALSE(f.deck(std::string(kPressedRow) + "dump csv x\n"));
  CHECK_THAT(f.first_error_line(), Catch::Contains("vtk"));
}
