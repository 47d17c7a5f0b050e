// Commands that build and run a model, through the real interpreter: save/restart continues
// bitwise, damaged saves are refused, lattices and ranges select what the language says, output
// files have the documented layout.
#include <catch2/catch.hpp>

#include <algorithm>
#include <array>

#include <cmath>
#include <sstream>
#include <utility>

#include "interp_support.hpp"
#include "io/csv.hpp"

using namespace trubal;
using namespace trubal::test;

namespace {

// A small dense pack under compression with friction and Rayleigh damping: contacts form, slide
// and carry shear history, so a restart that lost anything would show.
const char* kPack = R"(
start box -200 200 -200 200 -200 200
prop kn 1.5e9 ks 1.5e9 fric 20 dens 2000
lattice fcc 40 4 4 5 origin -60 -60 -60
fix zvel range z 80 200
fix zvel range z -200 -59
init zvel -0.5 range z 80 200
init zvel 0.5 range z -200 -59
damp 0.05 0.5
)";

}  // namespace

TEST_CASE("commands: SAVE then RESTART then CYCLE continues bitwise like an uninterrupted run", "[commands]") {
  TempDir dir;
  WorkingDir here(dir.path());
  Harness straight;
  REQUIRE(straight.deck(std::string(kPack) + "cycle 500\nprint balls file a_balls.csv\nprint contacts file a_contacts.csv\n"));
  Harness first;
  REQUIRE(first.deck(std::string(kPack) + "cycle 200\nsave pack.sav\n"));
  Harness second;
  REQUIRE(second.deck("restart pack.sav\ncycle 300\nprint balls file b_balls.csv\nprint contacts file b_contacts.csv\n"));
  // Byte-for-byte: every real is written in round-trip precision, so equal files mean equal doubles.
  CHECK(slurp("a_balls.csv") == slurp("b_balls.csv"));
  CHECK(slurp("a_contacts.csv") == slurp("b_contacts.csv"));
  // The scene really has sliding-free shear history to carry: some contacts and nonzero shear force.
  auto contacts = lines_of(slurp("a_contacts.csv"));
  REQUIRE(contacts.size() > 20);
  CHECK(straight.session.model().cycle == 500);
}

TEST_CASE("commands: a truncated, corrupted or foreign save file is refused and the model kept", "[commands]") {
  TempDir dir;
  WorkingDir here(dir.path());
  Harness h;
  REQUIRE(h.deck(std::string(kPack) + "cycle 50\nsave pack.sav\n"));
  std::string good = slurp("pack.sav");
  REQUIRE(good.size() > 1000);
  dir.write("half.sav", good.substr(0, good.size() / 2));
  std::string flipped = good;
  flipped[flipped.size() / 2] ^= 0x20;
  dir.write("flipped.sav", flipped);
  dir.write("foreign.sav", "id,type,x\n1,1,0\n");
  const auto balls = h.session.model().balls.size();

  CHECK_FALSE(h.deck("restart half.sav\n", "r.dat"));
  CHECK(h.err.str().find("r.dat:1: error:") != std::string::npos);
  CHECK(h.err.str().find("truncated") != std::string::npos);
  h.err.str("");
  CHECK_FALSE(h.deck("restart flipped.sav\n", "r.dat"));
  CHECK(h.err.str().find("corrupted") != std::string::npos);
  h.err.str("");
  CHECK_FALSE(h.deck("restart foreign.sav\n", "r.dat"));
  CHECK(h.err.str().find("not a trubal save file") != std::string::npos);
  h.err.str("");
  CHECK_FALSE(h.deck("restart missing.sav\n", "r.dat"));
  CHECK(h.err.str().find("cannot open") != std::string::npos);
  // Nothing was replaced: same balls, and the good file still restarts.
  CHECK(h.session.model().balls.size() == balls);
  CHECK(h.deck("restart pack.sav\n"));
  CHECK(h.session.model().cycle == 50);
}

