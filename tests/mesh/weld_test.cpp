#include <algorithm>
#include <random>

#include "mesh/exact_weld.h"
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

// An indexed mesh whose vertices repeat positions (bit-equal, signed zeros, neighbouring
// floats), some never used, and whose triangles may repeat an index: the material
// weld_indexed_exact() and weld_exact() must agree on.
struct IndexedCase {
  std::vector<Vec3> vertices;
  std::vector<Triangle> triangles;
};

IndexedCase random_indexed(uint32_t seed) {
  std::mt19937 rng(seed);
  const float pool[] = {0.0f, -0.0f, 1.0f, std::nextafter(1.0f, 2.0f), -2.5f, 3.0e-39f, 1e6f};
  std::uniform_int_distribution<int> pick(0, 6);
  std::uniform_int_distribution<uint32_t> count(1, 60);
  IndexedCase c;
  const uint32_t nv = count(rng), nt = count(rng);
  for (uint32_t i = 0; i < nv; ++i) {
    c.vertices.push_back(
        Vec3{double{pool[pick(rng)]}, double{pool[pick(rng)]}, double{pool[pick(rng)]}});
  }
  std::uniform_int_distribution<uint32_t> index(0, nv - 1);
  for (uint32_t t = 0; t < nt; ++t)
    c.triangles.push_back(Triangle{{index(rng), index(rng), index(rng)}});
  return c;
}

bool same_bits(const Vec3& a, const Vec3& b) { return std::memcmp(&a, &b, sizeof(Vec3)) == 0; }

TEST(WeldIndexedExact, GivesWeldExactsMeshBitForBit) {
  for (uint32_t seed = 1; seed <= 400; ++seed) {
    const IndexedCase c = random_indexed(seed);
    TestArena t(size_t{1} << 20);
    std::vector<SoupTriangle> soup;
    for (const Triangle& tri : c.triangles) {
      SoupTriangle s;
      for (int k = 0; k < 3; ++k) {
        const Vec3& v = c.vertices[tri.v[k]];
        for (int a = 0; a < 3; ++a) s.p[k][a] = static_cast<float>(v[a]);
      }
      soup.push_back(s);
    }
    Mesh expected(&t.arena);
    SPLINTCORE_ASSERT_OK(weld_exact(Context(&t.arena),
                                    Span<const SoupTriangle>(soup.data(), soup.size()), &expected));
    Mesh mesh(&t.arena);
    ASSERT_TRUE(mesh.vertices.resize(c.vertices.size()));
    ASSERT_TRUE(mesh.triangles.resize(c.triangles.size()));
    std::copy(c.vertices.begin(), c.vertices.end(), mesh.vertices.data());
    std::copy(c.triangles.begin(), c.triangles.end(), mesh.triangles.data());
    const size_t used = t.arena.used();
    SPLINTCORE_ASSERT_OK(weld_indexed_exact(Context(&t.arena), &mesh));
    EXPECT_EQ(t.arena.used(), used) << "seed " << seed;  // the temporaries given back
    ASSERT_EQ(mesh.vertices.size(), expected.vertices.size()) << "seed " << seed;
    for (size_t i = 0; i < mesh.vertices.size(); ++i) {
      EXPECT_TRUE(same_bits(mesh.vertices[i], expected.vertices[i]))
          << "seed " << seed << " vertex " << i;
    }
    ASSERT_EQ(mesh.triangles.size(), expected.triangles.size());
    for (size_t i = 0; i < mesh.triangles.size(); ++i) {
      for (int k = 0; k < 3; ++k) {
        EXPECT_EQ(mesh.triangles[i].v[k], expected.triangles[i].v[k]) << "seed " << seed;
      }
    }
  }
}

// Run above the mesh in exactly weld_indexed_exact_bound(vertex count) bytes it succeeds;
// in any less it fails cleanly, the mesh as it was and the arena where it was.
TEST(WeldIndexedExact, RunsInItsBoundAndFailsCleanlyBelow) {
  const auto torus = shapes::torus(24, 16, 10, 3);
  TestArena source;
  Mesh welded;
  SPLINTCORE_ASSERT_OK(test::mesh_from_soup(source.arena, torus, &welded));
  // Every position twice (the second copy used by the odd triangles), one never used.
  const size_t nv = welded.vertices.size();
  std::vector<Vec3> vertices(welded.vertices.data(), welded.vertices.data() + nv);
  vertices.insert(vertices.end(), welded.vertices.data(), welded.vertices.data() + nv);
  vertices.push_back(Vec3{7, 7, 7});
  std::vector<Triangle> triangles(welded.triangles.data(),
                                  welded.triangles.data() + welded.triangles.size());
  for (size_t i = 1; i < triangles.size(); i += 2) {
    for (uint32_t& v : triangles[i].v) v += static_cast<uint32_t>(nv);
  }
  const size_t mesh_bytes =
      arena_array_bound<Vec3>(vertices.size()) + arena_array_bound<Triangle>(triangles.size());
  const size_t bound = static_cast<size_t>(weld_indexed_exact_bound(vertices.size()));
  // At the bound, then one byte below what that run took, then less.
  size_t need = 0;
  for (int run = 0; run < 4; ++run) {
    const size_t cap = run == 0   ? mesh_bytes + bound
                       : run == 1 ? need - 1
                       : run == 2 ? need / 2
                                  : mesh_bytes;
    TestArena t(cap);
    Mesh mesh(&t.arena);
    ASSERT_TRUE(mesh.vertices.resize(vertices.size()));
    ASSERT_TRUE(mesh.triangles.resize(triangles.size()));
    std::copy(vertices.begin(), vertices.end(), mesh.vertices.data());
    std::copy(triangles.begin(), triangles.end(), mesh.triangles.data());
    const size_t used = t.arena.used();
    const Status s = weld_indexed_exact(Context(&t.arena), &mesh);
    EXPECT_EQ(t.arena.used(), used);
    if (run == 0) {
      SPLINTCORE_ASSERT_OK(s);
      need = t.arena.high_water();
      ASSERT_EQ(mesh.vertices.size(), nv);  // the copies welded, the unused vertex dropped
      for (size_t i = 0; i < nv; ++i) EXPECT_TRUE(same_bits(mesh.vertices[i], welded.vertices[i]));
      for (size_t i = 0; i < triangles.size(); ++i) {
        for (int k = 0; k < 3; ++k) EXPECT_EQ(mesh.triangles[i].v[k], welded.triangles[i].v[k]);
      }
    } else {
      EXPECT_EQ(s.code(), StatusCode::kArenaExhausted) << "cap " << cap;
      ASSERT_EQ(mesh.vertices.size(), vertices.size());  // untouched
      for (size_t i = 0; i < vertices.size(); ++i) {
        EXPECT_TRUE(same_bits(mesh.vertices[i], vertices[i]));
      }
      for (size_t i = 0; i < triangles.size(); ++i) {
        for (int k = 0; k < 3; ++k) EXPECT_EQ(mesh.triangles[i].v[k], triangles[i].v[k]);
      }
    }
  }
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
