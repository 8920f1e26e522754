// Vertex welding of STL triangle soup.
//
// Exact welding: an open-addressing hash table keyed on the corners' float32 bit patterns.
// Vertex ids are handed out in order of first appearance, so the output is a function of the
// soup alone (the hash only decides where entries sit, never an order that reaches output).
//
// Tolerance welding: corners are bucketed on a grid of cell size `tolerance`; corners in the
// same cell, or within tolerance (max-norm) across neighbouring cells, are united
// (union-find). Each component becomes one vertex at its lexicographically smallest corner,
// which makes positions independent of the order of the soup.
#include "core/union_find.h"
#include "mesh/exact_weld.h"
#include "splintcore/mesh.h"

namespace splintcore {

namespace {

inline Vec3 to_vec3(const float* p) {
  // -0 becomes +0 here too, so the mesh never holds a negative zero from the soup.
  return {static_cast<double>(p[0]) + 0.0, static_cast<double>(p[1]) + 0.0,
          static_cast<double>(p[2]) + 0.0};
}

// The exact weld's limit: an id for every corner in 32 bits.
Status check_triangle_count(uint64_t count) {
  if (count > (uint64_t{UINT32_MAX} - 1) / 3) {
    return make_error(StatusCode::kLimitExceeded, "mesh has ", count, " triangles; at most ",
                      (uint64_t{UINT32_MAX} - 1) / 3, " are supported (32-bit vertex ids)");
  }
  return Status::ok();
}

Status check_soup(Span<const SoupTriangle> soup) {
  SPLINTCORE_RETURN_IF_ERROR(check_triangle_count(soup.size()));
  for (size_t t = 0; t < soup.size(); ++t) {
    for (int k = 0; k < 3; ++k) {
      for (int a = 0; a < 3; ++a) {
        if (!is_finite(soup[t].p[k][a])) {
          return make_error(StatusCode::kNonFinite, "triangle ", t, " corner ", k,
                            " has a non-finite coordinate (NaN or infinity)")
              .at_index(t);
        }
      }
    }
  }
  return Status::ok();
}

// Copies the `count` vertices at `source` into a fresh arena allocation made after rewinding to
// `marker` (the temporaries between are dropped), and points `out` at it.
Status compact_vertices(Arena& arena, const Arena::Marker& marker, const Vec3* source, size_t count,
                        ArenaArray<Vec3>* out) {
  arena.rewind(marker);
  Vec3* target = arena.allocate_array<Vec3>(count);
  if (target == nullptr && count > 0) return arena.exhausted_status();  // cannot happen: it fit
  if (count > 0) std::memmove(static_cast<void*>(target), source, count * sizeof(Vec3));
  out->adopt(target, count, count);
  return Status::ok();
}

}  // namespace

uint64_t exact_weld_table_slots(uint64_t corners) {
  uint64_t size = 16;
  while (size < corners + corners / 2) size <<= 1;
  return size;
}

namespace {
// A closed mesh has about one vertex per two triangles: the positions first reserved, and
// the table's first size (load at most 2/3 there).
uint64_t expected_vertices(uint64_t triangle_count) {
  const uint64_t expected = triangle_count / 2 + triangle_count / 16 + 16;
  return expected < 3 * triangle_count ? expected : 3 * triangle_count;
}
}  // namespace

bool ExactWelder::init(Arena& arena, uint64_t triangle_count) {
  return init_corners(arena, 3 * triangle_count, expected_vertices(triangle_count));
}

bool ExactWelder::init_corners(Arena& arena, uint64_t corners, uint64_t expected) {
  // The positions first, where they stay unless they outgrow the reserve (then they move to
  // the top of the arena and grow there).
  positions_.bind(&arena);
  if (!positions_.reserve(static_cast<size_t>(expected))) return false;
  reserved_ = positions_.data();
  after_reserve_ = arena.mark();
  table_slots_ = exact_weld_table_slots(corners);
  table_ = arena.allocate_array<uint32_t>(static_cast<size_t>(table_slots_));
  if (table_ == nullptr) return false;
  id_mask_ = 1;
  while (id_mask_ < corners + 1 && id_mask_ != UINT32_MAX) id_mask_ = 2 * id_mask_ + 1;
  uint64_t slots = 16;
  while (slots < expected + expected / 2 && slots < table_slots_) slots <<= 1;
  mask_ = slots - 1;
  grow_at_ = slots == table_slots_ ? UINT64_MAX : slots / 3 * 2;
  std::memset(table_, 0, static_cast<size_t>(slots) * sizeof(uint32_t));
  return true;
}

uint32_t ExactWelder::add_vertex(double x, double y, double z, uint32_t tag, uint64_t slot) {
  const uint32_t id = static_cast<uint32_t>(positions_.size());
  if (!positions_.push_back(Vec3{x + 0.0, y + 0.0, z + 0.0})) return kFull;
  table_[slot] = tag | (id + 1);
  if (positions_.size() > grow_at_) grow();
  return id;
}

void ExactWelder::grow() {
  const uint64_t slots = 2 * (mask_ + 1);
  mask_ = slots - 1;
  grow_at_ = slots == table_slots_ ? UINT64_MAX : slots / 3 * 2;
  std::memset(table_, 0, static_cast<size_t>(slots) * sizeof(uint32_t));
  const Vec3* v = positions_.data();
  const uint32_t n = static_cast<uint32_t>(positions_.size());
  for (uint32_t id = 0; id < n; ++id) {
    // Back to the float corner (exact: every position came from a float).
    const float p[3] = {static_cast<float>(v[id].x), static_cast<float>(v[id].y),
                        static_cast<float>(v[id].z)};
    const uint64_t h = hash(p);
    uint64_t slot = h & mask_;
    while (table_[slot] != 0) slot = (slot + 1) & mask_;
    table_[slot] = tag_of(h) | (id + 1);
  }
}

void ExactWelder::finish(Arena& arena, const Arena::Marker& marker, ArenaArray<Vec3>* vertices) {
  const size_t count = positions_.size();
  if (positions_.data() == reserved_) {  // still in the reserve: give back its unused end
    arena.rewind(after_reserve_);
    (void)arena.try_shrink(reserved_, positions_.capacity() * sizeof(Vec3), count * sizeof(Vec3));
    vertices->adopt(reserved_, count, count);
    return;
  }
  Vec3* target = nullptr;
  {
    ArenaMover mover(arena, marker);  // (refused in an arena of blocks: they stay, the top above)
    target = mover.move(positions_.data(), count);
  }
  vertices->adopt(target, count, count);
}

// The triangles, the positions' reserve, the table (allocated whole, used in part), the
// positions when they outgrow the reserve (at most one per corner, grown at the top of the
// arena; copied down over the rest at the end).
uint64_t weld_exact_bound(uint64_t triangle_count) {
  const uint64_t corners = 3 * triangle_count;
  return arena_array_bound<Triangle>(triangle_count) +
         arena_array_bound<Vec3>(expected_vertices(triangle_count)) +
         arena_array_bound<uint32_t>(exact_weld_table_slots(corners)) +
         arena_array_bound<Vec3>(corners);
}

// Per vertex its distinct vertex, the welder's positions (one per vertex at most) and its
// table (the table is given back before the ids by first use are allocated, but it may be
// smaller than them).
uint64_t weld_indexed_exact_bound(uint64_t vertex_count) {
  const uint64_t table = arena_array_bound<uint32_t>(exact_weld_table_slots(vertex_count));
  const uint64_t ids = arena_array_bound<uint32_t>(vertex_count);
  return arena_array_bound<uint32_t>(vertex_count) + arena_array_bound<Vec3>(vertex_count) +
         (table > ids ? table : ids);
}

Status weld_indexed_exact(const Context& ctx, Mesh* mesh) {
  Arena& arena = *ctx.arena;
  SPLINTCORE_RETURN_IF_ERROR(check_triangle_count(mesh->triangles.size()));
  if (mesh->vertices.size() > uint64_t{UINT32_MAX} - 1) {
    return make_error(StatusCode::kLimitExceeded, "mesh has ", mesh->vertices.size(),
                      " vertices; at most ", uint64_t{UINT32_MAX} - 1,
                      " are supported (32-bit vertex ids)");
  }
  const uint32_t nv = static_cast<uint32_t>(mesh->vertices.size());
  ArenaScope scope(arena);
  // Each vertex's distinct vertex (ids by first appearance in the vertex array).
  uint32_t* distinct = arena.allocate_array<uint32_t>(nv);
  if (distinct == nullptr && nv > 0) return arena.exhausted_status();
  const Arena::Marker welder_start = arena.mark();
  ExactWelder welder;
  if (!welder.init_corners(arena, nv, nv)) return arena.exhausted_status();
  const Vec3* in = mesh->vertices.data();
  auto bits = [](double coordinate) {  // a float32 value's bits (the conversion is exact)
    const float f = static_cast<float>(coordinate);
    uint32_t b;
    std::memcpy(&b, &f, sizeof(b));
    return b;
  };
  for (uint32_t i = 0; i < nv; ++i) {
    if ((i & 0xffff) == 0) SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "weld", i, nv));
    if (i + 32 < nv) {  // the slot of a vertex ahead, about a memory latency
      const Vec3& a = in[i + 32];
      __builtin_prefetch(
          welder.first_slot(ExactWelder::hash_bits(bits(a.x), bits(a.y), bits(a.z))));
    }
    const uint32_t x = bits(in[i].x), y = bits(in[i].y), z = bits(in[i].z);
    const uint32_t id = welder.vertex(x, y, z, ExactWelder::hash_bits(x, y, z));
    if (id == ExactWelder::kFull) return arena.exhausted_status();
    distinct[i] = id;
  }
  ArenaArray<Vec3> positions(&arena);
  welder.finish(arena, welder_start, &positions);  // (the table given back)
  // Ids by first use in the triangles, as weld_exact() hands them out: the first corner of a
  // distinct vertex takes the next id, and its position goes there in the vertex array (the
  // input positions are no longer read; a vertex never used is dropped).
  const uint32_t nd = static_cast<uint32_t>(positions.size());
  uint32_t* first = arena.allocate_array<uint32_t>(nd);
  if (first == nullptr && nd > 0) return arena.exhausted_status();
  if (nd > 0) std::memset(first, 0xff, size_t{nd} * sizeof(uint32_t));
  Vec3* out = mesh->vertices.data();
  Triangle* tris = mesh->triangles.data();
  uint32_t used = 0;
  for (size_t t = 0; t < mesh->triangles.size(); ++t) {
    for (uint32_t& v : tris[t].v) {
      const uint32_t d = distinct[v];
      if (first[d] == UINT32_MAX) {
        out[used] = positions[d];
        first[d] = used++;
      }
      v = first[d];
    }
  }
  mesh->vertices.shrink_size(used);
  return Status::ok();
}

