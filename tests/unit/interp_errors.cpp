// Bad input through the real interpreter: each mistake gets its own clear message that starts with
// NAME:LINE: error:, a batch run stops there, and nothing crashes.
#include "paths.hpp"
#include <catch2/catch.hpp>

#include <fmt/format.h>

#include <random>

#include "interp/lexer.hpp"
#include "interp/signals.hpp"
#include "interp_support.hpp"

using namespace trubal;
using trubal::test::Harness;
using trubal::test::TempDir;

namespace {

// Runs a deck that must fail; returns the error stream's first line.
std::string deck_error(const std::string& deck, const std::string& name = "deck.dat") {
  Harness h;
  bool ok = h.deck(deck, name);
  INFO("deck:\n" << deck.substr(0, 400) << "\nstderr:\n" << h.err.str().substr(0, 2000));
  CHECK_FALSE(ok);
  return h.first_error_line();
}

}  // namespace

TEST_CASE("interp errors: unknown command names the file and line and stops the deck", "[interp][errors]") {
  Harness h;
  CHECK_FALSE(h.deck("set echo off\necho before\nfrobnicate 1 2\necho after\n"));
  CHECK(h.first_error_line() == "deck.dat:3: error: unknown command 'frobnicate' (HELP lists the commands)");
  // The first error ends a batch run: the line after it never runs.
  CHECK(h.out.str() == "before\n");
  CHECK(h.err.str().find("after") == std::string::npos);
}

TEST_CASE("interp errors: an ambiguous keyword lists the candidates and a short one says so", "[interp][errors]") {
  auto e = deck_error("\nprint str\n");
  CHECK(e.starts_with("deck.dat:2: error: 'str' is ambiguous: it could be STRESS, STRAIN"));
  auto s = deck_error("cy 10\n");
  CHECK(s.starts_with("deck.dat:1: error: 'cy' is too short"));
  CHECK_THAT(s, Catch::Contains("CYCLE"));
}

TEST_CASE("interp errors: missing and extra arguments name what is wrong and show the usage", "[interp][errors]") {
  auto missing = deck_error("start 1 1\n");
  CHECK(missing.starts_with("deck.dat:1: error: missing edge z (a number)"));
  CHECK_THAT(missing, Catch::Contains("usage: START"));
  auto extra = deck_error("frac 0.5\nfrac 0.5 7\n");
  CHECK(extra.starts_with("deck.dat:2: error: unexpected '7' at the end of the command"));
  CHECK_THAT(extra, Catch::Contains("usage: FRAC f"));
  auto word = deck_error("grav 0 zero -9.81\n");
  CHECK(word.starts_with("deck.dat:1: error: expected a number for gravity y, got 'zero'"));
}

TEST_CASE("interp errors: a real where a count is needed", "[interp][errors]") {
  auto e = deck_error("cycle 1.5\n");
  CHECK(e.starts_with("deck.dat:1: error: n (number of cycles) must be a whole number, got the real '1.5'"));
  // Digits only but beyond a 64-bit count: not "a real".
  auto huge = deck_error("cycle 99999999999999999999\n");
  CHECK(huge.starts_with("deck.dat:1: error: n (number of cycles) is out of range: 99999999999999999999"));
  auto negative = deck_error("cycle -3\n");
  CHECK(negative.starts_with("deck.dat:1: error: n (number of cycles) must be at least 0, got -3"));
}

TEST_CASE("interp errors: a real with a whole value is a count (cycle 1e3, gen 2e1)", "[interp][errors]") {
  Harness h;
  REQUIRE(h.deck("start box -1 1 -1 1 -1 1\nprop kn 1e5 dens 1000\ngen 2e1 0.05 0.08 seed 1.0e0\ncycle 1e3\n"));
  CHECK(h.session.model().balls.size() == 20);
  CHECK(h.session.model().cycle == 1000);
  // A whole value beyond a 64-bit count, or a fraction in exponent form, is still refused.
  CHECK(deck_error("cycle 1e30\n").starts_with("deck.dat:1: error: n (number of cycles) is out of range: 1e30"));
  CHECK(deck_error("cycle 2.5e0\n").starts_with("deck.dat:1: error: n (number of cycles) must be a whole number, got the real '2.5e0'"));
}

