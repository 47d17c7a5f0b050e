// The contract of the cycle: a run's answer does not depend on how it is cut. Scenes x cuts x
// backends, through the interpreter: one unbroken CYCLE, CYCLEs split evenly and unevenly, a
// backend or thread-count switch mid-run, SAVE then RESTART mid-run; each writes byte-identical
// PRINT balls and PRINT contacts files (and history files, where the cut keeps the history).
// The unbroken serial run is also checked against a stored reference (tests/reference/*.ref,
// column sums of those files), so that a change that shifts every backend and cut alike fails
// too. TRUBAL_UPDATE_REFERENCES=1 rewrites the references instead (after an intended change of
// the physics; say why in the commit).
#include "paths.hpp"
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <tuple>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "counters.hpp"
#include "interp_support.hpp"
#include "mpi_launch.hpp"
#include "scene_decks.hpp"
#include "skip.hpp"
#include "cycle/pipeline.hpp"

using namespace trubal;
using namespace trubal::test;

namespace {

struct Scene {
  const char* name;
  const char* setup;    // everything before the cycling under test
  const char* during;   // given before the cycling (histories, dumps); repeated after a RESTART
  int cycles;
};

// The servo, strain and shear deck of scene_decks.hpp.
const Scene kServoShear = {"servo_shear", kServoShearDeck, "hist stress strain contacts every 7 file h.csv\ndump vtk d every 50\n", 400};

// Hertz-Mindlin balls with restitution dashpots and Rayleigh damping falling under gravity onto a held
// floor, some pushed sideways and spun by applied loads; balls that bounce out of the box are destroyed.
// Put in space order every 100 cycles (SET sort), so that sorts fall inside the cuts.
const Scene kHertzDrop = {"hertz_drop", R"(start box -0.1 0.1 -0.1 0.1 -0.02 0.25 destroy
set sort 100
prop shear 3e7 poisson 0.3 fric 20 dens 2650 rest 0.6
lattice fcc 0.01 18 18 1 origin -0.09 -0.09 0
fix vel spin range z -0.005 0.005
gen 250 0.003 0.005 seed 3 range z 0.01 0.2
init zvel -1 range z 0.01 0.2
grav 0 0 -9.81
damp 0.02 200
apply xforce 1e-3 zmom 1e-7 range z 0.1 0.2
cycle 300
)", "hist energy every 5 file h.csv\n", 400};

// Rowe's test on a small FCC sample: the membrane (following the sample every 3 cycles), held
// platens moving at a fixed speed, linear
// springs, Rayleigh damping; sorted every 100 cycles, as the drop.
const Scene kMembrane = {"membrane", R"(start box -200 440 -200 440 -100 450
set sort 100
prop kn 1.5e9 ks 1.5e9 fric 7 dens 2000
lattice fcc 40 7 7 13 layers even range octagon 120 120 120 127
lattice fcc 40 7 7 13 layers odd  range octagon 120 120 120 99
group bottom range z -10 10
group top range z 330 350
group platens range not z 10 330
membrane 5e4 follow every 3
damp 0.05 0.5
apply zforce -8e7 range group top
apply zforce 8e7 range group bottom
cycle 600
apply zforce 0 range group platens
fix zvel range group platens
init zvel -0.05 range group top
init zvel 0.05 range group bottom
)", "hist ratio axial unbal contacts every 10 file h.csv range group platens\n", 400};

// Balls settling with local damping onto a floor plane inside a container cylinder, then a servo
// platen coming down on them while the cylinder spins about its axis and a triangle falls and
// turns: walls of every kind, moving, servo-driven, of two materials, with friction and dashpots.
const Scene kWalls = {"walls", R"(start box -0.05 0.05 -0.05 0.05 -0.01 0.2 destroy
prop type 1 kn 1e5 ks 1e5 fric 20 dens 2650 rest 0.5
prop type 2 kn 2e5 ks 1e5 fric 10
wall id 1 plane 0 0 0 0 0 1 type 2
wall id 2 cylinder 0 0 0 0 0 1 radius 0.03 length 0.15 type 2
gen 250 0.002 0.003 seed 5 range x -0.018 0.018 y -0.018 0.018 z 0.004 0.03
grav 0 0 -9.81
damp local 0.7
cycle 20000
wall id 3 plane 0 0 0.022 0 0 -1 type 2
servo wall 3 stress 200 area 0.0028274 max 0.05
wall id 2 spin 0 0 0.5
wall id 4 polygon -0.01 -0.01 0.05  0.01 -0.01 0.05  0.01 0.01 0.05 velocity 0 0 -0.3 spin 1 0 0
)", "hist wall 3 wall 2 energy every 7 file h.csv\n", 3000};

// A shear box: periodic in x and y, bounded in z by a rough floor and a servo platen that moves
// along x and drags the balls (mixed periodicity with walls); rolling resistance between the balls
// and, smaller, against the walls (the rolling springs' history carried, saved and moved).
const Scene kShearBox = {"shear_box", R"(start box 0 0.04 0 0.03 -0.01 0.05 destroy x periodic y periodic
prop kn 1e5 ks 1e5 fric 25 dens 2650 rest 0.4 rr_fric 0.3
prop type 2 kn 1e5 ks 1e5 fric 40 rr_fric 0.1
wall id 1 plane 0 0 0 0 0 1 type 2
gen 150 0.0018 0.0025 seed 9 range z 0.003 0.03
grav 0 0 -9.81
damp local 0.6
cycle 10000
wall id 2 plane 0 0 0.0195 0 0 -1 type 2
servo wall 2 stress 300 area 0.0012 max 0.1
cycle 9000
wall id 2 velocity 0.05 0 0
)", "hist wall 2 contacts rolling every 7 file h.csv\n", 2000};

// A wet bed: balls with capillary bridges settle on a wet floor, periodic in x and y; a servo platen
// presses them, then lifts away dragging sideways, the bridges to it and among the balls stretched
// and broken (the bridges' state carried, saved and moved; their reach beyond the skin searched).
const Scene kWetBox = {"wet_box", R"(start box 0 0.03 0 0.03 -0.01 0.05 destroy x periodic y periodic
prop kn 1e5 ks 1e5 fric 25 dens 2650 bridge 2e-10 tension 0.072 angle 20
prop type 2 kn 1e5 ks 1e5 fric 30 bridge 1e-10 tension 0.072
wall id 1 plane 0 0 0 0 0 1 type 2
gen 120 0.0018 0.0025 seed 4 range z 0.003 0.025
grav 0 0 -9.81
damp local 0.6
cycle 6000
wall id 2 plane 0 0 0.016 0 0 -1 type 2
servo wall 2 stress 300 area 0.0009 max 0.1
cycle 5000
servo wall 2 off
wall id 2 velocity 0.01 0 0.02
)", "hist wall 2 bridges every 7 file h.csv\n", 2000};

// A cemented block: an FCC lattice with parallel bonds, its top layers pushed down and its bottom
// held, bonds breaking in tension and in shear through the run (the bonds' table carried by its
// balls' ids, its state cut, saved and restarted; under BACKEND mpi every rank steps it whole).
const Scene kBondedBlock = {"bonded_block", R"(start box -3 8 -3 8 -3 8 destroy
prop kn 1e8 ks 5e7 mu 0.5 dens 2000
lattice fcc 1 5 5 7
bond gap 1e-6 kn 2e8 ks 1e8 ten 2e5 coh 4e5 fa 30 rmul 0.9 mcf 0.8
group top range z 3.5 10
fix vel spin range group top
fix vel spin range z -1 0.1
init zvel -0.3 range group top
)", "hist bonds energy every 7 file h.csv\n", 500};

struct Result {
  std::string balls, contacts, history, walls;
  std::string bonds = {};  // PRINT bonds file

