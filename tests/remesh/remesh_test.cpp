// Tests of Taubin smoothing (src/remesh/smooth.cpp) and quadric error decimation
// (src/remesh/decimate.cpp) on marching-tetrahedra spheres and tori: validity (closed, manifold,
// oriented, outward, genus kept, no self-intersection), distance to the analytic surface,
// volume, target counts, determinism, the arena exhaustion sweep and degenerate inputs.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "splintcore/platform.h"
#include "splintcore/remesh.h"
#include "splintcore/volume.h"
#include "support/distance_oracle.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

using test::TestArena;

constexpr double kPi = 3.14159265358979323846;

// An analytic signed distance sampled on a grid (sphere: a = radius; torus: a = ring radius,
// b = tube radius).
struct Shape {
  VolumeGrid grid;
  bool is_torus = false;
  Vec3 center{};
  double a = 0, b = 0;

  double sdf(const Vec3& p) const {
    const Vec3 q = p - center;
    if (!is_torus) return length(q) - a;
    const double ring = std::sqrt(q.x * q.x + q.y * q.y) - a;
    return std::sqrt(ring * ring + q.z * q.z) - b;
  }
  double volume() const {
    return is_torus ? 2 * kPi * kPi * a * b * b : 4.0 / 3.0 * kPi * a * a * a;
  }
};

Status fill_shape(void* user, uint32_t z_begin, uint32_t z_end, Span<float> out) {
  const Shape& s = *static_cast<const Shape*>(user);
  size_t i = 0;
  for (uint32_t z = z_begin; z < z_end; ++z) {
    for (uint32_t y = 0; y < s.grid.ny; ++y) {
      for (uint32_t x = 0; x < s.grid.nx; ++x, ++i) {
        const Vec3 p =
            s.grid.origin + Vec3{s.grid.spacing.x * x, s.grid.spacing.y * y, s.grid.spacing.z * z};
        out[i] = static_cast<float>(s.sdf(p));
      }
    }
  }
  return Status::ok();
}

Shape sphere_shape(double r, uint32_t cells) {
  Shape s;
  s.a = r;
  const double h = 2 * r / cells;
  s.grid.spacing = Vec3{h, h, h};
  s.grid.nx = s.grid.ny = s.grid.nz = cells + 4;
  s.grid.origin = Vec3{-1.3, 2.1, -0.7};
  const double c = h * (cells + 4) * 0.5;
  s.center = s.grid.origin + Vec3{c + 0.137 * h, c - 0.211 * h, c + 0.093 * h};
  return s;
}

Shape torus_shape(double big_r, double small_r, double h) {
  Shape s;
  s.is_torus = true;
  s.a = big_r;
  s.b = small_r;
  s.grid.spacing = Vec3{h, h, h};
  s.grid.nx = s.grid.ny = static_cast<uint32_t>(2 * (big_r + small_r) / h) + 5;
  s.grid.nz = static_cast<uint32_t>(2 * small_r / h) + 5;
  s.center = Vec3{h * s.grid.nx * 0.5 + 0.17 * h, h * s.grid.ny * 0.5 - 0.09 * h,
                  h * s.grid.nz * 0.5 + 0.05 * h};
  return s;
}

// The marching-tetrahedra mesh of the shape, copied out of the arena.
struct HostMesh {
  std::vector<Vec3> vertices;
  std::vector<Triangle> triangles;
};

HostMesh extract(const Shape& s) {
  TestArena ta(size_t{256} << 20);
  Context ctx(&ta.arena);
  Mesh mesh(&ta.arena);
  LayerSource source;
  source.fill = fill_shape;
  source.user = const_cast<Shape*>(&s);
  Status st = marching_cubes_mesh(ctx, s.grid, source, MarchingCubesOptions{}, &mesh);
  EXPECT_TRUE(st.is_ok()) << test::format(st);
  HostMesh h;
  h.vertices.assign(mesh.vertices.begin(), mesh.vertices.end());
  h.triangles.assign(mesh.triangles.begin(), mesh.triangles.end());
  return h;
}

// A Mesh in `arena` holding a copy of `h`.
Mesh to_arena(Arena& arena, const HostMesh& h) {
  Mesh m(&arena);
  EXPECT_TRUE(m.vertices.resize(h.vertices.size()));
  EXPECT_TRUE(m.triangles.resize(h.triangles.size()));
  if (!h.vertices.empty()) {
    std::memcpy(static_cast<void*>(m.vertices.data()), h.vertices.data(),
                h.vertices.size() * sizeof(Vec3));
  }
  if (!h.triangles.empty()) {
    std::memcpy(static_cast<void*>(m.triangles.data()), h.triangles.data(),
                h.triangles.size() * sizeof(Triangle));
  }
  return m;
}

std::string hash_of(const Mesh& m) {
  Sha256 sha;
  sha.update(m.vertices.data(), m.vertices.size() * sizeof(Vec3));
  sha.update(m.triangles.data(), m.triangles.size() * sizeof(Triangle));
  uint8_t digest[32];
  sha.finish(digest);
  char hex[65];
  Sha256::to_hex(digest, hex);
  return hex;
}

MeshReport report_of(const Mesh& mesh) {
  TestArena scratch(size_t{128} << 20);
  Context ctx(&scratch.arena);
  MeshReport report;
  Status st = check_mesh(ctx, mesh, &report);
  EXPECT_TRUE(st.is_ok()) << test::format(st);
  return report;
}

