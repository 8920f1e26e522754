// atan without libm, so that angle weights (pseudonormals) and solid angles (winding numbers)
// are the same bits on every platform. For |x| <= 1: atan(x) = atan(c) + atan((x - c) /
// (1 + x c)) with c = k / 16 the nearest sixteenth, which leaves |t| <= 1/32; there
// t - t^3/3 + t^5/5 - t^7/7 + t^9/9 is exact to double precision (the next term is below
// 1e-16 of t). For |x| > 1, atan(x) = pi/2 - atan(1/x). The table holds atan(k/16) rounded
// to double (fixed literals, so the same everywhere).
//
// sin and cos the same way (Cody and Waite, "Software Manual for the Elementary Functions",
// 1980, ch. 8): x less the nearest multiple k of pi/2, with pi/2 split in two (the first part
// has 33 significant bits, so k times it is exact for |k| < 2^20), leaves |r| <= pi/4; there
// the Taylor series to r^17 (sin) and r^18 (cos) is exact to double precision (the next terms
// are below 2^-60), and k mod 4 picks the quadrant.
#include "splintcore/geometry.h"

namespace splintcore {

namespace {
constexpr double kAtanSixteenths[17] = {0.0,
                                        0.06241880999595735,
                                        0.12435499454676144,
                                        0.18534794999569476,
                                        0.24497866312686414,
                                        0.3028848683749714,
                                        0.35877067027057225,
                                        0.4124104415973873,
                                        0.4636476090008061,
                                        0.5123894603107377,
                                        0.5585993153435624,
                                        0.6022873461349642,
                                        0.6435011087932844,
                                        0.6823165548747481,
                                        0.7188299996216245,
                                        0.7531512809621944,
                                        0.7853981633974483};
constexpr double kHalfPi = 1.57079632679489661923;
constexpr double kPi = 3.14159265358979323846;

// atan(a) for 0 <= a <= 1.
inline double atan_unit(double a) {
  const int k = static_cast<int>(a * 16.0 + 0.5);
  const double c = static_cast<double>(k) * 0.0625;
  const double t = (a - c) / (1.0 + a * c);
  const double z = t * t;
  const double series =
      t + t * z * (-1.0 / 3.0 + z * (1.0 / 5.0 + z * (-1.0 / 7.0 + z * (1.0 / 9.0))));
  return kAtanSixteenths[k] + series;
}
}  // namespace

double deterministic_atan(double x) {
  if (x != x) return x;  // NaN
  const bool negative = x < 0.0;
  const double a = negative ? -x : x;
  const double result = a <= 1.0 ? atan_unit(a) : kHalfPi - atan_unit(1.0 / a);
  return negative ? -result : result;
}

double deterministic_atan2(double y, double x) {
  if (y != y || x != x) return y + x;
  if (x == 0.0) {
    if (y > 0.0) return kHalfPi;
    if (y < 0.0) return -kHalfPi;
    return 0.0;
  }
  // atan of the smaller over the larger magnitude keeps the argument in [0, 1].
  const double ax = x < 0 ? -x : x, ay = y < 0 ? -y : y;
  double r = ay <= ax ? atan_unit(ay / ax) : kHalfPi - atan_unit(ax / ay);
  if (x < 0.0) r = kPi - r;
  return y < 0.0 ? -r : r;
}

namespace {
constexpr double kTwoOverPi = 0.636619772367581343076;
constexpr double kHalfPiHigh = 1.57079632673412561417e+00;  // the first 33 bits of pi/2
constexpr double kHalfPiLow = 6.07710050650619224932e-11;   // pi/2 - kHalfPiHigh

// sin r and cos r for |r| <= pi/4 + a little: Horner in z = r^2, the coefficients 1/n! as
// the compiler rounds the quotients (IEEE division: the same literal everywhere).
inline void sincos_reduced(double r, double* s, double* c) {
  const double z = r * r;
  const double ps =
      -1.0 / 6 +
      z * (1.0 / 120 + z * (-1.0 / 5040 +
                            z * (1.0 / 362880 + z * (-1.0 / 39916800 +
                                                     z * (1.0 / 6227020800.0 +
                                                          z * (-1.0 / 1307674368000.0 +
                                                               z * (1.0 / 355687428096000.0)))))));
  const double pc =
      1.0 / 24 +
      z * (-1.0 / 720 +
           z * (1.0 / 40320 +
                z * (-1.0 / 3628800 +
                     z * (1.0 / 479001600 +
                          z * (-1.0 / 87178291200.0 +
                               z * (1.0 / 20922789888000.0 + z * (-1.0 / 6402373705728000.0)))))));
  *s = r + r * z * ps;
  *c = 1.0 + z * (-0.5 + z * pc);
}
}  // namespace

void deterministic_sincos(double x, double* s, double* c) {
  if (!is_finite(x)) {
    *s = *c = x - x;  // NaN
    return;
  }
  const double q = x * kTwoOverPi;
  // The nearest integer (ties away from zero) without libm's round; far beyond 2^52 every
  // double is an integer already.
  double k = q;
  int64_t quadrant = 0;
  constexpr double kTwo52 = 4503599627370496.0;  // 2^52 (cppcheck misreads hex floats here)
  if (q > -kTwo52 && q < kTwo52) {
    const int64_t ki = static_cast<int64_t>(q + (q >= 0 ? 0.5 : -0.5));
    k = static_cast<double>(ki);
    quadrant = ki & 3;
  }
  const double r = (x - k * kHalfPiHigh) - k * kHalfPiLow;
  double sr = 0, cr = 0;
  sincos_reduced(r, &sr, &cr);
  switch (quadrant) {
    case 0:
      *s = sr;
      *c = cr;
      break;
    case 1:
      *s = cr;
      *c = -sr;
      break;
    case 2:
      *s = -sr;
      *c = -cr;
      break;
    default:
      *s = -cr;
      *c = sr;
      break;
  }
}

double angle_between(const Vec3& a, const Vec3& b) {
  const double s = length(cross(a, b));
  const double c = dot(a, b);
  if (s == 0.0 && c == 0.0) return 0.0;
  return deterministic_atan2(s, c);
}

}  // namespace splintcore
