// Branches of the STL reader (src/io/stl_read.cpp) the other tests do not reach (issue 9:
// >= 95% branch coverage of the parsers, measured by tools/coverage.sh): sources that do not
// know their size or name, every kind of white space, upper-case keywords, odd solid names,
// every spelling of a non-finite number, long bad tokens, tiny chunk sizes, a non-empty output.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "splintcore/io.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

const char* kTetra =
    "solid t\n"
    " facet normal 0 0 -1\n  outer loop\n   vertex 0 0 0\n   vertex 0 1 0\n   vertex 1 0 0\n"
    "  endloop\n endfacet\n"
    " facet normal 0 -1 0\n  outer loop\n   vertex 0 0 0\n   vertex 1 0 0\n   vertex 0 0 1\n"
    "  endloop\n endfacet\n"
    " facet normal -1 0 0\n  outer loop\n   vertex 0 0 0\n   vertex 0 0 1\n   vertex 0 1 0\n"
    "  endloop\n endfacet\n"
    " facet normal 1 1 1\n  outer loop\n   vertex 1 0 0\n   vertex 0 1 0\n   vertex 0 0 1\n"
    "  endloop\n endfacet\n"
    "endsolid t\n";

struct Read {
  Status status;
  std::vector<SoupTriangle> soup;
  StlInfo info;
};

// Reads `bytes`; `known_size` false hides the size from the reader; `name` may be null.
Read read(const std::string& bytes, bool known_size = true, const char* name = "t.stl",
          StlReadOptions options = StlReadOptions{}, size_t arena_bytes = size_t{1} << 20) {
  test::TestArena t(arena_bytes);
  MemorySource ms{reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size(), 0, 7};
  ByteSource source = memory_source(&ms, name);
  source.name = name;
  if (!known_size) source.size = kUnknownSize;
  ArenaArray<SoupTriangle> out(&t.arena);
  Read r;
  r.status = read_stl(Context(&t.arena), source, options, &out, &r.info);
  r.soup.assign(out.begin(), out.end());
  return r;
}

std::string replace_all(std::string s, const std::string& from, const std::string& to) {
  for (size_t at = s.find(from); at != std::string::npos; at = s.find(from, at + to.size())) {
    s.replace(at, from.size(), to);
  }
  return s;
}

TEST(StlCoverage, AsciiWhiteSpaceCaseAndNames) {
  // Form feeds, vertical tabs, tabs and CRs between tokens; upper-case keywords.
  std::string odd = replace_all(kTetra, "\n   vertex", "\f\v\tVERTEX");
  odd = replace_all(odd, "facet", "FaCeT");
  odd = replace_all(odd, "\n", "\r\n");
  // (Form feeds and control bytes make auto-detection say binary: the format is forced.)
  StlReadOptions ascii;
  ascii.format = StlFormat::kAscii;
  Read r = read(odd, true, "t.stl", ascii);
  SPLINTCORE_ASSERT_OK(r.status);
  EXPECT_EQ(r.soup.size(), 4u);
  // The solid name: leading blanks dropped, control and non-ASCII bytes dropped, cut at 80.
  std::string named = kTetra;
  named.replace(0, 7, "solid \t  my\x01na\xffme" + std::string(100, 'x') + "\n");
  r = read(named, true, "t.stl", ascii);
  SPLINTCORE_ASSERT_OK(r.status);
  EXPECT_EQ(std::string(r.info.header).substr(0, 6), "myname");
  EXPECT_EQ(std::string(r.info.header).size(), 80u);
  // "solid" alone, no name.
  std::string bare = kTetra;
  bare.replace(0, 7, "solid\n");
  r = read(bare);
  SPLINTCORE_ASSERT_OK(r.status);
  EXPECT_STREQ(r.info.header, "");
}

