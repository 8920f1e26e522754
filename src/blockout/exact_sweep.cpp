// The swept volume's boundary from the jaw's own triangles (blockout.h, sweep_exact_mesh): the
// front triangles (facing against d, decided exactly) whose prisms can reach the region, and
// a wall along d from each of their edges whose other triangle is not a front triangle.
#include <cmath>
#include <cstring>

#include "splintcore/blockout.h"

namespace splintcore {

namespace {

constexpr uint8_t kBack = 0, kFrontCulled = 1, kFrontKept = 2;
constexpr uint32_t kUnset = 0xffffffffu;

// Whether a front triangle's prism (the triangle moved along d, t >= 0) stays wholly beyond a
// side of the region: its corners all lie strictly beyond a side that moving along d never
// brings back (d pointing out of that side or along it).
bool prism_misses(const Vec3 p[3], const Vec3& d, const Aabb& region) {
  for (int k = 0; k < 3; ++k) {
    if (d[k] >= 0 && p[0][k] > region.hi[k] && p[1][k] > region.hi[k] && p[2][k] > region.hi[k]) {
      return true;
    }
    if (d[k] <= 0 && p[0][k] < region.lo[k] && p[1][k] < region.lo[k] && p[2][k] < region.lo[k]) {
      return true;
    }
  }
  return false;
}

// Classifies every triangle (kBack, kFrontCulled, kFrontKept) and marks the vertices of the kept
// ones (used[v] = 0; kUnset elsewhere).
Status classify_triangles(const Mesh& jaw, const Vec3& d, const Aabb& region, uint8_t* cls,
                          uint32_t* used, ExactSweepStats* st) {
  const size_t nv = jaw.vertices.size();
  for (size_t v = 0; v < nv; ++v) used[v] = kUnset;
  for (size_t t = 0; t < jaw.triangles.size(); ++t) {
    Vec3 p[3];
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = jaw.triangles[t].v[k];
      if (v >= nv) {
        return make_error(StatusCode::kInvalidMesh, "exact sweep: triangle ", t,
                          " has a vertex id out of range")
            .at_index(t);
      }
      p[k] = jaw.vertices[v];
      if (!std::isfinite(p[k].x) || !std::isfinite(p[k].y) || !std::isfinite(p[k].z)) {
        return make_error(StatusCode::kNonFinite, "exact sweep: vertex ", v, " is not finite")
            .at_index(v);
      }
    }
    cls[t] = kBack;
    if (!(normal_dot(p[0], p[1], p[2], d) < 0)) continue;
    ++st->front_triangles;
    cls[t] = prism_misses(p, d, region) ? kFrontCulled : kFrontKept;
    if (cls[t] != kFrontKept) continue;
    ++st->kept_triangles;
    for (int k = 0; k < 3; ++k) used[jaw.triangles[t].v[k]] = 0;
  }
  return Status::ok();
}

// The half-edges that can pair with a kept triangle's: those of the kept front triangles and
// of the culled front ones with at least two corners on kept ones. Keyed by the undirected
// edge; index = 3 * (the triangle's place in `tris`) + the edge's slot.
Status gather_half_edges(Arena& arena, const Mesh& jaw, const uint8_t* cls, const uint32_t* used,
                         ArenaArray<uint32_t>* tris, ArenaArray<KeyIndex>* edges) {
  size_t count = 0;
  for (size_t pass = 0; pass < 2; ++pass) {
    for (size_t t = 0; t < jaw.triangles.size(); ++t) {
      if (cls[t] == kBack) continue;
      const Triangle& g = jaw.triangles[t];
      if (cls[t] == kFrontCulled) {
        int on_kept = 0;
        for (int k = 0; k < 3; ++k) on_kept += used[g.v[k]] != kUnset ? 1 : 0;
        if (on_kept < 2) continue;
      }
      if (pass == 0) {
        ++count;
        continue;
      }
      const uint32_t local = static_cast<uint32_t>(tris->size());
      (void)tris->push_back(static_cast<uint32_t>(t));
      for (uint32_t k = 0; k < 3; ++k) {
        const uint64_t u = g.v[k], v = g.v[(k + 1) % 3];
        KeyIndex e;
        e.key = u < v ? (u << 32) | v : (v << 32) | u;
        e.index = 3 * local + k;
        e.pad = 0;
        (void)edges->push_back(e);
      }
    }
    if (pass == 0) {
      if (count > 0x55555555u) {
        return make_error(StatusCode::kLimitExceeded, "exact sweep: ", count,
                          " front triangles (at most 2^32 / 3)");
      }
      if (!tris->reserve(count) || !edges->reserve(3 * count)) return arena.exhausted_status();
    }
  }
  return radix_sort(arena, edges->span());
}

// The directed edge (from, to) of half-edge `e`.
void half_edge(const Mesh& jaw, const ArenaArray<uint32_t>& tris, const KeyIndex& e, uint32_t* from,
               uint32_t* to) {
  const Triangle& g = jaw.triangles[tris[e.index / 3]];
  const uint32_t k = e.index % 3;
  *from = g.v[k];
  *to = g.v[(k + 1) % 3];
}

// walls[i] bit k: the kept triangle tris[i]'s edge k has no front triangle across it (no
// half-edge the other way among the front ones), so a wall hangs from it.
void mark_walls(const Mesh& jaw, const uint8_t* cls, const ArenaArray<uint32_t>& tris,
                const ArenaArray<KeyIndex>& edges, uint8_t* walls) {
  const size_t n = edges.size();
  for (size_t i = 0; i < n;) {
    size_t j = i + 1;
    while (j < n && edges[j].key == edges[i].key) ++j;
    for (size_t a = i; a < j; ++a) {
      const uint32_t local = edges[a].index / 3;
      if (cls[tris[local]] != kFrontKept) continue;
      uint32_t u, v;
      half_edge(jaw, tris, edges[a], &u, &v);
      bool twin = false;
      for (size_t b = i; b < j && !twin; ++b) {
        uint32_t x, y;
        half_edge(jaw, tris, edges[b], &x, &y);
        twin = x == v && y == u;
      }
      if (!twin) walls[local] |= static_cast<uint8_t>(1u << (edges[a].index % 3));
    }
    i = j;
  }
}

// The top of the wall below jaw vertex p: p moved along d until it lies `reach` beyond the
// region's face that d points through most (at least `reach` from p), rounded to float32.
bool wall_top(const Vec3& p, const Vec3& d, const Aabb& region, Vec3* top) {
  int k = 0;
  for (int i = 1; i < 3; ++i) {
    if (std::fabs(d[i]) > std::fabs(d[k])) k = i;
  }
  double reach = 1.0;
  for (int i = 0; i < 3; ++i) reach = std::fmax(reach, region.hi[i] - region.lo[i]);
  const double plane = d[k] > 0 ? region.hi[k] + reach : region.lo[k] - reach;
  double t = (plane - p[k]) / d[k];
  if (!(t >= reach)) t = reach;
  *top = p + d * t;
  return round_to_float32(top);
}

}  // namespace

