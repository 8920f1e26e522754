// Tests of the tiled iso-surface extractor (src/volume/marching_cubes.cpp): analytic fields
// (spheres, tori, boxes, planes and random three-valued fields) written here, checked with
// check_mesh (closed, edge-manifold, oriented, outward, nothing degenerate, genus), against the
// analytic volume and surface, and for bit-identical output over slab sizes and memory caps,
// the arena exhaustion loop, the streaming interface and the errors.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "splintcore/io.h"
#include "splintcore/volume.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

using test::TestArena;

constexpr double kPi = 3.14159265358979323846;

Vec3 uniform(double h) { return Vec3{h, h, h}; }

// A field given by a function of the sample position (in double, rounded to float).
struct Field {
  VolumeGrid grid;
  double (*f)(const Field&, const Vec3&) = nullptr;
  Vec3 center{};
  double a = 0, b = 0;
  std::vector<float> table;  // when non-empty: the samples themselves (x fastest)
  uint32_t calls = 0;
  uint32_t next_layer = 0;  // checks the documented call order
  bool order_ok = true;
};

Status fill_field(void* user, uint32_t z_begin, uint32_t z_end, Span<float> out) {
  Field& field = *static_cast<Field*>(user);
  const VolumeGrid& g = field.grid;
  ++field.calls;
  if (z_begin != field.next_layer || z_end <= z_begin) field.order_ok = false;
  field.next_layer = z_end;
  if (out.size() != uint64_t{g.nx} * g.ny * (z_end - z_begin)) {
    return Status::error(StatusCode::kInternal, "wrong span size");
  }
  size_t i = 0;
  for (uint32_t z = z_begin; z < z_end; ++z) {
    for (uint32_t y = 0; y < g.ny; ++y) {
      for (uint32_t x = 0; x < g.nx; ++x, ++i) {
        if (!field.table.empty()) {
          out[i] = field.table[(size_t{z} * g.ny + y) * g.nx + x];
        } else {
          const Vec3 p = g.origin + Vec3{g.spacing.x * x, g.spacing.y * y, g.spacing.z * z};
          out[i] = static_cast<float>(field.f(field, p));
        }
      }
    }
  }
  return Status::ok();
}

double sphere_sdf(const Field& fd, const Vec3& p) { return length(p - fd.center) - fd.a; }

double torus_sdf(const Field& fd, const Vec3& p) {
  const Vec3 q = p - fd.center;
  const double ring = std::sqrt(q.x * q.x + q.y * q.y) - fd.a;
  return std::sqrt(ring * ring + q.z * q.z) - fd.b;
}

double box_field(const Field& fd, const Vec3& p) {
  const Vec3 q = p - fd.center;
  return std::fmax(std::fabs(q.x), std::fmax(std::fabs(q.y), std::fabs(q.z))) - fd.a;
}

double plane_field(const Field& fd, const Vec3& p) { return p.z - fd.a; }

// A sphere of radius r (mm) in a grid with `cells` cells across the diameter plus a margin,
// the centre off the grid's symmetry so that no two configurations repeat exactly.
Field sphere(double r, uint32_t cells) {
  Field fd;
  fd.f = sphere_sdf;
  fd.a = r;
  fd.grid.spacing = uniform(2 * r / cells);
  const uint32_t n = cells + 4;
  fd.grid.nx = fd.grid.ny = fd.grid.nz = n;
  fd.grid.origin = Vec3{-1.3, 2.1, -0.7};
  const double h = fd.grid.spacing.x;
  fd.center = fd.grid.origin +
              Vec3{h * n * 0.5 + 0.137 * h, h * n * 0.5 - 0.211 * h, h * n * 0.5 + 0.093 * h};
  return fd;
}

Field torus(double big_r, double small_r, double h) {
  Field fd;
  fd.f = torus_sdf;
  fd.a = big_r;
  fd.b = small_r;
  fd.grid.spacing = uniform(h);
  fd.grid.nx = fd.grid.ny = static_cast<uint32_t>(2 * (big_r + small_r) / h) + 5;
  fd.grid.nz = static_cast<uint32_t>(2 * small_r / h) + 5;
  fd.grid.origin = Vec3{0.0, 0.0, 0.0};
  fd.center = Vec3{h * fd.grid.nx * 0.5 + 0.17 * h, h * fd.grid.ny * 0.5 - 0.09 * h,
                   h * fd.grid.nz * 0.5 + 0.05 * h};
  return fd;
}

LayerSource source_of(Field* fd) {
  LayerSource s;
  s.fill = fill_field;
  s.user = fd;
  return s;
}

std::string arrays_hash(const Vec3* vertices, size_t vertex_count, const Triangle* triangles,
                        size_t triangle_count) {
  Sha256 sha;
  sha.update(vertices, vertex_count * sizeof(Vec3));
  sha.update(triangles, triangle_count * sizeof(Triangle));
  uint8_t digest[32];
  sha.finish(digest);
  char hex[65];
  Sha256::to_hex(digest, hex);
  return hex;
}

