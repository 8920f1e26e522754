// read_mesh_files (tools/splintcore/files.cpp): several mesh files read in tasks, each into its
// own slice of the arena, give the meshes, hashes and errors of reading them one after the
// other; a file that needs more than its slice sends them all to the serial read; the arena's
// high water is what the slices used, not the room they were given.

#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "common/shapes.h"
#include "splintcore/files.h"
#include "splintcore/platform.h"
#include "support/test_util.h"

namespace {

using namespace splintcore;

// Each test's own files (ctest runs the tests of a suite at the same time, as processes).
std::string temp_path(const char* name) {
  return ::testing::TempDir() + "splintcore_files_test_" +
         ::testing::UnitTest::GetInstance()->current_test_info()->name() + "_" + name;
}

void write_file(const std::string& path, const std::string& bytes) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  ASSERT_NE(f, nullptr) << path;
  ASSERT_EQ(std::fwrite(bytes.data(), 1, bytes.size(), f), bytes.size());
  std::fclose(f);
}

// A binary STL of the soup, written here (not by the library's writer).
std::string binary_stl(const std::vector<SoupTriangle>& soup) {
  std::string bytes(80, ' ');
  const uint32_t n = static_cast<uint32_t>(soup.size());
  for (int k = 0; k < 4; ++k) bytes.push_back(static_cast<char>(n >> (8 * k)));
  for (const SoupTriangle& t : soup) {
    const float zero[3] = {0, 0, 0};
    bytes.append(reinterpret_cast<const char*>(zero), 12);
    for (int c = 0; c < 3; ++c) bytes.append(reinterpret_cast<const char*>(t.p[c]), 12);
    bytes.append(2, '\0');
  }
  return bytes;
}

std::string ascii_stl(const std::vector<SoupTriangle>& soup) {
  std::string text = "solid test\n";
  char line[160];
  for (const SoupTriangle& t : soup) {
    text += "facet normal 0 0 0\nouter loop\n";
    for (int c = 0; c < 3; ++c) {
      std::snprintf(line, sizeof line, "vertex %.9g %.9g %.9g\n", static_cast<double>(t.p[c][0]),
                    static_cast<double>(t.p[c][1]), static_cast<double>(t.p[c][2]));
      text += line;
    }
    text += "endloop\nendfacet\n";
  }
  return text + "endsolid test\n";
}

struct Read {
  Status status;
  bool in_tasks = false;
  std::vector<Mesh> meshes;
  std::vector<tool::MeshFileInfo> infos;
  size_t high_water = 0;
};

Read read_all(test::TestArena& t, const Executor* executor, const std::vector<std::string>& paths) {
  std::vector<const char*> files;
  for (const std::string& p : paths) files.push_back(p.c_str());
  Read r;
  t.arena.reset();
  t.arena.reset_high_water();
  r.status = tool::read_mesh_files(Context(&t.arena, executor, nullptr), files, tool::kNoInputLimit,
                                   true, &r.meshes, &r.infos, &r.in_tasks);
  r.high_water = t.arena.high_water();
  return r;
}

void expect_same_meshes(const Read& a, const Read& b) {
  ASSERT_EQ(a.meshes.size(), b.meshes.size());
  for (size_t i = 0; i < a.meshes.size(); ++i) {
    const Mesh& x = a.meshes[i];
    const Mesh& y = b.meshes[i];
    ASSERT_EQ(x.vertices.size(), y.vertices.size()) << i;
    ASSERT_EQ(x.triangles.size(), y.triangles.size()) << i;
    EXPECT_EQ(std::memcmp(x.vertices.data(), y.vertices.data(), x.vertices.size() * sizeof(Vec3)),
              0)
        << i;
    EXPECT_EQ(
        std::memcmp(x.triangles.data(), y.triangles.data(), x.triangles.size() * sizeof(Triangle)),
        0)
        << i;
    EXPECT_EQ(a.infos[i].sha256, b.infos[i].sha256) << i;
    EXPECT_EQ(a.infos[i].sha256.size(), 64u) << i;
  }
}

