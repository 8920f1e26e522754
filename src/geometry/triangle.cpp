// Exact segment-triangle and triangle-triangle intersection tests on closed sets.
//
// Every decision is a sign of orient3d or orient2d (Shewchuk's exact predicates), so there is
// no tolerance anywhere. Non-coplanar case: two triangles meet iff an edge of one meets the
// other (their intersection, if any, is a segment whose ends lie on edges). A segment meets a
// triangle iff its ends are not strictly on one side of the plane and the line through it
// passes inside or on the triangle's boundary (the orient3d signs of pq against the three
// edges agree, zeros allowed). Coplanar cases are projected along an axis that keeps the
// triangle non-degenerate and decided with orient2d (Moller 1997 / Guigue-Devillers 2003 for
// the case analysis; written here from the definitions).
#include "splintcore/geometry.h"

namespace splintcore {

namespace {

struct P2 {
  double x, y;
};

inline P2 drop(const Vec3& v, int axis) {
  return axis == 0 ? P2{v.y, v.z} : (axis == 1 ? P2{v.z, v.x} : P2{v.x, v.y});
}

inline int o2(const P2& a, const P2& b, const P2& c) {
  return sign_of(orient2d(a.x, a.y, b.x, b.y, c.x, c.y));
}

// Separating-axis tests in 2D. Two closed convex polygons are disjoint iff a line through an
// edge of one of them has the other strictly on its outer side (for a segment, its own line
// counts as its edge). Touching leaves no strict separator, so it counts as meeting.

// Is every point of `pts` strictly on the outer side of the edge from a to b of a polygon
// whose orientation sign is `s`?
bool outside_edge(const P2& a, const P2& b, int s, const P2* pts, int n) {
  for (int i = 0; i < n; ++i) {
    if (o2(a, b, pts[i]) * s != -1) return false;
  }
  return true;
}

bool triangles_meet_2d(const P2 t[3], const P2 u[3]) {
  const int st = o2(t[0], t[1], t[2]), su = o2(u[0], u[1], u[2]);
  for (int i = 0; i < 3; ++i) {
    if (outside_edge(t[i], t[(i + 1) % 3], st, u, 3)) return false;
    if (outside_edge(u[i], u[(i + 1) % 3], su, t, 3)) return false;
  }
  return true;
}

bool segment_triangle_2d(const P2& p, const P2& q, const P2& a, const P2& b, const P2& c) {
  const P2 t[3] = {a, b, c};
  const P2 seg[2] = {p, q};
  const int st = o2(a, b, c);
  for (int i = 0; i < 3; ++i) {
    if (outside_edge(t[i], t[(i + 1) % 3], st, seg, 2)) return false;
  }
  // The segment's own line separates when the whole triangle is strictly on one side.
  const int s0 = o2(p, q, a), s1 = o2(p, q, b), s2 = o2(p, q, c);
  if ((s0 > 0 && s1 > 0 && s2 > 0) || (s0 < 0 && s1 < 0 && s2 < 0)) return false;
  // A degenerate segment (p == q) has no line: p must then be inside, which the edge tests
  // above already decided.
  return true;
}

}  // namespace

int projection_axis(const Vec3& a, const Vec3& b, const Vec3& c) {
  // Prefer the axis along which the triangle's normal is largest (best conditioned), but the
  // choice only has to give a non-degenerate projection, which orient2d decides exactly.
  Vec3 n = cross(b - a, c - a);
  double ax = n.x < 0 ? -n.x : n.x, ay = n.y < 0 ? -n.y : n.y, az = n.z < 0 ? -n.z : n.z;
  int order[3] = {2, 0, 1};
  if (ax >= ay && ax >= az) {
    order[0] = 0;
    order[1] = 1;
    order[2] = 2;
  } else if (ay >= az) {
    order[0] = 1;
    order[1] = 2;
    order[2] = 0;
  }
  for (int axis : order) {
    if (o2(drop(a, axis), drop(b, axis), drop(c, axis)) != 0) return axis;
  }
  return -1;
}

bool coplanar_segment_intersects_triangle(const Vec3& p, const Vec3& q, const Vec3& a,
                                          const Vec3& b, const Vec3& c) {
  const int axis = projection_axis(a, b, c);
  if (axis < 0) return false;  // degenerate triangle: not handled here
  return segment_triangle_2d(drop(p, axis), drop(q, axis), drop(a, axis), drop(b, axis),
                             drop(c, axis));
}

bool coplanar_triangles_intersect(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d,
                                  const Vec3& e, const Vec3& f) {
  const int axis = projection_axis(a, b, c);
  if (axis < 0) return false;
  const P2 t1[3] = {drop(a, axis), drop(b, axis), drop(c, axis)};
  const P2 t2[3] = {drop(d, axis), drop(e, axis), drop(f, axis)};
  return triangles_meet_2d(t1, t2);
}

namespace {
// Segment pq against triangle abc, given the exact sides sp and sq of p and q relative to the
// plane of abc (orient3d signs), so that callers who know them do not compute them again.
bool segment_meets(const Vec3& p, const Vec3& q, int sp, int sq, const Vec3& a, const Vec3& b,
                   const Vec3& c) {
  if (sp * sq > 0) return false;  // both strictly on one side
  if (sp == 0 && sq == 0) return coplanar_segment_intersects_triangle(p, q, a, b, c);
  // The segment crosses or touches the plane at one point; it is inside the closed triangle
  // iff the line pq sees the three edges with signs that do not disagree.
  const int s1 = sign_of(orient3d(p, q, a, b));
  const int s2 = sign_of(orient3d(p, q, b, c));
  if (s1 * s2 < 0) return false;
  const int s3 = sign_of(orient3d(p, q, c, a));
  const bool has_pos = s1 > 0 || s2 > 0 || s3 > 0;
  const bool has_neg = s1 < 0 || s2 < 0 || s3 < 0;
  return !(has_pos && has_neg);
}
}  // namespace

bool segment_intersects_triangle(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b,
                                 const Vec3& c) {
  const int sp = sign_of(orient3d(a, b, c, p));
  const int sq = sign_of(orient3d(a, b, c, q));
  return segment_meets(p, q, sp, sq, a, b, c);
}

SegmentCrossing segment_crossing(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b,
                                 const Vec3& c) {
  const int sp = sign_of(orient3d(a, b, c, p));
  const int sq = sign_of(orient3d(a, b, c, q));
  if (sp * sq > 0) return SegmentCrossing::kMisses;  // both strictly on one side
  if (sp == 0 || sq == 0) return SegmentCrossing::kTouches;
  // pq crosses the plane at one point X; the line sees each edge with X's side of it.
  const int s1 = sign_of(orient3d(p, q, a, b));
  const int s2 = sign_of(orient3d(p, q, b, c));
  const int s3 = sign_of(orient3d(p, q, c, a));
  const bool has_pos = s1 > 0 || s2 > 0 || s3 > 0;
  const bool has_neg = s1 < 0 || s2 < 0 || s3 < 0;
  if (has_pos && has_neg) return SegmentCrossing::kMisses;  // X strictly outside an edge
  return s1 != 0 && s2 != 0 && s3 != 0 ? SegmentCrossing::kCrosses : SegmentCrossing::kTouches;
}

bool triangles_intersect(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, const Vec3& e,
                         const Vec3& f) {
  // Quick rejection: def strictly on one side of abc's plane, or abc of def's.
  const int sd = sign_of(orient3d(a, b, c, d));
  const int se = sign_of(orient3d(a, b, c, e));
  const int sf = sign_of(orient3d(a, b, c, f));
  if (sd == se && se == sf && sd != 0) return false;
  const int sa = sign_of(orient3d(d, e, f, a));
  const int sb = sign_of(orient3d(d, e, f, b));
  const int sc = sign_of(orient3d(d, e, f, c));
  if (sa == sb && sb == sc && sa != 0) return false;
  if (sd == 0 && se == 0 && sf == 0) return coplanar_triangles_intersect(a, b, c, d, e, f);
  // Only edges that reach the other plane can meet the other triangle; the sides are known.
  return segment_meets(a, b, sa, sb, d, e, f) || segment_meets(b, c, sb, sc, d, e, f) ||
         segment_meets(c, a, sc, sa, d, e, f) || segment_meets(d, e, sd, se, a, b, c) ||
         segment_meets(e, f, se, sf, a, b, c) || segment_meets(f, d, sf, sd, a, b, c);
}

}  // namespace splintcore
