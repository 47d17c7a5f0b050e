// The balls' order in memory (Model::order, SET sort): the run puts them in space order at cycles
// fixed by the model's own counter and after balls were added; ids never change, output stays by
// id, and a sort changes a step's results by rounding alone.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <map>
#include <string>

#include "interp_support.hpp"
#include "model/edit.hpp"
#include "physics/measure.hpp"
#include "scene_decks.hpp"

using namespace trubal;
using namespace trubal::test;

namespace {

// How far apart in memory the balls of a touching pair lie: the median of |i - j|.
double memory_gap(const Model& m) {
  std::vector<double> gap;
  for (std::size_t p = 0; p < m.contacts.size(); ++p)
    if (m.contacts.touching(p)) gap.push_back(std::abs(double(m.contacts.j[p]) - double(m.contacts.i[p])));
  std::nth_element(gap.begin(), gap.begin() + gap.size() / 2, gap.end());
  return gap[gap.size() / 2];
}

// Each ball's state by id.
struct ById {
  std::map<std::int64_t, std::array<double, 9>> state;   // x y z vx vy vz fx fy fz
};
ById by_id(const Model& m) {
  ById out;
  const Balls& b = m.balls;
  for (std::size_t k = 0; k < b.size(); ++k)
    out.state[b.id[k]] = {b.x[k], b.y[k], b.z[k], b.vx[k], b.vy[k], b.vz[k], b.fx[k], b.fy[k], b.fz[k]};
  return out;
}

}  // namespace

TEST_CASE("order: the run puts the balls in space order, the ids unchanged, and a sort changes a step by rounding alone",
          "[order]") {
  // A packing whose balls lie in memory at random places (the BALL lines in scrambled id order,
  // never sorted), settled onto a floor wall with friction, across periodic faces; then the same
  // state stepped on twice: as it is, and sorted at every step.
  const std::string setup = scrambled_in_memory_deck() + "cycle 300\n";
  Harness h;
  REQUIRE(h.deck(setup));
  const Model& m = h.session.model();
  REQUIRE(contact_count(m) > 500);
  REQUIRE(m.wall_contacts.size() > 30);
  const std::vector<std::int64_t> ids_before = [&] { auto v = m.balls.id; std::sort(v.begin(), v.end()); return v; }();

  Harness kept, sorted;
  REQUIRE(kept.deck(setup + "cycle 5\n"));
  REQUIRE(sorted.deck(setup + "set sort 1\ncycle 5\n"));
  const Model& a = kept.session.model();
  const Model& b = sorted.session.model();
  // In space order the balls a ball touches lie nearer it in memory than at random.
  INFO("touching pairs' median distance in memory: " << memory_gap(a) << " kept, " << memory_gap(b) << " sorted");
  CHECK(memory_gap(b) < 0.5 * memory_gap(a));
  CHECK(b.balls.ids_indexed());
  std::vector<std::int64_t> ids_after = b.balls.id;
  std::sort(ids_after.begin(), ids_after.end());
  CHECK(ids_after == ids_before);   // the same ids, each on its own ball
  // The same step but for the order of each ball's sums: positions to the last bits, forces to a
  // few units in the last place of the largest contact force they sum (the net force of a ball in
  // a dense packing is far smaller than its contacts' forces, so relative to the net it is more).
  double largest_contact = 0;
  for (double f : b.contacts.fn) largest_contact = std::max(largest_contact, std::abs(f));
  REQUIRE(largest_contact > 0);
  const ById sa = by_id(a), sb = by_id(b);
  double worst_x = 0, worst_f = 0;
  for (const auto& [id, s] : sa.state) {
    const auto& t = sb.state.at(id);
    for (int d = 0; d < 3; ++d) worst_x = std::max(worst_x, std::abs(s[d] - t[d]));
    for (int d = 6; d < 9; ++d) worst_f = std::max(worst_f, std::abs(s[d] - t[d]));
  }
  CHECK(worst_x < 1e-15 * 400);   // the box is 400 across: a few ulps
  CHECK(worst_f < 1e-12 * largest_contact);
  CHECK(worst_f > 0);   // (the sums' order did change)
}

