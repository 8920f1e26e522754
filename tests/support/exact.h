// Test oracle for the exact predicates: arbitrary-precision integers and the signs of the
// orientation determinants computed with no rounding at all.
//
// Method: every finite double is m * 2^e with an integer m (|m| < 2^53) and -1074 <= e <= 971.
// All coordinates of one query are shifted to the smallest exponent among them, which turns
// them into integers on one common scale 2^emin; the determinant (a polynomial of degree 2 or
// 3, homogeneous under that scaling) is then evaluated in integer arithmetic, where
// subtraction and multiplication are exact. Its sign is the sign of the real determinant.
//
// Deliberately simple (schoolbook arithmetic on 32-bit limbs, std::vector storage): it is the
// reference the fast code is checked against, so it must be obviously correct, not fast.
#ifndef SPLINTCORE_TESTS_SUPPORT_EXACT_H
#define SPLINTCORE_TESTS_SUPPORT_EXACT_H

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

namespace splintcore_test {

// Signed integer of any size: sign and magnitude, magnitude in base 2^32, least significant
// limb first, no leading zero limbs; zero is an empty magnitude and is never negative.
class BigInt {
 public:
  BigInt() = default;
  explicit BigInt(int64_t value) {
    // Magnitude via unsigned arithmetic (well defined for INT64_MIN too).
    const uint64_t magnitude =
        value < 0 ? ~static_cast<uint64_t>(value) + 1u : static_cast<uint64_t>(value);
    *this = from_magnitude(magnitude, 0, value < 0);
  }

  // (negative ? -1 : 1) * magnitude * 2^shift.
  static BigInt from_magnitude(uint64_t magnitude, unsigned shift, bool negative) {
    BigInt r;
    if (magnitude == 0) return r;
    const size_t limb_shift = shift / 32;
    const unsigned bit_shift = shift % 32;
    r.limbs_.assign(limb_shift + 3, 0u);
    // The 64-bit magnitude shifted by bit_shift < 32 spans at most three limbs.
    const uint64_t low = magnitude << bit_shift;
    const uint64_t high = bit_shift == 0 ? 0 : magnitude >> (64 - bit_shift);
    r.limbs_[limb_shift] = static_cast<uint32_t>(low & 0xffffffffu);
    r.limbs_[limb_shift + 1] = static_cast<uint32_t>(low >> 32);
    r.limbs_[limb_shift + 2] = static_cast<uint32_t>(high);
    r.negative_ = negative;
    r.normalize();
    return r;
  }

  int sign() const { return limbs_.empty() ? 0 : (negative_ ? -1 : 1); }
  bool is_zero() const { return limbs_.empty(); }
  const std::vector<uint32_t>& limbs() const { return limbs_; }

  BigInt operator-() const {
    BigInt r = *this;
    if (!r.limbs_.empty()) r.negative_ = !r.negative_;
    return r;
  }

  friend BigInt operator+(const BigInt& a, const BigInt& b) { return add_signed(a, b, false); }
  friend BigInt operator-(const BigInt& a, const BigInt& b) { return add_signed(a, b, true); }

  friend BigInt operator*(const BigInt& a, const BigInt& b) {
    BigInt r;
    if (a.is_zero() || b.is_zero()) return r;
    const size_t na = a.limbs_.size();
    const size_t nb = b.limbs_.size();
    r.limbs_.assign(na + nb, 0u);
    // Raw pointers: the loops stay fast in unoptimised (-O0) test builds too.
    const uint32_t* pa = a.limbs_.data();
    const uint32_t* pb = b.limbs_.data();
    uint32_t* pr = r.limbs_.data();
    for (size_t i = 0; i < na; ++i) {
      uint64_t carry = 0;
      for (size_t j = 0; j < nb; ++j) {
        // (2^32-1)^2 + 2 (2^32-1) < 2^64: no overflow.
        const uint64_t t = static_cast<uint64_t>(pa[i]) * pb[j] + pr[i + j] + carry;
        pr[i + j] = static_cast<uint32_t>(t & 0xffffffffu);
        carry = t >> 32;
      }
      pr[i + nb] = static_cast<uint32_t>(carry);
    }
    r.negative_ = a.negative_ != b.negative_;
    r.normalize();
    return r;
  }

