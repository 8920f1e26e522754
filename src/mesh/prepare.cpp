// Scan preparation (prepare_scan, mesh.h): the repairs an intraoral scan needs before it can be
// a jaw, in a fixed order, each counted. The steps follow the usual mesh-repair pipeline
// (Attene, Campen, Kobbelt 2013, "Polygon mesh repairing: an application perspective", ACM
// Computing Surveys 45(2), sections 4-5: duplicates and degenerate elements, singular edges
// and vertices, small components, holes, orientation), with the choices kept simple and exact:
//
// 1. duplicate triangles (the same three vertex ids, either winding): the later ones go;
// 2. degenerate triangles (a repeated id, or zero area by the exact collinear3d) go;
// 3. an edge used by three or more triangles keeps two: the best connected (most of their two
//    other edges shared with some triangle), a pair of opposite windings before one of the
//    same, then the lower index; the others go (a flap on an edge has no other shared edge, so
//    it is the one removed). A triangle removed at one such edge is removed everywhere;
// 4. a vertex whose triangles form several fans (edge-connected around it) keeps the fan of
//    its lowest corner and gets a copy (same coordinates) for each other fan;
// 5. components through edges smaller than the island size go (area in mm^2 by default:
//    unlike a triangle count it means the same at any scan resolution); the largest is kept;
// 6. orientation: each component is made consistent by a breadth-first walk from its lowest
//    triangle, then turned whole when more of its triangles were flipped than kept (the
//    input's majority wins); a closed component is turned outward, an open one to agree with
//    the largest open component (net normals' dot product), and with `occlusal` set the whole
//    mesh is turned so its net normal points that way. Edges the walk cannot make agree (a
//    non-orientable strip) are counted, not guessed;
// 7. holes: each boundary loop (boundary half-edges chained head to tail; a loop through a
//    vertex with two outgoing ones is left alone) of at most max_hole_edges edges is filled, a
//    triangle for three edges, else a fan from the loop's centroid (one new vertex, rounded
//    to float32 so that the result is what an STL holds); a fill
//    with a triangle of zero area (exact) is not made. Filling after the orientation lets the
//    fill take its winding from the loop's;
// 8. vertices no triangle uses go; the order of what is kept never changes.
//
// Every step is linear after one radix sort of the half-edges (stable, by vertex pair), so the
// output depends only on the input.
#include "core/union_find.h"
#include "splintcore/mesh.h"

namespace splintcore {

namespace {

constexpr uint32_t kNone = ~uint32_t{0};

uint64_t half_edges_bound(uint64_t t) { return 2 * arena_array_bound<KeyIndex>(3 * t); }

struct Prep {
  Arena& arena;
  const PrepareOptions& o;
  PrepareReport* r;
  Vec3* v = nullptr;
  uint32_t nv = 0;
  Triangle* t = nullptr;
  uint32_t nt = 0;

  uint32_t from(uint32_t h) const { return t[h / 3].v[h % 3]; }
  uint32_t to(uint32_t h) const { return t[h / 3].v[h % 3 == 2 ? 0 : h % 3 + 1]; }

  // The half-edges 3 t + k sorted by their vertex pair (smaller id high), ascending ids within
  // a pair; *keys lives until the caller's scope ends.
  Status half_edges(KeyIndex** keys) {
    const size_t n = size_t{3} * nt;
    KeyIndex* k = arena.allocate_array<KeyIndex>(n);
    KeyIndex* scratch = arena.allocate_array<KeyIndex>(n);
    if ((k == nullptr || scratch == nullptr) && n > 0) return arena.exhausted_status();
    for (uint32_t h = 0; h < n; ++h) {
      const uint32_t a = from(h), b = to(h);
      k[h] = KeyIndex{a < b ? (uint64_t{a} << 32 | b) : (uint64_t{b} << 32 | a), h, 0};
    }
    radix_sort(Span<KeyIndex>(k, n), Span<KeyIndex>(scratch, n));
    *keys = k;
    return Status::ok();
  }

