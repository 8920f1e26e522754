// The Boolean run, broad phase: B's triangles near A and a grid over A's box listing A's
// triangles per cell, computed once for every attempt (boolean_run.h).
#include "boolean/boolean_run.h"

namespace splintcore {
namespace boolean_detail {

namespace {

// A triangle's plane for a conservative box test: n . x = d, with the slack that covers the
// rounding of n, d and the test itself (generous: it only lets a few more pairs through to the
// exact tests, never fewer).
struct PlaneSlab {
  Vec3 n;
  double d;
  double slack;
};

PlaneSlab slab_of(const Vec3& a, const Vec3& b, const Vec3& c) {
  PlaneSlab p;
  p.n = cross(b - a, c - a);
  p.d = dot(p.n, a);
  const double m = (a.x < 0 ? -a.x : a.x) + (a.y < 0 ? -a.y : a.y) + (a.z < 0 ? -a.z : a.z);
  const double n1 =
      (p.n.x < 0 ? -p.n.x : p.n.x) + (p.n.y < 0 ? -p.n.y : p.n.y) + (p.n.z < 0 ? -p.n.z : p.n.z);
  p.slack = 1e-9 * n1 * (m + 1.0);
  return p;
}

// A's triangles: their planes as slabs and their boxes widened by `reach`.
Status slabs_and_boxes(Arena& arena, const Mesh& a, double reach, PlaneSlab** slabs_out,
                       Aabb** boxes_out) {
  const uint32_t nta = static_cast<uint32_t>(a.triangles.size());
  PlaneSlab* slabs = arena.allocate_array<PlaneSlab>(nta);
  Aabb* boxes = arena.allocate_array<Aabb>(nta);
  if (slabs == nullptr || boxes == nullptr) return arena.exhausted_status();
  for (uint32_t t = 0; t < nta; ++t) {
    const Triangle& at = a.triangles[t];
    const Vec3& p0 = a.vertices[at.v[0]];
    const Vec3& p1 = a.vertices[at.v[1]];
    const Vec3& p2 = a.vertices[at.v[2]];
    slabs[t] = slab_of(p0, p1, p2);
    boxes[t] = Aabb{};
    boxes[t].add(p0);
    boxes[t].add(p1);
    boxes[t].add(p2);
    boxes[t].lo = boxes[t].lo - Vec3{reach, reach, reach};
    boxes[t].hi = boxes[t].hi + Vec3{reach, reach, reach};
  }
  *slabs_out = slabs;
  *boxes_out = boxes;
  return Status::ok();
}

// The grid over bp->abox: about 16 cells per triangle of A (a power-of-two size, so every
// platform picks the same grid), cubic cells, at most 256 a side.
void size_grid(uint32_t nta, Broadphase* bp) {
  const Vec3 ext = bp->abox.extent();
  const double volume = (ext.x + 1e-9) * (ext.y + 1e-9) * (ext.z + 1e-9);
  const double target = 16.0 * nta + 64.0;
  double h = 1.0;
  while (volume / (h * h * h) > target && h < 1e30) h *= 2.0;
  while (volume / (h * h * h) < target / 8.0 && h > 1e-30) h *= 0.5;
  uint32_t* dim = bp->dim;
  for (int k = 0; k < 3; ++k) {
    double cells = ext[k] / h;
    if (cells > 256.0) h = ext[k] / 256.0;
  }
  for (int k = 0; k < 3; ++k) {
    const double cells = ext[k] / h;
    dim[k] = cells < 1.0 ? 1u : (cells >= 256.0 ? 256u : static_cast<uint32_t>(cells) + 1u);
  }
  bp->h = h;
  bp->inv_h = 1.0 / h;
}

// The cells of triangle t's box (lo, hi) and the dominant axis of its plane's normal.
inline int column_axes(const Broadphase& bp, const PlaneSlab& slab, const Aabb& box, uint32_t lo[3],
                       uint32_t hi[3]) {
  bp.cell_range(box, lo, hi);
  const Vec3& n = slab.n;
  const double an[3] = {n.x < 0 ? -n.x : n.x, n.y < 0 ? -n.y : n.y, n.z < 0 ? -n.z : n.z};
  return (an[0] >= an[1] && an[0] >= an[2]) ? 0 : (an[1] >= an[2] ? 1 : 2);
}

// Pass one for one triangle of A: the interval [k0, k1] of each column of cells its plane
// passes through within its box, appended to `spans`, and a count for each of those cells at
// start[cell + 1]. `row`: 2 x 258 doubles of scratch. False when the arena is exhausted.
bool count_cells(const Broadphase& bp, const PlaneSlab& slab, const Aabb& box, double reach,
                 double* row, uint32_t* start, ArenaArray<uint8_t>* spans) {
  const Aabb& abox = bp.abox;
  const uint32_t* dim = bp.dim;
  const double h = bp.h, inv_h = bp.inv_h;
  uint32_t lo[3], hi[3];
  const int w = column_axes(bp, slab, box, lo, hi);
  const int u = (w + 1) % 3, v = (w + 2) % 3;
  const Vec3& n = slab.n;
  const double d = slab.d, nu = n[u], nv = n[v], nw = n[w];
  const double lo_u = abox.lo[u], lo_v = abox.lo[v];
  // row[0..]: nodes at u index idx[u], row[258..]: at idx[u] + 1; node j is v index lo[v] + j.
  const uint32_t nodes_v = hi[v] - lo[v] + 2;
  auto fill_row = [&](double* r, uint32_t iu) {
    const double cu = lo_u + iu * h;
    for (uint32_t j = 0; j < nodes_v; ++j) {
      const double cv = lo_v + (lo[v] + j) * h;
      r[j] = (d - nu * cu - nv * cv) / nw;
    }
  };
  double* row0 = row;
  double* row1 = row + 258;
  fill_row(row0, lo[u]);
  uint32_t idx[3];
  for (idx[u] = lo[u]; idx[u] <= hi[u]; ++idx[u]) {
    fill_row(row1, idx[u] + 1);
    for (idx[v] = lo[v]; idx[v] <= hi[v]; ++idx[v]) {
      const uint32_t j = idx[v] - lo[v];
      // Corners in the order (u, v), (u + 1, v), (u, v + 1), (u + 1, v + 1).
      const double c0 = row0[j], c1 = row1[j], c2 = row0[j + 1], c3 = row1[j + 1];
      double wmin = HUGE_VAL, wmax = -HUGE_VAL;
      wmin = c0 < wmin ? c0 : wmin;
      wmax = c0 > wmax ? c0 : wmax;
      wmin = c1 < wmin ? c1 : wmin;
      wmax = c1 > wmax ? c1 : wmax;
      wmin = c2 < wmin ? c2 : wmin;
      wmax = c2 > wmax ? c2 : wmax;
      wmin = c3 < wmin ? c3 : wmin;
      wmax = c3 > wmax ? c3 : wmax;
      const double pad = 1e-9 * ((wmin < 0 ? -wmin : wmin) + (wmax < 0 ? -wmax : wmax) + 1.0) +
                         1e-6 * h + 2.0 * reach;
      const double l = (wmin - pad - abox.lo[w]) * inv_h, r = (wmax + pad - abox.lo[w]) * inv_h;
      uint32_t k0 = l <= 0.0 ? 0u : (l >= dim[w] - 1.0 ? dim[w] - 1 : static_cast<uint32_t>(l));
      uint32_t k1 = r <= 0.0 ? 0u : (r >= dim[w] - 1.0 ? dim[w] - 1 : static_cast<uint32_t>(r));
      if (k0 < lo[w]) k0 = lo[w];
      if (k1 > hi[w]) k1 = hi[w];
      if (!spans->push_back(static_cast<uint8_t>(k0)) ||
          !spans->push_back(static_cast<uint8_t>(k1))) {
        return false;
      }
      for (idx[w] = k0; idx[w] <= k1; ++idx[w]) {
        ++start[(size_t{idx[2]} * dim[1] + idx[1]) * dim[0] + idx[0] + 1];
      }
    }
    double* swap = row0;
    row0 = row1;
    row1 = swap;
  }
  return true;
}

// Pass two for one triangle of A: the intervals of pass one replayed from spans[*at], t
// written into each cell's next item (start[cell]: its fill position).
void fill_cells(const Broadphase& bp, const PlaneSlab& slab, const Aabb& box, uint32_t t,
                const ArenaArray<uint8_t>& spans, size_t* at, uint32_t* start, uint32_t* items) {
  const uint32_t* dim = bp.dim;
  uint32_t lo[3], hi[3];
  const int w = column_axes(bp, slab, box, lo, hi);
  const int u = (w + 1) % 3, v = (w + 2) % 3;
  uint32_t idx[3];
  for (idx[u] = lo[u]; idx[u] <= hi[u]; ++idx[u]) {
    for (idx[v] = lo[v]; idx[v] <= hi[v]; ++idx[v]) {
      const uint32_t k0 = spans[*at], k1 = spans[*at + 1];
      *at += 2;
      for (idx[w] = k0; idx[w] <= k1; ++idx[w]) {
        items[start[(size_t{idx[2]} * dim[1] + idx[1]) * dim[0] + idx[0]]++] = t;
      }
    }
  }
}

// The cells a triangle's plane passes through within its box, column by column along the
// plane's dominant axis: in each column of cells the plane spans one interval of that axis
// (its values at the column's four corners bound it), widened by a hair and by twice the
// reach (a plane moved by `reach` moves at most sqrt(3) reach along its dominant axis).
// The plane's value at each grid node is computed once (two rows of nodes at a time, in
// `row`): a column reads its four corners in the same order, so the cells are the same bits.
// Pass one stores each column's interval [k0, k1] (a byte each: dim <= 256) in `spans` and
// counts; pass two replays the intervals. Both are temporaries, given back on return: *items
// lies in their memory (readable until the next allocation), for the caller to move down at
// once. `start` (cells + 1, zeroed) ends with each cell's end in *items.
Status cell_items(Arena& arena, const Broadphase& bp, uint32_t nta, const PlaneSlab* slabs,
                  const Aabb* boxes, double reach, uint32_t* start, uint32_t** items,
                  size_t* item_count) {
  ArenaScope temporaries(arena);
  const size_t cells = size_t{bp.dim[0]} * bp.dim[1] * bp.dim[2];
  double* row = arena.allocate_array<double>(2 * 258);
  if (row == nullptr) return arena.exhausted_status();
  ArenaArray<uint8_t> spans(&arena);
  for (uint32_t t = 0; t < nta; ++t) {
    if (!count_cells(bp, slabs[t], boxes[t], reach, row, start, &spans)) {
      return arena.exhausted_status();
    }
  }
  for (size_t c = 0; c < cells; ++c) start[c + 1] += start[c];
  *item_count = start[cells];
  *items = arena.allocate_array<uint32_t>(*item_count);
  if (*items == nullptr && *item_count > 0) return arena.exhausted_status();
  size_t at = 0;
  for (uint32_t t = 0; t < nta; ++t)
    fill_cells(bp, slabs[t], boxes[t], t, spans, &at, start, *items);
  return Status::ok();
}

// The grid's cell lists (bp->start, bp->items): A's triangles whose box and plane meet each
// cell.
Status list_cells(Arena& arena, uint32_t nta, const PlaneSlab* slabs, const Aabb* boxes,
                  double reach, Broadphase* bp) {
  const size_t cells = size_t{bp->dim[0]} * bp->dim[1] * bp->dim[2];
  uint32_t* start = arena.allocate_array<uint32_t>(cells + 1);
  if (start == nullptr) return arena.exhausted_status();
  std::memset(start, 0, (cells + 1) * sizeof(uint32_t));
  uint32_t* items = nullptr;
  size_t item_count = 0;
  SPLINTCORE_RETURN_IF_ERROR(
      cell_items(arena, *bp, nta, slabs, boxes, reach, start, &items, &item_count));
  // The items down over the temporaries (a lower address: memmove).
  uint32_t* kept = arena.allocate_array<uint32_t>(item_count);
  if (kept == nullptr && item_count > 0) return arena.exhausted_status();
  if (item_count > 0) std::memmove(kept, items, item_count * sizeof(uint32_t));
  for (size_t c = cells; c > 0; --c) start[c] = start[c - 1];
  start[0] = 0;
  bp->start = start;
  bp->items = kept;
  return Status::ok();
}

// B's triangles near A's box (bp->near_b, bp->near_ids), B's indices and finiteness checked,
// and with float32 output the near ones checked float32. B's vertices are tested against the
// box once (6 outcode bits, 64 when not finite); a triangle is near when no side of the box
// has all three of its corners beyond it.
Status near_triangles_of_b(Arena& arena, const Mesh& b, bool float32_output, Broadphase* bp) {
  const uint32_t ntb = static_cast<uint32_t>(b.triangles.size());
  const uint32_t nvb = static_cast<uint32_t>(b.vertices.size());
  const Aabb& abox = bp->abox;
  uint8_t* outcode = arena.allocate_array<uint8_t>(nvb);
  bp->near_b = arena.allocate_array<uint8_t>(ntb);
  if ((outcode == nullptr && nvb > 0) || (bp->near_b == nullptr && ntb > 0)) {
    return arena.exhausted_status();
  }
  const Vec3* vb = b.vertices.data();
  for (uint32_t v = 0; v < nvb; ++v) {
    const Vec3& p = vb[v];
    outcode[v] = static_cast<uint8_t>((p.x < abox.lo.x ? 1 : 0) | (p.x > abox.hi.x ? 2 : 0) |
                                      (p.y < abox.lo.y ? 4 : 0) | (p.y > abox.hi.y ? 8 : 0) |
                                      (p.z < abox.lo.z ? 16 : 0) | (p.z > abox.hi.z ? 32 : 0) |
                                      (is_finite(p) ? 0 : 64));
  }
  bp->near_ids.bind(&arena);
  for (uint32_t t = 0; t < ntb; ++t) {
    const Triangle& tri = b.triangles[t];
    if (tri.v[0] >= nvb || tri.v[1] >= nvb || tri.v[2] >= nvb) {
      return make_error(StatusCode::kInvalidMesh, "triangle ", t,
                        " of B refers to a vertex that does not exist")
          .at_index(t);
    }
    const uint32_t o0 = outcode[tri.v[0]], o1 = outcode[tri.v[1]], o2 = outcode[tri.v[2]];
    if (((o0 | o1 | o2) & 64u) != 0) {
      return make_error(StatusCode::kNonFinite, "triangle ", t,
                        " of B has a vertex that is not finite")
          .at_index(t);
    }
    const bool is_near = ((o0 & o1 & o2) & 63u) == 0;
    bp->near_b[t] = is_near ? 1 : 0;
    if (!is_near) continue;
    if (float32_output && !(is_float32_exact(vb[tri.v[0]]) && is_float32_exact(vb[tri.v[1]]) &&
                            is_float32_exact(vb[tri.v[2]]))) {
      return b_not_float32(t);
    }
    if (!bp->near_ids.push_back(t)) return arena.exhausted_status();
  }
  return Status::ok();
}

}  // namespace

// Candidate pairs through a uniform grid over A's box: each cell lists the triangles of A
// whose box and plane meet it (A is the small mesh: the splint base). A triangle of B looks
// only at the cells its box covers, so B's many triangles far from A's surface cost a few
// comparisons each.
Status build_broadphase(const Context& ctx, const Mesh& a, const Mesh& b, double reach,
                        bool float32_output, Broadphase* bp) {
  Arena& arena = *ctx.arena;
  const uint32_t nta = static_cast<uint32_t>(a.triangles.size());
  Aabb abox = mesh_bounds(a);
  abox.lo = abox.lo - Vec3{reach, reach, reach};
  abox.hi = abox.hi + Vec3{reach, reach, reach};
  bp->abox = abox;
  PlaneSlab* slabs = nullptr;
  Aabb* boxes = nullptr;
  SPLINTCORE_RETURN_IF_ERROR(slabs_and_boxes(arena, a, reach, &slabs, &boxes));
  size_grid(nta, bp);
  SPLINTCORE_RETURN_IF_ERROR(list_cells(arena, nta, slabs, boxes, reach, bp));
  SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "boolean: cull", 0, 1));
  return near_triangles_of_b(arena, b, float32_output, bp);
}

}  // namespace boolean_detail

}  // namespace splintcore
