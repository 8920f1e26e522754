// Hinge-axis autorotation (outline.h, autorotate_mandible): the first-contact and opening
// angles of two blocks in closed form (from apart and from interpenetration, both senses);
// on the phantom jaws against an oracle that turns a copy of the mandible and builds a new
// index per evaluation (support/autorotate_oracle.h); frame invariance; the memory bound at
// its exact size; the refusals.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "common/phantom.h"
#include "splintcore/distance.h"
#include "splintcore/outline.h"
#include "splintcore/platform.h"
#include "support/autorotate_oracle.h"
#include "support/frame_moves.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

// A closed box [lo, hi], each face an n x n grid of quads (two triangles each), outward.
void box_mesh(Arena& arena, const Vec3& lo, const Vec3& hi, int n, Mesh* out) {
  out->bind(&arena);
  const Vec3 e = hi - lo;
  // Per face: a corner and two edges (u x v outward).
  const Vec3 faces[6][3] = {{{lo.x, lo.y, lo.z}, {0, e.y, 0}, {e.x, 0, 0}},
                            {{lo.x, lo.y, hi.z}, {e.x, 0, 0}, {0, e.y, 0}},
                            {{lo.x, lo.y, lo.z}, {e.x, 0, 0}, {0, 0, e.z}},
                            {{lo.x, hi.y, lo.z}, {0, 0, e.z}, {e.x, 0, 0}},
                            {{lo.x, lo.y, lo.z}, {0, 0, e.z}, {0, e.y, 0}},
                            {{hi.x, lo.y, lo.z}, {0, e.y, 0}, {0, 0, e.z}}};
  for (const auto& f : faces) {
    const uint32_t base = static_cast<uint32_t>(out->vertices.size());
    for (int j = 0; j <= n; ++j) {
      for (int i = 0; i <= n; ++i) {
        ASSERT_TRUE(out->vertices.push_back(f[0] + f[1] * (static_cast<double>(i) / n) +
                                            f[2] * (static_cast<double>(j) / n)));
      }
    }
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        const uint32_t a = base + static_cast<uint32_t>(j * (n + 1) + i);
        const uint32_t b = a + 1, c = a + static_cast<uint32_t>(n + 1), d = c + 1;
        ASSERT_TRUE(out->triangles.push_back(Triangle{{a, b, d}}));
        ASSERT_TRUE(out->triangles.push_back(Triangle{{a, d, c}}));
      }
    }
  }
}

// The blocks: the maxilla's spans x in [50, 100] (times `side`), z in [-5, 10]; the mandible's
// x in [60, 80] (times `side`), z in [-30, top]; the hinge axis is the y axis.
struct Blocks {
  test::TestArena store{size_t{16} << 20};
  Mesh upper, lower;
  Blocks(double side, double top) {
    const double a = side > 0 ? 50 : -100, b = side > 0 ? 100 : -50;
    const double c = side > 0 ? 60 : -80, d = side > 0 ? 80 : -60;
    box_mesh(store.arena, Vec3{a, -20, -5}, Vec3{b, 20, 10}, 6, &upper);
    box_mesh(store.arena, Vec3{c, -10, -30}, Vec3{d, 10, top}, 6, &lower);
  }
};

AutorotateReport rotate(const Mesh& upper, const Mesh& lower, const Vec3& h0, const Vec3& h1,
                        double opening) {
  test::TestArena work{static_cast<size_t>(autorotate_mandible_bound(upper, lower))};
  AutorotateOptions o;
  o.hinge[0] = h0;
  o.hinge[1] = h1;
  o.opening_mm = opening;
  AutorotateReport r;
  const Status s = autorotate_mandible(Context(&work.arena), upper, lower, o, &r);
  EXPECT_TRUE(s.is_ok()) << test::format(s);
  EXPECT_EQ(work.arena.used(), 0u);
  return r;
}

