#!/usr/bin/env python3
"""Speed against error (issue 7): runs the head-on impact cases of VALIDATION.md at several FRAC values,
the oblique and spinning impacts of Chung & Ooi's tests 4-8, and the FCC-strength and Rowe examples
(cycle counts scaled so each run covers the same physical time), measures the loop's wall time and the
error against the closed form (contact time, rebound speed, peak overlap), against rigid-body theory
(oblique impacts in gross sliding) or against a converged run, and writes CSVs, a log-log PNG per case
(gnuplot) and Markdown tables.

    python3 tools/speed_vs_error.py [--trubal build/trubal] [--out speed_vs_error]
        [--oblique-only | --quasi-static-only | --cases a,b]

Standard library only. Each deck holds many identical impacts side by side (far apart), so that the wall
time is measurable; the error is taken from one of them (all are alike to rounding).
  - contact time: the balls move on straight lines before and after contact, so contact starts at
    t_s = gap0 / v (exact) and ends at t_e = T - gap_end / v_out, from the final positions (PRINT balls);
  - rebound: v_out / v_in;
  - peak overlap: from the largest strain energy recorded every step (HIST energy every 1),
    0.5 kn U^2 (linear) or 2/5 F U (Hertz), per impact.
"""
import argparse
import csv
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile

FRACS = [0.05, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.95]
DEFAULT_FRAC = 0.8
REPEAT = 3   # each timed deck runs this many times; the shortest loop counts (the machine is shared)


def timed(trubal, path, work, repeat=None):
    """Runs a deck `repeat` times (the results are bitwise the same); returns the last run and the
    shortest total of its CYCLE loops' wall times."""
    best, out = float("inf"), None
    for _ in range(repeat or REPEAT):
        out = subprocess.run([trubal, path], cwd=work, capture_output=True, text=True)
        if out.returncode != 0:
            return out, float("nan")
        best = min(best, sum(float(t) for _, t in re.findall(r"\((\d+) cycles in ([0-9.]+) s", out.stdout)))
    return out, best


def sphere_mass(rho, r):
    return rho * 4.0 / 3.0 * math.pi * r ** 3


def series(a, b):
    return a * b / (a + b)


# Each case: two equal balls at +-v/2 (pairs) or a ball flying into a large fixed ball (plane).
CASES = [
    dict(name="linear", title="two balls, linear law (VALIDATION 1)", law="linear", kn=1e5, rho=2650, R=0.01,
         v=1.0, layout="pairs"),
    dict(name="hertz", title="two balls, Hertz (VALIDATION 2; C&O 1 limestone)", law="hertz", E=2.0e10, nu=0.25,
         rho=2500, R=0.010, v=20.0, layout="pairs"),
    dict(name="co1_glass", title="Chung & Ooi 1, glass spheres +-10 m/s", law="hertz", E=4.8e10, nu=0.20, rho=2800,
         R=0.010, v=20.0, layout="pairs", table=dict(overlap=274.1e-6, time=40.34e-6)),
    dict(name="co2_al", title="Chung & Ooi 2, Al alloy sphere on a rigid plane, 0.2 m/s", law="hertz", E=7.0e10,
         nu=0.33, rho=2699, R=0.10, v=0.2, layout="plane", table=dict(overlap=49.3e-6, time=725.7e-6)),
    dict(name="co2_mg", title="Chung & Ooi 2, Mg alloy sphere on a rigid plane, 0.2 m/s", law="hertz", E=4.0e10,
         nu=0.35, rho=1800, R=0.10, v=0.2, layout="plane", table=dict(overlap=52.1e-6, time=767.1e-6)),
    dict(name="co3_aloxide", title="Chung & Ooi 3, Al oxide on a rigid plane, 3.9 m/s", law="hertz", E=3.8e11,
         nu=0.23, rho=4000, R=0.0025, v=3.9, layout="plane", table=dict(overlap=8.09e-6, time=6.10e-6)),
]


def closed_form(c):
    """Contact time, rebound ratio and peak overlap of the model trubal builds for case c."""
    m = sphere_mass(c["rho"], c["R"])
    if c["layout"] == "pairs":
        ms, rs = m / 2, c["R"] / 2
    else:   # a fixed ball of radius 1000 R, 1e4 times stiffer: a rigid plane
        ms, rs = m, c["R"] * 1000 / 1001
    v = c["v"]
    if c["law"] == "linear":
        k = c["kn"]
        return dict(time=math.pi * math.sqrt(ms / k), rebound=1.0, overlap=v * math.sqrt(ms / k), ms=ms, rs=rs)
    g = c["E"] / (2 * (1 + c["nu"]))
    a = 2 * g / (1 - c["nu"])
    b = 2 * g * 1e4 / (1 - c["nu"]) if c["layout"] == "plane" else a
    estar = series(a, b)   # trubal's mixed Hertz modulus; equal materials: G / (1 - nu)
    tc = 2.868 * (ms ** 2 / (rs * estar ** 2 * v)) ** 0.2
    d = (15 * ms * v ** 2 / (16 * estar * math.sqrt(rs))) ** 0.4
    return dict(time=tc, rebound=1.0, overlap=d, ms=ms, rs=rs, estar=estar)


