// Constrained Delaunay triangulation of one simple polygon with interior constraint segments
// (the re-triangulation step of the Boolean; the contract is in cdt.h).
//
// Sources:
//   C. L. Lawson, "Software for C1 surface interpolation", Mathematical Software III, 1977:
//     incremental insertion, each new point followed by edge flips back to Delaunay.
//   N. Amenta, S. Choi, G. Rote, "Incremental constructions con BRIO", SoCG 2003: insertion
//     in rounds of random samples, each round in space-filling-curve (Hilbert) order.
//   O. Devillers, S. Pion, M. Teillaud, "Walking in a triangulation", IJFCS 13(2), 2002:
//     the visibility walk for point location; it terminates in a Delaunay triangulation
//     (H. Edelsbrunner, "An acyclicity theorem for cell complexes in d dimensions", 1990).
//   S. W. Sloan, "A fast algorithm for generating constrained Delaunay triangulations",
//     Computers & Structures 47(3), 1993: a segment is inserted by flipping the edges that
//     cross it (each one whose quadrilateral is strictly convex), then the Delaunay property is
//     restored by flips.
//   L. P. Chew, "Constrained Delaunay triangulations", Algorithmica 4, 1989: a triangulation in
//     which every unconstrained edge is locally Delaunay is the constrained Delaunay one.
//   J. R. Shewchuk, predicates.cpp: every decision is an exact orient2d or incircle sign.
//   G. H. Meisters, "Polygons have ears", Amer. Math. Monthly 82(6), 1975, and J. O'Rourke,
//     "Computational Geometry in C", 2nd ed., 1998, section 1.6: ear clipping (the small path).
//
// Inputs of up to 32 points whose polygon is star-shaped from the mean of its corners take the
// small path ("the small path" below: the polygon ear-clipped, no super-triangle, no arena);
// the others, and every input the small path finds an error in, the general path.
//
// Steps of the general path:
//   1. Check the input (ids, closed boundary, coordinates), reserve the output, take the
//      temporaries (all sized up front from the point count).
//   2. A super-triangle whose corners are small multiples of a power of two R with
//      R > max |coordinate| (exact, and strictly around every point); insert the points, each
//      located by a walk from the previous one's triangle and followed by Lawson flips of the
//      edges opposite it. A point found on a vertex is a duplicate. Order: up to kBrioMin
//      points, the boundary in polygon order then the others as given; above, BRIO with a
//      fixed hash as the random source (deterministic). Points along the edges of the
//      Boolean's triangles are nearly collinear once rounded: inserted in order along the
//      line, each new point falls inside the huge circumcircles of the thin triangles before
//      it and the flips grow quadratically (10 ms for 1,500 points); in BRIO order they do
//      not (expected linear flips for any point set; 1.7 ms).
//   3. Insert the segments, boundary first: walk from a to b collecting the crossed edges (a
//      vertex on the open segment or a crossed constrained edge is an input error), flip them
//      away (Sloan), mark a-b, and restore the Delaunay property by flips of the unconstrained
//      edges of every triangle touched. Flips rather than the pseudo-polygon re-triangulation
//      (Anglada 1997): a segment may cross both triangles of an edge it does not cross (a
//      "hanging" edge, even the whole star of a vertex); flipping needs no special case for
//      that and never removes a constrained edge.
//   4. Flood-fill the exterior from a super-triangle corner across edges that are not boundary
//      segments; check the contract (counter-clockwise boundary, constraints and points
//      inside), emit the interior triangles (in triangle-slot order, each rotated to start at
//      its smallest id) and verify their number and orientation.
//
// Bounded work: every walk and rotation is capped by the triangle count; the flips of one
// segment insertion by 4 k^2 + 64 (k: edges crossed), and a full pass over the crossed edges
// without a flip is reported as an internal error rather than looping. Lawson flips terminate
// (each one strictly lowers the triangulation lifted to the paraboloid z = x^2 + y^2).

#include "boolean/cdt.h"

#include <cmath>

#include "geometry/incircle_stage_a.h"
#include "splintcore/geometry.h"

