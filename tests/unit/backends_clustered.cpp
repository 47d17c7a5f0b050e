// Balls crowded into a small part of a large space: the pair search's bins follow the balls (as
// fine as the reach where they are, only the bins that hold a ball kept), its pairs are every
// backend's, and GEN fills a range in a corner of a large periodic cell.
#include <catch2/catch.hpp>

#include <cmath>
#include <random>

#include <fmt/format.h>

#include "backends/bin_index.hpp"
#include "interp_support.hpp"

using namespace trubal;
using namespace trubal::test;

namespace {

// A simple cubic block of 14^3 balls of radius 0.01, 0.019 apart (overlap 0.001, jittered by up to
// 2e-4 so that no distance ties), centred on `centre`; where the space is periodic the coordinates
// are wrapped into [0, 10), so the block straddles the corner and its contacts cross every face.
std::string block(double centre, bool wrap) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> jitter(-1e-4, 1e-4);
  std::string deck;
  int id = 0;
  for (int i = 0; i < 14; ++i)
    for (int j = 0; j < 14; ++j)
      for (int k = 0; k < 14; ++k) {
        double p[3] = {centre + 0.019 * (i - 6.5), centre + 0.019 * (j - 6.5), centre + 0.019 * (k - 6.5)};
        for (double& v : p) {
          v += jitter(rng);
          if (wrap) v -= 10 * std::floor(v / 10);
        }
        deck += fmt::format("ball {:.17g} {:.17g} {:.17g} 0.01 id {}\n", p[0], p[1], p[2], ++id);
      }
  return deck;
}

// The `name: value` line of PRINT info's output.
std::string info_line(const std::string& info, const std::string& name) {
  const auto at = info.find(name + ": ");
  if (at == std::string::npos) return "";
  return info.substr(at + name.size() + 2, info.find('\n', at) - at - name.size() - 2);
}

struct Run { std::string contacts, info; };

Run run(const std::string& setup, const std::string& backend) {
  TempDir dir;
  WorkingDir cd(dir.path());
  Harness h;
  const bool ok = h.deck(setup + "backend " + backend + "\ncycle 5\nprint contacts file c.csv\n");
  INFO(h.err.str());
  REQUIRE(ok);
  h.out.str("");
  REQUIRE(h.line("print info"));
  return {slurp(dir.path() / "c.csv"), h.out.str()};
}

}  // namespace

TEST_CASE("clustered: balls in a corner of a 10 m periodic cell meet bins as fine as their reach, and the same "
          "contacts on every backend", "[backends][clustered][threads]") {
  const std::string setup = "start 10 10 10\nprop kn 1e5 ks 1e5 mu 0.5 dens 2650\n" + block(0, true);
  const Run serial = run(setup, "serial");
  // 2744 balls: at most about two bins a ball would be 5515 bins, 17 a side, 0.59 m across, some 400
  // balls in each. The reach (two radii and the skin) is under 0.03 m: over 300 bins a side.
  const std::string boxes = info_line(serial.info, "contact boxes");
  INFO(boxes);
  int nx = 0, ny = 0, nz = 0;
  REQUIRE(std::sscanf(boxes.c_str(), "%d x %d x %d", &nx, &ny, &nz) == 3);
  CHECK(nx > 300);
  CHECK(ny == nx);
  CHECK(nz == nx);
  // Each ball touches its lattice neighbours: 13 x 14 x 14 contacts along each axis, those across
  // the cell's faces among them.
  const auto rows = lines_of(serial.contacts);
  CHECK(rows.size() == 1 + 3 * 13 * 14 * 14);
  for (const char* backend : {"threaded threads 2", "threaded threads 3", "allpairs"}) {
    INFO(backend);
    CHECK(run(setup, backend).contacts == serial.contacts);
  }
}

TEST_CASE("clustered: balls at one end of a large box, and one far ball, meet boxes as fine as their reach",
          "[backends][clustered][threads]") {
  const std::string setup = "start box -1 1000 -1 1000 -1 1000\nprop kn 1e5 ks 1e5 mu 0.5 dens 2650\n" + block(0, false) +
                            "ball 900 900 900 0.01 id 9999\n";
  const Run serial = run(setup, "serial");
  // Boxes sized for the ball count over the extent would be 900 / 14 = 64 m across.
  const std::string size = info_line(serial.info, "box size");
  INFO(size);
  REQUIRE(!size.empty());
  CHECK(std::stod(size) < 0.05);
  CHECK(lines_of(serial.contacts).size() == 1 + 3 * 13 * 14 * 14);
  for (const char* backend : {"threaded threads 2", "allpairs"}) {
    INFO(backend);
    CHECK(run(setup, backend).contacts == serial.contacts);
  }
}

TEST_CASE("clustered: the bin index gives the same runs of balls kept whole or sparse", "[backends][clustered]") {
  // Keys of 5000 balls among 64^3 bins, crowded into a few rows: read as a table of every bin
  // (bins = 64^3 > 2n + 27 makes it sparse; the same keys under a count of bins <= 2n + 27 are not
  // possible, so the dense reference is a count per bin made here).
  std::mt19937_64 rng(3);
  std::vector<std::uint64_t> key(5000);
  for (auto& k : key) k = (rng() % 6) * 4096 + (rng() % 5) * 64 + rng() % 64;
  BinIndex sparse;
  sparse.build(key, 64 * 64 * 64);
  CHECK(sparse.sparse());
  std::vector<std::vector<std::uint32_t>> by_bin(64 * 64 * 64);
  for (std::uint32_t k = 0; k < key.size(); ++k) by_bin[key[k]].push_back(k);
  for (std::uint64_t row = 0; row < 64 * 64; row += 7)
    for (std::uint64_t x = 0; x + 2 < 64; x += 5) {
      std::vector<std::uint32_t> want;
      for (std::uint64_t q = row * 64 + x; q <= row * 64 + x + 2; ++q) want.insert(want.end(), by_bin[q].begin(), by_bin[q].end());
      const auto [b, e] = sparse.run(row * 64 + x, row * 64 + x + 2);
      const std::vector<std::uint32_t> got(sparse.order().begin() + b, sparse.order().begin() + e);
      CHECK(got == want);
    }
  BinIndex dense;   // few bins: every one has its slot
  std::vector<std::uint64_t> small(key.size());
  for (std::size_t k = 0; k < key.size(); ++k) small[k] = key[k] % 4096;
  dense.build(small, 4096);
  CHECK_FALSE(dense.sparse());
  const auto [b, e] = dense.run(64, 66);
  std::size_t count = 0;
  for (auto k : small) count += k >= 64 && k <= 66;
  CHECK(e - b == count);
}

TEST_CASE("clustered: GEN fills a range in a corner of a large periodic cell", "[gen][clustered]") {
  // The range is 1/15,625 of the cell: most places drawn miss it, which is no sign of a full range.
  Harness h;
  REQUIRE(h.deck("start 10 10 10\nprop kn 1e5 dens 2650\ngen 1500 0.006 0.009 seed 5 range x 0.3 0.7 y 0 0.4 z 0 0.4\n"));
  INFO(h.err.str());
  CHECK_THAT(h.out.str(), Catch::Contains("1500 balls generated"));
  CHECK(h.session.model().balls.size() == 1500);
  // A range that no new ball can be in stops at once, saying why, not that the space is full.
  Harness none;
  REQUIRE(none.deck("start 10 10 10\nprop kn 1e5 dens 2650\ngen 10 0.006 0.009 range id 5 6\n"));
  CHECK_THAT(none.err.str(), Catch::Contains("GEN placed only 0 of 10 balls: the places drawn stopped falling in the range"));
}
