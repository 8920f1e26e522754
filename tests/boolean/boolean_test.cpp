// Tests of the Boolean (src/boolean/boolean_run.h and its stage files): analytic shapes in generic
// position, the volume identities every corefinement must keep (|A - B| + |A * B| = |A|, |A + B| =
// |A| + |B| - |A * B|), closed manifold outward output without self-intersections, input vertices
// copied bit for bit and intersection points on both surfaces, degenerate contacts reported (not
// guessed), determinism and arena exhaustion.
//
// Random streams are std::mt19937_64 with fixed seeds.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "splintcore/boolean.h"
#include "splintcore/distance.h"
#include "splintcore/mesh.h"
#include "splintcore/platform.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

using test::TestArena;

constexpr double kPi = 3.14159265358979323846;

RigidTransform rotation(double ax, double ay, double az, const Vec3& t) {
  // Rz * Ry * Rx, then translate.
  const double cx = std::cos(ax), sx = std::sin(ax), cy = std::cos(ay), sy = std::sin(ay),
               cz = std::cos(az), sz = std::sin(az);
  RigidTransform x;
  x.r[0][0] = cz * cy;
  x.r[0][1] = cz * sy * sx - sz * cx;
  x.r[0][2] = cz * sy * cx + sz * sx;
  x.r[1][0] = sz * cy;
  x.r[1][1] = sz * sy * sx + cz * cx;
  x.r[1][2] = sz * sy * cx - cz * sx;
  x.r[2][0] = -sy;
  x.r[2][1] = cy * sx;
  x.r[2][2] = cy * cx;
  x.t = t;
  return x;
}

Mesh box_mesh(Arena& arena, const Vec3& lo, const Vec3& hi, const RigidTransform& x) {
  Mesh m(&arena);
  for (int i = 0; i < 8; ++i) {
    Vec3 p{(i & 1) ? hi.x : lo.x, (i & 2) ? hi.y : lo.y, (i & 4) ? hi.z : lo.z};
    EXPECT_TRUE(m.vertices.push_back(x.apply_point(p)));
  }
  const uint32_t f[12][3] = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}, {0, 1, 5}, {0, 5, 4},
                             {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
  for (const auto& t : f) EXPECT_TRUE(m.triangles.push_back(Triangle{{t[0], t[1], t[2]}}));
  return m;
}

Mesh sphere_mesh(Arena& arena, double r, int nlat, int nlon, const RigidTransform& x) {
  Mesh m(&arena);
  EXPECT_TRUE(m.vertices.push_back(x.apply_point(Vec3{0, 0, r})));
  for (int i = 1; i < nlat; ++i) {
    const double th = kPi * i / nlat;
    for (int j = 0; j < nlon; ++j) {
      const double ph = 2 * kPi * j / nlon;
      EXPECT_TRUE(m.vertices.push_back(x.apply_point(Vec3{
          r * std::sin(th) * std::cos(ph), r * std::sin(th) * std::sin(ph), r * std::cos(th)})));
    }
  }
  const uint32_t south = static_cast<uint32_t>(m.vertices.size());
  EXPECT_TRUE(m.vertices.push_back(x.apply_point(Vec3{0, 0, -r})));
  auto ring = [&](int i, int j) {
    return static_cast<uint32_t>(1 + (i - 1) * nlon + ((j % nlon) + nlon) % nlon);
  };
  for (int j = 0; j < nlon; ++j) {
    EXPECT_TRUE(m.triangles.push_back(Triangle{{0, ring(1, j), ring(1, j + 1)}}));
  }
  for (int i = 1; i + 1 < nlat; ++i) {
    for (int j = 0; j < nlon; ++j) {
      EXPECT_TRUE(
          m.triangles.push_back(Triangle{{ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)}}));
      EXPECT_TRUE(
          m.triangles.push_back(Triangle{{ring(i, j), ring(i + 1, j + 1), ring(i, j + 1)}}));
    }
  }
  for (int j = 0; j < nlon; ++j) {
    EXPECT_TRUE(m.triangles.push_back(Triangle{{south, ring(nlat - 1, j + 1), ring(nlat - 1, j)}}));
  }
  return m;
}

// Appends b's shells to a (a second shell in one mesh).
void append_mesh(const Mesh& b, Mesh* a) {
  const uint32_t off = static_cast<uint32_t>(a->vertices.size());
  for (const Vec3& v : b.vertices) EXPECT_TRUE(a->vertices.push_back(v));
  for (const Triangle& t : b.triangles) {
    EXPECT_TRUE(a->triangles.push_back(Triangle{{t.v[0] + off, t.v[1] + off, t.v[2] + off}}));
  }
}

MeshReport report_of(Arena& arena, const Mesh& m) {
  MeshReport r;
  EXPECT_TRUE(check_mesh(Context(&arena), m, &r).is_ok());
  return r;
}

// The tests work on double meshes: no float32 rounding unless a test asks for it.
BooleanOptions opts(BooleanOp op) {
  BooleanOptions o;
  o.op = op;
  o.float32_output = false;
  return o;
}

struct Result {
  Status status;
  double volume = 0;
  uint64_t triangles = 0;
  BooleanStats stats;
};

// Runs op and checks what every successful result must be.
Result run_op(Arena& arena, const Mesh& a, const Mesh& b, BooleanOp op, bool expect_nonempty) {
  ArenaScope scope(arena);
  Result res;
  Mesh out;
  res.status = mesh_boolean(Context(&arena), a, b, opts(op), &out, &res.stats);
  if (!res.status.is_ok()) return res;
  res.triangles = out.triangles.size();
  if (out.triangles.size() == 0) {
    EXPECT_FALSE(expect_nonempty) << boolean_op_name(op);
    return res;
  }
  const MeshReport r = report_of(arena, out);
  if (op != BooleanOp::kUnion) {
    EXPECT_TRUE(r.is_valid_solid())
        << boolean_op_name(op) << ": " << test::format(require_valid_solid(r));
  }
  res.volume = r.volume;
  SelfIntersectionReport si;
  EXPECT_TRUE(find_self_intersections(Context(&arena), out, 1, &si).is_ok());
  EXPECT_FALSE(si.self_intersecting())
      << boolean_op_name(op) << " pair " << si.first_a << " " << si.first_b;
  return res;
}

TEST(BooleanTest, SphereInsideCubeMakesACavity) {
  TestArena ta;
  Arena& arena = ta.arena;
  Mesh a = box_mesh(arena, {0, 0, 0}, {2, 2, 2}, RigidTransform{});
  Mesh b = sphere_mesh(arena, 0.5, 12, 24, rotation(0.1, 0.2, 0.3, {1.01, 0.98, 1.03}));
  const double vb = mesh_volume(b);
  Result d = run_op(arena, a, b, BooleanOp::kDifference, true);
  ASSERT_TRUE(d.status.is_ok()) << test::format(d.status);
  EXPECT_EQ(d.stats.intersecting_pairs, 0u);
  EXPECT_NEAR(d.volume, 8.0 - vb, 1e-12);
  EXPECT_EQ(d.triangles, a.triangles.size() + b.triangles.size());
  Result i = run_op(arena, a, b, BooleanOp::kIntersection, true);
  ASSERT_TRUE(i.status.is_ok()) << test::format(i.status);
  EXPECT_NEAR(i.volume, vb, 1e-12);
}

