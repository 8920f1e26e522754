// The design pipeline (src/design/pipeline.cpp): the paper-scale case with the phantom jaws
// gives the Boolean golden's bytes; bad calls are named errors; arena exhaustion is clean at
// every cap tried; the jaws given are not changed.
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>

#include "common/phantom.h"
#include "splintcore/design.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

struct CaseAndJaws {
  test::TestArena t{size_t{128} << 20};
  CaseFile c;
  Mesh jaws[2];
  bool ok = false;
  CaseAndJaws() {
    Context ctx(&t.arena);
    static std::vector<uint8_t> text;
    text = test::read_file_bytes(std::string(SPLINTCORE_FIXTURES_DIR) + "/cases/paper_scale.json");
    if (!parse_case(ctx, reinterpret_cast<const char*>(text.data()), text.size(), "paper_scale",
                    &c).is_ok()) {
      return;
    }
    for (int j = 0; j < 2; ++j) {
      phantom::JawMesh m;
      phantom::PhantomOptions po;
      po.target_triangles = 6000;
      if (!phantom::make_jaw(j == 0 ? phantom::Jaw::kMaxilla : phantom::Jaw::kMandible, po, &m)
               .is_ok()) {
        return;
      }
      jaws[j].bind(&t.arena);
      for (const Vec3& v : m.vertices) (void)jaws[j].vertices.push_back(v);
      for (const Triangle& tr : m.triangles) (void)jaws[j].triangles.push_back(tr);
    }
    ok = true;
  }
};

std::string golden(const char* key) {
  std::ifstream in(std::string(SPLINTCORE_FIXTURES_DIR) + "/golden.sha256");
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream f(line);
    std::string h, k;
    f >> h >> k;
    if (k == key) return h;
  }
  return "";
}

TEST(DesignPipeline, PaperScaleCaseGivesTheGoldenSplint) {
  CaseAndJaws f;
  ASSERT_TRUE(f.ok);
  const std::string before = test::sha256_hex(f.jaws[1].vertices.data(),
                                              f.jaws[1].vertices.size() * sizeof(Vec3));
  Mesh splint;
  DesignReport r;
  SPLINTCORE_ASSERT_OK(design_splint(Context(&f.t.arena), f.c, Span<const Mesh>(f.jaws, 2),
                                     &splint, &r));
  EXPECT_TRUE(r.print.printable);
  EXPECT_EQ(r.jaw_triangles, 12000u);
  EXPECT_GT(r.boolean.intersecting_pairs, 0u);
  std::vector<uint8_t> bytes;
  SPLINTCORE_ASSERT_OK(test::mesh_to_bytes(f.t.arena, splint, StlFormat::kBinary, &bytes));
  EXPECT_EQ(test::sha256_hex(bytes.data(), bytes.size()),
            golden("boolean:paper_scale-phantom6000"));
  // The jaws given are read, not moved.
  EXPECT_EQ(test::sha256_hex(f.jaws[1].vertices.data(), f.jaws[1].vertices.size() * sizeof(Vec3)),
            before);
}

TEST(DesignPipeline, BadCallsAreNamed) {
  CaseAndJaws f;
  ASSERT_TRUE(f.ok);
  Mesh splint;
  DesignReport r;
  Status s = design_splint(Context(&f.t.arena), f.c, Span<const Mesh>(f.jaws, 1), &splint, &r);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(std::string(s.message()).find("2 jaws"), std::string::npos) << s.message();
  CaseFile other = f.c;
  other.printer = "nope";
  s = design_splint(Context(&f.t.arena), other, Span<const Mesh>(f.jaws, 2), &splint, &r);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(std::string(s.message()).find("nope"), std::string::npos);
  // Jaws in occlusion (no opening): their shells overlap inside the base.
  CaseJaw closed[2] = {f.c.jaws[0], f.c.jaws[1]};
  closed[1].transform = RigidTransform{};
  other = f.c;
  other.jaws = Span<const CaseJaw>(closed, 2);
  s = design_splint(Context(&f.t.arena), other, Span<const Mesh>(f.jaws, 2), &splint, &r);
  EXPECT_FALSE(s.is_ok());
  EXPECT_NE(std::string(s.message()).find("boolean"), std::string::npos) << s.message();
}

