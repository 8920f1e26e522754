// Tests of the streaming STL writer (src/io/stl_write.cpp): the exact binary layout, the
// rounding and normal rules of io.h, bit-exact write/read round trips of random float32 data
// in both formats, byte-identical output whatever the buffer size, the unknown-count patch,
// and every error the writer reports.

#include <gtest/gtest.h>

#include <cfloat>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "common/shapes.h"
#include "splintcore/core.h"
#include "splintcore/io.h"
#include "splintcore/mesh.h"
#include "splintcore/platform.h"
#include "support/test_util.h"

namespace {

using splintcore::Arena;
using splintcore::ArenaArray;
using splintcore::ArenaScope;
using splintcore::ByteSink;
using splintcore::ByteSource;
using splintcore::Context;
using splintcore::kUnknownSize;
using splintcore::MemorySink;
using splintcore::MemorySource;
using splintcore::Mesh;
using splintcore::Progress;
using splintcore::SoupTriangle;
using splintcore::Status;
using splintcore::StatusCode;
using splintcore::StlFormat;
using splintcore::StlReadOptions;
using splintcore::StlWriteOptions;
using splintcore::StlWriter;
using splintcore::ThreadExecutor;
using splintcore::Triangle;
using splintcore::Vec3;
using splintcore::test::format;

Arena& shared_arena() {
  static splintcore::test::TestArena arena(size_t{32} << 20);
  return arena.arena;
}

struct Tri {
  Vec3 a, b, c;
};

uint32_t bits_of(float f) {
  uint32_t b;
  std::memcpy(&b, &f, sizeof(b));
  return b;
}

uint32_t load_u32(const std::vector<uint8_t>& bytes, size_t at) {
  return uint32_t{bytes[at]} | (uint32_t{bytes[at + 1]} << 8) | (uint32_t{bytes[at + 2]} << 16) |
         (uint32_t{bytes[at + 3]} << 24);
}

float load_f32(const std::vector<uint8_t>& bytes, size_t at) {
  uint32_t b = load_u32(bytes, at);
  float f;
  std::memcpy(&f, &b, sizeof(f));
  return f;
}

// A growable output: a MemorySink over a buffer big enough for the test.
struct Output {
  std::vector<uint8_t> buffer;
  MemorySink state{};
  explicit Output(size_t capacity = size_t{4} << 20) : buffer(capacity) {
    state.data = buffer.data();
    state.capacity = buffer.size();
  }
  ByteSink sink() { return splintcore::memory_sink(&state, "out.stl"); }
  std::vector<uint8_t> bytes() const {
    return std::vector<uint8_t>(buffer.begin(),
                                buffer.begin() + static_cast<std::ptrdiff_t>(state.size));
  }
};

// Writes the triangles with an StlWriter; `declared` may be kUnknownSize.
Status write_tris(const std::vector<Tri>& tris, const StlWriteOptions& options, uint64_t declared,
                  std::vector<uint8_t>* out) {
  Arena& arena = shared_arena();
  ArenaScope scope(arena);
  Context ctx(&arena);
  Output o;
  StlWriter writer;
  SPLINTCORE_RETURN_IF_ERROR(writer.begin(ctx, o.sink(), options, declared));
  for (const Tri& t : tris) SPLINTCORE_RETURN_IF_ERROR(writer.add(t.a, t.b, t.c));
  SPLINTCORE_RETURN_IF_ERROR(writer.finish());
  *out = o.bytes();
  if (writer.bytes_written() != out->size()) {
    return Status::error(StatusCode::kInternal, "bytes_written() disagrees with the sink");
  }
  return Status::ok();
}

StlWriteOptions with_format(StlFormat f) {
  StlWriteOptions o;
  o.format = f;
  return o;
}

// A mesh whose triangle t uses vertices 3t, 3t+1, 3t+2.
void mesh_of(const std::vector<Tri>& tris, Arena& arena, Mesh* mesh) {
  mesh->bind(&arena);
  for (const Tri& t : tris) {
    const uint32_t base = static_cast<uint32_t>(mesh->vertices.size());
    ASSERT_TRUE(mesh->vertices.push_back(t.a));
    ASSERT_TRUE(mesh->vertices.push_back(t.b));
    ASSERT_TRUE(mesh->vertices.push_back(t.c));
    ASSERT_TRUE(mesh->triangles.push_back(Triangle{{base, base + 1, base + 2}}));
  }
}

Status write_mesh(const Mesh& mesh, const StlWriteOptions& options, std::vector<uint8_t>* out) {
  Arena& arena = shared_arena();
  Context ctx(&arena);
  Output o;
  Status s = splintcore::write_stl(ctx, mesh, o.sink(), options);
  *out = o.bytes();
  return s;
}

// Reads STL bytes back as soup, with no coordinate limit.
Status read_back(const std::vector<uint8_t>& bytes, std::vector<SoupTriangle>* soup) {
  Arena& arena = shared_arena();
  ArenaScope scope(arena);
  Context ctx(&arena);
  MemorySource ms{bytes.data(), bytes.size(), 0, 0};
  StlReadOptions options;
  options.max_abs_coordinate = std::numeric_limits<double>::infinity();
  ArenaArray<SoupTriangle> out(&arena);
  Status s =
      splintcore::read_stl(ctx, splintcore::memory_source(&ms, "back.stl"), options, &out, nullptr);
  soup->assign(out.begin(), out.end());
  return s;
}

// The normal io.h promises, computed independently from the float32 corners.
void expected_normal(const Tri& t, float n[3]) {
  // Each coordinate rounded to float32, then widened back (exactly) to double.
  auto rounded = [](const Vec3& p) {
    return Vec3{static_cast<double>(static_cast<float>(p.x)),
                static_cast<double>(static_cast<float>(p.y)),
                static_cast<double>(static_cast<float>(p.z))};
  };
  const Vec3 a = rounded(t.a);
  const Vec3 b = rounded(t.b);
  const Vec3 c = rounded(t.c);
  const Vec3 u = b - a;
  const Vec3 v = c - a;
  const Vec3 m{u.y * v.z - u.z * v.y, u.z * v.x - u.x * v.z, u.x * v.y - u.y * v.x};
  const double len = std::sqrt(m.x * m.x + m.y * m.y + m.z * m.z);
  if (len > 0.0 && std::isfinite(len)) {
    n[0] = static_cast<float>(m.x / len);
    n[1] = static_cast<float>(m.y / len);
    n[2] = static_cast<float>(m.z / len);
  } else {
    n[0] = n[1] = n[2] = 0.0f;
  }
}

// The bits a float is written with (-0 becomes +0).
uint32_t written_bits(float f) {
  uint32_t b = bits_of(f);
  return b == 0x80000000u ? 0u : b;
}

// ---- binary layout ----------------------------------------------------------------------------

TEST(StlWriteTest, BinaryLayout) {
  const double nz = -0.0;
  const double tie_even = 1.0 + std::ldexp(1.0, -24);       // halfway: rounds down to 1
  const double tie_odd = 1.0 + 3.0 * std::ldexp(1.0, -24);  // halfway: rounds up to 1 + 2^-22
  const std::vector<Tri> tris = {
      {{0.1, 0.2, 0.3}, {1.7, -0.4, 2.2}, {-3.3, 5.5, 0.01}},
      {{nz, nz, nz}, {nz, 1.0, nz}, {1.0, nz, nz}},         // normal (0, 0, -1)
      {{1.0, 2.0, 3.0}, {1.0, 2.0, 3.0}, {1.0, 2.0, 3.0}},  // a point
      {{0.0, 0.0, 0.0}, {1.0, 1.0, 1.0}, {2.0, 2.0, 2.0}},  // collinear
      {{tie_even, tie_odd, 0.0}, {2.0, 0.0, 0.0}, {0.0, 2.0, 0.0}},
  };
  std::vector<uint8_t> bytes;
  SPLINTCORE_ASSERT_OK(write_tris(tris, with_format(StlFormat::kBinary), tris.size(), &bytes));
  ASSERT_EQ(bytes.size(), 84u + 50u * tris.size());

  std::string header(reinterpret_cast<const char*>(bytes.data()), 80);
  std::string expected_header = "splintcore binary STL";
  expected_header.resize(80, ' ');
  EXPECT_EQ(header, expected_header);
  EXPECT_NE(header.compare(0, 5, "solid"), 0);
  EXPECT_EQ(load_u32(bytes, 80), tris.size());

  for (size_t t = 0; t < tris.size(); ++t) {
    SCOPED_TRACE(t);
    const size_t r = 84 + 50 * t;
    float n[3];
    expected_normal(tris[t], n);
    for (size_t a = 0; a < 3; ++a) {
      EXPECT_EQ(load_u32(bytes, r + 4 * a), written_bits(n[a]));
    }
    const Vec3* corners[3] = {&tris[t].a, &tris[t].b, &tris[t].c};
    for (size_t k = 0; k < 3; ++k) {
      for (size_t a = 0; a < 3; ++a) {
        const float f = static_cast<float>((*corners[k])[static_cast<int>(a)]);
        EXPECT_EQ(load_u32(bytes, r + 12 + 12 * k + 4 * a), written_bits(f));
      }
    }
    EXPECT_EQ(bytes[r + 48], 0);  // attribute byte count
    EXPECT_EQ(bytes[r + 49], 0);
  }
  // Spot checks against known values rather than the re-computation above.
  const size_t r0 = 84;
  EXPECT_EQ(load_f32(bytes, r0 + 12), 0.1f);
  EXPECT_EQ(load_f32(bytes, r0 + 12 + 4), 0.2f);
  const size_t r1 = 84 + 50;
  EXPECT_EQ(load_u32(bytes, r1 + 0), 0u);  // normal x: +0, not -0
  EXPECT_EQ(load_u32(bytes, r1 + 4), 0u);
  EXPECT_EQ(load_f32(bytes, r1 + 8), -1.0f);
  for (size_t a = 0; a < 3; ++a) EXPECT_EQ(load_u32(bytes, r1 + 12 + 4 * a), 0u);  // -0 corner
  for (size_t t : {size_t{2}, size_t{3}}) {  // degenerate: zero normal
    for (size_t a = 0; a < 3; ++a) EXPECT_EQ(load_u32(bytes, 84 + 50 * t + 4 * a), 0u);
  }
  const size_t r4 = 84 + 50 * 4;
  EXPECT_EQ(load_f32(bytes, r4 + 12), 1.0f);                          // ties to even: down
  EXPECT_EQ(load_f32(bytes, r4 + 16), 1.0f + std::ldexp(1.0f, -22));  // ties to even: up
  // No negative zero anywhere in the float fields.
  for (size_t t = 0; t < tris.size(); ++t) {
    for (size_t f = 0; f < 12; ++f) EXPECT_NE(load_u32(bytes, 84 + 50 * t + 4 * f), 0x80000000u);
  }
}

TEST(StlWriteTest, NormalsOfAKnownMesh) {
  // Every facet normal of a box is an axis direction of length 1, pointing outward.
  const float lo[3] = {-1.0f, -2.0f, -3.0f};
  const float hi[3] = {4.0f, 5.0f, 6.0f};
  const std::vector<SoupTriangle> box = splintcore::shapes::box(lo, hi);
  Arena& arena = shared_arena();
  ArenaScope scope(arena);
  Mesh mesh;
  SPLINTCORE_ASSERT_OK(splintcore::test::mesh_from_soup(arena, box, &mesh));
  std::vector<uint8_t> bytes;
  SPLINTCORE_ASSERT_OK(write_mesh(mesh, with_format(StlFormat::kBinary), &bytes));
  ASSERT_EQ(bytes.size(), 684u);
  for (size_t t = 0; t < 12; ++t) {
    float n[3], centre[3] = {0, 0, 0};
    for (size_t a = 0; a < 3; ++a) n[a] = load_f32(bytes, 84 + 50 * t + 4 * a);
    for (size_t k = 0; k < 3; ++k) {
      for (size_t a = 0; a < 3; ++a)
        centre[a] += load_f32(bytes, 84 + 50 * t + 12 + 12 * k + 4 * a) / 3.0f;
    }
    int nonzero = 0;
    for (size_t a = 0; a < 3; ++a) {
      if (n[a] != 0.0f) {
        ++nonzero;
        EXPECT_EQ(std::fabs(n[a]), 1.0f);
        // Outward: the face lies on the side of the box the normal points to.
        EXPECT_EQ(n[a] > 0.0f, centre[a] == hi[a]) << "triangle " << t;
      }
    }
    EXPECT_EQ(nonzero, 1);
  }
}

TEST(StlWriteTest, AsciiLayout) {
  const std::vector<Tri> tris = {{{0.0, 0.0, 0.0}, {1.0, 0.0, 0.0}, {0.0, 1.0, 0.0}},
                                 {{-0.0, -0.0, 0.5}, {0.0, 1.0, 0.5}, {1.0, -0.0, 0.5}}};
  std::vector<uint8_t> bytes;
  SPLINTCORE_ASSERT_OK(write_tris(tris, with_format(StlFormat::kAscii), tris.size(), &bytes));
  const std::string text(bytes.begin(), bytes.end());
  EXPECT_EQ(text,
            "solid splintcore\n"
            "  facet normal 0 0 1\n"
            "    outer loop\n"
            "      vertex 0 0 0\n"
            "      vertex 1 0 0\n"
            "      vertex 0 1 0\n"
            "    endloop\n"
            "  endfacet\n"
            "  facet normal 0 0 -1\n"
            "    outer loop\n"
            "      vertex 0 0 0.5\n"
            "      vertex 0 1 0.5\n"
            "      vertex 1 0 0.5\n"
            "    endloop\n"
            "  endfacet\n"
            "endsolid splintcore\n");
}

// ---- round trips ------------------------------------------------------------------------------

// Any finite float32 (sign, exponent including subnormals, mantissa from raw random bits), so
// magnitudes range from 1.4e-45 to 3.4e38.
float random_float(std::mt19937_64& rng) {
  for (;;) {
    const uint32_t bits = static_cast<uint32_t>(rng());
    float f;
    std::memcpy(&f, &bits, sizeof(f));
    if (std::isfinite(f)) return f;
  }
}

// `count` random triangles and one more with the extreme values.
std::vector<Tri> random_tris(uint64_t seed, size_t count) {
  std::mt19937_64 rng(seed);
  std::vector<Tri> tris;
  for (size_t t = 0; t < count; ++t) {
    Vec3 p[3];
    for (Vec3& v : p) {
      for (int a = 0; a < 3; ++a) {
        const uint64_t kind = rng() % 4;
        float f;
        if (kind == 0) {
          f = random_float(rng);
        } else if (kind == 1) {  // ordinary millimetres
          f = static_cast<float>(static_cast<int64_t>(rng() % 2000001) - 1000000) / 1000.0f;
        } else if (kind == 2) {  // tiny, subnormals included
          f = std::ldexp(static_cast<float>(rng() % 16777216), -static_cast<int>(rng() % 130) - 24);
        } else {  // huge
          f = std::ldexp(1.0f + static_cast<float>(rng() % 8388608) / 8388608.0f,
                         100 + static_cast<int>(rng() % 28));
        }
        if (rng() % 2 == 0) f = -f;
        v[a] = static_cast<double>(f);
      }
    }
    tris.push_back({p[0], p[1], p[2]});
  }
  // Extremes.
  const double kMax = static_cast<double>(FLT_MAX);
  const double kMinSub = static_cast<double>(std::numeric_limits<float>::denorm_min());
  tris.push_back({{kMax, -kMax, kMinSub},
                  {-kMinSub, 0.0, -0.0},
                  {static_cast<double>(FLT_MIN), -static_cast<double>(FLT_MIN), kMax}});
  return tris;
}

TEST(StlWriteTest, RoundTripIsBitExact) {
  for (uint64_t seed : {uint64_t{1}, uint64_t{2}, uint64_t{20240601}}) {
    const std::vector<Tri> tris = random_tris(seed, 400);
    for (StlFormat f : {StlFormat::kBinary, StlFormat::kAscii}) {
      SCOPED_TRACE("seed " + std::to_string(seed) +
                   (f == StlFormat::kAscii ? " ascii" : " binary"));
      Arena& arena = shared_arena();
      ArenaScope scope(arena);
      Mesh mesh;
      mesh_of(tris, arena, &mesh);
      std::vector<uint8_t> bytes;
      SPLINTCORE_ASSERT_OK(write_mesh(mesh, with_format(f), &bytes));
      std::vector<SoupTriangle> back;
      Status s = read_back(bytes, &back);
      ASSERT_TRUE(s.is_ok()) << format(s);
      ASSERT_EQ(back.size(), tris.size());
      size_t mismatches = 0;
      for (size_t t = 0; t < tris.size(); ++t) {
        const Vec3* corners[3] = {&tris[t].a, &tris[t].b, &tris[t].c};
        for (int k = 0; k < 3; ++k) {
          for (int a = 0; a < 3; ++a) {
            const float want = static_cast<float>((*corners[k])[a]);
            if (bits_of(back[t].p[k][a]) != written_bits(want)) {
              if (++mismatches < 10) {
                ADD_FAILURE() << "triangle " << t << " corner " << k << " axis " << a << ": wrote "
                              << want << ", read " << back[t].p[k][a];
              }
            }
          }
        }
      }
      EXPECT_EQ(mismatches, 0u);
      if (f == StlFormat::kAscii) {
        // The normals read back too (checked as numbers by the reader); no "-0" anywhere.
        const std::string text(bytes.begin(), bytes.end());
        std::istringstream words(text);
        std::string w;
        while (words >> w) EXPECT_NE(w, "-0");
      }
    }
  }
}

TEST(StlWriteTest, AsciiUsesShortestForm) {
  const std::vector<Tri> tris = {
      {{0.1, 1.0 / 3.0, 1e-45}, {100.0, -2.5, 3.4028234663852886e38}, {1e10, 123456.789, 0.0}}};
  std::vector<uint8_t> bytes;
  SPLINTCORE_ASSERT_OK(write_tris(tris, with_format(StlFormat::kAscii), 1, &bytes));
  const std::string text(bytes.begin(), bytes.end());
  EXPECT_NE(text.find("vertex 0.1 0.33333334 1e-45\n"), std::string::npos) << text;
  EXPECT_NE(text.find("vertex 100 -2.5 3.4028235e+38\n"), std::string::npos) << text;
  EXPECT_NE(text.find("vertex 1e+10 123456.79 0\n"), std::string::npos) << text;
}

// ---- determinism ------------------------------------------------------------------------------

TEST(StlWriteTest, SameMeshSameBytes) {
  Arena& arena = shared_arena();
  ArenaScope scope(arena);
  Mesh torus;
  SPLINTCORE_ASSERT_OK(
      splintcore::test::mesh_from_soup(arena, splintcore::shapes::torus(24, 16, 10, 3), &torus));
  Mesh random;
  mesh_of(random_tris(7, 300), arena, &random);
  for (const Mesh* mesh : {&torus, &random}) {
    for (StlFormat f : {StlFormat::kBinary, StlFormat::kAscii, StlFormat::kAuto}) {
      StlWriteOptions o = with_format(f);
      std::vector<uint8_t> first, second, small, large, tiny;
      SPLINTCORE_ASSERT_OK(write_mesh(*mesh, o, &first));
      SPLINTCORE_ASSERT_OK(write_mesh(*mesh, o, &second));
      EXPECT_EQ(first, second);
      o.buffer_bytes = 4096;
      SPLINTCORE_ASSERT_OK(write_mesh(*mesh, o, &small));
      o.buffer_bytes = size_t{1} << 20;
      SPLINTCORE_ASSERT_OK(write_mesh(*mesh, o, &large));
      o.buffer_bytes = 1;  // clamped to the minimum
      SPLINTCORE_ASSERT_OK(write_mesh(*mesh, o, &tiny));
      EXPECT_GT(first.size(), 4096u);  // several flushes with the small buffer
      EXPECT_EQ(first, small);
      EXPECT_EQ(first, large);
      EXPECT_EQ(first, tiny);
      if (f == StlFormat::kAuto) {  // kAuto means binary
        std::vector<uint8_t> binary;
        SPLINTCORE_ASSERT_OK(write_mesh(*mesh, with_format(StlFormat::kBinary), &binary));
        EXPECT_EQ(first, binary);
      }
      // A hashing sink sees the same bytes.
      splintcore::HashSink hs;
      Context ctx(&arena);
      SPLINTCORE_ASSERT_OK(splintcore::write_stl(ctx, *mesh, splintcore::hash_sink(&hs), o));
      uint8_t digest[32];
      hs.sha.finish(digest);
      char hex[65];
      splintcore::Sha256::to_hex(digest, hex);
      EXPECT_EQ(hs.size, first.size());
      EXPECT_EQ(std::string(hex), splintcore::test::sha256_hex(first.data(), first.size()));
    }
  }
}

TEST(StlWriteTest, WriteStlLeavesTheArenaWhereItWas) {
  Arena& arena = shared_arena();
  ArenaScope scope(arena);
  Mesh mesh;
  mesh_of(random_tris(3, 50), arena, &mesh);
  const size_t before = arena.used();
  std::vector<uint8_t> bytes;
  SPLINTCORE_ASSERT_OK(write_mesh(mesh, with_format(StlFormat::kAscii), &bytes));
  EXPECT_EQ(arena.used(), before);
}

// ---- StlWriter: counts, sinks, bad values -----------------------------------------------------

TEST(StlWriteTest, UnknownCountIsPatchedOnASeekableSink) {
  const std::vector<Tri> tris = random_tris(11, 200);
  for (size_t buffer_bytes : {size_t{4096}, size_t{1} << 20}) {
    StlWriteOptions o = with_format(StlFormat::kBinary);
    o.buffer_bytes = buffer_bytes;
    std::vector<uint8_t> known, unknown;
    SPLINTCORE_ASSERT_OK(write_tris(tris, o, tris.size(), &known));
    SPLINTCORE_ASSERT_OK(write_tris(tris, o, kUnknownSize, &unknown));
    EXPECT_EQ(load_u32(unknown, 80), tris.size());
    EXPECT_EQ(unknown.size(), 84u + 50u * tris.size());
    EXPECT_EQ(known, unknown);
  }
  // Zero triangles.
  std::vector<uint8_t> empty;
  SPLINTCORE_ASSERT_OK(write_tris({}, with_format(StlFormat::kBinary), kUnknownSize, &empty));
  ASSERT_EQ(empty.size(), 84u);
  EXPECT_EQ(load_u32(empty, 80), 0u);
  // The sink's position is left at the end (so more writes would append).
  Arena& arena = shared_arena();
  ArenaScope scope(arena);
  Context ctx(&arena);
  Output out;
  StlWriter w;
  SPLINTCORE_ASSERT_OK(w.begin(ctx, out.sink(), with_format(StlFormat::kBinary), kUnknownSize));
  SPLINTCORE_ASSERT_OK(w.add(tris[0].a, tris[0].b, tris[0].c));
  SPLINTCORE_ASSERT_OK(w.finish());
  EXPECT_EQ(out.state.position, 134u);
  EXPECT_EQ(w.triangles_written(), 1u);
  EXPECT_EQ(w.bytes_written(), 134u);
}

TEST(StlWriteTest, UnknownCountNeedsASeekableSinkForBinaryOnly) {
  Arena& arena = shared_arena();
  ArenaScope scope(arena);
  Context ctx(&arena);
  splintcore::HashSink hs;
  StlWriter w;
  Status s =
      w.begin(ctx, splintcore::hash_sink(&hs), with_format(StlFormat::kBinary), kUnknownSize);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument) << format(s);
  EXPECT_TRUE(std::string(s.message()).find("seekable") != std::string::npos) << format(s);
  Output out;
  ByteSink no_seek = out.sink();
  no_seek.seek = nullptr;
  StlWriter w2;
  s = w2.begin(ctx, no_seek, with_format(StlFormat::kBinary), kUnknownSize);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument) << format(s);
  EXPECT_EQ(out.state.size, 0u);  // nothing written

  // ASCII has no count: an unknown count is fine on any sink, and the bytes are the same.
  const std::vector<Tri> tris = random_tris(5, 20);
  std::vector<uint8_t> known;
  SPLINTCORE_ASSERT_OK(write_tris(tris, with_format(StlFormat::kAscii), tris.size(), &known));
  Output out2;
  ByteSink no_seek2 = out2.sink();
  no_seek2.seek = nullptr;
  StlWriter w3;
  SPLINTCORE_ASSERT_OK(w3.begin(ctx, no_seek2, with_format(StlFormat::kAscii), kUnknownSize));
  for (const Tri& t : tris) SPLINTCORE_ASSERT_OK(w3.add(t.a, t.b, t.c));
  SPLINTCORE_ASSERT_OK(w3.finish());
  EXPECT_EQ(out2.bytes(), known);
}

