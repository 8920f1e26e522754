// Boolean operations by corefinement: exact pair tests, symbolic intersection points,
// per-triangle constrained re-triangulation, patch classification, assembly.
//
// Sources: Chen et al. 2016 (EasySplint), "The Boolean operation"; the pair test orders the
// crossing points along the line where the two planes meet by the signs of orient3d of an edge
// of one triangle against an edge of the other, as O. Devillers and P. Guigue, "Faster
// triangle-triangle intersection tests", INRIA RR-4488, 2002 (at most four such signs a pair);
// J. R. Shewchuk's predicates and error bounds (predicates.cpp) for every decision and filter.
// Degenerate pairs (a corner on the other plane, edges meeting exactly, coplanar faces) take
// their exact contact from contact.h and are split and classified by split_general: each side
// of a contact segment against the other mesh's triangles that hold it (a plane, or the wedge
// of two), as in the corefinement of S. Loriot et al. (CGAL, "Polygon Mesh Processing:
// corefinement", coplanar faces kept by orientation), here with every decision an orient3d or
// orient2d on input vertices.
#include "splintcore/boolean.h"

#include "boolean/boolean_internal.h"
#include "boolean/cdt.h"
#include "boolean/contact.h"
#include "boolean/pair_filter.h"
#include "core/union_find.h"
#include "geometry/plane_filter.h"
#include "splintcore/distance.h"

namespace splintcore {

const char* boolean_op_name(BooleanOp op) {
  switch (op) {
    case BooleanOp::kDifference: return "difference";
    case BooleanOp::kUnion: return "union";
    case BooleanOp::kIntersection: return "intersection";
  }
  return "unknown";
}

namespace {

// Ids: a vertex of A is its index, a vertex of B is nva + its index, intersection point p is
// nva + nvb + p. A triangle of A is its index, a triangle of B is nta + its index.
struct Inputs {
  const Mesh* a = nullptr;
  const Mesh* b = nullptr;
  uint32_t nva = 0, nvb = 0, nta = 0, ntb = 0;

  const Vec3& vertex(uint32_t g) const {
    return g < nva ? a->vertices[g] : b->vertices[g - nva];
  }
  void corners(uint32_t tg, uint32_t out[3]) const {
    if (tg < nta) {
      const Triangle& t = a->triangles[tg];
      out[0] = t.v[0]; out[1] = t.v[1]; out[2] = t.v[2];
    } else {
      const Triangle& t = b->triangles[tg - nta];
      out[0] = nva + t.v[0]; out[1] = nva + t.v[1]; out[2] = nva + t.v[2];
    }
  }
};

inline uint64_t edge_key(uint32_t u, uint32_t v) {
  return u < v ? (uint64_t{u} << 32) | v : (uint64_t{v} << 32) | u;
}
inline uint32_t key_lo(uint64_t k) { return static_cast<uint32_t>(k); }
inline uint32_t key_hi(uint64_t k) { return static_cast<uint32_t>(k >> 32); }

// A point where an edge (two vertex ids, smaller first) of one mesh crosses a triangle of the
// other.
struct PointKey {
  uint64_t edge;
  uint32_t tri;
  uint32_t pad;
};

// One crossing pair: the segment runs from `start` to `end` along d = n_a x n_b, the direction
// that has A's inside-B side on its left (seen from A's outside) and B's inside-A side on its
// right (seen from B's outside).
struct Hit {
  uint32_t ta, tb;  // triangle ids (tb already offset by nta)
  PointKey start, end;
};

// A point of a degenerate contact, named by the features that define it (contact.h): an input
// vertex (k1: its id), an edge of one mesh through a triangle of the other (k1: the edge key,
// k2: the triangle id; the same name as a PointKey), or an edge of A crossing an edge of B (k1:
// A's edge key, k2: B's edge key).
enum DegPointKind : uint8_t { kDegVertex, kDegEdgeFace, kDegEdgeEdge };
struct DegPoint {
  uint64_t k1, k2;
  uint8_t kind;
};

// One part of a degenerate contact between triangle `tri` and triangle `other` of the other
// mesh, recorded for `tri`: a lone point (p[1] == p[0]) or a segment. A transversal segment
// (the planes differ) runs from p[0] to p[1] along n_a x n_b, as intersect_triangles gives it;
// a coplanar one (a side of the polygon of overlap, or a touching along edges) has no
// direction that matters. loc_t and loc_o: where each end lies on `tri` and on `other`
// (contact.h's Loc). id: the ends' vertex ids once the points are numbered.
enum DegKind : uint8_t { kDegPointOnly, kDegTransversal, kDegCoplanar };
struct DegRecord {
  DegPoint p[2];
  uint32_t tri, other;
  uint32_t id[2];
  uint8_t loc_t[2], loc_o[2];
  uint8_t kind;
};

// Where a piece of a cut triangle lies against the other solid. The keep rules (keep()) take
// pieces on the other surface (coplanar overlap) by whether the two faces point the same way.
constexpr int8_t kStateNone = 0, kStateIn = 1, kStateOut = -1, kOnSame = 2, kOnOpposite = -2;
// A vertex on the other surface (its state is not passed on by flooding).
constexpr int8_t kVertexOn = 3;

enum class PairResult { kNone, kSegment, kDegenerate };
enum Through { kOut, kIn, kOnBoundary };

// Where the line of an edge that crosses a triangle's plane meets the triangle, from the signs
// x, y of the line against the triangle's two edges that cross the other triangle's plane
// (orient3d of the two edges, each in its own triangle's order). Both points lie on the line
// L where the two planes meet, and the triangle meets L in the interval between its two
// crossing edges, so the third edge's sign is implied (exact arithmetic, neither triangle
// degenerate, no corner on the other plane): the point is inside when x and y agree, outside
// when they differ, and on the boundary (a degenerate contact: edges crossing exactly) when
// one is zero; the same answers as testing it against all three edges.
inline Through through(int x, int y) {
  if (x == 0 || y == 0) return kOnBoundary;
  return x == y ? kIn : kOut;
}

inline int lone(const int s[3]) {
  if (s[0] == s[1]) return 2;
  if (s[0] == s[2]) return 1;
  return 0;
}

// The three planes through A's edges that contain A's normal direction (as filters), each
// with the side A's third corner is on: a triangle strictly beyond one of them cannot meet A; a
// triangle strictly within all three crosses A's plane only inside A.
// For single points the same test is done in 2-D, on the projection along the dominant axis
// of A's normal: the planes through A's edges parallel to that axis separate just as well (the
// third corner's side is found the same way, and A's plane meets the prism they bound in A
// itself), and each side is one 2 x 2 determinant (side2 below).
struct EdgePlanes {
  PlaneFilter plane[3];
  int inside[3];  // side of the third corner: +1 or -1; 0 when the filter could not tell
  // The 2-D edges: coordinates u, v (the axes after the dropped one); per edge its start and
  // its direction (q - p, rounded once), and the third corner's side (0: not certain).
  int u = 0, v = 1;
  double pu[3], pv[3], du[3], dv[3];
  int inside2[3];
};

// The side of the point (x, y) of the projection against edge k of `e`: +1 left, -1 right,
// 2 when the filter cannot tell. The determinant du (y - pv) - dv (x - pu) has the structure of
// Shewchuk's orient2d (differences of inputs, rounded once each, two products and a
// difference), so its rounding error is below (3 + 16 eps) eps (|du (y - pv)| + |dv (x - pu)|)
// (ccwerrboundA, orient2d in predicates.cpp): 1e-15 times that sum leaves room to spare. A zero
// sum is "cannot tell" (a filter, never the final word).
inline int side2(const EdgePlanes& e, int k, double x, double y) {
  const double l = e.du[k] * (y - e.pv[k]);
  const double r = e.dv[k] * (x - e.pu[k]);
  const double det = l - r;
  const double bound = 1e-15 * ((l < 0 ? -l : l) + (r < 0 ? -r : r));
  return det > bound ? 1 : (det < -bound ? -1 : 2);
}

EdgePlanes edge_planes(const Vec3& a0, const Vec3& a1, const Vec3& a2) {
  const Vec3 corner[3] = {a0, a1, a2};
  const Vec3 n = cross(a1 - a0, a2 - a0);
  EdgePlanes e;
  for (int k = 0; k < 3; ++k) {
    const Vec3& p = corner[k];
    const Vec3& q = corner[(k + 1) % 3];
    e.plane[k] = plane_filter(p, q, p + n);
    const int s = filtered_side(e.plane[k], corner[(k + 2) % 3]);
    e.inside[k] = (s == 1 || s == -1) ? s : 0;
  }
  const double ax = n.x < 0 ? -n.x : n.x, ay = n.y < 0 ? -n.y : n.y, az = n.z < 0 ? -n.z : n.z;
  const int w = (ax >= ay && ax >= az) ? 0 : (ay >= az ? 1 : 2);
  e.u = (w + 1) % 3;
  e.v = (w + 2) % 3;
  for (int k = 0; k < 3; ++k) {
    const Vec3& p = corner[k];
    const Vec3& q = corner[(k + 1) % 3];
    e.pu[k] = p[e.u];
    e.pv[k] = p[e.v];
    e.du[k] = q[e.u] - p[e.u];
    e.dv[k] = q[e.v] - p[e.v];
  }
  for (int k = 0; k < 3; ++k) {
    const Vec3& r = corner[(k + 2) % 3];
    const int s = side2(e, k, r[e.u], r[e.v]);
    e.inside2[k] = (s == 1 || s == -1) ? s : 0;
  }
  return e;
}

// pa, pb: the planes of ta and tb as filters (plane_filter of their corners in order); ea:
// ta's edge planes. The caller has tested tb's whole box against ea's planes first
// (detail::box_beyond): a box strictly beyond one means disjoint triangles, which the exact
// tests below would answer kNone too (a cheaper filter first, never a different answer).
PairResult intersect_pair(const Inputs& in, uint32_t ta, uint32_t tb, const PlaneFilter& pa,
                          const EdgePlanes& ea, const PlaneFilter& pb, Hit* hit) {
  uint32_t ga[3], gb[3];
  in.corners(ta, ga);
  in.corners(tb, gb);
  const Vec3 A[3] = {in.vertex(ga[0]), in.vertex(ga[1]), in.vertex(ga[2])};
  const Vec3 B[3] = {in.vertex(gb[0]), in.vertex(gb[1]), in.vertex(gb[2])};
  // sa[i] > 0: A's corner i is below B's plane (on B's inside); sb likewise.
  int sa[3], sb[3];
  for (int j = 0; j < 3; ++j) sb[j] = -exact_side(pa, A[1], A[2], B[j]);
  if (sb[0] == sb[1] && sb[1] == sb[2] && sb[0] != 0) return PairResult::kNone;
  // B beyond one of A's edge prisms (2-D; a filter: only certain answers are used): disjoint,
  // which the exact tests below would answer kNone too.
  const double bu[3] = {B[0][ea.u], B[1][ea.u], B[2][ea.u]};
  const double bv[3] = {B[0][ea.v], B[1][ea.v], B[2][ea.v]};
  for (int k = 0; k < 3; ++k) {
    if (ea.inside2[k] == 0) continue;
    int j = 0;
    while (j < 3 && side2(ea, k, bu[j], bv[j]) == -ea.inside2[k]) ++j;
    if (j == 3) return PairResult::kNone;
  }
  // B strictly within all three of A's edge planes (3-D, the normal's direction: this test
  // decides which pairs take the shortcut below, so it stays the one it always was; a pair it
  // sends to the exact tests instead may find a degenerate contact there).
  bool within = sb[0] != 0 && sb[1] != 0 && sb[2] != 0;
  for (int k = 0; k < 3 && within; ++k) {
    within = ea.inside[k] != 0;
    for (int j = 0; j < 3 && within; ++j) within = filtered_side(ea.plane[k], B[j]) == ea.inside[k];
  }
  const int j0 = lone(sb);
  // B's interval along d_b = n_b x n_a runs from its edge (b_j0, b_j0+1) to (b_j0+2, b_j0) when
  // b_j0 is on A's inside (by symmetry with A's below), so along d it is reversed.
  const uint64_t b_first = edge_key(gb[j0], gb[(j0 + 1) % 3]);
  const uint64_t b_second = edge_key(gb[(j0 + 2) % 3], gb[j0]);
  const uint64_t b_start = sb[j0] > 0 ? b_second : b_first;
  const uint64_t b_end = sb[j0] > 0 ? b_first : b_second;
  if (within) {
    // Both of B's crossings of A's plane lie inside A: the segment is B's whole interval.
    hit->start = PointKey{b_start, ta, 0};
    hit->end = PointKey{b_end, ta, 0};
    hit->ta = ta;
    hit->tb = tb;
    return PairResult::kSegment;
  }
  for (int i = 0; i < 3; ++i) sa[i] = -exact_side(pb, B[1], B[2], A[i]);
  if (sa[0] == sa[1] && sa[1] == sa[2] && sa[0] != 0) return PairResult::kNone;
  if (sa[0] == 0 || sa[1] == 0 || sa[2] == 0 || sb[0] == 0 || sb[1] == 0 || sb[2] == 0) {
    return triangles_intersect(A[0], A[1], A[2], B[0], B[1], B[2]) ? PairResult::kDegenerate
                                                                  : PairResult::kNone;
  }
  const int i0 = lone(sa);
  // A's interval along d = n_a x n_b: from its edge (a_i0, a_i0+1) to its edge (a_i0+2, a_i0)
  // when a_i0 is on the inside of B's plane, the other way round otherwise.
  const uint64_t a_first = edge_key(ga[i0], ga[(i0 + 1) % 3]);
  const uint64_t a_second = edge_key(ga[(i0 + 2) % 3], ga[i0]);
  const uint64_t a_start = sa[i0] > 0 ? a_first : a_second;
  const uint64_t a_end = sa[i0] > 0 ? a_second : a_first;

  // The four crossing edges: A's first (a_i0 -> a_i0+1) and second (a_i0+2 -> a_i0), B's
  // likewise, each in its triangle's order. Every answer below comes from the signs of the
  // four tetrahedra (B edge, A edge), each computed at most once (orient3d is alternating, so
  // the sign of (A edge, B edge) is the same number).
  const int ia[2][2] = {{i0, (i0 + 1) % 3}, {(i0 + 2) % 3, i0}};
  const int jb[2][2] = {{j0, (j0 + 1) % 3}, {(j0 + 2) % 3, j0}};
  int memo[2][2] = {{2, 2}, {2, 2}};  // 2: not computed yet
  auto tet = [&](int fb, int fa) {
    int& m = memo[fb][fa];
    if (m == 2) {
      m = sign_of(orient3d(B[jb[fb][0]], B[jb[fb][1]], A[ia[fa][0]], A[ia[fa][1]]));
    }
    return m;
  };
  const int fa_start = sa[i0] > 0 ? 0 : 1;  // a_start is A's first crossing edge, or its second
  const int fb_start = sb[j0] > 0 ? 1 : 0;
  // Where B's edge fb meets A's plane, against A's triangle; A's edge fa against B's.
  auto through_a = [&](int fb) { return through(tet(fb, 0), tet(fb, 1)); };
  auto through_b = [&](int fa) { return through(tet(0, fa), tet(1, fa)); };
  // The segment is [max(starts), min(ends)]: B's start is the later one exactly when it lies
  // inside A's triangle, else A's start when it lies inside B's; likewise the ends. (B's ends
  // first: B is the small mesh's triangle in the splint case, usually inside A's.)
  bool have_start = false, have_end = false;
  const Through bs = through_a(fb_start);
  if (bs == kOnBoundary) return PairResult::kDegenerate;
  if (bs == kIn) {
    hit->start = PointKey{b_start, ta, 0};
    have_start = true;
  } else {
    const Through as = through_b(fa_start);
    if (as == kOnBoundary) return PairResult::kDegenerate;
    if (as == kIn) {
      hit->start = PointKey{a_start, tb, 0};
      have_start = true;
    }
  }
  const Through be = through_a(1 - fb_start);
  if (be == kOnBoundary) return PairResult::kDegenerate;
  if (be == kIn) {
    hit->end = PointKey{b_end, ta, 0};
    have_end = true;
  } else {
    const Through ae = through_b(1 - fa_start);
    if (ae == kOnBoundary) return PairResult::kDegenerate;
    if (ae == kIn) {
      hit->end = PointKey{a_end, tb, 0};
      have_end = true;
    }
  }
  if (!have_start && !have_end) return PairResult::kNone;
  if (have_start != have_end) return PairResult::kDegenerate;  // cannot happen exactly
  hit->ta = ta;
  hit->tb = tb;
  return PairResult::kSegment;
}

// The plane a cut triangle is re-triangulated in: its projection along the dominant axis of
// its normal, the two remaining coordinates swapped when that keeps it counter-clockwise. The
// split paths (split_triangles, split_general) both use it, so the same triangle projects the
// same way in either.
struct Projection {
  int axis = 2;
  bool flip = false;
};
inline Projection projection_of(const Vec3& p0, const Vec3& p1, const Vec3& p2) {
  const Vec3 nrm = cross(p1 - p0, p2 - p0);
  const double ax = nrm.x < 0 ? -nrm.x : nrm.x, ay = nrm.y < 0 ? -nrm.y : nrm.y,
               az = nrm.z < 0 ? -nrm.z : nrm.z;
  Projection pr;
  pr.axis = (ax >= ay && ax >= az) ? 0 : (ay >= az ? 1 : 2);
  pr.flip = nrm[pr.axis] < 0;
  return pr;
}
inline detail::CdtPoint to_2d(const Vec3& q, const Projection& pr) {
  const double x = q[(pr.axis + 1) % 3], y = q[(pr.axis + 2) % 3];
  return pr.flip ? detail::CdtPoint{y, x} : detail::CdtPoint{x, y};
}

struct Point {
  Vec3 p;
  double s;  // parameter along the edge from its smaller vertex id
  PointKey key;
};

// The exact crossing rounded once: the same key always gives the same bits.
Point make_point(const Inputs& in, const PointKey& key) {
  const Vec3 u = in.vertex(key_hi(key.edge));
  const Vec3 v = in.vertex(key_lo(key.edge));
  uint32_t g[3];
  in.corners(key.tri, g);
  const Vec3 t0 = in.vertex(g[0]);
  const Vec3 n = cross(in.vertex(g[1]) - t0, in.vertex(g[2]) - t0);
  const double du = dot(n, u - t0);
  const double dv = dot(n, v - t0);
  double s = du / (du - dv);
  if (!(s > 0.0)) s = 0.0;
  if (s > 1.0) s = 1.0;
  Point pt;
  pt.p = u + (v - u) * s;
  pt.s = s;
  pt.key = key;
  return pt;
}

// One side of a segment inside one cut triangle, directed so that the other solid's inside is
// on its left, as seen from the triangle's outside.
struct Record {
  uint32_t tri;
  uint32_t from, to;  // point ids
  uint32_t hit;
};

// Stable sort of small KeyIndex arrays (insertion) or large ones (radix).
Status sort_keys(Arena& arena, KeyIndex* items, size_t n) {
  if (n <= 48) {
    for (size_t i = 1; i < n; ++i) {
      const KeyIndex x = items[i];
      size_t j = i;
      while (j > 0 && items[j - 1].key > x.key) {
        items[j] = items[j - 1];
        --j;
      }
      items[j] = x;
    }
    return Status::ok();
  }
  return radix_sort(arena, Span<KeyIndex>(items, n));
}

// A cut triangle's points in the order its re-triangulation takes them: corner 0, edge 0's
// points by position along it, corner 1, edge 1's, corner 2, edge 2's, then the inside ones.
// where(i): the edge (0..2) point i lies on, 3 inside; along(i): its position on that edge;
// id(i): its vertex id. Fills by[n] (temporary), vid[n + 3], local_of[n] (point i's place),
// corner_at[3]; *count = n + 3, *boundary = the corners and edge points.
template <class Where, class Along, class Id>
Status order_points(Arena& arena, size_t n, const uint32_t c[3], Where where, Along along, Id id,
                    KeyIndex* by, uint32_t* vid, uint32_t* local_of, uint32_t corner_at[3],
                    uint32_t* count, uint32_t* boundary) {
  for (size_t i = 0; i < n; ++i) by[i] = KeyIndex{order_key(along(i)), static_cast<uint32_t>(i), 0};
  SPLINTCORE_RETURN_IF_ERROR(sort_keys(arena, by, n));
  for (size_t i = 0; i < n; ++i) by[i].key = where(by[i].index);
  SPLINTCORE_RETURN_IF_ERROR(sort_keys(arena, by, n));
  uint32_t m = 0;
  size_t i = 0;
  for (uint32_t e = 0; e < 3; ++e) {
    corner_at[e] = m;
    vid[m++] = c[e];
    for (; i < n && by[i].key == e; ++i) {
      local_of[by[i].index] = m;
      vid[m++] = id(by[i].index);
    }
  }
  *boundary = m;
  for (; i < n; ++i) {
    local_of[by[i].index] = m;
    vid[m++] = id(by[i].index);
  }
  *count = m;
  return Status::ok();
}

// A piece of a cut triangle.
struct OutTri {
  uint32_t v[3];
  uint32_t src;   // the cut triangle's id
  int8_t state;   // +1 inside the other solid, -1 outside
};

// The broad phase, computed once for all attempts: B's triangles near A's box (with their
// validity checked) and a uniform grid over A's box whose cells list the triangles of A whose
// box and plane meet them (A is the small mesh: the splint base). Everything is widened by
// `reach`, the most a nudge (and its float32 rounding) can move A, so the candidates are a
// superset for every attempt; the exact tests then use A as moved. Its memory stays until the
// Boolean returns (the per-triangle planes of A, about 100 bytes a triangle, included).
struct Broadphase {
  Aabb abox;  // A's bounds widened by reach
  double h = 1, inv_h = 1;
  uint32_t dim[3] = {1, 1, 1};
  uint32_t* start = nullptr;  // cell -> [start[c], start[c + 1]) in items
  uint32_t* items = nullptr;
  uint8_t* near_b = nullptr;  // per B triangle: its box meets abox
  ArenaArray<uint32_t> near_ids;