TEST_CASE("order: balls added go last and are sorted at the next step, and SET sort 0 keeps the order made", "[order]") {
  Harness h;
  REQUIRE(h.deck("start 1 1 1\nprop kn 1e4 dens 1000\nball 0.9 0.9 0.9 0.05 id 7\nball 0.1 0.1 0.1 0.05 id 3\n"
                 "ball 0.5 0.5 0.5 0.05\n"));
  const Balls& b = h.session.model().balls;
  CHECK(b.id == std::vector<std::int64_t>{7, 3, 8});   // in the order made; the next free id is 8
  CHECK(h.session.model().order.pending);
  CHECK(find_ball(h.session.model(), 3) == 1);
  CHECK_FALSE(h.deck("ball 0.3 0.3 0.3 0.05 id 3\n"));   // taken, whatever its place
  REQUIRE(h.deck("cycle 1\n"));
  CHECK(b.id == std::vector<std::int64_t>{3, 8, 7});   // space order: (0.1..), (0.5..), (0.9..)
  CHECK_FALSE(h.session.model().order.pending);
  CHECK(find_ball(h.session.model(), 7) == 2);
  // PRINT balls lists them by id whatever their place.
  h.out.str("");
  REQUIRE(h.deck("print balls\n"));
  const std::string out = h.out.str();
  CHECK(out.find("\n       3 ") < out.find("\n       7 "));
  CHECK(out.find("\n       7 ") < out.find("\n       8 "));
  // SET sort 0: new balls stay last.
  REQUIRE(h.deck("set sort 0\nball 0.05 0.05 0.05 0.02 id 1\ncycle 1\n"));
  CHECK(b.id == std::vector<std::int64_t>{3, 8, 7, 1});
  Harness bad;
  CHECK_FALSE(bad.deck("set sort -1\n", "s.dat"));
  CHECK_THAT(bad.first_error_line(), Catch::Contains("s.dat:1: error:"));
}

TEST_CASE("order: a sort falls on the same cycles however the run is cut, and SAVE keeps the order", "[order]") {
  // Sorted every 7 cycles: CYCLE 20 against 3 + 4 + 13 and against a SAVE and RESTART at 10,
  // whose next sort (at 14) comes from the saved interval.
  const std::string setup = std::string(kServoShearDeck).insert(std::string(kServoShearDeck).find('\n') + 1, "set sort 7\n");
  TempDir dir;
  WorkingDir cd(dir.path());
  Harness whole, cut, saved, restarted;
  REQUIRE(whole.deck(setup + "cycle 20\n"));
  REQUIRE(cut.deck(setup + "cycle 3\ncycle 4\ncycle 13\n"));
  REQUIRE(saved.deck(setup + "cycle 10\nsave s.sav\n"));
  REQUIRE(restarted.deck("restart s.sav\ncycle 10\n"));
  for (const Harness* h : {&cut, &restarted}) {
    const Balls& a = whole.session.model().balls;
    const Balls& b = h->session.model().balls;
    CHECK(b.id == a.id);   // the same order in memory
    CHECK(b.x == a.x);
    CHECK(b.vx == a.vx);
    CHECK(b.fz == a.fz);
  }
  CHECK(restarted.session.model().order.every == 7);
}

TEST_CASE("order: a run cut on a cycle of the sort, with balls across a shrinking cell's faces, keeps the unbroken run's bits", "[order]") {
  // A CYCLE that deferred its last step's results, ending on a cycle of the sort: the next CYCLE's
  // first step sorts. Where the next CYCLE prepared its list first, the balls a shrinking cell had
  // left outside its faces were wrapped before that sort, whose order (so the sums') differed from
  // the unbroken run's: the last bits parted.
  // (The default sort, every 1000 cycles: cut there, the last bits parted by cycle 1500.)
  const std::string setup = "start 0.007 0.007 0.007\nprop kn 1e5 ks 1e5 fric 26.57 dens 2650\n"
                            "gen 500 0.0003 0.0005 seed 5\ndamp local 0.7\nstrain xx 100 yy 100 zz 150\n";
  const std::string cuts = "cycle 1000\ncycle 500\n";
  TempDir dir;
  WorkingDir cd(dir.path());
  Harness whole, cut;
  REQUIRE(whole.deck(setup + "cycle 1500\n"));
  REQUIRE(cut.deck(setup + cuts));
  const Balls& a = whole.session.model().balls;
  const Balls& b = cut.session.model().balls;
  CHECK(b.id == a.id);   // the same order in memory
  CHECK(b.x == a.x);
  CHECK(b.vx == a.vx);
  CHECK(b.fz == a.fz);
}
