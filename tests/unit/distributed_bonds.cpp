// Parallel bonds under BACKEND mpi: a bonded block crushed on several ranks, saved on three and
// restarted on two, keeps every bond's state to the bit of the serial run; a bar whose one weak
// bond lies across two ranks' parts breaks there as serially. (Each rank steps the bonds of its own
// balls, a bond across two ranks on both: cycle/brick_step.hpp.) Skipped where this build or
// machine has no MPI.
#include "paths.hpp"
#include <catch2/catch.hpp>
#include <fmt/format.h>

#include <filesystem>
#include <string>

#include "counters.hpp"
#include "interp_support.hpp"
#include "mpi_launch.hpp"
#include "skip.hpp"
#include "scene_decks.hpp"

using namespace trubal;
using namespace trubal::test;

namespace {

const char* kBlock = "start box -3 8 -3 8 -3 8 destroy\nprop kn 1e8 ks 5e7 mu 0.5 dens 2000\nlattice fcc 1 5 5 7\n"
                     "bond gap 1e-6 kn 2e8 ks 1e8 ten 2e5 coh 4e5 fa 30\ngroup top range z 3.5 10\n"
                     "fix vel spin range group top\nfix vel spin range z -1 0.1\ninit zvel -0.3 range group top\n";

const char* kBondOutputs = "print balls file balls.csv\nprint bonds file bonds.csv\nprint counters file counters.txt\n";

}  // namespace

TEST_CASE("distributed: a bonded block on 2 ranks, and saved on 3 and restarted on 2, gives the serial bits",
          "[mpi][system][bond]") {
  // HIST bonds is recorded on the parts (every rank's own bonds counted by fate, with the bonds no
  // part holds, broken before the split: BrickStep::own_bond_counts): no row gathers the model (each
  // did before), and after the RESTART on 2 ranks the bonds broken before the save are counted.
  // PRINT bonds and SAVE read rank 0's bond table, the parts' bonds' state gathered into it alone
  // (Pipeline::request_bonds): no whole model gathered for them either (both did before). Its
  // dumps, in the CYCLE and between, draw the bonds from rank 0's table and the balls' centres
  // gathered there alone (Session::dump_from_parts): serial's files, no whole model (each gathered it).
  if (!can_run_mpi()) TRUBAL_SKIP(kNoMpi);
  const std::string hist = "hist bonds every 10 file h.csv\n";
  const std::string dumps = "dump vtk d/b every 100\n";
  TempDir serial;
  serial.write("deck.dat", std::string(kBlock) + hist + dumps + "cycle 400\ndump vtk d/b\n" + kBondOutputs);
  REQUIRE(run_deck(serial, 0) == 0);
  const std::string balls = slurp(serial.path() / "balls.csv"), bonds = slurp(serial.path() / "bonds.csv");
  REQUIRE(bonds.find("tension") != std::string::npos);   // bonds broke, in tension and in shear
  REQUIRE(bonds.find("shear") != std::string::npos);
  const std::string history = slurp(serial.path() / "h.csv");
  REQUIRE(lines_of(history).size() == 41);   // (the header and cycles 10 to 400)
  // (Bonds broke before the save at cycle 170 below, which the restarted run's parts do not hold:
  // its row's bonds_broken, the fourth column.)
  std::string row170;
  for (const std::string& line : lines_of(history))
    if (line.rfind("170,", 0) == 0) row170 = line;
  std::vector<std::string> fields;
  for (std::size_t at = 0; at <= row170.size();) {
    const std::size_t comma = std::min(row170.find(',', at), row170.size());
    fields.push_back(row170.substr(at, comma - at));
    at = comma + 1;
  }
  INFO(row170);
  REQUIRE(fields.size() == 6);
  REQUIRE(std::stoi(fields[3]) > 0);

  TempDir two;
  two.write("deck.dat", "backend mpi\n" + std::string(kBlock) + hist + dumps + "cycle 400\ndump vtk d/b\nprint counters file k.txt\n" +
                            kBondOutputs);
  REQUIRE(run_deck(two, 2, kEqualShares) == 0);
  INFO(slurp(two.path() / "out.txt"));
  CHECK(slurp(two.path() / "h.csv") == history);
  int dumped = 0;
  for (const auto& entry : std::filesystem::directory_iterator(serial.path() / "d")) {
    INFO(entry.path().filename().string());
    CHECK(slurp(two.path() / "d" / entry.path().filename()) == slurp(entry.path()));
    dumped += entry.path().filename().string().find("_bonds_") != std::string::npos;
  }
  CHECK(dumped == 5);   // (cycles 0, 100, 200, 300 and 400, the last dumped twice: one file)
  CHECK(counter(read_counters(two.path() / "k.txt"), "whole_gathers") == 0);
  const Counters counters = read_counters(two.path() / "counters.txt");
  CHECK(counter(counters, "whole_gathers") == 0);   // (after PRINT bonds)
  CHECK(counter(counters, "ranks") == 2);
  // The ranks rebuild the list on their parts, balls changing rank with their bonds (6 rebuilds
  // in the runs measured, 2 to 20 balls moved: the moves follow the shares, which follow the
  // ranks' speeds, so their count is not checked).
  CHECK(counter(counters, "part_list_rebuilds") >= 2);
  CHECK(slurp(two.path() / "balls.csv") == balls);
  CHECK(slurp(two.path() / "bonds.csv") == bonds);

  // The save's bytes do not depend on the rank count, and a 2-rank run resumes a 3-rank save.
  TempDir cut, cut_serial;
  cut.write("deck.dat", "backend mpi\n" + std::string(kBlock) + hist + "cycle 170\nsave s.sav\nprint counters file k.txt\n");
  REQUIRE(run_deck(cut, 3, kEqualShares) == 0);
  CHECK(counter(read_counters(cut.path() / "k.txt"), "whole_gathers") == 0);
  cut_serial.write("deck.dat", std::string(kBlock) + hist + "cycle 170\nsave s.sav\n");
  REQUIRE(run_deck(cut_serial, 0) == 0);
  CHECK(slurp(cut.path() / "s.sav") == slurp(cut_serial.path() / "s.sav"));
  cut.write("deck.dat", "restart s.sav\nbackend mpi\ncycle 230\n" + std::string(kBondOutputs));
  REQUIRE(run_deck(cut, 2) == 0);
  INFO(slurp(cut.path() / "out.txt"));
  CHECK(slurp(cut.path() / "balls.csv") == balls);
  CHECK(slurp(cut.path() / "bonds.csv") == bonds);
  CHECK(slurp(cut.path() / "h.csv") == history);   // (the history resumed from the save)
}

