// The step on a part (BrickStep::step), the cell's field and wraps on the parts, and what the
// members report. The decomposition's other files are listed in brick_step_parts.hpp.
#include "cycle/brick_step.hpp"

#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>
#include <iterator>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <utility>

#include <fmt/format.h>

#include "cycle/sum_exchange.hpp"
#include "model/edit.hpp"
#include "model/periodic_cell.hpp"
#include "physics/scene.hpp"
#include "physics/timestep.hpp"
#include "support/comm.hpp"
#include "support/peak_memory.hpp"

namespace trubal {
namespace {

// The cycle's kernels with the part's own pair laws (per ball of the part): every field but `laws`.
void take_kernels(const StepKernels& from, StepKernels& to) {
  to.features = from.features;
  to.estimate = from.estimate;
  to.moments = from.moments;
  to.wall_loads = from.wall_loads;
  to.energies = from.energies;
  to.kinetic = from.kinetic;
  to.dt = from.dt;
  to.dt_prev = from.dt_prev;
  to.dt_mean = from.dt_mean;
  to.beta = from.beta;
  to.alpha = from.alpha;
  to.local = from.local;
  to.gravity = from.gravity;
  to.contacts = from.contacts; to.contacts_full = from.contacts_full; to.contacts_lean = from.contacts_lean;
  to.cross = from.cross;
  to.walls = from.walls; to.walls_full = from.walls_full; to.walls_lean = from.walls_lean;
  to.motion = from.motion; to.motion_full = from.motion_full; to.motion_lean = from.motion_lean;
}

}  // namespace

void apply_field_change(Balls& balls, const FieldChange& change, std::size_t begin, std::size_t end,
                        const std::uint8_t* skip, ExactSum& work, ExactSum& gross) {
  for (std::size_t k = begin; k < end; ++k) {
    double ball_work, ball_gross;
    apply_field_change(balls, change, k, ball_work, ball_gross);
    if (skip && skip[k]) continue;
    work.add(ball_work);
    gross.add(ball_gross);
  }
}

void BrickStep::apply_field(Model& full, const FieldChange& change) {
  ExactSum work, gross;
  apply_field_change(part_.balls, change, 0, part_.balls.size(), scratch_.ghost.data(), work, gross);
  current_ = false;   // the parts' velocities are newer than full's now
  shared_ = false;
  std::vector<double> out, in;
  pack(work, out);
  pack(gross, out);
  team_->allgather(out, in);
  if (team_->shares_whole() && team_->rank() != 0) return;   // member 0 adds to the one whole model
  ExactSum all_work, all_gross;
  const double* p = in.data();
  for (int r = 0; r < team_->size(); ++r) {
    ExactSum w, g;
    unpack(w, p);
    unpack(g, p);
    all_work.add(w);
    all_gross.add(g);
  }
  full.energy.boundary_work += all_work.value();
  full.space.gross_work += all_gross.value();
}

void BrickStep::reduce_tilt(const Space& before) {
  ++edition_;
  part_.space = before;
  reduce_cell_tilt(part_);
}

bool BrickStep::live_for(const Model& full) const {
  return live_ && model_ == &full && full.balls.size() == full_balls_ && full.contacts.list_version == list_version_ &&
         full.wall_contacts.list_version == wall_version_;
}

void BrickStep::together(const std::function<void()>& work, const std::string& doing) {
  if (team_->shares_whole()) work();   // (threads: Pipeline::each_part's abort releases the others)
  else comm::together(work, doing);
}

void BrickStep::step(ThreadPool& pool, Model& full, const StepKernels& kernels, StepSums& sums, PhaseTimes& times) {
  results_left_ = false;   // (the step makes the state another)
  // A rank's step about to make its results' arrays (mapped afresh): the memory a search or a
  // split before it freed goes back first, so that the two do not add up in the peak (a step taken
  // again on the parts searches and writes its results at once). (Threads share one process's
  // memory: not theirs to trim each.)
  if (!team_->shares_whole() && kernels.writes_results() && !part_.contacts.results_kept()) return_free_memory();
  // (Members sharing one whole model read its space and walls here, before the exchange below;
  // member 0 writes its walls' loads after it.)
  // The space and the walls are the whole model's (the cell's strain and the walls' motion and
  // servos act on it between steps).
  part_.space = full.space;
  part_.walls = full.walls;
  // The history parts of the whole model's laws (a law added since the part was cut: zero).
  part_.contacts.use_history(full.contacts.history_laws);
  take_kernels(kernels, kernels_);
  Balls& b = part_.balls;
  const std::size_t m = b.size();
  if (kernels_.moments) scratch_.ball_moments.resize(m);
  if (kernels_.features.stiffness_damping) scratch_.ball_dashpot.resize(m);
  if (kernels_.features.rolling) scratch_.ball_rolling.resize(m);
  StepSums mine;
  const auto t0 = std::chrono::steady_clock::now();
  step_.run(pool, part_, scratch_, kernels_, mine, times, ref_.x.size() == m ? &ref_ : nullptr);
  work_seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  work_ball_steps_ += static_cast<double>(owned_.size());
  current_ = false;
  shared_ = false;
  results_written_ = kernels.writes_results();

  // The ghosts' new state, from their owners.
  const int ranks = team_->size();
  for (int r = 0; r < ranks; ++r) {
    double* out = send_buf_[r].data();
    for (std::uint32_t k : send_[r]) {
      for (double v : {b.x[k], b.y[k], b.z[k], b.vx[k], b.vy[k], b.vz[k], b.wx[k], b.wy[k], b.wz[k]}) *out++ = v;
    }
  }
  team_->exchange(send_buf_, recv_buf_);
  for (int r = 0; r < ranks; ++r) {
    const double* in = recv_buf_[r].data();
    for (std::uint32_t k : recv_[r]) {
      for (double* v : {&b.x[k], &b.y[k], &b.z[k], &b.vx[k], &b.vy[k], &b.vz[k], &b.wx[k], &b.wy[k], &b.wz[k]}) *v = *in++;
    }
  }

  // What decides whether the next step needs the whole model (the largest over the ranks, sent
  // with the sums): the displacement since the list was made, a ball outside the box.
  const Space& s = part_.space;
  const double moved2 = ref_.x.size() == m ? step_.moved2() : std::numeric_limits<double>::infinity();
  bool outside = false;
  const std::vector<double>* pos[3] = {&b.x, &b.y, &b.z};
  for (int a = 0; a < 3 && !outside; ++a) {
    if (s.wraps(a)) continue;
    for (std::size_t k = 0; k < m && !outside; ++k) {
      const double x = (*pos[a])[k];
      outside = x < s.lo[a] || x > s.hi[a];
    }
  }

  // The global sums: every rank's exact sums, merged (in any order, the same bits).
  if (mine.fastest_ball < global_ball_.size()) mine.fastest_ball = global_ball_[mine.fastest_ball];
  const std::size_t wall_count = full.walls.size();
  std::vector<WallLoad>& loads = step_.wall_totals();
  if (loads.size() != wall_count) loads.assign(wall_count, WallLoad{});
  sums_out_.clear();
  pack(mine, sums_out_);
  for (std::size_t w = 0; w < wall_count; ++w) pack(loads[w], sums_out_);
  sums_out_.push_back(moved2);
  sums_out_.push_back(outside ? 1.0 : 0.0);
  team_->allgather(sums_out_, sums_in_);
  const bool adds = !team_->shares_whole() || team_->rank() == 0;   // to the one whole model, once
  moved2_ = 0;
  double outside_any = 0;
  std::vector<WallLoad> totals(wall_count);
  const double* in = sums_in_.data();
  for (int r = 0; r < ranks; ++r) {
    StepSums part = unpack_sums(in);
    if (adds) sums.add(part);
    for (std::size_t w = 0; w < wall_count; ++w) {
      WallLoad load = unpack_load(in);
      totals[w].add(load);
    }
    moved2_ = std::max(moved2_, *in++);
    outside_any = std::max(outside_any, *in++);
  }
  outside_box_ = outside_any != 0;
  if (wall_count && adds) set_wall_loads(full.walls, totals, kernels_.wall_loads);
}

bool BrickStep::wrap(Model& full) {
  results_left_ = false;   // (the parts' images change: rank 0's copy makes the results where read, make_results)
  if (policy_->local_rule < 0 || !live_ || model_ != &full) return false;
  if (results_written_ && !current_) return false;
  part_.space = full.space;
  // (Set first: where a member fails below, the others' parts may be wrapped, and every member
  // must then make the whole list from the parts alike.)
  list_local_ = true;
  current_ = false;
  shared_ = false;
  std::vector<WrapTerm> terms;
  // (A ball a million cells away fails the wrap on each rank that holds a copy of it, not on all.)
  together([&] { wrap_into_cell(part_, &ref_.x, &ref_.y, &ref_.z, &terms); },
                 "wrapping its balls into the periodic cell");
  // Every rank's own balls' terms, in the whole model's order (a ball's own terms stay in theirs).
  std::vector<double> mine, all;
  for (const WrapTerm& t : terms)
    if (!scratch_.ghost[t.ball]) {
      mine.push_back(static_cast<double>(global_ball_[t.ball]));
      mine.push_back(t.work);
      mine.push_back(t.gross);
    }
  team_->allgather(mine, all);
  std::vector<WrapTerm> merged(all.size() / 3);
  for (std::size_t q = 0; q < merged.size(); ++q)
    merged[q] = {static_cast<std::size_t>(all[3 * q]), all[3 * q + 1], all[3 * q + 2]};
  std::stable_sort(merged.begin(), merged.end(), [](const WrapTerm& p, const WrapTerm& q) { return p.ball < q.ball; });
  if (!team_->shares_whole() || team_->rank() == 0) add_wrap_terms(full, merged);   // (once to the one whole model)
  ++local_wraps_;
  return true;
}

bool BrickStep::outside_cell(const Model& full) {
  if (!full.space.periodic) return false;
  part_.space = full.space;
  // The part's ghosts are current, and each is some rank's own ball: the same answer as the owned
  // balls' alone.
  std::vector<double> any{trubal::outside_cell(part_, 0, part_.balls.size()) ? 1.0 : 0.0};
  team_->max_all(any);
  return any[0] != 0;
}

double BrickStep::critical_step(const Features& features) {
  const std::uint8_t* ghost = scratch_.ghost.size() == part_.balls.size() ? scratch_.ghost.data() : nullptr;
  std::vector<double> any{any_ball_free(part_, features.rotation, ghost) ? 1.0 : 0.0};
  team_->max_all(any);
  std::vector<double> least{-balls_critical_step(part_, features, any[0] != 0, ghost)};
  team_->max_all(least);   // (the smallest step: a max of the negatives, exact)
  return -least[0];
}

double BrickStep::free_step(const Features& features, double cap) {
  const std::uint8_t* ghost = scratch_.ghost.size() == part_.balls.size() ? scratch_.ghost.data() : nullptr;
  std::vector<double> any{any_ball_free(part_, features.rotation, ghost) ? 1.0 : 0.0};
  team_->max_all(any);
  std::vector<double> least{-contact_free_step(part_, features, cap, any[0] != 0, ghost)};
  team_->max_all(least);   // (the smallest step: a max of the negatives, exact)
  return -least[0];
}

void BrickStep::loads_changed(const Model& full) {
  const Balls& from = full.balls;
  Balls& to = part_.balls;
  for (std::size_t q = 0; q < to.size(); ++q) {
    const std::size_t k = global_ball_[q];
    to.ax[q] = from.ax[k]; to.ay[q] = from.ay[k]; to.az[q] = from.az[k];
    to.amx[q] = from.amx[k]; to.amy[q] = from.amy[k]; to.amz[q] = from.amz[k];
  }
}

std::size_t BrickStep::change_balls(const Model& full, const Range& range,
                                    const std::function<void(Balls&, std::size_t)>& change) {
  if (!live_ || team_->shares_whole()) throw std::logic_error("internal error: balls changed on parts where none is live");
  std::vector<double> mine{0}, all;
  together([&] {
    Balls& b = part_.balls;
    std::vector<std::uint8_t> own(b.size(), 0);
    for (std::uint32_t q : owned_) own[q] = 1;
    for (std::size_t k = 0; k < b.size(); ++k)
      if (holds(full, range, view_of(part_, k))) {
        change(b, k);
        mine[0] += own[k];
      }
  }, "changing its balls");
  team_->allgather(mine, all);   // (rank 0's whole model, where it is not hollow, is changed alike: Session::change_balls)
  double n = 0;
  for (double v : all) n += v;
  return static_cast<std::size_t>(n);
}

std::vector<std::int64_t> BrickStep::ids_where(const Model& full, const Range& range) {
  if (!live_ || team_->shares_whole()) throw std::logic_error("internal error: a range read on parts where none is live");
  std::vector<double> mine, all;
  together([&] {
    for (std::uint32_t q : owned_)
      if (holds(full, range, view_of(part_, q))) mine.push_back(std::bit_cast<double>(part_.balls.id[q]));   // (its bits: any id travels exactly)
  }, "reading the range on its balls");
  team_->allgather(mine, all);
  std::vector<std::int64_t> ids;
  together([&] {
    ids.reserve(all.size());
    for (double v : all) ids.push_back(std::bit_cast<std::int64_t>(v));
    std::sort(ids.begin(), ids.end());
  }, "reading the range on its balls");
  return ids;
}

std::vector<double> BrickStep::own_ball_values(std::int64_t id, std::size_t count,
                                               const std::function<std::vector<double>(const Balls&, std::size_t)>& read) {
  if (!live_ || team_->shares_whole()) throw std::logic_error("internal error: a ball read on parts where none is live");
  std::vector<double> mine, all;
  together([&] {
    for (std::uint32_t q : owned_)
      if (part_.balls.id[q] == id) {
        mine = read(part_.balls, q);
        break;
      }
  }, "reading a ball's history");
  team_->allgather(mine, all);   // (the owner's values alone)
  if (all.size() != count) all.assign(count, std::numeric_limits<double>::quiet_NaN());   // (no ball has that id)
  return all;
}

PlatenBalls BrickStep::own_platen_balls(const std::vector<std::int64_t>& ids) {
  if (!live_ || team_->shares_whole()) throw std::logic_error("internal error: platen balls read on parts where none is live");
  std::vector<std::int64_t> sorted = ids;
  std::sort(sorted.begin(), sorted.end());
  std::vector<double> mine, all;
  together([&] {
    const Balls& b = part_.balls;
    for (std::uint32_t q : owned_)
      if (std::binary_search(sorted.begin(), sorted.end(), b.id[q]))
        for (double v : {static_cast<double>(global_ball_[q]), b.z[q], b.fx[q], b.fy[q], b.fz[q]}) mine.push_back(v);
  }, "reading the platen balls");
  team_->allgather(mine, all);
  // (In the whole model's order, serial's: its sums over them are made in that order.)
  const std::size_t n = all.size() / 5;
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::sort(order.begin(), order.end(), [&](std::size_t p, std::size_t q) { return all[5 * p] < all[5 * q]; });
  PlatenBalls out;
  for (std::size_t p : order) {
    out.z.push_back(all[5 * p + 1]);
    out.fx.push_back(all[5 * p + 2]);
    out.fy.push_back(all[5 * p + 3]);
    out.fz.push_back(all[5 * p + 4]);
  }
  return out;
}

namespace {
// The membrane's loaded balls as (id, place in its ids), by id.
std::vector<std::pair<std::int64_t, std::size_t>> membrane_places(const Membrane& m) {
  std::vector<std::pair<std::int64_t, std::size_t>> at(m.ids.size());
  for (std::size_t q = 0; q < m.ids.size(); ++q) at[q] = {m.ids[q], q};
  std::sort(at.begin(), at.end());
  return at;
}
std::int64_t membrane_place(const std::vector<std::pair<std::int64_t, std::size_t>>& at, std::int64_t id) {
  const auto it = std::lower_bound(at.begin(), at.end(), std::pair<std::int64_t, std::size_t>{id, 0});
  return it != at.end() && it->first == id ? static_cast<std::int64_t>(it->second) : -1;
}
}  // namespace

void BrickStep::bonds_to_root(Model& full) {
  if (!live_ || team_->shares_whole() || model_ != &full) throw std::logic_error("internal error: bonds gathered from parts where none is live");
  if (!bonded_) return;   // (the same on every rank: no part holds a bond)
  std::vector<double> out, in;
  gather_bonds(full, out, in);
}

BondCounts BrickStep::own_bond_counts() {
  if (!live_ || team_->shares_whole()) throw std::logic_error("internal error: bonds counted on parts where none is live");
  std::vector<double> mine(3, 0), all;
  together([&] {
    const Bonds& t = part_.bonds;
    for (std::size_t q = 0; q < t.size(); ++q) {
      const std::int64_t i = find_ball(part_, t.id_i[q]);
      if (i < 0 || scratch_.ghost[static_cast<std::size_t>(i)]) continue;
      ++mine[t.fate[q] == static_cast<std::uint8_t>(BondFate::Tension) ? 1 : t.fate[q] == static_cast<std::uint8_t>(BondFate::Shear) ? 2 : 0];
    }
  }, "counting its bonds");
  team_->allgather(mine, all);
  BondCounts c = split_off_;
  for (std::size_t r = 0; r + 3 <= all.size(); r += 3) {
    c.intact += static_cast<std::size_t>(all[r]);
    c.tension += static_cast<std::size_t>(all[r + 1]);
    c.shear += static_cast<std::size_t>(all[r + 2]);
  }
  return c;
}

MembraneFollow BrickStep::follow_membrane(const Membrane& m) {
  if (!live_ || team_->shares_whole()) throw std::logic_error("internal error: the membrane followed on parts where none is live");
  std::vector<std::pair<std::int64_t, std::size_t>> at;
  std::vector<double> mine, all;
  together([&] {
    at = membrane_places(m);
    const Balls& b = part_.balls;
    for (std::uint32_t k : owned_)
      if (const std::int64_t q = membrane_place(at, b.id[k]); q >= 0)
        for (double v : {static_cast<double>(q), b.x[k], b.y[k], b.z[k]}) mine.push_back(v);
  }, "following the membrane");
  team_->allgather(mine, all);
  MembraneCentres c;
  const std::size_t n = m.ids.size();
  c.x.assign(n, 0);
  c.y.assign(n, 0);
  c.z.assign(n, 0);
  c.present.assign(n, 0);
  for (std::size_t r = 0; r + 4 <= all.size(); r += 4) {
    const auto q = static_cast<std::size_t>(all[r]);
    c.x[q] = all[r + 1];
    c.y[q] = all[r + 2];
    c.z[q] = all[r + 3];
    c.present[q] = 1;
  }
  MembraneFollow loads = follow_loads(m, c);
  together([&] {
    Balls& b = part_.balls;
    for (std::size_t k = 0; k < b.size(); ++k)
      if (const std::int64_t q = membrane_place(at, b.id[k]); q >= 0) {
        b.ax[k] = loads.ax[static_cast<std::size_t>(q)];
        b.ay[k] = loads.ay[static_cast<std::size_t>(q)];
      }
  }, "following the membrane");
  return loads;
}

void BrickStep::take_settings(const Model& full) {
  part_.settings = full.settings;
  together([&] {
    part_.materials = full.materials;
    update_mass(part_);
    const Balls& b = part_.balls;
    for (std::uint32_t k : owned_)
      if (std::string why = ball_mass_problem(b.id[k], b.mass[k], b.inertia[k], b.rad[k]); !why.empty())
        throw std::runtime_error(why);
  }, "taking the materials");
}

void BrickStep::release() {
  if (live_ && whole_hollow_) throw std::logic_error("internal error: the ranks' parts released where they alone hold the model");
  ++edition_;
  live_ = false;
  results_left_ = false;
  auto free = [](auto& v) { std::decay_t<decltype(v)>().swap(v); };
  part_ = Model{};
  scratch_ = StepScratch{};
  step_ = ParallelStep{*policy_};
  ref_ = VerletReference{};
  free(owner_); free(global_ball_); free(owned_); free(owned_pairs_); free(owned_walls_);
  free(rank_bonds_); free(split_bond_rows_); free(split_bond_ball_i_);
  free(rank_balls_); free(rank_pairs_); free(rank_walls_); free(send_); free(recv_); free(send_buf_); free(recv_buf_);
  free(sums_out_); free(sums_in_);
  free_saved();
}

void BrickStep::keep_copy() {
  if (team_->shares_whole() || !live_)
    throw std::logic_error("internal error: a part's rescue copy asked where no rank's part is live");
  copy_.part.take(part_);
  copy_.global_ball = global_ball_;
  copy_.owned = owned_;
  copy_.owned_pairs = owned_pairs_;
  copy_.owned_walls = owned_walls_;
  // Rank 0 places every rank's values in the whole model; a rank needs its own row of the bonds.
  const auto me = static_cast<std::size_t>(team_->rank());
  copy_.rank_balls.assign(rank_balls_.size(), {});
  copy_.rank_bonds.assign(rank_bonds_.size(), {});
  if (comm::root()) copy_.rank_balls = rank_balls_, copy_.rank_bonds = rank_bonds_;
  else if (me < rank_bonds_.size()) copy_.rank_bonds[me] = rank_bonds_[me];
  copy_.ghost = scratch_.ghost;
  copy_.ref = ref_;
  copy_.full_balls = full_balls_;
  copy_.bonded = bonded_;
  copy_.walls_any = walls_any_;
  copy_.edition = edition_;
  copy_.moved2 = moved2_;
  copy_.outside_box = outside_box_;
  copy_.held = true;
}

bool BrickStep::restore_copy_in_place(const Model& full) {
  const bool mine = copy_.held && live_ && model_ == &full && copy_.edition == edition_ && !team_->shares_whole();
  if (comm::any_all(!mine)) return false;   // (every rank's part, or none)
  together([&] {
    copy_.part.restore(part_);
    ref_ = copy_.ref;
  }, "putting back the rescue copy of its part");
  // (A wrap since renumbered the pairs' images, which the step taken again renumbers alike, and
  // sets list_local_ again: the whole model's list is the one the parts come back to.)
  moved2_ = copy_.moved2;
  outside_box_ = copy_.outside_box;
  whole_list_kept_ = !list_local_;   // (the whole model's list was the parts', made at the last sync)
  kept_edition_ = edition_;
  current_ = false;
  results_written_ = results_left_ = false;
  return true;
}

void BrickStep::free_copy() { copy_ = PartCopy{}; }

std::size_t BrickStep::copy_bytes() const {
  if (!copy_.held) return 0;
  std::size_t n = copy_.part.bytes();
  auto add = [&](const auto& v) { n += capacity_bytes(v); };
  for (const auto* v : {&copy_.global_ball, &copy_.owned, &copy_.owned_pairs, &copy_.owned_walls}) add(*v);
  for (const auto* lists : {&copy_.rank_balls, &copy_.rank_bonds})
    for (const auto& v : *lists) add(v);
  add(copy_.ghost);
  for (const auto* v : {&copy_.ref.x, &copy_.ref.y, &copy_.ref.z}) add(*v);
  return n;
}

std::size_t array_bytes(const Model& m) {
  std::size_t bytes = 0;
  auto add = [&](const auto& v) { bytes += capacity_bytes(v); };
  m.balls.for_each_array(add);
  m.contacts.for_each_pair_array(add);
  const_cast<WallContacts&>(m.wall_contacts).for_each_array(add);   // (it has no const visitor; it only reads)
  return bytes;
}

std::size_t BrickStep::part_bytes() const { return array_bytes(part_); }

std::vector<std::pair<std::string, std::string>> BrickStep::info() const {
  std::vector<std::pair<std::string, std::string>> lines;
  if (splits_ == 0) return lines;
  const std::string member = team_->shares_whole() ? "thread" : "rank";
  lines.emplace_back("balls per " + member, std::to_string(least_balls_) + " to " + std::to_string(most_balls_) +
                                                " (" + member + " 0 also holds " + std::to_string(ghosts_) + " ghosts)");
  std::string shares;
  for (double share : shares_) fmt::format_to(std::back_inserter(shares), "{}{:.2f}", shares.empty() ? "" : " ", share);
  lines.emplace_back("shares of the balls", shares + " (by " + member + ", in proportion to the speed each stepped its own balls at)");
  lines.emplace_back("decompositions made", std::to_string(splits_));
  if (bonded_)
    lines.emplace_back("bonds across " + member + "s", std::to_string(bonds_across_) + " intact at the last split (each stepped on both " +
                                                   member + "s, reported by its ball i's)");
  {
    lines.emplace_back("pair lists rebuilt on the parts",
                       std::to_string(local_rebuilds_) + " (each rank searching its own balls and those within reach of them)");
    lines.emplace_back("sorts on the parts", std::to_string(sorts_) + " (the balls put in space order by their ranks, "
                                                                  "no rank holding the whole model)");
    lines.emplace_back("wraps on the parts", std::to_string(local_wraps_) + " (balls moved across the periodic faces by their ranks)");
    lines.emplace_back("balls that changed rank", std::to_string(migrations_) +
                                                      " (at the rebuilds on the parts: a ball goes to the " + member +
                                                      " whose brick of the split holds it now, with its history)");
  }
  return lines;
}

}  // namespace trubal
