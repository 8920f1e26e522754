// Private to src/boolean: one corefinement run of the Boolean (BooleanRun) and what its stages
// share. The stages, one file each: broadphase.cpp (candidate pairs through a grid over A),
// points.cpp (exact pair tests, intersection points and degenerate contacts, numbered),
// split.cpp (cut triangles re-triangulated by constrained Delaunay, cdt.cpp), classify.cpp
// (pieces inside or outside the other solid: flooding, winding numbers), assemble.cpp (the
// result, its checks, and mesh_boolean_single). The public entry, mesh_boolean (boolean.cpp),
// groups B's shells and runs mesh_boolean_single once per group.
//
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
#ifndef SPLINTCORE_SRC_BOOLEAN_BOOLEAN_RUN_H
#define SPLINTCORE_SRC_BOOLEAN_BOOLEAN_RUN_H

#include "boolean/boolean_internal.h"
#include "boolean/cdt.h"
#include "boolean/contact.h"
#include "boolean/pair_filter.h"
#include "core/union_find.h"
#include "geometry/plane_filter.h"
#include "splintcore/boolean.h"
#include "splintcore/distance.h"

namespace splintcore {
namespace boolean_detail {

// Ids: a vertex of A is its index, a vertex of B is nva + its index, intersection point p is
// nva + nvb + p. A triangle of A is its index, a triangle of B is nta + its index.
// B may be the run's copy of B's triangles near A (mesh_boolean_single's bounded working set):
// then b_whole is B as given (for winding numbers and for what a message calls B's own
// triangles and vertices) and b_vertex_ids / b_triangle_ids map the copy's ids to B's.
struct Inputs {
  const Mesh* a = nullptr;
  const Mesh* b = nullptr;
  uint32_t nva = 0, nvb = 0, nta = 0, ntb = 0;
  const Mesh* b_whole = nullptr;
  const uint32_t* b_vertex_ids = nullptr;    // null: b is B itself
  const uint32_t* b_triangle_ids = nullptr;  // null: b is B itself
  bool a_solid = false;                      // a is known to be a solid (not checked again)

  // B's own id of vertex (triangle) i of b, for messages.
  uint32_t b_vertex(uint32_t i) const { return b_vertex_ids != nullptr ? b_vertex_ids[i] : i; }
  uint32_t b_triangle(uint32_t i) const {
    return b_triangle_ids != nullptr ? b_triangle_ids[i] : i;
  }
  // A run-wide vertex (triangle) id as its mesh numbers it: A's as is, B's as B's own.
  uint32_t named_vertex(uint32_t g) const { return g < nva ? g : b_vertex(g - nva); }
  uint32_t named_triangle(uint32_t tg) const { return tg < nta ? tg : b_triangle(tg - nta); }

