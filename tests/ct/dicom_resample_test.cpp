// Geometry as scanners write it (issue 31): DICOM series with gantry tilt, uneven spacing and a
// missing slice, written by the CT writer from the skull phantom, read back resampled onto a
// regular grid. The oracles: the same phantom sampled without tilt / evenly (voxel by voxel),
// and the phantom's analytic jaw surfaces (the reconstructed vertices' signed distances).
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "common/ct_files.h"
#include "common/ct_phantom.h"
#include "common/ct_write.h"
#include "splintcore/ct.h"
#include "splintcore/geometry.h"
#include "splintcore/segment.h"
#include "support/dicom_read.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

namespace fs = std::filesystem;
using cli::CtPhantom;
using cli::CtPhantomOptions;
using test::TestArena;

using test::TempDir;

// A volume's slices written as a DICOM series at `positions`, read back (voxels copied out).
using ReadBack = test::DicomRead;

ReadBack read_folder(const std::string& folder, size_t arena_bytes,
                     const CtReadOptions& options = CtReadOptions{}) {
  TestArena t(arena_bytes);
  Context ctx(&t.arena);
  ReadBack r;
  r.status = cli::read_ct_path(ctx, folder, options, &r.volume, &r.info);
  if (r.status.is_ok()) r.hu.assign(r.volume.hu, r.volume.hu + r.volume.voxel_count());
  r.volume.hu = nullptr;
  r.high_water = t.arena.high_water();
  return r;
}

// The CT phantom of `po` without streaks or noise (the reference the resampled series match).
void clean_phantom(CtPhantomOptions po, CtPhantom* phantom, std::vector<int16_t>* hu, CtVolume* v) {
  po.streak = false;
  po.noise_hu = 0;
  SPLINTCORE_ASSERT_OK(phantom->init(po));
  phantom->generate(hu, v);
}

void write_series(const CtVolume& v, const std::vector<Vec3>& positions, const TempDir& dir) {
  cli::CtWriteOptions wo;
  wo.slice_positions = positions;
  SPLINTCORE_ASSERT_OK(cli::write_dicom_series(v, dir.path.string(), wo));
}

// A CtVolume over `hu` with the given geometry.
CtVolume volume_of(std::vector<int16_t>* hu, uint32_t nx, uint32_t ny, uint32_t nz,
                   const CtVolume& frame, const Vec3& spacing, const Vec3& origin) {
  CtVolume v = frame;
  v.nx = nx;
  v.ny = ny;
  v.nz = nz;
  v.spacing = spacing;
  v.origin = origin;
  v.hu = hu->data();
  return v;
}

// Both jaws from a volume: closed, their volumes, and their vertices' distances to the
// phantom's analytic surfaces.
struct Jaws {
  double volume[2] = {0, 0};
  double mean_sdf[2] = {0, 0};
  double max_sdf[2] = {0, 0};
};

Jaws reconstruct_jaws(const CtPhantom& phantom, const CtVolume& volume) {
  Jaws out;
  TestArena ta(size_t{256} << 20);
  Context ctx(&ta.arena);
  LabelVolume labels;
  ThresholdStats ts;
  EXPECT_TRUE(threshold_window(ctx, volume, HuWindow{300, 4000}, &labels, &ts).is_ok());
  RegionSeed seeds[2];
  seeds[0].label = 1;
  seeds[0].patient_mm = phantom.seed_maxilla();
  seeds[1].label = 2;
  seeds[1].patient_mm = phantom.seed_mandible();
  RegionStats grow;
  Status s = grow_regions(ctx, volume, Span<const RegionSeed>(seeds, 2), RegionGrowOptions{},
                          &labels, &grow);
  EXPECT_TRUE(s.is_ok()) << test::format(s);
  if (!s.is_ok()) return out;
  for (int j = 0; j < 2; ++j) {
    ArenaScope scope(ta.arena);
    Mesh mesh(&ta.arena);
    ReconstructOptions ro;
    ro.label = static_cast<uint8_t>(j + 1);
    ReconstructStats rs;
    s = reconstruct_region(ctx, volume, labels, ro, &mesh, &rs);
    if (s.is_ok()) s = check_closed_oriented(ctx, mesh, &out.volume[j]);
    EXPECT_TRUE(s.is_ok()) << test::format(s);
    double sum = 0;
    for (const Vec3& p : mesh.vertices) {
      const double d = std::fabs(j == 0 ? phantom.sdf_maxilla(p) : phantom.sdf_mandible(p));
      sum += d;
      if (d > out.max_sdf[j]) out.max_sdf[j] = d;
    }
    out.mean_sdf[j] = sum / static_cast<double>(mesh.vertices.size());
  }
  return out;
}

