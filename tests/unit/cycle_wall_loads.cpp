// The walls' loads are formed only on the steps that read them (cycle/run.hpp): what a reader sees
// after a CYCLE is the bits a run forming them every step gives, and a moving wall's work is formed
// every step. The wall contacts come from the pair list's rebuilds, within its skin: a ball that
// comes to a wall between two rebuilds is caught as a search every step catches it.
#include <catch2/catch.hpp>

#include <algorithm>
#include <bit>
#include <cstdint>
#include <string>
#include <vector>

#include "counters.hpp"
#include "interp_support.hpp"
#include "io/csv.hpp"

using namespace trubal;
using namespace trubal::test;

namespace {

// Balls falling into a box of five planes (a small pour), one side moving in: its work is not zero.
const std::string kBox =
    "start box 0 0.008 0 0.008 -0.0005 0.03\n"
    "prop type 1 kn 1000 ks 1000 fric 0.5 dens 2500 rest 0.55\n"
    "prop type 2 kn 1000 ks 1000 fric 0.5 rest 0.45\n"
    "wall id 1 plane 0 0 0 0 0 1 type 2\nwall id 2 plane 0 0 0 1 0 0 type 2\n"
    "wall id 3 plane 0.008 0 0 -1 0 0 type 2\nwall id 4 plane 0 0 0 0 1 0 type 2\n"
    "wall id 5 plane 0 0.008 0 0 -1 0 type 2\n"
    "gen 80 0.0005 0.0005 seed 5 range x 0.0004 0.0076 y 0.0004 0.0076 z 0.0004 0.003\n"
    "init xvel 0.2 yvel -0.15 zvel -0.3\ngrav 0 0 -9.81\ntstep 1e-5\nwall id 3 velocity -0.02 0 0\n";

// Every wall's loads and work, as bits.
std::vector<std::uint64_t> wall_bits(const Model& m) {
  std::vector<std::uint64_t> out;
  for (const Wall& w : m.walls) {
    for (double v : w.force) out.push_back(std::bit_cast<std::uint64_t>(v));
    for (double v : w.moment) out.push_back(std::bit_cast<std::uint64_t>(v));
    for (double v : {w.normal_force, w.stiffness, w.work}) out.push_back(std::bit_cast<std::uint64_t>(v));
    out.push_back(static_cast<std::uint64_t>(w.contacts));
  }
  return out;
}

std::int64_t touching(const Model& m) {
  std::int64_t n = 0;
  for (const Wall& w : m.walls) n += w.contacts;
  return n;
}

}  // namespace

TEST_CASE("wall loads: read after a CYCLE of N steps, the bits of N CYCLEs of one step each", "[walls][cuts]") {
  // One CYCLE forms the loads at its last step only; CYCLEs of one step form them at every step.
  constexpr int kSteps = 1200;
  Harness whole, stepped;
  REQUIRE(whole.deck(kBox + "cycle " + std::to_string(kSteps) + "\n"));
  std::string ones = kBox;
  for (int s = 0; s < kSteps; ++s) ones += "cycle 1\n";
  REQUIRE(stepped.deck(ones));
  const Model& a = whole.session.model();
  const Model& b = stepped.session.model();
  REQUIRE(a.cycle == kSteps);
  REQUIRE(b.cycle == kSteps);
  // The scene must load its walls for the check to mean anything: the floor and the moving side.
  REQUIRE(touching(a) > 10);
  REQUIRE(a.walls[2].work != 0);
  CHECK(wall_bits(a) == wall_bits(b));
  CHECK(std::bit_cast<std::uint64_t>(a.energy.boundary_work) == std::bit_cast<std::uint64_t>(b.energy.boundary_work));
  CHECK(std::bit_cast<std::uint64_t>(a.balls.z[7]) == std::bit_cast<std::uint64_t>(b.balls.z[7]));
}