  // Keeps the triangles not marked, in order.
  void compact(const uint8_t* removed) {
    uint32_t kept = 0;
    for (uint32_t i = 0; i < nt; ++i) {
      if (removed[i] == 0) t[kept++] = t[i];
    }
    nt = kept;
  }

  Status remove_duplicates();
  void remove_degenerate();
  Status resolve_nonmanifold_edges();
  Status split_nonmanifold_vertices();
  Status remove_islands();
  Status orient();
  Status fill_holes();
  Status finish(const Arena::Marker& start, Mesh* out);
};

uint32_t lowest(const uint32_t* v) {
  const uint32_t m = v[0] < v[1] ? v[0] : v[1];
  return m < v[2] ? m : v[2];
}
uint32_t highest(const uint32_t* v) {
  const uint32_t m = v[0] > v[1] ? v[0] : v[1];
  return m > v[2] ? m : v[2];
}

// Sorted by the largest id, then (stable) by the two smallest: equal sets end up adjacent, in
// index order.
Status Prep::remove_duplicates() {
  ArenaScope scope(arena);
  KeyIndex* items = arena.allocate_array<KeyIndex>(nt);
  KeyIndex* scratch = arena.allocate_array<KeyIndex>(nt);
  uint8_t* removed = arena.allocate_array<uint8_t>(nt);
  if ((items == nullptr || scratch == nullptr || removed == nullptr) && nt > 0) {
    return arena.exhausted_status();
  }
  for (uint32_t i = 0; i < nt; ++i) items[i] = KeyIndex{highest(t[i].v), i, 0};
  radix_sort(Span<KeyIndex>(items, nt), Span<KeyIndex>(scratch, nt));
  for (uint32_t i = 0; i < nt; ++i) {
    const uint32_t* x = t[items[i].index].v;
    const uint32_t lo = lowest(x), mid = x[0] ^ x[1] ^ x[2] ^ lo ^ highest(x);
    items[i].key = uint64_t{lo} << 32 | mid;
  }
  radix_sort(Span<KeyIndex>(items, nt), Span<KeyIndex>(scratch, nt));
  if (nt > 0) std::memset(removed, 0, nt);
  for (uint32_t i = 1; i < nt; ++i) {
    if (items[i].key == items[i - 1].key &&
        highest(t[items[i].index].v) == highest(t[items[i - 1].index].v)) {
      removed[items[i].index] = 1;  // the later of two equal sets (stable: index order)
      ++r->duplicate_triangles;
    }
  }
  compact(removed);
  return Status::ok();
}

void Prep::remove_degenerate() {
  uint32_t kept = 0;
  for (uint32_t i = 0; i < nt; ++i) {
    const uint32_t* x = t[i].v;
    if (x[0] == x[1] || x[1] == x[2] || x[2] == x[0] || collinear3d(v[x[0]], v[x[1]], v[x[2]])) {
      ++r->degenerate_triangles;
    } else {
      t[kept++] = t[i];
    }
  }
  nt = kept;
}

Status Prep::resolve_nonmanifold_edges() {
  ArenaScope scope(arena);
  KeyIndex* keys = nullptr;
  SPLINTCORE_RETURN_IF_ERROR(half_edges(&keys));
  const uint32_t n = 3 * nt;
  uint32_t* uses = arena.allocate_array<uint32_t>(n);
  uint8_t* removed = arena.allocate_array<uint8_t>(nt);
  if ((uses == nullptr || removed == nullptr) && nt > 0) return arena.exhausted_status();
  if (nt > 0) std::memset(removed, 0, nt);
  for (uint32_t i = 0, j = 0; i < n; i = j) {
    for (j = i + 1; j < n && keys[j].key == keys[i].key;) ++j;
    for (uint32_t m = i; m < j; ++m) uses[keys[m].index] = j - i;
  }
  // Of a triangle's other two edges, how many some other triangle shares.
  auto score = [&](uint32_t h) {
    const uint32_t base = h - h % 3;
    uint32_t s = 0;
    for (uint32_t k = 0; k < 3; ++k) s += (base + k != h && uses[base + k] >= 2) ? 1u : 0u;
    return s;
  };
  for (uint32_t i = 0, j = 0; i < n; i = j) {
    for (j = i + 1; j < n && keys[j].key == keys[i].key;) ++j;
    if (j - i <= 2) continue;
    ++r->nonmanifold_edges;
    uint32_t first = i;
    for (uint32_t m = i + 1; m < j; ++m) {
      if (score(keys[m].index) > score(keys[first].index)) first = m;
    }
    const uint32_t f = keys[first].index;
    uint32_t second = kNone, best = 0;
    for (uint32_t m = i; m < j; ++m) {
      if (m == first) continue;
      const uint32_t h = keys[m].index;
      const uint32_t rank = 2 * score(h) + (from(h) != from(f) ? 1u : 0u);
      if (second == kNone || rank > best) {
        second = m;
        best = rank;
      }
    }
    for (uint32_t m = i; m < j; ++m) {
      if (m == first || m == second || removed[keys[m].index / 3] != 0) continue;
      removed[keys[m].index / 3] = 1;
      ++r->nonmanifold_triangles;
    }
  }
  compact(removed);
  return Status::ok();
}

// Corners (3 t + k) at one vertex are in one fan when their triangles share an edge at it.
// Union-find keeps the lowest corner as the root, so walking corners in order meets each fan's
// root first: the vertex's first fan keeps it, each later fan gets a new vertex.
Status Prep::split_nonmanifold_vertices() {
  ArenaScope scope(arena);
  KeyIndex* keys = nullptr;
  SPLINTCORE_RETURN_IF_ERROR(half_edges(&keys));
  const uint32_t n = 3 * nt, nv0 = nv;
  UnionFind fans;
  uint32_t* id = arena.allocate_array<uint32_t>(n);
  uint32_t* first_fan = arena.allocate_array<uint32_t>(nv0);
  uint8_t* split = arena.allocate_array<uint8_t>(nv0);
  if (!fans.init(arena, n) || ((id == nullptr) && n > 0) ||
      ((first_fan == nullptr || split == nullptr) && nv0 > 0)) {
    return arena.exhausted_status();
  }
  auto corner = [&](uint32_t tri, uint32_t vertex) {
    const uint32_t* x = t[tri].v;
    return 3 * tri + (x[0] == vertex ? 0u : (x[1] == vertex ? 1u : 2u));
  };
  for (uint32_t i = 0; i + 1 < n; ++i) {
    if (keys[i].key != keys[i + 1].key || (i + 2 < n && keys[i + 2].key == keys[i].key)) continue;
    const uint32_t t1 = keys[i].index / 3, t2 = keys[i + 1].index / 3;
    const uint32_t a = from(keys[i].index), b = to(keys[i].index);
    fans.unite(corner(t1, a), corner(t2, a));
    fans.unite(corner(t1, b), corner(t2, b));
  }
  std::memset(first_fan, 0xff, size_t{nv0} * sizeof(uint32_t));
  if (nv0 > 0) std::memset(split, 0, nv0);
  for (uint32_t c = 0; c < n; ++c) {
    const uint32_t vertex = t[c / 3].v[c % 3];
    const uint32_t root = fans.find(c);
    if (root == c) {
      if (first_fan[vertex] == kNone) {
        first_fan[vertex] = c;
        id[c] = vertex;
      } else {
        v[nv] = v[vertex];
        id[c] = nv++;
        ++r->split_vertices_added;
        if (split[vertex] == 0) ++r->nonmanifold_vertices;
        split[vertex] = 1;
      }
    }
    t[c / 3].v[c % 3] = id[root];
  }
  return Status::ok();
}

Status Prep::remove_islands() {
  ArenaScope scope(arena);
  KeyIndex* keys = nullptr;
  SPLINTCORE_RETURN_IF_ERROR(half_edges(&keys));
  const uint32_t n = 3 * nt;
  UnionFind parts;
  uint32_t* count = arena.allocate_array<uint32_t>(nt);
  double* area = arena.allocate_array<double>(nt);
  uint8_t* removed = arena.allocate_array<uint8_t>(nt);
  if (!parts.init(arena, nt) ||
      ((count == nullptr || area == nullptr || removed == nullptr) && nt > 0)) {
    return arena.exhausted_status();
  }
  for (uint32_t i = 0; i + 1 < n; ++i) {
    if (keys[i].key == keys[i + 1].key) parts.unite(keys[i].index / 3, keys[i + 1].index / 3);
  }
  for (uint32_t i = 0; i < nt; ++i) {
    count[i] = 0;
    area[i] = 0;
  }
  for (uint32_t i = 0; i < nt; ++i) {
    const uint32_t root = parts.find(i);
    const Vec3 &p0 = v[t[i].v[0]], &p1 = v[t[i].v[1]], &p2 = v[t[i].v[2]];
    ++count[root];
    area[root] += 0.5 * length(cross(p1 - p0, p2 - p0));
  }
  const bool by_count = o.min_island_triangles > 0;
  uint32_t largest = kNone;
  for (uint32_t i = 0; i < nt; ++i) {
    if (parts.find(i) != i) continue;
    if (largest == kNone || (by_count ? count[i] > count[largest] : area[i] > area[largest])) {
      largest = i;
    }
  }
  for (uint32_t i = 0; i < nt; ++i) {
    const uint32_t root = parts.find(i);
    const bool small =
        by_count ? count[root] < o.min_island_triangles : area[root] < o.min_island_area;
    removed[i] = (root != largest && small) ? 1 : 0;
    if (root == i) {
      if (removed[i] != 0) {
        ++r->islands;
      } else {
        ++r->components;
      }
    }
    r->island_triangles += removed[i];
  }
  compact(removed);
  return Status::ok();
}

// Per component (indexed by its lowest triangle): what the walk found.
struct Component {
  uint32_t triangles = 0;
  uint32_t flipped = 0;
  bool open = false;
  Vec3 normal{};       // the sum of the triangles' area vectors, as walked
  double volume = 0;   // six times the signed volume, as walked
  uint8_t invert = 0;  // turn the whole component
};

// The breadth-first walk: flip[] relative to the seed, components, conflicts. neighbor[h] is
// the other half-edge of h's edge (kNone: a boundary).
void walk(const Prep& p, const uint32_t* neighbor, uint32_t* comp, uint8_t* flip, uint32_t* queue,
          PrepareReport* r) {
  for (uint32_t seed = 0; seed < p.nt; ++seed) {
    if (comp[seed] != kNone) continue;
    comp[seed] = seed;
    flip[seed] = 0;
    uint32_t head = 0, tail = 0;
    queue[tail++] = seed;
    while (head < tail) {
      const uint32_t u = queue[head++];
      for (uint32_t k = 0; k < 3; ++k) {
        const uint32_t h = 3 * u + k, o = neighbor[h];
        if (o == kNone) continue;
        const uint32_t w = o / 3;
        const uint8_t need = static_cast<uint8_t>(flip[u] ^ (p.from(h) == p.from(o) ? 1u : 0u));
        if (comp[w] == kNone) {
          comp[w] = seed;
          flip[w] = need;
          queue[tail++] = w;
        } else if (flip[w] != need && h < o) {
          ++r->orientation_conflicts;
        }
      }
    }
  }
}

// Which components to turn whole (see the file's comment, step 6).
void decide_turns(const Prep& p, const uint32_t* comp, Component* c) {
  uint32_t largest_open = kNone;
  for (uint32_t i = 0; i < p.nt; ++i) {
    if (comp[i] != i) continue;
    c[i].invert = c[i].flipped * 2 > c[i].triangles ? 1 : 0;
    if (c[i].invert != 0) {
      c[i].normal = c[i].normal * -1.0;
      c[i].volume = -c[i].volume;
    }
    if (c[i].open && (largest_open == kNone || c[i].triangles > c[largest_open].triangles)) {
      largest_open = i;
    }
  }
  for (uint32_t i = 0; i < p.nt; ++i) {
    if (comp[i] != i) continue;
    const bool turn = c[i].open
                          ? (largest_open != i && dot(c[i].normal, c[largest_open].normal) < 0)
                          : c[i].volume < 0;
    if (turn) {
      c[i].invert ^= 1;
      c[i].normal = c[i].normal * -1.0;
    }
  }
  if (p.o.occlusal.x != 0 || p.o.occlusal.y != 0 || p.o.occlusal.z != 0) {
    Vec3 total{};
    for (uint32_t i = 0; i < p.nt; ++i) {
      if (comp[i] == i) total = total + c[i].normal;
    }
    if (dot(total, p.o.occlusal) < 0) {
      for (uint32_t i = 0; i < p.nt; ++i) {
        if (comp[i] == i) c[i].invert ^= 1;
      }
    }
  }
}

Status Prep::orient() {
  ArenaScope scope(arena);
  KeyIndex* keys = nullptr;
  SPLINTCORE_RETURN_IF_ERROR(half_edges(&keys));
  const uint32_t n = 3 * nt;
  uint32_t* neighbor = arena.allocate_array<uint32_t>(n);
  uint32_t* comp = arena.allocate_array<uint32_t>(nt);
  uint32_t* queue = arena.allocate_array<uint32_t>(nt);
  uint8_t* flip = arena.allocate_array<uint8_t>(nt);
  Component* c = arena.allocate_array<Component>(nt);
  if ((neighbor == nullptr || comp == nullptr || queue == nullptr || flip == nullptr ||
       c == nullptr) &&
      nt > 0) {
    return arena.exhausted_status();
  }
  for (uint32_t h = 0; h < n; ++h) neighbor[h] = kNone;
  for (uint32_t i = 0; i + 1 < n; ++i) {
    if (keys[i].key != keys[i + 1].key || (i + 2 < n && keys[i + 2].key == keys[i].key)) continue;
    neighbor[keys[i].index] = keys[i + 1].index;
    neighbor[keys[i + 1].index] = keys[i].index;
  }
  for (uint32_t i = 0; i < nt; ++i) {
    comp[i] = kNone;
    c[i] = Component{};
  }
  walk(*this, neighbor, comp, flip, queue, r);
  const Vec3 centre =
      mesh_bounds(mesh_view(Span<const Vec3>(v, nv), Span<const Triangle>(t, nt))).center();
  for (uint32_t i = 0; i < nt; ++i) {
    Component& k = c[comp[i]];
    const Vec3 &p0 = v[t[i].v[0]], &p1 = v[t[i].v[1]], &p2 = v[t[i].v[2]];
    const double sign = flip[i] != 0 ? -1.0 : 1.0;
    ++k.triangles;
    k.flipped += flip[i];
    k.open = k.open || neighbor[3 * i] == kNone || neighbor[3 * i + 1] == kNone ||
             neighbor[3 * i + 2] == kNone;
    k.normal = k.normal + cross(p1 - p0, p2 - p0) * sign;
    k.volume += sign * dot(p0 - centre, cross(p1 - centre, p2 - centre));
  }
  decide_turns(*this, comp, c);
  for (uint32_t i = 0; i < nt; ++i) {
    // Turned whole: most of its triangles turned (not a seed turned to agree with the rest).
    const Component& k = c[i];
    if (comp[i] == i &&
        2 * uint64_t{k.invert != 0 ? k.triangles - k.flipped : k.flipped} > k.triangles) {
      ++r->flipped_components;
    }
    if ((flip[i] ^ c[comp[i]].invert) == 0) continue;
    const uint32_t x = t[i].v[1];
    t[i].v[1] = t[i].v[2];
    t[i].v[2] = x;
    ++r->flipped_triangles;
  }
  return Status::ok();
}

// One loop from `start` along next[]; its length, or 0 when it is not a simple loop (a dead
// end, a vertex with two outgoing boundary edges, or a vertex already walked).
uint32_t trace_loop(uint32_t start, const uint32_t* next, uint8_t* state, uint32_t nv) {
  uint32_t x = start, length = 0;
  bool simple = true;
  do {
    if (state[x] == 2) simple = false;
    state[x] = state[x] == 2 ? 2 : 1;
    x = next[x];
    ++length;
    if (x == kNone || (x != start && state[x] != 0) || length > nv) {
      return 0;
    }
  } while (x != start);
  return simple ? length : 0;
}

// Fills the loop from `start` (its boundary half-edges run x -> next[x]; the fill runs the
// other way). False when a fill triangle would have zero area (nothing is added then).
bool fill_loop(Prep* p, uint32_t start, uint32_t length, const uint32_t* next) {
  if (length == 3) {
    const uint32_t a = start, b = next[a], c = next[b];
    if (collinear3d(p->v[a], p->v[b], p->v[c])) return false;
    p->t[p->nt++] = Triangle{{b, a, c}};
    ++p->r->hole_triangles;
    return true;
  }
  Vec3 sum{};
  uint32_t x = start;
  do {
    sum = sum + p->v[x];
    x = next[x];
  } while (x != start);
  // Rounded to float32: a scan's vertices are float32 (STL, PLY), and so the prepared mesh
  // stays what an STL holds, as the Boolean's float32 output needs of B.
  Vec3 m = sum * (1.0 / length);
  round_to_float32(&m);  // (finite and in range: the mean of float32 vertices)
  x = start;
  do {
    if (collinear3d(p->v[next[x]], p->v[x], m)) return false;
    x = next[x];
  } while (x != start);
  const uint32_t centre = p->nv++;
  p->v[centre] = m;
  do {
    p->t[p->nt++] = Triangle{{next[x], x, centre}};
    ++p->r->hole_triangles;
    x = next[x];
  } while (x != start);
  return true;
}

Status Prep::fill_holes() {
  ArenaScope scope(arena);
  KeyIndex* keys = nullptr;
  SPLINTCORE_RETURN_IF_ERROR(half_edges(&keys));
  const uint32_t n = 3 * nt, nv0 = nv;  // the fills add vertices past nv0
  uint32_t* next = arena.allocate_array<uint32_t>(nv0);
  uint32_t* tri = arena.allocate_array<uint32_t>(nv0);  // the triangle of a's boundary edge
  uint8_t* state = arena.allocate_array<uint8_t>(nv0);  // 0 free, 1 walked, 2 two outgoing
  if ((next == nullptr || tri == nullptr || state == nullptr) && nv0 > 0) {
    return arena.exhausted_status();
  }
  for (uint32_t i = 0; i < nv0; ++i) {
    next[i] = kNone;
    state[i] = 0;
  }
  for (uint32_t i = 0; i < n; ++i) {
    const bool single = (i == 0 || keys[i - 1].key != keys[i].key) &&
                        (i + 1 == n || keys[i + 1].key != keys[i].key);
    if (!single) continue;
    const uint32_t a = from(keys[i].index);
    if (next[a] != kNone) state[a] = 2;
    next[a] = to(keys[i].index);
    tri[a] = keys[i].index / 3;
  }
  for (uint32_t a = 0; a < nv0; ++a) {
    if (next[a] == kNone || state[a] == 1) continue;
    if (state[a] == 2) {
      ++r->holes_left;
      state[a] = 1;
      continue;
    }
    const uint32_t length = trace_loop(a, next, state, nv0);
    // Three edges of one triangle: a lone triangle, not a hole (its fill would be its back).
    const bool lone = length == 3 && tri[a] == tri[next[a]] && tri[a] == tri[next[next[a]]];
    if (length == 0 || lone || o.max_hole_edges == 0 || length > o.max_hole_edges ||
        !fill_loop(this, a, length, next)) {
      ++r->holes_left;
    } else {
      ++r->holes_filled;
    }
  }
  return Status::ok();
}

// Vertices no triangle uses go; the mesh is built above everything and moved down to `start`.
Status Prep::finish(const Arena::Marker& start, Mesh* out) {
  uint32_t* remap = arena.allocate_array<uint32_t>(nv);
  if (remap == nullptr && nv > 0) return arena.exhausted_status();
  for (uint32_t i = 0; i < nv; ++i) remap[i] = kNone;
  for (uint32_t i = 0; i < nt; ++i) {
    for (uint32_t x : t[i].v) remap[x] = 0;
  }
  uint32_t used = 0;
  for (uint32_t i = 0; i < nv; ++i) {
    if (remap[i] != kNone) remap[i] = used++;
  }
  r->unreferenced_vertices = nv - used;
  Triangle* tris = arena.allocate_array<Triangle>(nt);
  Vec3* verts = arena.allocate_array<Vec3>(used);
  if ((tris == nullptr && nt > 0) || (verts == nullptr && used > 0)) {
    return arena.exhausted_status();
  }
  for (uint32_t i = 0; i < nt; ++i) {
    tris[i] = Triangle{{remap[t[i].v[0]], remap[t[i].v[1]], remap[t[i].v[2]]}};
  }
  for (uint32_t i = 0; i < nv; ++i) {
    if (remap[i] != kNone) verts[remap[i]] = v[i];
  }
  r->output_vertices = used;
  r->output_triangles = nt;
  const Mesh built = mesh_view(Span<const Vec3>(verts, used), Span<const Triangle>(tris, nt));
  move_mesh_down(arena, start, built, out);
  return Status::ok();
}

// The input checked, copied into the working arrays (room for the vertices the splits and
// fills add, and the triangles the fills add).
Status load(const Mesh& mesh, Prep* p) {
  const uint32_t nv = static_cast<uint32_t>(mesh.vertices.size());
  const uint32_t nt = static_cast<uint32_t>(mesh.triangles.size());
  for (uint32_t i = 0; i < nv; ++i) {
    if (!is_finite(mesh.vertices[i])) {
      return make_error(StatusCode::kNonFinite, "prepare_scan: vertex ", i,
                        " is not finite (NaN or infinity)")
          .at_index(i);
    }
  }
  for (uint32_t i = 0; i < nt; ++i) {
    for (uint32_t x : mesh.triangles[i].v) {
      if (x >= nv) {
        return make_error(StatusCode::kInvalidMesh, "prepare_scan: triangle ", i,
                          " refers to vertex ", x, " but the mesh has ", nv, " vertices")
            .at_index(i);
      }
    }
  }
  p->v = p->arena.allocate_array<Vec3>(size_t{nv} + size_t{4} * nt);
  p->t = p->arena.allocate_array<Triangle>(size_t{4} * nt);
  if ((p->v == nullptr && nv + nt > 0) || (p->t == nullptr && nt > 0)) {
    return p->arena.exhausted_status();
  }
  if (nv > 0) std::memcpy(static_cast<void*>(p->v), mesh.vertices.data(), nv * sizeof(Vec3));
  if (nt > 0) std::memcpy(static_cast<void*>(p->t), mesh.triangles.data(), nt * sizeof(Triangle));
  p->nv = nv;
  p->nt = nt;
  return Status::ok();
}

Status run_steps(const Context& ctx, Prep* p) {
  SPLINTCORE_RETURN_IF_ERROR(p->remove_duplicates());
  SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "prepare: duplicates", 1, 7));
  p->remove_degenerate();
  SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "prepare: degenerate", 2, 7));
  SPLINTCORE_RETURN_IF_ERROR(p->resolve_nonmanifold_edges());
  SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "prepare: non-manifold edges", 3, 7));
  SPLINTCORE_RETURN_IF_ERROR(p->split_nonmanifold_vertices());
  SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "prepare: non-manifold vertices", 4, 7));
  SPLINTCORE_RETURN_IF_ERROR(p->remove_islands());
  SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "prepare: islands", 5, 7));
  SPLINTCORE_RETURN_IF_ERROR(p->orient());
  SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "prepare: orientation", 6, 7));
  SPLINTCORE_RETURN_IF_ERROR(p->fill_holes());
  return report_progress(ctx, "prepare: holes", 7, 7);
}

}  // namespace

