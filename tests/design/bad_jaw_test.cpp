// Every bad input of issue 30 named: a jaw that is a triangle soup without any tooth (a flat
// sheet, or loose triangles), wherever it goes (the design with its picks, with the automatic
// outline, as a jaw's scan in the fusion, in a plan); two scans of the same jaw (the case file,
// and a case built in code); the scan whose border crosses the outline is
// DesignFusion.ScanWhoseBorderCrossesTheBaseIsNamed (fusion_test.cpp). Each is an error that
// says what is wrong, where and what to do, with nothing made and the arena as it was.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "common/realcase.h"
#include "design/no_jaw.h"
#include "splintcore/design.h"
#include "splintcore/platform.h"
#include "splintcore/registration.h"
#include "support/phantom_jaws.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

// A seeded counter: uniform in [0, 1).
struct Uniform {
  uint64_t state;
  double operator()() {
    state += 0x9e3779b97f4a7c15ull;
    return static_cast<double>(hash_mix(state) >> 11) * (1.0 / 9007199254740992.0);
  }
};

// A flat sheet over the arch's footprint (60 x 55 mm in 1 mm squares) at height z.
void flat_sheet(double z, Mesh* m) {
  const uint32_t nx = 60, ny = 55;
  for (uint32_t j = 0; j <= ny; ++j) {
    for (uint32_t i = 0; i <= nx; ++i) {
      ASSERT_TRUE(m->vertices.push_back(Vec3{-30.0 + i, -10.0 + j, z}));
    }
  }
  for (uint32_t j = 0; j < ny; ++j) {
    for (uint32_t i = 0; i < nx; ++i) {
      const uint32_t a = j * (nx + 1) + i;
      ASSERT_TRUE(m->triangles.push_back(Triangle{{a, a + 1, a + nx + 2}}));
      ASSERT_TRUE(m->triangles.push_back(Triangle{{a, a + nx + 2, a + nx + 1}}));
    }
  }
}

// 2000 loose triangles (about 1 mm each, no corner shared) over the same footprint, z in
// [z_lo, z_hi].
void loose_triangles(double z_lo, double z_hi, Mesh* m) {
  Uniform u{7};
  for (uint32_t t = 0; t < 2000; ++t) {
    const Vec3 c{-30 + 60 * u(), -10 + 55 * u(), z_lo + (z_hi - z_lo) * u()};
    const uint32_t first = static_cast<uint32_t>(m->vertices.size());
    for (int k = 0; k < 3; ++k) {
      Vec3 p = c + Vec3{u() - 0.5, u() - 0.5, u() - 0.5};
      ASSERT_TRUE(round_to_float32(&p));
      ASSERT_TRUE(m->vertices.push_back(p));
    }
    ASSERT_TRUE(m->triangles.push_back(Triangle{{first, first + 1, first + 2}}));
  }
}

struct Soup {
  const char* what;
  const char* says;  // the cause, as the message gives it
  Mesh mesh;
};

// The paper-scale case and the phantom jaws, and four soups in place of the mandible: a sheet
// through the base and one below it, loose triangles through the base and below it.
struct BadJaws {
  test::TestArena t{size_t{192} << 20};
  CaseFile c;
  Mesh jaws[2];
  Soup soups[4] = {{"a flat sheet through the base",
                    "has no teeth: all its vertices lie within 0 "
                    "mm of one plane (normal 0, 0, 1;",
                    Mesh()},
                   {"a flat sheet below the base", "has no teeth", Mesh()},
                   {"loose triangles through the base",
                    "is a triangle soup, not a jaw: its 2000 triangles form 2000 pieces", Mesh()},
                   {"loose triangles below the base", "is a triangle soup", Mesh()}};
  bool ok = false;
  BadJaws() {
    const std::vector<uint8_t> text =
        test::read_file_bytes(std::string(SPLINTCORE_FIXTURES_DIR) + "/cases/paper_scale.json");
    if (!parse_case(Context(&t.arena), reinterpret_cast<const char*>(text.data()), text.size(),
                    "paper_scale", &c)
             .is_ok() ||
        !test::phantom_jaw_meshes(t.arena, 6000, jaws)) {
      return;
    }
    for (Soup& s : soups) s.mesh.bind(&t.arena);
    flat_sheet(1.8, &soups[0].mesh);  // z = -0.2 after the mandible's move: inside the base
    flat_sheet(-3.0, &soups[1].mesh);
    loose_triangles(-3.0, 3.0, &soups[2].mesh);
    loose_triangles(-8.0, -5.0, &soups[3].mesh);
    ok = !::testing::Test::HasFatalFailure();
  }
};

// The error's rules: the code, the message's start (the place) and cause, nothing made, the
// arena as it was.
void expect_named(const Status& s, const std::string& starts, const char* says, const Mesh& splint,
                  size_t used_before, const Arena& arena) {
  EXPECT_EQ(s.code(), StatusCode::kInvalidMesh) << test::format(s);
  const std::string m = s.message();
  EXPECT_EQ(m.rfind(starts, 0), 0u) << m;
  EXPECT_NE(m.find(says), std::string::npos) << m;
  EXPECT_NE(m.find("check "), std::string::npos) << m;  // what to do
  EXPECT_LT(m.size(), Status::kMessageCapacity - 1) << "truncated: " << m;
  EXPECT_TRUE(splint.triangles.empty() && splint.vertices.empty());
  EXPECT_EQ(arena.used(), used_before);
}

// design_splint of the fixture's case with `given`, with its picks or (automatic) the
// automatic outline; *used is the arena's use before the call.
Status design_as(BadJaws& f, const Context& ctx, const Mesh (&given)[2], bool automatic,
                 Mesh* splint, size_t* used) {
  CaseFile c = f.c;
  c.has_auto_outline = automatic;
  *used = f.t.arena.used();
  DesignReport r;
  return design_splint(ctx, c, Span<const Mesh>(given, 2), splint, &r);
}

