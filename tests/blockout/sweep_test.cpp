// The swept volume (blockout.h): the paper's cone experiment with measured errors, closed and
// oriented output, identical bytes for every slab size, any direction, bad input.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "common/phantom.h"
#include "common/shapes.h"
#include "splintcore/blockout.h"
#include "splintcore/design.h"
#include "splintcore/distance.h"
#include "splintcore/io.h"
#include "splintcore/platform.h"
#include "support/distance_oracle.h"
#include "support/phantom_jaws.h"
#include "support/test_util.h"
#include "support/undercut_lines.h"

namespace splintcore {
namespace {

using test::TestArena;

constexpr double kPi = 3.14159265358979323846;

// `part` appended to `m`, its vertex ids shifted: a splint of several shells. False when the
// arena is exhausted.
bool append_mesh(Mesh* m, const Mesh& part) {
  const uint32_t first = static_cast<uint32_t>(m->vertices.size());
  for (const Vec3& p : part.vertices) {
    if (!m->vertices.push_back(p)) return false;
  }
  for (Triangle t : part.triangles) {
    for (uint32_t& v : t.v) v += first;
    if (!m->triangles.push_back(t)) return false;
  }
  return true;
}

// A closed, outward frustum: radius r0 at z = z0, r1 at z = z1, n sides, capped.
void frustum(Mesh* m, double r0, double r1, double z0, double z1, uint32_t n,
             const RigidTransform* move = nullptr) {
  auto put = [&](Vec3 p) {
    if (move != nullptr) p = move->apply_point(p);
    (void)m->vertices.push_back(p);
  };
  for (uint32_t i = 0; i < n; ++i) {
    const double a = 2 * kPi * i / n;
    put(Vec3{r0 * std::cos(a), r0 * std::sin(a), z0});
  }
  for (uint32_t i = 0; i < n; ++i) {
    const double a = 2 * kPi * i / n;
    put(Vec3{r1 * std::cos(a), r1 * std::sin(a), z1});
  }
  put(Vec3{0, 0, z0});
  put(Vec3{0, 0, z1});
  const uint32_t bottom = 2 * n, top = 2 * n + 1;
  for (uint32_t i = 0; i < n; ++i) {
    const uint32_t j = (i + 1) % n;
    (void)m->triangles.push_back(Triangle{{i, j, n + j}});
    (void)m->triangles.push_back(Triangle{{i, n + j, n + i}});
    (void)m->triangles.push_back(Triangle{{bottom, j, i}});
    (void)m->triangles.push_back(Triangle{{top, n + i, n + j}});
  }
}

// The area of frustum()'s top ring (its vertices n .. 2n - 1) by the shoelace formula.
double rim_area(const Mesh& cone, uint32_t n) {
  double area = 0;
  for (uint32_t i = 0; i < n; ++i) {
    const Vec3& p = cone.vertices[n + i];
    const Vec3& q = cone.vertices[n + (i + 1) % n];
    area += p.x * q.y - q.x * p.y;
  }
  return area / 2;
}

struct Errors {
  double mean = 0, max = 0;
  size_t count = 0;
};

// Distance of the swept surface's side (z in [0.5, 7.5]) to the cylinder of radius 5.
Errors cylinder_errors(const Mesh& m, double radius) {
  Errors e;
  double sum = 0;
  for (const Vec3& p : m.vertices) {
    if (p.z < 0.5 || p.z > 7.5) continue;
    const double d = std::fabs(std::sqrt(p.x * p.x + p.y * p.y) - radius);
    sum += d;
    e.max = std::fmax(e.max, d);
    ++e.count;
  }
  e.mean = e.count > 0 ? sum / static_cast<double>(e.count) : 0;
  return e;
}

TEST(Sweep, ConeBecomesTheCylinderOfItsTopRadius) {
  // The paper's experiment (Chen et al. 2016, Fig. 6): a big-end-up frustum r = 3 -> 5 mm over
  // 8 mm, blocked out along its axis (the jaw moves down, away from the splint).
  TestArena ta(size_t{512} << 20);
  Mesh cone(&ta.arena);
  frustum(&cone, 3.0, 5.0, 0.0, 8.0, 720);
  const double polygon_gap = 5.0 * (1 - std::cos(kPi / 720));  // chord vs circle
  for (double h : {0.2, 0.1}) {
    for (bool correct : {false, true}) {
      SCOPED_TRACE(testing::Message() << "voxel " << h << (correct ? " corrected" : " plain"));
      ArenaScope scope(ta.arena);
      Context ctx(&ta.arena);
      SweepOptions o;
      o.direction = Vec3{0, 0, -1};
      o.voxel = h;
      o.extent = 1.0;
      o.correct_bias = correct;
      Mesh swept(&ta.arena);
      SweepStats stats;
      SPLINTCORE_ASSERT_OK(sweep_volume_mesh(ctx, Span<const Mesh>(&cone, 1), o, &swept, &stats));
      double volume = 0;
      SPLINTCORE_ASSERT_OK(check_closed_oriented(ctx, swept, &volume));
      EXPECT_GT(volume, 0);
      const Errors e = cylinder_errors(swept, 5.0);
      std::printf(
          "[ figures  ] cone sweep, voxel %.2f mm, %s: mean %.5f mm, max %.5f mm over %zu "
          "vertices; %llu segment tests, %llu distances, %llu corrected\n",
          h, correct ? "extrapolated inside" : "plain inside", e.mean, e.max, e.count,
          static_cast<unsigned long long>(stats.segment_tests),
          static_cast<unsigned long long>(stats.distance_evaluations),
          static_cast<unsigned long long>(stats.corrected_samples));
      ASSERT_GT(e.count, 100u);
      if (correct) {
        // The target of issue 6: under 0.01 mm mean at 0.1 mm voxels.
        EXPECT_LT(e.mean, 0.1 * h + polygon_gap);
        EXPECT_LT(e.max, 0.5 * h);
      }
    }
  }
}

// Streams every output triangle's bytes into a hash.
struct HashVisitor {
  Sha256 sha;
  uint64_t triangles = 0;
  static Status triangle(void* user, const Triangle&, const Vec3& a, const Vec3& b, const Vec3& c) {
    HashVisitor& h = *static_cast<HashVisitor*>(user);
    h.sha.update(&a, sizeof(Vec3));
    h.sha.update(&b, sizeof(Vec3));
    h.sha.update(&c, sizeof(Vec3));
    ++h.triangles;
    return Status::ok();
  }
  std::string hex() {
    uint8_t d[32];
    char out[65];
    sha.finish(d);
    Sha256::to_hex(d, out);
    return out;
  }
};

TEST(Sweep, SameBytesForEverySlabSize) {
  TestArena ta(size_t{256} << 20);
  Mesh cone(&ta.arena);
  // A rotation by the unit quaternion (0.9, 0.3, 0.3, 0.1) (normalised) and a shift.
  RigidTransform tilt;
  {
    const double n = std::sqrt(0.81 + 0.09 + 0.09 + 0.01);
    const double w = 0.9 / n, x = 0.3 / n, y = 0.3 / n, z = 0.1 / n;
    const double r[3][3] = {{1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)},
                            {2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)},
                            {2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)}};
    std::memcpy(tilt.r, r, sizeof(r));
    tilt.t = Vec3{0.3, -0.2, 1.1};
  }
  frustum(&cone, 2.0, 3.0, 0.0, 4.0, 90, &tilt);
  std::string first;
  for (uint32_t layers : {1u, 2u, 5u, 16u, 0u}) {
    SCOPED_TRACE(layers);
    ArenaScope scope(ta.arena);
    Context ctx(&ta.arena);
    SweepOptions o;
    o.direction = Vec3{0.2, -0.3, 1.0};
    o.voxel = 0.25;
    o.layers_per_tile = layers;
    HashVisitor hv;
    MarchingCubesVisitor v;
    v.triangle = HashVisitor::triangle;
    v.user = &hv;
    SweepStats stats;
    SPLINTCORE_ASSERT_OK(sweep_volume(ctx, Span<const Mesh>(&cone, 1), o, v, &stats));
    EXPECT_GT(hv.triangles, 1000u);
    const std::string hex = hv.hex();
    if (first.empty()) first = hex;
    EXPECT_EQ(hex, first);
  }
}

#if defined(SPLINTCORE_WITH_PLATFORM)
// sweep_state_bound is what the sweep's state takes at most: in an arena of exactly that plus
// one layer's extractor (marching_cubes_bound(grid, 1), the least slab it picks) the streamed
// sweep runs, with the bytes it gives with room to spare; jaws given as two meshes are summed.
TEST(Sweep, RunsInItsStateBoundAndOneExtractorLayer) {
  TestArena ta(size_t{64} << 20);
  Mesh jaws[2] = {Mesh(&ta.arena), Mesh(&ta.arena)};
  frustum(&jaws[0], 2.0, 3.0, 0.0, 4.0, 90);
  RigidTransform aside;
  aside.t = Vec3{7.0, 1.0, 0.5};
  frustum(&jaws[1], 1.5, 2.5, 0.0, 3.0, 40, &aside);
  SweepOptions o;
  o.direction = Vec3{0.2, -0.3, 1.0};
  o.voxel = 0.25;
  auto run = [&](Arena& arena, SweepStats* stats, std::string* hex) {
    HashVisitor hv;
    MarchingCubesVisitor v;
    v.triangle = HashVisitor::triangle;
    v.user = &hv;
    const Status s = sweep_volume(Context(&arena), Span<const Mesh>(jaws, 2), o, v, stats);
    *hex = hv.hex();
    return s;
  };
  SweepStats roomy;
  std::string reference;
  SPLINTCORE_ASSERT_OK(run(ta.arena, &roomy, &reference));
  ASSERT_GT(roomy.nx, 10u);
  ASSERT_GT(roomy.extraction.triangles, 1000u);
  VolumeGrid grid;
  grid.nx = roomy.nx;
  grid.ny = roomy.ny;
  grid.nz = roomy.nz;
  const uint64_t vertices = jaws[0].vertices.size() + jaws[1].vertices.size();
  const uint64_t triangles = jaws[0].triangles.size() + jaws[1].triangles.size();
  const uint64_t need =
      sweep_state_bound(vertices, triangles, roomy.nx, roomy.ny) + marching_cubes_bound(grid, 1);
  std::vector<unsigned char> buffer(static_cast<size_t>(need));
  Arena exact(buffer.data(), buffer.size());
  SweepStats tight;
  std::string hex;
  SPLINTCORE_ASSERT_OK(run(exact, &tight, &hex));
  EXPECT_EQ(hex, reference);
  EXPECT_EQ(exact.used(), 0u);
  std::printf(
      "[ figures  ] sweep of %llu triangles on %u x %u columns: bound %llu bytes, high "
      "water %zu bytes, %u layers a slab\n",
      static_cast<unsigned long long>(triangles), roomy.nx, roomy.ny,
      static_cast<unsigned long long>(need), exact.high_water(), tight.extraction.layers_per_tile);
}

TEST(Sweep, SameBytesForEveryThreadCount) {
  TestArena ta(size_t{256} << 20);
  Mesh cone(&ta.arena);
  frustum(&cone, 2.0, 3.0, 0.0, 4.0, 90);
  std::string first;
  for (unsigned threads : {1u, 2u, 3u, 8u}) {
    SCOPED_TRACE(threads);
    ThreadExecutor pool(threads);
    ArenaScope scope(ta.arena);
    Context ctx(&ta.arena, &pool.executor(), nullptr);
    SweepOptions o;
    o.direction = Vec3{0.1, 0.2, -1.0};
    o.voxel = 0.2;
    HashVisitor hv;
    MarchingCubesVisitor v;
    v.triangle = HashVisitor::triangle;
    v.user = &hv;
    SweepStats stats;
    SPLINTCORE_ASSERT_OK(sweep_volume(ctx, Span<const Mesh>(&cone, 1), o, v, &stats));
    const std::string hex = hv.hex();
    if (first.empty()) first = hex;
    EXPECT_EQ(hex, first);
  }
}
#endif

TEST(Sweep, AnyDirectionGivesAClosedSolidContainingTheJaw) {
  TestArena ta(size_t{256} << 20);
  Mesh cone(&ta.arena);
  frustum(&cone, 2.0, 3.0, 0.0, 4.0, 64);
  const Vec3 directions[] = {{1, 0, 0}, {0, -1, 0}, {0, 0, 1}, {1, 1, 1}, {-0.3, 0.1, 0.9}};
  for (const Vec3& d : directions) {
    SCOPED_TRACE(testing::Message() << d.x << "," << d.y << "," << d.z);
    ArenaScope scope(ta.arena);
    Context ctx(&ta.arena);
    SweepOptions o;
    o.direction = d;
    o.voxel = 0.2;
    o.extent = 2.0;
    Mesh swept(&ta.arena);
    SweepStats stats;
    SPLINTCORE_ASSERT_OK(sweep_volume_mesh(ctx, Span<const Mesh>(&cone, 1), o, &swept, &stats));
    double volume = 0;
    SPLINTCORE_ASSERT_OK(check_closed_oriented(ctx, swept, &volume));
    // At least the jaw itself plus some of the 2 mm beyond it along the direction.
    double cone_volume = 0;
    SPLINTCORE_ASSERT_OK(check_closed_oriented(ctx, cone, &cone_volume));
    EXPECT_GT(volume, cone_volume * 1.05);
    const Vec3 w = stats.axis_w;
    EXPECT_NEAR(length(w), 1.0, 1e-15);
    EXPECT_NEAR(length(cross(stats.axis_u, stats.axis_v) - w), 0.0, 1e-15);
  }
}

TEST(Sweep, RejectsBadOptionsAndInput) {
  TestArena ta(size_t{16} << 20);
  Context ctx(&ta.arena);
  Mesh cone(&ta.arena);
  frustum(&cone, 2.0, 3.0, 0.0, 4.0, 16);
  MarchingCubesVisitor none;
  SweepOptions o;
  o.direction = Vec3{0, 0, 0};
  EXPECT_EQ(sweep_volume(ctx, Span<const Mesh>(&cone, 1), o, none).code(),
            StatusCode::kInvalidArgument);
  o.direction = Vec3{0, 0, std::nan("")};
  EXPECT_EQ(sweep_volume(ctx, Span<const Mesh>(&cone, 1), o, none).code(),
            StatusCode::kInvalidArgument);
  o = SweepOptions{};
  o.voxel = 0;
  EXPECT_EQ(sweep_volume(ctx, Span<const Mesh>(&cone, 1), o, none).code(),
            StatusCode::kInvalidArgument);
  o = SweepOptions{};
  o.voxel = 1e-9;  // 4 mm / 1e-9 mm: beyond 2^31 samples per axis
  EXPECT_EQ(sweep_volume(ctx, Span<const Mesh>(&cone, 1), o, none).code(),
            StatusCode::kLimitExceeded);
  Mesh empty(&ta.arena);
  EXPECT_EQ(sweep_volume(ctx, Span<const Mesh>(&empty, 1), SweepOptions{}, none).code(),
            StatusCode::kInvalidArgument);
  // The other options' ranges, each text pinned (checked before anything is allocated), a
  // triangle naming a vertex out of range, an empty region, and an output that is not empty.
  struct Bad {
    void (*set)(SweepOptions*);
    const char* text;
  };
  const auto keep = [](const void*, const Vec3&, const Vec3&, const Vec3&) { return true; };
  static bool (*const kKeep)(const void*, const Vec3&, const Vec3&, const Vec3&) = keep;
  const Bad bad[] = {
      {[](SweepOptions* x) { x->closing_radius = 0.1; },
       "sweep: the closing radius must be 0 or from 2 to 10 voxels (radius 0.1 mm, voxel 0.1 "
       "mm)"},
      {[](SweepOptions* x) { x->inset = 0.2; },
       "sweep: the inset must be >= 0 and below two voxels (inset 0.2 mm, voxel 0.1 mm)"},
      {[](SweepOptions* x) { x->decimate_error = 0.02; },
       "sweep: the decimation error must be from 0 to a tenth of a voxel (0.02 mm, voxel 0.1 "
       "mm)"},
      {[](SweepOptions* x) { x->keep_triangle = kKeep; },
       "sweep: keep_triangle needs a region, open_at_region and float32_vertices, and no "
       "decimation"},
      {[](SweepOptions* x) { x->offset = 2.5; },
       "sweep: the offset must be from 0 to 20 voxels, with no inset (offset 2.5 mm, inset 0 "
       "mm, voxel 0.1 mm)"},
      {[](SweepOptions* x) {
         x->offset = 0.1;
         x->inset = 0.05;
       },
       "sweep: the offset must be from 0 to 20 voxels, with no inset (offset 0.1 mm, inset 0.05 "
       "mm, voxel 0.1 mm)"},
      {[](SweepOptions* x) {
         x->has_region = true;
         x->region.lo = Vec3{1, 1, 1};
         x->region.hi = Vec3{0, 0, 0};
       },
       "sweep: the region is empty or not finite"},
  };
  for (const Bad& b : bad) {
    o = SweepOptions{};
    b.set(&o);
    const size_t used = ta.arena.used();
    Mesh out(&ta.arena);
    const Status st = sweep_volume_mesh(ctx, Span<const Mesh>(&cone, 1), o, &out);
    EXPECT_EQ(st.code(), StatusCode::kInvalidArgument) << b.text;
    EXPECT_STREQ(st.message(), b.text);
    EXPECT_EQ(ta.arena.used(), used);
  }
  {
    Mesh out(&ta.arena);
    ASSERT_TRUE(out.triangles.push_back(Triangle{{0, 1, 2}}));
    const Status st = sweep_volume_mesh(ctx, Span<const Mesh>(&cone, 1), SweepOptions{}, &out);
    EXPECT_EQ(st.code(), StatusCode::kInvalidArgument);
    EXPECT_STREQ(st.message(), "sweep: the output mesh must be empty");
  }
  Mesh two[2] = {Mesh(&ta.arena), Mesh(&ta.arena)};
  frustum(&two[0], 2.0, 3.0, 0.0, 4.0, 16);
  frustum(&two[1], 2.0, 3.0, 0.0, 4.0, 16);
  two[1].triangles[5].v[1] = static_cast<uint32_t>(two[1].vertices.size());
  Status st = sweep_volume(ctx, Span<const Mesh>(two, 2), SweepOptions{}, none);
  EXPECT_EQ(st.code(), StatusCode::kInvalidMesh);
  EXPECT_STREQ(st.message(), "sweep: jaw 1 triangle 5 has a vertex id out of range");
  EXPECT_EQ(st.index(), 5u);
  cone.vertices[3].x = std::nan("");
  EXPECT_EQ(sweep_volume(ctx, Span<const Mesh>(&cone, 1), SweepOptions{}, none).code(),
            StatusCode::kNonFinite);
}

TEST(Sweep, ArenaExhaustionIsCleanAtEveryStep) {
  TestArena big(size_t{64} << 20);
  Mesh cone(&big.arena);
  frustum(&cone, 2.0, 3.0, 0.0, 4.0, 32);
  SweepOptions o;
  o.voxel = 0.3;
  size_t need = 0;
  {
    TestArena ta(size_t{64} << 20);
    Context ctx(&ta.arena);
    Mesh out(&ta.arena);
    SPLINTCORE_ASSERT_OK(sweep_volume_mesh(ctx, Span<const Mesh>(&cone, 1), o, &out));
    need = ta.arena.high_water();
  }
  uint32_t failures = 0;
  for (size_t cap = 0; cap < need; cap += cap < 4096 ? 64 : cap / 16) {
    TestArena ta(cap);
    Context ctx(&ta.arena);
    Mesh out(&ta.arena);
    const Status st = sweep_volume_mesh(ctx, Span<const Mesh>(&cone, 1), o, &out);
    if (st.is_ok()) continue;  // the slab size adapts to the cap
    EXPECT_EQ(st.code(), StatusCode::kArenaExhausted) << test::format(st);
    EXPECT_EQ(ta.arena.used(), 0u);
    EXPECT_TRUE(out.triangles.empty());
    ++failures;
  }
  EXPECT_GT(failures, 10u);
  TestArena ta(need);
  Context ctx(&ta.arena);
  Mesh out(&ta.arena);
  SPLINTCORE_EXPECT_OK(sweep_volume_mesh(ctx, Span<const Mesh>(&cone, 1), o, &out));
}

}  // namespace
}  // namespace splintcore

