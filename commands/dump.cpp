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
  const auto cycle = ctx.session.model().cycle;
  ctx.out << fmt::format("wrote {} and {} ({}){}\n", d.balls_path(cycle), d.contacts_path(cycle), d.pvd_path(),
                         every > 0 ? fmt::format("; again every {} cycles", every) : "");
}

const Command dump_command = {
    "DUMP", {}, "DUMP vtk file [every n]  |  DUMP off", "ParaView files of balls and contact forces",
    "Writes the balls and the contact forces as VTK XML PolyData files for ParaView, now and, with `every n`, "
    "every n cycles from then on (`DUMP off` stops). Each dump is two files named by the cycle: "
    "file_000123.vtp, the balls as points with id, type, radius, velocity, spin and force (show them with "
    "the Point Gaussian representation or a Glyph scaled by radius), and file_contacts_000123.vtp, the force "
    "chains: a line between the centres of each pair of touching balls with its normal_force (magnitude), "
    "force and ball ids as cell data. file.pvd lists all dumps with their times (open it to step through "
    "the run); it is rewritten after each dump. Arrays are binary (appended raw, little-endian); every file "
    "is written under a temporary name and renamed. START and RESTART stop periodic dumps.",
    {"vtk", "every", "off"}, run_dump};

}  // namespace trubal
