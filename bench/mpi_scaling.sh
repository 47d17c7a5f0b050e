#!/bin/bash
# Distributed runs against serial and threaded on the dense FCC benchmark scene: for each
# N, trubal serial, threaded on P threads and BACKEND mpi on P ranks, interleaved REPS times; prints
# the median cycling time, ball-steps/s, the speedup Sp = T*/Tp and efficiency Ep = Sp/p as the seed
# paper's Table 2 defines them (T*: serial), and the largest peak resident memory of a rank (PRINT
# INFO's "peak memory"), then rank 0's and the largest of the others' apart, of the whole process
# and by the timed CYCLE's end (PRINT INFO's "peak memory by the last CYCLE's end"). With
# LAMMPS installed, LAMMPS on P ranks too (the ratio the issue's target names), compared two ways,
# each like with like: trubal's cycling time against LAMMPS's "Loop time" (the steps alone), and
# whole process against whole process (reading the deck or the data file, the first search, MPI's
# start; trubal's deck also takes 2 untimed cycles).
#
#   bench/mpi_scaling.sh build/trubal [N ...]      N: 1680, 13500 (default) or 108000
#   env: STEPS (default 600), REPS (3), RANKS ("1 2"; more oversubscribe a small machine)
#
# The scene comes from ../shared/peers/gen_scenes.py (the peers' positions, so the numbers compare
# with compare.sh). Writes only under a temporary folder.
set -eu
TRUBAL=$(realpath "$1"); shift
SIZES=${*:-13500}; STEPS=${STEPS:-600}; REPS=${REPS:-3}; RANKS=${RANKS:-1 2}
HERE=$(cd "$(dirname "$0")" && pwd)
. "$HERE/mpi_setup.sh"
mpi_bench_setup mpi
SCENES_OUT=$W python3 "$PEERS/gen_scenes.py" fcc >/dev/null
echo "CPU: $(lscpu | sed -n 's/^Model name: *//p' | head -1), $(nproc) cores; $STEPS steps, median of $REPS"
"$HERE/core_speeds.sh"   # a lopsided machine shows beside its figures
for N in $SIZES; do
  [ -f "$W/fcc_$N.xyz" ] || { echo "no scene with N=$N (1680, 13500, 108000)" >&2; exit 2; }
  python3 - "$W" "$N" "$STEPS" "$RANKS" "$HERE" <<'PY'
import sys
w, n, steps, ranks = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4].split()
sys.path.insert(0, sys.argv[5])
from fcc_deck import fcc_body
body = fcc_body(f"{w}/fcc_{n}.xyz")
backends = {"serial": "BACKEND serial"}
for p in ranks:
    if p != "1":
        backends[f"threaded_{p}"] = f"BACKEND threaded threads {p}"
    backends[f"mpi_{p}"] = "BACKEND mpi"
for name, backend in backends.items():
    # CYCLE 2: the backend's first pair search outside the timing, as LAMMPS's setup is outside its loop time
    open(f"{w}/{name}.dat", "w").write("\n".join(body + [backend, "CYCLE 2", f"CYCLE {steps}", "PRINT INFO"]) + "\n")
