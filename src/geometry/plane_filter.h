// A triangle's plane as a floating-point filter for orient3d-style side tests: one plane, many
// points, most decided without the exact predicate. Internal (src/): used by the
// self-intersection check and the Boolean.
//
// side(x) = n . (x - a) with n = (b - a) x (c - a); `nabs` holds the magnitudes of the two
// terms of each component of n, so nabs . |x - a| is the permanent of det[b - a, c - a, x - a].
// The rounding error of side(x) is below (7 + 56 eps) eps times that permanent (Shewchuk's
// orient3d bound: the same three-term sum of a coordinate difference times a 2 x 2 minor), so a
// value beyond 1e-15 times the permanent has the exact sign. A zero permanent means every term
// has an exactly zero factor: the point is exactly on the plane.
#ifndef SPLINTCORE_SRC_GEOMETRY_PLANE_FILTER_H
#define SPLINTCORE_SRC_GEOMETRY_PLANE_FILTER_H

#include "splintcore/geometry.h"

namespace splintcore {

struct PlaneFilter {
  Vec3 a;
  Vec3 n;
  Vec3 nabs;
};

constexpr double kPlaneFilterBound = 1e-15;

inline PlaneFilter plane_filter(const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 e1 = b - a, e2 = c - a;
  auto m = [](double x) { return x < 0 ? -x : x; };
  PlaneFilter p;
  p.a = a;
  p.n = cross(e1, e2);
  p.nabs = Vec3{m(e1.y * e2.z) + m(e1.z * e2.y), m(e1.z * e2.x) + m(e1.x * e2.z),
                m(e1.x * e2.y) + m(e1.y * e2.x)};
  return p;
}

// +1 above (the side n points to, where a, b, c run counter-clockwise), -1 below, 0 exactly
// on the plane, 2 when the filter cannot tell (ask orient3d).
inline int filtered_side(const PlaneFilter& p, const Vec3& x) {
  const Vec3 d = x - p.a;
  const double side = p.n.x * d.x + p.n.y * d.y + p.n.z * d.z;
  const double permanent = p.nabs.x * (d.x < 0 ? -d.x : d.x) + p.nabs.y * (d.y < 0 ? -d.y : d.y) +
                           p.nabs.z * (d.z < 0 ? -d.z : d.z);
  if (permanent == 0.0) return 0;
  const double bound = kPlaneFilterBound * permanent;
  return side > bound ? 1 : (side < -bound ? -1 : 2);
}

// The exact side: the filter, then orient3d (which is > 0 below the plane).
inline int exact_side(const PlaneFilter& p, const Vec3& b, const Vec3& c, const Vec3& x) {
  const int s = filtered_side(p, x);
  return s != 2 ? s : -sign_of(orient3d(p.a, b, c, x));
}

}  // namespace splintcore

#endif  // SPLINTCORE_SRC_GEOMETRY_PLANE_FILTER_H
