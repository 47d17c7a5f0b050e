#!/bin/bash
# Speed of trubal beside LAMMPS on a small pour into a box: 500 balls of R = 0.5 mm (density 2500)
# start at rest on a loose jittered lattice (5 x 5 x 20, 1.6 mm apart across, 1.5 mm up, the lowest
# centres 5 mm above the floor) and fall under gravity 9.81 into a box of five planes, 8 mm square:
# the floor and four sides, no lid. Linear springs with shear history kn = ks = 1000 N/m,
# friction 0.5 between balls and at every wall, a normal dashpot giving a head-on restitution of
# 0.5 between balls in LAMMPS's law, no tangential dashpot, no rolling resistance, dt 4e-6 s (a
# twentieth of the ball-ball contact's half period): 100,000 steps are 0.4 s, the fall (the top
# layer lands by about 0.08 s), the heap's collapse and its settling. One Python generator writes
# the positions into a LAMMPS data file and trubal BALL lines; LAMMPS (gran/hooke/history, fix
# wall/gran hooke/history xplane, yplane, zplane) and trubal (PROP, WALL plane) run them with the
# laws matched as tests/peers/README.md says. Both on one core (trubal BACKEND serial, LAMMPS one
# rank), interleaved REPS times; prints median whole-process wall times (and CPU times, user + sys,
# the steadier on a shared machine), the ratio LAMMPS / trubal (above 1: trubal faster), and each code's final mean centre height and contacts per ball (ball
# pairs, 2 C / N) as the check that both ran the same scene: the codes start the same, but a pour
# is chaotic, so only such averages compare; the script fails (exit 1) when they differ by more
# than 2% (height) or 6% (contacts per ball; or 0.05 a ball, for short runs where few touch).
#
#   bench/pour_vs_lammps.sh build/trubal [STEPS]   STEPS: default 100000
#   env: REPS (default 3); TRUBAL2: a second trubal binary, run interleaved beside the first
#        (an older build, say), with its own median and ratio
#
# The laws, as tests/peers/README.md matches them (its settle_vs_lammps.py gives the restitutions):
#   - springs: LAMMPS kn = kt = 1000 N/m for the pairs and the walls; trubal PROP kn 1000 ks 1000
#     for the balls (type 1) and the walls (type 2), two types meeting at 2 k1 k2 / (k1 + k2) = 1000.
#   - friction: xmu 0.5 for the pairs and every wall fix; PROP mu 0.5 for both types.
#   - dashpot: LAMMPS's normal force m_eff gamma_n v_n (m_eff = m/2 between balls, m at a wall);
#     gamma_n is chosen so that LAMMPS's ball-ball restitution is 0.5 (damping ratio xi = 0.2155,
#     0.3047 at a wall). trubal's PROP rest e gives c = 2 xi sqrt(kn m_eff) with the same m_eff,
#     so each type's rest is the e trubal maps back to that xi: the same c as LAMMPS's.
#     trubal's dashpot never pulls at the end of an impact and LAMMPS's does, so trubal's own
#     head-on restitution is a little higher (printed), as in the peer check. The balls are of
#     one size because of this dashpot: LAMMPS's gamma_n is per unit mass, so its damping ratio
#     moves with each pair's masses, where trubal's rest gives one ratio per pair of types.
#   - the neighbour skin: trubal's is a fifth of the mean radius; LAMMPS's is set to the same
#     1e-4 m (its SI default is 1 mm, two radii); the two rebuild their lists about as often.
#
# Needs LAMMPS from Debian (lammps; .ci/deps installs it) and tests/peers/settle_vs_lammps.py.
# Writes only under a temporary folder.
set -eu
[ $# -ge 1 ] || { echo "usage: bench/pour_vs_lammps.sh TRUBAL [STEPS]  (env: REPS, TRUBAL2)" >&2; exit 2; }
TRUBAL=$(realpath "$1"); STEPS=${2:-100000}; REPS=${REPS:-3}
TRUBAL2=${TRUBAL2:+$(realpath "$TRUBAL2")}
HERE=$(cd "$(dirname "$0")" && pwd)
PEER_TESTS=$HERE/../tests/peers
[ -f "$PEER_TESTS/settle_vs_lammps.py" ] || { echo "no $PEER_TESTS/settle_vs_lammps.py (the peer check's law matching)" >&2; exit 2; }
command -v lmp >/dev/null || { echo "LAMMPS missing: apt-get install -y lammps" >&2; exit 2; }
lmp -h 2>/dev/null | grep -qw 'wall/gran' || { echo "this lmp has no fix wall/gran (GRANULAR package)" >&2; exit 2; }
for b in "$TRUBAL" ${TRUBAL2:+"$TRUBAL2"}; do [ -x "$b" ] || { echo "no trubal binary $b" >&2; exit 2; }; done
W=$(mktemp -d /tmp/trubal-pour-XXXXXX)
trap 'rm -rf "$W"' EXIT
python3 - "$W" "$STEPS" "$PEER_TESTS" <<'PY' >"$W/scene.txt"
import math, random, sys
w, steps = sys.argv[1], int(sys.argv[2])
sys.path.insert(0, sys.argv[3])
from settle_vs_lammps import clamped_restitution, clamped_xi, pulling_restitution
R, RHO, KN, MU, E_PP, G, DT = 0.5e-3, 2500.0, 1000.0, 0.5, 0.5, 9.81, 4e-6
NX, NZ, DXY, DZ, Z0 = 5, 20, 1.6e-3, 1.5e-3, 5e-3   # the lattice: NX x NX a layer, NZ layers
L = NX * DXY                                        # the box's edge in x and y: 8 mm
ZTOP = Z0 + (NZ - 1) * DZ + 20 * R                  # above the highest centre by 10 diameters
m = RHO * 4.0 / 3.0 * math.pi * R ** 3
xi_pp = -math.log(E_PP) / math.sqrt(math.pi ** 2 + math.log(E_PP) ** 2)   # LAMMPS's e = 0.5
gamma_n = 2.0 * xi_pp * math.sqrt(KN / (m / 2))                            # its 1/s
xi_w = gamma_n * math.sqrt(m / KN) / 2                                     # m_eff = m at a wall
e_pp, e_w = clamped_restitution(xi_pp), clamped_restitution(xi_w)          # trubal's rest
assert abs(clamped_xi(e_pp) - xi_pp) < 1e-6 and abs(clamped_xi(e_w) - xi_w) < 1e-6
half_period = math.pi / math.sqrt(KN / (m / 2))
rng = random.Random(2718)
balls = []   # jitter in x and y up to 0.25 mm (0.55 mm from a side at least), z up to 0.2 mm
for k in range(NZ):
    for j in range(NX):
        for i in range(NX):
            balls.append(((i + 0.5) * DXY + rng.uniform(-2.5e-4, 2.5e-4),
                          (j + 0.5) * DXY + rng.uniform(-2.5e-4, 2.5e-4),
                          Z0 + k * DZ + rng.uniform(-2e-4, 2e-4)))
n = len(balls)
with open(f"{w}/pour.data", "w") as f:
    f.write(f"pour: {n} balls, R {R!r}, density {RHO!r}\n\n{n} atoms\n1 atom types\n\n"
            f"0 {L!r} xlo xhi\n0 {L!r} ylo yhi\n{-R!r} {ZTOP!r} zlo zhi\n\nAtoms # sphere\n\n")
    for i, (x, y, z) in enumerate(balls, 1):
        f.write(f"{i} 1 {2 * R!r} {RHO!r} {x!r} {y!r} {z!r}\n")
with open(f"{w}/balls.dat", "w") as f:
    for i, (x, y, z) in enumerate(balls, 1):
        f.write(f"ball {x!r} {y!r} {z!r} {R!r} id {i}\n")
with open(f"{w}/pour.in", "w") as f:
    f.write(f"""units si
atom_style sphere
boundary f f fm
newton off
comm_modify vel yes
read_data {w}/pour.data
pair_style gran/hooke/history {KN!r} {KN!r} {gamma_n!r} 0.0 {MU!r} 0
pair_coeff * *
fix xw all wall/gran hooke/history {KN!r} {KN!r} {gamma_n!r} 0.0 {MU!r} 0 xplane 0.0 {L!r}
fix yw all wall/gran hooke/history {KN!r} {KN!r} {gamma_n!r} 0.0 {MU!r} 0 yplane 0.0 {L!r}
fix zw all wall/gran hooke/history {KN!r} {KN!r} {gamma_n!r} 0.0 {MU!r} 0 zplane 0.0 NULL
neighbor {R / 5!r} bin
neigh_modify delay 0 every 1 check yes
timestep {DT!r}
fix g all gravity {G!r} vector 0 0 -1
fix 1 all nve/sphere
compute rke all erotate/sphere
thermo_style custom step atoms ke c_rke
thermo {steps}
run {steps}
compute cc all contact/atom
compute nc all reduce sum c_cc
variable zpp equal c_nc/atoms
variable zm equal xcm(all,z)
variable kt equal ke
variable kr equal c_rke
thermo_style custom step atoms c_nc v_zpp v_zm ke c_rke
run 0 post no
print "RESULT contacts_per_ball ${{zpp}} mean_z ${{zm}} ke ${{kt}} rke ${{kr}}"
""")
with open(f"{w}/pour.dat", "w") as f:
    f.write("\n".join([
        f"start box 0 {L!r} 0 {L!r} {-R!r} {ZTOP!r}",
        f"prop type 1 kn {KN!r} ks {KN!r} mu {MU!r} dens {RHO!r} rest {e_pp!r}",
        f"prop type 2 kn {KN!r} ks {KN!r} mu {MU!r} rest {e_w!r}",
        "wall id 1 plane 0 0 0 0 0 1 type 2",
        "wall id 2 plane 0 0 0 1 0 0 type 2",
        f"wall id 3 plane {L!r} 0 0 -1 0 0 type 2",
        "wall id 4 plane 0 0 0 0 1 0 type 2",
        f"wall id 5 plane 0 {L!r} 0 0 -1 0 type 2",
        f"call {w}/balls.dat", f"grav 0 0 {-G!r}", f"tstep {DT!r}", "backend serial",
        f"cycle {steps}", "print coordination", "print counters", "print energy", f"print balls file {w}/final.csv"]) + "\n")
print(f"pour: {n} balls of R {R * 1e3:g} mm, box {L * 1e3:g} mm square, dt {DT:g} s "
      f"(ball-ball contact half period / {half_period / DT:.1f}), {steps} steps ({steps * DT:g} s); "
      f"gamma_n {gamma_n:.6g} 1/s: damping ratio {xi_pp:.4f} ball-ball, {xi_w:.4f} at a wall; "
      f"head-on restitution LAMMPS {pulling_restitution(xi_pp):.3f} / {pulling_restitution(xi_w):.3f}, "
      f"trubal rest {e_pp:.4f} / {e_w:.4f}")
PY
# One run of "$@" in $W, its output in $W/NAME.out: appends "NAME wall cpu" (seconds; cpu = user + sys)
t() {
  local name=$1 TIMEFORMAT='%R %U %S' r u c; shift
  { time "$@" >"$W/$name.out" 2>&1; } 2>"$W/time.txt" || { cat "$W/$name.out" >&2; echo "$name failed" >&2; exit 1; }
  read -r r u c <"$W/time.txt"
  echo "$name $r $(echo "$u + $c" | bc)" >>"$W/times"
}
echo "CPU: $(lscpu | sed -n 's/^Model name: *//p' | head -1), $(nproc) cores; $REPS interleaved runs, one core each"
cat "$W/scene.txt"
echo "trubal: $TRUBAL${TRUBAL2:+; trubal2: $TRUBAL2}; $(lmp -h | sed -n "s/^Large-scale[^-]*- /LAMMPS /p" | head -1)"
"$HERE/core_speeds.sh"   # a lopsided machine shows beside its figures
: >"$W/times"
cd "$W"
for r in $(seq "$REPS"); do
  t lammps lmp -in pour.in -log none
  t trubal "$TRUBAL" pour.dat; cp final.csv final_trubal.csv
  if [ -n "$TRUBAL2" ]; then t trubal2 "$TRUBAL2" pour.dat; cp final.csv final_trubal2.csv; fi
  echo "  run $r (name, wall s, cpu s): $(tail -n $([ -n "$TRUBAL2" ] && echo 3 || echo 2) times | tr '\n' ' ')"
done
"$HERE/core_speeds.sh"
python3 - "$W" "$STEPS" <<'PY'
import csv, re, statistics, sys
w, steps = sys.argv[1], int(sys.argv[2])
t, cpu = {}, {}
for line in open(f"{w}/times"):
    k, v, c = line.split(); t.setdefault(k, []).append(float(v)); cpu.setdefault(k, []).append(float(c))
m = {k: statistics.median(v) for k, v in t.items()}
mc = {k: statistics.median(v) for k, v in cpu.items()}
names = [k for k in ("lammps", "trubal", "trubal2") if k in t]
print(f"pour, 500 balls, {steps} steps, one core, median of {len(t['lammps'])} "
      "(whole-process wall time, min-max; CPU time user + sys, the less noisy on a shared machine)")
for k in names:
    print(f"  {k:8s} {m[k]:8.3f} s  ({min(t[k]):.3f}-{max(t[k]):.3f})  {500 * steps / m[k] / 1e6:6.2f} M ball-steps/s"
          f"   CPU {mc[k]:7.3f} s ({min(cpu[k]):.3f}-{max(cpu[k]):.3f})")
for k in names[1:]:
    print(f"  LAMMPS / {k}: {m['lammps'] / m[k]:.2f}x wall, {mc['lammps'] / mc[k]:.2f}x CPU")
res = re.findall(r"RESULT contacts_per_ball (\S+) mean_z (\S+) ke (\S+) rke (\S+)", open(f"{w}/lammps.out").read())
if not res:
    sys.exit("pour_vs_lammps: no RESULT line in LAMMPS's output")
got = {"lammps": (float(res[-1][0]), float(res[-1][1]))}
for k in names[1:]:
    text = open(f"{w}/{k}.out").read()
    rebuilds = re.search(r"^pair_list_rebuilds (\d+)$", text, re.M)
    c = re.search(r"^contacts (\d+)$", text, re.M)
    b = re.search(r"^wall_contacts (\d+)$", text, re.M)
    rows = list(csv.DictReader(open(f"{w}/final_{k}.csv")))
    zm = sum(float(r["z"]) for r in rows) / len(rows)
    got[k] = (2.0 * int(c.group(1)) / len(rows), zm)   # PRINT counters: contacts = touching ball pairs
    cyc = re.search(r"cycles in ([0-9.eE+-]+) s[^;]*; (.*)\)\s*$", text, re.M)
    ke = [re.search(rf"^kinetic \({p}\): *(\S+)", text, re.M) for p in ("translation", "rotation")]
    print(f"  {k}: last run's cycling {cyc.group(1) if cyc else '?'} s ({cyc.group(2) if cyc else '?'}); "
          f"{rebuilds.group(1) if rebuilds else '?'} pair list rebuilds; at the end {b.group(1) if b else '?'} "
          f"wall contacts, kinetic energy {' + '.join(x.group(1) if x else '?' for x in ke)} J (translation + rotation)")
loop = re.search(r"Loop time of ([0-9.eE+-]+) on 1 procs for [1-9]", open(f"{w}/lammps.out").read())
nb = re.search(r"Neighbor list builds = (\d+)", open(f"{w}/lammps.out").read())
print(f"  lammps: last run's loop time {loop.group(1) if loop else '?'} s; {nb.group(1) if nb else '?'} neighbour list "
      f"builds; at the end kinetic energy {res[-1][2]} + {res[-1][3]} J (translation + rotation)")
bad = False
print("  the same scene? final contacts per ball (ball pairs, 2 C / N) and mean centre height:")
zl, hl = got["lammps"]
for k in names:
    z, h = got[k]
    dz = (z - zl) / zl if zl else 0.0
    dh = (h - hl) / hl
    ok = (abs(dz) <= 0.06 or abs(z - zl) < 0.05) and abs(dh) <= 0.02
    bad |= not ok
    print(f"    {k:8s} {z:7.4f} ({dz:+.2%})  {h * 1e3:8.4f} mm ({dh:+.2%})" + ("" if ok else "  DIFFERS"))
sys.exit(1 if bad else 0)
PY
