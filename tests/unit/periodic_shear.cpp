// Shear of the periodic cell (STRAIN e12 e13 e23): the cell becomes a parallelepiped whose images
// across the y and z faces are shifted by its tilts (backends/periodic.hpp). Simple shear gives the
// strain tensor and the affine velocity field it should, with the energy balanced; a pair across the
// shifted face feels its image where the tilt puts it; a ball crossing a shifted face keeps its
// contact and history; renaming the images past half an edge changes nothing physical; SAVE and
// RESTART carry the tilts; GEN places balls clear of the shifted images.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstring>
#include <random>
#include <set>
#include <utility>
#include <sstream>
#include <string>
#include <vector>

#include "model/periodic_cell.hpp"
#include "backends_scenes.hpp"
#include "interp_support.hpp"
#include "io/save.hpp"
#include "physics/cell.hpp"
#include "physics/measure.hpp"

using namespace trubal;
using namespace trubal::test;

namespace {

// A dense frictional FCC block (4 n^3 balls of radius 1, every neighbour pair overlapping 1e-3 R)
// filling a cubic periodic cell.
Model fcc_cell(int n) {
  Model m;
  const double r = 1, a = 0.999 * 2 * r * std::sqrt(2.0);
  m.space.periodic = true;
  m.space.hi = {n * a, n * a, n * a};
  m.started = true;
  m.materials[1] = scene_linear(1e6, 1e6, 0.5, 1000);
  for_each_fcc_site(n, n, n, a, 0.25, [&](const FccSite& site) { add_ball(m, 0, 1, site.x, site.y, site.z, r); });
  update_mass(m);
  return m;
}

// Two balls of radius 0.5 in a 10-edge periodic cell, held (velocity and spin), touching only
// through the y faces; ball 2 sits across the y face from ball 1, where the xy tilt puts its image.
Model pair_across_y(double tilt_xy, double overlap) {
  Model m;
  m.space.periodic = true;
  m.space.hi = {10, 10, 10};
  m.space.tilt = {tilt_xy, 0, 0};
  m.started = true;
  m.materials[1] = scene_linear(1e4, 5e3, 10, 1000);
  m.settings.fixed_dt = 1e-3;
  // 1 at y = 0.5; 2's image one cell below (n_y = -1) at y = -0.5 + overlap, x shifted by -tilt.
  add_ball(m, 1, 1, 5, 0.5, 5, 0.5);
  add_ball(m, 2, 1, 5 + tilt_xy, 9.5 + overlap, 5, 0.5);
  m.balls.fixed = {kVel | kSpin, kVel | kSpin};
  update_mass(m);
  return m;
}

std::size_t touching_pair(const Model& m) {
  std::size_t p = 0;
  while (p < m.contacts.size() && m.contacts.state[p] == 0) ++p;
  return p;
}

}  // namespace

