#include "interp/interpreter.hpp"
#include "session.hpp"

#include <charconv>
#include <cstdio>
#include <new>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <limits>
#include <sstream>
#include <stdexcept>

#include <fmt/format.h>

#include "interp/command.hpp"
#include "interp/lexer.hpp"
#include "interp/signals.hpp"
#include "support/comm.hpp"

namespace trubal {

namespace fs = std::filesystem;

Interpreter::Interpreter(Session& session, Output& output) : session_(session), output_(output) {}

namespace {

// A file as rank 0 read it: its text and canonical path, or what went wrong. In a distributed run
// only rank 0 touches the file system for input; the others get its answer (support/comm.hpp).
struct FileText {
  bool ok = false;
  std::string error, canonical, text;
};

FileText read_on_root(const std::function<FileText()>& read) {
  FileText f;
  if (comm::root()) f = read();
  if (comm::size() == 1 || rank_alone()) return f;
  // (A deck of a million BALL lines is 65 MB: one copy of its text at a time, not three.)
  std::string packed = f.ok ? "1" + f.canonical + '\0' : "0" + f.error;
  if (f.ok) {
    packed += f.text;
    std::string().swap(f.text);
  }
  comm::broadcast(packed);
  FileText out;
  out.ok = !packed.empty() && packed[0] == '1';
  if (!out.ok) {
    out.error = packed.substr(1);
    return out;
  }
  const std::size_t cut = packed.find('\0', 1);
  out.canonical = packed.substr(1, cut - 1);
  packed.erase(0, cut + 1);
  out.text = std::move(packed);
  return out;
}

// A deck's text, read to its end or to the first line longer than kMaxLineLength or holding a NUL
// byte (kept: the LineReader reports it at its line; the rest is never read, so a file of zeros does
// not fill the memory). Throws InputError when a read fails: never taken for the end of the file.
std::string read_all(std::istream& in, const std::string& what) {
  std::string text;
  std::size_t line_length = 0;
  std::vector<char> chunk(std::size_t{1} << 16);
  while (in) {
    in.read(chunk.data(), static_cast<std::streamsize>(chunk.size()));   // (a read error: badbit)
    const auto got = static_cast<std::size_t>(in.gcount());
    for (std::size_t k = 0; k < got; ++k) {
      if (chunk[k] == '\n') {
        line_length = 0;
      } else if (chunk[k] == '\0' || ++line_length > kMaxLineLength) {
        text.append(chunk.data(), k + 1);
        return text;
      }
    }
    text.append(chunk.data(), got);
  }
  if (in.bad()) throw InputError(fmt::format("cannot read {}: a read error", what));
  return text;
}

// A stream over a text held elsewhere, read in place: a million-line deck is not copied again into
// an istringstream beside the text it was read into.
class TextStream : public std::istream {
 public:
  explicit TextStream(const std::string& text) : std::istream(&buf_), buf_(text) {}

 private:
  struct Buf : std::streambuf {
    explicit Buf(const std::string& text) {
      char* p = const_cast<char*>(text.data());   // (read only: a get area is never written)
      setg(p, p, p + text.size());
    }
  } buf_;
};

// A deck under mpirun, handed by rank 0 to the others in pieces as the interpreter reads it (a
// million BALL lines are 65 MB, which no rank then holds whole). Every rank reads the same lines at
// the same points, so each piece is a collective call; `before` runs first on every rank (the lines
// agreed lazily before it are agreed on there: a rank that failed at one waits in that agreement,
// not in this call). A failed read on rank 0 is every rank's InputError.
class RootPieces : public std::streambuf {
 public:
  RootPieces(std::istream* file, std::string what, std::function<void()> before)
      : file_(file), what_(std::move(what)), before_(std::move(before)) {}

