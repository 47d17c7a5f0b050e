#!/usr/bin/env python3
"""Turn a LAMMPS data file of spheres (atom_style sphere: id type diameter density x y z, as
../../../shared/peers/gen_scenes.py writes them) into trubal BALL commands.

    lammps_to_trubal.py IN.data --balls OUT.dat [--walls] [--data WALLED.data] [--seed S]

--balls OUT.dat   one `ball x y z rad id i` line per sphere, in id order (CALL it from a deck);
                  without --walls every sphere is kept where the data file puts it (trubal's
                  START box ... x periodic y periodic is LAMMPS's boundary p p: nothing to move)
--walls           for a container with walls on the x and y faces of the box instead of periodic
                  x and y (settle_vs_lammps.py --container walls). The centres closer to a face
                  than their radius (the spheres the periodic faces cut) are moved inward until
                  they just clear it; any sphere that then overlaps another is placed again at
                  random (random sequential addition, seed S) in the walled box, at a height
                  within the initial slab. Reports how many of each.
--data W.data     write the positions used as a LAMMPS data file too, so that LAMMPS can run the
                  walled scene from the very same state.
Prints one line `box xlo xhi ylo yhi zlo zhi n N radius R density RHO top ZMAX` for the caller
(ZMAX the highest centre).
"""
import argparse
import math
import random
import sys


def read_data(path):
    box = {}
    atoms = []
    header = []
    with open(path) as f:
        lines = f.read().splitlines()
    section = None
    for line in lines:
        text = line.split("#", 1)[0].strip()
        if not text:
            continue
        words = text.split()
        if section is None:
            if words[-2:] in (["xlo", "xhi"], ["ylo", "yhi"], ["zlo", "zhi"]):
                box[words[-2][0]] = (float(words[0]), float(words[1]))
            elif words[0] == "Atoms":
                section = "Atoms"
            header.append(line)
        elif section == "Atoms":
            if not words[0].lstrip("-").isdigit():
                break   # the next section
            i, t, d, rho, x, y, z = words[:7]
            atoms.append([int(i), int(t), float(d), float(rho), float(x), float(y), float(z)])
    atoms.sort(key=lambda a: a[0])
    return box, atoms