TEST_CASE("distributed: a bond across two ranks' parts is stepped on both and breaks there as serially",
          "[mpi][system][bond]") {
  if (!can_run_mpi()) TRUBAL_SKIP(kNoMpi);
  TempDir serial;
  serial.write("deck.dat", pulled_bar_deck() + kBondOutputs);
  REQUIRE(run_deck(serial, 0) == 0);
  const std::string balls = slurp(serial.path() / "balls.csv"), bonds = slurp(serial.path() / "bonds.csv");
  REQUIRE(bonds.find("\n20,21,") != std::string::npos);
  REQUIRE(bonds.find("tension") == bonds.rfind("tension"));   // one bond broke (the header has no such word)
  REQUIRE(bonds.find("tension") > bonds.find("\n20,21,"));
  REQUIRE(bonds.find("tension") < bonds.find("\n21,22,"));
  for (int ranks : {2, 3}) {
    TempDir dir;
    dir.write("deck.dat", "backend mpi\n" + pulled_bar_deck() + kBondOutputs);
    REQUIRE(run_deck(dir, ranks) == 0);
    INFO(ranks << " ranks: " << slurp(dir.path() / "out.txt"));
    const Counters counters = read_counters(dir.path() / "counters.txt");
    CHECK(counter(counters, "ranks") == ranks);
    CHECK(counter(counters, "decompositions") >= 1);
    if (ranks == 2) CHECK(counter(counters, "part_bonds_across") == 1);   // the weak bond
    CHECK(slurp(dir.path() / "balls.csv") == balls);
    CHECK(slurp(dir.path() / "bonds.csv") == bonds);
  }
}
