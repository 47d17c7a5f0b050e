// The exact accumulator of the step's global sums (support/exact_sum.hpp): exact, rounded once,
// and the same bits in any order or split, which is what lets threads and ranks share the sums.
#include <catch2/catch.hpp>

#include <algorithm>
#include <bit>
#include <cmath>
#include <random>
#include <vector>

#include "support/exact_sum.hpp"

using namespace trubal;

namespace {
double sum_of(const std::vector<double>& v) {
  ExactSum s;
  for (double x : v) s.add(x);
  return s.value();
}
}  // namespace

TEST_CASE("exact sum: cancellation and rounding are exact", "[support][exact]") {
  // 1e16 + 1 - 1e16: a double running sum loses the 1 (1e16 + 1 rounds to 1e16).
  CHECK(sum_of({1e16, 1.0, -1e16}) == 1.0);
  // Ten copies of double(0.1) sum exactly to 1 + 5.55e-17, whose nearest double is 1; the running
  // double sum gives 0.9999999999999999.
  CHECK(sum_of(std::vector<double>(10, 0.1)) == 1.0);
  // 1 + 2^-53 is halfway between 1 and the next double: ties go to the even one (1). Anything
  // beyond the half, however small, goes up.
  CHECK(sum_of({1.0, std::ldexp(1.0, -53)}) == 1.0);
  CHECK(sum_of({1.0, std::ldexp(1.0, -53), std::ldexp(1.0, -200)}) == std::nextafter(1.0, 2.0));
  CHECK(sum_of({1.0 + std::ldexp(1.0, -52), std::ldexp(1.0, -53)}) == 1.0 + std::ldexp(1.0, -51));
  // The ends of the range: the largest doubles cancel without overflow, subnormals add exactly.
  const double big = std::numeric_limits<double>::max(), tiny = std::numeric_limits<double>::denorm_min();
  CHECK(sum_of({big, big, -big, -big, 3.0}) == 3.0);
  CHECK(sum_of({big, big}) == INFINITY);
  CHECK(sum_of({tiny, tiny, tiny}) == 3 * tiny);
  CHECK(sum_of({-2.5, 1.0}) == -1.5);
  CHECK(sum_of({}) == 0.0);
  CHECK(sum_of({5.0, -5.0}) == 0.0);
  // NaN and infinities are kept aside.
  CHECK(std::isnan(sum_of({1.0, NAN})));
  CHECK(std::isnan(sum_of({INFINITY, -INFINITY})));
  CHECK(sum_of({INFINITY, 1e300, 1e300}) == INFINITY);
  CHECK(sum_of({-INFINITY, 2.0}) == -INFINITY);
}

TEST_CASE("exact sum: any order and any split give the same bits", "[support][exact]") {
  // Values of both signs over 40 decades, as energies and moments of a step are: the running
  // double sum depends on the order, the exact sum does not.
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<double> mantissa(-1, 1);
  std::uniform_int_distribution<int> exponent(-60, 70);
  std::vector<double> v(20000);
  for (double& x : v) x = std::ldexp(mantissa(rng), exponent(rng));
  const double reference = sum_of(v);
  bool naive_differs = false;
  double naive0 = 0;
  for (double x : v) naive0 += x;
  for (int trial = 0; trial < 5; ++trial) {
    std::shuffle(v.begin(), v.end(), rng);
    double naive = 0;
    for (double x : v) naive += x;
    naive_differs |= naive != naive0;
    CHECK(std::bit_cast<std::uint64_t>(sum_of(v)) == std::bit_cast<std::uint64_t>(reference));
    // Split into parts of uneven sizes, each summed on its own, merged in reverse: as threads and
    // ranks merge their parts.
    std::vector<ExactSum> parts(7);
    for (std::size_t k = 0; k < v.size(); ++k) parts[(k * k) % 7].add(v[k]);
    ExactSum merged;
    for (int p = 6; p >= 0; --p) merged.add(parts[p]);
    CHECK(std::bit_cast<std::uint64_t>(merged.value()) == std::bit_cast<std::uint64_t>(reference));
    // Through the limbs, as over MPI: summed as integers, then loaded.
    std::array<std::int64_t, ExactSum::kLimbs> total{};
    for (ExactSum& part : parts) {
      const auto& limbs = part.normalised_limbs();
      for (int k = 0; k < ExactSum::kLimbs; ++k) total[k] += limbs[k];
    }
    ExactSum loaded;
    loaded.load(total.data(), 0);
    CHECK(std::bit_cast<std::uint64_t>(loaded.value()) == std::bit_cast<std::uint64_t>(reference));
  }
  CHECK(naive_differs);   // the test would be empty if the order never mattered to doubles
}