// From apart: the mandible's far top corner (80, -15) sweeps the circle of radius
// |(80, -15)| about the axis; turned by -alpha (closing: a positive angle about +y lowers
// points at x > 0) it lies at height 80 sin alpha - 15 cos alpha, which meets -5 - X (the
// maxilla's bottom face less the opening): alpha = atan2(15, 80) + asin((-5 - X) / |(80, 15)|).
// Mirrored (x -> -x) the answer is +alpha; with the hinge points swapped (the axis reversed)
// the same.
TEST(Autorotate, BlocksFromApartMatchTheClosedForm) {
  for (double x : {0.0, 2.0}) {
    const double alpha = std::atan2(15.0, 80.0) + std::asin((-5.0 - x) / std::hypot(80.0, 15.0));
    for (double side : {1.0, -1.0}) {
      Blocks blocks(side, -15);
      for (int swap = 0; swap < 2; ++swap) {
        Vec3 h0{0, -50, 0}, h1{0, 50, 0};
        if (swap != 0) std::swap(h0, h1);
        const AutorotateReport r = rotate(blocks.upper, blocks.lower, h0, h1, x);
        const double expected = (swap != 0 ? -1 : 1) * -side * alpha;
        EXPECT_NEAR(r.angle_rad, expected, 1e-9) << "X " << x << " side " << side;
        EXPECT_EQ(r.closing_sign, expected > 0 ? 1 : -1);
        EXPECT_EQ(r.start_angle_rad, 0.0);
        EXPECT_FALSE(r.met_as_given);
        EXPECT_NEAR(r.gap_as_given, 10.0, 1e-12);
        EXPECT_NEAR(r.opening, x, 1e-7);
        EXPECT_GE(r.opening, x);
        EXPECT_LE(r.bracket_rad, 1e-10);
        // The first contact: on the mandible's far top edge, below the maxilla's face.
        const Vec3 corner = r.transform.apply_point(Vec3{side * 80, 0, -15});
        EXPECT_NEAR(r.contact_mandible.x, corner.x, 1e-6);
        EXPECT_NEAR(r.contact_mandible.z, corner.z, 1e-6);
        EXPECT_NEAR(r.contact_maxilla.z, -5.0, 1e-9);
        std::printf(
            "blocks apart X %.0f side %+.0f swap %d: %.12f rad (closed form %.12f), %u steps\n", x,
            side, swap, r.angle_rad, expected, r.steps);
      }
    }
  }
}

// From interpenetration (the mandible's top at z = -2, 3 mm into the maxilla): it opens first
// (a positive angle for x > 0), then closes; the near top corner (60, -2), turned by +beta,
// lies at -60 sin beta - 2 cos beta, which meets -5 - X: beta = asin((5 + X) / |(60, 2)|) -
// atan2(2, 60).
TEST(Autorotate, BlocksFromInterpenetrationMatchTheClosedForm) {
  for (double x : {0.0, 2.0}) {
    const double beta = std::asin((5.0 + x) / std::hypot(60.0, 2.0)) - std::atan2(2.0, 60.0);
    for (double side : {1.0, -1.0}) {
      Blocks blocks(side, -2);
      const AutorotateReport r =
          rotate(blocks.upper, blocks.lower, Vec3{0, -50, 0}, Vec3{0, 50, 0}, x);
      const double expected = side * beta;
      EXPECT_NEAR(r.angle_rad, expected, 1e-9) << "X " << x << " side " << side;
      EXPECT_TRUE(r.met_as_given);
      EXPECT_EQ(r.gap_as_given, 0.0);
      EXPECT_GT(std::fabs(r.start_angle_rad), std::fabs(expected));  // opened past it first
      EXPECT_EQ(r.start_angle_rad > 0, expected > 0);
      EXPECT_NEAR(r.opening, x, 1e-7);
      const Vec3 corner = r.transform.apply_point(Vec3{side * 60, 0, -2});
      EXPECT_NEAR(r.contact_mandible.z, corner.z, 1e-6);
      std::printf(
          "blocks interpenetrating X %.0f side %+.0f: %.12f rad (closed form %.12f), "
          "start %.6f, %u steps\n",
          x, side, r.angle_rad, expected, r.start_angle_rad, r.steps);
    }
  }
}

