// The interactive shell under a real pseudo-terminal (tmux): commands run, Tab completes, Ctrl-C
// clears the line or stops a CYCLE, errors do not end the session, history outlives the session.
// Without tmux, or without a pseudo-terminal, they are skipped (CI installs tmux: Debian package
// `tmux`).
#include "paths.hpp"
#include <catch2/catch.hpp>

#include <fcntl.h>
#include <stdlib.h>

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <thread>

#include "interp_support.hpp"
#include "skip.hpp"

using namespace trubal::test;

namespace {

// A pseudo-terminal can be opened (not in a chroot whose /dev has no devpts mounted).
bool have_pty() {
  int master = ::posix_openpt(O_RDWR | O_NOCTTY);
  if (master < 0) return false;
  bool ok = ::grantpt(master) == 0 && ::unlockpt(master) == 0;
  if (ok) {
    const char* name = ::ptsname(master);
    int slave = name ? ::open(name, O_RDWR | O_NOCTTY) : -1;
    ok = slave >= 0;
    if (slave >= 0) ::close(slave);
  }
  ::close(master);
  return ok;
}

// One trubal shell in a detached tmux session on its own server (socket), 200 x 50 characters.
class TmuxShell {
 public:
  TmuxShell(const TempDir& dir, const std::string& history_file) {
    static int counter = 0;
    socket_ = "trubal-test-" + std::to_string(::getpid()) + "-" + std::to_string(counter++);
    std::string program = "cd " + quote(dir.str()) + " && exec env TRUBAL_HISTORY=" + quote(history_file) +
                          " HOME=" + quote(dir.str()) + " INPUTRC=/dev/null " + quote(TRUBAL_EXE);
    started_ = tmux("-f /dev/null new-session -d -s shell -x 200 -y 50 " + quote(program)) == 0;
  }
  ~TmuxShell() { tmux("kill-server >/dev/null 2>&1"); }
  TmuxShell(const TmuxShell&) = delete;
  TmuxShell& operator=(const TmuxShell&) = delete;

