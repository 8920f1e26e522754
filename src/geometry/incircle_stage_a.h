// splintcore geometry, internal: the first stage of incircle (J. R. Shewchuk, "Adaptive
// precision floating-point arithmetic and fast robust geometric predicates", 1997, section
// 4.2: the rounded determinant of the differences and its error bound iccerrboundA), shared by
// incircle() in predicates.cpp and the CDT's inlined test (src/boolean/cdt.cpp), so that the
// CDT's filter is the predicate's own first stage, operation for operation.
#ifndef SPLINTCORE_SRC_GEOMETRY_INCIRCLE_STAGE_A_H
#define SPLINTCORE_SRC_GEOMETRY_INCIRCLE_STAGE_A_H

namespace splintcore {
namespace detail {

constexpr double kIncircleErrBoundA = (10.0 + 96.0 * 0x1p-53) * 0x1p-53;

struct IncircleStageA {
  double det;        // the determinant from the rounded differences, rounded
  double permanent;  // the same terms in absolute value (the error bound's scale)
  // True when det's sign is certain (then det is what incircle() returns). Strict comparison
  // (the paper has >=): a subnormal bound may be rounded onto the error itself.
  bool certain() const {
    const double errbound = kIncircleErrBoundA * permanent;
    return det > errbound || -det > errbound;
  }
};

// > 0 when d lies inside the circle through a, b, c (counter-clockwise), as a first stage.
inline IncircleStageA incircle_stage_a(double ax, double ay, double bx, double by, double cx,
                                       double cy, double dx, double dy) {
  const auto magnitude = [](double v) { return v < 0.0 ? -v : v; };
  const double adx = ax - dx;
  const double bdx = bx - dx;
  const double cdx = cx - dx;
  const double ady = ay - dy;
  const double bdy = by - dy;
  const double cdy = cy - dy;

  const double bdxcdy = bdx * cdy;
  const double cdxbdy = cdx * bdy;
  const double alift = adx * adx + ady * ady;
  const double cdxady = cdx * ady;
  const double adxcdy = adx * cdy;
  const double blift = bdx * bdx + bdy * bdy;
  const double adxbdy = adx * bdy;
  const double bdxady = bdx * ady;
  const double clift = cdx * cdx + cdy * cdy;

  IncircleStageA s;
  s.det = alift * (bdxcdy - cdxbdy) + blift * (cdxady - adxcdy) + clift * (adxbdy - bdxady);
  s.permanent = (magnitude(bdxcdy) + magnitude(cdxbdy)) * alift +
                (magnitude(cdxady) + magnitude(adxcdy)) * blift +
                (magnitude(adxbdy) + magnitude(bdxady)) * clift;
  return s;
}

}  // namespace detail
}  // namespace splintcore

#endif  // SPLINTCORE_SRC_GEOMETRY_INCIRCLE_STAGE_A_H
