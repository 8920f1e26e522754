// Exact orientation and in-circle predicates: orient2d, orient3d, collinear3d, incircle.
//
// Source: J. R. Shewchuk, "Adaptive Precision Floating-Point Arithmetic and Fast Robust
// Geometric Predicates", Discrete & Computational Geometry 18(3), 1997.
//   Section 2 (2.3-2.6): expansion arithmetic - Two-Sum, Fast-Two-Sum, Split, Two-Product,
//     Fast-Expansion-Sum and Scale-Expansion, here with zero elimination.
//   Section 4 (4.2-4.3): the orientation tests with their forward error bounds
//     (ccwerrboundA/B for orient2d, o3derrboundA/B for orient3d), and the in-circle test
//     (iccerrboundA/B) of Section 4.4.
// Written from the paper (not from predicates.c).
//
// Stages implemented:
//   orient2d: A (floating-point filter), B (exact products of the rounded differences),
//             then the exact result B + tail terms (the paper's stage D; stage C, the
//             first-order tail correction, is skipped: it only saves time).
//   orient3d: A (filter), B (exact products of the rounded differences), then the exact
//             4x4 determinant of the original coordinates as a sum of 2x2 minors scaled by
//             the z coordinates (the "exact" evaluation of Section 4.3, not the adaptive C/D).
//   collinear3d: the three coordinate-plane projections through orient2d.
//   incircle: A (filter), B (exact determinant of the rounded differences: exact whenever the
//             differences are, e.g. for integer or small dyadic coordinates), then the exact
//             4x4 lifted determinant of the original coordinates (as orient3d's exact stage,
//             with the lifting x^2 + y^2 in place of z).
// The sign is exact; the magnitude is an approximation (a stage estimate, or the most
// significant component of the exact expansion).
//
// Range in which the sign is exact (finite inputs; every nonzero coordinate must satisfy):
//   orient2d, collinear3d: 2^-485 <= |x| <= 2^509   (about 1.0e-146 .. 1.6e153)
//   orient3d:              2^-306 <= |x| <= 2^338   (about 7.7e-93  .. 5.6e101)
//   incircle:              2^-216 <= |x| <= 2^240   (about 9.5e-66  .. 1.8e72)
// Zero coordinates are always fine. Reason: each predicate is a polynomial of degree 2 (3, 4);
// every coordinate is a multiple of its last mantissa bit, which is at least 2^-537 (2^-358,
// 2^-268) in these ranges, so every product of two (three, four) of them is a multiple of
// 2^-1074, the smallest subnormal: products and their round-off terms never underflow, and
// subnormal results are exact. The upper bounds keep the filters' permanents below 2^1024 and
// Split(x) = (2^27 + 1) x finite (for incircle: permanent < 2^8 M^4 and expansion components
// < 2^6 M^4 for M the largest magnitude, both far below 2^1024 / 2^27). Outside these ranges
// the sign may be wrong.
//
// Requirements on the arithmetic: IEEE 754 binary64, round-to-nearest-even, no extended
// precision (FLT_EVAL_METHOD == 0), no contraction into FMA (-ffp-contract=off), no
// -ffast-math. Under these every operation below is bit-identical on x86-64 and AArch64.
//
// No heap, no exceptions, no recursion, no libm: all expansions live in fixed-size local arrays
// whose sizes follow from the paper's length bounds (a sum of expansions of lengths m and n has
// at most m + n components; scaling by one double doubles the length).

#include <cfloat>

#include "splintcore/geometry.h"

#include "geometry/incircle_stage_a.h"
#include "geometry/orient2d_stage_a.h"

