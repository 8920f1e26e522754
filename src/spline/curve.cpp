// Centripetal Catmull-Rom segments, evaluated with the Barry-Goldman pyramid (Barry and
// Goldman, "A recursive evaluation algorithm for a class of Catmull-Rom splines", SIGGRAPH
// 1988), with knot intervals |P(i+1) - P(i)|^(1/2) (Yuksel, Schaefer and Keyser, CAD 2011).
#include <cmath>

#include "splintcore/spline.h"

namespace splintcore {

namespace {
// |b - a|^(1/2), the centripetal knot interval: sqrt(sqrt(d.d)), exact-rounded operations only.
inline double knot_interval(const Vec3& a, const Vec3& b) {
  return std::sqrt(std::sqrt(length_squared(b - a)));
}

inline Vec3 lerp_knots(const Vec3& a, const Vec3& b, double ta, double tb, double t) {
  const double span = tb - ta;
  return a * ((tb - t) / span) + b * ((t - ta) / span);
}
}  // namespace

CatmullRomSegment catmull_rom_segment(const Vec3& p0, const Vec3& p1, const Vec3& p2,
                                      const Vec3& p3) {
  CatmullRomSegment s;
  s.p[0] = p0;
  s.p[1] = p1;
  s.p[2] = p2;
  s.p[3] = p3;
  s.t1 = 0.0 + knot_interval(p0, p1);
  s.t2 = s.t1 + knot_interval(p1, p2);
  s.t3 = s.t2 + knot_interval(p2, p3);
  return s;
}

Vec3 catmull_rom_point(const Vec3& p0, const Vec3& p1, const Vec3& p2, const Vec3& p3, double u) {
  return catmull_rom_point(catmull_rom_segment(p0, p1, p2, p3), u);
}

Vec3 catmull_rom_point(const CatmullRomSegment& s, double u) {
  // The ends are returned exactly, so sections at picks sit exactly on the lines' ends.
  const Vec3& p0 = s.p[0];
  const Vec3& p1 = s.p[1];
  const Vec3& p2 = s.p[2];
  const Vec3& p3 = s.p[3];
  if (u <= 0.0) return p1;
  if (u >= 1.0) return p2;
  const double t0 = 0.0;
  const double t1 = s.t1, t2 = s.t2, t3 = s.t3;
  const double t = t1 + (t2 - t1) * u;
  const Vec3 a1 = lerp_knots(p0, p1, t0, t1, t);
  const Vec3 a2 = lerp_knots(p1, p2, t1, t2, t);
  const Vec3 a3 = lerp_knots(p2, p3, t2, t3, t);
  const Vec3 b1 = lerp_knots(a1, a2, t0, t2, t);
  const Vec3 b2 = lerp_knots(a2, a3, t1, t3, t);
  return lerp_knots(b1, b2, t1, t2, t);
}

}  // namespace splintcore
