// Threshold segmentation, competitive region growing and reconstruction on small exact volumes.
#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "splintcore/segment.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

using test::TestArena;

// A volume of `fill` HU with unit spacing and identity axes; voxels set with put().
struct SmallVolume {
  std::vector<int16_t> hu;
  CtVolume v;
  SmallVolume(uint32_t nx, uint32_t ny, uint32_t nz, int16_t fill = -1000) {
    hu.assign(size_t{nx} * ny * nz, fill);
    v.nx = nx;
    v.ny = ny;
    v.nz = nz;
    v.spacing = Vec3{1, 1, 1};
    v.hu = hu.data();
  }
  void put(uint32_t i, uint32_t j, uint32_t k, int16_t value) {
    hu[(size_t{k} * v.ny + j) * v.nx + i] = value;
  }
  void box(uint32_t i0, uint32_t j0, uint32_t k0, uint32_t i1, uint32_t j1, uint32_t k1,
           int16_t value) {
    for (uint32_t k = k0; k <= k1; ++k) {
      for (uint32_t j = j0; j <= j1; ++j) {
        for (uint32_t i = i0; i <= i1; ++i) put(i, j, k, value);
      }
    }
  }
};

uint8_t label_at(const LabelVolume& l, uint32_t i, uint32_t j, uint32_t k) {
  return l.labels[(size_t{k} * l.ny + j) * l.nx + i];
}

RegionSeed voxel_seed(uint8_t label, uint32_t i, uint32_t j, uint32_t k) {
  RegionSeed s;
  s.label = label;
  s.in_patient_mm = false;
  s.i = i;
  s.j = j;
  s.k = k;
  return s;
}

TEST(CtThreshold, MarksExactlyTheWindow) {
  SmallVolume sv(4, 3, 2, 0);
  const int16_t values[] = {-1000, 299, 300, 301, 999, 1000, 1001, 4000, 4001, 32767, -32768, 12};
  for (size_t n = 0; n < 12; ++n) sv.hu[n] = values[n];
  TestArena ta(1 << 16);
  Context ctx(&ta.arena);
  LabelVolume labels;
  ThresholdStats stats;
  SPLINTCORE_ASSERT_OK(threshold_window(ctx, sv.v, HuWindow{300, 1000}, &labels, &stats));
  ASSERT_EQ(labels.nx, 4u);
  ASSERT_EQ(labels.nz, 2u);
  const uint8_t want[] = {0, 0, 255, 255, 255, 255, 0, 0, 0, 0, 0, 0};
  for (size_t n = 0; n < 12; ++n) EXPECT_EQ(labels.labels[n], want[n]) << n;
  for (size_t n = 12; n < 24; ++n) EXPECT_EQ(labels.labels[n], 0) << n;
  EXPECT_EQ(stats.in_window, 4u);
  EXPECT_LE(ta.arena.used(), threshold_window_bound(sv.v));

  // Windows reaching beyond the int16 range the voxels have.
  SPLINTCORE_ASSERT_OK(threshold_window(ctx, sv.v, HuWindow{4000, 100000}, &labels, &stats));
  EXPECT_EQ(stats.in_window, 3u);  // 4000, 4001, 32767
  EXPECT_EQ(labels.labels[9], 255);
  SPLINTCORE_ASSERT_OK(threshold_window(ctx, sv.v, HuWindow{40000, 100000}, &labels, &stats));
  EXPECT_EQ(stats.in_window, 0u);
  SPLINTCORE_ASSERT_OK(threshold_window(ctx, sv.v, HuWindow{-100000, -32768}, &labels, &stats));
  EXPECT_EQ(stats.in_window, 1u);
  EXPECT_EQ(labels.labels[10], 255);
  // 64-voxel blocks and a remainder: every value of a ramp lands on the right side.
  SmallVolume ramp(67, 3, 1, 0);
  for (size_t n = 0; n < ramp.hu.size(); ++n) ramp.hu[n] = static_cast<int16_t>(n * 7 - 500);
  SPLINTCORE_ASSERT_OK(threshold_window(ctx, ramp.v, HuWindow{-100, 900}, &labels, &stats));
  uint64_t want_in = 0;
  for (size_t n = 0; n < ramp.hu.size(); ++n) {
    const bool in = ramp.hu[n] >= -100 && ramp.hu[n] <= 900;
    want_in += in;
    ASSERT_EQ(labels.labels[n], in ? 255 : 0) << n;
  }
  EXPECT_EQ(stats.in_window, want_in);

  LabelVolume bad;
  Status s = threshold_window(ctx, sv.v, HuWindow{1000, 300}, &bad);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(test::format(s).find("lo 1000 > hi 300"), std::string::npos) << test::format(s);
  CtVolume empty;
  EXPECT_EQ(threshold_window(ctx, empty, HuWindow{}, &bad).code(), StatusCode::kInvalidArgument);
}

