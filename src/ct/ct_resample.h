// Geometry as scanners write it (issue 31): a DICOM stack that is not a uniform stack along its
// normal -- gantry tilt or shear (each slice's origin offset in-plane), uneven spacing, missing
// slices -- resampled onto a regular orthogonal grid while the slices stream in, in position
// order: each slice shifted in-plane by bilinear interpolation onto the output's columns and
// rows, then output slices interpolated linearly along the normal between the two input slices
// around them. Only + - * / and floor (no libm transcendental function reaches the voxels).
#ifndef SPLINTCORE_SRC_CT_CT_RESAMPLE_H
#define SPLINTCORE_SRC_CT_CT_RESAMPLE_H

#include "splintcore/ct.h"

namespace splintcore {
namespace ct_detail {

// The value of output samples that fall outside the input slice: air.
constexpr int16_t kAirHu = -1000;

// Where slice k (in position order) lies relative to slice 0, mm: along the normal, and in the
// slice plane along the row (+column index) and column (+row index) directions.
struct SliceOffset {
  double along = 0;
  double x = 0;
  double y = 0;
};

// How the slices become the output grid. shift and interpolate both false: the slices are the
// grid (a uniform stack along the normal, within the tolerances), read in place.
struct ResamplePlan {
  bool shift = false;        // slices shifted in-plane (gantry tilt, shear)
  bool interpolate = false;  // output slices interpolated along the normal
  uint32_t nz = 0;           // output slices
  double spacing_z = 0;      // output spacing along the normal, mm
  double origin_x = 0;       // the output's in-plane origin relative to slice 0's, mm (a whole
  double origin_y = 0;       // number of pixels: the centre of the slices' offsets, rounded)
  double tilt_degrees = 0;   // between the normal and slice 0 -> last slice
  double max_shift_mm = 0;   // the largest in-plane correction of a slice
  double max_offset_mm = 0;  // the largest distance of an output slice to its nearest input
  // Refusal: the gap after slice bad_gap (position order) is wider than max_gap x median.
  bool gap_too_wide = false;
  uint32_t bad_gap = 0;
  double median_gap = 0;
};

// How far positions may stray at distance x: max(tolerance_mm, relative x).
double allowed_deviation(const CtReadOptions& options, double x);

// The plan for slices at offsets[0, count) (position order, distinct along the normal, count
// >= 2), pixels pixel_x by pixel_y mm. uniform: the gaps are within the tolerance of their mean
// (then the output spacing is that mean and no slice is interpolated). gaps: count - 1 doubles
// of scratch. The output spacing of an uneven stack is the median gap (the lower one of an even
// count); every gap must be at most options.resample_max_gap medians (else gap_too_wide).
void plan_resampling(const SliceOffset* offsets, uint32_t count, bool uniform, double pixel_x,
                     double pixel_y, const CtReadOptions& options, double* gaps,
                     ResamplePlan* plan);

// out(i, j) = in at (i + sx, j + sy) pixels, bilinear; samples outside the slice are kAirHu.
void shift_slice(const int16_t* in, uint32_t nx, uint32_t ny, double sx, double sy, int16_t* out);

// out = a (1 - t) + b t, rounded half away from zero.
void blend_slices(const int16_t* a, const int16_t* b, uint64_t count, double t, int16_t* out);

// The streaming resampler: slice k (position order) is read into target(k), then place(k)
// writes the output slices it completes. Three slice buffers (raw, previous, current) of the
// caller's; the volume holds plan.nz slices.
struct SliceResampler {
  const ResamplePlan* plan = nullptr;
  const SliceOffset* offsets = nullptr;
  uint32_t count = 0;  // input slices
  uint32_t nx = 0, ny = 0;
  double pixel_x = 1, pixel_y = 1;
  int16_t* volume = nullptr;
  int16_t* raw = nullptr;
  int16_t* previous = nullptr;
  int16_t* current = nullptr;
  uint32_t next_out = 0;  // the next output slice to write

  int16_t* target(uint32_t k) const;
  void place(uint32_t k);
};

}  // namespace ct_detail
}  // namespace splintcore

#endif  // SPLINTCORE_SRC_CT_CT_RESAMPLE_H
