// The swept volume's boundary from the jaw's own triangles (blockout.h, sweep_exact_mesh): the
// front triangles (facing against d, decided exactly) whose prisms can reach the region, and
// a wall along d from each of their edges whose other triangle is not a front triangle; where
// the front fan around a vertex overlaps one of its walls seen along d, the back triangles
// around it join the patch.
#include <cmath>
#include <cstring>

#include "splintcore/blockout.h"

namespace splintcore {

namespace {

// A triangle's part: not in the surface, a front triangle left out (its prism cannot reach
// the region), a kept front triangle, a back triangle taken in around a fold.
constexpr uint8_t kBack = 0, kFrontCulled = 1, kFrontKept = 2, kAbsorbed = 3;
constexpr uint32_t kUnset = 0xffffffffu;
// Rounds of taking in back triangles at most; what is left crossing then is the Boolean's to
// refuse (blockout says why).
constexpr int kMaxRounds = 64;

inline bool in_patch(uint8_t c) { return c == kFrontKept || c == kAbsorbed; }

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

// One round's view of the surface: the triangles with a corner in it (`tris`, input order),
// their half-edges' twins, the walls, and per vertex of the surface (by rank) its triangles
// among `tris` and the other ends of its walls.
struct Round {
  ArenaArray<uint32_t> tris;
  uint32_t* twin = nullptr;  // per half-edge 3 * i + k of tris[i]: the twin's, or kUnset
  uint8_t* walls = nullptr;  // per tris[i]: bit k, a wall hangs from edge k
  uint32_t* rank = nullptr;  // per jaw vertex: its place among the surface's, or kUnset
  uint32_t vertex_count = 0;
  uint32_t* star_start = nullptr;  // vertex_count + 1 offsets into star
  uint32_t* star = nullptr;        // indices into tris
  uint32_t* wall_ends = nullptr;   // 2 per vertex: its first two walls' other ends (jaw ids)
  uint8_t* wall_degree = nullptr;  // walls at the vertex (saturating)
  uint32_t* seen = nullptr;        // per tris[i]: the last ring_triangles call that took it
  uint32_t calls = 0;
};

// The triangles with a corner on the surface and their half-edges' twins (the half-edge the
// other way along the same edge, first found; kUnset on a border).
Status pair_half_edges(Arena& arena, const Mesh& jaw, const uint32_t* used, Round* r) {
  size_t count = 0;
  for (const Triangle& g : jaw.triangles) {
    count += used[g.v[0]] != kUnset || used[g.v[1]] != kUnset || used[g.v[2]] != kUnset ? 1 : 0;
  }
  if (count > 0x55555555u) {
    return make_error(StatusCode::kLimitExceeded, "exact sweep: ", count,
                      " triangles near the surface (at most 2^32 / 3)");
  }
  ArenaArray<KeyIndex> edges(&arena);
  if (!r->tris.reserve(count) || !edges.reserve(3 * count)) return arena.exhausted_status();
  r->twin = arena.allocate_array<uint32_t>(3 * count + 1);
  if (r->twin == nullptr) return arena.exhausted_status();
  for (size_t t = 0; t < jaw.triangles.size(); ++t) {
    const Triangle& g = jaw.triangles[t];
    if (used[g.v[0]] == kUnset && used[g.v[1]] == kUnset && used[g.v[2]] == kUnset) continue;
    const uint32_t i = static_cast<uint32_t>(r->tris.size());
    (void)r->tris.push_back(static_cast<uint32_t>(t));
    for (uint32_t k = 0; k < 3; ++k) {
      const uint64_t u = g.v[k], v = g.v[(k + 1) % 3];
      (void)edges.push_back(KeyIndex{u < v ? (u << 32) | v : (v << 32) | u, 3 * i + k, 0});
      r->twin[3 * i + k] = kUnset;
    }
  }
  SPLINTCORE_RETURN_IF_ERROR(radix_sort(arena, edges.span()));
  const auto from = [&](uint32_t h) { return jaw.triangles[r->tris[h / 3]].v[h % 3]; };
  for (size_t a = 0, n = edges.size(); a < n;) {
    size_t b = a + 1;
    while (b < n && edges[b].key == edges[a].key) ++b;
    for (size_t x = a; x < b; ++x) {
      for (size_t y = a; y < b && r->twin[edges[x].index] == kUnset; ++y) {
        const uint32_t hx = edges[x].index, hy = edges[y].index;
        if (from(hx) != from(hy)) r->twin[hx] = hy;  // same key, other direction
      }
    }
    a = b;
  }
  return Status::ok();
}

// Walls (edges of the surface's triangles whose twin is neither on the surface nor a front
// triangle left out), the ranks, stars and wall ends of the surface's vertices.
Status build_round(Arena& arena, const Mesh& jaw, const uint8_t* cls, const uint32_t* used,
                   Round* r) {
  SPLINTCORE_RETURN_IF_ERROR(pair_half_edges(arena, jaw, used, r));
  const size_t nt = r->tris.size(), nv = jaw.vertices.size();
  r->walls = arena.allocate_array<uint8_t>(nt + 1);
  r->rank = arena.allocate_array<uint32_t>(nv + 1);
  if (r->walls == nullptr || r->rank == nullptr) return arena.exhausted_status();
  r->vertex_count = 0;
  for (size_t v = 0; v < nv; ++v) r->rank[v] = used[v] != kUnset ? r->vertex_count++ : kUnset;
  const uint32_t n = r->vertex_count;
  r->star_start = arena.allocate_array<uint32_t>(n + 1);
  r->wall_ends = arena.allocate_array<uint32_t>(2 * size_t{n} + 1);
  r->wall_degree = arena.allocate_array<uint8_t>(n + 1);
  r->star = arena.allocate_array<uint32_t>(3 * nt + 1);
  r->seen = arena.allocate_array<uint32_t>(nt + 1);
  if (r->star_start == nullptr || r->wall_ends == nullptr || r->wall_degree == nullptr ||
      r->star == nullptr || r->seen == nullptr) {
    return arena.exhausted_status();
  }
  std::memset(r->seen, 0, (nt + 1) * sizeof(uint32_t));
  std::memset(r->star_start, 0, (n + 1) * sizeof(uint32_t));
  std::memset(r->wall_degree, 0, n + 1);
  for (size_t i = 0; i < nt; ++i) {
    const Triangle& g = jaw.triangles[r->tris[i]];
    r->walls[i] = 0;
    for (uint32_t k = 0; k < 3; ++k) {
      if (r->rank[g.v[k]] != kUnset) ++r->star_start[r->rank[g.v[k]] + 1];
      if (!in_patch(cls[r->tris[i]])) continue;
      const uint32_t tw = r->twin[3 * i + k];
      const uint8_t other = tw == kUnset ? kBack : cls[r->tris[tw / 3]];
      if (in_patch(other) || other == kFrontCulled) continue;
      r->walls[i] |= static_cast<uint8_t>(1u << k);
      const uint32_t a = g.v[k], b = g.v[(k + 1) % 3];
      const auto add_end = [&](uint32_t at, uint32_t end) {
        const uint32_t ra = r->rank[at];
        if (r->wall_degree[ra] < 2) r->wall_ends[2 * ra + r->wall_degree[ra]] = end;
        if (r->wall_degree[ra] < 255) ++r->wall_degree[ra];
      };
      add_end(a, b);
      add_end(b, a);
    }
  }
  for (uint32_t v = 0; v < n; ++v) r->star_start[v + 1] += r->star_start[v];
  uint32_t* fill = arena.allocate_array<uint32_t>(n + 1);
  if (fill == nullptr) return arena.exhausted_status();
  std::memcpy(fill, r->star_start, (n + 1) * sizeof(uint32_t));
  for (size_t i = 0; i < nt; ++i) {
    const Triangle& g = jaw.triangles[r->tris[i]];
    for (int k = 0; k < 3; ++k) {
      if (r->rank[g.v[k]] != kUnset) r->star[fill[r->rank[g.v[k]]]++] = static_cast<uint32_t>(i);
    }
  }
  return Status::ok();
}

// Whether, seen along d, the wall from jaw vertex v towards s runs inside the corner at v of
// a triangle of the surface around v (other than those on the edge): the surface overlaps
// its own wall there.
bool wall_inside_fan(const Mesh& jaw, const uint8_t* cls, const Round& r, uint32_t v,
                     uint32_t rank_v, uint32_t s, const Vec3& d) {
  const Vec3& pv = jaw.vertices[v];
  for (uint32_t j = r.star_start[rank_v]; j < r.star_start[rank_v + 1]; ++j) {
    const uint32_t t = r.tris[r.star[j]];
    if (!in_patch(cls[t])) continue;
    const Triangle& g = jaw.triangles[t];
    const int k = g.v[0] == v ? 0 : (g.v[1] == v ? 1 : 2);
    const uint32_t p = g.v[(k + 1) % 3], q = g.v[(k + 2) % 3];
    if (p == s || q == s) continue;
    const int o = sign_of(normal_dot(pv, jaw.vertices[p], jaw.vertices[q], d));
    if (o == 0) continue;
    // Seen along d, s lies inside the corner p v q; and the triangle is above the edge v s
    // there (s on its normal's side for a front triangle, which faces against d; on the other
    // side for a back one): the wall rising from the edge crosses it near v.
    if (sign_of(normal_dot(pv, jaw.vertices[p], jaw.vertices[s], d)) == o &&
        sign_of(normal_dot(pv, jaw.vertices[s], jaw.vertices[q], d)) == o &&
        sign_of(orient3d(pv, jaw.vertices[p], jaw.vertices[q], jaw.vertices[s])) == o) {
      return true;
    }
  }
  return false;
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

// The surface's triangles within kRings rings of jaw vertex v (indices into r.tris, at most
// kRingCap of them, in the order found), for the wall test below.
constexpr int kRings = 8;
constexpr uint32_t kRingCap = 1024;
uint32_t ring_triangles(const Mesh& jaw, const uint8_t* cls, Round& r, uint32_t v, uint32_t* out) {
  uint32_t count = 0, done = 0;
  const uint32_t call = ++r.calls;
  const auto add_star = [&](uint32_t vertex) {
    const uint32_t rv = r.rank[vertex];
    if (rv == kUnset) return;
    for (uint32_t j = r.star_start[rv]; j < r.star_start[rv + 1] && count < kRingCap; ++j) {
      const uint32_t i = r.star[j];
      if (!in_patch(cls[r.tris[i]]) || r.seen[i] == call) continue;
      r.seen[i] = call;
      out[count++] = i;
    }
  };
  add_star(v);
  for (int ring = 1; ring < kRings; ++ring) {
    const uint32_t end = count;
    for (; done < end; ++done) {
      for (uint32_t w : jaw.triangles[r.tris[out[done]]].v) add_star(w);
    }
  }
  return count;
}

// Whether the wall from jaw vertex v to s (as emitted: tops rounded) meets a triangle of the
// surface near v that has neither corner of the edge: the surface overhangs its own wall
// further than the corner test above sees.
bool wall_meets_ring(const Mesh& jaw, const uint8_t* cls, Round& r, uint32_t v, uint32_t s,
                     const Vec3& d, const Aabb& region) {
  Vec3 vt, st;
  if (!wall_top(jaw.vertices[v], d, region, &vt) || !wall_top(jaw.vertices[s], d, region, &st)) {
    return false;  // the output says so
  }
  uint32_t ring[kRingCap];
  const uint32_t n = ring_triangles(jaw, cls, r, v, ring);
  const Vec3& pv = jaw.vertices[v];
  const Vec3& ps = jaw.vertices[s];
  Aabb wall;
  wall.add(pv);
  wall.add(ps);
  wall.add(vt);
  wall.add(st);
  for (uint32_t i = 0; i < n; ++i) {
    const Triangle& g = jaw.triangles[r.tris[ring[i]]];
    bool shares = false;
    for (uint32_t w : g.v) shares = shares || w == v || w == s;
    if (shares) continue;
    const Vec3& a = jaw.vertices[g.v[0]];
    const Vec3& b = jaw.vertices[g.v[1]];
    const Vec3& c = jaw.vertices[g.v[2]];
    Aabb box;
    box.add(a);
    box.add(b);
    box.add(c);
    if (!box.overlaps(wall)) continue;  // closed boxes: touching still tested
    if (triangles_intersect(pv, ps, vt, a, b, c) || triangles_intersect(ps, vt, st, a, b, c)) {
      return true;
    }
  }
  return false;
}

// Vertices whose walls the surface around them overlaps (or with more than two walls): their
// back triangles join the surface. Returns how many vertices did so.
uint32_t absorb_folds(const Mesh& jaw, Round& r, const Vec3& d, const Aabb& region, uint8_t* cls,
                      uint32_t* used) {
  uint32_t folds = 0;
  for (size_t v = 0; v < jaw.vertices.size(); ++v) {
    const uint32_t rv = r.rank[v];
    if (rv == kUnset || r.wall_degree[rv] == 0) continue;
    bool fold = r.wall_degree[rv] > 2;
    for (uint32_t w = 0; w < r.wall_degree[rv] && w < 2 && !fold; ++w) {
      const uint32_t end = r.wall_ends[2 * rv + w];
      fold = wall_inside_fan(jaw, cls, r, static_cast<uint32_t>(v), rv, end, d) ||
             wall_meets_ring(jaw, cls, r, static_cast<uint32_t>(v), end, d, region);
    }
    if (!fold) continue;
    ++folds;
    for (uint32_t j = r.star_start[rv]; j < r.star_start[rv + 1]; ++j) {
      const uint32_t t = r.tris[r.star[j]];
      if (cls[t] != kBack) continue;
      cls[t] = kAbsorbed;
      for (int k = 0; k < 3; ++k) {
        if (used[jaw.triangles[t].v[k]] == kUnset) used[jaw.triangles[t].v[k]] = 0;
      }
    }
  }
  return folds;
}

// The output from the final round: the surface's triangles in input order, then two per wall;
// the surface's vertices in input order, then the walls' tops in the order the walls come.
Status emit_surface(Arena& arena, const Mesh& jaw, const uint8_t* cls, const Round& r,
                    const Vec3& d, const Aabb& region, Mesh* result, ExactSweepStats* st) {
  const uint32_t n = r.vertex_count;
  uint32_t* top = arena.allocate_array<uint32_t>(n + 1);
  if (top == nullptr) return arena.exhausted_status();
  for (uint32_t v = 0; v < n; ++v) top[v] = kUnset;
  uint64_t patch = 0;
  uint32_t tops = 0;
  for (size_t i = 0; i < r.tris.size(); ++i) {
    const Triangle& g = jaw.triangles[r.tris[i]];
    patch += in_patch(cls[r.tris[i]]) ? 1u : 0u;
    for (int k = 0; k < 3; ++k) {
      if ((r.walls[i] & (1u << k)) == 0) continue;
      ++st->walls;
      for (int c = 0; c < 2; ++c) {
        const uint32_t v = r.rank[g.v[(k + c) % 3]];
        if (top[v] == kUnset) top[v] = n + tops++;
      }
    }
  }
  for (uint32_t v = 0; v < n; ++v) st->pinched_vertices += r.wall_degree[v] > 2 ? 1u : 0u;
  st->top_vertices = tops;
  result->bind(&arena);
  if (!result->triangles.reserve(patch + 2 * st->walls) ||
      !result->vertices.resize(static_cast<size_t>(n) + tops)) {
    return arena.exhausted_status();
  }
  for (size_t i = 0; i < r.tris.size(); ++i) {
    const Triangle& g = jaw.triangles[r.tris[i]];
    if (!in_patch(cls[r.tris[i]])) continue;
    (void)result->triangles.push_back(Triangle{{r.rank[g.v[0]], r.rank[g.v[1]], r.rank[g.v[2]]}});
  }
  for (size_t i = 0; i < r.tris.size(); ++i) {
    const Triangle& g = jaw.triangles[r.tris[i]];
    for (int k = 0; k < 3; ++k) {
      if ((r.walls[i] & (1u << k)) == 0) continue;
      const uint32_t a = r.rank[g.v[k]], b = r.rank[g.v[(k + 1) % 3]];
      // The wall shares the edge a -> b the other way: (b, a, a'), (b, a', b').
      (void)result->triangles.push_back(Triangle{{b, a, top[a]}});
      (void)result->triangles.push_back(Triangle{{b, top[a], top[b]}});
    }
  }
  for (size_t v = 0; v < jaw.vertices.size(); ++v) {
    const uint32_t rv = r.rank[v];
    if (rv == kUnset) continue;
    result->vertices[rv] = jaw.vertices[v];
    if (top[rv] != kUnset && !wall_top(jaw.vertices[v], d, region, &result->vertices[top[rv]])) {
      return make_error(StatusCode::kLimitExceeded, "exact sweep: the wall above vertex ", v,
                        " ends beyond float32 range")
          .at_index(v);
    }
  }
  return Status::ok();
}

}  // namespace

uint64_t sweep_exact_bound(uint64_t vertex_count, uint64_t triangle_count) {
  // A class byte per triangle, a mark and a rank per vertex; a round: per triangle near the
  // surface an id, three half-edges and their sort's scratch (16 bytes each), three twins,
  // three star entries and a wall byte; per vertex a star offset, its fill, two wall ends and
  // a degree byte, then the tops; the output at most the triangles with 2 walls each and the
  // vertices twice (the surface can hold every triangle at worst).
  return triangle_count * (1 + 4 + 96 + 12 + 12 + 1 + 3 * 12) + vertex_count * (4 + 4 + 18 + 4) +
         vertex_count * 48 + 8192;
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
  uint8_t* cls = arena.allocate_array<uint8_t>(nt + 1);
  uint32_t* used = arena.allocate_array<uint32_t>(nv + 1);
  if (cls == nullptr || used == nullptr) return arena.exhausted_status();
  SPLINTCORE_RETURN_IF_ERROR(classify_triangles(jaw, d, region, cls, used, st));
  const Arena::Marker rounds = arena.mark();
  Round r;
  for (int round = 0;; ++round) {
    arena.rewind(rounds);
    r = Round();
    r.tris.bind(&arena);
    SPLINTCORE_RETURN_IF_ERROR(build_round(arena, jaw, cls, used, &r));
    if (round == kMaxRounds) break;
    const uint32_t folds = absorb_folds(jaw, r, d, region, cls, used);
    if (folds == 0) break;
    st->fold_vertices += folds;
    ++st->fold_rounds;
  }
  for (size_t t = 0; t < nt; ++t) st->absorbed_triangles += cls[t] == kAbsorbed ? 1u : 0u;
  Mesh result;
  SPLINTCORE_RETURN_IF_ERROR(emit_surface(arena, jaw, cls, r, d, region, &result, st));
  move_mesh_down(arena, scope.start(), result, out);
  scope.commit();
  return Status::ok();
}

}  // namespace splintcore
