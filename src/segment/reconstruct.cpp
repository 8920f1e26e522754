// Surface reconstruction of one labelled region of a CT volume: the region's iso-surface at the
// segmentation threshold, extracted by the library's marching tetrahedra (volume.h) from a
// field streamed layer by layer out of the HU and the labels.
//
// Sources: Lorensen and Cline, "Marching cubes", SIGGRAPH 1987 (iso-surfaces of CT at a
// threshold, interpolated between voxels); Chen et al., "EasySplint", 2016, section 2.1 (jaw
// models reconstructed from the segmented CT). The field (HU where the region meets background,
// mirrored where it meets another region) is ours; segment.h states it.
#include <cmath>
#include <cstring>

#include "splintcore/segment.h"

namespace splintcore {

namespace {

struct RegionField {
  const CtVolume* volume = nullptr;
  const uint8_t* labels = nullptr;
  uint8_t label = 0;
  float centre = 0.0f;         // lo - 0.5: exact in float (|lo| < 2^23)
  uint32_t lo[3] = {0, 0, 0};  // the box's first voxel
  uint32_t size[3] = {0, 0, 0};

  static Status fill(void* user, uint32_t z_begin, uint32_t z_end, Span<float> out) {
    const RegionField& f = *static_cast<const RegionField*>(user);
    const CtVolume& v = *f.volume;
    const uint8_t label = f.label;
    const float c = f.centre;
    float* dst = out.data();
    for (uint32_t z = z_begin; z < z_end; ++z) {
      const uint64_t k = uint64_t{f.lo[2]} + z;
      for (uint32_t y = 0; y < f.size[1]; ++y) {
        const uint64_t row = (k * v.ny + (uint64_t{f.lo[1]} + y)) * v.nx + f.lo[0];
        const int16_t* hu = v.hu + row;
        const uint8_t* lab = f.labels + row;
        for (uint32_t x = 0; x < f.size[0]; ++x) {
          const float g = c - static_cast<float>(hu[x]);
          // g != 0 always (HU are integers, c is a half-integer): inside exactly on the label.
          dst[x] = lab[x] == label ? g : std::fabs(g);
        }
        dst += f.size[0];
      }
    }
    return Status::ok();
  }
};

// The checks of reconstruct_region's arguments (no memory needed).
Status check_reconstruct_input(const CtVolume& volume, const LabelVolume& labels,
                               const ReconstructOptions& options, const Mesh* out) {
  const uint8_t label = options.label;
  if (label == 0 || label > kMaxRegionLabel) {
    return make_error(StatusCode::kInvalidArgument, "reconstruct: label ",
                      static_cast<uint32_t>(label), " is not a region label (1..", kMaxRegionLabel,
                      ")");
  }
  if (labels.labels == nullptr || volume.hu == nullptr || labels.nx != volume.nx ||
      labels.ny != volume.ny || labels.nz != volume.nz || volume.voxel_count() == 0) {
    return make_error(StatusCode::kInvalidArgument,
                      "reconstruct: the label volume does not match the CT volume (", volume.nx,
                      " x ", volume.ny, " x ", volume.nz, ")");
  }
  if (options.hu_lo <= -(1 << 22) || options.hu_lo >= (1 << 22)) {
    return make_error(StatusCode::kInvalidArgument, "reconstruct: threshold ", options.hu_lo,
                      " HU is out of range");
  }
  if (out == nullptr || !out->vertices.empty() || !out->triangles.empty()) {
    return make_error(StatusCode::kInvalidArgument, "reconstruct: the output mesh must be empty");
  }
  return Status::ok();
}

// The box [lo, hi] of the voxels labelled `label`, and their *count, in one pass over the
// labels.
Status find_region_box(const Context& ctx, const LabelVolume& labels, uint8_t label, uint32_t lo[3],
                       uint32_t hi[3], uint64_t* count) {
  const uint32_t nx = labels.nx, ny = labels.ny, nz = labels.nz;
  for (uint32_t k = 0; k < nz; ++k) {
    if ((k & 31u) == 0) {
      SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "reconstruct: region box", k, nz));
    }
    for (uint32_t j = 0; j < ny; ++j) {
      const uint8_t* row = labels.labels + (uint64_t{k} * ny + j) * nx;
      // Most rows hold none of the region: memchr skips them at memory speed.
      if (std::memchr(row, label, nx) == nullptr) continue;
      uint32_t first = nx, last = 0, in_row = 0;
      for (uint32_t i = 0; i < nx; ++i) {
        if (row[i] == label) {
          if (first == nx) first = i;
          last = i;
          ++in_row;
        }
      }
      if (in_row == 0) continue;
      *count += in_row;
      if (first < lo[0]) lo[0] = first;
      if (last > hi[0]) hi[0] = last;
      if (j < lo[1]) lo[1] = j;
      if (j > hi[1]) hi[1] = j;
      if (k < lo[2]) lo[2] = k;
      if (k > hi[2]) hi[2] = k;
    }
  }
  return Status::ok();
}

