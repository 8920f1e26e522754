// Tests of the distance index (src/distance/bvh.cpp, src/distance/query.cpp) against oracles
// written here:
//
// - closest points: an O(n) brute force with its own point-triangle distance (projection onto
//   the plane with an exactly computed normal, and the nearest of the three edges, in double),
//   which must agree to 1e-12 relative (plus 1e-14 of the largest coordinate); and a verbatim
//   copy of the library's per-triangle routine (Ericson 5.1.5 and its sliver path) and of its
//   exact on-surface snap, run over every triangle with the documented tie rule, which must
//   give the same triangle, the same feature and the same bits (this checks that the hierarchy
//   and its pruning never change the answer). Meshes: random welded soups (with duplicates,
//   and slivers made of two corners and their float32 midpoint), boxes,
//   icospheres, tori, cones and frusta; points random, exactly on vertices, on edges (midpoints
//   of float32 corners, exact in double), exactly on faces ((a + b + 2c) / 4, checked coplanar
//   with the exact oracle), and just off them.
// - signed distance: the analytic box SDF (the box mesh IS the box), the analytic inside test
//   of spheres, tori and cones off a shell as thick as the tessellation error (measured here),
//   and agreement of the two sign methods next to every vertex and edge.
// - winding numbers: exact sum (beta = 0) against the hierarchical one (beta = 2), closed and
//   open meshes, and the real lower half-arch (tooth_17..tooth_24) with 5% of its triangles
//   removed.
// - rays (same Moller-Trumbore over all triangles), segments (an exact BigInt oracle, never the
//   library's predicates), boxes (all triangles), batches on 1..4 threads, the SDF sampler,
//   build errors, the arena exhaustion loop and the arena bound.
//
// All random streams are std::mt19937_64 with fixed seeds, doubles made from its raw bits.

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <map>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "splintcore/distance.h"
#include "splintcore/platform.h"
#include "support/exact.h"
#include "support/test_util.h"

#if defined(__clang__)
#pragma STDC FP_CONTRACT OFF
#elif defined(__GNUC__)
#pragma GCC optimize("fp-contract=off")
#endif

namespace splintcore {
namespace {

using test::TestArena;

#if defined(__OPTIMIZE__) && !defined(SPLINTCORE_TEST_SANITIZED)
constexpr int kEffort = 4;  // optimised builds run four times the cases of -O0 and sanitized ones
#else
constexpr int kEffort = 1;
#endif

// =============================================================================================
// Random numbers (raw bits only: the same on every standard library).

struct Rng {
  std::mt19937_64 engine;
  explicit Rng(uint64_t seed) : engine(seed) {}
  double uniform() { return static_cast<double>(engine() >> 11) * 0x1p-53; }  // [0, 1)
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  uint32_t below(uint32_t n) { return static_cast<uint32_t>(engine() % n); }
  Vec3 in_box(const Vec3& lo, const Vec3& hi) {
    return Vec3{uniform(lo.x, hi.x), uniform(lo.y, hi.y), uniform(lo.z, hi.z)};
  }
  Vec3 unit() {
    for (;;) {
      const Vec3 v{uniform(-1, 1), uniform(-1, 1), uniform(-1, 1)};
      const double l = length(v);
      if (l > 0.1 && l <= 1.0) return v * (1.0 / l);
    }
  }
};

// =============================================================================================
// Shapes (float32 corners, as from STL).

using Soup = std::vector<SoupTriangle>;

SoupTriangle soup_of(const Vec3& a, const Vec3& b, const Vec3& c) {
  SoupTriangle t;
  const Vec3* p[3] = {&a, &b, &c};
  for (int k = 0; k < 3; ++k) {
    for (int i = 0; i < 3; ++i) t.p[k][i] = static_cast<float>((*p[k])[i]);
  }
  return t;
}

Vec3 to_float(const Vec3& v) {
  return Vec3{static_cast<float>(v.x), static_cast<float>(v.y), static_cast<float>(v.z)};
}

Soup soup_from_indexed(const std::vector<Vec3>& v, const std::vector<std::array<uint32_t, 3>>& f) {
  Soup out;
  for (const auto& t : f) out.push_back(soup_of(v[t[0]], v[t[1]], v[t[2]]));
  return out;
}

// Icosahedron subdivided `levels` times, corners on the sphere then rounded to float.
Soup icosphere(int levels, double radius, const Vec3& center) {
  const double g = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Vec3> v = {{-1, g, 0},  {1, g, 0},  {-1, -g, 0}, {1, -g, 0}, {0, -1, g},  {0, 1, g},
                         {0, -1, -g}, {0, 1, -g}, {g, 0, -1},  {g, 0, 1},  {-g, 0, -1}, {-g, 0, 1}};
  for (Vec3& p : v) p = p * (1.0 / length(p));
  std::vector<std::array<uint32_t, 3>> f = {
      {0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
      {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
      {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (int s = 0; s < levels; ++s) {
    std::map<std::pair<uint32_t, uint32_t>, uint32_t> mids;
    auto mid = [&](uint32_t a, uint32_t b) {
      const auto key = std::make_pair(std::min(a, b), std::max(a, b));
      auto it = mids.find(key);
      if (it != mids.end()) return it->second;
      Vec3 m = (v[a] + v[b]) * 0.5;
      m = m * (1.0 / length(m));
      v.push_back(m);
      const uint32_t id = static_cast<uint32_t>(v.size() - 1);
      mids[key] = id;
      return id;
    };
    std::vector<std::array<uint32_t, 3>> next;
    for (const auto& t : f) {
      const uint32_t ab = mid(t[0], t[1]), bc = mid(t[1], t[2]), ca = mid(t[2], t[0]);
      next.push_back({t[0], ab, ca});
      next.push_back({t[1], bc, ab});
      next.push_back({t[2], ca, bc});
      next.push_back({ab, bc, ca});
    }
    f.swap(next);
  }
  for (Vec3& p : v) p = to_float(center + p * radius);
  return soup_from_indexed(v, f);
}

// Frustum (r1 > 0) or cone (r1 == 0) around z, base at z = 0 (radius r0), top at z = h.
Soup cone(uint32_t n, double r0, double r1, double h) {
  const double kTwoPi = 6.283185307179586;
  std::vector<Vec3> v;
  for (uint32_t i = 0; i < n; ++i) {
    const double a = kTwoPi * i / n;
    v.push_back(to_float(Vec3{r0 * std::cos(a), r0 * std::sin(a), 0}));
  }
  const bool apex = r1 == 0;
  if (!apex) {
    for (uint32_t i = 0; i < n; ++i) {
      const double a = kTwoPi * i / n;
      v.push_back(to_float(Vec3{r1 * std::cos(a), r1 * std::sin(a), h}));
    }
  }
  const uint32_t bottom_center = static_cast<uint32_t>(v.size());
  v.push_back(Vec3{0, 0, 0});
  const uint32_t top = static_cast<uint32_t>(v.size());
  v.push_back(to_float(Vec3{0, 0, h}));
  std::vector<std::array<uint32_t, 3>> f;
  for (uint32_t i = 0; i < n; ++i) {
    const uint32_t j = (i + 1) % n;
    f.push_back({bottom_center, j, i});
    if (apex) {
      f.push_back({i, j, top});
    } else {
      f.push_back({i, j, n + j});
      f.push_back({i, n + j, n + i});
      f.push_back({top, n + i, n + j});
    }
  }
  return soup_from_indexed(v, f);
}

Soup box_soup(const Vec3& lo, const Vec3& hi) {
  const float l[3] = {static_cast<float>(lo.x), static_cast<float>(lo.y), static_cast<float>(lo.z)};
  const float h[3] = {static_cast<float>(hi.x), static_cast<float>(hi.y), static_cast<float>(hi.z)};
  return shapes::box(l, h);
}

// Random triangles over a pool of float corners (so that welding shares vertices), with
// duplicates (same corners, later id) and exactly collinear triangles mixed in.
Soup random_soup(Rng& rng, uint32_t corners, uint32_t triangles, double extent) {
  std::vector<Vec3> pool;
  for (uint32_t i = 0; i < corners; ++i) {
    pool.push_back(
        to_float(rng.in_box(Vec3{-extent, -extent, -extent}, Vec3{extent, extent, extent})));
  }
  std::vector<std::array<uint32_t, 3>> f;
  while (f.size() < triangles) {
    const uint32_t a = rng.below(corners), b = rng.below(corners), c = rng.below(corners);
    if (a == b || b == c || a == c) continue;
    f.push_back({a, b, c});
  }
  Soup soup = soup_from_indexed(pool, f);
  // Duplicates at random later positions; collinear triangles (a, b, midpoint: exact).
  for (uint32_t k = 0; k < triangles / 16 + 1; ++k) {
    const SoupTriangle copy = soup[rng.below(static_cast<uint32_t>(soup.size()))];
    soup.insert(soup.begin() + rng.below(static_cast<uint32_t>(soup.size())), copy);
    const Vec3 a = pool[rng.below(corners)], b = pool[rng.below(corners)];
    SoupTriangle line = soup_of(a, b, a);
    for (int i = 0; i < 3; ++i) line.p[2][i] = (line.p[0][i] + line.p[1][i]) * 0.5f;
    soup.push_back(line);
  }
  return soup;
}

// =============================================================================================
// Mesh and index helpers.

struct Built {
  std::unique_ptr<TestArena> arena;
  Mesh mesh;
  DistanceIndex index;
  double scale = 1;           // largest absolute coordinate
  std::vector<Vec3> normals;  // per triangle, exact then rounded (for the oracle)
};

Vec3 exact_normal(const Vec3& a, const Vec3& b, const Vec3& c);

std::unique_ptr<Built> build(const Soup& soup, uint32_t leaf_size = 4,
                             size_t arena_bytes = size_t{64} << 20, bool oriented_boxes = false) {
  std::unique_ptr<Built> b(new Built);
  b->arena.reset(new TestArena(arena_bytes));
  Status s = test::mesh_from_soup(b->arena->arena, soup, &b->mesh);
  EXPECT_TRUE(s.is_ok()) << test::format(s);
  Context ctx(&b->arena->arena);
  DistanceIndexOptions options;
  options.leaf_size = leaf_size;
  options.oriented_boxes = oriented_boxes;
  s = build_distance_index(ctx, b->mesh, options, &b->index);
  EXPECT_TRUE(s.is_ok()) << test::format(s);
  double m = 1e-300;
  for (const Vec3& v : b->mesh.vertices) {
    m = std::max(m, std::max(std::fabs(v.x), std::max(std::fabs(v.y), std::fabs(v.z))));
  }
  b->scale = m;
  for (const Triangle& t : b->mesh.triangles) {
    b->normals.push_back(
        exact_normal(b->mesh.vertices[t.v[0]], b->mesh.vertices[t.v[1]], b->mesh.vertices[t.v[2]]));
  }
  return b;
}

const Vec3& corner(const Mesh& m, uint32_t t, int k) { return m.vertices[m.triangles[t].v[k]]; }

Aabb bounds_of(const Mesh& m) {
  Aabb b;
  for (const Vec3& v : m.vertices) b.add(v);
  return b;
}

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof(double)) == 0; }
bool same_bits(const Vec3& a, const Vec3& b) {
  return same_bits(a.x, b.x) && same_bits(a.y, b.y) && same_bits(a.z, b.z);
}

// =============================================================================================
// Oracle 1: point-triangle distance written independently: the projection onto the plane when
// it falls inside, and the nearest of the three edges, in double, with the normal computed
// exactly (BigInt) and then rounded: a normal from rounded products is tilted by about
// eps / sin(smallest angle), which on a sliver moves the plane by 1e-9 of its size.

double to_double(const splintcore_test::BigInt& x, int exponent) {
  const std::vector<uint32_t>& l = x.limbs();
  if (l.empty()) return 0;
  const size_t k = l.size() - 1;
  double v = static_cast<double>(l[k]);
  int e = 32 * static_cast<int>(k);
  for (size_t i = 1; i <= 2 && i <= k; ++i) {
    v = v * 4294967296.0 + static_cast<double>(l[k - i]);
    e -= 32;
  }
  return std::ldexp(x.sign() < 0 ? -v : v, e + exponent);
}

// (b - a) x (c - a), exact, then rounded (to an ulp or two).
Vec3 exact_normal(const Vec3& a, const Vec3& b, const Vec3& c) {
  const double values[9] = {a.x, a.y, a.z, b.x, b.y, b.z, c.x, c.y, c.z};
  int emin = 0;
  bool any = false;
  for (double x : values) {
    const splintcore_test::DyadicParts d = splintcore_test::decompose(x);
    if (d.mantissa != 0 && (!any || d.exponent < emin)) {
      emin = d.exponent;
      any = true;
    }
  }
  if (!any) return Vec3{};
  const std::vector<splintcore_test::BigInt> n = splintcore_test::to_common_scale(values, 9);
  const splintcore_test::BigInt ux = n[3] - n[0], uy = n[4] - n[1], uz = n[5] - n[2];
  const splintcore_test::BigInt vx = n[6] - n[0], vy = n[7] - n[1], vz = n[8] - n[2];
  return Vec3{to_double(uy * vz - uz * vy, 2 * emin), to_double(uz * vx - ux * vz, 2 * emin),
              to_double(ux * vy - uy * vx, 2 * emin)};
}

Vec3 closest_on_segment(const Vec3& q, const Vec3& a, const Vec3& b) {
  const Vec3 ab = b - a;
  const double l2 = dot(ab, ab);
  if (l2 == 0) return a;
  double t = dot(q - a, ab) / l2;
  t = t < 0 ? 0 : (t > 1 ? 1 : t);
  return a + ab * t;
}

double oracle_point_triangle(const Vec3& q, const Vec3& a, const Vec3& b, const Vec3& c,
                             const Vec3& n) {
  double best = length(q - closest_on_segment(q, a, b));
  best = std::min(best, length(q - closest_on_segment(q, b, c)));
  best = std::min(best, length(q - closest_on_segment(q, c, a)));
  const double n2 = dot(n, n);
  if (n2 > 0 && dot(cross(b - a, q - a), n) >= 0 && dot(cross(c - b, q - b), n) >= 0 &&
      dot(cross(a - c, q - c), n) >= 0) {
    best = std::min(best, std::fabs(dot(q - a, n)) / std::sqrt(n2));
  }
  return best;
}

double oracle_point_triangle(const Vec3& q, const Vec3& a, const Vec3& b, const Vec3& c) {
  return oracle_point_triangle(q, a, b, c, exact_normal(a, b, c));
}

double oracle_distance(const Built& b, const Vec3& q) {
  const Mesh& m = b.mesh;
  double best = HUGE_VAL;
  for (uint32_t t = 0; t < m.triangles.size(); ++t) {
    best = std::min(best, oracle_point_triangle(q, corner(m, t, 0), corner(m, t, 1),
                                                corner(m, t, 2), b.normals[t]));
  }
  return best;
}

// =============================================================================================
// Oracle 2: a verbatim copy of the library's per-triangle routine (src/distance/query.cpp
// closest_on_triangle: Ericson, "Real-Time Collision Detection", 5.1.5, and the sliver path)
// over every triangle, smallest squared distance first, then the smallest id, then the exact
// "on the surface" snap (decided here with the BigInt oracle, not the library's predicates).
// The hierarchy must give exactly this. (If the library's routine changes, change this copy.)

void ref_exact_product(double a, double b, double* hi, double* lo) {
  constexpr double kSplit = 134217729.0;
  *hi = a * b;
  double t = kSplit * a;
  const double ah = t - (t - a), al = a - ah;
  t = kSplit * b;
  const double bh = t - (t - b), bl = b - bh;
  *lo = al * bl - (((*hi - ah * bh) - al * bh) - ah * bl);
}
double ref_difference_of_products(double a, double b, double c, double d) {
  double p, pe, q, qe;
  ref_exact_product(a, b, &p, &pe);
  ref_exact_product(c, d, &q, &qe);
  const double s = p - q;
  const double bvirt = p - s;
  const double e = (p - (s + bvirt)) + (bvirt - q);
  return s + (e + (pe - qe));
}

void ref_sliver(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c, Vec3* out,
                Feature* feature, uint8_t* index) {
  const Vec3 ab = b - a, ac = c - a;
  const Vec3 n{ref_difference_of_products(ab.y, ac.z, ab.z, ac.y),
               ref_difference_of_products(ab.z, ac.x, ab.x, ac.z),
               ref_difference_of_products(ab.x, ac.y, ab.y, ac.x)};
  const double n2 = dot(n, n);
  if (n2 > 0 && dot(cross(ab, p - a), n) >= 0 && dot(cross(c - b, p - b), n) >= 0 &&
      dot(cross(a - c, p - c), n) >= 0) {
    *out = p - n * (dot(p - a, n) / n2);
    *feature = Feature::kFace;
    *index = 0;
    return;
  }
  const Vec3* v[3] = {&a, &b, &c};
  double best = 0;
  for (uint8_t k = 0; k < 3; ++k) {
    const Vec3& v0 = *v[k];
    const Vec3& v1 = *v[(k + 1) % 3];
    const Vec3 e = v1 - v0;
    const double num = dot(p - v0, e), den = dot(e, e);
    Vec3 q;
    Feature f;
    uint8_t fi;
    if (num <= 0 || den == 0) {
      q = v0;
      f = Feature::kVertex;
      fi = k;
    } else if (num >= den) {
      q = v1;
      f = Feature::kVertex;
      fi = static_cast<uint8_t>((k + 1) % 3);
    } else {
      q = v0 + e * (num / den);
      f = Feature::kEdge;
      fi = k;
    }
    const double d2 = length_squared(p - q);
    if (k == 0 || d2 < best) {
      best = d2;
      *out = q;
      *feature = f;
      *index = fi;
    }
  }
}

// Twice the area below a quarter of the longest edge squared (|ab x ac|^2 by Lagrange).
bool is_sliver(const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a;
  const double lab = dot(ab, ab), lac = dot(ac, ac), abac = dot(ab, ac);
  const double lbc = lab + lac - 2.0 * abac;
  const double longest = lab > lac ? (lab > lbc ? lab : lbc) : (lac > lbc ? lac : lbc);
  return (lab * lac - abac * abac) * 16.0 < longest * longest;
}

void ericson(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c, Vec3* out,
             Feature* feature, uint8_t* index) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) {
    *out = a;
    *feature = Feature::kVertex;
    *index = 0;
    return;
  }
  const Vec3 bp = p - b;
  const double d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) {
    *out = b;
    *feature = Feature::kVertex;
    *index = 1;
    return;
  }
  if (is_sliver(a, b, c)) {
    ref_sliver(p, a, b, c, out, feature, index);
    return;
  }
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double t = d1 / (d1 - d3);
    *out = a + ab * t;
    *feature = Feature::kEdge;
    *index = 0;
    return;
  }
  const Vec3 cp = p - c;
  const double d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) {
    *out = c;
    *feature = Feature::kVertex;
    *index = 2;
    return;
  }
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double t = d2 / (d2 - d6);
    *out = a + ac * t;
    *feature = Feature::kEdge;
    *index = 2;
    return;
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double t = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    *out = b + (c - b) * t;
    *feature = Feature::kEdge;
    *index = 1;
    return;
  }
  const double denom = 1.0 / (va + vb + vc);
  const double v = vb * denom, w = vc * denom;
  *out = a + ab * v + ac * w;
  *feature = Feature::kFace;
  *index = 0;
}

