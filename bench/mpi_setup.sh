# Sourced by the MPI benchmarks (bench/mpi_scaling.sh, bench/rank_memory.sh), with HERE their
# folder: `mpi_bench_setup NAME` checks for the peers' scenes and mpirun, makes the temporary
# folder W (/tmp/trubal-NAME-XXXXXX, removed on exit) and lets mpirun run as root and place more
# ranks than cores.
mpi_bench_setup() {
  PEERS=$HERE/../../shared/peers
  [ -f "$PEERS/gen_scenes.py" ] || { echo "no $PEERS/gen_scenes.py (the peers' scenes)" >&2; exit 2; }
  command -v mpirun >/dev/null || { echo "no mpirun (Debian: openmpi-bin)" >&2; exit 2; }
  W=$(mktemp -d "/tmp/trubal-$1-XXXXXX")
  trap 'rm -rf "$W"' EXIT
  export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
}
