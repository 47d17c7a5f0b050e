// Thornton's (1979) closed form for the strength of a face-centred-cubic array of uniform rigid
// spheres (as Itasca documents it for PFC3D), with friction coefficient f: axisymmetric compression
// sigma_zz/sigma_xx = 2(1+f)/(1-f), sigma_yy = sigma_xx; plane strain
// sigma_zz/sigma_xx = 2(sqrt3 + sqrt2 f)/(sqrt3 - 2 sqrt2 f), sigma_yy/sigma_xx = sqrt3/(sqrt3 - 2 sqrt2 f).
// An FCC lattice fills the periodic cell; stiff balls (overlaps ~1e-4 R), the lateral stress held by
// the servo, z compressed until the contacts slide; the peak sigma_zz/sigma_xx is the strength.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdlib>

#include "cycle/pipeline.hpp"
#include "model/edit.hpp"
#include "physics/cell.hpp"
#include "cycle/run.hpp"
#include "physics/scene.hpp"
#include "physics/timestep.hpp"
#include "physics/measure.hpp"
#include "../unit/fcc_lattice.hpp"

using namespace trubal;

namespace {

struct Ratios { double zz, yy; };

// Cube-aligned: every neighbour pair overlaps 4e-5 R at the start.
Model fcc_block(double f) {
  Model m;
  const int n = 4;
  const double r = 1, d = 2 * r * (1 - 2e-5);
  m.space.periodic = true;
  m.started = true;
  Material mat;
  mat.kn = 1e8; mat.ks = 1e8; mat.friction = f; mat.density = 1000;
  m.materials[1] = mat;
  const double a = std::sqrt(2.0) * d;
  m.space.hi = {n * a, n * a, n * a};
  test::for_each_fcc_site(n, n, n, a, 0.25, [&](const test::FccSite& site) { add_ball(m, 0, 1, site.x, site.y, site.z, r); });
  m.settings.frac = 0.5;
  return m;
}

// Axisymmetric compression from the isotropic state: x and y held at the starting stress.
Ratios axisymmetric(double f) {
  Model m = fcc_block(f);
  auto backend = make_pipeline("serial", 1);
  REQUIRE(run_cycles(m, *backend, 10, {}).done == 10);
  auto L = m.space.length();
  const double p0 = average_stress(m, L[0] * L[1] * L[2])[0];
  REQUIRE(p0 > 0);
  m.space.servo_on = {true, true, false};
  m.space.servo_target = {p0, p0, 0};
  const double rate = 2e-4 / (m.dt * 2000);   // 2e-4 axial strain in 2000 steps: about 5x the slip strain
  set_strain_rates(m, {0, 0, rate});
  double best = 0;
  Ratios at_best{};
  for (int block = 0; block < 20; ++block) {
    const CycleResult r = run_cycles(m, *backend, 200, {});
    INFO(r.message);
    REQUIRE(r.done == 200);
    L = m.space.length();
    const Sym6 s = average_stress(m, L[0] * L[1] * L[2]);
    if (std::getenv("TRUBAL_FCC_TRACE"))
      WARN("strain " << m.space.strain[2] << " zz/xx " << s[2] / s[0] << " yy/xx " << s[1] / s[0] << " xx " << s[0]
                     << " sliding " << sliding_fraction(m));
    if (s[2] / s[0] > best) { best = s[2] / s[0]; at_best = {s[2] / s[0], s[1] / s[0]}; }
  }
  return at_best;
}

// Plane strain. Thornton's mechanism for it (tests/unit/fcc_mechanism.cpp computes it): square
// layers normal to z with nearest-neighbour rows along x and y (as LATTICE fcc builds them), strain
// increments (2, 0, -1) in (x, y, z) (extension positive). The 8 contacts out of the layer slide,
// the rows along x open, and the rows along y (the zero-strain axis) neither open nor slide: their
// force is not set by the mechanism, and the closed form is the case where they carry none. The
// cube-aligned lattice has no such mechanism (its y-z contacts would have to close), which is why
// its ratios grow without a peak.
//
// In the periodic cell the y rows keep the force they had when y stopped straining (their overlap is
// set by the fixed y edge), so an isotropic prestress p0 adds p0 / (2 sigma_xx) to sigma_yy/sigma_xx:
// holding sigma_xx near p0 gives sigma_yy/sigma_xx 2.44 and 1.74 (f = 0.3, tan 7) against 1.96 and
// 1.25, while sigma_zz/sigma_xx is unchanged (checked below); the excess falls in proportion to p0 / sigma_xx and vanishes without prestress
// (p0/sigma_xx = 1, 0.5, 0.2, 0.1, 0.02, 0 gave +39%, +19%, +7.8%, +3.9%, +0.7%, -0.04% for tan 7).
// (An earlier try, servo at p0 with the default gain, lagged to sigma_xx = 1.45 p0 and so showed
// 2.16 and 1.57.) So the lattice starts just touching, is consolidated in x and z to the lateral
// stress p with y held, then z is compressed with sigma_xx held.
//
// Loading rate: once every contact slides, the homogeneous state is unstable against ball rolling
// (seeded by rounding, growing over some hundreds of steps); for f = 0.3 the peak comes out 1.0%
// low at 1e-7 strain per step and 2.5% low at 3e-8 as the balls start to roll before it is
// reached, while with spins fixed it is 0.21% low at every rate. At 3e-7 per step the peak comes
// first (0.22% low). f = tan 7 reaches its peak sooner and is 0.05% low at every rate tried.
struct PlaneStrain {
  Ratios peak;                 // sigma_zz/sigma_xx at its peak, and sigma_yy/sigma_xx there
  double row_share = 0;        // sigma_yy carried by the y rows over sigma_xx, at the peak
};

// squeeze: every neighbour pair starts overlapping 2 squeeze R (an isotropic prestress); 0: touching.
PlaneStrain plane_strain(double f, double squeeze, double p) {
  const int n = 4;
  const double r = 1, d = 2 * r * (1 - squeeze), h = d / std::sqrt(2.0);
  Model m;
  m.space.periodic = true;
  m.started = true;
  Material mat;
  mat.kn = 1e8; mat.ks = 1e8; mat.friction = f; mat.density = 1000;
  m.materials[1] = mat;
  m.space.hi = {n * d, n * d, 2 * n * h};
  for (int k = 0; k < 2 * n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const double o = k % 2 ? 0.5 : 0.0;
        add_ball(m, 0, 1, (i + o + 0.25) * d, (j + o + 0.25) * d, (k + 0.25) * h, r);
      }
  m.settings.frac = 0.5;
  auto backend = make_pipeline("serial", 1);
  // Consolidation in x and z to p, y held (the default servo).
  m.space.servo_on = {true, false, true};
  m.space.servo_target = {p, 0, p};
  REQUIRE(run_cycles(m, *backend, 2000, {}).done == 2000);
  auto L = m.space.length();
  Sym6 s = average_stress(m, L[0] * L[1] * L[2]);
  REQUIRE(s[0] == Approx(p).epsilon(1e-3));
  REQUIRE(s[2] == Approx(p).epsilon(1e-3));
  // Compression of z at 3e-7 per step with sigma_xx held. In a perfect lattice every ball moves with
  // the cell, so the stress follows the cell at once and the servo may close half its error per
  // step: g = 0.5 / (M dt), M = 4 k_n / V_ball the stiffness of sigma_xx once the x rows open.
  const double volume_per_ball = d * d * h;
  m.space.servo_on = {true, false, false};
  m.space.servo_gain = 0.5 / (4 * mat.kn / volume_per_ball * m.dt);
  set_strain_rates(m, {m.space.strain_rate[0], 0, 3e-7 / m.dt});
  PlaneStrain out;
  double best = 0;
  for (int block = 0; block < 20; ++block) {
    const CycleResult res = run_cycles(m, *backend, 100, {});
    INFO(res.message);
    REQUIRE(res.done == 100);
    L = m.space.length();
    const double volume = L[0] * L[1] * L[2];
    s = average_stress(m, volume);
    // The y rows' part of sigma_yy: contacts with normal along y.
    double rows = 0;
    const ContactTable& c = m.contacts;
    for (std::size_t q = 0; q < c.size(); ++q)
      if (c.state[q] != 0 && std::abs(c.ny[q]) > 0.99) rows += c.fy[q] * c.ny[q] * (2 * r - c.overlap[q]);
    if (std::getenv("TRUBAL_FCC_TRACE"))
      WARN("strain " << m.space.strain[2] << " zz/xx " << s[2] / s[0] << " yy/xx " << s[1] / s[0] << " xx/p "
                     << s[0] / p << " rows " << rows / volume / s[0] << " sliding " << sliding_fraction(m));
    if (s[2] / s[0] > best) {
      best = s[2] / s[0];
      out.peak = {s[2] / s[0], s[1] / s[0]};
      out.row_share = rows / volume / s[0];
    }
  }
  return out;
}

}  // namespace

