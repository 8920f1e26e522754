// The autorotation's test oracle (test code only): the smallest distance between the maxilla
// and a COPY of the mandible whose vertices were turned about the hinge axis (Rodrigues'
// formula with std::sin and std::cos, a new mesh and a new DistanceIndex per evaluation, the
// pair search with no move: none of the rigid traversal, the deterministic sin/cos or the
// advancement of autorotate_mandible), and the crossing angle by bisection over it.
#ifndef SPLINTCORE_TESTS_AUTOROTATE_ORACLE_H
#define SPLINTCORE_TESTS_AUTOROTATE_ORACLE_H

#include <gtest/gtest.h>

#include <cmath>

#include "splintcore/distance.h"
#include "splintcore/geometry.h"
#include "splintcore/mesh.h"
#include "support/test_util.h"

namespace splintcore {
namespace test {

// v turned by `angle` about the line through p along the unit u.
inline Vec3 rotate_about(const Vec3& v, const Vec3& p, const Vec3& u, double angle) {
  const Vec3 w = v - p;
  const double c = std::cos(angle), s = std::sin(angle);
  return p + w * c + cross(u, w) * s + u * (dot(u, w) * (1 - c));
}

class RotationOracle {
 public:
  RotationOracle(const Mesh& upper, const Mesh& lower, const Vec3& h0, const Vec3& h1,
                 size_t arena_bytes)
      : lower_(lower), p_(h0), store_(arena_bytes) {
    const Vec3 d = h1 - h0;
    u_ = d * (1.0 / length(d));
    options_.pairs_only = true;
    ok_ = build_distance_index(Context(&store_.arena), upper, options_, &upper_index_).is_ok();
    EXPECT_TRUE(ok_);
  }

  // The smallest distance at `angle` (0 when the surfaces meet); NaN on a failure.
  double distance(double angle) {
    if (!ok_) return std::nan("");
    Arena& arena = store_.arena;
    ArenaScope scope(arena);
    const size_t n = lower_.vertices.size();
    Vec3* moved = arena.allocate_array<Vec3>(n);
    if (moved == nullptr) return std::nan("");
    for (size_t i = 0; i < n; ++i) moved[i] = rotate_about(lower_.vertices[i], p_, u_, angle);
    const Mesh copy =
        mesh_view(Span<const Vec3>(moved, n),
                  Span<const Triangle>(lower_.triangles.data(), lower_.triangles.size()));
    DistanceIndex index;
    if (!build_distance_index(Context(&arena), copy, options_, &index).is_ok()) {
      return std::nan("");
    }
    MeshPairDistance d;
    if (!mesh_pair_distance(Context(&arena), upper_index_, index, Vec3{}, HUGE_VAL, &d).is_ok()) {
      return std::nan("");
    }
    ++evaluations;
    return d.distance;
  }

  // Bisection for the crossing of `opening` between `open` (distance > opening there) and
  // `closed` (<= opening), to `tolerance`; NaN when the ends do not bracket it.
  double crossing(double open, double closed, double opening, double tolerance) {
    const double d_open = distance(open), d_closed = distance(closed);
    EXPECT_GT(d_open, opening) << "at the open end " << open;
    EXPECT_LE(d_closed, opening) << "at the closed end " << closed;
    if (!(d_open > opening) || !(d_closed <= opening)) return std::nan("");
    while (std::fabs(closed - open) > tolerance) {
      const double mid = 0.5 * (open + closed);
      (distance(mid) > opening ? open : closed) = mid;
    }
    return 0.5 * (open + closed);
  }

  int evaluations = 0;

 private:
  const Mesh& lower_;
  Vec3 p_, u_;
  TestArena store_;
  DistanceIndexOptions options_;
  DistanceIndex upper_index_;
  bool ok_ = false;
};

}  // namespace test
}  // namespace splintcore

#endif  // SPLINTCORE_TESTS_AUTOROTATE_ORACLE_H
