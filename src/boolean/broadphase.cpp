// The Boolean run, broad phase: B's triangles near A and a grid over A's box listing A's
// triangles per cell, computed once for every attempt (boolean_run.h).
#include "boolean/boolean_run.h"

namespace splintcore {
namespace boolean_detail {

namespace {

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

// Whether a cell of [lo, hi] (cell_range) is marked; true also when the range has more than
// 64 cells (not worth the look: triangle_cells then filters each cell).
bool range_marked(const Broadphase& bp, const uint64_t* marked, const uint32_t lo[3],
                  const uint32_t hi[3]) {
  if (uint64_t{hi[0] - lo[0] + 1} * (hi[1] - lo[1] + 1) * (hi[2] - lo[2] + 1) > 64) return true;
  for (uint32_t z = lo[2]; z <= hi[2]; ++z) {
    for (uint32_t y = lo[1]; y <= hi[1]; ++y) {
      const size_t row = (size_t{z} * bp.dim[1] + y) * bp.dim[0];
      for (uint32_t x = lo[0]; x <= hi[0]; ++x) {
        if ((marked[(row + x) >> 6] >> ((row + x) & 63) & 1u) != 0) return true;
      }
    }
  }
  return false;
}

constexpr size_t kParallelMarkMin = 4096;  // near triangles of B below which one thread marks
constexpr uint32_t kMaxMarkTasks = 8;

// mark_near_cells for all of B's near triangles, on the executor when it has threads: each
// task a range of them into a bitmap of its own (the first task's is `marked`), the others
// then ORed into it: the same bits as one pass. The extra bitmaps are above everything (the
// caller rewinds them); where they do not fit, one thread marks all, as it would without the
// executor. (The real dentition's second pass: 161k near triangles, 45M instructions.)
void mark_all_near_cells(const Context& ctx, const Broadphase& bp, const Mesh& b, size_t words,
                         uint64_t* marked) {
  const size_t n = bp.near_ids.size();
  const Executor* executor = ctx.executor;
  if (!has_threads(executor) || n < kParallelMarkMin) {
    mark_near_cells(bp, b, 0, n, marked);
    return;
  }
  const uint32_t tasks =
      executor->concurrency < kMaxMarkTasks ? executor->concurrency : kMaxMarkTasks;
  Arena& arena = *ctx.arena;
  uint64_t* extra = arena.allocate_array<uint64_t>(words * (tasks - 1));
  if (extra == nullptr) {
    arena.forget_failure();
    mark_near_cells(bp, b, 0, n, marked);
    return;
  }
  auto task = [&](uint32_t i) {
    uint64_t* bits = i == 0 ? marked : extra + words * (i - 1);
    if (i > 0) std::memset(bits, 0, words * sizeof(uint64_t));
    mark_near_cells(bp, b, task_start(n, i, tasks), task_start(n, i + 1, tasks), bits);
  };
  parallel_for_each(executor, tasks, task);
  for (uint32_t i = 1; i < tasks; ++i) {
    const uint64_t* bits = extra + words * (i - 1);
    for (size_t w = 0; w < words; ++w) marked[w] |= bits[w];
  }
}

// The grid's cell lists (bp->start, bp->items): the cells each triangle of A may meet
// (triangle_cells, with `reach`: every attempt's A) among those the boxes of B's near
// triangles cover (mark_near_cells: the only cells a pair test or a batch reads), so that
// the part of A far from B (a later pass's A: the imprints of the groups before) costs a box
// each. One pass over the triangles counts the cells and notes them in order (triangle by
// triangle, above the lists); the notes are then sorted into the lists by cell (a counting
// sort, each cell's triangles ascending) and the lists moved down over them.
Status list_cells(const Context& ctx, const Mesh& a, const Mesh& b, double reach, Broadphase* bp) {
  Arena& arena = *ctx.arena;
  const uint32_t nta = static_cast<uint32_t>(a.triangles.size());
  const size_t cells = size_t{bp->dim[0]} * bp->dim[1] * bp->dim[2];
  uint32_t* start = arena.allocate_array<uint32_t>(cells + 1);
  if (start == nullptr) return arena.exhausted_status();
  std::memset(start, 0, (cells + 1) * sizeof(uint32_t));
  const Arena::Marker notes_at = arena.mark();
  const size_t words = cells / 64 + 1;
  uint64_t* marked = arena.allocate_array<uint64_t>(words);
  if (marked == nullptr) return arena.exhausted_status();
  std::memset(marked, 0, words * sizeof(uint64_t));
  mark_all_near_cells(ctx, *bp, b, words, marked);
  uint32_t* note_end = arena.allocate_array<uint32_t>(nta);  // per triangle: end of its notes
  if (note_end == nullptr && nta > 0) return arena.exhausted_status();
  ArenaArray<uint32_t> notes(&arena);  // the cells, triangle by triangle
  if (!notes.reserve(size_t{nta} * 4 + 16)) return arena.exhausted_status();
  const uint32_t* dim = bp->dim;
  const size_t stride[3] = {1, dim[0], static_cast<size_t>(dim[0]) * dim[1]};
  bool fits = true;
  for (uint32_t t = 0; t < nta && fits; ++t) {
    const Triangle& at = a.triangles[t];
    const Vec3 &p0 = a.vertices[at.v[0]], &p1 = a.vertices[at.v[1]], &p2 = a.vertices[at.v[2]];
    uint32_t lo[3], hi[3];
    bp->cell_range(reach_box(p0, p1, p2, reach), lo, hi);  // triangle_cells keeps to them
    int w = 2;
    if (range_marked(*bp, marked, lo, hi)) {
      triangle_cells(
          *bp, p0, p1, p2, reach, &w, [](uint32_t, uint32_t, uint32_t) {},
          [&](uint32_t iu, uint32_t iv, uint32_t k0, uint32_t k1) {
            size_t c = iu * stride[(w + 1) % 3] + iv * stride[(w + 2) % 3] + k0 * stride[w];
            for (uint32_t k = k0; k <= k1 && fits; ++k, c += stride[w]) {
              if ((marked[c >> 6] >> (c & 63) & 1u) == 0) continue;
              ++start[c + 1];
              fits = notes.push_back(static_cast<uint32_t>(c));
            }
          });
    }
    note_end[t] = static_cast<uint32_t>(notes.size());
  }
  if (!fits) return arena.exhausted_status();
  for (size_t c = 0; c < cells; ++c) start[c + 1] += start[c];
  const size_t item_count = start[cells];
  uint32_t* sorted = arena.allocate_array<uint32_t>(item_count);
  if (sorted == nullptr && item_count > 0) return arena.exhausted_status();
  for (uint32_t t = 0, i = 0; t < nta; ++t) {
    for (; i < note_end[t]; ++i) sorted[start[notes[i]]++] = t;
  }
  // start[c] now ends cell c: shifted to start it.
  for (size_t c = cells; c > 0; --c) start[c] = start[c - 1];
  start[0] = 0;
  // The lists down over the notes (the arena keeps the bytes readable after the rewind).
  arena.rewind(notes_at);
  uint32_t* items = arena.allocate_array<uint32_t>(item_count);
  if (items == nullptr && item_count > 0) return arena.exhausted_status();
  if (item_count > 0) std::memmove(items, sorted, item_count * sizeof(uint32_t));
  bp->start = start;
  bp->items = items;
  return Status::ok();
}

// B's triangles near A's box (bp->near_b, bp->near_ids), B's indices and finiteness checked
// (unless b_valid: mesh_boolean's find_shells checked them already), and with float32 output
// the near ones checked float32. B's vertices are tested against the box once (6 outcode bits,
// 64 when not finite, 128 when not float32 and that matters); a triangle is near when no side of
// the box has all three of its corners beyond it.
template <bool kChecked>
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
    outcode[v] = static_cast<uint8_t>(abox.outcode(p) | (!kChecked || is_finite(p) ? 0 : 64) |
                                      (!float32_output || is_float32_exact(p) ? 0 : 128));
  }
  bp->near_ids.bind(&arena);
  for (uint32_t t = 0; t < ntb; ++t) {
    const Triangle& tri = b.triangles[t];
    if (kChecked && (tri.v[0] >= nvb || tri.v[1] >= nvb || tri.v[2] >= nvb)) {
      return make_error(StatusCode::kInvalidMesh, "triangle ", t,
                        " of B refers to a vertex that does not exist")
          .at_index(t);
    }
    const uint32_t o0 = outcode[tri.v[0]], o1 = outcode[tri.v[1]], o2 = outcode[tri.v[2]];
    if (kChecked && ((o0 | o1 | o2) & 64u) != 0) {
      return make_error(StatusCode::kNonFinite, "triangle ", t,
                        " of B has a vertex that is not finite")
          .at_index(t);
    }
    const bool is_near = ((o0 & o1 & o2) & 63u) == 0;
    bp->near_b[t] = is_near ? 1 : 0;
    if (!is_near) continue;
    if (((o0 | o1 | o2) & 128u) != 0) return b_not_float32(t);
    if (!bp->near_ids.push_back(t)) return arena.exhausted_status();
  }
  return Status::ok();
}

}  // namespace