// The resampled volume's jaws against the reference's and the analytic surfaces: volumes
// within 1%, every vertex within `diagonal` (one voxel diagonal of the coarsest lattice the
// series holds) of its jaw's surface, the mean within a tenth of the smallest spacing.
void compare_jaws(const CtPhantom& phantom, const CtVolume& resampled, const CtVolume& reference,
                  double diagonal, double smallest, const char* name) {
  const Jaws a = reconstruct_jaws(phantom, resampled);
  const Jaws b = reconstruct_jaws(phantom, reference);
  const char* jaw[2] = {"maxilla", "mandible"};
  for (int j = 0; j < 2; ++j) {
    const double change = std::fabs(a.volume[j] - b.volume[j]) / b.volume[j];
    std::printf(
        "%s %s: volume %.1f mm^3 (reference %.1f, %.3f%%), |sdf| mean %.4f max %.4f mm "
        "(reference %.4f, %.4f)\n",
        name, jaw[j], a.volume[j], b.volume[j], 100 * change, a.mean_sdf[j], a.max_sdf[j],
        b.mean_sdf[j], b.max_sdf[j]);
    EXPECT_LT(change, 0.01) << name << " " << jaw[j];
    EXPECT_LT(a.max_sdf[j], diagonal) << name << " " << jaw[j];
    EXPECT_LT(a.mean_sdf[j], 0.1 * smallest) << name << " " << jaw[j];
  }
}

