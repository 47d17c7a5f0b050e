#!/usr/bin/env python3
"""Strong and weak scaling of trubal on the dense FCC benchmark scene, with LAMMPS
beside it where one is given.

Strong scaling: one scene (default 30x30x30 FCC cells, 108,000 balls) on P = 1, 2, 4, ... threads
(BACKEND threaded; P = 1 is serial) and ranks (mpirun -np P, BACKEND mpi). Weak scaling: a block
of cells per rank (default 15x15x15, 13,500 balls), the box doubled along x, y, z in turn as P
doubles, so that P ranks hold P times the balls. For each run it reads the stepping time (trubal:
the timed CYCLE's "N cycles in T s"; LAMMPS: its "Loop time"), and trubal's peak resident memory
per rank (PRINT INFO). It prints, as the seed paper's Table 2 defines them, Sp = T*/Tp and
Ep = Sp/p (T*: serial on one core), and for weak scaling the efficiency T1/Tp. The runs are
interleaved: each repetition goes once through every P and kind.

  bench/scaling.py build/trubal [--ranks 1 2 4 8 16] [--strong 30x30x30] [--weak 15x15x15]
                   [--steps 300] [--reps 1] [--lmp lmp] [--mpirun mpirun] [--raw FILE]
                   [--no-strong] [--no-weak] [--no-threaded] [--no-mpi] [--copies]

--copies adds, to weak scaling, P copies of the serial run (and of LAMMPS on 1 rank) started at
once, each on its own 13,500 balls, nothing exchanged: how much each core slows as P cores work,
against which the ranks' efficiency can be read (the time is the copies' median).

The scenes are the peers' (../shared/peers/gen_scenes.py, or --peers DIR). Each deck takes 2
untimed cycles first, as LAMMPS's setup is outside its loop time. Writes only under a temporary
folder, and the raw times to --raw if given.
"""
import argparse
import json
import os
import re
import shlex
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from fcc_deck import fcc_body  # noqa: E402  (the deck both benchmarks write)


def cells(text):
    nx, ny, nz = (int(v) for v in text.lower().split("x"))
    return nx, ny, nz


def weak_cells(base, p):
    """The base block doubled along x, y, z in turn until it holds p blocks (p a power of 2)."""
    dims = list(base)
    k, axis = p, 0
    while k > 1:
        if k % 2:
            sys.exit(f"--weak needs ranks that are powers of 2 (got {p})")
        dims[axis] *= 2
        axis = (axis + 1) % 3
        k //= 2
    return tuple(dims)


