// Two-jaw surgery (src/design/plan.cpp, design_plan; issue 32) on the phantom: both splints
// made, printable closed solids, different; the angle each reports is autorotate_mandible's on
// the jaws as the plan moves them; the same bytes every run; the report names both; an error
// leaves the arena as it was.
#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <vector>

#include "common/phantom.h"
#include "design/plan_internal.h"
#include "splintcore/design.h"
#include "splintcore/platform.h"
#include "support/phantom_jaws.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

// The phantom's arch runs round +y, the maxilla above: the condyles behind (-y) and above.
// The plan: the maxilla advanced 2 mm and impacted 1 mm, the mandible advanced 2.5 mm.
std::string phantom_plan_case(const char* sequence, const char* mandible, const char* extra = "") {
  return std::string(R"({"splintcore_case": 1, "case_id": "plan-1",)") + extra + R"(
    "jaws": [{"role": "maxilla", "mesh": "maxilla.stl"}, {"role": "mandible", "mesh": "mandible.stl"}],
    "base": {"spacing_mm": 0.5, "auto": {}},
    "plan": {"sequence": ")" +
         sequence + R"(",
      "maxilla": [1,0,0,0, 0,1,0,2, 0,0,1,1, 0,0,0,1],
      "mandible": )" +
         mandible + R"(,
      "hinge_axis": [[-50, -55, 25], [50, -55, 25]],
      "intermediate_opening_mm": 2, "final_opening_mm": 1.5}})";
}

struct PlanFixture {
  test::TestArena t{size_t{160} << 20};
  CaseFile c;
  Mesh jaws[2];
  bool ok = false;
  explicit PlanFixture(const char* sequence,
                       const char* mandible = "[1,0,0,0, 0,1,0,2.5, 0,0,1,0, 0,0,0,1]",
                       const char* extra = "", uint32_t triangles = 6000) {
    Context ctx(&t.arena);
    static std::string text;
    text = phantom_plan_case(sequence, mandible, extra);
    if (!parse_case(ctx, text.data(), text.size(), "plan", &c).is_ok()) return;
    if (!test::phantom_jaw_meshes(t.arena, triangles, jaws)) return;
    ok = true;
  }
  Span<const Mesh> span() const { return Span<const Mesh>(jaws, 2); }
};

std::vector<uint8_t> stl_bytes(Arena& arena, const Mesh& m) {
  std::vector<uint8_t> bytes;
  EXPECT_TRUE(test::mesh_to_bytes(arena, m, StlFormat::kBinary, &bytes).is_ok());
  return bytes;
}

// The same autorotation, computed here from the jaws moved as the plan says (float32, as
// design_splint moves them).
AutorotateReport autorotate_as_planned(Arena& arena, const PlanFixture& f, const RigidTransform& up,
                                       const RigidTransform& low, double opening) {
  ArenaScope scope(arena);
  Mesh moved[2];
  const RigidTransform* moves[2] = {&up, &low};
  for (int j = 0; j < 2; ++j) {
    moved[j].bind(&arena);
    for (const Vec3& v : f.jaws[j].vertices) {
      Vec3 p = moves[j]->apply_point(v);
      EXPECT_TRUE(round_to_float32(&p));
      (void)moved[j].vertices.push_back(p);
    }
    for (const Triangle& t : f.jaws[j].triangles) (void)moved[j].triangles.push_back(t);
  }
  AutorotateOptions o;
  o.hinge[0] = f.c.plan.hinge[0];
  o.hinge[1] = f.c.plan.hinge[1];
  o.opening_mm = opening;
  AutorotateReport r;
  EXPECT_TRUE(autorotate_mandible(Context(&arena), moved[0], moved[1], o, &r).is_ok());
  return r;
}

