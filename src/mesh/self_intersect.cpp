// Self-intersection of a triangle mesh: a bounding-volume hierarchy of quantized 14-DOPs over
// the triangles, traversed against itself; pairs sharing a vertex cleared a whole vertex star
// at a time; the other pairs behind a separating-direction filter; what remains decided by
// the exact tests (see geometry.h) that respect the vertices and edges triangles share.
//
// Sources:
// - J. T. Klosowski, M. Held, J. S. B. Mitchell, H. Sowizral, K. Zikan, "Efficient Collision
//   Detection Using Bounding Volume Hierarchies of k-DOPs", IEEE TVCG 4(1), 1998: the 14-DOP
//   (the box and the four corner diagonals), much tighter than the box around the long
//   diagonal slivers of a swept surface.
// - T. Karras, "Maximizing Parallelism in the Construction of BVHs, Octrees, and k-d Trees",
//   HPG 2012: triangles in Morton order of their centres, split at the highest differing bit.
// - J. R. Shewchuk, "Adaptive Precision Floating-Point Arithmetic and Fast Robust Geometric
//   Predicates", 1997, section 4.2: the static error bounds of every filter below.
// - T. Moller, "A Fast Triangle-Triangle Intersection Test", 1997, and P. Guigue, O. Devillers,
//   "Fast and Robust Triangle-Triangle Overlap Test Using Orientation Predicates", 2003: the
//   plane-side rejection; the 2D separating-axis test for the coplanar cases.
//
// Every filter only ever proves "no conflict"; anything it cannot prove goes to the exact
// tests, so the answer is exact. Results do not depend on the traversal: every conflicting
// pair is counted, the first pair is the smallest. Only when max_pairs stops the count early
// does the order of discovery matter; then the answer is that of the sweep over boxes sorted
// by x (this function's original algorithm), the pairs it always reported: found by two more
// passes of the hierarchy (Pass::first_in_sweep_order), or by the sweep itself.
#include "splintcore/mesh.h"

#include "geometry/float_bounds.h"
#include "geometry/lanes2.h"
#include "geometry/plane_filter.h"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace splintcore {

namespace {

// Maps a double to a key whose unsigned order is the numeric order (for the radix sort).
inline uint64_t order_key(double v) {
  uint64_t bits;
  std::memcpy(&bits, &v, sizeof(bits));
  return (bits >> 63) != 0 ? ~bits : bits | (uint64_t{1} << 63);
}

inline double magnitude(double x) { return x < 0 ? -x : x; }

// A triangle's plane as a floating-point filter (src/geometry/plane_filter.h): a side it
// reports is exact; kUnknown goes to the exact tests.
using Plane = PlaneFilter;
constexpr double kPlaneFilter = kPlaneFilterBound;
inline Plane plane_of(const Vec3& a, const Vec3& b, const Vec3& c) { return plane_filter(a, b, c); }
enum Side : int { kBelow = -1, kOn = 0, kAbove = 1, kUnknown = 2 };
inline Side side_of(const Plane& p, const Vec3& x) {
  return static_cast<Side>(filtered_side(p, x));
}

// All strictly on one side (certain), all exactly on the plane, or neither.
enum Spread { kSeparated, kCoplanar, kMixed };

inline Spread spread(const Plane& plane, const Vec3* pts, int n) {
  const Side s0 = side_of(plane, pts[0]);
  bool same = s0 != kUnknown;
  for (int i = 1; i < n && same; ++i) same = side_of(plane, pts[i]) == s0;
  if (!same) return kMixed;
  return s0 == kOn ? kCoplanar : kSeparated;
}

// ---- the 2D filter -----------------------------------------------------------------------------
// Projections along a coordinate axis. Disjoint projections prove disjoint triangles, whatever
// the axis (a common point would project to a common point), so these tests need no exact
// fallback of their own: "apart" is certain, anything else goes on to the exact tests.

struct P2 {
  double x, y;
};

inline P2 drop(const Vec3& v, int axis) {
  return axis == 0 ? P2{v.y, v.z} : (axis == 1 ? P2{v.z, v.x} : P2{v.x, v.y});
}

// The axis along which the plane's normal is largest: the projection that keeps the most.
inline int dominant_axis(const Vec3& n) {
  const double x = magnitude(n.x), y = magnitude(n.y), z = magnitude(n.z);
  return x >= y && x >= z ? 0 : (y >= z ? 1 : 2);
}

// The sign of orient2d(a, b, c) when its floating-point evaluation (the same expression as
// orient2d's stage A) is certain of it, else 0. Shewchuk's bound for this expression is
// (3 + 16 eps) eps (|left| + |right|); 2^-51 is above it. Inside the predicates' range no
// product underflows, so the bound holds.
constexpr double kOrient2dFilter = 0x1p-51;

inline int sure_orient2d(const P2& a, const P2& b, const P2& c) {
  const double left = (a.x - c.x) * (b.y - c.y);
  const double right = (a.y - c.y) * (b.x - c.x);
  const double det = left - right;
  const double bound = kOrient2dFilter * (magnitude(left) + magnitude(right));
  return det > bound ? 1 : (det < -bound ? -1 : 0);
}

// Is every point certainly strictly beyond the line ab, on the side opposite to sign s?
inline bool all_beyond(const P2& a, const P2& b, int s, const P2* pts, int n) {
  for (int i = 0; i < n; ++i) {
    if (sure_orient2d(a, b, pts[i]) != -s) return false;
  }
  return true;
}

// Are the projected triangles t and u certainly disjoint (an edge line of one with the other
// strictly beyond it)?
bool apart_2d(const P2 t[3], const P2 u[3]) {
  const int st = sure_orient2d(t[0], t[1], t[2]);
  const int su = sure_orient2d(u[0], u[1], u[2]);
  for (int i = 0; i < 3; ++i) {
    const int j = i == 2 ? 0 : i + 1;
    if (st != 0 && all_beyond(t[i], t[j], st, u, 3)) return true;
    if (su != 0 && all_beyond(u[i], u[j], su, t, 3)) return true;
  }
  return false;
}

bool triangles_apart(int axis, const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d,
                     const Vec3& e, const Vec3& f) {
  const P2 t[3] = {drop(a, axis), drop(b, axis), drop(c, axis)};
  const P2 u[3] = {drop(d, axis), drop(e, axis), drop(f, axis)};
  return apart_2d(t, u);
}

// The projected segment pq and triangle abc certainly disjoint?
bool segment_apart(int axis, const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b,
                   const Vec3& c) {
  const P2 s[2] = {drop(p, axis), drop(q, axis)};
  const P2 t[3] = {drop(a, axis), drop(b, axis), drop(c, axis)};
  const int st = sure_orient2d(t[0], t[1], t[2]);
  if (st != 0) {
    for (int i = 0; i < 3; ++i) {
      if (all_beyond(t[i], t[i == 2 ? 0 : i + 1], st, s, 2)) return true;
    }
  }
  // The segment's own line, with the whole triangle strictly on one side.
  const int s0 = sure_orient2d(s[0], s[1], t[0]);
  return s0 != 0 && sure_orient2d(s[0], s[1], t[1]) == s0 && sure_orient2d(s[0], s[1], t[2]) == s0;
}

// ---- the exact tests ---------------------------------------------------------------------------

// Same side of the shared edge ab, for coplanar c and d? `axis` (-1: none) is a projection to
// try first: when the filter is sure that it keeps abc non-degenerate (the projection is then
// one-to-one on the common plane, so it keeps sides of the line ab) and sure of both signs,
// they decide.
bool folded_onto(int axis, const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  if (axis >= 0) {
    const P2 pa = drop(a, axis), pb = drop(b, axis);
    const int sc = sure_orient2d(pa, pb, drop(c, axis));
    const int sd = sure_orient2d(pa, pb, drop(d, axis));
    if (sc != 0 && sd != 0) return sc == sd;
  }
  axis = projection_axis(a, b, c);
  if (axis < 0) return false;
  const P2 pa = drop(a, axis), pb = drop(b, axis), pc = drop(c, axis), pd = drop(d, axis);
  return sign_of(orient2d(pa.x, pa.y, pb.x, pb.y, pc.x, pc.y)) *
             sign_of(orient2d(pa.x, pa.y, pb.x, pb.y, pd.x, pd.y)) >
         0;
}

// Does the edge pq meet triangle abc (whose plane is pl)? `filters`: whether the 2D filter may
// be used (its bound needs coordinates within the predicates' range).
inline bool edge_meets(const Plane& pl, const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b,
                       const Vec3& c, bool filters) {
  const Vec3 pts[2] = {p, q};
  switch (spread(pl, pts, 2)) {
    case kSeparated: return false;
    case kCoplanar:
      if (filters && segment_apart(dominant_axis(pl.n), p, q, a, b, c)) return false;
      return coplanar_segment_intersects_triangle(p, q, a, b, c);
    default: return segment_intersects_triangle(p, q, a, b, c);
  }
}

// Do triangles s and t conflict, given the vertex ids they share? The planes let the common
// cases be decided by the filters; whatever they cannot decide goes to the exact tests.
// `filters`: whether the 2D filter may be used too (coordinates within the range).
bool conflict(const Vec3* v, const Triangle& s, const Triangle& t, const Plane& ps, const Plane& pt,
              bool filters) {
  int shared = 0;
  int s_at[3] = {-1, -1, -1};  // for each corner of s, the matching corner of t
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      if (s.v[i] == t.v[j]) {
        s_at[i] = j;
        ++shared;
      }
    }
  }
  const Vec3 &a = v[s.v[0]], &b = v[s.v[1]], &c = v[s.v[2]];
  const Vec3 &d = v[t.v[0]], &e = v[t.v[1]], &f = v[t.v[2]];
  if (shared == 0) {
    const Vec3 tv[3] = {d, e, f}, sv[3] = {a, b, c};
    const Spread t_vs_s = spread(ps, tv, 3);
    if (t_vs_s == kSeparated) return false;
    if (t_vs_s == kCoplanar) {
      if (filters && triangles_apart(dominant_axis(ps.n), a, b, c, d, e, f)) return false;
      return coplanar_triangles_intersect(a, b, c, d, e, f);
    }
    if (spread(pt, sv, 3) == kSeparated) return false;
    if (filters && triangles_apart(dominant_axis(ps.n), a, b, c, d, e, f)) return false;
    return triangles_intersect(a, b, c, d, e, f);
  }
  if (shared >= 3) return true;  // the same three vertices twice
  if (shared == 2) {
    int s_free = s_at[0] < 0 ? 0 : (s_at[1] < 0 ? 1 : 2);
    int t_free = 3 - s_at[(s_free + 1) % 3] - s_at[(s_free + 2) % 3];
    const Vec3& p = v[s.v[(s_free + 1) % 3]];
    const Vec3& q = v[s.v[(s_free + 2) % 3]];
    const Vec3& sc = v[s.v[s_free]];
    const Vec3& tc = v[t.v[t_free]];
    const Side side = side_of(ps, tc);
    // Not coplanar: the shared edge is all they share.
    if (side == kAbove || side == kBelow) return false;
    if (side == kUnknown && orient3d(p, q, sc, tc) != 0.0) return false;
    return folded_onto(filters ? dominant_axis(ps.n) : -1, p, q, sc, tc);
  }
  // One shared vertex: they conflict iff the edge of either opposite it meets the other.
  int si = s_at[0] >= 0 ? 0 : (s_at[1] >= 0 ? 1 : 2);
  int ti = s_at[si];
  const Vec3& s1 = v[s.v[(si + 1) % 3]];
  const Vec3& s2 = v[s.v[(si + 2) % 3]];
  const Vec3& t1 = v[t.v[(ti + 1) % 3]];
  const Vec3& t2 = v[t.v[(ti + 2) % 3]];
  return edge_meets(pt, s1, s2, d, e, f, filters) || edge_meets(ps, t1, t2, a, b, c, filters);
}

