// Which face-centred-cubic orientation Thornton's (1979) plane-strain strength belongs to, by a
// static computation on a rigid-plastic array (no DEM): every ball has the same 12 contacts; a
// homogeneous mechanism is a velocity gradient D = diag(ex, ey, -1) (extension positive) with no
// ball spin. A contact with normal n separates when n.Dn > 0 (no force), slides when n.Dn = 0 and
// the tangential relative velocity Dn is not zero (normal force N, friction f N against Dn),
// is stuck when Dn = 0 (its force is not determined by the mechanism), and D is not admissible when
// some n.Dn < 0 (rigid balls would overlap). By symmetry every sliding contact carries the same N;
// the stress is then proportional to sum (N n - f N Dn/|Dn|) (x) n (compression positive).
// Plane strain: ey = 0, ex the smallest value that keeps every contact from closing.
#include <catch2/catch.hpp>

#include <array>
#include <cmath>
#include <optional>
#include <vector>

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

}  // namespace

TEST_CASE("FCC plane-strain mechanism: layers normal to z with rows along x and y give Thornton's ratios",
          "[physics][periodic]") {
  const double s3 = std::sqrt(3.0), s2 = std::sqrt(2.0);
  for (double f : {0.3, std::tan(7 * M_PI / 180), 0.5}) {
    INFO("f = " << f);
    // x = [110], y = [-110], z = [001]: what LATTICE fcc builds.
    const auto m = plane_strain(normals({1, 1, 0}, {-1, 1, 0}, {0, 0, 1}), f);
    REQUIRE(m);
    CHECK(m->ex == Approx(2));             // Thornton's strain increments (2a, 2b, -(a+b)), a = 1, b = 0
    CHECK(m->open == 2);                   // the rows along x
    CHECK(m->sliding == 8);                // out of the layer
    CHECK(m->stuck == 2);                  // the rows along y: force not set by the mechanism
    // Exact up to rounding: the closed form is this computation with the y rows carrying nothing.
    CHECK(m->stress[2][2] / m->stress[0][0] == Approx(2 * (s3 + s2 * f) / (s3 - 2 * s2 * f)).epsilon(1e-12));
    CHECK(m->stress[1][1] / m->stress[0][0] == Approx(s3 / (s3 - 2 * s2 * f)).epsilon(1e-12));
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b)
        if (a != b) CHECK(std::abs(m->stress[a][b]) < 1e-12);   // principal axes, no moment on a ball
  }
}

TEST_CASE("FCC plane-strain mechanism: other orientations have none of that kind", "[physics][periodic]") {
  // Cube axes (y = [010]): the contacts in the y-z planes would close whatever ex is.
  CHECK_FALSE(plane_strain(normals({1, 0, 0}, {0, 1, 0}, {0, 0, 1}), 0.3));
  // z along a row ([110]) or along the body diagonal [111] with y in the close-packed plane.
  CHECK_FALSE(plane_strain(normals({0, 0, 1}, {1, -1, 0}, {1, 1, 0}), 0.3));
  CHECK_FALSE(plane_strain(normals({1, -1, 0}, {0, 0, 1}, {1, 1, 0}), 0.3));
  CHECK_FALSE(plane_strain(normals({1, -1, 0}, {1, 1, -2}, {1, 1, 1}), 0.3));
  // z = [111] with x = [11-2]: admissible, but only 4 contacts slide and the stress has shear
  // components (not principal in x y z): not the mechanism of the closed form.
  const auto m = plane_strain(normals({1, 1, -2}, {1, -1, 0}, {1, 1, 1}), 0.3);
  REQUIRE(m);
  CHECK(m->sliding == 4);
  double shear = 0;
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b)
      if (a != b) shear = std::max(shear, std::abs(m->stress[a][b]));
  CHECK(shear > 0.1);
}