TEST(DesignPlan, MaxillaFirstGivesTwoSplintsWithTheAutorotationsAngles) {
  PlanFixture f("maxilla_first");
  ASSERT_TRUE(f.ok);
  Context ctx(&f.t.arena);
  Mesh intermediate, final_splint;
  PlanReport r;
  SPLINTCORE_ASSERT_OK(design_plan(ctx, f.c, f.span(), &intermediate, &final_splint, &r));
  // Both printable closed solids (design_splint's printer check: closed, manifold, no
  // self-intersection), each from its own automatic outline.
  for (const PlanSplintReport* p : {&r.intermediate, &r.final_splint}) {
    EXPECT_TRUE(p->design.print.printable);
    EXPECT_TRUE(p->design.self_intersection_checked);
    EXPECT_TRUE(p->design.outlined);
    EXPECT_GT(p->design.print.mesh.volume, 100.0);
  }
  EXPECT_GT(intermediate.triangles.size(), 0u);
  EXPECT_GT(final_splint.triangles.size(), 0u);
  const std::vector<uint8_t> a = stl_bytes(f.t.arena, intermediate);
  const std::vector<uint8_t> b = stl_bytes(f.t.arena, final_splint);
  EXPECT_NE(a, b);
  EXPECT_NE(r.intermediate.design.print.mesh.volume, r.final_splint.design.print.mesh.volume);

  // The moves as applied: intermediate = maxilla moved, mandible preoperative then turned;
  // final = both moved, the mandible then turned.
  const RigidTransform none;
  EXPECT_EQ(r.intermediate.maxilla.t[1], 2.0);
  const AutorotateReport ai = autorotate_as_planned(f.t.arena, f, f.c.plan.maxilla, none, 2.0);
  EXPECT_EQ(r.intermediate.autorotation.angle_rad, ai.angle_rad);  // the same bits
  EXPECT_NEAR(r.intermediate.autorotation.opening, 2.0, 1e-6);
  EXPECT_EQ(r.intermediate.angle_deg, ai.angle_rad * (180.0 / 3.14159265358979323846));
  const AutorotateReport af =
      autorotate_as_planned(f.t.arena, f, f.c.plan.maxilla, f.c.plan.mandible, 1.5);
  EXPECT_EQ(r.final_splint.autorotation.angle_rad, af.angle_rad);
  EXPECT_NEAR(r.final_splint.autorotation.opening, 1.5, 1e-6);
  EXPECT_NE(ai.angle_rad, af.angle_rad);
  const RigidTransform expected = compose(af.transform, f.c.plan.mandible);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(r.final_splint.mandible.t[i], expected.t[i]);
    for (int k = 0; k < 3; ++k) EXPECT_EQ(r.final_splint.mandible.r[i][k], expected.r[i][k]);
  }
  std::printf("intermediate: %.9f deg, %zu triangles; final: %.9f deg, %zu triangles\n",
              r.intermediate.angle_deg, intermediate.triangles.size(), r.final_splint.angle_deg,
              final_splint.triangles.size());

  // Deterministic: a second run gives the same bytes.
  {
    ArenaScope again(f.t.arena);
    Mesh i2, f2;
    PlanReport r2;
    SPLINTCORE_ASSERT_OK(design_plan(ctx, f.c, f.span(), &i2, &f2, &r2));
    EXPECT_EQ(stl_bytes(f.t.arena, i2), a);
    EXPECT_EQ(stl_bytes(f.t.arena, f2), b);
  }

  // The report: the plan, then each splint with its autorotation and output.
  std::string json;
  const ByteSink sink = test::string_sink(&json);
  DesignReportFiles files[2];
  files[0].splint_path = "intermediate.stl";
  files[1].splint_path = "final.stl";
  SPLINTCORE_ASSERT_OK(
      write_plan_report(ctx, f.c, f.span(), intermediate, final_splint, r, files, nullptr, sink));
  JsonDocument doc;
  SPLINTCORE_ASSERT_OK(parse_json(ctx, json.data(), json.size(), JsonLimits{}, "report", &doc));
  const JsonValue* plan = doc.member(doc.root(), "plan");
  ASSERT_NE(plan, nullptr);
  EXPECT_STREQ(doc.member(*plan, "sequence")->string, "maxilla_first");
  for (const char* key : {"intermediate", "final"}) {
    const JsonValue* s = doc.member(doc.root(), key);
    ASSERT_NE(s, nullptr) << key;
    const JsonValue* rot = doc.member(*s, "autorotation");
    ASSERT_NE(rot, nullptr);
    const PlanSplintReport& p = std::strcmp(key, "final") == 0 ? r.final_splint : r.intermediate;
    EXPECT_EQ(doc.member(*rot, "angle_rad")->number, p.autorotation.angle_rad);
    EXPECT_NE(doc.member(*s, "output"), nullptr);
    EXPECT_NE(doc.member(*s, "inputs"), nullptr);
  }
}