// ---- four and eight lanes
// ------------------------------------------------------------------------ GCC and Clang vector
// extensions (the library builds with either: see core.h's overflow builtins), SSE2 on x86-64, NEON
// on AArch64. Every use is an exact integer comparison or bit operation: the lanes give the same
// answers as scalar code would, on every platform.
typedef int16_t Lanes8 __attribute__((vector_size(16)));
typedef uint32_t Ids4 __attribute__((vector_size(16)));
// (Mask4 and Halves: geometry/lanes2.h.)

#if defined(__clang__) || __GNUC__ >= 12
#define SPLINTCORE_SPLAT8(x, k) __builtin_shufflevector(x, x, k, k, k, k, k, k, k, k)
#else
#define SPLINTCORE_SPLAT8(x, k) __builtin_shuffle(x, Lanes8{k, k, k, k, k, k, k, k})
#endif

inline bool no_lane(Lanes8 m) {
  const Halves h = reinterpret_cast<Halves>(m);
  return (h[0] | h[1]) == 0;
}

// Bit j set when lane j is (m: lanes all ones or all zeros). On x86-64 the lanes are packed
// to bytes (saturating: -1 stays -1, 0 stays 0) and their sign bits taken in one instruction
// (pmovmskb), where the portable form takes eight: the walk asks this of every row of a leaf
// (about 25M instructions of 465M on the real dentition's result). The same bits either way.
#if defined(__SSE2__)
inline uint32_t lane_bits(Lanes8 m) {
  __m128i x;
  std::memcpy(&x, &m, sizeof(x));
  return static_cast<uint32_t>(_mm_movemask_epi8(_mm_packs_epi16(x, x))) & 0xffu;
}
inline uint32_t lane_bits(Mask4 lo, Mask4 hi) {  // lanes 0-3, then 4-7
  __m128i a, b;
  std::memcpy(&a, &lo, sizeof(a));
  std::memcpy(&b, &hi, sizeof(b));
  const __m128i w = _mm_packs_epi32(a, b);
  return static_cast<uint32_t>(_mm_movemask_epi8(_mm_packs_epi16(w, w))) & 0xffu;
}
#else
inline uint32_t lane_bits(Lanes8 m) {
  const Halves h = reinterpret_cast<Halves>(m & Lanes8{1, 2, 4, 8, 16, 32, 64, 128});
  uint64_t x = h[0] | h[1];
  x |= x >> 32;
  x |= x >> 16;
  return static_cast<uint32_t>(x & 0xffu);
}
inline uint32_t lane_bits(Mask4 lo, Mask4 hi) {  // lanes 0-3, then 4-7
  const Halves a = reinterpret_cast<Halves>(lo & Mask4{1, 2, 4, 8});
  const Halves b = reinterpret_cast<Halves>(hi & Mask4{16, 32, 64, 128});
  const uint64_t x = a[0] | a[1] | b[0] | b[1];
  return static_cast<uint32_t>((x | (x >> 32)) & 0xffu);
}
#endif

inline int lowest_bit(uint32_t x) { return __builtin_ctz(x); }
// How many of the eight lanes a mask of lane_bits() has: a table (no popcount instruction in
// the x86-64 baseline; the walk counts every row's candidates: 15 instructions a row computed,
// 7M of the real dentition's result).
struct LaneCounts {
  uint8_t n[256];
  constexpr LaneCounts() : n{} {
    for (int i = 1; i < 256; ++i) n[i] = static_cast<uint8_t>(n[i >> 1] + (i & 1));
  }
};
constexpr LaneCounts kLaneCounts;
inline uint32_t lane_count(uint32_t bits) { return kLaneCounts.n[bits & 0xffu]; }

// ---- bounding volumes
// ------------------------------------------------------------------------------ The 14-DOP: the
// extent of a triangle along the seven directions x, y, z, x + y + z, x + y - z, x - y + z, -x + y
// + z, quantized to 16-bit integers so that one comparison of eight lanes tests them all (the
// eighth lane is the same for every DOP and always overlaps).
//
// Sound: if two triangles share a point q, then along each direction u their exact extents
// both contain u . q, so the larger minimum is at most the smaller maximum. The computed
// projection g(p) (two rounded additions for a diagonal) is within E = 5 eps R of u . p (R
// the largest coordinate magnitude), so after it the gap is at most 2E. The quantized value
// is floor(c(y)), c(y) = (y - origin) * scale rounded (monotone in y, and within 1e-10 of the
// exact product, which stays below 65536), so a gap of 2E becomes at most floor(2 E scale) + 1
// cells; widening each extent by M = 1 + ceil(E scale) cells on each side closes it. So the
// quantized extents of two triangles that meet always overlap: a DOP test never drops a pair
// that meets. The extents of a triangle are those of its corners merged (floor and the
// roundings are monotone), computed once per vertex.
constexpr int kAxes = 7;
constexpr int kLanes = 8;

struct Dop {
  Lanes8 lo;
  Lanes8 hi;
};

inline bool dops_overlap(const Dop& a, const Dop& b) {
  return no_lane((a.lo > b.hi) | (b.lo > a.hi));
}

inline Dop dop_union(const Dop& a, const Dop& b) {
  const Lanes8 lo_less = b.lo<a.lo, hi_more = b.hi> a.hi;
  return Dop{(b.lo & lo_less) | (a.lo & ~lo_less), (b.hi & hi_more) | (a.hi & ~hi_more)};
}

// The directions as computed, and their error bounds in units of eps R.
inline void project(const Vec3& p, double u[kLanes]) {
  const double xy = p.x + p.y;
  u[0] = p.x;
  u[1] = p.y;
  u[2] = p.z;
  u[3] = xy + p.z;
  u[4] = xy - p.z;
  u[5] = (p.x - p.y) + p.z;
  u[6] = (p.y - p.x) + p.z;
  u[7] = 0.0;
}
constexpr double kErrorUnits[kLanes] = {0, 0, 0, 5, 5, 5, 5, 0};

// The runs the scans and the serial stages of the hierarchy pass are cut into, to share them
// on the executor: run r of n things is n * r / kRuns .. n * (r + 1) / kRuns - 1. Every stage gives
// the same result however it is cut, so the results do not depend on the thread count.
constexpr uint32_t kRuns = 8;
inline size_t run_start(size_t n, uint32_t r) { return task_start(n, r, kRuns); }

// The quantization of each direction (the pad lane: scale 0, margin 0).
struct Grid {
  double origin[kLanes];
  double scale[kLanes];
  int margin[kLanes];
};

// One scan of the mesh in runs on the executor (one run of tasks for what were three scans):
// each run's first triangle that refers to a vertex that does not exist, its vertices'
// largest coordinate magnitude (-1: one outside the exact range, exact_radius()) and their
// lanes' bounds (grid()). Each answer is the same, however the runs are shared out, as one
// scan's.
struct MeshScan {
  size_t bad[kRuns];
  double radius[kRuns];
  double run_lo[kRuns][kLanes], run_hi[kRuns][kLanes];

  void run(const Executor* executor, const Vec3* v, size_t nv, const Triangle* tris, size_t nt) {
    auto scan = [&](uint32_t r) {
      bad[r] = nt;
      for (size_t t = run_start(nt, r); t < run_start(nt, r + 1); ++t) {
        const Triangle& tri = tris[t];
        if (tri.v[0] >= nv || tri.v[1] >= nv || tri.v[2] >= nv) {
          bad[r] = t;
          break;
        }
      }
      double largest = 0.0, u[kLanes];
      const size_t first = run_start(nv, r);
      for (size_t i = first; i < run_start(nv, r + 1); ++i) {
        for (int a = 0; a < 3; ++a) {
          const double x = std::fabs(v[i][a]);
          if (x != 0.0 && !(x >= 0x1p-306 && x <= 0x1p100)) {  // NaN fails too
            radius[r] = -1.0;
            return;  // (no bounds: there is no grid then)
          }
          largest = x > largest ? x : largest;
        }
        project(v[i], u);
        for (int k = 0; k < kLanes; ++k) {
          run_lo[r][k] = i == first || u[k] < run_lo[r][k] ? u[k] : run_lo[r][k];
          run_hi[r][k] = i == first || u[k] > run_hi[r][k] ? u[k] : run_hi[r][k];
        }
      }
      radius[r] = largest;
    };
    parallel_for_each(executor, kRuns, scan);
  }

  // The first triangle that refers to a vertex that does not exist (nt: none): the first
  // run's first.
  size_t first_bad(size_t nt) const {
    for (size_t t : bad) {
      if (t != nt) return t;
    }
    return nt;
  }

  // The largest coordinate magnitude when every coordinate is finite and, when nonzero, within
  // [2^-306, 2^100] (orient3d's exact range, geometry.h, and well inside float's and the DOP
  // grid's), so that every filter's bound holds and every exact test is exact; -1 otherwise.
  double exact_radius() const {
    double largest = 0.0;
    for (double x : radius) {
      if (x < 0.0) return -1.0;
      largest = x > largest ? x : largest;
    }
    return largest;
  }

  // The grid over all the vertices (radius: exact_radius(), not -1): the bounds of the runs
  // in order, the same values (and the first of equal ones) as one scan.
  Grid grid(size_t nv, double exact) const {
    double lo[kLanes], hi[kLanes];
    for (int k = 0; k < kLanes; ++k) lo[k] = hi[k] = 0.0;
    bool any = false;
    for (uint32_t r = 0; r < kRuns; ++r) {
      if (run_start(nv, r) == run_start(nv, r + 1)) continue;
      for (int k = 0; k < kLanes; ++k) {
        lo[k] = !any || run_lo[r][k] < lo[k] ? run_lo[r][k] : lo[k];
        hi[k] = !any || run_hi[r][k] > hi[k] ? run_hi[r][k] : hi[k];
      }
      any = true;
    }
    Grid g;
    for (int k = 0; k < kLanes; ++k) {
      const double error = kErrorUnits[k] * 0x1p-53 * exact * (1.0 + 1e-9);
      const double extent = hi[k] - lo[k];
      double scale = k < kAxes && extent > 0.0 ? 64000.0 / extent : 0.0;
      if (error * scale > 600.0) scale = 600.0 / error;  // margins stay within 16 bits
      g.origin[k] = lo[k];
      g.scale[k] = scale;
      g.margin[k] = k < kAxes ? 2 + static_cast<int>(error * scale) : 0;  // 1 + ceil(E scale)
    }
    return g;
  }
};

// A DOP from its lanes' bounds.
inline Dop dop_of(const int16_t (&lo)[kLanes], const int16_t (&hi)[kLanes]) {
  Dop d;
  std::memcpy(&d.lo, lo, sizeof(lo));
  std::memcpy(&d.hi, hi, sizeof(hi));
  return d;
}

// A vertex's DOP: one quantized point, widened by the margins (values in -32602 .. 32602).
inline Dop point_dop(const Grid& g, const Vec3& p) {
  double u[kLanes];
  project(p, u);
  int16_t lo[kLanes], hi[kLanes];
  for (int k = 0; k < kLanes; ++k) {
    const int q = static_cast<int>((u[k] - g.origin[k]) * g.scale[k]) - 32000;  // >= 0 before
    lo[k] = static_cast<int16_t>(q - g.margin[k]);
    hi[k] = static_cast<int16_t>(q + g.margin[k]);
  }
  return dop_of(lo, hi);
}

inline Dop triangle_dop(const Dop& a, const Dop& b, const Dop& c) {
  return dop_union(dop_union(a, b), c);
}

// The same DOP from the corners themselves (when the vertices' DOPs are gone): the
// quantization is monotone, so quantizing the corners' smallest and largest projections gives
// the union of their point DOPs.
inline Dop triangle_dop(const Grid& g, const Vec3& a, const Vec3& b, const Vec3& c) {
  double ua[kLanes], ub[kLanes], uc[kLanes];
  project(a, ua);
  project(b, ub);
  project(c, uc);
  int16_t lo[kLanes], hi[kLanes];
  for (int k = 0; k < kLanes; ++k) {
    // (Only `<`: cppcheck reads a `<` and a `>` in one statement as template brackets.)
    const double l = ua[k] < ub[k] ? ua[k] : ub[k];
    const double h = ub[k] < ua[k] ? ua[k] : ub[k];
    const double least = l < uc[k] ? l : uc[k];
    const double most = uc[k] < h ? h : uc[k];
    const int ql = static_cast<int>((least - g.origin[k]) * g.scale[k]) - 32000;
    const int qh = static_cast<int>((most - g.origin[k]) * g.scale[k]) - 32000;
    lo[k] = static_cast<int16_t>(ql - g.margin[k]);
    hi[k] = static_cast<int16_t>(qh + g.margin[k]);
  }
  return dop_of(lo, hi);
}

