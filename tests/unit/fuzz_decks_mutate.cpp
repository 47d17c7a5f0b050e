// The deck fuzzer's seeds and mutations (fuzz_decks.hpp). Every choice is drawn from one generator
// seeded by the run's seed and the mutant's index, so a failing mutant is made again alone.
#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <initializer_list>
#include <random>
#include <sstream>

#include <fmt/format.h>

#include "fuzz_decks.hpp"
#include "interp/lexer.hpp"
#include "paths.hpp"

namespace trubal::test::fuzz {

namespace {

// The longest line a deck may hold: the huge lines and variable bombs aim at both sides of it.
constexpr std::size_t kMaxLine = kMaxLineLength;

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

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

bool is_number(const std::string& w) {
  char* end = nullptr;
  std::strtod(w.c_str(), &end);
  return !w.empty() && end && *end == '\0';
}

// The first word of a command line, lower case ("" for comments and blanks).
std::string keyword(const std::string& line) {
  const auto w = words_of(line);
  if (w.empty() || w[0][0] == '*' || w[0][0] == ';') return "";
  return lower(w[0]);
}

// Whether a keyword (as typed, perhaps abbreviated) is one of the commands named by their first
// three letters.
bool is_one_of(const std::string& key, std::initializer_list<const char*> prefixes) {
  for (const char* p : prefixes)
    if (key.size() >= 3 && key.compare(0, 3, p) == 0) return true;
  return false;
}

// Commands that end a deck with status 0: a line after one of them is never read.
bool ends_deck(const std::string& key) { return key == "stop" || key == "quit" || key == "end" || key == "exit"; }

const char* const kHardNumbers[] = {"0", "-1", "1e308", "-1e308", "1e-320", "nan", "inf", "-inf",
                                    "99999999999999999999", "-9223372036854775808", "1e999", "0x10", "1d400"};

// What SERVO, GEN, STRAIN, START, PROP and their neighbours are given at the edges of the doubles
// and of the integers.
const char* const kExtremes[] = {"1e308", "-1e308", "1.7976931348623157e308", "4.9e-324", "-4.9e-324", "1e-308",
                                 "0", "-0", "nan", "-nan", "inf", "-inf", "1e300", "1e15", "1e9", "4294967297",
                                 "9223372036854775807", "9223372036854775808", "-9223372036854775808",
                                 "18446744073709551616", "-1", "-1e9", "1e19", "1e-30", "2147483648"};

// '#' is an argument: an extreme, or now and then an ordinary value; '!' an extreme always. GEN
// porosity's radii and LATTICE's counts are '!': ordinary ones in a large START box ask for
// millions of balls, a legal run far past a mutant's time and memory.
const char* const kExtremeTemplates[] = {
    "servo # # #", "servo # # # gain # max #", "servo xx # yy # zz # gain # max #", "servo xx # gain #",
    "servo zz # max #", "servo wall 1 stress # gain # max # area #", "servo wall 2 stress # max #",
    "servo wall # stress # in #", "servo wall 3 stress # between 1 2 max #", "gen # # #", "gen # # # seed #",
    "gen # # # type #", "gen # 0.0004 0.0006 seed 7", "gen 20 # #", "gen porosity # psd uniform ! !",
    "gen porosity 0.4 psd normal ! ! cut ! !", "gen # # # range sphere # # # #", "strain # # #",
    "strain # # # # # #", "strain xx #", "strain xy #", "strain zz # xy #", "start # # #", "start # # # # # #",
    "start box # # # # # #", "start box -1 1 -1 1 # #", "prop kn # ks # dens #", "prop kn # ks # fric # dens #",
    "prop type # kn # dens #", "prop shear # poisson # dens # rest #", "prop coh # mu #", "prop dens #",
    "lattice fcc # ! ! !", "ball # # # #", "ball 0 0 0 # id #", "wall plane # # # # # #",
    "wall id 9 cylinder 0 0 0 0 0 1 radius # length #", "tstep #", "frac #", "grav # # #", "damp local #",
    "damp # #", "damp mass # stiff #", "membrane # follow every #", "init xvel # yspin #", "apply zforce #",
    "hist stress every # file x.csv", "set progress #", "set volume #", "backend threaded threads #",
    "backend serial maxmem #", "dump vtk v every #", "sample platens # # cylinder #"};
const char* const kOrdinary[] = {"1", "2", "0.5", "1e-3", "1e4", "100", "3"};

// Lines that read or write a file named p.*, for a deck that names none where a FIFO or a link can
// be planted.
const char* const kFileLines[] = {"save p.sav", "restart p.sav", "set log p.log", "hist stress every 1 file p.csv",
                                  "print balls file p.csv", "print contacts file p.csv", "print walls file p.csv",
                                  "print counters file p.csv", "dump vtk p", "call p.dat",
                                  "plot s11 vs time from p.csv file q.png", "gen porosity 0.4 psd sieve file p.txt"};

// The files a line names (to read or to write), found by the command's own words.
std::vector<std::string> files_named(const std::string& line) {
  const auto w = words_of(line);
  const std::string key = keyword(line);
  std::vector<std::string> out;
  if (key.empty()) return out;
  for (std::size_t k = 1; k + 1 < w.size(); ++k) {
    const std::string word = lower(w[k]);
    if (word == "file") out.push_back(w[k + 1]);
    if (word == "from" && is_one_of(key, {"plo"}))
      for (std::size_t j = k + 1; j < w.size() && w[j].find('.') != std::string::npos; ++j) out.push_back(w[j]);
    if (word == "vtk" && is_one_of(key, {"dum"})) out.push_back(w[k + 1]);
    if (word == "log" && k == 1 && is_one_of(key, {"set"}) && lower(w[2]) != "off") out.push_back(w[2]);
  }
  if (w.size() > 1 && is_one_of(key, {"sav", "res", "cal", "inc"})) out.push_back(w[1]);
  // Only a plain name in the scratch folder: no variable, no folder, nothing outside.
  std::erase_if(out, [](const std::string& n) {
    return n.empty() || n.find_first_of("$/\\\"'") != std::string::npos || n == "." || n == "..";
  });
  return out;
}

class Mutator {
 public:
  Mutator(std::uint64_t fuzz_seed, std::uint64_t index) {
    std::seed_seq seq{static_cast<std::uint32_t>(fuzz_seed), static_cast<std::uint32_t>(fuzz_seed >> 32),
                      static_cast<std::uint32_t>(index), static_cast<std::uint32_t>(index >> 32)};
    rng_.seed(seq);
  }

