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

}  // namespace
}  // namespace splintcore
