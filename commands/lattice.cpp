#include <fmt/format.h>

#include "commands/common.hpp"

namespace trubal {

static void run_lattice(Context& ctx, Args& args) {
  args.expect({"fcc"}, "lattice kind");
  double d = args.real("d (diameter)");
  int nx = static_cast<int>(args.count("nx", 1, 100000));
  int ny = static_cast<int>(args.count("ny", 1, 100000));
  int nz = static_cast<int>(args.count("nz", 1, 100000));
  std::array<double, 3> origin{0, 0, 0};
  int type = 1;
  auto layers = Session::Layers::All;
  while (!args.empty() && !match_keyword(args.peek(), {"range"})) {
    auto k = args.expect({"origin", "type", "layers"}, "LATTICE option");
    if (k == 0) {
      origin = read_xyz(args, "origin");
    } else if (k == 1) {
      type = static_cast<int>(args.count("type", 1, 1000000));
    } else {
      static const Session::Layers kinds[] = {Session::Layers::All, Session::Layers::Even, Session::Layers::Odd};
      layers = kinds[args.expect({"all", "even", "odd"}, "layers (all, even or odd)")];
    }
  }
  Range range = read_range(args, ctx.session);
  auto n = ctx.session.lattice_fcc(d, nx, ny, nz, origin, type, range, layers);
  ctx.out << fmt::format("{} balls on the fcc lattice\n", n);
}

const Command lattice_command = {
    "LATTICE", {}, "LATTICE fcc d nx ny nz [origin x y z] [type t] [layers all|even|odd] [range ...]",
    "balls on a face-centred cubic lattice (cube axis along z)",
    "Balls of diameter d on an FCC lattice built as square layers normal to z: layer k lies at "
    "z0 + k d/sqrt(2); even layers hold nx x ny balls at (x0 + i d, y0 + j d), odd layers (nx-1) x (ny-1) "
    "in the hollows at (x0 + (i+1/2) d, y0 + (j+1/2) d) (nx x ny in a periodic space, so the lattice "
    "wraps). `layers even` or `layers odd` builds only those layers (default all), so that each kind can "
    "take its own range. Only balls where the range holds are kept: `range octagon x y a b` cuts Rowe's "
    "octagonal layers, e.g. for his 1672-ball sample (d = 40, 13 layers of 76 and 12 of 57): "
    "`lattice fcc 40 10 10 25 layers even range octagon 180 180 180 184` then "
    "`lattice fcc 40 10 10 25 layers odd range octagon 180 180 180 156` (|dx| + |dy| <= b sqrt(2) "
    "keeps 6 d in the large layers and 5 d in the small ones).",
    "lattice fcc 0.01 5 5 5 origin 0.02 0.02 0.02",
    {"fcc", "origin", "type", "layers", "all", "even", "odd", "range"}, run_lattice, false, false, OnRanks::ModelOnZero, HeldUse::Add};

}  // namespace trubal
