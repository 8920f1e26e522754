// Threshold segmentation of a CT volume by a Hounsfield window, and the mapping of seed points
// from patient coordinates to voxels.
//
// Source: Chen et al., "EasySplint", 2016, section 2.1 (bone and teeth segmented from the CT by
// thresholding before region growing); the HU scale: DICOM PS3.3 C.11.1.1.2 (Modality LUT,
// rescale slope and intercept). See segment.h for the label encoding.
#include <cmath>
#include <cstring>

#include "splintcore/segment.h"

namespace splintcore {

uint64_t threshold_window_bound(const CtVolume& volume) {
  const uint64_t n = volume.voxel_count();
  uint64_t bytes = 0;
  if (!checked_add(n, 16, &bytes)) return 0;
  return bytes;
}

Status threshold_window(const Context& ctx, const CtVolume& volume, const HuWindow& window,
                        LabelVolume* out, ThresholdStats* stats) {
  if (volume.nx == 0 || volume.ny == 0 || volume.nz == 0 || volume.hu == nullptr) {
    return make_error(StatusCode::kInvalidArgument, "threshold: the CT volume is empty (",
                      volume.nx, " x ", volume.ny, " x ", volume.nz, " voxels)");
  }
  if (window.lo > window.hi) {
    return make_error(StatusCode::kInvalidArgument, "threshold: the HU window is empty: lo ",
                      window.lo, " > hi ", window.hi);
  }
  const uint64_t n = volume.voxel_count();
  if (n > SIZE_MAX) {
    return make_error(StatusCode::kLimitExceeded, "threshold: ", n,
                      " voxels do not fit this machine's address space");
  }
  const Arena::Marker start = ctx.arena->mark();
  uint8_t* labels = ctx.arena->allocate_array<uint8_t>(static_cast<size_t>(n));
  if (labels == nullptr) return ctx.arena->exhausted_status();

  const uint64_t slice = uint64_t{volume.nx} * volume.ny;
  // The window clipped to the int16 range the voxels have (it cannot be empty: lo <= hi, and a
  // window entirely outside int16 marks nothing, which the clipped one does too).
  const int32_t lo = window.lo < -32768 ? -32768 : (window.lo > 32767 ? 32767 : window.lo);
  const int32_t hi = window.hi > 32767 ? 32767 : (window.hi < -32768 ? -32768 : window.hi);
  const bool none = window.hi < -32768 || window.lo > 32767;
  const uint16_t lo16 = static_cast<uint16_t>(lo);
  const uint16_t span16 = none ? 0 : static_cast<uint16_t>(hi - lo);
  uint64_t count = 0;
  for (uint32_t k = 0; k < volume.nz; ++k) {
    if (none) {
      std::memset(labels + slice * k, 0, static_cast<size_t>(slice));
      continue;
    }
    if ((k & 15u) == 0) {
      Status s = report_progress(ctx, "threshold", k, volume.nz);
      if (!s.is_ok()) {
        ctx.arena->rewind(start);
        return s;
      }
    }
    const int16_t* src = volume.hu + slice * k;
    uint8_t* dst = labels + slice * k;
    // lo <= h <= hi as one 16-bit unsigned comparison (h - lo wraps modulo 2^16), branch-free,
    // in blocks of a fixed 64 voxels (loops of a constant trip count of same-width lanes are
    // vectorised even by GCC's cheap -O2 model).
    uint64_t v = 0;
    for (; v + 64 <= slice; v += 64) {
      uint8_t mask[64];
      for (uint32_t b = 0; b < 64; ++b) {
        const uint16_t d = static_cast<uint16_t>(static_cast<uint16_t>(src[v + b]) - lo16);
        mask[b] = d <= span16 ? 0xFF : 0x00;
      }
      uint32_t in = 0;
      for (uint32_t b = 0; b < 64; ++b) {
        dst[v + b] = mask[b];
        in += mask[b] & 1u;
      }
      count += in;
    }
    for (; v < slice; ++v) {
      const uint16_t d = static_cast<uint16_t>(static_cast<uint16_t>(src[v]) - lo16);
      dst[v] = d <= span16 ? 0xFF : 0x00;
      count += d <= span16 ? 1u : 0u;
    }
  }
  {
    Status s = report_progress(ctx, "threshold", volume.nz, volume.nz);
    if (!s.is_ok()) {
      ctx.arena->rewind(start);
      return s;
    }
  }
  out->nx = volume.nx;
  out->ny = volume.ny;
  out->nz = volume.nz;
  out->labels = labels;
  if (stats != nullptr) stats->in_window = count;
  return Status::ok();
}

Status seed_voxel(const CtVolume& volume, const RegionSeed& seed, uint32_t* i, uint32_t* j,
                  uint32_t* k) {
  const uint32_t n[3] = {volume.nx, volume.ny, volume.nz};
  if (!seed.in_patient_mm) {
    const uint32_t c[3] = {seed.i, seed.j, seed.k};
    for (int a = 0; a < 3; ++a) {
      if (c[a] >= n[a]) {
        return make_error(StatusCode::kInvalidArgument, "seed voxel (", seed.i, ", ", seed.j, ", ",
                          seed.k, ") is outside the volume of ", volume.nx, " x ", volume.ny, " x ",
                          volume.nz, " voxels");
      }
    }
    *i = seed.i;
    *j = seed.j;
    *k = seed.k;
    return Status::ok();
  }
  const Vec3 p = seed.patient_mm;
  if (!is_finite(p.x) || !is_finite(p.y) || !is_finite(p.z)) {
    return make_error(StatusCode::kInvalidArgument, "seed point is not finite");
  }
  // Inverse of ct_to_patient for orthonormal axes: the offset from the origin projected on
  // each axis, divided by the spacing; the nearest voxel centre per axis.
  const Vec3 d = p - volume.origin;
  const Vec3 axes[3] = {volume.axis_x, volume.axis_y, volume.axis_z};
  const double spacing[3] = {volume.spacing.x, volume.spacing.y, volume.spacing.z};
  uint32_t c[3] = {0, 0, 0};
  for (int a = 0; a < 3; ++a) {
    const double u = dot(d, axes[a]) / spacing[a];
    const double r = std::floor(u + 0.5);
    if (!(r >= 0.0) || !(r < static_cast<double>(n[a]))) {
      return make_error(StatusCode::kInvalidArgument, "seed point (", p.x, ", ", p.y, ", ", p.z,
                        ") mm is outside the volume (voxel coordinate ", u, " on axis ",
                        a == 0 ? "x" : (a == 1 ? "y" : "z"), ", valid -0.5 to ",
                        static_cast<double>(n[a]) - 0.5, ")");
    }
    c[a] = static_cast<uint32_t>(r);
  }
  *i = c[0];
  *j = c[1];
  *k = c[2];
  return Status::ok();
}

}  // namespace splintcore
