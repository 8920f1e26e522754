// Brute-force distances (tests only): the test's own point-to-triangle distance, sharing no
// code with the library's distance index, for oracles of decimation and offset surfaces.
#ifndef SPLINTCORE_TESTS_SUPPORT_DISTANCE_ORACLE_H
#define SPLINTCORE_TESTS_SUPPORT_DISTANCE_ORACLE_H

#include <algorithm>
#include <cmath>

#include "splintcore/geometry.h"
#include "splintcore/mesh.h"

namespace splintcore {
namespace test {

// The squared distance from p to the closed triangle abc by brute force (the plane's foot when
// it falls inside, else the nearest of the three sides).
inline double oracle_distance2(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  auto segment2 = [&p](const Vec3& s, const Vec3& e) {
    const Vec3 d = e - s;
    const double len2 = dot(d, d);
    double t = len2 > 0 ? dot(p - s, d) / len2 : 0.0;
    t = std::min(1.0, std::max(0.0, t));
    const Vec3 q = s + d * t;
    return dot(p - q, p - q);
  };
  const Vec3 n = cross(b - a, c - a);
  const double n2 = dot(n, n);
  if (n2 > 0) {
    const double h = dot(p - a, n);
    const Vec3 foot = p - n * (h / n2);
    const bool inside = dot(cross(b - a, foot - a), n) >= 0 &&
                        dot(cross(c - b, foot - b), n) >= 0 && dot(cross(a - c, foot - c), n) >= 0;
    if (inside) return h * h / n2;
  }
  return std::min(segment2(a, b), std::min(segment2(b, c), segment2(c, a)));
}

// The distance from p to mesh m, by brute force over every triangle (boxes prune only
// triangles farther than the best so far).
inline double oracle_distance_to_mesh(const Vec3& p, const Mesh& m) {
  double best2 = HUGE_VAL;
  for (const Triangle& t : m.triangles) {
    const Vec3 &a = m.vertices[t.v[0]], &b = m.vertices[t.v[1]], &c = m.vertices[t.v[2]];
    double box2 = 0;
    for (int k = 0; k < 3; ++k) {
      const double lo = std::min(a[k], std::min(b[k], c[k]));
      const double hi = std::max(a[k], std::max(b[k], c[k]));
      const double d = p[k] < lo ? lo - p[k] : (p[k] > hi ? p[k] - hi : 0.0);
      box2 += d * d;
    }
    if (box2 >= best2) continue;
    best2 = std::min(best2, oracle_distance2(p, a, b, c));
  }
  return std::sqrt(best2);
}

}  // namespace test
}  // namespace splintcore

#endif  // SPLINTCORE_TESTS_SUPPORT_DISTANCE_ORACLE_H