namespace splintcore {
namespace {

using test::TestArena;

Mesh box_mesh(Arena* arena, const float lo[3], const float hi[3]) {
  Mesh m(arena);
  Context ctx(arena);
  const std::vector<SoupTriangle> soup = shapes::box(lo, hi);
  SPLINTCORE_ASSERT(
      weld_exact(ctx, Span<const SoupTriangle>(soup.data(), soup.size()), &m).is_ok());
  return m;
}

// The independent line check on the cone blocked out along -z (the tests below): lines
// through the jaw, none locked by more than 1e-6 mm.
void expect_cone_unlocked(Arena* arena, const Mesh& blocked, const Mesh& cone) {
  const Vec3 d{0, 0, -1}, u{1, 0, 0}, v{0, 1, 0}, c{0, 0, 5};
  const test::LockReport after =
      test::lock_report(*arena, blocked, cone, d, u, v, c, 6.0, 60, 1e-6);
  EXPECT_GT(after.lines_through_jaw, 1000u);
  EXPECT_EQ(after.locked_lines, 0u) << after.longest;
}

// The line check's depth across d (undercut_lines.h) on a unit cube leaving along +z: a point
// above the cube lies in its sweep as deep as its distance to the nearest side wall; a point
// beside it is not in the sweep at all.
TEST(UndercutLines, LateralDepthIsTheDistanceToTheSweepsWall) {
  TestArena ta(size_t{64} << 20);
  Context ctx(&ta.arena);
  const float lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
  const Mesh cube = box_mesh(&ta.arena, lo, hi);
  DistanceIndex index;
  SPLINTCORE_ASSERT_OK(build_distance_index(ctx, cube, DistanceIndexOptions{}, &index));
  const Vec3 d{0, 0, 1}, u{1, 0, 0}, v{0, 1, 0};
  const double step = 0.005, slack = 1e-9;  // (r is a multiple of step, rounded)
  // Lines from z = -1; the point is at z = 2.5 (t = 3.5), above the cube.
  const auto depth = [&](double x, double y) {
    return test::lateral_depth(index, Vec3{x, y, -1}, 3.5, d, u, v, 10.0, step, 2.0);
  };
  const double near_wall = depth(0.95, 0.5), centre = depth(0.5, 0.5), corner = depth(0.9, 0.8);
  EXPECT_GT(near_wall, 0.05 - step);
  EXPECT_LE(near_wall, 0.05 + step + slack);
  EXPECT_GT(centre, 0.5 - step);
  EXPECT_LE(centre, 0.5 + step + slack);
  EXPECT_GT(corner, 0.1 - step);
  EXPECT_LE(corner, 0.1 + step + slack);
  EXPECT_EQ(depth(1.2, 0.5), step);  // outside the sweep: the first move frees it
  // Below the cube's bottom (t = 0.5) nothing of the cube lies before it: out of the sweep.
  EXPECT_EQ(test::lateral_depth(index, Vec3{0.5, 0.5, -1}, 0.5, d, u, v, 10.0, step, 2.0), step);
}

TEST(Blockout, UndercutOfABigEndUpConeIsRemoved) {
  // A splint (a box) over the top half of a big-end-up frustum: the cavity the Boolean leaves
  // narrows towards the opening (r 4 at the box's bottom, 5 at the cone's top), so the splint
  // is locked on. Inserted downwards (the cone moves down relative to it when it comes off),
  // the blockout widens the cavity to the cylinder of radius 5.
  TestArena ta(size_t{1} << 30);
  Context ctx(&ta.arena);
  Mesh cone(&ta.arena);
  frustum(&cone, 3.0, 5.0, 0.0, 8.0, 720);
  for (Vec3& p : cone.vertices) ASSERT_TRUE(round_to_float32(&p));
  const float lo[3] = {-7, -7, 4}, hi[3] = {7, 7, 10};
  Mesh splint = box_mesh(&ta.arena, lo, hi);
  BlockoutOptions o;
  o.sweep.direction = Vec3{0, 0, -1};
  o.sweep.voxel = 0.1;
  Mesh out;
  BlockoutStats stats;
  SPLINTCORE_ASSERT_OK(blockout(ctx, splint, Span<const Mesh>(&cone, 1), o, &out, &stats));
  double volume = 0;
  SPLINTCORE_ASSERT_OK(check_closed_oriented(ctx, out, &volume));
  const double n = 720;
  const double disc = 0.5 * n * 25.0 * std::sin(2 * kPi / n);  // the 720-gon of radius 5
  const double expected = 14.0 * 14.0 * 6.0 - disc * 4.0;
  // The cavity's wall is the swept surface: within its measured error (0.0012 mm mean at
  // 0.1 mm voxels) over the wall's area (2 pi 5 x 4 = 126 mm^2), and the cap of the cone's top.
  std::printf(
      "[ figures  ] blockout of the cone: volume %.4f mm^3, expected %.4f; swept mesh %llu "
      "triangles, result %zu triangles\n",
      volume, expected, static_cast<unsigned long long>(stats.swept_triangles),
      out.triangles.size());
  EXPECT_NEAR(volume, expected, 126.0 * 0.005);
  // No material left inside the radius-5 cylinder between z = 4 and 8: every vertex of the
  // result there is on its wall (r >= 5 - error).
  for (const Vec3& p : out.vertices) {
    if (p.z > 4.01 && p.z < 7.99) {
      EXPECT_GT(std::sqrt(p.x * p.x + p.y * p.y), 5.0 - 0.03);
    }
  }
}

// `count` cones (frustums of radius 3 to 5 and 8 high, `segments` sides) in a row along x,
// 14 mm apart and centred on x = 0, in float32.
void cones_in_a_row(Mesh* cones, int count, int segments) {
  for (int k = 0; k < count; ++k) {
    frustum(&cones[k], 3.0, 5.0, 0.0, 8.0, segments);
    for (Vec3& p : cones[k].vertices) {
      p.x += 14.0 * k - 7.0 * (count - 1);
      ASSERT_TRUE(round_to_float32(&p));
    }
  }
}

// `splint` holding cone k's swept surface at the inset o.sweep.inset + steps[k] voxels, each
// made by a blockout of its own (one attempt each: the imprint at exactly that inset, its
// triangles the sweep's, bit for bit).
void hold_imprints(const Context& ctx, const Mesh& splint, const Mesh* cones, int count,
                   const BlockoutOptions& o, const double* steps, Mesh* held) {
  *held = splint;
  for (int k = 0; k < count; ++k) {
    BlockoutOptions ok = o;
    ok.sweep.inset = o.sweep.inset + steps[k] * o.sweep.voxel;
    BlockoutStats st;
    Mesh next;
    SPLINTCORE_ASSERT_OK(blockout(ctx, *held, Span<const Mesh>(&cones[k], 1), ok, &next, &st));
    EXPECT_EQ(st.attempts, 1u) << k;
    *held = next;
  }
}

// When the Boolean cannot subtract the swept surface at the inset asked for, the retries take
// it deeper: 1/64 voxel, then a quarter and a half voxel more (BlockoutStats::inset_used). The
// splint here already holds each cone's swept surface: the left one's at the inset asked for,
// the right one's 1/64 voxel deeper (each made by the blockout itself, so its triangles are the
// sweep's, bit for bit). The blockout of both cones at that inset meets the left imprint
// coincident with its surface, the first retry the right one; the second retry, a quarter
// voxel deeper, meets neither.
TEST(Blockout, RetriesTakeTheSweptSurfaceDeeperUntilTheBooleanResolves) {
  TestArena ta(size_t{1} << 30);
  Context ctx(&ta.arena);
  Mesh cones[2] = {Mesh(&ta.arena), Mesh(&ta.arena)};
  cones_in_a_row(cones, 2, 180);
  const float lo[3] = {-14, -7, 4}, hi[3] = {14, 7, 10};
  BlockoutOptions o;
  o.sweep.direction = Vec3{0, 0, -1};
  o.sweep.voxel = 0.2;
  o.sweep.inset = 0.1;
  const double steps[2] = {0, 1.0 / 64};
  Mesh held;
  hold_imprints(ctx, box_mesh(&ta.arena, lo, hi), cones, 2, o, steps, &held);
  // Without the Boolean's own nudges (with them it gets past the coincidence here, at its
  // ninth attempt), so that only the blockout's retries can.
  o.boolean.max_nudges = 0;
  Mesh out;
  BlockoutStats st;
  SPLINTCORE_ASSERT_OK(blockout(ctx, held, Span<const Mesh>(cones, 2), o, &out, &st));
  EXPECT_EQ(st.attempts, 3u);
  EXPECT_EQ(st.inset_used, o.sweep.inset + o.sweep.voxel / 4);
  EXPECT_EQ(st.boolean.attempts, 1u);
  double before = 0, after = 0;
  SPLINTCORE_ASSERT_OK(check_closed_oriented(ctx, held, &before));
  SPLINTCORE_ASSERT_OK(check_closed_oriented(ctx, out, &after));
  // The deeper swept surface lies in the cavities already cut: nothing more to take.
  EXPECT_NEAR(after, before, 1e-6 * before);
  std::printf("[ figures  ] both cones: %u attempts, inset %.4f mm; volume %.6f -> %.6f mm^3\n",
              st.attempts, st.inset_used, before, after);
}

// When every retry fails too, the error says so first, with the insets tried, then the last
// attempt's reason: four cones, the splint already holding each one's swept surface at one of
// the four insets the attempts use, so that each attempt (the Boolean's nudges off) meets one
// exactly coincident.
TEST(Blockout, WhenEveryRetryFailsTheErrorSaysWhichInsetsWereTried) {
  TestArena ta(size_t{1} << 30);
  Context ctx(&ta.arena);
  Mesh cones[4] = {Mesh(&ta.arena), Mesh(&ta.arena), Mesh(&ta.arena), Mesh(&ta.arena)};
  cones_in_a_row(cones, 4, 60);
  const float lo[3] = {-28, -7, 4}, hi[3] = {28, 7, 10};
  BlockoutOptions o;
  o.sweep.direction = Vec3{0, 0, -1};
  o.sweep.voxel = 0.4;
  o.sweep.inset = 0.2;
  const double steps[4] = {0, 1.0 / 64, 1.0 / 4, 1.0 / 2};
  Mesh held;
  hold_imprints(ctx, box_mesh(&ta.arena, lo, hi), cones, 4, o, steps, &held);
  o.boolean.max_nudges = 0;
  Mesh out;
  BlockoutStats st;
  const Status s = blockout(ctx, held, Span<const Mesh>(cones, 4), o, &out, &st);
  ASSERT_EQ(s.code(), StatusCode::kUnsupported) << test::format(s);
  EXPECT_EQ(st.attempts, 4u);
  EXPECT_NE(std::strstr(s.message(),
                        "blockout: all 4 attempts failed (the swept surface inset "
                        "0.2 to 0.4 mm); the last: "),
            nullptr)
      << s.message();
  EXPECT_TRUE(out.triangles.empty());
  std::printf("[ figures  ] %s\n", s.message());
}

TEST(Blockout, SplintOutOfReachComesBackUnchanged) {
  TestArena ta(size_t{256} << 20);
  Context ctx(&ta.arena);
  Mesh cone(&ta.arena);
  frustum(&cone, 3.0, 5.0, 0.0, 8.0, 64);
  // The sweep goes down from the cone; a box above it is never reached.
  const float lo[3] = {-7, -7, 9}, hi[3] = {7, 7, 10};
  Mesh splint = box_mesh(&ta.arena, lo, hi);
  BlockoutOptions o;
  o.sweep.direction = Vec3{0, 0, -1};
  o.sweep.voxel = 0.2;
  Mesh out;
  BlockoutStats stats;
  SPLINTCORE_ASSERT_OK(blockout(ctx, splint, Span<const Mesh>(&cone, 1), o, &out, &stats));
  ASSERT_EQ(out.triangles.size(), splint.triangles.size());
  for (size_t i = 0; i < out.vertices.size(); ++i) EXPECT_EQ(out.vertices[i], splint.vertices[i]);
  EXPECT_EQ(stats.swept_triangles, 0u);
}

// The swept triangles near the splint alone (BlockoutOptions::filter_near_splint, the default)
// give the same solid as the whole swept surface in the splint's box: the same triangles, as
// corner coordinates (only the vertex numbering may differ), so the same volume; the swept
// mesh handed to the Boolean is a fraction of the whole. On the paper-scale case's base cut by
// a phantom maxilla, at 0.2 mm voxels, and on the cone.
std::vector<std::array<float, 9>> corner_list(const Mesh& m) {
  std::vector<std::array<float, 9>> out;
  for (const Triangle& t : m.triangles) {
    int first = 0;  // the rotation that starts at the smallest corner (x, then y, then z)
    for (int k = 1; k < 3; ++k) {
      const Vec3 &a = m.vertices[t.v[k]], &b = m.vertices[t.v[first]];
      if (a.x < b.x || (a.x == b.x && (a.y < b.y || (a.y == b.y && a.z < b.z)))) first = k;
    }
    std::array<float, 9> c{};
    for (int k = 0; k < 3; ++k) {
      const Vec3& p = m.vertices[t.v[(first + k) % 3]];
      c[3 * k] = static_cast<float>(p.x);
      c[3 * k + 1] = static_cast<float>(p.y);
      c[3 * k + 2] = static_cast<float>(p.z);
    }
    out.push_back(c);
  }
  std::sort(out.begin(), out.end());
  return out;
}

void expect_same_solid(const Context& ctx, const Mesh& splint, const Mesh& jaw, BlockoutOptions o,
                       const char* what, bool some_far) {
  o.filter_near_splint = false;
  Mesh whole;
  BlockoutStats whole_stats;
  SPLINTCORE_ASSERT_OK(blockout(ctx, splint, Span<const Mesh>(&jaw, 1), o, &whole, &whole_stats));
  o.filter_near_splint = true;
  Mesh near;
  BlockoutStats near_stats;
  SPLINTCORE_ASSERT_OK(blockout(ctx, splint, Span<const Mesh>(&jaw, 1), o, &near, &near_stats));
  double v_whole = 0, v_near = 0;
  SPLINTCORE_ASSERT_OK(check_closed_oriented(ctx, whole, &v_whole));
  SPLINTCORE_ASSERT_OK(check_closed_oriented(ctx, near, &v_near));
  std::printf(
      "[ figures  ] %s: swept mesh %llu triangles whole, %llu near the splint (%llu left "
      "out); result %zu / %zu triangles, volume %.9f / %.9f mm^3\n",
      what, static_cast<unsigned long long>(whole_stats.swept_triangles),
      static_cast<unsigned long long>(near_stats.swept_triangles),
      static_cast<unsigned long long>(near_stats.sweep.filtered_triangles), whole.triangles.size(),
      near.triangles.size(), v_whole, v_near);
  if (some_far) {
    EXPECT_GT(near_stats.sweep.filtered_triangles, whole_stats.swept_triangles / 10);
  }
  EXPECT_EQ(near_stats.swept_triangles + near_stats.sweep.filtered_triangles,
            whole_stats.swept_triangles);
  EXPECT_EQ(near_stats.attempts, whole_stats.attempts);
  EXPECT_TRUE(near_stats.boolean.self_intersection_checked);
  EXPECT_EQ(near.triangles.size(), whole.triangles.size());
  EXPECT_NEAR(v_near, v_whole, 1e-9 * v_whole);
  EXPECT_TRUE(corner_list(near) == corner_list(whole));
  EXPECT_LT(v_whole, mesh_volume(splint));  // the blockout did remove something
}

TEST(Blockout, NearSplintFilterGivesTheSameSolid) {
  TestArena ta(size_t{1} << 30);
  Context ctx(&ta.arena);
  {
    Mesh cone(&ta.arena);
    frustum(&cone, 3.0, 5.0, 0.0, 8.0, 720);
    for (Vec3& p : cone.vertices) ASSERT_TRUE(round_to_float32(&p));
    // Two blocks of a splint on either side of the cone (two shells): the swept surface
    // between them (|x| < 2) is in their box but far from both.
    const float lo0[3] = {-7, -7, 4}, hi0[3] = {-2, 7, 10};
    const float lo1[3] = {2, -7, 4}, hi1[3] = {7, 7, 10};
    Mesh splint = box_mesh(&ta.arena, lo0, hi0);
    const Mesh right = box_mesh(&ta.arena, lo1, hi1);
    ASSERT_TRUE(append_mesh(&splint, right));
    BlockoutOptions o;
    o.sweep.direction = Vec3{0, 0, -1};
    o.sweep.voxel = 0.1;
    expect_same_solid(ctx, splint, cone, o, "cone between two blocks, 0.1 mm", true);
  }
  const std::vector<uint8_t> text =
      test::read_file_bytes(std::string(SPLINTCORE_FIXTURES_DIR) + "/cases/paper_scale.json");
  CaseFile c;
  SPLINTCORE_ASSERT_OK(parse_case(ctx, reinterpret_cast<const char*>(text.data()), text.size(),
                                  "paper_scale.json", &c));
  phantom::JawMesh m;
  phantom::PhantomOptions po;
  po.target_triangles = 6000;
  ASSERT_TRUE(phantom::make_jaw(phantom::Jaw::kMaxilla, po, &m).is_ok());
  Mesh jaw(&ta.arena);
  for (const Vec3& v : m.vertices) ASSERT_TRUE(jaw.vertices.push_back(v));
  for (const Triangle& t : m.triangles) ASSERT_TRUE(jaw.triangles.push_back(t));
  Mesh base(&ta.arena), cut(&ta.arena);
  BaseReport br;
  SPLINTCORE_ASSERT_OK(build_case_base(ctx, c, &base, &br));
  SPLINTCORE_ASSERT_OK(mesh_boolean(ctx, base, jaw, BooleanOptions{}, &cut, nullptr));
  BlockoutOptions o;
  o.sweep.direction = Vec3{0, 0, 1};
  o.sweep.voxel = 0.2;
  o.sweep.inset = 0.1;
  expect_same_solid(ctx, cut, jaw, o, "phantom maxilla, 0.2 mm", false);
}

bool keep_all(const void*, const Vec3&, const Vec3&, const Vec3&) { return true; }

// A filtered sweep of the slab [-4, 4]^2 x [0, 1] through the region [-2, 2]^2 x [0.5, 3].
SweepOptions filtered_slab_options(const Vec3& direction, double voxel,
                                   bool (*keep)(const void*, const Vec3&, const Vec3&,
                                                const Vec3&)) {
  SweepOptions o;
  o.direction = direction;
  o.voxel = voxel;
  o.has_region = true;
  o.region.lo = Vec3{-2.0, -2.0, 0.5};
  o.region.hi = Vec3{2.0, 2.0, 3.0};
  o.open_at_region = true;
  o.keep_triangle = keep;
  o.float32_vertices = true;
  return o;
}

TEST(Sweep, FilteredSweepRunsAgainWithTheFullIdPoolWhenALayerNeedsIt) {
  // A slab wider than the region swept up through it: the region's last layer is inside
  // everywhere, so the closing cells cross four edges at each of its samples, more than the
  // quarter pool of the filtered extraction holds; it runs again with the full pool, with the
  // bytes of a run whose slab differs (the output never depends on the pool or the slab).
  TestArena ta(size_t{256} << 20);
  Context ctx(&ta.arena);
  const float lo[3] = {-4, -4, 0}, hi[3] = {4, 4, 1};
  Mesh slab = box_mesh(&ta.arena, lo, hi);
  SweepOptions o = filtered_slab_options(Vec3{0, 0, 1}, 0.25, keep_all);
  std::vector<Vec3> vertices[2];
  std::vector<Triangle> triangles[2];
  for (uint32_t layers : {0u, 1u}) {
    o.layers_per_tile = layers;
    Mesh swept(&ta.arena);
    SweepStats st;
    SPLINTCORE_ASSERT_OK(sweep_volume_mesh(ctx, Span<const Mesh>(&slab, 1), o, &swept, &st));
    EXPECT_TRUE(st.full_id_pool);
    EXPECT_FALSE(st.extraction.pool_short);
    EXPECT_GT(swept.triangles.size(), 100u);
    EXPECT_EQ(swept.triangles.size() + st.cap_triangles_dropped, st.extraction.triangles);
    vertices[layers].assign(swept.vertices.begin(), swept.vertices.end());
    triangles[layers].assign(swept.triangles.begin(), swept.triangles.end());
  }
  ASSERT_EQ(vertices[0].size(), vertices[1].size());
  ASSERT_EQ(triangles[0].size(), triangles[1].size());
  EXPECT_EQ(0,
            std::memcmp(vertices[0].data(), vertices[1].data(), vertices[0].size() * sizeof(Vec3)));
  EXPECT_EQ(0, std::memcmp(triangles[0].data(), triangles[1].data(),
                           triangles[0].size() * sizeof(Triangle)));
}

TEST(Sweep, FilteredLogGivesTheUnfilteredSurfaceWhenItKeepsAll) {
  // The filtered sweep logs each vertex's corner once (or again when the log's cache has
  // forgotten it): keeping every triangle, the mesh is the unfiltered variant's with its
  // corners rounded to float32 (SweepOptions::keep_triangle), byte for byte, here with more
  // vertices than the cache has slots.
  TestArena ta(size_t{512} << 20);
  Context ctx(&ta.arena);
  const float lo[3] = {-4, -4, 0}, hi[3] = {4, 4, 1};
  Mesh slab = box_mesh(&ta.arena, lo, hi);
  SweepOptions o = filtered_slab_options(Vec3{0, 0, -1}, 0.02, keep_all);
  Mesh kept(&ta.arena);
  SweepStats st;
  SPLINTCORE_ASSERT_OK(sweep_volume_mesh(ctx, Span<const Mesh>(&slab, 1), o, &kept, &st));
  EXPECT_EQ(st.filtered_triangles, 0u);
  ASSERT_GT(kept.vertices.size(), size_t{1} << 15);
  // Every vertex at least once, each record 16 bytes; under half the 48 bytes a triangle the
  // log took when it held every triangle's corners.
  const uint64_t tri_bytes = 12 * kept.triangles.size();
  EXPECT_GE(st.log_bytes, tri_bytes + 16 * kept.vertices.size());
  EXPECT_EQ((st.log_bytes - tri_bytes) % 16, 0u);
  EXPECT_LT(st.log_bytes, 2 * tri_bytes);
  o.keep_triangle = nullptr;
  Mesh all(&ta.arena);
  SPLINTCORE_ASSERT_OK(sweep_volume_mesh(ctx, Span<const Mesh>(&slab, 1), o, &all, nullptr));
  for (Vec3& p : all.vertices) ASSERT_TRUE(round_to_float32(&p));
  EXPECT_EQ(test::mesh_sha256(kept), test::mesh_sha256(all));
}

#if defined(SPLINTCORE_WITH_PLATFORM)
// A filter that keeps the triangles left of x = 0.3 and counts its calls (one user a task).
struct CountingFilter {
  mutable uint64_t calls = 0;
};
bool keep_left(const void* user, const Vec3& a, const Vec3& b, const Vec3& c) {
  ++static_cast<const CountingFilter*>(user)->calls;
  return a.x + b.x + c.x < 0.9;
}

TEST(Sweep, FilterInTasksSameBytesForEveryThreadCount) {
  // keep_triangle from the executor's tasks (SweepOptions::keep_tasks, several batches of
  // kSweepKeepBatch): the kept mesh of one filter called in order, at every thread count, each
  // triangle tested once, by more than one task's user when there are threads.
  TestArena ta(size_t{256} << 20);
  const float lo[3] = {-4, -4, 0}, hi[3] = {4, 4, 1};
  Mesh slab = box_mesh(&ta.arena, lo, hi);
  // Down: the slab's top face crosses the region.
  SweepOptions o = filtered_slab_options(Vec3{0, 0, -1}, 0.05, keep_left);
  std::string first;
  for (unsigned threads : {0u, 1u, 2u, 3u}) {
    SCOPED_TRACE(threads);
    ThreadExecutor pool(threads == 0 ? 1 : threads);
    ArenaScope scope(ta.arena);
    Context ctx(&ta.arena, threads == 0 ? nullptr : &pool.executor(), nullptr);
    CountingFilter one, users[4];
    const void* pointers[4] = {&users[0], &users[1], &users[2], &users[3]};
    if (threads == 0) {  // one at a time, keep_user
      o.keep_user = &one;
      o.keep_tasks = 0;
    } else {
      o.keep_task_users = pointers;
      o.keep_tasks = 4;
    }
    Mesh swept(&ta.arena);
    SweepStats st;
    SPLINTCORE_ASSERT_OK(sweep_volume_mesh(ctx, Span<const Mesh>(&slab, 1), o, &swept, &st));
    EXPECT_GT(st.filtered_triangles, uint64_t{kSweepKeepBatch});
    EXPECT_GT(swept.triangles.size(), size_t{kSweepKeepBatch});
    const uint64_t calls =
        one.calls + users[0].calls + users[1].calls + users[2].calls + users[3].calls;
    EXPECT_EQ(calls, swept.triangles.size() + st.filtered_triangles);
    EXPECT_EQ(users[1].calls > 0, threads > 1);
    EXPECT_EQ(users[3].calls > 0, threads > 3);
    std::string bytes(reinterpret_cast<const char*>(swept.vertices.data()),
                      swept.vertices.size() * sizeof(Vec3));
    bytes.append(reinterpret_cast<const char*>(swept.triangles.data()),
                 swept.triangles.size() * sizeof(Triangle));
    if (first.empty()) first = bytes;
    EXPECT_TRUE(bytes == first);
  }
}
#endif

// SweepOptions::jaw_vertex: the jaws read through a move give the bytes of the sweep of moved
// copies (the design passes its jaws so, not copied), with a second jaw of vertices only that
// anchors the lattice; a hook that gives a non-finite vertex is refused, naming it.
struct MovedJaws {
  const Mesh* jaws;
  RigidTransform move[2];
  static Vec3 vertex(const void* user, size_t j, size_t i) {
    const MovedJaws& m = *static_cast<const MovedJaws*>(user);
    return m.move[j].apply_point(m.jaws[j].vertices[i]);
  }
  static Vec3 broken(const void* user, size_t j, size_t i) {
    return j == 1 && i == 5 ? Vec3{0, std::numeric_limits<double>::quiet_NaN(), 0}
                            : vertex(user, j, i);
  }
};

TEST(Sweep, JawVertexHookGivesTheBytesOfMovedCopies) {
  TestArena ta(size_t{256} << 20);
  Context ctx(&ta.arena);
  Mesh jaws[2] = {Mesh(&ta.arena), Mesh(&ta.arena)};
  frustum(&jaws[0], 2.0, 3.0, 0.0, 4.0, 60);
  frustum(&jaws[1], 1.0, 1.0, -6.0, -5.0, 8);  // beyond the first: it moves the lattice
  jaws[1].triangles.clear();
  MovedJaws moved{jaws, {}};
  moved.move[0] = RigidTransform::translation(Vec3{0.3, -0.7, 2.0});
  moved.move[0].r[0][0] = moved.move[0].r[1][1] = 0.0;  // a quarter turn about z
  moved.move[0].r[0][1] = -1.0;
  moved.move[0].r[1][0] = 1.0;
  moved.move[1] = RigidTransform::translation(Vec3{0.05, 0.11, -0.4});
  Mesh copies[2] = {Mesh(&ta.arena), Mesh(&ta.arena)};
  for (int j = 0; j < 2; ++j) {
    for (size_t i = 0; i < jaws[j].vertices.size(); ++i) {
      ASSERT_TRUE(copies[j].vertices.push_back(MovedJaws::vertex(&moved, j, i)));
    }
    for (const Triangle& t : jaws[j].triangles) ASSERT_TRUE(copies[j].triangles.push_back(t));
  }
  SweepOptions o;
  o.direction = Vec3{0.1, 0.2, -1};
  o.voxel = 0.25;
  o.extent = 2.0;
  Mesh want(&ta.arena);
  SPLINTCORE_ASSERT_OK(sweep_volume_mesh(ctx, Span<const Mesh>(copies, 2), o, &want));
  ASSERT_GT(want.triangles.size(), 1000u);
  SweepOptions hooked = o;
  hooked.jaw_vertex = MovedJaws::vertex;
  hooked.jaw_vertex_user = &moved;
  Mesh got(&ta.arena);
  SPLINTCORE_ASSERT_OK(sweep_volume_mesh(ctx, Span<const Mesh>(jaws, 2), hooked, &got));
  EXPECT_EQ(test::mesh_sha256(got), test::mesh_sha256(want));
  // The jaws as they are make another surface (the hook is what moved them).
  Mesh unmoved(&ta.arena);
  SPLINTCORE_ASSERT_OK(sweep_volume_mesh(ctx, Span<const Mesh>(jaws, 2), o, &unmoved));
  EXPECT_NE(test::mesh_sha256(unmoved), test::mesh_sha256(want));
  hooked.jaw_vertex = MovedJaws::broken;
  Mesh bad(&ta.arena);
  const Status st = sweep_volume_mesh(ctx, Span<const Mesh>(jaws, 2), hooked, &bad);
  EXPECT_EQ(st.code(), StatusCode::kNonFinite);
  EXPECT_EQ(st.index(), 5u);
  EXPECT_NE(std::string(st.message()).find("jaw 1 has a non-finite vertex"), std::string::npos)
      << st.message();
}

TEST(Sweep, RegionGivesTheSameSurfaceInsideIt) {
  // Cutting the grid to a region changes nothing inside it: the samples are the same lattice
  // points with the same values, so the clipped surface's vertices away from the region's caps
  // are vertices of the whole sweep (to the last bits of the grid origin's arithmetic).
  TestArena ta(size_t{512} << 20);
  Context ctx(&ta.arena);
  Mesh cone(&ta.arena);
  frustum(&cone, 2.0, 3.0, 0.0, 4.0, 90);
  SweepOptions o;
  o.direction = Vec3{0, 0, -1};
  o.voxel = 0.2;
  o.extent = 3.0;
  Mesh whole(&ta.arena);
  SPLINTCORE_ASSERT_OK(sweep_volume_mesh(ctx, Span<const Mesh>(&cone, 1), o, &whole));
  SweepOptions r = o;
  r.has_region = true;
  r.region.lo = Vec3{-1.0, -4.0, 1.0};
  r.region.hi = Vec3{4.0, 4.0, 3.0};
  Mesh part(&ta.arena);
  SweepStats stats;
  SPLINTCORE_ASSERT_OK(sweep_volume_mesh(ctx, Span<const Mesh>(&cone, 1), r, &part, &stats));
  double volume = 0;
  SPLINTCORE_ASSERT_OK(check_closed_oriented(ctx, part, &volume));
  EXPECT_GT(stats.preroll_layers, 0u);
  std::vector<Vec3> all(whole.vertices.begin(), whole.vertices.end());
  auto less = [](const Vec3& a, const Vec3& b) {
    return a.x != b.x ? a.x < b.x : (a.y != b.y ? a.y < b.y : a.z < b.z);
  };
  std::sort(all.begin(), all.end(), less);
  size_t inner = 0, missing = 0;
  for (const Vec3& p : part.vertices) {
    const double pad = 0.5;  // away from the region's caps
    if (p.x < r.region.lo.x + pad || p.x > r.region.hi.x - pad || p.y < r.region.lo.y + pad ||
        p.y > r.region.hi.y - pad || p.z < r.region.lo.z + pad || p.z > r.region.hi.z - pad) {
      continue;
    }
    ++inner;
    auto it = std::lower_bound(all.begin(), all.end(), p - Vec3{1e-9, 0, 0}, less);
    bool found = false;
    for (; it != all.end() && it->x <= p.x + 1e-9; ++it) {
      if (length(*it - p) <= 1e-9) found = true;
    }
    if (!found) ++missing;
  }
  EXPECT_GT(inner, 100u);
  EXPECT_EQ(missing, 0u);

  // Open at the region: the same surface without the caps; its border lies outside the
  // region (what a Boolean with A inside the region needs).
  SweepOptions open = r;
  open.open_at_region = true;
  Mesh cut(&ta.arena);
  SweepStats open_stats;
  SPLINTCORE_ASSERT_OK(sweep_volume_mesh(ctx, Span<const Mesh>(&cone, 1), open, &cut, &open_stats));
  EXPECT_GT(open_stats.cap_triangles_dropped, 0u);
  EXPECT_EQ(cut.triangles.size() + open_stats.cap_triangles_dropped, part.triangles.size());
  MeshReport report;
  SPLINTCORE_ASSERT_OK(check_mesh(ctx, cut, &report));
  EXPECT_GT(report.boundary_edges, 0u);
  EXPECT_EQ(report.nonmanifold_edges, 0u);
  EXPECT_EQ(report.orientation_conflicts, 0u);
  EXPECT_EQ(report.unreferenced_vertices, 0u);
  // Every vertex on the border is outside the region's box.
  std::vector<std::pair<uint64_t, int>> edges;
  for (const Triangle& t : cut.triangles) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = t.v[k], b = t.v[(k + 1) % 3];
      edges.push_back({(uint64_t{std::min(a, b)} << 32) | std::max(a, b), a < b ? 1 : -1});
    }
  }
  std::sort(edges.begin(), edges.end());
  size_t border = 0;
  for (size_t i = 0; i < edges.size();) {
    size_t j = i;
    while (j < edges.size() && edges[j].first == edges[i].first) ++j;
    if (j - i == 1) {
      ++border;
      for (uint32_t v : {static_cast<uint32_t>(edges[i].first >> 32),
                         static_cast<uint32_t>(edges[i].first & 0xffffffffu)}) {
        EXPECT_FALSE(r.region.contains(cut.vertices[v])) << v;
      }
    }
    i = j;
  }
  EXPECT_EQ(border, report.boundary_edges);
}

}  // namespace
}  // namespace splintcore

