// PRINT info and PRINT counters: what the model, the run and the backend are, in words and as
// counters (commands/print.cpp dispatches).
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <sstream>

#include <fmt/format.h>

#include "commands/common.hpp"
#include "physics/bond.hpp"
#include "physics/bridge.hpp"
#include "cycle/pipeline.hpp"
#include "support/comm.hpp"
#include "support/peak_memory.hpp"
#include "model/wall_shape.hpp"
#include "physics/walls.hpp"
#include "io/atomic_file.hpp"
#include "io/csv.hpp"
#include "physics/measure.hpp"
#include "physics/measure_sphere.hpp"
#include "physics/scene.hpp"

#include "commands/print_parts.hpp"

namespace trubal {

// How far apart balls next to each other in memory lie, in diameters (medians of both): about 1
// in space order (which the run puts them in: SET sort), tens where at random, which the contact
// loop reads far more slowly. 0 for < 2 balls. (The positions an axis at a time: from the ranks'
// kept parts, where rank 0's whole model is hollow, Session::ball_array.)
static double memory_gap_in_diameters(const Session& s, const Balls& b) {
  if (b.size() < 2) return 0;
  auto median = [](std::vector<double>& v) {
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
  };
  // (One array of the balls' at a time beside the gaps: the radii's median first, then each axis,
  // fetched from the ranks' parts where rank 0's whole model is hollow.)
  double diameter = 0;
  {
    std::vector<double> rad(b.rad);
    diameter = 2 * median(rad);
  }
  std::vector<double> gap(b.size() - 1, 0.0), fetched;
  for (const std::vector<double>* axis : {&b.x, &b.y, &b.z}) {
    const std::vector<double>& v = s.ball_array(*axis, fetched);
    for (std::size_t k = 1; k < b.size(); ++k) gap[k - 1] += (v[k] - v[k - 1]) * (v[k] - v[k - 1]);
  }
  std::vector<double>().swap(fetched);
  for (double& g : gap) g = std::sqrt(g);
  return diameter > 0 ? median(gap) / diameter : 0;
}

void print_info(Context& ctx) {
  const Session& s = ctx.session;
  // (The light state and the counts: under mpirun rank 0's whole model is not gathered for them.)
  const Session::StateCounts counts = s.state_counts();
  const Model& m = s.state();
  auto& o = ctx.out;
  if (!m.title.empty()) o << "title: " << m.title << '\n';
  if (m.started) {
    auto L = m.space.length();
    std::string kind = m.space.periodic ? "periodic" : "box";
    if (m.space.mixed()) {
      kind = "box, periodic in";
      for (int a = 0; a < 3; ++a)
        if (m.space.wraps(a)) kind += std::string(" ") + "xyz"[a];
      kind += ":";
    }
    o << fmt::format("space: {} {} x {} x {}\n", kind, L[0], L[1], L[2]);
    const auto& t = m.space.tilt;
    if (m.space.periodic && (t[0] != 0 || t[1] != 0 || t[2] != 0))
      o << fmt::format("cell tilt: xy {:.6g}  xz {:.6g}  yz {:.6g}\n", t[0], t[1], t[2]);
  } else {
    o << "space: none (START first)\n";
  }
  o << fmt::format("balls: {}\n", m.balls.size() + s.held_balls());
  if (s.held_balls() > 0)
    o << fmt::format("balls held: {} (a batch deck's BALL lines, on the ranks that keep them, placed in the model "
                     "when a command reads the balls)\n", s.held_balls());
  else if (m.balls.size() >= 2) {
    const double gap = memory_gap_in_diameters(s, m.balls);
    o << fmt::format("ball order: neighbours in memory {:.3g} diameters apart (median); put in space order {}{}\n", gap,
                     m.order.pending && m.order.every > 0 ? "at the next step, then every " + std::to_string(m.order.every) + " cycles"
                                                          : m.order.every > 0 ? "every " + std::to_string(m.order.every) + " cycles"
                                                                              : std::string("never (SET sort 0)"),
                     gap > 3 && m.order.every == 0 ? ": the contact loop reads memory slowly; SET sort 1000 puts them in space order" : "");
  }
  o << fmt::format("contacts: {}\n", counts.touching);
  if (!m.walls.empty()) o << fmt::format("walls: {} ({} ball-wall contacts)\n", m.walls.size(), counts.wall_touching);
  if (!m.bonds.empty()) {
    const BondCounts n = count_bonds(m.bonds);
    o << fmt::format("bonds: {} intact, {} broken ({} in tension, {} in shear)\n", n.intact, n.broken(), n.tension,
                     n.shear);
  }
  if (has_bridges(m))
    o << fmt::format("bridges intact: {} between balls, {} to walls\n", counts.bridges, counts.wall_bridges);
  o << fmt::format("cycle: {}\n", m.cycle);
  o << fmt::format("time: {}\n", m.time);
  o << fmt::format("timestep: {}\n", m.dt);
  o << fmt::format("frac: {}\n", m.settings.frac);
  if (m.settings.fixed_dt > 0) o << fmt::format("fixed timestep: {}\n", m.settings.fixed_dt);
  if (m.space.destroyed > 0) o << fmt::format("balls destroyed: {} (they left the box)\n", m.space.destroyed);
  o << fmt::format("backend: {}\n", s.pipeline().backend().name());
  o << fmt::format("threads: {}\n", s.pipeline().threads());
  if (comm::launched()) o << fmt::format("ranks: {}\n", comm::size());   // (under mpirun, one rank included)
  // The process's peak resident memory so far, and the model's arrays held now (every rank's,
  // gathered before rank 0 runs PRINT: Session::gather_rank_figures).
  const auto ranks = s.rank_figures();
  auto each = [&](double Session::RankFigures::*f) {
    std::vector<double> v;
    for (const auto& r : ranks) v.push_back(r.*f);
    return mib_list(v);
  };
  auto each_array = [&](double Session::RankFigures::*f) {   // (3 digits: a small model's arrays are under 1 MiB)
    std::string line;
    for (const auto& r : ranks) line += fmt::format("{}{:.3g}", line.empty() ? "" : " ", r.*f);
    return line;
  };
  o << fmt::format("peak memory: {} MiB{}\n", each(&Session::RankFigures::peak_mib), comm::size() > 1 ? " (per rank)" : "");
  if (comm::size() > 1) {
    o << fmt::format("arrays held in the last step: whole model {} MiB, part {} MiB (per rank: each its part, and of the "
                     "whole model the balls' ids, types and radii, rank 0 their fixities too, and the whole model where an "
                     "output step read it)\n",
                     each_array(&Session::RankFigures::whole_arrays_mib), each_array(&Session::RankFigures::part_arrays_mib));
    o << fmt::format("model held now: {} MiB (per rank: {})\n", each_array(&Session::RankFigures::model_arrays_mib),
                     s.parts_kept() ? s.pipeline().whole_hollow(m) ? "each its part of the model, and rank 0 the whole model's "
                                                                     "light arrays, the rest gathered from the parts where a "
                                                                     "command reads it"
                                                                   : "each its part of the model, rank 0 the whole model too"
                     : s.held_balls() > 0 ? "rank 0 the whole model, the others its settings, walls and balls' ids, types "
                                            "and radii, and each the held balls it keeps"
                     : s.pipeline().others_hollow()
                         ? "rank 0 the whole model, the others its settings, walls and balls' ids, types and radii"
                         : "the whole model on every rank");
    o << fmt::format("contact results held: {} MiB (per rank: each its part's, made there for a command that "
                     "read them, and rank 0 those a command gathered)\n", each_array(&Session::RankFigures::results_mib));
    o << fmt::format("rescue copy held: {} MiB (per rank: each its part's, taken while the parts were live; else rank "
                     "0 the whole model's)\n", each_array(&Session::RankFigures::rescue_mib));
  }
  for (const auto& [k, v] : s.pipeline().info()) o << k << ": " << v << '\n';
  const Features f = scene_features(m, counts.flags);
  o << fmt::format("physics: {}\n", f.describe());
  // The loops compiled for exactly these features (the general kernel has every one on).
  const char* damping = f.mass_damping == DampKind::Rayleigh ? ", mass damping"
                        : f.mass_damping == DampKind::Local  ? ", local damping"
                                                             : "";
  const char* estimate = m.settings.fixed_dt > 0    ? "fixed step"
                         : f.stiffness_damping     ? "damped step estimate"
                                                   : "undamped step estimate";
  o << fmt::format("kernel: contacts {}{}{}{}; motion {}{}{}, {}\n", f.hertz ? "hertz" : "linear",
                   f.friction ? " shear" : " normal-only", f.rotation ? " moments" : "",
                   f.stiffness_damping ? " dashpots" : "", f.rotation ? "translation+rotation" : "translation only",
                   f.gravity || f.applied ? ", loads" : "", damping, estimate);
  o << fmt::format("types: {}\n", m.materials.size());
  o << fmt::format("groups: {}\n", m.groups.size());
}

// PRINT counters: the counts PRINT info tells in words, one `name value` line each under a name that
// stays (HELP lists them), for scripts and tests to read. Rank 0 alone runs it (the other ranks'
// values were gathered before: Session::gather_rank_figures).
void print_counters(Context& ctx, const std::string& file) {
  const Session& s = ctx.session;
  const Session::StateCounts counts = s.state_counts();
  const Model& m = s.state();
  const PipelineCounters c = s.pipeline().counters();
  std::string text;
  auto line = [&](std::string_view name, auto value) { text += fmt::format("{} {}\n", name, value); };
  line("cycle", m.cycle);
  line("balls", m.balls.size() + s.held_balls());
  line("balls_held", s.held_balls());
  line("contacts", counts.touching);
  line("wall_contacts", counts.wall_touching);
  line("balls_destroyed", m.space.destroyed);
  line("ranks", comm::size());
  line("threads", s.pipeline().threads());
  line("threads_used", c.threads_used);
  line("pair_list_rebuilds", c.rebuilds);
  line("pair_tests", c.pair_tests);
  line("results_made", c.results_made);
  line("results_gathered", c.results_gathered);
  line("decompositions", c.parts.decompositions);
  line("part_list_rebuilds", c.parts.list_rebuilds);
  line("part_wraps", c.parts.wraps);
  line("part_sorts", c.parts.sorts);
  line("migrations", c.parts.migrations);
  line("ghosts", c.parts.ghosts);
  line("least_part_balls", c.parts.least_balls);
  line("most_part_balls", c.parts.most_balls);
  line("part_bonds_across", c.parts.bonds_across);
  line("parts_kept", s.parts_kept() ? 1 : 0);
  line("whole_hollow", s.pipeline().whole_hollow(m) ? 1 : 0);
  line("whole_hand_overs", c.hand_overs);
  line("cycle_hand_overs", c.cycle_hand_overs);
  line("whole_gathers", c.parts.gathers);
  line("peak_mib", s.rank_figures().front().peak_mib);   // (rank 0's under mpirun, gathered before PRINT)
  line("model_held_mib", s.rank_figures().front().model_arrays_mib);
  line("copies_put_back_on_parts", c.copies_on_parts);
  line("parts_from_held_balls", c.parts_from_records);
  line("parts_from_saves", c.parts_from_saves);
  if (comm::size() > 1) {   // (gathered before rank 0 runs PRINT: Session::gather_rank_figures)
    const auto ranks = s.rank_figures();
    for (std::size_t r = 0; r < ranks.size(); ++r) {
      line(fmt::format("rank{}_contact_results_mib", r), ranks[r].results_mib);
      line(fmt::format("rank{}_whole_arrays_mib", r), ranks[r].whole_arrays_mib);
      line(fmt::format("rank{}_part_arrays_mib", r), ranks[r].part_arrays_mib);
      line(fmt::format("rank{}_model_held_mib", r), ranks[r].model_arrays_mib);
      line(fmt::format("rank{}_rescue_copy_mib", r), ranks[r].rescue_mib);
      line(fmt::format("rank{}_peak_mib", r), ranks[r].peak_mib);
    }
    for (std::size_t r = 0; r < c.cycle_peaks_mib.size(); ++r) line(fmt::format("rank{}_cycle_peak_mib", r), c.cycle_peaks_mib[r]);
  }
  if (file.empty()) {
    ctx.out << text;
    return;
  }
  write_file_atomically(file, text);
  ctx.out << fmt::format("counters written to {}\n", file);
}

}  // namespace trubal