TEST(BooleanTest, CubeMinusSphereCrossingAFace) {
  TestArena ta;
  Arena& arena = ta.arena;
  Mesh a = box_mesh(arena, {0, 0, 0}, {1, 1, 1}, RigidTransform{});
  Mesh b = sphere_mesh(arena, 0.45, 16, 32, rotation(0.3, -0.2, 0.7, {0.52, 0.47, 0.93}));
  const double va = 1.0, vb = mesh_volume(b);
  Result d = run_op(arena, a, b, BooleanOp::kDifference, true);
  ASSERT_TRUE(d.status.is_ok()) << test::format(d.status);
  Result i = run_op(arena, a, b, BooleanOp::kIntersection, true);
  ASSERT_TRUE(i.status.is_ok()) << test::format(i.status);
  Result u = run_op(arena, a, b, BooleanOp::kUnion, true);
  ASSERT_TRUE(u.status.is_ok()) << test::format(u.status);
  EXPECT_GT(d.stats.intersecting_pairs, 0u);
  EXPECT_NEAR((d.volume + i.volume) / va, 1.0, 1e-12);
  EXPECT_NEAR((u.volume + i.volume) / (va + vb), 1.0, 1e-12);
  EXPECT_GT(i.volume, 0.2 * vb);
  EXPECT_LT(i.volume, 0.8 * vb);
}

// The work bound: a run that would test more candidate pairs than max_candidate_pairs stops
// with kLimitExceeded naming the bound, the output empty and the arena as it was; the same
// bound with room to spare changes nothing.
TEST(BooleanTest, CandidatePairsBeyondTheBoundAreRefused) {
  TestArena ta;
  Arena& arena = ta.arena;
  Mesh a = box_mesh(arena, {0, 0, 0}, {1, 1, 1}, RigidTransform{});
  Mesh b = sphere_mesh(arena, 0.45, 16, 32, rotation(0.3, -0.2, 0.7, {0.52, 0.47, 0.93}));
  BooleanOptions o = opts(BooleanOp::kDifference);
  BooleanStats st;
  Mesh full;
  SPLINTCORE_ASSERT_OK(mesh_boolean(Context(&arena), a, b, o, &full, &st));
  const uint64_t needed = st.candidate_pairs;
  ASSERT_GT(needed, 10u);
  o.max_candidate_pairs = needed / 2;
  Mesh out;
  const size_t used = arena.used();
  const Status s = mesh_boolean(Context(&arena), a, b, o, &out, &st);
  EXPECT_EQ(s.code(), StatusCode::kLimitExceeded) << test::format(s);
  EXPECT_NE(std::string(s.message()).find("max_candidate_pairs"), std::string::npos);
  EXPECT_TRUE(out.triangles.empty());
  EXPECT_EQ(arena.used(), used);
  o.max_candidate_pairs = needed;
  Mesh again;
  SPLINTCORE_ASSERT_OK(mesh_boolean(Context(&arena), a, b, o, &again, &st));
  EXPECT_EQ(again.triangles.size(), full.triangles.size());
}

TEST(BooleanTest, DisjointAndSwallowed) {
  TestArena ta;
  Arena& arena = ta.arena;
  Mesh a = box_mesh(arena, {0, 0, 0}, {1, 1, 1}, RigidTransform{});
  Mesh far = sphere_mesh(arena, 0.3, 8, 16, rotation(0, 0, 0, {5, 5, 5}));
  Result d = run_op(arena, a, far, BooleanOp::kDifference, true);
  ASSERT_TRUE(d.status.is_ok()) << test::format(d.status);
  EXPECT_NEAR(d.volume, 1.0, 1e-15);
  EXPECT_EQ(d.stats.near_b_triangles, 0u);
  Result i = run_op(arena, a, far, BooleanOp::kIntersection, false);
  ASSERT_TRUE(i.status.is_ok());
  EXPECT_EQ(i.triangles, 0u);
  // A inside B: nothing is left of A - B.
  Mesh big = sphere_mesh(arena, 3.0, 8, 16, rotation(0.1, 0.1, 0.1, {0.5, 0.5, 0.5}));
  Result s = run_op(arena, a, big, BooleanOp::kDifference, false);
  ASSERT_TRUE(s.status.is_ok()) << test::format(s.status);
  EXPECT_EQ(s.triangles, 0u);
  EXPECT_GE(s.stats.winding_queries, 1u);
}

TEST(BooleanTest, TwoShellsInB) {
  TestArena ta;
  Arena& arena = ta.arena;
  Mesh a = box_mesh(arena, {0, 0, 0}, {2, 1, 1}, rotation(0.02, 0.01, 0.03, {0, 0, 0}));
  Mesh b = sphere_mesh(arena, 0.4, 10, 20, rotation(0.3, 0.2, 0.1, {0.4, 0.5, 0.95}));
  Mesh b2 = sphere_mesh(arena, 0.35, 9, 18, rotation(0.1, 0.5, 0.2, {1.5, 0.45, 0.1}));
  Mesh both(&arena);
  append_mesh(b, &both);
  append_mesh(b2, &both);
  const double va = mesh_volume(a);
  Result d = run_op(arena, a, both, BooleanOp::kDifference, true);
  ASSERT_TRUE(d.status.is_ok()) << test::format(d.status);
  Result i = run_op(arena, a, both, BooleanOp::kIntersection, true);
  ASSERT_TRUE(i.status.is_ok()) << test::format(i.status);
  EXPECT_NEAR((d.volume + i.volume) / va, 1.0, 1e-12);
  // The same as subtracting one after the other.
  Result d1 = run_op(arena, a, b, BooleanOp::kIntersection, true);
  Result d2 = run_op(arena, a, b2, BooleanOp::kIntersection, true);
  ASSERT_TRUE(d1.status.is_ok() && d2.status.is_ok());
  EXPECT_NEAR(i.volume, d1.volume + d2.volume, 1e-12);
}

// B's triangles near A are copied out when they are half of B or less, and B is used as it is
// when more are near: either way the result's bytes are those of the near shell alone (the
// copy renumbers in B's order; far shells before it only offset its ids).
TEST(BooleanTest, FarShellsOfBChangeNoByteWhetherOrNotNearBIsCopied) {
  TestArena ta;
  Arena& arena = ta.arena;
  Mesh a = box_mesh(arena, {0, 0, 0}, {1, 1, 1}, RigidTransform{});
  Mesh tooth = sphere_mesh(arena, 0.45, 16, 32, rotation(0.3, -0.2, 0.7, {0.52, 0.47, 0.93}));
  const Mesh far_big = sphere_mesh(arena, 0.45, 16, 32, rotation(0, 0, 0, {5, 5, 5}));
  const Mesh far_small = sphere_mesh(arena, 0.3, 6, 12, rotation(0, 0, 0, {-4, 5, 0}));
  Mesh mostly_far(&arena);  // its near triangles copied
  append_mesh(far_big, &mostly_far);
  append_mesh(tooth, &mostly_far);
  append_mesh(sphere_mesh(arena, 0.45, 16, 32, rotation(0, 0, 0, {0.5, 4, 0.5})), &mostly_far);
  append_mesh(sphere_mesh(arena, 0.45, 16, 32, rotation(0, 0, 0, {4, 0.5, 0.5})), &mostly_far);
  Mesh mostly_near(&arena);  // used as it is, the tooth's ids offset
  append_mesh(far_small, &mostly_near);
  append_mesh(tooth, &mostly_near);
  ASSERT_LT(4 * far_small.triangles.size(), tooth.triangles.size());
  std::string hash[3];
  uint64_t near[3] = {};
  const Mesh* bs[3] = {&tooth, &mostly_far, &mostly_near};
  for (int k = 0; k < 3; ++k) {
    ArenaScope scope(arena);
    Mesh out;
    BooleanStats st;
    SPLINTCORE_ASSERT_OK(
        mesh_boolean(Context(&arena), a, *bs[k], opts(BooleanOp::kDifference), &out, &st));
    near[k] = st.near_b_triangles;
    hash[k] = test::mesh_sha256(out);
  }
  // The tooth: more than half of it near A's box, a quarter of mostly_far.
  EXPECT_GT(2 * near[0], tooth.triangles.size());
  EXPECT_LE(2 * near[1], mostly_far.triangles.size());
  EXPECT_EQ(near[1], near[0]);
  EXPECT_EQ(near[2], near[0]);
  EXPECT_EQ(hash[1], hash[0]);
  EXPECT_EQ(hash[2], hash[0]);
}