TEST_CASE("periodic shear: simple shear of a frictional FCC block has the cell's strain and velocity field",
          "[periodic]") {
  Model m = fcc_cell(3);   // 108 balls
  m.settings.damping.kind = DampKind::Local;   // quasi-static: without damping the lattice rings
  m.settings.damping.local = 0.7;              // around the affine field by about 1%
  const auto L0 = m.space.length();
  const double e12 = 2e-3;
  set_all_strain_rates(m, {0, 0, 0, e12, 0, 0});
  auto backend = make_pipeline("serial", 1);
  const CycleResult r = run_cycles(m, *backend, 2000, {});
  REQUIRE(r.done == 2000);
  const double t = m.time;
  // The strain is the rate times the time, tensor shear components; only xy.
  CHECK(m.space.strain[3] == Approx(e12 * t).epsilon(1e-12));
  for (int a : {0, 1, 2, 4, 5}) CHECK(m.space.strain[a] == 0);
  // Simple shear: the faces normal to y have moved along -x by 2 e12 t L_y; the edges did not change.
  CHECK(m.space.tilt[0] == Approx(-2 * e12 * t * L0[1]).epsilon(1e-9));
  CHECK(m.space.tilt[1] == 0);
  CHECK(m.space.tilt[2] == 0);
  for (int a = 0; a < 3; ++a) CHECK(m.space.length()[a] == Approx(L0[a]).epsilon(1e-14));   // rounding only
  REQUIRE(m.space.strain[3] > 1e-3);   // a strain ten times the contacts' elastic range
  // The balls move with the cell: the velocity field fitted over the balls is v_x = -2 e12 (y - c_y),
  // to 2%, and there is no mean flow along y or z. What the contacts add on top rings from one step
  // to the next: over the last 200 cycles the fit is -0.3% to +1.4% off, at cycle 2000 measured 1.3%
  // (the step held from the first cycle; -0.14% when it followed the estimate, and -2.1% to +2.6%
  // at other steps held or FRACs).
  const Balls& b = m.balls;
  double sy = 0, syy = 0, svx = 0, syvx = 0, svy = 0, svz = 0;
  const double n = static_cast<double>(b.size());
  for (std::size_t k = 0; k < b.size(); ++k) {
    sy += b.y[k]; syy += b.y[k] * b.y[k]; svx += b.vx[k]; syvx += b.y[k] * b.vx[k];
    svy += b.vy[k]; svz += b.vz[k];
  }
  const double slope = (syvx - sy * svx / n) / (syy - sy * sy / n);
  CHECK(slope == Approx(-2 * e12).epsilon(0.02));
  // No mean flow: under 0.5% of the field's scale 2 e12 L_y. Local damping does not keep the
  // momentum, so the rounding of the sums leaves a drift: mean v_y measured -2.2e-5 (0.06%) with
  // the balls summed in id order, -8.7e-5 to -1.1e-4 (0.3%) in space order sorted every 1 to 1000
  // cycles; mean v_z under 1.3e-5.
  CHECK(std::abs(svy / n) < 5e-3 * 2 * e12 * L0[1]);
  CHECK(std::abs(svz / n) < 5e-3 * 2 * e12 * L0[1]);
  // The assembly resists: sigma_12 (compression positive) grows positive with e12.
  const Sym6 s = average_stress(m, L0[0] * L0[1] * L0[2]);
  CHECK(s[3] > 0.05 * s[0]);
  // The work the cell did (image contacts and velocity changes) is what the springs, the balls and
  // friction hold: the balance closes to 1% of the work.
  const EnergyReport e = energy(m);
  REQUIRE(e.boundary_work > 0);
  CHECK(std::abs(e.total()) < 0.01 * e.boundary_work);
}

TEST_CASE("periodic shear: a pair across the shifted y face feels its image where the tilt puts it",
          "[periodic][threads]") {
  for (const char* name : {"serial", "allpairs", "threaded"}) {
    INFO(name);
    // At rest: the overlap is the one across the shifted face.
    Model m = pair_across_y(3.25, 0.02);
    auto backend = make_pipeline(name, 1);
    REQUIRE(run_cycles(m, *backend, 1, {}).done == 1);
    REQUIRE(contact_count(m) == 1);
    std::size_t p = touching_pair(m);
    CHECK(m.contacts.image_y[p] == -1);
    CHECK(m.contacts.overlap[p] == Approx(0.02).epsilon(1e-9));
    CHECK(m.contacts.ny[p] == Approx(-1).epsilon(1e-12));
    CHECK(m.contacts.fn[p] == Approx(1e4 * 0.02).epsilon(1e-9));
    // Without the tilt the two are 3.25 apart along x: no contact.
    Model flat = pair_across_y(3.25, 0.02);
    flat.space.tilt = {0, 0, 0};
    REQUIRE(run_cycles(flat, *make_pipeline(name, 1), 1, {}).done == 1);
    CHECK(contact_count(flat) == 0);

    // Shearing: the image of 2 moves along x at 2 e12 L_y relative to 1 (e12 > 0 moves the image
    // below toward +x), the shear spring takes -k_s times that displacement (on 2), and the normal
    // force follows the image's new place: overlap from the distance to (x2 - xy(t), y2 - 10).
    Model s = pair_across_y(0.0, 0.02);
    const double e12 = 0.005;
    set_all_strain_rates(s, {0, 0, 0, e12, 0, 0});
    auto sb = make_pipeline(name, 1);
    REQUIRE(run_cycles(s, *sb, 200, {}).done == 200);
    REQUIRE(contact_count(s) == 1);
    p = touching_pair(s);
    const double t = s.time, slip = 2 * e12 * 10 * t;   // 0.02: well within the overlap's reach
    CHECK(s.space.tilt[0] == Approx(-slip).epsilon(1e-12));
    CHECK(s.balls.x[0] == 5);   // held balls do not take the homogeneous field
    // The last force pass saw the cell of one step before: the image at x2 - xy = 5 + slip', y = -0.48,
    // overlap 1 - |d|.
    const double d = std::hypot(2 * e12 * 10 * (t - s.dt), 0.98);
    CHECK(s.contacts.overlap[p] == Approx(1 - d).epsilon(1e-9));
    CHECK(s.contacts.fn[p] == Approx(1e4 * (1 - d)).epsilon(1e-9));
    // The shear force on 2: -k_s times its slip along x (the normal turned by slip / d; rotating the
    // force onto the new plane keeps its length), to 1e-3.
    CHECK(s.contacts.fsx[p] == Approx(-5e3 * slip).epsilon(2e-3));
    CHECK(std::abs(s.contacts.fsz[p]) < 1e-12);
  }
}

