#!/bin/sh
# A test whose program is missing is reported as skipped (exit 77 under ctest), never as passed:
# runs one MPI test and one shell (tmux) test of the test program with a PATH on which mpirun and
# tmux cannot be found (links to every other program of /usr/bin and /bin), and expects 77 from each.
#   tests/skip/missing_tools.sh TRUBAL_TESTS
set -u
tests=$1
W=$(mktemp -d); trap 'rm -rf "$W"' EXIT
mkdir "$W/bin"
for d in /bin /usr/bin; do
  for p in "$d"/*; do
    n=${p##*/}
    case "$n" in mpirun|mpiexec|orterun|tmux) continue ;; esac
    [ -e "$W/bin/$n" ] || ln -s "$p" "$W/bin/$n"
  done
done
fail=0
for t in "distributed: 4 ranks\, and a save on 3 ranks restarted on 2\, give the serial bits" \
         "interp shell: a command runs and HELP lists the commands"; do
  PATH=$W/bin TRUBAL_TEST_SKIP_CODE=77 "$tests" "$t" >"$W/out" 2>&1
  rc=$?
  if [ $rc != 77 ]; then echo "FAIL: '$t' without mpirun and tmux exited $rc, not 77 (skipped):"; cat "$W/out"; fail=1
  elif ! grep -q '^SKIP: ' "$W/out"; then echo "FAIL: '$t' gave 77 but printed no 'SKIP: reason'"; cat "$W/out"; fail=1
  else echo "ok: '$t' skipped: $(grep '^SKIP: ' "$W/out")"; fi
done
exit $fail