  void mutate(Mutant& m) {
    for (std::size_t count = 1 + below(3), k = 0; k < count; ++k) {
      if (m.lines.empty()) m.lines.push_back("");
      switch (below(11)) {
        case 0: case 1: case 2: line_mutation(m); break;
        case 3: case 4: extreme_arguments(m); break;
        case 5: case 6: planted_file(m); break;
        case 7: variable_bomb(m); break;
        case 8: huge_line(m); break;
        case 9: duplicated_line(m); break;
        default: called_file(m); break;
      }
    }
    bool stops = false;
    for (const auto& l : m.lines) stops = stops || ends_deck(keyword(l));
    if (stops) m.must_fail = false;   // a STOP before the bad line would end the deck cleanly
  }

 private:
  std::size_t below(std::size_t n) { return static_cast<std::size_t>(rng_() % n); }
  template <class T, std::size_t N> const T& pick(const T (&a)[N]) { return a[below(N)]; }
  std::size_t any_line(const Mutant& m) { return below(m.lines.size()); }
  // A place after the deck's first START or RESTART, where a model exists.
  std::size_t place_with_model(const Mutant& m) {
    std::size_t first = 0;
    for (std::size_t k = 0; k < m.lines.size(); ++k)
      if (is_one_of(keyword(m.lines[k]), {"sta", "res"})) {
        first = k + 1;
        break;
      }
    return first + below(m.lines.size() - first + 1);
  }
  void insert(Mutant& m, std::size_t at, const std::vector<std::string>& lines) {
    m.lines.insert(m.lines.begin() + static_cast<long>(std::min(at, m.lines.size())), lines.begin(), lines.end());
  }
  std::string fill(std::size_t n, char c = 'x') { return std::string(n, c); }

