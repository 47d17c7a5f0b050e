// trubal: runs decks of TRUBAL's command language, or an interactive shell.
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>

#include <chrono>
#include <iostream>
#include <new>
#include <sstream>
#include <streambuf>

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "cycle/step_policy.hpp"
#include "interp/interpreter.hpp"
#include "interp/manpage.hpp"
#include "interp/output.hpp"
#include "interp/shell.hpp"
#include "interp/signals.hpp"
#include "interp/summary.hpp"
#include "session.hpp"
#include "support/comm.hpp"

namespace {

// Where the other ranks' words go: nowhere (rank 0 alone prints).
class NullBuffer : public std::streambuf {
 protected:
  int overflow(int c) override { return c == EOF ? 0 : c; }
  std::streamsize xsputn(const char*, std::streamsize n) override { return n; }
};

int run(int argc, char** argv);

}  // namespace

int main(int argc, char** argv) {
  trubal::comm::init(argc, argv);
  int status = 1;
  // What the interpreter did not report (a deck that could not be read at all, a report that itself
  // ran out of memory) is still a plain error and exit status 1, never std::terminate's abort. By
  // here the session is gone and its memory free again; the out-of-memory text is fixed even so.
  try {
    status = run(argc, argv);
  } catch (const std::bad_alloc&) {
    std::fputs("trubal: error: out of memory: the system refused more memory\n", stderr);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "trubal: error: %s\n", e.what());
  }
  trubal::comm::finalize();
  return status;
}

namespace {

int run(int argc, char** argv) {
  CLI::App app{"trubal: discrete element simulation of spheres in TRUBAL's command language.\n"
               "Runs DECK as a batch (stops at the first error, exit status 1), or opens an interactive\n"
               "shell when no deck is given and standard input is a terminal. `-` reads a deck from\n"
               "standard input. See trubal(1) and HELP inside the program.",
               "trubal"};
  std::string deck, interactive_deck;
  bool version = false, man_commands = false;
  app.add_option("deck", deck, "command file to run (- for standard input)");
  app.add_option("-i,--interactive", interactive_deck, "run this deck, then stay in the shell");
  app.add_flag("-V,--version", version, "print the version and exit");
  app.add_flag("--man-commands", man_commands, "print the COMMANDS section of the man page (roff)")->group("");
  // Exit status: 0 success (and --help), 1 an error in the run, 2 a bad command line (CLI11 would
  // return its own codes, 105 to 113).
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : 2;
  }
  if (man_commands) {
    fmt::print("{}", trubal::man_commands_section());
    return 0;
  }
  if (version) {
    fmt::print("trubal {}\n", TRUBAL_VERSION);
    return 0;
  }

  const auto start = std::chrono::steady_clock::now();
  // A batch deck's output in large writes, at a terminal too (and under mpirun, whose pseudo
  // terminal would make every line a write it forwards): what must be seen when it happens is
  // flushed where it happens (each command that is not quick, progress, errors and warnings).
  if (interactive_deck.empty() && (!deck.empty() || !::isatty(STDIN_FILENO))) std::setvbuf(stdout, nullptr, _IOFBF, 1 << 16);
  NullBuffer nothing;
  std::ostream null_out(&nothing), null_err(&nothing);
  const bool root = trubal::comm::root();
  trubal::Output output(root ? std::cout : null_out, root ? std::cerr : null_err);
  output.terminal = root && ::isatty(STDOUT_FILENO);
  trubal::Session session;
  trubal::Interpreter interp(session, output);
  trubal::install_interrupt_handler();

