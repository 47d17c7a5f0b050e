// Speed of the engine on the peers' benchmark scene (shared/peers): a dense FCC block, every ball
// touching its 12 neighbours (nearest-neighbour distance 0.99 d, jitter 0.05), R = 20,
// kn = ks = 1.5e9, mu = 0.12278, density 2000, dt = 0.02, rotation on, no damping, no gravity.
// Free space until periodic space exists: the outer layer of lattice cells is held fixed (a rigid
// container), or the stored spring energy would blow the block apart.
//
//   trubal_bench [--backend name] [--threads t] [--steps k] [N ...]   N rounded to 4 n^3 (default 1680 13500 108000)
//   trubal_bench --compare [--steps k] [--phases] [N ...]   every backend on 1 and 2 threads, speedup and efficiency
//                                                 against the best one-thread time (default 403 1680 13500 108000)
//   trubal_bench --gen [N ...]     GEN's time: N balls of radius 0.4-0.6 in a periodic cell at a solid fraction of
//                                  0.21 (the loose gas of examples/periodic_triaxial.dat) (default 200000 1000000)
//   trubal_bench --gen-porosity [N ...]   GEN porosity 0.4 of a graded sand (a sieve curve) in a periodic cell
//                                  sized for about N balls (default 20000 200000)
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <vector>

#include "cycle/pipeline.hpp"
#include "session.hpp"
#include "model/edit.hpp"
#include "cycle/run.hpp"
#include "physics/scene.hpp"
#include "physics/timestep.hpp"
#include "physics/measure.hpp"

using namespace trubal;

