// The automatic outline (outline.h, design's resolve_case_outline): on the phantom jaws, the
// arch, the picks and the indentation measured on the designed splint independently of the
// outline (the tooth's tip to the highest of its vertices on the splint); the bite opened to
// an exact distance checked by a brute force of its own; the resolved case designs to the same
// bytes; frame invariance under random rigid moves; the refusals.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "common/phantom.h"
#include "splintcore/design.h"
#include "splintcore/distance.h"
#include "splintcore/io.h"
#include "splintcore/outline.h"
#include "splintcore/platform.h"
#include "support/frame_moves.h"
#include "support/outline_checks.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

// The phantom jaws (one tube mesh each, crowns labelled per vertex), in occlusion.
struct PhantomJaws {
  phantom::JawMesh jaw[2];
  explicit PhantomJaws(uint64_t triangles) {
    phantom::PhantomOptions po;
    po.target_triangles = triangles;
    EXPECT_TRUE(phantom::make_jaw(phantom::Jaw::kMaxilla, po, &jaw[0]).is_ok());
    EXPECT_TRUE(phantom::make_jaw(phantom::Jaw::kMandible, po, &jaw[1]).is_ok());
  }
};

void copy_mesh(const phantom::JawMesh& m, Arena& arena, Mesh* out, const RigidTransform& move) {
  out->bind(&arena);
  for (const Vec3& v : m.vertices) (void)out->vertices.push_back(move.apply_point(v));
  for (const Triangle& t : m.triangles) (void)out->triangles.push_back(t);
}

// A case for the phantom jaws: `extra` goes into "base": {"auto": {...}}; the mandible's
// transform moves it by dz along z.
std::string auto_case(const char* extra, double dz, const char* more = "") {
  char text[2048];
  std::snprintf(text, sizeof text,
                "{\"splintcore_case\": 1, \"case_id\": \"auto-phantom\", \"units\": \"mm\",\n"
                " \"jaws\": [{\"role\": \"maxilla\", \"mesh\": \"maxilla.stl\"},\n"
                "  {\"role\": \"mandible\", \"mesh\": \"mandible.stl\", \"transform\": "
                "[1,0,0,0, 0,1,0,0, 0,0,1,%.17g, 0,0,0,1]}],\n"
                " \"base\": {\"spacing_mm\": 0.42, \"auto\": {%s}}%s}\n",
                dz, extra, more);
  return text;
}

Status parse(Arena& arena, const std::string& text, CaseFile* c) {
  return parse_case(Context(&arena), text.data(), text.size(), "auto-phantom.json", c);
}

std::string stl_sha(Arena& arena, const Mesh& m) {
  std::vector<uint8_t> bytes;
  EXPECT_TRUE(test::mesh_to_bytes(arena, m, StlFormat::kBinary, &bytes).is_ok());
  return test::sha256_hex(bytes.data(), bytes.size());
}

// The distal surface of a phantom tooth: its crown's vertex farthest towards the arch's open
// back (-y).
Vec3 phantom_distal(const phantom::JawMesh& jaw, const Mesh& moved, uint8_t tooth) {
  Vec3 best{0, HUGE_VAL, 0};
  for (size_t v = 0; v < moved.vertices.size(); ++v) {
    if (jaw.vertex_tooth[v] == tooth && moved.vertices[v].y < best.y) best = moved.vertices[v];
  }
  return best;
}

TEST(Outline, PhantomArchAndPicks) {
  PhantomJaws p(87000);
  test::TestArena t{size_t{256} << 20};
  Mesh jaws[2];
  copy_mesh(p.jaw[0], t.arena, &jaws[0], RigidTransform{});
  copy_mesh(p.jaw[1], t.arena, &jaws[1], RigidTransform::translation(Vec3{0, 0, -2}));
  Outline o;
  SPLINTCORE_ASSERT_OK(compute_outline(Context(&t.arena), jaws[0], jaws[1], OutlineOptions{}, &o));
  const OutlineReport& r = o.report;
  // The phantom's occlusal plane is z = 0, its arch symmetric about x = 0, open towards -y.
  EXPECT_GT(r.occlusal_normal.z, 1 - 1e-6);
  EXPECT_GT(r.anterior.y, 0.99);
  EXPECT_FALSE(r.opened);
  EXPECT_NEAR(r.gap_as_given, 0.26, 0.05);
  ASSERT_EQ(o.upper.size(), o.lower.size());
  ASSERT_GE(o.upper.size(), 20u);
  const size_t n = o.upper.size();
  for (size_t i = 0; i < n; ++i) {
    const Pick& a = o.upper[i];
    const Pick& b = o.upper[n - 1 - i];
    EXPECT_NEAR(a.position.x, -b.position.x, 0.2) << i;  // mirror images
    EXPECT_NEAR(a.position.y, b.position.y, 0.2) << i;
    EXPECT_NEAR(length(a.direction), 1.0, 1e-12);
    EXPECT_NEAR(a.direction.z, 0.0, 1e-3);
    // Upper and lower picks pair: the same place in the occlusal plane, the same line.
    EXPECT_LT(length(cross(a.position - o.lower[i].position, r.occlusal_normal)), 1e-9);
    EXPECT_EQ(o.lower[i].direction, a.direction);
    EXPECT_GT(a.position.z, o.lower[i].position.z + 1.0);
    // The picks lie on the phantom's arch (the crowns follow the ellipse 24.5 cos t, 41.25
    // sin t within about a millimetre), the direction outward.
    const double ex = a.position.x / 24.5, ey = a.position.y / 41.25;
    if (a.position.y > 0) {
      EXPECT_NEAR(std::sqrt(ex * ex + ey * ey), 1.0, 0.05) << i;
    }
    EXPECT_GT(a.direction.x * a.position.x / 600 + a.direction.y * a.position.y / 1700, 0) << i;
  }
  // The ends pass the last crowns (which end about 1.5 mm inside the fixture's picks at
  // y = -7.5) by the overhang.
  EXPECT_LT(o.upper[0].position.y, -6.0);
  EXPECT_LT(o.upper[n - 1].position.y, -6.0);
  EXPECT_NEAR(r.arch_length_mm, 115, 6);
}

// Per tooth of a jaw: its tip (the lowest, for the maxilla, or highest vertex along z) and the
// highest (lowest) splint vertex that lies on that tooth's surface (within 1e-5 mm of one of its
// triangles): how deep the tooth sits in the wafer. Shares no code with the outline.
std::vector<double> indentation(const phantom::JawMesh& jaw, const Mesh& moved, bool upper,
                                const Mesh& splint, Arena& arena) {
  ArenaScope scope(arena);
  DistanceIndex index;
  EXPECT_TRUE(build_distance_index(Context(&arena), moved, DistanceIndexOptions{}, &index).is_ok());
  std::vector<double> tip(phantom::kTeethPerJaw, upper ? HUGE_VAL : -HUGE_VAL);
  std::vector<double> rim(phantom::kTeethPerJaw, upper ? -HUGE_VAL : HUGE_VAL);
  for (size_t v = 0; v < moved.vertices.size(); ++v) {
    const uint8_t k = jaw.vertex_tooth[v];
    if (k == phantom::kGumLabel) continue;
    const double z = moved.vertices[v].z;
    tip[k] = upper ? std::min(tip[k], z) : std::max(tip[k], z);
  }
  for (const Vec3& p : splint.vertices) {
    ClosestPoint c;
    if (!closest_point(index, p, &c) || c.distance > 1e-5) continue;
    const Triangle& tr = moved.triangles[c.triangle];
    const uint8_t k = jaw.vertex_tooth[tr.v[0]];
    if (k == phantom::kGumLabel || jaw.vertex_tooth[tr.v[1]] != k ||
        jaw.vertex_tooth[tr.v[2]] != k) {
      continue;
    }
    rim[k] = upper ? std::max(rim[k], p.z) : std::min(rim[k], p.z);
  }
  std::vector<double> depth(phantom::kTeethPerJaw);
  for (uint32_t k = 0; k < phantom::kTeethPerJaw; ++k) {
    depth[k] = upper ? rim[k] - tip[k] : tip[k] - rim[k];
  }
  return depth;
}

