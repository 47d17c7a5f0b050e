// Speed of the engine on the peers' benchmark scenes (shared/peers).
//
// The dense scene: an FCC block, every ball touching its 12 neighbours (nearest-neighbour distance
// 0.99 d, jitter 0.05), R = 20, kn = ks = 1.5e9, mu = 0.12278, density 2000, dt = 0.02, rotation on,
// no damping, no gravity. In free space (the default) the outer layer of lattice cells is held fixed
// (a rigid container), or the stored spring energy would blow the block apart; --periodic puts the
// block in a periodic cell of the lattice's size instead, every ball free (the peers' own scene,
// ../shared/peers/compare.sh).
//
// The sparse scene (--settle FILE): the peers' settle scene, FILE a settle_<N>.xyz that
// ../shared/peers/gen_scenes.py writes (`python3 gen_scenes.py settle`): balls falling from a loose
// gas under gravity 0.03 onto a floor wall at z = 0, x and y periodic, gran/hooke/history with a
// normal dashpot, dt = 0.04 (the deck of tests/peers/settle_trubal.dat and bench/settle_vs_lammps.sh).
//
// Run trubal_bench --help for the options.
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <algorithm>
#include <cerrno>
#include <exception>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "cycle/pipeline.hpp"
#include "interp/interpreter.hpp"
#include "interp/output.hpp"
#include "session.hpp"
#include "model/edit.hpp"
#include "cycle/run.hpp"
#include "physics/scene.hpp"
#include "physics/timestep.hpp"
#include "physics/measure.hpp"
#include "../tests/unit/fcc_lattice.hpp"   // the FCC block the tests build too
#include "traffic.hpp"

using namespace trubal;

namespace {

enum class Scene { Standard, NoRotation, Everything };

bool g_phases = false;     // --phases: print where each run's time went
bool g_periodic = false;   // --periodic: the FCC block in a periodic cell, every ball free

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
    // Not in a periodic cell: the whole block would fall through its images, gaining potential
    // energy at every wrap (the instability guard stops that run).
    if (!g_periodic) model.settings.gravity = {0, 0, -9.81};
  }
  std::uint64_t seed = 12345;
  auto jitter = [&] {   // deterministic, uniform in [-0.05, 0.05]
    seed = seed * 6364136223846793005ULL + 1442695040888963407ULL;
    return (static_cast<double>(seed >> 11) / 9007199254740992.0 - 0.5) * 0.1;
  };
  if (g_periodic) {   // the lattice's own cell: every ball has its 12 neighbours, across the faces too
    model.space.periodic = true;
    model.space.hi = {nx * a, ny * a, nz * a};
  }
  std::int64_t id = 1;
  // Ids in lattice order, as the peers' data files number them.
  test::for_each_fcc_site(nx, ny, nz, a, 0.25, [&](const test::FccSite& site) {
    const double x = site.x + jitter(), y = site.y + jitter();
    const double z = site.z + jitter();
    const std::size_t ball = add_ball(model, id++, 1, x, y, z, r);
    if (site.on_surface && !g_periodic) model.balls.fixed[ball] = kVel | kSpin;
  });
  return model;
}

double peak_memory_mib();

struct Timing {
  double ball_steps, contact_steps, seconds;
  std::size_t contacts;
  double peak_mib;
  double pairs_per_ball;   // the pair list's pairs (touching or within the skin) a ball
};