  std::string info = {};   // PRINT info at the end
  std::string dumps = {};  // every file of DUMP vtk d, by name (a scene's `during` may dump)
  Counters counters = {};  // PRINT counters at the end
};

// The files of the scene's dumps (d.pvd, d_*.vtp) in `dir`, each named, in the order of their names.
std::string dump_files(const std::filesystem::path& dir) {
  std::vector<std::string> names;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    const std::string name = entry.path().filename().string();
    if (name == "d.pvd" || name.rfind("d_", 0) == 0) names.push_back(name);
  }
  std::sort(names.begin(), names.end());
  std::string all;
  for (const auto& name : names) all += name + "\n" + slurp(dir / name);
  return all;
}

// What every run prints at its end: its files, PRINT info and PRINT counters.
const char* const kEndOutputs = "print balls file balls.csv\nprint contacts file contacts.csv\nprint walls file walls.csv\n"
                                "print bonds file bonds.csv\n"
                                "print info\nprint counters file counters.txt\n";

// Pair lists rebuilt on the parts of the decomposition (ranks' or threads').
double local_rebuilds(const Result& r) { return counter(r.counters, "part_list_rebuilds"); }
// Balls that changed owner at those rebuilds.
double migrations(const Result& r) { return counter(r.counters, "migrations"); }

