"""cycle(n, every=k, callback=f): the cut changes no bit, a callback's command is the deck's, and a
callback stops the run."""
import unittest

import numpy as np

import support
import trubal

CYCLES = 600


def squeezed():
    s = trubal.Session(quiet=True)
    s.run_deck(support.COMPRESS)
    return s


class Callbacks(unittest.TestCase):
    def test_cut_run_equals_uncut(self):
        calls = []
        cut = squeezed()
        done = cut.cycle(CYCLES, every=37, callback=lambda s: calls.append(s.step))
        uncut = squeezed()
        uncut.cycle(CYCLES)
        self.assertEqual(done, CYCLES)
        # 16 pieces of 37 and one of 8: the callback after each
        self.assertEqual(calls, list(range(37, CYCLES, 37)) + [CYCLES])
        support.assert_same_state(self, cut, uncut)

    def test_callback_command_equals_the_deck(self):
        # The callback stops the squeeze and turns on a servo at cycle 300; the deck does it between CYCLEs.
        change = "strain xx 0 yy 0 zz 0\nservo 2e4 2e4 2e4"
        def at_300(s):
            if s.step == 300:
                s.command(change)
        api = squeezed()
        api.cycle(CYCLES, every=100, callback=at_300)
        deck = squeezed()
        deck.command(f"cycle 300\n{change}\ncycle {CYCLES - 300}")
        support.assert_same_state(self, api, deck)
        # and the change did something: without it the balls end elsewhere
        plain = squeezed()
        plain.cycle(CYCLES)
        self.assertFalse(support.same_bits(plain.positions, api.positions))

    def test_returning_false_stops(self):
        s = squeezed()
        self.assertEqual(s.cycle(10000, every=100, callback=lambda s: s.step < 300), 300)
        self.assertEqual(s.step, 300)
        # any false value stops: here numpy's, as a comparison of array numbers gives
        self.assertEqual(s.cycle(10000, every=100, callback=lambda s: np.float64(s.step) < 400), 100)
        self.assertEqual(s.step, 400)
        # None (a callback without return) goes on
        self.assertEqual(s.cycle(200, every=100, callback=lambda s: None), 200)
        self.assertEqual(s.step, 600)

    def test_stop_method_stops(self):
        s = squeezed()
        def stop_at_200(s):
            if s.step >= 200:
                s.stop()
        self.assertEqual(s.cycle(1000, every=50, callback=stop_at_200), 200)
        self.assertEqual(s.step, 200)
        # a stop asked in one run does not stop the next
        self.assertEqual(s.cycle(100), 100)

    def test_callback_exception_propagates_model_kept(self):
        s = squeezed()
        def fail_at_200(s):
            if s.step == 200:
                raise ZeroDivisionError("from the callback")
        with self.assertRaises(ZeroDivisionError):
            s.cycle(1000, every=100, callback=fail_at_200)
        self.assertEqual(s.step, 200)
        self.assertEqual(s.cycle(100), 100)

    def test_bad_arguments(self):
        s = squeezed()
        with self.assertRaises(ValueError):
            s.cycle(-1)
        with self.assertRaises(ValueError):
            s.cycle(10, every=-5)
        with self.assertRaisesRegex(trubal.Error, "START"):
            trubal.Session().cycle(10)


if __name__ == "__main__":
    unittest.main()
