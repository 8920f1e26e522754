// Tests of the PLY reader (src/io/ply_read.cpp) and of format detection (read_mesh): hand-made
// files of every variant (ASCII, binary little- and big-endian, every scalar type, skipped
// properties, lists and elements), fan triangulation, sources that deliver a few bytes at a
// time or hide their size, truncation at every byte offset, lying and absurd counts, indices
// out of range, NaN and out-of-range coordinates, and the location of every error.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
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

struct Params {
  size_t max_chunk = 0;
  bool size_known = true;
  MeshReadOptions options{};
  bool detect = false;  // through read_mesh
  const char* name = "test.ply";
};

struct Result {
  Status status;
  std::vector<Vec3> vertices;
  std::vector<Triangle> triangles;
  MeshReadInfo info;
  size_t arena_after = 0;  // used() after the call, relative to before
  size_t arena_peak = 0;   // high water during the call, relative to before
};

Result read(const std::string& bytes, const Params& p = Params{}) {
  Arena& arena = shared_arena();
  ArenaScope scope(arena);
  const size_t before = arena.used();
  arena.reset_high_water();
  Context ctx(&arena);
  MemorySource ms{reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size(), 0, p.max_chunk};
  splintcore::ByteSource source = splintcore::memory_source(&ms, p.name);
  if (!p.size_known) source.size = kUnknownSize;
  Mesh mesh;
  Result r;
  r.status = p.detect ? splintcore::read_mesh(ctx, source, p.options, &mesh, &r.info)
                      : splintcore::read_ply(ctx, source, p.options, &mesh, &r.info);
  r.vertices.assign(mesh.vertices.begin(), mesh.vertices.end());
  r.triangles.assign(mesh.triangles.begin(), mesh.triangles.end());
  r.arena_after = arena.used() - before;
  r.arena_peak = arena.high_water() - before;
  return r;
}

bool same_triangles(const std::vector<Triangle>& a, const std::vector<std::vector<uint32_t>>& b) {
  if (a.size() != b.size()) return false;
  for (size_t t = 0; t < a.size(); ++t) {
    for (int k = 0; k < 3; ++k) {
      if (a[t].v[k] != b[t][static_cast<size_t>(k)]) return false;
    }
  }
  return true;
}

bool same_vertices(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i) {
    if (std::memcmp(&a[i], &b[i], sizeof(Vec3)) != 0) return false;
  }
  return true;
}

// The reference mesh of most tests: a square (two triangles by fan) and a triangle on top.
const std::vector<Vec3> kVertices = {
    {0, 0, 0}, {1.5, 0, 0}, {1.5, 2.25, 0}, {0, 2.25, 0}, {0.75, 1.125, -3.5}};
const std::vector<std::vector<uint32_t>> kTriangles = {{0, 1, 2}, {0, 2, 3}, {1, 2, 4}};

const char kAscii[] =
    "ply\n"                                     // 1
    "format ascii 1.0\n"                        // 2
    "comment made by hand\n"                    // 3
    "obj_info scanner test\n"                   // 4
    "element vertex 5\n"                        // 5
    "property float x\n"                        // 6
    "property float y\n"                        // 7
    "property float z\n"                        // 8
    "property float nx\n"                       // 9
    "property uchar red\n"                      // 10
    "property list uchar int texture\n"         // 11
    "element edge 1\n"                          // 12
    "property int vertex1\n"                    // 13
    "property int vertex2\n"                    // 14
    "element face 2\n"                          // 15
    "property uchar flags\n"                    // 16
    "property list uchar int vertex_indices\n"  // 17
    "end_header\n"                              // 18
    "0 0 0 1 255 0\n"                           // 19
    "1.5 0 0 1 255 2 7 8\n"                     // 20
    "1.5 2.25 0 1 255 0\n"                      // 21
    "0 2.25 0 1 0 0\n"                          // 22
    "0.75 1.125 -3.5 nan 3 0\n"                 // 23 (nan in a skipped property)
    "0 1\n"                                     // 24
    "9 4 0 1 2 3\n"                             // 25
    "0 3 1 2 4\n";                              // 26

// A binary file of the same mesh: every scalar type appears once.
enum class Endian { kLittle, kBig };

