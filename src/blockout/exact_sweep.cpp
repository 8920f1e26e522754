// The swept volume's boundary from the jaw's own triangles (blockout.h, sweep_exact_mesh): the
// front triangles (facing against d, decided exactly) whose prisms can reach the region, and
// a wall along d from each of their edges whose other triangle is not a front triangle; where
// the front fan around a vertex overlaps one of its walls seen along d, the back triangles
// around it join the patch.
#include <cmath>
#include <cstdint>
#include <cstring>

#include "core/fminmax.h"
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

// The surface's state: every jaw triangle's part (cls), its vertices' triangles (a table over
// the whole jaw, built once: the rounds only change parts), and per round the walls (a bit
// per edge of the surface's triangles) and per jaw vertex its walls' other ends.
struct Surface {
  const Mesh* jaw = nullptr;
  uint8_t* cls = nullptr;
  uint32_t* star_start = nullptr;  // nv + 1 offsets into star
  uint32_t* star = nullptr;        // triangle ids, in input order per vertex
  uint8_t* walls = nullptr;        // per triangle: bit k, a wall hangs from edge k
  uint32_t* wall_ends = nullptr;   // 2 per vertex: its first two walls' other ends
  uint8_t* wall_degree = nullptr;  // walls at the vertex (saturating)
  uint32_t* seen = nullptr;        // per triangle: the last ring_triangles call that took it
  uint32_t calls = 0;
};

// The vertex -> triangles table of the whole jaw (counting, then filling in input order).
Status build_stars(Arena& arena, const Mesh& jaw, Surface* f) {
  const size_t nv = jaw.vertices.size(), nt = jaw.triangles.size();
  if (nt > 0x55555555u) {
    return make_error(StatusCode::kLimitExceeded, "exact sweep: ", nt,
                      " triangles (at most 2^32 / 3)");
  }
  f->star_start = arena.allocate_array<uint32_t>(nv + 1);
  f->star = arena.allocate_array<uint32_t>(3 * nt + 1);
  uint32_t* fill = arena.allocate_array<uint32_t>(nv + 1);
  f->walls = arena.allocate_array<uint8_t>(nt + 1);
  f->seen = arena.allocate_array<uint32_t>(nt + 1);
  f->wall_ends = arena.allocate_array<uint32_t>(2 * nv + 1);
  f->wall_degree = arena.allocate_array<uint8_t>(nv + 1);
  if (f->star_start == nullptr || f->star == nullptr || fill == nullptr || f->walls == nullptr ||
      f->seen == nullptr || f->wall_ends == nullptr || f->wall_degree == nullptr) {
    return arena.exhausted_status();
  }
  std::memset(f->star_start, 0, (nv + 1) * sizeof(uint32_t));
  std::memset(f->seen, 0, (nt + 1) * sizeof(uint32_t));
  for (const Triangle& g : jaw.triangles) {
    for (uint32_t v : g.v) ++f->star_start[v + 1];
  }
  for (size_t v = 0; v < nv; ++v) f->star_start[v + 1] += f->star_start[v];
  std::memcpy(fill, f->star_start, (nv + 1) * sizeof(uint32_t));
  for (size_t t = 0; t < nt; ++t) {
    for (uint32_t v : jaw.triangles[t].v) f->star[fill[v]++] = static_cast<uint32_t>(t);
  }
  return Status::ok();
}

// The triangle across edge k of triangle t (the edge the other way round, first in the star
// of its far end), or kUnset on a border.
uint32_t across(const Surface& f, uint32_t t, uint32_t k) {
  const Mesh& jaw = *f.jaw;
  const uint32_t a = jaw.triangles[t].v[k], b = jaw.triangles[t].v[(k + 1) % 3];
  for (uint32_t j = f.star_start[b]; j < f.star_start[b + 1]; ++j) {
    const Triangle& g = jaw.triangles[f.star[j]];
    for (uint32_t m = 0; m < 3; ++m) {
      if (g.v[m] == b && g.v[(m + 1) % 3] == a) return f.star[j];
    }
  }
  return kUnset;
}