// Is q exactly on the closed triangle abc (not degenerate)? s[k]: the exact side of edge k.
bool exactly_on_triangle(const Vec3& q, const Vec3& a, const Vec3& b, const Vec3& c, int s[3]) {
  if (splintcore_test::exact_orient3d_sign(a, b, c, q) != 0) return false;
  if (splintcore_test::exact_collinear3d(a, b, c)) return false;
  for (int drop = 0; drop < 3; ++drop) {
    const int u = (drop + 1) % 3, w = (drop + 2) % 3;
    if (splintcore_test::exact_orient2d_sign(a[u], a[w], b[u], b[w], c[u], c[w]) == 0) continue;
    s[0] = splintcore_test::exact_orient2d_sign(a[u], a[w], b[u], b[w], q[u], q[w]);
    s[1] = splintcore_test::exact_orient2d_sign(b[u], b[w], c[u], c[w], q[u], q[w]);
    s[2] = splintcore_test::exact_orient2d_sign(c[u], c[w], a[u], a[w], q[u], q[w]);
    return (s[0] >= 0 && s[1] >= 0 && s[2] >= 0) || (s[0] <= 0 && s[1] <= 0 && s[2] <= 0);
  }
  return false;
}

bool reference_closest(const Mesh& m, const Vec3& q, ClosestPoint* out) {
  bool found = false;
  double best2 = HUGE_VAL;
  for (uint32_t t = 0; t < m.triangles.size(); ++t) {
    Vec3 p;
    // (ericson() sets both; g++ -O1 without UBSan, the ASan job, cannot see it.)
    Feature f = Feature::kFace;
    uint8_t fi = 0;
    ericson(q, corner(m, t, 0), corner(m, t, 1), corner(m, t, 2), &p, &f, &fi);
    const double d2 = length_squared(p - q);
    if (d2 < best2 || (!found && d2 <= best2)) {
      best2 = d2;
      found = true;
      out->point = p;
      out->triangle = t;
      out->feature = f;
      out->feature_index = fi;
    }
  }
  if (!found) return false;
  // The snap: within 2^-40 of the largest coordinate and exactly on the triangle.
  const Vec3 &a = corner(m, out->triangle, 0), &b = corner(m, out->triangle, 1),
             &c = corner(m, out->triangle, 2);
  double big = 0;
  for (const Vec3* p : {&q, &a, &b, &c}) {
    big = std::max(big, std::max(std::fabs(p->x), std::max(std::fabs(p->y), std::fabs(p->z))));
  }
  int s[3];
  if (best2 > 0 && best2 <= (big * 0x1p-40) * (big * 0x1p-40) &&
      exactly_on_triangle(q, a, b, c, s)) {
    best2 = 0;
    out->point = q;
    out->feature = Feature::kFace;
    out->feature_index = 0;
    for (uint8_t k = 0; k < 3; ++k) {
      if (s[k] == 0 && s[(k + 2) % 3] == 0) {
        out->point = corner(m, out->triangle, k);
        out->feature = Feature::kVertex;
        out->feature_index = k;
        break;
      }
      if (s[k] == 0) {
        out->feature = Feature::kEdge;
        out->feature_index = k;
      }
    }
  }
  out->distance = std::sqrt(best2);
  return true;
}

// Checks closest_point(q) against both oracles and its own promises. Returns the number of
// failures (so callers can stop early).
int check_closest(const Built& b, const Vec3& q, const char* what) {
  const Mesh& m = b.mesh;
  ClosestPoint cp;
  if (!closest_point(b.index, q, &cp)) {
    ADD_FAILURE() << what << ": no closest point";
    return 1;
  }
  int failures = 0;
  ClosestPoint ref;
  EXPECT_TRUE(reference_closest(m, q, &ref));
  if (cp.triangle != ref.triangle || !same_bits(cp.distance, ref.distance) ||
      !same_bits(cp.point, ref.point) || cp.feature != ref.feature ||
      cp.feature_index != ref.feature_index) {
    ADD_FAILURE() << what << " q=(" << q.x << ", " << q.y << ", " << q.z << "): library triangle "
                  << cp.triangle << " " << feature_name(cp.feature) << " d=" << cp.distance
                  << ", reference triangle " << ref.triangle << " " << feature_name(ref.feature)
                  << " d=" << ref.distance;
    ++failures;
  }
  // Independent distance.
  const double d = oracle_distance(b, q);
  const double qs =
      std::max(b.scale, std::max(std::fabs(q.x), std::max(std::fabs(q.y), std::fabs(q.z))));
  if (!(std::fabs(cp.distance - d) <= 1e-12 * d + 1e-14 * qs)) {
    ADD_FAILURE() << what << ": distance " << cp.distance << " vs oracle " << d;
    ++failures;
  }
  // Its own promises: the distance is |point - q|, the point is on the triangle and on the
  // feature.
  if (!same_bits(cp.distance, std::sqrt(length_squared(cp.point - q)))) {
    ADD_FAILURE() << what << ": distance is not |point - q|";
    ++failures;
  }
  const Vec3 &a = corner(m, cp.triangle, 0), &bb = corner(m, cp.triangle, 1),
             &c = corner(m, cp.triangle, 2);
  const double off = oracle_point_triangle(cp.point, a, bb, c, b.normals[cp.triangle]);
  if (!(off <= 1e-14 * qs)) {
    ADD_FAILURE() << what << ": returned point is " << off << " off its triangle";
    ++failures;
  }
  if (cp.feature_index > 2) {
    ADD_FAILURE() << what << ": feature index " << int{cp.feature_index};
    return failures + 1;
  }
  const Vec3& v0 = corner(m, cp.triangle, cp.feature_index);
  const Vec3& v1 = corner(m, cp.triangle, (cp.feature_index + 1) % 3);
  if (cp.feature == Feature::kVertex && cp.point != v0) {
    ADD_FAILURE() << what << ": vertex feature but the point is not the vertex";
    ++failures;
  }
  if (cp.feature == Feature::kEdge) {
    const double e = length(cp.point - closest_on_segment(cp.point, v0, v1));
    if (!(e <= 1e-14 * qs)) {
      ADD_FAILURE() << what << ": edge feature but the point is " << e << " off the edge";
      ++failures;
    }
  }
  return failures;
}

// Query points for a mesh: random in and around its box, exactly on vertices, on edges
// (midpoints: exact for float corners), on faces ((a + b + 2c) / 4), and just off them.
std::vector<Vec3> query_points(const Mesh& m, Rng& rng, int random_count, int feature_count) {
  std::vector<Vec3> q;
  const Aabb box = bounds_of(m);
  const Vec3 pad = box.extent() * 0.5 + Vec3{1e-3, 1e-3, 1e-3};
  for (int i = 0; i < random_count; ++i) q.push_back(rng.in_box(box.lo - pad, box.hi + pad));
  const uint32_t nt = static_cast<uint32_t>(m.triangles.size());
  for (int i = 0; i < feature_count && nt > 0; ++i) {
    const uint32_t t = rng.below(nt);
    const int k = static_cast<int>(rng.below(3));
    const Vec3 &a = corner(m, t, k), &b = corner(m, t, (k + 1) % 3), &c = corner(m, t, (k + 2) % 3);
    const Vec3 on_edge = (a + b) * 0.5;
    const Vec3 on_face = (a + b + c * 2.0) * 0.25;
    q.push_back(a);
    q.push_back(on_edge);
    q.push_back(on_face);
    const double eps = std::pow(10.0, -rng.uniform(1, 9));
    q.push_back(a + rng.unit() * eps);
    q.push_back(on_edge + rng.unit() * eps);
    q.push_back(on_face + rng.unit() * eps);
  }
  return q;
}

// =============================================================================================
// 1. Closest points against brute force.

TEST(DistanceClosest, MatchesBruteForceOnRandomAndClosedMeshes) {
  Rng rng(0x5eed0001);
  std::vector<std::pair<std::string, Soup>> shapes;
  for (int i = 0; i < 3; ++i) {
    shapes.emplace_back("random soup " + std::to_string(i),
                        random_soup(rng, 40 + 60 * static_cast<uint32_t>(i),
                                    60 + 150 * static_cast<uint32_t>(i), 5.0 * (i + 1)));
  }
  shapes.emplace_back("torus", shapes::torus(24, 12, 10, 3));
  shapes.emplace_back("icosphere", icosphere(3, 7.5, Vec3{1.25, -2.5, 30}));
  shapes.emplace_back("box", box_soup(Vec3{-1.5, -0.75, -2}, Vec3{2.25, 1.25, 0.5}));
  shapes.emplace_back("cone", cone(40, 4, 0, 9));
  shapes.emplace_back("frustum", cone(33, 4, 2.5, 6));
  // Tiny and far from the origin: coordinates much larger than the triangles.
  shapes.emplace_back("far sphere", icosphere(2, 0.3, Vec3{80, 40, 60}));
  int total = 0;
  for (const auto& shape : shapes) {
    for (uint32_t leaf : {0u, 1u, 4u, 16u}) {
      for (bool oriented : {false, true}) {
        auto b = build(shape.second, leaf, size_t{64} << 20, oriented);
        ASSERT_EQ(b->index.obbs.size(), oriented ? b->index.nodes.size() : 0u);
        const auto q = query_points(b->mesh, rng, 60 * kEffort, 20 * kEffort);
        int failures = 0;
        for (const Vec3& p : q) {
          failures += check_closest(*b, p, shape.first.c_str());
          ++total;
          if (failures > 5) break;
        }
        ASSERT_EQ(failures, 0) << shape.first << " leaf " << leaf << " oriented " << oriented;
      }
    }
  }
  EXPECT_GT(total, 4000 * kEffort / 4);
}

// Leaves of odd sizes: closest_within() takes a leaf's box gaps two triangles at a time (two
// lanes), so a leaf of 3, 5, 7 or 15 ends with a lone triangle in the first lane.
TEST(DistanceClosest, OddLeafSizesMatchBruteForce) {
  Rng rng(0x5eed0003);
  const Soup soups[2] = {shapes::torus(24, 12, 10, 3), random_soup(rng, 80, 200, 6.0)};
  int total = 0;
  for (const Soup& soup : soups) {
    for (uint32_t leaf : {3u, 5u, 7u, 15u}) {
      for (bool oriented : {false, true}) {
        auto b = build(soup, leaf, size_t{64} << 20, oriented);
        int failures = 0;
        for (const Vec3& p : query_points(b->mesh, rng, 40 * kEffort, 10 * kEffort)) {
          failures += check_closest(*b, p, "odd leaves");
          ++total;
          if (failures > 5) break;
        }
        ASSERT_EQ(failures, 0) << "leaf " << leaf << " oriented " << oriented;
      }
    }
  }
  EXPECT_GT(total, 400 * kEffort);
}

// Query points far beyond float range (the boxes are tested in float): no box may be pruned
// wrongly, with or without oriented boxes.
TEST(DistanceClosest, QueriesBeyondFloatRangeMatchBruteForce) {
  for (bool oriented : {false, true}) {
    auto b = build(shapes::torus(24, 12, 10, 3), 4, size_t{64} << 20, oriented);
    for (const Vec3& q : {Vec3{1e39, 2, 3}, Vec3{-3e38, 1e38, 7}, Vec3{1e150, -1e150, 1e149},
                          Vec3{0x1p100, 0, 0}, Vec3{0x1p99, 1, 1}}) {
      EXPECT_EQ(check_closest(*b, q, "far query"), 0) << q.x << " oriented " << oriented;
    }
  }
}

// The oriented boxes contain what they bound: every corner of every triangle below a child
// projects into the child's intervals on the node's axes (checked in long double, well inside
// the build's margins), and the axes are unit and orthogonal to float rounding. Both kinds of
// child are checked: leaves (intervals from their corners) and inner nodes (intervals from
// their own children's boxes).
TEST(DistanceClosest, OrientedBoxesContainTheirTriangles) {
  Rng rng(0x5eed0007);
  std::vector<Soup> soups = {shapes::torus(40, 20, 5, 1), icosphere(3, 7.5, Vec3{1.25, -2.5, 30}),
                             random_soup(rng, 200, 600, 4), cone(40, 4, 0, 9),
                             icosphere(2, 0.3, Vec3{80, 40, 60})};
  int oriented_nodes = 0, checked = 0;
  for (const Soup& soup : soups) {
    for (uint32_t leaf : {0u, 1u, 4u, 16u}) {
      auto b = build(soup, leaf, size_t{64} << 20, true);
      const DistanceIndex& x = b->index;
      ASSERT_EQ(x.obbs.size(), x.nodes.size());
      // The triangles below each node: the range of `order` its leaves cover.
      std::vector<uint32_t> first(x.nodes.size(), ~0u), last(x.nodes.size(), 0);
      for (size_t i = x.nodes.size(); i-- > 0;) {
        const BvhNode& n = x.nodes[i];
        for (int k = 0; k < 4; ++k) {
          if (n.child[k] == kNoChild) continue;
          const uint32_t f = n.count[k] > 0 ? n.child[k] : first[n.child[k]];
          const uint32_t l = n.count[k] > 0 ? n.child[k] + n.count[k] : last[n.child[k]];
          first[i] = std::min(first[i], f);
          last[i] = std::max(last[i], l);
        }
      }
      for (size_t i = 0; i < x.nodes.size(); ++i) {
        const BvhNode& n = x.nodes[i];
        const BvhObb& o = x.obbs[i];
        bool identity = true;
        for (int a = 0; a < 3; ++a) {
          long double len2 = 0;
          for (int j = 0; j < 3; ++j) {
            identity = identity && o.axis[a][j] == (a == j ? 1.0f : 0.0f);
            len2 += static_cast<long double>(o.axis[a][j]) * o.axis[a][j];
            long double d = 0;
            for (int c = 0; c < 3; ++c) d += static_cast<long double>(o.axis[a][c]) * o.axis[j][c];
            if (j != a) {
              EXPECT_LT(std::fabs(static_cast<double>(d)), 1e-6);
            }
          }
          EXPECT_NEAR(static_cast<double>(len2), 1.0, 1e-6);
        }
        oriented_nodes += !identity;
        for (int k = 0; k < 4; ++k) {
          if (n.child[k] == kNoChild) continue;
          const uint32_t f = n.count[k] > 0 ? n.child[k] : first[n.child[k]];
          const uint32_t l = n.count[k] > 0 ? n.child[k] + n.count[k] : last[n.child[k]];
          for (uint32_t j = f; j < l; ++j) {
            const Triangle& t = b->mesh.triangles[x.order[j]];
            for (int c = 0; c < 3; ++c) {
              const Vec3& v = b->mesh.vertices[t.v[c]];
              for (int a = 0; a < 3; ++a) {
                const long double p = static_cast<long double>(o.axis[a][0]) * v.x +
                                      static_cast<long double>(o.axis[a][1]) * v.y +
                                      static_cast<long double>(o.axis[a][2]) * v.z;
                ASSERT_GE(p, static_cast<long double>(o.lo[a][k]))
                    << "node " << i << " child " << k;
                ASSERT_LE(p, static_cast<long double>(o.hi[a][k]))
                    << "node " << i << " child " << k;
                ++checked;
              }
            }
          }
        }
      }
    }
  }
  EXPECT_GT(oriented_nodes, 100);  // the frames are used, not all left at the world axes
  EXPECT_GT(checked, 100000);
}