// One edge of A (the box's edge along x) crosses the surfaces of many small spheres of B: 40
// points on one edge of A take the two-pass numbering of the intersection points (runs of
// one edge longer than 32), 20 the insertion path; both give valid results with the volume
// identity.
TEST(BooleanTest, AnEdgeCrossingManyTrianglesOfB) {
  TestArena ta;
  Arena& arena = ta.arena;
  Mesh a = box_mesh(arena, {0, 0, 0}, {10, 1, 1}, RigidTransform{});
  for (int count : {10, 20}) {
    ArenaScope scope(arena);
    Mesh b(&arena);
    for (int i = 0; i < count; ++i) {
      Mesh s =
          sphere_mesh(arena, 0.2, 6, 8, rotation(0.1 * i, 0.2, 0.3, {0.4 + 0.45 * i, 0.01, 0.02}));
      append_mesh(s, &b);
    }
    Result d = run_op(arena, a, b, BooleanOp::kDifference, true);
    ASSERT_TRUE(d.status.is_ok()) << count << ": " << test::format(d.status);
    Result i = run_op(arena, a, b, BooleanOp::kIntersection, true);
    ASSERT_TRUE(i.status.is_ok()) << count << ": " << test::format(i.status);
    EXPECT_EQ(d.stats.attempts, 1u) << count;
    EXPECT_GE(d.stats.intersection_points, 4u * count) << count;
    EXPECT_NEAR((d.volume + i.volume) / 10.0, 1.0, 1e-12) << count;
    EXPECT_GT(i.volume, 0.0) << count;
  }
}

TEST(BooleanTest, CubeMinusRotatedCube) {
  TestArena ta;
  Arena& arena = ta.arena;
  Mesh a = box_mesh(arena, {0, 0, 0}, {1, 1, 1}, RigidTransform{});
  Mesh b = box_mesh(arena, {-0.5, -0.5, -0.5}, {0.5, 0.5, 0.5},
                    rotation(0.4, 0.5, 0.6, {0.9, 0.85, 0.95}));
  const double vb = mesh_volume(b);
  Result d = run_op(arena, a, b, BooleanOp::kDifference, true);
  ASSERT_TRUE(d.status.is_ok()) << test::format(d.status);
  Result i = run_op(arena, a, b, BooleanOp::kIntersection, true);
  ASSERT_TRUE(i.status.is_ok()) << test::format(i.status);
  Result u = run_op(arena, a, b, BooleanOp::kUnion, true);
  ASSERT_TRUE(u.status.is_ok()) << test::format(u.status);
  EXPECT_NEAR(d.volume + i.volume, 1.0, 1e-12);
  EXPECT_NEAR(u.volume + i.volume, 1.0 + vb, 1e-12);
}

// The cut triangles counted per operand: a slab through a cube. The slab's faces z = 0.5 and
// z = 1.5 (B's triangles 0 to 3, its first among them) cross the cube's four side faces (A's
// triangles 4 to 11); nothing else crosses. B's triangle 0 is the first triangle after A's,
// where the count passes from A to B.
TEST(BooleanTest, CutTrianglesAreCountedPerOperand) {
  TestArena ta;
  Arena& arena = ta.arena;
  const Mesh a = box_mesh(arena, {0, 0, 0}, {2, 2, 2}, RigidTransform{});
  const Mesh b = box_mesh(arena, {-1, -1, 0.5}, {3.5, 3, 1.5}, RigidTransform{});
  for (BooleanOp op : {BooleanOp::kDifference, BooleanOp::kUnion, BooleanOp::kIntersection}) {
    const Result r = run_op(arena, a, b, op, true);
    ASSERT_TRUE(r.status.is_ok()) << test::format(r.status);
    EXPECT_EQ(r.stats.cut_triangles_a, 8u) << boolean_op_name(op);
    EXPECT_EQ(r.stats.cut_triangles_b, 4u) << boolean_op_name(op);
  }
}

TEST(BooleanTest, CoplanarContactIsExact) {
  TestArena ta;
  Arena& arena = ta.arena;
  Mesh a = box_mesh(arena, {0, 0, 0}, {1, 1, 1}, RigidTransform{});
  // Shares the face z = 1 (coplanar overlap): resolved exactly, without a nudge.
  Mesh b = box_mesh(arena, {0.25, 0.25, 0.5}, {0.75, 0.75, 1.0}, RigidTransform{});
  const double expect[3] = {0.875, 1.0, 0.125};  // difference, union, intersection
  const BooleanOp ops[3] = {BooleanOp::kDifference, BooleanOp::kUnion, BooleanOp::kIntersection};
  for (int k = 0; k < 3; ++k) {
    ArenaScope scope(arena);
    Mesh out;
    BooleanOptions o = opts(ops[k]);
    o.max_nudges = 0;
    BooleanStats st;
    SPLINTCORE_ASSERT_OK(mesh_boolean(Context(&arena), a, b, o, &out, &st));
    EXPECT_EQ(st.attempts, 1u);
    EXPECT_GT(st.degenerate_pairs, 0u);
    const MeshReport r = report_of(arena, out);
    EXPECT_TRUE(r.is_valid_solid()) << boolean_op_name(ops[k]);
    EXPECT_EQ(r.volume, expect[k]) << boolean_op_name(ops[k]);
  }
  // The union of two boxes that touch along one edge only is not an edge-manifold solid: with
  // max_nudges = 0 that is reported (naming the result's problem), with nudges A moves by a few
  // nanometres and the boxes overlap or part.
  Mesh c = box_mesh(arena, {1, 1, 0}, {2, 2, 1}, RigidTransform{});
  {
    ArenaScope scope(arena);
    Mesh out;
    BooleanOptions o = opts(BooleanOp::kUnion);
    o.max_nudges = 0;
    Status s = mesh_boolean(Context(&arena), a, c, o, &out, nullptr);
    ASSERT_FALSE(s.is_ok());
    EXPECT_EQ(s.code(), StatusCode::kUnsupported) << test::format(s);
  }
  Result u = run_op(arena, a, c, BooleanOp::kUnion, true);
  ASSERT_TRUE(u.status.is_ok()) << test::format(u.status);
  EXPECT_GT(u.stats.attempts, 1u);
  EXPECT_LT(length(u.stats.nudge), 1e-3);  // under 1 um
  EXPECT_NEAR(u.volume, 2.0, 1e-4);
}

TEST(BooleanTest, OutputVerticesAreInputVerticesOrOnBothSurfaces) {
  TestArena ta;
  Arena& arena = ta.arena;
  Mesh a = box_mesh(arena, {0, 0, 0}, {1, 1, 1}, rotation(0.05, 0.1, 0.15, {0, 0, 0}));
  Mesh b = sphere_mesh(arena, 0.6, 14, 28, rotation(0.3, 0.2, 0.1, {0.9, 0.4, 0.6}));
  Mesh out;
  BooleanStats st;
  SPLINTCORE_ASSERT_OK(
      mesh_boolean(Context(&arena), a, b, opts(BooleanOp::kDifference), &out, &st));
  DistanceIndex ia, ib;
  SPLINTCORE_ASSERT_OK(build_distance_index(Context(&arena), a, DistanceIndexOptions{}, &ia));
  SPLINTCORE_ASSERT_OK(build_distance_index(Context(&arena), b, DistanceIndexOptions{}, &ib));
  uint64_t on_both = 0;
  for (const Vec3& v : out.vertices) {
    bool input = false;
    for (const Vec3& x : a.vertices) input = input || (x == v);
    for (const Vec3& x : b.vertices) input = input || (x == v);
    if (input) continue;
    ClosestPoint ca, cb;
    ASSERT_TRUE(closest_point(ia, v, &ca));
    ASSERT_TRUE(closest_point(ib, v, &cb));
    EXPECT_LT(ca.distance, 1e-15);
    EXPECT_LT(cb.distance, 1e-15);
    ++on_both;
  }
  EXPECT_EQ(on_both, st.intersection_points);
}

