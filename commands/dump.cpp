#include <fmt/format.h>

#include "commands/common.hpp"

namespace trubal {

static void run_dump(Context& ctx, Args& args) {
  if (args.accept("off")) {
    args.done();
    const bool was = ctx.session.dumps() && ctx.session.dumps()->every() > 0;
    ctx.session.dump_off();
    ctx.out << (was ? "periodic dumps stopped\n" : "no periodic dumps were on\n");
    return;
  }
  args.expect({"vtk"}, "dump format");
  std::string file = args.word("file name");
  std::int64_t every = 0;
  if (args.accept("every")) every = args.count("every (cycles)", 1);
  args.done();
  ctx.session.dump_vtk(file, every);
  const VtkSeries& d = *ctx.session.dumps();
  const auto cycle = ctx.session.state().cycle;
  const std::string files = ctx.session.state().walls.empty()
                                ? fmt::format("{}, {} and {}", d.balls_path(cycle), d.contacts_path(cycle),
                                              d.domain_path(cycle))
                                : fmt::format("{}, {}, {} and {}", d.balls_path(cycle), d.contacts_path(cycle),
                                              d.walls_path(cycle), d.domain_path(cycle));
  ctx.out << fmt::format("wrote {} ({}){}\n", files, d.pvd_path(),
                         every > 0 ? fmt::format("; again every {} cycles", every) : "");
}

const Command dump_command = {
    "DUMP", {}, "DUMP vtk file [every n]  |  DUMP off", "ParaView files of balls, contact forces, walls and the domain",
    "Writes the balls, the contact forces and the walls as VTK XML PolyData files for ParaView, now and, with "
    "`every n`, every n cycles from then on (`DUMP off` stops). Each dump is three files named by the cycle, "
    "four when the model has walls: file_000123.vtp, the balls as points with id, type, radius, velocity, spin "
    "and force (show them with the Point Gaussian representation or a Glyph scaled by radius); "
    "file_contacts_000123.vtp, the force chains: a line between the centres of each pair of touching balls with "
    "its normal_force (magnitude), force and ball ids as cell data; and file_walls_000123.vtp, the walls' "
    "surfaces as polygon cells with the wall's id and the force on the wall (that of the last force pass) as "
    "cell data: a plane as a square centred on its point, its side the diagonal of the START box; a polygon as "
    "one cell of its vertices; a cylinder as 48 quads around, one band along its length; and "
    "file_domain_000123.vtp, the START box or the periodic cell (a parallelepiped once sheared, as it is at "
    "that cycle) as its 12 edges, line cells with the edge's axis (0, 1, 2) and whether that axis is periodic "
    "(1) as cell data. file.pvd lists all dumps with their times (open it to step through the run; part 0 the "
    "balls, 1 the contacts, 2 the walls, 3 the domain); "
    "it is rewritten after each dump. Arrays are binary (appended raw, little-endian); every file is written "
    "under a temporary name and renamed. START and RESTART stop periodic dumps.",
    "dump vtk out/run every 1000",
    {"vtk", "every", "off"}, run_dump, false, false, OnRanks::Parts};

}  // namespace trubal
