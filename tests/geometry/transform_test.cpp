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
