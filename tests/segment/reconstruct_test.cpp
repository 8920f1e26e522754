// Phantom CT -> threshold -> competitive region growing -> reconstruction: each jaw is a closed,
// manifold, outward solid on its analytic surface, the jaws are separated where their crowns
// touch, and the bytes do not depend on the slab size.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <string>
#include <vector>

#include "common/ct_phantom.h"
#include "splintcore/segment.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

using cli::CtPhantom;
using cli::CtPhantomOptions;
using test::TestArena;

struct Jaws {
  RegionStats grow;
  std::vector<Vec3> vertices[2];
  std::vector<Triangle> triangles[2];
  double volume[2] = {0, 0};
  uint64_t triangle_count[2] = {0, 0};
};

// Runs the pipeline; meshes copied out of the arena.
void run_pipeline(const CtPhantom& phantom, const CtVolume& volume, uint32_t layers,
                  Connectivity connectivity, Jaws* out) {
  TestArena ta(size_t{512} << 20);
  Context ctx(&ta.arena);
  LabelVolume labels;
  ThresholdStats ts;
  SPLINTCORE_ASSERT_OK(threshold_window(ctx, volume, HuWindow{300, 4000}, &labels, &ts));
  RegionSeed seeds[2];
  seeds[0].label = 1;
  seeds[0].patient_mm = phantom.seed_maxilla();
  seeds[1].label = 2;
  seeds[1].patient_mm = phantom.seed_mandible();
  RegionGrowOptions go;
  go.connectivity = connectivity;
  SPLINTCORE_ASSERT_OK(
      grow_regions(ctx, volume, Span<const RegionSeed>(seeds, 2), go, &labels, &out->grow));
  for (int j = 0; j < 2; ++j) {
    ArenaScope scope(ta.arena);
    Mesh mesh(&ta.arena);
    ReconstructOptions ro;
    ro.label = static_cast<uint8_t>(j + 1);
    ro.layers_per_tile = layers;
    ReconstructStats rs;
    SPLINTCORE_ASSERT_OK(reconstruct_region(ctx, volume, labels, ro, &mesh, &rs));
    EXPECT_EQ(rs.flat_after_rounding, 0u);
    SPLINTCORE_ASSERT_OK(check_closed_oriented(ctx, mesh, &out->volume[j]));
    MeshReport report;
    SPLINTCORE_ASSERT_OK(check_mesh(ctx, mesh, &report));
    EXPECT_TRUE(report.is_valid_solid()) << test::format(require_valid_solid(report));
    out->vertices[j].assign(mesh.vertices.begin(), mesh.vertices.end());
    out->triangles[j].assign(mesh.triangles.begin(), mesh.triangles.end());
    out->triangle_count[j] = mesh.triangles.size();
  }
}

struct Accuracy {
  double mean_own = 0, max_own = 0;  // |SDF of its own jaw| at the vertices, mm
  double min_other = HUGE_VAL;       // smallest SDF of the other jaw at the vertices, mm
  uint64_t closer_to_other = 0;      // vertices nearer the other jaw's surface than their own
};

Accuracy measure(const CtPhantom& phantom, const std::vector<Vec3>& vertices, int jaw) {
  Accuracy a;
  double sum = 0;
  for (const Vec3& p : vertices) {
    const double own = jaw == 0 ? phantom.sdf_maxilla(p) : phantom.sdf_mandible(p);
    const double other = jaw == 0 ? phantom.sdf_mandible(p) : phantom.sdf_maxilla(p);
    sum += std::fabs(own);
    if (std::fabs(own) > a.max_own) a.max_own = std::fabs(own);
    if (other < a.min_other) a.min_other = other;
    if (std::fabs(other) < std::fabs(own)) ++a.closer_to_other;
  }
  a.mean_own = sum / static_cast<double>(vertices.size());
  return a;
}

