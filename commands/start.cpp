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
    // What happens to a ball that leaves: for every axis, then per axis.
    std::array<Outside, 3> outside{Outside::Stop, Outside::Stop, Outside::Stop};
    std::array<bool, 3> periodic{false, false, false};
    if (!args.empty() && match_keyword(args.peek(), {"stop", "destroy"}))
      outside.fill(args.expect({"stop", "destroy"}, "condition") == 0 ? Outside::Stop : Outside::Destroy);
    while (!args.empty()) {
      const auto a = args.expect({"x", "y", "z"}, "axis (x, y or z) and its condition (stop, destroy or periodic)");
      const auto c = args.expect({"stop", "destroy", "periodic"}, "condition (stop, destroy or periodic)");
      if (c == 2) periodic[a] = true;
      else { outside[a] = c == 0 ? Outside::Stop : Outside::Destroy; periodic[a] = false; }
    }
    args.done();
    if (periodic[0] && periodic[1] && periodic[2])
      args.fail("every axis periodic is the periodic space: START x y z (then lo is 0)");
    ctx.session.start_box(lo, hi, outside, periodic);
    auto name = [&](int a) { return periodic[a] ? "periodic" : outside[a] == Outside::Stop ? "stop" : "destroy"; };
    const bool same = std::string(name(0)) == name(1) && std::string(name(1)) == name(2);
    const std::string conditions = same ? fmt::format("balls leaving: {}", name(0))
                                        : fmt::format("faces: x {}, y {}, z {}", name(0), name(1), name(2));
    ctx.out << fmt::format("new model in the box [{}, {}] x [{}, {}] x [{}, {}]; {}\n", lo[0], hi[0], lo[1], hi[1],
                           lo[2], hi[2], conditions);
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
    "START", {}, "START x y z [nbx nby nbz]  |  START box x0 x1 y0 y1 z0 z1 [stop|destroy] [x|y|z stop|destroy|periodic]...",
    "new model: a periodic space, or a free region (box)",
    "Clears any model and starts a new one. `START x y z` makes a periodic space of edge lengths x, y, z "
    "(balls interact with images across every face); nbx nby nbz are the numbers of contact-detection boxes "
    "along each axis, chosen automatically if absent. `START box x0 x1 y0 y1 z0 z1` makes a free region "
    "with no walls; a ball whose centre leaves it is never lost silently (PFC's domain conditions): with "
    "`stop` (the default) CYCLE stops after that step with an error naming the ball, the face and the cycle, "
    "the model kept; with `destroy` the ball is deleted, the count reported (PRINT info: balls destroyed) and "
    "its kinetic and potential energy counted as boundary work. One word sets every axis; `x destroy` etc. one "
    "axis (`START box ... destroy z stop`). `x periodic` (and y, z: one or two of them) makes that axis periodic "
    "with period x1 - x0, as in the periodic space (images across its faces, centres wrapped into [x0, x1)), while "
    "the other axes stay bounded with their conditions: mixed periodicity, e.g. `START box 0 1 0 1 0 2 x periodic "
    "y periodic` for a shear box or a chute with walls across z. STRAIN and SERVO act only on periodic axes (a "
    "shear component only where both its axes are); walls see the balls' wrapped positions, not their images, "
    "so make walls across a bounded axis (infinite planes parallel to the periodic ones). Every periodic edge must stay at least twice the largest ball diameter (CYCLE refuses a "
    "smaller cell: a ball could touch two images of another); centres are wrapped into the cell as they "
    "cross a face ([0, x) etc.; in a sheared cell, the parallelepiped of its edge vectors). STRAIN and SERVO deform the cell. Materials, damping, gravity and histories are cleared; the backend choice and variables "
    "stay.",
    "start box 0 0.1 0 0.1 0 0.2",
    {"box", "stop", "destroy", "periodic", "x", "y", "z"}, run_start};

}  // namespace trubal