// Hashes a streamed output: every vertex and triangle callback, in order.
struct HashVisitorState {
  Sha256 sha;
  std::string hex() {
    uint8_t digest[32];
    sha.finish(digest);
    char text[65];
    Sha256::to_hex(digest, text);
    return text;
  }
};
MarchingCubesVisitor hash_visitor(HashVisitorState* state) {
  MarchingCubesVisitor v;
  v.vertex = [](void* user, uint32_t id, const Vec3& p) {
    auto& h = *static_cast<HashVisitorState*>(user);
    h.sha.update(&id, 4);
    h.sha.update(&p, sizeof(Vec3));
    return Status::ok();
  };
  v.triangle = [](void* user, const Triangle& t, const Vec3&, const Vec3&, const Vec3&) {
    static_cast<HashVisitorState*>(user)->sha.update(&t, sizeof(Triangle));
    return Status::ok();
  };
  v.user = state;
  return v;
}

std::string mesh_hash(const Mesh& mesh) {
  return arrays_hash(mesh.vertices.data(), mesh.vertices.size(), mesh.triangles.data(),
                     mesh.triangles.size());
}

Status run_mesh(Arena& arena, Field& fd, uint32_t layers, Mesh* mesh,
                MarchingCubesStats* stats = nullptr, double iso = 0.0) {
  Context ctx(&arena);
  mesh->bind(&arena);
  MarchingCubesOptions options;
  options.iso = iso;
  options.layers_per_tile = layers;
  fd.next_layer = 0;
  return marching_cubes_mesh(ctx, fd.grid, source_of(&fd), options, mesh, stats);
}

MeshReport report_of(const Mesh& mesh) {
  TestArena scratch(size_t{64} << 20);
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
  if (genus >= 0) {
    EXPECT_EQ(r.shells, 1u);
    EXPECT_EQ(r.genus, genus);
  }
  Context ctx(nullptr);
  TestArena scratch(size_t{64} << 20);
  ctx.arena = &scratch.arena;
  double volume = 0;
  SPLINTCORE_EXPECT_OK(check_closed_oriented(ctx, mesh, &volume));
}

// ------------------------------------------------------------------------------------------------

TEST(MarchingCubes, SphereIsClosedManifoldGenusZeroAndAccurate) {
  for (uint32_t cells : {6u, 12u, 24u, 40u}) {
    SCOPED_TRACE(cells);
    const double r = 5.0;
    Field fd = sphere(r, cells);
    TestArena ta(size_t{64} << 20);
    Mesh mesh;
    MarchingCubesStats stats;
    SPLINTCORE_ASSERT_OK(run_mesh(ta.arena, fd, 0, &mesh, &stats));
    EXPECT_TRUE(fd.order_ok);
    EXPECT_EQ(stats.vertices, mesh.vertices.size());
    EXPECT_EQ(stats.triangles, mesh.triangles.size());
    expect_valid_solid(mesh, 0);
    const double h = fd.grid.spacing.x;
    // Every vertex within a small fraction of a voxel of the sphere (linear interpolation of
    // the distance along an edge of length <= sqrt(3) h errs by about h^2 / r).
    double worst = 0;
    for (const Vec3& p : mesh.vertices)
      worst = std::fmax(worst, std::fabs(length(p - fd.center) - r));
    EXPECT_LT(worst, 0.5 * h);
    // (at most L^2 / (8 r) for an edge of length L: 3 h^2 / (8 r) on the body diagonal).
    EXPECT_LT(worst, 0.38 * h * h / r);
    // Volume: the surface is a chordal approximation, inside the sphere by O(h^2 / r).
    const double exact = 4.0 / 3.0 * kPi * r * r * r;
    const double measured = mesh_volume(mesh);
    EXPECT_NEAR(measured, exact, 4 * kPi * r * r * (0.25 * h * h / r));
  }
}

TEST(MarchingCubes, AnisotropicSpacingIsAccurate) {
  // CT-like voxels: 0.3 x 0.35 mm in plane, 0.6 mm between slices.
  const double r = 5.0;
  Field fd = sphere(r, 24);
  fd.grid.spacing = Vec3{0.3, 0.35, 0.6};
  fd.grid.nx = 40;
  fd.grid.ny = 34;
  fd.grid.nz = 20;
  fd.center = fd.grid.origin + Vec3{0.3 * 20.1, 0.35 * 16.9, 0.6 * 10.2};
  TestArena ta(size_t{64} << 20);
  Mesh mesh;
  SPLINTCORE_ASSERT_OK(run_mesh(ta.arena, fd, 0, &mesh));
  expect_valid_solid(mesh, 0);
  double worst = 0;
  for (const Vec3& p : mesh.vertices)
    worst = std::fmax(worst, std::fabs(length(p - fd.center) - r));
  // Chordal error of the longest edge (the body diagonal, about 0.757 mm): L^2 / (8 r).
  const double l2 = 0.3 * 0.3 + 0.35 * 0.35 + 0.6 * 0.6;
  EXPECT_LT(worst, l2 / (8 * r) + 1e-6);
  EXPECT_GT(worst, 0.0);
  const double exact = 4.0 / 3.0 * kPi * r * r * r;
  EXPECT_NEAR(mesh_volume(mesh), exact, 4 * kPi * r * r * (l2 / (8 * r)));
}

