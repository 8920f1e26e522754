// The Boolean's public entry, mesh_boolean (boolean.h): B as the union of its shells (issue 5).
// The jaws are one closed shell per tooth (Chen et al. 2016, "The Boolean operation": the
// splint base minus the teeth), and neighbouring teeth may overlap. One corefinement run
// (mesh_boolean_single: boolean_run.h and its stage files) needs shells that do not overlap
// each other where it matters, so the shells are grouped and the groups are applied in
// sequence:
//   A - (G1 u G2 u ...) = ((A - G1) - G2) - ...
//   A u (G1 u G2 u ...) = ((A u G1) u G2) u ...
//   A n (G1 u G2 u ...) = A n (((G1 u G2) u G3) u ...)
// (The intersection is not built as A - (A - B): A - B shares A's surface wherever B does not
// reach, and a Boolean of two meshes with coincident faces is the degenerate case the core can
// only nudge apart, leaving films. The union of the groups has no coincident faces unless
// B's shells themselves do.)
//
// Sources:
// - Shells: connected components through shared vertices (union-find with path halving,
//   R. E. Tarjan, J. van Leeuwen, "Worst-case analysis of set union algorithms", JACM 31(2),
//   1984; the smaller index is the root, as in src/core/union_find.h).
// - Shells whose boxes overlap: sorted by their boxes' lower x and swept (the one-way scan of
//   A. Zomorodian, H. Edelsbrunner, "Fast software for box intersections", IJCGA 12(1-2),
//   2002). A pair is first tried for a separating plane (normal along the line between the
//   centres; a solid lies in the convex hull of its vertices), then their triangles in the
//   boxes' overlap are binned in a uniform grid and the pairs whose boxes overlap decided by
//   the exact closed triangle-triangle test of geometry.h (touching counts), behind a plane
//   filter that only answers when certain.
// - Nesting of two shells whose surfaces do not meet: the generalised winding number of
//   A. Jacobson, L. Kavan, O. Sorkine-Hornung, "Robust Inside-Outside Segmentation using
//   Generalized Winding Numbers", SIGGRAPH 2013, each triangle's solid angle by
//   A. Van Oosterom, J. Strackee, "The Solid Angle of a Plane Triangle", IEEE TBME 30(2), 1983
//   (with deterministic_atan2: the same bits everywhere). The surfaces being disjoint, the
//   tested vertex is off the other surface, so the sum is within rounding of an integer.
// - Grouping: greedy colouring of the overlap graph in shell order (deterministic). The groups
//   are applied fewest triangles first: each pass's A holds the imprints of the passes before,
//   so the order that puts the largest group last does the least work, as a shortest job
//   first schedule does (the greedy order fills the first group most); when it fails, the
//   greedy order is tried too.
#include "boolean/boolean_internal.h"
#include "geometry/plane_filter.h"