// Jaws too close at angle 0 but not touching (X = 2, 1 mm apart): opened first as well.
TEST(Autorotate, BlocksNearerThanTheOpeningOpenFirst) {
  Blocks blocks(1, -6);
  const AutorotateReport r = rotate(blocks.upper, blocks.lower, Vec3{0, -50, 0}, Vec3{0, 50, 0}, 2);
  const double beta = std::asin(7.0 / std::hypot(60.0, 6.0)) - std::atan2(6.0, 60.0);
  EXPECT_FALSE(r.met_as_given);
  EXPECT_NEAR(r.gap_as_given, 1.0, 1e-12);
  EXPECT_NEAR(r.angle_rad, beta, 1e-9);
}

TEST(Autorotate, Refusals) {
  Blocks blocks(1, -15);
  test::TestArena work{size_t{16} << 20};
  AutorotateOptions o;
  o.hinge[0] = Vec3{0, -50, 0};
  o.hinge[1] = Vec3{0, 50, 0};
  AutorotateReport r;
  const auto refused = [&](const Mesh& up, const Mesh& low, const AutorotateOptions& opt,
                           const char* needle) {
    const Status s = autorotate_mandible(Context(&work.arena), up, low, opt, &r);
    EXPECT_EQ(s.code(), StatusCode::kInvalidArgument) << test::format(s);
    EXPECT_NE(test::format(s).find(needle), std::string::npos) << test::format(s);
    EXPECT_EQ(work.arena.used(), 0u);
  };
  AutorotateOptions bad = o;
  bad.opening_mm = 10.5;
  refused(blocks.upper, blocks.lower, bad, "opening must be in [0, 10]");
  bad = o;
  bad.hinge[1] = Vec3{0, -49.5, 0};
  refused(blocks.upper, blocks.lower, bad, "hinge points are 0.5 mm apart");
  bad = o;
  bad.hinge[0].x = std::nan("");
  refused(blocks.upper, blocks.lower, bad, "hinge point 1 is not finite");
  bad = o;  // a vertical axis: the mandible swings sideways
  bad.hinge[0] = Vec3{0, 0, -50};
  bad.hinge[1] = Vec3{0, 0, 50};
  refused(blocks.upper, blocks.lower, bad, "closing sense cannot be told");
  {
    // Far apart: 30 degrees of closing leave them apart.
    Mesh far;
    box_mesh(blocks.store.arena, Vec3{50, -20, 200}, Vec3{100, 20, 220}, 2, &far);
    refused(far, blocks.lower, o, "leaves the jaws");
  }
  {
    // A mandible across the axis inside a slab: it meets whichever way.
    Mesh slab, across;
    box_mesh(blocks.store.arena, Vec3{-60, -20, -5}, Vec3{140, 20, 10}, 2, &slab);
    box_mesh(blocks.store.arena, Vec3{-20, -10, -30}, Vec3{80, 10, -2}, 2, &across);
    refused(slab, across, o, "still meet");
  }
  Mesh empty(&blocks.store.arena);
  const Status s = autorotate_mandible(Context(&work.arena), blocks.upper, empty, o, &r);
  EXPECT_EQ(s.code(), StatusCode::kInvalidMesh) << test::format(s);
}

// ---------------------------------------------------------------------------------------------
// The phantom jaws.