TEST(CtRegionGrow, SixAndTwentySixConnectivityOnADiagonalPair) {
  // (0,0,0)-(1,0,0) share a face; (2,1,1) touches (1,0,0) only at a corner.
  SmallVolume sv(3, 2, 2);
  sv.put(0, 0, 0, 1000);
  sv.put(1, 0, 0, 1000);
  sv.put(2, 1, 1, 1000);
  const RegionSeed seed = voxel_seed(1, 0, 0, 0);
  for (int c = 0; c < 2; ++c) {
    TestArena ta(1 << 16);
    Context ctx(&ta.arena);
    LabelVolume labels;
    SPLINTCORE_ASSERT_OK(threshold_window(ctx, sv.v, HuWindow{300, 4000}, &labels));
    RegionGrowOptions options;
    options.connectivity = c == 0 ? Connectivity::k6 : Connectivity::k26;
    RegionStats stats;
    SPLINTCORE_ASSERT_OK(
        grow_regions(ctx, sv.v, Span<const RegionSeed>(&seed, 1), options, &labels, &stats));
    EXPECT_EQ(label_at(labels, 0, 0, 0), 1);
    EXPECT_EQ(label_at(labels, 1, 0, 0), 1);
    EXPECT_EQ(label_at(labels, 2, 1, 1), c == 0 ? kLabelUnclaimed : 1);
    EXPECT_EQ(label_at(labels, 1, 1, 1), kLabelBackground);
    EXPECT_EQ(stats.voxels[1], c == 0 ? 2u : 3u);
    EXPECT_EQ(stats.unclaimed, c == 0 ? 1u : 0u);
    EXPECT_TRUE(stats.touches_border[1]);
    EXPECT_FALSE(stats.meets_other_region[1]);
  }
}

// Two blocks stacked in z that touch (one connected window component): seeds at either end
// split it where their breadth-first fronts meet; a tie goes to the lower label.
TEST(CtRegionGrow, CompetitiveGrowthSplitsTouchingBlocks) {
  for (int c = 0; c < 2; ++c) {
    for (uint32_t top : {8u, 9u}) {
      SmallVolume sv(5, 5, 12);
      sv.box(1, 1, 0, 3, 3, 4, 2000);    // lower block
      sv.box(1, 1, 5, 3, 3, top, 1200);  // upper block, touching
      TestArena ta(1 << 16);
      Context ctx(&ta.arena);
      LabelVolume labels;
      SPLINTCORE_ASSERT_OK(threshold_window(ctx, sv.v, HuWindow{300, 4000}, &labels));
      const RegionSeed seeds[2] = {voxel_seed(2, 2, 2, top), voxel_seed(1, 2, 2, 0)};
      RegionGrowOptions options;
      options.connectivity = c == 0 ? Connectivity::k6 : Connectivity::k26;
      RegionStats stats;
      SPLINTCORE_ASSERT_OK(
          grow_regions(ctx, sv.v, Span<const RegionSeed>(seeds, 2), options, &labels, &stats));
      // Seed 1 at z = 0, seed 2 at z = top: on the axis a voxel at z is z steps from seed 1
      // and top - z from seed 2 (with 26-connectivity too: the block is 3 voxels wide, the
      // z distance dominates). top = 8: z = 4 is a tie (label 1).
      for (uint32_t k = 0; k <= top; ++k) {
        const uint8_t want = (k <= top - k) ? 1 : 2;
        EXPECT_EQ(label_at(labels, 2, 2, k), want) << "z " << k << " top " << top << " c " << c;
        EXPECT_EQ(label_at(labels, 1, 3, k), want) << "z " << k << " top " << top << " c " << c;
      }
      EXPECT_EQ(stats.voxels[1] + stats.voxels[2], 9u * (top + 1));
      EXPECT_EQ(stats.voxels[1], 9u * (top / 2 + 1));
      EXPECT_TRUE(stats.meets_other_region[1]);
      EXPECT_TRUE(stats.meets_other_region[2]);
      EXPECT_EQ(stats.unclaimed, 0u);
      EXPECT_GT(stats.layers, top / 2);
    }
  }
}

