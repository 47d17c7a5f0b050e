"""Errors raise trubal.Error with FILE:LINE and the message, and the model is kept."""
import os
import sys
import tempfile
import unittest

import support
import trubal


class Errors(unittest.TestCase):
    def test_deck_error_names_file_and_line(self):
        with tempfile.TemporaryDirectory() as tmp:
            deck = os.path.join(tmp, "bad.dat")
            with open(deck, "w") as f:
                f.write("start box -1 1 -1 1 -1 1\nball 0 0 0 0.1\n; a comment\nball 0.5 0 0 -0.2\nball 0.9 0 0 0.05\n")
            s = trubal.Session(quiet=True)
            with self.assertRaises(trubal.Error) as caught:
                s.run_deck(deck)
        e = caught.exception
        self.assertIsInstance(e, RuntimeError)
        self.assertEqual((e.file, e.line), (deck, 4))
        self.assertIn("radius must be positive", e.message)
        self.assertEqual(str(e), f"{deck}:4: {e.message}")
        self.assertEqual(s.num_balls, 1)   # line 2 ran, line 5 did not: the model is kept
        s.command("ball 0.5 0 0 0.2")      # and the session goes on
        self.assertEqual(s.num_balls, 2)

    def test_command_error_names_the_python_line(self):
        s = trubal.Session(quiet=True)
        line = sys._getframe().f_lineno + 2
        with self.assertRaises(trubal.Error) as caught:
            s.command("cycle 10")
        e = caught.exception
        self.assertEqual((e.file, e.line), (__file__, line))
        self.assertIn("START", e.message)
        # an error in the second of three lines: named one line after the call's
        line = sys._getframe().f_lineno + 2
        with self.assertRaises(trubal.Error) as caught:
            s.command("start box 0 1 0 1 0 1\nprop foo 1\nball 0.5 0.5 0.5 0.1")
        self.assertEqual(caught.exception.line, line + 1)
        self.assertIn("unknown property 'foo'", caught.exception.message)
        self.assertEqual(s.num_balls, 0)   # the third line did not run

    def test_called_deck_names_its_own_line(self):
        with tempfile.TemporaryDirectory() as tmp:
            inner = os.path.join(tmp, "inner.dat")
            with open(inner, "w") as f:
                f.write("start box 0 1 0 1 0 1\n\nfrobnicate 3\n")
            s = trubal.Session(quiet=True)
            with self.assertRaises(trubal.Error) as caught:
                s.command(f"call {inner}")
        self.assertEqual((caught.exception.file, caught.exception.line), (inner, 3))
        self.assertIn("frobnicate", caught.exception.message)

    def test_a_ball_leaving_the_box_raises_with_the_model_kept(self):
        s = trubal.Session(quiet=True)
        s.command("start box -1 1 -1 1 -1 1\nprop kn 1e5 dens 1000\nball 0 0 0.9 0.05\ninit zvel 50")
        with self.assertRaisesRegex(trubal.Error, "ball 1 left the box through z = 1 at cycle 1") as caught:
            s.cycle(1000, every=10, callback=lambda s: self.fail("no callback after an error"))
        self.assertIsNone(caught.exception.file)
        self.assertEqual((s.step, s.num_balls), (1, 1))
        # with `destroy` the ball goes, the run goes on
        s.command("start box -1 1 -1 1 -1 1 destroy\nprop kn 1e5 dens 1000\nball 0 0 0.9 0.05\ninit zvel 50")
        self.assertEqual(s.cycle(100), 100)
        self.assertEqual(s.num_balls, 0)

    def test_missing_deck(self):
        with self.assertRaisesRegex(trubal.Error, "cannot open the deck 'no/such.dat'") as caught:
            trubal.Session(quiet=True).run_deck("no/such.dat")
        self.assertIsNone(caught.exception.file)

    def test_stop_ends_a_deck_not_the_session(self):
        with tempfile.TemporaryDirectory() as tmp:
            deck = os.path.join(tmp, "stops.dat")
            with open(deck, "w") as f:
                f.write("start box 0 1 0 1 0 1\nball 0.5 0.5 0.5 0.1\nstop\nball 0.2 0.2 0.2 0.1\n")
            s = trubal.Session(quiet=True)
            s.run_deck(deck)
        self.assertEqual(s.num_balls, 1)
        s.command("ball 0.8 0.8 0.8 0.1")
        self.assertEqual(s.num_balls, 2)

    def test_output_goes_to_sys_stdout(self):
        import contextlib
        import io
        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            s = trubal.Session(echo=True)
            s.command("start box 0 1 0 1 0 1\nprint info")
        self.assertIn("trubal> start box 0 1 0 1 0 1", out.getvalue())
        self.assertIn("balls: 0", out.getvalue())
        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            trubal.Session(quiet=True).command("start box 0 1 0 1 0 1\nprint info")
        self.assertEqual(out.getvalue(), "")


if __name__ == "__main__":
    unittest.main()