TEST(DesignBadJaws, TriangleSoupWithoutAnyToothIsNamedWhereverItGoes) {
  BadJaws f;
  ASSERT_TRUE(f.ok);
  Context ctx(&f.t.arena);
  for (const Soup& soup : f.soups) {
    SCOPED_TRACE(soup.what);
    // As the mandible: with the case's picks (where a soup below the base would otherwise give
    // the base back, nothing subtracted) and with the automatic outline.
    const Mesh given[2] = {f.jaws[0], soup.mesh};
    for (bool automatic : {false, true}) {
      size_t used = 0;
      Mesh splint;
      const Status s = design_as(f, ctx, given, automatic, &splint, &used);
      expect_named(s, "design: jaw 1 (mandible) ", soup.says, splint, used, f.t.arena);
      EXPECT_EQ(s.index(), 1u);
    }
    // As the mandible's scan (the fusion would fit it to the jaw).
    CaseJaw scanned[2] = {f.c.jaws[0], f.c.jaws[1]};
    scanned[1].has_scan = true;
    scanned[1].scan.path = "soup.stl";
    CaseFile c = f.c;
    c.jaws = Span<const CaseJaw>(scanned, 2);
    const Mesh scans[2] = {Mesh(), soup.mesh};
    const size_t used = f.t.arena.used();
    Mesh splint;
    DesignReport r;
    Status s =
        design_splint(ctx, c, Span<const Mesh>(f.jaws, 2), Span<const Mesh>(scans, 2), &splint, &r);
    expect_named(s, "design: the scan of jaw 1 (mandible) ", soup.says, splint, used, f.t.arena);
    EXPECT_FALSE(r.fused[1]);  // refused before the registration
    // In a plan: the plan's autorotation and fusion never see it.
    const std::string plan = R"({"splintcore_case": 1, "case_id": "plan-soup",
      "jaws": [{"role": "maxilla", "mesh": "maxilla.stl"}, {"role": "mandible", "mesh": "m.stl"}],
      "base": {"spacing_mm": 0.5, "auto": {}},
      "plan": {"sequence": "maxilla_first", "maxilla": [1,0,0,0, 0,1,0,2, 0,0,1,1, 0,0,0,1],
        "mandible": [1,0,0,0, 0,1,0,2.5, 0,0,1,0, 0,0,0,1],
        "hinge_axis": [[-50, -55, 25], [50, -55, 25]],
        "intermediate_opening_mm": 2, "final_opening_mm": 1.5}})";
    CaseFile pc;
    SPLINTCORE_ASSERT_OK(parse_case(ctx, plan.data(), plan.size(), "plan.json", &pc));
    const size_t before = f.t.arena.used();
    Mesh intermediate, final_splint;
    PlanReport pr;
    s = design_plan(ctx, pc, Span<const Mesh>(given, 2), &intermediate, &final_splint, &pr);
    expect_named(s, "plan: design: jaw 1 (mandible) ", soup.says, final_splint, before, f.t.arena);
    EXPECT_TRUE(intermediate.triangles.empty());
  }
  // The real jaws pass the same check: the unchanged case makes its splint.
  Mesh splint;
  DesignReport r;
  SPLINTCORE_EXPECT_OK(design_splint(ctx, f.c, Span<const Mesh>(f.jaws, 2), &splint, &r));
}

// The jaws are checked each in a task of its own (refuse_no_jaw, then check_jaws): with two bad
// jaws the first is named, the same error with one thread and with two.
TEST(DesignBadJaws, TheFirstBadJawIsNamedWhenTheyAreCheckedInParallel) {
  BadJaws f;
  ASSERT_TRUE(f.ok);
  ThreadExecutor pool(2);
  // A soup and a flat sheet; then a jaw with a vertex that is NaN and one with a triangle
  // naming a vertex that does not exist.
  Mesh nan_jaw(&f.t.arena), broken_jaw(&f.t.arena);
  for (const Vec3& p : f.jaws[0].vertices) ASSERT_TRUE(nan_jaw.vertices.push_back(p));
  for (const Triangle& t : f.jaws[0].triangles) ASSERT_TRUE(nan_jaw.triangles.push_back(t));
  for (const Vec3& p : f.jaws[1].vertices) ASSERT_TRUE(broken_jaw.vertices.push_back(p));
  for (const Triangle& t : f.jaws[1].triangles) ASSERT_TRUE(broken_jaw.triangles.push_back(t));
  nan_jaw.vertices[5].y = std::nan("");
  broken_jaw.triangles[7].v[2] = static_cast<uint32_t>(broken_jaw.vertices.size());
  const Mesh soups[2] = {f.soups[2].mesh, f.soups[0].mesh};
  const Mesh broken[2] = {nan_jaw, broken_jaw};
  for (unsigned threads : {1u, 2u}) {
    SCOPED_TRACE(threads);
    Context ctx(&f.t.arena, threads == 1 ? nullptr : &pool.executor(), nullptr);
    const size_t used = f.t.arena.used();
    Mesh splint;
    DesignReport r;
    Status s = design_splint(ctx, f.c, Span<const Mesh>(soups, 2), &splint, &r);
    expect_named(s, "design: jaw 0 (maxilla) ", "is a triangle soup", splint, used, f.t.arena);
    EXPECT_EQ(s.index(), 0u);
    s = design_splint(ctx, f.c, Span<const Mesh>(broken, 2), &splint, &r);
    EXPECT_EQ(s.code(), StatusCode::kNonFinite) << test::format(s);
    EXPECT_EQ(std::string(s.message()),
              "design: jaw 0 (maxilla) has a vertex that is not finite (NaN or infinity): "
              "vertex 5");
    EXPECT_EQ(f.t.arena.used(), used);
  }
}