struct BinaryWriter {
  Endian endian;
  std::string bytes;
  void raw(uint64_t bits, int n) {
    for (int i = 0; i < n; ++i) {
      const int shift = endian == Endian::kLittle ? 8 * i : 8 * (n - 1 - i);
      bytes.push_back(static_cast<char>((bits >> shift) & 0xff));
    }
  }
  void f32(float f) {
    uint32_t b;
    std::memcpy(&b, &f, 4);
    raw(b, 4);
  }
  void f64(double d) {
    uint64_t b;
    std::memcpy(&b, &d, 8);
    raw(b, 8);
  }
};

std::string binary_ply(Endian endian, bool xyz_double = false, int64_t face_index_delta = 0) {
  BinaryWriter w{endian, ""};
  w.bytes = std::string("ply\nformat ") +
            (endian == Endian::kLittle ? "binary_little_endian" : "binary_big_endian") +
            " 1.0\ncomment binary\nelement vertex 5\n"
            "property char c\nproperty " +
            (xyz_double ? "double" : "float") +
            " x\n"
            "property uint8 u\nproperty " +
            (xyz_double ? "float64" : "float32") +
            " y\n"
            "property short s\nproperty ushort us\nproperty " +
            (xyz_double ? "double" : "float") +
            " z\n"
            "property int i\nproperty uint ui\nproperty double d\n"
            "property list ushort float tex\n"
            "element material 2\nproperty list uint uchar name\n"
            "element face 2\nproperty list uchar uint vertex_indices\nproperty int16 flag\n"
            "end_header\n";
  for (size_t v = 0; v < kVertices.size(); ++v) {
    w.raw(static_cast<uint8_t>(-3), 1);
    if (xyz_double)
      w.f64(kVertices[v].x);
    else
      w.f32(static_cast<float>(kVertices[v].x));
    w.raw(200, 1);
    if (xyz_double)
      w.f64(kVertices[v].y);
    else
      w.f32(static_cast<float>(kVertices[v].y));
    w.raw(0xfffe, 2);
    w.raw(65535, 2);
    if (xyz_double)
      w.f64(kVertices[v].z);
    else
      w.f32(static_cast<float>(kVertices[v].z));
    w.raw(0xffffffff, 4);
    w.raw(123456, 4);
    w.f64(std::numeric_limits<double>::quiet_NaN());  // skipped: never checked
    w.raw(v, 2);                                      // a list of v floats
    for (size_t k = 0; k < v; ++k) w.f32(0.5f);
  }
  w.raw(3, 4);
  w.bytes += "abc";
  w.raw(0, 4);
  w.raw(4, 1);
  for (uint32_t i : {0u, 1u, 2u, 3u}) w.raw(static_cast<uint64_t>(i + face_index_delta), 4);
  w.raw(7, 2);
  w.raw(3, 1);
  for (uint32_t i : {1u, 2u, 4u}) w.raw(i, 4);
  w.raw(7, 2);
  return w.bytes;
}

TEST(PlyRead, AsciiWithSkippedPropertiesElementsAndFan) {
  Result r = read(kAscii);
  ASSERT_TRUE(r.status.is_ok()) << format(r.status);
  EXPECT_TRUE(same_vertices(r.vertices, kVertices));
  EXPECT_TRUE(same_triangles(r.triangles, kTriangles));
  EXPECT_EQ(r.info.format, MeshFormat::kPlyAscii);
  EXPECT_EQ(r.info.vertices, 5u);
  EXPECT_EQ(r.info.faces, 2u);
  EXPECT_EQ(r.info.triangles, 3u);
  EXPECT_EQ(r.info.bytes, std::strlen(kAscii));
  // Only the mesh stays in the arena: 5 vertices, 3 triangles (with alignment padding).
  EXPECT_LE(r.arena_after, 5 * sizeof(Vec3) + 3 * sizeof(Triangle) + 32);
}

TEST(PlyRead, BinaryBothEndiansEqualAscii) {
  for (Endian e : {Endian::kLittle, Endian::kBig}) {
    for (bool dbl : {false, true}) {
      Result r = read(binary_ply(e, dbl));
      ASSERT_TRUE(r.status.is_ok()) << format(r.status);
      EXPECT_EQ(r.info.format, e == Endian::kLittle ? MeshFormat::kPlyBinaryLittleEndian
                                                    : MeshFormat::kPlyBinaryBigEndian);
      EXPECT_TRUE(same_vertices(r.vertices, kVertices));
      EXPECT_TRUE(same_triangles(r.triangles, kTriangles));
    }
  }
}

