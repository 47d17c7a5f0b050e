// Where the program's words go: the screen, and a copy in the log file when SET log asks for one.
#pragma once

#include <fstream>
#include <memory>
#include <ostream>
#include <streambuf>
#include <string>

namespace trubal {

class TeeBuffer : public std::streambuf {
 public:
  explicit TeeBuffer(std::streambuf* primary) : primary_(primary) {}
  void set_copy(std::streambuf* copy) { copy_ = copy; }

 protected:
  int overflow(int c) override;
  std::streamsize xsputn(const char* s, std::streamsize n) override;
  int sync() override;

 private:
  std::streambuf* primary_;
  std::streambuf* copy_ = nullptr;
};

class Output {
 public:
  Output(std::ostream& out, std::ostream& err);
  std::ostream& out() { return out_; }
  std::ostream& err() { return err_; }
  // Starts (or, with an empty path, stops) copying everything shown to a log file.
  void set_log(const std::string& path);
  const std::string& log_path() const { return log_path_; }
  // The screen stream is a terminal (main sets it; false for captured output): progress may
  // redraw one line there. A log file, or any other stream, gets plain lines only.
  bool terminal = false;
  // Seconds between plain progress lines of a long CYCLE or SOLVE (SET progress; 0: none).
  double progress_seconds = 10;

 private:
  TeeBuffer out_buf_, err_buf_;
  std::ostream out_, err_;
  std::unique_ptr<std::ofstream> log_;
  std::string log_path_;
};

}  // namespace trubal