// Slivers found by the random soups (kept as regressions): Ericson's barycentric tests lose
// about eps / sin^2 on them, and these came out 6.8e-4 and 4e-9 mm off before the sliver path.
// The expected distances were computed in exact rational arithmetic (Python fractions).
TEST(DistanceClosest, SliverRegressions) {
  const double a[3] = {0x1.65a8fap+0, 0x1.3ede86p+1, -0x1.cc61cap-1};
  const double b[3] = {0x1.89480cp+1, 0x1.f5b8f2p+0, -0x1.1332d2p+0};
  const double c[3] = {0x1.1e0e44p+1, 0x1.1cdd8p+1, -0x1.f963b8p-1};
  Soup soup = {soup_of(Vec3{a[0], a[1], a[2]}, Vec3{b[0], b[1], b[2]}, Vec3{c[0], c[1], c[2]})};
  auto built = build(soup, 1);
  struct Case {
    Vec3 q;
    double distance;
  };
  const Case cases[] = {
      {{0x1.38dcb64p+1, 0x1.145d3ep+1, -0x1.0252194p+0}, 0.0},  // was 6.8e-4
      {{0x1.1e0e43f652223p+1, 0x1.1cdd80049ecdfp+1, -0x1.f963b7e692b03p-1}, 2.248632275757277e-09},
      {{0x1.38dcb63ce7cc5p+1, 0x1.145d3e02ead14p+1, -0x1.0252195770933p+0}, 3.459125666486023e-09},
  };
  for (const Case& k : cases) {
    ClosestPoint cp;
    ASSERT_TRUE(closest_point(built->index, k.q, &cp));
    EXPECT_NEAR(cp.distance, k.distance, 1e-12 * k.distance + 1e-15);
    EXPECT_EQ(check_closest(*built, k.q, "sliver"), 0);
  }
}

TEST(DistanceClosest, PointsExactlyOnTheSurfaceAreAtDistanceZero) {
  auto b = build(icosphere(2, 5, Vec3{3, 4, 5}));
  int exact_zero = 0, n = 0;
  for (uint32_t t = 0; t < b->mesh.triangles.size(); ++t) {
    const Vec3 &a = corner(b->mesh, t, 0), &bb = corner(b->mesh, t, 1), &c = corner(b->mesh, t, 2);
    const Vec3 face = (a + bb + c * 2.0) * 0.25;
    ASSERT_EQ(splintcore_test::exact_orient3d_sign(a, bb, c, face), 0);  // truly on the face
    for (const Vec3& q : {a, (a + bb) * 0.5, face}) {
      ClosestPoint cp;
      ASSERT_TRUE(closest_point(b->index, q, &cp));
      EXPECT_LE(cp.distance, 1e-14 * b->scale);
      exact_zero += cp.distance == 0;
      ++n;
      // Points on the surface get +0 with every method.
      for (SignMethod method :
           {SignMethod::kPseudonormal, SignMethod::kWindingNumber, SignMethod::kAuto}) {
        SignedDistance sd;
        ASSERT_TRUE(signed_distance(b->index, q, method, &sd));
        EXPECT_TRUE(sd.distance == 0 && !std::signbit(sd.distance)) << sd.distance;
      }
    }
  }
  // Exactly on the surface (decided exactly), so exactly 0, not a rounding error away.
  EXPECT_EQ(exact_zero, n);
}

TEST(DistanceClosest, TiesGoToTheSmallestTriangleId) {
  // A box centred on the origin: the centre is at distance 1 from all 12 triangles.
  for (bool reversed : {false, true}) {
    Soup soup = box_soup(Vec3{-1, -1, -1}, Vec3{1, 1, 1});
    if (reversed) std::reverse(soup.begin(), soup.end());
    for (uint32_t leaf : {1u, 2u, 4u, 16u}) {
      auto b = build(soup, leaf);
      ClosestPoint cp;
      ASSERT_TRUE(closest_point(b->index, Vec3{0, 0, 0}, &cp));
      EXPECT_EQ(cp.triangle, 0u) << "leaf " << leaf << " reversed " << reversed;
      EXPECT_EQ(cp.distance, 1.0);
      // A corner of the box: every triangle there is at distance 0; the smallest id wins.
      const Vec3 c = corner(b->mesh, 11, 0);
      ASSERT_TRUE(closest_point(b->index, c, &cp));
      uint32_t smallest = 12;
      for (uint32_t t = 0; t < 12; ++t) {
        for (int k = 0; k < 3; ++k) {
          if (corner(b->mesh, t, k) == c) smallest = std::min(smallest, t);
        }
      }
      EXPECT_EQ(cp.triangle, smallest);
      EXPECT_EQ(cp.distance, 0.0);
      EXPECT_EQ(cp.feature, Feature::kVertex);
    }
  }
  // Two parallel triangles at z = 0 and z = 2, the query at z = 1; and many far-apart copies
  // in between so the two land in different subtrees.
  for (bool swap : {false, true}) {
    Soup soup;
    const Vec3 a{0, 0, 0}, bb{4, 0, 0}, c{0, 4, 0};
    const Vec3 up{0, 0, 2};
    soup.push_back(soup_of(swap ? a + up : a, swap ? bb + up : bb, swap ? c + up : c));
    for (int i = 1; i <= 50; ++i) {
      const Vec3 o{10.0 * i, 0, 0};
      soup.push_back(soup_of(a + o, bb + o, c + o));
    }
    soup.push_back(soup_of(swap ? a : a + up, swap ? bb : bb + up, swap ? c : c + up));
    for (uint32_t leaf : {1u, 4u}) {
      auto b = build(soup, leaf);
      ClosestPoint cp;
      ASSERT_TRUE(closest_point(b->index, Vec3{1, 1, 1}, &cp));
      EXPECT_EQ(cp.triangle, 0u);
      EXPECT_EQ(cp.distance, 1.0);
      EXPECT_EQ(cp.feature, Feature::kFace);
    }
  }
  // Duplicated triangles: the earlier copy always wins (random points, leaf size 1 puts the
  // copies in different leaves).
  Rng rng(0x5eed0003);
  Soup base = random_soup(rng, 30, 40, 3);
  Soup soup;
  for (const auto& t : base) soup.push_back(t);
  for (size_t i = base.size(); i-- > 0;) soup.push_back(base[i]);  // ids n..2n-1, reversed
  auto b = build(soup, 1);
  for (int i = 0; i < 100 * kEffort; ++i) {
    const Vec3 q = rng.in_box(Vec3{-4, -4, -4}, Vec3{4, 4, 4});
    ClosestPoint cp;
    ASSERT_TRUE(closest_point(b->index, q, &cp));
    EXPECT_LT(cp.triangle, base.size());
  }
}

TEST(DistanceClosest, DegenerateTrianglesNeverGiveAWrongDistance) {
  // Collinear and point-like triangles next to ordinary ones: the closest distance is still
  // the brute-force one (the copy of the per-triangle routine also agrees).
  Rng rng(0x5eed0004);
  for (int round = 0; round < 5 * kEffort; ++round) {
    Soup soup;
    for (int i = 0; i < 20; ++i) {
      const Vec3 a = to_float(rng.in_box(Vec3{-2, -2, -2}, Vec3{2, 2, 2}));
      const Vec3 d = to_float(rng.unit() * rng.uniform(0.01, 3));
      const Vec3 bb = to_float(a + d);
      SoupTriangle t = soup_of(a, bb, a);
      for (int k = 0; k < 3; ++k) t.p[2][k] = (t.p[0][k] + t.p[1][k]) * 0.5f;  // collinear
      if (i % 3 == 0) std::swap(t.p[0], t.p[2]);
      soup.push_back(t);
      if (i % 5 == 0) soup.push_back(soup_of(a, a, a));  // a point
      if (i % 4 == 0) soup.push_back(soup_of(a, bb, to_float(a + rng.unit())));
    }
    auto b = build(soup, 4);
    for (int i = 0; i < 100; ++i) {
      const Vec3 q = rng.in_box(Vec3{-4, -4, -4}, Vec3{4, 4, 4});
      ASSERT_EQ(check_closest(*b, q, "degenerate"), 0);
    }
  }
}

// =============================================================================================
// 2. The box mesh against the analytic box SDF.

double box_sdf(const Vec3& q, const Vec3& lo, const Vec3& hi) {
  double outside2 = 0, inside = -HUGE_VAL;
  for (int a = 0; a < 3; ++a) {
    const double d = std::max(lo[a] - q[a], q[a] - hi[a]);
    if (d > 0) outside2 += d * d;
    inside = std::max(inside, d);
  }
  return outside2 > 0 ? std::sqrt(outside2) : std::min(inside, 0.0);
}

TEST(DistanceSigned, BoxMatchesTheAnalyticSdfEverywhereWithEveryMethod) {
  const Vec3 lo{-1.5, -0.75, -2}, hi{2.25, 1.25, 0.5};
  Rng rng(0x5eed0010);
  std::vector<Vec3> q;
  // A grid of coordinates on, just off and away from every face plane: corners, edges, faces,
  // inside, outside.
  std::vector<double> axis[3];
  for (int a = 0; a < 3; ++a) {
    const double mid = 0.5 * (lo[a] + hi[a]);
    for (double off : {-1.0, -1e-3, -1e-7, 0.0, 1e-7, 1e-3}) {
      axis[a].push_back(lo[a] + off);
      axis[a].push_back(hi[a] - off);
    }
    axis[a].push_back(mid);
    axis[a].push_back(mid + 0.1);
    axis[a].push_back(lo[a] + 0.25);
  }
  for (double x : axis[0]) {
    for (double y : axis[1]) {
      for (double z : axis[2]) q.push_back(Vec3{x, y, z});
    }
  }
  for (int i = 0; i < 500 * kEffort; ++i)
    q.push_back(rng.in_box(lo - Vec3{2, 2, 2}, hi + Vec3{2, 2, 2}));
  // Random points exactly on the faces (float coordinates in the face).
  for (int i = 0; i < 200 * kEffort; ++i) {
    Vec3 p = to_float(rng.in_box(lo, hi));
    const int a = static_cast<int>(rng.below(3));
    p[a] = rng.below(2) ? hi[a] : lo[a];
    q.push_back(p);
  }
  for (uint32_t leaf : {1u, 4u}) {
    auto b = build(box_soup(lo, hi), leaf);
    ASSERT_TRUE(b->index.closed_manifold);
    for (SignMethod method :
         {SignMethod::kPseudonormal, SignMethod::kWindingNumber, SignMethod::kAuto}) {
      int failures = 0;
      for (const Vec3& p : q) {
        const double want = box_sdf(p, lo, hi);
        SignedDistance sd;
        ASSERT_TRUE(signed_distance(b->index, p, method, &sd));
        ClosestPoint cp;
        ASSERT_TRUE(closest_point(b->index, p, &cp));
        // On the surface: exactly +0 (documented); elsewhere the analytic sign.
        const bool sign_ok = want == 0 ? (sd.distance == 0 && !std::signbit(sd.distance))
                                       : sign_of(sd.distance) == sign_of(want);
        const bool ok = std::fabs(sd.distance - want) < 1e-9 &&
                        std::fabs(cp.distance - std::fabs(want)) < 1e-9 && sign_ok;
        if (!ok) {
          if (++failures <= 5) {
            ADD_FAILURE() << "method " << static_cast<int>(method) << " leaf " << leaf << " q=("
                          << p.x << ", " << p.y << ", " << p.z << "): signed " << sd.distance
                          << " unsigned " << cp.distance << ", analytic " << want;
          }
        }
        if (method == SignMethod::kAuto) {
          EXPECT_EQ(sd.method, SignMethod::kPseudonormal);
        }
      }
      EXPECT_EQ(failures, 0) << "of " << q.size();
    }
  }
}

// =============================================================================================
// 3. Sign on curved closed meshes.

// Analytic signed distances of the shapes the meshes approximate.
struct Analytic {
  enum Kind { kSphere, kTorus, kCone } kind;
  Vec3 center{};
  double a = 0, b = 0, h = 0;  // sphere: radius a; torus: R a, r b; cone: r0 a, r1 b, height h
  double operator()(const Vec3& p0) const {
    const Vec3 p = p0 - center;
    const double rho = std::sqrt(p.x * p.x + p.y * p.y);
    switch (kind) {
      case kSphere: return length(p) - a;
      case kTorus: return std::sqrt((rho - a) * (rho - a) + p.z * p.z) - b;
      case kCone: {
        // Distance in the meridian half-plane to the profile (0,0)-(a,0)-(b,h)-(0,h).
        auto seg = [&](double x0, double y0, double x1, double y1) {
          const double dx = x1 - x0, dy = y1 - y0;
          double t = ((rho - x0) * dx + (p.z - y0) * dy) / (dx * dx + dy * dy);
          t = t < 0 ? 0 : (t > 1 ? 1 : t);
          const double ex = rho - (x0 + t * dx), ey = p.z - (y0 + t * dy);
          return std::sqrt(ex * ex + ey * ey);
        };
        double d = std::min(seg(0, 0, a, 0), std::min(seg(a, 0, b, h), seg(b, h, 0, h)));
        const bool inside = p.z > 0 && p.z < h && rho < a + (b - a) * p.z / h;
        return inside ? -d : d;
      }
    }
    return 0;
  }
};

// How far the mesh strays from the analytic surface (sampled on a barycentric grid of every
// triangle), times two, plus float rounding.
double shell_of(const Mesh& m, const Analytic& f) {
  double worst = 0;
  for (uint32_t t = 0; t < m.triangles.size(); ++t) {
    for (int i = 0; i <= 6; ++i) {
      for (int j = 0; i + j <= 6; ++j) {
        const double u = i / 6.0, v = j / 6.0;
        const Vec3 p = corner(m, t, 0) * (1 - u - v) + corner(m, t, 1) * u + corner(m, t, 2) * v;
        worst = std::max(worst, std::fabs(f(p)));
      }
    }
  }
  return 2 * worst + 1e-5;
}

struct CurvedCase {
  const char* name;
  Soup soup;
  Analytic f;
};

std::vector<CurvedCase> curved_cases() {
  std::vector<CurvedCase> c;
  c.push_back({"sphere", icosphere(3, 6, Vec3{1, 2, 3}),
               Analytic{Analytic::kSphere, Vec3{1, 2, 3}, 6, 0, 0}});
  c.push_back(
      {"torus", shapes::torus(48, 24, 10, 3), Analytic{Analytic::kTorus, Vec3{}, 10, 3, 0}});
  c.push_back({"cone", cone(64, 5, 0, 8), Analytic{Analytic::kCone, Vec3{}, 5, 0, 8}});
  c.push_back({"frustum", cone(48, 5, 2, 7), Analytic{Analytic::kCone, Vec3{}, 5, 2, 7}});
  return c;
}

