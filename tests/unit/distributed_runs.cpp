// Distributed runs beyond the cut matrix of cycle_cuts.cpp: four ranks, the spatial
// decomposition of a strained and of a shearing cell on 2 to 4 ranks, a save on three
// ranks restarted on two, a fast gas crossing the periodic faces for 10,000 steps, and bad input on
// several ranks (one message, exit 1, no rank left hanging). Skipped where this build or machine
// has no MPI.
#include "paths.hpp"
#include "cycle/pipeline.hpp"
#include <catch2/catch.hpp>
#include <fmt/format.h>

#include <filesystem>
#include <sstream>
#include <string>

#include "counters.hpp"
#include "interp_support.hpp"
#include "scene_decks.hpp"
#include "skip.hpp"
#include "support/comm.hpp"

using namespace trubal;
using namespace trubal::test;

namespace {

// Runs trubal in `dir` with `args` (the file to run and the redirections) on `ranks` ranks (0: a
// plain trubal, no mpirun), with a time limit so that a hang fails the test instead of stalling it;
// returns the exit status (124: the limit). `env`: more variables for every rank ("NAME=value ...").
int run_in(const TempDir& dir, int ranks, const std::string& env, const std::string& args) {
  const std::string launcher =
      ranks == 0 ? std::string("timeout 120 ")
                 : "env " + env + " OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1 "
                   "ASAN_OPTIONS=detect_leaks=0 timeout 120 mpirun -np " + std::to_string(ranks) + " ";
  return shell("cd " + quote(dir.str()) + " && " + launcher + quote(TRUBAL_EXE) + args);
}

// deck.dat, output in out.txt.
int run_deck(const TempDir& dir, int ranks, const std::string& env = "") {
  return run_in(dir, ranks, env, " deck.dat >out.txt 2>&1");
}

// deck.dat, then the shell's lines in more.txt (trubal -i), output in out.txt.
int run_shell(const TempDir& dir, int ranks, const std::string& env = "") {
  return run_in(dir, ranks, env, " -i deck.dat <more.txt >out.txt 2>&1");
}

const char* kOutputs = "print balls file balls.csv\nprint contacts file contacts.csv\n";
// The counts, read back with counters_of.
const char* kCounters = "print counters file counters.txt\n";
Counters counters_of(const TempDir& dir) { return read_counters(dir.path() / "counters.txt"); }

}  // namespace

TEST_CASE("distributed: 4 ranks, and a save on 3 ranks restarted on 2, give the serial bits", "[mpi][system]") {
  if (!can_run_mpi()) TRUBAL_SKIP(kNoMpi);
  TempDir serial;
  serial.write("deck.dat", std::string(kServoShearDeck) + "cycle 400\n" + kOutputs);
  REQUIRE(run_deck(serial, 0) == 0);
  const std::string balls = slurp(serial.path() / "balls.csv"), contacts = slurp(serial.path() / "contacts.csv");
  REQUIRE(lines_of(contacts).size() > 100);   // contacts to carry history across the cut

  TempDir four;
  four.write("deck.dat", "backend mpi\n" + std::string(kServoShearDeck) + "cycle 400\n" + kOutputs + kCounters);
  REQUIRE(run_deck(four, 4) == 0);
  INFO(slurp(four.path() / "out.txt"));
  CHECK(counter(counters_of(four), "ranks") == 4);
  CHECK(slurp(four.path() / "balls.csv") == balls);
  CHECK(slurp(four.path() / "contacts.csv") == contacts);

  // The save's bytes do not depend on the rank count, and a 2-rank run resumes a 3-rank save.
  TempDir cut;
  cut.write("deck.dat", "backend mpi\n" + std::string(kServoShearDeck) + "cycle 150\nsave s.sav\n");
  REQUIRE(run_deck(cut, 3) == 0);
  TempDir cut_serial;
  cut_serial.write("deck.dat", std::string(kServoShearDeck) + "cycle 150\nsave s.sav\n");
  REQUIRE(run_deck(cut_serial, 0) == 0);
  CHECK(slurp(cut.path() / "s.sav") == slurp(cut_serial.path() / "s.sav"));
  cut.write("deck.dat", "restart s.sav\nbackend mpi\ncycle 250\n" + std::string(kOutputs));
  REQUIRE(run_deck(cut, 2) == 0);
  INFO(slurp(cut.path() / "out.txt"));
  CHECK(slurp(cut.path() / "balls.csv") == balls);
  CHECK(slurp(cut.path() / "contacts.csv") == contacts);
}

