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

#include <fmt/format.h>

#include "interp/signals.hpp"
#include "gen/placement_grid.hpp"
#include "gen/region.hpp"
#include "io/save.hpp"
#include "model/edit.hpp"
#include "physics/measure.hpp"

namespace trubal {

// Under mpirun the ranks share the step (BACKEND mpi); otherwise one thread, as TRUBAL.
Session::Session()
    : pipeline_(make_pipeline(comm::size() > 1 ? "mpi" : "serial", 1, 0, &policy_)), history_(std::make_unique<History>()) {}
Session::~Session() = default;

Model& Session::edit() {
  make_results_to_read(model_, *pipeline_);   // of the state before the change
  ++changes_;
  unsaved_ = true;
  model_.energy_at_step.valid = false;   // the balls may no longer be as the last step left them
  pipeline_->invalidate();
  model_.critical_dt = 0;   // masses, stiffnesses or fixities may have changed
  return model_;
}

const Model& Session::model_with_masses() {
  make_results_to_read(model_, *pipeline_);
  update_mass(model_);
  return model_;
}

void Session::set_backend(const std::string& name, int threads, std::uint64_t max_memory) {
  auto pipeline = make_pipeline(name, threads, max_memory, &policy_);
  make_results_to_read(model_, *pipeline_);   // the old pipeline holds the copy they are made from
  pipeline_ = std::move(pipeline);
}

void Session::require_started() const {
  if (!model_.started) throw std::runtime_error("no model yet: START one first (START box x0 x1 y0 y1 z0 z1)");
}

void Session::start(const Space& space) {
  Model fresh;
  fresh.space = space;
  fresh.space.reference_volume = space.volume();
  fresh.started = true;
  model_ = std::move(fresh);
  pipeline_->clear_deferred();
  last_sizes_.reset();
  last_generated_.clear();
  ++changes_;
  unsaved_ = true;
  overlap_warned = 0;
  history_->clear();
  dumps_.reset();
  pipeline_->invalidate();
}

void Session::start_box(const std::array<double, 3>& lo, const std::array<double, 3>& hi,
                        const std::array<Outside, 3>& outside, const std::array<bool, 3>& periodic) {
  for (int a = 0; a < 3; ++a)
    if (!(hi[a] > lo[a])) throw std::runtime_error(fmt::format("START box: upper bound must exceed lower bound on axis {}", "xyz"[a]));
  Space space;
  space.lo = lo;
  space.hi = hi;
  space.outside = outside;
  space.periodic = periodic[0] || periodic[1] || periodic[2];
  space.periodic_axis = space.periodic ? periodic : std::array<bool, 3>{true, true, true};
  start(space);
}

void Session::start_periodic(const std::array<double, 3>& length, const std::array<int, 3>& boxes) {
  for (int a = 0; a < 3; ++a)
    if (!(length[a] > 0)) throw std::runtime_error("START: the periodic cell's edge lengths must be positive");
  Space space;
  space.periodic = true;
  space.hi = length;
  space.boxes = boxes;
  start(space);
}

std::size_t Session::add_ball(std::int64_t id, int type, double x, double y, double z, double rad) {
  require_started();
  const Space& s = model_.space;
  double p[3] = {x, y, z};
  for (int a = 0; a < 3; ++a)
    if (!s.wraps(a))
      if (p[a] < s.lo[a] || p[a] > s.hi[a])
        throw std::runtime_error(fmt::format("ball centre {} = {} is outside the START box [{}, {}]", "xyz"[a], p[a],
                                             s.lo[a], s.hi[a]));
  // Two balls at one centre have no normal between them and would be thrown apart: refused.
  auto key = [](double a, double b, double c) {   // -0 and 0 are the same place
    return std::array<double, 3>{a == 0 ? 0.0 : a, b == 0 ? 0.0 : b, c == 0 ? 0.0 : c};
  };
  if (centres_changes_ != changes_) {
    centres_.clear();
    const Balls& b = model_.balls;
    for (std::size_t k = 0; k < b.size(); ++k) centres_.emplace(key(b.x[k], b.y[k], b.z[k]), b.id[k]);
  }
  if (const auto it = centres_.find(key(x, y, z)); it != centres_.end())
    throw std::runtime_error(fmt::format("ball {} is already at ({}, {}, {}): two balls at one centre would fly apart; "
                                         "give this one another centre", it->second, x, y, z));
  try {
    const std::size_t at = trubal::add_ball(edit(), id, type, x, y, z, rad);
    centres_.emplace(key(x, y, z), model_.balls.id[at]);
    centres_changes_ = changes_;
    return at;
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(e.what());
  }
}

std::size_t Session::CentreHash::operator()(const std::array<double, 3>& c) const {
  std::size_t h = 1469598103934665603ull;
  for (double v : c) {
    std::uint64_t bits;
    std::memcpy(&bits, &v, sizeof bits);
    h = (h ^ bits) * 1099511628211ull;
    h ^= h >> 29;
  }
  return h;
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
  // Numbered in space order: by cells of the largest diameter, z slowest, then y, then x (generation
  // order within a cell). Balls near in space are then near in number, which the pair lists' cache
  // use and the threaded backend's split (contiguous number ranges) depend on.
  const double cell = 2 * rmax;
  struct Placed { std::array<std::int64_t, 3> key; std::array<double, 4> ball; };   // key: z, y, x cell
  std::vector<Placed> sorted;
  sorted.reserve(made.size());
  for (const auto& q : made) {
    auto cell_of = [&](int a) { return static_cast<std::int64_t>(std::floor((q[a] - s.lo[a]) / cell)); };
    sorted.push_back({{cell_of(2), cell_of(1), cell_of(0)}, q});
  }
  std::stable_sort(sorted.begin(), sorted.end(), [](const Placed& p, const Placed& q) { return p.key < q.key; });
  Model& m = edit();
  last_sizes_ = SizeDistribution{SizeDistribution::Kind::Uniform, rlo, rhi, rlo, rhi, {}, {}};
  last_generated_.clear();
  for (const auto& [key, q] : sorted)
    last_generated_.push_back(m.balls.id[trubal::add_ball(m, 0, type, q[0], q[1], q[2], q[3])]);
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
  const Space& s = model_.space;
  double rmax = 0;
  for (double r : model_.balls.rad) rmax = std::max(rmax, r);
  for (const auto& b : made.balls) rmax = std::max(rmax, b[3]);
  const double cell = 2 * rmax;
  struct Placed { std::array<std::int64_t, 3> key; std::size_t k; };
  std::vector<Placed> sorted;
  sorted.reserve(made.balls.size());
  for (std::size_t k = 0; k < made.balls.size(); ++k) {
    const auto& q = made.balls[k];
    auto cell_of = [&](int a) { return static_cast<std::int64_t>(std::floor((q[a] - s.lo[a]) / cell)); };
    sorted.push_back({{cell_of(2), cell_of(1), cell_of(0)}, k});
  }
  std::stable_sort(sorted.begin(), sorted.end(), [](const Placed& p, const Placed& q) { return p.key < q.key; });
  Model& m = edit();
  last_sizes_ = sizes;
  last_generated_.clear();
  for (const auto& [key, k] : sorted) {
    const auto& q = made.balls[k];
    last_generated_.push_back(m.balls.id[trubal::add_ball(m, 0, type_of[k], q[0], q[1], q[2], q[3])]);
  }
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
  std::vector<std::array<double, 3>> points;
  for (int k = 0; k < nz; ++k) {
    bool odd = k % 2 == 1;
    if ((layers == Layers::Even && odd) || (layers == Layers::Odd && !odd)) continue;
    int mx = odd && !periodic_x ? nx - 1 : nx, my = odd && !periodic_y ? ny - 1 : ny;
    double shift = odd ? 0.5 * d : 0.0;
    for (int j = 0; j < my; ++j)
      for (int i = 0; i < mx; ++i) {
        std::array<double, 3> p = {origin[0] + i * d + shift, origin[1] + j * d + shift, origin[2] + k * layer};
        if (holds(model_, range, {0, type, p[0], p[1], p[2]})) points.push_back(p);
      }
  }
  const Space& s = model_.space;
  for (const auto& p : points)
    for (int a = 0; a < 3; ++a)
      if (!s.wraps(a) && (p[a] < s.lo[a] || p[a] > s.hi[a]))
        throw std::runtime_error(fmt::format("LATTICE: a ball centre ({}, {}, {}) falls outside the START box", p[0],
                                             p[1], p[2]));
  Model& m = edit();
  for (const auto& p : points) trubal::add_ball(m, 0, type, p[0], p[1], p[2], 0.5 * d);
  return points.size();
}

std::size_t Session::delete_balls(const Range& range) {
  require_started();
  std::vector<bool> remove(model_.balls.size(), false);
  for (auto k : select(range)) remove[k] = true;
  return remove_balls(edit(), remove);
}

Renumbering Session::renumber(RenumberOrder order) {
  require_started();
  const EnergyAtStep energy = model_.energy_at_step;
  const double critical_dt = model_.critical_dt;
  Renumbering r = renumber_balls(edit(), order);
  model_.energy_at_step = energy;   // the same balls, in the same state
  model_.critical_dt = critical_dt;
  for (const auto& t : history_->tables()) {
    for (auto& id : t->platen_ids) id = r.map(id);
    std::sort(t->platen_ids.begin(), t->platen_ids.end());
  }
  for (auto& id : last_generated_) id = r.map(id);
  return r;
}

std::size_t Session::define_group(const std::string& name, const Range& range) {
  make_results_to_read(model_, *pipeline_);   // groups are state the step taken again puts back: before the change
  require_started();
  std::vector<std::int64_t> ids;
  for (auto k : select(range)) ids.push_back(model_.balls.id[k]);
  std::size_t n = ids.size();
  model_.groups[name] = std::move(ids);
  unsaved_ = true;
  return n;
}

double Session::stress_volume() const {
  if (volume > 0) return volume;
  auto L = model_.space.length();
  return L[0] * L[1] * L[2];
}

CycleResult Session::cycle(std::int64_t n, const std::function<void(std::int64_t, std::int64_t)>& progress,
                           bool defer_results) {
  ++changes_;   // the balls move
  unsaved_ = true;
  require_started();
  check_ready(model_);
  update_mass(model_);
  interrupt_requested() = false;
  CycleControl control;
  control.interrupt = &interrupt_requested();
  control.progress = progress;
  control.defer_results = defer_results;
  const double vol = stress_volume();
  const bool histories = !history_->tables().empty();
  VtkSeries* dumps = dumps_ && dumps_->every() > 0 ? dumps_.get() : nullptr;
  const bool moving_cell = !(volume > 0) && model_.space.periodic;   // STRAIN and SERVO change it
  if (histories || dumps)
    control.after_step = [this, vol, histories, dumps, moving_cell](const Model& m) {
      const auto L = m.space.length();
      if (histories) history_->sample(m, moving_cell ? L[0] * L[1] * L[2] : vol);
      if (dumps && dumps->due(m.cycle)) dumps->write(m);
    };
  if (histories && comm::size() > 1)
    control.share_output = [this, marks = history_->recorded()]() mutable { history_->share_rows(marks); };
  control.reads_contacts = [this, histories, dumps](std::int64_t cycle) {
    return (histories && history_->due(cycle)) || (dumps && dumps->due(cycle));
  };
  CycleResult r = run_cycles(model_, *pipeline_, n, control);
  interrupt_requested() = false;
  totals_.cycles += r.done;
  totals_.ball_cycles += static_cast<double>(r.done) * static_cast<double>(model_.balls.size());
  totals_.seconds += r.seconds;
  totals_.times.add(r.times);
  return r;
}

void Session::dump_vtk(const std::string& base, std::int64_t every) {
  require_started();
  // `dump vtk out/tri`: the folder is made if it is not there (rank 0 writes the files).
  const std::filesystem::path folder = std::filesystem::path(base).parent_path();
  // (Agreed before make_results, which may search the pairs: a collective call.)
  comm::together([&] {
    if (!comm::root() || folder.empty()) return;
    std::error_code ec;
    std::filesystem::create_directories(folder, ec);
    if (ec) throw std::runtime_error(fmt::format("cannot make the folder '{}' for the dumps: {}", folder.string(), ec.message()));
  }, "making the dumps' folder");
  // The same files again continue their collection; other files start a new one.
  make_results_to_read(model_, *pipeline_);
  if (!dumps_ || dumps_->base() != VtkSeries(base).base()) dumps_ = std::make_unique<VtkSeries>(base, every);
  else dumps_->set_every(every);
  dumps_->write(model_);
}

CycleResult Session::cycle_in_chunks(std::int64_t limit, std::int64_t chunk,
                                     const std::function<void(std::int64_t, std::int64_t)>& progress,
                                     const std::function<bool()>& stop) {
  CycleResult out;
  std::int64_t done = 0;
  CycleResult worst;   // the chunk whose energy balance was off the most (its warning is the run's, once)
  while (done < limit) {
    std::int64_t n = std::min(chunk, limit - done);
    CycleResult r = cycle(n, progress ? [&](std::int64_t d, std::int64_t) { progress(done + d, limit); }
                                      : std::function<void(std::int64_t, std::int64_t)>{});
    done += r.done;
    const double seconds = out.seconds + r.seconds;
    PhaseTimes times = out.times;
    times.add(r.times);
    if (r.energy_scale > 0 && !(r.balance_error * worst.energy_scale <= worst.balance_error * r.energy_scale))
      worst = r;
    out = r;
    out.done = done;
    out.seconds = seconds;
    out.times = times;
    out.balance_error = worst.balance_error;
    out.energy_scale = worst.energy_scale;
    out.energy_warning = worst.energy_warning;
    // A chunk is often shorter than the engine's progress period: report between chunks too.
    if (progress) progress(done, limit);
    if (r.interrupted || r.unstable || r.left_box) return out;
    // Every rank takes rank 0's answer, so that all stop at the same cycle.
    std::int64_t stopping = stop() ? 1 : 0;
    comm::broadcast(stopping);
    if (stopping) return out;
  }
  return out;
}

Session::SolveResult Session::solve(double ratio, std::int64_t limit,
                                    const std::function<void(std::int64_t, std::int64_t)>& progress) {
  SolveResult out;
  out.run = cycle_in_chunks(limit, 100, progress, [&] {
    out.ratio = unbalanced_force(model_).mean_ratio;
    return out.converged = out.ratio < ratio;
  });
  return out;
}

Session::UntilResult Session::cycle_until(std::int64_t limit, const std::function<double(const Model&)>& measure,
                                          double target, bool driven, std::int64_t every,
                                          const std::function<void(std::int64_t, std::int64_t)>& progress) {
  UntilResult out;
  out.start = out.value = measure(model_);
  // A positive target is reached at or above it, a negative one at or below; 0 from the side the
  // measure starts on.
  const bool rising = target > 0 || (target == 0 && !(out.start > 0));
  auto reached = [&] { return rising ? out.value >= target : out.value <= target; };
  if (reached()) {
    out.reached = true;
    return out;
  }
  // A measure that has not moved at all over kChecks checks has nothing driving it (platens that do
  // not move, a cell that does not strain); a driven one (an axial strain, the time) that went
  // farther from the target at each of kChecks checks is driven the other way. Either way the run
  // stops there rather than cycling to the limit.
  constexpr int kChecks = 10;
  int still = 0, away = 0;
  out.run = cycle_in_chunks(limit, every, progress, [&] {
    const double before = out.value;
    out.value = measure(model_);
    still = out.value == out.start ? still + 1 : 0;
    away = driven && std::abs(out.value - target) > std::abs(before - target) ? away + 1 : 0;
    out.stalled = still >= kChecks;
    out.receding = away >= kChecks;
    return (out.reached = reached()) || out.stalled || out.receding;
  });
  return out;
}

void Session::save(const std::string& path) const {
  save_model(model(), path, history_.get());
  unsaved_ = false;
}

std::vector<std::string> Session::restart(const std::string& path) {
  auto histories = std::make_unique<History>();
  Model loaded = load_model(path, histories.get());
  model_ = std::move(loaded);
  pipeline_->clear_deferred();
  last_sizes_.reset();
  last_generated_.clear();
  ++changes_;
  unsaved_ = false;
  overlap_warned = 0;
  history_ = std::move(histories);
  dumps_.reset();
  pipeline_->invalidate();
  return history_->resume_files(model_.cycle);
}

}  // namespace trubal
