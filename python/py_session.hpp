// trubal.Session: one engine Session with its interpreter, driven from Python. The language runs as
// the shell runs it; errors become trubal.Error (FILE:LINE and the message), Ctrl-C becomes
// KeyboardInterrupt at the end of a step, and the model is kept either way.
#pragma once

#include <cstdint>
#include <ostream>
#include <string>

#include <pybind11/pybind11.h>

#include "interp/interpreter.hpp"
#include "interp/output.hpp"
#include "py_output.hpp"
#include "session.hpp"

namespace trubal::python {

namespace py = pybind11;

// The Python type trubal.Error (a RuntimeError with file, line and message), made at import.
void make_error_type(py::module_& m);
// Raises trubal.Error: "FILE:LINE: message", or the message alone where file is empty.
[[noreturn]] void raise_error(const std::string& file, int line, const std::string& message);
// Runs f, turning the engine's std::exception into trubal.Error (the model is kept: every Session
// operation checks before it changes anything, or changes nothing it cannot finish).
template <class F> decltype(auto) engine_call(F&& f) {
  try {
    return f();
  } catch (const py::error_already_set&) {
    throw;
  } catch (const std::exception& e) {
    raise_error("", 0, e.what());
  }
}

// While trubal runs (a command, a deck, a cycle): Ctrl-C sets the engine's interrupt flag (stop at
// the end of the step) instead of raising KeyboardInterrupt inside C++; Python's handler is put
// back after. Nested guards (a callback that gives a command) share the outermost one. Only on
// Python's main thread, where Python itself handles signals.
class InterruptGuard {
 public:
  InterruptGuard();
  ~InterruptGuard();
  InterruptGuard(const InterruptGuard&) = delete;
  InterruptGuard& operator=(const InterruptGuard&) = delete;
  // Raises KeyboardInterrupt if a Ctrl-C came since the last check (and clears it).
  static void raise_if_interrupted();

 private:
  bool installed_ = false;
};
// Called at import: which thread is Python's main thread.
void remember_main_thread();

class PySession {
 public:
  PySession(bool echo, bool quiet);

  // Lines of the language (several with newlines); errors are named by the calling Python file and
  // line.
  void command(const std::string& text);
  void run_deck(const std::string& path);
  // n cycles in pieces of `every` (0: one piece), callback(self) after each; returns the cycles done.
  std::int64_t cycle(py::object self, std::int64_t n, std::int64_t every, py::object callback);
  void stop() { stop_requested_ = true; }

  Session& session() { return session_; }
  Interpreter& interpreter() { return interp_; }
  void flush();

 private:
  // After the interpreter ran: KeyboardInterrupt for a Ctrl-C, trubal.Error for an error.
  void finish_language(bool ok);

  PythonStreamBuffer out_buf_{"stdout"}, err_buf_{"stderr"};
  std::ostream out_stream_{&out_buf_}, err_stream_{&err_buf_};
  Output output_{out_stream_, err_stream_};
  Session session_;
  Interpreter interp_{session_, output_};
  bool stop_requested_ = false;
};

// The numpy side (py_arrays.cpp): ball arrays, contacts, measurements, histories. load_numpy,
// called first at import, makes numpy ready for every thread.
void load_numpy();
void bind_arrays(py::class_<PySession>& cls);

}  // namespace trubal::python
