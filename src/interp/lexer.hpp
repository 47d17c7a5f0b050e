// The lexical rules of the command language (doc/language.md "Lexical rules"): comments, continuation,
// word separators, Fortran number forms, $variables, keyword abbreviation.
#pragma once

#include <cstdint>
#include <functional>
#include <istream>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace trubal {

// An error in the input, reported as FILE:LINE: error: what().
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Removes a trailing comment (`;`, `#`, `!` outside double quotes). A line whose column 1 is `*`
// is a comment as a whole and becomes empty.
std::string strip_comment(std::string_view line);

// The longest line a deck may have, physical or joined by continuations, and the longest a line
// may become with its $variables replaced (doc/language.md "Limits"): a longer one is an error at
// its FILE:LINE, found before more memory is taken (a file of zeros is one endless line).
inline constexpr std::size_t kMaxLineLength = std::size_t{1} << 20;

// Reads logical lines: comments stripped, `&`/`\` continuations joined. Tracks physical line
// numbers; `line()` of the last logical line is the physical line it started on.
class LineReader {
 public:
  explicit LineReader(std::istream& in) : in_(in) {}
  // Next logical line, or nullopt at end of input. Throws InputError for a continuation that runs
  // into the end of the input, a line longer than kMaxLineLength, a NUL byte (a binary file) and a
  // failed read (never taken for the end of the input).
  std::optional<std::string> next();
  int line() const { return start_line_; }

 private:
  // One physical line into `line`, without its newline; false at the end of the input.
  bool read_physical(std::string& line);

  std::istream& in_;
  int physical_ = 0;
  int start_line_ = 0;
};

// Splits a line into words: separators are blanks, tabs, commas, `=`, `(` and `)`. A double-quoted
// string is one word (quotes removed). Throws InputError for an unterminated quote.
std::vector<std::string> split_words(std::string_view line);

// The text after a line's first word, as typed, for a command that reads the rest of its line raw
// (TITLE): the blanks, commas and `=` between the keyword and the text are skipped, trailing blanks
// dropped, and the rest kept whole (commas, `=`, parentheses and inner blanks included). A text
// that is one double-quoted string loses its quotes. "" where nothing follows the first word.
std::string text_after_keyword(std::string_view line);

// Replaces $name and ${name} using lookup (which returns nullopt for an unknown name: an error).
std::string expand_variables(std::string_view line,
                             const std::function<std::optional<std::string>(const std::string&)>& lookup);

// Fortran number forms: 20, 20., .5, 1.5e9, 1.5E+09, 1.5d9, 1.5D+09 (and a sign).
std::optional<double> parse_real(std::string_view word);
// Whether the word is written as a number but is beyond what a double holds (|x| > 1.8e308): an
// input error, never infinity.
bool real_out_of_range(std::string_view word);
// A whole number: digits with an optional sign, nothing else.
std::optional<std::int64_t> parse_integer(std::string_view word);

// Keyword matching: case-insensitive; an exact name wins; otherwise a prefix of at least
// `min_prefix` letters that starts exactly one candidate. Returns the index of the candidate, or
// throws InputError ("ambiguous ... could be A, B") / returns nullopt when nothing matches.
std::optional<std::size_t> match_keyword(std::string_view word, const std::vector<std::string_view>& candidates,
                                         std::size_t min_prefix = 3);

// "Did you mean": the candidate nearest to `word` (case-insensitive, by edit distance with a swap of
// two neighbouring letters counting as one edit) where it is near enough to be a slip of the
// keyboard: one edit for words of up to four letters, two for longer ones. The first such candidate
// at the least distance; nullopt where none is near or the word is one of them.
std::optional<std::size_t> nearest_word(std::string_view word, const std::vector<std::string_view>& candidates);

std::string to_lower(std::string_view s);
std::string to_upper(std::string_view s);
// A word made safe to print: non-printable bytes as \xNN, long words cut.
std::string printable(std::string_view s, std::size_t max_len = 60);

}  // namespace trubal