// The warm-up builds the pair list, fills the caches and covers the threaded backend's trial of
// whether sharing a step pays (its first 128 steps): start-up costs, not throughput.
Timing run(Model model, const std::string& backend_name, int steps, int threads = 1, int warm_up = 150) {
  auto backend = make_pipeline(backend_name, threads);
  CycleControl as_cycle;   // as CYCLE runs: the last step's contact results made when read
  as_cycle.defer_results = true;
  run_cycles(model, *backend, warm_up, as_cycle);
  const auto t0 = std::chrono::steady_clock::now();
  const CycleResult r = run_cycles(model, *backend, steps, as_cycle);
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (r.unstable) std::fprintf(stderr, "unstable: %s\n", r.message.c_str());
  const double peak = peak_memory_mib();   // before the results are made, as a PRINT would
  make_results(model, *backend);
  const std::size_t contacts = contact_count(model);
  if (g_phases) {
    const PhaseTimes& p = r.times;
    const double us = 1e6 / steps;
    std::printf("  [%s %d thr: us per step: detect %.1f, forces %.1f, motion %.1f, rest of step %.1f, outside step %.1f]\n",
                backend_name.c_str(), threads, p.detect * us, p.forces * us, p.motion * us,
                (p.step - p.detect - p.forces - p.motion) * us, (s - p.step) * us);
  }
  const double n = static_cast<double>(model.balls.size());
  return {n * steps / s, static_cast<double>(contacts) * steps / s, s, contacts, peak,
          static_cast<double>(model.contacts.size()) / n};
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
  std::printf("dense FCC block, %s, dt 0.02, every backend; M = million per second, G = billion per second\n",
              g_periodic ? "periodic cell" : "free space, outer layer held");
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
                  v.threads, k, t.seconds, t.ball_steps / 1e6, tests, speedup, speedup / v.threads, t.peak_mib);
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

// The peers' settle scene from gen_scenes.py's settle_<N>.xyz (header "N Lx Ly Lz", Lz the data
// file's z extent from zlo = -R; then one "x y z" per ball), as tests/peers/settle_trubal.dat makes
// it: x and y periodic, the floor a wall at z = 0, the box top 10 diameters above the highest
// centre, LAMMPS's gran/hooke/history 1.5e9 1.5e9 1.338 0 0.12278 with the dashpot matched by PROP
// rest (tests/peers/README.md: xi = gamma_n sqrt(m_eff / kn) / 2, m_eff = m/2 between balls, m at
// the wall, and the restitution of trubal's non-pulling dashpot at that xi).
std::string settle_deck(const std::string& path, std::size_t& balls) {
  std::FILE* f = std::fopen(path.c_str(), "r");
  if (!f) throw std::runtime_error("--settle: cannot open " + path);
  long n = 0;
  double lx = 0, ly = 0, lz = 0;
  if (std::fscanf(f, "%ld %lf %lf %lf", &n, &lx, &ly, &lz) != 4 || n <= 0 || !(lx > 0) || lx != ly) {
    std::fclose(f);
    throw std::runtime_error("--settle: " + path + " is not a settle_<N>.xyz of gen_scenes.py (header N L L Lz)");
  }
  const double r = 20, rho = 2000, kn = 1.5e9, gamma_n = 1.338, zlo = -r;
  std::string lines;
  double top = zlo;
  char line[160];
  for (long k = 1; k <= n; ++k) {
    double x, y, z;
    if (std::fscanf(f, "%lf %lf %lf", &x, &y, &z) != 3) {
      std::fclose(f);
      throw std::runtime_error("--settle: " + path + " ends before its " + std::to_string(n) + " balls");
    }
    std::snprintf(line, sizeof line, "ball %.17g %.17g %.17g 20 id %ld\n", x, y, z, k);
    lines += line;
    top = std::max(top, z);
  }
  std::fclose(f);
  auto rest = [&](double m_eff) {   // tests/peers/settle_vs_lammps.py clamped_restitution
    const double xi = gamma_n * std::sqrt(m_eff / kn) / 2, s = std::sqrt(1 - xi * xi);
    return std::exp(-xi * std::atan2(2 * xi * s, 2 * xi * xi - 1) / s);
  };
  const double m = rho * 4.0 / 3.0 * M_PI * r * r * r;
  char head[1024];
  std::snprintf(head, sizeof head,
                "start box 0 %.17g 0 %.17g %.17g %.17g x periodic y periodic\n"
                "prop type 1 kn 1.5e9 ks 1.5e9 mu 0.12278 dens 2000 rest %.17g\n"
                "prop type 2 kn 1.5e9 ks 1.5e9 mu 0.12278 rest %.17g\n"
                "wall id 1 plane 0 0 0 0 0 1 type 2\n",
                lx, ly, zlo, std::max(zlo + lz, top + 20 * r), rest(m / 2), rest(m));
  balls = static_cast<std::size_t>(n);
  return head + lines + "grav 0 0 -0.03\ntstep 0.04\n";
}

