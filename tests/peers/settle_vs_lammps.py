#!/usr/bin/env python3
"""Checked against a peer: trubal and LAMMPS on the peers' sparse settle scene.

A few thousand spheres of one size (R = 20, density 2000) settle from a loose random gas under
gravity 0.03 onto a floor wall, with gran/hooke/history (kn = kt = 1.5e9, mu = 0.12278, normal
dashpot gamma_n = 1.338, no tangential dashpot) and a fixed step of 0.04. Both codes run the
same state, and the test compares
  - the final mean height of the ball centres            (within 1%)
  - the coordination number, ball pairs only, 2 C / N   (within 3%)
  - the first step, after the peak, at which the kinetic energy (translational + rotational)
    is below 1e-3 of its peak                            (within 10%)
Exit status 0 when all three hold, 1 when one does not, 77 (skipped) without LAMMPS (`lmp`) or
without the peers' scene generator.

The container is the peers' own (LAMMPS `boundary p p fm`): x and y periodic with the data file's
box (trubal START box 0 L 0 L zlo ztop x periodic y periodic), z bounded with the floor a wall at
z = 0 in both codes, no side walls, every ball where the data file puts it. LAMMPS's upper z is
shrink-wrapped; trubal's box top is fixed, at the highest centre plus --ztop-margin (default 10
diameters), its condition `stop` (a centre leaving the box stops CYCLE with an error, so the run
cannot pass with a lost ball); the highest centre during the run is reported for both codes.
LAMMPS runs tests/peers/lammps_settle_ke.in, the peers' lammps_settle.in restated with the KE
history (--also-shared runs the peers' file unchanged too and requires the same contact count).
`--container walls` instead runs both codes in a box with frictionless side walls on the x and y
faces (the comparison before trubal had mixed periodicity: the balls those faces cut are moved
inside by lammps_to_trubal.py --walls, and LAMMPS runs that walled state with `fix wall/gran`
xplane, yplane, xmu 0): a check of the side walls; `--container both` runs and checks both.

The laws (trubal PROP and WALL help, doc/physics.md):
  - springs: PROP kn = ks = 1.5e9 for the balls and the walls' types; two types meet with
    2 k1 k2 / (k1 + k2) = 1.5e9, so ball-ball and ball-wall contacts get LAMMPS's kn and kt.
  - friction: PROP mu 0.12278 (fric 7 degrees); the side walls' type has mu 0, as LAMMPS's
    side fixes (xmu 0), and a contact takes the smaller mu.
  - dashpot: LAMMPS's normal damping force is m_eff gamma_n v_n, m_eff = m/2 ball-ball and m at a
    wall; trubal's restitution dashpot is c = 2 xi sqrt(kn m_eff) with the same m_eff (a wall is a
    partner of infinite mass), xi the damping ratio from PROP rest e. So xi = gamma_n
    sqrt(m_eff / kn) / 2 (0.1000 ball-ball, 0.1414 ball-wall) gives LAMMPS's c exactly; the e
    passed to PROP rest is the one trubal maps back to that xi (its dashpot never pulls:
    Schwager & Poeschel's restitution, e = 0.7441 and 0.6648). The one difference left is that
    clamp: LAMMPS's dashpot pulls at the end of an impact (its head-on restitution for these xi
    is 0.7293 and 0.6384). `--match restitution` gives trubal those restitutions instead (a
    larger c); `--lammps-limit-damping` clamps LAMMPS's ball-ball dashpot as trubal's (its wall
    fix has no such option).
"""
import argparse
import csv
import math
import os
import shutil
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
SKIP = 77

# Scene constants of ../../../shared/peers/gen_scenes.py and lammps_settle.in.
R, RHO, KN, GAMMA_N = 20.0, 2000.0, 1.5e9, 1.338
TOL = {"mean_z": 0.01, "coordination": 0.03, "ke_step": 0.10}


def clamped_restitution(xi):
    """Head-on restitution of a linear spring-dashpot whose dashpot never pulls (trubal's
    PROP rest, src/physics/pair_laws.cpp), for damping ratio xi < 1."""
    s = math.sqrt(1 - xi * xi)
    return math.exp(-xi * math.atan2(2 * xi * s, 2 * xi * xi - 1) / s)


def clamped_xi(e):
    """The damping ratio trubal takes for PROP rest e (the inverse of clamped_restitution)."""
    lo, hi = 0.0, 0.999999
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if clamped_restitution(mid) > e else (lo, mid)
    return 0.5 * (lo + hi)


def pulling_restitution(xi):
    """Head-on restitution of a linear spring-dashpot that may pull (LAMMPS gran/hooke)."""
    return math.exp(-math.pi * xi / math.sqrt(1 - xi * xi))