TEST(StlCoverage, AsciiNonFiniteSpellings) {
  for (const char* word : {"nan", "NaN", "-nan", "-NAN", "inf", "-inf", "Inf", "-Infinity",
                           "INF", "-Inf"}) {
    SCOPED_TRACE(word);
    const std::string text = replace_all(kTetra, "vertex 0 1 0", std::string("vertex 0 ") + word + " 0");
    Read r = read(text);
    EXPECT_EQ(r.status.code(), StatusCode::kNonFinite) << test::format(r.status);
  }
  for (const char* word : {"ab", "-x", "x1", "1x", "-", "--1", "1e", "+-1", "0x10"}) {
    SCOPED_TRACE(word);
    const std::string text = replace_all(kTetra, "vertex 0 1 0", std::string("vertex 0 ") + word + " 0");
    Read r = read(text);
    EXPECT_EQ(r.status.code(), StatusCode::kParseError) << test::format(r.status);
  }
  // A leading '+' is taken.
  Read r = read(replace_all(kTetra, "vertex 0 1 0", "vertex +0 +1 +0"));
  SPLINTCORE_EXPECT_OK(r.status);
}

TEST(StlCoverage, LongUnexpectedTokensAreCut) {
  const std::string text = replace_all(kTetra, "outer loop", std::string(300, 'q'));
  Read r = read(text);
  EXPECT_EQ(r.status.code(), StatusCode::kParseError);
  const std::string m = r.status.message();
  EXPECT_EQ(m.find(std::string(41, 'q')), std::string::npos) << m;  // at most 40 shown
  const std::string long_word = replace_all(kTetra, "outer loop", "outer " + std::string(200, 'l'));
  r = read(long_word);
  EXPECT_EQ(r.status.code(), StatusCode::kParseError);
}

TEST(StlCoverage, SourcesWithoutSizeOrName) {
  const std::vector<uint8_t> bin = test::binary_stl(
      {SoupTriangle{{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}}, SoupTriangle{{{0, 0, 0}, {0, 1, 0}, {0, 0, 1}}}});
  const std::string bytes(bin.begin(), bin.end());
  // Size unknown: nothing is reserved, the triangles grow as they arrive.
  Read r = read(bytes, false, nullptr);
  SPLINTCORE_ASSERT_OK(r.status);
  EXPECT_EQ(r.soup.size(), 2u);
  // ... and the arena runs out while they grow.
  StlReadOptions one_chunk;
  one_chunk.chunk_bytes = 4096;
  r = read(bytes, false, nullptr, one_chunk, 4096 + 16);
  EXPECT_EQ(r.status.code(), StatusCode::kArenaExhausted) << test::format(r.status);
  // Size unknown and the count lies: truncated, or data after the last triangle.
  std::string lie = bytes;
  lie[80] = 3;
  r = read(lie, false, nullptr);
  EXPECT_EQ(r.status.code(), StatusCode::kTruncated) << test::format(r.status);
  EXPECT_STREQ(r.status.file(), "");  // no name: no file in the message
  lie[80] = 1;
  r = read(lie, false, "x.stl");
  EXPECT_EQ(r.status.code(), StatusCode::kParseError) << test::format(r.status);
  EXPECT_STREQ(r.status.file(), "x.stl");
  // A chunk smaller than the minimum is raised to it.
  StlReadOptions small;
  small.chunk_bytes = 16;
  r = read(kTetra, true, "t.stl", small);
  SPLINTCORE_EXPECT_OK(r.status);
  r = read(bytes, true, "t.stl", small);
  SPLINTCORE_EXPECT_OK(r.status);
}

TEST(StlCoverage, MeshOutputMustBeEmpty) {
  test::TestArena t(size_t{1} << 20);
  const std::string text = kTetra;
  MemorySource ms{reinterpret_cast<const uint8_t*>(text.data()), text.size(), 0, 0};
  Mesh mesh(&t.arena);
  ASSERT_TRUE(mesh.triangles.push_back(Triangle{{0, 1, 2}}));
  Status s = read_stl_mesh(Context(&t.arena), memory_source(&ms), StlReadOptions{}, &mesh, nullptr);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument) << test::format(s);
  Mesh other(&t.arena);
  ASSERT_TRUE(other.vertices.push_back(Vec3{0, 0, 0}));
  ms.position = 0;
  s = read_stl_mesh(Context(&t.arena), memory_source(&ms), StlReadOptions{}, &other, nullptr);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument) << test::format(s);
}

}  // namespace
}  // namespace splintcore