// 15 degrees of gantry tilt: slice k of the series is slice k of a phantom with rows half as
// far apart, taking every other row from row k: each slice lies half a row further along the
// column direction (tan 15 = 0.268 mm per 1 mm along the normal). The untilted reference takes
// rows 2 j + 24 of every slice: the resampled grid is centred on row 12 of the series, so its
// even slices are that reference exactly and its odd ones interpolated halfway between rows.
TEST(CtDicomResample, FifteenDegreeGantryTiltMatchesTheUntiltedPhantom) {
  double s = 0, c = 0;
  deterministic_sincos(15.0 * 3.14159265358979323846 / 180.0, &s, &c);
  const double dz = 1.0, half_row = dz * s / c, row = 2 * half_row;
  const uint32_t nx = 128, ny = 130, nz = 50, fine_ny = 2 * ny + nz - 2;
  CtPhantomOptions po;
  po.nx = nx;
  po.ny = fine_ny;
  po.nz = nz;
  po.spacing = Vec3{0.5, half_row, dz};
  po.axis_y = Vec3{0, c, -s};
  po.axis_z = Vec3{0, s, c};
  CtPhantom phantom;
  std::vector<int16_t> fine;
  CtVolume f;
  ASSERT_NO_FATAL_FAILURE(clean_phantom(po, &phantom, &fine, &f));
  std::vector<int16_t> tilted(size_t{nx} * ny * nz), untilted(size_t{nx} * ny * nz);
  std::vector<Vec3> positions;
  for (uint32_t k = 0; k < nz; ++k) {
    for (uint32_t j = 0; j < ny; ++j) {
      for (uint32_t i = 0; i < nx; ++i) {
        const size_t at = (size_t{k} * ny + j) * nx + i;
        tilted[at] = f.at(i, 2 * j + k, k);
        untilted[at] = f.at(i, 2 * j + 24, k);
      }
    }
    positions.push_back(f.origin + f.axis_y * (k * half_row) + f.axis_z * (k * dz));
  }
  const Vec3 spacing{0.5, row, dz};
  const CtVolume t = volume_of(&tilted, nx, ny, nz, f, spacing, positions[0]);
  const CtVolume u =
      volume_of(&untilted, nx, ny, nz, f, spacing, f.origin + f.axis_y * (24 * half_row));
  TempDir dir("resample", "tilt");
  write_series(t, positions, dir);
  ReadBack r = read_folder(dir.path.string(), size_t{64} << 20);
  SPLINTCORE_ASSERT_OK(r.status);
  EXPECT_EQ(r.volume.nx, nx);
  EXPECT_EQ(r.volume.ny, ny);
  ASSERT_EQ(r.volume.nz, nz);
  EXPECT_NEAR(r.volume.spacing.z, dz, 1e-9);
  EXPECT_NEAR(r.volume.spacing.y, row, 1e-9);
  EXPECT_LT(length(r.volume.origin - u.origin), 1e-6);
  EXPECT_LT(length(r.volume.axis_z - f.axis_z), 1e-9);
  EXPECT_TRUE(r.info.resampled);
  EXPECT_NEAR(r.info.tilt_degrees, 15.0, 1e-6);
  EXPECT_NEAR(r.info.max_shift_mm, 12.5 * row, 1e-6);  // slice 49: rows 24.5 - 12
  EXPECT_EQ(r.info.max_slice_offset_mm, 0.0);
  // Voxel by voxel: slice k's output row j is its row j + 12 - k / 2 (air outside).
  uint64_t odd = 0, inside = 0;
  double odd_error = 0;
  for (uint32_t k = 0; k < nz; ++k) {
    for (uint32_t j = 0; j < ny; ++j) {
      const int64_t source2 = 2 * int64_t{j} + 24 - k;  // twice the input row
      const bool in = source2 >= 0 && source2 <= 2 * int64_t{ny - 1};
      for (uint32_t i = 0; i < nx; ++i) {
        const size_t at = (size_t{k} * ny + j) * nx + i;
        if (!in) {
          ASSERT_EQ(r.hu[at], -1000) << i << " " << j << " " << k;
        } else if (k % 2 == 0) {
          ASSERT_EQ(r.hu[at], untilted[at]) << i << " " << j << " " << k;
        } else {
          odd_error += std::fabs(static_cast<double>(r.hu[at]) - untilted[at]);
          ++odd;
        }
        inside += in ? 1 : 0;
      }
    }
  }
  std::printf("tilt: %llu voxels from the slices, odd slices' mean |error| %.2f HU\n",
              static_cast<unsigned long long>(inside), odd_error / static_cast<double>(odd));
  EXPECT_LT(odd_error / static_cast<double>(odd), 8.0);  // measured 5.5 HU
  std::vector<int16_t> hu = r.hu;
  CtVolume v = r.volume;
  v.hu = hu.data();
  // Voxel 0.5 x 0.536 x 1 mm: diagonal 1.24 mm.
  compare_jaws(phantom, v, u, length(spacing), 0.5, "tilt");
}