  void cell_range(const Aabb& box, uint32_t lo[3], uint32_t hi[3]) const {
    for (int k = 0; k < 3; ++k) {
      const double l = (box.lo[k] - abox.lo[k]) * inv_h, u = (box.hi[k] - abox.lo[k]) * inv_h;
      lo[k] = l <= 0.0 ? 0u : (l >= dim[k] - 1.0 ? dim[k] - 1 : static_cast<uint32_t>(l));
      hi[k] = u <= 0.0 ? 0u : (u >= dim[k] - 1.0 ? dim[k] - 1 : static_cast<uint32_t>(u));
    }
  }
};

class BooleanRun {
 public:
  BooleanRun(const Context& ctx, const Inputs& in, const Broadphase& bp,
             const BooleanOptions& options, BooleanStats* stats)
      : ctx_(ctx), arena_(*ctx.arena), in_(in), op_(options.op), options_(options),
        st_(*stats), bp_(bp) {}

  Status run(Mesh* result);

 private:
  Status find_hits();
  Status add_contact(uint32_t ta, uint32_t tb);
  Status number_points();
  Status number_degenerate_points();
  Status check_points_apart();
  Status split_triangles();
  Status split_general(uint32_t t, const KeyIndex* proper, size_t np, const KeyIndex* dk,
                       size_t nd);
  int8_t side_state(uint32_t t, uint32_t r, const uint32_t* sheets, int nsheets) const;
  int8_t on_state(uint32_t t, uint32_t sheet) const;
  uint32_t canon(uint32_t v) const { return (alias_ != nullptr && v >= in_.nva && v < in_.nva + in_.nvb && alias_[v - in_.nva] != ~0u) ? alias_[v - in_.nva] : v; }
  bool keep(int8_t state, bool is_a) const;
  Status resolve_pending();
  int8_t uncut_state(uint32_t t, const uint32_t c[3]) const;
  Status classify();
  Status assemble(Mesh* result);
  Status check_result(Mesh* result);
  Status flood(bool side_a);
  Status degenerate(uint32_t ta, uint32_t tb) const;
  Status inconsistent_vertex(uint32_t v) const;

  const Context& ctx_;
  Arena& arena_;
  Inputs in_;
  BooleanOp op_;
  BooleanOptions options_;
  BooleanStats& st_;

  DistanceIndex index_a_{};             // built when a part of B needs a winding number
  bool have_a_index_ = false;
  const Broadphase& bp_;                // near B triangles and A's grid (all attempts)
  ArenaArray<Hit> hits_;
  uint32_t* hit_points_ = nullptr;      // 2 per hit: start, end point ids
  ArenaArray<Point> points_;
  Record* rec_ = nullptr;               // 2 per hit
  KeyIndex* order_ = nullptr;           // records sorted by triangle
  ArenaArray<OutTri> tris_;             // pieces of cut triangles, by triangle id
  int8_t* vstate_ = nullptr;            // per input vertex: +1 inside the other, -1 outside,
                                        // kVertexOn on the other surface
  // Degenerate contacts, resolved exactly (add_contact): their records, sorted by triangle
  // before the split; B's vertices that coincide with A's (alias_: the A vertex, or ~0u;
  // allocated at the first one); per triangle (nta + ntb): kUncut, kDecided (has constraints),
  // kPending (only lone points: its pieces take their state after flooding), and the state
  // of a triangle whose corners all lie on the other surface (by winding number).
  ArenaArray<DegRecord> deg_;
  uint32_t* alias_ = nullptr;
  uint8_t* tflag_ = nullptr;
  int8_t* tstate_ = nullptr;
  bool pending_ = false;
};

enum TriangleFlag : uint8_t { kUncut = 0, kDecided = 1, kPending = 2 };

Status BooleanRun::degenerate(uint32_t ta, uint32_t tb) const {
  return make_error(StatusCode::kUnsupported,
                    "contact between triangle ", ta, " of A and triangle ", tb - in_.nta,
                    " of B not decided: a coordinate is outside the exact predicates' range "
                    "(0, or 2^-300 .. 2^330 in magnitude)")
      .at_index(ta);
}

// A triangle's plane for a conservative box test: n . x = d, with the slack that covers the
// rounding of n, d and the test itself (generous: it only lets a few more pairs through to the
// exact tests, never fewer).
struct PlaneSlab {
  Vec3 n;
  double d;
  double slack;
};

PlaneSlab slab_of(const Vec3& a, const Vec3& b, const Vec3& c) {
  PlaneSlab p;
  p.n = cross(b - a, c - a);
  p.d = dot(p.n, a);
  const double m = (a.x < 0 ? -a.x : a.x) + (a.y < 0 ? -a.y : a.y) + (a.z < 0 ? -a.z : a.z);
  const double n1 = (p.n.x < 0 ? -p.n.x : p.n.x) + (p.n.y < 0 ? -p.n.y : p.n.y) +
                    (p.n.z < 0 ? -p.n.z : p.n.z);
  p.slack = 1e-9 * n1 * (m + 1.0);
  return p;
}

// Candidate pairs through a uniform grid over A's box: each cell lists the triangles of A
// whose box and plane meet it (A is the small mesh: the splint base). A triangle of B looks
// only at the cells its box covers, so B's many triangles far from A's surface cost a few
// comparisons each.
Status build_broadphase(const Context& ctx, const Mesh& a, const Mesh& b, double reach,
                        bool float32_output, Broadphase* bp) {
  Arena& arena = *ctx.arena;
  const uint32_t nta = static_cast<uint32_t>(a.triangles.size());
  const uint32_t ntb = static_cast<uint32_t>(b.triangles.size());
  const uint32_t nvb = static_cast<uint32_t>(b.vertices.size());
  Aabb abox = mesh_bounds(a);
  abox.lo = abox.lo - Vec3{reach, reach, reach};
  abox.hi = abox.hi + Vec3{reach, reach, reach};
  bp->abox = abox;
  PlaneSlab* slabs = arena.allocate_array<PlaneSlab>(nta);
  Aabb* boxes = arena.allocate_array<Aabb>(nta);
  if (slabs == nullptr || boxes == nullptr) return arena.exhausted_status();
  for (uint32_t t = 0; t < nta; ++t) {
    const Triangle& at = a.triangles[t];
    const Vec3& p0 = a.vertices[at.v[0]];
    const Vec3& p1 = a.vertices[at.v[1]];
    const Vec3& p2 = a.vertices[at.v[2]];
    slabs[t] = slab_of(p0, p1, p2);
    boxes[t] = Aabb{};
    boxes[t].add(p0);
    boxes[t].add(p1);
    boxes[t].add(p2);
    boxes[t].lo = boxes[t].lo - Vec3{reach, reach, reach};
    boxes[t].hi = boxes[t].hi + Vec3{reach, reach, reach};
  }
  // About 16 cells per triangle of A (a power-of-two size, so every platform picks the same
  // grid), cubic cells, at most 256 a side.
  const Vec3 ext = abox.extent();
  const double volume = (ext.x + 1e-9) * (ext.y + 1e-9) * (ext.z + 1e-9);
  const double target = 16.0 * nta + 64.0;
  double h = 1.0;
  while (volume / (h * h * h) > target && h < 1e30) h *= 2.0;
  while (volume / (h * h * h) < target / 8.0 && h > 1e-30) h *= 0.5;
  uint32_t* dim = bp->dim;
  for (int k = 0; k < 3; ++k) {
    double cells = ext[k] / h;
    if (cells > 256.0) h = ext[k] / 256.0;
  }
  for (int k = 0; k < 3; ++k) {
    const double cells = ext[k] / h;
    dim[k] = cells < 1.0 ? 1u : (cells >= 256.0 ? 256u : static_cast<uint32_t>(cells) + 1u);
  }
  bp->h = h;
  const double inv_h = 1.0 / h;
  bp->inv_h = inv_h;
  const size_t cells = size_t{dim[0]} * dim[1] * dim[2];
  uint32_t* start = arena.allocate_array<uint32_t>(cells + 1);
  if (start == nullptr) return arena.exhausted_status();
  std::memset(start, 0, (cells + 1) * sizeof(uint32_t));
  // The cells a triangle's plane passes through within its box, column by column along the
  // plane's dominant axis: in each column of cells the plane spans one interval of that axis
  // (its values at the column's four corners bound it), widened by a hair and by twice the
  // reach (a plane moved by `reach` moves at most sqrt(3) reach along its dominant axis).
  // The plane's value at each grid node is computed once (two rows of nodes at a time, in
  // `row`): a column reads its four corners in the same order, so the cells are the same bits.
  // Pass one stores each column's interval [k0, k1] (a byte each: dim <= 256) in `spans` and
  // counts; pass two replays the intervals; both are temporaries, and the items are moved
  // down over them at the end.
  const Arena::Marker temporaries = arena.mark();
  double* row = arena.allocate_array<double>(2 * 258);
  if (row == nullptr) return arena.exhausted_status();
  ArenaArray<uint8_t> spans(&arena);
  auto axes = [&](uint32_t t, uint32_t lo[3], uint32_t hi[3], int* pw) {
    bp->cell_range(boxes[t], lo, hi);
    const Vec3& n = slabs[t].n;
    const double an[3] = {n.x < 0 ? -n.x : n.x, n.y < 0 ? -n.y : n.y, n.z < 0 ? -n.z : n.z};
    *pw = (an[0] >= an[1] && an[0] >= an[2]) ? 0 : (an[1] >= an[2] ? 1 : 2);
  };
  auto count_cells = [&](uint32_t t) -> bool {
    uint32_t lo[3], hi[3];
    int w = 0;
    axes(t, lo, hi, &w);
    const int u = (w + 1) % 3, v = (w + 2) % 3;
    const Vec3& n = slabs[t].n;
    const double d = slabs[t].d, nu = n[u], nv = n[v], nw = n[w];
    const double lo_u = abox.lo[u], lo_v = abox.lo[v];
    // row[0..]: nodes at u index idx[u], row[258..]: at idx[u] + 1; node j is v index lo[v] + j.
    const uint32_t nodes_v = hi[v] - lo[v] + 2;
    auto fill_row = [&](double* r, uint32_t iu) {
      const double cu = lo_u + iu * h;
      for (uint32_t j = 0; j < nodes_v; ++j) {
        const double cv = lo_v + (lo[v] + j) * h;
        r[j] = (d - nu * cu - nv * cv) / nw;
      }
    };
    double* row0 = row;
    double* row1 = row + 258;
    fill_row(row0, lo[u]);
    uint32_t idx[3];
    for (idx[u] = lo[u]; idx[u] <= hi[u]; ++idx[u]) {
      fill_row(row1, idx[u] + 1);
      for (idx[v] = lo[v]; idx[v] <= hi[v]; ++idx[v]) {
        const uint32_t j = idx[v] - lo[v];
        // Corners in the order (u, v), (u + 1, v), (u, v + 1), (u + 1, v + 1).
        const double c0 = row0[j], c1 = row1[j], c2 = row0[j + 1], c3 = row1[j + 1];
        double wmin = HUGE_VAL, wmax = -HUGE_VAL;
        wmin = c0 < wmin ? c0 : wmin;
        wmax = c0 > wmax ? c0 : wmax;
        wmin = c1 < wmin ? c1 : wmin;
        wmax = c1 > wmax ? c1 : wmax;
        wmin = c2 < wmin ? c2 : wmin;
        wmax = c2 > wmax ? c2 : wmax;
        wmin = c3 < wmin ? c3 : wmin;
        wmax = c3 > wmax ? c3 : wmax;
        const double pad = 1e-9 * ((wmin < 0 ? -wmin : wmin) + (wmax < 0 ? -wmax : wmax) + 1.0) +
                           1e-6 * h + 2.0 * reach;
        const double l = (wmin - pad - abox.lo[w]) * inv_h, r = (wmax + pad - abox.lo[w]) * inv_h;
        uint32_t k0 = l <= 0.0 ? 0u : (l >= dim[w] - 1.0 ? dim[w] - 1 : static_cast<uint32_t>(l));
        uint32_t k1 = r <= 0.0 ? 0u : (r >= dim[w] - 1.0 ? dim[w] - 1 : static_cast<uint32_t>(r));
        if (k0 < lo[w]) k0 = lo[w];
        if (k1 > hi[w]) k1 = hi[w];
        if (!spans.push_back(static_cast<uint8_t>(k0)) ||
            !spans.push_back(static_cast<uint8_t>(k1))) {
          return false;
        }
        for (idx[w] = k0; idx[w] <= k1; ++idx[w]) {
          ++start[(size_t{idx[2]} * dim[1] + idx[1]) * dim[0] + idx[0] + 1];
        }
      }
      double* swap = row0;
      row0 = row1;
      row1 = swap;
    }
    return true;
  };
  for (uint32_t t = 0; t < nta; ++t) {
    if (!count_cells(t)) return arena.exhausted_status();
  }
  for (size_t c = 0; c < cells; ++c) start[c + 1] += start[c];
  const size_t item_count = start[cells];
  uint32_t* items = arena.allocate_array<uint32_t>(item_count);
  if (items == nullptr && item_count > 0) return arena.exhausted_status();
  size_t at = 0;
  for (uint32_t t = 0; t < nta; ++t) {
    uint32_t lo[3], hi[3];
    int w = 0;
    axes(t, lo, hi, &w);
    const int u = (w + 1) % 3, v = (w + 2) % 3;
    uint32_t idx[3];
    for (idx[u] = lo[u]; idx[u] <= hi[u]; ++idx[u]) {
      for (idx[v] = lo[v]; idx[v] <= hi[v]; ++idx[v]) {
        const uint32_t k0 = spans[at], k1 = spans[at + 1];
        at += 2;
        for (idx[w] = k0; idx[w] <= k1; ++idx[w]) {
          items[start[(size_t{idx[2]} * dim[1] + idx[1]) * dim[0] + idx[0]]++] = t;
        }
      }
    }
  }
  // The items down over the temporaries (a lower address: memmove).
  arena.rewind(temporaries);
  uint32_t* kept = arena.allocate_array<uint32_t>(item_count);
  if (kept == nullptr && item_count > 0) return arena.exhausted_status();
  if (item_count > 0) std::memmove(kept, items, item_count * sizeof(uint32_t));
  items = kept;
  for (size_t c = cells; c > 0; --c) start[c] = start[c - 1];
  start[0] = 0;
  bp->start = start;
  bp->items = items;

  SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "boolean: cull", 0, 1));
  // B's vertices against A's box once (6 outcode bits, 64 when not finite); a triangle is near
  // when no side of the box has all three of its corners beyond it.
  uint8_t* outcode = arena.allocate_array<uint8_t>(nvb);
  bp->near_b = arena.allocate_array<uint8_t>(ntb);
  if ((outcode == nullptr && nvb > 0) || (bp->near_b == nullptr && ntb > 0)) {
    return arena.exhausted_status();
  }
  const Vec3* vb = b.vertices.data();
  for (uint32_t v = 0; v < nvb; ++v) {
    const Vec3& p = vb[v];
    outcode[v] = static_cast<uint8_t>(
        (p.x < abox.lo.x ? 1 : 0) | (p.x > abox.hi.x ? 2 : 0) | (p.y < abox.lo.y ? 4 : 0) |
        (p.y > abox.hi.y ? 8 : 0) | (p.z < abox.lo.z ? 16 : 0) | (p.z > abox.hi.z ? 32 : 0) |
        (is_finite(p) ? 0 : 64));
  }
  bp->near_ids.bind(&arena);
  for (uint32_t t = 0; t < ntb; ++t) {
    const Triangle& tri = b.triangles[t];
    if (tri.v[0] >= nvb || tri.v[1] >= nvb || tri.v[2] >= nvb) {
      return make_error(StatusCode::kInvalidMesh, "triangle ", t,
                        " of B refers to a vertex that does not exist")
          .at_index(t);
    }
    const uint32_t o0 = outcode[tri.v[0]], o1 = outcode[tri.v[1]], o2 = outcode[tri.v[2]];
    if (((o0 | o1 | o2) & 64u) != 0) {
      return make_error(StatusCode::kNonFinite, "triangle ", t, " of B has a vertex that is not finite")
          .at_index(t);
    }
    const bool is_near = ((o0 & o1 & o2) & 63u) == 0;
    bp->near_b[t] = is_near ? 1 : 0;
    if (!is_near) continue;
    if (float32_output &&
        !(is_float32_exact(vb[tri.v[0]]) && is_float32_exact(vb[tri.v[1]]) &&
          is_float32_exact(vb[tri.v[2]]))) {
      return b_not_float32(t);
    }
    if (!bp->near_ids.push_back(t)) return arena.exhausted_status();
  }
  return Status::ok();
}

