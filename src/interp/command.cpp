#include "interp/command.hpp"

#include <cmath>

#include <fmt/format.h>

#include "interp/interpreter.hpp"

namespace trubal {

const std::string& Args::peek() const {
  static const std::string none;
  return empty() ? none : words_[pos_];
}

void Args::fail(const std::string& message) const {
  throw InputError(fmt::format("{} (usage: {})", message, usage_));
}

std::string Args::word(std::string_view what) {
  if (empty()) fail(fmt::format("missing {}", what));
  return words_[pos_++];
}

double Args::real(std::string_view what) {
  if (empty()) fail(fmt::format("missing {} (a number)", what));
  auto v = parse_real(words_[pos_]);
  if (!v && real_out_of_range(words_[pos_]))
    fail(fmt::format("{} is out of range: '{}' is beyond the largest number, 1.8e308", what, printable(words_[pos_])));
  if (!v) fail(fmt::format("expected a number for {}, got '{}'", what, printable(words_[pos_])));
  ++pos_;
  return *v;
}

std::int64_t Args::count(std::string_view what, std::int64_t min, std::int64_t max) {
  if (empty()) fail(fmt::format("missing {} (a whole number)", what));
  const std::string& w = words_[pos_];
  auto v = parse_integer(w);
  if (!v) {
    const std::size_t sign = !w.empty() && (w[0] == '-' || w[0] == '+');
    if (w.size() > sign && w.find_first_not_of("0123456789", sign) == std::string::npos)
      fail(fmt::format("{} is out of range: {}", what, printable(w)));   // digits only, beyond int64
    // A real with a whole value is a count (`cycle 1e6`); 2^63 and beyond, or a fraction, is not.
    if (const auto r = parse_real(w)) {
      if (std::isfinite(*r) && *r == std::floor(*r) && std::abs(*r) < 9.2e18) {
        v = static_cast<std::int64_t>(*r);
      } else if (std::isfinite(*r) && *r == std::floor(*r)) {
        fail(fmt::format("{} is out of range: {}", what, printable(w)));
      } else {
        fail(fmt::format("{} must be a whole number, got the real '{}'", what, printable(w)));
      }
    } else {
      fail(fmt::format("expected a whole number for {}, got '{}'", what, printable(w)));
    }
  }
  if (*v < min || *v > max) {
    if (max == INT64_MAX) fail(fmt::format("{} must be at least {}, got {}", what, min, *v));
    fail(fmt::format("{} must be between {} and {}, got {}", what, min, max, *v));
  }
  ++pos_;
  return *v;
}

std::optional<std::size_t> Args::keyword(const std::vector<std::string_view>& options) {
  if (empty()) return std::nullopt;
  std::optional<std::size_t> hit;
  try {
    hit = match_keyword(words_[pos_], options);
  } catch (const InputError& e) {
    fail(e.what());
  }
  if (hit) ++pos_;
  return hit;
}

std::size_t Args::expect(const std::vector<std::string_view>& options, std::string_view what) {
  std::string list;
  for (auto o : options) list += (list.empty() ? "" : ", ") + std::string(o);
  if (empty()) fail(fmt::format("missing {} (one of: {})", what, list));
  auto hit = keyword(options);
  if (!hit) fail(fmt::format("unknown {} '{}' (one of: {})", what, printable(peek()), list));
  return *hit;
}

bool Args::accept(std::string_view option) { return keyword({option}).has_value(); }

std::string Args::rest() {
  std::string r;
  while (!empty()) r += (r.empty() ? "" : " ") + words_[pos_++];
  return r;
}

void Args::done() const {
  if (!empty()) fail(fmt::format("unexpected '{}' at the end of the command", printable(peek())));
}

void Context::warn(const std::string& message) const { interp.warn(message); }

const Command& find_command(std::string_view keyword) {
  // Every keyword in lower case with its command, made once (a deck may hold a million BALL lines).
  struct Names {
    std::vector<std::string_view> names;
    std::vector<std::string> lower;
    std::vector<const Command*> owner;
  };
  static const Names all = [] {
    Names n;
    for (const Command* c : command_table()) {
      n.names.push_back(c->name);
      n.owner.push_back(c);
      for (auto a : c->aliases) n.names.push_back(a), n.owner.push_back(c);
    }
    for (auto name : n.names) n.lower.push_back(to_lower(name));
    return n;
  }();
  const auto& names = all.names;
  const auto& owner = all.owner;
  std::string w = to_lower(keyword);
  for (std::size_t k = 0; k < names.size(); ++k)
    if (all.lower[k] == w) return *owner[k];
  if (w.size() >= 3) {
    const Command* found = nullptr;
    std::string candidates;
    bool ambiguous = false;
    for (std::size_t k = 0; k < names.size(); ++k) {
      if (!all.lower[k].starts_with(w)) continue;
      candidates += (candidates.empty() ? "" : ", ") + std::string(names[k]);
      if (found && found != owner[k]) ambiguous = true;
      found = owner[k];
    }
    if (ambiguous) throw InputError(fmt::format("'{}' is ambiguous: it could be {}", printable(keyword), candidates));
    if (found) return *found;
  }
  if (w.size() < 3) {
    for (std::size_t k = 0; k < names.size(); ++k)
      if (!w.empty() && all.lower[k].starts_with(w))
        throw InputError(fmt::format("'{}' is too short: abbreviate a command to at least 3 letters ({}?)",
                                     printable(keyword), names[k]));
  }
  if (const auto near = nearest_word(w, names))
    throw InputError(fmt::format("unknown command '{}': did you mean {}? (HELP lists the commands)", printable(keyword),
                                 names[*near]));
  throw InputError(fmt::format("unknown command '{}' (HELP lists the commands)", printable(keyword)));
}

HeldUse held_use(const Command& command, const Args& args) {
  if (!command.places_held_after.empty())
    return !args.empty() && match_keyword(args.peek(), command.places_held_after) ? HeldUse::Place : command.held;
  if (command.keeps_held_after.empty()) return command.held;
  Args look = args;   // (a copy: the command reads its words itself)
  try {
    return !look.empty() && look.keyword(command.keeps_held_after) ? HeldUse::Keep : HeldUse::Place;
  } catch (const InputError&) {
    return HeldUse::Place;   // (the command reports the word)
  }
}

}  // namespace trubal
