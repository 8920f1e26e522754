// Tests of the mesh-to-mesh distance (src/distance/pair.cpp): exact small cases with closed-form
// answers, a brute-force oracle over every triangle pair with its own point-triangle distance
// (projection onto the plane, else the nearest clamped edge) and its own segment-segment
// distance (the interior critical point by Cramer's rule, else the four endpoint-to-segment
// distances), independence of the trees' shapes (leaf sizes, oriented boxes), the arena bound,
// and the real dentition when present.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "common/shapes.h"
#include "splintcore/distance.h"
#include "splintcore/platform.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

using Soup = std::vector<SoupTriangle>;

// ---------------------------------------------------------------------------------------------
// The oracle.

double point_segment_d2(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 ab = b - a;
  const double len2 = dot(ab, ab);
  double t = len2 > 0 ? dot(p - a, ab) / len2 : 0;
  t = t < 0 ? 0 : (t > 1 ? 1 : t);
  const Vec3 q = a + ab * t;
  return length_squared(p - q);
}

double point_triangle_d2(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 n = cross(b - a, c - a);
  const double n2 = dot(n, n);
  if (n2 > 0) {
    const bool inside = dot(cross(b - a, p - a), n) >= 0 && dot(cross(c - b, p - b), n) >= 0 &&
                        dot(cross(a - c, p - c), n) >= 0;
    if (inside) {
      const double h = dot(p - a, n);
      return h * h / n2;
    }
  }
  const double d0 = point_segment_d2(p, a, b), d1 = point_segment_d2(p, b, c);
  const double d2 = point_segment_d2(p, c, a);
  return std::min(d0, std::min(d1, d2));
}

double segment_segment_d2(const Vec3& p0, const Vec3& p1, const Vec3& q0, const Vec3& q1) {
  double best = std::min(std::min(point_segment_d2(p0, q0, q1), point_segment_d2(p1, q0, q1)),
                         std::min(point_segment_d2(q0, p0, p1), point_segment_d2(q1, p0, p1)));
  // Interior critical point: (p(s) - q(t)) orthogonal to both directions.
  const Vec3 u = p1 - p0, v = q1 - q0, w = p0 - q0;
  const double uu = dot(u, u), uv = dot(u, v), vv = dot(v, v), uw = dot(u, w), vw = dot(v, w);
  const double det = uu * vv - uv * uv;
  if (det > 1e-12 * uu * vv) {
    const double s = (uv * vw - vv * uw) / det, t = (uu * vw - uv * uw) / det;
    if (s > 0 && s < 1 && t > 0 && t < 1) {
      best = std::min(best, length_squared((p0 + u * s) - (q0 + v * t)));
    }
  }
  return best;
}

double oracle_pair_d2(const Vec3 a[3], const Vec3 b[3]) {
  if (triangles_intersect(a[0], a[1], a[2], b[0], b[1], b[2])) return 0;
  double best = HUGE_VAL;
  for (int i = 0; i < 3; ++i) {
    best = std::min(best, point_triangle_d2(a[i], b[0], b[1], b[2]));
    best = std::min(best, point_triangle_d2(b[i], a[0], a[1], a[2]));
    for (int j = 0; j < 3; ++j) {
      best = std::min(best, segment_segment_d2(a[i], a[(i + 1) % 3], b[j], b[(j + 1) % 3]));
    }
  }
  return best;
}

struct OracleResult {
  double d = HUGE_VAL;
  uint32_t ta = 0, tb = 0;  // the smallest pair within 1e-9 relative of the least distance
  uint32_t near = 0;        // how many pairs are that close
};

struct TriangleCorners {
  Vec3 p[3], lo, hi;
};

std::vector<TriangleCorners> corners_of(const Mesh& m, const Vec3& offset) {
  std::vector<TriangleCorners> out(m.triangles.size());
  for (size_t i = 0; i < out.size(); ++i) {
    for (int k = 0; k < 3; ++k) out[i].p[k] = m.vertices[m.triangles[i].v[k]] + offset;
    out[i].lo = min_vec(min_vec(out[i].p[0], out[i].p[1]), out[i].p[2]);
    out[i].hi = max_vec(max_vec(out[i].p[0], out[i].p[1]), out[i].p[2]);
  }
  return out;
}

double box_gap2(const TriangleCorners& a, const TriangleCorners& b) {
  double sum = 0;
  for (int i = 0; i < 3; ++i) {
    const double g = std::max(0.0, std::max(b.lo[i] - a.hi[i], a.lo[i] - b.hi[i]));
    sum += g * g;
  }
  return sum;
}

// Every pair, skipping those whose boxes are farther apart than the best so far (the box gap
// is a lower bound of the distance), then every pair within 1e-9 relative of the least.
OracleResult brute_force(const Mesh& a, const Mesh& b, const Vec3& offset) {
  const std::vector<TriangleCorners> x = corners_of(a, Vec3{}), y = corners_of(b, offset);
  double best2 = HUGE_VAL;
  for (size_t i = 0; i < x.size(); ++i) {
    for (size_t j = 0; j < y.size(); ++j) {
      if (box_gap2(x[i], y[j]) > best2) continue;
      best2 = std::min(best2, oracle_pair_d2(x[i].p, y[j].p));
    }
  }
  OracleResult r;
  r.d = std::sqrt(best2);
  const double tie2 = best2 * (1 + 2e-9) + 1e-24;
  for (uint32_t i = 0; i < x.size(); ++i) {
    for (uint32_t j = 0; j < y.size(); ++j) {
      if (box_gap2(x[i], y[j]) > tie2 || oracle_pair_d2(x[i].p, y[j].p) > tie2) continue;
      if (r.near++ == 0) {
        r.ta = i;
        r.tb = j;
      }
    }
  }
  return r;
}

double oracle_triangle_pair(const Mesh& a, uint32_t ta, const Mesh& b, uint32_t tb,
                            const Vec3& offset) {
  Vec3 x[3], y[3];
  for (int k = 0; k < 3; ++k) {
    x[k] = a.vertices[a.triangles[ta].v[k]];
    y[k] = b.vertices[b.triangles[tb].v[k]] + offset;
  }
  return std::sqrt(oracle_pair_d2(x, y));
}

// ---------------------------------------------------------------------------------------------
// Shapes.

// A closed UV sphere (u x v, poles as fans) with its radius jittered per vertex by up to
// `bump`: a closed mesh whose triangles face every way.
Soup bumpy_sphere(uint32_t u, uint32_t v, double radius, double bump, const Vec3& c,
                  uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> jitter(-bump, bump);
  const double kPi = 3.141592653589793;
  std::vector<Vec3> p;
  p.push_back(c + Vec3{0, 0, radius + jitter(rng)});
  for (uint32_t i = 1; i < v; ++i) {
    for (uint32_t j = 0; j < u; ++j) {
      const double th = kPi * i / v, ph = 2 * kPi * j / u, r = radius + jitter(rng);
      p.push_back(c + Vec3{r * std::sin(th) * std::cos(ph), r * std::sin(th) * std::sin(ph),
                           r * std::cos(th)});
    }
  }
  p.push_back(c + Vec3{0, 0, -radius + jitter(rng)});
  const auto ring = [&](uint32_t i, uint32_t j) { return 1 + (i - 1) * u + (j % u); };
  const auto tri = [&](uint32_t x, uint32_t y, uint32_t z) {
    SoupTriangle t;
    const uint32_t id[3] = {x, y, z};
    for (int k = 0; k < 3; ++k) {
      t.p[k][0] = static_cast<float>(p[id[k]].x);
      t.p[k][1] = static_cast<float>(p[id[k]].y);
      t.p[k][2] = static_cast<float>(p[id[k]].z);
    }
    return t;
  };
  Soup out;
  const uint32_t south = static_cast<uint32_t>(p.size() - 1);
  for (uint32_t j = 0; j < u; ++j) {
    out.push_back(tri(0, ring(1, j), ring(1, j + 1)));
    out.push_back(tri(south, ring(v - 1, j + 1), ring(v - 1, j)));
  }
  for (uint32_t i = 1; i + 1 < v; ++i) {
    for (uint32_t j = 0; j < u; ++j) {
      out.push_back(tri(ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)));
      out.push_back(tri(ring(i, j), ring(i + 1, j + 1), ring(i, j + 1)));
    }
  }
  return out;
}

