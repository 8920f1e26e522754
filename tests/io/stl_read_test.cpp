// Tests of the STL reader (src/io/stl_read.cpp): small exact cases in both formats, format
// auto-detection, the ASCII dialects found in the wild, sources that deliver a few bytes at a
// time, truncation at every byte offset (meshoptimizer's parser tests), lying binary headers,
// non-finite and out-of-range coordinates, and the exact location of ASCII syntax errors.

#include <gtest/gtest.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "common/shapes.h"
#include "splintcore/core.h"
#include "splintcore/io.h"
#include "splintcore/mesh.h"
#include "support/test_util.h"

namespace {

using splintcore::Arena;
using splintcore::ArenaArray;
using splintcore::ArenaScope;
using splintcore::ByteSource;
using splintcore::Context;
using splintcore::kNoPosition;
using splintcore::kUnknownSize;
using splintcore::MemorySource;
using splintcore::Mesh;
using splintcore::MeshReport;
using splintcore::SoupTriangle;
using splintcore::Status;
using splintcore::StatusCode;
using splintcore::StlFormat;
using splintcore::StlInfo;
using splintcore::StlReadOptions;
using splintcore::Vec3;
using splintcore::test::binary_stl;
using splintcore::test::format;
using splintcore::test::to_bytes;

// One arena for the whole file (a 256 MiB TestArena per test would be slow to zero); every
// read rewinds it.
Arena& shared_arena() {
  static splintcore::test::TestArena arena(size_t{32} << 20);
  return arena.arena;
}

struct ReadParams {
  size_t max_chunk = 0;    // MemorySource.max_chunk
  bool size_known = true;  // false: ByteSource.size = kUnknownSize (a stream)
  StlReadOptions options{};
};

struct ReadResult {
  Status status;
  std::vector<SoupTriangle> soup;
  StlInfo info;
};

ReadResult read_bytes(const std::vector<uint8_t>& bytes, const ReadParams& params = ReadParams{}) {
  Arena& arena = shared_arena();
  ArenaScope scope(arena);
  Context ctx(&arena);
  MemorySource ms{bytes.data(), bytes.size(), 0, params.max_chunk};
  ByteSource source = splintcore::memory_source(&ms, "test.stl");
  if (!params.size_known) source.size = kUnknownSize;
  ArenaArray<SoupTriangle> soup(&arena);
  ReadResult r;
  r.status = splintcore::read_stl(ctx, source, params.options, &soup, &r.info);
  r.soup.assign(soup.begin(), soup.end());
  return r;
}

ReadResult read_text(const std::string& text, const ReadParams& params = ReadParams{}) {
  return read_bytes(to_bytes(text), params);
}

uint32_t bits_of(float f) {
  uint32_t b;
  std::memcpy(&b, &f, sizeof(b));
  return b;
}

bool same_soup(const std::vector<SoupTriangle>& a, const std::vector<SoupTriangle>& b) {
  if (a.size() != b.size()) return false;
  for (size_t t = 0; t < a.size(); ++t) {
    for (int k = 0; k < 3; ++k) {
      for (int c = 0; c < 3; ++c) {
        if (bits_of(a[t].p[k][c]) != bits_of(b[t].p[k][c])) return false;
      }
    }
  }
  return true;
}

std::string float_text(float f) {
  char buf[64];
  auto r = std::to_chars(buf, buf + sizeof(buf), f);
  return std::string(buf, r.ptr);
}

// ASCII STL of the soup: facet t starts on line 2 + 7t, its vertex k is on line 4 + 7t + k,
// "endsolid" is on line 2 + 7n.
std::string ascii_stl(const std::vector<SoupTriangle>& soup, const std::string& name = "box",
                      const std::string& eol = "\n") {
  std::string s = "solid " + name + eol;
  for (const SoupTriangle& t : soup) {
    s += "  facet normal 0 0 0" + eol + "    outer loop" + eol;
    for (int k = 0; k < 3; ++k) {
      s += "      vertex " + float_text(t.p[k][0]) + " " + float_text(t.p[k][1]) + " " +
           float_text(t.p[k][2]) + eol;
    }
    s += "    endloop" + eol + "  endfacet" + eol;
  }
  s += "endsolid " + name + eol;
  return s;
}

const float kLo[3] = {-1.5f, 0.25f, -3.0f};
const float kHi[3] = {2.0f, 7.125f, 10.5f};

std::vector<SoupTriangle> test_box() { return splintcore::shapes::box(kLo, kHi); }

// A one-facet ASCII file; line numbers are given next to each line.
const char kOneFacet[] =
    "solid t\n"             // 1
    "facet normal 0 0 1\n"  // 2
    " outer loop\n"         // 3
    "  vertex 0 0 0\n"      // 4
    "  vertex 1 0 0\n"      // 5
    "  vertex 0 1 0\n"      // 6
    " endloop\n"            // 7
    "endfacet\n"            // 8
    "endsolid t\n";         // 9

std::string replace_once(std::string s, const std::string& from, const std::string& to) {
  size_t at = s.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) s.replace(at, from.size(), to);
  return s;
}

bool message_has(const Status& s, const std::string& text) {
  return std::string(s.message()).find(text) != std::string::npos;
}

// ---- small exact cases ------------------------------------------------------------------------

TEST(StlReadTest, BinaryBoxIsExact) {
  const std::vector<SoupTriangle> box = test_box();
  const std::vector<uint8_t> bytes = binary_stl(box, "a binary box");
  ASSERT_EQ(bytes.size(), 684u);
  ReadResult r = read_bytes(bytes);
  ASSERT_TRUE(r.status.is_ok()) << format(r.status);
  EXPECT_TRUE(same_soup(r.soup, box));
  EXPECT_EQ(r.info.format, StlFormat::kBinary);
  EXPECT_EQ(r.info.triangles, 12u);
  EXPECT_EQ(r.info.bytes, 684u);
  EXPECT_STREQ(r.info.header, "a binary box");  // the rest of the 80 bytes are NUL
}

TEST(StlReadTest, BinaryHeaderIsAll80Bytes) {
  std::string header(80, 'h');
  header[0] = 'H';
  std::vector<uint8_t> bytes = binary_stl(test_box(), header.c_str());
  ReadResult r = read_bytes(bytes);
  ASSERT_TRUE(r.status.is_ok()) << format(r.status);
  EXPECT_EQ(std::string(r.info.header), header);
  EXPECT_EQ(r.info.header[80], '\0');
}

TEST(StlReadTest, AsciiBoxIsExact) {
  const std::vector<SoupTriangle> box = test_box();
  const std::string text = ascii_stl(box, "my_box");
  ReadResult r = read_text(text);
  ASSERT_TRUE(r.status.is_ok()) << format(r.status);
  EXPECT_TRUE(same_soup(r.soup, box));
  EXPECT_EQ(r.info.format, StlFormat::kAscii);
  EXPECT_EQ(r.info.triangles, 12u);
  EXPECT_EQ(r.info.bytes, text.size());
  EXPECT_STREQ(r.info.header, "my_box");
}