void expect_valid_solid(const Mesh& mesh, int64_t genus) {
  const MeshReport r = report_of(mesh);
  EXPECT_TRUE(r.closed()) << r.boundary_edges << " boundary edges";
  EXPECT_TRUE(r.edge_manifold()) << r.nonmanifold_edges << " non-manifold edges";
  EXPECT_TRUE(r.oriented()) << r.orientation_conflicts << " orientation conflicts";
  EXPECT_TRUE(r.outward()) << "volume " << r.volume;
  EXPECT_EQ(r.degenerate_triangles, 0u);
  EXPECT_EQ(r.duplicate_triangles, 0u);
  EXPECT_EQ(r.unreferenced_vertices, 0u);
  EXPECT_EQ(r.shells, 1u);
  EXPECT_EQ(r.genus, genus);
  TestArena scratch(size_t{128} << 20);
  Context ctx(&scratch.arena);
  double volume = 0;
  SPLINTCORE_EXPECT_OK(check_closed_oriented(ctx, mesh, &volume));
}

double worst_distance(const Shape& s, const Mesh& m) {
  double worst = 0;
  for (const Vec3& p : m.vertices) worst = std::max(worst, std::fabs(s.sdf(p)));
  return worst;
}

// Vertex ids are in order of first use by the triangles, none unused.
void expect_first_use_order(const Mesh& m) {
  uint32_t next = 0;
  for (const Triangle& t : m.triangles) {
    for (uint32_t v : t.v) {
      ASSERT_LE(v, next);
      if (v == next) ++next;
    }
  }
  EXPECT_EQ(next, m.vertices.size());
}

Status decimate(Arena& arena, const Mesh& in, const DecimateOptions& options, Mesh* out,
                DecimateStats* stats = nullptr, const Executor* executor = nullptr) {
  Context ctx(&arena, executor, nullptr);
  out->bind(&arena);
  return decimate_qem(ctx, in, options, out, stats);
}

// ---------------------------------------------------------------------------------------------
// Taubin smoothing.

TEST(TaubinSmooth, ShrinksLessThanLaplacianAndStaysValid) {
  const Shape s = sphere_shape(5.0, 30);
  HostMesh h = extract(s);
  // Radial noise of +-2% of the radius (fixed seed): what smoothing is for.
  uint64_t state = 99;
  for (Vec3& p : h.vertices) {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    const double n = (static_cast<double>(state >> 11) * (1.0 / 9007199254740992.0) - 0.5) * 0.04;
    p = s.center + (p - s.center) * (1.0 + n);
  }
  TestArena ta(size_t{128} << 20);
  Context ctx(&ta.arena);
  Mesh laplace = to_arena(ta.arena, h);
  Mesh taubin = to_arena(ta.arena, h);
  const size_t used = ta.arena.used();
  TaubinOptions plain;
  plain.mu = 0.0;
  plain.iterations = 10;
  TaubinOptions options;  // lambda 0.5, mu -0.53
  options.iterations = 10;
  TaubinStats ps, ts;
  SPLINTCORE_ASSERT_OK(taubin_smooth(ctx, &laplace, plain, &ps));
  SPLINTCORE_ASSERT_OK(taubin_smooth(ctx, &taubin, options, &ts));
  EXPECT_EQ(ta.arena.used(), used);
  EXPECT_EQ(ps.volume_before, ts.volume_before);
  const double loss_plain = ps.volume_before - ps.volume_after;
  const double loss_taubin = std::fabs(ts.volume_before - ts.volume_after);
  EXPECT_GT(loss_plain, 0.0);
  EXPECT_LT(loss_taubin, 0.25 * loss_plain) << loss_taubin << " vs " << loss_plain;
  EXPECT_EQ(ts.volume_after, mesh_volume(taubin));
  EXPECT_EQ(ts.edges, h.triangles.size() * 3 / 2);
  EXPECT_EQ(ts.boundary_vertices, 0u);
  EXPECT_EQ(ts.clamped, 0u);
  // The noise is smoothed out: the spread of radii drops, by more than half.
  auto spread = [&](const Mesh& m) {  // standard deviation of the radius
    double sum = 0, sum2 = 0;
    for (const Vec3& p : m.vertices) {
      const double d = length(p - s.center);
      sum += d;
      sum2 += d * d;
    }
    const double n = static_cast<double>(m.vertices.size());
    return std::sqrt(std::max(0.0, sum2 / n - (sum / n) * (sum / n)));
  };
  const Mesh original = to_arena(ta.arena, h);
  EXPECT_LT(spread(taubin), 0.5 * spread(original));
  EXPECT_GT(spread(original), 0.01 * s.a);
  expect_valid_solid(taubin, 0);
  // Triangles are untouched.
  EXPECT_EQ(0, std::memcmp(taubin.triangles.data(), h.triangles.data(),
                           h.triangles.size() * sizeof(Triangle)));
}

TEST(TaubinSmooth, SameBitsTwiceAndWithThreads) {
  const Shape s = torus_shape(4.0, 1.5, 0.3);
  const HostMesh h = extract(s);
  TestArena ta(size_t{128} << 20);
  Mesh a = to_arena(ta.arena, h);
  Mesh b = to_arena(ta.arena, h);
  Mesh c = to_arena(ta.arena, h);
  TaubinOptions options;
  options.iterations = 7;
  SPLINTCORE_ASSERT_OK(taubin_smooth(Context(&ta.arena), &a, options));
  SPLINTCORE_ASSERT_OK(taubin_smooth(Context(&ta.arena), &b, options));
  ThreadExecutor pool(4);
  SPLINTCORE_ASSERT_OK(taubin_smooth(Context(&ta.arena, &pool.executor(), nullptr), &c, options));
  EXPECT_EQ(hash_of(a), hash_of(b));
  EXPECT_EQ(hash_of(a), hash_of(c));
  EXPECT_NE(hash_of(a), hash_of(to_arena(ta.arena, h)));
  expect_valid_solid(a, 1);
}