struct PhantomPair {
  test::TestArena store{size_t{64} << 20};
  Mesh jaw[2];
  PhantomPair(uint64_t triangles, double drop) {
    for (int j = 0; j < 2; ++j) {
      phantom::JawMesh m;
      phantom::PhantomOptions po;
      po.target_triangles = triangles;
      EXPECT_TRUE(
          phantom::make_jaw(j == 0 ? phantom::Jaw::kMaxilla : phantom::Jaw::kMandible, po, &m)
              .is_ok());
      jaw[j].bind(&store.arena);
      for (const Vec3& v : m.vertices) {
        (void)jaw[j].vertices.push_back(j == 1 ? Vec3{v.x, v.y, v.z - drop} : v);
      }
      for (const Triangle& t : m.triangles) (void)jaw[j].triangles.push_back(t);
    }
  }
};

struct Plan {
  Vec3 h0, h1;
  double opening;
  double drop;  // the mandible moved down first (mm): apart as given
};

// The phantom's arch runs round +y (incisors at y = 42, the last molars near y = -7), the
// maxilla above: condyles behind (-y) and above the teeth.
const Plan kPhantomPlans[] = {
    {{-50, -55, 25}, {50, -55, 25}, 0.0, 0}, {{-45, -70, 35}, {55, -60, 20}, 1.5, 0},
    {{50, -50, 15}, {-50, -65, 30}, 3.0, 0}, {{-50, -55, 25}, {50, -55, 25}, 1.0, 4},
    {{-48, -60, 10}, {52, -62, 12}, 0.0, 5},
};

TEST(Autorotate, PhantomAgreesWithTheRotatedCopyOracle) {
  PhantomPair p(20000, 0);
  PhantomPair dropped4(20000, 4), dropped5(20000, 5);
  for (const Plan& plan : kPhantomPlans) {
    const PhantomPair& jaws = plan.drop == 0 ? p : (plan.drop == 4 ? dropped4 : dropped5);
    const AutorotateReport r = rotate(jaws.jaw[0], jaws.jaw[1], plan.h0, plan.h1, plan.opening);
    EXPECT_EQ(r.met_as_given, plan.drop == 0);
    EXPECT_LE(std::fabs(r.angle_rad), 30 * M_PI / 180);
    test::RotationOracle oracle(jaws.jaw[0], jaws.jaw[1], plan.h0, plan.h1, size_t{48} << 20);
    const double delta = 1e-6;
    const double open = r.angle_rad - r.closing_sign * delta;
    const double closed = r.angle_rad + r.closing_sign * delta;
    const double found = oracle.crossing(open, closed, plan.opening, 1e-9);
    EXPECT_NEAR(r.angle_rad, found, 1e-7);
    // The first crossing: more than X apart all the way from the start (a sanity check at a
    // few angles: what certifies it is the advancement's bound).
    for (int k = 1; k < 8; ++k) {
      const double a = r.start_angle_rad + (r.angle_rad - r.start_angle_rad) * k / 8.0;
      EXPECT_GT(oracle.distance(a), plan.opening) << a;
    }
    EXPECT_NEAR(oracle.distance(r.angle_rad), r.opening, 1e-9);
    std::printf(
        "phantom X %.1f drop %.0f: %.12f rad (%.6f deg), oracle %.12f, start %.6f, "
        "%u steps, lever %.2f mm\n",
        plan.opening, plan.drop, r.angle_rad, r.angle_rad * 180 / M_PI, found, r.start_angle_rad,
        r.steps, r.lever_mm);
  }
}

