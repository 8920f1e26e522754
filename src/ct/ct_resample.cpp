// Resampling of tilted, sheared and unevenly spaced DICOM stacks onto a regular grid (see
// ct_resample.h). Arithmetic: + - * / sqrt floor round, fixed order (-ffp-contract=off), so the
// voxels are the same bits everywhere.
#include "ct/ct_resample.h"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace splintcore {
namespace ct_detail {

namespace {

constexpr double kDegreesPerRadian = 180.0 / 3.14159265358979323846;

// The in-plane part of the plan: the output origin (the centre of the slices' offsets, rounded
// to whole pixels, so the middle slices move least), the largest correction and the tilt.
void plan_shift(const SliceOffset* offsets, uint32_t count, double pixel_x, double pixel_y,
                ResamplePlan* plan) {
  double lo_x = offsets[0].x, hi_x = lo_x, lo_y = offsets[0].y, hi_y = lo_y;
  for (uint32_t k = 1; k < count; ++k) {
    lo_x = std::min(lo_x, offsets[k].x);
    hi_x = std::max(hi_x, offsets[k].x);
    lo_y = std::min(lo_y, offsets[k].y);
    hi_y = std::max(hi_y, offsets[k].y);
  }
  plan->origin_x = std::round(0.5 * (lo_x + hi_x) / pixel_x) * pixel_x;
  plan->origin_y = std::round(0.5 * (lo_y + hi_y) / pixel_y) * pixel_y;
  for (uint32_t k = 0; k < count; ++k) {
    const double dx = plan->origin_x - offsets[k].x, dy = plan->origin_y - offsets[k].y;
    plan->max_shift_mm = std::max(plan->max_shift_mm, std::sqrt(dx * dx + dy * dy));
  }
  const SliceOffset& last = offsets[count - 1];
  plan->tilt_degrees =
      angle_between(Vec3{last.x, last.y, last.along}, Vec3{0, 0, 1}) * kDegreesPerRadian;
}

// The largest distance of an output slice (at o x spacing) to its nearest input slice.
double largest_offset(const SliceOffset* offsets, uint32_t count, const ResamplePlan& plan) {
  double largest = 0;
  uint32_t a = 0;
  for (uint32_t o = 0; o < plan.nz; ++o) {
    const double z = static_cast<double>(o) * plan.spacing_z;
    while (a + 2 < count && offsets[a + 1].along <= z) ++a;
    const double below = z - offsets[a].along, above = offsets[a + 1].along - z;
    largest = std::max(largest, std::max(0.0, std::min(below, above)));
  }
  return largest;
}

}  // namespace

double allowed_deviation(const CtReadOptions& options, double x) {
  return options.slice_spacing_tolerance_mm > options.slice_spacing_tolerance_relative * x
             ? options.slice_spacing_tolerance_mm
             : options.slice_spacing_tolerance_relative * x;
}

void plan_resampling(const SliceOffset* offsets, uint32_t count, bool uniform, double pixel_x,
                     double pixel_y, const CtReadOptions& options, double* gaps,
                     ResamplePlan* plan) {
  *plan = ResamplePlan{};
  for (uint32_t k = 1; k < count; ++k) {
    const double off = std::sqrt(offsets[k].x * offsets[k].x + offsets[k].y * offsets[k].y);
    if (!(off <= allowed_deviation(options, offsets[k].along))) plan->shift = true;
  }
  if (plan->shift) plan_shift(offsets, count, pixel_x, pixel_y, plan);
  const double span = offsets[count - 1].along;
  if (uniform) {
    plan->nz = count;
    plan->spacing_z = span / static_cast<double>(count - 1);
    return;
  }
  for (uint32_t k = 0; k + 1 < count; ++k) gaps[k] = offsets[k + 1].along - offsets[k].along;
  const uint32_t middle = (count - 2) / 2;
  std::nth_element(gaps, gaps + middle, gaps + (count - 1));
  const double m = gaps[middle];
  plan->median_gap = m;
  const double widest = options.resample_max_gap * m + allowed_deviation(options, m);
  for (uint32_t k = 0; k + 1 < count; ++k) {
    if (!(offsets[k + 1].along - offsets[k].along <= widest)) {
      plan->gap_too_wide = true;
      plan->bad_gap = k;
      return;
    }
  }
  plan->interpolate = true;
  plan->spacing_z = m;
  // Every output slice within the stack (the last one up to the tolerance beyond it). At most
  // resample_max_gap x (count - 1) + 1 slices: the caller checks the limits.
  const double n = std::floor((span + allowed_deviation(options, m)) / m) + 1.0;
  plan->nz = n < 4294967295.0 ? static_cast<uint32_t>(n) : 4294967295u;
  if (plan->nz <= options.max_dimension)
    plan->max_offset_mm = largest_offset(offsets, count, *plan);
}

namespace {

// A shift within kSnap pixels of a whole number is that number: positions rounded to decimal
// strings must not turn a whole-pixel shift into a blend that loses the slice's last row.
constexpr double kSnap = 1.0e-6;

double snapped(double shift) {
  const double whole = std::round(shift);
  return std::fabs(shift - whole) <= kSnap ? whole : shift;
}

}  // namespace

void shift_slice(const int16_t* in, uint32_t nx, uint32_t ny, double sx, double sy, int16_t* out) {
  const double bx = std::floor(snapped(sx)), by = std::floor(snapped(sy));
  const double fx = snapped(sx) - bx, fy = snapped(sy) - by;
  const uint64_t count = uint64_t{nx} * ny;
  // Shifts of more than the slice leave nothing of it.
  if (!(bx > -static_cast<double>(nx) - 1 && bx < static_cast<double>(nx) + 1 &&
        by > -static_cast<double>(ny) - 1 && by < static_cast<double>(ny) + 1)) {
    for (uint64_t v = 0; v < count; ++v) out[v] = kAirHu;
    return;
  }
  const int64_t ix = static_cast<int64_t>(bx), iy = static_cast<int64_t>(by);
  // The last base index with both neighbours inside (one when the fraction is 0).
  const int64_t last_x = static_cast<int64_t>(nx) - (fx > 0 ? 2 : 1);
  const int64_t last_y = static_cast<int64_t>(ny) - (fy > 0 ? 2 : 1);
  const int64_t step_x = fx > 0 ? 1 : 0;
  const int64_t step_y = fy > 0 ? static_cast<int64_t>(nx) : 0;
  for (uint32_t j = 0; j < ny; ++j) {
    int16_t* row = out + uint64_t{j} * nx;
    const int64_t y0 = static_cast<int64_t>(j) + iy;
    if (y0 < 0 || y0 > last_y) {
      for (uint32_t i = 0; i < nx; ++i) row[i] = kAirHu;
      continue;
    }
    const int16_t* src = in + y0 * static_cast<int64_t>(nx);
    for (uint32_t i = 0; i < nx; ++i) {
      const int64_t x0 = static_cast<int64_t>(i) + ix;
      if (x0 < 0 || x0 > last_x) {
        row[i] = kAirHu;
        continue;
      }
      const int16_t* p = src + x0;
      const double top =
          static_cast<double>(p[0]) * (1.0 - fx) + static_cast<double>(p[step_x]) * fx;
      const double bottom = static_cast<double>(p[step_y]) * (1.0 - fx) +
                            static_cast<double>(p[step_y + step_x]) * fx;
      row[i] = static_cast<int16_t>(std::round(top * (1.0 - fy) + bottom * fy));
    }
  }
}

void blend_slices(const int16_t* a, const int16_t* b, uint64_t count, double t, int16_t* out) {
  const double s = 1.0 - t;
  for (uint64_t v = 0; v < count; ++v) {
    out[v] = static_cast<int16_t>(
        std::round(static_cast<double>(a[v]) * s + static_cast<double>(b[v]) * t));
  }
}

int16_t* SliceResampler::target(uint32_t k) const {
  if (plan->shift) return raw;
  if (plan->interpolate) return current;
  return volume + uint64_t{k} * nx * ny;
}

void SliceResampler::place(uint32_t k) {
  const uint64_t n = uint64_t{nx} * ny;
  int16_t* straight = plan->interpolate ? current : volume + k * n;
  if (plan->shift) {
    shift_slice(raw, nx, ny, (plan->origin_x - offsets[k].x) / pixel_x,
                (plan->origin_y - offsets[k].y) / pixel_y, straight);
  }
  if (!plan->interpolate) return;
  const bool last = k + 1 == count;
  while (next_out < plan->nz) {
    const double z = static_cast<double>(next_out) * plan->spacing_z;
    if (!last && z > offsets[k].along) break;
    int16_t* out = volume + next_out * n;
    const double t =
        k == 0 ? 1.0 : (z - offsets[k - 1].along) / (offsets[k].along - offsets[k - 1].along);
    if (t >= 1.0) {
      std::memcpy(out, current, static_cast<size_t>(n * sizeof(int16_t)));
    } else {
      blend_slices(previous, current, n, t, out);
    }
    ++next_out;
  }
  int16_t* swap = previous;
  previous = current;
  current = swap;
}

}  // namespace ct_detail
}  // namespace splintcore