// Mandible first: the intermediate splint holds the planned mandible, turned, against the
// maxilla as before surgery; the final one is the maxilla-first plan's final splint.
// Explicit picks (fixtures/cases/paper_scale.json's, on the phantom): the base's picks serve
// both splints; the plan's "picks" give each splint its own. Given the same picks that way,
// the same bytes; the final splint given its picks moved with the jaws (the upper picks by the
// maxilla's planned move, the lower by the mandible's), the final splint changes and the
// intermediate does not.
TEST(DesignPlan, EachSplintsOwnPicksShapeItsBase) {
  PlanFixture f("maxilla_first");
  ASSERT_TRUE(f.ok);
  Context ctx(&f.t.arena);
  const std::vector<uint8_t> text =
      test::read_file_bytes(std::string(SPLINTCORE_FIXTURES_DIR) + "/cases/paper_scale.json");
  CaseFile paper;
  SPLINTCORE_ASSERT_OK(
      parse_case(ctx, reinterpret_cast<const char*>(text.data()), text.size(), "paper", &paper));
  CaseFile shared = f.c;
  shared.has_auto_outline = false;
  shared.occlusal_normal = paper.occlusal_normal;
  shared.upper = paper.upper;
  shared.lower = paper.lower;
  auto design = [&](const CaseFile& c, std::vector<uint8_t> out[2]) {
    ArenaScope scope(f.t.arena);
    Mesh intermediate, final_splint;
    PlanReport r;
    SPLINTCORE_ASSERT_OK(design_plan(ctx, c, f.span(), &intermediate, &final_splint, &r));
    EXPECT_TRUE(r.intermediate.design.print.printable);
    EXPECT_TRUE(r.final_splint.design.print.printable);
    EXPECT_FALSE(r.final_splint.design.outlined);
    out[0] = stl_bytes(f.t.arena, intermediate);
    out[1] = stl_bytes(f.t.arena, final_splint);
  };
  std::vector<uint8_t> a[2], b[2], moved[2];
  design(shared, a);
  if (HasFatalFailure()) return;

  CaseFile own = shared;
  own.upper = Span<const Pick>();
  own.lower = Span<const Pick>();
  own.plan.has_picks = true;
  for (int k = 0; k < 2; ++k) {
    own.plan.upper[k] = paper.upper;
    own.plan.lower[k] = paper.lower;
  }
  design(own, b);
  EXPECT_EQ(b[0], a[0]);
  EXPECT_EQ(b[1], a[1]);

  std::vector<Pick> up(paper.upper.begin(), paper.upper.end());
  std::vector<Pick> low(paper.lower.begin(), paper.lower.end());
  for (Pick& p : up) p.position = f.c.plan.maxilla.apply_point(p.position);
  for (Pick& p : low) p.position = f.c.plan.mandible.apply_point(p.position);
  own.plan.upper[1] = Span<const Pick>(up.data(), up.size());
  own.plan.lower[1] = Span<const Pick>(low.data(), low.size());
  design(own, moved);
  EXPECT_EQ(moved[0], a[0]);
  EXPECT_NE(moved[1], a[1]);
}

TEST(DesignPlan, MandibleFirstMovesTheMandibleFirst) {
  PlanFixture f("mandible_first", "[1,0,0,0, 0,1,0,0.5, 0,0,1,-0.5, 0,0,0,1]");
  ASSERT_TRUE(f.ok);
  Context ctx(&f.t.arena);
  Mesh intermediate, final_splint;
  PlanReport r;
  SPLINTCORE_ASSERT_OK(design_plan(ctx, f.c, f.span(), &intermediate, &final_splint, &r));
  EXPECT_EQ(r.intermediate.maxilla.t[1], 0.0);
  const RigidTransform none;
  const AutorotateReport ai = autorotate_as_planned(f.t.arena, f, none, f.c.plan.mandible, 2.0);
  EXPECT_EQ(r.intermediate.autorotation.angle_rad, ai.angle_rad);
  std::printf("mandible first: intermediate %.9f deg, final %.9f deg\n", r.intermediate.angle_deg,
              r.final_splint.angle_deg);
  EXPECT_TRUE(r.intermediate.design.print.printable);
  EXPECT_TRUE(r.final_splint.design.print.printable);
  EXPECT_NE(stl_bytes(f.t.arena, intermediate), stl_bytes(f.t.arena, final_splint));
}

// The report of a plan run as text.
std::string plan_report_json(const Context& ctx, const PlanFixture& f, const Mesh& a, const Mesh& b,
                             const PlanReport& r) {
  std::string json;
  const ByteSink sink = test::string_sink(&json);
  DesignReportFiles files[2];
  EXPECT_TRUE(write_plan_report(ctx, f.c, f.span(), a, b, r, files, nullptr, sink).is_ok());
  return json;
}

