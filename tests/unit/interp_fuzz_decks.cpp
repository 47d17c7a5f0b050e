// The deck fuzzer: every deck of examples/, doc/tutorial/, tests/fuzz/corpus/ and
// tests/fuzz/regressions/, its work capped, then mutated (fuzz_decks_mutate.cpp: words and lines
// changed, extreme numbers for SERVO, GEN, STRAIN, START, PROP and the like, FIFOs and symbolic
// links planted where the deck reads or writes, variable bombs, lines near and over 1 MiB, a line
// repeated thousands of times, CALLs of big, binary or recursive files) and run by the real program
// in a scratch folder under a time, memory and file-size limit (fuzz_decks_run.cpp). A signal, a
// sanitizer report, a run past a limit, exit 0 where the deck must fail, status 1 without an error
// or a write through a planted link fails. The decks of tests/fuzz/regressions/ (one per finding)
// must fail cleanly with the message their first line names.
//
// Environment (doc/developer.md, "The deck fuzzer"): TRUBAL_FUZZ_DECKS how many mutants (default
// 40; CI's sanitizer build runs more), TRUBAL_FUZZ_SEED the seed (default 1), TRUBAL_FUZZ_FIRST the
// first mutant's index (default 0), TRUBAL_FUZZ_ONLY one mutant alone, TRUBAL_FUZZ_JOBS how many
// run at once (default 2), TRUBAL_FUZZ_KEEP where a failing mutant's folder is kept (default
// trubal-fuzz-failures in the temporary directory).
#include <catch2/catch.hpp>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <fstream>
#include <future>
#include <sstream>

#include <fmt/format.h>

#include "fuzz_decks.hpp"
#include "interp_support.hpp"
#include "paths.hpp"

using namespace trubal::test::fuzz;

namespace {

std::uint64_t env_number(const char* name, std::uint64_t otherwise) {
  const char* v = std::getenv(name);
  return v && *v ? std::strtoull(v, nullptr, 10) : otherwise;
}

// What a report shows of a run's output: from a sanitizer's first line (its memory map and stack
// can run to thousands of lines), else the end.
std::string output_end(const std::string& out) {
  for (const char* mark : {"runtime error:", "==ERROR:", "rss limit exhausted", "Sanitizer"}) {
    const std::size_t at = out.find(mark);
    if (at != std::string::npos) {
      const std::size_t from = out.rfind('\n', at) == std::string::npos ? 0 : out.rfind('\n', at) + 1;
      return out.substr(from, 3000);
    }
  }
  return out.size() > 3000 ? out.substr(out.size() - 3000) : out;
}

}  // namespace