TEST(MarchingCubes, TorusIsGenusOne) {
  for (double h : {0.5, 0.3, 0.2}) {
    SCOPED_TRACE(h);
    Field fd = torus(4.0, 1.5, h);
    TestArena ta(size_t{64} << 20);
    Mesh mesh;
    SPLINTCORE_ASSERT_OK(run_mesh(ta.arena, fd, 3, &mesh));
    expect_valid_solid(mesh, 1);
    double worst = 0;
    for (const Vec3& p : mesh.vertices) worst = std::fmax(worst, std::fabs(torus_sdf(fd, p)));
    EXPECT_LT(worst, 0.5 * h);
    const double exact = 2 * kPi * kPi * 4.0 * 1.5 * 1.5;
    const double area = 4 * kPi * kPi * 4.0 * 1.5;
    EXPECT_NEAR(mesh_volume(mesh), exact, area * (0.25 * h * h / 1.5));
  }
}

struct Collected {
  std::vector<Vec3> vertices;
  std::vector<Triangle> triangles;
  std::vector<Vec3> corners;
  bool ids_in_order = true;
  StlWriter* writer = nullptr;
};

Status collect_vertex(void* user, uint32_t id, const Vec3& p) {
  Collected& c = *static_cast<Collected*>(user);
  if (id != c.vertices.size()) c.ids_in_order = false;
  c.vertices.push_back(p);
  return Status::ok();
}

Status collect_triangle(void* user, const Triangle& t, const Vec3& a, const Vec3& b,
                        const Vec3& c3) {
  Collected& c = *static_cast<Collected*>(user);
  for (uint32_t v : t.v) {
    if (v >= c.vertices.size()) c.ids_in_order = false;
  }
  c.triangles.push_back(t);
  c.corners.push_back(a);
  c.corners.push_back(b);
  c.corners.push_back(c3);
  if (c.writer != nullptr) return c.writer->add(a, b, c3);
  return Status::ok();
}

// A visitor that collects into *c.
MarchingCubesVisitor collecting(Collected* c) {
  MarchingCubesVisitor visitor;
  visitor.vertex = collect_vertex;
  visitor.triangle = collect_triangle;
  visitor.user = c;
  return visitor;
}

TEST(MarchingCubes, IdenticalOutputForEveryTileSizeAndCap) {
  std::vector<Field> fields = {sphere(5.0, 17), torus(3.0, 1.0, 0.37)};
  for (Field& fd : fields) {
    std::string reference;
    size_t reference_triangles = 0, reference_vertices = 0;
    std::vector<uint32_t> layer_counts = {1, 2, 3, 7, fd.grid.nz, fd.grid.nz + 5};
    for (uint32_t layers : layer_counts) {
      SCOPED_TRACE(layers);
      TestArena ta(size_t{32} << 20);
      Mesh mesh;
      MarchingCubesStats stats;
      fd.calls = 0;
      SPLINTCORE_ASSERT_OK(run_mesh(ta.arena, fd, layers, &mesh, &stats));
      EXPECT_TRUE(fd.order_ok);
      const uint32_t used_layers = layers < fd.grid.nz ? layers : fd.grid.nz;
      EXPECT_EQ(stats.layers_per_tile, used_layers);
      EXPECT_EQ(fd.calls, (fd.grid.nz + used_layers - 1) / used_layers);
      const std::string h = mesh_hash(mesh);
      if (reference.empty()) {
        reference = h;
        reference_triangles = mesh.triangles.size();
        reference_vertices = mesh.vertices.size();
        EXPECT_GT(reference_triangles, 100u);
      }
      EXPECT_EQ(h, reference);
    }
    // Automatic slab sizes under several caps (each picks a different slab). The automatic
    // choice gives the working set at most a quarter of the free arena, so 4/3 of the output's
    // need plus a few minimum working sets always suffices.
    MarchingCubesMemory memory;
    SPLINTCORE_ASSERT_OK(marching_cubes_memory(fd.grid, &memory));
    const uint64_t mesh_bytes =
        marching_cubes_mesh_extra_bound(reference_vertices, reference_triangles);
    for (uint64_t minimums : {1u, 2u, 4u, 8u, 64u}) {
      TestArena ta(static_cast<size_t>(mesh_bytes * 4 / 3 + memory.minimum * minimums));
      Mesh mesh;
      MarchingCubesStats stats;
      SPLINTCORE_ASSERT_OK(run_mesh(ta.arena, fd, 0, &mesh, &stats));
      EXPECT_EQ(mesh_hash(mesh), reference);
      EXPECT_LE(ta.arena.high_water(), stats.working_set_bytes + mesh_bytes);
      EXPECT_EQ(ta.arena.used(),
                mesh.vertices.size() * sizeof(Vec3) + mesh.triangles.size() * sizeof(Triangle));
    }
    // Streaming under a cap of exactly the working set of k layers picks k layers.
    for (uint32_t k : {1u, 2u, 3u, 5u, 16u}) {
      SCOPED_TRACE(k);
      if (k > fd.grid.nz) continue;
      const uint64_t cap = marching_cubes_bound(fd.grid, k);
      TestArena ta(static_cast<size_t>(cap));
      Context ctx(&ta.arena);
      Collected c;
      const MarchingCubesVisitor visitor = collecting(&c);
      MarchingCubesStats stats;
      fd.next_layer = 0;
      SPLINTCORE_ASSERT_OK(
          marching_cubes(ctx, fd.grid, source_of(&fd), MarchingCubesOptions{}, visitor, &stats));
      EXPECT_EQ(stats.layers_per_tile, k);
      EXPECT_EQ(stats.working_set_bytes + 16, cap);
      EXPECT_EQ(ta.arena.used(), 0u);
      EXPECT_EQ(
          arrays_hash(c.vertices.data(), c.vertices.size(), c.triangles.data(), c.triangles.size()),
          reference);
    }
  }
}