// A case "label": the intermediate splint carries "INT " and the text, the final "FIN " and the
// text, engraved as design_splint engraves one (the glyphs cut out of each splint: less
// volume, closed and checked after the label's Boolean); each report section names its text.
TEST(DesignPlan, LabelsTheSplintsIntAndFin) {
  double plain_volume[2] = {};
  {
    PlanFixture plain("maxilla_first");
    ASSERT_TRUE(plain.ok);
    Mesh a, b;
    PlanReport r;
    SPLINTCORE_ASSERT_OK(design_plan(Context(&plain.t.arena), plain.c, plain.span(), &a, &b, &r));
    EXPECT_FALSE(r.intermediate.design.labelled);
    EXPECT_STREQ(r.intermediate.label_text, "");
    plain_volume[0] = r.intermediate.design.print.mesh.volume;
    plain_volume[1] = r.final_splint.design.print.mesh.volume;
  }
  PlanFixture f("maxilla_first", "[1,0,0,0, 0,1,0,2.5, 0,0,1,0, 0,0,0,1]",
                R"( "label": {"text": "Plan-1"},)");
  ASSERT_TRUE(f.ok);
  ASSERT_TRUE(f.c.has_label);
  Context ctx(&f.t.arena);
  Mesh splints[2];
  PlanReport r;
  SPLINTCORE_ASSERT_OK(design_plan(ctx, f.c, f.span(), &splints[0], &splints[1], &r));
  const PlanSplintReport* parts[2] = {&r.intermediate, &r.final_splint};
  const char* const texts[2] = {"INT Plan-1", "FIN Plan-1"};
  const char* const stats_texts[2] = {"INT PLAN-1", "FIN PLAN-1"};  // as engraved: upper case
  for (int k = 0; k < 2; ++k) {
    SCOPED_TRACE(texts[k]);
    const DesignReport& d = parts[k]->design;
    EXPECT_STREQ(parts[k]->label_text, texts[k]);
    ASSERT_TRUE(d.labelled);
    EXPECT_STREQ(d.label.text, stats_texts[k]);
    EXPECT_EQ(d.label.glyphs, 9u);  // the space has none
    EXPECT_TRUE(d.print.printable);
    EXPECT_STREQ(d.self_intersection_checked_by, "label");
    double volume = 0;
    SPLINTCORE_ASSERT_OK(check_closed_oriented(ctx, splints[k], &volume));
    EXPECT_NEAR(volume, d.print.mesh.volume, 1e-9 * volume);
    // Engraved: the glyphs' grooves are gone, about stroke length x stroke width x depth.
    const double groove = d.label.stroke_length_mm * 0.35 * 0.4;
    const double removed = plain_volume[k] - volume;
    std::printf("%s: %.4f mm^3 removed, %.1f mm of strokes (%.4f mm^3 as straight grooves)\n",
                texts[k], removed, d.label.stroke_length_mm, groove);
    EXPECT_GT(removed, 0.5 * groove);
    EXPECT_LT(removed, 2.0 * groove);
  }
  // Each section of report.json names the text applied, in the parameters and the label's check.
  const std::string json = plan_report_json(ctx, f, splints[0], splints[1], r);
  JsonDocument doc;
  SPLINTCORE_ASSERT_OK(parse_json(ctx, json.data(), json.size(), JsonLimits{}, "report", &doc));
  const char* const keys[2] = {"intermediate", "final"};
  for (int k = 0; k < 2; ++k) {
    const JsonValue* s = doc.member(doc.root(), keys[k]);
    ASSERT_NE(s, nullptr);
    const JsonValue* params = doc.member(*s, "parameters");
    ASSERT_NE(params, nullptr);
    EXPECT_STREQ(doc.member(*params, "label_text")->string, texts[k]);
    const JsonValue* checks = doc.member(*s, "checks");
    ASSERT_NE(checks, nullptr);
    const JsonValue* label = doc.member(*checks, "label");
    ASSERT_NE(label, nullptr);
    EXPECT_STREQ(doc.member(*label, "text")->string, stats_texts[k]);
  }
  // Embossed instead: the glyphs stand out of the wall, the splints gain volume.
  {
    ArenaScope scope(f.t.arena);
    CaseFile embossed = f.c;
    embossed.label.mode = LabelMode::kEmboss;
    Mesh a, b;
    PlanReport re;
    SPLINTCORE_ASSERT_OK(design_plan(ctx, embossed, f.span(), &a, &b, &re));
    EXPECT_STREQ(re.intermediate.design.label.text, "INT PLAN-1");
    EXPECT_STREQ(re.final_splint.design.label.text, "FIN PLAN-1");
    EXPECT_GT(re.intermediate.design.print.mesh.volume, plain_volume[0]);
    EXPECT_GT(re.final_splint.design.print.mesh.volume, plain_volume[1]);
    EXPECT_TRUE(re.intermediate.design.print.printable && re.final_splint.design.print.printable);
  }
  // A text the prefix would push past 32 characters: refused by the parser and by design_plan.
  CaseFile longer = f.c;
  longer.label.text = "ABCDEFGHIJKLMNOPQRSTUVWXYZ012";  // 29
  Mesh a, b;
  const Status s = design_plan(ctx, longer, f.span(), &a, &b, &r);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(std::string(s.message()).find("plan: intermediate: label: \"INT \""), std::string::npos)
      << s.message();
  const std::string text =
      phantom_plan_case("maxilla_first", "[1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1]",
                        R"( "label": {"text": "ABCDEFGHIJKLMNOPQRSTUVWXYZ012"},)");
  CaseFile parsed;
  const Status p = parse_case(ctx, text.data(), text.size(), "plan", &parsed);
  EXPECT_EQ(p.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(std::string(p.message()).find("at most 28 characters"), std::string::npos)
      << p.message();
}

void expect_same_transform(const RigidTransform& a, const RigidTransform& b) {
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(a.t[i], b.t[i]);
    for (int k = 0; k < 3; ++k) EXPECT_EQ(a.r[i][k], b.r[i][k]);
  }
}

std::string written_case(const CaseFile& c) {
  std::string text;
  const ByteSink sink = test::string_sink(&text);
  EXPECT_TRUE(write_case(c, sink).is_ok());
  return text;
}