  // The first mutations: words dropped, swapped, duplicated; a number replaced by a hard one;
  // binary bytes; an unterminated quote or continuation; a line dropped or doubled; a nonsense
  // command (the deck must then fail).
  void line_mutation(Mutant& m) {
    const std::size_t at = any_line(m);
    std::string& line = m.lines[at];
    auto words = words_of(line);
    const std::string key = keyword(line);
    // A CYCLE's count stays: a longer run is a legal run, not a finding.
    const bool counted = is_one_of(key, {"cyc", "sol"});
    switch (below(10)) {
      case 0:
        if (!words.empty()) words.erase(words.begin() + static_cast<long>(below(words.size())));
        line = join(words);
        m.mutations.push_back(fmt::format("line {}: a word dropped", at + 1));
        break;
      case 1:
        if (words.size() > 1) std::swap(words[below(words.size())], words[below(words.size())]);
        line = join(words);
        m.mutations.push_back(fmt::format("line {}: two words swapped", at + 1));
        break;
      case 2:
        if (!words.empty())
          words.insert(words.begin() + static_cast<long>(below(words.size())), words[below(words.size())]);
        line = join(words);
        m.mutations.push_back(fmt::format("line {}: a word doubled", at + 1));
        break;
      case 3: case 4: case 5: {
        std::vector<std::size_t> numbers;
        for (std::size_t k = counted ? 2 : 1; k < words.size(); ++k)
          if (is_number(words[k])) numbers.push_back(k);
        if (!numbers.empty()) words[numbers[below(numbers.size())]] = pick(kHardNumbers);
        line = join(words);
        m.mutations.push_back(fmt::format("line {}: a number made hard", at + 1));
        break;
      }
      case 6: {
        std::string junk;
        for (std::size_t k = 0, n = 1 + below(12); k < n; ++k) {
          const char c = static_cast<char>(below(256));
          if (c != '\n') junk.push_back(c);
        }
        line.insert(below(line.size() + 1), junk);
        m.mutations.push_back(fmt::format("line {}: binary bytes", at + 1));
        break;
      }
      case 7:
        if (below(2)) line += " \"open";
        else if (at + 1 == m.lines.size()) line += " &";
        else line.insert(below(line.size() + 1), "'");
        m.mutations.push_back(fmt::format("line {}: an open quote or continuation", at + 1));
        break;
      case 8:
        if (below(2)) m.lines.erase(m.lines.begin() + static_cast<long>(at));
        else m.lines.insert(m.lines.begin() + static_cast<long>(at), line);
        m.mutations.push_back(fmt::format("line {}: dropped or doubled", at + 1));
        break;
      default:
        m.lines.insert(m.lines.begin() + static_cast<long>(at), fmt::format("qzxv{} 1 2", below(1000)));
        m.must_fail = true;
        m.mutations.push_back(fmt::format("line {}: a nonsense command", at + 1));
        break;
    }
  }

  // SERVO, GEN, STRAIN, START, PROP and the like given extreme numbers: a line of the deck with
  // its numbers replaced, or a new line, then sometimes a few cycles so that the numbers act.
  void extreme_arguments(Mutant& m) {
    std::vector<std::size_t> candidates;
    for (std::size_t k = 0; k < m.lines.size(); ++k)
      if (is_one_of(keyword(m.lines[k]), {"ser", "gen", "str", "sta", "pro", "lat", "wal", "mem"}))
        candidates.push_back(k);
    if (!candidates.empty() && below(2)) {
      const std::size_t at = candidates[below(candidates.size())];
      auto words = words_of(m.lines[at]);
      const bool all = below(3) == 0;
      std::vector<std::size_t> numbers;
      for (std::size_t k = 1; k < words.size(); ++k)
        if (is_number(words[k])) numbers.push_back(k);
      if (numbers.empty()) return;
      if (all) for (auto k : numbers) words[k] = pick(kExtremes);
      else words[numbers[below(numbers.size())]] = pick(kExtremes);
      m.lines[at] = join(words);
      m.mutations.push_back(fmt::format("line {}: {} extreme", at + 1, all ? "every number" : "a number"));
      return;
    }
    std::string line;
    for (const char* c = pick(kExtremeTemplates); *c; ++c)
      line += *c == '#'   ? std::string(below(4) ? pick(kExtremes) : pick(kOrdinary))
              : *c == '!' ? std::string(pick(kExtremes))
                          : std::string(1, *c);
    std::vector<std::string> added{line};
    if (below(2)) added.push_back(fmt::format("cycle {}", 1 + below(20)));
    const std::size_t at = place_with_model(m);
    insert(m, at, added);
    m.mutations.push_back(fmt::format("line {}: extreme arguments: {}", at + 1, line));
  }