TEST(StlReadTest, BoxMeshWeldsToEightVertices) {
  const std::vector<SoupTriangle> box = test_box();
  for (int ascii = 0; ascii < 2; ++ascii) {
    SCOPED_TRACE(ascii ? "ascii" : "binary");
    const std::vector<uint8_t> bytes = ascii ? to_bytes(ascii_stl(box)) : binary_stl(box);
    Arena& arena = shared_arena();
    ArenaScope scope(arena);
    Mesh mesh;
    StlInfo info;
    Status s = splintcore::test::mesh_from_bytes(arena, bytes, &mesh, &info);
    ASSERT_TRUE(s.is_ok()) << format(s);
    ASSERT_EQ(mesh.vertices.size(), 8u);
    ASSERT_EQ(mesh.triangles.size(), 12u);
    EXPECT_EQ(info.triangles, 12u);
    // Every corner maps back to its exact coordinates; ids are in order of first appearance.
    uint32_t next_new = 0;
    for (size_t t = 0; t < 12; ++t) {
      for (int k = 0; k < 3; ++k) {
        const uint32_t id = mesh.triangles[t].v[k];
        ASSERT_LT(id, 8u);
        EXPECT_LE(id, next_new);
        if (id == next_new) ++next_new;
        const Vec3& v = mesh.vertices[id];
        EXPECT_EQ(v.x, static_cast<double>(box[t].p[k][0]));
        EXPECT_EQ(v.y, static_cast<double>(box[t].p[k][1]));
        EXPECT_EQ(v.z, static_cast<double>(box[t].p[k][2]));
      }
    }
    EXPECT_EQ(next_new, 8u);
    // All 8 corners of the box are present.
    for (int c = 0; c < 8; ++c) {
      const Vec3 corner{static_cast<double>((c & 1) ? kHi[0] : kLo[0]),
                        static_cast<double>((c & 2) ? kHi[1] : kLo[1]),
                        static_cast<double>((c & 4) ? kHi[2] : kLo[2])};
      bool found = false;
      for (const Vec3& v : mesh.vertices) found = found || v == corner;
      EXPECT_TRUE(found) << "corner " << c;
    }
    MeshReport report;
    Context ctx(&arena);
    SPLINTCORE_ASSERT_OK(splintcore::check_mesh(ctx, mesh, &report));
    EXPECT_TRUE(report.is_valid_solid());
    EXPECT_EQ(report.volume, 3.5 * 6.875 * 13.5);  // dyadic: exact
  }
}

// ---- auto-detection ---------------------------------------------------------------------------

TEST(StlReadTest, BinaryWithSolidHeaderIsBinary) {
  const std::vector<SoupTriangle> box = test_box();
  ReadResult r = read_bytes(binary_stl(box, "solid box exported by a CAD program"));
  ASSERT_TRUE(r.status.is_ok()) << format(r.status);
  EXPECT_EQ(r.info.format, StlFormat::kBinary);
  EXPECT_TRUE(same_soup(r.soup, box));
  EXPECT_STREQ(r.info.header, "solid box exported by a CAD program");

  // Larger than the 1024-byte detection window, and header text padded with spaces.
  const std::vector<SoupTriangle> torus = splintcore::shapes::torus(12, 8, 10, 3);
  std::string header = "solid torus";
  header.resize(80, ' ');
  r = read_bytes(binary_stl(torus, header.c_str()));
  ASSERT_TRUE(r.status.is_ok()) << format(r.status);
  EXPECT_EQ(r.info.format, StlFormat::kBinary);
  EXPECT_TRUE(same_soup(r.soup, torus));

  // Zero triangles: the count field (four NUL bytes) is still not text.
  r = read_bytes(binary_stl({}, "solid"));
  ASSERT_TRUE(r.status.is_ok()) << format(r.status);
  EXPECT_EQ(r.info.format, StlFormat::kBinary);
  EXPECT_EQ(r.info.triangles, 0u);
  EXPECT_EQ(r.info.bytes, 84u);
}

TEST(StlReadTest, AsciiWithLeadingWhiteSpace) {
  const std::vector<SoupTriangle> box = test_box();
  ReadResult r = read_text("\n\r\n \t  " + ascii_stl(box, "lead"));
  ASSERT_TRUE(r.status.is_ok()) << format(r.status);
  EXPECT_EQ(r.info.format, StlFormat::kAscii);
  EXPECT_TRUE(same_soup(r.soup, box));
  EXPECT_STREQ(r.info.header, "lead");
}

TEST(StlReadTest, AsciiUpperAndMixedCaseKeywords) {
  const std::string text =
      "SOLID UPPER\n"
      "  FACET NORMAL 0 0 1\n"
      "    OUTER LOOP\n"
      "      VERTEX 0 0 0\n"
      "      Vertex 1 0 0\n"
      "      VERTEX 0 1 0\n"
      "    ENDLOOP\n"
      "  ENDFACET\n"
      "  Facet Normal 0 0 1\n"
      "    Outer Loop\n"
      "      vErTeX 0 0 2\n"
      "      vertex 1 0 2\n"
      "      vertex 0 1 2\n"
      "    EndLoop\n"
      "  EndFacet\n"
      "ENDSOLID UPPER\n";
  ReadResult r = read_text(text);
  ASSERT_TRUE(r.status.is_ok()) << format(r.status);
  EXPECT_EQ(r.info.format, StlFormat::kAscii);
  ASSERT_EQ(r.soup.size(), 2u);
  EXPECT_EQ(r.soup[0].p[1][0], 1.0f);
  EXPECT_EQ(r.soup[1].p[2][2], 2.0f);
  EXPECT_STREQ(r.info.header, "UPPER");  // the name keeps its case
}

TEST(StlReadTest, AsciiMultipleSolidsAreConcatenated) {
  const std::vector<SoupTriangle> box = test_box();
  std::vector<SoupTriangle> first(box.begin(), box.begin() + 5);
  std::vector<SoupTriangle> second(box.begin() + 5, box.end());
  ReadResult r = read_text(ascii_stl(first, "part_a") + ascii_stl(second, "part_b") +
                           "solid empty\nendsolid empty\n");
  ASSERT_TRUE(r.status.is_ok()) << format(r.status);
  EXPECT_TRUE(same_soup(r.soup, box));
  EXPECT_EQ(r.info.triangles, 12u);
  EXPECT_STREQ(r.info.header, "part_a");  // the first solid's name
}

