// The pipeline's steps by the spatial decomposition (cycle/brick_step.hpp): a step on the parts,
// the parts made from the whole model and searched, their critical step, and a rank's model
// hollowed while its part is live (cycle/pipeline.hpp).
#include "cycle/pipeline.hpp"

#include <algorithm>
#include <stdexcept>
#include <bit>
#include <chrono>
#include <cstdint>
#include <exception>
#include <mutex>
#include <utility>

#include <fmt/format.h>

#include "cycle/pair_list.hpp"
#include "cycle/wall_list.hpp"
#include "support/comm.hpp"
#include "model/edit.hpp"
#include "model/wall_shape.hpp"
#include "model/periodic_cell.hpp"
#include "physics/bridge.hpp"
#include "physics/timestep.hpp"
#include "support/format_number.hpp"
#include "support/peak_memory.hpp"

#include "cycle/pipeline_parts.hpp"

namespace trubal {

bool Pipeline::parts_go_on(Model& model) {
  if (!bricks().live_for(model)) return search_next_step_ = false;   // (every rank decides alike: each input is the same on all)
  bool outside = false;                          // a collective call, made unconditionally
  each_part([&](BrickStep& part, int t) {
    const bool mine = part.outside_cell(model);
    if (t == 0) outside = mine;
  });
  // A ball across a periodic face: the members wrap their parts' balls where they can.
  if (outside) {
    bool wrapped = false;
    each_part([&](BrickStep& part, int t) {
      const bool done = part.wrap(model);   // (the same answer on every member)
      if (t == 0) wrapped = done;
    });
    outside = !wrapped;
  }
  const double limit2 = ref_.displacement_limit2(model);
  const bool sorted = std::exchange(search_next_step_, false);
  const bool walls = std::exchange(walls_next_step_, false);
  const bool stale = outside || sorted || !(limit2 >= 0) || !(bricks().moved2() <= limit2) ||
                     !(wall_travel_ <= 0.5 * ref_.skin());
  if (!stale) {
    if (walls) {
      const double reach = list_reach(model, list_skin(model));
      each_part([&](BrickStep& part, int t) { part.find_walls_again(model, reach, distributed() ? pool_ : *solo_pools_[t]); });
    }
    return true;
  }
  if (outside) return false;
  // A stale list alone: the members rebuild it on their parts where they can.
  const double skin = list_skin(model);
  if (!rebuild_parts(model, list_reach(model, skin))) return false;
  ref_.record_cell(model, skin);
  wall_travel_ = 0;
  return true;
}

std::size_t Pipeline::delete_on_parts(Model& model, const Range& range) {
  if (!parts_live(model)) throw std::logic_error("internal error: balls deleted on parts that are not live");
  if (!comm::root()) hollow(model);   // (as sort_on_parts: the others' whole models hollow)
  for (auto& part : bricks_) part->whole_freed();
  const std::size_t n = bricks().delete_balls(model, range);
  hollow_whole(model);
  // The list's reference of the balls left (as parts_from_records: the parts hold the positions),
  // and a search at the next step, as serial's after remove_balls.
  ref_.record(model, list_skin(model));
  ref_.forget_radii();
  search_next_step_ = true;   // (the same on every rank)
  return n;
}

bool Pipeline::follow_membrane_on_parts(Model& model) {
  if (!distributed() || comm_ranks_ < 2 || !bricks().live_for(model)) return false;
  Membrane& m = model.membrane;
  const MembraneFollow loads = bricks().follow_membrane(m);
  Balls& b = model.balls;
  if (b.ax.size() == b.size() && b.ay.size() == b.size())   // (rank 0's hollow arrays; any whole model)
    for (std::size_t q = 0; q < m.ids.size(); ++q)
      if (const std::int64_t k = find_ball(model, m.ids[q]); k >= 0) {
        b.ax[static_cast<std::size_t>(k)] = loads.ax[q];
        b.ay[static_cast<std::size_t>(k)] = loads.ay[q];
      }
  m.area = loads.area;
  return true;
}

bool Pipeline::rebuild_before_copy(Model& model) {
  if (!parts_live(model)) return false;   // (the same answer on every rank)
  bool outside = false;
  each_part([&](BrickStep& part, int t) {
    const bool mine = part.outside_cell(model);   // (every member's answer, the same on each)
    if (t == 0) outside = mine;
  });
  // (A wrap reads the cell's rates, which a periodic servo changes before the step: where one
  // drives the cell, the step wraps, after them; so beside a following membrane, whose loads are
  // made before the step.)
  const Space& s = model.space;
  if (outside && (s.servo_on[0] || s.servo_on[1] || s.servo_on[2] || model.membrane.follow_every > 0)) return false;
  const double limit2 = ref_.displacement_limit2(model);
  const bool stale = outside || search_next_step_ || walls_next_step_ || !(limit2 >= 0) || !(bricks().moved2() <= limit2) ||
                     !(wall_travel_ <= 0.5 * ref_.skin());
  if (!stale) return false;
  const std::uint64_t edition = bricks().edition();
  // (Where the parts cannot go on, the step decides again: its list searched afresh.)
  if (!parts_go_on(model)) search_next_step_ = true;
  return outside || bricks().edition() != edition;
}

void Pipeline::brick_step(Model& model, const StepKernels& kernels, StepSums& sums) {
  // The last step's findings (every rank's): the parts go on where the serial pipeline would only
  // step; a wrap or a rebuild goes through the whole model.
  const auto t0 = std::chrono::steady_clock::now();
  bool whole = !parts_go_on(model);
  times_.detect += seconds_since(t0);
  if (whole) {
    // A distributed run's parts made afresh (a new balance, a rebuild they could not make): their
    // state to rank 0 alone, the others left with the light arrays until rank 0 sends each its new
    // part (split_parts' scatter), rather than every rank handed the whole model.
    if (distributed() && comm_ranks_ > 1 && bricks().live_for(model)) release_parts(model);
    if (bricks().live() || !prepared_for(model)) prepare(model);   // syncs and drops the parts first
    if (!distributed() && !threads_in_space(model)) {   // the new list is better shared by numbers
      mode_ = StepMode::Numbers;
      shared_by_ = "ball numbers";
      whole_step(model, kernels, sums);
      return;
    }
    const auto t1 = std::chrono::steady_clock::now();
    split_parts(model);
    times_.detect += seconds_since(t1);
  }
  list_ = ListState::Unchecked;   // (the parts measure their own displacements)
  // The ranks other than 0 step their parts alone from here: their copy of the whole model's arrays
  // goes until sync_all hands it over again (rank 0 keeps its own, for the output and the rescue).
  if (distributed() && comm::size() > 1 && !comm::root() && bricks().live_for(model)) hollow(model);
  if (distributed()) {   // (PRINT info: what each rank held in its last step)
    held_whole_ = array_bytes(model);
    held_part_ = bricks().part_bytes();
  }
  each_part([&](BrickStep& part, int t) {
    if (distributed()) part.step(pool_, model, kernels, sums, times_);
    else part.step(*solo_pools_[t], model, kernels, sums, t == 0 ? times_ : member_times_[t]);
  });
}

void Pipeline::split_parts(Model& model) {
  // A list prepare() left stale is searched on the parts about to be made (they carry its history),
  // at the positions now.
  const bool search = list_ == ListState::PartsToSearch;
  double skin = 0;
  if (search) {
    skin = list_skin(model);
    ref_.record(model, skin);
    wall_travel_ = 0;
  }
  // The ranks other than 0 free their whole model's arrays before their part comes: rank 0 makes
  // every part and sends it (BrickStep::scatter_parts). Should that fail, rank 0 hands the whole
  // model back to them. No rank keeps the whole model's radii for the list's test.
  const bool scatter = distributed() && comm::size() > 1;
  if (scatter) {
    ref_.forget_radii();
    if (!comm::root()) hollow(model);
    for (auto& part : bricks_) part->whole_freed();
  }
  try {
    each_part([&](BrickStep& part, int) { part.split(model, ref_); });
  } catch (...) {
    if (scatter) broadcast_arrays(model, false);   // (the ranks agreed on the failure: every one is here)
    others_hollow_ = false;
    throw;
  }
  others_hollow_ = false;   // (they hold their parts)
  // Rank 0 too steps its part alone: its whole model's state goes (before the parts search their
  // lists) until a sync gathers it again, for the output or a command that reads it, so that no
  // rank holds a part and the whole model.
  if (scatter) hollow_whole(model);
  if (search) search_new_parts(model, skin);
}

void Pipeline::search_new_parts(Model& model, double skin) {
  const bool rebuilt = rebuild_parts(model, list_reach(model, skin));
  list_ = ListState::Current;
  if (rebuilt) return;
  // They could not (the same answer on every rank: a bond longer than the list's reach, or
  // TRUBAL_REBUILD_WHOLE): through the whole model, gathered back from the parts, which rank 0
  // hands to the others.
  for (auto& part : bricks_) part->reference_at_balls();
  sync(model);
  for (auto& part : bricks_) part->drop();
  if (distributed()) broadcast_arrays(model);
  rebuild(model);
  each_part([&](BrickStep& part, int) { part.split(model, ref_); });
  if (distributed() && comm::size() > 1) hollow_whole(model);
}

void Pipeline::parts_from_records(Model& model, std::vector<double>& records) {
  // As split_parts with a list to search, the parts made from the records rather than cut from
  // rank 0's whole model.
  const double skin = list_skin(model);
  ref_.record(model, skin);
  ref_.forget_radii();   // (as split_parts)
  wall_travel_ = 0;
  list_ = ListState::PartsToSearch;
  for (auto& part : bricks_) part->whole_freed();
  bricks().split_from_records(model, records);
  others_hollow_ = false;
  hollow_whole(model);
  search_new_parts(model, skin);
  sorted_cycle_ = model.cycle;
  sorted_edition_ = bricks().edition();
  ++parts_from_records_;
}

void Pipeline::parts_from_file(Model& model, TablePieces* file, bool results) {
  // As parts_from_records, the parts made from the save's pieces; their first list carries the
  // save's history and results in (BrickStep::rebuild_local), on the parts alone.
  const double skin = list_skin(model);
  ref_.record(model, skin);
  ref_.forget_radii();
  wall_travel_ = 0;
  list_ = ListState::PartsToSearch;
  for (auto& part : bricks_) part->whole_freed();
  try {
    bricks().split_from_file(model, file, results);
    others_hollow_ = false;
    hollow_whole(model);
    if (!rebuild_parts(model, list_reach(model, skin)))   // (the same answer on every rank)
      throw std::runtime_error("the ranks' parts made from it could not search their pair lists");
  } catch (...) {
    drop_parts_unsynced(model);
    throw;
  }
  list_ = ListState::Current;
  walls_next_step_ = !model.walls.empty();   // (the same on every rank)
  ++parts_from_saves_;
}

bool Pipeline::sort_on_parts(Model& model) {
  if (!sorts_on_parts(model)) throw std::logic_error("internal error: the balls sorted on parts that are not live");
  // (The others' whole models hollow, as each step leaves them: a command or START's escapes may
  // have handed the whole model over since.)
  if (!comm::root()) hollow(model);
  for (auto& part : bricks_) part->whole_freed();
  const std::vector<std::uint32_t> order = bricks().sort_in_space(model);
  model.order.pending = false;
  hollow_whole(model);   // (sort_in_space let rank 0's whole model go: what the pipeline keeps of it too)
  if (order.empty()) return false;
  ref_.reorder(order);
  // The parts' lists searched afresh now, as serial's are after its sort (at the step that follows,
  // from the same positions: nothing moves between), and before the rescue copy a deferred last
  // step takes after its sort (CycleRun::run), which is then put back on these parts in place.
  // Where the parts cannot, the step goes through the whole model (parts_go_on).
  const double skin = list_skin(model);
  if (rebuild_parts(model, list_reach(model, skin))) {
    ref_.record_cell(model, skin);
    wall_travel_ = 0;
  } else {
    search_next_step_ = true;   // (the same on every rank)
  }
  return true;
}

void Pipeline::hollow_whole(Model& model) {
  for (auto& part : bricks_) part->hollow_whole(model);
  if (!comm::root() || !bricks().whole_hollow()) return;
  // What rank 0's pipeline keeps of the whole model goes with it: the index of its arrays and the
  // list's reference positions (24 bytes a ball; the parts hold their own, and a sync after a
  // rebuild on the parts gathers them again).
  scratch_ = StepScratch{};
  for (auto* v : {&ref_.x, &ref_.y, &ref_.z}) std::vector<double>().swap(*v);
}

double Pipeline::list_reach(const Model& model, double skin) const {
  const double bridge = bridge_reach(model);
  if (bridge == 0) return skin;
  if (model.space.periodic) {   // (one image of a ball within its reach, as periodic_skin keeps the skin's)
    const auto w = cell_widths(model.space);
    const double d = 2 * model.balls.max_radius();
    for (int a = 0; a < 3; ++a)
      if (model.space.periodic_axis[a] && !(d + skin + bridge < 0.5 * w[a]))
        throw std::runtime_error(fmt::format(
            "periodic cell too small for the capillary bridges: its {} width {:.6g} is not more than twice the "
            "largest diameter, the pair list's skin and the bridges' rupture gap ({:.6g}); use a larger cell",
            "xyz"[a], w[a], d + skin + bridge));
  }
  return skin + bridge;
}

double Pipeline::list_skin(const Model& model) const {
  double skin = VerletReference::skin_for(model.balls);
  if (model.space.periodic) skin = periodic_skin(model, skin);
  check_periodic_cell(model);
  return skin;
}

bool Pipeline::rebuild_parts(const Model& model, double skin) {
  bool rebuilt = false;
  each_part([&](BrickStep& part, int t) {
    const bool done = part.rebuild_local(model, skin, *backend_, distributed() ? pool_ : *solo_pools_[t]);
    if (t == 0) rebuilt = done;   // (the same answer on every member)
  });
  return rebuilt;
}

double Pipeline::critical_timestep(Model& model, const Features& features, double cap) {
  // Kept parts (a CYCLE going on from them after a setting changed): each rank's own balls, their
  // list made current first (parts_go_on; the CYCLE hands the whole model over where it cannot be).
  if (parts_live(model)) return std::min(bricks().critical_step(features), cap);
  // (PartsToSearch: a distributed run's alone. The ranks other than 0 holding no balls but their
  // ids, types and radii: the parts are made now, rank 0 sending each rank its own.)
  if (list_ != ListState::PartsToSearch && !others_hollow_) return trubal::critical_timestep(model);
  // The parts search the stale list now, and each rank's own balls give their steps.
  const auto t0 = std::chrono::steady_clock::now();
  split_parts(model);
  times_.detect += seconds_since(t0);
  return std::min(bricks().critical_step(features), cap);
}

void Pipeline::hollow(Model& model) {
  Balls& b = model.balls;
  if (b.x.empty() && model.contacts.i.empty() && b.size() > 0) return;   // (hollow already)
  auto free = [](auto& v) { std::decay_t<decltype(v)>().swap(v); };
  // What stays: the ids (the count of balls: BrickStep::live_for), the radii (the skin and the
  // displacement test read them) and the types (a CYCLE that goes on from the parts reads them for
  // its laws and checks): none changes in a CYCLE.
  b.for_each_array([&](auto& v) {
    const void* a = &v;
    if (a != &b.id && a != &b.rad && a != &b.type) free(v);
  });
  model.contacts.for_each_pair_array(free);              // (its list_version stays: live_for)
  model.wall_contacts.for_each_array(free);
  scratch_ = StepScratch{};                               // (an index of the arrays that went)
}

}  // namespace trubal