namespace splintcore {

const char* boolean_op_name(BooleanOp op) {
  switch (op) {
    case BooleanOp::kDifference: return "difference";
    case BooleanOp::kUnion: return "union";
    case BooleanOp::kIntersection: return "intersection";
  }
  return "unknown";
}

namespace {

constexpr uint32_t kNone = ~uint32_t{0};

inline Aabb box_intersection(const Aabb& a, const Aabb& b) {
  Aabb r;
  r.lo = max_vec(a.lo, b.lo);
  r.hi = min_vec(a.hi, b.hi);
  return r;
}

inline bool box_inside(const Aabb& inner, const Aabb& outer) {
  return inner.lo.x >= outer.lo.x && inner.lo.y >= outer.lo.y && inner.lo.z >= outer.lo.z &&
         inner.hi.x <= outer.hi.x && inner.hi.y <= outer.hi.y && inner.hi.z <= outer.hi.z;
}

// B's shells: triangle and vertex labels, the triangles of each shell (ascending ids), boxes.
struct Shells {
  uint32_t count = 0;
  uint32_t* tri_shell = nullptr;   // per triangle of B
  uint32_t* vert_shell = nullptr;  // per vertex of B (kNone: unused)
  uint32_t* start = nullptr;       // shell -> [start[s], start[s + 1]) in tris
  uint32_t* tris = nullptr;        // null: the triangles of shell s are start[s]..start[s+1]
  uint32_t* vstart = nullptr;      // shell -> [vstart[s], vstart[s + 1]) in verts
  uint32_t* verts = nullptr;
  uint8_t* outcode = nullptr;  // per vertex of B: scratch for triangles_in_region
  Aabb* box = nullptr;
};

// Union-find root with path halving (one pass); the smaller index is always the root, so the
// roots depend only on the unions made.
inline uint32_t root_of(uint32_t* parent, uint32_t x) {
  while (parent[x] != x) {
    parent[x] = parent[parent[x]];
    x = parent[x];
  }
  return x;
}

// *usable = false (and nothing else) when B has an index out of range or a non-finite vertex:
// the single run reports those with its own messages. Shells are numbered in order of their
// smallest vertex id (the union-find's root). Three passes over the triangles (two when each
// shell's triangles are one run of B's), two over the vertices.
Status find_shells(Arena& arena, const Mesh& b, Shells* sh, bool* usable) {
  *usable = false;
  const uint32_t nv = static_cast<uint32_t>(b.vertices.size());
  const uint32_t nt = static_cast<uint32_t>(b.triangles.size());
  sh->tri_shell = arena.allocate_array<uint32_t>(nt);
  sh->vert_shell = arena.allocate_array<uint32_t>(nv);
  uint32_t* parent = arena.allocate_array<uint32_t>(nv);
  sh->outcode = arena.allocate_array<uint8_t>(nv);  // first: "used by a triangle"
  if ((sh->tri_shell == nullptr && nt > 0) ||
      ((sh->vert_shell == nullptr || parent == nullptr || sh->outcode == nullptr) && nv > 0)) {
    return arena.exhausted_status();
  }
  uint8_t* used = sh->outcode;
  for (uint32_t v = 0; v < nv; ++v) parent[v] = v;
  if (nv > 0) std::memset(used, 0, nv);
  const Triangle* tris = b.triangles.data();
  for (uint32_t t = 0; t < nt; ++t) {
    const Triangle& tri = tris[t];
    if (tri.v[0] >= nv || tri.v[1] >= nv || tri.v[2] >= nv) return Status::ok();
    used[tri.v[0]] = used[tri.v[1]] = used[tri.v[2]] = 1;
    // The common case: all three corners' parent is one root (a shell's root, its smallest
    // id, is where most of its vertices point), so they are in one set already. (The walks
    // below would find the same and change nothing.)
    const uint32_t p0 = parent[tri.v[0]];
    if (parent[p0] == p0 && parent[tri.v[1]] == p0 && parent[tri.v[2]] == p0) continue;
    uint32_t r0 = root_of(parent, tri.v[0]);
    for (int k = 1; k < 3; ++k) {
      const uint32_t r = root_of(parent, tri.v[k]);
      if (r < r0) {
        parent[r0] = r;
        r0 = r;
      } else if (r > r0) {
        parent[r] = r0;
      }
    }
  }
  // Vertices: a root (the smallest id of its shell, so met first) numbers its shell; boxes and
  // vertex counts on the way (vcounts, later the fill positions).
  ArenaArray<Aabb> boxes(&arena);
  ArenaArray<uint32_t> vcounts(&arena);
  const Vec3* vb = b.vertices.data();
  uint32_t count = 0;
  for (uint32_t v = 0; v < nv; ++v) {
    if (!is_finite(vb[v])) return Status::ok();
    if (used[v] == 0) {
      sh->vert_shell[v] = kNone;
      continue;
    }
    const uint32_t r = root_of(parent, v);
    if (r == v) {
      sh->vert_shell[v] = count++;
      if (!boxes.push_back(Aabb{}) || !vcounts.push_back(0)) return arena.exhausted_status();
    }
    const uint32_t s = sh->vert_shell[r];
    sh->vert_shell[v] = s;
    boxes[s].add(vb[v]);
    ++vcounts[s];
  }
  sh->count = count;
  sh->box = boxes.data();
  sh->start = arena.allocate_array<uint32_t>(size_t{count} + 1);
  sh->vstart = arena.allocate_array<uint32_t>(size_t{count} + 1);
  if (sh->start == nullptr || sh->vstart == nullptr) return arena.exhausted_status();
  std::memset(sh->start, 0, (size_t{count} + 1) * sizeof(uint32_t));
  bool runs = true;  // each shell's triangles one run, in shell order
  uint32_t previous = 0;
  for (uint32_t t = 0; t < nt; ++t) {
    const uint32_t s = sh->vert_shell[tris[t].v[0]];
    sh->tri_shell[t] = s;
    ++sh->start[s + 1];
    runs = runs && s >= previous;
    previous = s;
  }
  for (uint32_t s = 0; s < count; ++s) sh->start[s + 1] += sh->start[s];
  sh->vstart[0] = 0;
  for (uint32_t s = 0; s < count; ++s) sh->vstart[s + 1] = sh->vstart[s] + vcounts[s];
  // The vertices of each shell: the union-find's memory is done with and becomes the list.
  for (uint32_t s = 0; s < count; ++s) vcounts[s] = sh->vstart[s];
  sh->verts = parent;
  for (uint32_t v = 0; v < nv; ++v) {
    if (sh->vert_shell[v] != kNone) sh->verts[vcounts[sh->vert_shell[v]]++] = v;
  }
  if (!runs) {
    sh->tris = arena.allocate_array<uint32_t>(nt);
    if (sh->tris == nullptr && nt > 0) return arena.exhausted_status();
    for (uint32_t s = 0; s < count; ++s) vcounts[s] = sh->start[s];
    for (uint32_t t = 0; t < nt; ++t) sh->tris[vcounts[sh->tri_shell[t]]++] = t;
  }
  *usable = true;
  return Status::ok();
}

// The i-th triangle in shell order.
inline uint32_t tri_at(const Shells& sh, uint32_t i) { return sh.tris != nullptr ? sh.tris[i] : i; }

// The triangles of shell s whose boxes meet `region`: their ids and boxes.
struct RegionTriangles {
  Aabb* boxes = nullptr;
  uint32_t* ids = nullptr;
  uint32_t n = 0;
};

Status triangles_in_region(Arena& arena, const Mesh& b, const Shells& sh, uint32_t s,
                           const Aabb& region, RegionTriangles* r) {
  const uint32_t total = sh.start[s + 1] - sh.start[s];
  r->boxes = arena.allocate_array<Aabb>(total);
  r->ids = arena.allocate_array<uint32_t>(total);
  if ((r->boxes == nullptr || r->ids == nullptr) && total > 0) return arena.exhausted_status();
  // Outcodes of the shell's vertices first (one load of each vertex, not three per triangle):
  // a triangle whose corners are all beyond one side of the region misses it.
  uint8_t* oc = sh.outcode;
  const Vec3* vb = b.vertices.data();
  for (uint32_t i = sh.vstart[s]; i < sh.vstart[s + 1]; ++i) {
    const uint32_t v = sh.verts[i];
    const Vec3& p = vb[v];
    oc[v] = region.outcode(p);
  }
  uint32_t k = 0;
  for (uint32_t i = sh.start[s]; i < sh.start[s + 1]; ++i) {
    const uint32_t t = tri_at(sh, i);
    const Triangle& tri = b.triangles[t];
    if ((oc[tri.v[0]] & oc[tri.v[1]] & oc[tri.v[2]]) != 0) continue;
    const Aabb box = triangle_box(b, t);
    r->boxes[k] = box;
    r->ids[k] = t;
    ++k;
  }
  r->n = k;
  return Status::ok();
}

// Are the triangles of ri and rj certainly apart: all corners of ri's strictly on one side of
// a plane and all of rj's on the other, the plane's normal along the line between the
// centres of their boxes (the rounding margin as in certainly_apart)?
bool regions_apart(const Mesh& b, const RegionTriangles& ri, const RegionTriangles& rj) {
  Vec3 ci{}, cj{};
  for (uint32_t k = 0; k < ri.n; ++k) ci = ci + ri.boxes[k].center();
  for (uint32_t k = 0; k < rj.n; ++k) cj = cj + rj.boxes[k].center();
  const Vec3 n = cj * (1.0 / rj.n) - ci * (1.0 / ri.n);
  const double n1 = (n.x < 0 ? -n.x : n.x) + (n.y < 0 ? -n.y : n.y) + (n.z < 0 ? -n.z : n.z);
  if (!(n1 > 0)) return false;
  // The largest coordinate magnitude of any corner (each lies in its triangle's box).
  double m = 0;
  const RegionTriangles* both[2] = {&ri, &rj};
  for (const RegionTriangles* r : both) {
    for (uint32_t k = 0; k < r->n; ++k) {
      for (int a = 0; a < 3; ++a) {
        const double lo = r->boxes[k].lo[a] < 0 ? -r->boxes[k].lo[a] : r->boxes[k].lo[a];
        const double hi = r->boxes[k].hi[a] < 0 ? -r->boxes[k].hi[a] : r->boxes[k].hi[a];
        m = lo > m ? lo : m;
        m = hi > m ? hi : m;
      }
    }
  }
  const double margin = 1e-12 * n1 * m + 1e-300;
  const Vec3* v = b.vertices.data();
  double max_i = -HUGE_VAL, min_j = HUGE_VAL;
  for (uint32_t k = 0; k < ri.n; ++k) {
    for (uint32_t c : b.triangles[ri.ids[k]].v) {
      const double d = dot(n, v[c]);
      max_i = d > max_i ? d : max_i;
    }
  }
  for (uint32_t k = 0; k < rj.n; ++k) {
    for (uint32_t c : b.triangles[rj.ids[k]].v) {
      const double d = dot(n, v[c]);
      min_j = d < min_j ? d : min_j;
    }
  }
  return max_i + margin < min_j - margin;
}

// A uniform grid over the overlap of two shells' boxes, for the triangles of one of them.
struct RegionGrid {
  Aabb region;
  Vec3 ext;
  double h = 1.0;
  double inv_h = 1.0;
  uint32_t dim[3] = {1, 1, 1};

