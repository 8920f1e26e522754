// Shared checks of the CT reader fuzz targets (ct_dicom_fuzz.cpp, ct_nrrd_fuzz.cpp,
// ct_metaimage_fuzz.cpp): small limits so a run stays fast, and the invariants a successful
// read must satisfy (any violation aborts: a bug).
#ifndef SPLINTCORE_TESTS_FUZZ_CT_FUZZ_COMMON_H
#define SPLINTCORE_TESTS_FUZZ_CT_FUZZ_COMMON_H

#include <cmath>
#include <cstdlib>

#include "splintcore/ct.h"

namespace splintcore {
namespace fuzz {

inline CtReadOptions small_options(size_t size) {
  CtReadOptions o;
  o.max_dimension = 512;
  o.max_voxels = uint64_t{1} << 20;
  o.max_header_bytes = 1 << 16;
  o.chunk_bytes = 64 + size % 300;  // vary the chunking
  return o;
}

// After a failed read nothing stays in the arena; after a success only the voxels do, and the
// volume is well formed.
inline void check(const Status& status, const Arena& arena, const CtVolume& v,
                  const CtReadOptions& o) {
  if (!status.is_ok()) {
    if (arena.used() != 0) std::abort();
    return;
  }
  const uint64_t voxels = v.voxel_count();
  if (voxels == 0 || v.hu == nullptr || voxels > o.max_voxels) std::abort();
  if (arena.used() < voxels * 2 || arena.used() > voxels * 2 + 16) std::abort();
  const Vec3 axes[3] = {v.axis_x, v.axis_y, v.axis_z};
  for (const Vec3& a : axes) {
    if (!(std::fabs(length(a) - 1.0) < 1e-6)) std::abort();
  }
  for (int a = 0; a < 3; ++a) {
    if (!(v.spacing[a] >= o.min_spacing && v.spacing[a] <= o.max_spacing)) std::abort();
  }
  if (!is_finite(v.origin)) std::abort();
  int64_t sum = 0;  // touches every voxel (ASan checks the bounds)
  for (uint64_t i = 0; i < voxels; ++i) sum += v.hu[i];
  if (sum == INT64_MIN) std::abort();
}

}  // namespace fuzz
}  // namespace splintcore

#endif  // SPLINTCORE_TESTS_FUZZ_CT_FUZZ_COMMON_H
