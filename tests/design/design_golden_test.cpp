// Full cases from fixtures/cases designed end to end with the phantom jaws of
// `splintcore phantom --triangles 6000`: the written splint's SHA-256 is pinned in
// fixtures/golden.sha256 (the same with g++ and clang++, -O0 and -O2, every CI job), and
// MeshLab (meshlabserver, an independent implementation) confirms each written file is a
// watertight two-manifold with our volume. Two of them let the automatic outline choose the
// picks (auto.json, auto_open.json); their resolved cases (write_case, parsed again) give the
// same bytes. The full cases from CT are pinned by tests/tools/cli_test.sh
// (design:ct_phantom-120x110x80, design:ct_auto-120x110x80).
#include <cstdio>
#include <string>
#include <vector>

#include "common/phantom.h"
#include "splintcore/design.h"
#include "support/meshlab.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

struct Designed {
  std::vector<uint8_t> stl;
  DesignReport report;
  double volume = 0;
  size_t triangles = 0;
};

std::string fixture_case_text(const char* name) {
  const std::vector<uint8_t> bytes =
      test::read_file_bytes(std::string(SPLINTCORE_FIXTURES_DIR) + "/cases/" + name);
  return std::string(bytes.begin(), bytes.end());
}

// The 6,000-triangle phantom jaws (maxilla, mandible) in `arena`.
void phantom_jaws(Arena& arena, Mesh jaws[2]) {
  for (int j = 0; j < 2; ++j) {
    phantom::JawMesh m;
    phantom::PhantomOptions po;
    po.target_triangles = 6000;
    SPLINTCORE_ASSERT_OK(
        phantom::make_jaw(j == 0 ? phantom::Jaw::kMaxilla : phantom::Jaw::kMandible, po, &m));
    jaws[j].bind(&arena);
    for (const Vec3& v : m.vertices) ASSERT_TRUE(jaws[j].vertices.push_back(v));
    for (const Triangle& tr : m.triangles) ASSERT_TRUE(jaws[j].triangles.push_back(tr));
  }
}

// Designs the case TEXT (named NAME in messages) with the 6,000-triangle phantom jaws; the
// binary STL bytes.
void design_text(const std::string& text, const char* name, Designed* out) {
  test::TestArena t{size_t{768} << 20};
  Context ctx(&t.arena);
  ASSERT_FALSE(text.empty()) << name;
  CaseFile c;
  SPLINTCORE_ASSERT_OK(parse_case(ctx, text.data(), text.size(), name, &c));
  Mesh jaws[2];
  ASSERT_NO_FATAL_FAILURE(phantom_jaws(t.arena, jaws));
  Mesh splint;
  SPLINTCORE_ASSERT_OK(design_splint(ctx, c, Span<const Mesh>(jaws, 2), &splint, &out->report));
  SPLINTCORE_ASSERT_OK(check_closed_oriented(ctx, splint, &out->volume));
  out->triangles = splint.triangles.size();
  SPLINTCORE_ASSERT_OK(test::mesh_to_bytes(t.arena, splint, StlFormat::kBinary, &out->stl));
}

// Designs fixtures/cases/NAME with the 6,000-triangle phantom jaws; the binary STL bytes.
void design_case(const char* name, Designed* out) {
  design_text(fixture_case_text(name), name, out);
}

// The auto case fixtures/cases/NAME resolved with the phantom jaws (resolve_case_outline) and
// written as a case file (write_case): what `splintcore outline` writes, file names aside.
void resolved_case_text(const char* name, std::string* out) {
  test::TestArena t{size_t{256} << 20};
  Context ctx(&t.arena);
  const std::string text = fixture_case_text(name);
  CaseFile c;
  SPLINTCORE_ASSERT_OK(parse_case(ctx, text.data(), text.size(), name, &c));
  ASSERT_TRUE(c.has_auto_outline) << name;
  Mesh jaws[2];
  ASSERT_NO_FATAL_FAILURE(phantom_jaws(t.arena, jaws));
  CaseFile resolved;
  SPLINTCORE_ASSERT_OK(resolve_case_outline(ctx, c, Span<const Mesh>(jaws, 2), &resolved, nullptr));
  ByteSink sink;
  sink.user = out;
  sink.write = [](void* user, const uint8_t* data, size_t n) {
    static_cast<std::string*>(user)->append(reinterpret_cast<const char*>(data), n);
    return true;
  };
  out->clear();
  SPLINTCORE_ASSERT_OK(write_case(resolved, sink));
}

