#!/bin/bash
# One line on how fast each core of this machine runs the same work now: a pure-Python loop pinned
# to each core in turn (taskset), its time in seconds. On the project's shared 2-core virtual
# machines one core has run the same binary up to 1.7 times slower than the other for minutes at
# a time (bench/NOTES.md); a run that shares a step among threads or ranks then waits for the slow
# one. The benchmark scripts print this line before and after their runs so that a lopsided machine
# shows beside the figures it made.
#
#   bench/core_speeds.sh        e.g. "core seconds (same loop, pinned): 0: 0.21  1: 0.36"
set -eu
command -v taskset >/dev/null || { echo "core seconds: taskset missing (util-linux)"; exit 0; }
line="core seconds (same loop, pinned):"
for c in $(seq 0 $(($(nproc) - 1))); do
  t=$(taskset -c "$c" python3 -c '
import time
t = time.perf_counter()
s = 0
for i in range(2_000_000): s += i * i
print(f"{time.perf_counter() - t:.2f}")')
  line="$line  $c: $t"
done
echo "$line"
