// Helpers the interpreter tests share: an interpreter whose screen and error streams are strings,
// temporary directories, running the trubal executable through the shell.
#pragma once

#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

#include "ball_at.hpp"
#include "interp/interpreter.hpp"
#include "interp/output.hpp"
#include "session.hpp"

namespace trubal::test {

namespace fs = std::filesystem;

// A fresh directory under the system's temporary directory, removed with everything in it.
class TempDir {
 public:
  TempDir() {
    std::string pattern = (fs::temp_directory_path() / "trubal-test-XXXXXX").string();
    if (!::mkdtemp(pattern.data())) throw std::runtime_error("mkdtemp failed");
    path_ = pattern;
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const fs::path& path() const { return path_; }
  std::string str() const { return path_.string(); }
  // Writes a file in the directory and returns its full path.
  std::string write(const std::string& name, const std::string& text) const {
    fs::path p = path_ / name;
    std::ofstream f(p, std::ios::binary | std::ios::trunc);
    f << text;
    return p.string();
  }

 private:
  fs::path path_;
};

// Changes the working directory for a scope (commands that write files write them there).
class WorkingDir {
 public:
  explicit WorkingDir(const fs::path& dir) : saved_(fs::current_path()) { fs::current_path(dir); }
  ~WorkingDir() {
    std::error_code ec;
    fs::current_path(saved_, ec);
  }

 private:
  fs::path saved_;
};

inline std::string slurp(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}

inline std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string l; std::getline(in, l);) out.push_back(l);
  return out;
}

// An interpreter with its output captured.
struct Harness {
  std::ostringstream out, err;
  Output output{out, err};
  Session session;
  Interpreter interp{session, output};

  // Commands are not echoed unless a test asks (interp.echo = true), so `out` holds only what they print.
  Harness() { interp.echo = false; }

  bool deck(const std::string& text, const std::string& name = "deck.dat") {
    std::istringstream in(text);
    return interp.run_deck(in, name);
  }
  bool line(const std::string& text, int line_no = 1) { return interp.run_interactive_line(text, line_no); }
  // The first line that reports an error (warnings before it skipped), else the first line.
  std::string first_error_line() const {
    auto l = lines_of(err.str());
    for (const auto& line : l)
      if (line.find(": error: ") != std::string::npos) return line;
    return l.empty() ? std::string() : l.front();
  }
};

// Runs a shell command line; returns its exit status (or 128 + signal, or -1).
inline int shell(const std::string& command) {
  int status = std::system(command.c_str());
  if (status == -1) return -1;
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  if (WIFSIGNALED(status)) return 128 + WTERMSIG(status);
  return -1;
}

// Single-quotes a word for /bin/sh.
inline std::string quote(const std::string& s) {
  std::string r = "'";
  for (char c : s) r += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return r + "'";
}

}  // namespace trubal::test
