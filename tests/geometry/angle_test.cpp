#include <cmath>
#include <random>

#include "splintcore/geometry.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

double ulps(double a, double b) {
  if (a == b) return 0;
  return std::fabs(a - b) / std::ldexp(1.0, std::ilogb(b) - 52);
}

// Against the platform's libm (which the library must not use for output): within a few ulps.
TEST(DeterministicAtan, WithinThreeUlpsOfLibm) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  double worst = 0;
  for (int i = 0; i < 200000; ++i) {
    const double x = std::ldexp(u(rng), static_cast<int>(rng() % 60) - 30);
    worst = std::max(worst, ulps(deterministic_atan(x), std::atan(x)));
  }
  EXPECT_LE(worst, 3.0);
  EXPECT_EQ(deterministic_atan(0.0), 0.0);
  EXPECT_EQ(deterministic_atan(1.0), std::atan(1.0));
  EXPECT_NEAR(deterministic_atan(1e300), 1.5707963267948966, 1e-16);
}

TEST(DeterministicAtan, Atan2QuadrantsAndAngles) {
  std::mt19937_64 rng(8);
  std::uniform_real_distribution<double> u(-5, 5);
  for (int i = 0; i < 100000; ++i) {
    const double y = u(rng), x = u(rng);
    ASSERT_NEAR(deterministic_atan2(y, x), std::atan2(y, x), 8e-16) << y << " " << x;
  }
  EXPECT_EQ(deterministic_atan2(0.0, 0.0), 0.0);
  EXPECT_EQ(deterministic_atan2(1.0, 0.0), std::atan2(1.0, 0.0));
  EXPECT_EQ(deterministic_atan2(0.0, -1.0), std::atan2(0.0, -1.0));
  EXPECT_NEAR(angle_between(Vec3{1, 0, 0}, Vec3{0, 1, 0}), 1.5707963267948966, 1e-16);
  EXPECT_NEAR(angle_between(Vec3{1, 0, 0}, Vec3{-1, 1e-9, 0}), 3.141592653589793 - 1e-9, 1e-15);
  EXPECT_EQ(angle_between(Vec3{}, Vec3{1, 0, 0}), 0.0);
}

// sin and cos against libm: within 2 ulps (or 2^-53 absolute near a zero of the function) for
// |x| up to 100; the exact points; the rotation about an axis against Rodrigues' formula with
// libm, orthonormal, the axis' points fixed.
TEST(DeterministicSinCos, WithinTwoUlpsOfLibm) {
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> u(-1, 1);
  double worst = 0;
  for (int i = 0; i < 200000; ++i) {
    const double x =
        i % 2 == 0 ? 100 * u(rng) : std::ldexp(u(rng), static_cast<int>(rng() % 40) - 38);
    double s = 0, c = 0;
    deterministic_sincos(x, &s, &c);
    const double es = std::sin(x), ec = std::cos(x);
    worst = std::max(worst, std::fabs(es) < 0x1p-4 ? std::fabs(s - es) / 0x1p-57 : ulps(s, es));
    worst = std::max(worst, std::fabs(ec) < 0x1p-4 ? std::fabs(c - ec) / 0x1p-57 : ulps(c, ec));
  }
  EXPECT_LE(worst, 2.0);
  double s = 1, c = 0;
  deterministic_sincos(0.0, &s, &c);
  EXPECT_EQ(s, 0.0);
  EXPECT_EQ(c, 1.0);
  deterministic_sincos(std::nan(""), &s, &c);
  EXPECT_TRUE(std::isnan(s) && std::isnan(c));
  deterministic_sincos(HUGE_VAL, &s, &c);
  EXPECT_TRUE(std::isnan(s) && std::isnan(c));
}

TEST(DeterministicSinCos, RotationAboutAxis) {
  std::mt19937_64 rng(10);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int i = 0; i < 1000; ++i) {
    Vec3 axis{u(rng), u(rng), u(rng)};
    axis = axis * (1.0 / length(axis));
    const Vec3 p{50 * u(rng), 50 * u(rng), 50 * u(rng)};
    const double angle = i % 3 == 0 ? 1e-6 * u(rng) : 3.2 * u(rng);
    const RigidTransform m = rotation_about_axis(p, axis, angle);
    const Vec3 v{50 * u(rng), 50 * u(rng), 50 * u(rng)};
    const Vec3 w = v - p;
    const Vec3 expected = p + w * std::cos(angle) + cross(axis, w) * std::sin(angle) +
                          axis * (dot(axis, w) * (1 - std::cos(angle)));
    const Vec3 got = m.apply_point(v);
    ASSERT_NEAR(got.x, expected.x, 1e-13);
    ASSERT_NEAR(got.y, expected.y, 1e-13);
    ASSERT_NEAR(got.z, expected.z, 1e-13);
    const Vec3 on = m.apply_point(p + axis * 7.0);
    ASSERT_NEAR(length(on - (p + axis * 7.0)), 0.0, 1e-13);
    for (int r = 0; r < 3; ++r) {
      for (int q = 0; q < 3; ++q) {
        const double d = m.r[r][0] * m.r[q][0] + m.r[r][1] * m.r[q][1] + m.r[r][2] * m.r[q][2];
        // (The axis is unit only to rounding: |u|^2 - 1 up to 4e-16, times up to 2 vers.)
        ASSERT_NEAR(d, r == q ? 1.0 : 0.0, 4e-15);
      }
    }
  }
}

}  // namespace
}  // namespace splintcore
