// The memory contract, tested as a firmware engineer would use it (issue 27): every sizing
// function `<function>_bound()` is a true upper bound. Each function runs in an arena over a
// buffer of exactly its bound (16-byte aligned, as the C API and TestArena give) on varied
// inputs: tiny, degenerate, open, large, the phantom jaw and, when ../shared/realdata is there,
// the real dentition (887,688 triangles). A run may fail on its input (an open mesh is not a
// solid), but never with kArenaExhausted. On the large inputs the bound must also be useful:
// the run's high water is at least a third of it (printed per case, need / bound).
//
// The model is meshoptimizer's tests, which allocate exactly meshopt_...Bound() bytes.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include "common/phantom.h"
#include "common/realcase.h"
#include "common/shapes.h"
#include "splintcore/blockout.h"
#include "splintcore/boolean.h"
#include "splintcore/ct.h"
#include "splintcore/design.h"
#include "splintcore/distance.h"
#include "splintcore/label.h"
#include "splintcore/mesh.h"
#include "splintcore/remesh.h"
#include "splintcore/render.h"
#include "splintcore/segment.h"
#include "splintcore/spline.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

using test::format;
using test::TestArena;

struct Input {
  std::string name;
  std::vector<SoupTriangle> soup;
  bool large = false;  // the bound must be within 3x of the need
};

SoupTriangle tri(float ax, float ay, float az, float bx, float by, float bz, float cx, float cy,
                 float cz) {
  const float a[3] = {ax, ay, az}, b[3] = {bx, by, bz}, c[3] = {cx, cy, cz};
  return shapes::soup_triangle(a, b, c);
}

std::vector<SoupTriangle> tetrahedron() {
  return {tri(0, 0, 0, 0, 1, 0, 1, 0, 0), tri(0, 0, 0, 1, 0, 0, 0, 0, 1),
          tri(0, 0, 0, 0, 0, 1, 0, 1, 0), tri(1, 0, 0, 0, 1, 0, 0, 0, 1)};
}

// The triangles of an indexed mesh appended to a soup (float32 corners, as STL holds them).
void append_soup(const std::vector<Vec3>& vertices, const std::vector<Triangle>& triangles,
                 std::vector<SoupTriangle>* soup) {
  for (const Triangle& t : triangles) {
    SoupTriangle st;
    for (int k = 0; k < 3; ++k) {
      const Vec3& p = vertices[t.v[k]];
      for (int a = 0; a < 3; ++a) st.p[k][a] = static_cast<float>(p[a]);
    }
    soup->push_back(st);
  }
}

std::vector<Input> inputs() {
  std::vector<Input> out;
  out.push_back({"tetrahedron", tetrahedron()});
  {
    // Every fault check_mesh counts: a duplicate, a flat and a collapsed triangle, a fin on
    // an edge (non-manifold), a flipped copy (orientation conflict) and a loose triangle.
    std::vector<SoupTriangle> s = tetrahedron();
    s.push_back(s[1]);
    s.push_back(tri(0, 0, 0, 0.5f, 0, 0, 1, 0, 0));
    s.push_back(tri(2, 2, 2, 2, 2, 2, 2, 2, 2));
    s.push_back(tri(0, 0, 0, 1, 0, 0, 0.5f, -1, 0.5f));
    s.push_back(tri(0, 1, 0, 0, 0, 0, 1, 0, 0));
    s.push_back(tri(5, 5, 5, 6, 5, 5, 5, 6, 5));
    out.push_back({"degenerate", s});
  }
  out.push_back({"one_triangle", {tri(0, 0, 0, 1, 0, 0, 0, 1, 0)}});
  {
    std::vector<SoupTriangle> s = shapes::torus(40, 20, 10.0, 3.0);
    s.resize(s.size() - 37);  // open: a ragged hole
    out.push_back({"open_torus", s});
  }
  out.push_back({"torus_87k", shapes::torus(360, 121, 20.0, 6.0), true});
  {
    phantom::PhantomOptions po;
    po.target_triangles = 6000;
    phantom::JawMesh jaw;
    if (phantom::make_jaw(phantom::Jaw::kMaxilla, po, &jaw).is_ok()) {
      std::vector<SoupTriangle> s;
      append_soup(jaw.vertices, jaw.triangles, &s);
      out.push_back({"phantom_maxilla_6000", s, true});
    }
  }
  realcase::RealCase rc;
  std::string error;
  if (realcase::load(SPLINTCORE_REALDATA_DIR, 0.0, 2.0, 8.0, &rc, &error)) {
    std::vector<SoupTriangle> s;
    for (const realcase::Tooth& t : rc.teeth) append_soup(t.vertices, t.triangles, &s);
    out.push_back({"real_dentition", s, true});
  }
  return out;
}