TEST(DistanceSigned, CurvedMeshesHaveTheAnalyticSignOffTheShell) {
  Rng rng(0x5eed0020);
  for (const CurvedCase& c : curved_cases()) {
    auto b = build(c.soup);
    ASSERT_TRUE(b->index.closed_manifold) << c.name;
    ASSERT_GT(mesh_volume(b->mesh), 0) << c.name;
    const double shell = shell_of(b->mesh, c.f);
    const Aabb box = bounds_of(b->mesh);
    const Vec3 pad = box.extent() * 0.3;
    std::vector<Vec3> q;
    for (int i = 0; i < 300 * kEffort; ++i) q.push_back(rng.in_box(box.lo - pad, box.hi + pad));
    // Near the surface, just beyond the shell on both sides.
    for (int i = 0; i < 150 * kEffort; ++i) {
      const uint32_t v = rng.below(static_cast<uint32_t>(b->mesh.vertices.size()));
      q.push_back(b->mesh.vertices[v] + rng.unit() * (shell * rng.uniform(1.05, 3)));
    }
    int checked = 0, inside = 0;
    for (const Vec3& p : q) {
      const double want = c.f(p);
      if (std::fabs(want) <= shell) continue;
      ++checked;
      inside += want < 0;
      const double unsigned_distance = oracle_distance(*b, p);
      for (SignMethod method :
           {SignMethod::kPseudonormal, SignMethod::kWindingNumber, SignMethod::kAuto}) {
        SignedDistance sd;
        ASSERT_TRUE(signed_distance(b->index, p, method, &sd));
        ASSERT_EQ(sd.distance < 0, want < 0)
            << c.name << " method " << static_cast<int>(method) << " q=(" << p.x << ", " << p.y
            << ", " << p.z << ") analytic " << want << " shell " << shell << " got " << sd.distance;
        EXPECT_NEAR(std::fabs(sd.distance), unsigned_distance, 1e-12 * b->scale);
      }
    }
    EXPECT_GT(checked, 250 * kEffort) << c.name;
    EXPECT_GT(inside, 10 * kEffort) << c.name;
  }
}

// Offsets along +-normal next to every vertex and edge midpoint: both sign methods agree and
// give the side the offset went to.
TEST(DistanceSigned, PseudonormalAndWindingAgreeNextToEdgesAndVertices) {
  int points = 0, against = 0;
  for (const CurvedCase& c : curved_cases()) {
    auto b = build(c.soup);
    const Mesh& m = b->mesh;
    std::vector<Vec3> fnormal(m.triangles.size());
    for (uint32_t t = 0; t < m.triangles.size(); ++t) {
      const Vec3 n = cross(corner(m, t, 1) - corner(m, t, 0), corner(m, t, 2) - corner(m, t, 0));
      fnormal[t] = n * (1.0 / length(n));
    }
    std::vector<std::pair<Vec3, Vec3>> sites;  // point, unit outward direction
    // At vertices the angle-weighted pseudonormal: the area-weighted sum can lie in a face's
    // plane (at the rim of a cone the base and side areas cancel in z exactly).
    for (uint32_t v = 0; v < m.vertices.size(); ++v) {
      const Vec3 n = vertex_pseudonormal(b->index, v);
      sites.emplace_back(m.vertices[v], n * (1.0 / length(n)));
    }
    for (uint32_t t = 0; t < m.triangles.size(); ++t) {
      for (int k = 0; k < 3; ++k) {
        const uint32_t other = b->index.neighbors[3 * size_t{t} + static_cast<size_t>(k)];
        ASSERT_NE(other, kNoNeighbor);
        if (other < t) continue;  // each edge once
        const Vec3 n = fnormal[t] + fnormal[other];
        sites.emplace_back((corner(m, t, k) + corner(m, t, (k + 1) % 3)) * 0.5,
                           n * (1.0 / length(n)));
      }
    }
    const double eps[] = {1e-6, 1e-5, 1e-4, 1e-3};
    const size_t stride = kEffort == 4 ? 1 : 3;
    for (size_t i = 0; i < sites.size(); i += stride) {
      for (double sign : {1.0, -1.0}) {
        const Vec3 q = sites[i].first + sites[i].second * (sign * eps[(i + (sign > 0)) % 4]);
        SignedDistance pn, wn;
        ASSERT_TRUE(signed_distance(b->index, q, SignMethod::kPseudonormal, &pn));
        ASSERT_TRUE(signed_distance(b->index, q, SignMethod::kWindingNumber, &wn));
        ASSERT_EQ(pn.distance < 0, wn.distance < 0)
            << c.name << " site " << i << " sign " << sign << " winding " << wn.winding;
        // The truth: the exact winding number (0 or 1 off a closed surface). The offset
        // direction is not always the side it lands on (at the rim of a cone, -normal leaves
        // through the base), so that is only counted.
        if ((pn.distance < 0) != (sign < 0) || i % (8 * stride) == 0) {
          const double exact = winding_number(b->index, q, 0);
          ASSERT_LT(std::min(std::fabs(exact), std::fabs(exact - 1)), 1e-6)
              << c.name << " site " << i;
          ASSERT_EQ(pn.distance < 0, exact >= 0.5) << c.name << " site " << i;
        }
        ASSERT_GT(std::fabs(pn.distance), 0.0);
        against += (pn.distance < 0) != (sign < 0);
        ++points;
      }
    }
  }
  EXPECT_GT(points, 5000 / (kEffort == 4 ? 1 : 3));
  EXPECT_LT(against, points / 20);
  std::printf(
      "[ info ] %d points next to vertices and edges, %d landed on the other side of "
      "their offset\n",
      points, against);
}

// =============================================================================================
// 4. Winding numbers.

TEST(DistanceWinding, HierarchicalMatchesExactOnClosedMeshes) {
  Rng rng(0x5eed0030);
  for (const CurvedCase& c : curved_cases()) {
    auto b = build(c.soup);
    const Aabb box = bounds_of(b->mesh);
    const double diag = length(box.extent());
    const Vec3 mid = box.center();
    const double shell = shell_of(b->mesh, c.f);
    double worst_far = 0, worst_near = 0;
    int inside = 0;
    for (int i = 0; i < 100 * kEffort; ++i) {
      // Far: 3..20 bounding-box diagonals from the centre (the first-order far field with
      // beta = 2 is off by up to 1.5e-3 at 2 diagonals, 4e-4 at 3, 1e-4 at 5).
      const Vec3 far = mid + rng.unit() * (diag * rng.uniform(3, 20));
      const double we = winding_number(b->index, far, 0), wh = winding_number(b->index, far, 2);
      worst_far = std::max(worst_far, std::fabs(we - wh));
      EXPECT_LT(std::fabs(we), 1e-9);
      // Anywhere around the mesh, including near the surface: the decision is the same, and
      // the exact value is 0 or 1.
      const Vec3 p =
          i % 2 ? rng.in_box(box.lo - box.extent() * 0.2, box.hi + box.extent() * 0.2)
                : b->mesh.vertices[rng.below(static_cast<uint32_t>(b->mesh.vertices.size()))] +
                      rng.unit() * std::pow(10.0, -rng.uniform(1, 6));
      const double e = winding_number(b->index, p, 0), h = winding_number(b->index, p, 2);
      ASSERT_LT(std::min(std::fabs(e), std::fabs(e - 1)), 1e-9) << c.name;
      // With no index: the same solid angles in another order.
      ASSERT_NEAR(winding_number_direct(b->mesh, p), e, 1e-12) << c.name;
      ASSERT_EQ(e >= 0.5, h >= 0.5) << c.name << " exact " << e << " hierarchical " << h;
      ASSERT_LT(std::min(std::fabs(h), std::fabs(h - 1)), 0.25) << c.name;
      worst_near = std::max(worst_near, std::fabs(e - h));
      inside += e >= 0.5;
      if (std::fabs(c.f(p)) > shell) {
        EXPECT_EQ(e >= 0.5, c.f(p) < 0) << c.name;
      }
    }
    EXPECT_LT(worst_far, 1e-3) << c.name;
    EXPECT_GT(inside, 5 * kEffort) << c.name;
    std::printf("[ info ] %s: |exact - hierarchical| far %.3g, near %.3g\n", c.name, worst_far,
                worst_near);
  }
}

// A sphere with a cap cut off: inside still reads inside, outside reads outside.
TEST(DistanceWinding, SphereWithAHole) {
  const double R = 5;
  const Soup closed = icosphere(3, R, Vec3{});
  Soup open;
  for (const SoupTriangle& t : closed) {
    if ((t.p[0][2] + t.p[1][2] + t.p[2][2]) / 3 < 0.8 * R) open.push_back(t);
  }
  ASSERT_LT(open.size(), closed.size());
  auto b = build(open);
  EXPECT_FALSE(b->index.closed_manifold);
  Rng rng(0x5eed0031);
  int in = 0, out = 0;
  for (int i = 0; i < 200 * kEffort; ++i) {
    const Vec3 p = i % 3 == 0 ? rng.unit() * (0.7 * R * rng.uniform())
                              : rng.in_box(Vec3{-1.5 * R, -1.5 * R, -1.5 * R},
                                           Vec3{1.5 * R, 1.5 * R, 1.5 * R});
    const double r = length(p);
    const bool well_inside = r < 0.6 * R && p.z < 0.5 * R;
    const bool well_outside = r > 1.3 * R;
    if (!well_inside && !well_outside) continue;
    const double w = winding_number(b->index, p), we = winding_number(b->index, p, 0);
    EXPECT_EQ(w >= 0.5, well_inside) << r << " " << w;
    EXPECT_EQ(we >= 0.5, well_inside) << r << " " << we;
    EXPECT_NEAR(winding_number_direct(b->mesh, p), we, 1e-12) << r;
    SignedDistance sd;
    ASSERT_TRUE(signed_distance(b->index, p, SignMethod::kAuto, &sd));
    EXPECT_EQ(sd.method, SignMethod::kWindingNumber);
    EXPECT_EQ(sd.distance < 0, well_inside);
    in += well_inside;
    out += well_outside;
  }
  EXPECT_GT(in, 40 * kEffort);
  EXPECT_GT(out, 50 * kEffort);
  // Right above the hole, inside the sphere, the winding number is fractional.
  const double w = winding_number(b->index, Vec3{0, 0, 0.9 * R}, 0);
  EXPECT_GT(w, 0.1);
  EXPECT_LT(w, 0.9);
  EXPECT_NEAR(winding_number_direct(b->mesh, Vec3{0, 0, 0.9 * R}), w, 1e-12);
}

// The real lower half-arch (teeth 17..24), one mesh, 5% of its triangles removed.
TEST(DistanceWinding, RealHalfArchWithHoles) {
  const std::string dir = std::string(SPLINTCORE_REALDATA_DIR) + "/mandible/";
  if (!test::file_exists(dir + "tooth_17.stl")) GTEST_SKIP() << "realdata not found";
  TestArena t(size_t{512} << 20);
  Context ctx(&t.arena);
  std::vector<std::vector<uint8_t>> files;
  for (int tooth = 17; tooth <= 24; ++tooth) {
    files.push_back(test::read_file_bytes(dir + "tooth_" + std::to_string(tooth) + ".stl"));
    ASSERT_FALSE(files.back().empty()) << tooth;
  }
  ArenaArray<SoupTriangle> soup(&t.arena);
  for (const auto& bytes : files) {
    MemorySource ms{bytes.data(), bytes.size(), 0, 0};
    StlInfo info;
    SPLINTCORE_ASSERT_OK(read_stl(ctx, memory_source(&ms), StlReadOptions{}, &soup, &info));
  }
  Mesh closed(&t.arena);
  SPLINTCORE_ASSERT_OK(weld_exact(ctx, soup.span(), &closed));
  DistanceIndex closed_index;
  SPLINTCORE_ASSERT_OK(build_distance_index(ctx, closed, DistanceIndexOptions{}, &closed_index));
  ASSERT_TRUE(closed_index.closed_manifold);

  // Candidates: 0.3 mm inside and 1 mm outside random faces, kept when the closed mesh says
  // they are that deep (pseudonormals, exact on a closed mesh).
  Rng rng(0x5eed0032);
  const uint32_t nt = static_cast<uint32_t>(closed.triangles.size());
  std::vector<Vec3> inside, outside;
  const int want = 100 * kEffort;
  for (int i = 0; i < 4 * want; ++i) {
    const uint32_t f = rng.below(nt);
    const Vec3 &a = corner(closed, f, 0), &b = corner(closed, f, 1), &c = corner(closed, f, 2);
    Vec3 n = cross(b - a, c - a);
    if (!(length(n) > 0)) continue;
    n = n * (1.0 / length(n));
    const Vec3 centroid = (a + b + c) * (1.0 / 3.0);
    SignedDistance sd;
    const Vec3 pin = centroid - n * 0.3;
    ASSERT_TRUE(signed_distance(closed_index, pin, SignMethod::kPseudonormal, &sd));
    if (sd.distance < -0.25 && inside.size() < static_cast<size_t>(want)) inside.push_back(pin);
    const Vec3 pout = centroid + n * 1.0;
    ASSERT_TRUE(signed_distance(closed_index, pout, SignMethod::kPseudonormal, &sd));
    if (sd.distance > 0.9 && outside.size() < static_cast<size_t>(want)) outside.push_back(pout);
  }
  ASSERT_GE(inside.size(), static_cast<size_t>(want) / 2);
  ASSERT_GE(outside.size(), static_cast<size_t>(want) / 2);
  for (const Vec3& p : inside) EXPECT_GE(winding_number(closed_index, p), 0.5);
  for (const Vec3& p : outside) EXPECT_LT(winding_number(closed_index, p), 0.5);

  // The open mesh: the same vertices, every twentieth triangle (by a hash of its id) gone.
  Mesh open(&t.arena);
  ASSERT_TRUE(open.vertices.resize(closed.vertices.size()));
  std::memcpy(open.vertices.data(), closed.vertices.data(), closed.vertices.size() * sizeof(Vec3));
  for (uint32_t f = 0; f < nt; ++f) {
    if (hash_mix(f) % 20 != 0) {
      ASSERT_TRUE(open.triangles.push_back(closed.triangles[f]));
    }
  }
  EXPECT_NEAR(static_cast<double>(nt - open.triangles.size()) / nt, 0.05, 0.005);
  DistanceIndex open_index;
  SPLINTCORE_ASSERT_OK(build_distance_index(ctx, open, DistanceIndexOptions{}, &open_index));
  EXPECT_FALSE(open_index.closed_manifold);
  double min_in = 1, max_out = 0;
  for (const Vec3& p : inside) {
    const double w = winding_number(open_index, p);
    min_in = std::min(min_in, w);
    EXPECT_GE(w, 0.5);
    SignedDistance sd;
    ASSERT_TRUE(signed_distance(open_index, p, SignMethod::kAuto, &sd));
    EXPECT_LT(sd.distance, 0);
  }
  for (const Vec3& p : outside) {
    const double w = winding_number(open_index, p);
    max_out = std::max(max_out, w);
    EXPECT_LT(w, 0.5);
  }
  std::printf(
      "[ info ] half-arch: %u triangles (%zu open), %zu inside points (min w %.3f), %zu "
      "outside (max w %.3f)\n",
      nt, open.triangles.size(), inside.size(), min_in, outside.size(), max_out);
}

// =============================================================================================
// 5. Rays, segments and boxes.

// The same Moller-Trumbore as the library, over every triangle: the smallest t, then the
// smallest id.
bool reference_ray(const Mesh& m, const Vec3& o, const Vec3& d, double t_max, RayHit* out) {
  bool found = false;
  for (uint32_t t = 0; t < m.triangles.size(); ++t) {
    const Vec3 &a = corner(m, t, 0), &b = corner(m, t, 1), &c = corner(m, t, 2);
    const Vec3 e1 = b - a, e2 = c - a;
    const Vec3 p = cross(d, e2);
    const double det = dot(e1, p);
    if (det == 0.0) continue;
    const double inv_det = 1.0 / det;
    const Vec3 s = o - a;
    const double u = dot(s, p) * inv_det;
    if (u < 0.0 || u > 1.0) continue;
    const Vec3 qv = cross(s, e1);
    const double w = dot(d, qv) * inv_det;
    if (w < 0.0 || u + w > 1.0) continue;
    const double th = dot(e2, qv) * inv_det;
    if (th < 0.0 || th > t_max) continue;
    if (!found || th < out->t) {
      out->t = th;
      out->triangle = t;
      found = true;
    }
  }
  return found;
}