// The settle scene on one backend: the whole fall and settling in `parts` equal pieces, each with
// its contacts (touching ball pairs) and list (the pairs the contact loop visits) at the end and,
// with --phases, where its time went.
int settle(const std::string& path, const std::string& backend, int threads, int steps) {
  std::size_t n = 0;
  const std::string deck = settle_deck(path, n);
  Session session;
  std::ostringstream quiet_out, quiet_err;
  Output output(quiet_out, quiet_err);
  Interpreter interp(session, output);
  interp.echo = false;
  if (!interp.run_text(deck, "settle", "settle", 1))
    throw std::runtime_error("--settle: the deck failed: " + interp.last_error().message);
  session.set_backend(backend, threads);
  if (steps <= 0) steps = 20000;
  const int parts = 4;
  std::printf("settle scene %s: %zu balls, backend %s (%d threads), dt 0.04, %d steps in %d parts\n", path.c_str(), n,
              backend.c_str(), threads, steps, parts);
  std::printf("%8s %8s %10s %10s %8s %14s %s\n", "from", "steps", "contacts", "list", "s", "ball-steps/s",
              g_phases ? "  us per step: detect, forces, motion, rest of step, outside step" : "");
  double total = 0, pairs = 0, walls = 0;   // the pair list and the wall contacts a ball, summed over steps
  const double bandwidth = bench::copy_bandwidth();
  for (int p = 0; p < parts; ++p) {
    const int k = steps / parts + (p < steps % parts ? 1 : 0);
    const std::int64_t from = session.model().cycle;
    const CycleResult r = session.cycle(k);
    if (r.unstable || r.left_box || r.done != k) throw std::runtime_error("--settle: the run stopped: " + r.message);
    total += r.seconds;
    pairs += static_cast<double>(session.model().contacts.size()) / n * k;
    walls += static_cast<double>(session.model().wall_contacts.size()) / n * k;
    std::printf("%8lld %8d %10zu %10zu %8.3f %12.2f M", static_cast<long long>(from), k, contact_count(session.model()),
                session.model().contacts.size(), r.seconds, static_cast<double>(n) * k / r.seconds / 1e6);
    if (g_phases) {
      const PhaseTimes& t = r.times;
      const double us = 1e6 / k;
      std::printf("  %.1f, %.1f, %.1f, %.1f, %.1f", t.detect * us, t.forces * us, t.motion * us,
                  (t.step - t.detect - t.forces - t.motion) * us, (r.seconds - t.step) * us);
    }
    std::printf("\n");
    std::fflush(stdout);
  }
  std::printf("whole run: %.3f s, %.2f M ball-steps/s, coordination %.4f (ball pairs, 2 C / N)\n", total,
              static_cast<double>(n) * steps / total / 1e6, coordination_number(session.model()));
  const bench::TrafficScene scene{.dashpot = true, .loads = true, .periodic = true};
  const double bytes = bench::step_traffic(scene).bytes(pairs / steps, walls / steps), most = bandwidth / bytes;
  std::printf("the limit set by memory: %.0f B a ball-step (bench/traffic.hpp; the parts' pair lists and wall\n"
              "contacts at their ends), copy bandwidth %.2f GB/s: %.2f M ball-steps/s; reached %.0f%%\n",
              bytes, bandwidth / 1e9, most / 1e6, 100 * static_cast<double>(n) * steps / total / most);
  return 0;
}