TEST_CASE("distributed: the spatial decomposition on 2, 3 and 4 ranks, and its save restarted, give the serial bits",
          "[mpi][system]") {
  // A periodic cell squeezed at a constant strain rate (no servo: the ranks step their own balls
  // and ghosts, cycle/brick_step.hpp), with friction and local damping, so that contacts carry
  // history across the ranks' boundaries and the pair list is rebuilt many times. The shrinking
  // cell leaves balls outside it after a step: the first version missed them (it looked before the
  // cell moved) and parted from serial at cycle 505.
  if (!can_run_mpi()) TRUBAL_SKIP(kNoMpi);
  const std::string deck = R"(start 0.007 0.007 0.007
prop kn 1e5 ks 1e5 fric 26.57 dens 2650
gen 500 0.0003 0.0005 seed 5
damp local 0.7
strain xx 100 yy 100 zz 150
cycle 1500
)";
  TempDir serial;
  serial.write("deck.dat", deck + "save s.sav\ncycle 500\n" + kOutputs);
  REQUIRE(run_deck(serial, 0) == 0);
  const std::string balls = slurp(serial.path() / "balls.csv"), contacts = slurp(serial.path() / "contacts.csv");
  REQUIRE(lines_of(contacts).size() > 200);
  std::string three_save;
  for (int ranks : {2, 3, 4}) {
    TempDir dir;
    dir.write("deck.dat", "backend mpi\n" + deck + "save s.sav\ncycle 500\n" + kOutputs + "print info\n" + kCounters);
    REQUIRE(run_deck(dir, ranks) == 0);
    const std::string out = slurp(dir.path() / "out.txt");
    INFO(ranks << " ranks\n" << out);
    const Counters counters = counters_of(dir);
    CHECK_THAT(out, Catch::Contains("last step shared by: the spatial decomposition"));
    CHECK(counter(counters, "decompositions") >= 1);
    // Each rank searched its own range of balls and the lists were joined, or searched its own part:
    // the files below are serial's only if the joined lists are the serial list.
    CHECK_THAT(out, Catch::Contains("pair search: a stale list on each rank's part"));
    // Each CYCLE left its last step's results to be made when read, as serial does (SAVE after the
    // first, PRINT balls after the second): the ranks held no result arrays while they ran.
    CHECK(counter(counters, "results_made") == 2);
    CHECK(slurp(dir.path() / "s.sav") == slurp(serial.path() / "s.sav"));
    CHECK(slurp(dir.path() / "balls.csv") == balls);
    CHECK(slurp(dir.path() / "contacts.csv") == contacts);
    if (ranks == 3) three_save = slurp(dir.path() / "s.sav");
  }
  // The save written on 3 ranks, resumed on 2.
  TempDir cut;
  cut.write("s.sav", three_save);
  cut.write("deck.dat", "restart s.sav\nbackend mpi\ncycle 500\n" + std::string(kOutputs));
  REQUIRE(run_deck(cut, 2) == 0);
  INFO(slurp(cut.path() / "out.txt"));
  CHECK(slurp(cut.path() / "balls.csv") == balls);
  CHECK(slurp(cut.path() / "contacts.csv") == contacts);
}

TEST_CASE("distributed: a shearing cell whose tilt is reduced gives the serial bits on 2 and 3 ranks", "[mpi][system]") {
  // Simple shear past half an edge: the cell's tilt is brought back by an edge (reduce_cell_tilt),
  // which renumbers the images of every copy of the pair list, the ranks' parts included; the
  // strain rates' velocity field and the wraps of a shrinking, shearing cell come with it.
  if (!can_run_mpi()) TRUBAL_SKIP(kNoMpi);
  const std::string deck = R"(start 0.006 0.006 0.006
prop kn 1e5 ks 1e5 fric 26.57 dens 2650
gen 330 0.0003 0.0005 seed 3
damp local 0.7
strain xx 60 yy 60 zz 60 xy 400
cycle 2000
print info
)" + std::string(kOutputs);
  TempDir serial;
  serial.write("deck.dat", deck);
  REQUIRE(run_deck(serial, 0) == 0);
  // A positive shear this far has had its tilt reduced: it is negative now (xy strain about 0.6).
  REQUIRE_THAT(slurp(serial.path() / "out.txt"), Catch::Contains("cell tilt: xy -"));
  const std::string contacts = slurp(serial.path() / "contacts.csv");
  REQUIRE(lines_of(contacts).size() > 50);
  for (int ranks : {2, 3}) {
    TempDir dir;
    dir.write("deck.dat", "backend mpi\n" + deck);
    REQUIRE(run_deck(dir, ranks) == 0);
    const std::string out = slurp(dir.path() / "out.txt");
    INFO(ranks << " ranks\n" << out);
    CHECK_THAT(out, Catch::Contains("last step shared by: the spatial decomposition"));
    CHECK(slurp(dir.path() / "balls.csv") == slurp(serial.path() / "balls.csv"));
    CHECK(slurp(dir.path() / "contacts.csv") == contacts);
  }
}

