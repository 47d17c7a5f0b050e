// A save read a piece at a time (SavedTables, io/save.hpp), as a distributed RESTART reads it to
// hand each rank its part: the same model as load_model's, the same checks and messages, and the
// cases where the file is read whole instead.
#include <catch2/catch.hpp>

#include <cstring>
#include <fstream>
#include <functional>
#include <limits>
#include <type_traits>

#include "interp_support.hpp"
#include "io_support.hpp"
#include "io/save.hpp"

using namespace trubal;
using namespace trubal::test;

namespace {

// A periodic cell of balls squeezed with rolling resistance and capillary bridges (pairs with every
// history part), then a box of balls pressed against walls (wall contacts with history), each saved.
const char* const kCell =
    "start 0.006 0.006 0.006\nprop kn 1e5 ks 1e5 fric 26.57 dens 2650 rr_fric 0.1\nprop bridge 1e-12 tension 0.072\n"
    "gen porosity 0.4 0.0004 0.0006 seed 3\ndamp local 0.7\nstrain 20 20 20\ncycle 300\nsave cell.sav\n";
const char* const kWalls =
    "start box -1 7 -1 7 -1 12\nprop kn 1e6 ks 1e6 fric 30 dens 1000\nlattice fcc 1 6 6 10 origin 0.5 0.5 0.5\n"
    "wall id 1 plane 0 0 0 0 0 1\nwall id 2 plane 0 0 7.2 0 0 -1 velocity 0 0 -0.1\nwall id 3 plane 0 0 0 1 0 0\n"
    "wall id 4 plane 6 0 0 -1 0 0\nwall id 5 plane 0 0 0 0 1 0\nwall id 6 plane 0 6 0 0 -1 0\ngrav 0 0 -9.81\n"
    "damp local 0.5\ncycle 800\nsave walls.sav\n";

// Every array of `table` in the pieces' order read back from `saved`, `piece` rows at a time,
// against the loaded model's (a history part the table does not keep: none of it).
template <class Table>
void check_pieces(SavedTables& saved, PieceTable which, Table& loaded, std::uint64_t piece) {
  const std::uint64_t rows = saved.rows(which);
  each_piece_array(loaded, [&](auto& v, std::size_t k, bool used) {
    if (!used) return;
    INFO("array " << k);
    using T = typename std::decay_t<decltype(v)>::value_type;
    REQUIRE(v.size() == rows);
    std::vector<T> back(rows);
    for (std::uint64_t from = 0; from < rows; from += piece) {
      const std::uint64_t n = std::min(piece, rows - from);
      saved.read(which, k, from, n, back.data() + from, sizeof(T));
    }
    if (rows > 0) CHECK(std::memcmp(back.data(), v.data(), rows * sizeof(T)) == 0);   // (none: no array to compare)
  });
}

}  // namespace

TEST_CASE("io saved tables: read a piece at a time, a save gives load_model's model", "[io][restart]") {
  TempDir dir;
  WorkingDir cd(dir.path());
  Harness h;
  REQUIRE(h.deck(std::string(kCell) + kWalls));
  for (const char* file : {"cell.sav", "walls.sav"}) {
    INFO(file);
    Model loaded = load_model(file);
    REQUIRE(loaded.contacts.size() > 100);
    History histories;
    SavedTables saved(file, &histories);
    CHECK(saved.why_whole().empty());
    saved.check(7);   // (pieces of 7 rows: the pairs' order checked across them)
    CHECK(saved.rows(PieceTable::Balls) == loaded.balls.size());
    CHECK(saved.rows(PieceTable::Pairs) == loaded.contacts.size());
    CHECK(saved.rows(PieceTable::Walls) == loaded.wall_contacts.size());
    for (std::uint64_t piece : {std::uint64_t{1}, std::uint64_t{13}, std::uint64_t{1} << 16}) {
      check_pieces(saved, PieceTable::Balls, loaded.balls, piece);
      check_pieces(saved, PieceTable::Pairs, loaded.contacts, piece);
      check_pieces(saved, PieceTable::Walls, loaded.wall_contacts, piece);
    }
    const Model light = saved.take_model();
    // The light model: the balls' ids, types, fixities, radii and centres alone; the rest load_model's.
    const Balls &b = light.balls, &l = loaded.balls;
    CHECK(b.id == l.id);
    CHECK(b.type == l.type);
    CHECK(b.fixed == l.fixed);
    CHECK(b.rad == l.rad);
    CHECK(b.x == l.x);
    CHECK(b.z == l.z);
    CHECK(b.vx.empty());
    CHECK(b.mass.empty());
    CHECK(light.contacts.size() == 0);
    CHECK(light.wall_contacts.size() == 0);
    CHECK(light.contacts.history_laws == loaded.contacts.history_laws);
    CHECK(light.contacts.results_cycle == loaded.contacts.results_cycle);
    CHECK(light.cycle == loaded.cycle);
    CHECK(light.walls.size() == loaded.walls.size());
    CHECK(light.energy.friction_work == loaded.energy.friction_work);
  }
  CHECK(load_model("cell.sav").contacts.history_laws == HistoryLaws{true, true});
  CHECK(load_model("walls.sav").wall_contacts.size() > 10);
}

