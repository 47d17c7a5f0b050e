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
// Hands the heap's free pages back to the system (glibc's malloc_trim), after a large part of the
// model was freed: arrays below the allocator's mmap threshold are carved from the heap, whose
// free pages otherwise stay resident and count towards the next peak.
void return_free_memory();

}  // namespace trubal
