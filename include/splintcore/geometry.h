// splintcore geometry: Vec3, axis-aligned boxes, rigid transforms and exact predicates.
#ifndef SPLINTCORE_GEOMETRY_H
#define SPLINTCORE_GEOMETRY_H

#include <cmath>

#include "splintcore/core.h"

namespace splintcore {

struct Vec3 {
  double x = 0.0;
  double y = 0.0;
  double z = 0.0;

  constexpr Vec3() = default;
  constexpr Vec3(double x_, double y_, double z_) : x(x_), y(y_), z(z_) {}

  double operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
  double& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
};

inline Vec3 operator+(const Vec3& a, const Vec3& b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline Vec3 operator-(const Vec3& a, const Vec3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline Vec3 operator-(const Vec3& a) { return {-a.x, -a.y, -a.z}; }
inline Vec3 operator*(const Vec3& a, double s) { return {a.x * s, a.y * s, a.z * s}; }
inline Vec3 operator*(double s, const Vec3& a) { return {a.x * s, a.y * s, a.z * s}; }
inline bool operator==(const Vec3& a, const Vec3& b) {
  return a.x == b.x && a.y == b.y && a.z == b.z;
}
inline bool operator!=(const Vec3& a, const Vec3& b) { return !(a == b); }

inline double dot(const Vec3& a, const Vec3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline double length_squared(const Vec3& a) { return dot(a, a); }
// sqrt is correctly rounded by IEEE 754 on every platform, so this is bit-reproducible.
inline double length(const Vec3& a) { return std::sqrt(dot(a, a)); }
inline Vec3 min_vec(const Vec3& a, const Vec3& b) {
  return {a.x < b.x ? a.x : b.x, a.y < b.y ? a.y : b.y, a.z < b.z ? a.z : b.z};
}
inline Vec3 max_vec(const Vec3& a, const Vec3& b) {
  return {a.x > b.x ? a.x : b.x, a.y > b.y ? a.y : b.y, a.z > b.z ? a.z : b.z};
}

// True when the value is neither NaN nor infinite (decided on the bit pattern, so it holds
// under any compiler flag).
inline bool is_finite(double v) {
  uint64_t bits;
  std::memcpy(&bits, &v, sizeof(bits));
  return (bits & 0x7ff0000000000000ull) != 0x7ff0000000000000ull;
}
inline bool is_finite(float v) {
  uint32_t bits;
  std::memcpy(&bits, &v, sizeof(bits));
  return (bits & 0x7f800000u) != 0x7f800000u;
}
inline bool is_finite(const Vec3& v) { return is_finite(v.x) && is_finite(v.y) && is_finite(v.z); }

// True when the double is exactly a float32 value (decided on the bits: no float arithmetic
// that a compiler could elide). NaN and infinity count as not exact.
inline bool is_float32_exact(double x) {
  uint64_t bits;
  std::memcpy(&bits, &x, sizeof(bits));
  const uint64_t mantissa = bits & ((uint64_t{1} << 52) - 1);
  const int e = static_cast<int>((bits >> 52) & 0x7ff) - 1023;
  if (((bits >> 52) & 0x7ff) == 0) return mantissa == 0;  // zero (double subnormals are not)
  if (e > 127 || e < -149) return false;
  const int dropped = e >= -126 ? 29 : 29 + (-126 - e);  // mantissa bits float32 lacks
  return (mantissa & ((uint64_t{1} << dropped) - 1)) == 0;
}
inline bool is_float32_exact(const Vec3& v) {
  return is_float32_exact(v.x) && is_float32_exact(v.y) && is_float32_exact(v.z);
}

// Rounds each coordinate to the nearest float32 (what STL stores), -0 to +0. False (and v
// unchanged) when a coordinate is not finite or beyond float32's range. Out of line and through
// a volatile: GCC 12's SLP vectoriser drops neighbouring double -> float -> double round trips.
bool round_to_float32(Vec3* v);

// ---------------------------------------------------------------------------------------------
// Axis-aligned bounding box. Empty until a point is added.

struct Aabb {
  Vec3 lo{HUGE_VAL, HUGE_VAL, HUGE_VAL};
  Vec3 hi{-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};

  bool empty() const { return lo.x > hi.x || lo.y > hi.y || lo.z > hi.z; }
  void add(const Vec3& p) {
    lo = min_vec(lo, p);
    hi = max_vec(hi, p);
  }
  void add(const Aabb& b) {
    lo = min_vec(lo, b.lo);
    hi = max_vec(hi, b.hi);
  }
  Vec3 extent() const { return empty() ? Vec3{} : hi - lo; }
  Vec3 center() const { return empty() ? Vec3{} : (lo + hi) * 0.5; }
  // (All six compared, without a branch: which boxes overlap is data the branch predictor
  // cannot learn.)
  bool overlaps(const Aabb& b) const {
    return static_cast<bool>(static_cast<int>(lo.x <= b.hi.x) & static_cast<int>(b.lo.x <= hi.x) &
                             static_cast<int>(lo.y <= b.hi.y) & static_cast<int>(b.lo.y <= hi.y) &
                             static_cast<int>(lo.z <= b.hi.z) & static_cast<int>(b.lo.z <= hi.z));
  }
  bool contains(const Vec3& p) const {
    return p.x >= lo.x && p.x <= hi.x && p.y >= lo.y && p.y <= hi.y && p.z >= lo.z && p.z <= hi.z;
  }
  // The sides of the box that p lies beyond (strictly), one bit each: x below lo 1, above hi 2,
  // y 4 and 8, z 16 and 32; 0 inside (or on) it. A triangle or segment whose corners share a
  // bit lies wholly beyond that side, so its box misses this one.
  uint8_t outcode(const Vec3& p) const {
    return static_cast<uint8_t>((p.x < lo.x ? 1u : 0u) | (p.x > hi.x ? 2u : 0u) |
                                (p.y < lo.y ? 4u : 0u) | (p.y > hi.y ? 8u : 0u) |
                                (p.z < lo.z ? 16u : 0u) | (p.z > hi.z ? 32u : 0u));
  }
  // The triangle a, b, c lies wholly beyond one side of the box (its corners share an outcode
  // bit): it cannot meet the box. A NaN corner is beyond no side.
  bool beyond_one_side(const Vec3& a, const Vec3& b, const Vec3& c) const {
    return (outcode(a) & outcode(b) & outcode(c)) != 0;
  }
};

// The box of triangle abc grown by `reach` along each axis.
inline Aabb reach_box(const Vec3& a, const Vec3& b, const Vec3& c, double reach) {
  Aabb box;
  box.add(a);
  box.add(b);
  box.add(c);
  box.lo = box.lo - Vec3{reach, reach, reach};
  box.hi = box.hi + Vec3{reach, reach, reach};
  return box;
}

// ---------------------------------------------------------------------------------------------
// Rigid transform: p' = R p + t, R a rotation (orthonormal, det +1).

struct RigidTransform {
  double r[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  Vec3 t{};

  Vec3 apply_point(const Vec3& p) const {
    return {r[0][0] * p.x + r[0][1] * p.y + r[0][2] * p.z + t.x,
            r[1][0] * p.x + r[1][1] * p.y + r[1][2] * p.z + t.y,
            r[2][0] * p.x + r[2][1] * p.y + r[2][2] * p.z + t.z};
  }
  Vec3 apply_vector(const Vec3& v) const {
    return {r[0][0] * v.x + r[0][1] * v.y + r[0][2] * v.z,
            r[1][0] * v.x + r[1][1] * v.y + r[1][2] * v.z,
            r[2][0] * v.x + r[2][1] * v.y + r[2][2] * v.z};
  }
  static RigidTransform translation(const Vec3& t_) {
    RigidTransform x;
    x.t = t_;
    return x;
  }
};

// this then next: (next o first)(p) = next(first(p)).
RigidTransform compose(const RigidTransform& next, const RigidTransform& first);
RigidTransform inverse(const RigidTransform& x);

// Builds a rigid transform from a row-major 4x4 matrix, checking that it is rigid: finite,
// last row 0 0 0 1, R^T R = I within `tolerance` per entry, det(R) = +1 within tolerance
// (a reflection would turn a mesh inside out). The error names the offending entry.
Status rigid_from_matrix(const double m[16], double tolerance, RigidTransform* out);

// ---------------------------------------------------------------------------------------------
// Angles without libm: atan by range reduction to |t| <= tan(7.5 deg) and a Taylor series, with
// only + - * / (the libm functions are not the same bits on every platform). Accurate to a few
// ulps; exactly the same bits everywhere.
double deterministic_atan(double x);
double deterministic_atan2(double y, double x);  // in [-pi, pi]; atan2(0, 0) = 0
// The angle between two vectors, in [0, pi] (0 when either is zero).
double angle_between(const Vec3& a, const Vec3& b);
// sin x and cos x (Cody-Waite reduction by pi/2, Taylor series on [-pi/4, pi/4]): within 1 ulp
// or so of the true values for |x| <= 2^20 (farther, the reduction loses accuracy); the same
// bits everywhere. NaN for NaN and infinity.
void deterministic_sincos(double x, double* s, double* c);
// The rotation by `angle` (radians, right-handed about `unit_axis`) about the line through
// `point` along `unit_axis` (unit length; not checked): p -> R (p - point) + point. R from
// Rodrigues' formula with deterministic_sincos (the versine 1 - cos from the half angle, so
// small angles keep their accuracy): the same bits everywhere.
RigidTransform rotation_about_axis(const Vec3& point, const Vec3& unit_axis, double angle);

// ---------------------------------------------------------------------------------------------
// Exact geometric predicates (Shewchuk, "Adaptive Precision Floating-Point Arithmetic and Fast
// Robust Geometric Predicates", 1997). The sign of each result is exact for finite inputs
// whose products neither overflow nor underflow: every nonzero coordinate within
// [2^-485, 2^509] (about 1e-146 .. 1.6e153) for orient2d and collinear3d, within
// [2^-306, 2^338] (about 7.7e-93 .. 5.6e101) for orient3d, and within [2^-216, 2^240] for
// incircle (see predicates.cpp). The magnitude is an approximation.

// > 0 when a, b, c run counter-clockwise, < 0 clockwise, 0 when collinear.
// Equals (a - c) x (b - c) in exact arithmetic.
double orient2d(double ax, double ay, double bx, double by, double cx, double cy);

// > 0 when d lies strictly inside the circle through a, b, c (a, b, c counter-clockwise),
// < 0 outside, 0 on it (or when a, b, c are collinear and d on their line). Equals
// det[a - d, |a - d|^2; b - d, |b - d|^2; c - d, |c - d|^2] in exact arithmetic. A polynomial of
// degree 4: the sign is exact when every nonzero coordinate is within [2^-216, 2^240] (about
// 9.5e-66 .. 1.8e72).
double incircle(double ax, double ay, double bx, double by, double cx, double cy, double dx,
                double dy);

// > 0 when d lies below the plane through a, b, c (a, b, c counter-clockwise seen from above),
// < 0 above, 0 when coplanar. Equals det[a - d; b - d; c - d] in exact arithmetic.
double orient3d(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

// > 0 when the triangle a, b, c (counter-clockwise seen from outside) faces along the direction
// d, < 0 when it faces against it, 0 when d lies in its plane: ((b - a) x (c - a)) . d in exact
// arithmetic (d is a direction, not a point; the same range as orient3d).
double normal_dot(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

inline int sign_of(double v) { return (v > 0) - (v < 0); }

// True when a, b, c are exactly collinear (including coincident points): all three
// coordinate-plane projections have zero orientation.
bool collinear3d(const Vec3& a, const Vec3& b, const Vec3& c);

// ---------------------------------------------------------------------------------------------
// Exact intersection tests on closed triangles and segments (decided by orient2d/orient3d
// only, so every answer is exact within orient3d's range above: nonzero coordinates of
// magnitude 2^-306 .. 2^338, which every float32 STL coordinate and every mm-scale double
// meets; subnormal coordinates are outside it). Degenerate triangles are the caller's to
// reject first.

// Does the closed segment pq meet the closed triangle abc?
bool segment_intersects_triangle(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b,
                                 const Vec3& c);

// How the closed segment pq meets the closed triangle abc, for counting crossings: kMisses (no
// common point), kCrosses (p and q strictly on opposite sides of abc's plane and the segment
// through abc's interior, away from its edges), else kTouches (it meets an edge or a corner,
// an endpoint lies in the plane, or abc is degenerate): a crossing count is then not decided.
enum class SegmentCrossing : uint8_t { kMisses, kCrosses, kTouches };
SegmentCrossing segment_crossing(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b,
                                 const Vec3& c);

// Do the closed triangles abc and def meet (touching counts)?
bool triangles_intersect(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, const Vec3& e,
                         const Vec3& f);

// The same two tests when the caller already knows the points are coplanar (exactly): they
// skip the orient3d calls that would find it out again.
bool coplanar_segment_intersects_triangle(const Vec3& p, const Vec3& q, const Vec3& a,
                                          const Vec3& b, const Vec3& c);
bool coplanar_triangles_intersect(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d,
                                  const Vec3& e, const Vec3& f);

// For coplanar work: an axis (0 x, 1 y, 2 z) to drop so that the projection of the triangle
// abc is not degenerate, or -1 when abc is degenerate (collinear).
int projection_axis(const Vec3& a, const Vec3& b, const Vec3& c);

}  // namespace splintcore

#endif  // SPLINTCORE_GEOMETRY_H
