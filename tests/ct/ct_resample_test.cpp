// The resampling kernels of src/ct/ct_resample.h on small exact cases: in-plane shifts in x and
// y, whole and fractional, partly and wholly outside the slice; the plan's slice count clamped
// when a stack would need more than 2^32 slices.
#include <gtest/gtest.h>

#include <limits>
#include <vector>

#include "ct/ct_resample.h"

namespace splintcore {
namespace {

using ct_detail::kAirHu;

// A 4 x 3 slice with values 10 j + i.
std::vector<int16_t> ramp_slice() {
  std::vector<int16_t> s;
  for (int j = 0; j < 3; ++j) {
    for (int i = 0; i < 4; ++i) s.push_back(static_cast<int16_t>(10 * j + i));
  }
  return s;
}

std::vector<int16_t> shifted(double sx, double sy) {
  const std::vector<int16_t> in = ramp_slice();
  std::vector<int16_t> out(in.size());
  ct_detail::shift_slice(in.data(), 4, 3, sx, sy, out.data());
  return out;
}

TEST(CtResample, ShiftSliceWholeAndFractionalInXAndY) {
  const int16_t a = kAirHu;
  // Half a column right: the mean of neighbours (halves away from zero); the last column
  // has no right neighbour.
  EXPECT_EQ(shifted(0.5, 0), (std::vector<int16_t>{1, 2, 3, a, 11, 12, 13, a, 21, 22, 23, a}));
  // One and a quarter columns left: the first two columns come from outside.
  EXPECT_EQ(shifted(-1.25, 0), (std::vector<int16_t>{a, a, 1, 2, a, a, 11, 12, a, a, 21, 22}));
  // Whole rows (within 1e-6 of whole: snapped, the last row kept).
  EXPECT_EQ(shifted(0, 1 - 1e-9),
            (std::vector<int16_t>{10, 11, 12, 13, 20, 21, 22, 23, a, a, a, a}));
  EXPECT_EQ(shifted(0, -1), (std::vector<int16_t>{a, a, a, a, 0, 1, 2, 3, 10, 11, 12, 13}));
  // Both at once, a quarter each way: bilinear.
  EXPECT_EQ(shifted(0.25, 0.25)[0], 3);  // 0.75 (0.75 0 + 0.25 1) + 0.25 (0.75 10 + 0.25 11)
  // More than the slice either way, or not a number: all air.
  for (const double s : {-9.0, 9.0}) {
    EXPECT_EQ(shifted(s, 0), std::vector<int16_t>(12, a));
    EXPECT_EQ(shifted(0, s), std::vector<int16_t>(12, a));
  }
  EXPECT_EQ(shifted(std::numeric_limits<double>::quiet_NaN(), 0), std::vector<int16_t>(12, a));
}

TEST(CtResample, PlanClampsAnAbsurdSliceCount) {
  // Gaps of 1 micrometre and one of 2.5 (uneven), over 10 km: more than 2^32 slices.
  std::vector<ct_detail::SliceOffset> offsets(4);
  offsets[1].along = 1e-3;
  offsets[2].along = 2e-3;
  offsets[3].along = 1e7;
  CtReadOptions o;
  o.resample_max_gap = 1e12;
  std::vector<double> gaps(4);
  ct_detail::ResamplePlan plan;
  ct_detail::plan_resampling(offsets.data(), 4, false, 1, 1, o, gaps.data(), &plan);
  EXPECT_FALSE(plan.gap_too_wide);
  EXPECT_TRUE(plan.interpolate);
  EXPECT_EQ(plan.nz, 4294967295u);
  EXPECT_EQ(plan.max_offset_mm, 0.0);  // not computed beyond max_dimension
}

}  // namespace
}  // namespace splintcore
