// Decks that more than one test file runs.
#pragma once

#include <algorithm>
#include <string>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include <string>

namespace trubal::test {

// A loose periodic assembly compressed by the servo, then loaded under the mixed servo (xx, yy held)
// with an axial strain rate and a shear rate: servo, strain, shear strain (Lees-Edwards images),
// local damping. The cycling under test follows (cycle_cuts.cpp, distributed_runs.cpp).
inline constexpr const char* kServoShearDeck = R"(start 0.01 0.01 0.01
prop kn 1e5 ks 1e5 fric 26.57 dens 2650
gen 300 0.0004 0.0006 seed 7
damp local 0.7
servo 1e5 1e5 1e5
cycle 3000
servo xx 1e5 yy 1e5
strain zz 2 xy 1
)";

// 384 balls on a jittered 8 x 8 x 6 grid, overlapping a little, numbered at random (id 7919 k mod
// 384, plus one, for the k-th place), in a box periodic in x and y over a floor wall: gravity,
// friction and local damping, contacts across the periodic faces. For RENUMBER (renumber.cpp).
inline std::string scrambled_settle_deck() {
  std::string deck = R"(start box 0 316 0 316 -25 400 x periodic y periodic
prop kn 1.5e9 ks 1.5e9 fric 20 dens 2000
prop type 2 kn 1.5e9 ks 1.5e9 fric 15
wall id 1 plane 0 0 -1 0 0 1 type 2
)";
  const int n = 8 * 8 * 6;
  int k = 0;
  for (int c = 0; c < 6; ++c)
    for (int b = 0; b < 8; ++b)
      for (int a = 0; a < 8; ++a, ++k) {
        const double jitter = 0.3 * ((k * 37 % 11) - 5) / 5.0;
        deck += fmt::format("ball {} {} {} 20 id {}\n", 19.75 + 39.5 * a + jitter, 19.75 + 39.5 * b - 0.7 * jitter,
                            19.2 + 39.2 * c + 0.5 * jitter, static_cast<long>(k) * 7919 % n + 1);
      }
  return deck + "grav 0 0 -1\ndamp local 0.2\n";
}

// The same scene with its balls scrambled in memory as well: the BALL lines in id order, and the
// run never sorting them into space order (SET sort 0). For RENUMBER and PRINT info's ball order.
inline std::string scrambled_in_memory_deck() {
  const std::string deck = scrambled_settle_deck();
  const std::size_t first = deck.find("ball "), last = deck.find("grav ");
  std::vector<std::pair<long, std::string>> lines;
  for (std::size_t at = first; at < last;) {
    const std::size_t end = deck.find('\n', at) + 1;
    const std::string line = deck.substr(at, end - at);
    lines.emplace_back(std::stol(line.substr(line.rfind(" id ") + 4)), line);
    at = end;
  }
  std::sort(lines.begin(), lines.end());
  std::string out = deck.substr(0, first) + "set sort 0\n";
  for (const auto& [id, line] : lines) out += line;
  return out + deck.substr(last);
}

// A bar of 40 balls along x (ids 1 to 40 at x = 0 to 39), bonded strongly but for one weak bond in
// its middle, between ids 20 and 21, and pulled slowly from both ends: the weak bond alone breaks.
// Two threads' or ranks' parts meet there (the bisection cuts the bar at its median, between x = 19
// and 20). `before`: lines ahead of START (a BACKEND). For physics_bond.cpp, distributed_bonds.cpp.
inline std::string pulled_bar_deck(const std::string& before = "") {
  std::string deck = before + "start box -2 42 -2 2 -2 2\nprop kn 1e9 ks 1e9 mu 0.5 dens 1000\n";
  for (int k = 0; k < 40; ++k) deck += fmt::format("ball {} 0 0 0.5 id {}\n", k, k + 1);
  return deck + "bond range x -1 19.5 gap 1e-6 kn 1e10 ks 1e10 ten 1e9 coh 1e9\n"
                "bond range x 19.5 41 gap 1e-6 kn 1e10 ks 1e10 ten 1e9 coh 1e9\n"
                "bond range x 18.5 20.5 gap 1e-6 kn 1e10 ks 1e10 ten 1e6 coh 1e9\n"
                "fix vel spin range x -1 0.5\nfix vel spin range x 38.5 41\n"
                "init xvel -1e-2 range x -1 0.5\ninit xvel 1e-2 range x 38.5 41\ncycle 3000\n";
}

}  // namespace trubal::test
