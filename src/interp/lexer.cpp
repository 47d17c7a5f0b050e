#include "interp/lexer.hpp"

#include <algorithm>

#include <cmath>

#include <cctype>
#include <charconv>
#include <cstdlib>

#include <fmt/format.h>

namespace trubal {

std::string to_lower(std::string_view s) {
  std::string r(s);
  for (auto& c : r) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return r;
}

std::string to_upper(std::string_view s) {
  std::string r(s);
  for (auto& c : r) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return r;
}

std::string printable(std::string_view s, std::size_t max_len) {
  if (s.size() <= max_len && std::all_of(s.begin(), s.end(), [](char c) { return c >= 32 && c < 127; }))
    return std::string(s);   // (the common case, without a character at a time)
  std::string r;
  for (std::size_t k = 0; k < s.size() && k < max_len; ++k) {
    auto c = static_cast<unsigned char>(s[k]);
    if (c >= 32 && c < 127) r += static_cast<char>(c);
    else r += fmt::format("\\x{:02x}", c);
  }
  if (s.size() > max_len) r += fmt::format("... ({} characters)", s.size());
  return r;
}

std::string strip_comment(std::string_view line) {
  if (!line.empty() && line[0] == '*') return {};
  bool quoted = false;
  for (std::size_t k = 0; k < line.size(); ++k) {
    char c = line[k];
    if (c == '"') quoted = !quoted;
    else if (!quoted && (c == ';' || c == '#' || c == '!')) return std::string(line.substr(0, k));
  }
  return std::string(line);
}

static std::string_view trim_right(std::string_view s) {
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r' || s.back() == '\n'))
    s.remove_suffix(1);
  return s;
}

static std::string too_long(std::string_view what) {
  return fmt::format("{} is longer than {} characters (1 MiB): not a deck? (a binary file?)", what, kMaxLineLength);
}

bool LineReader::read_physical(std::string& line) {
  line.clear();
  bool any = false;   // characters (or a newline) read for this line
  char chunk[4096];
  for (bool more = true; more;) {
    // istream::getline stops at a full chunk (failbit) rather than growing a string without end, and
    // turns a failed read into badbit (an exception from the stream buffer included).
    in_.getline(chunk, sizeof chunk);
    const auto got = static_cast<std::size_t>(in_.gcount());
    if (in_.bad()) {
      start_line_ = physical_ + 1;
      throw InputError("cannot read the input: a read error (the rest of the deck is not run)");
    }
    more = false;
    if (!in_.fail()) {   // a whole line (its newline extracted unless the input ended)
      line.append(chunk, in_.eof() ? got : got - 1);
      any = true;
    } else if (got == sizeof chunk - 1 && !in_.eof()) {   // the line goes on past the chunk
      line.append(chunk, got);
      in_.clear();
      any = more = true;
    } else if (!any) {   // the end of the input
      return false;
    }
    if (line.size() > kMaxLineLength) {
      start_line_ = physical_ + 1;
      throw InputError(too_long("the line"));
    }
  }
  ++physical_;
  if (line.find('\0') != std::string::npos) {
    start_line_ = physical_;
    throw InputError("a NUL byte in the line: not a deck? (a binary file?)");
  }
  return true;
}

std::optional<std::string> LineReader::next() {
  std::string logical, physical_line;
  bool continuing = false;
  while (read_physical(physical_line)) {
    if (physical_ == 1 && physical_line.starts_with("\xEF\xBB\xBF")) physical_line.erase(0, 3);   // UTF-8 BOM
    if (!continuing) start_line_ = physical_;
    const std::string stripped = strip_comment(physical_line);   // body views it: keep it alive
    std::string_view body = trim_right(stripped);
    // An empty or comment line inside a continuation ends nothing: keep reading.
    if (continuing && body.empty()) continue;
    if (!body.empty() && (body.back() == '&' || body.back() == '\\')) {
      body.remove_suffix(1);
      logical.append(body);
      logical.push_back(' ');
      if (logical.size() > kMaxLineLength) throw InputError(too_long("the line joined by its continuations"));
      continuing = true;
      continue;
    }
    logical.append(body);
    if (logical.size() > kMaxLineLength) throw InputError(too_long("the line joined by its continuations"));
    return logical;
  }
  if (continuing)
    throw InputError("the continuation (& or \\ at the end of the line) runs into the end of the input");
  return std::nullopt;
}

static bool is_separator(char c) {
  return c == ' ' || c == '\t' || c == ',' || c == '=' || c == '(' || c == ')' || c == '\r' || c == '\n' ||
         c == '\v' || c == '\f';
}

std::vector<std::string> split_words(std::string_view line) {
  std::vector<std::string> words;
  std::size_t k = 0;
  while (k < line.size()) {
    if (is_separator(line[k])) { ++k; continue; }
    if (line[k] == '"') {
      auto end = line.find('"', k + 1);
      if (end == std::string_view::npos) throw InputError("unterminated quoted string (a \" without its closing \")");
      words.emplace_back(line.substr(k + 1, end - k - 1));
      k = end + 1;
      continue;
    }
    std::size_t start = k;
    while (k < line.size() && !is_separator(line[k]) && line[k] != '"') ++k;
    words.emplace_back(line.substr(start, k - start));
  }
  return words;
}

std::string text_after_keyword(std::string_view line) {
  std::size_t k = 0;
  while (k < line.size() && is_separator(line[k])) ++k;
  if (k < line.size() && line[k] == '"') {   // (the first word as split_words reads it)
    const auto end = line.find('"', k + 1);
    k = end == std::string_view::npos ? line.size() : end + 1;
  } else {
    while (k < line.size() && !is_separator(line[k]) && line[k] != '"') ++k;
  }
  while (k < line.size() && is_separator(line[k]) && line[k] != '(' && line[k] != ')') ++k;
  std::string_view text = trim_right(line.substr(k));
  if (text.size() >= 2 && text.front() == '"' && text.find('"', 1) == text.size() - 1) text = text.substr(1, text.size() - 2);
  return std::string(text);
}

static bool is_name_char(char c, bool first) {
  return std::isalpha(static_cast<unsigned char>(c)) || c == '_' || (!first && std::isdigit(static_cast<unsigned char>(c)));
}

std::string expand_variables(std::string_view line,
                             const std::function<std::optional<std::string>(const std::string&)>& lookup) {
  if (line.find('$') == std::string_view::npos) return std::string(line);
  std::string out;
  for (std::size_t k = 0; k < line.size(); ++k) {
    if (line[k] != '$') { out.push_back(line[k]); continue; }
    bool braced = k + 1 < line.size() && line[k + 1] == '{';
    std::size_t start = k + 1 + (braced ? 1 : 0), end = start;
    while (end < line.size() && is_name_char(line[end], end == start)) ++end;
    if (end == start) throw InputError("a $ must be followed by a variable name (letters, digits, _)");
    if (braced && (end >= line.size() || line[end] != '}')) throw InputError("${ without its closing }");
    std::string name = to_lower(line.substr(start, end - start));
    auto value = lookup(name);
    if (!value) throw InputError(fmt::format("undefined variable ${} (define it with SET {} value)", name, name));
    // A value is not expanded again (no depth to bound), but SET can double one line after line:
    // the line's length is bounded before it is built.
    if (value->size() > kMaxLineLength - std::min(kMaxLineLength, out.size() + (line.size() - end)))
      throw InputError(fmt::format("the line with ${} replaced would be longer than {} characters (1 MiB)", name,
                                   kMaxLineLength));
    out += *value;
    k = end - (braced ? 0 : 1);
  }
  return out;
}

namespace {

// The number a word spells, or nothing; a number beyond the doubles comes out infinite.
std::optional<double> convert_real(std::string_view w) {
  // Grammar first (strtod alone would take "inf", "nan", hex and "1e"); then convert.
  std::size_t k = 0, n = w.size();
  if (k < n && (w[k] == '+' || w[k] == '-')) ++k;
  std::size_t digits = 0;
  while (k < n && std::isdigit(static_cast<unsigned char>(w[k]))) ++k, ++digits;
  if (k < n && w[k] == '.') {
    ++k;
    while (k < n && std::isdigit(static_cast<unsigned char>(w[k]))) ++k, ++digits;
  }
  if (digits == 0) return std::nullopt;
  std::string text(w.substr(0, k));
  if (k < n && (w[k] == 'e' || w[k] == 'E' || w[k] == 'd' || w[k] == 'D')) {
    ++k;
    text.push_back('e');
    std::size_t exp_start = k;
    if (k < n && (w[k] == '+' || w[k] == '-')) text.push_back(w[k++]);
    std::size_t exp_digits = 0;
    while (k < n && std::isdigit(static_cast<unsigned char>(w[k]))) text.push_back(w[k++]), ++exp_digits;
    if (exp_digits == 0 || exp_start == n) return std::nullopt;
  }
  if (k != n) return std::nullopt;
  char* end = nullptr;
  double v = std::strtod(text.c_str(), &end);
  if (end != text.c_str() + text.size()) return std::nullopt;
  return v;
}

}  // namespace

std::optional<double> parse_real(std::string_view w) {
  const auto v = convert_real(w);
  if (!v || !std::isfinite(*v)) return std::nullopt;
  return v;
}

bool real_out_of_range(std::string_view w) {
  const auto v = convert_real(w);
  return v && !std::isfinite(*v);
}

std::optional<std::int64_t> parse_integer(std::string_view w) {
  std::size_t k = (!w.empty() && (w[0] == '+' || w[0] == '-')) ? 1 : 0;
  if (k == w.size()) return std::nullopt;
  for (std::size_t m = k; m < w.size(); ++m)
    if (!std::isdigit(static_cast<unsigned char>(w[m]))) return std::nullopt;
  std::int64_t v = 0;
  auto s = w.substr(w[0] == '+' ? 1 : 0);
  auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec != std::errc() || ptr != s.data() + s.size()) return std::nullopt;
  return v;
}

