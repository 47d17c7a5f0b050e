#!/usr/bin/env python3
"""Rowe's test on octagonal FCC samples of growing size: how the finite sample's peak R = F1/(A sigma2)
approaches Rowe's 2.56, beside the assembly's own sigma1/sigma3 (HIST sratio).

    python3 tools/rowe_size.py [--trubal build/trubal] [--sizes 7,10,14,20] [--strain 0.03]
                               [--out doc/rowe_size]

A sample of size n has large layers of n x n balls (spacing d) with k balls cut from each corner's
diagonals (k(k+1)/2 a corner: n = 7, k = 2 is Cundall's layer of 37; n = 10, k = 3 Rowe's 76), small
layers of (n-1) x (n-1) in the hollows cut alike, and 2 round(1.2 n) + 1 layers (the height grows
with the width, as from Cundall's 403 to Rowe's 1672; n = 7 keeps Cundall's 13). Properties, membrane, consolidation, damping and platen speed are those of
examples/rowe403.dat. For each sample: the membrane's area A (the union of the large layer's cells)
and S = d sum |x - axis| over the membrane faces normal to x, so that the peak R of an ideal
sample is 2.56 S / A (README, "Rowe's triaxial test"). Writes rowe_size.csv and rowe_size.png.
"""
import argparse
import csv
import math
import os
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
D = 40.0
ROWE = 2 * (1 + math.tan(math.radians(7))) / (1 - math.tan(math.radians(7)))


def cut_for(n):
    return {7: 2, 10: 3}.get(n, max(1, round(0.3 * n)))


def large_layer(n, k):
    """Cell offsets (in d, from the axis) of the large layer's balls."""
    m = (n - 1) / 2
    keep = []
    for i in range(n):
        for j in range(n):
            x, y = i - m, j - m
            if abs(x) + abs(y) <= (n - 1) - k + 1e-9:
                keep.append((x, y))
    return keep


def layers_for(n):
    return {7: 13}.get(n, 2 * round(1.2 * n) + 1)   # 7: Cundall's 403-ball sample as it was


def deck(n, k, strain, name):
    nz = layers_for(n)
    c = (n - 1) / 2 * D
    b_large = ((n - 1) - k + 0.5) * D / math.sqrt(2)
    b_small = ((n - 2) - k + 0.5) * D / math.sqrt(2)
    top = (nz - 1) * D / math.sqrt(2)
    cells = large_layer(n, k)
    load = len(cells) * D * D * 5e4            # A p: the platens' consolidation load
    per_ball = load / len(cells)
    height = top
    # platen speed 0.05 each: eps1 = 2 v t / h; the step is about the same for every size
    lo, hi = -5 * D, (n + 4) * D
    return f"""start box {lo} {hi} {lo} {hi} -100 {top + 5 * D}
prop kn 1.5e9 ks 1.5e9 fric 7 dens 2000
lattice fcc {D} {n} {n} {nz} layers even range octagon {c} {c} {c} {b_large}
lattice fcc {D} {n} {n} {nz} layers odd  range octagon {c} {c} {c} {b_small}
group bottom range z -10 10
group top range z {top - 10} {top + 10}
group platens range not z 10 {top - 10}
membrane 5e4
damp 0.05 0.5
apply zforce {-per_ball} range group top
apply zforce {per_ball} range group bottom
cycle 3000
apply zforce 0 range group platens
fix zvel range group platens
init zvel -0.05 range group top
init zvel 0.05 range group bottom
hist ratio axial sratio every 10 file {name}.csv range group platens
""", height, len(cells), nz


