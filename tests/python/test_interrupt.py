"""Ctrl-C (SIGINT) during a long cycle: KeyboardInterrupt at the end of a step, the model kept, and
Python's own handler back afterwards."""
import os
import signal
import subprocess
import sys
import textwrap
import time
import unittest

import support

CHILD = textwrap.dedent("""
    import signal, sys
    import numpy as np
    import trubal
    s = trubal.Session(quiet=True)
    s.run_deck(sys.argv[1])
    s.cycle(10)
    # The squeeze stops here: run for the parent's whole wait on a fast machine, it would crush the
    # cell below two diameters, which is an error of its own.
    s.command("strain xx 0 yy 0 zz 0")
    said = []
    def ready(s):   # said once the long run has taken a step, so the signal comes while it runs
        if not said:
            said.append(s.step)
            print("ready", flush=True)
    try:
        s.cycle(10**9, every=1, callback=ready)
        print("not interrupted")
    except KeyboardInterrupt:
        stopped = s.step
        assert said == [11] and 11 <= stopped < 10**9, (said, stopped)
        assert np.all(np.isfinite(s.positions))
        assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
        assert s.cycle(5) == 5 and s.step == stopped + 5   # the model goes on from where it stopped
        print("interrupted", stopped, flush=True)
    try:
        s.command("cycle 1000000000")   # the language's CYCLE: the same
        print("not interrupted")
    except KeyboardInterrupt:
        assert stopped + 5 <= s.step < stopped + 10**9, s.step
        print("interrupted again", flush=True)
""")


class Interrupt(unittest.TestCase):
    def test_ctrl_c_stops_the_run_and_keeps_the_model(self):
        child = subprocess.Popen([sys.executable, "-c", CHILD, support.COMPRESS], stdout=subprocess.PIPE,
                                 stderr=subprocess.PIPE, text=True, env=os.environ)
        try:
            self.assertEqual(child.stdout.readline().strip(), "ready")
            time.sleep(0.5)   # well inside the 10**9 cycles (hours)
            child.send_signal(signal.SIGINT)
            self.assertTrue(child.stdout.readline().startswith("interrupted "))
            time.sleep(0.5)
            child.send_signal(signal.SIGINT)
            out, err = child.communicate(timeout=60)
        finally:
            child.kill()
        self.assertEqual(child.returncode, 0, err)
        self.assertEqual(out, "interrupted again\n", err)


if __name__ == "__main__":
    unittest.main()
