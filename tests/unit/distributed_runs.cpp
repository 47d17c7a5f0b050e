// Distributed runs beyond the cut matrix of cycle_cuts.cpp: four ranks, the spatial
// decomposition of a strained and of a shearing cell on 2 to 4 ranks, a save on three ranks
// restarted on two, a fast gas crossing the periodic faces for 10,000 steps, the rescue copy, Rowe's
// test, the sorts into space order on the parts; each gives the serial bits. (What a user meets at the ranks, bad input and signals:
// distributed_user.cpp.) Skipped where this build or machine has no MPI.
#include "paths.hpp"
#include "cycle/pipeline.hpp"
#include <catch2/catch.hpp>
#include <fmt/format.h>

#include <filesystem>
#include <sstream>
#include <string>

#include "counters.hpp"
#include "interp_support.hpp"
#include "mpi_launch.hpp"
#include "scene_decks.hpp"
#include "skip.hpp"
#include "support/comm.hpp"

using namespace trubal;
using namespace trubal::test;

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

// A periodic cell of 500 balls squeezed at a constant strain rate, with friction and local damping.
constexpr const char* kSqueezedCell =
    "start 0.007 0.007 0.007\nprop kn 1e5 ks 1e5 fric 26.57 dens 2650\ngen 500 0.0003 0.0005 seed 5\n"
    "damp local 0.7\nstrain xx 100 yy 100 zz 150\n";

TEST_CASE("distributed: the spatial decomposition on 2, 3 and 4 ranks, and its save restarted on other rank counts, give the serial bits",
          "[mpi][system]") {
  // A periodic cell squeezed at a constant strain rate (no servo: the ranks step their own balls
  // and ghosts, cycle/brick_step.hpp), with friction and local damping, so that contacts carry
  // history across the ranks' boundaries and the pair list is rebuilt many times. The shrinking
  // cell leaves balls outside it after a step: the first version missed them (it looked before the
  // cell moved) and parted from serial at cycle 505.
  if (!can_run_mpi()) TRUBAL_SKIP(kNoMpi);
  const std::string deck = std::string(kSqueezedCell) + "cycle 1500\n";
  TempDir serial;
  serial.write("deck.dat", deck + "save s.sav\ncycle 500\n" + kOutputs);
  REQUIRE(run_deck(serial, 0) == 0);
  const std::string balls = slurp(serial.path() / "balls.csv"), contacts = slurp(serial.path() / "contacts.csv");
  REQUIRE(lines_of(contacts).size() > 200);
  std::string three_save, two_save;
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
    // first, PRINT balls and contacts after the second): the ranks took that step again on their
    // parts, once for each, and handed rank 0's command the arrays it read one at a time, none
    // gathered whole.
    CHECK(counter(counters, "results_made") == 2);
    CHECK(counter(counters, "results_gathered") == 0);
    // SAVE and PRINT, which rank 0 alone runs, left the ranks their parts.
    CHECK(counter(counters, "parts_kept") == 1);
    CHECK(slurp(dir.path() / "s.sav") == slurp(serial.path() / "s.sav"));
    CHECK(slurp(dir.path() / "balls.csv") == balls);
    CHECK(slurp(dir.path() / "contacts.csv") == contacts);
    if (ranks == 3) three_save = slurp(dir.path() / "s.sav");
    if (ranks == 2) two_save = slurp(dir.path() / "s.sav");
  }
  // The save written on 3 ranks resumed on 2; those written on 2 ranks and on one process resumed on 3.
  const std::pair<std::string, int> resumed[] = {{three_save, 2}, {two_save, 3}, {slurp(serial.path() / "s.sav"), 3}};
  for (const auto& [save, ranks] : resumed) {
    TempDir cut;
    cut.write("s.sav", save);
    cut.write("deck.dat", "restart s.sav\nbackend mpi\ncycle 500\n" + std::string(kOutputs));
    REQUIRE(run_deck(cut, ranks) == 0);
    INFO(ranks << " ranks\n" << slurp(cut.path() / "out.txt"));
    CHECK(slurp(cut.path() / "balls.csv") == balls);
    CHECK(slurp(cut.path() / "contacts.csv") == contacts);
  }
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
  REQUIRE(run_deck(two, 2, kEqualShares) == 0);
  INFO(slurp(two.path() / "out.txt"));
  const Counters counters = counters_of(two);
  CHECK(counter(counters, "decompositions") >= 1);
  // Most of its lists are rebuilt on the ranks' parts, and at those rebuilds the balls change rank
  // as they cross the split's planes, taking their pairs' history along (841 moves in one run;
  // the count follows the shares, which follow the ranks' speeds): checked by the bits.
  CHECK(counter(counters, "part_list_rebuilds") >= 100);
  CHECK(counter(counters, "migrations") >= 100);
  // Every rank stepped its part without the whole model's state (Pipeline::hollow,
  // BrickStep::hollow_whole): rank 1 kept the balls' ids, types and radii (20 of a ball's 205
  // bytes), rank 0 their fixities too (21 bytes), for the commands.
  {
    const double rank0 = counter(counters, "rank0_whole_arrays_mib"), rank1 = counter(counters, "rank1_whole_arrays_mib");
    const double per_ball = rank0 * (1 << 20) / counter(counters, "balls");
    INFO("whole model's arrays held: rank 0 " << rank0 << " MiB (" << per_ball << " bytes a ball), rank 1 " << rank1 << " MiB");
    CHECK(rank1 > 0);
    CHECK(per_ball < 25);
    CHECK(rank1 <= rank0);
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
  // whole model (TRUBAL_REBUILD_WHOLE): 46 against 60 MiB (rank 0: 75 and 84) in one run, 8 of
  // the 46 the contact results the last step leaves on rank 1's part, where rank 1's whole model
  // between CYCLEs and its part are about 26 and 8 MiB. The files give the serial bits either way.
  if (!can_run_mpi()) TRUBAL_SKIP(kNoMpi);
  const std::string deck = "start 30 30 29.698484809834994\nprop kn 1e5 ks 1e5 fric 0.5 dens 2650\n"
                           "lattice fcc 1 30 30 42\ncycle 20\n" + std::string(kOutputs);
  TempDir serial, parts, whole, rescue;
  serial.write("deck.dat", deck);
  REQUIRE(run_deck(serial, 0) == 0);
  auto peaks = [](const TempDir& dir) {
    INFO(slurp(dir.path() / "out.txt"));
    const Counters counters = counters_of(dir);
    return std::tuple{counter(counters, "rank0_cycle_peak_mib"), counter(counters, "rank1_cycle_peak_mib"),
                      counter(counters, "rank1_contact_results_mib")};
  };
  // (The copies as the CYCLE left them, before the PRINTs take its last step again and let them go.)
  const std::string copies = "print counters file copies.txt\n";
  const std::string split_deck = deck.substr(0, deck.find("cycle 20\n") + 9) + copies + kOutputs;
  parts.write("deck.dat", "backend mpi\n" + split_deck + kCounters);
  whole.write("deck.dat", "backend mpi\n" + deck + kCounters);
  REQUIRE(run_deck(parts, 2) == 0);
  REQUIRE(run_deck(whole, 2, "TRUBAL_REBUILD_WHOLE=1") == 0);
  rescue.write("deck.dat", "backend mpi\n" + split_deck + kCounters);
  REQUIRE(run_deck(rescue, 2, "TRUBAL_RESCUE_WHOLE=1") == 0);
  for (const char* file : {"balls.csv", "contacts.csv"}) {
    CHECK(slurp(parts.path() / file) == slurp(serial.path() / file));
    CHECK(slurp(whole.path() / file) == slurp(serial.path() / file));
    CHECK(slurp(rescue.path() / file) == slurp(serial.path() / file));
  }
  // (The CYCLE's first list; the step taken again on the parts for the PRINTs keeps the CYCLE's counts.)
  CHECK(counter(counters_of(parts), "part_list_rebuilds") == 1);
  const auto [parts0, parts1, results1] = peaks(parts);
  [[maybe_unused]] const auto [whole0, whole1, whole_results1] = peaks(whole);
  [[maybe_unused]] const auto [rescue0, rescue1, rescue_results1] = peaks(rescue);
  const Counters part_copies = read_counters(parts.path() / "copies.txt"), whole_copy = read_counters(rescue.path() / "copies.txt");
  const double copy0 = counter(part_copies, "rank0_rescue_copy_mib"), copy1 = counter(part_copies, "rank1_rescue_copy_mib");
  const double whole_copy0 = counter(whole_copy, "rank0_rescue_copy_mib");
  INFO("rescue copy MiB, ranks 0 and 1: " << copy0 << " " << copy1 << "; with the whole model's on rank 0: " << whole_copy0 << " "
                                          << counter(whole_copy, "rank1_rescue_copy_mib"));
  // Each rank keeps the rescue copy of its own part (the CYCLE's last step's step before, which
  // the PRINTs took again on the parts in place, no split from rank 0): rank 0 about half of the
  // whole model's copy, rank 1 the other half.
  CHECK(copy0 < 0.7 * whole_copy0);
  CHECK(copy1 > 0.3 * whole_copy0);
  CHECK(counter(whole_copy, "rank1_rescue_copy_mib") < 0.05 * whole_copy0);
  CHECK(counter(counters_of(parts), "copies_put_back_on_parts") >= 1);
  CHECK(counter(counters_of(rescue), "copies_put_back_on_parts") == 0);
  // (The PRINTs took the step again and let the copies go, as serial's results made let its go.)
  CHECK(counter(counters_of(parts), "rank0_rescue_copy_mib") == 0);
  CHECK(counter(counters_of(parts), "rank1_rescue_copy_mib") == 0);
  INFO("peak MiB by the CYCLE's end, ranks 0 and 1: searched on the parts " << parts0 << " " << parts1
                                                                          << ", through the whole model " << whole0 << " " << whole1
                                                                          << "; rank 1's part's results " << results1
                                                                          << "; the rescue copy of the whole model on rank 0 "
                                                                          << rescue0 << " " << rescue1);
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
  WARN("a sanitizer's build keeps freed memory aside: the peaks are not compared");
#else
  // (Searched on the parts, rank 1's peak is the CYCLE's last step, which writes the results it
  // leaves on the part, 8 MiB; through the whole model, the first step's search, before them.)
  CHECK(results1 > 0);
  CHECK(parts1 - results1 < 0.8 * whole1);
  CHECK(parts1 < parts0);
#endif
}