// Lane x of triangle_dop(g, a, b, c) alone (the same arithmetic, so the same values): the slabs'
// membership and owners (find_self_intersections' slab passes).
inline void x_cells(const Grid& g, const Vec3& a, const Vec3& b, const Vec3& c, int* lo, int* hi) {
  const double l = a.x < b.x ? a.x : b.x;
  const double h = b.x < a.x ? a.x : b.x;
  const double least = l < c.x ? l : c.x;
  const double most = c.x < h ? h : c.x;
  *lo = static_cast<int>((least - g.origin[0]) * g.scale[0]) - 32000 - g.margin[0];
  *hi = static_cast<int>((most - g.origin[0]) * g.scale[0]) - 32000 + g.margin[0];
}

// ---- the triangles, in Morton order -------------------------------------------------------------
// Each with its plane's normal (for the filters and the stars; the rest of the plane filter,
// the magnitudes of the normal's terms, is made again where needed from the corners) and,
// for pairs that share no vertex, a separating direction kept ready: the in-plane normal of
// its longest edge (a sliver's thin direction), scaled to a largest component of 1 and
// rounded to float, with the triangle's extent along it computed in double, widened by twice
// the error of evaluating a dot product with any vertex of the mesh (|fl(m . x) - m . x|
// <= 3 eps |m| . |x| <= 3 eps |m|_1 R, plus what underflow can lose), and rounded outward to
// float. A triangle whose three corners all evaluate beyond that widened extent is disjoint
// from it: any direction is a valid separating axis, the rounded one too. When neither
// triangle's ready direction separates them, the others (the normal and the other two
// edges') are tried, computed then. 40 bytes: the item array is the largest of the check's,
// and its size is most of the check's peak (the normal, (b - a) x (c - a), is computed again
// where it is needed: 24 bytes less an item, 3.2 MB on the real dentition's result).
struct Item {
  Triangle tri;  // (with the id: 16 bytes)
  uint32_t id;
  uint8_t cleared;  // bit k: corner k's vertex has a cleared star (see below)
  uint8_t longest;  // the longest edge: from corner `longest` to the next
  uint16_t unused;
  float m[3];    // its in-plane normal, scaled
  float lo, hi;  // the extent along m, widened
};
static_assert(sizeof(Item) == 40, "an item is 40 bytes");

// The extent of the triangle abc along m, widened (error: per unit of |m|_1, see above).
inline void extent_along(const Vec3& m, const Vec3& a, const Vec3& b, const Vec3& c, double error,
                         double* lo, double* hi) {
  const double margin =
      2.0 * error * (std::fabs(m.x) + std::fabs(m.y) + std::fabs(m.z)) + 0x1p-1000;
  const double da = dot(m, a), db = dot(m, b), dc = dot(m, c);
  const double l = da < db ? da : db, h = da > db ? da : db;
  *lo = (l < dc ? l : dc) - margin;
  *hi = (h > dc ? h : dc) + margin;
}

inline Vec3 scaled_to_unit_max(const Vec3& m) {
  const double x = std::fabs(m.x), y = std::fabs(m.y), z = std::fabs(m.z);
  const double xy = x > y ? x : y;  // (the same as nested choices, as maxima: no branch)
  const double big = xy > z ? xy : z;
  if (!(big > 0.0)) return Vec3{};
  return Vec3{m.x / big, m.y / big, m.z / big};
}

// The item's plane filter, from its corners.
inline Plane plane_of(const Vec3* v, const Item& t) {
  return plane_of(v[t.tri.v[0]], v[t.tri.v[1]], v[t.tri.v[2]]);
}

inline Vec3 ready_direction(const Item& t) {
  return Vec3{static_cast<double>(t.m[0]), static_cast<double>(t.m[1]),
              static_cast<double>(t.m[2])};
}

void fill_item(const Vec3* v, const Triangle& tri, uint32_t id, double error, Item* item) {
  const Vec3 p[3] = {v[tri.v[0]], v[tri.v[1]], v[tri.v[2]]};
  const Plane plane = plane_of(p[0], p[1], p[2]);
  item->tri = tri;
  item->id = id;
  item->cleared = 0;
  item->unused = 0;
  const Vec3 e[3] = {p[1] - p[0], p[2] - p[1], p[0] - p[2]};
  const double len[3] = {dot(e[0], e[0]), dot(e[1], e[1]), dot(e[2], e[2])};
  // (Selects, not branches: which edge is longest is a coin toss to the predictor.)
  const bool l01 = len[0] >= len[1], l02 = len[0] >= len[2], l12 = len[1] >= len[2];
  const uint32_t k = (1u - static_cast<uint32_t>(l01 && l02)) *  // 0, or then 1 or 2
                     (2u - static_cast<uint32_t>(!l01 && l12));
  // Components within [-1, 1]: in float range whatever the coordinates (R^3 would not be).
  const Vec3 m = scaled_to_unit_max(cross(plane.n, e[k]));
  item->longest = static_cast<uint8_t>(k);
  item->m[0] = static_cast<float>(m.x);
  item->m[1] = static_cast<float>(m.y);
  item->m[2] = static_cast<float>(m.z);
  double lo, hi;
  extent_along(ready_direction(*item), p[0], p[1], p[2], error, &lo, &hi);
  item->lo = float_down(lo);
  item->hi = float_up(hi);
}

// Are p, q, r all certainly beyond [lo, hi] along m?
inline bool beyond(const Vec3& m, double lo, double hi, const Vec3& p, const Vec3& q,
                   const Vec3& r) {
  const double dp = dot(m, p), dq = dot(m, q), dr = dot(m, r);
  return ((dp > hi) & (dq > hi) & (dr > hi)) | ((dp < lo) & (dq < lo) & (dr < lo));
}

// Are the corners p, q, r of another triangle certainly beyond the triangle of s (corners a,
// b, c) along one of its directions other than the ready one?
bool beyond_other_axes(const Item& s, const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& p,
                       const Vec3& q, const Vec3& r, double error) {
  const Vec3 corner[3] = {a, b, c};
  const Vec3 n = cross(b - a, c - a);  // (plane_filter's)
  double lo, hi;
  for (uint32_t k = 0; k < 3; ++k) {
    if (k == s.longest) continue;
    const Vec3 m = cross(n, corner[k == 2 ? 0 : k + 1] - corner[k]);
    extent_along(m, a, b, c, error, &lo, &hi);
    if (beyond(m, lo, hi, p, q, r)) return true;
  }
  extent_along(n, a, b, c, error, &lo, &hi);
  return beyond(n, lo, hi, p, q, r);
}

// The corners of t whose vertex is also one of s's, as bits.
inline uint32_t shared_corners(const Item& s, const Item& t) {
  static_assert(sizeof(Triangle) + sizeof(uint32_t) == sizeof(Ids4), "ids, then the id");
  Ids4 tv;  // t's three ids and its triangle id (masked off below)
  std::memcpy(&tv, &t.tri, sizeof(tv));
  const uint32_t s0 = s.tri.v[0], s1 = s.tri.v[1], s2 = s.tri.v[2];
  const Mask4 eq =
      (tv == Ids4{s0, s0, s0, s0}) | (tv == Ids4{s1, s1, s1, s1}) | (tv == Ids4{s2, s2, s2, s2});
  return lane_bits(eq, Mask4{0, 0, 0, 0}) & 7u;
}

// ---- vertex stars ------------------------------------------------------------------------------
// Most candidate pairs share a vertex (a triangle's DOP overlaps its dozen neighbours'), and a
// whole star can be cleared at once. Project the star of vertex o along a direction d (the
// sum of its normals): if its triangles, chained around o by their shared edges into one fan
// (o, u_i, u_i+1), i = 0..k-1, all project with the same orientation (certainly, by the
// filter) and the fan turns around o exactly once, the projected sectors tile the plane
// around o without overlapping, sector i sharing only the ray of u_i+1 with sector i + 1 and
// only o with the others. Each triangle projects one-to-one (it is not degenerate in the
// projection), so two triangles of the star share only o, or only their common edge: no pair
// of the star conflicts. The fan turns once when the sign of d . ((u_0 - o) x (u_i - o)),
// i = 1..k-1, is positive up to some i and negative from there on (the angle from u_0 grows
// by less than pi per step: a second turn would make it positive again, or zero). Stars that
// are not a single consistently oriented fan (boundary, non-manifold, folded, repeated
// triangles) are not cleared; their pairs go through the tests one by one.
constexpr uint32_t kMaxStar = 24;

struct Diff {  // a rounded difference of two vertices (plain: arrays of it are not zeroed)
  double x, y, z;
};

// A triangle's normal and its terms' magnitudes (a plane filter's n and nabs, see Plane;
// plain, as Diff).
struct Normal {
  Diff n;
  Diff nabs;
};

// The normal p x q of the triangle (o, p + o, q + o) and the magnitudes of its terms, as
// plane_filter makes them from corner o (p, q: the other corners less o, rounded).
inline Normal fan_normal(const Diff& p, const Diff& q) {
  const double m0 = p.y * q.z, m1 = p.z * q.y, m2 = p.z * q.x, m3 = p.x * q.z, m4 = p.x * q.y,
               m5 = p.y * q.x;
  return Normal{Diff{m0 - m1, m2 - m3, m4 - m5},
                Diff{std::fabs(m0) + std::fabs(m1), std::fabs(m2) + std::fabs(m3),
                     std::fabs(m4) + std::fabs(m5)}};
}

// The certain sign of d . (p x q) for the normal fan_normal(p, q) made and an exact d (dabs:
// its magnitudes), or 0: d . n is det[p, q, d], and its rounding error is below Shewchuk's
// orient3d bound (the same sum of coordinates times 2x2 minors: dabs . nabs; the plane
// filter's bound, with d for x - a). The absolute term covers products that underflow (d is
// scaled so that its largest component is 1).
inline int sure_sign(const Vec3& d, const Vec3& dabs, const Normal& nm) {
  const double det = d.x * nm.n.x + d.y * nm.n.y + d.z * nm.n.z;
  const double permanent = dabs.x * nm.nabs.x + dabs.y * nm.nabs.y + dabs.z * nm.nabs.z;
  const double bound = kPlaneFilter * permanent + 0x1p-1000;
  return det > bound ? 1 : (det < -bound ? -1 : 0);
}

// Do the fan's k triangles (o, u_i, u_i+1) (normals: theirs) certainly all face d, and does
// the fan turn once around o (e: u_i - o in fan order)?
bool fan_turns_once(const Vec3& d, const Normal* normals, const Diff* e, uint32_t k) {
  const Vec3 dabs{std::fabs(d.x), std::fabs(d.y), std::fabs(d.z)};
  bool turned = false;                // past the direction opposite u_0
  for (uint32_t i = 0; i < k; ++i) {  // (one loop for both tests: see star_embedded)
    if (sure_sign(d, dabs, normals[i]) != 1) return false;
    if (i < 2 || i + 1 >= k) continue;
    const int side = sure_sign(d, dabs, fan_normal(e[0], e[i]));
    if (side == 0 || (side > 0 && turned)) return false;
    turned = side < 0;
  }
  return true;
}

// The lanes of `ids` (whole groups of four) equal to x, as bits.
inline uint32_t equal_lanes(const uint32_t* ids, uint32_t groups, uint32_t x) {
  const Ids4 key{x, x, x, x};
  uint32_t bits = 0;
  for (uint32_t g = 0; g < groups; ++g) {
    Ids4 four;
    std::memcpy(&four, ids + 4 * g, sizeof(four));
    bits |= lane_bits(four == key, Mask4{0, 0, 0, 0}) << (4 * g);
  }
  return bits;
}

