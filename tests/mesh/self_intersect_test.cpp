// Tests of find_self_intersections (src/mesh/self_intersect.cpp): valid closed meshes report
// nothing; meshes with known self-intersections report them; the shared-vertex and shared-edge
// rules of mesh.h on hand-made pairs; vertex stars that turn twice or fold sharply; the count
// and first pair on hundreds of random small meshes and a large perturbed torus against an
// O(n^2) brute force built on the independent exact oracle of tests/geometry/triangle_test.cpp,
// with the candidate count bounded by what the broad phase must keep; max_pairs against a
// replay of the original sweep's order of discovery; the hierarchy and the sweep agreeing on
// everything; coordinates outside the filters' range; arena exhaustion, bad indices,
// cancellation.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <random>
#include <utility>
#include <vector>

#include "splintcore/platform.h"
#include "support/exact.h"
#include "support/self_intersection_oracle.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

using splintcore_test::exact_collinear3d;
using splintcore_test::exact_orient3d_sign;
using test::TestArena;
namespace oracle = splintcore_test::tri_oracle;
using brute::box_of;
using brute::Brute;
using brute::brute_conflict;
using brute::brute_force;
using brute::skipped;

#if defined(SPLINTCORE_TEST_SANITIZED)
constexpr int kRandomDivisor = 4;  // as at -O0: the sanitized build is as slow
#elif defined(__OPTIMIZE__)
constexpr int kRandomDivisor = 1;
#else
constexpr int kRandomDivisor = 4;
#endif

// ---- helpers -----------------------------------------------------------------------------------

SelfIntersectionReport run(const Mesh& mesh, uint64_t max_pairs = 0) {
  TestArena work(size_t{16} << 20);
  Context ctx(&work.arena);
  SelfIntersectionReport r;
  Status s = find_self_intersections(ctx, mesh, max_pairs, &r);
  EXPECT_TRUE(s.is_ok()) << test::format(s);
  EXPECT_EQ(work.arena.used(), 0u);  // temporaries returned
  return r;
}

// The pairs the broad phase must keep (mesh.h): every pair of non-degenerate triangles that
// share a vertex id or meet. Returns that count and, in *all, the number of pairs of
// non-degenerate triangles (the most there can be).
uint64_t required_candidates(const Mesh& mesh, const Brute& b, uint64_t* all) {
  const Vec3* v = mesh.vertices.data();
  const size_t n = mesh.triangles.size();
  std::vector<char> skip(n);
  for (size_t i = 0; i < n; ++i) skip[i] = skipped(v, mesh.triangles[i]);
  uint64_t required = 0, pairs = 0;
  for (uint32_t a = 0; a < n; ++a) {
    if (skip[a]) continue;
    for (uint32_t c = a + 1; c < n; ++c) {
      if (skip[c]) continue;
      ++pairs;
      bool shared = false;
      for (uint32_t x : mesh.triangles[a].v) {
        for (uint32_t y : mesh.triangles[c].v) shared = shared || x == y;
      }
      required += shared || b.is_conflict(a, c);
    }
  }
  *all = pairs;
  return required;
}

// The same mesh with copies of its vertices appended, unreferenced, until there are more than
// three vertices a triangle: find_self_intersections then takes its sweep over boxes instead of
// the hierarchy (the copies change no bound, so the DOPs are the same).
Mesh with_unreferenced_copies(TestArena& t, const Mesh& mesh) {
  Mesh out(&t.arena);
  for (const Triangle& tri : mesh.triangles) EXPECT_TRUE(out.triangles.push_back(tri));
  while (out.vertices.size() <= 3 * mesh.triangles.size()) {
    for (const Vec3& p : mesh.vertices) EXPECT_TRUE(out.vertices.push_back(p));
    if (mesh.vertices.empty()) break;
  }
  return out;
}

// What the original sweep over boxes reports when it stops at max_pairs = k (its order of
// discovery, replayed with the oracle): triangles in order of their boxes' x minimum (stable,
// keyed like the library's radix sort), each against the later ones whose x range starts
// before its own ends and whose y and z ranges overlap.
struct SweepReplay {
  uint64_t pairs = 0;
  uint32_t first_a = 0, first_b = 0;
};

SweepReplay replay_original_sweep(const Mesh& mesh, uint64_t k) {
  const Vec3* v = mesh.vertices.data();
  const size_t n = mesh.triangles.size();
  std::vector<Aabb> boxes(n);
  std::vector<char> skip(n);
  std::vector<std::pair<uint64_t, uint32_t>> order(n);
  for (uint32_t i = 0; i < n; ++i) {
    boxes[i] = box_of(v, mesh.triangles[i]);
    skip[i] = skipped(v, mesh.triangles[i]);
    uint64_t bits;
    std::memcpy(&bits, &boxes[i].lo.x, sizeof(bits));
    order[i] = {(bits >> 63) != 0 ? ~bits : bits | (uint64_t{1} << 63), i};
  }
  std::stable_sort(order.begin(), order.end(),
                   [](const auto& x, const auto& y) { return x.first < y.first; });
  SweepReplay r;
  for (size_t i = 0; i < n; ++i) {
    const uint32_t s = order[i].second;
    if (skip[s]) continue;
    for (size_t j = i + 1; j < n; ++j) {
      const uint32_t t = order[j].second;
      const Aabb &bs = boxes[s], &bt = boxes[t];
      if (bt.lo.x > bs.hi.x) break;
      if (bt.lo.y > bs.hi.y || bt.hi.y < bs.lo.y || bt.lo.z > bs.hi.z || bt.hi.z < bs.lo.z ||
          skip[t] || !brute_conflict(v, mesh.triangles[s], mesh.triangles[t])) {
        continue;
      }
      const uint32_t a = s < t ? s : t, b = s < t ? t : s;
      if (r.pairs == 0 || a < r.first_a || (a == r.first_a && b < r.first_b)) {
        r.first_a = a;
        r.first_b = b;
      }
      if (++r.pairs == k) return r;
    }
  }
  return r;
}

// max_pairs = k: the library reports what the original sweep reported.
void expect_original_order(const Mesh& mesh, uint64_t k, const char* what) {
  const SelfIntersectionReport r = run(mesh, k);
  const SweepReplay e = replay_original_sweep(mesh, k);
  EXPECT_EQ(r.intersecting_pairs, e.pairs) << what << ", max_pairs " << k;
  if (e.pairs > 0) {
    EXPECT_EQ(r.first_a, e.first_a) << what << ", max_pairs " << k;
    EXPECT_EQ(r.first_b, e.first_b) << what << ", max_pairs " << k;
  }
}

// The candidate count is at least what the broad phase must keep, at most every pair.
void expect_plausible_candidates(const SelfIntersectionReport& r, const Mesh& mesh, const Brute& b,
                                 const char* what) {
  uint64_t all = 0;
  EXPECT_GE(r.candidate_pairs, required_candidates(mesh, b, &all)) << what;
  EXPECT_LE(r.candidate_pairs, all) << what;
}

// Library and brute force agree on the count and the first pair; the candidate count is
// plausible.
void expect_matches_brute_force(const Mesh& mesh, const char* what) {
  const SelfIntersectionReport r = run(mesh);
  const Brute b = brute_force(mesh);
  EXPECT_EQ(r.intersecting_pairs, b.pairs) << what;
  expect_plausible_candidates(r, mesh, b, what);
  if (b.pairs > 0) {
    EXPECT_EQ(r.first_a, b.first_a) << what;
    EXPECT_EQ(r.first_b, b.first_b) << what;
  }
}

