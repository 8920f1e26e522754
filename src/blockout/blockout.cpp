// Interference elimination (Chen et al. 2016, "The Interference Elimination"): the splint
// minus the jaws' swept volume, by the exact Boolean (boolean.h) on the swept volume's mesh.
#include <cmath>
#include <cstring>

#include "core/fminmax.h"
#include "core/union_find.h"
#include "splintcore/blockout.h"
#include "splintcore/distance.h"

namespace splintcore {

namespace {

// The swept surface is filtered as it leaves the extractor: only its triangles that can
// matter to the splint are kept (SweepOptions::keep_triangle), which is all the Boolean needs.
// A coarse grid over the splint's box (cells of kCellVoxels voxels a side) marks the cells
// whose box meets a splint triangle's box (surface cells), the outside (reached from the
// grid's border face to face through unmarked cells: a path into the splint would cross its
// closed surface in a marked cell) and, left unmarked, the enclosed cells, wholly inside; and
// the cells within one cell (26 neighbours) of a cell not outside. A swept triangle is left
// out when its box meets no such cell; kept when it meets no surface cell but an enclosed
// one; else, near the surface, kept unless triangle_side (distance.h) finds it wholly outside
// and at least kReachVoxels from every splint triangle (one closest-point query from its first
// corner, which decides alone when that corner is farther than the triangle's extent plus the
// reach; else the exact triangle_near_mesh, meeting decided exactly). So every swept triangle that
// meets the splint is kept and every one left out is outside it, at least kReachVoxels from it: the
// kept part's open border lies outside the splint, as the Boolean needs of an open B. The imprint
// the sweep reproduces (the inset surface, just inside the jaw, in the splint's cavity) is most of
// the swept surface and is left out. The grid's border is two cells beyond the splint's box, so it
// starts unmarked.
constexpr double kCellVoxels = 5;
constexpr double kReachVoxels = 0.125;
constexpr uint8_t kSurface = 1, kOutside = 2, kNear = 4, kGrowX = 8, kGrowY = 16;
// The fine test's window (triangle_side_among): the splint triangles near a box that holds the
// swept triangle with kWindowVoxels to spare on every side, within kWindowReachVoxels of it;
// it serves the triangles that come next while they stay inside that box (the extractor goes
// cell by cell, row by row). At most kWindowTriangles of them (else the tree answers).
constexpr double kWindowVoxels = 1.5;
constexpr double kWindowReachVoxels = 1.5;
constexpr size_t kWindowTriangles = 1024;
// Points whose side is known, kHintSlots a task, by the cube (of the window's growth a side)
// they lie in: when the window moves on (a new row of cells), one from the same cube lies in it
// and may start the count of crossings (triangle_side_among's hint) instead of a closest-point
// search.
constexpr uint32_t kHintSlots = 1024;
// A hint in a slot: the swept triangles' corners are float32 (the extractor's log), so a point
// is kept in 12 bytes, exactly.
struct KeptHint {
  float p[3] = {0, 0, 0};
  TriangleSide side = TriangleSide::kNear;
};
// The filter's copies for the extractor's tasks (SweepOptions::keep_tasks).
constexpr uint32_t kKeepTasks = 4;

struct NearSplint {
  Vec3 origin{};
  double cell = 0;
  int64_t n[3] = {0, 0, 0};
  uint8_t* flags = nullptr;              // x fastest
  const DistanceIndex* index = nullptr;  // the splint's: the fine test (null: cells only)
  double reach = 0;                      // mm: kept when at most this far from the splint
  mutable uint32_t seed = kNoNeighbor;   // the last fine test's closest splint triangle
  // The window (kWindowTriangles ids from the arena); empty box: none yet.
  double window_grow = 0, window_reach = 0;  // mm
  uint32_t* window_ids = nullptr;
  Aabb* window_boxes = nullptr;  // the window's triangles' bounds (kWindowTriangles)
  mutable Aabb window;
  mutable size_t window_count = 0;  // kWindowTriangles + 1: too many, the tree answers
  mutable SideHint hint;            // the last side found, while it lies in the window
  KeptHint* hints = nullptr;        // kHintSlots (see above)
};

// The slot of hints for the cube that holds p.
KeptHint& hint_slot(const NearSplint& g, const Vec3& p) {
  uint32_t h = 0;
  for (int k = 0; k < 3; ++k) {
    const double f = std::floor((p[k] - g.origin[k]) / g.window_grow);
    const int64_t i = f < 0 ? -1 : (f > 1e9 ? 1000000000 : static_cast<int64_t>(f));
    h = h * 0x9E3779B1u + static_cast<uint32_t>(i);
  }
  return g.hints[(h ^ (h >> 15)) & (kHintSlots - 1)];
}

// p's side (not kNear), into its slot when p is float32 (the swept triangles' corners are).
void keep_hint(const NearSplint& g, const Vec3& p, TriangleSide side) {
  const float f[3] = {static_cast<float>(p.x), static_cast<float>(p.y), static_cast<float>(p.z)};
  if (side == TriangleSide::kNear || static_cast<double>(f[0]) != p.x ||
      static_cast<double>(f[1]) != p.y || static_cast<double>(f[2]) != p.z) {
    return;
  }
  KeptHint& slot = hint_slot(g, p);
  for (int k = 0; k < 3; ++k) slot.p[k] = f[k];
  slot.side = side;
}

// The fine test of a swept triangle near the splint's surface (see the top): from the window
// when it holds the triangle and decides, else by the tree.
TriangleSide fine_side(const NearSplint& g, const Aabb& box, const Vec3& p, const Vec3& q,
                       const Vec3& r) {
  if (g.window_ids != nullptr) {
    if (g.window.empty() || !g.window.contains(box.lo) || !g.window.contains(box.hi)) {
      const Vec3 grow{g.window_grow, g.window_grow, g.window_grow};
      g.window = Aabb{box.lo - grow, box.hi + grow};
      const Vec3 reach{g.window_reach, g.window_reach, g.window_reach};
      g.window_count =
          triangles_meeting_box(*g.index, Aabb{g.window.lo - reach, g.window.hi + reach},
                                g.window_ids, kWindowTriangles, g.window_boxes);
    }
    // The hint's point and p lie in the window, and so does the segment between them: every
    // splint triangle it meets is among the window's.
    if (g.hint.side == TriangleSide::kNear || !g.window.contains(g.hint.point)) {
      const KeptHint& kept = hint_slot(g, p);
      const Vec3 at{static_cast<double>(kept.p[0]), static_cast<double>(kept.p[1]),
                    static_cast<double>(kept.p[2])};
      g.hint = kept.side != TriangleSide::kNear && g.window.contains(at) ? SideHint{at, kept.side}
                                                                         : SideHint{};
    }
    TriangleSide side = TriangleSide::kOutside;
    ClosestPoint closest;
    closest.triangle = g.seed;  // left so when the hint decides: the seed stays
    if (g.window_count <= kWindowTriangles &&
        triangle_side_among(*g.index, g.window_ids, g.window_count, g.window_reach, p, q, r,
                            g.reach, &side, &closest, g.seed, g.window_boxes, &g.hint)) {
      g.seed = closest.triangle;
      keep_hint(g, p, side);
      return side;
    }
  }
  const TriangleSide side = triangle_side(*g.index, p, q, r, g.reach, &g.seed);
  if (g.hints != nullptr) {
    g.hint = side != TriangleSide::kNear ? SideHint{p, side} : SideHint{};
    keep_hint(g, p, side);
  }
  return side;
}

inline size_t cell_at(const NearSplint& g, int64_t x, int64_t y, int64_t z) {
  return static_cast<size_t>((z * g.n[1] + y) * g.n[0] + x);
}

// The cells a box [lo, hi] may meet (clamped to the grid; a margin of a thousandth of a cell
// against the rounding of the division). False when it misses the grid.
bool cell_range(const NearSplint& g, const Vec3& lo, const Vec3& hi, int64_t* a, int64_t* b) {
  for (int k = 0; k < 3; ++k) {
    const double f0 = std::floor((lo[k] - g.origin[k]) / g.cell - 1e-3);
    const double f1 = std::floor((hi[k] - g.origin[k]) / g.cell + 1e-3);
    if (f1 < 0 || f0 > static_cast<double>(g.n[k] - 1)) return false;
    a[k] = f0 < 0 ? 0 : static_cast<int64_t>(f0);
    b[k] = f1 > static_cast<double>(g.n[k] - 1) ? g.n[k] - 1 : static_cast<int64_t>(f1);
  }
  return true;
}

bool near_splint(const void* user, const Vec3& p, const Vec3& q, const Vec3& r) {
  const NearSplint& g = *static_cast<const NearSplint*>(user);
  Aabb box;
  box.add(p);
  box.add(q);
  box.add(r);
  int64_t a[3], b[3];
  if (!cell_range(g, box.lo, box.hi, a, b)) return false;
  bool near = false, surface = false, enclosed = false;
  for (int64_t z = a[2]; z <= b[2]; ++z) {
    for (int64_t y = a[1]; y <= b[1]; ++y) {
      for (int64_t x = a[0]; x <= b[0]; ++x) {
        const uint8_t f = g.flags[cell_at(g, x, y, z)];
        near = near || (f & kNear) != 0;
        surface = surface || (f & kSurface) != 0;
        enclosed = enclosed || (f & (kSurface | kOutside)) == 0;
      }
    }
  }
  if (!near) return false;
  if (g.index == nullptr) return true;
  // Cells that do not meet the surface lie wholly inside or wholly outside: the triangle
  // (within them) is inside when one is enclosed, outside when all are outside.
  if (!surface) return enclosed;
  // Near the surface: kept when it comes within reach of a splint triangle (meeting included,
  // decided exactly); else it lies at least that far from the surface, wholly on the side of
  // its first corner. The extractor's triangles come in order, each near the one before it:
  // a window of splint triangles serves the next ones, the last side found nearby (a hint: the
  // splint is closed and does not cross itself) gives the next one's by counting crossings, and
  // the previous answer seeds the tree's query (the answer depends on none of them).
  return fine_side(g, box, p, q, r) != TriangleSide::kOutside;
}

// Marks the outside: from the border, face to face through unmarked cells, by forward and
// backward raster passes until one changes nothing (no queue: the grid is the state).
void flood_outside(NearSplint& g) {
  const int64_t nx = g.n[0], ny = g.n[1], nz = g.n[2];
  for (int64_t z = 0; z < nz; ++z) {
    for (int64_t y = 0; y < ny; ++y) {
      for (int64_t x = 0; x < nx; ++x) {
        const bool border = x == 0 || y == 0 || z == 0 || x == nx - 1 || y == ny - 1 || z == nz - 1;
        uint8_t& f = g.flags[cell_at(g, x, y, z)];
        if (border && f == 0) f = kOutside;
      }
    }
  }
  const int64_t step[3] = {1, nx, nx * ny};
  for (bool changed = true; changed;) {
    changed = false;
    for (int pass = 0; pass < 2; ++pass) {
      const int64_t total = nx * ny * nz;
      for (int64_t n = 0; n < total; ++n) {
        const int64_t i = pass == 0 ? n : total - 1 - n;
        if (g.flags[i] != 0) continue;
        const int64_t x = i % nx, y = (i / nx) % ny, z = i / (nx * ny);
        if (x == 0 || y == 0 || z == 0 || x == nx - 1 || y == ny - 1 || z == nz - 1) continue;
        for (int k = 0; k < 3; ++k) {
          if (g.flags[i - step[k]] == kOutside || g.flags[i + step[k]] == kOutside) {
            g.flags[i] = kOutside;
            changed = true;
            break;
          }
        }
      }
    }
  }
}

// kNear: within one cell (26 neighbours) of a cell not outside; separably along x, y, z.
void grow_near(NearSplint& g) {
  const int64_t nx = g.n[0], ny = g.n[1], nz = g.n[2];
  const int64_t step[3] = {1, nx, nx * ny};
  const uint8_t from[3] = {0, kGrowX, kGrowY}, to[3] = {kGrowX, kGrowY, kNear};
  for (int k = 0; k < 3; ++k) {
    for (int64_t z = 0; z < nz; ++z) {
      for (int64_t y = 0; y < ny; ++y) {
        for (int64_t x = 0; x < nx; ++x) {
          const int64_t c[3] = {x, y, z};
          const size_t i = cell_at(g, x, y, z);
          auto has = [&](size_t j) {
            return k == 0 ? (g.flags[j] & kOutside) == 0 : (g.flags[j] & from[k]) != 0;
          };
          bool v = has(i);
          if (!v && c[k] > 0) v = has(i - static_cast<size_t>(step[k]));
          if (!v && c[k] + 1 < g.n[k]) v = has(i + static_cast<size_t>(step[k]));
          if (v) g.flags[i] |= to[k];
        }
      }
    }
  }
}

// The grid over the splint's box and its flags (a byte per cell, from the arena).
Status mark_near_splint(Arena& arena, const Mesh& splint, const Aabb& bounds, double voxel,
                        NearSplint* g) {
  g->cell = kCellVoxels * voxel;
  g->origin = bounds.lo - Vec3{2 * g->cell, 2 * g->cell, 2 * g->cell};
  uint64_t total = 1;
  for (int k = 0; k < 3; ++k) {
    const double cells = std::floor((bounds.hi[k] - bounds.lo[k]) / g->cell) + 5;
    if (!(cells < 1048576.0)) {
      return make_error(StatusCode::kLimitExceeded, "the splint spans ", cells, " cells of ",
                        g->cell, " mm (at most 2^20 per axis)");
    }
    g->n[k] = static_cast<int64_t>(cells);
    if (!checked_mul(total, static_cast<uint64_t>(cells), &total) || total > SIZE_MAX) {
      return make_error(StatusCode::kLimitExceeded, "the splint's cell grid is too large");
    }
  }
  g->flags = arena.allocate_array<uint8_t>(static_cast<size_t>(total));
  if (g->flags == nullptr) return arena.exhausted_status();
  std::memset(g->flags, 0, static_cast<size_t>(total));
  for (size_t i = 0; i < splint.triangles.size(); ++i) {
    const Triangle& t = splint.triangles[i];
    Aabb box;
    for (int k = 0; k < 3; ++k) {
      if (t.v[k] >= splint.vertices.size()) {
        return make_error(StatusCode::kInvalidMesh,
                          "a splint triangle has a vertex id out of range")
            .at_index(i);
      }
      box.add(splint.vertices[t.v[k]]);
    }
    int64_t a[3], b[3];
    if (!cell_range(*g, box.lo, box.hi, a, b)) continue;
    for (int64_t z = a[2]; z <= b[2]; ++z) {
      for (int64_t y = a[1]; y <= b[1]; ++y) {
        for (int64_t x = a[0]; x <= b[0]; ++x) g->flags[cell_at(*g, x, y, z)] = kSurface;
      }
    }
  }
  flood_outside(*g);
  grow_near(*g);
  return Status::ok();
}

// The swept mesh (sweep_volume_mesh), with `filter` only its triangles near the splint: the
// cells and the splint's distance index are made first and the mesh is moved down over them.
Status sweep_near_splint(const Context& ctx, const Mesh& splint, const Aabb& bounds,
                         Span<const Mesh> jaws, SweepOptions so, bool filter, Mesh* swept,
                         SweepStats* stats) {
  Arena& arena = *ctx.arena;
  if (!filter || so.decimate_error > 0) return sweep_volume_mesh(ctx, jaws, so, swept, stats);
  ArenaScope scope(arena);
  NearSplint near;
  DistanceIndex splint_index;
  SPLINTCORE_RETURN_IF_ERROR(mark_near_splint(arena, splint, bounds, so.voxel, &near));
  SPLINTCORE_RETURN_IF_ERROR(
      build_distance_index(ctx, splint, DistanceIndexOptions{}, &splint_index));
  near.index = &splint_index;
  near.reach = kReachVoxels * so.voxel;
  near.window_grow = kWindowVoxels * so.voxel;
  near.window_reach = kWindowReachVoxels * so.voxel;
  // One copy of the filter a task (its own window and seed: the answers never depend on
  // them), kKeepTasks of them whatever the executor, so the high water is the same at any
  // thread count.
  NearSplint tasks[kKeepTasks];
  const void* users[kKeepTasks];
  for (uint32_t i = 0; i < kKeepTasks; ++i) {
    tasks[i] = near;
    tasks[i].window_ids = arena.allocate_array<uint32_t>(kWindowTriangles);
    tasks[i].window_boxes = arena.allocate_array<Aabb>(kWindowTriangles);
    tasks[i].hints = arena.allocate_array<KeptHint>(kHintSlots);
    if (tasks[i].window_ids == nullptr || tasks[i].window_boxes == nullptr ||
        tasks[i].hints == nullptr) {
      return arena.exhausted_status();
    }
    for (uint32_t k = 0; k < kHintSlots; ++k) tasks[i].hints[k] = KeptHint{};
    users[i] = &tasks[i];
  }
  so.keep_triangle = near_splint;
  so.keep_task_users = users;
  so.keep_tasks = kKeepTasks;
  Mesh kept;
  SPLINTCORE_RETURN_IF_ERROR(sweep_volume_mesh(ctx, jaws, so, &kept, stats));
  // Triangles before vertices, as sweep_volume_mesh leaves a filtered mesh.
  move_mesh_down(arena, scope.start(), kept, swept);
  scope.commit();
  return Status::ok();
}

// A copy of the splint in the arena, for when nothing is swept near it (the caller's splint
// stays theirs).
Status copy_splint(Arena& arena, const Mesh& splint, Mesh* out) {
  out->bind(&arena);
  if (!out->triangles.resize(splint.triangles.size()) ||
      !out->vertices.resize(splint.vertices.size())) {
    return arena.exhausted_status();
  }
  for (size_t i = 0; i < splint.triangles.size(); ++i) out->triangles[i] = splint.triangles[i];
  for (size_t i = 0; i < splint.vertices.size(); ++i) out->vertices[i] = splint.vertices[i];
  return Status::ok();
}

// An error of a stage, named as the blockout's (the arena's and cancellation's pass as they are).
Status blockout_error(const Status& s) {
  if (s.code() == StatusCode::kArenaExhausted || s.code() == StatusCode::kCancelled) return s;
  Status e = make_error(s.code(), "blockout: ", s.message());
  if (s.index() != kNoPosition) e.at_index(s.index());
  return e;
}

// The sampled blockout's error after its attempts (st.attempts): with retries that all failed,
// that comes first, with the insets (or offsets) tried, then the last attempt's reason (a
// Status is cut at its capacity, so what a person needs most comes first).
Status attempts_error(const Status& s, const BlockoutOptions& options, const BlockoutStats& st) {
  if (st.attempts < 2 || s.code() == StatusCode::kArenaExhausted ||
      s.code() == StatusCode::kCancelled) {
    return blockout_error(s);
  }
  const bool offset = options.sweep.offset > 0;
  Status e = make_error(s.code(), "blockout: all ", st.attempts, " attempts failed (the swept ",
                        "surface ", offset ? "offset " : "inset ",
                        offset ? options.sweep.offset : options.sweep.inset, " to ",
                        offset ? st.offset_used : st.inset_used, " mm); the last: ", s.message());
  if (s.index() != kNoPosition) e.at_index(s.index());
  return e;
}

// The exact sweep's shells (its triangles connected through shared vertices: patches that overlap
// are separate shells, which the Boolean's groups unite) each checked exactly for self-crossing
// where the Boolean takes them: within the region (the splint's box as the Boolean widens it), its
// walls and the front triangles over their feet (WallCells; the front triangles, the jaw's own, do
// not cross each other). A shell found crossing there is checked again among those of its triangles
// that can matter to the splint: where a wall W crosses a front triangle F of its own shell, what
// is wrong in the shell (W above the crossing, F where the other side's prisms hide it) lies in F
// or above it along d, in F's prism; so a triangle whose prism, up to the region's far side along
// d, is not near the splint (SplintNear, below) is left out. On the real maxilla the walls that
// meet front triangles do so in the air above the base (2 of the 15 shells checked), and the splint
// is the Boolean's alone. A crossing left is refused (kUnsupported, with where) before the Boolean
// would spend its nudges on it. Arena: a union-find entry and a shell start per vertex, a triangle
// copy per triangle, a byte per wall cell (at most 1 MiB), find_self_intersections_bound of the
// largest shell, and for a shell crossing SplintNear; all rewound.
constexpr double kShellReach = 0.01;  // mm: what the Boolean's nudges of A may move it, and more

// What the checks ask of the splint: whether triangle abc, or its prism along d up to the plane
// x . d = top, comes within kShellReach of the splint or holds part of it: triangle_side of the
// triangle, each side's two triangles and the top (the splint's surface near or crossing them,
// or one of them inside it), or a shell of the splint whose box lies within the prism's box (a
// part wholly inside the prism, which its faces would not see). A triangle parallel to d (a
// wall) is its own prism. Built at the first question (the splint's distance index, and a box
// per shell); arena: distance_index_bound, a union-find entry per vertex and a box per shell.
struct SplintNear {
  const Context* ctx = nullptr;
  const Mesh* splint = nullptr;
  DistanceIndex index;
  Aabb* shell_boxes = nullptr;
  uint32_t shells = 0;
  bool built = false;
  uint32_t seed = kNoNeighbor;