TEST_CASE("io saved tables: what load_model refuses is refused, with its message", "[io][restart]") {
  TempDir dir;
  WorkingDir cd(dir.path());
  Harness h;
  REQUIRE(h.deck(kWalls));
  const Model good = h.session.model();
  REQUIRE(good.wall_contacts.size() > 10);
  // (The pairs a save keeps: touching, or with history.)
  std::vector<std::size_t> kept;
  for (std::size_t p = 0; p < good.contacts.size(); ++p)
    if (good.contacts.touching(p) || good.contacts.has_history(p)) kept.push_back(p);
  REQUIRE(kept.size() > 100);
  const std::size_t last = kept.back(), before = kept[kept.size() - 40], other = kept[kept.size() - 2];
  const std::vector<std::pair<const char*, std::function<void(Model&)>>> broken = {
      {"is given to two balls", [](Model& m) { m.balls.id[5] = m.balls.id[0]; }},
      {"has radius -0.5", [](Model& m) { m.balls.rad[9] = -0.5; }},
      {"a position or velocity that is not a number", [](Model& m) { m.balls.wz[150] = std::numeric_limits<double>::infinity(); }},
      {"has fixities", [](Model& m) { m.balls.fixed[3] = 200; }},
      {"is not i < j", [&](Model& m) { m.contacts.j[last] = m.contacts.i[last]; }},
      {"the contacts are not sorted", [&](Model& m) { std::swap(m.contacts.i[last], m.contacts.i[before]);
                                               std::swap(m.contacts.j[last], m.contacts.j[before]); }},
      {"has state 3", [&](Model& m) { m.contacts.state[other] = 3; }},
      {"FRAC is -1", [](Model& m) { m.settings.frac = -1; }},
      {"does not match the balls and walls", [](Model& m) { m.wall_contacts.ball_id[4] = 999999; }},
  };
  for (const auto& [message, spoil] : broken) {
    INFO(message);
    Model m = good;
    spoil(m);
    save_model(m, "bad.sav");
    std::string whole, pieces;
    try {
      load_model("bad.sav");
    } catch (const std::runtime_error& e) {
      whole = e.what();
    }
    try {
      SavedTables saved("bad.sav", nullptr);
      saved.check(16);
    } catch (const std::runtime_error& e) {
      pieces = e.what();
    }
    CHECK_THAT(whole, Catch::Contains(message) && Catch::Contains("not restarted"));
    CHECK(pieces == whole);
  }
  // A damaged body (a bool's byte neither 0 nor 1, the checksum made to match) and a cut file.
  save_model(good, "good.sav");
  std::string data = slurp(dir.path() / "good.sav");
  const std::size_t header = 8 + 4 + 8 + 8;
  data[header] = 7;
  const std::uint64_t sum = fnv1a(data.substr(header));
  std::memcpy(data.data() + 20, &sum, sizeof sum);
  std::ofstream(dir.path() / "damaged.sav", std::ios::binary) << data;
  CHECK_THROWS_WITH(SavedTables("damaged.sav", nullptr), Catch::Contains("is damaged"));
  std::ofstream(dir.path() / "cut.sav", std::ios::binary) << data.substr(0, data.size() / 2);
  CHECK_THROWS_WITH(SavedTables("cut.sav", nullptr), Catch::Contains("is truncated"));
}

TEST_CASE("io saved tables: a save the ranks' parts are not made from says why", "[io][restart]") {
  TempDir dir;
  WorkingDir cd(dir.path());
  Harness h;
  REQUIRE(h.deck(kWalls));
  Model m = h.session.model();
  save_model(m, "older.sav", nullptr, 11);
  CHECK(SavedTables("older.sav", nullptr).why_whole() == "saved by an older format");
  Model results = m;
  results.contacts.results_cycle = m.cycle - 1;
  save_model(results, "results.sav");
  CHECK(SavedTables("results.sav", nullptr).why_whole() == "contact results of another cycle");
  REQUIRE(h.deck("bond kn 1e9 ks 1e9 ten 1e6 coh 1e6 gap 0.01\nsave bonded.sav\n"));
  REQUIRE(!h.session.model().bonds.empty());
  CHECK(SavedTables("bonded.sav", nullptr).why_whole() == "bonds");
  REQUIRE(h.deck("start box 0 1 0 1 0 1\nsave empty.sav\n"));
  CHECK(SavedTables("empty.sav", nullptr).why_whole() == "no ball");
}
