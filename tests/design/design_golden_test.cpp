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
  out->clear();
  SPLINTCORE_ASSERT_OK(write_case(resolved, test::string_sink(out)));
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

// The default blockout ("blockout": {}, "auto"): the exact swept boundary of each jaw, with
// the same options as above; its bytes pinned (and on AArch64, ARMv7).
TEST(DesignGolden, ExactBlockoutRoundedLabelledOnTheTray) {
  Designed d;
  ASSERT_NO_FATAL_FAILURE(design_case("exact.json", &d));
  EXPECT_EQ(d.report.blockout_jaws, 2u);
  EXPECT_TRUE(d.report.imprint_swept);
  EXPECT_STREQ(d.report.blockout_fallback, "");
  EXPECT_EQ(d.report.boolean.intersecting_pairs, 0u);  // the jaws' own Boolean is not run
  EXPECT_TRUE(d.report.placed_on_tray);
  EXPECT_TRUE(d.report.labelled);
  EXPECT_TRUE(d.report.print.printable);
  expect_golden_and_meshlab("exact", "design:exact-phantom6000", d);
}

// The height field ("method": "heightfield", voxel 0.1 mm) with the same options: the jaws are
// not subtracted first, nothing is left undercut; its bytes pinned (and on AArch64, ARMv7).
TEST(DesignGolden, HeightfieldBlockoutRoundedLabelledOnTheTray) {
  Designed d;
  ASSERT_NO_FATAL_FAILURE(design_case("heightfield.json", &d));
  EXPECT_EQ(d.report.blockout_jaws, 2u);
  EXPECT_TRUE(d.report.imprint_heightfield);
  EXPECT_EQ(d.report.boolean.intersecting_pairs, 0u);
  for (int j = 0; j < 2; ++j) EXPECT_GT(d.report.blockout[j].heightfield.network_triangles, 0u);
  EXPECT_TRUE(d.report.placed_on_tray);
  EXPECT_TRUE(d.report.labelled);
  EXPECT_TRUE(d.report.print.printable);
  expect_golden_and_meshlab("heightfield", "design:heightfield-phantom6000", d);
}

// The spacer as the height field of the offset solid ("method": "heightfield", a 0.2 mm
// clearance on a 0.1 mm grid, spacer.json otherwise): the jaws are not subtracted first; its
// bytes pinned (and on AArch64, ARMv7).
TEST(DesignGolden, HeightfieldSpacerOnTheTray) {
  Designed d;
  ASSERT_NO_FATAL_FAILURE(design_case("heightfield_spacer.json", &d));
  EXPECT_EQ(d.report.blockout_jaws, 2u);
  EXPECT_TRUE(d.report.imprint_heightfield && d.report.imprint_offset);
  EXPECT_EQ(d.report.boolean.intersecting_pairs, 0u);
  for (int j = 0; j < 2; ++j) {
    EXPECT_GT(d.report.blockout[j].heightfield.offset_pieces, 0u);
    EXPECT_GE(d.report.blockout[j].offset_used, 0.2);
  }
  EXPECT_TRUE(d.report.placed_on_tray);
  EXPECT_TRUE(d.report.print.printable);
  expect_golden_and_meshlab("heightfield_spacer", "design:heightfield_spacer-phantom6000", d);
}

