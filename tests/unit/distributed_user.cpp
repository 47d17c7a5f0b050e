// What a user meets on several ranks: bad input on any rank stops every rank with one FILE:LINE
// message and exit 1 (no rank left hanging), PRINT info names the ranks, rank 0 alone reads the
// input files, and a signal stops every rank's CYCLE at the same step. Skipped where this build or
// machine has no MPI.
#include "paths.hpp"
#include <catch2/catch.hpp>
#include <fmt/format.h>

#include <filesystem>
#include <string>
#include <vector>

#include "counters.hpp"
#include "interp_support.hpp"
#include "model/held_balls.hpp"
#include "mpi_launch.hpp"
#include "skip.hpp"

using namespace trubal;
using namespace trubal::test;

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
  SECTION("a BALL line that rank 0 alone runs fails among others: one message, and the shell goes on with rank 0's model") {
    // BALL runs on rank 0 alone (OnRanks::ModelOnZero) and agrees lazily: rank 0 fails at line 6 and
    // waits in the agreement while the others skip the next BALL lines to the first command that is
    // not quick. Every rank then stops with line 6's message; in the shell the model is rank 0's
    // (the three balls before the failure), and the next CYCLE gives serial's bits.
    const std::string setup = "backend mpi\nstart 0.01 0.01 0.01\nprop kn 1e5 ks 1e5 mu 0.5 dens 2650\n"
                              "ball 0.004 0.005 0.005 0.0006 id 1\nball 0.005 0.005 0.005 0.0006 id 2\n";
    const std::string bad = "ball 0.004 0.005 0.005 0.0006 id 3\nball 0.006 0.005 0.005 0.0006 id 4\n";
    TempDir dir;
    dir.write("deck.dat", setup + bad + "cycle 10\n");
    CHECK(run_deck(dir, 3) == 1);   // not 124
    std::string out = slurp(dir.path() / "out.txt");
    INFO(out);
    const auto at = out.find("deck.dat:6: error:");
    REQUIRE(at != std::string::npos);
    CHECK(out.find("deck.dat:6:", at + 1) == std::string::npos);
    CHECK(out.find("cycle: ") == std::string::npos);
    TempDir shell, serial;
    shell.write("deck.dat", setup + bad);
    shell.write("more.txt", "ball 0.0055 0.0061 0.005 0.0006 id 5\ncycle 40\n" + std::string(kOutputs) + "quit\n");
    CHECK(run_shell(shell, 3) == 0);
    out = slurp(shell.path() / "out.txt");
    INFO(out);
    CHECK(out.find("deck.dat:6: error:") != std::string::npos);
    serial.write("deck.dat", setup.substr(setup.find('\n') + 1) + "ball 0.0055 0.0061 0.005 0.0006 id 5\ncycle 40\n" +
                                 kOutputs);
    REQUIRE(run_deck(serial, 0) == 0);
    CHECK(lines_of(slurp(serial.path() / "balls.csv")).size() == 4);   // (a header and balls 1, 2 and 5)
    CHECK(slurp(shell.path() / "balls.csv") == slurp(serial.path() / "balls.csv"));
    CHECK(slurp(shell.path() / "contacts.csv") == slurp(serial.path() / "contacts.csv"));
  }
  SECTION("a BALL line fails on rank 0 alone in a deck longer than the pieces rank 0 hands over") {
    // Rank 0 hands the deck to the others in pieces of 1 MiB as they read it, a collective call: rank
    // 0 fails at line 6 and waits in the lines' agreement, which the others must meet before they
    // ask for the next piece (2 MB of BALL lines follow, and the CYCLE after them).
    std::string deck = "backend mpi\nstart 1 1 1\nprop kn 1e5 ks 1e5 mu 0.5 dens 2650\n"
                       "ball 0.5 0.5 0.5 0.001 id 1\nball 0.6 0.5 0.5 0.001 id 2\nball 0.5 0.5 0.5 0.001 id 3\n";
    for (int k = 0; k < 50000; ++k)
      deck += fmt::format("ball {:.6f} {:.6f} {:.6f} 0.001 id {}\n", 0.01 + 0.005 * (k % 190), 0.01 + 0.005 * (k / 190 % 190),
                          0.1 + 0.005 * (k / 36100), k + 10);
    REQUIRE(deck.size() > 2 * (std::size_t{1} << 20));
    TempDir dir;
    dir.write("deck.dat", deck + "cycle 10\n");
    CHECK(run_deck(dir, 3) == 1);   // not 124
    const std::string out = slurp(dir.path() / "out.txt");
    INFO(out.substr(0, 2000));
    const auto at = out.find("deck.dat:6: error:");
    REQUIRE(at != std::string::npos);
    CHECK(out.find("deck.dat:6:", at + 1) == std::string::npos);
    CHECK(out.find("cycle: ") == std::string::npos);
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
    // Rank 0 makes every rank's part and sends it: where it fails cutting rank 2's ("2 cut"), rank
    // 1 has its part already and rank 2 is told to go without; each must stop with rank 0's message.
    // The split from rank 0's whole model (INIT places GEN's balls there), and the split of the
    // balls GEN left held on the ranks (Pipeline::parts_from_records), at the CYCLE's line.
    for (const auto& [where, held] : {std::pair{"part", false}, std::pair{"search", false}, std::pair{"split", false},
                                      std::pair{"cut", false}, std::pair{"part", true}, std::pair{"split", true}}) {
      INFO(where << (held ? ", held" : ""));
      TempDir dir;
      dir.write("deck.dat", fmt::format("start 0.01 0.01 0.01\ngen 300 0.0004 0.0006\nprop kn 1e5 ks 1e5 fric 0.5 dens 2650\n"
                                        "{}cycle 30\nprint info\n", held ? "" : "init xvel 0\n"));
      CHECK(run_deck(dir, 3, fmt::format("TRUBAL_TEST_FAIL_AT='{} {}'{}", std::string(where) == "cut" ? 2 : 1, where,
                                         std::string(where) == "search" ? " TRUBAL_REBUILD_WHOLE=1" : "")) == 1);   // not 124
      const std::string out = slurp(dir.path() / "out.txt");
      INFO(out);
      const std::string line = held ? "deck.dat:4:" : "deck.dat:5:";
      const std::string w = where;
      const auto at = out.find(fmt::format("{} error: rank {} ran out of memory {}", line, w == "cut" ? 0 : 1,
                                           w == "search"  ? "searching its share of the pairs"
                                           : w == "part" ? "making a new pair list for its part"
                                           : w == "cut"  ? "making the ranks' parts of the decomposition"
                                                         : "making its part of the decomposition"));
      REQUIRE(at != std::string::npos);
      CHECK(out.find(line, at + 1) == std::string::npos);
      CHECK(out.find("cycle: ") == std::string::npos);
    }
  }
  SECTION("after a rank ran out of memory in its first search on its part or at the split, the shell goes on with the whole model") {
    // The ranks other than 0 freed their whole model before their parts came (Pipeline::split_parts):
    // the failure hands it back, so the next CYCLE and the files are serial's (they crashed or hung).
    for (const auto& [fault, said] : {std::pair{"1 part", "rank 1 ran out of memory making a new pair list for its part"},
                                      std::pair{"1 split", "rank 1 ran out of memory making its part of the decomposition"},
                                      std::pair{"2 cut", "rank 0 ran out of memory making the ranks' parts"}}) {
      INFO(fault);
      TempDir dir, serial;
      const std::string setup = "start 0.01 0.01 0.01\ngen 300 0.0004 0.0006 seed 5\nprop kn 1e5 ks 1e5 fric 0.5 dens 2650\n";
      dir.write("deck.dat", setup);
      dir.write("more.txt", "cycle 30\ncycle 30\nprint balls file balls.csv\nprint contacts file contacts.csv\nquit\n");
      const int status = run_shell(dir, 3, fmt::format("TRUBAL_TEST_FAIL_AT='{}'", fault));
      const std::string out = slurp(dir.path() / "out.txt");
      INFO(out);
      CHECK(status != 124);
      CHECK_THAT(out, Catch::Contains(said));
      serial.write("deck.dat", setup + "cycle 30\n" + kOutputs);
      REQUIRE(run_deck(serial, 0) == 0);
      CHECK(slurp(dir.path() / "balls.csv") == slurp(serial.path() / "balls.csv"));
      CHECK(slurp(dir.path() / "contacts.csv") == slurp(serial.path() / "contacts.csv"));
    }
  }
  SECTION("out of memory making the contact results a command reads: the command fails on every rank, and the shell goes on") {
    // Two ways: rank 1 fails handing rank 0 the results the CYCLE's last step left on the parts,
    // for a PRINT (TRUBAL_TEST_FAIL_AT "1 results"; the others serve rank 0's command,
    // Pipeline::serve_root; PRINT contacts streams its rows from the parts, rank 0's whole model
    // hollow); rank 2 fails so for a SAVE, which streams the model from the parts a chunk at a time
    // and leaves no file, not even a part of one (StateSource). Either way every rank stops the
    // command with the one message, PRINT counters then finds cycle 30 with the parts kept, the
    // next PRINT has the results made on the parts (the step taken again there once) and read from
    // them (none gathered whole), and the next CYCLE, its SAVE and the files give the serial bits.
    struct Way {
      const char* fault;
      const char* reader;
      const char* message;
    };
    for (const Way& way : {Way{"1 results", "print contacts file first.csv\n",
                               "rank 1 ran out of memory gathering the contact results from the parts"},
                           Way{"2 results", "save s.sav\n", "rank 2 ran out of memory gathering the contact results from the parts"}}) {
      INFO(way.fault);
      TempDir dir, serial;
      const std::string setup = "start 0.01 0.01 0.01\ngen 300 0.0004 0.0006 seed 5\nprop kn 1e5 ks 1e5 fric 0.5 dens 2650\n";
      dir.write("deck.dat", setup);
      dir.write("more.txt", "cycle 30\n" + std::string(way.reader) + "print contacts file first.csv\n" + kCounters +
                                "cycle 30\nprint balls file balls.csv\nprint contacts file contacts.csv\nsave end.sav\nquit\n");
      const int status = run_shell(dir, 3, fmt::format("TRUBAL_TEST_FAIL_AT='{}'", way.fault));
      const std::string out = slurp(dir.path() / "out.txt");
      INFO(out);
      CHECK(status != 124);
      const auto at = out.find(way.message);
      REQUIRE(at != std::string::npos);
      CHECK(out.find(way.message, at + 1) == std::string::npos);
      const Counters counters = counters_of(dir);
      CHECK(counter(counters, "cycle") == 30);
      CHECK(counter(counters, "parts_kept") == 1);
      CHECK(counter(counters, "results_made") == 1);
      CHECK(counter(counters, "results_gathered") == 0);
      for (const auto& entry : std::filesystem::directory_iterator(dir.path()))   // (the failed SAVE's)
        CHECK(entry.path().filename().string().rfind("s.sav", 0) == std::string::npos);
      serial.write("deck.dat", setup + "cycle 30\nprint contacts file first.csv\ncycle 30\n" + kOutputs + "save end.sav\n");
      REQUIRE(run_deck(serial, 0) == 0);
      for (const char* file : {"first.csv", "balls.csv", "contacts.csv", "end.sav"})
        CHECK(slurp(dir.path() / file) == slurp(serial.path() / file));
    }
    // A rank failing the step taken again on the parts, rank 1 for a PRINT ("1 remake") or rank 0
    // for a DUMP ("0 remake": rank 0 writes the dump, the step is taken on every rank's part all
    // the same). Where each rank put its copy back in place and let it go (the default), the
    // parts, which alone hold the model (rank 0's whole model went hollow at the CYCLE's end), are
    // kept at the copy's state, the step before (cycle 29), its results not made; where rank 0
    // kept the copy of the whole model (TRUBAL_RESCUE_WHOLE), it is the copy's too. The cycles to
    // 60 then give serial's bits.
    struct Remake {
      Way way;
      const char* env;
      std::int64_t cycle;
    };
    for (const Remake& remake :
         {Remake{{"1 remake", "print contacts file first.csv\n", "rank 1 ran out of memory making the contact results"}, "", 29},
          Remake{{"0 remake", "dump vtk d/s\n", "rank 0 ran out of memory making the contact results"}, "", 29},
          Remake{{"1 remake", "print contacts file first.csv\n", "rank 1 ran out of memory making the contact results"},
                 " TRUBAL_RESCUE_WHOLE=1", 29}}) {
      const Way& way = remake.way;
      INFO(way.fault << remake.env);
      TempDir dir, serial;
      const std::string setup = "start 0.01 0.01 0.01\ngen 300 0.0004 0.0006 seed 5\nprop kn 1e5 ks 1e5 fric 0.5 dens 2650\n";
      dir.write("deck.dat", setup);
      dir.write("more.txt", "cycle 30\n" + std::string(way.reader) + kCounters +
                                fmt::format("cycle {}\n", 60 - remake.cycle) +
                                "print balls file balls.csv\nprint contacts file contacts.csv\nquit\n");
      CHECK(run_shell(dir, 3, fmt::format("TRUBAL_TEST_FAIL_AT='{}'{}", way.fault, remake.env)) != 124);
      const std::string out = slurp(dir.path() / "out.txt");
      INFO(out);
      const auto at = out.find(way.message);
      REQUIRE(at != std::string::npos);
      CHECK(out.find(way.message, at + 1) == std::string::npos);
      CHECK(counter(counters_of(dir), "cycle") == remake.cycle);
      serial.write("deck.dat", setup + "cycle 60\n" + kOutputs);
      REQUIRE(run_deck(serial, 0) == 0);
      for (const char* file : {"balls.csv", "contacts.csv"})
        CHECK(slurp(dir.path() / file) == slurp(serial.path() / file));
    }
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
"env " + kMpiEnv + " timeout 120 mpirun -np 1 -wdir " + quote(dir.str()) + " " + quote(TRUBAL_EXE) +
      " deck.dat : -np 1 -wdir " + quote(empty.str()) + " " + quote(TRUBAL_EXE) + " deck.dat";
  const int status = shell(mpmd + " >" + quote((dir.path() / "out.txt").string()) + " 2>&1");
  INFO(slurp(dir.path() / "out.txt"));
  REQUIRE(status == 0);
  CHECK(slurp(dir.path() / "balls.csv") == serial);
}