// Many random rigid placements of a sphere and a box against a box: the identities hold on all.
TEST(BooleanTest, RandomPlacementsKeepTheVolumeIdentities) {
  TestArena ta;
  Arena& arena = ta.arena;
  std::mt19937_64 rng(20261121);
  std::uniform_real_distribution<double> angle(0, 2 * kPi), pos(-0.2, 1.2), rad(0.2, 0.6);
  Mesh a = box_mesh(arena, {0, 0, 0}, {1, 1, 1}, rotation(0.01, 0.02, 0.03, {0, 0, 0}));
  const double va = mesh_volume(a);
  int done = 0, unsupported = 0;
  for (int c = 0; c < 150; ++c) {
    ArenaScope scope(arena);
    const RigidTransform x =
        rotation(angle(rng), angle(rng), angle(rng), {pos(rng), pos(rng), pos(rng)});
    const double r = rad(rng);
    Mesh b = (c % 2 == 0) ? sphere_mesh(arena, r, 6 + c % 7, 10 + c % 9, x)
                          : box_mesh(arena, {-r, -r, -r}, {r, r, 1.5 * r}, x);
    const double vb = mesh_volume(b);
    Result d = run_op(arena, a, b, BooleanOp::kDifference, false);
    Result i = run_op(arena, a, b, BooleanOp::kIntersection, false);
    Result u = run_op(arena, a, b, BooleanOp::kUnion, true);
    if (!d.status.is_ok() || !i.status.is_ok() || !u.status.is_ok()) {
      EXPECT_EQ(d.status.code(), StatusCode::kUnsupported) << c << test::format(d.status);
      ++unsupported;
      continue;
    }
    EXPECT_NEAR((d.volume + i.volume) / va, 1.0, 1e-9) << "case " << c;
    EXPECT_NEAR((u.volume + i.volume) / (va + vb), 1.0, 1e-9) << "case " << c;
    ++done;
  }
  EXPECT_EQ(unsupported, 0);
  EXPECT_EQ(done, 150);
}

TEST(BooleanTest, SameBytesEveryRun) {
  TestArena ta;
  Arena& arena = ta.arena;
  Mesh a = box_mesh(arena, {0, 0, 0}, {1, 1, 1}, RigidTransform{});
  Mesh b = sphere_mesh(arena, 0.45, 16, 32, rotation(0.3, -0.2, 0.7, {0.52, 0.47, 0.93}));
  std::string first;
  for (int run = 0; run < 2; ++run) {
    ArenaScope scope(arena);
    Mesh out;
    SPLINTCORE_ASSERT_OK(
        mesh_boolean(Context(&arena), a, b, opts(BooleanOp::kDifference), &out, nullptr));
    const std::string h = test::mesh_sha256(out);
    if (run == 0)
      first = h;
    else
      EXPECT_EQ(h, first);
  }
}

TEST(BooleanTest, ArenaExhaustionIsCleanAtEveryCap) {
  TestArena ta;
  Arena& arena = ta.arena;
  Mesh a = box_mesh(arena, {0, 0, 0}, {1, 1, 1}, RigidTransform{});
  Mesh b = sphere_mesh(arena, 0.45, 6, 10, rotation(0.3, -0.2, 0.7, {0.52, 0.47, 0.93}));
  size_t need = 0;
  std::string want;
  {
    std::vector<unsigned char> big(size_t{8} << 20);
    Arena probe(big.data(), big.size());
    Mesh out;
    SPLINTCORE_ASSERT_OK(
        mesh_boolean(Context(&probe), a, b, opts(BooleanOp::kDifference), &out, nullptr));
    need = probe.high_water();
    want = test::mesh_sha256(out);
  }
  // Below its ample peak a run fails cleanly, or (its final check in slabs, its hits in
  // batches) gives the same bytes; once it works, every larger cap works.
  const test::CapsTried c = test::expect_clean_or_same(
      test::caps_below(need, need / 300 + 1), want, [&](Arena& small, Mesh* out) {
        return mesh_boolean(Context(&small), a, b, opts(BooleanOp::kDifference), out, nullptr);
      });
  std::vector<unsigned char> buf(need);
  Arena exact(buf.data(), need);
  Mesh out;
  SPLINTCORE_EXPECT_OK(
      mesh_boolean(Context(&exact), a, b, opts(BooleanOp::kDifference), &out, nullptr));
  EXPECT_GT(c.failed, 100);
}

TEST(BooleanTest, RejectsOpenA) {
  TestArena ta;
  Arena& arena = ta.arena;
  Mesh a = box_mesh(arena, {0, 0, 0}, {1, 1, 1}, RigidTransform{});
  a.triangles.pop_back();
  Mesh b = sphere_mesh(arena, 0.45, 6, 10, rotation(0.3, -0.2, 0.7, {0.52, 0.47, 0.93}));
  Mesh out;
  Status s = mesh_boolean(Context(&arena), a, b, opts(BooleanOp::kDifference), &out, nullptr);
  EXPECT_EQ(s.code(), StatusCode::kInvalidMesh);
}

}  // namespace
}  // namespace splintcore

