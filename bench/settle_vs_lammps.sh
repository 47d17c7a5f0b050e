#!/bin/bash
# Speed of trubal beside LAMMPS on the peers' sparse scene, as ../shared/peers/compare.sh
# does for the dense one: balls of R = 20 settling from a loose random gas (solid fraction 0.3,
# gen_scenes.py settle) under gravity 0.03 onto a floor wall at z = 0, x and y periodic,
# gran/hooke/history 1.5e9 1.5e9 with mu 0.12278 and a normal dashpot (gamma_n 1.338), dt 0.04:
# the fall, the collapse and the settling, contacts opening and closing, about 5 per ball at rest.
# LAMMPS runs the peers' lammps_settle.in unchanged; trubal the same state with the laws matched as
# tests/peers/README.md says (the deck of tests/peers/settle_trubal.dat without its output). Both
# on 1 and on 2 cores (trubal serial and threaded 2, LAMMPS 1 and 2 MPI ranks), interleaved REPS
# times; prints median whole-process wall times, the speed ratios trubal / LAMMPS, and each code's
# contacts per ball at the end (ball pairs, 2 C / N) as a check that both ran the same scene.
#
#   bench/settle_vs_lammps.sh build/trubal [N] [STEPS]   N: 10000 (default), 100000 (the peers'
#                                                        sizes) or another (box edge 1200 sqrt(N/1e4))
#   env: REPS (default 3); SORT=n gives trubal `SET sort n` (the peers' balls are numbered at
#        random; trubal puts them in space order in memory every 1000 cycles by default, as LAMMPS
#        sorts its atoms every 1000 steps; SORT=0 keeps them in the file's random order)
#
# Needs LAMMPS and MPI from Debian (lammps, openmpi-bin; .ci/deps installs them) and
# ../shared/peers. Writes only under a temporary folder.
set -eu
TRUBAL=$(realpath "$1"); N=${2:-10000}; STEPS=${3:-20000}; REPS=${REPS:-3}
HERE=$(cd "$(dirname "$0")" && pwd)
PEERS=${TRUBAL_PEERS:-$HERE/../../shared/peers}
[ -f "$PEERS/gen_scenes.py" ] || { echo "no $PEERS/gen_scenes.py (the peers' scenes; TRUBAL_PEERS)" >&2; exit 2; }
PEERS=$(cd "$PEERS" && pwd)
command -v lmp >/dev/null || { echo "LAMMPS missing: apt-get install -y lammps" >&2; exit 2; }
command -v mpirun >/dev/null || { echo "mpirun missing: apt-get install -y openmpi-bin" >&2; exit 2; }
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
W=$(mktemp -d /tmp/trubal-settle-XXXXXX)
trap 'rm -rf "$W"' EXIT
case $N in 10000) L=1200 ;; 100000) L=3795 ;; *) L=$(python3 -c "import math; print(1200 * math.sqrt($N / 1e4))") ;; esac
(cd "$W" && SCENES_OUT=$W python3 -c "import sys; sys.path.insert(0, sys.argv[1]); import gen_scenes; gen_scenes.settle(int(sys.argv[2]), float(sys.argv[3]))" "$PEERS" "$N" "$L") >/dev/null
python3 "$HERE/../tests/peers/lammps_to_trubal.py" "$W/settle_$N.data" --balls "$W/balls.dat" >"$W/box.txt"
python3 - "$W" "$STEPS" "$HERE/../tests/peers" <<'PY'
import os, sys
w, steps, peers_tests = sys.argv[1], int(sys.argv[2]), sys.argv[3]
sys.path.insert(0, peers_tests)
import settle_vs_lammps as s   # the peer check's dashpot match (restitutions) and scene constants
words = [l for l in open(f"{w}/box.txt") if l.startswith("box ")][0].split()
x0, x1, y0, y1, z0, z1 = (float(v) for v in words[1:7])
top = float(words[words.index("top") + 1])
ztop = max(z1, top + 10 * 2 * s.R)   # as the peer check: 10 diameters above the highest centre
e = s.restitutions("dashpot")
body = [f"start box 0 {x1!r} 0 {y1!r} {z0!r} {ztop!r} x periodic y periodic",
        f"prop type 1 kn 1.5e9 ks 1.5e9 mu 0.12278 dens 2000 rest {e['e_pp']!r}",
        f"prop type 2 kn 1.5e9 ks 1.5e9 mu 0.12278 rest {e['e_wall']!r}",
        "wall id 1 plane 0 0 0 0 0 1 type 2", f"call {w}/balls.dat"]
