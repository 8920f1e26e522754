// splintcore ct: CT volumes in Hounsfield units and their readers (DICOM series, NRRD,
// MetaImage). Floor 4: core, geometry, io, volume.
//
// The voxel data of a volume lives in the caller's arena; its size (2 bytes per voxel) is
// known from the header and checked against the arena's cap before anything is allocated.
#ifndef SPLINTCORE_CT_H
#define SPLINTCORE_CT_H

#include "splintcore/core.h"
#include "splintcore/geometry.h"
#include "splintcore/io.h"
#include "splintcore/volume.h"

namespace splintcore {

// A CT volume. Voxel (i, j, k), 0 <= i < nx and so on, is hu[(k * ny + j) * nx + i]: x (the
// image columns) fastest, then y (rows), then z (slices). Its centre in patient coordinates (mm)
// is ct_to_patient(v, {spacing.x i, spacing.y j, spacing.z k}).
//
// Values are Hounsfield units after the file's rescale (HU = slope * stored + intercept),
// rounded to the nearest integer (halves away from zero) and saturated to the int16 range;
// `saturated` counts voxels that were clamped.
struct CtVolume {
  uint32_t nx = 0, ny = 0, nz = 0;
  Vec3 spacing{};                  // mm between voxel centres along x, y, z; each > 0
  Vec3 origin{};                   // patient position of voxel (0, 0, 0), mm
  Vec3 axis_x{1, 0, 0};            // unit directions of +i, +j, +k in patient space:
  Vec3 axis_y{0, 1, 0};            // orthonormal (readers check it; a right-handed frame is
  Vec3 axis_z{0, 0, 1};            // not required: axis_z follows the slice order)
  int16_t* hu = nullptr;           // nx * ny * nz values in the arena
  uint64_t saturated = 0;

  uint64_t voxel_count() const { return uint64_t{nx} * ny * nz; }
  int16_t at(uint32_t i, uint32_t j, uint32_t k) const {
    return hu[(uint64_t{k} * ny + j) * nx + i];
  }
};

// The volume's grid in its own (voxel-aligned) frame: origin (0, 0, 0), its spacing and size.
// Meshes made on this grid are in that frame; ct_to_patient() maps them into the patient's.
inline VolumeGrid ct_local_grid(const CtVolume& v) {
  VolumeGrid g;
  g.origin = Vec3{0, 0, 0};
  g.spacing = v.spacing;
  g.nx = v.nx;
  g.ny = v.ny;
  g.nz = v.nz;
  return g;
}

// origin + axis_x p.x + axis_y p.y + axis_z p.z, in that order of operations (no fused
// multiply-add), so the bits are the same everywhere. With identity axes this is exactly
// origin + p.
inline Vec3 ct_to_patient(const CtVolume& v, const Vec3& p) {
  const Vec3 a = v.axis_x * p.x;
  const Vec3 b = v.axis_y * p.y;
  const Vec3 c = v.axis_z * p.z;
  return v.origin + ((a + b) + c);
}

}  // namespace splintcore

#endif  // SPLINTCORE_CT_H
