#!/bin/bash
# The cost of parallel bonds (doc/speed.md "Bonds"): a periodic sample of 20,126 balls pressed by the
# servo to 37,500 contacts, then strained 1100 cycles unbonded and with a bond on every touching pair
# (37,584 bonds). Prints the CPU seconds of each run (restart and 1100 cycles), three times each;
# given a second program, the two interleaved (the first makes the sample).
# Usage: bench/bonds_speed.sh build/trubal [other/trubal]
set -euo pipefail
trubal=$(realpath "${1:-build/trubal}")
programs=("$trubal")
if [ -n "${2:-}" ]; then programs+=("$(realpath "$2")"); fi
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
cd "$dir"
cat > gen.dat <<'DECK'
start 0.1 0.1 0.1
prop kn 2e6 ks 1e6 fric 30 dens 2650
gen porosity 0.44 0.00144 0.00226 seed 3
damp local 0.7
servo 2e5 2e5 2e5
cycle 3000
save p20k.sav
DECK
"$trubal" gen.dat > /dev/null
for bonded in 0 1; do
  { echo "restart p20k.sav"
    if [ "$bonded" = 1 ]; then echo "bond kn 1e11 ks 4e10 ten 1e7 coh 2e7 fa 30"; fi
    echo "servo off"; echo "strain zz 1"; echo "cycle 1100"; } > run$bonded.dat
done
TIMEFORMAT='%U s'
for k in 1 2 3; do
  for program in "${programs[@]}"; do
    for bonded in 0 1; do
      echo -n "$program bonded=$bonded "
      { time "$program" run$bonded.dat > /dev/null; } 2>&1
    done
  done
done