Mesh welded(TestArena& t, const std::vector<SoupTriangle>& soup) {
  Mesh mesh;
  Status s = test::mesh_from_soup(t.arena, soup, &mesh);
  EXPECT_TRUE(s.is_ok()) << test::format(s);
  return mesh;
}

// A mesh from explicit vertices and triangles (ids exactly as given).
Mesh make_mesh(TestArena& t, const std::vector<Vec3>& vertices,
               const std::vector<Triangle>& triangles) {
  Mesh mesh(&t.arena);
  for (const Vec3& p : vertices) EXPECT_TRUE(mesh.vertices.push_back(p));
  for (const Triangle& tri : triangles) EXPECT_TRUE(mesh.triangles.push_back(tri));
  return mesh;
}

// Appends `other` as a separate shell (its vertex ids shifted: no id shared).
void append_shell(Mesh* mesh, const Mesh& other) {
  const uint32_t base = static_cast<uint32_t>(mesh->vertices.size());
  for (const Vec3& p : other.vertices) EXPECT_TRUE(mesh->vertices.push_back(p));
  for (const Triangle& t : other.triangles) {
    EXPECT_TRUE(mesh->triangles.push_back(Triangle{{t.v[0] + base, t.v[1] + base, t.v[2] + base}}));
  }
}

std::vector<SoupTriangle> box_soup(float x0, float y0, float z0, float x1, float y1, float z1) {
  const float lo[3] = {x0, y0, z0}, hi[3] = {x1, y1, z1};
  return shapes::box(lo, hi);
}

// A sphere: the octahedron's faces split into n^2 triangles each on the lattice i + j + k = n,
// projected onto the sphere, float32 corners (points on shared edges are computed from the
// same lattice coordinates, so they weld; -0 and +0 weld too). Outward, closed, genus 0.
std::vector<SoupTriangle> octasphere(int n, double radius) {
  std::vector<SoupTriangle> out;
  for (int octant = 0; octant < 8; ++octant) {
    const int sx = (octant & 1) ? -1 : 1, sy = (octant & 2) ? -1 : 1, sz = (octant & 4) ? -1 : 1;
    auto point = [&](int i, int j, int k, float* p) {
      const double x = sx * i, y = sy * j, z = sz * k;
      const double len = std::sqrt(x * x + y * y + z * z);
      p[0] = static_cast<float>(radius * x / len);
      p[1] = static_cast<float>(radius * y / len);
      p[2] = static_cast<float>(radius * z / len);
    };
    auto add = [&](int i0, int j0, int i1, int j1, int i2, int j2) {
      float a[3], b[3], c[3];
      point(i0, j0, n - i0 - j0, a);
      point(i1, j1, n - i1 - j1, b);
      point(i2, j2, n - i2 - j2, c);
      // (i, j, k) -> (i+1, j, k-1) -> (i, j+1, k-1) is outward in the + octant; a mirror
      // (odd number of negative signs) reverses it.
      if (sx * sy * sz > 0) {
        out.push_back(shapes::soup_triangle(a, b, c));
      } else {
        out.push_back(shapes::soup_triangle(a, c, b));
      }
    };
    for (int i = 0; i < n; ++i) {
      for (int j = 0; i + j < n; ++j) {
        add(i, j, i + 1, j, i, j + 1);
        if (i + j + 1 < n) add(i + 1, j, i + 1, j + 1, i, j + 1);
      }
    }
  }
  return out;
}

// ---- closed valid meshes -----------------------------------------------------------------------

TEST(SelfIntersection, ValidClosedMeshesReportNothing) {
  TestArena t;
  struct Case {
    const char* name;
    std::vector<SoupTriangle> soup;
  };
  const std::vector<Case> cases = {
      {"torus 32x16", shapes::torus(32, 16, 10, 3)},
      {"thin torus 48x6", shapes::torus(48, 6, 10, 0.5)},
      {"box", box_soup(0, 0, 0, 2, 3, 4)},
      {"flat box", box_soup(-1, -1, 0, 1, 1, 0.001f)},
      {"octasphere 8", octasphere(8, 5.0)},
      {"octasphere 20", octasphere(20, 1.0)},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    Mesh mesh = welded(t, c.soup);
    MeshReport check;
    Context ctx(&t.arena);
    SPLINTCORE_ASSERT_OK(check_mesh(ctx, mesh, &check));
    ASSERT_TRUE(check.is_valid_solid());
    const SelfIntersectionReport r = run(mesh);
    EXPECT_EQ(r.intersecting_pairs, 0u);
    EXPECT_FALSE(r.self_intersecting());
    EXPECT_GT(r.candidate_pairs, mesh.triangles.size());  // neighbours are tested
    expect_matches_brute_force(mesh, c.name);
  }
}

// Two unit boxes side by side, [0,1]^3 and [1,2]x[0,1]^2, as separate shells (no shared vertex
// id). All contact is in the square Q = {x = 1} x [0,1]^2. Expected: 62 intersecting pairs,
// counted by how each triangle meets the plane x = 1:
//   each box has 2 triangles covering Q (the same two triangles in both boxes: the same
//   diagonal), 4 triangles meeting it in one edge of Q, 4 meeting it in one corner of Q;
//   face x face 4 (identical or sharing the diagonal), face x edge 8 + 8, face x corner 6 + 6,
//   edge x edge 12 (same edge or adjacent ones), edge x corner 8 + 8, corner x corner 2.
// The coplanar overlapping face triangles are genuine self-intersections of the union; the
// smallest pair is (0, 12): box A's first triangle (z = 0, corner (1,0,0)) and box B's first
// (z = 0, edge from (1,0,0)), coplanar and touching at that point only.
TEST(SelfIntersection, TwoShellsTouchingAtAFaceWithSeparateVertexIds) {
  TestArena t;
  Mesh a = welded(t, box_soup(0, 0, 0, 1, 1, 1));
  Mesh b = welded(t, box_soup(1, 0, 0, 2, 1, 1));
  Mesh mesh(&t.arena);
  append_shell(&mesh, a);
  append_shell(&mesh, b);
  ASSERT_EQ(mesh.vertices.size(), 16u);
  const SelfIntersectionReport r = run(mesh);
  EXPECT_EQ(r.intersecting_pairs, 62u);
  EXPECT_EQ(r.first_a, 0u);
  EXPECT_EQ(r.first_b, 12u);
  expect_matches_brute_force(mesh, "two shells");

  // Welded instead (one set of ids): the shared face becomes two pairs of duplicate triangles
  // (all three ids shared); everything else touches only through shared ids and is fine.
  std::vector<SoupTriangle> soup = box_soup(0, 0, 0, 1, 1, 1);
  for (const SoupTriangle& s : box_soup(1, 0, 0, 2, 1, 1)) soup.push_back(s);
  Mesh one = welded(t, soup);
  ASSERT_EQ(one.vertices.size(), 12u);
  const SelfIntersectionReport w = run(one);
  EXPECT_EQ(w.intersecting_pairs, 2u);
  expect_matches_brute_force(one, "two boxes welded");
}

// ---- known self-intersections ------------------------------------------------------------------

