// Helpers the io tests share: a small scene with contacts, and a python3 that can import vtk.
#pragma once

#include <catch2/catch.hpp>

#include <cstdint>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "interp_support.hpp"

namespace trubal::test {

// The save format's checksum of a body (io/save_format.hpp): a test that changes a save's bytes
// writes it anew, so that the file is refused for what it holds, not for its sum.
inline std::uint64_t fnv1a(const std::string& data) {
  std::uint64_t h = 1469598103934665603ull;
  for (unsigned char c : data) h = (h ^ c) * 1099511628211ull;
  return h;
}

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

// Reads a .vtp with vtkXMLPolyDataReader and prints "name value..." lines: the counts (points,
// cells, verts, lines, polys), each point (p<k>), the point and cell data arrays (pd:<name>,
// cd:<name>, led by their component count), and each line and polygon cell's point ids
// (line<n>, poly<n>).
inline const char* kReadVtp = R"PY(
import sys, vtk
r = vtk.vtkXMLPolyDataReader()
r.SetFileName(sys.argv[1])
r.Update()
if r.GetErrorCode() != 0:
    sys.exit("vtk reader error %d" % r.GetErrorCode())
d = r.GetOutput()
print("points", d.GetNumberOfPoints())
print("cells", d.GetNumberOfCells())
print("verts", d.GetNumberOfVerts())
print("lines", d.GetNumberOfLines())
print("polys", d.GetNumberOfPolys())
for k in range(d.GetNumberOfPoints()):
    print("p%d" % k, *("%.17g" % v for v in d.GetPoint(k)))
for data, tag in ((d.GetPointData(), "pd"), (d.GetCellData(), "cd")):
    for a in range(data.GetNumberOfArrays()):
        arr = data.GetArray(a)
        vals = [arr.GetComponent(t, c) for t in range(arr.GetNumberOfTuples()) for c in range(arr.GetNumberOfComponents())]
        print(tag + ":" + arr.GetName(), arr.GetNumberOfComponents(), *("%.17g" % v for v in vals))
ids = vtk.vtkIdList()
for cells, tag in ((d.GetLines(), "line"), (d.GetPolys(), "poly")):
    cells.InitTraversal()
    n = 0
    while cells.GetNextCell(ids):
        print("%s%d" % (tag, n), *(ids.GetId(k) for k in range(ids.GetNumberOfIds())))
        n += 1
)PY";

// A .vtp file's fields as kReadVtp prints them.
inline Fields read_vtp(const TempDir& dir, const std::string& file) { return read_with_vtk(dir, "read_vtp.py", kReadVtp, file); }

// Every data set a .pvd collection names, read with VTK: "part file points polys" lines, in the
// collection's order (the test fails if a file does not read).
inline std::string read_pvd(const TempDir& dir, const std::string& pvd) {
  const std::string py = python_with_vtk();
  if (py.empty()) FAIL("these tests read the VTK files with VTK itself: install python3-vtk9");
  const std::string script = dir.write("read_pvd.py",
      "import sys, os, vtk, xml.etree.ElementTree as ET\n"
      "root = ET.parse(sys.argv[1]).getroot()\n"
      "for d in root.iter('DataSet'):\n"
      "    r = vtk.vtkXMLPolyDataReader(); r.SetFileName(os.path.join(os.path.dirname(sys.argv[1]), d.get('file'))); r.Update()\n"
      "    assert r.GetErrorCode() == 0, d.get('file')\n"
      "    print(d.get('part'), d.get('file'), r.GetOutput().GetNumberOfPoints(), r.GetOutput().GetNumberOfPolys())\n");
  const std::string out = (dir.path() / "read_pvd.txt").string();
  const int status = shell(py + " " + quote(script) + " " + quote(pvd) + " >" + quote(out) + " 2>&1");
  INFO(slurp(out));
  REQUIRE(status == 0);
  return slurp(out);
}

}  // namespace trubal::test