TEST(MarchingCubes, CapBelowMinimumIsACleanError) {
  Field fd = sphere(5.0, 12);
  MarchingCubesMemory memory;
  SPLINTCORE_ASSERT_OK(marching_cubes_memory(fd.grid, &memory));
  const uint64_t n = fd.grid.nx;
  const uint64_t bit_words = (n + 2 + 63) / 64;
  // The fixed part: samples and inside bits of two layers, rank prefixes of ten edge kinds.
  EXPECT_EQ(memory.minimum, 16 + ((8 * n * n + 15) / 16) * 16 +
                                ((8 * bit_words * n * 2 + 15) / 16) * 16 +
                                80 * bit_words * (n + 1));
  // With the full id pool (ten ids per grid point).
  EXPECT_EQ(memory.comfortable - memory.minimum,
            (4 * n * n * 17 + 15) / 16 * 16 - (8 * n * n + 15) / 16 * 16 +
                (8 * bit_words * n * 17 + 15) / 16 * 16 - (8 * bit_words * n * 2 + 15) / 16 * 16 +
                (40 * (n + 1) * (n + 1) + 15) / 16 * 16);
  EXPECT_EQ(memory.comfortable_layers, 16u);
  EXPECT_GT(memory.comfortable, memory.minimum);

  // Some bytes in use before the call: the error names the total cap needed.
  TestArena ta(static_cast<size_t>(memory.minimum + 99));
  ASSERT_NE(ta.arena.allocate(100), nullptr);
  const size_t used = ta.arena.used();
  Mesh mesh;
  Status st = run_mesh(ta.arena, fd, 0, &mesh);
  ASSERT_EQ(st.code(), StatusCode::kArenaExhausted);
  const std::string message = st.message();
  EXPECT_NE(message.find(std::to_string(memory.minimum)), std::string::npos) << message;
  EXPECT_NE(message.find(std::to_string(used + memory.minimum)), std::string::npos) << message;
  EXPECT_EQ(ta.arena.used(), used);
  EXPECT_TRUE(mesh.vertices.empty());
  EXPECT_TRUE(mesh.triangles.empty());
  EXPECT_EQ(fd.calls, 0u);

  // Streaming at the minimum has no room for vertex ids: the first layer the surface crosses
  // stops it with the bytes it needs; a cap raised by what each error asks for gets through
  // (whatever the starting alignment), with the same output as with plenty of room.
  std::string reference;
  {
    TestArena big(size_t{64} << 20);
    Context ctx(&big.arena);
    HashVisitorState hv;
    SPLINTCORE_ASSERT_OK(
        marching_cubes(ctx, fd.grid, source_of(&fd), MarchingCubesOptions{}, hash_visitor(&hv)));
    reference = hv.hex();
  }
  for (size_t offset : {size_t{0}, size_t{1}, size_t{8}, size_t{15}}) {
    SCOPED_TRACE(offset);
    uint64_t cap = memory.minimum + offset;
    int rounds = 0;
    for (;; ++rounds) {
      ASSERT_LT(rounds, 64);
      TestArena exact(static_cast<size_t>(cap));
      if (offset > 0) {
        ASSERT_NE(exact.arena.allocate(offset, 1), nullptr);
      }
      Context ctx(&exact.arena);
      HashVisitorState hv;
      MarchingCubesStats stats;
      const Status run = marching_cubes(ctx, fd.grid, source_of(&fd), MarchingCubesOptions{},
                                        hash_visitor(&hv), &stats);
      EXPECT_EQ(exact.arena.used(), offset);
      if (run.is_ok()) {
        EXPECT_EQ(hv.hex(), reference);
        EXPECT_GT(stats.triangles, 0u);
        break;
      }
      ASSERT_EQ(run.code(), StatusCode::kArenaExhausted) << test::format(run);
      const std::string text = run.message();
      const size_t at = text.find("at least ");
      ASSERT_NE(at, std::string::npos) << text;
      const uint64_t more = std::stoull(text.substr(at + 9));
      ASSERT_GT(more, 0u);
      cap += more;
    }
    EXPECT_GT(rounds, 0);
    EXPECT_LT(cap, memory.comfortable + offset);
  }
  // One byte less fails before touching the source.
  TestArena short_arena(static_cast<size_t>(memory.minimum - 1));
  Context ctx(&short_arena.arena);
  fd.calls = 0;
  Status st2 =
      marching_cubes(ctx, fd.grid, source_of(&fd), MarchingCubesOptions{}, MarchingCubesVisitor{});
  EXPECT_EQ(st2.code(), StatusCode::kArenaExhausted);
  EXPECT_EQ(fd.calls, 0u);
  EXPECT_EQ(short_arena.arena.used(), 0u);
}

