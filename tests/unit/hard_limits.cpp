// Limits a deck from someone else cannot pass (issue 50): the servo's max rate, a radius beyond the
// periodic cell or the START space, the length of a line read or expanded, a failed read, Ctrl-C in
// a batch deck, and an out-of-memory error reported rather than aborted on. Each case hung, grew the
// memory without bound, ended the deck silently or went on after Ctrl-C before.
#include "paths.hpp"
#include <catch2/catch.hpp>

#include <limits>
#include <streambuf>

#include <fmt/format.h>

#include "gen/placement_grid.hpp"
#include "interp/lexer.hpp"
#include "interp/signals.hpp"
#include "interp_support.hpp"
#include "model/periodic_cell.hpp"

using namespace trubal;
using namespace trubal::test;

namespace {

std::string deck_error(const std::string& deck) {
  Harness h;
  const bool ok = h.deck(deck);
  INFO("stderr:\n" << h.err.str().substr(0, 2000));
  CHECK_FALSE(ok);
  return h.first_error_line();
}

// A stream whose reads fail (an I/O error, as /proc/self/mem gives): the stream buffer throws.
class FailingBuffer : public std::streambuf {
 protected:
  int_type underflow() override { throw std::ios_base::failure("read error"); }
};

}  // namespace

TEST_CASE("limits: the tilt reduction takes any number of edges off at once", "[limits]") {
  // A tilt of 1e30 edges: one edge at a time, tilt - L rounds to tilt and the loop never ended.
  Model m;
  m.space.periodic = true;
  m.space.lo = {0, 0, 0};
  m.space.hi = {1, 1, 1};
  m.space.tilt = {1e30, -3.7e20, 2.25};
  CHECK(reduce_cell_tilt(m));
  for (double t : m.space.tilt) CHECK(std::abs(t) <= 0.5);
  // One edge, as the old loop took it, to the bit: 0.75 - 1 = -0.25.
  m.space.tilt = {0.75, 0, 0};
  CHECK(reduce_cell_tilt(m));
  CHECK(m.space.tilt[0] == -0.25);
  // A cell of no length reduces nothing (CYCLE refuses such a cell elsewhere), and returns.
  m.space.hi = {0, 1, 1};
  m.space.tilt = {1, 1, 0};
  CHECK_FALSE(reduce_cell_tilt(m));
}

TEST_CASE("limits: SERVO refuses a max rate beyond STRAIN's half an edge a step", "[limits]") {
  const std::string scene = "start 0.01 0.01 0.01\nprop kn 1e5 ks 1e5 fric 26.57 dens 2650\ngen 60 0.0008 0.0012 seed 7\n"
                            "damp local 0.7\nservo 1e4 1e4 1e4\n";
  // The step is not known yet: CYCLE refuses before its first step, the model as it was.
  const auto before = deck_error(scene + "servo 1e4 1e4 1e4 max 1e9\ncycle 3\n");
  CHECK(before.starts_with("deck.dat:7: error: SERVO max rate 1e+09 would change a cell edge by "));
  CHECK(before.find("lower SERVO max (at most ") != std::string::npos);
  // After a CYCLE the step is known: SERVO itself refuses (this deck, sheared, hung in the tilt reduction).
  const auto after = deck_error(scene + "cycle 20\nstrain zz 2 xy 1\nservo xx 1e4 yy 1e4 max 1e9\ncycle 3\n");
  CHECK(after.starts_with("deck.dat:8: error: max rate 1e+09 would change a cell edge by "));
  CHECK(after.find("(at most 0.5): give at most ") != std::string::npos);
  // A max rate within the bound runs.
  Harness h;
  REQUIRE(h.deck(scene + "cycle 20\nservo 1e4 1e4 1e4 max 100\ncycle 3\n"));
}

