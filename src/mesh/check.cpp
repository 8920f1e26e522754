// Topology checks and measures of an indexed mesh.
//
// Edges, in linear time: every triangle side goes into the bucket of its smaller vertex (a
// counting sort), and each bucket is tallied per larger vertex, so the uses of an undirected
// edge are counted without sorting keys. One use is a boundary edge, three or more a
// non-manifold edge, two uses in the same direction an orientation conflict. Shells are the
// components of triangles joined through edges (union-find); per shell, Euler's V - E + F =
// 2 - 2g gives the genus of a closed orientable surface. Duplicate triangles share the edge of
// their two smallest ids. Degeneracy is decided exactly (collinear3d).
#include <cmath>

#include "core/union_find.h"
#include "geometry/lanes2.h"
#include "geometry/orient2d_stage_a.h"
#include "splintcore/mesh.h"

namespace splintcore {

namespace {

// Marks an edge whose uses (three or more) are being collected for the duplicate search; the
// tallies hold forward uses in the low 32 bits and backward uses in the high 32 bits.
constexpr uint64_t kCollecting = ~uint64_t{0};

// The smaller of a and b by a mask, not a branch (compilers branch on a ?: that picks an array
// index, and which end of an edge is smaller is a coin toss to the branch predictor).
inline uint32_t min2(uint32_t a, uint32_t b) {
  return b ^ ((a ^ b) & (0u - static_cast<uint32_t>(a < b)));
}

inline uint32_t min3(uint32_t a, uint32_t b, uint32_t c) {
  const uint32_t m = a < b ? a : b;
  return m < c ? m : c;
}
inline uint32_t max3(uint32_t a, uint32_t b, uint32_t c) {
  const uint32_t m = a > b ? a : b;
  return m > c ? m : c;
}
inline uint32_t mid3(uint32_t a, uint32_t b, uint32_t c) {
  return a ^ b ^ c ^ min3(a, b, c) ^ max3(a, b, c);
}

// The per-phase arrays of check_mesh, in allocation order (check_mesh_bound adds them up).
struct EdgeArrays {
  uint32_t* start = nullptr;  // V + 1: half-edges bucketed by their smaller vertex
  uint32_t* half = nullptr;   // 3 T: the uses (t << 2 | k: side k of triangle t), by bucket
  uint64_t* tally = nullptr;  // V: per larger vertex, its uses in the current bucket
  uint32_t* last = nullptr;   // V: per larger vertex, the last triangle using it so far
};

}  // namespace

uint64_t check_mesh_bound(uint64_t vertex_count, uint64_t triangle_count) {
  // Kept through the check: the referenced flags, the union-find of shells, per triangle the
  // sides that first use their edge. Then the largest of three phases, each returned before the
  // next: the edge pass (buckets, half-edges, tallies, last users; and, taken at their first
  // need, the union-find of the boundary edges' vertices (the loops) and the triangles of edges
  // with 3+ uses), the duplicate search (those triangles, moved down, with keys and scratch),
  // the shell counts (a shell number per root triangle; a vertex stamp; counts per shell, one
  // shell per triangle at most; the (vertex, shell) pairs of vertices in several shells, with
  // their sort scratch).
  const uint64_t v = vertex_count, t = triangle_count;
  const uint64_t kept = arena_array_bound<uint8_t>(v) + arena_array_bound<uint32_t>(t) +
                        arena_array_bound<uint8_t>(t);
  const uint64_t edges = arena_array_bound<uint32_t>(v + 1) + arena_array_bound<uint32_t>(3 * t) +
                         arena_array_bound<uint64_t>(v) + arena_array_bound<uint32_t>(v) +
                         arena_array_bound<uint32_t>(v) + arena_array_bound<uint32_t>(t);
  const uint64_t duplicates = arena_array_bound<uint32_t>(t) + 3 * arena_array_bound<KeyIndex>(t);
  const uint64_t shells = arena_array_bound<uint32_t>(t) + arena_array_bound<uint32_t>(v) +
                          arena_array_bound<uint32_t>(3 * t) +
                          2 * arena_array_bound<uint64_t>(3 * t);
  const uint64_t phase = edges > shells ? edges : shells;
  return kept + (phase > duplicates ? phase : duplicates);
}

namespace {

// Indices in range (before anything reads a corner) and the referenced vertices (bit 1 of
// `referenced`).
Status check_indices(const Mesh& mesh, uint8_t* referenced, MeshReport* r) {
  const uint64_t nv = mesh.vertices.size();
  const Triangle* tris = mesh.triangles.data();
  if (nv > 0) std::memset(referenced, 0, static_cast<size_t>(nv));
  for (uint32_t t = 0; t < r->triangle_count; ++t) {
    const uint32_t* v = tris[t].v;
    if (v[0] >= nv || v[1] >= nv || v[2] >= nv) {
      const uint32_t bad = v[0] >= nv ? v[0] : (v[1] >= nv ? v[1] : v[2]);  // the first
      return make_error(StatusCode::kInvalidMesh, "triangle ", t, " refers to vertex ", bad,
                        " but the mesh has ", nv, " vertices")
          .at_index(t);
    }
    referenced[v[0]] = 1;
    referenced[v[1]] = 1;
    referenced[v[2]] = 1;
  }
  uint64_t referenced_count = 0;
  for (uint64_t i = 0; i < nv; ++i) referenced_count += referenced[i];
  r->unreferenced_vertices = nv - referenced_count;
  return Status::ok();
}

// Degenerate triangles (repeated ids or exactly flat), the area and the volume, with
// mesh_area()'s and mesh_volume()'s arithmetic in their order (the same bits), r->bounds being
// set. Writes only those fields of *r: it runs beside the edge pass (check_topology).
// Two triangles at a time, one per lane (the last one alone in both when the count is odd),
// summed one after the other in triangle order. Flat: the z component of the area's cross
// product, (p1 - p0) x (p2 - p0), is orient2d(p1, p2, p0) in x-y as its first stage computes
// it (orient2d_stage_a.h; a rotation of p0, p1, p2, so the same orientation): when its rounded
// value is beyond that stage's error bound, the triangle is certainly not flat; otherwise
// collinear3d decides exactly. (With the two products of opposite signs, or one of them zero,
// the value is beyond the bound exactly when it is nonzero: the stage's own shortcuts.)
void check_geometry(const Mesh& mesh, MeshReport* r) {
  const Triangle* tris = mesh.triangles.data();
  const Vec3* verts = mesh.vertices.data();
  const Vec3 c = r->bounds.center();
  const uint32_t n = static_cast<uint32_t>(r->triangle_count);
  const Lanes2 cx = {c.x, c.x}, cy = {c.y, c.y}, cz = {c.z, c.z}, zero = {0.0, 0.0};
  const Lanes2 bound = {detail::kCcwErrBoundA, detail::kCcwErrBoundA};
  double area = 0.0, volume = 0.0;
  for (uint32_t t = 0; t < n; t += 2) {
    const uint32_t u = t + 1 < n ? t + 1 : t;
    const uint32_t* v = tris[t].v;
    const uint32_t* w = tris[u].v;
    const Vec3 &a0 = verts[v[0]], &a1 = verts[v[1]], &a2 = verts[v[2]];
    const Vec3 &b0 = verts[w[0]], &b1 = verts[w[1]], &b2 = verts[w[2]];
    const Lanes2 x0 = {a0.x, b0.x}, y0 = {a0.y, b0.y}, z0 = {a0.z, b0.z};
    const Lanes2 x1 = {a1.x, b1.x}, y1 = {a1.y, b1.y}, z1 = {a1.z, b1.z};
    const Lanes2 x2 = {a2.x, b2.x}, y2 = {a2.y, b2.y}, z2 = {a2.z, b2.z};
    // Area: 0.5 * length(cross(p1 - p0, p2 - p0)).
    const Lanes2 ex = x1 - x0, ey = y1 - y0, ez = z1 - z0;
    const Lanes2 fx = x2 - x0, fy = y2 - y0, fz = z2 - z0;
    const Lanes2 kx = ey * fz - ez * fy, ky = ez * fx - ex * fz;
    const Lanes2 left = ex * fy, right = ey * fx;
    const Lanes2 kz = left - right;
    const Lanes2 len2 = (kx * kx + ky * ky) + kz * kz;
    // Volume: dot(p0 - c, cross(p1 - c, p2 - c)).
    const Lanes2 qx0 = x0 - cx, qy0 = y0 - cy, qz0 = z0 - cz;
    const Lanes2 qx1 = x1 - cx, qy1 = y1 - cy, qz1 = z1 - cz;
    const Lanes2 qx2 = x2 - cx, qy2 = y2 - cy, qz2 = z2 - cz;
    const Lanes2 mx = qy1 * qz2 - qz1 * qy2, my = qz1 * qx2 - qx1 * qz2, mz = qx1 * qy2 - qy1 * qx2;
    const Lanes2 six = (qx0 * mx + qy0 * my) + qz0 * mz;
    // Flat: |kz| beyond the bound on |left| + |right| (negation and comparison are exact).
    const Lanes2 abs_kz = kz < zero ? -kz : kz;
    const Lanes2 sum = (left < zero ? -left : left) + (right < zero ? -right : right);
    const Lanes2 err = bound * sum;
    const bool sure[2] = {abs_kz[0] > err[0], abs_kz[1] > err[1]};
    const Vec3* p[2][3] = {{&a0, &a1, &a2}, {&b0, &b1, &b2}};
    const uint32_t* ids[2] = {v, w};
    for (uint32_t lane = 0; lane < (u != t ? 2u : 1u); ++lane) {
      const uint32_t* id = ids[lane];
      const bool degenerate = id[0] == id[1] || id[1] == id[2] || id[2] == id[0] ||
                              (!sure[lane] && collinear3d(*p[lane][0], *p[lane][1], *p[lane][2]));
      if (degenerate) {
        if (r->degenerate_triangles == 0) r->first_degenerate_triangle = t + lane;
        ++r->degenerate_triangles;
      }
      area += 0.5 * std::sqrt(len2[lane]);
      volume += six[lane];
    }
  }
  r->area = area;
  r->volume = volume / 6.0;
}

// The edge pass, linear in the triangles: every side goes into the bucket of its smaller
// vertex (a counting sort, so each bucket lists its uses in triangle order); a bucket is
// tallied per larger vertex, then read in order, the first use of each edge reading (and
// clearing) its tally. One use is a boundary edge, three or more non-manifold, two in the same
// direction an orientation conflict. Triangles sharing an edge are united into shells; the
// side that first uses an edge is marked in `first_use` (the shells' edge counts). Duplicate
// triangles share the edge of their two smallest ids: an edge with two uses compares them
// directly, one with more collects its candidates into `collected` (sorted later).
// For the first offender of each kind the edge with the smallest triangle is kept (then the
// smallest key): the order a sort of the keys would give.
struct EdgePass {
  const Triangle* tris;
  uint32_t tri_count;
  uint32_t vertex_count;
  EdgeArrays a;
  UnionFind* shells;
  uint8_t* first_use;
  MeshReport* r;
  Arena* arena = nullptr;         // for what only some meshes need: border, collected
  uint32_t* collected = nullptr;  // T, taken at the first candidate
  uint32_t collected_count = 0;
  UnionFind* border = nullptr;   // per vertex: the components of the boundary edges (taken at
                                 // the first one)
  uint8_t* on_border = nullptr;  // per vertex: bit 1 set when a boundary edge ends there
  bool exhausted = false;        // the arena could not give border or collected

