// Tests of the exact closed triangle-triangle and segment-triangle tests
// (src/geometry/triangle.cpp) against an independent oracle written here.
//
// The oracle (namespace splintcore_test::tri_oracle, also used by
// tests/mesh/self_intersect_test.cpp) never calls the library's orient2d/orient3d. It scales
// all coordinates of one query to integers on one common power-of-two scale (as
// splintcore_test::to_common_scale does, tests/support/exact.h) and decides everything with
// exact integer arithmetic (splintcore_test::BigInt; __int128 when the integers are small
// enough, checked against BigInt by ArithmeticPathsAgree), the coplanar case by exact 2D
// orientations in a projection chosen by an exact sign. Its algorithms differ from the
// library's: the separating axis theorem in 3D (the library tests edges against triangles),
// vertex-in-triangle and edge-edge tests in 2D (the library uses 2D separating axes).
// Its code is checked by hand-made cases and by self-consistency (TriangleOracle.*).
//
// The inputs: hundreds of thousands of random pairs in small boxes (small integers, where
// touching and coplanar pairs are common, float32 values, dyadic grids, and the same scaled by
// 2^+-200), and adversarial constructions: a vertex exactly on the other's face, edge or vertex,
// an edge passing exactly through the other's edge or vertex, collinear overlapping edges,
// exactly coplanar pairs (from small integers in a tilted integer basis, and from float32
// values), each with its one-ulp perturbations (std::nextafter) across the touching
// configuration. Every answer of the library, in several vertex and argument orders, is
// compared with the oracle; none may differ. The tests also assert that the sets are hard:
// both answers are common, and many cases are knife edges (one ulp changes the answer).
//
// All random streams are std::mt19937_64 with fixed seeds, doubles made from its raw bits.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "splintcore/geometry.h"
#include "support/exact.h"

// Inputs are built with floating-point arithmetic: no FMA contraction, so every compiler
// builds the same inputs.
#if defined(__clang__)
#pragma STDC FP_CONTRACT OFF
#elif defined(__GNUC__)
#pragma GCC optimize("fp-contract=off")
#endif

// =============================================================================================
// The oracle.
//
// Closed convex sets A and B are disjoint iff 0 is not in their Minkowski difference
// M = A + (-B) (a convex polytope: the hull of the differences of their vertices). For a
// polytope, 0 is outside iff some facet's supporting half-space excludes it strictly, i.e.
// iff for that facet's outward normal u: max over A of u.x < min over B of u.y (strict, as
// both sets are closed). So A and B are disjoint iff their projections onto some facet normal
// of M are disjoint intervals; testing more axes than the facet normals is harmless (any axis
// with disjoint projections separates), so an axis list only has to contain every possible
// facet normal. (The coordinate axes are tried first, as a cheap extra.)
//
// Facets of M = A + (-B) are sums F_A + F_B of faces of A and -B maximising the same direction,
// with dim 2 when M is 3-dimensional. So:
// - Two triangles T1, T2 that are not coplanar. If their planes are parallel (distinct), T1's
//   normal n1 separates. Otherwise the edge directions span space, M is 3-dimensional and its
//   facets are T1 + vertex (normal n1), vertex + T2 (normal n2), or edge + non-parallel edge
//   (normal E_i x F_j). Axes: n1, n2, the nine E_i x F_j (a zero axis never separates).
// - A segment S = pq and a triangle T, not both p and q on T's plane. If S is parallel to the
//   plane (or a point), M is flat in a plane parallel to T's but not through 0, and n separates.
//   Otherwise M is a prism whose facets have normals n and (q - p) x E_i.
// - Coplanar: the common plane is mapped one-to-one onto a coordinate plane by dropping an
//   axis k along which T1's projection has non-zero area (n1[k] != 0, an exact sign: n1[k] is
//   twice that signed area), which preserves intersection. There, by explicit case analysis
//   (a vertex inside the other, or edges meeting; argued at coplanar_triangles_meet).
//
// Arithmetic: all coordinates of one query are scaled by one power of two to integers (exact;
// a common positive factor changes no sign, incidence or intersection), then every quantity
// above is a polynomial in them, evaluated exactly with splintcore_test::BigInt. When every
// scaled coordinate is below 2^40 in magnitude, the same code runs on __int128 instead (a
// speed-up only, and exact: differences < 2^41, normals and E x F < 2^83, projections and the
// 2D orientations < 2^126); ArithmeticPathsAgree checks the two against each other.
// =============================================================================================