TEST_CASE("distributed: RENUMBER mid-run gives the serial bits on 2 and 3 ranks", "[mpi][system]") {
  // Every rank renumbers its whole model alike (model/edit.hpp renumber_balls), and the next CYCLE
  // makes the parts from the new numbers: contacts turned round keep their history on every copy.
  if (!can_run_mpi()) TRUBAL_SKIP(kNoMpi);
  const std::string deck = scrambled_settle_deck() + "cycle 150\nrenumber\ncycle 150\n" + kOutputs;
  TempDir serial;
  serial.write("deck.dat", deck);
  REQUIRE(run_deck(serial, 0) == 0);
  const std::string contacts = slurp(serial.path() / "contacts.csv");
  REQUIRE(lines_of(contacts).size() > 500);
  for (int ranks : {2, 3}) {
    TempDir dir;
    dir.write("deck.dat", "backend mpi\n" + deck + "print info\n");
    REQUIRE(run_deck(dir, ranks) == 0);
    const std::string out = slurp(dir.path() / "out.txt");
    INFO(ranks << " ranks\n" << out);
    CHECK_THAT(out, Catch::Contains("384 balls renumbered 1 to 384 in space order"));
    CHECK_THAT(out, Catch::Contains("last step shared by: the spatial decomposition"));
    CHECK(slurp(dir.path() / "balls.csv") == slurp(serial.path() / "balls.csv"));
    CHECK(slurp(dir.path() / "contacts.csv") == contacts);
  }
}

TEST_CASE("distributed: a fast gas crossing the periodic faces for 10,000 steps keeps the serial bits", "[mpi][system]") {
  // Balls at 3 to 7 m/s, about ten of their radii per thousand steps, in a cell a few diameters wide: every
  // ball crosses the faces (and, in a decomposition, the ranks' boundaries) many times, and the
  // collisions carry shear history (friction) from one crossing to the next.
  if (!can_run_mpi()) TRUBAL_SKIP(kNoMpi);
  const std::string deck = R"(start 0.006 0.006 0.006
prop kn 1e5 ks 1e5 fric 30 dens 2650 rest 0.8
gen 250 0.0003 0.0005 seed 11
init xvel 4 yvel -3 zvel 2 range x 0 0.003
init xvel -2 yvel 5 zvel -4 range x 0.003 0.006
cycle 10000
)" + std::string(kOutputs);
  TempDir serial, two;
  serial.write("deck.dat", deck);
  REQUIRE(run_deck(serial, 0) == 0);
  two.write("deck.dat", "backend mpi\n" + deck + kCounters);
  REQUIRE(run_deck(two, 2) == 0);
  INFO(slurp(two.path() / "out.txt"));
  const Counters counters = counters_of(two);
  CHECK(counter(counters, "decompositions") >= 1);
  // Most of its lists are rebuilt on the ranks' parts, and at those rebuilds the balls change rank
  // as they cross the split's planes, taking their pairs' history along (841 moves in one run;
  // the count follows the shares, which follow the ranks' speeds): checked by the bits.
  CHECK(counter(counters, "part_list_rebuilds") >= 100);
  CHECK(counter(counters, "migrations") >= 100);
  // Rank 1 stepped its part without the whole model's arrays (Pipeline::hollow): it kept their ids
  // and radii, 16 of a ball's 180-odd bytes, where rank 0 kept them all.
  {
    const double rank0 = counter(counters, "rank0_whole_arrays_mib"), rank1 = counter(counters, "rank1_whole_arrays_mib");
    INFO("whole model's arrays held: rank 0 " << rank0 << " MiB, rank 1 " << rank1 << " MiB");
    CHECK(rank0 > 0);
    CHECK(rank1 < 0.2 * rank0);
  }
  // And with every list rebuilt through the whole model (TRUBAL_REBUILD_WHOLE): none on the parts,
  // the same bits.
  TempDir whole;
  whole.write("deck.dat", "backend mpi\n" + deck + kCounters);
  REQUIRE(run_deck(whole, 2, "TRUBAL_REBUILD_WHOLE=1") == 0);
  CHECK(counter(counters_of(whole), "part_list_rebuilds") == 0);
  CHECK(slurp(whole.path() / "balls.csv") == slurp(serial.path() / "balls.csv"));
  const std::string contacts = slurp(serial.path() / "contacts.csv");
  CHECK(lines_of(contacts).size() >= 2);   // a collision under way at the end (a header and at least one)
  CHECK(slurp(two.path() / "balls.csv") == slurp(serial.path() / "balls.csv"));
  CHECK(slurp(two.path() / "contacts.csv") == contacts);
}