 protected:
  int_type underflow() override {
    if (gptr() < egptr()) return traits_type::to_int_type(*gptr());
    before_();
    constexpr std::size_t kPiece = std::size_t{1} << 20;
    std::string piece;
    if (comm::root()) {
      piece.resize(kPiece + 1);
      piece[0] = 'D';
      file_->read(piece.data() + 1, static_cast<std::streamsize>(kPiece));
      piece.resize(1 + static_cast<std::size_t>(file_->gcount()));
      if (file_->bad()) piece = fmt::format("Ecannot read {}: a read error", what_);
    }
    comm::broadcast(piece);
    if (piece.empty() || piece[0] == 'E') throw InputError(piece.empty() ? "cannot read " + what_ : piece.substr(1));
    piece.erase(0, 1);
    held_ = std::move(piece);
    if (held_.empty()) return traits_type::eof();
    setg(held_.data(), held_.data(), held_.data() + held_.size());
    return traits_type::to_int_type(*gptr());
  }

 private:
  std::istream* file_;   // rank 0's (the others': none)
  std::string what_;
  std::function<void()> before_;
  std::string held_;
};

}  // namespace

std::optional<std::string> Interpreter::read_file_on_root(const std::string& path) {
  FileText file = read_on_root([&] {
    FileText f;
    // A regular file only (through a link): opening a FIFO waits for a writer for ever.
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) return f;
    std::ifstream in(path);
    f.ok = static_cast<bool>(in);
    try {
      if (f.ok) f.text = read_all(in, fmt::format("'{}'", printable(path)));
    } catch (const InputError&) {   // (on rank 0 alone: the others learn it from its answer)
      f.ok = false;
    }
    return f;
  });
  if (!file.ok) return std::nullopt;
  return std::move(file.text);
}

std::string Interpreter::read_stream_on_root(std::istream& in) {
  FileText file = read_on_root([&] {
    FileText f;
    try {
      f.text = read_all(in, "the standard input");
      f.ok = true;
    } catch (const InputError& e) {
      f.error = e.what();
    }
    return f;
  });
  if (!file.ok) throw InputError(file.error);   // on every rank alike
  return std::move(file.text);
}

void Interpreter::set_variable(const std::string& name, const std::string& value) { variables_[to_lower(name)] = value; }

std::optional<std::string> Interpreter::variable(const std::string& name) const {
  auto it = variables_.find(to_lower(name));
  if (it == variables_.end()) return std::nullopt;
  return it->second;
}

// Messages quote the user's words and file names: escape what a terminal would act on.
static std::string safe(const std::string& message) { return printable(message, std::string::npos); }

void Interpreter::report(const std::string& raw_message, const LocatedError* at) {
  const std::string message = safe(raw_message);
  // Another rank's place in the deck (this one's CALLs may not be its), or this rank's.
  last_error_ = at ? Error{at->file, at->line, message} : Error{here_file(), here_line(), message};
  if (!report_errors) return;
  auto& err = output_.err();
  output_.out().flush();
  if (at ? at->file.empty() : frames_.empty()) {
    err << "error: " << message << '\n';
  } else {
    err << fmt::format("{}:{}: error: {}\n", last_error_.file, last_error_.line, message);
    if (!at)
      for (auto f = frames_.rbegin() + 1; f != frames_.rend(); ++f)
        err << fmt::format("{}:{}: note: called from here\n", f->name, f->line);
  }
  err.flush();
}

void Interpreter::report_out_of_memory() {
  // Said with a fixed text and what is already allocated: formatting the usual message could itself
  // fail (a model that fills the memory leaves nothing to report with). FILE:LINE as report's.
  static constexpr char kText[] = ": error: out of memory: the system refused more memory for this command (the "
                                  "model is as the command left it)\n";
  try {
    last_error_ = Error{here_file(), here_line(), "out of memory"};
  } catch (...) {
  }
  if (!report_errors) return;
  try {
    output_.out().flush();
    char line[24];
    const auto [end, ec] = std::to_chars(line, line + sizeof line, here_line());
    auto& err = output_.err();
    if (!frames_.empty()) err << frames_.back().name << ':' << std::string_view(line, static_cast<std::size_t>(end - line));
    else err << "trubal";
    err << kText << std::flush;
  } catch (...) {
    std::fputs(kText + 2, stderr);
  }
}

