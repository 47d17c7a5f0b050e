#!/usr/bin/env python3
"""Speed against error (issue 7): runs the head-on impact cases of VALIDATION.md at several FRAC values,
and the FCC-strength and Rowe examples (cycle counts scaled so each run covers the same physical time),
measures the loop's wall time and the error against the closed form (contact time, rebound speed, peak
overlap), and writes a CSV, a log-log PNG per case (gnuplot) and a Markdown table.

    python3 tools/speed_vs_error.py [--trubal build/trubal] [--out speed_vs_error]

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
    out = subprocess.run([trubal, path], cwd=work, capture_output=True, text=True)
    if out.returncode != 0:
        raise RuntimeError(out.stdout + out.stderr)
    m = re.findall(r"\((\d+) cycles in ([0-9.]+) s", out.stdout)
    wall = float(m[-1][1])
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
    out = subprocess.run([trubal, path], cwd=work, capture_output=True, text=True)
    if out.returncode != 0:
        return dict(case=c["name"], backend=backend, frac=frac, wall_s=float("nan"), peak=float("nan"),
                    note=out.stderr.strip()[-200:])
    wall = sum(float(t) for _, t in re.findall(r"\((\d+) cycles in ([0-9.]+) s", out.stdout))
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
    script = (f"set terminal pngcairo size 800,600\nset output '{c['name']}.png'\nset logscale xy\n"
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
    script = f"""set terminal pngcairo size 800,600
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
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--trubal", default=os.path.join(root, "build", "trubal"))
    ap.add_argument("--out", default=os.path.join(root, "doc", "speed_vs_error"))
    ap.add_argument("--impacts", type=int, default=10000, help="identical impacts per deck (default 10000)")
    ap.add_argument("--fracs", default=",".join(str(f) for f in FRACS))
    ap.add_argument("--quasi-static-only", action="store_true", help="only the FCC strength and Rowe rows")
    args = ap.parse_args()
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
        quasi_table, quasi_rows = quasi_static_section(trubal, os.path.join(root, "examples"), work, args.out)
    write_quasi_static(args.out, quasi_table, quasi_rows)
    md = "\n".join(order_table) + "\n\n" + "\n".join(table) + "\n\n" + "\n".join(quasi_table) + "\n"
    with open(os.path.join(args.out, "speed_vs_error.md"), "w") as f:
        f.write(md)
    print(md)


if __name__ == "__main__":
    main()