  void set_cells() {
    for (int k = 0; k < 3; ++k) {
      const double cells = ext[k] / h;
      dim[k] = cells < 1.0 ? 1u : (cells >= 128.0 ? 128u : static_cast<uint32_t>(cells) + 1u);
    }
    inv_h = 1.0 / h;
  }
  void range(const Aabb& box, uint32_t lo[3], uint32_t hi[3]) const {
    const double blo[3] = {box.lo.x, box.lo.y, box.lo.z}, bhi[3] = {box.hi.x, box.hi.y, box.hi.z};
    const double glo[3] = {region.lo.x, region.lo.y, region.lo.z};
    for (int k = 0; k < 3; ++k) {
      lo[k] = grid_cell((blo[k] - glo[k]) * inv_h, dim[k]);
      hi[k] = grid_cell((bhi[k] - glo[k]) * inv_h, dim[k]);
    }
  }
  size_t cells() const { return size_t{dim[0]} * dim[1] * dim[2]; }
};

// The grid for rj's triangles: about two cells a triangle of j (power-of-two cells, so every
// platform picks the same grid), at most 128 a side; coarser (doubling the cell) while j's
// triangles would take more than 16 cells each on average (a coarse shell against a fine
// one), down to one cell. *uses: the cells rj's boxes cover, summed.
RegionGrid region_grid(const Aabb& region, const RegionTriangles& rj, uint64_t* uses) {
  RegionGrid g;
  g.region = region;
  g.ext = region.extent();
  const Vec3& ext = g.ext;
  const double volume = (ext.x + 1e-9) * (ext.y + 1e-9) * (ext.z + 1e-9);
  const double target = 2.0 * rj.n + 8.0;
  double h = 1.0;
  while (volume / (h * h * h) > target && h < 1e30) h *= 2.0;
  while (volume / (h * h * h) < target / 8.0 && h > 1e-30) h *= 0.5;
  for (int k = 0; k < 3; ++k) {
    if (ext[k] / h > 128.0) h = ext[k] / 128.0;
  }
  g.h = h;
  for (;;) {
    g.set_cells();
    *uses = 0;
    for (uint32_t k = 0; k < rj.n; ++k) {
      uint32_t lo[3], hi[3];
      g.range(rj.boxes[k], lo, hi);
      *uses += uint64_t{hi[0] - lo[0] + 1} * (hi[1] - lo[1] + 1) * (hi[2] - lo[2] + 1);
    }
    if (*uses <= 16 * uint64_t{rj.n} + 64 || (g.dim[0] == 1 && g.dim[1] == 1 && g.dim[2] == 1)) {
      return g;
    }
    g.h *= 2.0;
  }
}

// rj's triangles binned in the grid's cells (two passes: count, then fill). After the fill,
// start[c] is the end of cell c (and the start of cell c + 1). `seen`: rj.n entries, ~0u.
Status bin_triangles(Arena& arena, const RegionGrid& g, const RegionTriangles& rj, uint64_t uses,
                     uint32_t** start_out, uint32_t** items_out, uint32_t** seen_out) {
  const size_t cells = g.cells();
  uint32_t* start = arena.allocate_array<uint32_t>(cells + 1);
  uint32_t* seen = arena.allocate_array<uint32_t>(rj.n);
  uint32_t* items = arena.allocate_array<uint32_t>(static_cast<size_t>(uses));
  if (start == nullptr || seen == nullptr || items == nullptr) return arena.exhausted_status();
  std::memset(start, 0, (cells + 1) * sizeof(uint32_t));
  std::memset(seen, 0xff, size_t{rj.n} * sizeof(uint32_t));
  for (int pass = 0; pass < 2; ++pass) {
    for (uint32_t k = 0; k < rj.n; ++k) {
      uint32_t lo[3], hi[3];
      g.range(rj.boxes[k], lo, hi);
      for (uint32_t z = lo[2]; z <= hi[2]; ++z) {
        for (uint32_t y = lo[1]; y <= hi[1]; ++y) {
          for (uint32_t x = lo[0]; x <= hi[0]; ++x) {
            const size_t c = (size_t{z} * g.dim[1] + y) * g.dim[0] + x;
            if (pass == 0) {
              ++start[c + 1];
            } else {
              items[start[c]++] = k;
            }
          }
        }
      }
    }
    if (pass == 0) {
      for (size_t c = 0; c < cells; ++c) start[c + 1] += start[c];
    }
  }
  *start_out = start;
  *items_out = items;
  *seen_out = seen;
  return Status::ok();
}

// Does triangle ki of ri meet triangle kj of rj (exactly; touching counts)? A filter first
// (only certain sides count): one triangle strictly on one side of the other's plane cannot
// meet it.
bool pair_meets(const Mesh& b, const RegionTriangles& ri, uint32_t ki, const RegionTriangles& rj,
                uint32_t kj) {
  const Vec3* v = b.vertices.data();
  auto apart = [&](const Triangle& p, const Triangle& q) {
    const PlaneFilter pl = plane_filter(v[p.v[0]], v[p.v[1]], v[p.v[2]]);
    const int s0 = filtered_side(pl, v[q.v[0]]);
    return (s0 == 1 || s0 == -1) && filtered_side(pl, v[q.v[1]]) == s0 &&
           filtered_side(pl, v[q.v[2]]) == s0;
  };
  if (!ri.boxes[ki].overlaps(rj.boxes[kj])) return false;
  const Triangle& s = b.triangles[ri.ids[ki]];
  const Triangle& t = b.triangles[rj.ids[kj]];
  if (apart(s, t) || apart(t, s)) return false;
  return triangles_intersect(v[s.v[0]], v[s.v[1]], v[s.v[2]], v[t.v[0]], v[t.v[1]], v[t.v[2]]);
}

// Do the surfaces of shells i and j meet (exactly; touching counts)? Only their triangles
// whose boxes meet both shells' boxes can: j's are binned in a uniform grid over that region
// (region_grid), and each of i's looks at the cells its box covers. The answer (whether any
// pair meets) does not depend on the grid.
Status surfaces_meet(const Context& ctx, const Mesh& b, const Shells& sh, uint32_t i, uint32_t j,
                     bool* meet) {
  *meet = false;
  Arena& arena = *ctx.arena;
  ArenaScope scope(arena);
  const Aabb region = box_intersection(sh.box[i], sh.box[j]);
  RegionTriangles ri, rj;
  SPLINTCORE_RETURN_IF_ERROR(triangles_in_region(arena, b, sh, i, region, &ri));
  if (ri.n == 0) return Status::ok();
  SPLINTCORE_RETURN_IF_ERROR(triangles_in_region(arena, b, sh, j, region, &rj));
  if (rj.n == 0) return Status::ok();
  if (regions_apart(b, ri, rj)) return Status::ok();
  uint64_t uses = 0;
  const RegionGrid g = region_grid(region, rj, &uses);
  uint32_t *start = nullptr, *items = nullptr, *seen = nullptr;
  SPLINTCORE_RETURN_IF_ERROR(bin_triangles(arena, g, rj, uses, &start, &items, &seen));
  for (uint32_t k = 0; k < ri.n; ++k) {
    if ((k & 0xfffu) == 0xfffu) {
      SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "boolean: shell pairs", 0, 1));
    }
    uint32_t lo[3], hi[3];
    g.range(ri.boxes[k], lo, hi);
    for (uint32_t z = lo[2]; z <= hi[2]; ++z) {
      for (uint32_t y = lo[1]; y <= hi[1]; ++y) {
        for (uint32_t xx = lo[0]; xx <= hi[0]; ++xx) {
          const size_t c = (size_t{z} * g.dim[1] + y) * g.dim[0] + xx;
          for (uint32_t e = c == 0 ? 0 : start[c - 1]; e < start[c]; ++e) {
            const uint32_t m = items[e];
            if (seen[m] == k) continue;
            seen[m] = k;
            if (pair_meets(b, ri, k, rj, m)) {
              *meet = true;
              return Status::ok();
            }
          }
        }
      }
    }
  }
  return Status::ok();
}

