// Tests of the Boolean's box filter (src/boolean/pair_filter.h): whenever box_beyond() says a
// box lies beyond an edge plane of a triangle, every point of the box that we try (the
// triangle's corners and the box's corners, some of them exactly on the plane) is strictly
// beyond, by the exact orient3d. Random triangles, and boxes 1e-20 .. 1 mm from the plane
// (every third one a single point, which rests on the rounding bound alone); fixed seed, one
// draw per statement. std::pow and sqrt only shape the distances: the assertions hold for any
// values, so a libm that differs by an ulp changes nothing but the counts. Dropping either
// term of the filter's margin makes this test fail (checked by hand when it was written).

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <random>

// Internal to the library.
#include "../../src/boolean/pair_filter.h"
#include "splintcore/geometry.h"

namespace splintcore {
namespace {

double unit(std::mt19937_64& rng) {  // [0, 1)
  const uint64_t bits = rng() >> 11;
  return static_cast<double>(bits) * (1.0 / 9007199254740992.0);
}

double coord(std::mt19937_64& rng, bool as_float) {
  const double u = unit(rng);
  const double v = (u - 0.5) * 100.0;
  return as_float ? static_cast<double>(static_cast<float>(v)) : v;
}

Vec3 point(std::mt19937_64& rng, bool as_float) {
  const double x = coord(rng, as_float);
  const double y = coord(rng, as_float);
  const double z = coord(rng, as_float);
  return Vec3{x, y, z};
}

// The exact side of x for the plane through a, b, c as plane_filter orients it: +1 on the side
// n = (b - a) x (c - a) points to.
int exact_side_of(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& x) {
  return -sign_of(orient3d(a, b, c, x));
}

TEST(BooleanPairFilter, BoxBeyondIsOnlyEverExact) {
  std::mt19937_64 rng(0x5eed5eedULL);
  uint64_t beyond = 0, beyond_close = 0, tried = 0;
  for (int iter = 0; iter < 60000; ++iter) {
    const bool as_float = (iter & 1) == 0;
    const Vec3 p = point(rng, as_float);
    const Vec3 q = point(rng, as_float);
    const Vec3 r = point(rng, as_float);
    const Vec3 n = cross(q - p, r - p);
    const Vec3 pn = p + n;
    const PlaneFilter plane = plane_filter(p, q, pn);
    const int inside = exact_side_of(p, q, pn, r);
    if (inside == 0) continue;
    // A small triangle near the plane: a point on the edge p-q (rounded), pushed off along the
    // plane's normal by 1e-20 .. 1 mm towards either side, and three corners around it.
    const double t = unit(rng);
    const Vec3 on = p + (q - p) * t;
    const double nn = std::sqrt(dot(plane.n, plane.n));
    const double e = unit(rng);
    const double dist = std::pow(10.0, -20.0 + 20.0 * e);
    const double sgn = (rng() & 1) != 0 ? 1.0 : -1.0;
    const Vec3 base = on + plane.n * (sgn * dist / nn);
    // Boxes from much smaller than the distance to 1.5 times it: most lie on one side, many
    // within float32 rounding of the plane (the float32 cases round the corners below).
    // Every third box is a single point (its side then rests on the rounding bound alone).
    const double size = (iter % 3) == 0 ? 0.0 : dist * 1.5 * unit(rng);
    Vec3 corner[3];
    for (Vec3& c : corner) {
      const double dx = (unit(rng) - 0.5) * size;
      const double dy = (unit(rng) - 0.5) * size;
      const double dz = (unit(rng) - 0.5) * size;
      c = base + Vec3{dx, dy, dz};
      if (as_float) {
        c = Vec3{static_cast<double>(static_cast<float>(c.x)),
                 static_cast<double>(static_cast<float>(c.y)),
                 static_cast<double>(static_cast<float>(c.z))};
      }
    }
    if ((iter % 7) == 0) corner[0] = p;  // exactly on the plane: never beyond
    if ((iter % 11) == 0) corner[1] = q;
    Aabb box;
    for (const Vec3& c : corner) box.add(c);
    const Vec3 bc = (box.lo + box.hi) * 0.5;
    const Vec3 ext = box.hi - box.lo;
    ++tried;
    if (!detail::box_beyond(plane, inside, bc, ext)) continue;
    ++beyond;
    if (dist < 1e-6) ++beyond_close;
    for (const Vec3& c : corner) {
      ASSERT_EQ(exact_side_of(p, q, pn, c), -inside) << "iteration " << iter;
    }
    for (int k = 0; k < 8; ++k) {
      const Vec3 x{(k & 1) ? box.hi.x : box.lo.x, (k & 2) ? box.hi.y : box.lo.y,
                   (k & 4) ? box.hi.z : box.lo.z};
      ASSERT_EQ(exact_side_of(p, q, pn, x), -inside) << "iteration " << iter << " box corner " << k;
    }
  }
  std::printf("[   info   ] %llu boxes, %llu beyond (%llu within 1e-6 mm of the plane)\n",
              static_cast<unsigned long long>(tried), static_cast<unsigned long long>(beyond),
              static_cast<unsigned long long>(beyond_close));
  // The filter must also be useful: it answers for a good share of the boxes, also close ones.
  EXPECT_GT(tried, 50000u);
  EXPECT_GT(beyond, tried / 5);
  EXPECT_GT(beyond_close, 1000u);
}

TEST(BooleanPairFilter, FarBoxIsBeyondAndNearOneIsNot) {
  const Vec3 p{0, 0, 0}, q{10, 0, 0}, r{0, 10, 0};
  const Vec3 n = cross(q - p, r - p);  // +z
  const PlaneFilter plane = plane_filter(p, q, p + n);
  // The edge plane is y = 0 with r (y = 10) inside.
  const int inside = -sign_of(orient3d(p, q, p + n, r));
  ASSERT_NE(inside, 0);
  const Vec3 ext{0.5, 0.5, 0.5};
  EXPECT_TRUE(detail::box_beyond(plane, inside, Vec3{5, -1.0, 0}, ext));   // y in [-1.5, -0.5]
  EXPECT_FALSE(detail::box_beyond(plane, inside, Vec3{5, -0.4, 0}, ext));  // reaches y = 0.1
  EXPECT_FALSE(detail::box_beyond(plane, inside, Vec3{5, 3.0, 0}, ext));   // inside
  EXPECT_FALSE(detail::box_beyond(plane, inside, Vec3{5, -0.5, 0}, ext));  // touches y = 0
}

}  // namespace
}  // namespace splintcore
