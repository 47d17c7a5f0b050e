// Scenes for the cross-backend tests, built directly in C++, and bitwise comparison of two models.
#pragma once

#include <algorithm>

#include <numeric>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <map>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "cycle/pipeline.hpp"
#include "fcc_lattice.hpp"
#include "model/edit.hpp"
#include "model/model.hpp"
#include "physics/cell.hpp"
#include "cycle/run.hpp"
#include "physics/scene.hpp"
#include "physics/timestep.hpp"

namespace trubal::test {

// Under ThreadSanitizer (CI's TSan stage) the tests that compare every backend and thread count
// leave out the runs on one thread, and allpairs on 3 threads and threaded on 4: the first share
// nothing that could race, the others take the code that allpairs on 2 and threaded on 2 and 3
// take, at several times their cost under TSan (allpairs tests every pair). Every build but
// TSan's checks their bits.
#ifdef __SANITIZE_THREAD__
constexpr bool kRaceCheckOnly = true;
#else
constexpr bool kRaceCheckOnly = false;
#endif

struct Scene {
  std::string name;
  Model model;
  int cycles;
};

inline Material scene_linear(double kn, double ks, double mu, double density) {
  Material m;
  m.kn = kn; m.ks = ks; m.friction = mu; m.density = density;
  return m;
}

// A dense FCC block (R = 20, every ball touching its 12 neighbours, as the benchmark) whose outer
// layer is held and moves inward: compression with friction and rotation.
// by_layer_parity: the balls numbered as the Rowe decks number them, all even lattice layers
// first, then all odd ones, so that most pairs join balls far apart in numbering; kept so in memory
// (the run never sorts it: SET sort 0).
inline Scene fcc_compression(int nx, int ny, int nz, bool by_layer_parity = false) {
  Scene s{"dense FCC under compression", {}, 300};
  const double r = 20, a = 0.99 * 2 * r * std::sqrt(2.0);
  s.model.materials[1] = scene_linear(1.5e9, 1.5e9, 0.3, 2000);
  s.model.settings.fixed_dt = 0.02;
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> jitter(-0.05, 0.05);
  const double cx = 0.5 * nx * a, cy = 0.5 * ny * a, cz = 0.5 * nz * a, rate = 2e-3;
  for (int parity = 0; parity < (by_layer_parity ? 2 : 1); ++parity)
    for_each_fcc_site(nx, ny, nz, a, 0.25, [&](const FccSite& site) {
      if (by_layer_parity && (kFccBasis[site.basis][2] != 0) != (parity == 1)) return;
      const double x = site.x + jitter(rng), y = site.y + jitter(rng);
      const double z = site.z + jitter(rng);
      const std::size_t ball = add_ball(s.model, 0, 1, x, y, z, r);
      if (site.on_surface) {
        s.model.balls.fixed[ball] = kVel | kSpin;
        s.model.balls.vx[ball] = -rate * (x - cx);
        s.model.balls.vy[ball] = -rate * (y - cy);
        s.model.balls.vz[ball] = -rate * (z - cz);
      }
    });
  if (by_layer_parity) s.model.order.every = 0;
  return s;
}

// Balls of radius 0.3 to 0.5 on a jittered unit grid (n x n x layers, starting at height z0),
// with random velocities up to `speed`.
inline void jittered_grid(Model& model, int n, int layers, double z0, double speed, unsigned seed, int type = 1) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  for (int k = 0; k < layers; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const std::size_t b = add_ball(model, 0, type, i + 0.1 * (u(rng) - 0.5), j + 0.1 * (u(rng) - 0.5),
                                       z0 + k + 0.1 * (u(rng) - 0.5), 0.3 + 0.2 * u(rng));
        model.balls.vx[b] = speed * (u(rng) - 0.5);
        model.balls.vy[b] = speed * (u(rng) - 0.5);
        model.balls.vz[b] = speed * (u(rng) - 0.5);
      }
}

// A floor of held balls (radius 0.45, not touching each other) under the grid: all at z = 0.
inline void fixed_floor(Model& model, int n, int type) {
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const std::size_t b = add_ball(model, 0, type, i, j, 0, 0.45);
      model.balls.fixed[b] = kVel | kSpin;
    }
}

// Polydisperse balls falling under gravity, with friction and local damping, onto held balls.
inline Scene settling(int n, int layers, int cycles) {
  Scene s{"polydisperse settling onto fixed balls", {}, cycles};
  s.model.materials[1] = scene_linear(1e6, 5e5, 0.5, 1000);
  s.model.materials[2] = scene_linear(2e6, 1e6, 0.3, 3000);
  fixed_floor(s.model, n, 2);
  jittered_grid(s.model, n, layers, 1.0, 1.0, 17);
  s.model.settings.gravity = {0, 0, -9.81};
  s.model.settings.damping.kind = DampKind::Local;
  s.model.settings.damping.local = 0.3;
  return s;
}