namespace splintcore {
namespace {

using test::lock_report;
using test::LockReport;
using test::TestArena;

TEST(Blockout, IndependentCheckFindsTheUndercutBeforeAndNoneAfter) {
  TestArena ta(size_t{1} << 30);
  Context ctx(&ta.arena);
  Mesh cone(&ta.arena);
  frustum(&cone, 3.0, 5.0, 0.0, 8.0, 360);
  for (Vec3& p : cone.vertices) ASSERT_TRUE(round_to_float32(&p));
  const float lo[3] = {-7, -7, 4}, hi[3] = {7, 7, 10};
  Mesh box = box_mesh(&ta.arena, lo, hi);
  // The splint as the Boolean leaves it (box minus cone), then with the blockout.
  Mesh imprint;
  BooleanOptions bo;
  SPLINTCORE_ASSERT_OK(mesh_boolean(ctx, box, cone, bo, &imprint, nullptr));
  BlockoutOptions o;
  o.sweep.direction = Vec3{0, 0, -1};
  o.sweep.voxel = 0.1;
  o.sweep.inset = 0.05;
  Mesh blocked;
  SPLINTCORE_ASSERT_OK(blockout(ctx, imprint, Span<const Mesh>(&cone, 1), o, &blocked));
  const Vec3 d{0, 0, -1}, u{1, 0, 0}, v{0, 1, 0}, c{0, 0, 5};
  const LockReport before = lock_report(ta.arena, imprint, cone, d, u, v, c, 6.0, 60, 1e-3);
  const LockReport after = lock_report(ta.arena, blocked, cone, d, u, v, c, 6.0, 60, 1e-3);
  std::printf(
      "[ figures  ] undercut check, %zu lines through the cone: before %zu locked "
      "(longest %.3f mm), after %zu (longest %.4f mm)\n",
      before.lines_through_jaw, before.locked_lines, before.longest, after.locked_lines,
      after.longest);
  EXPECT_GT(before.locked_lines, 100u);
  EXPECT_GT(before.longest, 3.0);
  // After: what the inset leaves, on lines within the inset of the wall.
  EXPECT_LT(after.locked_lines, before.locked_lines / 10);
  // Every line still locked runs within the inset (plus the voxel error) of the wall.
  for (const Vec3& p : after.locked_at) {
    EXPECT_GT(std::sqrt(p.x * p.x + p.y * p.y), 5.0 - o.sweep.inset - 0.03) << p.x << " " << p.y;
  }
  EXPECT_EQ(after.lines_through_jaw, before.lines_through_jaw);
}

// The exact sweep (sweep_exact_mesh) of the big-end-up frustum along its axis: its one front
// face is the top cap (facing +z, against d = -z), its silhouette the rim; the surface is the
// cap and a wall down from each rim edge to beyond the region, open only at the walls' ends.
TEST(ExactSweep, BigEndUpConeGivesItsCapAndWallsOpenOnlyBeyondTheRegion) {
  TestArena ta(size_t{1} << 28);
  Context ctx(&ta.arena);
  Mesh cone(&ta.arena);
  const uint32_t n = 360;
  frustum(&cone, 3.0, 5.0, 0.0, 8.0, n);
  for (Vec3& p : cone.vertices) ASSERT_TRUE(round_to_float32(&p));
  const Aabb region{Vec3{-7, -7, 4}, Vec3{7, 7, 10}};
  Mesh swept;
  ExactSweepStats st;
  SPLINTCORE_ASSERT_OK(sweep_exact_mesh(ctx, cone, Vec3{0, 0, -2}, region, &swept, &st));
  EXPECT_EQ(st.front_triangles, n);  // the top cap's fan
  EXPECT_EQ(st.kept_triangles, n);
  EXPECT_EQ(st.walls, n);
  EXPECT_EQ(st.top_vertices, n);
  EXPECT_EQ(st.pinched_vertices, 0u);
  EXPECT_EQ(st.direction.z, -1.0);
  ASSERT_EQ(swept.triangles.size(), 3u * n);
  ASSERT_EQ(swept.vertices.size(), 2u * n + 1);
  // Every edge twice, once each way, but the walls' ends, whose corners lie beyond the region.
  std::vector<std::array<uint32_t, 2>> edges;
  for (const Triangle& t : swept.triangles) {
    for (int k = 0; k < 3; ++k) edges.push_back({t.v[k], t.v[(k + 1) % 3]});
  }
  std::sort(edges.begin(), edges.end());
  size_t border = 0;
  for (const auto& e : edges) {
    EXPECT_EQ(std::count(edges.begin(), edges.end(), e), 1);
    if (std::binary_search(edges.begin(), edges.end(), std::array<uint32_t, 2>{e[1], e[0]})) {
      continue;
    }
    ++border;
    for (uint32_t v : e) EXPECT_LT(swept.vertices[v].z, region.lo.z - 1) << v;
  }
  EXPECT_EQ(border, n);
  // The cap's vertices are the cone's, bit for bit; the tops sit straight below them.
  for (size_t v = 0; v < swept.vertices.size(); ++v) {
    EXPECT_TRUE(is_float32_exact(swept.vertices[v])) << v;
  }
  SelfIntersectionReport si;
  SPLINTCORE_ASSERT_OK(find_self_intersections(ctx, swept, 0, &si));
  EXPECT_FALSE(si.self_intersecting());
}

// The exact blockout of that cone from a box (the splint may be the base itself: the sweep
// holds the jaw): the cylinder below the rim comes out exactly, the volume is the box's less
// the rim polygon's area times the box's height below the cap, and the independent line check finds
// no line locked, with no inset (the voxel sweep leaves its inset's worth).
TEST(ExactSweep, BlockoutOfTheConeIsTheBoxLessTheRimsCylinderAndUnlocked) {
  TestArena ta(size_t{1} << 30);
  Context ctx(&ta.arena);
  Mesh cone(&ta.arena);
  const uint32_t n = 360;
  frustum(&cone, 3.0, 5.0, 0.0, 8.0, n);
  for (Vec3& p : cone.vertices) ASSERT_TRUE(round_to_float32(&p));
  const float lo[3] = {-7, -7, 4}, hi[3] = {7, 7, 10};
  Mesh box = box_mesh(&ta.arena, lo, hi);
  BlockoutOptions o;
  o.exact = true;
  o.sweep.direction = Vec3{0, 0, -1};
  Mesh blocked;
  BlockoutStats st;
  SPLINTCORE_ASSERT_OK(blockout(ctx, box, Span<const Mesh>(&cone, 1), o, &blocked, &st));
  EXPECT_EQ(st.swept_triangles, 3u * n);
  EXPECT_EQ(st.attempts, 1u);
  MeshReport report;
  SPLINTCORE_ASSERT_OK(check_mesh(ctx, blocked, &report));
  EXPECT_TRUE(report.closed() && report.edge_manifold() && report.outward());
  EXPECT_TRUE(st.boolean.self_intersection_checked);
  const double area = rim_area(cone, n);
  // The cone never rises above its cap (z = 8): the box keeps its top 2 mm.
  const double expected = 14.0 * 14.0 * 6.0 - area * 4.0;
  std::printf(
      "[ figures  ] exact blockout of the cone: volume %.9f, expected %.9f; %zu "
      "triangles\n",
      mesh_volume(blocked), expected, blocked.triangles.size());
  EXPECT_NEAR(mesh_volume(blocked), expected, 1e-9 * expected);
  expect_cone_unlocked(&ta.arena, blocked, cone);
}

// What blockout() refuses before it sweeps (each text pinned, the arena as it was): the exact
// sweep with an offset or with two jaws that have triangles, an output that is not empty, a
// splint with no vertices; and the exact sweep with no jaw triangles gives the splint back as
// it was.
TEST(ExactSweep, BlockoutRefusalsAndNoJawGiveTheSplintBack) {
  TestArena ta(size_t{64} << 20);
  Context ctx(&ta.arena);
  Mesh cones[2] = {Mesh(&ta.arena), Mesh(&ta.arena)};
  frustum(&cones[0], 3.0, 5.0, 0.0, 8.0, 32);
  frustum(&cones[1], 3.0, 5.0, 20.0, 28.0, 32);
  const float lo[3] = {-7, -7, 4}, hi[3] = {7, 7, 10};
  const Mesh box = box_mesh(&ta.arena, lo, hi);
  BlockoutOptions o;
  o.exact = true;
  o.sweep.direction = Vec3{0, 0, -1};
  const size_t used = ta.arena.used();
  auto refused = [&](const Mesh& splint, Span<const Mesh> jaws, const BlockoutOptions& options,
                     Mesh* out) {
    const Status s = blockout(ctx, splint, jaws, options, out, nullptr);
    EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
    EXPECT_EQ(ta.arena.used(), used);
    return std::string(s.message());
  };
  Mesh out;
  BlockoutOptions spacer = o;
  spacer.sweep.offset = 0.2;
  EXPECT_EQ(refused(box, Span<const Mesh>(cones, 1), spacer, &out),
            "blockout: the exact sweep has no offset (a spacer is the sampled one's)");
  EXPECT_EQ(refused(box, Span<const Mesh>(cones, 2), o, &out),
            "blockout: the exact sweep takes one jaw with triangles at a time");
  EXPECT_EQ(refused(Mesh(&ta.arena), Span<const Mesh>(cones, 1), o, &out),
            "blockout: the splint has no vertices");
  Mesh full(&ta.arena);
  ASSERT_TRUE(full.triangles.push_back(Triangle{{0, 1, 2}}));
  const size_t with_full = ta.arena.used();
  EXPECT_EQ(
      std::string(blockout(ctx, box, Span<const Mesh>(cones, 1), o, &full, nullptr).message()),
      "blockout: the output mesh must be empty");
  EXPECT_EQ(ta.arena.used(), with_full);
  // No jaw with triangles: nothing is swept, the splint comes back bit for bit.
  Mesh bare(&ta.arena);
  for (const Vec3& p : cones[0].vertices) ASSERT_TRUE(bare.vertices.push_back(p));
  Mesh same;
  BlockoutStats st;
  SPLINTCORE_ASSERT_OK(blockout(ctx, box, Span<const Mesh>(&bare, 1), o, &same, &st));
  EXPECT_EQ(st.swept_triangles, 0u);
  ASSERT_EQ(same.triangles.size(), box.triangles.size());
  ASSERT_EQ(same.vertices.size(), box.vertices.size());
  EXPECT_EQ(std::memcmp(same.triangles.data(), box.triangles.data(),
                        box.triangles.size() * sizeof(Triangle)),
            0);
  EXPECT_EQ(
      std::memcmp(same.vertices.data(), box.vertices.data(), box.vertices.size() * sizeof(Vec3)),
      0);
}

// Front triangles whose prism cannot reach the region are left out, with no wall where they
// were (the shell is open there, beyond the region); a direction along which the region lies
// ahead keeps them. A tilted direction still gives a valid open surface.
TEST(ExactSweep, TrianglesThatCannotReachTheRegionAreLeftOut) {
  TestArena ta(size_t{1} << 28);
  Context ctx(&ta.arena);
  // A strip of 20 unit squares along x at z = 0, facing down (each a box's bottom face).
  Mesh fine(&ta.arena);
  {
    std::vector<SoupTriangle> soup;
    for (int i = 0; i < 20; ++i) {
      const float a[3] = {static_cast<float>(i), 0, 0}, b[3] = {static_cast<float>(i + 1), 2, 2};
      for (const SoupTriangle& t : shapes::box(a, b)) {
        const bool bottom = t.p[0][2] == 0 && t.p[1][2] == 0 && t.p[2][2] == 0;
        if (bottom) soup.push_back(t);
      }
    }
    SPLINTCORE_ASSERT_OK(
        weld_exact(ctx, Span<const SoupTriangle>(soup.data(), soup.size()), &fine));
  }
  const Aabb region{Vec3{-1, -1, 1}, Vec3{10.5f, 3, 5}};
  Mesh up;
  ExactSweepStats st;
  SPLINTCORE_ASSERT_OK(sweep_exact_mesh(ctx, fine, Vec3{0, 0, 1}, region, &up, &st));
  EXPECT_EQ(st.front_triangles, 40u);
  EXPECT_EQ(st.kept_triangles, 22u);  // the slabs from x = 0 to 11 (the last one reaches 10.5)
  EXPECT_EQ(st.walls, 2u * 11 + 1);   // the strip's sides and its end at x = 0; none at x = 11
  for (const Triangle& t : up.triangles) {
    for (uint32_t v : t.v) EXPECT_LE(up.vertices[v].x, 11.0);
  }
  // "Strictly beyond": a region whose sides run through slab corners (x = 5 and x = 11) keeps
  // the slabs that only touch them, [4, 5] and [11, 12], beside those from 5 to 11; with the
  // corners of every triangle rotated in turn, so that the touching corner takes each place.
  for (uint32_t turn = 0; turn < 3; ++turn) {
    SCOPED_TRACE(turn);
    Mesh turned(&ta.arena);
    for (const Vec3& v : fine.vertices) ASSERT_TRUE(turned.vertices.push_back(v));
    for (const Triangle& t : fine.triangles) {
      ASSERT_TRUE(turned.triangles.push_back(
          Triangle{{t.v[turn], t.v[(turn + 1) % 3], t.v[(turn + 2) % 3]}}));
    }
    const Aabb touching{Vec3{5, -1, 1}, Vec3{11, 3, 5}};
    Mesh out;
    ExactSweepStats s;
    SPLINTCORE_ASSERT_OK(sweep_exact_mesh(ctx, turned, Vec3{0, 0, 1}, touching, &out, &s));
    EXPECT_EQ(s.kept_triangles, 2u * 8);
  }
  // Along +x the region lies ahead of every slab beyond it: all are kept.
  Mesh along;
  ExactSweepStats st2;
  SPLINTCORE_ASSERT_OK(sweep_exact_mesh(ctx, fine, Vec3{-1, 0, 1}, region, &along, &st2));
  EXPECT_EQ(st2.kept_triangles, 40u);
  SelfIntersectionReport si;
  SPLINTCORE_ASSERT_OK(find_self_intersections(ctx, along, 0, &si));
  EXPECT_FALSE(si.self_intersecting());
}

// The phantom's jaws at 20k triangles under a slab where the splint would be, each blocked
// out along the direction it leaves the splint: the mandible's front side folds over itself
// at its zigzag silhouettes (a back sliver between two front fans), where its back triangles
// are taken in; both come out valid solids that the independent line check finds unlocked,
// where the plain imprint is locked on its undercuts.
TEST(ExactSweep, PhantomJawsAreUnlockedFoldsIncluded) {
  TestArena ta(size_t{1} << 30);
  Context ctx(&ta.arena);
  Mesh jaws[2];
  ASSERT_TRUE(test::phantom_jaw_meshes(ta.arena, 20000, jaws));
  const float lo[3] = {-28.5f, -8, -1.6f}, hi[3] = {28.5f, 45.5f, 1.6f};
  Mesh slab = box_mesh(&ta.arena, lo, hi);
  for (int j = 0; j < 2; ++j) {
    BlockoutOptions o;
    o.exact = true;
    const Vec3 d{0, 0, j == 0 ? 1.0 : -1.0};
    o.sweep.direction = d;
    Mesh blocked;
    BlockoutStats st;
    SPLINTCORE_ASSERT_OK(blockout(ctx, slab, Span<const Mesh>(&jaws[j], 1), o, &blocked, &st));
    EXPECT_EQ(st.exact.pinched_vertices, 0u);
    EXPECT_GT(st.exact.walls, 100u);
    MeshReport report;
    SPLINTCORE_ASSERT_OK(check_mesh(ctx, blocked, &report));
    EXPECT_TRUE(require_valid_solid(report).is_ok());
    const Vec3 u{1, 0, 0}, v{0, 1, 0}, c{0, 18, 0};
    const LockReport lock = lock_report(ta.arena, blocked, jaws[j], d, u, v, c, 27.0, 120, 1e-4);
    Mesh plain;
    SPLINTCORE_ASSERT_OK(mesh_boolean(ctx, slab, jaws[j], BooleanOptions{}, &plain, nullptr));
    const LockReport before = lock_report(ta.arena, plain, jaws[j], d, u, v, c, 27.0, 120, 1e-4);
    std::printf(
        "[ figures  ] exact blockout of the phantom's jaw %d: %zu triangles (%llu swept, "
        "%llu fold vertices, %llu back triangles taken in), %zu lines through the jaw, "
        "%zu locked (longest %.2g mm); the plain imprint %zu locked (longest %.3f mm)\n",
        j, blocked.triangles.size(), static_cast<unsigned long long>(st.swept_triangles),
        static_cast<unsigned long long>(st.exact.fold_vertices),
        static_cast<unsigned long long>(st.exact.absorbed_triangles), lock.lines_through_jaw,
        lock.locked_lines, lock.longest, before.locked_lines, before.longest);
    EXPECT_GT(lock.lines_through_jaw, 3000u);
    EXPECT_EQ(lock.locked_lines, 0u);
    EXPECT_GT(before.locked_lines, 50u);
  }
}

// A slab reaching up the phantom's necks (its crowns are big-end-up, the gum ridge wider
// above): taking the neck band in as a fold would leave the undercut itself unswept, so the
// exact sweep stops (kUnsupported, naming the triangle and where), and so does the blockout;
// the slab as deep as the design's base is swept (the test above).
TEST(ExactSweep, AnOverhangIsRefusedNotTakenInAsAFold) {
  TestArena ta(size_t{1} << 30);
  Context ctx(&ta.arena);
  Mesh jaws[2];
  ASSERT_TRUE(test::phantom_jaw_meshes(ta.arena, 20000, jaws));
  const float lo[3] = {-28.5f, -8, -1.6f}, hi[3] = {28.5f, 45.5f, 5.0f};
  Mesh slab = box_mesh(&ta.arena, lo, hi);
  const Aabb region = boolean_region(slab, BooleanOptions{});
  Mesh swept;
  ExactSweepStats es;
  const Status s = sweep_exact_mesh(ctx, jaws[0], Vec3{0, 0, 1}, region, &swept, &es);
  EXPECT_EQ(s.code(), StatusCode::kUnsupported) << test::format(s);
  EXPECT_NE(std::strstr(s.message(), "mm of undercut unswept"), nullptr) << s.message();
  EXPECT_NE(s.index(), kNoPosition);
  EXPECT_TRUE(swept.triangles.empty());
  EXPECT_GT(es.absorbed_triangles, 100u);  // the rounds took the band in before the check
  EXPECT_GE(es.fold_rounds, 1u);
  EXPECT_GE(es.fold_vertices, 1u);
  BlockoutOptions o;
  o.exact = true;
  o.sweep.direction = Vec3{0, 0, 1};
  Mesh blocked;
  const Status b = blockout(ctx, slab, Span<const Mesh>(&jaws[0], 1), o, &blocked, nullptr);
  EXPECT_EQ(b.code(), StatusCode::kUnsupported) << test::format(b);
  EXPECT_EQ(std::strncmp(b.message(), "blockout: exact sweep:", 22), 0) << b.message();
  EXPECT_TRUE(blocked.triangles.empty());
}

// A fold wider than the bound seen along d, with and without front surface within the bound
// over it. A fan of six front triangles (facing -z, against d = +z) around v at the origin,
// its rim at radius 1, except that w1 is turned back past w0 (to -20 degrees): the triangle
// (v, w1, w0) faces +z (a back triangle about 0.34 mm wide seen along d) and (v, w2, w1) spans
// 140 degrees, over v's wall to w0, so v is a fold and the back triangle is taken in. Over its
// centroid lies (v, w2, w1), at height 0.177 of w2's (w5 is below: (v, w0, w5) lies under the
// centroid and does not cover it). With w2 at z = `w2_height`, the pocket is that deep there.
Mesh fold_fan(Arena* arena, double w2_height) {
  Mesh m(arena);
  const double kDeg = 3.14159265358979323846 / 180;
  const double angle[6] = {0, -20, 120, 180, 240, 300};
  const double height[6] = {0, 0, w2_height, 0, 0, -0.5};
  SPLINTCORE_ASSERT(m.vertices.push_back(Vec3{0, 0, 0}));
  for (int k = 0; k < 6; ++k) {
    SPLINTCORE_ASSERT(m.vertices.push_back(
        Vec3{std::cos(angle[k] * kDeg), std::sin(angle[k] * kDeg), height[k]}));
  }
  for (uint32_t k = 0; k < 6; ++k) {
    SPLINTCORE_ASSERT(m.triangles.push_back(Triangle{{0, 1 + (k + 1) % 6, 1 + k}}));
  }
  return m;
}

TEST(ExactSweep, AFoldPocketNoDeeperThanTheBoundIsTakenInADeeperOneRefused) {
  TestArena ta(size_t{16} << 20);
  Context ctx(&ta.arena);
  Aabb region;
  region.add(Vec3{-2, -2, -1});
  region.add(Vec3{2, 2, 3});
  const Vec3 d{0, 0, 1};
  for (const double w2 : {0.06, 0.27, 0.29, 2.0}) {
    SCOPED_TRACE(w2);
    const Mesh fan = fold_fan(&ta.arena, w2);
    for (uint32_t t = 0; t < 6; ++t) {  // the one back triangle, as the comment says
      const Triangle& g = fan.triangles[t];
      const double nz =
          normal_dot(fan.vertices[g.v[0]], fan.vertices[g.v[1]], fan.vertices[g.v[2]], d);
      EXPECT_EQ(nz > 0, t == 0) << t;
    }
    const Arena::Marker before = ta.arena.mark();
    Mesh swept;
    ExactSweepStats es;
    const Status s = sweep_exact_mesh(ctx, fan, d, region, &swept, &es);
    // One round, at v, w0 and w5 (the rim folds over the fan there too). The next finds w0
    // and w5 again with no back triangle left around them and stops: it went on to the 64th
    // round, counting them each time.
    EXPECT_EQ(es.fold_rounds, 1u);
    EXPECT_EQ(es.fold_vertices, 3u);
    EXPECT_EQ(es.absorbed_triangles, 1u);
    EXPECT_EQ(es.pockets_checked, 1u);
    // 0.177 of w2's height over the centroid: within 0.05 mm up to w2 = 0.28 mm.
    if (w2 < 0.28) {
      SPLINTCORE_EXPECT_OK(s);
      EXPECT_EQ(es.pockets_shallow, 1u);
      EXPECT_EQ(swept.triangles.size(), 6u + 2 * es.walls);  // every triangle kept
    } else {
      EXPECT_EQ(s.code(), StatusCode::kUnsupported) << test::format(s);
      EXPECT_NE(std::strstr(s.message(), "mm of undercut unswept"), nullptr) << s.message();
      EXPECT_EQ(s.index(), 0u);  // the back triangle
      EXPECT_EQ(es.pockets_shallow, 0u);
      EXPECT_TRUE(swept.triangles.empty());
    }
    ta.arena.rewind(before);
  }
  // The fold taken in at every 8-byte cap below its peak: a clean kArenaExhausted, or the
  // same bytes.
  const Mesh fan = fold_fan(&ta.arena, 0.06);
  auto sweep_fan = [&](Arena& a, Mesh* m) {
    return sweep_exact_mesh(Context(&a), fan, d, region, m);
  };
  const test::AmpleRun ample = test::ample_run(size_t{1} << 20, sweep_fan);
  ASSERT_TRUE(ample.ok);
  const test::CapsTried tried =
      test::expect_clean_or_same(test::caps_below(ample.peak, 8), ample.sha, sweep_fan);
  EXPECT_EQ(tried.failed, tried.tried);
}

// The neck band's pockets again, now with the splint a plate that only the crowns' tips
// reach and a pillar beside the arch reaching above the necks: the region (the splint's box)
// takes the band in, but no pocket's column along d meets the splint, so the blockout takes
// them in (ExactPocketTest) where the sweep alone stops; the tips' imprint is cut, the pillar
// is left whole, nothing is locked.
TEST(ExactSweep, PocketsClearOfTheSplintAreTakenIn) {
  TestArena ta(size_t{1} << 30);
  Context ctx(&ta.arena);
  Mesh jaws[2];
  ASSERT_TRUE(test::phantom_jaw_meshes(ta.arena, 20000, jaws));
  double tips = HUGE_VAL;  // the crowns' lowest point
  for (const Vec3& p : jaws[0].vertices) tips = std::fmin(tips, p.z);
  const float lo[3] = {-28.5f, -8, -3}, hi[3] = {28.5f, 45.5f, static_cast<float>(tips + 0.3)};
  const float plo[3] = {27.5f, -8, 2}, phi[3] = {28.5f, -7, 5};
  Mesh plate = box_mesh(&ta.arena, lo, hi);
  Mesh splint = box_mesh(&ta.arena, lo, hi);
  const Mesh pillar = box_mesh(&ta.arena, plo, phi);
  ASSERT_TRUE(append_mesh(&splint, pillar));
  const Vec3 d{0, 0, 1};
  Mesh swept;
  ExactSweepStats es;
  const Status s =
      sweep_exact_mesh(ctx, jaws[0], d, boolean_region(splint, BooleanOptions{}), &swept, &es);
  EXPECT_EQ(s.code(), StatusCode::kUnsupported) << test::format(s);
  BlockoutOptions o;
  o.exact = true;
  o.sweep.direction = d;
  Mesh alone, blocked;
  BlockoutStats sa, st;
  SPLINTCORE_ASSERT_OK(blockout(ctx, plate, Span<const Mesh>(&jaws[0], 1), o, &alone, &sa));
  SPLINTCORE_ASSERT_OK(blockout(ctx, splint, Span<const Mesh>(&jaws[0], 1), o, &blocked, &st));
  EXPECT_EQ(sa.exact.pockets_clear, 0u);
  EXPECT_GT(st.exact.pockets_clear, 10u);
  // Every pocket found clear or shallow was checked first (the report's counts).
  EXPECT_GE(st.exact.pockets_checked, st.exact.pockets_clear + st.exact.pockets_shallow);
  EXPECT_GE(sa.exact.pockets_checked, sa.exact.pockets_clear + sa.exact.pockets_shallow);
  EXPECT_GT(st.exact.absorbed_triangles, sa.exact.absorbed_triangles + 100);  // the band
  MeshReport alone_report, report;
  SPLINTCORE_ASSERT_OK(check_mesh(ctx, alone, &alone_report));
  SPLINTCORE_ASSERT_OK(check_mesh(ctx, blocked, &report));
  EXPECT_TRUE(require_valid_solid(report).is_ok());
  EXPECT_EQ(report.shells, alone_report.shells + 1);
  EXPECT_NEAR(report.volume, alone_report.volume + 3.0, 1e-6);  // the pillar, 1 x 1 x 3 mm
  const double whole = 57.0 * 53.5 * (static_cast<double>(hi[2]) + 3);
  EXPECT_LT(alone_report.volume, whole - 1.0);  // the tips' imprint
  const Vec3 u{1, 0, 0}, v{0, 1, 0}, c{0, 18, 0};
  const LockReport lock = lock_report(ta.arena, blocked, jaws[0], d, u, v, c, 27.0, 120, 1e-4);
  std::printf(
      "[ figures  ] plate and pillar: %llu of %llu taken-in triangles' pockets wider and deeper "
      "than the bound, clear of the splint; the imprint %.3f mm^3; %zu lines through the jaw, "
      "%zu locked\n",
      static_cast<unsigned long long>(st.exact.pockets_clear),
      static_cast<unsigned long long>(st.exact.absorbed_triangles), whole - alone_report.volume,
      lock.lines_through_jaw, lock.locked_lines);
  EXPECT_GT(lock.lines_through_jaw, 3000u);
  EXPECT_EQ(lock.locked_lines, 0u);
  // A speck of splint (a 2 um cube) floating in one such pocket's column, 0.5 mm above its
  // triangle, further from the column's sides than the reach: no face of the prism comes near
  // it, but the splint is there, and the pocket is refused, by name.
  struct Asked {
    static Status clear(void* user, const Vec3 p[3], bool* is_clear) {
      if (static_cast<std::vector<Vec3>*>(user)->empty()) {
        static_cast<std::vector<Vec3>*>(user)->assign(p, p + 3);
      }
      *is_clear = true;
      return Status::ok();
    }
  };
  std::vector<Vec3> pocket;
  ExactPocketTest asked;
  asked.clear = Asked::clear;
  asked.user = &pocket;
  Mesh taken;
  SPLINTCORE_ASSERT_OK(sweep_exact_mesh(ctx, jaws[0], d, boolean_region(splint, BooleanOptions{}),
                                        &taken, nullptr, &asked));
  ASSERT_EQ(pocket.size(), 3u);
  const Vec3 at = (pocket[0] + pocket[1] + pocket[2]) * (1.0 / 3) + d * 0.5;
  const float slo[3] = {static_cast<float>(at.x - 1e-3), static_cast<float>(at.y - 1e-3),
                        static_cast<float>(at.z - 1e-3)};
  const float shi[3] = {static_cast<float>(at.x + 1e-3), static_cast<float>(at.y + 1e-3),
                        static_cast<float>(at.z + 1e-3)};
  const Mesh speck = box_mesh(&ta.arena, slo, shi);
  for (int k = 0; k < 2; ++k) {  // the speck is within the triangle's box seen along d (z)
    EXPECT_GT(slo[k], std::fmin(pocket[0][k], std::fmin(pocket[1][k], pocket[2][k])));
    EXPECT_LT(shi[k], std::fmax(pocket[0][k], std::fmax(pocket[1][k], pocket[2][k])));
  }
  ASSERT_TRUE(append_mesh(&splint, speck));
  Mesh refused;
  const Status r = blockout(ctx, splint, Span<const Mesh>(&jaws[0], 1), o, &refused, nullptr);
  EXPECT_EQ(r.code(), StatusCode::kUnsupported) << test::format(r);
  EXPECT_NE(std::strstr(r.message(), "mm of undercut unswept"), nullptr) << r.message();
  EXPECT_TRUE(refused.triangles.empty());
}

// An open helicoid, 1.25 turns rising 1 mm a turn between radii 1 and 2 (float32 vertices),
// facing +z: seen along -z its last quarter turn lies over its first, so one front patch
// overhangs itself a whole turn away (far beyond the fold rounds' rings), and the walls of its
// upper turn go down through the lower one.
Mesh helicoid(Arena* arena) {
  Mesh m(arena);
  const uint32_t steps = 300, rings = 3;  // 1.25 turns, radii 1, 1.5, 2
  for (uint32_t j = 0; j <= steps; ++j) {
    const double t = 2.5 * 3.14159265358979323846 * j / steps;
    for (uint32_t i = 0; i < rings; ++i) {
      Vec3 p{(1.0 + 0.5 * i) * std::cos(t), (1.0 + 0.5 * i) * std::sin(t), t / 6.283185307};
      EXPECT_TRUE(round_to_float32(&p));
      EXPECT_TRUE(m.vertices.push_back(p));
    }
  }
  for (uint32_t j = 0; j < steps; ++j) {
    for (uint32_t i = 0; i + 1 < rings; ++i) {
      const uint32_t a = j * rings + i, b = a + 1, c = a + rings, e = c + 1;
      EXPECT_TRUE(m.triangles.push_back(Triangle{{a, b, e}}));  // normal up (+z)
      EXPECT_TRUE(m.triangles.push_back(Triangle{{a, e, c}}));
    }
  }
  return m;
}

// The exact sweep's crossing shells: where the wrong parts of a crossing (the walls below the
// crossing, the hidden part of the lower turn) reach into the splint (a plate below the whole
// helicoid), the blockout refuses it, naming where; where they stay outside it (a plate below
// the half turn that has no overlap above it, its box reaching the overlap only through a
// pillar outside the helicoid), the crossing is counted and the splint is the Boolean's:
// a valid solid with the helicoid's annulus cut through the plate.
TEST(ExactSweep, AShellCrossingItselfIsRefusedOnlyWhereItMeetsTheSplint) {
  TestArena ta(size_t{1} << 30);
  Context ctx(&ta.arena);
  const Mesh jaw = helicoid(&ta.arena);
  BlockoutOptions o;
  o.exact = true;
  o.sweep.direction = Vec3{0, 0, -1};
  ExactSweepStats es;
  {
    const float lo[3] = {-3, -3, -3}, hi[3] = {3, 3, -1};
    const Mesh plate = box_mesh(&ta.arena, lo, hi);
    Mesh out;
    BlockoutStats st;
    const Status s = blockout(ctx, plate, Span<const Mesh>(&jaw, 1), o, &out, &st);
    EXPECT_EQ(s.code(), StatusCode::kUnsupported) << test::format(s);
    EXPECT_NE(std::strstr(s.message(), "crosses itself inside the splint"), nullptr) << s.message();
    EXPECT_TRUE(out.triangles.empty());
    EXPECT_EQ(st.exact.fold_vertices, 0u);  // nothing the rounds could see
    es = st.exact;
  }
  EXPECT_EQ(es.walls, 2u * 300 + 2 * 2);  // both rims and both ends
  const float lo[3] = {-3, -3, -3}, hi[3] = {-0.25f, -0.25f, -1};
  const float plo[3] = {2.75f, 2.75f, -3}, phi[3] = {3, 3, 1};
  Mesh splint = box_mesh(&ta.arena, lo, hi);
  const Mesh pillar = box_mesh(&ta.arena, plo, phi);
  ASSERT_TRUE(append_mesh(&splint, pillar));
  Mesh out;
  BlockoutStats st;
  SPLINTCORE_ASSERT_OK(blockout(ctx, splint, Span<const Mesh>(&jaw, 1), o, &out, &st));
  EXPECT_EQ(st.exact.shells_crossing_outside, 1u);
  MeshReport report;
  SPLINTCORE_ASSERT_OK(check_mesh(ctx, out, &report));
  EXPECT_TRUE(report.is_valid_solid());
  EXPECT_EQ(report.shells, 3u);  // the annulus cuts the plate's corner off; the pillar
  // Plate and pillar 15.375 mm^3, less the annulus over the plate, 2 x 1.85354 mm^2 for the
  // circles (a grid of 4000^2 cells); the helicoid's chords (1.5 degrees) take 0.02% less.
  EXPECT_NEAR(report.volume, 11.6679, 0.002);
}

// A cylinder along the direction: its sides are parallel to it (normal . d exactly 0), so
// only the cap facing against d is front, either way along the axis.
TEST(ExactSweep, SidesAlongTheDirectionAreNotFront) {
  TestArena ta(size_t{1} << 24);
  Context ctx(&ta.arena);
  Mesh cylinder(&ta.arena);
  frustum(&cylinder, 3.0, 3.0, 0.0, 8.0, 64);
  const Aabb region{Vec3{-7, -7, -4}, Vec3{7, 7, 12}};
  for (double dz : {-1.0, 1.0}) {
    ArenaScope scope(ta.arena);
    Mesh out;
    ExactSweepStats st;
    SPLINTCORE_ASSERT_OK(sweep_exact_mesh(ctx, cylinder, Vec3{0, 0, dz}, region, &out, &st));
    EXPECT_EQ(st.front_triangles, 64u) << dz;
  }
}

TEST(ExactSweep, BadInputIsNamedAndTheArenaBoundHolds) {
  TestArena ta(size_t{1} << 28);
  Context ctx(&ta.arena);
  Mesh cone(&ta.arena);
  frustum(&cone, 3.0, 5.0, 0.0, 8.0, 64);
  const Aabb region{Vec3{-7, -7, 4}, Vec3{7, 7, 10}};
  Mesh out;
  EXPECT_EQ(sweep_exact_mesh(ctx, cone, Vec3{0, 0, 0}, region, &out).code(),
            StatusCode::kInvalidArgument);
  EXPECT_EQ(sweep_exact_mesh(ctx, cone, Vec3{0, std::nan(""), 1}, region, &out).code(),
            StatusCode::kInvalidArgument);
  EXPECT_EQ(sweep_exact_mesh(ctx, cone, Vec3{0, 0, 1}, Aabb{}, &out).code(),
            StatusCode::kInvalidArgument);
  // A region empty but finite (lo above hi), and one not empty but reaching infinity.
  EXPECT_EQ(
      sweep_exact_mesh(ctx, cone, Vec3{0, 0, 1}, Aabb{Vec3{1, 1, 1}, Vec3{0, 0, 0}}, &out).code(),
      StatusCode::kInvalidArgument);
  const Aabb endless{Vec3{-7, -7, 4}, Vec3{7, 7, std::numeric_limits<double>::infinity()}};
  EXPECT_EQ(sweep_exact_mesh(ctx, cone, Vec3{0, 0, 1}, endless, &out).code(),
            StatusCode::kInvalidArgument);
  // An output with only vertices, or only triangles, is not empty.
  for (int part = 0; part < 2; ++part) {
    Mesh used(&ta.arena);
    const bool pushed =
        part == 0 ? used.vertices.push_back(Vec3{}) : used.triangles.push_back(Triangle{{0, 0, 0}});
    ASSERT_TRUE(pushed);
    EXPECT_EQ(sweep_exact_mesh(ctx, cone, Vec3{0, 0, 1}, region, &used).code(),
              StatusCode::kInvalidArgument);
  }
  Mesh bad(&ta.arena);
  for (const Vec3& p : cone.vertices) ASSERT_TRUE(bad.vertices.push_back(p));
  for (const Triangle& t : cone.triangles) ASSERT_TRUE(bad.triangles.push_back(t));
  bad.triangles[5].v[1] = 9999;
  Status s = sweep_exact_mesh(ctx, bad, Vec3{0, 0, 1}, region, &out);
  EXPECT_EQ(s.code(), StatusCode::kInvalidMesh);
  EXPECT_EQ(s.index(), 5u);
  bad.triangles[5].v[1] = static_cast<uint32_t>(bad.vertices.size());  // one past the last
  s = sweep_exact_mesh(ctx, bad, Vec3{0, 0, 1}, region, &out);
  EXPECT_EQ(s.code(), StatusCode::kInvalidMesh);
  EXPECT_STREQ(s.message(), "exact sweep: triangle 5 has a vertex id out of range");
  bad.triangles[5] = cone.triangles[5];
  bad.vertices[7].y = std::numeric_limits<double>::infinity();
  s = sweep_exact_mesh(ctx, bad, Vec3{0, 0, 1}, region, &out);
  EXPECT_EQ(s.code(), StatusCode::kNonFinite);
  EXPECT_EQ(s.index(), 7u);
  EXPECT_TRUE(out.triangles.empty() && out.vertices.empty());
  // In exactly the bound's bytes it runs; the output is the same as with room to spare.
  Mesh roomy;
  SPLINTCORE_ASSERT_OK(sweep_exact_mesh(ctx, cone, Vec3{0, 0, -1}, region, &roomy));
  const uint64_t need = sweep_exact_bound(cone.vertices.size(), cone.triangles.size());
  std::vector<unsigned char> buffer(static_cast<size_t>(need));
  Arena exact(buffer.data(), buffer.size());
  Context ectx(&exact);
  Mesh tight;
  SPLINTCORE_ASSERT_OK(sweep_exact_mesh(ectx, cone, Vec3{0, 0, -1}, region, &tight));
  ASSERT_EQ(tight.triangles.size(), roomy.triangles.size());
  EXPECT_EQ(std::memcmp(tight.triangles.data(), roomy.triangles.data(),
                        roomy.triangles.size() * sizeof(Triangle)),
            0);
  EXPECT_EQ(std::memcmp(tight.vertices.data(), roomy.vertices.data(),
                        roomy.vertices.size() * sizeof(Vec3)),
            0);
  // Every 8-byte cap below the peak: a clean kArenaExhausted, or the same bytes.
  auto sweep_cone = [&](Arena& a, Mesh* m) {
    return sweep_exact_mesh(Context(&a), cone, Vec3{0, 0, -1}, region, m);
  };
  const test::AmpleRun ample = test::ample_run(static_cast<size_t>(need), sweep_cone);
  ASSERT_TRUE(ample.ok);
  EXPECT_EQ(ample.sha, test::mesh_sha256(roomy));
  const test::CapsTried tried =
      test::expect_clean_or_same(test::caps_below(ample.peak, 8), ample.sha, sweep_cone);
  EXPECT_EQ(tried.failed, tried.tried);
  // Too small an arena: a clean status, nothing left behind.
  std::vector<unsigned char> small(2048);
  Arena tiny(small.data(), small.size());
  Context tctx(&tiny);
  Mesh none;
  EXPECT_EQ(sweep_exact_mesh(tctx, cone, Vec3{0, 0, -1}, region, &none).code(),
            StatusCode::kArenaExhausted);
  EXPECT_EQ(tiny.used(), 0u);
}

}  // namespace
}  // namespace splintcore

