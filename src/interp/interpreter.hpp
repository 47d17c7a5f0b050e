// Runs lines of the command language: decks (batch), CALL'd files, and lines typed at the prompt.
#pragma once

#include <cstdint>
#include <istream>
#include <map>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "interp/command.hpp"
#include "interp/output.hpp"

namespace trubal {

class Session;
struct Command;
struct Context;
class Args;

// Thrown after an error has been reported, to unwind nested CALLs without reporting it again.
struct ReportedError {};

// An error another rank met at its FILE:LINE (under mpirun, where this rank may be further on).
struct LocatedError : std::runtime_error {
  LocatedError(std::string f, int l, const std::string& message) : std::runtime_error(message), file(std::move(f)), line(l) {}
  std::string file;
  int line = 0;
};

class Interpreter {
 public:
  Interpreter(Session& session, Output& output);

  // Runs a whole deck from a stream named `name` (a file name, or "<stdin>"). Returns false at the
  // first error, which is reported as NAME:LINE: error: ... on the error stream.
  bool run_deck(std::istream& in, const std::string& name);
  // Lines given by a host program (the Python module's Session.command): as a deck named `name`
  // whose first line is line `first_line` there (the caller's script and line), and whose
  // canonical path, for CALL's lookup beside the calling file, is `canonical`.
  bool run_text(const std::string& text, const std::string& name, const std::string& canonical, int first_line);
  bool run_file(const std::string& path);
  // One line typed at the prompt: errors are reported, the session goes on. Returns false on error.
  bool run_interactive_line(const std::string& line, int line_no);

  // A whole stream (a deck on standard input) as rank 0 read it, on every rank, to its first line
  // over kMaxLineLength (the LineReader reports it). Throws InputError on every rank when it fails.
  static std::string read_stream_on_root(std::istream& in);
  // A data file's text as rank 0 read it, on every rank (a collective call); nothing where rank 0
  // could not open it or it is not a regular file.
  static std::optional<std::string> read_file_on_root(const std::string& path);

  // For CALL: runs a file as part of the current command. Throws ReportedError after reporting
  // an error inside it.
  void call_file(const std::string& path);

  void warn(const std::string& message);
  void set_variable(const std::string& name, const std::string& value);
  std::optional<std::string> variable(const std::string& name) const;
  const std::map<std::string, std::string>& variables() const { return variables_; }

  // The last error reported: the innermost file and line (file empty for one outside any file)
  // and the message, for a host that raises it as its own exception.
  struct Error {
    std::string file;
    int line = 0;
    std::string message;
  };
  const Error& last_error() const { return last_error_; }
  // False: an error is only kept in last_error(), not written (a host raises it; warnings are written).
  bool report_errors = true;

  bool echo = true;                // echo commands in batch mode (SET echo on/off)
  bool interactive = false;        // lines come from the shell
  // Under mpirun, for a batch deck whose first error ends the run (main's): the ranks agree whether
  // a quick command (Command::quick: BALL, PROP, ECHO) failed only before the next command that is
  // not quick and at the deck's end, not after each. A failure is still agreed where it happens
  // (the failing rank's agreement meets the others' next), and carries its FILE:LINE, since the
  // others may be further on by then. Elsewhere (the shell, a host, a deck before the shell) every
  // command is agreed on as it ends: a rank that failed alone would leave the others' models changed.
  bool agree_lazily = false;
  // Tests (TRUBAL_TEST_FAIL_AT, main.cpp): the command at this line of a deck fails on this rank
  // alone, as a rank that ran out of memory would (0: none).
  int fail_line_for_test = 0;
  void request_stop() { stop_ = true; }
  bool stopped() const { return stop_; }
  // After STOP ended a deck: a host that goes on giving lines lets them run again.
  void resume() { stop_ = false; }
  Output& output() { return output_; }
  Session& session() { return session_; }

 private:
  struct Frame {
    std::string name;     // as shown in messages
    std::string canonical;
    int line = 0;
  };
  // Executes one logical line (comments and continuations already handled).
  void execute(const std::string& line);
  bool run_frames(std::istream& in, const std::string& name, const std::string& canonical, int first_line = 1);
  // Where this rank is: the innermost file and line ("" and 0 outside any file).
  std::string here_file() const { return frames_.empty() ? std::string() : frames_.back().name; }
  int here_line() const { return frames_.empty() ? 0 : frames_.back().line; }
  // `at`: the place another rank failed at, not this rank's.
  void report(const std::string& message, const LocatedError* at = nullptr);
  // An out-of-memory error at the current line, reported without allocating.
  void report_out_of_memory();
  // Runs a command on every rank and agrees whether it failed (comm::first_failure); `lazily`: a
  // success leaves the agreement pending (agree_lazily).
  // held: what the line does with BALL lines held on the ranks (held_use).
  void run_agreed(const Command& command, Context& ctx, Args& args, bool lazily, HeldUse held, OnRanks on_ranks);
  // The ranks' pending agreement on the quick commands run since the last one, if any: throws the
  // first failing rank's error.
  void settle_agreement();
  // The ranks agree whether a command failed (comm::first_failure), rank 0's echo of the lines run
  // lazily shown up to the first failing one (all where none failed); throws the failure.
  void agree(bool failed, std::string& message);
  void show_held_echo(std::int64_t through);
  // The echo of lines run lazily (agree_lazily), not yet agreed on: the text and where each
  // line's ends, by its order (commands_run_).
  std::string held_echo_;
  // What a command run lazily prints (ECHO's text), kept after its echo (keep_lazy_output).
  std::ostringstream lazy_out_;
  void keep_lazy_output();
  std::vector<std::pair<std::int64_t, std::size_t>> held_echo_ends_;
  // After the ranks agreed that a rank failed with `message` (encoded with its FILE:LINE): the error.
  [[noreturn]] void throw_agreed(std::string message);
  bool agreement_pending_ = false;
  std::int64_t commands_run_ = 0;   // on every rank alike: where in the deck a failure came first

  Session& session_;
  Output& output_;
  std::vector<Frame> frames_;
  std::map<std::string, std::string> variables_;
  Error last_error_;
  bool stop_ = false;
};

}  // namespace trubal
