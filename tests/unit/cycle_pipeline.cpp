// The pipeline's contract and counters, and the rooms' dependency rule.
#include "paths.hpp"
#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <regex>

#include "cycle/pipeline.hpp"
#include "cycle/run.hpp"
#include "interp_support.hpp"

using namespace trubal;
using namespace trubal::test;

namespace {

const char* kGas = R"(start 0.01 0.01 0.01
prop kn 1e5 ks 1e5 fric 26.57 dens 2650
gen 300 0.0004 0.0006 seed 7
damp local 0.7
servo 1e5 1e5 1e5
)";

}  // namespace

TEST_CASE("pipeline: every CYCLE leaves the contacts' results of its last step current", "[cycle]") {
  Harness h;
  REQUIRE(h.deck(kGas));
  CHECK(h.session.model().contacts.results_cycle == -1);   // no force pass yet
  for (int n : {1, 7, 3001, 3}) {
    INFO("cycle " << n);
    REQUIRE(h.line("cycle " + std::to_string(n)));
    CHECK(h.session.model().contacts.results_cycle == h.session.model().cycle);
  }
  // The results are those of that force pass: the stress they sum is the servo's measured one,
  // which the contact loop summed in its own order (so equal within rounding, not bitwise).
  const Model& m = h.session.model();
  REQUIRE(m.space.servo_measured_valid);
  double from_table = 0;
  for (std::size_t p = 0; p < m.contacts.size(); ++p) {
    const double l = (m.balls.rad[m.contacts.i[p]] + m.balls.rad[m.contacts.j[p]] - m.contacts.overlap[p]) * m.contacts.nx[p];
    from_table += m.contacts.fx[p] * l;
  }
  const double measured = m.space.servo_measured.force[0];
  REQUIRE(measured != 0);
  CHECK(from_table == Approx(measured).epsilon(1e-9));   // rounding of a sum of ~1000 terms
}

TEST_CASE("pipeline: counters say how the pair list was kept", "[cycle][threads]") {
  Harness h;
  REQUIRE(h.deck(kGas));
  REQUIRE(h.line("cycle 2000"));
  const PipelineCounters c = h.session.pipeline().counters();
  // The servo compresses the gas: the cell shrinks by more than the skin many times over.
  CHECK(c.rebuilds > 10);
  CHECK(c.rebuilds < 2000);                 // but not every step: the list is kept between
  CHECK(c.skin > 0);
  CHECK(c.threads_used == 1);
  CHECK(c.pair_tests == 0);                 // serial does not count its tests

  REQUIRE(h.line("backend allpairs threads 2"));
  REQUIRE(h.line("cycle 10"));
  const PipelineCounters a = h.session.pipeline().counters();
  CHECK(a.skin == 0);                       // asked every step for the pairs touching now
  CHECK(a.pair_tests == 10 * 300 * 299 / 2);   // every pair once a step (the first uses the CYCLE's own search)
  CHECK(a.threads_used >= 1);
}

TEST_CASE("pipeline: the model and physics rooms include neither the cycle nor a backend", "[cycle]") {
  namespace fs = std::filesystem;
  const fs::path src = fs::path(TRUBAL_SOURCE_DIR) / "src";
  const std::regex include(R"(#include\s+"([a-z_]+)/)");
  // room -> the rooms it may include (doc/developer.md, "Rooms")
  const std::map<std::string, std::set<std::string>> allowed = {
      {"model", {"model"}},
      {"physics", {"model", "physics", "support"}},
      {"io", {"model", "physics", "io", "support"}},
      {"backends", {"model", "backends", "support"}},
      {"support", {"support"}},
      {"cycle", {"model", "physics", "cycle", "support", "backends"}},
  };
  std::size_t files = 0;
  for (const auto& [room, may] : allowed) {
    for (const auto& entry : fs::recursive_directory_iterator(src / room)) {
      if (!entry.is_regular_file()) continue;
      std::ifstream in(entry.path());
      ++files;
      for (std::string line; std::getline(in, line);) {
        std::smatch m;
        if (!std::regex_search(line, m, include)) continue;
        INFO(entry.path().string() << ": " << line);
        CHECK(may.count(m[1].str()) == 1);
        // The cycle sees only the backend interface, never a concrete backend.
        if (room == "cycle" && m[1].str() == "backends")
          CHECK((line.find("backends/backend.hpp") != std::string::npos ||
                 line.find("backends/pair_candidates.hpp") != std::string::npos));
      }
    }
  }
  CHECK(files > 40);
}
