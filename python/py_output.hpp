// Where the engine's words go from Python: sys.stdout and sys.stderr as they are at each write
// (so contextlib.redirect_stdout and notebooks catch them), or nowhere when the session is quiet.
#pragma once

#include <streambuf>
#include <string>

namespace trubal::python {

class PythonStreamBuffer : public std::streambuf {
 public:
  explicit PythonStreamBuffer(const char* stream_name) : stream_name_(stream_name) {}
  bool quiet = false;

 protected:
  int overflow(int c) override;
  std::streamsize xsputn(const char* s, std::streamsize n) override;
  int sync() override;

 private:
  // Hands whole lines to Python (one write per line keeps interleaving with print() sane).
  void flush_pending();
  const char* stream_name_;   // "stdout" or "stderr": an attribute of sys
  std::string pending_;
};

}  // namespace trubal::python