// A triangle of the star of vertex o as (o, from, to), in its winding.
struct Wing {
  uint32_t from, to;
};

// Is the star of vertex o (`star`: every non-degenerate triangle using o) certainly embedded?
bool star_embedded(const Vec3* v, uint32_t o, const Wing* star, uint32_t k) {
  if (k < 3 || k > kMaxStar) return false;
  // The lanes past k hold o, which is neither end of a wing (the triangles are not degenerate).
  static_assert(kMaxStar % 4 == 0, "whole groups of four");
  // (All of both set: clang-tidy's analyzer cannot see that a chain step stays in the groups.)
  uint32_t from[kMaxStar] = {}, to[kMaxStar] = {};
  const uint32_t groups = (k + 3) / 4;
  for (uint32_t i = 0; i < 4 * groups; ++i) {
    from[i] = i < k ? star[i].from : o;
    to[i] = i < k ? star[i].to : o;
  }
  // Chain: the next triangle starts where this one ends, and only one does. Coming back to
  // the first after exactly k steps, without coming back earlier, visits each once. On the
  // way, e_i = u_i - o in fan order, and the normal of triangle i - 1 of the fan, (o, u_i-1,
  // u_i), a rotation of its corners (fan_normal): one loop, not five (each loop's end is a
  // branch the predictor misses when the stars' sizes vary).
  Diff e[kMaxStar];
  Normal normals[kMaxStar];
  Vec3 d{};  // their sum, in order
  const Vec3& po = v[o];
  uint32_t at = 0;
  for (uint32_t step = 0; step < k; ++step) {
    if (step > 0 && at == 0) return false;
    const Vec3& u = v[from[at]];
    e[step] = Diff{u.x - po.x, u.y - po.y, u.z - po.z};
    if (step > 0) {
      normals[step - 1] = fan_normal(e[step - 1], e[step]);
      d = d + Vec3{normals[step - 1].n.x, normals[step - 1].n.y, normals[step - 1].n.z};
    }
    const uint32_t next = equal_lanes(from, groups, to[at]);
    if (next == 0 || (next & (next - 1)) != 0) return false;  // none, or more than one
    at = static_cast<uint32_t>(lowest_bit(next));
  }
  if (at != 0) return false;
  normals[k - 1] = fan_normal(e[k - 1], e[0]);
  d = d + Vec3{normals[k - 1].n.x, normals[k - 1].n.y, normals[k - 1].n.z};
  // The direction: the sum of the normals, or when that fails (a sharp fold between big and
  // small triangles leaves the small ones edge-on), of the normals scaled alike.
  if (fan_turns_once(scaled_to_unit_max(d), normals, e, k)) return true;
  d = Vec3{};
  for (uint32_t i = 0; i < k; ++i) {
    d = d + scaled_to_unit_max(Vec3{normals[i].n.x, normals[i].n.y, normals[i].n.z});
  }
  return fan_turns_once(scaled_to_unit_max(d), normals, e, k);
}

// ---- the hierarchy
// -------------------------------------------------------------------------------- Nodes in
// preorder (the left child of node i is i + 1) over ranges of the triangles in Morton order, split
// where the highest differing Morton bit changes (Karras); leaves of at most eight triangles,
// stored lane by lane so that one triangle is tested against a whole leaf at once.
constexpr uint32_t kLeafSize = 8;
constexpr uint32_t kMinLeaf = kLeafSize / 2;
// Each split either takes one of the 30 bits of the Morton code or halves a range of equal
// codes (at most 32 times for 2^32 triangles): the height stays below 64.
constexpr int kMaxHeight = 64;

struct Node {
  Dop dop;
  uint32_t right;  // 0 for a leaf
  uint32_t begin;  // the items below: begin .. begin + count - 1
  uint32_t count;
  uint32_t leaf;  // for a leaf
};

// A leaf, lane j holding item first + j; empty lanes never overlap anything.
struct alignas(16) Leaf {
  int16_t lo[kAxes][8];  // axis k of the eight triangles
  int16_t hi[kAxes][8];
  uint32_t ids[3][8];  // corner k's vertex id
  uint32_t first;
  uint32_t count;
};

inline Lanes8 load8(const int16_t* p) {
  Lanes8 x;
  std::memcpy(&x, p, sizeof(x));
  return x;
}

// The DOP of lane i of leaf a (the items' DOPs are kept only there).
inline Dop lane_dop(const Leaf& a, uint32_t i) {
  static_assert(kAxes == 7, "the seven axes below");
  return Dop{
      Lanes8{a.lo[0][i], a.lo[1][i], a.lo[2][i], a.lo[3][i], a.lo[4][i], a.lo[5][i], a.lo[6][i], 0},
      Lanes8{a.hi[0][i], a.hi[1][i], a.hi[2][i], a.hi[3][i], a.hi[4][i], a.hi[5][i], a.hi[6][i],
             0}};
}

// The lanes of leaf b whose DOP overlaps the DOP d of one triangle.
inline uint32_t overlapping_lanes(const Dop& d, const Leaf& b) {
  static_assert(kAxes == 7, "the seven axes below");
#define SPLINTCORE_AXIS(k) \
  ((SPLINTCORE_SPLAT8(d.lo, k) > load8(b.hi[k])) | (load8(b.lo[k]) > SPLINTCORE_SPLAT8(d.hi, k)))
  Lanes8 apart = SPLINTCORE_AXIS(0) | SPLINTCORE_AXIS(1) | SPLINTCORE_AXIS(2) | SPLINTCORE_AXIS(3);
  apart |= SPLINTCORE_AXIS(4) | SPLINTCORE_AXIS(5) | SPLINTCORE_AXIS(6);
#undef SPLINTCORE_AXIS
  return ~lane_bits(apart) & 0xffu;
}

// The lanes of leaf b whose x minimum is `from` or more (a slab's own pairs).
inline uint32_t lanes_from(const Leaf& b, int from) {
  const int16_t f = static_cast<int16_t>(from);
  return lane_bits(load8(b.lo[0]) >= Lanes8{f, f, f, f, f, f, f, f});
}

// The lanes of leaf b whose triangle uses one of the vertex ids c[0..2].
inline uint32_t lanes_using(const uint32_t* c, const Leaf& b) {
  const Ids4 c0{c[0], c[0], c[0], c[0]}, c1{c[1], c[1], c[1], c[1]}, c2{c[2], c[2], c[2], c[2]};
  Mask4 m[2];
  for (int g = 0; g < 2; ++g) {
    Ids4 id[3];
    for (int k = 0; k < 3; ++k) std::memcpy(&id[k], &b.ids[k][4 * g], sizeof(Ids4));
    m[g] = (id[0] == c0) | (id[0] == c1) | (id[0] == c2) | (id[1] == c0) | (id[1] == c1) |
           (id[1] == c2) | (id[2] == c0) | (id[2] == c1) | (id[2] == c2);
  }
  return lane_bits(m[0], m[1]);
}

// Stable LSD radix sort on bits 32..61 of the keys, ten at a time (three passes, where the
// library's byte-wise sort takes a histogram of all eight bytes and a pass per byte), on the
// executor: each pass counts the digits of each run, places digit by digit and, within a
// digit, run by run (the order of the serial stable sort), and each run scatters its keys.
// Returns the sorted array, which is `keys` or `scratch`.
uint64_t* sort_morton(const Executor* executor, uint64_t* keys, uint64_t* scratch, uint32_t n) {
  uint64_t* from = keys;
  uint64_t* to = scratch;
  uint32_t start[kRuns][1024];
  for (int shift = 32; shift < 62; shift += 10) {
    auto count = [&](uint32_t r) {
      for (uint32_t& c : start[r]) c = 0;
      for (size_t i = run_start(n, r); i < run_start(n, r + 1); ++i) {
        ++start[r][(from[i] >> shift) & 1023u];
      }
    };
    parallel_for_each(executor, kRuns, count);
    uint32_t sum = 0;
    for (uint32_t b = 0; b < 1024; ++b) {
      for (uint32_t r = 0; r < kRuns; ++r) {
        const uint32_t c = start[r][b];
        start[r][b] = sum;
        sum += c;
      }
    }
    auto scatter = [&](uint32_t r) {
      for (size_t i = run_start(n, r); i < run_start(n, r + 1); ++i) {
        to[start[r][(from[i] >> shift) & 1023u]++] = from[i];
      }
    };
    parallel_for_each(executor, kRuns, scatter);
    uint64_t* t = from;
    from = to;
    to = t;
  }
  return from;
}

// Spreads the low 10 bits of x to every third bit (for a 30-bit Morton code).
inline uint64_t spread_bits(uint32_t x) {
  uint64_t r = x & 0x3ffu;
  r = (r | (r << 16)) & 0x30000ffull;
  r = (r | (r << 8)) & 0x300f00full;
  r = (r | (r << 4)) & 0x30c30c3ull;
  r = (r | (r << 2)) & 0x9249249ull;
  return r;
}

// A triangle DOP's Morton code: of the middle of its quantized x, y, z extents, 10 bits each.
inline uint32_t morton_code(const Dop& d) {
  uint64_t code = 0;
  for (int k = 0; k < 3; ++k) {  // centres in 0 .. 65535
    const uint32_t c = static_cast<uint32_t>((d.lo[k] + d.hi[k]) / 2 + 32768);
    code |= spread_bits(c >> 6) << (2 - k);
  }
  return static_cast<uint32_t>(code);
}

// ---- the two passes
// ---------------------------------------------------------------------------------

// A triangle's place in the sweep's order (sweep(): keyed by its box's x minimum, computed as
// there, in a stable sort: equal keys by triangle id), and a pair's: its earlier triangle's
// place, then the later's (the sweep meets pairs in that order).
struct SweepPlace {
  uint64_t key;
  uint32_t t;
};
inline SweepPlace sweep_place(const Vec3* v, const Triangle* tris, uint32_t t) {
  const Vec3 &a = v[tris[t].v[0]], &b = v[tris[t].v[1]], &c = v[tris[t].v[2]];
  const double lo = a.x < b.x ? a.x : b.x;
  return SweepPlace{order_key(lo < c.x ? lo : c.x), t};
}
inline bool before(const SweepPlace& p, const SweepPlace& q) {
  return p.key < q.key || (p.key == q.key && p.t < q.t);
}
struct SweepPair {
  SweepPlace first, second;
};
inline SweepPair sweep_pair(const SweepPlace& p, const SweepPlace& q) {
  return before(p, q) ? SweepPair{p, q} : SweepPair{q, p};
}
inline bool before(const SweepPair& x, const SweepPair& y) {
  if (before(x.first, y.first)) return true;
  if (before(y.first, x.first)) return false;
  return before(x.second, y.second);
}

// The `size` first pairs in the sweep's order among those offered: a max-heap of them.
struct SweepFirst {
  const Vec3* v;
  const Triangle* tris;
  SweepPair* heap;
  uint64_t size;
  uint64_t count = 0;
  void offer(uint32_t s, uint32_t t) {
    const SweepPair p = sweep_pair(sweep_place(v, tris, s), sweep_place(v, tris, t));
    if (count < size) {
      uint64_t i = count++;
      while (i > 0 && before(heap[(i - 1) / 2], p)) {
        heap[i] = heap[(i - 1) / 2];
        i = (i - 1) / 2;
      }
      heap[i] = p;
      return;
    }
    if (!before(p, heap[0])) return;
    uint64_t i = 0;  // p replaces the root and goes down
    for (;;) {
      const uint64_t l = 2 * i + 1, r = l + 1;
      uint64_t next = i;
      const SweepPair* largest = &p;
      if (l < count && before(*largest, heap[l])) {
        next = l;
        largest = &heap[l];
      }
      if (r < count && before(*largest, heap[r])) next = r;
      if (next == i) break;
      heap[i] = heap[next];
      i = next;
    }
    heap[i] = p;
  }
};