// The torus of shapes.h stood up: y and z swapped (a chain link through the lying one).
Soup standing(Soup s) {
  for (SoupTriangle& t : s) {
    for (int k = 0; k < 3; ++k) std::swap(t.p[k][1], t.p[k][2]);
  }
  return s;
}

struct Built {
  Mesh mesh;
  DistanceIndex index;
};

void build(test::TestArena& t, const Soup& soup, uint32_t leaf, bool oriented, Built* out,
           bool pairs_only = false) {
  ASSERT_TRUE(test::mesh_from_soup(t.arena, soup, &out->mesh).is_ok());
  DistanceIndexOptions o;
  o.leaf_size = leaf;
  o.oriented_boxes = oriented;
  o.pairs_only = pairs_only;
  const Status s = build_distance_index(Context(&t.arena), out->mesh, o, &out->index);
  ASSERT_TRUE(s.is_ok()) << test::format(s);
}

MeshPairDistance run_pair(const Built& a, const Built& b, const Vec3& offset,
                          double max_distance = HUGE_VAL, const Executor* executor = nullptr) {
  test::TestArena t(size_t{1} << 20);
  MeshPairDistance r;
  const Status s = mesh_pair_distance(Context(&t.arena, executor, nullptr), a.index, b.index,
                                      offset, max_distance, &r);
  EXPECT_TRUE(s.is_ok()) << test::format(s);
  EXPECT_EQ(t.arena.used(), 0u);
  return r;
}

// `r` is the answer `e` is, bit for bit.
void expect_same_pair(const MeshPairDistance& r, const MeshPairDistance& e) {
  EXPECT_EQ(std::memcmp(&r.distance, &e.distance, sizeof(double)), 0)
      << r.distance << " " << e.distance;
  EXPECT_EQ(r.triangle_a, e.triangle_a);
  EXPECT_EQ(r.triangle_b, e.triangle_b);
  EXPECT_EQ(r.point_a, e.point_a);
  EXPECT_EQ(r.point_b, e.point_b);
  EXPECT_EQ(r.intersecting, e.intersecting);
}

// ---------------------------------------------------------------------------------------------
// Exact small cases.

TEST(TrianglePairDistance, ParallelTrianglesAtKnownSeparation) {
  Vec3 pa, pb;
  const double d = triangle_pair_distance({0, 0, 0}, {4, 0, 0}, {0, 4, 0}, {1, 1, 2.5}, {3, 1, 2.5},
                                          {1, 3, 2.5}, &pa, &pb);
  EXPECT_EQ(d, 2.5);
  EXPECT_EQ(pa.z, 0.0);
  EXPECT_EQ(pb.z, 2.5);
  EXPECT_EQ(pa.x, pb.x);
  EXPECT_EQ(pa.y, pb.y);
}

TEST(TrianglePairDistance, CrossedSkewEdges) {
  // Edge A: (0,0,0)-(2,1,0); edge B: (0,2,1)-(2,0,3). The third corners lie away from the
  // other triangle along the common perpendicular, so the closest pair is interior to both
  // edges: distance |(q0 - p0) . (d1 x d2)| / |d1 x d2|.
  const Vec3 p0{0, 0, 0}, p1{2, 1, 0}, q0{0, 2, 1}, q1{2, 0, 3};
  const Vec3 n = cross(p1 - p0, q1 - q0);
  const double expect = std::fabs(dot(q0 - p0, n)) / length(n);
  const Vec3 u = n * ((dot(q0 - p0, n) > 0 ? 1.0 : -1.0) / length(n));  // from A toward B
  const Vec3 a2 = (p0 + p1) * 0.5 - u * 3.0, b2 = (q0 + q1) * 0.5 + u * 3.0;
  Vec3 pa, pb;
  const double d = triangle_pair_distance(p0, p1, a2, q0, q1, b2, &pa, &pb);
  EXPECT_NEAR(d, expect, 1e-15 * expect);
  EXPECT_NEAR(length(pa - pb), expect, 1e-15 * expect);
  // Both points interior to their edges.
  EXPECT_LT(length(cross(pa - p0, p1 - p0)), 1e-14);
  EXPECT_LT(length(cross(pb - q0, q1 - q0)), 1e-14);
  EXPECT_GT(dot(pa - p0, p1 - p0), 0.1);
  EXPECT_GT(dot(pb - q0, q1 - q0), 0.1);
  // An axis-aligned cross: exactly 0.75.
  EXPECT_EQ(triangle_pair_distance({-1, 0, 0}, {1, 0, 0}, {0, 0, -1}, {0, -1, 0.75}, {0, 1, 0.75},
                                   {0, 0, 1.75}, nullptr, nullptr),
            0.75);
}

TEST(TrianglePairDistance, VertexFace) {
  Vec3 pa, pb;
  const double d = triangle_pair_distance({-5, -5, 0}, {5, -5, 0}, {0, 5, 0}, {0.5, 0.25, 1.5},
                                          {2, 1, 3}, {-1, 2, 3}, &pa, &pb);
  EXPECT_EQ(d, 1.5);
  // The foot of the vertex on the face: exact in z, to rounding in x and y (barycentrics).
  EXPECT_EQ(pa.z, 0.0);
  EXPECT_NEAR(pa.x, 0.5, 1e-15);
  EXPECT_NEAR(pa.y, 0.25, 1e-15);
  EXPECT_EQ(pb, (Vec3{0.5, 0.25, 1.5}));
  // The other way round: the face is B's.
  EXPECT_EQ(triangle_pair_distance({0.5, 0.25, 1.5}, {2, 1, 3}, {-1, 2, 3}, {-5, -5, 0}, {5, -5, 0},
                                   {0, 5, 0}, &pa, &pb),
            1.5);
  EXPECT_EQ(pa, (Vec3{0.5, 0.25, 1.5}));
  EXPECT_EQ(pb.z, 0.0);
  EXPECT_NEAR(pb.x, 0.5, 1e-15);
}

