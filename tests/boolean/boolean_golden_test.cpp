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

// Compares `hash` with the committed one under `key` (or rewrites that line when
// SPLINTCORE_UPDATE_GOLDEN is set).
void check_golden(const char* key, const std::string& hash, const BooleanStats& st) {
  std::map<std::string, std::string> golden;
  std::vector<std::string> order;
  {
    std::ifstream in(golden_path());
    std::string line;
    while (std::getline(in, line)) {
      order.push_back(line);
      if (line.empty() || line[0] == '#') continue;
      std::istringstream fields(line);
      std::string h, k;
      fields >> h >> k;
      golden[k] = h;
    }
  }
  if (std::getenv("SPLINTCORE_UPDATE_GOLDEN") != nullptr) {
    std::ofstream outf(golden_path());
    bool written = false;
    for (const std::string& line : order) {
      if (line.find(key) != std::string::npos) {
        outf << hash << "  " << key << "\n";
        written = true;
      } else {
        outf << line << "\n";
      }
    }
    if (!written) outf << hash << "  " << key << "\n";
    return;
  }
  ASSERT_TRUE(golden.count(key)) << "no golden hash for " << key;
  EXPECT_EQ(hash, golden[key]) << "attempts " << st.attempts;
}

// The base of fixtures/cases/paper_scale.json.
void paper_scale_base(const Context& ctx, Mesh* base) {
  std::vector<uint8_t> text =
      test::read_file_bytes(std::string(SPLINTCORE_FIXTURES_DIR) + "/cases/paper_scale.json");
  CaseFile c;
  SPLINTCORE_ASSERT_OK(
      parse_case(ctx, reinterpret_cast<const char*>(text.data()), text.size(), "paper_scale", &c));
  BaseReport r;
  SPLINTCORE_ASSERT_OK(build_case_base(ctx, c, base, &r));
}

// a - b (the default options) into *out, and *out as binary STL appended to *stl: what each
// golden below hashes.
void difference_stl(const Context& ctx, test::TestArena& t, const Mesh& a, const Mesh& b, Mesh* out,
                    BooleanStats* st, std::vector<uint8_t>* stl) {
  SPLINTCORE_ASSERT_OK(mesh_boolean(ctx, a, b, BooleanOptions{}, out, st));
  std::vector<uint8_t> bytes;
  SPLINTCORE_ASSERT_OK(test::mesh_to_bytes(t.arena, *out, StlFormat::kBinary, &bytes));
  stl->insert(stl->end(), bytes.begin(), bytes.end());
}

TEST(BooleanGolden, BaseMinusPhantomJawsMatchesTheCommittedHash) {
  test::TestArena t(size_t{128} << 20);
  Context ctx(&t.arena);
  Mesh base(&t.arena);
  paper_scale_base(ctx, &base);
  if (HasFatalFailure()) return;
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
      ASSERT_TRUE(
          jaws.triangles.push_back(Triangle{{tr.v[0] + off, tr.v[1] + off, tr.v[2] + off}}));
    }
  }
  Mesh out;
  BooleanStats st;
  std::vector<uint8_t> bytes;
  difference_stl(ctx, t, base, jaws, &out, &st, &bytes);
  if (HasFatalFailure()) return;
  EXPECT_GT(st.intersecting_pairs, 0u);
  const std::string hash = test::sha256_hex(bytes.data(), bytes.size());

  check_golden(kKey, hash, st);
}

}  // namespace
}  // namespace splintcore

namespace splintcore {
namespace {

// Exact contacts, pinned too (so the cross-compiled jobs hold the exact path to the same
// bytes): the paper-scale base moved so that its vertex 0 lies exactly on the nearest jaw
// vertex (a vertex-on-vertex contact among the crossings), and a unit box minus two boxes of B
// that share faces with it and overlap each other (coplanar contacts, two passes). Both results
// as binary STL, hashed together, under "boolean:exact-contacts".
TEST(BooleanGolden, ExactContactsMatchTheCommittedHash) {
  test::TestArena t(size_t{128} << 20);
  Context ctx(&t.arena);
  Mesh base(&t.arena);
  paper_scale_base(ctx, &base);
  if (HasFatalFailure()) return;
  Mesh jaws(&t.arena);
  phantom::JawMesh m;
  phantom::PhantomOptions po;
  po.target_triangles = 6000;
  SPLINTCORE_ASSERT_OK(phantom::make_jaw(phantom::Jaw::kMaxilla, po, &m));
  for (const Vec3& v : m.vertices) ASSERT_TRUE(jaws.vertices.push_back(v));
  for (const Triangle& tr : m.triangles) ASSERT_TRUE(jaws.triangles.push_back(tr));
  uint32_t nearest = 0;
  for (uint32_t j = 1; j < jaws.vertices.size(); ++j) {
    if (length(jaws.vertices[j] - base.vertices[0]) <
        length(jaws.vertices[nearest] - base.vertices[0])) {
      nearest = j;
    }
  }
  const Vec3 d = jaws.vertices[nearest] - base.vertices[0];
  for (Vec3& v : base.vertices) {
    v = v + d;
    ASSERT_TRUE(round_to_float32(&v));
  }
  ASSERT_TRUE(base.vertices[0] == jaws.vertices[nearest]);
  std::vector<uint8_t> all;
  BooleanStats st;
  {
    Mesh out;
    difference_stl(ctx, t, base, jaws, &out, &st, &all);
    if (HasFatalFailure()) return;
    EXPECT_GT(st.degenerate_pairs, 0u);
  }
  auto box = [&](const Vec3& lo, const Vec3& hi, Mesh* mesh) {
    const uint32_t off = static_cast<uint32_t>(mesh->vertices.size());
    for (int i = 0; i < 8; ++i) {
      ASSERT_TRUE(mesh->vertices.push_back(
          Vec3{(i & 1) ? hi.x : lo.x, (i & 2) ? hi.y : lo.y, (i & 4) ? hi.z : lo.z}));
    }
    const uint32_t f[12][3] = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}, {0, 1, 5}, {0, 5, 4},
                               {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
    for (const auto& tr : f) {
      ASSERT_TRUE(mesh->triangles.push_back(Triangle{{tr[0] + off, tr[1] + off, tr[2] + off}}));
    }
  };
  Mesh a(&t.arena), b(&t.arena);
  box(Vec3{0, 0, 0}, Vec3{1, 1, 1}, &a);
  box(Vec3{0.25, 0.25, 0.5}, Vec3{0.75, 0.75, 1}, &b);
  box(Vec3{0.5, 0, 0}, Vec3{1.5, 1, 1}, &b);
  {
    Mesh out;
    BooleanStats sb;
    difference_stl(ctx, t, a, b, &out, &sb, &all);
    if (HasFatalFailure()) return;
    EXPECT_EQ(sb.attempts, sb.passes);  // no nudge in any pass
    EXPECT_NEAR(mesh_volume(out), 0.4375, 1e-12);
  }
  check_golden("boolean:exact-contacts", test::sha256_hex(all.data(), all.size()), st);
}

}  // namespace
}  // namespace splintcore