void Interpreter::warn(const std::string& raw_message) {
  const std::string message = safe(raw_message);
  show_held_echo(std::numeric_limits<std::int64_t>::max());   // (the lines before it, as they ran here)
  output_.out().flush();
  if (frames_.empty()) output_.err() << "warning: " << message << '\n';
  else output_.err() << fmt::format("{}:{}: warning: {}\n", frames_.back().name, frames_.back().line, message);
  output_.err().flush();
}

void Interpreter::execute(const std::string& line) {
  std::string expanded;
  std::vector<std::string> words;
  const Command* found = nullptr;
  try {
    expanded = expand_variables(line, [this](const std::string& n) { return variable(n); });
    words = split_words(expanded);
    if (words.empty()) return;
    found = &find_command(words[0]);
  } catch (...) {   // (every rank fails here alike; one that failed before this line is the one to report)
    if (comm::size() > 1) settle_agreement();
    throw;
  }
  const Command& command = *found;
  ++commands_run_;
  // Flushed before it runs: a long or hung command shows its own line (a quick one's waits for the
  // next command that is not, or for an error: Command::quick).
  const bool flush = interactive || !command.quick;
  // A batch deck's BALL lines are held on the ranks, not built into rank 0's model (Session::hold_balls).
  session_.set_hold_balls(comm::size() > 1 && agree_lazily && !interactive);
  const OnRanks on_ranks = command.ranks_for ? command.ranks_for(Args(command.usage, std::vector<std::string>(words.begin() + 1, words.end())),
                                                                 session_.parts_kept())
                                             : command.on_ranks;
  const HeldUse held = command.keeps_held_after.empty() && command.places_held_after.empty()
                           ? command.held
                           : held_use(command, Args(command.usage, std::vector<std::string>(words.begin() + 1, words.end())));
  // Before the command, a collective call: the held balls placed in the model, or the first held
  // BALL's start (Session::hold_start).
  const bool held_call = ((held == HeldUse::Place || held == HeldUse::Split) && session_.held_balls() > 0) ||
                         (held == HeldUse::Add && session_.hold_balls() && session_.hold_needs_start());
  // (Not where the ranks' parts are kept: the whole model is handed over first, a collective call.)
  // (Nor where the echo held for the agreement has grown to 64 KiB: each agreement shows it.)
  const bool lazily = comm::size() > 1 && agree_lazily && command.quick && !interactive && !session_.parts_kept() &&
                      !held_call && held_echo_.size() < (std::size_t{1} << 16);
  // The quick commands before it agreed on first (it may make collective calls), before its echo:
  // a deck that failed earlier on another rank does not show this command as run.
  if (comm::size() > 1 && !lazily) settle_agreement();
  if (echo && !interactive) {
    if (lazily) {
      // (Held until the ranks agree: a line after one that failed on another rank is not shown.)
      held_echo_ += fmt::format("trubal> {}\n", printable(expanded, 400));
      held_echo_ends_.emplace_back(commands_run_, held_echo_.size());
    } else {
      output_.out() << "trubal> " << printable(expanded, 400) << '\n';
      if (flush) output_.out() << std::flush;
    }
  }
  words.erase(words.begin());
  if (command.raw_text) {   // (split_words has checked the quotes; the text is the line's, as typed)
    std::string text = text_after_keyword(expanded);
    words.clear();
    if (!text.empty()) words.push_back(std::move(text));
  }
  Args args(command.usage, std::move(words));
  // (A command run lazily prints after its held echo: keep_lazy_output.)
  Context ctx{session_, *this, lazily ? static_cast<std::ostream&>(lazy_out_) : output_.out()};
  if (comm::size() == 1) command.run(ctx, args);
  else run_agreed(command, ctx, args, lazily, held, on_ranks);
  // Ctrl-C during a command that does not look for it (RESTART, SAVE): a batch deck stops after it,
  // as at a CYCLE (exit 1), rather than the next CYCLE clearing the request. Under mpirun the ranks
  // agree (a collective call: after the commands every rank runs in step, the ones that are not quick).
  if (!interactive && (comm::size() == 1 ? interrupt_requested().load() : !lazily && interrupt_now())) {
    interrupt_requested() = false;
    throw InputError(fmt::format("interrupted by {} (during {})",
                                 comm::size() > 1 ? "a signal (Ctrl-C at mpirun, or SIGUSR1)" : "Ctrl-C", command.name));
  }
  if (flush) output_.out().flush();
  const std::string log_failure = output_.take_log_failure();   // (with a log on, it flushes)
  if (!log_failure.empty()) output_.err() << "warning: " << log_failure << '\n';
}