TEST_CASE("interp errors: a number beyond the doubles is an input error, not infinity", "[interp][errors]") {
  // strtod gives infinity for these; the run would then fail later with a NaN.
  auto step = deck_error("start box 0 1 0 1 0 1\ntstep 1e999\n");
  CHECK(step.starts_with("deck.dat:2: error: "));
  CHECK(step.find("is out of range: '1e999' is beyond the largest number, 1.8e308") != std::string::npos);
  auto radius = deck_error("start box 0 1 0 1 0 1\nball 0 0 0 1e400\n");
  CHECK(radius.starts_with("deck.dat:2: error: "));
  CHECK(radius.find("'1e400'") != std::string::npos);
  auto negative = deck_error("start box 0 1 0 1 0 1\ngrav 0 0 -1d309\n");
  CHECK(negative.find("is out of range: '-1d309'") != std::string::npos);
  // The largest double itself, and numbers that underflow to 0 or a denormal, are numbers.
  Harness h;
  CHECK(h.deck("start box 0 1 0 1 0 1\nset volume 1.7976931348623157e308\ngrav 0 0 1e-400\n"));
}

TEST_CASE("interp errors: a continuation that runs into the end of the file names the line it started on",
          "[interp][errors]") {
  auto e = deck_error("set echo off\n\nstart 1 1 &\n  ; only a comment follows\n\n");
  CHECK(e.starts_with("deck.dat:3: error: the continuation"));
  CHECK_THAT(e, Catch::Contains("end of the input"));
  auto quote = deck_error("title \"never closed\n");
  CHECK(quote.starts_with("deck.dat:1: error: unterminated quoted string"));
}

TEST_CASE("interp errors: CALL of a missing file", "[interp][errors]") {
  TempDir dir;
  std::string missing = (dir.path() / "no-such-deck.dat").string();
  auto e = deck_error("set echo off\ncall " + missing + "\n");
  CHECK(e.starts_with("deck.dat:2: error: cannot open the file '" + missing + "' to CALL"));
}

TEST_CASE("interp errors: an error inside a CALLed file names that file and line and where it was called",
          "[interp][errors]") {
  TempDir dir;
  // inner.dat is found beside outer.dat although the working directory is elsewhere.
  dir.write("inner.dat", "echo inside\n\nbogus command\necho not reached\n");
  std::string outer = dir.write("outer.dat", "set echo off\ncall inner.dat\necho not reached either\n");
  Harness h;
  CHECK_FALSE(h.deck("set echo off\n\ncall " + outer + "\necho after\n"));
  auto err = trubal::test::lines_of(h.err.str());
  REQUIRE(err.size() == 3);
  CHECK(err[0] == "inner.dat:3: error: unknown command 'bogus' (HELP lists the commands)");
  CHECK(err[1] == outer + ":2: note: called from here");
  CHECK(err[2] == "deck.dat:3: note: called from here");
  CHECK(h.out.str() == "inside\n");
}

TEST_CASE("interp errors: include cycles, direct and through another file", "[interp][errors]") {
  TempDir dir;
  std::string self = dir.write("self.dat", "echo once\ncall self.dat\n");
  {
    Harness h;
    CHECK_FALSE(h.deck("set echo off\ncall " + self + "\n"));
    auto err = trubal::test::lines_of(h.err.str());
    REQUIRE(err.size() == 2);
    CHECK(err[0].starts_with(self + ":2: error: 'self.dat' calls itself (include cycle through " + self));
    CHECK(err[1] == "deck.dat:2: note: called from here");
    CHECK(h.out.str() == "once\n");  // stopped at the cycle, not after a thousand nested calls
  }
  std::string a = dir.write("a.dat", "echo in a\ncall b.dat\n");
  dir.write("b.dat", "echo in b\n\ncall a.dat\n");
  {
    Harness h;
    CHECK_FALSE(h.deck("set echo off\ncall " + a + "\n"));
    auto err = trubal::test::lines_of(h.err.str());
    REQUIRE(err.size() == 3);
    CHECK(err[0].starts_with("b.dat:3: error: 'a.dat' calls itself (include cycle through " + a));
    CHECK(err[1] == a + ":2: note: called from here");
    CHECK(err[2] == "deck.dat:2: note: called from here");
    CHECK(h.out.str() == "in a\nin b\n");
  }
  // Calling the same file twice in a row is not a cycle.
  std::string leaf = dir.write("leaf.dat", "echo leaf\n");
  Harness h;
  CHECK(h.deck("set echo off\ncall " + leaf + "\ninclude " + leaf + "\n"));
  CHECK(h.out.str() == "leaf\nleaf\n");
}