TEST_CASE("distributed: between CYCLEs the ranks keep their parts, rank 0 alone the whole model for the output",
          "[mpi][system]") {
  // A CYCLE's last step leaves its contact results on the parts: rank 0 alone runs PRINT and SAVE
  // (Command::on_ranks), the others serving it the results where it reads them, while they keep
  // their part and no more of the whole model than its balls' ids, types and radii; the next CYCLE
  // goes on from the parts. INIT before the first CYCLE (LATTICE's balls are held on the ranks
  // until INIT reads them, and placed in rank 0's model then) runs on rank 0 alone, and the others
  // take rank 0's model but the balls' arrays (their ids, types and radii alone): the CYCLE's split
  // sends each rank its part; INIT between CYCLEs runs on every rank's part (Session::change_balls).
  // The whole model is never handed over (it went to every rank, 28 MiB of this block's pairs).
  // The files, and the CYCLEs after each, give the serial bits.
  if (!can_run_mpi()) TRUBAL_SKIP(kNoMpi);
  const std::string built = "start 30 30 29.698484809834994\nprop kn 1e5 ks 1e5 fric 0.5 dens 2650\n"
                            "lattice fcc 1 30 30 42\n";
  // (HIST and DUMP run on every rank, rank 0 reading the balls for them: no hand-over either. The
  // HIST's `platen` of every ball, with no range, reads the whole model at its steps.)
  const std::string deck = "init xvel 0.01 range x 0 10\ncycle 20\n"
                           "print contacts file first.csv\nprint stress\nprint energy\n"
                           "hist energy ball 7 x vx platen every 5 file h.csv\ndump vtk d/s\ncycle 30\n" +
                           std::string(kOutputs);
  const std::string init = "init xvel 0.02 range x 0 10\n", after = "cycle 10\nprint balls file last.csv\n";
  TempDir serial, two;
  serial.write("deck.dat", built + deck + init + after);
  REQUIRE(run_deck(serial, 0) == 0);
  two.write("deck.dat", "backend mpi\n" + built + "print counters file built.txt\n" + deck +
                            "print counters file kept.txt\n" + init + "print counters file init.txt\n" + after + kCounters);
  REQUIRE(run_deck(two, 2) == 0);
  const std::string out = slurp(two.path() / "out.txt");
  INFO(out);
  for (const char* file : {"first.csv", "balls.csv", "contacts.csv", "last.csv", "h.csv"})
    CHECK(slurp(two.path() / file) == slurp(serial.path() / file));
  // PRINT stress and energy after the first CYCLE, which have the results gathered whole to rank 0
  // from the parts (the others serving its command), print what serial prints.
  auto readings = [](const std::string& text) {
    const auto from = text.find("trubal> print stress"), to = text.find("trubal> hist");
    return from == std::string::npos || to == std::string::npos ? std::string() : text.substr(from, to - from);
  };
  const std::string serial_readings = readings(slurp(serial.path() / "out.txt"));
  CHECK_THAT(serial_readings, Catch::Contains("stress: xx ") && Catch::Contains("strain: "));
  CHECK(readings(out) == serial_readings);
  CHECK(lines_of(slurp(serial.path() / "first.csv")).size() > 100000);   // most pairs of the block touch
  CHECK(lines_of(slurp(serial.path() / "h.csv")).size() > 8);
  int dumped = 0;
  for (const auto& entry : std::filesystem::directory_iterator(serial.path() / "d")) {
    INFO(entry.path().filename().string());
    CHECK(slurp(two.path() / "d" / entry.path().filename()) == slurp(entry.path()));
    ++dumped;
  }
  CHECK(dumped >= 4);   // (balls, contacts, domain and the collection)
  // After the second CYCLE and its PRINTs: the parts kept, rank 1 holding its part (about half the
  // balls and pairs) and no result, rank 0 the whole model with its results (43 MiB) and its part.
  const Counters kept = read_counters(two.path() / "kept.txt");
  CHECK(counter(kept, "parts_kept") == 1);
  // (For first.csv, the step taken again on the parts, where PRINT stress and DUMP read them; the
  // second CYCLE's last step is one HIST records, whose results rank 0's model takes at that step.)
  CHECK(counter(kept, "results_made") == 1);
  CHECK(counter(kept, "results_gathered") == 0);
  CHECK(counter(kept, "rank0_contact_results_mib") >= 20);
  CHECK(counter(kept, "rank1_contact_results_mib") == 0);
  CHECK(counter(kept, "rank0_model_held_mib") >= 40);
  CHECK(counter(kept, "rank1_model_held_mib") < 0.3 * counter(kept, "rank0_model_held_mib"));
  // After the INIT between CYCLEs: the parts kept, rank 1 holding its part as before it, nothing
  // gathered. After LATTICE, before the first INIT, each rank holds about half the lattice's balls
  // (model/held_balls.hpp: about 80 bytes a ball), which that INIT had rank 0 place in its model.
  const Counters light = read_counters(two.path() / "init.txt"), held = read_counters(two.path() / "built.txt");
  CHECK(counter(light, "parts_kept") == 1);
  CHECK(counter(light, "whole_gathers") == counter(kept, "whole_gathers"));
  CHECK(counter(light, "decompositions") == counter(kept, "decompositions"));
  CHECK(counter(light, "rank1_model_held_mib") == counter(kept, "rank1_model_held_mib"));
  CHECK(counter(held, "parts_kept") == 0);
  CHECK(counter(held, "balls_held") == 37800);
  for (const char* rank : {"rank0_model_held_mib", "rank1_model_held_mib"}) {
    INFO(rank);
    CHECK(counter(held, rank) > 0.04 * counter(kept, "rank0_model_held_mib"));
    CHECK(counter(held, rank) < 0.3 * counter(kept, "rank0_model_held_mib"));
  }
  // After INIT and one more CYCLE: the parts kept again; rank 1 got no results, and no command or
  // CYCLE handed the whole model over.
  const Counters counters = counters_of(two);
  CHECK(counter(counters, "parts_kept") == 1);
  CHECK(counter(counters, "whole_hand_overs") == 0);
  CHECK(counter(kept, "whole_hand_overs") == 0);
  CHECK(counter(counters, "rank1_contact_results_mib") == 0);
  CHECK(counter(counters, "rank1_model_held_mib") < 0.3 * counter(counters, "rank0_model_held_mib"));
}

