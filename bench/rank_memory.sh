#!/bin/bash
# Each rank's peak resident memory through a deck of the peers' dense FCC block, stage by stage,
# against its share of the serial run's peak (doc/distributed.md, "Memory per rank"): the BALL
# lines; CYCLE 20; SAVE and PRINT contacts file; DAMP and CYCLE 10; HIST of the stress, the
# unbalanced force and the contacts every 5 cycles and CYCLE 10 (its output steps); DUMP vtk every
# 10 cycles and CYCLE 10 (a dump now and one in the CYCLE, the files compared with serial's); with LONG, a long CYCLE
# (LONG cycles: the sorts into space order every 1000 cycles and the rescue copies every 500 in
# it); then, in a second run, RESTART of the serial run's save and CYCLE 10 after it. The decks
# have BACKEND mpi first and PRINT counters after each stage; a stage's figure is each rank's `rank<r>_peak_mib`
# there (the peak so far), read from the counters' files. Memory does not depend on the machine's
# load: one run each.
#
#   bench/rank_memory.sh build/trubal [CELLS]     CELLS: FCC cells a side (default 63: 1,000,188
#                                                   balls, about 2 GiB on one rank and 30 s)
#   env: RANKS ("2 4"; more oversubscribe a small machine), LONG (cycles of the long CYCLE; none
#        by default: at 1,000,188 balls a thousand cycles take some minutes a run)
#
# Prints, per stage, the serial peak, then for each rank count rank 0's peak, the others' (least
# to most) and the most of them over a share (serial peak / P). The files each run writes (the
# save, the contacts) are compared with serial's: a run whose bytes differ is reported. Writes only
# under a temporary folder.
set -eu
TRUBAL=$(realpath "$1"); CELLS=${2:-63}; RANKS=${RANKS:-2 4}
HERE=$(cd "$(dirname "$0")" && pwd)
. "$HERE/mpi_setup.sh"
mpi_bench_setup memory
cd "$W"
SCENES_OUT=. python3 -c "import sys; sys.path.insert(0, '$PEERS'); import gen_scenes; gen_scenes.fcc($CELLS, $CELLS, $CELLS)" >/dev/null
STAGES="balls cycle save damp hist dump"
LONG=${LONG:-}
[ -n "$LONG" ] && STAGES="$STAGES long"
{
  echo "backend mpi"
  python3 "$HERE/fcc_deck.py" fcc_*.xyz
  echo "print counters file balls.txt"
  echo "cycle 20"
  echo "print counters file cycle.txt"
  echo "save out.sav"
  echo "print contacts file contacts.csv"
  echo "print counters file save.txt"
  echo "damp local 0.1"
  echo "cycle 10"
  echo "print counters file damp.txt"
  echo "hist stress unbal contacts every 5 file hist.csv"
  echo "cycle 10"
  echo "print counters file hist.txt"
  echo "dump vtk d/run every 10"
  echo "cycle 10"
  echo "print counters file dump.txt"
  echo "dump off"
  if [ -n "$LONG" ]; then echo "cycle $LONG"; echo "print counters file long.txt"; fi
} > deck.dat
printf 'backend mpi\nrestart ../p1/out.sav\nprint counters file restart.txt\ncycle 10\nprint counters file rcycle.txt\nsave again.sav\n' > restart.dat
echo "$(head -1 fcc_*.xyz | cut -d' ' -f1) balls; CPU: $(lscpu | sed -n 's/^Model name: *//p' | head -1), $(nproc) cores"

# run P DECK DIR: the deck on P ranks (1: one process, without mpirun) in the folder DIR<P>.
run() {
  mkdir -p "$3$1" && cd "$3$1"
  if [ "$1" = 1 ]; then "$TRUBAL" "../$2" >out.txt 2>&1 || { echo "the serial run of $2 failed" >&2; tail -3 out.txt >&2; exit 1; }
  else mpirun -np "$1" "$TRUBAL" "../$2" >out.txt 2>&1 || { echo "the run of $2 on $1 ranks failed" >&2; tail -3 out.txt >&2; exit 1; }
  fi
  cd ..
}
# peaks P STAGE: each rank's peak MiB at that stage, space-separated (one process: its own); the
# stages after RESTART are the second run's (folder r<P>).
peaks() {
  local f="p$1/$2.txt"
  case "$2" in restart|rcycle) f="r$1/$2.txt" ;; esac
  if [ "$1" = 1 ]; then awk '$1 == "peak_mib" { printf "%.0f", $2 }' "$f"
  else awk '$1 ~ /^rank[0-9]+_peak_mib$/ { sub(/^rank/, "", $1); sub(/_peak_mib$/, "", $1); p[$1] = $2; n++ }
            END { for (r = 0; r < n; r++) printf "%s%.0f", (r ? " " : ""), p[r] }' "$f"
  fi
}
run 1 deck.dat p
run 1 restart.dat r
for p in $RANKS; do
  run "$p" deck.dat p
  run "$p" restart.dat r
  for f in out.sav contacts.csv hist.csv $(cd p1 && ls d/*); do cmp -s "p1/$f" "p$p/$f" || echo "$p ranks: $f differs from serial's" >&2; done
  rm -rf "p$p/d"
  cmp -s r1/again.sav "r$p/again.sav" || echo "$p ranks: the save after RESTART differs from serial's" >&2
done
STAGES="$STAGES restart rcycle"
printf '%-7s %7s' stage serial
for p in $RANKS; do printf ' | %-28s' "$p ranks: 0, others, most/share"; done
echo
for s in $STAGES; do
  serial=$(peaks 1 "$s")
  printf '%-7s %7s' "$s" "$serial"
  for p in $RANKS; do
    read -r -a v <<< "$(peaks "$p" "$s")"
    others=("${v[@]:1}")
    lo=$(printf '%s\n' "${others[@]}" | sort -n | head -1); hi=$(printf '%s\n' "${others[@]}" | sort -n | tail -1)
    ratio=$(awk -v hi="$hi" -v s="$serial" -v p="$p" 'BEGIN { printf "%.2f", hi / (s / p) }')
    rank0=$(awk -v r="${v[0]}" -v s="$serial" -v p="$p" 'BEGIN { printf "%s (%.1f)", r, r / (s / p) }')
    printf ' | %-28s' "$rank0, $lo-$hi, $ratio"
  done
  echo
done