  // Triangle t into `collected` (taken from the arena the first time).
  void collect(uint32_t t) {
    if (collected == nullptr) {
      collected = arena->allocate_array<uint32_t>(tri_count);
      if (collected == nullptr) exhausted = true;
    }
    if (collected != nullptr) collected[collected_count++] = t;
  }

  // A use's two ends (side k of triangle t runs from v[k] to v[k + 1 mod 3]).
  uint32_t start_of(uint32_t use) const { return tris[use >> 2].v[use & 3u]; }
  uint32_t end_of(uint32_t use) const {
    constexpr uint8_t kNext[4] = {1, 2, 0, 0};
    return tris[use >> 2].v[kNext[use & 3u]];
  }

  void bucket() {
    uint32_t* start = a.start;
    std::memset(start, 0, (size_t{vertex_count} + 1) * sizeof(uint32_t));
    for (uint32_t t = 0; t < tri_count; ++t) {
      const uint32_t* v = tris[t].v;
      ++start[min2(v[0], v[1]) + 1];
      ++start[min2(v[1], v[2]) + 1];
      ++start[min2(v[2], v[0]) + 1];
    }
    for (uint32_t i = 0; i < vertex_count; ++i) start[i + 1] += start[i];
    // start[lo] is now where bucket lo begins; filling advances it to where it ends.
    for (uint32_t t = 0; t < tri_count; ++t) {
      const uint32_t v0 = tris[t].v[0], v1 = tris[t].v[1], v2 = tris[t].v[2];
      a.half[start[min2(v0, v1)]++] = t << 2;
      a.half[start[min2(v1, v2)]++] = t << 2 | 1u;
      a.half[start[min2(v2, v0)]++] = t << 2 | 2u;
    }
  }

