// doc/tutorial.md: its three decks run as written (in a folder of their own, as a user copies them)
// and give what the tutorial says they give.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <string>

#include "interp_support.hpp"
#include "io/history.hpp"
#include "paths.hpp"
#include "skip.hpp"

using namespace trubal;
using namespace trubal::test;

namespace {

// Runs doc/tutorial/<name>.dat in a fresh folder; returns its history table (<name>.csv).
std::unique_ptr<HistoryTable> run_tutorial(const TempDir& dir, const std::string& name) {
  const std::string deck = slurp(fs::path(TRUBAL_SOURCE_DIR) / "doc" / "tutorial" / (name + ".dat"));
  REQUIRE_FALSE(deck.empty());
  dir.write(name + ".dat", deck);
  const int rc = shell("cd " + quote(dir.str()) + " && timeout 600 " + quote(TRUBAL_EXE) + " " + name +
                       ".dat > out.txt 2>&1");
  INFO(slurp(dir.path() / "out.txt"));
  REQUIRE(rc == 0);
  return read_history_csv((dir.path() / (name + ".csv")).string());
}

std::size_t column(const HistoryTable& t, const std::string& name) {
  const auto it = std::find(t.columns.begin(), t.columns.end(), name);
  REQUIRE(it != t.columns.end());
  return static_cast<std::size_t>(it - t.columns.begin());
}

bool png(const fs::path& p) { return slurp(p).rfind("\x89PNG", 0) == 0; }

}  // namespace

TEST_CASE("tutorial: the drained triaxial test between walls shears to 10% axial strain at 100 kPa", "[doc][tutorial][system]") {
  if (!on_path("gnuplot")) TRUBAL_SKIP("gnuplot is not installed (Debian: gnuplot-nox): the tutorial's decks plot");
  TempDir dir;
  const auto t = run_tutorial(dir, "triaxial");
  const auto& last = t->rows.back();
  // CYCLE ... until axial 0.1 stops at the first check (every 100 cycles) past 0.1: by then the
  // strain has grown by at most 100 steps of about 1.5e-6 s at 0.74 /s. The history records every
  // 200 cycles, so its last row may be 100 cycles before that stop (cycle 106,800 of 106,900:
  // 0.099997), 1.2e-4 of strain.
  CHECK(last[column(*t, "ea")] >= 0.1 - 3e-4);
  CHECK(last[column(*t, "ea")] < 0.1 + 1e-3);
  // The cylinder's servo holds sigma3 at 100 kPa (within 3%: the servo's error while the sample
  // dilates or contracts).
  CHECK(std::abs(last[column(*t, "sig3")] - 1e5) < 3e3);
  // Spheres without rolling resistance, friction 30 degrees: a peak deviator of 0.4 to 1.6 times
  // sigma3 (peak friction angles of about 10 to 25 degrees, what such assemblies reach).
  double peak = 0;
  for (const auto& row : t->rows) peak = std::max(peak, row[column(*t, "q")]);
  CHECK(peak > 0.4e5);
  CHECK(peak < 1.6e5);
  CHECK(png(dir.path() / "triaxial_q.png"));
  CHECK(png(dir.path() / "triaxial_ev.png"));
}

TEST_CASE("tutorial: the oedometer loads to 400 kPa and unloads with K0 below 1", "[doc][tutorial][system]") {
  if (!on_path("gnuplot")) TRUBAL_SKIP("gnuplot is not installed (Debian: gnuplot-nox): the tutorial's decks plot");
  TempDir dir;
  const auto t = run_tutorial(dir, "oedometer");
  const std::size_t ea = column(*t, "ea"), ev = column(*t, "ev"), s1 = column(*t, "sig1"), s3 = column(*t, "sig3");
  // The ring does not move: the volumetric strain is the axial strain (to rounding).
  double most = 0, at_most = 0, k0 = 0;
  for (const auto& row : t->rows) {
    CHECK(std::abs(row[ev] - row[ea]) < 1e-12);
    if (row[s1] > most) most = row[s1], at_most = row[ev], k0 = row[s3] / row[s1];
  }
  // The lid's servo reaches 400 kPa (within 2%), the sample compresses, and unloading to 50 kPa
  // gives back part of the strain, not all (the plastic part stays).
  CHECK(std::abs(most - 4e5) < 8e3);
  const auto& last = t->rows.back();
  CHECK(std::abs(last[s1] - 5e4) < 2.5e3);
  CHECK(last[ev] < at_most);
  CHECK(last[ev] > 0);
  // K0 at the largest load: the ring carries less than the lid (a granular K0 of 0.3 to 0.95).
  CHECK(k0 > 0.3);
  CHECK(k0 < 0.95);
  CHECK(png(dir.path() / "oedometer_ev.png"));
  CHECK(png(dir.path() / "oedometer_k0.png"));
}