TEST_CASE("fuzz: mutated decks fail cleanly or run, never crash, hang or run away", "[hard][fuzz][system]") {
  const auto seeds = seed_decks();
  REQUIRE(seeds.size() >= 30);
  const std::uint64_t fuzz_seed = env_number("TRUBAL_FUZZ_SEED", 1);
  std::uint64_t first = env_number("TRUBAL_FUZZ_FIRST", 0), count = env_number("TRUBAL_FUZZ_DECKS", 40);
  if (std::getenv("TRUBAL_FUZZ_ONLY")) first = env_number("TRUBAL_FUZZ_ONLY", 0), count = 1;
  const std::size_t jobs = std::max<std::uint64_t>(1, env_number("TRUBAL_FUZZ_JOBS", 2));
  const char* keep_env = std::getenv("TRUBAL_FUZZ_KEEP");
  const fs::path keep = keep_env && *keep_env ? fs::path(keep_env) : fs::temp_directory_path() / "trubal-fuzz-failures";
  const Limits limits;
  std::ofstream log;   // TRUBAL_FUZZ_LOG: one line per mutant (index, seed deck, status, seconds, last line said)
  if (const char* log_env = std::getenv("TRUBAL_FUZZ_LOG"); log_env && *log_env) log.open(log_env);

  const auto start = std::chrono::steady_clock::now();
  int failed_cleanly = 0, ran = 0, findings = 0;
  double slowest = 0;
  std::string slowest_name;
  for (std::uint64_t batch = first; batch < first + count; batch += jobs) {
    std::vector<std::future<std::pair<Mutant, Outcome>>> running;
    for (std::uint64_t k = batch; k < std::min(batch + jobs, first + count); ++k)
      running.push_back(std::async(std::launch::async, [&seeds, &limits, &keep, fuzz_seed, k] {
        Mutant m = make_mutant(seeds, fuzz_seed, k);
        Outcome o = run_mutant(m, limits, keep / fmt::format("seed{}-mutant{}", fuzz_seed, k));
        return std::make_pair(std::move(m), std::move(o));
      }));
    for (auto& r : running) {
      const auto [m, o] = r.get();
      if (o.seconds > slowest) slowest = o.seconds, slowest_name = fmt::format("mutant {} ({})", m.index, m.seed_name);
      const std::string what = finding(m, o);
      if (log.is_open()) {
        const auto said = trubal::test::lines_of(o.output.substr(o.output.size() > 4000 ? o.output.size() - 4000 : 0));
        log << m.index << '\t' << m.seed_name << '\t' << o.status << '\t' << fmt::format("{:.2f}", o.seconds) << '\t'
            << (said.empty() ? "" : visible(said.back(), 160)) << '\t' << (what.empty() ? "-" : what) << '\n';
      }
      if (!what.empty()) {
        ++findings;
        FAIL_CHECK(what << ", status " << o.status << ", after " << fmt::format("{:.1f}", o.seconds) << " s\n"
                        << describe(m) << "--- the scratch folder: "
                        << (keep / fmt::format("seed{}-mutant{}", fuzz_seed, m.index)).string()
                        << "\n--- output (end):\n" << visible(output_end(o.output), 3000));
      } else if (o.status == 1) {
        ++failed_cleanly;
      } else {
        ++ran;
      }
    }
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  WARN(fmt::format("{} mutants (seed {}, from {}, {} at once) in {:.0f} s: {} stopped at an error, {} ran to the "
                   "end, {} findings; the slowest {:.1f} s, {}",
                   count, fuzz_seed, first, jobs, seconds, failed_cleanly, ran, findings, slowest, slowest_name));
  // Not all refused at once: mutants that run to the end exercise the physics, not just the parser.
  // (Most mutants stop at an error: a third of the seeds are regression decks, made to, and most
  // mutations make one.)
  if (count >= 100) CHECK(ran > static_cast<int>(count / 30));
}

TEST_CASE("fuzz: the memory limit stops a deck that allocates far past it", "[hard][fuzz][system]") {
  // 343,000 balls and their contacts take about 430 MB without ASan (a small deck about 90 MB under
  // ASan), more than twice the limit; under a 192 MB limit the run must end as a runaway allocation
  // would: by ASan's report, or (without ASan) by the program's own clean error.
  Mutant m;
  m.lines = {"start 56 56 56", "prop kn 1e5 ks 1e5 dens 1000", "lattice fcc 1 70 70 70", "cycle 2"};
  Limits small;
  small.memory_mb = 192;
  const Outcome o = run_mutant(m, small);
  INFO(output_end(o.output));
#if defined(__SANITIZE_ADDRESS__)
  CHECK(finding(m, o) == "past the memory limit");
#else
  CHECK(o.status == 1);
  CHECK_THAT(o.output, Catch::Contains("out of memory"));
#endif
}

TEST_CASE("fuzz: every regression deck fails with the error its first line names", "[hard][fuzz][system]") {
  const fs::path dir = fs::path(TRUBAL_TEST_DIR) / "fuzz" / "regressions";
  std::vector<fs::path> decks;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().extension() == ".dat") decks.push_back(e.path());
  std::sort(decks.begin(), decks.end());
  REQUIRE(decks.size() >= 10);
  for (const auto& deck : decks) {
    Mutant m;
    m.seed_name = deck.filename().string();
    m.lines = trubal::test::lines_of(trubal::test::slurp(deck));
    REQUIRE_FALSE(m.lines.empty());
    const std::string prefix = "* expect: ";
    REQUIRE(m.lines[0].rfind(prefix, 0) == 0);
    const std::string expected = m.lines[0].substr(prefix.size());
    m.must_fail = true;
    // `* plant: fifo NAME`, `* plant: link NAME TARGET`, `* plant: folder NAME`: what the scratch
    // folder holds before the run (a comment to the program, and to the deck as a seed).
    for (const auto& l : m.lines) {
      std::istringstream words(l);
      std::string star, plant, kind, name, target;
      if (!(words >> star >> plant >> kind >> name) || star != "*" || plant != "plant:") continue;
      words >> target;
      const SideFile::Kind k = kind == "fifo" ? SideFile::Kind::Fifo : kind == "link" ? SideFile::Kind::Link
                                                                                      : SideFile::Kind::Folder;
      REQUIRE((kind == "fifo" || kind == "folder" || (kind == "link" && !target.empty())));
      m.files.push_back({k, name, target});
    }
    const Outcome o = run_mutant(m, Limits{});
    INFO(m.seed_name << ":\n" << output_end(o.output));
    CHECK(finding(m, o) == "");
    CHECK(o.status == 1);
    CHECK_THAT(o.output, Catch::Contains(expected));
  }
}