  static void note(EdgeRef* ref, uint64_t count, uint32_t lo, uint32_t hi, uint32_t tri) {
    const bool better =
        count == 0 || tri < ref->triangle ||
        (tri == ref->triangle && (uint64_t{lo} << 32 | hi) < (uint64_t{ref->v0} << 32 | ref->v1));
    if (better) *ref = EdgeRef{lo, hi, tri};
  }

  // True when (lo, hi) are triangle t's two smallest ids and side k is the first of its sides
  // on that edge (so a triangle is a candidate once, on one edge).
  bool candidate(uint32_t t, uint32_t k, uint32_t lo, uint32_t hi) const {
    const uint32_t* v = tris[t].v;
    if (third(v, lo, hi) < hi) return false;
    for (uint32_t j = 0; j < k; ++j) {
      const uint32_t p = v[j], q = v[j + 1];
      if ((p < q ? p : q) == lo && (p < q ? q : p) == hi) return false;
    }
    return true;
  }

  // The id of triangle v besides its side (lo, hi) (ids as a multiset: (a, a, b) on side (a, b)
  // leaves a). (lo, hi) are its two smallest exactly when this is >= hi.
  static uint32_t third(const uint32_t* v, uint32_t lo, uint32_t hi) {
    return v[0] ^ v[1] ^ v[2] ^ lo ^ hi;
  }

  // Two uses of one edge: a duplicate pair when both triangles have it as their two smallest
  // ids and share the third.
  void pair_duplicate(uint32_t t1, uint32_t t2, uint32_t lo, uint32_t hi) {
    if (t1 == t2) return;
    const uint32_t x = third(tris[t1].v, lo, hi);
    if (x != third(tris[t2].v, lo, hi) || x < hi) return;
    const uint32_t later = t1 > t2 ? t1 : t2;
    if (r->duplicate_triangles == 0 || later < r->first_duplicate_triangle) {
      r->first_duplicate_triangle = later;
    }
    ++r->duplicate_triangles;
  }

