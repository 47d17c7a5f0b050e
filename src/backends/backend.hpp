// The narrow interface every backend implements. Backends differ only in which pairs they visit and
// how the work is spread; the force at a contact, the gather order and the law of motion are shared
// (src/physics), which is what makes their answers bitwise equal.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "model/model.hpp"

namespace trubal {

struct StepKernels;   // the per-scene specialised loops, chosen once per CYCLE (physics/engine.hpp)

class Backend {
 public:
  virtual ~Backend() = default;
  virtual std::string name() const = 0;
  virtual int threads() const { return 1; }
  // One time step: find the pairs that may touch, compute contact forces, gather, move.
  virtual void step(Model& model, const StepKernels& kernels) = 0;
  // The balls were changed outside cycling (added, deleted, moved, resized): drop cached lists.
  virtual void invalidate() {}
  // Extra lines for PRINT info ("name: value").
  virtual std::vector<std::pair<std::string, std::string>> info() const { return {}; }
};

// Backends by name (the interpreter never names a concrete one). Throws std::invalid_argument
// with the list of names for an unknown name; options such as threads are given as words.
std::unique_ptr<Backend> make_backend(std::string_view name, int threads);
std::vector<std::string> backend_names();

}  // namespace trubal
