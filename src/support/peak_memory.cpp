#include "support/peak_memory.hpp"

#include <malloc.h>
#include <sys/resource.h>

#include <fmt/format.h>

#include "support/comm.hpp"

namespace trubal {

std::vector<double> peak_memory_per_rank() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  std::vector<double> mine{static_cast<double>(usage.ru_maxrss) / 1024.0}, all;   // (KiB on Linux)
  comm::allgather(mine, all);
  return all;
}

std::string mib_list(const std::vector<double>& mib) {
  std::string line;
  for (double v : mib) line += fmt::format("{}{:.0f}", line.empty() ? "" : " ", v);
  return line;
}

void return_free_memory() {
#if defined(__GLIBC__)
  malloc_trim(0);
#endif
}

}  // namespace trubal