// Candidate pairs through the broad phase's grid; each decided exactly (intersect_pair) with A
// as this attempt has it.
Status BooleanRun::find_hits() {
  const Mesh& b = *in_.b;
  const uint32_t nta = in_.nta;
  const uint32_t nv_in = in_.nva + in_.nvb;
  vstate_ = arena_.allocate_array<int8_t>(nv_in);
  if (vstate_ == nullptr && nv_in > 0) return arena_.exhausted_status();
  if (nv_in > 0) std::memset(vstate_, 0, nv_in);
  PlaneFilter* filters = arena_.allocate_array<PlaneFilter>(nta);
  EdgePlanes* edges = arena_.allocate_array<EdgePlanes>(nta);
  Aabb* boxes = arena_.allocate_array<Aabb>(nta);
  uint32_t* stamp = arena_.allocate_array<uint32_t>(nta);
  if (filters == nullptr || edges == nullptr || boxes == nullptr ||
      stamp == nullptr) {
    return arena_.exhausted_status();
  }
  for (uint32_t t = 0; t < nta; ++t) {
    const Triangle& at = in_.a->triangles[t];
    const Vec3& p0 = in_.a->vertices[at.v[0]];
    const Vec3& p1 = in_.a->vertices[at.v[1]];
    const Vec3& p2 = in_.a->vertices[at.v[2]];
    filters[t] = plane_filter(p0, p1, p2);
    edges[t] = edge_planes(p0, p1, p2);
    boxes[t] = Aabb{};
    boxes[t].add(p0);
    boxes[t].add(p1);
    boxes[t].add(p2);
    stamp[t] = ~0u;
  }
  const uint32_t* dim = bp_.dim;
  const uint32_t* start = bp_.start;
  const uint32_t* items = bp_.items;
  const Vec3* vb = b.vertices.data();
  st_.near_b_triangles = bp_.near_ids.size();
  SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx_, "boolean: hits", 0, 1));
  hits_.bind(&arena_);
  deg_.bind(&arena_);
  for (size_t ni = 0; ni < bp_.near_ids.size(); ++ni) {
    const uint32_t t = bp_.near_ids[ni];
    if ((ni & 65535u) == 0) {
      SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx_, "boolean: hits", ni, bp_.near_ids.size()));
    }
    const Triangle& tri = b.triangles[t];
    Aabb box;
    box.add(vb[tri.v[0]]);
    box.add(vb[tri.v[1]]);
    box.add(vb[tri.v[2]]);
    uint32_t lo[3], hi[3];
    bp_.cell_range(box, lo, hi);
    bool flat_checked = false;
    PlaneFilter pb{};
    const Vec3 bc = (box.lo + box.hi) * 0.5;
    const Vec3 bext = box.hi - box.lo;
    for (uint32_t z = lo[2]; z <= hi[2]; ++z) {
      for (uint32_t y = lo[1]; y <= hi[1]; ++y) {
        for (uint32_t x = lo[0]; x <= hi[0]; ++x) {
          const size_t c = (size_t{z} * dim[1] + y) * dim[0] + x;
          for (uint32_t k = start[c]; k < start[c + 1]; ++k) {
            const uint32_t ta = items[k];
            if (stamp[ta] == t) continue;
            stamp[ta] = t;
            if (!boxes[ta].overlaps(box)) continue;
            ++st_.candidate_pairs;
            if (!flat_checked) {
              if (collinear3d(vb[tri.v[0]], vb[tri.v[1]], vb[tri.v[2]])) {
                return make_error(StatusCode::kInvalidMesh, "triangle ", t,
                                  " of B is degenerate (zero area) and meets A near triangle ", ta)
                    .at_index(t);
              }
              flat_checked = true;
              pb = plane_filter(vb[tri.v[0]], vb[tri.v[1]], vb[tri.v[2]]);
            }
            // B's whole box strictly beyond one of A's edge planes: disjoint, which
            // intersect_pair would answer kNone (tested here: it spares the call for most pairs).
            const EdgePlanes& ea = edges[ta];
            if ((ea.inside[0] != 0 && detail::box_beyond(ea.plane[0], ea.inside[0], bc, bext)) ||
                (ea.inside[1] != 0 && detail::box_beyond(ea.plane[1], ea.inside[1], bc, bext)) ||
                (ea.inside[2] != 0 && detail::box_beyond(ea.plane[2], ea.inside[2], bc, bext))) {
              continue;
            }
            Hit hit;
            const PairResult r = intersect_pair(in_, ta, in_.nta + t, filters[ta], ea, pb, &hit);
            if (r == PairResult::kDegenerate) SPLINTCORE_RETURN_IF_ERROR(add_contact(ta, in_.nta + t));
            if (r == PairResult::kSegment && !hits_.push_back(hit)) {
              return arena_.exhausted_status();
            }
          }
        }
      }
    }
  }
  st_.intersecting_pairs = hits_.size();
  return Status::ok();
}

// A degenerate pair (a corner on the other plane, or edges meeting exactly): its exact contact
// (contact.h) becomes records for both triangles. Input vertices on the other surface are
// marked (kVertexOn); a vertex of B on a vertex of A becomes that vertex (alias_).
Status BooleanRun::add_contact(uint32_t ta, uint32_t tb) {
  using detail::Loc;
  uint32_t ga[3], gb[3];
  in_.corners(ta, ga);
  in_.corners(tb, gb);
  const Vec3 A[3] = {in_.vertex(ga[0]), in_.vertex(ga[1]), in_.vertex(ga[2])};
  const Vec3 B[3] = {in_.vertex(gb[0]), in_.vertex(gb[1]), in_.vertex(gb[2])};
  // The predicates are exact for coordinates 0 or of magnitude 2^-306 .. 2^338 (geometry.h);
  // outside that (subnormal or astronomical coordinates) the contact is not decided here.
  for (int i = 0; i < 3; ++i) {
    for (int k = 0; k < 3; ++k) {
      const double x = A[i][k] < 0 ? -A[i][k] : A[i][k];
      const double y = B[i][k] < 0 ? -B[i][k] : B[i][k];
      if ((x != 0 && (x < 0x1p-300 || x > 0x1p330)) || (y != 0 && (y < 0x1p-300 || y > 0x1p330))) {
        return degenerate(ta, tb);
      }
    }
  }
  detail::Contact c;
  if (!detail::intersect_triangles(A, B, &c)) return degenerate(ta, tb);
  if (c.kind == detail::ContactKind::kNone) return Status::ok();
  ++st_.degenerate_pairs;
  DegPoint name[6];
  for (int i = 0; i < c.count; ++i) {
    const detail::ContactPoint& cp = c.p[i];
    DegPoint d{0, 0, kDegVertex};
    const bool va = detail::loc_is_vertex(cp.on_a), vb = detail::loc_is_vertex(cp.on_b);
    if (va) {
      d.k1 = ga[detail::loc_index(cp.on_a)];
      vstate_[d.k1] = kVertexOn;
      if (vb) {
        const uint32_t bv = gb[detail::loc_index(cp.on_b)];
        vstate_[bv] = kVertexOn;
        if (alias_ == nullptr) {
          alias_ = arena_.allocate_array<uint32_t>(in_.nvb);
          if (alias_ == nullptr) return arena_.exhausted_status();
          std::memset(alias_, 0xff, size_t{in_.nvb} * sizeof(uint32_t));
        }
        uint32_t& al = alias_[bv - in_.nva];
        if (al != ~0u && al != d.k1) {
          return make_error(StatusCode::kUnsupported, "vertex ", bv - in_.nva,
                            " of B lies on two vertices of A (", al, " and ", d.k1,
                            "): A has coincident vertices")
              .at_index(bv - in_.nva);
        }
        al = static_cast<uint32_t>(d.k1);
      }
    } else if (vb) {
      d.k1 = gb[detail::loc_index(cp.on_b)];
      vstate_[d.k1] = kVertexOn;
    } else {
      const int i0 = detail::loc_index(cp.on_a), j0 = detail::loc_index(cp.on_b);
      if (cp.on_b == Loc::kFace) {
        d = DegPoint{edge_key(ga[i0], ga[(i0 + 1) % 3]), tb, kDegEdgeFace};
      } else if (cp.on_a == Loc::kFace) {
        d = DegPoint{edge_key(gb[j0], gb[(j0 + 1) % 3]), ta, kDegEdgeFace};
      } else {
        d = DegPoint{edge_key(ga[i0], ga[(i0 + 1) % 3]), edge_key(gb[j0], gb[(j0 + 1) % 3]),
                     kDegEdgeEdge};
      }
    }
    name[i] = d;
  }
  auto record = [&](int i, int j, uint8_t kind) -> Status {
    const detail::ContactPoint& p = c.p[i];
    const detail::ContactPoint& q = c.p[j];
    DegRecord ra{};
    ra.p[0] = name[i];
    ra.p[1] = name[j];
    ra.tri = ta;
    ra.other = tb;
    ra.kind = kind;
    DegRecord rb = ra;
    rb.tri = tb;
    rb.other = ta;
    ra.loc_t[0] = static_cast<uint8_t>(p.on_a);
    ra.loc_t[1] = static_cast<uint8_t>(q.on_a);
    ra.loc_o[0] = static_cast<uint8_t>(p.on_b);
    ra.loc_o[1] = static_cast<uint8_t>(q.on_b);
    rb.loc_t[0] = ra.loc_o[0];
    rb.loc_t[1] = ra.loc_o[1];
    rb.loc_o[0] = ra.loc_t[0];
    rb.loc_o[1] = ra.loc_t[1];
    // A lone point at a corner of the triangle changes nothing there (flooding treats the
    // corner as on the other surface).
    if (kind != kDegPointOnly || !detail::loc_is_vertex(p.on_a)) {
      if (!deg_.push_back(ra)) return arena_.exhausted_status();
    }
    if (kind != kDegPointOnly || !detail::loc_is_vertex(p.on_b)) {
      if (!deg_.push_back(rb)) return arena_.exhausted_status();
    }
    return Status::ok();
  };
  switch (c.kind) {
    case detail::ContactKind::kPoint:
      return record(0, 0, kDegPointOnly);
    case detail::ContactKind::kSegment:
      return record(0, 1, c.coplanar ? kDegCoplanar : kDegTransversal);
    case detail::ContactKind::kPolygon:
      for (int i = 0; i < c.count; ++i) {
        SPLINTCORE_RETURN_IF_ERROR(record(i, (i + 1) % c.count, kDegCoplanar));
      }
      return Status::ok();
    case detail::ContactKind::kNone:
      break;
  }
  return Status::ok();
}