TEST(CtRegionGrow, SplitPlaneAssignsBySide) {
  SmallVolume sv(5, 5, 12);
  sv.box(1, 1, 0, 3, 3, 9, 2000);
  sv.v.origin = Vec3{10, 20, 30};
  TestArena ta(1 << 16);
  Context ctx(&ta.arena);
  LabelVolume labels;
  SPLINTCORE_ASSERT_OK(threshold_window(ctx, sv.v, HuWindow{300, 4000}, &labels));
  // Seeds in patient mm (voxel (2, 2, k) is at (12, 22, 30 + k)).
  RegionSeed a;
  a.label = 1;
  a.patient_mm = Vec3{12.2, 21.9, 30.4};
  RegionSeed b;
  b.label = 2;
  b.patient_mm = Vec3{12, 22, 31};
  SplitPlane plane;
  plane.point = Vec3{0, 0, 36.5};
  plane.normal = Vec3{0, 0, 2};
  plane.label_negative = 1;
  plane.label_positive = 2;
  RegionGrowOptions options;
  options.plane = &plane;
  const RegionSeed seeds[2] = {a, b};
  // b (z = 31) is below the plane: on label 1's side.
  Status s = grow_regions(ctx, sv.v, Span<const RegionSeed>(seeds, 2), options, &labels);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(test::format(s).find("split plane's side of label 1"), std::string::npos)
      << test::format(s);
  EXPECT_EQ(s.index(), 1u);

  SPLINTCORE_ASSERT_OK(threshold_window(ctx, sv.v, HuWindow{300, 4000}, &labels));
  RegionSeed seeds2[2] = {a, b};
  seeds2[1].patient_mm = Vec3{12, 22, 39};
  RegionStats stats;
  SPLINTCORE_ASSERT_OK(
      grow_regions(ctx, sv.v, Span<const RegionSeed>(seeds2, 2), options, &labels, &stats));
  for (uint32_t k = 0; k <= 9; ++k) {
    EXPECT_EQ(label_at(labels, 3, 1, k), k <= 6 ? 1 : 2) << k;
  }
  EXPECT_EQ(stats.voxels[1], 9u * 7);
  EXPECT_EQ(stats.voxels[2], 9u * 3);
}

TEST(CtRegionGrow, BadSeedsAreNamed) {
  SmallVolume sv(6, 6, 6);
  sv.box(1, 1, 1, 4, 4, 2, 1500);
  sv.put(5, 5, 5, 1500);  // an isolated speck
  auto run = [&](std::vector<RegionSeed> seeds) {
    TestArena ta(1 << 16);
    Context ctx(&ta.arena);
    LabelVolume labels;
    Status t = threshold_window(ctx, sv.v, HuWindow{300, 4000}, &labels);
    EXPECT_TRUE(t.is_ok());
    return grow_regions(ctx, sv.v, Span<const RegionSeed>(seeds.data(), seeds.size()),
                        RegionGrowOptions{}, &labels);
  };
  Status s = run({voxel_seed(1, 2, 2, 2), voxel_seed(2, 6, 0, 0)});
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(s.index(), 1u);
  EXPECT_NE(test::format(s).find("seed voxel (6, 0, 0) is outside the volume"), std::string::npos)
      << test::format(s);

  RegionSeed far;
  far.label = 2;
  far.patient_mm = Vec3{2, 2, 5.6};
  s = run({voxel_seed(1, 2, 2, 2), far});
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(test::format(s).find("outside the volume"), std::string::npos) << test::format(s);

  s = run({voxel_seed(1, 0, 0, 0)});
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(test::format(s).find("voxel (0, 0, 0) is not in the HU window: its value is -1000"),
            std::string::npos)
      << test::format(s);

  s = run({voxel_seed(1, 2, 2, 2), voxel_seed(2, 2, 2, 2)});
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(test::format(s).find("same voxel as a seed of label 1"), std::string::npos)
      << test::format(s);

  s = run({voxel_seed(1, 2, 2, 2), voxel_seed(2, 5, 5, 5)});
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(s.index(), 1u);
  EXPECT_NE(test::format(s).find("region 2 grows no further than its seeds"), std::string::npos)
      << test::format(s);

  s = run({voxel_seed(16, 2, 2, 2)});
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  s = run({});
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  // Two seeds of one label in one voxel are fine.
  SPLINTCORE_EXPECT_OK(run({voxel_seed(1, 2, 2, 2), voxel_seed(1, 2, 2, 2)}));
}