  void classify(uint32_t lo, uint32_t hi, uint32_t use, uint64_t count) {
    const uint32_t t = use >> 2;
    const uint64_t forward = count & 0xffffffffu, uses = forward + (count >> 32);
    first_use[t] = static_cast<uint8_t>(first_use[t] | (1u << (use & 3u)));
    ++r->edge_count;
    if (uses == 1) {
      note(&r->first_boundary_edge, r->boundary_edges, lo, hi, t);
      if (r->boundary_edges == 0 && !border->init(*arena, vertex_count)) exhausted = true;
      ++r->boundary_edges;
      if (!exhausted) border->unite(lo, hi);  // (else the check fails anyway)
      on_border[lo] |= 2u;
      on_border[hi] |= 2u;
    } else if (uses > 2) {
      note(&r->first_nonmanifold_edge, r->nonmanifold_edges, lo, hi, t);
      ++r->nonmanifold_edges;
    } else {
      if (forward != 1) {
        note(&r->first_orientation_conflict, r->orientation_conflicts, lo, hi, t);
        ++r->orientation_conflicts;
      }
      pair_duplicate(t, a.last[hi], lo, hi);
    }
  }

  // One bucket; returns how many of its edges have one use each way (the common edge, handled
  // here; classify() counts the others). The members it uses are copied into locals first: a
  // store to first_use (bytes) could alias any member, which would then be read again after it.
  uint64_t run_bucket(uint32_t lo, uint32_t begin, uint32_t end) {
    const Triangle* const tr = tris;
    const uint32_t* const half = a.half;
    uint64_t* const tallies = a.tally;
    uint32_t* const lasts = a.last;
    uint8_t* const first = first_use;
    for (uint32_t i = begin; i < end; ++i) {
      const uint32_t use = half[i];
      const uint32_t t = use >> 2;
      const uint32_t from = start_of(use), hi = from ^ end_of(use) ^ lo;  // lo is one end
      // Forward: the side runs from the smaller id (always, for a side lo -> lo).
      const uint64_t tally = tallies[hi] + (from == lo ? 1u : (uint64_t{1} << 32));
      tallies[hi] = tally;
      if (tally != 1u && tally != (uint64_t{1} << 32)) shells->unite(lasts[hi], t);
      lasts[hi] = t;
    }
    constexpr uint64_t kOneEach = (uint64_t{1} << 32) | 1u;
    uint64_t paired = 0;
    bool collecting = false;
    for (uint32_t i = begin; i < end; ++i) {
      const uint32_t use = half[i];
      const uint32_t hi = start_of(use) ^ end_of(use) ^ lo;
      const uint64_t count = tallies[hi];
      if (count == 0) continue;  // a later use of an edge already read
      if (count == kOneEach) {   // classify's last case, inline
        const uint32_t t = use >> 2, other = lasts[hi];
        first[t] = static_cast<uint8_t>(first[t] | (1u << (use & 3u)));
        ++paired;
        if (third(tr[t].v, lo, hi) == third(tr[other].v, lo, hi)) pair_duplicate(t, other, lo, hi);
        tallies[hi] = 0;
        continue;
      }
      if (count != kCollecting) {
        classify(lo, hi, use, count);
        const uint64_t uses = (count & 0xffffffffu) + (count >> 32);
        if (uses <= 2) {
          tallies[hi] = 0;
          continue;
        }
        tallies[hi] = kCollecting;
        collecting = true;
      }
      if (candidate(use >> 2, use & 3u, lo, hi)) collect(use >> 2);
    }
    if (collecting) {
      for (uint32_t i = begin; i < end; ++i) {
        tallies[start_of(half[i]) ^ end_of(half[i]) ^ lo] = 0;
      }
    }
    return paired;
  }