TEST(StlReadTest, AsciiExplicitPlusSignsAndExponents) {
  const std::string text =
      "solid plus\n"
      "facet normal +0 +0 +1\n"
      "outer loop\n"
      "vertex +1.5 -2.5e+1 +0.125E1\n"
      "vertex 1e0 +2E-1 -0\n"
      "vertex 00003 .5 4.\n"
      "endloop\n"
      "endfacet\n"
      "endsolid plus\n";
  ReadResult r = read_text(text);
  ASSERT_TRUE(r.status.is_ok()) << format(r.status);
  ASSERT_EQ(r.soup.size(), 1u);
  EXPECT_EQ(r.soup[0].p[0][0], 1.5f);
  EXPECT_EQ(r.soup[0].p[0][1], -25.0f);
  EXPECT_EQ(r.soup[0].p[0][2], 1.25f);
  EXPECT_EQ(r.soup[0].p[1][0], 1.0f);
  EXPECT_EQ(r.soup[0].p[1][1], 0.2f);
  EXPECT_EQ(r.soup[0].p[1][2], 0.0f);
  EXPECT_EQ(r.soup[0].p[2][0], 3.0f);
  EXPECT_EQ(r.soup[0].p[2][1], 0.5f);
  EXPECT_EQ(r.soup[0].p[2][2], 4.0f);
}

TEST(StlReadTest, AsciiSignsThatAreNotNumbersAreRejected) {
  for (const char* bad : {"+-1", "-+1", "++1", "--1", "+", "-", "1e", "1e+", ".", "e5", "1-2"}) {
    SCOPED_TRACE(bad);
    ReadResult r =
        read_text(replace_once(kOneFacet, "vertex 1 0 0", std::string("vertex ") + bad + " 0 0"));
    EXPECT_EQ(r.status.code(), StatusCode::kParseError) << format(r.status);
    EXPECT_EQ(r.status.line(), 5u);
    EXPECT_EQ(r.status.column(), 10u);
  }
}

TEST(StlReadTest, AsciiCrlfLineEndings) {
  const std::vector<SoupTriangle> box = test_box();
  ReadResult r = read_text(ascii_stl(box, "crlf", "\r\n"));
  ASSERT_TRUE(r.status.is_ok()) << format(r.status);
  EXPECT_TRUE(same_soup(r.soup, box));
  EXPECT_STREQ(r.info.header, "crlf");  // no '\r' in the name
  // Line numbers still count '\n': an error on line 5 is reported as line 5.
  std::string text = ascii_stl(box, "crlf", "\r\n");
  text = replace_once(text, "outer loop\r\n      vertex -1.5", "outer loop\r\n      vertxe -1.5");
  r = read_text(text);
  EXPECT_EQ(r.status.code(), StatusCode::kParseError);
  EXPECT_EQ(r.status.line(), 4u);
  EXPECT_EQ(r.status.column(), 7u);
}

TEST(StlReadTest, AsciiEmptySolid) {
  ReadResult r = read_text("solid x\nendsolid x\n");
  ASSERT_TRUE(r.status.is_ok()) << format(r.status);
  EXPECT_EQ(r.info.format, StlFormat::kAscii);
  EXPECT_EQ(r.info.triangles, 0u);
  EXPECT_EQ(r.info.bytes, 19u);
  EXPECT_STREQ(r.info.header, "x");
  EXPECT_TRUE(r.soup.empty());

  // Nameless, no final newline.
  r = read_text("solid\nendsolid");
  ASSERT_TRUE(r.status.is_ok()) << format(r.status);
  EXPECT_STREQ(r.info.header, "");

  // And through read_stl_mesh: an empty mesh.
  Arena& arena = shared_arena();
  ArenaScope scope(arena);
  Mesh mesh;
  SPLINTCORE_EXPECT_OK(
      splintcore::test::mesh_from_bytes(arena, to_bytes("solid x\nendsolid x\n"), &mesh));
  EXPECT_EQ(mesh.vertices.size(), 0u);
  EXPECT_EQ(mesh.triangles.size(), 0u);
}

TEST(StlReadTest, AsciiGarbageAfterEndsolid) {
  ReadResult r = read_text("solid x\nendsolid x\n\n  junk\n");
  EXPECT_EQ(r.status.code(), StatusCode::kParseError);
  EXPECT_EQ(r.status.line(), 4u);
  EXPECT_EQ(r.status.column(), 3u);
  EXPECT_TRUE(message_has(r.status, "junk")) << format(r.status);
}

TEST(StlReadTest, ForcedFormat) {
  const std::vector<SoupTriangle> box = test_box();
  ReadParams p;
  p.options.format = StlFormat::kAscii;
  ReadResult r = read_text(ascii_stl(box), p);
  ASSERT_TRUE(r.status.is_ok()) << format(r.status);
  EXPECT_TRUE(same_soup(r.soup, box));
  p.options.format = StlFormat::kBinary;
  r = read_bytes(binary_stl(box, "solid forced"), p);
  ASSERT_TRUE(r.status.is_ok()) << format(r.status);
  EXPECT_TRUE(same_soup(r.soup, box));
  // ASCII bytes read as binary: a clean error.
  r = read_text(ascii_stl(box), p);
  EXPECT_FALSE(r.status.is_ok());
  EXPECT_NE(r.status.byte_offset(), kNoPosition);
}

// ---- chunked sources --------------------------------------------------------------------------

TEST(StlReadTest, ChunkedSourcesGiveTheSameTriangles) {
  const std::vector<SoupTriangle> torus = splintcore::shapes::torus(12, 8, 10, 3);
  const std::vector<std::vector<uint8_t>> files = {
      binary_stl(torus, "chunked"),
      binary_stl(torus, "solid chunked"),
      to_bytes(ascii_stl(torus, "chunked")),
      to_bytes("\r\n  " + ascii_stl(torus, "crlf", "\r\n")),
  };
  for (size_t f = 0; f < files.size(); ++f) {
    ReadResult reference = read_bytes(files[f]);
    ASSERT_TRUE(reference.status.is_ok()) << format(reference.status);
    ASSERT_TRUE(same_soup(reference.soup, torus));
    for (size_t chunk_bytes : {size_t{4096}, size_t{64} * 1024}) {
      for (size_t max_chunk :
           {size_t{1}, size_t{2}, size_t{3}, size_t{7}, size_t{50}, size_t{4096}}) {
        for (bool size_known : {true, false}) {
          SCOPED_TRACE("file " + std::to_string(f) + " chunk_bytes " + std::to_string(chunk_bytes) +
                       " max_chunk " + std::to_string(max_chunk) +
                       (size_known ? " sized" : " stream"));
          ReadParams p;
          p.max_chunk = max_chunk;
          p.size_known = size_known;
          p.options.chunk_bytes = chunk_bytes;
          ReadResult r = read_bytes(files[f], p);
          ASSERT_TRUE(r.status.is_ok()) << format(r.status);
          EXPECT_TRUE(same_soup(r.soup, reference.soup));
          EXPECT_EQ(r.info.format, reference.info.format);
          EXPECT_EQ(r.info.triangles, reference.info.triangles);
          EXPECT_EQ(r.info.bytes, files[f].size());
          EXPECT_STREQ(r.info.header, reference.info.header);
        }
      }
    }
  }
}

