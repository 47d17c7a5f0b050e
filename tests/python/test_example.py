"""examples/python/triaxial_loop.py runs as it is and writes its curves and figure (about 15 s)."""
import csv
import os
import pathlib
import subprocess
import sys
import tempfile
import unittest

import support

SCRIPT = support.HERE.parent.parent / "examples" / "python" / "triaxial_loop.py"


class Example(unittest.TestCase):
    def test_triaxial_loop(self):
        with tempfile.TemporaryDirectory() as tmp:
            run = subprocess.run([sys.executable, str(SCRIPT)], cwd=tmp, env=os.environ, capture_output=True,
                                 text=True, timeout=280)
            self.assertEqual(run.returncode, 0, run.stdout + run.stderr)
            png = pathlib.Path(tmp, "triaxial_loop.png").read_bytes()
            self.assertTrue(png.startswith(b"\x89PNG"))
            with open(pathlib.Path(tmp, "triaxial_loop.csv")) as f:
                rows = list(csv.DictReader(f))
        by_pressure = {}
        for r in rows:
            by_pressure.setdefault(float(r["pressure"]), []).append(r)
        self.assertEqual(sorted(by_pressure), [50e3, 100e3, 200e3])
        for p, curve in by_pressure.items():
            # each test ran to its target strain, stopped by the callback at the first record past it
            self.assertGreaterEqual(float(curve[-1]["axial_strain"]), 0.10)
            self.assertLess(float(curve[-2]["axial_strain"]), 0.10)
            # the servo holds the lateral stresses (0.2% in periodic_triaxial.dat; 1% leaves room)
            self.assertLess(max(float(r["lateral_error"]) for r in curve), 0.01)


if __name__ == "__main__":
    unittest.main()
