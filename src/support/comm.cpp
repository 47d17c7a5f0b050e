#include "support/comm.hpp"

#include <algorithm>
#include <cstdlib>
#include <limits>
#include <new>
#include <stdexcept>
#include <string>

#ifdef TRUBAL_HAVE_MPI
#include <mpi.h>
#endif

namespace trubal::comm {
namespace {

int g_rank = 0, g_size = 1;
[[maybe_unused]] bool g_started = false;   // MPI_Init was called (only in a build with MPI)

#ifdef TRUBAL_HAVE_MPI
// Launched by mpirun (or srun, hydra): the launcher's environment says so. A plain `trubal` does not
// start MPI (a singleton MPI start costs time and may print warnings on a machine without network).
bool launched_by_mpirun() {
  for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK", "PMI_SIZE"})
    if (std::getenv(v)) return true;
  return false;
}

template <class T> MPI_Datatype type_of();
template <> MPI_Datatype type_of<double>() { return MPI_DOUBLE; }
template <> MPI_Datatype type_of<float>() { return MPI_FLOAT; }
template <> MPI_Datatype type_of<std::uint8_t>() { return MPI_UINT8_T; }
template <> MPI_Datatype type_of<std::int8_t>() { return MPI_INT8_T; }
template <> MPI_Datatype type_of<int>() { return MPI_INT; }
template <> MPI_Datatype type_of<std::uint32_t>() { return MPI_UINT32_T; }
template <> MPI_Datatype type_of<std::int64_t>() { return MPI_INT64_T; }
#endif

template <class T> void gather_root_parts(const std::vector<T>& mine, std::vector<T>& all) {
#ifdef TRUBAL_HAVE_MPI
  if (g_started && g_size > 1) {
    int count = static_cast<int>(mine.size());
    std::vector<int> counts(g_size), starts(g_size);
    MPI_Gather(&count, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, MPI_COMM_WORLD);
    long total = 0;
    for (int r = 0; r < g_size; ++r) {
      starts[r] = static_cast<int>(total);
      total += counts[r];
    }
    all.resize(g_rank == 0 ? static_cast<std::size_t>(total) : 0);
    MPI_Gatherv(mine.data(), count, type_of<T>(), all.data(), counts.data(), starts.data(), type_of<T>(), 0,
                MPI_COMM_WORLD);
    return;
  }
#endif
  all = mine;
}

template <class T> void gather_parts(const std::vector<T>& mine, std::vector<T>& all) {
#ifdef TRUBAL_HAVE_MPI
  if (g_started && g_size > 1) {
    int count = static_cast<int>(mine.size());
    std::vector<int> counts(g_size), starts(g_size);
    MPI_Allgather(&count, 1, MPI_INT, counts.data(), 1, MPI_INT, MPI_COMM_WORLD);
    long total = 0;
    for (int r = 0; r < g_size; ++r) {
      starts[r] = static_cast<int>(total);
      total += counts[r];
    }
    all.resize(static_cast<std::size_t>(total));
    MPI_Allgatherv(mine.data(), count, type_of<T>(), all.data(), counts.data(), starts.data(), type_of<T>(),
                   MPI_COMM_WORLD);
    return;
  }
#endif
  all = mine;
}

}  // namespace

bool built_with_mpi() {
#ifdef TRUBAL_HAVE_MPI
  return true;
#else
  return false;
#endif
}

void init(int& argc, char**& argv) {
#ifdef TRUBAL_HAVE_MPI
  if (!launched_by_mpirun()) return;
  MPI_Init(&argc, &argv);
  MPI_Comm_rank(MPI_COMM_WORLD, &g_rank);
  MPI_Comm_size(MPI_COMM_WORLD, &g_size);
  g_started = true;
#else
  (void)argc;
  (void)argv;
#endif
}

void finalize() {
#ifdef TRUBAL_HAVE_MPI
  if (g_started) MPI_Finalize();
  g_started = false;
#endif
}

bool launched() {
#ifdef TRUBAL_HAVE_MPI
  return g_started;
#else
  return false;
#endif
}

int rank() { return g_rank; }
int size() { return g_size; }

void broadcast(std::string& text) {
#ifdef TRUBAL_HAVE_MPI
  if (!g_started || g_size == 1) return;
  std::int64_t n = static_cast<std::int64_t>(text.size());
  MPI_Bcast(&n, 1, MPI_INT64_T, 0, MPI_COMM_WORLD);
  text.resize(static_cast<std::size_t>(n));
  if (n > 0) MPI_Bcast(text.data(), static_cast<int>(n), MPI_CHAR, 0, MPI_COMM_WORLD);
#else
  (void)text;
#endif
}

void broadcast(std::int64_t& value) {
#ifdef TRUBAL_HAVE_MPI
  if (g_started && g_size > 1) MPI_Bcast(&value, 1, MPI_INT64_T, 0, MPI_COMM_WORLD);
#else
  (void)value;
#endif
}

int first_failure(bool failed, [[maybe_unused]] std::string& message, [[maybe_unused]] std::int64_t order,
                  std::int64_t* failed_order) {
#ifdef TRUBAL_HAVE_MPI
  if (g_started && g_size > 1) {
    // (order, rank) in one integer: the rank in the low 23 bits (MPI_Comm_size is an int, and no
    // run has 8 million ranks), the order in the 40 bits above.
    constexpr int kRankBits = 23;
    constexpr std::int64_t kNone = std::numeric_limits<std::int64_t>::max();
    const std::int64_t o = std::clamp<std::int64_t>(order, 0, (std::int64_t{1} << 40) - 1);
    std::int64_t mine = failed ? (o << kRankBits | g_rank) : kNone, least = kNone;
    MPI_Allreduce(&mine, &least, 1, MPI_INT64_T, MPI_MIN, MPI_COMM_WORLD);
    if (least == kNone) return -1;
    const int first = static_cast<int>(least & ((std::int64_t{1} << kRankBits) - 1));
    if (failed_order) *failed_order = least >> kRankBits;
    std::int64_t n = static_cast<std::int64_t>(message.size());
    MPI_Bcast(&n, 1, MPI_INT64_T, first, MPI_COMM_WORLD);
    message.resize(static_cast<std::size_t>(n));
    if (n > 0) MPI_Bcast(message.data(), static_cast<int>(n), MPI_CHAR, first, MPI_COMM_WORLD);
    return first;
  }
#endif
  if (failed && failed_order) *failed_order = order;
  return failed ? 0 : -1;
}

void allgather(const std::vector<double>& mine, std::vector<double>& all) { gather_parts(mine, all); }
void gather_to_root(const std::vector<double>& mine, std::vector<double>& all) { gather_root_parts(mine, all); }
void gather_to_root(const std::vector<std::uint8_t>& mine, std::vector<std::uint8_t>& all) { gather_root_parts(mine, all); }

template <class T> void broadcast(std::vector<T>& values) {
#ifdef TRUBAL_HAVE_MPI
  if (!g_started || g_size == 1) return;
  std::int64_t n = static_cast<std::int64_t>(values.size());
  MPI_Bcast(&n, 1, MPI_INT64_T, 0, MPI_COMM_WORLD);
  values.resize(static_cast<std::size_t>(n));
  // (In pieces below 2^31 elements: MPI counts are ints.)
  constexpr std::int64_t kPiece = std::int64_t{1} << 30;
  for (std::int64_t at = 0; at < n; at += kPiece)
    MPI_Bcast(values.data() + at, static_cast<int>(std::min(kPiece, n - at)), type_of<T>(), 0, MPI_COMM_WORLD);
#else
  (void)values;
#endif
}
template void broadcast(std::vector<double>&);
template void broadcast(std::vector<float>&);
template void broadcast(std::vector<std::int64_t>&);
template void broadcast(std::vector<int>&);
template void broadcast(std::vector<std::uint32_t>&);
template void broadcast(std::vector<std::uint8_t>&);
template void broadcast(std::vector<std::int8_t>&);

void exchange(const std::vector<std::vector<double>>& send, std::vector<std::vector<double>>& recv) {
#ifdef TRUBAL_HAVE_MPI
  if (g_started && g_size > 1) {
    std::vector<int> send_counts(g_size), send_starts(g_size), recv_counts(g_size), recv_starts(g_size);
    std::vector<double> out, in;
    long s = 0, r = 0;
    for (int k = 0; k < g_size; ++k) {
      send_starts[k] = static_cast<int>(s);
      send_counts[k] = static_cast<int>(send[k].size());
      s += send_counts[k];
      recv_starts[k] = static_cast<int>(r);
      recv_counts[k] = static_cast<int>(recv[k].size());
      r += recv_counts[k];
    }
    out.reserve(static_cast<std::size_t>(s));
    for (const auto& part : send) out.insert(out.end(), part.begin(), part.end());
    in.resize(static_cast<std::size_t>(r));
    MPI_Alltoallv(out.data(), send_counts.data(), send_starts.data(), MPI_DOUBLE, in.data(), recv_counts.data(),
                  recv_starts.data(), MPI_DOUBLE, MPI_COMM_WORLD);
    for (int k = 0; k < g_size; ++k)
      std::copy(in.begin() + recv_starts[k], in.begin() + recv_starts[k] + recv_counts[k], recv[k].begin());
    return;
  }
#endif
  if (!send.empty() && !recv.empty()) recv[0] = send[0];
}

void together(const std::function<void()>& work, const std::string& doing) {
  std::string failure;
  try {
    work();
  } catch (const std::bad_alloc&) {
    failure = "rank " + std::to_string(g_rank) + " ran out of memory " + doing +
              ": run on more ranks, or on machines with more memory";
  } catch (const std::exception& e) {
    failure = e.what();
  }
  if (first_failure(!failure.empty(), failure) >= 0) throw std::runtime_error(failure);
}

void on_root(const std::function<void()>& work, const std::string& doing) {
  if (g_size == 1) return work();
  together([&] { if (g_rank == 0) work(); }, doing);
}

namespace {
constexpr int kPointTag = 7;   // (the one tag of this program's point-to-point messages)
[[noreturn]] void no_peer() { throw std::logic_error("internal error: a point-to-point message without MPI ranks"); }
}  // namespace

void send_word([[maybe_unused]] int to, [[maybe_unused]] std::int64_t value) {
#ifdef TRUBAL_HAVE_MPI
  if (g_started && g_size > 1) {
    MPI_Send(&value, 1, MPI_INT64_T, to, kPointTag, MPI_COMM_WORLD);
    return;
  }
#endif
  no_peer();
}

std::int64_t receive_word([[maybe_unused]] int from) {
#ifdef TRUBAL_HAVE_MPI
  if (g_started && g_size > 1) {
    std::int64_t value = 0;
    MPI_Recv(&value, 1, MPI_INT64_T, from, kPointTag, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    return value;
  }
#endif
  no_peer();
}

// (In pieces: an MPI count is an int.)
constexpr std::size_t kPiece = std::size_t{1} << 30;

void send_bytes([[maybe_unused]] int to, [[maybe_unused]] const void* data, [[maybe_unused]] std::size_t bytes) {
#ifdef TRUBAL_HAVE_MPI
  if (g_started && g_size > 1) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (std::size_t at = 0; at < bytes; at += kPiece)
      MPI_Send(p + at, static_cast<int>(std::min(kPiece, bytes - at)), MPI_BYTE, to, kPointTag, MPI_COMM_WORLD);
    return;
  }
#endif
  no_peer();
}

void receive_bytes([[maybe_unused]] int from, [[maybe_unused]] void* data, [[maybe_unused]] std::size_t bytes) {
#ifdef TRUBAL_HAVE_MPI
  if (g_started && g_size > 1) {
    auto* p = static_cast<unsigned char*>(data);
    for (std::size_t at = 0; at < bytes; at += kPiece)
      MPI_Recv(p + at, static_cast<int>(std::min(kPiece, bytes - at)), MPI_BYTE, from, kPointTag, MPI_COMM_WORLD,
               MPI_STATUS_IGNORE);
    return;
  }
#endif
  no_peer();
}

void max_all([[maybe_unused]] std::vector<double>& values) {
#ifdef TRUBAL_HAVE_MPI
  if (g_started && g_size > 1)
    MPI_Allreduce(MPI_IN_PLACE, values.data(), static_cast<int>(values.size()), MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
#endif
}
bool any_all(bool mine) {
  std::vector<double> any{mine ? 1.0 : 0.0};
  max_all(any);
  return any[0] > 0;
}
void allgather(const std::vector<std::uint8_t>& mine, std::vector<std::uint8_t>& all) { gather_parts(mine, all); }

}  // namespace trubal::comm
