// Topology checks and measures of an indexed mesh.
//
// Edges: every triangle side becomes a key (min id, max id); a stable radix sort groups the
// uses of each undirected edge. One use is a boundary edge, three or more a non-manifold edge,
// two uses in the same direction an orientation conflict. Shells are the components of
// triangles joined through edges (union-find); per shell, Euler's V - E + F = 2 - 2g gives the
// genus of a closed orientable surface. Degeneracy is decided exactly (collinear3d).
#include "core/union_find.h"
#include "splintcore/mesh.h"

namespace splintcore {

namespace {
inline uint64_t edge_key(uint32_t a, uint32_t b) {
  return a < b ? (uint64_t{a} << 32) | b : (uint64_t{b} << 32) | a;
}
}  // namespace

uint64_t check_mesh_bound(uint64_t vertex_count, uint64_t triangle_count) {
  // The referenced flags, the edge uses and their sort scratch, the union-find, and the
  // per-shell vertex, edge and face counts: about 124 bytes a triangle.
  const uint64_t uses = 3 * triangle_count;
  return arena_array_bound<uint8_t>(vertex_count) + 2 * arena_array_bound<KeyIndex>(uses) +
         arena_array_bound<uint32_t>(triangle_count) +
         3 * arena_array_bound<int64_t>(triangle_count);
}

namespace {

// Indices in range, referenced vertices, degenerate triangles (repeated ids or exactly flat).
Status check_indices(const Mesh& mesh, uint8_t* referenced, MeshReport* r) {
  const uint64_t nv = mesh.vertices.size();
  const Triangle* tris = mesh.triangles.data();
  const Vec3* verts = mesh.vertices.data();
  if (nv > 0) std::memset(referenced, 0, static_cast<size_t>(nv));
  for (uint32_t t = 0; t < r->triangle_count; ++t) {
    const uint32_t* v = tris[t].v;
    for (int k = 0; k < 3; ++k) {
      if (v[k] >= nv) {
        return make_error(StatusCode::kInvalidMesh, "triangle ", t, " refers to vertex ", v[k],
                          " but the mesh has ", nv, " vertices")
            .at_index(t);
      }
      referenced[v[k]] = 1;
    }
    const bool degenerate = v[0] == v[1] || v[1] == v[2] || v[2] == v[0] ||
                            collinear3d(verts[v[0]], verts[v[1]], verts[v[2]]);
    if (degenerate) {
      if (r->degenerate_triangles == 0) r->first_degenerate_triangle = t;
      ++r->degenerate_triangles;
    }
  }
  uint64_t referenced_count = 0;
  for (uint64_t i = 0; i < nv; ++i) referenced_count += referenced[i];
  r->unreferenced_vertices = nv - referenced_count;
  return Status::ok();
}

// The edges: every side's key sorted so the uses of an edge are adjacent; one use is a
// boundary edge, three or more non-manifold, two in the same direction an orientation
// conflict. Triangles sharing an edge are united into shells. For the first offender of each
// kind the one with the smallest triangle index is kept.
void classify_edges(const Mesh& mesh, KeyIndex* items, KeyIndex* scratch, UnionFind* shells,
                    MeshReport* r) {
  const Triangle* tris = mesh.triangles.data();
  const uint32_t tri_count = static_cast<uint32_t>(r->triangle_count);
  const uint32_t uses = 3 * tri_count;
  for (uint32_t t = 0; t < tri_count; ++t) {
    for (uint32_t k = 0; k < 3; ++k) {
      items[3 * t + k] = KeyIndex{edge_key(tris[t].v[k], tris[t].v[(k + 1) % 3]), 3 * t + k, 0};
    }
  }
  radix_sort(Span<KeyIndex>(items, uses), Span<KeyIndex>(scratch, uses));
  auto note = [&](EdgeRef* ref, uint64_t count, uint32_t key_hi, uint32_t key_lo, uint32_t tri) {
    if (count == 0 || tri < ref->triangle) *ref = EdgeRef{key_hi, key_lo, tri};
  };
  // Directed use of side k of triangle t: v[k] -> v[k+1]. "Forward" when it runs a -> b.
  auto forward = [&](uint32_t use, uint32_t a) { return tris[use / 3].v[use % 3] == a; };
  uint32_t i = 0;
  while (i < uses) {
    uint32_t j = i + 1;
    while (j < uses && items[j].key == items[i].key) ++j;
    const uint32_t count = j - i;
    const uint32_t a = static_cast<uint32_t>(items[i].key >> 32);
    const uint32_t b = static_cast<uint32_t>(items[i].key);
    uint32_t min_tri = UINT32_MAX;
    for (uint32_t u = i; u < j; ++u) {
      const uint32_t t = items[u].index / 3;
      min_tri = t < min_tri ? t : min_tri;
      shells->unite(items[i].index / 3, t);
    }
    ++r->edge_count;
    if (count == 1) {
      note(&r->first_boundary_edge, r->boundary_edges, a, b, min_tri);
      ++r->boundary_edges;
    } else if (count > 2) {
      note(&r->first_nonmanifold_edge, r->nonmanifold_edges, a, b, min_tri);
      ++r->nonmanifold_edges;
    } else if (forward(items[i].index, a) == forward(items[i + 1].index, a)) {
      note(&r->first_orientation_conflict, r->orientation_conflicts, a, b, min_tri);
      ++r->orientation_conflicts;
    }
    i = j;
  }
}

// Shells and Euler characteristic: distinct (shell, vertex) pairs, edges and faces counted per
// shell (indexed by the shell's root triangle, in shell_v/e/f); the genus when every shell is
// a closed orientable surface.
void count_shells(const Mesh& mesh, KeyIndex* items, KeyIndex* scratch, UnionFind* shells,
                  int64_t* shell_v, int64_t* shell_e, int64_t* shell_f, MeshReport* r) {
  const Triangle* tris = mesh.triangles.data();
  const uint32_t tri_count = static_cast<uint32_t>(r->triangle_count);
  const uint32_t uses = 3 * tri_count;
  // Keys: shell root in the high half, vertex in the low half.
  for (uint32_t t = 0; t < tri_count; ++t) {
    const uint64_t root = shells->find(t);
    for (uint32_t k = 0; k < 3; ++k) {
      items[3 * t + k] = KeyIndex{(root << 32) | tris[t].v[k], 0, 0};
    }
  }
  radix_sort(Span<KeyIndex>(items, uses), Span<KeyIndex>(scratch, uses));
  for (uint32_t t = 0; t < tri_count; ++t) shell_v[t] = shell_e[t] = shell_f[t] = 0;
  int64_t total_v = 0;
  for (uint32_t u = 0; u < uses; ++u) {
    if (u == 0 || items[u].key != items[u - 1].key) {
      ++shell_v[items[u].key >> 32];
      ++total_v;
    }
  }
  for (uint32_t t = 0; t < tri_count; ++t) ++shell_f[shells->find(t)];
  // Edges per shell: each distinct edge counted once, at the shell of any triangle using it.
  for (uint32_t t = 0; t < tri_count; ++t) {
    for (uint32_t k = 0; k < 3; ++k) {
      items[3 * t + k] = KeyIndex{edge_key(tris[t].v[k], tris[t].v[(k + 1) % 3]), t, 0};
    }
  }
  radix_sort(Span<KeyIndex>(items, uses), Span<KeyIndex>(scratch, uses));
  for (uint32_t u = 0; u < uses; ++u) {
    if (u == 0 || items[u].key != items[u - 1].key) ++shell_e[shells->find(items[u].index)];
  }
  bool genus_defined = r->boundary_edges == 0 && r->nonmanifold_edges == 0 &&
                       r->orientation_conflicts == 0 && tri_count > 0;
  int64_t genus = 0;
  for (uint32_t t = 0; t < tri_count; ++t) {
    if (shells->find(t) != t) continue;
    ++r->shells;
    const int64_t chi = shell_v[t] - shell_e[t] + shell_f[t];
    if (chi > 2 || (2 - chi) % 2 != 0) genus_defined = false;
    genus += (2 - chi) / 2;
  }
  r->euler_characteristic = total_v - static_cast<int64_t>(r->edge_count) + int64_t{tri_count};
  r->genus = genus_defined ? genus : -1;
}

// Duplicate triangles: the same vertex set. Sorted by the largest id, then (stable) by the
// smallest two, so equal sets end up adjacent in triangle order. `items` and `scratch` hold
// 3 T entries each (the edge pass's).
void count_duplicates(const Mesh& mesh, KeyIndex* items, KeyIndex* scratch, MeshReport* r) {
  const Triangle* tris = mesh.triangles.data();
  const uint32_t tri_count = static_cast<uint32_t>(r->triangle_count);
  for (uint32_t t = 0; t < tri_count; ++t) {
    uint32_t a = tris[t].v[0], b = tris[t].v[1], c = tris[t].v[2];
    if (a > b) {
      uint32_t s = a;
      a = b;
      b = s;
    }
    if (b > c) {
      uint32_t s = b;
      b = c;
      c = s;
    }
    if (a > b) {
      uint32_t s = a;
      a = b;
      b = s;
    }
    items[t] = KeyIndex{c, t, 0};
    scratch[t] = KeyIndex{(uint64_t{a} << 32) | b, t, 0};  // kept aside, looked up by t
  }
  // Move the (a, b) keys next to the c keys' scratch: reuse the second third of items.
  KeyIndex* ab = items + tri_count;
  KeyIndex* sort_scratch = scratch + tri_count;  // 2 * tri_count spare entries remain
  if (tri_count > 0) std::memcpy(ab, scratch, tri_count * sizeof(KeyIndex));
  radix_sort(Span<KeyIndex>(items, tri_count), Span<KeyIndex>(sort_scratch, tri_count));
  for (uint32_t t = 0; t < tri_count; ++t) {
    items[t].key = ab[items[t].index].key;  // re-key by (a, b), keeping the c order
  }
  radix_sort(Span<KeyIndex>(items, tri_count), Span<KeyIndex>(sort_scratch, tri_count));
  // Now equal (a, b) are adjacent and ordered by c within; equal c must also be compared.
  auto max_id = [&](uint32_t t) {
    const uint32_t a = tris[t].v[0], b = tris[t].v[1], c = tris[t].v[2];
    const uint32_t m = a > b ? a : b;
    return m > c ? m : c;
  };
  bool have_dup = false;
  for (uint32_t u = 1; u < tri_count; ++u) {
    if (items[u].key == items[u - 1].key && max_id(items[u].index) == max_id(items[u - 1].index)) {
      const uint32_t later =
          items[u].index > items[u - 1].index ? items[u].index : items[u - 1].index;
      if (!have_dup || later < r->first_duplicate_triangle) r->first_duplicate_triangle = later;
      have_dup = true;
      ++r->duplicate_triangles;
    }
  }
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
  if (nt > (uint64_t{UINT32_MAX} - 1) / 3 || nv > UINT32_MAX) {
    return make_error(StatusCode::kLimitExceeded, "mesh too large to check: ", nt, " triangles, ",
                      nv, " vertices (32-bit ids)");
  }
  const uint32_t tri_count = static_cast<uint32_t>(nt);
  // The allocations check_mesh_bound() counts, in its order.
  uint8_t* referenced = arena.allocate_array<uint8_t>(static_cast<size_t>(nv));
  if (referenced == nullptr && nv > 0) return arena.exhausted_status();
  SPLINTCORE_RETURN_IF_ERROR(check_indices(mesh, referenced, &r));
  SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "check", 1, 4));