// write_case of a plan case: parsed again, the same plan bit for bit (a turned move and an odd
// hinge: numbers that need all 17 digits), the jaws without "transform" (which a plan case
// refuses); written again, the same text; designed, the same splints' bytes.
TEST(DesignPlan, WriteCaseRoundTripsThePlan) {
  // 0.6 and 0.8: a rotation about x whose entries are not short decimals after parsing.
  PlanFixture f("mandible_first", "[1,0,0,0.1, 0,0.8,-0.6,0.5, 0,0.6,0.8,-0.5, 0,0,0,1]");
  ASSERT_TRUE(f.ok);
  Context ctx(&f.t.arena);
  f.c.plan.hinge[0] = Vec3{-50.123456789012345, -55.1, 25.000000000000004};
  f.c.plan.intermediate_opening_mm = 1.9999999999999998;
  const std::string text = written_case(f.c);
  EXPECT_EQ(text.find("\"transform\""), std::string::npos) << text;
  CaseFile back;
  SPLINTCORE_ASSERT_OK(parse_case(ctx, text.data(), text.size(), "written", &back));
  ASSERT_TRUE(back.has_plan);
  EXPECT_EQ(back.plan.mandible_first, f.c.plan.mandible_first);
  expect_same_transform(back.plan.maxilla, f.c.plan.maxilla);
  expect_same_transform(back.plan.mandible, f.c.plan.mandible);
  for (int e = 0; e < 2; ++e) {
    for (int i = 0; i < 3; ++i) EXPECT_EQ(back.plan.hinge[e][i], f.c.plan.hinge[e][i]);
  }
  EXPECT_EQ(back.plan.intermediate_opening_mm, f.c.plan.intermediate_opening_mm);
  EXPECT_EQ(back.plan.final_opening_mm, f.c.plan.final_opening_mm);
  EXPECT_STREQ(back.case_id, f.c.case_id);
  EXPECT_EQ(back.has_auto_outline, f.c.has_auto_outline);
  EXPECT_EQ(written_case(back), text);
  // The maxilla-first plan of the other tests, written and read back, designs the same bytes.
  PlanFixture g("maxilla_first");
  ASSERT_TRUE(g.ok);
  const std::string gtext = written_case(g.c);
  CaseFile gback;
  SPLINTCORE_ASSERT_OK(parse_case(ctx, gtext.data(), gtext.size(), "written", &gback));
  Mesh a[2], b[2];
  PlanReport ra, rb;
  SPLINTCORE_ASSERT_OK(design_plan(ctx, g.c, g.span(), &a[0], &a[1], &ra));
  SPLINTCORE_ASSERT_OK(design_plan(ctx, gback, g.span(), &b[0], &b[1], &rb));
  for (int k = 0; k < 2; ++k) {
    EXPECT_EQ(stl_bytes(f.t.arena, a[k]), stl_bytes(f.t.arena, b[k])) << k;
  }
}

// A tetrahedron `size` mm across, float32-exact.
Mesh job_tetra(Arena& arena, double size) {
  Mesh m(&arena);
  const Vec3 v[4] = {{0, 0, 0}, {size, 0, 0}, {0, size, 0}, {0, 0, size / 2}};
  for (const Vec3& p : v) (void)m.vertices.push_back(p);
  const Triangle t[4] = {{{0, 2, 1}}, {{0, 1, 3}}, {{1, 2, 3}}, {{2, 0, 3}}};
  for (const Triangle& x : t) (void)m.triangles.push_back(x);
  return m;
}

// write_plan_job on small parts: the hashes given are the ones it would compute (the same
// bytes), other hashes give other bytes; an unknown printer, an empty splint, parts that do
// not fit the tray side by side and a sink that refuses are errors, the arena as it was.
TEST(DesignPlan, PrintJobHashesAndErrors) {
  test::TestArena t{size_t{8} << 20};
  const Context ctx(&t.arena);
  CaseFile c;
  c.case_id = "job-1";
  const Mesh a = job_tetra(t.arena, 20), b = job_tetra(t.arena, 30);
  std::string computed, given, other;
  Vec3 moves[2];
  SPLINTCORE_ASSERT_OK(write_plan_job(ctx, c, a, b, nullptr, test::string_sink(&computed), moves));
  EXPECT_GE(moves[1].x - moves[0].x, 20 + kPlanJobGapMm);  // a's box is 20 mm wide
  char hashes[2][65];
  SPLINTCORE_ASSERT_OK(splint_stl_sha256(ctx, a, hashes[0]));
  SPLINTCORE_ASSERT_OK(splint_stl_sha256(ctx, b, hashes[1]));
  const char* const right[2] = {hashes[0], hashes[1]};
  SPLINTCORE_ASSERT_OK(write_plan_job(ctx, c, a, b, right, test::string_sink(&given), nullptr));
  EXPECT_EQ(given, computed);
  const char* const swapped[2] = {hashes[1], hashes[0]};
  SPLINTCORE_ASSERT_OK(write_plan_job(ctx, c, a, b, swapped, test::string_sink(&other), nullptr));
  EXPECT_NE(other, computed);

  const Mesh wide = job_tetra(t.arena, 200);  // two of them: 405 mm, the tray 255
  const size_t used = t.arena.used();
  std::string unused;
  CaseFile unknown = c;
  unknown.printer = "nope";
  Status s = write_plan_job(ctx, unknown, a, b, nullptr, test::string_sink(&unused), nullptr);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(std::string(s.message()).find("nope"), std::string::npos) << s.message();
  s = write_plan_job(ctx, c, a, Mesh(), nullptr, test::string_sink(&unused), nullptr);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(std::string(s.message()).find("final splint is empty"), std::string::npos);
  s = write_plan_job(ctx, c, wide, wide, nullptr, test::string_sink(&unused), nullptr);
  EXPECT_EQ(s.code(), StatusCode::kLimitExceeded) << test::format(s);
  ByteSink refuse;
  refuse.write = [](void*, const uint8_t*, size_t) { return false; };
  s = write_plan_job(ctx, c, a, b, nullptr, refuse, nullptr);
  EXPECT_EQ(s.code(), StatusCode::kIoError) << test::format(s);
  EXPECT_EQ(t.arena.used(), used);
}