  void run() {
    bucket();
    std::memset(a.tally, 0, size_t{vertex_count} * sizeof(uint64_t));
    std::memset(first_use, 0, tri_count);
    uint64_t paired = 0;
    uint32_t begin = 0;
    for (uint32_t lo = 0; lo < vertex_count; ++lo) {
      const uint32_t end = a.start[lo];  // the fill left the bucket's end here
      if (end > begin) paired += run_bucket(lo, begin, end);
      begin = end;
    }
    r->edge_count += paired;
  }
};

// Shells and Euler characteristic: distinct (shell, vertex) pairs, edges and faces counted per
// shell (shells numbered in order of their root triangle: shell_of[root], written and read
// only at roots; in counts[3 shell + 0/1/2]); the genus when every shell is a closed
// orientable surface. A vertex is stamped with the shell that first uses it; a vertex used by
// other shells too (rare: shells touching at a vertex) gives (vertex, shell) pairs, sorted to
// count each once.
// count_shells' counts with several shells: per triangle, its shell's faces, edges and
// first-seen vertices; then the (vertex, shell) pairs of vertices in several shells.
Status count_per_shell(Arena& arena, const Mesh& mesh, const uint8_t* first_use, UnionFind* shells,
                       const uint32_t* shell_of, uint32_t* stamp, uint32_t* counts) {
  const Triangle* tris = mesh.triangles.data();
  const uint32_t tri_count = static_cast<uint32_t>(mesh.triangles.size());
  const uint32_t nv = static_cast<uint32_t>(mesh.vertices.size());
  if (nv > 0) std::memset(stamp, 0xff, size_t{nv} * sizeof(uint32_t));
  uint64_t others = 0;
  for (uint32_t t = 0; t < tri_count; ++t) {
    const uint32_t root = shell_of[shells->find(t)];
    uint32_t* c = counts + 3 * size_t{root};
    ++c[2];
    c[1] += (first_use[t] & 1u) + ((first_use[t] >> 1) & 1u) + (first_use[t] >> 2);  // 3 bits
    for (uint32_t v : tris[t].v) {
      if (stamp[v] == UINT32_MAX) {
        stamp[v] = root;
        ++c[0];
      } else if (stamp[v] != root) {
        ++others;
      }
    }
  }
  if (others == 0) return Status::ok();
  uint64_t* pairs = arena.allocate_array<uint64_t>(static_cast<size_t>(others));
  uint64_t* scratch = arena.allocate_array<uint64_t>(static_cast<size_t>(others));
  if (pairs == nullptr || scratch == nullptr) return arena.exhausted_status();
  size_t n = 0;
  for (uint32_t t = 0; t < tri_count; ++t) {
    const uint32_t root = shell_of[shells->find(t)];
    for (uint32_t v : tris[t].v) {
      if (stamp[v] != root) pairs[n++] = (uint64_t{v} << 32) | root;
    }
  }
  radix_sort_bits(Span<uint64_t>(pairs, n), Span<uint64_t>(scratch, n), 0, 64);
  for (size_t i = 0; i < n; ++i) {
    if (i == 0 || pairs[i] != pairs[i - 1]) ++counts[3 * (pairs[i] & 0xffffffffu)];
  }
  return Status::ok();
}

Status count_shells(Arena& arena, const Mesh& mesh, const uint8_t* first_use, UnionFind* shells,
                    MeshReport* r) {
  ArenaScope scope(arena);
  const uint32_t tri_count = static_cast<uint32_t>(r->triangle_count);
  const uint32_t nv = static_cast<uint32_t>(r->vertex_count);
  uint32_t* shell_of = arena.allocate_array<uint32_t>(tri_count);
  uint32_t* stamp = arena.allocate_array<uint32_t>(nv);
  if ((shell_of == nullptr && tri_count > 0) || (stamp == nullptr && nv > 0)) {
    return arena.exhausted_status();
  }
  uint32_t shell_count = 0;
  for (uint32_t t = 0; t < tri_count; ++t) {
    if (shells->is_root(t)) shell_of[t] = shell_count++;
  }
  uint32_t* counts = arena.allocate_array<uint32_t>(size_t{3} * shell_count);
  if (counts == nullptr && shell_count > 0) return arena.exhausted_status();
  if (shell_count == 1) {
    // One shell (the usual case): its counts are the mesh's, every referenced vertex, every
    // edge and every triangle, with no pass over the triangles.
    counts[0] = static_cast<uint32_t>(r->vertex_count - r->unreferenced_vertices);
    counts[1] = static_cast<uint32_t>(r->edge_count);
    counts[2] = tri_count;
  } else if (shell_count > 1) {
    std::memset(counts, 0, size_t{3} * shell_count * sizeof(uint32_t));
    SPLINTCORE_RETURN_IF_ERROR(
        count_per_shell(arena, mesh, first_use, shells, shell_of, stamp, counts));
  }
  bool genus_defined = r->boundary_edges == 0 && r->nonmanifold_edges == 0 &&
                       r->orientation_conflicts == 0 && tri_count > 0;
  int64_t genus = 0, total_v = 0;
  for (uint32_t i = 0; i < shell_count; ++i) {
    ++r->shells;
    const int64_t v = counts[3 * size_t{i}], e = counts[3 * size_t{i} + 1];
    const int64_t chi = v - e + counts[3 * size_t{i} + 2];
    total_v += v;
    if (chi > 2 || (2 - chi) % 2 != 0) genus_defined = false;
    genus += (2 - chi) / 2;
  }
  r->euler_characteristic = total_v - static_cast<int64_t>(r->edge_count) + int64_t{tri_count};
  r->genus = genus_defined ? genus : -1;
  return Status::ok();
}

// Duplicates among the triangles collected from edges with three or more uses: sorted by the
// largest id, then (stable) by the smallest two, so equal sets end up adjacent in the order
// they were collected (triangle order within an edge).
Status count_collected_duplicates(Arena& arena, const Mesh& mesh, const uint32_t* collected,
                                  uint32_t n, MeshReport* r) {
  if (n < 2) return Status::ok();
  ArenaScope scope(arena);
  const Triangle* tris = mesh.triangles.data();
  KeyIndex* items = arena.allocate_array<KeyIndex>(n);
  KeyIndex* ab = arena.allocate_array<KeyIndex>(n);
  KeyIndex* scratch = arena.allocate_array<KeyIndex>(n);
  if (items == nullptr || ab == nullptr || scratch == nullptr) return arena.exhausted_status();
  for (uint32_t i = 0; i < n; ++i) {
    const uint32_t* v = tris[collected[i]].v;
    items[i] = KeyIndex{max3(v[0], v[1], v[2]), i, 0};
    ab[i] = KeyIndex{(uint64_t{min3(v[0], v[1], v[2])} << 32) | mid3(v[0], v[1], v[2]), i, 0};
  }
  radix_sort(Span<KeyIndex>(items, n), Span<KeyIndex>(scratch, n));
  for (uint32_t i = 0; i < n; ++i) items[i].key = ab[items[i].index].key;  // keeps the c order
  radix_sort(Span<KeyIndex>(items, n), Span<KeyIndex>(scratch, n));
  auto largest = [&](uint32_t i) {
    const uint32_t* v = tris[collected[i]].v;
    return max3(v[0], v[1], v[2]);
  };
  for (uint32_t u = 1; u < n; ++u) {
    if (items[u].key != items[u - 1].key ||
        largest(items[u].index) != largest(items[u - 1].index)) {
      continue;
    }
    const uint32_t x = collected[items[u].index], y = collected[items[u - 1].index];
    const uint32_t later = x > y ? x : y;
    if (r->duplicate_triangles == 0 || later < r->first_duplicate_triangle) {
      r->first_duplicate_triangle = later;
    }
    ++r->duplicate_triangles;
  }
  return Status::ok();
}

// The boundary loops: the components of the graph of boundary edges, one per root vertex on
// the border (two holes that touch at a vertex count as one loop).
void count_boundary_loops(UnionFind* border, const uint8_t* on_border, MeshReport* r) {
  const uint32_t nv = static_cast<uint32_t>(r->vertex_count);
  for (uint32_t v = 0; v < nv && r->boundary_edges > 0; ++v) {
    if ((on_border[v] & 2u) != 0 && border->is_root(v)) ++r->boundary_loops;
  }
}

Status check_topology(const Context& ctx, const Mesh& mesh, uint8_t* on_border, MeshReport* r) {
  Arena& arena = *ctx.arena;
  const uint32_t tri_count = static_cast<uint32_t>(r->triangle_count);
  const uint32_t nv = static_cast<uint32_t>(r->vertex_count);
  // The allocations check_mesh_bound() counts, in its order.
  UnionFind shells;
  if (!shells.init(arena, tri_count)) return arena.exhausted_status();
  uint8_t* first_use = arena.allocate_array<uint8_t>(tri_count);
  if (first_use == nullptr && tri_count > 0) return arena.exhausted_status();
  uint32_t collected_count = 0;
  const uint32_t* collected = nullptr;  // where the edge pass left them
  {
    ArenaScope scope(arena);
    UnionFind border;  // taken at the first boundary edge
    EdgePass pass{mesh.triangles.data(), tri_count, nv, EdgeArrays{}, &shells, first_use, r};
    pass.arena = &arena;
    pass.border = &border;
    pass.on_border = on_border;
    pass.a.start = arena.allocate_array<uint32_t>(size_t{nv} + 1);
    pass.a.half = arena.allocate_array<uint32_t>(size_t{3} * tri_count);
    pass.a.tally = arena.allocate_array<uint64_t>(nv);
    pass.a.last = arena.allocate_array<uint32_t>(nv);
    if (pass.a.start == nullptr || ((pass.a.half == nullptr) && tri_count > 0) ||
        ((pass.a.tally == nullptr || pass.a.last == nullptr) && nv > 0)) {
      return arena.exhausted_status();
    }
    // The edge pass and the geometry (independent: they write different fields of *r) side
    // by side when there is an executor; in this order without one.
    auto task = [&](uint32_t i) {
      if (i == 0) {
        pass.run();
      } else {
        check_geometry(mesh, r);
      }
    };
    parallel_for_each(ctx.executor, 2, task);
    if (pass.exhausted) return arena.exhausted_status();
    count_boundary_loops(&border, on_border, r);
    collected_count = pass.collected_count;
    collected = pass.collected;
  }
  if (collected_count > 0) {
    // Moved down over the edge pass's arrays (given back), as move_mesh_down moves a mesh,
    // for the duplicate search.
    ArenaScope scope(arena);
    uint32_t* moved = arena.allocate_array<uint32_t>(collected_count);
    if (moved == nullptr) return arena.exhausted_status();
    std::memmove(moved, collected, size_t{collected_count} * sizeof(uint32_t));
    SPLINTCORE_RETURN_IF_ERROR(count_collected_duplicates(arena, mesh, moved, collected_count, r));
  }
  SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "check", 2, 4));
  return count_shells(arena, mesh, first_use, &shells, r);
}

}  // namespace