  // A FIFO, a symbolic link (to a file that must not change, nowhere, itself, a folder, a device)
  // or a folder planted where the deck reads or writes a file.
  void planted_file(Mutant& m) {
    std::vector<std::string> names;
    for (const auto& l : m.lines)
      for (auto& n : files_named(l)) names.push_back(n);
    if (names.empty() || below(4) == 0) {
      const std::string line = pick(kFileLines);
      const std::size_t at = place_with_model(m);
      insert(m, at, {line});
      m.mutations.push_back(fmt::format("line {}: {}", at + 1, line));
      names = files_named(line);
    }
    const std::string name = names[below(names.size())];
    for (const auto& f : m.files)
      if (f.name == name) return;   // one thing planted at a name
    using K = SideFile::Kind;
    static const std::pair<K, const char*> kinds[] = {
        {K::Fifo, ""}, {K::Fifo, ""}, {K::Link, "victim.txt"}, {K::Link, "victim.txt"}, {K::Link, "no/such/file"},
        {K::Link, "@self"}, {K::Link, "."}, {K::Folder, ""}, {K::Link, "/dev/zero"}, {K::Link, "/dev/urandom"},
        {K::Link, "/dev/full"}, {K::Link, "/dev/null"}};
    const auto& [kind, target] = pick(kinds);
    SideFile f{kind, name, std::string(target) == "@self" ? name : target};
    const bool victim_planted =
        std::any_of(m.files.begin(), m.files.end(), [](const SideFile& s) { return s.name == "victim.txt"; });
    if (f.text == "victim.txt" && !victim_planted)
      m.files.push_back({K::Text, "victim.txt", "a file a planted link points to: it must not change\n"});
    m.files.push_back(f);
    const char* what = kind == K::Fifo ? "a FIFO" : kind == K::Folder ? "a folder" : "a link";
    m.mutations.push_back(fmt::format("planted {} at '{}'{}", what, name, kind == K::Link ? " -> " + f.text : ""));
  }

