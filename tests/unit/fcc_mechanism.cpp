// Thornton's (1979) plane-strain strength of a face-centred-cubic array, against what trubal builds
// and runs.
//
// The reference is a static computation on a rigid-plastic array (no DEM): every ball has the same
// 12 contacts; a homogeneous mechanism is a velocity gradient D = diag(ex, ey, -1) (extension
// positive) with no ball spin. A contact with normal n separates when n.Dn > 0 (no force), slides
// when n.Dn = 0 and the tangential relative velocity Dn is not zero (normal force N, friction f N
// against Dn), is stuck when Dn = 0 (its force is not determined by the mechanism), and D is not
// admissible when some n.Dn < 0 (rigid balls would overlap). By symmetry every sliding contact
// carries the same N; the stress is then proportional to sum (N n - f N Dn/|Dn|) (x) n (compression
// positive). Plane strain: ey = 0, ex the smallest value that keeps every contact from closing.
// For layers normal to z with rows along x and y this gives Thornton's closed form,
// sigma_zz/sigma_xx = 2(sqrt3 + sqrt2 f)/(sqrt3 - 2 sqrt2 f), sigma_yy/sigma_xx = sqrt3/(sqrt3 - 2 sqrt2 f).
//
// What is asserted of trubal: that LATTICE fcc builds that orientation (the branch vectors of the
// lattice it makes, fed to the computation, give the mechanism and the closed form); that a run of
// examples/fcc_plane_strain.dat peaks at the closed form with the contacts in the mechanism's state;
// and that a cube-aligned lattice, for which the computation finds no mechanism, shows no peak.
// (The computation also finds none with z along a row or along [111] with y in a close-packed plane,
// and for z = [111], x = [11-2] one in which only 4 contacts slide and the stress has shear
// components; trubal has no command that builds those orientations.)
// tests/validation/periodic_fcc_strength.cpp runs the longer, prestressed variants.
#include "paths.hpp"
#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include "fcc_lattice.hpp"
#include "interp_support.hpp"
#include "physics/measure.hpp"

using namespace trubal;
using trubal::test::Harness;

namespace {
using Vec = std::array<double, 3>;

Vec unit(Vec v) {
  const double l = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  return {v[0] / l, v[1] / l, v[2] / l};
}

// The 12 contact normals of an FCC ball, <110> in cube axes, expressed in lab axes x, y, z (given
// in cube axes, mutually orthogonal).
std::vector<Vec> normals(Vec x, Vec y, Vec z) {
  x = unit(x); y = unit(y); z = unit(z);
  std::vector<Vec> out;
  for (int a = 0; a < 3; ++a)
    for (int b = a + 1; b < 3; ++b)
      for (int sa : {1, -1})
        for (int sb : {1, -1}) {
          Vec c{0, 0, 0};
          c[a] = sa;
          c[b] = sb;
          c = unit(c);
          out.push_back({x[0] * c[0] + x[1] * c[1] + x[2] * c[2], y[0] * c[0] + y[1] * c[1] + y[2] * c[2],
                         z[0] * c[0] + z[1] * c[1] + z[2] * c[2]});
        }
  return out;
}

struct Mechanism {
  double ex = 0;
  int open = 0, sliding = 0, stuck = 0;
  std::array<std::array<double, 3>, 3> stress{};   // from the sliding contacts, N = 1
};

// Plane strain (ey = 0, ez = -1): the mechanism, or none when no ex keeps every contact from closing.
std::optional<Mechanism> plane_strain(const std::vector<Vec>& ns, double f) {
  Mechanism m;
  m.ex = -1e300;
  for (const Vec& n : ns) {
    const double need = n[2] * n[2];   // ex n_x^2 - n_z^2 >= 0
    if (std::abs(n[0]) > 1e-12) m.ex = std::max(m.ex, need / (n[0] * n[0]));
    else if (need > 1e-12) return std::nullopt;
  }
  const Vec d{m.ex, 0, -1};
  for (const Vec& n : ns) {
    const Vec dn{d[0] * n[0], d[1] * n[1], d[2] * n[2]};
    const double normal_rate = dn[0] * n[0] + dn[1] * n[1] + dn[2] * n[2];
    const double slip = std::sqrt(dn[0] * dn[0] + dn[1] * dn[1] + dn[2] * dn[2]);
    if (normal_rate > 1e-9) { ++m.open; continue; }
    if (slip < 1e-12) { ++m.stuck; continue; }
    ++m.sliding;
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) m.stress[a][b] += (n[a] - f * dn[a] / slip) * n[b];
  }
  return m;
}