// Uneven spacing and one missing slice: slices of a phantom 0.25 mm apart taken 0.25 to 0.75 mm
// apart (median 0.5) with one gap of 1 mm through the crowns. The even reference: every other
// phantom slice, which is the output grid: output slices where the series has a slice are
// exact, the others interpolated.
TEST(CtDicomResample, UnevenSpacingAndAMissingSliceMatchTheEvenPhantom) {
  const uint32_t nx = 128, ny = 104, fine_nz = 197, nz = 99;
  CtPhantomOptions po;
  po.nx = nx;
  po.ny = ny;
  po.nz = fine_nz;
  po.spacing = Vec3{0.5, 0.5, 0.25};
  CtPhantom phantom;
  std::vector<int16_t> fine;
  CtVolume f;
  ASSERT_NO_FATAL_FAILURE(clean_phantom(po, &phantom, &fine, &f));
  // Fine slice indices: gaps of 2, 2, 3, 1 (0.5, 0.5, 0.75, 0.25 mm) repeated, and one gap of 4
  // (a missing slice) at the occlusal plane (fine slice 98).
  std::vector<uint32_t> taken = {0};
  const uint32_t pattern[4] = {2, 2, 3, 1};
  for (uint32_t n = 0; taken.back() < fine_nz - 1; ++n) {
    uint32_t next = taken.back() + pattern[n % 4];
    if (taken.back() == 96) next = 100;
    if (next > fine_nz - 1) next = fine_nz - 1;
    taken.push_back(next);
  }
  const size_t per = size_t{nx} * ny;
  std::vector<int16_t> uneven(per * taken.size()), even(per * nz);
  std::vector<Vec3> positions;
  std::vector<bool> present(nz, false);
  for (size_t n = 0; n < taken.size(); ++n) {
    std::copy(fine.begin() + static_cast<std::ptrdiff_t>(per * taken[n]),
              fine.begin() + static_cast<std::ptrdiff_t>(per * (taken[n] + 1)),
              uneven.begin() + static_cast<std::ptrdiff_t>(per * n));
    positions.push_back(f.origin + f.axis_z * (0.25 * taken[n]));
    if (taken[n] % 2 == 0) present[taken[n] / 2] = true;
  }
  ASSERT_FALSE(present[49]);  // the missing slice
  for (uint32_t k = 0; k < nz; ++k) {
    std::copy(fine.begin() + static_cast<std::ptrdiff_t>(per * 2 * k),
              fine.begin() + static_cast<std::ptrdiff_t>(per * (2 * k + 1)),
              even.begin() + static_cast<std::ptrdiff_t>(per * k));
  }
  const CtVolume in = volume_of(&uneven, nx, ny, static_cast<uint32_t>(taken.size()), f,
                                Vec3{0.5, 0.5, 0.5}, f.origin);
  const CtVolume e = volume_of(&even, nx, ny, nz, f, Vec3{0.5, 0.5, 0.5}, f.origin);
  TempDir dir("resample", "uneven");
  write_series(in, positions, dir);
  ReadBack r = read_folder(dir.path.string(), size_t{64} << 20);
  SPLINTCORE_ASSERT_OK(r.status);
  ASSERT_EQ(r.volume.nz, nz);
  EXPECT_NEAR(r.volume.spacing.z, 0.5, 1e-9);
  EXPECT_LT(length(r.volume.origin - f.origin), 1e-9);
  EXPECT_TRUE(r.info.resampled);
  EXPECT_EQ(r.info.slice_count, taken.size());
  EXPECT_EQ(r.info.tilt_degrees, 0.0);
  EXPECT_NEAR(r.info.max_slice_offset_mm, 0.5, 1e-9);  // the missing slice
  double error = 0;
  uint64_t interpolated = 0;
  for (uint32_t k = 0; k < nz; ++k) {
    for (size_t v = 0; v < per; ++v) {
      const size_t at = per * k + v;
      if (present[k]) {
        ASSERT_EQ(r.hu[at], even[at]) << k << " " << v;
      } else {
        error += std::fabs(static_cast<double>(r.hu[at]) - even[at]);
        ++interpolated;
      }
    }
  }
  std::printf("uneven: %zu slices -> %u, interpolated slices' mean |error| %.2f HU\n", taken.size(),
              nz, error / static_cast<double>(interpolated));
  EXPECT_LT(error / static_cast<double>(interpolated), 4.0);  // measured 2.6 HU
  std::vector<int16_t> hu = r.hu;
  CtVolume v = r.volume;
  v.hu = hu.data();
  // Around the missing slice the series is 0.5 x 0.5 x 1 mm: diagonal 1.22 mm.
  compare_jaws(phantom, v, e, length(Vec3{0.5, 0.5, 1.0}), 0.5, "uneven");
}

