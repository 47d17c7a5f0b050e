// What a long run shows while it runs and after: progress lines (a redrawn bar only at an
// interactive terminal, plain lines elsewhere and in the log), the one-line summary after each
// CYCLE in batch, the table at the end of the program, and SET log's copy of it all.
#include "paths.hpp"
#include <chrono>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "io_support.hpp"

using namespace trubal;
using namespace trubal::test;

namespace {

// About a thousand balls settling on a fixed layer: a few thousand cycles take a good part of a
// second, long enough for several progress reports at SET progress 0.05.
const std::string kScene =
    "start box -1 21 -1 21 -1 30 destroy\n"   // balls that roll off the layer go (they are not the point here)
    "prop kn 1e6 ks 1e6 fric 30 dens 1000\n"
    "lattice fcc 2 10 10 8\n"
    "fix vel spin range z -1 0.5\n"
    "grav 0 0 -10\n"
    "damp local 0.7\n";

// Cycles until the run has lasted `seconds` (one CYCLE command each time, doubling), so the test
// does not depend on this machine's speed; returns the last command.
std::string long_cycle(Harness& h, double seconds, bool interactive) {
  std::int64_t n = 500;
  for (;;) {
    const std::string command = fmt::format("cycle {}", n);
    const auto start = std::chrono::steady_clock::now();
    if (interactive) REQUIRE(h.line(command));
    else REQUIRE(h.deck(command + "\n"));
    if (std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() > seconds) return command;
    n *= 2;
  }
}

bool has_control_characters(const std::string& text) {
  for (char c : text)
    if ((static_cast<unsigned char>(c) < 0x20 && c != '\n') || c == 0x7f) return true;
  return false;
}

std::size_t count(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t at = 0; (at = text.find(what, at)) != std::string::npos; at += what.size()) ++n;
  return n;
}

}  // namespace

TEST_CASE("io_progress: batch runs print plain progress lines and copy them to SET log", "[io][progress]") {
  TempDir dir;
  WorkingDir wd(dir.path());
  Harness h;
  h.output.terminal = true;   // even on a terminal: batch means plain lines
  REQUIRE(h.deck(kScene + "set progress 0.05\nset log run.log\n"));
  long_cycle(h, 0.6, false);
  REQUIRE(h.deck("set log off\n"));
  const std::string out = h.out.str(), log = slurp(dir.path() / "run.log");
  INFO(out);
  CHECK(count(out, " cycles/s, ") >= 2);
  CHECK_THAT(out, Catch::Matches("(.|\n)*  cycle [0-9]+/[0-9]+ \\([0-9]+%\\), [0-9]+ cycles/s, [0-9]+ s left\n(.|\n)*"));
  CHECK_FALSE(has_control_characters(out));
  // The log holds what was shown while it was on: the progress and the summary lines, plain.
  CHECK(!log.empty());
  CHECK(out.ends_with(log));
  CHECK(count(log, " cycles/s, ") >= 2);
  CHECK_FALSE(has_control_characters(log));
  // The summary line of a batch CYCLE says where the time went.
  CHECK_THAT(out, Catch::Contains("ball-cycles/s; detect "));
  CHECK_THAT(out, Catch::Contains("forces "));
  CHECK_THAT(out, Catch::Contains("motion "));
  CHECK_THAT(out, Catch::Contains("output "));
}

TEST_CASE("io_progress: SET progress 0 silences the plain lines", "[io][progress]") {
  Harness h;
  REQUIRE(h.deck(kScene + "set progress 0\n"));
  long_cycle(h, 0.3, false);
  CHECK(count(h.out.str(), " cycles/s, ") == 0);
  CHECK_FALSE(h.deck("set progress -1\n"));
  CHECK_THAT(h.first_error_line(), Catch::Contains("must not be negative"));
}

TEST_CASE("io_progress: at an interactive terminal a bar is redrawn and erased before the summary", "[io][progress]") {
  TempDir dir;
  WorkingDir wd(dir.path());
  Harness h;
  h.interp.interactive = true;
  h.output.terminal = true;
  REQUIRE(h.deck(kScene));
  const std::string command = long_cycle(h, 1.2, true);
  const std::string out = h.out.str();
  const auto last = out.rfind("\r\033[K");
  INFO(out);   // (once seen failing under ASan with -j2, passing alone: the output says why next time)
  REQUIRE(last != std::string::npos);
  CHECK(count(out, "cycles/s  ") >= 1);
  CHECK_THAT(out, Catch::Contains("] "));
  // The bar is erased, then plain lines follow on a clean line: the report of balls that left the
  // box where the first CYCLE is the last (a slow build, ASan, reaches 1.2 s within the first 500
  // cycles, while a third of the balls roll off the layer), then the summary line, last (no time
  // split at the prompt).
  const std::string after = out.substr(last + 4);
  CHECK_FALSE(has_control_characters(after));
  REQUIRE(after.ends_with('\n'));
  std::vector<std::string> lines;
  for (std::size_t at = 0; at < after.size(); at = after.find('\n', at) + 1)
    lines.push_back(after.substr(at, after.find('\n', at) - at));
  CHECK(lines.back().starts_with("cycle "));
  for (std::size_t k = 0; k + 1 < lines.size(); ++k)
    CHECK_THAT(lines[k], Catch::Matches("[0-9]+ balls? left the box and (was|were) destroyed .*"));
  CHECK(after.find("; detect") == std::string::npos);

  // With a log file on, the same run gives plain lines (nothing in the log to redraw).
  Harness g;
  g.interp.interactive = true;
  g.output.terminal = true;
  REQUIRE(g.deck(kScene + "set progress 0.05\nset log run.log\n"));
  REQUIRE(g.line(command));
  REQUIRE(g.line("set log off"));
  CHECK_FALSE(has_control_characters(g.out.str()));
  CHECK_FALSE(has_control_characters(slurp(dir.path() / "run.log")));
  CHECK(count(slurp(dir.path() / "run.log"), " cycles/s, ") >= 1);
}

TEST_CASE("io_progress: the program ends with a run summary of where the time went", "[io][progress][system]") {
  TempDir dir;
  dir.write("deck.dat", kScene + "cycle 200\nset log run.log\ncycle 100\n");
  const int status = shell("cd " + quote(dir.str()) + " && timeout 60 " + quote(TRUBAL_EXE) +
                           " deck.dat >out.txt 2>err.txt");
  const std::string out = slurp(dir.path() / "out.txt");
  INFO(out << slurp(dir.path() / "err.txt"));
  CHECK(status == 0);
  CHECK_THAT(out, Catch::Contains("run summary: 300 cycles in "));
  for (const char* phase : {"contact detection", "forces", "motion", "output", "other"})
    CHECK_THAT(out, Catch::Contains(std::string("\n  ") + phase + " "));
  CHECK_FALSE(has_control_characters(out));
  // The log, on at the end, has the summary too.
  CHECK_THAT(slurp(dir.path() / "run.log"), Catch::Contains("run summary: 300 cycles in "));
  // A deck that never cycles has no summary.
  dir.write("still.dat", "start box 0 1 0 1 0 1\n");
  shell("cd " + quote(dir.str()) + " && " + quote(TRUBAL_EXE) + " still.dat >still.txt 2>&1");
  CHECK(slurp(dir.path() / "still.txt").find("run summary") == std::string::npos);
}
