// WALL: planes, polygons and cylinders the balls touch, and their motion.
#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "commands/common.hpp"
#include "model/edit.hpp"
#include "model/wall_shape.hpp"

namespace trubal {

static const std::vector<std::string_view> kWallOptions = {"type", "velocity", "spin", "about", "rrate", "inside",
                                                           "outside"};

// A vertex coordinate: any number form the language reads (1.5d9 too); one beyond a double is read
// as a number, so that its error says it is out of range.
static bool is_number(const std::string& w) { return parse_real(w).has_value() || real_out_of_range(w); }

// The options that may follow a wall's shape or its id: type, motion, the side of a cylinder.
static void read_options(Args& args, Wall& w, bool& about_given) {
  while (!args.empty()) {
    const std::size_t option = args.expect(kWallOptions, "WALL option");
    switch (option) {
      case 0: w.type = static_cast<int>(args.count("type", 1, 1000000)); break;
      case 1: w.velocity = read_xyz(args, "velocity v"); break;
      case 2: w.spin = read_xyz(args, "spin w"); break;
      case 3: w.spin_point = read_xyz(args, "spin point p"); about_given = true; break;
      case 4:
        if (w.kind != WallKind::Cylinder) args.fail("`rrate` (a radius rate) is for cylinders");
        w.radius_rate = args.real("radius rate");
        break;
      case 5:
      case 6:
        if (w.kind != WallKind::Cylinder) args.fail("`inside` and `outside` are for cylinders");
        w.inside = option == 5;
        break;
    }
  }
  auto finite = [](const Vec3& v) { return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]); };
  if (!finite(w.velocity) || !finite(w.spin) || !finite(w.spin_point) || !std::isfinite(w.radius_rate))
    args.fail("velocities, spins and points must be finite");
}

// WALL id n with motion alone (velocity, spin, about, rrate): where the ranks keep their parts,
// every rank changes its walls (the parts read them at each step) and the parts stay; else rank
// 0 alone, as every other form.
static OnRanks wall_ranks(const Args& given, bool parts_kept) {
  Args args = given;
  if (!parts_kept || !args.accept("id") || args.empty() || !is_number(args.peek())) return OnRanks::ModelOnZero;
  args.word("wall id");
  if (args.empty()) return OnRanks::ModelOnZero;
  while (!args.empty()) {
    const std::string& w = args.word("option");
    if (!is_number(w) && w != "velocity" && w != "spin" && w != "about" && w != "rrate") return OnRanks::ModelOnZero;
  }
  return OnRanks::Parts;
}