// Contraction into FMA is not only a matter of bit-identity here: it breaks Two-Sum, Split and
// Two-Product (their round-off terms rely on every operation being rounded separately), and
// the predicates then return wrong signs. The build passes -ffp-contract=off; these pragmas
// keep the file correct when compiled without it (GCC defaults to -ffp-contract=fast in C++,
// which fuses on AArch64 and on x86-64 with -mfma). The GCC pragma holds even against
// -ffp-contract=fast; clang's does not (an explicit -ffp-contract=fast wins there).
#if defined(__clang__)
#pragma STDC FP_CONTRACT OFF
#elif defined(__GNUC__)
#pragma GCC optimize("fp-contract=off")
#endif

#if !defined(FLT_EVAL_METHOD) || FLT_EVAL_METHOD != 0
#error "splintcore predicates need double arithmetic evaluated in double (FLT_EVAL_METHOD 0)"
#endif

namespace splintcore {
namespace {

// eps: half an ulp of 1, the bound on the relative error of one rounded operation.
constexpr double kEpsilon = 0x1p-53;
// 2^ceil(53/2) + 1: splits a double into two halves of at most 26 bits each (Section 2.5).
constexpr double kSplitter = 134217729.0;

// Error bounds of Section 4.3 (computed exactly: every constant here is representable).
// ccwerrboundA: detail::kCcwErrBoundA (orient2d_stage_a.h, shared with the mesh check).
constexpr double kCcwErrBoundB = (2.0 + 12.0 * kEpsilon) * kEpsilon;
constexpr double kO3dErrBoundA = (7.0 + 56.0 * kEpsilon) * kEpsilon;
constexpr double kO3dErrBoundB = (3.0 + 28.0 * kEpsilon) * kEpsilon;
// iccerrboundA: detail::kIncircleErrBoundA (incircle_stage_a.h, shared with the CDT).
constexpr double kIccErrBoundB = (4.0 + 48.0 * kEpsilon) * kEpsilon;

// ---- exact two-term operations (Section 2.3-2.5). x is the rounded result, y the exact
// round-off, so x + y equals the exact value.

// Needs |a| >= |b| (or a == 0).
inline void fast_two_sum(double a, double b, double& x, double& y) {
  x = a + b;
  const double b_virtual = x - a;
  y = b - b_virtual;
}

inline void two_sum(double a, double b, double& x, double& y) {
  x = a + b;
  const double b_virtual = x - a;
  const double a_virtual = x - b_virtual;
  const double b_roundoff = b - b_virtual;
  const double a_roundoff = a - a_virtual;
  y = a_roundoff + b_roundoff;
}

// The round-off of x = fl(a - b).
inline double two_diff_tail(double a, double b, double x) {
  const double b_virtual = a - x;
  const double a_virtual = x + b_virtual;
  const double b_roundoff = b_virtual - b;
  const double a_roundoff = a - a_virtual;
  return a_roundoff + b_roundoff;
}

inline void two_diff(double a, double b, double& x, double& y) {
  x = a - b;
  y = two_diff_tail(a, b, x);
}

// Veltkamp/Dekker: a = hi + lo exactly, each half fitting in 26 bits.
inline void split(double a, double& hi, double& lo) {
  const double c = kSplitter * a;
  const double a_big = c - a;
  hi = c - a_big;
  lo = a - hi;
}

// x + y = a * b exactly, with b already split (Dekker's product without FMA: the build must
// give the same bits everywhere, and an FMA is not available or not used on every target).
inline void two_product_presplit(double a, double b, double b_hi, double b_lo, double& x,
                                 double& y) {
  x = a * b;
  double a_hi = 0.0;
  double a_lo = 0.0;
  split(a, a_hi, a_lo);
  const double err1 = x - (a_hi * b_hi);
  const double err2 = err1 - (a_lo * b_hi);
  const double err3 = err2 - (a_hi * b_lo);
  y = (a_lo * b_lo) - err3;
}

inline void two_product(double a, double b, double& x, double& y) {
  double b_hi = 0.0;
  double b_lo = 0.0;
  split(b, b_hi, b_lo);
  two_product_presplit(a, b, b_hi, b_lo, x, y);
}

// (a1 + a0) - b as a three-component expansion x2 + x1 + x0 (a Grow-Expansion step).
inline void two_one_diff(double a1, double a0, double b, double& x2, double& x1, double& x0) {
  double i = 0.0;
  two_diff(a0, b, i, x0);
  two_sum(a1, i, x2, x1);
}

// (a1 + a0) - (b1 + b0) as a four-component nonoverlapping expansion x[0..3], increasing
// magnitude, zeros possible.
inline void two_two_diff(double a1, double a0, double b1, double b0, double x[4]) {
  double j = 0.0;
  double k = 0.0;
  two_one_diff(a1, a0, b0, j, k, x[0]);
  two_one_diff(j, k, b1, x[3], x[2], x[1]);
}

// a*d - b*c exactly, as a four-component expansion.
inline void two_by_two(double a, double d, double b, double c, double x[4]) {
  double ad1 = 0.0;
  double ad0 = 0.0;
  double bc1 = 0.0;
  double bc0 = 0.0;
  two_product(a, d, ad1, ad0);
  two_product(b, c, bc1, bc0);
  two_two_diff(ad1, ad0, bc1, bc0, x);
}

inline double magnitude(double v) { return v < 0.0 ? -v : v; }

// ---- expansions: nonoverlapping components in increasing magnitude (Section 2.1).

// h = e + f with zero elimination (Fast-Expansion-Sum, Theorem 13: needs round-to-even and
// strongly nonoverlapping inputs, which every producer in this file gives). h must hold
// elen + flen components; elen, flen >= 1. Returns the length of h (>= 1).
int fast_expansion_sum_zeroelim(int elen, const double* e, int flen, const double* f, double* h) {
  // Merge e and f by magnitude, taking the smaller head each time (never reads past an end).
  int ei = 0;
  int fi = 0;
  auto next_smallest = [&]() -> double {
    if (fi >= flen || (ei < elen && magnitude(e[ei]) <= magnitude(f[fi]))) return e[ei++];
    return f[fi++];
  };
  int hlen = 0;
  double q = next_smallest();
  const int total = elen + flen;
  if (total >= 2) {
    // The second term is at least as large as the first: Fast-Two-Sum is exact here.
    const double g = next_smallest();
    double q_new = 0.0;
    double hh = 0.0;
    fast_two_sum(g, q, q_new, hh);
    q = q_new;
    if (hh != 0.0) h[hlen++] = hh;
    for (int n = 2; n < total; ++n) {
      const double g_next = next_smallest();
      two_sum(q, g_next, q_new, hh);
      q = q_new;
      if (hh != 0.0) h[hlen++] = hh;
    }
  }
  if (q != 0.0 || hlen == 0) h[hlen++] = q;
  return hlen;
}

// h = b * e with zero elimination (Scale-Expansion, Theorem 19). h must hold 2 * elen
// components; elen >= 1. Returns the length of h (>= 1).
int scale_expansion_zeroelim(int elen, const double* e, double b, double* h) {
  double b_hi = 0.0;
  double b_lo = 0.0;
  split(b, b_hi, b_lo);
  int hlen = 0;
  double q = 0.0;
  double hh = 0.0;
  two_product_presplit(e[0], b, b_hi, b_lo, q, hh);
  if (hh != 0.0) h[hlen++] = hh;
  for (int i = 1; i < elen; ++i) {
    double product1 = 0.0;
    double product0 = 0.0;
    two_product_presplit(e[i], b, b_hi, b_lo, product1, product0);
    double sum = 0.0;
    two_sum(q, product0, sum, hh);
    if (hh != 0.0) h[hlen++] = hh;
    fast_two_sum(product1, sum, q, hh);  // |product1| >= |sum| (proof of Theorem 19)
    if (hh != 0.0) h[hlen++] = hh;
  }
  if (q != 0.0 || hlen == 0) h[hlen++] = q;
  return hlen;
}

// The rounded sum of the components, smallest first (the stage estimates of Section 4).
double estimate(int elen, const double* e) {
  double q = e[0];
  for (int i = 1; i < elen; ++i) q += e[i];
  return q;
}

// The most significant nonzero component, or 0: its sign is the sign of the expansion, as the
// smaller components of a nonoverlapping expansion sum to less than its lowest set bit.
double most_significant(int elen, const double* e) {
  for (int i = elen - 1; i >= 0; --i) {
    if (e[i] != 0.0) return e[i];
  }
  return 0.0;
}

void negate(int elen, double* e) {
  for (int i = 0; i < elen; ++i) e[i] = -e[i];
}

// ---- orient2d stages B and D.

double orient2d_adapt(double ax, double ay, double bx, double by, double cx, double cy,
                      double detsum) {
  const double acx = ax - cx;
  const double bcx = bx - cx;
  const double acy = ay - cy;
  const double bcy = by - cy;

  // Stage B: acx * bcy - acy * bcx exactly, for the rounded differences.
  double b_expansion[4];
  two_by_two(acx, bcy, acy, bcx, b_expansion);
  const double det = estimate(4, b_expansion);
  // Strict comparison: a tie may be an exact zero when the bound itself is subnormal.
  const double errbound = kCcwErrBoundB * detsum;
  if (det > errbound || -det > errbound) return det;

  const double acx_tail = two_diff_tail(ax, cx, acx);
  const double bcx_tail = two_diff_tail(bx, cx, bcx);
  const double acy_tail = two_diff_tail(ay, cy, acy);
  const double bcy_tail = two_diff_tail(by, cy, bcy);
  if (acx_tail == 0.0 && acy_tail == 0.0 && bcx_tail == 0.0 && bcy_tail == 0.0) {
    // The differences were exact, so the stage B expansion is the determinant.
    return most_significant(4, b_expansion);
  }

  // Stage D: with acx_exact = acx + acx_tail (and so on), the determinant is
  //   B + (acx_tail bcy - acy_tail bcx) + (acx bcy_tail - acy bcx_tail)
  //     + (acx_tail bcy_tail - acy_tail bcx_tail), every term exact.
  double u[4];
  double c1[8];
  double c2[12];
  double d[16];
  two_by_two(acx_tail, bcy, acy_tail, bcx, u);
  const int c1len = fast_expansion_sum_zeroelim(4, b_expansion, 4, u, c1);
  two_by_two(acx, bcy_tail, acy, bcx_tail, u);
  const int c2len = fast_expansion_sum_zeroelim(c1len, c1, 4, u, c2);
  two_by_two(acx_tail, bcy_tail, acy_tail, bcx_tail, u);
  const int dlen = fast_expansion_sum_zeroelim(c2len, c2, 4, u, d);
  return d[dlen - 1];
}

// ---- orient3d stage B and the exact evaluation.

// x of point p times y of point q minus x of q times y of p, exactly.
void minor_xy(const Vec3& p, const Vec3& q, double out[4]) { two_by_two(p.x, q.y, q.x, p.y, out); }

// det[p 1; q 1; r 1] over the x, y columns: m(p,q) + m(q,r) + m(r,p) with m as above;
// the three minors are passed in, the last one given as (p,r) and subtracted when
// `subtract_third` is set. Output holds 12 components.
int minor3_xy(const double pq[4], const double qr[4], const double third[4], bool subtract_third,
              double out[12]) {
  double sum2[8];
  double third_signed[4];
  for (int i = 0; i < 4; ++i) third_signed[i] = subtract_third ? -third[i] : third[i];
  const int len2 = fast_expansion_sum_zeroelim(4, pq, 4, qr, sum2);
  return fast_expansion_sum_zeroelim(len2, sum2, 4, third_signed, out);
}

// The four xy 3x3 minors of the rows a, b, c, d of a 4x4 matrix [x y * 1]:
// M(p,q,r) = m(p,q) + m(q,r) + m(r,p) for (p,q,r) = (b,c,d), (a,c,d), (a,b,d), (a,b,c).
// Each holds 12 components; the lengths are returned in len[0..3].
struct XyMinors {
  double bcd[12];
  double acd[12];
  double abd[12];
  double abc[12];
  int len[4];
};

void xy_minors(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, XyMinors* out) {
  double ab[4];
  double bc[4];
  double cd[4];
  double da[4];
  double ac[4];
  double bd[4];
  minor_xy(a, b, ab);
  minor_xy(b, c, bc);
  minor_xy(c, d, cd);
  minor_xy(d, a, da);
  minor_xy(a, c, ac);
  minor_xy(b, d, bd);

  out->len[0] = minor3_xy(bc, cd, bd, true, out->bcd);   // bc + cd + db = bc + cd - bd
  out->len[1] = minor3_xy(ac, cd, da, false, out->acd);  // ac + cd + da
  out->len[2] = minor3_xy(ab, bd, da, false, out->abd);  // ab + bd + da
  out->len[3] = minor3_xy(ab, bc, ac, true, out->abc);   // ab + bc + ca = ab + bc - ac
}

// det[a 1; b 1; c 1; d 1] = det[a - d; b - d; c - d], exactly, from the original coordinates:
// expansion along the z column,
//   az M(b,c,d) - bz M(a,c,d) + cz M(a,b,d) - dz M(a,b,c),
// where M(p,q,r) = m(p,q) + m(q,r) + m(r,p) is the xy 3x3 minor.
double orient3d_exact(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  XyMinors m;
  xy_minors(a, b, c, d, &m);
  const int bcd_len = m.len[0];
  const int acd_len = m.len[1];
  const int abd_len = m.len[2];
  const int abc_len = m.len[3];
  const double* m_bcd = m.bcd;
  const double* m_acd = m.acd;
  const double* m_abd = m.abd;
  const double* m_abc = m.abc;

  double a_det[24];
  double b_det[24];
  double c_det[24];
  double d_det[24];
  const int a_len = scale_expansion_zeroelim(bcd_len, m_bcd, a.z, a_det);
  const int b_len = scale_expansion_zeroelim(acd_len, m_acd, b.z, b_det);
  negate(b_len, b_det);
  const int c_len = scale_expansion_zeroelim(abd_len, m_abd, c.z, c_det);
  const int d_len = scale_expansion_zeroelim(abc_len, m_abc, d.z, d_det);
  negate(d_len, d_det);

  double ab_det[48];
  double cd_det[48];
  double det[96];
  const int ab_len = fast_expansion_sum_zeroelim(a_len, a_det, b_len, b_det, ab_det);
  const int cd_len = fast_expansion_sum_zeroelim(c_len, c_det, d_len, d_det, cd_det);
  const int det_len = fast_expansion_sum_zeroelim(ab_len, ab_det, cd_len, cd_det, det);
  return det[det_len - 1];
}

double orient3d_adapt(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d,
                      double permanent) {
  const double adx = a.x - d.x;
  const double bdx = b.x - d.x;
  const double cdx = c.x - d.x;
  const double ady = a.y - d.y;
  const double bdy = b.y - d.y;
  const double cdy = c.y - d.y;
  const double adz = a.z - d.z;
  const double bdz = b.z - d.z;
  const double cdz = c.z - d.z;

  // Stage B: the determinant of the rounded differences, exactly.
  double bc[4];
  double ca[4];
  double ab[4];
  two_by_two(bdx, cdy, cdx, bdy, bc);
  two_by_two(cdx, ady, adx, cdy, ca);
  two_by_two(adx, bdy, bdx, ady, ab);
  double a_det[8];
  double b_det[8];
  double c_det[8];
  const int a_len = scale_expansion_zeroelim(4, bc, adz, a_det);
  const int b_len = scale_expansion_zeroelim(4, ca, bdz, b_det);
  const int c_len = scale_expansion_zeroelim(4, ab, cdz, c_det);
  double ab_det[16];
  double fin[24];
  const int ab_len = fast_expansion_sum_zeroelim(a_len, a_det, b_len, b_det, ab_det);
  const int fin_len = fast_expansion_sum_zeroelim(ab_len, ab_det, c_len, c_det, fin);
  const double det = estimate(fin_len, fin);
  const double errbound = kO3dErrBoundB * permanent;
  if (det > errbound || -det > errbound) return det;

  if (two_diff_tail(a.x, d.x, adx) == 0.0 && two_diff_tail(b.x, d.x, bdx) == 0.0 &&
      two_diff_tail(c.x, d.x, cdx) == 0.0 && two_diff_tail(a.y, d.y, ady) == 0.0 &&
      two_diff_tail(b.y, d.y, bdy) == 0.0 && two_diff_tail(c.y, d.y, cdy) == 0.0 &&
      two_diff_tail(a.z, d.z, adz) == 0.0 && two_diff_tail(b.z, d.z, bdz) == 0.0 &&
      two_diff_tail(c.z, d.z, cdz) == 0.0) {
    // The differences were exact, so the stage B expansion is the determinant.
    return fin[fin_len - 1];
  }
  return orient3d_exact(a, b, c, d);
}

// ---- incircle stages B and the exact evaluation.

// (x^2 + y^2) * e for the expansion e (1 to 12 components), negated when `negative`.
// `out` must hold 8 * elen components.
int lift_scale(int elen, const double* e, double x, double y, bool negative, double* out) {
  double ex[24];
  double exx[48];
  double ey[24];
  double eyy[48];
  const int ex_len = scale_expansion_zeroelim(elen, e, x, ex);
  const int exx_len = scale_expansion_zeroelim(ex_len, ex, x, exx);
  const int ey_len = scale_expansion_zeroelim(elen, e, y, ey);
  const int eyy_len = scale_expansion_zeroelim(ey_len, ey, y, eyy);
  const int len = fast_expansion_sum_zeroelim(exx_len, exx, eyy_len, eyy, out);
  if (negative) negate(len, out);
  return len;
}

// det[a l(a) 1; b l(b) 1; c l(c) 1; d l(d) 1] with l(p) = px^2 + py^2, exactly, from the
// original coordinates (subtracting row d and then the multiples 2 dx, 2 dy of the x, y
// columns from the lift column turns it into the determinant of the differences that
// incircle() evaluates). Expansion along the lift column:
//   l(a) M(b,c,d) - l(b) M(a,c,d) + l(c) M(a,b,d) - l(d) M(a,b,c).
double incircle_exact(double ax, double ay, double bx, double by, double cx, double cy, double dx,
                      double dy) {
  const Vec3 a{ax, ay, 0.0};
  const Vec3 b{bx, by, 0.0};
  const Vec3 c{cx, cy, 0.0};
  const Vec3 d{dx, dy, 0.0};
  XyMinors m;
  xy_minors(a, b, c, d, &m);
  double a_det[96];
  double b_det[96];
  double c_det[96];
  double d_det[96];
  const int a_len = lift_scale(m.len[0], m.bcd, ax, ay, false, a_det);
  const int b_len = lift_scale(m.len[1], m.acd, bx, by, true, b_det);
  const int c_len = lift_scale(m.len[2], m.abd, cx, cy, false, c_det);
  const int d_len = lift_scale(m.len[3], m.abc, dx, dy, true, d_det);
  double ab_det[192];
  double cd_det[192];
  double det[384];
  const int ab_len = fast_expansion_sum_zeroelim(a_len, a_det, b_len, b_det, ab_det);
  const int cd_len = fast_expansion_sum_zeroelim(c_len, c_det, d_len, d_det, cd_det);
  const int det_len = fast_expansion_sum_zeroelim(ab_len, ab_det, cd_len, cd_det, det);
  return det[det_len - 1];
}

double incircle_adapt(double ax, double ay, double bx, double by, double cx, double cy, double dx,
                      double dy, double permanent) {
  const double adx = ax - dx;
  const double bdx = bx - dx;
  const double cdx = cx - dx;
  const double ady = ay - dy;
  const double bdy = by - dy;
  const double cdy = cy - dy;

  // Stage B: the determinant of the rounded differences, exactly:
  //   (adx^2 + ady^2) bc + (bdx^2 + bdy^2) ca + (cdx^2 + cdy^2) ab.
  double bc[4];
  double ca[4];
  double ab[4];
  two_by_two(bdx, cdy, cdx, bdy, bc);
  two_by_two(cdx, ady, adx, cdy, ca);
  two_by_two(adx, bdy, bdx, ady, ab);
  double a_det[32];
  double b_det[32];
  double c_det[32];
  const int a_len = lift_scale(4, bc, adx, ady, false, a_det);
  const int b_len = lift_scale(4, ca, bdx, bdy, false, b_det);
  const int c_len = lift_scale(4, ab, cdx, cdy, false, c_det);
  double ab_det[64];
  double fin[96];
  const int ab_len = fast_expansion_sum_zeroelim(a_len, a_det, b_len, b_det, ab_det);
  const int fin_len = fast_expansion_sum_zeroelim(ab_len, ab_det, c_len, c_det, fin);
  const double det = estimate(fin_len, fin);
  const double errbound = kIccErrBoundB * permanent;
  if (det > errbound || -det > errbound) return det;

  if (two_diff_tail(ax, dx, adx) == 0.0 && two_diff_tail(bx, dx, bdx) == 0.0 &&
      two_diff_tail(cx, dx, cdx) == 0.0 && two_diff_tail(ay, dy, ady) == 0.0 &&
      two_diff_tail(by, dy, bdy) == 0.0 && two_diff_tail(cy, dy, cdy) == 0.0) {
    // The differences were exact, so the stage B expansion is the determinant.
    return fin[fin_len - 1];
  }
  return incircle_exact(ax, ay, bx, by, cx, cy, dx, dy);
}

// ((b - a) x (c - a)) . d exactly, as a x b + b x c + c x a (each 2x2 minor of input
// coordinates is exact as four components) scaled by d's coordinates.
double normal_dot_exact(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const double pa[3] = {a.x, a.y, a.z}, pb[3] = {b.x, b.y, b.z}, pc[3] = {c.x, c.y, c.z};
  const double pd[3] = {d.x, d.y, d.z};
  double sum[72];
  int sum_len = 0;
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3, k = (i + 2) % 3;
    double ab[4], bc[4], ca[4], abbc[8], n[12], scaled[24], next[72];
    two_by_two(pa[j], pb[k], pa[k], pb[j], ab);
    two_by_two(pb[j], pc[k], pb[k], pc[j], bc);
    two_by_two(pc[j], pa[k], pc[k], pa[j], ca);
    const int abbc_len = fast_expansion_sum_zeroelim(4, ab, 4, bc, abbc);
    const int n_len = fast_expansion_sum_zeroelim(abbc_len, abbc, 4, ca, n);
    const int scaled_len = scale_expansion_zeroelim(n_len, n, pd[i], scaled);
    if (sum_len == 0) {
      for (int m = 0; m < scaled_len; ++m) sum[m] = scaled[m];
      sum_len = scaled_len;
      continue;
    }
    sum_len = fast_expansion_sum_zeroelim(sum_len, sum, scaled_len, scaled, next);
    for (int m = 0; m < sum_len; ++m) sum[m] = next[m];
  }
  return sum[sum_len - 1];
}

}  // namespace

