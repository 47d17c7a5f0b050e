// An exact sum of doubles: the result is the exact total, rounded once, so it does not depend on
// the order of the additions, on how they are split among threads or ranks, or on how partial sums
// are merged. The step's global sums (energies, the servo's stress, wall loads) use it, so every
// backend, thread count and rank count gives the same bits.
//
// The method is a long fixed-point accumulator (Kulisch's idea; Demmel and Nguyen's reproducible
// summation has the same aim with less memory): a double is m 2^(e - 1074) with an integer m of 53
// bits and 0 <= e < 2046, so every double is a whole number of units of 2^-1074. The accumulator
// keeps that whole number in 32-bit digits, each stored in a signed 64-bit limb so that carries can
// wait: one addition adds at most 2^32 to three limbs, and the limbs are normalised (carries
// propagated, every limb but the top one in [0, 2^32)) before they could overflow. A normalised
// accumulator is a unique representation of its value, so merging limbs (even over MPI, as integers)
// is exact and the final rounding sees the same number however it was reached.
//
// NaN and the infinities are kept aside: any NaN, or +inf with -inf, gives NaN; otherwise an
// infinity gives itself.
#pragma once

#include <array>
#include <bit>
#include <cmath>
#include <cstdint>

namespace trubal {

class ExactSum {
 public:
  static constexpr int kLimbs = 67;   // 2046 + 53 bits of range, and room for carries

  [[gnu::always_inline]] void add(double x) {
    const std::uint64_t bits = std::bit_cast<std::uint64_t>(x);
    const auto field = static_cast<std::uint32_t>((bits >> 52) & 0x7ff);
    if (field == 0x7ff) [[unlikely]] {   // NaN or an infinity
      if ((bits << 12) != 0) special_ |= kNaN;
      else special_ |= (bits >> 63) != 0 ? kMinusInf : kPlusInf;
      return;
    }
    // m 2^(position - 1074); a zero adds zeros. No branch on the sign: the signs of a step's
    // terms (moments, works) are as good as random.
    const std::uint64_t normal = field != 0;
    const std::uint64_t m = (bits & ((std::uint64_t{1} << 52) - 1)) | (normal << 52);
    const std::uint32_t position = field - static_cast<std::uint32_t>(normal);
    const std::uint32_t k = position >> 5, shift = position & 31;
    const std::uint64_t low = m << shift, high = (m >> 1) >> (63 - shift);   // the 84 bits of m 2^shift
    const std::int64_t negative = -static_cast<std::int64_t>(bits >> 63);   // 0 or all ones
    auto signed_digit = [negative](std::uint64_t d) { return (static_cast<std::int64_t>(d) ^ negative) - negative; };
    limb_[k] += signed_digit(low & 0xffffffffu);
    limb_[k + 1] += signed_digit(low >> 32);
    limb_[k + 2] += signed_digit(high);
    if (++pending_ >= kMaxPending) [[unlikely]] normalise();
  }

  // Adds v 2^e exactly (|v| < 2^63; e >= -1074 and small enough that v 2^e is finite).
  void add_integer(std::int64_t v, int e) {
    const auto high = static_cast<double>(v >> 32) * 0x1p32;       // exact: at most 31 bits, times 2^32
    const auto low = static_cast<double>(v & 0xffffffff);           // exact: 32 bits
    add(std::ldexp(high, e));
    add(std::ldexp(low, e));
  }

  class Stream;

  // Adds another sum (exactly): limb by limb, the carries left waiting (each side's limbs are at
  // most its pending count plus one times 2^32 from their normalised values).
  void add(const ExactSum& o) {
    if (pending_ + o.pending_ + 1 >= kMaxPending) [[unlikely]] {
      ExactSum other = o;
      other.normalise();
      normalise();
      return add(other);
    }
    for (int k = 0; k < kLimbs; ++k) limb_[k] += o.limb_[k];
    special_ |= o.special_;
    pending_ += o.pending_ + 1;
  }