// The points of the degenerate contacts get vertex ids: an input vertex its own (its alias for
// B), an edge through a triangle the id of the same point of a crossing pair when there is one
// (points_ is sorted by (edge, triangle) here), new points after the others otherwise, in
// (kind, k1, k2) order, each computed once from its name.
Status BooleanRun::number_degenerate_points() {
  const size_t nd = deg_.size();
  if (nd == 0) return Status::ok();
  const uint32_t base = in_.nva + in_.nvb;
  const size_t n0 = points_.size();
  auto find_ef = [&](const DegPoint& d) -> uint32_t {
    size_t lo = 0, hi = n0;
    while (lo < hi) {
      const size_t mid = (lo + hi) / 2;
      const PointKey& k = points_[mid].key;
      if (k.edge < d.k1 || (k.edge == d.k1 && k.tri < d.k2)) lo = mid + 1; else hi = mid;
    }
    return (lo < n0 && points_[lo].key.edge == d.k1 && points_[lo].key.tri == d.k2)
               ? static_cast<uint32_t>(lo) : ~0u;
  };
  if (!points_.reserve(n0 + 2 * nd)) return arena_.exhausted_status();  // before the scope
  ArenaScope scope(arena_);
  // The ends that name new points, sorted (stable radix passes: k2, then k1, then kind).
  KeyIndex* keys = arena_.allocate_array<KeyIndex>(2 * nd);
  if (keys == nullptr) return arena_.exhausted_status();
  size_t m = 0;
  for (size_t r = 0; r < nd; ++r) {
    DegRecord& rec = deg_[r];
    for (int e = 0; e < 2; ++e) {
      const DegPoint& d = rec.p[e];
      if (d.kind == kDegVertex) {
        rec.id[e] = static_cast<uint32_t>(d.k1);
        continue;
      }
      if (d.kind == kDegEdgeFace) {
        const uint32_t f = find_ef(d);
        if (f != ~0u) {
          rec.id[e] = base + f;
          continue;
        }
      }
      rec.id[e] = ~0u;
      keys[m++] = KeyIndex{d.k2, static_cast<uint32_t>(2 * r + static_cast<size_t>(e)), 0};
    }
  }
  auto point_of = [&](uint32_t i) -> const DegPoint& { return deg_[i / 2].p[i % 2]; };
  SPLINTCORE_RETURN_IF_ERROR(sort_keys(arena_, keys, m));
  for (size_t i = 0; i < m; ++i) keys[i].key = point_of(keys[i].index).k1;
  SPLINTCORE_RETURN_IF_ERROR(sort_keys(arena_, keys, m));
  for (size_t i = 0; i < m; ++i) keys[i].key = point_of(keys[i].index).kind;
  SPLINTCORE_RETURN_IF_ERROR(sort_keys(arena_, keys, m));
  uint64_t limit = 0;
  if (!checked_add(uint64_t{base} + n0, m, &limit) || limit >= (uint64_t{1} << 31)) {
    return make_error(StatusCode::kLimitExceeded, "too many vertices for 32-bit ids: ", limit);
  }
  const DegPoint* prev = nullptr;
  for (size_t i = 0; i < m; ++i) {
    const DegPoint& d = point_of(keys[i].index);
    if (prev == nullptr || d.kind != prev->kind || d.k1 != prev->k1 || d.k2 != prev->k2) {
      Point pt;
      pt.s = 0;
      if (d.kind == kDegEdgeFace) {
        pt = make_point(in_, PointKey{d.k1, static_cast<uint32_t>(d.k2), 0});
      } else {
        const Vec3 ea[3] = {in_.vertex(key_hi(d.k1)), in_.vertex(key_lo(d.k1)), Vec3{}};
        const Vec3 eb[3] = {in_.vertex(key_hi(d.k2)), in_.vertex(key_lo(d.k2)), Vec3{}};
        pt.p = detail::contact_point_position(ea, eb, detail::ContactPoint{detail::Loc::kE0, detail::Loc::kE0});
        pt.key = PointKey{d.k1, ~0u, 0};
      }
      if (options_.float32_output && !round_to_float32(&pt.p)) {
        return make_error(StatusCode::kLimitExceeded, "intersection point beyond float32 range");
      }
      if (!points_.push_back(pt)) return arena_.exhausted_status();
    }
    deg_[keys[i].index / 2].id[keys[i].index % 2] = base + static_cast<uint32_t>(points_.size() - 1);
    prev = &d;
  }
  return Status::ok();
}

Status BooleanRun::number_points() {
  const size_t n = hits_.size() * 2;
  KeyIndex* items = arena_.allocate_array<KeyIndex>(n);
  hit_points_ = arena_.allocate_array<uint32_t>(n);
  if ((items == nullptr || hit_points_ == nullptr) && n > 0) return arena_.exhausted_status();
  {
    ArenaScope scope(arena_);
    // Lexicographic (edge, triangle), ties in index order: stably by edge, then each run of
    // one edge (the few triangles its line crosses) stably by triangle, by insertion. The same
    // order as two stable passes (triangle, then edge), which remain for runs longer than 32.
    auto tri_of = [&](uint32_t i) { return (i & 1) == 0 ? hits_[i / 2].start.tri : hits_[i / 2].end.tri; };
    for (size_t i = 0; i < n; ++i) {
      const Hit& h = hits_[i / 2];
      items[i] = KeyIndex{(i & 1) == 0 ? h.start.edge : h.end.edge, static_cast<uint32_t>(i), 0};
    }
    SPLINTCORE_RETURN_IF_ERROR(radix_sort(arena_, Span<KeyIndex>(items, n)));
    bool long_run = false;
    for (size_t a = 0; a < n && !long_run;) {
      size_t b = a + 1;
      while (b < n && items[b].key == items[a].key) ++b;
      if (b - a > 32) long_run = true;
      for (size_t i = a + 1; i < b && !long_run; ++i) {
        const KeyIndex x = items[i];
        const uint32_t tx = tri_of(x.index);
        size_t j = i;
        for (; j > a && tri_of(items[j - 1].index) > tx; --j) items[j] = items[j - 1];
        items[j] = x;
      }
      a = b;
    }
    if (long_run) {
      for (size_t i = 0; i < n; ++i) items[i] = KeyIndex{tri_of(static_cast<uint32_t>(i)), static_cast<uint32_t>(i), 0};
      SPLINTCORE_RETURN_IF_ERROR(radix_sort(arena_, Span<KeyIndex>(items, n)));
      for (size_t i = 0; i < n; ++i) {
        const Hit& h = hits_[items[i].index / 2];
        items[i].key = (items[i].index & 1) == 0 ? h.start.edge : h.end.edge;
      }
      SPLINTCORE_RETURN_IF_ERROR(radix_sort(arena_, Span<KeyIndex>(items, n)));
    }
  }
  // Count distinct points, then make them (the point array is sized exactly).
  size_t distinct = 0;
  const PointKey* prev = nullptr;
  for (size_t i = 0; i < n; ++i) {
    const Hit& h = hits_[items[i].index / 2];
    const PointKey* k = (items[i].index & 1) == 0 ? &h.start : &h.end;
    if (prev == nullptr || k->edge != prev->edge || k->tri != prev->tri) ++distinct;
    prev = k;
  }
  uint64_t limit = 0;
  if (!checked_add(uint64_t{in_.nva} + in_.nvb, distinct, &limit) || limit >= (uint64_t{1} << 31)) {
    return make_error(StatusCode::kLimitExceeded, "too many vertices for 32-bit ids: ", limit);
  }
  points_.bind(&arena_);
  if (!points_.reserve(distinct)) return arena_.exhausted_status();
  prev = nullptr;
  for (size_t i = 0; i < n; ++i) {
    const Hit& h = hits_[items[i].index / 2];
    const PointKey* k = (items[i].index & 1) == 0 ? &h.start : &h.end;
    if (prev == nullptr || k->edge != prev->edge || k->tri != prev->tri) {
      // Rounded to float32 here, before any triangle is re-triangulated, when the result is
      // for STL: the triangulations are then valid for the coordinates the file will hold.
      Point pt = make_point(in_, *k);
      if (options_.float32_output && !round_to_float32(&pt.p)) {
        return make_error(StatusCode::kLimitExceeded, "intersection point beyond float32 range");
      }
      if (!points_.push_back(pt)) return arena_.exhausted_status();
    }
    hit_points_[items[i].index] = static_cast<uint32_t>(points_.size() - 1);
    prev = k;
  }
  return Status::ok();
}

// Two points rounded together would break the triangulations: found here, before any work
// depends on them (the caller then nudges A and tries again).
Status BooleanRun::check_points_apart() {
  st_.intersection_points = points_.size();
  const char* as = options_.float32_output ? " (as float32)" : "";
  // With exact contacts resolved, the result may not be a solid (parts that touch along an
  // edge, points that coincide after rounding): unsupported, so that the nudge takes over.
  // Two points that round together are a near-degeneracy, not a bug: a nudged A (attempts
  // > 1), or in a later pass of several shell groups an A that holds the previous pass's
  // rounded intersection points, meets B within a rounding error. The next nudge runs.
  const StatusCode fragile = StatusCode::kUnsupported;
  ArenaScope scope(arena_);
  const uint32_t np = static_cast<uint32_t>(points_.size());
  if (np > 1) {
    KeyIndex* keys = arena_.allocate_array<KeyIndex>(np);
    if (keys == nullptr) return arena_.exhausted_status();
    // First a cheaper look: sorted by x alone, equal points share a run of equal x; runs are
    // a handful of points. Only when it finds a pair (or a run too long to compare pairwise)
    // does the full lexicographic sort below run, so the pair named is the same as always.
    for (uint32_t i = 0; i < np; ++i) keys[i] = KeyIndex{order_key(points_[i].p.x + 0.0), i, 0};
    SPLINTCORE_RETURN_IF_ERROR(radix_sort(arena_, Span<KeyIndex>(keys, np)));
    bool maybe = false;
    for (uint32_t i = 0; i < np && !maybe;) {
      uint32_t j = i + 1;
      while (j < np && keys[j].key == keys[i].key) ++j;
      if (j - i > 16) maybe = true;
      for (uint32_t x = i; x < j && !maybe; ++x) {
        for (uint32_t y = x + 1; y < j; ++y) {
          if (points_[keys[x].index].p == points_[keys[y].index].p) maybe = true;
        }
      }
      i = j;
    }
    if (!maybe) return Status::ok();
    for (int axis = 2; axis >= 0; --axis) {
      for (uint32_t i = 0; i < np; ++i) {
        const uint32_t id = axis == 2 ? i : keys[i].index;
        keys[i] = KeyIndex{order_key(points_[id].p[axis] + 0.0), id, 0};
      }
      SPLINTCORE_RETURN_IF_ERROR(radix_sort(arena_, Span<KeyIndex>(keys, np)));
    }
    for (uint32_t i = 1; i < np; ++i) {
      if (points_[keys[i].index].p == points_[keys[i - 1].index].p) {
        // Named by what defines them: an edge (two vertex ids) of one mesh through a triangle
        // of the other, or through an edge of the other.
        auto named = [&](Status& st, const PointKey& k) {
          const uint32_t u = key_hi(k.edge), v = key_lo(k.edge);
          const bool of_a = u < in_.nva;
          st.append("edge ").append_u64(of_a ? u : u - in_.nva).append("-");
          st.append_u64(of_a ? v : v - in_.nva).append(of_a ? " of A" : " of B");
          if (k.tri == ~0u) {
            st.append(" across an edge of B");
          } else {
            const bool tri_a = k.tri < in_.nta;
            st.append(" through triangle ").append_u64(tri_a ? k.tri : k.tri - in_.nta);
            st.append(tri_a ? " of A" : " of B");
          }
        };
        Status e = make_error(fragile, "intersection points ", keys[i - 1].index, " and ",
                              keys[i].index, " coincide", as, ": ");
        named(e, points_[keys[i - 1].index].key);
        e.append(" and ");
        named(e, points_[keys[i].index].key);
        const uint32_t t = points_[keys[i].index].key.tri;
        return t == ~0u ? e : e.at_index(t < in_.nta ? t : t - in_.nta);
      }
    }
  }
  return Status::ok();
}

// Where the half-plane of triangle t beyond a contact line, on the side of t's corner r (off
// the line), lies against the other solid: inside, outside, or on its surface (then whether
// the faces point the same way). `sheets`: the other mesh's triangles that hold the line (one:
// the line crosses its interior; two: the line lies along their shared edge, a wedge, convex
// or reflex). Decided by orient3d on input vertices only. kStateNone when the configuration is
// not one of these (the caller reports it).
int8_t BooleanRun::side_state(uint32_t t, uint32_t r, const uint32_t* sheets, int nsheets) const {
  const Vec3 p = in_.vertex(r);
  uint32_t s1[3];
  in_.corners(sheets[0], s1);
  const Vec3 a0 = in_.vertex(s1[0]), a1 = in_.vertex(s1[1]), a2 = in_.vertex(s1[2]);
  const int o1 = sign_of(orient3d(a0, a1, a2, p));  // +1: below s1's plane (the inside side)
  if (nsheets == 1) return o1 > 0 ? kStateIn : (o1 < 0 ? kStateOut : on_state(t, sheets[0]));
  if (nsheets != 2) return kStateNone;
  uint32_t s2[3];
  in_.corners(sheets[1], s2);
  // The apexes: the corner of each sheet that the other does not share (exactly one each).
  int apex1 = -1, apex2 = -1, shared = 0;
  for (int i = 0; i < 3; ++i) {
    const bool in2 = s1[i] == s2[0] || s1[i] == s2[1] || s1[i] == s2[2];
    const bool in1 = s2[i] == s1[0] || s2[i] == s1[1] || s2[i] == s1[2];
    if (!in2) apex1 = i;
    if (!in1) apex2 = i;
    shared += in2 ? 1 : 0;
  }
  if (shared != 2 || apex1 < 0 || apex2 < 0) return kStateNone;
  const Vec3 b0 = in_.vertex(s2[0]), b1 = in_.vertex(s2[1]), b2 = in_.vertex(s2[2]);
  const Vec3 c1 = in_.vertex(s1[apex1]), c2 = in_.vertex(s2[apex2]);
  const int convex = sign_of(orient3d(a0, a1, a2, c2));  // +1 convex edge, -1 reflex, 0 flat
  const int o2 = sign_of(orient3d(b0, b1, b2, p));
  if (convex == 0) return o1 > 0 ? kStateIn : (o1 < 0 ? kStateOut : on_state(t, sheets[0]));
  if (o1 == 0) {  // in s1's plane: on s1 itself, or on its continuation beyond the edge
    if (o2 == sign_of(orient3d(b0, b1, b2, c1))) return on_state(t, sheets[0]);
    return convex > 0 ? kStateOut : kStateIn;
  }
  if (o2 == 0) {
    if (o1 == convex) return on_state(t, sheets[1]);
    return convex > 0 ? kStateOut : kStateIn;
  }
  if (convex > 0) return (o1 > 0 && o2 > 0) ? kStateIn : kStateOut;
  return (o1 > 0 || o2 > 0) ? kStateIn : kStateOut;
}