// The tally both passes keep.
struct Tally {
  SelfIntersectionReport* report;
  uint64_t max_pairs;
  bool have_first = false;
  SweepFirst* sweep_first = nullptr;  // set: the pairs go there (and nothing stops)
  // Counts a conflicting pair; true when max_pairs is reached.
  bool add(uint32_t s, uint32_t t) {
    if (sweep_first != nullptr) {
      sweep_first->offer(s, t);
      return false;
    }
    ++report->intersecting_pairs;
    const uint32_t a = s < t ? s : t, b = s < t ? t : s;
    if (!have_first || a < report->first_a || (a == report->first_a && b < report->first_b)) {
      report->first_a = a;
      report->first_b = b;
      have_first = true;
    }
    return max_pairs != 0 && report->intersecting_pairs >= max_pairs;
  }
};

// Degenerate: a repeated vertex id, or collinear corners (exactly; with `filters`, a component
// of the normal that orient2d's filter finds nonzero settles most triangles first).
inline bool skipped(const Vec3* v, const Triangle& tri, bool filters) {
  if (tri.v[0] == tri.v[1] || tri.v[1] == tri.v[2] || tri.v[0] == tri.v[2]) return true;
  const Vec3 &a = v[tri.v[0]], &b = v[tri.v[1]], &c = v[tri.v[2]];
  if (filters) {
    const Vec3 e1 = b - a, e2 = c - a;
    const double l = e1.x * e2.y, r = e1.y * e2.x;
    if (std::fabs(l - r) > kOrient2dFilter * (std::fabs(l) + std::fabs(r))) return false;
  }
  return collinear3d(a, b, c);
}

// A triangle the hierarchy keeps (not skipped, with the filters), with its x cells (x_cells):
// the slabs' histogram and their membership (HierarchyPass::kept_here).
inline bool kept_x_cells(const Grid& g, const Vec3* v, const Triangle& tri, int* lo, int* hi) {
  if (skipped(v, tri, true)) return false;
  x_cells(g, v[tri.v[0]], v[tri.v[1]], v[tri.v[2]], lo, hi);
  return true;
}

// The sweep over boxes sorted by their x minimum (the original algorithm, and its order of
// discovery): every pair of non-skipped triangles whose boxes overlap, in that order, stopping
// at max_pairs. With a grid (coordinates within the range), the candidates are the pairs whose
// DOPs overlap, as in the hierarchy: each triangle is taken on past the end of its box, as far
// as a DOP's x extent can reach (2 M + 1 cells, and one more for the roundings: see the
// bounding volumes), and the DOPs decide instead of the boxes. The pairs beyond the box do not
// meet (the exact test says so), so the conflicts come in the original order all the same;
// and the filters are used.
Status sweep(const Context& ctx, const Vec3* v, const Triangle* tris, size_t nt, const Grid* grid,
             Tally* tally) {
  Arena& arena = *ctx.arena;
  ArenaScope scope(arena);
  SelfIntersectionReport* report = tally->report;
  const bool filters = grid != nullptr;
  struct SweepBox {
    double lo[3];
    double hi[3];
    uint32_t triangle;
    uint32_t skip;
  };
  KeyIndex* order = arena.allocate_array<KeyIndex>(nt);
  KeyIndex* scratch = arena.allocate_array<KeyIndex>(nt);
  Plane* planes = arena.allocate_array<Plane>(nt);
  Dop* dops = filters ? arena.allocate_array<Dop>(nt) : nullptr;
  SweepBox* boxes = arena.allocate_array<SweepBox>(nt);
  if ((order == nullptr || scratch == nullptr || planes == nullptr || boxes == nullptr ||
       (filters && dops == nullptr)) &&
      nt > 0) {
    return arena.exhausted_status();
  }
  for (size_t t = 0; t < nt; ++t) {
    const Triangle& tri = tris[t];
    const Vec3 &a = v[tri.v[0]], &b = v[tri.v[1]], &c = v[tri.v[2]];
    planes[t] = plane_of(a, b, c);
    if (filters) {
      dops[t] = triangle_dop(point_dop(*grid, a), point_dop(*grid, b), point_dop(*grid, c));
    }
    const double lo = a.x < b.x ? a.x : b.x;
    order[t] = KeyIndex{order_key(lo < c.x ? lo : c.x), static_cast<uint32_t>(t), 0};
  }
  radix_sort(Span<KeyIndex>(order, nt), Span<KeyIndex>(scratch, nt));
  // Boxes in sweep order, contiguous: the inner loop below runs over many pairs whose x
  // ranges overlap but y or z do not, and must stream through memory.
  for (size_t i = 0; i < nt; ++i) {
    const uint32_t t = order[i].index;
    const Triangle& tri = tris[t];
    SweepBox& b = boxes[i];
    for (int a = 0; a < 3; ++a) {
      const double x0 = v[tri.v[0]][a], x1 = v[tri.v[1]][a], x2 = v[tri.v[2]][a];
      const double lo = x0 < x1 ? x0 : x1, hi = x0 > x1 ? x0 : x1;
      b.lo[a] = lo < x2 ? lo : x2;
      b.hi[a] = hi > x2 ? hi : x2;
    }
    b.triangle = t;
    b.skip = skipped(v, tri, filters);
  }

  const double reach =
      filters ? (grid->scale[0] > 0.0 ? (2.0 * grid->margin[0] + 3.0) / grid->scale[0] : HUGE_VAL)
              : 0.0;
  for (size_t i = 0; i < nt; ++i) {
    if ((i & 0xfff) == 0) {
      SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "self-intersection", i, nt));
    }
    const SweepBox& bs = boxes[i];
    if (bs.skip) continue;
    const uint32_t s = bs.triangle;
    const double end = bs.hi[0] + reach;
    for (size_t j = i + 1; j < nt; ++j) {
      const SweepBox& bt = boxes[j];
      if (bt.lo[0] > end) break;
      if (bt.skip) continue;
      const uint32_t t = bt.triangle;
      if (filters ? !dops_overlap(dops[s], dops[t])
                  : bt.lo[0] > bs.hi[0] || bt.lo[1] > bs.hi[1] || bt.hi[1] < bs.lo[1] ||
                        bt.lo[2] > bs.hi[2] || bt.hi[2] < bs.lo[2]) {
        continue;
      }
      ++report->candidate_pairs;
      if (!conflict(v, tris[s], tris[t], planes[s], planes[t], filters)) continue;
      if (tally->add(s, t)) return Status::ok();
    }
  }
  return Status::ok();
}

// The hierarchy pass (hierarchy_pass() below) stage by stage: the kept triangles as items in
// Morton order, their DOPs, the tree over them, and the pairs it finds.
struct HierarchyPass {
  Arena& arena;
  const Vec3* v;
  size_t nv;
  const Triangle* tris;
  size_t nt;
  const Grid& grid;
  Tally* tally;
  const Executor* executor;       // for the stages' runs (nullptr: serial)
  uint32_t run_kept[kRuns] = {};  // the kept triangles of each run of the triangles
  double error = 0;               // of the separating directions (fill_item)
  Dop* vd = nullptr;              // the vertices' DOPs
  uint64_t* order = nullptr;      // the kept triangles: Morton code << 32 | triangle id, sorted
                                  // (until the items are made: then `codes` holds the codes)
  uint32_t kept = 0;
  Item* items = nullptr;      // in Morton order
  uint32_t* codes = nullptr;  // their Morton codes (for the tree's splits)
  Node* nodes = nullptr;
  Leaf* leaves = nullptr;
  // The tree's top levels, split as build_tree() splits them, down to kSubtrees ranges (or
  // fewer when ranges become leaves); each range's subtree is counted and built on its own,
  // into the nodes and leaves preorder gives it. above[]: the nodes above them.
  static constexpr uint32_t kSubtrees = 32;
  struct Subtree {
    uint32_t begin, count;   // its items
    uint32_t node, leaf;     // its first node and leaf
    uint32_t nodes, leaves;  // how many
  };
  Subtree sub[2 * kSubtrees] = {};
  uint32_t sub_count = 0;
  uint32_t above[2 * kSubtrees] = {};
  uint32_t above_count = 0;
  // A slab pass (hierarchy_in_slabs): only the triangles whose quantized x extent (x_cells)
  // meets slab_lo .. slab_hi, and only the pairs whose larger x minimum is slab_lo or more (the
  // pairs of this slab, each counted in one slab only). The vertices' DOPs are not kept then.
  bool in_slab = false;
  int slab_lo = INT16_MIN, slab_hi = INT16_MAX;
  uint32_t progress_from = 0, progress_to = 0;  // the share of nt a slab reports, see walk
  // Set: only count the candidates that come in the sweep's order no later than this pair
  // (first_in_sweep_order), testing none.
  const SweepPair* count_until = nullptr;

  HierarchyPass(Arena& a, const Vec3* vertices, size_t vertex_count, const Triangle* triangles,
                size_t triangle_count, const Grid& quantization, Tally* counts,
                const Executor* runs)
      : arena(a),
        v(vertices),
        nv(vertex_count),
        tris(triangles),
        nt(triangle_count),
        grid(quantization),
        tally(counts),
        executor(runs) {}

  // Is triangle t one of this pass's items?
  bool kept_here(size_t t) const {
    if (!in_slab) return !skipped(v, tris[t], true);
    int lo, hi;
    return kept_x_cells(grid, v, tris[t], &lo, &hi) && lo <= slab_hi && hi >= slab_lo;
  }

  // 1. The kept triangles counted, the room for their items and Morton codes: these stay
  // below the sort's arrays and the star lists, which go before the tree is made (the arena
  // is a stack). The items' DOPs are not kept beside them: the leaves hold them.
  Status allocate_items() {
    auto count = [&](uint32_t r) {
      uint32_t k = 0;
      for (size_t t = run_start(nt, r); t < run_start(nt, r + 1); ++t) {
        k += kept_here(t) ? 1u : 0u;
      }
      run_kept[r] = k;
    };
    parallel_for_each(executor, kRuns, count);
    for (uint32_t k : run_kept) kept += k;
    if (kept == 0) return Status::ok();
    items = arena.allocate_array<Item>(kept);
    codes = arena.allocate_array<uint32_t>(kept);
    if (items == nullptr || codes == nullptr) return arena.exhausted_status();
    return Status::ok();
  }

  // 2. The vertices' DOPs; the kept triangles' Morton codes (morton_code, in bits 32..61 above
  // the triangle id), sorted.
  Status sort_triangles() {
    order = arena.allocate_array<uint64_t>(kept);
    uint64_t* scratch = arena.allocate_array<uint64_t>(kept);
    vd = in_slab ? nullptr : arena.allocate_array<Dop>(nv);
    if (order == nullptr || scratch == nullptr || (vd == nullptr && nv > 0 && !in_slab)) {
      return arena.exhausted_status();
    }
    auto dops = [&](uint32_t r) {
      for (size_t i = run_start(nv, r); i < run_start(nv, r + 1); ++i) {
        vd[i] = point_dop(grid, v[i]);
      }
    };
    if (!in_slab) parallel_for_each(executor, kRuns, dops);
    uint32_t first[kRuns];  // of each run's keys
    for (uint32_t r = 0, at = 0; r < kRuns; ++r) {
      first[r] = at;
      at += run_kept[r];
    }
    auto keys = [&](uint32_t r) {
      uint32_t at = first[r];
      for (size_t t = run_start(nt, r); t < run_start(nt, r + 1); ++t) {
        const Triangle& tri = tris[t];
        if (!kept_here(t)) continue;
        const Dop d = vd != nullptr ? triangle_dop(vd[tri.v[0]], vd[tri.v[1]], vd[tri.v[2]])
                                    : triangle_dop(grid, v[tri.v[0]], v[tri.v[1]], v[tri.v[2]]);
        order[at++] = uint64_t{morton_code(d)} << 32 | t;
      }
      SPLINTCORE_ASSERT(at == first[r] + run_kept[r]);
    };
    parallel_for_each(executor, kRuns, keys);
    order = sort_morton(executor, order, scratch, kept);
    return Status::ok();
  }