// Ctrl-C under mpirun: mpirun forwards SIGUSR1 to the ranks, and a CYCLE stops as Ctrl-C stops it
// in a serial run; Ctrl-C (or SIGTERM) at mpirun itself ends the job (SIGTERM to the ranks, SIGKILL
// a second later), and the ranks stop together and say where. A rank that stopped alone would leave the
// others waiting in the step's exchange: the time limit would end the run, without the message.
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
        " || exit 1; (" + launcher(2) + quote(TRUBAL_EXE) + " " + deck_path +
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

TEST_CASE("distributed: rank 0's whole model left hollow, what reads it reads the parts: serial's bytes", "[mpi][system]") {
  // A CYCLE's end leaves rank 0's whole model hollow (BrickStep::hollow_whole): PRINT info and
  // counters then sum their counts over the parts, PRINT stress, fabric and coordination their
  // exact sums and counts over the parts (the contacts', the wall contacts', the bridges', the
  // balls' unbalanced forces), PRINT energy, walls, strain and history read the light state (the
  // energies of the last step's sums), PRINT balls and contacts merge the parts' rows by
  // id, SAVE streams the parts' arrays a chunk at a time, and CYCLE's overlap warning and its next
  // start (a load, a spin: the kernel's features; the contact-free step) read the parts. Two scenes
  // on 3 ranks against serial: balls falling in a box onto a wall, one pressed into it by an applied
  // force (the warning, of a wall contact); a compressed periodic cell with rolling resistance and
  // capillary bridges.
  if (!can_run_mpi()) TRUBAL_SKIP(kNoMpi);
  const std::string reads =
      "print stress\nprint stress volume 2e-6\nprint fabric\nprint coordination\nprint energy\nprint walls\nprint strain\n"
      "print history\nprint counters file counters.txt\n"
      "print info\nprint contacts\nsave a.sav\nprint balls file b.csv\n"
      "print contacts file c.csv\ncycle 40\nprint contacts file c2.csv\nsave c.sav\nprint balls file b2.csv\n";
  const std::string box =
      "start box 0 0.01 0 0.01 0 0.01 destroy\nprop kn 1e5 ks 1e5 mu 0.5 dens 2650\nwall id 7 plane 0 0 0.0001 0 0 1\n"
      "ball 0.005 0.005 0.00115 0.001 id 1001\ngen 600 0.0004 0.0006 seed 5\napply zforce -20 range id 1001\n"
      "grav 0 0 -9.81\ncycle 150\n";
  const std::string wet =
      "start 0.01 0.01 0.01\ngen 900 0.0004 0.0006 seed 7\n"
      "prop kn 1e5 ks 1e5 mu 0.5 dens 2650 rr_fric 0.1 bridge 2e-10 tension 0.072\nstrain 200 200 200\ncycle 300\n";
  // And balls thrown out of a box through its faces (a wall placed over some of them), one at the
  // CYCLE's last steps: the parts end there, every rank holding the whole model, and rank 0's
  // commands have the results made with every rank first (they hung, rank 0 alone waiting for
  // the others).
  const std::string thrown =
      "start box 0 0.01 0 0.01 0 0.01 destroy\ngen 600 0.0004 0.0006 seed 5\n"
      "prop kn 1e5 ks 1e5 mu 0.5 dens 2650 rr_fric 0.1\nwall id 7 plane 0 0 0.0001 0 0 1\ngrav 0 0 -9.81\ncycle 300\n";
  for (const std::string& scene : {box, wet, thrown}) {
    INFO(scene);
    TempDir serial, ranks;
    serial.write("deck.dat", scene + reads);
    ranks.write("deck.dat", scene + reads);
    REQUIRE(run_deck(serial, 0) == 0);
    REQUIRE(run_deck(ranks, 3) == 0);
    const std::string out = slurp(ranks.path() / "out.txt"), serial_out = slurp(serial.path() / "out.txt");
    INFO(out);
    const Counters counters = counters_of(ranks);
    CHECK(counter(counters, "parts_kept") == (scene == thrown ? 0 : 1));
    CHECK(counter(counters, "whole_hollow") == (scene == thrown ? 0 : 1));   // (the counts read the parts)
    for (const char* file : {"a.sav", "b.csv", "c.csv", "c2.csv", "c.sav", "b2.csv"}) {
      INFO(file);
      CHECK(slurp(ranks.path() / file) == slurp(serial.path() / file));
    }
    if (scene == wet) CHECK(lines_of(slurp(serial.path() / "c.csv")).size() > 10);   // (contacts to print)
    if (scene == box) CHECK(out.find("overlap of ball 1001 on wall 7") != std::string::npos);
    // The lines PRINT info, PRINT contacts and the CYCLEs print of the model, as serial's.
    auto model_lines = [](const std::string& text) {
      std::string kept;
      for (const std::string& line : lines_of(text))
        for (const char* start : {"contacts:", "walls:", "bridges intact:", "physics:", "kernel:", "ball order:", "balls:",
                                  "deck.dat:8: warning: at cycle", "stress:", "fabric:", "coordination number:",
                                  "sliding fraction:", "unbalanced-force ratio:", "at the last force pass", "kinetic (",
                                  "strain:", "friction work:", "balance (should", "wall 7", "  force (", "volumetric strain:"})
          if (line.rfind(start, 0) == 0) kept += line + '\n';
      const auto rows = text.find("overlap          fn");
      kept += rows == std::string::npos ? "" : text.substr(rows, text.find("trubal>", rows) - rows);
      return kept;
    };
    CHECK(model_lines(out) == model_lines(serial_out));
    if (scene == wet) CHECK(model_lines(serial_out).find("bridges intact") != std::string::npos);
    for (const char* reading : {"stress: xx", "fabric: xx", "coordination number:", "unbalanced-force ratio: mean",
                                "at the last force pass", "balance (should stay constant)"})
      CHECK(model_lines(serial_out).find(reading) != std::string::npos);
  }
}

