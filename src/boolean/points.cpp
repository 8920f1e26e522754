// The Boolean run, intersection points: exact pair tests (intersect_pair), the crossing
// segments and degenerate contacts found through the broad phase, their points named and
// numbered (boolean_run.h).
#include <functional>
#include <utility>

#include "boolean/boolean_run.h"

namespace splintcore {
namespace boolean_detail {

EdgePlanes edge_planes(const Vec3& a0, const Vec3& a1, const Vec3& a2) {
  const Vec3 corner[3] = {a0, a1, a2};
  const Vec3 n = cross(a1 - a0, a2 - a0);
  EdgePlanes e;
  for (int k = 0; k < 3; ++k) {
    const Vec3& p = corner[k];
    const Vec3& q = corner[(k + 1) % 3];
    e.plane[k] = plane_filter(p, q, p + n);
    const int s = filtered_side(e.plane[k], corner[(k + 2) % 3]);
    e.inside[k] = (s == 1 || s == -1) ? s : 0;
  }
  const double ax = n.x < 0 ? -n.x : n.x, ay = n.y < 0 ? -n.y : n.y, az = n.z < 0 ? -n.z : n.z;
  const int w = (ax >= ay && ax >= az) ? 0 : (ay >= az ? 1 : 2);
  e.u = (w + 1) % 3;
  e.v = (w + 2) % 3;
  for (int k = 0; k < 3; ++k) {
    const Vec3& p = corner[k];
    const Vec3& q = corner[(k + 1) % 3];
    e.pu[k] = p[e.u];
    e.pv[k] = p[e.v];
    e.du[k] = q[e.u] - p[e.u];
    e.dv[k] = q[e.v] - p[e.v];
  }
  for (int k = 0; k < 3; ++k) {
    const Vec3& r = corner[(k + 2) % 3];
    const int s = side2(e, k, r[e.u], r[e.v]);
    e.inside2[k] = (s == 1 || s == -1) ? s : 0;
  }
  return e;
}

namespace {

// B beyond one of A's edge prisms (2-D; a filter: only certain answers are used): disjoint,
// which the exact tests would answer kNone too.
inline bool beyond_edge_prism(const EdgePlanes& ea, const Vec3 B[3]) {
  const double bu[3] = {B[0][ea.u], B[1][ea.u], B[2][ea.u]};
  const double bv[3] = {B[0][ea.v], B[1][ea.v], B[2][ea.v]};
  for (int k = 0; k < 3; ++k) {
    if (ea.inside2[k] == 0) continue;
    int j = 0;
    while (j < 3 && side2(ea, k, bu[j], bv[j]) == -ea.inside2[k]) ++j;
    if (j == 3) return true;
  }
  return false;
}

// B strictly within all three of A's edge planes (3-D, the normal's direction: this test
// decides which pairs take the shortcut in intersect_pair, so it stays the one it always was;
// a pair it sends to the exact tests instead may find a degenerate contact there). sb: B's
// corners against A's plane.
inline bool within_edge_planes(const EdgePlanes& ea, const Vec3 B[3], const int sb[3]) {
  bool within = sb[0] != 0 && sb[1] != 0 && sb[2] != 0;
  for (int k = 0; k < 3 && within; ++k) {
    within = ea.inside[k] != 0;
    for (int j = 0; j < 3 && within; ++j) within = filtered_side(ea.plane[k], B[j]) == ea.inside[k];
  }
  return within;
}

// The ends of A's and B's intervals along d = n_a x n_b (the keys of the edges they lie on).
struct Intervals {
  uint64_t a_start, a_end, b_start, b_end;
};

// The segment of a crossing pair with no corner on the other plane: i0 (j0) is A's (B's) lone
// corner, on B's (A's) inside when a_inside (b_inside). The four crossing edges: A's first
// (a_i0 -> a_i0+1) and second (a_i0+2 -> a_i0), B's likewise, each in its triangle's order.
// Every answer below comes from the signs of the four tetrahedra (B edge, A edge), each
// computed at most once (orient3d is alternating, so the sign of (A edge, B edge) is the same
// number). Fills *hit when the pair crosses (kSegment).
inline PairResult order_crossings(const Vec3 A[3], const Vec3 B[3], int i0, int j0, bool a_inside,
                                  bool b_inside, const Intervals& iv, uint32_t ta, uint32_t tb,
                                  Hit* hit) {
  const int ia[2][2] = {{i0, (i0 + 1) % 3}, {(i0 + 2) % 3, i0}};
  const int jb[2][2] = {{j0, (j0 + 1) % 3}, {(j0 + 2) % 3, j0}};
  int memo[2][2] = {{2, 2}, {2, 2}};  // 2: not computed yet
  auto tet = [&](int fb, int fa) {
    int& m = memo[fb][fa];
    if (m == 2) {
      m = sign_of(orient3d(B[jb[fb][0]], B[jb[fb][1]], A[ia[fa][0]], A[ia[fa][1]]));
    }
    return m;
  };
  const int fa_start = a_inside ? 0 : 1;  // a_start is A's first crossing edge, or its second
  const int fb_start = b_inside ? 1 : 0;
  // Where B's edge fb meets A's plane, against A's triangle; A's edge fa against B's.
  auto through_a = [&](int fb) { return through(tet(fb, 0), tet(fb, 1)); };
  auto through_b = [&](int fa) { return through(tet(0, fa), tet(1, fa)); };
  // The segment is [max(starts), min(ends)]: B's start is the later one exactly when it lies
  // inside A's triangle, else A's start when it lies inside B's; likewise the ends. (B's ends
  // first: B is the small mesh's triangle in the splint case, usually inside A's.)
  bool have_start = false, have_end = false;
  const Through bs = through_a(fb_start);
  if (bs == kOnBoundary) return PairResult::kDegenerate;
  if (bs == kIn) {
    hit->start = PointKey{iv.b_start, ta, 0};
    have_start = true;
  } else {
    const Through as = through_b(fa_start);
    if (as == kOnBoundary) return PairResult::kDegenerate;
    if (as == kIn) {
      hit->start = PointKey{iv.a_start, tb, 0};
      have_start = true;
    }
  }
  const Through be = through_a(1 - fb_start);
  if (be == kOnBoundary) return PairResult::kDegenerate;
  if (be == kIn) {
    hit->end = PointKey{iv.b_end, ta, 0};
    have_end = true;
  } else {
    const Through ae = through_b(1 - fa_start);
    if (ae == kOnBoundary) return PairResult::kDegenerate;
    if (ae == kIn) {
      hit->end = PointKey{iv.a_end, tb, 0};
      have_end = true;
    }
  }
  if (!have_start && !have_end) return PairResult::kNone;
  if (have_start != have_end) return PairResult::kDegenerate;  // cannot happen exactly
  hit->ta = ta;
  hit->tb = tb;
  return PairResult::kSegment;
}

}  // namespace

// pa, pb: the planes of ta and tb as filters (plane_filter of their corners in order); ea:
// ta's edge planes. The caller has tested tb's whole box against ea's planes first
// (detail::box_beyond): a box strictly beyond one means disjoint triangles, which the exact
// tests below would answer kNone too (a cheaper filter first, never a different answer).
PairResult intersect_pair(const Inputs& in, uint32_t ta, uint32_t tb, const PlaneFilter& pa,
                          const EdgePlanes& ea, const PlaneFilter& pb, Hit* hit) {
  uint32_t ga[3], gb[3];
  in.corners(ta, ga);
  in.corners(tb, gb);
  const Vec3 A[3] = {in.vertex(ga[0]), in.vertex(ga[1]), in.vertex(ga[2])};
  const Vec3 B[3] = {in.vertex(gb[0]), in.vertex(gb[1]), in.vertex(gb[2])};
  // sa[i] > 0: A's corner i is below B's plane (on B's inside); sb likewise.
  int sa[3], sb[3];
  for (int j = 0; j < 3; ++j) sb[j] = -exact_side(pa, A[1], A[2], B[j]);
  if (sb[0] == sb[1] && sb[1] == sb[2] && sb[0] != 0) return PairResult::kNone;
  if (beyond_edge_prism(ea, B)) return PairResult::kNone;
  const bool within = within_edge_planes(ea, B, sb);
  const int j0 = lone(sb);
  Intervals iv;
  // B's interval along d_b = n_b x n_a runs from its edge (b_j0, b_j0+1) to (b_j0+2, b_j0) when
  // b_j0 is on A's inside (by symmetry with A's below), so along d it is reversed.
  const uint64_t b_first = edge_key(gb[j0], gb[(j0 + 1) % 3]);
  const uint64_t b_second = edge_key(gb[(j0 + 2) % 3], gb[j0]);
  iv.b_start = sb[j0] > 0 ? b_second : b_first;
  iv.b_end = sb[j0] > 0 ? b_first : b_second;
  if (within) {
    // Both of B's crossings of A's plane lie inside A: the segment is B's whole interval.
    hit->start = PointKey{iv.b_start, ta, 0};
    hit->end = PointKey{iv.b_end, ta, 0};
    hit->ta = ta;
    hit->tb = tb;
    return PairResult::kSegment;
  }
  for (int i = 0; i < 3; ++i) sa[i] = -exact_side(pb, B[1], B[2], A[i]);
  if (sa[0] == sa[1] && sa[1] == sa[2] && sa[0] != 0) return PairResult::kNone;
  if (sa[0] == 0 || sa[1] == 0 || sa[2] == 0 || sb[0] == 0 || sb[1] == 0 || sb[2] == 0) {
    return triangles_intersect(A[0], A[1], A[2], B[0], B[1], B[2]) ? PairResult::kDegenerate
                                                                   : PairResult::kNone;
  }
  const int i0 = lone(sa);
  // A's interval along d = n_a x n_b: from its edge (a_i0, a_i0+1) to its edge (a_i0+2, a_i0)
  // when a_i0 is on the inside of B's plane, the other way round otherwise.
  const uint64_t a_first = edge_key(ga[i0], ga[(i0 + 1) % 3]);
  const uint64_t a_second = edge_key(ga[(i0 + 2) % 3], ga[i0]);
  iv.a_start = sa[i0] > 0 ? a_first : a_second;
  iv.a_end = sa[i0] > 0 ? a_second : a_first;
  return order_crossings(A, B, i0, j0, sa[i0] > 0, sb[j0] > 0, iv, ta, tb, hit);
}

// The exact crossing rounded once: the same key always gives the same bits.
Point make_point(const Inputs& in, const PointKey& key) {
  const Vec3 u = in.vertex(key_hi(key.edge));
  const Vec3 v = in.vertex(key_lo(key.edge));
  uint32_t g[3];
  in.corners(key.tri, g);
  const Vec3 t0 = in.vertex(g[0]);
  const Vec3 n = cross(in.vertex(g[1]) - t0, in.vertex(g[2]) - t0);
  const double du = dot(n, u - t0);
  const double dv = dot(n, v - t0);
  double s = du / (du - dv);
  if (!(s > 0.0)) s = 0.0;
  if (s > 1.0) s = 1.0;
  Point pt;
  pt.p = u + (v - u) * s;
  pt.s = s;
  pt.key = key;
  return pt;
}

// Stable sort of small KeyIndex arrays (insertion) or large ones (radix).
Status sort_keys(Arena& arena, KeyIndex* items, size_t n) {
  if (n <= 48) {
    for (size_t i = 1; i < n; ++i) {
      const KeyIndex x = items[i];
      size_t j = i;
      while (j > 0 && items[j - 1].key > x.key) {
        items[j] = items[j - 1];
        --j;
      }
      items[j] = x;
    }
    return Status::ok();
  }
  return radix_sort(arena, Span<KeyIndex>(items, n));
}

Status BooleanRun::degenerate(uint32_t ta, uint32_t tb) const {
  return make_error(StatusCode::kUnsupported, "contact between triangle ", ta,
                    " of A and triangle ", in_.named_triangle(tb),
                    " of B not decided: a coordinate is outside the exact predicates' range "
                    "(0, or 2^-300 .. 2^330 in magnitude)")
      .at_index(ta);
}

Status BooleanRun::check_pair_budget(uint32_t tb) const {
  if (st_.candidate_pairs <= pair_budget_) return Status::ok();
  // (Within the 255 characters of a Status message with 10-digit numbers.)
  return make_error(StatusCode::kLimitExceeded, "Boolean: over ", pair_budget_,
                    " candidate triangle pairs (max_candidate_pairs) at triangle ",
                    in_.b_triangle(tb),
                    " of B: A and B nearly coincide or crowd over a large area (e.g. long thin "
                    "triangles over dense ones); raise the bound to run it anyway")
      .at_index(in_.b_triangle(tb));
}

namespace {

// f(ta) for every triangle of A listed in the grid cells `box` covers (a triangle of A in
// several of them comes once per cell). Returns false as soon as f does.
template <class F>
bool for_each_listed(const Broadphase& bp, const Aabb& box, F&& f) {
  uint32_t lo[3], hi[3];
  bp.cell_range(box, lo, hi);
  for (uint32_t z = lo[2]; z <= hi[2]; ++z) {
    for (uint32_t y = lo[1]; y <= hi[1]; ++y) {
      for (uint32_t x = lo[0]; x <= hi[0]; ++x) {
        const size_t c = (size_t{z} * bp.dim[1] + y) * bp.dim[0] + x;
        for (uint32_t k = bp.start[c]; k < bp.start[c + 1]; ++k) {
          if (!f(bp.items[k])) return false;
        }
      }
    }
  }
  return true;
}

}  // namespace

// The slots' arrays for `count` triangles of A (about 470 bytes each).
Status BooleanRun::allocate_a_slots(uint32_t count, ASlots* out) {
  out->count = count;
  out->filters = arena_.allocate_array<PlaneFilter>(count);
  out->edges = arena_.allocate_array<EdgePlanes>(count);
  out->boxes = arena_.allocate_array<Aabb>(count);
  out->stamp = arena_.allocate_array<uint32_t>(count);
  if (count > 0 && (out->filters == nullptr || out->edges == nullptr || out->boxes == nullptr ||
                    out->stamp == nullptr)) {
    return arena_.exhausted_status();
  }
  return Status::ok();
}

// Slot k: the filters, edge planes and box of A's triangle t as this attempt has it (values of
// t alone, whichever slot holds them), its stamp cleared.
void BooleanRun::fill_a_slot(uint32_t t, uint32_t k, const ASlots& as) const {
  const Mesh& a = *in_.a;
  const Triangle& at = a.triangles[t];
  const Vec3& p0 = a.vertices[at.v[0]];
  const Vec3& p1 = a.vertices[at.v[1]];
  const Vec3& p2 = a.vertices[at.v[2]];
  as.filters[k] = plane_filter(p0, p1, p2);
  as.edges[k] = edge_planes(p0, p1, p2);
  as.boxes[k] = Aabb{};
  as.boxes[k].add(p0);
  as.boxes[k].add(p1);
  as.boxes[k].add(p2);
  as.stamp[k] = ~0u;
}

// The triangles of A that some near triangle of B may meet (listed in a cell its box covers:
// number_a_slots, once for all attempts) get a slot: their filters, edge planes, boxes and
// stamps (about 470 bytes each) are made for them only, from A as this attempt has it. A may be
// large and mostly far from this B: in a later pass of mesh_boolean it is the previous result,
// far from most of the next group of shells.
Status BooleanRun::prepare_a_slots(ASlots* out) {
  SPLINTCORE_RETURN_IF_ERROR(allocate_a_slots(bp_.a_slot_count, out));
  out->slot = bp_.a_slot;
  // Each slot's planes and box from A as this attempt has it, in chunks of A's triangles on the
  // executor (each writes only its own slots: the same values at every thread count).
  constexpr uint32_t kChunk = 8192;
  const uint32_t nta = in_.nta;
  const uint32_t chunks = (nta + kChunk - 1) / kChunk;
  const uint32_t* slot = bp_.a_slot;
  auto task = [&](uint32_t c) {
    const uint32_t end = nta - c * kChunk < kChunk ? nta : c * kChunk + kChunk;
    for (uint32_t t = c * kChunk; t < end; ++t) {
      if (slot[t] != ~0u) fill_a_slot(t, slot[t], *out);
    }
  };
  parallel_for_each(ctx_.executor, chunks, task);
  return Status::ok();
}

namespace {

// B's near triangle t against the triangles of A its box's cells list, each pair decided
// exactly (intersect_pair) with A as this attempt has it: every candidate pair counted in
// *candidates, each crossing given to on_hit(hit), each degenerate pair to on_contact(ta) and a
// flat t meeting A to on_flat(ta). `stamp` (one per slot of A) skips an A triangle listed in
// several cells; any stamps work that hold no triangle id of B yet. Returns false as soon as
// a handler does.
template <class Slots, class OnHit, class OnContact, class OnFlat>
bool test_near_triangle(const Inputs& in, const Broadphase& bp, const Slots& as, uint32_t* stamp,
                        uint32_t t, uint64_t* candidates, OnHit&& on_hit, OnContact&& on_contact,
                        OnFlat&& on_flat) {
  const Vec3* vb = in.b->vertices.data();
  const Triangle& tri = in.b->triangles[t];
  const Aabb box = b_box(vb, tri);
  bool flat_checked = false;
  PlaneFilter pb{};
  const Vec3 bc = (box.lo + box.hi) * 0.5;
  const Vec3 bext = box.hi - box.lo;
  return for_each_listed(bp, box, [&](uint32_t ta) {
    const uint32_t k = as.slot[ta];
    if (stamp[k] == t) return true;
    stamp[k] = t;
    if (!as.boxes[k].overlaps(box)) return true;
    ++*candidates;
    if (!flat_checked) {
      if (collinear3d(vb[tri.v[0]], vb[tri.v[1]], vb[tri.v[2]])) return on_flat(ta);
      flat_checked = true;
      pb = plane_filter(vb[tri.v[0]], vb[tri.v[1]], vb[tri.v[2]]);
    }
    // B's whole box strictly beyond one of A's edge planes: disjoint, which intersect_pair
    // would answer kNone (tested here: it spares the call for most pairs).
    const EdgePlanes& ea = as.edges[k];
    if ((ea.inside[0] != 0 && detail::box_beyond(ea.plane[0], ea.inside[0], bc, bext)) ||
        (ea.inside[1] != 0 && detail::box_beyond(ea.plane[1], ea.inside[1], bc, bext)) ||
        (ea.inside[2] != 0 && detail::box_beyond(ea.plane[2], ea.inside[2], bc, bext))) {
      return true;
    }
    Hit hit;
    const PairResult r = intersect_pair(in, ta, in.nta + t, as.filters[k], ea, pb, &hit);
    if (r == PairResult::kDegenerate) return on_contact(ta);
    if (r == PairResult::kSegment) return on_hit(hit);
    return true;
  });
}

// One task of the parallel prefix (BooleanRun::hits_in_parallel): the near triangles
// [begin, end) of B with its own stamps and hits. It stops before the first triangle that
// needs more than that (a degenerate pair, which add_contact records in the run; a flat
// triangle; a full buffer) or that takes its candidate pairs over the budget: done, hits and
// candidates are those of the triangles before `stop`.
struct HitTask {
  size_t begin = 0, end = 0, stop = 0;
  uint32_t* stamp = nullptr;
  Hit* hits = nullptr;
  size_t capacity = 0, count = 0;
  uint64_t candidates = 0;
};

constexpr size_t kParallelHitsMin = 4096;  // near triangles of B below which one thread does all
constexpr uint32_t kHitTasksPerThread = 2;
constexpr uint32_t kMaxHitTasks = 16;

}  // namespace

// The near triangles of B split into tasks run on the executor, each stopping where the run's
// own state would be needed; their hits are then joined in task order (the order one thread
// finds them in) at the bottom of their slab, which becomes hits_, with the capacity push_back
// would have given it: the arena is then as one thread leaves it. Returns the near index the
// serial loop goes on from (the first task that stopped early, or whose candidates pass the
// budget: that task is redone) with st_.candidate_pairs counting those before it. The slab is
// extra memory (per task 4 bytes per slot of A, and 20 per near triangle, 2.5 when short): without
// it, or when the hits need more than it and the arena has no more above it, one thread does all
// (0), and everything is the same but the time.
size_t BooleanRun::hits_in_parallel(const ASlots& as) {
  const Executor* executor = ctx_.executor;
  const size_t n = bp_.near_ids.size();
  if (!has_threads(executor) || n < kParallelHitsMin) return 0;
  uint32_t tasks = executor->concurrency * kHitTasksPerThread;
  if (tasks > kMaxHitTasks) tasks = kMaxHitTasks;
  const size_t per_task = (n + tasks - 1) / tasks;
  const size_t stamp_hits = (size_t{as.count} * sizeof(uint32_t) + sizeof(Hit) - 1) / sizeof(Hit);
  // A hit per 2 near triangles (the 87k phantom: 1 per 2.2; the real case: 1 per 25), or
  // where the arena is short a hit per 16; more stops the task (one thread goes on there).
  const Arena::Marker before = arena_.mark();
  size_t capacity = per_task / 2 + 256, slice = 0, slab_hits = 0;
  Hit* slab = nullptr;
  for (int attempt = 0; attempt < 2 && slab == nullptr; ++attempt) {
    if (attempt == 1) capacity = per_task / 16 + 256;
    slice = stamp_hits + capacity;  // in Hits: the stamps, then the hits
    slab_hits = slice * tasks;
    slab = arena_.allocate_array<Hit>(slab_hits);
    if (slab == nullptr) arena_.forget_failure();
  }
  if (slab == nullptr || arena_.mark().block != before.block) {  // (a new block: hooks mode)
    arena_.rewind(before);
    return 0;  // one thread does it all, in the memory it needs
  }
  HitTask task[kMaxHitTasks];
  for (uint32_t i = 0; i < tasks; ++i) {
    HitTask& h = task[i];
    h.begin = per_task * i < n ? per_task * i : n;
    h.end = h.begin + per_task < n ? h.begin + per_task : n;
    h.stop = h.begin;
    h.stamp = reinterpret_cast<uint32_t*>(slab + slice * i);
    h.hits = slab + slice * i + stamp_hits;
    h.capacity = capacity;
  }
  const uint64_t budget_left =
      pair_budget_ > st_.candidate_pairs ? pair_budget_ - st_.candidate_pairs : 0;
  auto run_task = [&](uint32_t i) {
    HitTask& h = task[i];
    for (uint32_t k = 0; k < as.count; ++k) h.stamp[k] = ~0u;
    const auto stop = [](uint32_t) { return false; };
    for (size_t ni = h.begin; ni < h.end; ++ni) {
      const size_t count = h.count;
      const uint64_t candidates = h.candidates;
      const bool done = test_near_triangle(
          in_, bp_, as, h.stamp, bp_.near_ids[ni], &h.candidates,
          [&h](const Hit& hit) {
            if (h.count == h.capacity) return false;
            h.hits[h.count++] = hit;
            return true;
          },
          stop, stop);
      if (!done || h.candidates > budget_left) {
        h.count = count;
        h.candidates = candidates;
        break;
      }
      h.stop = ni + 1;
    }
  };
  parallel_for_each(executor, tasks, run_task);
  size_t joined = 0, resume = n;
  uint64_t candidates = 0, done = 0;
  for (uint32_t i = 0; i < tasks; ++i) {
    const HitTask& h = task[i];
    if (candidates + h.candidates > budget_left) {  // the serial loop names where it passes
      resume = h.begin;
      break;
    }
    candidates += h.candidates;
    done += h.stop - h.begin;
    std::memmove(static_cast<void*>(slab + joined), h.hits, h.count * sizeof(Hit));
    joined += h.count;
    if (h.stop != h.end) {
      resume = h.stop;
      break;
    }
  }
  size_t capacity_one_thread = 0;  // push_back's, joined times from empty
  while (capacity_one_thread < joined) {
    capacity_one_thread = ArenaArray<Hit>::grown_capacity(capacity_one_thread);
  }
  const size_t have = slab_hits * sizeof(Hit), need = capacity_one_thread * sizeof(Hit);
  if (capacity_one_thread == 0) {
    arena_.rewind(before);
  } else if (need <= have ? !arena_.try_shrink(slab, have, need)
                          : !arena_.try_extend(slab, have, need)) {
    arena_.rewind(before);
    return 0;  // one thread would have taken other memory for them: it does it all
  } else {
    hits_.adopt(slab, joined, capacity_one_thread);
  }
  st_.candidate_pairs += candidates;
  st_.parallel_near_triangles += done;
  return resume;
}

// The near triangles [from, to) of B, in order, with the run's state (contacts, errors, the
// bound on pairs): each candidate pair decided exactly (intersect_pair) with A as this attempt
// has it.
Status BooleanRun::hits_serial(const ASlots& as, size_t from, size_t to) {
  Status failed;
  for (size_t ni = from; ni < to; ++ni) {
    const uint32_t t = bp_.near_ids[ni];
    if (ni == from || (ni & 65535u) == 0) {
      SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx_, "boolean: hits", ni, bp_.near_ids.size()));
    }
    const bool done = test_near_triangle(
        in_, bp_, as, as.stamp, t, &st_.candidate_pairs,
        [&](const Hit& hit) {
          if (hits_.push_back(hit)) return true;
          failed = arena_.exhausted_status();
          return false;
        },
        [&](uint32_t ta) {
          failed = add_contact(ta, in_.nta + t);
          return failed.is_ok();
        },
        [&](uint32_t ta) {
          failed = make_error(StatusCode::kInvalidMesh, "triangle ", in_.b_triangle(t),
                              " of B is degenerate (zero area) and meets A near triangle ", ta)
                       .at_index(in_.b_triangle(t));
          return false;
        });
    if (!done) return failed;
    SPLINTCORE_RETURN_IF_ERROR(check_pair_budget(t));
  }
  return Status::ok();
}

