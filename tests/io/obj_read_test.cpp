// Tests of the Wavefront OBJ reader (src/io/obj_read.cpp): every face-corner form, negative
// (relative) indices, polygons fan-triangulated, skipped statements, extra vertex numbers
// (w, or r g b), the location of every error, line-length and count limits, NaN, sources that
// deliver a byte at a time, and truncation at every byte offset.

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "splintcore/core.h"
#include "splintcore/io.h"
#include "splintcore/mesh.h"
#include "support/test_util.h"

namespace {

using splintcore::Arena;
using splintcore::ArenaScope;
using splintcore::Context;
using splintcore::kNoPosition;
using splintcore::kUnknownSize;
using splintcore::MemorySource;
using splintcore::Mesh;
using splintcore::MeshFormat;
using splintcore::MeshReadInfo;
using splintcore::MeshReadOptions;
using splintcore::Status;
using splintcore::StatusCode;
using splintcore::Triangle;
using splintcore::Vec3;
using splintcore::test::format;

Arena& shared_arena() {
  static splintcore::test::TestArena arena(size_t{16} << 20);
  return arena.arena;
}

struct Result {
  Status status;
  std::vector<Vec3> vertices;
  std::vector<Triangle> triangles;
  MeshReadInfo info;
  size_t arena_after = 0;
};

Result read(const std::string& text, const MeshReadOptions& options = MeshReadOptions{},
            size_t max_chunk = 0, bool size_known = true) {
  Arena& arena = shared_arena();
  ArenaScope scope(arena);
  const size_t before = arena.used();
  Context ctx(&arena);
  MemorySource ms{reinterpret_cast<const uint8_t*>(text.data()), text.size(), 0, max_chunk};
  splintcore::ByteSource source = splintcore::memory_source(&ms, "scan.obj");
  if (!size_known) source.size = kUnknownSize;
  Mesh mesh;
  Result r;
  r.status = splintcore::read_obj(ctx, source, options, &mesh, &r.info);
  r.vertices.assign(mesh.vertices.begin(), mesh.vertices.end());
  r.triangles.assign(mesh.triangles.begin(), mesh.triangles.end());
  r.arena_after = arena.used() - before;
  return r;
}

std::vector<std::vector<uint32_t>> triangles_of(const Result& r) {
  std::vector<std::vector<uint32_t>> out;
  for (const Triangle& t : r.triangles) out.push_back({t.v[0], t.v[1], t.v[2]});
  return out;
}

const char kCube[] =
    "# a unit cube as a scanner might export it\n"  // 1
    "mtllib cube.mtl\n"                             // 2
    "o cube\n"                                      // 3
    "v 0 0 0\n"                                     // 4  vertex 1
    "v 1 0 0 1.0\n"                                 // 5  2 (w)
    "v 1 1 0 0.5 0.5 0.5\n"                         // 6  3 (r g b)
    "v 0 1 0\n"                                     // 7  4
    "vt 0 0\n"                                      // 8
    "vn 0 0 -1\n"                                   // 9
    "g bottom\n"                                    // 10
    "usemtl gum\n"                                  // 11
    "s off\n"                                       // 12
    "f 1 4 3 2\n"                                   // 13 quad: two triangles
    "v 0 0 1\n"                                     // 14 5
    "v\t1 0 1\n"                                    // 15 6
    "v 1 1 1\n"                                     // 16 7
    "v 0 1 1\n"                                     // 17 8
    "f 5/1 6/1 7/1 8/1 # top\n"                     // 18
    "f 1//1 2//1 6//1 5//1\n"                       // 19
    "f 2/1/1 3/1/1 7/1/1 6/1/1\n"                   // 20
    "f -5/1 -1/1 -2/1 -6/1\n"                       // 21 3 8 7 4... relative: 4 8 7 3
    "f -8 -4 -1 -5\r\n"                             // 22 1 5 8 4
    "l 1 2\n";                                      // 23

TEST(ObjRead, FormsNegativeIndicesAndFans) {
  Result r = read(kCube);
  ASSERT_TRUE(r.status.is_ok()) << format(r.status);
  ASSERT_EQ(r.vertices.size(), 8u);
  EXPECT_EQ(r.vertices[5].x, 1.0);
  EXPECT_EQ(r.vertices[5].z, 1.0);
  const std::vector<std::vector<uint32_t>> expected = {{0, 3, 2}, {0, 2, 1}, {4, 5, 6}, {4, 6, 7},
                                                       {0, 1, 5}, {0, 5, 4}, {1, 2, 6}, {1, 6, 5},
                                                       {3, 7, 6}, {3, 6, 2}, {0, 4, 7}, {0, 7, 3}};
  EXPECT_EQ(triangles_of(r), expected);
  EXPECT_EQ(r.info.format, MeshFormat::kObj);
  EXPECT_EQ(r.info.faces, 6u);
  EXPECT_EQ(r.info.triangles, 12u);
  EXPECT_EQ(r.info.bytes, std::strlen(kCube));
  // A closed, outward solid: the fans kept every face's orientation.
  Arena& arena = shared_arena();
  ArenaScope scope(arena);
  Context ctx(&arena);
  MemorySource ms{reinterpret_cast<const uint8_t*>(kCube), std::strlen(kCube), 0, 0};
  Mesh mesh;
  SPLINTCORE_ASSERT_OK(
      splintcore::read_obj(ctx, splintcore::memory_source(&ms), MeshReadOptions{}, &mesh, nullptr));
  splintcore::MeshReport report;
  SPLINTCORE_ASSERT_OK(splintcore::check_mesh(ctx, mesh, &report));
  EXPECT_TRUE(report.is_valid_solid());
  EXPECT_EQ(report.volume, 1.0);
}

TEST(ObjRead, ChunkingAndUnknownSizeDoNotMatter) {
  const Result whole = read(kCube);
  for (size_t chunk : {size_t{1}, size_t{2}, size_t{5}, size_t{13}}) {
    for (bool known : {true, false}) {
      Result r = read(kCube, MeshReadOptions{}, chunk, known);
      ASSERT_TRUE(r.status.is_ok()) << format(r.status);
      EXPECT_EQ(triangles_of(r), triangles_of(whole));
      ASSERT_EQ(r.vertices.size(), whole.vertices.size());
      EXPECT_EQ(
          std::memcmp(r.vertices.data(), whole.vertices.data(), r.vertices.size() * sizeof(Vec3)),
          0);
    }
  }
}

TEST(ObjRead, NumbersAreExactAndLocaleFree) {
  Result r = read("v 0.1 -2.5e-3 +7\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  ASSERT_TRUE(r.status.is_ok()) << format(r.status);
  EXPECT_EQ(r.vertices[0].x, static_cast<double>(0.1f));
  EXPECT_EQ(r.vertices[0].y, static_cast<double>(-2.5e-3f));
  EXPECT_EQ(r.vertices[0].z, 7.0);
  MeshReadOptions exact;
  exact.round_to_float32 = false;
  r = read("v 0.1 -2.5e-3 +7\n", exact);
  ASSERT_TRUE(r.status.is_ok()) << format(r.status);
  EXPECT_EQ(r.vertices[0].x, 0.1);
  EXPECT_EQ(r.vertices[0].y, -2.5e-3);
  r = read("v 0,1 0 0\n");
  EXPECT_EQ(r.status.code(), StatusCode::kParseError);
  EXPECT_EQ(r.status.line(), 1u);
  EXPECT_EQ(r.status.column(), 3u);
}

TEST(ObjRead, ErrorsNameLineColumnAndElement) {
  struct Case {
    const char* text;
    StatusCode code;
    uint64_t line, column, index;
  };
  const Case cases[] = {
      {"v 0 0 0\nv 1 0 nan\n", StatusCode::kNonFinite, 2, 7, 1},
      {"v 0 0 0\nv 1 0 -Inf\n", StatusCode::kNonFinite, 2, 7, 1},
      {"v 0 0 0\nv 1 0 2e7\n", StatusCode::kLimitExceeded, 2, 1, 1},
      {"v 0 0\n", StatusCode::kParseError, 1, 6, 0},
      {"v 0 0 0 1 2 3 4\n", StatusCode::kParseError, 1, 15, 0},
      {"v 0 0 0 1 x\n", StatusCode::kParseError, 1, 11, 0},
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 0\n", StatusCode::kParseError, 4, 7, 0},
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", StatusCode::kParseError, 4, 7, 0},
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -4\n", StatusCode::kParseError, 4, 7, 0},
      {"v 0 0 0\nv 1 0 0\nf 1 2 3\nv 0 1 0\n", StatusCode::kParseError, 3, 7, 0},  // forward
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n", StatusCode::kParseError, 4, 1, 0},
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 3/\n", StatusCode::kParseError, 5, 7, 1},
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3//\n", StatusCode::kParseError, 4, 7, 0},
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3/1/1/1\n", StatusCode::kParseError, 4, 7, 0},
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3/a\n", StatusCode::kParseError, 4, 7, 0},
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3.0\n", StatusCode::kParseError, 4, 7, 0},
      {"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3 \\\n", StatusCode::kParseError, 4, 9, 0},
  };
  for (const Case& c : cases) {
    Result r = read(c.text);
    EXPECT_EQ(r.status.code(), c.code) << c.text << format(r.status);
    EXPECT_EQ(r.status.line(), c.line) << c.text << format(r.status);
    EXPECT_EQ(r.status.column(), c.column) << c.text << format(r.status);
    EXPECT_EQ(r.status.index(), c.index) << c.text << format(r.status);
    EXPECT_STREQ(r.status.file(), "scan.obj");
    EXPECT_EQ(r.arena_after, 0u);
  }
}

TEST(ObjRead, CommentsAfterValuesAndBlankLines) {
  Result r = read("\n\n   \t\nv 0 0 0 # origin\nv 1 0 0\nv 0 1 0\n\nf 1 2 3 # one\n#f 3 2 1\n");
  ASSERT_TRUE(r.status.is_ok()) << format(r.status);
  EXPECT_EQ(r.triangles.size(), 1u);
  r = read("");
  ASSERT_TRUE(r.status.is_ok()) << format(r.status);
  EXPECT_TRUE(r.vertices.empty());
}

TEST(ObjRead, Limits) {
  std::string text = "v 0 0 0\n# " + std::string(5000, 'x') + "\n";
  Result r = read(text);
  EXPECT_EQ(r.status.code(), StatusCode::kLimitExceeded) << format(r.status);
  EXPECT_EQ(r.status.line(), 2u);
  MeshReadOptions o;
  o.max_line_bytes = 6000;
  EXPECT_TRUE(read(text, o).status.is_ok());
  o = MeshReadOptions{};
  o.max_vertices = 2;
  r = read("v 0 0 0\nv 1 0 0\nv 0 1 0\n", o);
  EXPECT_EQ(r.status.code(), StatusCode::kLimitExceeded);
  EXPECT_EQ(r.status.line(), 3u);
  o = MeshReadOptions{};
  o.max_triangles = 2;
  r = read("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nv 2 2 0\nf 1 2 3 4 5\n", o);
  EXPECT_EQ(r.status.code(), StatusCode::kLimitExceeded);
  EXPECT_EQ(r.status.column(), 11u);
  o = MeshReadOptions{};
  o.max_line_bytes = 10;
  EXPECT_EQ(read("v 0 0 0\n", o).status.code(), StatusCode::kInvalidArgument);
}

TEST(ObjRead, WeldMergesSeamDuplicates) {
  // A texture seam: vertex 4 repeats vertex 2 and 5 repeats 3.
  const char text[] = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 4 6 5\n";
  MeshReadOptions o;
  o.weld = true;
  Result r = read(text, o);
  ASSERT_TRUE(r.status.is_ok()) << format(r.status);
  EXPECT_EQ(r.vertices.size(), 4u);
  const std::vector<std::vector<uint32_t>> expected = {{0, 1, 2}, {1, 3, 2}};
  EXPECT_EQ(triangles_of(r), expected);
}

// A cut OBJ is often still a valid OBJ (it is line oriented): every prefix must either read
// cleanly as a prefix of the mesh or fail cleanly, never anything else.
TEST(ObjRead, EveryTruncationIsCleanOrAPrefix) {
  const std::string text = kCube;
  const Result whole = read(text);
  ASSERT_TRUE(whole.status.is_ok());
  size_t failures = 0;
  for (size_t n = 0; n < text.size(); ++n) {
    Result r = read(text.substr(0, n), MeshReadOptions{}, 3, n % 2 == 0);
    if (r.status.is_ok()) {
      EXPECT_LE(r.vertices.size(), whole.vertices.size());
      ASSERT_LE(r.triangles.size(), whole.triangles.size());
      for (size_t t = 0; t < r.triangles.size(); ++t) {
        EXPECT_EQ(std::memcmp(&r.triangles[t], &whole.triangles[t], sizeof(Triangle)), 0) << n;
      }
    } else {
      ++failures;
      EXPECT_EQ(r.status.code(), StatusCode::kParseError) << n << ": " << format(r.status);
      EXPECT_NE(r.status.line(), kNoPosition);
      EXPECT_EQ(r.arena_after, 0u);
    }
  }
  EXPECT_GT(failures, 10u);  // cuts inside "f" lines and corners fail
}

TEST(ObjRead, ArenaExhaustion) {
  // Buffers of 4096 + 4096 bytes, then 16 vertices (384 bytes) and 16 triangles (192 bytes).
  MeshReadOptions options;
  options.chunk_bytes = 4096;
  for (size_t cap : {size_t{0}, size_t{1000}, size_t{8192 + 100}, size_t{8192 + 384 + 100}}) {
    std::vector<unsigned char> memory(cap + 16);
    Arena arena(memory.data(), cap);
    Context ctx(&arena);
    MemorySource ms{reinterpret_cast<const uint8_t*>(kCube), std::strlen(kCube), 0, 0};
    Mesh mesh;
    Status s = splintcore::read_obj(ctx, splintcore::memory_source(&ms), options, &mesh, nullptr);
    EXPECT_EQ(s.code(), StatusCode::kArenaExhausted) << cap;
    EXPECT_NE(std::string(s.message()).find("need"), std::string::npos) << format(s);
    EXPECT_EQ(arena.used(), 0u);
  }
}

}  // namespace
