// RENUMBER: the balls get ids 1..N in space order, and nothing about them changes. A renumbered
// deck steps as the same balls given in that order; a renumber mid-run keeps every ball's state and
// every contact's history (turned round where its balls change order), so the run goes on with the
// same physics; every backend gives the same bits after it.
#include <catch2/catch.hpp>
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>

#include "interp_support.hpp"
#include "scene_decks.hpp"

using namespace trubal;
using namespace trubal::test;

namespace {

using Place = std::array<double, 3>;
Place place(const Model& m, std::size_t k) { return {m.balls.x[k], m.balls.y[k], m.balls.z[k]}; }

// Index of each ball by its centre (the scene's centres are all different).
std::map<Place, std::size_t> by_place(const Model& m) {
  std::map<Place, std::size_t> out;
  for (std::size_t k = 0; k < m.balls.size(); ++k) out[place(m, k)] = k;
  return out;
}

}  // namespace

TEST_CASE("renumber: a deck renumbered before its CYCLE steps as the same balls given in that order", "[commands]") {
  TempDir dir;
  WorkingDir here(dir.path());
  const std::string scene = scrambled_settle_deck();
  const std::string run = "cycle 400\nprint balls file balls.csv\nprint contacts file contacts.csv\n";
  Harness renumbered;
  REQUIRE(renumbered.deck(scene + "renumber\n"));
  CHECK_THAT(renumbered.out.str(), Catch::Contains("384 balls renumbered 1 to 384 in space order (cells 40 wide)"));
  // The same balls written out in the new order, ids 1..N.
  const Model& m = renumbered.session.model();
  std::string in_order = scene.substr(0, scene.find("ball "));
  for (std::size_t k = 0; k < m.balls.size(); ++k) {
    REQUIRE(m.balls.id[k] == static_cast<std::int64_t>(k) + 1);
    in_order += fmt::format("ball {} {} {} 20 id {}\n", m.balls.x[k], m.balls.y[k], m.balls.z[k], k + 1);
  }
  in_order += scene.substr(scene.find("grav"));
  // Space order: consecutive balls are near (a random order puts them 150 apart on average here).
  double gap = 0;
  for (std::size_t k = 1; k < m.balls.size(); ++k)
    gap += std::hypot(m.balls.x[k] - m.balls.x[k - 1], m.balls.y[k] - m.balls.y[k - 1], m.balls.z[k] - m.balls.z[k - 1]);
  CHECK(gap / (m.balls.size() - 1) < 70);

  REQUIRE(renumbered.deck(run));
  const std::string balls = slurp("balls.csv"), contacts = slurp("contacts.csv");
  REQUIRE(lines_of(contacts).size() > 500);
  Harness given;
  REQUIRE(given.deck(in_order + run));
  CHECK(slurp("balls.csv") == balls);
  CHECK(slurp("contacts.csv") == contacts);
}

TEST_CASE("renumber: mid-run every ball keeps its state and every contact its history", "[commands]") {
  const std::string scene = scrambled_in_memory_deck() + "group top range z 150 400\ncycle 300\n";
  Harness h;
  REQUIRE(h.deck(scene));
  const Model before = h.session.model();
  REQUIRE(before.groups.at("top").size() > 100);
  REQUIRE(h.line("renumber"));
  const Model& after = h.session.model();
  const auto old_index = by_place(before);
  REQUIRE(after.balls.size() == before.balls.size());
  std::vector<std::size_t> from(after.balls.size());   // old index of each new one
  for (std::size_t k = 0; k < after.balls.size(); ++k) {
    CHECK(after.balls.id[k] == static_cast<std::int64_t>(k) + 1);
    const std::size_t o = old_index.at(place(after, k));
    from[k] = o;
    CHECK(after.balls.vx[k] == before.balls.vx[o]);
    CHECK(after.balls.wz[k] == before.balls.wz[o]);
    CHECK(after.balls.fz[k] == before.balls.fz[o]);
  }
  // The group holds the same balls.
  std::vector<Place> top_before, top_after;
  for (std::size_t k = 0; k < before.balls.size(); ++k)
    if (std::binary_search(before.groups.at("top").begin(), before.groups.at("top").end(), before.balls.id[k]))
      top_before.push_back(place(before, k));
  for (auto id : after.groups.at("top")) top_after.push_back(place(after, static_cast<std::size_t>(id - 1)));
  std::sort(top_before.begin(), top_before.end());
  std::sort(top_after.begin(), top_after.end());
  CHECK(top_before == top_after);

  // Each pair of the new list is a pair of the old one, turned round where its balls changed order:
  // shear history and image of the opposite sign. The list is in order (i < j, sorted).
  const ContactTable& a = after.contacts;
  const ContactTable& b = before.contacts;
  REQUIRE(a.size() == b.size());
  std::map<std::array<long, 5>, std::size_t> old_pair;
  for (std::size_t p = 0; p < b.size(); ++p)
    old_pair[{static_cast<long>(b.i[p]), static_cast<long>(b.j[p]), b.image_x[p], b.image_y[p], b.image_z[p]}] = p;
  std::size_t turned = 0, crossing = 0, sheared = 0;
  for (std::size_t p = 0; p < a.size(); ++p) {
    REQUIRE(a.i[p] < a.j[p]);
    if (p > 0) CHECK(pair_before(a, p - 1, a, p));
    const std::size_t oi = from[a.i[p]], oj = from[a.j[p]];
    const bool turn = oi > oj;
    const std::array<long, 5> key = turn ? std::array<long, 5>{static_cast<long>(oj), static_cast<long>(oi), -a.image_x[p], -a.image_y[p], -a.image_z[p]}
                                         : std::array<long, 5>{static_cast<long>(oi), static_cast<long>(oj), a.image_x[p], a.image_y[p], a.image_z[p]};
    const auto it = old_pair.find(key);
    REQUIRE(it != old_pair.end());
    const double sign = turn ? -1 : 1;
    CHECK(a.fsx[p] == sign * b.fsx[it->second]);
    CHECK(a.fsy[p] == sign * b.fsy[it->second]);
    CHECK(a.fsz[p] == sign * b.fsz[it->second]);
    CHECK(a.fx[p] == sign * b.fx[it->second]);
    CHECK(a.tx[p] == b.tx[it->second]);
    turned += turn;
    crossing += a.image_x[p] != 0 || a.image_y[p] != 0;
    sheared += turn && a.fsx[p] != 0;
  }
  // The scene tests what it should: pairs turned round with history, pairs across the faces.
  CHECK(turned > 100);
  CHECK(sheared > 50);
  CHECK(crossing > 20);

  // The run goes on with the same physics: the same balls where the run without RENUMBER puts them,
  // to round-off (each ball now adds its contacts in another order). A history lost or of the
  // wrong sign moves them by 1e-3 and more here.
  Harness straight;
  REQUIRE(straight.deck(scene + "cycle 200\n"));
  REQUIRE(h.line("cycle 200"));
  const Model& s = straight.session.model();
  const Model& r = h.session.model();
  double worst = 0;
  for (std::size_t k = 0; k < r.balls.size(); ++k) {
    const std::size_t o = from[k];
    worst = std::max({worst, std::abs(r.balls.x[k] - s.balls.x[o]), std::abs(r.balls.y[k] - s.balls.y[o]),
                      std::abs(r.balls.z[k] - s.balls.z[o])});
  }
  INFO("largest difference in place after 200 steps: " << worst);
  CHECK(worst < 1e-8);
}

