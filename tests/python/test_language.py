"""The API and the command language give the same bits: the trubal program against the module,
s.cycle against CYCLE, and every backend against serial."""
import csv
import os
import subprocess
import tempfile
import unittest

import numpy as np

import support
import trubal

CYCLES = 600   # enough for about 200 contacts, a third of them sliding


class SameBits(unittest.TestCase):
    def session_after(self, cycle):
        s = trubal.Session(quiet=True)
        s.run_deck(support.COMPRESS)
        cycle(s)
        return s

    @unittest.skipUnless(support.TRUBAL_EXE, "TRUBAL_EXE (the trubal program) not given")
    def test_program_and_module_same_bits(self):
        # The program runs the deck and CYCLE; the module the deck and Session.cycle. CSV rows are
        # written in round-trip precision, so float() gives back the very doubles.
        with tempfile.TemporaryDirectory() as tmp:
            deck = os.path.join(tmp, "run.dat")
            with open(deck, "w") as f:
                f.write(f"call {support.COMPRESS}\ncycle {CYCLES}\nprint balls file balls.csv\n")
            subprocess.run([support.TRUBAL_EXE, deck], cwd=tmp, check=True, stdout=subprocess.DEVNULL)
            with open(os.path.join(tmp, "balls.csv")) as f:
                rows = list(csv.DictReader(f))
        s = self.session_after(lambda s: s.cycle(CYCLES))
        self.assertEqual(len(rows), s.num_balls)
        self.assertEqual([int(r["id"]) for r in rows], list(s.ids))
        for name, cols in (("positions", "xyz"), ("velocities", ("vx", "vy", "vz")), ("spins", ("wx", "wy", "wz")),
                           ("forces", ("fx", "fy", "fz"))):
            program = np.array([[float(r[c]) for c in cols] for r in rows])
            self.assertTrue(support.same_bits(program, getattr(s, name)), f"{name} differ from the program's")
        self.assertTrue(support.same_bits(np.array([float(r["rad"]) for r in rows]), s.radii))

    def test_cycle_command_and_method_same_bits(self):
        by_command = self.session_after(lambda s: s.command(f"cycle {CYCLES}"))
        by_method = self.session_after(lambda s: s.cycle(CYCLES))
        support.assert_same_state(self, by_command, by_method)
        self.assertEqual(by_command.step, CYCLES)
        self.assertTrue(support.same_bits(by_command.stress(), by_method.stress()))

    def test_every_backend_same_bits(self):
        serial = self.session_after(lambda s: s.cycle(CYCLES))
        for backend in ("threaded threads 2", "allpairs"):
            def run(s):
                s.command(f"backend {backend}")
                s.cycle(CYCLES)
            with self.subTest(backend=backend):
                support.assert_same_state(self, serial, self.session_after(run))

    def test_cycling_moves_the_balls(self):
        # The comparisons above would pass for a scene that never moved: this one does.
        s = trubal.Session(quiet=True)
        s.run_deck(support.COMPRESS)
        before = s.positions
        s.cycle(CYCLES)
        self.assertFalse(support.same_bits(before, s.positions))
        self.assertGreater(np.count_nonzero(s.contacts()["sliding"]), 0)


if __name__ == "__main__":
    unittest.main()
