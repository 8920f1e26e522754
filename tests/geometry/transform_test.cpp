#include "splintcore/geometry.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

TEST(RigidTransform, AcceptsRotationAndComposesWithInverse) {
  // 90 degrees about z, then a translation.
  const double m[16] = {0, -1, 0, 5, 1, 0, 0, -2, 0, 0, 1, 3, 0, 0, 0, 1};
  RigidTransform x;
  SPLINTCORE_ASSERT_OK(rigid_from_matrix(m, 1e-9, &x));
  Vec3 p = x.apply_point(Vec3{1, 0, 0});
  EXPECT_EQ(p, (Vec3{5, -1, 3}));
  RigidTransform id = compose(inverse(x), x);
  Vec3 q = id.apply_point(Vec3{0.25, -7, 2});
  EXPECT_EQ(q, (Vec3{0.25, -7, 2}));
}

TEST(RigidTransform, RejectsScaleShearReflectionAndProjection) {
  RigidTransform x;
  const double scale[16] = {2, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  EXPECT_EQ(rigid_from_matrix(scale, 1e-6, &x).code(), StatusCode::kInvalidArgument);
  const double shear[16] = {1, 0.1, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  EXPECT_EQ(rigid_from_matrix(shear, 1e-6, &x).code(), StatusCode::kInvalidArgument);
  const double mirror[16] = {-1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  Status s = rigid_from_matrix(mirror, 1e-6, &x);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(std::strstr(s.message(), "reflection"), nullptr);
  const double projective[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 1, 1};
  EXPECT_EQ(rigid_from_matrix(projective, 1e-6, &x).code(), StatusCode::kInvalidArgument);
  double nan_matrix[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  nan_matrix[7] = std::nan("");
  s = rigid_from_matrix(nan_matrix, 1e-6, &x);
  EXPECT_EQ(s.code(), StatusCode::kNonFinite);
  EXPECT_EQ(s.index(), 7u);
}

}  // namespace
}  // namespace splintcore

namespace splintcore {
namespace {

TEST(Float32, ExactnessIsDecidedOnTheBits) {
  EXPECT_TRUE(is_float32_exact(0.0));
  EXPECT_TRUE(is_float32_exact(-0.0));
  EXPECT_TRUE(is_float32_exact(1.5));
  EXPECT_TRUE(is_float32_exact(static_cast<double>(0.1f)));
  EXPECT_FALSE(is_float32_exact(0.1));
  EXPECT_TRUE(is_float32_exact(std::ldexp(1.0, -149)));  // the smallest float32 subnormal
  EXPECT_FALSE(is_float32_exact(std::ldexp(1.0, -150)));
  EXPECT_TRUE(is_float32_exact(std::ldexp(3.0, -149)));
  EXPECT_FALSE(is_float32_exact(std::ldexp(3.0, -150)));
  EXPECT_TRUE(is_float32_exact(3.4028234663852886e38));  // FLT_MAX
  EXPECT_FALSE(is_float32_exact(std::ldexp(1.0, 128)));
  EXPECT_FALSE(is_float32_exact(1.0 + std::ldexp(1.0, -24)));
  EXPECT_TRUE(is_float32_exact(1.0 + std::ldexp(1.0, -23)));
  EXPECT_FALSE(is_float32_exact(std::nan("")));
  EXPECT_FALSE(is_float32_exact(HUGE_VAL));
  // Every value round_to_float32 makes is exact, and rounding leaves exact values alone.
  for (double x : {0.1, 1e-40, -7.3, 1234.5678, 3.0e38}) {
    Vec3 v{x, -x, x * 0.5};
    ASSERT_TRUE(round_to_float32(&v));
    EXPECT_TRUE(is_float32_exact(v));
    const Vec3 w = v;
    ASSERT_TRUE(round_to_float32(&v));
    EXPECT_EQ(v, w);
  }
  Vec3 big{4e38, 0, 0};
  EXPECT_FALSE(round_to_float32(&big));
}

}  // namespace
}  // namespace splintcore
