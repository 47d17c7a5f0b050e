// One mutant run by the real program (fuzz_decks.hpp): a scratch folder of its own as the working
// directory, so that whatever the deck writes lands there, and limits on time, memory and file size.
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstdlib>
#include <fstream>

#include <fmt/format.h>

#include "fuzz_decks.hpp"
#include "interp_support.hpp"
#include "paths.hpp"

namespace trubal::test::fuzz {

namespace {

const char kVictimName[] = "victim.txt";

// The last `most` bytes of a file (a run may print much more than a report can show).
std::string tail_of(const fs::path& p, std::size_t most) {
  std::ifstream f(p, std::ios::binary | std::ios::ate);
  if (!f) return "";
  const auto size = static_cast<std::size_t>(f.tellg());
  const std::size_t from = size > most ? size - most : 0;
  f.seekg(static_cast<std::streamoff>(from));
  std::string text(size - from, '\0');
  f.read(text.data(), static_cast<std::streamsize>(text.size()));
  return text;
}

void plant(const fs::path& dir, const SideFile& f) {
  const fs::path p = dir / f.name;
  switch (f.kind) {
    case SideFile::Kind::Text: {
      std::ofstream out(p, std::ios::binary | std::ios::trunc);
      out << f.text;
      break;
    }
    case SideFile::Kind::Fifo:
      if (::mkfifo(p.c_str(), 0666) != 0) throw std::runtime_error("mkfifo failed: " + p.string());
      break;
    case SideFile::Kind::Link:
      fs::create_symlink(f.text, p);
      break;
    case SideFile::Kind::Folder:
      fs::create_directory(p);
      break;
  }
}

// The limits as the shell applies them. Under AddressSanitizer `ulimit -v` cannot work (its shadow
// memory reserves terabytes of address space at start), so ASan's own limits stand in:
// hard_rss_limit_mb ends the process with a report when its resident memory passes the limit
// (checked by a background thread every 100 ms), max_allocation_size_mb refuses one allocation past
// it at once. Under ASan `new` never throws std::bad_alloc (an allocation that fails is a report),
// so such a run always fails; without ASan the allocation throws, and the program's own clean
// "out of memory" error (status 1) is an acceptable end. exitcode=86 keeps most of a sanitizer's
// ends apart from the program's status 1 (the RSS limit's is still 1): its report is what tells.
std::string limited(const Limits& limits) {
  std::string s = fmt::format("ulimit -c 0 && ulimit -f {} && ", static_cast<long>(limits.file_mb) * 1024);
#if defined(__SANITIZE_ADDRESS__)
  const char* given = std::getenv("ASAN_OPTIONS");
  s += "ASAN_OPTIONS=" +
       quote(fmt::format("hard_rss_limit_mb={0}:max_allocation_size_mb={0}:exitcode=86{1}{2}", limits.memory_mb,
                         given && *given ? ":" : "", given ? given : "")) +
       " ";
#else
  s = fmt::format("ulimit -v {} && {}", static_cast<long>(limits.memory_mb) * 1024, s);
#endif
  return s;
}

}  // namespace

Outcome run_mutant(const Mutant& m, const Limits& limits, const fs::path& keep) {
  TempDir dir;
  {
    std::ofstream deck(dir.path() / "deck.dat", std::ios::binary | std::ios::trunc);
    for (const auto& l : m.lines) deck << l << '\n';
  }
  std::string victim;
  for (const auto& f : m.files) {
    plant(dir.path(), f);
    if (f.name == kVictimName) victim = f.text;
  }
  const std::string command = "cd " + quote(dir.str()) + " && " + limited(limits) + "timeout -k 5 " +
                              std::to_string(limits.seconds) + " " + quote(TRUBAL_EXE) +
                              " deck.dat </dev/null >out.txt 2>&1";
  Outcome o;
  const auto start = std::chrono::steady_clock::now();
  o.status = shell(command);
  o.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  o.output = tail_of(dir.path() / "out.txt", std::size_t(1) << 20);
  if (!victim.empty()) {
    std::error_code ec;
    o.victim_changed = !fs::is_regular_file(fs::symlink_status(dir.path() / kVictimName, ec)) ||
                       slurp(dir.path() / kVictimName) != victim;
  }
  if (!keep.empty() && !finding(m, o).empty()) {
    std::error_code ec;
    fs::create_directories(keep.parent_path(), ec);
    fs::remove_all(keep, ec);
    fs::rename(dir.path(), keep, ec);   // left for whoever reproduces it; TempDir then finds nothing to remove
  }
  return o;
}

std::string finding(const Mutant& m, const Outcome& o) {
  const std::string& out = o.output;
  for (const char* mark : {"rss limit exhausted", "exceeds maximum supported size", "allocator is out of memory"})
    if (out.find(mark) != std::string::npos) return "past the memory limit";
  for (const char* mark : {"runtime error:", "AddressSanitizer", "LeakSanitizer", "ThreadSanitizer"})
    if (out.find(mark) != std::string::npos) return fmt::format("a sanitizer report ({})", mark);
  if (o.status == 124 || o.status == 137) return fmt::format("no end within {:.0f} s: a hang", o.seconds);
  if (o.status == 128 + SIGXFSZ) return "a file past the size limit (SIGXFSZ)";
  if (o.status > 128) return fmt::format("killed by signal {}", o.status - 128);
  if (o.status != 0 && o.status != 1) return fmt::format("exit status {}", o.status);
  // Status 1 says why: an error at a line, or the program's own last word (a log or the screen
  // that could not be written: "trubal: ...").
  if (o.status == 1 && out.find("error: ") == std::string::npos && out.find("trubal: ") == std::string::npos)
    return "status 1 without an error message";
  if (o.status == 0 && m.must_fail) return "status 0 where the deck must stop at an error";
  if (o.victim_changed) return "a file was written through a planted symbolic link";
  return "";
}

}  // namespace trubal::test::fuzz
