#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <sstream>

#include <fmt/format.h>

#include "commands/common.hpp"
#include "commands/print_parts.hpp"
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
                                                     "sample", "bonds"};

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


static void run_print(Context& ctx, Args& args) {
  auto item = args.expect(kItems, "PRINT item");
  std::string file;
  if (args.accept("file")) file = args.word("file name");
  if (!file.empty() && item != 1 && item != 2 && item != 11 && item != 12 && item != 15 && item != 17)
    args.fail("`file` goes with PRINT balls, contacts, bonds, walls, psd and counters");
  // (These read of the contact results no more than they need: Session::model_but_results.)
  switch (item) {
    case 0: args.done(); print_info(ctx); return;
    case 15: args.done(); print_counters(ctx, file); return;
    case 1: print_balls(ctx, read_range(args, ctx.session), file); return;
    case 2: print_contacts(ctx, read_range(args, ctx.session), file); return;
    // (A sphere's measurement, under mpirun from the ranks' parts where they hold the model:
    // Session::measure_in; the whole space's porosity reads the balls' radii alone.)
    case 13: {
      const auto sphere = measurement_sphere(args, read_range(args, ctx.session));
      ctx.session.require_started();
      if (sphere) {
        const SphereMeasurement sm = ctx.session.measure_in(*sphere);
        print_sphere_header(ctx, *sphere, sm);
        print_porosity(ctx, sm.porosity, sm.void_ratio, sm.solid, sm.volume);
        return;
      }
      const Porosity p = space_porosity(ctx.session.state(), ctx.session.stress_volume());
      print_porosity(ctx, p.porosity, p.void_ratio, p.solid, p.volume);
      return;
    }
    case 14: {
      const auto sphere = measurement_sphere(args, read_range(args, ctx.session));
      if (!sphere) args.fail("PRINT measure needs its sphere: `range sphere x y z r`");
      ctx.session.require_started();
      const SphereMeasurement sm = ctx.session.measure_in(*sphere);
      print_sphere_header(ctx, *sphere, sm);
      print_sym(ctx, "stress", sm.stress);
      print_porosity(ctx, sm.porosity, sm.void_ratio, sm.solid, sm.volume);
      ctx.out << fmt::format("coordination number: {:.6g}\nsliding fraction: {:.6g}\n", sm.coordination, sm.sliding);
      print_sym(ctx, "fabric", sm.fabric);
      return;
    }
    case 3: {
      double volume = 0;
      if (args.accept("volume")) volume = args.real("volume");
      const auto sphere = measurement_sphere(args, read_range(args, ctx.session));
      ctx.session.require_started();
      if (sphere) {
        if (volume > 0) args.fail("`volume` goes with the whole space's stress, not a measurement sphere's");
        const SphereMeasurement sm = ctx.session.measure_in(*sphere);
        print_sphere_header(ctx, *sphere, sm);
        print_sym(ctx, "stress", sm.stress);
        return;
      }
      // (Under mpirun from the ranks' parts where they hold the model: Session::average_stress_in.)
      print_sym(ctx, "stress", ctx.session.average_stress_in(volume > 0 ? volume : ctx.session.stress_volume()));
      return;
    }
    // (Of the whole space, under mpirun from the ranks' parts where they hold the model:
    // Session::whole_contact_sums.)
    case 6: {
      if (const auto sphere = measurement_sphere(args, read_range(args, ctx.session))) {
        const SphereMeasurement sm = ctx.session.measure_in(*sphere);
        print_sphere_header(ctx, *sphere, sm);
        print_sym(ctx, "fabric", sm.fabric);
        return;
      }
      print_sym(ctx, "fabric", ctx.session.whole_contact_sums().fabric_tensor());
      return;
    }
    case 7: {
      if (const auto sphere = measurement_sphere(args, read_range(args, ctx.session))) {
        const SphereMeasurement sm = ctx.session.measure_in(*sphere);
        print_sphere_header(ctx, *sphere, sm);
        ctx.out << fmt::format("coordination number: {:.6g}\nsliding fraction: {:.6g}\ncontacts: {}\n", sm.coordination,
                               sm.sliding, sm.contacts);
        return;
      }
      const ContactSums c = ctx.session.whole_contact_sums();
      ctx.out << fmt::format("coordination number: {:.6g}\nsliding fraction: {:.6g}\ncontacts: {}\n",
                             c.coordination(ctx.session.state().balls.size()), c.sliding_fraction(),
                             static_cast<std::size_t>(c.touching));
      const Unbalanced u = c.unbalanced_ratio();
      ctx.out << fmt::format("unbalanced-force ratio: mean {:.4g}  max {:.4g}\n", u.mean_ratio, u.max_ratio);
      return;
    }
  }
  // The cell's strain, the settings, the histories, the walls, the sample and the grading (the
  // balls' radii, which rank 0 keeps where its whole model is hollow) read the light state alone
  // (the walls' loads are formed at every CYCLE's last step), and so do the energies after a
  // step (its own sums): as it is, which under mpirun may leave rank 0's whole model hollow, the
  // parts holding the balls. The rest read the balls.
  const bool at_step = ctx.session.state().energy_at_step.valid;
  const bool light =
      item == 4 || (item == 5 && at_step) || item == 8 || item == 9 || item == 10 || item == 11 || item == 12 || item == 16 ||
      item == 17;   // (PRINT bonds reads its own: print_bonds)
  const Model& m = light ? ctx.session.state() : ctx.session.model();
  switch (item) {
    case 16: args.done(); print_sample(ctx); return;
    case 17: print_bonds(ctx, read_range(args, ctx.session), file); return;
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
      EnergyReport e = energy(at_step ? m : ctx.session.model_with_masses());   // before the first CYCLE too
      if (e.at_step)
        ctx.out << fmt::format("at the last force pass (cycle {}, time {:.8g}):\n", m.cycle - 1, m.time - m.dt);
      else
        ctx.out << "of the state as it is (no step since the balls or the settings last changed):\n";
      ctx.out << fmt::format(
          "kinetic (translation): {:.8g}\nkinetic (rotation): {:.8g}\nstrain: {:.8g}\npotential (gravity): "
          "{:.8g}\nfriction work: {:.8g}\n{}damping work: {:.8g}\nboundary work: {:.8g}\n{}{}balance (should stay "
          "constant): {:.8g}\n",
          e.kinetic_translation, e.kinetic_rotation, e.strain, e.potential, e.friction_work,
          has_rolling(m) || e.rolling_work != 0 ? fmt::format("rolling work: {:.8g}\n", e.rolling_work) : "",
          e.damping_work, e.boundary_work,
          has_bridges(m) || e.capillary_work != 0 ? fmt::format("capillary work: {:.8g}\n", e.capillary_work) : "",
          !m.bonds.empty() || e.bond_break_work != 0 ? fmt::format("bond breakage: {:.8g}\n", e.bond_break_work) : "",
          e.total());
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
  }
}