// Winding number of shell s at q (the sum of its triangles' solid angles over 4 pi).
double shell_winding(const Mesh& b, const Shells& sh, uint32_t s, const Vec3& q) {
  double sum = 0;
  for (uint32_t i = sh.start[s]; i < sh.start[s + 1]; ++i) {
    const Triangle& t = b.triangles[tri_at(sh, i)];
    const Vec3 p0 = b.vertices[t.v[0]] - q;
    const Vec3 p1 = b.vertices[t.v[1]] - q;
    const Vec3 p2 = b.vertices[t.v[2]] - q;
    const double l0 = length(p0), l1 = length(p1), l2 = length(p2);
    const double det = dot(p0, cross(p1, p2));
    const double den = l0 * l1 * l2 + dot(p0, p1) * l2 + dot(p0, p2) * l1 + dot(p1, p2) * l0;
    sum += 2.0 * deterministic_atan2(det, den);
  }
  return sum * (0.25 / 3.14159265358979323846);
}

// Are shells i and j certainly apart: all of i's vertices strictly on one side of a plane and
// all of j's on the other, with the plane's normal along the line between the boxes' centres?
// A solid lies in the convex hull of its vertices, so then they share no point. The margin
// covers the rounding of the dot products (3 eps |n|_1 max|v| each, with room to spare).
// Neighbouring teeth are nearly always told apart here, without looking at a triangle.
bool certainly_apart(const Mesh& b, const Shells& sh, uint32_t i, uint32_t j) {
  // One direction: the line between the centres. (The six face diagonals as well told two
  // more of the real case's 30 neighbouring pairs apart, for seven times the work on all.)
  constexpr int kDirections = 1;
  Vec3 n[kDirections] = {sh.box[j].center() - sh.box[i].center()};
  double m = 0;
  const Aabb* boxes[2] = {&sh.box[i], &sh.box[j]};
  for (const Aabb* box : boxes) {
    for (int k = 0; k < 3; ++k) {
      const double lo = box->lo[k] < 0 ? -box->lo[k] : box->lo[k];
      const double hi = box->hi[k] < 0 ? -box->hi[k] : box->hi[k];
      m = lo > m ? lo : m;
      m = hi > m ? hi : m;
    }
  }
  const Vec3* vb = b.vertices.data();
  double lo[2][kDirections], hi[2][kDirections];
  for (int side = 0; side < 2; ++side) {
    const uint32_t s = side == 0 ? i : j;
    for (int d = 0; d < kDirections; ++d) {
      lo[side][d] = HUGE_VAL;
      hi[side][d] = -HUGE_VAL;
    }
    for (uint32_t k = sh.vstart[s]; k < sh.vstart[s + 1]; ++k) {
      const Vec3& p = vb[sh.verts[k]];
      for (int d = 0; d < kDirections; ++d) {
        const double x = dot(n[d], p);
        lo[side][d] = x < lo[side][d] ? x : lo[side][d];
        hi[side][d] = x > hi[side][d] ? x : hi[side][d];
      }
    }
  }
  for (int d = 0; d < kDirections; ++d) {
    const double n1 = (n[d].x < 0 ? -n[d].x : n[d].x) + (n[d].y < 0 ? -n[d].y : n[d].y) +
                      (n[d].z < 0 ? -n[d].z : n[d].z);
    if (!(n1 > 0)) continue;
    const double margin = 1e-12 * n1 * m + 1e-300;
    if (hi[0][d] + margin < lo[1][d] - margin || hi[1][d] + margin < lo[0][d] - margin) {
      return true;
    }
  }
  return false;
}

