// The bonded examples do what doc/physics.md "Parallel bonds" says they do: examples/bonded_ucs.dat
// (unconfined compression: a peak, then the cracks) and examples/brazilian.dat (a disc split across
// its loaded diameter).
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>

#include "interp_support.hpp"
#include "io/history.hpp"
#include "paths.hpp"
#include "physics/bond.hpp"

using namespace trubal;
using namespace trubal::test;
namespace fs = std::filesystem;

namespace {

// The example's deck without its figures and dumps, run in a scratch folder; its history table.
struct ExampleRun {
  std::unique_ptr<HistoryTable> table;
  BondCounts bonds;
  std::size_t made = 0;
  double column(std::size_t row, const char* name) const {
    const auto at = std::find(table->columns.begin(), table->columns.end(), name) - table->columns.begin();
    return table->rows[row][static_cast<std::size_t>(at)];
  }
};
ExampleRun run_example(const char* deck_name, const char* csv) {
  std::string deck = slurp(fs::path(TRUBAL_SOURCE_DIR) / "examples" / deck_name);
  REQUIRE_FALSE(deck.empty());
  deck = deck.substr(0, deck.find("\ndump "));
  TempDir dir;
  WorkingDir here(dir.path());
  Harness h;
  REQUIRE(h.deck(deck));
  ExampleRun r;
  r.table = read_history_csv((dir.path() / csv).string());
  REQUIRE(r.table);
  REQUIRE(r.table->rows.size() > 50);
  r.bonds = count_bonds(h.session.model().bonds);
  r.made = h.session.model().bonds.size();
  return r;
}

}  // namespace

TEST_CASE("bond: examples/bonded_ucs.dat peaks and fails with cracks, most in tension", "[bond][example]") {
  const ExampleRun r = run_example("bonded_ucs.dat", "bonded_ucs.csv");
  std::size_t peak = 0;
  for (std::size_t k = 0; k < r.table->rows.size(); ++k)
    if (r.column(k, "w2_stress") > r.column(peak, "w2_stress")) peak = k;
  const double strength = r.column(peak, "w2_stress"), at = r.column(peak, "time");   // time: the axial strain
  const double end = r.column(r.table->rows.size() - 1, "w2_stress");
  INFO("peak " << strength << " Pa at strain " << at << ", " << end << " Pa at the end; " << r.bonds.tension
               << " broken in tension, " << r.bonds.shear << " in shear");
  // The doc's numbers (1.49 MPa at 0.47%, a twentieth of it left) within a quarter: a guard of what the
  // example shows, not a closed form; the bits are the cut matrix's business.
  CHECK(strength == Approx(1.49e6).epsilon(0.25));
  CHECK(at == Approx(0.0047).epsilon(0.25));
  CHECK(end < 0.1 * strength);
  CHECK(r.bonds.broken() > r.made / 3);
  CHECK(r.bonds.tension > 10 * r.bonds.shear);
  CHECK(r.column(peak, "bonds_broken") < 0.3 * static_cast<double>(r.bonds.broken()));   // most cracks after the peak
}

TEST_CASE("bond: examples/brazilian.dat splits the disc, its stress peaking and falling to nothing", "[long][bond][example]") {
  const ExampleRun r = run_example("brazilian.dat", "brazilian.csv");
  double strength = 0;
  for (std::size_t k = 0; k < r.table->rows.size(); ++k) strength = std::max(strength, r.column(k, "w2_stress"));
  const double end = r.column(r.table->rows.size() - 1, "w2_stress");
  INFO("peak " << strength << " Pa, " << end << " Pa at the end; " << r.bonds.broken() << " broken");
  CHECK(strength == Approx(1.40e5).epsilon(0.25));   // the doc's 140 kPa, as above
  CHECK(end < 0.1 * strength);
  CHECK(r.bonds.broken() > 100);
  CHECK(r.bonds.tension > 10 * r.bonds.shear);
}