  // SET doubling a value line after line, one line expanding many long values, braces nested deep,
  // a name of dollars, many variables.
  void variable_bomb(Mutant& m) {
    std::vector<std::string> added;
    std::string what;
    switch (below(6)) {
      case 0: {
        const std::size_t n = 8 + below(25), len = 1 + below(8);
        added.push_back("set b0 " + fill(len));
        for (std::size_t k = 1; k <= n; ++k) added.push_back(fmt::format("set b{} $b{}$b{}", k, k - 1, k - 1));
        added.push_back(fmt::format("echo $b{}", n));
        m.must_fail = m.must_fail || (len << std::min<std::size_t>(n, 40)) > kMaxLine;
        what = fmt::format("a value doubled {} times", n);
        break;
      }
      case 1: {
        const std::size_t len = std::size_t(1) << (10 + below(7)), refs = 1 + below(40);
        added.push_back("set w " + fill(len));
        std::string echo = "echo";
        for (std::size_t k = 0; k < refs; ++k) echo += " $w";
        added.push_back(echo);
        m.must_fail = m.must_fail || refs * (len + 1) > kMaxLine + 64;
        what = fmt::format("{} references to a value of {} characters", refs, len);
        break;
      }
      case 2: {
        static const std::size_t depths[] = {100, 10000, 300000};
        const std::size_t d = depths[below(3)];
        std::string l = "echo ";
        for (std::size_t k = 0; k < d; ++k) l += "${";
        l += "x";
        if (below(2)) l += fill(d, '}');
        added.push_back(l);
        what = fmt::format("braces nested {} deep", d);
        break;
      }
      case 3: {
        const std::size_t r = 5 + below(36);
        added.push_back("set a x");
        for (std::size_t k = 0; k < r; ++k) added.push_back("set a $a$a");
        m.must_fail = m.must_fail || r > 20;
        what = fmt::format("SET a $a$a {} times", r);
        break;
      }
      case 4: {
        const std::size_t d = std::size_t(1) << below(18);
        added.push_back("set a 1");
        added.push_back("echo " + fill(d, '$') + "a ${a${a}} $ ${ ${} $}");
        what = fmt::format("{} dollars before a name", d);
        break;
      }
      default: {
        const std::size_t n = below(2) ? 1000 : 100000;
        for (std::size_t k = 1; k <= n; ++k) added.push_back(fmt::format("set v{} {}", k, k));
        added.push_back(fmt::format("echo $v1 $v{}", n));
        what = fmt::format("{} variables", n);
        break;
      }
    }
    const std::size_t at = below(m.lines.size() + 1);
    insert(m, at, added);
    m.mutations.push_back(fmt::format("line {}: variable bomb: {}", at + 1, what));
  }

  // A line near and over the 1 MiB limit: a long ECHO, comment or padded command, a number of a
  // million digits, or a continuation chain that joins to more than the limit.
  void huge_line(Mutant& m) {
    static const std::size_t sizes[] = {65536, kMaxLine - 1, kMaxLine, kMaxLine + 1, 2 * kMaxLine + 7, 8 * kMaxLine};
    const std::size_t len = sizes[below(std::size(sizes))];
    const std::size_t at = any_line(m);
    std::string what;
    switch (below(5)) {
      case 0:
        m.lines.insert(m.lines.begin() + static_cast<long>(at), "echo " + fill(len - 5));
        what = "an ECHO";
        break;
      case 1:
        m.lines.insert(m.lines.begin() + static_cast<long>(at), "* " + fill(len - 2, '*'));
        what = "a comment";
        break;
      case 2: {
        std::string& l = m.lines[at];
        if (l.size() < len) l += fill(len - l.size(), below(2) ? ' ' : '\t');
        what = "a command padded with blanks";
        break;
      }
      case 3: {
        auto words = words_of(m.lines[at]);
        std::vector<std::size_t> numbers;
        for (std::size_t k = 1; k < words.size(); ++k)
          if (is_number(words[k])) numbers.push_back(k);
        if (numbers.empty()) return;
        const std::size_t k = numbers[below(numbers.size())];
        words[k] = below(2) ? "1" + fill(len / 2, '0') : "0." + fill(len / 2, '0') + "1";
        m.lines[at] = join(words);
        what = "a number of many digits";
        break;
      }
      default: {
        const std::size_t piece = 60000, pieces = len / piece + 1;
        std::vector<std::string> chain;
        for (std::size_t k = 0; k < pieces; ++k)
          chain.push_back((k ? "" : "echo ") + fill(piece) + (k + 1 < pieces ? " &" : ""));
        insert(m, at, chain);
        m.must_fail = m.must_fail || pieces * (piece + 1) > kMaxLine + 64;
        m.mutations.push_back(
            fmt::format("line {}: a continuation chain of {} lines of {} characters", at + 1, pieces, piece));
        return;
      }
    }
    m.must_fail = m.must_fail || m.lines[at].size() > kMaxLine;
    m.mutations.push_back(fmt::format("line {}: {}, {} characters", at + 1, what, m.lines[at].size()));
  }