// Arguments that do not fit together, each refused with its text before anything is read or
// written (the labels as they were, nothing taken from the arena).
TEST(CtSegment, ArgumentsThatDoNotFitAreNamed) {
  SmallVolume sv(6, 6, 6);
  sv.box(1, 1, 1, 4, 4, 2, 1500);
  TestArena ta(1 << 16);
  Context ctx(&ta.arena);
  LabelVolume labels;
  SPLINTCORE_ASSERT_OK(threshold_window(ctx, sv.v, HuWindow{300, 4000}, &labels));
  const std::vector<uint8_t> before(labels.labels, labels.labels + labels.voxel_count());
  const size_t used = ta.arena.used();
  const RegionSeed seed = voxel_seed(1, 2, 2, 2);
  auto grow = [&](const CtVolume& volume, Span<const RegionSeed> seeds, const SplitPlane* plane,
                  LabelVolume* l) {
    RegionGrowOptions options;
    options.plane = plane;
    return grow_regions(ctx, volume, seeds, options, l);
  };
  auto expect = [&](const Status& s, StatusCode code, const char* text) {
    EXPECT_EQ(s.code(), code) << text;
    EXPECT_STREQ(s.message(), text);
    EXPECT_EQ(ta.arena.used(), used) << text;
    EXPECT_TRUE(std::equal(before.begin(), before.end(), labels.labels)) << text;
  };
  const Span<const RegionSeed> one(&seed, 1);
  const char* mismatch =
      "region growing: the label volume does not match the CT volume (6 x 6 x 6)";
  expect(grow(sv.v, one, nullptr, nullptr), StatusCode::kInvalidArgument, mismatch);
  LabelVolume narrow = labels;
  narrow.nx = 5;
  expect(grow(sv.v, one, nullptr, &narrow), StatusCode::kInvalidArgument, mismatch);
  const std::vector<RegionSeed> many(kMaxSeeds + 1, seed);
  expect(grow(sv.v, Span<const RegionSeed>(many.data(), many.size()), nullptr, &labels),
         StatusCode::kInvalidArgument, "region growing: 257 seeds, at most 256");
  // 2^33 voxels: refused from the sizes alone (nothing of them is read).
  CtVolume huge = sv.v;
  huge.nx = huge.ny = 2048;
  huge.nz = 2048;
  LabelVolume huge_labels = labels;
  huge_labels.nx = huge_labels.ny = huge_labels.nz = 2048;
  expect(grow(huge, one, nullptr, &huge_labels), StatusCode::kLimitExceeded,
         "region growing: 8589934592 voxels; at most 4294967295 (32-bit voxel indices)");
  const char* bad_plane =
      "split plane: the point and normal must be finite and the normal not zero";
  const char* bad_labels = "split plane: its two labels must differ and lie in 1..15";
  const std::pair<void (*)(SplitPlane*), const char*> planes[] = {
      {[](SplitPlane* p) {
         p->normal = Vec3{0, 0, 0};
       },
       bad_plane},
      {[](SplitPlane* p) { p->point.y = std::nan(""); }, bad_plane},
      {[](SplitPlane* p) { p->normal.x = HUGE_VAL; }, bad_plane},
      {[](SplitPlane* p) { p->label_positive = p->label_negative; }, bad_labels},
      {[](SplitPlane* p) { p->label_negative = 0; }, bad_labels},
      {[](SplitPlane* p) { p->label_positive = kMaxRegionLabel + 1; }, bad_labels}};
  for (const auto& [edit, text] : planes) {
    SplitPlane plane;
    edit(&plane);
    expect(grow(sv.v, one, &plane, &labels), StatusCode::kInvalidArgument, text);
  }

  // reconstruct_region's own.
  auto reconstruct = [&](const CtVolume& volume, const LabelVolume& l, uint8_t label, int32_t hu_lo,
                         Mesh* out) {
    ReconstructOptions ro;
    ro.label = label;
    ro.hu_lo = hu_lo;
    return reconstruct_region(ctx, volume, l, ro, out);
  };
  Mesh mesh(&ta.arena);
  for (const uint8_t label : {uint8_t{0}, uint8_t{kMaxRegionLabel + 1}, kLabelUnclaimed}) {
    const std::string text =
        "reconstruct: label " + std::to_string(label) + " is not a region label (1..15)";
    expect(reconstruct(sv.v, labels, label, 300, &mesh), StatusCode::kInvalidArgument,
           text.c_str());
  }
  expect(reconstruct(sv.v, narrow, 1, 300, &mesh), StatusCode::kInvalidArgument,
         "reconstruct: the label volume does not match the CT volume (6 x 6 x 6)");
  CtVolume no_hu = sv.v;
  no_hu.hu = nullptr;
  expect(reconstruct(no_hu, labels, 1, 300, &mesh), StatusCode::kInvalidArgument,
         "reconstruct: the label volume does not match the CT volume (6 x 6 x 6)");
  expect(reconstruct(sv.v, labels, 1, 1 << 22, &mesh), StatusCode::kInvalidArgument,
         "reconstruct: threshold 4194304 HU is out of range");
  expect(reconstruct(sv.v, labels, 1, -(1 << 22), &mesh), StatusCode::kInvalidArgument,
         "reconstruct: threshold -4194304 HU is out of range");
  expect(reconstruct(sv.v, labels, 1, 300, nullptr), StatusCode::kInvalidArgument,
         "reconstruct: the output mesh must be empty");
  TestArena other(1 << 10);
  Mesh full(&other.arena);
  ASSERT_TRUE(full.triangles.push_back(Triangle{{0, 1, 2}}));
  expect(reconstruct(sv.v, labels, 1, 300, &full), StatusCode::kInvalidArgument,
         "reconstruct: the output mesh must be empty");
  EXPECT_EQ(full.triangles.size(), 1u);
}