  // The sum, rounded to the nearest double (ties to even; a total beyond the double range is an
  // infinity).
  double value() const {
    if (special_ != 0) {
      if ((special_ & kNaN) || (special_ & kPlusInf && special_ & kMinusInf)) return std::nan("");
      return special_ & kPlusInf ? INFINITY : -INFINITY;
    }
    // Normalised over the limbs in use only (a step's sums span a few of the 67).
    int lo = 0;
    while (lo < kLimbs && limb_[lo] == 0) ++lo;
    if (lo == kLimbs) return 0.0;
    int hi = kLimbs - 1;
    while (limb_[hi] == 0) --hi;
    std::array<std::int64_t, kLimbs> l = limb_;
    int top = carry_up(l.data(), lo, hi);
    const bool negative = l[top] < 0;
    if (negative) {   // the magnitude, normalised again
      for (int k = lo; k <= top; ++k) l[k] = -l[k];
      top = carry_up(l.data(), lo, top);
    }
    while (top >= lo && l[top] == 0) --top;
    if (top < lo) return 0.0;
    // The top three digits hold at least 65 significant bits; the rest only decide ties.
    unsigned __int128 m = 0;
    for (int k = top; k > top - 3; --k) m = (m << 32) | static_cast<std::uint64_t>(k >= 0 ? l[k] : 0);
    bool sticky = false;
    for (int k = top - 3; k >= lo; --k) sticky |= l[k] != 0;
    int exponent = 32 * (top - 2) - 1074;   // the unit of m
    const int bits = 128 - count_leading_zeros(m);
    if (bits > 53) {
      const int drop = bits - 53;
      const unsigned __int128 rest = m & ((static_cast<unsigned __int128>(1) << drop) - 1);
      const unsigned __int128 half = static_cast<unsigned __int128>(1) << (drop - 1);
      m >>= drop;
      exponent += drop;
      if (rest > half || (rest == half && (sticky || (m & 1)))) m += 1;
    }
    const double magnitude = std::ldexp(static_cast<double>(static_cast<std::uint64_t>(m)), exponent);
    return negative ? -magnitude : magnitude;
  }

  // The limbs, normalised, for an exchange between ranks (sum them as integers, then load).
  const std::array<std::int64_t, kLimbs>& normalised_limbs() {
    normalise();
    return limb_;
  }
  std::uint8_t special() const { return special_; }
  void load(const std::int64_t* limbs, std::uint8_t special) {
    for (int k = 0; k < kLimbs; ++k) limb_[k] = limbs[k];
    special_ = special;
    normalise();   // (limbs summed over ranks need their carries)
  }

 private:
  static constexpr std::uint8_t kNaN = 1, kPlusInf = 2, kMinusInf = 4;
  static constexpr std::uint32_t kMaxPending = 1u << 29;   // additions (or merges) between normalisations

  static int count_leading_zeros(unsigned __int128 v) {
    const auto high = static_cast<std::uint64_t>(v >> 64), low = static_cast<std::uint64_t>(v);
    return high != 0 ? std::countl_zero(high) : 64 + std::countl_zero(low);
  }
  // Carries from limb lo upwards, in place (hi: the highest limb that may be nonzero), stopping
  // where nothing is left to carry: the limbs below the returned one are in [0, 2^32), the returned
  // one holds the sign, and those above it are zero. The same number as normalise() makes, with
  // the run of all-ones limbs below a negative top folded into -1.
  static int carry_up(std::int64_t* l, int lo, int hi) {
    for (int k = lo; k < kLimbs - 1; ++k) {
      const std::int64_t carry = carry_from(l, k);
      if (k >= hi && (carry == 0 || carry == -1)) return k + 1;
    }
    return kLimbs - 1;
  }
  // Every limb's carry taken up (every limb but the top one in [0, 2^32)).
  void normalise() {
    for (int k = 0; k < kLimbs - 1; ++k) carry_from(limb_.data(), k);
    pending_ = 0;
  }
  // Limb k brought into [0, 2^32), what it held beyond added to limb k + 1; returns that carry.
  static std::int64_t carry_from(std::int64_t* l, int k) {
    const std::int64_t carry = l[k] >> 32;   // floor division by 2^32
    l[k] -= carry * (std::int64_t{1} << 32);
    l[k + 1] += carry;
    return carry;
  }

  std::array<std::int64_t, kLimbs> limb_{};
  std::uint32_t pending_ = 0;
  std::uint8_t special_ = 0;
};

// A fast front for a loop's stream of additions to one ExactSum, meant to live in the loop's
// registers. Most of a stream's terms lie within a few decades of each other: a term whose
// exponent falls in the window of 40 binades below 2^top is an integer multiple of the window's
// grid 2^(top - 92), so it goes exactly into two integer digits (46 bits each) with a few register
// operations; any other term goes to the ExactSum itself. The window follows the largest term so
// far. The digits go to the ExactSum (exactly) every 2^16 terms and at the end (flush, or the destructor),
// so the total is the ExactSum's, exact, whatever the window.
class ExactSum::Stream {
 public:
  explicit Stream(ExactSum& to) : to_(&to) {}
  Stream(const Stream&) = delete;
  Stream& operator=(const Stream&) = delete;
  ~Stream() { flush(); }

