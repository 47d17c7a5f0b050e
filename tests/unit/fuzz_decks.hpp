// The deck fuzzer's parts: the seeds (every deck of examples/, doc/tutorial/, tests/fuzz/corpus/
// and tests/fuzz/regressions/, their work capped), the mutations, and the run of one mutant by the
// real program in a scratch folder under a time, memory and file-size limit
// (interp_fuzz_decks.cpp holds the tests; doc/developer.md, "The deck fuzzer", says how to use it).
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace trubal::test::fuzz {

namespace fs = std::filesystem;

// A file the mutant's scratch folder holds before the run: its text, or a FIFO, a symbolic link
// (`text` its target) or a folder planted at a name the deck reads or writes.
struct SideFile {
  enum class Kind { Text, Fifo, Link, Folder };
  Kind kind = Kind::Text;
  std::string name;
  std::string text;
};

struct Mutant {
  std::string seed_name;               // the seed deck's file name
  std::uint64_t fuzz_seed = 0, index = 0;
  std::vector<std::string> lines;      // the deck, deck.dat in the scratch folder
  std::vector<SideFile> files;
  std::vector<std::string> mutations;  // what was done to the seed, one line each
  // A mutation made a line that must stop the deck with an error (a command no table holds, a line
  // past the 1 MiB limit, a CALLed file of NULs...): exit 0 is then a finding.
  bool must_fail = false;
};

// Every seed deck, sorted by path.
std::vector<fs::path> seed_decks();

// A seed's lines with its work capped so that a mutant runs in about a second under the
// sanitizers: CYCLE counts (and CYCLE ... until without one) at most kMostCycles, SOLVE limited,
// GEN's count at most kMostGenerated, LATTICE's cells at most kMostLatticeCells per axis.
constexpr long kMostCycles = 200, kMostGenerated = 300, kMostLatticeCells = 8;
std::vector<std::string> capped(const std::vector<std::string>& lines);

// Mutant `index` of the run seeded `fuzz_seed`: its seed is seeds[index % seeds.size()], and every
// choice comes from a generator seeded by (fuzz_seed, index) alone, so one mutant can be made again
// without the others (TRUBAL_FUZZ_ONLY).
Mutant make_mutant(const std::vector<fs::path>& seeds, std::uint64_t fuzz_seed, std::uint64_t index);

// The limits each run is held to. A runaway allocation or output fails the run instead of
// swapping the machine or filling its disk.
struct Limits {
  int seconds = 60;
  int memory_mb = 1024;   // ASan's hard_rss_limit_mb and max_allocation_size_mb, else ulimit -v (a
                          // seed takes 80 to 120 MB under ASan)
  int file_mb = 256;      // ulimit -f: the largest file a run may write
};

struct Outcome {
  int status = 0;                // exit status; 124 timed out, 128 + n killed by signal n
  std::string output;            // what it printed (stdout and stderr), its last MiB
  bool victim_changed = false;   // a file behind a planted symbolic link was written through it
  double seconds = 0;
};

// Runs the deck in a fresh scratch folder (removed after, or moved to `keep` when that is not
// empty), its side files planted first.
Outcome run_mutant(const Mutant& m, const Limits& limits, const fs::path& keep = {});

// "" when the outcome is acceptable: exit 0 or 1 (1 with an error message or the program's own
// "trubal: " last word; 0 not where the mutant must fail), no sanitizer report, no timeout, no
// signal, no write through a planted link.
// Otherwise what went wrong, in a few words.
std::string finding(const Mutant& m, const Outcome& o);

// The mutant as the test report shows it: what was done, the deck (long lines cut, runs of one
// line folded, bytes a terminal would act on as \xNN), the planted files, and how to make it again.
std::string describe(const Mutant& m);

// A line as the test report shows it: unprintable bytes as \xNN, cut to `most` characters.
std::string visible(const std::string& line, std::size_t most = 200);

}  // namespace trubal::test::fuzz