// ---- truncation at every byte offset ----------------------------------------------------------

void check_binary_prefixes(const std::vector<uint8_t>& full,
                           const std::vector<SoupTriangle>& soup) {
  for (size_t max_chunk : {size_t{0}, size_t{7}}) {
    for (bool size_known : {true, false}) {
      for (size_t n = 0; n <= full.size(); ++n) {
        SCOPED_TRACE("prefix " + std::to_string(n) + (size_known ? " sized" : " stream") +
                     " max_chunk " + std::to_string(max_chunk));
        std::vector<uint8_t> prefix(full.begin(), full.begin() + static_cast<std::ptrdiff_t>(n));
        ReadParams p;
        p.max_chunk = max_chunk;
        p.size_known = size_known;
        ReadResult r = read_bytes(prefix, p);
        if (n == full.size()) {
          ASSERT_TRUE(r.status.is_ok()) << format(r.status);
          EXPECT_TRUE(same_soup(r.soup, soup));
          continue;
        }
        const StatusCode code = r.status.code();
        ASSERT_TRUE(code == StatusCode::kTruncated || code == StatusCode::kParseError)
            << format(r.status);
        EXPECT_STREQ(r.status.file(), "test.stl");
        if (r.info.format == StlFormat::kAscii) {
          // A short prefix of a "solid..." header is all text: read as ASCII.
          EXPECT_NE(r.status.line(), kNoPosition) << format(r.status);
          continue;
        }
        EXPECT_EQ(code, StatusCode::kTruncated) << format(r.status);
        // The error points at the end of the input: where the missing bytes should be.
        EXPECT_EQ(r.status.byte_offset(), n) << format(r.status);
        if (!size_known && n >= 84) {
          EXPECT_EQ(r.status.index(), (n - 84) / 50) << format(r.status);
        }
      }
    }
  }
}

TEST(StlReadTest, BinaryTruncatedAtEveryByte) {
  const std::vector<SoupTriangle> box = test_box();
  check_binary_prefixes(binary_stl(box, "truncate me"), box);
}

TEST(StlReadTest, BinaryWithSolidHeaderTruncatedAtEveryByte) {
  const std::vector<SoupTriangle> box = test_box();
  check_binary_prefixes(binary_stl(box, "solid truncate me"), box);
}

void check_ascii_prefixes(const std::string& full, size_t triangles) {
  const size_t endsolid = full.rfind("endsolid");
  ASSERT_NE(endsolid, std::string::npos);
  for (size_t max_chunk : {size_t{0}, size_t{3}}) {
    for (size_t n = 0; n <= full.size(); ++n) {
      SCOPED_TRACE("prefix " + std::to_string(n) + " max_chunk " + std::to_string(max_chunk));
      const std::string prefix = full.substr(0, n);
      ReadParams sized;
      sized.max_chunk = max_chunk;
      ReadParams stream = sized;
      stream.size_known = false;
      ReadResult r = read_text(prefix, sized);
      ReadResult r_stream = read_text(prefix, stream);
      // ASCII reading does not depend on knowing the size.
      EXPECT_EQ(r.status.code(), r_stream.status.code());
      EXPECT_EQ(r.status.line(), r_stream.status.line());
      EXPECT_EQ(r.status.column(), r_stream.status.column());
      if (n >= endsolid + 8) {
        // "endsolid" complete: a valid file (the name after it is optional).
        ASSERT_TRUE(r.status.is_ok()) << format(r.status);
        EXPECT_EQ(r.soup.size(), triangles);
        continue;
      }
      const StatusCode code = r.status.code();
      ASSERT_TRUE(code == StatusCode::kTruncated || code == StatusCode::kParseError)
          << format(r.status);
      if (r.info.format != StlFormat::kAscii) {
        // Fewer than 5 bytes: too short to be "solid", so read as binary.
        EXPECT_LT(n, 5u + full.find('s'));
        EXPECT_EQ(code, StatusCode::kTruncated);
        EXPECT_EQ(r.status.byte_offset(), n);
        continue;
      }
      // Ends at white space: everything read was valid, so the input is merely short.
      const char last = n > 0 ? prefix[n - 1] : ' ';
      if (last == ' ' || last == '\n' || last == '\r') {
        EXPECT_EQ(code, StatusCode::kTruncated) << format(r.status);
      }
      const uint64_t lines =
          1 + static_cast<uint64_t>(std::count(prefix.begin(), prefix.end(), '\n'));
      ASSERT_NE(r.status.line(), kNoPosition) << format(r.status);
      EXPECT_GE(r.status.line(), 1u);
      EXPECT_LE(r.status.line(), lines) << format(r.status);
      ASSERT_NE(r.status.column(), kNoPosition) << format(r.status);
      EXPECT_GE(r.status.column(), 1u);
      if (code == StatusCode::kTruncated) {
        // The end of the input is where the next token should have been.
        const size_t line_start =
            prefix.rfind('\n') == std::string::npos ? 0 : prefix.rfind('\n') + 1;
        EXPECT_EQ(r.status.line(), lines) << format(r.status);
        EXPECT_EQ(r.status.column(), n - line_start + 1) << format(r.status);
      }
    }
  }
}

TEST(StlReadTest, AsciiTruncatedAtEveryByte) {
  const std::vector<SoupTriangle> box = test_box();
  std::vector<SoupTriangle> three(box.begin(), box.begin() + 3);
  check_ascii_prefixes(ascii_stl(three, "cut"), 3);
  check_ascii_prefixes(" " + ascii_stl(three, "crlf", "\r\n"), 3);
}

// ---- lying binary headers ---------------------------------------------------------------------

std::vector<uint8_t> box_with_count(uint32_t count) {
  std::vector<uint8_t> bytes = binary_stl(test_box());
  splintcore::test::put_u32(bytes, 80, count);
  return bytes;
}

TEST(StlReadTest, BinaryCountLargerThanData) {
  ReadResult r = read_bytes(box_with_count(13));
  EXPECT_EQ(r.status.code(), StatusCode::kTruncated) << format(r.status);
  EXPECT_EQ(r.status.byte_offset(), 684u);
  EXPECT_TRUE(message_has(r.status, "13 triangles")) << format(r.status);
  EXPECT_TRUE(r.soup.empty());  // refused before reading a triangle

  ReadParams stream;
  stream.size_known = false;
  r = read_bytes(box_with_count(13), stream);
  EXPECT_EQ(r.status.code(), StatusCode::kTruncated) << format(r.status);
  EXPECT_EQ(r.status.byte_offset(), 684u);
  EXPECT_EQ(r.status.index(), 12u);
}

