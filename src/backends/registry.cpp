// Backends by name. Each backend's folder offers one factory; this table is the only place that
// names them, so the interpreter and the cycle never include a concrete backend.
#include <stdexcept>

#include "support/format_number.hpp"
#include "backends/allpairs/allpairs_backend.hpp"
#include "backends/backend.hpp"
#include "backends/mpi/mpi_backend.hpp"
#include "backends/serial/serial_backend.hpp"
#include "backends/threaded/threaded_backend.hpp"

namespace trubal {
namespace {

struct Entry {
  const char* name;
  int max_threads;      // 0: any
  bool takes_max_memory;
  std::unique_ptr<Backend> (*make)(const BackendOptions& options);
};

const Entry kBackends[] = {
    {"serial", 1, false, [](const BackendOptions&) { return make_serial_backend(); }},
    {"allpairs", 0, true, [](const BackendOptions& o) { return make_allpairs_backend(o.max_memory); }},
    {"threaded", 0, false, [](const BackendOptions&) { return make_threaded_backend(); }},
    {"mpi", 1, false, [](const BackendOptions& o) { return make_mpi_backend(o.fail_search); }},
};

const Entry& entry(std::string_view name) {
  for (const Entry& e : kBackends)
    if (name == e.name) return e;
  std::string known;
  for (const auto& n : backend_names()) known += (known.empty() ? "" : ", ") + n;
  throw std::invalid_argument("unknown backend '" + std::string(name) + "' (known: " + known + ")");
}

}  // namespace

void Backend::find_part_pairs(const Model& part, double skin, PairCandidates& out) {
  // The serial search (every backend that keeps a list finds its pairs), with a grid of its own:
  // the threads of one process search their parts at once.
  BoxGrid grid;
  find_serial_pairs(part, skin, grid, out);
}

std::vector<std::string> backend_names() {
  std::vector<std::string> names;
  for (const Entry& e : kBackends) names.emplace_back(e.name);
  return names;
}

int default_threads(std::string_view name) {
  const Entry& e = entry(name);
  return e.max_threads > 0 ? e.max_threads : ThreadPool::hardware_threads();
}

std::unique_ptr<Backend> make_backend(std::string_view name, const BackendOptions& options) {
  const Entry& e = entry(name);
  if (e.max_threads > 0 && options.threads > e.max_threads)
    throw std::invalid_argument("backend " + std::string(name) + " runs on " +
                                count_of(static_cast<std::size_t>(e.max_threads), "thread"));
  if (options.max_memory > 0 && !e.takes_max_memory)
    throw std::invalid_argument("backend " + std::string(name) + " has no memory limit (maxmem goes with BACKEND allpairs)");
  return e.make(options);
}

}  // namespace trubal