// Runs `run` in an arena of exactly `bound` bytes: it must not run out, and on a large input
// it must need at least a third of the bound.
template <class Run>
void expect_fits(const Input& in, const char* function, uint64_t bound, Run run) {
  SCOPED_TRACE(std::string(function) + " on " + in.name);
  ASSERT_GT(bound, 0u);
  TestArena ta(static_cast<size_t>(bound));
  const Status s = run(ta.arena);
  EXPECT_NE(s.code(), StatusCode::kArenaExhausted) << format(s) << " (bound " << bound << ")";
  EXPECT_EQ(ta.arena.cap(), bound);
  std::printf("%-22s %-28s bound %11llu need %11llu (%.2f)%s\n", function, in.name.c_str(),
              static_cast<unsigned long long>(bound),
              static_cast<unsigned long long>(ta.arena.high_water()),
              static_cast<double>(ta.arena.high_water()) / static_cast<double>(bound),
              s.is_ok() ? "" : (std::string("  [") + format(s) + "]").c_str());
  if (in.large && s.is_ok()) {
    EXPECT_GE(ta.arena.high_water() * 3, bound);
  }
}

// The welded mesh of an input, in its own arena (outside the one under test).
struct Welded {
  TestArena storage{size_t{512} << 20};
  Mesh mesh;
  explicit Welded(const Input& in) {
    mesh.bind(&storage.arena);
    Status s = weld_exact(Context(&storage.arena),
                          Span<const SoupTriangle>(in.soup.data(), in.soup.size()), &mesh);
    EXPECT_TRUE(s.is_ok()) << format(s);
  }
  uint64_t v() const { return mesh.vertices.size(); }
  uint64_t t() const { return mesh.triangles.size(); }
};

TEST(BoundExact, WeldExact) {
  for (const Input& in : inputs()) {
    expect_fits(in, "weld_exact", weld_exact_bound(in.soup.size()), [&](Arena& arena) {
      Mesh out(&arena);
      return weld_exact(Context(&arena), Span<const SoupTriangle>(in.soup.data(), in.soup.size()),
                        &out);
    });
  }
}

TEST(BoundExact, CheckMesh) {
  for (const Input& in : inputs()) {
    Welded w(in);
    expect_fits(in, "check_mesh", check_mesh_bound(w.v(), w.t()), [&](Arena& arena) {
      MeshReport report;
      return check_mesh(Context(&arena), w.mesh, &report);
    });
    expect_fits(in, "check_closed_oriented", check_closed_oriented_bound(w.v(), w.t()),
                [&](Arena& arena) {
                  double volume = 0;
                  return check_closed_oriented(Context(&arena), w.mesh, &volume);
                });
  }
}

TEST(BoundExact, FindSelfIntersections) {
  for (const Input& in : inputs()) {
    Welded w(in);
    for (uint64_t max_pairs : {uint64_t{0}, uint64_t{1}}) {
      expect_fits(in, "find_self_intersections", find_self_intersections_bound(w.t()),
                  [&](Arena& arena) {
                    SelfIntersectionReport report;
                    return find_self_intersections(Context(&arena), w.mesh, max_pairs, &report);
                  });
    }
  }
}

TEST(BoundExact, BuildDistanceIndex) {
  for (const Input& in : inputs()) {
    Welded w(in);
    for (uint32_t leaf : {0u, 1u, 16u}) {
      for (bool oriented : {false, true}) {
        DistanceIndexOptions options;
        options.leaf_size = leaf;
        options.oriented_boxes = oriented;
        expect_fits(in, "build_distance_index", distance_index_bound(w.v(), w.t(), options),
                    [&](Arena& arena) {
                      DistanceIndex index;
                      return build_distance_index(Context(&arena), w.mesh, options, &index);
                    });
      }
    }
  }
}