double closed_zz(double f) {
  const double s3 = std::sqrt(3.0), s2 = std::sqrt(2.0);
  return 2 * (s3 + s2 * f) / (s3 - 2 * s2 * f);
}
double closed_yy(double f) {
  const double s3 = std::sqrt(3.0), s2 = std::sqrt(2.0);
  return s3 / (s3 - 2 * s2 * f);
}

std::string number(double v) {
  char s[32];
  std::snprintf(s, sizeof s, "%.17g", v);
  return s;
}

// The lattice of examples/fcc_plane_strain.dat: 128 balls of radius 1 just touching, in a periodic
// cell they fill exactly (z edge 8 layers of d/sqrt2, written here to the last digit).
std::string lattice_deck() {
  return "start 8 8 " + number(8 * std::sqrt(2.0)) +
         "\nprop kn 1e8 ks 1e8 mu 0.3 dens 1000\nlattice fcc 2 4 4 8 origin 0.5 0.5 0.5\n";
}

// Unit branch vectors from ball b to the balls nearer than `reach` (nearest periodic image), by
// distance.
struct Neighbour {
  Vec n;
  double distance;
};
std::vector<Neighbour> neighbours(const Model& m, std::size_t b, double reach) {
  const auto L = m.space.length();
  const Balls& balls = m.balls;
  std::vector<Neighbour> out;
  for (std::size_t k = 0; k < balls.size(); ++k) {
    if (k == b) continue;
    Vec d{balls.x[k] - balls.x[b], balls.y[k] - balls.y[b], balls.z[k] - balls.z[b]};
    for (int a = 0; a < 3; ++a) d[a] -= L[a] * std::round(d[a] / L[a]);
    const double l = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    if (l < reach) out.push_back({{d[0] / l, d[1] / l, d[2] / l}, l});
  }
  std::sort(out.begin(), out.end(), [](const Neighbour& p, const Neighbour& q) { return p.distance < q.distance; });
  return out;
}

// The state of a plane-strain run at the peak of sigma_zz/sigma_xx, and trubal's contacts there:
// those along x, along y and inclined (out of the layers).
struct Peak {
  double zz = 0, yy = 0;   // sigma_zz/sigma_xx at its peak, sigma_yy/sigma_xx there
  int block = -1;
  std::size_t balls = 0, x_rows = 0, y_rows = 0, inclined = 0, inclined_sliding = 0;
  double y_row_force = 0, inclined_force = 0;   // largest normal force along y; mean inclined one
};

// Runs a deck to the start of its compression, then `blocks` blocks of 50 cycles, reading trubal's
// average stress (the periodic cell's) after each.
Peak run_to_peak(Harness& h, const std::string& deck, int blocks) {
  REQUIRE(h.deck(deck, "fcc.dat"));
  Peak p;
  std::vector<double> ratios;
  for (int block = 0; block < blocks; ++block) {
    INFO("block " << block << ": " << h.err.str());
    REQUIRE(h.deck("cycle 50\n", "block.dat"));
    const Model& m = h.session.model();
    const auto L = m.space.length();
    const Sym6 s = average_stress(m, L[0] * L[1] * L[2]);
    if (!(s[2] / s[0] > p.zz)) continue;
    p = Peak{};
    p.zz = s[2] / s[0];
    p.yy = s[1] / s[0];
    p.block = block;
    p.balls = m.balls.size();
    const ContactTable& c = m.contacts;
    double inclined_sum = 0;
    for (std::size_t q = 0; q < c.size(); ++q) {
      if (c.state[q] == 0) continue;
      if (std::abs(c.nx[q]) > 0.9) {
        ++p.x_rows;
      } else if (std::abs(c.ny[q]) > 0.9) {
        ++p.y_rows;
        p.y_row_force = std::max(p.y_row_force, std::abs(c.fn[q]));
      } else {
        ++p.inclined;
        p.inclined_sliding += c.state[q] == 2;
        inclined_sum += c.fn[q];
      }
    }
    p.inclined_force = p.inclined ? inclined_sum / static_cast<double>(p.inclined) : 0;
  }
  return p;
}