double orient2d(double ax, double ay, double bx, double by, double cx, double cy) {
  const detail::Orient2dStageA s = detail::orient2d_stage_a(ax, ay, bx, by, cx, cy);
  if (s.certain) return s.det;
  return orient2d_adapt(ax, ay, bx, by, cx, cy, s.detsum);
}

double orient3d(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const double adx = a.x - d.x;
  const double bdx = b.x - d.x;
  const double cdx = c.x - d.x;
  const double ady = a.y - d.y;
  const double bdy = b.y - d.y;
  const double cdy = c.y - d.y;
  const double adz = a.z - d.z;
  const double bdz = b.z - d.z;
  const double cdz = c.z - d.z;

  const double bdxcdy = bdx * cdy;
  const double cdxbdy = cdx * bdy;
  const double cdxady = cdx * ady;
  const double adxcdy = adx * cdy;
  const double adxbdy = adx * bdy;
  const double bdxady = bdx * ady;

  const double det = adz * (bdxcdy - cdxbdy) + bdz * (cdxady - adxcdy) + cdz * (adxbdy - bdxady);
  const double permanent = (magnitude(bdxcdy) + magnitude(cdxbdy)) * magnitude(adz) +
                           (magnitude(cdxady) + magnitude(adxcdy)) * magnitude(bdz) +
                           (magnitude(adxbdy) + magnitude(bdxady)) * magnitude(cdz);
  const double errbound = kO3dErrBoundA * permanent;
  if (det > errbound || -det > errbound) return det;
  // A zero permanent means every term has an exactly zero factor (a rounded difference or
  // product is zero only when it is exactly zero, inside the range above): the determinant is
  // exactly 0. Common and worth the test: four points on an axis-aligned plane.
  if (permanent == 0.0) return 0.0;
  return orient3d_adapt(a, b, c, d, permanent);
}