// Triangle t and `sheet` lie in one plane: do they face the same way? (orient2d of both on a
// projection that keeps t proper, so it keeps the sheet proper too.)
int8_t BooleanRun::on_state(uint32_t t, uint32_t sheet) const {
  uint32_t g[3], h[3];
  in_.corners(t, g);
  in_.corners(sheet, h);
  const Vec3 p0 = in_.vertex(g[0]), p1 = in_.vertex(g[1]), p2 = in_.vertex(g[2]);
  const int w = projection_axis(p0, p1, p2);
  if (w < 0) return kStateNone;
  const int u = (w + 1) % 3, v = (w + 2) % 3;
  const Vec3 q0 = in_.vertex(h[0]), q1 = in_.vertex(h[1]), q2 = in_.vertex(h[2]);
  const int st = sign_of(orient2d(p0[u], p0[v], p1[u], p1[v], p2[u], p2[v]));
  const int ss = sign_of(orient2d(q0[u], q0[v], q1[u], q1[v], q2[u], q2[v]));
  if (st == 0 || ss == 0) return kStateNone;
  return st == ss ? kOnSame : kOnOpposite;
}

bool BooleanRun::keep(int8_t state, bool is_a) const {
  switch (state) {
    case kStateIn: return is_a ? op_ == BooleanOp::kIntersection : op_ != BooleanOp::kUnion;
    case kStateOut: return is_a ? op_ != BooleanOp::kIntersection : op_ == BooleanOp::kUnion;
    case kOnSame: return is_a && op_ != BooleanOp::kDifference;
    case kOnOpposite: return is_a && op_ == BooleanOp::kDifference;
    default: return false;
  }
}

// A cut triangle with degenerate contacts (besides any crossing segments): its points may be
// input vertices of the other mesh, on its edges or inside; its constraints may lie along its
// own edges; each side of a constraint has its own state (side_state), inside, outside or on
// the other surface. A triangle with lone points only is split as well, its pieces pending
// (their state comes from its corners after flooding).
Status BooleanRun::split_general(uint32_t t, const KeyIndex* proper, size_t np,
                                 const KeyIndex* dk, size_t nd) {
  using detail::Loc;
  ArenaScope scope(arena_);
  const uint32_t base = in_.nva + in_.nvb;
  const bool is_a = t < in_.nta;
  const uint32_t tn = is_a ? t : t - in_.nta;
  const char* which = is_a ? " of A" : " of B";
  auto unsupported = [&](const char* what) {
    return make_error(StatusCode::kUnsupported, "cannot split triangle ", tn, which,
                      " along its exact contacts: ", what)
        .at_index(tn);
  };
  uint32_t raw[3], c[3];
  in_.corners(t, raw);
  for (int k = 0; k < 3; ++k) c[k] = canon(raw[k]);
  const Vec3 cv[3] = {in_.vertex(raw[0]), in_.vertex(raw[1]), in_.vertex(raw[2])};
  auto coords = [&](uint32_t id) -> const Vec3& { return id < base ? in_.vertex(id) : points_[id - base].p; };
  // 1. The points: id, where (edge 0..2, 3 inside), position along the edge.
  struct GPoint {
    uint32_t id, where;
    double along;
  };
  const size_t cap = 2 * np + 2 * nd;
  GPoint* gp = arena_.allocate_array<GPoint>(cap);
  KeyIndex* ids = arena_.allocate_array<KeyIndex>(cap);
  if (gp == nullptr || ids == nullptr) return arena_.exhausted_status();
  size_t n = 0;
  auto along_edge = [&](int k, const Vec3& p) {
    const Vec3 d = cv[(k + 1) % 3] - cv[k];
    const double ax = d.x < 0 ? -d.x : d.x, ay = d.y < 0 ? -d.y : d.y, az = d.z < 0 ? -d.z : d.z;
    const int w = (ax >= ay && ax >= az) ? 0 : (ay >= az ? 1 : 2);
    return d[w] > 0 ? p[w] - cv[k][w] : cv[k][w] - p[w];
  };
  auto add = [&](uint32_t id, int where) {
    gp[n] = GPoint{id, static_cast<uint32_t>(where), where < 3 ? along_edge(where, coords(id)) : 0.0};
    ids[n] = KeyIndex{id, static_cast<uint32_t>(n), 0};
    ++n;
  };
  for (size_t i = 0; i < np; ++i) {
    const Record& rc = rec_[proper[i].index];
    for (int end = 0; end < 2; ++end) {
      const uint32_t pid = end == 0 ? rc.from : rc.to;
      const Point& pt = points_[pid];
      int where = 3;
      if (pt.key.tri != t) {
        where = -1;
        for (int e = 0; e < 3; ++e) {
          if (edge_key(raw[e], raw[(e + 1) % 3]) == pt.key.edge) where = e;
        }
        if (where < 0) return make_error(StatusCode::kInternal, "boolean: intersection point ", pid, " is not on triangle ", t);
      }
      add(base + pid, where);
    }
  }
  for (size_t i = 0; i < nd; ++i) {
    const DegRecord& r = deg_[dk[i].index];
    const int ends = r.kind == kDegPointOnly ? 1 : 2;
    for (int e = 0; e < ends; ++e) {
      const Loc l = static_cast<Loc>(r.loc_t[e]);
      if (detail::loc_is_vertex(l)) continue;
      add(canon(r.id[e]), detail::loc_is_edge(l) ? detail::loc_index(l) : 3);
    }
  }
  SPLINTCORE_RETURN_IF_ERROR(sort_keys(arena_, ids, n));
  // Distinct points, by id (the same id is the same point: it must lie in the same place).
  GPoint* up = arena_.allocate_array<GPoint>(n + 1);
  if (up == nullptr) return arena_.exhausted_status();
  size_t nu = 0;
  for (size_t i = 0; i < n; ++i) {
    const GPoint& q = gp[ids[i].index];
    if (q.id == c[0] || q.id == c[1] || q.id == c[2]) return unsupported("a contact point named inside is one of its corners");
    if (nu > 0 && up[nu - 1].id == q.id) {
      if (up[nu - 1].where != q.where) return unsupported("a point found on two different places of it");
      continue;
    }
    up[nu++] = q;
  }
  // 2. Boundary order: c0, edge 0's points, c1, edge 1's, c2, edge 2's; then the inside ones.
  KeyIndex* by = arena_.allocate_array<KeyIndex>(nu);
  detail::CdtPoint* pts = arena_.allocate_array<detail::CdtPoint>(nu + 3);
  uint32_t* vid = arena_.allocate_array<uint32_t>(nu + 3);
  uint32_t* local_of = arena_.allocate_array<uint32_t>(nu);  // by index in `up`
  if (by == nullptr || pts == nullptr || vid == nullptr || local_of == nullptr) return arena_.exhausted_status();
  uint32_t m = 0, boundary = 0;
  uint32_t corner_at[3];
  SPLINTCORE_RETURN_IF_ERROR(order_points(
      arena_, nu, c, [&](size_t x) { return up[x].where; }, [&](size_t x) { return up[x].along; },
      [&](size_t x) { return up[x].id; }, by, vid, local_of, corner_at, &m, &boundary));
  // Local index of a vertex id: a corner, or a point (binary search in `up`).
  auto local = [&](uint32_t id) -> uint32_t {
    for (int k = 0; k < 3; ++k) {
      if (id == c[k]) return corner_at[k];
    }
    size_t lo = 0, hi = nu;
    while (lo < hi) {
      const size_t mid = (lo + hi) / 2;
      if (up[mid].id < id) lo = mid + 1; else hi = mid;
    }
    return (lo < nu && up[lo].id == id) ? local_of[lo] : ~0u;
  };
  {
    const Projection pr = projection_of(cv[0], cv[1], cv[2]);
    for (uint32_t j = 0; j < m; ++j) pts[j] = to_2d(coords(vid[j]), pr);
  }
  // 3. Constraints with the states of their two sides: crossing segments (inside on the
  // left), then the degenerate segments grouped by their two ends (the records of one line
  // from its sheets, the other mesh's triangles that hold it).
  struct Cons {
    uint32_t from, to;
    int8_t left, right;
  };
  Cons* cons = arena_.allocate_array<Cons>(np + nd);
  KeyIndex* ckey = arena_.allocate_array<KeyIndex>(np + nd);
  KeyIndex* dseg = arena_.allocate_array<KeyIndex>(nd + 1);
  if (cons == nullptr || ckey == nullptr || dseg == nullptr) return arena_.exhausted_status();
  uint32_t nc = 0;
  for (size_t x = 0; x < np; ++x) {
    const Record& rc = rec_[proper[x].index];
    const uint32_t from = local(base + rc.from), to = local(base + rc.to);
    if (from == ~0u || to == ~0u) return make_error(StatusCode::kInternal, "boolean: a segment end is not a point of triangle ", t);
    cons[nc++] = Cons{from, to, kStateIn, kStateOut};
  }
  size_t ns = 0;
  for (size_t x = 0; x < nd; ++x) {
    const DegRecord& r = deg_[dk[x].index];
    if (r.kind == kDegPointOnly) continue;
    const uint32_t a = local(canon(r.id[0])), b = local(canon(r.id[1]));
    if (a == ~0u || b == ~0u) return make_error(StatusCode::kInternal, "boolean: a contact end is not a point of triangle ", t);
    if (a == b) return unsupported("a contact segment with both ends at one point");
    dseg[ns++] = KeyIndex{edge_key(a, b), static_cast<uint32_t>(x), 0};
  }
  SPLINTCORE_RETURN_IF_ERROR(sort_keys(arena_, dseg, ns));
  for (size_t g = 0; g < ns;) {
    size_t g_end = g + 1;
    while (g_end < ns && dseg[g_end].key == dseg[g].key) ++g_end;
    uint32_t sheets[2];
    int nsheets = 0;
    const DegRecord* trans = nullptr;
    for (size_t x = g; x < g_end; ++x) {
      const DegRecord& r = deg_[dk[dseg[x].index].index];
      bool seen = false;
      for (int y = 0; y < nsheets; ++y) seen = seen || sheets[y] == r.other;
      if (!seen) {
        if (nsheets == 2) return unsupported("a contact line held by more than two triangles of the other mesh");
        sheets[nsheets++] = r.other;
      }
      if (r.kind == kDegTransversal && trans == nullptr) trans = &r;
    }
    const DegRecord& first = deg_[dk[dseg[g].index].index];
    const Loc l0 = static_cast<Loc>(first.loc_t[0]), l1 = static_cast<Loc>(first.loc_t[1]);
    int on_edge = -1;
    for (int k = 0; k < 3; ++k) {
      if (detail::loc_on_closed_edge(l0, k) && detail::loc_on_closed_edge(l1, k)) on_edge = k;
    }
    Cons cn{key_hi(dseg[g].key), key_lo(dseg[g].key), kStateNone, kStateNone};
    if (on_edge >= 0) {
      // Along t's own edge: one side only, the one with t's third corner.
      const int8_t s = side_state(t, raw[(on_edge + 2) % 3], sheets, nsheets);
      cn.left = cn.right = s;
    } else if (trans != nullptr) {
      // Across t: its corners on each side, from the transversal sheet's plane (the segment
      // runs along n_a x n_b: A's left is below B's plane, B's left above A's).
      uint32_t o[3];
      in_.corners(trans->other, o);
      const Vec3 q0 = in_.vertex(o[0]), q1 = in_.vertex(o[1]), q2 = in_.vertex(o[2]);
      const int left_sign = is_a ? 1 : -1;
      uint32_t lc = ~0u, rc = ~0u;
      for (int k = 0; k < 3; ++k) {
        const int sd = sign_of(orient3d(q0, q1, q2, cv[k]));
        if (sd == left_sign && lc == ~0u) lc = raw[k];
        if (sd == -left_sign && rc == ~0u) rc = raw[k];
      }
      if (lc == ~0u || rc == ~0u) return unsupported("a contact segment across it without corners on both sides");
      cn.from = local(canon(trans->id[0]));
      cn.to = local(canon(trans->id[1]));
      cn.left = side_state(t, lc, sheets, nsheets);
      cn.right = side_state(t, rc, sheets, nsheets);
    } else {
      // Coplanar only, across t: two coplanar sheets (t lies on both sides).
      if (nsheets != 2) return unsupported("a coplanar contact side inside it with one triangle of the other mesh (an open border?)");
      cn.left = on_state(t, sheets[0]);
      cn.right = on_state(t, sheets[1]);
    }
    if (cn.left == kStateNone || cn.right == kStateNone) return unsupported("a contact line whose sides could not be classified");
    cons[nc++] = cn;
    g = g_end;
  }
  // 4. Triangulate: the boundary, then the constraints (repeats of boundary edges allowed).
  detail::CdtSegment* segs = arena_.allocate_array<detail::CdtSegment>(boundary + nc);
  if (segs == nullptr) return arena_.exhausted_status();
  uint32_t nseg = 0;
  for (uint32_t j = 0; j < boundary; ++j) segs[nseg++] = detail::CdtSegment{j, (j + 1) % boundary};
  for (uint32_t x = 0; x < nc; ++x) {
    segs[nseg++] = detail::CdtSegment{cons[x].from, cons[x].to};
    ckey[x] = KeyIndex{edge_key(cons[x].from, cons[x].to), x, 0};
  }
  SPLINTCORE_RETURN_IF_ERROR(sort_keys(arena_, ckey, nc));
  for (uint32_t x = 1; x < nc; ++x) {
    if (ckey[x].key == ckey[x - 1].key) return unsupported("a contact segment repeats a crossing segment");
  }
  ArenaArray<detail::CdtTriangle> out(&arena_);
  Status s = detail::cdt(arena_, Span<const detail::CdtPoint>(pts, m),
                         Span<const detail::CdtSegment>(segs, nseg), boundary, &out, nullptr);
  if (!s.is_ok()) {
    if (s.code() == StatusCode::kArenaExhausted) return s;
    return make_error(StatusCode::kUnsupported, "cannot re-triangulate triangle ", tn, which,
                      " along its exact contacts: ", s.message())
        .at_index(tn);
  }
  // 5. Votes from constraint edges (a piece is left of its own counter-clockwise edges), pieces
  // joined across other inside edges.
  const uint32_t k = static_cast<uint32_t>(out.size());
  int8_t* vote = arena_.allocate_array<int8_t>(k);
  KeyIndex* half = arena_.allocate_array<KeyIndex>(size_t{3} * k);
  UnionFind uf;
  if (vote == nullptr || half == nullptr || !uf.init(arena_, k)) return arena_.exhausted_status();
  for (uint32_t j = 0; j < k; ++j) {
    vote[j] = kStateNone;
    for (uint32_t e = 0; e < 3; ++e) {
      half[3 * j + e] = KeyIndex{edge_key(out[j].v[e], out[j].v[(e + 1) % 3]), 3 * j + e, 0};
    }
  }
  SPLINTCORE_RETURN_IF_ERROR(sort_keys(arena_, half, size_t{3} * k));
  size_t ci = 0;
  for (size_t a = 0; a < size_t{3} * k;) {
    size_t b = a + 1;
    while (b < size_t{3} * k && half[b].key == half[a].key) ++b;
    while (ci < nc && ckey[ci].key < half[a].key) ++ci;
    if (ci < nc && ckey[ci].key == half[a].key) {
      const Cons& cn = cons[ckey[ci].index];
      for (size_t x = a; x < b; ++x) {
        const uint32_t j = half[x].index / 3, e = half[x].index % 3;
        const int8_t v = out[j].v[e] == cn.from ? cn.left : cn.right;
        if (vote[j] != kStateNone && vote[j] != v) return unsupported("a piece between two contacts that disagree");
        vote[j] = v;
      }
    } else if (b - a == 2) {
      uf.unite(half[a].index / 3, half[a + 1].index / 3);
    }
    a = b;
  }
  int8_t* state = arena_.allocate_array<int8_t>(k);
  if (state == nullptr) return arena_.exhausted_status();
  for (uint32_t j = 0; j < k; ++j) state[j] = kStateNone;
  for (uint32_t j = 0; j < k; ++j) {
    if (vote[j] == kStateNone) continue;
    const uint32_t r = uf.find(j);
    if (state[r] == kStateNone) {
      state[r] = vote[j];
    } else if (state[r] != vote[j]) {
      return unsupported("inconsistent classification of its pieces");
    }
  }
  tflag_[t] = nc > 0 ? kDecided : kPending;
  if (nc == 0) pending_ = true;
  for (uint32_t j = 0; j < k; ++j) {
    const int8_t sj = state[uf.find(j)];
    if (sj == kStateNone && nc > 0) {
      return make_error(StatusCode::kInternal, "boolean: a piece of triangle ", t, " is not next to any contact");
    }
    const detail::CdtTriangle& ct = out[j];
    if (!tris_.push_back(OutTri{{vid[ct.v[0]], vid[ct.v[1]], vid[ct.v[2]]}, t, sj})) {
      return arena_.exhausted_status();
    }
    if (sj != kStateIn && sj != kStateOut) continue;
    for (uint32_t e = 0; e < 3; ++e) {
      for (uint32_t x = 0; x < 3; ++x) {
        if (ct.v[x] != corner_at[e]) continue;
        int8_t& vs = vstate_[c[e]];
        if (vs == kVertexOn) continue;
        if (vs != 0 && vs != sj) return inconsistent_vertex(c[e]);
        vs = sj;
      }
    }
  }
  return Status::ok();
}