TEST_CASE("distributed: the ranks other than 0 search the CYCLE's first list on their parts, not through the whole model", "[mpi][system]") {
  // A resting FCC block of 37,800 balls, every one touching 12 (a periodic cell of 30 x 30 x 42
  // layers): the CYCLE's first list is searched by each rank on its part (Pipeline::split_parts),
  // so that rank 1 never holds the whole model's list, its search's arrays or its index. Its peak by
  // the CYCLE's end is compared with that of the same run with every list searched through the
  // whole model (TRUBAL_REBUILD_WHOLE): 38 against 58 MiB (rank 0: 70 and 75) in one run,
  // where rank 1's whole model between CYCLEs and its part are about 26 and 8 MiB. The files give
  // the serial bits either way.
  if (!can_run_mpi()) TRUBAL_SKIP(kNoMpi);
  const std::string deck = "start 30 30 29.698484809834994\nprop kn 1e5 ks 1e5 fric 0.5 dens 2650\n"
                           "lattice fcc 1 30 30 42\ncycle 20\n" + std::string(kOutputs);
  TempDir serial, parts, whole;
  serial.write("deck.dat", deck);
  REQUIRE(run_deck(serial, 0) == 0);
  auto peaks = [](const TempDir& dir) {
    INFO(slurp(dir.path() / "out.txt"));
    const Counters counters = counters_of(dir);
    return std::pair{counter(counters, "rank0_cycle_peak_mib"), counter(counters, "rank1_cycle_peak_mib")};
  };
  parts.write("deck.dat", "backend mpi\n" + deck + kCounters);
  whole.write("deck.dat", "backend mpi\n" + deck + kCounters);
  REQUIRE(run_deck(parts, 2) == 0);
  REQUIRE(run_deck(whole, 2, "TRUBAL_REBUILD_WHOLE=1") == 0);
  for (const char* file : {"balls.csv", "contacts.csv"}) {
    CHECK(slurp(parts.path() / file) == slurp(serial.path() / file));
    CHECK(slurp(whole.path() / file) == slurp(serial.path() / file));
  }
  CHECK(counter(counters_of(parts), "part_list_rebuilds") == 1);
  const auto [parts0, parts1] = peaks(parts);
  const auto [whole0, whole1] = peaks(whole);
  INFO("peak MiB by the CYCLE's end, ranks 0 and 1: searched on the parts " << parts0 << " " << parts1
                                                                          << ", through the whole model " << whole0 << " " << whole1);
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
  WARN("a sanitizer's build keeps freed memory aside: the peaks are not compared");
#else
  CHECK(parts1 < 0.8 * whole1);
  CHECK(parts1 < 0.7 * parts0);
#endif
}

TEST_CASE("distributed: rank 0 alone makes the contact results a command reads after a CYCLE", "[mpi][system]") {
  // A CYCLE leaves its last step's contact results to be made when read (make_results_to_read).
  // On several ranks rank 0 alone takes that step again, for what it prints and writes; the others
  // leave them unmade, so that their memory stays at their share (129 bytes a pair: 28 MiB for this
  // block's 226,800 pairs). The files, and the CYCLE after, give the serial bits.
  if (!can_run_mpi()) TRUBAL_SKIP(kNoMpi);
  const std::string deck = "start 30 30 29.698484809834994\nprop kn 1e5 ks 1e5 fric 0.5 dens 2650\n"
                           "lattice fcc 1 30 30 42\ninit xvel 0.01 range x 0 10\ncycle 20\n"
                           "print contacts file first.csv\nprint stress\nprint energy\ncycle 30\n" +
                           std::string(kOutputs);
  TempDir serial, two;
  serial.write("deck.dat", deck);
  REQUIRE(run_deck(serial, 0) == 0);
  two.write("deck.dat", "backend mpi\n" + deck + kCounters);
  REQUIRE(run_deck(two, 2) == 0);
  const std::string out = slurp(two.path() / "out.txt");
  INFO(out);
  for (const char* file : {"first.csv", "balls.csv", "contacts.csv"}) CHECK(slurp(two.path() / file) == slurp(serial.path() / file));
  CHECK(lines_of(slurp(serial.path() / "first.csv")).size() > 100000);   // most pairs of the block touch
  // The results each rank holds at the end (made for the last PRINT: rank 0's, of 226,800 pairs).
  const Counters counters = counters_of(two);
  CHECK(counter(counters, "rank0_contact_results_mib") >= 20);
  CHECK(counter(counters, "rank1_contact_results_mib") == 0);
  CHECK(counter(counters, "results_made") == 2);
}