void expect_golden_and_meshlab(const char* name, const char* key, const Designed& d) {
  const std::string hash = test::sha256_hex(d.stl.data(), d.stl.size());
  const std::string want = test::golden_hash(key);
  EXPECT_EQ(hash, want) << "fixtures/golden.sha256 line, if the change is intended:\n"
                        << hash << "  " << key;
  std::printf("[ figures  ] %s: %zu triangles, %.4f mm^3, sha256 %s\n", name, d.triangles, d.volume,
              hash.c_str());
  if (!test::have_meshlab()) {
    std::printf("[ skipped  ] MeshLab: meshlabserver/xvfb-run not installed\n");
    return;
  }
  const std::string log = test::meshlab_log_of_bytes(d.stl);
  EXPECT_NE(log.find("Mesh is two-manifold"), std::string::npos) << name << "\n" << log;
  EXPECT_NE(log.find("Boundary Edges 0"), std::string::npos) << name << "\n" << log;
  const double theirs = test::number_after(log, "Mesh Volume  is ");
  EXPECT_NEAR(theirs, d.volume, 1e-5 * d.volume) << name;  // MeshLab sums in float
}

TEST(DesignGolden, PaperScaleCase) {
  Designed d;
  ASSERT_NO_FATAL_FAILURE(design_case("paper_scale.json", &d));
  EXPECT_FALSE(d.report.placed_on_tray);
  expect_golden_and_meshlab("paper_scale", "boolean:paper_scale-phantom6000", d);
}

TEST(DesignGolden, BlockoutRoundedLabelledOnTheTray) {
  Designed d;
  ASSERT_NO_FATAL_FAILURE(design_case("blockout.json", &d));
  EXPECT_EQ(d.report.blockout_jaws, 2u);
  EXPECT_TRUE(d.report.placed_on_tray);
  EXPECT_TRUE(d.report.thickness_checked);
  EXPECT_TRUE(d.report.labelled);
  EXPECT_STREQ(d.report.label.text, "PHANTOM-01");
  EXPECT_TRUE(d.report.print.printable);
  expect_golden_and_meshlab("blockout", "design:blockout-phantom6000", d);
}

TEST(DesignGolden, SpacerOnTheTray) {
  Designed d;
  ASSERT_NO_FATAL_FAILURE(design_case("spacer.json", &d));
  EXPECT_TRUE(d.report.imprint_offset);
  EXPECT_TRUE(d.report.placed_on_tray);
  EXPECT_TRUE(d.report.print.printable);
  expect_golden_and_meshlab("spacer", "design:spacer-phantom6000", d);
}

// The automatic outline (issue 28): an auto case designed, its resolved case (the picks, the
// occlusal normal, the mandible's move and the insertion direction written in) designed again:
// the same bytes, pinned.
void expect_auto_golden(const char* name, const char* key, bool opened) {
  Designed d;
  ASSERT_NO_FATAL_FAILURE(design_case(name, &d));
  EXPECT_TRUE(d.report.outlined);
  EXPECT_EQ(d.report.outline.opened, opened);
  EXPECT_EQ(d.report.outline.jaws_intersect, opened);  // auto_open's jaws are in occlusion
  EXPECT_GT(d.report.outline.picks, 8u);
  EXPECT_GT(d.report.outline.min_wafer_mm, 0.0);
  EXPECT_FALSE(d.report.placed_on_tray);
  expect_golden_and_meshlab(name, key, d);
  std::string resolved;
  ASSERT_NO_FATAL_FAILURE(resolved_case_text(name, &resolved));
  Designed again;
  ASSERT_NO_FATAL_FAILURE(design_text(resolved, "case.resolved.json", &again));
  EXPECT_FALSE(again.report.outlined);
  EXPECT_EQ(test::sha256_hex(again.stl.data(), again.stl.size()),
            test::sha256_hex(d.stl.data(), d.stl.size()))
      << resolved.substr(0, 600);
}

TEST(DesignGolden, AutoOutline) {
  expect_auto_golden("auto.json", "design:auto-phantom6000", false);
}

TEST(DesignGolden, AutoOutlineBiteOpened) {
  expect_auto_golden("auto_open.json", "design:auto_open-phantom6000", true);
}

}  // namespace
}  // namespace splintcore
