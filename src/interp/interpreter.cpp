#include "interp/interpreter.hpp"

#include <filesystem>
#include <fstream>
#include <stdexcept>

#include <fmt/format.h>

#include "interp/command.hpp"
#include "interp/lexer.hpp"

namespace trubal {

namespace fs = std::filesystem;

Interpreter::Interpreter(Session& session, Output& output) : session_(session), output_(output) {}

void Interpreter::set_variable(const std::string& name, const std::string& value) { variables_[to_lower(name)] = value; }

std::optional<std::string> Interpreter::variable(const std::string& name) const {
  auto it = variables_.find(to_lower(name));
  if (it == variables_.end()) return std::nullopt;
  return it->second;
}

// Messages quote the user's words and file names: escape what a terminal would act on.
static std::string safe(const std::string& message) { return printable(message, std::string::npos); }

void Interpreter::report(const std::string& raw_message) {
  const std::string message = safe(raw_message);
  auto& err = output_.err();
  output_.out().flush();
  if (frames_.empty()) {
    err << "error: " << message << '\n';
  } else {
    err << fmt::format("{}:{}: error: {}\n", frames_.back().name, frames_.back().line, message);
    for (auto f = frames_.rbegin() + 1; f != frames_.rend(); ++f)
      err << fmt::format("{}:{}: note: called from here\n", f->name, f->line);
  }
  err.flush();
}

void Interpreter::warn(const std::string& raw_message) {
  const std::string message = safe(raw_message);
  output_.out().flush();
  if (frames_.empty()) output_.err() << "warning: " << message << '\n';
  else output_.err() << fmt::format("{}:{}: warning: {}\n", frames_.back().name, frames_.back().line, message);
  output_.err().flush();
}

void Interpreter::execute(const std::string& line) {
  std::string expanded = expand_variables(line, [this](const std::string& n) { return variable(n); });
  auto words = split_words(expanded);
  if (words.empty()) return;
  const Command& command = find_command(words[0]);
  // Flushed before it runs: a long or hung command shows its own line.
  if (echo && !interactive) output_.out() << "trubal> " << printable(expanded, 400) << '\n' << std::flush;
  words.erase(words.begin());
  Args args(command.usage, std::move(words));
  Context ctx{session_, *this, output_.out()};
  command.run(ctx, args);
  output_.out().flush();
  const std::string log_failure = output_.take_log_failure();
  if (!log_failure.empty()) output_.err() << "warning: " << log_failure << '\n';
}

bool Interpreter::run_frames(std::istream& in, const std::string& name, const std::string& canonical) {
  frames_.push_back({name, canonical, 0});
  LineReader reader(in);
  try {
    while (!stop_) {
      std::optional<std::string> line;
      try {
        line = reader.next();
      } catch (const InputError&) {
        frames_.back().line = reader.line();
        throw;
      }
      if (!line) break;
      frames_.back().line = reader.line();
      execute(*line);
    }
  } catch (const ReportedError&) {
    frames_.pop_back();
    throw;
  } catch (const std::exception& e) {
    report(e.what());
    frames_.pop_back();
    throw ReportedError{};
  }
  frames_.pop_back();
  return true;
}

bool Interpreter::run_deck(std::istream& in, const std::string& name) {
  try {
    return run_frames(in, name, name);
  } catch (const ReportedError&) {
    return false;
  }
}

bool Interpreter::run_file(const std::string& path) {
  std::error_code dir_ec;
  if (fs::is_directory(path, dir_ec)) {   // an ifstream opens a directory and reads nothing: no silent success
    output_.err() << fmt::format("error: cannot open the deck '{}': it is a directory\n", path);
    return false;
  }
  std::ifstream in(path);
  if (!in) {
    output_.err() << fmt::format("error: cannot open the deck '{}'\n", path);
    return false;
  }
  std::error_code ec;
  auto canonical = fs::weakly_canonical(path, ec).string();
  try {
    return run_frames(in, path, canonical);
  } catch (const ReportedError&) {
    return false;
  }
}

bool Interpreter::run_interactive_line(const std::string& line, int line_no) {
  frames_.push_back({"<stdin>", "", line_no});
  try {
    execute(strip_comment(line));
  } catch (const ReportedError&) {
    frames_.pop_back();
    return false;
  } catch (const std::exception& e) {
    report(e.what());
    frames_.pop_back();
    return false;
  }
  frames_.pop_back();
  return true;
}

void Interpreter::call_file(const std::string& path) {
  // Relative names are looked up in the working directory, then beside the calling file.
  fs::path p(path);
  if (p.is_relative() && !fs::exists(p) && !frames_.empty() && !frames_.back().canonical.empty()) {
    fs::path beside = fs::path(frames_.back().canonical).parent_path() / p;
    if (fs::exists(beside)) p = beside;
  }
  // Each CALL nests the interpreter once more: a bounded depth, so a long chain of files is an error
  // rather than a stack overflow.
  constexpr std::size_t kMaxCallDepth = 100;
  if (frames_.size() >= kMaxCallDepth)
    throw InputError(fmt::format("CALL nested more than {} files deep (at '{}'): a chain of decks calling each other?",
                                 kMaxCallDepth, printable(path)));
  std::error_code ec;
  if (!fs::is_regular_file(p, ec)) throw InputError(fmt::format("cannot open the file '{}' to CALL", printable(path)));
  std::string canonical = fs::weakly_canonical(p, ec).string();
  for (const auto& f : frames_)
    if (f.canonical == canonical)
      throw InputError(fmt::format("'{}' calls itself (include cycle through {})", printable(path), f.name));
  std::ifstream in(p);
  if (!in) throw InputError(fmt::format("cannot read the file '{}'", printable(path)));
  run_frames(in, path, canonical);
}

}  // namespace trubal