namespace splintcore {
namespace {

using test::TestArena;

TEST(Sweep, ClosingFillsAGapNarrowerThanItsDiameter) {
  // Two "teeth" (boxes) 0.3 mm apart: the closing with r = 0.3 mm fills the gap between them
  // (narrower than 2 r), not the 1.5 mm gap on the other side of the second tooth.
  TestArena ta(size_t{1} << 30);
  Context ctx(&ta.arena);
  Mesh teeth(&ta.arena);
  {
    std::vector<SoupTriangle> soup;
    const float a_lo[3] = {0, 0, 0}, a_hi[3] = {3, 3, 3};
    const float b_lo[3] = {3.3f, 0, 0}, b_hi[3] = {6.3f, 3, 3};
    const float c_lo[3] = {7.8f, 0, 0}, c_hi[3] = {10.8f, 3, 3};
    for (const auto* box : {&a_lo, &b_lo, &c_lo}) {
      const float* lo = *box;
      const float* hi = lo == a_lo ? a_hi : (lo == b_lo ? b_hi : c_hi);
      const std::vector<SoupTriangle> part = shapes::box(lo, hi);
      soup.insert(soup.end(), part.begin(), part.end());
    }
    SPLINTCORE_ASSERT_OK(
        weld_exact(ctx, Span<const SoupTriangle>(soup.data(), soup.size()), &teeth));
  }
  auto inside = [&](const Mesh& m, const Vec3& p) {
    DistanceIndex index;
    ArenaScope scope(ta.arena);
    EXPECT_TRUE(build_distance_index(ctx, m, DistanceIndexOptions{}, &index).is_ok());
    return winding_number(index, p, 0.0) > 0.5;
  };
  SweepOptions o;
  o.direction = Vec3{0, 0, 1};
  o.voxel = 0.1;
  o.extent = 1.0;
  Mesh open_gap(&ta.arena), closed(&ta.arena);
  SweepStats plain_stats, closed_stats;
  SPLINTCORE_ASSERT_OK(
      sweep_volume_mesh(ctx, Span<const Mesh>(&teeth, 1), o, &open_gap, &plain_stats));
  o.closing_radius = 0.3;
  SPLINTCORE_ASSERT_OK(
      sweep_volume_mesh(ctx, Span<const Mesh>(&teeth, 1), o, &closed, &closed_stats));
  double v_open = 0, v_closed = 0;
  SPLINTCORE_ASSERT_OK(check_closed_oriented(ctx, open_gap, &v_open));
  SPLINTCORE_ASSERT_OK(check_closed_oriented(ctx, closed, &v_closed));
  const Vec3 narrow{3.15, 1.5, 1.5}, wide{7.05, 1.5, 1.5}, beside{1.5, -0.5, 1.5};
  EXPECT_FALSE(inside(open_gap, narrow));
  EXPECT_TRUE(inside(closed, narrow));
  EXPECT_FALSE(inside(closed, wide));
  EXPECT_FALSE(inside(closed, beside));
  // The gap's volume (0.3 x 3 x 4 mm, less what stays open where it meets the outside) is
  // added, and little else: convex parts are unchanged by a closing.
  std::printf(
      "[ figures  ] closing r 0.3 mm: volume %.3f -> %.3f mm^3 (gap 0.3 x 3 x 4 = 3.6); "
      "%llu samples searched, %llu filled\n",
      v_open, v_closed, static_cast<unsigned long long>(closed_stats.closing_samples),
      static_cast<unsigned long long>(closed_stats.closed_samples));
  EXPECT_GT(v_closed - v_open, 2.5);
  EXPECT_LT(v_closed - v_open, 4.0);
}

}  // namespace
}  // namespace splintcore

