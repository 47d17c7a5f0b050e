// PRINT counters read back: the tests take counts from its `name value` lines, never from PRINT
// info's sentences.
#pragma once

#include <catch2/catch.hpp>

#include <filesystem>
#include <map>
#include <sstream>
#include <string>

#include "interp_support.hpp"

namespace trubal::test {

using Counters = std::map<std::string, double>;

// The counters in `text` (what PRINT counters printed or wrote): every line must be a snake_case
// name, a space and a number, and no name may come twice.
inline Counters parse_counters(const std::string& text) {
  Counters counters;
  for (const std::string& line : lines_of(text)) {
    INFO("PRINT counters line: '" << line << "'");
    const auto space = line.find(' ');
    REQUIRE(space != std::string::npos);
    const std::string name = line.substr(0, space), value = line.substr(space + 1);
    REQUIRE(!name.empty());
    REQUIRE(name.find_first_not_of("abcdefghijklmnopqrstuvwxyz0123456789_") == std::string::npos);
    std::size_t used = 0;
    double number = 0;
    REQUIRE_NOTHROW(number = std::stod(value, &used));
    REQUIRE(used == value.size());
    REQUIRE(counters.emplace(name, number).second);
  }
  REQUIRE_FALSE(counters.empty());
  return counters;
}

// The counters of the file PRINT counters file NAME wrote.
inline Counters read_counters(const std::filesystem::path& file) {
  INFO("counters file " << file);
  REQUIRE(std::filesystem::exists(file));
  return parse_counters(slurp(file));
}

// One counter, which must be there.
inline double counter(const Counters& counters, const std::string& name) {
  const auto it = counters.find(name);
  INFO("counter " << name);
  REQUIRE(it != counters.end());
  return it->second;
}

}  // namespace trubal::test