TEST(BoundExact, TaubinSmooth) {
  for (const Input& in : inputs()) {
    Welded w(in);
    for (double clamp : {0.0, 0.05}) {
      TaubinOptions options;
      options.iterations = 2;
      options.max_displacement = clamp;
      expect_fits(in, "taubin_smooth", taubin_smooth_bound(w.v(), w.t()),
                  [&](Arena& arena) { return taubin_smooth(Context(&arena), &w.mesh, options); });
    }
  }
}

TEST(BoundExact, DecimateQem) {
  for (const Input& in : inputs()) {
    Welded w(in);
    DecimateOptions options;
    options.target_triangles = w.t() / 2;
    expect_fits(in, "decimate_qem", decimate_qem_bound(w.v(), w.t()), [&](Arena& arena) {
      Mesh out(&arena);
      return decimate_qem(Context(&arena), w.mesh, options, &out);
    });
  }
}

TEST(BoundExact, BuildSplintBase) {
  // The paper-scale arch at three spacings; the bound takes the section count the report
  // gives (the two-step contract: the count comes from the lines alone, see spline.h).
  TestArena scratch;
  Context sctx(&scratch.arena);
  const Pick upper[] = {
      {{-20, -5, 10}}, {{-12, 12, 10}}, {{0, 18, 10}}, {{12, 12, 10}}, {{20, -5, 10}}};
  const Pick lower[] = {{{-20, -5, 5}}, {{-12, 12, 5}}, {{0, 18, 5}}, {{12, 12, 5}}, {{20, -5, 5}}};
  Pick up[5], lo[5];
  for (int i = 0; i < 5; ++i) {
    up[i] = upper[i];
    lo[i] = lower[i];
    up[i].inner_length = lo[i].inner_length = 4;
    up[i].outside_length = lo[i].outside_length = 4;
  }
  ArenaArray<Line> ul(&scratch.arena), ll(&scratch.arena);
  SPLINTCORE_ASSERT_OK(make_lines(sctx, Span<const Pick>(up, 5), Vec3{0, 0, 1}, "upper", &ul));
  SPLINTCORE_ASSERT_OK(make_lines(sctx, Span<const Pick>(lo, 5), Vec3{0, 0, 1}, "lower", &ll));
  for (double spacing : {2.0, 0.5, 0.1}) {
    for (double radius : {0.0, 0.8}) {
      BaseParams params;
      params.spacing_mm = spacing;
      params.corner_radius_mm = radius;
      BaseReport report;
      {
        TestArena big;
        Mesh out(&big.arena);
        SPLINTCORE_ASSERT_OK(build_splint_base(Context(&big.arena), Span<const Line>(ul.data(), 5),
                                               Span<const Line>(ll.data(), 5), params, &out,
                                               &report));
      }
      Input in{"arch spacing " + std::to_string(spacing) + " radius " + std::to_string(radius),
               {},
               spacing < 1.0};
      expect_fits(in, "build_splint_base",
                  splint_base_bound(report.sections, report.points_per_section), [&](Arena& arena) {
                    Mesh out(&arena);
                    BaseReport r;
                    return build_splint_base(Context(&arena), Span<const Line>(ul.data(), 5),
                                             Span<const Line>(ll.data(), 5), params, &out, &r);
                  });
    }
  }
}

TEST(BoundExact, RenderAndPng) {
  for (const Input& in : inputs()) {
    Welded w(in);
    for (uint32_t side : {1u, 64u, 640u}) {
      // The mesh opaque and, drawn again, translucent with Gouraud shading: the bound's case.
      RenderMesh items[2];
      items[0].mesh = &w.mesh;
      items[1].mesh = &w.mesh;
      items[1].alpha = 100;
      RenderOptions options;
      options.width = side;
      options.height = side;
      options.view_count = side == 1 ? 1 : 4;
      options.shading = RenderShading::kGouraud;
      RenderImage image;
      std::vector<uint8_t> kept;
      expect_fits(in, "render_meshes", render_bound(side, side, 2 * w.v(), 2, options.view_count),
                  [&](Arena& arena) {
                    const Status s = render_meshes(
                        Context(&arena), Span<const RenderMesh>(items, 2), options, &image);
                    if (s.is_ok()) kept.assign(image.rgb, image.rgb + size_t{side} * side * 3);
                    return s;
                  });
      if (kept.empty()) continue;
      image.rgb = kept.data();
      Input png_input{in.name + " " + std::to_string(side) + " px", {}, side == 640};
      expect_fits(png_input, "write_png", png_bound(side, side), [&](Arena& arena) {
        ByteSink discard;
        discard.write = [](void*, const uint8_t*, size_t) { return true; };
        return write_png(Context(&arena), image, discard);
      });
    }
  }
}