PY
  : >"$W/times"
  # One run: its cycling time (trubal's "N cycles in T s" of the timed CYCLE), its whole process's
  # wall time and each rank's peak RSS.
  one() {
    local name=$1; shift
    local s secs whole rss
    s=$(date +%s.%N)
    (cd "$W" && "$@" >"$W/$name.out" 2>&1) || { cat "$W/$name.out" >&2; exit 1; }
    whole=$(echo "$(date +%s.%N) - $s" | bc)
    secs=$(grep -o "($STEPS cycles in [0-9.e+-]* s" "$W/$name.out" | tail -1 | awk '{print $4}')
    rss=$(sed -n 's/^peak memory: \([0-9 ]*\) MiB.*/\1/p' "$W/$name.out" | tail -1)
    cyc=$(sed -n "s/^peak memory by the last CYCLE's end: \([0-9 ]*\) MiB.*/\1/p" "$W/$name.out" | tail -1)
    echo "$name ${secs:--} $whole $rss | $cyc" >>"$W/times"   # (-: no stepping time found)
  }
  for r in $(seq "$REPS"); do
    one serial "$TRUBAL" serial.dat
    for p in $RANKS; do
      [ "$p" != 1 ] && one "threaded_$p" "$TRUBAL" "threaded_$p.dat"
      one "mpi_$p" mpirun -np "$p" "$TRUBAL" "mpi_$p.dat"
      if command -v lmp >/dev/null; then
        s=$(date +%s.%N)
        mpirun -np "$p" lmp -in "$PEERS/lammps_fcc.in" -var data "$W/fcc_$N.data" -var nsteps "$STEPS" >"$W/lmp.out" 2>&1 &&
          loop=$(sed -n "s/^Loop time of \([0-9.e+-]*\) on .* for $STEPS steps.*/\1/p" "$W/lmp.out" | head -1) &&
          echo "lammps_$p ${loop:--} $(echo "$(date +%s.%N) - $s" | bc)" >>"$W/times"
      fi
    done
  done
  python3 - "$W" "$N" "$STEPS" <<'PY'
import statistics, sys
w, n, steps = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
runs = {}
for line in open(f"{w}/times"):
    line, _, cycle = line.partition("|")
    parts = line.split()
    if len(parts) < 3 or parts[1] == "-": continue   # (a run whose stepping time was not found)
    # name, stepping time (trubal's cycling, LAMMPS's loop), whole process, peak RSS of each rank
    # (the process's; after "|", by the end of the timed CYCLE, under mpirun)
    runs.setdefault(parts[0], []).append((float(parts[1]), float(parts[2]), [int(x) for x in parts[3:]],
                                          [int(x) for x in cycle.split()]))
med = {k: statistics.median(t for t, _, _, _ in v) for k, v in runs.items()}
whole = {k: statistics.median(w for _, w, _, _ in v) for k, v in runs.items()}
rss = {k: max((max(r) if r else 0) for _, _, r, _ in v) for k, v in runs.items()}
# Rank 0's peak and the largest of the other ranks' (rank 0 alone keeps the whole model in a CYCLE).
def split_peak(k, pick):
    peaks = [pick(v) for v in runs[k] if pick(v)]
    if not peaks: return "-"
    return f"{max(p[0] for p in peaks)}" + (f"/{max(max(p[1:]) for p in peaks)}" if len(peaks[0]) > 1 else "")
base = med["serial"]
print(f"dense FCC, N = {n}: stepping time (trubal: the timed CYCLE; LAMMPS: its loop time) and whole process")
print(f"  {'run':12s} {'seconds':>8s} {'M ball-steps/s':>15s} {'Sp':>6s} {'Ep':>6s} {'whole s':>8s} {'peak RSS/rank':>14s}"
      f" {'0/rest MiB':>11s} {'in CYCLE':>9s}")
for k in sorted(med, key=lambda k: (k.split('_')[-1], k)):
    p = int(k.split("_")[1]) if "_" in k else 1
    sp = base / med[k]
    mem = f"{rss[k]} MiB" if rss[k] else "-"
    print(f"  {k:12s} {med[k]:8.3f} {n * steps / med[k] / 1e6:15.2f} {sp:6.2f} {sp / p:6.2f} {whole[k]:8.3f} {mem:>14s}"
          f" {split_peak(k, lambda v: v[2]):>11s} {split_peak(k, lambda v: v[3]):>9s}")
for k in med:
    if k.startswith("mpi_") and k != "mpi_1":
        p = k.split("_")[1]
        if f"threaded_{p}" in med: print(f"  mpi on {p} ranks / threaded on {p}: {med[f'threaded_{p}'] / med[k]:.2f}x")
        if f"lammps_{p}" in med:
            print(f"  mpi on {p} ranks / LAMMPS on {p}: {med[f'lammps_{p}'] / med[k]:.2f}x stepping, "
                  f"{whole[f'lammps_{p}'] / whole[k]:.2f}x whole process")
PY
done
"$HERE/core_speeds.sh"