// Candidate pairs through a uniform grid over A's box: each cell that the box of a near
// triangle of B covers lists the triangles of A that may meet it (A is the small mesh: the
// splint base; B's near triangles are found first). A triangle of B looks
// only at the cells its box covers, so B's many triangles far from A's surface cost a few
// comparisons each.
Status build_broadphase(const Context& ctx, const Mesh& a, const Mesh& b, double reach,
                        bool float32_output, bool b_valid, Broadphase* bp) {
  Arena& arena = *ctx.arena;
  const uint32_t nta = static_cast<uint32_t>(a.triangles.size());
  Aabb abox = mesh_bounds(a);
  abox.lo = abox.lo - Vec3{reach, reach, reach};
  abox.hi = abox.hi + Vec3{reach, reach, reach};
  bp->abox = abox;
  size_grid(nta, bp);
  SPLINTCORE_RETURN_IF_ERROR(b_valid ? near_triangles_of_b<false>(arena, b, float32_output, bp)
                                     : near_triangles_of_b<true>(arena, b, float32_output, bp));
  SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "boolean: cull", 0, 1));
  return list_cells(ctx, a, b, reach, bp);
}

void mark_near_cells(const Broadphase& bp, const Mesh& b, size_t begin, size_t end,
                     uint64_t* marked) {
  const Vec3* vb = b.vertices.data();
  for (size_t ni = begin; ni < end; ++ni) {
    uint32_t lo[3], hi[3];
    bp.cell_range(b_box(vb, b.triangles[bp.near_ids[ni]]), lo, hi);
    for (uint32_t z = lo[2]; z <= hi[2]; ++z) {
      for (uint32_t y = lo[1]; y <= hi[1]; ++y) {
        for (uint32_t x = lo[0]; x <= hi[0]; ++x) {
          const size_t c = (size_t{z} * bp.dim[1] + y) * bp.dim[0] + x;
          marked[c >> 6] |= uint64_t{1} << (c & 63);
        }
      }
    }
  }
}

// Every triangle of A the grid lists gets a slot, in A's order: the lists hold only the cells
// the boxes of B's near triangles cover (list_cells). A nudge moves A, not the grid or B: one
// numbering serves every attempt.
Status number_a_slots(Arena& arena, uint32_t nta, Broadphase* bp) {
  uint32_t* slot = arena.allocate_array<uint32_t>(nta);
  if (slot == nullptr && nta > 0) return arena.exhausted_status();
  if (nta > 0) std::memset(slot, 0xff, size_t{nta} * sizeof(uint32_t));
  const size_t cells = size_t{bp->dim[0]} * bp->dim[1] * bp->dim[2];
  for (uint32_t k = 0; k < bp->start[cells]; ++k) slot[bp->items[k]] = 0;
  uint32_t count = 0;
  for (uint32_t t = 0; t < nta; ++t) {
    if (slot[t] != ~0u) slot[t] = count++;
  }
  bp->a_slot = slot;
  bp->a_slot_count = count;
  return Status::ok();
}

}  // namespace boolean_detail

}  // namespace splintcore
