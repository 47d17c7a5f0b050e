// The limit memory sets on a step: the bytes a step of the lean kernels must move per ball, and
// the machine's copy bandwidth measured in the same run.
//
// The bytes are a count from the code of cycle/kernel_contacts.hpp, kernel_motion.hpp and
// verlet.hpp, not a measurement: every array a loop of the step streams is counted once for each
// loop that reads it and once for each that writes it, as a model too large for the caches must
// move it; a partner's state, read again for each of its pairs, is counted once (the space order
// keeps it in the cache). The loops of a step that keeps its list:
//
//   the skin rule    x y z and the positions at the last rebuild, read
//   the contacts     per ball: x y z, radius, velocity (and spin) read, the run's start in the
//                    list read, its contact sums (PairForce) and its parts of the global sums
//                    (BallParts) written (with dashpots: the mass and fixed bits read, the dashpot
//                    sums written); per pair: i and j read (and the image in a periodic cell),
//                    the shear history read and written
//   the walls        per wall contact: the ball and the wall read, the shear history read and
//                    written (the wall loop's scan of the balls is counted with the contacts')
//   the motion       the sums read, x y z and velocity (and spin) read and written, mass, fixed
//                    bits (and inertia and radius) read, and the applied loads where gravity or
//                    APPLY is on
//
// A step that rebuilds the list moves more; with the skin of a fifth of a radius the dense scenes
// keep their list for hundreds of steps.
#pragma once

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstring>
#include <vector>

#include "cycle/step_scratch.hpp"

namespace trubal::bench {

struct TrafficScene {
  bool rotation = true, shear = true, dashpot = false, loads = false, periodic = false;
};

struct StepTraffic {
  double per_ball = 0, per_pair = 0, per_wall_contact = 0;
  // Bytes a ball-step, for the list's pairs and the wall contacts a ball has on average.
  double bytes(double pairs_per_ball, double wall_contacts_per_ball) const {
    return per_ball + pairs_per_ball * per_pair + wall_contacts_per_ball * per_wall_contact;
  }
};

inline StepTraffic step_traffic(const TrafficScene& s) {
  constexpr double d = sizeof(double), index = sizeof(std::uint32_t), byte = 1;
  const double spin = s.rotation ? 3 * d : 0;
  StepTraffic t;
  // The skin rule.
  t.per_ball += 6 * d;
  // The contacts.
  t.per_ball += 4 * d + 3 * d + spin + index + sizeof(PairForce) + sizeof(BallParts);
  if (s.dashpot) t.per_ball += d + byte + d + sizeof(DashpotForce);
  t.per_pair += 2 * index + (s.periodic ? 3 * byte : 0) + (s.shear ? 2 * 3 * d : 0);
  // The walls.
  t.per_wall_contact += 2 * index + (s.shear ? 2 * 3 * d : 0);
  // The motion.
  t.per_ball += sizeof(PairForce) + sizeof(BallParts) + 2 * (3 * d + 3 * d + spin) + d + byte;
  if (s.rotation) t.per_ball += 2 * d;   // inertia, radius (the moment -R t)
  if (s.dashpot) t.per_ball += sizeof(DashpotForce);
  if (s.loads) t.per_ball += 3 * d + (s.rotation ? 3 * d : 0);
  return t;
}

// The copy bandwidth in bytes a second (read and written, as STREAM's Copy counts them): the best
// of `rounds` copies of a buffer of `mib` MiB, each side far larger than the caches.
inline double copy_bandwidth(std::size_t mib = 256, int rounds = 5) {
  const std::size_t n = mib * 1048576 / sizeof(double);
  std::vector<double> from(n), to(n);
  for (std::size_t k = 0; k < n; ++k) from[k] = static_cast<double>(k);
  std::memcpy(to.data(), from.data(), n * sizeof(double));   // touch every page of both first
  double best = 0;
  for (int r = 0; r < rounds; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    std::memcpy(to.data(), from.data(), n * sizeof(double));
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    best = std::max(best, 2.0 * n * sizeof(double) / s);
    from[r] = to[n - 1 - r];   // the copies depend on each other: none can be left out
  }
  return best;
}

}  // namespace trubal::bench
