#include "py_session.hpp"

#include <pythread.h>

#include <algorithm>
#include <atomic>
#include <csignal>
#include <filesystem>

#include <fmt/format.h>

#include "commands/common.hpp"
#include "interp/signals.hpp"

namespace trubal::python {

namespace {

PyObject* g_error_type = nullptr;   // trubal.Error; lives as long as the process, as module types do

py::str decode(const std::string& text) {
  PyObject* s = PyUnicode_DecodeUTF8(text.data(), static_cast<Py_ssize_t>(text.size()), "replace");
  if (!s) throw py::error_already_set();
  return py::reinterpret_steal<py::str>(s);
}

// Ctrl-C while trubal runs: the engine's flag (every step's end looks at it) and ours (the calls
// look at it when the engine hands control back). Both are lock-free atomics: safe in a handler.
std::atomic<bool> g_interrupted{false};
void on_sigint(int) {
  g_interrupted.store(true);
  interrupt_requested().store(true);
}
int g_guard_depth = 0;               // touched with the GIL held only
struct sigaction g_python_handler {};
unsigned long g_main_thread = 0;

}  // namespace

void make_error_type(py::module_& m) {
  g_error_type = PyErr_NewExceptionWithDoc(
      "trubal.Error",
      "An error of the trubal language or engine. str(e) is 'FILE:LINE: message' (the message alone where no "
      "file is involved); e.file, e.line and e.message hold the parts (file None and line 0 then). The model "
      "is kept as the failing command left it, as in the shell.",
      PyExc_RuntimeError, nullptr);
  if (!g_error_type) throw py::error_already_set();
  m.add_object("Error", py::handle(g_error_type));   // add_object takes a new reference
}

void raise_error(const std::string& file, int line, const std::string& message) {
  const std::string text = file.empty() ? message : fmt::format("{}:{}: {}", file, line, message);
  py::object error = py::reinterpret_borrow<py::object>(g_error_type)(decode(text));
  error.attr("file") = file.empty() ? py::object(py::none()) : py::object(decode(file));
  error.attr("line") = line;
  error.attr("message") = decode(message);
  PyErr_SetObject(g_error_type, error.ptr());
  throw py::error_already_set();
}

void remember_main_thread() {
  g_main_thread = py::module_::import("threading").attr("main_thread")().attr("ident").cast<unsigned long>();
}

InterruptGuard::InterruptGuard() {
  if (PyThread_get_thread_ident() != g_main_thread) return;
  installed_ = true;
  if (g_guard_depth++ > 0) return;
  struct sigaction sa {};
  sa.sa_handler = on_sigint;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESTART;
  sigaction(SIGINT, &sa, &g_python_handler);
}

InterruptGuard::~InterruptGuard() {
  if (!installed_) return;
  if (--g_guard_depth == 0) sigaction(SIGINT, &g_python_handler, nullptr);
}

void InterruptGuard::raise_if_interrupted() {
  if (!g_interrupted.exchange(false)) return;
  interrupt_requested().store(false);
  PyErr_SetNone(PyExc_KeyboardInterrupt);
  throw py::error_already_set();
}

PySession::PySession(bool echo, bool quiet) {
  out_buf_.quiet = err_buf_.quiet = quiet;
  interp_.echo = echo;
  interp_.report_errors = false;   // raised as trubal.Error instead
}

void PySession::flush() {
  output_.out().flush();
  output_.err().flush();
}

void PySession::finish_language(bool ok) {
  flush();
  InterruptGuard::raise_if_interrupted();
  if (!ok) {
    const auto& e = interp_.last_error();
    raise_error(e.file, e.line, e.message);
  }
}

void PySession::command(const std::string& text) {
  // The Python line that gave the command names it in errors (sys._getframe(0) is the caller's:
  // a function written in C has no frame of its own).
  std::string file = "<python>", canonical;
  int line = 1;
  try {
    const py::object frame = py::module_::import("sys").attr("_getframe")(0);
    file = frame.attr("f_code").attr("co_filename").cast<std::string>();
    line = frame.attr("f_lineno").cast<int>();
    std::error_code ec;
    if (std::filesystem::is_regular_file(file, ec)) canonical = std::filesystem::weakly_canonical(file, ec).string();
  } catch (py::error_already_set&) {
  }
  bool ok;
  {
    InterruptGuard guard;
    interp_.resume();   // a STOP in an earlier deck ended that deck only
    ok = interp_.run_text(text, file, canonical, line);
  }
  finish_language(ok);
}

void PySession::run_deck(const std::string& path) {
  bool ok;
  {
    InterruptGuard guard;
    interp_.resume();
    ok = interp_.run_file(path);
  }
  finish_language(ok);
}

std::int64_t PySession::cycle(py::object self, std::int64_t n, std::int64_t every, py::object callback) {
  if (n < 0) throw py::value_error("cycle: n must be 0 or more");
  if (every < 0) throw py::value_error("cycle: every must be 0 (one piece) or more");
  engine_call([&] { session_.require_started(); });
  if (every == 0) every = std::max<std::int64_t>(n, 1);
  stop_requested_ = false;
  std::int64_t done = 0;
  // The run cut into pieces of `every` cycles gives the uncut run's bits (tests/unit/cycle_cuts.cpp),
  // so a callback between pieces changes nothing it does not ask for.
  while (done < n && !stop_requested_) {
    const std::int64_t piece = std::min(every, n - done);
    CycleResult r;
    {
      InterruptGuard guard;
      r = engine_call([&] { return session_.cycle(piece); });
    }
    done += r.done;
    // A Ctrl-C between pieces reached Python's own handler: raised here, not after the last piece.
    if (PyErr_CheckSignals() != 0) throw py::error_already_set();
    flush();
    InterruptGuard::raise_if_interrupted();
    // As CYCLE reports it: balls destroyed, and an unstable run or a ball out of a box as an error.
    engine_call([&] {
      Context ctx{session_, interp_, output_.out()};
      report_cycle_result(ctx, r, piece);
    });
    flush();
    if (r.done < piece) break;   // nothing else stops a piece early; kept as a guard
    if (!callback.is_none()) {
      // None (no return statement) goes on; any false value stops (False, 0, a numpy False).
      const py::object answer = callback(self);
      if (!answer.is_none()) {
        const int truth = PyObject_IsTrue(answer.ptr());
        if (truth < 0) throw py::error_already_set();
        if (truth == 0) break;
      }
    }
    InterruptGuard::raise_if_interrupted();
  }
  return done;
}

}  // namespace trubal::python