TEST_CASE("interp errors: an undefined variable", "[interp][errors]") {
  auto e = deck_error("set n 5\necho $n $nope\n");
  CHECK(e.starts_with("deck.dat:2: error: undefined variable $nope"));
  CHECK_THAT(e, Catch::Contains("SET nope"));
}

TEST_CASE("interp errors: binary garbage is reported with its bytes escaped", "[interp][errors]") {
  static const char raw[] = "\x01\x02\xff\xfe\x1bzz\x7f\x80 more\x1bjunk\n";
  std::string garbage(raw, sizeof raw - 1);
  garbage += std::string("\x00\x00\x00\n", 4);
  Harness h;
  CHECK_FALSE(h.deck("set echo off\n" + garbage, "garbage.dat"));
  std::string err = h.err.str();
  CHECK(err.starts_with("garbage.dat:2: error: unknown command '\\x01\\x02\\xff\\xfe\\x1bzz\\x7f\\x80'"));
  // A NUL byte says the file is not text at all (hard_limits.cpp).
  Harness nul;
  CHECK_FALSE(nul.deck("set echo off\n" + std::string("\x00\x00\x00\n", 4), "garbage.dat"));
  CHECK(nul.err.str().starts_with("garbage.dat:2: error: a NUL byte in the line: not a deck? (a binary file?)"));
  // Nothing unprintable reaches the terminal through an error message.
  for (char c : err) {
    auto u = static_cast<unsigned char>(c);
    INFO("byte " << int(u));
    CHECK((u == '\n' || (u >= 32 && u < 127)));
  }
  // Random bytes, NULs included, never crash the reader: every deck ends with true or a reported error.
  std::mt19937 rng(7);
  for (int trial = 0; trial < 200; ++trial) {
    std::string bytes(1 + rng() % 300, '\0');
    for (auto& b : bytes) b = static_cast<char>(rng() & 0xff);
    Harness r;
    bool ok = r.deck(bytes, "random.bin");
    if (!ok) CHECK(r.first_error_line().starts_with("random.bin:"));
  }
}

TEST_CASE("interp errors: a one-megabyte line", "[interp][errors]") {
  // A word as long as a line may be (1 MiB, kMaxLineLength, the line's other words included).
  const std::string huge((1 << 20) - 16, 'x');
  // An unknown 1 MB word: one short message, the word cut.
  auto e = deck_error("set echo off\n" + huge + "\n");
  CHECK(e.starts_with("deck.dat:2: error: unknown command 'xxxx"));
  CHECK_THAT(e, Catch::Contains("(1048560 characters)"));
  CHECK(e.size() < 300);
  // A 1 MB line that is a real command is accepted whole.
  Harness h;
  REQUIRE(h.deck("set echo off\nset big " + huge + "\necho ${big}y\n"));
  CHECK(h.out.str().size() == huge.size() + 2);
  // A 1 MB run of numbers after a command that takes one: the first extra word is named.
  auto extra = deck_error("frac 0.5" + std::string(1 << 19, ' ') + std::string((1 << 19) - 16, '7') + "\n");
  CHECK(extra.starts_with("deck.dat:1: error: unexpected '7777"));
  CHECK(extra.size() < 400);
}

TEST_CASE("interp errors: warnings name the file and line and do not stop the deck", "[interp][errors]") {
  Harness h;
  REQUIRE(h.deck("set echo off\n\nfrac 2\necho still running\n"));
  CHECK(h.first_error_line().starts_with("deck.dat:3: warning: FRAC 2 is above the critical step"));
  CHECK(h.out.str() == "still running\n");
}