// write_splint_job: one splint's package, in exactly splint_job_bound(); the hash given is the
// one it would compute (the same bytes); its object is named by the case id, "splint" without
// one; an empty splint and an unknown printer are errors, the arena as it was.
TEST(DesignPlan, OneSplintsPrintJob) {
  test::TestArena t{size_t{4} << 20};
  const Context ctx(&t.arena);
  CaseFile c;
  c.case_id = "one-1";
  const Mesh a = job_tetra(t.arena, 20);
  std::string computed, given, unnamed;
  {
    test::TestArena exact{static_cast<size_t>(splint_job_bound(c, a))};
    Vec3 move;
    SPLINTCORE_ASSERT_OK(write_splint_job(Context(&exact.arena), c, a, nullptr,
                                          test::string_sink(&computed), &move));
    EXPECT_GE(move.x + 0.0, 0.0);  // placed on the tray, whose corner is the origin
    EXPECT_EQ(exact.arena.used(), 0u);
  }
  char hash[65];
  SPLINTCORE_ASSERT_OK(splint_stl_sha256(ctx, a, hash));
  SPLINTCORE_ASSERT_OK(write_splint_job(ctx, c, a, hash, test::string_sink(&given), nullptr));
  EXPECT_EQ(given, computed);
  CaseFile no_id = c;
  no_id.case_id = "";
  SPLINTCORE_ASSERT_OK(write_splint_job(ctx, no_id, a, hash, test::string_sink(&unnamed), nullptr));
  EXPECT_NE(unnamed, computed);  // another object name and no case id metadata
  const size_t used = t.arena.used();
  std::string unused;
  Status s = write_splint_job(ctx, c, Mesh(), nullptr, test::string_sink(&unused), nullptr);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(std::string(s.message()).find("the splint is empty"), std::string::npos) << s.message();
  CaseFile unknown = c;
  unknown.printer = "nope";
  s = write_splint_job(ctx, unknown, a, nullptr, test::string_sink(&unused), nullptr);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(t.arena.used(), used);
}

TEST(DesignPlan, ErrorsLeaveTheArenaAsItWas) {
  PlanFixture f("maxilla_first");
  ASSERT_TRUE(f.ok);
  Mesh a, b;
  PlanReport r;
  // Not a plan case.
  CaseFile no_plan = f.c;
  no_plan.has_plan = false;
  Status s = design_plan(Context(&f.t.arena), no_plan, f.span(), &a, &b, &r);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  // design_splint of a plan case: refused (its jaws are the preoperative ones).
  Mesh single;
  DesignReport single_report;
  s = design_splint(Context(&f.t.arena), f.c, f.span(), &single, &single_report);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(std::string(s.message()).find("design_plan makes its two splints"), std::string::npos);
  // One mesh for two jaws.
  s = design_plan(Context(&f.t.arena), f.c, Span<const Mesh>(f.jaws, 1), &a, &b, &r);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument) << test::format(s);
  // An opening the jaws cannot reach: named for the splint and the stage.
  CaseFile far = f.c;
  far.plan.hinge[0] = Vec3{0, 0, -50};  // a vertical axis: no closing sense
  far.plan.hinge[1] = Vec3{0, 0, 50};
  const size_t used = f.t.arena.used();
  s = design_plan(Context(&f.t.arena), far, f.span(), &a, &b, &r);
  EXPECT_NE(s.code(), StatusCode::kOk);
  EXPECT_NE(std::string(s.message()).find("plan: intermediate: autorotation: "), std::string::npos)
      << s.message();
  EXPECT_EQ(f.t.arena.used(), used);
  // The memory contract (design_plan has no bound of its own: design_splint has none): in
  // exactly the arena a first run took it gives the same splints; one byte less fails cleanly,
  // the arena as it was and both meshes empty.
  uint64_t need = 0;
  std::vector<uint8_t> first;
  {
    test::TestArena big{size_t{64} << 20};
    SPLINTCORE_ASSERT_OK(design_plan(Context(&big.arena), f.c, f.span(), &a, &b, &r));
    need = big.arena.high_water();
    first = stl_bytes(f.t.arena, b);
    a = Mesh{};
    b = Mesh{};
  }
  {
    test::TestArena exact{static_cast<size_t>(need)};
    SPLINTCORE_ASSERT_OK(design_plan(Context(&exact.arena), f.c, f.span(), &a, &b, &r));
    EXPECT_EQ(stl_bytes(f.t.arena, b), first);
    a = Mesh{};
    b = Mesh{};
  }
  test::TestArena small{static_cast<size_t>(need - 1)};
  s = design_plan(Context(&small.arena), f.c, f.span(), &a, &b, &r);
  EXPECT_EQ(s.code(), StatusCode::kArenaExhausted) << test::format(s);
  EXPECT_EQ(small.arena.used(), 0u);
  EXPECT_TRUE(a.triangles.empty() && b.triangles.empty());
  std::printf("design_plan on the 6000-triangle phantom: %llu arena bytes\n",
              static_cast<unsigned long long>(need));
}