// The limit memory sets: per row, the bytes a ball-step must move (bench/traffic.hpp), the copy
// bandwidth measured before that row's runs, the ball-steps a second that bandwidth allows, and
// the fraction of it the run reached.
template <class Limit> void print_limits(const std::vector<Limit>& limits) {
  std::printf("\nthe limit set by memory: bytes a ball-step must move (bench/traffic.hpp), copy bandwidth\n");
  std::printf("%8s %-22s %14s %8s %10s %14s %9s\n", "N", "scene", "ball-steps/s", "B/step", "copy GB/s",
              "limit", "of limit");
  for (const Limit& l : limits) {
    const double most = l.bandwidth / l.bytes;
    std::printf("%8d %-22s %12.2f M %8.0f %10.2f %12.2f M %8.0f%%\n", l.balls, l.scene, l.ball_steps / 1e6, l.bytes,
                l.bandwidth / 1e9, most / 1e6, 100 * l.ball_steps / most);
  }
  std::printf("A model small enough for the caches can pass 100%%: the limit is that of a model in main memory.\n");
}

const char* const kUsage =
    "usage:\n"
    "  trubal_bench [--backend NAME] [--threads T] [--steps K] [--periodic] [--phases] [N ...]\n"
    "      the dense FCC block on one backend, N rounded to 4 n^3 balls (default 1680 13500 108000):\n"
    "      the standard scene, without shear or rotation, and with damping and gravity; then each\n"
    "      run against the limit memory sets (bytes a ball-step moves, copy bandwidth measured)\n"
    "  trubal_bench --compare [--steps K] [--periodic] [--phases] [N ...]\n"
    "      every backend on 1 and 2 threads, speedup and efficiency against the best one-thread\n"
    "      time, peak memory per row (default 403 1680 13500 108000)\n"
    "  trubal_bench --settle FILE [--backend NAME] [--threads T] [--steps K] [--phases]\n"
    "      the peers' sparse settle scene, FILE a settle_<N>.xyz of ../shared/peers/gen_scenes.py\n"
    "      (default 20000 steps, timed in 4 parts)\n"
    "  trubal_bench --gen [N ...]          GEN's time: N balls of radius 0.4-0.6 in a periodic cell at a\n"
    "                                      solid fraction of 0.21 (default 200000 1000000)\n"
    "  trubal_bench --gen-porosity [N ...] GEN porosity 0.4 of a graded sand in a periodic cell sized\n"
    "                                      for about N balls (default 20000 200000)\n"
    "options:\n"
    "  --backend NAME  serial (default), threaded or allpairs\n"
    "  --threads T     the backend's threads (default 1)\n"
    "  --steps K       steps per timed run (default: by size)\n"
    "  --periodic      the FCC block in a periodic cell of the lattice's size, every ball free (the\n"
    "                  peers' scene); default: free space, the outer layer of lattice cells held\n"
    "  --phases        where each run's time went, in microseconds per step\n"
    "  -h, --help      this text\n";

