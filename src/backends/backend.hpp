// The narrow interface every backend implements. Backends differ only in which pairs they visit and
// how the work is spread; the force at a contact, the gather order and the law of motion are shared
// (src/physics), which is what makes their answers bitwise equal.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "model/model.hpp"

namespace trubal {

struct StepKernels;   // the per-scene specialised loops, chosen once per CYCLE (physics/kernels.hpp)
struct StepSums;      // what one step adds up: energies, the next critical step (physics/kernels.hpp)

class Backend {
 public:
  virtual ~Backend() = default;
  virtual std::string name() const = 0;
  virtual int threads() const { return 1; }
  // Brings model.contacts up to date for the current positions (pair list, carried history, gather
  // index) without computing forces; step() does it itself. Used before estimating the first step.
  virtual void prepare(Model& model) = 0;
  // One time step: find the pairs that may touch, compute contact forces and their sums per ball,
  // move (backends/threaded/parallel_step.hpp: the one way every backend runs the kernels).
  virtual void step(Model& model, const StepKernels& kernels, StepSums& sums) = 0;
  // The balls were changed outside cycling (added, deleted, moved, resized): drop cached lists.
  virtual void invalidate() {}
  // A limit on the memory the backend may take (allpairs: its pair slots); others refuse it.
  virtual void set_max_memory(std::uint64_t bytes);
  // Extra lines for PRINT info ("name: value").
  virtual std::vector<std::pair<std::string, std::string>> info() const { return {}; }
};

// Backends by name (the interpreter never names a concrete one). Throws std::invalid_argument
// with the list of names for an unknown name; options such as threads are given as words.
// threads <= 0: the backend's default (one per hardware thread where it runs threads).
std::unique_ptr<Backend> make_backend(std::string_view name, int threads);
std::vector<std::string> backend_names();

}  // namespace trubal
