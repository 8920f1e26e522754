// Checks of the automatic outline shared by its tests: the arch frame from what an outline
// reports, and a limited outline (distal_ends) against the whole one (test code only).
#ifndef SPLINTCORE_TESTS_OUTLINE_CHECKS_H
#define SPLINTCORE_TESTS_OUTLINE_CHECKS_H

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <utility>
#include <vector>

#include "splintcore/geometry.h"
#include "splintcore/outline.h"

namespace splintcore {
namespace test {

// The arch frame of an outline, from what it reports (no code of the library's arch): the
// centre line in the occlusal plane (e1 = anterior, e2 = n x e1) and a point's place s along it
// (the nearest point of the polyline, its end segments going on as rays).
struct ArchFrame {
  Vec3 n, e1, e2;
  std::vector<double> x, y, s;
  explicit ArchFrame(const Outline& o)
      : n(o.report.occlusal_normal), e1(o.report.anterior), e2(cross(n, e1)) {
    for (const Vec3& p : o.arch) {
      x.push_back(dot(p, e1));
      y.push_back(dot(p, e2));
      s.push_back(s.empty() ? 0.0
                            : s.back() + std::hypot(x.back() - x[x.size() - 2],
                                                    y.back() - y[y.size() - 2]));
    }
  }
  double along(const Vec3& p) const {
    const double px = dot(p, e1), py = dot(p, e2);
    double best = HUGE_VAL, at = 0;
    for (size_t k = 0; k + 1 < x.size(); ++k) {
      const double dx = x[k + 1] - x[k], dy = y[k + 1] - y[k];
      double t = ((px - x[k]) * dx + (py - y[k]) * dy) / (dx * dx + dy * dy);
      if (k > 0) t = std::max(t, 0.0);
      if (k + 2 < x.size()) t = std::min(t, 1.0);
      const double qx = x[k] + t * dx - px, qy = y[k] + t * dy - py;
      if (qx * qx + qy * qy < best) {
        best = qx * qx + qy * qy;
        at = s[k] + t * (s[k + 1] - s[k]);
      }
    }
    return at;
  }
};

inline bool same_pick(const Pick& a, const Pick& b) {
  return std::memcmp(&a, &b, sizeof(Pick)) == 0;
}

// The limited outline against the whole one: no pick beyond a limit (in the arch frame,
// tolerance 0), the first and last pick at the limits, the picks between them the whole
// outline's, bit for bit and in a row, the arch itself unchanged. Returns the picks cut.
inline size_t check_limited(const Outline& whole, const Outline& cut, const Vec3 ends[2]) {
  EXPECT_TRUE(cut.report.distal_limited);
  EXPECT_EQ(cut.arch.size(), whole.arch.size());
  for (size_t i = 0; i < cut.arch.size() && i < whole.arch.size(); ++i) {
    EXPECT_EQ(cut.arch[i], whole.arch[i]) << i;
  }
  const ArchFrame frame(cut);
  double lo = frame.along(ends[0]), hi = frame.along(ends[1]);
  if (lo > hi) std::swap(lo, hi);
  const size_t n = cut.upper.size();
  EXPECT_GE(n, 4u);
  EXPECT_EQ(cut.lower.size(), n);
  for (size_t i = 0; i < n; ++i) {
    for (const Pick* p : {&cut.upper[i], &cut.lower[i]}) {
      const double s = frame.along(p->position);
      EXPECT_GE(s, lo) << "pick " << i << " lies beyond the limit by " << lo - s << " mm";
      EXPECT_LE(s, hi) << "pick " << i << " lies beyond the limit by " << s - hi << " mm";
    }
  }
  EXPECT_NEAR(frame.along(cut.upper[0].position), lo, 1e-5);
  EXPECT_NEAR(frame.along(cut.upper[n - 1].position), hi, 1e-5);
  // The whole outline reaches past both limits (else the test would show nothing).
  EXPECT_LT(frame.along(whole.upper[0].position), lo);
  EXPECT_GT(frame.along(whole.upper[whole.upper.size() - 1].position), hi);
  size_t j = 0;
  while (j < whole.upper.size() && !same_pick(whole.upper[j], cut.upper[1])) ++j;
  EXPECT_LT(j, whole.upper.size()) << "the second pick is none of the whole outline's";
  for (size_t i = 1; i + 1 < n && j + i - 1 < whole.upper.size(); ++i) {
    EXPECT_TRUE(same_pick(cut.upper[i], whole.upper[j + i - 1])) << i;
    EXPECT_TRUE(same_pick(cut.lower[i], whole.lower[j + i - 1])) << i;
  }
  return whole.upper.size() - n;
}

}  // namespace test
}  // namespace splintcore

#endif  // SPLINTCORE_TESTS_OUTLINE_CHECKS_H
