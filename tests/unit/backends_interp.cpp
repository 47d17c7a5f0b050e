// Through the interpreter: the same deck on every backend and thread count, and with backend
// switches mid-run, writes byte-identical PRINT balls and PRINT contacts files.
#include <catch2/catch.hpp>

#include <cstring>

#include "backends_scenes.hpp"
#include "interp_support.hpp"

using namespace trubal;
using namespace trubal::test;

namespace {

// 576 held floor balls and 1500 thrown down onto them: friction, rotation, gravity, local damping.
const char* kSetup = R"(start box -0.3 0.3 -0.3 0.3 -0.05 0.6
prop kn 1e5 ks 1e5 fric 30 dens 2650
prop type 2 kn 2e5 ks 1e5 fric 20 dens 2650
lattice fcc 0.02 24 24 1 origin -0.25 -0.25 0 type 2
fix vel spin range type 2
gen 1500 0.004 0.007 seed 7 range cylinder 0 0 0.2 z 0.03 0.2
init zvel -2 xvel 0.3 range type 1
grav 0 0 -9.81
damp local 0.3
)";

struct Files { std::string balls, contacts, info; };

Files run_deck(const std::string& cycling) {
  TempDir dir;
  WorkingDir cd(dir.path());
  Harness h;
  const bool ok = h.deck(std::string(kSetup) + cycling + "print balls file balls.csv\nprint contacts file contacts.csv\n");
  INFO(h.err.str());
  REQUIRE(ok);
  h.out.str("");
  REQUIRE(h.line("print info"));
  return {slurp(dir.path() / "balls.csv"), slurp(dir.path() / "contacts.csv"), h.out.str()};
}

}  // namespace

TEST_CASE("backends: a deck writes byte-identical balls and contacts files on every backend", "[backends][threads]") {
  const Files serial = run_deck("cycle 900\n");
  REQUIRE(lines_of(serial.contacts).size() > 300);
  const char* variants[] = {"backend threaded threads 1\ncycle 900\n", "backend threaded threads 2\ncycle 900\n",
                            "backend threaded threads 3\ncycle 900\n", "backend threaded threads 4\ncycle 900\n",
                            "backend allpairs threads 2\ncycle 900\n",
                            // switching mid-run keeps the contacts' shear history
                            "cycle 300\nbackend allpairs threads 3\ncycle 300\nbackend threaded threads 2\ncycle 300\n",
                            "backend threaded\ncycle 450\nbackend serial\ncycle 450\n"};
  for (const char* cycling : variants) {
    if (kRaceCheckOnly && (std::strstr(cycling, "threads 1\n") || std::strstr(cycling, "threads 4\n"))) continue;
    INFO(cycling);
    const Files other = run_deck(cycling);
    CHECK(other.balls == serial.balls);
    CHECK(other.contacts == serial.contacts);
  }
}

TEST_CASE("backends: PRINT info names the backend and its threads", "[backends][threads]") {
  Harness h;
  REQUIRE(h.line("backend threaded threads 3"));
  CHECK(h.out.str() == "backend threaded (3 threads)\n");
  h.out.str("");
  REQUIRE(h.line("print info"));
  CHECK(h.out.str().find("backend: threaded\nthreads: 3\n") != std::string::npos);
  REQUIRE(h.line("backend allpairs threads 2 maxmem 1e6"));
  h.out.str("");
  REQUIRE(h.line("print info"));
  CHECK(h.out.str().find("backend: allpairs\nthreads: 2\n") != std::string::npos);
  CHECK(h.out.str().find("memory limit: 977 KiB (1000000 bytes)") != std::string::npos);
}

TEST_CASE("backends: allpairs above maxmem stops CYCLE with a clear error, model intact", "[backends]") {
  TempDir dir;
  WorkingDir cd(dir.path());
  Harness h;
  REQUIRE(h.deck(std::string(kSetup) + "backend allpairs maxmem 100000\n"));
  CHECK_FALSE(h.line("cycle 10"));
  const std::string error = h.err.str();
  CHECK(error.find("2076 balls have 2153850 pair slots") != std::string::npos);
  CHECK(error.find("BACKEND allpairs maxmem") != std::string::npos);
  CHECK(h.session.model().cycle == 0);
  CHECK_FALSE(h.line("backend serial maxmem 100"));
  CHECK(h.err.str().find("maxmem goes with BACKEND allpairs") != std::string::npos);
  REQUIRE(h.line("backend allpairs maxmem 3e6"));
  CHECK(h.line("cycle 10"));
  CHECK(h.session.model().cycle == 10);
}

TEST_CASE("backends: PRINT info reports the boxes of the search that ran, the periodic one's in a periodic space",
          "[backends][threads]") {
  // A box space: the boxes of TRUBAL's search. A box with periodic x and y: the periodic search's
  // bins (the boxes are never made; reporting their empty 1 x 1 x 1 misled).
  for (const char* backend : {"serial", "threaded threads 2"}) {
    INFO(backend);
    for (bool periodic : {false, true}) {
      INFO((periodic ? "periodic in x and y" : "a box"));
      Harness h;
      const std::string deck = std::string("start box 0 0.2 0 0.2 0 0.1") + (periodic ? " x periodic y periodic" : "") +
                               "\nprop kn 1e5 ks 1e5 fric 30 dens 2650\nbackend " + backend +
                               "\nlattice fcc 0.02 10 10 2 origin 0.01 0.01 0.01\ncycle 2\n";
      REQUIRE(h.deck(deck));
      h.out.str("");
      REQUIRE(h.line("print info"));
      const std::string info = h.out.str();
      const auto at = info.find("contact boxes: ");
      REQUIRE(at != std::string::npos);
      const std::string line = info.substr(at, info.find('\n', at) - at);
      if (periodic) {
        CHECK_THAT(line, Catch::EndsWith("(the periodic search's, across the cell)"));
        CHECK(line.find("contact boxes: 1 x 1 x") == std::string::npos);   // 0.2 wide, balls 0.02 apart: several bins
      } else {
        CHECK_THAT(info, Catch::Contains("box size: "));
        CHECK(line.find("periodic") == std::string::npos);
      }
    }
  }
}