// The walls of triangle t: bit k when its edge k has a wall (t on the surface, the triangle
// across neither on it nor a front triangle left out).
uint8_t wall_bits(const Surface& f, uint32_t t) {
  if (!in_patch(f.cls[t])) return 0;
  uint8_t bits = 0;
  for (uint32_t k = 0; k < 3; ++k) {
    const uint32_t o = across(f, t, k);
    const uint8_t other = o == kUnset ? kBack : f.cls[o];
    if (!in_patch(other) && other != kFrontCulled) bits = static_cast<uint8_t>(bits | (1u << k));
  }
  return bits;
}

// Vertex v's walls: their count and the other ends of the first two, in the order of v's
// triangles and their edges.
void vertex_walls(Surface* f, uint32_t v) {
  const Mesh& jaw = *f->jaw;
  f->wall_degree[v] = 0;
  for (uint32_t j = f->star_start[v]; j < f->star_start[v + 1]; ++j) {
    const uint32_t t = f->star[j];
    for (uint32_t k = 0; k < 3; ++k) {
      if ((f->walls[t] & (1u << k)) == 0) continue;
      const uint32_t a = jaw.triangles[t].v[k], b = jaw.triangles[t].v[(k + 1) % 3];
      if (a != v && b != v) continue;
      if (f->wall_degree[v] < 2) f->wall_ends[2 * v + f->wall_degree[v]] = a == v ? b : a;
      if (f->wall_degree[v] < 255) ++f->wall_degree[v];
    }
  }
}

// All the walls (edges of the surface's triangles whose other triangle is neither on the
// surface nor a front triangle left out) and, per vertex, their other ends.
void find_walls(Surface* f) {
  const Mesh& jaw = *f->jaw;
  for (uint32_t t = 0; t < jaw.triangles.size(); ++t) f->walls[t] = wall_bits(*f, t);
  for (uint32_t v = 0; v < jaw.vertices.size(); ++v) vertex_walls(f, v);
}

// The walls again where triangles joined the surface: theirs, their neighbours', and then
// the vertices of all of those.
void update_walls(Surface* f, const uint32_t* joined, uint32_t count) {
  const Mesh& jaw = *f->jaw;
  for (uint32_t i = 0; i < count; ++i) {
    const uint32_t t = joined[i];
    f->walls[t] = wall_bits(*f, t);
    for (uint32_t k = 0; k < 3; ++k) {
      const uint32_t o = across(*f, t, k);
      if (o != kUnset) f->walls[o] = wall_bits(*f, o);
    }
  }
  for (uint32_t i = 0; i < count; ++i) {
    const uint32_t t = joined[i];
    for (uint32_t v : jaw.triangles[t].v) vertex_walls(f, v);
    for (uint32_t k = 0; k < 3; ++k) {
      const uint32_t o = across(*f, t, k);
      if (o == kUnset) continue;
      for (uint32_t v : jaw.triangles[o].v) vertex_walls(f, v);
    }
  }
}