TEST(StlWriteTest, CountMismatches) {
  const std::vector<Tri> tris = random_tris(9, 3);
  for (StlFormat f : {StlFormat::kBinary, StlFormat::kAscii}) {
    SCOPED_TRACE(f == StlFormat::kAscii ? "ascii" : "binary");
    Arena& arena = shared_arena();
    ArenaScope scope(arena);
    Context ctx(&arena);
    {
      Output out;
      StlWriter w;
      SPLINTCORE_ASSERT_OK(w.begin(ctx, out.sink(), with_format(f), 2));
      SPLINTCORE_ASSERT_OK(w.add(tris[0].a, tris[0].b, tris[0].c));
      SPLINTCORE_ASSERT_OK(w.add(tris[1].a, tris[1].b, tris[1].c));
      Status s = w.add(tris[2].a, tris[2].b, tris[2].c);
      EXPECT_EQ(s.code(), StatusCode::kInvalidArgument) << format(s);
      EXPECT_TRUE(std::string(s.message()).find("2 declared") != std::string::npos) << format(s);
      // The error closed the writer: nothing more is taken, and nothing may seal the output.
      const size_t bytes = out.state.size;
      for (int call = 0; call < 2; ++call) {
        s = call == 0 ? w.add(tris[0].a, tris[0].b, tris[0].c) : w.finish();
        EXPECT_EQ(s.code(), StatusCode::kInvalidArgument) << format(s);
        EXPECT_STREQ(s.message(),
                     "STL writer is not open (begin() failed, or an earlier error closed it)");
      }
      EXPECT_EQ(out.state.size, bytes);
      EXPECT_EQ(w.triangles_written(), 2u);
    }
    {
      StlWriter never_begun;
      EXPECT_EQ(never_begun.add(tris[0].a, tris[0].b, tris[0].c).code(),
                StatusCode::kInvalidArgument);
      EXPECT_EQ(never_begun.finish().code(), StatusCode::kInvalidArgument);
    }
    {
      Output out;
      StlWriter w;
      SPLINTCORE_ASSERT_OK(w.begin(ctx, out.sink(), with_format(f), 3));
      SPLINTCORE_ASSERT_OK(w.add(tris[0].a, tris[0].b, tris[0].c));
      SPLINTCORE_ASSERT_OK(w.add(tris[1].a, tris[1].b, tris[1].c));
      Status s = w.finish();
      EXPECT_EQ(s.code(), StatusCode::kInvalidArgument) << format(s);
      EXPECT_TRUE(std::string(s.message()).find("declared 3 triangles but wrote 2") !=
                  std::string::npos)
          << format(s);
    }
  }
  // Binary cannot declare more than 2^32 - 1.
  Arena& arena = shared_arena();
  ArenaScope scope(arena);
  Context ctx(&arena);
  Output out;
  StlWriter w;
  Status s = w.begin(ctx, out.sink(), with_format(StlFormat::kBinary), uint64_t{1} << 32);
  EXPECT_EQ(s.code(), StatusCode::kLimitExceeded) << format(s);
  StlWriter w2;
  SPLINTCORE_EXPECT_OK(w2.begin(ctx, out.sink(), with_format(StlFormat::kBinary), UINT32_MAX));
}

