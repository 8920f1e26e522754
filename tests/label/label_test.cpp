// The case label (src/label/label.cpp, stroke_font.cpp): the font's glyphs stay in their
// cells; unsupported characters are named; engraving and embossing on the paper-scale base
// give valid solids whose volume changes by about the strokes' volume; the text reads left to
// right from outside whatever the pick order; the same bytes twice; clean arena exhaustion;
// text that does not fit is an error.
#include <algorithm>
#include <cmath>
#include <set>
#include <string>
#include <vector>

#include "splintcore/design.h"
#include "splintcore/label.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

using test::TestArena;

// The paper-scale case's base and lines, built once.
struct Fixture {
  TestArena t{size_t{64} << 20};
  CaseFile c;
  Mesh base;
  BaseReport base_report;
  ArenaArray<Line> upper, lower;
  double volume = 0;
  bool ok = false;
  Fixture() {
    Context ctx(&t.arena);
    static std::vector<uint8_t> text;
    text = test::read_file_bytes(std::string(SPLINTCORE_FIXTURES_DIR) + "/cases/paper_scale.json");
    if (!parse_case(ctx, reinterpret_cast<const char*>(text.data()), text.size(), "paper_scale", &c)
             .is_ok()) {
      return;
    }
    upper.bind(&t.arena);
    lower.bind(&t.arena);
    if (!make_lines(ctx, c.upper, c.occlusal_normal, "upper", &upper).is_ok() ||
        !make_lines(ctx, c.lower, c.occlusal_normal, "lower", &lower).is_ok()) {
      return;
    }
    base.bind(&t.arena);
    if (!build_case_base(ctx, c, &base, &base_report).is_ok()) return;
    ok = check_closed_oriented(ctx, base, &volume).is_ok();
  }
};

Fixture& fixture() {
  static Fixture f;
  return f;
}

// Total stroke length of `text` in grid units, from the font.
double stroke_units(const char* text) {
  double sum = 0;
  for (const char* p = text; *p != '\0'; ++p) {
    StrokeGlyph g;
    if (!stroke_font_glyph(*p, &g)) return -1;
    uint32_t first = 0;
    for (uint32_t s = 0; s < g.stroke_count; ++s) {
      for (uint32_t k = first; k + 1 < g.stroke_end[s]; ++k) {
        const double dx = g.points[k + 1].x - g.points[k].x;
        const double dy = g.points[k + 1].y - g.points[k].y;
        sum += std::sqrt(dx * dx + dy * dy);
      }
      first = g.stroke_end[s];
    }
  }
  return sum;
}

struct Labelled {
  Status status;
  Mesh mesh;
  LabelStats stats;
};

Labelled run(TestArena& t, const LabelOptions& o, bool apply = true,
             Span<const Line> upper = Span<const Line>(),
             Span<const Line> lower = Span<const Line>()) {
  Fixture& f = fixture();
  if (upper.empty()) {
    upper = f.upper.span();
    lower = f.lower.span();
  }
  Labelled l;
  Context ctx(&t.arena);
  l.mesh.bind(&t.arena);
  l.status = apply ? apply_label(ctx, f.base, upper, lower, o, &l.mesh, &l.stats)
                   : build_label_mesh(ctx, f.base, upper, lower, o, &l.mesh, &l.stats);
  return l;
}

MeshReport report_of(TestArena& t, const Mesh& m) {
  MeshReport r;
  Context ctx(&t.arena);
  Status s = check_mesh(ctx, m, &r);
  EXPECT_TRUE(s.is_ok()) << test::format(s);
  return r;
}

// ---------------------------------------------------------------------------------------------
// The font.

