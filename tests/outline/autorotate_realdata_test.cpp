// Hinge-axis autorotation on the real CBCT dentition (../shared/realdata: 31 closed teeth, 887k
// triangles, in occlusion as scanned; not in the repository, so these tests skip without it):
// with several hinge axes and openings, the angle agrees with the rotated-copy oracle
// (support/autorotate_oracle.h) within 1e-7 rad, and moving jaws and hinge together changes
// nothing.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <string>

#include "splintcore/outline.h"
#include "support/autorotate_oracle.h"
#include "support/frame_moves.h"
#include "support/real_jaws.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

using test::real_jaws;
using test::RealJaws;

// The dentition's frame: z up (the maxilla above), incisors at y = 5, molars near y = 40, the
// arch's middle at x = 54: condyles behind (+y) and above the teeth.
struct Plan {
  Vec3 h0, h1;
  double opening;
};
const Plan kRealPlans[] = {
    {{4, 90, 80}, {104, 90, 80}, 2.0},
    {{6, 85, 75}, {102, 95, 88}, 0.0},
    {{104, 100, 92}, {0, 98, 86}, 1.0},
};

AutorotateReport rotate(const Mesh& upper, const Mesh& lower, const Plan& plan) {
  test::TestArena work{static_cast<size_t>(autorotate_mandible_bound(upper, lower))};
  AutorotateOptions o;
  o.hinge[0] = plan.h0;
  o.hinge[1] = plan.h1;
  o.opening_mm = plan.opening;
  AutorotateReport r;
  const Status s = autorotate_mandible(Context(&work.arena), upper, lower, o, &r);
  EXPECT_TRUE(s.is_ok()) << test::format(s);
  return r;
}

TEST(AutorotateRealData, AgreesWithTheRotatedCopyOracle) {
  const RealJaws& jaws = real_jaws();
  if (!jaws.ok) GTEST_SKIP() << "no real dentition at " << SPLINTCORE_REALDATA_DIR;
  for (const Plan& plan : kRealPlans) {
    const AutorotateReport r = rotate(jaws.jaw[0], jaws.jaw[1], plan);
    test::RotationOracle oracle(jaws.jaw[0], jaws.jaw[1], plan.h0, plan.h1, size_t{512} << 20);
    const double delta = 2e-7;
    const double found = oracle.crossing(r.angle_rad - r.closing_sign * delta,
                                         r.angle_rad + r.closing_sign * delta, plan.opening, 5e-9);
    EXPECT_NEAR(r.angle_rad, found, 1e-7);
    std::printf(
        "real X %.1f: %.12f rad (%.6f deg), oracle %.12f (%d evaluations), start %.6f, "
        "as given %s %.4f mm, %u steps, contact maxilla triangle %u\n",
        plan.opening, r.angle_rad, r.angle_rad * 180 / M_PI, found, oracle.evaluations,
        r.start_angle_rad, r.met_as_given ? "meeting" : "apart", r.gap_as_given, r.steps,
        r.triangle_maxilla);
  }
}

TEST(AutorotateRealData, FrameInvariance) {
  const RealJaws& jaws = real_jaws();
  if (!jaws.ok) GTEST_SKIP() << "no real dentition at " << SPLINTCORE_REALDATA_DIR;
  const Plan& plan = kRealPlans[0];
  const AutorotateReport base = rotate(jaws.jaw[0], jaws.jaw[1], plan);
  std::mt19937_64 rng(26);
  const RigidTransform m = test::random_move(rng);
  test::TestArena store{size_t{128} << 20};
  Mesh moved[2];
  for (int j = 0; j < 2; ++j) {
    moved[j].bind(&store.arena);
    for (const Vec3& v : jaws.jaw[j].vertices) (void)moved[j].vertices.push_back(m.apply_point(v));
    for (const Triangle& t : jaws.jaw[j].triangles) (void)moved[j].triangles.push_back(t);
  }
  const Plan moved_plan{m.apply_point(plan.h0), m.apply_point(plan.h1), plan.opening};
  const AutorotateReport r = rotate(moved[0], moved[1], moved_plan);
  EXPECT_NEAR(r.angle_rad, base.angle_rad, 1e-9);
  EXPECT_NEAR(r.opening, base.opening, 1e-7);
}

}  // namespace
}  // namespace splintcore