// The same bits: EXPECT_EQ on doubles would take -0 for +0.
uint64_t bits(double x) {
  uint64_t u = 0;
  std::memcpy(&u, &x, sizeof u);
  return u;
}

void expect_same_autorotation(const AutorotateReport& a, const AutorotateReport& b) {
  EXPECT_EQ(bits(a.angle_rad), bits(b.angle_rad));
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(bits(a.transform.t[i]), bits(b.transform.t[i]));
    for (int k = 0; k < 3; ++k) EXPECT_EQ(bits(a.transform.r[i][k]), bits(b.transform.r[i][k]));
    EXPECT_EQ(bits(a.contact_maxilla[i]), bits(b.contact_maxilla[i]));
    EXPECT_EQ(bits(a.contact_mandible[i]), bits(b.contact_mandible[i]));
  }
  EXPECT_EQ(a.closing_sign, b.closing_sign);
  EXPECT_EQ(bits(a.gap_as_given), bits(b.gap_as_given));
  EXPECT_EQ(a.met_as_given, b.met_as_given);
  EXPECT_EQ(bits(a.start_angle_rad), bits(b.start_angle_rad));
  EXPECT_EQ(bits(a.opening), bits(b.opening));
  EXPECT_EQ(bits(a.bracket_rad), bits(b.bracket_rad));
  EXPECT_EQ(bits(a.lever_mm), bits(b.lever_mm));
  EXPECT_EQ(a.steps, b.steps);
  EXPECT_EQ(a.triangle_maxilla, b.triangle_maxilla);
  EXPECT_EQ(a.triangle_mandible, b.triangle_mandible);
}

// At 1, 2 and 3 threads (the autorotations serial, then in tasks, in either sequence: a
// different jaw shared by both splints' moves): the same splints, print job, report and
// autorotations, bit for bit; an opening the jaws cannot reach gives the same error.
TEST(DesignPlan, SameBytesAndAutorotationsAtOneTwoAndThreeThreads) {
  for (const char* sequence : {"maxilla_first", "mandible_first"}) {
    const bool maxilla_first = std::strcmp(sequence, "maxilla_first") == 0;
    PlanFixture f(sequence, maxilla_first ? "[1,0,0,0, 0,1,0,2.5, 0,0,1,0, 0,0,0,1]"
                                          : "[1,0,0,0, 0,1,0,0.5, 0,0,1,-0.5, 0,0,0,1]");
    ASSERT_TRUE(f.ok);
    std::string first[4];
    PlanReport first_report;
    std::string first_error;
    for (unsigned threads = 1; threads <= 3; ++threads) {
      ThreadExecutor pool(threads);
      const Context ctx(&f.t.arena, &pool.executor(), nullptr);
      ArenaScope scope(f.t.arena);
      Mesh a, b;
      PlanReport r;
      SPLINTCORE_ASSERT_OK(design_plan(ctx, f.c, f.span(), &a, &b, &r));
      std::string out[4] = {std::string(), std::string(), std::string(),
                            plan_report_json(ctx, f, a, b, r)};
      const std::vector<uint8_t> sa = stl_bytes(f.t.arena, a), sb = stl_bytes(f.t.arena, b);
      out[0].assign(sa.begin(), sa.end());
      out[1].assign(sb.begin(), sb.end());
      SPLINTCORE_ASSERT_OK(
          write_plan_job(ctx, f.c, a, b, nullptr, test::string_sink(&out[2]), nullptr));
      CaseFile far = f.c;
      far.plan.hinge[0] = Vec3{0, 0, -50};  // a vertical axis: no closing sense
      far.plan.hinge[1] = Vec3{0, 0, 50};
      Mesh c, d;
      PlanReport unused;
      const size_t used = f.t.arena.used();
      const Status s = design_plan(ctx, far, f.span(), &c, &d, &unused);
      EXPECT_EQ(f.t.arena.used(), used);
      const std::string error = test::format(s);
      EXPECT_NE(error.find("plan: intermediate: autorotation: "), std::string::npos) << error;
      if (threads == 1) {
        for (int i = 0; i < 4; ++i) first[i] = out[i];
        first_report = r;
        first_error = error;
        continue;
      }
      for (int i = 0; i < 4; ++i) EXPECT_TRUE(out[i] == first[i]) << sequence << " " << i;
      expect_same_autorotation(r.intermediate.autorotation, first_report.intermediate.autorotation);
      expect_same_autorotation(r.final_splint.autorotation, first_report.final_splint.autorotation);
      EXPECT_EQ(error, first_error);
    }
    EXPECT_FALSE(first[0].empty() || first[2].empty() || first[3].empty());
  }
}