def deck(c, frac, count, cf):
    """The deck text; returns (text, gap0, steps-independent end time)."""
    r, v = c["R"], c["v"]
    gap0 = 0.02 * cf["overlap"]
    t_end = gap0 / v + 1.25 * cf["time"]
    lines = ["start box -1e3 1e3 -1e3 1e3 -1e3 1e3"]
    if c["law"] == "linear":
        lines.append(f"prop type 1 kn {c['kn']!r} ks {c['kn']!r} fric 0 dens {c['rho']!r}")
    else:
        g = c["E"] / (2 * (1 + c["nu"]))
        lines.append(f"prop type 1 shear {g!r} poisson {c['nu']!r} dens {c['rho']!r} fric 0")
        if c["layout"] == "plane":
            lines.append(f"prop type 2 shear {g * 1e4!r} poisson {c['nu']!r} dens {c['rho']!r} fric 0")
    side = int(math.ceil(math.sqrt(count)))
    if c["layout"] == "pairs":
        pitch = 4 * r
        k = 0
        for iy in range(side):
            for iz in range(side):
                if k >= count:
                    break
                y, z = iy * pitch, iz * pitch
                lines.append(f"ball {-(r + gap0 / 2)!r} {y!r} {z!r} {r!r} id {2 * k + 1}")
                lines.append(f"ball {r + gap0 / 2!r} {y!r} {z!r} {r!r} id {2 * k + 2}")
                k += 1
        lines.append(f"init xvel {v / 2!r} range x -1e3 0")
        lines.append(f"init xvel {-v / 2!r} range x 0 1e3")
    else:
        # balls on a sphere around one fixed large ball, each flying at it along the radius
        big = 1000 * r
        lines.append(f"ball 0 0 0 {big!r} id 1 type 2")
        golden = math.pi * (3 - math.sqrt(5))
        for k in range(count):
            zc = 1 - 2 * (k + 0.5) / count
            s = math.sqrt(1 - zc * zc)
            nx, ny, nz = s * math.cos(golden * k), s * math.sin(golden * k), zc
            d = big + r + gap0
            lines.append(f"ball {d * nx!r} {d * ny!r} {d * nz!r} {r!r} id {k + 2}")
            lines.append(f"init xvel {-v * nx!r} yvel {-v * ny!r} zvel {-v * nz!r} range id {k + 2}")
        lines.append("fix xvel yvel zvel xspin yspin zspin range id 1")
    lines.append(f"frac {frac!r}")
    lines.append("hist time energy every 1 file hist.csv")
    lines.append("cycle 1")   # the step is estimated at the first cycle
    return "\n".join(lines) + "\n", gap0, t_end


def run_case(trubal, c, frac, count, work):
    cf = closed_form(c)
    text, gap0, t_end = deck(c, frac, count, cf)
    # the step is steady until contact (no contact: the lone-ball estimate); find it with one cycle
    path = os.path.join(work, "probe.dat")
    with open(path, "w") as f:
        f.write(text)
    out = subprocess.run([trubal, path], cwd=work, capture_output=True, text=True)
    if out.returncode != 0:
        raise RuntimeError(out.stdout + out.stderr)
    with open(os.path.join(work, "hist.csv")) as f:
        rows = list(csv.DictReader(f))
    dt = float(rows[-1]["time"])
    steps = int(math.ceil(t_end / dt)) + 5
    text = text.replace("cycle 1\n", f"cycle {steps}\nprint balls file balls.csv\n")
    with open(path, "w") as f:
        f.write(text)
    out, wall = timed(trubal, path, work)
    if out.returncode != 0:
        raise RuntimeError(out.stdout + out.stderr)
    with open(os.path.join(work, "hist.csv")) as f:
        rows = list(csv.DictReader(f))
    T = float(rows[-1]["time"])
    peak_strain = max(float(r["strain_energy"]) for r in rows)
    with open(os.path.join(work, "balls.csv")) as f:
        balls = {int(r["id"]): r for r in csv.DictReader(f)}
    impacts = count
    per = peak_strain / impacts
    if c["law"] == "linear":
        overlap = math.sqrt(2 * per / c["kn"])
    else:
        coef = 4.0 / 3.0 * cf["estar"] * math.sqrt(cf["rs"])   # F = coef U^1.5, energy 2/5 coef U^2.5
        overlap = (2.5 * per / coef) ** 0.4
    if c["layout"] == "pairs":
        a, b = balls[1], balls[2]
        gap_end = float(b["x"]) - float(a["x"]) - 2 * c["R"]
        v_out = float(b["vx"]) - float(a["vx"])
    else:
        a = balls[2]
        pos = [float(a[k]) for k in ("x", "y", "z")]
        vel = [float(a[k]) for k in ("vx", "vy", "vz")]
        dist = math.sqrt(sum(p * p for p in pos))
        gap_end = dist - 1000 * c["R"] - c["R"]
        v_out = sum(p * q for p, q in zip(pos, vel)) / dist
    if v_out <= 0 or gap_end <= 0:
        raise RuntimeError(f"{c['name']} FRAC {frac}: the balls had not parted after {steps} steps")
    t_c = T - gap_end / v_out - gap0 / c["v"]
    rebound = v_out / c["v"]
    return dict(case=c["name"], frac=frac, dt=dt, steps=steps, balls=len(balls), wall_s=wall,
                contact_time=t_c, contact_time_exact=cf["time"], err_time=abs(t_c / cf["time"] - 1),
                rebound=rebound, err_rebound=abs(rebound - 1),
                peak_overlap=overlap, peak_overlap_exact=cf["overlap"], err_overlap=abs(overlap / cf["overlap"] - 1))


# Quasi-static cases: an example deck run with its FRAC replaced, judged on its peak stress ratio.
QUASI_STATIC = [
    dict(name="fcc_strength", title="FCC strength, axisymmetric, f = 0.3 (VALIDATION 4)",
         deck="fcc_axisymmetric.dat", history="fcc_axisymmetric_history.csv", exact=2 * 1.3 / 0.7),
    dict(name="rowe403", title="Rowe triaxial test, 403 balls (VALIDATION 5)", deck="rowe403.dat",
         history="rowe403_history.csv", exact=None),   # no closed form for the finite sample: the finest run
]
QUASI_FRACS = [0.1, 0.2, 0.4, 0.6, 0.8]