namespace {

// The near triangles of B go in this many batches when A's slots for all of them do not fit.
constexpr size_t kHitBatches = 8;

// The triangles of A listed in the cells the boxes of B's near triangles [begin, end) cover,
// each once, in `members` (the cells' order), numbered there in slot[] (UINT32_MAX before);
// `marked` (a bit per cell, all clear) is left clear. Returns how many.
uint32_t list_batch(const Broadphase& bp, const Mesh& b, size_t begin, size_t end, uint64_t* marked,
                    uint32_t* slot, uint32_t* members) {
  mark_near_cells(bp, b, begin, end, marked);
  const size_t words = (size_t{bp.dim[0]} * bp.dim[1] * bp.dim[2]) / 64 + 1;
  uint32_t count = 0;
  for (size_t w = 0; w < words; ++w) {
    for (uint64_t bits = marked[w]; bits != 0; bits &= bits - 1) {
      const size_t c = w * 64 + static_cast<size_t>(__builtin_ctzll(bits));
      for (uint32_t k = bp.start[c]; k < bp.start[c + 1]; ++k) {
        const uint32_t ta = bp.items[k];
        if (slot[ta] != ~0u) continue;
        slot[ta] = count;
        members[count++] = ta;
      }
    }
    marked[w] = 0;
  }
  return count;
}

}  // namespace