Status check_mesh(const Context& ctx, const Mesh& mesh, MeshReport* report) {
  Arena& arena = *ctx.arena;
  ArenaScope scope(arena);
  *report = MeshReport{};
  MeshReport& r = *report;
  const uint64_t nv = mesh.vertices.size();
  const uint64_t nt = mesh.triangles.size();
  r.vertex_count = nv;
  r.triangle_count = nt;
  // (Below 2^30 triangles: the edge pass keeps a triangle and a side as t << 2 | k in 32 bits.)
  if (nt >= (uint64_t{1} << 30) || nv > UINT32_MAX) {
    return make_error(StatusCode::kLimitExceeded, "mesh too large to check: ", nt, " triangles, ",
                      nv, " vertices (32-bit ids)");
  }
  uint8_t* referenced = arena.allocate_array<uint8_t>(static_cast<size_t>(nv));
  if (referenced == nullptr && nv > 0) return arena.exhausted_status();
  r.bounds = mesh_bounds(mesh);
  SPLINTCORE_RETURN_IF_ERROR(check_indices(mesh, referenced, &r));
  SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "check", 1, 4));
  SPLINTCORE_RETURN_IF_ERROR(check_topology(ctx, mesh, referenced, &r));
  SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "check", 3, 4));
  SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "check", 4, 4));
  return Status::ok();
}

