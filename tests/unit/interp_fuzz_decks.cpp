// The deck fuzzer: the decks of tests/fuzz/corpus/, mutated (words
// dropped, swapped, duplicated; numbers replaced by 0, -1, 1e308, 1e-320, nan, inf, huge integers;
// binary bytes; unterminated quotes and continuations; lines dropped, doubled, or nonsense put in),
// run by the real program in a scratch folder. Any signal, sanitizer report, hang past the timeout
// or exit status other than 0 and 1 fails; so does exit 0 on a deck given a nonsense line. The
// decks of tests/fuzz/regressions/ (one per finding of the audit) must fail cleanly with the
// message their first line names.
//
// TRUBAL_FUZZ_DECKS sets how many mutants (default 40; CI's sanitizer build runs more),
// TRUBAL_FUZZ_SEED the seed (default 1). A failing mutant is printed whole: save it as a
// regression deck.
#include "paths.hpp"
#include <catch2/catch.hpp>

#include <cstdlib>
#include <random>
#include <set>

#include <fmt/format.h>

#include "interp_support.hpp"

using namespace trubal::test;

namespace {

const fs::path kFuzzDir = fs::path(TRUBAL_TEST_DIR) / "fuzz";

std::vector<fs::path> decks_in(const fs::path& dir) {
  std::vector<fs::path> out;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().extension() == ".dat") out.push_back(e.path());
  std::sort(out.begin(), out.end());
  return out;
}

bool is_number(const std::string& w) {
  char* end = nullptr;
  std::strtod(w.c_str(), &end);
  return !w.empty() && end && *end == '\0';
}

std::vector<std::string> words_of(const std::string& line) {
  std::vector<std::string> out;
  std::istringstream in(line);
  for (std::string w; in >> w;) out.push_back(w);
  return out;
}

std::string join(const std::vector<std::string>& words) {
  std::string s;
  for (const auto& w : words) s += (s.empty() ? "" : " ") + w;
  return s;
}

// The first word of a command line, lower case ("" for comments and blanks).
std::string keyword(const std::string& line) {
  const auto w = words_of(line);
  if (w.empty() || w[0][0] == '*' || w[0][0] == ';') return "";
  std::string k = w[0];
  for (char& c : k) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return k;
}

class Mutator {
 public:
  explicit Mutator(std::uint64_t seed) : rng_(seed) {}

  // One or two mutations of the deck. `nonsense` is set when one of them made a line no
  // command can be (the run must then fail).
  std::vector<std::string> mutate(std::vector<std::string> lines, bool& nonsense) {
    nonsense = false;
    const std::size_t count = 1 + below(2);
    for (std::size_t m = 0; m < count && !lines.empty(); ++m) {
      const std::size_t at = below(lines.size());
      std::string& line = lines[at];
      auto words = words_of(line);
      const std::string key = keyword(line);
      // A CYCLE's count stays: a longer run is a legal run, not a finding.
      const bool counted = key.rfind("cyc", 0) == 0 || key.rfind("sol", 0) == 0;
      switch (below(10)) {
        case 0:   // drop a word
          if (!words.empty()) { words.erase(words.begin() + below(words.size())); line = join(words); }
          break;
        case 1:   // swap two words
          if (words.size() > 1) { std::swap(words[below(words.size())], words[below(words.size())]); line = join(words); }
          break;
        case 2:   // duplicate a word
          if (!words.empty()) { words.insert(words.begin() + below(words.size()), words[below(words.size())]); line = join(words); }
          break;
        case 3: case 4: case 5: {   // a number replaced by a hard one
          static const char* hard[] = {"0", "-1", "1e308", "-1e308", "1e-320", "nan", "inf", "-inf",
                                       "99999999999999999999", "-9223372036854775808", "1e999", "0x10", "1d400"};
          std::vector<std::size_t> numbers;
          for (std::size_t k = counted ? 2 : 1; k < words.size(); ++k)
            if (is_number(words[k])) numbers.push_back(k);
          if (!numbers.empty()) { words[numbers[below(numbers.size())]] = hard[below(std::size(hard))]; line = join(words); }
          break;
        }
        case 6: {   // binary bytes in a line
          std::string junk;
          for (std::size_t k = 0, n = 1 + below(12); k < n; ++k) {
            char c = static_cast<char>(below(256));
            if (c != '\n') junk.push_back(c);
          }
          line.insert(below(line.size() + 1), junk);
          break;
        }
        case 7:   // an unterminated quote, or a continuation with nothing after it
          if (below(2)) line += " \"open";
          else if (at + 1 == lines.size()) line += " &";
          else line.insert(below(line.size() + 1), "'");
          break;
        case 8:   // a line dropped or doubled
          if (below(2)) lines.erase(lines.begin() + at);
          else lines.insert(lines.begin() + at, line);
          break;
        case 9:   // a nonsense command
          lines.insert(lines.begin() + at, "qzxv" + std::to_string(below(1000)) + " 1 2");
          nonsense = true;
          break;
      }
    }
    return lines;
  }