// The automatic case on the phantom's jaws (the mandible 2 mm down), indented `depth` mm.
Status design_phantom_at_depth(const PhantomJaws& p, Arena& arena, double depth, Mesh* splint,
                               DesignReport* r) {
  char extra[64];
  std::snprintf(extra, sizeof extra, "\"indentation_depth_mm\": %g", depth);
  CaseFile c;
  SPLINTCORE_RETURN_IF_ERROR(parse(arena, auto_case(extra, -2.0), &c));
  Mesh jaws[2];
  copy_mesh(p.jaw[0], arena, &jaws[0], RigidTransform{});
  copy_mesh(p.jaw[1], arena, &jaws[1], RigidTransform{});
  return design_splint(Context(&arena), c, Span<const Mesh>(jaws, 2), splint, r);
}

TEST(Outline, PhantomSplintIndentsEveryToothAsAsked) {
  PhantomJaws p(87000);
  test::TestArena t{size_t{512} << 20};
  for (const double depth : {2.0, 1.0}) {
    ArenaScope scope(t.arena);
    Mesh splint;
    DesignReport r;
    SPLINTCORE_ASSERT_OK(design_phantom_at_depth(p, t.arena, depth, &splint, &r));
    EXPECT_TRUE(r.outlined);
    EXPECT_TRUE(r.print.printable);
    EXPECT_TRUE(r.self_intersection_checked);
    EXPECT_EQ(r.print.mesh.shells, 1u);
    // The jaws as design moved them (float32), for the measurement.
    Mesh moved[2];
    copy_mesh(p.jaw[0], t.arena, &moved[0], RigidTransform{});
    copy_mesh(p.jaw[1], t.arena, &moved[1], RigidTransform::translation(Vec3{0, 0, -2}));
    for (Mesh& m : moved) {
      for (Vec3& v : m.vertices) round_to_float32(&v);
    }
    for (int jaw = 0; jaw < 2; ++jaw) {
      const std::vector<double> d = indentation(p.jaw[jaw], moved[jaw], jaw == 0, splint, t.arena);
      const double deepest = *std::max_element(d.begin(), d.end());
      const double shallowest = *std::min_element(d.begin(), d.end());
      EXPECT_NEAR(deepest, depth, 0.25) << "jaw " << jaw << " depth " << depth;
      EXPECT_GE(shallowest, depth / 2) << "jaw " << jaw << " depth " << depth;
    }
  }
}

// Indented deeper than the default, the slab between the faces reaches further up the teeth:
// the picks' reach across the arch must hold what it meets there, or the jaw crosses the
// base's side walls and its imprint opens through them (DesignReport::walls). The phantom's
// crowns have no palate or gums, so this holds with the occlusal band alone too; the real
// dentition's palate is what needed the deeper columns (OutlineRealData's test of the same).
TEST(Outline, DeepIndentationsCrossNoSideWall) {
  PhantomJaws p(20000);
  test::TestArena t{size_t{256} << 20};
  for (const double depth : {2.0, 3.0, 4.0, 5.0}) {
    ArenaScope scope(t.arena);
    Mesh splint;
    DesignReport r;
    SPLINTCORE_ASSERT_OK(design_phantom_at_depth(p, t.arena, depth, &splint, &r));
    EXPECT_TRUE(r.print.printable) << depth;
    ASSERT_EQ(r.wall_jaws, 2u);
    for (uint32_t j = 0; j < 2; ++j) {
      EXPECT_GT(r.walls[j].arch_mm, 50.0) << depth;
      EXPECT_EQ(r.walls[j].either_mm, 0.0)
          << "depth " << depth << " jaw " << j << ": crossed " << r.walls[j].crossed << " of "
          << r.walls[j].stretches << " stretches";
    }
  }
}

// Brute force, sharing no code with the library's pair search: the smallest distance between
// the triangles of two meshes near their contact (heights within 4 mm of it).
Vec3 closest_on_segment(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 d = b - a;
  double t = dot(p - a, d) / dot(d, d);
  t = t < 0 ? 0 : (t > 1 ? 1 : t);
  return a + d * t;
}

double point_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 n = cross(b - a, c - a);
  const double nn = dot(n, n);
  const Vec3 q = p - n * (dot(p - a, n) / nn);
  const double u = dot(cross(c - b, q - b), n), v = dot(cross(a - c, q - c), n),
               w = dot(cross(b - a, q - a), n);
  if (u >= 0 && v >= 0 && w >= 0) return length(p - q);
  return std::min({length(p - closest_on_segment(p, a, b)), length(p - closest_on_segment(p, b, c)),
                   length(p - closest_on_segment(p, c, a))});
}

double segment_segment(const Vec3& p1, const Vec3& q1, const Vec3& p2, const Vec3& q2) {
  // Sampled minimisation refined by the clamped closed form of each end.
  const Vec3 d1 = q1 - p1, d2 = q2 - p2, r = p1 - p2;
  const double a = dot(d1, d1), e = dot(d2, d2), f = dot(d2, r), c = dot(d1, r), b = dot(d1, d2);
  const double denom = a * e - b * b;
  double s = denom > 1e-20 ? (b * f - c * e) / denom : 0;
  s = s < 0 ? 0 : (s > 1 ? 1 : s);
  double t = (b * s + f) / e;
  if (t < 0) {
    t = 0;
    s = -c / a;
  } else if (t > 1) {
    t = 1;
    s = (b - c) / a;
  }
  s = s < 0 ? 0 : (s > 1 ? 1 : s);
  return length((p1 + d1 * s) - (p2 + d2 * t));
}

double brute_distance(const Mesh& a, const Mesh& b, const Vec3& offset, double z_lo, double z_hi) {
  std::vector<std::array<Vec3, 3>> ta, tb;
  for (const Triangle& t : a.triangles) {
    std::array<Vec3, 3> x{a.vertices[t.v[0]], a.vertices[t.v[1]], a.vertices[t.v[2]]};
    if (std::min({x[0].z, x[1].z, x[2].z}) < z_hi) ta.push_back(x);
  }
  for (const Triangle& t : b.triangles) {
    std::array<Vec3, 3> x{b.vertices[t.v[0]] + offset, b.vertices[t.v[1]] + offset,
                          b.vertices[t.v[2]] + offset};
    if (std::max({x[0].z, x[1].z, x[2].z}) > z_lo) tb.push_back(x);
  }
  double best = HUGE_VAL;
  for (const auto& x : ta) {
    for (const auto& y : tb) {
      for (int k = 0; k < 3; ++k) {
        best = std::min(best, point_triangle(x[k], y[0], y[1], y[2]));
        best = std::min(best, point_triangle(y[k], x[0], x[1], x[2]));
        for (int m = 0; m < 3; ++m) {
          best = std::min(best, segment_segment(x[k], x[(k + 1) % 3], y[m], y[(m + 1) % 3]));
        }
      }
    }
  }
  return best;
}

TEST(Outline, BiteOpensToTheExactDistance) {
  PhantomJaws p(2000);
  test::TestArena t{size_t{64} << 20};
  Mesh jaws[2];
  copy_mesh(p.jaw[0], t.arena, &jaws[0], RigidTransform{});
  copy_mesh(p.jaw[1], t.arena, &jaws[1], RigidTransform{});  // in occlusion: they overlap
  for (const double opening : {0.5, 2.0, 3.5}) {
    ArenaScope scope(t.arena);
    OutlineOptions options;
    options.has_bite_opening = true;
    options.bite_opening_mm = opening;
    Outline o;
    SPLINTCORE_ASSERT_OK(compute_outline(Context(&t.arena), jaws[0], jaws[1], options, &o));
    EXPECT_TRUE(o.report.jaws_intersect);
    EXPECT_EQ(o.report.gap_as_given, 0.0);
    EXPECT_TRUE(o.report.opened);
    EXPECT_NEAR(o.report.opening, opening, 1e-9);
    // The move is along the occlusal normal, away from the maxilla.
    const Vec3 m = o.report.mandible_translation;
    EXPECT_LT(length(cross(m, o.report.occlusal_normal)), 1e-12 + 1e-9 * length(m));
    EXPECT_LT(dot(m, o.report.occlusal_normal), 0);
    EXPECT_NEAR(brute_distance(jaws[0], jaws[1], m, -6, 6), opening, 1e-9) << opening;
  }
}

