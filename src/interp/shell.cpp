#include "interp/shell.hpp"

#include <unistd.h>

#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include <readline/history.h>
#include <readline/readline.h>

#include "support/comm.hpp"

#include <fmt/format.h>

#include "interp/command.hpp"
#include "interp/interpreter.hpp"
#include "interp/lexer.hpp"
#include "interp/signals.hpp"
#include "session.hpp"

namespace trubal {

namespace {

volatile std::sig_atomic_t g_at_prompt = 0;
volatile std::sig_atomic_t g_line_cancelled = 0;   // Ctrl-C at a prompt: drop any continued lines too

// At the prompt Ctrl-C throws the line away and shows a fresh prompt; while a command runs it asks
// the command to stop at the end of the current step.
void on_sigint(int) {
  if (g_at_prompt) {
    if (write(STDOUT_FILENO, "^C\n", 3) < 0) {}
    g_line_cancelled = 1;
    rl_set_prompt("trubal> ");
    rl_on_new_line();
    rl_replace_line("", 0);
    rl_redisplay();
    return;
  }
  if (interrupt_requested().exchange(true)) {
    std::signal(SIGINT, SIG_DFL);
    std::raise(SIGINT);
  }
}

std::vector<std::string> g_matches;

char* match_generator(const char*, int state) {
  static std::size_t next;
  if (state == 0) next = 0;
  if (next < g_matches.size()) return strdup(g_matches[next++].c_str());
  return nullptr;
}

char** complete(const char* text, int start, int) {
  std::string before(rl_line_buffer, static_cast<std::size_t>(start));
  g_matches = completions(before, text);
  rl_attempted_completion_over = 1;   // no file names unless we ask for them
  auto words = split_words(before);
  if (!words.empty()) {
    try {
      const Command& c = find_command(words[0]);
      if (c.name == "CALL" || c.name == "SAVE" || c.name == "RESTART" ||
          (!words.empty() && match_keyword(words.back(), {"file"})))
        rl_attempted_completion_over = 0;   // file names
    } catch (const InputError&) {
    }
  }
  if (g_matches.empty()) return nullptr;
  return rl_completion_matches(text, match_generator);
}

constexpr const char* kNotSaved = "note: the session ends with the model not saved (it changed since the last SAVE)\n";

// Ctrl-D at an empty prompt, or STOP typed there, with the model changed since the last SAVE (or RESTART): whether to
// leave. At a terminal the shell asks, as an editor does (no by default; Ctrl-D again leaves);
// elsewhere (a deck piped in after -i) it leaves, saying what was not saved.
bool leave_unsaved() {
  if (!::isatty(STDIN_FILENO)) {
    std::fputs(kNotSaved, stderr);
    return true;
  }
  g_at_prompt = 1;
  char* raw = readline("the model changed since the last SAVE; quit anyway? [y/N] ");
  g_at_prompt = 0;
  if (!raw) {   // (also where the terminal went away: no loop on a closed input)
    std::fputs("\n", stdout);
    std::fputs(kNotSaved, stderr);
    return true;
  }
  std::string answer = to_lower(raw);
  std::free(raw);
  answer.erase(0, answer.find_first_not_of(" \t"));
  const bool yes = answer.starts_with("y");
  if (yes) std::fputs(kNotSaved, stderr);
  return yes;
}

// A line that is STOP alone (or QUIT, END, EXIT, or a shortening): the shell leaves by it as by Ctrl-D.
bool is_stop(const std::string& line) {
  const auto words = split_words(line);
  if (words.size() != 1) return false;
  try {
    return find_command(words[0]).name == "STOP";
  } catch (const InputError&) {
    return false;
  }
}

}  // namespace

std::vector<std::string> completions(const std::string& line_before, const std::string& text) {
  std::vector<std::string_view> pool;
  auto words = split_words(line_before);
  if (words.empty()) {
    for (const Command* c : command_table()) {
      pool.push_back(c->name);
      for (auto a : c->aliases) pool.push_back(a);
    }
  } else {
    try {
      const Command& c = find_command(words[0]);
      if (c.name == "HELP")
        for (const Command* d : command_table()) pool.push_back(d->name);
      else
        pool = c.words;
    } catch (const InputError&) {
      return {};
    }
  }
  // Match the case the user types in: lower case in, lower case out.
  bool upper = !text.empty() && std::isupper(static_cast<unsigned char>(text[0]));
  if (text.empty()) upper = words.empty() || std::isupper(static_cast<unsigned char>(words[0][0]));
  std::vector<std::string> out;
  std::string t = to_lower(text);
  for (auto p : pool)
    if (to_lower(p).starts_with(t)) out.push_back(upper ? to_upper(p) : to_lower(p));
  return out;
}

std::string history_path() {
  if (const char* p = std::getenv("TRUBAL_HISTORY"); p && *p) return p;
  const char* home = std::getenv("HOME");
  return std::string(home && *home ? home : ".") + "/.trubal_history";
}

// The other ranks of a distributed run: rank 0's shell hands them each line it runs.
static int follow_shell(Interpreter& interp) {
  interp.interactive = true;
  int failures = 0;
  while (!interp.stopped()) {
    std::string packed;
    comm::broadcast(packed);
    if (packed.empty() || packed[0] != 'L') break;   // rank 0's shell ended
    const std::size_t cut = packed.find('\n');
    const int line_no = std::stoi(packed.substr(1, cut - 1));
    if (!interp.run_interactive_line(packed.substr(cut + 1), line_no)) ++failures;
  }
  return failures;
}

int run_shell(Interpreter& interp) {
  if (!comm::root()) return follow_shell(interp);
  interp.interactive = true;
  rl_readline_name = "trubal";
  rl_attempted_completion_function = complete;
  rl_catch_signals = 0;
  struct sigaction sa {};
  sa.sa_handler = on_sigint;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESTART;
  sigaction(SIGINT, &sa, nullptr);

  const std::string hist = history_path();
  using_history();
  read_history(hist.c_str());
  fmt::print("trubal {} - TRUBAL's command language. HELP lists the commands, Ctrl-D leaves.\n", TRUBAL_VERSION);
  int failures = 0, line_no = 0;
  while (!interp.stopped()) {
    std::string logical;
    const char* prompt = "trubal> ";
    bool eof = false;
    g_line_cancelled = 0;
    for (;;) {
      g_at_prompt = 1;
      char* raw = readline(prompt);
      g_at_prompt = 0;
      if (!raw) { eof = true; break; }
      if (g_line_cancelled) {   // the lines continued before Ctrl-C are dropped with it
        g_line_cancelled = 0;
        logical.clear();
        prompt = "trubal> ";
      }
      std::string line(raw);
      std::free(raw);
      ++line_no;
      if (!line.empty()) {
        add_history(line.c_str());
        // Appended as it is typed, so a crash loses no history.
        if (append_history(1, hist.c_str()) != 0) write_history(hist.c_str());
      }
      std::string body = strip_comment(line);
      while (!body.empty() && (body.back() == ' ' || body.back() == '\t')) body.pop_back();
      if (!body.empty() && (body.back() == '&' || body.back() == '\\')) {
        body.pop_back();
        logical += body + ' ';
        prompt = "   ...> ";
        continue;
      }
      logical += body;
      break;
    }
    if (eof) {
      std::fputs("\n", stdout);
      if (interp.session().unsaved() && !leave_unsaved()) continue;
      if (comm::size() > 1) {
        std::string end = "E";
        comm::broadcast(end);
      }
      break;
    }
    // STOP typed at the prompt asks as Ctrl-D does; a no leaves the line unrun (the other ranks never
    // see it).
    if (is_stop(logical) && interp.session().unsaved() && !leave_unsaved()) continue;
    if (comm::size() > 1) {
      std::string packed = fmt::format("L{}\n{}", line_no, logical);
      comm::broadcast(packed);
    }
    interrupt_requested() = false;
    if (!interp.run_interactive_line(logical, line_no)) ++failures;
  }
  history_truncate_file(hist.c_str(), 2000);
  return failures;
}

}  // namespace trubal