TEST(LabelFont, EveryCharacterHasStrokesInItsCell) {
  const std::string chars = stroke_font_characters();
  EXPECT_EQ(chars.size(), 26u + 10u + 1u + 9u);
  for (char c = 'A'; c <= 'Z'; ++c) EXPECT_NE(chars.find(c), std::string::npos) << c;
  for (char c = '0'; c <= '9'; ++c) EXPECT_NE(chars.find(c), std::string::npos) << c;
  for (char c : std::string(" -_./#+():")) EXPECT_NE(chars.find(c), std::string::npos) << c;
  std::set<char> seen;
  for (char c : chars) {
    EXPECT_TRUE(seen.insert(c).second) << "listed twice: " << c;
    StrokeGlyph g;
    ASSERT_TRUE(stroke_font_glyph(c, &g)) << c;
    EXPECT_EQ(g.character, c);
    EXPECT_LE(g.width, kStrokeFontMaxWidth) << c;
    EXPECT_EQ(g.advance, g.width + kStrokeFontGap) << c;
    EXPECT_GE(g.advance - g.width, kStrokeFontGap) << c;  // the gap that keeps glyphs apart
    if (c == ' ') {
      EXPECT_EQ(g.stroke_count, 0u);
      continue;
    }
    EXPECT_GE(g.stroke_count, 1u) << c;
    EXPECT_LE(g.stroke_count, kStrokeGlyphMaxStrokes) << c;
    uint32_t previous = 0;
    for (uint32_t s = 0; s < g.stroke_count; ++s) {
      EXPECT_GT(g.stroke_end[s], previous) << c << " stroke " << s << " is empty";
      previous = g.stroke_end[s];
    }
    EXPECT_EQ(previous, g.point_count) << c;
    int xmax = 0;
    for (uint32_t k = 0; k < g.point_count; ++k) {
      EXPECT_GE(g.points[k].x, 0) << c;
      EXPECT_LE(g.points[k].x, g.width) << c;
      EXPECT_GE(g.points[k].y, 0) << c;
      EXPECT_LE(g.points[k].y, kStrokeFontHeight) << c;
      xmax = std::max<int>(xmax, g.points[k].x);
    }
    EXPECT_EQ(xmax, g.width) << c << ": the width is the strokes' extent";
    if (c >= 'A' && c <= 'Z') {
      StrokeGlyph lower;
      ASSERT_TRUE(stroke_font_glyph(static_cast<char>(c - 'A' + 'a'), &lower));
      EXPECT_EQ(lower.character, c);
      EXPECT_EQ(lower.point_count, g.point_count);
    }
  }
  StrokeGlyph g;
  for (char c : std::string("%@!?*=,;\"'<>[]{}|\\~`$&^"))
    EXPECT_FALSE(stroke_font_glyph(c, &g)) << c;
  EXPECT_FALSE(stroke_font_glyph('\0', &g));
  EXPECT_FALSE(stroke_font_glyph(static_cast<char>(0xc3), &g));
}

// ---------------------------------------------------------------------------------------------
// Errors.