TEST_CASE("interp errors: at the prompt an error is reported and the session goes on", "[interp][errors]") {
  Harness h;
  h.interp.interactive = true;
  CHECK_FALSE(h.line("frobnicate", 1));
  CHECK_FALSE(h.line("cycle 1.5", 2));
  CHECK_FALSE(h.line("echo $undefined", 3));
  CHECK(h.line("echo alive ; a comment", 4));
  auto err = trubal::test::lines_of(h.err.str());
  REQUIRE(err.size() == 3);
  CHECK(err[0].starts_with("<stdin>:1: error: unknown command 'frobnicate'"));
  CHECK(err[1].starts_with("<stdin>:2: error: n (number of cycles) must be a whole number"));
  CHECK(err[2].starts_with("<stdin>:3: error: undefined variable $undefined"));
  // No echo of commands at the prompt (the user just typed them), and ECHO still works.
  CHECK(h.out.str() == "alive\n");
  CHECK_FALSE(h.interp.stopped());
  CHECK(h.line("stop", 5));
  CHECK(h.interp.stopped());
}

TEST_CASE("interp errors: batch mode echoes each command and STOP ends the deck", "[interp][errors]") {
  Harness h;
  h.interp.echo = true;
  REQUIRE(h.deck("echo one ; comment\nstop\necho two\n"));
  CHECK(h.out.str() == "trubal> echo one\none\ntrubal> stop\n");
  CHECK(h.err.str().empty());
}

namespace {
// A screen that records what it held at each flush.
struct FlushLog : std::stringbuf {
  std::vector<std::string> flushed;
  int sync() override {
    flushed.push_back(str());
    return 0;
  }
};
}  // namespace

TEST_CASE("interp errors: a batch deck flushes the echo before a command that may take long, not before each BALL",
          "[interp][errors][system]") {
  // A deck of a million BALL lines spent most of its time writing each echo line by itself (and
  // under mpirun each write went through mpirun): quick commands wait for the next flush.
  FlushLog screen;
  std::ostream out(&screen);
  std::ostringstream err;
  Output output(out, err);
  Session session;
  Interpreter interp(session, output);
  interp.echo = true;
  std::string deck = "start box 0 100 0 100 0 100\nprop kn 1e5 dens 1000\n";
  for (int k = 0; k < 200; ++k) deck += fmt::format("ball {} {} {} 0.4\n", 1 + (k % 10), 1 + (k / 10) % 10, 1 + k / 100);
  deck += "cycle 1\necho done\n";
  std::istringstream in(deck);
  REQUIRE(interp.run_deck(in, "deck.dat"));
  // Every line is there, in order.
  const std::string all = screen.str();
  CHECK(all.find("trubal> ball 1 1 1 0.4\n") < all.find("trubal> cycle 1\n"));
  CHECK(all.find("trubal> cycle 1\n") < all.find("trubal> echo done\ndone\n"));
  // START flushes (before and after), the 200 BALL lines and PROP do not: far fewer flushes than lines.
  CHECK(screen.flushed.size() < 10);
  // CYCLE's line was on the screen before it ran: some flush ends with it.
  bool shown = false;
  for (const auto& f : screen.flushed) shown = shown || f.ends_with("trubal> cycle 1\n");
  CHECK(shown);
  CHECK(err.str().empty());
}

TEST_CASE("interp errors: inputs that hung, overflowed or ran on nothing are errors now", "[interp][errors][hard]") {
  // A shear rate that moves the cell by more than half an edge a step: the tilt reduction could
  // never catch up (past 2^53 the subtraction changed nothing, and CYCLE hung).
  auto shear = deck_error("start 1 1 1\nprop kn 1e4 ks 1e4 dens 1000\ngen 20 0.1 0.1 seed 1\nstrain xy 1e20\ncycle 5\n");
  CHECK(shear.starts_with("deck.dat:5: error: the strain rates would change the cell's xy tilt by"));
  // The next free id after the largest possible one (signed overflow before).
  auto ids = deck_error("start box -5 5 -5 5 -5 5\nball 0 0 0 1 id 9223372036854775807\nball 3 0 0 1\n");
  CHECK(ids.starts_with("deck.dat:3: error: no ball id is left after 9223372036854775807"));
  // Cycling nothing set time and step to inf for good.
  auto empty = deck_error("start box 0 1 0 1 0 1\ncycle 10\n");
  CHECK(empty.starts_with("deck.dat:2: error: there are no balls to cycle"));
}