  const uint32_t uses = 3 * tri_count;
  KeyIndex* items = arena.allocate_array<KeyIndex>(uses);
  KeyIndex* scratch = arena.allocate_array<KeyIndex>(uses);
  if ((items == nullptr || scratch == nullptr) && tri_count > 0) return arena.exhausted_status();
  UnionFind shells;
  if (!shells.init(arena, tri_count)) return arena.exhausted_status();
  classify_edges(mesh, items, scratch, &shells, &r);
  SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "check", 2, 4));

  int64_t* shell_v = arena.allocate_array<int64_t>(tri_count);
  int64_t* shell_e = arena.allocate_array<int64_t>(tri_count);
  int64_t* shell_f = arena.allocate_array<int64_t>(tri_count);
  if ((shell_v == nullptr || shell_e == nullptr || shell_f == nullptr) && tri_count > 0) {
    return arena.exhausted_status();
  }
  count_shells(mesh, items, scratch, &shells, shell_v, shell_e, shell_f, &r);
  SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "check", 3, 4));

  count_duplicates(mesh, items, scratch, &r);
  r.bounds = mesh_bounds(mesh);
  r.area = mesh_area(mesh);
  r.volume = mesh_volume(mesh);
  SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "check", 4, 4));
  return Status::ok();
}