// When A's slots for all of B's near triangles would not fit (find_hits), the near triangles go
// in kHitBatches runs, in order, each with slots for only the triangles of A its cells list (a
// triangle of A listed by two batches gets its slot made twice): the same pairs tested in the
// same order, so the same hits, contacts, stats and errors, in about 1/kHitBatches of the
// slots' memory (B's near triangles come in B's order, which is mostly local: a swept
// surface's is its extractor's) plus 8 bytes per triangle of A and a bit per cell. One thread.
Status BooleanRun::hits_in_batches() {
  const size_t n = bp_.near_ids.size();
  const uint32_t nta = in_.nta;
  const size_t words = (size_t{bp_.dim[0]} * bp_.dim[1] * bp_.dim[2]) / 64 + 1;
  uint32_t* slot = arena_.allocate_array<uint32_t>(nta);
  uint32_t* members = arena_.allocate_array<uint32_t>(bp_.a_slot_count);
  uint64_t* marked = arena_.allocate_array<uint64_t>(words);
  if (((slot == nullptr && nta > 0) || (members == nullptr && bp_.a_slot_count > 0)) ||
      marked == nullptr) {
    return arena_.exhausted_status();
  }
  if (nta > 0) std::memset(slot, 0xff, size_t{nta} * sizeof(uint32_t));
  std::memset(marked, 0, words * sizeof(uint64_t));
  const size_t per = n / kHitBatches + 1;
  uint32_t most = 0;  // the largest batch's slots
  for (size_t begin = 0; begin < n; begin += per) {
    const size_t end = n - begin < per ? n : begin + per;
    const uint32_t count = list_batch(bp_, *in_.b, begin, end, marked, slot, members);
    for (uint32_t i = 0; i < count; ++i) slot[members[i]] = ~0u;
    most = count > most ? count : most;
  }
  ASlots as;
  SPLINTCORE_RETURN_IF_ERROR(allocate_a_slots(most, &as));
  as.slot = slot;
  for (size_t begin = 0; begin < n; begin += per) {
    const size_t end = n - begin < per ? n : begin + per;
    const uint32_t count = list_batch(bp_, *in_.b, begin, end, marked, slot, members);
    for (uint32_t i = 0; i < count; ++i) fill_a_slot(members[i], i, as);
    SPLINTCORE_RETURN_IF_ERROR(hits_serial(as, begin, end));
    for (uint32_t i = 0; i < count; ++i) slot[members[i]] = ~0u;
    ++st_.hit_batches;
  }
  return Status::ok();
}

