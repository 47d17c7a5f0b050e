#!/bin/sh
# The benchmark scripts still run (they are run by hand, on other machines, where a broken one
# costs a lease): bench/mpi_scaling.sh, bench/scaling.py and bench/rank_memory.sh on the smallest
# scenes for a few steps, their tables checked for a row per rank count. Nothing is timed or
# compared. Exit 77 (skipped) without python3, mpirun or the peers' scene writer beside the checkout
# (../shared/peers/gen_scenes.py).
#   tests/bench/scripts.sh TRUBAL
set -eu
trubal=$1
here=$(cd "$(dirname "$0")/../.." && pwd)
peers=$here/../shared/peers
command -v python3 >/dev/null || { echo "skipped: no python3"; exit 77; }
command -v mpirun >/dev/null || { echo "skipped: no mpirun (openmpi-bin)"; exit 77; }
[ -f "$peers/gen_scenes.py" ] || { echo "skipped: no $peers/gen_scenes.py"; exit 77; }
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
# (Under ASan, Open MPI's own allocations left at exit are not trubal's leaks: the MPI tests say the same.)
export ASAN_OPTIONS="detect_leaks=0${ASAN_OPTIONS:+:$ASAN_OPTIONS}"
out=$(mktemp)
trap 'rm -f "$out"' EXIT
fail() { cat "$out"; echo "FAILED: $1"; exit 1; }

STEPS=5 REPS=1 RANKS="1 2" "$here/bench/mpi_scaling.sh" "$trubal" 1680 >"$out" 2>&1 || fail "mpi_scaling.sh exited $?"
for run in mpi_1 mpi_2 threaded_2 serial; do
  grep -Eq "^  $run +[0-9.]+ " "$out" || fail "mpi_scaling.sh: no row for $run"
done
grep -q "mpi on 2 ranks / threaded on 2: " "$out" || fail "mpi_scaling.sh: no ratio line"

python3 "$here/bench/scaling.py" "$trubal" --ranks 1 2 --strong 5x5x5 --weak 4x4x4 --steps 5 --reps 1 \
    >"$out" 2>&1 || fail "scaling.py exited $?"
for mode in strong weak; do
  grep -q "^$mode scaling, 5 steps" "$out" || fail "scaling.py: no $mode table"
done
# Rows "P N | ...": P = 1 and 2, in each table (4 rows), with the ranks' peak memory read.
rows=$(grep -Ec "^ +[12] +[0-9]+ \| .* [0-9]+/[0-9]+ \|" "$out") || true
[ "$rows" = 4 ] || fail "scaling.py: $rows table rows with the ranks' memory, not 4"
# bench/rank_memory.sh on a block of 500 balls on 2 ranks: a row per stage, each with rank 0's and
# the other's peaks, and the files serial's (it says where they are not).
RANKS=2 "$here/bench/rank_memory.sh" "$trubal" 5 >"$out" 2>&1 || fail "rank_memory.sh exited $?"
for stage in balls cycle save damp; do
  grep -Eq "^$stage +[0-9]+ \| [0-9]+ \([0-9.]+\), [0-9]+-[0-9]+, [0-9.]+" "$out" || fail "rank_memory.sh: no row for $stage"
done
if grep -q "differs" "$out"; then fail "rank_memory.sh: a file differs from serial's"; fi
echo "bench scripts: mpi_scaling.sh, scaling.py and rank_memory.sh ran"
