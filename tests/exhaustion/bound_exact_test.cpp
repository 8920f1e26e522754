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
#include "exhaustion/bound_util.h"
#include "splintcore/blockout.h"
#include "splintcore/boolean.h"
#include "splintcore/ct.h"
#include "splintcore/design.h"
#include "splintcore/distance.h"
#include "splintcore/label.h"
#include "splintcore/mesh.h"
#include "splintcore/printer.h"
#include "splintcore/remesh.h"
#include "splintcore/render.h"
#include "splintcore/segment.h"
#include "splintcore/spline.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

using test::format;
using test::TestArena;
using namespace bound_test;

TEST(BoundExact, WeldExact) {
  for (const Input& in : inputs()) {
    expect_fits(in, "weld_exact", weld_exact_bound(in.soup.size()), [&](Arena& arena) {
      Mesh out(&arena);
      return weld_exact(Context(&arena), Span<const SoupTriangle>(in.soup.data(), in.soup.size()),
                        &out);
    });
  }
}

TEST(BoundExact, WeldTolerance) {
  for (const Input& in : inputs()) {
    for (double tolerance : {1e-4, 0.05}) {
      expect_fits(in, "weld_tolerance", weld_tolerance_bound(in.soup.size()), [&](Arena& arena) {
        Mesh out(&arena);
        return weld_tolerance(Context(&arena),
                              Span<const SoupTriangle>(in.soup.data(), in.soup.size()), tolerance,
                              &out);
      });
    }
  }
}