// A failure's message travels with the failing rank's FILE:LINE: "line length file message".
static std::string with_location(const std::string& file, int line, const std::string& message) {
  return fmt::format("{} {} {}{}", line, file.size(), file, message);
}

void Interpreter::run_agreed(const Command& command, Context& ctx, Args& args, bool lazily, HeldUse held, OnRanks on_ranks) {
  // Every rank runs the command; they agree whether it failed, so that they stay in step (a file
  // only rank 0 writes may fail there alone). The first failing rank's message is everyone's.
  bool failed = false, reported = false;
  std::string message;
  try {
    if (fail_line_for_test > 0 && !frames_.empty() && frames_.back().line == fail_line_for_test)
      throw std::runtime_error(fmt::format("rank {} fails here for a test (TRUBAL_TEST_FAIL_AT)", comm::rank()));
    // GEN: held where the model holds no ball (rank 0's word, every rank's), else placed first.
    if (held == HeldUse::Generate) held = session_.generates_held() ? HeldUse::Add : HeldUse::Place;
    // DELETE: on every rank's held balls where the model holds no other (rank 0's word), else
    // placed first.
    bool on_held = false;
    if (held == HeldUse::Delete) {
      on_held = session_.deletes_held();
      held = on_held ? HeldUse::Keep : HeldUse::Place;
    }
    // The balls of BALL lines held on the ranks, placed in the model where the command reads them
    // (Command::held); or the start of holding them.
    const bool hold = held == HeldUse::Add && session_.hold_balls();
    if (held == HeldUse::Place) session_.place_held();
    else if (held == HeldUse::Split) session_.place_held_as_parts();
    else if (hold && session_.hold_needs_start()) session_.hold_start();
    // What the command needs of the model (Command::on_ranks, ranks_for): the same on every rank.
    if (on_ranks != OnRanks::ModelOnZero) session_.light_everywhere();
    switch (on_ranks) {
      case OnRanks::Whole:
        session_.whole_everywhere();
        command.run(ctx, args);
        break;
      case OnRanks::RankZero:
        session_.gather_rank_figures();
        session_.run_on_root([&] {
          RankAlone alone;
          command.run(ctx, args);
        });
        break;
      case OnRanks::Parts:
        command.run(ctx, args);
        break;
      case OnRanks::ModelOnZero:
        if (on_held) {   // (every rank, in step: a collective call)
          command.run(ctx, args);
          break;
        }
        if (hold && command.held == HeldUse::Generate) {
          // Rank 0 generates the balls alone, then hands them out to be held (a collective call:
          // what it made before a failure too, as serial's GEN keeps what it placed).
          std::exception_ptr failure;
          if (comm::root()) {
            RankAlone alone;
            try {
              command.run(ctx, args);
            } catch (...) {
              failure = std::current_exception();
            }
          }
          session_.hand_out_generated();
          if (failure) std::rethrow_exception(failure);
          break;
        }
        if (hold) {   // (every rank: each checks its part of the rules, one keeps the ball)
          RankAlone alone;
          command.run(ctx, args);
          break;
        }
        // (Quick, agreed lazily: rank 0 alone may fail, and waits in the agreement for the others,
        // which go on to the next command that is not quick, or the deck's end, and agree there.)
        session_.model_on_zero();
        if (comm::root()) {
          RankAlone alone;
          command.run(ctx, args);
        }
        break;
    }
  } catch (const ReportedError&) {
    failed = reported = true;
  } catch (const std::exception& e) {
    failed = true;
    message = e.what();
  }
  session_.end_held_command();
  if (lazily) keep_lazy_output();
  if (!failed && lazily) {
    agreement_pending_ = true;
    return;
  }
  agreement_pending_ = false;
  if (failed && !reported)
    message = with_location(here_file(), here_line(), message);
  agree(failed, message);
}