TEST(TaubinSmooth, ClampKeepsVerticesNearTheirStart) {
  const Shape s = sphere_shape(5.0, 16);
  const HostMesh h = extract(s);
  TestArena ta(size_t{64} << 20);
  Mesh m = to_arena(ta.arena, h);
  TaubinOptions options;
  options.iterations = 20;
  options.mu = 0.0;  // plain Laplacian: moves far without the clamp
  options.max_displacement = 0.02;
  TaubinStats stats;
  SPLINTCORE_ASSERT_OK(taubin_smooth(Context(&ta.arena), &m, options, &stats));
  EXPECT_GT(stats.clamped, 0u);
  double worst = 0;
  for (size_t i = 0; i < h.vertices.size(); ++i) {
    worst = std::max(worst, length(m.vertices[i] - h.vertices[i]));
  }
  EXPECT_LE(worst, 0.02 * (1 + 1e-12));
  EXPECT_GT(worst, 0.019);
}

TEST(TaubinSmooth, OpenMeshKeepsItsBoundaryWhenAsked) {
  // A flat 6 x 6 grid of squares, its interior vertices lifted in a checkerboard pattern.
  HostMesh h;
  const int n = 6;
  for (int y = 0; y <= n; ++y) {
    for (int x = 0; x <= n; ++x) {
      const bool inner = x > 0 && y > 0 && x < n && y < n;
      h.vertices.push_back(Vec3{double(x), double(y), inner && ((x + y) & 1) ? 0.3 : 0.0});
    }
  }
  for (int y = 0; y < n; ++y) {
    for (int x = 0; x < n; ++x) {
      const uint32_t v0 = uint32_t(y * (n + 1) + x), v1 = v0 + 1, v2 = v0 + n + 1, v3 = v2 + 1;
      h.triangles.push_back(Triangle{{v0, v1, v3}});
      h.triangles.push_back(Triangle{{v0, v3, v2}});
    }
  }
  TestArena ta(size_t{16} << 20);
  for (bool fix : {true, false}) {
    Mesh m = to_arena(ta.arena, h);
    TaubinOptions options;
    options.fix_boundary = fix;
    TaubinStats stats;
    SPLINTCORE_ASSERT_OK(taubin_smooth(Context(&ta.arena), &m, options, &stats));
    EXPECT_EQ(stats.boundary_vertices, uint64_t(4 * n));
    bool boundary_kept = true;
    double bump = 0;
    for (size_t i = 0; i < h.vertices.size(); ++i) {
      const int x = int(i) % (n + 1), y = int(i) / (n + 1);
      const bool inner = x > 0 && y > 0 && x < n && y < n;
      if (!inner && m.vertices[i] != h.vertices[i]) boundary_kept = false;
      if (inner) bump = std::max(bump, std::fabs(m.vertices[i].z - 0.15));
    }
    EXPECT_EQ(boundary_kept, fix);
    EXPECT_LT(bump, 0.15);  // the checkerboard is flattened
  }
}

TEST(TaubinSmooth, ErrorsLeaveTheMeshUnchanged) {
  const Shape s = sphere_shape(3.0, 8);
  const HostMesh h = extract(s);
  TestArena ta(size_t{16} << 20);
  Mesh m = to_arena(ta.arena, h);
  const std::string before = hash_of(m);
  const size_t used = ta.arena.used();
  Context ctx(&ta.arena);
  TaubinOptions bad;
  bad.lambda = 0.0;
  EXPECT_EQ(taubin_smooth(ctx, &m, bad).code(), StatusCode::kInvalidArgument);
  bad = TaubinOptions{};
  bad.mu = 0.2;
  EXPECT_EQ(taubin_smooth(ctx, &m, bad).code(), StatusCode::kInvalidArgument);
  bad = TaubinOptions{};
  bad.max_displacement = std::nan("");
  EXPECT_EQ(taubin_smooth(ctx, &m, bad).code(), StatusCode::kInvalidArgument);
  m.triangles[5].v[1] = static_cast<uint32_t>(m.vertices.size());
  Status st = taubin_smooth(ctx, &m, TaubinOptions{});
  EXPECT_EQ(st.code(), StatusCode::kInvalidMesh);
  EXPECT_EQ(st.index(), 5u);
  m.triangles[5] = h.triangles[5];
  m.vertices[7].y = HUGE_VAL;
  st = taubin_smooth(ctx, &m, TaubinOptions{});
  EXPECT_EQ(st.code(), StatusCode::kNonFinite);
  EXPECT_EQ(st.index(), 7u);
  m.vertices[7] = h.vertices[7];
  EXPECT_EQ(hash_of(m), before);
  EXPECT_EQ(ta.arena.used(), used);
  // Exhaustion: every cap below the need fails cleanly with the mesh unchanged; the bound holds.
  const uint64_t bound = taubin_smooth_bound(h.vertices.size(), h.triangles.size());
  TaubinOptions clamp;
  clamp.max_displacement = 0.1;
  std::string reference;
  for (uint64_t cap = 0;; cap += 4096) {
    TestArena small(static_cast<size_t>(cap));
    Mesh copy = to_arena(ta.arena, h);
    TaubinStats stats;
    Status r = taubin_smooth(Context(&small.arena), &copy, clamp, &stats);
    if (r.is_ok()) {
      EXPECT_LE(small.arena.high_water(), bound);
      reference = hash_of(copy);
      break;
    }
    ASSERT_EQ(r.code(), StatusCode::kArenaExhausted) << test::format(r);
    EXPECT_EQ(small.arena.used(), 0u);
    EXPECT_EQ(hash_of(copy), before);
    ASSERT_LT(cap, bound + 4096);
  }
  Mesh again = to_arena(ta.arena, h);
  SPLINTCORE_ASSERT_OK(taubin_smooth(Context(&ta.arena), &again, clamp));
  EXPECT_EQ(hash_of(again), reference);
  // An empty mesh is a no-op.
  Mesh empty(&ta.arena);
  TaubinStats es;
  SPLINTCORE_EXPECT_OK(taubin_smooth(ctx, &empty, TaubinOptions{}, &es));
  EXPECT_EQ(es.volume_after, 0.0);
}