TEST_CASE("interp errors: a chain of CALLs is limited in depth, not by the stack", "[interp][errors][hard]") {
  TempDir dir;
  // deck k calls deck k+1, 150 of them (distinct files, so no self-call): 5,570 of them crashed.
  for (int k = 0; k < 150; ++k) dir.write(fmt::format("d{}.dat", k), fmt::format("call d{}.dat\n", k + 1));
  dir.write("d150.dat", "echo bottom\n");
  Harness h;
  CHECK_FALSE(h.deck("call " + (dir.path() / "d0.dat").string() + "\n"));
  CHECK(h.err.str().find("CALL nested more than 100 files deep") != std::string::npos);
}

TEST_CASE("interp errors: a ball thrown across the periodic space, all balls held, a massless ball", "[interp][errors][hard]") {
  // apply zforce -1e15: the ball crosses ~1e10 cells in a step; its image shift overflowed (UB) and the
  // run ended with exit 0 and the ball at z = -7e9 in a unit cell.
  auto thrown = deck_error("start 1 1 1\nprop kn 1e4 ks 1e4 dens 1000\ngen 20 0.1 0.1 seed 1\n"
                           "apply zforce -1e15 range id 1\ncycle 5\n");
  CHECK(thrown.starts_with("deck.dat:5: error: ball 1 is "));
  CHECK(thrown.find("edge lengths of the periodic cell away along z") != std::string::npos);
  // Every ball held: no free ball sets a step, so the step is that of the balls as if free (it was
  // infinite, and the run ended in a false "unstable").
  Harness held;
  REQUIRE(held.deck("start box -1 2 -1 2 -1 2\nprop kn 1e4 ks 1e4 dens 1000\nball 0 0 0 0.1\nball 0.19 0 0 0.1\n"
                    "fix vel spin\ncycle 5\n"));
  const double mass = 1000 * 4.0 / 3.0 * M_PI * 1e-3;
  // The free-ball bound of a ball in one contact without rotation (the spins are fixed):
  // 2 / sqrt(2 k / m) (doc/physics.md "Time step"), times FRAC 0.8.
  CHECK(held.session.model().dt == Approx(0.8 * 2 / std::sqrt(2 * 1e4 / mass)).epsilon(1e-9));
  // A ball whose mass rounds to zero is an input error, not an instability.
  auto massless = deck_error("start box -1 2 -1 2 -1 2\nprop kn 1e4 ks 1e4 dens 1e-300\nball 0 0 0 1e-120\ncycle 5\n");
  CHECK(massless.starts_with("deck.dat:4: error: ball 1 has mass 0"));
}