TEST(MarchingCubes, ExhaustionSweepSucceedsIdenticallyOrFailsCleanly) {
  Field fd = sphere(4.0, 9);
  std::string reference;
  size_t reference_bytes = 0;
  {
    TestArena ta(size_t{16} << 20);
    Mesh mesh;
    SPLINTCORE_ASSERT_OK(run_mesh(ta.arena, fd, 0, &mesh));
    reference = mesh_hash(mesh);
    reference_bytes = ta.arena.high_water();
  }
  int successes = 0, failures = 0;
  for (size_t cap = 0; cap <= reference_bytes + 4096; cap += 397) {
    for (uint32_t layers : {0u, 2u}) {
      TestArena ta(cap);
      Mesh mesh;
      Status st = run_mesh(ta.arena, fd, layers, &mesh);
      if (st.is_ok()) {
        ++successes;
        EXPECT_EQ(mesh_hash(mesh), reference) << "cap " << cap;
      } else {
        ++failures;
        EXPECT_EQ(st.code(), StatusCode::kArenaExhausted) << test::format(st);
        EXPECT_NE(std::string(st.message()).find("increase the memory cap"), std::string::npos);
        EXPECT_EQ(ta.arena.used(), 0u);
        EXPECT_TRUE(mesh.vertices.empty() && mesh.triangles.empty());
      }
    }
  }
  EXPECT_GT(successes, 0);
  EXPECT_GT(failures, 0);
}

TEST(MarchingCubes, FieldTouchingTheBorderIsClosed) {
  // A sphere larger than the grid: cut by all six faces, closed just outside them.
  Field fd = sphere(5.0, 16);
  fd.a = 6.5;
  TestArena ta(size_t{64} << 20);
  Mesh mesh;
  SPLINTCORE_ASSERT_OK(run_mesh(ta.arena, fd, 4, &mesh));
  expect_valid_solid(mesh, 0);
  const double h = fd.grid.spacing.x;
  const VolumeGrid& g = fd.grid;
  for (const Vec3& p : mesh.vertices) {
    for (int a = 0; a < 3; ++a) {
      const double n = a == 0 ? g.nx : (a == 1 ? g.ny : g.nz);
      EXPECT_GE(p[a], g.origin[a] - kEdgeMargin * h * 1.0001);
      EXPECT_LE(p[a], g.origin[a] + (n - 1 + kEdgeMargin * 1.0001) * h);
    }
  }
  // Everything inside: the closed box around the grid.
  Field all = fd;
  all.table.assign(size_t{g.nx} * g.ny * g.nz, -1.0f);
  TestArena tb(size_t{64} << 20);
  Mesh box;
  SPLINTCORE_ASSERT_OK(run_mesh(tb.arena, all, 0, &box));
  expect_valid_solid(box, 0);
  const double side_x = (g.nx - 1 + 2 * kEdgeMargin) * h, side_y = (g.ny - 1 + 2 * kEdgeMargin) * h;
  const double side_z = (g.nz - 1 + 2 * kEdgeMargin) * h;
  // (The box edges are chamfered by about (kEdgeMargin h)^2 where the tetrahedra cut them.)
  EXPECT_NEAR(mesh_volume(box), side_x * side_y * side_z, 1e-6 * side_x * side_y * side_z);
  // A single inside sample in a 1 x 1 x 1 grid.
  Field one;
  one.grid.spacing = uniform(1.0);
  one.grid.nx = one.grid.ny = one.grid.nz = 1;
  one.table.assign(1, -1.0f);
  TestArena tc(size_t{1} << 20);
  Mesh tiny;
  SPLINTCORE_ASSERT_OK(run_mesh(tc.arena, one, 0, &tiny));
  expect_valid_solid(tiny, 0);
}

TEST(MarchingCubes, SamplesExactlyAtIsoGiveNoDegenerateTriangles) {
  // Integer-valued box field on an integer grid: whole planes of samples equal the iso value.
  Field box;
  box.f = box_field;
  box.grid.spacing = uniform(1.0);
  box.grid.nx = box.grid.ny = box.grid.nz = 12;
  box.center = Vec3{5, 6, 5};
  box.a = 3;
  for (double iso : {0.0, 1.0, -1.0, 0.5}) {
    SCOPED_TRACE(iso);
    TestArena ta(size_t{16} << 20);
    Mesh mesh;
    SPLINTCORE_ASSERT_OK(run_mesh(ta.arena, box, 0, &mesh, nullptr, iso));
    expect_valid_solid(mesh, 0);
  }
  // A plane through a layer of samples, closed by the border.
  Field plane;
  plane.f = plane_field;
  plane.grid.spacing = uniform(0.5);
  plane.grid.nx = 7;
  plane.grid.ny = 5;
  plane.grid.nz = 9;
  plane.a = 2.0;  // z = 2 is sample layer 4
  TestArena tp(size_t{16} << 20);
  Mesh slab;
  SPLINTCORE_ASSERT_OK(run_mesh(tp.arena, plane, 0, &slab));
  expect_valid_solid(slab, 0);
  // Random three-valued fields {-1, 0, +1} with iso 0: every kind of tie and saddle.
  std::mt19937_64 rng(20240611);
  for (int round = 0; round < 40; ++round) {
    Field rnd;
    rnd.grid.spacing = uniform(0.25);
    rnd.grid.origin = Vec3{1.0, -2.0, 3.0};
    rnd.grid.nx = 3 + static_cast<uint32_t>(rng() % 6);
    rnd.grid.ny = 3 + static_cast<uint32_t>(rng() % 6);
    rnd.grid.nz = 3 + static_cast<uint32_t>(rng() % 6);
    rnd.table.resize(size_t{rnd.grid.nx} * rnd.grid.ny * rnd.grid.nz);
    for (float& v : rnd.table) v = static_cast<float>(static_cast<int>(rng() % 3) - 1);
    TestArena ta(size_t{16} << 20);
    Mesh mesh;
    SPLINTCORE_ASSERT_OK(run_mesh(ta.arena, rnd, 1 + static_cast<uint32_t>(round % 3), &mesh));
    if (mesh.triangles.empty()) continue;
    expect_valid_solid(mesh, -1);
    Context ctx(&ta.arena);
    SelfIntersectionReport si;
    SPLINTCORE_ASSERT_OK(find_self_intersections(ctx, mesh, 1, &si));
    EXPECT_FALSE(si.self_intersecting()) << "round " << round;
  }
}

