// Backends by name. Each backend's folder offers one factory; this table is the only place that
// names them, so the interpreter never includes a concrete backend.
#include <stdexcept>

#include "backends/allpairs/allpairs_backend.hpp"
#include "backends/backend.hpp"
#include "backends/serial/serial_backend.hpp"
#include "backends/threaded/threaded_backend.hpp"

namespace trubal {
namespace {

struct Entry {
  const char* name;
  int max_threads;   // 0: any
  std::unique_ptr<Backend> (*make)(int threads);
};

std::unique_ptr<Backend> make_serial(int) { return make_serial_backend(); }

const Entry kBackends[] = {
    {"serial", 1, &make_serial},
    {"allpairs", 0, &make_allpairs_backend},
    {"threaded", 0, &make_threaded_backend},
};

}  // namespace

void Backend::set_max_memory(std::uint64_t) {
  throw std::invalid_argument("backend " + name() + " has no memory limit (maxmem is for allpairs)");
}

std::vector<std::string> backend_names() {
  std::vector<std::string> names;
  for (const Entry& e : kBackends) names.emplace_back(e.name);
  return names;
}

std::unique_ptr<Backend> make_backend(std::string_view name, int threads) {
  for (const Entry& e : kBackends) {
    if (name != e.name) continue;
    if (e.max_threads > 0 && threads > e.max_threads)
      throw std::invalid_argument("backend " + std::string(name) + " runs on " + std::to_string(e.max_threads) +
                                  " thread" + (e.max_threads == 1 ? "" : "s"));
    return e.make(threads);
  }
  std::string known;
  for (const auto& n : backend_names()) known += (known.empty() ? "" : ", ") + n;
  throw std::invalid_argument("unknown backend '" + std::string(name) + "' (known: " + known + ")");
}

}  // namespace trubal
