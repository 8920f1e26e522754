// Tests of the exact triangle-triangle contact (src/boolean/contact.cpp): hand cases for every
// degenerate kind (both argument orders), the swap and corner-rotation relations as property
// tests, an exact rational oracle on random pairs with corners on a small integer grid (where
// degenerate contacts are frequent: the per-kind counts are printed and each kind must
// appear), random general-position pairs with arbitrary doubles, and the position error bound
// of contact_point_position.
// Random streams are std::mt19937_64 with fixed seeds, never two draws in one call's
// arguments (their order is unspecified), so every compiler sees the same inputs.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <map>
#include <random>
#include <string>
#include <vector>

// Internal to the library: src/ is not on the tests' include path.
#include "../../src/boolean/contact.h"
#include "splintcore/geometry.h"

namespace splintcore {
namespace {

using detail::Contact;
using detail::contact_point_position;
using detail::ContactKind;
using detail::ContactPoint;
using detail::intersect_triangles;
using detail::Loc;
using detail::loc_index;
using detail::loc_is_edge;
using detail::loc_is_vertex;

constexpr Loc V0 = Loc::kV0, V1 = Loc::kV1, V2 = Loc::kV2;
constexpr Loc E0 = Loc::kE0, E1 = Loc::kE1, E2 = Loc::kE2, F = Loc::kFace;

const char* loc_name(Loc l) {
  static const char* const names[] = {"V0", "V1", "V2", "E0", "E1", "E2", "F"};
  const int i = static_cast<int>(l);
  return i >= 0 && i < 7 ? names[i] : "?";
}

std::string describe(const Contact& c) {
  static const char* const kinds[] = {"none", "point", "segment", "polygon"};
  std::string s = kinds[static_cast<int>(c.kind)];
  if (c.coplanar) s += " coplanar";
  for (int i = 0; i < c.count; ++i) {
    s += std::string(" (") + loc_name(c.p[i].on_a) + "," + loc_name(c.p[i].on_b) + ")";
  }
  s += " sides";
  for (int i = 0; i < 3; ++i) s += " " + std::to_string(c.side_a[i]);
  s += " /";
  for (int i = 0; i < 3; ++i) s += " " + std::to_string(c.side_b[i]);
  return s;
}

Contact run(const Vec3 a[3], const Vec3 b[3]) {
  Contact c;
  EXPECT_TRUE(intersect_triangles(a, b, &c));
  return c;
}

// Equal, with a polygon compared up to where its cycle starts.
bool same_contact(const Contact& x, const Contact& y) {
  if (x.kind != y.kind || x.coplanar != y.coplanar || x.count != y.count) return false;
  for (int i = 0; i < 3; ++i) {
    if (x.side_a[i] != y.side_a[i] || x.side_b[i] != y.side_b[i]) return false;
  }
  const int n = x.count;
  for (int shift = 0; shift < (x.kind == ContactKind::kPolygon ? n : 1); ++shift) {
    bool ok = true;
    for (int i = 0; i < n && ok; ++i) ok = x.p[i] == y.p[(i + shift) % n];
    if (ok) return true;
  }
  return n == 0;
}

// What intersect_triangles(b, a) must give, from c = intersect_triangles(a, b):
// names and sides swapped; a non-coplanar segment reversed (d = n_a x n_b changes sign); a
// coplanar segment or polygon reversed when n_a and n_b point the same way (it follows A's
// edge, now B's; the polygon is seen from the other normal's side), kept when they are
// opposite.
Contact swapped(const Contact& c, bool normals_same_way) {
  Contact s = c;
  for (int i = 0; i < 3; ++i) {
    s.side_a[i] = c.side_b[i];
    s.side_b[i] = c.side_a[i];
  }
  for (int i = 0; i < c.count; ++i) s.p[i] = ContactPoint{c.p[i].on_b, c.p[i].on_a};
  const bool reverse = c.kind == ContactKind::kSegment
                           ? (!c.coplanar || normals_same_way)
                           : (c.kind == ContactKind::kPolygon && !normals_same_way);
  if (reverse) std::reverse(s.p, s.p + c.count);
  return s;
}

bool normals_same_way(const Vec3 a[3], const Vec3 b[3]) {
  return dot(cross(a[1] - a[0], a[2] - a[0]), cross(b[1] - b[0], b[2] - b[0])) > 0;
}

// The name of the same point after A's corners are permuted: new corner i is old corner
// perm[i].
Loc rename(Loc l, const int perm[3]) {
  if (l == F) return F;
  int inv[3];
  for (int i = 0; i < 3; ++i) inv[perm[i]] = i;
  const int k = loc_index(l);
  if (loc_is_vertex(l)) return static_cast<Loc>(inv[k]);
  const int x = inv[k], y = inv[(k + 1) % 3];
  for (int e = 0; e < 3; ++e) {
    if ((e == x && (e + 1) % 3 == y) || (e == y && (e + 1) % 3 == x))
      return static_cast<Loc>(3 + e);
  }
  return F;
}

// ---------------------------------------------------------------------------------------------
// Hand cases. A is the triangle (0,0,0) (4,0,0) (0,4,0) unless said otherwise: n_a = +z, so
// side +1 means z < 0.

const Vec3 kA[3] = {{0, 0, 0}, {4, 0, 0}, {0, 4, 0}};

struct Expected {
  ContactKind kind;
  bool coplanar;
  std::vector<ContactPoint> p;
};

void expect_contact(const Vec3 a[3], const Vec3 b[3], const Expected& e, const char* what) {
  SCOPED_TRACE(what);
  const Contact c = run(a, b);
  Contact want;
  want.kind = e.kind;
  want.coplanar = e.coplanar;
  want.count = static_cast<uint8_t>(e.p.size());
  for (size_t i = 0; i < e.p.size(); ++i) want.p[i] = e.p[i];
  EXPECT_EQ(c.kind, want.kind) << describe(c);
  EXPECT_EQ(c.coplanar, want.coplanar) << describe(c);
  ASSERT_EQ(c.count, want.count) << describe(c);
  for (int i = 0; i < c.count; ++i) {
    EXPECT_TRUE(c.p[i] == want.p[i]) << "point " << i << ": " << describe(c);
  }
  // The other order, by the swap relation.
  const Contact r = run(b, a);
  EXPECT_TRUE(same_contact(r, swapped(c, normals_same_way(a, b))))
      << "swapped: " << describe(r) << " from " << describe(c);
}

TEST(BooleanContact, VertexOnFace) {
  const Vec3 b[3] = {{1, 1, 0}, {1, 1, 2}, {2, 1, 2}};
  expect_contact(kA, b, {ContactKind::kPoint, false, {{F, V0}}}, "b0 inside A's face");
  const Contact c = run(kA, b);
  // B's plane is y = 1 with n_b = +y: a0, a1 below it, a2 above; B above A but b0.
  EXPECT_EQ(c.side_a[0], 1);
  EXPECT_EQ(c.side_a[1], 1);
  EXPECT_EQ(c.side_a[2], -1);
  EXPECT_EQ(c.side_b[0], 0);
  EXPECT_EQ(c.side_b[1], -1);
  EXPECT_EQ(c.side_b[2], -1);
}

TEST(BooleanContact, VertexOnEdgeAndOnVertex) {
  const Vec3 on_edge[3] = {{2, 0, 0}, {2, -1, 2}, {2, 1, 2}};
  expect_contact(kA, on_edge, {ContactKind::kPoint, false, {{E0, V0}}}, "b0 on A's edge 0");
  const Vec3 on_vertex[3] = {{4, 0, 0}, {5, 0, 2}, {5, 1, 2}};
  expect_contact(kA, on_vertex, {ContactKind::kPoint, false, {{V1, V0}}}, "b0 = a1");
  const Vec3 shared[3] = {{0, 0, 0}, {-2, 0, 3}, {0, -2, 3}};
  expect_contact(kA, shared, {ContactKind::kPoint, false, {{V0, V0}}}, "shared vertex");
}

TEST(BooleanContact, EdgeInThePlane) {
  // B's edge 0 lies in A's plane along y = 1 and crosses A from its edge 2 (x = 0) to its
  // edge 1 (x = 3); d = n_a x n_b = +x.
  const Vec3 crossing[3] = {{-1, 1, 0}, {5, 1, 0}, {2, 1, 3}};
  expect_contact(kA, crossing, {ContactKind::kSegment, false, {{E2, E0}, {E1, E0}}},
                 "edge in plane crossing");
  // The same edge only touching A's corner a2.
  const Vec3 touching[3] = {{-2, 4, 0}, {2, 4, 0}, {0, 4, 3}};
  expect_contact(kA, touching, {ContactKind::kPoint, false, {{V2, E0}}}, "edge touching a2");
  // B's edge 0 in A's plane ending inside A: between b0 (inside A) and A's edge 1. B hangs
  // below A, n_b = +y, so d = n_a x n_b = -x: from (3,1,0) to b0.
  const Vec3 ending[3] = {{1, 1, 0}, {5, 1, 0}, {2, 1, -3}};
  expect_contact(kA, ending, {ContactKind::kSegment, false, {{E1, E0}, {F, V0}}},
                 "edge in plane ending inside");
}

TEST(BooleanContact, EdgesCrossingExactly) {
  // B's edge 0 crosses A's edge 0 at (1, 0, 0); B meets A's plane in [(1,-1,0), (1,0,0)].
  const Vec3 b[3] = {{1, -1, 1}, {1, 1, -1}, {1, -3, 1}};
  expect_contact(kA, b, {ContactKind::kPoint, false, {{E0, E0}}}, "edges crossing");
  // Crossing and going on through the face: B's plane is x = 1 with n_b = +x, so
  // d = n_a x n_b = +y: from (1,0,0) = (E0,E0) to (1,2,0), where B's edge 1 passes A's face.
  const Vec3 through[3] = {{1, -1, 1}, {1, 1, -1}, {1, 3, 1}};
  expect_contact(kA, through, {ContactKind::kSegment, false, {{E0, E0}, {F, E1}}},
                 "edges crossing, then through the face");
}

TEST(BooleanContact, SharedEdges) {
  // Hinge: B's edge 0 is A's edge 0 reversed, B rising from it; d = -x.
  const Vec3 hinge[3] = {{4, 0, 0}, {0, 0, 0}, {2, -1, 3}};
  expect_contact(kA, hinge, {ContactKind::kSegment, false, {{V1, V0}, {V0, V1}}}, "hinge");
  // Coplanar, B on the other side of the shared edge: a segment along A's edge 0.
  const Vec3 flat[3] = {{4, 0, 0}, {0, 0, 0}, {2, -3, 0}};
  expect_contact(kA, flat, {ContactKind::kSegment, true, {{V0, V1}, {V1, V0}}}, "flat");
  // Coplanar, B overlapping part of A's edge 0 from below: (2,0)-(4,0), b0 on A's edge.
  const Vec3 partial[3] = {{2, 0, 0}, {6, 0, 0}, {4, -2, 0}};
  expect_contact(kA, partial, {ContactKind::kSegment, true, {{E0, V0}, {V1, E0}}}, "partial");
}

TEST(BooleanContact, CoplanarPolygons) {
  expect_contact(kA, kA, {ContactKind::kPolygon, true, {{V0, V0}, {V1, V1}, {V2, V2}}},
                 "identical");
  const Vec3 reversed[3] = {kA[0], kA[2], kA[1]};
  expect_contact(kA, reversed, {ContactKind::kPolygon, true, {{V0, V0}, {V1, V2}, {V2, V1}}},
                 "identical, opposite orientation");
  const Vec3 inside[3] = {{1, 1, 0}, {2, 1, 0}, {1, 2, 0}};
  expect_contact(kA, inside, {ContactKind::kPolygon, true, {{F, V0}, {F, V1}, {F, V2}}},
                 "B inside A");
  const Vec3 inside_cw[3] = {{1, 1, 0}, {1, 2, 0}, {2, 1, 0}};
  expect_contact(kA, inside_cw, {ContactKind::kPolygon, true, {{F, V0}, {F, V2}, {F, V1}}},
                 "B inside A, opposite orientation");
  // Star of David: six proper edge crossings.
  const Vec3 a[3] = {{-4, -2, 0}, {4, -2, 0}, {0, 4, 0}};
  const Vec3 b[3] = {{-4, 2, 0}, {0, -4, 0}, {4, 2, 0}};
  expect_contact(
      a, b,
      {ContactKind::kPolygon, true, {{E0, E0}, {E0, E1}, {E1, E1}, {E1, E2}, {E2, E2}, {E2, E0}}},
      "hexagon");
  // A quadrilateral: B's corner b0 inside A, A's corner a1 inside B... (1,1) (5,1) (1,5):
  // a1 = (4,0) is outside; B cut by A's edge 1: corners b0, (3,1) = (E1,E0), (1,3) = (E1,E2).
  const Vec3 cut[3] = {{1, 1, 0}, {5, 1, 0}, {1, 5, 0}};
  expect_contact(kA, cut, {ContactKind::kPolygon, true, {{F, V0}, {E1, E0}, {E1, E2}}},
                 "corner cut off");
}

TEST(BooleanContact, TouchingAtOnePoint) {
  const Vec3 coplanar_corner[3] = {{4, 0, 0}, {6, 0, 0}, {5, -2, 0}};
  expect_contact(kA, coplanar_corner, {ContactKind::kPoint, true, {{V1, V0}}},
                 "coplanar, corners touching");
  const Vec3 coplanar_edge[3] = {{2, 2, 0}, {4, 4, 0}, {2, 5, 0}};  // b0 on A's edge 1
  expect_contact(kA, coplanar_edge, {ContactKind::kPoint, true, {{E1, V0}}},
                 "coplanar, corner on edge");
  const Vec3 apart[3] = {{5, 0, 0}, {7, 0, 0}, {6, -2, 0}};
  expect_contact(kA, apart, {ContactKind::kNone, true, {}}, "coplanar, apart");
}

TEST(BooleanContact, PlanesMeetingAtACorner) {
  // B's plane x = 4 meets A only at its corner a1.
  const Vec3 holds[3] = {{4, -1, -1}, {4, 2, -1}, {4, -1, 2}};
  expect_contact(kA, holds, {ContactKind::kPoint, false, {{V1, F}}}, "a1 inside B");
  const Vec3 misses[3] = {{4, 1, -1}, {4, 3, -1}, {4, 1, 1}};
  expect_contact(kA, misses, {ContactKind::kNone, false, {}}, "a1 beside B");
  const Vec3 edge[3] = {{4, 0, -1}, {4, 3, -1}, {4, 0, 2}};  // a1 on B's edge 2
  expect_contact(kA, edge, {ContactKind::kPoint, false, {{V1, E2}}}, "a1 on B's edge");
}

TEST(BooleanContact, GeneralPositionSegment) {
  // B pierces A: crossings of B's edges 0 and 2 with A's plane, both inside A.
  const Vec3 b[3] = {{1, 1, -2}, {2, 1, 2}, {1, 2, 2}};
  expect_contact(kA, b, {ContactKind::kSegment, false, {{F, E2}, {F, E0}}}, "piercing");
  const Vec3 far[3] = {{1, 1, 1}, {2, 1, 2}, {1, 2, 2}};
  expect_contact(kA, far, {ContactKind::kNone, false, {}}, "above");
}

TEST(BooleanContact, DegenerateTriangleIsRefused) {
  const Vec3 line[3] = {{0, 0, 0}, {1, 1, 1}, {2, 2, 2}};
  Contact c;
  c.kind = ContactKind::kPoint;
  EXPECT_FALSE(intersect_triangles(kA, line, &c));
  EXPECT_EQ(c.kind, ContactKind::kNone);
  EXPECT_FALSE(intersect_triangles(line, kA, &c));
}

TEST(BooleanContact, PositionsOfHandCases) {
  // Vertices are copies; (E2,E0) of the in-plane edge is (0,1,0); (F,E2) of the piercing
  // triangle is (1, 1.5, 0) exactly.
  const Vec3 crossing[3] = {{-1, 1, 0}, {5, 1, 0}, {2, 1, 3}};
  const Vec3 p = contact_point_position(kA, crossing, ContactPoint{E2, E0});
  EXPECT_EQ(p, (Vec3{0, 1, 0}));
  const Vec3 q = contact_point_position(kA, crossing, ContactPoint{E1, E0});
  EXPECT_EQ(q, (Vec3{3, 1, 0}));
  const Vec3 b[3] = {{1, 1, -2}, {2, 1, 2}, {1, 2, 2}};
  EXPECT_EQ(contact_point_position(kA, b, ContactPoint{F, E2}), (Vec3{1, 1.5, 0}));
  EXPECT_EQ(contact_point_position(kA, b, ContactPoint{F, E0}), (Vec3{1.5, 1, 0}));
  const Vec3 on_vertex[3] = {{4, 0, 0}, {5, 0, 2}, {5, 1, 2}};
  EXPECT_EQ(contact_point_position(kA, on_vertex, ContactPoint{V1, V0}), kA[1]);
  EXPECT_EQ(contact_point_position(kA, on_vertex, ContactPoint{F, V1}), on_vertex[1]);
}

// ---------------------------------------------------------------------------------------------
// A triangle with non-collinear corners (the generators below draw until they get one).
bool proper(const Vec3 t[3]) { return !collinear3d(t[0], t[1], t[2]); }

// The exact rational oracle (small integer coordinates: everything fits in __int128).

#ifdef __SIZEOF_INT128__
__extension__ typedef __int128 I128;

I128 abs128(I128 v) { return v < 0 ? -v : v; }
I128 gcd128(I128 a, I128 b) {
  a = abs128(a);
  b = abs128(b);
  while (b != 0) {
    const I128 t = a % b;
    a = b;
    b = t;
  }
  return a;
}

struct IV {
  I128 x = 0, y = 0, z = 0;
  I128 operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
};
IV operator-(const IV& a, const IV& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
IV operator+(const IV& a, const IV& b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
IV operator*(const IV& a, I128 s) { return {a.x * s, a.y * s, a.z * s}; }
I128 idot(const IV& a, const IV& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
IV icross(const IV& a, const IV& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
bool is_zero(const IV& a) { return a.x == 0 && a.y == 0 && a.z == 0; }

// A rational point num / den, den > 0, reduced.
struct QP {
  IV num;
  I128 den = 1;
};
QP reduce(IV num, I128 den) {
  if (den < 0) {
    num = num * -1;
    den = -den;
  }
  const I128 g = gcd128(gcd128(gcd128(num.x, num.y), num.z), den);
  if (g > 1) {
    num = {num.x / g, num.y / g, num.z / g};
    den /= g;
  }
  return {num, den};
}
bool operator==(const QP& a, const QP& b) {
  return a.num.x == b.num.x && a.num.y == b.num.y && a.num.z == b.num.z && a.den == b.den;
}

IV to_iv(const Vec3& v) {
  return {static_cast<I128>(v.x), static_cast<I128>(v.y), static_cast<I128>(v.z)};
}

struct ExactPair {
  IV a[3], b[3];
};

QP edge_plane(const IV& u, const IV& v, const IV t[3], bool* ok) {
  const IV n = icross(t[1] - t[0], t[2] - t[0]);
  const I128 du = idot(n, u - t[0]), dv = idot(n, v - t[0]);
  *ok = du != dv && ((du > 0 && dv < 0) || (du < 0 && dv > 0));
  if (du == dv) return {};
  return reduce(u * -dv + v * du, du - dv);
}

QP edge_edge(const IV& u, const IV& v, const IV& r, const IV& w, bool* ok) {
  const IV e = v - u, f = w - r;
  const IV n = icross(e, f);
  *ok = !is_zero(n) && idot(n, r - u) == 0;
  if (is_zero(n)) return {};
  const I128 snum = idot(icross(r - u, f), n), sden = idot(n, n);
  return reduce(u * sden + e * snum, sden);
}

// The exact point a contact point names (ok false when the name does not define a point).
QP exact_point(const ExactPair& x, const ContactPoint& p, bool* ok) {
  *ok = true;
  if (loc_is_vertex(p.on_a)) return {x.a[loc_index(p.on_a)], 1};
  if (loc_is_vertex(p.on_b)) return {x.b[loc_index(p.on_b)], 1};
  const int i = loc_index(p.on_a), j = loc_index(p.on_b);
  if (loc_is_edge(p.on_a) && p.on_b == F) return edge_plane(x.a[i], x.a[(i + 1) % 3], x.b, ok);
  if (p.on_a == F && loc_is_edge(p.on_b)) return edge_plane(x.b[j], x.b[(j + 1) % 3], x.a, ok);
  if (loc_is_edge(p.on_a) && loc_is_edge(p.on_b)) {
    return edge_edge(x.a[i], x.a[(i + 1) % 3], x.b[j], x.b[(j + 1) % 3], ok);
  }
  *ok = false;
  return {};
}

constexpr int kOff = 8;      // not in the triangle's plane
constexpr int kOutside = 7;  // in the plane, outside the closed triangle

// Where the rational point q lies on triangle t, by exact barycentric coordinates.
int exact_loc(const IV t[3], const QP& q) {
  const IV n = icross(t[1] - t[0], t[2] - t[0]);
  if (idot(n, q.num - t[0] * q.den) != 0) return kOff;
  I128 lambda[3];
  for (int i = 0; i < 3; ++i) {
    const IV p1 = t[(i + 1) % 3] * q.den - q.num, p2 = t[(i + 2) % 3] * q.den - q.num;
    lambda[i] = idot(n, icross(p1, p2));
  }
  if (lambda[0] < 0 || lambda[1] < 0 || lambda[2] < 0) return kOutside;
  int zeros = 0, nonzero = -1, zero = -1;
  for (int i = 0; i < 3; ++i) {
    if (lambda[i] == 0) {
      ++zeros;
      zero = i;
    } else {
      nonzero = i;
    }
  }
  if (zeros == 0) return static_cast<int>(F);
  if (zeros == 1) return 3 + (zero + 1) % 3;  // lambda_i = 0: on the edge opposite corner i
  return nonzero;                             // two zeros: at the remaining corner
}

// A n plane(other) as points (corners on it, edge crossings).
std::vector<QP> plane_cut(const IV t[3], const IV o[3]) {
  const IV n = icross(o[1] - o[0], o[2] - o[0]);
  I128 s[3];
  for (int i = 0; i < 3; ++i) s[i] = idot(n, t[i] - o[0]);
  std::vector<QP> pts;
  for (int i = 0; i < 3; ++i) {
    if (s[i] == 0) pts.push_back({t[i], 1});
    const int j = (i + 1) % 3;
    if ((s[i] > 0 && s[j] < 0) || (s[i] < 0 && s[j] > 0)) {
      pts.push_back(reduce(t[i] * -s[j] + t[j] * s[i], s[i] - s[j]));
    }
  }
  return pts;
}

// -1, 0, 1: the order of p and q along direction d.
int compare_along(const IV& d, const QP& p, const QP& q) {
  const I128 l = idot(d, p.num) * q.den, r = idot(d, q.num) * p.den;
  return (l > r) - (l < r);
}

// 2-D rational points for the coplanar oracle.
struct Q2 {
  I128 x = 0, y = 0, den = 1;
};
Q2 reduce2(I128 x, I128 y, I128 den) {
  if (den < 0) {
    x = -x;
    y = -y;
    den = -den;
  }
  const I128 g = gcd128(gcd128(x, y), den);
  if (g > 1) {
    x /= g;
    y /= g;
    den /= g;
  }
  return {x, y, den};
}
bool operator==(const Q2& a, const Q2& b) { return a.x == b.x && a.y == b.y && a.den == b.den; }
int orient_q(const Q2& p, const Q2& q, const Q2& r) {
  const I128 ux = q.x * p.den - p.x * q.den, uy = q.y * p.den - p.y * q.den;  // / (pd qd)
  const I128 vx = r.x * p.den - p.x * r.den, vy = r.y * p.den - p.y * r.den;  // / (pd rd)
  const I128 det = ux * vy - uy * vx;
  return (det > 0) - (det < 0);
}
// Side value of q against the line p0 p1 (integers), times q.den.
I128 side_value(const Q2& p0, const Q2& p1, const Q2& q) {
  return (p1.x - p0.x) * (q.y - p0.y * q.den) - (p1.y - p0.y) * (q.x - p0.x * q.den);
}

struct Oracle {
  // Counts of what the random pairs produced, by kind.
  std::map<std::string, long> counts;
  long checked = 0;
};

// Checks intersect_triangles(a, b) on integer corners against the exact oracle. Returns false
// (after reporting through gtest) on the first disagreement.
bool check_pair(const Vec3 a[3], const Vec3 b[3], Oracle* oracle) {
  ExactPair x;
  for (int i = 0; i < 3; ++i) {
    x.a[i] = to_iv(a[i]);
    x.b[i] = to_iv(b[i]);
  }
  Contact c;
  if (!intersect_triangles(a, b, &c)) {
    ADD_FAILURE() << "refused a proper pair";
    return false;
  }
  const std::string what = describe(c);
  const IV na = icross(x.a[1] - x.a[0], x.a[2] - x.a[0]);
  const IV nb = icross(x.b[1] - x.b[0], x.b[2] - x.b[0]);
  // Sides.
  for (int i = 0; i < 3; ++i) {
    const I128 sa = -idot(nb, x.a[i] - x.b[0]), sb = -idot(na, x.b[i] - x.a[0]);
    const int want_a = c.coplanar ? 0 : static_cast<int>((sa > 0) - (sa < 0));
    const int want_b = c.coplanar ? 0 : static_cast<int>((sb > 0) - (sb < 0));
    if (c.side_a[i] != want_a || c.side_b[i] != want_b) {
      ADD_FAILURE() << "sides wrong: " << what;
      return false;
    }
  }
  const bool coplanar = is_zero(icross(na, nb)) && idot(na, x.b[0] - x.a[0]) == 0;
  if (coplanar != c.coplanar) {
    ADD_FAILURE() << "coplanar flag wrong: " << what;
    return false;
  }
  // (c) kNone exactly when the triangles do not meet.
  const bool meet = triangles_intersect(a[0], a[1], a[2], b[0], b[1], b[2]);
  if (meet != (c.kind != ContactKind::kNone)) {
    ADD_FAILURE() << "triangles_intersect says " << meet << ": " << what;
    return false;
  }
  // (a) every point is in both closed triangles, at the place its name claims.
  std::vector<QP> pts;
  for (int i = 0; i < c.count; ++i) {
    bool ok = false;
    const QP q = exact_point(x, c.p[i], &ok);
    if (!ok) {
      ADD_FAILURE() << "point " << i << " is not defined by its name: " << what;
      return false;
    }
    if (exact_loc(x.a, q) != static_cast<int>(c.p[i].on_a) ||
        exact_loc(x.b, q) != static_cast<int>(c.p[i].on_b)) {
      ADD_FAILURE() << "point " << i << " lies at (" << exact_loc(x.a, q) << ","
                    << exact_loc(x.b, q) << "): " << what;
      return false;
    }
    for (const QP& r : pts) {
      if (r == q) {
        ADD_FAILURE() << "repeated point: " << what;
        return false;
      }
    }
    pts.push_back(q);
  }
  // (b) the reported set is the true intersection.
  if (!coplanar) {
    const IV d = icross(na, nb);
    std::vector<QP> ca = plane_cut(x.a, x.b), cb = plane_cut(x.b, x.a);
    std::vector<QP> want;
    if (!ca.empty() && !cb.empty()) {
      auto lo = [&](const std::vector<QP>& v) {
        QP m = v[0];
        for (const QP& q : v)
          if (compare_along(d, q, m) < 0) m = q;
        return m;
      };
      auto hi = [&](const std::vector<QP>& v) {
        QP m = v[0];
        for (const QP& q : v)
          if (compare_along(d, q, m) > 0) m = q;
        return m;
      };
      QP s = lo(ca), e = hi(ca);
      const QP sb2 = lo(cb), eb2 = hi(cb);
      if (compare_along(d, sb2, s) > 0) s = sb2;
      if (compare_along(d, eb2, e) < 0) e = eb2;
      const int order = compare_along(d, s, e);
      if (order == 0) want = {s};
      if (order < 0) want = {s, e};
    }
    bool same = want.size() == pts.size();
    for (size_t i = 0; same && i < want.size(); ++i) same = want[i] == pts[i];
    const ContactKind kind = want.empty()
                                 ? ContactKind::kNone
                                 : (want.size() == 1 ? ContactKind::kPoint : ContactKind::kSegment);
    if (!same || kind != c.kind) {
      ADD_FAILURE() << "oracle wants " << want.size() << " points in order along d: " << what;
      return false;
    }
  } else {
    // Project along an axis that keeps A proper; clip A by B's three closed half-planes.
    int w = 0;
    auto proj = [&](const IV& v, int axis) { return Q2{v[(axis + 1) % 3], v[(axis + 2) % 3], 1}; };
    while (w < 3 && orient_q(proj(x.a[0], w), proj(x.a[1], w), proj(x.a[2], w)) == 0) ++w;
    const Q2 pb[3] = {proj(x.b[0], w), proj(x.b[1], w), proj(x.b[2], w)};
    const int sigma_b = orient_q(pb[0], pb[1], pb[2]);
    std::vector<Q2> poly = {proj(x.a[0], w), proj(x.a[1], w), proj(x.a[2], w)};
    const int sigma_a = orient_q(poly[0], poly[1], poly[2]);
    for (int m = 0; m < 3 && !poly.empty(); ++m) {
      std::vector<Q2> outp;
      for (size_t i = 0; i < poly.size(); ++i) {
        const Q2& p = poly[i];
        const Q2& q = poly[(i + 1) % poly.size()];
        const I128 vp = side_value(pb[m], pb[(m + 1) % 3], p) * sigma_b;
        const I128 vq = side_value(pb[m], pb[(m + 1) % 3], q) * sigma_b;
        if (vp >= 0) outp.push_back(p);
        if ((vp > 0 && vq < 0) || (vp < 0 && vq > 0)) {
          // (vp/pd * q - vq/qd * p) / (vp/pd - vq/qd)
          outp.push_back(
              reduce2(vp * q.x - vq * p.x, vp * q.y - vq * p.y, vp * q.den - vq * p.den));
        }
      }
      poly = outp;
    }
    std::vector<Q2> distinct;
    for (const Q2& p : poly) {
      if (std::find(distinct.begin(), distinct.end(), p) == distinct.end()) distinct.push_back(p);
    }
    bool all_collinear = true;
    for (size_t i = 2; i < distinct.size(); ++i) {
      if (orient_q(distinct[0], distinct[1], distinct[i]) != 0) all_collinear = false;
    }
    std::vector<Q2> got;
    for (const QP& q : pts) {
      got.push_back(reduce2(q.num[(w + 1) % 3], q.num[(w + 2) % 3], q.den));
    }
    if (all_collinear) {
      // A point or a segment: its two extreme points.
      std::vector<Q2> want;
      if (!distinct.empty()) {
        auto less = [](const Q2& p, const Q2& q) {
          const I128 px = p.x * q.den, qx = q.x * p.den;
          if (px != qx) return px < qx;
          return p.y * q.den < q.y * p.den;
        };
        want.push_back(*std::min_element(distinct.begin(), distinct.end(), less));
        const Q2 mx = *std::max_element(distinct.begin(), distinct.end(), less);
        if (!(mx == want[0])) want.push_back(mx);
      }
      bool same = want.size() == got.size();
      if (same && want.size() == 2) {
        same = (want[0] == got[0] && want[1] == got[1]) || (want[0] == got[1] && want[1] == got[0]);
      } else if (same && want.size() == 1) {
        same = want[0] == got[0];
      }
      if (!same || c.kind != (want.empty() ? ContactKind::kNone
                                           : (want.size() == 1 ? ContactKind::kPoint
                                                               : ContactKind::kSegment))) {
        ADD_FAILURE() << "coplanar oracle wants " << want.size() << " points: " << what;
        return false;
      }
      if (want.size() == 2) {
        // Directed as A's edge that holds it.
        bool along = false;
        for (int k = 0; k < 3; ++k) {
          const IV e = x.a[(k + 1) % 3] - x.a[k];
          const IV seg = pts[1].num * pts[0].den - pts[0].num * pts[1].den;
          if (is_zero(icross(e, seg)) && idot(e, seg) > 0 && exact_loc(x.a, pts[0]) != kOutside) {
            const int l0 = exact_loc(x.a, pts[0]), l1 = exact_loc(x.a, pts[1]);
            auto on_edge = [&](int l) { return l == k || l == (k + 1) % 3 || l == 3 + k; };
            along = along || (on_edge(l0) && on_edge(l1));
          }
        }
        if (!along) {
          ADD_FAILURE() << "coplanar segment not directed along A's edge: " << what;
          return false;
        }
      }
    } else {
      // Remove collinear-redundant corners (the clipped polygon is convex), then compare
      // cycles: both run as A does in the projection.
      std::vector<Q2> cyc;
      for (size_t i = 0; i < poly.size(); ++i) {
        if (!(poly[i] == poly[(i + 1) % poly.size()])) cyc.push_back(poly[i]);
      }
      bool changed = true;
      while (changed && cyc.size() > 3) {
        changed = false;
        for (size_t i = 0; i < cyc.size(); ++i) {
          const Q2& p = cyc[(i + cyc.size() - 1) % cyc.size()];
          const Q2& q = cyc[(i + 1) % cyc.size()];
          if (orient_q(p, cyc[i], q) == 0) {
            cyc.erase(cyc.begin() + static_cast<long>(i));
            changed = true;
            break;
          }
        }
      }
      bool same = c.kind == ContactKind::kPolygon && cyc.size() == got.size();
      if (same) {
        size_t shift = 0;
        while (shift < cyc.size() && !(cyc[shift] == got[0])) ++shift;
        same = shift < cyc.size();
        for (size_t i = 0; same && i < got.size(); ++i)
          same = cyc[(shift + i) % cyc.size()] == got[i];
      }
      if (!same || orient_q(got[0], got[1], got[2]) != sigma_a) {
        ADD_FAILURE() << "coplanar oracle wants a polygon of " << cyc.size() << ": " << what;
        return false;
      }
    }
  }
  // Counts by kind and by point name.
  static const char* const kinds[] = {"none", "point", "segment", "polygon"};
  std::string kind = std::string(c.coplanar ? "coplanar " : "") + kinds[static_cast<int>(c.kind)];
  if (c.kind == ContactKind::kPolygon) kind += std::to_string(c.count);
  ++oracle->counts[kind];
  for (int i = 0; i < c.count; ++i) {
    auto cls = [](Loc l) { return loc_is_vertex(l) ? "V" : (loc_is_edge(l) ? "E" : "F"); };
    ++oracle->counts[std::string("point ") + cls(c.p[i].on_a) + "-" + cls(c.p[i].on_b) +
                     (c.coplanar ? " coplanar" : "")];
  }
  if (!c.coplanar) {
    for (const int8_t* s : {c.side_a, c.side_b}) {
      const int zeros = (s[0] == 0) + (s[1] == 0) + (s[2] == 0);
      if (zeros == 2 && c.kind != ContactKind::kNone) {
        ++oracle->counts["edge in the other plane, meeting"];
      }
      // The planes' line touches this triangle at a corner only.
      if (zeros == 1 && s[0] + s[1] + s[2] != 0) {
        ++oracle->counts[c.kind == ContactKind::kNone ? "plane line at a corner only, apart"
                                                      : "plane line at a corner only, meeting"];
      }
    }
  }
  if (c.kind == ContactKind::kPolygon) {
    bool a_in_b = true, b_in_a = true;
    for (int i = 0; i < c.count; ++i) {
      a_in_b = a_in_b && loc_is_vertex(c.p[i].on_a);
      b_in_a = b_in_a && loc_is_vertex(c.p[i].on_b);
    }
    if (a_in_b != b_in_a) ++oracle->counts["coplanar, one inside the other"];
  }
  int shared = 0;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) shared += a[i] == b[j];
  }
  if (shared == 1) ++oracle->counts["shared vertex"];
  if (shared == 2) ++oracle->counts["shared edge"];
  if (shared == 3) ++oracle->counts["same corners"];
  ++oracle->checked;
  return true;
}

// A random pair on the grid, in one of several modes that make degenerate contacts frequent.
void random_pair(std::mt19937_64& rng, Vec3 a[3], Vec3 b[3]) {
  auto coord = [&](int lo, int hi) {
    const uint64_t r = rng();
    return static_cast<double>(lo + static_cast<int>(r % static_cast<uint64_t>(hi - lo + 1)));
  };
  auto point = [&](int lo, int hi) {
    const double px = coord(lo, hi);
    const double py = coord(lo, hi);
    const double pz = coord(lo, hi);
    return Vec3{px, py, pz};
  };
  const int mode = static_cast<int>(rng() % 7);
  do {
    for (int i = 0; i < 3; ++i) a[i] = point(mode == 1 ? -4 : -2, mode == 1 ? 4 : 2);
    if (mode == 5 || mode == 6) {
      for (int i = 0; i < 3; ++i) a[i].z = 0;
    }
  } while (!proper(a));
  // Grid points on A's plane, for the coplanar mode.
  std::vector<Vec3> in_plane;
  if (mode == 4) {
    for (int gx = -3; gx <= 3; ++gx) {
      for (int gy = -3; gy <= 3; ++gy) {
        for (int gz = -3; gz <= 3; ++gz) {
          const Vec3 g{static_cast<double>(gx), static_cast<double>(gy), static_cast<double>(gz)};
          if (orient3d(a[0], a[1], a[2], g) == 0) in_plane.push_back(g);
        }
      }
    }
  }
  do {
    for (int j = 0; j < 3; ++j) {
      switch (mode) {
        case 0:
        case 1: b[j] = point(mode == 1 ? -4 : -2, mode == 1 ? 4 : 2); break;
        case 2:  // one corner of A (at a random place), the others random
        case 3:  // two corners of A
          b[j] = point(-2, 2);
          break;
        case 4: {
          const uint64_t r = rng();
          b[j] = in_plane[r % in_plane.size()];
          break;
        }
        case 5:  // coplanar, axis-aligned plane
          b[j] = point(-3, 3);
          b[j].z = 0;
          break;
        default:  // corners near A's plane z = 0
          b[j] = point(-3, 3);
          b[j].z = coord(-1, 1);
          break;
      }
    }
    if (mode == 2 || mode == 3) {
      const uint64_t r = rng();
      const int ia = static_cast<int>(r % 3), jb = static_cast<int>((r / 3) % 3);
      b[jb] = a[ia];
      if (mode == 3) b[(jb + 1) % 3] = a[(ia + 1 + (r / 9) % 2) % 3];
    }
  } while (!proper(b));
}

TEST(BooleanContact, ExactOracleOnTheGrid) {
  std::mt19937_64 rng(20261122);
  Oracle oracle;
  const int kPairs = 60000;
  int failures = 0;
  for (int n = 0; n < kPairs && failures < 5; ++n) {
    Vec3 a[3], b[3];
    random_pair(rng, a, b);
    if (!check_pair(a, b, &oracle) || !check_pair(b, a, &oracle)) {
      ++failures;
      ADD_FAILURE() << "pair " << n << ": A (" << a[0].x << "," << a[0].y << "," << a[0].z << ") ("
                    << a[1].x << "," << a[1].y << "," << a[1].z << ") (" << a[2].x << "," << a[2].y
                    << "," << a[2].z << ")  B (" << b[0].x << "," << b[0].y << "," << b[0].z
                    << ") (" << b[1].x << "," << b[1].y << "," << b[1].z << ") (" << b[2].x << ","
                    << b[2].y << "," << b[2].z << ")";
    }
  }
  std::printf("[ contact  ] %ld oracle checks (pairs in both orders)\n", oracle.checked);
  for (const auto& kv : oracle.counts) {
    std::printf("[ contact  ] %-40s %ld\n", kv.first.c_str(), kv.second);
  }
  const char* const must[] = {"none",
                              "point",
                              "segment",
                              "coplanar none",
                              "coplanar point",
                              "coplanar segment",
                              "coplanar polygon3",
                              "coplanar polygon4",
                              "coplanar polygon5",
                              "coplanar polygon6",
                              "point V-V",
                              "point V-E",
                              "point E-V",
                              "point V-F",
                              "point F-V",
                              "point E-E",
                              "point E-F",
                              "point F-E",
                              "point V-V coplanar",
                              "point V-E coplanar",
                              "point E-V coplanar",
                              "point V-F coplanar",
                              "point F-V coplanar",
                              "point E-E coplanar",
                              "edge in the other plane, meeting",
                              "plane line at a corner only, apart",
                              "plane line at a corner only, meeting",
                              "coplanar, one inside the other",
                              "shared vertex",
                              "shared edge",
                              "same corners"};
  for (const char* k : must) EXPECT_GT(oracle.counts[k], 0) << k;
}
#endif  // __SIZEOF_INT128__

// ---------------------------------------------------------------------------------------------
// Properties on the grid pairs (no oracle needed): swapping the arguments, rotating or
// reversing A's corners, and an affine map x -> o + c x (uniform scale, so every orientation
// keeps its sign) all give the corresponding answer.

void grid_pair(std::mt19937_64& rng, Vec3 a[3], Vec3 b[3]) {
  auto coord = [&]() { return static_cast<double>(static_cast<int>(rng() % 5) - 2); };
  do {
    for (int i = 0; i < 3; ++i) {
      const double px = coord(), py = coord(), pz = rng() % 2 == 0 ? 0.0 : coord();
      a[i] = Vec3{px, py, pz};
    }
  } while (!proper(a));
  do {
    for (int i = 0; i < 3; ++i) {
      const double px = coord(), py = coord(), pz = rng() % 2 == 0 ? 0.0 : coord();
      b[i] = Vec3{px, py, pz};
    }
    if (rng() % 3 == 0) {
      const uint64_t r = rng();
      b[r % 3] = a[(r / 3) % 3];
    }
  } while (!proper(b));
}

TEST(BooleanContact, SwapPermuteAndMapProperties) {
  std::mt19937_64 rng(77);
  const double c = 1.0 + 0x1p-20 + 0x1p-40;  // k c and o + k c are exact for |k| <= 4
  const Vec3 o{1000.0, -500.0, 250.0};
  const int perms[6][3] = {{0, 1, 2}, {1, 2, 0}, {2, 0, 1}, {0, 2, 1}, {2, 1, 0}, {1, 0, 2}};
  int failures = 0;
  for (int n = 0; n < 20000 && failures < 5; ++n) {
    Vec3 a[3], b[3];
    grid_pair(rng, a, b);
    const Contact x = run(a, b);
    const Contact s = run(b, a);
    if (!same_contact(s, swapped(x, normals_same_way(a, b)))) {
      ++failures;
      ADD_FAILURE() << "swap: " << describe(x) << " vs " << describe(s);
    }
    Vec3 ma[3], mb[3];
    for (int i = 0; i < 3; ++i) {
      ma[i] = o + a[i] * c;
      mb[i] = o + b[i] * c;
    }
    const Contact m = run(ma, mb);
    if (!same_contact(m, x) || (x.kind != ContactKind::kPolygon && !(m.p[0] == x.p[0]))) {
      ++failures;
      ADD_FAILURE() << "affine map: " << describe(x) << " vs " << describe(m);
    }
    const int* perm = perms[rng() % 6];
    const Vec3 pa[3] = {a[perm[0]], a[perm[1]], a[perm[2]]};
    const Contact p = run(pa, b);
    Contact want = x;
    for (int i = 0; i < 3; ++i)
      want.side_b[i] = static_cast<int8_t>(x.side_b[i] * (perm[1] == (perm[0] + 1) % 3 ? 1 : -1));
    for (int i = 0; i < 3; ++i) want.side_a[i] = x.side_a[perm[i]];
    for (int i = 0; i < x.count; ++i) want.p[i].on_a = rename(x.p[i].on_a, perm);
    const bool odd = perm[1] != (perm[0] + 1) % 3;  // reverses n_a
    // n_a reversed: a transversal segment (along n_a x n_b) reverses; a coplanar polygon is
    // then seen from the other side and reverses; a coplanar segment follows A's edge, which
    // now runs the other way.
    if (odd && (x.kind == ContactKind::kSegment || x.kind == ContactKind::kPolygon)) {
      std::reverse(want.p, want.p + x.count);
    }
    if (!same_contact(p, want)) {
      ++failures;
      ADD_FAILURE() << "corner permutation " << perm[0] << perm[1] << perm[2] << ": " << describe(x)
                    << " vs " << describe(p);
    }
    // Positions depend only on the features named: the same bits after the permutation.
    for (int i = 0; i < x.count && p.kind == x.kind; ++i) {
      const ContactPoint q{rename(x.p[i].on_a, perm), x.p[i].on_b};
      const Vec3 u = contact_point_position(ma, mb, x.p[i]);
      const Vec3 ma_p[3] = {ma[perm[0]], ma[perm[1]], ma[perm[2]]};
      const Vec3 v = contact_point_position(ma_p, mb, q);
      if (std::memcmp(&u, &v, sizeof(u)) != 0) {
        ++failures;
        ADD_FAILURE() << "position depends on corner order: " << describe(x);
      }
    }
  }
}

// ---------------------------------------------------------------------------------------------
// General position: random doubles.

TEST(BooleanContact, GeneralPositionAgreesWithTrianglesIntersect) {
  std::mt19937_64 rng(4242);
  auto unit = [&]() { return static_cast<double>(rng() >> 11) * 0x1p-53 * 2.0 - 1.0; };
  int segments = 0, none = 0;
  for (int n = 0; n < 40000; ++n) {
    Vec3 a[3], b[3];
    for (int i = 0; i < 3; ++i) {
      const double ax = unit(), ay = unit(), az = unit();
      a[i] = Vec3{ax, ay, az};
      const double bx = unit(), by = unit(), bz = unit();
      b[i] = Vec3{bx, by, bz} * 0.5;
    }
    const Contact c = run(a, b);
    const bool meet = triangles_intersect(a[0], a[1], a[2], b[0], b[1], b[2]);
    ASSERT_EQ(meet, c.kind != ContactKind::kNone) << describe(c);
    if (!meet) {
      ++none;
      continue;
    }
    // No degeneracy: a segment whose ends are an edge of one through the other's face, as
    // the Boolean's pair test names them (edge of one mesh, triangle of the other).
    ASSERT_EQ(c.kind, ContactKind::kSegment) << describe(c);
    ASSERT_FALSE(c.coplanar);
    ++segments;
    const Vec3 na = cross(a[1] - a[0], a[2] - a[0]), nb = cross(b[1] - b[0], b[2] - b[0]);
    Vec3 pos[2];
    for (int i = 0; i < 2; ++i) {
      const ContactPoint& p = c.p[i];
      ASSERT_TRUE((loc_is_edge(p.on_a) && p.on_b == F) || (p.on_a == F && loc_is_edge(p.on_b)))
          << describe(c);
      pos[i] = contact_point_position(a, b, p);
      // On both planes, to rounding.
      EXPECT_LE(std::fabs(dot(na, pos[i] - a[0])), 1e-12 * length(na)) << describe(c);
      EXPECT_LE(std::fabs(dot(nb, pos[i] - b[0])), 1e-12 * length(nb)) << describe(c);
    }
    // Directed along d = n_a x n_b (checked where the segment is not tiny).
    const Vec3 d = cross(na, nb);
    const Vec3 run_dir = pos[1] - pos[0];
    if (length(run_dir) > 1e-9 && length(d) > 1e-9) {
      EXPECT_GT(dot(run_dir, d), 0.0);
    }
  }
  std::printf("[ contact  ] general position: %d segments, %d disjoint\n", segments, none);
  EXPECT_GT(segments, 1000);
  EXPECT_GT(none, 1000);
}

// ---------------------------------------------------------------------------------------------
// Positions against the documented bound: grid pairs mapped by x -> o + c x (so the rounding
// is real), compared with the exact rational point mapped the same way.

#ifdef __SIZEOF_INT128__
bool lex_less(const Vec3& p, const Vec3& q) {
  if (p.x != q.x) return p.x < q.x;
  if (p.y != q.y) return p.y < q.y;
  return p.z < q.z;
}

long double norm_l(const Vec3& v) {
  const long double x = v.x, y = v.y, z = v.z;
  return std::sqrt(x * x + y * y + z * z);
}
long double max_abs(const Vec3& v) {
  return std::max({std::fabs(static_cast<long double>(v.x)),
                   std::fabs(static_cast<long double>(v.y)),
                   std::fabs(static_cast<long double>(v.z))});
}

// The bound documented in contact.h for the point p of (a, b).
long double documented_bound(const Vec3 a[3], const Vec3 b[3], const ContactPoint& p) {
  const long double eps = 0x1p-53L;
  if (loc_is_vertex(p.on_a) || loc_is_vertex(p.on_b)) return 0;
  const int i = loc_index(p.on_a), j = loc_index(p.on_b);
  if (p.on_a == F || p.on_b == F) {
    const bool a_edge = p.on_b == F;
    Vec3 u = a_edge ? a[i] : b[j], v = a_edge ? a[(i + 1) % 3] : b[(j + 1) % 3];
    Vec3 t[3] = {a_edge ? b[0] : a[0], a_edge ? b[1] : a[1], a_edge ? b[2] : a[2]};
    if (lex_less(v, u)) std::swap(u, v);
    std::sort(t, t + 3, lex_less);
    const Vec3 n = cross(t[1] - t[0], t[2] - t[0]);
    const long double dd = std::fabs(static_cast<long double>(dot(n, u - v)));
    return 32 * eps *
           (norm_l(t[1] - t[0]) * norm_l(t[2] - t[0]) * (norm_l(u - t[0]) + norm_l(v - t[0])) *
                norm_l(v - u) / dd +
            max_abs(u) + norm_l(v - u));
  }
  Vec3 u = a[i], v = a[(i + 1) % 3], r = b[j], w = b[(j + 1) % 3];
  if (lex_less(v, u)) std::swap(u, v);
  if (lex_less(w, r)) std::swap(r, w);
  if (lex_less(r, u) || (!lex_less(u, r) && lex_less(w, v))) {
    std::swap(u, r);
    std::swap(v, w);
  }
  const Vec3 n = cross(v - u, w - r);
  const double nx = std::fabs(n.x), ny = std::fabs(n.y), nz = std::fabs(n.z);
  const int drop = (nx >= ny && nx >= nz) ? 0 : (ny >= nz ? 1 : 2);
  auto flat = [&](const Vec3& q) {
    Vec3 f = q;
    f[drop] = 0;
    return f;
  };
  const Vec3 f = flat(w - r), gu = flat(u - r), gv = flat(v - r);
  const int k1 = (drop + 1) % 3, k2 = (drop + 2) % 3;
  const long double du =
      static_cast<long double>(f[k1]) * gu[k2] - static_cast<long double>(f[k2]) * gu[k1];
  const long double dv =
      static_cast<long double>(f[k1]) * gv[k2] - static_cast<long double>(f[k2]) * gv[k1];
  return 32 * eps *
         (norm_l(f) * (norm_l(gu) + norm_l(gv)) * norm_l(flat(v - u)) / std::fabs(du - dv) +
          max_abs(u) + norm_l(v - u));
}

TEST(BooleanContact, PositionsWithinTheDocumentedBound) {
  std::mt19937_64 rng(99);
  const double scales[2] = {1.0, 1.0 + 0x1p-20 + 0x1p-40};
  const Vec3 offsets[2] = {{0, 0, 0}, {1000.0, -500.0, 250.0}};
  long double worst_ratio = 0;
  long points = 0, exact = 0;
  for (int n = 0; n < 20000; ++n) {
    Vec3 a[3], b[3];
    random_pair(rng, a, b);
    const int v = n % 2;
    Vec3 ma[3], mb[3];
    for (int i = 0; i < 3; ++i) {
      ma[i] = offsets[v] + a[i] * scales[v];
      mb[i] = offsets[v] + b[i] * scales[v];
    }
    const Contact c = run(ma, mb);
    ExactPair x;
    for (int i = 0; i < 3; ++i) {
      x.a[i] = to_iv(a[i]);
      x.b[i] = to_iv(b[i]);
    }
    for (int i = 0; i < c.count; ++i) {
      bool ok = false;
      const QP q = exact_point(x, c.p[i], &ok);
      ASSERT_TRUE(ok) << describe(c);
      const Vec3 got = contact_point_position(ma, mb, c.p[i]);
      const long double bound = documented_bound(ma, mb, c.p[i]);
      long double err = 0;
      for (int k = 0; k < 3; ++k) {
        const long double want = static_cast<long double>(offsets[v][k]) +
                                 static_cast<long double>(scales[v]) *
                                     (static_cast<long double>(static_cast<int64_t>(q.num[k])) /
                                      static_cast<long double>(static_cast<int64_t>(q.den)));
        err = std::max(err, std::fabs(static_cast<long double>(got[k]) - want));
      }
      if (loc_is_vertex(c.p[i].on_a) || loc_is_vertex(c.p[i].on_b)) {
        const Vec3 corner =
            loc_is_vertex(c.p[i].on_a) ? ma[loc_index(c.p[i].on_a)] : mb[loc_index(c.p[i].on_b)];
        EXPECT_EQ(std::memcmp(&got, &corner, sizeof(got)), 0);
        continue;
      }
      ++points;
      // The long double reference itself is off by about 2^-64 relative.
      EXPECT_LE(err, bound + 1e-15L) << describe(c) << " point " << i;
      if (err == 0) ++exact;
      if (bound > 0) worst_ratio = std::max(worst_ratio, err / bound);
    }
  }
  std::printf("[ contact  ] %ld computed points, %ld exact, worst error / bound %.3Lg\n", points,
              exact, worst_ratio);
  EXPECT_GT(points, 1000);
}
#endif  // __SIZEOF_INT128__

}  // namespace
}  // namespace splintcore