// Both jaws and the hinge moved by a rigid motion: the same angle.
TEST(Autorotate, PhantomFrameInvariance) {
  PhantomPair p(20000, 0);
  std::mt19937_64 rng(32);
  for (const Plan& plan : {kPhantomPlans[0], kPhantomPlans[1]}) {
    const AutorotateReport base = rotate(p.jaw[0], p.jaw[1], plan.h0, plan.h1, plan.opening);
    for (int k = 0; k < 3; ++k) {
      const RigidTransform m = test::random_move(rng);
      test::TestArena store{size_t{8} << 20};
      Mesh moved[2];
      for (int j = 0; j < 2; ++j) {
        moved[j].bind(&store.arena);
        for (const Vec3& v : p.jaw[j].vertices) (void)moved[j].vertices.push_back(m.apply_point(v));
        for (const Triangle& t : p.jaw[j].triangles) (void)moved[j].triangles.push_back(t);
      }
      const AutorotateReport r =
          rotate(moved[0], moved[1], m.apply_point(plan.h0), m.apply_point(plan.h1), plan.opening);
      EXPECT_NEAR(r.angle_rad, base.angle_rad, 1e-9);
      EXPECT_EQ(r.closing_sign, base.closing_sign);
      EXPECT_NEAR(r.opening, base.opening, 1e-7);
    }
  }
}

// The same report, bit for bit: the angle, the opening, the transform, the contact and its
// triangles, the steps.
void expect_same_report(const AutorotateReport& r, const AutorotateReport& base) {
  EXPECT_EQ(std::memcmp(&r.angle_rad, &base.angle_rad, sizeof(double)), 0)
      << r.angle_rad << " " << base.angle_rad;
  EXPECT_EQ(std::memcmp(&r.opening, &base.opening, sizeof(double)), 0);
  EXPECT_EQ(std::memcmp(&r.transform, &base.transform, sizeof(RigidTransform)), 0);
  EXPECT_EQ(r.contact_maxilla, base.contact_maxilla);
  EXPECT_EQ(r.contact_mandible, base.contact_mandible);
  EXPECT_EQ(r.triangle_maxilla, base.triangle_maxilla);
  EXPECT_EQ(r.triangle_mandible, base.triangle_mandible);
  EXPECT_EQ(r.steps, base.steps);
}

// autorotate_mandible_indexed over the caller's indexes (built with other options, or refit
// from another mesh's tree as a plan refits them) gives autorotate_mandible's report bit for bit,
// in autorotate_mandible_indexed_bound(); an empty jaw is refused.
TEST(Autorotate, IndexedGivesTheSameBits) {
  PhantomPair p(20000, 0);
  for (const Plan& plan : kPhantomPlans) {
    PhantomPair q(20000, plan.drop);
    const AutorotateReport base = rotate(q.jaw[0], q.jaw[1], plan.h0, plan.h1, plan.opening);
    test::TestArena t(size_t{32} << 20);
    // The maxilla's index built with the triangles' boxes and leaves of 4; the mandible's
    // refit from the undropped mandible's tree.
    DistanceIndexOptions boxed;
    boxed.pairs_only = true;
    boxed.leaf_size = 4;
    DistanceIndex upper, shape, lower;
    SPLINTCORE_ASSERT_OK(build_distance_index(Context(&t.arena), q.jaw[0], boxed, &upper));
    SPLINTCORE_ASSERT_OK(
        build_distance_index(Context(&t.arena), p.jaw[1], autorotate_index_options(), &shape));
    SPLINTCORE_ASSERT_OK(refit_distance_index(Context(&t.arena), shape, q.jaw[1], &lower));
    AutorotateOptions o;
    o.hinge[0] = plan.h0;
    o.hinge[1] = plan.h1;
    o.opening_mm = plan.opening;
    AutorotateReport r;
    test::TestArena work{static_cast<size_t>(autorotate_mandible_indexed_bound())};
    SPLINTCORE_ASSERT_OK(autorotate_mandible_indexed(Context(&work.arena), upper, lower, o, &r));
    EXPECT_EQ(work.arena.used(), 0u);
    expect_same_report(r, base);
  }
  test::TestArena t(size_t{8} << 20);
  Mesh empty;
  DistanceIndex upper, none;
  SPLINTCORE_ASSERT_OK(
      build_distance_index(Context(&t.arena), p.jaw[0], autorotate_index_options(), &upper));
  SPLINTCORE_ASSERT_OK(
      build_distance_index(Context(&t.arena), empty, autorotate_index_options(), &none));
  AutorotateOptions o;
  o.hinge[0] = kPhantomPlans[0].h0;
  o.hinge[1] = kPhantomPlans[0].h1;
  AutorotateReport r;
  const Status s = autorotate_mandible_indexed(Context(&t.arena), upper, none, o, &r);
  EXPECT_EQ(s.code(), StatusCode::kInvalidMesh);
  EXPECT_NE(std::string(s.message()).find("the mandible is empty"), std::string::npos)
      << s.message();
}