TEST_CASE("limits: GEN refuses balls the periodic cell cannot hold, and its grid has no overflow", "[limits]") {
  // 1000 in a 0.01 cell searched for ever; 1e308 overflowed the grid's cell count (UB).
  for (const char* radius : {"1000", "1e308", "0.003"}) {
    const auto e = deck_error(fmt::format("start 0.01 0.01 0.01\ngen 400 0.0004 {}\n", radius));
    CHECK(e.starts_with("deck.dat:2: error: GEN: the periodic edge x = 0.01 is less than twice the largest diameter"));
  }
  const auto psd = deck_error("start 0.01 0.01 0.01\ngen 1 psd uniform 0.003 0.004\n");
  CHECK(psd.find("less than twice the largest diameter") != std::string::npos);
  // The grid itself, asked about any finite reach, answers at once.
  Space s;
  s.periodic = true;
  s.lo = {0, 0, 0};
  s.hi = {0.01, 0.01, 0.01};
  PlacementGrid grid(s, 0.0006, 10);
  grid.insert(0.005, 0.005, 0.005, 0.0005);
  CHECK(grid.overlaps(0.0051, 0.005, 0.005, 1e308));
  CHECK(grid.overlaps(0.0051, 0.005, 0.005, 1000));
  CHECK_FALSE(grid.overlaps(0.001, 0.001, 0.001, 0.0001));
}

TEST_CASE("limits: BALL refuses a radius beyond the START space's diagonal", "[limits]") {
  // 1e300 was taken, its mass overflowed, and the first CYCLE blamed the step ("try FRAC").
  for (const char* radius : {"1e300", "3.47"}) {
    const auto e = deck_error(fmt::format("start box -1 1 -1 1 -1 1\nball 0 0 0 {}\n", radius));
    CHECK(e.starts_with("deck.dat:2: error: the radius must be at most the START space's diagonal, 3.4641 (a larger "
                        "ball would cover all of it)"));
  }
  CHECK(deck_error("start box -1 1 -1 1 -1 1\nball 0 0 0 0\n")
            .starts_with("deck.dat:2: error: the radius must be positive"));
  // Up to the diagonal a ball is made and runs (sqrt(12) = 3.4641...).
  Harness h;
  REQUIRE(h.deck("start box -1 1 -1 1 -1 1\nprop kn 1e5 dens 1000\nball 0 0 0 3.46\ncycle 10\n"));
}

TEST_CASE("limits: a line longer than 1 MiB or with a NUL byte is an error at its line", "[limits]") {
  const std::string long_line(kMaxLineLength + 1, 'a');
  CHECK(deck_error("echo one\n" + long_line + "\necho never\n")
            .starts_with("deck.dat:2: error: the line is longer than 1048576 characters (1 MiB): not a deck?"));
  // A line of exactly the limit is read (and is then an unknown command, not a read error).
  CHECK(deck_error(std::string(kMaxLineLength, 'a') + "\n").find("longer than") == std::string::npos);
  // Joined by continuations: each piece short, the whole too long.
  std::string joined;
  for (int k = 0; k < 3; ++k) joined += std::string(kMaxLineLength / 2, 'b') + " &\n";
  CHECK(deck_error("echo one\n" + joined + "c\n")
            .starts_with("deck.dat:2: error: the line joined by its continuations is longer than 1048576"));
  CHECK(deck_error(std::string("echo one\necho t\0wo\n", 19))
            .starts_with("deck.dat:2: error: a NUL byte in the line: not a deck? (a binary file?)"));
}

TEST_CASE("limits: a read that fails is an error, never the end of the deck", "[limits]") {
  FailingBuffer failing;
  std::istream in(&failing);
  Harness h;
  CHECK_FALSE(h.interp.run_deck(in, "broken.dat"));
  CHECK(h.first_error_line().starts_with("broken.dat:1: error: cannot read the input: a read error"));
}

TEST_CASE("limits: a $variable expansion longer than 1 MiB is an error before it is built", "[limits]") {
  // Each SET doubles the value: 2 characters, 2^19 at a18; a19's line would pass the limit.
  std::string deck = "set a0 xx\n";
  for (int k = 1; k <= 24; ++k) deck += fmt::format("set a{} $a{}$a{}\n", k, k - 1, k - 1);
  const auto e = deck_error(deck);
  CHECK(e.starts_with("deck.dat:20: error: the line with $a18 replaced would be longer than 1048576 characters"));
  // Below the limit is fine.
  Harness h;
  REQUIRE(h.deck(deck.substr(0, deck.find("set a19"))));
  CHECK(h.interp.variable("a18")->size() == (std::size_t{1} << 19));
}

