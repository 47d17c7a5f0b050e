#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <sstream>

#include <fmt/format.h>

#include "commands/common.hpp"
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

namespace trubal {

void print_sample(Context& ctx);   // commands/sample.cpp

static const std::vector<std::string_view> kItems = {"info", "balls", "contacts", "stress", "strain",
                                                     "energy", "fabric", "coordination", "prop", "damp",
                                                     "history", "walls", "psd", "porosity", "measure", "counters",
                                                     "sample"};

// The region of PRINT stress, fabric, coordination, porosity and measure: a measurement sphere,
// given as the range element `sphere x y z r` (nothing else, since the measurement needs a volume).
static std::optional<MeasureSphere> measurement_sphere(Args& args, const Range& range) {
  if (range.empty()) return std::nullopt;
  if (range.size() != 1 || range[0].kind != RangeElement::Kind::Sphere || range[0].negate)
    args.fail("a measurement region is one sphere: `range sphere x y z r` (PFC's measurement sphere)");
  MeasureSphere s;
  s.centre = {range[0].v[0], range[0].v[1], range[0].v[2]};
  s.radius = range[0].v[3];
  return s;
}

static void print_sphere_header(Context& ctx, const MeasureSphere& s, const SphereMeasurement& m) {
  ctx.out << fmt::format("measurement sphere at ({:.6g}, {:.6g}, {:.6g}), radius {:.6g}: {} balls, {} contacts\n",
                         s.centre[0], s.centre[1], s.centre[2], s.radius, m.balls, m.contacts);
}

static void print_porosity(Context& ctx, double porosity, double void_ratio, double solid, double volume) {
  ctx.out << fmt::format("porosity: {:.6g}\nvoid ratio: {:.6g}\nsolid volume: {:.6g} of {:.6g}\n", porosity, void_ratio,
                         solid, volume);
}

// How far apart balls of consecutive ids lie, in diameters (medians of both): about 1 where the
// balls are numbered in space order (a lattice, GEN, RENUMBER), tens where at random. Memory holds
// the balls in id order, so the contact loop reads the latter far more slowly. 0 for < 2 balls.
static double id_gap_in_diameters(const Balls& b) {
  if (b.size() < 2) return 0;
  std::vector<double> gap(b.size() - 1), rad(b.rad);
  for (std::size_t k = 1; k < b.size(); ++k)
    gap[k - 1] = std::hypot(b.x[k] - b.x[k - 1], b.y[k] - b.y[k - 1], b.z[k] - b.z[k - 1]);
  auto median = [](std::vector<double>& v) {
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
  };
  const double diameter = 2 * median(rad);
  return diameter > 0 ? median(gap) / diameter : 0;
}

static void print_info(Context& ctx) {
  const Session& s = ctx.session;
  const Model& m = s.model();
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
  o << fmt::format("balls: {}\n", m.balls.size());
  if (m.balls.size() >= 2) {
    const double gap = id_gap_in_diameters(m.balls);
    o << fmt::format("ball order: consecutive ids {:.3g} diameters apart (median){}\n", gap,
                     gap > 3 ? "; numbered at random, the contact loop reads memory slowly: RENUMBER numbers them in space order" : "");
  }
  o << fmt::format("contacts: {}\n", contact_count(m));
  if (!m.walls.empty()) {
    std::size_t touching = 0;
    for (auto st : m.wall_contacts.state) touching += st != 0;
    o << fmt::format("walls: {} ({} ball-wall contacts)\n", m.walls.size(), touching);
  }
  if (has_bridges(m))
    o << fmt::format("bridges intact: {} between balls, {} to walls\n", count_bridges(m.contacts),
                     count_bridges(m.wall_contacts));
  o << fmt::format("cycle: {}\n", m.cycle);
  o << fmt::format("time: {}\n", m.time);
  o << fmt::format("timestep: {}\n", m.dt);
  o << fmt::format("frac: {}\n", m.settings.frac);
  if (m.settings.fixed_dt > 0) o << fmt::format("fixed timestep: {}\n", m.settings.fixed_dt);
  if (m.space.destroyed > 0) o << fmt::format("balls destroyed: {} (they left the box)\n", m.space.destroyed);
  o << fmt::format("backend: {}\n", s.pipeline().backend().name());
  o << fmt::format("threads: {}\n", s.pipeline().threads());
  if (comm::launched()) o << fmt::format("ranks: {}\n", comm::size());   // (under mpirun, one rank included)
  // The process's peak resident memory so far (every rank's, gathered: every rank runs PRINT).
  o << fmt::format("peak memory: {} MiB{}\n", mib_list(peak_memory_per_rank()), comm::size() > 1 ? " (per rank)" : "");
  if (comm::size() > 1) {   // (gathered: every rank runs PRINT)
    std::vector<double> mine{static_cast<double>(m.contacts.result_bytes()) / (1 << 20)}, all;
    comm::allgather(mine, all);
    o << fmt::format("contact results held: {} MiB (per rank: rank 0 alone makes those a command reads after a "
                     "CYCLE, for what it prints and writes)\n", mib_list(all));
  }
  for (const auto& [k, v] : s.pipeline().info()) o << k << ": " << v << '\n';
  const Features f = scene_features(m);
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
// stays (HELP lists them), for scripts and tests to read. Every rank runs it (the per-rank values
// are gathered); rank 0 alone prints or writes.
static void print_counters(Context& ctx, const std::string& file) {
  const Session& s = ctx.session;
  const Model& m = s.model();
  const PipelineCounters c = s.pipeline().counters();
  std::size_t wall_touching = 0;
  for (auto st : m.wall_contacts.state) wall_touching += st != 0;
  std::string text;
  auto line = [&](std::string_view name, auto value) { text += fmt::format("{} {}\n", name, value); };
  line("cycle", m.cycle);
  line("balls", m.balls.size());
  line("contacts", contact_count(m));
  line("wall_contacts", wall_touching);
  line("balls_destroyed", m.space.destroyed);
  line("ranks", comm::size());
  line("threads", s.pipeline().threads());
  line("threads_used", c.threads_used);
  line("pair_list_rebuilds", c.rebuilds);
  line("pair_tests", c.pair_tests);
  line("results_made", c.results_made);
  line("decompositions", c.parts.decompositions);
  line("part_list_rebuilds", c.parts.list_rebuilds);
  line("part_wraps", c.parts.wraps);
  line("migrations", c.parts.migrations);
  line("ghosts", c.parts.ghosts);
  line("least_part_balls", c.parts.least_balls);
  line("most_part_balls", c.parts.most_balls);
  if (comm::size() > 1) {   // (gathered: every rank runs PRINT)
    std::vector<double> mine{static_cast<double>(m.contacts.result_bytes()) / (1 << 20), c.whole_arrays_mib,
                             c.part_arrays_mib}, all;
    comm::allgather(mine, all);
    for (std::size_t r = 0; 3 * r + 2 < all.size(); ++r) {
      line(fmt::format("rank{}_contact_results_mib", r), all[3 * r]);
      line(fmt::format("rank{}_whole_arrays_mib", r), all[3 * r + 1]);
      line(fmt::format("rank{}_part_arrays_mib", r), all[3 * r + 2]);
    }
    for (std::size_t r = 0; r < c.cycle_peaks_mib.size(); ++r) line(fmt::format("rank{}_cycle_peak_mib", r), c.cycle_peaks_mib[r]);
  }
  if (!comm::root()) return;
  if (file.empty()) {
    ctx.out << text;
    return;
  }
  write_file_atomically(file, text);
  ctx.out << fmt::format("counters written to {}\n", file);
}

static void print_balls(Context& ctx, const Range& range, const std::string& file) {
  const Model& m = ctx.session.model();
  const Balls& b = m.balls;
  auto sel = ctx.session.select(range);
  if (!comm::root()) return;   // (the table or file is rank 0's to print or write: the others' would go nowhere)
  if (!file.empty()) {
    write_file_atomically(file, [&](std::ostream& csv) {
      csv << "id,type,x,y,z,rad,vx,vy,vz,wx,wy,wz,fx,fy,fz\n";
      for (auto k : sel) {
        csv << b.id[k] << ',' << b.type[k];
        for (const auto* v : {&b.x, &b.y, &b.z, &b.rad, &b.vx, &b.vy, &b.vz, &b.wx, &b.wy, &b.wz, &b.fx, &b.fy, &b.fz})
          csv << ',' << csv_real((*v)[k]);
        csv << '\n';
      }
    });
    ctx.out << fmt::format("{} written to {}\n", count_of(sel.size(), "ball"), file);
    return;
  }
  ctx.out << fmt::format("{:>8} {:>4} {:>12} {:>12} {:>12} {:>10} {:>11} {:>11} {:>11} {:>11} {:>11} {:>11}\n", "id",
                         "type", "x", "y", "z", "rad", "vx", "vy", "vz", "fx", "fy", "fz");
  for (auto k : sel)
    ctx.out << fmt::format("{:>8} {:>4} {:>12.6g} {:>12.6g} {:>12.6g} {:>10.4g} {:>11.4g} {:>11.4g} {:>11.4g} {:>11.4g} "
                           "{:>11.4g} {:>11.4g}\n",
                           b.id[k], b.type[k], b.x[k], b.y[k], b.z[k], b.rad[k], b.vx[k], b.vy[k], b.vz[k], b.fx[k],
                           b.fy[k], b.fz[k]);
}

static void print_contacts(Context& ctx, const Range& range, const std::string& file) {
  const Model& m = ctx.session.model();
  const ContactTable& c = m.contacts;
  std::vector<bool> in(m.balls.size(), range.empty());
  if (!range.empty())
    for (auto k : ctx.session.select(range)) in[k] = true;
  if (!comm::root()) return;   // (as print_balls)
  std::vector<std::size_t> rows;
  // (Capillary bridges: the pairs they hold apart too, and a column saying which hold one.)
  const bool bridges = has_bridges(m) && c.bridge.size() == c.size();
  for (std::size_t p = 0; p < c.size(); ++p)
    if ((c.touching(p) || (bridges && c.bridge[p] != 0)) && (in[c.i[p]] || in[c.j[p]])) rows.push_back(p);
  const auto& id = m.balls.id;
  const bool rolling = has_rolling(m);   // (the rolling moment on j: columns only where a material has it)
  if (!file.empty()) {
    write_file_atomically(file, [&](std::ostream& csv) {
      csv << "i,j,nx,ny,nz,overlap,fn,fsx,fsy,fsz," << (rolling ? "mrx,mry,mrz," : "") << "sliding"
          << (bridges ? ",bridge\n" : "\n");
      for (auto p : rows) {
        csv << id[c.i[p]] << ',' << id[c.j[p]];
        for (const auto* v : {&c.nx, &c.ny, &c.nz, &c.overlap, &c.fn, &c.fsx, &c.fsy, &c.fsz}) csv << ',' << csv_real((*v)[p]);
        if (rolling)
          for (const auto* v : {&c.mrx, &c.mry, &c.mrz}) csv << ',' << csv_real((*v)[p]);
        csv << ',' << (c.state[p] == 2 ? 1 : 0);
        if (bridges) csv << ',' << (c.bridge[p] != 0 ? 1 : 0);
        csv << '\n';
      }
    });
    ctx.out << fmt::format("{} contacts written to {}\n", rows.size(), file);
    return;
  }
  ctx.out << fmt::format("{:>8} {:>8} {:>9} {:>9} {:>9} {:>11} {:>11} {:>11} {}{:>7}{}\n", "i", "j", "nx", "ny", "nz",
                         "overlap", "fn", "|fs|", rolling ? fmt::format("{:>11} ", "|mr|") : "", "sliding",
                         bridges ? "  bridge" : "");
  for (auto p : rows)
    ctx.out << fmt::format("{:>8} {:>8} {:>9.5f} {:>9.5f} {:>9.5f} {:>11.4g} {:>11.4g} {:>11.4g} {}{:>7}{}\n", id[c.i[p]],
                           id[c.j[p]], c.nx[p], c.ny[p], c.nz[p], c.overlap[p], c.fn[p],
                           std::sqrt(c.fsx[p] * c.fsx[p] + c.fsy[p] * c.fsy[p] + c.fsz[p] * c.fsz[p]),
                           rolling ? fmt::format("{:>11.4g} ", std::sqrt(c.mrx[p] * c.mrx[p] + c.mry[p] * c.mry[p] +
                                                                         c.mrz[p] * c.mrz[p]))
                                   : "",
                           c.state[p] == 2 ? "yes" : "no",
                           bridges ? (c.bridge[p] != 0 ? "     yes" : "      no") : "");
}

static void print_sym(Context& ctx, const char* what, const Sym6& s) {
  ctx.out << fmt::format("{}: xx {:.6g}  yy {:.6g}  zz {:.6g}  xy {:.6g}  xz {:.6g}  yz {:.6g}\n", what, s[0], s[1], s[2],
                         s[3], s[4], s[5]);
}

static void print_history(Context& ctx) {
  const auto& tables = ctx.session.history().tables();
  if (tables.empty()) ctx.out << "no histories (HIST records them)\n";
  for (const auto& t : tables) {
    ctx.out << fmt::format("history every {} cycles{}: {} rows{}\n", t->every, t->file.empty() ? "" : " -> " + t->file,
                           t->recorded,
                           t->recorded > t->rows.size()
                               ? fmt::format(" (the last {} below; every row is in the file)", t->rows.size())
                               : std::string());
    for (const auto& c : t->columns) ctx.out << fmt::format("{:>14}", c);
    ctx.out << '\n';
    for (const auto& row : t->rows) {
      for (double v : row) ctx.out << fmt::format("{:>14.6g}", v);
      ctx.out << '\n';
    }
  }
}

static void print_walls(Context& ctx, const std::string& file) {
  const Model& m = ctx.session.model();
  if (!file.empty()) {
    std::ostringstream csv;
    csv << "id,kind,type,x,y,z,nx,ny,nz,radius,vx,vy,vz,wx,wy,wz,rrate,fx,fy,fz,mx,my,mz,stress,contacts,work\n";
    for (const Wall& w : m.walls) {
      const Vec3 c = wall_centre(w);
      // No area, no stress: nan, as the screen's "(no area)" and HIST's w<n>_stress say it.
      const double stress = wall_servo_area(m, w) > 0 ? wall_stress(m, w) : std::numeric_limits<double>::quiet_NaN();
      csv << w.id << ',' << wall_kind_name(w.kind) << ',' << w.type;
      for (double v : {c[0], c[1], c[2], w.normal[0], w.normal[1], w.normal[2], w.radius, w.velocity[0], w.velocity[1],
                       w.velocity[2], w.spin[0], w.spin[1], w.spin[2], w.radius_rate, w.force[0], w.force[1], w.force[2],
                       w.moment[0], w.moment[1], w.moment[2], stress})
        csv << ',' << csv_real(v);
      csv << ',' << w.contacts << ',' << csv_real(w.work) << '\n';
    }
    write_file_atomically(file, csv.str());
    ctx.out << fmt::format("{} walls written to {}\n", m.walls.size(), file);
    return;
  }
  if (m.walls.empty()) { ctx.out << "no walls (WALL makes them)\n"; return; }
  for (const Wall& w : m.walls) {
    const Vec3 c = wall_centre(w);
    ctx.out << fmt::format("wall {} ({} of type {}): centre ({:.6g}, {:.6g}, {:.6g}), {} ({:.6g}, {:.6g}, {:.6g})", w.id,
                           wall_kind_name(w.kind), w.type, c[0], c[1], c[2], w.kind == WallKind::Cylinder ? "axis" : "normal",
                           w.normal[0], w.normal[1], w.normal[2]);
    if (w.kind == WallKind::Cylinder)
      ctx.out << fmt::format(", radius {:.6g}, length {:.6g}, balls {}", w.radius, w.length, w.inside ? "inside" : "outside");
    if (w.kind == WallKind::Polygon) ctx.out << fmt::format(", {} vertices", w.vertices.size());
    ctx.out << '\n';
    ctx.out << fmt::format("  velocity ({:.6g}, {:.6g}, {:.6g})  spin ({:.6g}, {:.6g}, {:.6g})", w.velocity[0], w.velocity[1],
                           w.velocity[2], w.spin[0], w.spin[1], w.spin[2]);
    if (w.kind == WallKind::Cylinder) ctx.out << fmt::format("  radius rate {:.6g}", w.radius_rate);
    if (w.servo_on) ctx.out << fmt::format("  servo to {:.6g}", w.servo_target);
    ctx.out << '\n';
    const double area = wall_servo_area(m, w);
    ctx.out << fmt::format("  force ({:.6g}, {:.6g}, {:.6g})  moment ({:.6g}, {:.6g}, {:.6g})  stress {}  contacts {}  "
                           "work {:.6g}\n",
                           w.force[0], w.force[1], w.force[2], w.moment[0], w.moment[1], w.moment[2],
                           area > 0 ? fmt::format("{:.6g}", wall_stress(m, w)) : std::string("(no area)"), w.contacts, w.work);
  }
}

// The grading of the balls the last GEN made (those still there) next to the one it asked for.
static void print_psd(Context& ctx, const std::string& file) {
  const auto& sizes = ctx.session.last_sizes();
  if (!sizes) throw std::runtime_error("PRINT psd: no GEN since START or RESTART (it compares the last GEN's balls with its sizes)");
  const Model& m = ctx.session.model();
  std::vector<double> radii;
  for (std::int64_t id : ctx.session.last_generated()) {
    auto it = std::lower_bound(m.balls.id.begin(), m.balls.id.end(), id);
    if (it != m.balls.id.end() && *it == id) radii.push_back(m.balls.rad[static_cast<std::size_t>(it - m.balls.id.begin())]);
  }
  if (radii.empty()) throw std::runtime_error("PRINT psd: the balls of the last GEN are gone");
  const auto rows = compare_grading(*sizes, radii);
  double worst = 0, at = 0;
  for (const auto& r : rows)
    if (std::abs(r.sample - r.asked) > worst) { worst = std::abs(r.sample - r.asked); at = r.diameter; }
  if (!file.empty()) {
    std::ostringstream csv;
    csv << "diameter,passing_asked,passing_sample\n";
    for (const auto& r : rows) csv << csv_real(r.diameter) << ',' << csv_real(r.asked) << ',' << csv_real(r.sample) << '\n';
    write_file_atomically(file, csv.str());
    ctx.out << fmt::format("grading at {} diameters written to {}\n", rows.size(), file);
  } else {
    ctx.out << fmt::format("grading of the last GEN's {} balls ({}), percent passing by mass:\n", radii.size(),
                           sizes->describe());
    ctx.out << fmt::format("{:>14} {:>10} {:>10} {:>10}\n", "diameter", "asked", "sample", "difference");
    for (const auto& r : rows)
      ctx.out << fmt::format("{:>14.6g} {:>10.3f} {:>10.3f} {:>10.3f}\n", r.diameter, r.asked, r.sample, r.sample - r.asked);
  }
  ctx.out << fmt::format("largest difference: {:.3f} percent passing, at diameter {:.6g}\n", worst, at);
}

static void run_print(Context& ctx, Args& args) {
  auto item = args.expect(kItems, "PRINT item");
  std::string file;
  if (args.accept("file")) file = args.word("file name");
  if (!file.empty() && item != 1 && item != 2 && item != 11 && item != 12 && item != 15)
    args.fail("`file` goes with PRINT balls, contacts, walls, psd and counters");
  const Model& m = ctx.session.model();
  switch (item) {
    case 0: args.done(); print_info(ctx); return;
    case 16: args.done(); print_sample(ctx); return;
    case 15: args.done(); print_counters(ctx, file); return;
    case 1: print_balls(ctx, read_range(args, ctx.session), file); return;
    case 2: print_contacts(ctx, read_range(args, ctx.session), file); return;
    case 3: {
      double volume = 0;
      if (args.accept("volume")) volume = args.real("volume");
      const auto sphere = measurement_sphere(args, read_range(args, ctx.session));
      ctx.session.require_started();
      if (sphere) {
        if (volume > 0) args.fail("`volume` goes with the whole space's stress, not a measurement sphere's");
        const SphereMeasurement sm = measure_sphere(m, *sphere);
        print_sphere_header(ctx, *sphere, sm);
        print_sym(ctx, "stress", sm.stress);
        return;
      }
      print_sym(ctx, "stress", average_stress(m, volume > 0 ? volume : ctx.session.stress_volume()));
      return;
    }
    case 4: {
      args.done();
      const auto& e = m.space.strain;
      ctx.out << fmt::format("strain: xx {:.6g}  yy {:.6g}  zz {:.6g}  xy {:.6g}  xz {:.6g}  yz {:.6g}\n", e[0], e[1],
                             e[2], e[3], e[4], e[5]);
      if (m.space.periodic)
        ctx.out << fmt::format("volumetric strain: {:.6g} (1 - V/V0, compression positive)\n", volumetric_strain(m));
      return;
    }
    case 5: {
      args.done();
      EnergyReport e = energy(ctx.session.model_with_masses());   // before the first CYCLE too
      if (e.at_step)
        ctx.out << fmt::format("at the last force pass (cycle {}, time {:.8g}):\n", m.cycle - 1, m.time - m.dt);
      else
        ctx.out << "of the state as it is (no step since the balls or the settings last changed):\n";
      ctx.out << fmt::format(
          "kinetic (translation): {:.8g}\nkinetic (rotation): {:.8g}\nstrain: {:.8g}\npotential (gravity): "
          "{:.8g}\nfriction work: {:.8g}\n{}damping work: {:.8g}\nboundary work: {:.8g}\n{}balance (should stay "
          "constant): {:.8g}\n",
          e.kinetic_translation, e.kinetic_rotation, e.strain, e.potential, e.friction_work,
          has_rolling(m) || e.rolling_work != 0 ? fmt::format("rolling work: {:.8g}\n", e.rolling_work) : "",
          e.damping_work, e.boundary_work,
          has_bridges(m) || e.capillary_work != 0 ? fmt::format("capillary work: {:.8g}\n", e.capillary_work) : "",
          e.total());
      return;
    }
    case 6: {
      if (const auto sphere = measurement_sphere(args, read_range(args, ctx.session))) {
        const SphereMeasurement sm = measure_sphere(m, *sphere);
        print_sphere_header(ctx, *sphere, sm);
        print_sym(ctx, "fabric", sm.fabric);
        return;
      }
      print_sym(ctx, "fabric", fabric_tensor(m));
      return;
    }
    case 7: {
      if (const auto sphere = measurement_sphere(args, read_range(args, ctx.session))) {
        const SphereMeasurement sm = measure_sphere(m, *sphere);
        print_sphere_header(ctx, *sphere, sm);
        ctx.out << fmt::format("coordination number: {:.6g}\nsliding fraction: {:.6g}\ncontacts: {}\n", sm.coordination,
                               sm.sliding, sm.contacts);
        return;
      }
      ctx.out << fmt::format("coordination number: {:.6g}\nsliding fraction: {:.6g}\ncontacts: {}\n",
                             coordination_number(m), sliding_fraction(m), contact_count(m));
      auto u = unbalanced_force(m);
      ctx.out << fmt::format("unbalanced-force ratio: mean {:.4g}  max {:.4g}\n", u.mean_ratio, u.max_ratio);
      return;
    }
    case 8: {
      args.done();
      if (m.materials.empty()) ctx.out << "no materials (PROP sets them)\n";
      for (const auto& [t, p] : m.materials)
        ctx.out << fmt::format("type {}: kn {:.6g} ks {:.6g} mu {:.6g} (fric {:.4g} deg) dens {:.6g} coh {:.6g}{}{}{}{}\n", t,
                               p.kn, p.ks, p.friction, std::atan(p.friction) * 180 / std::numbers::pi, p.density,
                               p.cohesion,
                               p.hertz() ? fmt::format(" shear {:.6g} poisson {:.4g} (Hertz-Mindlin)", p.shear_modulus,
                                                       p.poisson)
                                         : "",
                               p.has_restitution ? fmt::format(" rest {:.4g}", p.restitution) : "",
                               p.rolling_friction > 0 ? fmt::format(" rr_fric {:.4g}", p.rolling_friction) : "",
                               p.bridge_volume > 0 ? fmt::format(" bridge {:.6g} tension {:.6g} angle {:.4g}", p.bridge_volume,
                                                                 p.surface_tension, p.contact_angle * 180 / std::numbers::pi)
                                                   : "");
      return;
    }
    case 9: {
      args.done();
      const Damping& d = m.settings.damping;
      switch (d.kind) {
        case DampKind::None: ctx.out << "damping: none\n"; break;
        case DampKind::Local: ctx.out << fmt::format("damping: local {:.4g}\n", d.local); break;
        case DampKind::Rayleigh:
          ctx.out << fmt::format("damping: Rayleigh, mass coefficient {:.6g}, stiffness coefficient {:.6g}", d.alpha, d.beta);
          if (d.freq > 0) ctx.out << fmt::format(" (lambda {:.4g} at {:.4g} Hz)", d.lambda, d.freq);
          ctx.out << '\n';
          break;
      }
      return;
    }
    case 10: args.done(); print_history(ctx); return;
    case 11: args.done(); print_walls(ctx, file); return;
    case 12: args.done(); print_psd(ctx, file); return;
    case 13: {
      const auto sphere = measurement_sphere(args, read_range(args, ctx.session));
      ctx.session.require_started();
      if (sphere) {
        const SphereMeasurement sm = measure_sphere(m, *sphere);
        print_sphere_header(ctx, *sphere, sm);
        print_porosity(ctx, sm.porosity, sm.void_ratio, sm.solid, sm.volume);
        return;
      }
      const Porosity p = space_porosity(m, ctx.session.stress_volume());
      print_porosity(ctx, p.porosity, p.void_ratio, p.solid, p.volume);
      return;
    }
    case 14: {
      const auto sphere = measurement_sphere(args, read_range(args, ctx.session));
      if (!sphere) args.fail("PRINT measure needs its sphere: `range sphere x y z r`");
      ctx.session.require_started();
      const SphereMeasurement sm = measure_sphere(m, *sphere);
      print_sphere_header(ctx, *sphere, sm);
      print_sym(ctx, "stress", sm.stress);
      print_porosity(ctx, sm.porosity, sm.void_ratio, sm.solid, sm.volume);
      ctx.out << fmt::format("coordination number: {:.6g}\nsliding fraction: {:.6g}\n", sm.coordination, sm.sliding);
      print_sym(ctx, "fabric", sm.fabric);
      return;
    }
  }
}

const Command print_command = {
    "PRINT", {}, "PRINT info|counters|balls|contacts|stress|strain|energy|fabric|coordination|prop|damp|history|walls|psd|porosity|measure|sample [file f] [range ...]",
    "print a table or a measurement",
    "info: a `name: value` summary (space, balls, contacts, cycle, time, timestep, backend, threads, active "
    "physics; the ball order, how far apart consecutive ids lie (a median, in diameters: about 1 in space "
    "order, more than 3 suggests RENUMBER); the capillary bridges intact where a material has them; the cell's tilts xy xz yz once STRAIN has sheared it; the number of "
    "processes under mpirun; the peak memory so far). counters [file f]: the counts for scripts, one `name value` "
    "line each, under names that stay (cycle, balls, contacts, wall_contacts, balls_destroyed, threads, "
    "pair_list_rebuilds, ...; doc/language.md lists them all and what each counts). "
    "balls, contacts: tables; with `file f.csv` a CSV file with every real in round-trip precision "
    "(balls: id,type,x,y,z,rad,vx,vy,vz,wx,wy,wz,fx,fy,fz sorted by id; contacts: "
    "i,j,nx,ny,nz,overlap,fn,fsx,fsy,fsz,sliding sorted by (i, j), with mrx,mry,mrz, the rolling moment on "
    "j, before sliding where a material has rr_fric; the table then shows |mr|; where a material has a capillary "
    "bridge, the pairs a bridge holds apart too (their overlap and normal 0) and a last column bridge, 1 where "
    "one holds), optionally for a range. "
    "stress [volume "
    "v]: the average stress tensor over the volume (SET volume, the periodic cell or the START box), "
    "compression positive. stress, fabric, coordination and porosity with `range sphere x y z r`: those of a "
    "measurement sphere (PFC's; man page, CONVENTIONS): the stress from the contacts of the balls whose centres "
    "are inside, scaled by the sphere's solid fraction; the fabric, coordination number and sliding fraction of "
    "those contacts; the porosity from the parts of balls inside it. measure range sphere x y z r: all of them. "
    "porosity without a range: the whole space's (the balls' volume over SET volume, the periodic cell or the "
    "START box) and its void ratio. strain: the periodic space's accumulated strain (xx yy zz xy xz yz, tensor "
    "components) and its volumetric strain 1 - V/V0 (V0 the cell's volume at START or the last STRAIN reset). "
    "energy: the energy terms and "
    "their balance, all at the time of the last step's force pass (the model's time less dt; the step's "
    "own sums, man page CONVENTIONS): kinetic m v(t-dt/2).v(t+dt/2)/2 and I w(t-dt/2).w(t+dt/2)/2, the "
    "springs' energy and gravity's potential at the positions of that pass, and the works up to it (friction, "
    "rolling where a material has rr_fric, damping, boundary, and capillary, the work the capillary bridges did "
    "on the balls, energy in as the boundary's, where a material has a bridge; the "
    "step's works less their part after it); central differences keep that sum for linear springs, so the "
    "balance moves only by the integration's error. Before the first CYCLE, and after a command that "
    "changes the balls or the settings, the terms are of the state as it is (velocities now, positions now, "
    "the contact table's last force pass) and the output says so. fabric: the fabric tensor. coordination: coordination number, sliding fraction and "
    "unbalanced-force ratio. prop, damp: the settings. history: the recorded histories. walls: each wall's "
    "shape, motion, and the loads of the last step (force and moment on it, the moment about its spin point; "
    "its stress, touching contacts, and the work it has done on the balls); with `file f.csv`: "
    "id,kind,type,x,y,z,nx,ny,nz,radius,vx,vy,vz,wx,wy,wz,rrate,fx,fy,fz,mx,my,mz,stress,contacts,work (x y z "
    "its centre; stress is nan for a wall with no area, a plane that SERVO wall gave no `area` or `in`, where the "
    "screen says \"(no area)\", as HIST's w<n>_stress). The coordination number counts ball pairs only; stress and the unbalanced-force ratio "
    "include the wall contacts (a wall contact's branch vector runs from the ball's centre to the contact "
    "point). psd: the grading of the balls the last GEN made (those still there), percent passing by mass "
    "(solid volume) at the sieve diameters of a sieve curve or at 21 diameters evenly spaced in log d, next to "
    "the grading asked for, and the largest difference; with `file f.csv`: diameter,passing_asked,passing_sample. "
    "sample: the measures of the sample between walls (SAMPLE): height, cross-section and volume, the axial and "
    "volumetric strains, sigma1, sigma3, q and p.",
    "print stress",
    {"sample", "info", "counters", "balls", "contacts", "stress", "strain", "energy", "fabric", "coordination", "prop", "damp",
     "history", "walls", "psd", "porosity", "measure", "file", "volume", "range"},
    run_print};

}  // namespace trubal