Status BooleanRun::split_triangles() {
  const uint32_t nh = static_cast<uint32_t>(hits_.size());
  const uint32_t base = in_.nva + in_.nvb;  // first intersection point's vertex id
  // Records: two per hit, grouped by triangle (stable: hit order within a triangle).
  rec_ = arena_.allocate_array<Record>(size_t{2} * nh);
  order_ = arena_.allocate_array<KeyIndex>(size_t{2} * nh);
  if ((rec_ == nullptr || order_ == nullptr) && nh > 0) return arena_.exhausted_status();
  Record* rec = rec_;
  KeyIndex* order = order_;
  for (uint32_t h = 0; h < nh; ++h) {
    const uint32_t p = hit_points_[2 * h], q = hit_points_[2 * h + 1];
    rec[2 * h] = Record{hits_[h].ta, p, q, h};
    rec[2 * h + 1] = Record{hits_[h].tb, q, p, h};
    order[2 * h] = KeyIndex{hits_[h].ta, 2 * h, 0};
    order[2 * h + 1] = KeyIndex{hits_[h].tb, 2 * h + 1, 0};
  }
  SPLINTCORE_RETURN_IF_ERROR(radix_sort(arena_, Span<KeyIndex>(order, size_t{2} * nh)));

  // Per cut triangle: its distinct points, each on an edge (0..2, with the position along it)
  // or inside (3).
  struct Local {
    uint32_t point;
    uint32_t where;
    double along;
  };
  auto gather = [&](size_t g, size_t g_end, ArenaArray<Local>* locals) -> Status {
    const uint32_t t = static_cast<uint32_t>(order[g].key);
    uint32_t c[3];
    in_.corners(t, c);
    const size_t k = 2 * (g_end - g);
    KeyIndex* ids = arena_.allocate_array<KeyIndex>(k);
    if (ids == nullptr) return arena_.exhausted_status();
    for (size_t i = g; i < g_end; ++i) {
      const Record& r = rec[order[i].index];
      ids[2 * (i - g)] = KeyIndex{r.from, 0, 0};
      ids[2 * (i - g) + 1] = KeyIndex{r.to, 0, 0};
    }
    SPLINTCORE_RETURN_IF_ERROR(sort_keys(arena_, ids, k));
    if (!locals->reserve(k)) return arena_.exhausted_status();
    for (size_t i = 0; i < k; ++i) {
      if (i > 0 && ids[i].key == ids[i - 1].key) continue;
      const uint32_t pid = static_cast<uint32_t>(ids[i].key);
      const Point& pt = points_[pid];
      Local l{pid, 3, 0.0};
      if (pt.key.tri != t) {
        const uint32_t u = key_hi(pt.key.edge), v = key_lo(pt.key.edge);
        for (uint32_t e = 0; e < 3; ++e) {
          const uint32_t x = c[e], y = c[(e + 1) % 3];
          if (x == u && y == v) l = Local{pid, e, pt.s};
          if (x == v && y == u) l = Local{pid, e, -pt.s};
        }
        if (l.where == 3) {
          return make_error(StatusCode::kInternal, "boolean: intersection point ", pid,
                            " is not on triangle ", t);
        }
      }
      if (!locals->push_back(l)) return arena_.exhausted_status();
    }
    return Status::ok();
  };

  // Room for the pieces: a triangle with r segments has at most 2r points, so at most
  // 3 + 2 * 2r - 2 pieces (b + 2i - 2 for b boundary and i inside points).
  // Degenerate records by triangle (stable), and their triangles' flags.
  const size_t nd = deg_.size();
  KeyIndex* dorder = nullptr;
  if (st_.degenerate_pairs > 0) {
    const size_t ntri = size_t{in_.nta} + in_.ntb;
    tflag_ = arena_.allocate_array<uint8_t>(ntri);
    tstate_ = arena_.allocate_array<int8_t>(ntri);
    dorder = arena_.allocate_array<KeyIndex>(nd + 1);
    if (tflag_ == nullptr || tstate_ == nullptr || dorder == nullptr) return arena_.exhausted_status();
    std::memset(tflag_, kUncut, ntri);
    std::memset(tstate_, 0, ntri);
    for (size_t r = 0; r < nd; ++r) dorder[r] = KeyIndex{deg_[r].tri, static_cast<uint32_t>(r), 0};
    SPLINTCORE_RETURN_IF_ERROR(radix_sort(arena_, Span<KeyIndex>(dorder, nd)));
  }
  // The next triangle with records of either kind, and the ends of its two runs.
  auto next_group = [&](size_t g, size_t d, size_t* g_end, size_t* d_end) -> uint32_t {
    const uint64_t tg = g < size_t{2} * nh ? order[g].key : ~uint64_t{0};
    const uint64_t td = d < nd ? dorder[d].key : ~uint64_t{0};
    const uint64_t t = tg < td ? tg : td;
    *g_end = g;
    while (*g_end < size_t{2} * nh && order[*g_end].key == t) ++*g_end;
    *d_end = d;
    while (*d_end < nd && dorder[*d_end].key == t) ++*d_end;
    return static_cast<uint32_t>(t);
  };
  uint64_t total = 0;
  uint32_t cut_a = 0, cut_b = 0;
  for (size_t g = 0, d = 0; g < size_t{2} * nh || d < nd;) {
    size_t g_end = 0, d_end = 0;
    const uint32_t t = next_group(g, d, &g_end, &d_end);
    total += d_end > d ? 4 * (g_end - g + d_end - d) + 3 : 4 * (g_end - g) + 1;
    if (t < in_.nta) ++cut_a; else ++cut_b;
    g = g_end;
    d = d_end;
  }
  st_.cut_triangles_a = cut_a;
  st_.cut_triangles_b = cut_b;
  if (total >= (uint64_t{1} << 31)) {
    return make_error(StatusCode::kLimitExceeded, "too many triangles for 32-bit ids: ", total);
  }
  tris_.bind(&arena_);
  if (!tris_.reserve(static_cast<size_t>(total))) return arena_.exhausted_status();

  // Sets the state of a corner of a cut triangle (all pieces at a corner agree: no segment
  // passes through an input vertex).
  auto corner_state = [&](uint32_t v, int8_t sj) -> Status {
    int8_t& vs = vstate_[v];
    if (vs == kVertexOn) return Status::ok();  // on the other surface: no state to pass on
    if (vs != 0 && vs != sj) return inconsistent_vertex(v);
    vs = sj;
    return Status::ok();
  };
  auto project = [&](const uint32_t c[3]) {
    return projection_of(in_.vertex(c[0]), in_.vertex(c[1]), in_.vertex(c[2]));
  };
  auto point_2d = [&](uint32_t id, const Projection& pr) {
    return to_2d(id < base ? in_.vertex(id) : points_[id - base].p, pr);
  };

  // Re-triangulate each cut triangle along its segments, classify its pieces (each piece lies
  // on one side of a segment; pieces joined by other edges share a side) and give its corners
  // their state.
  for (size_t g = 0, d = 0; g < size_t{2} * nh || d < nd;) {
    size_t g_end = 0, d_end = 0;
    const uint32_t t = next_group(g, d, &g_end, &d_end);
    if ((g & 1023u) == 0) {
      SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx_, "boolean: split", g, size_t{2} * nh));
    }
    if (tflag_ != nullptr) tflag_[t] = kDecided;
    if (d_end > d) {
      SPLINTCORE_RETURN_IF_ERROR(split_general(t, order + g, g_end - g, dorder + d, d_end - d));
      g = g_end;
      d = d_end;
      continue;
    }
    uint32_t c[3];
    in_.corners(t, c);
    // Fast path: one segment from an edge to another edge (most of B's cut triangles): a
    // triangle on one side, a quadrilateral split by its Delaunay diagonal on the other.
    if (g_end - g == 1) {
      const Record& rc = rec[order[g].index];
      const Point& pf = points_[rc.from];
      const Point& pt = points_[rc.to];
      int ef = -1, et = -1;
      for (int e = 0; e < 3; ++e) {
        const uint64_t k = edge_key(c[e], c[(e + 1) % 3]);
        if (pf.key.tri != t && pf.key.edge == k) ef = e;
        if (pt.key.tri != t && pt.key.edge == k) et = e;
      }
      if (ef >= 0 && et >= 0 && ef != et) {
        // The pentagon c0 [e0] c1 [e1] c2 [e2] and the chord between its two points.
        uint32_t poly[5];
        int m = 0, at_from = 0, at_to = 0;
        for (int e = 0; e < 3; ++e) {
          poly[m++] = c[e];
          if (e == ef) { at_from = m; poly[m++] = base + rc.from; }
          if (e == et) { at_to = m; poly[m++] = base + rc.to; }
        }
        // Part one runs from the lower chord end to the higher one, part two on from there.
        const int x = at_from < at_to ? at_from : at_to, y = at_from < at_to ? at_to : at_from;
        uint32_t one[4], two[4];
        int n1 = 0, n2 = 0;
        for (int i = x; i <= y; ++i) one[n1++] = poly[i];
        for (int i = y; i != x; i = (i + 1) % 5) two[n2++] = poly[i];
        two[n2++] = poly[x];
        // Part one lies left of poly[y] -> poly[x]; the record's inside is left of from -> to.
        const int8_t s_one = poly[x] == base + rc.from ? -1 : 1;
        const uint32_t* tri3 = n1 == 3 ? one : two;
        const uint32_t* quad = n1 == 3 ? two : one;
        const int8_t s3 = n1 == 3 ? s_one : static_cast<int8_t>(-s_one);
        const int8_t s4 = static_cast<int8_t>(-s3);
        const Projection pr = project(c);
        detail::CdtPoint q2[4];
        for (int i = 0; i < 4; ++i) q2[i] = point_2d(quad[i], pr);
        const detail::CdtPoint t2[3] = {point_2d(tri3[0], pr), point_2d(tri3[1], pr),
                                         point_2d(tri3[2], pr)};
        auto ccw = [](const detail::CdtPoint& a, const detail::CdtPoint& b2, const detail::CdtPoint& c2) {
          return orient2d(a.x, a.y, b2.x, b2.y, c2.x, c2.y) > 0;
        };
        // Diagonal 0-2 unless quad[3] is inside the circle of 0, 1, 2 (then 1-3).
        const bool d13 = incircle(q2[0].x, q2[0].y, q2[1].x, q2[1].y, q2[2].x, q2[2].y, q2[3].x,
                                  q2[3].y) > 0;
        const int qa[2][3] = {{0, 1, 2}, {0, 2, 3}};
        const int qb[2][3] = {{0, 1, 3}, {1, 2, 3}};
        const int (*qs)[3] = d13 ? qb : qa;
        if (ccw(t2[0], t2[1], t2[2]) && ccw(q2[qs[0][0]], q2[qs[0][1]], q2[qs[0][2]]) &&
            ccw(q2[qs[1][0]], q2[qs[1][1]], q2[qs[1][2]])) {
          if (!tris_.push_back(OutTri{{tri3[0], tri3[1], tri3[2]}, t, s3})) {
            return arena_.exhausted_status();
          }
          for (int k = 0; k < 2; ++k) {
            if (!tris_.push_back(OutTri{{quad[qs[k][0]], quad[qs[k][1]], quad[qs[k][2]]}, t, s4})) {
              return arena_.exhausted_status();
            }
          }
          for (int i = 0; i < 3; ++i) {
            if (tri3[i] < base) SPLINTCORE_RETURN_IF_ERROR(corner_state(tri3[i], s3));
          }
          for (int i = 0; i < 4; ++i) {
            if (quad[i] < base) SPLINTCORE_RETURN_IF_ERROR(corner_state(quad[i], s4));
          }
          g = g_end;
          continue;
        }
      }
    }
    ArenaScope scope(arena_);
    ArenaArray<Local> locals(&arena_);
    SPLINTCORE_RETURN_IF_ERROR(gather(g, g_end, &locals));
    const size_t n = locals.size();
    const size_t nseg = g_end - g;
    // Boundary order: c0, edge 0's points from c0, c1, edge 1's points, c2, edge 2's points,
    // then the inside points. Sort by position along the edge, then stably by edge.
    KeyIndex* by = arena_.allocate_array<KeyIndex>(n);
    detail::CdtPoint* pts = arena_.allocate_array<detail::CdtPoint>(n + 3);
    uint32_t* vid = arena_.allocate_array<uint32_t>(n + 3);
    uint32_t* local_of = arena_.allocate_array<uint32_t>(n);  // by index in `locals`
    detail::CdtSegment* segs = arena_.allocate_array<detail::CdtSegment>(n + 3 + nseg);
    if (by == nullptr || pts == nullptr || vid == nullptr || local_of == nullptr ||
        segs == nullptr) {
      return arena_.exhausted_status();
    }
    uint32_t m = 0, boundary = 0;
    uint32_t corner_at[3];
    SPLINTCORE_RETURN_IF_ERROR(order_points(
        arena_, n, c, [&](size_t x) { return locals[x].where; },
        [&](size_t x) { return locals[x].along; }, [&](size_t x) { return base + locals[x].point; },
        by, vid, local_of, corner_at, &m, &boundary));
    const Projection pr = project(c);
    for (uint32_t j = 0; j < m; ++j) pts[j] = point_2d(vid[j], pr);
    uint32_t ns = 0;
    for (uint32_t j = 0; j < boundary; ++j) segs[ns++] = detail::CdtSegment{j, (j + 1) % boundary};
    // Constraint end points: find each point id among the sorted locals (binary search).
    auto local = [&](uint32_t pid) {
      size_t lo = 0, hi = n;
      while (hi - lo > 1) {
        const size_t mid = (lo + hi) / 2;
        if (locals[mid].point <= pid) lo = mid; else hi = mid;
      }
      SPLINTCORE_ASSERT(locals[lo].point == pid);
      return local_of[lo];
    };
    // The constraints, directed with the other solid's inside on their left, sorted by their
    // undirected key (for the classification below).
    KeyIndex* cons = arena_.allocate_array<KeyIndex>(nseg);
    uint32_t* cons_from = arena_.allocate_array<uint32_t>(nseg);  // by segment, in record order
    if (cons == nullptr || cons_from == nullptr) return arena_.exhausted_status();
    // `distinct`: no constraint repeats another or lies on the boundary, so the CDT's segment
    // id on an edge names its record (boundary + r - g): the adjacency path below applies.
    bool distinct = true;
    for (size_t r = g; r < g_end; ++r) {
      const Record& rc = rec[order[r].index];
      const uint32_t from = local(rc.from), to = local(rc.to);
      cons[r - g] = KeyIndex{edge_key(from, to), from, 0};
      cons_from[r - g] = from;
      segs[ns++] = detail::CdtSegment{from, to};
      if (from < boundary && to < boundary) {
        const uint32_t gap = from < to ? to - from : from - to;
        if (gap == 1 || gap == boundary - 1) distinct = false;
      }
    }
    SPLINTCORE_RETURN_IF_ERROR(sort_keys(arena_, cons, nseg));
    for (size_t x = 1; x < nseg; ++x) {
      if (cons[x].key == cons[x - 1].key) distinct = false;
    }
    ArenaArray<detail::CdtTriangle> cdt_out(&arena_);
    ArenaArray<detail::CdtAdjacency> adjacency(&arena_);
    Status s = detail::cdt(arena_, Span<const detail::CdtPoint>(pts, m),
                           Span<const detail::CdtSegment>(segs, ns), boundary, &cdt_out,
                           distinct ? &adjacency : nullptr);
    if (!s.is_ok()) {
      if (s.code() == StatusCode::kArenaExhausted) return s;
      return make_error(StatusCode::kUnsupported, "cannot re-triangulate triangle ",
                        t < in_.nta ? t : t - in_.nta, t < in_.nta ? " of A" : " of B",
                        " along its intersection (nearly degenerate contact): ", s.message())
          .at_index(t < in_.nta ? t : t - in_.nta);
    }
    // Classify the pieces: a constraint votes for the piece on its left (inside the other
    // solid) and against the one on its right; other shared edges join pieces. A piece with
    // two constraint edges takes the vote of the one with the larger undirected key.
    const uint32_t k = static_cast<uint32_t>(cdt_out.size());
    int8_t* vote = arena_.allocate_array<int8_t>(k);
    UnionFind uf;
    if (vote == nullptr || !uf.init(arena_, k)) return arena_.exhausted_status();
    if (distinct) {
      // From the CDT's own adjacency: the same votes and the same joined sets as matching
      // half-edges by key (the path below), without sorting them.
      for (uint32_t j = 0; j < k; ++j) {
        vote[j] = 0;
        uint64_t best = 0;
        bool voted = false;
        const detail::CdtTriangle& ct = cdt_out[j];
        const detail::CdtAdjacency& adj = adjacency[j];
        for (uint32_t e = 0; e < 3; ++e) {
          const uint32_t seg = adj.seg[e];
          if (seg == detail::kCdtNone) {
            if (adj.nb[e] != detail::kCdtNone) uf.unite(j, adj.nb[e]);
            continue;
          }
          if (seg < boundary) continue;
          const uint64_t key = edge_key(ct.v[e], ct.v[(e + 1) % 3]);
          if (!voted || key > best) {
            best = key;
            voted = true;
            vote[j] = ct.v[e] == cons_from[seg - boundary] ? 1 : -1;
          }
        }
      }
    }
    // Otherwise half-edges matched by their undirected key.
    KeyIndex* half = distinct ? nullptr : arena_.allocate_array<KeyIndex>(size_t{3} * k);
    if (!distinct && half == nullptr && k > 0) return arena_.exhausted_status();
    for (uint32_t j = 0; j < k && !distinct; ++j) {
      vote[j] = 0;
      for (uint32_t e = 0; e < 3; ++e) {
        half[3 * j + e] = KeyIndex{edge_key(cdt_out[j].v[e], cdt_out[j].v[(e + 1) % 3]), 3 * j + e, 0};
      }
    }
    if (!distinct) SPLINTCORE_RETURN_IF_ERROR(sort_keys(arena_, half, size_t{3} * k));
    size_t ci = 0;
    for (size_t a = 0; a < size_t{3} * k && !distinct;) {
      size_t b = a + 1;
      while (b < size_t{3} * k && half[b].key == half[a].key) ++b;
      while (ci < nseg && cons[ci].key < half[a].key) ++ci;
      if (ci < nseg && cons[ci].key == half[a].key) {
        for (size_t x = a; x < b; ++x) {
          const uint32_t j = half[x].index / 3, e = half[x].index % 3;
          vote[j] = cdt_out[j].v[e] == cons[ci].index ? 1 : -1;
        }
      } else if (b - a == 2) {
        uf.unite(half[a].index / 3, half[a + 1].index / 3);
      }
      a = b;
    }
    int8_t* state = arena_.allocate_array<int8_t>(k);
    if (state == nullptr) return arena_.exhausted_status();
    for (uint32_t j = 0; j < k; ++j) state[j] = 0;
    for (uint32_t j = 0; j < k; ++j) {
      if (vote[j] == 0) continue;
      const uint32_t r = uf.find(j);
      if (state[r] == 0) {
        state[r] = vote[j];
      } else if (state[r] != vote[j]) {
        return make_error(StatusCode::kUnsupported,
                          "inconsistent inside/outside classification in triangle ",
                          t < in_.nta ? t : t - in_.nta, t < in_.nta ? " of A" : " of B",
                          " (overlapping shells in B, or a nearly degenerate contact)")
            .at_index(t < in_.nta ? t : t - in_.nta);
      }
    }
    for (uint32_t j = 0; j < k; ++j) {
      const int8_t sj = state[uf.find(j)];
      if (sj == 0) {
        return make_error(StatusCode::kInternal, "boolean: a piece of triangle ", t,
                          " is not next to any intersection segment");
      }
      const detail::CdtTriangle& ct = cdt_out[j];
      if (!tris_.push_back(OutTri{{vid[ct.v[0]], vid[ct.v[1]], vid[ct.v[2]]}, t, sj})) {
        return arena_.exhausted_status();
      }
      // Most pieces have no corner of the triangle (only those do have a vertex id below base).
      if (vid[ct.v[0]] >= base && vid[ct.v[1]] >= base && vid[ct.v[2]] >= base) continue;
      for (uint32_t e = 0; e < 3; ++e) {
        for (uint32_t x = 0; x < 3; ++x) {
          if (ct.v[x] == corner_at[e]) SPLINTCORE_RETURN_IF_ERROR(corner_state(c[e], sj));
        }
      }
    }
    g = g_end;
  }
  return Status::ok();
}