TEST_CASE("commands: SAVE over an existing file leaves no temporary file behind", "[commands]") {
  TempDir dir;
  WorkingDir here(dir.path());
  Harness h;
  REQUIRE(h.deck(std::string(kPack) + "save pack.sav\ncycle 10\nsave pack.sav\n"));
  int files = 0;
  for (auto& e : fs::directory_iterator(dir.path())) files += e.path().filename().string().rfind("pack.sav", 0) == 0;
  CHECK(files == 1);
  // A save into a directory that does not exist fails cleanly.
  CHECK_FALSE(h.deck("save no/such/dir/pack.sav\n"));
  CHECK(h.err.str().find("cannot write") != std::string::npos);
}

TEST_CASE("commands: LATTICE with an octagon range cuts Rowe's layers", "[commands]") {
  Harness h;
  // 10 x 10 square cut 3-2-1 at each corner keeps 76 (Rowe's large layer): |dx| + |dy| <= 6.5 d.
  REQUIRE(h.deck("start box -1000 1000 -1000 1000 -1000 1000\n"
                 "lattice fcc 40 10 10 1 range octagon 180 180 180 " + fmt::format("{}", 6.5 * 40 / std::sqrt(2.0)) + "\n"));
  CHECK(h.session.model().balls.size() == 76);
  // 7 x 7 cut 2-1 keeps 37 (Cundall's reduced large layer): |dx| + |dy| <= 4.5 d.
  REQUIRE(h.deck("start box -1000 1000 -1000 1000 -1000 1000\n"
                 "lattice fcc 40 7 7 1 range octagon 120 120 120 " + fmt::format("{}", 4.5 * 40 / std::sqrt(2.0)) + "\n"));
  CHECK(h.session.model().balls.size() == 37);
  // Full FCC layers: 3 layers of 4 x 4, 3 x 3, 4 x 4 in free space.
  REQUIRE(h.deck("start box -1000 1000 -1000 1000 -1000 1000\nlattice fcc 40 4 4 3\n"));
  CHECK(h.session.model().balls.size() == 16 + 9 + 16);
  // Nearest neighbours touch: layer spacing d/sqrt(2) puts the hollow ball at distance d.
  const auto& b = h.session.model().balls;
  double dx = b.x[16] - b.x[0], dy = b.y[16] - b.y[0], dz = b.z[16] - b.z[0];
  CHECK(std::sqrt(dx * dx + dy * dy + dz * dz) == Approx(40).epsilon(1e-12));
}

TEST_CASE("commands: ranges, groups and DELETE select the balls the language says", "[commands]") {
  Harness h;
  REQUIRE(h.deck("start box -100 100 -100 100 -100 100\n"
                 "ball 0 0 0 1 id 1\nball 10 0 0 1 id 2\nball 20 0 0 1 id 3 type 2\nball 30 0 5 1 id 7\n"
                 "group left range x -100 15\n"));
  auto count = [&](const std::string& range) {
    h.out.str("");
    REQUIRE(h.deck("fix xvel " + range + "\n"));
    REQUIRE(h.deck("free xvel\n"));
    return std::stoi(h.out.str().substr(0, h.out.str().find(' ')));
  };
  CHECK(count("range id 2 3") == 2);
  CHECK(count("range group left") == 2);
  CHECK(count("range not group left") == 2);
  CHECK(count("range type 2") == 1);
  CHECK(count("range sphere 0 0 0 10") == 2);       // bounds are inclusive
  CHECK(count("range cylinder 30 0 0.5") == 1);
  CHECK(count("range x 5 35 z 1 10") == 1);          // all elements must hold
  REQUIRE(h.deck("delete range group left\n"));
  CHECK(h.session.model().balls.size() == 2);
  CHECK(h.session.model().groups.at("left").empty());   // deleted balls leave their groups
  CHECK_FALSE(h.deck("fix xvel range group\n"));       // a group element needs its name
}