TEST(PlyRead, SmallChunksAndUnknownSizeGiveTheSameMesh) {
  const std::string files[] = {kAscii, binary_ply(Endian::kLittle), binary_ply(Endian::kBig)};
  for (const std::string& f : files) {
    for (size_t chunk : {size_t{1}, size_t{3}, size_t{7}, size_t{64}}) {
      for (bool known : {true, false}) {
        Params p;
        p.max_chunk = chunk;
        p.size_known = known;
        Result r = read(f, p);
        ASSERT_TRUE(r.status.is_ok()) << format(r.status);
        EXPECT_TRUE(same_vertices(r.vertices, kVertices));
        EXPECT_TRUE(same_triangles(r.triangles, kTriangles));
      }
    }
  }
}

TEST(PlyRead, Float32RoundingAndExactDoubles) {
  const std::string text =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\nproperty double y\n"
      "property double z\nelement face 1\nproperty list uchar uint vertex_index\nend_header\n"
      "0.1 0.2 0.3\n1 0 0\n0 1 0\n3 0 1 2\n";
  Result r = read(text);
  ASSERT_TRUE(r.status.is_ok()) << format(r.status);
  EXPECT_EQ(r.vertices[0].x, static_cast<double>(0.1f));  // rounded to float32 by default
  Params p;
  p.options.round_to_float32 = false;
  r = read(text, p);
  ASSERT_TRUE(r.status.is_ok()) << format(r.status);
  EXPECT_EQ(r.vertices[0].x, 0.1);
  EXPECT_EQ(r.vertices[0].z, 0.3);
  // Binary double kept exactly without rounding, rounded with.
  BinaryWriter w{Endian::kLittle,
                 "ply\nformat binary_little_endian 1.0\nelement vertex 1\n"
                 "property double x\nproperty double y\nproperty double z\n"
                 "end_header\n"};
  w.f64(0.1);
  w.f64(-0.2);
  w.f64(1e-300);
  r = read(w.bytes, p);
  ASSERT_TRUE(r.status.is_ok()) << format(r.status);
  EXPECT_EQ(r.vertices[0].x, 0.1);
  EXPECT_EQ(r.vertices[0].z, 1e-300);
  r = read(w.bytes);
  ASSERT_TRUE(r.status.is_ok()) << format(r.status);
  EXPECT_EQ(r.vertices[0].y, static_cast<double>(-0.2f));
  EXPECT_EQ(r.vertices[0].z, 0.0);
  EXPECT_TRUE(r.triangles.empty());  // a point cloud is a mesh without triangles
}

TEST(PlyRead, WeldMergesExactDuplicates) {
  const std::string text =
      "ply\nformat ascii 1.0\nelement vertex 6\nproperty float x\nproperty float y\n"
      "property float z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n"
      "0 0 0\n1 0 0\n0 1 0\n1 0 0\n0 1 0\n1 1 -0\n3 0 1 2\n3 3 5 4\n";
  Params p;
  p.options.weld = true;
  Result r = read(text, p);
  ASSERT_TRUE(r.status.is_ok()) << format(r.status);
  EXPECT_EQ(r.vertices.size(), 4u);
  EXPECT_TRUE(same_triangles(r.triangles, {{0, 1, 2}, {1, 3, 2}}));
  p.options.round_to_float32 = false;
  EXPECT_EQ(read(text, p).status.code(), StatusCode::kInvalidArgument);
  r = read(text);
  EXPECT_EQ(r.vertices.size(), 6u);  // not welded: as given
}

