// atan without libm, so that angle weights (pseudonormals) and solid angles (winding numbers)
// are the same bits on every platform. Range reduction: atan(x) = c + atan((x - tan c) /
// (1 + x tan c)) with c the multiple of 15 degrees nearest atan(x), which leaves |t| <=
// tan(7.5 deg) = 0.1317; there the series t - t^3/3 + t^5/5 - ... needs 10 terms for full
// double precision (0.1317^21 / 21 < 1e-19).
#include "splintcore/geometry.h"

namespace splintcore {

namespace {
// tan(k * 15 degrees), k = 0..5, and k * pi / 12.
constexpr double kTan15[6] = {0.0,
                              0.26794919243112270647,  // 2 - sqrt(3)
                              0.57735026918962576451,  // 1 / sqrt(3)
                              1.0,
                              1.73205080756887729353,  // sqrt(3)
                              3.73205080756887729353};  // 2 + sqrt(3)
constexpr double kAngle15[6] = {0.0, 0.26179938779914943654, 0.52359877559829887308,
                                0.78539816339744830962, 1.04719755119659774615,
                                1.30899693899574718269};
constexpr double kHalfPi = 1.57079632679489661923;
constexpr double kPi = 3.14159265358979323846;
// Midpoints between consecutive multiples: tan(7.5 + 15 k degrees).
constexpr double kSplit[6] = {0.13165249758739585347, 0.41421356237309504880,
                              0.76732698797895999893, 1.30322537284120588734,
                              2.41421356237309504880, 7.59575411272515360661};

double atan_small(double t) {
  const double z = t * t;
  // Horner on t * (1 - z/3 + z^2/5 - ... - z^9/19).
  double sum = -1.0 / 19.0;
  sum = sum * z + 1.0 / 17.0;
  sum = sum * z - 1.0 / 15.0;
  sum = sum * z + 1.0 / 13.0;
  sum = sum * z - 1.0 / 11.0;
  sum = sum * z + 1.0 / 9.0;
  sum = sum * z - 1.0 / 7.0;
  sum = sum * z + 1.0 / 5.0;
  sum = sum * z - 1.0 / 3.0;
  return t + t * (sum * z);
}
}  // namespace

double deterministic_atan(double x) {
  if (x != x) return x;  // NaN
  const bool negative = x < 0.0;
  double a = negative ? -x : x;
  double result;
  if (a > kSplit[5]) {
    // Beyond 82.5 degrees: pi/2 - atan(1/a), with 1/a < 0.1317.
    result = kHalfPi - atan_small(1.0 / a);
  } else {
    int k = 0;
    while (k < 5 && a > kSplit[k]) ++k;
    const double t = k == 0 ? a : (a - kTan15[k]) / (1.0 + a * kTan15[k]);
    result = kAngle15[k] + atan_small(t);
  }
  return negative ? -result : result;
}

double deterministic_atan2(double y, double x) {
  if (y != y || x != x) return y + x;
  if (x == 0.0) {
    if (y > 0.0) return kHalfPi;
    if (y < 0.0) return -kHalfPi;
    return 0.0;
  }
  // atan of the smaller over the larger magnitude keeps the argument in [-1, 1].
  const double ax = x < 0 ? -x : x, ay = y < 0 ? -y : y;
  double r = ay <= ax ? deterministic_atan(ay / ax) : kHalfPi - deterministic_atan(ax / ay);
  if (x < 0.0) r = kPi - r;
  return y < 0.0 ? -r : r;
}

double angle_between(const Vec3& a, const Vec3& b) {
  const double s = length(cross(a, b));
  const double c = dot(a, b);
  if (s == 0.0 && c == 0.0) return 0.0;
  return deterministic_atan2(s, c);
}

}  // namespace splintcore
