// The ranks of a distributed run (`mpirun -np P trubal deck.dat`), and the few collective
// operations trubal needs. Built without MPI, or started without mpirun, there is one rank and
// every operation is a no-op, so the rest of the program never asks which.
//
// The rule every rank follows: all ranks execute every command; rank 0 alone reads the deck, the
// shell's lines and CALLed files (and hands their text to the others), prints, and writes files.
// After each command the ranks agree whether it failed (first_failure), so they stay in step.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace trubal::comm {

// Starts MPI when the process was launched by mpirun (Open MPI's or another PMI launcher's
// environment), else nothing. Call once, first thing in main.
void init(int& argc, char**& argv);
void finalize();
// Built with MPI at all (for PRINT info and tests).
bool built_with_mpi();
// Whether init started MPI: the process was launched by mpirun, on however many ranks (one
// included). False in a build without MPI and in a plain `trubal`.
bool launched();

int rank();
int size();
inline bool root() { return rank() == 0; }

// Rank 0's value to every rank.
void broadcast(std::string& text);
void broadcast(std::int64_t& value);

// The rank on which `failed` is true with the lowest `order` (then the lowest rank), or -1 where it
// is true on none; that rank's `message` is handed to every rank. `order`: where in the deck the
// rank failed (its count of commands run; 0 to 2^40), for ranks that may meet at different commands.
// failed_order, where given: that rank's order (unchanged where none failed).
int first_failure(bool failed, std::string& message, std::int64_t order = 0, std::int64_t* failed_order = nullptr);

// Rank 0's vector (its size and values) to every rank. Instantiated for the element types of the
// model's arrays: double, float, std::int64_t, int, std::uint32_t, std::uint8_t, std::int8_t.
template <class T> void broadcast(std::vector<T>& values);

// Every rank's part in rank order, concatenated into rank 0's `all` (left empty on the others).
void gather_to_root(const std::vector<double>& mine, std::vector<double>& all);
void gather_to_root(const std::vector<std::uint8_t>& mine, std::vector<std::uint8_t>& all);

// Every rank's part in rank order, concatenated into `all` (part sizes may differ).
void allgather(const std::vector<double>& mine, std::vector<double>& all);
void allgather(const std::vector<std::uint8_t>& mine, std::vector<std::uint8_t>& all);

// Point to point, all at once: send[r] goes to rank r, and recv[r] (already sized to what rank r
// sends this rank) is filled from it. Every rank calls it; empty parts cost nothing but the call.
void exchange(const std::vector<std::vector<double>>& send, std::vector<std::vector<double>>& recv);

// One rank to another, blocking: the other rank calls the matching half, in the same order. A word;
// bytes (the receiver's memory as long as what comes, as a word before said).
void send_word(int to, std::int64_t value);
std::int64_t receive_word(int from);
void send_bytes(int to, const void* data, std::size_t bytes);
void receive_bytes(int from, void* data, std::size_t bytes);

// Runs `work` on every rank, where a rank's failure would otherwise leave the others waiting in the
// next collective call: an exception on any rank becomes every rank's, a std::runtime_error with the
// message of the lowest failing rank (running out of memory named as such, `doing` saying while
// doing what). A collective call; on one rank, only the message changes (for std::bad_alloc).
void together(const std::function<void()>& work, const std::string& doing);
// `work` on rank 0 alone, its failure every rank's (together: a collective call). On one rank it
// runs as it is.
void on_root(const std::function<void()>& work, const std::string& doing);

// The largest of each rank's values, element by element, on every rank (exact in any order).
void max_all(std::vector<double>& values);
// Whether any rank's `mine` is true, on every rank (a collective call; on one rank: mine).
bool any_all(bool mine);

}  // namespace trubal::comm