TEST_CASE("distributed: a run that goes unstable is put back to the same rescue copy as serial's", "[mpi][system]") {
  // A chain held between two fixed balls, stepped a little above its critical step from an overlap
  // of 1e-14: the error grows for some hundred steps, so the copy put back is one taken in the
  // CYCLE (at cycle 500), which on several ranks rank 0 alone holds in full and hands to the others
  // (Pipeline::restore_rescue); every rank then steps through the whole model to the same message.
  if (!can_run_mpi()) TRUBAL_SKIP(kNoMpi);
  const std::string deck = R"(start box -1 1 -1 1 -1 1
prop kn 1e6 ks 1e6 fric 0.3 dens 1000
ball 0 0 0 0.01 id 1
ball 0.02 0 0 0.01 id 2
ball 0.04 0 0 0.01 id 3
ball 0.06 0 0 0.01 id 4
ball 0.07999999999999 0 0 0.01 id 5
fix xvel yvel zvel xspin yspin zspin range id 1
fix xvel yvel zvel xspin yspin zspin range id 5
hist energy every 10 file h.csv
tstep 7.05e-5
cycle 5000
)";
  TempDir serial;
  serial.write("deck.dat", deck);
  REQUIRE(run_deck(serial, 0) == 1);
  const std::string out = slurp(serial.path() / "out.txt");
  const auto at = out.find("error: unstable at cycle");
  REQUIRE(at != std::string::npos);
  const std::string message = out.substr(at, out.find('\n', at) - at);
  INFO(message);
  REQUIRE(message.find("back at cycle 500,") != std::string::npos);
  for (int ranks : {2, 3}) {
    TempDir dir;
    dir.write("deck.dat", "backend mpi\n" + deck);
    CHECK(run_deck(dir, ranks) == 1);
    INFO(ranks << " ranks\n" << slurp(dir.path() / "out.txt"));
    CHECK_THAT(slurp(dir.path() / "out.txt"), Catch::Contains(message));
    CHECK(slurp(dir.path() / "h.csv") == slurp(serial.path() / "h.csv"));
  }
}