// The triangles, the sort keys, then either the radix sort's scratch (returned) or the
// union-find, the two per-corner tables and the positions (at most one per corner); the
// vertices are then copied down over the temporaries.
uint64_t weld_tolerance_bound(uint64_t triangle_count) {
  const uint64_t corners = 3 * triangle_count;
  const uint64_t sort = arena_array_bound<KeyIndex>(corners);
  const uint64_t sets = 3 * arena_array_bound<uint32_t>(corners) + arena_array_bound<Vec3>(corners);
  return arena_array_bound<Triangle>(triangle_count) + arena_array_bound<KeyIndex>(corners) +
         (sort > sets ? sort : sets);
}

namespace {

// The bodies of weld_exact and weld_tolerance; their public wrappers below check that `out` is
// empty and, on an error, rewind the arena to where it was at entry and empty `out` again.
Status weld_exact_steps(const Context& ctx, Span<const SoupTriangle> soup, Mesh* out) {
  Arena& arena = *ctx.arena;
  SPLINTCORE_RETURN_IF_ERROR(check_soup(soup));
  const size_t n = soup.size();
  if (n == 0) return Status::ok();
  if (!out->triangles.resize(n)) return arena.exhausted_status();

  const Arena::Marker temp_start = arena.mark();
  ExactWelder welder;
  if (!welder.init(arena, n)) return arena.exhausted_status();
  const float* corners = &soup.data()[0].p[0][0];
  Triangle* tris = out->triangles.data();
  for (size_t t = 0; t < n; ++t) {
    if ((t & 0xffff) == 0) {
      SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "weld", t, n));
    }
    if (t + 32 < n) {  // the slots of a triangle ahead, about a memory latency
      const float* ahead = corners + 9 * (t + 32);
      __builtin_prefetch(welder.first_slot(ExactWelder::hash(ahead)));
      __builtin_prefetch(welder.first_slot(ExactWelder::hash(ahead + 3)));
      __builtin_prefetch(welder.first_slot(ExactWelder::hash(ahead + 6)));
    }
    if (!welder.add(corners + 9 * t, tris + t)) return arena.exhausted_status();
  }
  welder.finish(arena, temp_start, &out->vertices);
  return Status::ok();
}

