// The independent undercut check (blockout tests): lines along the direction a jaw leaves
// its splint, cast through both with the distance index's ray queries (not the sweep's code).
#ifndef SPLINTCORE_TESTS_SUPPORT_UNDERCUT_LINES_H
#define SPLINTCORE_TESTS_SUPPORT_UNDERCUT_LINES_H

#include <cmath>
#include <vector>

#include "splintcore/distance.h"
#include "splintcore/mesh.h"

namespace splintcore {
namespace test {

// The independent undercut check: lines parallel to d through a grid of points in the plane
// across d; on each, the parameters where it enters and leaves each solid (ray casting on the
// BVH, a different code path from the sweep). The jaw leaves along +d; splint material beyond
// the jaw's first point along d is in its way. Returns the longest such stretch on any line
// and counts the lines that have one longer than `tolerance`.
struct LockReport {
  double longest = 0;
  size_t locked_lines = 0;
  size_t lines_through_jaw = 0;
  std::vector<Vec3> locked_at;  // a point of each locked line (in the plane through center)
  // With lock_report's `depth_step` > 0, per locked line: how deep its splint lies inside the
  // jaw's sweep across d (lateral_depth below), the largest over samples of its stretches.
  std::vector<double> depth;
};

// Two unit vectors across d (u, v, d right-handed): the plane the lines start from.
inline void axes_across(const Vec3& d, Vec3* u, Vec3* v) {
  Vec3 a = std::fabs(d.x) < 0.9 ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
  a = a - d * dot(a, d);
  *u = a * (1.0 / std::sqrt(dot(a, a)));
  *v = cross(d, *u);
}

inline std::vector<double> crossings(const DistanceIndex& index, const Vec3& origin, const Vec3& d,
                                     double length) {
  std::vector<double> ts;
  double t = 0;
  RayHit hit;
  while (ray_intersect(index, origin + d * t, d, length - t, &hit)) {
    ts.push_back(t + hit.t);
    t += hit.t + 1e-7;
  }
  return ts;
}

// How far across d a point q of a line (origin + t_q d) lies inside the jaw's sweep: the least
// radius r, in steps of `step` up to `most` (returned when nothing frees it), at which one of
// 32 directions across d (u, v) moves q out of the sweep: its line then meets the jaw first
// beyond q, or not at all. An undercut's depth as the splint must flex to pass it, which the
// sampled sweep's inset bounds (the length along d, which lock_report counts, is not: a line
// grazing a wall runs the wall's height inside an inset's sheet).
inline double lateral_depth(const DistanceIndex& jaw, const Vec3& origin, double t_q, const Vec3& d,
                            const Vec3& u, const Vec3& v, double length, double step, double most) {
  for (int i = 1; i * step < most; ++i) {
    const double r = i * step;
    for (int k = 0; k < 32; ++k) {
      const double a = 6.283185307179586 * k / 32;
      const Vec3 w = u * (r * std::cos(a)) + v * (r * std::sin(a));
      RayHit hit;
      if (!ray_intersect(jaw, origin + w, d, length, &hit) || hit.t > t_q) return r;
    }
  }
  return most;
}

// The largest lateral_depth over 8 samples of each stretch of splint beyond the jaw's first
// point (crossings `st`), up to 2 mm.
inline double stretch_depth(const DistanceIndex& jaw, const Vec3& origin, const Vec3& d,
                            const Vec3& u, const Vec3& v, double length,
                            const std::vector<double>& st, double first_jaw, double step) {
  double deepest = 0;
  for (size_t k = 0; k + 1 < st.size(); k += 2) {
    const double lo = std::fmax(st[k], first_jaw), hi = st[k + 1];
    for (int i = 0; hi > lo && i < 8; ++i) {
      const double t = lo + (hi - lo) * (i + 0.5) / 8;
      deepest = std::fmax(deepest, lateral_depth(jaw, origin, t, d, u, v, length, step, 2.0));
    }
  }
  return deepest;
}

inline LockReport lock_report(Arena& arena, const Mesh& splint, const Mesh& jaw, const Vec3& d,
                              const Vec3& u, const Vec3& v, const Vec3& center, double half,
                              uint32_t n, double tolerance, double depth_step = 0) {
  Context ctx(&arena);
  DistanceIndex si, ji;
  EXPECT_TRUE(build_distance_index(ctx, splint, DistanceIndexOptions{}, &si).is_ok());
  EXPECT_TRUE(build_distance_index(ctx, jaw, DistanceIndexOptions{}, &ji).is_ok());
  LockReport r;
  const double reach = 100.0;
  for (uint32_t i = 0; i < n; ++i) {
    for (uint32_t j = 0; j < n; ++j) {
      // Irrational-ish offsets keep lines off the meshes' edges.
      const double a = -half + 2 * half * (i + 0.5 + 0.123 * std::sin(7.1 * i + j)) / n;
      const double b = -half + 2 * half * (j + 0.5 + 0.137 * std::cos(3.3 * j + i)) / n;
      const Vec3 origin = center + u * a + v * b - d * (reach / 2);
      const std::vector<double> jt = crossings(ji, origin, d, reach);
      if (jt.size() < 2) continue;
      ++r.lines_through_jaw;
      const double first_jaw = jt.front();
      const std::vector<double> st = crossings(si, origin, d, reach);
      double beyond = 0;
      for (size_t k = 0; k + 1 < st.size(); k += 2) {
        const double lo = std::fmax(st[k], first_jaw), hi = st[k + 1];
        if (hi > lo) beyond += hi - lo;
      }
      r.longest = std::fmax(r.longest, beyond);
      if (beyond > tolerance) {
        ++r.locked_lines;
        r.locked_at.push_back(center + u * a + v * b);
        if (depth_step > 0)
          r.depth.push_back(stretch_depth(ji, origin, d, u, v, reach, st, first_jaw, depth_step));
      }
    }
  }
  return r;
}

}  // namespace test
}  // namespace splintcore

#endif  // SPLINTCORE_TESTS_SUPPORT_UNDERCUT_LINES_H