namespace splintcore {
namespace {

using test::TestArena;

// A torus (R 4, r 1.5) tilted about x, as a jaw: curved everywhere, with a hole.
Mesh tilted_torus(Arena* arena) {
  Mesh m(arena);
  Context ctx(arena);
  const std::vector<SoupTriangle> soup = shapes::torus(96, 48, 4.0, 1.5);
  SPLINTCORE_ASSERT(
      weld_exact(ctx, Span<const SoupTriangle>(soup.data(), soup.size()), &m).is_ok());
  const double c = 0.8, s = 0.6;  // 36.87 degrees about x
  for (Vec3& p : m.vertices) p = Vec3{p.x, c * p.y - s * p.z, s * p.y + c * p.z};
  return m;
}

struct SideErrors {
  double outside_max = 0;  // the largest distance of a sample of `a` outside `b`
  double inside_max = 0;   // the largest depth of a sample of `a` inside `b`
  size_t samples = 0;
};

// Samples of a's triangles against the closed mesh b: signed distance (pseudonormals), split
// by side. step 2: the corners and the sides' midpoints; step 1: the barycentric quarters too,
// and then `coarse` (if given) gets the errors at the step-2 points alone (the same pass).
SideErrors sampled_errors(Arena& arena, const Mesh& a, const Mesh& b, int step = 2,
                          SideErrors* coarse = nullptr) {
  Context ctx(&arena);
  ArenaScope scope(arena);
  DistanceIndex index;
  EXPECT_TRUE(build_distance_index(ctx, b, DistanceIndexOptions{}, &index).is_ok());
  SideErrors e;
  for (const Triangle& t : a.triangles) {
    const Vec3& p0 = a.vertices[t.v[0]];
    const Vec3& p1 = a.vertices[t.v[1]];
    const Vec3& p2 = a.vertices[t.v[2]];
    for (int i = 0; i <= 4; i += step) {
      for (int j = 0; i + j <= 4; j += step) {
        const int k = 4 - i - j;
        const Vec3 q = (p0 * (i / 4.0) + p1 * (j / 4.0)) + p2 * (k / 4.0);
        SignedDistance sd;
        EXPECT_TRUE(signed_distance(index, q, SignMethod::kPseudonormal, &sd));
        const bool even = i % 2 == 0 && j % 2 == 0;
        for (SideErrors* x : {&e, coarse != nullptr && even ? coarse : nullptr}) {
          if (x == nullptr) continue;
          if (sd.distance >= 0) {
            x->outside_max = std::fmax(x->outside_max, sd.distance);
          } else {
            x->inside_max = std::fmax(x->inside_max, -sd.distance);
          }
          ++x->samples;
        }
      }
    }
  }
  return e;
}

// The decimation's error, measured (sampled both ways against the surface without it). The
// aim is one-sided and within a tenth of a voxel: the extraction decimate_error / 2 further
// out, decimated within decimate_error / 2 of it. decimate_qem keeps that bound at points
// (every extractor vertex, side midpoint and centroid to the result; the midpoint of every
// new side and the centroid of every new triangle to the extractor's surface): asserted on
// the same surface (the inset that puts the decimation's extraction at iso 0) at the corners
// and the sides' midpoints; between them, at the barycentric quarters, measured up to 1.7x the
// bound (asserted within 2x). Against the plain surface (iso 0) the cone's rim differs by the
// extractor's own error at a crease (0.045-0.051 mm, the same without decimation: two
// extractions at different isos), so that comparison asserts half a voxel; decimation stays
// off by default.
TEST(SweepDecimate, StaysWithinHalfAVoxelOfTheSurface) {
  TestArena ta(size_t{1} << 30);
  Context ctx(&ta.arena);
  Mesh cone(&ta.arena);
  frustum(&cone, 3.0, 5.0, 0.0, 8.0, 360);
  const Mesh torus = tilted_torus(&ta.arena);
  struct Shape {
    const char* name;
    const Mesh* jaw;
    Vec3 direction;
    double voxel;
  };
  // 0.15 mm voxels (0.1 took 80 s in Release, 2.2x the triangles): the bounds are relative to
  // the voxel.
  const Shape shapes[] = {{"tilted cone", &cone, {0.2, -0.1, -1}, 0.15},
                          {"torus", &torus, {0.1, 0.2, 1}, 0.15}};
  for (const Shape& sh : shapes) {
    SCOPED_TRACE(sh.name);
    ArenaScope scope(ta.arena);
    SweepOptions o;
    o.direction = sh.direction;
    o.voxel = sh.voxel;
    o.extent = 2.0;
    Mesh plain(&ta.arena), reduced(&ta.arena);
    SweepStats plain_stats, stats;
    SPLINTCORE_ASSERT_OK(
        sweep_volume_mesh(ctx, Span<const Mesh>(sh.jaw, 1), o, &plain, &plain_stats));
    o.decimate_error = o.voxel / 10;
    SPLINTCORE_ASSERT_OK(sweep_volume_mesh(ctx, Span<const Mesh>(sh.jaw, 1), o, &reduced, &stats));
    double v_plain = 0, v_reduced = 0;
    SPLINTCORE_ASSERT_OK(check_closed_oriented(ctx, plain, &v_plain));
    SPLINTCORE_ASSERT_OK(check_closed_oriented(ctx, reduced, &v_reduced));
    // The extractor's own count (of the surface decimate_error / 2 further out).
    EXPECT_GT(stats.undecimated_triangles, plain.triangles.size() * 99 / 100);
    EXPECT_LT(stats.undecimated_triangles, plain.triangles.size() * 101 / 100);
    EXPECT_GT(stats.decimated_tiles, 1u);
    // Both ways: the decimated surface against the plain one, and the plain one's samples
    // against the decimated (so neither has parts the other lacks).
    const SideErrors there = sampled_errors(ta.arena, reduced, plain);
    const SideErrors back = sampled_errors(ta.arena, plain, reduced);
    std::printf(
        "[ figures  ] %s: %zu -> %zu triangles (%.1fx, %llu tiles); decimated vs plain: out "
        "%.5f, in %.6f mm; plain vs decimated: in %.5f, out %.6f mm (bound %.4f); volume "
        "%.4f -> %.4f mm^3\n",
        sh.name, plain.triangles.size(), reduced.triangles.size(),
        static_cast<double>(plain.triangles.size()) / reduced.triangles.size(),
        static_cast<unsigned long long>(stats.decimated_tiles), there.outside_max, there.inside_max,
        back.inside_max, back.outside_max, o.decimate_error, v_plain, v_reduced);
    // The bound at the extractor's vertices, on the same surface: with inset = decimate_error
    // / 2 the decimation's extraction is at iso 0 exactly, the plain surface, so every plain
    // vertex must lie within decimate_error / 2 of the decimated one (the distance index's
    // closest point).
    {
      SweepOptions same = o;
      same.inset = o.decimate_error / 2;
      Mesh centred(&ta.arena);
      SweepStats centred_stats;
      SPLINTCORE_ASSERT_OK(
          sweep_volume_mesh(ctx, Span<const Mesh>(sh.jaw, 1), same, &centred, &centred_stats));
      EXPECT_EQ(centred_stats.undecimated_triangles, plain.triangles.size());
      DistanceIndex index;
      SPLINTCORE_ASSERT_OK(build_distance_index(ctx, centred, DistanceIndexOptions{}, &index));
      double worst_vertex = 0;
      for (const Vec3& q : plain.vertices) {
        ClosestPoint cp;
        ASSERT_TRUE(closest_point(index, q, &cp));
        worst_vertex = std::fmax(worst_vertex, cp.distance);
      }
      // Both ways at the corners and the sides' midpoints (where decimate_qem keeps the bound:
      // the input's vertices and midpoints, the result's new sides' midpoints), then at the
      // barycentric quarters, where nothing is proved (measured).
      SideErrors on, under;  // at the corners and midpoints, from the finer passes
      const SideErrors on_fine = sampled_errors(ta.arena, centred, plain, 1, &on);
      const SideErrors under_fine = sampled_errors(ta.arena, plain, centred, 1, &under);
      const double worst_kept = std::fmax(std::fmax(on.outside_max, on.inside_max),
                                          std::fmax(under.outside_max, under.inside_max));
      const double worst_fine = std::fmax(std::fmax(on_fine.outside_max, on_fine.inside_max),
                                          std::fmax(under_fine.outside_max, under_fine.inside_max));
      std::printf(
          "[ figures  ] %s, same surface: %zu -> %zu triangles; plain vertices to the decimated "
          "surface at most %.5f mm; both ways at corners and midpoints %.5f mm, at the "
          "barycentric quarters %.5f mm (bound %.4f)\n",
          sh.name, plain.triangles.size(), centred.triangles.size(), worst_vertex, worst_kept,
          worst_fine, o.decimate_error / 2);
      const double bound = o.decimate_error / 2 * (1 + 1e-9);
      EXPECT_LE(worst_vertex, bound);
      EXPECT_LE(worst_kept, bound);
      EXPECT_GT(worst_kept, o.decimate_error / 4);  // the bound is what stops it
      // Measured 0.0111 (cone) and 0.0125 mm (torus) at 0.15 mm voxels: up to 1.7x the bound.
      EXPECT_LE(worst_fine, 2 * o.decimate_error / 2);
    }
    EXPECT_LT(reduced.triangles.size() * 4, plain.triangles.size());
    EXPECT_LE(there.inside_max, 0.5 * o.voxel);
    EXPECT_LE(there.outside_max, 0.5 * o.voxel);
    EXPECT_LE(back.inside_max, 0.5 * o.voxel);
    EXPECT_LE(back.outside_max, 0.5 * o.voxel);
    // Outside on the whole: the iso moved out by decimate_error / 2 adds more volume than
    // the collapses take (area about 300 mm^2 x 0.005 mm).
    EXPECT_GT(v_reduced, v_plain);
  }
}

// Every slab size at one thread, two of them (one slab a tile, the default) at three threads,
// and the mesh variant once at three threads: seven sweeps where every pairing was sixteen (the
// test took 132 s at clang -O0).
// A visitor that keeps the streamed vertices (their ids must come in order, 0 up) and the
// triangles by id, the positions each gives agreeing with its vertices, and hashes the
// triangles as HashVisitor does.
struct IndexedVisitor {
  HashVisitor hash;
  std::vector<Vec3> vertices;
  std::vector<Triangle> triangles;
  bool consistent = true;
  static Status vertex(void* user, uint32_t id, const Vec3& p) {
    IndexedVisitor& x = *static_cast<IndexedVisitor*>(user);
    if (id != x.vertices.size()) x.consistent = false;
    x.vertices.push_back(p);
    return Status::ok();
  }
  static Status triangle(void* user, const Triangle& t, const Vec3& a, const Vec3& b,
                         const Vec3& c) {
    IndexedVisitor& x = *static_cast<IndexedVisitor*>(user);
    const Vec3* q[3] = {&a, &b, &c};
    for (int k = 0; k < 3; ++k) {
      if (t.v[k] >= x.vertices.size() || !(x.vertices[t.v[k]] == *q[k])) x.consistent = false;
    }
    x.triangles.push_back(t);
    return HashVisitor::triangle(&x.hash, t, a, b, c);
  }
};

TEST(SweepDecimate, SameBytesForEverySlabSizeAndThreadCount) {
  TestArena ta(size_t{256} << 20);
  const Mesh torus = tilted_torus(&ta.arena);
  std::vector<Vec3> streamed_vertices;  // the first streamed run's, by id
  std::vector<Triangle> streamed_triangles;
  struct Run {
    uint32_t layers;
    unsigned threads;
    bool mesh;
  };
  const Run runs[] = {{1, 1, false}, {3, 1, false}, {16, 1, false}, {0, 1, false},
                      {3, 3, false}, {0, 3, false}, {0, 3, true}};
  std::string first;
  for (const Run& r : runs) {
    SCOPED_TRACE(testing::Message()
                 << r.layers << " layers, " << r.threads << " threads" << (r.mesh ? ", mesh" : ""));
#if defined(SPLINTCORE_WITH_PLATFORM)
    ThreadExecutor pool(r.threads);
    Context ctx(&ta.arena, &pool.executor(), nullptr);
#else
    Context ctx(&ta.arena);
#endif
    ArenaScope scope(ta.arena);
    SweepOptions o;
    o.direction = Vec3{0.2, -0.3, 1.0};
    o.voxel = 0.15;  // coarser than the other tests: the bytes, not the error
    o.decimate_error = 0.015;
    o.layers_per_tile = r.layers;
    HashVisitor hv;
    if (r.mesh) {  // the mesh variant is the same surface, triangle for triangle, and the
                   // same vertices and ids as the stream gave
      Mesh m(&ta.arena);
      SPLINTCORE_ASSERT_OK(sweep_volume_mesh(ctx, Span<const Mesh>(&torus, 1), o, &m));
      for (const Triangle& t : m.triangles) {
        SPLINTCORE_ASSERT_OK(HashVisitor::triangle(&hv, t, m.vertices[t.v[0]], m.vertices[t.v[1]],
                                                   m.vertices[t.v[2]]));
      }
      ASSERT_EQ(m.vertices.size(), streamed_vertices.size());
      ASSERT_EQ(m.triangles.size(), streamed_triangles.size());
      EXPECT_EQ(std::memcmp(m.vertices.data(), streamed_vertices.data(),
                            streamed_vertices.size() * sizeof(Vec3)),
                0);
      EXPECT_EQ(std::memcmp(m.triangles.data(), streamed_triangles.data(),
                            streamed_triangles.size() * sizeof(Triangle)),
                0);
    } else {
      IndexedVisitor iv;
      MarchingCubesVisitor v;
      v.vertex = IndexedVisitor::vertex;
      v.triangle = IndexedVisitor::triangle;
      v.user = &iv;
      SweepStats stats;
      SPLINTCORE_ASSERT_OK(sweep_volume(ctx, Span<const Mesh>(&torus, 1), o, v, &stats));
      EXPECT_GT(stats.decimated_tiles, 1u);
      EXPECT_TRUE(iv.consistent);
      if (streamed_vertices.empty()) {
        streamed_vertices = iv.vertices;
        streamed_triangles = iv.triangles;
      }
      hv = iv.hash;
    }
    const std::string hex = hv.hex();
    if (first.empty()) first = hex;
    EXPECT_EQ(hex, first);
  }
}

TEST(SweepDecimate, RunsInExactlyItsHighWaterAndFailsCleanlyBelow) {
  TestArena big(size_t{256} << 20);
  const Mesh torus = tilted_torus(&big.arena);
  SweepOptions o;
  o.direction = Vec3{0, 0, 1};
  o.voxel = 0.15;
  o.decimate_error = 0.015;
  o.has_region = true;
  o.region.lo = Vec3{-6, -6, 0};
  o.region.hi = Vec3{6, 6, 4};
  o.open_at_region = true;
  size_t need = 0;
  size_t triangles = 0;
  {
    TestArena ta(size_t{256} << 20);
    Context ctx(&ta.arena);
    Mesh out(&ta.arena);
    SPLINTCORE_ASSERT_OK(sweep_volume_mesh(ctx, Span<const Mesh>(&torus, 1), o, &out));
    need = ta.arena.high_water();
    triangles = out.triangles.size();
    EXPECT_GT(triangles, 1000u);
  }
  {
    TestArena ta(need);
    Context ctx(&ta.arena);
    Mesh out(&ta.arena);
    SPLINTCORE_EXPECT_OK(sweep_volume_mesh(ctx, Span<const Mesh>(&torus, 1), o, &out));
    EXPECT_EQ(out.triangles.size(), triangles);
  }
  uint32_t failures = 0;
  for (size_t cap = need / 64; cap < need; cap += need / 16) {
    TestArena ta(cap);
    Context ctx(&ta.arena);
    Mesh out(&ta.arena);
    const Status st = sweep_volume_mesh(ctx, Span<const Mesh>(&torus, 1), o, &out);
    if (st.is_ok()) {
      EXPECT_EQ(out.triangles.size(), triangles);
      continue;
    }
    EXPECT_EQ(st.code(), StatusCode::kArenaExhausted) << test::format(st);
    EXPECT_EQ(ta.arena.used(), 0u);
    EXPECT_TRUE(out.triangles.empty());
    ++failures;
  }
  EXPECT_GT(failures, 3u);
}

// The border edges of an open surface (edges one triangle uses) as their ends' positions, the
// lesser end first, sorted: comparable between meshes whatever their vertex ids.
std::vector<std::array<double, 6>> border_by_position(const Mesh& m) {
  std::vector<uint64_t> edges;  // (smaller id << 32) | larger id
  for (const Triangle& t : m.triangles) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = t.v[k], b = t.v[(k + 1) % 3];
      edges.push_back((uint64_t{std::min(a, b)} << 32) | std::max(a, b));
    }
  }
  std::sort(edges.begin(), edges.end());
  std::vector<std::array<double, 6>> out;
  for (size_t i = 0; i < edges.size();) {
    size_t j = i;
    while (j < edges.size() && edges[j] == edges[i]) ++j;
    if (j - i == 1) {
      const Vec3& p = m.vertices[edges[i] >> 32];
      const Vec3& q = m.vertices[edges[i] & 0xffffffffu];
      std::array<double, 6> e{p.x, p.y, p.z, q.x, q.y, q.z};
      if (std::lexicographical_compare(e.begin() + 3, e.end(), e.begin(), e.begin() + 3)) {
        e = {q.x, q.y, q.z, p.x, p.y, p.z};
      }
      out.push_back(e);
    }
    i = j;
  }
  std::sort(out.begin(), out.end());
  return out;
}