// A random binary PLY: vertices with x, y, z float32 among other properties (or, for some
// seeds, a double or a list, the layouts the in-buffer runs leave to the general path), faces
// of 3 corners (some polygons) with a count of any integer type and int or uint indices (for
// some seeds a second face property), a few bad records (an index out of range or negative, a
// face of 2 corners, a NaN) and, for some seeds, the file cut short.
std::string random_binary_ply(uint32_t seed) {
  std::mt19937 rng(seed);
  auto coin = [&](int in) { return std::uniform_int_distribution<int>(0, in - 1)(rng) == 0; };
  const bool big = coin(2);
  const bool plain_vertex = !coin(4), plain_face = !coin(4);
  const char* count_type = coin(2) ? "uchar" : coin(2) ? "ushort" : "int";
  const size_t count_bytes = count_type[0] == 'u' && count_type[1] == 'c' ? 1
                             : count_type[1] == 's'                       ? 2
                                                                          : 4;
  const bool signed_index = coin(2);
  const uint32_t nv = 3 + std::uniform_int_distribution<uint32_t>(0, 200)(rng);
  const uint32_t nf = std::uniform_int_distribution<uint32_t>(0, 300)(rng);
  std::string out =
      std::string("ply\nformat ") + (big ? "binary_big_endian" : "binary_little_endian") +
      " 1.0\nelement vertex " + std::to_string(nv) +
      "\nproperty uchar red\nproperty float x\nproperty float y\n" +
      (plain_vertex ? "property float z\n" : "property double z\n") +
      "property short quality\nelement face " + std::to_string(nf) + "\nproperty list " +
      count_type + (signed_index ? " int" : " uint") + " vertex_indices\n" +
      (plain_face ? "" : "property float weight\n") + "end_header\n";
  auto put = [&](uint64_t bits, size_t n) {
    for (size_t k = 0; k < n; ++k) {
      out.push_back(static_cast<char>(bits >> (8 * (big ? n - 1 - k : k))));
    }
  };
  auto put_float = [&](float f) {
    uint32_t bits;
    std::memcpy(&bits, &f, 4);
    put(bits, 4);
  };
  std::uniform_real_distribution<float> coordinate(-50.0f, 50.0f);
  for (uint32_t v = 0; v < nv; ++v) {
    put(v & 0xff, 1);
    put_float(coordinate(rng));
    put_float(coin(300) ? std::numeric_limits<float>::quiet_NaN() : coordinate(rng));
    if (plain_vertex) {
      put_float(coordinate(rng));
    } else {
      const double z = static_cast<double>(coordinate(rng));
      uint64_t bits;
      std::memcpy(&bits, &z, 8);
      put(bits, 8);
    }
    put(v & 0xffff, 2);
  }
  std::uniform_int_distribution<uint32_t> index(0, nv - 1);
  for (uint32_t f = 0; f < nf; ++f) {
    const uint32_t corners = coin(10) ? 4 + static_cast<uint32_t>(coin(2)) : coin(400) ? 2 : 3;
    put(corners, count_bytes);
    for (uint32_t k = 0; k < corners; ++k) {
      uint32_t i = index(rng);
      if (coin(800)) i = nv + static_cast<uint32_t>(coin(2));  // out of range
      if (coin(800)) i = 0xffffffffu;                          // -1 as int, 2^32 - 1 as uint
      put(i, 4);
    }
    if (!plain_face) put_float(0.5f);
  }
  if (coin(5)) out.resize(out.size() - std::uniform_int_distribution<size_t>(1, 40)(rng));
  return out;
}

// The runs that read whole records in the buffer (the usual layouts), the in-place decoding of
// the others, and the value-by-value path (a source that gives one byte at a time, so no
// record is ever whole in the buffer) read the same meshes and report the same errors.
TEST(PlyRead, RecordsInTheBufferReadAsValueByValue) {
  int errors = 0;
  for (uint32_t seed = 1; seed <= 300; ++seed) {
    const std::string file = random_binary_ply(seed);
    Params by_values;
    by_values.max_chunk = 1;
    const Result a = read(file, by_values);
    for (size_t chunk : {size_t{0}, size_t{97}, size_t{4096}}) {
      Params p;
      p.max_chunk = chunk;
      p.options.weld = (seed & 1) != 0;
      by_values.options.weld = p.options.weld;
      const Result w = p.options.weld ? read(file, by_values) : a;
      const Result b = read(file, p);
      ASSERT_EQ(b.status.code(), w.status.code()) << "seed " << seed << ": " << format(b.status);
      EXPECT_STREQ(b.status.message(), w.status.message()) << "seed " << seed;
      EXPECT_EQ(b.status.byte_offset(), w.status.byte_offset()) << "seed " << seed;
      EXPECT_EQ(b.status.index(), w.status.index()) << "seed " << seed;
      EXPECT_TRUE(same_vertices(b.vertices, w.vertices)) << "seed " << seed;
      ASSERT_EQ(b.triangles.size(), w.triangles.size()) << "seed " << seed;
      for (size_t t = 0; t < b.triangles.size(); ++t) {
        for (int k = 0; k < 3; ++k) EXPECT_EQ(b.triangles[t].v[k], w.triangles[t].v[k]);
      }
    }
    errors += a.status.is_ok() ? 0 : 1;
  }
  // Both kinds of file are there: read whole, and refused.
  EXPECT_GT(errors, 30);
  EXPECT_LT(errors, 270);
}