// Exact segment-triangle test (closed), by exact integer signs only.
int o3(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  return splintcore_test::exact_orient3d_sign(a, b, c, d);
}
int o2(const double* a, const double* b, const double* c) {
  return splintcore_test::exact_orient2d_sign(a[0], a[1], b[0], b[1], c[0], c[1]);
}
bool on_segment_2d(const double* a, const double* b, const double* p) {  // p collinear
  return std::min(a[0], b[0]) <= p[0] && p[0] <= std::max(a[0], b[0]) &&
         std::min(a[1], b[1]) <= p[1] && p[1] <= std::max(a[1], b[1]);
}
bool segments_meet_2d(const double* a, const double* b, const double* c, const double* d) {
  const int d1 = o2(c, d, a), d2 = o2(c, d, b), d3 = o2(a, b, c), d4 = o2(a, b, d);
  if (d1 * d2 < 0 && d3 * d4 < 0) return true;
  return (d1 == 0 && on_segment_2d(c, d, a)) || (d2 == 0 && on_segment_2d(c, d, b)) ||
         (d3 == 0 && on_segment_2d(a, b, c)) || (d4 == 0 && on_segment_2d(a, b, d));
}
bool exact_segment_triangle(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b,
                            const Vec3& c) {
  const int sp = o3(a, b, c, p), sq = o3(a, b, c, q);
  if (sp * sq > 0) return false;
  if (sp != 0 || sq != 0) {
    const int s1 = o3(p, q, a, b), s2 = o3(p, q, b, c), s3 = o3(p, q, c, a);
    return (s1 >= 0 && s2 >= 0 && s3 >= 0) || (s1 <= 0 && s2 <= 0 && s3 <= 0);
  }
  // Coplanar: in a projection where the triangle is not degenerate.
  for (int drop = 0; drop < 3; ++drop) {
    const int u = (drop + 1) % 3, v = (drop + 2) % 3;
    const double A[2] = {a[u], a[v]}, B[2] = {b[u], b[v]}, C[2] = {c[u], c[v]};
    const double P[2] = {p[u], p[v]}, Q[2] = {q[u], q[v]};
    if (o2(A, B, C) == 0) continue;
    auto in_tri = [&](const double* x) {
      const int s1 = o2(A, B, x), s2 = o2(B, C, x), s3 = o2(C, A, x);
      return (s1 >= 0 && s2 >= 0 && s3 >= 0) || (s1 <= 0 && s2 <= 0 && s3 <= 0);
    };
    return in_tri(P) || in_tri(Q) || segments_meet_2d(P, Q, A, B) || segments_meet_2d(P, Q, B, C) ||
           segments_meet_2d(P, Q, C, A);
  }
  return false;  // degenerate triangle
}

bool boxes_overlap(const Vec3& alo, const Vec3& ahi, const Vec3& blo, const Vec3& bhi) {
  for (int i = 0; i < 3; ++i) {
    if (alo[i] > bhi[i] || blo[i] > ahi[i]) return false;
  }
  return true;
}

bool oracle_segment(const Mesh& m, const Vec3& p, const Vec3& q, uint32_t* first) {
  const Vec3 slo = min_vec(p, q), shi = max_vec(p, q);
  for (uint32_t t = 0; t < m.triangles.size(); ++t) {
    const Vec3 &a = corner(m, t, 0), &b = corner(m, t, 1), &c = corner(m, t, 2);
    if (!boxes_overlap(min_vec(a, min_vec(b, c)), max_vec(a, max_vec(b, c)), slo, shi)) continue;
    if (splintcore_test::exact_collinear3d(a, b, c)) continue;
    if (exact_segment_triangle(p, q, a, b, c)) {
      *first = t;
      return true;
    }
  }
  return false;
}

std::vector<std::pair<std::string, Soup>> query_shapes(Rng& rng) {
  std::vector<std::pair<std::string, Soup>> s;
  s.emplace_back("random soup", random_soup(rng, 80, 300, 4));
  s.emplace_back("torus", shapes::torus(24, 12, 10, 3));
  s.emplace_back("box", box_soup(Vec3{-1.5, -0.75, -2}, Vec3{2.25, 1.25, 0.5}));
  s.emplace_back("icosphere", icosphere(2, 3, Vec3{0.5, 0.25, -1}));
  return s;
}

TEST(DistanceRay, MatchesBruteForce) {
  Rng rng(0x5eed0040);
  int hits = 0, total = 0, sliver_hits = 0;
  for (const auto& shape : query_shapes(rng)) {
    for (uint32_t leaf : {1u, 4u}) {
      auto b = build(shape.second, leaf);
      const Mesh& m = b->mesh;
      const Aabb box = bounds_of(m);
      const Vec3 pad = box.extent() * 0.5;
      for (int i = 0; i < 150 * kEffort; ++i) {
        const Vec3 o = rng.in_box(box.lo - pad, box.hi + pad);
        Vec3 d;
        double t_max = HUGE_VAL;
        switch (i % 5) {
          case 0: d = rng.unit(); break;
          case 1:
            d = rng.unit() * 3.5;
            t_max = rng.uniform(0, 10);
            break;
          case 2: {  // exactly at a vertex
            const uint32_t t = rng.below(static_cast<uint32_t>(m.triangles.size()));
            d = corner(m, t, 0) - o;
            t_max = 1.0;
            break;
          }
          case 3: {  // exactly at an edge midpoint
            const uint32_t t = rng.below(static_cast<uint32_t>(m.triangles.size()));
            d = (corner(m, t, 0) + corner(m, t, 1)) * 0.5 - o;
            t_max = 2.0;
            break;
          }
          default: {  // axis-aligned (zero direction components)
            const int a = static_cast<int>(rng.below(3));
            d = Vec3{};
            d[a] = rng.below(2) ? 1.0 : -1.0;
            break;
          }
        }
        RayHit lib, ref;
        const bool hl = ray_intersect(b->index, o, d, t_max, &lib);
        const bool hr = reference_ray(m, o, d, t_max, &ref);
        ASSERT_EQ(hl, hr) << shape.first << " case " << i % 5;
        ++total;
        if (!hl) continue;
        ++hits;
        ASSERT_EQ(lib.triangle, ref.triangle) << shape.first;
        ASSERT_TRUE(same_bits(lib.t, ref.t));
        // The hit point is on the triangle (Moller-Trumbore loses about eps / sin(angle) on
        // slivers: those are only counted).
        const Vec3 x = o + d * lib.t;
        const Vec3 &ta = corner(m, lib.triangle, 0), &tb = corner(m, lib.triangle, 1),
                   &tc = corner(m, lib.triangle, 2);
        if (is_sliver(ta, tb, tc)) {
          ++sliver_hits;
          continue;
        }
        EXPECT_LE(oracle_point_triangle(x, ta, tb, tc),
                  1e-13 * (b->scale + length(o) + length(d) * lib.t))
            << shape.first << " case " << i % 5 << " triangle " << lib.triangle << " t " << lib.t;
      }
    }
  }
  EXPECT_GT(hits, total / 5);
  std::printf("[ info ] %d rays, %d hits (%d on slivers)\n", total, hits, sliver_hits);
}

TEST(DistanceSegment, MatchesExactBruteForce) {
  Rng rng(0x5eed0041);
  int hits = 0, total = 0;
  for (const auto& shape : query_shapes(rng)) {
    auto b = build(shape.second, 4);
    const Mesh& m = b->mesh;
    const Aabb box = bounds_of(m);
    const Vec3 pad = box.extent() * 0.3;
    const uint32_t nt = static_cast<uint32_t>(m.triangles.size());
    for (int i = 0; i < 60 * kEffort; ++i) {
      Vec3 p = rng.in_box(box.lo - pad, box.hi + pad), q;
      const uint32_t t = rng.below(nt);
      const Vec3 &a = corner(m, t, 0), &bb = corner(m, t, 1), &c = corner(m, t, 2);
      switch (i % 6) {
        case 0: q = rng.in_box(box.lo - pad, box.hi + pad); break;
        case 1: q = p + rng.unit() * 0.2; break;
        case 2: q = a; break;               // ends on a vertex
        case 3: q = (a + bb) * 0.5; break;  // ends on an edge
        case 4:
          p = bb * 2.0 - a;
          q = a * 2.0 - bb;
          break;  // along an edge (coplanar)
        default:
          p = (a + bb) * 0.5;
          q = c * 2.0 - (a + bb) * 0.5;
          break;  // across the face, in its plane
      }
      uint32_t lib = 0, want = 0;
      const bool hl = segment_intersects_mesh(b->index, p, q, &lib);
      const bool hw = oracle_segment(m, p, q, &want);
      ASSERT_EQ(hl, hw) << shape.first << " case " << i % 6;
      ++total;
      if (hl) {
        ++hits;
        ASSERT_EQ(lib, want) << shape.first << " case " << i % 6;
      }
      EXPECT_EQ(segment_intersects_mesh(b->index, p, q, nullptr), hl);
    }
  }
  EXPECT_GT(hits, total / 3);
  EXPECT_LT(hits, total);
}

// triangle_near_mesh against the brute-force least triangle_pair_distance, with small
// triangles near the surface (the blockout's swept triangles against its splint), reaches of
// 0.01 and 0.05 times the shape's size, and triangles through the surface (distance 0).
TEST(DistanceTriangle, NearMeshMatchesBruteForce) {
  Rng rng(0x5eed0077);
  int near = 0, total = 0;
  for (const auto& shape : query_shapes(rng)) {
    auto b = build(shape.second, 4);
    const Mesh& m = b->mesh;
    const Aabb box = bounds_of(m);
    const double size = length(box.extent());
    const uint32_t nt = static_cast<uint32_t>(m.triangles.size());
    for (int i = 0; i < 40 * kEffort; ++i) {
      const uint32_t t = rng.below(nt);
      const Vec3 on = (corner(m, t, 0) + corner(m, t, 1) + corner(m, t, 2)) * (1.0 / 3.0);
      const Vec3 c = on + rng.unit() * (size * 0.06 * rng.uniform());
      const Vec3 p = c + rng.unit() * (size * 0.01), q = c + rng.unit() * (size * 0.01),
                 r = c + rng.unit() * (size * 0.01);
      const double reach = size * (i % 2 == 0 ? 0.01 : 0.05);
      double least = HUGE_VAL;
      for (uint32_t k = 0; k < nt; ++k) {
        least = std::fmin(least, triangle_pair_distance(p, q, r, corner(m, k, 0), corner(m, k, 1),
                                                        corner(m, k, 2), nullptr, nullptr));
      }
      const bool got = triangle_near_mesh(b->index, p, q, r, reach);
      ASSERT_EQ(got, least < reach) << shape.first << " i " << i << " least " << least;
      near += got ? 1 : 0;
      ++total;
    }
  }
  EXPECT_GT(near, total / 5);
  EXPECT_LT(near, total * 9 / 10);
}

// A query triangle for triangle_side: about a random triangle of m, up to 8% of the shape's
// size off it, up to a tenth of that size wide; reach 0.2% or 2% of the size (by i).
struct QueryTriangle {
  Vec3 p, q, r;
  double reach;
};
QueryTriangle query_triangle(Rng& rng, const Mesh& m, double size, int i) {
  const uint32_t t = rng.below(static_cast<uint32_t>(m.triangles.size()));
  const Vec3 on = (corner(m, t, 0) + corner(m, t, 1) + corner(m, t, 2)) * (1.0 / 3.0);
  const Vec3 c = on + rng.unit() * (size * 0.08 * rng.uniform());
  const double spread = size * (i % 3 == 0 ? 0.05 : 0.005);
  QueryTriangle qt;
  qt.p = c + rng.unit() * spread;
  qt.q = c + rng.unit() * spread;
  qt.r = c + rng.unit() * spread;
  qt.reach = size * (i % 2 == 0 ? 0.002 : 0.02);
  return qt;
}

// triangle_side against brute force on the closed shapes: near exactly when the least pair
// distance is under reach; otherwise the side of the exact winding number at every corner
// (the triangle lies wholly on one side). Triangles up to a tenth of the shape's size, so both
// paths run: the closest-point query deciding alone, and the exact near test after it. The
// seed carried from call to call gives the answers a fresh one gives.
TEST(DistanceTriangle, SideMatchesBruteForce) {
  Rng rng(0x5eed0078);
  int counts[3] = {0, 0, 0};
  for (const auto& shape : query_shapes(rng)) {
    auto b = build(shape.second, 4);
    if (!b->index.closed_manifold) continue;
    const Mesh& m = b->mesh;
    const Aabb box = bounds_of(m);
    const double size = length(box.extent());
    const uint32_t nt = static_cast<uint32_t>(m.triangles.size());
    uint32_t seed = kNoNeighbor;
    for (int i = 0; i < 40 * kEffort; ++i) {
      const QueryTriangle qt = query_triangle(rng, m, size, i);
      const Vec3 &p = qt.p, &q = qt.q, &r = qt.r;
      const double reach = qt.reach;
      double least = HUGE_VAL;
      for (uint32_t k = 0; k < nt; ++k) {
        least = std::fmin(least, triangle_pair_distance(p, q, r, corner(m, k, 0), corner(m, k, 1),
                                                        corner(m, k, 2), nullptr, nullptr));
      }
      const TriangleSide got = triangle_side(b->index, p, q, r, reach, &seed);
      uint32_t fresh = kNoNeighbor;
      ASSERT_EQ(static_cast<int>(triangle_side(b->index, p, q, r, reach, &fresh)),
                static_cast<int>(got));
      if (least < reach) {
        ASSERT_EQ(static_cast<int>(got), static_cast<int>(TriangleSide::kNear))
            << shape.first << " i " << i << " least " << least;
      } else {
        const bool inside = winding_number(b->index, p, 0.0) >= 0.5;
        ASSERT_EQ(winding_number(b->index, q, 0.0) >= 0.5, inside);
        ASSERT_EQ(winding_number(b->index, r, 0.0) >= 0.5, inside);
        ASSERT_EQ(static_cast<int>(got),
                  static_cast<int>(inside ? TriangleSide::kInside : TriangleSide::kOutside))
            << shape.first << " i " << i << " least " << least;
      }
      ++counts[static_cast<int>(got)];
    }
  }
  // Each answer comes up often enough to mean something.
  for (int k = 0; k < 3; ++k) EXPECT_GT(counts[k], 10) << k;
}

// triangle_side_among (the blockout's window): given every triangle whose box meets abc's box
// grown by window_reach (triangles_meeting_box of a box holding abc's, grown so), it answers
// exactly as triangle_side, with closest_point's closest point (bits), or declines (the closest
// triangle may lie beyond the window).
// Windows from a reach's width to a third of the shape; too small ones decline, large ones
// answer nearly always. triangles_meeting_box finds the set triangles_in_box finds, and says
// when it has more than its capacity.
TEST(DistanceTriangle, SideAmongAWindowIsTriangleSide) {
  Rng rng(0x5eed0079);
  int answered = 0, declined = 0, overflowed = 0;
  for (const auto& shape : query_shapes(rng)) {
    auto b = build(shape.second, 4);
    if (!b->index.closed_manifold) continue;
    const Mesh& m = b->mesh;
    const double size = length(bounds_of(m).extent());
    const uint32_t nt = static_cast<uint32_t>(m.triangles.size());
    std::vector<uint32_t> ids(nt + 1);
    for (int i = 0; i < 40 * kEffort; ++i) {
      const QueryTriangle qt = query_triangle(rng, m, size, i);
      const Vec3 &p = qt.p, &q = qt.q, &r = qt.r;
      const double reach = qt.reach;
      uint32_t seed = kNoNeighbor;
      const TriangleSide want = triangle_side(b->index, p, q, r, reach, &seed);
      const double window_reach = reach + size * (i % 4 == 0 ? 0.0 : 0.01 * (i % 4) * (i % 4));
      Aabb window;
      window.add(p);
      window.add(q);
      window.add(r);
      // Half of them exactly the triangles the contract asks for (the tightest window).
      const double grow = (i / 2) % 2 == 0 ? 0.0 : size * 0.02 * rng.uniform();
      const Vec3 pad{grow + window_reach, grow + window_reach, grow + window_reach};
      const Aabb query{window.lo - pad, window.hi + pad};
      const size_t n = triangles_meeting_box(b->index, query, ids.data(), nt);
      ASSERT_LE(n, static_cast<size_t>(nt));
      TestArena scratch;
      Context ctx(&scratch.arena);
      ArenaArray<uint32_t> in_box(&scratch.arena);
      SPLINTCORE_ASSERT_OK(triangles_in_box(ctx, b->index, query, &in_box));
      std::vector<uint32_t> got_ids(ids.begin(), ids.begin() + static_cast<std::ptrdiff_t>(n));
      std::sort(got_ids.begin(), got_ids.end());
      ASSERT_EQ(got_ids, std::vector<uint32_t>(in_box.begin(), in_box.end())) << shape.first;
      if (n > 1) {
        ASSERT_EQ(triangles_meeting_box(b->index, query, ids.data(), n - 1), n);  // capacity + 1
        ++overflowed;
      }
      TriangleSide side = TriangleSide::kNear;
      ClosestPoint among;
      if (!triangle_side_among(b->index, ids.data(), n, window_reach, p, q, r, reach, &side,
                               &among)) {
        ++declined;
        continue;
      }
      // A seed (the answer itself, another triangle, an id out of range) changes nothing.
      for (const uint32_t s : {among.triangle, static_cast<uint32_t>(i * 7919) % nt, nt + 7}) {
        TriangleSide seeded_side = TriangleSide::kNear;
        ClosestPoint seeded;
        ASSERT_TRUE(triangle_side_among(b->index, ids.data(), n, window_reach, p, q, r, reach,
                                        &seeded_side, &seeded, s));
        ASSERT_EQ(static_cast<int>(seeded_side), static_cast<int>(side));
        ASSERT_EQ(seeded.triangle, among.triangle);
        ASSERT_EQ(std::memcmp(&seeded.point, &among.point, sizeof among.point), 0);
      }
      // With the window's boxes (triangles_meeting_box gives them): the same bits.
      std::vector<Aabb> boxes(n > 0 ? n : 1);
      std::vector<uint32_t> boxed_ids(n > 0 ? n : 1);
      ASSERT_EQ(triangles_meeting_box(b->index, query, boxed_ids.data(), n, boxes.data()), n);
      for (size_t k = 0; k < n; ++k) {
        const Triangle& t = m.triangles[boxed_ids[k]];
        Aabb want_box;
        for (uint32_t v : t.v) want_box.add(m.vertices[v]);
        ASSERT_TRUE(boxes[k].lo == want_box.lo && boxes[k].hi == want_box.hi);
      }
      TriangleSide boxed_side = TriangleSide::kNear;
      ClosestPoint boxed;
      ASSERT_TRUE(triangle_side_among(b->index, boxed_ids.data(), n, window_reach, p, q, r, reach,
                                      &boxed_side, &boxed, kNoNeighbor, boxes.data()));
      ASSERT_EQ(static_cast<int>(boxed_side), static_cast<int>(side));
      ASSERT_EQ(boxed.triangle, among.triangle);
      ASSERT_EQ(std::memcmp(&boxed.point, &among.point, sizeof among.point), 0);
      ASSERT_EQ(static_cast<int>(side), static_cast<int>(want))
          << shape.first << " i " << i << " window_reach " << window_reach;
      ClosestPoint tree;
      ASSERT_TRUE(closest_point(b->index, p, &tree));
      ASSERT_EQ(among.triangle, tree.triangle) << shape.first << " i " << i;
      ASSERT_EQ(std::memcmp(&among.distance, &tree.distance, sizeof tree.distance), 0);
      ASSERT_EQ(std::memcmp(&among.point, &tree.point, sizeof tree.point), 0);
      ++answered;
    }
  }
  // Each outcome often enough to mean something (the counts scale with kEffort: at 1, about
  // 75 answered, the rest declined).
  std::printf("[ figures  ] answered %d, declined %d, windows that overflowed %d\n", answered,
              declined, overflowed);
  EXPECT_GT(answered, 40 * kEffort);
  EXPECT_GT(declined, 5 * kEffort);
  EXPECT_GT(overflowed, 5 * kEffort);
}