// Jaws already apart (moved apart along z by hand, as a plan's autorotated jaws come): the
// first bands reach the nearest pair of column tips; the distance as given and the opening,
// nearer or farther than the gap, are still exact (a brute force over every pair agrees).
TEST(Outline, BiteOpensToTheExactDistanceFromApart) {
  PhantomJaws p(2000);
  test::TestArena t{size_t{64} << 20};
  Mesh jaws[2];
  copy_mesh(p.jaw[0], t.arena, &jaws[0], RigidTransform{});
  copy_mesh(p.jaw[1], t.arena, &jaws[1], RigidTransform::translation(Vec3{0, 0, -4}));
  const double gap = brute_distance(jaws[0], jaws[1], Vec3{}, -6, 6);
  ASSERT_GT(gap, 2.0);
  {
    OutlineOptions options;  // no opening asked: the gap as given
    Outline o;
    SPLINTCORE_ASSERT_OK(compute_outline(Context(&t.arena), jaws[0], jaws[1], options, &o));
    EXPECT_FALSE(o.report.opened);
    EXPECT_NEAR(o.report.gap_as_given, gap, 1e-9);
  }
  for (const double opening : {1.0, gap + 1.5}) {
    ArenaScope scope(t.arena);
    OutlineOptions options;
    options.has_bite_opening = true;
    options.bite_opening_mm = opening;
    Outline o;
    SPLINTCORE_ASSERT_OK(compute_outline(Context(&t.arena), jaws[0], jaws[1], options, &o));
    EXPECT_FALSE(o.report.jaws_intersect);
    EXPECT_NEAR(o.report.gap_as_given, gap, 1e-9);
    EXPECT_NEAR(o.report.opening, opening, 1e-9);
    EXPECT_NEAR(brute_distance(jaws[0], jaws[1], o.report.mandible_translation, -6, 6), opening,
                1e-9)
        << opening;
  }
}

TEST(Outline, ResolvedCaseDesignsTheSameBytes) {
  PhantomJaws p(87000);
  test::TestArena t{size_t{512} << 20};
  const Context ctx(&t.arena);
  Mesh jaws[2];
  copy_mesh(p.jaw[0], t.arena, &jaws[0], RigidTransform{});
  copy_mesh(p.jaw[1], t.arena, &jaws[1], RigidTransform{});
  // Limits at the first molars' distal surfaces: the resolved case keeps the cut picks.
  char ends[256];
  const Vec3 a = phantom_distal(p.jaw[0], jaws[0], 1), b = phantom_distal(p.jaw[0], jaws[0], 12);
  std::snprintf(ends, sizeof ends,
                "\"distal_ends\": [[%.17g, %.17g, %.17g], [%.17g, %.17g, %.17g]]", b.x, b.y, b.z,
                a.x, a.y, a.z);
  for (const std::string& text :
       {auto_case(ends, -2.0), auto_case("", -2.0), auto_case("\"bite_opening_mm\": 2.5", 0.0),
        auto_case("\"overhang_mm\": 1.5, \"pick_spacing_mm\": 5", -2.0,
                  ", \"label\": {\"text\": \"AUTO\"}, \"placement\": \"tray\"")}) {
    ArenaScope scope(t.arena);
    CaseFile c;
    SPLINTCORE_ASSERT_OK(parse(t.arena, text, &c));
    Mesh a;
    DesignReport ra;
    SPLINTCORE_ASSERT_OK(design_splint(ctx, c, Span<const Mesh>(jaws, 2), &a, &ra));
    CaseFile resolved;
    SPLINTCORE_ASSERT_OK(
        resolve_case_outline(ctx, c, Span<const Mesh>(jaws, 2), &resolved, nullptr));
    std::string written;
    ByteSink sink = test::string_sink(&written);
    // The auto case itself written and read back: the same options, distal ends bit for bit.
    SPLINTCORE_ASSERT_OK(write_case(c, sink));
    CaseFile unresolved;
    SPLINTCORE_ASSERT_OK(parse(t.arena, written, &unresolved));
    EXPECT_TRUE(unresolved.has_auto_outline);
    EXPECT_EQ(unresolved.outline.has_distal_ends, c.outline.has_distal_ends);
    for (int i = 0; i < 2; ++i)
      EXPECT_EQ(unresolved.outline.distal_ends[i], c.outline.distal_ends[i]);
    EXPECT_EQ(unresolved.outline.overhang_mm, c.outline.overhang_mm);
    written.clear();
    SPLINTCORE_ASSERT_OK(write_case(resolved, sink));
    CaseFile again;
    SPLINTCORE_ASSERT_OK(parse(t.arena, written, &again));
    EXPECT_FALSE(again.has_auto_outline);
    ASSERT_EQ(again.upper.size(), resolved.upper.size());
    Mesh b;
    DesignReport rb;
    SPLINTCORE_ASSERT_OK(design_splint(ctx, again, Span<const Mesh>(jaws, 2), &b, &rb));
    EXPECT_EQ(stl_sha(t.arena, a), stl_sha(t.arena, b)) << written.substr(0, 400);
    // Writing the parsed case again gives the same text: nothing is lost either way.
    std::string twice;
    sink.user = &twice;
    SPLINTCORE_ASSERT_OK(write_case(again, sink));
    EXPECT_EQ(written, twice);
  }
}

TEST(Outline, FrameInvariance) {
  PhantomJaws p(24000);
  test::TestArena t{size_t{768} << 20};
  const Context ctx(&t.arena);
  CaseFile c;
  SPLINTCORE_ASSERT_OK(parse(t.arena, auto_case("\"bite_opening_mm\": 2", 0.0), &c));
  Mesh jaws[2];
  copy_mesh(p.jaw[0], t.arena, &jaws[0], RigidTransform{});
  copy_mesh(p.jaw[1], t.arena, &jaws[1], RigidTransform{});
  Mesh reference;
  DesignReport r0;
  SPLINTCORE_ASSERT_OK(design_splint(ctx, c, Span<const Mesh>(jaws, 2), &reference, &r0));
  const double volume = r0.print.mesh.volume;
  std::mt19937_64 rng(28);
  int nudged = 0;
  double worst_unnudged = 0;
  for (int draw = 0; draw < 10; ++draw) {
    ArenaScope scope(t.arena);
    const RigidTransform move = test::random_move(rng);
    CaseFile moved = c;
    CaseJaw cj[2] = {c.jaws[0], c.jaws[1]};
    for (CaseJaw& j : cj) j.transform = compose(move, j.transform);
    moved.jaws = Span<const CaseJaw>(cj, 2);
    Mesh splint;
    DesignReport r;
    SPLINTCORE_ASSERT_OK(design_splint(ctx, moved, Span<const Mesh>(jaws, 2), &splint, &r));
    EXPECT_NEAR(r.print.mesh.volume / volume, 1.0, 1e-6) << "draw " << draw;
    Mesh back(&t.arena);
    const RigidTransform undo = inverse(move);
    for (const Vec3& v : splint.vertices) (void)back.vertices.push_back(undo.apply_point(v));
    for (const Triangle& tr : splint.triangles) (void)back.triangles.push_back(tr);
    const double h = std::max(test::one_sided(back, reference, t.arena),
                              test::one_sided(reference, back, t.arena));
    // The Boolean may nudge the base by a fraction of a micrometre where rounding to float32
    // would break its result (boolean.h, max_nudges): in 1 of these 10 frames it does, by
    // 0.117 um, and the splint moves with it. That move is the Boolean's, reported, and added.
    std::printf("frame %d: Hausdorff %.3g mm, volume ratio - 1 = %.3g, Boolean nudge %.3g mm\n",
                draw, h, r.print.mesh.volume / volume - 1, length(r.boolean.nudge));
    EXPECT_LT(h, 1e-4 + length(r.boolean.nudge) + length(r0.boolean.nudge)) << "draw " << draw;
    EXPECT_LT(length(r.boolean.nudge), 1e-3) << "draw " << draw;
    nudged += length(r.boolean.nudge) > 0 ? 1 : 0;
    worst_unnudged = length(r.boolean.nudge) > 0 ? worst_unnudged : std::max(worst_unnudged, h);
  }
  EXPECT_LT(worst_unnudged, 1e-4);
  EXPECT_LE(nudged, 3);
  std::printf("frames the Boolean nudged: %d of 10; largest Hausdorff of the others %.3g mm\n",
              nudged, worst_unnudged);
}