// Do shells i and j overlap (share a point: their surfaces meet, or one lies in the other)?
Status shells_overlap(const Context& ctx, const Mesh& b, const Shells& sh, uint32_t i, uint32_t j,
                      bool* overlap) {
  *overlap = false;
  if (certainly_apart(b, sh, i, j)) return Status::ok();
  SPLINTCORE_RETURN_IF_ERROR(surfaces_meet(ctx, b, sh, i, j, overlap));
  if (*overlap) return Status::ok();
  // Disjoint surfaces: nested or apart. Nested only when one box holds the other.
  for (int k = 0; k < 2; ++k) {
    const uint32_t inner = k == 0 ? i : j, outer = k == 0 ? j : i;
    if (!box_inside(sh.box[inner], sh.box[outer])) continue;
    const Vec3& q = b.vertices[b.triangles[tri_at(sh, sh.start[inner])].v[0]];
    const double w = shell_winding(b, sh, outer, q);
    if (w >= 0.5 || w <= -0.5) {
      *overlap = true;
      return Status::ok();
    }
  }
  return Status::ok();
}

// A group's shells as one mesh: its vertices and triangles in B's order.
Status group_mesh(Arena& arena, const Mesh& b, const Shells& sh, const uint32_t* group, uint32_t g,
                  uint32_t* remap, Mesh* out) {
  const uint32_t nv = static_cast<uint32_t>(b.vertices.size());
  const uint32_t nt = static_cast<uint32_t>(b.triangles.size());
  uint32_t count_v = 0, count_t = 0;
  for (uint32_t v = 0; v < nv; ++v) {
    const uint32_t s = sh.vert_shell[v];
    remap[v] = s != kNone && group[s] == g ? count_v++ : kNone;
  }
  for (uint32_t t = 0; t < nt; ++t) count_t += group[sh.tri_shell[t]] == g ? 1 : 0;
  out->bind(&arena);
  if (!out->triangles.reserve(count_t) || !out->vertices.reserve(count_v)) {
    return arena.exhausted_status();
  }
  for (uint32_t t = 0; t < nt; ++t) {
    if (group[sh.tri_shell[t]] != g) continue;
    const Triangle& tri = b.triangles[t];
    (void)out->triangles.push_back(Triangle{{remap[tri.v[0]], remap[tri.v[1]], remap[tri.v[2]]}});
  }
  for (uint32_t v = 0; v < nv; ++v) {
    if (remap[v] != kNone) (void)out->vertices.push_back(b.vertices[v]);
  }
  return Status::ok();
}