namespace {

enum class Scene { Standard, NoRotation, Everything };

Model fcc_block(int nx, int ny, int nz, Scene scene) {
  const double r = 20, d = 2 * r, a = 0.99 * d * std::sqrt(2.0);
  Model model;
  Material m;
  m.kn = 1.5e9;
  m.ks = scene == Scene::NoRotation ? 0 : 1.5e9;
  m.friction = 0.12278;
  m.density = 2000;
  model.materials[1] = m;
  model.settings.fixed_dt = 0.02;
  if (scene == Scene::Everything) {
    model.settings.damping.kind = DampKind::Rayleigh;
    model.settings.damping.alpha = 0.05 * M_PI;
    model.settings.damping.beta = 1e-4;
    model.settings.gravity = {0, 0, -9.81};
  }
  std::uint64_t seed = 12345;
  auto jitter = [&] {   // deterministic, uniform in [-0.05, 0.05]
    seed = seed * 6364136223846793005ULL + 1442695040888963407ULL;
    return (static_cast<double>(seed >> 11) / 9007199254740992.0 - 0.5) * 0.1;
  };
  const double basis[4][3] = {{0, 0, 0}, {0.5, 0.5, 0}, {0.5, 0, 0.5}, {0, 0.5, 0.5}};
  std::int64_t id = 1;
  // Ids in lattice order, as the peers' data files number them.
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
        for (const auto& b : basis) {
          const double x = (i + b[0] + 0.25) * a + jitter(), y = (j + b[1] + 0.25) * a + jitter();
          const double z = (k + b[2] + 0.25) * a + jitter();
          const std::size_t ball = add_ball(model, id++, 1, x, y, z, r);
          const bool shell = i == 0 || j == 0 || k == 0 || i == nx - 1 || j == ny - 1 || k == nz - 1;
          if (shell) model.balls.fixed[ball] = kVel | kSpin;
        }
  return model;
}

struct Timing { double ball_steps, contact_steps, seconds; std::size_t contacts; };

bool g_phases = false;   // --phases: print where each run's time went

// The warm-up builds the pair list, fills the caches and covers the threaded backend's trial of
// whether sharing a step pays (its first 128 steps): start-up costs, not throughput.
Timing run(Model model, const std::string& backend_name, int steps, int threads = 1, int warm_up = 150) {
  auto backend = make_pipeline(backend_name, threads);
  run_cycles(model, *backend, warm_up, {});
  const auto t0 = std::chrono::steady_clock::now();
  const CycleResult r = run_cycles(model, *backend, steps, {});
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (r.unstable) std::fprintf(stderr, "unstable: %s\n", r.message.c_str());
  const std::size_t contacts = contact_count(model);
  if (g_phases) {
    const PhaseTimes& p = r.times;
    const double us = 1e6 / steps;
    std::printf("  [%s %d thr: us per step: detect %.1f, forces %.1f, motion %.1f, rest of step %.1f, outside step %.1f]\n",
                backend_name.c_str(), threads, p.detect * us, p.forces * us, p.motion * us,
                (p.step - p.detect - p.forces - p.motion) * us, (s - p.step) * us);
  }
  return {static_cast<double>(model.balls.size()) * steps / s, static_cast<double>(contacts) * steps / s, s, contacts};
}

// Peak resident memory of the process since the last reset_peak_memory(), from /proc (Linux);
// 0 where it cannot be read.
void reset_peak_memory() {
  if (std::FILE* f = std::fopen("/proc/self/clear_refs", "w")) {   // "5": reset VmHWM (Linux 4.0+)
    std::fputs("5", f);
    std::fclose(f);
  }
}
double peak_memory_mib() {
  std::FILE* f = std::fopen("/proc/self/status", "r");
  if (!f) return 0;
  char line[256];
  double kib = 0;
  while (std::fgets(line, sizeof line, f))
    if (std::sscanf(line, "VmHWM: %lf kB", &kib) == 1) break;
  std::fclose(f);
  return kib / 1024;
}

// The lattice for about n balls: 4 nx ny nz (1680 is the peers' 7 x 6 x 10 block, 403 becomes 400).
void lattice_for(int n, int& nx, int& ny, int& nz) {
  nx = static_cast<int>(std::lround(std::cbrt(n / 4.0))); ny = nx; nz = nx;
  if (n == 1680) { nx = 7; ny = 6; nz = 10; }
  if (n == 403) { nx = 4; ny = 5; nz = 5; }
}

// Every backend on one and two threads, on the standard scene. Speedup Sp = T* / Tp against the
// best one-thread time T* at that size, efficiency Ep = Sp / p. allpairs only where its pair slots
// fit the default memory limit (it refuses the rest, and says so), and with fewer steps (it tests every pair every step).
int compare(const std::vector<int>& sizes, int steps) {
  struct Variant { const char* backend; int threads; };
  const Variant variants[] = {{"serial", 1}, {"threaded", 1}, {"threaded", 2}, {"allpairs", 1}, {"allpairs", 2}};
  std::printf("dense FCC block, dt 0.02, every backend; M = million per second, G = billion per second\n");
  std::printf("%8s %10s %9s %2s %7s %8s %14s %16s %7s %6s %9s\n", "N", "contacts", "backend", "p", "steps", "s",
              "ball-cycles/s", "pair tests/s", "Sp", "Ep", "peak MiB");
  for (int n : sizes) {
    int nx, ny, nz;
    lattice_for(n, nx, ny, nz);
    const double balls = 4.0 * nx * ny * nz, pair_slots = balls * (balls - 1) / 2;
    std::vector<Timing> times;
    double best_one = 0;
    for (const Variant& v : variants) {
      const bool all = std::string(v.backend) == "allpairs";
      int k = steps > 0 ? steps : std::max(20, static_cast<int>(1.2e7 / balls));
      if (all && steps <= 0) k = std::max(3, std::min(k, static_cast<int>(2e9 / pair_slots)));
      Timing t;
      reset_peak_memory();
      try {
        t = run(fcc_block(nx, ny, nz, Scene::Standard), v.backend, k, v.threads, all ? 2 : 150);
      } catch (const std::exception& e) {   // allpairs above its memory limit says so
        std::printf("%8.0f %10s %9s %2d  %s\n", balls, "", v.backend, v.threads, e.what());
        continue;
      }
      const double per_step = t.seconds / k;
      if (v.threads == 1 && (best_one == 0 || per_step < best_one)) best_one = per_step;
      const double speedup = best_one / per_step;
      char tests[32] = "-";
      if (all) std::snprintf(tests, sizeof tests, "%.3f G", pair_slots / per_step / 1e9);
      std::printf("%8.0f %10zu %9s %2d %7d %8.3f %12.2f M %16s %6.2fx %6.2f %9.0f\n", balls, t.contacts, v.backend,
                  v.threads, k, t.seconds, t.ball_steps / 1e6, tests, speedup, speedup / v.threads, peak_memory_mib());
      std::fflush(stdout);
    }
  }
  std::printf("Sp = T*/Tp with T* the best one-thread time per step at that N (serial first), Ep = Sp/p;\n"
              "peak MiB: the process's peak resident memory during that row (model, lists, backend).\n");
  return 0;
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

int gen_speed(std::vector<int> sizes, bool porosity) {
  if (sizes.empty()) sizes = porosity ? std::vector<int>{20000, 200000} : std::vector<int>{200000, 1000000};
  std::printf("%10s %12s %10s %10s   %s\n", "N asked", "placed", "s", "porosity", "what");
  for (int n : sizes) {
    // Mean ball volume 4/3 pi E[r^3] for r uniform in [0.4, 0.6]: pi (0.6^4 - 0.4^4) / (3 * 0.2).
    const double mean_volume = M_PI * (std::pow(0.6, 4) - std::pow(0.4, 4)) / 0.6;
    const double edge = std::cbrt(n * mean_volume / 0.21);
    if (!porosity) {
      Session s;
      s.start_periodic({edge, edge, edge}, {0, 0, 0});
      const auto t0 = std::chrono::steady_clock::now();
      const std::size_t placed = s.generate(static_cast<std::size_t>(n), 0.4, 0.6, 1, 7, {});
      std::printf("%10d %12zu %10.2f %10.4f   GEN n 0.4 0.6 in a periodic cell, solid fraction 0.21\n", n, placed,
                  seconds_since(t0), 1 - placed * mean_volume / (edge * edge * edge));
      std::fflush(stdout);
    }
    if (porosity) {
      // A graded sand, d 0.5 to 1.5 (uniform in log d between the points), to porosity 0.4.
      Session s;
      Session::GenSpec spec;
      spec.sizes.kind = SizeDistribution::Kind::Sieve;
      spec.sizes.diameter = {0.5, 0.8, 1.0, 1.5};
      spec.sizes.passing = {0, 20, 50, 100};
      spec.porosity = 0.4;
      spec.seed = 7;
      const double mean = 0.35;   // about the sand's mean ball volume (d^3 pi / 6 at d ~ 0.87)
      const double side = std::cbrt(n * mean / 0.6);
      s.start_periodic({side, side, side}, {0, 0, 0});
      const auto t0 = std::chrono::steady_clock::now();
      const PackResult made = s.generate(spec);
      std::printf("%10d %12zu %10.2f %10.4f   GEN porosity 0.4 psd sieve 0.5 0 0.8 20 1 50 1.5 100 (%d stages, %lld "
                  "sweeps)\n", n, made.balls.size(), seconds_since(t0), made.porosity, made.stages,
                  static_cast<long long>(made.sweeps));
    }
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  std::string backend = "serial";
  int steps = 0, threads = 1;
  bool comparing = false, gen = false, gen_porosity = false;
  std::vector<int> sizes;
  for (int k = 1; k < argc; ++k) {
    const std::string arg = argv[k];
    if (arg == "--compare") comparing = true;
    else if (arg == "--gen") gen = true;
    else if (arg == "--gen-porosity") gen_porosity = true;
    else if (arg == "--threads" && k + 1 < argc) threads = std::atoi(argv[++k]);
    else if (arg == "--backend" && k + 1 < argc) backend = argv[++k];
    else if (arg == "--steps" && k + 1 < argc) steps = std::atoi(argv[++k]);
    else if (arg == "--phases") g_phases = true;
    else sizes.push_back(std::atoi(arg.c_str()));
  }
  if (gen || gen_porosity) return gen_speed(sizes, gen_porosity);
  if (comparing) {
    if (sizes.empty()) sizes = {403, 1680, 13500, 108000};
    return compare(sizes, steps);
  }
  if (sizes.empty()) sizes = {1680, 13500, 108000};
  std::printf("dense FCC block, backend %s (%d threads), dt 0.02, M = million per second\n", backend.c_str(), threads);
  std::printf("%8s %10s %8s %6s %14s %14s %10s %10s\n", "N", "contacts", "steps", "s", "ball-steps/s",
              "contacts/s", "no-rot x", "all-on x");
  for (int n : sizes) {
    // 4 n^3 balls; 1680 is the peers' 7 x 6 x 10 block.
    int nx, ny, nz;
    lattice_for(n, nx, ny, nz);
    const int k = steps > 0 ? steps : std::max(20, static_cast<int>(4e6 / (4.0 * nx * ny * nz)));
    const Timing standard = run(fcc_block(nx, ny, nz, Scene::Standard), backend, k, threads);
    const Timing reduced = run(fcc_block(nx, ny, nz, Scene::NoRotation), backend, k, threads);
    const Timing full = run(fcc_block(nx, ny, nz, Scene::Everything), backend, k, threads);
    std::printf("%8d %10zu %8d %6.2f %12.2f M %12.2f M %9.2fx %9.2fx\n", 4 * nx * ny * nz, standard.contacts, k,
                standard.seconds, standard.ball_steps / 1e6, standard.contact_steps / 1e6,
                reduced.ball_steps / standard.ball_steps, full.ball_steps / standard.ball_steps);
  }
  std::printf("no-rot x: a scene without shear or rotation against the standard one; all-on x: with Rayleigh\n"
              "damping and gravity as well.\n");
  return 0;
}