// The picks themselves move with the jaws: the outline of the jaws moved (and rounded to
// float32, as design moves them) is the outline moved, to the rounding.
// The phantom pair as the move tests use it: the mandible 2 mm below its occlusion, both
// rounded to float32 (as design moves them).
void opened_pair(const PhantomJaws& p, Arena& arena, Mesh jaws[2]) {
  copy_mesh(p.jaw[0], arena, &jaws[0], RigidTransform{});
  copy_mesh(p.jaw[1], arena, &jaws[1], RigidTransform::translation(Vec3{0, 0, -2}));
  for (int j = 0; j < 2; ++j)
    for (Vec3& v : jaws[j].vertices) round_to_float32(&v);
}

// The outline of the jaws (and of options' distal ends) moved by six random rigid moves is
// `ref` moved, to the float32 rounding of the moved vertices.
void expect_moves_with_jaws(const Context& ctx, Arena& arena, const Mesh jaws[2],
                            const OutlineOptions& options, const Outline& ref, uint64_t seed) {
  std::mt19937_64 rng(seed);
  for (int draw = 0; draw < 6; ++draw) {
    ArenaScope scope(arena);
    const RigidTransform move = test::random_move(rng);
    Mesh m[2];
    for (int j = 0; j < 2; ++j) {
      m[j].bind(&arena);
      for (const Vec3& v : jaws[j].vertices) {
        Vec3 q = move.apply_point(v);
        round_to_float32(&q);
        (void)m[j].vertices.push_back(q);
      }
      for (const Triangle& tr : jaws[j].triangles) (void)m[j].triangles.push_back(tr);
    }
    OutlineOptions moved = options;
    for (Vec3& e : moved.distal_ends) e = move.apply_point(e);
    Outline o;
    SPLINTCORE_ASSERT_OK(compute_outline(ctx, m[0], m[1], moved, &o));
    const RigidTransform undo = inverse(move);
    double dp = 0, dd = 0, dl = 0,
           dn = length(undo.apply_vector(o.report.occlusal_normal) - ref.report.occlusal_normal);
    ASSERT_EQ(o.upper.size(), ref.upper.size()) << draw;
    for (size_t i = 0; i < o.upper.size(); ++i) {
      dp = std::max(dp, length(undo.apply_point(o.upper[i].position) - ref.upper[i].position));
      dp = std::max(dp, length(undo.apply_point(o.lower[i].position) - ref.lower[i].position));
      dd = std::max(dd, length(undo.apply_vector(o.upper[i].direction) - ref.upper[i].direction));
      dl = std::max(dl, std::fabs(o.upper[i].inner_length - ref.upper[i].inner_length));
      dl = std::max(dl, std::fabs(o.upper[i].outside_length - ref.upper[i].outside_length));
    }
    EXPECT_LT(dn, 1e-7) << draw;
    EXPECT_LT(dp, 3e-5) << draw;
    EXPECT_LT(dd, 1e-6) << draw;
    EXPECT_LT(dl, 3e-5) << draw;
    EXPECT_NEAR(o.report.arch_length_mm, ref.report.arch_length_mm, 3e-5) << draw;
    for (int i = 0; i < 2; ++i) {
      EXPECT_NEAR(o.report.distal_cut_mm[i], ref.report.distal_cut_mm[i], 3e-5) << draw;
    }
  }
}

TEST(Outline, PicksMoveWithTheJaws) {
  PhantomJaws p(87000);
  test::TestArena t{size_t{768} << 20};
  const Context ctx(&t.arena);
  Mesh jaws[2];
  opened_pair(p, t.arena, jaws);
  Outline ref;
  SPLINTCORE_ASSERT_OK(compute_outline(ctx, jaws[0], jaws[1], OutlineOptions{}, &ref));
  expect_moves_with_jaws(ctx, t.arena, jaws, OutlineOptions{}, ref, 28);
}

// distal_ends: on the phantom, limits at the distal surfaces of the second molars (the last
// teeth: they cut the overhang) and of the first molars (they cut a tooth each side); the
// order of the two points does not matter; limits past the arch's ends change nothing; the
// limits move with the jaws.
TEST(Outline, DistalEndsCutTheArch) {
  PhantomJaws p(87000);
  test::TestArena t{size_t{768} << 20};
  const Context ctx(&t.arena);
  Mesh jaws[2];
  opened_pair(p, t.arena, jaws);
  Outline whole;
  SPLINTCORE_ASSERT_OK(compute_outline(ctx, jaws[0], jaws[1], OutlineOptions{}, &whole));
  EXPECT_FALSE(whole.report.distal_limited);
  const uint8_t kTeeth[2][2] = {{0, 13}, {1, 12}};
  for (const auto& teeth : kTeeth) {
    ArenaScope scope(t.arena);
    OutlineOptions options;
    options.has_distal_ends = true;
    options.distal_ends[0] = phantom_distal(p.jaw[0], jaws[0], teeth[0]);
    options.distal_ends[1] = phantom_distal(p.jaw[0], jaws[0], teeth[1]);
    Outline cut;
    SPLINTCORE_ASSERT_OK(compute_outline(ctx, jaws[0], jaws[1], options, &cut));
    const size_t dropped = test::check_limited(whole, cut, options.distal_ends);
    const OutlineReport& r = cut.report;
    std::printf(
        "teeth %d and %d: %zu of %zu picks, cut %.3f and %.3f mm, limits %.3f and %.3f mm "
        "from the arch\n",
        teeth[0], teeth[1], cut.upper.size(), whole.upper.size(), r.distal_cut_mm[0],
        r.distal_cut_mm[1], r.distal_offset_mm[0], r.distal_offset_mm[1]);
    for (int i = 0; i < 2; ++i) {
      EXPECT_GT(r.distal_cut_mm[i], teeth[0] == 0 ? 0.5 : 8.0) << i;
      EXPECT_LT(r.distal_offset_mm[i], 15.0) << i;
    }
    EXPECT_GE(dropped, teeth[0] == 0 ? 0u : 4u);
    EXPECT_EQ(r.picks, cut.upper.size());
    // The order of the points does not matter: the same picks, bit for bit.
    std::swap(options.distal_ends[0], options.distal_ends[1]);
    Outline swapped;
    SPLINTCORE_ASSERT_OK(compute_outline(ctx, jaws[0], jaws[1], options, &swapped));
    ASSERT_EQ(swapped.upper.size(), cut.upper.size());
    for (size_t i = 0; i < cut.upper.size(); ++i) {
      EXPECT_TRUE(test::same_pick(swapped.upper[i], cut.upper[i])) << i;
      EXPECT_TRUE(test::same_pick(swapped.lower[i], cut.lower[i])) << i;
    }
    EXPECT_EQ(swapped.report.distal_cut_mm[0], r.distal_cut_mm[1]);
    EXPECT_EQ(swapped.report.distal_offset_mm[1], r.distal_offset_mm[0]);
  }
  // Past the ends (6 mm beyond the last crowns, the overhang 2): nothing changes.
  {
    OutlineOptions options;
    options.has_distal_ends = true;
    options.distal_ends[0] = phantom_distal(p.jaw[0], jaws[0], 0) + Vec3{0, -6, 0};
    options.distal_ends[1] = phantom_distal(p.jaw[0], jaws[0], 13) + Vec3{0, -6, 0};
    Outline o;
    SPLINTCORE_ASSERT_OK(compute_outline(ctx, jaws[0], jaws[1], options, &o));
    EXPECT_TRUE(o.report.distal_limited);
    EXPECT_EQ(o.report.distal_cut_mm[0], 0.0);
    EXPECT_EQ(o.report.distal_cut_mm[1], 0.0);
    ASSERT_EQ(o.upper.size(), whole.upper.size());
    for (size_t i = 0; i < o.upper.size(); ++i) {
      EXPECT_TRUE(test::same_pick(o.upper[i], whole.upper[i])) << i;
      EXPECT_TRUE(test::same_pick(o.lower[i], whole.lower[i])) << i;
    }
  }
}