  // this * 2^bits.
  BigInt shifted_left(unsigned bits) const {
    BigInt r;
    if (is_zero()) return r;
    const size_t limb_shift = bits / 32;
    const unsigned bit_shift = bits % 32;
    r.limbs_.assign(limb_shift + limbs_.size() + 1, 0u);
    for (size_t i = 0; i < limbs_.size(); ++i) {
      const uint64_t v = static_cast<uint64_t>(limbs_[i]) << bit_shift;
      r.limbs_[i + limb_shift] |= static_cast<uint32_t>(v & 0xffffffffu);
      r.limbs_[i + limb_shift + 1] |= static_cast<uint32_t>(v >> 32);
    }
    r.negative_ = negative_;
    r.normalize();
    return r;
  }

  // -1, 0, 1 as a <, ==, > b.
  friend int compare(const BigInt& a, const BigInt& b) { return (a - b).sign(); }
  friend bool operator==(const BigInt& a, const BigInt& b) { return compare(a, b) == 0; }
  friend bool operator!=(const BigInt& a, const BigInt& b) { return compare(a, b) != 0; }
  friend bool operator<(const BigInt& a, const BigInt& b) { return compare(a, b) < 0; }

 private:
  // a + b, or a - b when subtract_b.
  static BigInt add_signed(const BigInt& a, const BigInt& b, bool subtract_b) {
    const bool b_negative = subtract_b ? !b.negative_ : b.negative_;
    BigInt r;
    if (a.negative_ == b_negative) {
      r.limbs_ = add_magnitudes(a.limbs_, b.limbs_);
      r.negative_ = a.negative_;
    } else {
      const int c = compare_magnitudes(a.limbs_, b.limbs_);
      if (c == 0) return r;
      if (c > 0) {
        r.limbs_ = subtract_magnitudes(a.limbs_, b.limbs_);
        r.negative_ = a.negative_;
      } else {
        r.limbs_ = subtract_magnitudes(b.limbs_, a.limbs_);
        r.negative_ = b_negative;
      }
    }
    r.normalize();
    return r;
  }
  static int compare_magnitudes(const std::vector<uint32_t>& a, const std::vector<uint32_t>& b) {
    if (a.size() != b.size()) return a.size() < b.size() ? -1 : 1;
    for (size_t i = a.size(); i-- > 0;) {
      if (a[i] != b[i]) return a[i] < b[i] ? -1 : 1;
    }
    return 0;
  }
  static std::vector<uint32_t> add_magnitudes(const std::vector<uint32_t>& a,
                                              const std::vector<uint32_t>& b) {
    const std::vector<uint32_t>& longer = a.size() >= b.size() ? a : b;
    const std::vector<uint32_t>& shorter = a.size() >= b.size() ? b : a;
    const size_t nl = longer.size();
    const size_t ns = shorter.size();
    std::vector<uint32_t> r(nl + 1, 0u);
    const uint32_t* pl = longer.data();
    const uint32_t* ps = shorter.data();
    uint32_t* pr = r.data();
    uint64_t carry = 0;
    for (size_t i = 0; i < nl; ++i) {
      const uint64_t t = static_cast<uint64_t>(pl[i]) + (i < ns ? ps[i] : 0u) + carry;
      pr[i] = static_cast<uint32_t>(t & 0xffffffffu);
      carry = t >> 32;
    }
    pr[nl] = static_cast<uint32_t>(carry);
    return r;
  }
  // a - b for |a| >= |b|.
  static std::vector<uint32_t> subtract_magnitudes(const std::vector<uint32_t>& a,
                                                   const std::vector<uint32_t>& b) {
    const size_t na = a.size();
    const size_t nb = b.size();
    std::vector<uint32_t> r(na, 0u);
    const uint32_t* pa = a.data();
    const uint32_t* pb = b.data();
    uint32_t* pr = r.data();
    uint64_t borrow = 0;
    for (size_t i = 0; i < na; ++i) {
      const uint64_t subtrahend = static_cast<uint64_t>(i < nb ? pb[i] : 0u) + borrow;
      const uint64_t minuend = pa[i];
      if (minuend >= subtrahend) {
        pr[i] = static_cast<uint32_t>(minuend - subtrahend);
        borrow = 0;
      } else {
        pr[i] = static_cast<uint32_t>((minuend + (uint64_t{1} << 32)) - subtrahend);
        borrow = 1;
      }
    }
    return r;  // borrow is 0 here since |a| >= |b|
  }
  // Drops leading zero limbs; zero is never negative.
  void normalize() {
    size_t n = limbs_.size();
    const uint32_t* p = limbs_.data();
    while (n > 0 && p[n - 1] == 0u) --n;
    limbs_.resize(n);
    if (n == 0) negative_ = false;
  }