// Decimating, the caps are left out in the stream (the tile decimator's own test of a corner
// beyond the grid) and their corners stay where they are: over a region that cuts the swept
// torus on all six sides, the open surface has the plain sweep's border exactly, edge for edge
// (the decimated run extracted at the plain surface: inset decimate_error / 2, as above), and
// the same number of cap triangles left out. A cap missed on any one side leaves a closed
// patch there (without its x or y terms, only this test fails).
TEST(SweepDecimate, OpenAtARegionKeepsThePlainBorderOnEverySide) {
  TestArena ta(size_t{512} << 20);
  Context ctx(&ta.arena);
  const Mesh torus = tilted_torus(&ta.arena);
  SweepOptions o;
  o.direction = Vec3{0, 0, 1};
  o.voxel = 0.08;
  o.has_region = true;
  o.region.lo = Vec3{-3.2, -2.9, -2.5};
  o.region.hi = Vec3{3.7, 2.6, 2.5};
  o.open_at_region = true;
  Mesh plain(&ta.arena), reduced(&ta.arena);
  SweepStats plain_stats, stats;
  SPLINTCORE_ASSERT_OK(
      sweep_volume_mesh(ctx, Span<const Mesh>(&torus, 1), o, &plain, &plain_stats));
  SweepOptions dec = o;
  dec.decimate_error = o.voxel / 10;
  dec.inset = dec.decimate_error / 2;
  SPLINTCORE_ASSERT_OK(sweep_volume_mesh(ctx, Span<const Mesh>(&torus, 1), dec, &reduced, &stats));
  EXPECT_GT(stats.decimated_tiles, 1u);
  EXPECT_LT(reduced.triangles.size() * 2, plain.triangles.size());
  EXPECT_GT(plain_stats.cap_triangles_dropped, 0u);
  EXPECT_EQ(stats.cap_triangles_dropped, plain_stats.cap_triangles_dropped);
  const auto want = border_by_position(plain);
  const auto got = border_by_position(reduced);
  EXPECT_GT(want.size(), 100u);
  EXPECT_TRUE(want == got) << want.size() << " border edges plain, " << got.size() << " decimated";
  // The border runs beyond every side of the region: both ends of each border edge lie
  // outside it, and some beyond each of its six faces.
  int faces[6] = {0, 0, 0, 0, 0, 0};
  auto at = [](const Vec3& v, int axis) { return axis == 0 ? v.x : axis == 1 ? v.y : v.z; };
  for (const auto& e : want) {
    for (int k = 0; k < 2; ++k) {
      const Vec3 p{e[3 * k], e[3 * k + 1], e[3 * k + 2]};
      EXPECT_FALSE(o.region.contains(p));
      for (int axis = 0; axis < 3; ++axis) {
        faces[2 * axis] += at(p, axis) < at(o.region.lo, axis) ? 1 : 0;
        faces[2 * axis + 1] += at(p, axis) > at(o.region.hi, axis) ? 1 : 0;
      }
    }
  }
  for (int face = 0; face < 6; ++face) EXPECT_GT(faces[face], 0) << "face " << face;
}

// The decimated sweep's mesh variant over two tiles (its output logged between them and
// moved down over the tile's working set at each) in an arena of 4 KiB blocks (caller hooks):
// with the allocator refusing each block request in turn, and under caps from half of what
// the blocks reserve in a run to all of it (there the log's move can need a block of its own,
// refused by the cap: tiles.cpp's move_down), every run fails with kArenaExhausted naming the
// need, the arena's top where it was, `out` empty and every block given back, or makes the
// same mesh as in one buffer.
TEST(SweepDecimate, InAnArenaOfBlocksEveryFailureIsClean) {
  TestArena big(size_t{256} << 20);
  const Mesh torus = tilted_torus(&big.arena);
  SweepOptions o;
  o.direction = Vec3{0.2, -0.3, 1.0};
  o.voxel = 0.15;
  o.decimate_error = 0.015;
  std::vector<Triangle> want_t;
  std::vector<Vec3> want_v;
  {
    TestArena ta(size_t{256} << 20);
    Context ctx(&ta.arena);
    Mesh out(&ta.arena);
    SweepStats stats;
    SPLINTCORE_ASSERT_OK(sweep_volume_mesh(ctx, Span<const Mesh>(&torus, 1), o, &out, &stats));
    ASSERT_GE(stats.decimated_tiles, 2u);
    want_t.assign(out.triangles.begin(), out.triangles.end());
    want_v.assign(out.vertices.begin(), out.vertices.end());
  }
  // One run: refusing the sweep's request number `refuse` (-1: none) under `cap`; true when
  // it made the mesh. *reserved: what the blocks took at most.
  auto run = [&](int64_t refuse, size_t cap, size_t* reserved) {
    test::FailNthBlock blocks;
    bool made = false;
    {
      Arena arena(blocks.hooks(), cap, 4096);
      EXPECT_NE(arena.allocate(16), nullptr);  // the top above a block already there
      if (refuse >= 0) blocks.fail_at = blocks.calls + refuse;
      const size_t used = arena.used();
      Context ctx(&arena);
      Mesh out(&arena);
      const Status st = sweep_volume_mesh(ctx, Span<const Mesh>(&torus, 1), o, &out);
      made = st.is_ok();
      if (made) {
        EXPECT_TRUE(std::equal(want_t.begin(), want_t.end(), out.triangles.begin(),
                               out.triangles.end(), [](const Triangle& a, const Triangle& b) {
                                 return std::memcmp(a.v, b.v, sizeof(a.v)) == 0;
                               }));
        EXPECT_TRUE(std::equal(
            want_v.begin(), want_v.end(), out.vertices.begin(), out.vertices.end(),
            [](const Vec3& a, const Vec3& b) { return a.x == b.x && a.y == b.y && a.z == b.z; }));
      } else {
        EXPECT_EQ(st.code(), StatusCode::kArenaExhausted) << test::format(st);
        EXPECT_NE(std::string(st.message()).find("need"), std::string::npos) << st.message();
        EXPECT_EQ(arena.used(), used);
        EXPECT_TRUE(out.triangles.empty() && out.vertices.empty());
      }
      if (reserved != nullptr) *reserved = arena.reserved();
    }
    EXPECT_EQ(blocks.outstanding, 0);
    return made;
  };
  size_t reserved = 0;
  ASSERT_TRUE(run(-1, size_t{1} << 30, &reserved));
  int failures = 0;
  for (int64_t n = 0; n < 1000; ++n) {
    SCOPED_TRACE(testing::Message() << "block request " << n << " refused");
    if (run(n, size_t{1} << 30, nullptr)) break;
    ++failures;
  }
  EXPECT_GT(failures, 4);
  for (size_t k = 32; k <= 36; ++k) {
    SCOPED_TRACE(testing::Message() << "cap " << k << "/64 of " << reserved);
    EXPECT_FALSE(run(-1, reserved / 64 * k, nullptr));
  }
  // In hooks mode the need is what the blocks reserve (docs/embedding.md): the same run in
  // exactly that cap.
  EXPECT_TRUE(run(-1, reserved, nullptr));
}

TEST(Blockout, DecimatedSweepPassesTheIndependentCheck) {
  TestArena ta(size_t{1} << 30);
  Context ctx(&ta.arena);
  Mesh cone(&ta.arena);
  frustum(&cone, 3.0, 5.0, 0.0, 8.0, 360);
  for (Vec3& p : cone.vertices) ASSERT_TRUE(round_to_float32(&p));
  const float lo[3] = {-7, -7, 4}, hi[3] = {7, 7, 10};
  Mesh box = box_mesh(&ta.arena, lo, hi);
  Mesh imprint;
  SPLINTCORE_ASSERT_OK(mesh_boolean(ctx, box, cone, BooleanOptions{}, &imprint, nullptr));
  BlockoutOptions o;
  o.sweep.direction = Vec3{0, 0, -1};
  o.sweep.voxel = 0.1;
  o.sweep.inset = 0.05;
  o.sweep.decimate_error = 0.01;
  Mesh blocked;
  BlockoutStats stats;
  SPLINTCORE_ASSERT_OK(blockout(ctx, imprint, Span<const Mesh>(&cone, 1), o, &blocked, &stats));
  double volume = 0;
  SPLINTCORE_ASSERT_OK(check_closed_oriented(ctx, blocked, &volume));
  const Vec3 d{0, 0, -1}, u{1, 0, 0}, v{0, 1, 0}, c{0, 0, 5};
  const LockReport before = lock_report(ta.arena, imprint, cone, d, u, v, c, 6.0, 60, 1e-3);
  const LockReport after = lock_report(ta.arena, blocked, cone, d, u, v, c, 6.0, 60, 1e-3);
  std::printf(
      "[ figures  ] decimated blockout: swept %llu triangles (%llu before decimation); %zu "
      "lines through the cone: before %zu locked, after %zu (longest %.4f mm)\n",
      static_cast<unsigned long long>(stats.swept_triangles),
      static_cast<unsigned long long>(stats.sweep.undecimated_triangles), before.lines_through_jaw,
      before.locked_lines, after.locked_lines, after.longest);
  EXPECT_GT(before.locked_lines, 100u);
  EXPECT_LT(after.locked_lines, before.locked_lines / 10);
  for (const Vec3& p : after.locked_at) {
    EXPECT_GT(std::sqrt(p.x * p.x + p.y * p.y), 5.0 - o.sweep.inset - 0.03) << p.x << " " << p.y;
  }
  EXPECT_LT(stats.swept_triangles * 4, stats.sweep.undecimated_triangles);
}