struct FailingSink {
  uint64_t accept = 0;  // bytes accepted before write() starts failing
  uint64_t written = 0;
  bool seek_ok = true;
};

bool failing_write(void* user, const uint8_t*, size_t bytes) {
  FailingSink* f = static_cast<FailingSink*>(user);
  if (f->written + bytes > f->accept) return false;
  f->written += bytes;
  return true;
}

bool failing_seek(void* user, uint64_t) { return static_cast<FailingSink*>(user)->seek_ok; }

ByteSink failing_sink(FailingSink* f) {
  ByteSink s;
  s.write = failing_write;
  s.seek = failing_seek;
  s.user = f;
  s.name = "failing.stl";
  return s;
}

TEST(StlWriteTest, FailingSinkGivesIoError) {
  Arena& arena = shared_arena();
  ArenaScope scope(arena);
  Mesh torus;
  SPLINTCORE_ASSERT_OK(
      splintcore::test::mesh_from_soup(arena, splintcore::shapes::torus(24, 16, 10, 3), &torus));
  Context ctx(&arena);
  for (StlFormat f : {StlFormat::kBinary, StlFormat::kAscii}) {
    for (uint64_t accept : {uint64_t{0}, uint64_t{4096}, uint64_t{10000}}) {
      SCOPED_TRACE(std::to_string(accept) + (f == StlFormat::kAscii ? " ascii" : " binary"));
      FailingSink fs{accept, 0, true};
      StlWriteOptions o = with_format(f);
      o.buffer_bytes = 4096;
      Status s = splintcore::write_stl(ctx, torus, failing_sink(&fs), o);
      EXPECT_EQ(s.code(), StatusCode::kIoError) << format(s);
      EXPECT_STREQ(s.file(), "failing.stl");
      EXPECT_EQ(s.byte_offset(), fs.written);  // where the failed write would have gone
    }
  }
  // A tiny mesh: the only write happens in finish().
  FailingSink fs{0, 0, true};
  std::vector<Tri> one = random_tris(1, 1);
  StlWriter w;
  SPLINTCORE_ASSERT_OK(w.begin(ctx, failing_sink(&fs), with_format(StlFormat::kBinary), 1));
  SPLINTCORE_ASSERT_OK(w.add(one[0].a, one[0].b, one[0].c));
  Status s = w.finish();
  EXPECT_EQ(s.code(), StatusCode::kIoError) << format(s);
  // The count patch fails.
  FailingSink no_patch{1u << 20, 0, false};
  StlWriter w2;
  SPLINTCORE_ASSERT_OK(
      w2.begin(ctx, failing_sink(&no_patch), with_format(StlFormat::kBinary), kUnknownSize));
  SPLINTCORE_ASSERT_OK(w2.add(one[0].a, one[0].b, one[0].c));
  s = w2.finish();
  EXPECT_EQ(s.code(), StatusCode::kIoError) << format(s);
  EXPECT_EQ(s.byte_offset(), 80u);
  // A memory sink that is too small.
  Output small(1000);
  s = splintcore::write_stl(ctx, torus, small.sink(), with_format(StlFormat::kBinary));
  EXPECT_EQ(s.code(), StatusCode::kIoError) << format(s);
  // A sink with no write().
  StlWriter w3;
  s = w3.begin(ctx, ByteSink{}, with_format(StlFormat::kBinary), 1);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument) << format(s);
}