  Status build() {
    Arena& arena = *ctx->arena;
    SPLINTCORE_RETURN_IF_ERROR(build_distance_index(*ctx, *splint, DistanceIndexOptions{}, &index));
    const uint32_t nv = static_cast<uint32_t>(splint->vertices.size());
    UnionFind parts;
    uint32_t* root_box = arena.allocate_array<uint32_t>(static_cast<size_t>(nv) + 1);
    if (!parts.init(arena, nv) || root_box == nullptr) return arena.exhausted_status();
    for (const Triangle& g : splint->triangles) {
      (void)parts.unite(g.v[0], g.v[1]);
      (void)parts.unite(g.v[0], g.v[2]);
    }
    for (uint32_t v = 0; v < nv; ++v) {
      if (parts.find(v) == v) root_box[v] = shells++;
    }
    shell_boxes = arena.allocate_array<Aabb>(static_cast<size_t>(shells) + 1);
    if (shell_boxes == nullptr) return arena.exhausted_status();
    for (uint32_t i = 0; i < shells; ++i) shell_boxes[i] = Aabb{};
    for (uint32_t v = 0; v < nv; ++v) shell_boxes[root_box[parts.find(v)]].add(splint->vertices[v]);
    built = true;
    return Status::ok();
  }

  Status prism_near(const Vec3 p[3], const Vec3& d, double top, bool* near) {
    if (!built) SPLINTCORE_RETURN_IF_ERROR(build());
    const auto outside = [&](const Vec3& a, const Vec3& b, const Vec3& c) {
      return triangle_side(index, a, b, c, kShellReach, &seed) == TriangleSide::kOutside;
    };
    *near = true;
    if (!outside(p[0], p[1], p[2])) return Status::ok();
    Aabb box;
    for (int k = 0; k < 3; ++k) box.add(p[k]);
    if (normal_dot(p[0], p[1], p[2], d) != 0) {
      Vec3 q[3];
      for (int k = 0; k < 3; ++k) q[k] = p[k] + d * max_of(0.0, top - dot(p[k], d));
      for (int k = 0; k < 3; ++k) {
        const int n = (k + 1) % 3;
        if (!outside(p[k], p[n], q[n]) || !outside(p[k], q[n], q[k])) return Status::ok();
        box.add(q[k]);
      }
      if (!outside(q[0], q[1], q[2])) return Status::ok();
    }
    for (uint32_t i = 0; i < shells; ++i) {
      const Aabb& b = shell_boxes[i];
      if (b.lo.x >= box.lo.x && b.lo.y >= box.lo.y && b.lo.z >= box.lo.z && b.hi.x <= box.hi.x &&
          b.hi.y <= box.hi.y && b.hi.z <= box.hi.z) {
        return Status::ok();
      }
    }
    *near = false;
    return Status::ok();
  }
};

// The cells, seen along d over the region, that the walls' feet pass through (their boxes, a
// micrometre wider: a wall's top is its foot moved along d and rounded to float32). A wall is
// the strip above its foot, so a front triangle it meets overlaps its foot seen along d: only
// the front triangles over a marked cell can meet a wall (front triangles do not cross each
// other: they are the jaw's). Arena: a byte per cell, at most 1024 x 1024 cells.
struct WallCells {
  Vec3 u{}, v{};
  double u0 = 0, v0 = 0, cell = 1;
  int64_t nu = 0, nv = 0;
  uint8_t* marked = nullptr;