// Candidate pairs through the broad phase's grid; each decided exactly (intersect_pair) with A
// as this attempt has it. With an executor a parallel prefix does most of them
// (hits_in_parallel); one thread goes on from where it stopped, with the run's state. When the
// slots for all of A's triangles near B do not fit, B's near triangles go in batches instead
// (hits_in_batches): everything is the same but the time and the memory.
Status BooleanRun::find_hits() {
  const uint32_t nv_in = in_.nva + in_.nvb;
  vstate_ = arena_.allocate_array<int8_t>(nv_in);
  if (vstate_ == nullptr && nv_in > 0) return arena_.exhausted_status();
  if (nv_in > 0) std::memset(vstate_, 0, nv_in);
  const Arena::Marker slots_at = arena_.mark();
  // Batches when the slots would take more than half of what the arena has left (the hits
  // grow above them), or do not fit at all.
  const size_t left = arena_.cap() > arena_.used() ? arena_.cap() - arena_.used() : 0;
  const uint64_t slot_bytes =
      uint64_t{bp_.a_slot_count} * (sizeof(PlaneFilter) + sizeof(EdgePlanes) + sizeof(Aabb) + 4);
  const bool can_batch = bp_.near_ids.size() >= kHitBatches;
  bool batches = can_batch && slot_bytes > left / 2;
  ASlots as;
  if (!batches) {
    const Status prepared = prepare_a_slots(&as);
    if (prepared.code() == StatusCode::kArenaExhausted && can_batch) {
      arena_.rewind(slots_at);
      arena_.forget_failure();
      batches = true;
    } else {
      SPLINTCORE_RETURN_IF_ERROR(prepared);
    }
  }
  st_.near_b_triangles = bp_.near_ids.size();
  SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx_, "boolean: hits", 0, 1));
  hits_.bind(&arena_);
  deg_.bind(&arena_);
  if (batches) {
    SPLINTCORE_RETURN_IF_ERROR(hits_in_batches());
  } else {
    const size_t from = hits_in_parallel(as);
    SPLINTCORE_RETURN_IF_ERROR(hits_serial(as, from, bp_.near_ids.size()));
  }
  st_.intersecting_pairs = hits_.size();
  hits_over_slots(slots_at);
  return Status::ok();
}