TEST_CASE("tutorial: the undrained test keeps the volume and climbs a stress path to q/p near 1.2", "[doc][tutorial][system]") {
  if (!on_path("gnuplot")) TRUBAL_SKIP("gnuplot is not installed (Debian: gnuplot-nox): the tutorial's decks plot");
  TempDir dir;
  const auto t = run_tutorial(dir, "undrained");
  const std::size_t p = column(*t, "p"), q = column(*t, "q"), evol = column(*t, "evol");
  // Rates summing to zero keep the cell's volume to rounding.
  for (const auto& row : t->rows) CHECK(std::abs(row[evol]) < 1e-12);
  // The dense sample dilates, so at constant volume p' rises, and the path runs along a line of
  // q/p' = M: for spheres with mu 0.5, 0.8 to 1.6 (a critical-state angle of about 20 to 40 degrees).
  const auto& first = t->rows.front();
  const auto& last = t->rows.back();
  CHECK(last[p] > 2 * first[p]);
  CHECK(last[q] / last[p] > 0.8);
  CHECK(last[q] / last[p] < 1.6);
  CHECK(png(dir.path() / "undrained_path.png"));
}

TEST_CASE("examples: every file an example deck writes is one git ignores, run in examples/ or at the root", "[doc][examples]") {
  // A user runs an example from the checkout (README's first command does, in examples/): what it
  // writes must leave `git status` clean, and no committed file may be overwritten by a run.
  if (!on_path("git")) TRUBAL_SKIP("git is not installed: the check asks git what it ignores");
  const fs::path source(TRUBAL_SOURCE_DIR);
  if (shell("git -C " + quote(source.string()) + " rev-parse --is-inside-work-tree > /dev/null 2>&1") != 0)
    TRUBAL_SKIP("the source folder is not a git checkout");
  std::size_t decks = 0, outputs = 0;
  for (const auto& entry : fs::directory_iterator(source / "examples")) {
    if (entry.path().extension() != ".dat") continue;
    ++decks;
    const std::string text = slurp(entry.path());
    // Its header says how long it takes.
    INFO(entry.path().filename().string());
    CHECK((text.find("Run: trubal examples/") != std::string::npos));
    CHECK((text.find("(about ") != std::string::npos || text.find("(under a second") != std::string::npos));
    // The files it writes: `file NAME` on a HIST, PLOT, PRINT or DUMP line, and SAVE's.
    for (const auto& line : lines_of(text)) {
      std::istringstream in(line);
      std::vector<std::string> words;
      for (std::string w; in >> w;) words.push_back(w);
      if (words.empty() || words[0][0] == '*' || words[0][0] == ';') continue;
      std::vector<std::string> names;
      if (words[0] == "save" && words.size() > 1) names.push_back(words[1]);
      for (std::size_t k = 0; k + 1 < words.size(); ++k)
        if (words[k] == "file" && words[0] != "call") names.push_back(words[k + 1]);
      for (const auto& name : names) {
        ++outputs;
        INFO("writes " << name);
        for (const std::string& where : {"examples/" + name, name})
          CHECK(shell("cd " + quote(source.string()) + " && git check-ignore -q " + quote(where)) == 0);
      }
    }
  }
  CHECK(decks >= 10);
  CHECK(outputs >= 20);
}