namespace {
// "s" after a count other than 1 (the messages' nouns).
const char* plural(uint64_t count) { return count == 1 ? "" : "s"; }
}  // namespace

Status require_valid_solid(const MeshReport& r) {
  if (r.triangle_count == 0) {
    return Status::error(StatusCode::kInvalidMesh, "mesh is empty: no triangles");
  }
  if (r.boundary_edges > 0) {
    return make_error(StatusCode::kInvalidMesh, "mesh is not closed: ", r.boundary_edges,
                      " boundary edge", plural(r.boundary_edges), ", first between vertices ",
                      r.first_boundary_edge.v0, " and ", r.first_boundary_edge.v1, " (triangle ",
                      r.first_boundary_edge.triangle, ")")
        .at_index(r.first_boundary_edge.triangle);
  }
  if (r.nonmanifold_edges > 0) {
    return make_error(StatusCode::kInvalidMesh, "mesh is not edge-manifold: ", r.nonmanifold_edges,
                      " edge", plural(r.nonmanifold_edges),
                      " shared by 3 or more triangles, first between "
                      "vertices ",
                      r.first_nonmanifold_edge.v0, " and ", r.first_nonmanifold_edge.v1,
                      " (triangle ", r.first_nonmanifold_edge.triangle, ")")
        .at_index(r.first_nonmanifold_edge.triangle);
  }
  if (r.orientation_conflicts > 0) {
    return make_error(StatusCode::kInvalidMesh,
                      "mesh is not consistently oriented: ", r.orientation_conflicts, " edge",
                      plural(r.orientation_conflicts),
                      " used twice in the same direction, first "
                      "between vertices ",
                      r.first_orientation_conflict.v0, " and ", r.first_orientation_conflict.v1,
                      " (triangle ", r.first_orientation_conflict.triangle, ")")
        .at_index(r.first_orientation_conflict.triangle);
  }
  if (r.degenerate_triangles > 0) {
    return make_error(StatusCode::kInvalidMesh, "mesh has ", r.degenerate_triangles,
                      " degenerate (zero-area) triangle", plural(r.degenerate_triangles),
                      ", first is triangle ", r.first_degenerate_triangle)
        .at_index(r.first_degenerate_triangle);
  }
  if (r.duplicate_triangles > 0) {
    return make_error(StatusCode::kInvalidMesh, "mesh has ", r.duplicate_triangles,
                      " duplicate triangle", plural(r.duplicate_triangles), ", first is triangle ",
                      r.first_duplicate_triangle)
        .at_index(r.first_duplicate_triangle);
  }
  if (!(r.volume > 0.0)) {
    return make_error(StatusCode::kInvalidMesh, "mesh is inside out: signed volume ", r.volume,
                      " mm^3 (expected > 0; the triangles' winding is reversed)");
  }
  return Status::ok();
}

uint32_t find_flat_triangle(const Mesh& mesh) {
  const Triangle* tris = mesh.triangles.data();
  const Vec3* v = mesh.vertices.data();
  const uint32_t nt = static_cast<uint32_t>(mesh.triangles.size());
  for (uint32_t t = 0; t < nt; ++t) {
    const Vec3& p0 = v[tris[t].v[0]];
    const Vec3 e1 = v[tris[t].v[1]] - p0, e2 = v[tris[t].v[2]] - p0;
    const double c2 = length_squared(cross(e1, e2));
    if (!(c2 > 1e-24 * length_squared(e1) * length_squared(e2)) &&
        collinear3d(p0, v[tris[t].v[1]], v[tris[t].v[2]])) {
      return t;
    }
  }
  return kNoTriangle;
}