// ---------------------------------------------------------------------------------------------
// Decimation.

TEST(DecimateQem, SphereToTenPercentStaysCloseAndValid) {
  const double r = 5.0;
  const Shape s = sphere_shape(r, 40);
  const HostMesh h = extract(s);
  ASSERT_GT(h.triangles.size(), 20000u);
  TestArena ta(size_t{256} << 20);
  Mesh in = to_arena(ta.arena, h);
  const size_t used = ta.arena.used();
  DecimateOptions options;
  options.target_triangles = h.triangles.size() / 10;
  Mesh out;
  DecimateStats stats;
  SPLINTCORE_ASSERT_OK(decimate(ta.arena, in, options, &out, &stats));
  EXPECT_EQ(stats.stop, DecimateStop::kTargetReached);
  EXPECT_LE(out.triangles.size(), options.target_triangles);
  EXPECT_GE(out.triangles.size() + 2, options.target_triangles);
  EXPECT_EQ(stats.output_triangles, out.triangles.size());
  EXPECT_EQ(stats.output_vertices, out.vertices.size());
  EXPECT_EQ(stats.collapses * 2, h.triangles.size() - out.triangles.size());
  EXPECT_EQ(out.vertices.size(), out.triangles.size() / 2 + 2);  // Euler, genus 0
  // Only the output stays in the arena, where the top was (alignment padding aside).
  const size_t out_bytes =
      out.triangles.size() * sizeof(Triangle) + out.vertices.size() * sizeof(Vec3);
  EXPECT_GE(ta.arena.used(), used + out_bytes);
  EXPECT_LE(ta.arena.used(), used + out_bytes + 32);
  EXPECT_GT(static_cast<const void*>(out.triangles.data()),
            static_cast<const void*>(in.vertices.data()));
  expect_valid_solid(out, 0);
  expect_first_use_order(out);
  const double worst = worst_distance(s, out);
  EXPECT_LT(worst, 0.05 * r) << worst;
  EXPECT_LT(worst, 0.02 * r) << worst;
  EXPECT_GT(stats.max_error, 0.0);
  EXPECT_LT(stats.max_error, 0.02 * r);
  EXPECT_NEAR(mesh_volume(out), s.volume(), 0.01 * s.volume());
  EXPECT_NEAR(mesh_volume(out), mesh_volume(in), 0.005 * s.volume());
  // No self-intersection.
  TestArena scratch(size_t{256} << 20);
  SelfIntersectionReport si;
  SPLINTCORE_ASSERT_OK(find_self_intersections(Context(&scratch.arena), out, 0, &si));
  EXPECT_FALSE(si.self_intersecting()) << si.first_a << " " << si.first_b;
}

TEST(DecimateQem, ModeratelyDecimatedSphereHasNoSelfIntersection) {
  const Shape s = sphere_shape(5.0, 24);
  const HostMesh h = extract(s);
  TestArena ta(size_t{128} << 20);
  Mesh in = to_arena(ta.arena, h);
  for (uint64_t fraction : {2u, 4u, 20u}) {
    SCOPED_TRACE(fraction);
    DecimateOptions options;
    options.target_triangles = h.triangles.size() / fraction;
    Mesh out;
    SPLINTCORE_ASSERT_OK(decimate(ta.arena, in, options, &out));
    expect_valid_solid(out, 0);
    TestArena scratch(size_t{128} << 20);
    SelfIntersectionReport si;
    SPLINTCORE_ASSERT_OK(find_self_intersections(Context(&scratch.arena), out, 0, &si));
    EXPECT_FALSE(si.self_intersecting());
    EXPECT_LT(worst_distance(s, out), 0.05 * s.a);
  }
}

TEST(DecimateQem, TorusKeepsGenusOne) {
  const Shape s = torus_shape(4.0, 1.5, 0.15);
  const HostMesh h = extract(s);
  TestArena ta(size_t{256} << 20);
  Mesh in = to_arena(ta.arena, h);
  for (uint64_t fraction : {10u, 50u}) {
    SCOPED_TRACE(fraction);
    DecimateOptions options;
    options.target_triangles = h.triangles.size() / fraction;
    Mesh out;
    DecimateStats stats;
    SPLINTCORE_ASSERT_OK(decimate(ta.arena, in, options, &out, &stats));
    EXPECT_EQ(stats.stop, DecimateStop::kTargetReached);
    EXPECT_LE(out.triangles.size(), options.target_triangles);
    expect_valid_solid(out, 1);
    EXPECT_EQ(out.vertices.size(), out.triangles.size() / 2);  // Euler, genus 1
    EXPECT_LT(worst_distance(s, out), (fraction == 10 ? 0.05 : 0.15) * s.b);
    EXPECT_NEAR(mesh_volume(out), s.volume(), (fraction == 10 ? 0.01 : 0.05) * s.volume());
  }
}