def run_quasi_static(trubal, c, frac, examples, work, backend="serial"):
    """Peak `ratio` and the cycling wall time of an example deck at this FRAC on a backend."""
    with open(os.path.join(examples, c["deck"])) as f:
        source = f.readlines()
    # The same physical run: the cycle counts grow as the step shrinks against the deck's own FRAC.
    own = next((float(l.split()[1]) for l in source if l.strip().lower().startswith("frac ")), DEFAULT_FRAC)
    lines = [f"backend {backend}\n"]
    for line in source:
        words = line.split()
        word = words[0].lower() if words else ""
        if word == "plot":
            continue
        if word == "frac":
            line = f"frac {frac!r}\n"
        if word == "cycle":
            line = f"cycle {int(math.ceil(int(words[1]) * own / frac))}\n"
        lines.append(line)
        if word == "prop" and not any(l.strip().lower().startswith("frac ") for l in source):
            lines.append(f"frac {frac!r}\n")   # decks without FRAC get it after their PROP
    path = os.path.join(work, c["deck"])
    with open(path, "w") as f:
        f.writelines(lines)
    out, wall = timed(trubal, path, work)
    if out.returncode != 0:
        return dict(case=c["name"], backend=backend, frac=frac, wall_s=float("nan"), peak=float("nan"),
                    note=out.stderr.strip()[-200:])
    with open(os.path.join(work, c["history"])) as f:
        peak = max(float(r["ratio"]) for r in csv.DictReader(f))
    return dict(case=c["name"], backend=backend, frac=frac, wall_s=wall, peak=peak, note="")


def quasi_static_section(trubal, examples, work, outdir):
    table = ["| case | backend | FRAC | wall s (cycling) | peak ratio | error | against |",
             "|---|---|---|---|---|---|---|"]
    rows_all = []
    for c in QUASI_STATIC:
        per_backend = {}
        for backend in ("serial", "threaded threads 2"):
            rows = [run_quasi_static(trubal, c, frac, examples, work, backend) for frac in QUASI_FRACS]
            finest = rows[0]["peak"]
            ref, against = (c["exact"], "closed form") if c["exact"] else (finest, f"FRAC {QUASI_FRACS[0]}")
            for r in rows:
                r["error"] = abs(r["peak"] / ref - 1) if r["peak"] == r["peak"] else float("nan")
                mark = " **(default)**" if abs(r["frac"] - DEFAULT_FRAC) < 1e-12 else ""
                status = f"{r['peak']:.6f}" if not r["note"] else f"stopped: {r['note']}"
                table.append(f"| {c['name']} | {backend} | {r['frac']:g}{mark} | {r['wall_s']:.3f} | {status} | "
                             f"{r['error']:.2e} | {against} ({ref:.4f}) |")
                print(f"{c['name']:12s} {backend:18s} FRAC {r['frac']:4.2f}  {r['wall_s']:.3f} s  "
                      f"peak {r['peak']:.6f}  err {r['error']:.2e}", flush=True)
            per_backend[backend] = rows
            rows_all += rows
        plot_quasi_static(c, per_backend, outdir)
    return table, rows_all


def plot_quasi_static(c, per_backend, outdir):
    if not shutil.which("gnuplot"):
        return
    plots = []
    for k, (backend, rows) in enumerate(per_backend.items()):
        dat = os.path.join(outdir, f"{c['name']}_{k}.dat")
        with open(dat, "w") as f:
            for r in rows:
                if r["error"] > 0:   # the reference run itself has no error to draw
                    f.write(f"{r['wall_s']} {r['error']} {r['frac']}\n")
        plots.append(f"'{c['name']}_{k}.dat' u 1:2 w lp t '{backend}', '' u 1:2:(sprintf('%.2g', $3)) "
                     f"w labels offset 1.5,0.5 font ',8' notitle")
    script = (f"set terminal pngcairo size 800,600 noenhanced\nset output '{c['name']}.png'\nset logscale xy\n"
              f"set xlabel 'wall time of the cycles (s)'\nset ylabel 'relative error of the peak ratio'\n"
              f"set title \"{c['title']}\"\nplot " + ", ".join(plots) + "\n")
    res = subprocess.run(["gnuplot"], input=script, text=True, cwd=outdir, capture_output=True)
    if res.returncode != 0:
        subprocess.run(["gnuplot"], input=script.replace("pngcairo", "png"), text=True, cwd=outdir,
                       capture_output=True)


