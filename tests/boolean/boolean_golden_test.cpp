// Golden-file test of the Boolean: the base of fixtures/cases/paper_scale.json minus the
// phantom maxilla and mandible (6,000 triangles each, the mandible opened by the case's 2 mm and
// rounded to float32 as its STL would be), written as binary STL; the SHA-256 of those bytes is
// pinned in fixtures/golden.sha256 under "boolean:paper_scale-phantom6000" and checked by every
// CI build (g++ and clang++, -O0 and -O2, sanitizers).
//
// To regenerate after an intended change: SPLINTCORE_UPDATE_GOLDEN=1 ./splintcore_tests
// --gtest_filter='BooleanGolden*'.
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>

#include "common/phantom.h"
#include "splintcore/boolean.h"
#include "splintcore/design.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

const char kKey[] = "boolean:paper_scale-phantom6000";

std::string golden_path() { return std::string(SPLINTCORE_FIXTURES_DIR) + "/golden.sha256"; }

TEST(BooleanGolden, BaseMinusPhantomJawsMatchesTheCommittedHash) {
  test::TestArena t(size_t{128} << 20);
  Context ctx(&t.arena);
  std::vector<uint8_t> text = test::read_file_bytes(std::string(SPLINTCORE_FIXTURES_DIR) +
                                                    "/cases/paper_scale.json");
  CaseFile c;
  SPLINTCORE_ASSERT_OK(parse_case(ctx, reinterpret_cast<const char*>(text.data()), text.size(),
                                  "paper_scale", &c));
  Mesh base(&t.arena);
  BaseReport r;
  SPLINTCORE_ASSERT_OK(build_case_base(ctx, c, &base, &r));
  Mesh jaws(&t.arena);
  for (int j = 0; j < 2; ++j) {
    phantom::JawMesh m;
    phantom::PhantomOptions po;
    po.target_triangles = 6000;
    SPLINTCORE_ASSERT_OK(
        phantom::make_jaw(j == 0 ? phantom::Jaw::kMaxilla : phantom::Jaw::kMandible, po, &m));
    const uint32_t off = static_cast<uint32_t>(jaws.vertices.size());
    for (Vec3 v : m.vertices) {
      if (j == 1) {
        v.z -= 2.0;
        ASSERT_TRUE(round_to_float32(&v));
      }
      ASSERT_TRUE(jaws.vertices.push_back(v));
    }
    for (const Triangle& tr : m.triangles) {
      ASSERT_TRUE(jaws.triangles.push_back(Triangle{{tr.v[0] + off, tr.v[1] + off, tr.v[2] + off}}));
    }
  }
  Mesh out;
  BooleanStats st;
  SPLINTCORE_ASSERT_OK(mesh_boolean(ctx, base, jaws, BooleanOptions{}, &out, &st));
  EXPECT_GT(st.intersecting_pairs, 0u);
  std::vector<uint8_t> bytes;
  SPLINTCORE_ASSERT_OK(test::mesh_to_bytes(t.arena, out, StlFormat::kBinary, &bytes));
  const std::string hash = test::sha256_hex(bytes.data(), bytes.size());

  std::map<std::string, std::string> golden;
  std::vector<std::string> order;
  {
    std::ifstream in(golden_path());
    std::string line;
    while (std::getline(in, line)) {
      order.push_back(line);
      if (line.empty() || line[0] == '#') continue;
      std::istringstream fields(line);
      std::string h, key;
      fields >> h >> key;
      golden[key] = h;
    }
  }
  if (std::getenv("SPLINTCORE_UPDATE_GOLDEN") != nullptr) {
    std::ofstream outf(golden_path());
    bool written = false;
    for (const std::string& line : order) {
      if (line.find(kKey) != std::string::npos) {
        outf << hash << "  " << kKey << "\n";
        written = true;
      } else {
        outf << line << "\n";
      }
    }
    if (!written) outf << hash << "  " << kKey << "\n";
    return;
  }
  ASSERT_TRUE(golden.count(kKey)) << "no golden hash for " << kKey;
  EXPECT_EQ(hash, golden[kKey]) << "attempts " << st.attempts;
}

}  // namespace
}  // namespace splintcore