  [[gnu::always_inline]] void add(double x) {
    const auto field = static_cast<std::uint32_t>((std::bit_cast<std::uint64_t>(x) >> 52) & 0x7ff);
    if (field - s_.low < kWidth) [[likely]] {
      const double y = x * s_.scale;                          // a whole number, |y| < 2^92
      const auto high = static_cast<std::int64_t>(y * 0x1p-46);   // truncated: |high| < 2^46
      const double rest = y - static_cast<double>(high) * 0x1p46;   // exact: a whole number below 2^46
      s_.high += high;
      s_.low_digit += static_cast<std::int64_t>(rest);
      if (++s_.count == kFlushEvery) [[unlikely]] s_ = flushed(to_, s_);
    } else if (x != 0) {   // (a zero adds nothing; a NaN goes to the ExactSum)
      s_ = outside(to_, s_, x, field);
    }
  }
  void flush() { s_ = flushed(to_, s_); }

  // Adds x[0, n): the same as add() term by term, but where every term is within the window (or
  // zero) the block goes in as one vector loop. Each term is split on the window's grid by the
  // magic-number rounding (t + 1.5 2^52 rounds |t| < 2^51 to a whole number, exactly, and its bits
  // less the constant's are that whole number), so the loop is plain double and integer arithmetic
  // the compiler vectorises, with no conversion instructions (AVX2 has none for 64-bit integers).
  // The digits' sums wrap as unsigned integers; the true totals fit (n < 2^16 terms below 2^46).
  void add_block(const double* __restrict x, std::size_t n) {
    if (n == 0) return;
    if (n > kFlushEvery / 2 || s_.count + n >= kFlushEvery) {   // (never in the motion loop's blocks)
      for (std::size_t q = 0; q < n; ++q) add(x[q]);
      return;
    }
    const std::uint32_t low = s_.low;
    const double scale = s_.scale;
    constexpr double kMagic = 0x1.8p52;
    std::uint64_t outside = 0, high = 0, low_digit = 0;
    for (std::size_t q = 0; q < n; ++q) {
      const std::uint64_t bits = std::bit_cast<std::uint64_t>(x[q]);
      const auto field = static_cast<std::uint32_t>((bits >> 52) & 0x7ff);
      outside |= static_cast<std::uint64_t>(field - low >= kWidth) & static_cast<std::uint64_t>((bits << 1) != 0);
      const double y = x[q] * scale;                          // a whole number, |y| < 2^92 (inside)
      const double u = y * 0x1p-46 + kMagic;                  // the high digit h, rounded, plus the constant
      const double rest = y - (u - kMagic) * 0x1p46;          // exact: a whole number, |rest| <= 2^45
      high += std::bit_cast<std::uint64_t>(u);
      low_digit += std::bit_cast<std::uint64_t>(rest + kMagic);
    }
    if (outside != 0) {   // some term needs the slow path: the block goes term by term
      for (std::size_t q = 0; q < n; ++q) add(x[q]);
      return;
    }
    const std::uint64_t bias = std::bit_cast<std::uint64_t>(kMagic) * n;   // (mod 2^64, as the sums)
    s_.high += static_cast<std::int64_t>(high - bias);
    s_.low_digit += static_cast<std::int64_t>(low_digit - bias);
    s_.count += static_cast<std::uint32_t>(n);
  }

 private:
  static constexpr std::uint32_t kWidth = 40;            // binades in the window
  static constexpr std::uint32_t kFlushEvery = 1u << 16;   // digits stay below 2^62
  // The stream's state, passed by value to the slow paths so that the loop keeps it in registers.
  struct State {
    std::int64_t high = 0, low_digit = 0;
    std::uint32_t count = 0;
    std::uint32_t low = 0xffffffffu - kWidth;   // exponent field of the window's bottom; none yet: every term is outside
    int grid = 0;                               // 2^grid: the unit of the low digit
    double scale = 1;                           // 2^-grid
  };
  [[gnu::noinline]] static State flushed(ExactSum* to, State s) {
    if (s.count == 0) return s;
    to->add_integer(s.high, s.grid + 46);
    to->add_integer(s.low_digit, s.grid);
    s.high = s.low_digit = 0;
    s.count = 0;
    return s;
  }
  [[gnu::noinline]] static State outside(ExactSum* to, State s, double x, std::uint32_t field) {
    // A normal term of moderate size above the window (or the first) moves the window up to it,
    // with room for terms up to 2^6 times larger; terms below it go to the ExactSum.
    const bool none = s.low > 2047;
    if (field >= 92 && field <= 1800 && (none || field >= s.low + kWidth)) {
      s = flushed(to, s);
      const std::uint32_t top = field + 6;            // exponent field bound (exclusive)
      s.low = top - kWidth;
      s.grid = static_cast<int>(top) - 1115;
      s.scale = std::ldexp(1.0, -s.grid);
      const double y = x * s.scale;
      const auto high = static_cast<std::int64_t>(y * 0x1p-46);
      s.high += high;
      s.low_digit += static_cast<std::int64_t>(y - static_cast<double>(high) * 0x1p46);
      s.count += 1;
      return s;
    }
    to->add(x);
    return s;
  }

  ExactSum* to_;
  State s_;
};

}  // namespace trubal