// A block of bone in soft tissue: closed, oriented, outward; its volume close to the block's.
TEST(CtReconstruct, BlockIsAClosedOutwardSolid) {
  SmallVolume sv(8, 7, 6, 40);
  sv.box(2, 2, 1, 5, 4, 4, 2000);
  sv.v.spacing = Vec3{0.5, 0.75, 1.0};
  TestArena ta(1 << 20);
  Context ctx(&ta.arena);
  LabelVolume labels;
  SPLINTCORE_ASSERT_OK(threshold_window(ctx, sv.v, HuWindow{300, 4000}, &labels));
  const RegionSeed seed = voxel_seed(3, 3, 3, 3);
  SPLINTCORE_ASSERT_OK(
      grow_regions(ctx, sv.v, Span<const RegionSeed>(&seed, 1), RegionGrowOptions{}, &labels));
  Mesh mesh(&ta.arena);
  ReconstructOptions ro;
  ro.label = 3;
  ReconstructStats rs;
  const size_t before = ta.arena.used();
  ta.arena.reset_high_water();
  SPLINTCORE_ASSERT_OK(reconstruct_region(ctx, sv.v, labels, ro, &mesh, &rs));
  const uint32_t box[3] = {rs.box_hi[0] - rs.box_lo[0] + 1, rs.box_hi[1] - rs.box_lo[1] + 1,
                           rs.box_hi[2] - rs.box_lo[2] + 1};
  const uint64_t bound = reconstruct_region_bound(box, rs.marching.layers_per_tile,
                                                  mesh.vertices.size(), mesh.triangles.size());
  EXPECT_GT(bound, 0u);
  EXPECT_LE(ta.arena.high_water() - before, bound);
  EXPECT_GE(ta.arena.high_water() - before, bound / 2);  // a bound, not a gross overestimate
  double volume = 0;
  SPLINTCORE_ASSERT_OK(check_closed_oriented(ctx, mesh, &volume));
  // The surface crosses each edge at HU 299.5 between 2000 and 40: t = 0.868 from the inside
  // sample, so the solid is the block grown by 0.368 voxel per side (not more than a voxel).
  const double block = (4 * 0.5) * (3 * 0.75) * (4 * 1.0);
  EXPECT_GT(volume, block);
  EXPECT_LT(volume, (5 * 0.5) * (4 * 0.75) * (5 * 1.0));
  EXPECT_EQ(rs.region_voxels, 48u);
  EXPECT_EQ(rs.box_lo[0], 1u);
  EXPECT_EQ(rs.box_hi[0], 6u);
  EXPECT_EQ(rs.flat_after_rounding, 0u);
  for (const Vec3& p : mesh.vertices) EXPECT_TRUE(is_float32_exact(p));

  Mesh other(&ta.arena);
  ro.label = 4;
  Status s = reconstruct_region(ctx, sv.v, labels, ro, &other);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(test::format(s).find("region 4 is empty"), std::string::npos) << test::format(s);
}