TEST_CASE("distributed: RESTART hands each rank its part of the file, no rank holding the whole model: serial's bits", "[mpi][system]") {
  // A resting FCC block of 37,800 balls (a periodic cell, balls on its faces), its 226,800 contacts
  // and a history saved at cycle 20 (serially, and on 2 ranks: the same bytes), restarted on 3
  // ranks: rank 0 reads the file's light state and the balls' centres, splits them, then reads
  // each array of the balls, pairs and wall contacts a piece at a time (of 5000 rows here, so that
  // every table crosses pieces) and sends each rank its rows; the parts search their lists and hold
  // the saved history and contact results (Session::restart, Pipeline::parts_from_file). Before,
  // rank 0 held the whole model with its pairs from RESTART to the next CYCLE's split.
  if (!can_run_mpi()) TRUBAL_SKIP(kNoMpi);
  const std::string make = "start 30 30 29.698484809834994\nprop kn 1e5 ks 1e5 mu 0.5 dens 2650\n"
                           "lattice fcc 1 30 30 42\nhist energy every 5 file h.csv\ncycle 20\nsave s.sav\n";
  TempDir first, two;
  first.write("deck.dat", make);
  two.write("deck.dat", "backend mpi\n" + make);
  REQUIRE(run_deck(first, 0) == 0);
  REQUIRE(run_deck(two, 2) == 0);
  const std::string save = slurp(first.path() / "s.sav"), history = slurp(first.path() / "h.csv");
  CHECK(slurp(two.path() / "s.sav") == save);
  // (PRINT stress and contacts read the results on the parts; SAVE streams the parts' state.)
  const std::string rest = "print counters file r.txt\nprint stress\nprint contacts file c0.csv\nsave again.sav\n"
                           "cycle 30\nsave t.sav\n" + std::string(kOutputs) + kCounters;
  TempDir serial, ranks, ranks2;
  for (TempDir* dir : {&serial, &ranks, &ranks2}) {
    dir->write("s.sav", dir == &ranks2 ? slurp(two.path() / "s.sav") : save);
    dir->write("h.csv", history);
  }
  serial.write("deck.dat", "restart s.sav\n" + rest);
  for (TempDir* dir : {&ranks, &ranks2}) dir->write("deck.dat", "backend mpi\nrestart s.sav\n" + rest);
  REQUIRE(run_deck(serial, 0) == 0);
  REQUIRE(run_deck(ranks, 3, "TRUBAL_SAVE_PIECE=5000") == 0);
  REQUIRE(run_deck(ranks2, 3) == 0);
  const std::string out = slurp(ranks.path() / "out.txt"), serial_out = slurp(serial.path() / "out.txt");
  INFO(out);
  auto between = [](const std::string& text, const char* from, const char* to) {
    const auto a = text.find(from), b = text.find(to, a == std::string::npos ? 0 : a);
    return a == std::string::npos || b == std::string::npos ? std::string() : text.substr(a, b - a);
  };
  CHECK_THAT(serial_out, Catch::Contains("restarted from s.sav: 37800 balls, cycle 20"));
  CHECK_THAT(between(serial_out, "print stress", "print contacts"), Catch::Contains("stress: xx "));
  for (TempDir* dir : {&ranks, &ranks2}) {
    const std::string text = slurp(dir->path() / "out.txt");
    CHECK_THAT(text, Catch::Contains("restarted from s.sav: 37800 balls, cycle 20"));
    CHECK(between(text, "print stress", "print contacts") == between(serial_out, "print stress", "print contacts"));
    for (const char* file : {"c0.csv", "again.sav", "balls.csv", "contacts.csv", "h.csv", "t.sav"}) {
      INFO(file);
      CHECK(slurp(dir->path() / file) == slurp(serial.path() / file));
    }
  }
  CHECK(slurp(serial.path() / "again.sav") == save);   // (a save of a restarted model is the file's bytes)
  CHECK(lines_of(slurp(ranks.path() / "h.csv")).size() > 10);   // (the saved rows and the CYCLE's after)
  // After RESTART: every rank holds its part (a third of the balls, its pairs with their results,
  // its ghosts), rank 0 no more, and the parts are kept: nothing gathered the whole model.
  const Counters after = read_counters(ranks.path() / "r.txt"), end = counters_of(ranks);
  const Counters serial_end = counters_of(serial);
  const double whole = counter(serial_end, "model_held_mib");   // (serial's model after the CYCLE)
  CHECK(counter(after, "parts_from_saves") == 1);
  CHECK(counter(after, "parts_kept") == 1);
  CHECK(counter(after, "whole_hollow") == 1);
  CHECK(counter(after, "whole_gathers") == 0);
  CHECK(counter(end, "whole_gathers") == 0);
  CHECK(counter(end, "whole_hand_overs") == 0);
  CHECK(counter(end, "decompositions") == 1);
  for (const char* rank : {"rank0", "rank1", "rank2"}) {
    INFO(rank);
    CHECK(counter(after, std::string(rank) + "_model_held_mib") < 0.5 * whole);
    CHECK(counter(after, std::string(rank) + "_model_held_mib") > 0.2 * whole);
  }
  CHECK(counter(after, "rank0_peak_mib") < counter(after, "rank1_peak_mib") + 0.25 * whole);
}

TEST_CASE("distributed: a rank out of memory while RESTART hands out the parts stops every rank, and RESTART again works", "[mpi][system]") {
  // Rank 1 fails as out of memory as the parts are made from the file (TRUBAL_TEST_FAIL_AT "1
  // split"): every rank stops with its one message, and no model is left (the old one was
  // replaced, the new one part way to the parts); in the shell the next RESTART makes the parts,
  // and the run goes on with serial's bits.
  if (!can_run_mpi()) TRUBAL_SKIP(kNoMpi);
  TempDir first, serial, ranks;
  first.write("deck.dat", std::string(kSqueezedCell) + "cycle 300\nsave s.sav\n");
  REQUIRE(run_deck(first, 0) == 0);
  const std::string after = "cycle 200\nsave t.sav\n" + std::string(kOutputs);
  for (TempDir* dir : {&serial, &ranks}) dir->write("s.sav", slurp(first.path() / "s.sav"));
  serial.write("deck.dat", "restart s.sav\n" + after);
  REQUIRE(run_deck(serial, 0) == 0);
  ranks.write("deck.dat", "backend mpi\nrestart s.sav\n");
  ranks.write("more.txt", "print info\nrestart s.sav\n" + after + kCounters);
  CHECK(run_shell(ranks, 3, "TRUBAL_TEST_FAIL_AT='1 split'") == 0);   // (not 124: no rank hangs)
  const std::string out = slurp(ranks.path() / "out.txt");
  INFO(out);
  const auto at = out.find("deck.dat:2: error: 's.sav': the ranks could not take their parts of it: rank 1 ran out of "
                           "memory making its part of the decomposition from the save");
  REQUIRE(at != std::string::npos);
  CHECK(out.find("no model is left: RESTART again", at) != std::string::npos);
  CHECK(out.find("deck.dat:2:", at + 1) == std::string::npos);   // one message
  CHECK_THAT(out, Catch::Contains("space: none (START first)"));  // (PRINT info after it)
  for (const char* file : {"t.sav", "balls.csv", "contacts.csv"}) {
    INFO(file);
    CHECK(slurp(ranks.path() / file) == slurp(serial.path() / file));
  }
  CHECK(counter(counters_of(ranks), "parts_from_saves") == 1);
}

namespace {
// The deck serially and on 3 ranks (BACKEND mpi first, the shares equal: the tests count the
// decompositions), each in its own folder, each ending with the exit status `status`.
void run_both(const std::string& deck, TempDir& serial, TempDir& ranks, int status = 0) {
  serial.write("deck.dat", deck);
  ranks.write("deck.dat", "backend mpi\n" + deck);
  REQUIRE(run_deck(serial, 0) == status);
  REQUIRE(run_deck(ranks, 3, kEqualShares) == status);
}
}  // namespace

TEST_CASE("distributed: DELETE between CYCLEs deletes the balls on the ranks' parts, nothing gathered: serial's bits",
          "[mpi][system]") {
  // Balls settled onto a floor, a sphere of them deleted between CYCLEs, then a layer and a range
  // of ids after another CYCLE (with a history of the platen balls some of which go), on 3 ranks:
  // each rank reads the range on its own balls, the deleted balls' places go to every rank, and
  // each takes them out of its part and its whole model's light arrays, numbering the rest again
  // in their order (BrickStep::delete_balls); the next step searches afresh, as serial's does
  // after remove_balls. The contacts printed right after (their results kept for the pairs left),
  // the histories, the balls, contacts and save at the end: serial's bytes; nothing gathered (each
  // DELETE gathered the whole model to rank 0 and the next CYCLE split it again). A periodic cell
  // alike; a bonded block's DELETE runs on rank 0's whole model, the parts' state given to it
  // first, as before (its bonds are not deleted on the parts yet).
  if (!can_run_mpi()) TRUBAL_SKIP(kNoMpi);
  const std::string floor = R"(start box 0 0.02 0 0.02 0 0.04
prop kn 1e5 ks 1e5 mu 0.5 dens 2650
wall id 1 plane 0 0 0 0 0 1
gen porosity 0.5 0.0006 0.001 seed 3 range z 0 0.03
grav 0 0 -9.81
damp local 0.7
hist unbal contacts every 10 file h.csv
cycle 1000
hist platen every 10 file p.csv range z 0 0.003
delete range sphere 0.01 0.01 0.01 0.004
print counters file c1.txt
print contacts file c1.csv
cycle 200
delete range z 0.015 0.02
delete range id 30 60 not z 0.0015 0.03
print counters file c2.txt
cycle 100
save s.sav
)";
  const std::string cell = std::string(kSqueezedCell) + "cycle 700\ndelete range sphere 0.0035 0.0035 0.0035 0.0015\n"
                           "print counters file c1.txt\nprint contacts file c1.csv\ncycle 300\ndelete range id 1 40\n"
                           "print counters file c2.txt\ncycle 200\nsave s.sav\n";
  const std::string bonded = std::string("start box -3 8 -3 8 -3 8\nprop kn 1e8 ks 5e7 mu 0.5 dens 2000\nlattice fcc 1 5 5 7\n") +
                             "bond gap 1e-6 kn 2e8 ks 1e8 ten 2e5 coh 4e5 fa 30\ngrav 0 0 -9.81\nfix vel spin range z -1 0.1\n"
                             "cycle 100\ndelete range z 4 5\nprint counters file c1.txt\nprint contacts file c1.csv\ncycle 100\n"
                             "print counters file c2.txt\nsave s.sav\n";
  for (const auto& [name, deck] : {std::pair{"floor", floor}, std::pair{"cell", cell}, std::pair{"bonded", bonded}}) {
    INFO(name);
    TempDir serial, ranks;
    run_both(deck + kOutputs, serial, ranks);
    const std::string out = slurp(ranks.path() / "out.txt"), serial_out = slurp(serial.path() / "out.txt");
    INFO(out);
    for (const char* file : {"c1.csv", "s.sav", "balls.csv", "contacts.csv", "h.csv", "p.csv"}) {
      INFO(file);
      if (std::string(file).find(".csv") != std::string::npos && file[0] != 'c' && file[0] != 'b' && name != std::string("floor"))
        continue;
      CHECK(slurp(ranks.path() / file) == slurp(serial.path() / file));
    }
    CHECK(lines_of(slurp(serial.path() / "c1.csv")).size() > 20);
    auto deleted = [](const std::string& text) {
      std::string lines;
      for (const std::string& line : lines_of(text))
        if (line.find(" deleted") != std::string::npos) lines += line + '\n';
      return lines;
    };
    CHECK(!deleted(serial_out).empty());
    CHECK(deleted(out) == deleted(serial_out));
    const Counters first = read_counters(ranks.path() / "c1.txt"), second = read_counters(ranks.path() / "c2.txt");
    const bool on_parts = name != std::string("bonded");
    CHECK(counter(first, "parts_kept") == (on_parts ? 1 : 0));
    if (on_parts) {
      CHECK(counter(first, "whole_gathers") == 0);
      CHECK(counter(second, "whole_gathers") == 0);
      CHECK(counter(second, "decompositions") == 1);   // (the first CYCLE's split alone)
    }
  }
}

