// Rowe's triaxial test, piece by piece: LATTICE layers even|odd cuts both octagons, MEMBRANE puts
// p times each side's area on each side of the octagon, HIST ratio and axial follow their
// definitions (R = F1 / (A sigma2), eps1 = 2 delta / dh).
#include <catch2/catch.hpp>

#include <cmath>
#include <map>

#include "interp_support.hpp"
#include "physics/measure.hpp"

using namespace trubal;
using namespace trubal::test;

namespace {

const double kD = 40, kP = 5e4;
const double kLayer = kD / std::sqrt(2.0);

// Rowe's 1672 balls: 13 large layers of 76 (10 x 10, 3-2-1 cut), 12 small of 57 (9 x 9, 3-2-1 cut).
const char* kRowe1672 =
    "start box -200 560 -200 560 -100 800\n"
    "prop kn 1.5e9 ks 1.5e9 fric 7 dens 2000\n"
    "lattice fcc 40 10 10 25 layers even range octagon 180 180 180 184\n"
    "lattice fcc 40 10 10 25 layers odd range octagon 180 180 180 156\n";
// Cundall's 403: 7 large layers of 37 (7 x 7, 2-1 cut), 6 small of 24 (6 x 6, 2-1 cut).
const char* kRowe403 =
    "start box -200 440 -200 440 -100 450\n"
    "prop kn 1.5e9 ks 1.5e9 fric 7 dens 2000\n"
    "lattice fcc 40 7 7 13 layers even range octagon 120 120 120 127\n"
    "lattice fcc 40 7 7 13 layers odd range octagon 120 120 120 99\n";

std::map<long, int> balls_per_layer(const Model& m) {
  std::map<long, int> count;
  for (double z : m.balls.z) ++count[std::lround(z / kLayer)];
  return count;
}

}  // namespace

TEST_CASE("rowe: LATTICE layers even|odd gives each layer kind its own octagon", "[commands][rowe]") {
  Harness h;
  REQUIRE(h.deck(kRowe1672));
  CHECK(h.session.model().balls.size() == 1672);
  auto layers = balls_per_layer(h.session.model());
  REQUIRE(layers.size() == 25);
  for (auto [k, n] : layers) CHECK(n == (k % 2 == 0 ? 76 : 57));
  Harness small;
  REQUIRE(small.deck(kRowe403));
  CHECK(small.session.model().balls.size() == 403);
  for (auto [k, n] : balls_per_layer(small.session.model())) CHECK(n == (k % 2 == 0 ? 37 : 24));
  // `layers all` is the default; a bad word is an error that names the choices.
  Harness all;
  REQUIRE(all.deck("start box -1000 1000 -1000 1000 -1000 1000\nlattice fcc 40 4 4 3 layers all\n"));
  CHECK(all.session.model().balls.size() == 16 + 9 + 16);
  CHECK_FALSE(all.deck("lattice fcc 40 4 4 3 layers some\n"));
  CHECK(all.err.str().find("even") != std::string::npos);
}