static void run_wall(Context& ctx, Args& args) {
  ctx.session.require_started();
  // (The ranks keep their parts: every rank runs a wall's motion, reading the light state.)
  const bool on_parts = ctx.session.parts_kept();
  {
    const Space& s = ctx.session.state().space;
    if (s.periodic && !s.mixed())
      args.fail("walls need a free region (START box ..., with some axis bounded): a periodic space has no room for "
                "them");
  }
  if (args.accept("delete")) {
    args.expect({"all"}, "`all` (or WALL id n delete)");
    args.done();
    Model& m = ctx.session.edit();
    const std::size_t n = m.walls.size();
    m.walls.clear();
    m.wall_contacts = WallContacts{};
    ctx.out << fmt::format("{} walls deleted\n", n);
    if (m.sample.declared()) {
      m.sample = Sample{};
      ctx.out << "the sample (SAMPLE) went with its walls\n";
    }
    return;
  }
  std::int64_t id = 0;
  if (args.accept("id")) id = args.count("wall id", 1);
  const Model& now = on_parts ? ctx.session.state() : ctx.session.model();
  const auto found = std::find_if(now.walls.begin(), now.walls.end(), [&](const Wall& w) { return w.id == id; });
  const auto kind = args.empty() ? std::nullopt : args.keyword({"plane", "polygon", "cylinder"});
  if (!kind) {   // an existing wall: its motion, its type, or delete
    if (id == 0) args.fail("name a shape (plane, polygon, cylinder), or `id n` of a wall to change");
    if (found == now.walls.end()) args.fail(fmt::format("there is no wall {} (PRINT walls lists them)", id));
    if (args.accept("delete")) {
      args.done();
      for (const Wall& other : now.walls)
        if (other.servo_on && (other.area_walls[0] == id || other.area_walls[1] == id))
          args.fail(fmt::format("wall {}'s servo takes its area from wall {}: SERVO wall {} off first", other.id, id,
                                other.id));
      const Sample& s = now.sample;
      const bool in_sample = s.declared() && (std::find(s.platens.begin(), s.platens.end(), id) != s.platens.end() ||
                                              std::find(s.sides.begin(), s.sides.end(), id) != s.sides.end());
      Model& m = ctx.session.edit();
      if (in_sample) {
        m.sample = Sample{};
        ctx.out << fmt::format("the sample (SAMPLE) is gone: wall {} was one of its walls\n", id);
      }
      for (Wall& other : m.walls)   // a servo that is off keeps no claim on the wall
        for (auto& a : other.area_walls)
          if (a == id) other.area_walls = {0, 0};
      m.walls.erase(m.walls.begin() + (found - now.walls.begin()));
      reindex_wall_contacts(m);
      ctx.out << fmt::format("wall {} deleted\n", id);
      return;
    }
    if (args.empty()) args.fail("say what to change: type, velocity, spin, about, rrate");
    Wall w = *found;
    bool about = false;
    read_options(args, w, about);
    Model& m = on_parts ? ctx.session.edit_walls() : ctx.session.edit();
    m.walls[found - now.walls.begin()] = w;
    ctx.out << fmt::format("wall {}: velocity ({:.6g}, {:.6g}, {:.6g}), spin ({:.6g}, {:.6g}, {:.6g})\n", id,
                           w.velocity[0], w.velocity[1], w.velocity[2], w.spin[0], w.spin[1], w.spin[2]);
    return;
  }
  if (found != now.walls.end()) args.fail(fmt::format("wall id {} is taken (WALL id {} delete first)", id, id));
  Wall w;
  w.kind = static_cast<WallKind>(*kind);
  switch (w.kind) {
    case WallKind::Plane:
      w.point = read_xyz(args, "point p");
      w.normal = read_xyz(args, "normal n");
      break;
    case WallKind::Polygon:
      while (!args.empty() && is_number(args.peek())) w.vertices.push_back(read_xyz(args, "vertex"));
      break;
    case WallKind::Cylinder:
      w.point = read_xyz(args, "axis start p");
      w.normal = read_xyz(args, "axis direction a");
      args.expect({"radius"}, "`radius r`");
      w.radius = args.real("radius");
      args.expect({"length"}, "`length l`");
      w.length = args.real("length");
      break;
  }
  bool about = false;
  read_options(args, w, about);
  const std::string problem = complete_wall(w);
  if (!problem.empty()) args.fail(problem);
  if (!about) w.spin_point = wall_centre(w);
  Model& m = ctx.session.edit();
  if (id == 0) id = m.walls.empty() ? 1 : m.walls.back().id + 1;
  w.id = id;
  const auto at = std::lower_bound(m.walls.begin(), m.walls.end(), id, [](const Wall& a, std::int64_t v) { return a.id < v; });
  m.walls.insert(at, w);
  reindex_wall_contacts(m);   // the walls after it moved up one place
  if (m.materials.find(w.type) == m.materials.end())
    ctx.warn(fmt::format("type {0} has no properties yet (PROP type {0} kn ... ks ... fric ...)", w.type));
  ctx.out << fmt::format("wall {}: {} of type {}", id, wall_kind_name(w.kind), w.type);
  if (w.kind == WallKind::Plane)
    ctx.out << fmt::format(" through ({:.6g}, {:.6g}, {:.6g}), normal ({:.6g}, {:.6g}, {:.6g})", w.point[0], w.point[1],
                           w.point[2], w.normal[0], w.normal[1], w.normal[2]);
  if (w.kind == WallKind::Polygon)
    ctx.out << fmt::format(", {} vertices, area {:.6g}, normal ({:.6g}, {:.6g}, {:.6g})", w.vertices.size(), wall_area(w),
                           w.normal[0], w.normal[1], w.normal[2]);
  if (w.kind == WallKind::Cylinder)
    ctx.out << fmt::format(", radius {:.6g}, length {:.6g}, balls {}", w.radius, w.length, w.inside ? "inside" : "outside");
  ctx.out << "\n";
  // Balls the new wall cuts into would be thrown off at the first step: say so.
  std::size_t cut = 0;
  for (std::size_t k = 0; k < m.balls.size(); ++k) {
    const WallTouch t = wall_touch(w, {m.balls.x[k], m.balls.y[k], m.balls.z[k]});
    cut += t.gap < m.balls.rad[k] && t.gap > -m.balls.rad[k];
  }
  if (cut > 0)
    ctx.warn(fmt::format("{} balls overlap wall {} now: they will be pushed off hard at the first step (place the "
                         "wall clear of them, or move it in)", cut, id));
}