def cpu_line():
    model, threads = "?", "?"
    try:
        out = subprocess.run(["lscpu"], capture_output=True, text=True).stdout
        m = re.search(r"^Model name:\s*(.+)$", out, re.M)
        t = re.search(r"^Thread\(s\) per core:\s*(\d+)$", out, re.M)
        model, threads = (m.group(1) if m else "?"), (t.group(1) if t else "?")
    except OSError:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    return f"CPU: {model}, {os.cpu_count()} logical cores, {threads} thread(s) per core"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("trubal")
    ap.add_argument("--ranks", nargs="+", type=int, default=[1, 2, 4, 8, 16])
    ap.add_argument("--strong", type=cells, default=(30, 30, 30), help="FCC cells of the strong scene")
    ap.add_argument("--weak", type=cells, default=(15, 15, 15), help="FCC cells per rank (weak)")
    ap.add_argument("--no-strong", action="store_true")
    ap.add_argument("--no-weak", action="store_true")
    ap.add_argument("--no-threaded", action="store_true")
    ap.add_argument("--no-mpi", action="store_true")
    ap.add_argument("--copies", action="store_true",
                    help="weak scaling also as P independent serial runs at once (and P LAMMPS runs of 1 rank)")
    ap.add_argument("--steps", type=int, default=300)
    ap.add_argument("--reps", type=int, default=1)
    ap.add_argument("--lmp", default="", help="LAMMPS binary, run beside trubal where given")
    ap.add_argument("--mpirun", default="mpirun", help="the launcher, split as a shell would")
    ap.add_argument("--peers", default=os.path.join(HERE, "..", "..", "shared", "peers"))
    ap.add_argument("--raw", default="", help="write every run's figures here (JSON)")
    ap.add_argument("--timeout", type=float, default=600, help="seconds one run may take")
    a = ap.parse_args()

    sys.path.insert(0, os.path.abspath(a.peers))
    work = tempfile.mkdtemp(prefix="trubal-scaling-")
    os.environ["SCENES_OUT"] = work
    import gen_scenes  # the peers' scene writer; SCENES_OUT is read at import

    trubal = os.path.abspath(a.trubal)
    mpirun = shlex.split(a.mpirun)
    lmp_in = os.path.join(os.path.abspath(a.peers), "lammps_fcc.in")
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
               OMPI_MCA_rmaps_base_oversubscribe="1")

    # (mode, p) -> scene name and ball count
    scenes = {}
    plan = []
    if not a.no_strong:
        plan += [("strong", p, a.strong) for p in a.ranks]
    if not a.no_weak:
        plan += [("weak", p, weak_cells(a.weak, p)) for p in a.ranks]
    for mode, p, c in plan:
        n = gen_scenes.fcc(*c)
        name = f"fcc_{n}"
        scenes[(mode, p)] = (name, n)
        deck = os.path.join(work, f"{name}.body")
        if not os.path.exists(deck):
            open(deck, "w").write("\n".join(fcc_body(os.path.join(work, name + ".xyz"))) + "\n")

    def deck_for(name, backend):
        path = os.path.join(work, f"{name}_{backend.replace(' ', '_')}.dat")
        if not os.path.exists(path):
            body = open(os.path.join(work, f"{name}.body")).read()
            open(path, "w").write(body + f"BACKEND {backend}\nCYCLE 2\nCYCLE {a.steps}\nPRINT INFO\n")
        return path

    def run(cmd):
        t = time.perf_counter()
        try:
            r = subprocess.run(cmd, cwd=work, env=env, capture_output=True, text=True, timeout=a.timeout)
            out, rc = r.stdout + r.stderr, r.returncode
        except subprocess.TimeoutExpired as e:
            out, rc = f"timed out after {a.timeout} s: {e}", 124
        whole = time.perf_counter() - t
        if rc != 0:
            print(f"  FAILED (rc {rc}): {' '.join(cmd)}\n{out[-2000:]}", flush=True)
        return rc, out, whole

    def run_copies(cmds):
        # Each copy pinned to its own core where taskset is at hand (as mpirun binds its ranks).
        pin = shutil.which("taskset") is not None
        procs = [subprocess.Popen((["taskset", "-c", str(c)] if pin else []) + cmd, cwd=work, env=env,
                                  stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
                 for c, cmd in enumerate(cmds)]
        outs = []
        for pr in procs:
            try:
                out, _ = pr.communicate(timeout=a.timeout)
            except subprocess.TimeoutExpired:
                pr.kill()
                out, _ = pr.communicate()
            outs.append(out if pr.returncode == 0 else "")
        return outs

    def loop_time(out, lammps):
        if lammps:
            m = re.search(rf"^Loop time of ([0-9.e+-]+) on .* for {a.steps} steps", out, re.M)
        else:
            m = list(re.finditer(rf"\({a.steps} cycles in ([0-9.e+-]+) s", out))
            m = m[-1] if m else None
        return float(m.group(1)) if m else None

    print(cpu_line())
    print(f"{a.steps} steps per run, {a.reps} repetition(s), ranks {a.ranks}", flush=True)
    rows = []
    for rep in range(a.reps):
        for mode, p, _ in plan:
            name, n = scenes[(mode, p)]
            kinds = []
            if p == 1:
                kinds.append(("serial", [trubal, deck_for(name, "serial")]))
            elif not a.no_threaded:
                kinds.append(("threaded", [trubal, deck_for(name, f"threaded threads {p}")]))
            if not a.no_mpi:
                kinds.append(("mpi", mpirun + ["-np", str(p), trubal, deck_for(name, "mpi")]))
            if a.lmp:
                kinds.append(("lammps", mpirun + ["-np", str(p)] + shlex.split(a.lmp) +
                              ["-in", lmp_in, "-var", "data", os.path.join(work, name + ".data"),
                               "-var", "nsteps", str(a.steps), "-log", "none"]))
            if a.copies and mode == "weak":
                one, n1 = scenes[("weak", 1)]
                kinds.append(("copies", [[trubal, deck_for(one, "serial")]] * p))
                if a.lmp:
                    kinds.append(("lmpcopies", [shlex.split(a.lmp) + ["-in", lmp_in, "-var", "data",
                                  os.path.join(work, one + ".data"), "-var", "nsteps", str(a.steps), "-log", "none"]] * p))
            for kind, cmd in kinds:
                if kind in ("copies", "lmpcopies"):
                    outs = run_copies(cmd)
                    times = [loop_time(o, kind == "lmpcopies") for o in outs]
                    if not outs or None in times:
                        print(f"  {kind} x{p}: a copy failed or printed no time", flush=True)
                        continue
                    row = dict(mode=mode, p=p, kind=kind, n=n1, rep=rep, step_s=statistics.median(times),
                               whole_s=0.0, peaks=[], copies=times)
                    rows.append(row)
                    print(f"  {mode} P={p:<3d} {kind:9s} {p} x N={n1:<8d} median {row['step_s']:8.3f} s"
                          f"  (min {min(times):.3f}, max {max(times):.3f})", flush=True)
                    continue
                rc, out, whole = run(cmd)
                if rc != 0:
                    continue
                step_s = loop_time(out, kind == "lammps")
                if step_s is None:
                    print(f"  no stepping time in the output of {' '.join(cmd)}", flush=True)
                    continue
                pk = re.findall(r"^peak memory: ([0-9 ]+) MiB", out, re.M)   # (trubal's, per rank)
                peaks = [int(v) for v in pk[-1].split()] if pk else []
                row = dict(mode=mode, p=p, kind=kind, n=n, rep=rep, step_s=step_s, whole_s=whole, peaks=peaks)
                rows.append(row)
                print(f"  {mode} P={p:<3d} {kind:9s} N={n:<8d} {row['step_s']:8.3f} s  whole {whole:7.2f} s"
                      f"  peaks {peaks}", flush=True)
    if a.raw:
        with open(a.raw, "w") as f:
            json.dump(dict(cpu=cpu_line(), steps=a.steps, rows=rows), f, indent=1)

    med = {}
    for r in rows:
        med.setdefault((r["mode"], r["p"], r["kind"]), []).append(r)

    def t(mode, p, kind):
        v = med.get((mode, p, kind))
        return statistics.median(r["step_s"] for r in v) if v else None

    for mode in ("strong", "weak"):
        if not any(k[0] == mode for k in med):
            continue
        t1 = t(mode, 1, "serial")
        l1 = t(mode, 1, "lammps")
        print(f"\n{mode} scaling, {a.steps} steps: stepping seconds (median), million ball-steps/s,"
              f" {'Sp = T*/Tp, Ep = Sp/p' if mode == 'strong' else 'efficiency T1/Tp'}")
        print(f"  {'P':>3s} {'N':>8s} | {'threaded':>8s} {'Mbs/s':>6s} {'Sp':>5s} {'Ep':>5s} | {'mpi':>8s}"
              f" {'Mbs/s':>6s} {'Sp':>5s} {'Ep':>5s} {'MiB r0/max':>11s} | {'LAMMPS':>8s} {'Ep':>5s} | mpi/LMP")
        for p in a.ranks:
            n = scenes[(mode, p)][1]
            cols = []
            for kind in ("threaded", "mpi"):
                tp = t(mode, p, "serial" if (kind == "threaded" and p == 1) else kind)
                if not tp or not t1:   # (none, or a run too short to time: 0.000 s)
                    cols.append(f"{'-':>8s} {'-':>6s} {'-':>5s} {'-':>5s}")
                    continue
                sp = t1 / tp if mode == "strong" else p * t1 / tp
                ep = sp / p
                cols.append(f"{tp:8.3f} {n * a.steps / tp / 1e6:6.2f} {sp:5.2f} {ep:5.2f}")
            pk = [r["peaks"] for r in med.get((mode, p, "mpi"), []) if r["peaks"]]
            mem = f"{max(x[0] for x in pk)}/{max(max(x) for x in pk)}" if pk else "-"
            lp = t(mode, p, "lammps")
            lcol = f"{lp:8.3f} {(l1 / lp if mode == 'weak' else l1 / lp / p):5.2f}" if lp and l1 else f"{'-':>8s} {'-':>5s}"
            mp = t(mode, p, "mpi")
            ratio = f"{lp / mp:5.2f}x" if lp and mp else "-"
            print(f"  {p:3d} {n:8d} | {cols[0]} | {cols[1]} {mem:>11s} | {lcol} | {ratio}")
        if mode == "weak" and any(k[2] == "copies" for k in med):
            c1, lc1 = t("weak", 1, "copies"), t("weak", 1, "lmpcopies")
            print(f"  P independent copies at once, each on {scenes[('weak', 1)][1]} balls, a core each (median time;"
                  " efficiency T1/Tp):")
            for p in a.ranks:
                cp, lc = t("weak", p, "copies"), t("weak", p, "lmpcopies")
                tr = f"trubal {cp:7.3f} s {c1 / cp:5.2f}" if cp and c1 else "trubal -"
                lm = f"LAMMPS {lc:7.3f} s {lc1 / lc:5.2f}" if lc and lc1 else "LAMMPS -"
                print(f"  {p:3d}  {tr}   {lm}")


if __name__ == "__main__":
    main()
