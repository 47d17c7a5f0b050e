#include <cmath>
#include <thread>

#include <fmt/format.h>

#include "commands/common.hpp"

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
    "Chooses how the pairs of balls that may touch are found, and on how many threads the step runs (the "
    "contact forces, each ball's sums and the motion are one pipeline for every backend); switching keeps "
    "balls, contacts and their shear history, and every backend gives the same numbers, bitwise, for any "
    "thread count and however the run is cut into CYCLEs. serial: TRUBAL's boxes (each box's balls kept in order, where TRUBAL hung them on linked lists), one thread. "
    "threaded: the same pairs, the boxes searched and forces and motion spread over `threads n` threads "
    "(default: one per hardware thread); each thread takes a range of ball numbers where balls near in space "
    "are near in number (GEN numbers them so), and whether sharing pays is timed in the first steps (where it "
    "does not, one thread does the work and PRINT info says so); where they are not (4096 balls or more, and "
    "a split of the numbers would leave a quarter of the pairs or more across two threads, as with balls read "
    "in random order from another program's file), and also from 50,000 to 500,000 balls however they are numbered "
    "(each part's arrays are then compact: 13% faster at 108,000 balls; beyond, the parts' copies would cost "
    "more memory than the speed is worth), the threads share the step in space instead, each stepping "
    "a part of the decomposition BACKEND mpi makes (below; its lists rebuilt on the parts as there), decided again wherever the whole model is stepped through, and "
    "timed against one thread as the split by numbers is (where another program keeps a core busy, one "
    "thread wins; not from 50,000 to 500,000 balls, where each switch would make the parts afresh); PRINT info says which (\"last step shared by\"); the parts copy their balls, so memory grows by about that "
    "of the model's balls and contacts. allpairs: TPM's arrangement, every pair of balls tested every cycle "
    "(N(N-1)/2 pair slots of one byte; it cannot miss a contact); it refuses to take more than `maxmem` bytes "
    "(default 4 GiB or half the physical memory, the smaller). mpi: under `mpirun -np P trubal deck.dat` "
    "(the default backend there) the step is shared among the P ranks by a spatial decomposition: the balls "
    "are split by recursive coordinate bisection into P groups (equal at first, then each rank's share in proportion to the speed it stepped its own balls at since the last split, so that a rank on a slower core, or with more contacts a ball, gets fewer; PRINT info shows the shares), each rank steps its own balls with ghost copies of their partners, and each step the owners "
    "send the ghosts' new positions, velocities and spins; a stale pair list is rebuilt on the parts (the "
    "CYCLE's first too: the parts are made with the stale list and search it, so that in a CYCLE no rank but 0 "
    "holds the whole model's list): "
    "a ball now in another rank's brick of the bisection moves to that rank with its pairs' and wall contacts' history, "
    "each rank keeps its other balls, receives the others' balls that may be within reach of them "
    "(in the bins, a reach wide, around its own balls' bins, through the periodic faces too), searches "
    "its pairs with the serial search's test and carries their history and its walls' contacts over, "
    "and a ball leaving the periodic cell is wrapped on each rank that holds it; the whole model's list "
    "is made from the ranks' at the next output step; balls spread far from their parts (the balls "
    "received grew to twice their count at the first such rebuild), a rank's count of balls a tenth off its share after the moves, ranks whose speeds would move their "
    "shares by a tenth, a ball outside a START box or an edit goes through the whole model (there the parts are made afresh, the bisection balanced again, "
    "and where the list is stale they search it themselves; only a periodic servo's first stress "
    "searches the whole model's list, each rank the pairs of its range of ball numbers, the ranks' lists "
    "joined, in order, into the serial list; the step taken again that makes the contact results a command "
    "reads after a CYCLE is rank 0's alone, searched on its own), which every rank "
    "holds (between CYCLEs; in a CYCLE the ranks other than 0 hold their part and the balls' ids and radii, while rank 0 alone gathers the state for the output and keeps the rescue copy's balls and pairs, handing on what it recorded; PRINT info shows the arrays each rank held); a periodic servo's or a shearing cell's new "
    "rates change every copy of a ball's velocity, a following membrane's new forces every copy of its "
    "loads. PRINT info shows the balls per rank. The answer is the serial one bit for bit for any P (tests/unit/cycle_cuts.cpp and "
    "distributed_runs.cpp run the scenes on 2, 3 and 4 ranks). On one rank it is the serial backend. Under "
    "mpirun, the other backends compute the whole step on every rank.",
    {"serial", "allpairs", "threaded", "mpi", "threads", "maxmem"}, run_backend};

}  // namespace trubal