// Consolidation and compression as in examples/fcc_plane_strain.dat: x and z to 1 kPa with y held,
// then z shortened at 3e-7 per step with sigma_xx held and y at zero strain.
const char* const kLoading =
    "frac 0.3\nservo xx 1000 zz 1000\ncycle 2000\nservo xx 1000 gain 1.5e-5\nstrain zz 6.5e-4\n";

}  // namespace

TEST_CASE("FCC plane-strain mechanism: LATTICE fcc builds layers normal to z with rows along x and y, "
          "which give Thornton's ratios",
          "[physics][periodic]") {
  Harness h;
  REQUIRE(h.deck(lattice_deck()));
  const Model& m = h.session.model();
  REQUIRE(m.balls.size() == 128);
  // x = [110], y = [-110], z = [001] in cube axes: the orientation of the closed form.
  const std::vector<Vec> expected = normals({1, 1, 0}, {-1, 1, 0}, {0, 0, 1});
  // LATTICE places the balls at multiples of d and d/sqrt2 from the origin: exact but for rounding
  // (~1e-15), so distances and directions to 1e-12.
  for (std::size_t b = 0; b < m.balls.size(); ++b) {
    INFO("ball " << m.balls.id[b]);
    CHECK(m.balls.rad[b] == 1);
    // 12 neighbours at d = 2 and no other within 2.5 (the next shell is at d sqrt2 = 2.83).
    const auto near = neighbours(m, b, 2.5);
    REQUIRE(near.size() == 12);
    std::vector<bool> matched(expected.size(), false);
    for (const Neighbour& nb : near) {
      CHECK(nb.distance == Approx(2).epsilon(1e-12));
      bool found = false;
      for (std::size_t e = 0; e < expected.size() && !found; ++e) {
        const double gap = std::max({std::abs(nb.n[0] - expected[e][0]), std::abs(nb.n[1] - expected[e][1]),
                                     std::abs(nb.n[2] - expected[e][2])});
        if (!matched[e] && gap < 1e-12) matched[e] = found = true;
      }
      INFO("branch " << nb.n[0] << " " << nb.n[1] << " " << nb.n[2]);
      CHECK(found);
    }
  }
  // The mechanism of trubal's lattice (ball 1's branch vectors as the contact normals).
  std::vector<Vec> trubal_normals;
  for (const Neighbour& nb : neighbours(m, 0, 2.5)) trubal_normals.push_back(nb.n);
  for (double f : {0.3, std::tan(7 * M_PI / 180), 0.5}) {
    INFO("f = " << f);
    const auto mech = plane_strain(trubal_normals, f);
    REQUIRE(mech);
    CHECK(mech->ex == Approx(2).epsilon(1e-12));   // Thornton's strain increments (2a, 2b, -(a+b)), a = 1, b = 0
    CHECK(mech->open == 2);                   // the rows along x
    CHECK(mech->sliding == 8);                // out of the layer
    CHECK(mech->stuck == 2);                  // the rows along y: force not set by the mechanism
    // The closed form is this computation with the y rows carrying nothing: equal but for the
    // rounding of the normals (1e-15), so 1e-12.
    CHECK(mech->stress[2][2] / mech->stress[0][0] == Approx(closed_zz(f)).epsilon(1e-12));
    CHECK(mech->stress[1][1] / mech->stress[0][0] == Approx(closed_yy(f)).epsilon(1e-12));
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b)
        if (a != b) CHECK(std::abs(mech->stress[a][b]) < 1e-12);   // principal axes, no moment on a ball
  }
}