def restitutions(match):
    m = RHO * 4.0 / 3.0 * math.pi * R ** 3
    e = {}
    for name, meff in (("e_pp", m / 2), ("e_wall", m)):
        xi = GAMMA_N * math.sqrt(meff / KN) / 2
        e[name] = clamped_restitution(xi) if match == "dashpot" else pulling_restitution(xi)
        e[name.replace("e_", "xi_")] = xi
    return e


def ke_step(steps, ke):
    peak = max(range(len(ke)), key=ke.__getitem__)
    for k in range(peak, len(ke)):
        if ke[k] < 1e-3 * ke[peak]:
            return steps[k], steps[peak], ke[peak]
    return None, steps[peak], ke[peak]


def run(cmd, cwd, log):
    t0 = time.time()
    with open(os.path.join(cwd, log), "w") as f:
        rc = subprocess.call(cmd, cwd=cwd, stdout=f, stderr=subprocess.STDOUT)
    dt = time.time() - t0
    if rc != 0:
        with open(os.path.join(cwd, log)) as f:
            tail = f.read()[-3000:]
        sys.exit("settle_vs_lammps: %s failed (exit %d); the end of %s:\n%s" % (cmd[0], rc, log, tail))
    return dt


def run_lammps(lmp, work, data, walls, args, tag):
    wall_s = run([lmp, "-in", os.path.join(HERE, "lammps_settle_ke.in"), "-var", "data", data,
                  "-var", "nsteps", str(args.nsteps), "-var", "every", str(args.every), "-var", "out", tag,
                  "-var", "walls", str(walls), "-var", "limit", "1" if args.lammps_limit_damping else "0",
                  "-log", tag + ".log", "-screen", "none"],
                 work, tag + ".screen")
    zpp = lammps_result(os.path.join(work, tag + ".log"))
    steps, ke, ztop = [], [], []
    with open(os.path.join(work, tag + "_ke.txt")) as f:
        for line in f:
            if not line.startswith("#"):
                w = line.split()
                steps.append(int(w[0]))
                ke.append(float(w[1]) + float(w[2]))
                ztop.append(float(w[3]))
    z = []
    with open(os.path.join(work, tag + "_final.txt")) as f:
        lines = f.read().splitlines()
    cols = lines[8].split()[2:]   # ITEM: ATOMS id x y z ...
    for line in lines[9:]:
        z.append(float(line.split()[cols.index("z")]))
    s = summary(steps, ke, z, zpp, wall_s)
    s["top"] = "%.1f" % max(ztop)
    return s


def lammps_result(log):
    zpp = None
    with open(log) as f:
        for line in f:
            if line.startswith("RESULT contacts_per_particle"):
                zpp = float(line.split()[2])
    return zpp


def run_lammps_shared(lmp, work, data, args):
    """The peers' lammps_settle.in itself, unchanged: its contact count only."""
    wall_s = run([lmp, "-in", os.path.join(args.peers, "lammps_settle.in"), "-var", "data", data,
                  "-var", "nsteps", str(args.nsteps), "-log", "lammps_shared.log", "-screen", "none"],
                 work, "lammps_shared.screen")
    return lammps_result(os.path.join(work, "lammps_shared.log")), wall_s


def run_trubal(trubal, work, box, top, periodic, e, args, balls, tag):
    (x0, x1), (y0, y1), (z0, z1) = box
    if x0 != 0 or y0 != 0 or x1 != y1:
        sys.exit("settle_vs_lammps: a square box from 0 expected in x and y, got %s" % (box,))
    ztop = max(z1, top + args.ztop_margin * 2 * R)
    sides = os.path.join(work, tag + "_sides.dat")
    with open(sides, "w") as f:
        if periodic:
            f.write("; x and y periodic: no side walls\n")
        else:
            f.write("; frictionless side walls (type 3) on the box's x and y faces\n")
            f.write("wall id 2 plane 0 0 0 1 0 0 type 3\nwall id 3 plane %.17g 0 0 -1 0 0 type 3\n" % x1)
            f.write("wall id 4 plane 0 0 0 0 1 0 type 3\nwall id 5 plane 0 %.17g 0 0 -1 0 type 3\n" % y1)
    deck = os.path.join(work, tag + ".dat")
    with open(deck, "w") as f:
        f.write("; settle_vs_lammps.py: the variables of tests/peers/settle_trubal.dat\n")
        f.write("set L %.17g\nset zlo %.17g\nset ztop %.17g\n" % (x1, z0, ztop))
        f.write("set axes %s\nset sides %s\n" % ("x periodic y periodic" if periodic else "stop", sides))
        f.write("set e_pp %.17g\nset e_wall %.17g\n" % (e["e_pp"], e["e_wall"]))
        f.write("set nsteps %d\nset every %d\nset balls %s\n" % (args.nsteps, args.every, balls))
        if args.backend:
            f.write("backend %s\n" % args.backend)
        f.write("call %s\n" % os.path.join(HERE, "settle_trubal.dat"))
    rundir = os.path.join(work, tag)
    os.mkdir(rundir)
    wall_s = run([trubal, deck], rundir, "trubal.out")
    steps, ke, zpp = [], [], None
    with open(os.path.join(rundir, "trubal_ke.csv")) as f:
        for row in csv.DictReader(f):
            steps.append(int(row["cycle"]))
            ke.append(float(row["ke"]))
            zpp = float(row["coordination"])
    # the state before the first cycle (at rest) is row 0 in LAMMPS's history
    steps.insert(0, 0)
    ke.insert(0, 0.0)
    with open(os.path.join(rundir, "trubal_final.csv")) as f:
        z = [float(row["z"]) for row in csv.DictReader(f)]
    floor = None
    with open(os.path.join(rundir, "trubal_walls.csv")) as f:
        for row in csv.DictReader(f):
            if row["id"] == "1":
                floor = int(row["contacts"])
    s = summary(steps, ke, z, zpp, wall_s)
    s["floor_contacts"] = floor
    s["top"] = "<%.0f" % ztop   # trubal's box top, `stop`: no centre went above it
    return s