TEST(SelfIntersection, TorusWithAVertexPushedThroughTheOppositeWall) {
  TestArena t;
  Mesh mesh = welded(t, shapes::torus(32, 16, 10, 3));
  ASSERT_EQ(run(mesh).intersecting_pairs, 0u);
  // The outer-equator vertex (13, 0, 0) pushed to (4, 0, 0): through the tube and out through
  // its inner wall (radius 7) into the hole.
  uint32_t id = UINT32_MAX;
  for (uint32_t i = 0; i < mesh.vertices.size(); ++i) {
    if (mesh.vertices[i] == Vec3{13, 0, 0}) id = i;
  }
  ASSERT_NE(id, UINT32_MAX);
  mesh.vertices[id] = Vec3{4, 0, 0};
  const SelfIntersectionReport r = run(mesh);
  EXPECT_GT(r.intersecting_pairs, 0u);
  const Brute b = brute_force(mesh);
  EXPECT_EQ(r.intersecting_pairs, b.pairs);
  ASSERT_TRUE(b.is_conflict(r.first_a, r.first_b));
  // Every conflicting pair has one of the spike's triangles (those using the moved vertex).
  for (const auto& c : b.conflicts) {
    const Triangle& s = mesh.triangles[c.first];
    const Triangle& u = mesh.triangles[c.second];
    const bool s_spike = s.v[0] == id || s.v[1] == id || s.v[2] == id;
    const bool u_spike = u.v[0] == id || u.v[1] == id || u.v[2] == id;
    EXPECT_TRUE(s_spike || u_spike);
  }
  expect_matches_brute_force(mesh, "pushed torus");
}

TEST(SelfIntersection, TwoOverlappingBoxesInOneMesh) {
  TestArena t;
  std::vector<SoupTriangle> soup = box_soup(0, 0, 0, 2, 2, 2);
  for (const SoupTriangle& s : box_soup(1, 1, 1, 3, 3, 3)) soup.push_back(s);
  Mesh mesh = welded(t, soup);
  ASSERT_EQ(mesh.vertices.size(), 16u);  // no shared corner
  const SelfIntersectionReport r = run(mesh);
  EXPECT_GT(r.intersecting_pairs, 0u);
  const Mesh& m = mesh;
  const Triangle& s = m.triangles[r.first_a];
  const Triangle& u = m.triangles[r.first_b];
  EXPECT_LT(r.first_a, r.first_b);
  EXPECT_TRUE(oracle::triangles_meet(m.vertices[s.v[0]], m.vertices[s.v[1]], m.vertices[s.v[2]],
                                     m.vertices[u.v[0]], m.vertices[u.v[1]], m.vertices[u.v[2]]));
  expect_matches_brute_force(mesh, "overlapping boxes");

  // Offset by float32 amounts so nothing is axis-coincident, and rotated a little.
  std::vector<SoupTriangle> tilted = box_soup(0, 0, 0, 2, 2, 2);
  for (const SoupTriangle& q : box_soup(1.25f, 0.5f, 0.75f, 3.1f, 2.7f, 2.2f)) tilted.push_back(q);
  for (SoupTriangle& q : tilted) {
    for (auto& p : q.p) {
      const float x = p[0], y = p[1];
      p[0] = 0.8f * x - 0.6f * y;
      p[1] = 0.6f * x + 0.8f * y;
    }
  }
  Mesh tm = welded(t, tilted);
  const SelfIntersectionReport tr = run(tm);
  EXPECT_GT(tr.intersecting_pairs, 0u);
  expect_matches_brute_force(tm, "overlapping boxes, rotated");
}

// ---- the shared-vertex and shared-edge rules ---------------------------------------------------

uint64_t pairs_of(const std::vector<Vec3>& v, const std::vector<Triangle>& tris) {
  TestArena t(size_t{1} << 20);
  Mesh mesh = make_mesh(t, v, tris);
  const Brute b = brute_force(mesh);
  const SelfIntersectionReport r = run(mesh);
  EXPECT_EQ(r.intersecting_pairs, b.pairs) << "brute force disagrees";
  return r.intersecting_pairs;
}

TEST(SelfIntersection, TrianglesSharingAnEdge) {
  const Vec3 p{0, 0, 0}, q{4, 0, 0}, s{1, 3, 0};
  // Coplanar, the free vertices on the same side of the shared edge: folded onto each other.
  EXPECT_EQ(pairs_of({p, q, s, {3, 2, 0}}, {{{0, 1, 2}}, {{1, 0, 3}}}), 1u);
  EXPECT_EQ(pairs_of({p, q, s, {3, 2, 0}}, {{{0, 1, 2}}, {{0, 1, 3}}}), 1u);  // any winding
  EXPECT_EQ(pairs_of({p, q, s, {9, 1, 0}}, {{{0, 1, 2}}, {{1, 0, 3}}}), 1u);  // beyond q
  EXPECT_EQ(pairs_of({p, q, s, {1, 3, 0}}, {{{0, 1, 2}}, {{1, 0, 3}}}), 1u);  // same position
  // Coplanar, opposite sides: a flat continuation.
  EXPECT_EQ(pairs_of({p, q, s, {2, -3, 0}}, {{{0, 1, 2}}, {{1, 0, 3}}}), 0u);
  EXPECT_EQ(pairs_of({p, q, s, {-5, -1, 0}}, {{{0, 1, 2}}, {{1, 0, 3}}}), 0u);
  // Not coplanar (even nearly folded shut): only the edge is shared.
  EXPECT_EQ(pairs_of({p, q, s, {2, 1, 1}}, {{{0, 1, 2}}, {{1, 0, 3}}}), 0u);
  EXPECT_EQ(pairs_of({p, q, s, {1, 3, 0x1p-40}}, {{{0, 1, 2}}, {{1, 0, 3}}}), 0u);
  EXPECT_EQ(pairs_of({p, q, s, {3, 2, -0x1p-60}}, {{{0, 1, 2}}, {{1, 0, 3}}}), 0u);
  // Tilted plane from float32 values, exactly coplanar and folded.
  const Vec3 a{0.25, 0.5, 0.75}, b{1.5, 0.375, 1.875};  // z = x + y
  const Vec3 c{0.5, 1.25, 1.75}, d{1.0, 1.0, 2.0};
  ASSERT_EQ(exact_orient3d_sign(a, b, c, d), 0);
  EXPECT_EQ(pairs_of({a, b, c, d}, {{{0, 1, 2}}, {{1, 0, 3}}}), 1u);
  // All three shared: the same triangle twice (either winding).
  EXPECT_EQ(pairs_of({p, q, s}, {{{0, 1, 2}}, {{2, 1, 0}}}), 1u);
  EXPECT_EQ(pairs_of({p, q, s}, {{{0, 1, 2}}, {{1, 2, 0}}}), 1u);
}

