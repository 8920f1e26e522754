// The scan-like phantom (tools/common/scan_phantom.cpp) and scan preparation on it: prepare_scan
// finds exactly what the phantom planted, on several seeds and both arches, and the result is
// edge-manifold and oriented with one border; write_ply's bytes read back through read_ply;
// the Teeth3DS sample scan (../shared/realdata/teeth3ds-sample, read there, never copied).
#include <vector>

#include "common/phantom.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

using test::TestArena;

Mesh to_mesh(Arena& arena, const phantom::ScanJaw& jaw) {
  Mesh m(&arena);
  for (const Vec3& v : jaw.vertices) EXPECT_TRUE(m.vertices.push_back(v));
  for (const Triangle& t : jaw.triangles) EXPECT_TRUE(m.triangles.push_back(t));
  return m;
}

TEST(ScanPhantom, PrepareFindsWhatWasPlanted) {
  TestArena ta;
  for (uint64_t seed : {1u, 2u, 7u}) {
    for (phantom::Jaw which : {phantom::Jaw::kMaxilla, phantom::Jaw::kMandible}) {
      SCOPED_TRACE(testing::Message() << "seed " << seed << ", jaw " << static_cast<int>(which));
      ArenaScope scope(ta.arena);
      phantom::ScanOptions so;
      so.seed = seed;
      phantom::ScanJaw jaw;
      SPLINTCORE_ASSERT_OK(phantom::make_scan_jaw(which, so, &jaw));
      EXPECT_EQ(jaw.holes, 3u);
      EXPECT_EQ(jaw.islands, 3u);
      const Mesh in = to_mesh(ta.arena, jaw);
      MeshReport before;
      SPLINTCORE_ASSERT_OK(check_mesh(Context(&ta.arena), in, &before));
      EXPECT_FALSE(before.closed());
      EXPECT_GT(before.nonmanifold_edges, 0u);
      EXPECT_GT(before.orientation_conflicts, 0u);
      Mesh out;
      PrepareReport r;
      SPLINTCORE_ASSERT_OK(prepare_scan(Context(&ta.arena), in, PrepareOptions{}, &out, &r));
      EXPECT_EQ(r.duplicate_triangles, jaw.duplicates);
      EXPECT_EQ(r.degenerate_triangles, 0u);
      EXPECT_EQ(r.nonmanifold_edges, jaw.nonmanifold_edges);
      EXPECT_EQ(r.nonmanifold_triangles, jaw.nonmanifold_edges);  // the flaps
      EXPECT_EQ(r.nonmanifold_vertices, 0u);
      EXPECT_EQ(r.islands, jaw.islands);
      EXPECT_EQ(r.components, 1u);
      EXPECT_EQ(r.flipped_triangles, jaw.flipped_triangles);
      EXPECT_EQ(r.orientation_conflicts, 0u);
      EXPECT_LE(jaw.max_hole_edges, PrepareOptions{}.max_hole_edges);
      EXPECT_EQ(r.holes_filled, jaw.holes);
      EXPECT_EQ(r.holes_left, 1u);  // the scan's border
      MeshReport after;
      SPLINTCORE_ASSERT_OK(check_mesh(Context(&ta.arena), out, &after));
      EXPECT_TRUE(after.edge_manifold() && after.oriented());
      EXPECT_EQ(after.boundary_loops, 1u);
      EXPECT_EQ(after.shells, 1u);
      EXPECT_EQ(after.degenerate_triangles + after.duplicate_triangles, 0u);
      EXPECT_EQ(after.unreferenced_vertices, 0u);
      for (const Vec3& v : out.vertices) {  // fills included: what an STL holds
        ASSERT_TRUE(static_cast<float>(v.x) == v.x && static_cast<float>(v.y) == v.y &&
                    static_cast<float>(v.z) == v.z);
      }
      // The crowns face the other jaw: +z for the mandible, -z for the maxilla.
      Vec3 net{};
      for (const Triangle& t : out.triangles) {
        net = net + cross(out.vertices[t.v[1]] - out.vertices[t.v[0]],
                          out.vertices[t.v[2]] - out.vertices[t.v[0]]);
      }
      EXPECT_EQ(net.z > 0, which == phantom::Jaw::kMandible);
    }
  }
}

TEST(ScanPhantom, SameSeedSameBytesOtherSeedOtherBytes) {
  phantom::ScanJaw a, b, c;
  phantom::ScanOptions so;
  so.seed = 5;
  SPLINTCORE_ASSERT_OK(phantom::make_scan_jaw(phantom::Jaw::kMandible, so, &a));
  SPLINTCORE_ASSERT_OK(phantom::make_scan_jaw(phantom::Jaw::kMandible, so, &b));
  so.seed = 6;
  SPLINTCORE_ASSERT_OK(phantom::make_scan_jaw(phantom::Jaw::kMandible, so, &c));
  ASSERT_EQ(a.vertices.size(), b.vertices.size());
  EXPECT_EQ(test::sha256_hex(a.vertices.data(), a.vertices.size() * sizeof(Vec3)),
            test::sha256_hex(b.vertices.data(), b.vertices.size() * sizeof(Vec3)));
  EXPECT_NE(test::sha256_hex(a.vertices.data(), a.vertices.size() * sizeof(Vec3)),
            test::sha256_hex(c.vertices.data(), c.vertices.size() * sizeof(Vec3)));
  so.rows = 10;
  EXPECT_EQ(phantom::make_scan_jaw(phantom::Jaw::kMandible, so, &c).code(),
            StatusCode::kInvalidArgument);
}

