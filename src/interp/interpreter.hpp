// Runs lines of the command language: decks (batch), CALL'd files, and lines typed at the prompt.
#pragma once

#include <istream>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "interp/output.hpp"

namespace trubal {

class Session;

// Thrown after an error has been reported, to unwind nested CALLs without reporting it again.
struct ReportedError {};

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

  // A whole stream (a deck on standard input) as rank 0 read it, on every rank.
  static std::string read_stream_on_root(std::istream& in);

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
  void report(const std::string& message);

  Session& session_;
  Output& output_;
  std::vector<Frame> frames_;
  std::map<std::string, std::string> variables_;
  Error last_error_;
  bool stop_ = false;
};

}  // namespace trubal
