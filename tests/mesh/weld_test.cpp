#include <algorithm>
#include <random>

#include "support/test_util.h"

namespace splintcore {
namespace {

using test::TestArena;

TEST(WeldExact, BoxWeldsToEightVerticesInFirstAppearanceOrder) {
  TestArena t;
  const float lo[3] = {0, 0, 0}, hi[3] = {1, 2, 3};
  auto soup = shapes::box(lo, hi);
  Mesh mesh;
  SPLINTCORE_ASSERT_OK(test::mesh_from_soup(t.arena, soup, &mesh));
  EXPECT_EQ(mesh.vertices.size(), 8u);
  ASSERT_EQ(mesh.triangles.size(), 12u);
  // First triangle's corners get ids 0, 1, 2 in order.
  EXPECT_EQ(mesh.triangles[0].v[0], 0u);
  EXPECT_EQ(mesh.triangles[0].v[1], 1u);
  EXPECT_EQ(mesh.triangles[0].v[2], 2u);
  EXPECT_EQ(mesh.vertices[0], (Vec3{0, 0, 0}));
  // Every corner maps to a vertex with exactly its coordinates.
  for (size_t i = 0; i < soup.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      const Vec3& v = mesh.vertices[mesh.triangles[i].v[k]];
      EXPECT_EQ(v, (Vec3{soup[i].p[k][0], soup[i].p[k][1], soup[i].p[k][2]}));
    }
  }
}

TEST(WeldExact, DistinguishesNeighbouringFloatsAndMergesSignedZeros) {
  TestArena t;
  float a[3] = {1.0f, 0.0f, 0.0f};
  float b[3] = {std::nextafter(1.0f, 2.0f), 0.0f, 0.0f};
  float c[3] = {0.0f, 1.0f, -0.0f};
  float d[3] = {-0.0f, 1.0f, 0.0f};
  std::vector<SoupTriangle> soup = {shapes::soup_triangle(a, b, c), shapes::soup_triangle(a, c, d)};
  Mesh mesh;
  SPLINTCORE_ASSERT_OK(test::mesh_from_soup(t.arena, soup, &mesh));
  EXPECT_EQ(mesh.vertices.size(), 3u);  // a, b, c==d
  EXPECT_EQ(mesh.triangles[1].v[2], mesh.triangles[0].v[2]);
  EXPECT_FALSE(std::signbit(mesh.vertices[2].x));  // no negative zero in the mesh
}

TEST(WeldExact, RejectsNonFiniteNamingTheTriangle) {
  TestArena t;
  float a[3] = {0, 0, 0}, b[3] = {1, 0, 0}, c[3] = {0, std::numeric_limits<float>::infinity(), 0};
  std::vector<SoupTriangle> soup = {shapes::soup_triangle(a, b, a), shapes::soup_triangle(a, b, c)};
  Mesh mesh;
  Status s = test::mesh_from_soup(t.arena, soup, &mesh);
  EXPECT_EQ(s.code(), StatusCode::kNonFinite);
  EXPECT_EQ(s.index(), 1u);
}

TEST(WeldExact, LeavesOnlyTheMeshInTheArena) {
  TestArena t;
  auto soup = shapes::torus(40, 30, 10, 3);
  Mesh mesh;
  size_t before = t.arena.used();
  SPLINTCORE_ASSERT_OK(test::mesh_from_soup(t.arena, soup, &mesh));
  size_t expected = mesh.triangles.size() * sizeof(Triangle) + mesh.vertices.size() * sizeof(Vec3);
  EXPECT_LE(t.arena.used() - before, expected + 64);
  EXPECT_LE(t.arena.high_water(), weld_exact_bound(soup.size()) + before);
  EXPECT_EQ(mesh.vertices.size(), 40u * 30u);
}

// Permuting triangles never moves a vertex, and every weld class is within tolerance chains.
TEST(WeldTolerance, OrderIndependentPositions) {
  std::mt19937_64 rng(7);
  auto soup = shapes::torus(24, 16, 10, 3);
  // Jitter every corner by up to 1e-4 mm so exact welding would fail.
  std::uniform_real_distribution<float> jitter(-1e-4f, 1e-4f);
  for (auto& tri : soup) {
    for (auto& p : tri.p) {
      for (float& x : p) x += jitter(rng);
    }
  }
  TestArena t1;
  Context c1(&t1.arena);
  Mesh m1(&t1.arena);
  SPLINTCORE_ASSERT_OK(
      weld_tolerance(c1, Span<const SoupTriangle>(soup.data(), soup.size()), 1e-3, &m1));
  EXPECT_EQ(m1.vertices.size(), 24u * 16u);
  MeshReport r;
  SPLINTCORE_ASSERT_OK(check_mesh(c1, m1, &r));
  EXPECT_TRUE(r.closed());
  EXPECT_EQ(r.genus, 1);

  std::vector<size_t> perm(soup.size());
  for (size_t i = 0; i < perm.size(); ++i) perm[i] = i;
  std::shuffle(perm.begin(), perm.end(), rng);
  std::vector<SoupTriangle> shuffled(soup.size());
  for (size_t i = 0; i < perm.size(); ++i) shuffled[i] = soup[perm[i]];
  TestArena t2;
  Context c2(&t2.arena);
  Mesh m2(&t2.arena);
  SPLINTCORE_ASSERT_OK(
      weld_tolerance(c2, Span<const SoupTriangle>(shuffled.data(), shuffled.size()), 1e-3, &m2));
  ASSERT_EQ(m2.vertices.size(), m1.vertices.size());
  for (size_t i = 0; i < perm.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      ASSERT_EQ(m2.vertices[m2.triangles[i].v[k]], m1.vertices[m1.triangles[perm[i]].v[k]]);
    }
  }
}

TEST(WeldTolerance, RejectsBadTolerance) {
  TestArena t;
  Context ctx(&t.arena);
  auto soup = shapes::torus(6, 4, 10, 3);
  Mesh m(&t.arena);
  Span<const SoupTriangle> s(soup.data(), soup.size());
  EXPECT_EQ(weld_tolerance(ctx, s, 0.0, &m).code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(weld_tolerance(ctx, s, -1.0, &m).code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(weld_tolerance(ctx, s, std::nan(""), &m).code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(weld_tolerance(ctx, s, 1e-12, &m).code(), StatusCode::kLimitExceeded);
}

}  // namespace
}  // namespace splintcore