// A CT-like volume: a block of bone (2000 HU) with a bump, in air, n voxels a side.
struct BoneVolume {
  std::vector<int16_t> hu;
  CtVolume v;
  explicit BoneVolume(uint32_t n) {
    hu.assign(size_t{n} * n * n, -1000);
    v.nx = v.ny = v.nz = n;
    v.spacing = Vec3{0.3, 0.3, 0.3};
    v.hu = hu.data();
    for (uint32_t k = n / 4; k < 3 * n / 4; ++k) {
      for (uint32_t j = n / 4; j < 3 * n / 4; ++j) {
        for (uint32_t i = n / 4; i < 3 * n / 4 + (k % 5 == 0 ? n / 8 : 0); ++i) {
          hu[(size_t{k} * n + j) * n + i] = 2000;
        }
      }
    }
  }
};

TEST(BoundExact, CtSegmentation) {
  for (uint32_t n : {8u, 40u, 160u}) {
    BoneVolume bone(n);
    Input in{"bone cube " + std::to_string(n), {}, n == 160};
    // Threshold, then grow from the centre, then mesh the region: each in exactly its bound,
    // the inputs of the next made in an arena of their own.
    expect_fits(in, "threshold_window", threshold_window_bound(bone.v), [&](Arena& arena) {
      LabelVolume labels;
      return threshold_window(Context(&arena), bone.v, HuWindow{}, &labels);
    });
    TestArena storage(size_t{64} << 20);
    Context sctx(&storage.arena);
    LabelVolume labels;
    ThresholdStats ts;
    SPLINTCORE_ASSERT_OK(threshold_window(sctx, bone.v, HuWindow{}, &labels, &ts));
    RegionSeed seed;
    seed.in_patient_mm = false;
    seed.i = seed.j = seed.k = n / 2;
    std::vector<uint8_t> before(labels.labels, labels.labels + labels.voxel_count());
    expect_fits(in, "grow_regions", grow_regions_bound(ts.in_window), [&](Arena& arena) {
      std::copy(before.begin(), before.end(), labels.labels);
      return grow_regions(Context(&arena), bone.v, Span<const RegionSeed>(&seed, 1),
                          RegionGrowOptions{}, &labels);
    });
    // The two-step contract: the box and the mesh's size from a first run, then the bound.
    ReconstructStats rs;
    {
      Mesh probe(&storage.arena);
      SPLINTCORE_ASSERT_OK(
          reconstruct_region(sctx, bone.v, labels, ReconstructOptions{}, &probe, &rs));
      const uint32_t box[3] = {rs.box_hi[0] - rs.box_lo[0] + 1, rs.box_hi[1] - rs.box_lo[1] + 1,
                               rs.box_hi[2] - rs.box_lo[2] + 1};
      const uint64_t bound = reconstruct_region_bound(
          box, rs.marching.layers_per_tile, probe.vertices.size(), probe.triangles.size());
      expect_fits(in, "reconstruct_region", bound, [&](Arena& arena) {
        Mesh out(&arena);
        ReconstructOptions ro;
        ro.layers_per_tile = rs.marching.layers_per_tile;
        return reconstruct_region(Context(&arena), bone.v, labels, ro, &out);
      });
    }
  }
}

// The two-step contract of the functions without an a-priori bound (embedding.md): a first
// run in any arena large enough gives the need, the arena's high water; the same input then
// runs in exactly that many bytes, and fails cleanly in one byte less. Allocation depends on
// the input alone, so the need measured once (on a workstation) holds on the device.
template <class Run>
void expect_two_step(const char* function, const char* input, Run run) {
  SCOPED_TRACE(std::string(function) + " on " + input);
  uint64_t need = 0;
  {
    TestArena big(size_t{1} << 30);
    SPLINTCORE_ASSERT_OK(run(big.arena));
    need = big.arena.high_water();
  }
  {
    TestArena exact(static_cast<size_t>(need));
    SPLINTCORE_EXPECT_OK(run(exact.arena));
    EXPECT_EQ(exact.arena.high_water(), need);
  }
  {
    TestArena short_by_one(static_cast<size_t>(need - 1));
    const Status s = run(short_by_one.arena);
    EXPECT_EQ(s.code(), StatusCode::kArenaExhausted) << format(s);
    EXPECT_EQ(short_by_one.arena.used(), 0u) << "the arena is as it was";
  }
  std::printf("%-22s %-34s need %11llu bytes, exactly enough\n", function, input,
              static_cast<unsigned long long>(need));
}

