#!/bin/sh
# Whether the contact law's batch loops (physics/contact_law.hpp, contact_lanes and the rolling
# springs' rolling_lanes) were compiled to SIMD code: each instantiation in the binary must hold
# packed double arithmetic (mulpd, vmulpd, ...),
# not only scalar (mulsd). g++ 12 once left the loop scalar on AVX2 machines, where a division it
# kept on one path of a select could trap (CMakeLists.txt, -fno-trapping-math): the dense block's
# step 1.3 times slower, with the same answers, so no other test saw it. Exit 77 (skipped) where it cannot look: not
# x86-64, or no objdump.
#   tests/bench/vectorised.sh BINARY
set -eu
bin=$1
[ "$(uname -m)" = x86_64 ] || { echo "skipped: not x86-64"; exit 77; }
command -v objdump >/dev/null || { echo "skipped: objdump missing (binutils)"; exit 77; }
# Left out: one lane alone (kOne, the third bool), and the one-law dashpot loops' entry, which only
# picks the loop of its restitution (kRest 0 with a dashpot and one law; contact_law.hpp). The
# features print as far as their last true member (details after dashpot; contact_lanes has no
# rolling).
objdump -d -C --no-show-raw-insn "$bin" | awk -v one=', (true|false), (true|false), true(, [0-9])?>\\(' \
    -v dispatch='ContactFeatures\\{[a-z]+, [a-z]+, [a-z]+, true(, [a-z]+)*\\}, true, (true|false), (true|false), 0>\\(' '
  /^[0-9a-f]+ <.*>:$/ { name = $0; inside = (name ~ /(contact|rolling)_lanes</ && name !~ one && name !~ dispatch); if (inside) { count++; packed[name] = 0 } next }
  inside && /(add|sub|mul|div|sqrt)pd/ { packed[name]++ }
  END {
    bad = 0
    for (n in packed) if (packed[n] == 0) { print "scalar: " n; bad++ }
    printf "%d contact_lanes and rolling_lanes instantiations over a batch, %d without packed double arithmetic\n", count, bad
    if (count == 0) { print "no contact_lanes in the binary"; exit 1 }
    exit bad > 0
  }'