namespace splintcore {
namespace {

TEST(BooleanTest, EmptyBLeavesAAndHostileBIsNamed) {
  test::TestArena ta;
  Arena& arena = ta.arena;
  Mesh a = box_mesh(arena, {0, 0, 0}, {1, 1, 1}, RigidTransform{});
  Mesh empty(&arena);
  Result d = run_op(arena, a, empty, BooleanOp::kDifference, true);
  ASSERT_TRUE(d.status.is_ok()) << test::format(d.status);
  EXPECT_EQ(d.triangles, 12u);
  EXPECT_NEAR(d.volume, 1.0, 1e-15);
  // A NaN vertex in a triangle near A.
  Mesh b = sphere_mesh(arena, 0.45, 6, 10, rotation(0.3, -0.2, 0.7, {0.52, 0.47, 0.93}));
  b.vertices[3].x = std::nan("");
  {
    ArenaScope scope(arena);
    Mesh out;
    Status s = mesh_boolean(Context(&arena), a, b, opts(BooleanOp::kDifference), &out, nullptr);
    EXPECT_EQ(s.code(), StatusCode::kNonFinite) << test::format(s);
    EXPECT_NE(std::string(s.message()).find("of B"), std::string::npos);
  }
  // An index out of range.
  b.vertices[3].x = 0.5;
  b.triangles[5].v[1] = 100000;
  {
    ArenaScope scope(arena);
    Mesh out;
    Status s = mesh_boolean(Context(&arena), a, b, opts(BooleanOp::kDifference), &out, nullptr);
    EXPECT_EQ(s.code(), StatusCode::kInvalidMesh) << test::format(s);
    EXPECT_EQ(s.index(), 5u);
  }
  // Double B with float32 output: refused (B's vertices are kept bit for bit).
  b.triangles[5].v[1] = b.triangles[5].v[0] == 0 ? 1 : 0;
  Mesh c = sphere_mesh(arena, 0.45, 6, 10, rotation(0.3, -0.2, 0.7, {0.52, 0.47, 0.93}));
  {
    ArenaScope scope(arena);
    Mesh out;
    BooleanOptions o;
    Status s = mesh_boolean(Context(&arena), a, c, o, &out, nullptr);
    EXPECT_EQ(s.code(), StatusCode::kInvalidArgument) << test::format(s);
  }
  // With float32 output, A (which is rounded to float32 as it is moved into place) with a
  // corner beyond float32 range: refused as such, in every operation, nothing kept.
  Mesh far = box_mesh(arena, {0, 0, 0}, {1, 1, 1}, RigidTransform{});
  for (Vec3& p : far.vertices) {
    if (p.x > 0.5 && p.y > 0.5 && p.z > 0.5) p.x = 4e38;
  }
  Mesh small = box_mesh(arena, {0.25, 0.25, 0.25}, {0.75, 0.75, 0.75}, RigidTransform{});
  for (BooleanOp op : {BooleanOp::kDifference, BooleanOp::kUnion, BooleanOp::kIntersection}) {
    const size_t used = arena.used();
    Mesh out;
    BooleanOptions o;
    o.op = op;
    Status s = mesh_boolean(Context(&arena), far, small, o, &out, nullptr);
    EXPECT_EQ(s.code(), StatusCode::kLimitExceeded) << test::format(s);
    EXPECT_NE(std::string(s.message()).find("A has a coordinate beyond float32 range"),
              std::string::npos)
        << test::format(s);
    EXPECT_EQ(arena.used(), used);
    EXPECT_TRUE(out.triangles.empty());
  }
}

// A contact the predicates are not proved exact for (a coordinate of magnitude under 2^-300,
// here 1e-100, in a triangle of B lying in A's top face) is not decided: kUnsupported naming
// the pair and the range; with nudges A moves off the contact, and then B's triangle, cut,
// is refused by the triangulation's own range (2^-200 .. 2^200): kUnsupported still, named,
// nothing kept either way.
TEST(BooleanTest, ACoordinateBelowTheExactRangeIsRefusedByName) {
  test::TestArena ta;
  Arena& arena = ta.arena;
  const Mesh a = box_mesh(arena, {0, 0, 0}, {1, 1, 1}, RigidTransform{});
  const Mesh b = box_mesh(arena, {1e-100, 0.25, 0.5}, {0.5, 0.75, 1}, RigidTransform{});
  BooleanOptions o = opts(BooleanOp::kDifference);
  for (uint32_t nudges : {0u, 8u}) {
    o.max_nudges = nudges;
    const size_t used = arena.used();
    Mesh out;
    const Status s = mesh_boolean(Context(&arena), a, b, o, &out, nullptr);
    EXPECT_EQ(s.code(), StatusCode::kUnsupported) << test::format(s);
    const char* want = nudges == 0 ? "of B not decided: a coordinate is outside the exact "
                                     "predicates' range (0, or 2^-300 .. 2^330 in magnitude)"
                                   : "not within [2^-200, 2^200] in magnitude";
    EXPECT_NE(std::string(s.message()).find(want), std::string::npos) << test::format(s);
    EXPECT_TRUE(out.triangles.empty());
    EXPECT_EQ(arena.used(), used);
  }
}

// Inputs the Boolean cannot decide are refused, nothing kept: A with two vertices at one point
// (two boxes meeting at a corner, each with its own vertex there) and a vertex of B exactly on
// it; B with a zero-area triangle (a closed box whose vertical edge is split at a
// midpoint on one side and glued by a sliver) across A's face.
TEST(BooleanTest, CoincidentVerticesOfAAndADegenerateTriangleOfBAreRefused) {
  TestArena ta;
  Arena& arena = ta.arena;
  Mesh a = box_mesh(arena, {0, 0, 0}, {1, 1, 1}, RigidTransform{});
  const Mesh upper = box_mesh(arena, {1, 1, 1}, {2, 2, 2}, RigidTransform{});
  for (const Vec3& v : upper.vertices) ASSERT_TRUE(a.vertices.push_back(v));
  for (const Triangle& t : upper.triangles) {
    ASSERT_TRUE(a.triangles.push_back(Triangle{{t.v[0] + 8, t.v[1] + 8, t.v[2] + 8}}));
  }
  const Mesh b = box_mesh(arena, {0.5, 0.5, 0.5}, {1, 1, 1}, RigidTransform{});
  const size_t top = arena.used();
  // (Refused by the result's check: the two corners make the result cross itself there.)
  Result r = run_op(arena, a, b, BooleanOp::kDifference, true);
  EXPECT_FALSE(r.status.is_ok());
  EXPECT_NE(std::string(r.status.message()).find("self-intersects"), std::string::npos)
      << test::format(r.status);
  EXPECT_EQ(arena.used(), top);

  const Mesh unit = box_mesh(arena, {0, 0, 0}, {1, 1, 1}, RigidTransform{});
  Mesh sliver = box_mesh(arena, {0.3, 0.3, 0.3}, {0.7, 0.7, 1.3}, RigidTransform{});
  ASSERT_TRUE(sliver.vertices.push_back(Vec3{0.3, 0.3, 0.8}));  // 8, on the edge 0 - 4
  ASSERT_EQ(sliver.triangles[8].v[1], 4u);                      // {0, 4, 6}, the face x = 0.3
  sliver.triangles[8] = Triangle{{0, 8, 6}};
  ASSERT_TRUE(sliver.triangles.push_back(Triangle{{8, 4, 6}}));
  ASSERT_TRUE(sliver.triangles.push_back(Triangle{{4, 8, 0}}));  // zero area: 4, 8, 0 on a line
  const MeshReport closed = report_of(arena, sliver);
  EXPECT_EQ(closed.boundary_edges + closed.nonmanifold_edges, 0u);
  r = run_op(arena, unit, sliver, BooleanOp::kDifference, true);
  EXPECT_EQ(r.status.code(), StatusCode::kInvalidMesh) << test::format(r.status);
  EXPECT_NE(std::string(r.status.message()).find("is degenerate (zero area) and meets A"),
            std::string::npos)
      << test::format(r.status);
  EXPECT_EQ(r.status.index(), 13u);
}

// The result check (a faster edge pairing first, check_closed_oriented only for the error):
// an open B is fine for the difference when its border lies outside A, but the union keeps
// that border, and the error names the first boundary edge as check_closed_oriented does.
TEST(BooleanTest, ResultCheckNamesTheOpenEdgeOfAUnion) {
  TestArena ta;
  Arena& arena = ta.arena;
  Mesh a = box_mesh(arena, {0, 0, 0}, {1, 1, 1}, RigidTransform{});
  // A sphere through A's top face; its north cap (above z = 1.3) is outside A.
  Mesh b = sphere_mesh(arena, 0.45, 6, 10, RigidTransform::translation({0.52, 0.47, 0.93}));
  ASSERT_GT(b.vertices[b.triangles[0].v[1]].z, 1.2);
  b.triangles[0] = b.triangles[b.triangles.size() - 1];
  b.triangles.pop_back();
  const Result d = run_op(arena, a, b, BooleanOp::kDifference, true);
  ASSERT_TRUE(d.status.is_ok()) << test::format(d.status);
  EXPECT_GT(d.volume, 0.5);
  Mesh out;
  ArenaScope scope(arena);
  const Status u = mesh_boolean(Context(&arena), a, b, opts(BooleanOp::kUnion), &out, nullptr);
  EXPECT_EQ(u.code(), StatusCode::kInvalidMesh) << test::format(u);
  EXPECT_NE(std::string(u.message()).find("union result: mesh is not closed: a boundary edge"),
            std::string::npos)
      << u.message();
  EXPECT_NE(u.index(), kNoPosition);
  // The same B made whole again: the union passes the check.
  Mesh whole = sphere_mesh(arena, 0.45, 6, 10, RigidTransform::translation({0.52, 0.47, 0.93}));
  const Result w = run_op(arena, a, whole, BooleanOp::kUnion, true);
  ASSERT_TRUE(w.status.is_ok()) << test::format(w.status);
  EXPECT_GT(w.volume, 1.0);
}

// A solid that crosses itself (closed, edge-manifold and oriented, so check_mesh calls it
// valid: a cube [0, 2]^3 whose corner (2, 2, 2) is pulled through the bottom to (1.5, 1.5,
// -1)) against a box. The runs fail as they did (a cut that cannot be re-triangulated, an
// inside/outside that does not agree), but the error now names the operand that crosses
// itself: A in every operation, B in the union (kInvalidMesh, at A's or B's first crossing
// triangle); before, each was kUnsupported "nearly degenerate contact". A B that crosses
// itself in the difference or the intersection may do so away from A: that error stands.
TEST(BooleanTest, AnOperandCrossingItselfIsNamedWhenTheRunFails) {
  TestArena ta;
  Arena& arena = ta.arena;
  Mesh crossing = box_mesh(arena, {0, 0, 0}, {2, 2, 2}, RigidTransform{});
  crossing.vertices[7] = Vec3{1.5, 1.5, -1};
  SelfIntersectionReport si;
  SPLINTCORE_ASSERT_OK(find_self_intersections(Context(&arena), crossing, 1, &si));
  ASSERT_TRUE(si.self_intersecting());
  const Mesh cube = box_mesh(arena, {0.5, 0.5, -0.5}, {1.25, 1.25, 1.5}, RigidTransform{});
  for (const BooleanOp op : {BooleanOp::kDifference, BooleanOp::kUnion, BooleanOp::kIntersection}) {
    for (const bool swap : {false, true}) {
      for (const bool f32 : {false, true}) {
        SCOPED_TRACE(std::string(boolean_op_name(op)) + (swap ? " swapped" : "") +
                     (f32 ? " float32" : ""));
        Mesh out;
        BooleanOptions o = opts(op);
        o.float32_output = f32;
        const Arena::Marker before = arena.mark();
        const Status s = mesh_boolean(Context(&arena), swap ? cube : crossing,
                                      swap ? crossing : cube, o, &out, nullptr);
        EXPECT_EQ(arena.mark().offset, before.offset);  // as it was, after the extra check too
        const std::string m = s.message();
        if (!swap || op == BooleanOp::kUnion) {
          EXPECT_EQ(s.code(), StatusCode::kInvalidMesh) << m;
          const std::string who = swap ? "B" : "A";
          EXPECT_NE(
              m.find(": " + who + " crosses itself (its triangles " + std::to_string(si.first_a) +
                     " and " + std::to_string(si.first_b) + " meet), so no solid comes of it: "),
              std::string::npos)
              << m;
          EXPECT_EQ(s.index(), si.first_a);
        } else {
          EXPECT_EQ(s.code(), StatusCode::kUnsupported) << m;
          EXPECT_EQ(m.find("crosses itself"), std::string::npos) << m;
        }
      }
    }
  }
}

}  // namespace
}  // namespace splintcore