// Where the check draws its lines: a flat sheet with 1.2 mm of relief (a bump) is past the flat
// test, and pieces of 4 triangles (a tetrahedron's surface each) are past the soup test; one
// triangle less a piece (3 loose triangles sharing a corner) is a soup.
TEST(DesignBadJaws, TheLinesAreWhereTheDocumentationDrawsThem) {
  BadJaws f;
  ASSERT_TRUE(f.ok);
  Context ctx(&f.t.arena);
  const auto design_with = [&](const Mesh& mandible) {
    const Mesh given[2] = {f.jaws[0], mandible};
    Mesh splint;
    DesignReport r;
    return design_splint(ctx, f.c, Span<const Mesh>(given, 2), &splint, &r);
  };
  Mesh bumped(&f.t.arena), flat_by_a_hair(&f.t.arena);
  flat_sheet(-3.0, &bumped);
  flat_sheet(-3.0, &flat_by_a_hair);
  bumped.vertices[bumped.vertices.size() / 2].z += 1.2;
  EXPECT_EQ(std::string(design_with(bumped).message()).find("has no teeth"), std::string::npos);
  flat_by_a_hair.vertices[flat_by_a_hair.vertices.size() / 2].z += 0.8;
  const Status flat = design_with(flat_by_a_hair);
  EXPECT_NE(std::string(flat.message()).find("has no teeth: all its vertices lie within 0.8 mm"),
            std::string::npos)
      << flat.message();
  // Tetrahedra far below the base: past the soup and size tests, refused only as out of reach.
  Mesh pieces(&f.t.arena), fans(&f.t.arena);
  for (uint32_t k = 0; k < 50; ++k) {
    const Vec3 o{-25.0 + k, 0, -30};
    const uint32_t b = static_cast<uint32_t>(pieces.vertices.size());
    for (const Vec3& d : {Vec3{0, 0, 0}, Vec3{0.5, 0, 0}, Vec3{0, 0.5, 0}, Vec3{0, 0, 0.5}}) {
      ASSERT_TRUE(pieces.vertices.push_back(o + d));
      ASSERT_TRUE(fans.vertices.push_back(o + d));
    }
    for (const Triangle& t : {Triangle{{b, b + 2, b + 1}}, Triangle{{b, b + 1, b + 3}},
                              Triangle{{b, b + 3, b + 2}}, Triangle{{b + 1, b + 2, b + 3}}}) {
      ASSERT_TRUE(pieces.triangles.push_back(t));
      if (t.v[0] == b) {  // 3 a piece
        ASSERT_TRUE(fans.triangles.push_back(t));
      }
    }
  }
  const auto past_the_shape_tests = [](const Status& s) {
    return std::string(s.message()).find("does not reach the base") != std::string::npos;
  };
  EXPECT_TRUE(past_the_shape_tests(design_with(pieces))) << design_with(pieces).message();
  // The size line: the same 50 tetrahedra 9.9 mm across are too small for a jaw in mm, 10.1 mm
  // across are not (refused only as out of reach).
  for (double across : {9.9, 10.1}) {
    Mesh row(&f.t.arena);
    const double step = (across - 0.5) / 49;
    for (uint32_t k = 0; k < 50; ++k) {
      for (uint32_t c = 0; c < 4; ++c) {
        ASSERT_TRUE(row.vertices.push_back(pieces.vertices[4 * k + c] +
                                           Vec3{(25.0 + k * (step - 1.0)), 0, 0}));
      }
      for (uint32_t c = 0; c < 4; ++c)
        ASSERT_TRUE(row.triangles.push_back(pieces.triangles[4 * k + c]));
    }
    const Status s = design_with(row);
    if (across < 10) {
      EXPECT_NE(std::string(s.message()).find("is 9.9 x 0.5 x 0.5 across: too small"),
                std::string::npos)
          << s.message();
    } else {
      EXPECT_TRUE(past_the_shape_tests(s)) << s.message();
    }
  }
  const Status fan = design_with(fans);
  EXPECT_NE(std::string(fan.message())
                .find("is a triangle soup, not a jaw: its 150 triangles "
                      "form 50 pieces"),
            std::string::npos)
      << fan.message();
}

// A jaw whose file is in other units than the case's mm (issue 29's review: with the case's
// picks, a maxilla in inches made a splint that imprinted only the mandible, with no word of
// it): named with its size and the factor to mm, as a jaw and as a scan.
TEST(DesignBadJaws, AJawInOtherUnitsIsNamedWithTheFactorToMm) {
  BadJaws f;
  ASSERT_TRUE(f.ok);
  Context ctx(&f.t.arena);
  struct Units {
    double scale;  // from mm to the file's units
    const char* says;
    const char* factor;
  };
  const Units units[] = {{1 / 25.4, "across: too small for a jaw in mm (at least 10 mm)", "x25.4"},
                         {0.1, "too small", "x10"},
                         {0.001, "too small", "x1000"},
                         {1000, "across: too large for a jaw in mm (at most 1000 mm)", "x0.001"}};
  for (const Units& u : units) {
    SCOPED_TRACE(u.scale);
    Mesh scaled(&f.t.arena);
    for (Vec3 p : f.jaws[0].vertices) {
      p = p * u.scale;
      ASSERT_TRUE(round_to_float32(&p));
      ASSERT_TRUE(scaled.vertices.push_back(p));
    }
    for (const Triangle& t : f.jaws[0].triangles) ASSERT_TRUE(scaled.triangles.push_back(t));
    const Mesh given[2] = {scaled, f.jaws[1]};
    for (bool automatic : {false, true}) {
      size_t used = 0;
      Mesh splint;
      const Status s = design_as(f, ctx, given, automatic, &splint, &used);
      expect_named(s, "design: jaw 0 (maxilla) is ", u.says, splint, used, f.t.arena);
      EXPECT_NE(std::string(s.message()).find(u.factor), std::string::npos) << s.message();
      EXPECT_EQ(s.index(), 0u);
      if (automatic) {  // the outline alone (as the CLI resolves it first) names it the same way
        CaseFile c = f.c, resolved;
        c.has_auto_outline = true;
        const Status o =
            resolve_case_outline(ctx, c, Span<const Mesh>(given, 2), &resolved, nullptr);
        expect_named(o, "design: jaw 0 (maxilla) is ", u.says, splint, used, f.t.arena);
      }
    }
    CaseJaw scanned[2] = {f.c.jaws[0], f.c.jaws[1]};
    scanned[0].has_scan = true;
    scanned[0].scan.path = "scan_in_other_units.stl";
    CaseFile c = f.c;
    c.jaws = Span<const CaseJaw>(scanned, 2);
    const Mesh scans[2] = {scaled, Mesh()};
    const size_t used = f.t.arena.used();
    Mesh splint;
    DesignReport r;
    const Status s =
        design_splint(ctx, c, Span<const Mesh>(f.jaws, 2), Span<const Mesh>(scans, 2), &splint, &r);
    expect_named(s, "design: the scan of jaw 0 (maxilla) is ", u.says, splint, used, f.t.arena);
    EXPECT_NE(std::string(s.message()).find("check the scan's file"), std::string::npos);
  }
}