TEST_CASE("validation: FCC strength in axisymmetric compression matches Thornton's closed form",
          "[validation][periodic]") {
  for (double f : {0.3, std::tan(7 * M_PI / 180)}) {
    INFO("f = " << f);
    const Ratios got = axisymmetric(f);
    CHECK(got.zz == Approx(2 * (1 + f) / (1 - f)).epsilon(0.02));
    CHECK(got.yy == Approx(1).epsilon(0.02));
  }
}

TEST_CASE("validation: FCC strength in plane strain matches Thornton's closed form", "[validation][periodic]") {
  const double s3 = std::sqrt(3.0), s2 = std::sqrt(2.0);
  const double p = 2828;   // the isotropic stress of overlaps 4e-5 R
  for (double f : {0.3, std::tan(7 * M_PI / 180)}) {
    INFO("f = " << f);
    const double zz = 2 * (s3 + s2 * f) / (s3 - 2 * s2 * f), yy = s3 / (s3 - 2 * s2 * f);
    const PlaneStrain got = plane_strain(f, 0, p);
    // 2%: the target. Measured: zz 4.8703 (-0.22%), yy 1.9557 (-0.24%) for f = 0.3; zz 2.7509,
    // yy 1.2500 (-0.06%) for tan 7, the rest being the finite stiffness and the lattice's change of
    // shape (overlaps ~1.5e-4 R, 3e-4 strain to the peak).
    CHECK(got.peak.zz == Approx(zz).epsilon(0.02));
    CHECK(got.peak.yy == Approx(yy).epsilon(0.02));
    CHECK(std::abs(got.row_share) < 1e-5);   // without prestress the y rows hold rounding only (<4e-7)
    // An isotropic prestress as large as p stays in the y rows: sigma_yy/sigma_xx is then the closed
    // form plus their share (p / (2 sigma_xx), about 0.49), while sigma_zz/sigma_xx does not change.
    const PlaneStrain pre = plane_strain(f, 2e-5, p);
    CHECK(pre.row_share > 0.1);
    CHECK(pre.peak.zz == Approx(zz).epsilon(0.02));
    CHECK(pre.peak.yy == Approx(yy + pre.row_share).epsilon(0.02));
  }
}