TEST(LabelTest, UnsupportedCharacterIsNamed) {
  ASSERT_TRUE(fixture().ok);
  TestArena t(size_t{16} << 20);
  LabelOptions o;
  o.text = "AB%1";
  Labelled l = run(t, o);
  EXPECT_EQ(l.status.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(std::string(l.status.message()).find("'%'"), std::string::npos) << l.status.message();
  EXPECT_NE(std::string(l.status.message()).find("index 2"), std::string::npos);
  EXPECT_EQ(l.status.index(), 2u);
  EXPECT_EQ(t.arena.used(), 0u);
  EXPECT_TRUE(l.mesh.vertices.empty() && l.mesh.triangles.empty());

  o.text = "ab\xc3\xa9";  // UTF-8 e-acute: its first byte is named
  l = run(t, o);
  EXPECT_EQ(l.status.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(std::string(l.status.message()).find("byte 195 at index 2"), std::string::npos)
      << l.status.message();

  o.text = "";
  EXPECT_EQ(run(t, o).status.code(), StatusCode::kInvalidArgument);
  o.text = "   ";
  l = run(t, o);
  EXPECT_NE(std::string(l.status.message()).find("nothing to write"), std::string::npos);
  const std::string long_text(kLabelMaxCharacters + 1, 'A');
  o.text = long_text.c_str();
  l = run(t, o);
  EXPECT_EQ(l.status.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(std::string(l.status.message()).find("longer than 32"), std::string::npos);
  EXPECT_EQ(t.arena.used(), 0u);
}

// o placed explicitly: normal +y, up +z (valid); for a test to spoil one part.
LabelOptions& placed_explicitly(LabelOptions& o) {
  o.placement = LabelPlacement::kExplicit;
  o.normal = Vec3{0, 1, 0};
  o.up = Vec3{0, 0, 1};
  return o;
}

TEST(LabelTest, OptionsOutOfRangeAreErrors) {
  ASSERT_TRUE(fixture().ok);
  TestArena t(size_t{16} << 20);
  // The status of "A1" with the options `edit` sets; the arena as it was.
  auto status = [&](void (*edit)(LabelOptions&)) {
    LabelOptions o;
    o.text = "A1";
    edit(o);
    Labelled l = run(t, o, false);
    EXPECT_EQ(t.arena.used(), 0u);
    return l.status;
  };
  auto code = [&](void (*edit)(LabelOptions&)) { return status(edit).code(); };
  EXPECT_EQ(code([](LabelOptions& o) { o.height_mm = 0; }), StatusCode::kInvalidArgument);
  EXPECT_EQ(code([](LabelOptions& o) { o.height_mm = NAN; }), StatusCode::kInvalidArgument);
  EXPECT_EQ(code([](LabelOptions& o) { o.stroke_width_mm = 1.0; }), StatusCode::kInvalidArgument);
  EXPECT_EQ(code([](LabelOptions& o) { o.depth_mm = -0.1; }), StatusCode::kInvalidArgument);
  EXPECT_EQ(code([](LabelOptions& o) { o.voxel_mm = 0.5; }), StatusCode::kInvalidArgument);
  EXPECT_EQ(code([](LabelOptions& o) { o.wall_margin_mm = -1; }), StatusCode::kInvalidArgument);
  EXPECT_EQ(code([](LabelOptions& o) {
              o.placement = LabelPlacement::kExplicit;
              o.normal = Vec3{0, 1, 0};
              o.up = Vec3{0, 2, 0};
            }),
            StatusCode::kInvalidArgument);
  // Each bound's other side and NaN, refused by the check of that very option (its message).
  auto refusal = [&](void (*edit)(LabelOptions&)) {
    const Status s = status(edit);
    EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
    return std::string(s.message());
  };
  auto starts = [](const std::string& text, const char* prefix) {
    return text.rfind(prefix, 0) == 0;
  };
  EXPECT_PRED2(starts, refusal([](LabelOptions& o) { o.height_mm = 20.5; }), "label: height");
  EXPECT_PRED2(starts, refusal([](LabelOptions& o) { o.stroke_width_mm = NAN; }),
               "label: stroke width");
  EXPECT_PRED2(starts, refusal([](LabelOptions& o) { o.stroke_width_mm = 0; }),
               "label: stroke width");
  EXPECT_PRED2(starts, refusal([](LabelOptions& o) { o.depth_mm = NAN; }), "label: depth");
  EXPECT_PRED2(starts, refusal([](LabelOptions& o) { o.depth_mm = 0; }), "label: depth");
  EXPECT_PRED2(starts, refusal([](LabelOptions& o) { o.depth_mm = 5.01; }), "label: depth");
  EXPECT_PRED2(starts, refusal([](LabelOptions& o) { o.voxel_mm = NAN; }), "label: voxel");
  EXPECT_PRED2(starts, refusal([](LabelOptions& o) { o.wall_margin_mm = NAN; }),
               "label: wall margin");
  EXPECT_PRED2(starts, refusal([](LabelOptions& o) { o.wall_margin_mm = 5.01; }),
               "label: wall margin");
  // Explicit placement (normal +y, up +z) with one part bad.
  for (void (*edit)(LabelOptions&) : {
           +[](LabelOptions& o) { placed_explicitly(o).position.y = NAN; },
           +[](LabelOptions& o) { placed_explicitly(o).normal.x = NAN; },
           +[](LabelOptions& o) {
             placed_explicitly(o).normal = Vec3{0, 0, 0};
           },
           +[](LabelOptions& o) { placed_explicitly(o).up.z = NAN; },
       }) {
    EXPECT_PRED2(starts, refusal(edit), "label: explicit placement needs");
  }
  // Lists that do not pair up.
  Fixture& f = fixture();
  LabelOptions o;
  o.text = "A";
  Labelled l = run(t, o, false, f.upper.span(), f.lower.span().subspan(0, 5));
  EXPECT_EQ(l.status.code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(t.arena.used(), 0u);
}

// The refusals of the lines, the options' enums and the meshes, each by its text (and the
// line as the status's index), the arena as it was: one line per list, a non-finite line, two
// lines with the same outside points, a mode or placement outside the enums, a splint with no
// triangles, an output that is not empty; and the modes' names.
TEST(LabelTest, LinesEnumsAndMeshesTheLabelRefusesAreNamed) {
  Fixture& f = fixture();
  ASSERT_TRUE(f.ok);
  TestArena t(size_t{16} << 20);
  LabelOptions o;
  o.text = "A1";
  auto message = [&](const Labelled& l) {
    EXPECT_EQ(t.arena.used(), 0u);
    EXPECT_TRUE(l.mesh.vertices.empty() && l.mesh.triangles.empty());
    return std::string(l.status.message());
  };
  Labelled l = run(t, o, false, f.upper.span().subspan(0, 1), f.lower.span().subspan(0, 1));
  EXPECT_EQ(l.status.code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(message(l), "label: automatic placement needs at least 2 lines in each list, got 1");

  std::vector<Line> upper(f.upper.begin(), f.upper.end()), lower(f.lower.begin(), f.lower.end());
  auto lines = [](const std::vector<Line>& v) { return Span<const Line>(v.data(), v.size()); };
  {
    std::vector<Line> bad = lower;
    bad[3].inner.z = std::nan("");
    l = run(t, o, false, lines(upper), lines(bad));
    EXPECT_EQ(message(l), "label: line 3 has a coordinate that is not finite");
    EXPECT_EQ(l.status.index(), 3u);
  }
  {
    std::vector<Line> bad = upper;
    bad[5].outside = bad[4].outside;
    bad[5].inner = bad[4].inner;
    l = run(t, o, true, lines(bad), lines(lower));
    EXPECT_EQ(message(l),
              "label: lines 4 and 5 have the same outside points; the wall's curve is undefined "
              "there");
    EXPECT_EQ(l.status.index(), 4u);
  }
  {
    LabelOptions bad = o;
    bad.mode = static_cast<LabelMode>(7);
    EXPECT_EQ(message(run(t, bad)), "label: unknown mode");
    bad = o;
    bad.placement = static_cast<LabelPlacement>(7);
    EXPECT_EQ(message(run(t, bad)), "label: unknown placement");
  }
  Context ctx(&t.arena);
  {
    Mesh none(&t.arena);
    Labelled e;
    e.mesh.bind(&t.arena);
    e.status = apply_label(ctx, none, f.upper.span(), f.lower.span(), o, &e.mesh, &e.stats);
    EXPECT_EQ(e.status.code(), StatusCode::kInvalidMesh);
    EXPECT_EQ(message(e), "label: the splint has no triangles");
  }
  {
    TestArena held(size_t{1} << 20);
    Mesh full(&held.arena);
    ASSERT_TRUE(full.triangles.push_back(Triangle{{0, 1, 2}}));
    for (bool apply : {false, true}) {
      const Status s =
          apply ? apply_label(ctx, f.base, f.upper.span(), f.lower.span(), o, &full, nullptr)
                : build_label_mesh(ctx, f.base, f.upper.span(), f.lower.span(), o, &full, nullptr);
      EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
      EXPECT_STREQ(s.message(), "label: the output mesh must be empty");
      EXPECT_EQ(full.triangles.size(), 1u);
      EXPECT_EQ(t.arena.used(), 0u);
    }
  }
  EXPECT_STREQ(label_mode_name(LabelMode::kEngrave), "engrave");
  EXPECT_STREQ(label_mode_name(LabelMode::kEmboss), "emboss");
}

TEST(LabelTest, TextTooTallForTheWallIsAnError) {
  ASSERT_TRUE(fixture().ok);
  TestArena t(size_t{64} << 20);
  LabelOptions o;
  o.text = "AB12";
  o.height_mm = 4.0;  // the paper-scale wall is about 3.3 mm high
  Labelled l = run(t, o);
  EXPECT_EQ(l.status.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(std::string(l.status.message()).find("does not fit on the outer wall"),
            std::string::npos)
      << l.status.message();
  EXPECT_NE(std::string(l.status.message()).find("high"), std::string::npos);
  EXPECT_EQ(t.arena.used(), 0u);
  EXPECT_TRUE(l.mesh.vertices.empty() && l.mesh.triangles.empty());
}

TEST(LabelTest, TextTooLongForTheArchIsAnError) {
  Fixture& f = fixture();
  ASSERT_TRUE(f.ok);
  TestArena t(size_t{64} << 20);
  LabelOptions o;
  o.text = "CASE-0001";  // about 22.8 mm; the middle pick interval is about 7 mm
  Labelled l = run(t, o, true, f.upper.span().subspan(6, 2), f.lower.span().subspan(6, 2));
  EXPECT_EQ(l.status.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(std::string(l.status.message()).find("does not fit on the outer wall"),
            std::string::npos)
      << l.status.message();
  EXPECT_EQ(t.arena.used(), 0u);
}

TEST(LabelTest, RayThatMissesTheSplintIsAnError) {
  ASSERT_TRUE(fixture().ok);
  TestArena t(size_t{64} << 20);
  LabelOptions o;
  o.text = "A";
  o.placement = LabelPlacement::kExplicit;
  o.position = Vec3{0, 80, 0};  // far in front of the arch
  o.normal = Vec3{0, 1, 0};
  o.up = Vec3{0, 0, 1};
  Labelled l = run(t, o);
  EXPECT_EQ(l.status.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(std::string(l.status.message()).find("meets no part of the splint"), std::string::npos)
      << l.status.message();
  EXPECT_EQ(t.arena.used(), 0u);
}

// On the front of the arch the wall is convex: glyphs cut 5 mm deep meet below the surface (the
// message names the depth among what to change); 3 mm deep they stay apart.
TEST(LabelTest, GlyphsThatWouldMeetOnABendAreRefused) {
  ASSERT_TRUE(fixture().ok);
  for (const double depth : {5.0, 3.0}) {
    TestArena t(size_t{256} << 20);
    LabelOptions o;
    o.text = "WWWW";
    o.depth_mm = depth;
    Labelled l = run(t, o, false);
    if (depth == 3.0) {
      EXPECT_TRUE(l.status.is_ok()) << l.status.message();
      continue;
    }
    EXPECT_EQ(l.status.code(), StatusCode::kInvalidArgument);
    EXPECT_STREQ(l.status.message(),
                 "label: glyphs 0 ('W') and 1 ('W') would touch; the wall bends too sharply for "
                 "this text: use a smaller height, stroke width or depth");
    EXPECT_EQ(l.status.index(), 0u);
    EXPECT_EQ(t.arena.used(), 0u);
  }
}

// A 20 mm glyph at the finest voxel the options take (the stroke width / 32) would need 312
// million samples: refused before any is taken, the character named.
TEST(LabelTest, GlyphWithTooManySamplesIsRefused) {
  ASSERT_TRUE(fixture().ok);
  TestArena t(size_t{64} << 20);
  LabelOptions o;
  o.text = "W";
  o.placement = LabelPlacement::kExplicit;
  o.position = Vec3{27.9, 3.7, 0};
  o.normal = Vec3{1, 0, 0};
  o.up = Vec3{0, 0, 1};
  o.height_mm = 20;
  o.voxel_mm = o.stroke_width_mm / 32;
  Labelled l = run(t, o, false);
  EXPECT_EQ(l.status.code(), StatusCode::kLimitExceeded);
  EXPECT_STREQ(l.status.message(),
               "label: character 0 needs 311959746 samples at voxel 0.0109375 mm; at most "
               "16777216");
  EXPECT_EQ(l.status.index(), 0u);
  EXPECT_EQ(t.arena.used(), 0u);
}

// ---------------------------------------------------------------------------------------------
// Engrave and emboss on the paper-scale base.

TEST(LabelTest, EngraveAB12GivesAValidSolidWithTheStrokesRemoved) {
  Fixture& f = fixture();
  ASSERT_TRUE(f.ok);
  TestArena t(size_t{256} << 20);
  LabelOptions o;
  o.text = "ab12";  // folded to upper case
  Labelled glyphs = run(t, o, false);
  ASSERT_TRUE(glyphs.status.is_ok()) << test::format(glyphs.status);
  EXPECT_STREQ(glyphs.stats.text, "AB12");
  EXPECT_EQ(glyphs.stats.glyphs, 4u);
  EXPECT_EQ(glyphs.stats.glyph_triangles, glyphs.mesh.triangles.size());
  EXPECT_GE(glyphs.stats.attempts, 1u);
  EXPECT_LE(glyphs.stats.attempts, 4u);
  // Decimation keeps the flat walls as a few large triangles.
  EXPECT_LT(glyphs.stats.glyph_triangles * 5, glyphs.stats.marched_triangles);
  MeshReport gr = report_of(t, glyphs.mesh);
  EXPECT_TRUE(gr.is_valid_solid());
  EXPECT_EQ(gr.shells, 4u);  // one per glyph: disjoint
  for (const Vec3& v : glyphs.mesh.vertices) ASSERT_TRUE(is_float32_exact(v));

  Labelled l = run(t, o);
  ASSERT_TRUE(l.status.is_ok()) << test::format(l.status);
  double volume = 0;
  SPLINTCORE_ASSERT_OK(check_closed_oriented(Context(&t.arena), l.mesh, &volume));
  MeshReport r = report_of(t, l.mesh);
  EXPECT_TRUE(r.is_valid_solid());
  EXPECT_TRUE(r.closed() && r.edge_manifold() && r.outward());
  EXPECT_EQ(r.shells, 1u);
  EXPECT_GT(l.stats.boolean.intersecting_pairs, 0u);
  EXPECT_EQ(l.stats.glyph_triangles, glyphs.stats.glyph_triangles);

  const double scale = o.height_mm / kStrokeFontHeight;
  const double strokes_mm = stroke_units("AB12") * scale;
  EXPECT_NEAR(l.stats.stroke_length_mm, strokes_mm, 1e-9);
  const double expected = strokes_mm * o.stroke_width_mm * o.depth_mm;
  const double removed = f.volume - volume;
  EXPECT_GT(removed, 0.3 * expected) << removed << " vs " << expected;
  EXPECT_LT(removed, 1.5 * expected) << removed << " vs " << expected;

  // Every glyph sits on the outer wall: its normal points away from the arch's inside, and its
  // surface point is on the base's surface (within the voxel).
  for (uint32_t k = 0; k < l.stats.glyphs; ++k) {
    const LabelGlyphPlacement& p = l.stats.placements[k];
    EXPECT_GT(p.wall_height_mm, o.height_mm);
    EXPECT_NEAR(length(p.n), 1.0, 1e-12);
    EXPECT_NEAR(dot(p.u, p.n), 0.0, 1e-12);
    EXPECT_NEAR(dot(p.up, p.n), 0.0, 1e-12);
    EXPECT_GT(p.n.y, 0.5) << "the middle of this arch faces +y";
    EXPECT_GT(p.up.z, 0.9) << "up is towards the upper jaw";
  }
}

// The case id the pipeline will write: nine glyphs along the front of the arch.
TEST(LabelTest, CaseIdAlongTheArch) {
  Fixture& f = fixture();
  ASSERT_TRUE(f.ok);
  TestArena t(size_t{256} << 20);
  LabelOptions o;
  o.text = "CASE-0001";
  Labelled l = run(t, o);
  ASSERT_TRUE(l.status.is_ok()) << test::format(l.status);
  EXPECT_EQ(l.stats.glyphs, 9u);
  EXPECT_EQ(l.stats.characters, 9u);
  double volume = 0;
  SPLINTCORE_ASSERT_OK(check_closed_oriented(Context(&t.arena), l.mesh, &volume));
  MeshReport r = report_of(t, l.mesh);
  EXPECT_TRUE(r.is_valid_solid());
  EXPECT_EQ(r.shells, 1u);
  const double expected = l.stats.stroke_length_mm * o.stroke_width_mm * o.depth_mm;
  EXPECT_GT(f.volume - volume, 0.3 * expected);
  EXPECT_LT(f.volume - volume, 1.5 * expected);
  // Consecutive glyphs advance along the arch by their cells' advance (within the chord
  // error of the arc-length table), and each faces its own way (the row follows the arch).
  const double scale = o.height_mm / kStrokeFontHeight;
  for (uint32_t k = 0; k + 1 < l.stats.glyphs; ++k) {
    const LabelGlyphPlacement& a = l.stats.placements[k];
    const LabelGlyphPlacement& b = l.stats.placements[k + 1];
    StrokeGlyph ga, gb;
    ASSERT_TRUE(stroke_font_glyph(a.character, &ga) && stroke_font_glyph(b.character, &gb));
    const double advance = (ga.advance - 0.5 * ga.width + 0.5 * gb.width) * scale;
    EXPECT_NEAR(std::fabs(b.arc_mm - a.arc_mm), advance, 1e-9) << k;
    EXPECT_GT(dot(b.surface_point - a.surface_point, a.u), 0.0) << k;
  }
  EXPECT_LT(dot(l.stats.placements[0].n, l.stats.placements[8].n), 0.999);
}

TEST(LabelTest, TheTextReadsLeftToRightFromOutsideWhateverThePickOrder) {
  Fixture& f = fixture();
  ASSERT_TRUE(f.ok);
  TestArena t(size_t{128} << 20);
  LabelOptions o;
  o.text = "AB12";
  Labelled l = run(t, o, false);
  ASSERT_TRUE(l.status.is_ok()) << test::format(l.status);
  const uint32_t last = l.stats.glyphs - 1;
  const LabelGlyphPlacement& first = l.stats.placements[0];
  const LabelGlyphPlacement& final = l.stats.placements[last];
  EXPECT_EQ(first.character, 'A');
  EXPECT_EQ(final.character, '2');
  // Seen from outside (looking along -n, up = up), u points right: 'A' is left of '2'.
  EXPECT_LT(dot(first.surface_point, first.u), dot(final.surface_point, first.u));
  // u = up x n.
  const Vec3 c = cross(first.up, first.n);
  EXPECT_NEAR(length(c - first.u), 0.0, 1e-12);
  // The fixture's arch runs from +x to -x through +y: seen from the front (+y) the viewer's
  // left is +x.
  EXPECT_GT(first.surface_point.x, final.surface_point.x);

  // The same lines in reverse order: the same places.
  std::vector<Line> up_rev(f.upper.begin(), f.upper.end()), lo_rev(f.lower.begin(), f.lower.end());
  std::reverse(up_rev.begin(), up_rev.end());
  std::reverse(lo_rev.begin(), lo_rev.end());
  TestArena t2(size_t{128} << 20);
  Labelled r = run(t2, o, false, Span<const Line>(up_rev.data(), up_rev.size()),
                   Span<const Line>(lo_rev.data(), lo_rev.size()));
  ASSERT_TRUE(r.status.is_ok()) << test::format(r.status);
  ASSERT_EQ(r.stats.glyphs, l.stats.glyphs);
  for (uint32_t k = 0; k < l.stats.glyphs; ++k) {
    EXPECT_EQ(r.stats.placements[k].character, l.stats.placements[k].character);
    EXPECT_LT(length(r.stats.placements[k].surface_point - l.stats.placements[k].surface_point),
              0.01)
        << k;
    EXPECT_GT(dot(r.stats.placements[k].u, l.stats.placements[k].u), 0.999) << k;
  }
}

TEST(LabelTest, EmbossAddsTheStrokes) {
  Fixture& f = fixture();
  ASSERT_TRUE(f.ok);
  TestArena t(size_t{256} << 20);
  LabelOptions o;
  o.text = "A:B";
  o.mode = LabelMode::kEmboss;
  Labelled glyphs = run(t, o, false);
  ASSERT_TRUE(glyphs.status.is_ok()) << test::format(glyphs.status);
  EXPECT_EQ(report_of(t, glyphs.mesh).shells, 4u);  // ':' is two dots
  Labelled l = run(t, o);
  ASSERT_TRUE(l.status.is_ok()) << test::format(l.status);
  double volume = 0;
  SPLINTCORE_ASSERT_OK(check_closed_oriented(Context(&t.arena), l.mesh, &volume));
  MeshReport r = report_of(t, l.mesh);
  EXPECT_TRUE(r.is_valid_solid());
  EXPECT_EQ(r.shells, 1u);
  const double scale = o.height_mm / kStrokeFontHeight;
  // Dots have no length: count each as a disc of the stroke's diameter.
  const double area = stroke_units("A:B") * scale * o.stroke_width_mm +
                      2 * 0.7854 * o.stroke_width_mm * o.stroke_width_mm;
  const double expected = area * o.depth_mm;
  const double added = volume - f.volume;
  EXPECT_GT(added, 0.3 * expected) << added << " vs " << expected;
  EXPECT_LT(added, 1.5 * expected) << added << " vs " << expected;
}

TEST(LabelTest, ExplicitPlacementWritesAStraightRow) {
  Fixture& f = fixture();
  ASSERT_TRUE(f.ok);
  TestArena t(size_t{256} << 20);
  LabelOptions o;
  o.text = "7";
  o.placement = LabelPlacement::kExplicit;
  o.position = Vec3{27.9, 3.7, 0};  // the +x side of the arch's wall, facing +x
  o.normal = Vec3{1, 0, 0};
  o.up = Vec3{0, 0, 1};
  Labelled l = run(t, o);
  ASSERT_TRUE(l.status.is_ok()) << test::format(l.status);
  double volume = 0;
  SPLINTCORE_ASSERT_OK(check_closed_oriented(Context(&t.arena), l.mesh, &volume));
  EXPECT_LT(volume, f.volume);
  EXPECT_EQ(l.stats.placements[0].u.y, 1.0);  // up x n = z x x = +y: the right seen from +x
  EXPECT_GT(l.stats.placements[0].surface_point.x, 20.0);
}

TEST(LabelTest, SameBytesTwice) {
  ASSERT_TRUE(fixture().ok);
  LabelOptions o;
  o.text = "AB12";
  std::string hashes[2];
  for (int i = 0; i < 2; ++i) {
    TestArena t(size_t{256} << 20);
    Labelled l = run(t, o);
    ASSERT_TRUE(l.status.is_ok()) << test::format(l.status);
    hashes[i] = test::mesh_sha256(l.mesh);
  }
  EXPECT_EQ(hashes[0], hashes[1]);
}

TEST(LabelTest, ArenaExhaustionIsCleanAtEveryCapTried) {
  ASSERT_TRUE(fixture().ok);
  LabelOptions o;
  o.text = "AB";
  size_t need = 0;
  std::string reference;
  {
    TestArena t(size_t{256} << 20);
    Labelled l = run(t, o);
    ASSERT_TRUE(l.status.is_ok()) << test::format(l.status);
    need = t.arena.high_water();
    reference = test::mesh_sha256(l.mesh);
  }
  // Coarse steps over the whole range (each try is a full label), then the exact need.
  for (size_t k = 0; k < 24; ++k) {
    const size_t cap = need * k / 24;
    for (bool apply : {false, true}) {
      TestArena t(cap);
      Labelled l = run(t, o, apply);
      if (l.status.is_ok()) {
        EXPECT_FALSE(apply) << "cap " << cap << " of " << need;  // the glyphs alone need less
        continue;
      }
      ASSERT_EQ(l.status.code(), StatusCode::kArenaExhausted)
          << cap << " " << test::format(l.status);
      EXPECT_NE(std::string(l.status.message()).find("need"), std::string::npos);
      EXPECT_EQ(t.arena.used(), 0u) << "cap " << cap;
      EXPECT_TRUE(l.mesh.vertices.empty() && l.mesh.triangles.empty());
    }
  }
  TestArena t(need);
  Labelled l = run(t, o);
  ASSERT_TRUE(l.status.is_ok()) << test::format(l.status);
  EXPECT_EQ(test::mesh_sha256(l.mesh), reference);
}

// The glyph mesh alone, failed at every allocation that raises the arena's high water: from
// cap 0, each failing run names its need (test::need_of) and the next run gets exactly that
// much, so it passes that allocation and fails at a later one, until one works. Each failure
// is clean; the run at the end gives the bytes of a run with room to spare. (The cap sweep
// above steps by a 24th of the whole label's need. Allocations below a high water an earlier
// stage left, such as the arc-length table and the jobs beside the segments, no cap refuses.)
TEST(LabelTest, GlyphMeshFailsCleanlyAtEveryNewHighWater) {
  ASSERT_TRUE(fixture().ok);
  LabelOptions o;
  o.text = "AB";
  std::string reference;
  size_t need = 0;
  {
    TestArena t(size_t{256} << 20);
    const Labelled l = run(t, o, false);
    ASSERT_TRUE(l.status.is_ok()) << test::format(l.status);
    reference = test::mesh_sha256(l.mesh);
    need = t.arena.high_water();
  }
  size_t cap = 0;
  int points = 0;
  for (; points < 10000; ++points) {
    TestArena t(cap);
    const Labelled l = run(t, o, false);
    if (l.status.is_ok()) {
      EXPECT_EQ(test::mesh_sha256(l.mesh), reference) << "cap " << cap;
      break;
    }
    ASSERT_EQ(l.status.code(), StatusCode::kArenaExhausted) << cap << " " << test::format(l.status);
    EXPECT_EQ(t.arena.used(), 0u) << "cap " << cap;
    EXPECT_TRUE(l.mesh.vertices.empty() && l.mesh.triangles.empty()) << "cap " << cap;
    const uint64_t named = test::need_of(l.status, cap);
    ASSERT_GT(named, cap) << "a need within the cap: " << l.status.message();
    // (A growth may name more than an unconstrained run takes: then the reference's need.)
    cap = named < need ? static_cast<size_t>(named) : need;
  }
  EXPECT_LE(cap, need);
  EXPECT_GT(points, 5);
  std::printf("[ figures  ] glyph mesh: %d failure points up to %zu bytes\n", points, cap);
}

}  // namespace
}  // namespace splintcore