def summary(steps, ke, z, zpp, wall_s):
    step, peak_step, peak = ke_step(steps, ke)
    if zpp is None or step is None or steps[-1] < steps[0]:
        sys.exit("settle_vs_lammps: incomplete results (coordination %s, KE step %s)" % (zpp, step))
    return {"mean_z": sum(z) / len(z), "coordination": zpp, "ke_step": step, "ke_peak": peak,
            "ke_peak_step": peak_step, "ke_last": ke[-1], "n": len(z), "seconds": wall_s}


KEYS = (("mean_z", "mean height"), ("coordination", "coordination"), ("ke_step", "KE below 1e-3 of peak"))


def main():
    ap = argparse.ArgumentParser(description="trubal against LAMMPS on the peers' settle scene")
    ap.add_argument("--trubal", required=True, help="the trubal executable")
    ap.add_argument("--lmp", default=os.environ.get("LAMMPS", "lmp"), help="the LAMMPS executable (lmp)")
    ap.add_argument("--peers", default=os.environ.get("TRUBAL_PEERS",
                                                      os.path.join(HERE, "..", "..", "..", "shared", "peers")),
                    help="the peers' directory (gen_scenes.py, lammps_settle.in)")
    ap.add_argument("--n", type=int, default=3000, help="balls")
    ap.add_argument("--width", type=float, default=660.0, help="box edge in x and y (16.5 diameters)")
    ap.add_argument("--seed", type=int, default=4242, help="gen_scenes.settle's seed (4242 is the peers')")
    ap.add_argument("--nsteps", type=int, default=20000)
    ap.add_argument("--every", type=int, default=10, help="steps between kinetic-energy samples")
    ap.add_argument("--container", choices=("periodic", "walls", "both"), default="periodic",
                    help="x and y periodic as the peers' scene (default), frictionless side walls "
                         "(balls fitted inside), or both, each checked")
    ap.add_argument("--ztop-margin", type=float, default=10.0,
                    help="trubal's box top above the highest starting centre, in diameters")
    ap.add_argument("--match", choices=("dashpot", "restitution"), default="dashpot",
                    help="trubal's dashpot: LAMMPS's coefficient (default) or its head-on restitution")
    ap.add_argument("--lammps-limit-damping", action="store_true",
                    help="LAMMPS's ball-ball dashpot may not pull either (limit_damping; a diagnostic)")
    ap.add_argument("--also-shared", action="store_true",
                    help="run the peers' lammps_settle.in unchanged too; its contact count must equal "
                         "the restated input's (periodic container)")
    ap.add_argument("--backend", default="", help="a trubal BACKEND line's words (default: serial)")
    ap.add_argument("--keep", action="store_true", help="keep the work directory")
    args = ap.parse_args()

    lmp = shutil.which(args.lmp)
    if not lmp:
        print("SKIPPED: LAMMPS (%s) is not installed (Debian: apt-get install lammps; .ci/deps does)" % args.lmp)
        return SKIP
    gen = os.path.join(args.peers, "gen_scenes.py")
    if not os.path.isfile(gen):
        print("SKIPPED: the peers' scene generator %s is not here (set TRUBAL_PEERS or --peers)" % gen)
        return SKIP
    args.peers = os.path.abspath(args.peers)
    trubal = os.path.abspath(args.trubal)
    containers = ("periodic", "walls") if args.container == "both" else (args.container,)

    work = tempfile.mkdtemp(prefix="settle_vs_lammps_")
    ok = False
    try:
        env = dict(os.environ, SCENES_OUT=work)
        t0 = time.time()
        subprocess.check_call([sys.executable, "-c",
                               "import sys; sys.path.insert(0, sys.argv[1]); import gen_scenes; "
                               "gen_scenes.settle(int(sys.argv[2]), float(sys.argv[3]), seed=int(sys.argv[4]))",
                               args.peers, str(args.n), repr(args.width), str(args.seed)], env=env, cwd=work)
        data = "settle_%d.data" % args.n
        print("scene: gen_scenes.settle(%d, %g, seed=%d), %.1f s" % (args.n, args.width, args.seed,
                                                                   time.time() - t0))
        e = restitutions(args.match)
        print("LAMMPS's dashpot: xi ball-ball %.6f, ball-wall %.6f; trubal PROP rest %.10f, %.10f "
              "(its dashpot ratio %.6f, %.6f: matched by %s)"
              % (e["xi_pp"], e["xi_wall"], e["e_pp"], e["e_wall"], clamped_xi(e["e_pp"]),
                 clamped_xi(e["e_wall"]), args.match))

        res, pairs = {}, []
        for c in containers:
            walls = c == "walls"
            cmd = [sys.executable, os.path.join(HERE, "lammps_to_trubal.py"), data, "--balls", c + "_balls.dat"]
            if walls:
                cmd += ["--walls", "--data", "walled.data"]
            conv = subprocess.check_output(cmd, cwd=work, universal_newlines=True)
            for line in conv.splitlines():
                if not line.startswith("box "):
                    print("%s: %s" % (c, line))
            w = [l for l in conv.splitlines() if l.startswith("box ")][0].split()
            box = tuple((float(w[1 + 2 * k]), float(w[2 + 2 * k])) for k in range(3))
            top = float(w[w.index("top") + 1])
            print("%s: box x [%g, %g] y [%g, %g] z [%g, %g], highest centre %.3f%s" % (
                c, box[0][0], box[0][1], box[1][0], box[1][1], box[2][0], box[2][1], top,
                ", x and y periodic" if not walls else ", side walls"))
            lname, tname = "LAMMPS, " + c, "trubal, " + c
            res[lname] = run_lammps(lmp, work, "walled.data" if walls else data, 1 if walls else 0, args,
                                    "lammps_" + c)
            res[tname] = run_trubal(trubal, work, box, top, not walls, e, args,
                                    os.path.join(work, c + "_balls.dat"), "trubal_" + c)
            pairs.append((c, lname, tname))

        print("\n%d balls, %d steps of 0.04 (KE sampled every %d):" % (args.n, args.nsteps, args.every))
        print("%-18s %12s %13s %9s %10s %9s %11s %8s" % ("", "mean height", "coordination", "KE step",
                                                        "KE peak", "at step", "top centre", "seconds"))
        for name, r in res.items():
            print("%-18s %12.4f %13.4f %9d %10.4g %9d %11s %8.1f" % (
                name, r["mean_z"], r["coordination"], r["ke_step"], r["ke_peak"], r["ke_peak_step"],
                r["top"], r["seconds"]))
        for c, lname, tname in pairs:
            print("trubal's floor contacts at the end (%s): %s" % (c, res[tname]["floor_contacts"]))
        print("(top centre: LAMMPS the highest centre sampled during the run; trubal its box top, "
              "which no centre passed)")

        ok = True
        for c, lname, tname in pairs:
            ref, got = res[lname], res[tname]
            print("\ntrubal against LAMMPS (%s):" % c)
            for key, label in KEYS:
                rel = (got[key] - ref[key]) / ref[key]
                good = abs(rel) <= TOL[key]
                ok = ok and good
                print("  %-22s %+8.3f%%  (tolerance %g%%)  %s" % (label, 100 * rel, 100 * TOL[key],
                                                                 "ok" if good else "FAILED"))
        if len(pairs) == 2:
            print("\nside walls against periodic x y (not checked):")
            for key, label in KEYS:
                print("  %-22s LAMMPS %+8.3f%%  trubal %+8.3f%%" % (label, *(
                    100 * (res[code + ", walls"][key] - res[code + ", periodic"][key]) / res[code + ", periodic"][key]
                    for code in ("LAMMPS", "trubal"))))
        if args.also_shared and "periodic" in containers:
            zpp, secs = run_lammps_shared(lmp, work, data, args)
            mine = res["LAMMPS, periodic"]["coordination"]
            same = zpp is not None and zpp == mine
            ok = ok and same
            print("\nthe peers' lammps_settle.in unchanged (%.1f s): contacts per particle %s, the restated "
                  "input's %.10g: %s" % (secs, zpp, mine, "the same" if same else "DIFFERENT"))
        print("\n%s" % ("PASSED" if ok else "FAILED"))
    finally:
        if args.keep or not ok:
            print("work directory kept: %s" % work)
        else:
            shutil.rmtree(work, ignore_errors=True)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
