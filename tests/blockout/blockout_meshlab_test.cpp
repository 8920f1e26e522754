// MeshLab (meshlabserver) as an independent oracle of the blockout: the phantom maxilla's
// swept volume and the paper-scale splint after interference elimination, written as STL,
// are watertight and two-manifold for MeshLab, with our volume.
#include <cstdio>
#include <string>
#include <vector>

#include "common/phantom.h"
#include "splintcore/blockout.h"
#include "splintcore/design.h"
#include "support/meshlab.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

struct Case {
  test::TestArena t{size_t{512} << 20};
  CaseFile c;
  Mesh jaws[2];
  bool ok = false;

  Case() {
    Context ctx(&t.arena);
    std::vector<uint8_t> text =
        test::read_file_bytes(std::string(SPLINTCORE_FIXTURES_DIR) + "/cases/paper_scale.json");
    if (!parse_case(ctx, reinterpret_cast<const char*>(text.data()), text.size(), "paper_scale", &c)
             .is_ok()) {
      return;
    }
    for (int j = 0; j < 2; ++j) {
      phantom::JawMesh m;
      phantom::PhantomOptions po;
      po.target_triangles = 12000;
      if (!phantom::make_jaw(j == 0 ? phantom::Jaw::kMaxilla : phantom::Jaw::kMandible, po, &m)
               .is_ok()) {
        return;
      }
      jaws[j].bind(&t.arena);
      for (const Vec3& v : m.vertices) (void)jaws[j].vertices.push_back(v);
      for (const Triangle& tr : m.triangles) (void)jaws[j].triangles.push_back(tr);
    }
    ok = true;
  }
};

void expect_meshlab_solid(Arena& arena, const Mesh& m) {
  std::vector<uint8_t> bytes;
  SPLINTCORE_ASSERT_OK(test::mesh_to_bytes(arena, m, StlFormat::kBinary, &bytes));
  const std::string log = test::meshlab_log_of_bytes(bytes);
  EXPECT_NE(log.find("Mesh is two-manifold"), std::string::npos) << log;
  EXPECT_NE(log.find("Boundary Edges 0"), std::string::npos) << log;
  const double theirs = test::number_after(log, "Mesh Volume  is ");
  const double ours = mesh_volume(m);
  std::printf("[ figures  ] MeshLab volume %.6f mm^3, ours %.6f mm^3, %zu triangles\n", theirs,
              ours, m.triangles.size());
  EXPECT_NEAR(theirs, ours, 1e-5 * ours);  // MeshLab sums in float
}

TEST(BlockoutMeshLab, SweptVolumeIsWatertightTwoManifold) {
  if (!test::have_meshlab()) GTEST_SKIP() << "meshlabserver/xvfb-run not installed";
  Case k;
  ASSERT_TRUE(k.ok);
  Context ctx(&k.t.arena);
  SweepOptions o;
  o.direction = k.c.insertion_direction;
  o.voxel = 0.3;  // 0.2 made 1.23M triangles: 12-15 s, nearly all of it MeshLab's reading
  o.extent = 2.0;
  Mesh swept;
  SPLINTCORE_ASSERT_OK(sweep_volume_mesh(ctx, Span<const Mesh>(&k.jaws[0], 1), o, &swept));
  for (Vec3& p : swept.vertices) ASSERT_TRUE(round_to_float32(&p));
  expect_meshlab_solid(k.t.arena, swept);
}

TEST(BlockoutMeshLab, BlockedOutSplintIsWatertightTwoManifold) {
  if (!test::have_meshlab()) GTEST_SKIP() << "meshlabserver/xvfb-run not installed";
  Case k;
  ASSERT_TRUE(k.ok);
  Context ctx(&k.t.arena);
  Mesh splint;
  DesignReport report;
  SPLINTCORE_ASSERT_OK(design_splint(ctx, k.c, Span<const Mesh>(k.jaws, 2), &splint, &report));
  // Each jaw as the design moved it; the maxilla comes off along the insertion direction, the
  // mandible along its reverse.
  Mesh current = splint;
  for (int j = 0; j < 2; ++j) {
    Mesh moved(&k.t.arena);
    for (const Vec3& v : k.jaws[j].vertices) {
      Vec3 p = k.c.jaws[j].transform.apply_point(v);
      ASSERT_TRUE(round_to_float32(&p));
      (void)moved.vertices.push_back(p);
    }
    for (const Triangle& tr : k.jaws[j].triangles) (void)moved.triangles.push_back(tr);
    BlockoutOptions bo;
    bo.sweep.direction = j == 0 ? k.c.insertion_direction : -k.c.insertion_direction;
    bo.sweep.voxel = 0.2;
    bo.sweep.inset = 0.1;
    Mesh out;
    BlockoutStats stats;
    SPLINTCORE_ASSERT_OK(blockout(ctx, current, Span<const Mesh>(&moved, 1), bo, &out, &stats));
    EXPECT_GT(stats.boolean.intersecting_pairs, 0u);
    current = out;
  }
  EXPECT_LT(mesh_volume(current), mesh_volume(splint));
  expect_meshlab_solid(k.t.arena, current);
}

}  // namespace
}  // namespace splintcore