TEST(SelfIntersection, TrianglesSharingOneVertex) {
  const Vec3 o{0, 0, 0};
  // Coplanar wedges that overlap.
  EXPECT_EQ(pairs_of({o, {4, 0, 0}, {4, 4, 0}, {4, 2, 0}, {0, 4, 0}}, {{{0, 1, 2}}, {{0, 3, 4}}}),
            1u);
  // Coplanar wedges along one ray (they share a segment from o).
  EXPECT_EQ(pairs_of({o, {4, 0, 0}, {4, 4, 0}, {2, 2, 0}, {0, 4, 0}}, {{{0, 1, 2}}, {{0, 3, 4}}}),
            1u);
  // One wedge inside the other.
  EXPECT_EQ(pairs_of({o, {4, 0, 0}, {0, 4, 0}, {1, 1, 0}, {1, 2, 0}}, {{{0, 1, 2}}, {{0, 3, 4}}}),
            1u);
  // Coplanar wedges meeting only at o.
  EXPECT_EQ(pairs_of({o, {4, 0, 0}, {4, 4, 0}, {0, 4, 0}, {-4, 4, 0}}, {{{0, 1, 2}}, {{0, 3, 4}}}),
            0u);
  EXPECT_EQ(
      pairs_of({o, {4, 0, 0}, {4, 4, 0}, {-4, 0, 0}, {-4, -4, 0}}, {{{0, 1, 2}}, {{0, 3, 4}}}),
      0u);  // vertical angles
  // Not coplanar: meeting only at o.
  EXPECT_EQ(pairs_of({o, {4, 0, 0}, {0, 4, 0}, {0, 0, 4}, {-4, -4, 4}}, {{{0, 1, 2}}, {{0, 3, 4}}}),
            0u);
  EXPECT_EQ(
      pairs_of({o, {4, 0, 0}, {0, 4, 0}, {-1, -1, 1}, {-1, -1, -1}}, {{{0, 1, 2}}, {{0, 3, 4}}}),
      0u);  // through o's outside
  // Not coplanar: the far edge of one pierces the other, or just touches it.
  EXPECT_EQ(pairs_of({o, {4, 0, 0}, {0, 4, 0}, {1, 1, 1}, {1, 1, -1}}, {{{0, 1, 2}}, {{0, 3, 4}}}),
            1u);
  EXPECT_EQ(pairs_of({o, {4, 0, 0}, {0, 4, 0}, {1, 1, 0}, {1, 1, 5}}, {{{0, 1, 2}}, {{0, 3, 4}}}),
            1u);  // vertex on the face
  EXPECT_EQ(pairs_of({o, {4, 0, 0}, {0, 4, 0}, {2, 2, 0}, {2, 2, 5}}, {{{0, 1, 2}}, {{0, 3, 4}}}),
            1u);  // on the far edge
  EXPECT_EQ(
      pairs_of({o, {4, 0, 0}, {0, 4, 0}, {2, 2, 0x1p-50}, {2, 2, 5}}, {{{0, 1, 2}}, {{0, 3, 4}}}),
      0u);  // just above it
  // A vertex of one at another vertex position of the other (different id): a second contact.
  EXPECT_EQ(pairs_of({o, {4, 0, 0}, {0, 4, 0}, {4, 0, 0}, {0, 0, 4}}, {{{0, 1, 2}}, {{0, 3, 4}}}),
            1u);
}

// ---- random small meshes against the brute force -----------------------------------------------

struct RandomMeshStats {
  int64_t meshes = 0, triangles = 0, skipped = 0, pairs = 0, meshes_with_pairs = 0;
  int64_t by_shared[4] = {0, 0, 0, 0};      // conflicting pairs by shared ids
  int64_t tested_shared[4] = {0, 0, 0, 0};  // candidate pairs by shared ids
};

Vec3 pool_point(std::mt19937_64& rng, int kind) {
  auto integer = [&](int lo, int hi) {
    return static_cast<double>(lo + static_cast<int>(rng() % static_cast<uint64_t>(hi - lo + 1)));
  };
  auto f32 = [&]() {
    return static_cast<double>(static_cast<float>(static_cast<double>(rng() >> 11) * 0x1p-53));
  };
  switch (kind) {
    case 0: {
      const double x = integer(0, 3), y = integer(0, 3), z = integer(0, 3);
      return {x, y, z};
    }
    case 1: {  // a slab: many coplanar triangles
      const double x = integer(0, 4), y = integer(0, 4), z = integer(0, 1);
      return {x, y, z};
    }
    case 2: {
      const double x = f32(), y = f32(), z = f32();
      return {x, y, z};
    }
    default: {  // dyadic points on the tilted plane z = x + y, or one ulp off it (2^-300 off
                // it at 0: the predicates are exact for magnitudes >= 2^-306, not subnormals)
      const double x = integer(0, 8) * 0.125, y = integer(0, 8) * 0.125;
      double z = x + y;
      if (rng() % 4 == 0) z = z == 0.0 ? 0x1p-300 : std::nextafter(z, 9.0);
      return {x, y, z};
    }
  }
}

// Kinds 0-3: 20-60 triangles on a pool of 6-14 vertices (some at repeated positions), mostly
// sharing an edge with an earlier triangle (folds, fans, duplicates); degenerate triangles are
// mostly redrawn, a few kept (skipped by both sides).
// Kinds 4-5: a small closed mesh (a 32-triangle octasphere, a 48-triangle torus) with one or
// two vertices moved: onto another vertex's position, an edge midpoint, or a random point
// nearby; about half of these stay free of self-intersections.
Mesh random_mesh(TestArena& t, std::mt19937_64& rng, int kind) {
  std::vector<Vec3> v;
  std::vector<Triangle> tris;
  if (kind >= 4) {
    TestArena scratch(size_t{1} << 20);
    Mesh closed = welded(scratch, kind == 4 ? octasphere(2, 2.0) : shapes::torus(8, 3, 3, 1));
    v.assign(closed.vertices.begin(), closed.vertices.end());
    tris.assign(closed.triangles.begin(), closed.triangles.end());
    const int moves = rng() % 4 == 0 ? 2 : 1;
    for (int i = 0; i < moves; ++i) {
      Vec3& p = v[rng() % v.size()];
      const Triangle& near = tris[rng() % tris.size()];
      switch (rng() % 3) {
        case 0: p = v[near.v[rng() % 3]]; break;
        case 1: p = (v[near.v[0]] + v[near.v[1]]) * 0.5; break;
        default: {
          const double dx = static_cast<double>(rng() % 9) * 0.25 - 1.0;
          const double dy = static_cast<double>(rng() % 9) * 0.25 - 1.0;
          const double dz = static_cast<double>(rng() % 9) * 0.25 - 1.0;
          p = p + Vec3{dx, dy, dz} * 0.25;
        }
      }
    }
    return make_mesh(t, v, tris);
  }
  const int pool = 6 + static_cast<int>(rng() % 9);
  const int count = 20 + static_cast<int>(rng() % 41);
  for (int i = 0; i < pool; ++i) {
    if (i > 0 && rng() % 6 == 0) {
      v.push_back(v[rng() % v.size()]);  // an earlier position under a new id
    } else {
      v.push_back(pool_point(rng, kind));
    }
  }
  for (int i = 0; i < count; ++i) {
    Triangle tri;
    for (int attempt = 0; attempt < 20; ++attempt) {
      for (uint32_t& id : tri.v) id = static_cast<uint32_t>(rng() % v.size());
      if (!tris.empty() && rng() % 3 != 0) {
        const Triangle& old = tris[rng() % tris.size()];
        const int k = static_cast<int>(rng() % 3);
        tri.v[0] = old.v[(k + 1) % 3];
        tri.v[1] = old.v[k];
      }
      if (!skipped(v.data(), tri) || rng() % 16 == 0) break;
    }
    tris.push_back(tri);
  }
  return make_mesh(t, v, tris);
}