void check_phantom(const CtPhantomOptions& po, const char* name) {
  CtPhantom phantom;
  SPLINTCORE_ASSERT_OK(phantom.init(po));
  std::vector<int16_t> hu;
  CtVolume volume;
  phantom.generate(&hu, &volume);
  Jaws jaws;
  run_pipeline(phantom, volume, 0, Connectivity::k6, &jaws);
  if (::testing::Test::HasFatalFailure()) return;
  // The crowns touch: the regions met, and neither reached the border.
  EXPECT_TRUE(jaws.grow.meets_other_region[1]);
  EXPECT_TRUE(jaws.grow.meets_other_region[2]);
  EXPECT_FALSE(jaws.grow.touches_border[1]);
  EXPECT_FALSE(jaws.grow.touches_border[2]);
  // Figures in units of the smallest spacing (the strictest reading of "a voxel").
  double voxel = po.spacing.x, largest = po.spacing.x;
  if (po.spacing.y < voxel) voxel = po.spacing.y;
  if (po.spacing.z < voxel) voxel = po.spacing.z;
  if (po.spacing.y > largest) largest = po.spacing.y;
  if (po.spacing.z > largest) largest = po.spacing.z;
  const char* jaw_names[2] = {"maxilla", "mandible"};
  for (int j = 0; j < 2; ++j) {
    const Accuracy a = measure(phantom, jaws.vertices[j], j);
    std::printf(
        "%s %s: %llu triangles, volume %.1f mm^3, mean |sdf| %.4f mm = %.3f voxel, "
        "max %.3f mm = %.2f voxel, other jaw's sdf >= %.3f mm, %llu of %zu vertices "
        "nearer the other jaw\n",
        name, jaw_names[j], static_cast<unsigned long long>(jaws.triangle_count[j]), jaws.volume[j],
        a.mean_own, a.mean_own / voxel, a.max_own, a.max_own / voxel, a.min_other,
        static_cast<unsigned long long>(a.closer_to_other), jaws.vertices[j].size());
    ::testing::Test::RecordProperty(std::string(name) + "_" + jaw_names[j] + "_mean_sdf_voxels",
                                    std::to_string(a.mean_own / voxel));
    EXPECT_LT(a.mean_own, 0.25 * voxel) << name << " " << jaw_names[j];
    EXPECT_LT(a.max_own, 2.0 * voxel) << name << " " << jaw_names[j];
    // Separation: no vertex of one jaw lies inside the other by more than half the largest
    // spacing (the split surface runs through the molar crowns' 0.3 mm overlap), and almost
    // all (98%) are nearer their own jaw's surface than the other's (the exceptions: around
    // the contacts, where both distances are small).
    EXPECT_GT(a.min_other, -0.5 * largest) << name << " " << jaw_names[j];
    EXPECT_LT(a.closer_to_other * 50, jaws.vertices[j].size()) << name << " " << jaw_names[j];
  }
}

TEST(CtReconstruct, PhantomJawsOnTheirAnalyticSurfaces) {
  CtPhantomOptions po;
  po.nx = 116;
  po.ny = 104;
  po.nz = 72;
  po.spacing = Vec3{0.6, 0.6, 0.6};
  check_phantom(po, "isotropic");
}

TEST(CtReconstruct, AnisotropicRotatedAndMirroredPhantom) {
  CtPhantomOptions po;
  po.nx = 140;
  po.ny = 125;
  po.nz = 52;
  po.spacing = Vec3{0.5, 0.5, 0.8};
  // A rotation about z by atan(4/3), and z flipped (a left-handed frame: slices stored from
  // the top down).
  po.axis_x = Vec3{0.6, 0.8, 0};
  po.axis_y = Vec3{-0.8, 0.6, 0};
  po.axis_z = Vec3{0, 0, -1};
  po.seed = 7;
  check_phantom(po, "anisotropic-rotated-mirrored");
}

TEST(CtReconstruct, TwentySixConnectivityAndNoStreakStillSeparate) {
  CtPhantomOptions po;
  po.nx = 116;
  po.ny = 104;
  po.nz = 72;
  po.spacing = Vec3{0.6, 0.6, 0.6};
  po.streak = false;
  po.noise_hu = 40;
  CtPhantom phantom;
  SPLINTCORE_ASSERT_OK(phantom.init(po));
  std::vector<int16_t> hu;
  CtVolume volume;
  phantom.generate(&hu, &volume);
  Jaws jaws;
  run_pipeline(phantom, volume, 0, Connectivity::k26, &jaws);
  if (::testing::Test::HasFatalFailure()) return;
  for (int j = 0; j < 2; ++j) {
    const Accuracy a = measure(phantom, jaws.vertices[j], j);
    EXPECT_LT(a.mean_own, 0.25 * 0.6);
    EXPECT_GT(a.min_other, -0.45);  // three quarters of a voxel: twice the noise of the others
  }
}

TEST(CtReconstruct, BytesIndependentOfSlabSizeAndRun) {
  CtPhantomOptions po;
  po.nx = 116;
  po.ny = 104;
  po.nz = 72;
  po.spacing = Vec3{0.6, 0.6, 0.6};
  CtPhantom phantom;
  SPLINTCORE_ASSERT_OK(phantom.init(po));
  std::vector<int16_t> hu, hu2;
  CtVolume volume, volume2;
  phantom.generate(&hu, &volume);
  phantom.generate(&hu2, &volume2);
  ASSERT_EQ(hu, hu2);
  EXPECT_EQ(hu[(size_t{40} * 104 + 50) * 116 + 60], phantom.voxel(60, 50, 40));
  Jaws reference;
  run_pipeline(phantom, volume, 0, Connectivity::k6, &reference);
  for (uint32_t layers : {1u, 3u, 16u, 0u}) {
    Jaws again;
    run_pipeline(phantom, volume2, layers, Connectivity::k6, &again);
    for (int j = 0; j < 2; ++j) {
      ASSERT_EQ(again.vertices[j].size(), reference.vertices[j].size()) << layers;
      ASSERT_EQ(again.triangles[j].size(), reference.triangles[j].size()) << layers;
      EXPECT_EQ(std::memcmp(again.vertices[j].data(), reference.vertices[j].data(),
                            again.vertices[j].size() * sizeof(Vec3)),
                0)
          << layers;
      EXPECT_EQ(std::memcmp(again.triangles[j].data(), reference.triangles[j].data(),
                            again.triangles[j].size() * sizeof(Triangle)),
                0)
          << layers;
    }
  }
}

