// The history parts a contact table keeps (ContactTable::history_laws): only those of the laws a
// scene has, and a law added later continues as if its part had been kept, zero, from the start.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <string>

#include <fmt/format.h>

#include "interp_support.hpp"

using namespace trubal;
using namespace trubal::test;

namespace {

// 48 balls stacked as an FCC block on a floor under gravity, touching from the start, slumping
// (no side walls) with friction and no law with history of its own; a few rolling and spinning.
std::string heap(const std::string& backend) {
  std::string deck =
      fmt::format("backend {}\nstart box -1 1 -1 1 -1 1\nprop kn 1e4 ks 1e4 mu 0.5 dens 2650 rest 0.3\n", backend);
  int id = 1;
  for (int k = 0; k < 3; ++k)
    for (int j = 0; j < 4; ++j)
      for (int i = 0; i < 4; ++i)
        deck += fmt::format("ball {:.5f} {:.5f} {:.5f} 0.01 id {}\n", 0.02 * i + 0.01 * (k % 2), 0.02 * j + 0.01 * (k % 2),
                            0.01 + 0.01414 * k, id++);
  return deck + "wall plane 0 0 0 0 0 1\ngrav 0 0 -9.81\ninit xvel 0.02 yspin 3 range id 1 8\n";
}

std::size_t bytes(const std::vector<double>& v) { return v.capacity() * sizeof(double); }

}  // namespace

TEST_CASE("history parts: a scene without rolling or bridges keeps only the shear spring's arrays", "[history]") {
  TempDir dir;
  WorkingDir here(dir.path());
  Harness h;
  REQUIRE(h.deck(heap("serial") + "cycle 50\nsave plain.sav\n"));
  const ContactTable& c = h.session.model().contacts;
  REQUIRE(c.size() > 50);
  CHECK(c.history_count() == 3);
  CHECK(c.mrx.capacity() + c.mry.capacity() + c.mrz.capacity() + c.bridge.capacity() == 0);
  CHECK(c.history_bytes() == bytes(c.fsx) + bytes(c.fsy) + bytes(c.fsz));
  // A save of it (which names every part, zero where not kept) restarts as lean.
  Harness back;
  REQUIRE(back.deck("restart plain.sav\n"));
  const ContactTable& b = back.session.model().contacts;
  CHECK(b.size() > 0);
  CHECK(b.history_count() == 3);
  CHECK(b.mrx.capacity() + b.bridge.capacity() == 0);
  // A bridge law takes its part into use, zero for every pair found so far; the rolling part stays out.
  REQUIRE(back.deck("prop bridge 1e-12 tension 0.07\n"));
  CHECK(b.bridge.size() == b.size());
  CHECK(b.history_count() == 4);
  CHECK(b.mrx.capacity() == 0);
}

// A run that gains rolling resistance after its first CYCLE, on two threads and cut by a SAVE and
// RESTART, against one on one thread whose table kept every part (zero) from the start, as a
// table did before parts were kept by law: the same steps to the bit, so the same save bytes.
TEST_CASE("history parts: rolling added after a CYCLE continues as if its part had been kept from the start", "[history]") {
  TempDir dir;
  WorkingDir here(dir.path());
  Harness late;
  REQUIRE(late.deck(heap("threaded threads 2") + "cycle 150\nsave mid.sav\n"));
  Harness cut;
  REQUIRE(cut.deck("restart mid.sav\n"));
  CHECK(cut.session.model().contacts.mrx.capacity() == 0);
  // (PRINT contacts between the PROP and the next CYCLE: the rolling columns, zero.)
  REQUIRE(cut.deck("prop rr_fric 0.2\nprint contacts file between.csv\ncycle 150\nsave late.sav\n"));
  const ContactTable& c = cut.session.model().contacts;
  CHECK(c.mrx.size() == c.size());
  CHECK(c.history_count() == 6);
  const std::string between = slurp(dir.path() / "between.csv");
  CHECK(between.rfind("i,j,nx,ny,nz,overlap,fn,fsx,fsy,fsz,mrx,mry,mrz,sliding\n", 0) == 0);

  Harness kept;
  REQUIRE(kept.deck(heap("serial")));
  kept.session.edit().contacts.use_history(HistoryLaws{true, true});
  REQUIRE(kept.deck("cycle 150\nprop rr_fric 0.2\ncycle 150\nsave kept.sav\n"));
  CHECK(kept.session.model().contacts.history_count() == 7);
  // The rolling springs did act (else the comparison says nothing of their history).
  double most = 0;
  for (double v : c.mry) most = std::max(most, std::abs(v));
  CHECK(most > 0);
  const std::string a = slurp(dir.path() / "late.sav"), b = slurp(dir.path() / "kept.sav");
  REQUIRE(!a.empty());
  CHECK(a == b);
}