TEST(PlyRead, EveryTruncationIsACleanError) {
  const std::string files[] = {kAscii, binary_ply(Endian::kLittle), binary_ply(Endian::kBig)};
  for (const std::string& f : files) {
    // The ASCII file's last byte is its final newline, which a file may leave out.
    const size_t valid_from =
        f[0] == 'p' && f.find("ascii") != std::string::npos ? f.size() - 1 : f.size();
    for (size_t n = 0; n < valid_from; ++n) {
      for (bool known : {true, false}) {
        Params p;
        p.size_known = known;
        p.max_chunk = 5;
        Result r = read(f.substr(0, n), p);
        ASSERT_FALSE(r.status.is_ok()) << "prefix of " << n << " bytes was read";
        const StatusCode c = r.status.code();
        // (kUnsupported: "format ascii 1.0" cut to "1.")
        EXPECT_TRUE(c == StatusCode::kTruncated || c == StatusCode::kParseError ||
                    c == StatusCode::kUnsupported)
            << n << ": " << format(r.status);
        EXPECT_TRUE(r.vertices.empty() && r.triangles.empty());
        EXPECT_EQ(r.arena_after, 0u);
        EXPECT_STREQ(r.status.file(), "test.ply");
        EXPECT_TRUE(r.status.byte_offset() != kNoPosition || r.status.line() != kNoPosition)
            << format(r.status);
      }
    }
  }
}

TEST(PlyRead, LyingCountsAreCaughtBeforeReserving) {
  // 1000000 vertices declared, 5 present.
  std::string text = kAscii;
  text.replace(text.find("vertex 5"), 8, "vertex 1000000");
  Result r = read(text);
  EXPECT_EQ(r.status.code(), StatusCode::kTruncated) << format(r.status);
  EXPECT_LT(r.arena_peak, size_t{1} << 20);  // nothing of 24 MB was reserved
  EXPECT_NE(std::string(r.status.message()).find("follow the header"), std::string::npos);
  // The same for an unknown size: read until the records stop matching (the edge line).
  Params p;
  p.size_known = false;
  r = read(text, p);
  EXPECT_EQ(r.status.code(), StatusCode::kParseError) << format(r.status);
  EXPECT_EQ(r.status.line(), 24u);
  EXPECT_LT(r.arena_peak, size_t{1} << 20);
  // Fewer declared than present: data after the last element.
  std::string bin = binary_ply(Endian::kLittle);
  bin.replace(bin.find("face 2"), 6, "face 1");
  r = read(bin);
  EXPECT_EQ(r.status.code(), StatusCode::kParseError) << format(r.status);
  EXPECT_NE(std::string(r.status.message()).find("data after"), std::string::npos);
  text = kAscii;
  text.replace(text.find("face 2"), 6, "face 1");
  r = read(text);
  EXPECT_EQ(r.status.code(), StatusCode::kParseError);
  EXPECT_EQ(r.status.line(), 26u);
}