// The limits move with the jaws: the jaws and the points moved by a random rigid move give
// the same picks moved (to the rounding, as PicksMoveWithTheJaws).
TEST(Outline, DistalEndsMoveWithTheJaws) {
  PhantomJaws p(87000);
  test::TestArena t{size_t{768} << 20};
  const Context ctx(&t.arena);
  Mesh jaws[2];
  opened_pair(p, t.arena, jaws);
  OutlineOptions options;
  options.has_distal_ends = true;
  options.distal_ends[0] = phantom_distal(p.jaw[0], jaws[0], 1);
  options.distal_ends[1] = phantom_distal(p.jaw[0], jaws[0], 12);
  Outline ref;
  SPLINTCORE_ASSERT_OK(compute_outline(ctx, jaws[0], jaws[1], options, &ref));
  expect_moves_with_jaws(ctx, t.arena, jaws, options, ref, 2801);
}

// The refusals of distal_ends, each naming the point and what is wrong.
TEST(Outline, DistalEndsRefusals) {
  PhantomJaws p(24000);
  test::TestArena t{size_t{256} << 20};
  const Context ctx(&t.arena);
  Mesh jaws[2];
  copy_mesh(p.jaw[0], t.arena, &jaws[0], RigidTransform{});
  copy_mesh(p.jaw[1], t.arena, &jaws[1], RigidTransform::translation(Vec3{0, 0, -2}));
  Outline whole;
  SPLINTCORE_ASSERT_OK(compute_outline(ctx, jaws[0], jaws[1], OutlineOptions{}, &whole));
  const Vec3 right = phantom_distal(p.jaw[0], jaws[0], 0),
             left = phantom_distal(p.jaw[0], jaws[0], 13);
  auto refused = [&](const Vec3& a, const Vec3& b, const std::vector<const char*>& why) {
    OutlineOptions options;
    options.has_distal_ends = true;
    options.distal_ends[0] = a;
    options.distal_ends[1] = b;
    Outline o;
    const size_t used = t.arena.used();
    const Status s = compute_outline(ctx, jaws[0], jaws[1], options, &o);
    EXPECT_EQ(s.code(), StatusCode::kInvalidArgument) << test::format(s);
    for (const char* w : why) {
      EXPECT_NE(std::string(s.message()).find(w), std::string::npos) << s.message();
    }
    EXPECT_EQ(t.arena.used(), used);
    std::printf("refused: %s\n", s.message());
  };
  // 30 mm buccal of the arch (the right molar lies at +x).
  refused(left, right + Vec3{30, 0, 0},
          {"distal_ends[1] lies 3", "mm from the arch's centre line", "at most 15"});
  refused(left + Vec3{-30, 0, 0}, right, {"distal_ends[0] lies 3", "at most 15"});
  // Both on one side.
  refused(right, right + Vec3{0, 3, 0}, {"distal_ends[0] and [1] lie on the same half"});
  refused(left + Vec3{0, 3, 0}, left, {"same half", "give one point a side"});
  // Not finite.
  refused(left, Vec3{0, std::numeric_limits<double>::quiet_NaN(), 0},
          {"distal_ends[1] is not finite"});
  // Either side of the incisors, 12 mm apart: too little arch left.
  const size_t mid = whole.upper.size() / 2;
  refused(whole.upper[mid - 2].position, whole.upper[mid + 2].position,
          {"the distal ends leave", "mm of the arch (at least 20)"});
}

// The survey: within 15 degrees of the occlusal normal, a direction with less undercut than
// the normal's, and the blockout (an independent measure: the swept volume's voxels, not
// rays) removes less along it than along the normal.
TEST(Outline, SurveyChoosesLessUndercut) {
  PhantomJaws p(24000);
  test::TestArena t{size_t{768} << 20};
  const Context ctx(&t.arena);
  Mesh jaws[2];
  copy_mesh(p.jaw[0], t.arena, &jaws[0], RigidTransform{});
  copy_mesh(p.jaw[1], t.arena, &jaws[1], RigidTransform{});
  CaseFile c;
  SPLINTCORE_ASSERT_OK(parse(
      t.arena,
      auto_case("\"survey\": true", -2.0, ", \"blockout\": {\"voxel\": 0.3, \"inset\": 0}"), &c));
  CaseFile resolved;
  Outline o;
  SPLINTCORE_ASSERT_OK(resolve_case_outline(ctx, c, Span<const Mesh>(jaws, 2), &resolved, &o));
  const OutlineReport& r = o.report;
  EXPECT_TRUE(r.surveyed);
  EXPECT_GE(r.survey_directions, 20u);
  EXPECT_GT(r.undercut_plain_mm3, 0.0);
  EXPECT_LT(r.undercut_chosen_mm3, r.undercut_plain_mm3);
  EXPECT_GE(dot(r.insertion_direction, r.occlusal_normal), std::cos(15.0 * M_PI / 180) - 1e-12);
  EXPECT_EQ(resolved.insertion_direction, r.insertion_direction);
#ifndef __OPTIMIZE__
  GTEST_SKIP() << "the blockout comparison runs in optimised builds (two blockouts)";
#endif
  double removed[2] = {0, 0};
  for (int k = 0; k < 2; ++k) {
    ArenaScope scope(t.arena);
    CaseFile explicit_case = resolved;
    explicit_case.insertion_direction = k == 0 ? r.occlusal_normal : r.insertion_direction;
    Mesh splint;
    DesignReport dr;
    SPLINTCORE_ASSERT_OK(
        design_splint(ctx, explicit_case, Span<const Mesh>(jaws, 2), &splint, &dr));
    EXPECT_TRUE(dr.print.printable);
    removed[k] = dr.blockout_removed_mm3[0] + dr.blockout_removed_mm3[1];
  }
  std::printf(
      "undercut (rays): normal %.3f mm^3, chosen %.3f; blockout removed: normal %.3f, "
      "chosen %.3f\n",
      r.undercut_plain_mm3, r.undercut_chosen_mm3, removed[0], removed[1]);
  EXPECT_LT(removed[1], removed[0]);
}