class Grid:
    """Cells of side >= one diameter over the walled box (no periodicity)."""

    def __init__(self, lo, hi, cell):
        self.lo, self.cell = lo, cell
        self.n = [max(1, int((h - l) // cell)) for l, h in zip(lo, hi)]
        self.cells = {}

    def key(self, p):
        return tuple(min(max(int((p[k] - self.lo[k]) / self.cell), 0), self.n[k] - 1) for k in range(3))

    def add(self, idx, p):
        self.cells.setdefault(self.key(p), []).append(idx)

    def overlaps(self, p, r, pos, rad, skip):
        ci = self.key(p)
        for dx in (-1, 0, 1):
            for dy in (-1, 0, 1):
                for dz in (-1, 0, 1):
                    for j in self.cells.get((ci[0] + dx, ci[1] + dy, ci[2] + dz), ()):
                        if j == skip:
                            continue
                        q = pos[j]
                        lim = r + rad[j]
                        if (p[0] - q[0]) ** 2 + (p[1] - q[1]) ** 2 + (p[2] - q[2]) ** 2 < lim * lim:
                            return True
        return False


def fit_walls(box, atoms, seed):
    """Move the spheres that the x and y faces cut inside; re-place those that then overlap."""
    (x0, x1), (y0, y1) = box["x"], box["y"]
    rad = [a[2] / 2 for a in atoms]
    pos = [[a[4], a[5], a[6]] for a in atoms]
    rmax = max(rad)
    zs = [p[2] for p in pos]
    zlo, zhi = min(zs), max(zs)
    grid = Grid((x0, y0, zlo - 2 * rmax), (x1, y1, zhi + 2 * rmax), 2 * rmax)
    cut = [k for k, p in enumerate(pos)
           if p[0] - x0 < rad[k] or x1 - p[0] < rad[k] or p[1] - y0 < rad[k] or y1 - p[1] < rad[k]]
    cutset = set(cut)
    for k, p in enumerate(pos):
        if k not in cutset:
            grid.add(k, p)
    rng = random.Random(seed)
    moved = replaced = 0
    clear = 1e-6   # just clear of the wall: no overlap, no force
    for k in cut:
        r = rad[k]
        p = pos[k]
        q = [min(max(p[0], x0 + r + clear), x1 - r - clear), min(max(p[1], y0 + r + clear), y1 - r - clear), p[2]]
        if grid.overlaps(q, r, pos, rad, k):
            for _ in range(10 ** 6):
                q = [rng.uniform(x0 + r + clear, x1 - r - clear), rng.uniform(y0 + r + clear, y1 - r - clear),
                     rng.uniform(max(zlo, r), zhi)]
                if not grid.overlaps(q, r, pos, rad, k):
                    break
            else:
                sys.exit("lammps_to_trubal.py: no room to place sphere %d inside the walls" % atoms[k][0])
            replaced += 1
        else:
            moved += 1
        pos[k] = q
        grid.add(k, q)
    for a, p in zip(atoms, pos):
        a[4], a[5], a[6] = p
    return moved, replaced


def write_data(path, box, atoms, comment):
    with open(path, "w") as f:
        f.write("# %s\n\n%d atoms\n\n%d atom types\n\n" % (comment, len(atoms), max(a[1] for a in atoms)))
        for k in "xyz":
            f.write("%.10g %.10g %slo %shi\n" % (box[k][0], box[k][1], k, k))
        f.write("\nAtoms\n\n")
        for i, t, d, rho, x, y, z in atoms:
            f.write("%d %d %.17g %.17g %.17g %.17g %.17g\n" % (i, t, d, rho, x, y, z))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("data")
    ap.add_argument("--balls", required=True)
    ap.add_argument("--walls", action="store_true")
    ap.add_argument("--data", dest="data_out")
    ap.add_argument("--seed", type=int, default=1601)
    a = ap.parse_args()
    box, atoms = read_data(a.data)
    if not atoms or set(box) != set("xyz"):
        sys.exit("lammps_to_trubal.py: %s: no box or no Atoms section" % a.data)
    if len({at[1] for at in atoms}) != 1 or len({at[3] for at in atoms}) != 1:
        sys.exit("lammps_to_trubal.py: one atom type and one density expected (PROP type 1)")
    (x0, x1), (y0, y1), (z0, z1) = box["x"], box["y"], box["z"]
    out = [at[0] for at in atoms if not (x0 <= at[4] < x1 and y0 <= at[5] < y1 and z0 <= at[6] <= z1)]
    if out:
        sys.exit("lammps_to_trubal.py: %d centres outside the box (first: id %d)" % (len(out), out[0]))
    if a.walls:
        moved, replaced = fit_walls(box, atoms, a.seed)
        print("walls: %d spheres cut by the x/y faces, %d moved inward, %d placed again"
              % (moved + replaced, moved, replaced))
    if a.data_out:
        write_data(a.data_out, box, atoms, "%s%s" % (a.data, ", fitted inside x/y walls" if a.walls else ""))
    with open(a.balls, "w") as f:
        f.write("; %d balls from %s%s\n" % (len(atoms), a.data, " (fitted inside x/y walls)" if a.walls else ""))
        for i, t, d, rho, x, y, z in atoms:
            f.write("ball %.17g %.17g %.17g %.17g id %d\n" % (x, y, z, d / 2, i))
    radii = {at[2] / 2 for at in atoms}
    print("box %.17g %.17g %.17g %.17g %.17g %.17g n %d radius %.17g density %.17g top %.17g"
          % (box["x"] + box["y"] + box["z"] + (len(atoms), max(radii), atoms[0][3],
                                               max(at[6] for at in atoms))))


if __name__ == "__main__":
    main()
