// splintcore geometry, internal: the first stage of orient2d (J. R. Shewchuk, "Adaptive
// precision floating-point arithmetic and fast robust geometric predicates", 1997, section
// 4.3: the rounded determinant and its error bound ccwerrboundA), for orient2d() in
// predicates.cpp. The mesh check's flat-triangle test (src/mesh/check.cpp) uses the bound on
// its own products (two triangles at a time), skipping collinear3d when it already shows the
// x-y orientation nonzero.
#ifndef SPLINTCORE_SRC_GEOMETRY_ORIENT2D_STAGE_A_H
#define SPLINTCORE_SRC_GEOMETRY_ORIENT2D_STAGE_A_H

namespace splintcore {
namespace detail {

constexpr double kCcwErrBoundA = (3.0 + 16.0 * 0x1p-53) * 0x1p-53;

struct Orient2dStageA {
  double det;     // the rounded determinant: orient2d's answer when `certain`
  double detsum;  // the error bound's scale (the adaptive stage's input) when not `certain`
  bool certain;
};

inline Orient2dStageA orient2d_stage_a(double ax, double ay, double bx, double by, double cx,
                                       double cy) {
  const double detleft = (ax - cx) * (by - cy);
  const double detright = (ay - cy) * (bx - cx);
  const double det = detleft - detright;
  double detsum = 0.0;
  // When the two products do not have the same sign, no cancellation: det has the right sign.
  // (A rounded product is zero only when one factor is exactly zero, inside the range.)
  if (detleft > 0.0) {
    if (detright <= 0.0) return Orient2dStageA{det, 0.0, true};
    detsum = detleft + detright;
  } else if (detleft < 0.0) {
    if (detright >= 0.0) return Orient2dStageA{det, 0.0, true};
    detsum = -detleft - detright;
  } else {
    return Orient2dStageA{det, 0.0, true};
  }
  // Strict comparison (the paper has >=): when the bound is subnormal it may be rounded down
  // onto the error itself, and a tie could then hide an exact zero.
  const double errbound = kCcwErrBoundA * detsum;
  return Orient2dStageA{det, detsum, det > errbound || -det > errbound};
}

}  // namespace detail
}  // namespace splintcore

#endif  // SPLINTCORE_SRC_GEOMETRY_ORIENT2D_STAGE_A_H