void Interpreter::agree(bool failed, std::string& message) {
  std::int64_t failed_at = -1;
  const bool any = comm::first_failure(failed, message, commands_run_, &failed_at) >= 0;
  show_held_echo(any ? failed_at : std::numeric_limits<std::int64_t>::max());
  if (any) throw_agreed(std::move(message));
}

void Interpreter::keep_lazy_output() {
  std::string text = lazy_out_.str();
  if (text.empty()) return;
  lazy_out_.str("");
  held_echo_ += text;
  held_echo_ends_.emplace_back(commands_run_, held_echo_.size());
}

void Interpreter::show_held_echo(std::int64_t through) {
  if (held_echo_ends_.empty()) return;
  std::size_t end = 0;
  for (const auto& [order, at] : held_echo_ends_)
    if (order <= through) end = at;
  output_.out().write(held_echo_.data(), static_cast<std::streamsize>(end));
  held_echo_.clear();
  held_echo_ends_.clear();
}

void Interpreter::settle_agreement() {
  if (!std::exchange(agreement_pending_, false)) return;
  std::string message;
  agree(false, message);
}

void Interpreter::throw_agreed(std::string message) {
  if (message.empty()) throw ReportedError{};   // reported where it happened
  int line = 0;
  std::size_t length = 0;
  const char* const end = message.data() + message.size();
  auto [p, e1] = std::from_chars(message.data(), end, line);
  if (e1 != std::errc{} || p == end || *p != ' ') throw std::runtime_error(message);
  auto [q, e2] = std::from_chars(p + 1, end, length);
  if (e2 != std::errc{} || q == end || *q != ' ' || static_cast<std::size_t>(end - q - 1) < length)
    throw std::runtime_error(message);
  std::string file(q + 1, length);
  std::string text(q + 1 + length, end);
  // Where this rank is at that line too, its own report says it (with the CALLs that led there).
  if (!frames_.empty() && frames_.back().name == file && frames_.back().line == line) throw std::runtime_error(text);
  throw LocatedError(std::move(file), line, std::move(text));
}