class ReadMeshFilesInParallel : public ::testing::Test {
 protected:
  void SetUp() override {
    // Three files of different sizes and formats: a fine torus (binary), a coarse one (ASCII),
    // a box (binary).
    paths_ = {temp_path("a.stl"), temp_path("b.stl"), temp_path("c.stl")};
    write_file(paths_[0], binary_stl(shapes::torus(160, 80, 20, 6)));
    write_file(paths_[1], ascii_stl(shapes::torus(24, 12, 10, 3)));
    const float lo[3] = {-1, -2, -3}, hi[3] = {4, 5, 6};
    write_file(paths_[2], binary_stl(shapes::box(lo, hi)));
  }
  void TearDown() override {
    for (const std::string& p : paths_) std::remove(p.c_str());
  }
  std::vector<std::string> paths_;
};

TEST_F(ReadMeshFilesInParallel, InTasksTheSameAsOneAfterTheOther) {
  ThreadExecutor threads(2);
  test::TestArena t(size_t{64} << 20);
  const Read serial = read_all(t, nullptr, paths_);
  ASSERT_TRUE(serial.status.is_ok()) << test::format(serial.status);
  EXPECT_EQ(serial.meshes[0].triangles.size(), 2u * 160 * 80);
  const Read parallel = read_all(t, &threads.executor(), paths_);
  ASSERT_TRUE(parallel.status.is_ok()) << test::format(parallel.status);
  EXPECT_FALSE(serial.in_tasks);
  EXPECT_TRUE(parallel.in_tasks);
  expect_same_meshes(serial, parallel);
  // The meshes lie in the arena, one after the other (moved down from their slices).
  for (const Mesh& m : parallel.meshes) {
    EXPECT_EQ(m.vertices.arena(), &t.arena);
    EXPECT_EQ(m.triangles.arena(), &t.arena);
  }
  // The high water counts what the slices used: more than the serial read (the files were
  // read at the same time), far less than the 64 MiB the slices were given.
  EXPECT_GE(parallel.high_water, serial.high_water);
  EXPECT_LT(parallel.high_water, 3 * serial.high_water);
}

// An arena with room for the serial read but not for the slices: the same meshes, read one
// after the other.
TEST_F(ReadMeshFilesInParallel, SlicesTooSmallFallBackToTheSerialRead) {
  ThreadExecutor threads(2);
  size_t need = 0;
  {
    test::TestArena t(size_t{64} << 20);
    const Read serial = read_all(t, nullptr, paths_);
    ASSERT_TRUE(serial.status.is_ok());
    need = serial.high_water;
  }
  test::TestArena t(need + 4096);
  const Read serial_again = read_all(t, nullptr, paths_);
  ASSERT_TRUE(serial_again.status.is_ok()) << test::format(serial_again.status);
  const Read parallel = read_all(t, &threads.executor(), paths_);
  ASSERT_TRUE(parallel.status.is_ok()) << test::format(parallel.status);
  EXPECT_FALSE(parallel.in_tasks);
  expect_same_meshes(serial_again, parallel);
  EXPECT_LE(parallel.high_water, need + 4096);
}

// A bad file is named as the serial read names it: the first bad one in order.
TEST_F(ReadMeshFilesInParallel, TheFirstBadFileIsNamed) {
  ThreadExecutor threads(2);
  test::TestArena t(size_t{64} << 20);
  std::string bytes = binary_stl(shapes::torus(24, 12, 10, 3));
  bytes.resize(bytes.size() - 30);  // the last triangle cut short
  write_file(paths_[2], bytes);
  write_file(paths_[1], "solid x\nfacet normal 0 0 0\nouter loop\nvertex 1 2\n");
  const std::vector<std::vector<std::string>> orders = {
      {paths_[0], paths_[1], paths_[2]},
      {paths_[0], paths_[2], paths_[1]},
      {paths_[0], temp_path("missing.stl"), paths_[1]}};  // not opened: read one after another
  for (size_t k = 0; k < orders.size(); ++k) {
    const std::vector<std::string>& order = orders[k];
    const Read serial = read_all(t, nullptr, order);
    const Read parallel = read_all(t, &threads.executor(), order);
    ASSERT_FALSE(serial.status.is_ok());
    EXPECT_EQ(parallel.in_tasks, k < 2) << k;
    EXPECT_EQ(test::format(parallel.status), test::format(serial.status));
    EXPECT_NE(test::format(serial.status).find(order[1]), std::string::npos)
        << test::format(serial.status);
  }
}

}  // namespace
