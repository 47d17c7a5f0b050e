#include "session.hpp"
#include "cycle/pipeline.hpp"

#include "support/comm.hpp"
#include "support/peak_memory.hpp"

#include <algorithm>
#include <bit>
#include <cstring>
#include <exception>
#include <limits>
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
#include "model/periodic_cell.hpp"
#include "physics/bridge.hpp"
#include "physics/scene.hpp"
#include "physics/cell.hpp"
#include "physics/measure.hpp"

namespace trubal {

// Under mpirun the ranks share the step (BACKEND mpi); otherwise one thread, as TRUBAL.
Session::Session()
    : pipeline_(make_pipeline(comm::size() > 1 ? "mpi" : "serial", 1, 0, &policy_)), history_(std::make_unique<History>()),
      comm_size_(comm::size()) {}

bool Session::distributed() const { return pipeline_->distributed(); }
Session::~Session() = default;

Model& Session::edit() {
  make_results_to_read(model_, *pipeline_);   // of the state before the change
  mark_edited();
  return model_;
}

void Session::mark_changed() {
  ++changes_;
  unsaved_ = true;
  model_.energy_at_step.valid = false;   // the balls may no longer be as the last step left them
  model_.critical_dt = 0;   // masses, stiffnesses or fixities may have changed: the step estimated afresh
}

void Session::mark_edited() {
  mark_changed();
  pipeline_->invalidate();
}

void Session::edit_on_parts() {
  // (Not gathered to rank 0: the step taken again reads the state, so it is taken before it changes.)
  results_onto_parts(model_, *pipeline_);
  pipeline_->clear_deferred();
  pipeline_->search_next_step();
  mark_changed();
}

Model& Session::edit_walls() {
  if (!parts_kept()) return edit();
  edit_on_parts();
  return model_;
}

std::size_t Session::change_balls(const Range& range, const std::function<void(Balls&, std::size_t)>& change,
                                  bool fixities) {
  if (!parts_kept()) {
    const std::vector<std::size_t> selected = select(range);
    Model& m = edit();
    for (std::size_t k : selected) change(m.balls, k);
    return selected.size();
  }
  edit_on_parts();
  // Rank 0's whole model, where it holds the parts' state, changed alike (the others' are hollow).
  if (!pipeline_->whole_hollow(model_) && comm::root())
    for (std::size_t k : select(range)) change(model_.balls, k);
  const std::size_t n = pipeline_->change_balls_on_parts(model_, range, change);
  if (fixities && pipeline_->whole_hollow(model_)) pipeline_->fixities_to_root(model_);
  return n;
}

Model& Session::edit_cell() {
  // Where the ranks keep their parts, as edit_walls: the results made on the parts (of the state
  // before the change) and left there, the next step searching afresh as serial's does.
  if (parts_kept()) {
    edit_on_parts();
    return model_;
  }
  results_before_setting();   // (of the state before the change)
  mark_changed();
  pipeline_->invalidate();
  return model_;
}

void Session::set_cell_rates(const std::array<double, 6>& rates) {
  const bool hollow = pipeline_->others_hollow();
  if (!parts_kept() && !hollow) return set_all_strain_rates(model_, rates);
  // The change on the parts and rank 0's model, or where the others hold no balls on rank 0's alone
  // (before the first CYCLE: the work needs the masses), its work every rank's: a collective call.
  FieldChange field;
  set_all_strain_rates(model_, rates, &field);
  if (hollow && comm::root()) update_mass(model_);
  pipeline_->apply_field_kept(model_, field);
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

bool Session::parts_kept() const { return pipeline_->parts_live(model_); }

void Session::whole_everywhere() {
  light_everywhere();
  pipeline_->share_whole(model_, true);   // (from the light state too: Pipeline::others_hollow)
}

void Session::model_on_zero() {
  light_pending_ = true;
  // The results a CYCLE deferred, of the state before the change, made where every rank agrees
  // (rank 0's edit would make them alone, where every rank holds the whole model a collective call).
  results_before_setting();
  pipeline_->release_parts(model_);   // (where they are kept)
}

void Session::run_on_root(const std::function<void()>& work) {
  if (comm::size() < 2) return work();
  // No part kept (the parts ended in the CYCLE: a ball left the box at one of its last steps), the
  // contact results it deferred are made with every rank (a collective call: make_results_to_read
  // agrees on a failure, and the parts' copies come to rank 0): here, before rank 0 runs alone.
  if (!pipeline_->parts_live(model_) && pipeline_->results_deferred(model_)) make_results_to_read(model_, *pipeline_);
  if (!comm::root()) return pipeline_->serve_root(model_);
  pipeline_->start_requests();
  try {
    work();
  } catch (...) {
    pipeline_->end_requests();
    throw;
  }
  pipeline_->end_requests();
}

void Session::light_everywhere() {
  if (!light_pending_ || comm::size() < 2) return;
  // (Any failure is every rank's: the ranks other than 0 may then hold a part of it, and take the
  // whole model at the next hand-over, which others_hollow asks for.)
  pipeline_->set_others_hollow();
  std::string bytes;
  comm::on_root([&] { bytes = light_state(model_); }, "writing its model for the other ranks");
  comm::broadcast(bytes);
  comm::together([&] {
    if (!comm::root()) {
      take_light_state(model_, bytes);
      centres_.clear();
    }
  }, "taking rank 0's model");
  // The balls' ids, types and radii (the split, the skin and the laws read them on every rank).
  broadcast_ball_names(model_.balls);
  pipeline_->invalidate();
  light_pending_ = false;
  return_free_memory();
}


void Session::results_before_setting() {
  if (!parts_kept()) return make_results_to_read(model_, *pipeline_);
  // (Made on the parts, where the CYCLE deferred them, and gathered to rank 0, and rank 0's whole
  // model with them where it is hollow: rank 0 reads it next.)
  results_onto_parts(model_, *pipeline_);
  pipeline_->gather_part_results(model_);
  pipeline_->refresh_whole(model_);
  comm::on_root([&] { make_results_to_read(model_, *pipeline_); }, "making the contact results");
  // (The next CYCLE takes a copy of its own on every rank, of the new settings, as serial does.)
  pipeline_->clear_deferred();
}

namespace {
// This process's memory figures but its peak, in RankFigures' order after peak_mib.
std::vector<double> own_figures(const Model& model, const Pipeline& pipeline, std::size_t held_bytes) {
  const PipelineCounters c = pipeline.counters();
  constexpr double kMiB = 1 << 20;
  return {static_cast<double>(model.contacts.result_bytes() + pipeline.part_result_bytes_now()) / kMiB,
          c.whole_arrays_mib, c.part_arrays_mib,
          static_cast<double>(array_bytes(model) + pipeline.part_bytes_now() + held_bytes) / kMiB,
          static_cast<double>(pipeline.rescue_bytes()) / kMiB};
}
}  // namespace

void Session::gather_rank_figures() {
  const std::vector<double> peaks = peak_memory_per_rank();
  std::vector<double> all;
  comm::allgather(own_figures(model_, *pipeline_, held_.bytes()), all);
  rank_figures_.assign(peaks.size(), {});
  constexpr std::size_t kOwn = 5;   // (own_figures' count)
  for (std::size_t r = 0; r < rank_figures_.size() && kOwn * r + kOwn - 1 < all.size(); ++r)
    rank_figures_[r] = {peaks[r], all[kOwn * r], all[kOwn * r + 1], all[kOwn * r + 2], all[kOwn * r + 3], all[kOwn * r + 4]};
}

std::vector<Session::RankFigures> Session::rank_figures() const {
  if (comm::size() > 1) return rank_figures_;
  const std::vector<double> f = own_figures(model_, *pipeline_, held_.bytes());
  return {{peak_memory_per_rank()[0], f[0], f[1], f[2], f[3], f[4]}};
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

void Session::check_in_box(double x, double y, double z) const {
  require_started();
  const Space& s = model_.space;
  double p[3] = {x, y, z};
  for (int a = 0; a < 3; ++a)
    if (!s.wraps(a))
      if (p[a] < s.lo[a] || p[a] > s.hi[a])
        throw std::runtime_error(fmt::format("ball centre {} = {} is outside the START box [{}, {}]", "xyz"[a], p[a],
                                             s.lo[a], s.hi[a]));
}

// Two balls at one centre have no normal between them and would be thrown apart: refused.
static std::string centre_taken(std::int64_t id, double x, double y, double z) {
  return fmt::format("ball {} is already at ({}, {}, {}): two balls at one centre would fly apart; give this one "
                     "another centre", id, x, y, z);
}

std::size_t Session::add_ball(std::int64_t id, int type, double x, double y, double z, double rad) {
  check_in_box(x, y, z);
  if (centres_changes_ != changes_) centres_.rebuild(model_.balls);
  if (const std::size_t k = centres_.find(model_.balls, x, y, z); k != CentreIndex::kNone)
    throw std::runtime_error(centre_taken(model_.balls.id[k], x, y, z));
  try {
    const std::size_t at = trubal::add_ball(edit(), id, type, x, y, z, rad);
    centres_.insert(model_.balls, at);
    centres_changes_ = changes_;
    return at;
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(e.what());
  }
}

bool Session::hold_needs_start() const {
  return light_pending_ || parts_kept() || pipeline_->results_deferred(model_);
}

void Session::hold_start() {
  // As model_on_zero, then light_everywhere: every rank holds the model's light state and its
  // balls' ids (the next free id is every rank's to know).
  model_on_zero();
  light_everywhere();
}

std::int64_t Session::add_ball_line(std::int64_t id, int type, double x, double y, double z, double rad) {
  if (!hold_balls()) {
    const std::size_t k = add_ball(id, type, x, y, z, rad);
    return model_.balls.id[k];
  }
  // Every rank runs this for every line, each checking what it holds the facts for, in the order
  // add_ball checks them: the box; a centre taken (rank 0 the model's balls, the keeper the held
  // ones); the ids (every rank knows the largest; rank 0 the model's, the id's checker the held).
  check_in_box(x, y, z);
  const int ranks = comm_size_, me = comm::rank();
  if (me == 0) {
    if (centres_changes_ != changes_) centres_.rebuild(model_.balls);
    if (const std::size_t k = centres_.find(model_.balls, x, y, z); k != CentreIndex::kNone)
      throw std::runtime_error(centre_taken(model_.balls.id[k], x, y, z));
  }
  const int keeper = HeldBalls::keeper(x, y, z, ranks);
  if (keeper == me)
    if (const std::size_t k = held_.centres.find(held_, x, y, z); k != CentreIndex::kNone)
      throw std::runtime_error(centre_taken(held_.id[k], x, y, z));
  if (id > 0 && ((me == 0 && find_ball(model_, id) >= 0) ||
                  (HeldBalls::id_checker(id, ranks) == me && held_.ids.contains(id))))
    throw std::runtime_error("ball id " + std::to_string(id) + " is taken");
  return hold_ball(id, type, x, y, z, rad);
}

std::int64_t Session::hold_ball(std::int64_t id, int type, double x, double y, double z, double rad) {
  const int ranks = comm_size_, me = comm::rank();
  const Balls& b = model_.balls;
  if (id <= 0) {
    const std::int64_t largest = std::max(b.by_id.empty() ? 0 : b.id[b.by_id.back()], held_.max_id);
    if (largest == std::numeric_limits<std::int64_t>::max())
      throw std::runtime_error("no ball id is left after " + std::to_string(largest) +
                               ": give the new ball its id (BALL ... id n)");
    id = largest + 1;
  }
  if (b.size() + held_.total >= std::numeric_limits<std::uint32_t>::max())
    throw std::runtime_error("a model holds at most " + std::to_string(std::numeric_limits<std::uint32_t>::max()) +
                             " balls");
  if (HeldBalls::id_checker(id, ranks) == me) held_.ids.insert(id);
  if (HeldBalls::keeper(x, y, z, ranks) == me) held_.add(held_.total, id, type, x, y, z, rad);
  ++held_.total;
  held_.max_id = std::max(held_.max_id, id);
  // What an edit marks (no results are deferred: hold_start made them), and what add_ball sets;
  // rank 0's index of the model's centres stays current.
  const bool centres_current = centres_changes_ == changes_;
  mark_edited();
  if (centres_current) centres_changes_ = changes_;
  model_.order.pending = true;
  return id;
}

std::exception_ptr Session::gather_held(
    const std::function<void(std::int64_t, int, double, double, double, double)>& take) {
  // The lines a chunk at a time: each rank sends its balls of the chunk (seven numbers each, the
  // integers by their bits), rank 0 puts them in the lines' order and takes them.
  constexpr std::uint64_t kChunk = std::uint64_t{1} << 18;
  constexpr std::size_t kRecord = 7;
  auto bits = [](std::int64_t v) { return std::bit_cast<double>(v); };
  auto integer = [](double v) { return std::bit_cast<std::int64_t>(v); };
  std::exception_ptr failure;
  std::size_t next = 0;
  std::vector<double> mine, all;
  std::vector<std::uint32_t> at;
  for (std::uint64_t lo = 0; lo < held_.total; lo += kChunk) {
    const std::uint64_t hi = std::min(held_.total, lo + kChunk);
    mine.clear();
    for (; next < held_.size() && held_.line[next] < hi; ++next)
      for (double v : {bits(static_cast<std::int64_t>(held_.line[next])), bits(held_.id[next]),
                       static_cast<double>(held_.type[next]), held_.x[next], held_.y[next], held_.z[next],
                       held_.rad[next]})
        mine.push_back(v);
    comm::gather_to_root(mine, all);
    if (!comm::root() || failure) continue;
    try {
      at.assign(hi - lo, ~std::uint32_t{0});
      for (std::size_t r = 0; r + kRecord <= all.size(); r += kRecord)
        at[static_cast<std::uint64_t>(integer(all[r])) - lo] = static_cast<std::uint32_t>(r / kRecord);
      for (std::uint32_t q : at) {
        if (q == ~std::uint32_t{0}) throw std::logic_error("internal error: a held ball's line is missing");
        const double* v = &all[kRecord * q];
        take(integer(v[1]), static_cast<int>(v[2]), v[3], v[4], v[5], v[6]);
      }
    } catch (...) {
      failure = std::current_exception();
    }
  }
  return failure;
}

void Session::place_held() {
  if (held_.total == 0) return;
  // Rank 0 adds them to its model in the lines' order. A failure there (out of memory) stops every
  // rank with its message.
  const std::exception_ptr failure = gather_held([&](std::int64_t id, int type, double x, double y, double z, double rad) {
    trubal::add_ball(model_, id, type, x, y, z, rad);
  });
  held_.clear();
  // (The others take the new balls' ids, types and radii before the next command that is not rank 0's.)
  light_pending_ = true;
  ++changes_;
  pipeline_->invalidate();
  comm::together([&] {
    if (failure) std::rethrow_exception(failure);
  }, "adding the BALL lines' balls to the model");
  return_free_memory();
}

void Session::place_held_as_parts() {
  if (held_.total == 0) return;
  light_everywhere();   // (the others' materials give their parts' masses)
  // Where the space wraps an axis, a ball outside the cell would be wrapped before the first search
  // (Pipeline::prepare): rank 0 places them in its model then. (A collective call on every rank.)
  bool wraps = false;
  for (int a = 0; a < 3; ++a) wraps = wraps || model_.space.wraps(a);
  bool outside_here = false;
  if (wraps) outside_here = outside_cell(model_.space, held_.x, held_.y, held_.z, 0, held_.x.size());
  const bool outside = comm::any_all(outside_here);
  // (The same answer on every rank: each holds the model's light state and its balls' ids.)
  if (!(pipeline_->distributed() && comm_size_ > 1 && model_.balls.size() == 0 && model_.bonds.empty() && !outside &&
        !parts_kept()))
    return place_held();
  // Rank 0 takes the balls' ids, types, radii and centres in the lines' order (their fixities
  // none), checks them as a CYCLE does, where it can, and puts them in space order where the CYCLE's first step would;
  // for each rank it notes the whole model's index of each ball the rank keeps, in its order.
  const bool sorts = sort_due(model_);
  Balls& b = model_.balls;
  std::exception_ptr failure = gather_held([&](std::int64_t id, int type, double x, double y, double z, double rad) {
    b.id.push_back(id);
    b.type.push_back(type);
    b.fixed.push_back(0);
    b.rad.push_back(rad);
    b.x.push_back(x);
    b.y.push_back(y);
    b.z.push_back(z);
  });
  const int ranks = comm_size_;
  std::vector<std::vector<std::uint32_t>> kept(static_cast<std::size_t>(ranks));
  std::int64_t checked = 1;
  comm::together([&] {
    if (failure) std::rethrow_exception(failure);
    if (!comm::root()) return;
    b.index_ids();
    // A ball or type the CYCLE will refuse: the balls are placed on rank 0 instead, and the CYCLE
    // says why, as serially (after reading its own words).
    try {
      check_ready(model_);
      for (std::size_t k = 0; k < b.size(); ++k) {
        const BallMass m = ball_mass(model_, b.type[k], b.rad[k]);
        if (!ball_mass_problem(b.id[k], m.mass, m.inertia, b.rad[k]).empty()) throw std::runtime_error("");
      }
    } catch (const std::runtime_error&) {
      checked = 0;
      return;
    }
    const std::vector<std::size_t> order = sorts ? sort_in_space_order(model_) : std::vector<std::size_t>{};
    std::vector<std::uint32_t> at(b.size());   // each line's index
    for (std::size_t k = 0; k < at.size(); ++k) at[order.empty() ? k : order[k]] = static_cast<std::uint32_t>(k);
    for (std::uint32_t k : at) kept[HeldBalls::keeper(b.x[k], b.y[k], b.z[k], ranks)].push_back(k);
  }, "placing the BALL lines' balls in the ranks' parts");
  comm::broadcast(checked);
  if (checked == 0) {
    if (comm::root()) {
      b.for_each_array([](auto& v) { std::decay_t<decltype(v)>().swap(v); });
      b.by_id.clear();
    }
    return place_held();
  }
  if (sorts) model_.order.pending = false;
  // Each rank learns the whole model's index of each of its balls, and takes their ids, types and
  // radii in the whole model's order.
  std::vector<std::uint32_t> mine;
  if (comm::root()) {
    for (int r = 1; r < ranks; ++r) comm::send_bytes(r, kept[r].data(), kept[r].size() * sizeof(std::uint32_t));
    mine = std::move(kept[0]);
  } else {
    mine.resize(held_.size());
    comm::receive_bytes(0, mine.data(), mine.size() * sizeof(std::uint32_t));
  }
  std::vector<std::vector<std::uint32_t>>().swap(kept);
  broadcast_ball_names(b);
  std::vector<double> records;
  records.reserve(BrickStep::kRecord * held_.size());
  for (std::size_t q = 0; q < held_.size(); ++q)
    for (double v : {static_cast<double>(mine[q]), std::bit_cast<double>(held_.id[q]), static_cast<double>(held_.type[q]),
                     held_.x[q], held_.y[q], held_.z[q], held_.rad[q]})
      records.push_back(v);
  held_.clear();
  std::vector<std::uint32_t>().swap(mine);
  ++changes_;
  pipeline_->parts_from_records(model_, records);
}

bool Session::deletes_held() {
  deleting_held_ = false;
  if (!hold_balls() || held_.total == 0) return false;   // (the same on every rank)
  std::int64_t alone = 0;
  comm::on_root([&] { alone = model_.balls.size() == 0 && model_.bonds.empty() ? 1 : 0; },
                "looking at the model before DELETE");
  comm::broadcast(alone);
  return deleting_held_ = alone != 0;
}

std::size_t Session::delete_held(const Range& range) {
  light_everywhere();   // (the groups a range reads, every rank's)
  // This rank's held balls where the range holds; their lines and ids to every rank.
  auto bits = [](std::int64_t v) { return std::bit_cast<double>(v); };
  auto integer = [](double v) { return std::bit_cast<std::int64_t>(v); };
  HeldBalls& h = held_;
  std::vector<std::uint8_t> gone(h.size(), 0);
  std::vector<double> mine, all;
  comm::together([&] {
    for (std::size_t k = 0; k < h.size(); ++k)
      if (holds(model_, range, {h.id[k], h.type[k], h.x[k], h.y[k], h.z[k]})) {
        gone[k] = 1;
        mine.push_back(bits(static_cast<std::int64_t>(h.line[k])));
        mine.push_back(bits(h.id[k]));
      }
  }, "deleting the held balls");
  comm::allgather(mine, all);
  mark_edited();   // (as serial's DELETE, which edits whether or not a ball goes)
  const std::size_t removed = all.size() / 2;
  if (removed == 0) return 0;
  std::vector<std::uint64_t> lines(removed);
  std::vector<std::int64_t> ids(removed);
  for (std::size_t q = 0; q < removed; ++q) {
    lines[q] = static_cast<std::uint64_t>(integer(all[2 * q]));
    ids[q] = integer(all[2 * q + 1]);
  }
  std::vector<double>().swap(all);
  std::sort(lines.begin(), lines.end());
  std::sort(ids.begin(), ids.end());
  std::int64_t largest = 0;
  comm::together([&] {
    // The rest in their order, each line less the lines gone before it (the lines stay 0, 1, ...).
    std::size_t w = 0;
    for (std::size_t k = 0; k < h.size(); ++k) {
      if (gone[k]) continue;
      const auto before = std::lower_bound(lines.begin(), lines.end(), h.line[k]) - lines.begin();
      h.line[w] = h.line[k] - static_cast<std::uint64_t>(before);
      h.id[w] = h.id[k];
      h.type[w] = h.type[k];
      h.x[w] = h.x[k];
      h.y[w] = h.y[k];
      h.z[w] = h.z[k];
      h.rad[w] = h.rad[k];
      largest = std::max(largest, h.id[w]);
      ++w;
    }
    for (auto* v : {&h.x, &h.y, &h.z, &h.rad}) v->resize(w);
    h.line.resize(w);
    h.id.resize(w);
    h.type.resize(w);
    h.centres.rebuild(h);
    h.ids.erase_all(ids);
    for (auto& [name, members] : model_.groups)
      std::erase_if(members, [&](std::int64_t id) { return std::binary_search(ids.begin(), ids.end(), id); });
  }, "deleting the held balls");
  h.total -= removed;
  // The next free id follows the largest left, as serial's DELETE leaves it.
  std::vector<double> most{bits(largest)}, every;
  comm::allgather(most, every);
  h.max_id = 0;
  for (double v : every) h.max_id = std::max(h.max_id, integer(v));
  return removed;
}

std::size_t Session::delete_balls(const Range& range) {
  require_started();
  if (deleting_held_) return delete_held(range);
  // Where the ranks keep their parts (every rank runs DELETE then: commands/delete.cpp): on the
  // parts, the results the CYCLE deferred made there first; a bonded model's on rank 0's whole
  // model, the parts' state given to it first (Session::model_on_zero), as before.
  if (parts_kept()) {
    if (bonds_agreed_empty()) {
      edit_on_parts();
      return pipeline_->delete_on_parts(model_, range);
    }
    model_on_zero();
    std::int64_t n = 0;
    comm::on_root([&] {
      std::vector<bool> remove(model_.balls.size(), false);
      for (auto k : select(range)) remove[k] = true;
      n = static_cast<std::int64_t>(remove_balls(edit(), remove));
    }, "deleting the balls");
    comm::broadcast(n);
    return static_cast<std::size_t>(n);
  }
  std::vector<bool> remove(model_.balls.size(), false);
  for (auto k : select(range)) remove[k] = true;
  return remove_balls(edit(), remove);
}

std::size_t Session::make_bonds(const Range& range, const BondSpec& spec) {
  require_started();
  const std::vector<std::size_t> selected = select(range);
  // The balls are where the last step left them: their energies stand, with the new bonds' (at zero).
  const EnergyAtStep energy = model_.energy_at_step;
  const std::size_t made = add_bonds(edit(), selected, spec);
  model_.energy_at_step = energy;
  return made;
}

std::size_t Session::delete_bonds(const Range& range) {
  require_started();
  const std::vector<std::size_t> selected = select(range);
  return trubal::delete_bonds(edit(), selected);
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

void Session::set_material(int type, const Material& material) {
  if (!parts_kept()) {
    Model& m = edit();
    m.materials[type] = material;
    m.contacts.use_history(laws_with_history(m));
    return;
  }
  // (The parts take the materials, and their balls' masses from them, at the next CYCLE's start, as
  // serial's does; the laws' history parts at each step.)
  edit_on_parts();
  model_.materials[type] = material;
  model_.contacts.use_history(laws_with_history(model_));
}

std::vector<std::int64_t> Session::platen_choice(const Range& range, PlatenBalls& rows) {
  std::vector<std::int64_t> ids;
  if (parts_kept()) {
    results_onto_parts(model_, *pipeline_);   // (the balls' forces of the last step, where deferred)
    ids = pipeline_->ids_on_parts(model_, range);
    rows = pipeline_->platens_on_parts(ids);
    return ids;
  }
  results_on_root();
  comm::on_root([&] {
    const std::vector<std::size_t> selected = select(range);
    const Model& m = model();
    for (std::size_t k : selected) ids.push_back(m.balls.id[k]);
    std::sort(ids.begin(), ids.end());   // (as the parts give them: a save's bytes the same)
    rows = platen_balls_of(m, selected);
  }, "choosing the platen balls");
  return ids;
}

std::size_t Session::define_group(const std::string& name, const Range& range) {
  require_started();
  std::vector<std::int64_t> ids;
  if (parts_kept()) {
    results_onto_parts(model_, *pipeline_);   // (as below: on the parts, which keep them)
    ids = pipeline_->ids_on_parts(model_, range);
  } else {
    make_results_to_read(model_, *pipeline_);   // groups are state the step taken again puts back: before the change
    for (auto k : select(range)) ids.push_back(model_.balls.id[k]);
    std::sort(ids.begin(), ids.end());   // (a group's ids are kept ascending)
  }
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
                           bool defer_results, bool keep_parts) {
  light_everywhere();   // (a CYCLE of the python module's: not through the interpreter)
  // (Where the ranks do not split the model, each steps all of it: rank 0 hands it over. Where they
  // do, the ranks other than 0 take their parts from rank 0: CycleRun.)
  if (!pipeline_->distributed()) pipeline_->share_whole(model_);
  ++changes_;   // the balls move
  centres_.clear();   // (the next BALL makes it again)
  unsaved_ = true;
  require_started();
  check_ready(model_);
  // (The ranks' parts keep theirs, and rank 0 sets the others' at the split: CycleRun.)
  if ((!(parts_kept() || pipeline_->others_hollow()) || comm::root()) && !pipeline_->whole_hollow(model_)) update_mass(model_);
  interrupt_requested() = false;
  CycleControl control;
  control.interrupt = &interrupt_requested();
  control.progress = progress;
  control.keep_parts = keep_parts && comm::size() > 1;
  control.defer_results = defer_results;
  const double vol = stress_volume();
  const bool histories = !history_->tables().empty();
  VtkSeries* dumps = dumps_ && dumps_->every() > 0 ? dumps_.get() : nullptr;
  const bool moving_cell = !(volume > 0) && model_.space.periodic;   // STRAIN and SERVO change it
  // The histories' volume at a step: the cell's as it is then, where it moves.
  auto volume_at = [vol, moving_cell](const Model& m) {
    const auto L = m.space.length();
    return moving_cell ? L[0] * L[1] * L[2] : vol;
  };
  if (histories || dumps)
    control.after_step = [this, volume_at, histories, dumps](const Model& m) {
      if (histories) history_->sample(m, volume_at(m));
      if (dumps && dumps->due(m.cycle)) dumps->write(m);
    };
  // (The rows rank 0 recorded since: share_rows hands them on. Rows every rank recorded on the
  // parts move the marks past them.)
  auto marks = std::make_shared<std::vector<std::size_t>>(history_->recorded());
  if (histories && comm::size() > 1) control.share_output = [this, marks] { history_->share_rows(*marks); };
  // Histories of sums alone and dumps, where the ranks keep their parts: every rank records the
  // histories from the sums merged over the parts, and the dumps' rows come to rank 0 from the parts
  // in order (dump_from_parts): rank 0 is not handed the whole model for them. Dumps beside a
  // history that reads the whole model go by after_step, which records the rows on rank 0
  // (share_rows hands them on).
  const bool on_parts = control.keep_parts && pipeline_->distributed() && (!histories || history_->recorded_on_parts());
  const bool dumps_on_parts = dumps && on_parts;
  if (histories && dumps && !dumps_on_parts) control.reads_whole = [dumps](std::int64_t cycle) { return dumps->due(cycle); };
  if (on_parts && (histories || dumps_on_parts))
    control.after_step_on_parts = [this, volume_at, marks, histories, dumps_on_parts, dumps](const Model& m) {
      if (histories) {
        HistorySums sums;
        sums.stress = [this, &m] { return pipeline_->stress_on_parts(m); };
        sums.contacts = [this, &m] { return pipeline_->contact_sums_on_parts(m); };
        sums.ball = [this](std::int64_t id, std::size_t count, const HistorySums::BallRead& read) {
          return pipeline_->ball_on_parts(id, count, read);
        };
        sums.sphere = [this, &m](const MeasureSphere& s) { return pipeline_->sphere_on_parts(m, s); };
        sums.platens = [this](const std::vector<std::int64_t>& ids) { return pipeline_->platens_on_parts(ids); };
        sums.bonds = [this] { return pipeline_->bond_counts_on_parts(); };
        sums.bridges = [this, &m] {
          const Pipeline::PartCounts c = pipeline_->part_counts(m);
          return c.bridges + c.wall_bridges;
        };
        history_->sample_on_parts(m, volume_at(m), sums);
        *marks = history_->recorded();
      }
      if (dumps_on_parts && dumps->due(m.cycle)) dump_from_parts(*dumps, m);
    };
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
  // The same files again continue their collection; other files start a new one. (Every rank keeps
  // the schedule: a CYCLE's steps that dump make their results on every rank alike.)
  if (!dumps_ || dumps_->base() != VtkSeries(base).base()) dumps_ = std::make_unique<VtkSeries>(base, every);
  else dumps_->set_every(every);
  // The dump now, rank 0's to write from its whole model (under mpirun the others may hold their
  // parts, or the model's light state alone: OnRanks::Parts).
  if (comm::size() == 1) {
    make_results_to_read(model_, *pipeline_);
    return dumps_->write(model_);
  }
  // Where the ranks' kept parts alone hold the model, the rows come to rank 0 from them (the
  // results made there first where the CYCLE deferred them): rank 0 is not handed the whole model.
  if (pipeline_->whole_hollow(model_)) {
    results_onto_parts(model_, *pipeline_);
    if (pipeline_->results_on_parts(model_)) return dump_from_parts(*dumps_, model_);
  }
  results_on_root();   // (with every rank: made on the parts where they are kept, and gathered)
  comm::on_root([&] { dumps_->write(model_); }, "writing the dump");
}

namespace {
// A dump's balls and lines from the ranks' kept parts (Pipeline::vtk_ball_rows, ...): each pass a
// collective call, rank 0 writing.
class PartRows final : public VtkRows {
 public:
  PartRows(const Model& model, Pipeline& pipeline) : model_(model), pipeline_(pipeline) {}
  bool writes() const override { return comm::root(); }
  std::uint64_t lines() override { return pipeline_.part_counts(model_).touching; }
  void ball_rows(const Take& take) override { pipeline_.vtk_ball_rows(take); }
  void line_rows(const Take& take) override { pipeline_.vtk_line_rows(model_, take); }

 private:
  const Model& model_;
  Pipeline& pipeline_;
};
}  // namespace

void Session::dump_from_parts(VtkSeries& dumps, const Model& model) {
  // A bonded model's bonds' file reads rank 0's bond table and the balls' centres: its bonds'
  // state and the centres gathered there (24 bytes a ball), let go after.
  const bool bonded = !bonds_agreed_empty();
  Balls& b = model_.balls;
  const bool centres_held = b.x.size() == b.size();   // (rank 0's hollow model holds none)
  // (Let go whatever happens: a hollow model holds no centres, Pipeline::hollow.)
  auto let_go = [&] {
    if (bonded && !centres_held)
      for (auto* v : {&b.x, &b.y, &b.z}) std::vector<double>().swap(*v);
  };
  PartRows rows(model, *pipeline_);
  try {
    if (bonded) pipeline_->bonds_and_centres_to_root(model_);
    // (Every pass runs on every rank whatever failed: a failure, rank 0's writing, is every rank's.)
    comm::together([&] { dumps.write(model, &rows); }, "writing the dump");
  } catch (...) {
    let_go();
    throw;
  }
  let_go();
}

bool Session::bonds_agreed_empty() const {
  std::int64_t empty = model_.bonds.empty() ? 1 : 0;
  comm::broadcast(empty);   // (rank 0's answer: the others may not hold the bonds)
  return empty != 0;
}

CycleResult Session::cycle_in_chunks(std::int64_t limit, std::int64_t chunk,
                                     const std::function<void(std::int64_t, std::int64_t)>& progress,
                                     const std::function<bool()>& stop, bool on_parts) {
  CycleResult out;
  std::int64_t done = 0;
  CycleResult worst;   // the chunk whose energy balance was off the most (its warning is the run's, once)
  while (done < limit) {
    std::int64_t n = std::min(chunk, limit - done);
    CycleResult r = cycle(n, progress ? [&](std::int64_t d, std::int64_t) { progress(done + d, limit); }
                                      : std::function<void(std::int64_t, std::int64_t)>{},
                          on_parts, on_parts);
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
  // Under mpirun each CYCLE of 100 keeps the ranks' parts (as CYCLE does: no rank handed the whole
  // model, nor the model split again), and the ratio's sums are made on them, every rank taking
  // part (the last step taken again there where its results were deferred); where the parts ended
  // (a ball left the box) every rank holds the whole model and rank 0's answer is every rank's.
  const bool on_parts = pipeline_->distributed() && comm_size_ > 1;
  out.run = cycle_in_chunks(limit, 100, progress, [&] {
    if (on_parts && parts_kept()) {
      results_onto_parts(model_, *pipeline_);
      out.ratio = pipeline_->contact_sums_on_parts(model_).unbalanced_ratio().mean_ratio;
    } else {
      out.ratio = unbalanced_force(on_parts ? model() : model_).mean_ratio;
    }
    return out.converged = out.ratio < ratio;
  }, on_parts);
  return out;
}

Session::UntilResult Session::cycle_until(std::int64_t limit, const std::function<double(const Model&)>& measure,
                                          double target, bool driven, std::int64_t every,
                                          const std::function<void(std::int64_t, std::int64_t)>& progress) {
  UntilResult out;
  // (Rank 0 reads; the others serve it, their parts kept, and take its value: every rank stops at
  // the same cycle.)
  auto measured = [&] {
    std::vector<double> value{0.0};
    run_on_root([&] { value[0] = measure(model_); });
    comm::broadcast(value);
    return value[0];
  };
  out.start = out.value = measured();
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
  const bool on_parts = pipeline_->distributed() && comm_size_ > 1;
  out.run = cycle_in_chunks(limit, every, progress, [&] {
    const double before = out.value;
    out.value = measured();
    still = out.value == out.start ? still + 1 : 0;
    away = driven && std::abs(out.value - target) > std::abs(before - target) ? away + 1 : 0;
    out.stalled = still >= kChecks;
    out.receding = away >= kChecks;
    return (out.reached = reached()) || out.stalled || out.receding;
  }, on_parts);
  return out;
}

namespace {
// The results made on the ranks' parts (results_onto_parts), an array at a time, for rank 0's SAVE
// while the others serve it (Pipeline::request_result_array).
class PartResults final : public ResultSource {
 public:
  PartResults(Model& model, Pipeline& pipeline) : model_(model), pipeline_(pipeline) {}
  void fetch(std::size_t k, std::vector<std::uint8_t>& into) override {
    pipeline_.request_result_array(model_, k, nullptr, &into);
  }
  void fetch(std::size_t k, std::vector<double>& into) override { pipeline_.request_result_array(model_, k, &into, nullptr); }
  std::int64_t cycle() const override { return model_.cycle; }

 private:
  Model& model_;
  Pipeline& pipeline_;
};
}  // namespace

const Model& Session::model_for_bonds() const {
  if (!pipeline_->serving() || !pipeline_->whole_hollow(model_)) return model();
  pipeline_->request_bonds(model_);
  return model_;
}

const Model& Session::model_but_results() const {
  if (!pipeline_->serving()) return model();
  pipeline_->request_results_onto_parts(model_);   // (the balls' unbalanced forces are made with them)
  if (!results_from_parts()) return model();
  pipeline_->request_whole(model_);   // (gathered from the parts where a CYCLE left it hollow)
  return model_;
}

Sym6 Session::average_stress_in(double volume) const {
  if (pipeline_->serving() && pipeline_->whole_hollow(model_)) return pipeline_->request_stress(model_).over(volume);
  return average_stress(model(), volume);
}

ContactSums Session::whole_contact_sums() const {
  if (pipeline_->serving() && pipeline_->whole_hollow(model_)) return pipeline_->request_contact_sums(model_);
  return contact_sums(model());
}

SphereMeasurement Session::measure_in(const MeasureSphere& sphere) const {
  check_measure_sphere(model_.space, sphere, 0);   // (a radius that is not positive: before any request)
  if (pipeline_->serving() && pipeline_->whole_hollow(model_)) return pipeline_->request_sphere(model_, sphere);
  return measure_sphere(model(), sphere);
}

Session::StateCounts Session::state_counts() const {
  if (pipeline_->serving() && pipeline_->whole_hollow(model_)) {
    const Pipeline::PartCounts c = pipeline_->request_part_counts(model_);
    return {c.touching, c.wall_touching, c.bridges, c.wall_bridges, c.flags()};
  }
  const Model& m = model_but_results();
  StateCounts n;
  n.touching = touching_pairs();
  for (auto st : m.wall_contacts.state) n.wall_touching += st != 0;
  n.bridges = count_bridges(m.contacts);
  n.wall_bridges = count_bridges(m.wall_contacts);
  return n;
}

const std::vector<double>& Session::ball_array(const std::vector<double>& of, std::vector<double>& into) const {
  if (!(pipeline_->serving() && pipeline_->whole_hollow(model_))) return of;
  std::size_t k = 0, at = ~std::size_t{0};
  model_.balls.for_each_array([&](const auto& v) {
    if (static_cast<const void*>(&v) == &of) at = k;
    ++k;
  });
  if (at == ~std::size_t{0}) throw std::logic_error("internal error: not one of the balls' arrays");
  into.clear();
  pipeline_->request_stream(model_, 0, at, [&](const std::vector<double>& chunk) { into.insert(into.end(), chunk.begin(), chunk.end()); });
  return into;
}

bool Session::rows_from_parts() const {
  if (!(pipeline_->serving() && pipeline_->whole_hollow(model_))) return false;
  pipeline_->request_results_onto_parts(model_);   // (the balls' unbalanced forces are made with them)
  return pipeline_->whole_hollow(model_);
}

void Session::ball_rows(const std::function<void(const double*)>& take, const Range& range) const {
  pipeline_->request_ball_rows(model_, take, range);
}

void Session::contact_rows(bool bridges, const std::function<void(const double*)>& take, const Range& range) const {
  pipeline_->request_contact_rows(model_, bridges, take, range);
}

LargestOverlap Session::largest_overlap_now() {
  if (pipeline_->whole_hollow(model_)) return pipeline_->largest_overlap_on_parts(model_, kOverlapWarning);
  return largest_overlap(model_);
}

std::size_t Session::touching_pairs() const {
  if (!results_from_parts()) return contact_count(model());
  std::vector<std::uint8_t> fetched;
  const std::vector<std::uint8_t>& state = results_of(model_.contacts.state, fetched);
  return static_cast<std::size_t>(std::count_if(state.begin(), state.end(), [](std::uint8_t s) { return s != 0; }));
}

bool Session::results_from_parts() const { return pipeline_->serving() && pipeline_->results_on_parts(model_); }

template <class T> const std::vector<T>& Session::fetch_results(const std::vector<T>& of, std::vector<T>& into) const {
  if (model_.contacts.results_kept() || !results_from_parts()) return of;
  const int k = model_.contacts.result_index(&of);
  if (k < 0) throw std::logic_error("internal error: not one of the contact table's result arrays");
  if constexpr (std::is_same_v<T, double>) pipeline_->request_result_array(model_, static_cast<std::size_t>(k), &into, nullptr);
  else pipeline_->request_result_array(model_, static_cast<std::size_t>(k), nullptr, &into);
  return into;
}

const std::vector<double>& Session::results_of(const std::vector<double>& of, std::vector<double>& into) const {
  return fetch_results(of, into);
}

const std::vector<std::uint8_t>& Session::results_of(const std::vector<std::uint8_t>& of,
                                                     std::vector<std::uint8_t>& into) const {
  return fetch_results(of, into);
}

namespace {
// The state of the ranks' kept parts where rank 0's whole model is hollow, streamed to rank 0's
// SAVE a chunk at a time while the others serve it (Pipeline::request_stream).
class PartState final : public StateSource {
 public:
  PartState(Model& model, Pipeline& pipeline) : model_(model), pipeline_(pipeline) {}
  std::uint64_t place_pairs() override { return pipeline_.request_place_pairs(model_); }
  std::uint64_t place_walls() override { return pipeline_.request_place_walls(model_); }
  void stream(Table table, std::size_t k, const std::function<void(const std::vector<double>&)>& write) override {
    pipeline_.request_stream(model_, static_cast<int>(table), k, write);
  }
  std::int64_t results_cycle() const override { return pipeline_.results_on_parts(model_) ? model_.cycle : -1; }

 private:
  Model& model_;
  Pipeline& pipeline_;
};
}  // namespace

void Session::save(const std::string& path) const {
  // (The results made on the parts go into the file from there, an array at a time: rank 0 never
  // holds them all, and the parts keep them for what reads them next.)
  if (pipeline_->serving()) {
    pipeline_->request_results_onto_parts(model_);
    // Rank 0's whole model hollow: the parts' state streamed into the file, a chunk at a time (a
    // bonded model's bonds from rank 0's table, their state gathered into it first).
    if (pipeline_->whole_hollow(model_)) {
      if (!model_.bonds.empty()) pipeline_->request_bonds(model_);
      PartState state(model_, *pipeline_);
      try {
        save_model(model_, path, history_.get(), 0, nullptr, &state);
      } catch (...) {
        pipeline_->request_free_saved();
        throw;
      }
      pipeline_->request_free_saved();
      unsaved_ = false;
      return;
    }
    pipeline_->request_whole(model_);   // (gathered from the parts where a CYCLE left it hollow)
  }
  if (results_from_parts()) {
    PartResults results(model_, *pipeline_);
    save_model(model_, path, history_.get(), 0, &results);
  } else {
    save_model(model(), path, history_.get());
  }
  unsaved_ = false;
}

std::vector<std::string> Session::restart(const std::string& path) {
  auto histories = std::make_unique<History>();
  Model loaded;
  std::unique_ptr<SavedTables> saved;   // (rank 0's, where the parts are made from the file)
  std::int64_t from_file = 0;           // 1: the parts are made from it; 2: with the contact results
  if (comm_size_ < 2) {
    loaded = load_model(path, histories.get());
  } else {
    // Rank 0 alone reads the file, a buffer at a time. Where the ranks' parts can be made from it
    // (SavedTables::why_whole), it reads and checks all of it but the bulk, and each rank then
    // takes its part of the bulk from it a piece at a time (Pipeline::parts_from_file): no rank
    // holds the whole model. Else rank 0 holds the model and the others take its light state and
    // the balls' ids, types and radii (light_everywhere), as after a command rank 0 ran alone; a
    // CYCLE then sends each rank its part. A file refused is refused on every rank, the model kept.
    const bool parts_may = pipeline_->distributed() && pipeline_->policy().local_rule >= 0;
    comm::on_root([&] {
      if (parts_may) {
        saved = std::make_unique<SavedTables>(path, histories.get());
        if (saved->why_whole().empty()) saved->check(policy_.save_piece_rows);
        else saved.reset();
      }
      if (saved) from_file = saved->rows(PieceTable::Pairs) > 0 ? 2 : 1;
      else loaded = load_model(path, histories.get());
    }, "reading the save file");
    comm::broadcast(from_file);
    std::string bytes;
    comm::on_root([&] { bytes = history_bytes(*histories); }, "writing its histories for the other ranks");
    comm::broadcast(bytes);
    comm::together([&] {
      if (!comm::root()) take_history_bytes(*histories, bytes);
    }, "taking rank 0's histories");
    // The model it replaces goes, its parts unsynced (nothing of it is read again).
    pipeline_->drop_parts_unsynced(model_);
    if (saved) loaded = saved->take_model();
    light_pending_ = true;
  }
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
  light_everywhere();   // (under mpirun: the others' light state; a collective call)
  if (from_file > 0) {
    try {
      pipeline_->parts_from_file(model_, saved.get(), from_file == 2);
    } catch (const std::exception& e) {
      // (Every rank's: the model is gone, its balls part way to the parts.)
      model_ = Model{};
      history_->clear();
      throw std::runtime_error(fmt::format("'{}': the ranks could not take their parts of it: {}; no model is left: "
                                           "RESTART again", path, e.what()));
    }
  }
  return history_->resume_files(model_.cycle);
}

}  // namespace trubal