// triangle_side_among with a hint (the blockout's stream): the window holds every triangle of
// the shape, so the segment from any hint holds only triangles among them. Query triangles
// come along a random walk, each near the one before, and every answer is triangle_side's.
// Most are answered from the hint (the closest point is then left as it was: kNear from the
// window's reach test, a side from the crossings); the first of each shape from the closest
// point. On the box, a segment from the hint through the top face's diagonal edge (a touch,
// not counted) is answered from the closest point, with the same answer.
TEST(DistanceTriangle, SideAmongWithAHintIsTriangleSide) {
  Rng rng(0x5eed007a);
  int hinted = 0, near_first = 0, searched = 0, crossed = 0;
  for (const auto& shape : query_shapes(rng)) {
    auto b = build(shape.second, 4);
    if (!b->index.closed_manifold) continue;
    const Mesh& m = b->mesh;
    const Aabb bounds = bounds_of(m);
    const double size = length(bounds.extent());
    const uint32_t nt = static_cast<uint32_t>(m.triangles.size());
    std::vector<uint32_t> ids(nt);
    std::vector<Aabb> boxes(nt);
    const Vec3 pad{size, size, size};
    ASSERT_EQ(triangles_meeting_box(b->index, Aabb{bounds.lo - pad, bounds.hi + pad}, ids.data(),
                                    nt, boxes.data()),
              size_t{nt});
    const uint32_t untouched = nt + 1;
    SideHint hint;
    const auto answer = [&](const Vec3& p, const Vec3& q, const Vec3& r, double reach,
                            bool* from_hint) {
      uint32_t seed = kNoNeighbor;
      const TriangleSide want = triangle_side(b->index, p, q, r, reach, &seed);
      const SideHint before = hint;
      TriangleSide side = TriangleSide::kNear;
      ClosestPoint closest;
      closest.triangle = untouched;
      EXPECT_TRUE(triangle_side_among(b->index, ids.data(), nt, 10 * size, p, q, r, reach, &side,
                                      &closest, kNoNeighbor, boxes.data(), &hint));
      EXPECT_EQ(static_cast<int>(side), static_cast<int>(want)) << shape.first;
      *from_hint = closest.triangle == untouched;
      if (side == TriangleSide::kNear) {
        EXPECT_TRUE(std::memcmp(&hint, &before, sizeof hint) == 0);  // kept as it was
      } else {
        EXPECT_TRUE(hint.point == p && hint.side == side);
      }
      return side;
    };
    Vec3 c = (bounds.lo + bounds.hi) * 0.5;
    for (int i = 0; i < 200 * kEffort; ++i) {
      const Vec3 step = c + rng.unit() * (size * 0.03);
      if (step.x > bounds.lo.x - 0.2 * size && step.x < bounds.hi.x + 0.2 * size &&
          step.y > bounds.lo.y - 0.2 * size && step.y < bounds.hi.y + 0.2 * size &&
          step.z > bounds.lo.z - 0.2 * size && step.z < bounds.hi.z + 0.2 * size) {
        c = step;
      }
      const double spread = size * 0.005;
      const Vec3 p = c + rng.unit() * spread, q = c + rng.unit() * spread,
                 r = c + rng.unit() * spread;
      const Vec3 before = hint.point;
      bool from_hint = false;
      const TriangleSide side = answer(p, q, r, size * 0.002, &from_hint);
      if (!from_hint) {
        ++searched;
      } else if (side == TriangleSide::kNear) {
        ++near_first;
      } else {
        ++hinted;
        // Whether the segment from the hint crossed the surface: the side changed.
        const bool was_inside = winding_number(b->index, before, 0.0) >= 0.5;
        if (i > 0 && was_inside != (side == TriangleSide::kInside)) {
          ++crossed;
        }
      }
    }
    if (shape.first == "box") {
      // The box's top face (z = 0.5) is two triangles split along a diagonal, and both
      // diagonals pass through the face's centre (0.375, 0.25).
      bool from_hint = true;
      hint = SideHint{Vec3{0.375, 0.25, 1}, TriangleSide::kOutside};
      EXPECT_EQ(static_cast<int>(answer(Vec3{0.375, 0.25, 0}, Vec3{0.4, 0.25, 0},
                                        Vec3{0.375, 0.3, 0}, 0.01, &from_hint)),
                static_cast<int>(TriangleSide::kInside));
      EXPECT_FALSE(from_hint);
      // Off the diagonal, the same crossing counts.
      hint = SideHint{Vec3{0.5, 0.25, 1}, TriangleSide::kOutside};
      EXPECT_EQ(static_cast<int>(answer(Vec3{0.5, 0.25, 0}, Vec3{0.55, 0.25, 0}, Vec3{0.5, 0.3, 0},
                                        0.01, &from_hint)),
                static_cast<int>(TriangleSide::kInside));
      EXPECT_TRUE(from_hint);
    }
  }
  std::printf(
      "[ figures  ] from the hint: %d sides (%d across the surface), %d near; from the "
      "closest point: %d\n",
      hinted, crossed, near_first, searched);
  EXPECT_GT(hinted, 100 * kEffort);
  EXPECT_GT(crossed, 5 * kEffort);
  EXPECT_GT(near_first, 5 * kEffort);
  EXPECT_GE(searched, 3);  // the first of each closed shape at least
}

TEST(DistanceBox, TrianglesInBoxMatchBruteForce) {
  Rng rng(0x5eed0042);
  for (const auto& shape : query_shapes(rng)) {
    auto b = build(shape.second, 4);
    const Mesh& m = b->mesh;
    const Aabb bounds = bounds_of(m);
    Context ctx(&b->arena->arena);
    for (int i = 0; i < 100 * kEffort; ++i) {
      Aabb box;
      if (i % 4 == 3) {  // a box whose corner is a vertex (touching counts)
        const Vec3& v = m.vertices[rng.below(static_cast<uint32_t>(m.vertices.size()))];
        box.add(v);
        box.add(v + rng.unit() * rng.uniform(0, 2));
      } else {
        box.add(rng.in_box(bounds.lo - bounds.extent() * 0.2, bounds.hi + bounds.extent() * 0.2));
        box.add(box.lo + rng.unit() * rng.uniform(0, length(bounds.extent()) * 0.3));
      }
      ArenaScope scope(b->arena->arena);
      ArenaArray<uint32_t> got(&b->arena->arena);
      ASSERT_TRUE(got.push_back(12345u));  // appended after what is there
      SPLINTCORE_ASSERT_OK(triangles_in_box(ctx, b->index, box, &got));
      std::vector<uint32_t> want = {12345u};
      for (uint32_t t = 0; t < m.triangles.size(); ++t) {
        const Vec3 &a = corner(m, t, 0), &bb = corner(m, t, 1), &c = corner(m, t, 2);
        if (boxes_overlap(min_vec(a, min_vec(bb, c)), max_vec(a, max_vec(bb, c)), box.lo, box.hi)) {
          want.push_back(t);
        }
      }
      ASSERT_EQ(std::vector<uint32_t>(got.begin(), got.end()), want) << shape.first;
    }
    // An empty box finds nothing.
    ArenaArray<uint32_t> none(&b->arena->arena);
    SPLINTCORE_ASSERT_OK(triangles_in_box(ctx, b->index, Aabb{}, &none));
    EXPECT_EQ(none.size(), 0u);
  }
}

// =============================================================================================
// 6. Batches: bitwise the single queries, at any thread count.

TEST(DistanceBatch, SameBitsAsSingleQueriesOnAnyThreadCount) {
  Rng rng(0x5eed0050);
  std::vector<std::pair<std::string, Soup>> shapes = query_shapes(rng);
  for (const auto& shape : shapes) {
    auto b = build(shape.second, 4);
    std::vector<Vec3> q = query_points(b->mesh, rng, 250 * kEffort, 40 * kEffort);
    q.push_back(Vec3{NAN, 0, 0});  // queries are taken as given
    std::vector<ClosestPoint> single(q.size());
    std::vector<char> found(q.size());
    for (size_t i = 0; i < q.size(); ++i) found[i] = closest_point(b->index, q[i], &single[i]);
    std::vector<double> sd_single[3];
    const SignMethod methods[3] = {SignMethod::kAuto, SignMethod::kPseudonormal,
                                   SignMethod::kWindingNumber};
    for (int mth = 0; mth < 3; ++mth) {
      for (const Vec3& p : q) {
        SignedDistance sd;
        sd_single[mth].push_back(signed_distance(b->index, p, methods[mth], &sd) ? sd.distance
                                                                                 : HUGE_VAL);
      }
    }
    for (unsigned threads : {0u, 1u, 2u, 4u}) {
      ThreadExecutor pool(threads == 0 ? 1 : threads);
      Context ctx(&b->arena->arena, threads == 0 ? nullptr : &pool.executor(), nullptr);
      std::vector<ClosestPoint> got(q.size());
      SPLINTCORE_ASSERT_OK(batch_closest_points(ctx, b->index, Span<const Vec3>(q.data(), q.size()),
                                                Span<ClosestPoint>(got.data(), got.size())));
      for (size_t i = 0; i < q.size(); ++i) {
        if (!found[i]) {
          EXPECT_EQ(got[i].distance, 0.0);  // ClosestPoint{}
          continue;
        }
        ASSERT_EQ(got[i].triangle, single[i].triangle)
            << shape.first << " threads " << threads << " i " << i;
        ASSERT_TRUE(same_bits(got[i].distance, single[i].distance));
        ASSERT_TRUE(same_bits(got[i].point, single[i].point));
        ASSERT_EQ(got[i].feature, single[i].feature);
        ASSERT_EQ(got[i].feature_index, single[i].feature_index);
      }
      for (int mth = 0; mth < 3; ++mth) {
        std::vector<double> d(q.size());
        SPLINTCORE_ASSERT_OK(
            batch_signed_distances(ctx, b->index, Span<const Vec3>(q.data(), q.size()),
                                   methods[mth], Span<double>(d.data(), d.size())));
        ASSERT_EQ(std::memcmp(d.data(), sd_single[mth].data(), d.size() * sizeof(double)), 0)
            << shape.first << " threads " << threads << " method " << mth;
      }
      // Size mismatch.
      std::vector<ClosestPoint> small(1);
      EXPECT_EQ(batch_closest_points(ctx, b->index, Span<const Vec3>(q.data(), q.size()),
                                     Span<ClosestPoint>(small.data(), small.size()))
                    .code(),
                StatusCode::kInvalidArgument);
      std::vector<double> small_d(1);
      EXPECT_EQ(
          batch_signed_distances(ctx, b->index, Span<const Vec3>(q.data(), q.size()),
                                 SignMethod::kAuto, Span<double>(small_d.data(), small_d.size()))
              .code(),
          StatusCode::kInvalidArgument);
    }
  }
}

// More queries than one Morton chunk (2^16), on a torus, 1 vs 4 threads.
TEST(DistanceBatch, ManyQueriesAcrossChunks) {
  Rng rng(0x5eed0051);
  auto b = build(shapes::torus(32, 16, 4, 1), 4);
  const size_t n = (size_t{1} << 16) + 1500;  // one full Morton chunk and a part
  std::vector<Vec3> q(n);
  for (Vec3& p : q) p = rng.in_box(Vec3{-6, -6, -2}, Vec3{6, 6, 2});
  std::vector<ClosestPoint> r1(n), r4(n);
  ThreadExecutor one(1), four(4);
  Context c1(&b->arena->arena, &one.executor(), nullptr),
      c4(&b->arena->arena, &four.executor(), nullptr);
  SPLINTCORE_ASSERT_OK(batch_closest_points(c1, b->index, Span<const Vec3>(q.data(), n),
                                            Span<ClosestPoint>(r1.data(), n)));
  SPLINTCORE_ASSERT_OK(batch_closest_points(c4, b->index, Span<const Vec3>(q.data(), n),
                                            Span<ClosestPoint>(r4.data(), n)));
  for (size_t i = 0; i < n; i += (i < 1000 || i > n - 1000) ? 1 : 97) {
    ClosestPoint s;
    ASSERT_TRUE(closest_point(b->index, q[i], &s));
    ASSERT_EQ(r1[i].triangle, s.triangle) << i;
    ASSERT_TRUE(same_bits(r1[i].distance, s.distance)) << i;
  }
  for (size_t i = 0; i < n; ++i) {
    ASSERT_EQ(r1[i].triangle, r4[i].triangle) << i;
    ASSERT_TRUE(same_bits(r1[i].distance, r4[i].distance)) << i;
    ASSERT_TRUE(same_bits(r1[i].point, r4[i].point)) << i;
  }
}