// Two touching blocks split by competition: the two meshes meet on the interface plane and do
// not overlap (their volumes add up to the merged block's).
TEST(CtReconstruct, TouchingRegionsShareTheirInterface) {
  SmallVolume sv(6, 6, 12, 40);
  sv.box(1, 1, 1, 4, 4, 10, 1800);
  TestArena ta(8 << 20);
  Context ctx(&ta.arena);
  LabelVolume labels;
  SPLINTCORE_ASSERT_OK(threshold_window(ctx, sv.v, HuWindow{300, 4000}, &labels));
  const RegionSeed seeds[2] = {voxel_seed(1, 2, 2, 1), voxel_seed(2, 2, 2, 10)};
  SPLINTCORE_ASSERT_OK(
      grow_regions(ctx, sv.v, Span<const RegionSeed>(seeds, 2), RegionGrowOptions{}, &labels));
  double volumes[3] = {0, 0, 0};
  for (uint8_t l = 1; l <= 2; ++l) {
    Mesh mesh(&ta.arena);
    ReconstructOptions ro;
    ro.label = l;
    ro.round_to_float32 = false;
    SPLINTCORE_ASSERT_OK(reconstruct_region(ctx, sv.v, labels, ro, &mesh));
    SPLINTCORE_ASSERT_OK(check_closed_oriented(ctx, mesh, &volumes[l]));
    // No vertex of either mesh is beyond the interface plane z = 5.5 on the other's side,
    // except on the rim where the interface meets the outer surface (edges from a region
    // voxel to soft tissue cross the plane there: at most 0.4 voxel, see segment.h).
    for (const Vec3& p : mesh.vertices) {
      const bool rim = p.x < 1 || p.x > 4 || p.y < 1 || p.y > 4;
      if (l == 1) {
        EXPECT_LE(p.z, rim ? 5.9 : 5.5 + 1e-12) << p.x << " " << p.y;
      } else {
        EXPECT_GE(p.z, rim ? 5.1 : 5.5 - 1e-12) << p.x << " " << p.y;
      }
    }
  }
  {
    // The merged block as one region.
    LabelVolume one;
    SPLINTCORE_ASSERT_OK(threshold_window(ctx, sv.v, HuWindow{300, 4000}, &one));
    SPLINTCORE_ASSERT_OK(
        grow_regions(ctx, sv.v, Span<const RegionSeed>(seeds, 1), RegionGrowOptions{}, &one));
    Mesh mesh(&ta.arena);
    ReconstructOptions ro;
    ro.round_to_float32 = false;
    SPLINTCORE_ASSERT_OK(reconstruct_region(ctx, sv.v, one, ro, &mesh));
    SPLINTCORE_ASSERT_OK(check_closed_oriented(ctx, mesh, &volumes[0]));
  }
  EXPECT_NEAR(volumes[1] + volumes[2], volumes[0], 0.02 * volumes[0]);
  RecordProperty("overlap_fraction", std::to_string((volumes[1] + volumes[2]) / volumes[0] - 1));
  std::printf("two regions / merged volume: %.5f\n", (volumes[1] + volumes[2]) / volumes[0]);
  EXPECT_NEAR(volumes[1], volumes[2], 1e-9 * volumes[0]);
}