TEST_CASE("FCC plane-strain strength: examples/fcc_plane_strain.dat peaks at Thornton's ratios, in his mechanism",
          "[physics][periodic]") {
  test::TempDir dir;
  test::WorkingDir here(dir.path());   // the deck's HIST writes its file here
  const std::string example = test::slurp(std::string(TRUBAL_SOURCE_DIR) + "/examples/fcc_plane_strain.dat");
  // The compression is the deck's last CYCLE: run here in blocks, to read the state at the peak.
  const auto last = example.rfind("\ncycle 2000");
  REQUIRE(last != std::string::npos);
  const auto friction = example.find("mu 0.3");
  REQUIRE(friction != std::string::npos);
  const int blocks = 40;   // 2000 cycles, as the deck; the peak comes within the first 400
  for (const auto& [words, f] : {std::pair<std::string, double>{"mu 0.3", 0.3}, {"fric 7", std::tan(7 * M_PI / 180)}}) {
    INFO(words);
    std::string deck = example.substr(0, last + 1);
    deck.replace(friction, 6, words);
    Harness h;
    const Peak p = run_to_peak(h, deck, blocks);
    INFO("peak " << p.zz << " (" << closed_zz(f) << "), yy/xx " << p.yy << " (" << closed_yy(f) << ") in block "
                 << p.block << "; contacts: x " << p.x_rows << ", y " << p.y_rows << ", inclined " << p.inclined
                 << " (" << p.inclined_sliding << " sliding)");
    // A maximum within the run, not a ratio still growing at its end.
    CHECK(p.block >= 0);
    CHECK(p.block < blocks - 1);
    // Against the closed form: trubal's balls are elastic (overlaps ~6e-5 R at the peak) and the
    // lattice has changed shape by the strain to the peak (1.4e-4 for f = 0.3), which the rigid-
    // plastic closed form leaves out: measured -0.10% and -0.14% (f = 0.3), -0.03% and -0.07%
    // (tan 7 deg). 1% holds them with room; a wrong mechanism is far off (y rows that carry force
    // raise sigma_yy/sigma_xx by tens of percent, tests/validation/periodic_fcc_strength.cpp).
    CHECK(p.zz == Approx(closed_zz(f)).epsilon(0.01));
    CHECK(p.yy == Approx(closed_yy(f)).epsilon(0.01));
    // The contacts in the state the computation gives each ball: the rows along x open, every
    // contact out of the layer sliding, and the rows along y (stuck: force not set by the
    // mechanism) carrying none, as the closed form assumes: they were left just touching, with no
    // prestress (y held through the consolidation), so anything there is rounding; 1e-6 of the
    // inclined contacts' force.
    const auto mech = plane_strain(normals({1, 1, 0}, {-1, 1, 0}, {0, 0, 1}), f);
    REQUIRE(mech);
    CHECK(p.x_rows == 0);
    CHECK(p.inclined == p.balls * static_cast<std::size_t>(mech->sliding) / 2);
    CHECK(p.inclined_sliding == p.inclined);
    CHECK(p.inclined_force > 0);
    CHECK(p.y_row_force <= 1e-6 * p.inclined_force);
  }
}

TEST_CASE("FCC plane-strain strength: a cube-aligned lattice has no mechanism and no peak", "[physics][periodic]") {
  // Cube axes along x, y, z: the contacts in the y-z planes would close whatever ex is, so the
  // computation finds no admissible mechanism ...
  CHECK_FALSE(plane_strain(normals({1, 0, 0}, {0, 1, 0}, {0, 0, 1}), 0.3));
  // ... and trubal, given that lattice (4 x 4 x 4 cubes of 4 balls, radius 1, just touching) and the
  // example's loading, finds no peak: those contacts are compressed elastically, so sigma_zz/sigma_xx
  // rises in every block, far past the strength of the layered orientation (4.88): by the end (6e-4
  // strain) it is 31.0 (measured). The bound is 3 times 4.88, which a lattice that found a way to
  // slide would not pass.
  const int n = 4;
  const double a = 2 * std::sqrt(2.0), edge = n * a;
  std::string deck = "start " + number(edge) + " " + number(edge) + " " + number(edge) +
                     "\nprop kn 1e8 ks 1e8 mu 0.3 dens 1000\n";
  trubal::test::for_each_fcc_site(n, n, n, a, 0.25, [&](const trubal::test::FccSite& site) {
    deck += "ball " + number(site.x) + " " + number(site.y) + " " + number(site.z) + " 1\n";
  });
  deck += kLoading;
  Harness h;
  REQUIRE(h.deck(deck, "cube.dat"));
  REQUIRE(h.session.model().balls.size() == 256);
  double previous = 0;
  for (int block = 0; block < 40; ++block) {
    REQUIRE(h.deck("cycle 50\n", "block.dat"));
    const Model& m = h.session.model();
    const auto L = m.space.length();
    const Sym6 s = average_stress(m, L[0] * L[1] * L[2]);
    INFO("block " << block << ": sigma_zz/sigma_xx " << s[2] / s[0] << " after " << previous);
    CHECK(s[2] / s[0] > previous);
    previous = s[2] / s[0];
  }
  CHECK(previous > 3 * closed_zz(0.3));
}