void add_stats(const BooleanStats& p, BooleanStats* total) {
  total->near_b_triangles += p.near_b_triangles;
  total->candidate_pairs += p.candidate_pairs;
  total->intersecting_pairs += p.intersecting_pairs;
  total->degenerate_pairs += p.degenerate_pairs;
  total->intersection_points += p.intersection_points;
  total->merged_points += p.merged_points;
  total->cut_triangles_a += p.cut_triangles_a;
  total->cut_triangles_b += p.cut_triangles_b;
  total->winding_queries += p.winding_queries;
  total->self_intersection_candidates += p.self_intersection_candidates;
  total->attempts += p.attempts;
  total->parallel_near_triangles += p.parallel_near_triangles;
  total->hit_batches += p.hit_batches;
  total->output_triangles = p.output_triangles;
  total->output_triangles_a = p.output_triangles_a;
  total->self_intersection_checked = p.self_intersection_checked;  // the final pass's result
  total->result_report_made = p.result_report_made;
  total->nudge = p.nudge;
  total->nudge_sum = total->nudge_sum + p.nudge_sum;
}

// The box that matters for the difference and the intersection: A's, widened by what a nudge
// can move A (the single run's reach, with room to spare).
Aabb region_of_a(const Mesh& a, uint32_t max_nudges) {
  const double reach = (max_nudges + 2.0) * nudge_step(a) * 16.0;
  Aabb box = mesh_bounds(a);
  box.lo = box.lo - Vec3{reach, reach, reach};
  box.hi = box.hi + Vec3{reach, reach, reach};
  return box;
}

}  // namespace