namespace splintcore_test {
namespace tri_oracle {

using splintcore::Vec3;

// Statistics for the tests (left false when the triangles' boxes are apart).
struct Info {
  bool coplanar = false;         // all six vertices on one plane
  bool vertex_on_plane = false;  // some vertex exactly on the other triangle's plane
};

enum class Arithmetic { kAuto, kBigInt };

namespace {

// __int128 is a fast path only: 32-bit targets (ARMv7, Cortex-M) have no __int128 and use BigInt.
#ifdef __SIZEOF_INT128__
__extension__ typedef __int128 Int128;
#endif

int sgn(const BigInt& v) { return v.sign(); }
#ifdef __SIZEOF_INT128__
int sgn(Int128 v) { return (v > 0) - (v < 0); }
#endif

template <class Z>
struct V3 {
  Z c[3];
};

template <class Z>
V3<Z> operator-(const V3<Z>& a, const V3<Z>& b) {
  return {{a.c[0] - b.c[0], a.c[1] - b.c[1], a.c[2] - b.c[2]}};
}
template <class Z>
V3<Z> cross(const V3<Z>& a, const V3<Z>& b) {
  return {{a.c[1] * b.c[2] - a.c[2] * b.c[1], a.c[2] * b.c[0] - a.c[0] * b.c[2],
           a.c[0] * b.c[1] - a.c[1] * b.c[0]}};
}
template <class Z>
Z dot(const V3<Z>& a, const V3<Z>& b) {
  return a.c[0] * b.c[0] + a.c[1] * b.c[1] + a.c[2] * b.c[2];
}

[[noreturn]] void oracle_precondition(const char* what) {
  std::fprintf(stderr, "tri_oracle: %s\n", what);
  std::abort();
}

// The coordinates as odd integers (or 0) times powers of two, and the common scale.
struct Scaled {
  std::vector<DyadicParts> parts;  // x = mantissa 2^exponent, mantissa odd or 0
  int emin = 0;                    // smallest exponent of a nonzero coordinate
  int max_bits = 0;                // bits of the largest scaled magnitude
};

Scaled scale(const Vec3* p, size_t n) {
  Scaled s;
  bool any = false;
  for (size_t i = 0; i < 3 * n; ++i) {
    DyadicParts d = decompose(p[i / 3][static_cast<int>(i % 3)]);
    if (d.mantissa != 0) {
      const int zeros = __builtin_ctzll(static_cast<unsigned long long>(d.mantissa));
      d.mantissa /= int64_t{1} << zeros;  // exact: drops trailing zero bits
      d.exponent += zeros;
    }
    if (d.mantissa != 0 && (!any || d.exponent < s.emin)) {
      s.emin = d.exponent;
      any = true;
    }
    s.parts.push_back(d);
  }
  for (const DyadicParts& d : s.parts) {
    if (d.mantissa == 0) continue;
    int bits = 0;
    for (uint64_t m = static_cast<uint64_t>(d.mantissa < 0 ? -d.mantissa : d.mantissa); m != 0;
         m >>= 1) {
      ++bits;
    }
    bits += d.exponent - s.emin;
    if (bits > s.max_bits) s.max_bits = bits;
  }
  return s;
}

void convert(const DyadicParts& d, int emin, BigInt* out) {
  const int64_t m = d.mantissa;  // |m| < 2^53
  *out = BigInt::from_magnitude(static_cast<uint64_t>(m < 0 ? -m : m),
                                static_cast<unsigned>(m == 0 ? 0 : d.exponent - emin), m < 0);
}
#ifdef __SIZEOF_INT128__
void convert(const DyadicParts& d, int emin, Int128* out) {
  *out = d.mantissa == 0 ? 0 : static_cast<Int128>(d.mantissa) * (Int128{1} << (d.exponent - emin));
}
#endif

// The points as integer vectors on the common scale.
template <class Z>
std::vector<V3<Z>> integer_points(const Scaled& s, size_t n) {
  std::vector<V3<Z>> out(n);
  for (size_t i = 0; i < 3 * n; ++i) convert(s.parts[i], s.emin, &out[i / 3].c[i % 3]);
  return out;
}

// Are the projections onto `axis` of the points a[0..na) and b[0..nb) disjoint intervals?
template <class Z>
bool separated_along(const V3<Z>& axis, const V3<Z>* const* a, int na, const V3<Z>* const* b,
                     int nb) {
  Z va[3], vb[3];
  int alo = 0, ahi = 0, blo = 0, bhi = 0;
  for (int i = 0; i < na; ++i) {
    va[i] = dot(axis, *a[i]);
    if (va[i] < va[alo]) alo = i;
    if (va[ahi] < va[i]) ahi = i;
  }
  for (int i = 0; i < nb; ++i) {
    vb[i] = dot(axis, *b[i]);
    if (vb[i] < vb[blo]) blo = i;
    if (vb[bhi] < vb[i]) bhi = i;
  }
  return va[ahi] < vb[blo] || vb[bhi] < va[alo];
}

// Coordinate axes are candidate axes too (cheap, compared exactly as doubles).
bool boxes_apart(const Vec3* a, int na, const Vec3* b, int nb) {
  for (int k = 0; k < 3; ++k) {
    double alo = a[0][k], ahi = alo, blo = b[0][k], bhi = blo;
    for (int i = 1; i < na; ++i) {
      alo = a[i][k] < alo ? a[i][k] : alo;
      ahi = a[i][k] > ahi ? a[i][k] : ahi;
    }
    for (int i = 1; i < nb; ++i) {
      blo = b[i][k] < blo ? b[i][k] : blo;
      bhi = b[i][k] > bhi ? b[i][k] : bhi;
    }
    if (ahi < blo || bhi < alo) return true;
  }
  return false;
}

// ---- the plane of a triangle, mapped one-to-one to 2D --------------------------------------

template <class Z>
struct P2 {
  Z u, v;
};

// Drops coordinate k (the first axis with n[k] != 0: the projection keeps the area).
template <class Z>
int projection_for(const V3<Z>& n) {
  for (int k = 0; k < 3; ++k) {
    if (sgn(n.c[k]) != 0) return k;
  }
  oracle_precondition("degenerate triangle");
}

template <class Z>
P2<Z> keep(const V3<Z>& p, int k) {
  return {p.c[(k + 1) % 3], p.c[(k + 2) % 3]};
}

// Sign of (b - a) x (c - a).
template <class Z>
int o2(const P2<Z>& a, const P2<Z>& b, const P2<Z>& c) {
  return sgn((b.u - a.u) * (c.v - a.v) - (b.v - a.v) * (c.u - a.u));
}

// Is p in the closed triangle t (non-degenerate)? No vertex-to-p orientation opposes t's.
template <class Z>
bool in_triangle(const P2<Z>& p, const P2<Z>* t) {
  const int s = o2(t[0], t[1], t[2]);
  for (int i = 0; i < 3; ++i) {
    if (o2(t[i], t[(i + 1) % 3], p) == -s) return false;
  }
  return true;
}

// Do the closed segments pq and rs meet? If the four points are not all on one line: iff
// r and s are not strictly on one side of line pq and p and q not strictly on one side of
// line rs (when r is on line pq, the lines cross at r, and p, q straddling line rs puts r on
// pq). If all are on one line: iff their boxes overlap (for collinear segments the same as
// overlapping).
template <class Z>
bool segments_meet(const P2<Z>& p, const P2<Z>& q, const P2<Z>& r, const P2<Z>& s) {
  const int d1 = o2(p, q, r), d2 = o2(p, q, s), d3 = o2(r, s, p), d4 = o2(r, s, q);
  if (d1 == 0 && d2 == 0 && d3 == 0 && d4 == 0) {
    auto lo = [](const Z& a, const Z& b) { return a < b ? a : b; };
    auto hi = [](const Z& a, const Z& b) { return a < b ? b : a; };
    return !(hi(p.u, q.u) < lo(r.u, s.u) || hi(r.u, s.u) < lo(p.u, q.u) ||
             hi(p.v, q.v) < lo(r.v, s.v) || hi(r.v, s.v) < lo(p.v, q.v));
  }
  return d1 * d2 <= 0 && d3 * d4 <= 0;
}

// Closed coplanar triangles meet iff a vertex of one is in the other or their edges meet: if
// the boundaries are disjoint, each boundary (connected) is inside the other triangle or
// outside it; if both were outside, a ray from a common point would leave one triangle, through
// its boundary, while still in the other, putting that boundary point inside the other.
// (A different argument from the library's 2D separating-axis test.)
template <class Z>
bool coplanar_triangles_meet(const P2<Z>* t, const P2<Z>* s) {
  for (int i = 0; i < 3; ++i) {
    if (in_triangle(t[i], s) || in_triangle(s[i], t)) return true;
  }
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      if (segments_meet(t[i], t[(i + 1) % 3], s[j], s[(j + 1) % 3])) return true;
    }
  }
  return false;
}

// A coplanar segment meets the triangle iff an end is in it or it meets an edge (a segment
// with both ends outside that reaches the triangle crosses its boundary).
template <class Z>
bool coplanar_segment_meets(const P2<Z>& p, const P2<Z>& q, const P2<Z>* t) {
  if (in_triangle(p, t) || in_triangle(q, t)) return true;
  for (int i = 0; i < 3; ++i) {
    if (segments_meet(p, q, t[i], t[(i + 1) % 3])) return true;
  }
  return false;
}

// ---- the two tests on integer points ---------------------------------------------------------

// P[0..2] = abc, P[3..5] = def.
template <class Z>
bool triangles_meet_z(const std::vector<V3<Z>>& P, Info* info) {
  const V3<Z>* A = &P[0];
  const V3<Z>* D = &P[3];
  const V3<Z> E[3] = {A[1] - A[0], A[2] - A[1], A[0] - A[2]};  // E[i] runs from A[i]
  const V3<Z> F[3] = {D[1] - D[0], D[2] - D[1], D[0] - D[2]};
  const V3<Z> n1 = cross(E[0], E[1]);
  const V3<Z> n2 = cross(F[0], F[1]);
  for (const V3<Z>* n : {&n1, &n2}) {
    if (sgn(n->c[0]) == 0 && sgn(n->c[1]) == 0 && sgn(n->c[2]) == 0) {
      oracle_precondition("degenerate triangle");
    }
  }
  // Which side of the other's plane each vertex is on. Along n1 the whole of abc projects to
  // n1.A[0], so n1 separates iff d, e, f are strictly on one side (likewise n2).
  int side_d[3], side_a[3];
  for (int k = 0; k < 3; ++k) {
    side_d[k] = sgn(dot(n1, D[k] - A[0]));
    side_a[k] = sgn(dot(n2, A[k] - D[0]));
  }
  const bool coplanar = side_d[0] == 0 && side_d[1] == 0 && side_d[2] == 0;
  if (info != nullptr) {
    info->coplanar = coplanar;
    for (int k = 0; k < 3; ++k) {
      if (side_d[k] == 0 || side_a[k] == 0) info->vertex_on_plane = true;
    }
  }
  if (coplanar) {
    const int k = projection_for(n1);
    const P2<Z> t[3] = {keep(A[0], k), keep(A[1], k), keep(A[2], k)};
    const P2<Z> s[3] = {keep(D[0], k), keep(D[1], k), keep(D[2], k)};
    return coplanar_triangles_meet(t, s);
  }
  if (side_d[0] != 0 && side_d[0] == side_d[1] && side_d[1] == side_d[2]) return false;
  if (side_a[0] != 0 && side_a[0] == side_a[1] && side_a[1] == side_a[2]) return false;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      // Along E[i] x F[j] the ends of edge E[i] project to one value, so abc projects onto
      // the interval of A[i] and the third vertex; likewise def.
      const V3<Z>* ta[2] = {&A[i], &A[(i + 2) % 3]};
      const V3<Z>* tb[2] = {&D[j], &D[(j + 2) % 3]};
      if (separated_along(cross(E[i], F[j]), ta, 2, tb, 2)) return false;
    }
  }
  return true;
}

