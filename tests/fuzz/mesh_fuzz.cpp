// libFuzzer target: bytes -> a small binary STL (the input is the triangle records, 36 bytes
// of float32 coordinates each, at most 64 triangles; coordinates are also taken from a small
// lattice when the mode byte asks, so that shared vertices, coplanar faces and exact touches
// are common; or, with mode bit 7, a terrain: a closed solid whose floor is a grid of bytes'
// heights and sideways shifts, which fold it as seen from below) -> weld_exact -> check_mesh ->
// find_self_intersections; then, when the mesh is a valid solid, mesh_boolean against a fixed cube,
// and the mesh as a jaw: its exact sweep (sweep_exact_mesh) over the cube and the cube's exact
// blockout (blockout with `exact`), along a direction the mode byte picks. Any crash or sanitizer
// report is a bug, and so is:
// - a Boolean or blockout that succeeds with a result that is not a closed, oriented,
//   non-self-intersecting mesh, or fails with kInternal (the Boolean with a mesh that crosses
//   itself: only where it names such an operand, as A, or as B in the union);
// - a sweep whose triangle count is not its stats' (kept + taken in + 2 per wall), or whose
//   open border has an end inside the region (it may be open only beyond it: at the walls'
//   tops and beside front triangles left out, whose corners lie beyond one side).
//   build/fuzz/tests/splintcore_fuzz_mesh -max_total_time=60 fixtures/fuzz/mesh
#include <algorithm>
#include <cstdlib>
#include <cstring>

#include "splintcore/blockout.h"
#include "splintcore/boolean.h"
#include "splintcore/io.h"
#include "splintcore/mesh.h"

