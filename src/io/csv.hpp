// Numbers in CSV files: round-trip precision, so two runs compare byte for byte.
#pragma once

#include <string>

#include <fmt/format.h>

namespace trubal {

// The shortest text that reads back to exactly the same double (at most 17 significant digits).
inline std::string csv_real(double v) {
  if (v == 0) return "0";   // no "-0": a sign of zero must not make two equal runs differ
  return fmt::format("{}", v);
}

}  // namespace trubal