TEST(CtPhantom, RejectsAVolumeTooSmallForTheJaws) {
  CtPhantomOptions po;
  po.nx = 40;
  po.ny = 40;
  po.nz = 40;
  po.spacing = Vec3{0.5, 0.5, 0.5};
  CtPhantom phantom;
  Status s = phantom.init(po);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(test::format(s).find("the jaws need at least"), std::string::npos) << test::format(s);
  po = CtPhantomOptions{};
  po.axis_x = Vec3{1, 0.1, 0};
  EXPECT_EQ(phantom.init(po).code(), StatusCode::kInvalidArgument);
}

// The analytic surfaces: the seeds are deep in bone, the occlusal plane between the jaws, and
// the molars' crowns overlap (both SDFs negative at the contact).
TEST(CtPhantom, SeedsAndContacts) {
  CtPhantom phantom;
  SPLINTCORE_ASSERT_OK(phantom.init(CtPhantomOptions{}));
  EXPECT_LT(phantom.sdf_maxilla(phantom.seed_maxilla()), -3.0);
  EXPECT_LT(phantom.sdf_mandible(phantom.seed_mandible()), -3.0);
  EXPECT_GT(phantom.sdf_maxilla(phantom.seed_mandible()), 10.0);
  // A point on the occlusal plane inside both crowns exists (the molars overlap by 0.3 mm).
  bool both = false;
  for (int i = -60; i <= 60 && !both; ++i) {
    for (int j = -60; j <= 60 && !both; ++j) {
      const Vec3 p{0.5 * i, 0.5 * j, 0.0};
      both = phantom.sdf_maxilla(p) < -0.1 && phantom.sdf_mandible(p) < -0.1;
    }
  }
  EXPECT_TRUE(both);
}

// Golden bytes (fixtures/golden.sha256; the same from g++ and clang++, -O0 and -O2): the voxels
// of a small phantom, and the binary STL of each jaw reconstructed from it.
TEST(CtGolden, PhantomAndReconstructedJawsMatchTheCommittedHashes) {
  CtPhantomOptions po;
  po.nx = 100;
  po.ny = 92;
  po.nz = 64;
  po.spacing = Vec3{0.7, 0.7, 0.75};
  CtPhantom phantom;
  SPLINTCORE_ASSERT_OK(phantom.init(po));
  std::vector<int16_t> hu;
  CtVolume volume;
  phantom.generate(&hu, &volume);
  std::map<std::string, std::string> hashes;
  hashes["ct-phantom:100x92x64"] = test::sha256_hex(hu.data(), hu.size() * sizeof(int16_t));
  TestArena ta(size_t{256} << 20);
  Context ctx(&ta.arena);
  LabelVolume labels;
  SPLINTCORE_ASSERT_OK(threshold_window(ctx, volume, HuWindow{300, 4000}, &labels));
  RegionSeed seeds[2];
  seeds[0].label = 1;
  seeds[0].patient_mm = phantom.seed_maxilla();
  seeds[1].label = 2;
  seeds[1].patient_mm = phantom.seed_mandible();
  SPLINTCORE_ASSERT_OK(
      grow_regions(ctx, volume, Span<const RegionSeed>(seeds, 2), RegionGrowOptions{}, &labels));
  const char* names[2] = {"reconstruct:ct-phantom-100x92x64-maxilla",
                          "reconstruct:ct-phantom-100x92x64-mandible"};
  for (int j = 0; j < 2; ++j) {
    ArenaScope scope(ta.arena);
    Mesh mesh(&ta.arena);
    ReconstructOptions ro;
    ro.label = static_cast<uint8_t>(j + 1);
    SPLINTCORE_ASSERT_OK(reconstruct_region(ctx, volume, labels, ro, &mesh));
    std::vector<uint8_t> bytes;
    SPLINTCORE_ASSERT_OK(test::mesh_to_bytes(ta.arena, mesh, StlFormat::kBinary, &bytes));
    hashes[names[j]] = test::sha256_hex(bytes.data(), bytes.size());
  }
  std::map<std::string, std::string> golden = test::golden_hashes();
  for (const auto& kv : hashes) {
    // To pin new bytes: copy these lines into fixtures/golden.sha256 (and say why).
    if (golden[kv.first] != kv.second) std::printf("%s  %s\n", kv.second.c_str(), kv.first.c_str());
    EXPECT_EQ(golden[kv.first], kv.second) << kv.first;
  }
}

}  // namespace
}  // namespace splintcore
