// Where the program's words go: the screen, and a copy in the log file when SET log asks for one.
#pragma once

#include <fstream>
#include <memory>
#include <ostream>
#include <streambuf>
#include <string>

#include "support/fd_output.hpp"

namespace trubal {

class TeeBuffer : public std::streambuf {
 public:
  explicit TeeBuffer(std::streambuf* primary) : primary_(primary) {}
  void set_copy(std::streambuf* copy) { copy_ = copy; copy_error_ = 0; }
  // The errno of the first failed write to the copy (the log) or to the screen stream; 0: none.
  int copy_error() const { return copy_error_; }
  int primary_error() const { return primary_error_; }

 protected:
  int overflow(int c) override;
  std::streamsize xsputn(const char* s, std::streamsize n) override;
  int sync() override;

 private:
  std::streambuf* primary_;
  std::streambuf* copy_ = nullptr;
  int copy_error_ = 0, primary_error_ = 0;
};

class Output {
 public:
  Output(std::ostream& out, std::ostream& err);
  std::ostream& out() { return out_; }
  std::ostream& err() { return err_; }
  // Starts (or, with an empty path, stops) copying everything shown to a log file, appending. A
  // FIFO that no process reads is refused at once (opening it would wait for ever).
  void set_log(const std::string& path);
  const std::string& log_path() const { return log_path_; }
  // After a write to the log failed (a full disk): stops logging and says why, once; "" otherwise.
  std::string take_log_failure();
  // The first such failure of the run ("" when none): the run then ends with exit status 1.
  const std::string& log_failure() const { return log_failure_; }
  // The errno of the first failed write to the screen streams (0: none), after flushing them.
  int screen_error();
  // The screen stream is a terminal (main sets it; false for captured output): progress may
  // redraw one line there. A log file, or any other stream, gets plain lines only.
  bool terminal = false;
  // Seconds between plain progress lines of a long CYCLE or SOLVE (SET progress; 0: none).
  double progress_seconds = 10;

 private:
  TeeBuffer out_buf_, err_buf_;
  std::ostream out_, err_;
  std::unique_ptr<FdOutput> log_;
  std::string log_path_, log_failure_;
};

}  // namespace trubal