// A small tilted stack with a missing slice: read in exactly its high water (two reads: the
// first finds five output slices for four files), and one byte less is a clean
// kArenaExhausted; a gap of four medians is refused; resample_max_gap 0 refuses all.
TEST(CtDicomResample, ExactArenaAndRefusals) {
  const uint32_t nx = 9, ny = 7, nz = 4;
  std::vector<int16_t> hu(size_t{nx} * ny * nz);
  for (size_t v = 0; v < hu.size(); ++v)
    hu[v] = static_cast<int16_t>(static_cast<int>((v * 37) % 2001) - 1000);
  CtVolume frame;
  const CtVolume v = volume_of(&hu, nx, ny, nz, frame, Vec3{0.5, 0.5, 1.0}, Vec3{0, 0, 0});
  std::vector<Vec3> positions = {Vec3{0, 0, 0}, Vec3{0, 0.3, 1}, Vec3{0, 0.6, 2}, Vec3{0, 1.2, 4}};
  TempDir dir("resample", "small");
  write_series(v, positions, dir);
  ReadBack r = read_folder(dir.path.string(), size_t{1} << 20);
  SPLINTCORE_ASSERT_OK(r.status);
  EXPECT_EQ(r.volume.nz, 5u);
  EXPECT_TRUE(r.info.resampled);
  ReadBack exact = read_folder(dir.path.string(), r.high_water);
  SPLINTCORE_EXPECT_OK(exact.status);
  EXPECT_EQ(exact.hu, r.hu);
  ReadBack less = read_folder(dir.path.string(), r.high_water - 1);
  EXPECT_EQ(less.status.code(), StatusCode::kArenaExhausted) << test::format(less.status);
  CtReadOptions strict;
  strict.resample_max_gap = 0;
  ReadBack refused = read_folder(dir.path.string(), size_t{1} << 20, strict);
  EXPECT_EQ(refused.status.code(), StatusCode::kUnsupported);
  EXPECT_NE(std::string(refused.status.message()).find("non-uniform slice spacing"),
            std::string::npos)
      << test::format(refused.status);

  TempDir far("resample", "far");
  positions.back() = Vec3{0, 1.2, 6.5};  // 4.5 mm after a median of 1
  write_series(v, positions, far);
  r = read_folder(far.path.string(), size_t{1} << 20);
  EXPECT_EQ(r.status.code(), StatusCode::kUnsupported);
  EXPECT_NE(std::string(r.status.message()).find("slices too far apart to resample"),
            std::string::npos)
      << test::format(r.status);
}

// The GE head CT of the public dcm2niix validation set (neurolabusc/dcm_qa_ct, In/GE): 28
// slices of 512 x 512, 18.5 degree gantry tilt, 4 mm apart, then 1.08 mm, then 7 mm apart.
// Optional: read where it lies (SPLINTCORE_DCM_QA_CT_DIR, a checkout or an extraction such as
// `git --git-dir=<mirror> archive HEAD In/GE | tar -x -C <dir>`), skipped when absent. The
// oracle: an independent resampling written here in patient space (each output voxel's
// position projected on the two input slices around it through their own Image Position,
// bilinear in each, linear between), from the slices read one by one.
struct InputSlice {
  Vec3 position;
  double along = 0;
  std::vector<int16_t> hu;
};

double sample(const InputSlice& s, const CtVolume& g, const Vec3& p, bool* inside) {
  const Vec3 d = p - s.position;
  const double u = dot(d, g.axis_x) / g.spacing.x, v = dot(d, g.axis_y) / g.spacing.y;
  *inside = u >= 0 && v >= 0 && u <= g.nx - 1.0 && v <= g.ny - 1.0;
  if (!*inside) return -1000.0;
  const uint32_t i = static_cast<uint32_t>(u), j = static_cast<uint32_t>(v);
  const uint32_t i1 = i + 1 < g.nx ? i + 1 : i, j1 = j + 1 < g.ny ? j + 1 : j;
  const double fu = u - i, fv = v - j;
  auto at = [&](uint32_t a, uint32_t b) { return static_cast<double>(s.hu[size_t{b} * g.nx + a]); };
  return (at(i, j) * (1 - fu) + at(i1, j) * fu) * (1 - fv) +
         (at(i, j1) * (1 - fu) + at(i1, j1) * fu) * fv;
}

