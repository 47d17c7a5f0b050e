#!/bin/sh
# trubal_bench's command line: --help prints the usage and exits 0 without running a
# benchmark; bad arguments are refused with a message and exit status 2, before any run; with the
# peers' scene generator (../shared/peers, or TRUBAL_PEERS), --settle runs a small settle scene.
#   bench_cli.sh BENCH [PEERS_DIR]
BENCH=$1
PEERS=${2:-${TRUBAL_PEERS:-}}
fail=0
W=$(mktemp -d /tmp/trubal-bench-cli-XXXXXX)
trap 'rm -rf "$W"' EXIT

for h in --help -h; do
  if ! "$BENCH" $h >"$W/out" 2>"$W/err"; then echo "FAIL: $h exited $?"; fail=1; fi
  grep -q '^usage:' "$W/out" || { echo "FAIL: $h printed no usage:"; cat "$W/out" "$W/err"; fail=1; }
  grep -q -- '--settle FILE' "$W/out" || { echo "FAIL: $h does not name --settle"; fail=1; }
  if grep -qi 'nan\|ball-steps/s' "$W/out"; then echo "FAIL: $h ran a benchmark:"; cat "$W/out"; fail=1; fi
done

# Each refused with exit status 2 and a message naming what was wrong.
refuse() {
  want=$1; shift
  "$BENCH" "$@" >"$W/out" 2>"$W/err"
  rc=$?
  if [ "$rc" -ne 2 ]; then echo "FAIL: trubal_bench $* exited $rc, not 2"; cat "$W/out" "$W/err"; fail=1; return; fi
  grep -q -- "$want" "$W/err" || { echo "FAIL: trubal_bench $*: no '$want' in:"; cat "$W/err"; fail=1; }
  [ -s "$W/out" ] && { echo "FAIL: trubal_bench $* printed results:"; cat "$W/out"; fail=1; }
}
refuse "unknown option" --bogus
refuse "not a ball count" 0
refuse "not a ball count" 12x
refuse "not a ball count" -5
refuse "whole number above 0" --steps
refuse "whole number above 0" --steps 0
refuse "whole number above 0" --threads two
refuse "unknown backend 'mpi'" --backend mpi
refuse "separate benchmarks" --compare --gen
refuse "not ball counts" --settle x.xyz 1000
"$BENCH" --settle "$W/none.xyz" >"$W/out" 2>"$W/err"
rc=$?
[ "$rc" -eq 1 ] && grep -q "cannot open" "$W/err" || { echo "FAIL: --settle of a missing file: exit $rc"; cat "$W/err"; fail=1; }

# The dense block prints its peak memory: a small block,
# whose peak is above the program's own few MiB and below 200 MiB, and the same per ball.
if "$BENCH" --steps 20 1680 >"$W/out" 2>"$W/err"; then
  grep -q 'peak MiB' "$W/out" || { echo "FAIL: no peak MiB column"; cat "$W/out"; fail=1; }
  awk '$1 == 1680 && $NF ~ /^[0-9]+$/ { ok = ($(NF-1) > 2 && $(NF-1) < 200 && $NF > 1000) } END { exit !ok }' "$W/out" ||
    { echo "FAIL: the 1680-ball row's peak memory is not plausible"; cat "$W/out"; fail=1; }
  # The limit memory sets, per scene: the bytes a ball-step moves are those bench/traffic.hpp counts
  # (the standard scene's about 800 at 5.9 pairs a ball: 500 to 1500 says the count and the pairs
  # were taken), the copy bandwidth is measured (above 0.1 GB/s) and the fraction is a number.
  awk '$1 == 1680 && $2 == "standard" { ok = ($(NF-4) > 500 && $(NF-4) < 1500 && $(NF-3) > 0.1 && $NF ~ /^[0-9]+%$/) }
       END { exit !ok }' "$W/out" ||
    { echo "FAIL: the 1680-ball standard scene's memory limit row is not plausible"; cat "$W/out"; fail=1; }
else
  echo "FAIL: trubal_bench --steps 20 1680 exited $?"; cat "$W/out" "$W/err"; fail=1
fi

# A small settle scene (the peers' generator, 400 balls, 300 steps), where the generator is here.
if [ -n "$PEERS" ] && [ -f "$PEERS/gen_scenes.py" ] && command -v python3 >/dev/null; then
  PEERS=$(cd "$PEERS" && pwd)
  (cd "$W" && SCENES_OUT=$W python3 -c "import sys; sys.path.insert(0, sys.argv[1]); import gen_scenes; gen_scenes.settle(400, 300.0)" "$PEERS") >/dev/null || { echo "FAIL: gen_scenes.settle"; fail=1; }
  if "$BENCH" --settle "$W/settle_400.xyz" --steps 300 --phases >"$W/out" 2>"$W/err"; then
    grep -q 'whole run:' "$W/out" || { echo "FAIL: --settle printed no totals"; cat "$W/out"; fail=1; }
    grep -q 'the limit set by memory: [0-9]* B a ball-step' "$W/out" || { echo "FAIL: --settle printed no memory limit"; cat "$W/out"; fail=1; }
  else
    echo "FAIL: --settle exited $?"; cat "$W/out" "$W/err"; fail=1
  fi
else
  echo "(the peers' gen_scenes.py is not here: --settle not run)"
fi
[ "$fail" -eq 0 ] && echo "trubal_bench command line: ok"
exit $fail