  // One line many times over. Commands that do work (cycling, generating, writing files) are
  // repeated a few times: a longer run is a legal run, not a finding. So is a line naming a
  // variable (it may expand to 1 MiB: 10,000 of them take minutes of copying). The deck stays
  // under about 16 MiB: a program that reads a deck whole needs memory in proportion to it.
  void duplicated_line(Mutant& m) {
    const std::size_t at = any_line(m);
    const std::string key = keyword(m.lines[at]);
    const bool heavy = is_one_of(key, {"cyc", "sol", "gen", "lat", "plo", "dum", "sav", "res", "pri", "his", "cal",
                                       "inc", "ren", "bac", "mem", "sam", "del", "wal", "bal", "cre", "ser"}) ||
                       m.lines[at].find('$') != std::string::npos;
    static const std::size_t many[] = {100, 1000, 10000};
    const std::size_t times = std::min(heavy ? 2 + below(9) : many[below(3)],
                                       std::max<std::size_t>(2, (kMaxLine << 4) / (m.lines[at].size() + 1)));
    m.lines.insert(m.lines.begin() + static_cast<long>(at), times - 1, m.lines[at]);
    m.mutations.push_back(fmt::format("line {}: repeated {} times", at + 1, times));
  }

  // A CALL of a generated file: many lines, a big file of comments, NULs, one line longer than the
  // limit, random bytes, a chain of files calling each other, a file calling itself, an empty one.
  void called_file(Mutant& m) {
    const std::size_t n = m.files.size();
    std::string name = fmt::format("called{}.dat", n);
    std::string text, what;
    switch (below(9)) {
      case 0: {
        static const char* const harmless[] = {"set v 1", "* a comment", "echo x", "", "; ;"};
        const char* l = pick(harmless);
        const std::size_t count = below(2) ? 10000 : 200000;
        for (std::size_t k = 0; k < count; ++k) (text += l) += '\n';
        what = fmt::format("{} lines of '{}'", count, l);
        break;
      }
      case 1:
        for (std::size_t k = 0; k < 16000; ++k) (text += "* " + fill(1000)) += '\n';
        what = "16 MB of comments";
        break;
      case 2: {
        static const std::size_t sizes[] = {1, 4096, 4 << 20};
        text.assign(sizes[below(3)], '\0');
        m.must_fail = true;
        what = fmt::format("{} NUL bytes", text.size());
        break;
      }
      case 3:
        text = "echo " + fill(2 * kMaxLine);
        m.must_fail = true;
        what = "one line of 2 MiB, no newline";
        break;
      case 4:
        for (std::size_t k = 0; k < (1 << 20); ++k) text.push_back(static_cast<char>(below(256)));
        text[below(text.size())] = '\0';
        m.must_fail = true;
        what = "1 MiB of random bytes";
        break;
      case 5: case 6: {
        static const std::size_t depths[] = {50, 98, 99, 100, 101, 150};
        const std::size_t depth = depths[below(std::size(depths))];
        for (std::size_t k = 1; k < depth; ++k)
          m.files.push_back({SideFile::Kind::Text, fmt::format("chain{}_{}.dat", n, k),
                             k + 1 < depth ? fmt::format("call chain{}_{}.dat\n", n, k + 1) : "echo bottom\n"});
        text = depth > 1 ? fmt::format("call chain{}_1.dat\n", n) : "echo bottom\n";
        what = fmt::format("a chain of {} files", depth);
        break;
      }
      case 7:
        text = fmt::format("echo again\ncall {}\n", name);
        m.must_fail = true;
        what = "a file that calls itself";
        break;
      default:
        what = "an empty file";
        break;
    }
    m.files.push_back({SideFile::Kind::Text, name, std::move(text)});
    const std::size_t at = below(m.lines.size() + 1);
    insert(m, at, {(below(4) ? "call " : "include ") + name});
    m.mutations.push_back(fmt::format("line {}: CALL of {}", at + 1, what));
  }