const Command wall_command = {
    "WALL", {},
    "WALL [id n] plane px py pz nx ny nz [options]  |  WALL [id n] polygon x1 y1 z1 x2 y2 z2 x3 y3 z3 ... [options]  "
    "|  WALL [id n] cylinder px py pz ax ay az radius r length l [inside|outside] [options]  |  WALL id n options  "
    "|  WALL id n delete  |  WALL delete all;  options: type t, velocity vx vy vz, spin wx wy wz, about px py pz, "
    "rrate v",
    "rigid walls: planes, polygons, cylinders; their motion",
    "Makes a rigid wall the balls touch, in a START box (not in a periodic space). Ball-wall contacts use the "
    "contact law of ball pairs (linear or Hertz-Mindlin, friction, cohesion, dashpots) with the wall's type "
    "(`type t`, default 1; PROP type t gives its kn, ks, fric, shear, poisson, rest; a wall needs no "
    "density) mixed with the ball's as two ball types mix, the wall a partner of infinite mass and, for "
    "Hertz, of infinite radius (R* = R). Each contact keeps its shear history by (ball id, wall id). "
    "`plane`: the infinite plane through p with normal n; it is one-sided: the balls live on the side n "
    "points to, and a ball whose centre passes the plane is still pushed back while it is less than its "
    "radius behind. `polygon`: the planar polygon of the vertices (3 or more, in order, convex or not), "
    "touched from either side and at its edges and corners (a rectangle is 4 vertices); its normal is the "
    "right-hand one of the vertex order. `cylinder`: the open cylinder of radius r around the axis from p "
    "along a, of length l; `inside` (the default) keeps the balls inside it (a container), `outside` outside; "
    "beyond its ends balls touch the rim. The id is the next free one unless `id n` is given. Motion: "
    "`velocity` translates the wall, `spin` turns it about an axis through `about` (default its centre: the "
    "point of a plane, a polygon's vertex mean, a cylinder's axis midpoint; the point moves with the wall), "
    "`rrate` changes a cylinder's radius; these hold for every step until changed (`WALL id n velocity 0 0 "
    "0`) and are set on a wall at any time. SERVO wall drives a wall to hold a stress. PRINT walls shows each "
    "wall's force and moment (about its spin point) from the last step, its stress and the work it has done "
    "on the balls (counted as boundary work in the energy balance); HIST wall n records them; DUMP vtk writes "
    "the walls beside the balls.",
    "wall plane 0 0 0 0 0 1",
    {"id", "plane", "polygon", "cylinder", "radius", "length", "inside", "outside", "type", "velocity", "spin", "about",
     "rrate", "delete", "all"},
    run_wall, false, false, OnRanks::ModelOnZero, HeldUse::Place, {}, wall_ranks};

}  // namespace trubal