TEST(StlReadTest, BinaryCountSmallerThanData) {
  ReadResult r = read_bytes(box_with_count(11));
  EXPECT_EQ(r.status.code(), StatusCode::kParseError) << format(r.status);
  EXPECT_EQ(r.status.byte_offset(), 634u);  // where the extra data starts
  EXPECT_TRUE(message_has(r.status, "50 bytes after the last triangle")) << format(r.status);

  ReadParams stream;
  stream.size_known = false;
  r = read_bytes(box_with_count(11), stream);
  EXPECT_EQ(r.status.code(), StatusCode::kParseError) << format(r.status);
  EXPECT_EQ(r.status.byte_offset(), 634u);

  // One stray byte after the data.
  std::vector<uint8_t> bytes = binary_stl(test_box());
  bytes.push_back(0);
  r = read_bytes(bytes);
  EXPECT_EQ(r.status.code(), StatusCode::kParseError) << format(r.status);
  r = read_bytes(bytes, stream);
  EXPECT_EQ(r.status.code(), StatusCode::kParseError) << format(r.status);
  EXPECT_EQ(r.status.byte_offset(), 684u);
}

TEST(StlReadTest, BinaryHugeCountFailsFastAndClearly) {
  // 0xFFFFFFFF triangles claimed, one present; a 1 MiB arena. Must not try to reserve 154 GB.
  std::vector<unsigned char> memory(size_t{1} << 20);
  std::vector<uint8_t> bytes = binary_stl({test_box()[0]});
  splintcore::test::put_u32(bytes, 80, 0xFFFFFFFFu);
  for (int mode = 0; mode < 3; ++mode) {
    SCOPED_TRACE(mode);
    Arena arena(memory.data(), memory.size());
    Context ctx(&arena);
    MemorySource ms{bytes.data(), bytes.size(), 0, 0};
    ByteSource source = splintcore::memory_source(&ms, "huge.stl");
    StlReadOptions options;
    if (mode >= 1) source.size = kUnknownSize;
    if (mode == 2) options.max_triangles = ~uint64_t{0};
    ArenaArray<SoupTriangle> soup(&arena);
    StlInfo info;
    Status s = splintcore::read_stl(ctx, source, options, &soup, &info);
    EXPECT_NE(s.code(), StatusCode::kArenaExhausted) << format(s);
    EXPECT_TRUE(message_has(s, "4294967295")) << format(s);
    if (mode == 0) {
      EXPECT_EQ(s.code(), StatusCode::kTruncated) << format(s);
      EXPECT_EQ(s.byte_offset(), bytes.size());
      EXPECT_TRUE(soup.empty());
    } else if (mode == 1) {
      EXPECT_EQ(s.code(), StatusCode::kLimitExceeded) << format(s);
    } else {
      EXPECT_EQ(s.code(), StatusCode::kTruncated) << format(s);
      EXPECT_EQ(s.byte_offset(), bytes.size());
      EXPECT_EQ(s.index(), 1u);
    }
    EXPECT_LT(arena.high_water(), size_t{128} * 1024);  // the read buffer and one triangle
  }
}

TEST(StlReadTest, BinaryCountOverLimit) {
  ReadParams p;
  p.options.max_triangles = 11;
  ReadResult r = read_bytes(binary_stl(test_box()), p);
  EXPECT_EQ(r.status.code(), StatusCode::kLimitExceeded) << format(r.status);
  EXPECT_TRUE(message_has(r.status, "12")) << format(r.status);
  EXPECT_TRUE(message_has(r.status, "11")) << format(r.status);
  p.options.max_triangles = 12;
  r = read_bytes(binary_stl(test_box()), p);
  EXPECT_TRUE(r.status.is_ok()) << format(r.status);
}

TEST(StlReadTest, AsciiCountOverLimit) {
  ReadParams p;
  p.options.max_triangles = 3;
  ReadResult r = read_text(ascii_stl(test_box()), p);
  EXPECT_EQ(r.status.code(), StatusCode::kLimitExceeded) << format(r.status);
  EXPECT_EQ(r.status.line(), 2u + 7u * 3u);  // the fourth facet
  p.options.max_triangles = 12;
  r = read_text(ascii_stl(test_box()), p);
  EXPECT_TRUE(r.status.is_ok()) << format(r.status);
}

// ---- non-finite and out-of-range coordinates --------------------------------------------------

TEST(StlReadTest, BinaryNonFiniteCoordinates) {
  const float kNan = std::numeric_limits<float>::quiet_NaN();
  const float kInf = std::numeric_limits<float>::infinity();
  struct Case {
    size_t triangle;
    int corner;
    int axis;
    float value;
  };
  const Case cases[] = {{5, 1, 1, kNan}, {0, 2, 0, kInf}, {11, 0, 2, -kInf}, {3, 2, 2, -kNan}};
  for (const Case& c : cases) {
    SCOPED_TRACE(c.triangle);
    std::vector<SoupTriangle> box = test_box();
    box[c.triangle].p[c.corner][c.axis] = c.value;
    for (bool size_known : {true, false}) {
      ReadParams p;
      p.size_known = size_known;
      ReadResult r = read_bytes(binary_stl(box), p);
      EXPECT_EQ(r.status.code(), StatusCode::kNonFinite) << format(r.status);
      EXPECT_EQ(r.status.index(), c.triangle);
      EXPECT_EQ(r.status.byte_offset(),
                84u + 50u * c.triangle + 12u + 12u * static_cast<unsigned>(c.corner));
      EXPECT_TRUE(message_has(r.status, "triangle " + std::to_string(c.triangle)))
          << format(r.status);
    }
  }
  // A NaN in the facet normal is ignored: normals are not kept.
  std::vector<uint8_t> bytes = binary_stl(test_box());
  splintcore::test::put_f32(bytes, 84 + 50 * 4, kNan);
  ReadResult r = read_bytes(bytes);
  EXPECT_TRUE(r.status.is_ok()) << format(r.status);
}

TEST(StlReadTest, AsciiNonFiniteText) {
  for (const char* bad : {"nan", "NaN", "-nan", "inf", "-inf", "+inf", "INF", "infinity", "+NAN"}) {
    SCOPED_TRACE(bad);
    ReadResult r =
        read_text(replace_once(kOneFacet, "vertex 0 1 0", std::string("vertex 0 ") + bad + " 0"));
    EXPECT_EQ(r.status.code(), StatusCode::kNonFinite) << format(r.status);
    EXPECT_EQ(r.status.line(), 6u);
    EXPECT_EQ(r.status.column(), 12u);
    // In the normal too.
    r = read_text(replace_once(kOneFacet, "normal 0 0 1", std::string("normal ") + bad + " 0 1"));
    EXPECT_EQ(r.status.code(), StatusCode::kNonFinite) << format(r.status);
    EXPECT_EQ(r.status.line(), 2u);
    EXPECT_EQ(r.status.column(), 14u);
  }
}

