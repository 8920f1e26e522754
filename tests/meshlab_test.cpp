// MeshLab (meshlabserver) as an oracle independent of our own checks: our written STL must be
// two-manifold and watertight for MeshLab too, with the same genus and volume. Skips when
// meshlabserver or xvfb-run is not installed (the README's test command installs both).
#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <sstream>

#include "splintcore/design.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

bool have_meshlab() {
  return std::system("command -v meshlabserver >/dev/null 2>&1 && "
                     "command -v xvfb-run >/dev/null 2>&1") == 0;
}

// Runs the topology + geometry filters on `stl` and returns MeshLab's log.
std::string meshlab_log(const std::string& stl) {
  std::string log = stl + ".meshlab.log";
  std::string cmd = "xvfb-run -a meshlabserver -i '" + stl + "' -s '" +
                    std::string(SPLINTCORE_FIXTURES_DIR) + "/meshlab/topo.mlx' -l '" + log +
                    "' >/dev/null 2>&1";
  EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;
  std::ifstream in(log);
  std::stringstream text;
  text << in.rdbuf();
  std::remove(log.c_str());
  return text.str();
}

// Writes the bytes to a temporary STL, runs MeshLab on it, removes it, returns the log.
std::string meshlab_log_of_bytes(const std::vector<uint8_t>& bytes) {
  char path[] = "/tmp/splintcore-meshlab-XXXXXX.stl";
  int fd = mkstemps(path, 4);
  EXPECT_GE(fd, 0);
  if (fd < 0) return "";
  EXPECT_EQ(write(fd, bytes.data(), bytes.size()), static_cast<ssize_t>(bytes.size()));
  close(fd);
  std::string log = meshlab_log(path);
  std::remove(path);
  return log;
}

double number_after(const std::string& text, const std::string& label) {
  size_t at = text.find(label);
  if (at == std::string::npos) return std::nan("");
  return std::strtod(text.c_str() + at + label.size(), nullptr);
}

TEST(MeshLab, ConvertedFixturesAreWatertightTwoManifoldWithOurVolume) {
  if (!have_meshlab()) GTEST_SKIP() << "meshlabserver/xvfb-run not installed";
  struct Case {
    const char* fixture;
    int genus;
  } cases[] = {{"stl/torus_binary.stl", 1}, {"stl/box_solid_header.stl", 0},
               {"stl/tetra_ascii.stl", 0}};
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
  for (const char* fixture : {"cases/paper_scale.json", "cases/rounded.json", "cases/uneven.json"}) {
    test::TestArena t(64 << 20);
    std::vector<uint8_t> text =
        test::read_file_bytes(std::string(SPLINTCORE_FIXTURES_DIR) + "/" + fixture);
    Context ctx(&t.arena);
    CaseFile c;
    SPLINTCORE_ASSERT_OK(parse_case(ctx, reinterpret_cast<const char*>(text.data()), text.size(),
                                    fixture, &c));
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
