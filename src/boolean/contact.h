// splintcore boolean, internal: the exact intersection of two closed triangles, described
// combinatorially. The Boolean (points.cpp, split.cpp) splits and classifies the triangles of a
// degenerate (coplanar, edge-on-edge, vertex-on-face) contact with it, so such contacts are
// resolved exactly; nudging A remains only for what rounding to float32 would merge.
//
// Every point of the result is named by the features of the two triangles that define it
// (a corner, the open interior of an edge, the open interior of the face), never by rounded
// coordinates, so the same point found from different triangle pairs gets the same name once
// the caller maps local features to global ids (a vertex id, an edge as its two vertex ids, a
// triangle id). Every decision is the sign of orient3d or orient2d (Shewchuk's exact
// predicates, geometry.h) on the input coordinates, never on a computed point; results are
// therefore exact whenever those predicates are (every nonzero coordinate of magnitude within
// 2^-306 .. 2^338: every float32 STL coordinate and every mm-scale double).
//
// Pure functions: no memory (nothing from any arena, a few hundred bytes of stack), no errors,
// no recursion, deterministic bytes on every compiler and platform (no FMA: -ffp-contract=off).
// Algorithm and sources: contact.cpp.
#ifndef SPLINTCORE_SRC_BOOLEAN_CONTACT_H
#define SPLINTCORE_SRC_BOOLEAN_CONTACT_H

#include "splintcore/core.h"
#include "splintcore/geometry.h"

namespace splintcore {
namespace detail {

// Where a point lies on one triangle (corners 0, 1, 2; edge k runs from corner k to corner
// k + 1 mod 3): a corner, the open interior of an edge, the open interior of the face.
enum class Loc : uint8_t { kV0, kV1, kV2, kE0, kE1, kE2, kFace };

inline bool loc_is_vertex(Loc l) { return l <= Loc::kV2; }
inline bool loc_is_edge(Loc l) { return l >= Loc::kE0 && l <= Loc::kE2; }
// The corner (0..2) of a vertex Loc, or the edge (0..2) of an edge Loc; 3 for kFace.
inline int loc_index(Loc l) {
  const int v = static_cast<int>(l);
  return v < 3 ? v : v - 3;
}
inline Loc vertex_loc(int corner) { return static_cast<Loc>(corner); }
inline Loc edge_loc(int edge) { return static_cast<Loc>(3 + edge); }
// True when the point at `l` lies on the closed edge k (its interior or either end).
inline bool loc_on_closed_edge(Loc l, int k) {
  return l == edge_loc(k) || l == vertex_loc(k) || l == vertex_loc((k + 1) % 3);
}

// A point of the intersection, named by where it lies on A and on B. The pair names it
// uniquely and symbolically:
//   on_a a vertex           -> that corner of A (on_b says where it lies on B);
//   else on_b a vertex      -> that corner of B (on_a says where it lies on A);
//   else edge and edge      -> the crossing of those two edges (their interiors cross at one
//                              point: transversally, never overlapping);
//   else edge of A, face of B -> A's edge through B's plane (the edge is not in that plane);
//   else face of A, edge of B -> B's edge through A's plane.
// (kFace, kFace) never occurs.
struct ContactPoint {
  Loc on_a = Loc::kFace;
  Loc on_b = Loc::kFace;
};
inline bool operator==(const ContactPoint& x, const ContactPoint& y) {
  return x.on_a == y.on_a && x.on_b == y.on_b;
}
inline bool operator!=(const ContactPoint& x, const ContactPoint& y) { return !(x == y); }

enum class ContactKind : uint8_t { kNone, kPoint, kSegment, kPolygon };

struct Contact {
  ContactKind kind = ContactKind::kNone;
  // The two planes are the same plane (exactly). Set whenever they are, kNone included.
  bool coplanar = false;
  // Points in p: 0 (kNone), 1 (kPoint), 2 (kSegment), 3..6 (kPolygon, coplanar only).
  uint8_t count = 0;
  ContactPoint p[6];
  // side_a[i]: the sign of orient3d(b0, b1, b2, a_i): +1 when A's corner i lies below B's
  // plane (on the side opposite to n_b = (b1 - b0) x (b2 - b0): B's inside, for a triangle
  // of an outward-oriented closed mesh), -1 above, 0 on it. side_b likewise for B's corners
  // against A's plane. All 0 when coplanar.
  int8_t side_a[3] = {0, 0, 0};
  int8_t side_b[3] = {0, 0, 0};
};

// The exact intersection of the closed triangles a and b, described in *out (overwritten).
// Reads a[0..2] and b[0..2] only (finite coordinates within the predicates' range, see top;
// outside it the signs may be wrong and an internal consistency check may assert).
// - Not coplanar: kNone, or a point, or a segment on the line where the two planes meet; a
//   segment runs along d = n_a x n_b (n = (v1 - v0) x (v2 - v0)) from p[0] to p[1] (so
//   swapping a and b reverses it).
// - Coplanar: the convex polygon A n B, its vertices counter-clockwise seen from the side n_a
//   points to, starting at the first in the order: A's corners inside B, B's corners inside A,
//   edge crossings (A's edge major); no repeated and no collinear-redundant points. A polygon
//   that degenerates to a segment (A and B touch along part of an edge) is kSegment, directed
//   as A's edge that holds it (A's interior on its left seen from n_a, B's on its right; so
//   swapping a and b reverses it when n_a and n_b point the same way and keeps it when they
//   are opposite); one that degenerates to a point is kPoint.
// Memory: none. Errors: none. Returns false (and *out = kNone) only when a or b is degenerate
// (its corners are collinear, exactly): the caller checks for those first.
bool intersect_triangles(const Vec3 a[3], const Vec3 b[3], Contact* out);

// The coordinates of a contact point of intersect_triangles(a, b), rounded from the exact
// value with the error below. Reads a, b and p; pure, no memory, no errors. The result depends
// only on the geometric features named (the same point named from another pair of triangles
// that share those features gives the same bits, whatever the corner order):
// - a vertex: a bit-for-bit copy of that corner;
// - an edge (u, v) through a triangle's plane: u, v sorted lexicographically (x, then y, then
//   z), the plane's corners sorted likewise (t0 < t1 < t2), n = (t1 - t0) x (t2 - t0),
//   du = n . (u - t0), dv = n . (v - t0), s = du / (du - dv) clamped to [0, 1] (NaN to 0),
//   p = u + (v - u) s (points.cpp's make_point formula). Each coordinate is within
//   32 eps (|t1 - t0| |t2 - t0| (|u - t0| + |v - t0|) |v - u| / |du - dv| + |u| + |v - u|)
//   of the exact point (eps = 2^-53; |.| the Euclidean norm, |u| the largest |coordinate|):
//   small unless the edge is nearly parallel to the plane;
// - two edges crossing: each edge's ends sorted lexicographically and the two edges ordered
//   by their ends; (u, v) the first, (r, w) the second; projected to 2-D by dropping the
//   largest component of (v - u) x (w - r); du = (w - r) x (u - r), dv = (w - r) x (v - r)
//   (2-D cross products), the same s and p. Each coordinate is within
//   32 eps (|w - r| (|u - r| + |v - r|) |v - u| / |du - dv| + |u| + |v - u|) (norms of the
//   projected vectors): small unless the edges cross at a very small angle.
// Precondition (asserted): p is not (kFace, kFace).
Vec3 contact_point_position(const Vec3 a[3], const Vec3 b[3], const ContactPoint& p);

}  // namespace detail
}  // namespace splintcore

#endif  // SPLINTCORE_SRC_BOOLEAN_CONTACT_H