// Batches with at least 4096 queries and half as many as triangles take the region path
// (regions.cpp), whose answers must be the tree's bit for bit: on soups with duplicate and
// collinear triangles, open and closed meshes, sharp apexes, ties (a box and queries on a
// lattice through its corners), queries on and near vertices, edges and faces, far ones
// (beyond the band, which the tree answers) and non-finite ones; 1 and 3 threads.
TEST(DistanceBatch, RegionPathSameBitsAsSingleQueries) {
  Rng rng(0x5eed0052);
  std::vector<std::pair<std::string, Soup>> shapes = query_shapes(rng);
  // A sparser soup than query_shapes' (whose estimated overlap, about 3.9 face regions a
  // query, sits at the path's limit of 4): here at most 2.2 over all shapes.
  shapes[0].second = random_soup(rng, 120, 100, 8);
  shapes.emplace_back("fine torus", shapes::torus(96, 48, 10, 3));
  shapes.emplace_back("cone", cone(40, 4, 0, 9));
  shapes.emplace_back("far sphere", icosphere(3, 0.3, Vec3{80, 40, 60}));
  Soup cut;
  for (const SoupTriangle& t : icosphere(4, 2.5, Vec3{})) {
    if ((t.p[0][0] + t.p[1][0] + t.p[2][0]) / 3 < 1.0f) cut.push_back(t);
  }
  shapes.emplace_back("cut ball", cut);
  struct Stages {
    bool regions = false;
  };
  Progress progress;
  progress.report = [](void* user, const char* stage, uint64_t, uint64_t) {
    if (std::strcmp(stage, "closest points, by regions") == 0)
      static_cast<Stages*>(user)->regions = true;
    return true;
  };
  for (const auto& shape : shapes) {
    auto b = build(shape.second, 4, size_t{256} << 20, shape.first == "torus");
    const Mesh& m = b->mesh;
    std::vector<Vec3> q = query_points(m, rng, 2000, 400);
    // Near the surface: a point of a random triangle moved along a random direction.
    const uint32_t nt = static_cast<uint32_t>(m.triangles.size());
    for (int i = 0; i < 2000; ++i) {
      const uint32_t t = rng.below(nt);
      double u = rng.uniform(0, 1), w = rng.uniform(0, 1);
      if (u + w > 1) {
        u = 1 - u;
        w = 1 - w;
      }
      const Vec3 p = corner(m, t, 0) + (corner(m, t, 1) - corner(m, t, 0)) * u +
                     (corner(m, t, 2) - corner(m, t, 0)) * w;
      const Vec3 direction = rng.unit();  // two statements: the same draws with every compiler
      q.push_back(p + direction * rng.uniform(0, 0.5));
    }
    // A lattice through the box's corners (and any shape's): exact ties.
    const Aabb box = bounds_of(m);
    const Vec3 step = box.extent() * 0.125;
    for (int x = -2; x <= 10; ++x) {
      for (int y = -2; y <= 10; ++y) {
        for (int z = -2; z <= 10; z += 2)
          q.push_back(box.lo + Vec3{step.x * x, step.y * y, step.z * z});
      }
    }
    q.push_back(Vec3{NAN, 0, 0});
    q.push_back(Vec3{0, HUGE_VAL, 0});
    q.push_back(box.hi + box.extent() * 50.0);
    ASSERT_GE(q.size(), 4096u);
    ASSERT_GE(q.size(), m.triangles.size() / 2) << shape.first;
    std::vector<ClosestPoint> single(q.size());
    std::vector<char> found(q.size());
    for (size_t i = 0; i < q.size(); ++i) found[i] = closest_point(b->index, q[i], &single[i]);
    for (unsigned threads : {1u, 3u}) {
      ThreadExecutor pool(threads);
      Stages stages;
      progress.user = &stages;
      Context ctx(&b->arena->arena, &pool.executor(), &progress);
      std::vector<ClosestPoint> got(q.size());
      SPLINTCORE_ASSERT_OK(batch_closest_points(ctx, b->index, Span<const Vec3>(q.data(), q.size()),
                                                Span<ClosestPoint>(got.data(), got.size())));
      EXPECT_TRUE(stages.regions) << shape.first;
      int failures = 0;
      for (size_t i = 0; i < q.size() && failures < 5; ++i) {
        if (!found[i]) {
          EXPECT_EQ(got[i].distance, 0.0);
          continue;
        }
        const bool same = got[i].triangle == single[i].triangle &&
                          same_bits(got[i].distance, single[i].distance) &&
                          same_bits(got[i].point, single[i].point) &&
                          got[i].feature == single[i].feature &&
                          got[i].feature_index == single[i].feature_index;
        if (!same) {
          ++failures;
          ADD_FAILURE() << shape.first << " threads " << threads << " query " << i << " (" << q[i].x
                        << ", " << q[i].y << ", " << q[i].z << "): batch triangle "
                        << got[i].triangle << " distance " << got[i].distance << ", single "
                        << single[i].triangle << " " << single[i].distance;
        }
      }
      ASSERT_EQ(failures, 0);
      for (SignMethod method : {SignMethod::kPseudonormal, SignMethod::kWindingNumber}) {
        // Winding numbers are slow to check one by one: once, on the open and imperfect meshes.
        if (method == SignMethod::kWindingNumber && (threads != 1 || b->index.closed_manifold))
          continue;
        std::vector<double> d(q.size());
        SPLINTCORE_ASSERT_OK(batch_signed_distances(ctx, b->index,
                                                    Span<const Vec3>(q.data(), q.size()), method,
                                                    Span<double>(d.data(), d.size())));
        for (size_t i = 0; i < q.size(); i += method == SignMethod::kWindingNumber ? 5 : 1) {
          SignedDistance sd;
          const double want = signed_distance(b->index, q[i], method, &sd) ? sd.distance : HUGE_VAL;
          ASSERT_TRUE(same_bits(d[i], want))
              << shape.first << " method " << static_cast<int>(method) << " i " << i;
        }
      }
    }
  }
}

// =============================================================================================
// 7. The narrow-band SDF sampler.

TEST(DistanceSdf, BoxGridMatchesTheClampedAnalyticSdf) {
  const Vec3 lo{-1, -0.5, -1.25}, hi{1, 0.75, 1};
  auto b = build(box_soup(lo, hi), 4);
  SdfGrid grid;
  grid.origin = Vec3{-2, -2, -2};
  grid.spacing = 0.125;  // lands exactly on every face plane
  grid.nx = 33;
  grid.ny = 31;
  grid.nz = kEffort == 4 ? 34 : 20;
  grid.band = 0.5;
  const size_t layer = size_t{grid.nx} * grid.ny;
  ThreadExecutor one(1), three(3);
  Context c1(&b->arena->arena, &one.executor(), nullptr),
      c3(&b->arena->arena, &three.executor(), nullptr);
  for (SignMethod method :
       {SignMethod::kAuto, SignMethod::kPseudonormal, SignMethod::kWindingNumber}) {
    std::vector<float> v1(layer * grid.nz), v3(layer * grid.nz);
    SPLINTCORE_ASSERT_OK(
        sample_sdf(c1, b->index, grid, method, 0, grid.nz, Span<float>(v1.data(), v1.size())));
    SPLINTCORE_ASSERT_OK(
        sample_sdf(c3, b->index, grid, method, 0, grid.nz, Span<float>(v3.data(), v3.size())));
    ASSERT_EQ(std::memcmp(v1.data(), v3.data(), v1.size() * sizeof(float)), 0);
    int beyond = 0, surface = 0;
    for (uint32_t z = 0; z < grid.nz; ++z) {
      for (uint32_t y = 0; y < grid.ny; ++y) {
        for (uint32_t x = 0; x < grid.nx; ++x) {
          const Vec3 p = grid.origin + Vec3{grid.spacing * x, grid.spacing * y, grid.spacing * z};
          const double d = box_sdf(p, lo, hi);
          const double clamped = std::max(-grid.band, std::min(grid.band, d));
          const float got = v1[(size_t{z} * grid.ny + y) * grid.nx + x];
          ASSERT_NEAR(got, clamped, 1e-6) << x << " " << y << " " << z;
          ASSERT_EQ(sign_of(got), sign_of(d)) << x << " " << y << " " << z;
          if (std::fabs(d) > grid.band) {
            ASSERT_EQ(got, static_cast<float>(d > 0 ? grid.band : -grid.band));
            ++beyond;
          }
          surface += d == 0;
        }
      }
    }
    EXPECT_GT(beyond, 100);
    EXPECT_GT(surface, 20);
    // A slab of layers is the same as those layers of the whole.
    const uint32_t z0 = 5, z1 = 11;
    std::vector<float> part(layer * (z1 - z0));
    SPLINTCORE_ASSERT_OK(
        sample_sdf(c3, b->index, grid, method, z0, z1, Span<float>(part.data(), part.size())));
    EXPECT_EQ(std::memcmp(part.data(), v1.data() + layer * z0, part.size() * sizeof(float)), 0);
    SPLINTCORE_EXPECT_OK(sample_sdf(c1, b->index, grid, method, 7, 7, Span<float>()));
  }
}

// Beyond the band a sample's sign on a closed mesh is carried along its row from the sample
// before it (when the spacing is at most half the band); on open meshes, and with a coarser
// spacing, every such sample takes the winding number. Either way every sample must be what
// one query gives: the clamped signed distance within the band, the winding number's decision
// beyond it. Closed meshes of several shells (a hollow ball, whose inner shell faces inward;
// two tori apart) and an open one (a ball with its cap cut off across the rows, which
// run along x: carried through the hole, an inside sign would reach the outside).
TEST(DistanceSdf, SamplesBeyondTheBandTakeTheWindingNumbersSign) {
  Soup hollow = icosphere(3, 2.5, Vec3{});
  for (SoupTriangle t : icosphere(2, 1.5, Vec3{0.25, -0.125, 0.375})) {
    std::swap(t.p[1], t.p[2]);
    hollow.push_back(t);
  }
  Soup tori = shapes::torus(24, 12, 2.5, 0.75);
  for (SoupTriangle t : shapes::torus(20, 10, 1.5, 0.5)) {
    for (float* p : {t.p[0], t.p[1], t.p[2]}) {
      p[0] += 5.0f;
      p[1] += 0.5f;
      p[2] += 0.25f;
    }
    tori.push_back(t);
  }
  Soup cut;
  for (const SoupTriangle& t : icosphere(3, 2.5, Vec3{})) {
    if ((t.p[0][0] + t.p[1][0] + t.p[2][0]) / 3 < 2.0f) cut.push_back(t);
  }
  const struct {
    const char* name;
    const Soup* soup;
    bool closed;
  } cases[] = {
      {"hollow ball", &hollow, true}, {"two tori", &tori, true}, {"cut ball", &cut, false}};
  for (const auto& c : cases) {
    auto b = build(*c.soup, 4);
    ASSERT_EQ(b->index.closed_manifold, c.closed) << c.name;
    const Aabb box = bounds_of(b->mesh);
    for (double spacing : {0.2, 0.3}) {  // carried (closed meshes) or not: the band is 0.5
      SdfGrid grid;
      grid.origin = box.lo - Vec3{0.6, 0.6, 0.6};
      grid.spacing = spacing;
      grid.nx = static_cast<uint32_t>((box.hi.x - box.lo.x + 1.2) / spacing) + 1;
      grid.ny = static_cast<uint32_t>((box.hi.y - box.lo.y + 1.2) / spacing) + 1;
      grid.nz = static_cast<uint32_t>((box.hi.z - box.lo.z + 1.2) / spacing) + 1;
      grid.band = 0.5;
      std::vector<float> v(size_t{grid.nx} * grid.ny * grid.nz);
      Context ctx(&b->arena->arena);
      SPLINTCORE_ASSERT_OK(sample_sdf(ctx, b->index, grid, SignMethod::kAuto, 0, grid.nz,
                                      Span<float>(v.data(), v.size())));
      int beyond_inside = 0, beyond_outside = 0, within = 0;
      for (uint32_t z = 0; z < grid.nz; ++z) {
        for (uint32_t y = 0; y < grid.ny; ++y) {
          for (uint32_t x = 0; x < grid.nx; ++x) {
            const Vec3 p = grid.origin + Vec3{spacing * x, spacing * y, spacing * z};
            const float got = v[(size_t{z} * grid.ny + y) * grid.nx + x];
            SignedDistance sd;
            ASSERT_TRUE(signed_distance(b->index, p, SignMethod::kAuto, &sd));
            if (sd.closest.distance <= grid.band) {
              ASSERT_EQ(got, static_cast<float>(std::max(-0.5, std::min(0.5, sd.distance))))
                  << c.name << " " << x << " " << y << " " << z;
              ++within;
            } else {
              const bool inside = winding_number(b->index, p) >= 0.5;
              ASSERT_EQ(got, inside ? -0.5f : 0.5f) << c.name << " " << x << " " << y << " " << z;
              ++(inside ? beyond_inside : beyond_outside);
            }
          }
        }
      }
      EXPECT_GT(within, 1000) << c.name;
      EXPECT_GT(beyond_inside, 50) << c.name;  // the shells' insides, the cut ball's inside
      EXPECT_GT(beyond_outside, 1000) << c.name;
    }
  }
}

TEST(DistanceSdf, BadArgumentsAreInvalidArgument) {
  auto b = build(box_soup(Vec3{0, 0, 0}, Vec3{1, 1, 1}), 4);
  Context ctx(&b->arena->arena);
  SdfGrid good;
  good.spacing = 0.5;
  good.nx = good.ny = good.nz = 4;
  good.band = 1;
  std::vector<float> out(64);
  const Span<float> all(out.data(), out.size());
  SPLINTCORE_EXPECT_OK(sample_sdf(ctx, b->index, good, SignMethod::kAuto, 0, 4, all));
  auto code = [&](const SdfGrid& g, uint32_t z0, uint32_t z1, Span<float> o) {
    return sample_sdf(ctx, b->index, g, SignMethod::kAuto, z0, z1, o).code();
  };
  SdfGrid g = good;
  for (double s : {0.0, -1.0, static_cast<double>(NAN)}) {
    g = good;
    g.spacing = s;
    EXPECT_EQ(code(g, 0, 4, all), StatusCode::kInvalidArgument) << s;
    g = good;
    g.band = s;
    EXPECT_EQ(code(g, 0, 4, all), StatusCode::kInvalidArgument) << s;
  }
  EXPECT_EQ(code(good, 3, 2, Span<float>()), StatusCode::kInvalidArgument);
  EXPECT_EQ(code(good, 0, 5, all), StatusCode::kInvalidArgument);
  EXPECT_EQ(code(good, 0, 4, Span<float>(out.data(), 63)), StatusCode::kInvalidArgument);
  EXPECT_EQ(code(good, 1, 4, all), StatusCode::kInvalidArgument);
  // A layer count whose size wraps around 2^64 (2^31 x 2^31 x 4 = 2^64 = 0 mod 2^64).
  g = good;
  g.nx = g.ny = 1u << 31;
  g.nz = 4;
  EXPECT_EQ(code(g, 0, 4, Span<float>()), StatusCode::kInvalidArgument);
}

// =============================================================================================
// 8. Building: empty meshes, bad meshes, the arena.

TEST(DistanceBuild, EmptyMesh) {
  TestArena t;
  Mesh mesh(&t.arena);
  Context ctx(&t.arena);
  DistanceIndex index;
  SPLINTCORE_ASSERT_OK(build_distance_index(ctx, mesh, DistanceIndexOptions{}, &index));
  EXPECT_FALSE(index.closed_manifold);
  ClosestPoint cp;
  EXPECT_FALSE(closest_point(index, Vec3{1, 2, 3}, &cp));
  EXPECT_EQ(winding_number(index, Vec3{1, 2, 3}), 0.0);
  EXPECT_EQ(winding_number(index, Vec3{1, 2, 3}, 0), 0.0);
  SignedDistance sd;
  EXPECT_FALSE(signed_distance(index, Vec3{}, SignMethod::kAuto, &sd));
  RayHit hit;
  EXPECT_FALSE(ray_intersect(index, Vec3{}, Vec3{1, 0, 0}, HUGE_VAL, &hit));
  uint32_t tri = 7;
  EXPECT_FALSE(segment_intersects_mesh(index, Vec3{}, Vec3{1, 1, 1}, &tri));
  EXPECT_EQ(tri, 7u);
  Aabb box;
  box.add(Vec3{-10, -10, -10});
  box.add(Vec3{10, 10, 10});
  ArenaArray<uint32_t> ids(&t.arena);
  SPLINTCORE_ASSERT_OK(triangles_in_box(ctx, index, box, &ids));
  EXPECT_EQ(ids.size(), 0u);
  std::vector<Vec3> q(3, Vec3{1, 1, 1});
  std::vector<ClosestPoint> r(3);
  r[1].distance = 5;
  SPLINTCORE_ASSERT_OK(batch_closest_points(ctx, index, Span<const Vec3>(q.data(), 3),
                                            Span<ClosestPoint>(r.data(), 3)));
  EXPECT_EQ(r[1].distance, 0.0);
  std::vector<double> d(3);
  SPLINTCORE_ASSERT_OK(batch_signed_distances(ctx, index, Span<const Vec3>(q.data(), 3),
                                              SignMethod::kAuto, Span<double>(d.data(), 3)));
  EXPECT_EQ(d[0], HUGE_VAL);
  SdfGrid g;
  g.spacing = 1;
  g.nx = g.ny = g.nz = 2;
  g.band = 0.5;
  std::vector<float> v(8);
  SPLINTCORE_ASSERT_OK(
      sample_sdf(ctx, index, g, SignMethod::kAuto, 0, 2, Span<float>(v.data(), 8)));
  for (float x : v) EXPECT_EQ(x, 0.5f);
  // A mesh with vertices and no triangles is empty too.
  ASSERT_TRUE(mesh.vertices.push_back(Vec3{1, 2, 3}));
  SPLINTCORE_ASSERT_OK(build_distance_index(ctx, mesh, DistanceIndexOptions{}, &index));
  EXPECT_FALSE(closest_point(index, Vec3{}, &cp));
}

TEST(DistanceBuild, BadMeshesAndOptions) {
  TestArena t;
  Context ctx(&t.arena);
  Mesh mesh;
  ASSERT_TRUE(test::mesh_from_soup(t.arena, box_soup(Vec3{0, 0, 0}, Vec3{1, 1, 1}), &mesh).is_ok());
  DistanceIndex index;
  mesh.triangles[5].v[1] = static_cast<uint32_t>(mesh.vertices.size());
  Status s = build_distance_index(ctx, mesh, DistanceIndexOptions{}, &index);
  EXPECT_EQ(s.code(), StatusCode::kInvalidMesh);
  EXPECT_EQ(s.index(), 5u);
  mesh.triangles[5].v[1] = 0;
  for (double bad : {static_cast<double>(NAN), HUGE_VAL, -HUGE_VAL}) {
    const Vec3 keep = mesh.vertices[3];
    mesh.vertices[3].y = bad;
    s = build_distance_index(ctx, mesh, DistanceIndexOptions{}, &index);
    EXPECT_EQ(s.code(), StatusCode::kInvalidMesh);
    EXPECT_EQ(s.index(), 3u);
    mesh.vertices[3] = keep;
  }
  DistanceIndexOptions options;
  options.leaf_size = 17;
  EXPECT_EQ(build_distance_index(ctx, mesh, options, &index).code(), StatusCode::kInvalidArgument);
  // Cancellation.
  Progress stop;
  stop.report = [](void*, const char*, uint64_t, uint64_t) { return false; };
  Context cancelled(&t.arena, nullptr, &stop);
  EXPECT_EQ(build_distance_index(cancelled, mesh, DistanceIndexOptions{}, &index).code(),
            StatusCode::kCancelled);
}

