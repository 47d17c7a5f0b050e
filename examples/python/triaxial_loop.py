"""Drained triaxial compression at three confining pressures, in a loop: trubal from Python.

A notebook-style script (plain Python; run it as it is, or cell by cell in an editor that knows
`# %%`). It is examples/periodic_triaxial.dat made parametric and shorter: what the command
language cannot do on its own (it has no loops or arithmetic) is here a for loop over pressures,
a callback that records the curves and stops each test at the target strain, and numpy.

Run from anywhere, with the module on the path (doc/python.md):
    PYTHONPATH=build/python /usr/bin/python3 examples/python/triaxial_loop.py
It writes triaxial_loop.csv and triaxial_loop.png into the current folder (about 15 s).
"""
# %% Setup
import shutil
import subprocess
import sys
import time

import numpy as np

import trubal

PRESSURES = [50e3, 100e3, 200e3]   # confining stress, Pa
AXIAL_STRAIN = 0.10                # each test stops here (strain counted from the start of shearing)
RECORD_EVERY = 250                 # cycles between two points of a curve


# %% One test: the command language builds and consolidates the sample, Python drives the shear.
def triaxial(pressure):
    s = trubal.Session(quiet=True)
    # The sample of periodic_triaxial.dat: 400 balls anywhere in a periodic cell (SI units).
    s.command(f"""
        start 0.01 0.01 0.01
        prop kn 1e5 ks 1e5 fric 26.57 dens 2650
        gen 400 0.0004 0.0006 seed 7
        damp local 0.7
        servo {pressure} {pressure} {pressure}
    """)

    # Isotropic consolidation: until the mean stress is within 1% of the target and the packing is
    # near equilibrium (SOLVE's measure, from the contact forces), at most 20000 cycles.
    def consolidated(s):
        mean = np.trace(s.stress()) / 3
        forces = np.linalg.norm(s.forces, axis=1).mean()
        contact = np.linalg.norm(s.contacts()["force"], axis=1).mean()
        return not (abs(mean / pressure - 1) < 0.01 and forces < 0.01 * contact)   # False: stop
    s.cycle(20000, every=500, callback=consolidated)
    # The cell's edges shrink as exp(-strain) (strain() is logarithmic, compression positive).
    volume = 1e-6 * np.exp(-s.strain().diagonal().sum())
    print(f"  {pressure / 1e3:.0f} kPa: consolidated after {s.step} cycles, "
          f"porosity {1 - (4 / 3 * np.pi * s.radii**3).sum() / volume:.3f}")

    # Shear, as the deck: the z edge shortens at 2 /s while the servo holds the lateral stresses.
    s.command(f"servo xx {pressure} yy {pressure}\nstrain zz 2")
    start = s.strain().diagonal().copy()
    # axial strain, deviator stress q = s33 - (s11 + s22)/2, volumetric strain, coordination number,
    # and the lateral stresses' largest error (how well the servo holds them)
    curve = []

    def record(s):
        e = s.strain().diagonal() - start          # compression positive
        sigma = s.stress().diagonal()
        c = s.contacts()
        curve.append((e[2], sigma[2] - (sigma[0] + sigma[1]) / 2, e.sum(), 2 * len(c["i"]) / s.num_balls,
                      np.abs(sigma[:2] / pressure - 1).max()))
        return e[2] < AXIAL_STRAIN                 # False stops the run
    s.cycle(10**6, every=RECORD_EVERY, callback=record)
    return np.array(curve)


# %% The loop over pressures
t0 = time.time()
curves = {}
for p in PRESSURES:
    curves[p] = triaxial(p)
    q = curves[p][:, 1]
    print(f"  {p / 1e3:.0f} kPa: peak deviator {q.max() / 1e3:.1f} kPa (q/p {q.max() / p:.2f}), lateral stresses "
          f"held within {100 * curves[p][:, 4].max():.2f}%")
print(f"three tests in {time.time() - t0:.1f} s")

with open("triaxial_loop.csv", "w") as f:
    f.write("pressure,axial_strain,deviator,volumetric_strain,coordination,lateral_error\n")
    for p, c in curves.items():
        for row in c:
            f.write(f"{p!r}," + ",".join(repr(float(v)) for v in row) + "\n")


# %% Plot: matplotlib where it is installed (Debian: python3-matplotlib), else gnuplot.
def plot_matplotlib():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (top, bottom) = plt.subplots(2, 1, sharex=True, figsize=(7, 7))
    for p, c in curves.items():
        top.plot(100 * c[:, 0], c[:, 1] / 1e3, label=f"{p / 1e3:.0f} kPa")
        bottom.plot(100 * c[:, 0], 100 * c[:, 2], label=f"{p / 1e3:.0f} kPa")
    top.set_ylabel("deviator stress q (kPa)")
    top.set_title("Drained triaxial compression, periodic cell, 400 balls")
    top.legend(title="confining")
    bottom.set_ylabel("volumetric strain (%, compression +)")
    bottom.set_xlabel("axial strain (%)")
    for ax in (top, bottom):
        ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig("triaxial_loop.png", dpi=110)


def plot_gnuplot():
    script = ["if (strstrt(GPVAL_TERMINALS, 'pngcairo') > 0) { set terminal pngcairo size 770,770 } "
              "else { set terminal png size 770,770 }",
              "set output 'triaxial_loop.png'", "set datafile separator ','",
              "set multiplot layout 2,1", "set grid", "set ylabel 'deviator stress q (kPa)'", "set key top left"]
    series = lambda col, scale: ", ".join(
        f"'triaxial_loop.csv' using ($1=={p!r} ? 100*$2 : 1/0):(${col}*{scale}) with lines title '{p / 1e3:.0f} kPa'"
        for p in curves)
    script += ["plot " + series(3, 1e-3), "set ylabel 'volumetric strain (%)'", "set xlabel 'axial strain (%)'",
               "plot " + series(4, 100), "unset multiplot"]
    subprocess.run(["gnuplot"], input="\n".join(script), text=True, check=True)


try:
    plot_matplotlib()
except ImportError:
    if not shutil.which("gnuplot"):
        sys.exit("no plot: neither matplotlib (python3-matplotlib) nor gnuplot is installed")
    plot_gnuplot()
print("wrote triaxial_loop.csv and triaxial_loop.png")