TEST(TrianglePairDistance, IntersectingAndTouchingGiveZero) {
  Vec3 pa, pb;
  // B pierces A's interior: no vertex or edge pair is at distance 0.
  EXPECT_EQ(triangle_pair_distance({-5, -5, 0}, {5, -5, 0}, {0, 5, 0}, {0.5, 0.25, -1},
                                   {0.5, 0.25, 1}, {3, 3, 1}, &pa, &pb),
            0.0);
  // The common point: where A's edge (5,-5,0)-(0,5,0) crosses B (first in edge order).
  EXPECT_EQ(pa, pb);
  EXPECT_EQ(pa.z, 0.0);
  EXPECT_NEAR(pa.x, 5 - 5 * (10.2 / 15.5), 1e-14);
  EXPECT_NEAR(pa.y, -5 + 10 * (10.2 / 15.5), 1e-14);
  // Touching at a vertex, and coplanar overlapping.
  EXPECT_EQ(triangle_pair_distance({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 0, 0}, {2, 0, 1}, {2, 1, 0},
                                   &pa, &pb),
            0.0);
  EXPECT_EQ(triangle_pair_distance({0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {0.5, 0.5, 0}, {3, 0.5, 0},
                                   {0.5, 3, 0}, &pa, &pb),
            0.0);
  EXPECT_LT(std::fabs(pa.z) + std::fabs(pb.z), 1e-15);
  // A degenerate triangle (a segment) piercing a face.
  EXPECT_EQ(triangle_pair_distance({-5, -5, 0}, {5, -5, 0}, {0, 5, 0}, {1, 1, -1}, {1, 1, 1},
                                   {1, 1, 0.5}, &pa, &pb),
            0.0);
  EXPECT_EQ(pa, (Vec3{1, 1, 0}));
}

TEST(MeshPairDistance, ArgumentsAndEmptyMeshes) {
  test::TestArena t(size_t{16} << 20);
  Built a, empty;
  build(t, shapes::torus(12, 8, 10, 3), 0, false, &a);
  build(t, Soup{}, 0, false, &empty);
  MeshPairDistance r;
  const Context ctx(&t.arena);
  EXPECT_EQ(mesh_pair_distance(ctx, a.index, a.index, {HUGE_VAL, 0, 0}, 1, &r).code(),
            StatusCode::kInvalidArgument);
  EXPECT_EQ(mesh_pair_distance(ctx, a.index, a.index, {0, 0, 0}, -1, &r).code(),
            StatusCode::kInvalidArgument);
  EXPECT_EQ(mesh_pair_distance(ctx, a.index, a.index, {0, 0, 0}, std::nan(""), &r).code(),
            StatusCode::kInvalidArgument);
  ASSERT_TRUE(mesh_pair_distance(ctx, a.index, empty.index, {0, 0, 0}, HUGE_VAL, &r).is_ok());
  EXPECT_EQ(r.distance, HUGE_VAL);
  ASSERT_TRUE(mesh_pair_distance(ctx, empty.index, a.index, {0, 0, 0}, HUGE_VAL, &r).is_ok());
  EXPECT_EQ(r.distance, HUGE_VAL);
  // Beyond max_distance: nothing; within: the pair.
  ASSERT_TRUE(mesh_pair_distance(ctx, a.index, a.index, {0, 0, 40}, 30, &r).is_ok());
  EXPECT_EQ(r.distance, HUGE_VAL);
  ASSERT_TRUE(mesh_pair_distance(ctx, a.index, a.index, {0, 0, 40}, 40, &r).is_ok());
  EXPECT_NEAR(r.distance, 34, 1e-6);  // tube tops at z = 3, bottoms at 40 - 3
  // Two unit boxes face to face (touching counts as meeting) and 0.5 apart.
  const float lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
  Built box;
  build(t, shapes::box(lo, hi), 0, false, &box);
  ASSERT_TRUE(mesh_pair_distance(ctx, box.index, box.index, {1, 0, 0}, HUGE_VAL, &r).is_ok());
  EXPECT_EQ(r.distance, 0.0);
  EXPECT_TRUE(r.intersecting);
  ASSERT_TRUE(
      mesh_pair_distance(ctx, box.index, box.index, {1.5, 0.25, -0.5}, HUGE_VAL, &r).is_ok());
  EXPECT_EQ(r.distance, 0.5);
  EXPECT_FALSE(r.intersecting);
  EXPECT_EQ(r.point_b.x - r.point_a.x, 0.5);
}

// ---------------------------------------------------------------------------------------------
// Against the oracle.

struct Case {
  Soup a, b;
  std::vector<Vec3> offsets;
};

std::vector<Case> oracle_cases() {
  std::vector<Case> cases;
  std::mt19937_64 rng(20240611);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  // Chain links: the standing torus through the lying one at some offsets, beside it at others.
  Case links{shapes::torus(24, 12, 10, 3), standing(shapes::torus(20, 10, 9, 2.5)), {}};
  links.offsets = {{10, 0, 0}, {10, 0, 5}, {0, 0, 0}, {22.5, 0, 0}, {23, 1, 0}, {0, 30, 1}};
  for (int k = 0; k < 6; ++k)
    links.offsets.push_back({20 * unit(rng), 20 * unit(rng), 12 * unit(rng)});
  cases.push_back(links);
  // Bumpy spheres (several seeds), apart, near, and overlapping.
  for (uint64_t seed = 1; seed <= 3; ++seed) {
    Case c{bumpy_sphere(20, 12, 8, 0.6, {0, 0, 0}, seed),
           bumpy_sphere(16, 14, 6, 0.5, {0, 0, 0}, seed + 100),
           {}};
    c.offsets = {{14.5, 0, 0}, {0, 13.9, 1}, {3, 4, 5}, {0, 0, 30}};
    for (int k = 0; k < 4; ++k) {
      Vec3 dir{unit(rng), unit(rng), unit(rng)};
      dir = dir * (1.0 / length(dir));
      c.offsets.push_back(dir * (15.0 + 4.0 * unit(rng)));
    }
    cases.push_back(c);
  }
  return cases;
}

TEST(MeshPairDistance, MatchesBruteForce) {
  int unique = 0, zero = 0, apart = 0;
  for (const Case& c : oracle_cases()) {
    test::TestArena t(size_t{32} << 20);
    Built a, b;
    build(t, c.a, 0, false, &a);
    build(t, c.b, 0, false, &b);
    for (const Vec3& off : c.offsets) {
      const OracleResult o = brute_force(a.mesh, b.mesh, off);
      const MeshPairDistance r = run_pair(a, b, off);
      SCOPED_TRACE(testing::Message() << "offset " << off.x << " " << off.y << " " << off.z);
      EXPECT_NEAR(r.distance, o.d, 1e-12 * o.d + 1e-13);
      if (o.d == 0) {
        ++zero;
        // The smallest meeting pair, by (triangle a, triangle b): the oracle's first.
        EXPECT_TRUE(r.intersecting);
        EXPECT_EQ(r.triangle_a, o.ta);
        EXPECT_EQ(r.triangle_b, o.tb);
        EXPECT_EQ(r.point_a, r.point_b);
      } else {
        ++apart;
        EXPECT_FALSE(r.intersecting);
        EXPECT_NEAR(length(r.point_a - r.point_b), r.distance, 1e-12 * r.distance);
        // The library's pair is as close by the oracle's own measure; when no other pair is
        // within 1e-9, it is the oracle's pair.
        EXPECT_NEAR(oracle_triangle_pair(a.mesh, r.triangle_a, b.mesh, r.triangle_b, off), o.d,
                    1e-12 * o.d + 1e-13);
        if (o.near == 1) {
          ++unique;
          EXPECT_EQ(r.triangle_a, o.ta);
          EXPECT_EQ(r.triangle_b, o.tb);
        }
        // The points lie on their triangles (moved for B).
        const Triangle& ta = a.mesh.triangles[r.triangle_a];
        const Triangle& tb = b.mesh.triangles[r.triangle_b];
        EXPECT_LT(point_triangle_d2(r.point_a, a.mesh.vertices[ta.v[0]], a.mesh.vertices[ta.v[1]],
                                    a.mesh.vertices[ta.v[2]]),
                  1e-24);
        EXPECT_LT(point_triangle_d2(r.point_b, b.mesh.vertices[tb.v[0]] + off,
                                    b.mesh.vertices[tb.v[1]] + off, b.mesh.vertices[tb.v[2]] + off),
                  1e-24);
      }
    }
  }
  // (A closest pair at a vertex or an edge is shared by the triangles around it: unique pairs
  // are rare.)
  EXPECT_GE(apart, 12);
  std::printf("[   info   ] %d offsets apart (%d with a unique closest pair), %d meeting\n", apart,
              unique, zero);
  EXPECT_GE(zero, 4);
}

// mesh_pair_meet says whether the meshes meet exactly when mesh_pair_distance finds a meeting
// pair, and the pair it gives does meet (triangle_pair_distance, on its own, says 0).
TEST(MeshPairDistance, MeetAgreesWithTheFullSearch) {
  int met = 0, apart = 0;
  for (const Case& c : oracle_cases()) {
    test::TestArena t(size_t{32} << 20);
    Built a, b;
    build(t, c.a, 0, false, &a);
    build(t, c.b, 0, false, &b);
    for (const Vec3& off : c.offsets) {
      SCOPED_TRACE(testing::Message() << "offset " << off.x << " " << off.y << " " << off.z);
      const MeshPairDistance full = run_pair(a, b, off);
      test::TestArena s(size_t{1} << 20);
      bool meet = false;
      MeshPairDistance r;
      const Status st = mesh_pair_meet(Context(&s.arena), a.index, b.index, off, &meet, &r);
      ASSERT_TRUE(st.is_ok()) << test::format(st);
      EXPECT_EQ(s.arena.used(), 0u);
      EXPECT_EQ(meet, full.intersecting);
      if (!meet) {
        ++apart;
        EXPECT_EQ(r.distance, HUGE_VAL);
        continue;
      }
      ++met;
      EXPECT_EQ(r.distance, 0.0);
      EXPECT_TRUE(r.intersecting);
      const Triangle& ta = a.mesh.triangles[r.triangle_a];
      const Triangle& tb = b.mesh.triangles[r.triangle_b];
      const Vec3* va = a.mesh.vertices.data();
      const Vec3* vb = b.mesh.vertices.data();
      EXPECT_EQ(triangle_pair_distance(va[ta.v[0]], va[ta.v[1]], va[ta.v[2]], vb[tb.v[0]] + off,
                                       vb[tb.v[1]] + off, vb[tb.v[2]] + off, nullptr, nullptr),
                0.0);
    }
  }
  EXPECT_GE(met, 4);
  EXPECT_GE(apart, 12);
}

// ---------------------------------------------------------------------------------------------
// Independence of the trees' shapes, and the arena.

TEST(MeshPairDistance, SameBitsAtEveryLeafSizeAndBoxKind) {
  for (const Case& c : oracle_cases()) {
    std::vector<MeshPairDistance> reference;
    bool first = true;
    for (uint32_t leaf : {1u, 4u, 8u, 16u}) {
      for (bool oriented : {false, true}) {
        test::TestArena t(size_t{32} << 20);
        Built a, b;
        // B's shape differs from A's; either index may hold only what the pairs need.
        build(t, c.a, leaf, oriented, &a, leaf >= 8);
        build(t, c.b, 16 / leaf, !oriented, &b, leaf < 8);
        for (size_t k = 0; k < c.offsets.size(); ++k) {
          const MeshPairDistance r = run_pair(a, b, c.offsets[k]);
          if (first) {
            reference.push_back(r);
            continue;
          }
          SCOPED_TRACE(testing::Message() << "leaf " << leaf << ", oriented " << oriented);
          expect_same_pair(r, reference[k]);
        }
        first = false;
      }
    }
  }
}

// Indexes without the triangles' float boxes (DistanceIndexOptions::without_triangle_boxes,
// autorotation's) give the same answers to the rigid pair queries, bit for bit: the boxes only
// spare loading far triangles. Random moves as below, every offset of each oracle case.
TEST(MeshPairDistance, WithoutTriangleBoxesTheSameBits) {
  std::mt19937_64 rng(33);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  int compared = 0;
  for (const Case& c : oracle_cases()) {
    test::TestArena t(size_t{32} << 20);
    Built a, b, a_lean, b_lean;
    build(t, c.a, 0, false, &a, true);
    build(t, c.b, 0, false, &b, true);
    DistanceIndexOptions lean;
    lean.pairs_only = true;
    lean.without_triangle_boxes = true;
    SPLINTCORE_ASSERT_OK(build_distance_index(Context(&t.arena), a.mesh, lean, &a_lean.index));
    SPLINTCORE_ASSERT_OK(build_distance_index(Context(&t.arena), b.mesh, lean, &b_lean.index));
    ASSERT_TRUE(a_lean.index.triangle_boxes.empty());
    ASSERT_FALSE(a.index.triangle_boxes.empty());
    for (const Vec3& off : c.offsets) {
      Vec3 axis{unit(rng), unit(rng), unit(rng)};
      axis = axis * (1.0 / length(axis));
      RigidTransform move = rotation_about_axis(Vec3{unit(rng), unit(rng), unit(rng)}, axis,
                                                compared % 2 == 0 ? 0.5 * unit(rng) : 0.0);
      move.t = move.t + off;
      test::TestArena s(size_t{1} << 20);
      MeshPairDistance r, e;
      SPLINTCORE_ASSERT_OK(
          mesh_pair_distance_rigid(Context(&s.arena), a.index, b.index, move, HUGE_VAL, &r));
      SPLINTCORE_ASSERT_OK(mesh_pair_distance_rigid(Context(&s.arena), a_lean.index, b_lean.index,
                                                    move, HUGE_VAL, &e));
      EXPECT_EQ(std::memcmp(&r.distance, &e.distance, sizeof(double)), 0);
      EXPECT_EQ(r.triangle_a, e.triangle_a);
      EXPECT_EQ(r.triangle_b, e.triangle_b);
      EXPECT_EQ(r.point_a, e.point_a);
      EXPECT_EQ(r.point_b, e.point_b);
      bool meet = false, meet_lean = false;
      MeshPairDistance m;
      SPLINTCORE_ASSERT_OK(
          mesh_pair_meet_rigid(Context(&s.arena), a.index, b.index, move, &meet, &m));
      SPLINTCORE_ASSERT_OK(mesh_pair_meet_rigid(Context(&s.arena), a_lean.index, b_lean.index, move,
                                                &meet_lean, &m));
      EXPECT_EQ(meet, meet_lean);
      ++compared;
    }
  }
  EXPECT_GE(compared, 16);
}

// mesh_pair_distance_rigid and mesh_pair_meet_rigid give the bits mesh_pair_distance and
// mesh_pair_meet give over an index of B's moved copy (its corners through apply_point): B's
// boxes bounded after the move only prune less. Random moves (rotations about axes through
// B's region, some by small angles), every offset of each case as the move's translation; the
// pure translation gives the translated search's bits too.
TEST(MeshPairDistance, RigidMoveMatchesAMovedCopy) {
  std::mt19937_64 rng(32);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  int compared = 0, met = 0, scans = 0;
  for (const Case& c : oracle_cases()) {
    test::TestArena t(size_t{32} << 20);
    Built a, b;
    build(t, c.a, 0, false, &a, true);
    build(t, c.b, 0, false, &b, true);
    for (const Vec3& off : c.offsets) {
      RigidTransform move;
      const int kind = compared % 3;
      if (kind > 0) {
        Vec3 axis{unit(rng), unit(rng), unit(rng)};
        axis = axis * (1.0 / length(axis));
        const double angle = kind == 1 ? 0.5 * unit(rng) : 1e-7 * unit(rng);
        move = rotation_about_axis(Vec3{unit(rng), unit(rng), unit(rng)}, axis, angle);
      }
      move.t = move.t + off;
      // The moved copy, indexed afresh.
      test::TestArena u(size_t{8} << 20);
      Built copy;
      copy.mesh.bind(&u.arena);
      for (const Vec3& v : b.mesh.vertices)
        ASSERT_TRUE(copy.mesh.vertices.push_back(move.apply_point(v)));
      for (const Triangle& tr : b.mesh.triangles) ASSERT_TRUE(copy.mesh.triangles.push_back(tr));
      DistanceIndexOptions o;
      o.pairs_only = true;
      ASSERT_TRUE(build_distance_index(Context(&u.arena), copy.mesh, o, &copy.index).is_ok());
      const MeshPairDistance e = run_pair(a, copy, Vec3{});
      test::TestArena s(size_t{1} << 20);
      MeshPairDistance r;
      SPLINTCORE_ASSERT_OK(
          mesh_pair_distance_rigid(Context(&s.arena), a.index, b.index, move, HUGE_VAL, &r));
      EXPECT_EQ(s.arena.used(), 0u);
      expect_same_pair(r, e);
      // The pairs within 0.5 mm of the closest, collected at this move, answer a further small
      // turn with the full search's bits (points move by well under 0.5 mm here).
      std::vector<TrianglePairIds> pool(4096);
      size_t count = 0;
      MeshPairDistance collected;
      SPLINTCORE_ASSERT_OK(mesh_pair_distance_collect_rigid(
          Context(&s.arena), a.index, b.index, move, r.distance + 0.5,
          Span<TrianglePairIds>(pool.data(), pool.size()), &count, &collected));
      EXPECT_EQ(std::memcmp(&collected.distance, &r.distance, sizeof(double)), 0);
      if (count <= pool.size()) {
        const RigidTransform nudged =
            compose(rotation_about_axis(Vec3{0.1, 0.2, 0.3}, Vec3{0, 0.6, 0.8}, 1e-3), move);
        MeshPairDistance full, scanned;
        SPLINTCORE_ASSERT_OK(
            mesh_pair_distance_rigid(Context(&s.arena), a.index, b.index, nudged, HUGE_VAL, &full));
        SPLINTCORE_ASSERT_OK(candidate_pair_distance_rigid(
            a.index, b.index, Span<const TrianglePairIds>(pool.data(), count), nudged, &scanned));
        EXPECT_EQ(std::memcmp(&full.distance, &scanned.distance, sizeof(double)), 0);
        EXPECT_EQ(full.triangle_a, scanned.triangle_a);
        EXPECT_EQ(full.triangle_b, scanned.triangle_b);
        ++scans;
      }
      bool meet = false;
      MeshPairDistance m;
      SPLINTCORE_ASSERT_OK(
          mesh_pair_meet_rigid(Context(&s.arena), a.index, b.index, move, &meet, &m));
      EXPECT_EQ(meet, e.intersecting);
      if (kind == 0) {  // a pure translation: the translated search's bits
        const MeshPairDistance shifted = run_pair(a, b, off);
        EXPECT_EQ(std::memcmp(&r.distance, &shifted.distance, sizeof(double)), 0);
        EXPECT_EQ(r.triangle_b, shifted.triangle_b);
      }
      ++compared;
      met += meet ? 1 : 0;
    }
  }
  EXPECT_GE(compared, 16);
  EXPECT_GE(met, 2);
  EXPECT_GE(scans, 8);
  // A move that is not finite is refused.
  test::TestArena t(size_t{4} << 20);
  Built a, b;
  build(t, oracle_cases()[0].a, 0, false, &a);
  build(t, oracle_cases()[0].b, 0, false, &b);
  RigidTransform bad;
  bad.r[1][2] = std::nan("");
  MeshPairDistance r;
  EXPECT_EQ(mesh_pair_distance_rigid(Context(&t.arena), a.index, b.index, bad, HUGE_VAL, &r).code(),
            StatusCode::kInvalidArgument);
}

// refit_distance_index: B moved rigidly and rounded to float32 (as a plan moves a jaw), its
// index refit from the unmoved B's tree, answers every search with the bits of an index built
// afresh over the moved copy; the refit runs in its bound, and one byte short of what it took
// fails cleanly; a mesh of another triangle
// count and a non-finite vertex are refused, the arena as it was.
TEST(MeshPairDistance, RefitIndexGivesTheSameBitsAsABuild) {
  std::mt19937_64 rng(34);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  int compared = 0;
  for (const Case& c : oracle_cases()) {
    for (const bool boxes : {false, true}) {
      test::TestArena t(size_t{32} << 20);
      Built a, b;
      build(t, c.a, 0, false, &a, true);
      DistanceIndexOptions o;
      o.pairs_only = true;
      o.without_triangle_boxes = !boxes;
      ASSERT_TRUE(test::mesh_from_soup(t.arena, c.b, &b.mesh).is_ok());
      SPLINTCORE_ASSERT_OK(build_distance_index(Context(&t.arena), b.mesh, o, &b.index));
      Vec3 axis{unit(rng), unit(rng), unit(rng)};
      axis = axis * (1.0 / length(axis));
      RigidTransform move =
          rotation_about_axis(Vec3{unit(rng), unit(rng), unit(rng)}, axis, 0.5 * unit(rng));
      move.t = move.t + Vec3{unit(rng), unit(rng), unit(rng)};
      Built copy, fresh;
      copy.mesh.bind(&t.arena);
      for (const Vec3& v : b.mesh.vertices) {
        Vec3 p = move.apply_point(v);
        ASSERT_TRUE(round_to_float32(&p));
        ASSERT_TRUE(copy.mesh.vertices.push_back(p));
      }
      for (const Triangle& tr : b.mesh.triangles) ASSERT_TRUE(copy.mesh.triangles.push_back(tr));
      fresh.mesh = mesh_view(copy.mesh.vertices.span(), copy.mesh.triangles.span());
      SPLINTCORE_ASSERT_OK(build_distance_index(Context(&t.arena), fresh.mesh, o, &fresh.index));
      size_t need = 0;
      {
        test::TestArena exact(static_cast<size_t>(refit_distance_index_bound(b.index)));
        SPLINTCORE_ASSERT_OK(
            refit_distance_index(Context(&exact.arena), b.index, copy.mesh, &copy.index));
        EXPECT_EQ(copy.index.mesh, &copy.mesh);
        EXPECT_EQ(copy.index.triangle_boxes.empty(), !boxes);
        for (const Vec3& off : c.offsets) {
          const MeshPairDistance r = run_pair(a, copy, off);
          const MeshPairDistance e = run_pair(a, fresh, off);
          expect_same_pair(r, e);
          ++compared;
        }
        need = exact.arena.high_water();
      }
      test::TestArena short_by_one(need - 1);
      DistanceIndex none;
      EXPECT_EQ(
          refit_distance_index(Context(&short_by_one.arena), b.index, copy.mesh, &none).code(),
          StatusCode::kArenaExhausted);
      EXPECT_EQ(short_by_one.arena.used(), 0u);
      EXPECT_TRUE(none.nodes.empty());
      const Mesh fewer = mesh_view(
          copy.mesh.vertices.span(),
          Span<const Triangle>(copy.mesh.triangles.data(), copy.mesh.triangles.size() - 1));
      EXPECT_EQ(refit_distance_index(Context(&t.arena), b.index, fewer, &none).code(),
                StatusCode::kInvalidArgument);
      copy.mesh.vertices[0].y = std::nan("");
      const size_t used = t.arena.used();
      EXPECT_EQ(refit_distance_index(Context(&t.arena), b.index, copy.mesh, &none).code(),
                StatusCode::kInvalidMesh);
      EXPECT_EQ(t.arena.used(), used);
    }
  }
  EXPECT_GE(compared, 16);
}

// The bound holds the search split on an executor of more than one thread (its tasks' heaps
// and stacks); with less room the search runs serially (the same answer), and it fails
// cleanly only with less than the serial search's own heap and stack.
TEST(MeshPairDistance, RunsInExactlyItsBound) {
  ThreadExecutor two(2);
  size_t split_peaks = 0;
  for (const Case& c : oracle_cases()) {
    test::TestArena t(size_t{32} << 20);
    Built a, b;
    build(t, c.a, 1, false, &a);
    build(t, c.b, 1, false, &b);
    const uint64_t bound = mesh_pair_distance_bound(a.index, b.index);
    EXPECT_LT(bound, uint64_t{1} << 20);
    for (const Vec3& off : c.offsets) {
      const MeshPairDistance e = run_pair(a, b, off);
      for (const Executor* executor : {static_cast<const Executor*>(nullptr), &two.executor()}) {
        for (const size_t size : {static_cast<size_t>(bound), static_cast<size_t>(bound / 2)}) {
          std::vector<unsigned char> buffer(size);
          Arena arena(buffer.data(), buffer.size());
          MeshPairDistance r;
          const Status s = mesh_pair_distance(Context(&arena, executor, nullptr), a.index, b.index,
                                              off, HUGE_VAL, &r);
          ASSERT_TRUE(s.is_ok()) << test::format(s);
          EXPECT_EQ(arena.used(), 0u);
          EXPECT_LE(arena.high_water(), size);
          EXPECT_EQ(r.distance, e.distance);
          EXPECT_EQ(r.triangle_a, e.triangle_a);
          EXPECT_EQ(r.triangle_b, e.triangle_b);
          if (executor != nullptr && size == bound && arena.high_water() > bound / 2) {
            ++split_peaks;
          }
        }
      }
      std::vector<unsigned char> small(1024);
      Arena smaller(small.data(), small.size());
      MeshPairDistance r;
      const Status s = mesh_pair_distance(Context(&smaller, &two.executor(), nullptr), a.index,
                                          b.index, off, HUGE_VAL, &r);
      EXPECT_EQ(s.code(), StatusCode::kArenaExhausted);
      EXPECT_EQ(smaller.used(), 0u);
    }
  }
  EXPECT_GT(split_peaks, 0u);  // some searches were split, in the bound
}

// ---------------------------------------------------------------------------------------------
// Dense near-parallel surfaces (what the bite opening measures): every pruning of the search
// (boxes, triangles against the other leaf, separation along a normal, best first) must leave
// the answer of an exhaustive search with the library's own per-pair routine.

// A wavy height field z = base + h(x, y), n x n cells of `cell` mm, vertices jittered: dense
// triangles tilted every way by a few degrees.
Soup wavy_grid(uint32_t n, double cell, double base, double phase, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> jitter(-0.1 * cell, 0.1 * cell);
  std::vector<Vec3> p;
  for (uint32_t i = 0; i <= n; ++i) {
    for (uint32_t j = 0; j <= n; ++j) {
      const double x = i * cell + jitter(rng), y = j * cell + jitter(rng);
      p.push_back({x, y, base + 0.15 * std::sin(0.9 * x + phase) * std::cos(0.7 * y - phase)});
    }
  }
  Soup out;
  const auto tri = [&](uint32_t a, uint32_t b, uint32_t c) {
    SoupTriangle t;
    const uint32_t id[3] = {a, b, c};
    for (int k = 0; k < 3; ++k) {
      for (int d = 0; d < 3; ++d) t.p[k][d] = static_cast<float>(p[id[k]][d]);
    }
    out.push_back(t);
  };
  for (uint32_t i = 0; i < n; ++i) {
    for (uint32_t j = 0; j < n; ++j) {
      const uint32_t v = i * (n + 1) + j;
      tri(v, v + n + 1, v + n + 2);
      tri(v, v + n + 2, v + 1);
    }
  }
  return out;
}

struct ExhaustiveResult {
  double d2 = HUGE_VAL, d = HUGE_VAL;
  uint32_t ta = 0, tb = 0;
  Vec3 pa, pb;
};

// `x` is the answer `e` names, bit for bit, with the closest points pa and pb.
void expect_answer(const MeshPairDistance& x, const ExhaustiveResult& e, const Vec3& pa,
                   const Vec3& pb) {
  EXPECT_EQ(std::memcmp(&x.distance, &e.d, sizeof(double)), 0) << x.distance << " " << e.d;
  EXPECT_EQ(x.triangle_a, e.ta);
  EXPECT_EQ(x.triangle_b, e.tb);
  EXPECT_EQ(x.point_a, pa);
  EXPECT_EQ(x.point_b, pb);
  EXPECT_EQ(x.intersecting, e.d == 0);
}

// The least (squared distance, triangle a, triangle b) over every pair, by
// triangle_pair_distance() (the squared distance being that of its two points, 0 for meeting
// triangles: the key the library orders by), skipping only pairs whose boxes are farther apart
// than the best by a wide margin (with `prune`; without, every pair: all_pairs).
ExhaustiveResult exhaustive(const Mesh& a, const Mesh& b, const Vec3& offset, bool prune = true) {
  const std::vector<TriangleCorners> x = corners_of(a, Vec3{}), y = corners_of(b, offset);
  ExhaustiveResult r;
  for (uint32_t i = 0; i < x.size(); ++i) {
    for (uint32_t j = 0; j < y.size(); ++j) {
      if (prune && r.d2 < HUGE_VAL && box_gap2(x[i], y[j]) > r.d2 * (1 + 1e-6) + 1e-12) continue;
      Vec3 pa, pb;
      const double d = triangle_pair_distance(x[i].p[0], x[i].p[1], x[i].p[2], y[j].p[0], y[j].p[1],
                                              y[j].p[2], &pa, &pb);
      const double d2 = d == 0 ? 0 : length_squared(pa - pb);
      if (d2 < r.d2) r = ExhaustiveResult{d2, d, i, j, pa, pb};
    }
  }
  return r;
}

// The least (squared distance, triangle a, triangle b) over every pair, by
// triangle_pair_distance() (0 for meeting triangles), with no pruning at all.
ExhaustiveResult all_pairs(const Mesh& a, const Mesh& b, const Vec3& offset) {
  return exhaustive(a, b, offset, false);
}

// A flat n x n grid of unit squares at height z, two triangles a square: congruent
// triangles at integer coordinates, so that many pairs tie at exactly the least distance.
Soup flat_grid(uint32_t n, float z) {
  Soup out;
  for (uint32_t i = 0; i < n; ++i) {
    for (uint32_t j = 0; j < n; ++j) {
      const float x = static_cast<float>(i), y = static_cast<float>(j);
      SoupTriangle lower, upper;
      const float l[3][3] = {{x, y, z}, {x + 1, y, z}, {x + 1, y + 1, z}};
      const float u[3][3] = {{x, y, z}, {x + 1, y + 1, z}, {x, y + 1, z}};
      std::memcpy(lower.p, l, sizeof l);
      std::memcpy(upper.p, u, sizeof u);
      out.push_back(lower);
      out.push_back(upper);
    }
  }
  return out;
}

// The search split over tasks on an executor (more than one thread) answers what the serial
// search does, bit for bit, at 1, 2, 3 and 8 threads, and both the least of every pair: on grids
// of congruent triangles where many pairs tie (every triangle over its twin, and its
// neighbours' edges, at the same distance), apart, side by side and coplanar (every
// overlapping pair meets); with leaves of one triangle and of the default size, translated
// and moved rigidly.
TEST(MeshPairDistance, SplitSearchAnswersAsTheSerialOneAtEveryThreadCount) {
  test::TestArena t(size_t{64} << 20);
  Built a[2], b[2];
  for (int k = 0; k < 2; ++k) {
    build(t, flat_grid(24, 0), k == 0 ? 1 : 0, false, &a[k]);
    build(t, flat_grid(24, 0), k == 0 ? 1 : 0, false, &b[k], true);
  }
  ThreadExecutor one(1), two(2), three(3), eight(8);
  const Executor* executors[4] = {&one.executor(), &two.executor(), &three.executor(),
                                  &eight.executor()};
  for (const Vec3 off : {Vec3{0, 0, 1}, Vec3{0.5, 0.25, 1}, Vec3{3, -2, 2}, Vec3{25.5, 0, 0.75},
                         Vec3{0, 0, 0}, Vec3{0.5, 0.5, 0}}) {
    SCOPED_TRACE(testing::Message() << "offset " << off.x << " " << off.y << " " << off.z);
    const ExhaustiveResult e = all_pairs(a[0].mesh, b[0].mesh, off);
    for (int k = 0; k < 2; ++k) {
      const MeshPairDistance serial = run_pair(a[k], b[k], off);
      EXPECT_EQ(std::memcmp(&serial.distance, &e.d, sizeof(double)), 0);
      EXPECT_EQ(serial.triangle_a, e.ta);
      EXPECT_EQ(serial.triangle_b, e.tb);
      RigidTransform move;
      move.t = off;
      for (const Executor* ex : executors) {
        test::TestArena arena(size_t{1} << 20);
        const Context ctx(&arena.arena, ex, nullptr);
        MeshPairDistance r, m;
        ASSERT_TRUE(mesh_pair_distance(ctx, a[k].index, b[k].index, off, HUGE_VAL, &r).is_ok());
        ASSERT_TRUE(
            mesh_pair_distance_rigid(ctx, a[k].index, b[k].index, move, HUGE_VAL, &m).is_ok());
        EXPECT_EQ(arena.arena.used(), 0u);
        for (const MeshPairDistance& x : {r, m})
          expect_answer(x, e, serial.point_a, serial.point_b);
      }
    }
  }
}

// The pairs a split search collects (on an executor of more than one thread) are the serial
// search's, as a set (their order is the tasks' one after the other), with the same count and
// answer; in a pool of exactly their number (a task's slice overflows: the search again,
// serially, which fits them) and in one too small (the count past it).
TEST(MeshPairDistance, SplitCollectGathersTheSerialPairsAtEveryThreadCount) {
  test::TestArena t(size_t{64} << 20);
  Built a, b;
  build(t, flat_grid(24, 0), 1, false, &a);
  build(t, flat_grid(24, 0), 1, false, &b, true);
  ThreadExecutor two(2), three(3), eight(8);
  const auto key = [](const TrianglePairIds& p) { return uint64_t{p.a} << 32 | p.b; };
  for (const Vec3 off : {Vec3{0, 0, 1}, Vec3{0.5, 0.25, 1}, Vec3{0, 0, 0}}) {
    SCOPED_TRACE(testing::Message() << "offset " << off.x << " " << off.y << " " << off.z);
    std::vector<TrianglePairIds> serial(size_t{1} << 18);
    size_t count = 0;
    MeshPairDistance rs;
    ASSERT_TRUE(mesh_pair_distance_collect(Context(&t.arena), a.index, b.index, off, 1.6,
                                           Span<TrianglePairIds>(serial.data(), serial.size()),
                                           &count, &rs)
                    .is_ok());
    ASSERT_GT(count, 200u);
    ASSERT_LE(count, serial.size());
    std::vector<uint64_t> want;
    for (size_t i = 0; i < count; ++i) want.push_back(key(serial[i]));
    std::sort(want.begin(), want.end());
    for (const ThreadExecutor* pool : {&two, &three, &eight}) {
      for (const size_t room : {serial.size(), count, count - 1}) {
        std::vector<TrianglePairIds> pairs(room);
        size_t n = 0;
        MeshPairDistance r;
        const Context ctx(&t.arena, &pool->executor(), nullptr);
        ASSERT_TRUE(mesh_pair_distance_collect(ctx, a.index, b.index, off, 1.6,
                                               Span<TrianglePairIds>(pairs.data(), pairs.size()),
                                               &n, &r)
                        .is_ok());
        EXPECT_EQ(std::memcmp(&r.distance, &rs.distance, sizeof(double)), 0);
        EXPECT_EQ(r.triangle_a, rs.triangle_a);
        EXPECT_EQ(r.triangle_b, rs.triangle_b);
        if (room < count) {
          EXPECT_EQ(n, room + 1);
          continue;
        }
        ASSERT_EQ(n, count);
        std::vector<uint64_t> got;
        for (size_t i = 0; i < n; ++i) got.push_back(key(pairs[i]));
        std::sort(got.begin(), got.end());
        EXPECT_EQ(got, want);
      }
    }
  }
}

TEST(MeshPairDistance, DenseNearParallelSurfacesMatchExhaustiveSearch) {
  test::TestArena t(size_t{64} << 20);
  Built a, b, a1, b16;
  build(t, wavy_grid(22, 0.25, 0, 0, 7), 0, false, &a);
  build(t, wavy_grid(20, 0.27, 0.35, 1.3, 8), 0, false, &b);
  build(t, wavy_grid(22, 0.25, 0, 0, 7), 1, true, &a1);
  build(t, wavy_grid(20, 0.27, 0.35, 1.3, 8), 16, false, &b16);
  int meeting = 0, apart = 0;
  // (Also split over tasks on two threads: the same answers.)
  ThreadExecutor two(2);
  const Executor* split = &two.executor();
  // B above A: far, near, grazing, touching at the crests and interpenetrating.
  for (const double dz : {1.5, 0.6, 0.2, 0.05, 0.01, 0.0, -0.05, -0.2, -0.35}) {
    for (const Vec3 lateral : {Vec3{0, 0, 0}, Vec3{0.61, -0.37, 0}, Vec3{-1.1, 0.9, 0}}) {
      const Vec3 off = lateral + Vec3{0, 0, dz};
      SCOPED_TRACE(testing::Message() << "offset " << off.x << " " << off.y << " " << off.z);
      const ExhaustiveResult e = exhaustive(a.mesh, b.mesh, off);
      for (const MeshPairDistance& r :
           {run_pair(a, b, off), run_pair(a1, b16, off), run_pair(a, b, off, HUGE_VAL, split),
            run_pair(a1, b16, off, HUGE_VAL, split)}) {
        expect_answer(r, e, e.pa, e.pb);
      }
      // A limit just above and just below the answer (e.d squared may round below e.d2).
      if (e.d > 0) {
        EXPECT_EQ(run_pair(a, b, off, e.d * (1 + 1e-12)).triangle_a, e.ta);
        EXPECT_EQ(run_pair(a, b, off, e.d * (1 - 1e-9)).distance, HUGE_VAL);
        EXPECT_EQ(run_pair(a, b, off, e.d * (1 + 1e-12), split).triangle_a, e.ta);
        EXPECT_EQ(run_pair(a, b, off, e.d * (1 - 1e-9), split).distance, HUGE_VAL);
      }
      ++(e.d == 0 ? meeting : apart);
    }
  }
  EXPECT_GE(meeting, 4);
  EXPECT_GE(apart, 12);
}

// The pairs kept within a margin of the closest answer every move along a unit direction by at
// most a quarter of the margin as the full search does (the bite opening's last steps).
TEST(MeshPairDistance, CollectedPairsAnswerNearbyMovesWithTheSameBits) {
  test::TestArena t(size_t{64} << 20);
  Built a, b;
  build(t, wavy_grid(22, 0.25, 0, 0, 7), 0, false, &a);
  build(t, wavy_grid(20, 0.27, 0.35, 1.3, 8), 0, false, &b);
  std::vector<TrianglePairIds> pool(1 << 16);
  const Vec3 tilt{0.1, -0.2, 1.0};
  const Vec3 up = tilt * (1.0 / length(tilt));
  int scanned = 0;
  for (const double dz : {1.5, 0.6, 0.2, 0.05, 0.0, -0.2}) {
    for (const double margin : {0.08, 0.01, 1e-6}) {
      const Vec3 off = Vec3{0.61, -0.37, 0} + up * dz;
      SCOPED_TRACE(testing::Message() << "dz " << dz << " margin " << margin);
      const MeshPairDistance full = run_pair(a, b, off);
      const double limit = full.distance + margin;
      MeshPairDistance got;
      size_t count = 0;
      const Status s =
          mesh_pair_distance_collect(Context(&t.arena), a.index, b.index, off, limit,
                                     Span<TrianglePairIds>(pool.data(), pool.size()), &count, &got);
      ASSERT_TRUE(s.is_ok()) << test::format(s);
      ASSERT_GE(count, 1u);
      ASSERT_LE(count, pool.size());
      EXPECT_EQ(std::memcmp(&got.distance, &full.distance, sizeof(double)), 0);
      EXPECT_EQ(got.triangle_a, full.triangle_a);
      EXPECT_EQ(got.triangle_b, full.triangle_b);
      for (const double move : {0.0, 0.25, -0.25, 0.1, -0.02}) {
        const Vec3 moved = off + up * (move * margin);
        const MeshPairDistance want = run_pair(a, b, moved);
        MeshPairDistance r;
        ASSERT_TRUE(candidate_pair_distance(a.index, b.index,
                                            Span<const TrianglePairIds>(pool.data(), count), moved,
                                            &r)
                        .is_ok());
        expect_same_pair(r, want);
        ++scanned;
      }
    }
  }
  EXPECT_EQ(scanned, 90);
  // Too many pairs for the room: counted past it.
  size_t count = 0;
  MeshPairDistance r;
  ASSERT_TRUE(mesh_pair_distance_collect(Context(&t.arena), a.index, b.index, Vec3{0, 0, 0.2}, 2.0,
                                         Span<TrianglePairIds>(pool.data(), 3), &count, &r)
                  .is_ok());
  EXPECT_EQ(count, 4u);
  EXPECT_EQ(r.triangle_a, run_pair(a, b, Vec3{0, 0, 0.2}).triangle_a);
  // A pair out of range is refused.
  const TrianglePairIds bad[1] = {TrianglePairIds{~uint32_t{0}, 0}};
  EXPECT_EQ(
      candidate_pair_distance(a.index, b.index, Span<const TrianglePairIds>(bad, 1), Vec3{}, &r)
          .code(),
      StatusCode::kInvalidArgument);
}

// ---------------------------------------------------------------------------------------------
// The real dentition: upper teeth against the lower teeth moved 3 mm down.

TEST(MeshPairDistance, RealDentitionMatchesRestrictedBruteForce) {
  const std::string dir = SPLINTCORE_REALDATA_DIR;
  if (!test::file_exists(dir + "/maxilla/tooth_1.stl")) GTEST_SKIP() << "realdata not found";
  test::TestArena t(size_t{1} << 30);
  // The two jaws, each its teeth in one mesh (tooth 16 is absent in the source).
  std::vector<Vec3> vertices[2];
  std::vector<Triangle> triangles[2];
  for (int tooth = 1; tooth <= 32; ++tooth) {
    const std::string path = dir + (tooth <= 16 ? "/maxilla/" : "/mandible/") + "tooth_" +
                             std::to_string(tooth) + ".stl";
    if (!test::file_exists(path)) continue;
    const Arena::Marker m = t.arena.mark();
    Mesh one;
    ASSERT_TRUE(test::mesh_from_bytes(t.arena, test::read_file_bytes(path), &one).is_ok());
    const int j = tooth <= 16 ? 0 : 1;
    const uint32_t base = static_cast<uint32_t>(vertices[j].size());
    vertices[j].insert(vertices[j].end(), one.vertices.begin(), one.vertices.end());
    for (const Triangle& tr : one.triangles) {
      triangles[j].push_back(Triangle{{tr.v[0] + base, tr.v[1] + base, tr.v[2] + base}});
    }
    t.arena.rewind(m);
  }
  Mesh jaws[2];
  DistanceIndex index[2];
  for (int j = 0; j < 2; ++j) {
    jaws[j].bind(&t.arena);
    ASSERT_TRUE(jaws[j].vertices.reserve(vertices[j].size()));
    ASSERT_TRUE(jaws[j].triangles.reserve(triangles[j].size()));
    for (const Vec3& v : vertices[j]) ASSERT_TRUE(jaws[j].vertices.push_back(v));
    for (const Triangle& tr : triangles[j]) ASSERT_TRUE(jaws[j].triangles.push_back(tr));
    const Status s = build_distance_index(Context(&t.arena), jaws[j], {}, &index[j]);
    ASSERT_TRUE(s.is_ok()) << test::format(s);
  }
  const Vec3 off{0, 0, -3};
  MeshPairDistance r;
  const Status s = mesh_pair_distance(Context(&t.arena), index[0], index[1], off, HUGE_VAL, &r);
  ASSERT_TRUE(s.is_ok()) << test::format(s);
  EXPECT_GT(r.distance, 0.0);
  EXPECT_FALSE(r.intersecting);
  // Brute force over the triangle pairs whose boxes lie within the distance found (a pair
  // farther apart cannot be closer), found through a grid of cells `reach` wide holding the
  // upper triangles by their boxes.
  const double reach = r.distance * (1 + 1e-9) + 1e-9;
  const auto box_of = [&](int j, uint32_t i, Vec3* lo, Vec3* hi) {
    const Triangle& tr = jaws[j].triangles[i];
    const Vec3 shift = j == 0 ? Vec3{} : off;
    *lo = *hi = jaws[j].vertices[tr.v[0]] + shift;
    for (int k = 1; k < 3; ++k) {
      *lo = min_vec(*lo, jaws[j].vertices[tr.v[k]] + shift);
      *hi = max_vec(*hi, jaws[j].vertices[tr.v[k]] + shift);
    }
  };
  const auto cell = [&](double x) { return static_cast<int64_t>(std::floor(x / reach)); };
  std::map<std::array<int64_t, 3>, std::vector<uint32_t>> grid;
  for (uint32_t i = 0; i < jaws[0].triangles.size(); ++i) {
    Vec3 lo, hi;
    box_of(0, i, &lo, &hi);
    for (int64_t x = cell(lo.x); x <= cell(hi.x); ++x)
      for (int64_t y = cell(lo.y); y <= cell(hi.y); ++y)
        for (int64_t z = cell(lo.z); z <= cell(hi.z); ++z) grid[{x, y, z}].push_back(i);
  }
  double best2 = HUGE_VAL;
  uint64_t pairs = 0;
  for (uint32_t j = 0; j < jaws[1].triangles.size(); ++j) {
    Vec3 blo, bhi, y[3];
    box_of(1, j, &blo, &bhi);
    for (int k = 0; k < 3; ++k) y[k] = jaws[1].vertices[jaws[1].triangles[j].v[k]] + off;
    for (int64_t cx = cell(blo.x - reach); cx <= cell(bhi.x + reach); ++cx)
      for (int64_t cy = cell(blo.y - reach); cy <= cell(bhi.y + reach); ++cy)
        for (int64_t cz = cell(blo.z - reach); cz <= cell(bhi.z + reach); ++cz) {
          const auto it = grid.find({cx, cy, cz});
          if (it == grid.end()) continue;
          for (uint32_t i : it->second) {
            Vec3 alo, ahi, x[3];
            box_of(0, i, &alo, &ahi);
            double g2 = 0;
            for (int a = 0; a < 3; ++a) {
              const double g = std::max(0.0, std::max(blo[a] - ahi[a], alo[a] - bhi[a]));
              g2 += g * g;
            }
            if (g2 > reach * reach) continue;
            ++pairs;
            for (int k = 0; k < 3; ++k) x[k] = jaws[0].vertices[jaws[0].triangles[i].v[k]];
            best2 = std::min(best2, oracle_pair_d2(x, y));
          }
        }
  }
  EXPECT_GT(pairs, 0u);
  EXPECT_NEAR(r.distance, std::sqrt(best2), 1e-12 * r.distance);
}

}  // namespace
}  // namespace splintcore
