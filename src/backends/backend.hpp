// What a backend is: a way of finding the pairs of balls that may touch. Everything else a step
// does (the contact forces, each ball's sums in the fixed order, the law of motion, the threads)
// is the one pipeline's (cycle/pipeline.hpp), which is what makes every backend's answer the same
// to the bit.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "backends/pair_candidates.hpp"
#include "model/model.hpp"
#include "support/thread_pool.hpp"

namespace trubal {

class Backend {
 public:
  virtual ~Backend() = default;
  virtual std::string name() const = 0;
  // Every pair i < j (ball indices) whose centres are closer than R_i + R_j + skin, sorted by
  // (i, j, image); in a periodic cell at j's nearest image, the positions wrapped into the cell
  // (model/periodic_cell.hpp). The pool's threads may share the search; the list is the same for
  // any pool.
  virtual void find_pairs(const Model& model, double skin, ThreadPool& pool, PairCandidates& out) = 0;
  // Whether the pipeline keeps the list between searches while the skin rule allows (cycle/verlet.hpp);
  // false: the backend is asked every step for the pairs touching now (skin 0), as TPM 2.0's static
  // pair slots were tested every step.
  virtual bool keeps_list() const { return true; }
  // Whether the step is shared among the ranks of a distributed run (BACKEND mpi), not threads.
  virtual bool distributed() const { return false; }
  // The search of one part of the spatial decomposition (cycle/brick_step.hpp: a rank's or a
  // thread's own balls and the others' within reach of them), on the calling thread alone, safe
  // to call from several threads at once: every pair of `part` as find_pairs gives them, the same
  // test on each pair, so a pair of two given balls is found, with the same image, in any model
  // that holds both. The default is the serial search.
  virtual void find_part_pairs(const Model& part, double skin, PairCandidates& out);
  // Extra lines for PRINT info ("name: value").
  virtual std::vector<std::pair<std::string, std::string>> info() const { return {}; }
  // Candidate pairs tested so far, for tests and PRINT info (0 where the backend does not count).
  virtual std::uint64_t pair_tests() const { return 0; }
};

// What BACKEND may say besides the name.
struct BackendOptions {
  int threads = 0;                 // <= 0: the backend's default
  std::uint64_t max_memory = 0;    // allpairs: the limit on its pair slots (0: its default)
  // mpi, a test's fault (the pipeline's StepPolicy::fail_search): the rank whose next share of a
  // search fails as if out of memory, once (-1: none); none without it.
  int* fail_search = nullptr;
};

// Backends by name (nothing outside src/backends/ names a concrete one). Throws
// std::invalid_argument with the list of names for an unknown name, and for an option the backend
// does not take.
std::unique_ptr<Backend> make_backend(std::string_view name, const BackendOptions& options = {});
std::vector<std::string> backend_names();
// The threads a backend runs on by default (1 for serial, one per hardware thread for the others),
// and at most (0: any).
int default_threads(std::string_view name);

}  // namespace trubal