double incircle(double ax, double ay, double bx, double by, double cx, double cy, double dx,
                double dy) {
  const detail::IncircleStageA stage = detail::incircle_stage_a(ax, ay, bx, by, cx, cy, dx, dy);
  if (stage.certain()) return stage.det;
  const double permanent = stage.permanent;
  // A zero permanent: every term has an exactly zero factor (a lift is zero only when its
  // point equals d, a product only when a factor is zero, inside the range), so the
  // determinant is exactly 0. Common: d equal to one of a, b, c.
  if (permanent == 0.0) return 0.0;
  return incircle_adapt(ax, ay, bx, by, cx, cy, dx, dy, permanent);
}

bool collinear3d(const Vec3& a, const Vec3& b, const Vec3& c) {
  // (b - a) x (c - a) = 0: its z, x and y components are the xy, yz and zx orientations.
  return orient2d(a.x, a.y, b.x, b.y, c.x, c.y) == 0.0 &&
         orient2d(a.y, a.z, b.y, b.z, c.y, c.z) == 0.0 &&
         orient2d(a.z, a.x, b.z, b.x, c.z, c.x) == 0.0;
}

double normal_dot(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const double ux = b.x - a.x, uy = b.y - a.y, uz = b.z - a.z;
  const double vx = c.x - a.x, vy = c.y - a.y, vz = c.z - a.z;
  const double uyvz = uy * vz, uzvy = uz * vy, uzvx = uz * vx;
  const double uxvz = ux * vz, uxvy = ux * vy, uyvx = uy * vx;
  const double det = d.x * (uyvz - uzvy) + d.y * (uzvx - uxvz) + d.z * (uxvy - uyvx);
  // orient3d's bound: the same products of rounded differences, the third row exact here.
  const double permanent = (magnitude(uyvz) + magnitude(uzvy)) * magnitude(d.x) +
                           (magnitude(uzvx) + magnitude(uxvz)) * magnitude(d.y) +
                           (magnitude(uxvy) + magnitude(uyvx)) * magnitude(d.z);
  const double errbound = kO3dErrBoundA * permanent;
  if (det > errbound || -det > errbound) return det;
  if (permanent == 0.0) return 0.0;
  return normal_dot_exact(a, b, c, d);
}

}  // namespace splintcore
