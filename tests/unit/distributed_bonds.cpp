// Parallel bonds under BACKEND mpi: a bonded block crushed on several ranks, saved on three and
// restarted on two, keeps every bond's state to the bit of the serial run. (Bonds do not travel with
// the balls of the spatial decomposition: each rank steps a bonded scene whole.) Skipped where this
// build or machine has no MPI.
#include "paths.hpp"
#include <catch2/catch.hpp>
#include <fmt/format.h>

#include <string>

#include "counters.hpp"
#include "interp_support.hpp"
#include "mpi_launch.hpp"
#include "skip.hpp"

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
  if (!can_run_mpi()) TRUBAL_SKIP(kNoMpi);
  TempDir serial;
  serial.write("deck.dat", std::string(kBlock) + "cycle 400\n" + kBondOutputs);
  REQUIRE(run_deck(serial, 0) == 0);
  const std::string balls = slurp(serial.path() / "balls.csv"), bonds = slurp(serial.path() / "bonds.csv");
  REQUIRE(bonds.find("tension") != std::string::npos);   // bonds broke, in tension and in shear
  REQUIRE(bonds.find("shear") != std::string::npos);

  TempDir two;
  two.write("deck.dat", "backend mpi\n" + std::string(kBlock) + "cycle 400\n" + kBondOutputs);
  REQUIRE(run_deck(two, 2) == 0);
  INFO(slurp(two.path() / "out.txt"));
  CHECK(counter(read_counters(two.path() / "counters.txt"), "ranks") == 2);
  CHECK(slurp(two.path() / "balls.csv") == balls);
  CHECK(slurp(two.path() / "bonds.csv") == bonds);

  // The save's bytes do not depend on the rank count, and a 2-rank run resumes a 3-rank save.
  TempDir cut, cut_serial;
  cut.write("deck.dat", "backend mpi\n" + std::string(kBlock) + "cycle 170\nsave s.sav\n");
  REQUIRE(run_deck(cut, 3) == 0);
  cut_serial.write("deck.dat", std::string(kBlock) + "cycle 170\nsave s.sav\n");
  REQUIRE(run_deck(cut_serial, 0) == 0);
  CHECK(slurp(cut.path() / "s.sav") == slurp(cut_serial.path() / "s.sav"));
  cut.write("deck.dat", "restart s.sav\nbackend mpi\ncycle 230\n" + std::string(kBondOutputs));
  REQUIRE(run_deck(cut, 2) == 0);
  INFO(slurp(cut.path() / "out.txt"));
  CHECK(slurp(cut.path() / "balls.csv") == balls);
  CHECK(slurp(cut.path() / "bonds.csv") == bonds);
}