TEST(DistanceBuild, ClosedManifoldFlag) {
  Rng rng(0x5eed0060);
  for (const CurvedCase& c : curved_cases())
    EXPECT_TRUE(build(c.soup)->index.closed_manifold) << c.name;
  EXPECT_TRUE(build(box_soup(Vec3{0, 0, 0}, Vec3{1, 2, 3}))->index.closed_manifold);
  Soup s = icosphere(1, 1, Vec3{});
  Soup open(s.begin() + 1, s.end());
  EXPECT_FALSE(build(open)->index.closed_manifold);
  Soup flipped = s;
  std::swap(flipped[3].p[0], flipped[3].p[1]);  // one triangle inside out
  EXPECT_FALSE(build(flipped)->index.closed_manifold);
  Soup doubled = s;
  doubled.push_back(s[0]);  // an edge used three times
  EXPECT_FALSE(build(doubled)->index.closed_manifold);
  EXPECT_FALSE(build(random_soup(rng, 20, 30, 1))->index.closed_manifold);
}

// Edge neighbours against brute force, on indexed meshes made to break them: few vertices
// (an edge used from zero to several times, either way), corners repeated in a triangle (a->a,
// a->b->a), and hubs of more than 32 corners (the sorted-list path: a hub's edges to small and
// to other hub vertices). A half-edge a->b (a != b) has a neighbour when the mesh holds a->b
// once and b->a once: the triangle of b->a.
TEST(DistanceBuild, NeighboursMatchBruteForce) {
  Rng rng(0x5eed0070);
  uint32_t linked = 0, linked_long = 0;
  for (int round = 0; round < 80; ++round) {
    TestArena t(size_t{8} << 20);
    Mesh mesh(&t.arena);
    const uint32_t nv = 3 + rng.below(round < 40 ? 8 : 60);
    for (uint32_t i = 0; i < nv; ++i) {
      ASSERT_TRUE(mesh.vertices.push_back(rng.in_box(Vec3{-1, -1, -1}, Vec3{1, 1, 1})));
    }
    const uint32_t hubs = round % 4 == 0 ? 0 : 1 + rng.below(3);
    const uint32_t nt = 1 + rng.below(round < 40 ? 30 : 400);
    for (uint32_t k = 0; k < nt; ++k) {
      Triangle tri;
      const uint32_t shape = rng.below(10);
      if (shape < 4 && hubs > 0) {
        // A fan piece around a hub: (hub, i, i + 1), mostly manifold, with the other hubs
        // among the rim.
        const uint32_t i = rng.below(nv - 1);
        tri = Triangle{{rng.below(hubs), i, i + 1}};
      } else if (shape < 5) {
        const uint32_t a = rng.below(nv), b = rng.below(nv);
        tri = Triangle{{a, b, rng.below(2) == 0 ? a : b}};  // a repeated corner
      } else {
        tri = Triangle{{rng.below(nv), rng.below(nv), rng.below(nv)}};
      }
      if (rng.below(2) == 0) std::swap(tri.v[1], tri.v[2]);
      ASSERT_TRUE(mesh.triangles.push_back(tri));
    }
    Context ctx(&t.arena);
    DistanceIndex index;
    SPLINTCORE_ASSERT_OK(build_distance_index(ctx, mesh, DistanceIndexOptions{}, &index));
    const std::vector<Triangle> tris(mesh.triangles.begin(), mesh.triangles.end());
    bool closed = !tris.empty();
    const auto degree = [&](uint32_t v) {
      return index.vertex_start[v + 1] - index.vertex_start[v];
    };
    for (uint32_t tt = 0; tt < tris.size(); ++tt) {
      for (uint32_t k = 0; k < 3; ++k) {
        const uint32_t a = tris[tt].v[k], b = tris[tt].v[(k + 1) % 3];
        uint32_t same = 0, reverse = 0, other = kNoNeighbor;
        for (uint32_t u = 0; u < tris.size(); ++u) {
          for (uint32_t j = 0; j < 3; ++j) {
            const uint32_t x = tris[u].v[j], y = tris[u].v[(j + 1) % 3];
            if (x == a && y == b) ++same;
            if (x == b && y == a) {
              ++reverse;
              other = u;
            }
          }
        }
        const uint32_t expected = a != b && same == 1 && reverse == 1 ? other : kNoNeighbor;
        ASSERT_EQ(index.neighbors[3 * size_t{tt} + k], expected)
            << "round " << round << ", triangle " << tt << ", edge " << k;
        closed = closed && expected != kNoNeighbor;
        if (expected == kNoNeighbor) continue;
        ++linked;
        if (degree(a) > 32 || degree(b) > 32) ++linked_long;
      }
    }
    EXPECT_EQ(index.closed_manifold, closed) << "round " << round;
  }
  // The cases reach both paths: edges linked from short lists and from long ones.
  EXPECT_GT(linked, 100u);
  EXPECT_GT(linked_long, 10u);
}

// A closed mesh whose two poles have 100 corners each (the sorted-list path on both ends of
// no edge, and on one end of 200): a closed manifold, every neighbour across the same edge.
TEST(DistanceBuild, NeighboursAroundHighDegreePoles) {
  TestArena t(size_t{8} << 20);
  Mesh mesh(&t.arena);
  const uint32_t n = 100;
  ASSERT_TRUE(mesh.vertices.push_back(Vec3{0, 0, 1}));   // 0: top
  ASSERT_TRUE(mesh.vertices.push_back(Vec3{0, 0, -1}));  // 1: bottom
  for (uint32_t i = 0; i < n; ++i) {
    const double a = 6.283185307179586 * i / n;
    ASSERT_TRUE(mesh.vertices.push_back(Vec3{std::cos(a), std::sin(a), 0}));
  }
  for (uint32_t i = 0; i < n; ++i) {
    const uint32_t p = 2 + i, q = 2 + (i + 1) % n;
    ASSERT_TRUE(mesh.triangles.push_back(Triangle{{0, p, q}}));
    ASSERT_TRUE(mesh.triangles.push_back(Triangle{{1, q, p}}));
  }
  Context ctx(&t.arena);
  DistanceIndex index;
  SPLINTCORE_ASSERT_OK(build_distance_index(ctx, mesh, DistanceIndexOptions{}, &index));
  EXPECT_TRUE(index.closed_manifold);
  for (uint32_t i = 0; i < n; ++i) {
    const uint32_t top = 2 * i, bottom = 2 * i + 1;
    EXPECT_EQ(index.neighbors[3 * top + 0], 2 * ((i + n - 1) % n));  // edge 0 -> p
    EXPECT_EQ(index.neighbors[3 * top + 1], bottom);                 // edge p -> q
    EXPECT_EQ(index.neighbors[3 * top + 2], 2 * ((i + 1) % n));      // edge q -> 0
    EXPECT_EQ(index.neighbors[3 * bottom + 1], top);
  }
}

struct IndexBytes {
  std::vector<uint8_t> bytes;
  bool closed = false;
};
IndexBytes snapshot(const DistanceIndex& x) {
  IndexBytes s;
  auto add = [&](const void* p, size_t n) {
    const uint8_t* b = static_cast<const uint8_t*>(p);
    s.bytes.insert(s.bytes.end(), b, b + n);
  };
  add(x.nodes.data(), x.nodes.size() * sizeof(BvhNode));
  add(x.dipoles.data(), x.dipoles.size() * sizeof(BvhDipole));
  add(x.obbs.data(), x.obbs.size() * sizeof(BvhObb));
  add(x.order.data(), x.order.size() * sizeof(uint32_t));
  add(x.neighbors.data(), x.neighbors.size() * sizeof(uint32_t));
  add(x.vertex_start.data(), x.vertex_start.size() * sizeof(uint32_t));
  add(x.vertex_uses.data(), x.vertex_uses.size() * sizeof(uint32_t));
  s.closed = x.closed_manifold;
  return s;
}

TEST(DistanceBuild, ArenaBoundCoversTheHighWater) {
  Rng rng(0x5eed0061);
  std::vector<Soup> soups = {Soup{},
                             box_soup(Vec3{0, 0, 0}, Vec3{1, 1, 1}),
                             icosphere(0, 1, Vec3{}),
                             icosphere(2, 1, Vec3{}),
                             icosphere(4, 1, Vec3{}),
                             shapes::torus(40, 20, 5, 1),
                             random_soup(rng, 50, 333, 2),
                             random_soup(rng, 500, 3001, 2)};
  for (const Soup& soup : soups) {
    TestArena t;
    Mesh mesh;
    ASSERT_TRUE(test::mesh_from_soup(t.arena, soup, &mesh).is_ok());
    for (uint32_t leaf : {0u, 1u, 2u, 3u, 4u, 7u, 16u}) {
      for (int kind = 0; kind < 6; ++kind) {
        const bool oriented = (kind & 1) != 0;
        DistanceIndexOptions options;
        options.leaf_size = leaf;
        options.oriented_boxes = oriented;
        options.pairs_only = (kind & 2) != 0;
        options.winding_only = kind >= 4;
        const Arena::Marker m = t.arena.mark();
        t.arena.reset_high_water();
        const size_t before = t.arena.used();
        Context ctx(&t.arena);
        DistanceIndex index;
        SPLINTCORE_ASSERT_OK(build_distance_index(ctx, mesh, options, &index));
        const uint64_t bound =
            distance_index_bound(mesh.vertices.size(), mesh.triangles.size(), options);
        EXPECT_GE(bound, t.arena.high_water() - before)
            << mesh.triangles.size() << " triangles, leaf " << leaf << " oriented " << oriented
            << " pairs_only " << options.pairs_only << " winding_only " << options.winding_only;
        if (options.winding_only) {
          // The tree and its dipoles only (and the oriented boxes when asked).
          EXPECT_TRUE(index.neighbors.empty());
          EXPECT_TRUE(index.vertex_start.empty());
          EXPECT_TRUE(index.vertex_uses.empty());
          EXPECT_TRUE(index.triangle_boxes.empty());
          EXPECT_EQ(index.dipoles.size(), index.nodes.size());
          EXPECT_EQ(index.obbs.size(), oriented ? index.nodes.size() : 0u);
        } else if (options.pairs_only) {
          // Only the tree: no neighbours, corner lists, and dipoles only for oriented boxes.
          EXPECT_TRUE(index.neighbors.empty());
          EXPECT_TRUE(index.vertex_uses.empty());
          EXPECT_EQ(index.dipoles.size(), oriented ? index.nodes.size() : 0u);
          // Each triangle's float box holds its corners.
          ASSERT_EQ(index.triangle_boxes.size(), 6 * mesh.triangles.size());
          for (size_t j = 0; j < index.order.size(); ++j) {
            const Triangle& tri = mesh.triangles[index.order[j]];
            for (int c = 0; c < 3; ++c) {
              const Vec3& p = mesh.vertices[tri.v[c]];
              for (int a = 0; a < 3; ++a) {
                EXPECT_LE(static_cast<double>(index.triangle_boxes[6 * j + a]), p[a]);
                EXPECT_GE(static_cast<double>(index.triangle_boxes[6 * j + 3 + a]), p[a]);
              }
            }
          }
        }
        t.arena.rewind(m);
      }
    }
  }
}

// A winding_only index (the Boolean's winding numbers) is a full index's tree, order and
// dipoles and nothing else: the same winding numbers and closest points, bit for bit, at
// points inside, outside and near the surface, in less memory (kept, and at the build's peak).
TEST(DistanceBuild, WindingOnlyIndexGivesTheSameBits) {
  Rng rng(0x5eed0063);
  std::vector<Soup> soups = {icosphere(3, 1, Vec3{}), shapes::torus(40, 20, 5, 1),
                             random_soup(rng, 500, 3001, 2)};
  for (const Soup& soup : soups) {
    TestArena t;
    Mesh mesh;
    ASSERT_TRUE(test::mesh_from_soup(t.arena, soup, &mesh).is_ok());
    Context ctx(&t.arena);
    size_t before = t.arena.used();
    t.arena.reset_high_water();
    DistanceIndex full;
    SPLINTCORE_ASSERT_OK(build_distance_index(ctx, mesh, DistanceIndexOptions{}, &full));
    const size_t full_kept = t.arena.used() - before, full_peak = t.arena.high_water() - before;
    before = t.arena.used();
    t.arena.reset_high_water();
    DistanceIndexOptions wo;
    wo.winding_only = true;
    DistanceIndex lean;
    SPLINTCORE_ASSERT_OK(build_distance_index(ctx, mesh, wo, &lean));
    const size_t lean_kept = t.arena.used() - before, lean_peak = t.arena.high_water() - before;
    EXPECT_LT(lean_kept, full_kept);
    EXPECT_LT(lean_peak, full_peak);
    ASSERT_EQ(lean.nodes.size(), full.nodes.size());
    ASSERT_EQ(lean.order.size(), full.order.size());
    EXPECT_EQ(
        std::memcmp(lean.nodes.data(), full.nodes.data(), full.nodes.size() * sizeof(BvhNode)), 0);
    EXPECT_EQ(std::memcmp(lean.dipoles.data(), full.dipoles.data(),
                          full.dipoles.size() * sizeof(BvhDipole)),
              0);
    EXPECT_EQ(
        std::memcmp(lean.order.data(), full.order.data(), full.order.size() * sizeof(uint32_t)), 0);
    const Aabb box = mesh_bounds(mesh);
    const Vec3 pad = box.extent() * 0.25;
    for (int i = 0; i < 300; ++i) {
      const Vec3 q = rng.in_box(box.lo - pad, box.hi + pad);
      const double wf = winding_number(full, q), wl = winding_number(lean, q);
      EXPECT_EQ(std::memcmp(&wf, &wl, sizeof wf), 0) << "winding number at query " << i;
      ClosestPoint cf, cl;
      ASSERT_TRUE(closest_point(full, q, &cf));
      ASSERT_TRUE(closest_point(lean, q, &cl));
      EXPECT_EQ(cf.triangle, cl.triangle) << "query " << i;
      EXPECT_EQ(std::memcmp(&cf.distance, &cl.distance, sizeof cf.distance), 0) << "query " << i;
    }
  }
}

TEST(DistanceBuild, ArenaExhaustionLoop) {
  Rng rng(0x5eed0062);
  for (const Soup& soup : {icosphere(1, 2, Vec3{}), random_soup(rng, 40, 100, 2)}) {
    for (bool oriented : {false, true}) {
      DistanceIndexOptions options;
      options.oriented_boxes = oriented;
      TestArena t;
      Mesh mesh;
      ASSERT_TRUE(test::mesh_from_soup(t.arena, soup, &mesh).is_ok());
      DistanceIndex want_index;
      Context big(&t.arena);
      SPLINTCORE_ASSERT_OK(build_distance_index(big, mesh, options, &want_index));
      const IndexBytes want = snapshot(want_index);
      const uint64_t bound =
          distance_index_bound(mesh.vertices.size(), mesh.triangles.size(), options);
      std::unique_ptr<unsigned char[]> buffer(new unsigned char[bound + 64]);
      const size_t step = 16;  // the index of 100 triangles takes a few kB: over 100 caps fail
      size_t cap = 0;
      int failures = 0;
      for (;; cap += step) {
        ASSERT_LE(cap, bound + 64) << "no success within the bound";
        Arena arena(buffer.get(), cap);
        Context ctx(&arena);
        DistanceIndex index;
        Status s = build_distance_index(ctx, mesh, options, &index);
        if (s.is_ok()) {
          const IndexBytes got = snapshot(index);
          EXPECT_EQ(got.bytes, want.bytes);
          EXPECT_EQ(got.closed, want.closed);
          break;
        }
        ASSERT_EQ(s.code(), StatusCode::kArenaExhausted) << cap << ": " << test::format(s);
        ++failures;
      }
      EXPECT_GT(failures, 100);
      std::printf(
          "[ info ] %zu triangles: %d caps exhausted, first success at %zu bytes, bound %llu\n",
          mesh.triangles.size(), failures, cap, static_cast<unsigned long long>(bound));
    }
  }
}

}  // namespace
}  // namespace splintcore