// Runs the scene with `cycling` (its cycle lines) after the setup, on `backend`, the threads
// sharing the steps in space as `split_rule` says (StepPolicy::split_rule).
Result run(const Scene& scene, const std::string& backend, const std::string& cycling, int split_rule = 0) {
  TempDir dir;
  WorkingDir cd(dir.path());
  Harness h;
  h.session.policy().split_rule = split_rule;
  h.session.policy().follow_speeds = false;   // (the lists rebuilt on the parts are counted: speeds would move the shares)
  const std::string deck = "backend " + backend + "\n" + scene.setup + scene.during + cycling + kEndOutputs;
  const bool ok = h.deck(deck);
  INFO(deck);
  INFO(h.err.str());
  REQUIRE(ok);
  return {slurp(dir.path() / "balls.csv"), slurp(dir.path() / "contacts.csv"), slurp(dir.path() / "h.csv"),
          slurp(dir.path() / "walls.csv"), slurp(dir.path() / "bonds.csv"), h.out.str(), dump_files(dir.path()),
          read_counters(dir.path() / "counters.txt")};
}

// The cuts of a run of n cycles. `keeps_history`: the history file is the unbroken one's (every cut
// now: SAVE keeps the histories, RESTART resumes them and the repeated HIST goes on with them).
struct Cut {
  std::string name, lines;
  bool keeps_history;
};
std::vector<Cut> cuts(const Scene& scene) {
  const int n = scene.cycles, half = n / 2;
  auto cyc = [](int k) { return "cycle " + std::to_string(k) + "\n"; };
  return {
      {"halves", cyc(half) + cyc(n - half), true},
      {"1, n-2, 1", cyc(1) + cyc(n - 2) + cyc(1), true},
      {"thirds, odd", cyc(137) + cyc(n - 137 - 71) + cyc(71), true},
      {"switch to threaded 2", cyc(half) + "backend threaded threads 2\n" + cyc(n - half), true},
      {"switch to allpairs 3", cyc(half - 13) + "backend allpairs threads 3\n" + cyc(n - half + 13), true},
      {"save and restart", cyc(half) + "save s.sav\nrestart s.sav\n" + scene.during + cyc(n - half), true},
  };
}

// Per column of a CSV file: the sum of the values and the sum of their sizes.
std::map<std::string, std::pair<double, double>> column_sums(const std::string& prefix, const std::string& csv) {
  std::map<std::string, std::pair<double, double>> out;
  const auto lines = lines_of(csv);
  if (lines.empty()) return out;
  std::vector<std::string> names;
  {
    std::stringstream head(lines[0]);
    for (std::string c; std::getline(head, c, ',');) names.push_back(prefix + "." + c);
  }
  for (std::size_t l = 1; l < lines.size(); ++l) {
    std::stringstream row(lines[l]);
    std::size_t k = 0;
    for (std::string c; std::getline(row, c, ',') && k < names.size(); ++k) {
      const double v = std::strtod(c.c_str(), nullptr);
      // nan marks a value that does not exist (a wall's stress where it has no area): the bits
      // comparisons between cuts check where it stands; the sums take the numbers.
      if (std::isnan(v)) continue;
      auto& [sum, size] = out[names[k]];
      sum += v;
      size += std::abs(v);
    }
  }
  return out;
}

// The stored reference: `name sum size` lines. A value matches within kRelative of its column's
// size: the references hold the numbers of this code on x86-64 with g++, and every step is the
// same arithmetic on any such machine (no FMA contraction, sqrt correctly rounded), so a real
// change of the physics moves them by far more; the margin is for another libm's last bit in the
// set-up (restitution's damping ratio uses exp and atan2), amplified over the run.
constexpr double kRelative = 1e-9;