Status BooleanRun::inconsistent_vertex(uint32_t v) const {
  const bool is_a = v < in_.nva;
  return make_error(StatusCode::kUnsupported,
                    "inconsistent inside/outside classification at vertex ",
                    is_a ? v : v - in_.nva, is_a ? " of A" : " of B",
                    " (overlapping shells in B, or a nearly degenerate contact)")
      .at_index(is_a ? v : v - in_.nva);
}

// Vertex states spread from the corners of cut triangles across the uncut triangles of one
// mesh (an uncut triangle does not cross the other surface, so its three corners agree);
// a part no cut triangle reaches gets one winding number.
Status BooleanRun::flood(bool side_a) {
  ArenaScope scope(arena_);
  const Mesh& mesh = side_a ? *in_.a : *in_.b;
  const uint32_t voff = side_a ? 0 : in_.nva;
  const uint32_t toff = side_a ? 0 : in_.nta;
  const uint32_t nv = side_a ? in_.nva : in_.nvb;
  const uint32_t nt = side_a ? in_.nta : in_.ntb;
  // Cut flags per triangle from the sorted groups.
  uint8_t* cut = arena_.allocate_array<uint8_t>(nt);
  uint32_t* start = arena_.allocate_array<uint32_t>(size_t{nv} + 1);
  if ((cut == nullptr && nt > 0) || start == nullptr) return arena_.exhausted_status();
  if (nt > 0) std::memset(cut, 0, nt);
  if (tflag_ != nullptr) {
    // Triangles with pending pieces (lone contact points only) pass states on like uncut ones.
    for (uint32_t t = 0; t < nt; ++t) cut[t] = tflag_[toff + t] == kDecided ? 1 : 0;
  } else {
    for (size_t i = 0; i < 2 * hits_.size(); ++i) {
      const uint32_t t = static_cast<uint32_t>(order_[i].key);
      if (t >= toff && t - toff < nt) cut[t - toff] = 1;
    }
  }
  // The triangles that take part: all of A's, B's near ones; the uncut ones are flooded.
  const uint32_t count = side_a ? nt : static_cast<uint32_t>(bp_.near_ids.size());
  auto id = [&](uint32_t i) { return side_a ? i : bp_.near_ids[i]; };
  // Vertex -> uncut triangles (compressed rows).
  std::memset(start, 0, (size_t{nv} + 1) * sizeof(uint32_t));
  uint64_t uses = 0;
  for (uint32_t i = 0; i < count; ++i) {
    const uint32_t t = id(i);
    if (cut[t] != 0) continue;
    for (uint32_t v : mesh.triangles[t].v) ++start[v + 1];
    uses += 3;
  }
  for (uint32_t v = 0; v < nv; ++v) start[v + 1] += start[v];
  // start[] holds uint32 prefix sums of the uses, and rows is sized by them (size_t is 32 bits
  // on 32-bit targets): more than 2^32 - 1 uses must fail, not wrap.
  if (uses > UINT32_MAX) {
    return Status::error(StatusCode::kLimitExceeded,
                         "boolean: more than 4294967295 vertex uses in one mesh");
  }
  uint32_t* fill = arena_.allocate_array<uint32_t>(nv);
  uint32_t* rows = arena_.allocate_array<uint32_t>(static_cast<size_t>(uses));
  uint32_t* queue = arena_.allocate_array<uint32_t>(nv);
  if (((fill == nullptr || queue == nullptr) && nv > 0) || (rows == nullptr && uses > 0)) {
    return arena_.exhausted_status();
  }
  if (nv > 0) std::memcpy(fill, start, size_t{nv} * sizeof(uint32_t));
  for (uint32_t i = 0; i < count; ++i) {
    const uint32_t t = id(i);
    if (cut[t] != 0) continue;
    for (uint32_t v : mesh.triangles[t].v) rows[fill[v]++] = t;
  }
  int8_t* vs = vstate_ + voff;
  uint32_t head = 0, tail = 0;
  for (uint32_t v = 0; v < nv; ++v) {
    if (vs[v] != 0 && vs[v] != kVertexOn && start[v + 1] > start[v]) queue[tail++] = v;
  }
  auto spread = [&]() -> Status {
    while (head < tail) {
      const uint32_t v = queue[head++];
      for (uint32_t r = start[v]; r < start[v + 1]; ++r) {
        for (uint32_t w : mesh.triangles[rows[r]].v) {
          const int8_t x = vs[w];
          if (x == 0) {
            vs[w] = vs[v];
            queue[tail++] = w;
          } else if (x != vs[v] && x != kVertexOn) {  // on the other surface: passes nothing on
            return inconsistent_vertex(voff + w);
          }
        }
      }
    }
    return Status::ok();
  };
  SPLINTCORE_RETURN_IF_ERROR(spread());
  // Parts without a cut: one winding number of the other mesh each.
  DistanceIndex index_b{};
  bool have_b = false;
  for (uint32_t i = 0; i < count; ++i) {
    const uint32_t t = id(i);
    if (cut[t] != 0) continue;
    const Triangle& tri = mesh.triangles[t];
    if (vs[tri.v[0]] == kStateIn || vs[tri.v[0]] == kStateOut) continue;
    // Decided when a corner has a state; a corner without one (not on the other surface)
    // takes the winding number; with every corner on the other surface the triangle does.
    int first_free = -1;
    bool decided = false;
    for (int k = 0; k < 3; ++k) {
      const int8_t x = vs[tri.v[k]];
      if (x == kStateIn || x == kStateOut) decided = true;
      if (x == 0 && first_free < 0) first_free = k;
    }
    if (decided || (first_free < 0 && tstate_ != nullptr && tstate_[toff + t] != 0)) continue;
    const Vec3 centroid = (mesh.vertices[tri.v[0]] + mesh.vertices[tri.v[1]] +
                           mesh.vertices[tri.v[2]]) * (1.0 / 3.0);
    double w = 0;
    if (side_a) {
      if (!have_b) {
        SPLINTCORE_RETURN_IF_ERROR(
            build_distance_index(ctx_, *in_.b, DistanceIndexOptions{}, &index_b));
        have_b = true;
      }
      w = winding_number(index_b, centroid);
    } else {
      if (!have_a_index_) {
        SPLINTCORE_RETURN_IF_ERROR(
            build_distance_index(ctx_, *in_.a, DistanceIndexOptions{}, &index_a_));
        have_a_index_ = true;
      }
      w = winding_number(index_a_, centroid);
    }
    ++st_.winding_queries;
    if (first_free < 0) {
      if (tstate_ == nullptr) {
        return make_error(StatusCode::kInternal, "boolean: triangle ", toff + t,
                          " has every corner on the other surface but no contact");
      }
      tstate_[toff + t] = w >= 0.5 ? kStateIn : kStateOut;
      continue;
    }
    vs[tri.v[first_free]] = w >= 0.5 ? 1 : -1;
    queue[tail++] = tri.v[first_free];
    SPLINTCORE_RETURN_IF_ERROR(spread());
  }
  return Status::ok();
}

Status BooleanRun::classify() {
  SPLINTCORE_RETURN_IF_ERROR(flood(true));
  SPLINTCORE_RETURN_IF_ERROR(flood(false));
  return resolve_pending();
}

// The state of a triangle without constraints from its corners (those not on the other
// surface, which agree), or from its winding number when every corner is on it. kStateNone
// when neither is known.
static int8_t corner_agreement(const int8_t* vstate, const int8_t* tstate, const uint32_t c[3],
                               uint32_t t, bool* conflict) {
  int8_t s = kStateNone;
  *conflict = false;
  for (int k = 0; k < 3; ++k) {
    const int8_t x = vstate[c[k]];
    if (x != kStateIn && x != kStateOut) continue;
    if (s != kStateNone && s != x) *conflict = true;
    s = x;
  }
  if (s == kStateNone && tstate != nullptr) s = tstate[t];
  return s;
}

// The state of an uncut triangle whose corners do not simply agree (some on the other
// surface): from the others, or its winding number; kStateNone when unknown (a bug).
int8_t BooleanRun::uncut_state(uint32_t t, const uint32_t c[3]) const {
  if (tstate_ == nullptr) return kStateNone;
  bool conflict = false;
  const int8_t s = corner_agreement(vstate_, tstate_, c, t, &conflict);
  if (conflict || vstate_[c[0]] == 0 || vstate_[c[1]] == 0 || vstate_[c[2]] == 0) return kStateNone;
  return s;
}

// Pieces of triangles with lone contact points only: the triangle's state, after flooding.
Status BooleanRun::resolve_pending() {
  if (!pending_) return Status::ok();
  for (size_t i = 0; i < tris_.size(); ++i) {
    OutTri& o = tris_[i];
    if (o.state != kStateNone) continue;
    uint32_t c[3];
    in_.corners(o.src, c);
    bool conflict = false;
    o.state = corner_agreement(vstate_, tstate_, c, o.src, &conflict);
    if (conflict) return inconsistent_vertex(c[0]);
    if (o.state == kStateNone) {
      return make_error(StatusCode::kInternal, "boolean: triangle ", o.src, " was left unclassified");
    }
  }
  return Status::ok();
}