// A jaw that does not reach the base (given in another frame, or moved by a wrong transform)
// could leave no imprint: the splint would be the base alone on that side. Refused once the
// base is made, whatever makes the imprint (the Boolean, the exact sweep, the voxel sweep, a
// spacer's height field), naming the jaw and both boxes; nothing made, the arena as it was.
TEST(DesignBadJaws, AJawThatDoesNotReachTheBaseIsNamed) {
  BadJaws f;
  ASSERT_TRUE(f.ok);
  Context ctx(&f.t.arena);
  Mesh far(&f.t.arena);
  for (const Vec3& p : f.jaws[1].vertices) ASSERT_TRUE(far.vertices.push_back(p + Vec3{0, 0, -60}));
  for (const Triangle& t : f.jaws[1].triangles) ASSERT_TRUE(far.triangles.push_back(t));
  const Mesh given[2] = {f.jaws[0], far};
  struct Way {
    const char* what;
    bool blockout;
    BlockoutMethod method;
    double clearance;
  };
  for (const Way& w : {Way{"Boolean", false, BlockoutMethod::kAuto, 0},
                       Way{"exact sweep", true, BlockoutMethod::kExact, 0},
                       Way{"voxel sweep", true, BlockoutMethod::kVoxel, 0},
                       Way{"spacer", true, BlockoutMethod::kHeightfield, 0.2}}) {
    SCOPED_TRACE(w.what);
    CaseFile c = f.c;
    c.has_blockout = w.blockout;
    c.blockout_method = w.method;
    c.blockout.voxel = 0.5;
    c.blockout.offset = w.clearance;
    const size_t used = f.t.arena.used();
    Mesh splint;
    DesignReport r;
    const Status s = design_splint(ctx, c, Span<const Mesh>(given, 2), &splint, &r);
    expect_named(s, "design: jaw 1 (mandible) does not reach the base: placed, it spans [",
                 "] and the base [", splint, used, f.t.arena);
    EXPECT_EQ(s.index(), 1u);
  }
  // The jaws as the case places them reach it: the splint is made.
  Mesh splint;
  DesignReport r;
  SPLINTCORE_EXPECT_OK(design_splint(ctx, f.c, Span<const Mesh>(f.jaws, 2), &splint, &r));
}

// The stretches of the base where jaw j, placed (its transform, then float32), meets the base's
// outer (bit 1) or inner (bit 2) wall, by brute force: every triangle of the jaw against every
// wall triangle, with none of the check's culling, grid or side rule. The paper-scale base has
// sharp corners: four points a section, segment 1 (upper outside to lower outside) the outer
// wall, segment 3 (lower inner to upper inner) the inner one (spline.h's layout).
std::vector<uint8_t> crossings_by_brute_force(const CaseFile& c, const Mesh& jaw, size_t j,
                                              const Mesh& base, const BaseReport& built) {
  EXPECT_EQ(built.points_per_section, 4u);
  std::vector<uint8_t> hit(built.sections - 1, 0);
  for (const Triangle& t : jaw.triangles) {
    Vec3 p[3];
    for (int i = 0; i < 3; ++i) {
      p[i] = c.jaws[j].transform.apply_point(jaw.vertices[t.v[i]]);
      EXPECT_TRUE(round_to_float32(&p[i]));
    }
    if (collinear3d(p[0], p[1], p[2])) continue;
    Aabb tb;
    for (const Vec3& q : p) tb.add(q);
    for (uint32_t k = 0; k + 1 < built.sections; ++k) {
      for (uint32_t segment : {1u, 3u}) {
        for (uint32_t h = 0; h < 2; ++h) {
          const Triangle& w = base.triangles[2 * (k * 4 + segment) + h];
          Aabb wb;
          for (uint32_t v : w.v) wb.add(base.vertices[v]);
          if (tb.overlaps(wb) &&
              triangles_intersect(p[0], p[1], p[2], base.vertices[w.v[0]], base.vertices[w.v[1]],
                                  base.vertices[w.v[2]])) {
            hit[k] |= segment == 1 ? 1 : 2;
          }
        }
      }
    }
  }
  return hit;
}

// The report's figures for jaw j against the brute force's stretches: the same stretches, the
// lengths of the same section centres.
void expect_walls_as_brute_force(const CaseFile& c, const Mesh (&jaws)[2], const DesignReport& r) {
  test::TestArena t{size_t{32} << 20};
  Mesh base(&t.arena);
  BaseReport built;
  SPLINTCORE_ASSERT_OK(build_case_base(Context(&t.arena), c, &base, &built));
  ASSERT_EQ(r.wall_jaws, 2u);
  for (size_t j = 0; j < 2; ++j) {
    SCOPED_TRACE(c.jaws[j].role);
    const std::vector<uint8_t> hit = crossings_by_brute_force(c, jaws[j], j, base, built);
    auto centre = [&](uint32_t k) {
      Vec3 sum{};
      for (uint32_t i = 0; i < 4; ++i) sum = sum + base.vertices[k * 4 + i];
      return sum * 0.25;
    };
    double arch = 0, outer = 0, inner = 0, either = 0;
    uint32_t crossed = 0, first = 0;
    for (uint32_t k = 0; k < hit.size(); ++k) {
      const double len = length(centre(k + 1) - centre(k));
      arch += len;
      outer += (hit[k] & 1) != 0 ? len : 0;
      inner += (hit[k] & 2) != 0 ? len : 0;
      either += hit[k] != 0 ? len : 0;
      if (hit[k] != 0 && crossed++ == 0) first = k;
    }
    // The halves: a stretch whose middle lies before half the arch's length is the first's.
    double half_outer[2] = {0, 0}, half_inner[2] = {0, 0}, before = 0;
    for (uint32_t k = 0; k < hit.size(); ++k) {
      const double len = length(centre(k + 1) - centre(k));
      const int h = before + len / 2 < arch / 2 ? 0 : 1;
      before += len;
      half_outer[h] += (hit[k] & 1) != 0 ? len : 0;
      half_inner[h] += (hit[k] & 2) != 0 ? len : 0;
    }
    const double sideways =
        std::max(std::min(half_outer[0], half_inner[1]), std::min(half_inner[0], half_outer[1]));
    const WallCrossing& w = r.walls[j];
    EXPECT_EQ(w.stretches, built.sections - 1);
    EXPECT_EQ(w.crossed, crossed);
    if (crossed > 0) {
      EXPECT_EQ(w.first_stretch, first);
    }
    EXPECT_NEAR(w.arch_mm, arch, 1e-9);
    EXPECT_NEAR(w.outer_mm, outer, 1e-9);
    EXPECT_NEAR(w.inner_mm, inner, 1e-9);
    EXPECT_NEAR(w.either_mm, either, 1e-9);
    for (int h = 0; h < 2; ++h) {
      EXPECT_NEAR(w.half_outer_mm[h], half_outer[h], 1e-9) << "half " << h;
      EXPECT_NEAR(w.half_inner_mm[h], half_inner[h], 1e-9) << "half " << h;
    }
    EXPECT_NEAR(w.sideways_mm(), sideways, 1e-9);
  }
}