TEST(SelfIntersection, RandomSmallMeshesMatchBruteForce) {
  std::mt19937_64 rng(2024);
  RandomMeshStats st;
  const int meshes = 360 / kRandomDivisor;
  for (int m = 0; m < meshes; ++m) {
    TestArena t(size_t{1} << 20);
    const int kind = m % 6;
    Mesh mesh = random_mesh(t, rng, kind);
    const SelfIntersectionReport r = run(mesh);
    const Brute b = brute_force(mesh);
    ++st.meshes;
    st.triangles += static_cast<int64_t>(mesh.triangles.size());
    for (const Triangle& tri : mesh.triangles) st.skipped += skipped(mesh.vertices.data(), tri);
    st.pairs += static_cast<int64_t>(b.pairs);
    st.meshes_with_pairs += b.pairs > 0;
    for (const auto& c : b.conflicts) {
      int shared = 0;
      for (uint32_t x : mesh.triangles[c.first].v) {
        for (uint32_t y : mesh.triangles[c.second].v) shared += x == y;
      }
      ++st.by_shared[shared];
    }
    const Vec3* v = mesh.vertices.data();
    for (uint32_t a = 0; a < mesh.triangles.size(); ++a) {
      for (uint32_t c = a + 1; c < mesh.triangles.size(); ++c) {
        if (skipped(v, mesh.triangles[a]) || skipped(v, mesh.triangles[c])) continue;
        int shared = 0;
        for (uint32_t x : mesh.triangles[a].v) {
          for (uint32_t y : mesh.triangles[c].v) shared += x == y;
        }
        ++st.tested_shared[shared];
      }
    }
    ASSERT_EQ(r.intersecting_pairs, b.pairs) << "mesh " << m << " (kind " << kind << ")";
    {
      uint64_t all = 0;
      ASSERT_GE(r.candidate_pairs, required_candidates(mesh, b, &all)) << "mesh " << m;
      ASSERT_LE(r.candidate_pairs, all) << "mesh " << m;
    }
    if (b.pairs > 0) {
      ASSERT_EQ(r.first_a, b.first_a) << "mesh " << m;
      ASSERT_EQ(r.first_b, b.first_b) << "mesh " << m;
    }
    // The sweep (taken with more vertices than the hierarchy allows) says the same.
    {
      TestArena copies(size_t{1} << 20);
      const SelfIntersectionReport rs = run(with_unreferenced_copies(copies, mesh));
      ASSERT_EQ(rs.intersecting_pairs, r.intersecting_pairs) << "mesh " << m;
      ASSERT_EQ(rs.first_a, r.first_a) << "mesh " << m;
      ASSERT_EQ(rs.first_b, r.first_b) << "mesh " << m;
      ASSERT_EQ(rs.candidate_pairs, r.candidate_pairs) << "mesh " << m;
    }
    // max_pairs stops at that many, with the pairs the original sweep found first.
    for (uint64_t k : {uint64_t{1}, uint64_t{2}, uint64_t{5}}) {
      const SelfIntersectionReport rk = run(mesh, k);
      ASSERT_EQ(rk.intersecting_pairs, b.pairs < k ? b.pairs : k) << "mesh " << m;
      const SweepReplay e = replay_original_sweep(mesh, k);
      ASSERT_EQ(rk.intersecting_pairs, e.pairs) << "mesh " << m;
      if (rk.intersecting_pairs > 0) {
        ASSERT_TRUE(b.is_conflict(rk.first_a, rk.first_b)) << "mesh " << m;
        ASSERT_EQ(rk.first_a, e.first_a) << "mesh " << m << ", max_pairs " << k;
        ASSERT_EQ(rk.first_b, e.first_b) << "mesh " << m << ", max_pairs " << k;
      }
      ASSERT_LE(rk.candidate_pairs, r.candidate_pairs);
      if (b.pairs <= k) {
        ASSERT_EQ(rk.candidate_pairs, r.candidate_pairs);  // never stopped
      }
    }
  }
  std::printf(
      "[   info   ] %lld meshes, %lld triangles (%lld degenerate, skipped), %lld conflicting "
      "pairs in %lld meshes; conflicts / tested by shared ids: 0: %lld/%lld, 1: %lld/%lld, "
      "2: %lld/%lld, 3: %lld/%lld\n",
      static_cast<long long>(st.meshes), static_cast<long long>(st.triangles),
      static_cast<long long>(st.skipped), static_cast<long long>(st.pairs),
      static_cast<long long>(st.meshes_with_pairs), static_cast<long long>(st.by_shared[0]),
      static_cast<long long>(st.tested_shared[0]), static_cast<long long>(st.by_shared[1]),
      static_cast<long long>(st.tested_shared[1]), static_cast<long long>(st.by_shared[2]),
      static_cast<long long>(st.tested_shared[2]), static_cast<long long>(st.by_shared[3]),
      static_cast<long long>(st.tested_shared[3]));
  // Hard sets: every sharing case both conflicts and does not, often.
  for (int s = 0; s < 3; ++s) {
    EXPECT_GT(st.by_shared[s], st.meshes) << "shared " << s;
    EXPECT_LT(st.by_shared[s], st.tested_shared[s] * 9 / 10) << "shared " << s;
  }
  EXPECT_GT(st.by_shared[3], 0);
  EXPECT_GT(st.skipped, 0);
  EXPECT_GT(st.meshes_with_pairs, st.meshes / 2);
  EXPECT_LT(st.meshes_with_pairs, st.meshes * 19 / 20);
}

// ---- vertex stars, large meshes, the sweep
// ---------------------------------------------------------

// A fan of eight triangles around the origin whose rim turns twice around it along the four
// axis directions (radius 1 on the first turn, 2 on the second): its star is a closed,
// consistently oriented fan facing +z, but not embedded. Flat, the two triangles over each
// quadrant overlap (4 pairs), and so do, along each of the four rays, the two edges on it
// that are not one shared edge (8 pairs): 12 conflicts, all sharing only the origin. One
// turn of four quadrants is embedded, flat or with its rim at alternating heights.
TEST(SelfIntersection, AStarTurningTwiceIsNotCleared) {
  auto fan = [](int turns, double lift) {
    const Vec3 dir[4] = {{1, 0, 0}, {0, 1, 0}, {-1, 0, 0}, {0, -1, 0}};
    std::vector<Vec3> v = {{0, 0, 0}};
    std::vector<Triangle> tris;
    const uint32_t k = 4 * static_cast<uint32_t>(turns);
    for (uint32_t i = 0; i < k; ++i) {
      v.push_back(dir[i % 4] * (i < 4 ? 1.0 : 2.0) + Vec3{0, 0, i % 2 == 0 ? 0.0 : lift});
    }
    for (uint32_t i = 0; i < k; ++i) tris.push_back(Triangle{{0, 1 + i, 1 + (i + 1) % k}});
    return std::make_pair(v, tris);
  };
  const auto twice = fan(2, 0.0);
  EXPECT_EQ(pairs_of(twice.first, twice.second), 12u);
  const auto once = fan(1, 0.0);
  EXPECT_EQ(pairs_of(once.first, once.second), 0u);
  const auto rising = fan(1, 0.5);
  EXPECT_EQ(pairs_of(rising.first, rising.second), 0u);
}

// A flat fan of six triangles around the origin whose rim runs to 0, 55, 115, 25, 205 and
// 290 degrees: the third triangle turns back (it faces -z, the others +z) over the first
// two, yet the rim still turns once around the origin, so only the faces' signs tell that
// the star is not embedded. The first and third triangles share only the origin: only its
// star can clear them (an edge's pairs are tested through the rim's stars, which are open).
// Each triangle is first in the list once (the star's fan starts there), so the one turned
// back takes every place in the fan; each time the overlaps are found, as brute force finds
// them.
TEST(SelfIntersection, AStarWithOneTriangleTurnedBackIsNotClearedWhereverItStarts) {
  const double kDeg = 3.14159265358979323846 / 180;
  const double angle[6] = {0, 55, 115, 25, 205, 290};
  std::vector<Vec3> v = {{0, 0, 0}};
  for (const double a : angle) v.push_back(Vec3{std::cos(a * kDeg), std::sin(a * kDeg), 0});
  for (uint32_t first = 0; first < 6; ++first) {
    std::vector<Triangle> tris;
    for (uint32_t j = 0; j < 6; ++j) {
      const uint32_t i = (first + j) % 6;
      tris.push_back(Triangle{{0, 1 + i, 1 + (i + 1) % 6}});
    }
    EXPECT_GT(pairs_of(v, tris), 0u) << "first " << first;
  }
}

