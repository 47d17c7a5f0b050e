#include "cycle/pipeline.hpp"
#include "cycle/pipeline_parts.hpp"

#include <algorithm>
#include <array>
#include <stdexcept>
#include <bit>
#include <chrono>
#include <cstdint>
#include <exception>
#include <mutex>
#include <utility>

#include <fmt/format.h>

#include "cycle/pair_list.hpp"
#include "cycle/run.hpp"
#include "cycle/sum_exchange.hpp"
#include "cycle/wall_list.hpp"
#include "support/comm.hpp"
#include "model/wall_shape.hpp"
#include "model/periodic_cell.hpp"
#include "physics/bridge.hpp"
#include "physics/timestep.hpp"
#include "support/format_number.hpp"
#include "support/peak_memory.hpp"

namespace trubal {
namespace {

// Fewer balls than this are tested (outside the cell, displacement) on one thread: waking workers
// costs more.
constexpr std::size_t kParallelBalls = 8192;

// The threads share the steps in space (one part of the decomposition each, cycle/brick_step.hpp)
// where the model has at least kSpaceBalls balls and a split of the balls by numbers into one
// contiguous range per thread would leave at least kSpaceCross of the pairs across two ranges:
// balls numbered far from their places (read from another program's file in random order), which
// the split by numbers shares badly (each such pair is computed twice, its balls scattered). A part
// copies its balls, so smaller scenes and well numbered ones keep the split by numbers. The two
// bounds are not tuned: they were measured only at the extremes (the peers' settle scene, numbered
// at random, half its pairs across, where the split by numbers was no faster than one thread and
// the split in space was; doc/speed.md "Threads and the numbering of the balls").
constexpr std::size_t kSpaceBalls = 4096;
constexpr double kSpaceCross = 0.25;
// From kSpaceLarge balls on, the threads share in space however well the balls are numbered: each
// part's balls, pairs and sums are then compact arrays of its own, which was faster on the dense
// FCC block at 108,000 balls and no slower at 13,500, the only two sizes measured (bench/NOTES.md,
// "Threads in space from 50,000 balls"). Such steps are not timed against one thread (below, in
// step()). Up to kSpaceLargeMax balls: beyond, the parts' copies (about 0.8 KB a ball more) are the
// larger cost, and a million balls should stay within about 1 GiB on the threads as they do
// serially (doc/speed.md "Memory").
constexpr std::size_t kSpaceLarge = 50000, kSpaceLargeMax = 500000;
bool large_in_space(std::size_t balls) { return balls >= kSpaceLarge && balls < kSpaceLargeMax; }

}  // namespace

Pipeline::Pipeline(std::unique_ptr<Backend> backend, int threads, StepPolicy* policy)
    : own_policy_(policy ? nullptr : std::make_unique<StepPolicy>()),
      policy_(policy ? policy : own_policy_.get()),
      backend_(std::move(backend)),
      pool_(threads > 0 ? threads : default_threads(backend_->name())),
      step_(*policy_) {
  comm_ranks_ = comm::size();
  if (backend_->distributed() && comm_ranks_ > 1) mode_ = StepMode::Ranks;
  const int members = distributed() ? 1 : pool_.size();
  for (int t = 0; t < members; ++t) bricks_.push_back(std::make_unique<BrickStep>(*policy_));
  if (members > 1) {
    thread_team_ = std::make_unique<ThreadTeam::Shared>(members);
    member_times_.resize(members);
    for (int t = 0; t < members; ++t) {
      thread_members_.push_back(std::make_unique<ThreadTeam>(*thread_team_, t));
      bricks_[t]->set_team(*thread_members_[t]);
      solo_pools_.push_back(std::make_unique<ThreadPool>(1));
    }
  }
}

bool Pipeline::threads_in_space(const Model& model) {
  if (distributed() || bricks_.size() < 2 || !backend_->keeps_list()) return false;
  const int rule = policy_->split_rule;
  if (rule != 0) return rule > 0;
  const ContactTable& c = model.contacts;
  if (space_verdict_.model == &model && space_verdict_.list_version == c.list_version) return space_verdict_.in_space;
  space_verdict_ = {&model, c.list_version, false};
  const std::size_t n = model.balls.size();
  if (n < kSpaceBalls || c.size() == 0) return false;
  if (large_in_space(n)) return space_verdict_.in_space = true;
  const int parts = static_cast<int>(bricks_.size());
  std::vector<std::uint16_t> range(n);   // (BACKEND allows up to 4096 threads)
  for (int t = 0; t < parts; ++t)
    for (std::size_t k = split_point(n, parts, t); k < split_point(n, parts, t + 1); ++k) range[k] = static_cast<std::uint16_t>(t);
  std::size_t cross = 0;
  for (std::size_t p = 0; p < c.size(); ++p) cross += range[c.i[p]] != range[c.j[p]];
  space_verdict_.in_space = static_cast<double>(cross) >= kSpaceCross * static_cast<double>(c.size());
  return space_verdict_.in_space;
}

void Pipeline::invalidate() {
  for (auto& part : bricks_) part->drop();
  ref_.invalidate();
  list_ = ListState::Unchecked;
  list_from_parts_ = false;
  model_ = nullptr;
  whole_next_ = false;   // (a step rewind_step asked for that never came: every rank decides afresh)
  search_next_step_ = false;
  walls_next_step_ = false;
}

bool Pipeline::any_outside(const Model& model) {
  const std::size_t n = model.balls.size();
  ThreadPool& pool = pool_now();
  const int parts = pool.size();
  partial_.assign(parts, 0.0);
  pool.run([&](int t) {
    partial_[t] = outside_cell(model, split_point(n, parts, t), split_point(n, parts, t + 1)) ? 1.0 : 0.0;
  }, n >= kParallelBalls);
  return std::any_of(partial_.begin(), partial_.end(), [](double m) { return m != 0; });
}

bool Pipeline::needs_rebuild(const Model& model) {
  // The last step measured the displacements as it moved the balls: read once.
  const bool known = list_ == ListState::Measured;
  if (known) list_ = ListState::Unchecked;
  if (model_ != &model) return true;
  // A list made from the ranks' parts (a sync), or handed over by rank 0, is current: only the index
  // is of an older one (prepare indexes it). Anything else not indexed here was changed outside.
  if ((!scratch_.fits(model.contacts, model.balls.size()) || !scratch_.fits_walls(model.wall_contacts, model.balls.size())) &&
      !(distributed() && list_from_parts_))
    return true;
  // A ball and a wall each moving half the skin can just close the gap of a candidate.
  if (!(wall_travel_ <= 0.5 * ref_.skin())) return true;
  const double limit2 = ref_.displacement_limit2(model);
  if (!(limit2 >= 0)) return true;
  if (known) return !(step_.moved2() <= limit2);
  // (A distributed run's rank other than 0 that holds no reference positions: rank 0 decides.)
  if (ref_.x.size() != model.balls.size()) return true;
  const Balls& b = model.balls;
  const std::size_t n = b.size();
  ThreadPool& pool = pool_now();
  const int parts = pool.size();
  partial_.assign(parts, 0.0);
  pool.run([&](int t) { partial_[t] = ref_.max_displacement2(b, split_point(n, parts, t), split_point(n, parts, t + 1)); },
            n >= kParallelBalls);
  double moved2 = 0;
  for (double m : partial_) moved2 = std::max(moved2, m);   // a max is exact in any order
  return !(moved2 <= limit2);
}

void Pipeline::rebuild(Model& model) {
  const std::size_t n = model.balls.size();
  double skin = 0;   // (none for a backend that keeps no list)
  if (backend_->keeps_list()) skin = list_skin(model);
  else check_periodic_cell(model);
  const double reach = list_reach(model, skin);
  if (list_ == ListState::PartsToSearch) list_ = ListState::Current;   // (searched here instead)
  list_from_parts_ = false;
  backend_->find_pairs(model, reach, pool_now(), pairs_);
  auto install = [&] {
    // A backend asked every step mostly finds the list it found before: nothing to carry over then.
    if (backend_->keeps_list() || model_ != &model || !holds_pairs(model.contacts, pairs_)) install_pairs(model.contacts, pairs_);
    if (!scratch_.fits(model.contacts, n)) scratch_.index(model.contacts, n);
    if (!model.walls.empty() || model.wall_contacts.size() > 0) find_wall_contacts(model, reach, pool_now());
    if (!scratch_.fits_walls(model.wall_contacts, n)) scratch_.index_walls(model.wall_contacts, n);
  };
  // (Ranks: one that fails alone, out of memory, must not leave the others in the next collective call.)
  if (distributed()) {
    comm::together(install, "installing the new pair list");
    // The parts rebuild their own lists from here on: the whole search's list goes back.
    pairs_ = PairCandidates{};
  } else {
    install();
  }
  wall_travel_ = 0;
  if (backend_->keeps_list()) ref_.record(model, skin);
  model_ = &model;
}

void Pipeline::sync(Model& model) {
  if (!bricks().live_for(model)) return;
  list_from_parts_ = true;
  each_part([&](BrickStep& part, int) { part.sync(model, &ref_); });
}

void Pipeline::sync_all(Model& model) {
  hand_over_to_hollow(model);
  if (!bricks().live_for(model)) return;
  list_from_parts_ = true;
  each_part([&](BrickStep& part, int) { part.share(model, &ref_); });
}

void Pipeline::end_cycle(Model& model, bool keep_parts) {
  if (!bricks().live_for(model)) return;
  list_from_parts_ = true;
  // (PRINT info: each rank's peak so far, the CYCLE's included, the results it may make after not)
  if (distributed()) cycle_peaks_ = peak_memory_per_rank();
  if (keep_parts && parts_live(model)) {
    // Nothing gathered: rank 0's whole model goes hollow, gathered again where a command reads it
    // (refresh_whole). Not where it holds the last step's results, which an observer's sync
    // gathered from the parts (they let theirs go): it keeps them, made current.
    std::int64_t results_here = comm::root() && model.contacts.size() > 0 && model.contacts.results_kept() &&
                                model.contacts.results_cycle == model.cycle;
    comm::broadcast(results_here);
    if (results_here != 0) {
      each_part([&](BrickStep& part, int) { part.sync(model, &ref_, true); });
      return;
    }
    each_part([&](BrickStep& part, int) { part.end_on_parts(model); });
    hollow_whole(model);   // (what the pipeline keeps of it)
    return;
  }
  share_whole(model);
}

void Pipeline::gather_part_results(Model& model) {
  if (!results_on_parts(model)) return;   // (the same answer on every rank)
  refresh_whole(model);   // (the table they go into: rank 0's list)
  each_part([&](BrickStep& part, int) { part.gather_results(model); });
  // (As make_results leaves a CYCLE's deferred results: made, and the next CYCLE takes a copy of its own.)
  clear_deferred();
  release_rescue();
  ++results_gathered_;
  return_free_memory();
}

namespace {
// What rank 0 asks of the others while it runs a command alone (Pipeline::serve_root).
enum RootRequest : std::int64_t {
  kCommandEnded = 0, kGatherResults = 1, kResultArray = 2, kOntoParts = 3, kWhole = 4, kCounts = 5,
  kPlacePairs = 7, kPlaceWalls = 8, kStream = 9, kFreeSaved = 10, kBallRows = 11, kContactRows = 12, kStress = 13,
  kContactSums = 14, kSphere = 15, kBonds = 16
};
}  // namespace

void Pipeline::request_part_results(Model& model) {
  std::int64_t word = kGatherResults;
  comm::broadcast(word);
  results_onto_parts(model, *this);
  gather_part_results(model);
}

void Pipeline::request_results_onto_parts(Model& model) {
  if (!results_to_make_on_parts(model)) return;   // (rank 0's answer, the same on every rank)
  std::int64_t word = kOntoParts;
  comm::broadcast(word);
  results_onto_parts(model, *this);
}

void Pipeline::request_result_array(Model& model, std::size_t k, std::vector<double>* reals,
                                    std::vector<std::uint8_t>* bytes) {
  request_whole(model);   // (the table they go into: rank 0's list)
  std::int64_t word = kResultArray, array = static_cast<std::int64_t>(k);
  comm::broadcast(word);
  comm::broadcast(array);
  results_onto_parts(model, *this);
  bricks().gather_result_array(model, k, reals, bytes);
}

Pipeline::PartCounts Pipeline::part_counts(const Model& model) {
  if (!parts_live(model)) return {};
  std::vector<double> all;
  comm::allgather(bricks().own_counts(), all);
  std::array<double, 7> sum{};
  for (std::size_t k = 0; k < all.size(); ++k) sum[k % sum.size()] += all[k];   // (integers: exact in any order)
  auto count = [](double v) { return static_cast<std::size_t>(v); };
  return {count(sum[0]), count(sum[1]), count(sum[2]), count(sum[3]), count(sum[4]), count(sum[5]), count(sum[6])};
}

LargestOverlap Pipeline::largest_overlap_on_parts(const Model& model, double threshold) {
  if (!parts_live(model)) return largest_overlap(model, threshold);
  std::vector<double> all;
  comm::allgather(bricks().own_largest_overlap(model, threshold), all);
  constexpr std::size_t kEach = 9;   // (BrickStep::own_largest_overlap's count)
  LargestOverlap out;
  const double* best = nullptr;
  for (std::size_t r = 0; r + kEach <= all.size(); r += kEach) {
    const double* v = all.data() + r;
    out.beyond += static_cast<std::size_t>(v[4]);
    if (v[4] == 0) continue;
    // The largest ratio; of equal ones, the first in the whole model's order (pairs, then walls).
    if (!best || v[0] > best[0] ||
        (v[0] == best[0] && std::lexicographical_compare(v + 5, v + kEach, best + 5, best + kEach)))
      best = v;
  }
  if (best) {
    out.ratio = best[0];
    out.ball = static_cast<std::int64_t>(best[1]);
    out.other = static_cast<std::int64_t>(best[2]);
    out.wall = best[3] != 0;
  }
  return out;
}

namespace {
// Each rank's sums merged over the ranks, exactly (every rank given the total): `each(sums, sum,
// count)` visits a Sums' exact sums, then its counts and largest values, in one order.
template <class Sums, class Each> Sums merged_over_ranks(Sums own, Each each) {
  std::vector<double> mine, all;
  each(own, [&](ExactSum& e) { pack(e, mine); }, [&](double& v) { mine.push_back(v); });
  comm::allgather(mine, all);
  Sums total;
  const double* in = all.data();
  for (std::size_t r = 0; r < all.size() / mine.size(); ++r) {
    Sums rank_sums;
    each(rank_sums, [&](ExactSum& e) { unpack(e, in); }, [&](double& v) { v = *in++; });
    total.add(rank_sums);
  }
  return total;
}
}  // namespace

StressSums Pipeline::stress_on_parts(const Model& model) {
  if (!parts_live(model)) return stress_sums(model);
  return merged_over_ranks(bricks().own_stress(model), [](StressSums& s, auto&& sum, auto&&) {
    for (ExactSum& e : s.s) sum(e);
  });
}

ContactSums Pipeline::contact_sums_on_parts(const Model& model) {
  if (!parts_live(model)) return contact_sums(model);
  return merged_over_ranks(bricks().own_contact_sums(), [](ContactSums& s, auto&& sum, auto&& count) {
    s.each_sum(sum);
    for (double* v : {&s.unbalanced_max, &s.touching, &s.sliding, &s.contacts, &s.free_balls}) count(*v);
  });
}

SphereMeasurement Pipeline::sphere_on_parts(const Model& model, const MeasureSphere& sphere) {
  if (!parts_live(model)) return measure_sphere(model, sphere);
  return sphere_measurement(model.space, sphere,
                            merged_over_ranks(bricks().own_sphere_sums(model, sphere), [](SphereSums& s, auto&& sum, auto&& count) {
                              s.each_sum(sum);
                              s.each_count(count);
                            }));
}

std::optional<ContactMoments> Pipeline::servo_reading_on_parts(Model& model) {
  if (!whole_hollow(model)) return std::nullopt;   // (the same answer on every rank)
  results_onto_parts(model, *this);
  if (!results_on_parts(model)) {
    // Parts that hold no results: where nothing on any of them touches and no bridge holds (their
    // lists searched since any step: parts made from held balls, Pipeline::parts_from_records),
    // the reading is of no force and no stiffness, as serial's after its search.
    return comm::any_all(!bricks().part_touches_nothing()) ? std::nullopt : std::optional<ContactMoments>(ContactMoments{});
  }
  const StressSums force = stress_on_parts(model);
  struct Stiffness {
    std::array<ExactSum, 3> s;
    void add(const Stiffness& o) {
      for (int a = 0; a < 3; ++a) s[a].add(o.s[a]);
    }
  };
  const Stiffness stiffness = merged_over_ranks(Stiffness{bricks().own_servo_stiffness()}, [](Stiffness& k, auto&& sum, auto&&) {
    for (ExactSum& e : k.s) sum(e);
  });
  return table_moments(force.s, stiffness.s);
}

namespace {
// Rank 0's side of a reading the ranks make together where it serves them: the word (and `extra`,
// the reading's arguments) to every rank, the results the CYCLE deferred made on the parts, then
// read() (Pipeline::serve_root, the others' side).
template <class Read> auto request_reading(Model& model, Pipeline& pipeline, std::int64_t word, Read&& read,
                                           std::vector<double> extra = {}) {
  comm::broadcast(word);
  if (!extra.empty()) comm::broadcast(extra);
  results_onto_parts(model, pipeline);
  return read();
}
}  // namespace

ContactSums Pipeline::request_contact_sums(Model& model) {
  return request_reading(model, *this, kContactSums, [&] { return contact_sums_on_parts(model); });
}

StressSums Pipeline::request_stress(Model& model) {
  return request_reading(model, *this, kStress, [&] { return stress_on_parts(model); });
}

Pipeline::PartCounts Pipeline::request_part_counts(Model& model) {
  return request_reading(model, *this, kCounts, [&] { return part_counts(model); });
}

SphereMeasurement Pipeline::request_sphere(Model& model, const MeasureSphere& sphere) {
  return request_reading(model, *this, kSphere, [&] { return sphere_on_parts(model, sphere); },
                         {sphere.centre[0], sphere.centre[1], sphere.centre[2], sphere.radius});
}

std::uint64_t Pipeline::request_place_pairs(Model& model) {
  if (!whole_hollow(model)) throw std::logic_error("internal error: pairs streamed where rank 0's whole model holds them");
  std::int64_t word = kPlacePairs;
  comm::broadcast(word);
  return bricks().place_saved_pairs(bricks().results_left());
}

std::uint64_t Pipeline::request_place_walls(Model& model) {
  if (!whole_hollow(model)) throw std::logic_error("internal error: wall contacts streamed where rank 0's whole model holds them");
  std::int64_t word = kPlaceWalls;
  comm::broadcast(word);
  return bricks().place_saved_walls();
}

void Pipeline::request_stream(Model& model, int table, std::size_t k,
                              const std::function<void(const std::vector<double>&)>& write) {
  if (!whole_hollow(model)) throw std::logic_error("internal error: a table streamed where rank 0's whole model holds it");
  std::int64_t word = kStream, which = table * 1024 + static_cast<std::int64_t>(k);
  comm::broadcast(word);
  comm::broadcast(which);
  bricks().stream_table(table, k, write);
}

void Pipeline::request_ball_rows(Model& model, const std::function<void(const double*)>& take, const Range& range) {
  if (!whole_hollow(model)) throw std::logic_error("internal error: balls streamed where rank 0's whole model holds them");
  std::int64_t word = kBallRows;
  comm::broadcast(word);
  std::vector<double> numbers = range_numbers(range);
  comm::broadcast(numbers);
  bricks().stream_ball_rows(take, &model, &range);
}

void Pipeline::request_contact_rows(Model& model, bool bridges, const std::function<void(const double*)>& take,
                                    const Range& range) {
  if (!whole_hollow(model)) throw std::logic_error("internal error: contacts streamed where rank 0's whole model holds them");
  std::int64_t word = kContactRows, flag = bridges ? 1 : 0;
  comm::broadcast(word);
  comm::broadcast(flag);
  std::vector<double> numbers = range_numbers(range);
  comm::broadcast(numbers);
  bricks().stream_contact_rows(bridges, take, &model, &range);
}

void Pipeline::fixities_to_root(Model& model) {
  if (!whole_hollow(model)) throw std::logic_error("internal error: fixities streamed where rank 0's whole model holds them");
  std::size_t k = 0, fixed = 0;
  model.balls.for_each_array([&](const auto& v) {
    if (static_cast<const void*>(&v) == static_cast<const void*>(&model.balls.fixed)) fixed = k;
    ++k;
  });
  std::size_t at = 0;
  bricks().stream_table(0, fixed, [&](const std::vector<double>& chunk) {
    for (double v : chunk) model.balls.fixed.at(at++) = static_cast<std::uint8_t>(v);
  });
}

void Pipeline::request_free_saved() {
  std::int64_t word = kFreeSaved;
  comm::broadcast(word);
  bricks().free_saved();
}

void Pipeline::request_bonds(Model& model) {
  std::int64_t word = kBonds;
  comm::broadcast(word);
  bricks().bonds_to_root(model);
}

void Pipeline::request_whole(Model& model) {
  if (!whole_to_refresh(model)) return;   // (rank 0's answer, which the others follow)
  std::int64_t word = kWhole;
  comm::broadcast(word);
  refresh_whole(model);
}

void Pipeline::end_requests() {
  if (!serving_) return;
  serving_ = false;
  std::int64_t word = kCommandEnded;
  comm::broadcast(word);
}

void Pipeline::serve_root(Model& model) {
  for (;;) {
    std::int64_t word = -1;
    comm::broadcast(word);
    if (word == kCommandEnded) return;
    std::int64_t array = 0;
    if (word == kResultArray || word == kStream || word == kContactRows) comm::broadcast(array);
    else if (word != kGatherResults && word != kOntoParts && word != kWhole && word != kCounts && word != kPlacePairs &&
             word != kPlaceWalls && word != kFreeSaved && word != kBallRows && word != kStress &&
             word != kContactSums && word != kSphere && word != kBonds)
      throw std::logic_error("internal error: rank 0 asked for work this rank does not know");
    Range range;   // (the rows' range: every rank reads it the same, so no failure is one rank's)
    if (word == kBallRows || word == kContactRows) {
      std::vector<double> numbers;
      comm::broadcast(numbers);
      range = range_of_numbers(numbers);
    }
    MeasureSphere sphere;
    if (word == kSphere) {
      std::vector<double> given;
      comm::broadcast(given);
      if (given.size() != 4) throw std::logic_error("internal error: a measurement sphere sent without its four numbers");
      sphere.centre = {given[0], given[1], given[2]};
      sphere.radius = given[3];
    }
    // (A failure here is every rank's, in the collective calls: rank 0's command reports it.)
    try {
      if (word == kBallRows) bricks().stream_ball_rows(nullptr, &model, &range);
      if (word == kContactRows) bricks().stream_contact_rows(array != 0, nullptr, &model, &range);
      if (word == kBallRows || word == kContactRows) continue;
      if (word == kPlacePairs) bricks().place_saved_pairs(bricks().results_left());
      if (word == kPlaceWalls) bricks().place_saved_walls();
      if (word == kFreeSaved) bricks().free_saved();
      if (word == kStream) bricks().stream_table(static_cast<int>(array / 1024), static_cast<std::size_t>(array % 1024), nullptr);
      if (word == kBonds) bricks().bonds_to_root(model);
      if (word == kPlacePairs || word == kPlaceWalls || word == kFreeSaved || word == kStream || word == kBonds) continue;
      if (word == kWhole) {
        refresh_whole(model);
        continue;
      }
      results_onto_parts(model, *this);
      if (word == kCounts) {
        part_counts(model);
        continue;
      }
      if (word == kStress) {
        stress_on_parts(model);
        continue;
      }
      if (word == kContactSums) {
        contact_sums_on_parts(model);
        continue;
      }
      if (word == kSphere) {
        sphere_on_parts(model, sphere);
        continue;
      }
      if (word == kGatherResults) gather_part_results(model);
      else if (word == kResultArray) bricks().gather_result_array(model, static_cast<std::size_t>(array), nullptr, nullptr);
    } catch (const std::exception&) {
    }
  }
}

void Pipeline::refresh_whole(Model& model, bool even_hollow) {
  if (!parts_live(model)) return;   // (the same answer on every rank)
  std::int64_t stale = whole_stale_ ? 1 : 0;
  comm::broadcast(stale);
  whole_stale_ = false;
  if (stale != 0) {
    for (auto& part : bricks_) part->mark_stale();
  } else if (!even_hollow || !bricks().whole_hollow()) {
    return;
  }
  sync(model);
}

void Pipeline::share_whole(Model& model, bool for_command) {
  // (The contact results a step taken again left on the parts are nowhere else: rank 0's first.)
  gather_part_results(model);
  if (others_hollow_ || parts_live(model)) ++(for_command ? hand_overs_ : cycle_hand_overs_);
  hand_over_to_hollow(model);
  refresh_whole(model);   // (rank 0's whole model, where it is hollow and no results came)
  if (!bricks().live_for(model)) return;
  list_from_parts_ = true;
  each_part([&](BrickStep& part, int) { part.share(model, &ref_, distributed()); });
}

void Pipeline::release_parts(Model& model) {
  refresh_whole(model);
  if (!parts_live(model)) return;
  sync(model);
  for (auto& part : bricks_) part->release();
  return_free_memory();
  invalidate();
  others_hollow_ = true;   // (they were hollow while their parts were live)
}

void Pipeline::hand_over_to_hollow(Model& model) {
  if (!others_hollow_) return;
  others_hollow_ = false;
  broadcast_whole(model, &ref_);
}

namespace {
// Whether this process keeps only the light rescue copy (a distributed run's ranks other than 0).
bool light_rescue(bool distributed) { return distributed && comm::size() > 1 && !comm::root(); }
}  // namespace

void Pipeline::take_rescue(Model& model) {
  // The ranks' parts live: each rank keeps a copy of its own part and the light state, and rank 0's
  // whole model, not gathered, holds none of the copy.
  part_rescue_ = parts_live(model) && !policy_->whole_rescue;
  if (part_rescue_) {
    rescue_.take_light(model);
    bricks().keep_copy();
    rescue_wall_travel_ = wall_travel_;
    return;
  }
  bricks().free_copy();
  sync(model);
  if (light_rescue(distributed())) rescue_.take_light(model);
  else rescue_.take(model);
}

void Pipeline::whole_from_part_copies(Model& model) {
  rescue_.restore_light(model);
  bricks().whole_from_copy(model);
}

bool Pipeline::restore_rescue_on_parts(Model& model) {
  if (!part_rescue_ || !parts_live(model) || !bricks().restore_copy_in_place(model)) return false;
  rescue_.restore_light(model);
  wall_travel_ = rescue_wall_travel_;
  list_ = ListState::Unchecked;
  ++copies_on_parts_;
  return true;
}

void Pipeline::rescue_to_root(Model& model) {
  if (!part_rescue_) return;   // (the same answer on every rank)
  // Rank 0's model the copy's state; the others' as they are (they hold the state after the copy's
  // step: make_results_alone takes it again on rank 0 alone). Their light state comes back after.
  Snapshot others_light;
  if (!comm::root()) others_light.take_light(model);
  whole_from_part_copies(model);
  if (!comm::root()) others_light.restore_light(model);
}

bool Pipeline::restore_rescue(Model& model) {
  list_from_parts_ = false;   // (the list put back is the copy's, older than the reference: searched afresh)
  if (part_rescue_) {
    // Every rank's part copy gathered to rank 0's whole model, which rank 0 hands to the others.
    whole_from_part_copies(model);
    broadcast_arrays(model);
    others_hollow_ = false;
    for (auto& part : bricks_) part->drop();
    return false;
  }
  if (!distributed() || comm::size() < 2) return rescue_.restore(model);
  // Rank 0 puts its copy back and hands the arrays to the others, which put the rest back from theirs.
  bool current = false;
  if (comm::root()) current = rescue_.restore(model);
  else rescue_.restore_light(model);
  broadcast_arrays(model);   // (rank 0 decides whether the next step searches: prepare)
  others_hollow_ = false;
  std::int64_t flag = current ? 1 : 0;
  comm::broadcast(flag);
  for (auto& part : bricks_) part->drop();   // (they are of another state)
  return flag != 0;
}

void Pipeline::drop_parts_unsynced(Model& model) {
  for (auto& part : bricks_) {
    if (part->whole_hollow()) part->drop_hollow();
    part->release();
  }
  return_free_memory();
  invalidate();
  others_hollow_ = comm_ranks_ > 1;
  model.contacts.drop_results();
}

void Pipeline::restore_rescue_on_root(Model& model) {
  if (part_rescue_) whole_from_part_copies(model);
  else if (comm::root()) rescue_.restore(model);
  else rescue_.restore_light(model);
  for (auto& part : bricks_) part->release();
  invalidate();
  others_hollow_ = comm_ranks_ > 1;
  broadcast_ball_names(model.balls);   // (the copy's: balls a step destroyed since come back)
}

void Pipeline::apply_field(Model& model, const FieldChange& change) {
  if (!change.any) return;
  if (bricks().live_for(model)) return each_part([&](BrickStep& part, int) { part.apply_field(model, change); });
  if (!others_hollow_ || comm::root()) {
    ExactSum work, gross;
    apply_field_change(model.balls, change, 0, model.balls.size(), nullptr, work, gross);
    model.energy.boundary_work += work.value();
    model.space.gross_work += gross.value();
  }
  if (!others_hollow_) return;
  // Rank 0 alone holds the balls: every rank takes its work.
  std::vector<double> works{model.energy.boundary_work, model.space.gross_work};
  comm::broadcast(works);
  model.energy.boundary_work = works[0];
  model.space.gross_work = works[1];
}

void Pipeline::apply_field_kept(Model& model, const FieldChange& change) {
  if (!change.any || !parts_live(model)) return apply_field(model, change);
  apply_field(model, change);
  if (bricks().whole_hollow()) return;   // (the parts alone hold the balls: gathered from them when read)
  if (comm::root())
    for (std::size_t k = 0; k < model.balls.size(); ++k) {
      double work, gross;   // (summed on the parts)
      apply_field_change(model.balls, change, k, work, gross);
    }
  for (auto& part : bricks_) part->mark_current();
}

void Pipeline::loads_changed(Model& model) {
  if (bricks().live_for(model)) each_part([&](BrickStep& part, int) { part.loads_changed(model); });
}

void Pipeline::reduce_cell_tilt(Model& model) {
  const Space before = model.space;
  if (trubal::reduce_cell_tilt(model) && bricks().live_for(model))
    each_part([&](BrickStep& part, int) { part.reduce_tilt(before); });
}

bool Pipeline::may_be_outside_box(const Model& model) const {
  return !bricks().live_for(model) || bricks().outside_box();
}

void Pipeline::prepare(Model& model, bool parts_may_search) {
  // The whole model is about to be read and changed: the ranks' parts first, then dropped.
  if (bricks().live()) {
    sync_all(model);
    for (auto& part : bricks_) part->drop();
    if (list_ == ListState::Measured) list_ = ListState::Unchecked;   // (not of the parts' steps)
  }
  const auto t0 = std::chrono::steady_clock::now();
  // (The ranks other than 0 holding the balls' ids, types and radii alone: rank 0 wraps and decides.)
  const bool hollow_here = others_hollow_ && !comm::root();
  // The rare wrap itself is serial; the test for it is shared out.
  if (!hollow_here && model.space.periodic && any_outside(model)) wrap_into_cell(model, &ref_.x, &ref_.y, &ref_.z);
  if (others_hollow_ && comm_ranks_ > 1) {
    // Rank 0 alone wrapped (a straining cell's wrap does work on the balls): its energy terms are
    // every rank's, as apply_field hands them on.
    std::vector<double> works{model.energy.boundary_work, model.space.gross_work};
    comm::broadcast(works);
    model.energy.boundary_work = works[0];
    model.space.gross_work = works[1];
  }
  bool search = hollow_here || !backend_->keeps_list() || needs_rebuild(model);
  if (distributed() && comm::size() > 1) {
    // Rank 0 decides: the others' lists take new versions whenever rank 0 hands them over
    // (BrickStep::share, restore_rescue), so their own index would search where rank 0's need not.
    std::int64_t flag = search ? 1 : 0;
    comm::broadcast(flag);
    search = flag != 0;
    if (!search && !hollow_here) {   // (the list is rank 0's, bit for bit: only its index may be of an older version)
      const std::size_t n = model.balls.size();
      if (!scratch_.fits(model.contacts, n)) scratch_.index(model.contacts, n);
      if (!scratch_.fits_walls(model.wall_contacts, n)) scratch_.index_walls(model.wall_contacts, n);
    }
  }
  if (search && distributed() && parts_may_search && !whole_next_ && policy_->local_rule >= 0) {
    // The ranks search on their parts at the split (brick_step), not through the whole model: no
    // rank but 0 then ever holds the whole model's list in a CYCLE. A whole step searches first.
    list_ = ListState::PartsToSearch;
    model_ = &model;
  } else {
    if (search) {
      hand_over_to_hollow(model);   // (the search goes through the whole model on every rank)
      rebuild(model);
    }
    list_ = ListState::Current;
  }
  times_.detect += seconds_since(t0);
}

void Pipeline::rewind_step() {
  // The ranks' parts hold the state after the step, not the one put back. Every rank holds the
  // whole model: each takes that one step on all of it, as serial does (the same bits), so the
  // parts' memory goes back before the results are made (the peak of a read after a CYCLE).
  for (auto& part : bricks_) part->release();
  whole_next_ = true;
  list_ = ListState::Unchecked;   // tested again at the positions put back, as that step did
  wall_travel_ = wall_travel_at_step_;
}

void Pipeline::step(Model& model, const StepKernels& kernels, StepSums& sums) {
  wall_travel_at_step_ = wall_travel_;
  if (std::exchange(whole_next_, false)) {
    // The whole model on the whole pool, on every rank; the mode goes on after this step, but for
    // one thread's verdict, which is the split in space's and not this step's.
    if (mode_ == StepMode::OneThread) mode_ = StepMode::Numbers;
    whole_step(model, kernels, sums);
    move_walls(model, kernels.dt);
    return;
  }
  if (mode_ == StepMode::Ranks) {
    shared_by_ = "the spatial decomposition";
    brick_step(model, kernels, sums);
    move_walls(model, kernels.dt);
    return;
  }
  if (bricks_.size() > 1) {
    // The threads: in space while the parts are live (brick_step decides again at the next list),
    // else as the current list says.
    // (on one thread if the last step was: OneThread holds until a step is shared again)
    const auto t0 = std::chrono::steady_clock::now();   // a trial times the whole step, its search too
    if (!bricks().live_for(model) && !prepared_for(model)) prepare(model);
    if (bricks().live_for(model) || threads_in_space(model)) {
      // In space, or on one thread where sharing it was timed slower (cycle/timed_choice.hpp).
      // (Not timed from kSpaceLarge balls on: each switch between one thread and the parts makes
      // the parts afresh, 0.2 s at 108,000 balls, four times in a trial; and a shared step where
      // one thread would have been faster costs only a few percent, timed_choice.hpp.)
      const bool timed = policy_->split_rule == 0 && policy_->share_rule == 0 &&
                         !large_in_space(model.balls.size());
      const bool in_space = !timed || space_choice_.shared_now(model.balls.size(), pool_.size());
      if (in_space) {
        mode_ = StepMode::Space;
        shared_by_ = "the spatial decomposition, a part per thread";
        brick_step(model, kernels, sums);
      } else {
        mode_ = StepMode::OneThread;
        shared_by_ = kOneThread;
        whole_step(model, kernels, sums);
      }
      if (timed && space_choice_.in_trial())
        space_choice_.record(in_space, seconds_since(t0) * (in_space ? policy_->space_time_scale : 1.0));
      move_walls(model, kernels.dt);
      return;
    }
    mode_ = StepMode::Numbers;
    shared_by_ = "ball numbers";
  }
  whole_step(model, kernels, sums);
  move_walls(model, kernels.dt);
}

void Pipeline::whole_step(Model& model, const StepKernels& kernels, StepSums& sums) {
  hand_over_to_hollow(model);
  if (bricks().live()) prepare(model);   // the parts' state into the whole model, the parts dropped
  // The first step of a CYCLE follows the loop's prepare(): the balls have not moved since.
  if (!prepared_for(model)) prepare(model);
  if (list_ == ListState::PartsToSearch) rebuild(model);   // (a whole step needs the whole list)
  list_ = ListState::Unchecked;
  const bool measure = backend_->keeps_list() && ref_.x.size() == model.balls.size();
  if (kernels.moments) scratch_.ball_moments.resize(model.balls.size());   // the contact loops zero their balls'
  if (kernels.features.stiffness_damping) scratch_.ball_dashpot.resize(model.balls.size());   // (and these)
  if (kernels.features.rolling) scratch_.ball_rolling.resize(model.balls.size());
  step_.run(pool_now(), model, scratch_, kernels, sums, times_, measure ? &ref_ : nullptr);
  if (measure) list_ = ListState::Measured;
}

void Pipeline::move_walls(Model& model, double dt) {
  double most = 0;
  for (Wall& w : model.walls) most = std::max(most, move_wall(w, dt));
  wall_travel_ += most;
}

bool Pipeline::Deferred::same(const Deferred& o) const {
  auto bits = [](double v) { return std::bit_cast<std::uint64_t>(v); };
  return model == o.model && cycle == o.cycle && bits(time) == bits(o.time) &&
         bits(friction_work) == bits(o.friction_work) && bits(damping_work) == bits(o.damping_work) &&
         bits(boundary_work) == bits(o.boundary_work) && bits(kinetic) == bits(o.kinetic);
}

bool Pipeline::Deferred::same_settings(const Settings& s) const {
  auto bits = [](double v) { return std::bit_cast<std::uint64_t>(v); };
  const Settings& t = settings;
  const Damping &a = s.damping, &b = t.damping;
  return bits(s.frac) == bits(t.frac) && bits(s.fixed_dt) == bits(t.fixed_dt) && bits(s.gravity[0]) == bits(t.gravity[0]) &&
         bits(s.gravity[1]) == bits(t.gravity[1]) && bits(s.gravity[2]) == bits(t.gravity[2]) && a.kind == b.kind &&
         bits(a.alpha) == bits(b.alpha) && bits(a.beta) == bits(b.beta) && bits(a.lambda) == bits(b.lambda) &&
         bits(a.freq) == bits(b.freq) && bits(a.local) == bits(b.local);
}

PipelineCounters Pipeline::counters() const {
  return {ref_.rebuilds(),    mode_ == StepMode::Space ? pool_.size() : step_.active(), backend_->keeps_list() ? ref_.skin() : 0.0,
          backend_->pair_tests(), results_made_, results_gathered_, bricks().counts(), cycle_peaks_,
          static_cast<double>(held_whole_) / (1 << 20), static_cast<double>(held_part_) / (1 << 20), hand_overs_,
          cycle_hand_overs_, copies_on_parts_, parts_from_records_, parts_from_saves_};
}

std::vector<std::pair<std::string, std::string>> Pipeline::info() const {
  auto lines = backend_->info();
  if (!shared_by_.empty()) lines.emplace_back("last step shared by", shared_by_);
  if (shared_by_.starts_with("the spatial decomposition"))
    for (auto& line : bricks().info()) lines.push_back(std::move(line));
  if (!cycle_peaks_.empty()) {
    lines.emplace_back("peak memory by the last CYCLE's end",
                       mib_list(cycle_peaks_) + " MiB (per rank; the whole model's list is searched on the parts, so that in a CYCLE "
                               "no rank holds it, but rank 0 where an output step reads the whole model)");
  }
  if (backend_->keeps_list()) {
    lines.emplace_back("pair list skin", format_number(ref_.skin()));
    lines.emplace_back("pair list rebuilds", std::to_string(ref_.rebuilds()));
  }
  if (results_made_ > 0)
    lines.emplace_back("contact results made when read", std::to_string(results_made_) +
                                                             " (a CYCLE's last step taken again, since BACKEND)");
  if (results_gathered_ > 0)
    lines.emplace_back("contact results gathered from the parts", std::to_string(results_gathered_) +
                                                                      " (made there for a command that read them, since BACKEND)");
  const int used = step_.active();
  if (shared_by_ == kOneThread)
    lines.emplace_back("threads used", "1 (the last trial of the split in space found one thread faster: another "
                                       "program busy on a core, or a scene too small to share)");
  else if (mode_ != StepMode::Space && used > 0 && used < pool_.size())
    lines.emplace_back("threads used", std::to_string(used) +
                                           (used > 1 ? " (one per block of 256 balls)"
                                                     : " (the balls fill one block of 256, or sharing the step was "
                                                       "timed no faster: a small scene, or balls near in space far "
                                                       "apart in numbering)"));
  return lines;
}

std::unique_ptr<Pipeline> make_pipeline(std::string_view backend, int threads, std::uint64_t max_memory,
                                        StepPolicy* policy) {
  return std::make_unique<Pipeline>(make_backend(backend, {threads, max_memory, policy ? &policy->fail_search : nullptr}),
                                    threads, policy);
}

}  // namespace trubal