// Into patient coordinates, then (optionally) float32: in place, vertex by vertex. Axes
// that make a left-handed frame (slice order reversed) mirror the mesh, which would turn it
// inside out: then every triangle's winding is reversed (its first corner kept). The axes are
// orthonormal (the readers check), so the determinant is +-1 and its sign is never in doubt.
Status to_patient_coordinates(const CtVolume& volume, bool to_float32, Mesh* mesh) {
  const Vec3& ax = volume.axis_x;
  const Vec3& ay = volume.axis_y;
  const Vec3& az = volume.axis_z;
  const double det = ax.x * (ay.y * az.z - ay.z * az.y) - ax.y * (ay.x * az.z - ay.z * az.x) +
                     ax.z * (ay.x * az.y - ay.y * az.x);
  if (det < 0.0) {
    for (Triangle& t : mesh->triangles) {
      const uint32_t b = t.v[1];
      t.v[1] = t.v[2];
      t.v[2] = b;
    }
  }
  for (size_t v = 0; v < mesh->vertices.size(); ++v) {
    Vec3 p = ct_to_patient(volume, mesh->vertices[v]);
    if (to_float32 && !round_to_float32(&p)) {
      return make_error(StatusCode::kNonFinite, "reconstruct: vertex ", v,
                        " is beyond float32's range in patient coordinates")
          .at_index(v);
    }
    mesh->vertices[v] = p;
  }
  return Status::ok();
}

}  // namespace

uint64_t reconstruct_region_bound(const uint32_t box_voxels[3], uint32_t layers,
                                  uint64_t vertex_count, uint64_t triangle_count) {
  VolumeGrid grid;
  grid.spacing = Vec3{1, 1, 1};
  grid.nx = box_voxels[0];
  grid.ny = box_voxels[1];
  grid.nz = box_voxels[2];
  const uint64_t work = marching_cubes_bound(grid, layers);
  const uint64_t mesh = marching_cubes_mesh_extra_bound(vertex_count, triangle_count);
  uint64_t total = 0;
  if (work == 0 || mesh == 0 || !checked_add(work, mesh, &total)) return 0;
  return total;
}

Status reconstruct_region(const Context& ctx, const CtVolume& volume, const LabelVolume& labels,
                          const ReconstructOptions& options, Mesh* out, ReconstructStats* stats) {
  SPLINTCORE_RETURN_IF_ERROR(check_reconstruct_input(volume, labels, options, out));
  const uint8_t label = options.label;
  uint32_t lo[3] = {volume.nx, volume.ny, volume.nz};
  uint32_t hi[3] = {0, 0, 0};
  uint64_t count = 0;
  SPLINTCORE_RETURN_IF_ERROR(find_region_box(ctx, labels, label, lo, hi, &count));
  if (count == 0) {
    return make_error(StatusCode::kInvalidArgument, "reconstruct: region ",
                      static_cast<uint32_t>(label), " is empty (no voxel has that label)");
  }
  // One voxel of margin (the outside samples the surface interpolates to), within the volume.
  const uint32_t n[3] = {volume.nx, volume.ny, volume.nz};
  RegionField field;
  field.volume = &volume;
  field.labels = labels.labels;
  field.label = label;
  field.centre = static_cast<float>(options.hu_lo) - 0.5f;
  for (int a = 0; a < 3; ++a) {
    const uint32_t b0 = lo[a] > 0 ? lo[a] - 1 : 0;
    const uint32_t b1 = hi[a] + 1 < n[a] ? hi[a] + 1 : n[a] - 1;
    field.lo[a] = b0;
    field.size[a] = b1 - b0 + 1;
    if (stats != nullptr) {
      stats->box_lo[a] = b0;
      stats->box_hi[a] = b1;
    }
  }
  VolumeGrid grid;
  grid.spacing = volume.spacing;
  grid.origin = Vec3{volume.spacing.x * static_cast<double>(field.lo[0]),
                     volume.spacing.y * static_cast<double>(field.lo[1]),
                     volume.spacing.z * static_cast<double>(field.lo[2])};
  grid.nx = field.size[0];
  grid.ny = field.size[1];
  grid.nz = field.size[2];

  LayerSource source;
  source.fill = &RegionField::fill;
  source.user = &field;
  MarchingCubesOptions mo;
  mo.iso = 0.0;
  mo.layers_per_tile = options.layers_per_tile;
  MarchingCubesStats ms;
  ArenaScope scope(*ctx.arena);  // on an error the arena is as it was and `out` empty
  SPLINTCORE_RETURN_IF_ERROR(marching_cubes_mesh(ctx, grid, source, mo, out, &ms));
  Status s = report_progress(ctx, "reconstruct: patient coordinates", 0, 1);
  if (s.is_ok()) s = to_patient_coordinates(volume, options.round_to_float32, out);
  if (!s.is_ok()) {
    out->bind(ctx.arena);
    return s;
  }
  scope.commit();
  uint32_t flat = 0;
  if (options.round_to_float32 && find_flat_triangle(*out) != kNoTriangle) flat = 1;
  if (stats != nullptr) {
    stats->region_voxels = count;
    stats->marching = ms;
    stats->flat_after_rounding = flat;
  }
  return Status::ok();
}

}  // namespace splintcore