TEST(MarchingCubes, StreamingYieldsExactlyTheMeshTriangles) {
  Field fd = torus(3.0, 1.2, 0.3);
  TestArena ta(size_t{64} << 20);
  Mesh mesh;
  SPLINTCORE_ASSERT_OK(run_mesh(ta.arena, fd, 5, &mesh));
  std::vector<uint8_t> expected_stl;
  SPLINTCORE_ASSERT_OK(test::mesh_to_bytes(ta.arena, mesh, StlFormat::kBinary, &expected_stl));

  for (uint32_t layers : {1u, 4u, 0u}) {
    TestArena tb(size_t{8} << 20);
    Context ctx(&tb.arena);
    std::vector<uint8_t> bytes(expected_stl.size() + 4096);
    MemorySink ms{bytes.data(), bytes.size(), 0, 0};
    StlWriter writer;
    SPLINTCORE_ASSERT_OK(writer.begin(ctx, memory_sink(&ms), StlWriteOptions{}, kUnknownSize));
    Collected c;
    c.writer = &writer;
    const MarchingCubesVisitor visitor = collecting(&c);
    MarchingCubesOptions options;
    options.layers_per_tile = layers;
    fd.next_layer = 0;
    MarchingCubesStats stats;
    SPLINTCORE_ASSERT_OK(marching_cubes(ctx, fd.grid, source_of(&fd), options, visitor, &stats));
    SPLINTCORE_ASSERT_OK(writer.finish());
    bytes.resize(static_cast<size_t>(ms.size));
    EXPECT_TRUE(c.ids_in_order);
    ASSERT_EQ(c.vertices.size(), mesh.vertices.size());
    ASSERT_EQ(c.triangles.size(), mesh.triangles.size());
    EXPECT_EQ(stats.triangles, mesh.triangles.size());
    EXPECT_EQ(
        0, std::memcmp(c.vertices.data(), mesh.vertices.data(), c.vertices.size() * sizeof(Vec3)));
    EXPECT_EQ(0, std::memcmp(c.triangles.data(), mesh.triangles.data(),
                             c.triangles.size() * sizeof(Triangle)));
    for (size_t t = 0; t < c.triangles.size(); ++t) {
      for (int k = 0; k < 3; ++k) {
        ASSERT_EQ(0, std::memcmp(&c.corners[3 * t + static_cast<size_t>(k)],
                                 &mesh.vertices[mesh.triangles[t].v[k]], sizeof(Vec3)));
      }
    }
    EXPECT_EQ(bytes, expected_stl);
  }
}

// MarchingCubesOptions::pool_ids: a pool that holds what the layers need gives the same
// output in less memory; one that does not stops cleanly with pool_short set.
TEST(MarchingCubes, SmallerIdPoolSameOutputOrPoolShort) {
  Field fd = torus(3.0, 1.2, 0.3);
  auto stream = [&](uint64_t pool_ids, std::string* hash, size_t* high_water,
                    MarchingCubesStats* stats) {
    TestArena ta(size_t{64} << 20);
    Context ctx(&ta.arena);
    Collected c;
    const MarchingCubesVisitor visitor = collecting(&c);
    MarchingCubesOptions options;
    options.layers_per_tile = 4;
    options.pool_ids = pool_ids;
    fd.next_layer = 0;
    const Status st = marching_cubes(ctx, fd.grid, source_of(&fd), options, visitor, stats);
    *hash =
        arrays_hash(c.vertices.data(), c.vertices.size(), c.triangles.data(), c.triangles.size());
    *high_water = ta.arena.high_water();
    EXPECT_EQ(ta.arena.used(), 0u);
    return st;
  };
  std::string full_hash, small_hash, short_hash;
  size_t full_water = 0, small_water = 0, short_water = 0;
  MarchingCubesStats full_stats, small_stats, short_stats;
  SPLINTCORE_ASSERT_OK(stream(0, &full_hash, &full_water, &full_stats));
  EXPECT_FALSE(full_stats.pool_short);
  EXPECT_GT(full_stats.triangles, 100u);
  const uint64_t full_ids = (uint64_t{fd.grid.nx} + 1) * (fd.grid.ny + 1) * 10;
  SPLINTCORE_ASSERT_OK(stream(full_ids / 4, &small_hash, &small_water, &small_stats));
  EXPECT_FALSE(small_stats.pool_short);
  EXPECT_EQ(small_hash, full_hash);
  EXPECT_EQ(small_stats.triangles, full_stats.triangles);
  EXPECT_LE(small_water + 3 * full_ids, full_water);
  const Status st = stream(8, &short_hash, &short_water, &short_stats);
  EXPECT_EQ(st.code(), StatusCode::kArenaExhausted) << test::format(st);
  EXPECT_TRUE(short_stats.pool_short);
}

