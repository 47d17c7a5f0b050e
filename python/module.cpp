// The `trubal` Python module (doc/python.md): trubal.Session, trubal.Error, trubal.__version__.
#include <pybind11/pybind11.h>

#include "py_session.hpp"

namespace py = pybind11;
using trubal::python::PySession;

PYBIND11_MODULE(trubal, m) {
  m.doc() =
      "trubal: discrete elements (spheres) in TRUBAL's command language, from Python.\n\n"
      "    s = trubal.Session()\n"
      "    s.command('start box -1 1 -1 1 -1 1')\n"
      "    s.run_deck('deck.dat')\n"
      "    s.cycle(1000, every=100, callback=lambda s: print(s.step))\n"
      "    x = s.positions          # (n, 3) numpy, ordered by ball id\n\n"
      "Arrays read are read-only copies; assign a whole array to change the model. See doc/python.md.";
  m.attr("__version__") = TRUBAL_VERSION;
  trubal::python::load_numpy();
  trubal::python::make_error_type(m);
  trubal::python::remember_main_thread();

  py::class_<PySession> session(m, "Session",
                                "One model with its own command interpreter (variables, SET, histories), as one "
                                "run of the trubal program. Several sessions are independent.");
  session
      .def(py::init<bool, bool>(), py::arg("echo") = false, py::arg("quiet") = false,
           "echo: show each command as a batch run does ('trubal> ...'; SET echo changes it). quiet: show nothing "
           "the commands print (errors are raised either way).")
      .def("command", &PySession::command, py::arg("text"),
           "Runs lines of the command language (several separated by newlines). An error raises trubal.Error "
           "named by this Python file and line (a CALLed deck's own file and line inside it); the commands "
           "before it have run, and the model is kept. Ctrl-C stops a CYCLE at the end of a step and raises "
           "KeyboardInterrupt, the model kept.")
      .def("run_deck", &PySession::run_deck, py::arg("path"),
           "Runs a deck file as `trubal deck.dat` does; an error raises trubal.Error with the deck's FILE:LINE.")
      .def(
          "cycle",
          [](py::object self, std::int64_t n, std::int64_t every, py::object callback) {
            return self.cast<PySession&>().cycle(self, n, every, std::move(callback));
          },
          py::arg("n"), py::arg("every") = 0, py::arg("callback") = py::none(),
          "Runs n cycles, the same bits as CYCLE n. With every=k the run goes in pieces of k cycles (the last "
          "may be shorter; every cut gives the uncut run's bits) and callback(session) is called after each "
          "piece: it may read arrays, give commands (loads, SERVO, WALL ...) and stop the run by returning a "
          "false value other than None (False, 0, a numpy False) or by calling session.stop(). Returns the "
          "cycles done. An unstable run or a ball leaving a `stop` box raises trubal.Error; Ctrl-C raises "
          "KeyboardInterrupt at the end of a step; the model is kept.")
      .def("stop", &PySession::stop,
           "Asks a running cycle() to stop after the current piece (call it from the callback).");
  trubal::python::bind_arrays(session);
}