TEST(BoundExact, CheckPrintableAndWallThickness) {
  for (const Input& in : inputs()) {
    Welded w(in);
    expect_fits(in, "check_printable", check_printable_bound(w.v(), w.t()), [&](Arena& arena) {
      PrintCheck check;
      return check_printable(Context(&arena), w.mesh, eden260_profile(), PrintCheckOptions{},
                             &check);
    });
    // 0.2 mm: a few thin triangles; 50 mm: every triangle thin (the largest list). Up to the
    // 87k torus: the index's bound is tried on the real dentition above, and 887k rays of
    // 50 mm take minutes at -O0 and under ASan.
    if (w.t() > 100000) continue;
    for (double min_thickness : {0.2, 50.0}) {
      Input unchecked = in;
      unchecked.large = in.large && min_thickness > 1.0;
      expect_fits(unchecked, "check_wall_thickness", check_wall_thickness_bound(w.v(), w.t()),
                  [&](Arena& arena) {
                    ThicknessReport report;
                    return check_wall_thickness(Context(&arena), w.mesh, min_thickness, &report);
                  });
    }
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

TEST(BoundExact, RemoveSmallShells) {
  for (const Input& in : inputs()) {
    Welded w(in);
    // Every shell but the largest taken out (the real dentition: 30 of its 31 teeth), from a
    // copy outside the arena measured.
    TestArena copy(static_cast<size_t>(w.v() * sizeof(Vec3) + w.t() * sizeof(Triangle)) + 4096);
    const Arena::Marker empty = copy.arena.mark();
    expect_fits(in, "remove_small_shells", remove_small_shells_bound(w.v()), [&](Arena& arena) {
      copy.arena.rewind(empty);
      Mesh mesh;
      if (!test::copy_mesh(copy.arena, w.mesh, &mesh)) return copy.arena.exhausted_status();
      SmallShells removed;
      return remove_small_shells(Context(&arena), 1e30, &mesh, &removed);
    });
  }
}

TEST(BoundExact, PrepareScan) {
  for (const Input& in : inputs()) {
    Welded w(in);
    expect_fits(in, "prepare_scan", prepare_scan_bound(w.v(), w.t()), [&](Arena& arena) {
      Mesh out;
      PrepareReport report;
      return prepare_scan(Context(&arena), w.mesh, PrepareOptions{}, &out, &report);
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
    // With the distance bound kept at samples (and three given samples on triangle 0).
    DecimateOptions bounded = options;
    bounded.keep_positions = true;
    bounded.max_distance = 0.05;
    const Triangle& t0 = w.mesh.triangles[0];
    const Vec3 samples[3] = {w.mesh.vertices[t0.v[0]], w.mesh.vertices[t0.v[1]],
                             w.mesh.vertices[t0.v[2]]};
    const uint32_t homes[3] = {0, 0, 0};
    bounded.samples = Span<const Vec3>(samples, 3);
    bounded.sample_triangles = Span<const uint32_t>(homes, 3);
    expect_fits(in, "decimate_qem max_distance", decimate_qem_bound(w.v(), w.t(), true, 3),
                [&](Arena& arena) {
                  Mesh out(&arena);
                  return decimate_qem(Context(&arena), w.mesh, bounded, &out);
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
      // The mesh opaque and, drawn again moved, translucent with Gouraud shading: the bound's case.
      RenderMesh items[2];
      items[0].mesh = &w.mesh;
      items[1].mesh = &w.mesh;
      items[1].alpha = 100;
      const RigidTransform move = RigidTransform::translation({0.5, -0.25, 1});
      items[1].transform = &move;  // the moved copy of its vertices
      RenderOptions options;
      options.width = side;
      options.height = side;
      options.view_count = side == 1 ? 1 : 4;
      options.shading = RenderShading::kGouraud;
      RenderImage image;
      std::vector<uint8_t> kept;
      expect_fits(in, "render_meshes", render_bound(side, side, w.v(), 1), [&](Arena& arena) {
        const Status s =
            render_meshes(Context(&arena), Span<const RenderMesh>(items, 2), options, &image);
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

// The paper-scale case (fixtures/cases/paper_scale.json, blockout.json, exact.json or
// heightfield.json, heightfield_spacer.json) and two
// phantom jaws of 6,000 triangles, in an arena of their own.
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
  for (const char* name : {"paper_scale.json", "blockout.json", "exact.json", "heightfield.json",
                           "heightfield_spacer.json"}) {
    PhantomCase pc(name);
    std::string result;
    expect_two_step(
        "design_splint", name,
        [&](Arena& arena) {
          Mesh splint(&arena);
          DesignReport report;
          const Status s =
              design_splint(Context(&arena), pc.c, Span<const Mesh>(pc.jaws, 2), &splint, &report);
          result = test::mesh_sha256(splint);
          return s;
        },
        true, &result);
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
  std::string result;
  expect_two_step(
      "mesh_boolean", "base - phantom maxilla",
      [&](Arena& arena) {
        Mesh out(&arena);
        const Status s = mesh_boolean(Context(&arena), base, pc.jaws[0], bo, &out, nullptr);
        result = test::mesh_sha256(out);
        return s;
      },
      true, &result);
  BlockoutOptions bl;
  bl.sweep.direction = Vec3{0, 0, 1};
  bl.sweep.voxel = 0.3;
  bl.sweep.inset = 0.15;
  expect_two_step(
      "blockout", "cut, phantom maxilla, 0.3 mm",
      [&](Arena& arena) {
        Mesh out(&arena);
        const Status s = blockout(Context(&arena), cut, Span<const Mesh>(&pc.jaws[0], 1), bl, &out);
        result = test::mesh_sha256(out);
        return s;
      },
      true, &result);
  // The exact sweep's blockout takes the uncut base (the sweep holds the jaw): the sweep, the
  // shells' check (and the splint's distance index where one crosses) and the Boolean.
  BlockoutOptions bx;
  bx.sweep.direction = Vec3{0, 0, 1};
  bx.exact = true;
  expect_two_step(
      "blockout (exact)", "base, phantom maxilla",
      [&](Arena& arena) {
        Mesh out(&arena);
        const Status s =
            blockout(Context(&arena), base, Span<const Mesh>(&pc.jaws[0], 1), bx, &out);
        result = test::mesh_sha256(out);
        return s;
      },
      true, &result);
  ArenaArray<Line> upper(&pc.storage.arena), lower(&pc.storage.arena);
  SPLINTCORE_ASSERT_OK(make_lines(sctx, pc.c.upper, pc.c.occlusal_normal, "upper", &upper));
  SPLINTCORE_ASSERT_OK(make_lines(sctx, pc.c.lower, pc.c.occlusal_normal, "lower", &lower));
  LabelOptions lo;
  lo.text = "CASE-27";
  expect_two_step("build_label_mesh", "cut, \"CASE-27\"", [&](Arena& arena) {
    Mesh out(&arena);
    LabelStats stats;
    return build_label_mesh(Context(&arena), cut, upper.span(), lower.span(), lo, &out, &stats);
  });
  expect_two_step("apply_label", "cut, \"CASE-27\"", [&](Arena& arena) {
    Mesh out(&arena);
    LabelStats stats;
    return apply_label(Context(&arena), cut, upper.span(), lower.span(), lo, &out, &stats);
  });
}

// Every fixture case's base, in exactly case_base_bound() (the section count from a first run).
TEST(BoundExact, CaseBase) {
  for (const char* name : {"paper_scale.json", "blockout.json", "rounded.json", "spacer.json",
                           "uneven.json", "ct_phantom.json"}) {
    PhantomCase pc(name);
    if (pc.c.upper.empty()) continue;  // a case without picks has no base to build
    BaseReport first;
    {
      TestArena big;
      Mesh out(&big.arena);
      SPLINTCORE_ASSERT_OK(build_case_base(Context(&big.arena), pc.c, &out, &first));
    }
    Input in{name, {}, true};
    expect_fits(in, "build_case_base",
                case_base_bound(pc.c, first.sections, first.points_per_section), [&](Arena& arena) {
                  Mesh out(&arena);
                  BaseReport report;
                  return build_case_base(Context(&arena), pc.c, &out, &report);
                });
  }
}

// The swept volume (blockout.h) has the two-step contract: its grid and surface come from the
// jaws. Plain, with an inset, as a spacer (offset) and closed, on the phantom maxilla.
TEST(BoundTwoStep, SweepVolume) {
  PhantomCase pc("paper_scale.json");
  SweepOptions plain;
  plain.direction = Vec3{0, 0, 1};
  plain.voxel = 0.5;
  SweepOptions inset = plain, offset = plain, closed = plain;
  inset.inset = 0.25;
  offset.offset = 0.5;
  closed.closing_radius = 1.0;
  const SweepOptions* options[] = {&plain, &inset, &offset, &closed};
  const char* names[] = {"phantom maxilla, 0.5 mm", "inset 0.25 mm", "offset 0.5 mm",
                         "closing 1 mm"};
  for (int i = 0; i < 4; ++i) {
    expect_two_step("sweep_volume_mesh", names[i], [&](Arena& arena) {
      Mesh out(&arena);
      return sweep_volume_mesh(Context(&arena), Span<const Mesh>(&pc.jaws[0], 1), *options[i],
                               &out);
    });
  }
}

}  // namespace
}  // namespace splintcore
