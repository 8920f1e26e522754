// Float bounds of double values, rounded outward by their bits (no library call, no rounding
// mode): for bounding volumes stored as float that must contain what the doubles gave.
// Internal (src/): used by the distance index and the self-intersection check.
#ifndef SPLINTCORE_SRC_GEOMETRY_FLOAT_BOUNDS_H
#define SPLINTCORE_SRC_GEOMETRY_FLOAT_BOUNDS_H

#include <cmath>
#include <cstdint>
#include <cstring>

namespace splintcore {

// The float next to f towards -infinity (or +infinity), by its bits (finite f only; the
// library call costs more than everything else in the bounds pass).
inline float float_step(float f, bool up) {
  uint32_t bits;
  std::memcpy(&bits, &f, sizeof(bits));
  if ((bits & 0x7fffffffu) == 0) {
    bits = up ? 1u : 0x80000001u;  // the smallest subnormal of the right sign
  } else if (((bits >> 31) == 0) == up) {
    ++bits;  // away from zero
  } else {
    --bits;  // towards zero
  }
  std::memcpy(&f, &bits, sizeof(f));
  return f;
}

// Float bounds that contain the double value: rounded down for lo, up for hi (beyond float
// range: the largest float or infinity, never an out-of-range conversion, which would be
// undefined).
inline float float_down(double x) {
  constexpr double kMax = 3.4028234663852886e38;  // FLT_MAX
  if (x > kMax) return static_cast<float>(kMax);
  if (x < -kMax) return -HUGE_VALF;
  float f = static_cast<float>(x);
  return static_cast<double>(f) > x ? float_step(f, false) : f;
}
inline float float_up(double x) {
  constexpr double kMax = 3.4028234663852886e38;  // FLT_MAX
  if (x > kMax) return HUGE_VALF;
  if (x < -kMax) return static_cast<float>(-kMax);
  float f = static_cast<float>(x);
  return static_cast<double>(f) < x ? float_step(f, true) : f;
}

}  // namespace splintcore

#endif  // SPLINTCORE_SRC_GEOMETRY_FLOAT_BOUNDS_H