// Hertz-Mindlin with restitution in a held FCC block, the time step estimated every cycle.
inline Scene hertz_block(int n) {
  Scene s = fcc_compression(n, n, n);
  s.name = "Hertz-Mindlin with restitution";
  s.cycles = 200;
  Material m;
  m.shear_modulus = 2.9e10; m.poisson = 0.2; m.density = 2650; m.friction = 0.3;
  m.has_restitution = true; m.restitution = 0.7;
  s.model.materials[1] = m;
  s.model.settings.fixed_dt = 0;
  return s;
}

// Rayleigh damping (mass and stiffness parts) on a loose polydisperse cloud with friction.
inline Scene rayleigh_cloud(int n) {
  Scene s{"Rayleigh damping", {}, 200};
  s.model.materials[1] = scene_linear(1e6, 7e5, 0.4, 1000);
  jittered_grid(s.model, n, n, 0, 3.0, 23);
  s.model.settings.damping.kind = DampKind::Rayleigh;
  s.model.settings.damping.alpha = 0.5;
  s.model.settings.damping.beta = 1e-3;
  return s;
}

// A frictional polydisperse cloud in a periodic cell of edge n straining in all six components,
// the cell already sheared: the xy tilt starts just below half an edge, so that the cell renames
// its images during the run, and balls cross every face, the shifted ones included.
inline Scene sheared_periodic(int n, int cycles) {
  Scene s{"sheared periodic cell", {}, cycles};
  s.model.space.periodic = true;
  s.model.started = true;
  s.model.space.lo = {-0.5, -0.5, -0.5};
  s.model.space.hi = {n - 0.5, n - 0.5, n - 0.5};
  s.model.space.tilt = {0.5 * n - 0.01, 0.3, -0.2};
  s.model.materials[1] = scene_linear(1e6, 7e5, 0.4, 1000);
  jittered_grid(s.model, n, n, 0, 3.0, 29);
  update_mass(s.model);
  set_all_strain_rates(s.model, {1e-3, -1e-3, 2e-3, -0.05, 0.01, -0.01});
  return s;
}

// Ball data and touching contacts, for bitwise comparison.
struct Picture {
  std::vector<std::vector<double>> balls;                       // every real per-ball array
  std::map<std::pair<std::int64_t, std::int64_t>, std::vector<double>> contacts;   // touching only
  std::int64_t cycle = 0;
  double time = 0, dt = 0, critical_dt = 0;
};

// The model with its balls in id order in memory (to compare states whose order differs).
inline Model in_id_order(Model m) {
  std::vector<std::size_t> order(m.balls.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::sort(order.begin(), order.end(), [&](std::size_t p, std::size_t q) { return m.balls.id[p] < m.balls.id[q]; });
  reorder_balls(m, order);
  return m;
}

inline Picture picture(const Model& m) {
  Picture p;
  const Balls& b = m.balls;
  for (const auto* v : {&b.x, &b.y, &b.z, &b.vx, &b.vy, &b.vz, &b.wx, &b.wy, &b.wz, &b.fx, &b.fy, &b.fz, &b.mx, &b.my,
                        &b.mz})
    p.balls.push_back(*v);
  const ContactTable& c = m.contacts;
  for (std::size_t q = 0; q < c.size(); ++q) {
    if (c.state[q] == 0) continue;
    std::vector<double> row;
    for (const auto* v : {&c.nx, &c.ny, &c.nz, &c.overlap, &c.fn, &c.fx, &c.fy, &c.fz, &c.tx, &c.ty, &c.tz, &c.fsx,
                          &c.fsy, &c.fsz, &c.kn_eff, &c.ks_eff, &c.cn_eff, &c.work_friction, &c.work_damping})
      row.push_back((*v)[q]);
    row.push_back(c.state[q]);
    p.contacts[{b.id[c.i[q]], b.id[c.j[q]]}] = row;
  }
  p.cycle = m.cycle; p.time = m.time; p.dt = m.dt; p.critical_dt = m.critical_dt;
  return p;
}

inline bool same_bits(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0);
}

// Empty when equal bit for bit, else what differs first.
inline std::string difference(const Picture& a, const Picture& b) {
  const char* names[] = {"x", "y", "z", "vx", "vy", "vz", "wx", "wy", "wz", "fx", "fy", "fz", "mx", "my", "mz"};
  for (std::size_t k = 0; k < a.balls.size(); ++k)
    if (!same_bits(a.balls[k], b.balls[k])) return std::string("ball ") + names[k] + " differs";
  if (a.contacts.size() != b.contacts.size())
    return "contact counts differ: " + std::to_string(a.contacts.size()) + " vs " + std::to_string(b.contacts.size());
  for (const auto& [key, row] : a.contacts) {
    auto it = b.contacts.find(key);
    if (it == b.contacts.end()) return "contact " + std::to_string(key.first) + "-" + std::to_string(key.second) + " missing";
    if (!same_bits(row, it->second)) return "contact " + std::to_string(key.first) + "-" + std::to_string(key.second) + " differs";
  }
  if (a.cycle != b.cycle) return "cycle differs";
  if (std::memcmp(&a.time, &b.time, sizeof(double)) || std::memcmp(&a.dt, &b.dt, sizeof(double)) ||
      std::memcmp(&a.critical_dt, &b.critical_dt, sizeof(double)))
    return "time or step differs";
  return {};
}

}  // namespace trubal::test