  Status build(Arena& arena, const Mesh& swept, size_t first_wall, const Vec3& d,
               const Aabb& region) {
    u = std::fabs(d.x) < 0.9 ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
    u = u - d * dot(u, d);
    u = u * (1.0 / std::sqrt(dot(u, u)));
    v = cross(d, u);
    double u1 = -HUGE_VAL, v1 = -HUGE_VAL;
    u0 = v0 = HUGE_VAL;
    for (int k = 0; k < 8; ++k) {
      const Vec3 c{(k & 1) ? region.hi.x : region.lo.x, (k & 2) ? region.hi.y : region.lo.y,
                   (k & 4) ? region.hi.z : region.lo.z};
      u0 = min_of(u0, dot(c, u));
      u1 = max_of(u1, dot(c, u));
      v0 = min_of(v0, dot(c, v));
      v1 = max_of(v1, dot(c, v));
    }
    cell = max_of(0.25, max_of(u1 - u0, v1 - v0) / 1000);
    nu = static_cast<int64_t>((u1 - u0) / cell) + 1;
    nv = static_cast<int64_t>((v1 - v0) / cell) + 1;
    marked = arena.allocate_array<uint8_t>(static_cast<size_t>(nu * nv));
    if (marked == nullptr) return arena.exhausted_status();
    std::memset(marked, 0, static_cast<size_t>(nu * nv));
    for (size_t w = first_wall; w < swept.triangles.size(); w += 2) {
      const Triangle& g = swept.triangles[w];  // (b, a, a'): its foot is b a
      const Vec3 p[2] = {swept.vertices[g.v[0]], swept.vertices[g.v[1]]};
      int64_t lo[2], hi[2];
      range(p, 2, 1e-3, lo, hi);
      for (int64_t j = lo[1]; j <= hi[1]; ++j) {
        for (int64_t i = lo[0]; i <= hi[0]; ++i) marked[j * nu + i] = 1;
      }
    }
    return Status::ok();
  }
  // The cells (clamped) that the points' box, `margin` wider, covers seen along d.
  void range(const Vec3* p, int n, double margin, int64_t lo[2], int64_t hi[2]) const {
    double a0 = HUGE_VAL, a1 = -HUGE_VAL, b0 = HUGE_VAL, b1 = -HUGE_VAL;
    for (int k = 0; k < n; ++k) {
      a0 = min_of(a0, dot(p[k], u));
      a1 = max_of(a1, dot(p[k], u));
      b0 = min_of(b0, dot(p[k], v));
      b1 = max_of(b1, dot(p[k], v));
    }
    const auto at = [&](double x, double origin, int64_t count) {
      const double c = std::floor((x - origin) / cell);
      return c < 0 ? int64_t{0}
                   : (c >= static_cast<double>(count) ? count - 1 : static_cast<int64_t>(c));
    };
    lo[0] = at(a0 - margin, u0, nu);
    hi[0] = at(a1 + margin, u0, nu);
    lo[1] = at(b0 - margin, v0, nv);
    hi[1] = at(b1 + margin, v0, nv);
  }
  bool near(const Vec3 p[3]) const {
    int64_t lo[2], hi[2];
    range(p, 3, 1e-3, lo, hi);
    for (int64_t j = lo[1]; j <= hi[1]; ++j) {
      for (int64_t i = lo[0]; i <= hi[0]; ++i) {
        if (marked[j * nu + i] != 0) return true;
      }
    }
    return false;
  }
};

// The region's far side along d: the largest x . d over its corners, which is the corner with
// each coordinate on d's side (rounding is monotone in each product and sum: the same bits as
// the largest of the eight). No loop: gcc 12 for AArch64 stops with an internal error
// vectorising that eight-corner fmax reduction on its own.
double far_side(const Aabb& region, const Vec3& d) {
  const Vec3 corner{d.x > 0 ? region.hi.x : region.lo.x, d.y > 0 ? region.hi.y : region.lo.y,
                    d.z > 0 ? region.hi.z : region.lo.z};
  return dot(corner, d);
}

// The exact sweep's ExactPocketTest: a fold's pocket too deep for its bound is clear when the
// taken-in triangle's prism along d, up to the region's far side, is not near the splint
// (SplintNear: what a pocket leaves unswept lies in that column). SplintNear is built at the
// first such pocket, in the sweep's temporaries.
struct PocketClear {
  SplintNear near;
  Vec3 d{};
  double top = 0;

