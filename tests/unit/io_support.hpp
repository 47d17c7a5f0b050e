// Helpers the io tests share: a small scene with contacts, and a python3 that can import vtk.
#pragma once

#include <catch2/catch.hpp>

#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "interp_support.hpp"

namespace trubal::test {

// Three balls in a row, each pressed into the next (overlap 0.1 of radius 1), and a fourth alone.
inline const char* kPressedRow =
    "start box -10 10 -10 10 -10 10\n"
    "prop kn 1e6 ks 1e6 fric 30 dens 1000\n"
    "ball 0 0 0 1 id 1\n"
    "ball 1.9 0 0 1 id 2\n"
    "ball 3.8 0 0 1.0 id 3 type 2\n"
    "ball -5 5 5 0.5 id 4\n"
    "prop type 2 kn 1e6 ks 1e6 fric 30 dens 1000\n"
    "init zvel 0.25 range id 4\n";

// The first python3 that imports vtk (Debian's /usr/bin/python3 with python3-vtk9), or "".
inline std::string python_with_vtk() {
  for (const char* py : {"/usr/bin/python3", "python3"})
    if (shell(std::string(py) + " -c 'import vtk' >/dev/null 2>&1") == 0) return py;
  return "";
}

// What a VTK reader script printed: one `name v1 v2 ...` line per field.
using Fields = std::map<std::string, std::vector<double>>;

// Runs a Python reader script (text) on `file` with the python3 that imports vtk, and parses
// its lines into fields. Fails the test with an install hint where no python3 has vtk.
inline Fields read_with_vtk(const TempDir& dir, const std::string& script_name, const char* script,
                            const std::string& file) {
  const std::string py = python_with_vtk();
  if (py.empty())
    FAIL("these tests read the VTK files with VTK itself: install python3-vtk9 (apt-get install -y python3-vtk9; "
         ".ci/deps lists it) so that /usr/bin/python3 can `import vtk`");
  const std::string path = dir.write(script_name, script);
  const std::string out = (dir.path() / (script_name + ".txt")).string();
  const int status = shell(py + " " + quote(path) + " " + quote(file) + " >" + quote(out) + " 2>&1");
  INFO(slurp(out));
  REQUIRE(status == 0);
  Fields fields;
  for (const auto& line : lines_of(slurp(out))) {
    std::istringstream in(line);
    std::string name;
    in >> name;
    std::vector<double> values;
    for (double v; in >> v;) values.push_back(v);
    fields[name] = values;
  }
  return fields;
}

}  // namespace trubal::test