// A closed prism over a thin triangle with a 5-degree corner, swept along a gentle arc: at the
// sharp edge, the sum of the normals of the big faces leaves the narrow ones nearly edge-on,
// the case the stars retry with normals scaled alike. Valid, so nothing may be reported;
// then with a section pushed through the opposite wall.
TEST(SelfIntersection, SharpFoldsAndAPushedSectionMatchBruteForce) {
  TestArena t;
  const int sections = 40;
  const double tan5 = std::tan(5.0 * 3.14159265358979323846 / 180.0);
  std::vector<Vec3> v;
  std::vector<Triangle> tris;
  for (int s = 0; s < sections; ++s) {
    const double a = 0.02 * s, cx = 20.0 * std::cos(a), cy = 20.0 * std::sin(a);
    const double ux = std::cos(a), uy = std::sin(a);  // outward
    // The section in the plane (u, z): (0, 0), (8, 0), (8, 8 tan 5): the corner at (0, 0).
    const double pts[3][2] = {{0, 0}, {8, 0}, {8, 8 * tan5}};
    for (const auto& q : pts) {
      v.push_back(Vec3{static_cast<double>(static_cast<float>(cx + ux * q[0])),
                       static_cast<double>(static_cast<float>(cy + uy * q[0])),
                       static_cast<double>(static_cast<float>(q[1]))});
    }
  }
  for (uint32_t s = 0; s + 1 < sections; ++s) {
    for (uint32_t j = 0; j < 3; ++j) {
      const uint32_t a = 3 * s + j, b = 3 * s + (j + 1) % 3;
      const uint32_t c = 3 * (s + 1) + (j + 1) % 3, d = 3 * (s + 1) + j;
      tris.push_back(Triangle{{a, c, b}});
      tris.push_back(Triangle{{a, d, c}});
    }
  }
  const uint32_t last = 3 * (sections - 1);
  tris.push_back(Triangle{{0, 1, 2}});
  tris.push_back(Triangle{{last, last + 2, last + 1}});
  Mesh mesh = make_mesh(t, v, tris);
  MeshReport check;
  Context ctx(&t.arena);
  SPLINTCORE_ASSERT_OK(check_mesh(ctx, mesh, &check));
  ASSERT_TRUE(check.closed() && check.edge_manifold() && check.oriented());
  const SelfIntersectionReport r = run(mesh);
  EXPECT_EQ(r.intersecting_pairs, 0u);
  expect_matches_brute_force(mesh, "sharp prism");
  // Section 20 pushed down through the bottom face (z = 0): its sharp corner by 1 mm, its top
  // corner by 2 mm.
  mesh.vertices[3 * 20] = mesh.vertices[3 * 20] + Vec3{0, 0, -1};
  mesh.vertices[3 * 20 + 2] = mesh.vertices[3 * 20 + 2] + Vec3{0, 0, -2};
  const SelfIntersectionReport pushed = run(mesh);
  EXPECT_GT(pushed.intersecting_pairs, 0u);
  expect_matches_brute_force(mesh, "pushed sharp prism");
}

// A torus of 2,304 triangles with a few dozen vertices moved at random: a hierarchy several
// levels deep, against the brute force.
TEST(SelfIntersection, LargePerturbedTorusMatchesBruteForce) {
  TestArena t;
  Mesh mesh = welded(t, shapes::torus(48, 24, 10, 3));
  ASSERT_EQ(mesh.triangles.size(), 2304u);
  expect_matches_brute_force(mesh, "torus 48x24");
  std::mt19937_64 rng(7);
  for (int i = 0; i < 40 / kRandomDivisor; ++i) {
    Vec3& p = mesh.vertices[rng() % mesh.vertices.size()];
    const double dx = static_cast<double>(rng() % 17) * 0.25 - 2.0;
    const double dy = static_cast<double>(rng() % 17) * 0.25 - 2.0;
    const double dz = static_cast<double>(rng() % 17) * 0.25 - 2.0;
    p = p + Vec3{dx, dy, dz};
  }
  const SelfIntersectionReport r = run(mesh);
  EXPECT_GT(r.intersecting_pairs, 0u);
  expect_matches_brute_force(mesh, "perturbed torus");
  for (uint64_t k : {uint64_t{1}, uint64_t{3}}) expect_original_order(mesh, k, "perturbed torus");
}

// Moves `count` vertices of *mesh, picked at random (seed), by up to 2 mm along each axis: a
// torus pushed through itself in places.
void push_vertices(uint64_t seed, int count, Mesh* mesh) {
  std::mt19937_64 rng(seed);
  for (int i = 0; i < count; ++i) {
    Vec3& p = mesh->vertices[rng() % mesh->vertices.size()];
    p = p + Vec3{static_cast<double>(rng() % 9) * 0.5 - 2.0,
                 static_cast<double>(rng() % 9) * 0.5 - 2.0, static_cast<double>(rng() % 5) - 2.0};
  }
}

// A clean octasphere of 12,800 triangles, a torus of 9,216 with vertices pushed through it,
// and a sphere and a torus crossing in one mesh.
struct ThreeMeshes {
  static constexpr const char* kNames[3] = {"octasphere", "pushed torus", "sphere and torus"};
  Mesh meshes[3];
  explicit ThreeMeshes(TestArena& t) {
    meshes[0] = welded(t, octasphere(40, 5.0));
    meshes[1] = welded(t, shapes::torus(96, 48, 10, 3));
    push_vertices(11, 30, &meshes[1]);
    std::vector<SoupTriangle> both = octasphere(40, 5.0);
    for (const SoupTriangle& q : shapes::torus(96, 48, 6, 2)) both.push_back(q);
    meshes[2] = welded(t, both);
  }
};

// The hierarchy and the sweep over boxes (taken when a mesh has more than three vertices a
// triangle) report the same pairs, first pair and candidates; with max_pairs below the pairs
// there are, the hierarchy's answer in the sweep's order (the first max_pairs pairs the sweep
// meets, and the candidates it met up to the last of them) is the sweep's.
TEST(SelfIntersection, HierarchyAndSweepAgree) {
  TestArena t;
  std::vector<SoupTriangle> boxes = box_soup(0, 0, 0, 2, 2, 2);
  for (const SoupTriangle& q : box_soup(1, 1, 1, 3, 3, 3)) boxes.push_back(q);
  Mesh pushed = welded(t, shapes::torus(48, 24, 10, 3));
  push_vertices(5, 12, &pushed);
  const Mesh meshes[4] = {welded(t, shapes::torus(32, 16, 10, 3)), welded(t, octasphere(12, 4.0)),
                          welded(t, boxes), pushed};
  for (int m = 0; m < 4; ++m) {
    const Mesh& mesh = meshes[m];
    const Mesh sweep_only = with_unreferenced_copies(t, mesh);
    const uint64_t all = run(mesh).intersecting_pairs;
    EXPECT_EQ(all > 0, m >= 2) << m;
    for (uint64_t k : {uint64_t{0}, uint64_t{1}, uint64_t{2}, uint64_t{3}, uint64_t{7}, all / 2}) {
      const SelfIntersectionReport h = run(mesh, k);
      const SelfIntersectionReport s = run(sweep_only, k);
      EXPECT_EQ(h.intersecting_pairs, s.intersecting_pairs) << m << ", max_pairs " << k;
      EXPECT_EQ(h.first_a, s.first_a) << m << ", max_pairs " << k;
      EXPECT_EQ(h.first_b, s.first_b) << m << ", max_pairs " << k;
      EXPECT_EQ(h.candidate_pairs, s.candidate_pairs) << m << ", max_pairs " << k;
      EXPECT_GT(h.candidate_pairs, 0u);
    }
  }
}