uint64_t sweep_exact_bound(uint64_t vertex_count, uint64_t triangle_count) {
  // A class byte per triangle and a rank per vertex; per front triangle one id, three
  // half-edges and their sort's scratch (16 bytes each) and a wall byte; the output at most
  // 3 + 6 triangles and 3 + 3 vertices per kept triangle (then moved down over the rest).
  return triangle_count * (1 + 4 + 96 + 1 + 9 * 12 + 6 * 24) + vertex_count * 4 + 4096;
}

Status sweep_exact_mesh(const Context& ctx, const Mesh& jaw, const Vec3& direction,
                        const Aabb& region, Mesh* out, ExactSweepStats* stats) {
  SPLINTCORE_ASSERT(ctx.arena != nullptr && out != nullptr);
  ExactSweepStats local;
  ExactSweepStats* st = stats != nullptr ? stats : &local;
  *st = ExactSweepStats{};
  if (!out->vertices.empty() || !out->triangles.empty()) {
    return make_error(StatusCode::kInvalidArgument, "exact sweep: the output mesh must be empty");
  }
  const double len = std::sqrt(dot(direction, direction));
  if (!(len > 0) || !std::isfinite(len)) {
    return make_error(StatusCode::kInvalidArgument,
                      "exact sweep: the direction must be a non-zero finite vector");
  }
  if (region.empty() || !std::isfinite(region.lo.x + region.lo.y + region.lo.z + region.hi.x +
                                       region.hi.y + region.hi.z)) {
    return make_error(StatusCode::kInvalidArgument,
                      "exact sweep: the region must be a non-empty finite box");
  }
  const Vec3 d = direction * (1.0 / len);
  st->direction = d;
  Arena& arena = *ctx.arena;
  ArenaScope scope(arena);
  const size_t nv = jaw.vertices.size(), nt = jaw.triangles.size();
  uint8_t* cls = arena.allocate_array<uint8_t>(nt > 0 ? nt : 1);
  uint32_t* used = arena.allocate_array<uint32_t>(nv > 0 ? nv : 1);
  if (cls == nullptr || used == nullptr) return arena.exhausted_status();
  SPLINTCORE_RETURN_IF_ERROR(classify_triangles(jaw, d, region, cls, used, st));

  ArenaArray<uint32_t> tris(&arena);
  ArenaArray<KeyIndex> edges(&arena);
  SPLINTCORE_RETURN_IF_ERROR(gather_half_edges(arena, jaw, cls, used, &tris, &edges));
  uint8_t* walls = arena.allocate_array<uint8_t>(tris.size() > 0 ? tris.size() : 1);
  if (walls == nullptr) return arena.exhausted_status();
  std::memset(walls, 0, tris.size());
  mark_walls(jaw, cls, tris, edges, walls);

  // Output ids: the kept triangles' vertices in input order, then a top per wall corner in
  // the order the walls come (kept triangles in input order, edges in order).
  uint32_t vertex_count = 0;
  for (size_t v = 0; v < nv; ++v) {
    if (used[v] != kUnset) used[v] = vertex_count++;
  }
  uint32_t* top = arena.allocate_array<uint32_t>(vertex_count > 0 ? vertex_count : 1);
  uint8_t* degree = arena.allocate_array<uint8_t>(vertex_count > 0 ? vertex_count : 1);
  if (top == nullptr || degree == nullptr) return arena.exhausted_status();
  std::memset(degree, 0, vertex_count);
  for (uint32_t v = 0; v < vertex_count; ++v) top[v] = kUnset;
  uint32_t top_count = 0;
  for (size_t i = 0; i < tris.size(); ++i) {
    const Triangle& g = jaw.triangles[tris[i]];
    for (int k = 0; k < 3; ++k) {
      if ((walls[i] & (1u << k)) == 0) continue;
      ++st->walls;
      for (int c = 0; c < 2; ++c) {
        const uint32_t v = used[g.v[(k + c) % 3]];
        if (top[v] == kUnset) top[v] = vertex_count + top_count++;
        if (degree[v] < 255) ++degree[v];
      }
    }
  }
  for (uint32_t v = 0; v < vertex_count; ++v) st->pinched_vertices += degree[v] > 2 ? 1 : 0;
  st->top_vertices = top_count;

  Mesh result(&arena);
  if (!result.triangles.reserve(st->kept_triangles + 2 * st->walls) ||
      !result.vertices.reserve(static_cast<size_t>(vertex_count) + top_count)) {
    return arena.exhausted_status();
  }
  for (size_t i = 0; i < tris.size(); ++i) {
    const Triangle& g = jaw.triangles[tris[i]];
    if (cls[tris[i]] != kFrontKept) continue;
    (void)result.triangles.push_back(Triangle{{used[g.v[0]], used[g.v[1]], used[g.v[2]]}});
  }
  for (size_t i = 0; i < tris.size(); ++i) {
    const Triangle& g = jaw.triangles[tris[i]];
    for (int k = 0; k < 3; ++k) {
      if ((walls[i] & (1u << k)) == 0) continue;
      const uint32_t a = used[g.v[k]], b = used[g.v[(k + 1) % 3]];
      // The wall shares the edge a -> b the other way: (b, a, a'), (b, a', b').
      (void)result.triangles.push_back(Triangle{{b, a, top[a]}});
      (void)result.triangles.push_back(Triangle{{b, top[a], top[b]}});
    }
  }
  for (size_t v = 0; v < nv; ++v) {
    if (used[v] != kUnset) (void)result.vertices.push_back(jaw.vertices[v]);
  }
  (void)result.vertices.resize(static_cast<size_t>(vertex_count) + top_count);
  for (size_t v = 0; v < nv; ++v) {
    if (used[v] == kUnset || top[used[v]] == kUnset) continue;
    if (!wall_top(jaw.vertices[v], d, region, &result.vertices[top[used[v]]])) {
      return make_error(StatusCode::kLimitExceeded, "exact sweep: the wall above vertex ", v,
                        " ends beyond float32 range")
          .at_index(v);
    }
  }
  move_mesh_down(arena, scope.start(), result, out);
  scope.commit();
  return Status::ok();
}

}  // namespace splintcore