TEST_CASE("exact sum: a negative total rounds as its magnitude, merged parts with their carries waiting too",
          "[support][exact]") {
  // value() carries only over the limbs in use and folds a negative total's run of borrows: the
  // ties and the sticky bits below them must round as for the positive total, mirrored.
  for (const double sign : {1.0, -1.0}) {
    CHECK(sum_of({sign * 1.0, sign * std::ldexp(1.0, -53)}) == sign * 1.0);   // a tie, to even
    CHECK(sum_of({sign * 1.0, sign * std::ldexp(1.0, -53), sign * std::ldexp(1.0, -200)}) ==
          sign * std::nextafter(1.0, 2.0));                                   // a sticky bit far below
    CHECK(sum_of({sign * std::ldexp(1.0, 300), -sign * std::ldexp(1.0, -300)}) ==
          sign * std::ldexp(1.0, 300));                                       // a borrow through 19 limbs
    CHECK(sum_of({sign * 3.0, -sign * std::ldexp(1.0, -1074)}) == sign * 3.0);
    CHECK(sum_of({-sign * std::ldexp(1.0, -1074), sign * std::ldexp(1.0, -1073)}) == sign * std::ldexp(1.0, -1074));
  }
  // One part merged many times over (its limbs unnormalised each time): 1000 times -(1 + 2^-40).
  ExactSum part, total;
  for (int k = 0; k < 7; ++k) part.add(-1.0 / 7.0);   // (not exactly -1: the sum of the rounded sevenths)
  part.add(-std::ldexp(1.0, -40));
  const double one = part.value();
  for (int k = 0; k < 1000; ++k) total.add(part);
  ExactSum reference;
  for (int k = 0; k < 1000; ++k) {
    for (int q = 0; q < 7; ++q) reference.add(-1.0 / 7.0);
    reference.add(-std::ldexp(1.0, -40));
  }
  CHECK(one < 0);
  CHECK(std::bit_cast<std::uint64_t>(total.value()) == std::bit_cast<std::uint64_t>(reference.value()));
}

TEST_CASE("exact sum: many additions between normalisations stay exact", "[support][exact]") {
  // 3 million additions of the largest 32-bit digit pattern (every limb's increment at its
  // largest) and as many subtractions: the carries must be propagated in time.
  ExactSum s;
  const double x = std::ldexp(static_cast<double>((std::uint64_t{1} << 53) - 1), 11);
  for (int k = 0; k < 3000000; ++k) s.add(x);
  ExactSum copy = s;
  CHECK(copy.value() == 3000000.0 * x);   // the exact total rounded once: the correctly rounded product
  for (int k = 0; k < 3000000; ++k) s.add(-x);
  s.add(0.25);
  CHECK(s.value() == 0.25);
}