namespace splintcore {
namespace detail {

namespace {

constexpr uint32_t kNone = 0xffffffffu;

// Points beyond this are refused (the half-edge ids 3 * (2 n + 1) must fit in 32 bits, with
// room to spare).
constexpr uint64_t kMaxPoints = uint64_t{1} << 28;

// Nonzero coordinates must lie in [2^-200, 2^200]: the super-triangle's corners reach 4 R
// < 2^203, and incircle's exact range is [2^-216, 2^240] (predicates.cpp).
constexpr double kMinMagnitude = 0x1p-200;  // and 2^200 above: coordinate_ok()

// A coordinate in that range, or 0 (either sign), decided on the bit pattern: with the sign
// bit cleared, the patterns of non-negative doubles order as their values, and infinity and
// NaN lie above every finite one. (One unsigned compare does both bounds: below 2^-200 the
// difference wraps round to a huge value.)
inline bool coordinate_ok(double v) {
  uint64_t bits = 0;
  std::memcpy(&bits, &v, sizeof(bits));
  constexpr uint64_t kMinBits = uint64_t{1023 - 200} << 52;  // 2^-200
  constexpr uint64_t kMaxBits = uint64_t{1023 + 200} << 52;  // 2^200
  const uint64_t mag = bits & ~(uint64_t{1} << 63);
  return mag == 0 || mag - kMinBits <= kMaxBits - kMinBits;
}

// From this many points on, the insertion order is BRIO (below it the sort costs more than
// it saves).
constexpr uint32_t kBrioMin = 32;

struct Tri {
  uint32_t v[3];  // point ids, counter-clockwise
  uint32_t n[3];  // neighbour across the edge opposite v[i]; kNone outside the super-triangle
  uint32_t c[3];  // id of the segment lying on the edge opposite v[i], or kNone
};

struct EdgeKey {
  uint32_t a;
  uint32_t b;
};

inline uint32_t next3(uint32_t i) { return i == 2 ? 0 : i + 1; }
inline uint32_t prev3(uint32_t i) { return i == 0 ? 2 : i - 1; }

inline uint32_t index_of(const Tri& t, uint32_t v) {
  return t.v[0] == v ? 0 : (t.v[1] == v ? 1 : 2);
}

// The index in `t` of the vertex opposite the edge it shares with triangle `other`.
inline uint32_t index_facing(const Tri& t, uint32_t other) {
  return t.n[0] == other ? 0 : (t.n[1] == other ? 1 : 2);
}

struct Work {
  const CdtPoint* p = nullptr;  // the n input points, then the super-triangle's 3 corners
  uint32_t n = 0;
  Tri* t = nullptr;
  uint32_t tri_count = 0;
  uint32_t* vt = nullptr;     // a triangle holding each vertex
  uint32_t* stack = nullptr;  // 3 * triangle capacity entries
  uint32_t stack_size = 0;
  uint8_t* queued = nullptr;  // per triangle: bit i set while half-edge (t, i) is on the stack
  EdgeKey* queue = nullptr;   // ring of edges crossing the segment being inserted
  uint32_t queue_cap = 0;
  uint32_t queue_head = 0;
  uint32_t queue_size = 0;
};

// orient2d and incircle with their first filter inline (J. R. Shewchuk, "Adaptive precision
// floating-point arithmetic and fast robust geometric predicates", 1997, section 4.2: the
// stage A error bounds ccwerrboundA and iccerrboundA; incircle's is the predicate's own
// (incircle_stage_a.h), orient2d's the same computation, operation for operation, as the
// start of orient2d in predicates.cpp, with |.| summed first). When the rounded
// determinant clears the bound, its sign is exact and it is the very value the predicate
// returns; otherwise the predicate itself decides. So every sign, and every value, is the
// predicate's: only the call is saved on the clear cases (nearly all of the CDT's, whose
// calls are most of its work at 3..20 points). Valid in the predicates' ranges (cdt.h).
constexpr double kEps = 0x1p-53;  // half an ulp of 1
constexpr double kCcwErrBoundA = (3.0 + 16.0 * kEps) * kEps;

// |v| (std::fabs: one and-not of the sign bit, where the comparison costs a branch; for -0 it
// gives +0 where predicates.cpp's gives -0, which moves no bound: both compare alike).
inline double magnitude(double v) { return std::fabs(v); }

inline double orient_filtered(const CdtPoint& a, const CdtPoint& b, const CdtPoint& c) {
  const double detleft = (a.x - c.x) * (b.y - c.y);
  const double detright = (a.y - c.y) * (b.x - c.x);
  const double det = detleft - detright;
  // orient2d's detsum: |detleft| + |detright| (it returns det at once when the signs differ or
  // detleft is 0; then |det| >= detsum (1 - eps) clears the bound here too, or det is 0 and
  // orient2d returns 0).
  const double errbound = kCcwErrBoundA * (magnitude(detleft) + magnitude(detright));
  if (det > errbound || -det > errbound) return det;
  return orient2d(a.x, a.y, b.x, b.y, c.x, c.y);
}

inline double orient(const Work& w, uint32_t a, uint32_t b, uint32_t c) {
  return orient_filtered(w.p[a], w.p[b], w.p[c]);
}

// > 0 when point d is strictly inside the circumcircle of triangle t.
inline double in_circle(const Work& w, const Tri& t, uint32_t d) {
  const CdtPoint& a = w.p[t.v[0]];
  const CdtPoint& b = w.p[t.v[1]];
  const CdtPoint& c = w.p[t.v[2]];
  const CdtPoint& e = w.p[d];
  const detail::IncircleStageA stage =
      detail::incircle_stage_a(a.x, a.y, b.x, b.y, c.x, c.y, e.x, e.y);
  if (stage.certain()) return stage.det;
  return incircle(a.x, a.y, b.x, b.y, c.x, c.y, e.x, e.y);
}

void put(Work& w, uint32_t ti, uint32_t a, uint32_t b, uint32_t c, uint32_t na, uint32_t nb,
         uint32_t nc, uint32_t ca, uint32_t cb, uint32_t cc) {
  Tri& t = w.t[ti];
  t.v[0] = a;
  t.v[1] = b;
  t.v[2] = c;
  t.n[0] = na;
  t.n[1] = nb;
  t.n[2] = nc;
  t.c[0] = ca;
  t.c[1] = cb;
  t.c[2] = cc;
  w.vt[a] = ti;
  w.vt[b] = ti;
  w.vt[c] = ti;
}

// In triangle `ti` (when there is one), the edge it shares with `old` (which ran from x to y
// in ti) gets neighbour `nb` instead. Two triangles share at most one edge, so the edge is the
// one whose neighbour is `old`; x and y only check it.
void link(Work& w, uint32_t ti, uint32_t old, uint32_t x, uint32_t y, uint32_t nb) {
  if (ti == kNone) return;
  Tri& t = w.t[ti];
  const uint32_t k = index_facing(t, old);
  if (t.n[k] != old || t.v[next3(k)] != x || t.v[prev3(k)] != y) {
    assert_failed("cdt: neighbour links out of step", __FILE__, __LINE__);
  }
  t.n[k] = nb;
}

// Flips the edge opposite v[e] of triangle t1 (t1 = (r, p, q) from e, its neighbour (s, q, p)):
// afterwards t1 = (r, p, s) and the neighbour t2 = (s, q, r). The caller has checked that
// both are counter-clockwise and that the edge is not constrained. Returns t2.
uint32_t flip(Work& w, uint32_t t1, uint32_t e) {
  const Tri a = w.t[t1];
  const uint32_t e1 = next3(e);
  const uint32_t e2 = prev3(e);
  const uint32_t r = a.v[e];
  const uint32_t p = a.v[e1];
  const uint32_t q = a.v[e2];
  const uint32_t t2 = a.n[e];
  const Tri b = w.t[t2];
  const uint32_t j = index_facing(b, t1);
  const uint32_t j1 = next3(j);  // b.v[j1] == q
  const uint32_t j2 = prev3(j);  // b.v[j2] == p
  const uint32_t s = b.v[j];
  SPLINTCORE_ASSERT(a.c[e] == kNone && b.v[j1] == q && b.v[j2] == p);
  // Outer edges: (q, r) = a opposite p, (r, p) = a opposite q, (p, s) = b opposite q,
  // (s, q) = b opposite p.
  put(w, t1, r, p, s, b.n[j1], t2, a.n[e2], b.c[j1], kNone, a.c[e2]);
  put(w, t2, s, q, r, a.n[e1], t1, b.n[j2], a.c[e1], kNone, b.c[j2]);
  link(w, b.n[j1], t2, s, p, t1);
  link(w, a.n[e1], t1, r, q, t2);
  return t2;
}

// ---- point insertion ------------------------------------------------------------------------

// Splits triangle ti at the point strictly inside it; the three new triangles go on the stack.
void split_triangle(Work& w, uint32_t ti, uint32_t pid) {
  const Tri t = w.t[ti];
  const uint32_t tb = w.tri_count++;
  const uint32_t tc = w.tri_count++;
  const uint32_t v0 = t.v[0], v1 = t.v[1], v2 = t.v[2];
  put(w, ti, v1, v2, pid, tb, tc, t.n[0], kNone, kNone, t.c[0]);
  put(w, tb, v2, v0, pid, tc, ti, t.n[1], kNone, kNone, t.c[1]);
  put(w, tc, v0, v1, pid, ti, tb, t.n[2], kNone, kNone, t.c[2]);
  link(w, t.n[1], ti, v0, v2, tb);
  link(w, t.n[2], ti, v1, v0, tc);
  w.stack[w.stack_size++] = ti;
  w.stack[w.stack_size++] = tb;
  w.stack[w.stack_size++] = tc;
}

// Splits the edge opposite v[k] of triangle ti (and the neighbour across it) at the point
// lying on it; the four new triangles go on the stack.
void split_edge(Work& w, uint32_t ti, uint32_t k, uint32_t pid) {
  const Tri t = w.t[ti];
  const uint32_t a0 = t.v[k], a1 = t.v[next3(k)], a2 = t.v[prev3(k)];
  const uint32_t ui = t.n[k];
  const Tri u = w.t[ui];
  const uint32_t j = index_facing(u, ti);
  const uint32_t d = u.v[j];  // u = (d, a2, a1) from j
  SPLINTCORE_ASSERT(t.c[k] == kNone && u.v[next3(j)] == a2 && u.v[prev3(j)] == a1);
  const uint32_t n_a0a1 = t.n[prev3(k)], c_a0a1 = t.c[prev3(k)];
  const uint32_t n_a2a0 = t.n[next3(k)], c_a2a0 = t.c[next3(k)];
  const uint32_t n_a1d = u.n[next3(j)], c_a1d = u.c[next3(j)];
  const uint32_t n_da2 = u.n[prev3(j)], c_da2 = u.c[prev3(j)];
  const uint32_t t2 = w.tri_count++;
  const uint32_t u2 = w.tri_count++;
  put(w, ti, a0, a1, pid, ui, t2, n_a0a1, kNone, kNone, c_a0a1);
  put(w, t2, a2, a0, pid, ti, u2, n_a2a0, kNone, kNone, c_a2a0);
  put(w, ui, a1, d, pid, u2, ti, n_a1d, kNone, kNone, c_a1d);
  put(w, u2, d, a2, pid, t2, ui, n_da2, kNone, kNone, c_da2);
  link(w, n_a2a0, ti, a0, a2, t2);
  link(w, n_da2, ui, a2, d, u2);
  w.stack[w.stack_size++] = ti;
  w.stack[w.stack_size++] = t2;
  w.stack[w.stack_size++] = ui;
  w.stack[w.stack_size++] = u2;
}

// Lawson flips after inserting pid: the stack holds triangles incident to pid whose edge
// opposite pid may not be locally Delaunay (each triangle at most once: a flip replaces the
// popped one and its neighbour, which was not incident to pid, by two incident ones).
void legalize_around(Work& w, uint32_t pid) {
  while (w.stack_size > 0) {
    const uint32_t ti = w.stack[--w.stack_size];
    const Tri& t = w.t[ti];
    const uint32_t i = index_of(t, pid);
    const uint32_t nb = t.n[i];
    if (nb == kNone || t.c[i] != kNone) continue;
    const Tri& u = w.t[nb];
    const uint32_t d = u.v[index_facing(u, ti)];
    if (in_circle(w, t, d) > 0.0) {
      const uint32_t t2 = flip(w, ti, i);
      w.stack[w.stack_size++] = ti;
      w.stack[w.stack_size++] = t2;
    }
  }
}

// Triangle (closed) holding point pid, found by a visibility walk from `start` (capped by the
// triangle count, then a scan). `zero_mask` bit k: pid is on the line of edge k.
bool locate(const Work& w, uint32_t pid, uint32_t start, uint32_t* tri, uint32_t* zero_mask) {
  uint32_t ti = start;
  uint32_t from = kNone;
  for (uint32_t step = 0; step <= w.tri_count; ++step) {
    const Tri& t = w.t[ti];
    uint32_t mask = 0;
    // Edge k (from a to b): true when pid is strictly outside it. The edge the walk came
    // through is skipped: pid is strictly inside it. (Edges 0, 1, 2 in turn, written out.)
    auto outside_edge = [&](uint32_t k, uint32_t a, uint32_t b) {
      if (from != kNone && t.n[k] == from) return false;
      const double o = orient(w, a, b, pid);
      if (o < 0.0) return true;
      if (o == 0.0) mask |= 1u << k;
      return false;
    };
    uint32_t exit_edge = 0;
    if (outside_edge(0, t.v[1], t.v[2])) {
      exit_edge = 0;
    } else if (outside_edge(1, t.v[2], t.v[0])) {
      exit_edge = 1;
    } else if (outside_edge(2, t.v[0], t.v[1])) {
      exit_edge = 2;
    } else {
      *tri = ti;
      *zero_mask = mask;
      return true;
    }
    const uint32_t next = t.n[exit_edge];
    if (next == kNone) break;  // out of the super-triangle: impossible, it holds every point
    from = ti;
    ti = next;
  }
  for (uint32_t ti2 = 0; ti2 < w.tri_count; ++ti2) {
    const Tri& t = w.t[ti2];
    uint32_t mask = 0;
    bool inside = true;
    for (uint32_t k = 0; k < 3 && inside; ++k) {
      const double o = orient(w, t.v[next3(k)], t.v[prev3(k)], pid);
      inside = o >= 0.0;
      if (o == 0.0) mask |= 1u << k;
    }
    if (inside) {
      *tri = ti2;
      *zero_mask = mask;
      return true;
    }
  }
  return false;
}

Status insert_point(Work& w, uint32_t pid, uint32_t start) {
  uint32_t ti = 0;
  uint32_t mask = 0;
  if (!locate(w, pid, start, &ti, &mask)) {
    return make_error(StatusCode::kInternal, "cdt: point ", pid, " not located");
  }
  if (mask == 0) {
    split_triangle(w, ti, pid);
  } else if (mask == 1 || mask == 2 || mask == 4) {
    split_edge(w, ti, mask == 1 ? 0 : (mask == 2 ? 1 : 2), pid);
  } else {
    // On two edge lines: at their common vertex.
    const uint32_t k = mask == 3 ? 2 : (mask == 5 ? 1 : 0);
    const uint32_t other = w.t[ti].v[k];
    const uint32_t lo = other < pid ? other : pid;
    const uint32_t hi = other < pid ? pid : other;
    return make_error(StatusCode::kInvalidArgument, "cdt: points ", lo, " and ", hi, " coincide (",
                      w.p[pid].x, ", ", w.p[pid].y, ")")
        .at_index(hi);
  }
  legalize_around(w, pid);
  return Status::ok();
}

// ---- segment insertion ----------------------------------------------------------------------

// A triangle holding the edge x-y, and the index of its third vertex. x must be an input
// point. Its star is closed in the general path (it lies strictly inside the super-triangle);
// in the small path (no super-triangle) a vertex on the polygon has an open star: the turn
// counter-clockwise then ends at the polygon's edge, and the search goes on clockwise from
// where it started.
bool find_edge(const Work& w, uint32_t x, uint32_t y, uint32_t* tri, uint32_t* third) {
  const uint32_t first = w.vt[x];
  uint32_t ti = first;
  bool clockwise = false;
  for (uint32_t step = 0; step < 2 * w.tri_count; ++step) {
    const Tri& t = w.t[ti];
    const uint32_t i = index_of(t, x);
    if (t.v[next3(i)] == y) {
      *tri = ti;
      *third = prev3(i);
      return true;
    }
    if (t.v[prev3(i)] == y) {
      *tri = ti;
      *third = next3(i);
      return true;
    }
    // The next triangle counter-clockwise around x (clockwise on the way back).
    ti = clockwise ? t.n[prev3(i)] : t.n[next3(i)];
    if (ti == first) return false;
    if (ti == kNone) {
      if (clockwise) return false;
      clockwise = true;
      const Tri& f = w.t[first];
      ti = f.n[prev3(index_of(f, x))];
      if (ti == kNone) return false;
    }
  }
  return false;
}

// Marks the edge opposite v[k] of triangle ti (both sides) as segment s, unless a segment
// already lies there (a repeated segment keeps the first id).
void constrain(Work& w, uint32_t ti, uint32_t k, uint32_t s) {
  Tri& t = w.t[ti];
  if (t.c[k] != kNone) return;
  t.c[k] = s;
  const uint32_t nb = t.n[k];
  if (nb != kNone) w.t[nb].c[index_facing(w.t[nb], ti)] = s;
}

// For x on the line through a and b (x != a): is x on the same side of a as b?
inline bool ahead(const Work& w, uint32_t a, uint32_t x, uint32_t b) {
  const CdtPoint& pa = w.p[a];
  const CdtPoint& px = w.p[x];
  const CdtPoint& pb = w.p[b];
  if (px.x != pa.x) return (px.x > pa.x) == (pb.x > pa.x);
  return (px.y > pa.y) == (pb.y > pa.y);
}

Status on_segment_error(const Work& w, uint32_t x, uint32_t s, uint32_t a, uint32_t b) {
  if (x >= w.n) return make_error(StatusCode::kInternal, "cdt: segment ", s, " meets the frame");
  return make_error(StatusCode::kInvalidArgument, "cdt: point ", x, " lies on segment ", s,
                    " (points ", a, "-", b, ") but is not one of its ends")
      .at_index(s);
}

Status crossing_error(uint32_t s, uint32_t other) {
  const uint32_t lo = s < other ? s : other;
  const uint32_t hi = s < other ? other : s;
  return make_error(StatusCode::kInvalidArgument, "cdt: segments ", lo, " and ", hi, " cross")
      .at_index(hi);
}

void enqueue(Work& w, uint32_t a, uint32_t b) {
  SPLINTCORE_ASSERT(w.queue_size < w.queue_cap);
  uint32_t at = w.queue_head + w.queue_size;
  if (at >= w.queue_cap) at -= w.queue_cap;
  w.queue[at] = EdgeKey{a, b};
  ++w.queue_size;
}

EdgeKey dequeue(Work& w) {
  const EdgeKey e = w.queue[w.queue_head];
  ++w.queue_head;
  if (w.queue_head == w.queue_cap) w.queue_head = 0;
  --w.queue_size;
  return e;
}

void push_half_edge(Work& w, uint32_t ti, uint32_t i) {
  const uint8_t bit = static_cast<uint8_t>(1u << i);
  if ((w.queued[ti] & bit) != 0) return;
  w.queued[ti] = static_cast<uint8_t>(w.queued[ti] | bit);
  w.stack[w.stack_size++] = ti * 3 + i;
}

void push_triangle_edges(Work& w, uint32_t ti) {
  push_half_edge(w, ti, 0);
  push_half_edge(w, ti, 1);
  push_half_edge(w, ti, 2);
}

// Lawson flips of the unconstrained edges on the half-edge stack until all are locally
// Delaunay (a flip puts the edges of both new triangles back on the stack).
//
// The new diagonal of the latest flip (edge 1 of both its triangles, flip()) is locally
// Delaunay, strictly: with s strictly inside the circle through r, p, q, the determinant of
// (r, p, s; q) and of (s, q, r; p) is that of (r, p, q; s) with its rows permuted oddly, so
// both incircle signs are < 0 exactly. Until the next flip rewrites those two slots the edge
// keeps its four points, and its test (no flip) is skipped: the same stack, the same flips.
void legalize_edges(Work& w) {
  uint32_t fresh1 = kNone;  // the latest flip's two triangles
  uint32_t fresh2 = kNone;
  while (w.stack_size > 0) {
    const uint32_t he = w.stack[--w.stack_size];
    const uint32_t ti = he / 3;
    const uint32_t i = he % 3;
    w.queued[ti] = static_cast<uint8_t>(w.queued[ti] & ~(1u << i));
    if (i == 1 && (ti == fresh1 || ti == fresh2)) continue;
    const Tri& t = w.t[ti];
    const uint32_t nb = t.n[i];
    if (nb == kNone || t.c[i] != kNone) continue;
    const Tri& u = w.t[nb];
    const uint32_t d = u.v[index_facing(u, ti)];
    if (in_circle(w, t, d) > 0.0) {
      const uint32_t t2 = flip(w, ti, i);
      push_triangle_edges(w, ti);
      push_triangle_edges(w, t2);
      fresh1 = ti;
      fresh2 = t2;
    }
  }
}

// Where the walk along a-b starts: the triangle ti = (a, p, q), a at index i, whose open wedge
// at a holds b.
struct Wedge {
  uint32_t ti, i, p, q;
};

// 1. Around a: the edge a-b (then marked, and *done set), or the triangle (a, p, q) whose open
// wedge at a holds b (counter-clockwise from vt[a]; when a's star is open, as on the small
// path's polygon, on clockwise from vt[a] once the turn reaches the polygon's edge).
Status find_wedge(Work& w, uint32_t s, uint32_t a, uint32_t b, Wedge* wedge, bool* done) {
  uint32_t ti = w.vt[a];
  bool clockwise = false;
  for (uint32_t step = 0;; ++step) {
    if (ti == kNone && !clockwise) {
      clockwise = true;
      const Tri& f = w.t[w.vt[a]];
      ti = f.n[prev3(index_of(f, a))];
    }
    if (step > 2 * w.tri_count || ti == kNone) {
      return make_error(StatusCode::kInternal, "cdt: no way out of point ", a);
    }
    const Tri& t = w.t[ti];
    const uint32_t i = index_of(t, a);
    const uint32_t p = t.v[next3(i)];
    const uint32_t q = t.v[prev3(i)];
    if (p == b || q == b) {
      constrain(w, ti, p == b ? prev3(i) : next3(i), s);
      *done = true;
      return Status::ok();
    }
    const double op = orient(w, a, p, b);
    if (op == 0.0 && ahead(w, a, p, b)) return on_segment_error(w, p, s, a, b);
    const double oq = orient(w, a, q, b);
    if (oq == 0.0 && ahead(w, a, q, b)) return on_segment_error(w, q, s, a, b);
    if (op > 0.0 && oq < 0.0) {
      *wedge = Wedge{ti, i, p, q};
      return Status::ok();
    }
    ti = clockwise ? t.n[prev3(i)] : t.n[next3(i)];  // counter-clockwise around a (or back)
  }
}

// 2. Walk to b from `start`: the crossed edges onto the queue, each (right end, left end) seen
// from a towards b.
Status queue_crossed_edges(Work& w, uint32_t s, uint32_t a, uint32_t b, const Wedge& start) {
  w.queue_head = 0;
  w.queue_size = 0;
  uint32_t cur = start.ti;
  uint32_t e = start.i;  // the edge p-q of cur, cur running p -> q
  uint32_t p = start.p;
  uint32_t q = start.q;
  for (uint32_t step = 0;; ++step) {
    const Tri& t = w.t[cur];
    if (t.c[e] != kNone) return crossing_error(s, t.c[e]);
    const uint32_t nb = t.n[e];
    if (step > w.tri_count || nb == kNone || w.queue_size == w.queue_cap) {
      return make_error(StatusCode::kInternal, "cdt: lost walking along segment ", s);
    }
    enqueue(w, p, q);
    const Tri& u = w.t[nb];
    const uint32_t k = index_facing(u, cur);  // u = (x, q, p) from k
    const uint32_t x = u.v[k];
    if (x == b) return Status::ok();
    const double o = orient(w, a, b, x);
    if (o == 0.0) return on_segment_error(w, x, s, a, b);
    if (o < 0.0) {
      p = x;
      e = prev3(k);
    } else {
      q = x;
      e = next3(k);
    }
    cur = nb;
  }
}

// 3. Flip the crossed edges away (Sloan): one whose quadrilateral is strictly convex is
// flipped, and its new diagonal queued again if it still crosses; otherwise it waits.
Status flip_crossed_edges(Work& w, uint32_t s, uint32_t a, uint32_t b) {
  const uint64_t crossed = w.queue_size;
  const uint64_t flip_cap = 4 * crossed * crossed + 64;
  uint64_t flips = 0;
  uint32_t idle = 0;
  while (w.queue_size > 0) {
    const EdgeKey edge = dequeue(w);
    const uint32_t x = edge.a < w.n ? edge.a : edge.b;
    const uint32_t y = edge.a < w.n ? edge.b : edge.a;
    uint32_t t1 = 0;
    uint32_t r_at = 0;
    if (!find_edge(w, x, y, &t1, &r_at)) {
      return make_error(StatusCode::kInternal, "cdt: crossed edge lost (segment ", s, ")");
    }
    const Tri& t = w.t[t1];
    const uint32_t r = t.v[r_at];
    const uint32_t tp = t.v[next3(r_at)];
    const uint32_t tq = t.v[prev3(r_at)];
    const Tri& u = w.t[t.n[r_at]];
    const uint32_t sv = u.v[index_facing(u, t1)];
    if (orient(w, r, tp, sv) > 0.0 && orient(w, sv, tq, r) > 0.0) {
      const uint32_t t2 = flip(w, t1, r_at);
      push_triangle_edges(w, t1);
      push_triangle_edges(w, t2);
      if (++flips > flip_cap) {
        return make_error(StatusCode::kInternal, "cdt: too many flips inserting segment ", s);
      }
      idle = 0;
      const double o_r = orient(w, a, b, r);
      const double o_s = orient(w, a, b, sv);
      if ((o_r > 0.0 && o_s < 0.0) || (o_r < 0.0 && o_s > 0.0)) enqueue(w, r, sv);
    } else {
      enqueue(w, edge.a, edge.b);
      if (++idle > w.queue_size) {
        return make_error(StatusCode::kInternal, "cdt: no flippable edge inserting segment ", s);
      }
    }
  }
  return Status::ok();
}

Status insert_segment(Work& w, uint32_t s, uint32_t a, uint32_t b) {
  // 0. Already an edge (nearly always on the Boolean's cut triangles, whose segments are
  // mostly Delaunay edges of their points): found by ids alone, no predicate. The search in 1
  // would have marked the same edge: when a-b is an edge, no other neighbour of a lies on the
  // ray from a through b (it would put b inside an edge) and no triangle's open wedge at a
  // holds b, so it meets neither an error nor a break before it finds a-b; and marking either
  // side of the edge marks both.
  uint32_t tab = 0;
  uint32_t third = 0;
  if (find_edge(w, a, b, &tab, &third)) {
    constrain(w, tab, third, s);
    return Status::ok();
  }
  Wedge wedge{};
  bool done = false;
  SPLINTCORE_RETURN_IF_ERROR(find_wedge(w, s, a, b, &wedge, &done));
  if (done) return Status::ok();
  SPLINTCORE_RETURN_IF_ERROR(queue_crossed_edges(w, s, a, b, wedge));
  SPLINTCORE_RETURN_IF_ERROR(flip_crossed_edges(w, s, a, b));
  // 4. Mark a-b, then restore the Delaunay property around it.
  if (!find_edge(w, a, b, &tab, &third)) {
    return make_error(StatusCode::kInternal, "cdt: segment ", s, " missing after its flips");
  }
  constrain(w, tab, third, s);
  legalize_edges(w);
  return Status::ok();
}

// The smallest power of two above every |coordinate| (1 when all are zero).
double frame_scale(Span<const CdtPoint> points) {
  double m = 0.0;
  for (const CdtPoint& pt : points) {
    const double ax = pt.x < 0 ? -pt.x : pt.x;
    const double ay = pt.y < 0 ? -pt.y : pt.y;
    if (ax > m) m = ax;
    if (ay > m) m = ay;
  }
  if (m == 0.0) return 1.0;
  uint64_t bits = 0;
  std::memcpy(&bits, &m, sizeof(bits));
  // m is normal (>= 2^-200): 2^(exponent + 1) > m.
  const uint64_t exponent = (bits >> 52) & 0x7ffu;
  const uint64_t scale_bits = (exponent + 1) << 52;
  double scale = 0.0;
  std::memcpy(&scale, &scale_bits, sizeof(scale));
  return scale;
}

// Position along a Hilbert curve of the point (x, y) of a 2^16 x 2^16 grid.
uint32_t hilbert_index(uint32_t x, uint32_t y) {
  uint32_t d = 0;
  for (uint32_t s = 1u << 15; s > 0; s >>= 1) {
    const uint32_t rx = (x & s) != 0 ? 1u : 0u;
    const uint32_t ry = (y & s) != 0 ? 1u : 0u;
    d += s * s * ((3u * rx) ^ ry);
    if (ry == 0) {
      if (rx == 1) {
        x = 0xffffu - x;
        y = 0xffffu - y;
      }
      const uint32_t swap = x;
      x = y;
      y = swap;
    }
  }
  return d;
}

// The BRIO insertion order of the n points: round r holds the points whose hash has
// R - r leading zero bits (R - r or more for round 0), so each round is about as large as all
// before it; within a round, Hilbert order on the bounding box.
void brio_order(Span<const CdtPoint> points, KeyIndex* keys, KeyIndex* scratch) {
  const size_t n = points.size();
  double lo_x = points[0].x, hi_x = lo_x, lo_y = points[0].y, hi_y = lo_y;
  for (const CdtPoint& pt : points) {
    lo_x = pt.x < lo_x ? pt.x : lo_x;
    hi_x = pt.x > hi_x ? pt.x : hi_x;
    lo_y = pt.y < lo_y ? pt.y : lo_y;
    hi_y = pt.y > hi_y ? pt.y : hi_y;
  }
  // Cells per unit; the differences are below 2^201, so nothing overflows.
  const double sx = hi_x > lo_x ? 65535.0 / (hi_x - lo_x) : 0.0;
  const double sy = hi_y > lo_y ? 65535.0 / (hi_y - lo_y) : 0.0;
  uint32_t rounds = 0;
  while ((size_t{1} << rounds) < n) ++rounds;
  for (size_t i = 0; i < n; ++i) {
    double fx = (points[i].x - lo_x) * sx;
    double fy = (points[i].y - lo_y) * sy;
    fx = fx < 0.0 ? 0.0 : (fx > 65535.0 ? 65535.0 : fx);
    fy = fy < 0.0 ? 0.0 : (fy > 65535.0 ? 65535.0 : fy);
    const uint64_t h = hash_mix(uint64_t{i} + 0x9e3779b97f4a7c15ull);
    const uint32_t zeros = h == 0 ? 64u : static_cast<uint32_t>(__builtin_clzll(h));
    const uint32_t round = rounds - (zeros < rounds ? zeros : rounds);
    keys[i] = KeyIndex{(uint64_t{round} << 32) |
                           hilbert_index(static_cast<uint32_t>(fx), static_cast<uint32_t>(fy)),
                       static_cast<uint32_t>(i), 0};
  }
  if (n > 256) {
    radix_sort(Span<KeyIndex>(keys, n), Span<KeyIndex>(scratch, n));
    return;
  }
  // Few keys: insertion sort (stable, as the radix sort; its 8 passes over 256 buckets would
  // cost more than the sorting).
  for (size_t i = 1; i < n; ++i) {
    const KeyIndex item = keys[i];
    size_t j = i;
    for (; j > 0 && keys[j - 1].key > item.key; --j) keys[j] = keys[j - 1];
    keys[j] = item;
  }
}

// ---- the output ----------------------------------------------------------------------------

// Writes the slots not marked in `exterior`, in slot order, each rotated
// to start at its smallest id, into the room `out` (and `adjacency`) reserved for `expected`
// more triangles; index_of_slot: tri_count entries of scratch. False, with `out` and
// `adjacency` cut back to their sizes and *bad set, when a triangle is not counter-clockwise
// (a bug: never in the tests).
bool write_output(const Work& w, const uint8_t* exterior, uint32_t* index_of_slot,
                  uint64_t expected, ArenaArray<CdtTriangle>* out,
                  ArenaArray<CdtAdjacency>* adjacency, CdtTriangle* bad) {
  // Every element below `expected` is written (or the sizes are cut back): the arrays take
  // their new sizes over the reserved room without zeroing it first.
  const size_t out_start = out->size();
  const size_t adjacency_start = adjacency != nullptr ? adjacency->size() : 0;
  SPLINTCORE_ASSERT(out->capacity() - out_start >= expected);  // reserved by the caller
  out->adopt(out->data(), out_start + static_cast<size_t>(expected), out->capacity());
  CdtTriangle* out_tri = out->data() + out_start;
  CdtAdjacency* out_adj = nullptr;
  if (adjacency != nullptr) {
    SPLINTCORE_ASSERT(adjacency->capacity() - adjacency_start >= expected);
    adjacency->adopt(adjacency->data(), adjacency_start + static_cast<size_t>(expected),
                     adjacency->capacity());
    out_adj = adjacency->data() + adjacency_start;
    // Output index of each inside slot.
    uint32_t count = 0;
    for (uint32_t ti = 0; ti < w.tri_count; ++ti) {
      index_of_slot[ti] = exterior[ti] != 0 ? kCdtNone : count++;
    }
  }
  // The slot's edge opposite t.v[kOpposite[k][e]] is edge e of the triangle rotated by k.
  static constexpr uint8_t kOpposite[3][3] = {{2, 0, 1}, {0, 1, 2}, {1, 2, 0}};
  size_t produced = 0;
  for (uint32_t ti = 0; ti < w.tri_count; ++ti) {
    if (exterior[ti] != 0) continue;
    const Tri& t = w.t[ti];
    const uint32_t k = t.v[0] < t.v[1] ? (t.v[0] < t.v[2] ? 0 : 2) : (t.v[1] < t.v[2] ? 1 : 2);
    const CdtTriangle tri{{t.v[k], t.v[next3(k)], t.v[prev3(k)]}};
    if (orient(w, tri.v[0], tri.v[1], tri.v[2]) <= 0.0) {
      out->shrink_size(out_start);
      if (adjacency != nullptr) adjacency->shrink_size(adjacency_start);
      *bad = tri;
      return false;
    }
    out_tri[produced] = tri;
    if (out_adj != nullptr) {
      // Per output triangle (rotated by k from its slot) the edge v[e] -> v[e + 1], which is
      // the slot's edge opposite t.v[(k + e + 2) % 3].
      CdtAdjacency& a = out_adj[produced];
      for (uint32_t e = 0; e < 3; ++e) {
        const uint32_t o = kOpposite[k][e];  // (k + e + 2) % 3
        const uint32_t nb = t.n[o];
        a.nb[e] = nb == kNone ? kCdtNone : index_of_slot[nb];
        a.seg[e] = t.c[o] == kNone ? kCdtNone : t.c[o];
      }
    }
    ++produced;
  }
  return true;
}

// write_output() for the small path, whose slots are all inside: the same triangles, rotations
// and adjacency (a neighbour's output index is its slot; kNone is kCdtNone), written into the
// room reserved for them. Without write_output()'s orientation check: every triangle of the
// small path is counter-clockwise by its construction, each step deciding on the exact
// predicates: an ear's corner turns strictly left (orient2d > 0; the last triangle is
// checked); a split point is strictly inside its triangle (three orient2d > 0) or strictly
// inside an edge (orient2d = 0 there, > 0 on the other two); a Lawson flip has its fourth
// point strictly inside the circumcircle (incircle > 0) and across the edge, which puts it
// strictly left of both new edges; a Sloan flip checks both new triangles (orient2d > 0). The
// property tests hold every result against the general path, which keeps the check.
static_assert(kNone == kCdtNone, "the slots' kNone is the output's kCdtNone");
void write_small_output(const Work& w, ArenaArray<CdtTriangle>* out,
                        ArenaArray<CdtAdjacency>* adjacency) {
  const size_t count = w.tri_count;
  const size_t out_start = out->size();
  SPLINTCORE_ASSERT(out->capacity() - out_start >= count);  // reserved by the caller
  CdtTriangle* out_tri = out->data() + out_start;
  CdtAdjacency* out_adj = nullptr;
  if (adjacency != nullptr) {
    SPLINTCORE_ASSERT(adjacency->capacity() - adjacency->size() >= count);
    out_adj = adjacency->data() + adjacency->size();
    adjacency->adopt(adjacency->data(), adjacency->size() + count, adjacency->capacity());
  }
  out->adopt(out->data(), out_start + count, out->capacity());
  for (uint32_t ti = 0; ti < w.tri_count; ++ti) {
    const Tri& t = w.t[ti];
    const uint32_t k = t.v[0] < t.v[1] ? (t.v[0] < t.v[2] ? 0 : 2) : (t.v[1] < t.v[2] ? 1 : 2);
    const uint32_t k1 = next3(k), k2 = prev3(k);
    out_tri[ti] = CdtTriangle{{t.v[k], t.v[k1], t.v[k2]}};
    // Rotated by k from its slot: the edge v[e] -> v[e + 1] is the slot's edge opposite
    // t.v[(k + e + 2) % 3].
    if (out_adj != nullptr) {
      out_adj[ti] = CdtAdjacency{{t.n[k2], t.n[k], t.n[k1]}, {t.c[k2], t.c[k], t.c[k1]}};
    }
  }
}

// ---- the small path ------------------------------------------------------------------------
//
// Up to kSmallMaxPoints points (the Boolean's cut triangles: 98% have 10 or fewer, nearly all
// the rest fewer than 32), with all of its memory on the stack (4.7 KB). The general path
// spends most of its time outside the polygon (the super-triangle's triangles, half of all,
// each inserted point flipped against them, the flood of the exterior, the checks); this one
// starts from a triangulation of the polygon:
//   1. The polygon must be star-shaped from the mean O of its corners, winding once: every edge
//      has O strictly on its left (orient2d), and going round, the sign of y - O.y changes
//      exactly twice (the corners turn about O by less than pi at each step, so a turn once
//      round changes it twice and k turns 2 k times). Such a polygon is simple and
//      counter-clockwise (each ray from O meets it once). Otherwise: the general path.
//   2. Ear clipping (G. H. Meisters, "Polygons have ears", Amer. Math. Monthly 82, 1975): a
//      corner that turns strictly left and whose closed triangle holds no other corner that
//      does not (only such a corner can lie in it: J. O'Rourke, "Computational Geometry in C",
//      2nd ed., 1998, section 1.6); its diagonal is a new edge of the rest.
//   3. Lawson flips of every edge until all are locally Delaunay: the constrained Delaunay
//      triangulation of the polygon (Chew 1989).
//   4. The other points, each located (walk, then a scan) and inserted with Lawson flips of
//      the edges opposite it (the polygon's edges are never flipped: that keeps it constrained
//      Delaunay); then the interior segments as in the general path (Sloan).
// Anything the contract calls an error (a point outside or on the boundary, a duplicate,
// crossing segments, ...) sends the input to the general path, which reports it. The result
// is the constrained Delaunay triangulation of the same input, the same triangles as the
// general path's but for ties (four cocircular points), in this path's slot order.

constexpr uint32_t kSmallMaxPoints = 32;
constexpr uint32_t kSmallMaxTris = 2 * kSmallMaxPoints;

// 1. Star-shaped from O, the mean of its corners, winding once (see above); poly: the b
// corners' point ids in boundary order.
bool star_shaped(const CdtPoint* p, const uint32_t* poly, uint32_t b) {
  double ox = 0.0, oy = 0.0;
  for (uint32_t s = 0; s < b; ++s) {
    ox += p[poly[s]].x;
    oy += p[poly[s]].y;
  }
  ox = ox / b;
  oy = oy / b;
  // O enters orient2d: keep it in the coordinates' range (exact signs).
  const double aox = ox < 0 ? -ox : ox, aoy = oy < 0 ? -oy : oy;
  if ((ox != 0.0 && aox < kMinMagnitude) || (oy != 0.0 && aoy < kMinMagnitude)) return false;
  const CdtPoint centre{ox, oy};
  int first_sign = 0, last_sign = 0, changes = 0;
  for (uint32_t s = 0; s < b; ++s) {
    const CdtPoint& u = p[poly[s]];
    const CdtPoint& v = p[poly[s + 1 == b ? 0 : s + 1]];
    if (orient_filtered(centre, u, v) <= 0.0) return false;
    const int sign = u.y > oy ? 1 : (u.y < oy ? -1 : 0);
    if (sign == 0) continue;
    if (last_sign != 0 && sign != last_sign) ++changes;
    if (first_sign == 0) first_sign = sign;
    last_sign = sign;
  }
  if (first_sign != last_sign) ++changes;  // round the corner from the last to the first
  return changes == 2;
}

// 2. Ear clipping. Per position: the neighbours on what is left, whether the corner turns
// strictly left, and the triangle outside the edge that starts there (kNone: a boundary
// segment, whose id is the position). A clipped triangle (u, v, w) has its diagonal w-u
// opposite v, at index 1, where the triangle clipped later across it links in. A corner's
// turn is found when first asked for (2: not yet) and forgotten when its neighbours change:
// the same orient2d on the same points as computing every one up front and after each
// clip, without those never asked for (all of them for a triangle, b = 3). The test whether
// a corner o lies in an ear asks first about the ear's diagonal, which most corners are
// beyond (the three signs are the same whatever the order).
// Only the first b slots are written and read (not zeroed first: that cost more than the
// rest of this set-up at the usual 6 corners). A do-while: b >= 3 (cppcheck, which does not
// read small_cdt's assertion, then sees every slot read written).
bool clip_ears(Work& w, const uint32_t* poly, uint32_t b) {
  uint32_t next_at[kSmallMaxPoints], prev_at[kSmallMaxPoints], outer[kSmallMaxPoints];
  uint8_t convex[kSmallMaxPoints];
  uint32_t pos = 0;
  do {
    next_at[pos] = pos + 1 == b ? 0 : pos + 1;
    prev_at[pos] = pos == 0 ? b - 1 : pos - 1;
    outer[pos] = kNone;
    convex[pos] = 2;
  } while (++pos < b);
  auto turns_left = [&](uint32_t at) {
    if (convex[at] == 2) {
      convex[at] = orient(w, poly[prev_at[at]], poly[at], poly[next_at[at]]) > 0.0 ? 1 : 0;
    }
    return convex[at] != 0;
  };
  auto seg_of = [&](uint32_t at) { return outer[at] == kNone ? at : kNone; };
  auto link_outer = [&](uint32_t at, uint32_t ti) {
    if (outer[at] != kNone) w.t[outer[at]].n[1] = ti;
  };
  uint32_t left = b;
  uint32_t cur = 0;
  while (left > 3) {
    bool found = false;
    for (uint32_t tries = 0; tries < left && !found; ++tries) {
      if (turns_left(cur)) {
        const uint32_t u = prev_at[cur], x = next_at[cur];
        found = true;
        for (uint32_t o = next_at[x]; o != u && found; o = next_at[o]) {
          if (turns_left(o)) continue;
          found = !(orient(w, poly[x], poly[u], poly[o]) >= 0.0 &&
                    orient(w, poly[u], poly[cur], poly[o]) >= 0.0 &&
                    orient(w, poly[cur], poly[x], poly[o]) >= 0.0);
        }
      }
      if (!found) cur = next_at[cur];
    }
    if (!found) return false;  // never for a simple polygon
    const uint32_t u = prev_at[cur], x = next_at[cur];
    const uint32_t ti = w.tri_count++;
    put(w, ti, poly[u], poly[cur], poly[x], outer[cur], kNone, outer[u], seg_of(cur), kNone,
        seg_of(u));
    link_outer(cur, ti);
    link_outer(u, ti);
    outer[u] = ti;
    next_at[u] = x;
    prev_at[x] = u;
    --left;
    convex[u] = 2;
    convex[x] = 2;
    cur = x;
  }
  {
    const uint32_t x = cur, y = next_at[x], z = next_at[y];  // y turns from x to z
    if (!turns_left(y)) return false;                        // never (simple polygon)
    const uint32_t ti = w.tri_count++;
    put(w, ti, poly[x], poly[y], poly[z], outer[y], outer[z], outer[x], seg_of(y), seg_of(z),
        seg_of(x));
    link_outer(x, ti);
    link_outer(y, ti);
    link_outer(z, ti);
  }
  return true;
}

// 4. The other points (their triangles stay inside the polygon: b - 2 + 2 per point in
// all), then the interior segments.
bool insert_interior(Work& w, const uint8_t* on_boundary, const CdtSegment* sg, uint32_t b,
                     uint32_t m) {
  const uint32_t n = w.n;
  uint32_t last = 0;
  for (uint32_t v = 0; v < n; ++v) {
    if (on_boundary[v] != 0) continue;
    uint32_t ti = 0;
    uint32_t mask = 0;
    if (!locate(w, v, last, &ti, &mask)) return false;  // outside the polygon
    if (mask == 0) {
      split_triangle(w, ti, v);
    } else if (mask == 1 || mask == 2 || mask == 4) {
      const uint32_t k = mask == 1 ? 0 : (mask == 2 ? 1 : 2);
      if (w.t[ti].n[k] == kNone || w.t[ti].c[k] != kNone) return false;  // on the boundary
      split_edge(w, ti, k, v);
    } else {
      return false;  // on a vertex: a duplicate
    }
    legalize_around(w, v);
    last = w.vt[v];
  }
  for (uint32_t s = b; s < m; ++s) {
    // Nearly always already an edge (insert_segment()'s step 0, without its Status).
    uint32_t tab = 0;
    uint32_t third = 0;
    if (find_edge(w, sg[s].a, sg[s].b, &tab, &third)) {
      constrain(w, tab, third, s);
      continue;
    }
    if (!insert_segment(w, s, sg[s].a, sg[s].b).is_ok()) return false;
  }
  return true;
}

// True when it wrote the output (into the room reserved for `expected` more triangles); false
// when the input is for the general path (nothing written then). The caller has checked ids,
// coordinates and that the boundary closes; n <= kSmallMaxPoints.
bool small_cdt(Span<const CdtPoint> points, Span<const CdtSegment> segments,
               uint32_t boundary_count, uint64_t expected, ArenaArray<CdtTriangle>* out,
               ArenaArray<CdtAdjacency>* adjacency) {
  const uint32_t n = static_cast<uint32_t>(points.size());
  const uint32_t m = static_cast<uint32_t>(segments.size());
  const uint32_t b = boundary_count;
  SPLINTCORE_ASSERT(n <= kSmallMaxPoints && b >= 3 && b <= n);
  const CdtPoint* p = points.data();
  const CdtSegment* sg = segments.data();
  uint8_t on_boundary[kSmallMaxPoints] = {};
  uint32_t poly[kSmallMaxPoints];  // point id per boundary position
  for (uint32_t s = 0; s < b; ++s) {
    const uint32_t v = sg[s].a;
    if (on_boundary[v] != 0) return false;  // not simple: the general path says so
    on_boundary[v] = 1;
    poly[s] = v;
  }
  if (!star_shaped(p, poly, b)) return false;
  // Its memory, on the stack.
  Tri tris[kSmallMaxTris];
  uint32_t vt[kSmallMaxPoints];
  uint32_t stack[3 * kSmallMaxTris];
  uint8_t queued[kSmallMaxTris] = {};
  EdgeKey queue[3 * kSmallMaxPoints + 3];
  Work w;
  w.p = p;
  w.n = n;
  w.t = tris;
  w.tri_count = 0;
  w.vt = vt;
  w.stack = stack;
  w.queued = queued;
  w.queue = queue;
  w.queue_cap = 3 * kSmallMaxPoints + 3;
  if (!clip_ears(w, poly, b)) return false;
  // 3. Delaunay: every inner edge on the stack once (the diagonal of the ear that cut it off,
  // at index 1; the last triangle has none of its own), then Lawson flips.
  w.stack_size = 0;
  for (uint32_t ti = 0; ti + 1 < w.tri_count; ++ti) push_half_edge(w, ti, 1);
  legalize_edges(w);
  if (!insert_interior(w, on_boundary, sg, b, m)) return false;
  if (w.tri_count != expected) return false;  // never: b + 2 i - 2 by construction
  write_small_output(w, out, adjacency);
  return true;
}

struct Sizes {
  uint64_t out;    // output triangles (upper bound)
  uint64_t tris;   // triangle capacity
  uint64_t verts;  // points + super-triangle corners
  uint64_t edges;  // edges of the full triangulation
};

Sizes sizes_for(uint64_t n) { return Sizes{2 * n, 2 * n + 1, n + 3, 3 * n + 3}; }

}  // namespace

uint64_t cdt_bound(uint64_t point_count, uint64_t segment_count) {
  (void)segment_count;  // every temporary is sized by the point count
  if (point_count > kMaxPoints) point_count = kMaxPoints;
  const Sizes z = sizes_for(point_count);
  constexpr uint64_t kSlack = 64;  // alignment padding per allocation, generously
  return z.out * (sizeof(CdtTriangle) + sizeof(CdtAdjacency)) + z.verts * sizeof(CdtPoint) +
         z.tris * sizeof(Tri) + z.verts * sizeof(uint32_t) + 3 * z.tris * sizeof(uint32_t) +
         z.tris + z.edges * sizeof(EdgeKey) + point_count + 2 * point_count * sizeof(KeyIndex) +
         10 * kSlack;
}

namespace {

// ---- the general path, step by step -----------------------------------------------------------

// 1. The input, checked before any memory is taken: counts, coordinates, segment ids, a closed
// boundary.
Status check_input(Span<const CdtPoint> points, Span<const CdtSegment> segments,
                   uint32_t boundary_count) {
  const size_t n_size = points.size();
  const size_t m = segments.size();
  if (n_size > kMaxPoints) {
    return make_error(StatusCode::kInvalidArgument, "cdt: ", n_size,
                      " points, more than the limit ", kMaxPoints);
  }
  if (m > UINT32_MAX) {
    return make_error(StatusCode::kInvalidArgument, "cdt: ", m, " segments, too many");
  }
  const uint32_t n = static_cast<uint32_t>(n_size);
  if (boundary_count < 3 || boundary_count > m) {
    return make_error(StatusCode::kInvalidArgument, "cdt: the boundary needs 3 to ", m,
                      " segments (one closed polygon), got ", boundary_count);
  }
  if (boundary_count > n) {
    return make_error(StatusCode::kInvalidArgument, "cdt: the boundary has ", boundary_count,
                      " segments but there are only ", n, " points: it repeats a point");
  }
  const CdtPoint* pt = points.data();
  for (uint32_t i = 0; i < n; ++i) {
    if (!coordinate_ok(pt[i].x) || !coordinate_ok(pt[i].y)) {
      return make_error(StatusCode::kInvalidArgument, "cdt: point ", i, " (", pt[i].x, ", ",
                        pt[i].y,
                        ") has a coordinate that is not finite or not 0 and not within "
                        "[2^-200, 2^200] in magnitude")
          .at_index(i);
    }
  }
  const CdtSegment* sg = segments.data();
  for (size_t s = 0; s < m; ++s) {
    const CdtSegment& g = sg[s];
    if (g.a >= n || g.b >= n) {
      return make_error(StatusCode::kInvalidArgument, "cdt: segment ", s, " (", g.a, "-", g.b,
                        ") refers to a point that does not exist (", n, " points)")
          .at_index(s);
    }
    if (g.a == g.b) {
      return make_error(StatusCode::kInvalidArgument, "cdt: segment ", s,
                        " starts and ends at point ", g.a)
          .at_index(s);
    }
  }
  for (uint32_t s = 0; s < boundary_count; ++s) {
    const uint32_t next = s + 1 == boundary_count ? 0 : s + 1;
    if (sg[s].b != sg[next].a) {
      return make_error(StatusCode::kInvalidArgument, "cdt: the boundary is not closed: segment ",
                        next, " starts at point ", sg[next].a, ", not where segment ", s,
                        " ends (point ", sg[s].b, ")")
          .at_index(next);
    }
  }
  return Status::ok();
}

// The output's room for the `expected` triangles, taken first (it must survive the
// temporaries).
Status reserve_output(uint64_t expected, ArenaArray<CdtTriangle>* out,
                      ArenaArray<CdtAdjacency>* adjacency) {
  const uint64_t out_total = uint64_t{out->size()} + expected;
  if (out_total > SIZE_MAX) {  // 32-bit targets: fail, never wrap
    return make_error(StatusCode::kLimitExceeded, "cdt: ", out_total,
                      " output triangles are more than this target can address");
  }
  if (!out->reserve(static_cast<size_t>(out_total))) return out->arena()->exhausted_status();
  if (adjacency != nullptr) {
    SPLINTCORE_ASSERT(adjacency->arena() != nullptr);
    const uint64_t adjacency_total = uint64_t{adjacency->size()} + expected;
    if (adjacency_total > SIZE_MAX) {
      return make_error(StatusCode::kLimitExceeded, "cdt: ", adjacency_total,
                        " output triangles are more than this target can address");
    }
    if (!adjacency->reserve(static_cast<size_t>(adjacency_total))) {
      return adjacency->arena()->exhausted_status();
    }
  }
  return Status::ok();
}

// The temporaries (all sized up front from the point count): the points and after them the
// super-triangle's corners (w->p; see step 2), and `*flags`, n bytes: the boundary's points
// marked 1, each checked to appear once.
Status take_temporaries(Arena& arena, Span<const CdtPoint> points, Span<const CdtSegment> segments,
                        uint32_t boundary_count, Work* w, uint8_t** flags) {
  const uint32_t n = static_cast<uint32_t>(points.size());
  // n <= kMaxPoints, so every count (at most 3 * (2n + 1)) fits a 32-bit size_t.
  static_assert(3 * (2 * kMaxPoints + 1) <= UINT32_MAX, "CDT counts must fit 32 bits");
  const Sizes z64 = sizes_for(n);
  const struct {
    size_t tris, verts, edges;
  } z = {static_cast<size_t>(z64.tris), static_cast<size_t>(z64.verts),
         static_cast<size_t>(z64.edges)};
  w->n = n;
  CdtPoint* p = arena.allocate_array<CdtPoint>(z.verts);
  w->t = arena.allocate_array<Tri>(z.tris);
  w->vt = arena.allocate_array<uint32_t>(z.verts);
  w->stack = arena.allocate_array<uint32_t>(3 * z.tris);
  w->queued = arena.allocate_array<uint8_t>(z.tris);
  w->queue = arena.allocate_array<EdgeKey>(z.edges);
  uint8_t* f = arena.allocate_array<uint8_t>(n);
  if (p == nullptr || w->t == nullptr || w->vt == nullptr || w->stack == nullptr ||
      w->queued == nullptr || w->queue == nullptr || f == nullptr) {
    return arena.exhausted_status();
  }
  w->p = p;
  w->queue_cap = static_cast<uint32_t>(z.edges);
  std::memcpy(static_cast<void*>(p), points.data(), points.size() * sizeof(CdtPoint));
  const double r = frame_scale(points);
  p[n] = CdtPoint{-4.0 * r, -2.0 * r};
  p[n + 1] = CdtPoint{4.0 * r, -2.0 * r};
  p[n + 2] = CdtPoint{0.0, 4.0 * r};
  std::memset(w->queued, 0, z.tris);
  std::memset(f, 0, n);
  *flags = f;
  for (uint32_t s = 0; s < boundary_count; ++s) {
    const uint32_t v = segments[s].a;
    if (f[v] != 0) {
      return make_error(StatusCode::kInvalidArgument, "cdt: the boundary is not simple: point ", v,
                        " appears twice on it")
          .at_index(v);
    }
    f[v] = 1;
  }
  return Status::ok();
}

// 2. The super-triangle (its corners are points n..n + 2), then the points: BRIO order from
// kBrioMin points on, otherwise the boundary in order, then the others (those not marked in
// `flags`).
Status insert_points(Arena& arena, Work& w, Span<const CdtPoint> points,
                     Span<const CdtSegment> segments, uint32_t boundary_count,
                     const uint8_t* flags) {
  const uint32_t n = w.n;
  w.tri_count = 1;
  put(w, 0, n, n + 1, n + 2, kNone, kNone, kNone, kNone, kNone, kNone);
  uint32_t last = 0;
  if (n >= kBrioMin) {
    KeyIndex* keys = arena.allocate_array<KeyIndex>(n);
    KeyIndex* scratch = arena.allocate_array<KeyIndex>(n);
    if (keys == nullptr || scratch == nullptr) return arena.exhausted_status();
    brio_order(points, keys, scratch);
    for (uint32_t i = 0; i < n; ++i) {
      const uint32_t v = keys[i].index;
      SPLINTCORE_RETURN_IF_ERROR(insert_point(w, v, last));
      last = w.vt[v];
    }
    return Status::ok();
  }
  for (uint32_t s = 0; s < boundary_count; ++s) {
    const uint32_t v = segments[s].a;
    SPLINTCORE_RETURN_IF_ERROR(insert_point(w, v, last));
    last = w.vt[v];
  }
  for (uint32_t v = 0; v < n; ++v) {
    if (flags[v] != 0) continue;
    SPLINTCORE_RETURN_IF_ERROR(insert_point(w, v, last));
    last = w.vt[v];
  }
  return Status::ok();
}

// 4. The exterior: flood fill from the super-triangle, stopped by boundary segments
// (`exterior`: a byte per triangle of the capacity, zeroed here).
void flood_exterior(Work& w, uint32_t boundary_count, uint8_t* exterior) {
  std::memset(exterior, 0, static_cast<size_t>(sizes_for(w.n).tris));
  const uint32_t seed = w.vt[w.n];
  exterior[seed] = 1;
  w.stack_size = 0;
  w.stack[w.stack_size++] = seed;
  while (w.stack_size > 0) {
    const Tri& t = w.t[w.stack[--w.stack_size]];
    for (uint32_t k = 0; k < 3; ++k) {
      if (t.c[k] < boundary_count) continue;  // kNone is never below it
      const uint32_t nb = t.n[k];
      if (nb == kNone || exterior[nb] != 0) continue;
      exterior[nb] = 1;
      w.stack[w.stack_size++] = nb;
    }
  }
}

// The segments against the exterior. First one pass over the slots: every marked edge is
// its segment, with no exterior triangle on its inner side (the left of a boundary segment,
// both sides of a constraint), and 2 m marked sides (so no segment repeats another and every
// one is an edge). Only when that does not hold does the per-segment walk below run; it
// finds the same problems and names the first one in segment order.
Status check_segments(const Work& w, Span<const CdtSegment> segments, uint32_t boundary_count,
                      const uint8_t* exterior) {
  const uint32_t m = static_cast<uint32_t>(segments.size());
  bool segments_fine = true;
  uint64_t marked = 0;
  for (uint32_t ti = 0; ti < w.tri_count && segments_fine; ++ti) {
    const Tri& t = w.t[ti];
    for (uint32_t k = 0; k < 3; ++k) {
      const uint32_t c = t.c[k];
      if (c == kNone) continue;
      ++marked;
      const uint32_t x = t.v[next3(k)], y = t.v[prev3(k)];  // ti lies left of x -> y
      const CdtSegment& g = segments[c];
      if (g.a == x && g.b == y) {
        segments_fine = exterior[ti] == 0;
      } else if (g.a == y && g.b == x) {
        segments_fine = c < boundary_count || exterior[ti] == 0;
      } else {
        segments_fine = false;
      }
      if (!segments_fine) break;
    }
  }
  if (segments_fine && marked == 2 * uint64_t{m}) return Status::ok();
  for (uint32_t s = 0; s < m; ++s) {
    const uint32_t a = segments[s].a;
    const uint32_t b = segments[s].b;
    uint32_t ti = 0;
    uint32_t k = 0;
    if (!find_edge(w, a, b, &ti, &k)) {
      return make_error(StatusCode::kInternal, "cdt: segment ", s, " is not an edge");
    }
    const Tri& t = w.t[ti];
    const uint32_t nb = t.n[k];
    if (s < boundary_count) {
      // The triangle left of a -> b must be inside.
      const uint32_t left = t.v[next3(k)] == a ? ti : nb;
      if (exterior[left] != 0) {
        return make_error(StatusCode::kInvalidArgument,
                          "cdt: the boundary is not counter-clockwise (segment ", s, ", points ", a,
                          "-", b, ", has the outside on its left)")
            .at_index(s);
      }
    } else if (t.c[k] >= boundary_count && (exterior[ti] != 0 || exterior[nb] != 0)) {
      return make_error(StatusCode::kInvalidArgument, "cdt: constraint segment ", s, " (points ", a,
                        "-", b, ") lies outside the boundary")
          .at_index(s);
    }
  }
  return Status::ok();
}

// Every point is a corner of an inside triangle, no corner of the frame is, and there are
// `expected` of them (`used`: n bytes of scratch).
Status check_inside(const Work& w, const uint8_t* exterior, uint8_t* used, uint64_t expected) {
  const uint32_t n = w.n;
  std::memset(used, 0, n);
  uint64_t inside = 0;
  for (uint32_t ti = 0; ti < w.tri_count; ++ti) {
    if (exterior[ti] != 0) continue;
    ++inside;
    for (uint32_t k = 0; k < 3; ++k) {
      const uint32_t v = w.t[ti].v[k];
      if (v >= n) return make_error(StatusCode::kInternal, "cdt: the frame leaks inside");
      used[v] = 1;
    }
  }
  for (uint32_t v = 0; v < n; ++v) {
    if (used[v] == 0) {
      return make_error(StatusCode::kInvalidArgument, "cdt: point ", v, " (", w.p[v].x, ", ",
                        w.p[v].y, ") lies outside the boundary")
          .at_index(v);
    }
  }
  if (inside != expected) {
    return make_error(StatusCode::kInternal, "cdt: ", inside, " triangles inside, expected ",
                      expected);
  }
  return Status::ok();
}

// Steps 1 to 4 of the general path (the top of the file), after check_input and
// reserve_output; its temporaries are given back before it returns.
Status general_cdt(Arena& arena, Span<const CdtPoint> points, Span<const CdtSegment> segments,
                   uint32_t boundary_count, uint64_t expected, ArenaArray<CdtTriangle>* out,
                   ArenaArray<CdtAdjacency>* adjacency) {
  ArenaScope scope(arena);
  Work w;
  uint8_t* flags = nullptr;
  SPLINTCORE_RETURN_IF_ERROR(take_temporaries(arena, points, segments, boundary_count, &w, &flags));
  SPLINTCORE_RETURN_IF_ERROR(insert_points(arena, w, points, segments, boundary_count, flags));
  SPLINTCORE_ASSERT(w.tri_count == sizes_for(w.n).tris);
  // 3. The segments, boundary first (so boundary edges carry boundary ids).
  for (uint32_t s = 0; s < static_cast<uint32_t>(segments.size()); ++s) {
    SPLINTCORE_RETURN_IF_ERROR(insert_segment(w, s, segments[s].a, segments[s].b));
  }
  uint8_t* exterior = w.queued;  // the half-edge stack is empty: its flags are free
  flood_exterior(w, boundary_count, exterior);
  SPLINTCORE_RETURN_IF_ERROR(check_segments(w, segments, boundary_count, exterior));
  SPLINTCORE_RETURN_IF_ERROR(check_inside(w, exterior, flags, expected));
  // The output, written into the room reserved for it: slot order, each triangle starting at
  // its smallest id; on an error `out` and `adjacency` are cut back to their sizes. The
  // half-edge stack is free again: the slots' output indices.
  CdtTriangle bad{};
  if (!write_output(w, exterior, w.stack, expected, out, adjacency, &bad)) {
    return make_error(StatusCode::kInternal, "cdt: triangle ", bad.v[0], "-", bad.v[1], "-",
                      bad.v[2], " is not counter-clockwise");
  }
  return Status::ok();
}

Status cdt_impl(Arena& arena, Span<const CdtPoint> points, Span<const CdtSegment> segments,
                uint32_t boundary_count, ArenaArray<CdtTriangle>* out,
                ArenaArray<CdtAdjacency>* adjacency, bool small_path) {
  SPLINTCORE_ASSERT(out != nullptr && out->arena() != nullptr);
  SPLINTCORE_RETURN_IF_ERROR(check_input(points, segments, boundary_count));
  const uint32_t n = static_cast<uint32_t>(points.size());
  const uint64_t expected = 2 * uint64_t{n} - boundary_count - 2;  // b + 2 i - 2
  SPLINTCORE_RETURN_IF_ERROR(reserve_output(expected, out, adjacency));
  // Small inputs: the polygon first, without the super-triangle (or the general path below
  // when the small path cannot take this input).
  if (small_path && n <= kSmallMaxPoints &&
      small_cdt(points, segments, boundary_count, expected, out, adjacency)) {
    return Status::ok();
  }
  return general_cdt(arena, points, segments, boundary_count, expected, out, adjacency);
}

}  // namespace

Status cdt(Arena& arena, Span<const CdtPoint> points, Span<const CdtSegment> segments,
           uint32_t boundary_count, ArenaArray<CdtTriangle>* out,
           ArenaArray<CdtAdjacency>* adjacency) {
  return cdt_impl(arena, points, segments, boundary_count, out, adjacency, true);
}

Status cdt_general(Arena& arena, Span<const CdtPoint> points, Span<const CdtSegment> segments,
                   uint32_t boundary_count, ArenaArray<CdtTriangle>* out,
                   ArenaArray<CdtAdjacency>* adjacency) {
  return cdt_impl(arena, points, segments, boundary_count, out, adjacency, false);
}

}  // namespace detail
}  // namespace splintcore