// The paper-scale case (fixtures/cases/paper_scale.json or blockout.json) and two phantom jaws
// of 6,000 triangles, in an arena of their own.
struct PhantomCase {
  TestArena storage{size_t{128} << 20};
  std::vector<uint8_t> text;
  CaseFile c;
  Mesh jaws[2];
  explicit PhantomCase(const char* case_name) {
    Context ctx(&storage.arena);
    text = test::read_file_bytes(std::string(SPLINTCORE_FIXTURES_DIR) + "/cases/" + case_name);
    EXPECT_TRUE(
        parse_case(ctx, reinterpret_cast<const char*>(text.data()), text.size(), case_name, &c)
            .is_ok());
    for (int j = 0; j < 2; ++j) {
      phantom::JawMesh m;
      phantom::PhantomOptions po;
      po.target_triangles = 6000;
      EXPECT_TRUE(
          phantom::make_jaw(j == 0 ? phantom::Jaw::kMaxilla : phantom::Jaw::kMandible, po, &m)
              .is_ok());
      jaws[j].bind(&storage.arena);
      for (const Vec3& v : m.vertices) (void)jaws[j].vertices.push_back(v);
      for (const Triangle& tr : m.triangles) (void)jaws[j].triangles.push_back(tr);
    }
  }
};

TEST(BoundTwoStep, DesignBooleanBlockoutLabel) {
  for (const char* name : {"paper_scale.json", "blockout.json"}) {
    PhantomCase pc(name);
    expect_two_step("design_splint", name, [&](Arena& arena) {
      Mesh splint(&arena);
      DesignReport report;
      return design_splint(Context(&arena), pc.c, Span<const Mesh>(pc.jaws, 2), &splint, &report);
    });
  }
  // The stages on their own: the base minus the maxilla, its blockout, a label on it.
  PhantomCase pc("paper_scale.json");
  Context sctx(&pc.storage.arena);
  Mesh base(&pc.storage.arena);
  BaseReport br;
  SPLINTCORE_ASSERT_OK(build_case_base(sctx, pc.c, &base, &br));
  Mesh cut(&pc.storage.arena);
  BooleanOptions bo;
  SPLINTCORE_ASSERT_OK(mesh_boolean(sctx, base, pc.jaws[0], bo, &cut, nullptr));
  expect_two_step("mesh_boolean", "base - phantom maxilla", [&](Arena& arena) {
    Mesh out(&arena);
    return mesh_boolean(Context(&arena), base, pc.jaws[0], bo, &out, nullptr);
  });
  BlockoutOptions bl;
  bl.sweep.direction = Vec3{0, 0, 1};
  bl.sweep.voxel = 0.3;
  bl.sweep.inset = 0.15;
  expect_two_step("blockout", "cut, phantom maxilla, 0.3 mm", [&](Arena& arena) {
    Mesh out(&arena);
    return blockout(Context(&arena), cut, Span<const Mesh>(&pc.jaws[0], 1), bl, &out);
  });
  ArenaArray<Line> upper(&pc.storage.arena), lower(&pc.storage.arena);
  SPLINTCORE_ASSERT_OK(make_lines(sctx, pc.c.upper, pc.c.occlusal_normal, "upper", &upper));
  SPLINTCORE_ASSERT_OK(make_lines(sctx, pc.c.lower, pc.c.occlusal_normal, "lower", &lower));
  LabelOptions lo;
  lo.text = "CASE-27";
  expect_two_step("apply_label", "cut, \"CASE-27\"", [&](Arena& arena) {
    Mesh out(&arena);
    LabelStats stats;
    return apply_label(Context(&arena), cut, upper.span(), lower.span(), lo, &out, &stats);
  });
}

}  // namespace
}  // namespace splintcore