TEST_CASE("wall loads: a HIST of the walls reads the loads of the steps it samples", "[walls][cuts]") {
  // HIST samples every 7 cycles: those steps form the loads; the last sample (cycle 1197) is read
  // against a run that stops there.
  TempDir dir;
  Harness sampled, stopped;
  REQUIRE(sampled.deck(kBox + "hist wall 1 wall 3 every 7 file " + dir.str() + "/h.csv\ncycle 1200\n"));
  REQUIRE(stopped.deck(kBox + "cycle 1197\n"));
  const Model& m = stopped.session.model();
  REQUIRE(touching(m) > 10);
  const std::string csv = slurp(dir.path() / "h.csv");
  // The row of cycle 1197: its wall 1 fz and wall 3 fx, as HIST writes them (the shortest text
  // that reads back to the same double: equal text, equal bits).
  const std::string want_fz = csv_real(m.walls[0].force[2]);
  const std::string want_fx = csv_real(m.walls[2].force[0]);
  INFO(csv.substr(csv.size() > 600 ? csv.size() - 600 : 0));
  const std::size_t row = csv.find("\n1197,");
  REQUIRE(row != std::string::npos);
  const std::string line = csv.substr(row + 1, csv.find('\n', row + 1) - row - 1);
  INFO("row: " << line << "; wall 1 fz " << want_fz << ", wall 3 fx " << want_fx);
  std::vector<std::string> fields;
  for (std::size_t a = 0, b; a <= line.size(); a = b + 1) {
    b = line.find(',', a);
    if (b == std::string::npos) b = line.size();
    fields.push_back(line.substr(a, b - a));
  }
  CHECK(std::find(fields.begin(), fields.end(), want_fz) != fields.end());
  CHECK(std::find(fields.begin(), fields.end(), want_fx) != fields.end());
}

TEST_CASE("wall loads: a wall servo given after a CYCLE reads the loads of that CYCLE's last step", "[walls][cuts]") {
  // CYCLE leaves its last step's contact results to be made when read, but forms the walls' loads
  // at that step: a SERVO wall given after it reads them at the next CYCLE's first step. Against a
  // run whose HIST reads (so forms) every step's loads.
  TempDir dir;
  const std::string servo = "servo wall 1 stress 20 area 6.4e-5\ncycle 50\n";
  Harness plain, sampled;
  REQUIRE(plain.deck(kBox + "cycle 1200\n" + servo));
  REQUIRE(sampled.deck(kBox + "hist wall 1 every 1 file " + dir.str() + "/h.csv\ncycle 1200\n" + servo));
  const Model& a = plain.session.model();
  const Model& b = sampled.session.model();
  REQUIRE(a.walls[0].point[2] != 0);   // the servo moved the floor
  CHECK(std::bit_cast<std::uint64_t>(a.walls[0].point[2]) == std::bit_cast<std::uint64_t>(b.walls[0].point[2]));
  CHECK(wall_bits(a) == wall_bits(b));
}

TEST_CASE("wall contacts: a ball that comes to a wall between rebuilds is caught (the skin rule)", "[walls]") {
  // A ball flies at a plane from five skins away (skin: a fifth of the mean radius, 0.002 here); the
  // kept list is rebuilt when a ball has moved half a skin, every 100 steps here, so the ball
  // becomes a wall candidate at a rebuild before it touches. The same bits as allpairs, which
  // searches every step and keeps no list: a candidate found late would let the ball in deeper.
  const std::string deck =
      "start box -0.1 0.2 -0.1 0.1 -0.1 0.1\nprop kn 1e5 ks 1e5 fric 0.3 dens 1000 rest 0.6\n"
      "wall plane 0 0 0 1 0 0\nball 0.02 0 0 0.01 id 1\nball 0.15 0 0 0.01 id 2\n"
      "init xvel -1 yvel 0.1 range id 1\ntstep 1e-5\ncycle 3000\n";
  Harness kept, searched;
  REQUIRE(kept.deck("backend serial\n" + deck));
  REQUIRE(searched.deck("backend allpairs\n" + deck));
  const Model& a = kept.session.model();
  const Model& b = searched.session.model();
  kept.out.str("");
  REQUIRE(kept.deck("print counters\n"));
  INFO(kept.out.str());
  CHECK(a.balls.vx[0] > 0.3);   // it bounced (restitution 0.6 with the spring's own error)
  CHECK(a.walls[0].work == 0);
  CHECK(parse_counters(kept.out.str()).at("pair_list_rebuilds") >= 3);
  for (const auto v : {&Balls::x, &Balls::y, &Balls::vx, &Balls::vy, &Balls::wz})
    CHECK(std::bit_cast<std::uint64_t>((a.balls.*v)[0]) == std::bit_cast<std::uint64_t>((b.balls.*v)[0]));
}