// Coordinates beyond the filters' range (2^100 here) take the original sweep over boxes:
// still exact within the predicates' range, with the box overlaps as candidates.
TEST(SelfIntersection, CoordinatesBeyondTheFiltersRangeTakeTheBoxSweep) {
  TestArena t;
  std::vector<SoupTriangle> soup = box_soup(0, 0, 0, 2, 2, 2);
  for (const SoupTriangle& q : box_soup(1.25f, 0.5f, 0.75f, 3.1f, 2.7f, 2.2f)) soup.push_back(q);
  Mesh mesh = welded(t, soup);
  for (Vec3& p : mesh.vertices) p = p * 0x1p120;
  const SelfIntersectionReport r = run(mesh);
  const Brute b = brute_force(mesh);
  EXPECT_GT(b.pairs, 0u);
  EXPECT_EQ(r.intersecting_pairs, b.pairs);
  EXPECT_EQ(r.first_a, b.first_a);
  EXPECT_EQ(r.first_b, b.first_b);
  EXPECT_EQ(r.candidate_pairs, b.candidates);
  expect_original_order(mesh, 1, "scaled boxes");
}

// ---- max_pairs, arena, errors
// --------------------------------------------------------------------

TEST(SelfIntersection, MaxPairsStopsEarly) {
  TestArena t;
  std::vector<SoupTriangle> soup = box_soup(0, 0, 0, 2, 2, 2);
  for (const SoupTriangle& s : box_soup(1, 1, 1, 3, 3, 3)) soup.push_back(s);
  Mesh mesh = welded(t, soup);
  const SelfIntersectionReport all = run(mesh);
  ASSERT_GT(all.intersecting_pairs, 3u);
  const Brute b = brute_force(mesh);
  for (uint64_t k = 1; k <= all.intersecting_pairs + 2; ++k) {
    const SelfIntersectionReport r = run(mesh, k);
    EXPECT_EQ(r.intersecting_pairs, k < all.intersecting_pairs ? k : all.intersecting_pairs);
    EXPECT_TRUE(b.is_conflict(r.first_a, r.first_b)) << k;
    EXPECT_LE(r.candidate_pairs, all.candidate_pairs);
    expect_original_order(mesh, k, "overlapping boxes");
  }
  EXPECT_EQ(run(mesh, 1).self_intersecting(), true);
}

// Every cap from 0 up: kArenaExhausted with an actionable need, or the full answer.
TEST(SelfIntersection, ArenaExhaustionSweep) {
  TestArena t;
  std::vector<SoupTriangle> soup = box_soup(0, 0, 0, 2, 2, 2);
  for (const SoupTriangle& s : box_soup(1, 1, 1, 3, 3, 3)) soup.push_back(s);
  for (const SoupTriangle& s : shapes::torus(8, 6, 10, 3)) soup.push_back(s);
  Mesh mesh = welded(t, soup);
  const SelfIntersectionReport expected = run(mesh);
  ASSERT_GT(expected.intersecting_pairs, 0u);

  std::vector<unsigned char> memory(size_t{1} << 17);
  unsigned char* base = memory.data();
  base += (64 - reinterpret_cast<uintptr_t>(base) % 64) % 64;  // same padding for every cap
  size_t high_water = 0;
  {
    Arena arena(base, memory.size() - 64);
    Context ctx(&arena);
    SelfIntersectionReport r;
    SPLINTCORE_ASSERT_OK(find_self_intersections(ctx, mesh, 0, &r));
    high_water = arena.high_water();
    EXPECT_EQ(arena.used(), 0u);
  }
  ASSERT_GT(high_water, 0u);
  ASSERT_LT(high_water + 256, memory.size() - 64);
  EXPECT_LE(high_water, find_self_intersections_bound(mesh.triangles.size()));

  auto attempt = [&](size_t cap, SelfIntersectionReport* r, size_t* need) {
    Arena arena(base, cap);
    Context ctx(&arena);
    Status s = find_self_intersections(ctx, mesh, 0, r);
    EXPECT_EQ(arena.used(), 0u) << "cap " << cap;
    EXPECT_LE(arena.high_water(), cap);
    *need = arena.last_need();
    return s;
  };
  size_t first_success = 0;
  for (size_t cap = 0; cap <= high_water + 256; ++cap) {
    SelfIntersectionReport r;
    size_t need = 0;
    Status s = attempt(cap, &r, &need);
    if (s.is_ok()) {
      if (first_success == 0) first_success = cap;
      EXPECT_EQ(r.intersecting_pairs, expected.intersecting_pairs) << "cap " << cap;
      EXPECT_EQ(r.first_a, expected.first_a) << "cap " << cap;
      EXPECT_EQ(r.first_b, expected.first_b) << "cap " << cap;
      EXPECT_EQ(r.candidate_pairs, expected.candidate_pairs) << "cap " << cap;
      continue;
    }
    ASSERT_EQ(s.code(), StatusCode::kArenaExhausted) << "cap " << cap << ": " << test::format(s);
    EXPECT_EQ(first_success, 0u) << "failed at cap " << cap << " after succeeding at "
                                 << first_success;
    EXPECT_GT(need, cap) << test::format(s);
    EXPECT_NE(std::string(s.message()).find("arena exhausted"), std::string::npos);
    // The need is actionable: with it, the run succeeds or gets further.
    if (cap % 7 == 0 && need <= high_water + 256) {
      SelfIntersectionReport again;
      size_t need2 = 0;
      Status s2 = attempt(need, &again, &need2);
      if (!s2.is_ok()) {
        EXPECT_GT(need2, need) << "cap " << cap;
      }
    }
  }
  // Below the whole pass's peak, the pass runs in slabs along x (the same answer above).
  EXPECT_LT(first_success, high_water);
  {
    SelfIntersectionReport r;
    size_t need = 0;
    Status s = attempt(first_success - 1, &r, &need);
    EXPECT_FALSE(s.is_ok());
  }
}

