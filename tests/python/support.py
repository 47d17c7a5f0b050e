"""What the Python tests share: where things are, and what "the same bits" means."""
import os
import pathlib
import sys

import numpy as np

HERE = pathlib.Path(__file__).resolve().parent
COMPRESS = str(HERE / "compress.dat")   # a periodic packing squeezed until its balls touch and slide
TRUBAL_EXE = os.environ.get("TRUBAL_EXE", "")

try:
    import trubal  # noqa: F401  (PYTHONPATH=build/python, set by ctest)
except ImportError as e:
    sys.exit(f"cannot import the trubal module ({e}); ctest sets PYTHONPATH to build/python")


def same_bits(a, b):
    """Arrays equal bit for bit: same shape, and every double the same 64 bits (-0 is not 0)."""
    a, b = np.ascontiguousarray(a), np.ascontiguousarray(b)
    return a.shape == b.shape and a.dtype == b.dtype and bool(np.all(a.view(np.uint8) == b.view(np.uint8)))


def ball_state(s):
    """Everything cycling changes about the balls, by id."""
    return {"positions": s.positions, "velocities": s.velocities, "spins": s.spins, "forces": s.forces,
            "moments": s.moments}


def assert_same_state(case, s1, s2, same_step=True):
    case.assertGreater(s1.num_balls, 0)
    for name, a in ball_state(s1).items():
        case.assertTrue(same_bits(a, ball_state(s2)[name]), f"{name} differ")
    c1, c2 = s1.contacts(), s2.contacts()
    case.assertGreater(len(c1["i"]), 0, "the scene should have contacts")
    for name in ("i", "j", "normal", "overlap", "normal_force", "shear_force", "force", "sliding"):
        case.assertTrue(same_bits(c1[name], c2[name]), f"contacts' {name} differ")
    # Every part of the history the contact law declares, by name; the shear spring's is shear_force.
    case.assertEqual(sorted(c1["history"]), sorted(c2["history"]))
    for name in c1["history"]:
        case.assertTrue(same_bits(c1["history"][name], c2["history"][name]), f"contacts' history {name} differ")
    for k, name in enumerate(("fsx", "fsy", "fsz")):
        case.assertTrue(same_bits(c1["history"][name], c1["shear_force"][:, k]), f"history {name} is not shear_force")
    if same_step:
        case.assertEqual(s1.step, s2.step)