namespace {

// The order of the passes by the groups' triangles, fewest first (ties in the greedy order):
// by_size[p] is the group of pass p. Each pass takes the result of the passes before as its A,
// imprints and all, so the largest group is best applied last (on the real dentition's 30
// teeth, two groups of 161,219 and 31,345 triangles: the second pass's A has 23,780 triangles
// this way, 113,828 the greedy way, and the Boolean takes 18% fewer instructions). `size`:
// scratch for `groups`. An insertion sort: every group is a whole pass of the Boolean.
void order_groups_by_size(const Shells& sh, const uint32_t* group, uint32_t groups, KeyIndex* size,
                          uint32_t* by_size) {
  for (uint32_t g = 0; g < groups; ++g) size[g] = KeyIndex{0, g, 0};
  for (uint32_t s = 0; s < sh.count; ++s) {
    if (group[s] != kNone) size[group[s]].key += sh.start[s + 1] - sh.start[s];
  }
  for (uint32_t i = 1; i < groups; ++i) {
    const KeyIndex x = size[i];
    uint32_t j = i;
    for (; j > 0 && size[j - 1].key > x.key; --j) size[j] = size[j - 1];
    size[j] = x;
  }
  for (uint32_t p = 0; p < groups; ++p) by_size[p] = size[p].index;
}

// Which group each of B's shells goes in (kNone: it cannot matter: for all but the union,
// a shell away from A's region) and how many groups there are. Shells whose boxes meet where
// it matters are tested exactly; overlapping ones go in different groups, greedily in shell
// order (the first group none of the earlier overlapping shells is in); *by_size_out: the
// groups fewest triangles first (order_groups_by_size). The arrays stay in the arena; one
// group when no two shells overlap.
Status group_shells(const Context& ctx, const Mesh& b, const Shells& sh, const Aabb& region,
                    bool everywhere, uint32_t** group_out, uint32_t* groups_out,
                    uint32_t** by_size_out) {
  Arena& arena = *ctx.arena;
  uint32_t* group = arena.allocate_array<uint32_t>(sh.count);
  KeyIndex* order = arena.allocate_array<KeyIndex>(sh.count);
  uint32_t* stamp = arena.allocate_array<uint32_t>(sh.count);
  if (group == nullptr || order == nullptr || stamp == nullptr) return arena.exhausted_status();
  uint32_t relevant = 0;
  for (uint32_t i = 0; i < sh.count; ++i) {
    const bool matters = everywhere || sh.box[i].overlaps(region);
    group[i] = matters ? 0 : kNone;
    if (matters) order[relevant++] = KeyIndex{order_key(sh.box[i].lo.x), i, 0};
    stamp[i] = kNone;
  }
  SPLINTCORE_RETURN_IF_ERROR(radix_sort(arena, Span<KeyIndex>(order, relevant)));
  // Pairs whose boxes meet (where it matters), then the exact test: (j << 32 | i), i < j.
  ArenaArray<uint64_t> conflicts(&arena);
  for (uint32_t x = 0; x < relevant; ++x) {
    const uint32_t i = order[x].index;
    for (uint32_t y = x + 1; y < relevant && sh.box[order[y].index].lo.x <= sh.box[i].hi.x; ++y) {
      const uint32_t j = order[y].index;
      if (!sh.box[i].overlaps(sh.box[j])) continue;
      if (!everywhere && !box_intersection(sh.box[i], sh.box[j]).overlaps(region)) continue;
      const uint64_t lo = i < j ? i : j, hi = i < j ? j : i;
      bool overlap = false;
      SPLINTCORE_RETURN_IF_ERROR(shells_overlap(ctx, b, sh, static_cast<uint32_t>(lo),
                                                static_cast<uint32_t>(hi), &overlap));
      if (overlap && !conflicts.push_back(hi << 32 | lo)) return arena.exhausted_status();
    }
  }
  uint32_t groups = 1;
  if (!conflicts.empty()) {
    uint64_t* scratch = arena.allocate_array<uint64_t>(conflicts.size());
    if (scratch == nullptr) return arena.exhausted_status();
    radix_sort(Span<uint64_t>(conflicts.data(), conflicts.size()),
               Span<uint64_t>(scratch, conflicts.size()));
    size_t c = 0;
    for (uint32_t j = 0; j < sh.count; ++j) {
      if (group[j] == kNone) continue;
      for (; c < conflicts.size() && (conflicts[c] >> 32) == j; ++c) {
        stamp[group[static_cast<uint32_t>(conflicts[c])]] = j;
      }
      uint32_t g = 0;
      while (stamp[g] == j) ++g;
      group[j] = g;
      groups = g + 1 > groups ? g + 1 : groups;
    }
  }
  // (order and stamp are done with: groups <= shells.)
  order_groups_by_size(sh, group, groups, order, stamp);
  *by_size_out = stamp;
  *group_out = group;
  *groups_out = groups;
  return Status::ok();
}

// B's float32 requirement, checked on B itself so that an error names B's own triangle (a
// pass sees a copy of one group, numbered anew): only triangles near A's region matter.
Status check_b_float32(const Mesh& b, const Aabb& region) {
  const Vec3* vb = b.vertices.data();
  // Every vertex exact (B read from STL files, the usual case) answers for every triangle, a
  // vertex once instead of once per triangle using it (the real dentition's B: 96k vertices,
  // 577k corners); otherwise the triangles, for the first one that matters.
  bool every_vertex = true;
  for (size_t i = 0; i < b.vertices.size() && every_vertex; ++i) {
    every_vertex = is_float32_exact(vb[i]);
  }
  if (every_vertex) return Status::ok();
  for (uint32_t t = 0; t < b.triangles.size(); ++t) {
    const Triangle& tri = b.triangles[t];
    if (is_float32_exact(vb[tri.v[0]]) && is_float32_exact(vb[tri.v[1]]) &&
        is_float32_exact(vb[tri.v[2]])) {
      continue;
    }
    if (triangle_box(b, t).overlaps(region)) return b_not_float32(t);
  }
  return Status::ok();
}

// Several groups: one run each, in `order` (order[p]: the group of pass p; null: the groups'
// own order), the result of one the first operand of the next (for the
// intersection: the union of the groups first, then A and that union). Arena layout:
// [shells][current result][group mesh][this pass's result]; each result is moved down over
// the previous one and the group; the last down to `start`, into *out.
Status run_passes(const Context& ctx, const Mesh& a, const Mesh& b, const Shells& sh,
                  const uint32_t* group, uint32_t groups, const uint32_t* order,
                  const BooleanOptions& options, const Arena::Marker& start, Mesh* out,
                  BooleanStats* stats) {
  Arena& arena = *ctx.arena;
  uint32_t* remap = arena.allocate_array<uint32_t>(b.vertices.size());
  if (remap == nullptr && !b.vertices.empty()) return arena.exhausted_status();
  const Arena::Marker base = arena.mark();
  const bool intersection = options.op == BooleanOp::kIntersection;
  const uint32_t passes = groups;  // intersection: groups - 1 unions, then one intersection
  BooleanStats total{};
  Mesh current;
  const Mesh* first = &a;
  uint32_t g = 0;
  if (intersection) {
    SPLINTCORE_RETURN_IF_ERROR(
        group_mesh(arena, b, sh, group, order != nullptr ? order[0] : 0, remap, &current));
    first = &current;
    g = 1;
  }
  uint32_t done = 0;
  bool first_checked = false;  // *first is an earlier pass's result (its run checked it a solid)
  for (uint32_t pass = 0; pass < passes; ++pass) {
    const bool last = pass + 1 == passes;
    Mesh operand;
    const Mesh* second = &operand;
    BooleanOptions o = options;
    if (intersection && last) {
      second = first;  // A n (the union of the groups)
      first = &a;
      first_checked = false;
    } else {
      SPLINTCORE_RETURN_IF_ERROR(
          group_mesh(arena, b, sh, group, order != nullptr ? order[g] : g, remap, &operand));
      ++g;
      if (intersection) o.op = BooleanOp::kUnion;
    }
    // Intermediate results are checked closed and oriented by the run; the exact
    // self-intersection check is left to the final result.
    if (!last) {
      o.check_self_intersection = false;
      o.result_report = nullptr;
    }
    Mesh result;
    BooleanStats ps;
    // (The groups are copies of B's valid shells; the intersection's union a checked result.)
    Status s = mesh_boolean_single(ctx, *first, *second, o, &result, &ps, true, first_checked);
    add_stats(ps, &total);
    if (!s.is_ok()) {
      s.append(" (pass ").append_u64(pass + 1).append(" of ").append_u64(passes);
      s.append(intersection ? (last ? ": A and the union of B's overlapping shells)"
                                    : ": the union of B's overlapping shells)")
                            : ": a group of B's shells that do not overlap)");
      *stats = total;
      stats->passes = pass + 1;
      return s;
    }
    Mesh moved;
    move_mesh_down(arena, base, result, &moved);
    current = moved;
    first = &current;
    first_checked = !current.triangles.empty();
    done = pass + 1;
    // Nothing is left of A: the later groups can only take from nothing (and an empty mesh
    // is not a solid that a next pass could take as A).
    if (options.op == BooleanOp::kDifference && current.triangles.empty()) break;
  }
  move_mesh_down(arena, start, current, out);
  *stats = total;
  stats->passes = done;
  return Status::ok();
}

// The passes fewest triangles first (by_size); when that fails other than for memory or a
// cancel, and the greedy order differs, the greedy order as before the order by size (a group
// applied to a result the others have already cut can pass where it fails on A itself, and
// the other way round: the real case's exact sweep with a base 4 mm deep needs the greedy
// order). Its error is the one returned when both fail.
Status run_passes_in_order(const Context& ctx, const Mesh& a, const Mesh& b, const Shells& sh,
                           const uint32_t* group, uint32_t groups, const uint32_t* by_size,
                           const BooleanOptions& options, const Arena::Marker& start, Mesh* out,
                           BooleanStats* stats) {
  const Arena::Marker m = ctx.arena->mark();
  Status s = run_passes(ctx, a, b, sh, group, groups, by_size, options, start, out, stats);
  if (s.is_ok() || s.code() == StatusCode::kArenaExhausted || s.code() == StatusCode::kCancelled) {
    return s;
  }
  uint32_t p = 0;
  while (p < groups && by_size[p] == p) ++p;
  if (p == groups) return s;
  const uint32_t tried = stats->attempts;
  ctx.arena->rewind(m);
  s = run_passes(ctx, a, b, sh, group, groups, nullptr, options, start, out, stats);
  stats->attempts += tried;
  return s;
}

// A result that failed its own check (kInternal, or kUnsupported as fragile) from an operand
// that crosses itself is that operand's fault: said as such (kInvalidMesh, naming its first
// pair), the check's words kept. A must be a solid; B only for the union, and only when it is
// one shell (elsewhere B's parts away from A, and its shells among themselves, may cross).
// Checked only then (find_self_intersections, in the arena as the run left it: when that does
// not fit, or neither crosses itself, `s` stands as it is).
Status blame_crossing_operand(const Context& ctx, const Mesh& a, const Mesh& b, uint32_t b_shells,
                              BooleanOp op, Status s) {
  if (s.code() != StatusCode::kInternal && s.code() != StatusCode::kUnsupported) return s;
  const Mesh* operands[2] = {&a, op == BooleanOp::kUnion && b_shells == 1 ? &b : nullptr};
  for (int k = 0; k < 2; ++k) {
    if (operands[k] == nullptr) continue;
    SelfIntersectionReport si;
    if (!find_self_intersections(ctx, *operands[k], 1, &si).is_ok()) {
      ctx.arena->forget_failure();
      return s;
    }
    if (si.self_intersecting()) {
      return make_error(StatusCode::kInvalidMesh, "Boolean ", boolean_op_name(op), ": ",
                        k == 0 ? "A" : "B", " crosses itself (its triangles ", si.first_a, " and ",
                        si.first_b, " meet), so no solid comes of it: ", s.message())
          .at_index(si.first_a);
    }
  }
  return s;
}

}  // namespace