  static Status clear(void* user, const Vec3 p[3], bool* is_clear) {
    PocketClear& c = *static_cast<PocketClear*>(user);
    bool near = true;
    SPLINTCORE_RETURN_IF_ERROR(c.near.prism_near(p, c.d, c.top, &near));
    *is_clear = !near;
    return Status::ok();
  }
};

Status check_swept_shells(const Context& ctx, const Mesh& swept, const Mesh& splint,
                          const Aabb& region, ExactSweepStats* st) {
  const Vec3 d = st->direction;
  const double top = far_side(region, d);
  Arena& arena = *ctx.arena;
  ArenaScope scope(arena);  // all rewound
  const uint32_t nv = static_cast<uint32_t>(swept.vertices.size());
  UnionFind shells;
  uint32_t* start = arena.allocate_array<uint32_t>(static_cast<size_t>(nv) + 2);
  Triangle* order = arena.allocate_array<Triangle>(swept.triangles.size() + 1);
  if (!shells.init(arena, nv) || start == nullptr || order == nullptr) {
    return arena.exhausted_status();
  }
  for (const Triangle& g : swept.triangles) {
    (void)shells.unite(g.v[0], g.v[1]);
    (void)shells.unite(g.v[0], g.v[2]);
  }
  // The surface's triangles come first, then two per wall (sweep_exact_mesh).
  const size_t first_wall = static_cast<size_t>(st->kept_triangles + st->absorbed_triangles);
  WallCells cells;
  SPLINTCORE_RETURN_IF_ERROR(cells.build(arena, swept, first_wall, d, region));
  // A triangle checked: meeting the region, and a wall or a front triangle over a wall's foot.
  const auto checked = [&](size_t t) {
    const Triangle& g = swept.triangles[t];
    const Vec3 p[3] = {swept.vertices[g.v[0]], swept.vertices[g.v[1]], swept.vertices[g.v[2]]};
    Aabb box;
    for (const Vec3& q : p) box.add(q);
    if (!(box.lo.x <= region.hi.x && box.hi.x >= region.lo.x && box.lo.y <= region.hi.y &&
          box.hi.y >= region.lo.y && box.lo.z <= region.hi.z && box.hi.z >= region.lo.z)) {
      return false;
    }
    return t >= first_wall || cells.near(p);
  };
  std::memset(start, 0, (static_cast<size_t>(nv) + 2) * sizeof(uint32_t));
  for (size_t t = 0; t < swept.triangles.size(); ++t) {
    if (checked(t)) ++start[shells.find(swept.triangles[t].v[0]) + 2];
  }
  for (uint32_t v = 0; v < nv; ++v) start[v + 2] += start[v + 1];
  for (size_t t = 0; t < swept.triangles.size(); ++t) {
    const Triangle& g = swept.triangles[t];
    if (checked(t)) order[start[shells.find(g.v[0]) + 1]++] = g;
  }
  SplintNear near;
  near.ctx = &ctx;
  near.splint = &splint;
  // start[r] .. start[r + 1]: the shell of root r, in the sweep's order.
  for (uint32_t r = 0; r < nv; ++r) {
    uint32_t count = start[r + 1] - start[r];
    if (count == 0) continue;
    ++st->shells;
    Triangle* tris = order + start[r];
    SelfIntersectionReport rep;
    SPLINTCORE_RETURN_IF_ERROR(find_self_intersections(
        ctx, mesh_view(swept.vertices.span(), Span<const Triangle>(tris, count)), 1, &rep));
    st->shell_check_candidates += rep.candidate_pairs;
    if (!rep.self_intersecting()) continue;
    uint32_t kept = 0;
    for (uint32_t i = 0; i < count; ++i) {
      const Triangle g = tris[i];
      const Vec3 p[3] = {swept.vertices[g.v[0]], swept.vertices[g.v[1]], swept.vertices[g.v[2]]};
      bool is_near = true;
      SPLINTCORE_RETURN_IF_ERROR(near.prism_near(p, d, top, &is_near));
      if (is_near) tris[kept++] = g;
    }
    count = kept;
    SPLINTCORE_RETURN_IF_ERROR(find_self_intersections(
        ctx, mesh_view(swept.vertices.span(), Span<const Triangle>(tris, count)), 1, &rep));
    st->shell_check_candidates += rep.candidate_pairs;
    if (!rep.self_intersecting()) {
      ++st->shells_crossing_outside;
      continue;
    }
    const auto um = [](double x) { return std::floor(x * 1000 + 0.5) / 1000; };
    const Vec3& p = swept.vertices[tris[rep.first_b].v[0]];
    return make_error(StatusCode::kUnsupported, "exact sweep: its surface crosses itself inside ",
                      "the splint near (", um(p.x), ", ", um(p.y), ", ", um(p.z),
                      "): a wall meets the jaw's front side further than the fold rounds ",
                      "reach (an overhang along the direction)");
  }
  return Status::ok();
}

// BlockoutOptions::exact: the splint minus the exact swept boundary of the one jaw with
// triangles (the others only anchor the sampled sweep's lattice).
Status blockout_exact(const Context& ctx, const Mesh& splint, Span<const Mesh> jaws,
                      const BlockoutOptions& options, Mesh* result, BlockoutStats* st) {
  if (options.sweep.offset > 0) {
    return make_error(StatusCode::kInvalidArgument,
                      "the exact sweep has no offset (a spacer is the sampled one's)");
  }
  const Mesh* jaw = nullptr;
  for (const Mesh& m : jaws) {
    if (m.triangles.empty()) continue;
    if (jaw != nullptr) {
      return make_error(StatusCode::kInvalidArgument,
                        "the exact sweep takes one jaw with triangles at a time");
    }
    jaw = &m;
  }
  BooleanOptions bo = options.boolean;
  bo.op = BooleanOp::kDifference;
  bo.b_border_outside_a = true;  // the walls end beyond the region, left-out parts lie beyond it
  st->attempts = 1;
  ArenaScope scope(*ctx.arena);
  Mesh swept;
  if (jaw != nullptr) {
    const Aabb region = boolean_region(splint, bo);
    PocketClear clear;
    clear.near.ctx = &ctx;
    clear.near.splint = &splint;
    const Vec3 dir = options.sweep.direction;
    clear.d = dir * (1.0 / std::sqrt(dot(dir, dir)));  // as the sweep normalises it
    clear.top = far_side(region, clear.d);
    ExactPocketTest pockets;
    pockets.clear = PocketClear::clear;
    pockets.user = &clear;
    SPLINTCORE_RETURN_IF_ERROR(
        sweep_exact_mesh(ctx, *jaw, dir, region, &swept, &st->exact, &pockets));
  }
  st->swept_triangles = swept.triangles.size();
  SPLINTCORE_RETURN_IF_ERROR(
      check_swept_shells(ctx, swept, splint, boolean_region(splint, bo), &st->exact));
  Mesh out;
  if (swept.triangles.empty()) {
    SPLINTCORE_RETURN_IF_ERROR(copy_splint(*ctx.arena, splint, &out));
  } else {
    Status s = mesh_boolean(ctx, splint, swept, bo, &out, &st->boolean);
    if (!s.is_ok() && s.code() != StatusCode::kArenaExhausted &&
        s.code() != StatusCode::kCancelled) {
      s.append(
          " (exact sweep: a fold of the jaw's front side along the direction that its "
          "rounds did not resolve lets a wall cross it; the voxel method takes such jaws)");
    }
    SPLINTCORE_RETURN_IF_ERROR(s);
  }
  move_mesh_down(*ctx.arena, scope.start(), out, result);
  scope.commit();
  return Status::ok();
}

// The blockouts' retries, in voxels past the first attempt: the sampled sweep's deeper insets,
// the height field's lower surfaces (see blockout() and blockout_heightfield()).
constexpr int kAttempts = 4;
constexpr double kRetrySteps[kAttempts] = {0, 1.0 / 64, 1.0 / 4, 1.0 / 2};
// A spacer's retries (either blockout): this much of a voxel further out each time.
constexpr double kOffsetRetryStep = 1.0 / 64;

// `out` moved down to `start` with a copy of `swept` after it (kept->mesh, held): the copy is
// made at the top first, above both, then each moves down. False, with nothing moved, when the
// arena has no room for the copy.
bool keep_after(Arena& arena, const Arena::Marker& start, const Mesh& swept, const Mesh& out,
                Mesh* result, BlockoutSwept* kept) {
  const size_t nt = swept.triangles.size(), nv = swept.vertices.size();
  Triangle* t = arena.allocate_array<Triangle>(nt);
  Vec3* v = arena.allocate_array<Vec3>(nv);
  if ((t == nullptr && nt > 0) || (v == nullptr && nv > 0)) {
    arena.forget_failure();
    return false;
  }
  if (nt > 0) std::memcpy(static_cast<void*>(t), swept.triangles.data(), nt * sizeof(Triangle));
  if (nv > 0) std::memcpy(static_cast<void*>(v), swept.vertices.data(), nv * sizeof(Vec3));
  Mesh copy(&arena);
  copy.triangles.adopt(t, nt, nt);
  copy.vertices.adopt(v, nv, nv);
  move_mesh_down(arena, start, out, result);
  move_mesh_down(arena, arena.mark(), copy, &kept->mesh);
  kept->held = true;
  return true;
}

// The height-field blockout (BlockoutOptions::heightfield): the swept surface over the
// splint's bounds, subtracted once; its border is the grid's edge, beyond the splint's box.
Status blockout_heightfield(const Context& ctx, const Mesh& splint, const Aabb& bounds,
                            Span<const Mesh> jaws, const BlockoutOptions& options, Mesh* result,
                            BlockoutStats* st) {
  if (options.sweep.inset > 0 || options.sweep.closing_radius > 0) {
    return make_error(StatusCode::kInvalidArgument, "the height field takes no inset or closing");
  }
  SweepOptions so = options.sweep;
  so.has_region = true;
  so.region = bounds;
  so.float32_vertices = true;
  ArenaScope scope(*ctx.arena);
  const double tolerance =
      options.heightfield_tolerance > 0 ? options.heightfield_tolerance : 0.1 * so.voxel;
  BooleanOptions bo = options.boolean;
  bo.op = BooleanOp::kDifference;
  bo.b_border_outside_a = true;
  // As the sampled blockout's retries (kRetrySteps, the same voxels lower): a configuration the
  // Boolean cannot resolve (two of its points rounded together) is met again on a grid moved by
  // a share of a cell, 1/64 voxel lower, then a quarter and half a voxel; with an offset (a
  // spacer) 1/64 voxel further out each time instead, as the sampled spacer's (offset_used).
  constexpr double kShiftU[kAttempts] = {0, 0.375, 0.625, 0.125};
  constexpr double kShiftV[kAttempts] = {0, 0.25, 0.75, 0.5};
  const bool offset = so.offset > 0;
  BlockoutSwept* kept = options.heightfield_swept;
  const bool reuse = kept != nullptr && kept->held;
  const int first = reuse ? static_cast<int>(kept->attempt) : 0;
  Status s;
  Mesh out, swept;
  for (int attempt = first; attempt < kAttempts; ++attempt) {
    ctx.arena->rewind(scope.start());
    out = Mesh();
    st->attempts = static_cast<uint32_t>(attempt + 1);
    const double lower =
        offset ? attempt * (so.voxel * kOffsetRetryStep) : kRetrySteps[attempt] * so.voxel;
    st->inset_used = lower;  // the height field's lowering (its report's lowered_mm)
    st->offset_used = offset ? so.offset + lower : 0;
    HeightfieldOptions ho;
    ho.tolerance = tolerance;
    ho.lower = lower;
    ho.shift_u = kShiftU[attempt];
    ho.shift_v = kShiftV[attempt];
    if (reuse && attempt == first) {  // the surface this attempt made before (below the scope)
      swept = kept->mesh;
      st->heightfield = kept->stats;
    } else {
      swept = Mesh();
      s = sweep_heightfield_mesh(ctx, jaws, so, ho, &swept, &st->heightfield);
      if (!s.is_ok()) return s;
    }
    st->swept_triangles = swept.triangles.size();
    s = mesh_boolean(ctx, splint, swept, bo, &out, &st->boolean);
    if (s.is_ok() || s.code() == StatusCode::kArenaExhausted ||
        s.code() == StatusCode::kCancelled || s.code() == StatusCode::kInvalidArgument) {
      break;
    }
  }
  if (!s.is_ok()) return attempts_error(s, options, *st);
  if (kept != nullptr && !reuse &&
      keep_after(*ctx.arena, scope.start(), swept, out, result, kept)) {
    kept->attempt = st->attempts - 1;
    kept->stats = st->heightfield;
  } else {
    move_mesh_down(*ctx.arena, scope.start(), out, result);
  }
  scope.commit();
  return Status::ok();
}

}  // namespace

Status blockout(const Context& ctx, const Mesh& splint, Span<const Mesh> jaws,
                const BlockoutOptions& options, Mesh* out, BlockoutStats* stats) {
  SPLINTCORE_ASSERT(ctx.arena != nullptr && out != nullptr);
  if (!out->vertices.empty() || !out->triangles.empty()) {
    return make_error(StatusCode::kInvalidArgument, "blockout: the output mesh must be empty");
  }
  BlockoutStats local;
  BlockoutStats* st = stats != nullptr ? stats : &local;
  *st = BlockoutStats{};
  Arena& arena = *ctx.arena;
  out->bind(&arena);

  Aabb bounds;
  for (const Vec3& p : splint.vertices) bounds.add(p);
  if (bounds.empty()) {
    return make_error(StatusCode::kInvalidArgument, "blockout: the splint has no vertices");
  }
  ArenaScope scope(arena);  // on an error the arena is as it was
  if (options.heightfield) {
    const Status e = blockout_heightfield(ctx, splint, bounds, jaws, options, out, st);
    if (e.is_ok()) {
      scope.commit();
      return e;
    }
    out->bind(&arena);
    return blockout_error(e);
  }
  if (options.exact) {
    const Status e = blockout_exact(ctx, splint, jaws, options, out, st);
    if (e.is_ok()) {
      scope.commit();
      return e;
    }
    out->bind(&arena);
    return blockout_error(e);
  }
  // The retries' insets, in voxels past the one asked for: 1/64 breaks an unlucky coincidence
  // of the two surfaces; a quarter and a half voxel take the swept surface clear of where the
  // sampled surface crosses the jaw's imprint at shallow angles all along (a deep base: on the
  // real dentition with the base 5 mm deep every Boolean attempt at 0.05 and 0.0516 mm met a
  // contact it could not triangulate; 0.08 mm had none). What is left of undercut is at most
  // the inset used (BlockoutStats::inset_used).
  Mesh result;
  Status s;
  for (int attempt = 0; attempt < kAttempts; ++attempt) {
    arena.rewind(scope.start());
    result = Mesh();
    SweepOptions so = options.sweep;
    so.has_region = true;
    so.region = bounds;
    so.open_at_region = true;  // the caps lie outside the splint: the Boolean takes an open B
    if (so.edge_margin < 1.0 / 16) so.edge_margin = 1.0 / 16;
    so.float32_vertices = true;  // rounded below anyway; decimating, before the decimation
    if (options.sweep.offset > 0) {
      so.offset = options.sweep.offset + attempt * (options.sweep.voxel * kOffsetRetryStep);
      if (attempt > 0 && !(so.offset <= 20 * so.voxel)) break;
    } else {
      so.inset = options.sweep.inset + kRetrySteps[attempt] * options.sweep.voxel;
      if (attempt > 0 && !(so.inset < 2 * so.voxel)) break;
    }
    st->attempts = static_cast<uint32_t>(attempt + 1);
    st->inset_used = so.inset;
    st->offset_used = so.offset;
    Mesh swept;
    s = sweep_near_splint(ctx, splint, bounds, jaws, so, options.filter_near_splint, &swept,
                          &st->sweep);
    if (!s.is_ok()) break;
    st->swept_triangles = swept.triangles.size();
    for (size_t i = 0; i < swept.vertices.size() && s.is_ok(); ++i) {
      if (!round_to_float32(&swept.vertices[i])) {
        s = make_error(StatusCode::kLimitExceeded,
                       "a vertex of the swept volume is beyond float32 range")
                .at_index(i);
      }
    }
    if (!s.is_ok()) break;
    if (swept.triangles.empty()) {
      s = copy_splint(arena, splint, &result);  // nothing reaches the splint
      break;
    }
    BooleanOptions bo = options.boolean;
    bo.op = BooleanOp::kDifference;
    // The filter leaves B's border outside the splint, a reach away (see the top); the caps'
    // border lies beyond the splint's box.
    if (options.filter_near_splint && so.decimate_error == 0) bo.b_border_outside_a = true;
    s = mesh_boolean(ctx, splint, swept, bo, &result, &st->boolean);
    if (s.is_ok() || s.code() == StatusCode::kArenaExhausted ||
        s.code() == StatusCode::kCancelled || s.code() == StatusCode::kInvalidArgument) {
      break;
    }
  }
  if (!s.is_ok()) {
    out->bind(&arena);
    return attempts_error(s, options, *st);
  }
  move_mesh_down(arena, scope.start(), result, out);
  scope.commit();
  return Status::ok();
}

}  // namespace splintcore