// The firmware example's third stage (tools/firmware/main.cpp, issue 29): the paper-scale case
// with blockout on a 0.1 mm grid (inset 0.05 mm, no closing), designed in an arena of exactly
// the board's 16 MiB (the jaws in an arena of their own, as the board's come from flash). Its
// hash is what the Cortex-M7 and the cross builds must give.
TEST(DesignGolden, FirmwareBlockoutTenthMillimetreIn16MiB) {
  test::TestArena jaw_arena{size_t{16} << 20};
  Mesh jaws[2];
  ASSERT_NO_FATAL_FAILURE(phantom_jaws(jaw_arena.arena, jaws));
  test::TestArena t{size_t{16} << 20};
  Context ctx(&t.arena);
  const std::string text = fixture_case_text("paper_scale.json");
  CaseFile c;
  SPLINTCORE_ASSERT_OK(parse_case(ctx, text.data(), text.size(), "paper_scale.json", &c));
  c.has_blockout = true;
  c.blockout_method = BlockoutMethod::kVoxel;
  c.blockout.voxel = 0.1;
  c.blockout.inset = 0.05;
  c.blockout.closing_radius = 0;
  Designed d;
  Mesh splint;
  SPLINTCORE_ASSERT_OK(design_splint(ctx, c, Span<const Mesh>(jaws, 2), &splint, &d.report));
  EXPECT_EQ(d.report.blockout_jaws, 2u);
  EXPECT_TRUE(d.report.print.printable);
  std::printf("[ figures  ] firmware blockout: arena high water %zu of %zu bytes\n",
              t.arena.high_water(), t.arena.cap());
  Context check(&jaw_arena.arena);  // the checks below are the test's, not the board's
  SPLINTCORE_ASSERT_OK(check_closed_oriented(check, splint, &d.volume));
  d.triangles = splint.triangles.size();
  SPLINTCORE_ASSERT_OK(test::mesh_to_bytes(jaw_arena.arena, splint, StlFormat::kBinary, &d.stl));
  expect_golden_and_meshlab("firmware_blockout", "design:blockout-0.1mm-paper_scale-phantom6000",
                            d);
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

// Two-jaw surgery (issue 32): fixtures/cases/plan.json designed with the phantom jaws
// (design_plan: both splints, each labelled, INT and FIN) and its print job (write_plan_job:
// both on the Eden260 tray, one 3MF package), the bytes of all three pinned; the C API
// (tests/capi/capi_test.c) and `splintcore design` (tests/tools/cli_test.sh) must give them too.
TEST(DesignGolden, PlanSplintsAndPrintJob) {
  test::TestArena t{size_t{256} << 20};
  Context ctx(&t.arena);
  const std::string text = fixture_case_text("plan.json");
  CaseFile c;
  SPLINTCORE_ASSERT_OK(parse_case(ctx, text.data(), text.size(), "plan.json", &c));
  Mesh jaws[2];
  ASSERT_NO_FATAL_FAILURE(phantom_jaws(t.arena, jaws));
  Mesh splints[2];
  PlanReport r;
  SPLINTCORE_ASSERT_OK(
      design_plan(ctx, c, Span<const Mesh>(jaws, 2), &splints[0], &splints[1], &r));
  EXPECT_STREQ(r.intermediate.design.label.text, "INT P1");
  EXPECT_STREQ(r.final_splint.design.label.text, "FIN P1");
  static const char* const kKeys[2] = {"design:plan-intermediate-phantom6000",
                                       "design:plan-final-phantom6000"};
  for (int k = 0; k < 2; ++k) {
    Designed d;
    d.report = k == 0 ? r.intermediate.design : r.final_splint.design;
    SPLINTCORE_ASSERT_OK(check_closed_oriented(ctx, splints[k], &d.volume));
    d.triangles = splints[k].triangles.size();
    SPLINTCORE_ASSERT_OK(test::mesh_to_bytes(t.arena, splints[k], StlFormat::kBinary, &d.stl));
    expect_golden_and_meshlab(kKeys[k], kKeys[k], d);
  }
  std::string job;
  ByteSink sink = test::string_sink(&job);
  Vec3 moves[2];
  const uint64_t before = t.arena.used();
  t.arena.reset_high_water();
  SPLINTCORE_ASSERT_OK(write_plan_job(ctx, c, splints[0], splints[1], nullptr, sink, moves));
  EXPECT_EQ(t.arena.used(), before);  // nothing stays
  EXPECT_LE(t.arena.high_water() - before, plan_job_bound(c, splints[0], splints[1]));
  {  // in an arena of exactly plan_job_bound() bytes: the same bytes
    const uint64_t bound = plan_job_bound(c, splints[0], splints[1]);
    test::TestArena exact{static_cast<size_t>(bound)};
    std::string again;
    sink.user = &again;
    SPLINTCORE_ASSERT_OK(
        write_plan_job(Context(&exact.arena), c, splints[0], splints[1], nullptr, sink, nullptr));
    EXPECT_EQ(again, job);
    EXPECT_EQ(exact.arena.used(), 0u);
  }
  const std::string hash = test::sha256_hex(job.data(), job.size());
  const char* key = "design:plan-job3mf-phantom6000";
  EXPECT_EQ(hash, test::golden_hash(key))
      << "fixtures/golden.sha256 line, if the change is intended:\n"
      << hash << "  " << key;
  std::printf(
      "[ figures  ] job.3mf: %zu bytes, sha256 %s; splints moved by (%.4f, %.4f, %.4f) "
      "and (%.4f, %.4f, %.4f)\n",
      job.size(), hash.c_str(), moves[0].x, moves[0].y, moves[0].z, moves[1].x, moves[1].y,
      moves[1].z);
}

}  // namespace
}  // namespace splintcore
