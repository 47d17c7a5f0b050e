// The contract of the cycle on packings read between CYCLEs: random GEN packings consolidated by the
// servo, then strained, each stage cut in several places and the results read after every CYCLE; on
// every backend and on 2 ranks, where two runs read at the same cycle they read the same bits (the
// scenes' cut matrix: cycle_cuts.cpp).
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

// Random GEN packings consolidated by the servo from their first step (the first CYCLE's servo reads
// the contact table), then the servo on two axes and a strain rate on the third, the settings
// switched between the two stages. Each stage is cut 1 + n, n + 1 and 1 + n + 1, and the results are
// read after every CYCLE (PRINT balls, PRINT contacts, PRINT info's count of contacts): where two runs
// read at the same cycle, they read the same bits. The parts of 1999 and 499 steps end a step before
// a cycle of the rescue copies (every 500 steps), where a CYCLE whose last step's results are made
// when read must keep its copy of the step before.
struct Packing {
  const char* name;
  double edge;   // of the cubic periodic cell
  int balls, seed;
};
const Packing kPackings[] = {{"180 balls, seed 3", 0.006, 180, 3},
                             {"180 balls, seed 11", 0.006, 180, 11},
                             {"230 balls, seed 29", 0.0065, 230, 29}};
constexpr int kConsolidate = 2000, kStrain = 500;   // the stages' steps
const char* const kSwitchToStrain = "servo xx 1e5 yy 1e5\nstrain zz 2\n";

std::string packing_setup(const Packing& p) {
  return fmt::format("start {0} {0} {0}\nprop kn 1e5 ks 1e5 fric 26.57 dens 2650\ngen {1} 0.0004 0.0006 seed {2}\n"
                     "damp local 0.7\nservo 1e5 1e5 1e5\n",
                     p.edge, p.balls, p.seed);
}

// A cut: the CYCLEs of the consolidation, then those of the strain stage.
struct StageCut {
  std::string name;
  std::vector<int> consolidate, strain;
};
std::vector<StageCut> stage_cuts() {
  const int c = kConsolidate, e = kStrain;
  return {{"unbroken", {c}, {e}},
          {"1 + n", {1, c - 1}, {1, e - 1}},
          {"n + 1", {c - 1, 1}, {e - 1, 1}},
          {"1 + n + 1", {1, c - 2, 1}, {1, e - 2, 1}}};
}

// What a run read after each CYCLE, by the cycle it ended at.
struct Read {
  std::string balls, contacts;
  long info_contacts = -1;   // PRINT info's `contacts:`
};
using Reads = std::map<int, Read>;

// The deck of a cut, reading after every CYCLE into files named by the cycle; and the cycles read.
std::string stage_deck(const std::string& setup, const StageCut& cut, std::vector<int>& read_at) {
  std::string deck = setup;
  int done = 0;
  auto cycles = [&](const std::vector<int>& parts) {
    for (const int k : parts) {
      done += k;
      deck += fmt::format("cycle {0}\nprint balls file b{1}.csv\nprint contacts file c{1}.csv\nprint info\n", k, done);
      read_at.push_back(done);
    }
  };
  cycles(cut.consolidate);
  deck += kSwitchToStrain;
  cycles(cut.strain);
  return deck;
}

// The reads' files, and PRINT info's counts of contacts in `out` (one a read, in order).
Reads collect_reads(const std::filesystem::path& dir, const std::string& out, const std::vector<int>& read_at) {
  std::vector<long> counts;
  for (const std::string& line : lines_of(out))
    if (line.rfind("contacts: ", 0) == 0) counts.push_back(std::stol(line.substr(10)));
  REQUIRE(counts.size() == read_at.size());
  Reads reads;
  for (std::size_t k = 0; k < read_at.size(); ++k) {
    const int at = read_at[k];
    reads[at] = {slurp(dir / fmt::format("b{}.csv", at)), slurp(dir / fmt::format("c{}.csv", at)), counts[k]};
  }
  return reads;
}

Reads run_stages(const std::string& backend, const Packing& p, const StageCut& cut) {
  TempDir dir;
  WorkingDir cd(dir.path());
  Harness h;
  std::vector<int> read_at;
  const std::string deck = "backend " + backend + "\n" + stage_deck(packing_setup(p), cut, read_at);
  const bool ok = h.deck(deck);
  INFO(deck);
  INFO(h.err.str());
  REQUIRE(ok);
  return collect_reads(dir.path(), h.out.str(), read_at);
}

Reads run_stages_mpi(int ranks, const Packing& p, const StageCut& cut) {
  TempDir dir;
  std::vector<int> read_at;
  const std::string deck = "backend mpi\n" + stage_deck(packing_setup(p), cut, read_at);
  dir.write("deck.dat", deck);
  const int status = shell("cd " + quote(dir.str()) + " && " + launcher(ranks, "", kLongRunLimit) + quote(TRUBAL_EXE) +
                           " deck.dat >out.txt 2>&1");
  const std::string out = slurp(dir.path() / "out.txt");
  INFO(deck);
  INFO(out);
  REQUIRE(status == 0);
  return collect_reads(dir.path(), out, read_at);
}

// Each read against itself (PRINT info counts the contacts PRINT contacts lists, and the stages
// have them) and against the first read at its cycle in `seen` (which it joins where it is the first).
void check_reads(const Reads& reads, Reads& seen) {
  for (const auto& [at, read] : reads) {
    INFO("read after cycle " << at);
    const auto rows = lines_of(read.contacts);
    CHECK(read.info_contacts == static_cast<long>(rows.size()) - 1);   // (the header)
    if (at >= kConsolidate - 1) CHECK(read.info_contacts > 200);
    const auto [it, first] = seen.emplace(at, read);
    if (first) continue;
    CHECK(read.info_contacts == it->second.info_contacts);
    CHECK(read.contacts == it->second.contacts);
    CHECK(read.balls == it->second.balls);
  }
}

}  // namespace

TEST_CASE("cycle cuts: random GEN packings under the servo, cut 1 + n and n + 1, switched to strain between the stages",
          "[cuts][backends][system][threads]") {
  for (const Packing& packing : kPackings) {
    Reads seen;
    // Every packing serially; the first on threads and all-pairs too.
    std::vector<std::string> backends{"serial"};
    if (&packing == &kPackings[0]) backends.insert(backends.end(), {"threaded threads 2", "allpairs threads 2"});
    for (const std::string& backend : backends)
      for (const StageCut& cut : stage_cuts()) {
        INFO(packing.name << " on " << backend << ", cut: " << cut.name);
        check_reads(run_stages(backend, packing, cut), seen);
      }
  }
}

TEST_CASE("cycle cuts: a random GEN packing under the servo on BACKEND mpi, 2 ranks, cut 1 + n and n + 1",
          "[cuts][mpi][system][threads]") {
  if (!can_run_mpi()) TRUBAL_SKIP(kNoMpi);
  const Packing& packing = kPackings[0];
  const std::vector<StageCut> all = stage_cuts();
  Reads seen;
  check_reads(run_stages("serial", packing, all.front()), seen);   // (unbroken)
  for (const StageCut& cut : all) {
    if (cut.name == "1 + n + 1") continue;
    INFO(packing.name << " on 2 ranks, cut: " << cut.name);
    check_reads(run_stages_mpi(2, packing, cut), seen);
  }
}