// The stages of weld_tolerance: the corners' grid cells, sorted; cells joined by union-find;
// then one vertex per component at its smallest corner.
struct ToleranceWeld {
  ToleranceWeld(Arena& a, const float* c, uint32_t count, double t)
      : arena(a), corners(c), corner_count(count), tolerance(t) {}

  Arena& arena;
  const float* corners;
  uint32_t corner_count;
  double tolerance;
  double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL};
  KeyIndex* items = nullptr;  // (cell key, corner), sorted by key
  UnionFind sets;

  double coordinate(uint32_t c, int a) const {
    return static_cast<double>(corners[3 * size_t{c} + static_cast<size_t>(a)]);
  }
  static uint64_t cell_key(uint64_t cx, uint64_t cy, uint64_t cz) {
    return (cx << 42) | (cy << 21) | cz;
  }
  uint64_t cell_of(uint32_t c, int a) const {
    return static_cast<uint64_t>((coordinate(c, a) - lo[a]) / tolerance) + 1;  // >= 1: room for -1
  }
  bool within(uint32_t a, uint32_t b) const {
    for (int k = 0; k < 3; ++k) {
      const double d = coordinate(a, k) - coordinate(b, k);
      if (d > tolerance || d < -tolerance) return false;
    }
    return true;
  }
  // Lexicographic order of two corners' positions.
  bool less(uint32_t a, uint32_t b) const {
    for (int k = 0; k < 3; ++k) {
      const float fa = corners[3 * size_t{a} + static_cast<size_t>(k)];
      const float fb = corners[3 * size_t{b} + static_cast<size_t>(k)];
      if (fa < fb) return true;
      if (fb < fa) return false;
    }
    return false;
  }

  // Cells must fit in 21 bits per axis after offsetting, for a 63-bit key.
  Status check_extent() {
    double hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
    for (uint32_t c = 0; c < corner_count; ++c) {
      for (int a = 0; a < 3; ++a) {
        const double x = coordinate(c, a);
        lo[a] = x < lo[a] ? x : lo[a];
        hi[a] = x > hi[a] ? x : hi[a];
      }
    }
    for (int a = 0; a < 3; ++a) {
      if (corner_count > 0 && (hi[a] - lo[a]) / tolerance > double{(1 << 20) - 2}) {
        return make_error(StatusCode::kLimitExceeded, "weld tolerance ", tolerance,
                          " mm is too small for a mesh ", hi[a] - lo[a],
                          " mm across (at most 2^20 cells per axis)");
      }
    }
    return Status::ok();
  }

  Status sort_cells() {
    items = arena.allocate_array<KeyIndex>(corner_count);
    if (items == nullptr && corner_count > 0) return arena.exhausted_status();
    for (uint32_t c = 0; c < corner_count; ++c) {
      items[c] = KeyIndex{cell_key(cell_of(c, 0), cell_of(c, 1), cell_of(c, 2)), c, 0};
    }
    return radix_sort(arena, Span<KeyIndex>(items, corner_count));
  }

  // The run of items with `key` by binary search: [*begin, returned end).
  uint32_t find_run(uint64_t key, uint32_t* begin) const {
    uint32_t a = 0, b = corner_count;
    while (a < b) {
      const uint32_t m = a + (b - a) / 2;
      if (items[m].key < key)
        a = m + 1;
      else
        b = m;
    }
    *begin = a;
    uint32_t e = a;
    while (e < corner_count && items[e].key == key) ++e;
    return e;
  }

  // For each cell run, unite it with itself and with the 13 neighbours that come after it in
  // key order (the other 13 see this cell as their forward neighbour).
  void join_cells() {
    static const int kForward[13][3] = {{1, -1, -1}, {1, -1, 0}, {1, -1, 1}, {1, 0, -1}, {1, 0, 0},
                                        {1, 0, 1},   {1, 1, -1}, {1, 1, 0},  {1, 1, 1},  {0, 1, -1},
                                        {0, 1, 0},   {0, 1, 1},  {0, 0, 1}};
    uint32_t run_begin = 0;
    while (run_begin < corner_count) {
      uint32_t run_end = run_begin;
      while (run_end < corner_count && items[run_end].key == items[run_begin].key) ++run_end;
      const uint64_t key = items[run_begin].key;
      const uint64_t cx = key >> 42, cy = (key >> 21) & 0x1fffff, cz = key & 0x1fffff;
      // Corners in one cell are less than `tolerance` apart on every axis: one component.
      for (uint32_t i = run_begin + 1; i < run_end; ++i) {
        sets.unite(items[run_begin].index, items[i].index);
      }
      // Two cells join when any pair across them is within tolerance; one pair is enough.
      for (const auto& d : kForward) {
        uint32_t nb = 0;
        const uint32_t ne =
            find_run(cell_key(cx + static_cast<uint64_t>(d[0]), cy + static_cast<uint64_t>(d[1]),
                              cz + static_cast<uint64_t>(d[2])),
                     &nb);
        join_runs(run_begin, run_end, nb, ne);
      }
      run_begin = run_end;
    }
  }
  void join_runs(uint32_t begin, uint32_t end, uint32_t nb, uint32_t ne) {
    for (uint32_t i = begin; i < end; ++i) {
      for (uint32_t j = nb; j < ne; ++j) {
        if (within(items[i].index, items[j].index)) {
          sets.unite(items[i].index, items[j].index);
          return;
        }
      }
    }
  }

  // Representative corner of each component: the lexicographically smallest position; vertex
  // ids by first use in corner order.
  Status number_vertices(Triangle* tris, const Arena::Marker& temp_start, Mesh* out) {
    uint32_t* best = arena.allocate_array<uint32_t>(corner_count);
    uint32_t* id_of_root = arena.allocate_array<uint32_t>(corner_count);
    if ((best == nullptr || id_of_root == nullptr) && corner_count > 0) {
      return arena.exhausted_status();
    }
    for (uint32_t c = 0; c < corner_count; ++c) {
      best[c] = c;
      id_of_root[c] = UINT32_MAX;
    }
    for (uint32_t c = 0; c < corner_count; ++c) {
      const uint32_t r = sets.find(c);
      if (less(c, best[r])) best[r] = c;
    }
    uint32_t vertex_count = 0;
    for (uint32_t c = 0; c < corner_count; ++c) {
      const uint32_t r = sets.find(c);
      if (id_of_root[r] == UINT32_MAX) id_of_root[r] = vertex_count++;
      tris[c / 3].v[c % 3] = id_of_root[r];
    }
    Vec3* positions = arena.allocate_array<Vec3>(vertex_count);
    if (positions == nullptr && vertex_count > 0) return arena.exhausted_status();
    for (uint32_t c = 0; c < corner_count; ++c) {
      const uint32_t r = sets.find(c);
      positions[id_of_root[r]] = to_vec3(corners + 3 * size_t{best[r]});
    }
    return compact_vertices(arena, temp_start, positions, vertex_count, &out->vertices);
  }
};