namespace splintcore {
namespace {

// An open B whose border meets or enters A is refused up front, saying that B is open and
// where (issue 30: the classification's "inconsistent inside/outside" said neither); an open
// B whose border lies outside A (here inside A's box, so the exact test decides) still works.
TEST(BooleanOpenB, BorderInsideAIsRefusedUpFrontAndOutsideAWorks) {
  TestArena ta;
  Arena& arena = ta.arena;
  Mesh a = box_mesh(arena, {0, 0, 0}, {1, 1, 1}, RigidTransform{});
  Mesh b = sphere_mesh(arena, 0.45, 6, 10, RigidTransform::translation({0.52, 0.47, 0.93}));
  // The south cap's last triangle lies inside A.
  ASSERT_LT(b.vertices[b.triangles[b.triangles.size() - 1].v[0]].z, 0.6);
  b.triangles.pop_back();
  {
    const Result r = run_op(arena, a, b, BooleanOp::kDifference, true);
    EXPECT_EQ(r.status.code(), StatusCode::kInvalidMesh) << test::format(r.status);
    const std::string m = r.status.message();
    EXPECT_NE(m.find("B is open: 3 boundary edges in 1 loop; its border meets A at vertex "),
              std::string::npos)
        << m;
    EXPECT_NE(m.find("splintcore prepare"), std::string::npos) << m;
    EXPECT_LT(r.status.index(), b.vertices.size());
  }
  // The tetrahedron x, y, z >= 0, x + y + z <= 1 (box [0, 1]^3) and a sphere through its
  // slanted face, open where x + y + z > 1.5: in A's box, outside A.
  Mesh t(&arena);
  for (const Vec3& p : {Vec3{0, 0, 0}, Vec3{1, 0, 0}, Vec3{0, 1, 0}, Vec3{0, 0, 1}}) {
    ASSERT_TRUE(t.vertices.push_back(p));
  }
  for (const Triangle& f :
       {Triangle{{0, 2, 1}}, Triangle{{0, 1, 3}}, Triangle{{0, 3, 2}}, Triangle{{1, 2, 3}}}) {
    ASSERT_TRUE(t.triangles.push_back(f));
  }
  Mesh s = sphere_mesh(arena, 0.4, 6, 10, RigidTransform::translation({0.5, 0.5, 0.5}));
  for (uint32_t v : s.triangles[0].v) {
    const Vec3& p = s.vertices[v];
    ASSERT_GT(p.x + p.y + p.z, 1.5);
  }
  s.triangles[0] = s.triangles[s.triangles.size() - 1];  // triangle 0 gone
  s.triangles.pop_back();
  EXPECT_EQ(report_of(arena, s).boundary_loops, 1u);
  const Result ok = run_op(arena, t, s, BooleanOp::kDifference, true);
  SPLINTCORE_EXPECT_OK(ok.status);
  EXPECT_GT(ok.volume, 0.0);
  EXPECT_LT(ok.volume, 1.0 / 6);
}

// The open-border check runs in ranges on the executor (its outcodes, edge counts and
// fingerprints, and the keys of an open B): the same refusal, word for word, at every thread
// count. B: a fine sphere (16,256 triangles, so that every range has some) without one
// triangle of its south cap, which lies inside A.
TEST(BooleanOpenB, TheRefusalIsTheSameAtEveryThreadCount) {
  TestArena inputs(size_t{64} << 20);
  Mesh a = box_mesh(inputs.arena, {0, 0, 0}, {1, 1, 1}, RigidTransform{});
  Mesh b =
      sphere_mesh(inputs.arena, 0.45, 64, 128, RigidTransform::translation({0.52, 0.47, 0.93}));
  ASSERT_LT(b.vertices[b.triangles[b.triangles.size() - 1].v[0]].z, 0.5);
  b.triangles.pop_back();
  std::string first;
  for (unsigned threads : {0u, 1u, 2u, 3u}) {
    TestArena run(size_t{64} << 20);
    ThreadExecutor pool(threads == 0 ? 1 : threads);
    const Context ctx(&run.arena, threads == 0 ? nullptr : &pool.executor(), nullptr);
    Mesh out;
    const Status s = mesh_boolean(ctx, a, b, opts(BooleanOp::kDifference), &out, nullptr);
    EXPECT_EQ(s.code(), StatusCode::kInvalidMesh) << threads << " threads: " << test::format(s);
    const std::string m = s.message();
    EXPECT_NE(m.find("B is open: 3 boundary edges in 1 loop; its border meets A at vertex "),
              std::string::npos)
        << m;
    if (threads == 0) first = m;
    EXPECT_EQ(m, first) << threads << " threads";
  }
}

// With b_border_outside_a, B's uncut parts that reach the border of its near triangles are
// outside A without a winding number (the blockout's swept surface leaves thousands of such
// islands near the splint); a closed uncut part still takes one. A: two boxes with a gap in
// A's box. B: a sphere through the first box's face, open in the gap; a small sphere in the
// gap, open (uncut, in A's box, outside A); a closed small sphere inside the first box. The
// same result as without the vouch (which checks the border and asks every uncut part's
// winding number), with one winding query fewer.
TEST(BooleanOpenB, UncutPartsThatReachTheBorderNeedNoWindingNumber) {
  TestArena ta;
  Arena& arena = ta.arena;
  auto append = [&](Mesh* to, const Mesh& from) {
    const uint32_t base = static_cast<uint32_t>(to->vertices.size());
    for (const Vec3& p : from.vertices) ASSERT_TRUE(to->vertices.push_back(p));
    for (const Triangle& t : from.triangles) {
      ASSERT_TRUE(to->triangles.push_back(Triangle{{base + t.v[0], base + t.v[1], base + t.v[2]}}));
    }
  };
  // Opens a sphere at its triangle whose centroid has the largest x (in the gap).
  auto open_at_largest_x = [](Mesh* m) {
    size_t best = 0;
    double best_x = -HUGE_VAL;
    for (size_t i = 0; i < m->triangles.size(); ++i) {
      const Triangle& t = m->triangles[i];
      const double x = m->vertices[t.v[0]].x + m->vertices[t.v[1]].x + m->vertices[t.v[2]].x;
      if (x > best_x) {
        best_x = x;
        best = i;
      }
    }
    m->triangles[best] = m->triangles[m->triangles.size() - 1];
    m->triangles.pop_back();
  };
  Mesh a(&arena);
  append(&a, box_mesh(arena, {0, 0, 0}, {4, 10, 10}, RigidTransform{}));
  append(&a, box_mesh(arena, {6, 0, 0}, {10, 10, 10}, RigidTransform{}));
  Mesh cut = sphere_mesh(arena, 1.0, 8, 12, RigidTransform::translation({4.3, 5.1, 4.9}));
  open_at_largest_x(&cut);
  Mesh island = sphere_mesh(arena, 0.3, 6, 10, RigidTransform::translation({5.0, 5.0, 2.0}));
  open_at_largest_x(&island);
  Mesh bubble = sphere_mesh(arena, 0.5, 6, 10, RigidTransform::translation({2.0, 5.0, 5.0}));
  Mesh b(&arena);
  append(&b, cut);
  append(&b, island);
  append(&b, bubble);
  EXPECT_EQ(report_of(arena, b).boundary_loops, 2u);
  std::vector<Vec3> vertices[2];
  std::vector<Triangle> triangles[2];
  BooleanStats stats[2];
  for (int vouch = 0; vouch < 2; ++vouch) {
    ArenaScope scope(arena);
    BooleanOptions o = opts(BooleanOp::kDifference);
    o.b_border_outside_a = vouch == 1;
    Mesh out;
    SPLINTCORE_ASSERT_OK(mesh_boolean(Context(&arena), a, b, o, &out, &stats[vouch]));
    vertices[vouch].assign(out.vertices.begin(), out.vertices.end());
    triangles[vouch].assign(out.triangles.begin(), out.triangles.end());
    const MeshReport r = report_of(arena, out);
    EXPECT_TRUE(r.is_valid_solid()) << test::format(require_valid_solid(r));
    EXPECT_EQ(r.shells, 3u);  // the two boxes and the bubble's cavity
  }
  EXPECT_GT(stats[0].cut_triangles_b, 0u);
  // A's uncut second box (B's winding number), the island and the bubble; with the vouch, not
  // the island.
  EXPECT_EQ(stats[0].winding_queries, 3u);
  EXPECT_EQ(stats[1].winding_queries, 2u);
  ASSERT_EQ(vertices[0].size(), vertices[1].size());
  ASSERT_EQ(triangles[0].size(), triangles[1].size());
  for (size_t i = 0; i < vertices[0].size(); ++i) {
    ASSERT_TRUE(vertices[0][i] == vertices[1][i]) << "vertex " << i;
  }
  for (size_t i = 0; i < triangles[0].size(); ++i) {
    for (int k = 0; k < 3; ++k) ASSERT_EQ(triangles[0][i].v[k], triangles[1][i].v[k]);
  }
}

// ---- the parallel prefix of the pair tests (find_hits on the executor) ------------------------

// One difference of a fine sphere (B, 16,256 triangles: enough near triangles for the tasks)
// and a box (A; box_hi.z < 0: its top face through a ring of the sphere's vertices) at
// `threads` (0: no executor), in an arena of `cap` bytes (0: 256 MiB): the result's bytes and
// the stats that say what was done.
struct ThreadedRun {
  Status status;
  std::string bytes;
  BooleanStats stats;
  size_t high_water = 0;
};

ThreadedRun threaded_difference(const Vec3& box_hi, unsigned threads, size_t cap,
                                uint64_t max_pairs) {
  TestArena inputs(size_t{64} << 20);
  Mesh b = sphere_mesh(inputs.arena, 0.45, 64, 128, rotation(0.3, -0.2, 0.7, {0.52, 0.47, 0.93}));
  const Vec3 hi = box_hi.z < 0 ? Vec3{1, 1, b.vertices[1 + 20 * 128].z} : box_hi;
  Mesh a = box_mesh(inputs.arena, {0, 0, 0}, hi, RigidTransform{});
  TestArena run(cap == 0 ? size_t{256} << 20 : cap);
  ThreadExecutor pool(threads == 0 ? 1 : threads);
  const Context ctx(&run.arena, threads == 0 ? nullptr : &pool.executor(), nullptr);
  BooleanOptions o = opts(BooleanOp::kDifference);
  o.max_candidate_pairs = max_pairs;
  ThreadedRun r;
  Mesh out;
  r.status = mesh_boolean(ctx, a, b, o, &out, &r.stats);
  r.high_water = run.arena.high_water();
  if (r.status.is_ok()) {
    r.bytes = test::mesh_sha256(out);
  }
  return r;
}

void expect_same_run(const ThreadedRun& r, const ThreadedRun& one, unsigned threads) {
  EXPECT_EQ(r.status.code(), one.status.code())
      << threads << " threads: " << test::format(r.status);
  EXPECT_STREQ(r.status.message(), one.status.message()) << threads << " threads";
  EXPECT_EQ(r.bytes, one.bytes) << threads << " threads";
  EXPECT_EQ(r.stats.candidate_pairs, one.stats.candidate_pairs) << threads << " threads";
  EXPECT_EQ(r.stats.intersecting_pairs, one.stats.intersecting_pairs) << threads << " threads";
  EXPECT_EQ(r.stats.degenerate_pairs, one.stats.degenerate_pairs) << threads << " threads";
  EXPECT_EQ(r.stats.attempts, one.stats.attempts) << threads << " threads";
}

// Crossings only (every task runs to its end), and a box whose top face holds a whole ring of
// the sphere's vertices exactly (degenerate contacts: the tasks stop there and one thread
// goes on with the run's state): the same result, stats included, at every thread count.
TEST(BooleanThreads, SameResultAtEveryThreadCount) {
  for (const Vec3& hi : {Vec3{1, 1, 1}, Vec3{1, 1, -1}}) {
    const ThreadedRun one = threaded_difference(hi, 0, 0, 0);
    SPLINTCORE_ASSERT_OK(one.status);
    ASSERT_GT(one.stats.near_b_triangles, 4096u);  // enough for the tasks
    ASSERT_GT(one.stats.intersecting_pairs, 100u);
    if (hi.z < 0) {
      EXPECT_GT(one.stats.degenerate_pairs, 0u);
    }
    EXPECT_EQ(one.stats.parallel_near_triangles, 0u);
    for (unsigned threads : {1u, 2u, 3u, 5u}) {
      const ThreadedRun r = threaded_difference(hi, threads, 0, 0);
      expect_same_run(r, one, threads);
      if (threads == 1) {
        EXPECT_EQ(r.stats.parallel_near_triangles, 0u);
      } else if (hi.z > 0) {  // every task ran to its end, in every attempt
        EXPECT_EQ(r.stats.parallel_near_triangles, r.stats.near_b_triangles * r.stats.attempts);
      } else {  // the tasks stopped at the first contact
        EXPECT_GT(r.stats.parallel_near_triangles, 0u);
        EXPECT_LT(r.stats.parallel_near_triangles, r.stats.near_b_triangles * r.stats.attempts);
      }
    }
  }
}

// Over max_candidate_pairs: the same error, naming the same triangle of B, at every thread
// count (one thread redoes the task where the sum passes the bound).
TEST(BooleanThreads, TheBoundIsPassedAtTheSameTriangle) {
  const ThreadedRun full = threaded_difference({1, 1, 1}, 0, 0, 0);
  SPLINTCORE_ASSERT_OK(full.status);
  for (uint64_t bound : {full.stats.candidate_pairs / 7, full.stats.candidate_pairs * 3 / 4,
                         full.stats.candidate_pairs - 1}) {
    const ThreadedRun one = threaded_difference({1, 1, 1}, 0, 0, bound);
    ASSERT_EQ(one.status.code(), StatusCode::kLimitExceeded) << test::format(one.status);
    for (unsigned threads : {2u, 3u}) {
      expect_same_run(threaded_difference({1, 1, 1}, threads, 0, bound), one, threads);
    }
  }
  expect_same_run(threaded_difference({1, 1, 1}, 2, 0, full.stats.candidate_pairs), full, 2);
}

// The tasks' memory is extra, taken only when the arena has it: at every cap two threads
// succeed where one does, with the same bytes, and run out where one runs out.
TEST(BooleanThreads, TwoThreadsFitWhereOneFits) {
  // A box low enough that fewer than half of the sphere's 16,128 triangles are near it: the run
  // works on a copy of those, and some caps fit the run on one thread but not the tasks'.
  const ThreadedRun one = threaded_difference({1, 1, 0.75}, 0, 0, 0);
  SPLINTCORE_ASSERT_OK(one.status);
  ASSERT_LE(one.stats.near_b_triangles, 16128u / 2);
  ASSERT_GT(one.stats.near_b_triangles, 4096u);  // enough for the tasks
  const ThreadedRun two = threaded_difference({1, 1, 0.75}, 2, one.high_water, 0);
  expect_same_run(two, one, 2);
  EXPECT_GT(two.stats.parallel_near_triangles, 0u);
  bool fell_back = false;
  for (size_t k = 1; k <= 32; ++k) {
    const size_t cap = one.high_water * k / 32;
    const ThreadedRun serial = threaded_difference({1, 1, 0.75}, 0, cap, 0);
    const ThreadedRun parallel = threaded_difference({1, 1, 0.75}, 2, cap, 0);
    EXPECT_EQ(parallel.status.code(), serial.status.code()) << "cap " << cap;
    EXPECT_STREQ(parallel.status.message(), serial.status.message()) << "cap " << cap;
    EXPECT_EQ(parallel.bytes, serial.bytes) << "cap " << cap;
    if (serial.status.is_ok()) {
      EXPECT_EQ(parallel.bytes, one.bytes) << "cap " << cap;
    } else {
      EXPECT_EQ(serial.status.code(), StatusCode::kArenaExhausted) << test::format(serial.status);
    }
    fell_back = fell_back || (parallel.stats.near_b_triangles > 0 &&
                              parallel.stats.parallel_near_triangles == 0);
  }
  EXPECT_TRUE(fell_back);  // some cap left no room for the tasks: one thread went on
}

}  // namespace
}  // namespace splintcore

