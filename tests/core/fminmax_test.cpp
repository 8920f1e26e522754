// min_of and max_of (src/core/fminmax.h): for two zeros the second, for a NaN the other value,
// in either order, on every target and at every optimisation level. (std::fmin and std::fmax
// give other zeros on x86-64 at -O0 and at -O2, where GCC may swap their arguments, on AArch64
// and on ARMv7: 2026-12-06, g++ 12 and qemu-user.) The cross-golden job runs this under qemu.
// The values pass through volatiles, so no compiler folds the calls.
#include <cmath>
#include <limits>

#include "core/fminmax.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

volatile double g_plus_zero = 0.0;
volatile double g_minus_zero = -0.0;
volatile double g_nan = std::numeric_limits<double>::quiet_NaN();
volatile double g_one = 1.0;

TEST(DeterministicMinMax, TwoZerosGiveTheSecond) {
  const double pz = g_plus_zero, nz = g_minus_zero;
  EXPECT_FALSE(std::signbit(max_of(nz, pz)));
  EXPECT_TRUE(std::signbit(max_of(pz, nz)));
  EXPECT_FALSE(std::signbit(min_of(nz, pz)));
  EXPECT_TRUE(std::signbit(min_of(pz, nz)));
  EXPECT_TRUE(std::signbit(max_of(nz, nz)));
  EXPECT_FALSE(std::signbit(min_of(pz, pz)));
}

TEST(DeterministicMinMax, NaNGivesTheOther) {
  const double nan = g_nan, one = g_one;
  EXPECT_EQ(max_of(one, nan), 1.0);
  EXPECT_EQ(max_of(nan, one), 1.0);
  EXPECT_EQ(min_of(one, nan), 1.0);
  EXPECT_EQ(min_of(nan, one), 1.0);
  EXPECT_TRUE(std::isnan(max_of(nan, nan)));
  EXPECT_TRUE(std::isnan(min_of(nan, nan)));
}

TEST(DeterministicMinMax, OrderedValuesAsFminFmax) {
  const double one = g_one;
  const double values[] = {-one * 1e308,
                           -2.5 * one,
                           -one * 1e-310,
                           one * 1e-310,
                           3 * one,
                           std::numeric_limits<double>::infinity() * one,
                           -std::numeric_limits<double>::infinity() * one};
  for (double a : values) {
    for (double b : values) {
      EXPECT_EQ(max_of(a, b), a > b ? a : b) << a << " " << b;
      EXPECT_EQ(min_of(a, b), a < b ? a : b) << a << " " << b;
      EXPECT_EQ(max_of(a, b), std::fmax(a, b)) << a << " " << b;
      EXPECT_EQ(min_of(a, b), std::fmin(a, b)) << a << " " << b;
    }
  }
}

}  // namespace
}  // namespace splintcore