 private:
  std::size_t below(std::size_t n) { return static_cast<std::size_t>(rng_() % n); }
  std::mt19937_64 rng_;
};

struct Run {
  int status = 0;
  std::string output;
};

// The deck run by the program in a scratch folder of its own, under a timeout; the exit status
// (124 timed out, 128 + n a signal) and what it printed.
Run run_deck(const std::vector<std::string>& lines, int seconds) {
  TempDir dir;
  std::string text;
  for (const auto& l : lines) text += l + "\n";
  dir.write("deck.dat", text);
  const std::string command = "cd " + quote(dir.str()) + " && timeout -k 5 " + std::to_string(seconds) + " " +
                              quote(TRUBAL_EXE) + " deck.dat </dev/null >out.txt 2>&1";
  Run r;
  r.status = shell(command);
  r.output = slurp(dir.path() / "out.txt");
  return r;
}

std::vector<std::string> read_lines(const fs::path& p) { return lines_of(slurp(p)); }

// A line as the test report shows it: bytes a terminal would act on as \xNN.
std::string visible(const std::string& line) {
  std::string out;
  for (unsigned char c : line) {
    if (c >= 32 && c < 127) out.push_back(static_cast<char>(c));
    else out += fmt::format("\\x{:02x}", c);
  }
  return out;
}

std::string sanitizer_report(const std::string& out) {
  for (const char* mark : {"runtime error:", "AddressSanitizer", "LeakSanitizer", "ThreadSanitizer"})
    if (out.find(mark) != std::string::npos) return mark;
  return "";
}

}  // namespace

TEST_CASE("fuzz: mutated decks of the corpus fail cleanly or run, never crash or hang", "[hard][fuzz][system]") {
  const auto corpus = decks_in(kFuzzDir / "corpus");
  REQUIRE(corpus.size() >= 5);
  const char* count_env = std::getenv("TRUBAL_FUZZ_DECKS");
  const char* seed_env = std::getenv("TRUBAL_FUZZ_SEED");
  const int count = count_env ? std::atoi(count_env) : 40;
  Mutator mutator(seed_env ? std::strtoull(seed_env, nullptr, 10) : 1);
  int failed_cleanly = 0, ran = 0;
  for (int k = 0; k < count; ++k) {
    const fs::path& deck = corpus[static_cast<std::size_t>(k) % corpus.size()];
    bool nonsense = false;
    const auto mutant = mutator.mutate(read_lines(deck), nonsense);
    const Run r = run_deck(mutant, 60);
    std::string text;
    for (const auto& l : mutant) text += visible(l) + "\n";
    INFO("mutant " << k << " of " << deck.filename().string() << ":\n" << text << "--- output (end):\n"
                   << r.output.substr(r.output.size() > 3000 ? r.output.size() - 3000 : 0));
    CHECK(sanitizer_report(r.output) == "");
    CHECK((r.status == 0 || r.status == 1));   // not a timeout (124), a signal, or another code
    if (nonsense) CHECK(r.status == 1);         // a line no command can be is an error
    if (r.status == 1) {
      CHECK_THAT(r.output, Catch::Contains(": error: ") || Catch::Contains("error: "));
      ++failed_cleanly;
    } else {
      ++ran;
    }
  }
  WARN(count << " mutants: " << failed_cleanly << " stopped at an error, " << ran << " ran to the end");
}

TEST_CASE("fuzz: every regression deck fails with the error its first line names", "[hard][fuzz][system]") {
  const auto decks = decks_in(kFuzzDir / "regressions");
  REQUIRE(decks.size() >= 10);
  for (const auto& deck : decks) {
    const auto lines = read_lines(deck);
    REQUIRE_FALSE(lines.empty());
    const std::string prefix = "* expect: ";
    REQUIRE(lines[0].rfind(prefix, 0) == 0);
    const std::string expected = lines[0].substr(prefix.size());
    const Run r = run_deck(lines, 60);
    INFO(deck.filename().string() << ":\n" << r.output);
    CHECK(r.status == 1);
    CHECK_THAT(r.output, Catch::Contains(expected));
    CHECK(sanitizer_report(r.output) == "");
  }
}
