// Helpers the io tests share: a small scene with contacts, and a python3 that can import vtk.
#pragma once

#include <catch2/catch.hpp>

#include <string>

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

}  // namespace trubal::test
