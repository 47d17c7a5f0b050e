#include <cmath>
#include <thread>

#include <fmt/format.h>

#include "commands/common.hpp"
#include "cycle/pipeline.hpp"

namespace trubal {

static void run_backend(Context& ctx, Args& args) {
  auto names = backend_names();
  std::vector<std::string_view> views(names.begin(), names.end());
  auto k = args.expect(views, "backend");
  int threads = 0;
  double max_memory = 0;
  for (;;) {
    if (args.accept("threads")) threads = static_cast<int>(args.count("threads", 1, 4096));
    else if (args.accept("maxmem")) {
      max_memory = args.real("maxmem");
      if (!(max_memory >= 1 && max_memory < 1.8e19)) args.fail("maxmem is a number of bytes, at least 1");
      if (names[k] != "allpairs") args.fail("maxmem goes with BACKEND allpairs (the memory of its pair slots)");
    } else break;
  }
  args.done();
  ctx.session.set_backend(names[k], threads, static_cast<std::uint64_t>(std::floor(max_memory)));
  const Pipeline& p = ctx.session.pipeline();
  ctx.out << fmt::format("backend {} ({} threads)\n", p.backend().name(), p.threads());
}

const Command backend_command = {
    "BACKEND", {}, "BACKEND serial|allpairs|threaded|mpi [threads n] [maxmem bytes]", "choose how contacts are found",
    "Chooses how the pairs of balls that may touch are found, and on how many threads the step runs. "
    "Every backend runs the same step, so all give the same numbers, bitwise, for any thread or process count "
    "and however the run is cut into CYCLEs; switching keeps the balls, the contacts and their shear history. "
    "The choice decides only the speed and the memory. serial (the default): TRUBAL's boxes, one thread; the "
    "choice for small scenes and the reference for the others. threaded: the same pairs, found and stepped on "
    "`threads n` threads (default: one per hardware thread); the choice on a machine with several cores. It "
    "times in the first steps whether sharing pays (where it does not, one thread does the work and PRINT info "
    "says so), and for large or randomly numbered scenes it may share the step in space, which takes about the "
    "model's memory again (doc/speed.md, \"Threads and the numbering of the balls\"; RENUMBER helps). allpairs: "
    "every pair of balls tested every cycle, so it cannot miss a contact; the slowest backend, for checking the "
    "others on small scenes. It refuses to take more than `maxmem` bytes (default 4 GiB or half the physical "
    "memory, the smaller). mpi: the backend of `mpirun -np P trubal deck.dat` (the default there), for models "
    "too large or too slow for one process: each process steps a part of the space (doc/distributed.md says how, "
    "and PRINT info what each holds). Under mpirun, the other backends compute the whole step in every process.",
    "backend threaded threads 2",
    {"serial", "allpairs", "threaded", "mpi", "threads", "maxmem"}, run_backend};

}  // namespace trubal
