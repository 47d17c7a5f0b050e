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
    auto condition = [&](const char* what) {
      return args.expect({"stop", "destroy"}, what) == 0 ? Outside::Stop : Outside::Destroy;
    };
    if (!args.empty() && match_keyword(args.peek(), {"stop", "destroy"})) outside.fill(condition("condition"));
    while (!args.empty()) {
      const auto a = args.expect({"x", "y", "z"}, "axis (x, y or z) and its condition (stop or destroy)");
      outside[a] = condition("condition (stop or destroy)");
    }
    args.done();
    ctx.session.start_box(lo, hi, outside);
    auto name = [](Outside o) { return o == Outside::Stop ? "stop" : "destroy"; };
    const std::string conditions = outside[0] == outside[1] && outside[1] == outside[2]
                                       ? fmt::format("balls leaving: {}", name(outside[0]))
                                       : fmt::format("balls leaving: x {}, y {}, z {}", name(outside[0]),
                                                     name(outside[1]), name(outside[2]));
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
    "START", {}, "START x y z [nbx nby nbz]  |  START box x0 x1 y0 y1 z0 z1 [stop|destroy] [x|y|z stop|destroy]...",
    "new model: a periodic space, or a free region (box)",
    "Clears any model and starts a new one. `START x y z` makes a periodic space of edge lengths x, y, z "
    "(balls interact with images across every face); nbx nby nbz are the numbers of contact-detection boxes "
    "along each axis, chosen automatically if absent. `START box x0 x1 y0 y1 z0 z1` makes a free region "
    "with no walls; a ball whose centre leaves it is never lost silently (PFC's domain conditions): with "
    "`stop` (the default) CYCLE stops after that step with an error naming the ball, the face and the cycle, "
    "the model kept; with `destroy` the ball is deleted, the count reported (PRINT info: balls destroyed) and "
    "its kinetic and potential energy counted as boundary work. One word sets every axis; `x destroy` etc. one "
    "axis (`START box ... destroy z stop`). Every periodic edge must stay at least twice the largest ball diameter (CYCLE refuses a "
    "smaller cell: a ball could touch two images of another); centres are wrapped into the cell as they "
    "cross a face ([0, x) etc.; in a sheared cell, the parallelepiped of its edge vectors). STRAIN and SERVO deform the cell. Materials, damping, gravity and histories are cleared; the backend choice and variables "
    "stay.",
    {"box", "stop", "destroy"}, run_start};

}  // namespace trubal