namespace splintcore {
namespace {

struct CappedRun {
  Status status;
  std::string bytes;
  BooleanStats stats;
  size_t high_water = 0;
};

// A fine sphere minus a second one, crossing it: most of A lies near B, so the slots of A's
// triangles near B are the run's largest allocation. cap 0: ample.
CappedRun sphere_difference(size_t cap) {
  TestArena inputs(size_t{64} << 20);
  const Mesh a = sphere_mesh(inputs.arena, 0.5, 96, 192, RigidTransform{});
  const Mesh b =
      sphere_mesh(inputs.arena, 0.48, 96, 192, rotation(0.2, 0.1, 0.3, {0.05, 0.03, 0.02}));
  TestArena run(cap == 0 ? size_t{512} << 20 : cap);
  CappedRun r;
  Mesh out;
  BooleanOptions o = opts(BooleanOp::kDifference);
  o.check_self_intersection = false;  // the run's own peak, not its result's check
  r.status = mesh_boolean(Context(&run.arena), a, b, o, &out, &r.stats);
  r.high_water = run.arena.high_water();
  if (r.status.is_ok()) {
    r.bytes = test::mesh_sha256(out);
  }
  return r;
}

// When the slots for all of A's triangles near B do not fit, B's near triangles go in batches:
// the same pairs in the same order, so the same result and stats, in less memory. The least
// cap that works (found by halving) is well under the peak with ample memory, it batches, and
// below it the run ends cleanly.
TEST(BooleanBatches, SameResultInLessMemory) {
  const CappedRun full = sphere_difference(0);
  SPLINTCORE_ASSERT_OK(full.status);
  EXPECT_EQ(full.stats.hit_batches, 0u);
  ASSERT_GT(full.stats.intersecting_pairs, 1000u);
  size_t lo = 0, hi = full.high_water;
  CappedRun least = full;
  while (hi - lo > (size_t{1} << 14)) {
    const size_t mid = lo + (hi - lo) / 2;
    CappedRun r = sphere_difference(mid);
    if (r.status.is_ok()) {
      hi = mid;
      least = r;
    } else {
      EXPECT_EQ(r.status.code(), StatusCode::kArenaExhausted) << test::format(r.status);
      lo = mid;
    }
  }
  std::printf(
      "[ figures  ] sphere difference, %llu near triangles of B: peak %zu bytes with "
      "ample memory, least cap %zu (%u batches)\n",
      static_cast<unsigned long long>(full.stats.near_b_triangles), full.high_water, hi,
      least.stats.hit_batches);
  EXPECT_LT(hi, full.high_water * 3 / 4);
  EXPECT_EQ(least.stats.hit_batches, 8u);
  EXPECT_EQ(least.bytes, full.bytes);
  EXPECT_EQ(least.stats.candidate_pairs, full.stats.candidate_pairs);
  EXPECT_EQ(least.stats.intersecting_pairs, full.stats.intersecting_pairs);
  EXPECT_EQ(least.stats.intersection_points, full.stats.intersection_points);
  EXPECT_EQ(least.stats.attempts, full.stats.attempts);
}

// More uncut shells than a side sums directly (kDirectWindings, 4): from the fifth winding
// query on, the other mesh's index answers, with the same classification. A = a 20 mm box; B =
// one cube across A's face (so that the run cuts) and eight apart from everything: six inside
// A (cavities of the difference, gone from the union: a winding query each), two outside, far
// from A's box (gone from the difference, kept by the union; no query). The volumes are exact
// sums of whole cubes.
TEST(BooleanTest, ManyUncutShellsAreClassifiedThroughTheIndex) {
  TestArena t(size_t{16} << 20);
  Arena& arena = t.arena;
  const RigidTransform id;
  const Mesh a = box_mesh(arena, {0, 0, 0}, {20, 20, 20}, id);
  Mesh b = box_mesh(arena, {18, 8, 8}, {22, 12, 12}, id);  // 2 x 4 x 4 inside A, as much out
  const Vec3 inside[6] = {{2, 2, 2}, {2, 2, 6}, {2, 6, 2}, {6, 2, 2}, {6, 6, 2}, {2, 6, 6}};
  const Vec3 outside[2] = {{30, 0, 0}, {30, 5, 0}};
  for (const Vec3& lo : inside) append_mesh(box_mesh(arena, lo, lo + Vec3{1, 1, 1}, id), &b);
  for (const Vec3& lo : outside) append_mesh(box_mesh(arena, lo, lo + Vec3{1, 1, 1}, id), &b);
  struct Want {
    BooleanOp op;
    double volume;
    uint64_t shells;
  };
  const Want wants[] = {{BooleanOp::kDifference, 8000.0 - 32 - 6, 7},
                        {BooleanOp::kUnion, 8000.0 + 32 + 2, 3}};
  for (const Want& w : wants) {
    ArenaScope scope(arena);
    Mesh out;
    BooleanStats stats;
    SPLINTCORE_ASSERT_OK(mesh_boolean(Context(&arena), a, b, opts(w.op), &out, &stats));
    const MeshReport r = report_of(arena, out);
    EXPECT_TRUE(r.is_valid_solid()) << test::format(require_valid_solid(r));
    EXPECT_EQ(r.shells, w.shells);
    EXPECT_NEAR(r.volume, w.volume, 1e-9);
    EXPECT_EQ(stats.winding_queries, 6u);  // one per cube inside A's box (the others are far)
  }
}
}  // namespace
}  // namespace splintcore