TEST_CASE("distributed: SOLVE keeps the ranks' parts between its checks and sums the ratio on them: serial's bits", "[mpi][system]") {
  // A squeezed periodic cell let go, SOLVEd on 3 ranks: each of SOLVE's CYCLEs of 100 keeps the
  // parts (no rank handed the whole model, nor the model split again), its last step's results
  // made on the parts and the ratio's sums merged there (Session::solve). Before, each CYCLE of
  // 100 ended by handing every rank the whole model, and the next split it again.
  if (!can_run_mpi()) TRUBAL_SKIP(kNoMpi);
  const std::string deck = "start 0.01 0.01 0.01\nprop kn 1e5 ks 1e5 mu 0.5 dens 2650\ngen 1500 0.0004 0.0005 seed 9\n"
                           "damp local 0.7\nstrain 150 150 150\ncycle 400\nstrain off\nprint counters file before.txt\n"
                           "solve ratio 0.02 limit 1500\nprint counters file after.txt\nsave s.sav\n" +
                           std::string(kOutputs);
  TempDir serial, ranks;
  run_both(deck, serial, ranks);
  const std::string out = slurp(ranks.path() / "out.txt"), serial_out = slurp(serial.path() / "out.txt");
  INFO(out);
  auto solved = [](const std::string& text) {
    std::string kept;
    for (const std::string& line : lines_of(text))
      if (line.find("solved:") != std::string::npos || line.find("SOLVE stopped") != std::string::npos) kept += line + '\n';
    return kept;
  };
  CHECK(!solved(serial_out).empty());
  CHECK(solved(out) == solved(serial_out));
  for (const char* file : {"balls.csv", "contacts.csv", "s.sav"}) {
    INFO(file);
    CHECK(slurp(ranks.path() / file) == slurp(serial.path() / file));
  }
  const Counters before = read_counters(ranks.path() / "before.txt"), after = read_counters(ranks.path() / "after.txt");
  CHECK(counter(after, "cycle") - counter(before, "cycle") >= 200);   // (at least two checks)
  CHECK(counter(after, "parts_kept") == 1);
  CHECK(counter(after, "whole_hand_overs") == counter(before, "whole_hand_overs"));
  CHECK(counter(after, "decompositions") == counter(before, "decompositions"));
}

namespace {
// What a deck printed after each `trubal> print <what>` line, up to the next prompt.
std::string printed(const std::string& out, const std::string& what) {
  std::string kept;
  bool in = false;
  for (const std::string& line : lines_of(out)) {
    if (line.rfind("trubal> ", 0) == 0) in = line == "trubal> print " + what;
    else if (in) kept += line + '\n';
  }
  return kept;
}
}  // namespace

// A measurement sphere's readings, one of them near the cell's corner (its nearest images).
constexpr const char* kSphereReadings =
    "print measure range sphere 0.0035 0.0035 0.0035 0.0015\nprint stress range sphere 0.0003 0.0066 0.0012 0.0012\n"
    "print fabric range sphere 0.0035 0.0035 0.0035 0.0015\nprint coordination range sphere 0.0035 0.0035 0.0035 0.0015\n"
    "print porosity range sphere 0.0035 0.0035 0.0035 0.0015\nprint porosity\n"
    // And PRINT balls and contacts of a range (a group, a negated element; the pairs with a ball
    // in it), from the parts' rows.
    "group corner range x 0 0.003 y 0 0.003\nprint balls file rb.csv range group corner not z 0.002 0.004\n"
    "print contacts file rc.csv range z 0.001 0.004 not type 2\nprint balls range id 1 12\n"
    "print contacts range id 40 60\n";

TEST_CASE("distributed: HIST of sums, DUMP and CYCLE until read the ranks' parts, rank 0 never handed the whole model: serial's bits",
          "[mpi][system]") {
  // Histories whose every item is a sum over the contacts or the balls (stress, pq, ratio, sratio,
  // unbal, contacts, a measurement sphere's) or the light state every rank holds (strain, volumetric, energy, porosity, a
  // wall's loads, the sample's measures) or a ball's values (its owner's: HistorySums::ball) or the
  // platen balls' (ratio, axial and platen with a range: their heights and forces in the model's
  // order, HistorySums::platens; HIST's choice of them between CYCLEs is read on the parts too): at
  // their output steps every rank records the row from the sums merged over the parts (the
  // capillary bridges' count too), which keep
  // their results there (CycleControl::
  // after_step_on_parts). Before, each output step gathered the whole model to rank 0, which then
  // held it to the CYCLE's end. CYCLE until checks its measure every k cycles with the parts kept
  // (rank 0 reads, the stress summed on the parts); before, it handed every rank the whole model.
  // A DUMP's files, in a CYCLE and between, are written from the parts' rows merged to rank 0 in
  // the whole model's order (Session::dump_from_parts); before, each dump gathered the whole model.
  // The sample between walls SHEARed by CYCLE until in CYCLEs of 100: one begins at a sort into
  // space order on the parts, whose lists are searched afresh there as serial's are (the parts kept
  // their lists, which gave serial's steps but not its save: the wall contacts' candidates).
  if (!can_run_mpi()) TRUBAL_SKIP(kNoMpi);
  const std::string cell = std::string(kSqueezedCell) +
                           "hist stress pq ratio sratio strain volumetric energy rolling unbal contacts porosity every 10 file h.csv\n"
                           "hist time unbal ball 7 x vx fz ball 300 y wz measure sphere 0.0035 0.0035 0.0035 0.0015 "
                           "measure sphere 0.0003 0.0066 0.0012 0.0012 every 7\n"
                           "hist ratio axial platen every 9 area 4.9e-5 pressure 1e3 file p.csv range not z 0.001 0.006\n"
                           "cycle 1205\n" + std::string(kSphereReadings) +
                           "print counters file c1.txt\nhist platen axial every 11 file p2.csv range not z 0.0015 0.0055\n"
                           "print counters file c1b.txt\ncycle 600 until q -500 every 50\ncycle 2000 until axial 0.2 every 20\n"
                           "print history\nprint strain\nprint counters file c2.txt\nsave s.sav\n" + std::string(kOutputs);
  const std::string walls = R"(start box -0.04 0.04 -0.04 0.04 -0.01 0.11
prop kn 2e6 ks 2e6 fric 30 dens 2650
prop type 2 kn 2e6 ks 2e6 fric 0
wall id 1 plane 0 0 0 0 0 1 type 2
wall id 2 plane 0 0 0.1 0 0 -1 type 2
wall id 3 cylinder 0 0 -0.005 0 0 1 radius 0.02 length 0.11 type 2
sample platens 1 2 cylinder 3
gen 1500 0.0015 0.0025 seed 11
damp local 0.7
servo wall 1 stress 1e5 in 3 max 0.05
servo wall 2 stress 1e5 in 3 max 0.05
servo wall 3 stress 1e5 between 1 2 max 0.05
hist sample wall 3 wall 1 energy unbal contacts porosity stress measure sphere 0 0.002 0.008 0.01 every 50 file h.csv
dump vtk d/w every 2000
cycle 3000
print measure range sphere 0.005 0 0.006 0.008
print counters file c1.txt
servo wall 1 off
servo wall 2 off
wall id 1 velocity 0 0 0.02
wall id 2 velocity 0 0 -0.02
sample reset
print counters file c1b.txt
cycle 5000 until axial 0.004 every 100
print history
print walls
print sample
print counters file c2.txt
save s.sav
)" + std::string(kOutputs);
  // And the cell dumped every 400 cycles (a ball's line is across the cell's faces), and once
  // between CYCLEs where the parts alone hold the model: the rows come from the parts.
  std::string dumped = cell;
  dumped.insert(dumped.find("cycle 1205"), "dump vtk d/run every 400\n");
  dumped.insert(dumped.find("print counters file c1b.txt"), "dump vtk d/run every 400\n");
  // And the cell wet (capillary bridges), its history counting them: summed over the parts.
  std::string wet = cell;
  wet.insert(wet.find("hist stress pq"), "prop bridge 1e-12 tension 0.072\n");
  wet.replace(wet.find("stress pq ratio sratio strain volumetric energy rolling unbal contacts porosity"),
              std::string("stress pq ratio sratio strain volumetric energy rolling unbal contacts porosity").size(),
              "bridges stress contacts");
  for (const auto& [name, deck] :
       {std::pair{"cell", cell}, std::pair{"walls", walls}, std::pair{"dumped", dumped}, std::pair{"wet", wet}}) {
    INFO(name);
    TempDir serial, ranks;
    run_both(deck, serial, ranks);
    const std::string out = slurp(ranks.path() / "out.txt"), serial_out = slurp(serial.path() / "out.txt");
    INFO(out);
    for (const char* file : {"h.csv", "balls.csv", "contacts.csv", "s.sav", "rb.csv", "rc.csv", "p.csv", "p2.csv"}) {
      INFO(file);
      const bool cell_only = std::string(file).starts_with("r") || std::string(file).starts_with("p");
      if (cell_only && name == std::string("walls")) continue;
      CHECK(slurp(ranks.path() / file) == slurp(serial.path() / file));
      if (cell_only) CHECK(lines_of(slurp(serial.path() / file)).size() > 5);
    }
    if (name != std::string("walls"))
      for (const char* what : {"balls range id 1 12", "contacts range id 40 60"}) {
        INFO(what);
        CHECK(lines_of(printed(serial_out, what)).size() > 5);
        CHECK(printed(out, what) == printed(serial_out, what));
      }
    // The dumps a CYCLE wrote (after the one DUMP wrote at cycle 0) up to a cycle: serial's files.
    std::vector<std::int64_t> dumps;
    if (std::filesystem::exists(serial.path() / "d"))
      for (const auto& e : std::filesystem::directory_iterator(serial.path() / "d")) {
        const std::string file = e.path().filename().string();
        INFO(file);
        CHECK(slurp(ranks.path() / "d" / file) == slurp(e.path()));
        if (file.size() == 14 && file.rfind("run_", 0) == 0 && file.ends_with(".vtp") && std::stoll(file.substr(4, 6)) > 0)
          dumps.push_back(std::stoll(file.substr(4, 6)));
      }
    CHECK(dumps.size() == (name == std::string("dumped") ? 6u : 0u));
    // (Rows in memory alone, and the file's: rank 0 recorded them with the others.)
    CHECK(lines_of(printed(serial_out, "history")).size() > 20);
    for (const char* what : {"history", "strain", "walls", "sample"}) {
      INFO(what);
      CHECK(printed(out, what) == printed(serial_out, what));
    }
    // A measurement sphere's readings between CYCLEs, from the sums over the parts (the wall
    // contacts' too, in the walled sample's sphere on its base), print serial's.
    for (const std::string what : {"measure range sphere 0.0035 0.0035 0.0035 0.0015", "stress range sphere 0.0003 0.0066 0.0012 0.0012",
                                   "fabric range sphere 0.0035 0.0035 0.0035 0.0015", "coordination range sphere 0.0035 0.0035 0.0035 0.0015",
                                   "porosity range sphere 0.0035 0.0035 0.0035 0.0015", "porosity", "measure range sphere 0.005 0 0.006 0.008"}) {
      INFO(what);
      const bool walled = what.ends_with("0.008");
      if (walled != (name == std::string("walls"))) continue;
      CHECK_THAT(printed(serial_out, what), Catch::Contains(what == "porosity" ? "porosity: " : "measurement sphere at"));
      CHECK(printed(out, what) == printed(serial_out, what));
    }
    auto reached = [](const std::string& text) {
      std::string kept;
      for (const std::string& line : lines_of(text))
        if (line.rfind("reached ", 0) == 0) kept += line + '\n';
      return kept;
    };
    CHECK(!reached(serial_out).empty());
    CHECK(reached(out) == reached(serial_out));
    // No output step, no dump, no check of CYCLE until's and no PRINT of the light state above
    // gathered the whole model to rank 0.
    const Counters first = read_counters(ranks.path() / "c1.txt"), before = read_counters(ranks.path() / "c1b.txt"),
                   after = read_counters(ranks.path() / "c2.txt");
    // (The wet cell's CYCLE until met a CYCLE whose last step rebuilt the parts' lists: the copy of
    // the step before, taken before the rebuild, could not be put back on the parts, and the step
    // was taken again through the whole model gathered to rank 0. The lists are now rebuilt before
    // that copy is taken: Pipeline::rebuild_before_copy.)
    for (const Counters* c : {&first, &before, &after}) CHECK(counter(*c, "whole_gathers") == 0);
    // (CYCLE until's CYCLEs of k keep the parts: the walls' first splits afresh, after the WALL
    // lines' edits on rank 0.)
    CHECK(counter(after, "decompositions") - counter(before, "decompositions") <= 1);
    for (const Counters* c : {&first, &after}) {
      CHECK(counter(*c, "parts_kept") == 1);
      CHECK(counter(*c, "whole_hollow") == 1);
      CHECK(counter(*c, "whole_hand_overs") == 0);
    }
  }
}