TEST(StlWriteTest, UnwritableCoordinates) {
  const double kNan = std::numeric_limits<double>::quiet_NaN();
  const double kInf = std::numeric_limits<double>::infinity();
  const double kFltMax = static_cast<double>(FLT_MAX);
  struct Case {
    Vec3 bad;
    StatusCode code;
  };
  const Case cases[] = {{{kNan, 0.0, 0.0}, StatusCode::kNonFinite},
                        {{0.0, -kInf, 0.0}, StatusCode::kNonFinite},
                        {{0.0, 0.0, 1e300}, StatusCode::kLimitExceeded},
                        {{-1e39, 0.0, 0.0}, StatusCode::kLimitExceeded},
                        {{0.0, std::nextafter(kFltMax, kInf), 0.0}, StatusCode::kLimitExceeded}};
  for (StlFormat f : {StlFormat::kBinary, StlFormat::kAscii}) {
    for (const Case& c : cases) {
      SCOPED_TRACE(format(Status::error(c.code, "")));
      std::vector<Tri> tris = random_tris(4, 5);
      tris[3].c = c.bad;
      Arena& arena = shared_arena();
      ArenaScope scope(arena);
      Mesh mesh;
      mesh_of(tris, arena, &mesh);
      std::vector<uint8_t> bytes;
      Status s = write_mesh(mesh, with_format(f), &bytes);
      EXPECT_EQ(s.code(), c.code) << format(s);
      EXPECT_EQ(s.index(), 3u);
      EXPECT_TRUE(std::string(s.message()).find("triangle 3") != std::string::npos) << format(s);
    }
  }
  // The largest float is writable.
  std::vector<Tri> tris = {{{kFltMax, -kFltMax, 0.0}, {0.0, 0.0, 0.0}, {1.0, 1.0, 1.0}}};
  std::vector<uint8_t> bytes;
  SPLINTCORE_EXPECT_OK(write_tris(tris, with_format(StlFormat::kBinary), 1, &bytes));
}