TEST_CASE("renumber: every backend gives the same bits after a renumber mid-run", "[backends][threads]") {
  auto run = [](const std::string& backend) {
    TempDir dir;
    WorkingDir cd(dir.path());
    Harness h;
    const bool ok = h.deck(scrambled_settle_deck() + "cycle 150\nrenumber\n" + backend +
                           "cycle 150\nprint balls file balls.csv\nprint contacts file contacts.csv\n");
    INFO(h.err.str());
    REQUIRE(ok);
    return slurp("balls.csv") + slurp("contacts.csv");
  };
  const std::string serial = run("");
  REQUIRE(lines_of(serial).size() > 800);
  for (const char* backend : {"backend threaded threads 2\n", "backend threaded threads 3\n", "backend allpairs threads 2\n"}) {
    INFO(backend);
    CHECK(run(backend) == serial);
  }
}

TEST_CASE("renumber: present order closes DELETE's gaps, and bad input is refused", "[commands]") {
  Harness h;
  CHECK_FALSE(h.deck("renumber\n", "r.dat"));
  CHECK_THAT(h.first_error_line(), Catch::Contains("r.dat:1: error: no model yet"));
  h.err.str("");
  REQUIRE(h.deck("start 1 1 1\nrenumber\n"));
  CHECK(h.out.str() == "new model in the periodic space 1 x 1 x 1\nno balls to renumber\n");
  h.out.str("");
  REQUIRE(h.deck(scrambled_in_memory_deck() + "delete range id 1 100\n"));
  const Model before = h.session.model();
  CHECK_FALSE(h.deck("renumber sideways\n", "r.dat"));
  CHECK_THAT(h.first_error_line(), Catch::Contains("r.dat:1: error:"));
  CHECK(h.session.model().balls.id == before.balls.id);   // nothing done
  h.out.str("");
  REQUIRE(h.line("renumber present"));
  CHECK(h.out.str() == "284 balls renumbered 1 to 284 in their present order\n");
  const Model& after = h.session.model();
  REQUIRE(after.balls.size() == 284);
  for (std::size_t k = 0; k < after.balls.size(); ++k) {
    CHECK(after.balls.id[k] == static_cast<std::int64_t>(k) + 1);
    CHECK(after.balls.x[k] == before.balls.x[k]);
  }
}

TEST_CASE("renumber: PRINT info says how far apart neighbours in memory lie, and suggests SET sort", "[commands]") {
  // The scrambled scene's neighbours in memory are a random pair of its 384 places (the grid's edge
  // is 8 diameters: about 4 apart at the median); in space order, about one apart.
  Harness h;
  REQUIRE(h.deck(scrambled_in_memory_deck() + "print info\n"));
  const auto gap = [](const std::string& out) {
    const std::string label = "ball order: neighbours in memory ";
    const auto at = out.find(label);
    REQUIRE(at != std::string::npos);
    return std::stod(out.substr(at + label.size()));
  };
  const std::string before = h.out.str();
  CHECK(gap(before) > 3);
  CHECK_THAT(before, Catch::Contains("never (SET sort 0): the contact loop reads memory slowly; SET sort 1000 puts them in space order"));
  h.out.str("");
  REQUIRE(h.deck("set sort 1000\ncycle 1\nprint info\n"));
  const std::string after = h.out.str();
  CHECK(gap(after) < 1.6);
  CHECK_THAT(after, Catch::Contains("put in space order every 1000 cycles\n"));
  // Balls added are put in order at the next step.
  h.out.str("");
  REQUIRE(h.deck("ball 100 100 300 20\nprint info\n"));
  CHECK_THAT(h.out.str(), Catch::Contains("put in space order at the next step, then every 1000 cycles\n"));
}
