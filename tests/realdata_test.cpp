// The real CBCT dentition in ../shared/realdata (31 closed tooth meshes, 887k triangles). The
// data is not in the repository (non-commercial licence): these tests skip when it is absent.
#include "support/test_util.h"

namespace splintcore {
namespace {

std::string tooth_path(int tooth) {
  return std::string(SPLINTCORE_REALDATA_DIR) + (tooth <= 16 ? "/maxilla/" : "/mandible/") +
         "tooth_" + std::to_string(tooth) + ".stl";
}

TEST(RealData, EveryToothIsAClosedOutwardGenusZeroSolid) {
  if (!test::file_exists(tooth_path(1))) GTEST_SKIP() << "realdata not found";
  test::TestArena t(size_t{512} << 20);
  uint64_t triangles = 0;
  int teeth = 0;
  for (int tooth = 1; tooth <= 32; ++tooth) {
    if (!test::file_exists(tooth_path(tooth))) continue;  // tooth 16 is absent in the source
    Arena::Marker m = t.arena.mark();
    std::vector<uint8_t> bytes = test::read_file_bytes(tooth_path(tooth));
    Mesh mesh;
    SPLINTCORE_ASSERT_OK(test::mesh_from_bytes(t.arena, bytes, &mesh));
    MeshReport r;
    Context ctx(&t.arena);
    SPLINTCORE_ASSERT_OK(check_mesh(ctx, mesh, &r));
    EXPECT_TRUE(r.is_valid_solid())
        << "tooth " << tooth << ": " << test::format(require_valid_solid(r));
    EXPECT_EQ(r.genus, 0) << tooth;
    EXPECT_EQ(r.shells, 1u) << tooth;
    // SOURCES.md: volumes 199.5 - 891.5 mm^3.
    EXPECT_GT(r.volume, 150.0) << tooth;
    EXPECT_LT(r.volume, 950.0) << tooth;
    triangles += r.triangle_count;
    ++teeth;
    t.arena.rewind(m);
  }
  EXPECT_EQ(teeth, 31);
  EXPECT_EQ(triangles, 887688u);
}

TEST(RealData, Tooth1VolumeMatchesSources) {
  if (!test::file_exists(tooth_path(1))) GTEST_SKIP() << "realdata not found";
  test::TestArena t(size_t{64} << 20);
  Mesh mesh;
  SPLINTCORE_ASSERT_OK(test::mesh_from_bytes(t.arena, test::read_file_bytes(tooth_path(1)), &mesh));
  EXPECT_EQ(mesh.triangles.size(), 32948u);
  EXPECT_NEAR(mesh_volume(mesh), 643.6, 0.05);  // SOURCES.md table
}

}  // namespace
}  // namespace splintcore