TEST_CASE("periodic shear: a ball crossing a shifted face keeps its contact and shear history", "[periodic][threads]") {
  for (const char* name : {"serial", "allpairs", "threaded"}) {
    INFO(name);
    Model m = pair_across_y(3.25, 0.05);
    set_all_strain_rates(m, {0, 0, 0, 0.01, 0, 0});   // the image also moves along x
    // Both drift across the face y = 0 (and along x), and slide along z: the history grows.
    m.balls.vy = {-1.0, -1.0};
    m.balls.vx = {0.3, 0.1};      // 2's image moves with 1: its own 0.1 and the image's 0.2
    m.balls.vz = {0.01, -0.01};
    auto backend = make_pipeline(name, 1);
    double last_shear = 0;
    bool wrapped = false;
    for (int step = 0; step < 60; ++step) {
      REQUIRE(run_cycles(m, *backend, 10, {}).done == 10);
      REQUIRE(contact_count(m) == 1);
      const std::size_t p = touching_pair(m);
      const double shear = std::hypot(m.contacts.fsx[p], m.contacts.fsz[p]);
      CHECK(shear > last_shear);   // never reset to zero
      last_shear = shear;
      // Apart along y by 0.95; along z they have slid 0.02 t (to the last force pass).
      const double slid = 0.02 * (m.time - m.dt);
      CHECK(m.contacts.overlap[p] == Approx(1 - std::hypot(0.95, slid)).epsilon(1e-9));
      wrapped = wrapped || m.balls.y[0] > 5;
    }
    CHECK(wrapped);
  }
}