TEST_CASE("commands: GEN places non-overlapping balls reproducibly and says when it runs out of room", "[commands]") {
  Harness a, b;
  const char* deck = "start box 0 100 0 100 0 100\ngen 300 2 4 seed 9\n";
  REQUIRE(a.deck(deck));
  REQUIRE(b.deck(deck));
  const auto& ba = a.session.model().balls;
  REQUIRE(ba.size() == 300);
  CHECK(ba.x == b.session.model().balls.x);   // the same seed gives the same balls
  for (std::size_t i = 0; i < ba.size(); ++i) {
    CHECK(ba.x[i] - ba.rad[i] >= 0);          // whole balls inside the box
    for (std::size_t j = i + 1; j < ba.size(); ++j) {
      double dx = ba.x[i] - ba.x[j], dy = ba.y[i] - ba.y[j], dz = ba.z[i] - ba.z[j];
      REQUIRE(std::sqrt(dx * dx + dy * dy + dz * dz) >= ba.rad[i] + ba.rad[j]);
    }
  }
  Harness c;
  // 20 is below what the densest packing could hold (22 in this box) but more than random placing
  // reaches: GEN gives up after 200,000 failed tries in a row and says how many it placed.
  REQUIRE(c.deck("start box 0 10 0 10 0 10\ngen 20 2 2 seed 1\n"));
  CHECK(c.session.model().balls.size() < 20);
  CHECK(c.session.model().balls.size() > 3);
  CHECK(c.err.str().find("placed only") != std::string::npos);
  // Far more than could ever fit is an error at once (it tried 2000 n times before).
  Harness d;
  CHECK_FALSE(d.deck("start box 0 10 0 10 0 10\ngen 1000 2 2 seed 1\n"));
  CHECK(d.first_error_line().find("1000 balls of radius 2 or more cannot fit in the region (at most 22.1") != std::string::npos);
}

TEST_CASE("commands: GEN numbers its balls in space order", "[commands][threads]") {
  // By cells of the largest diameter (8 here), z slowest, then y, then x: balls near in space are
  // near in number, which the threaded backend's split into number ranges needs. Generation order
  // would put neighbours anywhere in the numbering.
  Harness h;
  REQUIRE(h.deck("start box 0 100 0 100 0 100\ngen 400 2 4 seed 9\n"));
  const auto& b = h.session.model().balls;
  REQUIRE(b.size() == 400);
  auto key = [&](std::size_t k) {
    auto cell = [](double v) { return static_cast<long>(std::floor(v / 8)); };
    return std::array<long, 3>{cell(b.z[k]), cell(b.y[k]), cell(b.x[k])};
  };
  for (std::size_t k = 1; k < b.size(); ++k) {
    INFO("ball " << b.id[k]);
    REQUIRE(key(k - 1) <= key(k));
    REQUIRE(b.id[k - 1] < b.id[k]);
  }
  CHECK(key(0)[0] < key(b.size() - 1)[0]);   // not all in one layer of cells
}

TEST_CASE("commands: PRINT balls file and HIST file write the documented CSV", "[commands]") {
  TempDir dir;
  WorkingDir here(dir.path());
  Harness h;
  REQUIRE(h.deck(std::string(kPack) + "hist stress energy contacts every 10 file h.csv\ncycle 100\n"
                 "print balls file b.csv\nprint contacts file c.csv\n"));
  auto hist = lines_of(slurp("h.csv"));
  REQUIRE(hist.size() == 11);   // header + cycles 10, 20, ..., 100
  CHECK(hist[0] == "cycle,time,s11,s22,s33,s12,s13,s23,ke,strain_energy,friction_work,damping_work,boundary_work,potential,"
                   "contacts,sliding,coordination");
  CHECK(hist[10].rfind("100,", 0) == 0);
  auto balls = lines_of(slurp("b.csv"));
  CHECK(balls[0] == "id,type,x,y,z,rad,vx,vy,vz,wx,wy,wz,fx,fy,fz");
  const auto& b = h.session.model().balls;
  REQUIRE(balls.size() == b.size() + 1);
  // Round trip: the text reads back to the very same double; rows by ascending id (the model keeps
  // its balls in space order: by_id is the id order).
  for (std::size_t r = 0; r < b.size(); r += 7) {
    const std::size_t k = b.by_id[r];
    std::string row = balls[r + 1];
    std::vector<std::string> f;
    std::stringstream ss(row);
    for (std::string c; std::getline(ss, c, ',');) f.push_back(c);
    REQUIRE(f.size() == 15);
    CHECK(std::stoll(f[0]) == b.id[k]);
    CHECK(std::strtod(f[2].c_str(), nullptr) == b.x[k]);
    CHECK(std::strtod(f[8].c_str(), nullptr) == b.vz[k]);
    CHECK(std::strtod(f[14].c_str(), nullptr) == b.fz[k]);
  }
  auto contacts = lines_of(slurp("c.csv"));
  CHECK(contacts[0] == "i,j,nx,ny,nz,overlap,fn,fsx,fsy,fsz,sliding");
  // Sorted by (i, j) with i < j.
  long long pi = 0, pj = 0;
  for (std::size_t k = 1; k < contacts.size(); ++k) {
    long long i = std::stoll(contacts[k]), j = std::stoll(contacts[k].substr(contacts[k].find(',') + 1));
    CHECK(i < j);
    CHECK((i > pi || (i == pi && j > pj)));
    pi = i, pj = j;
  }
}