// P[0], P[1] = pq; P[2..4] = abc.
template <class Z>
bool segment_meets_z(const std::vector<V3<Z>>& P, Info* info) {
  const V3<Z>* S = &P[0];
  const V3<Z>* A = &P[2];
  const V3<Z> E[3] = {A[1] - A[0], A[2] - A[1], A[0] - A[2]};
  const V3<Z> n = cross(E[0], E[1]);
  const int sp = sgn(dot(n, S[0] - A[0]));
  const int sq = sgn(dot(n, S[1] - A[0]));
  if (info != nullptr) {
    info->coplanar = sp == 0 && sq == 0;
    info->vertex_on_plane = (sp == 0) != (sq == 0);
  }
  if (sp == 0 && sq == 0) {
    const int k = projection_for(n);
    const P2<Z> t[3] = {keep(A[0], k), keep(A[1], k), keep(A[2], k)};
    return coplanar_segment_meets(keep(S[0], k), keep(S[1], k), t);
  }
  if (sp == sq) return false;  // strictly on one side of the plane (the axis n)
  const V3<Z> s = S[1] - S[0];
  for (int i = 0; i < 3; ++i) {
    // Along s x E[i] the segment projects to one value, and so do the ends of edge E[i].
    const V3<Z>* ta[1] = {&S[0]};
    const V3<Z>* tb[2] = {&A[i], &A[(i + 2) % 3]};
    if (separated_along(cross(s, E[i]), ta, 1, tb, 2)) return false;
  }
  return true;
}

bool use_int128(const Scaled& s, Arithmetic arithmetic) {
#ifdef __SIZEOF_INT128__
  return arithmetic == Arithmetic::kAuto && s.max_bits <= 40;
#else
  (void)s;
  (void)arithmetic;
  return false;
#endif
}

}  // namespace

// Does kAuto take the __int128 path for these points?
bool fits_int128(const Vec3* p, size_t n) { return use_int128(scale(p, n), Arithmetic::kAuto); }

// Do the closed triangles abc and def meet? Both must be non-degenerate.
bool triangles_meet_with(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, const Vec3& e,
                         const Vec3& f, Info* info, Arithmetic arithmetic) {
  const Vec3 in[6] = {a, b, c, d, e, f};
  if (info != nullptr) *info = Info{};
  if (boxes_apart(in, 3, in + 3, 3)) {
    if (exact_collinear3d(a, b, c) || exact_collinear3d(d, e, f)) {
      oracle_precondition("degenerate triangle");
    }
    return false;
  }
  const Scaled s = scale(in, 6);
#ifdef __SIZEOF_INT128__
  if (use_int128(s, arithmetic)) return triangles_meet_z(integer_points<Int128>(s, 6), info);
#else
  (void)arithmetic;
#endif
  return triangles_meet_z(integer_points<BigInt>(s, 6), info);
}

// Does the closed segment pq (p == q allowed) meet the closed non-degenerate triangle abc?
// (info: coplanar = both ends on the plane, vertex_on_plane = one end on it.)
bool segment_meets_triangle_with(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b,
                                 const Vec3& c, Info* info, Arithmetic arithmetic) {
  if (exact_collinear3d(a, b, c)) oracle_precondition("degenerate triangle");
  const Vec3 in[5] = {p, q, a, b, c};
  if (info != nullptr) *info = Info{};
  if (boxes_apart(in, 2, in + 2, 3)) return false;
  const Scaled s = scale(in, 5);
#ifdef __SIZEOF_INT128__
  if (use_int128(s, arithmetic)) {
    return segment_meets_z(integer_points<Int128>(s, 5), info);
  }
#else
  (void)arithmetic;
#endif
  return segment_meets_z(integer_points<BigInt>(s, 5), info);
}

// The plain forms (tests/mesh/self_intersect_test.cpp declares these three).
bool triangles_meet(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, const Vec3& e,
                    const Vec3& f) {
  return triangles_meet_with(a, b, c, d, e, f, nullptr, Arithmetic::kAuto);
}
bool segment_meets_triangle(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b,
                            const Vec3& c) {
  return segment_meets_triangle_with(p, q, a, b, c, nullptr, Arithmetic::kAuto);
}

// For coplanar p, q, s, t (s, t off line pq): are s and t on the same side of line pq? Both
// cross products are normal to the common plane, so they point the same way iff they are.
bool same_side_of_line(const Vec3& p, const Vec3& q, const Vec3& s, const Vec3& t) {
  const Vec3 in[4] = {p, q, s, t};
  const std::vector<V3<BigInt>> z = integer_points<BigInt>(scale(in, 4), 4);
  const V3<BigInt> pq = z[1] - z[0];
  return dot(cross(pq, z[2] - z[0]), cross(pq, z[3] - z[0])).sign() > 0;
}

}  // namespace tri_oracle
}  // namespace splintcore_test

// =============================================================================================
// The tests.

