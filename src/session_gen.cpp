// GEN: the balls a Session generates, at random places or by radius expansion to a porosity
// (session.hpp).
#include "session.hpp"
#include "cycle/pipeline.hpp"

#include "support/comm.hpp"

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <cmath>
#include <random>
#include <stdexcept>
#include <unordered_map>
#include <utility>

#include <fmt/format.h>

#include "interp/signals.hpp"
#include "gen/placement_grid.hpp"
#include "gen/region.hpp"
#include "io/save.hpp"
#include "model/edit.hpp"
#include "physics/measure.hpp"

namespace trubal {
namespace {

// GEN's balls numbered in space order: by cells of the largest diameter (rmax the largest radius
// of the model's and the new balls), z slowest, then y, then x (generation order within a cell).
// Balls near in space are then near in number, which the pair lists' cache use and the threaded
// backend's split (contiguous number ranges) depend on. The balls' indices in that order.
std::vector<std::size_t> space_numbering(const Space& s, const std::vector<std::array<double, 4>>& balls, double rmax) {
  const double cell = 2 * rmax;
  struct Placed { std::array<std::int64_t, 3> key; std::size_t k; };   // key: z, y, x cell
  std::vector<Placed> sorted;
  sorted.reserve(balls.size());
  for (std::size_t k = 0; k < balls.size(); ++k) {
    const auto& q = balls[k];
    auto cell_of = [&](int a) { return static_cast<std::int64_t>(std::floor((q[a] - s.lo[a]) / cell)); };
    sorted.push_back({{cell_of(2), cell_of(1), cell_of(0)}, k});
  }
  std::stable_sort(sorted.begin(), sorted.end(), [](const Placed& p, const Placed& q) { return p.key < q.key; });
  std::vector<std::size_t> order(sorted.size());
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = sorted[k].k;
  return order;
}

}  // namespace

bool Session::generates_held() {
  generating_held_ = false;
  if (!hold_balls()) return false;   // (the same on every rank)
  std::int64_t empty = 0;
  comm::on_root([&] { empty = model_.balls.size() == 0 && held_.total == 0 && model_.bonds.empty() ? 1 : 0; },
                "looking at the model before GEN");
  comm::broadcast(empty);
  return generating_held_ = empty != 0;
}

void Session::keep_generated(const std::vector<std::array<double, 4>>& balls, const std::vector<int>& types,
                             const std::vector<std::size_t>& order) {
  last_generated_.clear();
  if (generating_held_) {   // (rank 0 alone: held on every rank by hand_out_generated)
    generated_.clear();
    generated_.reserve(order.size());
    for (std::size_t k : order)
      generated_.push_back({balls[k][0], balls[k][1], balls[k][2], balls[k][3], static_cast<double>(types[k])});
    return;
  }
  Model& m = edit();
  for (std::size_t k : order) {
    const auto& q = balls[k];
    last_generated_.push_back(m.balls.id[trubal::add_ball(m, 0, types[k], q[0], q[1], q[2], q[3])]);
  }
}

void Session::hand_out_generated() {
  if (!std::exchange(generating_held_, false)) return;   // (the same on every rank)
  // Rank 0's balls a chunk at a time to every rank, each holding those its hash picks, numbered
  // as add_ball numbers them; rank 0 alone keeps their ids (PRINT psd reads them there).
  constexpr std::size_t kChunk = std::size_t{1} << 16;
  std::int64_t n = comm::root() ? static_cast<std::int64_t>(generated_.size()) : 0;
  comm::broadcast(n);
  std::vector<double> chunk;
  for (std::size_t lo = 0; lo < static_cast<std::size_t>(n); lo += kChunk) {
    const std::size_t hi = std::min(static_cast<std::size_t>(n), lo + kChunk);
    chunk.clear();
    if (comm::root())
      for (std::size_t k = lo; k < hi; ++k) chunk.insert(chunk.end(), generated_[k].begin(), generated_[k].end());
    comm::broadcast(chunk);
    comm::together([&] {
      for (std::size_t q = 0; q + 5 <= chunk.size(); q += 5) {
        const std::int64_t id = hold_ball(0, static_cast<int>(chunk[q + 4]), chunk[q], chunk[q + 1], chunk[q + 2], chunk[q + 3]);
        if (comm::root()) last_generated_.push_back(id);
      }
    }, "holding the balls GEN made");
  }
  std::vector<std::array<double, 5>>().swap(generated_);
}

std::size_t Session::generate(std::size_t n, double rlo, double rhi, int type, std::uint64_t seed, const Range& range) {
  require_started();
  if (!(rlo > 0) || rhi < rlo) throw std::runtime_error("GEN: radii must satisfy 0 < rlo <= rhi");
  const Space& s = model_.space;
  double rmax = rhi;
  for (double r : model_.balls.rad) rmax = std::max(rmax, r);
  // The periodic cell's rule (CYCLE's): every periodic edge at least twice the largest diameter. A
  // ball far larger than the cell was sought for ever among its own images.
  for (int a = 0; a < 3; ++a)
    if (s.wraps(a) && !(4 * rhi <= s.hi[a] - s.lo[a]))
      throw std::runtime_error(fmt::format("GEN: the periodic edge {} = {:g} is less than twice the largest diameter "
                                           "{:g} (CYCLE would refuse the cell)", "xyz"[a], s.hi[a] - s.lo[a], 2 * rhi));
  const Balls& b = model_.balls;
  PlacementGrid grid(s, rmax, b.size() + n);
  for (std::size_t k = 0; k < b.size(); ++k) grid.insert(b.x[k], b.y[k], b.z[k], b.rad[k]);
  // More balls than the densest packing of the smallest could hold is no run at all: say so at once.
  double share = 1;   // of the places drawn, about how many can fall in the range
  {
    const auto L = s.length();
    const double volume = room_for_centres(s, range, model_.walls, rhi);   // the part the range and the walls leave
    share = std::clamp(volume / (L[0] * L[1] * L[2]), 0.0, 1.0);
    const double most = 0.7405 * volume / (4.0 / 3.0 * M_PI * rlo * rlo * rlo);
    if (static_cast<double>(n) > most)
      throw std::runtime_error(fmt::format(
          "GEN: {} balls of radius {} or more cannot fit in the region (at most {:.3g} even packed as densely as "
          "spheres can be){}", n, rlo, most, radius_unit_hint(rlo, rhi, L)));
  }
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::size_t placed = 0;
  const std::size_t max_tries = 2000 * n + 10000;
  // Give up after this many failed tries in a row (the space is as full as random placing gets), and
  // look at Ctrl-C now and then: GEN keeps what it placed and says how many. A place drawn outside
  // the range is no try (a range in a corner of a large cell misses most draws, and the room left
  // in it is not what they measure), up to kMostDraws draws in all and as many misses in a row as
  // kFailuresInARow tries would take at the range's share of the space (a range that holds no
  // place, by id or type, gives up as soon as before).
  constexpr std::size_t kFailuresInARow = 200000;
  constexpr std::size_t kMostDraws = 1000000000;
  const auto most_misses = static_cast<std::size_t>(static_cast<double>(kFailuresInARow) / std::max(share, 1e-3));
  std::size_t failures = 0, tries = 0, misses = 0;
  gen_interrupted = false;
  std::vector<std::array<double, 4>> made;
  for (std::size_t drawn = 0; placed < n && tries < max_tries && failures < kFailuresInARow && drawn < kMostDraws &&
                              misses < most_misses;
       ++drawn) {
    if ((drawn & 4095) == 0 && interrupt_now()) {
      interrupt_requested() = false;
      gen_interrupted = true;
      break;
    }
    double r = rlo + (rhi - rlo) * unit(rng);
    double p[3];
    for (int a = 0; a < 3; ++a) {
      double lo = s.lo[a] + (s.wraps(a) ? 0 : r), hi = s.hi[a] - (s.wraps(a) ? 0 : r);
      if (hi < lo) throw std::runtime_error("GEN: the balls do not fit in the START box");
      p[a] = lo + (hi - lo) * unit(rng);
    }
    if (!holds(model_, range, {0, type, p[0], p[1], p[2]})) {
      ++misses;
      continue;
    }
    misses = 0;
    ++tries;
    if (!clear_of_walls(model_.walls, {p[0], p[1], p[2]}, r) || grid.overlaps(p[0], p[1], p[2], r)) {
      ++failures;
      continue;
    }
    failures = 0;
    grid.insert(p[0], p[1], p[2], r);
    made.push_back({p[0], p[1], p[2], r});
    ++placed;
  }
  gen_missed_range = placed < n && !gen_interrupted && misses >= most_misses;
  last_sizes_ = SizeDistribution{SizeDistribution::Kind::Uniform, rlo, rhi, rlo, rhi, {}, {}};
  keep_generated(made, std::vector<int>(made.size(), type), space_numbering(s, made, rmax));
  return placed;
}

PackResult Session::generate(const GenSpec& spec) {
  require_started();
  SizeDistribution sizes = spec.sizes;
  check(sizes);
  gen_interrupted = false;
  PackRequest request{sizes, spec.count, spec.porosity, spec.seed, spec.range,
                      spec.types.empty() ? 1 : spec.types.front().first};
  PackResult made = pack(model_, request);
  gen_interrupted = made.interrupted;
  // Types by mass fraction: largest ball first, each to the type furthest below its share of the
  // mass given so far (so every type gets the same grading). Mass at each type's density where PROP
  // has given every one of them one, else by solid volume.
  std::vector<int> type_of(made.balls.size(), spec.types.front().first);
  if (spec.types.size() > 1) {
    std::vector<double> density(spec.types.size(), 1.0);
    bool all = true;
    for (std::size_t t = 0; t < spec.types.size(); ++t) {
      auto it = model_.materials.find(spec.types[t].first);
      if (it == model_.materials.end() || !(it->second.density > 0)) all = false;
      else density[t] = it->second.density;
    }
    if (!all) std::fill(density.begin(), density.end(), 1.0);
    std::vector<double> given(spec.types.size(), 0);
    double total = 0;
    for (std::size_t k = 0; k < made.balls.size(); ++k) {
      const double r = made.balls[k][3], v = r * r * r;
      std::size_t best = 0;
      double most = -INFINITY;
      for (std::size_t t = 0; t < spec.types.size(); ++t) {
        const double mass = density[t] * v;
        const double short_of = spec.types[t].second * (total + mass) - given[t];
        if (short_of > most) { most = short_of; best = t; }
      }
      given[best] += density[best] * v;
      total += density[best] * v;
      type_of[k] = spec.types[best].first;
    }
  }
  // Numbered in space order, as GEN n rlo rhi numbers them.
  double rmax = 0;
  for (double r : model_.balls.rad) rmax = std::max(rmax, r);
  for (const auto& b : made.balls) rmax = std::max(rmax, b[3]);
  last_sizes_ = sizes;
  keep_generated(made.balls, type_of, space_numbering(model_.space, made.balls, rmax));
  return made;
}

std::size_t Session::lattice_fcc(double d, int nx, int ny, int nz, const std::array<double, 3>& origin, int type,
                                 const Range& range, Layers layers) {
  require_started();
  if (!(d > 0)) throw std::runtime_error("LATTICE: the diameter must be positive");
  const bool periodic_x = model_.space.wraps(0), periodic_y = model_.space.wraps(1);
  const double layer = d / std::sqrt(2.0);
  // Sized before it is built: a lattice of 1e15 points would take all memory first.
  constexpr double kMostPoints = 1e8;
  if (static_cast<double>(nx) * ny * nz > kMostPoints)
    throw std::runtime_error(fmt::format("LATTICE: {} x {} x {} = {:.3g} points is more than {:.0e}", nx, ny, nz,
                                         static_cast<double>(nx) * ny * nz, kMostPoints));
  // The lattice's points the range holds, in order, to `f` (twice: checked, then added).
  auto each_point = [&](auto&& f) {
    for (int k = 0; k < nz; ++k) {
      bool odd = k % 2 == 1;
      if ((layers == Layers::Even && odd) || (layers == Layers::Odd && !odd)) continue;
      int mx = odd && !periodic_x ? nx - 1 : nx, my = odd && !periodic_y ? ny - 1 : ny;
      double shift = odd ? 0.5 * d : 0.0;
      for (int j = 0; j < my; ++j)
        for (int i = 0; i < mx; ++i) {
          const double p[3] = {origin[0] + i * d + shift, origin[1] + j * d + shift, origin[2] + k * layer};
          if (holds(model_, range, {0, type, p[0], p[1], p[2]})) f(p);
        }
    }
  };
  const Space& s = model_.space;
  std::size_t count = 0;
  each_point([&](const double* p) {
    for (int a = 0; a < 3; ++a)
      if (!s.wraps(a) && (p[a] < s.lo[a] || p[a] > s.hi[a]))
        throw std::runtime_error(fmt::format("LATTICE: a ball centre ({}, {}, {}) falls outside the START box", p[0],
                                             p[1], p[2]));
    ++count;
  });
  // (Under mpirun in a batch deck every rank runs it, and each keeps the balls its hash picks, as
  // BALL lines: hold_ball.)
  if (hold_balls()) {
    each_point([&](const double* p) { hold_ball(0, type, p[0], p[1], p[2], 0.5 * d); });
    return count;
  }
  Model& m = edit();
  each_point([&](const double* p) { trubal::add_ball(m, 0, type, p[0], p[1], p[2], 0.5 * d); });
  return count;
}

}  // namespace trubal