// Whether, seen along d, the wall from jaw vertex v towards s runs inside the corner at v of
// a triangle of the surface around v (other than those on the edge) that lies above the edge
// there: the surface overlaps its own wall.
bool wall_inside_fan(const Surface& f, uint32_t v, uint32_t s, const Vec3& d) {
  const Mesh& jaw = *f.jaw;
  const Vec3& pv = jaw.vertices[v];
  for (uint32_t j = f.star_start[v]; j < f.star_start[v + 1]; ++j) {
    const uint32_t t = f.star[j];
    if (!in_patch(f.cls[t])) continue;
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
  for (int i = 0; i < 3; ++i) reach = max_of(reach, region.hi[i] - region.lo[i]);
  const double plane = d[k] > 0 ? region.hi[k] + reach : region.lo[k] - reach;
  double t = (plane - p[k]) / d[k];
  if (!(t >= reach)) t = reach;
  *top = p + d * t;
  return round_to_float32(top);
}

// The surface's triangles within kRings rings of jaw vertex v (at most kRingCap of them, in
// the order found), for the wall test below.
constexpr int kRings = 8;
constexpr uint32_t kRingCap = 1024;
uint32_t ring_triangles(Surface& f, uint32_t v, uint32_t* out) {
  uint32_t count = 0, done = 0;
  const uint32_t call = ++f.calls;
  const auto add_star = [&](uint32_t vertex) {
    for (uint32_t j = f.star_start[vertex]; j < f.star_start[vertex + 1] && count < kRingCap; ++j) {
      const uint32_t t = f.star[j];
      if (!in_patch(f.cls[t]) || f.seen[t] == call) continue;
      f.seen[t] = call;
      out[count++] = t;
    }
  };
  add_star(v);
  for (int ring = 1; ring < kRings; ++ring) {
    const uint32_t end = count;
    for (; done < end; ++done) {
      for (uint32_t w : f.jaw->triangles[out[done]].v) add_star(w);
    }
  }
  return count;
}

// Whether the wall from jaw vertex v to s (as emitted: tops rounded) meets a triangle of the
// surface near v (`ring`, v's ring_triangles) that has neither corner of the edge: the surface
// overhangs its own wall further than the corner test above sees.
bool wall_meets_ring(const Surface& f, uint32_t v, uint32_t s, const Vec3& d, const Aabb& region,
                     const uint32_t* ring, uint32_t n) {
  const Mesh& jaw = *f.jaw;
  Vec3 vt, st;
  if (!wall_top(jaw.vertices[v], d, region, &vt) || !wall_top(jaw.vertices[s], d, region, &st)) {
    return false;  // the output says so
  }
  const Vec3& pv = jaw.vertices[v];
  const Vec3& ps = jaw.vertices[s];
  Aabb wall;
  wall.add(pv);
  wall.add(ps);
  wall.add(vt);
  wall.add(st);
  for (uint32_t i = 0; i < n; ++i) {
    const Triangle& g = jaw.triangles[ring[i]];
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

// Marks for recheck (state 0) every jaw vertex of a surface triangle within kRings rings of a
// vertex of the round's joined triangles: one breadth-first search from all of them at once,
// over the round's whole surface, in `queue` (room for every jaw vertex). Rings of vertices
// that reach each other are walked once, where a ring per corner walked them up to six times.
constexpr uint8_t kQueued = 2;
void reset_around(Surface& f, const uint32_t* joined, uint32_t joined_count, uint8_t* state,
                  uint32_t* queue) {
  const Mesh& jaw = *f.jaw;
  uint32_t end = 0;
  const auto push = [&](uint32_t w) {
    if (state[w] == kQueued) return;
    state[w] = kQueued;
    queue[end++] = w;
  };
  for (uint32_t i = 0; i < joined_count; ++i) {
    for (uint32_t w : jaw.triangles[joined[i]].v) push(w);
  }
  const uint32_t call = ++f.calls;
  uint32_t done = 0;
  for (int ring = 0; ring < kRings; ++ring) {
    const uint32_t level_end = end;
    for (; done < level_end; ++done) {
      const uint32_t w = queue[done];
      for (uint32_t j = f.star_start[w]; j < f.star_start[w + 1]; ++j) {
        const uint32_t t = f.star[j];
        if (!in_patch(f.cls[t]) || f.seen[t] == call) continue;
        f.seen[t] = call;
        for (uint32_t x : jaw.triangles[t].v) push(x);
      }
    }
  }
  for (uint32_t i = 0; i < end; ++i) state[queue[i]] = 0;
}

// Vertices whose walls the surface around them overlaps (or with more than two walls): their
// back triangles join the surface. A vertex found clean stays clean until a triangle within
// its rings joins (then every vertex around that triangle is tested again: reset_around):
// state[v] is kClean or not, per jaw vertex. `folds` holds the round's fold vertices (room for
// one per jaw vertex; reset_around's queue after). Returns how many vertices were folds.
constexpr uint8_t kClean = 1;
uint32_t absorb_folds(Surface& f, const Vec3& d, const Aabb& region, uint32_t* used, uint8_t* state,
                      uint32_t* folds, uint32_t* joined, uint32_t* joined_count) {
  const Mesh& jaw = *f.jaw;
  uint32_t count = 0;
  uint32_t ring[kRingCap];
  for (uint32_t v = 0; v < jaw.vertices.size(); ++v) {
    if (f.wall_degree[v] == 0 || state[v] == kClean) continue;
    bool fold = f.wall_degree[v] > 2;
    uint32_t n = kUnset;  // v's ring, found once for both its walls
    for (uint32_t w = 0; w < f.wall_degree[v] && w < 2 && !fold; ++w) {
      const uint32_t end = f.wall_ends[2 * v + w];
      fold = wall_inside_fan(f, v, end, d);
      if (fold) break;
      if (n == kUnset) n = ring_triangles(f, v, ring);
      fold = wall_meets_ring(f, v, end, d, region, ring, n);
    }
    if (fold) {
      folds[count++] = v;
    } else {
      state[v] = kClean;
    }
  }
  for (uint32_t i = 0; i < count; ++i) {
    const uint32_t v = folds[i];
    for (uint32_t j = f.star_start[v]; j < f.star_start[v + 1]; ++j) {
      const uint32_t t = f.star[j];
      if (f.cls[t] != kBack) continue;
      f.cls[t] = kAbsorbed;
      joined[(*joined_count)++] = t;
      for (uint32_t w : jaw.triangles[t].v) used[w] = 0;
    }
  }
  reset_around(f, joined, *joined_count, state, folds);
  return count;
}

// The most undercut a fold may leave unswept. A back triangle taken into the surface leaves the
// column above it (along d, up to the front side over it) out of the swept volume: its
// cross-section lies within the triangle seen along d. At a fold of the tessellation (a
// sliver between two front fans on a side nearly parallel to d) that is a fin micrometres
// wide (at most 0.040 mm on the real maxilla, 0.026 mm on the mandible, measured); at a real
// overhang (a neck band under a crown) it is the undercut itself, and the sweep must not pass
// it off as resolved. 0.05 mm is the undercut the voxel method leaves everywhere by default
// (its inset, half its 0.1 mm voxel), and about the printer's dot (0.042 mm on the Eden260).
constexpr double kFoldPocket = 0.05;

// Every back triangle taken in whose prism can reach the region is checked: seen along d it
// is at most kFoldPocket wide (twice its area over its longest side, in doubles), or the
// segment from its centroid kFoldPocket along d meets a surface triangle within the rings
// (segment_intersects_triangle: the pocket is no deeper), or `pockets` finds its column clear.
// *deep: the first taken-in triangle that is none of these, or kUnset.
Status deep_pocket(Surface& f, const Vec3& d, const Aabb& region, const ExactPocketTest* pockets,
                   ExactSweepStats* st, uint32_t* deep) {
  const Mesh& jaw = *f.jaw;
  *deep = kUnset;
  uint32_t ring[kRingCap];
  for (uint32_t t = 0; t < jaw.triangles.size(); ++t) {
    if (f.cls[t] != kAbsorbed) continue;
    const Triangle& g = jaw.triangles[t];
    const Vec3 p[3] = {jaw.vertices[g.v[0]], jaw.vertices[g.v[1]], jaw.vertices[g.v[2]]};
    if (prism_misses(p, d, region)) continue;
    ++st->pockets_checked;
    Vec3 seen[3];
    for (int k = 0; k < 3; ++k) seen[k] = p[k] - d * dot(p[k], d);
    const Vec3 n = cross(seen[1] - seen[0], seen[2] - seen[0]);
    double longest = 0;
    for (int k = 0; k < 3; ++k) {
      const Vec3 e = seen[(k + 1) % 3] - seen[k];
      longest = max_of(longest, dot(e, e));
    }
    const double width = std::sqrt(dot(n, n)) / std::sqrt(longest);
    if (width <= kFoldPocket) continue;  // longest > 0 then (else width is NaN)
    const Vec3 c = (p[0] + p[1] + p[2]) * (1.0 / 3);
    const Vec3 q = c + d * kFoldPocket;
    const uint32_t count = ring_triangles(f, g.v[0], ring);
    bool covered = false;
    for (uint32_t i = 0; i < count && !covered; ++i) {
      if (ring[i] == t) continue;
      const Triangle& h = jaw.triangles[ring[i]];
      covered = segment_intersects_triangle(c, q, jaw.vertices[h.v[0]], jaw.vertices[h.v[1]],
                                            jaw.vertices[h.v[2]]);
    }
    if (covered) {
      ++st->pockets_shallow;
      continue;
    }
    bool clear = false;
    if (pockets != nullptr && pockets->clear != nullptr) {
      SPLINTCORE_RETURN_IF_ERROR(pockets->clear(pockets->user, p, &clear));
    }
    if (!clear) {
      *deep = t;
      return Status::ok();
    }
    ++st->pockets_clear;
  }
  return Status::ok();
}

// The output: the surface's triangles in input order, then two per wall; the surface's
// vertices in input order (used[v]: its rank), then the walls' tops in the order the walls
// come.
Status emit_surface(Arena& arena, const Surface& f, uint32_t* used, const Vec3& d,
                    const Aabb& region, Mesh* result, ExactSweepStats* st) {
  const Mesh& jaw = *f.jaw;
  const size_t nv = jaw.vertices.size(), nt = jaw.triangles.size();
  uint32_t n = 0;
  for (size_t v = 0; v < nv; ++v) {
    if (used[v] != kUnset) used[v] = n++;
  }
  uint32_t* top = arena.allocate_array<uint32_t>(n + 1);
  if (top == nullptr) return arena.exhausted_status();
  for (uint32_t v = 0; v < n; ++v) top[v] = kUnset;
  uint64_t patch = 0;
  uint32_t tops = 0;
  for (size_t t = 0; t < nt; ++t) {
    const Triangle& g = jaw.triangles[t];
    patch += in_patch(f.cls[t]) ? 1u : 0u;
    for (int k = 0; k < 3; ++k) {
      if ((f.walls[t] & (1u << k)) == 0) continue;
      ++st->walls;
      for (int c = 0; c < 2; ++c) {
        const uint32_t v = used[g.v[(k + c) % 3]];
        if (top[v] == kUnset) top[v] = n + tops++;
      }
    }
  }
  for (size_t v = 0; v < nv; ++v) st->pinched_vertices += f.wall_degree[v] > 2 ? 1u : 0u;
  st->top_vertices = tops;
  const uint64_t out_triangles = patch + 2 * st->walls;
  if (out_triangles > 0xffffffffu || out_triangles > SIZE_MAX) {
    return make_error(StatusCode::kLimitExceeded, "exact sweep: ", out_triangles,
                      " triangles out (at most 2^32 - 1)");
  }
  result->bind(&arena);
  if (!result->triangles.reserve(static_cast<size_t>(out_triangles)) ||
      !result->vertices.resize(static_cast<size_t>(n) + tops)) {
    return arena.exhausted_status();
  }
  for (size_t t = 0; t < nt; ++t) {
    const Triangle& g = jaw.triangles[t];
    if (!in_patch(f.cls[t])) continue;
    (void)result->triangles.push_back(Triangle{{used[g.v[0]], used[g.v[1]], used[g.v[2]]}});
  }
  for (size_t t = 0; t < nt; ++t) {
    const Triangle& g = jaw.triangles[t];
    for (int k = 0; k < 3; ++k) {
      if ((f.walls[t] & (1u << k)) == 0) continue;
      const uint32_t a = used[g.v[k]], b = used[g.v[(k + 1) % 3]];
      // The wall shares the edge a -> b the other way: (b, a, a'), (b, a', b').
      (void)result->triangles.push_back(Triangle{{b, a, top[a]}});
      (void)result->triangles.push_back(Triangle{{b, top[a], top[b]}});
    }
  }
  for (size_t v = 0; v < nv; ++v) {
    const uint32_t rv = used[v];
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
  // Per triangle its part, three star entries, a wall byte, a ring stamp and a place in a
  // round's list of joined triangles (22 bytes); per
  // vertex a mark, a state, a star offset and its fill, two wall ends, a degree, a fold entry
  // and a top id (30); the output at most every triangle with three walls (7 triangles, 84
  // bytes) and every vertex with a top (48); the arena's alignment of each array.
  return triangle_count * (22 + 84) + vertex_count * (30 + 48) + 4096;
}

Status sweep_exact_mesh(const Context& ctx, const Mesh& jaw, const Vec3& direction,
                        const Aabb& region, Mesh* out, ExactSweepStats* stats,
                        const ExactPocketTest* pockets) {
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
  uint8_t* state = arena.allocate_array<uint8_t>(nv + 1);
  if (cls == nullptr || used == nullptr || state == nullptr) return arena.exhausted_status();
  std::memset(state, 0, nv + 1);
  SPLINTCORE_RETURN_IF_ERROR(classify_triangles(jaw, d, region, cls, used, st));
  Surface f;
  f.jaw = &jaw;
  f.cls = cls;
  SPLINTCORE_RETURN_IF_ERROR(build_stars(arena, jaw, &f));
  uint32_t* fold_list = arena.allocate_array<uint32_t>(nv + 1);
  uint32_t* joined = arena.allocate_array<uint32_t>(nt + 1);
  if (fold_list == nullptr || joined == nullptr) return arena.exhausted_status();
  find_walls(&f);
  for (int round = 0; round < kMaxRounds; ++round) {
    uint32_t joined_count = 0;
    const uint32_t folds =
        absorb_folds(f, d, region, used, state, fold_list, joined, &joined_count);
    // Folds with no back triangle left around them (every one taken in already) are the same
    // in the next round: what they leave crossing is the Boolean's to refuse, as after the
    // last round.
    if (folds == 0 || joined_count == 0) break;
    update_walls(&f, joined, joined_count);
    st->fold_vertices += folds;
    ++st->fold_rounds;
  }
  for (size_t t = 0; t < nt; ++t) st->absorbed_triangles += cls[t] == kAbsorbed ? 1u : 0u;
  uint32_t deep = kUnset;
  SPLINTCORE_RETURN_IF_ERROR(deep_pocket(f, d, region, pockets, st, &deep));
  if (deep != kUnset) {
    const auto um = [](double x) { return std::floor(x * 1000 + 0.5) / 1000; };
    const Vec3& p = jaw.vertices[jaw.triangles[deep].v[0]];
    return make_error(StatusCode::kUnsupported, "exact sweep: the fold taken in at jaw triangle ",
                      deep, " near (", um(p.x), ", ", um(p.y), ", ", um(p.z),
                      ") would leave more than ", kFoldPocket,
                      " mm of undercut unswept (an overhang along the direction)")
        .at_index(deep);
  }
  Mesh result;
  SPLINTCORE_RETURN_IF_ERROR(emit_surface(arena, f, used, d, region, &result, st));
  move_mesh_down(arena, scope.start(), result, out);
  scope.commit();
  return Status::ok();
}

}  // namespace splintcore