void check_reference(const Scene& scene, const Result& r) {
  auto sums = column_sums("balls", r.balls);
  for (const auto& kv : column_sums("contacts", r.contacts)) sums.insert(kv);
  if (lines_of(r.walls).size() > 1)
    for (const auto& kv : column_sums("walls", r.walls)) sums.insert(kv);
  if (lines_of(r.bonds).size() > 1)
    for (const auto& kv : column_sums("bonds", r.bonds)) sums.insert(kv);
  const std::string path = std::string(TRUBAL_TEST_DIR) + "/reference/" + scene.name + ".ref";
  if (std::getenv("TRUBAL_UPDATE_REFERENCES")) {
    std::ofstream f(path);
    f << "# " << scene.name << ": column sums of PRINT balls / PRINT contacts after the run (tests/unit/cycle_cuts.cpp)\n";
    char line[256];
    for (const auto& [name, v] : sums) {
      std::snprintf(line, sizeof line, "%s %.17g %.17g\n", name.c_str(), v.first, v.second);
      f << line;
    }
    REQUIRE(f.good());
    WARN("wrote " << path);
    return;
  }
  std::ifstream f(path);
  REQUIRE(f.good());
  std::size_t checked = 0;
  for (std::string line; std::getline(f, line);) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream in(line);
    std::string name;
    double sum = 0, size = 0;
    in >> name >> sum >> size;
    INFO(scene.name << " " << name);
    REQUIRE(sums.count(name) == 1);
    CHECK(std::abs(sums[name].first - sum) <= kRelative * size);
    CHECK(std::abs(sums[name].second - size) <= kRelative * size);
    ++checked;
  }
  CHECK(checked == sums.size());
}

// in_space: the threads share every step in space (StepPolicy::split_rule 1, a part of the
// decomposition per thread), on 2 and 3 threads only; else every backend.
void check_scene(const Scene& scene, bool in_space = false) {
  const std::string unbroken = "cycle " + std::to_string(scene.cycles) + "\n";
  const Result serial = run(scene, "serial", unbroken);
  REQUIRE(lines_of(serial.contacts).size() > 50);   // a scene with contacts to carry history (the shear box has 94)
  REQUIRE(lines_of(serial.history).size() > 10);
  if (!in_space) check_reference(scene, serial);
  const std::vector<std::string> backends =
      in_space ? std::vector<std::string>{"threaded threads 2", "threaded threads 3"}
               : std::vector<std::string>{"serial", "threaded threads 2", "threaded threads 3", "allpairs threads 2"};
  const int split_rule = in_space ? 1 : -1;
  for (const std::string& backend : backends) {
    std::vector<Cut> all = cuts(scene);
    if (backend != "serial") all.insert(all.begin(), {"unbroken", unbroken, true});
    for (const Cut& cut : all) {
      // In space, to keep the suite short: on 2 threads the unbroken run, the cut with the most CYCLE
      // boundaries (the parts made again at each) and the restart; on 3 threads the unbroken run.
      // The other cuts differ from these only in where the boundaries fall, which the split by
      // numbers above checks on every backend.
      if (in_space && cut.name != "unbroken" &&
          (backend == "threaded threads 3" || (cut.name != "1, n-2, 1" && cut.name != "save and restart")))
        continue;
      INFO(scene.name << " on " << backend << ", cut: " << cut.name);
      const Result other = run(scene, backend, cut.lines, split_rule);
      CHECK(other.balls == serial.balls);
      CHECK(other.contacts == serial.contacts);
      CHECK(other.walls == serial.walls);
      CHECK(other.bonds == serial.bonds);
      if (cut.keeps_history) CHECK(other.history == serial.history);
      if (in_space && cut.name != "switch to allpairs 3")   // (allpairs keeps no list to share out)
        CHECK_THAT(other.info, Catch::Contains("last step shared by: the spatial decomposition, a part per thread"));
      // The threads rebuild the lists on their parts too (BrickStep::rebuild_local), so the files
      // above check that path on threads.
      if (in_space && cut.name == "unbroken" && std::string(scene.name) == "hertz_drop") CHECK(local_rebuilds(other) >= 20);
      if (in_space && cut.name == "unbroken" && std::string(scene.name) == "servo_shear") CHECK(migrations(other) >= 10);
    }
  }
}

// The same scene under `mpirun -np ranks trubal` with BACKEND mpi, `cycling` after the setup.
Result run_mpi(const Scene& scene, int ranks, const std::string& cycling) {
  TempDir dir;
  const std::string deck = "backend mpi\n" + std::string(scene.setup) + scene.during + cycling + kEndOutputs;
  dir.write("deck.dat", deck);
  const int status = shell("cd " + quote(dir.str()) + " && " + launcher(ranks, "", kLongRunLimit) + quote(TRUBAL_EXE) +
                           " deck.dat >out.txt 2>&1");
  INFO(deck);
  INFO(slurp(dir.path() / "out.txt"));
  REQUIRE(status == 0);
  // Really on that many ranks, and rank 0 alone printed (one copy of each line).
  const std::string out = slurp(dir.path() / "out.txt");
  const Counters counters = read_counters(dir.path() / "counters.txt");
  CHECK(counter(counters, "ranks") == ranks);
  CHECK(out.find("trubal> print info") == out.rfind("trubal> print info"));
  return Result{slurp(dir.path() / "balls.csv"), slurp(dir.path() / "contacts.csv"), slurp(dir.path() / "h.csv"),
                slurp(dir.path() / "walls.csv"), slurp(dir.path() / "bonds.csv"), out, dump_files(dir.path()), counters};
}

