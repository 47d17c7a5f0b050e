#include "py_output.hpp"

#include <cstring>

#include <pybind11/pybind11.h>

namespace py = pybind11;

namespace trubal::python {

int PythonStreamBuffer::overflow(int c) {
  if (c == traits_type::eof()) return traits_type::not_eof(c);
  pending_.push_back(static_cast<char>(c));
  if (c == '\n') flush_pending();
  return c;
}

std::streamsize PythonStreamBuffer::xsputn(const char* s, std::streamsize n) {
  pending_.append(s, static_cast<std::size_t>(n));
  if (std::memchr(s, '\n', static_cast<std::size_t>(n))) flush_pending();
  return n;
}

int PythonStreamBuffer::sync() {
  flush_pending();
  return 0;
}

void PythonStreamBuffer::flush_pending() {
  if (pending_.empty()) return;
  std::string text;
  text.swap(pending_);
  if (quiet) return;
  py::gil_scoped_acquire gil;
  // Bytes that are not UTF-8 (a user's file name) are shown replaced, never an exception here.
  PyObject* decoded = PyUnicode_DecodeUTF8(text.data(), static_cast<Py_ssize_t>(text.size()), "replace");
  if (!decoded) {
    PyErr_Clear();
    return;
  }
  const py::str line = py::reinterpret_steal<py::str>(decoded);
  // An error in the stream itself (closed, or sys.stdout set to None) loses the words, not the run.
  try {
    py::object stream = py::module_::import("sys").attr(stream_name_);
    if (!stream.is_none()) stream.attr("write")(line);
  } catch (py::error_already_set&) {
  }
}

}  // namespace trubal::python