TEST(MarchingCubes, IsoBetweenTwoFloatsClassifiesExactly) {
  // Samples are float, iso is double: "inside" is (double)sample < iso, exactly, also when iso
  // lies strictly between two floats (the extractor compares against the least float not
  // below iso).
  const float above = 0.1f;  // 0.100000001490116... > 0.1
  const float below = std::nextafter(above, 0.0f);
  Field fd;
  fd.grid.spacing = uniform(1.0);
  fd.grid.nx = 3;
  fd.grid.ny = fd.grid.nz = 1;
  fd.table = {below, above, below};
  auto inside_count = [&](double iso, uint64_t* triangles) {
    TestArena ta(size_t{1} << 20);
    Mesh mesh;
    MarchingCubesStats stats;
    Status st = run_mesh(ta.arena, fd, 0, &mesh, &stats, iso);
    *triangles = stats.triangles;
    return st;
  };
  uint64_t t_mid = 0, t_all = 0, t_none = 0, t_huge = 0;
  SPLINTCORE_ASSERT_OK(inside_count(0.1, &t_mid));         // two separate inside samples
  SPLINTCORE_ASSERT_OK(inside_count(0.10000001, &t_all));  // all three: one blob
  SPLINTCORE_ASSERT_OK(inside_count(-1e39, &t_none));      // below every float: nothing
  SPLINTCORE_ASSERT_OK(inside_count(1e39, &t_huge));       // above every float: all inside
  EXPECT_GT(t_mid, 0u);
  EXPECT_GT(t_all, 0u);
  EXPECT_NE(t_mid, t_all);
  EXPECT_EQ(t_none, 0u);
  EXPECT_EQ(t_huge, t_all);
  // Just above `below` (nearer to it than to `above`): rounding iso to the nearest float would
  // make `below` outside too and give nothing.
  uint64_t t_near = 0;
  SPLINTCORE_ASSERT_OK(inside_count(static_cast<double>(below) + 1e-12, &t_near));
  EXPECT_EQ(t_near, t_mid);
}

TEST(MarchingCubes, GoldenHashIsTheSameEverywhere) {
  // Pinned: the same bytes from g++ and clang++, -O0 and -O2 (only + - * / and sqrt reach them).
  Field fd = sphere(5.0, 12);
  TestArena ta(size_t{16} << 20);
  Mesh mesh;
  SPLINTCORE_ASSERT_OK(run_mesh(ta.arena, fd, 0, &mesh));
  EXPECT_EQ(mesh_hash(mesh), "9859a21a011f2517a756fd020dfc87bcdf5cdebd02b6c7d089011495a1a5e7fa");
}

void* hooks_allocate(void*, size_t bytes) { return std::malloc(bytes); }
void hooks_release(void*, void* pointer, size_t) { std::free(pointer); }

TEST(MarchingCubes, BlockArenaGivesTheSameMesh) {
  // An arena of small blocks: the log outgrows blocks and is moved; the mesh is then assembled
  // from cached blocks. Same bytes as in one buffer.
  Field fd = torus(3.0, 1.2, 0.3);
  TestArena ta(size_t{64} << 20);
  Mesh reference;
  SPLINTCORE_ASSERT_OK(run_mesh(ta.arena, fd, 2, &reference));
  for (size_t block : {size_t{4096}, size_t{65536}, size_t{1} << 20}) {
    SCOPED_TRACE(block);
    AllocatorHooks hooks;
    hooks.allocate = hooks_allocate;
    hooks.release = hooks_release;
    Arena arena(hooks, size_t{64} << 20, block);
    ASSERT_NE(arena.allocate(1000), nullptr);
    const size_t used = arena.used();
    for (uint32_t layers : {1u, 3u, 0u}) {
      Mesh mesh;
      SPLINTCORE_ASSERT_OK(run_mesh(arena, fd, layers, &mesh));
      EXPECT_EQ(mesh_hash(mesh), mesh_hash(reference));
      const size_t mesh_size =
          mesh.vertices.size() * sizeof(Vec3) + mesh.triangles.size() * sizeof(Triangle);
      EXPECT_GE(arena.used() - used, mesh_size);
      if (block >= (size_t{1} << 20)) {
        EXPECT_LE(arena.used() - used, mesh_size + 32);
      }
      // A second mesh above the first, then both dropped.
      Arena::Marker m = arena.mark();
      Mesh again;
      SPLINTCORE_ASSERT_OK(run_mesh(arena, fd, layers, &again));
      EXPECT_EQ(mesh_hash(again), mesh_hash(reference));
      EXPECT_EQ(mesh_hash(mesh), mesh_hash(reference));
      arena.rewind(m);
      arena.reset();
      ASSERT_NE(arena.allocate(1000), nullptr);
    }
  }
}

bool cancel_after_two(void* user, const char*, uint64_t, uint64_t) {
  int& calls = *static_cast<int*>(user);
  return ++calls <= 2;
}