TEST_CASE("distributed: a batch deck's BALL lines held on the ranks: serial's model, a bad line found on any rank",
          "[mpi][system]") {
  // Every rank reads each BALL line and one keeps the ball (model/held_balls.hpp), until a command
  // reads the balls: PROP, GRAV and PRINT counters keep them held, CYCLE has them placed in rank 0's
  // model in the lines' order. The model is serial's; each rank holds about a third of the balls,
  // and checks the centres it keeps and the ids its hash picks, so that a repeat is found on the
  // rank that keeps the first ball, with serial's message and FILE:LINE, and no line after it shown.
  if (!can_run_mpi()) TRUBAL_SKIP(kNoMpi);
  constexpr int kRanks = 3, kBalls = 30000;
  auto x_of = [](int k) { return 0.01 + 0.0098 * (k % 100); };
  auto y_of = [](int k) { return 0.01 + 0.0098 * (k / 100 % 100); };
  auto z_of = [](int k) { return 0.01 + 0.0098 * (k / 10000); };
  std::string balls;
  for (int k = 0; k < kBalls; ++k)   // (every third with its id, the others the next free one)
    balls += fmt::format("ball {} {} {} 0.004{}\n", x_of(k), y_of(k), z_of(k), k % 3 == 0 ? fmt::format(" id {}", 100000 + k) : "");
  const std::string head = "start box 0 1 0 1 0 1\nprop kn 1e5 ks 1e5 mu 0.5 dens 2650\nwall id 3 plane 0 0 0.008 0 0 1\n";
  SECTION("placed at the CYCLE: serial's model; held, a third on each rank") {
    const std::string deck = head + balls + "grav 0 0 -9.81\n" + kCounters + "print info\ncycle 30\nsave a.sav\n" + kOutputs +
                             "print counters file after.txt\n";
    TempDir serial, ranks;
    serial.write("deck.dat", deck);
    ranks.write("deck.dat", deck);
    REQUIRE(run_deck(serial, 0) == 0);
    REQUIRE(run_deck(ranks, kRanks) == 0);
    const std::string out = slurp(ranks.path() / "out.txt"), serial_out = slurp(serial.path() / "out.txt");
    INFO(out.substr(out.size() > 3000 ? out.size() - 3000 : 0));
    for (const char* file : {"a.sav", "balls.csv", "contacts.csv"}) {
      INFO(file);
      CHECK(slurp(ranks.path() / file) == slurp(serial.path() / file));
    }
    // The wall's warnings (the balls of the first layer cross it), one each, as serial's: the
    // standard error of a run apart (under mpirun it reaches the file apart from the output, and
    // may fall inside an echoed line there).
    TempDir serial_err, ranks_err;
    serial_err.write("deck.dat", head + balls + "cycle 1\n");
    ranks_err.write("deck.dat", head + balls + "cycle 1\n");
    REQUIRE(run_trubal(serial_err, 0, " deck.dat >out.txt 2>err.txt") == 0);
    REQUIRE(run_trubal(ranks_err, kRanks, " deck.dat >out.txt 2>err.txt") == 0);
    // (The deck's lines alone: mpirun may add its own, as where a machine's hardware is hidden.)
    auto deck_lines = [](const std::string& text) {
      std::string kept;
      for (const std::string& line : lines_of(text))
        if (line.rfind("deck.dat:", 0) == 0) kept += line + '\n';
      return kept;
    };
    const std::string warnings = deck_lines(slurp(ranks_err.path() / "err.txt"));
    CHECK(lines_of(warnings).size() >= 10000);   // (the first layer's balls, and the CYCLE's overlap warning)
    CHECK(warnings == deck_lines(slurp(serial_err.path() / "err.txt")));
    const Counters counters = counters_of(ranks);
    CHECK(counter(counters, "balls") == kBalls);
    CHECK(counter(counters, "balls_held") == kBalls);
    // A held ball is 52 bytes of arrays and its share of two hash tables (at most 48 bytes at their
    // emptiest after growing), the arrays up to twice their length: under 160 bytes. The model's
    // arrays are 205 bytes a ball, so a rank holding them all would hold 3 times this bound.
    for (int r = 0; r < kRanks; ++r) {
      INFO("rank " << r);
      const double held = counter(counters, fmt::format("rank{}_model_held_mib", r));
      CHECK(held > 0);
      CHECK(held * (1 << 20) < 160.0 * kBalls / kRanks);
    }
    CHECK(out.find("balls held: 30000") != std::string::npos);
    // The CYCLE made the parts from the held balls (Session::place_held_as_parts).
    CHECK(counter(read_counters(ranks.path() / "after.txt"), "parts_from_held_balls") == 1);
  }
  SECTION("a centre or an id taken twice, found by the rank that keeps the first") {
    // A repeat of ball k's centre, where rank 2 keeps it; and of an id rank 1 checks: each line's
    // error is serial's, once, and the run shows no line after it.
    int k_centre = 0, k_id = 0;
    while (HeldBalls::keeper(x_of(k_centre), y_of(k_centre), z_of(k_centre), kRanks) != 2) ++k_centre;
    while (k_id % 3 != 0 || HeldBalls::id_checker(100000 + k_id, kRanks) != 1) ++k_id;
    const std::vector<std::string> repeats = {
        fmt::format("ball {} {} {} 0.003\n", x_of(k_centre), y_of(k_centre), z_of(k_centre)),
        fmt::format("ball 0.5 0.5 0.995 0.003 id {}\n", 100000 + k_id)};
    for (const std::string& repeat : repeats) {
      INFO(repeat);
      const std::size_t cut = balls.find('\n', balls.size() / 2) + 1;   // (the repeat halfway)
      const std::string deck = "start box 0 1 0 1 0 1\n" + balls.substr(0, cut) + repeat + balls.substr(cut) + "cycle 10\n";
      TempDir serial, ranks;
      serial.write("deck.dat", deck);
      ranks.write("deck.dat", deck);
      CHECK(run_trubal(serial, 0, " deck.dat >out.txt 2>err.txt") == 1);
      CHECK(run_trubal(ranks, kRanks, " deck.dat >out.txt 2>err.txt") == 1);
      const std::string out = slurp(ranks.path() / "out.txt"), serial_out = slurp(serial.path() / "out.txt");
      const std::string message = lines_of(slurp(serial.path() / "err.txt")).at(0);
      INFO(message);
      CHECK(message.find("error:") != std::string::npos);
      const std::string err = slurp(ranks.path() / "err.txt");
      const auto at = err.find(message);
      REQUIRE(at != std::string::npos);
      CHECK(err.find("deck.dat:", at + 1) == std::string::npos);
      // The echo: serial's lines, the repeated one last.
      auto echoed = [](const std::string& text) {
        std::size_t n = 0;
        for (const std::string& line : lines_of(text)) n += line.rfind("trubal> ", 0) == 0;
        return n;
      };
      CHECK(echoed(out) == echoed(serial_out));
    }
  }
}