Status BooleanRun::assemble(Mesh* result) {
  // Which pieces stay: (inside the other?) per side and operation.
  const bool reverse_b = op_ == BooleanOp::kDifference;
  // keep(state, is_a) as a table: [is_a][state + 2].
  bool keeps[2][5];
  for (int side = 0; side < 2; ++side) {
    for (int st = -2; st <= 2; ++st) keeps[side][st + 2] = keep(static_cast<int8_t>(st), side == 1);
  }
  const uint32_t base = in_.nva + in_.nvb;
  const uint32_t nv_all = base + static_cast<uint32_t>(points_.size());
  uint32_t* remap = arena_.allocate_array<uint32_t>(nv_all);
  if (remap == nullptr && nv_all > 0) return arena_.exhausted_status();
  if (nv_all > 0) std::memset(remap, 0xff, size_t{nv_all} * sizeof(uint32_t));
  // Visits the result's triangles in order (A's, then B's, each in input order, a cut triangle
  // replaced by its pieces): emit(v0, v1, v2) for each kept one.
  // Visits the result's triangles in order (A's, then B's near ones, each in input order, a
  // cut triangle replaced by its pieces; for the union B's far ones last): emit(v0, v1, v2)
  // for each kept one.
  auto visit = [&](auto&& emit) -> Status {
    size_t piece = 0;
    const uint32_t count = in_.nta + static_cast<uint32_t>(bp_.near_ids.size());
    for (uint32_t i = 0; i < count; ++i) {
      const bool is_a = i < in_.nta;
      const uint32_t t = is_a ? i : in_.nta + bp_.near_ids[i - in_.nta];
      const bool reverse = !is_a && reverse_b;
      const bool* keep_row = keeps[is_a ? 1 : 0];
      if (piece < tris_.size() && tris_[piece].src == t) {
        for (; piece < tris_.size() && tris_[piece].src == t; ++piece) {
          const OutTri& o = tris_[piece];
          if (!keep_row[o.state + 2]) continue;
          if (reverse) emit(o.v[0], o.v[2], o.v[1], is_a); else emit(o.v[0], o.v[1], o.v[2], is_a);
        }
        continue;
      }
      uint32_t c[3];
      in_.corners(t, c);
      int8_t s = vstate_[c[0]];
      if (s == 0 || s == kVertexOn || vstate_[c[1]] != s || vstate_[c[2]] != s) {
        s = uncut_state(t, c);  // corners on the other surface (degenerate contacts)
        if (s == kStateNone) {
          return make_error(StatusCode::kInternal, "boolean: triangle ", t,
                            " was left unclassified");
        }
      }
      if (!keep_row[s + 2]) continue;
      if (reverse) emit(c[0], c[2], c[1], is_a); else emit(c[0], c[1], c[2], is_a);
    }
    if (op_ == BooleanOp::kUnion) {
      for (uint32_t t = 0; t < in_.ntb; ++t) {
        if (bp_.near_b[t] != 0) continue;
        const Triangle& bt = in_.b->triangles[t];
        emit(in_.nva + bt.v[0], in_.nva + bt.v[1], in_.nva + bt.v[2], false);
      }
    }
    return Status::ok();
  };
  uint64_t kept = 0;
  uint64_t kept_a = 0;
  SPLINTCORE_RETURN_IF_ERROR(visit([&](uint32_t, uint32_t, uint32_t, bool is_a) {
    ++kept;
    kept_a += is_a ? 1 : 0;
  }));
  Triangle* out_t = arena_.allocate_array<Triangle>(static_cast<size_t>(kept));
  if (out_t == nullptr && kept > 0) return arena_.exhausted_status();
  uint32_t nv = 0;
  size_t k = 0;
  SPLINTCORE_RETURN_IF_ERROR(visit([&](uint32_t v0, uint32_t v1, uint32_t v2, bool) {
    uint32_t v[3] = {v0, v1, v2};
    if (alias_ != nullptr) {
      for (uint32_t& x : v) x = canon(x);
    }
    for (uint32_t& x : v) {
      if (remap[x] == ~0u) remap[x] = nv++;
      x = remap[x];
    }
    out_t[k++] = Triangle{{v[0], v[1], v[2]}};
  }));
  Vec3* out_v = arena_.allocate_array<Vec3>(nv);
  if (out_v == nullptr && nv > 0) return arena_.exhausted_status();
  for (uint32_t v = 0; v < nv_all; ++v) {
    if (remap[v] == ~0u) continue;
    out_v[remap[v]] = v < base ? in_.vertex(v) : points_[v - base].p;
  }
  result->triangles.adopt(out_t, static_cast<size_t>(kept), static_cast<size_t>(kept));
  result->vertices.adopt(out_v, nv, nv);
  st_.output_triangles = kept;
  st_.output_triangles_a = kept_a;
  return Status::ok();
}

Status BooleanRun::run(Mesh* result) {
  {
    Status s = check_closed_oriented(ctx_, *in_.a, nullptr);
    if (s.code() == StatusCode::kArenaExhausted) return s;
    if (!s.is_ok()) {
      // A nudged A (in a later pass: the previous result, moved and rounded to float32) can
      // lose a sliver to rounding: that attempt is unsupported and the next nudge runs.
      if (st_.attempts > 1) {
        return make_error(StatusCode::kUnsupported, "A moved by the nudge is not a solid: ",
                          s.message())
            .at_index(s.index());
      }
      return make_error(StatusCode::kInvalidMesh, "A must be a solid: ", s.message())
          .at_index(s.index());
    }
  }
  SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx_, "boolean: hits", 0, in_.ntb));
  SPLINTCORE_RETURN_IF_ERROR(find_hits());
  SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx_, "boolean: points", 0, 1));
  SPLINTCORE_RETURN_IF_ERROR(number_points());
  SPLINTCORE_RETURN_IF_ERROR(number_degenerate_points());
  SPLINTCORE_RETURN_IF_ERROR(check_points_apart());
  SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx_, "boolean: split", 0, 1));
  SPLINTCORE_RETURN_IF_ERROR(split_triangles());
  SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx_, "boolean: classify", 0, 1));
  SPLINTCORE_RETURN_IF_ERROR(classify());
  SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx_, "boolean: assemble", 0, 1));
  SPLINTCORE_RETURN_IF_ERROR(assemble(result));
  SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx_, "boolean: check", 0, 1));
  SPLINTCORE_RETURN_IF_ERROR(check_result(result));
  return report_progress(ctx_, "boolean: done", 1, 1);
}

// The same answer as the edge part of check_closed_oriented (every edge used by exactly two
// triangles, in opposite directions; no triangle repeating a vertex), faster: half-edges
// bucketed by their smaller vertex (other end << 1 | forward), and in each bucket the uses of
// each other end counted in a per-vertex tally (forward uses in the low 32 bits, backward in
// the high: exactly one of each is 2^32 + 1), read and cleared again. *paired is false when it
// does not hold or a vertex id is out of range: the caller then runs check_closed_oriented,
// which names the first offending edge as it always did. Arena: 12 nv + 12 nt bytes or so,
// returned before it returns.
Status edges_paired(Arena& arena, const Mesh& mesh, bool* paired) {
  *paired = false;
  const uint64_t nv64 = mesh.vertices.size(), nt64 = mesh.triangles.size();
  if (nv64 >= (uint64_t{1} << 31) || nt64 >= (uint64_t{1} << 31)) return Status::ok();
  const uint32_t nv = static_cast<uint32_t>(nv64), nt = static_cast<uint32_t>(nt64);
  const Triangle* tris = mesh.triangles.data();
  uint32_t largest = 0;
  for (uint32_t t = 0; t < nt; ++t) {
    const uint32_t a = tris[t].v[0], b = tris[t].v[1], c = tris[t].v[2];
    const uint32_t m = a > b ? a : b;
    largest = m > largest ? m : largest;
    largest = c > largest ? c : largest;
  }
  if (nt > 0 && largest >= nv) return Status::ok();
  ArenaScope scope(arena);
  uint32_t* start = arena.allocate_array<uint32_t>(size_t{nv} + 1);
  uint32_t* half = arena.allocate_array<uint32_t>(size_t{3} * nt);
  uint64_t* tally = arena.allocate_array<uint64_t>(nv);
  if (start == nullptr || (half == nullptr && nt > 0) || (tally == nullptr && nv > 0)) {
    return arena.exhausted_status();
  }
  std::memset(start, 0, (size_t{nv} + 1) * sizeof(uint32_t));
  if (nv > 0) std::memset(tally, 0, size_t{nv} * sizeof(uint64_t));
  for (uint32_t t = 0; t < nt; ++t) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = tris[t].v[k], b = tris[t].v[k == 2 ? 0 : k + 1];
      ++start[(a < b ? a : b) + 1];
    }
  }
  for (uint32_t i = 0; i < nv; ++i) start[i + 1] += start[i];
  for (uint32_t t = 0; t < nt; ++t) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = tris[t].v[k], b = tris[t].v[k == 2 ? 0 : k + 1];
      const uint32_t lo = a < b ? a : b, hi = a < b ? b : a;
      half[start[lo]++] = (hi << 1) | (a < b ? 1u : 0u);
    }
  }
  // start[lo] now ends bucket lo (and begins bucket lo + 1).
  constexpr uint64_t kOneEach = (uint64_t{1} << 32) | 1u;
  uint32_t begin = 0;
  for (uint32_t lo = 0; lo < nv; ++lo) {
    const uint32_t end = start[lo];
    for (uint32_t i = begin; i < end; ++i) {
      tally[half[i] >> 1] += (half[i] & 1u) != 0 ? 1u : (uint64_t{1} << 32);
    }
    // The first use of each other end reads its total (then clears it); later ones read 0.
    for (uint32_t i = begin; i < end; ++i) {
      const uint32_t hi = half[i] >> 1;
      const uint64_t count = tally[hi];
      if ((count != kOneEach && count != 0) || hi == lo) return Status::ok();
      tally[hi] = 0;
    }
    begin = end;
  }
  *paired = true;
  return Status::ok();
}

// The result as the file will hold it: no two intersection points rounded together, every
// edge used exactly twice in opposite directions (closed, edge-manifold, oriented), no flat
// triangle (exact), positive volume; then, when asked, no self-intersection. Linear except for
// the sort of the intersection points.
Status BooleanRun::check_result(Mesh* result) {
  if (result->triangles.empty()) return Status::ok();
  ArenaScope scope(arena_);
  const char* as = options_.float32_output ? " (as float32)" : "";
  // With exact contacts resolved, the result may not be a solid (parts that touch along an
  // edge, points that coincide after rounding): unsupported, so that the nudge takes over.
  const StatusCode fragile = (options_.float32_output || st_.degenerate_pairs > 0)
                                 ? StatusCode::kUnsupported : StatusCode::kInternal;
  // A flat triangle can come from rounding (then A is nudged); anything else would be a bug
  // (or, for the union, an open B). check_closed_oriented scans for flat triangles itself, so
  // the scan here runs only when it fails: the same answer as scanning first, one scan less.
  // First the checks of check_closed_oriented with its edge part done by edges_paired (the
  // same answer, faster); only when one fails (or edges_paired runs out of arena) does
  // check_closed_oriented itself run, so every error, and the order of the checks, is as before.
  bool paired = false;
  {
    const Status e = edges_paired(arena_, *result, &paired);
    if (!e.is_ok()) {
      if (e.code() != StatusCode::kArenaExhausted) return e;
      arena_.forget_failure();  // check_closed_oriented's own request is the one to report
      paired = false;
    }
  }
  Status s;
  if (!paired || find_flat_triangle(*result) != kNoTriangle || !(mesh_volume(*result) > 0)) {
    double volume = 0;
    s = check_closed_oriented(ctx_, *result, &volume);
  }
  if (!s.is_ok()) {
    const uint32_t flat = find_flat_triangle(*result);
    if (flat != kNoTriangle) {
      return make_error(fragile, "Boolean ", boolean_op_name(op_), " result has a flat triangle ",
                        flat, as)
          .at_index(flat);
    }
  }
  if (s.code() == StatusCode::kArenaExhausted) return s;
  if (!s.is_ok()) {
    // An open B whose border meets A (or lies inside it, perhaps after a nudge) leaves the
    // result open: that is the input's fault (B's border must lie outside A), said as such.
    if (op_ != BooleanOp::kUnion) {
      bool b_paired = false;
      const Status e = edges_paired(arena_, *in_.b, &b_paired);
      if (e.code() == StatusCode::kArenaExhausted) return e;
      if (e.is_ok() && !b_paired) {
        return make_error(StatusCode::kInvalidMesh, "Boolean ", boolean_op_name(op_), " result",
                          as, ": ", s.message(),
                          " (B is open or not edge-manifold: its border must lie outside A)")
            .at_index(s.index());
      }
    }
    const StatusCode code = st_.degenerate_pairs > 0 ? StatusCode::kUnsupported
                            : (op_ == BooleanOp::kUnion ? StatusCode::kInvalidMesh : StatusCode::kInternal);
    return make_error(code, "Boolean ", boolean_op_name(op_), " result", as,
                      st_.degenerate_pairs > 0 ? " with exact contacts" : "", ": ", s.message())
        .at_index(s.index());
  }
  if (options_.check_self_intersection) {
    SelfIntersectionReport si;
    SPLINTCORE_RETURN_IF_ERROR(find_self_intersections(ctx_, *result, 1, &si));
    st_.self_intersection_candidates = si.candidate_pairs;
    if (si.self_intersecting()) {
      return make_error(fragile, "Boolean ", boolean_op_name(op_), " result self-intersects", as,
                        ": triangles ", si.first_a, " and ", si.first_b)
          .at_index(si.first_a);
    }
    st_.self_intersection_checked = true;
  }
  return Status::ok();
}

}  // namespace

Status mesh_boolean_single(const Context& ctx, const Mesh& a, const Mesh& b,
                           const BooleanOptions& options, Mesh* out, BooleanStats* stats) {
  Arena& arena = *ctx.arena;
  BooleanStats local{};
  if (stats == nullptr) stats = &local;
  *stats = BooleanStats{};
  SPLINTCORE_RETURN_IF_ERROR(check_boolean_arguments(a, b, *out));
  // Attempt k > 0 runs with A translated by k * step * (1, 3, 7) (nudge_step: float32
  // vertices of A stay float32). B is never moved.
  const double step = nudge_step(a);
  const Arena::Marker start = arena.mark();
  // What a nudge can move A by, with its float32 rounding: the broad phase covers all attempts.
  const double reach = (options.max_nudges + 1.0) * step * 8.0;
  Broadphase bp;
  Status s = report_progress(ctx, "boolean: grid", 0, 1);
  if (s.is_ok()) s = build_broadphase(ctx, a, b, reach, options.float32_output, &bp);
  if (!s.is_ok()) {
    arena.rewind(start);
    return s;
  }
  const Arena::Marker attempts_start = arena.mark();
  Mesh result;
  for (uint32_t attempt = 0; attempt <= options.max_nudges; ++attempt) {
    *stats = BooleanStats{};
    arena.rewind(attempts_start);
    Mesh moved;
    const Mesh* pa = &a;
    // For STL output A is used as it will be written: rounded to float32 (a no-op for A read
    // from STL), after the nudge (a nudge can carry a coordinate into a coarser binade).
    if (attempt > 0 || options.float32_output) {
      const Vec3 d{attempt * step, 3.0 * attempt * step, 7.0 * attempt * step};
      moved.bind(&arena);
      if (!moved.vertices.reserve(a.vertices.size()) || !moved.triangles.reserve(a.triangles.size())) {
        s = arena.exhausted_status();
        break;
      }
      bool in_range = true;
      for (const Vec3& v : a.vertices) {
        Vec3 p = v + d;
        if (options.float32_output) in_range = round_to_float32(&p) && in_range;
        (void)moved.vertices.push_back(p);
      }
      if (!in_range) {
        s = Status::error(StatusCode::kLimitExceeded, "A has a coordinate beyond float32 range");
        break;
      }
      for (const Triangle& t : a.triangles) (void)moved.triangles.push_back(t);
      pa = &moved;
      stats->nudge = d;
    }
    stats->attempts = attempt + 1;
    Inputs in;
    in.a = pa;
    in.b = &b;
    in.nva = static_cast<uint32_t>(a.vertices.size());
    in.nvb = static_cast<uint32_t>(b.vertices.size());
    in.nta = static_cast<uint32_t>(a.triangles.size());
    in.ntb = static_cast<uint32_t>(b.triangles.size());
    result = Mesh();
    BooleanRun run(ctx, in, bp, options, stats);
    s = run.run(&result);
    if (s.code() != StatusCode::kUnsupported) break;
  }
  if (!s.is_ok()) {
    arena.rewind(start);
    if (s.code() == StatusCode::kUnsupported && options.max_nudges > 0) {
      s.append(" (also with A moved by up to ");
      s.append_u64(options.max_nudges);
      s.append(" nudges)");
    }
    return s;
  }
  // The result down over the temporaries (its triangles were allocated before its vertices).
  move_mesh_down(arena, start, result, out);
  return Status::ok();
}

}  // namespace splintcore
