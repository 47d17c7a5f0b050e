// RESTART checks the model a save file holds, not only its checksum: a file written by hand or by
// another program (the checksum is easy to recompute) must not load a model that cannot run.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <limits>

#include "interp_support.hpp"
#include "io_support.hpp"
#include "io/save.hpp"
#include "model/edit.hpp"

using namespace trubal;
using namespace trubal::test;

namespace {

Model good_model() {
  Model m;
  m.started = true;
  m.space.lo = {0, 0, 0};
  m.space.hi = {1, 1, 1};
  m.materials[1].kn = 1e4;
  m.materials[1].density = 1000;
  add_ball(m, 0, 1, 0.2, 0.2, 0.2, 0.1);
  add_ball(m, 0, 1, 0.6, 0.6, 0.6, 0.1);
  return m;
}

}  // namespace

TEST_CASE("io restart: a model that breaks an invariant is refused with what is wrong", "[io][restart]") {
  TempDir dir;
  const std::string path = (dir.path() / "m.sav").string();
  save_model(good_model(), path);
  CHECK(load_model(path).balls.size() == 2);   // the good one loads
  const std::vector<std::pair<const char*, std::function<void(Model&)>>> broken = {
      {"ball id 1 is given to two balls", [](Model& m) { m.balls.id[1] = m.balls.id[0]; }},
      {"ball ids are not positive", [](Model& m) { m.balls.id[1] = -3; }},
      {"ball 1 has radius -0.5", [](Model& m) { m.balls.rad[0] = -0.5; }},
      {"ball 2 has a position or velocity that is not a number",
       [](Model& m) { m.balls.y[1] = std::numeric_limits<double>::quiet_NaN(); }},
      {"the space's x bounds are [1, 0]", [](Model& m) { m.space.lo[0] = 1; m.space.hi[0] = 0; }},
      {"FRAC is -1", [](Model& m) { m.settings.frac = -1; }},
  };
  for (const auto& [message, spoil] : broken) {
    INFO(message);
    Model m = good_model();
    spoil(m);
    save_model(m, path);
    try {
      load_model(path);
      FAIL("a broken model loaded");
    } catch (const std::runtime_error& e) {
      CHECK(std::string(e.what()).find(message) != std::string::npos);
      CHECK(std::string(e.what()).find("not restarted") != std::string::npos);
    }
  }
}

TEST_CASE("io restart: a bool byte that is neither 0 nor 1 is a damaged file, not undefined behaviour", "[io][restart]") {
  TempDir dir;
  const std::string path = (dir.path() / "m.sav").string();
  save_model(good_model(), path);
  std::string data = slurp(path);
  const std::size_t header = 8 + 4 + 8 + 8;   // magic, version, size, checksum
  REQUIRE(data.size() > header);
  REQUIRE(data[header] == 0);                 // the body starts with Space::periodic (false)
  data[header] = 7;
  const std::uint64_t sum = fnv1a(data.substr(header));
  std::memcpy(data.data() + 8 + 4 + 8, &sum, sizeof sum);   // a checksum that matches
  std::ofstream(path, std::ios::binary | std::ios::trunc) << data;
  CHECK_THROWS_WITH(load_model(path), Catch::Contains("is damaged"));
}

TEST_CASE("io restart: a directory is not a save file", "[io][restart]") {
  TempDir dir;
  CHECK_THROWS_WITH(load_model(dir.str()), Catch::Contains("is a directory, not a save file"));
}

TEST_CASE("io restart: the contacts' history is saved by name, and a save of format 8 reads as well",
          "[io][restart]") {
  // A row pressed and sheared under gravity with friction walls: pairs and wall contacts with a
  // shear history.
  TempDir dir;
  WorkingDir cd(dir.path());
  const std::string scene =
      std::string(kPressedRow) + "grav 0 0 -9.81\nwall plane 0 0 -0.95 0 0 1\ninit xvel 0.2 range id 1\ninit yvel 0.3 range id 2\ncycle 3\n";
  Harness h;
  REQUIRE(h.deck(scene + "save now.sav\n"));
  const Model& m = h.session.model();
  std::size_t with_history = 0;
  for (std::size_t p = 0; p < m.contacts.size(); ++p) with_history += m.contacts.has_history(p);
  REQUIRE(with_history > 0);
  REQUIRE(std::any_of(m.wall_contacts.fsx.begin(), m.wall_contacts.fsx.end(), [](double v) { return v != 0; }));
  save_model(m, (dir.path() / "old.sav").string(), nullptr, 8);
  for (const char* file : {"now.sav", "old.sav"}) {
    INFO(file);
    const Model back = load_model((dir.path() / file).string());
    CHECK(back.contacts.i == m.contacts.i);
    m.contacts.for_each_history([&](const auto& v, const HistoryPart& part) {
      INFO(part.name);
      back.contacts.for_each_history([&](const auto& w, const HistoryPart& other) {
        if (std::string(part.name) != other.name) return;
        REQUIRE(w.size() == back.contacts.size());
        for (std::size_t p = 0, q = 0; p < m.contacts.size(); ++p)   // the kept pairs, in order
          if (m.contacts.touching(p) || m.contacts.has_history(p)) CHECK(w[q++] == v[p]);
      });
    });
    CHECK(back.wall_contacts.fsx == m.wall_contacts.fsx);
    CHECK(back.wall_contacts.fsz == m.wall_contacts.fsz);
  }
  // Format 9 names each part: one this build does not know is refused by name, not read as another.
  std::string data = slurp(dir.path() / "now.sav");
  const std::size_t header = 8 + 4 + 8 + 8;
  std::uint32_t version = 0;
  std::memcpy(&version, data.data() + 8, sizeof version);
  CHECK(version == 13);
  const std::string named = std::string("\x03\0\0\0\0\0\0\0fsy", 11);   // the length, then the name
  const auto at = data.find(named, header);
  REQUIRE(at != std::string::npos);
  data.replace(at + 8, 3, "rrx");
  const std::uint64_t sum = fnv1a(data.substr(header));
  std::memcpy(data.data() + 20, &sum, sizeof sum);
  {
    std::ofstream f(dir.path() / "later.sav", std::ios::binary);
    f << data;
  }
  CHECK_THROWS_WITH(load_model((dir.path() / "later.sav").string()),
                    Catch::Contains("holds a contact history 'rrx' that this trubal does not know"));
}
