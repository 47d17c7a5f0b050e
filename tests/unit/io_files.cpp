// Files written where a careless or hostile deck, or a planted link, could make them go wrong
// (issue 50): a PLOT name gnuplot would run, HIST and SET log through links and FIFOs, temporaries
// planted or left behind, a log that cannot be written.
#include "paths.hpp"

#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <cstdlib>

#include <fmt/format.h>

#include "io/atomic_file.hpp"
#include "io_support.hpp"
#include "skip.hpp"

using namespace trubal;
using namespace trubal::test;

namespace {

const std::string kRecorded = std::string(kPressedRow) + "hist energy every 2\ncycle 10\n";

// The names in `dir` that hold ".tmp-" (temporaries, ours or planted).
std::vector<std::string> temporaries_in(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().filename().string().find(".tmp-") != std::string::npos) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

}  // namespace

TEST_CASE("io files: a PLOT file name never reaches gnuplot, and one it would run is refused", "[io][plot][system]") {
  if (!on_path("gnuplot")) TRUBAL_SKIP("gnuplot is not installed (Debian: gnuplot-nox)");
  TempDir dir;
  WorkingDir wd(dir.path());
  // gnuplot's `set output '|cmd'` runs cmd through /bin/sh: the name (and the temporary made from
  // it, NAME.tmp-PID, as before) went there as given, and PWNED was made.
  for (const std::string name : {"|touch PWNED;.png", "<touch PWNED;.png"}) {
    INFO(name);
    Harness h;
    REQUIRE(h.deck(kRecorded));
    CHECK_FALSE(h.deck("plot ke vs cycle file \"" + name + "\"\n"));
    CHECK_FALSE(fs::exists(dir.path() / "PWNED"));
  }
  Harness bar;
  REQUIRE(bar.deck(kRecorded));
  CHECK_FALSE(bar.deck("plot ke vs cycle file \"|touch PWNED;.png\"\n"));
  CHECK_THAT(bar.first_error_line(),
             Catch::Contains("PLOT: will not write '|touch PWNED;.png': a file name may not start with '|' or '<' or "
                             "hold a control character"));
  // Inside a name a bar or a quote is just a character: gnuplot draws into our own folder, and the
  // picture is renamed into place (no temporary left beside it). A title's backquotes run nothing.
  fs::create_directory(dir.path() / "a|b");
  Harness ok;
  REQUIRE(ok.deck(kRecorded + "plot ke vs cycle file \"a|b/it's |touch PWNED;.png\" title \"`touch PWNED`\"\n"));
  INFO(ok.err.str());
  CHECK(fs::file_size(dir.path() / "a|b" / "it's |touch PWNED;.png") > 0);
  CHECK_FALSE(fs::exists(dir.path() / "PWNED"));
  CHECK(temporaries_in(dir.path() / "a|b").empty());
  CHECK(temporaries_in(dir.path()).empty());
}

TEST_CASE("io files: HIST never writes through a link, and a FIFO is refused at once", "[io][system]") {
  TempDir dir;
  const std::string precious = dir.write("precious.txt", "keep me\n");
  const std::string link = (dir.path() / "h.csv").string();
  REQUIRE(::symlink(precious.c_str(), link.c_str()) == 0);
  for (const std::string mode : {"", " new"}) {
    INFO(mode);
    Harness h;
    CHECK_FALSE(h.deck(std::string(kPressedRow) + "hist energy every 1 file " + link + mode + "\ncycle 2\n"));
    CHECK_THAT(h.first_error_line(), Catch::Contains("deck.dat:9: error: will not replace '" + link +
                                                     "': it is a symbolic link (name a regular file, or a new one)"));
    CHECK(slurp(precious) == "keep me\n");
    CHECK(fs::is_symlink(link));
  }
  {   // SET log appends, but not through a link either
    Harness h;
    CHECK_FALSE(h.deck("set log " + link + "\necho hello\n"));
    CHECK_THAT(h.first_error_line(), Catch::Contains("deck.dat:1: error: will not append to the log file '" + link +
                                                     "': it is a symbolic link (name a regular file, or a new one)"));
    CHECK(slurp(precious) == "keep me\n");
    Harness device;   // a link to a device is followed, as /dev/stderr is one
    CHECK(device.deck("set log /dev/stderr\necho hello\nset log off\n"));
  }
  // A FIFO with no reader: opening it blocked for ever (and Ctrl-C could not stop it). HIST
  // refuses it, as PRINT and SAVE do; SET log opens without waiting and fails. `timeout` ends the
  // old hang (124).
  const std::string fifo = (dir.path() / "p.csv").string();
  REQUIRE(::mkfifo(fifo.c_str(), 0600) == 0);
  struct Case {
    std::string deck, said;
  };
  for (const Case& c : {Case{std::string(kPressedRow) + "hist energy every 1 file p.csv\ncycle 2\n",
                             "deck.dat:9: error: will not replace 'p.csv': it is a FIFO (a named pipe: writing to it "
                             "waits for a reader) (name a regular file, or a new one)"},
                        Case{"set log p.csv\necho hello\n",
                             "deck.dat:1: error: cannot open the log file 'p.csv': it is a FIFO (a named pipe) that no "
                             "process reads; writing to it would wait for ever"}}) {
    INFO(c.deck);
    dir.write("deck.dat", c.deck);
    const int status = shell("cd " + quote(dir.str()) + " && timeout 20 " + quote(TRUBAL_EXE) +
                             " deck.dat </dev/null >out.txt 2>err.txt");
    CHECK(status == 1);
    CHECK_THAT(slurp(dir.path() / "err.txt"), Catch::Contains(c.said));
  }
}