namespace {

// The cells of one CSV line.
std::vector<std::string> cells_of(const std::string& line) {
  std::vector<std::string> f;
  std::stringstream ss(line);
  for (std::string c; std::getline(ss, c, ',');) f.push_back(c);
  return f;
}

// kPack on a backend, with two balls' histories, cut into CYCLEs as `cycling`: the history file and
// PRINT balls' file at the end.
std::pair<std::string, std::string> ball_history(const std::string& backend, const std::string& cycling) {
  TempDir dir;
  WorkingDir here(dir.path());
  Harness h;
  const bool ok = h.deck(std::string(kPack) + backend +
                         "hist ball 18 x y z vx vy vz wx wy wz fx fy fz ball 26 fz vx every 5 file h.csv\n" + cycling +
                         "print balls file b.csv\n");
  INFO(h.err.str());
  REQUIRE(ok);
  return {slurp("h.csv"), slurp("b.csv")};
}

}  // namespace

TEST_CASE("commands: HIST ball records one ball's values, the same bits on every backend and however the run is cut",
          "[commands][threads]") {
  const auto [hist, balls] = ball_history("", "cycle 100\n");
  const auto rows = lines_of(hist);
  REQUIRE(rows.size() == 21);   // header + cycles 5, 10, ..., 100
  CHECK(rows[0] == "cycle,time,b18_x,b18_y,b18_z,b18_vx,b18_vy,b18_vz,b18_wx,b18_wy,b18_wz,b18_fx,b18_fy,b18_fz,"
                   "b26_fz,b26_vx");
  // The row of cycle 100 is PRINT balls' row of the ball, to the bit (both in round-trip form):
  // x y z vx vy vz wx wy wz fx fy fz are its columns 2-4 and 6-14.
  const auto last = cells_of(rows[20]);
  REQUIRE(last.size() == 16);
  CHECK(last[0] == "100");
  std::vector<std::string> row18, row26;
  for (const auto& line : lines_of(balls)) {
    const auto f = cells_of(line);
    if (f[0] == "18") row18 = f;
    if (f[0] == "26") row26 = f;
  }
  REQUIRE(row18.size() == 15);
  REQUIRE(row26.size() == 15);
  for (int k = 0; k < 3; ++k) CHECK(last[2 + k] == row18[2 + k]);
  for (int k = 0; k < 9; ++k) CHECK(last[5 + k] == row18[6 + k]);
  CHECK(last[14] == row26[14]);
  CHECK(last[15] == row26[6]);
  // The ball is in the pack's contacts: a force and a motion to record.
  CHECK(last[13] != "0");
  CHECK(last[7] != "0");
  // Histories are taken at cycles fixed by the absolute count, so cuts that are not multiples of
  // the period, and other backends, write the same bytes.
  CHECK(ball_history("", "cycle 33\ncycle 1\ncycle 66\n").first == hist);
  CHECK(ball_history("backend allpairs\n", "cycle 33\ncycle 1\ncycle 66\n").first == hist);
  CHECK(ball_history("backend threaded threads 2\n", "cycle 48\ncycle 52\n").first == hist);
}