TEST(DecimateQem, DeterministicAndValidUnderPermutation) {
  const Shape s = torus_shape(3.0, 1.0, 0.2);
  const HostMesh h = extract(s);
  TestArena ta(size_t{256} << 20);
  Mesh in = to_arena(ta.arena, h);
  DecimateOptions options;
  options.target_triangles = h.triangles.size() / 8;
  Mesh a, b;
  SPLINTCORE_ASSERT_OK(decimate(ta.arena, in, options, &a));
  const std::string first = hash_of(a);
  SPLINTCORE_ASSERT_OK(decimate(ta.arena, in, options, &b));
  EXPECT_EQ(hash_of(b), first);
  // Another arena (other addresses, another cap) and an executor: the same bytes.
  {
    TestArena other(size_t{100} << 20);
    ThreadExecutor pool(3);
    Mesh in2 = to_arena(other.arena, h);
    Mesh c;
    SPLINTCORE_ASSERT_OK(decimate(other.arena, in2, options, &c, nullptr, &pool.executor()));
    EXPECT_EQ(hash_of(c), first);
  }
  // Triangles in another order (each also rotated): maybe another result, always valid.
  HostMesh p = h;
  uint64_t state = 12345;
  for (size_t i = p.triangles.size(); i > 1; --i) {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    std::swap(p.triangles[i - 1], p.triangles[(state >> 33) % i]);
  }
  for (size_t i = 0; i < p.triangles.size(); i += 3) {
    Triangle& t = p.triangles[i];
    t = Triangle{{t.v[1], t.v[2], t.v[0]}};
  }
  Mesh pin = to_arena(ta.arena, p);
  Mesh c;
  DecimateStats stats;
  SPLINTCORE_ASSERT_OK(decimate(ta.arena, pin, options, &c, &stats));
  EXPECT_EQ(stats.stop, DecimateStop::kTargetReached);
  EXPECT_LE(c.triangles.size(), options.target_triangles);
  expect_valid_solid(c, 1);
  EXPECT_LT(worst_distance(s, c), 0.05 * s.b);
}

TEST(DecimateQem, ErrorLimitStopsEarly) {
  const Shape s = sphere_shape(5.0, 24);
  const HostMesh h = extract(s);
  TestArena ta(size_t{128} << 20);
  Mesh in = to_arena(ta.arena, h);
  uint64_t previous = 0;
  for (double limit : {0.002, 0.01, 0.05}) {
    SCOPED_TRACE(limit);
    DecimateOptions options;
    options.max_error = limit;
    Mesh out;
    DecimateStats stats;
    SPLINTCORE_ASSERT_OK(decimate(ta.arena, in, options, &out, &stats));
    EXPECT_EQ(stats.stop, DecimateStop::kErrorLimit);
    EXPECT_LE(stats.max_error, limit);
    EXPECT_GT(stats.collapses, 0u);
    EXPECT_GT(stats.collapses, previous);
    previous = stats.collapses;
    expect_valid_solid(out, 0);
    // The error is an RMS distance to the original planes: the vertices stay near the sphere.
    EXPECT_LT(worst_distance(s, out), 0.05 * s.a);
  }
  // Both limits: whichever comes first.
  DecimateOptions both;
  both.max_error = 0.05;
  both.target_triangles = h.triangles.size() / 2;
  Mesh out;
  DecimateStats stats;
  SPLINTCORE_ASSERT_OK(decimate(ta.arena, in, both, &out, &stats));
  EXPECT_EQ(stats.stop, DecimateStop::kTargetReached);
}

// The largest distance from a point of `points` to the mesh, by brute force.
double oracle_worst_to_mesh(const std::vector<Vec3>& points, const Mesh& m) {
  double worst = 0;
  for (const Vec3& p : points) worst = std::max(worst, test::oracle_distance_to_mesh(p, m));
  return worst;
}

TEST(DecimateQem, MaxDistanceHoldsAtEveryInputVertex) {
  // A torus and a sphere at a fine grid, decimated keeping positions with a distance bound
  // and a loose quadric limit (the bound is what stops it): every input vertex within the
  // bound of the result (the brute-force oracle), far fewer triangles, still a valid solid.
  const Shape shapes[2] = {torus_shape(4.0, 1.5, 0.2), sphere_shape(5.0, 40)};
  const int64_t genus[2] = {1, 0};
  for (int k = 0; k < 2; ++k) {
    SCOPED_TRACE(k);
    const HostMesh h = extract(shapes[k]);
    TestArena ta(size_t{512} << 20);
    Mesh in = to_arena(ta.arena, h);
    const double bound = 0.1 * shapes[k].grid.spacing.x;  // a tenth of the grid step
    for (double limit : {0.0, bound}) {
      SCOPED_TRACE(limit);
      DecimateOptions o;
      o.keep_positions = true;
      o.max_error = limit > 0 ? limit : 1.0;  // mm; 1: no quadric limit in practice
      o.max_distance = bound;
      std::vector<uint32_t> removed(h.vertices.size());
      o.removed_map = Span<uint32_t>(removed.data(), removed.size());
      Mesh out;
      DecimateStats stats;
      const Arena::Marker before = ta.arena.mark();
      SPLINTCORE_ASSERT_OK(decimate(ta.arena, in, o, &out, &stats));
      EXPECT_GT(stats.rejected_distance, 0u);
      EXPECT_LT(out.triangles.size() * 3, h.triangles.size()) << out.triangles.size();
      expect_valid_solid(out, genus[k]);
      const double worst = oracle_worst_to_mesh(h.vertices, out);
      EXPECT_LE(worst, bound) << worst;
      EXPECT_GT(worst, 0.5 * bound) << worst;  // the bound is what stopped it
      // Every removed vertex is assigned to a triangle within reach of it; kept ones to none.
      uint64_t gone = 0;
      for (size_t i = 0; i < removed.size(); ++i) {
        if (removed[i] == ~0u) continue;
        ++gone;
        ASSERT_LT(removed[i], out.triangles.size());
        const Triangle& t = out.triangles[removed[i]];
        EXPECT_LE(test::oracle_distance2(h.vertices[i], out.vertices[t.v[0]], out.vertices[t.v[1]],
                                         out.vertices[t.v[2]]),
                  bound * bound * (1 + 1e-12));
      }
      EXPECT_EQ(gone + out.vertices.size(), h.vertices.size());
      ta.arena.rewind(before);
    }
  }
}

