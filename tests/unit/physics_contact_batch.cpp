// The batch kernel's way around the Coulomb cap (physics/contact_law.hpp contact_forces): a batch
// first made as if every spring held, its sliding lanes made again, must give every lane the bits
// of the batch made with the cap throughout, whatever the number of sliding lanes.
#include <catch2/catch.hpp>

#include <cstring>
#include <random>
#include <vector>

#include "physics/contact_law.hpp"

using namespace trubal;

namespace {

// 32 lanes of touching pairs (and a few apart), the shear history of `sliding` of them past the
// Coulomb limit (fewer where some of those are apart), the others well within it. Lanes apart get a
// large history too: they do not slide.
struct Lanes {
  ContactBatch B;
  std::vector<double> hx, hy, hz;
  std::size_t sliding = 0;   // touching lanes whose history is past the limit
};

Lanes make_lanes(std::size_t sliding, std::uint32_t seed, const PairLaw& law) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  Lanes L;
  L.hx.resize(kBatch); L.hy.resize(kBatch); L.hz.resize(kBatch);
  for (std::size_t q = 0; q < kBatch; ++q) {
    ContactBatch& B = L.B;
    B.ri[q] = 1.0 + 0.1 * unit(rng);
    B.rj[q] = 1.0 + 0.1 * unit(rng);
    const bool apart = q % 11 == 5;
    const double u = apart ? -0.01 : 0.001 * (1.5 + unit(rng));   // overlap
    double nx = unit(rng), ny = unit(rng), nz = unit(rng);
    const double n = std::sqrt(nx * nx + ny * ny + nz * nz);
    nx /= n; ny /= n; nz /= n;
    const double d = B.ri[q] + B.rj[q] - u;
    B.dx[q] = d * nx; B.dy[q] = d * ny; B.dz[q] = d * nz;
    B.vx[q] = 1e-4 * unit(rng); B.vy[q] = 1e-4 * unit(rng); B.vz[q] = 1e-4 * unit(rng);
    B.sx[q] = 1e-4 * unit(rng); B.sy[q] = 1e-4 * unit(rng); B.sz[q] = 1e-4 * unit(rng);
    B.mstar[q] = 1.0;
    B.set_law(q, law);
    // The limit is about mu k_n U: a slider's history ten times that, a holder's a hundredth.
    const bool slides = apart || (q * 7 % kBatch) < sliding;
    L.sliding += slides && !apart;
    const double scale = (slides ? 10.0 : 0.01) * law.friction * law.kn * (apart ? 0.001 : u);
    L.hx[q] = scale * unit(rng); L.hy[q] = scale * unit(rng); L.hz[q] = scale * unit(rng);
  }
  return L;
}

template <ContactFeatures F>
void check_same_bits(const PairLaw& law) {
  for (std::size_t sliding : {0, 1, 2, 5, 31}) {
    CAPTURE(sliding);
    for (std::uint32_t seed = 1; seed <= 5; ++seed) {
      CAPTURE(seed);
      Lanes capped = make_lanes(sliding, seed, law);
      Lanes tried = capped;
      std::vector<double> ch(3 * kBatch), th(3 * kBatch);
      contact_forces<F, true>(capped.B, kBatch, law, 1e-3, 1e-3, 0.0, capped.hx.data(), capped.hy.data(),
                              capped.hz.data(), ch.data(), ch.data() + kBatch, ch.data() + 2 * kBatch);
      int clean_run = kCleanRun;   // the batches before had no sliding lane: this one is tried without the cap
      contact_forces<F, true>(tried.B, kBatch, law, 1e-3, 1e-3, 0.0, tried.hx.data(), tried.hy.data(), tried.hz.data(),
                              th.data(), th.data() + kBatch, th.data() + 2 * kBatch, &clean_run);
      std::size_t slid = 0;
      for (std::size_t q = 0; q < kBatch; ++q) slid += capped.B.state[q] == 2.0;
      CHECK(slid == capped.sliding);   // the lanes are as meant (those apart do not slide)
      // Every result and the new history, bit for bit (a lane made without the cap that should
      // have slid would keep a force past the limit).
      CHECK(std::memcmp(&capped.B, &tried.B, sizeof(ContactBatch)) == 0);
      CHECK(std::memcmp(ch.data(), th.data(), ch.size() * sizeof(double)) == 0);
      // The way it went: none or one sliding lane keep trying without the cap; more make the next
      // batches start with it again.
      CHECK(clean_run == (capped.sliding <= 1 ? kCleanRun : 0));
    }
  }
}

}  // namespace

TEST_CASE("contact batch: made without the Coulomb cap first, every lane gets the capped bits",
          "[physics][kernel]") {
  PairLaw linear;
  linear.kn = 1e6; linear.ks = 5e5; linear.friction = 0.5;
  SECTION("linear springs, spins") { check_same_bits<ContactFeatures{.rotation = true, .shear = true}>(linear); }
  SECTION("linear springs, restitution dashpot") {
    PairLaw damped = linear;
    damped.rest_xi = 0.2;
    check_same_bits<ContactFeatures{.rotation = true, .shear = true, .dashpot = true}>(damped);
  }
  SECTION("Hertz-Mindlin") {
    PairLaw hertz;
    hertz.hertz_n = 1e9; hertz.hertz_s = 5e8; hertz.friction = 0.3;
    hertz.kn = 3e7;   // (only sizes the histories above: about F_n / U at these overlaps)
    check_same_bits<ContactFeatures{.rotation = true, .shear = true, .hertz = true}>(hertz);
  }
}

TEST_CASE("contact batch: a batch made with the cap counts the clean batches before a try without it",
          "[physics][kernel]") {
  PairLaw law;
  law.kn = 1e6; law.ks = 5e5; law.friction = 0.5;
  constexpr ContactFeatures F{.rotation = true, .shear = true};
  std::vector<double> h(3 * kBatch);
  int clean_run = 0;
  for (int k = 1; k <= kCleanRun; ++k) {
    Lanes L = make_lanes(0, 7, law);
    contact_forces<F, true>(L.B, kBatch, law, 1e-3, 1e-3, 0.0, L.hx.data(), L.hy.data(), L.hz.data(), h.data(),
                            h.data() + kBatch, h.data() + 2 * kBatch, &clean_run);
    CHECK(clean_run == k);
  }
  Lanes L = make_lanes(3, 7, law);
  contact_forces<F, true>(L.B, kBatch, law, 1e-3, 1e-3, 0.0, L.hx.data(), L.hy.data(), L.hz.data(), h.data(),
                          h.data() + kBatch, h.data() + 2 * kBatch, &clean_run);
  CHECK(clean_run == 0);
}
