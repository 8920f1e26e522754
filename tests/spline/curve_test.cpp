#include <cmath>

#include "splintcore/spline.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

TEST(CatmullRom, InterpolatesTheEndsExactly) {
  const Vec3 p0{-1, 0.3, 0}, p1{0, 0, 0}, p2{1.25, 0.5, 0.1}, p3{2, 2, 0};
  EXPECT_EQ(catmull_rom_point(p0, p1, p2, p3, 0.0), p1);
  EXPECT_EQ(catmull_rom_point(p0, p1, p2, p3, 1.0), p2);
}

TEST(CatmullRom, CollinearPointsStayOnTheLineWithoutOvershoot) {
  // Very uneven spacing: uniform Catmull-Rom overshoots here; centripetal must not.
  const Vec3 p0{0, 0, 0}, p1{1, 0, 0}, p2{1.05, 0, 0}, p3{9, 0, 0};
  double previous = p1.x;
  for (int i = 1; i <= 100; ++i) {
    Vec3 q = catmull_rom_point(p0, p1, p2, p3, i / 100.0);
    EXPECT_EQ(q.y, 0.0);
    EXPECT_GE(q.x, previous - 1e-15) << i;  // monotone: no loop back
    EXPECT_LE(q.x, p2.x + 1e-15) << i;      // no overshoot past p2
    previous = q.x;
  }
}

TEST(CatmullRom, FollowsACircleClosely) {
  const double r = 30.0;
  auto on_circle = [&](double a) { return Vec3{r * std::cos(a), r * std::sin(a), 0}; };
  const double step = 0.25;  // 14 degrees between picks, like teeth on an arch
  double worst = 0;
  for (int i = 0; i <= 50; ++i) {
    Vec3 q = catmull_rom_point(on_circle(-step), on_circle(0), on_circle(step), on_circle(2 * step),
                               i / 50.0);
    worst = std::max(worst, std::fabs(length(q) - r));
  }
  EXPECT_LT(worst, 0.01);  // mm, on a 30 mm radius
}

}  // namespace
}  // namespace splintcore