  // 3. The items and their codes in Morton order.
  void make_items(double radius) {
    error = 1e-15 * radius;  // above 3 eps R, generously
    auto fill = [&](uint32_t r) {
      for (size_t i = run_start(kept, r); i < run_start(kept, r + 1); ++i) {
        const uint32_t t = static_cast<uint32_t>(order[i]);
        fill_item(v, tris[t], t, error, &items[i]);
        codes[i] = static_cast<uint32_t>(order[i] >> 32);
      }
    };
    parallel_for_each(executor, kRuns, fill);
  }

  // 5. The memory for the tree: its shape first, so that its nodes and leaves take what it
  // has (a leaf holds kMinLeaf to kLeafSize items, see split_point: on a real splint 5.5 on
  // average).
  Status allocate_tree() {
    find_subtrees();
    auto count = [&](uint32_t i) {
      Subtree& t = sub[i];
      t.nodes = t.leaves = 0;
      count_tree(t.begin, t.count, &t.nodes, &t.leaves);
    };
    parallel_for_each(executor, sub_count, count);
    uint32_t node_total = sub_count - 1, leaf_total = 0;  // a binary top over the subtrees
    for (uint32_t i = 0; i < sub_count; ++i) {
      node_total += sub[i].nodes;
      leaf_total += sub[i].leaves;
    }
    nodes = arena.allocate_array<Node>(node_total);
    leaves = arena.allocate_array<Leaf>(leaf_total);
    if (nodes == nullptr || leaves == nullptr) return arena.exhausted_status();
    return Status::ok();
  }

  // 4. Stars: per-vertex lists of the items' wings by counting sort (the wings, not the
  // items: read in the vertices' order, the items would come from all over), then each star
  // checked (its triangles' normals made there, from the differences the fan test takes).
  Status clear_stars() {
    ArenaScope star_scope(arena);
    uint32_t* start = arena.allocate_array<uint32_t>(nv + 1);
    Wing* list = arena.allocate_array<Wing>(3 * size_t{kept});
    uint8_t* cleared = arena.allocate_array<uint8_t>(nv);
    if (start == nullptr || list == nullptr || (cleared == nullptr && nv > 0)) {
      return arena.exhausted_status();
    }
    for (size_t i = 0; i <= nv; ++i) start[i] = 0;
    for (uint32_t i = 0; i < kept; ++i) {
      for (uint32_t id : items[i].tri.v) ++start[id + 1];
    }
    for (size_t i = 0; i < nv; ++i) start[i + 1] += start[i];
    for (uint32_t i = 0; i < kept; ++i) {
      const uint32_t a = items[i].tri.v[0], b = items[i].tri.v[1], c = items[i].tri.v[2];
      list[start[a]++] = Wing{b, c};
      list[start[b]++] = Wing{c, a};
      list[start[c]++] = Wing{a, b};
    }
    // start[i] is now the end of vertex i's list, the start of vertex i + 1's.
    auto stars = [&](uint32_t r) {
      for (size_t i = run_start(nv, r); i < run_start(nv, r + 1); ++i) {
        const uint32_t begin = i == 0 ? 0 : start[i - 1];
        cleared[i] = star_embedded(v, static_cast<uint32_t>(i), list + begin, start[i] - begin);
      }
    };
    parallel_for_each(executor, kRuns, stars);
    auto mark = [&](uint32_t r) {
      for (size_t i = run_start(kept, r); i < run_start(kept, r + 1); ++i) {
        const Triangle& tri = items[i].tri;
        items[i].cleared =
            static_cast<uint8_t>((cleared[tri.v[0]] ? 1u : 0u) | (cleared[tri.v[1]] ? 2u : 0u) |
                                 (cleared[tri.v[2]] ? 4u : 0u));
      }
    };
    parallel_for_each(executor, kRuns, mark);
    return Status::ok();
  }

  // Node `node` as the leaf of items begin .. begin + count - 1 (count <= kLeafSize).
  void fill_leaf(Node& node, uint32_t leaf_index, uint32_t begin, uint32_t count) {
    node.leaf = leaf_index;
    Leaf& leaf = leaves[leaf_index];
    leaf.first = begin;
    leaf.count = count;
    for (int k = 0; k < kAxes; ++k) {
      for (uint32_t j = 0; j < kLeafSize; ++j) {
        leaf.lo[k][j] = INT16_MAX;  // empty lanes: never overlap
        leaf.hi[k][j] = INT16_MIN;
      }
    }
    for (uint32_t j = 0; j < kLeafSize; ++j) {
      for (int k = 0; k < 3; ++k) leaf.ids[k][j] = 0;
    }
    for (uint32_t j = 0; j < count; ++j) {
      const Triangle& tri = items[begin + j].tri;
      const Dop d = triangle_dop(grid, v[tri.v[0]], v[tri.v[1]], v[tri.v[2]]);
      node.dop = j == 0 ? d : dop_union(node.dop, d);
      for (int k = 0; k < kAxes; ++k) {
        leaf.lo[k][j] = d.lo[k];
        leaf.hi[k][j] = d.hi[k];
      }
      for (int k = 0; k < 3; ++k) leaf.ids[k][j] = items[begin + j].tri.v[k];
    }
  }

  // The size of the first half of items begin .. begin + count - 1 (count > kLeafSize): where
  // the highest differing Morton bit changes (equal codes: in the middle), but leaving at
  // least kMinLeaf items on either side. So every leaf but a lone root holds kMinLeaf or more
  // (at most n / kMinLeaf leaves: the bound), and the height bound holds: a side cut short
  // is a leaf, the other side is all on one side of the bit.
  uint32_t split_point(uint32_t begin, uint32_t count) const {
    const uint32_t half = morton_split(begin, count);
    return half < kMinLeaf ? kMinLeaf : (half > count - kMinLeaf ? count - kMinLeaf : half);
  }
  uint32_t morton_split(uint32_t begin, uint32_t count) const {
    const uint32_t first = codes[begin];
    const uint32_t last = codes[begin + count - 1];
    if (first == last) return count / 2;
    const uint32_t bit = uint32_t{1} << (31 - __builtin_clz(first ^ last));
    uint32_t without = 0, with = count - 1;  // the bit: clear at without, set at with
    while (without + 1 < with) {
      const uint32_t mid = without + (with - without) / 2;
      if ((codes[begin + mid] & bit) == 0) {
        without = mid;
      } else {
        with = mid;
      }
    }
    return with;
  }

  // The number of nodes and leaves build_tree() makes below the range of `count` items from
  // `begin` (the same splits, nothing filled).
  void count_tree(uint32_t begin, uint32_t count, uint32_t* node_total,
                  uint32_t* leaf_total) const {
    struct Range {
      uint32_t begin, count;
    };
    Range stack[kMaxHeight + 2];
    int top_of_stack = 0;
    stack[top_of_stack++] = Range{begin, count};
    while (top_of_stack > 0) {
      const Range r = stack[--top_of_stack];
      ++*node_total;
      if (r.count <= kLeafSize) {
        ++*leaf_total;
        continue;
      }
      const uint32_t half = split_point(r.begin, r.count);
      SPLINTCORE_ASSERT(top_of_stack + 2 <= kMaxHeight + 2);
      stack[top_of_stack++] = Range{r.begin + half, r.count - half};
      stack[top_of_stack++] = Range{r.begin, half};
    }
  }

  // The top levels' ranges (see sub): every range of more than a leaf split, level by level,
  // until there are kSubtrees of them or all are leaves; in order of their items.
  void find_subtrees() {
    sub[0] = Subtree{0, kept, 0, 0, 0, 0};
    sub_count = 1;
    bool split = true;
    while (split && sub_count < kSubtrees) {
      split = false;
      Subtree next[2 * kSubtrees];
      uint32_t m = 0;
      for (uint32_t i = 0; i < sub_count; ++i) {
        const Subtree& r = sub[i];
        if (r.count <= kLeafSize) {
          next[m++] = r;
          continue;
        }
        const uint32_t half = split_point(r.begin, r.count);
        next[m++] = Subtree{r.begin, half, 0, 0, 0, 0};
        next[m++] = Subtree{r.begin + half, r.count - half, 0, 0, 0, 0};
        split = true;
      }
      std::memcpy(sub, next, m * sizeof(Subtree));
      sub_count = m;
    }
  }

  // 6. Build: the nodes in preorder, the top levels first (their nodes, and each subtree's
  // place: its counts are known), then the subtrees in parallel; bounds bottom-up (children
  // come after their parent), the subtrees' in their tasks, then the top's.
  void build_tree() {
    place_subtrees();
    auto build = [&](uint32_t i) { build_subtree(sub[i]); };
    parallel_for_each(executor, sub_count, build);
    for (uint32_t k = above_count; k-- > 0;) {
      Node& node = nodes[above[k]];
      node.dop = dop_union(nodes[above[k] + 1].dop, nodes[node.right].dop);
    }
  }

  // The top levels in preorder, with an explicit stack of ranges (and the parent waiting for
  // its right child): a subtree's range takes its place, the others are split.
  void place_subtrees() {
    struct Pending {
      uint32_t begin, count, parent;  // parent: UINT32_MAX for the root or a left child
    };
    Pending stack[kMaxHeight + 2];
    int top_of_stack = 0;
    stack[top_of_stack++] = Pending{0, kept, UINT32_MAX};
    uint32_t next_sub = 0, node_at = 0, leaf_at = 0;
    while (top_of_stack > 0) {
      const Pending p = stack[--top_of_stack];
      if (p.parent != UINT32_MAX) nodes[p.parent].right = node_at;
      if (next_sub < sub_count && p.begin == sub[next_sub].begin &&
          p.count == sub[next_sub].count) {
        Subtree& t = sub[next_sub++];
        t.node = node_at;
        t.leaf = leaf_at;
        node_at += t.nodes;
        leaf_at += t.leaves;
        continue;
      }
      above[above_count++] = node_at;
      Node& node = nodes[node_at];
      node = Node{Dop{}, 0, p.begin, p.count, 0};
      const uint32_t half = split_point(p.begin, p.count);
      SPLINTCORE_ASSERT(top_of_stack + 2 <= kMaxHeight + 2);
      stack[top_of_stack++] = Pending{p.begin + half, p.count - half, node_at++};
      stack[top_of_stack++] = Pending{p.begin, half, UINT32_MAX};
    }
    SPLINTCORE_ASSERT(next_sub == sub_count);
  }

  // One subtree in preorder into its nodes and leaves, leaves filled as they come, then its
  // bounds bottom-up. Its root's parent is linked already.
  void build_subtree(const Subtree& t) {
    struct Pending {
      uint32_t begin, count, parent;  // parent: UINT32_MAX for the root or a left child
    };
    Pending stack[kMaxHeight + 2];
    int top_of_stack = 0;
    stack[top_of_stack++] = Pending{t.begin, t.count, UINT32_MAX};
    uint32_t node_at = t.node, leaf_at = t.leaf;
    while (top_of_stack > 0) {
      const Pending p = stack[--top_of_stack];
      const uint32_t index = node_at++;
      if (p.parent != UINT32_MAX) nodes[p.parent].right = index;
      Node& node = nodes[index];
      node.begin = p.begin;
      node.count = p.count;
      node.right = 0;
      if (p.count <= kLeafSize) {
        fill_leaf(node, leaf_at++, p.begin, p.count);
        continue;
      }
      const uint32_t half = split_point(p.begin, p.count);
      SPLINTCORE_ASSERT(top_of_stack + 2 <= kMaxHeight + 2);
      stack[top_of_stack++] = Pending{p.begin + half, p.count - half, index};
      stack[top_of_stack++] = Pending{p.begin, half, UINT32_MAX};
    }
    SPLINTCORE_ASSERT(node_at == t.node + t.nodes && leaf_at == t.leaf + t.leaves);
    for (uint32_t i = node_at; i-- > t.node;) {
      Node& node = nodes[i];
      if (node.right != 0) node.dop = dop_union(nodes[i + 1].dop, nodes[node.right].dop);
    }
  }