def s_over_a(n, k):
    cells = set(large_layer(n, k))
    s = 0.0
    for (x, y) in cells:
        for dx in (-1, 1):
            if (x + dx, y) not in cells:
                s += abs(x)            # a face normal to x at this ball; its distance to the axis, in d
    return s / len(cells)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--trubal", default=os.path.join(HERE, "..", "build", "trubal"))
    p.add_argument("--sizes", default="7,10,14,20")
    p.add_argument("--strain", type=float, default=0.03, help="axial strain to run to")
    p.add_argument("--out", default=tempfile.mkdtemp(prefix="rowe-size-"))
    a = p.parse_args()
    os.makedirs(a.out, exist_ok=True)
    rows = []
    print(f"{'n':>3} {'layer':>6} {'layers':>6} {'balls':>6} {'S/A':>7} {'2.56 S/A':>8} {'peak R':>7} {'peak sratio':>11} {'cycles':>7} {'s':>6}")
    for n in (int(v) for v in a.sizes.split(",")):
        k = cut_for(n)
        name = f"rowe_n{n}"
        text, height, layer, nz = deck(n, k, a.strain, name)
        # cycles to the strain: eps1 = 2 v t / h, with the step of the 403-ball deck (about the same)
        probe = text + "cycle 1\nprint info\n"
        with open(os.path.join(a.out, name + "_probe.dat"), "w") as f:
            f.write(probe)
        info = subprocess.run([a.trubal, name + "_probe.dat"], cwd=a.out, capture_output=True, text=True).stdout
        dt = next(float(l.split()[1]) for l in info.splitlines() if l.startswith("timestep:"))
        balls = next(int(l.split()[1]) for l in info.splitlines() if l.startswith("balls:"))
        cycles = int(math.ceil(a.strain * height / (2 * 0.05) / dt))
        with open(os.path.join(a.out, name + ".dat"), "w") as f:
            f.write(text + f"cycle {cycles}\n")
        t0 = time.time()
        r = subprocess.run([a.trubal, name + ".dat"], cwd=a.out, capture_output=True, text=True)
        seconds = time.time() - t0
        if r.returncode != 0:
            print(f"n={n} failed: {r.stderr[-300:]}")
            continue
        hist = list(csv.DictReader(open(os.path.join(a.out, name + ".csv"))))
        peak_r = max(float(h["ratio"]) for h in hist)
        peak_s = max(float(h["sratio"]) for h in hist)
        sa = s_over_a(n, k)
        rows.append((n, layer, nz, balls, sa, ROWE * sa, peak_r, peak_s, cycles + 3000, seconds))
        print(f"{n:3d} {layer:6d} {nz:6d} {balls:6d} {sa:7.4f} {ROWE * sa:8.4f} {peak_r:7.4f} {peak_s:11.4f} {cycles + 3000:7d} {seconds:6.1f}")
    with open(os.path.join(a.out, "rowe_size.csv"), "w") as f:
        f.write("n,layer,layers,balls,S_over_A,ideal_R,peak_R,peak_sratio,cycles,seconds\n")
        for row in rows:
            f.write(",".join(str(v) for v in row) + "\n")
    script = f"""set terminal png size 900,600 noenhanced
set output '{os.path.join(a.out, "rowe_size.png")}'
set datafile separator ','
set title "Rowe's test, octagonal FCC samples: peak stress ratio against layer size"
set xlabel 'balls in a large layer'
set ylabel 'peak stress ratio'
set key bottom right
set grid
set yrange [1.9:2.7]
plot '{os.path.join(a.out, "rowe_size.csv")}' using 2:7 skip 1 with linespoints title 'peak R = F1/(A sigma2)', \\
     '' using 2:6 skip 1 with linespoints dashtype 2 title '2.56 S/A (ideal sample)', \\
     '' using 2:8 skip 1 with linespoints title 'peak sratio (sigma1/sigma3 of the assembly)', \\
     {ROWE} with lines dashtype 3 title 'Rowe 2 tan(45+phi_mu) = 2.56'
"""
    subprocess.run(["gnuplot"], input=script, text=True, check=True)
    print(f"wrote {a.out}/rowe_size.csv and rowe_size.png")
    return 0


if __name__ == "__main__":
    sys.exit(main())