TEST(StlReadTest, CoordinatesBeyondTheLimit) {
  // Binary: the default limit of 1e6 mm.
  std::vector<SoupTriangle> box = test_box();
  box[7].p[2][1] = -2.0e6f;
  ReadResult r = read_bytes(binary_stl(box));
  EXPECT_EQ(r.status.code(), StatusCode::kLimitExceeded) << format(r.status);
  EXPECT_EQ(r.status.index(), 7u);
  EXPECT_EQ(r.status.byte_offset(), 84u + 50u * 7u + 12u + 24u);
  EXPECT_TRUE(message_has(r.status, "wrong units")) << format(r.status);

  // Exactly at the limit is accepted; a caller-set limit is honoured.
  box = test_box();
  box[0].p[0][0] = 1.0e6f;
  r = read_bytes(binary_stl(box));
  EXPECT_TRUE(r.status.is_ok()) << format(r.status);
  ReadParams p;
  p.options.max_abs_coordinate = 10.0;  // the box reaches 10.5
  r = read_bytes(binary_stl(test_box()), p);
  EXPECT_EQ(r.status.code(), StatusCode::kLimitExceeded) << format(r.status);

  // ASCII: reported on the vertex line.
  r = read_text(replace_once(kOneFacet, "vertex 1 0 0", "vertex 1 0 1e7"));
  EXPECT_EQ(r.status.code(), StatusCode::kLimitExceeded) << format(r.status);
  EXPECT_EQ(r.status.line(), 5u);
  EXPECT_EQ(r.status.index(), 0u);
  r = read_text(ascii_stl(test_box()), p);
  EXPECT_EQ(r.status.code(), StatusCode::kLimitExceeded) << format(r.status);
  EXPECT_EQ(r.status.line(), 4u + 7u * 2u + 0u);  // triangle 2 corner 0 is the first with z = 10.5

  // Beyond float32 range in text: rejected with its line.
  r = read_text(replace_once(kOneFacet, "vertex 1 0 0", "vertex 1 0 1e39"));
  EXPECT_FALSE(r.status.is_ok());
  EXPECT_EQ(r.status.line(), 5u);
}

// ---- ASCII syntax errors: exact line and column -----------------------------------------------

struct SyntaxCase {
  const char* what;
  std::string text;
  StatusCode code;
  uint64_t line;
  uint64_t column;
  const char* message;
};

TEST(StlReadTest, AsciiSyntaxErrorsAreLocated) {
  const std::string good = kOneFacet;
  ASSERT_TRUE(read_text(good).status.is_ok());
  const std::string long_token(300, '1');
  const SyntaxCase cases[] = {
      {"misspelled loop", replace_once(good, " outer loop", " outer lop"), StatusCode::kParseError,
       3, 8, "expected 'loop', found 'lop'"},
      {"misspelled vertex", replace_once(good, "  vertex 1 0 0", "  vertx 1 0 0"),
       StatusCode::kParseError, 5, 3, "expected 'vertex'"},
      {"misspelled facet", replace_once(good, "facet normal", "facte normal"),
       StatusCode::kParseError, 2, 1, "found 'facte'"},
      {"missing endloop", replace_once(good, " endloop\n", ""), StatusCode::kParseError, 7, 1,
       "expected 'endloop', found 'endfacet'"},
      {"missing endfacet", replace_once(good, "endfacet\n", ""), StatusCode::kParseError, 8, 1,
       "expected 'endfacet', found 'endsolid'"},
      {"1.2.3", replace_once(good, "vertex 1 0 0", "vertex 1.2.3 0 0"), StatusCode::kParseError, 5,
       10, "1.2.3"},
      {"two vertices only", replace_once(good, "  vertex 0 1 0\n", ""), StatusCode::kParseError, 6,
       2, "expected 'vertex', found 'endloop'"},
      {"four numbers", replace_once(good, "vertex 0 1 0", "vertex 0 1 0 0"),
       StatusCode::kParseError, 6, 16, "expected 'endloop'"},
      {"long token", replace_once(good, "vertex 1 0 0", "vertex 1 " + long_token + " 0"),
       StatusCode::kParseError, 5, 12, "longer than 256"},
      {"missing endsolid", replace_once(good, "endsolid t\n", ""), StatusCode::kTruncated, 9, 1,
       "found the end of the input"},
      {"missing endsolid, no newline", replace_once(good, "endfacet\nendsolid t\n", "endfacet"),
       StatusCode::kTruncated, 8, 9, "found the end of the input"},
      {"ends inside a vertex", good.substr(0, good.find("  vertex 0 1 0") + 12),
       StatusCode::kTruncated, 6, 13, "expected a number"},
  };
  for (const SyntaxCase& c : cases) {
    SCOPED_TRACE(c.what);
    ReadResult r = read_text(c.text);
    EXPECT_EQ(r.status.code(), c.code) << format(r.status);
    EXPECT_EQ(r.status.line(), c.line) << format(r.status);
    EXPECT_EQ(r.status.column(), c.column) << format(r.status);
    EXPECT_TRUE(message_has(r.status, c.message)) << format(r.status);
    EXPECT_STREQ(r.status.file(), "test.stl");
    // The formatted message leads with FILE:LINE:COL.
    EXPECT_EQ(format(r.status).rfind(
                  "test.stl:" + std::to_string(c.line) + ":" + std::to_string(c.column) + ":", 0),
              0u)
        << format(r.status);
  }
}

TEST(StlReadTest, AsciiTokenOf256CharactersIsAccepted) {
  const std::string token = "1." + std::string(254, '0');  // 256 characters, value 1
  ReadResult r = read_text(replace_once(kOneFacet, "vertex 1 0 0", "vertex " + token + " 0 0"));
  ASSERT_TRUE(r.status.is_ok()) << format(r.status);
  EXPECT_EQ(r.soup[0].p[1][0], 1.0f);
  r = read_text(replace_once(kOneFacet, "vertex 1 0 0", "vertex " + token + "0 0 0"));
  EXPECT_EQ(r.status.code(), StatusCode::kParseError) << format(r.status);
  EXPECT_EQ(r.status.column(), 10u);
}

TEST(StlReadTest, AsciiNonTextByte) {
  // In a small file the byte makes auto-detection say binary, so force ASCII here...
  ReadParams forced;
  forced.options.format = StlFormat::kAscii;
  for (char bad : {'\x01', '\x7f', '\xc3', '\0'}) {
    SCOPED_TRACE(static_cast<int>(static_cast<unsigned char>(bad)));
    std::string text =
        replace_once(kOneFacet, "vertex 0 1 0", std::string("vertex 0 1") + bad + " 0");
    ReadResult r = read_text(text, forced);
    EXPECT_EQ(r.status.code(), StatusCode::kParseError) << format(r.status);
    EXPECT_EQ(r.status.line(), 6u);
    EXPECT_EQ(r.status.column(), 13u);
    EXPECT_EQ(r.status.byte_offset(), text.find(bad));
    EXPECT_TRUE(message_has(r.status, "non-text byte")) << format(r.status);
  }
  // ... and past the 1024-byte detection window, auto-detection reads ASCII and the same error
  // is reported.
  const std::vector<SoupTriangle> box = test_box();
  std::string text = ascii_stl(box, "late");
  ASSERT_GT(text.size(), 1200u);
  size_t at = text.find("vertex", 1100);
  ASSERT_NE(at, std::string::npos);
  text.insert(at + 6, 1, '\x02');  // "vertex\x02"
  uint64_t line = 1 + static_cast<uint64_t>(std::count(
                          text.begin(), text.begin() + static_cast<std::ptrdiff_t>(at), '\n'));
  ReadResult r = read_text(text);
  EXPECT_EQ(r.info.format, StlFormat::kAscii);
  EXPECT_EQ(r.status.code(), StatusCode::kParseError) << format(r.status);
  EXPECT_EQ(r.status.line(), line);
  EXPECT_EQ(r.status.column(), 13u);
  EXPECT_EQ(r.status.byte_offset(), at + 6);
}

