// MeshLab (meshlabserver) as an oracle independent of our own checks: our written STL must be
// two-manifold and watertight for MeshLab too, with the same genus and volume. Skips when
// meshlabserver or xvfb-run is not installed (the README's test command installs both).
#include "support/meshlab.h"
#include "splintcore/design.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

using test::have_meshlab;
using test::meshlab_log_of_bytes;
using test::number_after;

TEST(MeshLab, ConvertedFixturesAreWatertightTwoManifoldWithOurVolume) {
  if (!have_meshlab()) GTEST_SKIP() << "meshlabserver/xvfb-run not installed";
  struct Case {
    const char* fixture;
    int genus;
  } cases[] = {
      {"stl/torus_binary.stl", 1}, {"stl/box_solid_header.stl", 0}, {"stl/tetra_ascii.stl", 0}};
  for (const Case& c : cases) {
    test::TestArena t(64 << 20);
    Mesh mesh;
    SPLINTCORE_ASSERT_OK(test::mesh_from_bytes(
        t.arena, test::read_file_bytes(std::string(SPLINTCORE_FIXTURES_DIR) + "/" + c.fixture),
        &mesh));
    std::vector<uint8_t> out;
    SPLINTCORE_ASSERT_OK(test::mesh_to_bytes(t.arena, mesh, StlFormat::kBinary, &out));
    std::string log = meshlab_log_of_bytes(out);
    EXPECT_NE(log.find("Mesh is two-manifold"), std::string::npos) << c.fixture << "\n" << log;
    EXPECT_NE(log.find("Boundary Edges 0"), std::string::npos) << c.fixture;
    EXPECT_NE(log.find("Genus is " + std::to_string(c.genus)), std::string::npos) << c.fixture;
    double theirs = number_after(log, "Mesh Volume  is ");
    double ours = mesh_volume(mesh);
    EXPECT_NEAR(theirs, ours, 1e-5 * ours) << c.fixture;  // MeshLab sums in float
  }
}

TEST(MeshLab, CaseBasesAreWatertightTwoManifold) {
  if (!have_meshlab()) GTEST_SKIP() << "meshlabserver/xvfb-run not installed";
  for (const char* fixture :
       {"cases/paper_scale.json", "cases/rounded.json", "cases/uneven.json"}) {
    test::TestArena t(64 << 20);
    std::vector<uint8_t> text =
        test::read_file_bytes(std::string(SPLINTCORE_FIXTURES_DIR) + "/" + fixture);
    Context ctx(&t.arena);
    CaseFile c;
    SPLINTCORE_ASSERT_OK(
        parse_case(ctx, reinterpret_cast<const char*>(text.data()), text.size(), fixture, &c));
    Mesh m(&t.arena);
    BaseReport r;
    SPLINTCORE_ASSERT_OK(build_case_base(ctx, c, &m, &r));
    std::vector<uint8_t> out;
    SPLINTCORE_ASSERT_OK(test::mesh_to_bytes(t.arena, m, StlFormat::kBinary, &out));
    std::string log = meshlab_log_of_bytes(out);
    EXPECT_NE(log.find("Mesh is two-manifold"), std::string::npos) << fixture << "\n" << log;
    EXPECT_NE(log.find("Boundary Edges 0"), std::string::npos) << fixture;
    EXPECT_NE(log.find("Genus is 0"), std::string::npos) << fixture;
    double theirs = number_after(log, "Mesh Volume  is ");
    EXPECT_NEAR(theirs, r.volume, 1e-5 * r.volume) << fixture;
  }
}

}  // namespace
}  // namespace splintcore