TEST_CASE("exact sum: the fast stream gives the exact sum's bits, inside its window and out", "[support][exact]") {
  // Terms over 300 decades (most far outside any window of 40 binades), zeros, subnormals, and
  // more than 2^16 of them (the digits' flush): the stream must equal the plain exact sum.
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> mantissa(-1, 1);
  std::uniform_int_distribution<int> near(-20, 8), far(-1000, 1000), pick(0, 9);
  for (int trial = 0; trial < 4; ++trial) {
    std::vector<double> v(70000);
    for (double& x : v) {
      const int kind = pick(rng);
      x = kind == 0 ? 0.0 : kind == 1 ? std::ldexp(mantissa(rng), far(rng)) : kind == 2 ? 1e-310 * mantissa(rng)
                                                                           : std::ldexp(mantissa(rng), near(rng));
    }
    if (trial == 1) v[0] = 1e-320;   // a first term too small to set a window
    if (trial == 2) v[0] = 1e200;    // a first term far above the rest
    ExactSum plain, streamed;
    {
      ExactSum::Stream stream(streamed);
      for (double x : v) { plain.add(x); stream.add(x); }
    }
    CHECK(std::bit_cast<std::uint64_t>(streamed.value()) == std::bit_cast<std::uint64_t>(plain.value()));
  }
  ExactSum with_nan;
  {
    ExactSum::Stream stream(with_nan);
    stream.add(1.0);
    stream.add(NAN);
  }
  CHECK(std::isnan(with_nan.value()));
}

TEST_CASE("exact sum: the stream's vector blocks give the exact sum's bits", "[support][exact]") {
  // Blocks of 0 to 300 terms: most within a few decades (the vector path), some blocks with a
  // zero, a subnormal, a term far outside the window, a NaN-free overflow of the window upwards
  // (the slow path), and more than 2^16 terms in all (the digits' flush between blocks). The
  // vector path must equal the plain exact sum: a wrong split or a lost carry changes the bits.
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> mantissa(-1, 1);
  std::uniform_int_distribution<int> near(-30, 4), far(-900, 900), pick(0, 199), size(0, 300);
  for (int trial = 0; trial < 6; ++trial) {
    ExactSum plain, streamed;
    std::size_t vector_blocks = 0;
    {
      ExactSum::Stream stream(streamed);
      std::size_t total = 0;
      while (total < 90000) {
        std::vector<double> block(static_cast<std::size_t>(size(rng)));
        bool odd = false;
        for (double& x : block) {
          const int kind = pick(rng);
          odd |= kind == 1 || kind == 2 || kind == 3;
          x = kind == 0 ? 0.0 : kind == 1 ? std::ldexp(mantissa(rng), far(rng))
                              : kind == 2 ? 1e-310 * mantissa(rng)
                              : kind == 3 ? std::ldexp(mantissa(rng), 12)   // above the window: it moves up
                                          : std::ldexp(mantissa(rng), near(rng)) * (trial == 5 ? 1e-12 : 1.0);
        }
        vector_blocks += !odd && !block.empty();
        for (double x : block) plain.add(x);
        stream.add_block(block.data(), block.size());
        total += block.size();
      }
    }
    CHECK(vector_blocks > 100);   // the vector path was taken, not only the term-by-term one
    CHECK(std::bit_cast<std::uint64_t>(streamed.value()) == std::bit_cast<std::uint64_t>(plain.value()));
  }
  // One block of the same magnitude many times over: the digits' sums cross 2^63 as unsigned
  // integers (each term's bits are about 2^62) and must still come out exact.
  ExactSum plain, streamed;
  {
    ExactSum::Stream stream(streamed);
    std::vector<double> block(256);
    for (std::size_t q = 0; q < block.size(); ++q) block[q] = (q % 2 ? -1.0 : 1.0) * (1.0 + 0x1p-52 * static_cast<double>(q)) * 3e5;
    for (int r = 0; r < 700; ++r) {
      for (double x : block) plain.add(x);
      stream.add_block(block.data(), block.size());
    }
  }
  CHECK(std::bit_cast<std::uint64_t>(streamed.value()) == std::bit_cast<std::uint64_t>(plain.value()));
}
