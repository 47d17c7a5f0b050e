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
    "Every backend runs the same step (the contact forces, each ball's sums in one fixed order, the "
    "motion), so all give the same numbers, bitwise, for any thread or rank count and however the run is "
    "cut into CYCLEs; switching keeps the balls, the contacts and their shear history. The choice decides "
    "only the speed and the memory. "
    "serial (the default): TRUBAL's boxes (each box's balls kept in order, where TRUBAL hung them on "
    "linked lists), one thread; the choice for small scenes and the reference for the others. "
    "threaded: the same pairs, found and stepped on `threads n` threads (default: one per hardware "
    "thread); the choice on a machine with several cores. The threads take ranges of ball numbers where "
    "balls near in space are near in number (GEN, LATTICE and RENUMBER number them so), and whether "
    "sharing pays is timed in the first steps (where it does not, one thread does the work and PRINT info "
    "says so). Where the numbering is far from the places (4096 balls or more, and a split of the numbers "
    "would leave a quarter of the pairs or more across two threads, as with balls read in random order "
    "from another program's file), and for any scene of 50,000 to 500,000 balls (where compact parts "
    "step faster; beyond, their copies would cost more memory than the speed is worth), the threads share "
    "the step in space instead, each stepping a part of the decomposition BACKEND mpi makes (below), its "
    "lists rebuilt on the parts as there. That is decided again wherever the whole model is stepped "
    "through, and below 50,000 balls timed against one thread as the split by numbers is (where another "
    "program keeps a core busy, one thread wins); PRINT info says which (\"last step shared by\"). The "
    "parts copy their balls, so memory grows by about that of the model's balls and contacts. "
    "allpairs: TPM's arrangement, every pair of balls tested every cycle (N(N-1)/2 pair slots of one "
    "byte), so it cannot miss a contact; the slowest backend, for checking the others on small scenes. It "
    "refuses to take more than `maxmem` bytes (default 4 GiB or half the physical memory, the smaller). "
    "mpi: the backend of `mpirun -np P trubal deck.dat` (the default there), for models too large or too "
    "slow for one process. The balls are split by recursive coordinate bisection into P groups, each "
    "rank's share in proportion to the speed it stepped its own balls at since the last split (equal at "
    "first), so that a rank on a slower core, or with more contacts a ball, gets fewer; each rank steps its "
    "own balls with ghost copies of their partners, and each step the owners send the ghosts' new "
    "positions, velocities and spins. A stale pair list is rebuilt on the parts (the CYCLE's first too): a "
    "ball now in another rank's brick of the bisection moves to that rank with its pairs' and wall "
    "contacts' history, each rank receives the others' balls within reach of its own (through the periodic "
    "faces too), searches its pairs with the serial search's test and carries their history over, and a "
    "ball leaving the periodic cell is wrapped on each rank that holds it. What the parts cannot do alone "
    "goes through the whole model, which every rank holds between CYCLEs, and the parts are then made "
    "afresh and balanced again: balls spread far from their parts, a rank's count of balls a tenth off its "
    "share, speeds that would move a share by a tenth, a ball outside a START box, an edit. In a CYCLE the "
    "ranks other than 0 hold their part and the balls' ids and radii; rank 0 gathers the state for the "
    "output and keeps the rescue copy, and alone takes again the step that makes the contact results a "
    "command reads after a CYCLE. A periodic servo's or a shearing cell's new rates change every copy of a "
    "ball's velocity, a following membrane's new forces every copy of its loads. PRINT info shows the "
    "balls, shares, arrays and peak memory per rank. The answer is the serial one bit for bit for any P "
    "(tests/unit/cycle_cuts.cpp and distributed_runs.cpp run the scenes on 2, 3 and 4 ranks); on one "
    "rank it is the serial backend. Under mpirun, the other backends compute the whole step on every rank. "
    "How the ranks keep one answer: doc/distributed.md.",
    {"serial", "allpairs", "threaded", "mpi", "threads", "maxmem"}, run_backend};

}  // namespace trubal