Status weld_tolerance_steps(const Context& ctx, Span<const SoupTriangle> soup, double tolerance,
                            Mesh* out) {
  Arena& arena = *ctx.arena;
  if (!is_finite(tolerance) || !(tolerance > 0.0)) {
    return make_error(StatusCode::kInvalidArgument, "weld tolerance must be > 0 mm, got ",
                      tolerance);
  }
  SPLINTCORE_RETURN_IF_ERROR(check_soup(soup));
  const size_t n = soup.size();
  if (n == 0) return Status::ok();
  ToleranceWeld weld(arena, &soup.data()[0].p[0][0], static_cast<uint32_t>(3 * n), tolerance);
  SPLINTCORE_RETURN_IF_ERROR(weld.check_extent());
  if (!out->triangles.resize(n)) return arena.exhausted_status();
  const Arena::Marker temp_start = arena.mark();
  SPLINTCORE_RETURN_IF_ERROR(weld.sort_cells());
  if (!weld.sets.init(arena, weld.corner_count)) return arena.exhausted_status();
  weld.join_cells();
  return weld.number_vertices(out->triangles.data(), temp_start, out);
}

// A failed weld leaves nothing: the arena as it was (the caller's scope), `out` empty.
Status undo_on_error(Status s, ArenaScope& scope, const Mesh& saved, Mesh* out) {
  if (s.is_ok()) {
    scope.commit();
  } else {
    *out = saved;
  }
  return s;
}

}  // namespace

Status weld_exact(const Context& ctx, Span<const SoupTriangle> soup, Mesh* out) {
  if (!out->vertices.empty() || !out->triangles.empty()) {
    return Status::error(StatusCode::kInvalidArgument, "weld_exact: output mesh must be empty");
  }
  ArenaScope scope(*ctx.arena);
  const Mesh saved = *out;
  return undo_on_error(weld_exact_steps(ctx, soup, out), scope, saved, out);
}

Status weld_tolerance(const Context& ctx, Span<const SoupTriangle> soup, double tolerance,
                      Mesh* out) {
  if (!out->vertices.empty() || !out->triangles.empty()) {
    return Status::error(StatusCode::kInvalidArgument, "weld_tolerance: output mesh must be empty");
  }
  ArenaScope scope(*ctx.arena);
  const Mesh saved = *out;
  return undo_on_error(weld_tolerance_steps(ctx, soup, tolerance, out), scope, saved, out);
}

}  // namespace splintcore
