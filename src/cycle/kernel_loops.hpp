// The loops of one time step as templates over the features a scene uses (doc/physics.md "Law of
// motion"), in four headers: this one (what the contact loops share: the gather of a pair's inputs,
// the dashpots' part), kernel_contacts.hpp (the per-contact loop, adding each pair to its balls'
// sums, and the cross pairs), kernel_walls.hpp (the wall contacts) and kernel_motion.hpp (the
// per-ball law of motion). Included only by the files that instantiate their tables
// (kernels_*.cpp, a few tables each, so that a parallel build compiles them side by side);
// make_kernels (kernels.cpp) picks one entry of each per CYCLE.
#pragma once

#include "cycle/kernel_tables.hpp"
#include "model/periodic_cell.hpp"
#include "physics/timestep.hpp"
#include "physics/walls.hpp"

#include <bit>
#include <utility>

namespace trubal::loops {

// Raw pointers, so that the compiler knows the stores into one array cannot move another's data.
#define TRUBAL_PTR(name, vec) auto* __restrict name = (vec).data()

// The ball data the contact loops read, and the one gather of a pair's inputs into a batch lane.
struct PairInputs {
  const double *x, *y, *z, *rad, *mass, *vx, *vy, *vz, *wx, *wy, *wz;
  const std::uint8_t* fixed;
  const std::int8_t *img_x, *img_y, *img_z;
  bool periodic;
  CellFrame cell;   // periodic space: j's image is x_j + H image, moving at v_j + (dH/dt) image
  // CellFrame::moving. (In a still cell every image velocity is +-0: the gather leaves it out, and
  // the batch's ivx, ivy, ivz are not written.)
  bool cell_moving;
  PairInputs(const Model& model)
      : x(model.balls.x.data()), y(model.balls.y.data()), z(model.balls.z.data()), rad(model.balls.rad.data()),
        mass(model.balls.mass.data()), vx(model.balls.vx.data()), vy(model.balls.vy.data()), vz(model.balls.vz.data()),
        wx(model.balls.wx.data()), wy(model.balls.wy.data()), wz(model.balls.wz.data()), fixed(model.balls.fixed.data()),
        img_x(model.contacts.image_x.data()), img_y(model.contacts.image_y.data()), img_z(model.contacts.image_z.data()),
        periodic(model.space.periodic), cell(cell_frame(model.space)),
        cell_moving(periodic && cell.moving()) {}

  // Lane q of B gets pair p (balls i < j): separation, radii, relative velocity (image included),
  // the spin term, m*, and the pair's law where the scene has several.
  template <ContactFeatures F, bool kOneLaw>
  void gather(ContactBatch& B, std::size_t q, const StepKernels& k, std::size_t p, std::size_t i, std::size_t j) const {
    if constexpr (!kOneLaw) B.set_law(q, k.laws.law(i, j));
    B.dx[q] = x[j] - x[i]; B.dy[q] = y[j] - y[i]; B.dz[q] = z[j] - z[i];
    B.ri[q] = rad[i]; B.rj[q] = rad[j];
    B.vx[q] = vx[j] - vx[i]; B.vy[q] = vy[j] - vy[i]; B.vz[q] = vz[j] - vz[i];
    if (periodic) {
      double ox, oy, oz;
      image_offset(cell, img_x[p], img_y[p], img_z[p], ox, oy, oz);
      B.dx[q] = image_delta(x[j], x[i], ox);
      B.dy[q] = image_delta(y[j], y[i], oy);
      B.dz[q] = image_delta(z[j], z[i], oz);
      if (cell_moving) {
        image_velocity(cell, img_x[p], img_y[p], img_z[p], B.ivx[q], B.ivy[q], B.ivz[q]);
        B.vx[q] += B.ivx[q]; B.vy[q] += B.ivy[q]; B.vz[q] += B.ivz[q];
      }
    }
    if constexpr (F.rotation) {
      B.sx[q] = rad[i] * wx[i] + rad[j] * wx[j];
      B.sy[q] = rad[i] * wy[i] + rad[j] * wy[j];
      B.sz[q] = rad[i] * wz[i] + rad[j] * wz[j];
    }
    if constexpr (F.dashpot) B.mstar[q] = pair_mstar(mass[i], mass[j], velocity_held(fixed[i]), velocity_held(fixed[j]));
    if constexpr (F.rolling) { B.wx[q] = wx[j] - wx[i]; B.wy[q] = wy[j] - wy[i]; B.wz[q] = wz[j] - wz[i]; }
  }
};

// The dashpots' work (doc/physics.md "Energy"). The law of motion charges every force F(t) with
// F(t) . (v(t - dt/2) + v(t + dt/2)) / 2 dt_mean, half of it after t: the dashpots too, however
// their force jumps where a contact starts or ends. A contact's loop knows the relative velocity
// before the step: it books F(t) . V(t - dt/2) dt_mean (half of it after t), as if the velocity
// stayed; the law of motion adds, per ball, the dashpot force (DashpotForce) times the change of
// the ball's velocity over the step, half of dt_mean, to the work and to its part after t.
constexpr double kDashpotAhead = 0.5;

// Lane q's dashpot part to ball j's sums (as PairForce's: +F on j, and t).
[[gnu::always_inline]] inline void add_dashpot(DashpotForce& d, const ContactBatch& B, std::size_t q) {
  d.fx += B.dfx[q]; d.fy += B.dfy[q]; d.fz += B.dfz[q];
  d.tx += B.dtx[q]; d.ty += B.dty[q]; d.tz += B.dtz[q];
}

}  // namespace trubal::loops
