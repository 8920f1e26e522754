// splintcore boolean, internal: a box filter for the Boolean's pair test (src/boolean/
// points.cpp). A triangle of B whose whole bounding box lies strictly beyond one of the
// planes through an edge of a triangle of A (plane_filter(p, q, p + n_A), the side A's third
// corner is not on) cannot meet A, so the pair is rejected before any per-vertex or exact test.
// It is only a filter: it answers "beyond" only when that is exactly true (tested in
// tests/boolean/pair_filter_test.cpp against orient3d), so the Boolean's result is the same
// with or without it.
//
// Source: J. R. Shewchuk, "Adaptive precision floating-point arithmetic and fast robust
// geometric predicates", 1997 (the orient3d error bound that plane_filter.h uses), applied to
// the box centre, plus the exact affine spread of the determinant over the box.
#ifndef SPLINTCORE_SRC_BOOLEAN_PAIR_FILTER_H
#define SPLINTCORE_SRC_BOOLEAN_PAIR_FILTER_H

#include "geometry/plane_filter.h"

namespace splintcore {
namespace detail {

// True when every point x of the box lies strictly on side -inside (inside = +1 or -1) of the
// plane p, exactly: sign(orient3d(p's points, x)) says so for each. c is the box centre as
// computed ((lo + hi) * 0.5, which lies in [lo, hi]), ext >= hi - lo per axis (the computed
// hi - lo), so |x - c| <= ext (up to one rounding) for x in the box.
// Why it is exact: the determinant E(x) is affine in x, E(x) = E(c) + N . (x - c), with
// |E(c) - side(c)| <= 1e-15 perm(c) (plane_filter.h's bound) and |N . (x - c)| <= nabs . ext
// up to a few ulps (nabs bounds |N| componentwise); 2e-15 and 1 + 1e-9 cover those and the
// rounding of this test. Reads p, c and ext only; no memory; never an error.
inline bool box_beyond(const PlaneFilter& p, int inside, const Vec3& c, const Vec3& ext) {
  const Vec3 d = c - p.a;
  const double side = p.n.x * d.x + p.n.y * d.y + p.n.z * d.z;
  const double permanent = p.nabs.x * (d.x < 0 ? -d.x : d.x) + p.nabs.y * (d.y < 0 ? -d.y : d.y) +
                           p.nabs.z * (d.z < 0 ? -d.z : d.z);
  const double reach = p.nabs.x * ext.x + p.nabs.y * ext.y + p.nabs.z * ext.z;
  const double margin = 2e-15 * permanent + (1.0 + 1e-9) * reach;
  return inside > 0 ? side < -margin : side > margin;
}

}  // namespace detail
}  // namespace splintcore

#endif  // SPLINTCORE_SRC_BOOLEAN_PAIR_FILTER_H
