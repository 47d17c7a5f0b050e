// The traps a new user (a PFC user) falls into on the first day (issue 45): `fric` typed as a
// coefficient, a misspelt group, huge overlaps, a typo'd command, CALL of a missing file, GEN sizes
// in another unit, leaving the shell with the model not saved. Each gets a message that names what
// happened and what to do.
#include "paths.hpp"
#include <catch2/catch.hpp>

#include <cctype>
#include <cmath>

#include <fmt/format.h>

#include "cycle/pipeline.hpp"
#include "interp_support.hpp"

using namespace trubal;
using trubal::test::Harness;
using trubal::test::TempDir;
using trubal::test::WorkingDir;
namespace fs = std::filesystem;

namespace {

std::size_t count_of(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

// A box with two groups of balls: `platens` (the two balls below z = 0) and `sample`.
const std::string kScene =
    "start box -1 1 -1 1 -1 1\n"
    "prop kn 1e5 ks 1e5 fric 30 dens 1000\n"
    "ball 0 0 -0.5 0.1\nball 0.3 0 -0.5 0.1\nball 0 0 0.5 0.1\n"
    "group platens range z -1 0\n"
    "group sample range z 0 1\n";

}  // namespace

TEST_CASE("traps: PROP fric between 0 and 1 warns once that it is degrees and points to mu", "[interp][traps]") {
  Harness h;
  REQUIRE(h.deck("start box -1 1 -1 1 -1 1\nprop kn 100 ks 100 fric 0.5 dens 2.65\n"));
  CHECK(h.err.str() ==
        "deck.dat:2: warning: fric 0.5 is a friction angle in degrees: mu = tan(0.5 deg) = 0.00873; for a friction "
        "coefficient of 0.5 write `mu 0.5`\n");
  // The property is still what the deck said: an angle of half a degree (one tan: a few ulps).
  CHECK(h.session.model().materials.at(1).friction == Approx(std::tan(0.5 * M_PI / 180)).epsilon(1e-14));

  Harness quiet;   // an angle, or the coefficient by `mu`, or fric 0: no warning
  REQUIRE(quiet.deck("start box -1 1 -1 1 -1 1\nprop kn 100 fric 30\nprop mu 0.5\nprop fric 0\nprop fric 1\n"
                     "prop fric 0.5 mu 0.5\n"));
  CHECK(quiet.err.str().empty());
  CHECK(quiet.session.model().materials.at(1).friction == 0.5);   // mu, given last, is taken as typed

  Harness once;   // one warning per PROP, of the value that stands
  REQUIRE(once.deck("start box -1 1 -1 1 -1 1\nprop fric 0.3 kn 100 fric 0.7\n"));
  CHECK(count_of(once.err.str(), "warning:") == 1);
  CHECK_THAT(once.err.str(), Catch::Contains("fric 0.7 is a friction angle in degrees"));
}

TEST_CASE("traps: PROP's HELP gives the unit of every property", "[interp][traps]") {
  Harness h;
  REQUIRE(h.deck("help prop\n"));
  // Read as one line: where HELP wraps its text is no part of what it says.
  std::string help;
  for (const char c : h.out.str())
    if (!std::isspace(static_cast<unsigned char>(c)))
      help.push_back(c);
    else if (!help.empty() && help.back() != ' ')
      help.push_back(' ');
  for (const char* unit : {"N/m", "degrees", "kg/m^3", "cohesion in N", "(Pa)", "mu: the friction coefficient",
                           "no units of its own"})
    CHECK_THAT(help, Catch::Contains(unit));
}

TEST_CASE("traps: a range naming a group that does not exist is an error at FILE:LINE with the near name",
          "[interp][traps][errors]") {
  // Every command that reads a range, each with the misspelt group at line 8 of the deck.
  for (const char* command : {"fix zvel", "free zvel", "init zvel -0.1", "apply zforce 1", "delete", "print balls",
                              "print contacts", "print stress", "group top", "hist platen", "membrane 1000",
                              "lattice fcc 0.1 2 2 2 origin 0.5 0.5 0.5"}) {
    Harness h;
    const std::string deck = kScene + fmt::format("{} range group platen\necho after\n", command);
    INFO(command << "\n" << h.err.str());
    CHECK_FALSE(h.deck(deck));
    CHECK(h.first_error_line().starts_with("deck.dat:8: error: no group 'platen': did you mean 'platens'?"));
    CHECK(h.out.str().find("after") == std::string::npos);   // the deck stopped there
  }
  // `not group`, and a name far from every group: the groups are listed.
  Harness far;
  CHECK_FALSE(far.deck(kScene + "fix zvel range z -1 1 not group walls\n"));
  CHECK(far.first_error_line().starts_with("deck.dat:8: error: no group 'walls' (the groups are platens, sample)"));
  Harness none;
  CHECK_FALSE(none.deck("start box -1 1 -1 1 -1 1\nball 0 0 0 0.1\ndelete range group platens\n"));
  CHECK(none.first_error_line().starts_with("deck.dat:3: error: no group 'platens': there are no groups yet"));
  CHECK(none.session.model().balls.size() == 1);   // nothing deleted
}

TEST_CASE("traps: a range that holds no ball is still a warning, and the deck goes on", "[interp][traps]") {
  Harness h;
  REQUIRE(h.deck(kScene + "group empty range z 0.9 1\nfix zvel range group empty\ndelete range group empty\n"));
  const std::string err = h.err.str();
  CHECK_THAT(err, Catch::Contains("deck.dat:8: warning: group empty holds no ball"));
  CHECK_THAT(err, Catch::Contains("deck.dat:9: warning: the range holds for no ball"));
  CHECK_THAT(err, Catch::Contains("deck.dat:10: warning: the range holds for no ball"));
  CHECK(h.session.model().balls.size() == 3);
}

TEST_CASE("traps: an unknown command gets a did-you-mean from the command names and aliases", "[interp][traps][errors]") {
  Harness h;
  CHECK_FALSE(h.deck("cylce 10\n"));
  CHECK(h.first_error_line() == "deck.dat:1: error: unknown command 'cylce': did you mean CYCLE? (HELP lists the commands)");
  Harness alias;
  CHECK_FALSE(alias.deck("restroe run.sav\n"));
  CHECK(alias.first_error_line().starts_with("deck.dat:1: error: unknown command 'restroe': did you mean RESTORE?"));
  Harness far;   // nothing near: no guess
  CHECK_FALSE(far.deck("frobnicate 1\n"));
  CHECK(far.first_error_line() == "deck.dat:1: error: unknown command 'frobnicate' (HELP lists the commands)");
}

TEST_CASE("traps: CALL of a missing file says where it looked and the current folder", "[interp][traps][errors]") {
  TempDir dir, work;
  const std::string deck = dir.write("main.dat", "echo before\ncall nothere.dat\n");
  WorkingDir in(work.path());
  Harness h;
  CHECK_FALSE(h.interp.run_file(deck));
  const std::string here = fs::current_path().string();
  CHECK(h.first_error_line() ==
        fmt::format("{}:2: error: cannot open the file 'nothere.dat' to CALL: looked for {}/nothere.dat and "
                    "{}/nothere.dat (the current folder is {})",
                    deck, here, fs::weakly_canonical(dir.path()).string(), here));
}

TEST_CASE("traps: GEN with radii larger than the box hints at the unit", "[interp][traps][errors]") {
  Harness h;
  CHECK_FALSE(h.deck("start box 0 0.1 0 0.1 0 0.1\ngen 100 2 3\n"));
  CHECK(h.first_error_line() ==
        "deck.dat:2: error: GEN: 100 balls of radius 2 or more cannot fit in the region (at most 2.21e-05 even packed as "
        "densely as spheres can be); the radii (2 to 3) are larger than the space (0.1 wide): sizes in another "
        "unit? trubal has no units of its own; in SI, as in the examples, a radius of 2 mm is 0.002");
  Harness fits;   // sizes of the space's unit that are merely too many: no hint
  CHECK_FALSE(fits.deck("start box 0 0.1 0 0.1 0 0.1\ngen 100000 0.01 0.02\n"));
  CHECK(fits.first_error_line().find("unit") == std::string::npos);
}

TEST_CASE("traps: an overlap past a tenth of the smaller radius is warned of once, with the balls and the cycle",
          "[interp][traps]") {
  // Balls held still (FIX vel, velocity 0): their overlaps stay exactly as placed.
  Harness h;
  REQUIRE(h.deck("start box -1 1 -1 1 -1 1\nprop kn 1e5 dens 1000\n"
                 "ball 0 0 0 0.1\nball 0.17 0 0 0.1\nball 0.5 0 0 0.1\nball 0.65 0 0 0.05\n"
                 "ball 0 0.5 0 0.1\nball 0 0.695 0 0.1\n"
                 "fix vel\ncycle 3\ncycle 2\n"));
  // Ball pairs 1-2 (overlap 0.03 of radius 0.1), 3-4 (0.0 of 0.05: 0) and 5-6 (0.005 of 0.1, below).
  const std::string err = h.err.str();
  CHECK(count_of(err, "warning:") == 1);   // the second CYCLE finds the same: not said again
  CHECK_THAT(err, Catch::Contains("deck.dat:10: warning: at cycle 3 the overlap of balls 1 and 2 is 0.3 of ball 1's "
                                  "radius: past 0.1 of a radius"));
  // A read of the positions: no contact result was made for it (no step taken again).
  CHECK(h.session.pipeline().counters().results_made == 0);

  // A wall contact; and after the overlaps came back below, a new one is warned of again.
  Harness w;
  REQUIRE(w.deck("start box -1 1 -1 1 -1 1\nprop kn 1e5 dens 1000\nwall plane 0 0 -0.5 0 0 1\n"
                 "ball 0 0 -0.42 0.1\nfix vel\ntstep 0.01\ncycle 1\ninit zvel 2\ncycle 1\ninit zvel -2\ncycle 1\n"));
  const std::string werr = w.err.str();
  // Three: BALL's own (the ball is placed across the wall), then the two overlaps.
  CHECK(count_of(werr, "warning:") == 3);
  CHECK_THAT(werr, Catch::Contains("deck.dat:4: warning: BALL: ball 1 crosses wall 1"));
  CHECK_THAT(werr, Catch::Contains("deck.dat:7: warning: at cycle 1 the overlap of ball 1 on wall 1 is 0.2 of ball 1's radius"));
  CHECK_THAT(werr, Catch::Contains("deck.dat:11: warning: at cycle 3 the overlap of ball 1 on wall 1 is 0.2"));
}

TEST_CASE("traps: leaving with the model not saved is said where stdin is no terminal", "[interp][traps][exe][system]") {
  TempDir dir;
  dir.write("changed.dat", "start box 0 1 0 1 0 1\nball 0.5 0.5 0.5 0.1\n");
  dir.write("saved.dat", "start box 0 1 0 1 0 1\nball 0.5 0.5 0.5 0.1\nsave run.sav\nprint info\n");
  dir.write("restarted.dat", "restart run.sav\n");
  // The shell reads `typed` (nothing: the end of its input, as Ctrl-D) after the deck.
  auto run = [&](const std::string& deck, const std::string& typed = "") {
    dir.write("typed.txt", typed);
    const int status = trubal::test::shell("cd " + trubal::test::quote(dir.str()) + " && env TRUBAL_HISTORY=" +
                                           trubal::test::quote(dir.str() + "/history") + " timeout 60 " +
                                           trubal::test::quote(TRUBAL_EXE) + " -i " + deck +
                                           " <typed.txt >stdout.txt 2>stderr.txt");
    CHECK(status == 0);
    return trubal::test::slurp(dir.path() / "stderr.txt");
  };
  const std::string notice = "note: the session ends with the model not saved (it changed since the last SAVE)\n";
  CHECK(run("changed.dat") == notice);
  CHECK(run("saved.dat").empty());       // PRINT after SAVE changes nothing
  CHECK(run("restarted.dat").empty());   // the model is the file's
  // STOP (or QUIT) typed at the prompt leaves as the end of the input does.
  CHECK(run("changed.dat", "stop\n") == notice);
  CHECK(run("changed.dat", "quit\necho after\n") == notice);
  CHECK(trubal::test::slurp(dir.path() / "stdout.txt").find("after") == std::string::npos);
  CHECK(run("saved.dat", "stop\n").empty());
}

TEST_CASE("traps: SET of a setting PFC sets with `set` says it only made a variable, and which command sets it",
          "[interp][traps]") {
  Harness h;
  REQUIRE(h.deck("start box -1 1 -1 1 -1 1\nset gravity 0 0 -9.81\nset kn 1e6\nset dt 1e-5\n"));
  CHECK(h.err.str() ==
        "deck.dat:2: warning: SET gravity defines the variable $gravity and sets nothing else; gravity is set by "
        "GRAV gx gy gz\n"
        "deck.dat:4: warning: SET dt defines the variable $dt and sets nothing else; dt is set by TSTEP dt (or FRAC "
        "f)\n");
  // The variables are made all the same (a deck may mean them), and gravity stays off.
  CHECK(h.session.model().settings.gravity == std::array<double, 3>{0, 0, 0});
  Harness grav;   // GRAV itself, and a variable by another name: no warning
  REQUIRE(grav.deck("start box -1 1 -1 1 -1 1\nset g -9.81\ngrav 0 0 $g\n"));
  CHECK(grav.err.str().empty());
  CHECK(grav.session.model().settings.gravity[2] == -9.81);
}

TEST_CASE("traps: a count of one ball is said in the singular", "[interp][traps]") {
  Harness h;
  REQUIRE(h.deck(kScene + "fix vel range id 1\ndelete range id 2\ngroup one range id 3\ninit xvel 1 range group one\n"));
  const std::string out = h.out.str();
  INFO(out);
  CHECK_THAT(out, Catch::Contains("1 ball fixed"));
  CHECK_THAT(out, Catch::Contains("1 ball deleted"));
  CHECK_THAT(out, Catch::Contains("group one: 1 ball\n"));
  CHECK_THAT(out, Catch::Contains("1 ball set"));
  CHECK_THAT(out, Catch::Contains("group platens: 2 balls"));
  CHECK(out.find("1 balls") == std::string::npos);
}
