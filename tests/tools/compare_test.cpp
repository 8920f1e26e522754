// Tests of `splintcore compare`'s code (tools/common/compare.cpp): exact deviations between a
// box and the same box moved by 1 mm, independence of the thread count, the colour ramp, and
// the round trip of the coloured PLY through the PLY reader (src/io/ply_read.cpp).

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "common/compare.h"
#include "common/shapes.h"
#include "splintcore/io.h"
#include "splintcore/mesh.h"
#include "splintcore/platform.h"
#include "support/test_util.h"

namespace {

using namespace splintcore;

Mesh box_mesh(Arena* arena, const float lo[3], const float hi[3]) {
  const std::vector<SoupTriangle> soup = shapes::box(lo, hi);
  Mesh m(arena);
  Status s = weld_exact(Context(arena), Span<const SoupTriangle>(soup.data(), soup.size()), &m);
  EXPECT_TRUE(s.is_ok()) << test::format(s);
  return m;
}

TEST(Compare, BoxAgainstMovedBox) {
  test::TestArena t(size_t{64} << 20);
  const float lo[3] = {0, 0, 0}, hi[3] = {10, 10, 10};
  const float lo2[3] = {0, 0, 1}, hi2[3] = {10, 10, 11};
  Mesh a = box_mesh(&t.arena, lo, hi);
  Mesh b = box_mesh(&t.arena, lo2, hi2);
  std::vector<double> da, db;
  cli::Comparison c;
  SPLINTCORE_ASSERT_OK(cli::compare_meshes(Context(&t.arena), a, b, &da, &db, &c));
  // A's bottom corners are 1 mm below B; its top corners lie on B's sides.
  EXPECT_EQ(c.a_to_b.vertices, 8u);
  EXPECT_EQ(c.a_to_b.max, 1.0);
  EXPECT_EQ(c.a_to_b.mean, 0.5);
  EXPECT_EQ(c.a_to_b.rms, std::sqrt(0.5));
  EXPECT_EQ(c.b_to_a.max, 1.0);
  EXPECT_EQ(c.hausdorff, 1.0);
  for (size_t i = 0; i < a.vertices.size(); ++i) {
    EXPECT_EQ(da[i], a.vertices[i].z == 0 ? 1.0 : 0.0);
  }
  // Any thread count gives the same distances, bit for bit.
  ThreadExecutor pool(3);
  Context ctx3(&t.arena, &pool.executor(), nullptr);
  std::vector<double> da3, db3;
  cli::Comparison c3;
  SPLINTCORE_ASSERT_OK(cli::compare_meshes(ctx3, a, b, &da3, &db3, &c3));
  EXPECT_EQ(da3, da);
  EXPECT_EQ(db3, db);
  EXPECT_EQ(std::memcmp(&c3, &c, sizeof(c)), 0);
  // A mesh without triangles is rejected.
  Mesh empty(&t.arena);
  EXPECT_EQ(cli::compare_meshes(Context(&t.arena), a, empty, &da, &db, &c).code(),
            StatusCode::kInvalidMesh);
}

TEST(Compare, ColourRamp) {
  uint8_t rgb[3];
  cli::distance_colour(0, 2, rgb);
  EXPECT_EQ(rgb[0], 0);
  EXPECT_EQ(rgb[1], 0);
  EXPECT_EQ(rgb[2], 255);
  cli::distance_colour(1, 2, rgb);
  EXPECT_EQ(rgb[0], 0);
  EXPECT_EQ(rgb[1], 255);
  EXPECT_EQ(rgb[2], 0);
  cli::distance_colour(2, 2, rgb);
  EXPECT_EQ(rgb[0], 255);
  EXPECT_EQ(rgb[1], 0);
  EXPECT_EQ(rgb[2], 0);
  cli::distance_colour(7, 2, rgb);  // beyond the range: red
  EXPECT_EQ(rgb[0], 255);
  EXPECT_EQ(rgb[2], 0);
  cli::distance_colour(0.5, 2, rgb);  // a quarter: half way from blue to green
  EXPECT_EQ(rgb[0], 0);
  EXPECT_EQ(rgb[1], 128);
  EXPECT_EQ(rgb[2], 128);
  cli::distance_colour(1, 0, rgb);  // no range: blue
  EXPECT_EQ(rgb[2], 255);
}

TEST(Compare, ColouredPlyReadsBack) {
  test::TestArena t(size_t{64} << 20);
  const std::vector<SoupTriangle> soup = shapes::torus(24, 12, 20.0, 5.0);
  Mesh a(&t.arena);
  SPLINTCORE_ASSERT_OK(
      weld_exact(Context(&t.arena), Span<const SoupTriangle>(soup.data(), soup.size()), &a));
  std::vector<double> d(a.vertices.size());
  for (size_t i = 0; i < d.size(); ++i) d[i] = 0.01 * static_cast<double>(i);
  const std::string ply = cli::distance_ply(a, d, 1.0);
  EXPECT_EQ(ply, cli::distance_ply(a, d, 1.0));  // deterministic bytes
  const size_t header = ply.find("end_header\n") + 11;
  EXPECT_EQ(ply.size(), header + 19 * a.vertices.size() + 13 * a.triangles.size());
  MemorySource ms{reinterpret_cast<const uint8_t*>(ply.data()), ply.size(), 0, 0};
  Mesh back;
  MeshReadInfo info;
  SPLINTCORE_ASSERT_OK(
      read_mesh(Context(&t.arena), memory_source(&ms, "out.ply"), MeshReadOptions{}, &back, &info));
  EXPECT_EQ(info.format, MeshFormat::kPlyBinaryLittleEndian);
  ASSERT_EQ(back.vertices.size(), a.vertices.size());
  ASSERT_EQ(back.triangles.size(), a.triangles.size());
  for (size_t i = 0; i < a.vertices.size(); ++i) {  // == : -0 is written as +0
    EXPECT_TRUE(back.vertices[i].x == a.vertices[i].x && back.vertices[i].y == a.vertices[i].y &&
                back.vertices[i].z == a.vertices[i].z)
        << i;
  }
  EXPECT_EQ(
      std::memcmp(back.triangles.data(), a.triangles.data(), a.triangles.size() * sizeof(Triangle)),
      0);
  // The quality of vertex 7 is its distance as float32, right after its colour.
  float q;
  std::memcpy(&q, ply.data() + header + 19 * 7 + 15, 4);
  EXPECT_EQ(q, static_cast<float>(0.07));
}

}  // namespace