namespace {

using splintcore::segment_intersects_triangle;
using splintcore::triangles_intersect;
using splintcore::Vec3;
using splintcore_test::exact_collinear3d;
using splintcore_test::exact_orient3d_sign;
namespace oracle = splintcore_test::tri_oracle;

// Unoptimised and sanitized builds run a quarter of the random cases and half of the constructed
// ones (the oracle is schoolbook big-integer arithmetic), to stay quick at -O0 and under
// sanitizers.
#if defined(__OPTIMIZE__) && !defined(SPLINTCORE_TEST_SANITIZED)
constexpr int kRandomDivisor = 1;
constexpr int kAdversarialDivisor = 1;
#else
constexpr int kRandomDivisor = 4;
constexpr int kAdversarialDivisor = 2;
#endif

class Rng {
 public:
  explicit Rng(uint64_t seed) : engine_(seed) {}
  double unit() { return static_cast<double>(engine_() >> 11) * 0x1p-53; }
  int small(int lo, int hi) {
    const uint64_t span = static_cast<uint64_t>(static_cast<int64_t>(hi) - lo + 1);
    return static_cast<int>(lo + static_cast<int64_t>(engine_() % span));
  }
  double integer(int lo, int hi) { return static_cast<double>(small(lo, hi)); }
  double float32(double lo, double hi) {
    return static_cast<double>(static_cast<float>(lo + (hi - lo) * unit()));
  }
  bool coin() { return (engine_() >> 63) != 0; }
  // Draws in a fixed order (argument evaluation order is unspecified).
  Vec3 int_point(int lo, int hi) {
    const double x = integer(lo, hi);
    const double y = integer(lo, hi);
    const double z = integer(lo, hi);
    return {x, y, z};
  }
  Vec3 float32_point(double lo, double hi) {
    const double x = float32(lo, hi);
    const double y = float32(lo, hi);
    const double z = float32(lo, hi);
    return {x, y, z};
  }

 private:
  std::mt19937_64 engine_;
};

// x moved by k ulps. Zero is moved to k 2^-300 instead: the predicates are documented exact
// for nonzero coordinates of magnitude at least 2^-306 only (no subnormals).
double ulps(double x, int k) {
  if (x == 0.0) return std::ldexp(static_cast<double>(k), -300);
  const double toward =
      k > 0 ? std::numeric_limits<double>::infinity() : -std::numeric_limits<double>::infinity();
  for (int i = 0; i < (k > 0 ? k : -k); ++i) x = std::nextafter(x, toward);
  return x;
}

Vec3 scaled(const Vec3& p, int e) {  // exact for the magnitudes used here
  return {std::ldexp(p.x, e), std::ldexp(p.y, e), std::ldexp(p.z, e)};
}

// (w0 a + w1 b + w2 c) / 8 for integer points and weights: exact.
Vec3 combo8(const Vec3& a, const Vec3& b, const Vec3& c, int w0, int w1, int w2) {
  return (a * w0 + b * w1 + c * w2) * 0.125;
}

bool degenerate(const Vec3* t) { return exact_collinear3d(t[0], t[1], t[2]); }

std::string hex(double v) {
  std::ostringstream s;
  s << std::hexfloat << v;
  return s.str();
}
std::string hex(const Vec3& p) { return "(" + hex(p.x) + ", " + hex(p.y) + ", " + hex(p.z) + ")"; }

struct Tally {
  std::string name;
  int64_t cases = 0;
  int64_t wrong = 0;
  int64_t meet = 0;
  int64_t coplanar = 0;
  int64_t on_plane = 0;   // non-coplanar, a vertex exactly on the other's plane
  int64_t groups = 0;     // constructed cases (each with its ulp variants)
  int64_t base_meet = 0;  // constructed cases that meet exactly
  int64_t knife = 0;      // constructed cases whose answer one ulp changes