bool Interpreter::run_frames(std::istream& in, const std::string& name, const std::string& canonical,
                             int first_line) {
  frames_.push_back({name, canonical, 0});
  const int offset = first_line - 1;
  LineReader reader(in);
  try {
    while (!stop_) {
      std::optional<std::string> line;
      try {
        line = reader.next();
      } catch (const InputError&) {
        frames_.back().line = reader.line() + offset;
        settle_agreement();   // a rank that failed before this line is the one to report
        throw;
      }
      if (!line) break;
      frames_.back().line = reader.line() + offset;
      execute(*line);
    }
    if (frames_.size() == 1) settle_agreement();   // the deck's end: its last quick commands
  } catch (const ReportedError&) {
    frames_.pop_back();
    throw;
  } catch (const LocatedError& e) {
    report(e.what(), &e);
    frames_.pop_back();
    throw ReportedError{};
  } catch (const std::bad_alloc&) {
    report_out_of_memory();
    frames_.pop_back();
    throw ReportedError{};
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

bool Interpreter::run_text(const std::string& text, const std::string& name, const std::string& canonical,
                           int first_line) {
  TextStream in(text);
  try {
    return run_frames(in, name, canonical, first_line);
  } catch (const ReportedError&) {
    return false;
  }
}

bool Interpreter::run_file(const std::string& path) {
  // Each process reads its deck as it runs it (a million BALL lines are 65 MB): under mpirun rank 0
  // reads it and hands it to the others in pieces (RootPieces).
  std::ifstream streamed;
  const FileText file = read_on_root([&] {
    FileText f;
    std::error_code dir_ec;
    if (fs::is_directory(path, dir_ec)) {   // an ifstream opens a directory and reads nothing: no silent success
      f.error = fmt::format("cannot open the deck '{}': it is a directory", path);
      return f;
    }
    std::ifstream in(path);
    if (!in) {
      f.error = fmt::format("cannot open the deck '{}'", path);
      return f;
    }
    std::error_code ec;
    f.canonical = fs::weakly_canonical(path, ec).string();
    streamed = std::move(in);
    f.ok = true;
    return f;
  });
  if (!file.ok) {
    last_error_ = {std::string(), 0, file.error};
    if (report_errors) output_.err() << "error: " << file.error << '\n';
    return false;
  }
  RootPieces pieces(comm::root() ? &streamed : nullptr, fmt::format("the deck '{}'", path), [this] { settle_agreement(); });
  std::istream handed(&pieces);
  handed.exceptions(std::ios::badbit);   // (what the pieces throw reaches run_frames as thrown)
  std::istream& in = comm::size() == 1 ? static_cast<std::istream&>(streamed) : handed;
  try {
    return run_frames(in, path, file.canonical);
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
  } catch (const std::bad_alloc&) {
    report_out_of_memory();
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
  // Each CALL nests the interpreter once more: a bounded depth, so a long chain of files is an error
  // rather than a stack overflow.
  constexpr std::size_t kMaxCallDepth = 100;
  if (frames_.size() >= kMaxCallDepth)
    throw InputError(fmt::format("CALL nested more than {} files deep (at '{}'): a chain of decks calling each other?",
                                 kMaxCallDepth, printable(path)));
  const std::string caller = frames_.empty() ? std::string() : frames_.back().canonical;
  const FileText file = read_on_root([&] {
    FileText f;
    // Relative names are looked up in the working directory, then beside the calling file.
    fs::path p(path);
    std::error_code ec;
    std::vector<fs::path> tried{fs::absolute(p, ec)};
    if (p.is_relative() && !fs::exists(p) && !caller.empty()) {
      fs::path beside = fs::path(caller).parent_path() / p;
      if (beside.is_absolute() && tried.back() != beside) tried.push_back(beside);
      if (fs::exists(beside)) p = beside;
    }
    if (!fs::is_regular_file(p, ec)) {
      std::string where;
      for (const auto& t : tried) where += (where.empty() ? "" : " and ") + printable(t.string(), 400);
      f.error = fmt::format("cannot open the file '{}' to CALL: {} {} (the current folder is {})", printable(path),
                            fs::is_directory(p, ec) ? "it is a directory:" : "looked for", where,
                            printable(fs::current_path(ec).string(), 400));
      return f;
    }
    f.canonical = fs::weakly_canonical(p, ec).string();
    std::ifstream in(p);
    if (!in) {
      f.error = fmt::format("cannot read the file '{}'", printable(path));
      return f;
    }
    try {
      f.text = read_all(in, fmt::format("the file '{}' to CALL", printable(path)));
    } catch (const InputError& e) {
      f.error = e.what();
      return f;
    }
    f.ok = true;
    return f;
  });
  if (!file.ok) throw InputError(file.error);
  for (const auto& f : frames_)
    if (f.canonical == file.canonical)
      throw InputError(fmt::format("'{}' calls itself (include cycle through {})", printable(path), f.name));
  TextStream in(file.text);
  run_frames(in, path, file.canonical);
}

}  // namespace trubal