  const Vec3& vertex(uint32_t g) const { return g < nva ? a->vertices[g] : b->vertices[g - nva]; }
  void corners(uint32_t tg, uint32_t out[3]) const {
    if (tg < nta) {
      const Triangle& t = a->triangles[tg];
      out[0] = t.v[0];
      out[1] = t.v[1];
      out[2] = t.v[2];
    } else {
      const Triangle& t = b->triangles[tg - nta];
      out[0] = nva + t.v[0];
      out[1] = nva + t.v[1];
      out[2] = nva + t.v[2];
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
// A piece that no constraint decides because the segment beside it collapsed when its two
// ends were merged (rounded together): it takes its corners' state after flooding.
constexpr int8_t kStateFromCorners = 4;

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

// One side of a segment inside one cut triangle, directed so that the other solid's inside is
// on its left, as seen from the triangle's outside.
struct Record {
  uint32_t tri;
  uint32_t from, to;  // point ids
  uint32_t hit;
};

// Stable sort of small KeyIndex arrays (insertion) or large ones (radix); points.cpp.
Status sort_keys(Arena& arena, KeyIndex* items, size_t n);

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
  uint32_t src;  // the cut triangle's id
  int8_t state;  // +1 inside the other solid, -1 outside
};

// The broad phase, computed once for all attempts: B's triangles near A's box (with their
// validity checked) and a uniform grid over A's box whose cells list the triangles of A whose
// box and plane meet them (A is the small mesh: the splint base). Everything is widened by
// `reach`, the most a nudge (and its float32 rounding) can move A, so the candidates are a
// superset for every attempt; the exact tests then use A as moved. Its memory stays until the
// Boolean returns (the per-triangle planes of A, about 100 bytes a triangle, included); while
// the grid is built, 4 bytes per triangle of A and 8 per (triangle, cell) listed more, returned.
struct Broadphase {
  Aabb abox;  // A's bounds widened by reach
  double h = 1, inv_h = 1;
  uint32_t dim[3] = {1, 1, 1};
  uint32_t* start = nullptr;  // cell -> [start[c], start[c + 1]) in items
  uint32_t* items = nullptr;
  uint8_t* near_b = nullptr;  // per B triangle: its box meets abox
  ArenaArray<uint32_t> near_ids;
  // Per triangle of A: its slot among those listed in a cell that a near triangle of B's box
  // covers (the only ones a pair test can meet), in A's order; UINT32_MAX for the others
  // (number_a_slots, once: the same for every attempt).
  uint32_t* a_slot = nullptr;
  uint32_t a_slot_count = 0;

  void cell_range(const Aabb& box, uint32_t lo[3], uint32_t hi[3]) const {
    const double blo[3] = {box.lo.x, box.lo.y, box.lo.z}, bhi[3] = {box.hi.x, box.hi.y, box.hi.z};
    const double glo[3] = {abox.lo.x, abox.lo.y, abox.lo.z};
    // (Three times written out: a loop's end is a branch, taken once in three.)
    lo[0] = grid_cell((blo[0] - glo[0]) * inv_h, dim[0]);
    hi[0] = grid_cell((bhi[0] - glo[0]) * inv_h, dim[0]);
    lo[1] = grid_cell((blo[1] - glo[1]) * inv_h, dim[1]);
    hi[1] = grid_cell((bhi[1] - glo[1]) * inv_h, dim[1]);
    lo[2] = grid_cell((blo[2] - glo[2]) * inv_h, dim[2]);
    hi[2] = grid_cell((bhi[2] - glo[2]) * inv_h, dim[2]);
  }
};

// The box of B's triangle `tri` (vertices vb).
inline Aabb b_box(const Vec3* vb, const Triangle& tri) {
  Aabb box;
  box.add(vb[tri.v[0]]);
  box.add(vb[tri.v[1]]);
  box.add(vb[tri.v[2]]);
  return box;
}

// The cells of the grid that triangle (p0, p1, p2) may meet, also when moved by up to `reach`
// along each axis: a superset, every rounding covered by a pad. Long thin triangles (CAD
// meshes) meet a line of cells where their boxes cover a sheet or a block, so the triangle
// itself is rasterised, not its box (issue 29: 48 M pairs of boxes, 1,239 crossings). Along
// the dominant axis w of its normal the triangle is a graph over (u, v) = (w + 1, w + 2)
// (mod 3): the rows of cells along u that its box covers; in each row the columns along v
// that its projection meets within the row's strip (the three edges clipped to the strip,
// the clipped ends bounding v); in each column the cells along w that its plane spans at the
// column's four corners (the plane through p0, so that no large constant cancels, padded for
// the rounding of its normal: a sliver's normal tilts by up to about eps |e1| |e2| / |n|).
// row(iu, v0, v1) is called for each row (v0 > v1: none) and column(iu, iv, k0, k1) for each
// of its columns, in order; *w_out: the axis w. A flat triangle (zero normal) takes its box's
// cells.
template <class Row, class Column>
void triangle_cells(const Broadphase& bp, const Vec3& p0, const Vec3& p1, const Vec3& p2,
                    double reach, int* w_out, Row row, Column column) {
  auto mag = [](double x) { return x < 0 ? -x : x; };
  const Vec3 e1 = p1 - p0, e2 = p2 - p0;
  const Vec3 n = cross(e1, e2);
  const double an[3] = {mag(n.x), mag(n.y), mag(n.z)};
  const int w = (an[0] >= an[1] && an[0] >= an[2]) ? 0 : (an[1] >= an[2] ? 1 : 2);
  const int u = (w + 1) % 3, v = (w + 2) % 3;
  *w_out = w;
  const Aabb box = reach_box(p0, p1, p2, reach);
  uint32_t lo[3], hi[3];
  bp.cell_range(box, lo, hi);
  // Coordinates as arrays, indexed by axis in the loops below (Vec3's operator[] branches).
  const double q[3][3] = {{p0.x, p0.y, p0.z}, {p1.x, p1.y, p1.z}, {p2.x, p2.y, p2.z}};
  const double nn[3] = {n.x, n.y, n.z}, e1a[3] = {e1.x, e1.y, e1.z}, e2a[3] = {e2.x, e2.y, e2.z};
  const double glo[3] = {bp.abox.lo.x, bp.abox.lo.y, bp.abox.lo.z};
  const double ghi[3] = {bp.abox.hi.x, bp.abox.hi.y, bp.abox.hi.z};
  const double blo[3] = {box.lo.x, box.lo.y, box.lo.z}, bhi[3] = {box.hi.x, box.hi.y, box.hi.z};
  const double h = bp.h, inv_h = bp.inv_h;
  double m = 0, e1m = 0, e2m = 0;
  for (int k = 0; k < 3; ++k) {
    const double x[4] = {mag(glo[k]), mag(ghi[k]), mag(blo[k]), mag(bhi[k])};
    for (double y : x) m = y > m ? y : m;
    e1m = mag(e1a[k]) > e1m ? mag(e1a[k]) : e1m;
    e2m = mag(e2a[k]) > e2m ? mag(e2a[k]) : e2m;
  }
  // (u, v): the rounding of cell bounds, of the clipping and of the projection, and the move.
  const double pad = 1e-9 * m + 1e-6 * h + reach;
  const double span = (bhi[u] - blo[u]) + (bhi[v] - blo[v]) + 4.0 * (h + pad);
  const double pad_w = pad + 2.0 * reach + 1e-13 * (e1m * e2m / an[w]) * span;
  if (!(an[w] > 0) || !(pad_w < HUGE_VAL)) {
    for (uint32_t iu = lo[u]; iu <= hi[u]; ++iu) {
      row(iu, lo[v], hi[v]);
      for (uint32_t iv = lo[v]; iv <= hi[v]; ++iv) column(iu, iv, lo[w], hi[w]);
    }
    return;
  }
  const double su = nn[u] / nn[w], sv = nn[v] / nn[w];  // w = p0_w - su (u - p0_u) - sv (v - p0_v)
  double du[3], dv[3];                                  // the edges k -> k + 1 along u and v
  for (int k = 0; k < 3; ++k) {
    const double* b = q[k == 2 ? 0 : k + 1];
    du[k] = b[u] - q[k][u];
    dv[k] = b[v] - q[k][v];
  }
  for (uint32_t iu = lo[u]; iu <= hi[u]; ++iu) {
    const double u0 = glo[u] + iu * h - pad, u1 = glo[u] + (iu + 1.0) * h + pad;
    double vmin = HUGE_VAL, vmax = -HUGE_VAL;
    for (int k = 0; k < 3; ++k) {
      const double* a = q[k];
      double t0 = 0, t1 = 1;
      if (du[k] != 0) {
        double ta = (u0 - a[u]) / du[k], tb = (u1 - a[u]) / du[k];
        if (ta > tb) {
          const double swap = ta;
          ta = tb;
          tb = swap;
        }
        t0 = ta > t0 ? ta : t0;
        t1 = tb < t1 ? tb : t1;
        if (t0 > t1) continue;
      } else if (a[u] < u0 || a[u] > u1) {
        continue;
      }
      const double va = a[v] + dv[k] * t0, vb = a[v] + dv[k] * t1;
      vmin = va < vmin ? va : vmin;
      vmin = vb < vmin ? vb : vmin;
      vmax = va > vmax ? va : vmax;
      vmax = vb > vmax ? vb : vmax;
    }
    uint32_t v0 = 1, v1 = 0;
    if (vmin <= vmax) {
      v0 = grid_cell((vmin - pad - glo[v]) * inv_h, bp.dim[v]);
      v1 = grid_cell((vmax + pad - glo[v]) * inv_h, bp.dim[v]);
      v0 = v0 < lo[v] ? lo[v] : v0;
      v1 = v1 > hi[v] ? hi[v] : v1;
    }
    row(iu, v0, v1);
    if (v0 > v1) continue;
    const double a0 = su * (u0 - q[0][u]), a1 = su * (u1 - q[0][u]);
    const double amax = a0 > a1 ? a0 : a1, amin = a0 < a1 ? a0 : a1;
    for (uint32_t iv = v0; iv <= v1; ++iv) {
      const double c0 = glo[v] + iv * h - pad, c1 = glo[v] + (iv + 1.0) * h + pad;
      const double b0 = sv * (c0 - q[0][v]), b1 = sv * (c1 - q[0][v]);
      const double wmin = q[0][w] - amax - (b0 > b1 ? b0 : b1);
      const double wmax = q[0][w] - amin - (b0 < b1 ? b0 : b1);
      uint32_t k0 = grid_cell((wmin - pad_w - glo[w]) * inv_h, bp.dim[w]);
      uint32_t k1 = grid_cell((wmax + pad_w - glo[w]) * inv_h, bp.dim[w]);
      k0 = k0 < lo[w] ? lo[w] : k0;
      k1 = k1 > hi[w] ? hi[w] : k1;
      column(iu, iv, k0, k1);  // k0 > k1: none
    }
  }
}

class BooleanRun {
 public:
  BooleanRun(const Context& ctx, const Inputs& in, const Broadphase& bp,
             const BooleanOptions& options, BooleanStats* stats)
      : ctx_(ctx),
        arena_(*ctx.arena),
        in_(in),
        op_(options.op),
        options_(options),
        st_(*stats),
        bp_(bp) {}

  // The whole run; the result is moved down to result_at (over the run's temporaries and
  // anything else above it) before it is checked.
  Status run(Mesh* result, const Arena::Marker& result_at);
  // The candidate pairs this run may test (options.max_candidate_pairs, less what earlier
  // attempts used); over it, find_hits stops with kLimitExceeded.
  void set_pair_budget(uint64_t budget) { pair_budget_ = budget; }
  // Intersection points that round together are merged (check_points_apart, and those a
  // triangulation fails on: split_with_merges), not refused. The error this run would have
  // ended with had they been refused, from where the two would part (the first pair of such
  // points, or the first triangulation that failed on them); ok while they have not parted.
  const Status& unmerged_status() const { return unmerged_; }

 private:
  Status check_pair_budget(uint32_t tb) const;
  // The pair tests' data for the triangles of A near B (prepare_a_slots, find_hits).
  struct ASlots {
    uint32_t* slot = nullptr;  // per triangle of A: its slot, or UINT32_MAX (none)
    PlaneFilter* filters = nullptr;
    EdgePlanes* edges = nullptr;
    Aabb* boxes = nullptr;
    uint32_t* stamp = nullptr;  // the last triangle of B tested against it
    uint32_t count = 0;         // slots
  };
  Status allocate_a_slots(uint32_t count, ASlots* out);
  void fill_a_slot(uint32_t t, uint32_t k, const ASlots& as) const;
  Status prepare_a_slots(ASlots* out);
  size_t hits_in_parallel(const ASlots& as);
  Status hits_serial(const ASlots& as, size_t from, size_t to);
  Status hits_in_batches();
  Status find_hits();
  void hits_over_slots(const Arena::Marker& slots_at);
  Status add_contact(uint32_t ta, uint32_t tb);
  Status name_contact_point(const detail::ContactPoint& cp, const uint32_t ga[3],
                            const uint32_t gb[3], uint32_t ta, uint32_t tb, DegPoint* name);
  Status alias_b_vertex(uint32_t bv, uint32_t av);
  Status record_contact(const detail::Contact& c, const DegPoint name[6], int i, int j,
                        uint8_t kind, uint32_t ta, uint32_t tb);
  Status number_points();
  void points_over_items(const Arena::Marker& items_at);
  Status number_degenerate_points();
  Status check_points_apart();
  Status sort_points_by_position(KeyIndex* keys, uint32_t np);
  Status coincide(const PointKey& kp, uint32_t p, const PointKey& kq, uint32_t q) const;
  bool same_features(const PointKey& kp, const PointKey& kq) const;
  Status duplicated(const PointKey& kp, const PointKey& kq) const;
  // The point that stands for intersection point p (itself unless it was merged into one that
  // rounds to the same coordinates); vertex id x likewise (input vertices stand for themselves).
  uint32_t rep(uint32_t p) const { return merge_ != nullptr ? merge_[p] : p; }
  uint32_t rep_id(uint32_t x) const {
    const uint32_t base = in_.nva + in_.nvb;
    return (merge_ != nullptr && x >= base) ? base + merge_[x - base] : x;
  }
  // split.cpp: the records grouped by triangle, then each cut triangle split by the fast path
  // (one segment edge to edge), by CutSplit (crossing segments only) or by ContactSplit
  // (split_general: degenerate contacts too), each a struct with one method per stage.
  struct CutSplit;
  struct ContactSplit;
  Status split_triangles();
  Status split_with_merges();
  bool note_coincident(const detail::CdtPoint* pts, const uint32_t* vid, uint32_t m);
  Status merge_noted();
  Status sort_records_by_triangle();
  Status sort_contacts_by_triangle(KeyIndex** dorder);
  Status split_single_crossing(uint32_t t, const uint32_t c[3], const Record& rc, bool* done);
  Status split_cut(uint32_t t, const uint32_t c[3], const KeyIndex* recs, size_t nseg);
  Status split_general(uint32_t t, const KeyIndex* proper, size_t np, const KeyIndex* dk,
                       size_t nd);
  // Where vertex id `id` lies: an input vertex, or an intersection point (ids from nva + nvb).
  const Vec3& position(uint32_t id) const {
    const uint32_t base = in_.nva + in_.nvb;
    return id < base ? in_.vertex(id) : points_[id - base].p;
  }
  int8_t side_state(uint32_t t, uint32_t r, const uint32_t* sheets, int nsheets) const;
  int8_t on_state(uint32_t t, uint32_t sheet) const;
  uint32_t canon(uint32_t v) const {
    return (alias_ != nullptr && v >= in_.nva && v < in_.nva + in_.nvb &&
            alias_[v - in_.nva] != ~0u)
               ? alias_[v - in_.nva]
               : v;
  }
  bool keep(int8_t state, bool is_a) const;
  Status resolve_pending();
  int8_t uncut_state(uint32_t t, const uint32_t c[3]) const;
  Status classify();
  Status assemble(Mesh* result);
  void move_over_pieces(uint32_t nv_all, size_t kept, uint32_t** remap, Triangle** out_t);
  Status pair_result_edges(const Mesh& result, bool* paired);
  Status check_result(Mesh* result);
  Status check_merged_fans(const Triangle* tris, size_t nt, const uint32_t* remap, uint32_t nv);
  struct FloodSide;  // classify.cpp: one mesh's flood, one method per stage
  Status flood(bool side_a);
  Status degenerate(uint32_t ta, uint32_t tb) const;
  Status inconsistent_vertex(uint32_t v) const;

  const Context& ctx_;
  Arena& arena_;
  Inputs in_;
  BooleanOp op_;
  BooleanOptions options_;
  BooleanStats& st_;

  const Broadphase& bp_;  // near B triangles and A's grid (all attempts)
  ArenaArray<Hit> hits_;
  uint32_t* hit_points_ = nullptr;  // 2 per hit: start, end point ids
  ArenaArray<Point> points_;
  // Per intersection point, the lowest-id point with the same (rounded) coordinates; null when
  // no two coincide (check_points_apart). A triangle whose points merge is split by split_cut
  // or split_general with the merged ids (CutSplit::merge_coincident).
  uint32_t* merge_ = nullptr;
  // Pairs of intersection points that coincide in the projection of a triangle they share
  // (distinct in 3-D by a rounding step along its normal), noted by a split that failed on
  // them; split_with_merges merges them and splits again. kMaxNoted: more is unsupported.
  static constexpr uint32_t kMaxNoted = 64;
  uint32_t noted_[kMaxNoted][2] = {};
  uint32_t n_noted_ = 0;
  bool noted_overflow_ = false;
  Record* rec_ = nullptr;      // 2 per hit
  KeyIndex* order_ = nullptr;  // records sorted by triangle
  ArenaArray<OutTri> tris_;    // pieces of cut triangles, by triangle id
  // Where the pieces begin: nothing the run keeps lies above them until assemble, which puts
  // its output there once they are written out.
  Arena::Marker pieces_at_;
  int8_t* vstate_ = nullptr;  // per input vertex: +1 inside the other, -1 outside,
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
  uint64_t pair_budget_ = ~uint64_t{0};
  Status unmerged_;  // unmerged_status()
};

enum TriangleFlag : uint8_t { kUncut = 0, kDecided = 1, kPending = 2 };

// Defined in the stage files.
EdgePlanes edge_planes(const Vec3& a0, const Vec3& a1, const Vec3& a2);
PairResult intersect_pair(const Inputs& in, uint32_t ta, uint32_t tb, const PlaneFilter& pa,
                          const EdgePlanes& ea, const PlaneFilter& pb, Hit* hit);
Point make_point(const Inputs& in, const PointKey& key);
// b_valid: B's indices are known to be in range and its vertices finite (not checked again).
Status build_broadphase(const Context& ctx, const Mesh& a, const Mesh& b, double reach,
                        bool float32_output, bool b_valid, Broadphase* bp);
// bp->a_slot and a_slot_count over nta triangles of A: a slot for each triangle the grid lists.
// Arena: 4 bytes per triangle of A (kept).
Status number_a_slots(Arena& arena, uint32_t nta, Broadphase* bp);
// Sets the bit (marked: one per grid cell) of every cell that the box of one of B's near
// triangles near_ids[begin, end) covers (the grid's lists; the hits' batches).
void mark_near_cells(const Broadphase& bp, const Mesh& b, size_t begin, size_t end,
                     uint64_t* marked);

}  // namespace boolean_detail
}  // namespace splintcore

#endif  // SPLINTCORE_SRC_BOOLEAN_BOOLEAN_RUN_H