  bool negative_ = false;
  std::vector<uint32_t> limbs_;
};

// x = mantissa * 2^exponent exactly, for finite x (read from the IEEE 754 bit pattern).
struct DyadicParts {
  int64_t mantissa = 0;
  int exponent = 0;
};

inline DyadicParts decompose(double x) {
  uint64_t bits = 0;
  std::memcpy(&bits, &x, sizeof(bits));
  const bool negative = (bits >> 63) != 0;
  const int biased = static_cast<int>((bits >> 52) & 0x7ffu);
  const uint64_t fraction = bits & ((uint64_t{1} << 52) - 1);
  DyadicParts p;
  if (biased == 0) {  // zero or subnormal: fraction * 2^-1074
    p.mantissa = static_cast<int64_t>(fraction);
    p.exponent = -1074;
  } else {  // normal (callers pass finite values only: biased != 0x7ff)
    p.mantissa = static_cast<int64_t>(fraction | (uint64_t{1} << 52));
    p.exponent = biased - 1075;
  }
  if (negative) p.mantissa = -p.mantissa;
  return p;
}

// The values as integers on one common scale: out[i] * 2^emin == values[i] exactly, emin the
// smallest exponent of the nonzero values.
inline std::vector<BigInt> to_common_scale(const double* values, size_t count) {
  std::vector<DyadicParts> parts(count);
  int emin = 0;
  bool any = false;
  for (size_t i = 0; i < count; ++i) {
    parts[i] = decompose(values[i]);
    if (parts[i].mantissa != 0 && (!any || parts[i].exponent < emin)) {
      emin = parts[i].exponent;
      any = true;
    }
  }
  std::vector<BigInt> out(count);
  for (size_t i = 0; i < count; ++i) {
    const int64_t m = parts[i].mantissa;  // |m| < 2^53
    out[i] = BigInt::from_magnitude(static_cast<uint64_t>(m < 0 ? -m : m),
                                    static_cast<unsigned>(parts[i].exponent - emin), m < 0);
  }
  return out;
}

// Sign of (a - c) x (b - c) = (ax - cx)(by - cy) - (ay - cy)(bx - cx), exactly.
inline int exact_orient2d_sign(double ax, double ay, double bx, double by, double cx, double cy) {
  const double v[6] = {ax, ay, bx, by, cx, cy};
  const std::vector<BigInt> n = to_common_scale(v, 6);
  const BigInt acx = n[0] - n[4];
  const BigInt acy = n[1] - n[5];
  const BigInt bcx = n[2] - n[4];
  const BigInt bcy = n[3] - n[5];
  return (acx * bcy - acy * bcx).sign();
}

// Sign of det[a - d; b - d; c - d], exactly. P is any point type with x, y, z members.
template <class P>
int exact_orient3d_sign(const P& a, const P& b, const P& c, const P& d) {
  const double v[12] = {a.x, a.y, a.z, b.x, b.y, b.z, c.x, c.y, c.z, d.x, d.y, d.z};
  const std::vector<BigInt> n = to_common_scale(v, 12);
  const BigInt adx = n[0] - n[9], ady = n[1] - n[10], adz = n[2] - n[11];
  const BigInt bdx = n[3] - n[9], bdy = n[4] - n[10], bdz = n[5] - n[11];
  const BigInt cdx = n[6] - n[9], cdy = n[7] - n[10], cdz = n[8] - n[11];
  const BigInt det =
      adx * (bdy * cdz - bdz * cdy) - ady * (bdx * cdz - bdz * cdx) + adz * (bdx * cdy - bdy * cdx);
  return det.sign();
}

// True when a, b, c are exactly collinear: (b - a) x (c - a) = 0, i.e. all three
// coordinate-plane projections have zero orientation.
template <class P>
bool exact_collinear3d(const P& a, const P& b, const P& c) {
  return exact_orient2d_sign(a.x, a.y, b.x, b.y, c.x, c.y) == 0 &&
         exact_orient2d_sign(a.y, a.z, b.y, b.z, c.y, c.z) == 0 &&
         exact_orient2d_sign(a.z, a.x, b.z, b.x, c.z, c.x) == 0;
}

// True when s == x + y exactly (no rounding in the double sum).
inline bool exact_sum_is(double x, double y, double s) {
  const double v[3] = {x, y, s};
  const std::vector<BigInt> n = to_common_scale(v, 3);
  return n[0] + n[1] == n[2];
}

}  // namespace splintcore_test

#endif  // SPLINTCORE_TESTS_SUPPORT_EXACT_H
