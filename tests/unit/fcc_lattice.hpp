// The face-centred cubic block the tests' and the benchmark's dense scenes are built on (bench.cpp
// includes it too): nx x ny x nz cubic cells of edge a, four sites a cell, the cube axes along x, y
// and z. At a = 2 sqrt(2) r every ball of radius r touches its 12 neighbours. (LATTICE fcc builds
// the other orientation, close-packed layers normal to z, as the Rowe decks want.)
//
// The scenes differ in what they put at a site (jitter, fixities, types, deck lines), so the
// lattice hands each site to the caller, which makes its ball.
#pragma once

namespace trubal::test {

// Each cell's four sites, in cell units from the cell's lowest corner, in the order they are visited.
inline constexpr double kFccBasis[4][3] = {{0, 0, 0}, {0.5, 0.5, 0}, {0.5, 0, 0.5}, {0, 0.5, 0.5}};

struct FccSite {
  int i, j, k;         // the cell
  int basis;           // the site in the cell (kFccBasis)
  double x, y, z;      // the centre: ((i + basis x + offset) a, (j + ...) a, (k + ...) a)
  bool on_surface;     // the cell is on the block's outer layer (the scenes hold those balls)
};

// Calls visit(site) for every site, cell by cell (z slowest, then y, then x), the four of a cell in
// the order of kFccBasis: the order the scenes number their balls in. offset: the lattice shifted
// by that many cells along each axis (0.25 keeps balls off the faces of a cell of the block's size).
template <class Visit>
void for_each_fcc_site(int nx, int ny, int nz, double a, double offset, Visit&& visit) {
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
        for (int b = 0; b < 4; ++b) {
          const double* p = kFccBasis[b];
          visit(FccSite{i, j, k, b, (i + p[0] + offset) * a, (j + p[1] + offset) * a, (k + p[2] + offset) * a,
                        i == 0 || j == 0 || k == 0 || i == nx - 1 || j == ny - 1 || k == nz - 1});
        }
}

}  // namespace trubal::test