// A whole positive number, or nothing.
bool positive(const char* text, int& value) {
  char* end = nullptr;
  errno = 0;
  const long v = std::strtol(text, &end, 10);
  if (end == text || *end != '\0' || errno != 0 || v <= 0 || v > 1000000000) return false;
  value = static_cast<int>(v);
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  std::string backend = "serial", settle_file;
  int steps = 0, threads = 1;
  bool comparing = false, gen = false, gen_porosity = false;
  std::vector<int> sizes;
  auto bad = [](const std::string& why) {
    std::fprintf(stderr, "trubal_bench: %s\n(trubal_bench --help for the usage)\n", why.c_str());
    return 2;
  };
  for (int k = 1; k < argc; ++k) {
    const std::string arg = argv[k];
    const bool has_value = k + 1 < argc;
    if (arg == "--help" || arg == "-h") {
      std::fputs(kUsage, stdout);
      return 0;
    } else if (arg == "--compare") comparing = true;
    else if (arg == "--gen") gen = true;
    else if (arg == "--gen-porosity") gen_porosity = true;
    else if (arg == "--phases") g_phases = true;
    else if (arg == "--periodic") g_periodic = true;
    else if (arg == "--threads" || arg == "--steps") {
      int v = 0;
      if (!has_value || !positive(argv[k + 1], v))
        return bad(arg + " needs a whole number above 0" + (has_value ? std::string(", not '") + argv[k + 1] + "'" : ""));
      (arg == "--threads" ? threads : steps) = v;
      ++k;
    } else if (arg == "--backend") {
      if (!has_value) return bad("--backend needs a name: serial, threaded or allpairs");
      backend = argv[++k];
      if (backend != "serial" && backend != "threaded" && backend != "allpairs")
        return bad("unknown backend '" + backend + "' (serial, threaded or allpairs)");
    } else if (arg == "--settle") {
      if (!has_value) return bad("--settle needs a settle_<N>.xyz file of gen_scenes.py");
      settle_file = argv[++k];
    } else {
      int n = 0;
      if (!positive(arg.c_str(), n) || n < 4)
        return bad("unknown option or not a ball count (a whole number, at least 4): '" + arg + "'");
      sizes.push_back(n);
    }
  }
  if (comparing + gen + gen_porosity + !settle_file.empty() > 1)
    return bad("--compare, --gen, --gen-porosity and --settle are separate benchmarks: give one");
  try {
    if (!settle_file.empty()) {
      if (!sizes.empty()) return bad("--settle takes its balls from the file, not ball counts");
      return settle(settle_file, backend, threads, steps);
    }
    if (gen || gen_porosity) return gen_speed(sizes, gen_porosity);
    if (comparing) {
      if (sizes.empty()) sizes = {403, 1680, 13500, 108000};
      return compare(sizes, steps);
    }
    if (sizes.empty()) sizes = {1680, 13500, 108000};
    std::printf("dense FCC block, %s, backend %s (%d threads), dt 0.02, M = million per second\n",
                g_periodic ? "periodic cell" : "free space, outer layer held", backend.c_str(), threads);
    std::printf("%8s %10s %8s %6s %14s %14s %10s %10s %9s %7s\n", "N", "contacts", "steps", "s", "ball-steps/s",
                "contacts/s", "no-rot x", "all-on x", "peak MiB", "B/ball");
    struct Limit { int balls; const char* scene; double ball_steps, bytes, bandwidth; };
    std::vector<Limit> limits;
    for (int n : sizes) {
      // 4 n^3 balls; 1680 is the peers' 7 x 6 x 10 block.
      int nx, ny, nz;
      lattice_for(n, nx, ny, nz);
      const int k = steps > 0 ? steps : std::max(20, static_cast<int>(4e6 / (4.0 * nx * ny * nz)));
      reset_peak_memory();
      const Timing standard = run(fcc_block(nx, ny, nz, Scene::Standard), backend, k, threads);
      const double peak = standard.peak_mib;   // the standard run's: model, lists, scratch, rescue copy
      const Timing reduced = run(fcc_block(nx, ny, nz, Scene::NoRotation), backend, k, threads);
      const Timing full = run(fcc_block(nx, ny, nz, Scene::Everything), backend, k, threads);
      const int balls = 4 * nx * ny * nz;
      const double bandwidth = bench::copy_bandwidth();   // beside the runs it is the limit of
      auto limit = [&](const char* scene, const Timing& t, bench::TrafficScene traffic) {
        traffic.periodic = g_periodic;
        limits.push_back({balls, scene, t.ball_steps, bench::step_traffic(traffic).bytes(t.pairs_per_ball, 0), bandwidth});
      };
      limit("standard", standard, {});
      limit("no rotation, no shear", reduced, {.rotation = false, .shear = false});
      limit("damping + gravity", full, {.loads = !g_periodic});
      std::printf("%8d %10zu %8d %6.2f %12.2f M %12.2f M %9.2fx %9.2fx %9.0f %7.0f\n", balls, standard.contacts, k,
                  standard.seconds, standard.ball_steps / 1e6, standard.contact_steps / 1e6,
                  reduced.ball_steps / standard.ball_steps, full.ball_steps / standard.ball_steps, peak,
                  peak * 1048576.0 / balls);
      std::fflush(stdout);
    }
    std::printf("no-rot x: a scene without shear or rotation against the standard one; all-on x: with Rayleigh\n"
                "damping%s as well. peak MiB: the process's peak resident memory in the standard run (the\n"
                "program's own few MiB included); B/ball: that per ball.\n",
                g_periodic ? " (no gravity in the periodic cell)" : " and gravity");
    print_limits(limits);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "trubal_bench: %s\n", e.what());
    return 1;
  }
  return 0;
}