// On an executor of more than one thread the rotation's pair searches (meeting, distance,
// collecting) are split over tasks: the report is the serial one bit for bit, at 2 and 3
// threads, in autorotate_mandible_bound(), for every plan (from occlusion and from apart).
TEST(Autorotate, SameBitsAtEveryThreadCount) {
  PhantomPair p(20000, 0), dropped4(20000, 4), dropped5(20000, 5);
  ThreadExecutor two(2), three(3);
  for (const Plan& plan : kPhantomPlans) {
    const PhantomPair& jaws = plan.drop == 0 ? p : (plan.drop == 4 ? dropped4 : dropped5);
    const AutorotateReport base = rotate(jaws.jaw[0], jaws.jaw[1], plan.h0, plan.h1, plan.opening);
    AutorotateOptions o;
    o.hinge[0] = plan.h0;
    o.hinge[1] = plan.h1;
    o.opening_mm = plan.opening;
    for (const ThreadExecutor* pool : {&two, &three}) {
      test::TestArena work{
          static_cast<size_t>(autorotate_mandible_bound(jaws.jaw[0], jaws.jaw[1]))};
      AutorotateReport r;
      SPLINTCORE_ASSERT_OK(autorotate_mandible(Context(&work.arena, &pool->executor(), nullptr),
                                               jaws.jaw[0], jaws.jaw[1], o, &r));
      EXPECT_EQ(work.arena.used(), 0u);
      expect_same_report(r, base);
    }
  }
}

// The memory contract: autorotate_mandible runs in exactly autorotate_mandible_bound() bytes,
// and in exactly its measured need (one byte less fails cleanly, the arena as it was).
TEST(Autorotate, RunsInItsBoundAndInItsMeasuredNeed) {
  PhantomPair p(20000, 0);
  AutorotateOptions o;
  o.hinge[0] = kPhantomPlans[0].h0;
  o.hinge[1] = kPhantomPlans[0].h1;
  o.opening_mm = 2;
  const uint64_t bound = autorotate_mandible_bound(p.jaw[0], p.jaw[1]);
  uint64_t need = 0;
  AutorotateReport first;
  {
    test::TestArena exact{static_cast<size_t>(bound)};
    SPLINTCORE_ASSERT_OK(autorotate_mandible(Context(&exact.arena), p.jaw[0], p.jaw[1], o, &first));
    need = exact.arena.high_water();
    std::printf("autorotate_mandible: bound %llu, need %llu (%.2f)\n",
                static_cast<unsigned long long>(bound), static_cast<unsigned long long>(need),
                static_cast<double>(need) / static_cast<double>(bound));
  }
  {
    test::TestArena exact{static_cast<size_t>(need)};
    AutorotateReport r;
    SPLINTCORE_EXPECT_OK(autorotate_mandible(Context(&exact.arena), p.jaw[0], p.jaw[1], o, &r));
    EXPECT_EQ(r.angle_rad, first.angle_rad);  // the same bits
  }
  {
    test::TestArena short_by_one{static_cast<size_t>(need - 1)};
    AutorotateReport r;
    const Status s = autorotate_mandible(Context(&short_by_one.arena), p.jaw[0], p.jaw[1], o, &r);
    EXPECT_EQ(s.code(), StatusCode::kArenaExhausted) << test::format(s);
    EXPECT_EQ(short_by_one.arena.used(), 0u);
  }
}

}  // namespace
}  // namespace splintcore
