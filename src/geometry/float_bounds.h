// Float bounds of double values, rounded outward by their bits (no library call, no rounding
// mode): for bounding volumes stored as float that must contain what the doubles gave.
// Internal (src/): used by the distance index and the self-intersection check.
#ifndef SPLINTCORE_SRC_GEOMETRY_FLOAT_BOUNDS_H
#define SPLINTCORE_SRC_GEOMETRY_FLOAT_BOUNDS_H

#include <cmath>
#include <cstdint>
#include <cstring>

namespace splintcore {

// f, or with `step` the float next to it towards +infinity (up) or -infinity, by its bits (finite
// f only; the library call costs more than everything else in the bounds pass; from a zero, the
// smallest subnormal of the right sign). Whether the conversion rounded the wrong way is a coin
// toss to the branch predictor: the step is chosen by selects, not branches.
inline float float_step_if(float f, bool step, bool up) {
  uint32_t bits;
  std::memcpy(&bits, &f, sizeof(bits));
  const bool zero = (bits & 0x7fffffffu) == 0;
  const bool away = ((bits >> 31) == 0) == up;
  uint32_t stepped = away ? bits + 1u : bits - 1u;
  stepped = zero ? (up ? 1u : 0x80000001u) : stepped;
  bits ^= (bits ^ stepped) & (0u - static_cast<uint32_t>(step));  // (compilers branch on ?:)
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
  const float f = static_cast<float>(x);
  return float_step_if(f, static_cast<double>(f) > x, false);
}
inline float float_up(double x) {
  constexpr double kMax = 3.4028234663852886e38;  // FLT_MAX
  if (x > kMax) return HUGE_VALF;
  if (x < -kMax) return static_cast<float>(-kMax);
  const float f = static_cast<float>(x);
  return float_step_if(f, static_cast<double>(f) < x, true);
}

}  // namespace splintcore

#endif  // SPLINTCORE_SRC_GEOMETRY_FLOAT_BOUNDS_H