// The memory contract: compute_outline runs in an arena of exactly compute_outline_bound()
// bytes, and in exactly the high water of a first run (one byte less fails cleanly). On two
// threads (the bands' indexes and the pair searches in tasks, each in slices of the arena) it
// runs in the bound too, and in the serial run's need (serially where the slices do not fit),
// with the serial run's picks.
TEST(Outline, RunsInItsBoundAndInItsMeasuredNeed) {
  PhantomJaws p(24000);
  test::TestArena store{size_t{64} << 20};
  Mesh jaws[2];
  copy_mesh(p.jaw[0], store.arena, &jaws[0], RigidTransform{});
  copy_mesh(p.jaw[1], store.arena, &jaws[1], RigidTransform{});
  OutlineOptions opened;
  opened.has_bite_opening = true;
  opened.bite_opening_mm = 2;
  OutlineOptions surveyed = opened;
  surveyed.survey = true;
  for (const OutlineOptions& options : {opened, surveyed}) {
    const uint64_t bound = compute_outline_bound(jaws[0], jaws[1]);
    uint64_t need = 0;
    std::vector<Pick> serial_picks;
    {
      test::TestArena exact{static_cast<size_t>(bound)};
      Outline o;
      SPLINTCORE_ASSERT_OK(compute_outline(Context(&exact.arena), jaws[0], jaws[1], options, &o));
      need = exact.arena.high_water();
      serial_picks.assign(o.upper.begin(), o.upper.end());
      serial_picks.insert(serial_picks.end(), o.lower.begin(), o.lower.end());
      std::printf("compute_outline%s: bound %llu, need %llu (%.2f)\n",
                  options.survey ? " (survey)" : "", static_cast<unsigned long long>(bound),
                  static_cast<unsigned long long>(need),
                  static_cast<double>(need) / static_cast<double>(bound));
    }
    {
      test::TestArena exact{static_cast<size_t>(need)};
      Outline o;
      SPLINTCORE_EXPECT_OK(compute_outline(Context(&exact.arena), jaws[0], jaws[1], options, &o));
    }
    {
      test::TestArena short_by_one{static_cast<size_t>(need - 1)};
      Outline o;
      const Status s = compute_outline(Context(&short_by_one.arena), jaws[0], jaws[1], options, &o);
      EXPECT_EQ(s.code(), StatusCode::kArenaExhausted) << test::format(s);
      EXPECT_EQ(short_by_one.arena.used(), 0u);
    }
    ThreadExecutor two(2);
    for (const uint64_t size : {bound, need}) {
      test::TestArena arena{static_cast<size_t>(size)};
      Outline o;
      SPLINTCORE_ASSERT_OK(compute_outline(Context(&arena.arena, &two.executor(), nullptr), jaws[0],
                                           jaws[1], options, &o));
      EXPECT_LE(arena.arena.high_water(), size);
      std::vector<Pick> picks(o.upper.begin(), o.upper.end());
      picks.insert(picks.end(), o.lower.begin(), o.lower.end());
      ASSERT_EQ(picks.size(), serial_picks.size());
      EXPECT_EQ(std::memcmp(picks.data(), serial_picks.data(), sizeof(Pick) * picks.size()), 0);
      if (size == bound) {
        std::printf("compute_outline%s on two threads: need %llu\n",
                    options.survey ? " (survey)" : "",
                    static_cast<unsigned long long>(arena.arena.high_water()));
      }
    }
  }
}

// The same outline at every thread count: the jaws' checks, columns, band marks and extremes
// (one task a jaw) and the arch's projections (runs of points) split over the executor, with
// the bite opened from occlusion and the survey on.
TEST(Outline, SameBitsAtEveryThreadCount) {
  PhantomJaws p(87000);
  test::TestArena t{size_t{512} << 20};
  Mesh jaws[2];
  copy_mesh(p.jaw[0], t.arena, &jaws[0], RigidTransform{});
  copy_mesh(p.jaw[1], t.arena, &jaws[1], RigidTransform{});
  OutlineOptions options;
  options.has_bite_opening = true;
  options.bite_opening_mm = 2;
  options.survey = true;
  Outline ref;
  SPLINTCORE_ASSERT_OK(compute_outline(Context(&t.arena), jaws[0], jaws[1], options, &ref));
  ASSERT_TRUE(ref.report.opened);
  ASSERT_GE(ref.upper.size(), 20u);
  for (unsigned threads : {1u, 2u, 3u, 4u}) {
    ThreadExecutor pool(threads);
    ArenaScope scope(t.arena);
    Outline o;
    SPLINTCORE_ASSERT_OK(compute_outline(Context(&t.arena, &pool.executor(), nullptr), jaws[0],
                                         jaws[1], options, &o));
    ASSERT_EQ(o.upper.size(), ref.upper.size()) << threads;
    ASSERT_EQ(o.arch.size(), ref.arch.size()) << threads;
    EXPECT_EQ(std::memcmp(o.upper.data(), ref.upper.data(), sizeof(Pick) * o.upper.size()), 0);
    EXPECT_EQ(std::memcmp(o.lower.data(), ref.lower.data(), sizeof(Pick) * o.lower.size()), 0);
    EXPECT_EQ(std::memcmp(o.arch.data(), ref.arch.data(), sizeof(Vec3) * o.arch.size()), 0);
    const OutlineReport &a = o.report, &b = ref.report;
    EXPECT_EQ(std::memcmp(&a.occlusal_normal, &b.occlusal_normal, sizeof(Vec3)), 0) << threads;
    EXPECT_EQ(std::memcmp(&a.mandible_translation, &b.mandible_translation, sizeof(Vec3)), 0);
    EXPECT_EQ(std::memcmp(&a.insertion_direction, &b.insertion_direction, sizeof(Vec3)), 0);
    EXPECT_EQ(a.opening, b.opening) << threads;
    EXPECT_EQ(a.gap_as_given, b.gap_as_given) << threads;
    EXPECT_EQ(a.arch_length_mm, b.arch_length_mm) << threads;
    EXPECT_EQ(a.min_wafer_mm, b.min_wafer_mm) << threads;
    EXPECT_EQ(a.undercut_chosen_mm3, b.undercut_chosen_mm3) << threads;
  }
}

// The jaws' checks on the executor: the maxilla's error first, whichever task ends first.
TEST(Outline, BothJawsCheckedMaxillaFirst) {
  PhantomJaws p(24000);
  test::TestArena t{size_t{64} << 20};
  Mesh jaws[2];
  copy_mesh(p.jaw[0], t.arena, &jaws[0], RigidTransform{});
  copy_mesh(p.jaw[1], t.arena, &jaws[1], RigidTransform{});
  jaws[0].vertices[5].x = std::numeric_limits<double>::quiet_NaN();
  jaws[1].triangles[7].v[1] = static_cast<uint32_t>(jaws[1].vertices.size());
  ThreadExecutor pool(2);
  for (const Executor* e : {static_cast<const Executor*>(nullptr), &pool.executor()}) {
    Outline o;
    const Status s =
        compute_outline(Context(&t.arena, e, nullptr), jaws[0], jaws[1], OutlineOptions{}, &o);
    EXPECT_EQ(s.code(), StatusCode::kNonFinite) << test::format(s);
    EXPECT_NE(std::strstr(s.message(), "maxilla"), nullptr) << test::format(s);
  }
}

// A closed 20 mm cube from `corner`, each face a grid of 0.25 mm squares (two triangles each).
void block(Arena& arena, const Vec3& corner, Mesh* out) {
  const int n = 80;
  const double step = 20.0 / n;
  out->bind(&arena);
  // Six faces: origin, u, v (outward normal u x v).
  const Vec3 faces[6][3] = {{{0, 0, 0}, {0, 1, 0}, {1, 0, 0}}, {{0, 0, 1}, {1, 0, 0}, {0, 1, 0}},
                            {{0, 0, 0}, {1, 0, 0}, {0, 0, 1}}, {{0, 1, 0}, {0, 0, 1}, {1, 0, 0}},
                            {{0, 0, 0}, {0, 0, 1}, {0, 1, 0}}, {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
  std::vector<SoupTriangle> soup;
  for (const auto& f : faces) {
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) {
        auto at = [&](int a, int b) {
          return corner + (f[0] * 20.0 + f[1] * (a * step) + f[2] * (b * step));
        };
        const Vec3 q[2][3] = {{at(i, j), at(i + 1, j), at(i + 1, j + 1)},
                              {at(i, j), at(i + 1, j + 1), at(i, j + 1)}};
        for (const auto& tri : q) {
          SoupTriangle st;
          for (int k = 0; k < 3; ++k) {
            st.p[k][0] = static_cast<float>(tri[k].x);
            st.p[k][1] = static_cast<float>(tri[k].y);
            st.p[k][2] = static_cast<float>(tri[k].z);
          }
          soup.push_back(st);
        }
      }
    }
  }
  EXPECT_TRUE(test::mesh_from_soup(arena, soup, out).is_ok());
}