// plan_autorotations in tasks: each task in its slice, which takes more of the arena than the
// serial order at its peak; in exactly that peak the tasks run (the same peak again), and in
// every smaller arena down to the serial peak the serial order takes over for what does not
// fit: always the same answers, nothing left in the arena. Too small for the serial order: its
// error, to the byte. On the 6000-triangle phantom the autorotations' slices are what stops
// fitting first (the indexes stay those the tasks built), on the 60000-triangle one the
// indexes' slices (all serial).
void autorotations_in_tasks_or_serially(uint32_t triangles) {
  PlanFixture f("maxilla_first", "[1,0,0,0, 0,1,0,2.5, 0,0,1,0, 0,0,0,1]", "", triangles);
  ASSERT_TRUE(f.ok);
  ThreadExecutor two(2);
  struct Run {
    PlanReport r;
    Status status[2];
    size_t peak = 0;
  };
  auto run = [&](size_t cap, const Executor* executor, Run* out) {
    test::TestArena t{cap};
    design_detail::plan_autorotations(Context(&t.arena, executor, nullptr), f.c, f.span(),
                                      design_detail::PlanFusion{}, &out->r, out->status);
    EXPECT_EQ(t.arena.used(), 0u);
    out->peak = t.arena.high_water();
  };
  auto expect_same = [](const Run& a, const Run& b) {
    for (int k = 0; k < 2; ++k) {
      EXPECT_EQ(a.status[k].code(), b.status[k].code());
      EXPECT_EQ(test::format(a.status[k]), test::format(b.status[k]));
    }
    expect_same_autorotation(a.r.intermediate.autorotation, b.r.intermediate.autorotation);
    expect_same_autorotation(a.r.final_splint.autorotation, b.r.final_splint.autorotation);
    EXPECT_EQ(bits(a.r.final_splint.opening_asked_mm), bits(b.r.final_splint.opening_asked_mm));
    EXPECT_EQ(bits(a.r.final_splint.mandible.t[1]), bits(b.r.final_splint.mandible.t[1]));
  };
  Run serial, tasks;
  run(size_t{64} << 20, nullptr, &serial);
  SPLINTCORE_ASSERT_OK(serial.status[0]);
  SPLINTCORE_ASSERT_OK(serial.status[1]);
  run(size_t{64} << 20, &two.executor(), &tasks);
  expect_same(tasks, serial);
  ASSERT_GT(tasks.peak, serial.peak);  // the slices: the tasks ran
  Run exact;
  run(tasks.peak, &two.executor(), &exact);
  expect_same(exact, serial);
  EXPECT_EQ(exact.peak, tasks.peak);
  for (int i = 1; i <= 12; ++i) {
    const size_t cap = tasks.peak - (tasks.peak - serial.peak) * static_cast<size_t>(i) / 12;
    Run smaller;
    run(cap, &two.executor(), &smaller);
    expect_same(smaller, serial);
    EXPECT_LE(smaller.peak, cap);
  }
  // (The peak is not the least arena that does: arrays grow by more than they need when they
  // can.)
  Run short_serial, short_tasks;
  run(serial.peak / 2, nullptr, &short_serial);
  run(serial.peak / 2, &two.executor(), &short_tasks);
  EXPECT_EQ(short_serial.status[0].code(), StatusCode::kArenaExhausted);
  expect_same(short_tasks, short_serial);
  std::printf(
      "plan_autorotations on the %u-triangle phantom: %zu arena bytes serial, %zu in tasks\n",
      triangles, serial.peak, tasks.peak);
}

TEST(DesignPlan, AutorotationsInTasksFitTheirSlicesOrRunSerially) {
  autorotations_in_tasks_or_serially(6000);
  autorotations_in_tasks_or_serially(60000);
}

}  // namespace
}  // namespace splintcore
