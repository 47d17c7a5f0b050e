#!/bin/bash
# The peak resident memory of a deck of the peers' dense FCC block, stage by stage: the BALL lines
# alone; + CYCLE 20; + SAVE; + PRINT contacts file. Each trubal given is run on each stage in turn
# (interleaved), one run at a time, and its peak (`/usr/bin/time -f %M`) printed in MiB.
#
#   bench/memory_deck.sh [CELLS] TRUBAL [TRUBAL...]
#
# CELLS: FCC cells a side (default 63: 1,000,188 balls; a run then takes about 1.6 GiB and a
# minute or two). The scene is ../shared/peers/gen_scenes.py's, the deck bench/fcc_deck.py's. Writes
# only under a temporary folder.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
cells=63
if [[ $# -gt 0 && $1 =~ ^[0-9]+$ ]]; then cells=$1; shift; fi
[[ $# -ge 1 ]] || { echo "usage: $0 [CELLS] TRUBAL [TRUBAL...]" >&2; exit 2; }
exes=()
for e in "$@"; do exes+=("$(readlink -f "$e")"); done
peers=${PEERS:-$here/../../shared/peers}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cd "$tmp"
SCENES_OUT=. python3 -c "import sys; sys.path.insert(0, '$peers'); import gen_scenes; gen_scenes.fcc($cells, $cells, $cells)" >/dev/null
xyz=$(ls fcc_*.xyz)
python3 "$here/fcc_deck.py" "$xyz" > body.dat
(cat body.dat; echo CYCLE 20) > cycle.dat
(cat cycle.dat; echo SAVE out.sav) > save.dat
(cat save.dat; echo PRINT contacts file contacts.csv) > print.dat
echo "$(head -1 "$xyz" | cut -d" " -f1) balls; $(lscpu | grep 'Model name' | sed 's/  */ /g')"
printf '%-8s %s\n' stage "peak MiB of each trubal in turn"
for stage in body cycle save print; do
  line=$(printf '%-8s' "$stage")
  for e in "${exes[@]}"; do
    /usr/bin/time -f %M -o peak.txt "$e" "$stage.dat" >/dev/null 2>&1
    kib=$(tail -1 peak.txt)
    line+=" $((kib / 1024))"
    rm -f out.sav contacts.csv
  done
  echo "$line"
done