// When the whole pass does not fit, the slabs along x give the same report (every pair counted
// in one slab only: the same candidates) in a fraction of the memory, at every thread count;
// with max_pairs below the pairs there are, too.
TEST(SelfIntersection, SlabsGiveTheSameReportInLessMemory) {
  TestArena t;
  const ThreeMeshes three(t);
  const Mesh* meshes = three.meshes;
  const char* const* names = ThreeMeshes::kNames;
  std::vector<unsigned char> memory(size_t{8} << 20);
  unsigned char* base = memory.data();
  base += (64 - reinterpret_cast<uintptr_t>(base) % 64) % 64;
  for (int m = 0; m < 3; ++m) {
    const Mesh& mesh = meshes[m];
    const SelfIntersectionReport whole = run(mesh);
    EXPECT_EQ(whole.intersecting_pairs > 0, m > 0) << names[m];
    auto attempt = [&](size_t cap, const Executor* executor, SelfIntersectionReport* r,
                       uint64_t max_pairs = 0) {
      Arena arena(base, cap);
      const Context ctx(&arena, executor, nullptr);
      const Status s = find_self_intersections(ctx, mesh, max_pairs, r);
      EXPECT_EQ(arena.used(), 0u);
      EXPECT_LE(arena.high_water(), cap);
      if (!s.is_ok()) {
        EXPECT_EQ(s.code(), StatusCode::kArenaExhausted) << names[m] << ": " << test::format(s);
      }
      return s.is_ok() ? size_t{0} : arena.last_need();
    };
    size_t peak = 0;
    {
      Arena arena(base, memory.size() - 64);
      const Context ctx(&arena);
      SelfIntersectionReport r;
      SPLINTCORE_ASSERT_OK(find_self_intersections(ctx, mesh, 0, &r));
      peak = arena.high_water();
    }
    // The least cap that works, by halving (success is monotone in the cap).
    size_t fails = 0, works = peak;
    while (fails + 1 < works) {
      const size_t mid = fails + (works - fails) / 2;
      SelfIntersectionReport r;
      (attempt(mid, nullptr, &r) == 0 ? works : fails) = mid;
    }
    EXPECT_LT(works, peak / 3) << names[m] << ": least cap " << works << ", whole " << peak;
    ThreadExecutor pool(2);
    for (const Executor* executor : {static_cast<const Executor*>(nullptr), &pool.executor()}) {
      for (size_t cap : {works, (works + peak) / 2}) {
        SelfIntersectionReport r;
        ASSERT_EQ(attempt(cap, executor, &r), 0u) << names[m] << ", cap " << cap;
        EXPECT_EQ(r.intersecting_pairs, whole.intersecting_pairs) << names[m] << ", cap " << cap;
        EXPECT_EQ(r.first_a, whole.first_a) << names[m] << ", cap " << cap;
        EXPECT_EQ(r.first_b, whole.first_b) << names[m] << ", cap " << cap;
        EXPECT_EQ(r.candidate_pairs, whole.candidate_pairs) << names[m] << ", cap " << cap;
      }
    }
    // Fewer pairs asked for than there are: the sweep's first pairs, found in slabs too (a
    // pair kept takes 32 bytes more).
    for (uint64_t k : {uint64_t{1}, uint64_t{3}}) {
      const SelfIntersectionReport ample = run(mesh, k);
      SelfIntersectionReport r;
      ASSERT_EQ(attempt(works + 1024, nullptr, &r, k), 0u) << names[m] << ", max_pairs " << k;
      EXPECT_EQ(r.intersecting_pairs, ample.intersecting_pairs) << names[m] << ", " << k;
      EXPECT_EQ(r.first_a, ample.first_a) << names[m] << ", max_pairs " << k;
      EXPECT_EQ(r.first_b, ample.first_b) << names[m] << ", max_pairs " << k;
      EXPECT_EQ(r.candidate_pairs, ample.candidate_pairs) << names[m] << ", max_pairs " << k;
    }
    SelfIntersectionReport r;
    const size_t need = attempt(works - 1, nullptr, &r);
    EXPECT_GE(need, works) << names[m];
    std::printf("%s: %zu triangles, whole pass %zu bytes, least cap %zu\n", names[m],
                mesh.triangles.size(), peak, works);
  }
}

TEST(SelfIntersection, EmptyMeshBadIndexAndCancellation) {
  TestArena t;
  Mesh empty(&t.arena);
  const SelfIntersectionReport r = run(empty);
  EXPECT_EQ(r.intersecting_pairs, 0u);
  EXPECT_EQ(r.candidate_pairs, 0u);

  Mesh bad = make_mesh(t, {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{{0, 1, 2}}, {{0, 1, 3}}});
  {
    TestArena work(size_t{1} << 20);
    Context ctx(&work.arena);
    SelfIntersectionReport rep;
    Status s = find_self_intersections(ctx, bad, 0, &rep);
    EXPECT_EQ(s.code(), StatusCode::kInvalidMesh);
    EXPECT_EQ(s.index(), 1u);
    EXPECT_EQ(work.arena.used(), 0u);
  }

  Mesh torus = welded(t, shapes::torus(16, 8, 10, 3));
  {
    TestArena work(size_t{1} << 20);
    Progress progress;
    progress.report = [](void*, const char*, uint64_t, uint64_t) { return false; };
    Context ctx(&work.arena, nullptr, &progress);
    SelfIntersectionReport rep;
    Status s = find_self_intersections(ctx, torus, 0, &rep);
    EXPECT_EQ(s.code(), StatusCode::kCancelled);
    EXPECT_EQ(work.arena.used(), 0u);
  }
}

// ---- threads ----------------------------------------------------------------------------------

// The traversal in tasks (more than 8,192 triangles and an executor) gives the report one
// thread gives, pairs, first pair and candidates, whether it counts all, stops at max_pairs
// (then in the sweep's order) or finds nothing: a clean octasphere of 12,800 triangles, a torus of
// 9,216 with vertices pushed through it, and both in one mesh.
TEST(SelfIntersection, SameReportAtEveryThreadCount) {
  TestArena t;
  const ThreeMeshes three(t);
  const Mesh* meshes = three.meshes;
  const char* const* names = ThreeMeshes::kNames;
  ASSERT_GE(meshes[1].triangles.size(), 8192u);
  for (int m = 0; m < 3; ++m) {
    for (uint64_t max_pairs : {uint64_t{0}, uint64_t{1}, uint64_t{7}}) {
      const SelfIntersectionReport one = run(meshes[m], max_pairs);
      if (m == 0) {
        EXPECT_EQ(one.intersecting_pairs, 0u);
      } else {
        EXPECT_GT(one.intersecting_pairs, 0u) << names[m];
      }
      for (unsigned threads : {2u, 3u, 5u}) {
        ThreadExecutor pool(threads);
        TestArena work(size_t{16} << 20);
        const Context ctx(&work.arena, &pool.executor(), nullptr);
        SelfIntersectionReport r;
        SPLINTCORE_ASSERT_OK(find_self_intersections(ctx, meshes[m], max_pairs, &r));
        EXPECT_EQ(r.intersecting_pairs, one.intersecting_pairs)
            << names[m] << ", " << threads << " threads, max_pairs " << max_pairs;
        EXPECT_EQ(r.first_a, one.first_a) << names[m] << ", " << threads << " threads";
        EXPECT_EQ(r.first_b, one.first_b) << names[m] << ", " << threads << " threads";
        EXPECT_EQ(r.candidate_pairs, one.candidate_pairs)
            << names[m] << ", " << threads << " threads, max_pairs " << max_pairs;
        EXPECT_EQ(work.arena.used(), 0u);
      }
    }
  }
}

// The checks before the pass run in runs on the executor: a mesh with vertex ids out of range
// in several runs names the first such triangle at every thread count.
TEST(SelfIntersection, FirstBadTriangleAtEveryThreadCount) {
  TestArena t;
  Mesh torus = welded(t, shapes::torus(96, 48, 10, 3));
  const uint32_t nv = static_cast<uint32_t>(torus.vertices.size());
  const size_t nt = torus.triangles.size();
  for (size_t first : {size_t{0}, nt / 5, nt - 1}) {
    Mesh bad = welded(t, shapes::torus(96, 48, 10, 3));  // (a copy would share the arrays)
    bad.triangles[first].v[1] = nv;                      // the first bad one, then others after it
    for (size_t later = first + 1; later < nt; later += nt / 7) bad.triangles[later].v[2] = nv + 5;
    for (unsigned threads : {1u, 2u, 3u}) {
      ThreadExecutor pool(threads);
      TestArena work(size_t{1} << 20);
      const Context ctx(&work.arena, &pool.executor(), nullptr);
      SelfIntersectionReport r;
      const Status s = find_self_intersections(ctx, bad, 0, &r);
      EXPECT_EQ(s.code(), StatusCode::kInvalidMesh) << threads << " threads";
      EXPECT_EQ(s.index(), first) << threads << " threads";
      EXPECT_EQ(work.arena.used(), 0u);
    }
  }
}

}  // namespace
}  // namespace splintcore
