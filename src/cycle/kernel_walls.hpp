// The wall-contact loop of one step (kernel_loops.hpp says how the step's loops are laid out).
#pragma once

#include "cycle/kernel_loops.hpp"

namespace trubal::loops {

// The ball-wall contacts [begin, end) by the pair law (physics/walls.hpp: the wall as a partner j of
// radius 2R), each added to its ball's sum after the ball's pairs (so in wall order) and to its
// wall's load; the wall's work on the balls is boundary work.
template <ContactFeatures F>
void wall_loop(Model& model, StepScratch& scratch, const StepKernels& k, std::size_t begin, std::size_t end,
               WallLoad* loads) {
  constexpr ContactFeatures kLaw = F.law();
  if (begin >= end) return;
  WallContacts& c = model.wall_contacts;
  const Balls& b = model.balls;
  const std::vector<Wall>& walls = model.walls;
  ContactBatch B;
  alignas(64) double hx[kBatch], hy[kBatch], hz[kBatch], rx[kBatch], ry[kBatch], rz[kBatch];
  Vec3 point[kBatch], surface[kBatch];
  for (std::size_t p0 = begin; p0 < end; p0 += kBatch) {
    const std::size_t count = std::min(kBatch, end - p0);
    for (std::size_t q = 0; q < count; ++q) {
      const std::size_t p = p0 + q, i = c.ball[p];
      const WallLane lane = wall_lane(walls[c.wall[p]], {b.x[i], b.y[i], b.z[i]}, b.rad[i]);
      B.set_law(q, k.laws.wall_law(i, c.wall[p]));
      B.dx[q] = lane.dx; B.dy[q] = lane.dy; B.dz[q] = lane.dz;
      B.ri[q] = lane.r; B.rj[q] = lane.r;
      B.vx[q] = lane.velocity[0] - b.vx[i]; B.vy[q] = lane.velocity[1] - b.vy[i]; B.vz[q] = lane.velocity[2] - b.vz[i];
      if constexpr (kLaw.rotation) {
        B.sx[q] = b.rad[i] * b.wx[i]; B.sy[q] = b.rad[i] * b.wy[i]; B.sz[q] = b.rad[i] * b.wz[i];
      }
      if constexpr (kLaw.dashpot) B.mstar[q] = b.mass[i];
      if constexpr (kLaw.rolling) {   // the wall's spin against the ball's
        const Wall& w = walls[c.wall[p]];
        B.wx[q] = w.spin[0] - b.wx[i]; B.wy[q] = w.spin[1] - b.wy[i]; B.wz[q] = w.spin[2] - b.wz[i];
      }
      point[q] = lane.point;
      surface[q] = lane.velocity;
    }
    const RollingLanes roll{{c.mrx.data() + p0, c.mry.data() + p0, c.mrz.data() + p0}, {rx, ry, rz}};
    contact_forces<kLaw, false>(B, count, k.laws.table[0], k.dt_prev, k.dt_mean, k.beta, c.fsx.data() + p0, c.fsy.data() + p0,
                                c.fsz.data() + p0, hx, hy, hz, nullptr, &roll);
    for (std::size_t q = 0; q < count; ++q) {
      const std::size_t p = p0 + q, i = c.ball[p];
      if constexpr (kLaw.shear) { c.fsx[p] = hx[q]; c.fsy[p] = hy[q]; c.fsz[p] = hz[q]; }
      if constexpr (kLaw.rolling) {
        c.mrx[p] = rx[q]; c.mry[p] = ry[q]; c.mrz[p] = rz[q];
        RollingMoment& mi = scratch.ball_rolling[i];
        mi.mx -= rx[q]; mi.my -= ry[q]; mi.mz -= rz[q];
      }
      PairForce& fi = scratch.ball_force[i];
      fi.fx -= B.fx[q]; fi.fy -= B.fy[q]; fi.fz -= B.fz[q];
      if constexpr (kLaw.rotation) { fi.tx += B.tx[q]; fi.ty += B.ty[q]; fi.tz += B.tz[q]; }
      if (k.sums_stiffness()) {
        fi.kmax += std::max(B.kn[q], B.ks[q]); fi.ks += B.ks[q];
        if constexpr (kLaw.rolling) fi.ks += rolling_ks(B.ks[q], 1.0);   // (the wall does not turn with it)
      }
      if constexpr (kLaw.dashpot) {
        scratch.ball_cn[i] += B.cn[q];
        DashpotForce& d = scratch.ball_dashpot[i];
        d.fx -= B.dfx[q]; d.fy -= B.dfy[q]; d.fz -= B.dfz[q];
        d.tx += B.dtx[q]; d.ty += B.dty[q]; d.tz += B.dtz[q];
      }
      const Wall& w = walls[c.wall[p]];
      WallLoad& load = loads[c.wall[p]];
      const double fx = B.fx[q], fy = B.fy[q], fz = B.fz[q];
      const double ax = point[q][0] - w.spin_point[0], ay = point[q][1] - w.spin_point[1], az = point[q][2] - w.spin_point[2];
      const double power = -(fx * surface[q][0] + fy * surface[q][1] + fz * surface[q][2]);   // the wall's on the ball
      // Each contact goes to the exact sums on its own (the same additions wherever it is computed):
      // the loads on the steps that read them, the work where the surface moves (a surface standing
      // still adds zeros to it), and there the kinetic energy in the wall's frame on the steps the
      // guard checks (StepKernels::energies).
      if (k.wall_loads) {
        load.fx.add(fx); load.fy.add(fy); load.fz.add(fz);
        load.mx.add(ay * fz - az * fy); load.my.add(az * fx - ax * fz); load.mz.add(ax * fy - ay * fx);
        load.normal_force.add(B.fn[q]);
        load.stiffness.add(B.kn[q]);
        load.contacts += B.state[q] != 0;
      }
      if (surface[q][0] != 0 || surface[q][1] != 0 || surface[q][2] != 0) {
        load.work.add(power * k.dt_mean);
        // The touching ball's kinetic energy in the wall's frame (Wall::relative_kinetic).
        const double ux = surface[q][0] - b.vx[i], uy = surface[q][1] - b.vy[i], uz = surface[q][2] - b.vz[i];
        if (B.state[q] != 0 && k.energies) load.relative_kinetic.add(0.5 * b.mass[i] * (ux * ux + uy * uy + uz * uz));
      }
      BallParts& part = scratch.ball_parts[i];
      part.boundary += power * k.dt_mean;
      part.boundary_ahead += power * (0.5 * k.dt_mean);   // the wall moves on with the balls: half after t
      part.friction += B.work_friction[q];
      if constexpr (kLaw.rolling) scratch.ball_rolling[i].work += B.work_rolling[q];
      part.damping += B.work_damping[q];
      part.damping_ahead += kDashpotAhead * B.work_damping[q];
      part.strain += B.strain[q];
    }
    if constexpr (F.details) {
      for (std::size_t q = 0; q < count; ++q) {
        const std::size_t p = p0 + q;
        c.nx[p] = B.nx[q]; c.ny[p] = B.ny[q]; c.nz[p] = B.nz[q]; c.overlap[p] = B.overlap[q]; c.fn[p] = B.fn[q];
        c.fx[p] = B.fx[q]; c.fy[p] = B.fy[q]; c.fz[p] = B.fz[q];
        c.kn_eff[p] = B.kn[q]; c.ks_eff[p] = B.ks[q];
        c.state[p] = static_cast<std::uint8_t>(B.state[q]);
      }
    }
  }
}

}  // namespace trubal::loops