TEST_CASE("io files: a link planted where a temporary would go is never followed", "[io]") {
  TempDir dir;
  WorkingDir wd(dir.path());
  // The temporaries were FILE.tmp-PID, opened without O_EXCL or O_NOFOLLOW: a link planted under
  // that name was followed (its target replaced by the table or the save) and then renamed over FILE.
  const std::string victim = dir.write("victim.txt", "keep me\n");
  for (const std::string file : {"b.csv", "s.sav", "c.txt"}) {
    INFO(file);
    const std::string planted = fmt::format("{}.tmp-{}", file, ::getpid());
    REQUIRE(::symlink(victim.c_str(), planted.c_str()) == 0);
    Harness h;
    const std::string command = file == "b.csv" ? "print balls file b.csv" : file == "s.sav" ? "save s.sav"
                                                                                         : "print counters file c.txt";
    REQUIRE(h.deck(std::string(kPressedRow) + command + "\n"));
    INFO(h.err.str());
    CHECK(slurp(victim) == "keep me\n");
    CHECK(fs::is_regular_file(fs::symlink_status(file)));
    CHECK(fs::file_size(file) > 0);
    CHECK(fs::is_symlink(planted));   // (ours to ignore, not to remove: its process is this one)
    fs::remove(planted);
  }
  CHECK(temporaries_in(dir.path()).empty());
}

TEST_CASE("io files: the temporaries a killed run left are removed by the next write of the same file", "[io]") {
  TempDir dir;
  WorkingDir wd(dir.path());
  // Pids above the largest Linux allows (2^22): no process has them. Only names of our pattern go;
  // a file of the user's that merely looks alike stays.
  for (const char* name : {"snap.pvd.tmp-999999999", "snap_000000.vtp.tmp-999999998-aB3xY9", "b.csv.tmp-999999997",
                           "snap.pvd.tmp-notes", "snap.pvd.tmp-999999999-toolong1", "other.csv.tmp-999999996"})
    dir.write(name, "left over\n");
  Harness h;
  REQUIRE(h.deck(std::string(kPressedRow) + "dump vtk snap\nprint balls file b.csv\n"));
  CHECK(temporaries_in(dir.path()) ==
        std::vector<std::string>{"other.csv.tmp-999999996", "snap.pvd.tmp-999999999-toolong1", "snap.pvd.tmp-notes"});
}

TEST_CASE("io files: SIGTERM during a write leaves no temporary", "[io]") {
  TempDir dir;
  const std::string target = (dir.path() / "t.csv").string();
  // A child writes the file and is sent SIGTERM while the temporary is open (its default action,
  // as for a run that a job scheduler stops). The temporary was left behind.
  const pid_t child = ::fork();
  REQUIRE(child >= 0);
  if (child == 0) {
    std::signal(SIGTERM, SIG_DFL);   // (the test runner's own handler, not the program's state)
    try {
      write_file_atomically(target, [](std::ostream& out) {
        out << "half a table\n" << std::flush;
        std::raise(SIGTERM);
      });
    } catch (...) {
    }
    ::_exit(3);
  }
  int status = 0;
  REQUIRE(::waitpid(child, &status, 0) == child);
  CHECK(WIFSIGNALED(status));
  CHECK((WIFSIGNALED(status) && WTERMSIG(status) == SIGTERM));
  CHECK(temporaries_in(dir.path()).empty());
  CHECK_FALSE(fs::exists(target));
}

TEST_CASE("io files: a log that cannot be written ends the run with exit status 1", "[io][system]") {
  if (!fs::exists("/dev/full")) TRUBAL_SKIP("no /dev/full");
  TempDir dir;
  dir.write("deck.dat", "set log /dev/full\necho one\necho two\n");
  // It warned and the run went on, as it still does; the run then exited 0.
  const int status = shell("cd " + quote(dir.str()) + " && " + quote(TRUBAL_EXE) + " deck.dat </dev/null >out.txt 2>err.txt");
  CHECK(status == 1);
  const std::string err = slurp(dir.path() / "err.txt");
  CHECK_THAT(err, Catch::Contains("warning: the log file '/dev/full' could not be written (No space left on device); "
                                  "logging stopped"));
  CHECK_THAT(err, Catch::Contains("trubal: the log file '/dev/full' could not be written (No space left on device)"));
  CHECK_THAT(slurp(dir.path() / "out.txt"), Catch::Contains("two"));
}