// A jaw moved sideways by a wrong transform, still touching the base: its imprint crosses the
// base's side walls (its teeth outside the outline), which the base's reach check cannot see.
// Measured on every design against a brute force (the case's own jaws: no crossing; the
// mandible 3 mm to the side: much of the arch, the outer wall in one half, the inner in the
// other). By default (max_sideways_crossing 0.05) that is refused, naming the jaw and both
// lengths, nothing made; with 1 the splint is made and the report holds it. With
// max_wall_crossing below the share the design is refused naming the jaw, the lengths and
// where; at exactly either share it is not.
// Designing c, whose mandible sits 3 mm to one side, is refused as sideways of the base by
// default: nothing made, the arena as it was. Returns the refusal.
Status expect_refused_sideways(BadJaws& f, const Context& ctx, const CaseFile& c, DesignReport* r) {
  Mesh refused;
  const size_t used = f.t.arena.used();
  const Status s = design_splint(ctx, c, Span<const Mesh>(f.jaws, 2), &refused, r);
  expect_named(s, "design: jaw 1 (mandible) sits to one side of the base: it crosses the ",
               "max_sideways_crossing 0.05); check the jaw's transform and the picks", refused,
               used, f.t.arena);
  return s;
}

TEST(DesignBadJaws, AJawMovedSidewaysCrossesTheSideWalls) {
  BadJaws f;
  ASSERT_TRUE(f.ok);
  Context ctx(&f.t.arena);
  Mesh splint(&f.t.arena);
  DesignReport r;
  SPLINTCORE_ASSERT_OK(design_splint(ctx, f.c, Span<const Mesh>(f.jaws, 2), &splint, &r));
  expect_walls_as_brute_force(f.c, f.jaws, r);
  EXPECT_EQ(r.walls[0].crossed + r.walls[1].crossed, 0u);
  EXPECT_GT(r.walls[0].arch_mm, 100.0);  // the paper's arch

  CaseJaw moved[2] = {f.c.jaws[0], f.c.jaws[1]};
  moved[1].transform = compose(RigidTransform::translation(Vec3{3, 0, 0}), moved[1].transform);
  CaseFile c = f.c;
  c.jaws = Span<const CaseJaw>(moved, 2);
  DesignReport rs;
  EXPECT_EQ(expect_refused_sideways(f, ctx, c, &rs).index(), 1u);
  c.max_sideways_crossing = 1;
  Mesh shifted(&f.t.arena);
  SPLINTCORE_ASSERT_OK(design_splint(ctx, c, Span<const Mesh>(f.jaws, 2), &shifted, &rs));
  expect_walls_as_brute_force(c, f.jaws, rs);
  EXPECT_EQ(rs.walls[0].crossed, 0u);
  const WallCrossing w = rs.walls[1];
  EXPECT_GT(w.outer_mm, 10.0);
  EXPECT_GT(w.inner_mm, 10.0);
  const double share = w.either_mm / w.arch_mm;
  EXPECT_GT(share, 0.3);
  // The outer wall in one half, the inner in the other: sideways, most of each.
  EXPECT_GT(w.sideways_share(), 0.25);
  EXPECT_EQ(std::min(w.half_inner_mm[0], w.half_outer_mm[1]), 0.0);
  {
    CaseFile at = c;
    at.max_sideways_crossing = w.sideways_share();
    Mesh made(&f.t.arena);
    SPLINTCORE_EXPECT_OK(design_splint(ctx, at, Span<const Mesh>(f.jaws, 2), &made, &rs));
  }

  c.max_wall_crossing = 0.1;
  Mesh refused;
  const size_t used = f.t.arena.used();
  const Status s = design_splint(ctx, c, Span<const Mesh>(f.jaws, 2), &refused, &rs);
  expect_named(s, "design: jaw 1 (mandible) crosses the base's side walls along ", "), first at [",
               refused, used, f.t.arena);
  EXPECT_EQ(s.index(), 1u);
  c.max_wall_crossing = share;
  Mesh at_share(&f.t.arena);
  SPLINTCORE_EXPECT_OK(design_splint(ctx, c, Span<const Mesh>(f.jaws, 2), &at_share, &rs));
}

// A base with rounded corners has more points a section (4 (segments + 1): 8 with one arc
// segment, 68 with 16, the most the case allows); its walls are measured as the sharp base's:
// the jaws in place cross none, the mandible 3 mm sideways is refused.
TEST(DesignBadJaws, RoundedBasesMeasureTheSideWallsToo) {
  BadJaws f;
  ASSERT_TRUE(f.ok);
  Context ctx(&f.t.arena);
  for (uint32_t segments : {1u, 16u}) {
    SCOPED_TRACE(segments);
    CaseFile c = f.c;
    c.base.corner_radius_mm = 0.8;
    c.base.corner_segments = segments;
    Mesh splint(&f.t.arena);
    DesignReport r;
    SPLINTCORE_ASSERT_OK(design_splint(ctx, c, Span<const Mesh>(f.jaws, 2), &splint, &r));
    EXPECT_EQ(r.base.points_per_section, 4 * (segments + 1));
    ASSERT_EQ(r.wall_jaws, 2u);
    EXPECT_GT(r.walls[0].arch_mm, 100.0);
    EXPECT_EQ(r.walls[0].crossed + r.walls[1].crossed, 0u);
    CaseJaw moved[2] = {f.c.jaws[0], f.c.jaws[1]};
    moved[1].transform = compose(RigidTransform::translation(Vec3{3, 0, 0}), moved[1].transform);
    c.jaws = Span<const CaseJaw>(moved, 2);
    (void)expect_refused_sideways(f, ctx, c, &r);
  }
}