Status failing_fill(void*, uint32_t, uint32_t, Span<float>) {
  return Status::error(StatusCode::kIoError, "scanner unplugged");
}

TEST(MarchingCubes, ErrorsAreCleanAndLeaveNoOutput) {
  Field fd = sphere(3.0, 10);
  // A NaN sample.
  {
    Field bad = fd;
    bad.table.resize(size_t{bad.grid.nx} * bad.grid.ny * bad.grid.nz, 1.0f);
    const size_t at = (size_t{7} * bad.grid.ny + 3) * bad.grid.nx + 2;
    bad.table[at] = std::nanf("");
    TestArena ta(size_t{8} << 20);
    Mesh mesh;
    Status st = run_mesh(ta.arena, bad, 2, &mesh);
    EXPECT_EQ(st.code(), StatusCode::kNonFinite);
    EXPECT_EQ(st.index(), at);
    EXPECT_NE(std::string(st.message()).find("(2, 3, 7)"), std::string::npos) << st.message();
    EXPECT_EQ(ta.arena.used(), 0u);
  }
  // The source's error is returned as is.
  {
    TestArena ta(size_t{8} << 20);
    Context ctx(&ta.arena);
    Mesh mesh(&ta.arena);
    LayerSource src;
    src.fill = failing_fill;
    Status st = marching_cubes_mesh(ctx, fd.grid, src, MarchingCubesOptions{}, &mesh);
    EXPECT_EQ(st.code(), StatusCode::kIoError);
    EXPECT_EQ(ta.arena.used(), 0u);
  }
  // Cancellation during the sweep, after some output.
  {
    TestArena ta(size_t{8} << 20);
    int calls = 0;
    Progress progress{cancel_after_two, &calls};
    Context ctx(&ta.arena, nullptr, &progress);
    Mesh mesh(&ta.arena);
    MarchingCubesOptions options;
    options.layers_per_tile = 4;
    fd.next_layer = 0;
    Status st = marching_cubes_mesh(ctx, fd.grid, source_of(&fd), options, &mesh);
    EXPECT_EQ(st.code(), StatusCode::kCancelled);
    EXPECT_EQ(ta.arena.used(), 0u);
    EXPECT_TRUE(mesh.vertices.empty() && mesh.triangles.empty());
  }
  // Arguments.
  {
    TestArena ta(size_t{8} << 20);
    Context ctx(&ta.arena);
    MarchingCubesVisitor none;
    VolumeGrid empty = fd.grid;
    empty.ny = 0;
    EXPECT_EQ(marching_cubes(ctx, empty, source_of(&fd), MarchingCubesOptions{}, none).code(),
              StatusCode::kInvalidArgument);
    VolumeGrid flat = fd.grid;
    flat.spacing.z = 0;
    EXPECT_EQ(marching_cubes(ctx, flat, source_of(&fd), MarchingCubesOptions{}, none).code(),
              StatusCode::kInvalidArgument);
    flat.spacing.z = -fd.grid.spacing.x;
    EXPECT_EQ(marching_cubes(ctx, flat, source_of(&fd), MarchingCubesOptions{}, none).code(),
              StatusCode::kInvalidArgument);
    MarchingCubesOptions nan_iso;
    nan_iso.iso = std::nan("");
    EXPECT_EQ(marching_cubes(ctx, fd.grid, source_of(&fd), nan_iso, none).code(),
              StatusCode::kInvalidArgument);
    EXPECT_EQ(marching_cubes(ctx, fd.grid, LayerSource{}, MarchingCubesOptions{}, none).code(),
              StatusCode::kInvalidArgument);
    MarchingCubesMemory memory;
    EXPECT_EQ(marching_cubes_memory(empty, &memory).code(), StatusCode::kInvalidArgument);
    VolumeGrid huge = fd.grid;
    huge.nx = huge.ny = UINT32_MAX;
    EXPECT_EQ(marching_cubes_memory(huge, &memory).code(), StatusCode::kLimitExceeded);
    // A non-empty output mesh.
    Mesh mesh(&ta.arena);
    ASSERT_TRUE(mesh.vertices.push_back(Vec3{}));
    EXPECT_EQ(
        marching_cubes_mesh(ctx, fd.grid, source_of(&fd), MarchingCubesOptions{}, &mesh).code(),
        StatusCode::kInvalidArgument);
  }
}

bool count_progress(void* user, const char* stage, uint64_t done, uint64_t total) {
  auto& seen = *static_cast<std::vector<uint64_t>*>(user);
  EXPECT_STREQ(stage, "marching cubes");
  EXPECT_LE(done, total);
  seen.push_back(done);
  return true;
}

TEST(VolumeProgress, ReportedOncePerSlabInOrder) {
  Field fd = sphere(3.0, 10);  // 14 layers
  TestArena ta(size_t{8} << 20);
  std::vector<uint64_t> seen;
  Progress progress{count_progress, &seen};
  Context ctx(&ta.arena, nullptr, &progress);
  MarchingCubesOptions options;
  options.layers_per_tile = 4;
  SPLINTCORE_ASSERT_OK(
      marching_cubes(ctx, fd.grid, source_of(&fd), options, MarchingCubesVisitor{}));
  EXPECT_EQ(seen, (std::vector<uint64_t>{0, 4, 8, 12, 14}));
}

}  // namespace
}  // namespace splintcore
