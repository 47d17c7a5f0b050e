#!/bin/bash
# Packs a trubal binary with this Debian machine's Open MPI (4.1) and LAMMPS, and every library
# they load, glibc's included, into one tarball that runs on a Linux machine of another
# distribution, where these packages cannot be installed (the 16-core runs of doc/distributed.md,
# "16 cores", were made so). Every ELF file in it loads its libraries from the bundle alone: its
# interpreter and DT_RPATH point into PREFIX, which is where the tarball must be unpacked there.
#
#   bench/portable_bundle.sh TRUBAL OUT.tar.xz [PREFIX (default /tmp/tdev)]
# There:  tar -C "$(dirname PREFIX)" -xJf OUT.tar.xz
#         export OPAL_PREFIX=PREFIX/usr PMIX_MCA_mca_base_component_path=PREFIX/usr/lib/x86_64-linux-gnu/pmix2/lib/pmix
#         python3 bench/scaling.py PREFIX/bin/trubal --mpirun PREFIX/usr/bin/mpirun --lmp PREFIX/usr/bin/lmp
# Needs patchelf (Debian: patchelf) and the packages of .ci/deps. Build TRUBAL for the other
# machine's CPU (-DTRUBAL_NATIVE=OFF -DCMAKE_CXX_FLAGS=-march=...): a -march=native build is for
# the building machine's.
set -eu
[ $# -ge 2 ] || { sed -n 2,13p "$0"; exit 2; }
TRUBAL=$(realpath "$1"); OUTFILE=$(realpath -m "$2"); T=${3:-/tmp/tdev}
command -v patchelf >/dev/null || { echo "patchelf missing (Debian: patchelf)" >&2; exit 2; }
rm -rf "$T"; mkdir -p "$T/lib" "$T/bin"
for p in openmpi-bin libopenmpi3 openmpi-common libpmix2 lammps liblammps0 libhwloc15 libhwloc-plugins; do
  dpkg -L "$p"
done | sort -u | while read -r f; do
  case "$f" in /usr/share/doc*|/usr/share/man*|/usr/share/lintian*) continue;; esac
  if [ -L "$f" ] || [ -f "$f" ]; then mkdir -p "$T$(dirname "$f")"; cp -a "$f" "$T$f"; fi
done
ln -sf orterun "$T/usr/bin/mpirun"
cp "$TRUBAL" "$T/bin/trubal"
elfs=$(find "$T" -type f | while read -r f; do file "$f" | grep -q ELF && echo "$f"; done)
for f in $elfs; do ldd "$f" 2>/dev/null | awk '/=> \//{print $3}'; done | sort -u | while read -r l; do
  b=$(basename "$l"); [ -e "$T/lib/$b" ] || cp -L "$l" "$T/lib/$b"
done
cp -L /lib64/ld-linux-x86-64.so.2 "$T/lib/"
RP=$T/lib:$T/usr/lib/x86_64-linux-gnu:$T/usr/lib/x86_64-linux-gnu/openmpi/lib
for f in $elfs $(ls "$T"/lib/*.so* | grep -v -E "ld-linux|/libc.so"); do
  patchelf --force-rpath --set-rpath "$RP" "$f"
  if readelf -l "$f" 2>/dev/null | grep -q "program interpreter"; then
    patchelf --set-interpreter "$T/lib/ld-linux-x86-64.so.2" "$f"
  fi
done
tar -C "$(dirname "$T")" -cJf "$OUTFILE" "$(basename "$T")"
echo "$OUTFILE: $(du -h "$OUTFILE" | cut -f1) ($(du -sh "$T" | cut -f1) unpacked)"
