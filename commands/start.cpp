#include <fmt/format.h>

#include "commands/common.hpp"

namespace trubal {

static void run_start(Context& ctx, Args& args) {
  if (args.accept("box")) {
    std::array<double, 3> lo{}, hi{};
    for (int a = 0; a < 3; ++a) {
      lo[a] = args.real(fmt::format("{}0", "xyz"[a]));
      hi[a] = args.real(fmt::format("{}1", "xyz"[a]));
    }
    args.done();
    ctx.session.start_box(lo, hi);
    ctx.out << fmt::format("new model in the box [{}, {}] x [{}, {}] x [{}, {}]\n", lo[0], hi[0], lo[1], hi[1], lo[2], hi[2]);
    return;
  }
  std::array<double, 3> length = read_xyz(args, "edge");
  std::array<int, 3> boxes{0, 0, 0};
  if (!args.empty())
    for (int a = 0; a < 3; ++a) boxes[a] = static_cast<int>(args.count(fmt::format("nb{}", "xyz"[a]), 1, 100000));
  args.done();
  ctx.session.start_periodic(length, boxes);
  ctx.out << fmt::format("new model in the periodic space {} x {} x {}\n", length[0], length[1], length[2]);
}

const Command start_command = {
    "START", {}, "START x y z [nbx nby nbz]  |  START box x0 x1 y0 y1 z0 z1",
    "new model: a periodic space, or a free region (box)",
    "Clears any model and starts a new one. `START x y z` makes a periodic space of edge lengths x, y, z "
    "(balls interact with images across every face); nbx nby nbz are the numbers of contact-detection boxes "
    "along each axis, chosen automatically if absent. `START box x0 x1 y0 y1 z0 z1` makes a free region "
    "with no walls. Every periodic edge must stay at least twice the largest ball diameter (CYCLE refuses a "
    "smaller cell: a ball could touch two images of another); centres are wrapped into the cell as they "
    "cross a face ([0, x) etc.; in a sheared cell, the parallelepiped of its edge vectors). STRAIN and SERVO deform the cell. Materials, damping, gravity and histories are cleared; the backend choice and variables "
    "stay.",
    {"box"}, run_start};

}  // namespace trubal