TEST_CASE("periodic shear: renaming the images past half an edge keeps every pair's image", "[periodic]") {
  Scene scene = sheared_periodic(6, 0);   // 216 balls
  Model m = scene.model;
  auto backend = make_pipeline("serial", 1);
  REQUIRE(run_cycles(m, *backend, 50, {}).done == 50);
  // An equivalent cell one edge further tilted, each image renamed to stay the same image.
  Model far = m;
  const auto L = far.space.length();
  far.space.tilt[0] += L[0];
  far.space.tilt[1] -= L[0];
  for (std::size_t p = 0; p < far.contacts.size(); ++p) {
    far.contacts.image_x[p] = static_cast<std::int8_t>(far.contacts.image_x[p] - far.contacts.image_y[p] +
                                                       far.contacts.image_z[p]);
  }
  CHECK(reduce_cell_tilt(far));
  CHECK(far.space.tilt[0] == Approx(m.space.tilt[0]).margin(1e-12));
  CHECK(far.space.tilt[1] == Approx(m.space.tilt[1]).margin(1e-12));
  CHECK(far.contacts.image_x == m.contacts.image_x);
  CHECK(far.contacts.image_y == m.contacts.image_y);
  CHECK(far.contacts.image_z == m.contacts.image_z);
  CHECK_FALSE(reduce_cell_tilt(m));
  // z past half a y edge: c less b also takes xy off xz.
  Model zy = m;
  zy.space.tilt[2] += L[1];
  zy.space.tilt[1] += zy.space.tilt[0];
  for (std::size_t p = 0; p < zy.contacts.size(); ++p)
    zy.contacts.image_y[p] = static_cast<std::int8_t>(zy.contacts.image_y[p] - zy.contacts.image_z[p]);
  CHECK(reduce_cell_tilt(zy));
  CHECK(zy.space.tilt[2] == Approx(m.space.tilt[2]).margin(1e-12));
  CHECK(zy.space.tilt[1] == Approx(m.space.tilt[1]).margin(1e-12));
  CHECK(zy.contacts.image_y == m.contacts.image_y);
}

TEST_CASE("periodic shear: shear to large strain renames the images and keeps the contacts and the energy",
          "[periodic]") {
  Model m = fcc_cell(2);   // 32 balls
  m.settings.damping.kind = DampKind::Local;
  m.settings.damping.local = 0.3;
  auto backend = make_pipeline("serial", 1);
  REQUIRE(run_cycles(m, *backend, 1, {}).done == 1);
  const int steps = 6000;
  const double t0 = m.time, e12 = -2.6 / (2 * steps * m.dt);   // shear about 2.6: xy passes half an edge 3 times
  set_all_strain_rates(m, {0, 0, 0, e12, 0.1 * e12, -0.2 * e12});
  const auto L = m.space.length();
  double smallest_width = L[0];
  int renames = 0;
  // Touching pairs by ids, and the sum of normal forces, after each step.
  auto touching = [](const Model& model) {
    std::set<std::pair<std::int64_t, std::int64_t>> out;
    const ContactTable& c = model.contacts;
    for (std::size_t p = 0; p < c.size(); ++p)
      if (c.state[p] != 0) out.insert({model.balls.id[c.i[p]], model.balls.id[c.j[p]]});
    return out;
  };
  auto force_sum = [](const Model& model) {
    double f = 0;
    for (std::size_t p = 0; p < model.contacts.size(); ++p) f += model.contacts.fn[p];
    return f;
  };
  auto before = touching(m);
  double force_before = force_sum(m);
  for (int step = 0; step < steps; ++step) {
    const double xy = m.space.tilt[0];
    const CycleResult r = run_cycles(m, *backend, 1, {});
    INFO(r.message);
    REQUIRE(r.done == 1);
    for (double w : cell_widths(m.space)) smallest_width = std::min(smallest_width, w);
    const auto now = touching(m);
    const double force_now = force_sum(m);
    if (m.space.tilt[0] < xy) {   // renamed at the end of the last step: the first forces in the new cell
      ++renames;
      INFO("renamed at step " << step);
      // About one step in ten opens or closes a contact as the block shears; a wrong image after
      // renaming would tear every contact across the y faces at once.
      std::size_t lost = 0, across = 0;
      for (const auto& pair : before) lost += now.count(pair) == 0;
      for (std::size_t p = 0; p < m.contacts.size(); ++p) across += m.contacts.state[p] != 0 && m.contacts.image_y[p] != 0;
      CHECK(across >= 5);
      CHECK(lost <= 2);
      CHECK(now.size() + 2 >= before.size());
      CHECK(force_now == Approx(force_before).epsilon(0.01));
    }
    before = now;
    force_before = force_now;
  }
  CHECK(m.space.strain[3] == Approx(e12 * (m.time - t0)).epsilon(1e-9));
  const double shear = -2 * m.space.strain[3];   // tilt / edge without renaming
  REQUIRE(shear > 2.5);
  CHECK(renames == static_cast<int>(std::floor(shear + 0.5)));
  for (double t : {m.space.tilt[0], m.space.tilt[1]}) CHECK(std::abs(t) <= 0.5 * L[0]);
  CHECK(std::abs(m.space.tilt[2]) <= 0.5 * L[1]);
  CHECK(smallest_width > 0.8 * L[0]);
  const EnergyReport e = energy(m);
  CHECK(std::abs(e.total()) < 0.01 * std::abs(e.boundary_work));
}