// Closed bands of constant height, welded into one mesh: each from z0 up to z1 over the strip
// between its stations' inner and outer points (in the plane z = 0), walls at both ends.
class Bands {
 public:
  // A band along `stations` (at least two): {inner x, inner y, outer x, outer y} (mm), the
  // inner points on the left of the way from the first station to the last.
  void add(const std::vector<std::array<double, 4>>& stations, double z0, double z1) {
    const int n = static_cast<int>(stations.size()) - 1;
    // Corner c of station k: c = 0 inner bottom, 1 outer bottom, 2 outer top, 3 inner top.
    auto at = [&](int k, int c) {
      const std::array<double, 4>& s = stations[static_cast<size_t>(k)];
      const bool outer = c == 1 || c == 2;
      return Vec3{outer ? s[2] : s[0], outer ? s[3] : s[1], c < 2 ? z0 : z1};
    };
    for (int k = 0; k < n; ++k) {
      for (int c = 0; c < 4; ++c) {  // the four walls, outward
        quad(at(k, c), at(k + 1, c), at(k + 1, (c + 1) % 4), at(k, (c + 1) % 4));
      }
    }
    quad(at(0, 0), at(0, 1), at(0, 2), at(0, 3));
    quad(at(n, 3), at(n, 2), at(n, 1), at(n, 0));
  }
  void weld(Arena& arena, Mesh* out) const {
    EXPECT_TRUE(test::mesh_from_soup(arena, soup_, out).is_ok());
    MeshReport report;
    EXPECT_TRUE(check_mesh(Context(&arena), *out, &report).is_ok());
    EXPECT_TRUE(report.is_valid_solid());
  }

 private:
  void quad(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
    triangle(a, b, c);
    triangle(a, c, d);
  }
  void triangle(const Vec3& a, const Vec3& b, const Vec3& c) {
    SoupTriangle st;
    const Vec3* p[3] = {&a, &b, &c};
    for (int k = 0; k < 3; ++k) {
      st.p[k][0] = static_cast<float>(p[k]->x);
      st.p[k][1] = static_cast<float>(p[k]->y);
      st.p[k][2] = static_cast<float>(p[k]->z);
    }
    soup_.push_back(st);
  }
  std::vector<SoupTriangle> soup_;
};

// A horseshoe: the ring between radii r - 1 and r + 1 mm around the origin from angle a0 to
// a1 (radians, counter-clockwise) in `segments` steps, from z0 up to z1.
void horseshoe(Arena& arena, double r, double a0, double a1, int segments, double z0, double z1,
               Mesh* out) {
  std::vector<std::array<double, 4>> stations;
  for (int k = 0; k <= segments; ++k) {
    const double a = a0 + (a1 - a0) * k / segments, c = std::cos(a), s = std::sin(a);
    stations.push_back({(r - 1) * c, (r - 1) * s, (r + 1) * c, (r + 1) * s});
  }
  Bands bands;
  bands.add(stations, z0, z1);
  bands.weld(arena, out);
}

// Two bars 0.1 mm wide along the line through the origin at angle a (radians), from 20 to 40
// mm on either side of it, in stations 0.25 mm apart, from z0 up to z1.
void spokes(Arena& arena, double a, double z0, double z1, Mesh* out) {
  Bands bands;
  for (const double side : {1.0, -1.0}) {
    const double c = side * std::cos(a), s = side * std::sin(a);
    std::vector<std::array<double, 4>> stations;
    for (int k = 0; k <= 80; ++k) {
      const double d = 20 + 0.25 * k;
      stations.push_back({d * c - 0.05 * s, d * s + 0.05 * c, d * c + 0.05 * s, d * s - 0.05 * c});
    }
    bands.add(stations, z0, z1);
  }
  bands.weld(arena, out);
}

// Jaws that are not dental arches, each refused with what is wrong with it and the arena as it
// was; the same shapes where they do make an arch are accepted.
TEST(Outline, ShapesThatAreNoArchAreRefused) {
  test::TestArena t{size_t{256} << 20};
  const Context ctx(&t.arena);
  struct Result {
    Status status;
    double arch_mm = 0;
    size_t picks = 0;
  };
  // Both jaws made by `make`, the maxilla over z = 0.5 and the mandible under z = -0.5.
  auto outline = [&](const std::function<void(double, double, Mesh*)>& make,
                     const OutlineOptions& options) {
    ArenaScope scope(t.arena);
    Mesh jaws[2];
    make(0.5, 10, &jaws[0]);
    make(-10, -0.5, &jaws[1]);
    const size_t used = t.arena.used();
    Outline o;
    Result r;
    r.status = compute_outline(ctx, jaws[0], jaws[1], options, &o);
    r.arch_mm = o.report.arch_length_mm;
    r.picks = o.upper.size();
    if (!r.status.is_ok()) {
      EXPECT_EQ(t.arena.used(), used) << r.status.message();
    }
    return r;
  };
  // The number the message gives after `prefix`.
  auto number_after = [](const Status& s, const char* prefix) {
    const std::string m = s.message();
    EXPECT_EQ(m.rfind(prefix, 0), 0u) << m;
    return std::strtod(m.c_str() + std::strlen(prefix), nullptr);
  };
  const OutlineOptions defaults;

  // Two thin bars on a line through their centre (at 0.9 degrees: the middle of a sector):
  // every point lies in one of two directions from the centre.
  {
    const Result r = outline(
        [&](double z0, double z1, Mesh* m) { spokes(t.arena, 0.0157, z0, z1, m); }, defaults);
    EXPECT_EQ(r.status.code(), StatusCode::kInvalidArgument);
    EXPECT_STREQ(r.status.message(),
                 "outline: the arch is too short: the teeth fill only 2 of 128 sectors around "
                 "their centre");
  }
  // A horseshoe 2 mm wide of centre radius 4 mm round 4.1 radians (16.4 mm, less the ends
  // that curl): under the 20 mm an arch needs end to end. With a radius of 25 mm it is one.
  {
    auto small = [&](double z0, double z1, Mesh* m) {
      horseshoe(t.arena, 4, -0.5, 3.6, 40, z0, z1, m);
    };
    const Result r = outline(small, defaults);
    EXPECT_EQ(r.status.code(), StatusCode::kInvalidArgument);
    const double mm = number_after(r.status, "outline: the arch is too short: ");
    EXPECT_EQ(mm, r.arch_mm);
    EXPECT_GT(mm, 12.0);
    EXPECT_LT(mm, 16.4);
    EXPECT_NE(std::string(r.status.message()).find(" mm end to end (at least 20)"),
              std::string::npos);
    const Result big = outline(
        [&](double z0, double z1, Mesh* m) { horseshoe(t.arena, 25, -0.5, 3.6, 100, z0, z1, m); },
        defaults);
    EXPECT_TRUE(big.status.is_ok()) << big.status.message();
    EXPECT_GT(big.arch_mm, 90.0);  // 102.5 mm along the centre, less the ends
  }
  // A ring of centre radius 110 mm round 5.9 radians (649 mm, and the overhang at both ends):
  // more than 256 picks 2 mm apart; 3 mm apart (the default) it has its picks.
  {
    auto ring = [&](double z0, double z1, Mesh* m) {
      horseshoe(t.arena, 110, -1.4, 4.5, 400, z0, z1, m);
    };
    OutlineOptions two;
    two.pick_spacing_mm = 2;
    const Result r = outline(ring, two);
    EXPECT_EQ(r.status.code(), StatusCode::kInvalidArgument);
    const double mm = number_after(r.status, "outline: the arch is ");
    EXPECT_GT(mm, 600.0);
    EXPECT_LT(mm, 653.0);
    EXPECT_NE(std::string(r.status.message()).find(" mm long: more than 256 picks at 2 mm apart"),
              std::string::npos)
        << r.status.message();
    const Result three = outline(ring, defaults);
    EXPECT_TRUE(three.status.is_ok()) << three.status.message();
    EXPECT_GT(three.picks, 200u);
    EXPECT_LE(three.picks, 256u);
  }
}

