// Mixed periodicity: START box ... x periodic y periodic makes those axes periodic and leaves z
// bounded (its box conditions, walls across it).
#include <catch2/catch.hpp>

#include <cmath>

#include "interp_support.hpp"
#include "physics/measure.hpp"

using namespace trubal;
using namespace trubal::test;

TEST_CASE("mixed periodicity: balls touch across a periodic face, never across a bounded one", "[periodic]") {
  // Two balls 2 mm from opposite x faces of a 0.1-long periodic x: 4 mm apart through the face,
  // radius 2.5 mm, so they overlap by 1 mm there. The same two across z (bounded) do not touch.
  Harness h;
  REQUIRE(h.deck("start box 0 0.1 0 0.1 0 0.1 x periodic y periodic\nprop kn 1e5 dens 1000\n"
                 "ball 0.002 0.05 0.05 0.0025 id 1\nball 0.098 0.05 0.05 0.0025 id 2\n"
                 "ball 0.05 0.05 0.002 0.0025 id 3\nball 0.05 0.05 0.098 0.0025 id 4\ncycle 1\n"));
  const Model& m = h.session.model();
  REQUIRE(contact_count(m) == 1);
  const ContactTable& c = m.contacts;
  for (std::size_t p = 0; p < c.size(); ++p) {
    if (c.state[p] == 0) continue;
    CHECK(m.balls.id[c.i[p]] == 1);
    CHECK(m.balls.id[c.j[p]] == 2);
    CHECK(c.image_x[p] == -1);            // j seen from i through the lower x face
    CHECK(c.overlap[p] == Approx(0.001).epsilon(1e-9));
    CHECK(c.nx[p] == Approx(-1.0));        // i -> j's image, which is at x = -0.002
  }
  // They push each other apart through the face: ball 1 toward +x, ball 2 toward -x.
  CHECK(m.balls.vx[trubal::test::at(m, 1)] > 0);
  CHECK(m.balls.vx[trubal::test::at(m, 2)] < 0);
}

TEST_CASE("mixed periodicity: a ball wraps across a periodic face and stops at a bounded one", "[periodic]") {
  Harness h;
  REQUIRE(h.deck("start box 0 1 0 1 0 1 z periodic\nprop kn 1e5 dens 1000\nball 0.5 0.5 0.95 0.01\n"
                 "init zvel 1 xvel 0.3\ntstep 0.01\ncycle 10\n"));
  const Model& m = h.session.model();
  CHECK(m.balls.z[0] == Approx(0.05).margin(1e-12));   // 0.95 + 0.1, wrapped into [0, 1)
  CHECK(m.balls.x[0] == Approx(0.53));
  CHECK_FALSE(h.deck("cycle 200\n"));                    // x is bounded: it leaves at x = 1
  CHECK_THAT(h.first_error_line(), Catch::Contains("left the box through x = 1"));
}

TEST_CASE("mixed periodicity: only periodic axes strain, servo and wrap, and walls go across bounded ones", "[periodic][walls]") {
  struct Case { const char* lines; const char* expected; };
  const Case cases[] = {
      {"strain zz 1\n", "STRAIN zz needs that axis periodic"},
      {"strain xz 1\n", "needs both of its axes"},
      {"servo zz 100\n", "bounded across z"},
      {"servo 100 100 100\n", "bounded across z"},
  };
  for (const Case& c : cases) {
    INFO(c.lines);
    Harness h;
    CHECK_FALSE(h.deck(std::string("start box 0 1 0 1 0 1 x periodic y periodic\nprop kn 1 dens 1\n") + c.lines));
    CHECK_THAT(h.first_error_line(), Catch::Contains(c.expected));
  }
  Harness ok;
  REQUIRE(ok.deck("start box 0 1 0 1 0 1 x periodic y periodic\nprop kn 1 dens 1\nstrain xx 0.1 xy 0.2\n"
                  "servo yy 5\nwall plane 0 0 0 0 0 1\nprint info\n"));
  CHECK_THAT(ok.out.str(), Catch::Contains("space: box, periodic in x y: 1 x 1 x 1"));
  Harness all;
  CHECK_FALSE(all.deck("start box 0 1 0 1 0 1 x periodic y periodic z periodic\n"));
  CHECK_THAT(all.first_error_line(), Catch::Contains("START x y z"));
  Harness periodic;
  CHECK_FALSE(periodic.deck("start 1 1 1\nwall plane 0 0 0 0 0 1\n"));
  CHECK_THAT(periodic.first_error_line(), Catch::Contains("walls need a free region"));
}
