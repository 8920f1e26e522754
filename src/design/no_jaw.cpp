// Jaws that are no jaws (no_jaw.h): a triangle soup or a flat sheet given as a jaw or a scan.
// Three measures, each linear and far from any real jaw: the triangles per connected piece
// (union-find over the vertices), the box of the corners (a jaw in other units than mm) and
// the relief across the plane of the summed area vectors. Once the base is made: jaws that do
// not reach it, and where jaws cross its side walls (the stretches of the arch where a placed
// jaw meets a wall triangle, through a grid of the walls).
#include "design/no_jaw.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "core/union_find.h"
#include "design/b_vertex.h"
#include "splintcore/boolean.h"

namespace splintcore {
namespace design_detail {

namespace {

// What refuse_no_jaw measures of one mesh.
struct JawShape {
  bool measured = false;  // false: empty, ids out of range or no area (left to later stages)
  uint64_t pieces = 0;    // connected through shared vertices
  double relief = 0;      // mm across `normal`
  Vec3 normal{};          // unit
  Aabb box;               // of the triangles' corners
  bool in_range = true;   // every corner in float32 range (else check_jaws names the first not)
};

// |v| is at most float32's largest finite value (false for NaN and infinities).
bool in_float32_range(double v) {
  constexpr double kMax = 3.4028234663852886e38;  // FLT_MAX
  return v >= -kMax && v <= kMax;
}

// The pieces: referenced vertices less the unions that joined two of them. `uf` and `used`
// (one byte a vertex) are the mesh's own, set up by the caller.
void count_pieces(const Mesh& m, UnionFind* uf, uint8_t* used, JawShape* out) {
  const size_t n = m.vertices.size();
  for (size_t i = 0; i < n; ++i) used[i] = 0;
  uint64_t referenced = 0, unions = 0;
  for (const Triangle& t : m.triangles) {
    for (uint32_t v : t.v) {
      if (v >= n) return;  // check_jaws names it
      referenced += used[v] == 0 ? 1u : 0u;
      used[v] = 1;
    }
    unions += uf->unite(t.v[0], t.v[1]) ? 1u : 0u;
    unions += uf->unite(t.v[1], t.v[2]) ? 1u : 0u;
  }
  out->pieces = referenced - unions;
  for (size_t i = 0; i < n; ++i) {
    if (used[i] == 0) continue;
    const Vec3& p = m.vertices[i];
    out->in_range =
        out->in_range && in_float32_range(p.x) && in_float32_range(p.y) && in_float32_range(p.z);
    out->box.add(p);
  }
}

// The relief: the plane's normal is the sum of the triangles' area vectors, each turned to
// agree with the largest one (a sheet's triangles may be wound either way).
void measure_relief(const Mesh& m, JawShape* out) {
  Vec3 largest{};
  double largest_sq = 0;
  for (const Triangle& t : m.triangles) {
    const Vec3& a = m.vertices[t.v[0]];
    const Vec3 n = cross(m.vertices[t.v[1]] - a, m.vertices[t.v[2]] - a);
    const double sq = length_squared(n);
    if (sq > largest_sq) {
      largest_sq = sq;
      largest = n;
    }
  }
  Vec3 sum{};
  for (const Triangle& t : m.triangles) {
    const Vec3& a = m.vertices[t.v[0]];
    const Vec3 n = cross(m.vertices[t.v[1]] - a, m.vertices[t.v[2]] - a);
    sum = dot(n, largest) < 0 ? sum - n : sum + n;
  }
  const double sq = length_squared(sum);
  if (!(sq > 0) || !std::isfinite(sq)) return;  // no area (or not finite): left to later stages
  const Vec3 u = sum * (1.0 / std::sqrt(sq));
  double lo = HUGE_VAL, hi = -HUGE_VAL;
  for (const Triangle& t : m.triangles) {
    for (uint32_t v : t.v) {
      const double h = dot(m.vertices[v], u);
      lo = h < lo ? h : lo;
      hi = h > hi ? h : hi;
    }
  }
  out->relief = hi - lo;
  out->normal = u;
  out->measured = true;
}

// For a message: to 3 decimals.
double shown(double v) { return std::floor(v * 1000 + 0.5) / 1000; }

// One mesh, its union-find and `used` set up by the caller (uf null: too many vertices to
// measure, left to a later stage).
Status check_one(const Mesh& m, UnionFind* uf, uint8_t* used, size_t j, const char* role,
                 bool scan) {
  if (m.triangles.empty() || uf == nullptr) return Status::ok();
  JawShape shape;
  count_pieces(m, uf, used, &shape);
  if (shape.pieces == 0) return Status::ok();  // not measured
  const char* of = scan ? "the scan of " : "";
  const char* file = scan ? "the scan's file" : "the jaw's file";
  const uint64_t triangles = m.triangles.size();
  if (triangles < kMinTrianglesPerPiece * shape.pieces) {
    return make_error(StatusCode::kInvalidMesh, "design: ", of, "jaw ", j, " (", role,
                      ") is a triangle soup, not a jaw: its ", triangles, " triangles form ",
                      shape.pieces, " pieces (a jaw is one piece or a few); check ", file,
                      ": its triangles must meet at their corners (export it again)")
        .at_index(j);
  }
  const Vec3 e = shape.box.extent();
  const double longest = e.x > e.y ? (e.x > e.z ? e.x : e.z) : (e.y > e.z ? e.y : e.z);
  if (shape.in_range && (longest < kMinJawExtentMm || longest > kMaxJawExtentMm)) {
    const bool small = longest < kMinJawExtentMm;
    return make_error(StatusCode::kInvalidMesh, "design: ", of, "jaw ", j, " (", role, ") is ",
                      shown(e.x), " x ", shown(e.y), " x ", shown(e.z), " across: too ",
                      small ? "small" : "large", " for a jaw in mm (",
                      small ? "at least " : "at most ", small ? kMinJawExtentMm : kMaxJawExtentMm,
                      " mm); check ", file,
                      small ? ": if it is in inches, centimetres or metres, scale it to mm (x25.4, "
                              "x10 or x1000)"
                            : ": if it is in micrometres, scale it to mm (x0.001)")
        .at_index(j);
  }
  measure_relief(m, &shape);
  if (shape.measured && shape.relief < kMinJawReliefMm) {
    return make_error(StatusCode::kInvalidMesh, "design: ", of, "jaw ", j, " (", role,
                      ") has no teeth: all its vertices lie within ", shown(shape.relief),
                      " mm of one plane (normal ", shown(shape.normal.x), ", ",
                      shown(shape.normal.y), ", ", shown(shape.normal.z), "; crowns rise at least ",
                      kMinJawReliefMm, " mm from it); check ", file,
                      ": it is a flat sheet, not this jaw")
        .at_index(j);
  }
  return Status::ok();
}

// The same bits in every entry.
bool same_transform(const RigidTransform& a, const RigidTransform& b) {
  const double x[12] = {a.r[0][0], a.r[0][1], a.r[0][2], a.r[1][0], a.r[1][1], a.r[1][2],
                        a.r[2][0], a.r[2][1], a.r[2][2], a.t.x,     a.t.y,     a.t.z};
  const double y[12] = {b.r[0][0], b.r[0][1], b.r[0][2], b.r[1][0], b.r[1][1], b.r[1][2],
                        b.r[2][0], b.r[2][1], b.r[2][2], b.t.x,     b.t.y,     b.t.z};
  return same_bits(x, y, 12);
}

// Two jaws that are one: the same triangles and vertices, bit for bit, moved by the same
// transform (the same file given twice). Their Boolean meets its own surface everywhere and
// fails on coinciding intersection points, a message that does not say why.
Status refuse_same_jaw_twice(const CaseFile& c, Span<const Mesh> jaws) {
  const size_t n = jaws.size() < c.jaws.size() ? jaws.size() : c.jaws.size();
  for (size_t k = 1; k < n; ++k) {
    const Mesh& b = jaws[k];
    for (size_t j = 0; j < k; ++j) {
      const Mesh& a = jaws[j];
      if (a.triangles.empty() || a.vertices.size() != b.vertices.size() ||
          a.triangles.size() != b.triangles.size() ||
          !same_transform(c.jaws[j].transform, c.jaws[k].transform) ||
          std::memcmp(a.triangles.data(), b.triangles.data(),
                      a.triangles.size() * sizeof(Triangle)) != 0 ||
          std::memcmp(a.vertices.data(), b.vertices.data(), a.vertices.size() * sizeof(Vec3)) !=
              0) {
        continue;
      }
      return make_error(StatusCode::kInvalidArgument, "design: jaw ", k, " (", c.jaws[k].role,
                        ") is jaw ", j, " (", c.jaws[j].role, ") again: the same ",
                        b.triangles.size(),
                        " triangles at the same place; check the case's jaw files (one file "
                        "given for both?)")
          .at_index(k);
    }
  }
  return Status::ok();
}

}  // namespace

Status refuse_no_jaw(const Context& ctx, const CaseFile& c, Span<const Mesh> jaws,
                     Span<const Mesh> scans) {
  // The meshes in the order they are named: each jaw, then its scan.
  struct Item {
    const Mesh* mesh;
    size_t jaw;
    bool scan;
    UnionFind uf;
    uint8_t* used;
    Status status;
  };
  Arena& arena = *ctx.arena;
  ArenaScope scope(arena);
  const size_t most = 2 * jaws.size();
  Item* items = arena.allocate_array<Item>(most);
  if (items == nullptr && most > 0) return arena.exhausted_status();
  uint32_t n = 0;
  for (size_t j = 0; j < jaws.size() && j < c.jaws.size(); ++j) {
    for (int k = 0; k < 2; ++k) {
      if (k == 1 && !(j < scans.size() && c.jaws[j].has_scan)) continue;
      Item& it = items[n++];
      it = Item{k == 0 ? &jaws[j] : &scans[j], j, k == 1, UnionFind{}, nullptr, Status::ok()};
      const size_t nv = it.mesh->vertices.size();
      if (static_cast<uint64_t>(nv) >= (uint64_t{1} << 32)) continue;  // a later stage names it
      it.used = arena.allocate_array<uint8_t>(nv);
      if (!it.uf.init(arena, static_cast<uint32_t>(nv)) || (it.used == nullptr && nv > 0)) {
        return arena.exhausted_status();
      }
    }
  }
  // Each mesh in a task of its own; the first error in the order above.
  auto task = [&](uint32_t i) {
    Item& it = items[i];
    const bool measured = it.used != nullptr || it.mesh->vertices.empty();
    it.status = check_one(*it.mesh, measured ? &it.uf : nullptr, it.used, it.jaw,
                          c.jaws[it.jaw].role, it.scan);
  };
  parallel_for_each(ctx.executor, n, task);
  for (uint32_t i = 0; i < n; ++i) SPLINTCORE_RETURN_IF_ERROR(items[i].status);
  return refuse_same_jaw_twice(c, jaws);
}

namespace {

// Whether a triangle of jaw j, placed (b_vertex), has corners not all beyond one side of
// `region`: the first such triangle ends the scan.
bool jaw_reaches(const CaseFile& c, Span<const Mesh> jaws, size_t j, const Aabb& region) {
  for (const Triangle& t : jaws[j].triangles) {
    uint8_t beyond = 0x3f;
    for (uint32_t v : t.v) {
      Vec3 p;
      if (!b_vertex(c, jaws, j, v, &p)) return true;  // beyond float32: check_jaws names it
      beyond &= region.outcode(p);
    }
    if (beyond == 0) return true;
  }
  return false;
}

// "[x, y, z]" of a box corner, to 3 decimals, for a message.
void append_corner(Status* s, const Vec3& p) {
  s->append("[").append_f64(shown(p.x)).append(", ").append_f64(shown(p.y));
  s->append(", ").append_f64(shown(p.z)).append("]");
}

}  // namespace

Status refuse_out_of_reach(const Context& ctx, const CaseFile& c, Span<const Mesh> jaws,
                           const Mesh& base) {
  const size_t n = jaws.size() < c.jaws.size() ? jaws.size() : c.jaws.size();
  if (n == 0 || base.triangles.empty()) return Status::ok();
  Arena& arena = *ctx.arena;
  ArenaScope scope(arena);
  uint8_t* reaches = arena.allocate_array<uint8_t>(n);
  if (reaches == nullptr) return arena.exhausted_status();
  const Aabb region = boolean_region(base, BooleanOptions{});
  auto task = [&](uint32_t j) {
    reaches[j] = jaws[j].triangles.empty() || jaw_reaches(c, jaws, j, region) ? 1 : 0;
  };
  parallel_for_each(ctx.executor, static_cast<uint32_t>(n), task);
  for (size_t j = 0; j < n; ++j) {
    if (reaches[j] != 0) continue;
    Aabb placed;
    for (size_t v = 0; v < jaws[j].vertices.size(); ++v) {
      Vec3 p;
      (void)b_vertex(c, jaws, j, v, &p);  // in range: jaw_reaches returned at one that is not
      placed.add(p);
    }
    const Aabb b = mesh_bounds(base);
    Status s = make_error(StatusCode::kInvalidMesh, "design: jaw ", j, " (", c.jaws[j].role,
                          ") does not reach the base: placed, it spans ");
    append_corner(&s, placed.lo);
    s.append(" - ");
    append_corner(&s, placed.hi);
    s.append(" and the base ");
    append_corner(&s, b.lo);
    s.append(" - ");
    append_corner(&s, b.hi);
    s.append(" mm; check its transform and the picks");
    return s.at_index(j);
  }
  return Status::ok();
}

namespace {

// The base's side-wall triangles, stretch by stretch (wall w lies in stretch w / per_stretch),
// and a uniform grid of them over their box.
struct WallIndex {
  uint32_t stretches = 0;
  uint32_t per_stretch = 0;
  uint32_t* tri = nullptr;   // the base triangle of wall w
  uint8_t* outer = nullptr;  // 1: the outer wall, 0: the inner
  Aabb box;                  // of the wall triangles
  double cell = 1.0;         // mm, the grid's edge
  uint32_t n[3] = {1, 1, 1};
  uint32_t* start = nullptr;  // the walls of cell c: items[start[c] .. start[c + 1])
  uint32_t* items = nullptr;
};

constexpr uint32_t kMaxWallGridCells = uint32_t{1} << 16;

// The cells a box covers, per axis [lo, hi] (the box overlaps the grid's).
void cell_span(const WallIndex& g, const Aabb& b, uint32_t lo[3], uint32_t hi[3]) {
  for (int a = 0; a < 3; ++a) {
    const double o = g.box.lo[a], last = static_cast<double>(g.n[a] - 1);
    const double l = std::floor((b.lo[a] - o) / g.cell);
    const double h = std::floor((b.hi[a] - o) / g.cell);
    lo[a] = static_cast<uint32_t>(l < 0 ? 0 : l > last ? last : l);
    hi[a] = static_cast<uint32_t>(h < 0 ? 0 : h > last ? last : h);
  }
}

// f(cell) for each cell of the span [lo, hi].
template <typename F>
void for_each_cell(const WallIndex& g, const uint32_t lo[3], const uint32_t hi[3], F f) {
  for (uint32_t z = lo[2]; z <= hi[2]; ++z) {
    for (uint32_t y = lo[1]; y <= hi[1]; ++y) {
      for (uint32_t x = lo[0]; x <= hi[0]; ++x) f((z * g.n[1] + y) * g.n[0] + x);
    }
  }
}

// Each cell's walls: counted (pass 0), summed into starts, then listed (pass 1), in the arena;
// the cell's edge doubles from 1 mm until the grid has at most kMaxWallGridCells cells.
Status grid_walls(Arena& arena, const Mesh& base, WallIndex* g) {
  const uint32_t walls = g->stretches * g->per_stretch;
  const Vec3 e = g->box.extent();
  auto cells_at = [&](double cell) {
    return (static_cast<uint64_t>(e.x / cell) + 1) * (static_cast<uint64_t>(e.y / cell) + 1) *
           (static_cast<uint64_t>(e.z / cell) + 1);
  };
  while (cells_at(g->cell) > kMaxWallGridCells) g->cell *= 2;
  g->n[0] = static_cast<uint32_t>(e.x / g->cell) + 1;
  g->n[1] = static_cast<uint32_t>(e.y / g->cell) + 1;
  g->n[2] = static_cast<uint32_t>(e.z / g->cell) + 1;
  const uint32_t cells = g->n[0] * g->n[1] * g->n[2];
  g->start = arena.allocate_array<uint32_t>(size_t{cells} + 1);
  uint32_t* cursor = arena.allocate_array<uint32_t>(cells);
  if (g->start == nullptr || cursor == nullptr) return arena.exhausted_status();
  std::memset(g->start, 0, (size_t{cells} + 1) * sizeof(uint32_t));
  auto each_wall = [&](auto f) {
    for (uint32_t w = 0; w < walls; ++w) {
      uint32_t lo[3], hi[3];
      cell_span(*g, triangle_box(base, g->tri[w]), lo, hi);
      for_each_cell(*g, lo, hi, [&](uint32_t c) { f(w, c); });
    }
  };
  each_wall([&](uint32_t, uint32_t c) { ++g->start[c + 1]; });
  for (uint32_t c = 0; c < cells; ++c) g->start[c + 1] += g->start[c];
  std::memcpy(cursor, g->start, size_t{cells} * sizeof(uint32_t));
  g->items = arena.allocate_array<uint32_t>(g->start[cells]);
  if (g->items == nullptr && g->start[cells] > 0) return arena.exhausted_status();
  each_wall([&](uint32_t w, uint32_t c) { g->items[cursor[c]++] = w; });
  return Status::ok();
}

// The side-wall triangles of `base` (built with `params`: S sections of P points) and their
// grid; stretches 0 when the base is not laid out as build_splint_base makes it.
Status index_walls(Arena& arena, const Mesh& base, const BaseParams& params,
                   const BaseReport& built, WallIndex* g) {
  const uint32_t S = built.sections, P = built.points_per_section;
  if (S < 2 || P < 4 || P > 4 * 17 || base.triangles.size() < 2 * uint64_t{S - 1} * P ||
      base.vertices.size() < uint64_t{S} * P) {
    return Status::ok();
  }
  uint32_t segment[4 * 17];
  uint8_t outer[4 * 17];
  uint32_t m = 0;
  for (uint32_t j = 0; j < P; ++j) {
    const BaseSide side = base_segment_side(params, j);
    if (side != BaseSide::kOuter && side != BaseSide::kInner) continue;
    segment[m] = j;
    outer[m++] = side == BaseSide::kOuter ? 1 : 0;
  }
  g->per_stretch = 2 * m;
  const size_t walls = size_t{S - 1} * g->per_stretch;
  g->tri = arena.allocate_array<uint32_t>(walls);
  g->outer = arena.allocate_array<uint8_t>(walls);
  if ((g->tri == nullptr || g->outer == nullptr) && walls > 0) return arena.exhausted_status();
  size_t w = 0;
  for (uint32_t k = 0; k + 1 < S; ++k) {
    for (uint32_t i = 0; i < m; ++i) {
      for (uint32_t h = 0; h < 2; ++h, ++w) {
        g->tri[w] = 2 * (k * P + segment[i]) + h;
        g->outer[w] = outer[i];
        g->box.add(triangle_box(base, g->tri[w]));
      }
    }
  }
  g->stretches = S - 1;
  return grid_walls(arena, base, g);
}

// The walls' box in jaw j's own frame (its 8 corners taken back through the transform), grown
// by a margin for the rounding of placed vertices to float32 (2^-24 of the world coordinates)
// and for the transform's rotation being orthonormal only to 1e-6 (the case's tolerance: the
// transpose undoes it to about 3e-6 of the local coordinates): a triangle whose corners as given
// are all beyond one side of it cannot meet a wall once placed.
Aabb walls_in_jaw_frame(const CaseFile& c, size_t j, const Aabb& box) {
  const RigidTransform back = inverse(c.jaws[j].transform);
  Aabb local;
  for (int i = 0; i < 8; ++i) {
    local.add(back.apply_point(Vec3{(i & 1) != 0 ? box.hi.x : box.lo.x,
                                    (i & 2) != 0 ? box.hi.y : box.lo.y,
                                    (i & 4) != 0 ? box.hi.z : box.lo.z}));
  }
  const Vec3 e = local.extent();
  const double margin =
      1e-3 + 1e-5 * (std::fabs(local.lo.x) + std::fabs(local.lo.y) + std::fabs(local.lo.z) + e.x +
                     e.y + e.z + std::fabs(box.lo.x) + std::fabs(box.lo.y) + std::fabs(box.lo.z) +
                     std::fabs(box.hi.x) + std::fabs(box.hi.y) + std::fabs(box.hi.z));
  local.lo = local.lo - Vec3{margin, margin, margin};
  local.hi = local.hi + Vec3{margin, margin, margin};
  return local;
}

// Jaw j's triangle p (placed, its box tb) against wall w: hit[k] gets bit 1 where it meets
// stretch k's outer wall, 2 its inner.
void cross_wall(const Mesh& base, const WallIndex& g, const Vec3 (&p)[3], const Aabb& tb,
                uint32_t w, uint8_t* hit) {
  const uint32_t k = w / g.per_stretch;
  const uint8_t bit = g.outer[w] != 0 ? 1 : 2;
  if ((hit[k] & bit) != 0) return;
  const Triangle& b = base.triangles[g.tri[w]];
  const Vec3& a0 = base.vertices[b.v[0]];
  const Vec3& a1 = base.vertices[b.v[1]];
  const Vec3& a2 = base.vertices[b.v[2]];
  if (!tb.overlaps(triangle_box(base, g.tri[w])) || collinear3d(a0, a1, a2)) return;
  if (triangles_intersect(p[0], p[1], p[2], a0, a1, a2)) hit[k] |= bit;
}

// A jaw triangle over more cells than this is tested against every wall instead: a few large
// triangles (a hostile mesh's, or a coarse jaw's) cannot cost cells times walls each.
constexpr uint64_t kMaxCellsPerTriangle = 64;

// Jaw j against the walls: hit[k] gets bit 1 where it meets stretch k's outer wall, 2 its inner.
void cross_walls(const CaseFile& c, Span<const Mesh> jaws, size_t j, const Mesh& base,
                 const WallIndex& g, uint8_t* hit) {
  const Mesh& jaw = jaws[j];
  const Aabb local = walls_in_jaw_frame(c, j, g.box);
  const uint32_t walls = g.stretches * g.per_stretch;
  for (const Triangle& t : jaw.triangles) {
    uint8_t beyond = 0x3f;
    for (uint32_t v : t.v) beyond &= local.outcode(jaw.vertices[v]);
    if (beyond != 0) continue;
    Vec3 p[3];
    Aabb tb;
    bool placed = true;
    for (int i = 0; i < 3; ++i) {
      placed = placed && b_vertex(c, jaws, j, t.v[i], &p[i]);
      tb.add(p[i]);
    }
    if (!placed || !tb.overlaps(g.box) || collinear3d(p[0], p[1], p[2])) continue;
    uint32_t lo[3], hi[3];
    cell_span(g, tb, lo, hi);
    const uint64_t cells = uint64_t{hi[0] - lo[0] + 1} * (hi[1] - lo[1] + 1) * (hi[2] - lo[2] + 1);
    if (cells > kMaxCellsPerTriangle) {
      for (uint32_t w = 0; w < walls; ++w) cross_wall(base, g, p, tb, w, hit);
      continue;
    }
    for_each_cell(g, lo, hi, [&](uint32_t cell) {
      for (uint32_t e = g.start[cell]; e < g.start[cell + 1]; ++e) {
        cross_wall(base, g, p, tb, g.items[e], hit);
      }
    });
  }
}

// The mean of section k's points.
Vec3 section_centre(const Mesh& base, uint32_t points, uint32_t k) {
  Vec3 sum{};
  for (uint32_t i = 0; i < points; ++i) sum = sum + base.vertices[size_t{k} * points + i];
  return sum * (1.0 / points);
}

// The lengths along the arch of jaw j's crossings (hit, per stretch).
WallCrossing crossing_lengths(const Mesh& base, const BaseReport& built, const uint8_t* hit) {
  WallCrossing w;
  w.stretches = built.sections - 1;
  const uint32_t p = built.points_per_section;
  for (uint32_t k = 0; k < w.stretches; ++k) {
    w.arch_mm += length(section_centre(base, p, k + 1) - section_centre(base, p, k));
  }
  bool first = true;
  double along = 0;  // the arch's length before stretch k
  Vec3 a = section_centre(base, p, 0);
  for (uint32_t k = 0; k < w.stretches; ++k) {
    const Vec3 b = section_centre(base, p, k + 1);
    const double len = length(b - a);
    const int half = along + 0.5 * len < 0.5 * w.arch_mm ? 0 : 1;
    along += len;
    if ((hit[k] & 1) != 0) {
      w.outer_mm += len;
      w.half_outer_mm[half] += len;
    }
    if ((hit[k] & 2) != 0) {
      w.inner_mm += len;
      w.half_inner_mm[half] += len;
    }
    if (hit[k] != 0) {
      w.either_mm += len;
      ++w.crossed;
      if (first) {
        w.first_stretch = k;
        w.first_at = (a + b) * 0.5;
        first = false;
      }
    }
    a = b;
  }
  return w;
}

// The error for jaw j's crossing `w` over c's bounds (ok when within them).
Status refuse_crossing(const CaseFile& c, size_t j, const WallCrossing& w) {
  const double share = w.share(), sideways = w.sideways_share();
  if (share > c.max_wall_crossing) {
    Status s = make_error(StatusCode::kInvalidMesh, "design: jaw ", j, " (", c.jaws[j].role,
                          ") crosses the base's side walls along ");
    s.append_f64(shown(w.either_mm)).append(" of its ").append_f64(shown(w.arch_mm));
    s.append(" mm (share ").append_f64(shown(share));
    s.append(", max_wall_crossing ").append_f64(c.max_wall_crossing).append("), first at ");
    append_corner(&s, w.first_at);
    s.append(": its teeth lie outside the outline there; check the jaw's transform and the picks");
    return s.at_index(j);
  }
  if (sideways > c.max_sideways_crossing) {
    // The pair sideways_mm() took: the outer wall in the first half, or the inner.
    const bool outer_first = std::min(w.half_outer_mm[0], w.half_inner_mm[1]) >=
                             std::min(w.half_inner_mm[0], w.half_outer_mm[1]);
    Status s = make_error(StatusCode::kInvalidMesh, "design: jaw ", j, " (", c.jaws[j].role,
                          ") sits to one side of the base: it crosses the ");
    s.append(outer_first ? "outer" : "inner").append(" wall along ");
    s.append_f64(shown(outer_first ? w.half_outer_mm[0] : w.half_inner_mm[0]));
    s.append(" mm in one half of the arch, the ").append(outer_first ? "inner" : "outer");
    s.append(" along ").append_f64(shown(outer_first ? w.half_inner_mm[1] : w.half_outer_mm[1]));
    s.append(" in the other (share ").append_f64(shown(sideways));
    s.append(", max_sideways_crossing ").append_f64(c.max_sideways_crossing);
    s.append("); check the jaw's transform and the picks");
    return s.at_index(j);
  }
  return Status::ok();
}

}  // namespace

Status measure_side_walls(const Context& ctx, const CaseFile& c, Span<const Mesh> jaws,
                          const Mesh& base, const BaseReport& built, DesignReport* report) {
  const size_t n = jaws.size() < c.jaws.size() ? jaws.size() : c.jaws.size();
  report->wall_jaws = 0;
  if (n == 0) return Status::ok();
  Arena& arena = *ctx.arena;
  ArenaScope scope(arena);
  WallIndex g;
  SPLINTCORE_RETURN_IF_ERROR(index_walls(arena, base, c.base, built, &g));
  if (g.stretches == 0 || g.per_stretch == 0) return Status::ok();
  uint8_t* hit = arena.allocate_array<uint8_t>(n * g.stretches);
  if (hit == nullptr) return arena.exhausted_status();
  std::memset(hit, 0, n * g.stretches);
  auto task = [&](uint32_t j) { cross_walls(c, jaws, j, base, g, hit + size_t{j} * g.stretches); };
  parallel_for_each(ctx.executor, static_cast<uint32_t>(n), task);
  for (size_t j = 0; j < n; ++j) {
    const WallCrossing w = crossing_lengths(base, built, hit + j * g.stretches);
    if (j < DesignReport::kMaxBlockoutJaws) {
      report->walls[j] = w;
      report->wall_jaws = static_cast<uint32_t>(j + 1);
    }
    SPLINTCORE_RETURN_IF_ERROR(refuse_crossing(c, j, w));
  }
  return Status::ok();
}

Status refuse_swapped_roles(const CaseFile& c, Span<const Mesh> jaws) {
  if (!c.has_blockout) return Status::ok();
  const Vec3 d = c.insertion_direction;
  int upper = -1, lower = -1;
  double mean[2] = {0, 0};  // along d: the maxilla's, the mandible's
  const size_t n = jaws.size() < c.jaws.size() ? jaws.size() : c.jaws.size();
  for (size_t j = 0; j < n; ++j) {
    const bool maxilla = std::strcmp(c.jaws[j].role, "maxilla") == 0;
    const bool mandible = std::strcmp(c.jaws[j].role, "mandible") == 0;
    if ((!maxilla && !mandible) || jaws[j].vertices.empty()) continue;
    double sum = 0;
    for (size_t v = 0; v < jaws[j].vertices.size(); ++v) {
      Vec3 p;
      (void)b_vertex(c, jaws, j, v, &p);  // in range: check_jaws
      sum += dot(p, d);
    }
    (maxilla ? upper : lower) = static_cast<int>(j);
    mean[maxilla ? 0 : 1] = sum / static_cast<double>(jaws[j].vertices.size());
  }
  if (upper < 0 || lower < 0 || mean[0] > mean[1]) return Status::ok();
  Status s =
      make_error(StatusCode::kInvalidArgument, "design: jaw ", upper, " (maxilla) is below jaw ",
                 lower, " (mandible) along the insertion direction [");
  s.append_f64(shown(d.x)).append(", ").append_f64(shown(d.y)).append(", ").append_f64(shown(d.z));
  s.append("] (mean heights ").append_f64(shown(mean[0])).append(", ").append_f64(shown(mean[1]));
  s.append(" mm); check the roles and the insertion direction (mandible to maxilla)");
  return s.at_index(static_cast<uint64_t>(upper));
}

}  // namespace design_detail
}  // namespace splintcore
