#include <algorithm>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "commands/common.hpp"
#include "model/edit.hpp"
#include "physics/measure.hpp"
#include "physics/measure_sphere.hpp"
#include "physics/walls.hpp"
#include "support/comm.hpp"

namespace trubal {

// Under mpirun HIST runs on every rank (OnRanks::Parts), which may hold no more of the model than
// its light state and the balls' ids, types and radii (Session::light_everywhere): what reads the
// balls themselves (the platen balls of a range) is rank 0's, its failure every rank's
// (comm::on_root).

static void run_hist(Context& ctx, Args& args) {
  ctx.session.require_started();
  if (args.accept("reset")) {
    args.done();
    ctx.session.history().clear();
    ctx.out << "histories cleared\n";
    return;
  }
  std::vector<std::string> items;
  std::int64_t every = 10;
  std::string file;
  double area = 0, pressure = 0;
  bool membrane_area = false;
  HistoryFileMode mode = HistoryFileMode::Default;
  const auto& names = History::item_names();
  while (!args.empty() && !match_keyword(args.peek(), {"range"})) {
    if (args.accept("every")) { every = args.count("every", 1); continue; }
    if (args.accept("file")) { file = args.word("file name"); continue; }
    if (args.accept("area")) { area = args.real("area"); continue; }
    if (args.accept("pressure")) { pressure = args.real("pressure"); continue; }
    if (args.accept("new")) { mode = HistoryFileMode::New; continue; }
    if (args.accept("append")) { mode = HistoryFileMode::Append; continue; }
    std::string item(names[args.expect(names, "history item")]);
    if (item == "wall") {
      const std::int64_t id = args.count("wall id", 1);
      if (!find_wall(ctx.session.state(), id))
        args.fail(fmt::format("there is no wall {} (PRINT walls lists them)", id));
      item = fmt::format("wall {}", id);
    } else if (item == "ball") {
      const std::int64_t id = args.count("ball id", 1);
      if (find_ball(ctx.session.state(), id) < 0)
        args.fail(fmt::format("there is no ball {} (PRINT balls lists them)", id));
      const auto& quantities = History::ball_quantities();
      std::vector<std::string_view> asked;
      // Its quantities: the words that name one exactly (x, vz, fx: no prefixes, they are short).
      while (!args.empty()) {
        const auto q = std::find_if(quantities.begin(), quantities.end(),
                                    [&](std::string_view n) { return to_lower(args.peek()) == n; });
        if (q == quantities.end()) break;
        if (std::find(asked.begin(), asked.end(), *q) != asked.end())
          args.fail(fmt::format("`ball {}` names {} twice", id, *q));
        asked.push_back(*q);
        args.word("ball quantity");
      }
      if (asked.empty())
        args.fail(fmt::format("`ball {}` needs the quantities to record, any of: {}", id, fmt::join(quantities, " ")));
      item = fmt::format("ball {} {}", id, fmt::join(asked, " "));
    } else if (item == "measure") {
      if (!args.accept("sphere")) args.fail("`measure` takes its sphere: `measure sphere x y z r [id n]`");
      MeasureSphere sphere;
      for (double& c : sphere.centre) c = args.real("sphere centre");
      sphere.radius = args.real("sphere radius");
      if (!(sphere.radius > 0)) args.fail("a measurement sphere needs a positive radius");
      // Its columns are m<id>_...: the id given, else one more than the measurement spheres so far.
      std::int64_t id = 0;
      if (args.accept("id")) id = args.count("measurement sphere id", 1);
      else {
        id = 1;
        for (const auto& t : ctx.session.history().tables())
          for (const auto& it : t->items) id += it.rfind("measure ", 0) == 0;
        for (const auto& it : items) id += it.rfind("measure ", 0) == 0;
      }
      // A sphere the cell cannot hold is refused now (from the balls' radii, which every rank holds).
      try {
        check_measure_sphere(ctx.session.state().space, sphere, ctx.session.state().balls.max_radius());
      } catch (const std::runtime_error& e) {
        args.fail(e.what());
      }
      item = measure_item(id, sphere);
    }
    items.push_back(std::move(item));
  }
  if (items.empty()) args.fail("name at least one quantity to record");
  if (std::find(items.begin(), items.end(), "sample") != items.end()) {
    if (!ctx.session.state().sample.declared())
      args.fail("`sample` records the sample between walls: declare it first (SAMPLE platens a b cylinder c)");
    if (std::find(items.begin(), items.end(), "pq") != items.end())
      args.fail("`sample` and `pq` would both make columns p and q: give them to two HISTs");
  }
  if (mode != HistoryFileMode::Default && file.empty()) args.fail("`new` and `append` go with `file f.csv`");
  Range range = read_range(args, ctx.session);
  auto has = [&](const char* item) { return std::find(items.begin(), items.end(), item) != items.end(); };
  const bool rowe = has("ratio") || has("axial");
  if (!range.empty() && !has("platen") && !rowe)
    args.fail("a RANGE goes with `platen`, `ratio` or `axial` (the platen balls)");
  std::vector<std::int64_t> ids;
  double gap0 = 0;
  if (!range.empty()) {
    PlatenBalls rows;
    ids = ctx.session.platen_choice(range, rows);   // (rank 0's; a collective call)
    comm::on_root([&] {
      const Model& model = ctx.session.state();   // (the membrane's area and pressure)
      if (ids.empty()) args.fail("the range holds for no ball: name the platen balls (e.g. range group platens)");
      const Platens p = platens(rows);
      if (rowe && !p.two)
        args.fail("`ratio` and `axial` with a range need both platens in it (balls at two heights)");
      gap0 = p.gap;
      if (area == 0) { area = model.membrane.area; membrane_area = area > 0; }
      if (pressure == 0) pressure = model.membrane.pressure;
      if (has("ratio") && !(area > 0 && pressure > 0))
        args.fail("`ratio` with a range needs the area and the confining pressure: give MEMBRANE first, or "
                  "`area a pressure p`");
    }, "choosing the platen balls");
    if (comm::size() > 1) {   // (rank 0's answer)
      comm::broadcast(ids);
      std::vector<double> got{gap0, area, pressure, membrane_area ? 1.0 : 0.0};
      comm::broadcast(got);
      gap0 = got[0];
      area = got[1];
      pressure = got[2];
      membrane_area = got[3] != 0;
    }
  }
  auto added = ctx.session.history().add(items, every, file, range, mode, ctx.session.state().cycle);
  if (added.continued) {
    ctx.out << fmt::format("recording {} every {} cycles to {} (going on: {} rows so far)\n",
                           fmt::join(added.table.columns, ","), every, file, added.table.recorded);
    return;
  }
  if (!added.note.empty()) ctx.warn(added.note);
  auto& t = added.table;
  t.platen_ids = std::move(ids);
  t.platen_gap0 = gap0;
  t.area = area;
  t.membrane_area = membrane_area;
  t.pressure = pressure;
  ctx.out << fmt::format("recording {} every {} cycles{}\n", fmt::join(t.columns, ","), every,
                         file.empty() ? "" : " to " + file);
  if (rowe && !t.platen_ids.empty())
    ctx.out << fmt::format("  platens: {} balls, {:.6g} apart; area {:.6g}, confining pressure {:.6g}\n",
                           t.platen_ids.size(), gap0, area, pressure);
}

const Command hist_command = {
    "HIST", {},
    "HIST what... [every n] [file f.csv [new|append]] [area a] [pressure p] [range ...]  |  HIST reset;  what: sample stress pq strain volumetric ratio sratio axial platen energy rolling bridges bonds unbal contacts porosity time, wall n, ball id x y z vx vy vz wx wy wz fx fy fz, measure sphere x y z r [id n]",
    "record quantities every n cycles",
    "Records quantities every n cycles (default 10): sample (ea ev sig1 sig3 q p: the axial and volumetric "
    "strains, sigma1, sigma3, the deviator and the mean stress of the sample between walls that SAMPLE "
    "declares, compression positive; NaN once it is gone), stress (s11 s22 s33 s12 s13 s23), pq (p = (s11 + s22 + s33) / 3 "
    "and q = s33 - (s11 + s22) / 2, the mean stress and the deviator of a triaxial test with z the axial direction, "
    "compression positive; in a dry sample the effective stresses p' and q), strain (e11 e22 e33 e12 e13 e23), "
    "volumetric (evol = 1 - V/V0, the cell's loss of volume over its volume V0 at START or the last STRAIN reset, "
    "compression positive: a strain, about e11 + e22 + e33 while they are small), "
    "porosity (porosity void_ratio: of the whole space, the balls' volume over SET volume, the periodic cell or the "
    "START box), measure sphere x y z r [id n] (a measurement sphere, PFC's: m<n>_s11 ... m<n>_s23 its stress, "
    "m<n>_porosity, m<n>_void_ratio, m<n>_coordination, m<n>_sliding, m<n>_f11 ... m<n>_f23 its fabric; PRINT "
    "measure and the man page say how each is taken; n counts the spheres from 1 unless given; NaN where a "
    "periodic cell has shrunk until it cannot hold the sphere), "
    "ratio, sratio, axial, platen, wall n (w<n>_fx w<n>_fy w<n>_fz: the force on wall n; w<n>_stress; w<n>_pos: a "
    "cylinder's radius, else the plane's offset point.normal), ball id followed by any of x y z vx vy vz wx wy "
    "wz fx fy fz, in the order given (b<id>_x ... b<id>_fz: one ball's position, velocity, spin and unbalanced "
    "force, PFC's ball histories, as PRINT balls shows them: the position at the model's time, the velocity "
    "and spin at the half step before it, the force of the last step; the id must be a ball's when HIST is "
    "given; the ball is found by its id at each record, so after RENUMBER it is the ball that has that id "
    "then, and NaN is recorded once no ball has it, after DELETE or an escape from the START box), energy (ke "
    "strain_energy friction_work damping_work boundary_work potential; potential is gravity's, as PRINT energy "
    "shows it), rolling (rolling_work: the work the rolling springs' limit dissipated, PROP rr_fric), bridges "
    "(bridges capillary_work: the capillary bridges intact, between balls and to walls, and the work they did "
    "on the balls, PROP bridge), bonds (bonds_intact bonds_broken broken_tension broken_shear: the parallel "
    "bonds intact, those broken, and of them those broken in tension and in shear, BOND), unbal (mean "
    "unbalanced-force ratio), contacts (contacts sliding coordination), time. The range names the platen "
    "balls, fixed as the balls where it holds now (a group is the safe choice, since they move). With a "
    "range holding the top and bottom platens (the balls above and below the middle of its height): ratio "
    "is R = sigma1/sigma2 = F1 / (A sigma2), F1 the axial force the platens carry (half the difference of "
    "the upper and lower platens' z reactions, compression positive), A and sigma2 from the last MEMBRANE "
    "(or `area a` and `pressure p`); axial is eps1 = 2 delta / dh, the platens' approach over their first "
    "distance apart (delta the displacement of one platen, dh the distance between their centres when HIST "
    "is given). Without a range, ratio is s33 over the mean of s11 and s22 and axial is the cell strain e33. "
    "sratio is sigma1/sigma3 of the assembly itself: s33 over the mean of s11 and s22 of its average stress "
    "from the contact forces (Love's formula over every contact; the volume cancels), which for Rowe's "
    "test is F1 / (S sigma2) with S the section through the perimeter balls' centres, where the membrane "
    "acts (doc/validation.md, 5). "
    "platen is the z reaction force of the balls in the range (all balls without one). With `file` the rows "
    "are written as CSV (header cycle,time,... then one row per record, flushed as they come), and memory keeps "
    "only the last 10,000 to 20,000 (PRINT history shows those, PLOT reads the file back), so a long `every 1` "
    "run does not fill the memory; without `file` every row stays in memory. A file that is there already is "
    "started afresh (`new`, the default; without the word HIST says how many rows of an earlier run it "
    "replaced), or with `append` kept up to the present cycle (later rows, of a later part of the run that "
    "wrote it, are dropped, and so is a last row cut short by a full disk or a kill, the file cut where they "
    "start and its bytes before kept as they were) and added "
    "to, the file read a row at a time (memory keeps its last 10,000 rows, however long it is); its columns "
    "must be this HIST's. A second HIST on the file of a live "
    "history is refused, unless it asks for the same quantities every the same period: then that history goes "
    "on (a deck that repeats its HIST after RESTART, which resumes the saved histories). SAVE keeps the "
    "histories. `HIST reset` forgets all histories.",
    "hist stress strain every 100 file tri.csv",
    {"sample", "stress", "pq", "strain", "volumetric", "ratio", "sratio", "axial", "platen", "energy", "rolling", "bridges", "bonds", "unbal", "contacts", "time", "wall", "ball",
     "x", "y", "z", "vx", "vy", "vz", "wx", "wy", "wz", "fx", "fy", "fz",
     "porosity", "measure", "sphere", "id", "every", "file", "area", "pressure", "reset", "new", "append", "range"},
    run_hist, false, false, OnRanks::Parts};

}  // namespace trubal