  std::mt19937_64 rng_;
};

std::vector<std::string> read_lines(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  std::vector<std::string> out;
  for (std::string l; std::getline(f, l);) out.push_back(l);
  return out;
}

}  // namespace

std::vector<fs::path> seed_decks() {
  const fs::path source(TRUBAL_SOURCE_DIR);
  std::vector<fs::path> out;
  for (const fs::path& dir : {source / "examples", source / "doc" / "tutorial", source / "tests" / "fuzz" / "corpus",
                             source / "tests" / "fuzz" / "regressions"})
    for (const auto& e : fs::directory_iterator(dir))
      if (e.path().extension() == ".dat") out.push_back(e.path());
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<std::string> capped(const std::vector<std::string>& lines) {
  std::vector<std::string> out;
  for (const auto& line : lines) {
    auto w = words_of(line);
    const std::string key = keyword(line);
    bool changed = false;
    auto cap = [&](std::size_t k, long most) {
      if (k < w.size() && is_number(w[k]) && !(std::strtod(w[k].c_str(), nullptr) <= static_cast<double>(most))) {
        w[k] = std::to_string(most);
        changed = true;
      }
    };
    if (is_one_of(key, {"cyc"}) && w.size() > 1) {
      if (lower(w[1]) == "until") w.insert(w.begin() + 1, std::to_string(kMostCycles)), changed = true;
      else cap(1, kMostCycles);
    } else if (is_one_of(key, {"sol"})) {
      auto limit = std::find_if(w.begin(), w.end(), [](const std::string& s) { return lower(s) == "limit"; });
      if (limit == w.end()) w.insert(w.end(), {"limit", std::to_string(kMostCycles)}), changed = true;
      else cap(static_cast<std::size_t>(limit - w.begin()) + 1, kMostCycles);
    } else if (is_one_of(key, {"gen"})) {
      cap(1, kMostGenerated);
    } else if (is_one_of(key, {"lat"})) {
      for (std::size_t k = 3; k <= 5; ++k) cap(k, kMostLatticeCells);
    }
    out.push_back(changed ? join(w) : line);
  }
  return out;
}

Mutant make_mutant(const std::vector<fs::path>& seeds, std::uint64_t fuzz_seed, std::uint64_t index) {
  Mutant m;
  const fs::path& seed = seeds[index % seeds.size()];
  m.seed_name = seed.lexically_relative(TRUBAL_SOURCE_DIR).string();
  m.fuzz_seed = fuzz_seed;
  m.index = index;
  m.lines = capped(read_lines(seed));
  Mutator(fuzz_seed, index).mutate(m);
  return m;
}

std::string visible(const std::string& line, std::size_t most) {
  std::string out;
  for (std::size_t k = 0; k < line.size() && k < most; ++k) {
    const auto c = static_cast<unsigned char>(line[k]);
    if (c >= 32 && c < 127) out.push_back(static_cast<char>(c));
    else out += fmt::format("\\x{:02x}", c);
  }
  if (line.size() > most) out += fmt::format(" ... ({} characters)", line.size());
  return out;
}

std::string describe(const Mutant& m) {
  std::string s = fmt::format("mutant {} of seed {} (TRUBAL_FUZZ_SEED={} TRUBAL_FUZZ_ONLY={}), from {}:\n", m.index,
                              m.fuzz_seed, m.fuzz_seed, m.index, m.seed_name);
  for (const auto& what : m.mutations) s += "  " + what + "\n";
  s += "--- deck.dat:\n";
  std::size_t shown = 0;
  for (std::size_t k = 0; k < m.lines.size();) {
    std::size_t same = 1;
    while (k + same < m.lines.size() && m.lines[k + same] == m.lines[k]) ++same;
    if (++shown == 300) s += "[... the rest of the deck left out]\n";
    if (shown < 300) s += visible(m.lines[k]) + (same > 1 ? fmt::format("   [this line {} times]", same) : "") + "\n";
    k += same;
  }
  for (const auto& f : m.files) {
    if (f.kind == SideFile::Kind::Text)
      s += fmt::format("--- {} ({} bytes): {}\n", f.name, f.text.size(), visible(f.text.substr(0, 200), 200));
    else
      s += fmt::format("--- {}: {}\n", f.name,
                       f.kind == SideFile::Kind::Fifo     ? "a FIFO"
                       : f.kind == SideFile::Kind::Folder ? "a folder"
                                                          : "a link to " + f.text);
  }
  return s;
}

}  // namespace trubal::test::fuzz