// The jaws are moved (and checked finite) in chunks on the executor: the first bad vertex in
// jaw order is named, maxilla before mandible, at 1 and 2 threads alike.
TEST(Outline, BadVertexNamedInJawOrderInParallel) {
  PhantomJaws p(6000);
  test::TestArena t{size_t{256} << 20};
  ThreadExecutor threads(2);
  Mesh jaws[2];
  copy_mesh(p.jaw[0], t.arena, &jaws[0], RigidTransform{});
  copy_mesh(p.jaw[1], t.arena, &jaws[1], RigidTransform{});
  CaseFile c;
  SPLINTCORE_ASSERT_OK(parse(t.arena, auto_case("", -2.0), &c));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  auto resolve = [&](const Executor* executor) {
    ArenaScope scope(t.arena);
    CaseFile resolved;
    return resolve_case_outline(Context(&t.arena, executor, nullptr), c, Span<const Mesh>(jaws, 2),
                                &resolved, nullptr);
  };
  const Vec3 last = jaws[1].vertices[jaws[1].vertices.size() - 1];
  jaws[1].vertices[jaws[1].vertices.size() - 1].z = nan;  // the mandible's last vertex
  for (const Executor* e : {static_cast<const Executor*>(nullptr), &threads.executor()}) {
    const Status s = resolve(e);
    EXPECT_EQ(s.code(), StatusCode::kNonFinite);
    EXPECT_NE(std::string(s.message()).find("jaw 1 (mandible) has a vertex that is not finite"),
              std::string::npos)
        << s.message();
  }
  const Vec3 first = jaws[0].vertices[0];
  jaws[0].vertices[0].x = nan;  // and the maxilla's first: the maxilla is named
  for (const Executor* e : {static_cast<const Executor*>(nullptr), &threads.executor()}) {
    const Status s = resolve(e);
    EXPECT_NE(std::string(s.message()).find("jaw 0 (maxilla) has a vertex that is not finite"),
              std::string::npos)
        << s.message();
  }
  jaws[0].vertices[0] = first;
  jaws[1].vertices[jaws[1].vertices.size() - 1] = last;
  SPLINTCORE_EXPECT_OK(resolve(&threads.executor()));
}

TEST(Outline, RefusalsSayWhy) {
  PhantomJaws p(6000);
  test::TestArena t{size_t{256} << 20};
  const Context ctx(&t.arena);
  Mesh jaws[2];
  copy_mesh(p.jaw[0], t.arena, &jaws[0], RigidTransform{});
  copy_mesh(p.jaw[1], t.arena, &jaws[1], RigidTransform{});
  auto refused = [&](const std::string& text, Span<const Mesh> given, const char* why) {
    ArenaScope scope(t.arena);
    CaseFile c;
    Status s = parse(t.arena, text, &c);
    if (s.is_ok()) {
      CaseFile resolved;
      s = resolve_case_outline(ctx, c, given, &resolved, nullptr);
    }
    EXPECT_FALSE(s.is_ok()) << why;
    EXPECT_NE(std::string(s.message()).find(why), std::string::npos) << s.message();
  };
  const Span<const Mesh> both(jaws, 2);
  refused(auto_case("", 0.0), both, "interpenetrate as given");
  refused(auto_case("", 0.0), both, "bite_opening_mm");
  refused(auto_case("", -25.0), both, "more than 10 mm apart");
  // One jaw only.
  refused(
      "{\"splintcore_case\": 1, \"jaws\": [{\"role\": \"maxilla\", \"mesh\": \"m.stl\"}], "
      "\"base\": {\"auto\": {}}}",
      Span<const Mesh>(jaws, 1), "needs one mandible");
  // Jaws side by side, not facing: the mandible moved 80 mm along x.
  {
    ArenaScope scope(t.arena);
    Mesh aside;
    copy_mesh(p.jaw[1], t.arena, &aside, RigidTransform::translation(Vec3{80, 0, 0}));
    Outline o;
    const Status s = compute_outline(ctx, jaws[0], aside, OutlineOptions{}, &o);
    EXPECT_NE(std::string(s.message()).find("do not face each other"), std::string::npos)
        << s.message();
  }
  // No arch: two finely tessellated blocks facing each other, 1 mm apart.
  {
    ArenaScope scope(t.arena);
    Mesh blocks[2];
    block(t.arena, Vec3{0, 0, 0.5}, &blocks[0]);
    block(t.arena, Vec3{0, 0, -20.5}, &blocks[1]);
    Outline o;
    const Status s = compute_outline(ctx, blocks[0], blocks[1], OutlineOptions{}, &o);
    EXPECT_FALSE(s.is_ok());
    EXPECT_NE(std::string(s.message()).find("no dental arch"), std::string::npos) << s.message();
  }
  // A wafer too thin to print: the bite opened 0.1 mm and each arch indented 0.1 mm leave
  // under the 1 mm the wafer needs at the first pick; the message says what to change.
  {
    ArenaScope scope(t.arena);
    OutlineOptions thin;
    thin.indentation_depth_mm = 0.1;
    thin.has_bite_opening = true;
    thin.bite_opening_mm = 0.1;
    Outline o;
    const Status s = compute_outline(ctx, jaws[0], jaws[1], thin, &o);
    EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
    const std::string m = s.message();
    EXPECT_EQ(m.rfind("outline: the wafer would be 0.6", 0), 0u) << m;
    EXPECT_NE(m.find(" mm thick at pick 0 (at least 1): the jaws are too close there; open the "
                     "bite (\"bite_opening_mm\") or indent less"),
              std::string::npos)
        << m;
    EXPECT_EQ(s.index(), 0u);
  }
  // Options out of range: each named with its range and the value given (NaN is out of
  // every range), the arena as it was.
  {
    OutlineOptions bad;
    bad.indentation_depth_mm = 0;
    Outline o;
    EXPECT_NE(std::string(compute_outline(ctx, jaws[0], jaws[1], bad, &o).message())
                  .find("indentation_depth_mm"),
              std::string::npos);
    const std::pair<void (*)(OutlineOptions*), const char*> ranges[] = {
        {[](OutlineOptions* x) { x->overhang_mm = 10.5; },
         "outline: overhang_mm must be in [0, 10], not 10.5"},
        {[](OutlineOptions* x) { x->overhang_mm = std::nan(""); },
         "outline: overhang_mm must be in [0, 10], not nan"},
        {[](OutlineOptions* x) { x->pick_spacing_mm = 1.5; },
         "outline: pick_spacing_mm must be in [2, 20], not 1.5"},
        {[](OutlineOptions* x) {
           x->has_bite_opening = true;
           x->bite_opening_mm = 0.05;
         },
         "outline: bite_opening_mm must be in [0.1, 10], not 0.05"},
        {[](OutlineOptions* x) { x->max_gap_mm = 60; },
         "outline: max_gap_mm must be in [0.1, 50], not 60"}};
    for (const auto& [edit, text] : ranges) {
      OutlineOptions options;
      edit(&options);
      const size_t used = t.arena.used();
      const Status s = compute_outline(ctx, jaws[0], jaws[1], options, &o);
      EXPECT_EQ(s.code(), StatusCode::kInvalidArgument) << text;
      EXPECT_STREQ(s.message(), text);
      EXPECT_EQ(t.arena.used(), used);
    }
    // A bite opening out of range is no error when none is asked for.
    OutlineOptions unused;
    unused.bite_opening_mm = 0.05;
    EXPECT_EQ(std::string(compute_outline(ctx, jaws[0], jaws[1], unused, &o).message())
                  .find("bite_opening_mm must be"),
              std::string::npos);
  }
}

}  // namespace
}  // namespace splintcore