std::optional<std::size_t> match_keyword(std::string_view word, const std::vector<std::string_view>& candidates,
                                         std::size_t min_prefix) {
  std::string w = to_lower(word);
  for (std::size_t k = 0; k < candidates.size(); ++k)
    if (to_lower(candidates[k]) == w) return k;
  if (w.size() < min_prefix) return std::nullopt;
  std::vector<std::size_t> hits;
  for (std::size_t k = 0; k < candidates.size(); ++k)
    if (to_lower(candidates[k]).starts_with(w)) hits.push_back(k);
  if (hits.empty()) return std::nullopt;
  if (hits.size() > 1) {
    std::string list;
    for (auto h : hits) list += (list.empty() ? "" : ", ") + to_upper(candidates[h]);
    throw InputError(fmt::format("'{}' is ambiguous: it could be {}", printable(word), list));
  }
  return hits[0];
}

// Optimal string alignment distance (Damerau's edits, no substring edited twice): a typed `cylce`
// is one edit from `cycle`.
static std::size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<std::vector<std::size_t>> d(a.size() + 1, std::vector<std::size_t>(b.size() + 1));
  for (std::size_t i = 0; i <= a.size(); ++i) d[i][0] = i;
  for (std::size_t j = 0; j <= b.size(); ++j) d[0][j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i)
    for (std::size_t j = 1; j <= b.size(); ++j) {
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + (a[i - 1] != b[j - 1])});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1]) d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  return d[a.size()][b.size()];
}

std::optional<std::size_t> nearest_word(std::string_view word, const std::vector<std::string_view>& candidates) {
  const std::string w = to_lower(word);
  if (w.empty() || w.size() > 64) return std::nullopt;   // (a long word is no slip; the table stays small)
  const std::size_t allowed = w.size() <= 4 ? 1 : 2;
  std::optional<std::size_t> best;
  std::size_t best_distance = allowed + 1;
  for (std::size_t k = 0; k < candidates.size(); ++k) {
    const std::string c = to_lower(candidates[k]);
    if (c == w) return std::nullopt;
    const std::size_t distance = edit_distance(w, c);
    if (distance < best_distance) {
      best_distance = distance;
      best = k;
    }
  }
  return best;
}

}  // namespace trubal