body += [f"set sort {os.environ['SORT']}"] if os.environ.get("SORT", "") != "" else []
body += ["grav 0 0 -0.03", "tstep 0.04"]
for name, backend in (("serial", "backend serial"), ("threaded2", "backend threaded threads 2")):
    open(f"{w}/{name}.dat", "w").write("\n".join(body + [backend, f"cycle {steps}", "print coordination",
                                                        "print info"]) + "\n")
PY
LMP="lmp -in $PEERS/lammps_settle.in -var data $W/settle_$N.data -var nsteps $STEPS"
t() { local s; s=$(date +%s.%N); "$@" >"$W/last.out" 2>&1 || { cat "$W/last.out" >&2; exit 1; }; echo "$(date +%s.%N) - $s" | bc; }
echo "CPU: $(lscpu | sed -n 's/^Model name: *//p' | head -1), $(nproc) cores; settle N=$N, $STEPS steps, $REPS interleaved runs$([ -n "${SORT:-}" ] && echo ", trubal's SET sort $SORT")"
"$HERE/core_speeds.sh"   # a lopsided machine shows beside its figures
for r in $(seq "$REPS"); do
  echo "lammps_1 $(cd "$W" && t $LMP)" >>"$W/times"; cp "$W/last.out" "$W/lammps_1.out"
  echo "trubal_serial $(cd "$W" && t "$TRUBAL" serial.dat)" >>"$W/times"; cp "$W/last.out" "$W/serial.out"
  echo "lammps_2 $(cd "$W" && t mpirun -np 2 $LMP)" >>"$W/times"; cp "$W/last.out" "$W/lammps_2.out"
  echo "trubal_threaded2 $(cd "$W" && t "$TRUBAL" threaded2.dat)" >>"$W/times"; cp "$W/last.out" "$W/threaded2.out"
  echo "  run $r: $(tail -4 "$W/times" | tr '\n' ' ')"
done
python3 - "$W" "$N" "$STEPS" <<'PY'
import re, statistics, sys
w, n, steps = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
t = {}
for line in open(f"{w}/times"):
    k, v = line.split(); t.setdefault(k, []).append(float(v))
m = {k: statistics.median(v) for k, v in t.items()}
def grab(path, pattern, last=True):
    found = re.findall(pattern, open(path).read())
    return (found[-1] if last else found[0]) if found else "?"
print(f"settle, N={n}, {steps} steps, median of {len(t['lammps_1'])} (whole-process wall time; min-max)")
for k in ("lammps_1", "trubal_serial", "lammps_2", "trubal_threaded2"):
    print(f"  {k:18s} {m[k]:8.3f} s  ({min(t[k]):.3f}-{max(t[k]):.3f})  {n * steps / m[k] / 1e6:6.2f} M ball-steps/s")
print(f"  trubal serial / LAMMPS 1 rank:      {m['lammps_1'] / m['trubal_serial']:.2f}x")
print(f"  trubal threaded 2 / LAMMPS 2 ranks: {m['lammps_2'] / m['trubal_threaded2']:.2f}x")
for k in ("lammps_1", "lammps_2"):
    print(f"  {k} contacts per ball {grab(f'{w}/{k}.out', r'RESULT contacts_per_particle ([0-9.eE+-]+)')}, "
          f"loop time {grab(f'{w}/{k}.out', r'Loop time of ([0-9.eE+-]+)', last=False)} s")
for k in ("serial", "threaded2"):
    print(f"  trubal {k}: coordination {grab(f'{w}/{k}.out', r'coordination[^0-9]*([0-9.eE+-]+)')}, "
          f"cycling {grab(f'{w}/{k}.out', r'cycles in ([0-9.eE+-]+) s')} s")
PY
"$HERE/core_speeds.sh"