// The slots of A (about 470 bytes per triangle of A near B, a fifth of the blockout's Boolean
// on the real dentition) are done with once the hits are found: what the stage keeps above
// them (the hits, and the contacts recorded and B's vertices aliased to A's when there are
// any) moves down over them, lowest first (each lands at or below where it was, never on one
// not yet moved), so the rest of the run has that room, and the stage leaves the same bytes
// behind whether its slots were taken whole or in batches: the room there was decides only
// that (a whole stage left above a hole of slots had failed later where the batches fit,
// under a smaller cap). Nothing is added to the hits and contacts after this: they keep no
// spare capacity (push_back's growth left up to a third of them). In hooks mode with the
// stage across blocks the spare capacity is given back where they lie, when at the top.
void BooleanRun::hits_over_slots(const Arena::Marker& slots_at) {
  if (arena_.mark().block != slots_at.block) {
    hits_.shrink_to_fit();
    deg_.shrink_to_fit();
    return;
  }
  struct Live {
    const void* at;
    size_t bytes, align;
    void* moved;
  };
  Live live[3];
  int n = 0;
  const auto add = [&](const void* at, size_t bytes, size_t align) {
    if (at != nullptr && bytes > 0) live[n++] = Live{at, bytes, align, nullptr};
  };
  add(hits_.data(), hits_.size() * sizeof(Hit), alignof(Hit));
  add(deg_.data(), deg_.size() * sizeof(DegRecord), alignof(DegRecord));
  add(alias_, alias_ != nullptr ? size_t{in_.nvb} * sizeof(uint32_t) : 0, alignof(uint32_t));
  for (int i = 1; i < n; ++i) {  // by address (three at most)
    for (int k = i; k > 0 && std::less<const void*>()(live[k].at, live[k - 1].at); --k) {
      std::swap(live[k], live[k - 1]);
    }
  }
  const size_t hit_count = hits_.size(), deg_count = deg_.size();
  const void* hits_at = hits_.data();
  const void* deg_at = deg_.data();
  const void* alias_at = alias_;
  arena_.rewind(slots_at);
  for (int i = 0; i < n; ++i) {
    const size_t align =
        live[i].align > Arena::kDefaultAlignment ? live[i].align : Arena::kDefaultAlignment;
    live[i].moved = arena_.allocate(live[i].bytes, align);  // at or below where it was: it fits
    SPLINTCORE_ASSERT(live[i].moved != nullptr &&
                      !std::less<const void*>()(live[i].at, live[i].moved));
    std::memmove(live[i].moved, live[i].at, live[i].bytes);
  }
  const auto moved = [&](const void* at) {
    for (int i = 0; i < n; ++i) {
      if (live[i].at == at) return live[i].moved;
    }
    return static_cast<void*>(nullptr);
  };
  hits_.bind(&arena_);
  deg_.bind(&arena_);
  if (hit_count > 0) hits_.adopt(static_cast<Hit*>(moved(hits_at)), hit_count, hit_count);
  if (deg_count > 0) deg_.adopt(static_cast<DegRecord*>(moved(deg_at)), deg_count, deg_count);
  if (alias_at != nullptr) alias_ = static_cast<uint32_t*>(moved(alias_at));
}

namespace {

// The predicates are exact for coordinates 0 or of magnitude 2^-306 .. 2^338 (geometry.h);
// outside that (subnormal or astronomical coordinates) the contact is not decided here.
bool within_exact_range(const Vec3 A[3], const Vec3 B[3]) {
  for (int i = 0; i < 3; ++i) {
    for (int k = 0; k < 3; ++k) {
      const double x = A[i][k] < 0 ? -A[i][k] : A[i][k];
      const double y = B[i][k] < 0 ? -B[i][k] : B[i][k];
      if ((x != 0 && (x < 0x1p-300 || x > 0x1p330)) || (y != 0 && (y < 0x1p-300 || y > 0x1p330))) {
        return false;
      }
    }
  }
  return true;
}

}  // namespace

// Vertex bv of B lies on vertex av of A: bv becomes av (alias_, allocated at the first one).
Status BooleanRun::alias_b_vertex(uint32_t bv, uint32_t av) {
  if (alias_ == nullptr) {
    alias_ = arena_.allocate_array<uint32_t>(in_.nvb);
    if (alias_ == nullptr) return arena_.exhausted_status();
    std::memset(alias_, 0xff, size_t{in_.nvb} * sizeof(uint32_t));
  }
  uint32_t& al = alias_[bv - in_.nva];
  if (al != ~0u && al != av) {
    return make_error(StatusCode::kUnsupported, "vertex ", in_.named_vertex(bv),
                      " of B lies on two vertices of A (", al, " and ", av,
                      "): A has coincident vertices")
        .at_index(in_.named_vertex(bv));
  }
  al = av;
  return Status::ok();
}

// The name of contact point cp between triangles ta (corners ga) and tb (corners gb) (DegPoint);
// an input vertex on the other surface is marked kVertexOn.
Status BooleanRun::name_contact_point(const detail::ContactPoint& cp, const uint32_t ga[3],
                                      const uint32_t gb[3], uint32_t ta, uint32_t tb,
                                      DegPoint* name) {
  using detail::Loc;
  DegPoint d{0, 0, kDegVertex};
  const bool va = detail::loc_is_vertex(cp.on_a), vb = detail::loc_is_vertex(cp.on_b);
  if (va) {
    d.k1 = ga[detail::loc_index(cp.on_a)];
    vstate_[d.k1] = kVertexOn;
    if (vb) {
      const uint32_t bv = gb[detail::loc_index(cp.on_b)];
      vstate_[bv] = kVertexOn;
      SPLINTCORE_RETURN_IF_ERROR(alias_b_vertex(bv, static_cast<uint32_t>(d.k1)));
    }
  } else if (vb) {
    d.k1 = gb[detail::loc_index(cp.on_b)];
    vstate_[d.k1] = kVertexOn;
  } else {
    const int i0 = detail::loc_index(cp.on_a), j0 = detail::loc_index(cp.on_b);
    if (cp.on_b == Loc::kFace) {
      d = DegPoint{edge_key(ga[i0], ga[(i0 + 1) % 3]), tb, kDegEdgeFace};
    } else if (cp.on_a == Loc::kFace) {
      d = DegPoint{edge_key(gb[j0], gb[(j0 + 1) % 3]), ta, kDegEdgeFace};
    } else {
      d = DegPoint{edge_key(ga[i0], ga[(i0 + 1) % 3]), edge_key(gb[j0], gb[(j0 + 1) % 3]),
                   kDegEdgeEdge};
    }
  }
  *name = d;
  return Status::ok();
}