Status require_valid_solid(const MeshReport& r) {
  if (r.triangle_count == 0) {
    return Status::error(StatusCode::kInvalidMesh, "mesh is empty: no triangles");
  }
  if (r.boundary_edges > 0) {
    return make_error(StatusCode::kInvalidMesh, "mesh is not closed: ", r.boundary_edges,
                      " boundary edges, first between vertices ", r.first_boundary_edge.v0, " and ",
                      r.first_boundary_edge.v1, " (triangle ", r.first_boundary_edge.triangle, ")")
        .at_index(r.first_boundary_edge.triangle);
  }
  if (r.nonmanifold_edges > 0) {
    return make_error(StatusCode::kInvalidMesh, "mesh is not edge-manifold: ", r.nonmanifold_edges,
                      " edges shared by 3 or more triangles, first between "
                      "vertices ",
                      r.first_nonmanifold_edge.v0, " and ", r.first_nonmanifold_edge.v1,
                      " (triangle ", r.first_nonmanifold_edge.triangle, ")")
        .at_index(r.first_nonmanifold_edge.triangle);
  }
  if (r.orientation_conflicts > 0) {
    return make_error(StatusCode::kInvalidMesh,
                      "mesh is not consistently oriented: ", r.orientation_conflicts,
                      " edges used twice in the same direction, first "
                      "between vertices ",
                      r.first_orientation_conflict.v0, " and ", r.first_orientation_conflict.v1,
                      " (triangle ", r.first_orientation_conflict.triangle, ")")
        .at_index(r.first_orientation_conflict.triangle);
  }
  if (r.degenerate_triangles > 0) {
    return make_error(StatusCode::kInvalidMesh, "mesh has ", r.degenerate_triangles,
                      " degenerate (zero-area) triangles, first is triangle ",
                      r.first_degenerate_triangle)
        .at_index(r.first_degenerate_triangle);
  }
  if (r.duplicate_triangles > 0) {
    return make_error(StatusCode::kInvalidMesh, "mesh has ", r.duplicate_triangles,
                      " duplicate triangles, first is triangle ", r.first_duplicate_triangle)
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