TEST_CASE("distributed: bad input on 3 ranks stops every rank with one message and exit 1", "[mpi][system]") {
  if (!can_run_mpi()) TRUBAL_SKIP(kNoMpi);
  SECTION("a deck error") {
    TempDir dir;
    dir.write("deck.dat", "start 0.01 0.01 0.01\ngen 10 0.0004 0.0006\nprop kn banana\ncycle 10\n");
    CHECK(run_deck(dir, 3) == 1);
    const std::string out = slurp(dir.path() / "out.txt");
    INFO(out);
    const auto at = out.find("deck.dat:3:");
    REQUIRE(at != std::string::npos);
    CHECK(out.find("deck.dat:3:", at + 1) == std::string::npos);   // rank 0 alone reports it
  }
  SECTION("a failure on rank 0 alone (its file write) stops the others too") {
    TempDir dir;
    dir.write("deck.dat", "start 0.01 0.01 0.01\ngen 10 0.0004 0.0006\nsave no/such/folder/s.sav\ncycle 10\n");
    CHECK(run_deck(dir, 3) == 1);   // not 124: no rank waits for the others
    const std::string out = slurp(dir.path() / "out.txt");
    INFO(out);
    CHECK(out.find("deck.dat:3:") != std::string::npos);
    CHECK(out.find("deck.dat:3:") == out.rfind("deck.dat:3:"));
  }
  SECTION("a dump that rank 0 alone fails to write mid-CYCLE stops every rank at that step") {
    // The dump of cycle 10 cannot replace a folder of its name: rank 0 fails in the CYCLE's
    // observer while the others would go on into the next step's exchange (they hung there).
    TempDir dir;
    std::filesystem::create_directories(dir.path() / "out" / "d_000010.vtp");
    dir.write("deck.dat", "start 0.01 0.01 0.01\ngen 10 0.0004 0.0006\nprop kn 1e5 ks 1e5 fric 0.5 dens 2650\n"
                          "dump vtk out/d every 10\ncycle 30\nprint info\n");
    CHECK(run_deck(dir, 3) == 1);   // not 124
    const std::string out = slurp(dir.path() / "out.txt");
    INFO(out);
    const auto at = out.find("deck.dat:5: error: will not replace 'out/d_000010.vtp'");
    REQUIRE(at != std::string::npos);
    CHECK(out.find("deck.dat:5:", at + 1) == std::string::npos);   // one message
    CHECK(out.find("cycle: ") == std::string::npos);                 // the deck went no further
  }
  SECTION("a rank out of memory in its share of the search or its part stops every rank's CYCLE") {
    // Rank 1 fails as out of memory in its first search on its part (the CYCLE's first list), in
    // its first share of a search through the whole model (the way of TRUBAL_REBUILD_WHOLE), or at
    // its first split (TRUBAL_TEST_FAIL_AT "1 part", "1 search", "1 split"): the others must not go
    // on into the exchange of the balls or the gather of the lists, or step their parts and wait
    // for its ghosts.
    for (const std::string where : {"part", "search", "split"}) {
      INFO(where);
      TempDir dir;
      dir.write("deck.dat", "start 0.01 0.01 0.01\ngen 300 0.0004 0.0006\nprop kn 1e5 ks 1e5 fric 0.5 dens 2650\n"
                            "cycle 30\nprint info\n");
      CHECK(run_deck(dir, 3, fmt::format("TRUBAL_TEST_FAIL_AT='1 {}'{}", where,
                                         where == "search" ? " TRUBAL_REBUILD_WHOLE=1" : "")) == 1);   // not 124
      const std::string out = slurp(dir.path() / "out.txt");
      INFO(out);
      const auto at = out.find(fmt::format("deck.dat:4: error: rank 1 ran out of memory {}",
                                           where == "search"  ? "searching its share of the pairs"
                                           : where == "part" ? "making a new pair list for its part"
                                                             : "making its part of the decomposition"));
      REQUIRE(at != std::string::npos);
      CHECK(out.find("deck.dat:4:", at + 1) == std::string::npos);
      CHECK(out.find("cycle: ") == std::string::npos);
    }
  }
  SECTION("after a rank ran out of memory in its first search on its part, the shell goes on with the whole model") {
    // The ranks other than 0 freed their whole model before that search (Pipeline::split_parts):
    // the failure hands it back, so the next CYCLE and the files are serial's (they crashed or hung).
    TempDir dir, serial;
    const std::string setup = "start 0.01 0.01 0.01\ngen 300 0.0004 0.0006 seed 5\nprop kn 1e5 ks 1e5 fric 0.5 dens 2650\n";
    dir.write("deck.dat", setup);
    dir.write("more.txt", "cycle 30\ncycle 30\nprint balls file balls.csv\nprint contacts file contacts.csv\nquit\n");
    const int status = run_shell(dir, 3, "TRUBAL_TEST_FAIL_AT='1 part'");
    const std::string out = slurp(dir.path() / "out.txt");
    INFO(out);
    CHECK(status != 124);
    CHECK_THAT(out, Catch::Contains("rank 1 ran out of memory making a new pair list for its part"));
    serial.write("deck.dat", setup + "cycle 30\n" + kOutputs);
    REQUIRE(run_deck(serial, 0) == 0);
    CHECK(slurp(dir.path() / "balls.csv") == slurp(serial.path() / "balls.csv"));
    CHECK(slurp(dir.path() / "contacts.csv") == slurp(serial.path() / "contacts.csv"));
  }
  SECTION("rank 0 out of memory making the contact results a command reads: every rank goes back a step, and the shell goes on") {
    // Rank 0 alone takes the CYCLE's last step again for the PRINT (make_results_to_read); its
    // serial search fails (TRUBAL_TEST_FAIL_AT "0 search"). Every rank goes back to the rescue
    // copy, cycle 29, and the PRINT fails with one message; the next CYCLE gives the serial bits of
    // 29 steps and then 30 (a rank left at cycle 30 would split its part from another state).
    TempDir dir, serial;
    const std::string setup = "start 0.01 0.01 0.01\ngen 300 0.0004 0.0006 seed 5\nprop kn 1e5 ks 1e5 fric 0.5 dens 2650\n";
    dir.write("deck.dat", setup);
    dir.write("more.txt", "cycle 30\nprint contacts file first.csv\n" + std::string(kCounters) + "cycle 30\nprint balls file balls.csv\n"
                          "print contacts file contacts.csv\nquit\n");
    const int status = run_shell(dir, 3, "TRUBAL_TEST_FAIL_AT='0 search'");
    const std::string out = slurp(dir.path() / "out.txt");
    INFO(out);
    CHECK(status != 124);
    const std::string message = "rank 0 ran out of memory making the contact results";
    const auto at = out.find(message);
    REQUIRE(at != std::string::npos);
    CHECK(out.find(message, at + 1) == std::string::npos);
    CHECK(counter(counters_of(dir), "cycle") == 29);
    serial.write("deck.dat", setup + "cycle 29\ncycle 30\n" + kOutputs);
    REQUIRE(run_deck(serial, 0) == 0);
    CHECK(slurp(dir.path() / "balls.csv") == slurp(serial.path() / "balls.csv"));
    CHECK(slurp(dir.path() / "contacts.csv") == slurp(serial.path() / "contacts.csv"));
  }
  SECTION("a history file rank 0 cannot open leaves the history on no rank, and the shell goes on") {
    // After an error the shell (and a deck run with -i) goes on: a table kept by the other ranks
    // alone made their CYCLE record, and wait for rank 0, on steps rank 0 did not (it hung).
    TempDir dir;
    dir.write("afile", "a file, not a folder\n");
    dir.write("deck.dat", "start 0.01 0.01 0.01\ngen 200 0.0004 0.0006\nprop kn 1e5 ks 1e5 fric 0.5 dens 2650\n"
                          "hist stress every 10 file afile/h.csv\n");
    dir.write("more.txt", "cycle 30\n" + std::string(kCounters) + "quit\n");
    const int status = run_shell(dir, 3);
    const std::string out = slurp(dir.path() / "out.txt");
    INFO(out);
    CHECK(status != 124);
    const auto at = out.find("deck.dat:4: error: cannot write the history file");
    REQUIRE(at != std::string::npos);
    CHECK(out.find("deck.dat:4:", at + 1) == std::string::npos);
    CHECK(counter(counters_of(dir), "cycle") == 30);
  }
  SECTION("a quick command (BALL) failing on one rank alone stops every rank at that rank's FILE:LINE") {
    // In a batch deck the ranks agree on quick commands only before the next command that is not
    // quick, or at the deck's end (Interpreter::agree_lazily): the others go on past the failing
    // line, so the error must carry the failing rank's place. Lines 3-42 are BALL lines; rank 1 or
    // rank 0 fails at line 10, then a CYCLE follows; or at the deck's last line (nothing follows);
    // or at line 10 where line 20 is bad on every rank (the earlier failure is the one reported).
    std::string deck = "start 0.01 0.01 0.01\nprop kn 1e5 ks 1e5 fric 0.5 dens 2650\n";
    for (int k = 0; k < 40; ++k)
      deck += fmt::format("{}ball {} 0.005 0.005 0.00008\n", k == 17 ? "#" : "", 0.001 + 0.0002 * k);
    for (const char* kind : {"cycle follows", "deck ends", "later error"}) {
      for (const int rank : {1, 0}) {
        const int line = kind == std::string("deck ends") ? 42 : 10;
        INFO(kind << ": rank " << rank << " fails at line " << line);
        std::string text = deck;
        if (kind == std::string("later error")) text.replace(text.find("#ball"), 1, "ball 1 2\n#");   // line 20
        if (kind != std::string("deck ends")) text += "cycle 10\nprint info\n";
        TempDir dir;
        dir.write("deck.dat", text);
        const std::string env = fmt::format("TRUBAL_TEST_FAIL_AT='{} {}'", rank, line);
        CHECK(run_deck(dir, 2, env) == 1);   // not 124: no rank waits for the others
        const std::string out = slurp(dir.path() / "out.txt");
        INFO(out);
        const std::string where = fmt::format("deck.dat:{}: error: rank {} fails here", line, rank);
        CHECK(out.find(where) != std::string::npos);
        CHECK(out.find(": error:") == out.rfind(": error:"));   // one message
        CHECK(out.find("cycle 10") == std::string::npos);       // the CYCLE did not run
      }
    }
  }
}

