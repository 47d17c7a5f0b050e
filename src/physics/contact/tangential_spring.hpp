// Tangential part, the incremental shear spring with the Coulomb limit (doc/physics.md "Contacts"):
// last step's shear force turned onto the new contact plane at its old length, plus -k_s V_s dt,
// capped at mu F_n + cohesion. With the linear law k_s is the pair's; with Hertz it is Mindlin's
// no-slip stiffness 8 G* sqrt(R* U) (the normal part gives it).
#pragma once

#include <cmath>

#include "physics/contact/energy.hpp"

namespace trubal {

struct ShearState {
  double fsx, fsy, fsz;          // the new shear spring force (the history)
  double vsx, vsy, vsz;          // the sliding velocity
  double work_friction;          // force times plastic slip this step
  double strain;                 // |F_s|^2 / (2 k_s)
  bool slide;
};

struct CoulombSpring {
  static constexpr bool kOn = true;
  // kCap false: the spring as if it held (no square root, no divisions for the cap and the slip):
  // s.slide still says whether it would slide, and where it would not, every output has the bits
  // of kCap true (the same expressions), so a batch none of whose touching lanes slides may be
  // made this way (contact_forces).
  template <bool kCap = true>
  [[gnu::always_inline]] static void force(double hx, double hy, double hz, double nx, double ny, double nz, double vx, double vy,
                    double vz, double vn, double ks, double dt, double limit, ShearState& s) {
    const double old2 = hx * hx + hy * hy + hz * hz;
    const double h_n = hx * nx + hy * ny + hz * nz;
    const double px = hx - h_n * nx, py = hy - h_n * ny, pz = hz - h_n * nz;
    const double new2 = px * px + py * py + pz * pz;
    const bool turn = old2 > 0, rescale = turn && new2 > 0;
    // (x * 1.0 is x, bit for bit: where the projection is not rescaled it is multiplied by 1.0.
    // One select a value, not two nested: g++ 12 if-converts (and so vectorises) the lanes' loop
    // with AVX2 only where no value has more than 4 ways to reach it.)
    const double scale = rescale ? std::sqrt(old2 / (rescale ? new2 : 1.0)) : 1.0;
    const double hx_turned = turn ? px * scale : hx;
    const double hy_turned = turn ? py * scale : hy;
    const double hz_turned = turn ? pz * scale : hz;
    double fsx = hx_turned, fsy = hy_turned, fsz = hz_turned;
    s.vsx = vx - vn * nx; s.vsy = vy - vn * ny; s.vsz = vz - vn * nz;
    const double kdt = ks * dt;
    fsx -= kdt * s.vsx; fsy -= kdt * s.vsy; fsz -= kdt * s.vsz;
    const double fs2 = fsx * fsx + fsy * fsy + fsz * fsz;
    s.slide = fs2 > limit * limit;
    if constexpr (!kCap) {
      s.fsx = fsx; s.fsy = fsy; s.fsz = fsz;
      s.work_friction = 0.0;
      s.strain = shear_spring_energy(s.fsx * s.fsx + s.fsy * s.fsy + s.fsz * s.fsz, ks);
      return;
    }
    const double fs = std::sqrt(fs2);
    const double cut = s.slide ? limit / (s.slide ? fs : 1.0) : 1.0;
    s.fsx = fsx * cut; s.fsy = fsy * cut; s.fsz = fsz * cut;   // (cut is 1.0 where it holds)
    // The slip (trial - force) / k_s times the mean of the force before and after it (the history
    // turned onto the plane, and the capped force): the trapezoid rule the law of motion integrates
    // the contact forces with (cycle/kernels.cpp), so a step's spring energy, friction work and the
    // balls' kinetic energy balance.
    const double ks_safe = ks > 0 ? ks : 1.0;
    const double mean_x = 0.5 * (s.fsx + hx_turned), mean_y = 0.5 * (s.fsy + hy_turned);
    const double mean_z = 0.5 * (s.fsz + hz_turned);
    const double slip_work = (fsx - s.fsx) * mean_x + (fsy - s.fsy) * mean_y + (fsz - s.fsz) * mean_z;
    s.work_friction = s.slide && ks > 0 ? slip_work / ks_safe : 0.0;
    s.strain = shear_spring_energy(s.fsx * s.fsx + s.fsy * s.fsy + s.fsz * s.fsz, ks);
  }
};

}  // namespace trubal