TEST(StlWriteTest, InvalidMeshIndex) {
  Arena& arena = shared_arena();
  ArenaScope scope(arena);
  Mesh mesh;
  mesh_of(random_tris(6, 4), arena, &mesh);
  mesh.triangles[2].v[1] = static_cast<uint32_t>(mesh.vertices.size());  // one past the end
  std::vector<uint8_t> bytes;
  Status s = write_mesh(mesh, with_format(StlFormat::kBinary), &bytes);
  EXPECT_EQ(s.code(), StatusCode::kInvalidMesh) << format(s);
  EXPECT_EQ(s.index(), 2u);
}

TEST(StlWriteTest, AsciiSolidName) {
  const std::vector<Tri> tris = random_tris(8, 2);
  const std::string max_name(64, 'n');
  for (const std::string& name : {std::string("a"), std::string("Part_1-v2.0"), max_name}) {
    SCOPED_TRACE(name);
    StlWriteOptions o = with_format(StlFormat::kAscii);
    o.solid_name = name.c_str();
    std::vector<uint8_t> bytes;
    SPLINTCORE_ASSERT_OK(write_tris(tris, o, tris.size(), &bytes));
    const std::string text(bytes.begin(), bytes.end());
    EXPECT_EQ(text.rfind("solid " + name + "\n", 0), 0u);
    const std::string tail = "endsolid " + name + "\n";
    ASSERT_GE(text.size(), tail.size());
    EXPECT_EQ(text.substr(text.size() - tail.size()), tail);
    std::vector<SoupTriangle> back;
    SPLINTCORE_EXPECT_OK(read_back(bytes, &back));
    EXPECT_EQ(back.size(), tris.size());
  }
  const std::string too_long(65, 'n');
  const char* bad_names[] = {"",       "two words",   "semi;colon",     "tab\there", "new\nline",
                             "slash/", "caf\xc3\xa9", too_long.c_str(), nullptr};
  Arena& arena = shared_arena();
  ArenaScope scope(arena);
  Context ctx(&arena);
  for (const char* name : bad_names) {
    SCOPED_TRACE(name == nullptr ? "(null)" : name);
    StlWriteOptions o = with_format(StlFormat::kAscii);
    o.solid_name = name;
    Output out;
    StlWriter w;
    Status s = w.begin(ctx, out.sink(), o, 1);
    EXPECT_EQ(s.code(), StatusCode::kInvalidArgument) << format(s);
    EXPECT_EQ(out.state.size, 0u);
    // Binary output ignores the name.
    o.format = StlFormat::kBinary;
    StlWriter wb;
    SPLINTCORE_EXPECT_OK(wb.begin(ctx, out.sink(), o, 0));
  }
}