// Every scene on 2 and 3 ranks, unbroken and cut (a switch from serial to mpi, SAVE and RESTART),
// byte for byte the serial run.
void check_scene_mpi(const Scene& scene) {
  const std::string unbroken = "cycle " + std::to_string(scene.cycles) + "\n";
  const Result serial = run(scene, "serial", unbroken);
  const int half = scene.cycles / 2;
  const std::string halves = "cycle " + std::to_string(half) + "\nsave s.sav\nrestart s.sav\n" + scene.during +
                             "cycle " + std::to_string(scene.cycles - half) + "\n";
  for (const auto& [ranks, cycling, keeps_history] :
       {std::tuple{2, unbroken, true}, std::tuple{3, unbroken, true}, std::tuple{2, halves, true}}) {
    INFO(scene.name << " on " << ranks << " ranks: " << cycling);
    const auto other = run_mpi(scene, ranks, cycling);
    CHECK(other.balls == serial.balls);
    CHECK(other.contacts == serial.contacts);
    CHECK(other.walls == serial.walls);
    CHECK(other.bonds == serial.bonds);
    if (keeps_history) CHECK(other.history == serial.history);
    // The dumps, which rank 0 alone writes from the state gathered to it at their steps.
    if (keeps_history && cycling == unbroken) CHECK(other.dumps == serial.dumps);
    if (std::string(scene.name) == "servo_shear") CHECK(serial.dumps.find("d_contacts_") != std::string::npos);
    // The scene without walls whose balls fall through many lists rebuilds them on the ranks'
    // parts (BrickStep::rebuild_local), so the files above check that path too.
    if (std::string(scene.name) == "hertz_drop") CHECK(local_rebuilds(other) >= 20);
    // Its balls change rank at those rebuilds, with their history (44 to 81 of them in the runs
    // measured; the count follows the shares, which follow the ranks' speeds).
    if (std::string(scene.name) == "servo_shear") CHECK(migrations(other) >= 10);
  }
}

}  // namespace

TEST_CASE("cycle cuts: servo, strain and shear strain in a periodic cell", "[cuts][backends][system][threads]") {
  check_scene(kServoShear);
}

TEST_CASE("cycle cuts: Hertz, dashpots, Rayleigh damping, gravity and applied loads", "[cuts][backends][system][threads]") {
  check_scene(kHertzDrop);
}

TEST_CASE("cycle cuts: Rowe's test with the membrane and moving platens", "[cuts][backends][system][threads]") {
  check_scene(kMembrane);
}

TEST_CASE("cycle cuts: walls of every kind, moving and servo-driven", "[cuts][backends][walls][system][threads]") {
  check_scene(kWalls);
}

TEST_CASE("cycle cuts: a shear box with rolling resistance, periodic in x and y between walls across z",
          "[cuts][backends][walls][system][threads]") {
  check_scene(kShearBox);
}

TEST_CASE("cycle cuts: a wet bed with capillary bridges between balls and to walls, pressed and pulled apart",
          "[cuts][backends][walls][system][threads]") {
  check_scene(kWetBox);
}

TEST_CASE("cycle cuts: a cemented block with parallel bonds breaking in tension and shear", "[cuts][backends][bond][system][threads]") {
  check_scene(kBondedBlock);
}

TEST_CASE("cycle cuts: threads sharing the step in space on 2 and 3 threads give the serial bits, every scene",
          "[cuts][backends][system][threads]") {
  for (const Scene* scene : {&kServoShear, &kHertzDrop, &kMembrane, &kWalls, &kShearBox, &kWetBox, &kBondedBlock}) {
    check_scene(*scene, true);   // (and every run's PRINT info says the threads shared it in space)
  }
}

TEST_CASE("cycle cuts: BACKEND mpi on 2 and 3 ranks gives the serial bits, every scene", "[cuts][mpi][system][threads]") {
  if (!can_run_mpi()) TRUBAL_SKIP(kNoMpi);
  for (const Scene* scene : {&kServoShear, &kHertzDrop, &kMembrane, &kWalls, &kShearBox, &kWetBox, &kBondedBlock})
    check_scene_mpi(*scene);
}