TEST_CASE("distributed: a CYCLE after held BALL lines or GEN makes the ranks' parts of them, or places them on rank 0",
          "[mpi][system]") {
  // The CYCLE right after the BALL lines makes the parts from the balls the ranks hold, rank 0
  // sorting their ids and centres alone (Session::place_held_as_parts): serial's bits, with the
  // first step's sort or without it (SET sort 0), in a box or a periodic cell. Where the model holds
  // other balls, a ball lies outside the periodic cell (the first step wraps it first), or the CYCLE
  // refuses a type, rank 0 places them in its model (place_held) and the CYCLE goes on, or fails, as
  // serially. GEN in a model that holds no ball has rank 0 make the balls alone and every rank hold
  // those its hash picks, as BALL lines (Session::hand_out_generated): no rank builds the whole
  // model for it; a GEN after other balls runs on rank 0's model (placed there first). DELETE where
  // the model holds held balls alone deletes them where they are held (Session::deletes_held): the
  // lines renumbered, the next free id the largest left's successor (the BALL after it), as serially.
  if (!can_run_mpi()) TRUBAL_SKIP(kNoMpi);
  std::string balls;
  for (int k = 0; k < 3000; ++k)
    balls += fmt::format("ball {} {} {} 0.005\n", 0.01 + 0.0098 * (k % 30), 0.01 + 0.0098 * (k / 30 % 30), 0.01 + 0.0098 * (k / 900));
  const std::string prop = "prop kn 1e5 ks 1e5 mu 0.5 dens 2650\n",
                    after = "echo the balls are read\ngrav 0 -3 -9.81\ncycle 40\nsave a.sav\n";
  struct Scene {
    std::string name, deck;
    int from_held;   // parts_from_held_balls
  };
  const std::vector<Scene> scenes = {
      {"sorted", "start box 0 1 0 1 0 1\n" + prop + balls + after, 1},
      {"not sorted", "start box 0 1 0 1 0 1\nset sort 0\n" + prop + balls + after, 1},
      {"another ball first", "start box 0 1 0 1 0 1\n" + prop + "ball 0.9 0.9 0.9 0.004\nfix xvel range id 1\n" + balls + after, 0},
      {"periodic", "start 0.4 0.4 0.4\n" + prop + balls + after, 1},
      {"a lattice", "start box 0 1 0 1 0 1\n" + prop + "lattice fcc 0.0102 20 20 12 origin 0.1 0.1 0.1\n" + after, 1},
      {"periodic, a ball outside the cell", "start 0.4 0.4 0.4\n" + prop + balls + "ball 0.45 0.2 0.2 0.005\n" + after, 0},
      {"GEN n", "start box 0 0.3 0 0.3 0 0.3\n" + prop + "gen 3000 0.004 0.006 seed 5\n" + after, 1},
      {"GEN porosity, two types, a servo", "start 0.05 0.05 0.05\n" + prop + "prop type 2 kn 2e5 ks 1e5 mu 0.3 dens 2000\n" +
                                               "gen porosity 0.42 psd uniform 0.002 0.003 types 1 0.6 2 0.4 seed 3\n" +
                                               "servo 1e3 1e3 1e3\n" + after + "print psd\n", 1},
      {"GEN after a ball", "start box 0 0.3 0 0.3 0 0.3\n" + prop + "ball 0.29 0.29 0.29 0.004\n" +
                               "gen 3000 0.004 0.006 seed 5\n" + after, 0},
      {"GEN, DELETE, BALL", "start box 0 0.3 0 0.3 0 0.3\n" + prop + "gen 3000 0.004 0.006 seed 5\n" +
                                "delete range not cylinder 0.15 0.15 0.1\ndelete range z 0.25 0.3\n" +
                                "delete range id 7 40\nball 0.15 0.15 0.29 0.004\n" + after, 1},
      {"BALL lines, DELETE", "start box 0 1 0 1 0 1\n" + prop + balls + "delete range sphere 0.15 0.15 0.02 0.05\ndelete range id 2900 3000\n" +
                                 "ball 0.9 0.9 0.9 0.004\n" + after, 1},
      {"GEN twice", "start box 0 0.3 0 0.3 0 0.3\n" + prop + "gen 2000 0.004 0.006 seed 5 range z 0 0.15\n" +
                        "gen 1000 0.004 0.006 seed 6 range z 0.15 0.3\n" + after, 0},
  };
  for (const Scene& scene : scenes) {
    INFO(scene.name);
    TempDir serial, ranks;
    serial.write("deck.dat", scene.deck + kOutputs + kCounters);
    ranks.write("deck.dat", scene.deck + kOutputs + kCounters);
    REQUIRE(run_deck(serial, 0) == 0);
    REQUIRE(run_deck(ranks, 3, kEqualShares) == 0);   // (the gathers counted below: no new shares by speed)
    INFO(slurp(ranks.path() / "out.txt").substr(0, 3000));
    for (const char* file : {"a.sav", "balls.csv", "contacts.csv"}) {
      INFO(file);
      CHECK(slurp(ranks.path() / file) == slurp(serial.path() / file));
    }
    if (scene.name != "a lattice" && scene.name.find("GEN") == std::string::npos)   // (its balls touch, falling together)
      CHECK(lines_of(slurp(serial.path() / "contacts.csv")).size() > 100);   // (balls in contact)
    if (scene.name.rfind("GEN porosity", 0) == 0)   // (GEN's balls overlap a little: the servo's first reading)
      CHECK(lines_of(slurp(serial.path() / "contacts.csv")).size() > 100);
    const Counters counters = counters_of(ranks);
    CHECK(counter(counters, "parts_from_held_balls") == scene.from_held);
    // (Nothing gathered whole to rank 0 or handed to every rank: the servo's first reading, of parts
    // whose lists were searched and whose contacts nothing touches yet, is made on them; PRINT psd
    // reads the radii rank 0 keeps.)
    if (scene.from_held == 1) {
      CHECK(counter(counters, "whole_gathers") == 0);
      CHECK(counter(counters, "cycle_hand_overs") == 0);
    }
    if (scene.name.find("DELETE") != std::string::npos) {   // DELETE's counts, and the BALL's id after them
      auto said = [](const std::string& text) {
        std::string lines;
        for (const std::string& line : lines_of(text))
          if (line.find(" deleted") != std::string::npos) lines += line + '\n';
        return lines;
      };
      CHECK(lines_of(said(slurp(serial.path() / "out.txt"))).size() == 3 - (scene.name[0] == 'B'));
      CHECK(said(slurp(ranks.path() / "out.txt")) == said(slurp(serial.path() / "out.txt")));
    }
    if (scene.name.rfind("GEN porosity", 0) == 0) {   // PRINT psd: serial's table
      auto psd = [](const std::string& text) {
        const auto at = text.find("grading of the last GEN");
        return at == std::string::npos ? std::string() : text.substr(at, text.find("largest difference", at) - at);
      };
      CHECK(!psd(slurp(serial.path() / "out.txt")).empty());
      CHECK(psd(slurp(ranks.path() / "out.txt")) == psd(slurp(serial.path() / "out.txt")));
    }
    // ECHO, run lazily, prints after its line's echo and the lines before, as serially (its text
    // is held with the echo until the ranks agree).
    const std::string out = slurp(ranks.path() / "out.txt");
    const auto echo_at = out.find("trubal> echo the balls are read\nthe balls are read\n");
    CHECK(echo_at != std::string::npos);
    const auto last_ball = out.rfind("trubal> ball ");
    CHECK((last_ball == std::string::npos || echo_at > last_ball));
  }
  // A type without a density: the CYCLE's message; a BALL at a centre LATTICE took (each rank
  // keeps the lattice's balls its hash picks, as BALL lines): BALL's. As serial's.
  const std::vector<std::pair<std::string, std::string>> failures = {
      {"start box 0 1 0 1 0 1\nprop kn 1e5 ks 1e5 mu 0.5\n" + balls + "cycle 10\n", "has no density"},
      {"start box 0 1 0 1 0 1\n" + prop + "lattice fcc 0.0102 20 20 12 origin 0.1 0.1 0.1\nball 0.1 0.1 0.1 0.004\ncycle 10\n",
       "ball 1 is already at (0.1, 0.1, 0.1)"},
      // GEN's own refusal, on rank 0 alone where it makes the balls: every rank stops with it.
      {"start box 0 0.1 0 0.1 0 0.1\n" + prop + "gen 1000000 0.004 0.006\ncycle 10\n", "cannot fit in the region"}};
  for (const auto& [deck, says] : failures) {
    TempDir serial, ranks;
    serial.write("deck.dat", deck);
    ranks.write("deck.dat", deck);
    CHECK(run_trubal(serial, 0, " deck.dat >out.txt 2>err.txt") == 1);
    CHECK(run_trubal(ranks, 3, " deck.dat >out.txt 2>err.txt") == 1);
    const std::string message = lines_of(slurp(serial.path() / "err.txt")).at(0);
    INFO(message);
    CHECK(message.find(says) != std::string::npos);
    CHECK(slurp(ranks.path() / "err.txt").find(message) != std::string::npos);
  }
}