// The check's figures (its culling in the jaw's frame, its grid of the walls, its side rule,
// the arch's halves) against the brute force, on random placements of the mandible (up to 4 mm
// sideways and along, 1.5 mm up or down, turned up to 6 degrees about the occlusal normal),
// serially and on two workers (the same figures, bit for bit); measured, not refused
// (max_sideways_crossing 1).
TEST(DesignBadJaws, PropertySideWallCrossingsAreTheBruteForces) {
  BadJaws f;
  ASSERT_TRUE(f.ok);
  Mesh base(&f.t.arena);
  BaseReport built;
  SPLINTCORE_ASSERT_OK(build_case_base(Context(&f.t.arena), f.c, &base, &built));
  ThreadExecutor pool(2);
  Uniform u{2026};
  uint32_t crossing = 0;
  for (int trial = 0; trial < 8; ++trial) {
    const double angle = (u() - 0.5) * 0.21;
    RigidTransform turn;
    turn.r[0][0] = turn.r[1][1] = std::cos(angle);
    turn.r[0][1] = -std::sin(angle);
    turn.r[1][0] = std::sin(angle);
    turn.t = Vec3{8 * (u() - 0.5), 8 * (u() - 0.5), 3 * (u() - 0.5)};
    CaseJaw moved[2] = {f.c.jaws[0], f.c.jaws[1]};
    moved[1].transform = compose(turn, moved[1].transform);
    CaseFile c = f.c;
    c.jaws = Span<const CaseJaw>(moved, 2);
    c.max_sideways_crossing = 1;
    SCOPED_TRACE(testing::Message() << "trial " << trial << ": angle " << angle << ", move "
                                    << turn.t.x << ", " << turn.t.y << ", " << turn.t.z);
    DesignReport serial, two;
    const size_t used = f.t.arena.used();
    SPLINTCORE_ASSERT_OK(design_detail::measure_side_walls(
        Context(&f.t.arena), c, Span<const Mesh>(f.jaws, 2), base, built, &serial));
    EXPECT_EQ(f.t.arena.used(), used);
    SPLINTCORE_ASSERT_OK(
        design_detail::measure_side_walls(Context(&f.t.arena, &pool.executor(), nullptr), c,
                                          Span<const Mesh>(f.jaws, 2), base, built, &two));
    expect_walls_as_brute_force(c, f.jaws, serial);
    for (size_t j = 0; j < 2; ++j) {
      EXPECT_EQ(std::memcmp(&serial.walls[j], &two.walls[j], sizeof(WallCrossing)), 0);
    }
    crossing += serial.walls[1].crossed > 0 ? 1 : 0;
  }
  EXPECT_GE(crossing, 4u);  // the placements cross the walls, most of them
  // A coarse jaw: a box 50 x 50 x 3 mm of 12 triangles about the base's middle (its top and
  // bottom cut the walls), each spanning more grid cells than the check walks: tested against
  // every wall instead, the same crossings.
  Mesh coarse(&f.t.arena);
  const Vec3 mid = mesh_bounds(base).center() + Vec3{0, 0, 2};  // the mandible's move undone
  for (int i = 0; i < 8; ++i) {
    ASSERT_TRUE(coarse.vertices.push_back(mid + Vec3{(i & 1) != 0 ? 25.0 : -25.0,
                                                     (i & 2) != 0 ? 25.0 : -25.0,
                                                     (i & 4) != 0 ? 1.5 : -1.5}));
  }
  static const uint32_t kFaces[12][3] = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6},
                                         {0, 1, 4}, {1, 5, 4}, {2, 6, 3}, {3, 6, 7},
                                         {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  for (const auto& t : kFaces)
    ASSERT_TRUE(coarse.triangles.push_back(Triangle{{t[0], t[1], t[2]}}));
  const Mesh with_coarse[2] = {f.jaws[0], coarse};
  CaseFile measured = f.c;  // (the box's sides cross the walls unevenly: sideways too)
  measured.max_sideways_crossing = 1;
  DesignReport r;
  SPLINTCORE_ASSERT_OK(design_detail::measure_side_walls(
      Context(&f.t.arena), measured, Span<const Mesh>(with_coarse, 2), base, built, &r));
  expect_walls_as_brute_force(measured, with_coarse, r);
  EXPECT_GT(r.walls[1].crossed, 10u);
}