// The part of contact c from its point i to its point j (a lone point when i == j), recorded
// for ta and for tb.
Status BooleanRun::record_contact(const detail::Contact& c, const DegPoint name[6], int i, int j,
                                  uint8_t kind, uint32_t ta, uint32_t tb) {
  const detail::ContactPoint& p = c.p[i];
  const detail::ContactPoint& q = c.p[j];
  DegRecord ra{};
  ra.p[0] = name[i];
  ra.p[1] = name[j];
  ra.tri = ta;
  ra.other = tb;
  ra.kind = kind;
  DegRecord rb = ra;
  rb.tri = tb;
  rb.other = ta;
  ra.loc_t[0] = static_cast<uint8_t>(p.on_a);
  ra.loc_t[1] = static_cast<uint8_t>(q.on_a);
  ra.loc_o[0] = static_cast<uint8_t>(p.on_b);
  ra.loc_o[1] = static_cast<uint8_t>(q.on_b);
  rb.loc_t[0] = ra.loc_o[0];
  rb.loc_t[1] = ra.loc_o[1];
  rb.loc_o[0] = ra.loc_t[0];
  rb.loc_o[1] = ra.loc_t[1];
  // A lone point at a corner of the triangle changes nothing there (flooding treats the
  // corner as on the other surface).
  if (kind != kDegPointOnly || !detail::loc_is_vertex(p.on_a)) {
    if (!deg_.push_back(ra)) return arena_.exhausted_status();
  }
  if (kind != kDegPointOnly || !detail::loc_is_vertex(p.on_b)) {
    if (!deg_.push_back(rb)) return arena_.exhausted_status();
  }
  return Status::ok();
}

// A degenerate pair (a corner on the other plane, or edges meeting exactly): its exact contact
// (contact.h) becomes records for both triangles. Input vertices on the other surface are
// marked (kVertexOn); a vertex of B on a vertex of A becomes that vertex (alias_).
Status BooleanRun::add_contact(uint32_t ta, uint32_t tb) {
  uint32_t ga[3], gb[3];
  in_.corners(ta, ga);
  in_.corners(tb, gb);
  const Vec3 A[3] = {in_.vertex(ga[0]), in_.vertex(ga[1]), in_.vertex(ga[2])};
  const Vec3 B[3] = {in_.vertex(gb[0]), in_.vertex(gb[1]), in_.vertex(gb[2])};
  if (!within_exact_range(A, B)) return degenerate(ta, tb);
  detail::Contact c;
  if (!detail::intersect_triangles(A, B, &c)) return degenerate(ta, tb);
  if (c.kind == detail::ContactKind::kNone) return Status::ok();
  ++st_.degenerate_pairs;
  DegPoint name[6];
  for (int i = 0; i < c.count; ++i) {
    SPLINTCORE_RETURN_IF_ERROR(name_contact_point(c.p[i], ga, gb, ta, tb, &name[i]));
  }
  switch (c.kind) {
    case detail::ContactKind::kPoint: return record_contact(c, name, 0, 0, kDegPointOnly, ta, tb);
    case detail::ContactKind::kSegment:
      return record_contact(c, name, 0, 1, c.coplanar ? kDegCoplanar : kDegTransversal, ta, tb);
    case detail::ContactKind::kPolygon:
      for (int i = 0; i < c.count; ++i) {
        SPLINTCORE_RETURN_IF_ERROR(
            record_contact(c, name, i, (i + 1) % c.count, kDegCoplanar, ta, tb));
      }
      return Status::ok();
    case detail::ContactKind::kNone: break;
  }
  return Status::ok();
}

// The points of the degenerate contacts get vertex ids: an input vertex its own (its alias for
// B), an edge through a triangle the id of the same point of a crossing pair when there is one
// (points_ is sorted by (edge, triangle) here), new points after the others otherwise, in
// (kind, k1, k2) order, each computed once from its name.
Status BooleanRun::number_degenerate_points() {
  const size_t nd = deg_.size();
  if (nd == 0) return Status::ok();
  const uint32_t base = in_.nva + in_.nvb;
  const size_t n0 = points_.size();
  auto find_ef = [&](const DegPoint& d) -> uint32_t {
    size_t lo = 0, hi = n0;
    while (lo < hi) {
      const size_t mid = (lo + hi) / 2;
      const PointKey& k = points_[mid].key;
      if (k.edge < d.k1 || (k.edge == d.k1 && k.tri < d.k2))
        lo = mid + 1;
      else
        hi = mid;
    }
    return (lo < n0 && points_[lo].key.edge == d.k1 && points_[lo].key.tri == d.k2)
               ? static_cast<uint32_t>(lo)
               : ~0u;
  };
  if (!points_.reserve(n0 + 2 * nd)) return arena_.exhausted_status();  // before the scope
  ArenaScope scope(arena_);
  // The ends that name new points, sorted (stable radix passes: k2, then k1, then kind).
  KeyIndex* keys = arena_.allocate_array<KeyIndex>(2 * nd);
  if (keys == nullptr) return arena_.exhausted_status();
  size_t m = 0;
  for (size_t r = 0; r < nd; ++r) {
    DegRecord& rec = deg_[r];
    for (int e = 0; e < 2; ++e) {
      const DegPoint& d = rec.p[e];
      if (d.kind == kDegVertex) {
        rec.id[e] = static_cast<uint32_t>(d.k1);
        continue;
      }
      if (d.kind == kDegEdgeFace) {
        const uint32_t f = find_ef(d);
        if (f != ~0u) {
          rec.id[e] = base + f;
          continue;
        }
      }
      rec.id[e] = ~0u;
      keys[m++] = KeyIndex{d.k2, static_cast<uint32_t>(2 * r + static_cast<size_t>(e)), 0};
    }
  }
  auto point_of = [&](uint32_t i) -> const DegPoint& { return deg_[i / 2].p[i % 2]; };
  SPLINTCORE_RETURN_IF_ERROR(sort_keys(arena_, keys, m));
  for (size_t i = 0; i < m; ++i) keys[i].key = point_of(keys[i].index).k1;
  SPLINTCORE_RETURN_IF_ERROR(sort_keys(arena_, keys, m));
  for (size_t i = 0; i < m; ++i) keys[i].key = point_of(keys[i].index).kind;
  SPLINTCORE_RETURN_IF_ERROR(sort_keys(arena_, keys, m));
  uint64_t limit = 0;
  if (!checked_add(uint64_t{base} + n0, m, &limit) || limit >= (uint64_t{1} << 31)) {
    return make_error(StatusCode::kLimitExceeded, "too many vertices for 32-bit ids: ", limit);
  }
  const DegPoint* prev = nullptr;
  for (size_t i = 0; i < m; ++i) {
    const DegPoint& d = point_of(keys[i].index);
    if (prev == nullptr || d.kind != prev->kind || d.k1 != prev->k1 || d.k2 != prev->k2) {
      Point pt;
      pt.s = 0;
      if (d.kind == kDegEdgeFace) {
        pt = make_point(in_, PointKey{d.k1, static_cast<uint32_t>(d.k2), 0});
      } else {
        const Vec3 ea[3] = {in_.vertex(key_hi(d.k1)), in_.vertex(key_lo(d.k1)), Vec3{}};
        const Vec3 eb[3] = {in_.vertex(key_hi(d.k2)), in_.vertex(key_lo(d.k2)), Vec3{}};
        pt.p = detail::contact_point_position(
            ea, eb, detail::ContactPoint{detail::Loc::kE0, detail::Loc::kE0});
        pt.key = PointKey{d.k1, ~0u, 0};
      }
      if (options_.float32_output && !round_to_float32(&pt.p)) {
        return make_error(StatusCode::kLimitExceeded, "intersection point beyond float32 range");
      }
      if (!points_.push_back(pt)) return arena_.exhausted_status();
    }
    deg_[keys[i].index / 2].id[keys[i].index % 2] =
        base + static_cast<uint32_t>(points_.size() - 1);
    prev = &d;
  }
  return Status::ok();
}

