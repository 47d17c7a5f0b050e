// RESTART checks the model a save file holds, not only its checksum: a file written by hand or by
// another program (the checksum is easy to recompute) must not load a model that cannot run.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <limits>

#include "interp_support.hpp"
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

std::uint64_t fnv1a(const std::string& data) {   // the save format's checksum (io/save.cpp)
  std::uint64_t h = 1469598103934665603ull;
  for (unsigned char c : data) h = (h ^ c) * 1099511628211ull;
  return h;
}

}  // namespace

TEST_CASE("io restart: a model that breaks an invariant is refused with what is wrong", "[io][restart]") {
  TempDir dir;
  const std::string path = (dir.path() / "m.sav").string();
  save_model(good_model(), path);
  CHECK(load_model(path).balls.size() == 2);   // the good one loads
  const std::vector<std::pair<const char*, std::function<void(Model&)>>> broken = {
      {"ball ids are not positive and ascending", [](Model& m) { m.balls.id[1] = m.balls.id[0]; }},
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