TEST(ScanPhantom, PlyWithColoursReadsBack) {
  TestArena ta;
  phantom::ScanJaw jaw;
  SPLINTCORE_ASSERT_OK(make_scan_jaw(phantom::Jaw::kMaxilla, phantom::ScanOptions{}, &jaw));
  const Mesh m = to_mesh(ta.arena, jaw);
  std::vector<uint8_t> bytes(size_t{64} << 20);
  MemorySink ms{bytes.data(), bytes.size(), 0, 0};
  SPLINTCORE_ASSERT_OK(write_ply(m, Span<const uint8_t>(jaw.rgb.data(), jaw.rgb.size()),
                                 memory_sink(&ms, "scan.ply")));
  bytes.resize(static_cast<size_t>(ms.size));
  const std::string head(bytes.begin(), bytes.begin() + 300);
  EXPECT_NE(head.find("format binary_little_endian 1.0"), std::string::npos);
  EXPECT_NE(head.find("property uchar red"), std::string::npos);
  MemorySource src{bytes.data(), bytes.size(), 0, 0};
  Mesh back;
  MeshReadInfo info;
  SPLINTCORE_ASSERT_OK(read_ply(Context(&ta.arena), memory_source(&src, "scan.ply"),
                                MeshReadOptions{}, &back, &info));
  EXPECT_EQ(info.format, MeshFormat::kPlyBinaryLittleEndian);
  ASSERT_EQ(back.vertices.size(), m.vertices.size());
  ASSERT_EQ(back.triangles.size(), m.triangles.size());
  for (size_t i = 0; i < m.vertices.size(); ++i) ASSERT_EQ(back.vertices[i], m.vertices[i]) << i;
  for (size_t i = 0; i < m.triangles.size(); ++i) {
    for (int k = 0; k < 3; ++k) ASSERT_EQ(back.triangles[i].v[k], m.triangles[i].v[k]) << i;
  }
  // Without colours, and the errors.
  MemorySink plain{bytes.data(), bytes.size(), 0, 0};
  SPLINTCORE_EXPECT_OK(write_ply(m, Span<const uint8_t>(), memory_sink(&plain)));
  EXPECT_LT(plain.size, ms.size);
  EXPECT_EQ(write_ply(m, Span<const uint8_t>(jaw.rgb.data(), 3), memory_sink(&plain)).code(),
            StatusCode::kInvalidArgument);
  MemorySink tiny{bytes.data(), 100, 0, 0};
  EXPECT_EQ(write_ply(m, Span<const uint8_t>(), memory_sink(&tiny)).code(), StatusCode::kIoError);
}

// The Teeth3DS sample: a real upper-jaw scan (CC BY-NC-ND; read where it lies).
TEST(ScanRealData, Teeth3dsSampleIsPrepared) {
  const std::string path = std::string(SPLINTCORE_TEETH3DS_DIR) + "/YBSESUN6_upper.ply";
  if (!test::file_exists(path)) GTEST_SKIP() << "Teeth3DS sample not found: " << path;
  TestArena ta(size_t{256} << 20);
  const std::vector<uint8_t> bytes = test::read_file_bytes(path);
  MemorySource src{bytes.data(), bytes.size(), 0, 0};
  Mesh in;
  MeshReadInfo info;
  SPLINTCORE_ASSERT_OK(read_ply(Context(&ta.arena), memory_source(&src, path.c_str()),
                                MeshReadOptions{}, &in, &info));
  MeshReport before;
  SPLINTCORE_ASSERT_OK(check_mesh(Context(&ta.arena), in, &before));
  Mesh out;
  PrepareReport r;
  SPLINTCORE_ASSERT_OK(prepare_scan(Context(&ta.arena), in, PrepareOptions{}, &out, &r));
  MeshReport after;
  SPLINTCORE_ASSERT_OK(check_mesh(Context(&ta.arena), out, &after));
  std::printf(
      "[ teeth3ds ] %llu triangles, %llu boundary edges in %llu loops; prepared: %llu "
      "duplicate, %llu degenerate, %llu non-manifold edges, %llu non-manifold vertices, %llu "
      "islands, %llu flipped, %llu holes filled (%llu triangles), %llu left; result %llu "
      "triangles, %llu boundary edges in %llu loops, %llu shell(s)\n",
      static_cast<unsigned long long>(before.triangle_count),
      static_cast<unsigned long long>(before.boundary_edges),
      static_cast<unsigned long long>(before.boundary_loops),
      static_cast<unsigned long long>(r.duplicate_triangles),
      static_cast<unsigned long long>(r.degenerate_triangles),
      static_cast<unsigned long long>(r.nonmanifold_edges),
      static_cast<unsigned long long>(r.nonmanifold_vertices),
      static_cast<unsigned long long>(r.islands),
      static_cast<unsigned long long>(r.flipped_triangles),
      static_cast<unsigned long long>(r.holes_filled),
      static_cast<unsigned long long>(r.hole_triangles),
      static_cast<unsigned long long>(r.holes_left),
      static_cast<unsigned long long>(after.triangle_count),
      static_cast<unsigned long long>(after.boundary_edges),
      static_cast<unsigned long long>(after.boundary_loops),
      static_cast<unsigned long long>(after.shells));
  EXPECT_GT(before.triangle_count, 10000u);
  EXPECT_GT(before.boundary_loops, 0u);
  EXPECT_EQ(r.components, 1u);
  EXPECT_EQ(after.shells, 1u);
  EXPECT_TRUE(after.edge_manifold() && after.oriented());
  EXPECT_EQ(after.degenerate_triangles + after.duplicate_triangles, 0u);
  EXPECT_EQ(after.boundary_loops, r.holes_left);
  EXPECT_GE(after.triangle_count, before.triangle_count - before.triangle_count / 100);
}

}  // namespace
}  // namespace splintcore