TEST_CASE("rowe: MEMBRANE puts p times the side's area on each side of the octagon", "[commands][rowe]") {
  Harness h;
  REQUIRE(h.deck(std::string(kRowe1672) + "membrane 5e4\n"));
  const Model& m = h.session.model();
  CHECK(m.membrane.pressure == kP);
  CHECK(m.membrane.area == Approx(76 * kD * kD).epsilon(1e-12));   // the union of the large layer's cells
  const Balls& b = m.balls;
  const double c = 180;   // the octagon's centre
  std::map<long, std::vector<std::size_t>> loaded;   // layer -> loaded balls
  for (std::size_t i = 0; i < b.size(); ++i)
    if (b.ax[i] != 0 || b.ay[i] != 0) {
      loaded[std::lround(b.z[i] / kLayer)].push_back(i);
      CHECK((b.fixed[i] & kSpin) == kSpin);   // the membrane fixes its balls' spins
      CHECK((b.fixed[i] & kVel) == 0);
    }
  REQUIRE(loaded.size() == 13);
  for (const auto& [k, balls] : loaded) {
    INFO("layer " << k);
    CHECK(k % 2 == 0);              // only the large layers
    CHECK(balls.size() == 24);      // the perimeter of the 76
    // Tributary height: half-way to the large layers above and below (the platen layers: half that).
    const double h_trib = (k == 0 || k == 24) ? kLayer : 2 * kLayer;
    const double face = kP * kD * h_trib;
    double sum_x = 0, sum_y = 0, straight = 0, diag_x = 0, diag_y = 0, projected = 0;
    for (auto i : balls) {
      const double dx = b.x[i] - c, dy = b.y[i] - c;
      sum_x += b.ax[i];
      sum_y += b.ay[i];
      projected += std::abs(b.ax[i]);
      if (std::abs(dx - 4.5 * kD) < 1) straight += b.ax[i];   // the straight side x = +4.5 d: 4 balls
      if (dx > 0 && dy > 0) diag_x += b.ax[i], diag_y += b.ay[i];
      // Every force is horizontal, inward, and either normal to a straight side or at 45 degrees.
      CHECK(b.ax[i] * dx <= 0);
      CHECK(b.ay[i] * dy <= 0);
      CHECK(b.az[i] == 0);
    }
    CHECK(std::abs(sum_x) < 1e-6 * face);
    CHECK(std::abs(sum_y) < 1e-6 * face);
    CHECK(straight == Approx(-kP * 4 * kD * h_trib));    // p x (4 d x h)
    CHECK(projected == Approx(kP * 2 * 10 * kD * h_trib));   // both x sides: p x 10 d x h each
    // The quadrant holds half of each straight side next to it and the whole diagonal side:
    // what is left is p x (3 sqrt(2) d x h), normal to the diagonal.
    const double fx = diag_x + kP * 2 * kD * h_trib, fy = diag_y + kP * 2 * kD * h_trib;
    CHECK(fx == Approx(fy));
    CHECK(std::hypot(fx, fy) == Approx(kP * 3 * std::sqrt(2.0) * kD * h_trib));
  }
  // The heights add up to the distance between the end layers: the membrane's total lateral
  // load on the +x half is p x 10 d x dh.
  double total = 0;
  for (std::size_t i = 0; i < b.size(); ++i) total += std::max(0.0, -b.ax[i]);
  CHECK(total == Approx(kP * 10 * kD * 24 * kLayer));
  // MEMBRANE 0 removes the forces.
  REQUIRE(h.deck("membrane 0\n"));
  for (std::size_t i = 0; i < b.size(); ++i) REQUIRE((b.ax[i] == 0 && b.ay[i] == 0));
  CHECK(m.membrane.area == 0);
  // Balls of two sizes have no square cells.
  Harness mixed;
  REQUIRE(mixed.deck("start box -100 100 -100 100 -100 100\nball 0 0 0 1\nball 5 0 0 2\n"));
  CHECK_FALSE(mixed.deck("membrane 5e4\n"));
  CHECK(mixed.err.str().find("one size") != std::string::npos);
}

TEST_CASE("rowe: HIST ratio and axial follow R = F1 / (A sigma2) and eps1 = 2 delta / dh", "[commands][rowe]") {
  Harness h;
  REQUIRE(h.deck(std::string(kRowe403) +
                 "group top range z 330 350\ngroup bottom range z -10 10\ngroup platens range not z 10 330\n"));
  // ratio with a platen range needs A and sigma2.
  CHECK_FALSE(h.deck("hist ratio range group platens\n"));
  CHECK(h.err.str().find("MEMBRANE") != std::string::npos);
  // Both platens must be in the range.
  REQUIRE(h.deck("membrane 5e4\n"));
  CHECK_FALSE(h.deck("hist ratio axial range group top\n"));
  REQUIRE(h.deck("fix zvel range group platens\ninit zvel -0.05 range group top\ninit zvel 0.05 range group bottom\n"
                 "damp 0.05 0.5\nhist ratio axial platen every 10 range group platens\ncycle 200\n"));
  const Model& m = h.session.model();
  const auto& t = *h.session.history().tables().front();
  REQUIRE(t.columns == std::vector<std::string>{"cycle", "time", "ratio", "axial", "platen"});
  REQUIRE(t.rows.size() == 20);
  const auto& last = t.rows.back();
  const double dh = 12 * kLayer;
  // Each platen moved 0.05 t: eps1 = 2 delta / dh.
  CHECK(last[3] == Approx(2 * 0.05 * m.time / dh).epsilon(1e-9));
  // F1: half the difference of the top and bottom reactions; A = 37 d^2.
  double top = 0, bottom = 0;
  for (std::size_t i = 0; i < m.balls.size(); ++i)
    (m.balls.z[i] > 170 ? top : bottom) += (m.balls.fixed[i] & kZVel) ? m.balls.fz[i] : 0.0;
  CHECK(last[2] == Approx(0.5 * (top - bottom) / (37 * kD * kD * kP)).epsilon(1e-12));
  CHECK(last[2] > 0.1);   // the sample is being compressed
  CHECK(last[4] == Approx(top + bottom).margin(1e-6 * std::abs(top)));   // platen: the z reaction
  // `area` and `pressure` override the membrane's.
  REQUIRE(h.deck("hist ratio area 1 pressure 1 range group platens\ncycle 10\n"));
  const auto& t2 = *h.session.history().tables().back();
  CHECK(t2.rows.back()[2] == Approx(0.5 * (top - bottom)).epsilon(0.2));
}