// ---- welding of signed zeros ------------------------------------------------------------------

TEST(StlReadTest, SignedZerosWeldToOneVertex) {
  const float lo[3] = {0.0f, 0.0f, 0.0f};
  const float hi[3] = {1.0f, 2.0f, 3.0f};
  std::vector<SoupTriangle> box = splintcore::shapes::box(lo, hi);
  size_t negated = 0;
  for (size_t t = 1; t < box.size(); t += 2) {
    for (auto& corner : box[t].p) {
      for (float& c : corner) {
        if (c == 0.0f) {
          c = -0.0f;
          ++negated;
        }
      }
    }
  }
  ASSERT_GT(negated, 0u);
  const std::vector<std::vector<uint8_t>> files = {binary_stl(box), to_bytes(ascii_stl(box))};
  for (const auto& bytes : files) {
    Arena& arena = shared_arena();
    ArenaScope scope(arena);
    Mesh mesh;
    Status s = splintcore::test::mesh_from_bytes(arena, bytes, &mesh);
    ASSERT_TRUE(s.is_ok()) << format(s);
    EXPECT_EQ(mesh.vertices.size(), 8u);
    for (const Vec3& v : mesh.vertices) {
      EXPECT_FALSE(std::signbit(v.x) || std::signbit(v.y) || std::signbit(v.z));
    }
  }
  // The soup itself keeps the sign (welding is what merges them).
  ReadResult r = read_bytes(binary_stl(box));
  ASSERT_TRUE(r.status.is_ok());
  EXPECT_TRUE(std::signbit(r.soup[1].p[0][0]) || std::signbit(r.soup[1].p[0][1]) ||
              std::signbit(r.soup[1].p[0][2]) || std::signbit(r.soup[1].p[1][0]) ||
              std::signbit(r.soup[1].p[2][2]));
}

// ---- failing sources and bad arguments --------------------------------------------------------

struct FlakySource {
  MemorySource inner;
  uint64_t fail_at = 0;   // read() fails once this many bytes have been delivered
  bool overfill = false;  // return more than asked
};

int64_t flaky_read(void* user, uint8_t* buffer, size_t capacity) {
  FlakySource* f = static_cast<FlakySource*>(user);
  if (f->overfill) return static_cast<int64_t>(capacity) + 1;
  if (f->inner.position >= f->fail_at) return -1;
  uint64_t left = f->fail_at - f->inner.position;
  size_t take = capacity < left ? capacity : static_cast<size_t>(left);
  ByteSource src = splintcore::memory_source(&f->inner);
  return src.read(src.user, buffer, take);
}

Status read_flaky(FlakySource* f, bool size_known) {
  Arena& arena = shared_arena();
  ArenaScope scope(arena);
  Context ctx(&arena);
  ByteSource source;
  source.read = flaky_read;
  source.user = f;
  source.size = size_known ? f->inner.size : kUnknownSize;
  source.name = "flaky.stl";
  Mesh mesh;
  return splintcore::read_stl_mesh(ctx, source, StlReadOptions{}, &mesh, nullptr);
}

TEST(StlReadTest, FailingSourceGivesIoError) {
  const std::vector<uint8_t> binary = binary_stl(splintcore::shapes::torus(12, 8, 10, 3));
  const std::string ascii = ascii_stl(splintcore::shapes::torus(12, 8, 10, 3));
  ASSERT_GT(ascii.size(), 3000u);
  for (uint64_t fail_at : {uint64_t{0}, uint64_t{200}, uint64_t{3000}}) {
    for (bool size_known : {true, false}) {
      SCOPED_TRACE(fail_at);
      FlakySource f{{binary.data(), binary.size(), 0, 100}, fail_at, false};
      Status s = read_flaky(&f, size_known);
      EXPECT_EQ(s.code(), StatusCode::kIoError) << format(s);
      EXPECT_EQ(s.byte_offset(), fail_at) << format(s);
      EXPECT_STREQ(s.file(), "flaky.stl");
      FlakySource g{
          {reinterpret_cast<const uint8_t*>(ascii.data()), ascii.size(), 0, 100}, fail_at, false};
      s = read_flaky(&g, size_known);
      EXPECT_EQ(s.code(), StatusCode::kIoError) << format(s);
    }
  }
  FlakySource over{{binary.data(), binary.size(), 0, 0}, binary.size(), true};
  Status s = read_flaky(&over, true);
  EXPECT_EQ(s.code(), StatusCode::kIoError) << format(s);
}

TEST(StlReadTest, BadArguments) {
  Arena& arena = shared_arena();
  ArenaScope scope(arena);
  Context ctx(&arena);
  ByteSource no_read;
  ArenaArray<SoupTriangle> soup(&arena);
  Status s = splintcore::read_stl(ctx, no_read, StlReadOptions{}, &soup, nullptr);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);

  // read_stl_mesh wants an empty mesh.
  const std::vector<uint8_t> bytes = binary_stl(test_box());
  Mesh mesh;
  SPLINTCORE_ASSERT_OK(splintcore::test::mesh_from_bytes(arena, bytes, &mesh));
  MemorySource ms{bytes.data(), bytes.size(), 0, 0};
  s = splintcore::read_stl_mesh(ctx, splintcore::memory_source(&ms), StlReadOptions{}, &mesh,
                                nullptr);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(mesh.triangles.size(), 12u);
}

TEST(StlReadTest, FailedReadLeavesTheArenaWhereItWas) {
  Arena& arena = shared_arena();
  ArenaScope scope(arena);
  const size_t before = arena.used();
  Mesh mesh;
  std::vector<uint8_t> bytes = box_with_count(13);
  Status s = splintcore::test::mesh_from_bytes(arena, bytes, &mesh);
  EXPECT_EQ(s.code(), StatusCode::kTruncated);
  EXPECT_EQ(arena.used(), before);
  // A successful read keeps only the mesh (the soup and the read buffer are reclaimed).
  bytes = binary_stl(test_box());
  Mesh ok_mesh;
  SPLINTCORE_ASSERT_OK(splintcore::test::mesh_from_bytes(arena, bytes, &ok_mesh));
  EXPECT_LE(arena.used() - before, 12 * sizeof(splintcore::Triangle) + 8 * sizeof(Vec3) + 64);
}