TEST(DecimateQem, MaxDistanceCarriesGivenSamples) {
  // Decimated once, then again with the first pass's removed vertices as given samples: every
  // original vertex stays within the bound of the second result (not twice the bound).
  const Shape s = sphere_shape(5.0, 40);
  const HostMesh h = extract(s);
  TestArena ta(size_t{512} << 20);
  Mesh in = to_arena(ta.arena, h);
  const double bound = 0.02;
  DecimateOptions first;
  first.keep_positions = true;
  first.max_error = 1.0;
  first.max_distance = bound;
  first.target_triangles = h.triangles.size() / 3;
  std::vector<uint32_t> removed(h.vertices.size());
  first.removed_map = Span<uint32_t>(removed.data(), removed.size());
  Mesh mid;
  SPLINTCORE_ASSERT_OK(decimate(ta.arena, in, first, &mid, nullptr));
  std::vector<Vec3> samples;
  std::vector<uint32_t> homes;
  for (size_t i = 0; i < removed.size(); ++i) {
    if (removed[i] == ~0u) continue;
    samples.push_back(h.vertices[i]);
    homes.push_back(removed[i]);
  }
  ASSERT_GT(samples.size(), 0u);
  DecimateOptions second = first;
  second.target_triangles = 0;
  second.removed_map = Span<uint32_t>();
  second.samples = Span<const Vec3>(samples.data(), samples.size());
  second.sample_triangles = Span<const uint32_t>(homes.data(), homes.size());
  std::vector<uint32_t> map(samples.size());
  second.sample_map = Span<uint32_t>(map.data(), map.size());
  Mesh out;
  DecimateStats stats;
  SPLINTCORE_ASSERT_OK(decimate(ta.arena, mid, second, &out, &stats));
  EXPECT_LT(out.triangles.size(), mid.triangles.size());
  EXPECT_LE(oracle_worst_to_mesh(h.vertices, out), bound);
  for (size_t i = 0; i < map.size(); ++i) ASSERT_LT(map[i], out.triangles.size());
  // Without the given samples the second pass strays further from the original.
  DecimateOptions forgetful = second;
  forgetful.samples = Span<const Vec3>();
  forgetful.sample_triangles = Span<const uint32_t>();
  forgetful.sample_map = Span<uint32_t>();
  Mesh loose;
  SPLINTCORE_ASSERT_OK(decimate(ta.arena, mid, forgetful, &loose, nullptr));
  EXPECT_GT(oracle_worst_to_mesh(h.vertices, loose), bound);
}

TEST(DecimateQem, ExhaustionSweepFailsCleanlyThenMatches) {
  const Shape s = sphere_shape(3.0, 10);
  const HostMesh h = extract(s);
  TestArena big(size_t{64} << 20);
  Mesh in = to_arena(big.arena, h);
  DecimateOptions options;
  options.target_triangles = h.triangles.size() / 5;
  Mesh reference;
  SPLINTCORE_ASSERT_OK(decimate(big.arena, in, options, &reference));
  const std::string expected = hash_of(reference);
  const uint64_t bound = decimate_qem_bound(h.vertices.size(), h.triangles.size());
  ASSERT_GT(bound, 0u);
  uint32_t failures = 0;
  for (uint64_t cap = 0;; cap += 1024) {
    SCOPED_TRACE(cap);
    TestArena small(static_cast<size_t>(cap) + 32);
    ASSERT_NE(small.arena.allocate(32), nullptr);  // something below, as in real use
    Mesh out;
    DecimateStats stats;
    Status st = decimate(small.arena, in, options, &out, &stats);
    if (st.is_ok()) {
      EXPECT_EQ(hash_of(out), expected);
      EXPECT_LE(small.arena.high_water() - 32, bound);
      break;
    }
    ++failures;
    ASSERT_EQ(st.code(), StatusCode::kArenaExhausted) << test::format(st);
    EXPECT_EQ(small.arena.used(), 32u);
    EXPECT_TRUE(out.vertices.empty());
    EXPECT_TRUE(out.triangles.empty());
    ASSERT_LE(cap, bound);
  }
  EXPECT_GT(failures, 10u);
}