uint64_t prepare_scan_bound(uint64_t vertex_count, uint64_t triangle_count) {
  const uint64_t v = vertex_count, t = triangle_count, vmax = v + 4 * t;
  const uint64_t work = arena_array_bound<Vec3>(vmax) + arena_array_bound<Triangle>(4 * t);
  const uint64_t edges = half_edges_bound(t);
  const uint64_t duplicates = 2 * arena_array_bound<KeyIndex>(t) + arena_array_bound<uint8_t>(t);
  const uint64_t nm_edges =
      edges + arena_array_bound<uint32_t>(3 * t) + arena_array_bound<uint8_t>(t);
  const uint64_t nm_vertices = edges + 2 * arena_array_bound<uint32_t>(3 * t) +
                               arena_array_bound<uint32_t>(vmax) + arena_array_bound<uint8_t>(vmax);
  const uint64_t islands = edges + 2 * arena_array_bound<uint32_t>(t) +
                           arena_array_bound<double>(t) + arena_array_bound<uint8_t>(t);
  const uint64_t orient = edges + arena_array_bound<uint32_t>(3 * t) +
                          2 * arena_array_bound<uint32_t>(t) + arena_array_bound<uint8_t>(t) +
                          arena_array_bound<Component>(t);
  const uint64_t holes =
      edges + 2 * arena_array_bound<uint32_t>(vmax) + arena_array_bound<uint8_t>(vmax);
  const uint64_t output = arena_array_bound<uint32_t>(vmax) + arena_array_bound<Triangle>(4 * t) +
                          arena_array_bound<Vec3>(vmax);
  const uint64_t steps[] = {duplicates, nm_edges, nm_vertices, islands, orient, holes, output};
  uint64_t step = 0;
  for (uint64_t s : steps) step = s > step ? s : step;
  return work + step;
}