const Command print_command = {
    "PRINT", {}, "PRINT info|counters|balls|contacts|bonds|stress|strain|energy|fabric|coordination|prop|damp|history|walls|psd|porosity|measure|sample [file f] [range ...]",
    "print a table or a measurement",
    "info: a `name: value` summary (space, balls, contacts, cycle, time, timestep, backend, threads, active "
    "physics; the ball order: how far apart balls next to each other in memory lie (a median, in diameters: "
    "about 1 in space order) and when the run next puts them in space order (SET sort); the capillary bridges intact where a material has them; the bonds intact and broken (in tension, in shear) where there are any; the cell's tilts xy xz yz once STRAIN has sheared it; the number of "
    "processes under mpirun; the peak memory so far). counters [file f]: the counts for scripts, one `name value` "
    "line each, under names that stay (cycle, balls, contacts, wall_contacts, balls_destroyed, threads, "
    "pair_list_rebuilds, ...; doc/language.md lists them all and what each counts). "
    "balls, contacts: tables; with `file f.csv` a CSV file with every real in round-trip precision "
    "(balls: id,type,x,y,z,rad,vx,vy,vz,wx,wy,wz,fx,fy,fz sorted by id; contacts: "
    "i,j,nx,ny,nz,overlap,fn,fsx,fsy,fsz,sliding sorted by (i, j), with mrx,mry,mrz, the rolling moment on "
    "j, before sliding where a material has rr_fric; the table then shows |mr|; where a material has a capillary "
    "bridge, the pairs a bridge holds apart too (their unit normal, and their gap as a negative overlap) and a "
    "last column bridge, 1 where one holds), optionally for a range. "
    "bonds: the parallel bonds (BOND) that hold a ball of the range (all without one), by their balls' ids: "
    "the normal force (compression positive), |shear force|, |twisting| and |bending moment|, the largest "
    "tensile and shear stresses on the section, and intact, or broken in tension or shear (a broken bond "
    "shows what broke it); with `file f.csv`: i,j,radius,fn,fsx,fsy,fsz,mt,mbx,mby,mbz,sigma,tau,"
    "strength_t,strength_s,state (the forces and moments on j; strength_s the shear strength C - sigma_n "
    "tan(fa) at the bond's mean normal stress). "
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
    {"sample", "info", "counters", "balls", "contacts", "bonds", "stress", "strain", "energy", "fabric", "coordination", "prop", "damp",
     "history", "walls", "psd", "porosity", "measure", "file", "volume", "range"},
    run_print, false, false, OnRanks::RankZero, HeldUse::Place, {"info", "counters"}};

}  // namespace trubal