TEST_CASE("commands: HIST ball names a ball that exists, one deleted later records NaN, and SAVE keeps it",
          "[commands]") {
  {
    Harness h;
    CHECK_FALSE(h.deck(std::string(kPack) + "hist ball 99999 x\n"));
    CHECK(h.first_error_line().starts_with("deck.dat:10: error: there is no ball 99999"));
  }
  {
    Harness h;
    CHECK_FALSE(h.deck(std::string(kPack) + "hist ball 18 every 5\n"));
    CHECK(h.first_error_line().starts_with("deck.dat:10: error: `ball 18` needs the quantities to record"));
  }
  {
    Harness h;
    CHECK_FALSE(h.deck(std::string(kPack) + "hist ball 18 x vx x\n"));
    CHECK(h.first_error_line().starts_with("deck.dat:10: error: `ball 18` names x twice"));
  }
  TempDir dir;
  WorkingDir here(dir.path());
  Harness h;
  REQUIRE(h.deck(std::string(kPack) + "hist ball 18 z fz every 10 file h.csv\ncycle 20\ndelete range id 18\ncycle 20\n"
                 "save s.sav\n"));
  const auto rows = lines_of(slurp("h.csv"));
  REQUIRE(rows.size() == 5);
  CHECK(rows[0] == "cycle,time,b18_z,b18_fz");
  CHECK(cells_of(rows[2])[2] != "nan");
  CHECK(cells_of(rows[3])[2] == "nan");
  CHECK(cells_of(rows[4])[3] == "nan");
  // A save holding a ball's history restarts (its table passes the checks of a saved table).
  Harness again;
  REQUIRE(again.deck("restart s.sav\ncycle 10\n"));
  CHECK(lines_of(slurp("h.csv")).size() == 6);
}

TEST_CASE("commands: PRINT walls file writes nan for the stress of a wall that has no area", "[commands]") {
  TempDir dir;
  WorkingDir here(dir.path());
  Harness h;
  REQUIRE(h.deck("start box -1 1 -1 1 -1 1\nprop kn 1e6 ks 1e6 dens 1000\nball 0 0 0 0.1\n"
                 "wall id 1 plane 0 0 -0.5 0 0 1\nwall id 2 plane 0 0 0.5 0 0 -1\n"
                 "servo wall 2 stress 100 area 0.5\nprint walls\nprint walls file w.csv\n"));
  // The screen says "(no area)" for wall 1, a plane with no area of its own; the file says nan.
  CHECK_THAT(h.out.str(), Catch::Contains("stress (no area)"));
  const auto rows = lines_of(slurp("w.csv"));
  REQUIRE(rows.size() == 3);
  const auto header = cells_of(rows[0]);
  const auto at = std::find(header.begin(), header.end(), "stress") - header.begin();
  REQUIRE(at < static_cast<std::ptrdiff_t>(header.size()));
  CHECK(cells_of(rows[1])[0] == "1");
  CHECK(cells_of(rows[1])[static_cast<std::size_t>(at)] == "nan");
  // Wall 2 has the servo's area: a stress, 0 while nothing touches it.
  CHECK(cells_of(rows[2])[static_cast<std::size_t>(at)] == "0");
}

TEST_CASE("commands: CYCLE names the type that lacks a density or a stiffness", "[commands]") {
  Harness h;
  CHECK_FALSE(h.deck("start box 0 10 0 10 0 10\nprop kn 1e6\nball 5 5 5 1\ncycle 1\n", "t.dat"));
  CHECK(h.first_error_line().find("t.dat:4: error:") == 0);
  CHECK(h.err.str().find("type 1") != std::string::npos);
  Harness g;
  CHECK_FALSE(g.deck("prop kn 1e6\n"));   // nothing to give properties to yet
  CHECK(g.err.str().find("START") != std::string::npos);
}

TEST_CASE("commands: a lattice of touching balls at rest cycles without a false instability alarm", "[commands]") {
  // Touching balls get overlaps of rounding size; their energy is ~1e-30 and its rounding noise
  // once looked like energy created from nothing.
  Harness h;
  REQUIRE(h.deck("start box 0 10 0 10 0 10\nlattice fcc 1 9 9 9 origin 0.5 0.5 0.5\n"
                 "prop kn 1e6 ks 1e6 dens 1000\ncycle 1000\n"));
  double fastest = 0;
  const auto& b = h.session.model().balls;
  for (std::size_t k = 0; k < b.size(); ++k) fastest = std::max(fastest, std::abs(b.vx[k]) + std::abs(b.vz[k]));
  CHECK(fastest < 1e-9);   // still at rest: rounding forces only
  CHECK(h.session.model().cycle == 1000);
}