  bool started() const { return started_; }
  bool alive() { return tmux("has-session -t shell >/dev/null 2>&1") == 0; }
  // Literal text, no Enter.
  void type(const std::string& text) { tmux("send-keys -t shell -l " + quote(text)); }
  // Named keys: Enter, Tab, C-c, C-d, C-u, Up.
  void key(const std::string& name) { tmux("send-keys -t shell " + name); }
  std::string screen() {
    std::string cmd = "tmux -L " + socket_ + " capture-pane -p -t shell 2>/dev/null";
    std::string text;
    if (FILE* p = ::popen(cmd.c_str(), "r")) {
      char buf[4096];
      for (std::size_t n; (n = std::fread(buf, 1, sizeof buf, p)) > 0;) text.append(buf, n);
      ::pclose(p);
    }
    return text;
  }
  // Waits until the screen shows `text` (or a line equal to it, with whole_line).
  bool wait_for(const std::string& text, bool whole_line = false, double seconds = 15) {
    auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    while (std::chrono::steady_clock::now() < until) {
      std::string s = screen();
      if (!whole_line && s.find(text) != std::string::npos) return true;
      if (whole_line)
        for (const auto& l : lines_of(s))
          if (l == text) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    return false;
  }
  // Waits until the shell shows a fresh, empty prompt on its last line: readline is reading
  // again. A control key sent earlier, while a command still runs, reaches the terminal in
  // its line mode, where Ctrl-D is no end of input to readline once it takes the terminal.
  bool wait_prompt(double seconds = 15) {
    auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    while (std::chrono::steady_clock::now() < until) {
      std::string last;
      for (const auto& l : lines_of(screen()))
        if (l.find_first_not_of(' ') != std::string::npos) last = l;
      if (last.substr(0, last.find_last_not_of(' ') + 1) == "trubal>") return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    return false;
  }
  bool wait_exit(double seconds = 15) {
    auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    while (std::chrono::steady_clock::now() < until) {
      if (!alive()) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    return false;
  }

 private:
  int tmux(const std::string& args) { return shell("tmux -L " + socket_ + " " + args); }
  std::string socket_;
  bool started_ = false;
};

// Checks a condition on the shell's screen; shows the screen when it fails.
#define CHECK_SCREEN(sh, cond)                                            \
  do {                                                                    \
    bool screen_ok_ = (cond);                                             \
    INFO("condition: " #cond);                                            \
    if (!screen_ok_) UNSCOPED_INFO("screen:\n" << (sh).screen());          \
    CHECK(screen_ok_);                                                    \
  } while (0)

#define REQUIRE_TMUX()                                                                  \
  do {                                                                                  \
    if (!on_path("tmux")) TRUBAL_SKIP("tmux is not installed (Debian: tmux)");          \
    if (!have_pty()) TRUBAL_SKIP("no pseudo-terminal can be opened (no devpts mounted)"); \
  } while (0)

}  // namespace

TEST_CASE("interp shell: a command runs and HELP lists the commands", "[interp][shell][system]") {
  REQUIRE_TMUX();
  TempDir dir;
  TmuxShell sh(dir, dir.str() + "/history");
  REQUIRE(sh.started());
  REQUIRE(sh.wait_for("trubal>"));
  CHECK_THAT(sh.screen(), Catch::Contains("HELP lists the commands"));
  sh.type("help");
  sh.key("Enter");
  CHECK_SCREEN(sh, sh.wait_for("STOP/QUIT/END/EXIT"));
  CHECK_SCREEN(sh, sh.wait_for("  CYCLE "));
  CHECK(sh.alive());
}

TEST_CASE("interp shell: Tab completes keywords and the words a command takes", "[interp][shell][system]") {
  REQUIRE_TMUX();
  TempDir dir;
  TmuxShell sh(dir, dir.str() + "/history");
  REQUIRE(sh.started());
  REQUIRE(sh.wait_for("trubal>"));
  sh.type("cyc");
  sh.key("Tab");
  CHECK_SCREEN(sh, sh.wait_for("trubal> cycle"));
  sh.key("C-u");
  sh.type("print bal");
  sh.key("Tab");
  CHECK_SCREEN(sh, sh.wait_for("trubal> print balls"));
  sh.key("C-u");
  // A completed keyword runs: `hel<Tab>` then Enter is HELP.
  sh.type("hel");
  sh.key("Tab");
  sh.key("Enter");
  CHECK_SCREEN(sh, sh.wait_for("STOP/QUIT/END/EXIT"));
}

TEST_CASE("interp shell: Ctrl-C at the prompt clears the line and the shell goes on", "[interp][shell][system]") {
  REQUIRE_TMUX();
  TempDir dir;
  TmuxShell sh(dir, dir.str() + "/history");
  REQUIRE(sh.started());
  REQUIRE(sh.wait_for("trubal>"));
  sh.type("echo leftover");
  REQUIRE(sh.wait_for("trubal> echo leftover"));
  sh.key("C-c");
  CHECK_SCREEN(sh, sh.wait_for("^C"));
  sh.type("echo fresh");
  sh.key("Enter");
  // Had the line not been cleared the command would have been `echo leftoverecho fresh`.
  CHECK_SCREEN(sh, sh.wait_for("fresh", true));
  CHECK(sh.screen().find("leftoverecho") == std::string::npos);
  // Ctrl-C also drops lines already continued with &: only the new command runs.
  sh.type("echo pending &");
  sh.key("Enter");
  CHECK_SCREEN(sh, sh.wait_for("   ...>"));
  sh.type("more");
  sh.key("C-c");
  sh.type("echo second");
  sh.key("Enter");
  CHECK_SCREEN(sh, sh.wait_for("second", true));
  CHECK(sh.screen().find("pending") == sh.screen().rfind("pending"));   // only where it was typed
  CHECK(sh.alive());
}

TEST_CASE("interp shell: an error is reported and the session goes on", "[interp][shell][system]") {
  REQUIRE_TMUX();
  TempDir dir;
  TmuxShell sh(dir, dir.str() + "/history");
  REQUIRE(sh.started());
  REQUIRE(sh.wait_for("trubal>"));
  sh.type("frobnicate 1 2");
  sh.key("Enter");
  CHECK_SCREEN(sh, sh.wait_for("<stdin>:1: error: unknown command 'frobnicate'"));
  sh.type("cycle 1.5");
  sh.key("Enter");
  CHECK_SCREEN(sh, sh.wait_for("<stdin>:2: error: n (number of cycles) must be a whole number"));
  sh.type("echo alive");
  sh.key("Enter");
  CHECK_SCREEN(sh, sh.wait_for("alive", true));
  CHECK(sh.alive());
  // STOP ends it.
  sh.type("stop");
  sh.key("Enter");
  CHECK_SCREEN(sh, sh.wait_exit());
}

TEST_CASE("interp shell: history is kept between sessions", "[interp][shell][system]") {
  REQUIRE_TMUX();
  TempDir dir;
  const std::string history = dir.str() + "/history";
  {
    TmuxShell sh(dir, history);
    REQUIRE(sh.started());
    REQUIRE(sh.wait_for("trubal>"));
    sh.type("echo remembered 123");
    sh.key("Enter");
    REQUIRE(sh.wait_for("remembered 123", true));
    REQUIRE(sh.wait_prompt());
    sh.key("C-d");
    CHECK_SCREEN(sh, sh.wait_exit());
  }
  CHECK_THAT(slurp(history), Catch::Contains("echo remembered 123"));
  TmuxShell again(dir, history);
  REQUIRE(again.started());
  REQUIRE(again.wait_for("trubal>"));
  again.key("Up");
  CHECK_SCREEN(again, again.wait_for("trubal> echo remembered 123"));
}

TEST_CASE("interp shell: Ctrl-C stops a running CYCLE and keeps the model", "[interp][shell][system]") {
  REQUIRE_TMUX();
  TempDir dir;
  TmuxShell sh(dir, dir.str() + "/history");
  REQUIRE(sh.started());
  REQUIRE(sh.wait_for("trubal>"));
  sh.type("start box 0 10 0 10 0 10 ; a free region");
  sh.key("Enter");
  sh.type("gen 500 0.2 0.3 seed 5");
  sh.key("Enter");
  sh.type("prop kn 1e6 ks 1e6 dens 1000");
  sh.key("Enter");
  sh.type("cycle 2000000000");
  sh.key("Enter");
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));
  sh.key("C-c");
  CHECK_SCREEN(sh, sh.wait_for("interrupted after"));
  CHECK(sh.alive());
  sh.type("print info");
  sh.key("Enter");
  CHECK_SCREEN(sh, sh.wait_for("backend: "));
  // The cycles run before Ctrl-C are kept: PRINT info shows a cycle count above 0.
  std::string screen = sh.screen();
  auto at = screen.find("\ncycle: ");
  REQUIRE(at != std::string::npos);
  CHECK(std::stol(screen.substr(at + 8)) > 0);
}

TEST_CASE("interp shell: Ctrl-D or STOP with the model changed since the last SAVE asks first", "[interp][shell][system]") {
  REQUIRE_TMUX();
  TempDir dir;
  TmuxShell sh(dir, dir.str() + "/history");
  REQUIRE(sh.started());
  REQUIRE(sh.wait_for("trubal>"));
  // Nothing changed yet: Ctrl-D would leave at once (tried at the end, after a SAVE).
  sh.type("start box 0 1 0 1 0 1");
  sh.key("Enter");
  CHECK_SCREEN(sh, sh.wait_for("new model in the box"));
  CHECK_SCREEN(sh, sh.wait_prompt());
  sh.key("C-d");
  CHECK_SCREEN(sh, sh.wait_for("the model changed since the last SAVE; quit anyway? [y/N]"));
  sh.key("Enter");   // no, by default: back at the prompt with the model
  sh.type("print counters");
  sh.key("Enter");
  CHECK_SCREEN(sh, sh.wait_for("balls 0"));
  CHECK(sh.alive());
  CHECK_SCREEN(sh, sh.wait_prompt());
  sh.key("C-d");
  CHECK_SCREEN(sh, sh.wait_for("quit anyway? [y/N]"));
  sh.type("y");
  sh.key("Enter");
  CHECK(sh.wait_exit());

  // STOP typed at the prompt asks as Ctrl-D does; no keeps the session.
  TmuxShell stop(dir, dir.str() + "/history");
  REQUIRE(stop.started());
  REQUIRE(stop.wait_for("trubal>"));
  stop.type("start box 0 1 0 1 0 1");
  stop.key("Enter");
  CHECK_SCREEN(stop, stop.wait_for("new model in the box"));
  stop.type("quit");
  stop.key("Enter");
  CHECK_SCREEN(stop, stop.wait_for("the model changed since the last SAVE; quit anyway? [y/N]"));
  stop.type("n");
  stop.key("Enter");
  stop.type("print counters");
  stop.key("Enter");
  CHECK_SCREEN(stop, stop.wait_for("balls 0"));
  CHECK(stop.alive());
  stop.type("stop");
  stop.key("Enter");
  auto asked_again = [&] {   // the second question on the screen
    for (int k = 0; k < 300; ++k) {
      const std::string screen = stop.screen();
      if (screen.find("quit anyway") != screen.rfind("quit anyway")) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    return false;
  };
  CHECK_SCREEN(stop, asked_again());
  stop.type("y");
  stop.key("Enter");
  CHECK(stop.wait_exit());

  // After a SAVE, Ctrl-D leaves without a question.
  TmuxShell saved(dir, dir.str() + "/history");
  REQUIRE(saved.started());
  REQUIRE(saved.wait_for("trubal>"));
  saved.type("start box 0 1 0 1 0 1");
  saved.key("Enter");
  saved.type("save run.sav");
  saved.key("Enter");
  CHECK_SCREEN(saved, saved.wait_for("saved to run.sav"));   // SAVE's message, not the line typed
  CHECK_SCREEN(saved, saved.wait_prompt());
  saved.key("C-d");
  CHECK(saved.wait_exit());
}