TEST_CASE("periodic shear: SAVE and RESTART continue a sheared run bitwise and a version 2 file still reads",
          "[periodic][commands]") {
  TempDir dir;
  const Scene scene = sheared_periodic(6, 0);
  Model straight = scene.model;
  REQUIRE(run_cycles(straight, *make_pipeline("serial", 1), 60, {}).done == 60);
  Model first = scene.model;
  REQUIRE(run_cycles(first, *make_pipeline("serial", 1), 2, {}).done == 2);
  const std::string path = (dir.path() / "sheared.sav").string();
  save_model(first, path);
  REQUIRE(first.space.tilt[0] > 0);   // the restarted run renames its images on the way
  Model second = load_model(path);
  CHECK(std::memcmp(second.space.tilt.data(), first.space.tilt.data(), sizeof first.space.tilt) == 0);
  REQUIRE(run_cycles(second, *make_pipeline("serial", 1), 58, {}).done == 58);
  CHECK(difference(picture(straight), picture(second)) == "");
  CHECK(std::memcmp(straight.space.tilt.data(), second.space.tilt.data(), sizeof straight.space.tilt) == 0);
  CHECK(straight.space.tilt[0] < 0);

  // Version 2 had no tilts (nor servo moments, walls or histories): the same model written in
  // that format reads as a cell without tilt.
  const std::string old_path = (dir.path() / "old.sav").string();
  save_model(first, old_path, nullptr, 2);
  const Model old = load_model(old_path);
  CHECK(old.space.tilt == std::array<double, 3>{0, 0, 0});
  CHECK(old.balls.x == first.balls.x);
  // A save keeps the pairs that carry something (touching, or a shear history); the search's spare
  // candidates are the next step's to find again.
  std::vector<std::array<double, 3>> carried, read;
  const ContactTable& c = first.contacts;
  for (std::size_t p = 0; p < c.size(); ++p)
    if ((c.results_kept() && c.state[p] != 0) || c.fsx[p] != 0 || c.fsy[p] != 0 || c.fsz[p] != 0)
      carried.push_back({static_cast<double>(c.i[p]), static_cast<double>(c.j[p]), c.fsx[p]});
  for (std::size_t p = 0; p < old.contacts.size(); ++p)
    read.push_back({static_cast<double>(old.contacts.i[p]), static_cast<double>(old.contacts.j[p]), old.contacts.fsx[p]});
  REQUIRE(carried.size() >= 4);
  CHECK(read == carried);
}