TEST(PlyRead, AbsurdCounts) {
  const std::string head = "ply\nformat binary_big_endian 1.0\nelement vertex ";
  const std::string props = "\nproperty float x\nproperty float y\nproperty float z\n";
  // Over the limits.
  Result r = read(head + "4000000000" + props + "end_header\n");
  EXPECT_EQ(r.status.code(), StatusCode::kLimitExceeded) << format(r.status);
  Params p;
  p.options.max_triangles = 10;
  r = read(
      head + "3" + props + "element face 11\nproperty list uchar int vertex_indices\nend_header\n",
      p);
  EXPECT_EQ(r.status.code(), StatusCode::kLimitExceeded) << format(r.status);
  // A count whose byte size overflows 64 bits.
  r = read(head + "1" + props +
           "element junk 9223372036854775807\nproperty double a\n"
           "property double b\nend_header\n");
  EXPECT_EQ(r.status.code(), StatusCode::kTruncated) << format(r.status);
  EXPECT_NE(std::string(r.status.message()).find("2^64"), std::string::npos);
  r = read(head + "-1" + props + "end_header\n");
  EXPECT_EQ(r.status.code(), StatusCode::kParseError);
  r = read(head + "99999999999999999999999" + props + "end_header\n");
  EXPECT_EQ(r.status.code(), StatusCode::kParseError);
  // A list claiming 4 billion items in a stream of unknown size: truncated, no allocation.
  BinaryWriter w{Endian::kLittle,
                 "ply\nformat binary_little_endian 1.0\nelement vertex 0\n"
                 "property float x\nproperty float y\nproperty float z\n"
                 "element blob 1\nproperty list uint double data\nend_header\n"};
  w.raw(0xffffffffu, 4);
  w.f64(1);
  p = Params{};
  p.size_known = false;
  r = read(w.bytes, p);
  EXPECT_EQ(r.status.code(), StatusCode::kTruncated) << format(r.status);
  EXPECT_EQ(r.status.index(), 0u);
  // An element of 10^18 records of no properties (no bytes each, in binary): read at once (it
  // looped for minutes, found by the fuzzer), the mesh the same as without it; in ASCII each
  // record needs a line, which the file runs out of.
  const std::string box_props =
      "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
  BinaryWriter plain{Endian::kLittle, "ply\nformat binary_little_endian 1.0\n" + box_props};
  BinaryWriter padded{Endian::kLittle,
                      "ply\nformat binary_little_endian 1.0\nelement pad "
                      "1000000000000000000\n" +
                          box_props};
  for (BinaryWriter* b : {&plain, &padded}) {
    for (float c : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f}) b->f32(c);
    b->raw(3, 1);
    for (uint32_t i : {0u, 1u, 2u}) b->raw(i, 4);
  }
  const Result without = read(plain.bytes);
  r = read(padded.bytes);
  ASSERT_TRUE(without.status.is_ok()) << format(without.status);
  ASSERT_TRUE(r.status.is_ok()) << format(r.status);
  EXPECT_EQ(r.vertices, without.vertices);
  EXPECT_EQ(r.triangles.size(), 1u);
  r = read("ply\nformat ascii 1.0\nelement pad 1000000000000000000\n" + box_props +
           "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  EXPECT_NE(r.status.code(), splintcore::StatusCode::kOk);
  // Many faces of many corners: the triangle limit counts after fan triangulation.
  p = Params{};
  p.options.max_triangles = 2;
  r = read(kAscii, p);
  EXPECT_EQ(r.status.code(), StatusCode::kLimitExceeded) << format(r.status);
  EXPECT_EQ(r.status.index(), 1u);  // the second face makes the third triangle
}

TEST(PlyRead, IndicesOutOfRange) {
  Result r = read(binary_ply(Endian::kBig, false, 2));  // first face: 2 3 4 5
  EXPECT_EQ(r.status.code(), StatusCode::kParseError) << format(r.status);
  EXPECT_EQ(r.status.index(), 0u);
  EXPECT_NE(r.status.byte_offset(), kNoPosition);
  EXPECT_NE(std::string(r.status.message()).find("vertex index 5"), std::string::npos);
  std::string text = kAscii;
  text.replace(text.find("0 3 1 2 4"), 9, "0 3 1 2 -1");
  r = read(text);
  EXPECT_EQ(r.status.code(), StatusCode::kParseError) << format(r.status);
  EXPECT_EQ(r.status.index(), 1u);
  EXPECT_EQ(r.status.line(), 26u);
  EXPECT_EQ(r.status.column(), 9u);
  text = kAscii;
  text.replace(text.find("0 3 1 2 4"), 9, "0 2 1 2");
  r = read(text);
  EXPECT_EQ(r.status.code(), StatusCode::kParseError) << format(r.status);
  EXPECT_NE(std::string(r.status.message()).find("at least 3"), std::string::npos);
  // An index beyond its declared type (uchar count 256).
  text = kAscii;
  text.replace(text.find("0 3 1 2 4"), 9, "0 256 1 2 4");
  EXPECT_EQ(read(text).status.code(), StatusCode::kParseError);
}