  explicit Tally(std::string n) : name(std::move(n)) {}
  void print() const {
    std::printf(
        "[   info   ] %-40s %7lld cases %7lld meet %6lld coplanar %6lld on-plane | %5lld "
        "groups %5lld meet %5lld knife-edge | %lld wrong\n",
        name.c_str(), static_cast<long long>(cases), static_cast<long long>(meet),
        static_cast<long long>(coplanar), static_cast<long long>(on_plane),
        static_cast<long long>(groups), static_cast<long long>(base_meet),
        static_cast<long long>(knife), static_cast<long long>(wrong));
  }
  void add(const Tally& o) {
    cases += o.cases;
    wrong += o.wrong;
    meet += o.meet;
    coplanar += o.coplanar;
    on_plane += o.on_plane;
    groups += o.groups;
    base_meet += o.base_meet;
    knife += o.knife;
  }
};

// The library on the pair in three argument orders (as given, swapped and rotated, both
// reversed) against the oracle. Returns the oracle's answer.
bool check_tt(Tally& t, const Vec3* s, const Vec3* r) {
  oracle::Info info;
  const bool expected = oracle::triangles_meet_with(s[0], s[1], s[2], r[0], r[1], r[2], &info,
                                                    oracle::Arithmetic::kAuto);
  ++t.cases;
  if (expected) ++t.meet;
  if (info.coplanar) ++t.coplanar;
  if (!info.coplanar && info.vertex_on_plane) ++t.on_plane;
  const Vec3 &a = s[0], &b = s[1], &c = s[2], &d = r[0], &e = r[1], &f = r[2];
  const bool got[3] = {triangles_intersect(a, b, c, d, e, f),
                       triangles_intersect(f, d, e, b, c, a),   // swapped, rotated
                       triangles_intersect(c, b, a, e, d, f)};  // both reversed
  for (int k = 0; k < 3; ++k) {
    if (got[k] != expected) {
      if (++t.wrong <= 5) {
        ADD_FAILURE() << t.name << ": triangles_intersect (argument order " << k << ") says "
                      << got[k] << ", oracle " << expected << " for " << hex(a) << " " << hex(b)
                      << " " << hex(c) << " / " << hex(d) << " " << hex(e) << " " << hex(f);
      }
      break;
    }
  }
  return expected;
}

// The same for a segment and a triangle.
bool check_st(Tally& t, const Vec3& p, const Vec3& q, const Vec3* tri) {
  const Vec3 &a = tri[0], &b = tri[1], &c = tri[2];
  oracle::Info info;
  const bool expected =
      oracle::segment_meets_triangle_with(p, q, a, b, c, &info, oracle::Arithmetic::kAuto);
  ++t.cases;
  if (expected) ++t.meet;
  if (info.coplanar) ++t.coplanar;
  if (info.vertex_on_plane) ++t.on_plane;
  const bool got[3] = {segment_intersects_triangle(p, q, a, b, c),
                       segment_intersects_triangle(q, p, b, c, a),
                       segment_intersects_triangle(p, q, c, b, a)};
  // segment_crossing against the oracle's answer and exact signs: a crossing meets abc with p
  // and q strictly on opposite sides and the line pq off every edge's line; a miss does not
  // meet it; a touch meets it, or has an endpoint in abc's plane, or abc is degenerate.
  {
    const int sp = exact_orient3d_sign(a, b, c, p), sq = exact_orient3d_sign(a, b, c, q);
    const splintcore::SegmentCrossing crossing = splintcore::segment_crossing(p, q, a, b, c);
    bool right = true;
    switch (crossing) {
      case splintcore::SegmentCrossing::kMisses: right = !expected; break;
      case splintcore::SegmentCrossing::kCrosses:
        right = expected && sp * sq < 0 && exact_orient3d_sign(p, q, a, b) != 0 &&
                exact_orient3d_sign(p, q, b, c) != 0 && exact_orient3d_sign(p, q, c, a) != 0;
        break;
      case splintcore::SegmentCrossing::kTouches: right = expected || sp == 0 || sq == 0; break;
    }
    if (!right && ++t.wrong <= 5) {
      ADD_FAILURE() << t.name << ": segment_crossing says " << static_cast<int>(crossing)
                    << ", oracle " << expected << " for segment " << hex(p) << " " << hex(q)
                    << " triangle " << hex(a) << " " << hex(b) << " " << hex(c);
    }
  }
  for (int k = 0; k < 3; ++k) {
    if (got[k] != expected) {
      if (++t.wrong <= 5) {
        ADD_FAILURE() << t.name << ": segment_intersects_triangle (argument order " << k
                      << ") says " << got[k] << ", oracle " << expected << " for segment " << hex(p)
                      << " " << hex(q) << " triangle " << hex(a) << " " << hex(b) << " " << hex(c);
      }
      break;
    }
  }
  return expected;
}

// A constructed case and its variants with vertex `moved` of r moved by one ulp along each
// axis both ways: counts knife edges (cases whose answer one ulp changes).
void group_tt(Tally& t, const Vec3* s, const Vec3* r, int moved) {
  const bool base = check_tt(t, s, r);
  ++t.groups;
  if (base) ++t.base_meet;
  bool differs = false;
  for (int axis = 0; axis < 3; ++axis) {
    for (int k : {-1, 1}) {
      Vec3 v[3] = {r[0], r[1], r[2]};
      v[moved][axis] = ulps(v[moved][axis], k);
      if (degenerate(v)) continue;
      if (check_tt(t, s, v) != base) differs = true;
    }
  }
  if (differs) ++t.knife;
}

// A segment case and its variants with endpoint p moved by one ulp (both ends when the
// segment is a point).
void group_st(Tally& t, const Vec3& p, const Vec3& q, const Vec3* tri) {
  const bool base = check_st(t, p, q, tri);
  ++t.groups;
  if (base) ++t.base_meet;
  bool differs = false;
  for (int axis = 0; axis < 3; ++axis) {
    for (int k : {-1, 1}) {
      Vec3 m = p;
      m[axis] = ulps(m[axis], k);
      if (check_st(t, m, p == q ? m : q, tri) != base) differs = true;
    }
  }
  if (differs) ++t.knife;
}

void expect_clean(const Tally& t) {
  t.print();
  EXPECT_EQ(t.wrong, 0) << t.name;
}

// ---- random inputs ---------------------------------------------------------------------------

enum class Kind { kInt3, kSlab, kInt12, kFloat32, kDyadic, kInt12Times2p200, kFloat32Times2pm200 };
constexpr Kind kAllKinds[] = {Kind::kInt3,
                              Kind::kSlab,
                              Kind::kInt12,
                              Kind::kFloat32,
                              Kind::kDyadic,
                              Kind::kInt12Times2p200,
                              Kind::kFloat32Times2pm200};

const char* kind_name(Kind k) {
  switch (k) {
    case Kind::kInt3: return "integers [0,3]";
    case Kind::kSlab: return "integers [0,5]^2 x [0,1]";
    case Kind::kInt12: return "integers [0,12]";
    case Kind::kFloat32: return "float32 [0,1]";
    case Kind::kDyadic: return "k/8, k in [0,16]";
    case Kind::kInt12Times2p200: return "integers [0,12] * 2^200";
    case Kind::kFloat32Times2pm200: return "float32 [0,1] * 2^-200";
  }
  return "?";
}

Vec3 random_point(Rng& rng, Kind k) {
  switch (k) {
    case Kind::kInt3: return rng.int_point(0, 3);
    case Kind::kSlab: {
      const double x = rng.integer(0, 5);
      const double y = rng.integer(0, 5);
      const double z = rng.integer(0, 1);
      return {x, y, z};
    }
    case Kind::kInt12: return rng.int_point(0, 12);
    case Kind::kFloat32: return rng.float32_point(0.0, 1.0);
    case Kind::kDyadic: return rng.int_point(0, 16) * 0.125;
    case Kind::kInt12Times2p200: return scaled(rng.int_point(0, 12), 200);
    case Kind::kFloat32Times2pm200: return scaled(rng.float32_point(0.0, 1.0), -200);
  }
  return {};
}

void random_triangle(Rng& rng, Kind k, Vec3* t) {
  do {
    for (int i = 0; i < 3; ++i) t[i] = random_point(rng, k);
  } while (degenerate(t));
}

// Integer point with coordinates in [-r, r].
Vec3 int_vec(Rng& rng, int r) { return rng.int_point(-r, r); }

void random_int_triangle(Rng& rng, int r, Vec3* t) {
  do {
    for (int i = 0; i < 3; ++i) t[i] = int_vec(rng, r);
  } while (degenerate(t));
}

// Two further points u, v such that (p, p + u, p + v) is non-degenerate and, when one_side,
// p + u and p + v are strictly on one side of the plane of s.
void fan_from(Rng& rng, const Vec3* s, const Vec3& p, bool one_side, Vec3* out) {
  for (;;) {
    const Vec3 u = int_vec(rng, 24), v = int_vec(rng, 24);
    out[0] = p;
    out[1] = p + u;
    out[2] = p + v;
    if (degenerate(out)) continue;
    if (one_side) {
      const int su = exact_orient3d_sign(s[0], s[1], s[2], out[1]);
      const int sv = exact_orient3d_sign(s[0], s[1], s[2], out[2]);
      if (su == 0 || su != sv) continue;
    }
    return;
  }
}

// ---- the oracle itself -----------------------------------------------------------------------

TEST(TriangleOracle, HandCheckedCases) {
  const Vec3 o{0, 0, 0}, x{4, 0, 0}, y{0, 4, 0};
  const Vec3 t[3] = {o, x, y};
  auto meets = [&](Vec3 d, Vec3 e, Vec3 f) {
    return oracle::triangles_meet(t[0], t[1], t[2], d, e, f);
  };
  EXPECT_TRUE(meets(o, x, y));                               // the same triangle
  EXPECT_TRUE(meets({0, 0, 0}, {-1, 0, 1}, {0, -1, 1}));     // a shared vertex only
  EXPECT_TRUE(meets({1, 1, 0}, {1, 1, 5}, {2, 3, 5}));       // a vertex on the face
  EXPECT_FALSE(meets({1, 1, 1}, {1, 1, 5}, {2, 3, 5}));      // just above it
  EXPECT_TRUE(meets({2, 0, 0}, {2, -1, 3}, {2, 1, 3}));      // a vertex on an edge
  EXPECT_TRUE(meets({1, 1, -1}, {1, 1, 1}, {9, 9, 0}));      // an edge through the face
  EXPECT_TRUE(meets({2, -1, -1}, {2, 1, 1}, {2, -5, 3}));    // edge through edge (2,0,0)
  EXPECT_FALSE(meets({2, -1, -1}, {2, -1, 1}, {2, -5, 3}));  // edge passing beside it
  EXPECT_FALSE(meets({0, 0, 1}, {4, 0, 1}, {0, 4, 1}));      // parallel planes
  EXPECT_TRUE(meets({1, 1, 0}, {5, 1, 0}, {1, 5, 0}));       // coplanar overlap
  EXPECT_TRUE(meets({4, 0, 0}, {5, 0, 0}, {4, 1, 0}));       // coplanar, vertex touch
  EXPECT_TRUE(meets({2, 2, 0}, {5, 2, 0}, {2, 5, 0}));       // coplanar, vertex on edge
  EXPECT_TRUE(meets({3, 1, 0}, {1, 3, 0}, {5, 5, 0}));       // coplanar, edge on edge
  EXPECT_FALSE(meets({3, 2, 0}, {2, 3, 0}, {5, 5, 0}));      // coplanar, just outside
  EXPECT_FALSE(meets({5, 0, 0}, {6, 0, 0}, {5, 1, 0}));      // coplanar, disjoint
  EXPECT_TRUE(meets({-1, -1, 0}, {9, -1, 0}, {-1, 9, 0}));   // coplanar, containing
  EXPECT_TRUE(meets({1, 1, 0}, {1, 1, 1}, {1, 2, 0}));       // coplanar edge in face
  EXPECT_FALSE(meets({-1, 2, -1}, {-1, 2, 1}, {-3, 2, 0}));  // beside, planes crossing

  auto seg = [&](Vec3 p, Vec3 q) { return oracle::segment_meets_triangle(p, q, o, x, y); };
  EXPECT_TRUE(seg({1, 1, -1}, {1, 1, 1}));    // through the face
  EXPECT_TRUE(seg({1, 1, 0}, {1, 1, 1}));     // ending on the face
  EXPECT_FALSE(seg({1, 1, 1}, {1, 1, 2}));    // above
  EXPECT_TRUE(seg({2, 2, -1}, {2, 2, 1}));    // through the hypotenuse
  EXPECT_FALSE(seg({3, 2, -1}, {3, 2, 1}));   // beside it
  EXPECT_TRUE(seg({4, 0, 5}, {4, 0, -5}));    // through a vertex
  EXPECT_TRUE(seg({-1, 1, 0}, {5, 1, 0}));    // coplanar, across
  EXPECT_TRUE(seg({-1, 0, 0}, {0, 0, 0}));    // coplanar, touching a vertex
  EXPECT_FALSE(seg({-1, 0, 0}, {-1, 3, 0}));  // coplanar, beside
  EXPECT_TRUE(seg({1, 1, 0}, {1, 1, 0}));     // a point in the face
  EXPECT_FALSE(seg({1, 1, 1}, {1, 1, 1}));    // a point above it
  EXPECT_FALSE(seg({1, 1, 1}, {9, 1, 1}));    // parallel, above

  EXPECT_TRUE(oracle::same_side_of_line(o, x, y, {1, 1, 0}));
  EXPECT_FALSE(oracle::same_side_of_line(o, x, y, {1, -1, 0}));
}

// The two oracles agree with each other where their answers are related. Two non-coplanar
// triangles meet iff an edge of one meets the other (the intersection, a segment on the line
// where the planes meet, has its ends on edges). Two coplanar ones meet iff an edge of one
// meets the other or a vertex of one (a segment of length 0) is in the other. This checks the
// oracles' own code: the 3D separating axes against the segment test, and the coplanar path
// of the triangle test against that of the segment test.
TEST(TriangleOracle, ConsistentWithItsSegmentTest) {
  Rng rng(11);
  int64_t checked = 0, meet = 0, coplanar = 0, coplanar_meet = 0;
  for (int i = 0; i < 6000 / kRandomDivisor; ++i) {
    Vec3 s[3], r[3];
    if (i % 3 == 2) {  // coplanar: small integers in the tilted plane z = x + 2y
      for (Vec3* t : {s, r}) {
        do {
          for (int j = 0; j < 3; ++j) {
            const double x = rng.integer(0, 7), y = rng.integer(0, 7);
            t[j] = Vec3{x, y, x + 2 * y};
          }
        } while (degenerate(t));
      }
    } else {
      const Kind k = i % 3 == 0 ? Kind::kInt3 : Kind::kFloat32;
      random_triangle(rng, k, s);
      random_triangle(rng, k, r);
    }
    oracle::Info info;
    const bool tt = oracle::triangles_meet_with(s[0], s[1], s[2], r[0], r[1], r[2], &info,
                                                oracle::Arithmetic::kAuto);
    bool parts = false;
    for (int j = 0; j < 3 && !parts; ++j) {
      parts = oracle::segment_meets_triangle(s[j], s[(j + 1) % 3], r[0], r[1], r[2]) ||
              oracle::segment_meets_triangle(r[j], r[(j + 1) % 3], s[0], s[1], s[2]);
      if (info.coplanar) {
        parts = parts || oracle::segment_meets_triangle(s[j], s[j], r[0], r[1], r[2]) ||
                oracle::segment_meets_triangle(r[j], r[j], s[0], s[1], s[2]);
      }
    }
    ++checked;
    meet += tt;
    coplanar += info.coplanar;
    coplanar_meet += info.coplanar && tt;
    ASSERT_EQ(tt, parts) << hex(s[0]) << hex(s[1]) << hex(s[2]) << " / " << hex(r[0]) << hex(r[1])
                         << hex(r[2]);
    // Symmetric in the triangles and their vertex order.
    ASSERT_EQ(tt, oracle::triangles_meet(r[2], r[0], r[1], s[1], s[0], s[2]));
  }
  EXPECT_GT(meet, checked / 5);
  EXPECT_LT(meet, checked * 4 / 5);
  EXPECT_GT(coplanar_meet, checked / 40);
  EXPECT_GT(coplanar - coplanar_meet, checked / 40);
}

// The __int128 shortcut and BigInt give the same answers (on random and constructed inputs,
// small enough for the shortcut or not).
TEST(TriangleOracle, ArithmeticPathsAgree) {
#ifndef __SIZEOF_INT128__
  GTEST_SKIP() << "no __int128 on this target: the oracle runs on BigInt only";
#endif
  Rng rng(13);
  int64_t narrow = 0, cases = 0;
  for (int i = 0; i < 8000 / kRandomDivisor; ++i) {
    const Kind k = kAllKinds[i % 7];
    Vec3 s[3], r[3];
    random_triangle(rng, k, s);
    if (i % 3 == 0) {  // touching: a vertex of r on an edge of s, moved by an ulp or not
      r[0] = (s[0] + s[1]) * 0.5;
      do {
        r[1] = random_point(rng, k);
        r[2] = random_point(rng, k);
      } while (degenerate(r));
      if (i % 2 == 0) r[0].x = ulps(r[0].x, 1);
      if (degenerate(r)) continue;
    } else {
      random_triangle(rng, k, r);
    }
    const Vec3 all[6] = {s[0], s[1], s[2], r[0], r[1], r[2]};
    narrow += oracle::fits_int128(all, 6);
    ++cases;
    ASSERT_EQ(oracle::triangles_meet(s[0], s[1], s[2], r[0], r[1], r[2]),
              oracle::triangles_meet_with(s[0], s[1], s[2], r[0], r[1], r[2], nullptr,
                                          oracle::Arithmetic::kBigInt))
        << hex(s[0]) << hex(s[1]) << hex(s[2]) << " / " << hex(r[0]) << hex(r[1]) << hex(r[2]);
    ASSERT_EQ(oracle::segment_meets_triangle(r[0], r[1], s[0], s[1], s[2]),
              oracle::segment_meets_triangle_with(r[0], r[1], s[0], s[1], s[2], nullptr,
                                                  oracle::Arithmetic::kBigInt));
  }
  // Both paths ran.
  EXPECT_GT(narrow, cases / 4);
  EXPECT_GT(cases - narrow, cases / 10);
}

// ---- triangles_intersect ----------------------------------------------------------------------

TEST(TrianglesIntersect, RandomPairsInSmallBoxesAgreeWithOracle) {
  // 7 kinds x 30,000 pairs = 210,000 pairs (a quarter unoptimised), 3 argument orders each.
  const int per_kind = 30000 / kRandomDivisor;
  Tally all("random, all kinds");
  uint64_t seed = 100;
  for (Kind k : kAllKinds) {
    Tally t(std::string("random ") + kind_name(k));
    Rng rng(seed++);
    for (int i = 0; i < per_kind; ++i) {
      Vec3 s[3], r[3];
      random_triangle(rng, k, s);
      random_triangle(rng, k, r);
      check_tt(t, s, r);
    }
    expect_clean(t);
    // Both answers are common.
    EXPECT_GT(t.meet, t.cases / 10) << t.name;
    EXPECT_LT(t.meet, t.cases * 9 / 10) << t.name;
    all.add(t);
  }
  all.print();
  EXPECT_GE(all.cases, 6 * per_kind);
  // The integer boxes give many exactly coplanar pairs and vertices exactly on planes.
  EXPECT_GT(all.coplanar, all.cases / 500);
  EXPECT_GT(all.on_plane, all.cases / 10);
}

TEST(TrianglesIntersect, VertexOnFaceEdgeOrVertexAndUlpPerturbations) {
  Rng rng(7);
  Tally face("vertex on face"), edge("vertex on edge"), vertex("vertex on vertex");
  const int scales[] = {0, 0, 0, 200, -200};
  for (int i = 0; i < 2400 / kAdversarialDivisor; ++i) {
    Vec3 s[3];
    random_int_triangle(rng, 32, s);
    const int which = i % 3;
    Vec3 p;
    if (which == 0) {  // strictly inside the face: positive weights summing to 8
      const int w0 = rng.small(1, 6), w1 = rng.small(1, 7 - w0);
      p = combo8(s[0], s[1], s[2], w0, w1, 8 - w0 - w1);
    } else if (which == 1) {  // on an edge
      const int w = rng.small(1, 7);
      p = combo8(s[0], s[1], s[2], 8 - w, w, 0);
    } else {
      p = s[rng.small(0, 2)];
    }
    Vec3 r[3];
    fan_from(rng, s, p, i % 4 != 3, r);
    const int e = scales[i % 5];
    for (int j = 0; j < 3; ++j) {
      s[j] = scaled(s[j], e);
      r[j] = scaled(r[j], e);
    }
    group_tt(which == 0 ? face : (which == 1 ? edge : vertex), s, r, 0);
  }
  for (Tally* t : {&face, &edge, &vertex}) {
    expect_clean(*t);
    // The unperturbed contact is exact: it meets, and one ulp often separates it.
    EXPECT_EQ(t->base_meet, t->groups) << t->name;
    EXPECT_GT(t->knife, t->groups / 2) << t->name;
    EXPECT_GT(t->meet, t->cases / 4) << t->name;
    EXPECT_LT(t->meet, t->cases * 9 / 10) << t->name;
  }
}

TEST(TrianglesIntersect, EdgeThroughEdgeOrVertexExactly) {
  Rng rng(8);
  Tally cross("edge through edge"), through_vertex("edge through vertex"),
      collinear("collinear edges");
  for (int i = 0; i < 2400 / kAdversarialDivisor; ++i) {
    Vec3 s[3];
    random_int_triangle(rng, 32, s);
    const int which = i % 3;
    Vec3 r[3];
    if (which < 2) {
      // r's edge (x + u, x - u) passes through x, on s's edge (or at its vertex).
      Vec3 xs = s[0];
      if (which == 0) {
        const int w = rng.small(1, 7);
        xs = combo8(s[0], s[1], s[2], 8 - w, w, 0);
      }
      do {
        const Vec3 u = int_vec(rng, 24), v = int_vec(rng, 24);
        r[0] = xs + u;
        r[1] = xs - u;
        r[2] = xs + v;
      } while (degenerate(r));
      group_tt(which == 0 ? cross : through_vertex, s, r, 0);
    } else {
      // r's edge on the line of s's edge 01: overlapping, touching at an end, or apart.
      do {
        const int k0 = rng.small(-8, 16), k1 = rng.small(-8, 16);
        r[0] = combo8(s[0], s[1], s[2], 8 - k0, k0, 0);
        r[1] = combo8(s[0], s[1], s[2], 8 - k1, k1, 0);
        r[2] = int_vec(rng, 32);
      } while (degenerate(r));
      group_tt(collinear, s, r, rng.small(0, 1));
    }
  }
  for (Tally* t : {&cross, &through_vertex, &collinear}) {
    expect_clean(*t);
    EXPECT_GT(t->knife, t->groups / 4) << t->name;
    EXPECT_GT(t->meet, t->cases / 5) << t->name;
    EXPECT_LT(t->meet, t->cases * 9 / 10) << t->name;
  }
  EXPECT_EQ(cross.base_meet, cross.groups);
  EXPECT_EQ(through_vertex.base_meet, through_vertex.groups);
}

TEST(TrianglesIntersect, ExactlyCoplanarPairs) {
  Rng rng(9);
  Tally ints("coplanar, integer basis"), f32("coplanar, float32 z = c"),
      tilted("coplanar, float32 z = x + y");
  // Small integers in the plane o + x U + y V (integer U, V): exact, and tilted.
  for (int i = 0; i < 2000 / kAdversarialDivisor; ++i) {
    Vec3 o = int_vec(rng, 20), u, v;
    do {
      u = int_vec(rng, 3);
      v = int_vec(rng, 3);
    } while (exact_collinear3d(Vec3{}, u, v));
    auto at = [&](int x, int y) { return o + u * x + v * y; };
    Vec3 s[3], r[3];
    do {
      for (Vec3& p : s) p = at(rng.small(0, 5), rng.small(0, 5));
    } while (degenerate(s));
    do {
      for (Vec3& p : r) p = at(rng.small(0, 5), rng.small(0, 5));
    } while (degenerate(r));
    ASSERT_EQ(exact_orient3d_sign(s[0], s[1], s[2], r[0]), 0);
    group_tt(ints, s, r, rng.small(0, 2));  // the ulp variants leave the plane
  }
  // float32 coordinates on z = c, with shared vertices and edge midpoints (exact).
  for (int i = 0; i < 1200 / kAdversarialDivisor; ++i) {
    const double c = rng.float32(-1, 1);
    auto pt = [&]() {
      const double x = rng.float32(0, 1);
      const double y = rng.float32(0, 1);
      return Vec3{x, y, c};
    };
    Vec3 s[3], r[3];
    do {
      for (Vec3& p : s) p = pt();
    } while (degenerate(s));
    do {
      for (Vec3& p : r) p = pt();
      if (i % 3 == 1) r[0] = s[rng.small(0, 2)];
      if (i % 3 == 2) r[0] = (s[0] + s[1]) * 0.5;
    } while (degenerate(r));
    if (exact_orient3d_sign(s[0], s[1], s[2], r[0]) != 0) continue;  // midpoint not exact
    group_tt(f32, s, r, 0);
  }
  // float32 x, y on the tilted plane z = x + y (kept only where x + y is exact).
  for (int i = 0; i < 1200 / kAdversarialDivisor; ++i) {
    auto pt = [&]() {
      const double x = rng.float32(-1, 1);
      const double y = rng.float32(-1, 1);
      return Vec3{x, y, x + y};
    };
    Vec3 s[3], r[3];
    do {
      for (Vec3& p : s) p = pt();
    } while (degenerate(s));
    do {
      for (Vec3& p : r) p = pt();
      if (i % 2 == 1) r[0] = s[rng.small(0, 2)];
    } while (degenerate(r));
    bool exact = true;
    for (const Vec3* t : {s, r}) {
      for (int j = 0; j < 3; ++j)
        exact = exact && splintcore_test::exact_sum_is(t[j].x, t[j].y, t[j].z);
    }
    if (!exact) continue;
    ASSERT_EQ(exact_orient3d_sign(s[0], s[1], s[2], r[0]), 0);
    ASSERT_EQ(exact_orient3d_sign(s[0], s[1], s[2], r[1]), 0);
    group_tt(tilted, s, r, 0);
  }
  for (Tally* t : {&ints, &f32, &tilted}) {
    expect_clean(*t);
    EXPECT_GT(t->groups, 800 / kAdversarialDivisor) << t->name;
    EXPECT_GT(t->base_meet, t->groups / 5) << t->name;
    EXPECT_LT(t->base_meet, t->groups * 9 / 10) << t->name;
  }
  EXPECT_GT(ints.knife, ints.groups / 10);
  EXPECT_GT(f32.knife + tilted.knife, (f32.groups + tilted.groups) / 10);
}

// ---- segment_intersects_triangle --------------------------------------------------------------

TEST(SegmentIntersectsTriangle, RandomSegmentsInSmallBoxesAgreeWithOracle) {
  const int per_kind = 25000 / kRandomDivisor;
  uint64_t seed = 300;
  int64_t total = 0;
  for (Kind k : kAllKinds) {
    Tally t(std::string("segment random ") + kind_name(k));
    Rng rng(seed++);
    for (int i = 0; i < per_kind; ++i) {
      Vec3 tri[3];
      random_triangle(rng, k, tri);
      const Vec3 p = random_point(rng, k);
      const Vec3 q = i % 50 == 0 ? p : random_point(rng, k);  // some degenerate segments
      check_st(t, p, q, tri);
    }
    expect_clean(t);
    EXPECT_GT(t.meet, t.cases / 20) << t.name;
    EXPECT_LT(t.meet, t.cases * 9 / 10) << t.name;
    total += t.cases;
  }
  EXPECT_EQ(total, 7 * per_kind);
}

// segment_crossing on a triangle in the plane z = 0, each outcome built exactly.
TEST(SegmentCrossing, CrossesMissesAndTouches) {
  using splintcore::segment_crossing;
  using splintcore::SegmentCrossing;
  const Vec3 a{0, 0, 0}, b{4, 0, 0}, c{0, 4, 0};
  const auto at = [&](const Vec3& p, const Vec3& q) { return segment_crossing(p, q, a, b, c); };
  // Through the interior, either way round, and slanted.
  EXPECT_EQ(at({1, 1, -1}, {1, 1, 1}), SegmentCrossing::kCrosses);
  EXPECT_EQ(at({1, 1, 1}, {1, 1, -1}), SegmentCrossing::kCrosses);
  EXPECT_EQ(at({0.5, 0.5, -2}, {1.5, 1, 3}), SegmentCrossing::kCrosses);
  // Both ends on one side; through the plane outside the triangle; short of the plane.
  EXPECT_EQ(at({1, 1, 0.5}, {1, 1, 2}), SegmentCrossing::kMisses);
  EXPECT_EQ(at({3, 3, -1}, {3, 3, 1}), SegmentCrossing::kMisses);
  EXPECT_EQ(at({-1, 1, -1}, {-1, 1, 1}), SegmentCrossing::kMisses);
  // Through an edge, through a corner, an end in the plane (inside and outside the triangle),
  // lying in the plane, and a degenerate triangle: none of them is counted.
  EXPECT_EQ(at({2, 0, -1}, {2, 0, 1}), SegmentCrossing::kTouches);
  EXPECT_EQ(at({2, 2, -1}, {2, 2, 1}), SegmentCrossing::kTouches);
  EXPECT_EQ(at({4, 0, -1}, {4, 0, 1}), SegmentCrossing::kTouches);
  EXPECT_EQ(at({1, 1, 0}, {1, 1, 1}), SegmentCrossing::kTouches);
  EXPECT_EQ(at({5, 5, 0}, {1, 1, 1}), SegmentCrossing::kTouches);
  EXPECT_EQ(at({-1, 1, 0}, {5, 1, 0}), SegmentCrossing::kTouches);
  EXPECT_EQ(segment_crossing({1, 0, -1}, {1, 0, 1}, a, b, Vec3{2, 0, 0}),
            SegmentCrossing::kTouches);
  // One ulp off the edge x + y = 4 inside: a crossing; on it: a touch; one ulp outside: a miss.
  const double below = std::nextafter(2.0, 0.0), above = std::nextafter(2.0, 4.0);
  EXPECT_EQ(at({2, below, -1}, {2, below, 1}), SegmentCrossing::kCrosses);
  EXPECT_EQ(at({2, 2, -1}, {2, 2, 1}), SegmentCrossing::kTouches);
  EXPECT_EQ(at({2, above, -1}, {2, above, 1}), SegmentCrossing::kMisses);
}

TEST(SegmentIntersectsTriangle, AdversarialContactsAndUlpPerturbations) {
  Rng rng(12);
  Tally end_on("segment end on face/edge/vertex"), through("segment through edge/vertex"),
      coplanar("segment coplanar"), point("segment is a point"), parallel("segment parallel");
  for (int i = 0; i < 2000 / kAdversarialDivisor; ++i) {
    Vec3 s[3];
    random_int_triangle(rng, 32, s);
    const int where = i % 3;  // face, edge, vertex
    Vec3 x;
    if (where == 0) {
      const int w0 = rng.small(1, 6), w1 = rng.small(1, 7 - w0);
      x = combo8(s[0], s[1], s[2], w0, w1, 8 - w0 - w1);
    } else if (where == 1) {
      const int w = rng.small(1, 7);
      x = combo8(s[0], s[1], s[2], 8 - w, w, 0);
    } else {
      x = s[rng.small(0, 2)];
    }
    Vec3 u;
    do {
      u = int_vec(rng, 24);
    } while (u == Vec3{});
    // An end exactly on the triangle.
    group_st(end_on, x, x + u, s);
    // Passing exactly through the point.
    group_st(through, x + u, x - u, s);
    // The point alone.
    group_st(point, x, x, s);
    // Coplanar: x plus an in-plane direction (integer combination of the edges).
    Vec3 w;
    do {
      w = (s[1] - s[0]) * rng.small(-2, 2) + (s[2] - s[0]) * rng.small(-2, 2);
    } while (w == Vec3{});
    group_st(coplanar, x, x + w, s);
    group_st(coplanar, x + w, x + w * 2, s);
    // Parallel to the plane, off it by a multiple of the (integer) normal.
    const Vec3 n = splintcore::cross(s[1] - s[0], s[2] - s[0]);
    group_st(parallel, x + n * rng.small(1, 2), x + w + n * rng.small(1, 2), s);
  }
  for (Tally* t : {&end_on, &through, &coplanar, &point, &parallel}) expect_clean(*t);
  for (Tally* t : {&end_on, &through, &point}) {
    EXPECT_EQ(t->base_meet, t->groups) << t->name;
    EXPECT_GT(t->knife, t->groups / 4) << t->name;
  }
  EXPECT_GT(coplanar.knife, coplanar.groups / 10);
  EXPECT_GT(coplanar.base_meet, coplanar.groups / 5);
  EXPECT_LT(coplanar.base_meet, coplanar.groups * 9 / 10);
  EXPECT_EQ(parallel.base_meet, 0);
}

}  // namespace