uint64_t check_closed_oriented_bound(uint64_t vertex_count, uint64_t triangle_count) {
  return (vertex_count + 1) * sizeof(uint32_t) + 3 * triangle_count * sizeof(uint64_t) +
         vertex_count * sizeof(uint64_t) + 2 * 64;
}

Status check_closed_oriented(const Context& ctx, const Mesh& mesh, double* volume) {
  Arena& arena = *ctx.arena;
  const uint64_t nv64 = mesh.vertices.size(), nt64 = mesh.triangles.size();
  if (nt64 == 0) return Status::error(StatusCode::kInvalidMesh, "mesh is empty");
  if (nv64 >= (uint64_t{1} << 31) || nt64 >= (uint64_t{1} << 31)) {
    return make_error(StatusCode::kLimitExceeded, "mesh too large to check: ", nt64, " triangles, ",
                      nv64, " vertices");
  }
  const uint32_t nv = static_cast<uint32_t>(nv64), nt = static_cast<uint32_t>(nt64);
  const Triangle* tris = mesh.triangles.data();
  for (uint32_t t = 0; t < nt; ++t) {
    for (uint32_t k : tris[t].v) {
      if (k >= nv) {
        return make_error(StatusCode::kInvalidMesh, "triangle ", t, " refers to vertex ", k,
                          " but the mesh has ", nv, " vertices")
            .at_index(t);
      }
    }
  }
  ArenaScope scope(arena);
  // Half-edges bucketed by their smaller vertex: other end << 33 | forward << 32 | triangle.
  // Per other end, its uses in the current bucket: forward in the low 32 bits, backward in
  // the high (a good edge: exactly 2^32 + 1).
  uint32_t* start = arena.allocate_array<uint32_t>(size_t{nv} + 1);
  uint64_t* half = arena.allocate_array<uint64_t>(size_t{3} * nt);
  uint64_t* tally = arena.allocate_array<uint64_t>(nv);
  if (start == nullptr || half == nullptr || tally == nullptr) return arena.exhausted_status();
  std::memset(start, 0, (size_t{nv} + 1) * sizeof(uint32_t));
  std::memset(tally, 0, size_t{nv} * sizeof(uint64_t));
  for (uint32_t t = 0; t < nt; ++t) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = tris[t].v[k], b = tris[t].v[(k + 1) % 3];
      ++start[(a < b ? a : b) + 1];
    }
  }
  for (uint32_t i = 0; i < nv; ++i) start[i + 1] += start[i];
  for (uint32_t t = 0; t < nt; ++t) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = tris[t].v[k], b = tris[t].v[(k + 1) % 3];
      const uint32_t lo = a < b ? a : b, hi = a < b ? b : a;
      half[start[lo]++] = (uint64_t{hi} << 33) | (uint64_t{a < b ? 1u : 0u} << 32) | t;
    }
  }
  for (uint32_t i = nv; i > 0; --i) start[i] = start[i - 1];
  start[0] = 0;
  // Each bucket is tallied, then read in order: the first use of an edge reads its counts
  // (and clears them), so the first half-edge of the first bad edge is the one reported;
  // linear, however many triangles share a vertex.
  constexpr uint64_t kOneEach = (uint64_t{1} << 32) | 1u;
  for (uint32_t lo = 0; lo < nv; ++lo) {
    for (uint32_t i = start[lo]; i < start[lo + 1]; ++i) {
      tally[half[i] >> 33] += ((half[i] >> 32) & 1u) != 0 ? 1u : (uint64_t{1} << 32);
    }
    for (uint32_t i = start[lo]; i < start[lo + 1]; ++i) {
      const uint32_t hi = static_cast<uint32_t>(half[i] >> 33);
      const uint64_t count = tally[hi];
      if (count == 0) continue;  // a later use of an edge already read (and good)
      tally[hi] = 0;
      const uint64_t forward = count & 0xffffffffu, uses = forward + (count >> 32);
      if (count != kOneEach || lo == hi) {
        const uint32_t t = static_cast<uint32_t>(half[i]);
        const char* what = uses == 1  ? "not closed: a boundary edge"
                           : uses > 2 ? "not edge-manifold: an edge with 3 or more triangles"
                                      : (lo == hi ? "degenerate: a triangle repeats a vertex"
                                                  : "not consistently oriented: an edge used twice "
                                                    "in the same direction");
        return make_error(StatusCode::kInvalidMesh, "mesh is ", what, " between vertices ", lo,
                          " and ", hi, " (triangle ", t, ")")
            .at_index(t);
      }
    }
  }
  const uint32_t flat = find_flat_triangle(mesh);
  if (flat != kNoTriangle) {
    return make_error(StatusCode::kInvalidMesh, "mesh is degenerate: triangle ", flat,
                      " has zero area")
        .at_index(flat);
  }
  const double vol = mesh_volume(mesh);
  if (volume != nullptr) *volume = vol;
  if (!(vol > 0)) {
    return make_error(StatusCode::kInvalidMesh, "mesh is inside out: volume ", vol, " mm^3");
  }
  return Status::ok();
}

}  // namespace splintcore