  // Items i and j, whose DOPs overlap: sharing a cleared vertex, no conflict; sharing none,
  // the separating directions first; the rest to the exact tests. True when the tally is full.
  bool test_pair(uint32_t i, uint32_t j, Tally* found) const {
    const Item& s = items[i];
    const Item& t = items[j];
    const uint32_t shared = shared_corners(s, t);  // of t
    const uint32_t s0 = s.tri.v[0], s1 = s.tri.v[1], s2 = s.tri.v[2];
    const uint32_t t0 = t.tri.v[0], t1 = t.tri.v[1], t2 = t.tri.v[2];
    if (shared == 0) {
      const Vec3 &a = v[s0], &b = v[s1], &c = v[s2], &d = v[t0], &e = v[t1], &f = v[t2];
      if (beyond(ready_direction(s), static_cast<double>(s.lo), static_cast<double>(s.hi), d, e,
                 f) ||
          beyond(ready_direction(t), static_cast<double>(t.lo), static_cast<double>(t.hi), a, b,
                 c)) {
        return false;
      }
      if (beyond_other_axes(s, a, b, c, d, e, f, error) ||
          beyond_other_axes(t, d, e, f, a, b, c, error)) {
        return false;
      }
    } else if ((shared & t.cleared) != 0) {
      return false;  // part of a cleared star
    }
    if (!conflict(v, s.tri, t.tri, plane_of(v, s), plane_of(v, t), true)) {
      return false;
    }
    return found->add(s.id, t.id);
  }

  // The pairs of two leaves (the same leaf: i < j) whose DOPs overlap: one triangle of a
  // against all of b at once; those that share a cleared vertex dropped (their stars are
  // embedded), the rest decided one by one, counted in *candidates. True when the tally is
  // full.
  bool leaf_pairs(const Leaf& a, const Leaf& b, const Dop& da, const Dop& db, bool same,
                  Tally* found, uint64_t* tested) const {
    const uint32_t valid = (1u << b.count) - 1;
    // Two leaves: only the triangles of each whose DOP overlaps the other leaf's (its node's
    // DOP, the union of its lanes') can overlap one of its triangles.
    uint32_t rows = (1u << a.count) - 1;
    const uint32_t cols = same ? valid : valid & overlapping_lanes(da, b);
    if (!same) rows &= overlapping_lanes(db, a);
    for (; rows != 0; rows &= rows - 1) {
      const uint32_t i = static_cast<uint32_t>(lowest_bit(rows));
      const uint32_t lanes = same ? valid & ~((2u << i) - 1) : cols;
      if (lanes == 0) break;
      const uint32_t si = a.first + i;
      uint32_t bits = overlapping_lanes(lane_dop(a, i), b) & lanes;
      if (a.lo[0][i] < slab_lo) bits &= lanes_from(b, slab_lo);  // another slab's pairs
      if (bits == 0) continue;
      if (count_until != nullptr) {
        *tested += count_before(si, b.first, bits);
        continue;
      }
      *tested += lane_count(bits);
      const Item& s = items[si];
      const uint32_t cleared_ids[3] = {(s.cleared & 1u) != 0 ? s.tri.v[0] : UINT32_MAX,
                                       (s.cleared & 2u) != 0 ? s.tri.v[1] : UINT32_MAX,
                                       (s.cleared & 4u) != 0 ? s.tri.v[2] : UINT32_MAX};
      bits &= ~lanes_using(cleared_ids, b);
      while (bits != 0) {
        const uint32_t j = b.first + static_cast<uint32_t>(lowest_bit(bits));
        bits &= bits - 1;
        if (test_pair(si, j, found)) return true;
      }
    }
    return false;
  }

  // The pairs of item si with items first + j, j a bit of `bits`, that the sweep meets no
  // later than *count_until.
  uint64_t count_before(uint32_t si, uint32_t first, uint32_t bits) const {
    const SweepPlace p = sweep_place(v, tris, items[si].id);
    uint64_t n = 0;
    while (bits != 0) {
      const uint32_t j = first + static_cast<uint32_t>(lowest_bit(bits));
      bits &= bits - 1;
      n += before(*count_until, sweep_pair(p, sweep_place(v, tris, items[j].id))) ? 0u : 1u;
    }
    return n;
  }

  // 7. Traversal of the hierarchy against itself: (i, i) stands for the pairs within node i,
  // (i, j) for those between two nodes whose DOPs overlap. Depth first: each step goes one
  // level down in one of the two nodes and leaves at most two pairs pending, so the stack
  // never holds more than 4 * height + 1.
  struct PairOfNodes {
    uint32_t a, b;
  };

  // The pairs p stands for one level down, in the order the walk pushes them (its last is
  // walked first); -1 when p is a leaf with itself or two leaves (leaf_pairs' work).
  int open(const PairOfNodes& p, PairOfNodes out[3]) const {
    const Node& na = nodes[p.a];
    const Node& nb = nodes[p.b];
    // (The pairs are written whether they overlap or not, and the count advanced by whether
    // they do: the overlaps are a coin toss to the branch predictor.)
    if (p.a == p.b) {
      if (na.right == 0) return -1;
      const uint32_t l = p.a + 1, r = na.right;
      const int both = dops_overlap(nodes[l].dop, nodes[r].dop) ? 1 : 0;
      out[0] = PairOfNodes{l, r};
      out[both] = PairOfNodes{r, r};
      out[both + 1] = PairOfNodes{l, l};
      return both + 2;
    }
    if (na.right == 0 && nb.right == 0) return -1;
    // Open the larger node.
    const bool open_a = nb.right == 0 || (na.right != 0 && na.count >= nb.count);
    const uint32_t keep = open_a ? p.b : p.a;
    const uint32_t opened = open_a ? p.a : p.b;
    const Dop& other = nodes[keep].dop;
    const uint32_t l = opened + 1, r = nodes[opened].right;
    const int with_r = dops_overlap(nodes[r].dop, other) ? 1 : 0;
    const int with_l = dops_overlap(nodes[l].dop, other) ? 1 : 0;
    out[0] = PairOfNodes{r, keep};
    out[with_r] = PairOfNodes{l, keep};
    return with_r + with_l;
  }

  // The pairs below `start`, depth first, into *found and *tested; with ctx, progress
  // (and a cancel) every 65,536 steps (a slab's: its done items, from progress_from, kept
  // below progress_to). *stop: the tally is full.
  Status walk(const Context* ctx, const PairOfNodes& start, Tally* found, uint64_t* tested,
              uint32_t* done, bool* stop) const {
    constexpr int kMaxStack = 4 * kMaxHeight + 8;
    PairOfNodes stack[kMaxStack];
    int top = 0;
    stack[top++] = start;
    uint64_t steps = 0;
    while (top > 0 && !*stop) {
      if (ctx != nullptr && (++steps & 0xffff) == 0) {
        uint64_t at = *done;
        if (in_slab) at = at + progress_from < progress_to ? at + progress_from : progress_to;
        SPLINTCORE_RETURN_IF_ERROR(report_progress(*ctx, "self-intersection", at, nt));
      }
      const PairOfNodes p = stack[--top];
      SPLINTCORE_ASSERT(top + 3 <= kMaxStack);
      const int n = open(p, stack + top);
      if (n >= 0) {
        top += n;
        continue;
      }
      const Node& na = nodes[p.a];
      const Node& nb = nodes[p.b];
      *stop =
          leaf_pairs(leaves[na.leaf], leaves[nb.leaf], na.dop, nb.dop, p.a == p.b, found, tested);
      if (p.a == p.b) *done += na.count;
    }
    return Status::ok();
  }

  // The whole traversal: in tasks on the executor when there is one (traverse_in_tasks),
  // otherwise one walk from the root. Sets *stopped when the tally is full.
  Status traverse(const Context& ctx, bool* stopped) {
    uint64_t candidates = 0;
    bool stop = false;
    // (Tasks keep tallies of their own: the sweep's order is kept on one thread.)
    const bool serial = tally->sweep_first != nullptr || count_until != nullptr;
    if (serial || !traverse_in_tasks(&candidates, &stop)) {
      uint32_t done = 0;  // triangles whose leaf is done with itself (for progress)
      SPLINTCORE_RETURN_IF_ERROR(walk(&ctx, PairOfNodes{0, 0}, tally, &candidates, &done, &stop));
    }
    tally->report->candidate_pairs += candidates;
    *stopped = stop;
    return Status::ok();
  }

  // The root opened level by level (the walk's own rule) until the pairs pending are enough
  // for the tasks; each task walks a run of them with its own tally, and the tallies are
  // summed. The traversal visits every pair whose DOPs overlap whatever the order, so the
  // counts, candidates and smallest pair are those of one walk, unless the tally fills up,
  // which stops the pass either way (the sweep then answers). False: one thread (no
  // executor, or too few triangles to share).
  bool traverse_in_tasks(uint64_t* candidates, bool* stop) const {
    constexpr size_t kFrontier = 768, kEnough = 256, kMinItems = 8192;
    constexpr uint32_t kMaxTasks = 16;
    if (!has_threads(executor) || kept < kMinItems) return false;
    PairOfNodes pending[kFrontier], next[kFrontier];
    size_t n = 1;
    pending[0] = PairOfNodes{0, 0};
    bool opened = true;
    while (opened && n < kEnough && 3 * n <= kFrontier) {
      opened = false;
      size_t m = 0;
      for (size_t i = 0; i < n; ++i) {
        const int k = open(pending[i], next + m);
        if (k < 0) {
          next[m++] = pending[i];
        } else {
          m += static_cast<size_t>(k);
          opened = true;
        }
      }
      std::memcpy(pending, next, m * sizeof(PairOfNodes));
      n = m;
    }
    uint32_t tasks = executor->concurrency * 4;
    tasks = tasks > kMaxTasks ? kMaxTasks : tasks;
    struct Part {
      SelfIntersectionReport report;
      Tally tally{nullptr, 0};
      uint64_t candidates = 0;
      bool stop = false;
    };
    Part part[kMaxTasks];
    auto task = [&](uint32_t t) {
      Part& p = part[t];
      p.tally = Tally{&p.report, tally->max_pairs};
      uint32_t done = 0;
      for (size_t i = n * t / tasks; i < n * (t + 1) / tasks && !p.stop; ++i) {
        (void)walk(nullptr, pending[i], &p.tally, &p.candidates, &done, &p.stop);
      }
    };
    parallel_for_each(executor, tasks, task);
    SelfIntersectionReport* r = tally->report;
    for (uint32_t t = 0; t < tasks; ++t) {
      const Part& p = part[t];
      *candidates += p.candidates;
      *stop = *stop || p.stop;
      r->intersecting_pairs += p.report.intersecting_pairs;
      if (p.tally.have_first &&
          (!tally->have_first || p.report.first_a < r->first_a ||
           (p.report.first_a == r->first_a && p.report.first_b < r->first_b))) {
        r->first_a = p.report.first_a;
        r->first_b = p.report.first_b;
        tally->have_first = true;
      }
    }
    *stop = *stop || (tally->max_pairs != 0 && r->intersecting_pairs >= tally->max_pairs);
    return true;
  }
};

constexpr uint64_t kMostSweepFirst = 65536;  // Pass::first_in_sweep_order's max_pairs

// A slab of the x axis in quantized cells (see HierarchyPass::in_slab), and the share of the
// progress its walk reports.
struct Slab {
  int lo, hi;
  uint32_t progress_from, progress_to;
};