TEST(DecimateQem, DegenerateAndInvalidInputs) {
  TestArena ta(size_t{16} << 20);
  // Empty.
  Mesh empty(&ta.arena);
  DecimateOptions options;
  options.target_triangles = 10;
  Mesh out;
  DecimateStats stats;
  SPLINTCORE_EXPECT_OK(decimate(ta.arena, empty, options, &out, &stats));
  EXPECT_TRUE(out.triangles.empty());
  EXPECT_TRUE(out.vertices.empty());
  // A tetrahedron cannot go below 4 triangles.
  HostMesh tet;
  tet.vertices = {Vec3{0, 0, 0}, Vec3{1, 0, 0}, Vec3{0, 1, 0}, Vec3{0, 0, 1}};
  tet.triangles = {Triangle{{0, 2, 1}}, Triangle{{0, 1, 3}}, Triangle{{0, 3, 2}},
                   Triangle{{1, 2, 3}}};
  Mesh tin = to_arena(ta.arena, tet);
  options.target_triangles = 2;
  SPLINTCORE_ASSERT_OK(decimate(ta.arena, tin, options, &out, &stats));
  EXPECT_EQ(stats.stop, DecimateStop::kNoValidCollapse);
  EXPECT_EQ(out.triangles.size(), 4u);
  EXPECT_EQ(stats.collapses, 0u);
  EXPECT_GT(stats.rejected_link, 0u);
  expect_valid_solid(out, 0);
  // A target at or above the count: a compact copy (an unused vertex dropped).
  HostMesh extra = tet;
  extra.vertices.insert(extra.vertices.begin(), Vec3{9, 9, 9});
  for (Triangle& t : extra.triangles) {
    for (uint32_t& v : t.v) ++v;
  }
  Mesh ein = to_arena(ta.arena, extra);
  options.target_triangles = 100;
  Mesh copy, plain;
  SPLINTCORE_ASSERT_OK(decimate(ta.arena, ein, options, &copy, &stats));
  EXPECT_EQ(stats.stop, DecimateStop::kTargetReached);
  EXPECT_EQ(stats.collapses, 0u);
  SPLINTCORE_ASSERT_OK(decimate(ta.arena, tin, options, &plain));
  EXPECT_EQ(hash_of(copy), hash_of(plain));
  EXPECT_EQ(copy.vertices.size(), 4u);
  expect_first_use_order(copy);
  // Open: one triangle of the tetrahedron missing.
  HostMesh open = tet;
  open.triangles.pop_back();
  Mesh oin = to_arena(ta.arena, open);
  const size_t used = ta.arena.used();
  Mesh none;
  Status st = decimate(ta.arena, oin, options, &none);
  EXPECT_EQ(st.code(), StatusCode::kInvalidMesh);
  EXPECT_NE(std::string(st.message()).find("boundary edge"), std::string::npos) << st.message();
  EXPECT_EQ(ta.arena.used(), used);
  EXPECT_TRUE(none.triangles.empty());
  // Two tetrahedra sharing a vertex: edge-manifold but not vertex-manifold.
  HostMesh bow = tet;
  bow.vertices.push_back(Vec3{-1, 0, 0});
  bow.vertices.push_back(Vec3{0, -1, 0});
  bow.vertices.push_back(Vec3{0, 0, -1});
  bow.triangles.push_back(Triangle{{0, 4, 5}});
  bow.triangles.push_back(Triangle{{0, 6, 4}});
  bow.triangles.push_back(Triangle{{0, 5, 6}});
  bow.triangles.push_back(Triangle{{4, 6, 5}});
  {
    // Orient the second one outward too: it is the first reflected through the origin.
    TestArena scratch(size_t{1} << 20);
    Mesh bm = to_arena(scratch.arena, bow);
    MeshReport r = report_of(bm);
    ASSERT_TRUE(r.closed() && r.oriented() && r.edge_manifold() && r.outward());
  }
  Mesh bin = to_arena(ta.arena, bow);
  st = decimate(ta.arena, bin, options, &none);
  EXPECT_EQ(st.code(), StatusCode::kInvalidMesh);
  EXPECT_NE(std::string(st.message()).find("vertex 0"), std::string::npos) << st.message();
  // Inconsistent orientation: one triangle flipped.
  HostMesh flipped = tet;
  std::swap(flipped.triangles[1].v[0], flipped.triangles[1].v[1]);
  Mesh fin = to_arena(ta.arena, flipped);
  EXPECT_EQ(decimate(ta.arena, fin, options, &none).code(), StatusCode::kInvalidMesh);
  // Repeated id, index out of range, non-finite vertex, bad options, non-empty output.
  HostMesh rep = tet;
  rep.triangles[2].v[2] = 0;
  Mesh rin = to_arena(ta.arena, rep);
  st = decimate(ta.arena, rin, options, &none);
  EXPECT_EQ(st.code(), StatusCode::kInvalidMesh);
  EXPECT_EQ(st.index(), 2u);
  HostMesh range = tet;
  range.triangles[3].v[0] = 4;
  Mesh gin = to_arena(ta.arena, range);
  EXPECT_EQ(decimate(ta.arena, gin, options, &none).code(), StatusCode::kInvalidMesh);
  HostMesh nan = tet;
  nan.vertices[2].z = std::nan("");
  Mesh nin = to_arena(ta.arena, nan);
  st = decimate(ta.arena, nin, options, &none);
  EXPECT_EQ(st.code(), StatusCode::kNonFinite);
  EXPECT_EQ(st.index(), 2u);
  DecimateOptions nothing;
  EXPECT_EQ(decimate(ta.arena, tin, nothing, &none).code(), StatusCode::kInvalidArgument);
  nothing.max_error = -1;
  EXPECT_EQ(decimate(ta.arena, tin, nothing, &none).code(), StatusCode::kInvalidArgument);
  Context ctx(&ta.arena);
  EXPECT_EQ(decimate_qem(ctx, tin, options, &copy).code(), StatusCode::kInvalidArgument);
  // The distance bound's options: each misuse a clear kInvalidArgument (or kNonFinite for a
  // sample), the arena untouched.
  const Vec3 samples[2] = {Vec3{0.2, 0.2, 0}, Vec3{0.1, 0, 0.1}};
  const uint32_t homes[2] = {0, 1};
  const uint32_t far_home[2] = {0, 4};
  const uint8_t approximate[4] = {0, 0, 1, 0};
  uint32_t map[2];
  struct Misuse {
    const char* what;
    void (*set)(DecimateOptions*);
  };
  DecimateOptions base;
  base.target_triangles = 2;
  base.keep_positions = true;
  base.max_distance = 0.1;
  const Misuse misuses[] = {
      {"max_distance without keep_positions",
       [](DecimateOptions* o) { o->keep_positions = false; }},
      {"max_distance negative", [](DecimateOptions* o) { o->max_distance = -0.1; }},
      {"max_distance NaN", [](DecimateOptions* o) { o->max_distance = std::nan(""); }},
      {"samples without max_distance", [](DecimateOptions* o) { o->max_distance = 0; }},
      {"sample_triangles short",
       [](DecimateOptions* o) { o->sample_triangles = Span<const uint32_t>(); }},
      {"sample_sources short",
       [](DecimateOptions* o) {
         o->sample_sources = Span<const uint32_t>(o->sample_triangles.data(), 1);
       }},
      {"sample_map short",
       [](DecimateOptions* o) { o->sample_map = Span<uint32_t>(o->sample_map.data(), 1); }},
      {"approximate short",
       [](DecimateOptions* o) { o->approximate = Span<const uint8_t>(o->approximate.data(), 3); }},
  };
  for (const Misuse& m : misuses) {
    SCOPED_TRACE(m.what);
    DecimateOptions o = base;
    o.samples = Span<const Vec3>(samples, 2);
    o.sample_triangles = Span<const uint32_t>(homes, 2);
    o.sample_map = Span<uint32_t>(map, 2);
    o.approximate = Span<const uint8_t>(approximate, 4);
    m.set(&o);
    const size_t before = ta.arena.used();
    Mesh bad;
    EXPECT_EQ(decimate(ta.arena, tin, o, &bad).code(), StatusCode::kInvalidArgument);
    EXPECT_EQ(ta.arena.used(), before);
  }
  {
    DecimateOptions o = base;
    o.samples = Span<const Vec3>(samples, 2);
    o.sample_triangles = Span<const uint32_t>(far_home, 2);  // triangle 4 of 4
    st = decimate(ta.arena, tin, o, &none);
    EXPECT_EQ(st.code(), StatusCode::kInvalidArgument);
    EXPECT_EQ(st.index(), 1u);
    const Vec3 bad_samples[2] = {Vec3{0.2, 0.2, 0}, Vec3{0, std::nan(""), 0}};
    o.samples = Span<const Vec3>(bad_samples, 2);
    o.sample_triangles = Span<const uint32_t>(homes, 2);
    st = decimate(ta.arena, tin, o, &none);
    EXPECT_EQ(st.code(), StatusCode::kNonFinite);
    EXPECT_EQ(st.index(), 1u);
    // Well formed: the tetrahedron stays, and each sample is on the triangle it was given.
    o.samples = Span<const Vec3>(samples, 2);
    o.sample_map = Span<uint32_t>(map, 2);
    Mesh kept;
    SPLINTCORE_ASSERT_OK(decimate(ta.arena, tin, o, &kept));
    EXPECT_EQ(kept.triangles.size(), 4u);
    EXPECT_EQ(map[0], 0u);
    EXPECT_EQ(map[1], 1u);
  }
}

