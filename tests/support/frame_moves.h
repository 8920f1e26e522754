// Frame-invariance helpers shared by the tests: random rigid moves from a seeded generator and
// the one-sided Hausdorff distance between two meshes (test code only).
#ifndef SPLINTCORE_TESTS_FRAME_MOVES_H
#define SPLINTCORE_TESTS_FRAME_MOVES_H

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "splintcore/core.h"
#include "splintcore/distance.h"
#include "splintcore/geometry.h"
#include "splintcore/mesh.h"

namespace splintcore {
namespace test {

// A rigid move from a seed: a random rotation (unit quaternion) and a translation of up to
// 100 mm along each axis (a CT or scanner frame).
inline RigidTransform random_move(std::mt19937_64& rng) {
  std::normal_distribution<double> g(0, 1);
  double q[4] = {g(rng), g(rng), g(rng), g(rng)};
  const double l = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  for (double& x : q) x /= l;
  const double w = q[0], x = q[1], y = q[2], z = q[3];
  RigidTransform m;
  m.r[0][0] = 1 - 2 * (y * y + z * z);
  m.r[0][1] = 2 * (x * y - w * z);
  m.r[0][2] = 2 * (x * z + w * y);
  m.r[1][0] = 2 * (x * y + w * z);
  m.r[1][1] = 1 - 2 * (x * x + z * z);
  m.r[1][2] = 2 * (y * z - w * x);
  m.r[2][0] = 2 * (x * z - w * y);
  m.r[2][1] = 2 * (y * z + w * x);
  m.r[2][2] = 1 - 2 * (x * x + y * y);
  std::uniform_real_distribution<double> u(-100, 100);
  m.t = Vec3{u(rng), u(rng), u(rng)};
  return m;
}

// The largest distance from a vertex of `a` to the surface of `b` (one side of Hausdorff; the
// vertices of a fine mesh stand for its surface at the scale asked).
inline double one_sided(const Mesh& a, const Mesh& b, Arena& arena) {
  ArenaScope scope(arena);
  DistanceIndex index;
  EXPECT_TRUE(build_distance_index(Context(&arena), b, DistanceIndexOptions{}, &index).is_ok());
  double worst = 0;
  for (const Vec3& p : a.vertices) {
    ClosestPoint c;
    closest_point(index, p, &c);
    worst = std::max(worst, c.distance);
  }
  return worst;
}

// The mesh moved by x with its vertices rounded to float32, as the design moves a jaw (the
// triangles are the same). A vertex beyond float32 range fails the calling test.
inline Mesh moved_mesh(Arena& arena, const Mesh& mesh, const RigidTransform& x) {
  Mesh m(&arena);
  for (const Vec3& v : mesh.vertices) {
    Vec3 p = x.apply_point(v);
    EXPECT_TRUE(round_to_float32(&p));
    EXPECT_TRUE(m.vertices.push_back(p));
  }
  for (const Triangle& t : mesh.triangles) EXPECT_TRUE(m.triangles.push_back(t));
  return m;
}

}  // namespace test
}  // namespace splintcore

#endif  // SPLINTCORE_TESTS_FRAME_MOVES_H