Status BooleanRun::number_points() {
  const size_t n = hits_.size() * 2;
  const Arena::Marker items_at = arena_.mark();
  KeyIndex* items = arena_.allocate_array<KeyIndex>(n);
  hit_points_ = arena_.allocate_array<uint32_t>(n);
  if ((items == nullptr || hit_points_ == nullptr) && n > 0) return arena_.exhausted_status();
  {
    ArenaScope scope(arena_);
    // Lexicographic (edge, triangle), ties in index order: stably by edge, then each run of
    // one edge (the few triangles its line crosses) stably by triangle, by insertion. The same
    // order as two stable passes (triangle, then edge), which remain for runs longer than 32.
    auto tri_of = [&](uint32_t i) {
      return (i & 1) == 0 ? hits_[i / 2].start.tri : hits_[i / 2].end.tri;
    };
    for (size_t i = 0; i < n; ++i) {
      const Hit& h = hits_[i / 2];
      items[i] = KeyIndex{(i & 1) == 0 ? h.start.edge : h.end.edge, static_cast<uint32_t>(i), 0};
    }
    SPLINTCORE_RETURN_IF_ERROR(radix_sort(arena_, Span<KeyIndex>(items, n)));
    bool long_run = false;
    for (size_t a = 0; a < n && !long_run;) {
      size_t b = a + 1;
      while (b < n && items[b].key == items[a].key) ++b;
      if (b - a > 32) long_run = true;
      for (size_t i = a + 1; i < b && !long_run; ++i) {
        const KeyIndex x = items[i];
        const uint32_t tx = tri_of(x.index);
        size_t j = i;
        for (; j > a && tri_of(items[j - 1].index) > tx; --j) items[j] = items[j - 1];
        items[j] = x;
      }
      a = b;
    }
    if (long_run) {
      for (size_t i = 0; i < n; ++i)
        items[i] = KeyIndex{tri_of(static_cast<uint32_t>(i)), static_cast<uint32_t>(i), 0};
      SPLINTCORE_RETURN_IF_ERROR(radix_sort(arena_, Span<KeyIndex>(items, n)));
      for (size_t i = 0; i < n; ++i) {
        const Hit& h = hits_[items[i].index / 2];
        items[i].key = (items[i].index & 1) == 0 ? h.start.edge : h.end.edge;
      }
      SPLINTCORE_RETURN_IF_ERROR(radix_sort(arena_, Span<KeyIndex>(items, n)));
    }
  }
  // Count distinct points, then make them (the point array is sized exactly).
  size_t distinct = 0;
  const PointKey* prev = nullptr;
  for (size_t i = 0; i < n; ++i) {
    const Hit& h = hits_[items[i].index / 2];
    const PointKey* k = (items[i].index & 1) == 0 ? &h.start : &h.end;
    if (prev == nullptr || k->edge != prev->edge || k->tri != prev->tri) ++distinct;
    prev = k;
  }
  uint64_t limit = 0;
  if (!checked_add(uint64_t{in_.nva} + in_.nvb, distinct, &limit) || limit >= (uint64_t{1} << 31)) {
    return make_error(StatusCode::kLimitExceeded, "too many vertices for 32-bit ids: ", limit);
  }
  points_.bind(&arena_);
  if (!points_.reserve(distinct)) return arena_.exhausted_status();
  prev = nullptr;
  for (size_t i = 0; i < n; ++i) {
    const Hit& h = hits_[items[i].index / 2];
    const PointKey* k = (items[i].index & 1) == 0 ? &h.start : &h.end;
    if (prev == nullptr || k->edge != prev->edge || k->tri != prev->tri) {
      // Rounded to float32 here, before any triangle is re-triangulated, when the result is
      // for STL: the triangulations are then valid for the coordinates the file will hold.
      Point pt = make_point(in_, *k);
      if (options_.float32_output && !round_to_float32(&pt.p)) {
        return make_error(StatusCode::kLimitExceeded, "intersection point beyond float32 range");
      }
      if (!points_.push_back(pt)) return arena_.exhausted_status();
    }
    hit_points_[items[i].index] = static_cast<uint32_t>(points_.size() - 1);
    prev = k;
  }
  points_over_items(items_at);
  return Status::ok();
}

// The sorted hit ends (`items`, 16 bytes each, below the hit points and the points) are done
// with once the points are numbered: the two move down over them, so the rest of the run does
// not carry them (1.75 MB in the real 4 mm-deep design's last Boolean). Only within one block
// of the arena (always so for an arena over one buffer), where the moves go down.
void BooleanRun::points_over_items(const Arena::Marker& items_at) {
  if (arena_.mark().block != items_at.block) return;
  const size_t n = hits_.size() * 2, np = points_.size();
  const uint32_t* old_ids = hit_points_;
  const Point* old_points = points_.data();
  arena_.rewind(items_at);
  hit_points_ = arena_.allocate_array<uint32_t>(n);
  SPLINTCORE_ASSERT((hit_points_ != nullptr && hit_points_ <= old_ids) || n == 0);
  if (n > 0) std::memmove(hit_points_, old_ids, n * sizeof(uint32_t));
  points_.bind(&arena_);
  Point* moved = arena_.allocate_array<Point>(np);
  SPLINTCORE_ASSERT((moved != nullptr && moved <= old_points) || np == 0);
  if (np > 0) std::memmove(static_cast<void*>(moved), old_points, np * sizeof(Point));
  points_.adopt(moved, np, np);
}

// Points p and q (keys kp, kq) coincide after rounding: kUnsupported (a near-degeneracy, not a
// bug: the next nudge runs, then the attempts that merge them), the points named by what
// defines them: an edge (two vertex ids) of one mesh through a triangle of the other, or
// through an edge of the other.
Status BooleanRun::coincide(const PointKey& kp, uint32_t p, const PointKey& kq, uint32_t q) const {
  const char* as = options_.float32_output ? " (as float32)" : "";
  auto named = [&](Status& st, const PointKey& k) {
    const uint32_t u = key_hi(k.edge), v = key_lo(k.edge);
    const bool of_a = u < in_.nva;
    st.append("edge ").append_u64(in_.named_vertex(u)).append("-");
    st.append_u64(in_.named_vertex(v)).append(of_a ? " of A" : " of B");
    if (k.tri == ~0u) {
      st.append(" across an edge of B");
    } else {
      const bool tri_a = k.tri < in_.nta;
      st.append(" through triangle ").append_u64(in_.named_triangle(k.tri));
      st.append(tri_a ? " of A" : " of B");
    }
  };
  Status e = make_error(StatusCode::kUnsupported, "intersection points ", p, " and ", q,
                        " coincide", as, ": ");
  named(e, kp);
  e.append(" and ");
  named(e, kq);
  return kq.tri == ~0u ? e : e.at_index(in_.named_triangle(kq.tri));
}