TEST_CASE("distributed: Rowe's test with a following membrane runs by the spatial decomposition, with the serial bits",
          "[mpi][system]") {
  // The membrane's forces are made again from the positions every 3 cycles: the whole model is made
  // current, the forces are set on it, and each rank's part takes its balls' new loads
  // (BrickStep::loads_changed). A part that kept the old loads parts from serial at the first
  // cycle after 3.
  if (!can_run_mpi()) TRUBAL_SKIP(kNoMpi);
  const std::string deck = R"(start box -200 440 -200 440 -100 450
prop kn 1.5e9 ks 1.5e9 fric 7 dens 2000
lattice fcc 40 7 7 13 layers even range octagon 120 120 120 127
lattice fcc 40 7 7 13 layers odd  range octagon 120 120 120 99
group bottom range z -10 10
group top range z 330 350
membrane 5e4 follow every 3
damp 0.05 0.5
apply zforce -8e7 range group top
apply zforce 8e7 range group bottom
cycle 400
)";
  TempDir serial;
  serial.write("deck.dat", deck + kOutputs);
  REQUIRE(run_deck(serial, 0) == 0);
  const std::string balls = slurp(serial.path() / "balls.csv"), contacts = slurp(serial.path() / "contacts.csv");
  REQUIRE(lines_of(contacts).size() > 200);
  for (int ranks : {2, 3}) {
    TempDir dir;
    dir.write("deck.dat", "backend mpi\n" + deck + kOutputs + "print info\n");
    REQUIRE(run_deck(dir, ranks) == 0);
    const std::string out = slurp(dir.path() / "out.txt");
    INFO(ranks << " ranks\n" << out);
    CHECK_THAT(out, Catch::Contains("last step shared by: the spatial decomposition"));
    CHECK(slurp(dir.path() / "balls.csv") == balls);
    CHECK(slurp(dir.path() / "contacts.csv") == contacts);
  }
}

// Ctrl-C under mpirun: mpirun forwards SIGUSR1 to the ranks, and a CYCLE stops as Ctrl-C stops it
// in a serial run; Ctrl-C (or SIGTERM) at mpirun itself ends the job (SIGTERM to the ranks, SIGKILL
// a second later), and the ranks stop together and say where. A rank that stopped alone would leave the
// others waiting in the step's exchange: the time limit would end the run, without the message.
// One rank under mpirun is still a distributed run (BACKEND mpi is its default): PRINT info says so.
// A plain trubal has no ranks line.
TEST_CASE("distributed: PRINT info says `ranks: 1` under mpirun -np 1", "[system]") {
  if (!can_run_mpi()) TRUBAL_SKIP(kNoMpi);
  TempDir dir;
  dir.write("deck.dat", "start box 0 1 0 1 0 1\nprop kn 1e5 dens 1000\nball 0.5 0.5 0.5 0.1\nbackend mpi\ncycle 2\n"
                        "print info\n");
  REQUIRE(run_deck(dir, 1) == 0);
  const std::string out = slurp(dir.path() / "out.txt");
  INFO(out);
  CHECK_THAT(out, Catch::Contains("\nranks: 1\n"));
  CHECK_THAT(out, Catch::Contains("\nbackend: mpi\n"));
  dir.write("deck.dat", "start box 0 1 0 1 0 1\nprop kn 1e5 dens 1000\nball 0.5 0.5 0.5 0.1\ncycle 2\nprint info\n");
  REQUIRE(run_deck(dir, 0) == 0);
  CHECK_THAT(slurp(dir.path() / "out.txt"), !Catch::Contains("ranks:"));
}