// ---- the height field (sweep_heightfield_mesh, BlockoutOptions::heightfield)

// Options for a height field along -z over `region` at `voxel` mm.
SweepOptions down_over(const Aabb& region, double voxel) {
  SweepOptions o;
  o.direction = Vec3{0, 0, -1};
  o.voxel = voxel;
  o.has_region = true;
  o.region = region;
  return o;
}

// The big-end-up cone's height field along -z over a box: an open sheet whose border is the
// grid's edge outside the region, every edge of it used once each way; flat over the cap and
// within the tolerance above it (z from 8 up: w = -z lies below h = -8), nowhere below it.
TEST(Heightfield, ConeGivesAnOpenSheetOverTheCapWithinTheTolerance) {
  TestArena ta(size_t{256} << 20);
  Context ctx(&ta.arena);
  Mesh cone(&ta.arena);
  frustum(&cone, 3.0, 5.0, 0.0, 8.0, 360);
  SweepOptions o = down_over(Aabb{Vec3{-7, -7, 4}, Vec3{7, 7, 10}}, 0.1);
  HeightfieldOptions ho;
  ho.tolerance = 0.01;
  Mesh sheet;
  HeightfieldStats st;
  SPLINTCORE_ASSERT_OK(sweep_heightfield_mesh(ctx, Span<const Mesh>(&cone, 1), o, ho, &sheet, &st));
  // 14 mm / 0.1 + 5 = 145 cells: squares of 16 (at most 145 / 8), 10 of them each way.
  EXPECT_EQ(st.square_cells, 16u);
  EXPECT_EQ(st.cells_u, 160u);
  EXPECT_EQ(st.cells_v, 160u);
  EXPECT_EQ(st.triangles_in, 360u);       // the top cap's fan faces against d
  EXPECT_GT(st.covered_vertices, 7000u);  // about pi 50^2
  std::vector<std::array<uint32_t, 2>> edges;
  for (const Triangle& t : sheet.triangles) {
    for (int k = 0; k < 3; ++k) edges.push_back({t.v[k], t.v[(k + 1) % 3]});
  }
  std::sort(edges.begin(), edges.end());
  size_t border = 0;
  for (size_t i = 0; i < edges.size(); ++i) {
    ASSERT_TRUE(i == 0 || edges[i] != edges[i - 1]) << "an edge used twice the same way";
    if (std::binary_search(edges.begin(), edges.end(),
                           std::array<uint32_t, 2>{edges[i][1], edges[i][0]})) {
      continue;
    }
    ++border;
    for (uint32_t v : edges[i]) {
      const Vec3& p = sheet.vertices[v];
      EXPECT_TRUE(std::fabs(p.x) > 7 || std::fabs(p.y) > 7) << p.x << " " << p.y;
    }
  }
  EXPECT_GT(border, 0u);
  // The flat cap: every vertex over it between 8 and 8 + tolerance (+ the float32 margin).
  size_t over_cap = 0;
  for (const Vec3& p : sheet.vertices) {
    const double r = std::sqrt(p.x * p.x + p.y * p.y);
    if (r > 4.6) continue;
    ++over_cap;
    EXPECT_GT(p.z, 8.0);
    EXPECT_LE(p.z, 8.0 + ho.tolerance + 1e-4);
  }
  EXPECT_GT(over_cap, 2u);
  // Few triangles where it is flat: far fewer than the grid's 2 * 256^2.
  std::printf(
      "[ figures  ] heightfield of the cone: %zu triangles, %zu vertices, %llu lowered "
      "grid vertices (at most %.3f mm)\n",
      sheet.triangles.size(), sheet.vertices.size(),
      static_cast<unsigned long long>(st.lowered_vertices), st.max_lowering);
  EXPECT_LT(sheet.triangles.size(), size_t{2} * 256 * 256 / 4);
  // The same bytes again.
  Mesh again;
  SPLINTCORE_ASSERT_OK(sweep_heightfield_mesh(ctx, Span<const Mesh>(&cone, 1), o, ho, &again));
  EXPECT_EQ(test::mesh_sha256(again), test::mesh_sha256(sheet));
}

// The height-field blockout of the cone from a box: a valid solid, the independent line check
// finds no line locked (nothing is left undercut, no inset), and it cuts at most a little more
// than the exact cylinder: the tolerance over the cap, about two cells around the rim.
TEST(Heightfield, BlockoutOfTheConeLeavesNoUndercutAndCutsLittleMore) {
  TestArena ta(size_t{1} << 30);
  Context ctx(&ta.arena);
  Mesh cone(&ta.arena);
  const uint32_t n = 360;
  frustum(&cone, 3.0, 5.0, 0.0, 8.0, n);
  for (Vec3& p : cone.vertices) ASSERT_TRUE(round_to_float32(&p));
  const float lo[3] = {-7, -7, 4}, hi[3] = {7, 7, 10};
  Mesh box = box_mesh(&ta.arena, lo, hi);
  BlockoutOptions o;
  o.heightfield = true;
  o.sweep.direction = Vec3{0, 0, -1};
  o.sweep.voxel = 0.1;
  o.sweep.inset = 0;
  Mesh blocked;
  BlockoutStats st;
  SPLINTCORE_ASSERT_OK(blockout(ctx, box, Span<const Mesh>(&cone, 1), o, &blocked, &st));
  EXPECT_EQ(st.attempts, 1u);
  EXPECT_EQ(st.swept_triangles, st.heightfield.network_triangles);
  MeshReport report;
  SPLINTCORE_ASSERT_OK(check_mesh(ctx, blocked, &report));
  EXPECT_TRUE(report.closed() && report.edge_manifold() && report.outward());
  const double area = rim_area(cone, n);
  const double exact = 14.0 * 14.0 * 6.0 - area * 4.0;
  const double volume = mesh_volume(blocked);
  std::printf(
      "[ figures  ] heightfield blockout of the cone: volume %.6f, exact %.6f (%.4f "
      "mm^3 more cut), %zu triangles\n",
      volume, exact, exact - volume, blocked.triangles.size());
  EXPECT_LT(volume, exact);  // it cuts no less
  // At most the tolerance over the cap's disc and two cells' ring around the rim, 4 mm tall.
  const double rim = 2 * kPi * 5.0;
  EXPECT_GT(volume, exact - (area * 0.0101 + rim * 2 * 0.1 * 4.0));
  expect_cone_unlocked(&ta.arena, blocked, cone);
}

// A tilted, overhanging pair (a torus leaning over a frustum) along a slanted direction: the
// height field never crosses itself, the blockout is a valid solid, and no line is locked.
TEST(Heightfield, SlantedOverhangsGiveAValidUnlockedSolid) {
  TestArena ta(size_t{1} << 30);
  Context ctx(&ta.arena);
  Mesh jaws[2] = {Mesh(&ta.arena), Mesh(&ta.arena)};
  frustum(&jaws[0], 2.0, 3.0, 0.0, 4.0, 90);
  RigidTransform aside =
      rotation_about_axis(Vec3{0, 0, 0}, Vec3{0.7071067811865476, 0.7071067811865476, 0}, 0.5);
  aside.t = Vec3{3, 0, 1};
  frustum(&jaws[1], 1.5, 2.5, 0.0, 3.0, 40, &aside);
  for (Mesh& m : jaws) {
    for (Vec3& p : m.vertices) ASSERT_TRUE(round_to_float32(&p));
  }
  const float lo[3] = {-5, -5, 2}, hi[3] = {8, 5, 7};
  Mesh box = box_mesh(&ta.arena, lo, hi);
  const Vec3 d = Vec3{0.2, -0.1, -1} * (1.0 / std::sqrt(1.05));
  BlockoutOptions o;
  o.heightfield = true;
  o.sweep.direction = d;
  o.sweep.voxel = 0.05;
  o.sweep.inset = 0;
  Mesh blocked;
  BlockoutStats st;
  SPLINTCORE_ASSERT_OK(blockout(ctx, box, Span<const Mesh>(jaws, 2), o, &blocked, &st));
  MeshReport report;
  SPLINTCORE_ASSERT_OK(check_mesh(ctx, blocked, &report));
  EXPECT_TRUE(report.closed() && report.edge_manifold() && report.outward());
  SelfIntersectionReport si;
  SPLINTCORE_ASSERT_OK(find_self_intersections(ctx, blocked, 0, &si));
  EXPECT_FALSE(si.self_intersecting());
  Mesh both(&ta.arena);
  for (const Mesh& m : jaws) ASSERT_TRUE(test::append_mesh_to(m, &both));
  Vec3 u, v;
  test::axes_across(d, &u, &v);
  const LockReport after =
      lock_report(ta.arena, blocked, both, d, u, v, Vec3{1.5, 0, 4}, 7.0, 70, 1e-6);
  EXPECT_GT(after.lines_through_jaw, 500u);
  EXPECT_EQ(after.locked_lines, 0u) << after.longest;
}

// The two-step contract: a first run's high water, then exactly that much works and less
// fails cleanly; the high water is the bound (16 bytes a grid vertex) plus the output.
TEST(Heightfield, RunsInItsHighWaterAndFailsCleanlyBelow) {
  TestArena big(size_t{256} << 20);
  Mesh cone(&big.arena);
  frustum(&cone, 3.0, 5.0, 0.0, 8.0, 120);
  // Without and with an offset (the spacer's 4 bytes a jaw vertex and polytope).
  for (double offset : {0.0, 0.2}) {
    SCOPED_TRACE(offset);
    SweepOptions o;
    o.direction = Vec3{0.1, 0, -1};
    o.voxel = 0.1;
    o.offset = offset;
    o.has_region = true;
    o.region = Aabb{Vec3{-7, -7, 4}, Vec3{7, 7, 10}};
    HeightfieldOptions ho;
    ho.tolerance = 0.01;
    size_t need = 0, triangles = 0, vertices = 0;
    uint32_t cells_u = 0, cells_v = 0;
    {
      TestArena ta(size_t{256} << 20);
      Context ctx(&ta.arena);
      Mesh out;
      HeightfieldStats st;
      SPLINTCORE_ASSERT_OK(
          sweep_heightfield_mesh(ctx, Span<const Mesh>(&cone, 1), o, ho, &out, &st));
      need = ta.arena.high_water();
      triangles = out.triangles.size();
      vertices = out.vertices.size();
      cells_u = st.cells_u;
      cells_v = st.cells_v;
    }
    const uint64_t grid =
        sweep_heightfield_bound(cells_u, cells_v, offset > 0 ? cone.vertices.size() : 0);
    const uint64_t bound =
        grid + 24 * uint64_t{vertices} + 12 * uint64_t{triangles} + 4 * Arena::kDefaultAlignment;
    EXPECT_LE(need, bound);
    EXPECT_GT(need, grid - 4 * Arena::kDefaultAlignment);
    {
      TestArena ta(need);
      Context ctx(&ta.arena);
      Mesh out;
      SPLINTCORE_EXPECT_OK(sweep_heightfield_mesh(ctx, Span<const Mesh>(&cone, 1), o, ho, &out));
      EXPECT_EQ(out.triangles.size(), triangles);
    }
    for (size_t cap : {need - 1, need / 2, need / 8}) {
      TestArena ta(cap);
      Context ctx(&ta.arena);
      Mesh out;
      const Status s = sweep_heightfield_mesh(ctx, Span<const Mesh>(&cone, 1), o, ho, &out);
      EXPECT_EQ(s.code(), StatusCode::kArenaExhausted) << test::format(s);
      EXPECT_EQ(ta.arena.used(), 0u);
      EXPECT_TRUE(out.triangles.empty() && out.vertices.empty());
    }
  }
}

// The least and the largest brute-force distance to `jaws` of the sheet's points that `keep`
// takes: its vertices and its triangles' centroids.
struct Reach {
  double least = HUGE_VAL, most = 0;
  size_t points = 0;
};
template <typename Keep>
Reach sheet_reach(const Mesh& sheet, const Mesh& jaws, Keep keep) {
  Reach r;
  auto take = [&](const Vec3& p) {
    if (!keep(p)) return;
    const double d = test::oracle_distance_to_mesh(p, jaws);
    r.least = std::min(r.least, d);
    r.most = std::max(r.most, d);
    ++r.points;
  };
  for (const Vec3& p : sheet.vertices) take(p);
  for (const Triangle& t : sheet.triangles) {
    take((sheet.vertices[t.v[0]] + sheet.vertices[t.v[1]] + sheet.vertices[t.v[2]]) * (1.0 / 3));
  }
  return r;
}

// The height field of the offset solid S + B(c) (a spacer): over the cone's flat cap exactly c
// out (the polytope's bottom face is tangent to the ball) within the tolerance; no point of the
// sheet comes nearer the jaw than c (brute-force distances), and near the jaw it stays within
// the polytope's reach (1.0718 c) and the tolerance of it.
// With an executor the passes run in two halves side by side (each into its own h and low,
// merged: the least h, the most low): the same mesh and counts as the serial run, bit for
// bit, with and without an offset, over two jaws whose halves split inside the second; and
// with an executor in an arena of the serial run's high water, where the second share may not
// fit (the passes then run serially), the same again.
TEST(Heightfield, PassesInTasksGiveTheSerialBytes) {
  TestArena inputs(size_t{64} << 20);
  Mesh jaws[2] = {Mesh(&inputs.arena), Mesh(&inputs.arena)};
  frustum(&jaws[0], 2.0, 3.0, 0.0, 5.0, 150);
  frustum(&jaws[1], 1.5, 2.5, -1.0, 6.0, 450);
  for (Vec3& p : jaws[1].vertices) p.x += 3.0;
  ThreadExecutor pool(2);
  for (double offset : {0.0, 0.15}) {
    SCOPED_TRACE(offset);
    SweepOptions o;
    o.direction = Vec3{0.05, -0.1, -1};
    o.voxel = 0.1;
    o.offset = offset;
    o.has_region = true;
    o.region = Aabb{Vec3{-4, -4, 3}, Vec3{7, 4, 8}};
    HeightfieldOptions ho;
    ho.tolerance = 0.01;
    struct Run {
      std::vector<Vec3> vertices;
      std::vector<Triangle> triangles;
      HeightfieldStats st;
      size_t high_water = 0;
    };
    auto run = [&](const Executor* executor, size_t cap, Run* r) {
      TestArena ta(cap);
      Context ctx(&ta.arena, executor, nullptr);
      Mesh out;
      const Status s = sweep_heightfield_mesh(ctx, Span<const Mesh>(jaws, 2), o, ho, &out, &r->st);
      r->vertices.assign(out.vertices.begin(), out.vertices.end());
      r->triangles.assign(out.triangles.begin(), out.triangles.end());
      r->high_water = ta.arena.high_water();
      return s;
    };
    Run serial, sides, tight;
    SPLINTCORE_ASSERT_OK(run(nullptr, size_t{256} << 20, &serial));
    SPLINTCORE_ASSERT_OK(run(&pool.executor(), size_t{256} << 20, &sides));
    SPLINTCORE_ASSERT_OK(run(&pool.executor(), serial.high_water, &tight));
    EXPECT_GT(sides.high_water, serial.high_water);  // the second share was taken
    EXPECT_GT(serial.st.lowered_vertices, 0u);
    EXPECT_GT(serial.st.clipped_pairs, 0u);
    for (const Run* r : {&sides, &tight}) {
      ASSERT_EQ(r->vertices.size(), serial.vertices.size());
      ASSERT_EQ(r->triangles.size(), serial.triangles.size());
      EXPECT_EQ(0, std::memcmp(r->vertices.data(), serial.vertices.data(),
                               serial.vertices.size() * sizeof(Vec3)));
      EXPECT_EQ(0, std::memcmp(r->triangles.data(), serial.triangles.data(),
                               serial.triangles.size() * sizeof(Triangle)));
      EXPECT_EQ(r->st.triangles_in, serial.st.triangles_in);
      EXPECT_EQ(r->st.offset_pieces, serial.st.offset_pieces);
      EXPECT_EQ(r->st.covered_vertices, serial.st.covered_vertices);
      EXPECT_EQ(r->st.clipped_pairs, serial.st.clipped_pairs);
      EXPECT_EQ(r->st.lowered_vertices, serial.st.lowered_vertices);
      EXPECT_EQ(r->st.max_lowering, serial.st.max_lowering);
    }
    EXPECT_LE(tight.high_water, serial.high_water);
  }
}

TEST(Heightfield, OffsetKeepsTheClearanceOverTheCone) {
  TestArena ta(size_t{256} << 20);
  Context ctx(&ta.arena);
  Mesh cone(&ta.arena);
  frustum(&cone, 3.0, 5.0, 0.0, 8.0, 360);
  SweepOptions o;
  o.direction = Vec3{0, 0, -1};
  o.voxel = 0.1;
  o.offset = 0.1;
  o.has_region = true;
  o.region = Aabb{Vec3{-7, -7, 4}, Vec3{7, 7, 10}};
  HeightfieldOptions ho;
  ho.tolerance = 0.01;
  Mesh sheet;
  HeightfieldStats st;
  SPLINTCORE_ASSERT_OK(sweep_heightfield_mesh(ctx, Span<const Mesh>(&cone, 1), o, ho, &sheet, &st));
  EXPECT_EQ(st.triangles_in, 360u);
  EXPECT_GT(st.offset_pieces, 360u * 20);
  size_t over_cap = 0;
  for (const Vec3& p : sheet.vertices) {
    if (std::sqrt(p.x * p.x + p.y * p.y) > 4.6) continue;
    ++over_cap;
    EXPECT_GE(p.z, 8.0 + o.offset);
    EXPECT_LE(p.z, 8.0 + o.offset + ho.tolerance + 1e-4);
  }
  EXPECT_GT(over_cap, 2u);
  const Reach all = sheet_reach(sheet, cone, [&](const Vec3& p) { return o.region.contains(p); });
  EXPECT_GT(all.points, 1000u);
  EXPECT_GE(all.least, o.offset * (1 - 1e-6)) << all.least;
  // Above the cap to two cells from its rim (not the step lowered beyond it): within the reach.
  const Reach near = sheet_reach(sheet, cone, [](const Vec3& p) {
    return p.z < 8.5 && std::sqrt(p.x * p.x + p.y * p.y) < 4.8;
  });
  EXPECT_GT(near.points, 100u);
  EXPECT_LE(near.most, 1.0718 * o.offset + ho.tolerance + 1e-4) << near.most;
  std::printf(
      "[ figures  ] offset height field of the cone (c 0.1 mm): %zu triangles, %llu pieces, "
      "distance to the jaw %.5f .. %.5f mm over the cap, least %.5f mm in the region\n",
      sheet.triangles.size(), static_cast<unsigned long long>(st.offset_pieces), near.least,
      near.most, all.least);
}

// A spacer by the height field: the box less the cone's offset sweep is a valid solid, no line
// along d is locked, and no point of its surface comes nearer the jaw than the clearance.
TEST(Heightfield, SpacerBlockoutIsAValidSolidWithItsClearance) {
  TestArena ta(size_t{1} << 30);
  Context ctx(&ta.arena);
  Mesh cone(&ta.arena);
  frustum(&cone, 3.0, 5.0, 0.0, 8.0, 90);
  for (Vec3& p : cone.vertices) ASSERT_TRUE(round_to_float32(&p));
  const float lo[3] = {-7, -7, 4}, hi[3] = {7, 7, 10};
  Mesh box = box_mesh(&ta.arena, lo, hi);
  BlockoutOptions o;
  o.heightfield = true;
  o.sweep.direction = Vec3{0, 0, -1};
  o.sweep.voxel = 0.1;
  o.sweep.inset = 0;
  o.sweep.offset = 0.1;
  Mesh blocked;
  BlockoutStats st;
  SPLINTCORE_ASSERT_OK(blockout(ctx, box, Span<const Mesh>(&cone, 1), o, &blocked, &st));
  EXPECT_GE(st.offset_used, 0.1);
  MeshReport report;
  SPLINTCORE_ASSERT_OK(check_mesh(ctx, blocked, &report));
  EXPECT_TRUE(report.closed() && report.edge_manifold() && report.outward());
  const Reach r = sheet_reach(blocked, cone, [](const Vec3&) { return true; });
  EXPECT_GE(r.least, 0.1 * (1 - 1e-6)) << r.least;
  EXPECT_LE(r.least, 0.1 * 1.0718 + 0.01) << r.least;
  expect_cone_unlocked(&ta.arena, blocked, cone);
}