Status mesh_boolean(const Context& ctx, const Mesh& a, const Mesh& b, const BooleanOptions& options,
                    Mesh* out, BooleanStats* stats) {
  Arena& arena = *ctx.arena;
  BooleanStats local{};
  if (stats == nullptr) stats = &local;
  *stats = BooleanStats{};
  SPLINTCORE_RETURN_IF_ERROR(check_boolean_arguments(a, b, *out));
  SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "boolean: shells", 0, 1));
  ArenaScope scope(arena);  // on any error the arena is as it was
  // ---- B's shells, which overlap where it matters, and their groups.
  Shells sh;
  bool usable = false;
  SPLINTCORE_RETURN_IF_ERROR(find_shells(arena, b, &sh, &usable));
  SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "boolean: shell pairs", 0, 1));
  const Aabb region = region_of_a(a, options.max_nudges);
  if (!options.b_border_outside_a) {
    SPLINTCORE_RETURN_IF_ERROR(refuse_open_border_in_a(ctx, a, b, region, usable));
  }
  uint32_t* group = nullptr;
  uint32_t* by_size = nullptr;
  uint32_t groups = 1;
  if (usable && sh.count > 1) {
    SPLINTCORE_RETURN_IF_ERROR(group_shells(ctx, b, sh, region, options.op == BooleanOp::kUnion,
                                            &group, &groups, &by_size));
  }
  Status s;
  if (groups == 1) {
    // One run, with the arena as the caller gave it (it rewinds itself on an error).
    arena.rewind(scope.start());
    s = mesh_boolean_single(ctx, a, b, options, out, stats, usable, false);
    scope.commit();
  } else if (options.float32_output && !(s = check_b_float32(b, region)).is_ok()) {
    return s;
  } else {
    s = run_passes_in_order(ctx, a, b, sh, group, groups, by_size, options, scope.start(), out,
                            stats);
    if (s.is_ok()) scope.commit();
  }
  stats->shells = sh.count;
  stats->shell_groups = groups;
  if (groups == 1) stats->passes = 1;
  if (!s.is_ok()) s = blame_crossing_operand(ctx, a, b, sh.count, options.op, s);
  return s;
}

Aabb boolean_region(const Mesh& a, const BooleanOptions& options) {
  if (options.op == BooleanOp::kUnion) {
    Aabb all;
    all.lo = Vec3{-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
    all.hi = Vec3{HUGE_VAL, HUGE_VAL, HUGE_VAL};
    return all;
  }
  return region_of_a(a, options.max_nudges);
}

}  // namespace splintcore
