// float_down and float_up (src/geometry/float_bounds.h) against std::nextafter, an oracle that
// shares no code with them: the float next to each double on the right side, bit for bit.
#include <cfloat>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>

#include "geometry/float_bounds.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

uint32_t bits_of(float f) {
  uint32_t b;
  std::memcpy(&b, &f, sizeof(b));
  return b;
}

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr double kMax = static_cast<double>(FLT_MAX);

// The largest float at most x (beyond float range: FLT_MAX above, -infinity below).
float expected_down(double x) {
  if (x > kMax) return FLT_MAX;
  if (x < -kMax) return -kInf;
  const float f = static_cast<float>(x);
  return static_cast<double>(f) > x ? std::nextafter(f, -kInf) : f;
}

// The smallest float at least x.
float expected_up(double x) {
  if (x > kMax) return kInf;
  if (x < -kMax) return -FLT_MAX;
  const float f = static_cast<float>(x);
  return static_cast<double>(f) < x ? std::nextafter(f, kInf) : f;
}

void expect_bounds(double x) {
  ASSERT_EQ(bits_of(float_down(x)), bits_of(expected_down(x))) << "float_down(" << x << ")";
  ASSERT_EQ(bits_of(float_up(x)), bits_of(expected_up(x))) << "float_up(" << x << ")";
  ASSERT_LE(static_cast<double>(float_down(x)), x);
  ASSERT_GE(static_cast<double>(float_up(x)), x);
}

TEST(FloatBounds, TheNextFloatOnEachSideAsNextafterGivesIt) {
  std::mt19937_64 rng(29);
  std::uniform_real_distribution<double> unit(-1, 1);
  for (int i = 0; i < 400000; ++i) {
    // Exponents from below the float subnormals to beyond float range, both signs.
    const double x = std::ldexp(unit(rng), static_cast<int>(rng() % 300) - 160);
    expect_bounds(x);
    // Floats themselves need no step.
    const float f = static_cast<float>(std::ldexp(unit(rng), static_cast<int>(rng() % 200) - 100));
    expect_bounds(static_cast<double>(f));
    ASSERT_EQ(bits_of(float_down(static_cast<double>(f))), bits_of(f));
    ASSERT_EQ(bits_of(float_up(static_cast<double>(f))), bits_of(f));
  }
  for (double x : {0.0, -0.0, 1e-50, -1e-50, 1e-45, -1e-45, 1.0 + 1e-12, -1.0 - 1e-12, kMax, -kMax,
                   1e39, -1e39}) {
    expect_bounds(x);
  }
  // From a zero the step is the smallest subnormal, of the sign the step takes.
  EXPECT_EQ(bits_of(float_down(-1e-50)), 0x80000001u);
  EXPECT_EQ(bits_of(float_up(1e-50)), 0x00000001u);
}

}  // namespace
}  // namespace splintcore