// The real dentition's picks case, as splintcore-bench --export-realcase writes it (the mandible
// opened 2 mm, crowns 1.5 mm into the wafer, lines 6 mm each way): its jaws cross no side
// wall, nor does either moved 1 mm sideways; moved 3 mm, either crosses along more than a fifth
// of the arch (measured: 27% the mandible, 34% the maxilla), which max_wall_crossing 0.1
// refuses, and sideways (the outer wall in one half, the inner in the other) along more than a
// tenth (10.8%, 14.9%), which the default max_sideways_crossing refuses. Skipped without the
// data.
TEST(DesignBadJaws, RealDentitionMovedSidewaysCrossesTheSideWalls) {
  realcase::RealCase rc;
  std::string error;
  if (!realcase::load(SPLINTCORE_REALDATA_DIR, 2.0, 1.5, 6.0, &rc, &error)) {
    GTEST_SKIP() << "real dentition absent: " << error;
  }
  test::TestArena t{size_t{256} << 20};
  Mesh jaws[2] = {Mesh(&t.arena), Mesh(&t.arena)};
  for (const realcase::Tooth& tooth : rc.teeth) {
    Mesh& m = jaws[tooth.number <= 16 ? 0 : 1];
    const uint32_t first = static_cast<uint32_t>(m.vertices.size());
    for (const Vec3& v : tooth.vertices) ASSERT_TRUE(m.vertices.push_back(v));
    for (const Triangle& tr : tooth.triangles) {
      ASSERT_TRUE(
          m.triangles.push_back(Triangle{{tr.v[0] + first, tr.v[1] + first, tr.v[2] + first}}));
    }
  }
  CaseJaw placed[2];
  placed[0].role = "maxilla";
  placed[1].role = "mandible";
  CaseFile c;
  c.jaws = Span<const CaseJaw>(placed, 2);
  c.upper = Span<const Pick>(rc.upper.data(), rc.upper.size());
  c.lower = Span<const Pick>(rc.lower.data(), rc.lower.size());
  c.occlusal_normal = Vec3{0, 0, 1};
  c.base.spacing_mm = 0.5;
  const Context ctx(&t.arena);
  Mesh base(&t.arena);
  BaseReport built;
  SPLINTCORE_ASSERT_OK(build_case_base(ctx, c, &base, &built));
  DesignReport r;
  SPLINTCORE_ASSERT_OK(
      design_detail::measure_side_walls(ctx, c, Span<const Mesh>(jaws, 2), base, built, &r));
  EXPECT_EQ(r.walls[0].crossed + r.walls[1].crossed, 0u);
  for (size_t j = 0; j < 2; ++j) {
    for (double dx : {1.0, 3.0}) {
      SCOPED_TRACE(testing::Message() << placed[j].role << " moved " << dx << " mm");
      CaseJaw moved[2] = {placed[0], placed[1]};
      moved[j].transform = RigidTransform::translation(Vec3{dx, 0, 0});
      CaseFile m = c;
      m.jaws = Span<const CaseJaw>(moved, 2);
      const Status by_default =
          design_detail::measure_side_walls(ctx, m, Span<const Mesh>(jaws, 2), base, built, &r);
      m.max_sideways_crossing = 1;
      SPLINTCORE_ASSERT_OK(
          design_detail::measure_side_walls(ctx, m, Span<const Mesh>(jaws, 2), base, built, &r));
      EXPECT_EQ(r.walls[1 - j].crossed, 0u);
      const double share = r.walls[j].either_mm / r.walls[j].arch_mm;
      if (dx == 1.0) {
        SPLINTCORE_EXPECT_OK(by_default);
        EXPECT_EQ(r.walls[j].crossed, 0u);
      } else {
        EXPECT_GT(share, 0.2);
        EXPECT_GT(r.walls[j].sideways_share(), 0.1);
        EXPECT_EQ(by_default.code(), StatusCode::kInvalidMesh) << test::format(by_default);
        EXPECT_NE(std::string(by_default.message()).find("sits to one side of the base"),
                  std::string::npos)
            << by_default.message();
        EXPECT_EQ(by_default.index(), j);
        m.max_wall_crossing = 0.1;
        const Status s =
            design_detail::measure_side_walls(ctx, m, Span<const Mesh>(jaws, 2), base, built, &r);
        EXPECT_EQ(s.code(), StatusCode::kInvalidMesh) << test::format(s);
        EXPECT_EQ(s.index(), j);
      }
    }
  }
}

// With a blockout the roles say which way each jaw is swept: the maxilla along the insertion
// direction, the mandible against it. Swapped (or the direction reversed), each sweep would run
// back through the splint, leaving a valid solid with hardly an imprint: refused, naming both
// jaws. Without a blockout the roles change nothing: the same splint either way.
TEST(DesignBadJaws, SwappedRolesWithABlockoutAreNamed) {
  BadJaws f;
  ASSERT_TRUE(f.ok);
  Context ctx(&f.t.arena);
  CaseJaw swapped[2] = {f.c.jaws[0], f.c.jaws[1]};
  swapped[0].role = "mandible";
  swapped[1].role = "maxilla";
  for (BlockoutMethod m :
       {BlockoutMethod::kExact, BlockoutMethod::kVoxel, BlockoutMethod::kHeightfield}) {
    SCOPED_TRACE(blockout_method_name(m));
    CaseFile c = f.c;
    c.has_blockout = true;
    c.blockout_method = m;
    c.blockout.voxel = 0.5;
    CaseFile roles = c, reversed = c;
    roles.jaws = Span<const CaseJaw>(swapped, 2);
    reversed.insertion_direction = -c.insertion_direction;
    for (const CaseFile* bad : {&roles, &reversed}) {
      const size_t used = f.t.arena.used();
      Mesh splint;
      DesignReport r;
      const Status s = design_splint(ctx, *bad, Span<const Mesh>(f.jaws, 2), &splint, &r);
      EXPECT_EQ(s.code(), StatusCode::kInvalidArgument) << test::format(s);
      const std::string m = s.message();
      const std::string expected = bad == &roles
                                       ? "design: jaw 1 (maxilla) is below jaw 0 (mandible) along"
                                       : "design: jaw 0 (maxilla) is below jaw 1 (mandible) along";
      EXPECT_EQ(m.rfind(expected, 0), 0u) << m;
      EXPECT_NE(m.find("check the roles and the insertion direction"), std::string::npos) << m;
      EXPECT_TRUE(splint.triangles.empty());
      EXPECT_EQ(f.t.arena.used(), used);
    }
    Mesh splint;
    DesignReport r;
    SPLINTCORE_EXPECT_OK(design_splint(ctx, c, Span<const Mesh>(f.jaws, 2), &splint, &r));
  }
  CaseFile plain = f.c;
  plain.jaws = Span<const CaseJaw>(swapped, 2);
  Mesh a, b;
  DesignReport ra, rb;
  SPLINTCORE_ASSERT_OK(design_splint(ctx, f.c, Span<const Mesh>(f.jaws, 2), &a, &ra));
  SPLINTCORE_ASSERT_OK(design_splint(ctx, plain, Span<const Mesh>(f.jaws, 2), &b, &rb));
  EXPECT_EQ(test::mesh_sha256(a), test::mesh_sha256(b));
}