TEST_CASE("distributed: a RESTART's parts hold the save's wall contacts, history and contact results: serial's bits",
          "[mpi][system]") {
  // Saves made serially, restarted serially and on 3 ranks (the tables handed out 300 rows at a
  // time): a triaxial sample between servo walls (wall contacts with history), and a squeezed
  // periodic cell with rolling resistance, capillary bridges and a history. After RESTART the
  // parts hold the file's wall contacts as serial's table does until the first step's search (a
  // SAVE then is the file's bytes), the pairs' history and the contact results (PRINT reads them
  // there); the CYCLEs after, a rank-0 edit, WALL and SERVO go on from the parts as after a CYCLE.
  // And Rowe's sample with a following membrane and its platens' history.
  if (!can_run_mpi()) TRUBAL_SKIP(kNoMpi);
  struct Scene {
    const char* name;
    std::string make, deck;
    std::vector<const char*> files, prints;
  };
  const std::vector<Scene> scenes = {
      {"walls",
       "start box -0.04 0.04 -0.04 0.04 -0.01 0.11\nprop kn 2e6 ks 2e6 fric 30 dens 2650\nprop type 2 kn 2e6 ks 2e6 fric 0\n"
       "wall id 1 plane 0 0 0 0 0 1 type 2\nwall id 2 plane 0 0 0.1 0 0 -1 type 2\n"
       "wall id 3 cylinder 0 0 -0.005 0 0 1 radius 0.02 length 0.11 type 2\nsample platens 1 2 cylinder 3\n"
       "gen 1500 0.0015 0.0025 seed 11\ndamp local 0.7\nservo wall 1 stress 1e5 in 3 max 0.05\n"
       "servo wall 2 stress 1e5 in 3 max 0.05\nservo wall 3 stress 1e5 between 1 2 max 0.05\ncycle 3000\nsave s.sav\n",
       "restart s.sav\nprint counters file r.txt\nsave again.sav\nprint stress\nprint energy\nprint walls\n"
       "print contacts file c0.csv\ncycle 1500\nsave t.sav\nservo wall 1 off\nservo wall 2 off\n"
       "wall id 1 velocity 0 0 0.02\nwall id 2 velocity 0 0 -0.02\ncycle 1000\nsave u.sav\nprint walls\n",
       {"again.sav", "c0.csv", "t.sav", "u.sav"},
       {"stress", "energy", "walls"}},
      {"wet cell",
       "start 0.01 0.01 0.01\nprop kn 1e5 ks 1e5 fric 26.57 dens 2650 rr_fric 0.1\nprop bridge 1e-12 tension 0.072\n"
       "gen 1200 0.0004 0.0006 seed 7\ndamp local 0.7\nstrain 20 20 20\ncycle 700\n"
       "hist pq unbal bridges every 50 file h.csv\ncycle 300\nsave s.sav\n",
       "restart s.sav\nprint counters file r.txt\nsave again.sav\nprint stress\nprint energy\n"
       "print contacts file c0.csv\ncycle 800\nsave t.sav\nprint energy\nprop type 1 fric 10\ncycle 200\nsave u.sav\n",
       {"again.sav", "c0.csv", "t.sav", "u.sav", "h.csv"},
       {"stress", "energy"}},
      // (A following membrane: its loads are the balls' applied loads, handed out with them; it
      // follows on the parts after, Pipeline::follow_membrane_on_parts. Before, such a save was
      // read whole on rank 0.)
      {"membrane",
       "start box -200 440 -200 440 -100 450\nprop kn 1.5e9 ks 1.5e9 fric 7 dens 2000\n"
       "lattice fcc 40 7 7 13 layers even range octagon 120 120 120 127\n"
       "lattice fcc 40 7 7 13 layers odd  range octagon 120 120 120 99\ngroup bottom range z -10 10\n"
       "group top range z 330 350\nmembrane 5e4 follow every 3\ndamp 0.05 0.5\napply zforce -8e7 range group top\n"
       "apply zforce 8e7 range group bottom\nhist ratio axial unbal every 10 file h.csv range not z 10 330\ncycle 301\nsave s.sav\n",
       "restart s.sav\nprint counters file r.txt\nsave again.sav\nprint stress\ncycle 299\nsave t.sav\n",
       {"again.sav", "t.sav", "h.csv"},
       {"stress"}},
  };
  for (const Scene& scene : scenes) {
    INFO(scene.name);
    TempDir first, serial, ranks;
    first.write("deck.dat", scene.make);
    REQUIRE(run_deck(first, 0) == 0);
    for (TempDir* dir : {&serial, &ranks}) {
      dir->write("s.sav", slurp(first.path() / "s.sav"));
      if (std::filesystem::exists(first.path() / "h.csv")) dir->write("h.csv", slurp(first.path() / "h.csv"));
    }
    serial.write("deck.dat", scene.deck + kCounters);
    ranks.write("deck.dat", "backend mpi\n" + scene.deck + kCounters);
    REQUIRE(run_deck(serial, 0) == 0);
    REQUIRE(run_deck(ranks, 3, kEqualShares + " TRUBAL_SAVE_PIECE=300") == 0);
    const std::string out = slurp(ranks.path() / "out.txt"), serial_out = slurp(serial.path() / "out.txt");
    INFO(out);
    CHECK(slurp(serial.path() / "again.sav") == slurp(first.path() / "s.sav"));
    for (const char* file : scene.files) {
      INFO(file);
      CHECK(slurp(ranks.path() / file) == slurp(serial.path() / file));
    }
    for (const char* what : scene.prints) {
      INFO(what);
      CHECK(!printed(serial_out, what).empty());
      CHECK(printed(out, what) == printed(serial_out, what));
    }
    const Counters after = read_counters(ranks.path() / "r.txt"), end = counters_of(ranks);
    CHECK(counter(after, "parts_from_saves") == 1);
    CHECK(counter(after, "whole_hollow") == 1);
    CHECK(counter(end, "whole_hand_overs") == 0);
  }
}