// The hierarchy pass: every pair of non-skipped triangles whose DOPs overlap (with a slab: of
// the slab's), counted all, or stopped (*stopped set) once tally->max_pairs is reached. Needs
// coordinates within the range (radius >= 0), nv <= 3 nt (the memory bound) and nv < 2^32 - 1
// (UINT32_MAX is no vertex id).
Status hierarchy_pass(const Context& ctx, const Vec3* v, size_t nv, const Triangle* tris, size_t nt,
                      double radius, const Grid& grid, const Slab* slab,
                      const SweepPair* count_until, Tally* tally, bool* stopped) {
  Arena& arena = *ctx.arena;
  ArenaScope scope(arena);
  *stopped = false;
  SPLINTCORE_ASSERT(nv <= 3 * nt && nv < UINT32_MAX);
  HierarchyPass pass(arena, v, nv, tris, nt, grid, tally, ctx.executor);
  pass.count_until = count_until;
  if (slab != nullptr) {
    pass.in_slab = true;
    pass.slab_lo = slab->lo;
    pass.slab_hi = slab->hi;
    pass.progress_from = slab->progress_from;
    pass.progress_to = slab->progress_to;
  }
  SPLINTCORE_RETURN_IF_ERROR(pass.allocate_items());
  if (pass.kept == 0) return Status::ok();
  {
    // The sort's keys and the vertices' DOPs are done with once the items are made: the star
    // lists, then the tree take their room.
    ArenaScope sorting(arena);
    SPLINTCORE_RETURN_IF_ERROR(pass.sort_triangles());
    pass.make_items(radius);
    pass.order = nullptr;
    pass.vd = nullptr;
  }
  SPLINTCORE_RETURN_IF_ERROR(pass.clear_stars());
  SPLINTCORE_RETURN_IF_ERROR(pass.allocate_tree());
  pass.build_tree();
  return pass.traverse(ctx, stopped);
}

// The most a hierarchy pass over `kept` items takes: the items and their codes, and above them
// in turn the keys, scratch and the DOPs of `dop_vertices` vertices (nv, or none in a slab),
// the star lists of nv vertices, and the leaves (every one but a lone root holds kMinLeaf items
// or more) with the nodes (one fewer than twice the leaves); each array's alignment.
uint64_t pass_bound(uint64_t kept, uint64_t dop_vertices, uint64_t nv) {
  const uint64_t sorting = kept * 2 * sizeof(uint64_t) + dop_vertices * sizeof(Dop);
  const uint64_t stars = (nv + 1) * sizeof(uint32_t) + 3 * kept * sizeof(Wing) + nv;
  const uint64_t nodes = (kept / kMinLeaf + 1) * (2 * sizeof(Node) + sizeof(Leaf));
  uint64_t above = sorting > stars ? sorting : stars;
  above = above > nodes ? above : nodes;
  return kept * (sizeof(Item) + sizeof(uint32_t)) + above + 10 * 64;
}

// The hierarchy pass in slabs along x, when the whole pass does not fit in what the arena has
// left: the x axis's cells in bins (16 to 2048 of them, about a bin for 16 triangles, so that
// the counts take little room beside a small mesh's pass), and each slab as many bins as the
// pass over its
// triangles (those whose x extent meets it) is sure to fit (pass_bound; a bin that alone does
// not is tried all the same). A pair whose DOPs overlap belongs to the slab that holds the larger
// of their x minima: both triangles reach it (each one's extent holds both minima's larger,
// up to the smaller maximum), so it is found there, and only there. The counts, candidates and
// smallest pair are those of the whole pass; so is stopping (the tally goes on from slab to
// slab). A star is cleared from the slab's triangles that use it: a subset of a star that is
// a single fan turning once is certainly embedded too, and the pairs a slab tests are of its
// triangles. The cost: each slab scans all triangles, and the triangles that cross a boundary
// are in two slabs' hierarchies.
inline uint32_t slab_bin(int cell, int shift, uint32_t bins) {
  const int b = (cell + 32768) >> shift;
  return b < 0 ? 0u : (b >= static_cast<int>(bins) ? bins - 1 : static_cast<uint32_t>(b));
}

Status hierarchy_in_slabs(const Context& ctx, const Vec3* v, size_t nv, const Triangle* tris,
                          size_t nt, double radius, const Grid& grid, const SweepPair* count_until,
                          Tally* tally, bool* stopped) {
  Arena& arena = *ctx.arena;
  ArenaScope scope(arena);
  // lo_below[b]: the kept triangles whose x minimum's bin is below b; hi_below[b] the same for
  // the maximum. Slab b0 .. b1 holds lo_below[b1 + 1] - hi_below[b0] (a triangle whose maximum
  // is below b0 has its minimum there too).
  uint32_t bins = 16;
  int shift = 12;  // 65536 cells over the bins
  while (bins < 2048 && uint64_t{bins} * 16 < nt) {
    bins *= 2;
    --shift;
  }
  uint32_t* lo_below = arena.allocate_array<uint32_t>(bins + 1);
  uint32_t* hi_below = arena.allocate_array<uint32_t>(bins + 1);
  if (lo_below == nullptr || hi_below == nullptr) return arena.exhausted_status();
  for (uint32_t b = 0; b <= bins; ++b) lo_below[b] = hi_below[b] = 0;
  for (size_t t = 0; t < nt; ++t) {
    int lo, hi;
    if (!kept_x_cells(grid, v, tris[t], &lo, &hi)) continue;
    ++lo_below[slab_bin(lo, shift, bins) + 1];
    ++hi_below[slab_bin(hi, shift, bins) + 1];
  }
  for (uint32_t b = 0; b < bins; ++b) {
    lo_below[b + 1] += lo_below[b];
    hi_below[b + 1] += hi_below[b];
  }
  const size_t left = arena.cap() > arena.used() ? arena.cap() - arena.used() : 0;
  uint64_t most = 0, beyond = uint64_t{nt} + 1;  // fits, does not
  while (most + 1 < beyond) {
    const uint64_t mid = most + (beyond - most) / 2;
    if (pass_bound(mid, 0, nv) <= left) {
      most = mid;
    } else {
      beyond = mid;
    }
  }
  for (uint32_t b0 = 0; b0 < bins;) {
    uint32_t b1 = b0;
    while (b1 + 1 < bins && lo_below[b1 + 2] - hi_below[b0] <= most) ++b1;
    const Slab slab{static_cast<int>(b0 << shift) - 32768,
                    static_cast<int>(((b1 + 1) << shift) - 1) - 32768, lo_below[b0],
                    lo_below[b1 + 1]};
    SPLINTCORE_RETURN_IF_ERROR(
        hierarchy_pass(ctx, v, nv, tris, nt, radius, grid, &slab, count_until, tally, stopped));
    if (*stopped) return Status::ok();
    b0 = b1 + 1;
  }
  return Status::ok();
}

}  // namespace

// The hierarchy over a mesh's triangles, whole or in slabs.
struct Pass {
  const Context& ctx;
  const Vec3* v;
  size_t nv;
  const Triangle* tris;
  size_t nt;
  double radius;
  const Grid& grid;

  // The whole pass, or in slabs when it does not fit (the same answer in less memory): at
  // once when its sort alone (items, codes, keys and the vertices' DOPs) would not.
  Status run(const SweepPair* count_until, Tally* tally, bool* stopped) const {
    Arena& arena = *ctx.arena;
    const size_t left = arena.cap() > arena.used() ? arena.cap() - arena.used() : 0;
    const uint64_t sort_needs =
        uint64_t{nt} * (sizeof(Item) + 5 * sizeof(uint32_t)) + uint64_t{nv} * sizeof(Dop);
    bool in_slabs = sort_needs > left;
    const SelfIntersectionReport before = *tally->report;
    if (!in_slabs) {
      const Status whole =
          hierarchy_pass(ctx, v, nv, tris, nt, radius, grid, nullptr, count_until, tally, stopped);
      in_slabs = whole.code() == StatusCode::kArenaExhausted;
      if (!in_slabs) return whole;
    }
    arena.forget_failure();
    *tally->report = before;  // (nothing is counted before the pass's memory is all taken)
    return hierarchy_in_slabs(ctx, v, nv, tris, nt, radius, grid, count_until, tally, stopped);
  }

  // The report of the sweep (sweep()) when more than max_pairs > 0 pairs conflict: it stops
  // at the max_pairs-th conflicting pair it meets, P, having counted the candidates (pairs of
  // overlapping DOPs, as here) it met up to P, and its first pair is the smallest of the pairs
  // it counted. Here: a pass that keeps the max_pairs first conflicting pairs in the sweep's
  // order (SweepFirst), then one that counts the candidates no later than P, the last of them.
  // Memory: a pass's, and 32 bytes per pair kept.
  Status first_in_sweep_order(uint64_t max_pairs, SelfIntersectionReport* report) const {
    Arena& arena = *ctx.arena;
    ArenaScope scope(arena);
    SweepPair* heap = arena.allocate_array<SweepPair>(static_cast<size_t>(max_pairs));
    if (heap == nullptr) return arena.exhausted_status();
    SweepFirst first{v, tris, heap, max_pairs};
    SelfIntersectionReport unused;
    Tally keep{&unused, 0};
    keep.sweep_first = &first;
    bool stopped = false;
    SPLINTCORE_RETURN_IF_ERROR(run(nullptr, &keep, &stopped));
    SPLINTCORE_ASSERT(first.count == max_pairs);  // (more than max_pairs conflict)
    const SweepPair last = heap[0];
    Tally count{report, 0};
    SPLINTCORE_RETURN_IF_ERROR(run(&last, &count, &stopped));
    report->intersecting_pairs = max_pairs;
    for (uint64_t i = 0; i < max_pairs; ++i) {
      const uint32_t s = heap[i].first.t, t = heap[i].second.t;
      const uint32_t a = s < t ? s : t, b = s < t ? t : s;
      if (i == 0 || a < report->first_a || (a == report->first_a && b < report->first_b)) {
        report->first_a = a;
        report->first_b = b;
      }
    }
    return Status::ok();
  }
};

uint64_t find_self_intersections_bound(uint64_t triangle_count) {
  const uint64_t n = triangle_count;
  // The whole hierarchy pass (at most 3n vertices).
  const uint64_t tree = pass_bound(n, 3 * n, 3 * n);
  // The sweep: keys, planes, DOPs, boxes.
  const uint64_t sweep_bytes =
      n * (2 * sizeof(KeyIndex) + sizeof(Plane) + sizeof(Dop) + 56) + 6 * 64;
  return tree > sweep_bytes ? tree : sweep_bytes;
}

Status find_self_intersections(const Context& ctx, const Mesh& mesh, uint64_t max_pairs,
                               SelfIntersectionReport* report) {
  *report = SelfIntersectionReport{};
  const size_t nt = mesh.triangles.size();
  const size_t nv = mesh.vertices.size();
  if (nt > UINT32_MAX) {
    return make_error(StatusCode::kLimitExceeded, "mesh too large: ", nt, " triangles");
  }
  const Vec3* v = mesh.vertices.data();
  const Triangle* tris = mesh.triangles.data();
  MeshScan scan;
  scan.run(ctx.executor, v, nv, tris, nt);
  const size_t bad = scan.first_bad(nt);
  if (bad != nt) {
    return make_error(StatusCode::kInvalidMesh, "triangle ", bad,
                      " refers to a vertex that does not exist")
        .at_index(bad);
  }
  SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "self-intersection", 0, nt));
  const double radius = scan.exact_radius();
  if (radius < 0.0) {
    // Non-finite or extreme coordinates: no filter bound holds and nothing is exact there;
    // the sweep over boxes answers as it always has.
    Tally tally{report, max_pairs};
    return sweep(ctx, v, tris, nt, nullptr, &tally);
  }
  const Grid grid = scan.grid(nv, radius);
  if (nv <= 3 * nt && nv < UINT32_MAX) {
    // All pairs are counted unless there are more than max_pairs: the pass stops at one more.
    Tally all{report, max_pairs != 0 && max_pairs != UINT64_MAX ? max_pairs + 1 : 0};
    bool stopped = false;
    const Pass pass{ctx, v, nv, tris, nt, radius, grid};
    SPLINTCORE_RETURN_IF_ERROR(pass.run(nullptr, &all, &stopped));
    if (!stopped) return Status::ok();
    *report = SelfIntersectionReport{};
    // More than max_pairs: which pairs count then depends on the order of discovery. The
    // answer is the sweep's (below), found by the hierarchy in its memory.
    if (max_pairs <= kMostSweepFirst) return pass.first_in_sweep_order(max_pairs, report);
  }
  // More than max_pairs, too many of them for the hierarchy's answer, or more vertices than
  // the hierarchy's memory bound allows: the sweep, whose order of discovery is the answer.
  Tally tally{report, max_pairs};
  return sweep(ctx, v, tris, nt, &grid, &tally);
}

}  // namespace splintcore