TEST_CASE("limits: Ctrl-C during GEN or RESTART stops a batch deck, as during CYCLE", "[limits]") {
  TempDir dir;
  WorkingDir here(dir.path());
  {
    Harness h;
    REQUIRE(h.deck("start box 0 20 0 20 0 20\nprop kn 1e5 dens 1000\nball 1 1 1 0.5\nsave m.sav\n"));
  }
  // GEN: it keeps what it placed, and the deck stops there (it went on to cycle and save).
  Harness gen;
  REQUIRE(gen.deck("start box 0 20 0 20 0 20\n"));
  interrupt_requested() = true;
  CHECK_FALSE(gen.deck("gen 100 0.5 0.5\necho never\n"));
  CHECK(gen.first_error_line() == "deck.dat:1: error: GEN interrupted by Ctrl-C: 0 of 100 balls placed (kept)");
  CHECK(gen.out.str().find("never") == std::string::npos);
  CHECK_FALSE(interrupt_requested().load());
  // At the shell it is a warning, and the shell goes on.
  gen.interp.interactive = true;
  interrupt_requested() = true;
  CHECK(gen.line("gen 100 0.5 0.5"));
  CHECK(gen.err.str().find("warning: GEN interrupted by Ctrl-C: 0 of 100 balls placed (kept)") != std::string::npos);
  // RESTART does not look for Ctrl-C: the deck stops after it (the next CYCLE cleared the request).
  Harness restart;
  interrupt_requested() = true;
  CHECK_FALSE(restart.deck("restart m.sav\necho never\n"));
  CHECK(restart.first_error_line() == "deck.dat:1: error: interrupted by Ctrl-C (during RESTART)");
  CHECK(restart.session.model().balls.size() == 1);   // what it did is kept
  CHECK_FALSE(interrupt_requested().load());
}

TEST_CASE("limits: zeros, unreadable files and out of memory are plain errors with exit 1", "[limits][system]") {
  TempDir dir;
  const std::string exe = quote(TRUBAL_EXE);
  auto run = [&](const std::string& command) {
    const int status = shell("cd " + quote(dir.str()) + " && " + command + " >out.txt 2>&1");
    return std::make_pair(status, slurp(dir.path() / "out.txt"));
  };
  // /dev/zero: one endless line (it was read to the end of the memory: std::bad_alloc, exit 134),
  // read as the deck runs: stopped at 1 MiB.
  auto [zero_status, zero] = run("timeout 60 " + exe + " /dev/zero </dev/null");
  INFO(zero);
  CHECK(zero_status == 1);
  CHECK(zero.find("/dev/zero:1: error: the line is longer than") != std::string::npos);
  // From standard input (under a memory limit it took the failed read for the end: exit 0), read
  // a line at a time: the endless line is stopped at 1 MiB.
  auto [stdin_status, from_stdin] = run("timeout 60 " + exe + " - < /dev/zero");
  INFO(from_stdin);
  CHECK(stdin_status == 1);
  CHECK(from_stdin.find("<stdin>:1: error: the line is longer than") != std::string::npos);
  // A file whose reads fail (std::__ios_failure, exit 134); the deck is read as it runs, so the
  // failed read is its first line's.
  auto [mem_status, mem] = run("timeout 60 " + exe + " /proc/self/mem </dev/null");
  INFO(mem);
  CHECK(mem_status == 1);
  CHECK(mem.find("/proc/self/mem:1: error: cannot read the input: a read error") != std::string::npos);
  // CALL of a file of zeros stops the deck at that file's line (it skipped the file and went on).
  dir.write("zeros.dat", std::string(3 << 20, '\0'));
  dir.write("calls.dat", "echo first\ncall zeros.dat\necho never\n");
  auto [call_status, call] = run("timeout 60 " + exe + " calls.dat </dev/null");
  INFO(call);
  CHECK(call_status == 1);
  CHECK(call.find("zeros.dat:1: error: a NUL byte in the line") != std::string::npos);
  CHECK(call.find("never\n") == std::string::npos);
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
  SUCCEED("a sanitizer reserves more address space than a memory limit allows: the rest needs a plain build");
#else
  // Out of memory in a command: FILE:LINE and a fixed message, exit 1 (reporting one bad_alloc threw
  // another, and the program aborted).
  dir.write("big.dat", "start box 0 1000 0 1000 0 1000\ngen 20000000 0.5 0.5\necho never\n");
  auto [big_status, big] = run("ulimit -v 400000; timeout 120 " + exe + " big.dat </dev/null");
  INFO(big);
  CHECK(big_status == 1);
  CHECK(big.find("big.dat:2: error: out of memory") != std::string::npos);
#endif
}