// How the reader's resampled volume r of `folder` agrees with the independent resampling:
// voxels compared (inside both slices around them), the largest difference, how many are
// more than 1 HU apart.
struct Agreement {
  bool ok = false;
  uint64_t compared = 0, off_by_more = 0;
  int largest = 0;
};

Agreement compare_with_independent_resampling(const std::string& folder, const ReadBack& r) {
  Agreement out;
  const CtVolume& g = r.volume;
  // The input slices, read one by one, in order along the normal.
  std::vector<std::string> files;
  if (!cli::list_dicom_folder(folder, &files).is_ok()) return out;
  std::vector<InputSlice> slices;
  for (const std::string& name : files) {
    ReadBack one = read_folder(name, size_t{8} << 20);
    if (!one.status.is_ok()) return out;
    InputSlice s;
    s.position = one.volume.origin;
    s.along = dot(s.position, g.axis_z);
    s.hu = one.hu;
    slices.push_back(s);
  }
  std::sort(slices.begin(), slices.end(),
            [](const InputSlice& a, const InputSlice& b) { return a.along < b.along; });
  uint64_t& compared = out.compared;
  uint64_t& off_by_more = out.off_by_more;
  int& largest = out.largest;
  for (uint32_t k = 0; k < g.nz; ++k) {
    for (uint32_t j = 0; j < g.ny; ++j) {
      for (uint32_t i = 0; i < g.nx; ++i) {
        const Vec3 p = ct_to_patient(g, Vec3{g.spacing.x * i, g.spacing.y * j, g.spacing.z * k});
        const double a = dot(p, g.axis_z);
        size_t n = 0;
        while (n + 2 < slices.size() && slices[n + 1].along <= a) ++n;
        double w = (a - slices[n].along) / (slices[n + 1].along - slices[n].along);
        w = w < 0 ? 0 : (w > 1 ? 1 : w);
        bool in0 = false, in1 = false;
        const double v0 = sample(slices[n], g, p, &in0), v1 = sample(slices[n + 1], g, p, &in1);
        if (!in0 || !in1) continue;  // at the slices' borders: air, not compared
        const int expected = static_cast<int>(std::lround(v0 * (1 - w) + v1 * w));
        const int got = r.hu[(size_t{k} * g.ny + j) * g.nx + i];
        const int diff = std::abs(got - expected);
        ++compared;
        if (diff > largest) largest = diff;
        if (diff > 1) ++off_by_more;
      }
    }
  }
  out.ok = true;
  return out;
}