// Every arena cap from 0 up: either the whole pipeline succeeds or the first step that runs out
// returns kArenaExhausted with a message naming the bytes; results never depend on the cap.
TEST(CtSegment, ArenaExhaustionSweep) {
  SmallVolume sv(10, 9, 8, 40);
  sv.box(2, 2, 1, 7, 6, 3, 2000);
  sv.box(2, 2, 4, 7, 6, 6, 1200);
  const RegionSeed seeds[2] = {voxel_seed(1, 4, 4, 1), voxel_seed(2, 4, 4, 6)};
  std::vector<uint8_t> reference_labels;
  std::vector<Vec3> reference_vertices;
  size_t first_ok = 0;
  for (size_t cap = 0; cap <= 200000; cap += cap < 4096 ? 16 : 256) {
    TestArena ta(cap);
    Context ctx(&ta.arena);
    LabelVolume labels;
    size_t used_before = ta.arena.used();
    Status s = threshold_window(ctx, sv.v, HuWindow{300, 4000}, &labels);
    if (s.is_ok()) {
      used_before = ta.arena.used();
      s = grow_regions(ctx, sv.v, Span<const RegionSeed>(seeds, 2), RegionGrowOptions{}, &labels);
    }
    Mesh mesh(&ta.arena);
    if (s.is_ok()) {
      EXPECT_EQ(ta.arena.used(), used_before);  // growth returns its queue
      ReconstructOptions ro;
      ro.label = 2;
      s = reconstruct_region(ctx, sv.v, labels, ro, &mesh);
    }
    if (!s.is_ok()) {
      ASSERT_EQ(s.code(), StatusCode::kArenaExhausted) << cap << ": " << test::format(s);
      EXPECT_NE(test::format(s).find("need"), std::string::npos) << test::format(s);
      EXPECT_TRUE(mesh.vertices.empty());
      EXPECT_EQ(ta.arena.used(), used_before) << cap << ": the failing step moved the top";
      continue;
    }
    std::vector<uint8_t> l(labels.labels, labels.labels + labels.voxel_count());
    std::vector<Vec3> v(mesh.vertices.begin(), mesh.vertices.end());
    if (first_ok == 0) {
      first_ok = cap;
      reference_labels = l;
      reference_vertices = v;
      EXPECT_GT(v.size(), 0u);
    } else {
      ASSERT_EQ(l, reference_labels) << cap;
      ASSERT_EQ(v.size(), reference_vertices.size()) << cap;
      for (size_t n = 0; n < v.size(); ++n) ASSERT_TRUE(v[n] == reference_vertices[n]) << cap;
    }
  }
  EXPECT_GT(first_ok, 0u);
}

// Each stage checks the progress callback and stops with kCancelled when it says so; a
// cancelled reconstruction leaves the arena and the mesh as they were.
TEST(CtSegment, CancelStopsEachStage) {
  SmallVolume sv(10, 9, 8, 40);
  sv.box(2, 2, 1, 7, 6, 6, 2000);
  const RegionSeed seed = voxel_seed(1, 4, 4, 3);
  struct Cancel {
    const char* stage;
    static bool report(void* user, const char* stage, uint64_t, uint64_t) {
      return std::strcmp(static_cast<Cancel*>(user)->stage, stage) != 0;
    }
  };
  const char* stages[] = {"threshold", "region growing", "reconstruct: region box",
                          "marching cubes", "reconstruct: patient coordinates"};
  for (const char* stage : stages) {
    Cancel cancel{stage};
    Progress progress;
    progress.report = &Cancel::report;
    progress.user = &cancel;
    TestArena ta(1 << 20);
    Context ctx(&ta.arena, nullptr, &progress);
    LabelVolume labels;
    Status s = threshold_window(ctx, sv.v, HuWindow{300, 4000}, &labels);
    if (!s.is_ok()) {
      EXPECT_EQ(ta.arena.used(), 0u) << stage;
    }
    if (s.is_ok()) {
      s = grow_regions(ctx, sv.v, Span<const RegionSeed>(&seed, 1), RegionGrowOptions{}, &labels);
    }
    Mesh mesh(&ta.arena);
    size_t used = ta.arena.used();
    if (s.is_ok()) s = reconstruct_region(ctx, sv.v, labels, ReconstructOptions{}, &mesh);
    EXPECT_EQ(s.code(), StatusCode::kCancelled) << stage;
    EXPECT_TRUE(mesh.vertices.empty()) << stage;
    if (std::strncmp(stage, "re", 2) == 0 || std::strcmp(stage, "marching cubes") == 0) {
      EXPECT_EQ(ta.arena.used(), used) << stage;
    }
  }
}

}  // namespace
}  // namespace splintcore