TEST_CASE("distributed: WALL's motion and SERVO wall between CYCLEs leave the ranks their parts, nothing gathered: serial's bits",
          "[mpi][system]") {
  // A triaxial sample consolidated between servo walls, then SERVO wall off and WALL velocity (the
  // shear's start), later the cylinder's servo off and a radius rate of its own, each between CYCLEs on 3
  // ranks: every rank changes its walls, the results the CYCLE deferred made on the parts first
  // (Session::edit_walls); SAMPLE reset, which reads the walls alone, runs on every rank. Before,
  // each WALL line gathered the model to rank 0 and ended the parts, and the next CYCLE split it
  // again; each SERVO wall and SAMPLE gathered it to rank 0.
  if (!can_run_mpi()) TRUBAL_SKIP(kNoMpi);
  const std::string deck =
      "start box -0.04 0.04 -0.04 0.04 -0.01 0.11\nprop kn 2e6 ks 2e6 fric 30 dens 2650\nprop type 2 kn 2e6 ks 2e6 fric 0\n"
      "wall id 1 plane 0 0 0 0 0 1 type 2\nwall id 2 plane 0 0 0.1 0 0 -1 type 2\n"
      "wall id 3 cylinder 0 0 -0.005 0 0 1 radius 0.02 length 0.11 type 2\nsample platens 1 2 cylinder 3\n"
      "gen 1500 0.0015 0.0025 seed 11\ndamp local 0.7\nservo wall 1 stress 1e5 in 3 max 0.05\n"
      "servo wall 2 stress 1e5 in 3 max 0.05\nservo wall 3 stress 1e5 between 1 2 max 0.05\ncycle 3000\n"
      "print counters file before.txt\nservo wall 1 off\nservo wall 2 off\nwall id 1 velocity 0 0 0.02\n"
      "wall id 2 velocity 0 0 -0.02\nsample reset\nprint walls\nsave s1.sav\nprint contacts file k1.csv\ncycle 1000\nsave s2.sav\n"
      "servo wall 3 off\nwall id 3 rrate -0.01\ncycle 500\nsave s3.sav\nprint walls\nprint sample\n" +
      std::string(kOutputs) + kCounters;
  TempDir serial, ranks;
  run_both(deck, serial, ranks);
  const std::string out = slurp(ranks.path() / "out.txt"), serial_out = slurp(serial.path() / "out.txt");
  INFO(out);
  for (const char* file : {"s1.sav", "k1.csv", "s2.sav", "s3.sav", "balls.csv", "contacts.csv"}) {
    INFO(file);
    CHECK(slurp(ranks.path() / file) == slurp(serial.path() / file));
  }
  CHECK_THAT(printed(serial_out, "walls"), Catch::Contains("velocity (0, 0, 0.02)") && Catch::Contains("radius rate -0.01"));
  CHECK(printed(out, "walls") == printed(serial_out, "walls"));
  CHECK_THAT(printed(serial_out, "sample"), Catch::Contains("axial strain"));
  CHECK(printed(out, "sample") == printed(serial_out, "sample"));
  const Counters before = read_counters(ranks.path() / "before.txt"), after = counters_of(ranks);
  CHECK(counter(after, "parts_kept") == 1);
  CHECK(counter(after, "decompositions") == counter(before, "decompositions"));
  CHECK(counter(after, "whole_gathers") == counter(before, "whole_gathers"));
  CHECK(counter(after, "whole_hand_overs") == 0);
}

TEST_CASE("distributed: INIT, APPLY, FIX, FREE, GROUP and PROP between CYCLEs change the ranks' parts, nothing gathered: serial's bits",
          "[mpi][system]") {
  // A squeezed periodic cell whose balls are changed between CYCLEs on 3 ranks by ranges of every
  // kind (a height, a box, a sphere, ids, groups read on the parts): every rank changes its own
  // balls and its ghosts (Session::change_balls), FIX's fixities go to rank 0's hollow whole model,
  // which keeps them, and the counts printed are summed over the ranks; PROP's density and a law
  // new to the scene (rolling resistance: its history part added) go to each part, which takes its
  // balls' masses from them (BrickStep::take_materials). Then the same after a
  // CYCLE whose last step the platen history of every ball read (rank 0's whole model current: changed alike).
  // Before, each line gathered the model to rank 0 and ended the parts, and the next CYCLE split it
  // again (3 decompositions and 2 gathers where 1 and 0 are asserted).
  if (!can_run_mpi()) TRUBAL_SKIP(kNoMpi);
  const std::string deck = std::string(kSqueezedCell) + R"(cycle 400
print counters file c1.txt
group low range z -1 0.002
group mid range z 0.003 0.004 x 0.001 0.005
init zvel 0.01 xspin 3 range group low
fix zvel xspin range group low
apply xforce 1e-4 zmom 1e-9 range sphere 0.0035 0.0035 0.0035 0.002
init xvel -0.02 range group mid
free xspin range id 1 100
prop kn 1.5e5 dens 3000 rr_fric 0.05
print counters file c2.txt
save s1.sav
cycle 300
apply off range id 1 400
free vel range group low
cycle 200
print counters file c3.txt
hist platen every 100
cycle 200
print counters file c4.txt
init yvel 0.001 range z 0 0.003
fix vel range id 5 50
prop dens 2650 rr_fric 0.1
cycle 100
save s2.sav
)" + std::string(kOutputs);
  TempDir serial, ranks;
  run_both(deck, serial, ranks);
  const std::string out = slurp(ranks.path() / "out.txt"), serial_out = slurp(serial.path() / "out.txt");
  INFO(out);
  for (const char* file : {"s1.sav", "s2.sav", "balls.csv", "contacts.csv"}) {
    INFO(file);
    CHECK(slurp(ranks.path() / file) == slurp(serial.path() / file));
  }
  // Each command's line (its count) as serial's.
  for (const char* line : {"group low: ", "group mid: ", "balls set", "balls fixed", "balls loaded", "balls freed", "balls unloaded"}) {
    INFO(line);
    auto kept = [&](const std::string& text) {
      std::string k;
      for (const std::string& l : lines_of(text))
        if (l.find(line) != std::string::npos && l.rfind("trubal> ", 0) != 0) k += l + '\n';
      return k;
    };
    CHECK(!kept(serial_out).empty());
    CHECK(kept(out) == kept(serial_out));
  }
  const Counters first = read_counters(ranks.path() / "c1.txt"), edited = read_counters(ranks.path() / "c2.txt"),
                 hollow_end = read_counters(ranks.path() / "c3.txt"), whole_end = read_counters(ranks.path() / "c4.txt");
  for (const Counters* c : {&first, &edited, &hollow_end}) {
    CHECK(counter(*c, "decompositions") == 1);
    CHECK(counter(*c, "whole_gathers") == 0);
    CHECK(counter(*c, "whole_hollow") == 1);
    CHECK(counter(*c, "parts_kept") == 1);
  }
  CHECK(counter(whole_end, "whole_hollow") == 0);   // (the platen's history read the last step whole)
  CHECK(counter(whole_end, "parts_kept") == 1);
}

