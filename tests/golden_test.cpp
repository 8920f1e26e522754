// Golden-file tests: every fixture STL is read, welded, checked and written back (binary and
// ASCII) through the library; the SHA-256 of the output bytes must equal the committed value in
// fixtures/golden.sha256. The same file is checked by every CI build (g++ and clang++, -O0 and
// -O2, sanitizers, and cross builds), which is what makes the bytes deterministic rather than
// merely repeatable.
//
// To regenerate after an intended change of output: SPLINTCORE_UPDATE_GOLDEN=1 ./splintcore_tests
// --gtest_filter='Golden*' (then review the diff and say why in the commit).
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>

#include "splintcore/design.h"
#include "splintcore/render.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

const char* kFixtures[] = {"stl/torus_binary.stl",   "stl/box_solid_header.stl",
                           "stl/tetra_ascii.stl",    "stl/open_box_ascii.stl",
                           "stl/inside_out_box.stl", "stl/too_large_box.stl"};

const char* kCases[] = {"cases/paper_scale.json", "cases/rounded.json", "cases/uneven.json"};

std::string golden_path() { return std::string(SPLINTCORE_FIXTURES_DIR) + "/golden.sha256"; }

std::map<std::string, std::string> load_golden() { return test::golden_hashes(); }

std::string convert_hash(const std::string& fixture, StlFormat format) {
  test::TestArena t(64 << 20);
  std::vector<uint8_t> bytes =
      test::read_file_bytes(std::string(SPLINTCORE_FIXTURES_DIR) + "/" + fixture);
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
  Status s =
      parse_case(ctx, reinterpret_cast<const char*>(text.data()), text.size(), fixture.c_str(), &c);
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
  fresh
      << "# SHA-256 of `splintcore convert` output for each fixture (see tests/golden_test.cpp)\n";
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

// Preview renders (include/splintcore/render.h): the PNG bytes of two small scenes, pinned as
// "render:<name>" like the meshes above: a translucent box over the torus in the four views
// (flat shading, overlay blending), and the torus coloured by |z| (Gouraud, ramp, legend).
bool append_bytes(void* user, const uint8_t* data, size_t bytes) {
  auto* out = static_cast<std::vector<uint8_t>*>(user);
  out->insert(out->end(), data, data + bytes);
  return true;
}

std::string render_hash(bool scalars) {
  test::TestArena t(64 << 20);
  Mesh torus, box;
  Status s = test::mesh_from_bytes(
      t.arena,
      test::read_file_bytes(std::string(SPLINTCORE_FIXTURES_DIR) + "/stl/torus_binary.stl"),
      &torus);
  EXPECT_TRUE(s.is_ok()) << test::format(s);
  s = test::mesh_from_bytes(
      t.arena,
      test::read_file_bytes(std::string(SPLINTCORE_FIXTURES_DIR) + "/stl/box_solid_header.stl"),
      &box);
  EXPECT_TRUE(s.is_ok()) << test::format(s);
  std::vector<double> height(torus.vertices.size());
  for (size_t i = 0; i < height.size(); ++i) height[i] = std::fabs(torus.vertices[i].z);
  std::vector<RenderMesh> items(scalars ? 1 : 2);
  RenderOptions o;
  if (scalars) {
    items[0].mesh = &torus;
    items[0].scalars = height.data();
    items[0].scalar_max = 1.5;
    o.width = 200;
    o.height = 160;
    o.shading = RenderShading::kGouraud;
    o.legend = true;
  } else {
    items[0].mesh = &box;
    items[0].alpha = 150;
    items[1].mesh = &torus;
    o.width = 256;
    o.height = 256;
  }
  RenderImage image;
  s = render_meshes(Context(&t.arena), Span<const RenderMesh>(items.data(), items.size()), o,
                    &image);
  EXPECT_TRUE(s.is_ok()) << test::format(s);
  std::vector<uint8_t> png;
  ByteSink sink;
  sink.write = &append_bytes;
  sink.user = &png;
  s = write_png(Context(&t.arena), image, sink);
  EXPECT_TRUE(s.is_ok()) << test::format(s);
  return test::sha256_hex(png.data(), png.size());
}

TEST(Golden, RenderedPreviewsMatchCommittedHashes) {
  std::map<std::string, std::string> golden = load_golden();
  const std::pair<std::string, std::string> fresh[] = {
      {"render:torus+box-4views", render_hash(false)},
      {"render:torus-height-ramp", render_hash(true)}};
  if (std::getenv("SPLINTCORE_UPDATE_GOLDEN") != nullptr) {
    // Replace or append this test's lines; every other line is kept as it is.
    std::ifstream in(golden_path());
    std::ostringstream text;
    std::string line;
    std::map<std::string, bool> written;
    while (std::getline(in, line)) {
      std::istringstream fields(line);
      std::string hash, key;
      fields >> hash >> key;
      for (const auto& kv : fresh) {
        if (line.empty() || line[0] == '#' || key != kv.first) continue;
        line = kv.second + "  " + kv.first;
        written[kv.first] = true;
      }
      text << line << "\n";
    }
    for (const auto& kv : fresh) {
      if (!written[kv.first]) text << kv.second << "  " << kv.first << "\n";
    }
    in.close();
    std::ofstream(golden_path()) << text.str();
    return;
  }
  for (const auto& kv : fresh) {
    ASSERT_TRUE(golden.count(kv.first)) << "no golden hash for " << kv.first;
    EXPECT_EQ(kv.second, golden[kv.first]) << kv.first;
  }
}

}  // namespace
}  // namespace splintcore