// BlockoutOptions::heightfield_swept: a first run leaves its swept surface after its result;
// a second run with the Boolean's check (as the design's after a crossing) given that surface
// makes no sweep of its own and gives the bytes and counts of a fresh run with the check (its
// allocations all above the kept surface, which stays as it was). Keeping it takes no more
// than a plain run's high water: the copy fits under the Boolean's working set.
TEST(Heightfield, BlockoutKeepsItsSweptSurfaceForASecondRun) {
  TestArena inputs(size_t{64} << 20);
  Mesh cone(&inputs.arena);
  frustum(&cone, 3.0, 5.0, 0.0, 8.0, 90);
  for (Vec3& p : cone.vertices) ASSERT_TRUE(round_to_float32(&p));
  const float lo[3] = {-7, -7, 4}, hi[3] = {7, 7, 10};
  const Mesh box = box_mesh(&inputs.arena, lo, hi);
  BlockoutOptions o;
  o.heightfield = true;
  o.sweep.direction = Vec3{0.05, 0, -1};
  o.sweep.voxel = 0.1;
  o.sweep.offset = 0.1;
  auto same = [](const Mesh& a, const Mesh& b) {
    return a.vertices.size() == b.vertices.size() && a.triangles.size() == b.triangles.size() &&
           std::memcmp(a.vertices.data(), b.vertices.data(), a.vertices.size() * sizeof(Vec3)) ==
               0 &&
           std::memcmp(a.triangles.data(), b.triangles.data(),
                       a.triangles.size() * sizeof(Triangle)) == 0;
  };
  const Span<const Mesh> jaws(&cone, 1);
  TestArena fresh(size_t{256} << 20);
  Mesh checked;
  BlockoutStats want;
  SPLINTCORE_ASSERT_OK(blockout(Context(&fresh.arena), box, jaws, o, &checked, &want));
  ASSERT_TRUE(want.boolean.self_intersection_checked);
  ASSERT_GT(want.swept_triangles, 0u);

  TestArena ta(size_t{256} << 20);
  BlockoutSwept kept;
  BlockoutOptions first = o;
  first.boolean.check_self_intersection = false;
  first.heightfield_swept = &kept;
  Mesh unchecked;
  BlockoutStats st1;
  SPLINTCORE_ASSERT_OK(blockout(Context(&ta.arena), box, jaws, first, &unchecked, &st1));
  ASSERT_TRUE(kept.held);
  EXPECT_EQ(kept.mesh.triangles.size(), st1.swept_triangles);
  EXPECT_EQ(kept.attempt + 1, st1.attempts);
  EXPECT_EQ(kept.stats.clipped_pairs, st1.heightfield.clipped_pairs);
  EXPECT_TRUE(same(unchecked, checked));  // (no crossing here: the check changes nothing)
  const std::vector<Vec3> kept_vertices(kept.mesh.vertices.begin(), kept.mesh.vertices.end());
  BlockoutOptions second = o;
  second.heightfield_swept = &kept;
  Mesh again;
  BlockoutStats st2;
  SPLINTCORE_ASSERT_OK(blockout(Context(&ta.arena), box, jaws, second, &again, &st2));
  EXPECT_TRUE(same(again, checked));
  EXPECT_EQ(st2.attempts, want.attempts);
  EXPECT_EQ(st2.swept_triangles, want.swept_triangles);
  EXPECT_EQ(st2.heightfield.clipped_pairs, want.heightfield.clipped_pairs);
  EXPECT_EQ(st2.heightfield.offset_pieces, want.heightfield.offset_pieces);
  EXPECT_EQ(st2.heightfield.network_triangles, want.heightfield.network_triangles);
  EXPECT_EQ(st2.offset_used, want.offset_used);
  EXPECT_TRUE(st2.boolean.self_intersection_checked);
  EXPECT_EQ(0, std::memcmp(kept_vertices.data(), kept.mesh.vertices.data(),
                           kept_vertices.size() * sizeof(Vec3)));
  EXPECT_GT(static_cast<const void*>(again.triangles.data()),
            static_cast<const void*>(kept.mesh.vertices.data()));

  // In an arena of a plain run's high water.
  BlockoutOptions unkept = first;
  unkept.heightfield_swept = nullptr;
  TestArena plain(size_t{256} << 20);
  Mesh p1;
  SPLINTCORE_ASSERT_OK(blockout(Context(&plain.arena), box, jaws, unkept, &p1, nullptr));
  TestArena tight(plain.arena.high_water());
  BlockoutSwept none;
  first.heightfield_swept = &none;
  Mesh p2;
  SPLINTCORE_ASSERT_OK(blockout(Context(&tight.arena), box, jaws, first, &p2, nullptr));
  EXPECT_TRUE(none.held);  // the copy fits under the Boolean's own high water
  EXPECT_EQ(tight.arena.high_water(), plain.arena.high_water());
  EXPECT_TRUE(same(p2, p1));
}

// Overhangs along a slanted direction with sharp edges and corners (the pieces of the
// polytope's edges and faces): no point of the sheet nearer the jaws than the offset, and the
// nearest within the reach and tolerance of it; the same bytes again.
TEST(Heightfield, OffsetKeepsTheClearanceAlongSlantedOverhangs) {
  TestArena ta(size_t{512} << 20);
  Context ctx(&ta.arena);
  Mesh jaws(&ta.arena);
  frustum(&jaws, 2.0, 3.0, 0.0, 4.0, 7);
  Mesh tilted(&ta.arena);
  RigidTransform aside =
      rotation_about_axis(Vec3{0, 0, 0}, Vec3{0.7071067811865476, 0.7071067811865476, 0}, 0.5);
  aside.t = Vec3{3, 0, 1};
  frustum(&tilted, 1.5, 2.5, 0.0, 3.0, 5, &aside);
  ASSERT_TRUE(append_mesh(&jaws, tilted));
  SweepOptions o;
  o.direction = Vec3{0.2, -0.1, -1} * (1.0 / std::sqrt(1.05));
  o.voxel = 0.05;
  o.offset = 0.25;
  o.has_region = true;
  o.region = Aabb{Vec3{-5, -5, 2}, Vec3{8, 5, 7}};
  HeightfieldOptions ho;
  ho.tolerance = 0.005;
  Mesh sheet;
  HeightfieldStats st;
  SPLINTCORE_ASSERT_OK(sweep_heightfield_mesh(ctx, Span<const Mesh>(&jaws, 1), o, ho, &sheet, &st));
  const Reach r = sheet_reach(sheet, jaws, [&](const Vec3& p) { return o.region.contains(p); });
  EXPECT_GT(r.points, 1000u);
  EXPECT_GE(r.least, o.offset * (1 - 1e-6)) << r.least;
  EXPECT_LE(r.least, 1.0718 * o.offset + ho.tolerance) << r.least;
  std::printf(
      "[ figures  ] offset height field of slanted overhangs (c 0.25 mm): %zu triangles, "
      "least distance %.5f mm\n",
      sheet.triangles.size(), r.least);
  Mesh again;
  SPLINTCORE_ASSERT_OK(sweep_heightfield_mesh(ctx, Span<const Mesh>(&jaws, 1), o, ho, &again));
  EXPECT_EQ(test::mesh_sha256(again), test::mesh_sha256(sheet));
}

TEST(Heightfield, RefusesWhatItCannotDo) {
  TestArena ta(size_t{64} << 20);
  Context ctx(&ta.arena);
  Mesh cone(&ta.arena);
  frustum(&cone, 3.0, 5.0, 0.0, 8.0, 60);
  SweepOptions o;
  o.direction = Vec3{0, 0, -1};
  o.voxel = 0.1;
  HeightfieldOptions ho;
  ho.tolerance = 0.01;
  const Span<const Mesh> jaws(&cone, 1);
  Mesh out;
  Status s = sweep_heightfield_mesh(ctx, jaws, o, ho, &out);  // no region
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(std::strstr(s.message(), "region"), nullptr) << s.message();
  o.has_region = true;
  o.region = Aabb{Vec3{-7, -7, 4}, Vec3{7, 7, 10}};
  ho.tolerance = 0.2;  // above the voxel
  s = sweep_heightfield_mesh(ctx, jaws, o, ho, &out);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(std::strstr(s.message(), "tolerance"), nullptr) << s.message();
  ho.tolerance = 0.01;
  o.offset = 2.5;  // above 20 voxels
  s = sweep_heightfield_mesh(ctx, jaws, o, ho, &out);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(std::strstr(s.message(), "offset"), nullptr) << s.message();
  o.offset = 0;
  ho.shift_u = 1.0;
  EXPECT_EQ(sweep_heightfield_mesh(ctx, jaws, o, ho, &out).code(), StatusCode::kInvalidArgument);
  ho.shift_u = 0;
  o.voxel = 0.003;  // 14 mm: 4672 voxels across
  ho.tolerance = 0.001;
  s = sweep_heightfield_mesh(ctx, jaws, o, ho, &out);
  EXPECT_EQ(s.code(), StatusCode::kLimitExceeded);
  EXPECT_NE(std::strstr(s.message(), "larger voxel"), nullptr) << s.message();
  o.voxel = 0.1;
  ho.tolerance = 0.01;
  const size_t used = ta.arena.used();
  cone.vertices[5].x = std::nan("");
  s = sweep_heightfield_mesh(ctx, jaws, o, ho, &out);
  EXPECT_EQ(s.code(), StatusCode::kNonFinite);
  EXPECT_EQ(s.index(), 5u);
  EXPECT_EQ(ta.arena.used(), used);
  EXPECT_TRUE(out.triangles.empty());
  BlockoutOptions b;
  b.heightfield = true;
  b.sweep.voxel = 0.1;
  b.sweep.inset = 0.05;  // the height field has no inset
  cone.vertices[5].x = 1;
  const float lo[3] = {-7, -7, 4}, hi[3] = {7, 7, 10};
  Mesh box = box_mesh(&ta.arena, lo, hi);
  Mesh blocked;
  s = blockout(ctx, box, jaws, b, &blocked);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(std::strstr(s.message(), "no inset"), nullptr) << s.message();
}

// A box's vertical sides, standing on grid lines (x, y = +-2 with the grid's vertices every
// 0.5 mm from -4), face neither way along d (their shadows turn neither way, exactly): only
// its top's two triangles are taken, and the sheet lies just over the top (3 mm) up to the
// footprint's edge.
TEST(Heightfield, VerticalSidesOnGridLinesAreNotTaken) {
  TestArena ta(size_t{64} << 20);
  Context ctx(&ta.arena);
  const float lo[3] = {-2, -2, 0}, hi[3] = {2, 2, 3};
  const Mesh box = box_mesh(&ta.arena, lo, hi);
  SweepOptions o = down_over(Aabb{Vec3{-3, -3, 1}, Vec3{3, 3, 5}}, 0.5);
  HeightfieldOptions ho;
  ho.tolerance = 0.05;
  Mesh sheet;
  HeightfieldStats st;
  SPLINTCORE_ASSERT_OK(sweep_heightfield_mesh(ctx, Span<const Mesh>(&box, 1), o, ho, &sheet, &st));
  EXPECT_EQ(st.triangles_in, 2u);
  size_t over_top = 0, on_edge = 0;
  for (const Vec3& p : sheet.vertices) {
    if (std::fabs(p.x) > 2 || std::fabs(p.y) > 2) continue;
    ++over_top;
    if (std::fabs(p.x) == 2 || std::fabs(p.y) == 2) ++on_edge;
    EXPECT_GT(p.z, 3.0) << p.x << " " << p.y;
    EXPECT_LE(p.z, 3.0 + ho.tolerance + 1e-4) << p.x << " " << p.y;
  }
  EXPECT_GT(on_edge, 0u);
  EXPECT_GT(over_top, on_edge);
}

// A jaw triangle whose corner is one past the jaw's last vertex, at each corner in turn, in
// the second of two jaws: refused by name (the triangle and its jaw), the output empty and the
// arena as it was.
TEST(Heightfield, AVertexIdOnePastTheLastIsNamedWithItsJaw) {
  TestArena ta(size_t{64} << 20);
  Context ctx(&ta.arena);
  Mesh jaws[2] = {Mesh(&ta.arena), Mesh(&ta.arena)};
  frustum(&jaws[0], 3.0, 5.0, 0.0, 8.0, 24);
  frustum(&jaws[1], 3.0, 5.0, 0.0, 8.0, 24);
  SweepOptions o = down_over(Aabb{Vec3{-7, -7, 4}, Vec3{7, 7, 10}}, 0.5);
  HeightfieldOptions ho;
  ho.tolerance = 0.05;
  const Triangle kept = jaws[1].triangles[7];
  for (int k = 0; k < 3; ++k) {
    jaws[1].triangles[7] = kept;
    jaws[1].triangles[7].v[k] = static_cast<uint32_t>(jaws[1].vertices.size());
    const size_t used = ta.arena.used();
    Mesh out;
    const Status s = sweep_heightfield_mesh(ctx, Span<const Mesh>(jaws, 2), o, ho, &out);
    EXPECT_EQ(s.code(), StatusCode::kInvalidMesh) << k;
    EXPECT_STREQ(s.message(),
                 "heightfield: triangle 7 of jaw 1 refers to a vertex that does not exist");
    EXPECT_EQ(s.index(), 7u);
    EXPECT_TRUE(out.triangles.empty() && out.vertices.empty());
    EXPECT_EQ(ta.arena.used(), used);
  }
}

// With an offset, two jaws give the bytes of the same two meshes as one: each jaw's vertices
// keep their own offset faces (the jaws' vertices numbered on from the first's). Two cones
// side by side, the second with fewer sides, so that its vertex ids are no copy of the first's.
TEST(Heightfield, OffsetOverTwoJawsGivesTheBytesOfOneMeshOfBoth) {
  TestArena ta(size_t{256} << 20);
  Context ctx(&ta.arena);
  Mesh jaws[2] = {Mesh(&ta.arena), Mesh(&ta.arena)};
  const RigidTransform left = RigidTransform::translation(Vec3{-4, 0, 0});
  const RigidTransform right = RigidTransform::translation(Vec3{4, 0, 1});
  frustum(&jaws[0], 2.0, 3.0, 0.0, 6.0, 40, &left);
  frustum(&jaws[1], 2.0, 3.0, 0.0, 6.0, 30, &right);
  Mesh both(&ta.arena);
  for (const Mesh& m : jaws) ASSERT_TRUE(test::append_mesh_to(m, &both));
  SweepOptions o = down_over(Aabb{Vec3{-8, -4, 3}, Vec3{8, 4, 9}}, 0.2);
  o.offset = 0.3;
  HeightfieldOptions ho;
  ho.tolerance = 0.02;
  Mesh apart, one;
  HeightfieldStats st_apart, st_one;
  SPLINTCORE_ASSERT_OK(
      sweep_heightfield_mesh(ctx, Span<const Mesh>(jaws, 2), o, ho, &apart, &st_apart));
  SPLINTCORE_ASSERT_OK(
      sweep_heightfield_mesh(ctx, Span<const Mesh>(&both, 1), o, ho, &one, &st_one));
  EXPECT_EQ(st_apart.triangles_in, 70u);  // the two top caps' fans
  EXPECT_EQ(st_one.triangles_in, 70u);
  EXPECT_EQ(test::mesh_sha256(apart), test::mesh_sha256(one));
  EXPECT_GT(apart.triangles.size(), 0u);
}

// Each option of the height field at its bound: the value at the bound is taken, the nearest
// outside it refused by name (kInvalidArgument), with the output left empty. Bounds: voxel > 0
// and finite, 0 < tolerance <= voxel, 0 <= offset <= 20 voxels with no inset or closing,
// lower >= 0 and finite, each shift in [0, 1); and the output must be empty.
TEST(Heightfield, EachOptionIsTakenAtItsBoundAndRefusedBeyond) {
  TestArena ta(size_t{64} << 20);
  Context ctx(&ta.arena);
  Mesh cone(&ta.arena);
  frustum(&cone, 3.0, 5.0, 0.0, 8.0, 24);
  const Span<const Mesh> jaws(&cone, 1);
  // A coarse grid: the runs that are taken stay quick.
  const SweepOptions base = down_over(Aabb{Vec3{-7, -7, 4}, Vec3{7, 7, 10}}, 0.5);
  HeightfieldOptions hbase;
  hbase.tolerance = 0.05;
  const double below_one = std::nextafter(1.0, 0.0);
  const double inf = std::numeric_limits<double>::infinity();
  struct Case {
    const char* what;
    std::function<void(SweepOptions*, HeightfieldOptions*)> set;
    bool taken;
    const char* named;  // in the message when refused
  };
  const std::vector<Case> cases = {
      {"voxel 0", [](SweepOptions* o, HeightfieldOptions*) { o->voxel = 0; }, false,
       "the voxel must be > 0"},
      {"voxel -0.5", [](SweepOptions* o, HeightfieldOptions*) { o->voxel = -0.5; }, false,
       "the voxel must be > 0"},
      {"voxel inf", [&](SweepOptions* o, HeightfieldOptions*) { o->voxel = inf; }, false,
       "the voxel must be > 0"},
      {"voxel NaN", [](SweepOptions* o, HeightfieldOptions*) { o->voxel = std::nan(""); }, false,
       "the voxel must be > 0"},
      {"tolerance 0", [](SweepOptions*, HeightfieldOptions* h) { h->tolerance = 0; }, false,
       "the tolerance ("},
      {"tolerance = voxel", [](SweepOptions*, HeightfieldOptions* h) { h->tolerance = 0.5; }, true,
       nullptr},
      {"tolerance past the voxel",
       [](SweepOptions*, HeightfieldOptions* h) { h->tolerance = std::nextafter(0.5, 1.0); }, false,
       "the tolerance ("},
      {"offset 20 voxels", [](SweepOptions* o, HeightfieldOptions*) { o->offset = 10.0; }, true,
       nullptr},
      {"offset past 20 voxels",
       [](SweepOptions* o, HeightfieldOptions*) { o->offset = std::nextafter(10.0, 11.0); }, false,
       "offset"},
      {"offset below 0", [](SweepOptions* o, HeightfieldOptions*) { o->offset = -1e-9; }, false,
       "offset"},
      {"an inset", [](SweepOptions* o, HeightfieldOptions*) { o->inset = 0.1; }, false, "inset"},
      {"a closing", [](SweepOptions* o, HeightfieldOptions*) { o->closing_radius = 0.5; }, false,
       "closing"},
      {"lower below 0", [](SweepOptions*, HeightfieldOptions* h) { h->lower = -1e-9; }, false,
       "lower"},
      {"lower inf", [&](SweepOptions*, HeightfieldOptions* h) { h->lower = inf; }, false, "lower"},
      {"shift_u just below 1",
       [&](SweepOptions*, HeightfieldOptions* h) { h->shift_u = below_one; }, true, nullptr},
      {"shift_v just below 1",
       [&](SweepOptions*, HeightfieldOptions* h) { h->shift_v = below_one; }, true, nullptr},
      {"shift_v 1", [](SweepOptions*, HeightfieldOptions* h) { h->shift_v = 1.0; }, false,
       "shifts"},
      {"shift_u below 0", [](SweepOptions*, HeightfieldOptions* h) { h->shift_u = -1e-9; }, false,
       "shifts"},
      {"shift_v below 0", [](SweepOptions*, HeightfieldOptions* h) { h->shift_v = -1e-9; }, false,
       "shifts"},
  };
  for (const Case& c : cases) {
    SweepOptions o = base;
    HeightfieldOptions h = hbase;
    c.set(&o, &h);
    const size_t used = ta.arena.used();
    const Arena::Marker mark = ta.arena.mark();
    Mesh out(&ta.arena);
    const Status s = sweep_heightfield_mesh(ctx, jaws, o, h, &out);
    if (c.taken) {
      EXPECT_TRUE(s.is_ok()) << c.what << ": " << s.message();
      EXPECT_GT(out.triangles.size(), 0u) << c.what;
    } else {
      EXPECT_EQ(s.code(), StatusCode::kInvalidArgument) << c.what << ": " << s.message();
      EXPECT_NE(std::strstr(s.message(), c.named), nullptr) << c.what << ": " << s.message();
      EXPECT_TRUE(out.triangles.empty() && out.vertices.empty()) << c.what;
      EXPECT_EQ(ta.arena.used(), used) << c.what;
    }
    ta.arena.rewind(mark);
  }
  // An output that is not empty, by its triangles or by its vertices alone.
  for (int part = 0; part < 2; ++part) {
    Mesh out(&ta.arena);
    if (part == 0) {
      ASSERT_TRUE(out.vertices.push_back(Vec3{0, 0, 0}));
    } else {
      ASSERT_TRUE(out.triangles.push_back(Triangle{{0, 0, 0}}));
    }
    const Status s = sweep_heightfield_mesh(ctx, jaws, base, hbase, &out);
    EXPECT_EQ(s.code(), StatusCode::kInvalidArgument) << part;
    EXPECT_NE(std::strstr(s.message(), "output mesh must be empty"), nullptr) << s.message();
  }
}

}  // namespace
}  // namespace splintcore