// The same jaw given twice (one file for both roles, the same transform): named up front, not
// left to the Boolean, which fails on its own surface meeting itself everywhere.
TEST(DesignBadJaws, TheSameJawTwiceIsNamed) {
  BadJaws f;
  ASSERT_TRUE(f.ok);
  Context ctx(&f.t.arena);
  CaseJaw same[2] = {f.c.jaws[0], f.c.jaws[1]};
  same[1].transform = same[0].transform;
  CaseFile c = f.c;
  c.jaws = Span<const CaseJaw>(same, 2);
  const Mesh twice[2] = {f.jaws[0], f.jaws[0]};
  const size_t used = f.t.arena.used();
  Mesh splint;
  DesignReport r;
  Status s = design_splint(ctx, c, Span<const Mesh>(twice, 2), &splint, &r);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument) << test::format(s);
  EXPECT_EQ(std::string(s.message()),
            "design: jaw 1 (mandible) is jaw 0 (maxilla) again: the same " +
                std::to_string(f.jaws[0].triangles.size()) +
                " triangles at the same place; check the case's jaw files (one file given for "
                "both?)");
  EXPECT_EQ(s.index(), 1u);
  EXPECT_TRUE(splint.triangles.empty());
  EXPECT_EQ(f.t.arena.used(), used);
  // Moved apart by the case's own transforms, they are two jaws to this check.
  s = design_splint(ctx, f.c, Span<const Mesh>(twice, 2), &splint, &r);
  EXPECT_EQ(std::string(s.message()).find("again"), std::string::npos) << s.message();
}

TEST(DesignBadJaws, TwoScansOfTheSameJaw) {
  test::TestArena t(size_t{4} << 20);
  Context ctx(&t.arena);
  CaseFile c;
  // In the case file: the mandible twice, each with a scan; or a list of scans.
  const std::string twice = R"({"splintcore_case": 1,
 "jaws": [{"role": "maxilla", "mesh": "maxilla.stl"},
          {"role": "mandible", "mesh": "mandible.stl", "scan": {"path": "first.ply"}},
          {"role": "mandible", "mesh": "mandible.stl", "scan": {"path": "second.ply"}}],
 "base": {"auto": {}}})";
  Status s = parse_case(ctx, twice.data(), twice.size(), "twice.json", &c);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(std::string(s.message()),
            "two jaws with the role \"mandible\" (jaws[1] and jaws[2]), each with a \"scan\": two "
            "scans of the mandible; a case takes one scan per jaw: merge them into one mesh (or "
            "choose one) and give the jaw once");
  EXPECT_EQ(s.line(), 4u);  // the second mandible's role
  const std::string list = R"({"splintcore_case": 1,
 "jaws": [{"role": "mandible", "mesh": "mandible.stl",
           "scan": [{"path": "first.ply"}, {"path": "second.ply"}]}],
 "base": {"auto": {}}})";
  s = parse_case(ctx, list.data(), list.size(), "list.json", &c);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(std::string(s.message()).find("\"scan\" is a list: a jaw takes one scan"),
            std::string::npos)
      << s.message();
  EXPECT_EQ(s.line(), 3u);
  // The same jaw twice without scans: named too, and what to do.
  const std::string plain = R"({"splintcore_case": 1,
 "jaws": [{"role": "maxilla", "mesh": "a.stl"}, {"role": "maxilla", "mesh": "b.stl"}],
 "base": {"auto": {}}})";
  s = parse_case(ctx, plain.data(), plain.size(), "plain.json", &c);
  EXPECT_EQ(std::string(s.message()),
            "two jaws with the role \"maxilla\" (jaws[0] and jaws[1]): give each jaw once");
  // Twice, the first with a scan and the second without: the jaw twice, not two scans.
  const std::string one_scan = R"({"splintcore_case": 1,
 "jaws": [{"role": "maxilla", "mesh": "a.stl", "scan": {"path": "s.ply"}},
          {"role": "maxilla", "mesh": "b.stl"}],
 "base": {"auto": {}}})";
  s = parse_case(ctx, one_scan.data(), one_scan.size(), "one_scan.json", &c);
  EXPECT_EQ(std::string(s.message()),
            "two jaws with the role \"maxilla\" (jaws[0] and jaws[1]): give each jaw once");
  // A case made in code (the C++ API does not require the parser): design refuses it before
  // anything is registered.
  const std::string one = R"({"splintcore_case": 1,
 "jaws": [{"role": "mandible", "mesh": "m.stl", "scan": {"path": "a.ply"}}],
 "base": {"upper": [{"position": [0, 0, 1]}, {"position": [10, 0, 1]}],
          "lower": [{"position": [0, 0, -1]}, {"position": [10, 0, -1]}]}})";
  SPLINTCORE_ASSERT_OK(parse_case(ctx, one.data(), one.size(), "one.json", &c));
  CaseJaw both[2] = {c.jaws[0], c.jaws[0]};
  both[1].scan.path = "b.ply";
  c.jaws = Span<const CaseJaw>(both, 2);
  Mesh jaws[2], scans[2];
  const size_t used = t.arena.used();
  Mesh splint;
  DesignReport r;
  s = design_splint(ctx, c, Span<const Mesh>(jaws, 2), Span<const Mesh>(scans, 2), &splint, &r);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(std::string(s.message()),
            "design: jaws 0 and 1 are both the mandible, each with a \"scan\": two scans of the "
            "same jaw; give one scan per jaw (merge them into one mesh, or choose one)");
  EXPECT_EQ(t.arena.used(), used);
  EXPECT_TRUE(splint.triangles.empty());
}

// `register` alone (no design to check the jaws first): a sheet or loose triangles, as the scan
// or as the CT jaw, are refused too, saying why (a fit far over the limit, with what to check;
// or a surface that does not fix the motion).
TEST(DesignBadJaws, RegistrationAloneRefusesSoupsSayingWhy) {
  BadJaws f;
  ASSERT_TRUE(f.ok);
  Context ctx(&f.t.arena);
  for (const Soup* soup : {&f.soups[0], &f.soups[2]}) {
    for (bool as_scan : {true, false}) {
      SCOPED_TRACE(std::string(soup->what) + (as_scan ? " as the scan" : " as the CT jaw"));
      const size_t used = f.t.arena.used();
      RegisterResult rr;
      const Status s = register_rigid(ctx, as_scan ? soup->mesh : f.jaws[1],
                                      as_scan ? f.jaws[1] : soup->mesh, RegisterOptions{}, &rr);
      const std::string m = s.message();
      EXPECT_TRUE(
          (s.code() == StatusCode::kLimitExceeded &&
           m.find("check that the scan and the CT are the same jaw") != std::string::npos) ||
          (s.code() == StatusCode::kInvalidMesh &&
           m.find("(a flat or symmetric surface)") != std::string::npos))
          << test::format(s);
      EXPECT_EQ(f.t.arena.used(), used);
    }
  }
}

}  // namespace
}  // namespace splintcore