// add_mesh encodes binary records in batches straight into the buffer, in tasks when the
// executor has threads and the buffer holds 8,192 records or more: the same bytes and the
// same error (with what the sink got before it) as add() one by one, and the same progress
// reports at every thread count. 70,000 triangles: past a progress report (65,536) and over
// several batches, in the smallest buffer (4,096 bytes), the default (64,000), the smallest
// task buffer (409,684) and a larger one; a NaN corner and an index out of range (which
// add() cannot be given: add_mesh names it) inside a batch.
TEST(StlWriteTest, RecordsEncodedInTasksAreTheSameAsOneByOne) {
  const std::vector<Tri> tris = random_tris(11, 70000);
  struct Seen {
    std::vector<uint64_t> done;
    static bool report(void* user, const char* stage, uint64_t done, uint64_t) {
      if (std::strcmp(stage, "write") == 0) static_cast<Seen*>(user)->done.push_back(done);
      return true;
    }
  };
  for (int fault = 0; fault < 3; ++fault) {
    for (size_t buffer : {size_t{4096}, size_t{64000}, size_t{409684}, size_t{1} << 20}) {
      SCOPED_TRACE("fault " + std::to_string(fault) + ", buffer " + std::to_string(buffer));
      StlWriteOptions options;
      options.buffer_bytes = buffer;
      std::vector<Tri> one_by_one = tris;
      if (fault == 1) one_by_one[50001].c.y = std::numeric_limits<double>::quiet_NaN();
      std::vector<uint8_t> added_bytes;  // what the sink got, also when add() refused
      Status added;
      {
        Arena& arena = shared_arena();
        ArenaScope scope(arena);
        const Context ctx(&arena);
        Output o;
        StlWriter writer;
        added = writer.begin(ctx, o.sink(), options, one_by_one.size());
        for (size_t t = 0; t < one_by_one.size() && added.is_ok(); ++t) {
          added = writer.add(one_by_one[t].a, one_by_one[t].b, one_by_one[t].c);
        }
        if (added.is_ok()) added = writer.finish();
        added_bytes = o.bytes();
      }
      EXPECT_EQ(added.is_ok(), fault != 1) << format(added);
      std::vector<uint8_t> first_bytes;
      std::vector<uint64_t> first_done;
      std::string first_status;
      for (unsigned threads : {0u, 1u, 2u, 3u}) {
        Arena& arena = shared_arena();
        ArenaScope scope(arena);
        Mesh mesh;
        mesh_of(tris, arena, &mesh);
        if (fault == 1) mesh.vertices[3 * 50001 + 2].y = std::numeric_limits<double>::quiet_NaN();
        if (fault == 2) mesh.triangles[30001].v[1] = static_cast<uint32_t>(mesh.vertices.size());
        ThreadExecutor pool(threads == 0 ? 1 : threads);
        Seen seen;
        Progress progress;
        progress.report = &Seen::report;
        progress.user = &seen;
        const Context ctx(&arena, threads == 0 ? nullptr : &pool.executor(), &progress);
        Output o;
        const Status s = splintcore::write_stl(ctx, mesh, o.sink(), options);
        EXPECT_EQ(s.is_ok(), fault == 0) << format(s);
        if (fault > 0) {
          EXPECT_EQ(s.index(), fault == 1 ? 50001u : 30001u);
        }
        if (threads == 0) {
          first_bytes = o.bytes();
          first_done = seen.done;
          first_status = format(s);
          if (fault == 0) {
            EXPECT_EQ(first_bytes.size(), 84u + 50u * tris.size());
          }
          if (fault != 2) {  // add() wrote the same before it stopped, and said the same
            EXPECT_TRUE(first_bytes == added_bytes);
            EXPECT_EQ(first_status, format(added));
          }
          continue;
        }
        EXPECT_TRUE(o.bytes() == first_bytes) << threads << " threads";
        EXPECT_EQ(seen.done, first_done) << threads << " threads";
        EXPECT_EQ(format(s), first_status) << threads << " threads";
      }
      // (A fault stops the writing before the second report.)
      const std::vector<uint64_t> reports =
          fault == 0 ? std::vector<uint64_t>{0, 65536} : std::vector<uint64_t>{0};
      EXPECT_EQ(first_done, reports);
    }
  }
}

}  // namespace
