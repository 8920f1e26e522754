// Golden-file tests: every fixture STL is read, welded, checked and written back (binary and
// ASCII) through the library; the SHA-256 of the output bytes must equal the committed value in
// fixtures/golden.sha256. The same file is checked by every CI build (g++ and clang++, -O0 and
// -O2, sanitizers, and cross builds), which is what makes the bytes deterministic rather than
// merely repeatable.
//
// To regenerate after an intended change of output: SPLINTCORE_UPDATE_GOLDEN=1 ./splintcore_tests
// --gtest_filter='Golden*' (then review the diff and say why in the commit).
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>

#include "splintcore/design.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

const char* kFixtures[] = {"stl/torus_binary.stl",  "stl/box_solid_header.stl",
                           "stl/tetra_ascii.stl",   "stl/open_box_ascii.stl",
                           "stl/inside_out_box.stl", "stl/too_large_box.stl"};

const char* kCases[] = {"cases/paper_scale.json", "cases/rounded.json", "cases/uneven.json"};

std::string golden_path() { return std::string(SPLINTCORE_FIXTURES_DIR) + "/golden.sha256"; }

std::map<std::string, std::string> load_golden() {
  std::map<std::string, std::string> out;
  std::ifstream in(golden_path());
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    std::string hash, key;
    fields >> hash >> key;
    out[key] = hash;
  }
  return out;
}

std::string convert_hash(const std::string& fixture, StlFormat format) {
  test::TestArena t(64 << 20);
  std::vector<uint8_t> bytes = test::read_file_bytes(std::string(SPLINTCORE_FIXTURES_DIR) + "/" +
                                                     fixture);
  EXPECT_FALSE(bytes.empty()) << fixture;
  Mesh mesh;
  Status s = test::mesh_from_bytes(t.arena, bytes, &mesh);
  EXPECT_TRUE(s.is_ok()) << test::format(s);
  std::vector<uint8_t> out;
  s = test::mesh_to_bytes(t.arena, mesh, format, &out);
  EXPECT_TRUE(s.is_ok()) << test::format(s);
  return test::sha256_hex(out.data(), out.size());
}

// The base a case file builds, written as binary STL (what `splintcore base` writes).
std::string base_hash(const std::string& fixture, size_t* triangles) {
  test::TestArena t(64 << 20);
  std::vector<uint8_t> text =
      test::read_file_bytes(std::string(SPLINTCORE_FIXTURES_DIR) + "/" + fixture);
  EXPECT_FALSE(text.empty()) << fixture;
  Context ctx(&t.arena);
  CaseFile c;
  Status s = parse_case(ctx, reinterpret_cast<const char*>(text.data()), text.size(),
                        fixture.c_str(), &c);
  EXPECT_TRUE(s.is_ok()) << test::format(s);
  Mesh m(&t.arena);
  BaseReport r;
  s = build_case_base(ctx, c, &m, &r);
  EXPECT_TRUE(s.is_ok()) << test::format(s);
  *triangles = m.triangles.size();
  std::vector<uint8_t> out;
  s = test::mesh_to_bytes(t.arena, m, StlFormat::kBinary, &out);
  EXPECT_TRUE(s.is_ok()) << test::format(s);
  return test::sha256_hex(out.data(), out.size());
}

TEST(Golden, ConvertedFixturesMatchCommittedHashes) {
  std::map<std::string, std::string> golden = load_golden();
  std::ostringstream fresh;
  fresh << "# SHA-256 of `splintcore convert` output for each fixture (see tests/golden_test.cpp)\n";
  for (const char* f : kFixtures) {
    for (StlFormat format : {StlFormat::kBinary, StlFormat::kAscii}) {
      std::string key = std::string(format == StlFormat::kBinary ? "binary:" : "ascii:") + f;
      std::string hash = convert_hash(f, format);
      fresh << hash << "  " << key << "\n";
      if (std::getenv("SPLINTCORE_UPDATE_GOLDEN") == nullptr) {
        ASSERT_TRUE(golden.count(key)) << "no golden hash for " << key;
        EXPECT_EQ(hash, golden[key]) << key;
      }
    }
  }
  for (const char* f : kCases) {
    std::string key = std::string("base:") + f;
    size_t triangles = 0;
    std::string hash = base_hash(f, &triangles);
    fresh << hash << "  " << key << "\n";
    if (std::getenv("SPLINTCORE_UPDATE_GOLDEN") == nullptr) {
      ASSERT_TRUE(golden.count(key)) << "no golden hash for " << key;
      EXPECT_EQ(hash, golden[key]) << key;
    }
  }
  if (std::getenv("SPLINTCORE_UPDATE_GOLDEN") != nullptr) {
    // Keys other tests own (e.g. boolean:) are kept.
    for (const auto& kv : golden) {
      if (kv.first.rfind("binary:", 0) != 0 && kv.first.rfind("ascii:", 0) != 0 &&
          kv.first.rfind("base:", 0) != 0) {
        fresh << kv.second << "  " << kv.first << "\n";
      }
    }
    std::ofstream(golden_path()) << fresh.str();
  }
}

// The paper's scale (Table 1): 2,560-2,640 cells for the initial splint.
TEST(Golden, PaperScaleCaseHasThePapersTriangleCount) {
  size_t triangles = 0;
  base_hash("cases/paper_scale.json", &triangles);
  EXPECT_GE(triangles, 2560u);
  EXPECT_LE(triangles, 2640u);
}

// A converted file is a fixed point: converting the output again gives the same bytes.
TEST(Golden, ConvertIsIdempotent) {
  for (const char* f : kFixtures) {
    test::TestArena t(64 << 20);
    std::vector<uint8_t> bytes =
        test::read_file_bytes(std::string(SPLINTCORE_FIXTURES_DIR) + "/" + f);
    Mesh a;
    SPLINTCORE_ASSERT_OK(test::mesh_from_bytes(t.arena, bytes, &a));
    std::vector<uint8_t> once, twice;
    SPLINTCORE_ASSERT_OK(test::mesh_to_bytes(t.arena, a, StlFormat::kBinary, &once));
    Mesh b;
    SPLINTCORE_ASSERT_OK(test::mesh_from_bytes(t.arena, once, &b));
    SPLINTCORE_ASSERT_OK(test::mesh_to_bytes(t.arena, b, StlFormat::kBinary, &twice));
    EXPECT_EQ(once, twice) << f;
  }
}

}  // namespace
}  // namespace splintcore