TEST(DecimateQem, CancelledCleanly) {
  const Shape s = sphere_shape(5.0, 40);
  const HostMesh h = extract(s);
  TestArena ta(size_t{128} << 20);
  Mesh in = to_arena(ta.arena, h);
  const size_t used = ta.arena.used();
  Progress progress;
  uint32_t calls = 0;
  progress.user = &calls;
  progress.report = [](void* user, const char* stage, uint64_t, uint64_t) {
    EXPECT_STREQ(stage, "decimate");
    return ++*static_cast<uint32_t*>(user) < 1;
  };
  DecimateOptions options;
  options.target_triangles = 100;
  Mesh out(&ta.arena);
  Status st = decimate_qem(Context(&ta.arena, nullptr, &progress), in, options, &out);
  EXPECT_EQ(st.code(), StatusCode::kCancelled);
  EXPECT_EQ(calls, 1u);
  EXPECT_EQ(ta.arena.used(), used);
  EXPECT_TRUE(out.triangles.empty());
}

TEST(DecimateQem, SmoothThenDecimateAsReconstructionWill) {
  const Shape s = sphere_shape(4.0, 32);
  const HostMesh h = extract(s);
  TestArena ta(size_t{128} << 20);
  Mesh m = to_arena(ta.arena, h);
  TaubinOptions smooth;
  smooth.max_displacement = 0.5 * s.grid.spacing.x;
  SPLINTCORE_ASSERT_OK(taubin_smooth(Context(&ta.arena), &m, smooth));
  DecimateOptions options;
  options.target_triangles = 2000;
  Mesh out;
  SPLINTCORE_ASSERT_OK(decimate(ta.arena, m, options, &out));
  expect_valid_solid(out, 0);
  EXPECT_LT(worst_distance(s, out), 0.05 * s.a);
}

// The same bytes from every compiler, optimisation level and CPU: pinned hashes (computed once;
// a change here means the output changed and must be explained).
TEST(RemeshGolden, PinnedOutputHashes) {
  const Shape s = torus_shape(4.0, 1.5, 0.25);
  const HostMesh h = extract(s);
  TestArena ta(size_t{128} << 20);
  Mesh m = to_arena(ta.arena, h);
  TaubinOptions smooth;
  smooth.max_displacement = 0.1;
  SPLINTCORE_ASSERT_OK(taubin_smooth(Context(&ta.arena), &m, smooth));
  const std::string smoothed = hash_of(m);
  DecimateOptions options;
  options.target_triangles = h.triangles.size() / 10;
  Mesh out;
  SPLINTCORE_ASSERT_OK(decimate(ta.arena, m, options, &out));
  const std::string decimated = hash_of(out);
  std::printf("# remesh golden: input %zu triangles, smoothed %s, decimated %s\n",
              h.triangles.size(), smoothed.c_str(), decimated.c_str());
  EXPECT_EQ(smoothed, "8accb0a38490b0cd2c606bdd73fc5d0097fdc75ea9336288bd6e53a17bdf311c");
  EXPECT_EQ(decimated, "13a49f414eb03ec2f637e3e95423fbe4101b1887b4aabec565822401c0fa3c01");
}

}  // namespace
}  // namespace splintcore