// The limit is inclusive on both readers (the streamed weld's bit test and the soup reader's
// comparison): with a limit a float holds exactly, a corner at +-the limit is read, the next
// float beyond is refused naming its triangle and that coordinate (not one of the corner's
// others, set exactly at +limit and -limit); a limit of 0 reads a file at the origin (both
// zeros) and refuses the least float above 0.
TEST(StlRead, ACoordinateExactlyAtTheLimitIsRead) {
  const std::vector<SoupTriangle> torus = splintcore::shapes::torus(17, 13, 30.0, 8.0);
  const SoupTriangle origin{{{0.0f, -0.0f, 0.0f}, {0.0f, 0.0f, -0.0f}, {-0.0f, 0.0f, 0.0f}}};
  struct Case {
    double limit;
    float value;
    bool read;
  };
  const float at = 40.25f, beyond = std::nextafter(at, 100.0f);
  const float least = std::numeric_limits<float>::denorm_min();
  const Case cases[] = {{40.25, at, true},       {40.25, -at, true},  {40.25, beyond, false},
                        {40.25, -beyond, false}, {0.0, 0.0f, true},   {0.0, -0.0f, true},
                        {0.0, least, false},     {0.0, -least, false}};
  for (const Case& c : cases) {
    std::vector<SoupTriangle> soup =
        c.limit > 0 ? torus : std::vector<SoupTriangle>{origin, origin};
    soup[soup.size() / 2].p[1][2] = c.value;
    if (!c.read) {
      soup[soup.size() / 2].p[1][0] = static_cast<float>(c.limit);
      soup[soup.size() / 2].p[1][1] = -static_cast<float>(c.limit);
    }
    char named[64] = "has coordinate ";
    const size_t n = std::strlen(named);
    *std::to_chars(named + n, named + sizeof(named) - 4, static_cast<double>(c.value)).ptr = '\0';
    std::strcat(named, " mm");
    const std::vector<uint8_t> file = binary_stl(soup, "limit");
    for (int sized = 0; sized < 2; ++sized) {
      SCOPED_TRACE(std::to_string(c.limit) + " " + std::to_string(c.value) + " sized " +
                   std::to_string(sized));
      splintcore::test::TestArena t(size_t{16} << 20);
      StlReadOptions options;
      options.max_abs_coordinate = c.limit;
      MemorySource ms{file.data(), file.size(), 0, 0};
      ByteSource source = splintcore::memory_source(&ms, "t.stl");
      source.size = sized == 0 ? kUnknownSize : file.size();
      Mesh mesh(&t.arena);
      const Status st =
          splintcore::read_stl_mesh(Context(&t.arena), source, options, &mesh, nullptr);
      if (c.read) {
        EXPECT_TRUE(st.is_ok()) << format(st);
        EXPECT_EQ(mesh.triangles.size(), soup.size());
      } else {
        EXPECT_EQ(st.code(), StatusCode::kLimitExceeded) << format(st);
        EXPECT_EQ(st.index(), soup.size() / 2);
        EXPECT_NE(format(st).find("beyond the limit"), std::string::npos) << format(st);
        EXPECT_NE(format(st).find(named), std::string::npos) << format(st) << " / " << named;
      }
    }
  }
}

// A binary STL from a source that knows its size is welded straight from the read buffer; from
// one that does not, it is read whole and welded. Both must give the same mesh bytes, or the
// same error (code, text, byte, triangle), whatever the chunk size: coordinates at and just
// past a limit that no float holds exactly, NaN, infinity, -0, a source that delivers fewer or
// more bytes than its size says.
TEST(StlRead, StreamedWeldAgreesWithSoupThenWeld) {
  std::vector<SoupTriangle> soup = splintcore::shapes::torus(17, 13, 30.0, 8.0);
  // Not a float, and the nearest float lies above it: the float below passes, the next fails.
  const double limit = 40.2;
  ASSERT_GT(static_cast<double>(static_cast<float>(limit)), limit);
  const float below = std::nextafter(static_cast<float>(limit), 0.0f);
  const float above = std::nextafter(below, 100.0f);
  std::vector<std::vector<uint8_t>> files;
  files.push_back(binary_stl(soup, "torus"));
  for (float bad : {below, -below, above, -above, std::numeric_limits<float>::quiet_NaN(),
                    std::numeric_limits<float>::infinity(), -0.0f}) {
    std::vector<SoupTriangle> s = soup;
    s[soup.size() / 2].p[1][2] = bad;
    s[0].p[2][0] = -0.0f;
    files.push_back(binary_stl(s, "edited"));
  }
  std::vector<uint8_t> truncated = files[0];
  truncated.resize(truncated.size() - 20);
  std::vector<uint8_t> extra = files[0];
  extra.push_back(0);
  files.push_back(truncated);
  files.push_back(extra);
  for (size_t f = 0; f < files.size(); ++f) {
    for (size_t chunk : {size_t{4096}, size_t{5000}, size_t{1} << 16}) {
      std::string result[2];
      for (int sized = 0; sized < 2; ++sized) {
        splintcore::test::TestArena t(size_t{16} << 20);
        StlReadOptions options;
        options.chunk_bytes = chunk;
        options.max_abs_coordinate = limit;
        MemorySource ms{files[f].data(), files[f].size(), 0, 0};
        ByteSource source = splintcore::memory_source(&ms, "t.stl");
        // The short and the long file claim the right size (a source that then delivers less
        // or more): the streamed reader must notice as the soup reader does.
        source.size = sized == 0 ? kUnknownSize : files[0].size();
        if (sized == 1 && f + 2 < files.size()) source.size = files[f].size();
        Mesh mesh(&t.arena);
        StlInfo info;
        const size_t before = t.arena.used();
        const Status st =
            splintcore::read_stl_mesh(Context(&t.arena), source, options, &mesh, &info);
        if (!st.is_ok()) {
          EXPECT_EQ(t.arena.used(), before);
          EXPECT_TRUE(mesh.vertices.empty() && mesh.triangles.empty());
          result[sized] = format(st) + " byte " + std::to_string(st.byte_offset()) + " index " +
                          std::to_string(st.index());
          continue;
        }
        result[sized].assign(reinterpret_cast<const char*>(mesh.vertices.data()),
                             mesh.vertices.size() * sizeof(Vec3));
        result[sized].append(reinterpret_cast<const char*>(mesh.triangles.data()),
                             mesh.triangles.size() * sizeof(splintcore::Triangle));
        result[sized] += std::string(info.header) + std::to_string(info.triangles) + " " +
                         std::to_string(info.bytes);
      }
      EXPECT_EQ(result[0], result[1]) << "file " << f << " chunk " << chunk;
      EXPECT_FALSE(result[1].empty());
    }
  }
}

}  // namespace