TEST_CASE("distributed: DAMP, FRAC, TSTEP, GRAV, STRAIN and SERVO between CYCLEs leave the ranks their parts, with the serial bits",
          "[mpi][system]") {
  // A squeezed periodic cell whose settings change between nine CYCLEs: each setting's command runs
  // on every rank's model as it is (Command::on_ranks), the ranks first gathering to rank 0 the
  // results the CYCLE's last step left on the parts (taken again, they would read the changed
  // setting), and the next CYCLE estimates its step
  // afresh on the parts, their list made current first (it read a stale list, and the estimate went
  // 14% long, when it was not: the third CYCLE parted from serial). STRAIN's change of the velocity
  // field goes to the parts and to rank 0's model alike (Pipeline::apply_field_kept), its work summed
  // exactly as serial's is; SERVO's first reading of the contact table is summed on the parts, the
  // stress and the stiffness exact sums as serial's are.
  if (!can_run_mpi()) TRUBAL_SKIP(kNoMpi);
  const std::string deck = std::string(kSqueezedCell) + R"(set sort 0
cycle 700
print contacts file first.csv
damp 0.05 2000
cycle 300
frac 0.5
cycle 300
grav 0 0 -9.81
cycle 200
tstep 2e-7
cycle 200
tstep auto
damp local 0.5
cycle 300
strain xx 60 yy 60 zz 90 xy 20
cycle 200
servo 1e3 1e3 1e3
cycle 200
servo off
strain reset
cycle 100
)" + std::string(kOutputs);
  TempDir serial;
  serial.write("deck.dat", deck);
  REQUIRE(run_deck(serial, 0) == 0);
  // (The squeeze leaves contacts that carry history; the servo's low target lets most of them go.)
  REQUIRE(lines_of(slurp(serial.path() / "first.csv")).size() > 20);
  REQUIRE(lines_of(slurp(serial.path() / "contacts.csv")).size() > 3);
  for (int ranks : {2, 3}) {
    TempDir dir;
    dir.write("deck.dat", "backend mpi\n" + deck + kCounters);
    REQUIRE(run_deck(dir, ranks) == 0);
    INFO(ranks << " ranks\n" << slurp(dir.path() / "out.txt"));
    for (const char* file : {"first.csv", "balls.csv", "contacts.csv"})
      CHECK(slurp(dir.path() / file) == slurp(serial.path() / file));
    const Counters counters = counters_of(dir);
    CHECK(counter(counters, "parts_kept") == 1);
    // No command between the CYCLEs had the whole model handed over (the split count follows the
    // ranks' measured speeds, so it depends on the machine's load: the hand-overs do not).
    CHECK(counter(counters, "whole_hand_overs") == 0);
    // The ranks took a CYCLE's last step again on their parts for first.csv, for the STRAIN and
    // the SERVOs that change the cell's rates (the settings leave the results deferred: the step
    // taken again reads the settings it was taken with) and for the outputs, and never gathered
    // them to rank 0: the STRAIN and both SERVO lines leave them on the parts (Session::edit_cell;
    // before, each of the three changes gathered them, and SERVO off, a change where a servo
    // drives the cell, still did), and first.csv and the outputs read them there, an array at a
    // time. The servo's first reading of the contact table, where contacts touch, is summed on the
    // parts (Pipeline::servo_reading_on_parts; before, the results were gathered and the whole
    // model handed to every rank for it: results_gathered 2, cycle_hand_overs 1).
    CHECK(counter(counters, "results_made") == 5);
    CHECK(counter(counters, "results_gathered") == 0);
    CHECK(counter(counters, "cycle_hand_overs") == 0);
  }
  // A servo from the start (GEN, SERVO, CYCLE): its first reading, of a table where nothing
  // touches yet, is of no force and no stiffness, as serial's: no rank is handed the whole model
  // for it (before, every rank was, at the first CYCLE's start).
  const std::string servo = "start 0.007 0.007 0.007\nprop kn 1e5 ks 1e5 fric 26.57 dens 2650\n"
                            "gen porosity 0.42 0.0003 0.0005 seed 5\ndamp local 0.7\nservo 1e3 1e3 1e3\ncycle 400\n"
                            "servo 2e3 1e3 1e3\ncycle 300\n" + std::string(kOutputs);
  TempDir serial_servo;
  serial_servo.write("deck.dat", servo);
  REQUIRE(run_deck(serial_servo, 0) == 0);
  REQUIRE(lines_of(slurp(serial_servo.path() / "contacts.csv")).size() > 100);
  TempDir ranks_servo;
  ranks_servo.write("deck.dat", "backend mpi\n" + servo + kCounters);
  REQUIRE(run_deck(ranks_servo, 3) == 0);
  INFO(slurp(ranks_servo.path() / "out.txt"));
  for (const char* file : {"balls.csv", "contacts.csv"}) CHECK(slurp(ranks_servo.path() / file) == slurp(serial_servo.path() / file));
  const Counters counters = counters_of(ranks_servo);
  CHECK(counter(counters, "cycle_hand_overs") == 0);
  CHECK(counter(counters, "whole_hand_overs") == 0);
  CHECK(counter(counters, "parts_kept") == 1);
  // (No gather: the second SERVO, a change where a servo drives the cell, has the results made on
  // the parts, Session::edit_cell, where they were gathered through rank 0's whole model. No
  // CYCLE's end gathers either.)
  CHECK(counter(counters, "whole_gathers") == 0);
}

TEST_CASE("a setting between CYCLEs leaves the results deferred: read after it, they are of the step as it was taken",
          "[mpi][system]") {
  // DAMP, FRAC and GRAV after a CYCLE do not make the contact results its last step deferred: the
  // step taken again to make them when read uses the settings it was first taken with
  // (Pipeline::Deferred), and a CYCLE that follows, whose steps read the new settings, drops them.
  // Read after the settings they are those read before them (a step taken again with the new
  // damping and gravity gives other forces: the 700th step's squeeze is still on), and the next
  // CYCLE gives the same bits whether they were read before the settings, after, or not at all;
  // under mpirun the parts make them and nothing gathers them whole to rank 0.
  const std::string setup = std::string(kSqueezedCell) + "cycle 700\n";
  const std::string settings = "damp local 0.2\nfrac 0.5\ngrav 0 0 -9.81\n";
  const std::string after = "cycle 40\n" + std::string(kOutputs) + kCounters;
  TempDir before, read, unread;
  before.write("deck.dat", setup + "print contacts file before.csv\n" + settings + "print contacts file after.csv\n" + after);
  read.write("deck.dat", setup + settings + "print contacts file after.csv\n" + after);
  unread.write("deck.dat", setup + settings + after);
  for (TempDir* dir : {&before, &read, &unread}) REQUIRE(run_deck(*dir, 0) == 0);
  const std::string contacts = slurp(before.path() / "before.csv");
  REQUIRE(lines_of(contacts).size() > 20);
  CHECK(slurp(before.path() / "after.csv") == contacts);
  CHECK(slurp(read.path() / "after.csv") == contacts);
  for (const TempDir* dir : {&read, &unread})
    for (const char* file : {"balls.csv", "contacts.csv"}) CHECK(slurp(dir->path() / file) == slurp(before.path() / file));
  // (before: for its first PRINT, none for the settings; read: after them; unread: none; each then
  // once for the outputs after the last CYCLE.)
  CHECK(counter(counters_of(before), "results_made") == 2);
  CHECK(counter(counters_of(read), "results_made") == 2);
  CHECK(counter(counters_of(unread), "results_made") == 1);
  if (!can_run_mpi()) TRUBAL_SKIP(kNoMpi);
  TempDir ranks;
  ranks.write("deck.dat", "backend mpi\n" + setup + settings + "print contacts file after.csv\n" + after);
  REQUIRE(run_deck(ranks, 3) == 0);
  INFO(slurp(ranks.path() / "out.txt"));
  CHECK(slurp(ranks.path() / "after.csv") == contacts);
  for (const char* file : {"balls.csv", "contacts.csv"}) CHECK(slurp(ranks.path() / file) == slurp(before.path() / file));
  const Counters counters = counters_of(ranks);
  CHECK(counter(counters, "results_made") == 2);
  CHECK(counter(counters, "results_gathered") == 0);
  CHECK(counter(counters, "parts_kept") == 1);
}

TEST_CASE("distributed: the results a read made on the parts, their copy gone, reach whatever reads them next", "[mpi][system]") {
  // The first PRINT takes the CYCLE's last step again on the parts from their copies in place and
  // lets the copies go (Pipeline::release_rescue): the results are then on the parts alone. Each
  // command after it must find them there: a command handed the whole model (RENUMBER: rank 0
  // gathers them first, Pipeline::share_whole), one rank 0 alone runs after a change (PROP: made
  // where every rank agrees, Session::model_on_zero), a setting (none made), DUMP, a HIST with a
  // range, and PRINT stress and contacts; the files are serial's, byte for byte, and each rank's
  // copy is gone after the first PRINT.
  if (!can_run_mpi()) TRUBAL_SKIP(kNoMpi);
  const std::string deck = std::string(kSqueezedCell) + "cycle 700\n" + kCounters +
                           "print contacts file a.csv\nprint counters file after_print.txt\n"
                           "renumber\nprint contacts file b.csv\ncycle 20\nprint contacts file c.csv\n"
                           "prop kn 2e5\nprint contacts file d.csv\ncycle 20\ndamp local 0.3\ndump vtk d/s\n"
                           "hist platen every 5 file h.csv range id 1 40\nprint stress\nprint contacts file e.csv\ncycle 20\n" +
                           kOutputs;
  TempDir serial, ranks;
  serial.write("deck.dat", deck);
  REQUIRE(run_deck(serial, 0) == 0);
  ranks.write("deck.dat", "backend mpi\n" + deck);
  REQUIRE(run_deck(ranks, 3) == 0);
  INFO(slurp(ranks.path() / "out.txt"));
  REQUIRE(lines_of(slurp(serial.path() / "a.csv")).size() > 20);
  for (const char* file : {"a.csv", "b.csv", "c.csv", "d.csv", "e.csv", "h.csv", "balls.csv", "contacts.csv"})
    CHECK(slurp(ranks.path() / file) == slurp(serial.path() / file));
  const Counters before = counters_of(ranks), after = read_counters(ranks.path() / "after_print.txt");
  CHECK(counter(before, "rank1_rescue_copy_mib") > 0);
  CHECK(counter(after, "rank1_rescue_copy_mib") == 0);
  CHECK(counter(after, "rank0_rescue_copy_mib") == 0);
  CHECK(counter(after, "results_made") == 1);
}