namespace {

using namespace splintcore;

constexpr size_t kMaxTriangles = 64;

void put_u32(uint8_t* p, uint32_t v) {
  for (int i = 0; i < 4; ++i) p[i] = static_cast<uint8_t>(v >> (8 * i));
}

// The cube [-1, 1]^3 as 12 outward triangles.
void cube(Arena& arena, Mesh* out) {
  static const float c[8][3] = {{-1, -1, -1}, {1, -1, -1}, {-1, 1, -1}, {1, 1, -1},
                                {-1, -1, 1},  {1, -1, 1},  {-1, 1, 1},  {1, 1, 1}};
  static const uint32_t f[12][3] = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6},
                                    {0, 1, 4}, {1, 5, 4}, {2, 6, 3}, {3, 6, 7},
                                    {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  out->bind(&arena);
  for (const auto& p : c) (void)out->vertices.push_back(Vec3{p[0], p[1], p[2]});
  for (const auto& t : f) (void)out->triangles.push_back(Triangle{{t[0], t[1], t[2]}});
}

// A result that must be a valid solid: closed, edge-manifold, oriented, not crossing itself
// (empty is a valid answer: nothing left).
void require_solid(const Context& ctx, const Mesh& result) {
  if (result.triangles.empty()) return;
  MeshReport rr;
  if (!check_mesh(ctx, result, &rr).is_ok()) return;
  if (!rr.closed() || !rr.edge_manifold() || !rr.oriented()) std::abort();
  SelfIntersectionReport rsi;
  if (find_self_intersections(ctx, result, 1, &rsi).is_ok() && rsi.self_intersecting()) {
    std::abort();
  }
}

// A failure is an answer, unless it says the library contradicted itself (kInternal: a result
// that fails its own check), which only inputs that are solids may hold it to (`solid_in`: the
// mesh does not cross itself; the Boolean names A crossing itself, and B in the union, but
// not B elsewhere, which may cross itself away from A).
bool succeeded(const Status& s, bool solid_in = true) {
  if (s.code() == StatusCode::kInternal && solid_in) std::abort();
  return s.is_ok();
}

// The mesh and the cube: the operation and the order from mode bits 1-2 and 4, float32
// output unless bit 3. `crossing`: the mesh crosses itself.
void boolean_stage(const Context& ctx, const Mesh& mesh, const Mesh& box, uint8_t mode,
                   bool crossing) {
  BooleanOptions bo;
  bo.op = static_cast<BooleanOp>((mode >> 1) % 3);
  bo.float32_output = (mode & 8) == 0;
  Mesh result;
  BooleanStats stats;
  const bool swap = (mode & 16) != 0;
  const bool named = !swap || bo.op == BooleanOp::kUnion;  // a crossing mesh is named there
  if (succeeded(mesh_boolean(ctx, swap ? box : mesh, swap ? mesh : box, bo, &result, &stats),
                !crossing || named)) {
    require_solid(ctx, result);
  }
}

// The mesh as a jaw leaving the cube along one of four directions (mode bits 5-6).
void sweep_stage(const Context& ctx, const Mesh& mesh, const Mesh& box, uint8_t mode) {
  static const Vec3 kDirections[4] = {{0, 0, 1}, {0, 0, -1}, {0.25, -0.5, 1}, {1, 0, 0}};
  const Vec3 d = kDirections[(mode >> 5) & 3];
  Aabb region;
  region.add(Vec3{-1, -1, -1});
  region.add(Vec3{1, 1, 1});
  Arena& arena = *ctx.arena;
  const Arena::Marker start = arena.mark();
  Mesh swept;
  ExactSweepStats st;
  if (succeeded(sweep_exact_mesh(ctx, mesh, d, region, &swept, &st))) {
    if (swept.triangles.size() != st.kept_triangles + st.absorbed_triangles + 2 * st.walls) {
      std::abort();
    }
    // Each edge once per use, as (smaller id, larger id); an edge used once is on the border.
    const size_t n = 3 * swept.triangles.size();
    uint64_t* edges = arena.allocate_array<uint64_t>(n);
    if (edges == nullptr) return;
    for (size_t t = 0; t < swept.triangles.size(); ++t) {
      for (int k = 0; k < 3; ++k) {
        const uint64_t a = swept.triangles[t].v[k], b = swept.triangles[t].v[(k + 1) % 3];
        edges[3 * t + k] = a < b ? (a << 32 | b) : (b << 32 | a);
      }
    }
    std::sort(edges, edges + n);
    for (size_t i = 0; i < n;) {
      size_t j = i;
      while (j < n && edges[j] == edges[i]) ++j;
      if (j - i == 1 && (region.contains(swept.vertices[edges[i] >> 32]) ||
                         region.contains(swept.vertices[edges[i] & 0xffffffffu]))) {
        std::abort();
      }
      i = j;
    }
  }
  arena.rewind(start);
  BlockoutOptions o;
  o.exact = true;
  o.sweep.direction = d;
  Mesh blocked;
  if (succeeded(blockout(ctx, box, Span<const Mesh>(&mesh, 1), o, &blocked, nullptr))) {
    require_solid(ctx, blocked);
  }
}

// The terrain (mode bit 7): a 5 x 5 grid over [-1, 1]^2 at spacing 0.5, its border at z = -1,
// each of its 9 inner points moved by 3 bytes (height in [-1, 0.5], x and y by up to 0.375, in
// steps of 1/64 and 3/1024: exact in float32), under a lid at z = 1 with four side walls (each a
// fan from a lid corner). Closed and outward; its floor faces down, and where the shifts fold it
// seen along z, a triangle of it faces up. Returns the triangles written (54).
size_t terrain(const uint8_t* data, size_t size, float (*out)[9]) {
  constexpr int kN = 5;
  float p[kN][kN][3];
  for (int j = 0; j < kN; ++j) {
    for (int i = 0; i < kN; ++i) {
      p[j][i][0] = -1.0f + 0.5f * static_cast<float>(i);
      p[j][i][1] = -1.0f + 0.5f * static_cast<float>(j);
      p[j][i][2] = -1.0f;
      if (i == 0 || j == 0 || i == kN - 1 || j == kN - 1) continue;
      const size_t at = 3 * static_cast<size_t>((j - 1) * (kN - 2) + (i - 1));
      const auto byte = [&](size_t k) { return at + k < size ? data[at + k] : uint8_t{128}; };
      p[j][i][2] = -1.0f + static_cast<float>(byte(0) % 97) / 64.0f;
      p[j][i][0] += (static_cast<float>(byte(1)) - 128.0f) * (3.0f / 1024.0f);
      p[j][i][1] += (static_cast<float>(byte(2)) - 128.0f) * (3.0f / 1024.0f);
    }
  }
  size_t n = 0;
  const auto put = [&](const float* a, const float* b, const float* c) {
    std::memcpy(out[n], a, 12);
    std::memcpy(out[n] + 3, b, 12);
    std::memcpy(out[n] + 6, c, 12);
    ++n;
  };
  for (int j = 0; j + 1 < kN; ++j) {  // the floor, facing down: clockwise seen from above
    for (int i = 0; i + 1 < kN; ++i) {
      put(p[j][i], p[j + 1][i + 1], p[j][i + 1]);
      put(p[j][i], p[j + 1][i], p[j + 1][i + 1]);
    }
  }
  const float lid[4][3] = {{-1, -1, 1}, {1, -1, 1}, {1, 1, 1}, {-1, 1, 1}};
  put(lid[0], lid[1], lid[2]);
  put(lid[0], lid[2], lid[3]);
  // The sides, counter-clockwise around the grid's border seen from above: side s runs from
  // lid corner s to s + 1 over the border points between them, each facing out.
  const float* border[4][kN];
  for (int k = 0; k < kN; ++k) {
    border[0][k] = p[0][k];
    border[1][k] = p[k][kN - 1];
    border[2][k] = p[kN - 1][kN - 1 - k];
    border[3][k] = p[kN - 1 - k][0];
  }
  for (int side = 0; side < 4; ++side) {
    const float* from = lid[side];
    for (int k = 0; k + 1 < kN; ++k) put(from, border[side][k], border[side][k + 1]);
    put(from, border[side][kN - 1], lid[(side + 1) % 4]);
  }
  return n;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static unsigned char memory[32 << 20];
  static uint8_t stl[84 + 50 * kMaxTriangles];
  if (size < 1) return 0;
  const uint8_t mode = data[0];
  ++data;
  --size;
  // Lattice mode: each coordinate is one byte, (b % 9 - 4) / 2 (a half-unit lattice around the
  // cube, so faces coincide with the cube's); else 4 bytes of float32 bits.
  const bool lattice = (mode & 1) != 0;
  const size_t record = lattice ? 9 : 36;
  size_t n = size / record;
  if (n > kMaxTriangles) n = kMaxTriangles;
  const bool ground = (mode & 128) != 0;
  float terrain_corners[kMaxTriangles][9];
  if (ground) n = terrain(data, size, terrain_corners);
  std::memset(stl, 0, sizeof(stl));
  put_u32(stl + 80, static_cast<uint32_t>(n));
  for (size_t t = 0; t < n; ++t) {
    uint8_t* r = stl + 84 + 50 * t + 12;
    for (size_t k = 0; k < 9; ++k) {
      float f = 0;
      if (ground) {
        f = terrain_corners[t][k];
      } else if (lattice) {
        f = static_cast<float>(static_cast<int>(data[t * 9 + k] % 9) - 4) * 0.5f;
      } else {
        std::memcpy(&f, data + t * 36 + 4 * k, 4);
      }
      std::memcpy(r + 4 * k, &f, 4);
    }
  }
  Arena arena(memory, sizeof(memory));
  Context ctx(&arena);
  MemorySource ms{stl, 84 + 50 * n, 0, 0};
  ArenaArray<SoupTriangle> soup(&arena);
  StlReadOptions options;
  options.format = StlFormat::kBinary;
  if (!read_stl(ctx, memory_source(&ms), options, &soup, nullptr).is_ok()) return 0;
  Mesh mesh(&arena);
  if (!weld_exact(ctx, soup.span(), &mesh).is_ok()) return 0;
  MeshReport report;
  if (!check_mesh(ctx, mesh, &report).is_ok()) return 0;
  SelfIntersectionReport si;
  Status s = find_self_intersections(ctx, mesh, 16, &si);
  if (!s.is_ok()) return 0;
  if (!report.is_valid_solid()) return 0;
  Mesh box;
  cube(arena, &box);
  const Arena::Marker stage = arena.mark();
  boolean_stage(ctx, mesh, box, mode, si.self_intersecting());
  arena.rewind(stage);
  if (!si.self_intersecting()) sweep_stage(ctx, mesh, box, mode);  // (a jaw must not cross itself)
  return 0;
}
