// libFuzzer target: bytes -> a small binary STL (the input is the triangle records, 36 bytes
// of float32 coordinates each, at most 64 triangles; coordinates are also taken from a small
// lattice when the mode byte asks, so that shared vertices, coplanar faces and exact touches
// are common) -> weld_exact -> check_mesh -> find_self_intersections -> mesh_boolean against a
// fixed cube, when the mesh is a valid solid. Any crash, sanitizer report, or a Boolean that
// succeeds with a result that is not a closed, oriented, non-self-intersecting mesh is a bug.
//   build/fuzz/tests/splintcore_fuzz_mesh -max_total_time=60 fixtures/fuzz/mesh
#include <cstdlib>
#include <cstring>

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
  std::memset(stl, 0, sizeof(stl));
  put_u32(stl + 80, static_cast<uint32_t>(n));
  for (size_t t = 0; t < n; ++t) {
    uint8_t* r = stl + 84 + 50 * t + 12;
    for (size_t k = 0; k < 9; ++k) {
      float f = 0;
      if (lattice) {
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
  BooleanOptions bo;
  bo.op = static_cast<BooleanOp>((mode >> 1) % 3);
  bo.float32_output = (mode & 8) == 0;
  Mesh result;
  BooleanStats stats;
  const bool swap = (mode & 16) != 0;
  s = mesh_boolean(ctx, swap ? box : mesh, swap ? mesh : box, bo, &result, &stats);
  if (!s.is_ok()) {
    if (s.code() == StatusCode::kInternal) std::abort();
    return 0;
  }
  if (result.triangles.empty()) return 0;  // an empty result is a valid answer (nothing left)
  MeshReport rr;
  if (!check_mesh(ctx, result, &rr).is_ok()) return 0;
  if (!rr.closed() || !rr.edge_manifold() || !rr.oriented()) std::abort();
  SelfIntersectionReport rsi;
  if (find_self_intersections(ctx, result, 1, &rsi).is_ok() && rsi.self_intersecting()) {
    std::abort();
  }
  return 0;
}