// Points p and q are defined by features with the same coordinates: edges of one mesh with the
// same two ends through triangles of the other with the same three corners (two copies of a
// triangle, or of an edge). They are the same exact point in every attempt, and both copies of
// the triangle (or of the triangles at the edge) cross the other mesh: whatever is kept of one
// is kept of the other, so every result has coincident faces. Edge-across-edge points are not
// judged here.
bool BooleanRun::same_features(const PointKey& kp, const PointKey& kq) const {
  if (kp.tri == ~0u || kq.tri == ~0u) return false;
  if ((kp.tri < in_.nta) != (kq.tri < in_.nta)) return false;
  const uint32_t pu = key_hi(kp.edge), pv = key_lo(kp.edge);
  const uint32_t qu = key_hi(kq.edge), qv = key_lo(kq.edge);
  if ((pu < in_.nva) != (qu < in_.nva)) return false;
  const Vec3 &p0 = in_.vertex(pu), &p1 = in_.vertex(pv);
  const Vec3 &q0 = in_.vertex(qu), &q1 = in_.vertex(qv);
  if (!((p0 == q0 && p1 == q1) || (p0 == q1 && p1 == q0))) return false;
  uint32_t cp[3], cq[3];
  in_.corners(kp.tri, cp);
  in_.corners(kq.tri, cq);
  // Each corner of one among the other's, both ways (a corner may repeat in a degenerate one).
  auto among = [&](const uint32_t* x, const uint32_t* y) {
    for (int i = 0; i < 3; ++i) {
      const Vec3& v = in_.vertex(x[i]);
      if (!(v == in_.vertex(y[0]) || v == in_.vertex(y[1]) || v == in_.vertex(y[2]))) return false;
    }
    return true;
  };
  return among(cp, cq) && among(cq, cp);
}

// The refusal for same_features: the input's fault, named by both copies (no nudge or merge
// can help, so the attempts stop).
Status BooleanRun::duplicated(const PointKey& kp, const PointKey& kq) const {
  const bool tri_of_a = kp.tri < in_.nta;
  Status e;
  if (kp.tri != kq.tri) {
    e = make_error(StatusCode::kInvalidArgument, "triangles ", in_.named_triangle(kp.tri), " and ",
                   in_.named_triangle(kq.tri), tri_of_a ? " of A" : " of B",
                   " have the same corners");
  } else {
    e = make_error(StatusCode::kInvalidArgument, "edges ", in_.named_vertex(key_hi(kp.edge)), "-",
                   in_.named_vertex(key_lo(kp.edge)), " and ", in_.named_vertex(key_hi(kq.edge)),
                   "-", in_.named_vertex(key_lo(kq.edge)), tri_of_a ? " of B" : " of A",
                   " have the same ends");
  }
  e.append(
      " and cross the other mesh at the same point: what is kept of one is kept of the other,"
      " so any result would have coincident faces; remove the duplicates");
  return e.at_index(in_.named_triangle(kp.tri));
}

// The points sorted by their coordinates (lexicographic x, y, z; -0 as +0), equal ones in id
// order: three stable radix passes.
Status BooleanRun::sort_points_by_position(KeyIndex* keys, uint32_t np) {
  for (int axis = 2; axis >= 0; --axis) {
    for (uint32_t i = 0; i < np; ++i) {
      const uint32_t id = axis == 2 ? i : keys[i].index;
      keys[i] = KeyIndex{order_key(points_[id].p[axis] + 0.0), id, 0};
    }
    SPLINTCORE_RETURN_IF_ERROR(radix_sort(arena_, Span<KeyIndex>(keys, np)));
  }
  return Status::ok();
}

// Points that round together (issue 29): distinct exact points closer than a rounding step
// (float32 for STL: 4-8 nm at 60 mm), e.g. several edges of B from a vertex just off a
// triangle of A crossing it nm apart, or crossings near the tip of a needle triangle. A nudge
// draws new ones, so they are merged rather than refused: each group of equal points is
// named by its lowest id (merge_), the coordinates being equal, the choice depends on nothing
// else. The splits then see the merged ids: a segment whose ends merged collapses, the corner
// a triangle's outline pinches off is dropped (CutSplit::merge_coincident). The result's
// checks stay the safety net: a merge that leaves it open or self-intersecting is
// kUnsupported, and the next nudge runs. No memory is kept when no two points coincide.
Status BooleanRun::check_points_apart() {
  st_.intersection_points = points_.size();
  const uint32_t np = static_cast<uint32_t>(points_.size());
  if (np < 2) return Status::ok();
  bool maybe = false;
  {
    ArenaScope scope(arena_);
    KeyIndex* keys = arena_.allocate_array<KeyIndex>(np);
    if (keys == nullptr) return arena_.exhausted_status();
    // First a cheaper look: sorted by x alone, equal points share a run of equal x; runs are
    // a handful of points. Only when it finds a pair (or a run too long to compare pairwise)
    // does the full lexicographic sort below run.
    for (uint32_t i = 0; i < np; ++i) keys[i] = KeyIndex{order_key(points_[i].p.x + 0.0), i, 0};
    SPLINTCORE_RETURN_IF_ERROR(radix_sort(arena_, Span<KeyIndex>(keys, np)));
    for (uint32_t i = 0; i < np && !maybe;) {
      uint32_t j = i + 1;
      while (j < np && keys[j].key == keys[i].key) ++j;
      if (j - i > 16) maybe = true;
      for (uint32_t x = i; x < j && !maybe; ++x) {
        for (uint32_t y = x + 1; y < j; ++y) {
          if (points_[keys[x].index].p == points_[keys[y].index].p) maybe = true;
        }
      }
      i = j;
    }
  }
  if (!maybe) return Status::ok();
  bool found = false;
  {
    ArenaScope scope(arena_);
    KeyIndex* keys = arena_.allocate_array<KeyIndex>(np);
    if (keys == nullptr) return arena_.exhausted_status();
    SPLINTCORE_RETURN_IF_ERROR(sort_points_by_position(keys, np));
    // Duplicated geometry first (every attempt would meet it, merging or not), else the first
    // pair that rounds together: its refusal is what the attempt would have ended with without
    // merging (unmerged_status), and the points are merged.
    uint32_t first_pair = 0;
    for (uint32_t i = 1; i < np; ++i) {
      const Point& p = points_[keys[i - 1].index];
      const Point& q = points_[keys[i].index];
      if (!(q.p == p.p)) continue;
      if (same_features(p.key, q.key)) return duplicated(p.key, q.key);
      if (first_pair == 0) first_pair = i;
    }
    if (first_pair != 0) {
      const Status refused =
          coincide(points_[keys[first_pair - 1].index].key, keys[first_pair - 1].index,
                   points_[keys[first_pair].index].key, keys[first_pair].index);
      if (unmerged_.is_ok()) unmerged_ = refused;
      found = true;
    }
  }
  if (!found) return Status::ok();
  // Kept for the split (below the sort's temporaries).
  merge_ = arena_.allocate_array<uint32_t>(np);
  if (merge_ == nullptr) return arena_.exhausted_status();
  for (uint32_t i = 0; i < np; ++i) merge_[i] = i;
  ArenaScope scope(arena_);
  KeyIndex* keys = arena_.allocate_array<KeyIndex>(np);
  if (keys == nullptr) return arena_.exhausted_status();
  SPLINTCORE_RETURN_IF_ERROR(sort_points_by_position(keys, np));
  uint32_t first = keys[0].index;  // the lowest id of its run (ties are in id order)
  for (uint32_t i = 1; i < np; ++i) {
    const uint32_t id = keys[i].index;
    if (points_[id].p == points_[first].p) {
      merge_[id] = first;
      ++st_.merged_points;
    } else {
      first = id;
    }
  }
  st_.intersection_points = np - st_.merged_points;  // distinct ones
  return Status::ok();
}

}  // namespace boolean_detail

}  // namespace splintcore