TEST(CtDicomResample, GeHeadCtWithGantryTiltMatchesAnIndependentResampling) {
  const std::string folder = std::string(SPLINTCORE_DCM_QA_CT_DIR) + "/In/GE";
  if (!fs::is_directory(folder)) GTEST_SKIP() << "dcm_qa_ct not found at " << folder;
  ReadBack r = read_folder(folder, size_t{160} << 20);
  SPLINTCORE_ASSERT_OK(r.status);
  const CtVolume& g = r.volume;
  EXPECT_TRUE(r.info.resampled);
  EXPECT_EQ(r.info.slice_count, 28u);
  EXPECT_NEAR(r.info.tilt_degrees, 18.5, 0.01);
  EXPECT_EQ(g.nx, 512u);
  EXPECT_EQ(g.ny, 512u);
  std::printf(
      "GE: %u slices -> %u of %.4f mm, tilt %.3f deg, in-plane correction <= %.2f mm, "
      "slice correction <= %.3f mm\n",
      r.info.slice_count, g.nz, g.spacing.z, r.info.tilt_degrees, r.info.max_shift_mm,
      r.info.max_slice_offset_mm);
  const Agreement a = compare_with_independent_resampling(folder, r);
  ASSERT_TRUE(a.ok);
  std::printf(
      "GE: %llu voxels compared with the independent resampling, largest difference %d HU, "
      "%llu more than 1 HU apart\n",
      static_cast<unsigned long long>(a.compared), a.largest,
      static_cast<unsigned long long>(a.off_by_more));
  EXPECT_GT(a.compared, uint64_t{g.nx} * g.ny * g.nz / 2);
  EXPECT_LT(a.off_by_more * 10000, a.compared);  // the rounding of the straightened slices aside
  // The skull (300 HU and up, grown from the first bone voxel left of the middle row of the
  // middle slice) reconstructs into a closed, oriented mesh.
  std::vector<int16_t> hu = r.hu;
  CtVolume v = g;
  v.hu = hu.data();
  TestArena ta(size_t{1} << 30);
  Context ctx(&ta.arena);
  LabelVolume labels;
  ThresholdStats ts;
  SPLINTCORE_ASSERT_OK(threshold_window(ctx, v, HuWindow{300, 4000}, &labels, &ts));
  RegionSeed seed;
  seed.label = 1;
  bool found = false;
  for (uint32_t i = 0; i < v.nx && !found; ++i) {
    if (v.at(i, v.ny / 2, v.nz / 2) >= 1000) {
      seed.patient_mm = ct_to_patient(
          v, Vec3{v.spacing.x * i, v.spacing.y * (v.ny / 2), v.spacing.z * (v.nz / 2)});
      found = true;
    }
  }
  ASSERT_TRUE(found);
  RegionStats grow;
  SPLINTCORE_ASSERT_OK(
      grow_regions(ctx, v, Span<const RegionSeed>(&seed, 1), RegionGrowOptions{}, &labels, &grow));
  Mesh mesh(&ta.arena);
  ReconstructOptions ro;
  ro.label = 1;
  ReconstructStats rs;
  SPLINTCORE_ASSERT_OK(reconstruct_region(ctx, v, labels, ro, &mesh, &rs));
  double volume = 0;
  SPLINTCORE_ASSERT_OK(check_closed_oriented(ctx, mesh, &volume));
  std::printf("GE: skull %llu voxels, %zu triangles, %.0f mm^3, closed and oriented\n",
              static_cast<unsigned long long>(grow.voxels[1]), mesh.triangles.size(), volume);
  EXPECT_GT(volume, 1.0e4);
}

// The Philips phantom series of the same set (In/Philips/S21610: S2010 and S3010, two gantry
// tilts; each folder holds a DIRFILE, the DICOM directory the folder lister skips), against
// the same independent resampling. Skipped when absent.
TEST(CtDicomResample, PhilipsTiltedSeriesMatchAnIndependentResampling) {
  for (const char* series : {"S2010", "S3010"}) {
    const std::string folder =
        std::string(SPLINTCORE_DCM_QA_CT_DIR) + "/In/Philips/S21610/" + series;
    if (!fs::is_directory(folder)) GTEST_SKIP() << "dcm_qa_ct not found at " << folder;
    ReadBack r = read_folder(folder, size_t{160} << 20);
    SPLINTCORE_ASSERT_OK(r.status);
    EXPECT_TRUE(r.info.resampled) << series;
    EXPECT_GT(r.info.tilt_degrees, 1.0) << series;
    const Agreement a = compare_with_independent_resampling(folder, r);
    ASSERT_TRUE(a.ok);
    std::printf(
        "Philips %s: %u slices -> %u of %.4f mm, tilt %.3f deg, in-plane correction <= %.2f mm; "
        "%llu voxels compared, largest difference %d HU, %llu more than 1 HU apart\n",
        series, r.info.slice_count, r.volume.nz, r.volume.spacing.z, r.info.tilt_degrees,
        r.info.max_shift_mm, static_cast<unsigned long long>(a.compared), a.largest,
        static_cast<unsigned long long>(a.off_by_more));
    EXPECT_GT(a.compared, r.volume.voxel_count() / 2) << series;
    EXPECT_LT(a.off_by_more * 10000, a.compared) << series;
  }
}

}  // namespace
}  // namespace splintcore