TEST(PlyRead, NonFiniteAndOutOfRangeCoordinates) {
  std::string text = kAscii;
  text.replace(text.find("0.75 1.125 -3.5"), 15, "0.75 -inf -3.5");
  Result r = read(text);
  EXPECT_EQ(r.status.code(), StatusCode::kNonFinite) << format(r.status);
  EXPECT_EQ(r.status.line(), 23u);
  EXPECT_EQ(r.status.column(), 6u);
  EXPECT_EQ(r.status.index(), 4u);
  text = kAscii;
  text.replace(text.find("0.75 1.125 -3.5"), 15, "0.75 1.125 -3.5e7");
  r = read(text);
  EXPECT_EQ(r.status.code(), StatusCode::kLimitExceeded) << format(r.status);
  EXPECT_EQ(r.status.index(), 4u);
  text = kAscii;
  text.replace(text.find("0.75 1.125 -3.5"), 15, "0.75 1.125 -3,5");
  EXPECT_EQ(read(text).status.code(), StatusCode::kParseError);
  text = kAscii;
  text.replace(text.find("0.75 1.125 -3.5"), 15, "0.75 1.125 1e99");  // beyond float32
  EXPECT_EQ(read(text).status.code(), StatusCode::kParseError);
  // Binary: a NaN in z of vertex 2, and 1e300 (a double) beyond the limit.
  for (bool dbl : {false, true}) {
    std::string bin = binary_ply(Endian::kLittle, dbl);
    const size_t header = bin.find("end_header\n") + 11;
    // Records of c x u y s us z i ui d and a list of v floats (record v has v items).
    const size_t base = dbl ? 48 : 36;
    const size_t z_at = header + 2 * base + 4 + (dbl ? 22 : 14);  // record 2's z
    BinaryWriter w{Endian::kLittle, ""};
    if (dbl)
      w.f64(1e300);
    else
      w.f32(std::numeric_limits<float>::quiet_NaN());
    bin.replace(z_at, w.bytes.size(), w.bytes);
    r = read(bin);
    EXPECT_EQ(r.status.code(), dbl ? StatusCode::kLimitExceeded : StatusCode::kNonFinite)
        << format(r.status);
    EXPECT_EQ(r.status.index(), 2u);
    EXPECT_NE(r.status.byte_offset(), kNoPosition);
  }
}

TEST(PlyRead, HeaderErrorsNameTheLine) {
  struct Case {
    std::string text;
    StatusCode code;
    uint64_t line;
  };
  const std::string xyz = "property float x\nproperty float y\nproperty float z\n";
  const Case cases[] = {
      {"plx\n", StatusCode::kParseError, 1},
      {"ply\nelement vertex 1\n", StatusCode::kParseError, 2},
      {"ply\nformat ascii 2.0\n", StatusCode::kUnsupported, 2},
      {"ply\nformat binary 1.0\n", StatusCode::kParseError, 2},
      {"ply\nformat ascii 1.0\nelement vertex 1\n" + xyz + "bogus\nend_header\n",
       StatusCode::kParseError, 7},
      {"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
       "end_header\n0 0\n",
       StatusCode::kParseError, 6},
      {"ply\nformat ascii 1.0\nelement vertex 1\n" + xyz + "property quad w\nend_header\n",
       StatusCode::kParseError, 7},
      {"ply\nformat ascii 1.0\nelement vertex 1\n" + xyz + "property float x\nend_header\n",
       StatusCode::kParseError, 7},
      {"ply\nformat ascii 1.0\nelement vertex 0\n" + xyz +
           "element face 0\nproperty list float int vertex_indices\nend_header\n",
       StatusCode::kUnsupported, 8},
      {"ply\nformat ascii 1.0\nelement vertex 0\n" + xyz +
           "element face 0\nproperty list uchar float vertex_indices\nend_header\n",
       StatusCode::kUnsupported, 8},
      {"ply\nformat ascii 1.0\nelement vertex 0\n" + xyz +
           "element face 0\nproperty list uchar int corners\nend_header\n",
       StatusCode::kParseError, 9},
      {"ply\nformat ascii 1.0\nelement face 0\nproperty list uchar int vertex_indices\n"
       "end_header\n",
       StatusCode::kParseError, 5},
      {"ply\nformat ascii 1.0\nproperty float x\n", StatusCode::kParseError, 3},
      {"ply\nformat ascii 1.0\nelement vertex 1\n" + xyz, StatusCode::kTruncated, 7},
  };
  for (const Case& c : cases) {
    Result r = read(c.text);
    EXPECT_EQ(r.status.code(), c.code) << c.text << "\n" << format(r.status);
    EXPECT_EQ(r.status.line(), c.line) << c.text << "\n" << format(r.status);
  }
}

TEST(PlyRead, LongLinesAndCrLf) {
  std::string text = kAscii;
  for (size_t at = text.find('\n'); at != std::string::npos; at = text.find('\n', at + 2)) {
    text.insert(at, "\r");
  }
  Result r = read(text);
  ASSERT_TRUE(r.status.is_ok()) << format(r.status);
  EXPECT_TRUE(same_triangles(r.triangles, kTriangles));
  text = kAscii;
  text.replace(text.find("made by hand"), 12, std::string(5000, 'x'));
  r = read(text);
  EXPECT_EQ(r.status.code(), StatusCode::kLimitExceeded) << format(r.status);
  EXPECT_EQ(r.status.line(), 3u);
  Params p;
  p.options.max_line_bytes = 8192;
  EXPECT_TRUE(read(text, p).status.is_ok());
}