TEST_CASE("periodic shear: STRAIN takes shear rates and PRINT and HIST show the shear strain and tilt",
          "[periodic][commands]") {
  TempDir dir;
  WorkingDir here(dir.path());
  Harness h;
  REQUIRE(h.deck(R"(
start 200 200 200
prop kn 1e6 ks 1e6 fric 0.3 dens 2000
gen 100 8 10 seed 3
tstep 0.01
strain 0 0 0 1e-3 0 -2e-3
hist strain every 50 file shear.csv
cycle 100
print strain
print info
)"));
  const Model& m = h.session.model();
  CHECK(m.space.strain[3] == Approx(100 * 1e-3 * 0.01));
  CHECK(m.space.strain[5] == Approx(-100 * 2e-3 * 0.01));
  CHECK(m.space.tilt[0] == Approx(-2 * 1e-3 * 200 * 1.0).epsilon(1e-9));
  CHECK(m.space.tilt[2] == Approx(2 * 2e-3 * 200 * 1.0).epsilon(1e-9));
  // Simple shear in two planes composes: c's x moves with its y (L_xy yz): -2 e12 * yz(t) integrated.
  CHECK(m.space.tilt[1] == Approx(-2 * 1e-3 * 0.8 / 2).epsilon(0.02));
  CHECK(h.out.str().find("strain: xx 0  yy 0  zz 0  xy 0.001  xz 0  yz -0.002") != std::string::npos);
  CHECK(h.out.str().find("cell tilt: xy -0.4  xz -0.000792  yz 0.8") != std::string::npos);
  const auto rows = lines_of(slurp("shear.csv"));
  REQUIRE(rows.size() == 3);
  CHECK(rows[0] == "cycle,time,e11,e22,e33,e12,e13,e23");
  std::vector<double> last;
  std::istringstream row(rows[2]);
  for (std::string field; std::getline(row, field, ',');) last.push_back(std::stod(field));
  REQUIRE(last.size() == 8);
  CHECK(last[5] == Approx(1e-3));
  CHECK(last[6] == 0);
  CHECK(last[7] == Approx(-2e-3));
  // The keyword form changes only the components named; the positional form sets all six.
  REQUIRE(h.deck("strain xz 5e-4\n"));
  CHECK(m.space.strain_rate == std::array<double, 6>{0, 0, 0, 1e-3, 5e-4, -2e-3});
  REQUIRE(h.deck("strain 0 0 1e-4\n"));
  CHECK(m.space.strain_rate == std::array<double, 6>{0, 0, 1e-4, 0, 0, 0});
  REQUIRE(h.deck("strain off\n"));
  CHECK(m.space.strain_rate == std::array<double, 6>{0, 0, 0, 0, 0, 0});
}

TEST_CASE("periodic shear: GEN in a sheared cell places balls clear of the shifted images", "[periodic][commands]") {
  Harness h;
  REQUIRE(h.deck(R"(
start 40 40 40
prop kn 1e6 ks 1e6 fric 0.3 dens 2000
gen 1 1 1 seed 1
tstep 0.01
strain 0 0 0 -1.6 1 0.6
cycle 10
strain off
)"));
  const auto& tilt = h.session.model().space.tilt;
  REQUIRE(tilt[0] > 10);
  REQUIRE(tilt[1] < -5);
  REQUIRE(tilt[2] < -3);
  REQUIRE(h.deck("gen 600 1.5 2 seed 4\ncycle 1\n"));
  const Model& m = h.session.model();
  CHECK(m.balls.size() == 601);
  CHECK(contact_count(m) == 0);   // no ball overlaps another or an image
}

TEST_CASE("periodic: HIST volumetric records the cell's volumetric strain 1 - V/V0", "[periodic][commands]") {
  TempDir dir;
  WorkingDir here(dir.path());
  Harness h;
  REQUIRE(h.deck(R"(
start 200 200 200
prop kn 1e6 ks 1e6 fric 0.3 dens 2000
gen 50 8 10 seed 3
tstep 0.01
strain 1e-3 -4e-4 2e-3
hist strain volumetric every 50 file vol.csv
cycle 100
)"));
  const auto rows = lines_of(slurp("vol.csv"));
  REQUIRE(rows.size() == 3);
  CHECK(rows[0] == "cycle,time,e11,e22,e33,e12,e13,e23,evol");
  std::vector<double> last;
  std::istringstream row(rows[2]);
  for (std::string field; std::getline(row, field, ',');) last.push_back(std::stod(field));
  REQUIRE(last.size() == 9);
  // 100 steps of 0.01: each edge L becomes L exp(-rate dt) per step, so V / V0 is exp(-2.6e-3) and
  // evol = 1 - V / V0 = 2.59662e-3 (compression positive), a strain, where the accumulated (natural)
  // strains add to 2.6e-3; exact but for the rounding of 100 steps.
  const double ratio = std::exp(-2.6e-3);
  CHECK(last[8] == Approx(1 - ratio).epsilon(1e-9));
  CHECK(last[2] + last[3] + last[4] == Approx(2.6e-3).epsilon(1e-9));
}