TEST_CASE("distributed: a run that goes unstable is put back to the same rescue copy as serial's", "[mpi][system]") {
  // A chain held between two fixed balls, stepped a little above its critical step from an overlap
  // of 1e-14: the error grows for some hundred steps, so the copy put back is one taken in the
  // CYCLE (at cycle 500), which on several ranks each rank holds of its own part and which is put
  // back to rank 0's whole model and handed to the others (Pipeline::restore_rescue,
  // BrickStep::whole_from_copy); every rank then steps through the whole model to the same message.
  // Cut at cycle 605, the second CYCLE starts from the parts and reuses the copies of the step
  // before (cycle 604) as its own: the instability comes before its next copy, so that copy is put
  // back and its step taken again, as serial's cut run does, with the results current.
  if (!can_run_mpi()) TRUBAL_SKIP(kNoMpi);
  const std::string setup = R"(start box -1 1 -1 1 -1 1
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
)";
  // Cut at 605 with the results read between too (the step taken again on the parts, their copies
  // let go, as serial's make_results lets its copy go): the second CYCLE then takes a copy of its
  // own at 605 and goes back to it, with serial's message (the results not kept, there too).
  struct Cut {
    const char* between;   // the deck's lines before the CYCLE that goes unstable
    const char* back;      // where the message says the model is
    bool results_kept;
  };
  for (const Cut& cut : {Cut{"", "back at cycle 500,", true}, Cut{"cycle 605\n", "back at cycle 605,", true},
                         Cut{"cycle 605\nprint contacts file c605.csv\n", "back at cycle 605,", false}}) {
    const std::string deck = setup + cut.between + "cycle 5000\n";
    INFO("before the last CYCLE: " << cut.between);
    TempDir serial;
    serial.write("deck.dat", deck);
    REQUIRE(run_deck(serial, 0) == 1);
    const std::string out = slurp(serial.path() / "out.txt");
    const auto at = out.find("error: unstable at cycle");
    REQUIRE(at != std::string::npos);
    const std::string message = out.substr(at, out.find('\n', at) - at);
    INFO(message);
    REQUIRE(message.find(cut.back) != std::string::npos);
    // (The results are those of the state put back.)
    if (cut.results_kept) CHECK(message.find("not kept") == std::string::npos);
    for (int ranks : {2, 3}) {
      TempDir dir;
      dir.write("deck.dat", "backend mpi\n" + deck);
      CHECK(run_deck(dir, ranks) == 1);
      INFO(ranks << " ranks\n" << slurp(dir.path() / "out.txt"));
      CHECK_THAT(slurp(dir.path() / "out.txt"), Catch::Contains(message));
      for (const char* file : {"h.csv", "c605.csv"})
        if (std::filesystem::exists(serial.path() / file)) CHECK(slurp(dir.path() / file) == slurp(serial.path() / file));
    }
  }
}

TEST_CASE("distributed: Rowe's test with a following membrane runs by the spatial decomposition, with the serial bits",
          "[mpi][system]") {
  // The membrane's forces are made again from the positions every 3 cycles: where the ranks' parts
  // are live, from the loaded balls' centres their owners send to every rank in the membrane's
  // order, each rank setting the loads on its part's balls, rank 0 on its hollow whole model's
  // arrays (Pipeline::follow_membrane_on_parts); else through the whole model (loads_changed). A
  // part that kept the old loads parted from serial at the first cycle after 3. Rowe's history,
  // its platens' ratio and axial strain, is recorded on the parts too: nothing gathers the whole
  // model (before, every follow and every row did), the second CYCLE going on from the parts.
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
hist ratio axial unbal every 10 file h.csv range not z 10 330
cycle 400
cycle 200
)";
  TempDir serial;
  serial.write("deck.dat", deck + kOutputs);
  REQUIRE(run_deck(serial, 0) == 0);
  const std::string balls = slurp(serial.path() / "balls.csv"), contacts = slurp(serial.path() / "contacts.csv");
  REQUIRE(lines_of(contacts).size() > 200);
  REQUIRE(lines_of(slurp(serial.path() / "h.csv")).size() == 61);
  for (int ranks : {2, 3}) {
    TempDir dir;
    dir.write("deck.dat", "backend mpi\n" + deck + kOutputs + "print info\n" + kCounters);
    REQUIRE(run_deck(dir, ranks, kEqualShares) == 0);   // (the gathers counted: no new shares by speed)
    const std::string out = slurp(dir.path() / "out.txt");
    INFO(ranks << " ranks\n" << out);
    CHECK_THAT(out, Catch::Contains("last step shared by: the spatial decomposition"));
    CHECK(slurp(dir.path() / "balls.csv") == balls);
    CHECK(slurp(dir.path() / "contacts.csv") == contacts);
    CHECK(slurp(dir.path() / "h.csv") == slurp(serial.path() / "h.csv"));
    const Counters counters = counters_of(dir);
    CHECK(counter(counters, "whole_gathers") == 0);
    CHECK(counter(counters, "parts_kept") == 1);
  }
}


TEST_CASE("distributed: the balls put in space order on the ranks' parts inside a CYCLE, however it is cut: serial's bits",
          "[mpi][system]") {
  // SET sort 25: the run puts the balls in space order every 25 cycles. Where the ranks' parts are
  // live, the ranks sort them where they are (Pipeline::sort_on_parts, BrickStep::sort_in_space):
  // every rank's keys to every rank, the light arrays, owners, cuts and bonds renumbered, each part
  // renumbered with its pairs turned round as serial's table is, and no part given back to rank 0.
  // Before, each sort gathered the whole model to rank 0 and split it again (24 decompositions in
  // 600 cycles); now the one split of the CYCLE's start stays (the ranks' speeds may ask for
  // another: under 10 are allowed). Four scenes on 3 ranks against serial: balls falling onto a
  // wall in a box; a compressed periodic cell with rolling resistance and capillary bridges (balls
  // crossing the faces and changing rank), in one CYCLE and cut into three (the second starting at
  // a cycle of the sort, on the kept parts); a bonded block crushed (SET sort 10); and that cell
  // stepped above its critical step, which goes unstable 196 cycles after the copy of its CYCLE's
  // start, eight sorts later: every ball array is put back from the copies, in their order. And
  // a CYCLE whose last step sorts, its results read after.
  if (!can_run_mpi()) TRUBAL_SKIP(kNoMpi);
  const std::string outputs =
      "print balls file b.csv\nprint contacts file c.csv\nsave a.sav\nprint counters file counters.txt\n";
  const std::string box =
      "start box 0 0.01 0 0.01 0 0.01 destroy\nset sort 25\nprop kn 1e5 ks 1e5 mu 0.5 dens 2650\n"
      "wall id 7 plane 0 0 0.0001 0 0 1\ngen 600 0.0004 0.0006 seed 5\ngrav 0 0 -9.81\ncycle 600\n";
  const std::string cell =
      "start 0.01 0.01 0.01\nset sort 25\ngen 900 0.0004 0.0006 seed 7\n"
      "prop kn 1e5 ks 1e5 mu 0.5 dens 2650 rr_fric 0.1 bridge 2e-10 tension 0.072\nstrain 200 200 200\n";
  const std::string bonded =
      "start box -3 8 -3 8 -3 8 destroy\nset sort 10\nprop kn 1e8 ks 5e7 mu 0.5 dens 2000\nlattice fcc 1 5 5 7\n"
      "bond gap 1e-6 kn 2e8 ks 1e8 ten 2e5 coh 4e5 fa 30\ngroup top range z 3.5 10\nfix vel spin range group top\n"
      "fix vel spin range z -1 0.1\ninit zvel -0.3 range group top\ncycle 400\nprint bonds file bonds.csv\n";
  struct Scene {
    std::string name, deck;
    std::size_t sorts;   // the sorts on the parts at least: the CYCLEs' cycles of the sort after their first step
  };
  const std::vector<Scene> scenes = {
      {"a box", box, 23},
      {"a cell", cell + "cycle 600\n", 23},
      {"a cell, cut", cell + "cycle 300\ncycle 137\ncycle 163\n", 23},
      {"a bonded block", bonded, 39},
  };
  for (const Scene& scene : scenes) {
    INFO(scene.name);
    TempDir serial, ranks;
    run_both(scene.deck + outputs, serial, ranks, 0);
    INFO(slurp(ranks.path() / "out.txt").substr(0, 3000));
    for (const char* file : {"b.csv", "c.csv", "a.sav", "bonds.csv"}) {
      if (!std::filesystem::exists(serial.path() / file)) continue;
      INFO(file);
      CHECK(slurp(ranks.path() / file) == slurp(serial.path() / file));
    }
    const Counters counters = counters_of(ranks);
    CHECK(counter(counters, "part_sorts") >= scene.sorts);
    CHECK(counter(counters, "decompositions") < 10);
  }
  {
    // A CYCLE whose last step starts at a cycle of the sort (26 from 0), its results read after:
    // the copy they are made from is taken after that step's sort (CycleRun::run), so that it is
    // put back on the parts in place. (Taken before, it was of the order before the sort, which
    // changed the parts' edition: the parts gave their state to rank 0, which made the results
    // and split the model again.)
    TempDir serial, ranks;
    run_both(cell + "cycle 26\nprint contacts file c.csv\nprint counters file counters.txt\ncycle 50\nsave a.sav\n", serial,
             ranks, 0);
    for (const char* file : {"c.csv", "a.sav"}) {
      INFO(file);
      CHECK(slurp(ranks.path() / file) == slurp(serial.path() / file));
    }
    const Counters counters = counters_of(ranks);
    CHECK(counter(counters, "results_made") == 1);
    CHECK(counter(counters, "copies_put_back_on_parts") == 1);
  }
  // Unstable: serial's message, which tells the state put back (its energies, its fastest ball).
  TempDir serial, ranks;
  run_both(cell + "cycle 300\ntstep 2.3e-6\ncycle 1500\n", serial, ranks, 1);
  auto message = [](const TempDir& dir) {
    const std::string out = slurp(dir.path() / "out.txt");
    const auto at = out.find("error: unstable at cycle");
    return at == std::string::npos ? std::string() : out.substr(at, out.find('\n', at) - at);
  };
  const std::string expected = message(serial);
  REQUIRE(expected.find("unstable at cycle 496") != std::string::npos);
  REQUIRE(expected.find("back at cycle 300") != std::string::npos);
  CHECK(message(ranks) == expected);
}