TEST_CASE("rowe: SAVE and RESTART keep the membrane, so HIST ratio still has its A and sigma2", "[commands][rowe]") {
  TempDir dir;
  WorkingDir here(dir.path());
  Harness h;
  REQUIRE(h.deck(std::string(kRowe1672) + "membrane 5e4\nsave m.sav\n"));
  Harness r;
  REQUIRE(r.deck("restart m.sav\n"));
  CHECK(r.session.model().membrane.pressure == h.session.model().membrane.pressure);
  CHECK(r.session.model().membrane.area == h.session.model().membrane.area);
  CHECK(r.session.model().balls.ax == h.session.model().balls.ax);   // the membrane's forces themselves
}

TEST_CASE("rowe: MEMBRANE follow starts from the fixed loads and keeps p on the bulging sample", "[commands][rowe]") {
  // The consolidation and loading of examples/rowe403.dat, to 10% axial strain, with the membrane
  // fixed and following the sample (every 10 cycles).
  auto run = [](const std::string& membrane) {
    auto h = std::make_unique<Harness>();
    REQUIRE(h->deck(std::string(kRowe403) + membrane +
                    "group top range z 330 350\ngroup bottom range z -10 10\ngroup platens range not z 10 330\n"
                    "damp 0.05 0.5\napply zforce -8e7 range group top\napply zforce 8e7 range group bottom\n"));
    return h;
  };
  auto fixed = run("membrane 5e4\n");
  auto follow = run("membrane 5e4 follow every 10\n");
  CHECK(follow->out.str().find("following the sample every 10 cycles") != std::string::npos);
  // The first recomputation (cycle 0) is from the positions MEMBRANE used: the same loads, to
  // rounding (the layer heights are means of equal numbers).
  REQUIRE(fixed->line("cycle 1"));
  REQUIRE(follow->line("cycle 1"));
  const Balls& a = fixed->session.model().balls;
  const Balls& b = follow->session.model().balls;
  std::size_t loaded = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (a.ax[i] == 0 && a.ay[i] == 0) continue;
    ++loaded;
    CHECK(b.ax[i] == Approx(a.ax[i]).epsilon(1e-12));
    CHECK(b.ay[i] == Approx(a.ay[i]).epsilon(1e-12));
  }
  CHECK(loaded == 112);
  const std::string loading =
      "cycle 2999\napply zforce 0 range group platens\nfix zvel range group platens\n"
      "init zvel -0.05 range group top\ninit zvel 0.05 range group bottom\n"
      "hist ratio axial sratio every 20 range group platens\ncycle 10000\n";
  REQUIRE(fixed->deck(loading));
  REQUIRE(follow->deck(loading));
  const auto& rf = fixed->session.history().tables().front()->rows.back();
  const auto& rw = follow->session.history().tables().front()->rows.back();
  REQUIRE(rf[3] == Approx(0.10).margin(0.005));
  // At 10% axial strain the sample has shortened and bulged: the following membrane's area has grown
  // with the widest layer's extent, its forces with the side areas.
  const Model& m = follow->session.model();
  CHECK(m.membrane.area > 37 * kD * kD * 1.02);
  // R = F1 / (A sigma2) with the bulged A reads lower (measured 1.25 against 1.55 with the fixed
  // membrane), while sigma1/sigma3 of the assembly is almost the same (1.57 against 1.56): the
  // confinement the sample feels is p either way.
  CHECK(rw[2] < 0.9 * rf[2]);
  CHECK(rw[4] == Approx(rf[4]).epsilon(0.03));
}