TEST(DesignPipeline, ArenaExhaustionIsCleanAtEveryCapTried) {
  CaseAndJaws f;
  ASSERT_TRUE(f.ok);
  size_t need = 0;
  {
    std::vector<unsigned char> big(size_t{64} << 20);
    Arena probe(big.data(), big.size());
    Mesh splint;
    DesignReport r;
    SPLINTCORE_ASSERT_OK(design_splint(Context(&probe), f.c, Span<const Mesh>(f.jaws, 2),
                                       &splint, &r));
    need = probe.high_water();
  }
  int tried = 0;
  for (size_t cap = 0; cap < need; cap += need / 40 + 1) {
    std::vector<unsigned char> buf(cap + 1);
    Arena small(buf.data(), cap);
    Mesh splint;
    DesignReport r;
    Status s = design_splint(Context(&small), f.c, Span<const Mesh>(f.jaws, 2), &splint, &r);
    ASSERT_EQ(s.code(), StatusCode::kArenaExhausted) << cap << " " << test::format(s);
    EXPECT_EQ(small.used(), 0u);
    EXPECT_TRUE(splint.triangles.empty());
    ++tried;
  }
  std::vector<unsigned char> buf(need);
  Arena exact(buf.data(), need);
  Mesh splint;
  DesignReport r;
  SPLINTCORE_EXPECT_OK(design_splint(Context(&exact), f.c, Span<const Mesh>(f.jaws, 2), &splint, &r));
  EXPECT_GE(tried, 40);
}

}  // namespace
}  // namespace splintcore

namespace splintcore {
namespace {

TEST(DesignPipeline, BlockoutRemovesInterferenceAndStaysPrintable) {
  CaseAndJaws f;
  ASSERT_TRUE(f.ok);
  Mesh plain;
  DesignReport r0;
  SPLINTCORE_ASSERT_OK(design_splint(Context(&f.t.arena), f.c, Span<const Mesh>(f.jaws, 2),
                                     &plain, &r0));
  EXPECT_EQ(r0.blockout_jaws, 0u);
  CaseFile c = f.c;
  c.has_blockout = true;
  c.blockout_voxel = 0.2;
  c.blockout_inset = 0.1;
  Mesh blocked;
  DesignReport r;
  SPLINTCORE_ASSERT_OK(design_splint(Context(&f.t.arena), c, Span<const Mesh>(f.jaws, 2),
                                     &blocked, &r));
  EXPECT_TRUE(r.print.printable);
  ASSERT_EQ(r.blockout_jaws, 2u);
  // The maxilla is swept along the insertion direction, the mandible along its reverse.
  EXPECT_EQ(r.blockout[0].sweep.axis_w, c.insertion_direction);
  EXPECT_EQ(r.blockout[1].sweep.axis_w, -c.insertion_direction);
  double v_plain = 0, v_blocked = 0;
  SPLINTCORE_ASSERT_OK(check_closed_oriented(Context(&f.t.arena), plain, &v_plain));
  SPLINTCORE_ASSERT_OK(check_closed_oriented(Context(&f.t.arena), blocked, &v_blocked));
  EXPECT_LE(v_blocked, v_plain);
  EXPECT_NEAR(v_plain - v_blocked, r.blockout_removed_mm3[0] + r.blockout_removed_mm3[1], 1e-6);
  // Run twice: the same bytes.
  Mesh again;
  DesignReport r2;
  SPLINTCORE_ASSERT_OK(design_splint(Context(&f.t.arena), c, Span<const Mesh>(f.jaws, 2),
                                     &again, &r2));
  std::vector<uint8_t> a, b;
  SPLINTCORE_ASSERT_OK(test::mesh_to_bytes(f.t.arena, blocked, StlFormat::kBinary, &a));
  SPLINTCORE_ASSERT_OK(test::mesh_to_bytes(f.t.arena, again, StlFormat::kBinary, &b));
  EXPECT_EQ(a, b);
}

}  // namespace
}  // namespace splintcore