TEST_CASE("interp errors: outputs never replace a link, and a failed write is reported", "[interp][errors][hard][system]") {
  TempDir dir;
  const std::string target = dir.write("target.txt", "keep me\n");
  const std::string link = (dir.path() / "link.csv").string();
  REQUIRE(::symlink(target.c_str(), link.c_str()) == 0);
  // PRINT ... file and SAVE write a temporary and rename it: over a link that would have turned the
  // link into a regular file.
  for (const std::string& command : {"print balls file " + link, "save " + link}) {
    INFO(command);
    auto e = deck_error("start box 0 1 0 1 0 1\n" + command + "\n");
    CHECK(e.find("will not replace '" + link + "': it is a symbolic link") != std::string::npos);
    CHECK(std::filesystem::is_symlink(link));
    CHECK(trubal::test::slurp(target) == "keep me\n");
  }
  // PRINT's tables are written row by row into the temporary (a million balls' table is never held
  // whole in memory): a file that cannot be made, or a disk that fills, is still an error naming it.
  const std::string missing = (dir.path() / "no_such_folder" / "b.csv").string();
  for (const std::string item : {"balls", "contacts"}) {
    INFO(item);
    auto e = deck_error("start box 0 1 0 1 0 1\nprop kn 1e4 dens 1000\nball 0.5 0.5 0.5 0.1\nball 0.69 0.5 0.5 0.1\n"
                        "cycle 1\nprint " + item + " file " + missing + "\n");
    CHECK(e.find("deck.dat:6: error: cannot write '" + missing + "': No such file or directory") != std::string::npos);
    if (std::filesystem::exists("/dev/full")) {
      auto full = deck_error("start box 0 1 0 1 0 1\nprop kn 1e4 dens 1000\nball 0.5 0.5 0.5 0.1\n"
                             "ball 0.69 0.5 0.5 0.1\ncycle 1\nprint " + item + " file /dev/full\n");
      CHECK(full.find("deck.dat:6: error: ") != std::string::npos);
    }
  }
  // A HIST file that cannot take its rows (a full disk: /dev/full) stops the run and says so.
  if (std::filesystem::exists("/dev/full")) {
    auto full = deck_error("start box 0 1 0 1 0 1\nprop kn 1e4 dens 1000\nball 0.5 0.5 0.5 0.1\n"
                           "hist time every 1 file /dev/full\ncycle 3\n");
    CHECK(full.find("cannot write the history file '/dev/full' (No space left on device)") != std::string::npos);
    // SET log on a full disk: a warning, once, and logging stops; the deck goes on.
    Harness h;
    REQUIRE(h.deck("set log /dev/full\necho one\necho two\n"));
    CHECK(h.err.str().find("warning: the log file '/dev/full' could not be written (No space left on device); "
                           "logging stopped") != std::string::npos);
    CHECK(h.out.str().find("two") != std::string::npos);
    // Standard output on a full disk: exit status 1 and the reason, not 0.
    const std::string deck = dir.write("ok.dat", "echo hello\n");
    CHECK(trubal::test::shell(trubal::test::quote(TRUBAL_EXE) + " " + trubal::test::quote(deck) + " > /dev/full 2> " + trubal::test::quote(dir.str() + "/err.txt")) == 1);
    CHECK(trubal::test::slurp(dir.path() / "err.txt").find("cannot write the standard output: No space left on device") !=
          std::string::npos);
  }
}

TEST_CASE("interp errors: GEN and LATTICE check their size first and heed Ctrl-C", "[interp][errors][hard]") {
  // GEN of 1e8 in a 20^3 box tried 2000 n times (hours); a LATTICE of 1e15 points built first.
  auto gen = deck_error("start box 0 20 0 20 0 20\ngen 100000000 1 1\n");
  CHECK(gen.starts_with("deck.dat:2: error: GEN: 100000000 balls of radius 1 or more cannot fit"));
  auto lattice = deck_error("start box 0 20 0 20 0 20\nlattice fcc 1 100000 100000 100000\n");
  CHECK(lattice.starts_with("deck.dat:2: error: LATTICE: 100000 x 100000 x 100000 = 1e+15 points is more than"));
  // A box far larger than its balls overflowed GEN's placement cells (UB); now the balls are placed.
  Harness wide;
  REQUIRE(wide.deck("start 1e23 0.01 0.01\ngen 10 0.001 0.001\n"));
  CHECK(wide.session.model().balls.size() == 10);
  // Ctrl-C during GEN: it stops, keeps what it placed, and says so (in a batch deck as the error
  // that stops it: hard_limits.cpp).
  Harness h;
  REQUIRE(h.deck("start box 0 20 0 20 0 20\n"));
  interrupt_requested() = true;
  REQUIRE_FALSE(h.deck("gen 100 0.5 0.5\n"));
  CHECK(h.err.str().find("GEN interrupted by Ctrl-C: 0 of 100 balls placed (kept)") != std::string::npos);
  CHECK_FALSE(interrupt_requested().load());
}

TEST_CASE("interp errors: BACKEND threads the system cannot start is an error, not a hang", "[interp][errors][hard][system][threads]") {
  // Under a 4 GB address-space limit 4096 threads' stacks do not fit: the pool used to destroy the
  // condition variable its started workers waited on, and hung. In a child process, with a timeout.
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
  SUCCEED("a sanitizer reserves more address space than the limit allows: the program cannot start under it");
  return;
#endif
  TempDir dir;
  const std::string deck = dir.write("threads.dat", "backend threaded threads 4096\necho after\n");
  const int status = trubal::test::shell("ulimit -v 4000000; timeout 120 " + trubal::test::quote(TRUBAL_EXE) + " " +
                                         trubal::test::quote(deck) + " > " + trubal::test::quote(dir.str() + "/out.txt") +
                                         " 2>&1");
  const std::string out = trubal::test::slurp(dir.path() / "out.txt");
  INFO(out);
  if (out.find("backend threaded (4096 threads)") != std::string::npos) {
    SUCCEED("this machine started 4096 threads under the limit: nothing to check");
    return;
  }
  CHECK(status == 1);   // not 124 (the timeout) nor a signal
  CHECK(out.find("threads.dat:1: error: could not start thread") != std::string::npos);
  CHECK(out.find("ask for fewer threads") != std::string::npos);
}