def write_quasi_static(outdir, table, rows):
    with open(os.path.join(outdir, "quasi_static.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        w.writeheader()
        w.writerows(rows)
    with open(os.path.join(outdir, "quasi_static.md"), "w") as f:
        f.write("\n".join(table) + "\n")


# Oblique and spinning impacts (Chung & Ooi tests 4-8, VALIDATION 3). Each deck holds many impacts of one
# set-up, the samples (angles, tangential speeds or spins) side by side, so that one run gives the whole
# curve at one FRAC. A mover meets a target: "plane" (a fixed ball of PLANE R, 1e4 times stiffer: test 2
# uses 1000 R, but a mover sliding across so small a sphere sees its normal turn by Vt t_c / (1000 R),
# 1e-3 of the tangential change at Vt/(mu Vn) = 20), "pair" (an equal ball coming the other way, test 7) or "big" (a fixed ball of 5 R of the same
# material, test 8). In each impact's own frame n (from the target's centre to the mover), t (the
# tangential direction of the incoming contact point) and the spin axis t x n, the mover comes in with
# normal speed Vn, tangential speed Vt and spin w, so that its contact point slides at Vc = Vt + R w.
# Rigid-body theory (VALIDATION 3): gross sliding when Vc > 3.5 mu (1 + e) Vn; then the tangential
# speed drops by mu (1 + e) Vn and the spin by 2.5 mu (1 + e) Vn / R (for the pair, Vn is each ball's
# own speed). Errors are those of the two changes: against the rigid-body values on the samples that
# slide throughout, and against a converged reference run (FRAC_REF) on all samples, each relative to
# its gross-sliding value (so that sticking samples, whose changes are small, are not magnified).
FRAC_REF = 0.0125
PLANE = 1e5
ANGLES = [5, 10, 15, 20, 25, 30, 35, 40, 45, 50, 55, 60, 65, 70, 75, 80, 85]
PSIS = [0.5, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 12, 14, 16, 20]
SPINS = [0.175, 0.3, 0.5, 1, 1.5, 2, 3, 4, 5, 6, 8, 10, 14, 21]
AL_ALLOY = dict(E=7.0e10, nu=0.33, rho=2699)
OBLIQUE = [
    dict(name="co4_aloxide", test=4, title="Chung & Ooi 4, Al oxide on a rigid plane, 3.9 m/s at 5-85 deg",
         E=3.8e11, nu=0.23, rho=4000, R=0.0025, mu=0.092, e=0.98, target="plane", speed=3.9, angles=ANGLES),
    dict(name="co4_alalloy", test=4, title="Chung & Ooi 4, Al alloy on a rigid plane, 3.9 m/s at 5-85 deg",
         R=0.0025, mu=0.092, e=0.98, target="plane", speed=3.9, angles=ANGLES, **AL_ALLOY),
    dict(name="co5_steel", test=5, title="Chung & Ooi 5, steel on a rigid plane, Vn 5 m/s, Vt/(mu Vn) 0.5-20",
         E=2.08e11, nu=0.3, rho=7850, R=0.01, mu=0.3, e=1.0, target="plane", vn=5.0, psis=PSIS),
    dict(name="co5_polyeth", test=5, title="Chung & Ooi 5, polyethylene on a rigid plane, Vn 5 m/s, "
         "Vt/(mu Vn) 0.5-20", E=1.0e9, nu=0.4, rho=1400, R=0.01, mu=0.3, e=1.0, target="plane", vn=5.0, psis=PSIS),
    dict(name="co6_alalloy", test=6, title="Chung & Ooi 6, Al alloy on a rigid plane, Vn 0.2 m/s, spin 0.175-21 rad/s",
         R=0.1, mu=0.4, e=0.5, target="plane", vn=0.2, spins=SPINS, **AL_ALLOY),
    dict(name="co6_nylon", test=6, title="Chung & Ooi 6, nylon on a rigid plane, Vn 0.2 m/s, spin 0.175-21 rad/s",
         E=2.5e9, nu=0.4, rho=1000, R=0.1, mu=0.4, e=0.5, target="plane", vn=0.2, spins=SPINS),
    dict(name="co7_alalloy", test=7, title="Chung & Ooi 7, two Al alloy spheres +-0.2 m/s, spin 0.175-21 rad/s",
         R=0.1, mu=0.4, e=0.5, target="pair", vn=0.2, spins=SPINS, **AL_ALLOY),
    dict(name="co7_copper", test=7, title="Chung & Ooi 7, two copper spheres +-0.2 m/s, spin 0.175-21 rad/s",
         E=1.2e11, nu=0.35, rho=8900, R=0.1, mu=0.4, e=0.5, target="pair", vn=0.2, spins=SPINS),
    dict(name="co8_alalloy", test=8, title="Chung & Ooi 8, Al alloy sphere on a fixed one of 5 R, Vn 0.2 m/s, "
         "spin 0.175-21 rad/s", R=0.1, mu=0.4, e=0.5, target="big", vn=0.2, spins=SPINS, **AL_ALLOY),
    dict(name="co8_nylon", test=8, title="Chung & Ooi 8, nylon sphere on a fixed one of 5 R, Vn 0.2 m/s, "
         "spin 0.175-21 rad/s", E=2.5e9, nu=0.4, rho=1000, R=0.1, mu=0.4, e=0.5, target="big", vn=0.2,
         spins=SPINS),
]


def oblique_samples(c):
    """(x, Vn, Vt, w) per sample: x is what the benchmark plots against."""
    if "angles" in c:
        return [(a, c["speed"] * math.cos(math.radians(a)), c["speed"] * math.sin(math.radians(a)), 0.0)
                for a in c["angles"]]
    if "psis" in c:
        return [(p, c["vn"], p * c["mu"] * c["vn"], 0.0) for p in c["psis"]]
    return [(w, c["vn"], 0.0, w) for w in c["spins"]]


def oblique_contact(c, vn):
    """m*, R*, E* and the Hertz contact time and peak overlap of one impact at normal speed vn."""
    m = sphere_mass(c["rho"], c["R"])
    g = c["E"] / (2 * (1 + c["nu"]))
    own = 2 * g / (1 - c["nu"])
    if c["target"] == "plane":
        ms, rs, estar, v = m, c["R"] * PLANE / (PLANE + 1), series(own, 1e4 * own), vn
    elif c["target"] == "pair":
        ms, rs, estar, v = m / 2, c["R"] / 2, own / 2, 2 * vn
    else:
        ms, rs, estar, v = m, c["R"] * 5 / 6, own / 2, vn
    tc = 2.868 * (ms ** 2 / (rs * estar ** 2 * v)) ** 0.2
    d = (15 * ms * v ** 2 / (16 * estar * math.sqrt(rs))) ** 0.4
    return tc, d


def oblique_deck(c, frac, count):
    """Deck text, the end time, and per impact (sample index, mover id, n, t) in the order of the ids."""
    r = c["R"]
    samples = oblique_samples(c)
    g = c["E"] / (2 * (1 + c["nu"]))
    rest = f" rest {c['e']!r}" if c["e"] < 1 else ""
    lines = ["start box -1e5 1e5 -1e5 1e5 -1e5 1e5",
             f"prop type 1 shear {g!r} poisson {c['nu']!r} dens {c['rho']!r} mu {c['mu']!r}{rest}"]
    stiff = 1e4 if c["target"] == "plane" else 1.0
    lines.append(f"prop type 2 shear {g * stiff!r} poisson {c['nu']!r} dens {c['rho']!r} mu {c['mu']!r}{rest}")
    impacts, t_end = [], 0.0
    golden = math.pi * (3 - math.sqrt(5))
    side = int(math.ceil(math.sqrt(count)))
    for k in range(count):
        s = k % len(samples)
        _, vn, vt, w = samples[s]
        tc, d = oblique_contact(c, vn)
        gap = 0.02 * d
        t_end = max(t_end, gap / vn + 1.25 * tc)
        mover = k + 1
        if c["target"] == "plane":
            zc = 1 - 2 * (k + 0.5) / count
            sr = math.sqrt(1 - zc * zc)
            n = (sr * math.cos(golden * k), sr * math.sin(golden * k), zc)
            a = (0.0, 0.0, 1.0) if abs(n[2]) < 0.9 else (1.0, 0.0, 0.0)
            t = cross(a, n)
            tn = math.sqrt(dot(t, t))
            t = tuple(x / tn for x in t)
            pos = tuple((PLANE * r + r + gap) * x for x in n)
            lines.append(f"ball {pos[0]!r} {pos[1]!r} {pos[2]!r} {r!r} id {mover}")
        else:
            # rows of (mover, target) along x; the target is the ball coming the other way or a fixed 5 R ball
            big = r if c["target"] == "pair" else 5 * r
            pitch = 2 * (r + big) + 4 * r
            y, z = (k // side) * pitch, (k % side) * pitch
            n, t = (-1.0, 0.0, 0.0), (0.0, 1.0, 0.0)
            half = gap / 2 if c["target"] == "pair" else gap
            lines.append(f"ball {-(r + half)!r} {y!r} {z!r} {r!r} id {mover}")
            target_id = count + 1 + k
            lines.append(f"ball {big + gap - half!r} {y!r} {z!r} {big!r} id {target_id} type 2")
            if c["target"] == "pair":   # the mirror image: same spin vector, so the surfaces slide at 2 R w
                lines.append(f"init xvel {-vn!r} zspin {w!r} range id {target_id}")
        v = tuple(-vn * a + vt * b for a, b in zip(n, t))
        spin = tuple(w * x for x in cross(t, n))
        lines.append(f"init xvel {v[0]!r} yvel {v[1]!r} zvel {v[2]!r} xspin {spin[0]!r} yspin {spin[1]!r} "
                     f"zspin {spin[2]!r} range id {mover}")
        impacts.append((s, mover, n, t))
    if c["target"] == "plane":
        lines.append(f"ball 0 0 0 {PLANE * r!r} id {count + 1} type 2")
        lines.append(f"fix vel spin range id {count + 1}")
    elif c["target"] == "big":
        lines.append(f"fix vel spin range id {count + 1} {2 * count}")
    lines.append(f"frac {frac!r}")
    return "\n".join(lines) + "\n", t_end, impacts


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def dot(a, b):
    return sum(x * y for x, y in zip(a, b))


def run_oblique(trubal, c, frac, count, work):
    """One deck at this FRAC: wall time and, per sample, the rebound of its first impact."""
    text, t_end, impacts = oblique_deck(c, frac, count)
    path = os.path.join(work, "oblique.dat")
    with open(path, "w") as f:
        f.write(text + "hist time every 1 file hist.csv\ncycle 1\n")
    out = subprocess.run([trubal, path], cwd=work, capture_output=True, text=True)
    if out.returncode != 0:
        raise RuntimeError(out.stdout + out.stderr)
    with open(os.path.join(work, "hist.csv")) as f:
        dt = float(list(csv.DictReader(f))[-1]["time"])
    # The held step may shrink in contact at large FRAC: room for that, and the balls fly freely after.
    steps = int(math.ceil(1.2 * t_end / dt)) + 5
    with open(path, "w") as f:
        f.write(text + f"cycle {steps}\nprint balls file balls.csv\n")
    out, wall = timed(trubal, path, work, 1 if count < 1000 else None)   # the reference run is not timed
    if out.returncode != 0:
        raise RuntimeError(out.stdout + out.stderr)
    with open(os.path.join(work, "balls.csv")) as f:
        balls = {int(b["id"]): b for b in csv.DictReader(f)}
    samples = oblique_samples(c)
    first = {}
    for s, mover, n, t in impacts:
        first.setdefault(s, (mover, n, t))
    r, mu, e = c["R"], c["mu"], c["e"]
    rows = []
    for s, (x, vn, vt, w) in enumerate(samples):
        mover, n, t = first[s]
        b = balls[mover]
        v = [float(b[k]) for k in ("vx", "vy", "vz")]
        spin = [float(b[k]) for k in ("wx", "wy", "wz")]
        vn_out, vt_out, w_out = dot(v, n), dot(v, t), dot(spin, cross(t, n))
        pos = [float(b[k]) for k in ("x", "y", "z")]
        if c["target"] == "plane":
            gap = math.sqrt(dot(pos, pos)) - (PLANE + 1) * r
        else:
            other = balls[count + mover]
            gap = float(other["x"]) - pos[0] - r - float(other["rad"])
        if not (vn_out > 0 and gap > 0):
            raise RuntimeError(f"{c['name']} FRAC {frac} sample {x}: not parted after {steps} steps")
        vc_in, vc_out = vt + r * w, vt_out + r * w_out
        slide_dv, slide_dw = mu * (1 + e) * vn, 2.5 * mu * (1 + e) * vn / r
        sliding = vc_in > 1.5 * 3.5 * mu * (1 + e) * vn   # clear of the transition at 3.5 mu (1 + e) Vn
        rows.append(dict(case=c["name"], frac=frac, wall_s=wall, steps=steps, dt=dt, x=x, vn=vn, vt=vt, w=w,
                         vn_out=vn_out, vt_out=vt_out, w_out=w_out, e_n=vn_out / vn,
                         e_t=vt_out / vt if vt else float("nan"),
                         vt_out_norm=vt_out / (mu * vn), w_out_norm=r * w_out / (mu * vn),
                         beta=-vc_out / vc_in if vc_in else float("nan"),
                         dv=vt - vt_out, dw=w - w_out, slide_dv=slide_dv, slide_dw=slide_dw, sliding=sliding))
    return rows


def oblique_errors(rows, ref):
    """Largest errors of one run: against rigid-body sliding, and against the reference run."""
    rigid = [max(abs(r["dv"] / r["slide_dv"] - 1), abs(r["dw"] / r["slide_dw"] - 1)) for r in rows if r["sliding"]]
    against = [max(abs(r["dv"] - q["dv"]) / r["slide_dv"], abs(r["dw"] - q["dw"]) / r["slide_dw"])
               for r, q in zip(rows, ref)]
    return max(rigid), max(against)


def oblique_section(trubal, fracs, count, work, outdir):
    """Runs every oblique case; returns the table lines, the order lines and the rows for the CSV."""
    table = ["| case | FRAC | wall s | sliding: err vs rigid body | all samples: err vs FRAC "
             f"{FRAC_REF} |", "|---|---|---|---|---|"]
    orders = ["| case | samples (sliding) | rigid-body err at FRAC 0.05, 0.8 | order in FRAC: vs rigid body "
              "| vs reference |", "|---|---|---|---|---|"]
    all_rows = []
    for c in OBLIQUE:
        ref = run_oblique(trubal, c, FRAC_REF, len(oblique_samples(c)), work)
        runs = []
        for frac in fracs:
            rows = run_oblique(trubal, c, frac, count, work)
            err_rigid, err_ref = oblique_errors(rows, ref)
            runs.append(dict(frac=frac, wall_s=rows[0]["wall_s"], err_rigid=err_rigid, err_ref=err_ref, rows=rows))
            mark = " **(default)**" if abs(frac - DEFAULT_FRAC) < 1e-12 else ""
            table.append(f"| {c['name']} | {frac:g}{mark} | {rows[0]['wall_s']:.3f} | {err_rigid:.2e} | {err_ref:.2e} |")
            print(f"{c['name']:12s} FRAC {frac:4.2f}  {rows[0]['steps']:5d} steps  {rows[0]['wall_s']:.3f} s  "
                  f"rigid {err_rigid:.2e}  ref {err_ref:.2e}", flush=True)
            all_rows += rows
        err_ref_rigid, _ = oblique_errors(ref, ref)
        all_rows += ref
        f = [r["frac"] for r in runs]
        at = {r["frac"]: r["err_rigid"] for r in runs}
        n_slide = sum(1 for r in ref if r["sliding"])
        orders.append(f"| {c['title']} | {len(ref)} ({n_slide}) | {at.get(0.05, float('nan')):.1e}, "
                      f"{at.get(0.8, float('nan')):.1e} (FRAC {FRAC_REF}: {err_ref_rigid:.1e}) | "
                      f"{slope(f, [r['err_rigid'] for r in runs]):.2f} | {slope(f, [r['err_ref'] for r in runs]):.2f} |")
        plot_oblique(c, runs, ref, outdir)
    with open(os.path.join(outdir, "oblique.csv"), "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(all_rows[0].keys()))
        w.writeheader()
        w.writerows(all_rows)
    return table, orders


def write_oblique(outdir, table, orders):
    with open(os.path.join(outdir, "oblique.md"), "w") as f:
        f.write("\n".join(orders) + "\n\n" + "\n".join(table) + "\n")
    print("\n".join(orders) + "\n\n" + "\n".join(table))


def plot_oblique(c, runs, ref, outdir):
    """Two PNGs per case: error against wall time, and the benchmark's curve against rigid-body theory."""
    if not shutil.which("gnuplot"):
        return
    name = c["name"]
    with open(os.path.join(outdir, f"{name}.dat"), "w") as f:
        for r in runs:
            f.write(f"{r['wall_s']} {max(r['err_rigid'], 1e-16)} {max(r['err_ref'], 1e-16)} {r['frac']}\n")
    script = f"""set terminal pngcairo size 800,600 noenhanced
set output '{name}.png'
set logscale xy
set xlabel 'wall time of the loop (s)'
set ylabel 'relative error of the tangential and spin changes'
set title "{c['title']}"
set key top right
plot '{name}.dat' u 1:2 w lp t 'sliding samples against rigid body', '' u 1:3 w lp t 'all samples against FRAC {FRAC_REF}', \\
     '' u 1:2:(sprintf('%.2g', $4)) w labels offset 1.5,0.5 font ',8' notitle
"""
    # The curve the benchmark plots, at the reference FRAC and at the default, with rigid-body theory:
    # sliding throughout beyond the transition, rolling away (the contact point stopped) below it.
    mu, e, r = c["mu"], c["e"], c["R"]
    default = next((x["rows"] for x in runs if abs(x["frac"] - DEFAULT_FRAC) < 1e-12), runs[-1]["rows"])
    nan = float("nan")
    with open(os.path.join(outdir, f"{name}_curve.dat"), "w") as f:
        for q, d in zip(ref, default):
            x, vn, vt, w = q["x"], q["vn"], q["vt"], q["w"]
            vc = vt + r * w
            slides = vc > 3.5 * mu * (1 + e) * vn
            dv, dw = (q["slide_dv"], q["slide_dw"]) if slides else (vc / 3.5, 2.5 * vc / (3.5 * r))
            if c["test"] == 4:     # tangential restitution and spin against the angle
                cols = [q["e_t"], d["e_t"], (vt - dv) / vt, q["w_out"], d["w_out"], w - dw]
            elif c["test"] == 5:   # normalised tangential speed and spin against Vt / (mu Vn)
                cols = [q["vt_out_norm"], d["vt_out_norm"], (vt - dv) / (mu * vn), q["w_out_norm"], d["w_out_norm"],
                        r * (w - dw) / (mu * vn)]
            elif c["test"] == 7:   # tangential speed and spin against the spin coming in
                cols = [q["vt_out"], d["vt_out"], vt - dv, q["w_out"], d["w_out"], w - dw]
            else:                  # rebound against incident contact-point angle
                cols = [q["beta"], d["beta"], -(vc - 3.5 * dv) / vc]
                x = vc / vn
            theory = [cols[2]] + ([cols[5]] if len(cols) > 3 else [])
            # one theory column for each regime, so that gnuplot draws two separate lines
            split = [v if slides else nan for v in theory] + [nan if slides else v for v in theory]
            f.write(" ".join(str(v) for v in [x] + cols[:2] + cols[3:5] + split) + "\n")
    labels = {4: ("incident angle (deg)", "tangential restitution", "rebound spin (rad/s)"),
              5: ("Vt / (mu Vn)", "Vt_out / (mu Vn)", "R w_out / (mu Vn)"),
              6: ("incident tan = R w / Vn", "beta = -Vc_out / Vc", None),
              7: ("spin coming in (rad/s)", "tangential speed out (m/s)", "spin out (rad/s)"),
              8: ("incident tan = R w / Vn", "beta = -Vc_out / Vc", None)}[c["test"]]
    curve = f"""set terminal pngcairo size 800,600 noenhanced
set output '{name}_curve.png'
set xlabel '{labels[0]}'
set ylabel '{labels[1]}'
set title "{c['title']}"
set key below
"""
    if labels[2]:   # columns: x, y ref, y default, spin ref, spin default, y and spin sliding, y and spin rolling
        curve += f"set y2label '{labels[2]}'\nset y2tics\nset ytics nomirror\n"
        curve += (f"plot '{name}_curve.dat' u 1:2 w lp t 'FRAC {FRAC_REF}', '' u 1:3 w p t 'FRAC {DEFAULT_FRAC:g}', "
                  f"'' u 1:6 w l dt 2 t 'rigid body: sliding', '' u 1:8 w l dt 3 t 'rigid body: rolling', "
                  f"'' u 1:4 axes x1y2 w lp t 'spin, FRAC {FRAC_REF}', '' u 1:5 axes x1y2 w p t 'spin, FRAC "
                  f"{DEFAULT_FRAC:g}', '' u 1:7 axes x1y2 w l dt 2 t 'spin, rigid body: sliding', "
                  f"'' u 1:9 axes x1y2 w l dt 3 t 'spin, rigid body: rolling'\n")
    else:           # columns: x, beta ref, beta default, sliding, rolling
        curve += "set logscale x\n"
        curve += (f"plot '{name}_curve.dat' u 1:2 w lp t 'FRAC {FRAC_REF}', '' u 1:3 w p t 'FRAC {DEFAULT_FRAC:g}', "
                  f"'' u 1:4 w l dt 2 t 'rigid body: sliding', '' u 1:5 w l dt 3 t 'rigid body: rolling'\n")
    for text in (script, curve):
        res = subprocess.run(["gnuplot"], input=text, text=True, cwd=outdir, capture_output=True)
        if res.returncode != 0:
            subprocess.run(["gnuplot"], input=text.replace("pngcairo", "png"), text=True, cwd=outdir,
                           capture_output=True)


def slope(xs, ys):
    pts = [(math.log(x), math.log(y)) for x, y in zip(xs, ys) if y > 1e-13]
    if len(pts) < 3:
        return float("nan")
    n = len(pts)
    mx = sum(p[0] for p in pts) / n
    my = sum(p[1] for p in pts) / n
    return sum((p[0] - mx) * (p[1] - my) for p in pts) / sum((p[0] - mx) ** 2 for p in pts)


def plot(rows, c, outdir):
    if not shutil.which("gnuplot"):
        print("gnuplot not found: no PNG (Debian: apt-get install gnuplot-nox)", file=sys.stderr)
        return
    dat = os.path.join(outdir, f"{c['name']}.dat")
    with open(dat, "w") as f:
        for r in rows:
            f.write(f"{r['wall_s']} {max(r['err_time'], 1e-16)} {max(r['err_overlap'], 1e-16)} "
                    f"{max(r['err_rebound'], 1e-16)} {r['frac']}\n")
    script = f"""set terminal pngcairo size 800,600 noenhanced
set output '{c['name']}.png'
set logscale xy
set xlabel 'wall time of the loop (s)'
set ylabel 'relative error'
set title "{c['title']}"
set key top right
plot '{c['name']}.dat' u 1:2 w lp t 'contact time', '' u 1:3 w lp t 'peak overlap', \\
     '' u 1:4 w lp t 'rebound speed', '' u 1:2:(sprintf('%.2g', $5)) w labels offset 1.5,0.5 font ',8' notitle
"""
    res = subprocess.run(["gnuplot"], input=script, text=True, cwd=outdir, capture_output=True)
    if res.returncode != 0:
        # pngcairo may be missing: fall back to the png terminal
        res = subprocess.run(["gnuplot"], input=script.replace("pngcairo", "png"), text=True, cwd=outdir,
                             capture_output=True)
    if res.returncode != 0:
        print(res.stderr, file=sys.stderr)


def main():
    global REPEAT
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--trubal", default=os.path.join(root, "build", "trubal"))
    ap.add_argument("--out", default=os.path.join(root, "doc", "speed_vs_error"))
    ap.add_argument("--impacts", type=int, default=10000, help="identical impacts per deck (default 10000)")
    ap.add_argument("--fracs", default=",".join(str(f) for f in FRACS))
    ap.add_argument("--quasi-static-only", action="store_true", help="only the FCC strength and Rowe rows")
    ap.add_argument("--repeat", type=int, default=REPEAT, help=f"runs of each timed deck, the fastest counts "
                    f"(default {REPEAT})")
    ap.add_argument("--oblique-only", action="store_true", help="only the Chung & Ooi 4-8 rows")
    ap.add_argument("--cases", default="", help="comma-separated case names to run (default: all); no files written")
    args = ap.parse_args()
    REPEAT = args.repeat
    trubal = os.path.abspath(args.trubal)
    os.makedirs(args.out, exist_ok=True)
    fracs = [float(f) for f in args.fracs.split(",")]
    all_rows = []
    table = ["| case | FRAC | wall s | contact time err | rebound err | peak overlap err |", "|---|---|---|---|---|---|"]
    orders = []
    if args.quasi_static_only:
        with tempfile.TemporaryDirectory() as work:
            table, rows = quasi_static_section(trubal, os.path.join(root, "examples"), work, args.out)
        write_quasi_static(args.out, table, rows)
        print("\n".join(table))
        return
    if args.oblique_only:
        with tempfile.TemporaryDirectory() as work:
            oblique_table, oblique_orders = oblique_section(trubal, fracs, args.impacts, work, args.out)
        write_oblique(args.out, oblique_table, oblique_orders)
        return
    if args.cases:
        wanted = args.cases.split(",")
        with tempfile.TemporaryDirectory() as work:
            for c in [c for c in CASES if c["name"] in wanted]:
                for frac in fracs:
                    r = run_case(trubal, c, frac, args.impacts, work)
                    print(f"{c['name']:12s} FRAC {frac:4.2f}  {r['steps']:5d} steps  {r['wall_s']:.3f} s  "
                          f"t_c {r['err_time']:.2e}  e {r['err_rebound']:.2e}  U {r['err_overlap']:.2e}", flush=True)
            for c in [c for c in OBLIQUE if c["name"] in wanted]:
                ref = run_oblique(trubal, c, FRAC_REF, len(oblique_samples(c)), work)
                for frac in fracs:
                    rows = run_oblique(trubal, c, frac, args.impacts, work)
                    err_rigid, err_ref = oblique_errors(rows, ref)
                    print(f"{c['name']:12s} FRAC {frac:4.2f}  {rows[0]['steps']:5d} steps  {rows[0]['wall_s']:.3f} s  "
                          f"rigid {err_rigid:.2e}  ref {err_ref:.2e}", flush=True)
        return
    with tempfile.TemporaryDirectory() as work:
        for c in CASES:
            rows = []
            for frac in fracs:
                r = run_case(trubal, c, frac, args.impacts, work)
                rows.append(r)
                print(f"{c['name']:12s} FRAC {frac:4.2f}  {r['steps']:5d} steps  {r['wall_s']:.3f} s  "
                      f"t_c {r['err_time']:.2e}  e {r['err_rebound']:.2e}  U {r['err_overlap']:.2e}", flush=True)
            all_rows += rows
            plot(rows, c, args.out)
            f = [r["frac"] for r in rows]
            orders.append((c, slope(f, [r["err_time"] for r in rows]), slope(f, [r["err_rebound"] for r in rows]),
                           slope(f, [r["err_overlap"] for r in rows])))
            for r in rows:
                mark = " **(default)**" if abs(r["frac"] - DEFAULT_FRAC) < 1e-12 else ""
                table.append(f"| {c['name']} | {r['frac']:g}{mark} | {r['wall_s']:.3f} | {r['err_time']:.2e} | "
                             f"{r['err_rebound']:.2e} | {r['err_overlap']:.2e} |")
    with open(os.path.join(args.out, "speed_vs_error.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(all_rows[0].keys()))
        w.writeheader()
        w.writerows(all_rows)
    order_table = ["| case | closed form: t_c, U_max | order in FRAC: t_c | rebound | U_max |", "|---|---|---|---|---|"]
    for c, st, se, so in orders:
        cf = closed_form(c)
        order_table.append(f"| {c['title']} | {cf['time'] * 1e6:.4g} us, {cf['overlap'] * 1e6:.4g} um | {st:.2f} | "
                           f"{se:.2f} | {so:.2f} |")
    with tempfile.TemporaryDirectory() as work:
        oblique_table, oblique_orders = oblique_section(trubal, fracs, args.impacts, work, args.out)
    write_oblique(args.out, oblique_table, oblique_orders)
    with tempfile.TemporaryDirectory() as work:
        quasi_table, quasi_rows = quasi_static_section(trubal, os.path.join(root, "examples"), work, args.out)
    write_quasi_static(args.out, quasi_table, quasi_rows)
    md = ("\n".join(order_table) + "\n\n" + "\n".join(table) + "\n\n" + "\n".join(oblique_orders) + "\n\n" +
          "\n".join(oblique_table) + "\n\n" + "\n".join(quasi_table) + "\n")
    with open(os.path.join(args.out, "speed_vs_error.md"), "w") as f:
        f.write(md)
    print(md)


if __name__ == "__main__":
    main()