  // Tests: "R L" makes rank R's command at line L of the deck fail there alone, "R split" rank R's
  // first split of the spatial decomposition, "R cut" rank 0's cut of rank R's part at its first
  // split, "R search" its first share of a pair search through
  // the whole model, "R part" its first search on its part, "R results" its first gather of the
  // contact results from the parts, "R remake" its first step taken again to make them
  // (distributed_runs.cpp, distributed_user.cpp).
  trubal::StepPolicy& policy = session.policy();
  if (const char* at = std::getenv("TRUBAL_TEST_FAIL_AT")) {
    int rank = -1, line = 0;
    char word[8] = {};
    if (std::sscanf(at, "%d %d", &rank, &line) == 2) {
      if (rank == trubal::comm::rank()) interp.fail_line_for_test = line;
    } else if (std::sscanf(at, "%d %7s", &rank, word) == 2) {
      if (std::strcmp(word, "split") == 0) policy.fail_split = rank;
      if (std::strcmp(word, "cut") == 0) policy.fail_cut = rank;
      if (std::strcmp(word, "search") == 0) policy.fail_search = rank;
      if (std::strcmp(word, "part") == 0) policy.fail_part_search = rank;
      if (std::strcmp(word, "results") == 0) policy.fail_results = rank;
      if (std::strcmp(word, "remake") == 0) policy.fail_remake = rank;
    }
  }
  // Measurements: every stale pair list rebuilt through the whole model, as before the ranks
  // rebuilt them on their parts (to compare the two ways in one build).
  if (const char* whole = std::getenv("TRUBAL_REBUILD_WHOLE"); whole && std::strcmp(whole, "1") == 0)
    policy.local_rule = -1;
  // Measurements: the rescue copy of the whole model on rank 0, as before each rank kept its part's.
  if (const char* whole = std::getenv("TRUBAL_RESCUE_WHOLE"); whole && std::strcmp(whole, "1") == 0)
    policy.whole_rescue = true;
  // Tests: the decomposition's shares kept equal, whatever the ranks' speeds.
  if (const char* equal = std::getenv("TRUBAL_EQUAL_SHARES"); equal && std::strcmp(equal, "1") == 0)
    policy.follow_speeds = false;
  // Tests: a save's tables read a few rows at a time at a distributed RESTART.
  if (const char* rows = std::getenv("TRUBAL_SAVE_PIECE"); rows && std::atoi(rows) > 0)
    policy.save_piece_rows = static_cast<std::uint64_t>(std::atoi(rows));
  int status = 0;
  // What to run is rank 0's choice (its standard input is the terminal; the others' is not).
  std::int64_t stdin_deck = deck == "-" || (deck.empty() && !::isatty(STDIN_FILENO)) ? 1 : 0;
  trubal::comm::broadcast(stdin_deck);
  if (!interactive_deck.empty()) {
    interp.run_file(interactive_deck);   // errors are reported; the shell opens anyway
    if (!interp.stopped()) trubal::run_shell(interp);
  } else if (stdin_deck) {
    interp.agree_lazily = true;   // the deck's first error ends the run
    if (trubal::comm::size() == 1) {   // read as it comes: a pipe may feed commands one by one
      status = interp.run_deck(std::cin, "<stdin>") ? 0 : 1;
    } else {   // rank 0 reads it all, and hands it to the others
      std::istringstream in(trubal::Interpreter::read_stream_on_root(std::cin));
      status = interp.run_deck(in, "<stdin>") ? 0 : 1;
    }
  } else if (!deck.empty()) {
    interp.agree_lazily = true;
    status = interp.run_file(deck) ? 0 : 1;
  } else {
    trubal::run_shell(interp);
  }
  // Where the time went, when anything was cycled (to the screen and the log, if one is on).
  const auto& t = session.totals();
  output.out() << trubal::run_summary(t.cycles, t.ball_cycles, t.seconds,
                                      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(),
                                      t.times)
               << std::flush;
  // Output nobody received is a failure, not a success (trubal deck.dat > /dev/full).
  if (const int err = output.screen_error()) {
    std::fprintf(stderr, "trubal: cannot write the standard output: %s\n", std::strerror(err));
    return 1;
  }
  // So is a log that could not be written (a full disk): warned when it happened, and the status.
  output.take_log_failure();
  if (!output.log_failure().empty()) {
    std::fprintf(stderr, "trubal: %s\n", output.log_failure().c_str());
    return 1;
  }
  return status;
}

}  // namespace