TEST_CASE("interp errors: BALL refuses a centre another ball has, and says which", "[interp][errors]") {
  const auto e = deck_error("start box -1 1 -1 1 -1 1\nball 0.1 0.2 0.3 0.1 id 7\nball 0.5 0 0 0.1\nball 0.1 0.2 0.3 0.05\n");
  CHECK(e.starts_with("deck.dat:4: error: ball 7 is already at (0.1, 0.2, 0.3)"));
  // After the balls move, the check is against where they are now.
  Harness h;
  REQUIRE(h.deck("start box -1 1 -1 1 -1 1\nprop kn 1e5 dens 1000\nball 0 0 0 0.1 id 1\ninit xvel 1\ntstep 0.01\n"
                 "cycle 10\nball 0 0 0 0.1 id 2\n"));
  CHECK(h.session.model().balls.size() == 2);
  CHECK_FALSE(h.deck("ball 0 0 0 0.1 id 3\n"));
  CHECK_THAT(h.first_error_line(), Catch::Contains("ball 2 is already at"));
  // -0 is the centre 0 (the index hashes them alike).
  Harness signs;
  CHECK_FALSE(signs.deck("start box -1 1 -1 1 -1 1\nball 0 0.5 0 0.1 id 1\nball -0 0.5 -0.0 0.1 id 2\n"));
  CHECK_THAT(signs.first_error_line(), Catch::Contains("ball 1 is already at"));
  // Thousands of balls (the index grows many times over): a repeat of any one is found, by its id.
  std::string many = "start box 0 100 0 100 0 100\n";
  for (int k = 1; k <= 3000; ++k) many += fmt::format("ball {} {} {} 0.1 id {}\n", 1 + k % 97, 1 + k / 97, 1 + (k * 7) % 89, k);
  Harness lots;
  REQUIRE(lots.deck(many));
  CHECK_FALSE(lots.deck(fmt::format("ball {} {} {} 0.05\n", 1 + 1234 % 97, 1 + 1234 / 97, 1 + (1234 * 7) % 89)));
  CHECK_THAT(lots.first_error_line(), Catch::Contains("ball 1234 is already at"));
}

// For a host program (the Python module): lines run as part of its own file from its line, the
// error kept rather than written, and STOP ending one text, not the next.
TEST_CASE("interp errors: text from a host names its file and line, and the error is kept", "[interp][errors]") {
  Harness h;
  h.interp.report_errors = false;
  CHECK_FALSE(h.interp.run_text("start box 0 1 0 1 0 1\nball 0.5 0.5 0.5 0.1\nprop foo 1\nball 0.2 0.2 0.2 0.1",
                                "script.py", "", 40));
  const auto& e = h.interp.last_error();
  CHECK(e.file == "script.py");
  CHECK(e.line == 42);   // the third line of a text that starts at line 40
  CHECK(e.message.find("unknown property 'foo'") == 0);
  CHECK(h.err.str().empty());                    // kept, not written
  CHECK(h.session.model().balls.size() == 1);   // the lines before it ran, the one after did not

  h.interp.report_errors = true;   // the shell's way: written as well
  CHECK_FALSE(h.interp.run_text("frobnicate", "script.py", "", 7));
  CHECK(h.interp.last_error().line == 7);
  CHECK(h.first_error_line().rfind("script.py:7: error: ", 0) == 0);

  CHECK(h.interp.run_text("stop\nball 0.2 0.2 0.2 0.1", "script.py", "", 9));
  CHECK(h.interp.stopped());
  CHECK(h.session.model().balls.size() == 1);
  h.interp.resume();
  CHECK(h.interp.run_text("ball 0.2 0.2 0.2 0.1", "script.py", "", 10));
  CHECK(h.session.model().balls.size() == 2);
}
