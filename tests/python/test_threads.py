"""Several Python threads reading arrays at once. Each case runs in a fresh interpreter, so that
numpy is first loaded by trubal itself: the threads' first arrays are then the first numpy work
of the process, where pybind11 used to find numpy's C API lazily and two threads could wait on
each other for ever."""
import os
import subprocess
import sys
import unittest

import support  # noqa: F401  (checks that trubal imports)

TIMEOUT = 60   # seconds; a healthy run takes well under one

# Four threads released together by a barrier, each reading arrays many times, on a Session with
# no balls and on one with balls.
CHILD = r"""
import sys, threading
assert "numpy" not in sys.modules, "the case must start without numpy"
import trubal
empty, full = trubal.Session(quiet=True), trubal.Session(quiet=True)
full.command("start box -1 1 -1 1 -1 1\nball 0 0 0 0.1\nball 0.5 0 0 0.1")
go = threading.Barrier(4)
shapes = []
def read():
    go.wait()
    for _ in range(200):
        shapes.append((empty.positions.shape, empty.radii.shape, full.positions.shape, full.velocities.shape))
threads = [threading.Thread(target=read) for _ in range(4)]
for t in threads:
    t.start()
for t in threads:
    t.join()
assert set(shapes) == {((0, 3), (0,), (2, 3), (2, 3))} and len(shapes) == 800, set(shapes)
print("ok")
"""


class Threads(unittest.TestCase):
    def test_first_arrays_from_four_threads(self):
        # Three fresh processes: the wait needed only two threads to meet at the first array.
        for run in range(3):
            try:
                done = subprocess.run([sys.executable, "-c", CHILD], capture_output=True, text=True,
                                      timeout=TIMEOUT, env=os.environ)
            except subprocess.TimeoutExpired:
                self.fail(f"run {run}: four threads reading arrays still hung after {TIMEOUT} s")
            self.assertEqual(done.returncode, 0, done.stderr)
            self.assertEqual(done.stdout.strip(), "ok")


if __name__ == "__main__":
    unittest.main()
