// The process's peak resident memory, as PRINT info reports it per rank.
#pragma once

#include <string>
#include <vector>

namespace trubal {

// Every rank's peak resident memory so far, in MiB, by rank (a collective call under mpirun; one
// entry otherwise).
std::vector<double> peak_memory_per_rank();
// Those peaks as PRINT info writes them: whole MiB, a space between ranks.
std::string mib_list(const std::vector<double>& mib);

}  // namespace trubal
