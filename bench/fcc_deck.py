"""The peers' dense FCC block as a trubal deck's opening lines: START (the lattice's box), the
material of ../shared/peers/lammps_fcc.in, one BALL per line of gen_scenes.py's fcc_<N>.xyz (radius
20, ids from 1 in the file's order) and the step. bench/scaling.py and bench/mpi_scaling.sh both
write their decks from it, so the two benchmarks step the same model."""
import sys


def fcc_body(xyz_path):
    """The deck lines (a list of strings, no newlines) for the block in xyz_path."""
    lines = open(xyz_path).read().split("\n")
    count, lx, ly, lz = lines[0].split()
    body = [f"START {lx} {ly} {lz}", "PROP KN 1.5E9 KS 1.5E9 MU 0.12278 DENS 2000"]
    body += [f"BALL {l} 20 ID {i}" for i, l in enumerate(lines[1:int(count) + 1], 1)]
    body.append("TSTEP 0.02")
    return body


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit("usage: fcc_deck.py fcc_<N>.xyz   (prints the deck's opening lines)")
    print("\n".join(fcc_body(sys.argv[1])))
