#!/bin/bash
# The same 20,384 balls (a jittered simple cubic block, radius 0.0178, 0.035 apart: each touches
# its neighbours) crowded into a 1 m corner of a 10 m periodic cell, and filling a 0.98 m cell
# alone; 100 cycles of each, interleaved, `repeats` times. The corner costs what the filled cell
# costs when the pair search's bins follow the balls (doc/speed.md, "Balls crowded into a corner").
#   bench/clustered.sh [trubal] [repeats]     (default build/trubal, 2)
set -eu
bin=${1:-build/trubal}
repeats=${2:-2}
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
python3 - "$dir" <<'PY'
import random, sys
random.seed(1)
lines, n = [], 0
for i in range(28):
    for j in range(28):
        for k in range(26):
            n += 1
            p = [0.0175 + 0.035 * c + random.uniform(-3e-4, 3e-4) for c in (i, j, k)]
            lines.append("ball %.12g %.12g %.12g 0.0178 id %d" % (p[0], p[1], p[2], n))
body = "\n".join(lines) + "\n"
for name, L in (("corner", 10), ("filled", 0.98)):
    with open(f"{sys.argv[1]}/{name}.dat", "w") as f:
        f.write(f"start {L} {L} {L}\nprop kn 1e5 ks 1e5 mu 0.5 dens 2650\n{body}cycle 1\ncycle 100\n")
PY
echo "$(lscpu | sed -n 's/^Model name: *//p'); $bin"
for r in $(seq "$repeats"); do
  for scene in corner filled; do
    line=$("$bin" "$dir/$scene.dat" 2>&1 | grep '^cycle 101')
    echo "$scene: ${line#*(}" | cut -d';' -f1-2
  done
done