TEST(PlyRead, ArenaExhaustionIsReportedAtEveryCap) {
  const std::string bin = binary_ply(Endian::kLittle);
  bool succeeded = false;
  for (size_t cap = 0; cap < 200000 && !succeeded; cap += 997) {
    std::vector<unsigned char> memory(cap + 16);
    Arena arena(memory.data(), cap);
    Context ctx(&arena);
    MemorySource ms{reinterpret_cast<const uint8_t*>(bin.data()), bin.size(), 0, 0};
    Mesh mesh;
    MeshReadOptions options;
    options.weld = true;
    Status s = splintcore::read_ply(ctx, splintcore::memory_source(&ms), options, &mesh, nullptr);
    if (s.is_ok()) {
      succeeded = true;
      EXPECT_EQ(mesh.triangles.size(), 3u);
    } else {
      EXPECT_EQ(s.code(), StatusCode::kArenaExhausted) << format(s);
      EXPECT_EQ(arena.used(), 0u);
    }
  }
  EXPECT_TRUE(succeeded);
}

TEST(MeshReadDetect, ByContentThenExtension) {
  auto detect = [](const std::string& head, const char* name) {
    return splintcore::detect_mesh_format(reinterpret_cast<const uint8_t*>(head.data()),
                                          head.size(), name);
  };
  EXPECT_EQ(detect("ply\nformat ascii 1.0\n", "a.stl"), MeshFormat::kPlyAscii);
  EXPECT_EQ(detect("ply\r\nformat ascii 1.0\n", nullptr), MeshFormat::kPlyAscii);
  EXPECT_EQ(detect("solid x\nfacet normal 0 0 1\n", "a.obj"), MeshFormat::kStlAscii);
  EXPECT_EQ(detect("# scan\nv 1 2 3\n", "a.stl"), MeshFormat::kObj);
  EXPECT_EQ(detect("\n\nmtllib a.mtl\nv 1 2 3\n", nullptr), MeshFormat::kObj);
  EXPECT_EQ(detect("v 1 2 3\n", nullptr), MeshFormat::kObj);
  EXPECT_EQ(detect(std::string("\x01\x02\x00\x00", 4), "scan.PLY"), MeshFormat::kPlyAscii);
  EXPECT_EQ(detect(std::string("\x01\x02\x00\x00", 4), "scan.Obj"), MeshFormat::kObj);
  EXPECT_EQ(detect(std::string("\x01\x02\x00\x00", 4), "scan.stl"), MeshFormat::kStlBinary);
  EXPECT_EQ(detect("hello world\n", nullptr), MeshFormat::kStlBinary);
  EXPECT_STREQ(splintcore::mesh_format_name(MeshFormat::kPlyBinaryBigEndian), "ply-binary-be");
}

TEST(MeshReadDetect, ReadMeshDispatches) {
  Params p;
  p.detect = true;
  p.max_chunk = 100;  // the peek and the replay cross chunk boundaries
  p.name = "scan.bin";
  for (const std::string& f : {std::string(kAscii), binary_ply(Endian::kBig)}) {
    Result r = read(f, p);
    ASSERT_TRUE(r.status.is_ok()) << format(r.status);
    EXPECT_TRUE(same_triangles(r.triangles, kTriangles));
  }
  Result r = read("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", p);
  ASSERT_TRUE(r.status.is_ok()) << format(r.status);
  EXPECT_EQ(r.info.format, MeshFormat::kObj);
  EXPECT_EQ(r.triangles.size(), 1u);
  // STL through read_mesh: welded, as read_stl_mesh does.
  const float lo[3] = {0, 0, 0}, hi[3] = {1, 2, 3};
  const std::vector<uint8_t> stl = splintcore::test::binary_stl(splintcore::shapes::box(lo, hi));
  r = read(std::string(stl.begin(), stl.end()), p);
  ASSERT_TRUE(r.status.is_ok()) << format(r.status);
  EXPECT_EQ(r.info.format, MeshFormat::kStlBinary);
  EXPECT_EQ(r.vertices.size(), 8u);
  EXPECT_EQ(r.triangles.size(), 12u);
  EXPECT_EQ(r.info.bytes, stl.size());
  // An error inside a detected PLY names the source.
  std::string bad = kAscii;
  bad.replace(bad.find("0 3 1 2 4"), 9, "0 3 1 2 9");
  r = read(bad, p);
  EXPECT_EQ(r.status.code(), StatusCode::kParseError);
  EXPECT_STREQ(r.status.file(), "scan.bin");
}

}  // namespace