TEST_CASE("distributed: rank 0 alone reads the input files (the others need not see them)", "[mpi][system]") {
  if (!can_run_mpi()) TRUBAL_SKIP(kNoMpi);
  // Rank 1 starts in an empty folder (an MPMD launch): the deck, a CALLed file and GEN's sieve
  // curve are rank 0's to read. Rank 1 read the sieve curve itself, failed alone and left rank 0's
  // GEN waiting on a collective call (a hang, or a GEN cut short).
  TempDir dir, empty;
  dir.write("sieve.csv", "diameter,passing\n0.0005,0\n0.0008,20\n0.001,50\n0.0015,100\n");
  dir.write("props.dat", "prop kn 1e5 ks 1e5 fric 0.5 dens 2650\n");
  dir.write("deck.dat", "start 0.01 0.01 0.01\ngen porosity 0.6 psd sieve file sieve.csv seed 3\ncall props.dat\n"
                        "cycle 20\nprint balls file balls.csv\n");
  REQUIRE(run_deck(dir, 0) == 0);
  const std::string serial = slurp(dir.path() / "balls.csv");
  REQUIRE(lines_of(serial).size() > 1000);
  std::filesystem::remove(dir.path() / "balls.csv");
  const std::string mpmd =
      "env OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1 "
      "ASAN_OPTIONS=detect_leaks=0 timeout 120 mpirun -np 1 -wdir " + quote(dir.str()) + " " + quote(TRUBAL_EXE) +
      " deck.dat : -np 1 -wdir " + quote(empty.str()) + " " + quote(TRUBAL_EXE) + " deck.dat";
  const int status = shell(mpmd + " >" + quote((dir.path() / "out.txt").string()) + " 2>&1");
  INFO(slurp(dir.path() / "out.txt"));
  REQUIRE(status == 0);
  CHECK(slurp(dir.path() / "balls.csv") == serial);
}

TEST_CASE("distributed: a signal stops every rank's CYCLE at the same step, with one message", "[mpi][system]") {
  if (!can_run_mpi()) TRUBAL_SKIP(kNoMpi);
  const std::string deck = std::string(R"(backend mpi
start 0.007 0.007 0.007
prop kn 1e5 ks 1e5 fric 26.57 dens 2650
gen 500 0.0003 0.0005 seed 5
damp local 0.7
)") + "save before.sav\ncycle 100000000\nsave after.sav\n";
  // mpirun takes SIGTERM as it takes Ctrl-C (it ends the job: SIGTERM to the ranks, SIGKILL a
  // second later); the test sends TERM because a shell's background job ignores SIGINT.
  for (const char* signal : {"USR1", "TERM"}) {
    INFO("SIG" << signal << " to mpirun");
    TempDir dir;
    const std::string deck_path = dir.write("deck.dat", deck);
    // The signal goes once the CYCLE has begun (before.sav is written just before it).
    const int status = shell(
        "cd " + quote(dir.str()) +
        " || exit 1; (env OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1 "
        "ASAN_OPTIONS=detect_leaks=0 timeout 120 mpirun -np 2 " + quote(TRUBAL_EXE) + " " + deck_path +
        " >out.txt 2>&1; echo $? >status.txt) & launched=$!; "
        "for i in $(seq 1 600); do [ -e before.sav ] && break; sleep 0.1; done; sleep 1; "
        // this test's mpirun alone (the deck's path is unique; its ranks and `timeout` do not match)
        "pkill -" + signal + " -f '^mpirun -np 2 .*" + deck_path + "'; wait $launched");
    REQUIRE(status == 0);
    const std::string out = slurp(dir.path() / "out.txt");
    INFO(out);
    CHECK(std::stoi(slurp(dir.path() / "status.txt")) != 0);
    CHECK_THAT(out, Catch::Contains("interrupted by a signal (Ctrl-C at mpirun, or SIGUSR1) at cycle "));
    const auto at = out.find("interrupted by a signal");
    CHECK(out.find("interrupted by a signal", at + 1) == std::string::npos);   // rank 0 alone says it
    CHECK_FALSE(std::filesystem::exists(dir.path() / "after.sav"));   // the deck stopped there
  }
}
