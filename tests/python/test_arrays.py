"""Ball arrays: the copy rule, and that setting them then cycling is the deck that builds the same
state with BALL and INIT."""
import re
import unittest

import numpy as np

import support
import trubal

CYCLES = 600
SETUP = "start 0.01 0.01 0.01\nprop kn 1e5 ks 1e5 fric 26.57 dens 2650\n"
SQUEEZE = "damp local 0.5\nstrain xx 100 yy 100 zz 100\n"


def target_state():
    """Where the balls should be: another GEN's packing, and velocities and spins drawn here."""
    s = trubal.Session(quiet=True)
    s.command(SETUP + "gen 250 0.0006 0.0008 seed 99")
    rng = np.random.default_rng(5)
    n = s.num_balls
    return s.positions, s.radii, rng.uniform(-0.05, 0.05, (n, 3)), rng.uniform(-20, 20, (n, 3))


class SetArrays(unittest.TestCase):
    def test_set_then_cycle_equals_the_deck(self):
        pos, rad, vel, spin = target_state()
        # The deck: BALL and INIT give the state directly (repr() of a double reads back the same double).
        lines = [SETUP]
        for k, (p, r) in enumerate(zip(pos, rad)):
            lines.append(f"ball {p[0]!r} {p[1]!r} {p[2]!r} {r!r}\n")
        for k, (v, w) in enumerate(zip(vel, spin)):
            lines.append(f"init xvel {v[0]!r} yvel {v[1]!r} zvel {v[2]!r} xspin {w[0]!r} yspin {w[1]!r} "
                         f"zspin {w[2]!r} range id {k + 1}\n")
        deck = trubal.Session(quiet=True)
        deck.command("".join(lines) + SQUEEZE)
        deck.cycle(CYCLES)

        # The API: other balls first, cycled so that the backend holds pair lists of the old places,
        # then every array set. Stale lists would miss contacts and give other bits.
        api = trubal.Session(quiet=True)
        api.command(SETUP + "gen 250 0.0004 0.0005 seed 3\ninit xvel 0.1 yvel -0.2 zvel 0.05")
        api.cycle(50)
        self.assertEqual(api.num_balls, len(pos))
        api.positions, api.radii, api.velocities, api.spins = pos, rad, vel, spin
        api.command(SQUEEZE)
        api.cycle(CYCLES)
        support.assert_same_state(self, deck, api, same_step=False)   # the API's 50 cycles more

    def test_set_radii_then_cycle_equals_the_deck(self):
        # Radii alone, on balls at rest whose pair lists, masses and time step are those of balls
        # half as large: the run must be the deck's that makes the large balls at once.
        pos, rad, vel, _ = target_state()
        balls = lambda scale: "".join(f"ball {p[0]!r} {p[1]!r} {p[2]!r} {r * scale!r}\n" for p, r in zip(pos, rad))
        deck = trubal.Session(quiet=True)
        deck.command(SETUP + balls(1.0) + SQUEEZE)
        deck.velocities = vel
        deck.cycle(CYCLES)
        api = trubal.Session(quiet=True)
        api.command(SETUP + balls(0.5))
        api.cycle(50)   # at rest, apart: nothing moves, the lists and the step are of the small balls
        self.assertTrue(support.same_bits(api.positions, pos))
        api.radii = rad
        api.command(SQUEEZE)
        api.velocities = vel
        api.cycle(CYCLES)
        support.assert_same_state(self, deck, api, same_step=False)

    def test_moved_balls_leave_their_old_centres(self):
        # BALL refuses a centre another ball has, from a table of centres it keeps: setting positions
        # must make it look again (the pipeline's own checks would not notice this).
        s = trubal.Session(quiet=True)
        s.command("start box 0 1 0 1 0 1\nball 0.2 0.2 0.2 0.05\nball 0.6 0.6 0.6 0.05")
        s.positions = [[0.3, 0.3, 0.3], [0.7, 0.7, 0.7]]
        s.command("ball 0.2 0.2 0.2 0.05")   # free now
        with self.assertRaisesRegex(trubal.Error, r"ball 1 is already at \(0.3, 0.3, 0.3\)"):
            s.command("ball 0.3 0.3 0.3 0.01")
        self.assertEqual(s.num_balls, 3)

    def test_reads_are_read_only_snapshots(self):
        s = trubal.Session(quiet=True)
        s.run_deck(support.COMPRESS)
        x = s.positions
        with self.assertRaises(ValueError):   # numpy: assignment destination is read-only
            x[0, 0] = 1.0
        y = x.copy()
        y[0, 0] += 1e-4
        self.assertFalse(support.same_bits(y, s.positions))   # a copy changed: the model not
        s.cycle(100)
        self.assertFalse(support.same_bits(x, s.positions))   # the balls moved: the snapshot did not
        s.positions = y
        self.assertEqual(s.positions[0, 0], y[0, 0])

    def test_layout(self):
        s = trubal.Session(quiet=True)
        s.run_deck(support.COMPRESS)
        s.command("fix xvel zspin range id 3")
        n = s.num_balls
        self.assertEqual(list(s.ids), list(range(1, n + 1)))
        for name, shape in (("positions", (n, 3)), ("velocities", (n, 3)), ("spins", (n, 3)), ("forces", (n, 3)),
                            ("moments", (n, 3)), ("radii", (n,)), ("types", (n,)), ("fixed", (n, 6))):
            self.assertEqual(getattr(s, name).shape, shape, name)
        self.assertEqual(s.fixed[2].tolist(), [True, False, False, False, False, True])
        self.assertEqual(int(s.fixed.sum()), 2)
        self.assertTrue(np.all(s.types == 1))
        self.assertTrue(np.all((s.radii >= 0.0006) & (s.radii <= 0.0008)))

    def test_bad_arrays_are_refused_and_change_nothing(self):
        s = trubal.Session(quiet=True)
        s.run_deck(support.COMPRESS)
        before = s.positions
        with self.assertRaisesRegex(ValueError, r"shape \(249, 3\) given, \(250, 3\) needed"):
            s.positions = before[1:]
        bad = before.copy()
        bad[7, 1] = np.nan
        with self.assertRaisesRegex(ValueError, "row 7 holds nan"):
            s.positions = bad
        twin = before.copy()
        twin[9] = twin[4]
        with self.assertRaisesRegex(trubal.Error, "ball 10 is given the centre of another ball"):
            s.positions = twin
        with self.assertRaisesRegex(trubal.Error, "radius must be positive"):
            s.radii = np.zeros(s.num_balls)
        self.assertTrue(support.same_bits(before, s.positions))

    # What numpy's cast would take in silently (a complex part dropped with only a warning, a mask
    # ignored, a string read as a number), and a radius whose mass overflows (CYCLE then blamed the
    # step): each is refused by name, and the model is unchanged and runs on.
    SETTABLE = ("positions", "velocities", "spins", "radii")

    def assert_refused_and_unchanged(self, s, cases):
        before = {name: getattr(s, name) for name in self.SETTABLE}
        for name, value, error, pattern in cases:
            with self.assertRaisesRegex(error, pattern, msg=name):
                setattr(s, name, value)
        for name, value in before.items():
            self.assertTrue(support.same_bits(value, getattr(s, name)), name)
        s.cycle(10)

    def test_complex_numbers_are_refused(self):
        s = trubal.Session(quiet=True)
        s.run_deck(support.COMPRESS)
        cases = []
        for name in self.SETTABLE:
            value = getattr(s, name)
            one = [1j] if value.ndim == 1 else [[1j, 0, 0]]
            cases += [(name, value.astype(complex), TypeError, rf"^{name}: complex numbers given \(dtype complex128\)"),
                      (name, value.tolist()[:-1] + one, TypeError, rf"^{name}: complex numbers given")]   # lists too
        self.assert_refused_and_unchanged(s, cases)

    def test_masked_arrays_are_refused(self):
        s = trubal.Session(quiet=True)
        s.run_deck(support.COMPRESS)
        cases = []
        for name in self.SETTABLE:
            value = getattr(s, name)
            masked = np.ma.masked_array(value.copy(), mask=np.zeros(value.shape, bool))
            masked[3] = np.ma.masked
            cases.append((name, masked, TypeError, rf"^{name}: a masked array is refused"))
        self.assert_refused_and_unchanged(s, cases)

    def test_strings_and_non_finite_numbers_are_refused(self):
        s = trubal.Session(quiet=True)
        s.run_deck(support.COMPRESS)
        cases = []
        for name in self.SETTABLE:
            value = getattr(s, name)
            cases.append((name, value.astype(str), TypeError, rf"^{name}: numbers are needed, dtype <U"))
            for bad in (np.inf, -np.inf, np.nan):
                wrong = value.copy()
                wrong.flat[5] = bad
                cases.append((name, wrong, ValueError, rf"^{name}: row \d+ holds {bad}"))
        self.assert_refused_and_unchanged(s, cases)

    def test_a_radius_beyond_the_space_is_refused(self):
        # At most the START space's diagonal, as BALL: here the periodic cell's, 0.01 * sqrt(3).
        s = trubal.Session(quiet=True)
        s.run_deck(support.COMPRESS)
        cases = []
        for huge in (1e300, 0.02):
            big = s.radii.copy()
            big[3] = huge
            given = re.escape(f"{huge:g}")
            cases.append(("radii", big, trubal.Error, rf"^radii: ball 4 is given radius {given}: the radius must be at "
                                                      r"most the START space's diagonal, 0.0173205"))
        self.assert_refused_and_unchanged(s, cases)

    def test_box_bounds_are_checked(self):
        s = trubal.Session(quiet=True)
        s.command("start box 0 1 0 1 0 1\nball 0.5 0.5 0.5 0.1")
        with self.assertRaisesRegex(trubal.Error, "outside the START box"):
            s.positions = [[0.5, 0.5, 1.5]]
        s.positions = [[0.25, 0.5, 0.5]]   # nested lists are arrays too
        self.assertEqual(s.positions.tolist(), [[0.25, 0.5, 0.5]])

    def test_measurements(self):
        s = trubal.Session(quiet=True)
        s.run_deck(support.COMPRESS)
        s.command("hist stress contacts every 100")
        s.cycle(CYCLES)
        stress = s.stress()
        self.assertEqual(stress.shape, (3, 3))
        self.assertTrue(np.array_equal(stress, stress.T))
        self.assertGreater(np.trace(stress), 0)   # squeezed: compression positive
        # Strain: 100 /s on each axis for CYCLES steps of the model's time (tensor, compression positive);
        # the accumulated strain is the rate times the time to the rounding of CYCLES additions.
        self.assertAlmostEqual(s.strain()[0, 0], 100 * s.time, delta=1e-9)
        table, = s.history()
        self.assertEqual(table["cycle"].tolist(), list(range(100, CYCLES + 1, 100)))
        # The last row is this state's stress (HIST records after the step, as stress() reads now).
        self.assertEqual(table["s11"][-1], stress[0, 0])
        e = s.energy()
        self.assertGreater(e["strain"], 0)
        self.assertGreater(e["damping_work"], 0)
        self.assertTrue(e["at_step"])   # taken at the last step's force pass


    def test_ball_resting_on_a_wall(self):
        # Closed form: at rest on a plane, the contact carries the weight m g and is pressed in by
        # m g / kn. Local damping stops the bounce; after 20000 steps (some 1900 periods of the
        # contact; at 2000 the force is already within 1e-13) 1e-9 is all rounding leaves room for.
        s = trubal.Session(quiet=True)
        s.command("start box -1 1 -1 1 -0.5 1\nprop kn 1e5 ks 1e5 fric 0.5 dens 1000\n"
                  "wall id 1 plane 0 0 0 0 0 1\nball 0 0 0.105 0.1\ngrav 0 0 -9.81\ndamp local 0.7")
        s.cycle(20000)
        weight = 1000 * 4 / 3 * np.pi * 0.1**3 * 9.81
        wall, = s.walls()
        self.assertEqual((wall["id"], wall["kind"], wall["contacts"]), (1, "plane", 1))
        self.assertAlmostEqual(wall["normal_force"] / weight, 1, delta=1e-9)
        self.assertAlmostEqual(wall["force"][2] / weight, -1, delta=1e-9)   # on the wall: pushed down
        self.assertAlmostEqual(s.positions[0, 2], 0.1 - weight / 1e5, delta=1e-9 * 0.1)
        self.assertEqual(len(s.contacts()["i"]), 0)   # ball pairs only: there are none

    def test_bonds(self):
        # Two bonded balls pulled apart break in tension at T A (A = pi (L R)^2): bonds() says which
        # broke, why, and the force that broke it, within one step's increment (1e-4 of it here).
        s = trubal.Session(quiet=True)
        s.command("start box -2 3 -2 2 -2 2\nprop kn 1e8 ks 1e8 mu 0.5 dens 1000\ntstep 1e-5\n"
                  "ball 0 0 0 0.5 id 1\nball 1 0 0 0.5 id 2\n"
                  "bond kn 1e9 ks 4e8 ten 1e5 coh 1e9 rmul 0.8\nfix vel spin\ninit xvel 1.0000317e-3 range id 2")
        b = s.bonds()
        self.assertEqual((b["i"].tolist(), b["j"].tolist(), b["intact"].tolist()), ([1], [2], [True]))
        self.assertAlmostEqual(b["radius"][0], 0.4, delta=1e-15)
        s.cycle(10100)
        b = s.bonds()
        self.assertEqual((b["intact"].tolist(), b["state"].tolist()), ([False], [1]))
        area = np.pi * 0.4**2
        self.assertAlmostEqual(-b["normal_force"][0] / (1e5 * area), 1, delta=2e-4)
        self.assertEqual(b["shear_force"].shape, (1, 3))
        self.assertGreater(s.energy()["bond_break_work"], 0)


if __name__ == "__main__":
    unittest.main()