Status prepare_scan(const Context& ctx, const Mesh& mesh, const PrepareOptions& options, Mesh* out,
                    PrepareReport* report) {
  *report = PrepareReport{};
  if (!out->vertices.empty() || !out->triangles.empty()) {
    return Status::error(StatusCode::kInvalidArgument, "prepare_scan: output mesh must be empty");
  }
  const uint64_t nv = mesh.vertices.size(), nt = mesh.triangles.size();
  if (nt >= (uint64_t{1} << 29) || nv + 4 * nt >= (uint64_t{1} << 32)) {
    return make_error(StatusCode::kLimitExceeded, "prepare_scan: mesh too large: ", nt,
                      " triangles, ", nv, " vertices (at most 2^29 triangles)");
  }
  if (!(options.min_island_area >= 0)) {
    return Status::error(StatusCode::kInvalidArgument,
                         "prepare_scan: min_island_area must be a number >= 0");
  }
  report->input_vertices = nv;
  report->input_triangles = nt;
  Arena& arena = *ctx.arena;
  ArenaScope scope(arena);  // on an error the arena is as it was
  Prep p{arena, options, report};
  SPLINTCORE_RETURN_IF_ERROR(load(mesh, &p));
  SPLINTCORE_RETURN_IF_ERROR(run_steps(ctx, &p));
  SPLINTCORE_RETURN_IF_ERROR(p.finish(scope.start(), out));
  scope.commit();
  return Status::ok();
}

}  // namespace splintcore
