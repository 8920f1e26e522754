// The Boolean run, assembly: the pieces an operation keeps, welded into the result, the
// result's checks (closed, oriented, float32, no self-intersection), and mesh_boolean_single,
// one whole run with its nudges (boolean_run.h, boolean_internal.h).
#include "boolean/boolean_run.h"

namespace splintcore {
namespace boolean_detail {

Status BooleanRun::assemble(Mesh* result) {
  // Which pieces stay: (inside the other?) per side and operation.
  const bool reverse_b = op_ == BooleanOp::kDifference;
  // keep(state, is_a) as a table: [is_a][state + 2].
  bool keeps[2][5];
  for (int side = 0; side < 2; ++side) {
    for (int st = -2; st <= 2; ++st) keeps[side][st + 2] = keep(static_cast<int8_t>(st), side == 1);
  }
  const uint32_t base = in_.nva + in_.nvb;
  const uint32_t nv_all = base + static_cast<uint32_t>(points_.size());
  uint32_t* remap = arena_.allocate_array<uint32_t>(nv_all);
  if (remap == nullptr && nv_all > 0) return arena_.exhausted_status();
  if (nv_all > 0) std::memset(remap, 0xff, size_t{nv_all} * sizeof(uint32_t));
  // Visits the result's triangles in order (A's, then B's near ones, each in input order, a
  // cut triangle replaced by its pieces; for the union B's far ones last): emit(v0, v1, v2)
  // for each kept one.
  auto visit = [&](auto&& emit) -> Status {
    size_t piece = 0;
    const uint32_t count = in_.nta + static_cast<uint32_t>(bp_.near_ids.size());
    for (uint32_t i = 0; i < count; ++i) {
      const bool is_a = i < in_.nta;
      const uint32_t t = is_a ? i : in_.nta + bp_.near_ids[i - in_.nta];
      const bool reverse = !is_a && reverse_b;
      const bool* keep_row = keeps[is_a ? 1 : 0];
      if (piece < tris_.size() && tris_[piece].src == t) {
        for (; piece < tris_.size() && tris_[piece].src == t; ++piece) {
          const OutTri& o = tris_[piece];
          if (!keep_row[o.state + 2]) continue;
          if (reverse)
            emit(o.v[0], o.v[2], o.v[1], is_a);
          else
            emit(o.v[0], o.v[1], o.v[2], is_a);
        }
        continue;
      }
      uint32_t c[3];
      in_.corners(t, c);
      int8_t s = vstate_[c[0]];
      if (s == 0 || s == kVertexOn || vstate_[c[1]] != s || vstate_[c[2]] != s) {
        s = uncut_state(t, c);  // corners on the other surface (degenerate contacts)
        if (s == kStateNone) {
          return make_error(StatusCode::kInternal, "boolean: triangle ", t,
                            " was left unclassified");
        }
      }
      if (!keep_row[s + 2]) continue;
      if (reverse)
        emit(c[0], c[2], c[1], is_a);
      else
        emit(c[0], c[1], c[2], is_a);
    }
    if (op_ == BooleanOp::kUnion) {
      for (uint32_t t = 0; t < in_.ntb; ++t) {
        if (bp_.near_b[t] != 0) continue;
        const Triangle& bt = in_.b->triangles[t];
        emit(in_.nva + bt.v[0], in_.nva + bt.v[1], in_.nva + bt.v[2], false);
      }
    }
    return Status::ok();
  };
  // The result's vertices are numbered in the order of their first use.
  uint64_t kept = 0;
  uint64_t kept_a = 0;
  uint32_t nv = 0;
  SPLINTCORE_RETURN_IF_ERROR(visit([&](uint32_t v0, uint32_t v1, uint32_t v2, bool is_a) {
    ++kept;
    kept_a += is_a ? 1 : 0;
    const uint32_t v[3] = {canon(v0), canon(v1), canon(v2)};
    for (const uint32_t x : v) {
      if (remap[x] == ~0u) remap[x] = nv++;
    }
  }));
  Triangle* out_t = arena_.allocate_array<Triangle>(static_cast<size_t>(kept));
  if (out_t == nullptr && kept > 0) return arena_.exhausted_status();
  size_t k = 0;
  SPLINTCORE_RETURN_IF_ERROR(visit([&](uint32_t v0, uint32_t v1, uint32_t v2, bool) {
    out_t[k++] = Triangle{{remap[canon(v0)], remap[canon(v1)], remap[canon(v2)]}};
  }));
  move_over_pieces(nv_all, static_cast<size_t>(kept), &remap, &out_t);
  if (merge_ != nullptr) {
    SPLINTCORE_RETURN_IF_ERROR(check_merged_fans(out_t, static_cast<size_t>(kept), remap, nv));
  }
  Vec3* out_v = arena_.allocate_array<Vec3>(nv);
  if (out_v == nullptr && nv > 0) return arena_.exhausted_status();
  for (uint32_t v = 0; v < nv_all; ++v) {
    if (remap[v] == ~0u) continue;
    out_v[remap[v]] = v < base ? in_.vertex(v) : points_[v - base].p;
  }
  result->triangles.adopt(out_t, static_cast<size_t>(kept), static_cast<size_t>(kept));
  result->vertices.adopt(out_v, nv, nv);
  st_.output_triangles = kept;
  st_.output_triangles_a = kept_a;
  return Status::ok();
}

// The pieces are done with: the remap (nv_all) and the result's triangles (kept) move down over
// them, and the vertices take the room the pieces had (the peak is the larger of the two
// stages, not their sum: 5.4 MB less in the real 4 mm-deep design's last Boolean). Nothing
// moves when something was taken above the pieces in another block.
void BooleanRun::move_over_pieces(uint32_t nv_all, size_t kept, uint32_t** remap,
                                  Triangle** out_t) {
  if (arena_.mark().block != pieces_at_.block) return;
  const uint32_t* old_remap = *remap;
  const Triangle* old_t = *out_t;
  arena_.rewind(pieces_at_);
  tris_.bind(&arena_);
  *remap = arena_.allocate_array<uint32_t>(nv_all);
  SPLINTCORE_ASSERT((*remap != nullptr && *remap <= old_remap) || nv_all == 0);
  if (nv_all > 0) std::memmove(*remap, old_remap, size_t{nv_all} * sizeof(uint32_t));
  *out_t = arena_.allocate_array<Triangle>(kept);
  SPLINTCORE_ASSERT((*out_t != nullptr && *out_t <= old_t) || kept == 0);
  if (kept > 0) std::memmove(static_cast<void*>(*out_t), old_t, kept * sizeof(Triangle));
}

// Merged points (check_points_apart, split_with_merges) stand for several: the result must
// still pass once around each of them (one fan of triangles), or the merge pinched it there
// (a hole in a face smaller than the rounding step closed to a point): kUnsupported, and the
// nudge runs. The fans of the other vertices are as the exact arrangement made them. Arena: a
// byte per result vertex and 16 bytes per corner at a merged point, returned.
Status BooleanRun::check_merged_fans(const Triangle* tris, size_t nt, const uint32_t* remap,
                                     uint32_t nv) {
  ArenaScope scope(arena_);
  const uint32_t base = in_.nva + in_.nvb;
  const uint32_t np = static_cast<uint32_t>(points_.size());
  uint8_t* merged = arena_.allocate_array<uint8_t>(nv);
  if (merged == nullptr && nv > 0) return arena_.exhausted_status();
  if (nv > 0) std::memset(merged, 0, nv);
  for (uint32_t i = 0; i < np; ++i) {
    const uint32_t o = merge_[i] != i ? remap[base + merge_[i]] : ~0u;
    if (o != ~0u) merged[o] = 1;
  }
  size_t count = 0;
  for (size_t t = 0; t < nt; ++t) {
    for (const uint32_t v : tris[t].v) count += merged[v];
  }
  if (count == 0) return Status::ok();
  struct Wedge {
    uint32_t from, to;  // the triangle's other corners, counter-clockwise
  };
  KeyIndex* at = arena_.allocate_array<KeyIndex>(count);
  Wedge* wedge = arena_.allocate_array<Wedge>(count);
  if (at == nullptr || wedge == nullptr) return arena_.exhausted_status();
  size_t n = 0;
  for (size_t t = 0; t < nt; ++t) {
    for (int k = 0; k < 3; ++k) {
      if (merged[tris[t].v[k]] == 0) continue;
      wedge[n] = Wedge{tris[t].v[(k + 1) % 3], tris[t].v[(k + 2) % 3]};
      at[n] = KeyIndex{tris[t].v[k], static_cast<uint32_t>(n), 0};
      ++n;
    }
  }
  SPLINTCORE_RETURN_IF_ERROR(sort_keys(arena_, at, n));
  for (size_t a = 0; a < n;) {
    size_t b = a + 1;
    while (b < n && at[b].key == at[a].key) ++b;
    // Around the vertex from the first wedge: (v, x, y) is followed by (v, y, z).
    const uint32_t start = wedge[at[a].index].from;
    uint32_t cur = wedge[at[a].index].to;
    size_t steps = 1;
    while (cur != start && steps <= b - a) {
      size_t next = b;
      for (size_t x = a; x < b && next == b; ++x) {
        if (wedge[at[x].index].from == cur) next = x;
      }
      if (next == b) break;  // open there: the result's edge check names it
      cur = wedge[at[next].index].to;
      ++steps;
    }
    if (cur == start && steps < b - a) {
      return make_error(StatusCode::kUnsupported, "Boolean ", boolean_op_name(op_),
                        " result is pinched at a point where intersection points that round "
                        "together were merged (a hole smaller than the rounding step)");
    }
    a = b;
  }
  return Status::ok();
}

Status BooleanRun::run(Mesh* result, const Arena::Marker& result_at) {
  if (!in_.a_solid) {
    Status s = check_closed_oriented(ctx_, *in_.a, nullptr);
    if (s.code() == StatusCode::kArenaExhausted) return s;
    if (!s.is_ok()) {
      // A nudged A (in a later pass: the previous result, moved and rounded to float32) can
      // lose a sliver to rounding: that attempt is unsupported and the next nudge runs.
      if (st_.attempts > 1) {
        return make_error(StatusCode::kUnsupported,
                          "A moved by the nudge is not a solid: ", s.message())
            .at_index(s.index());
      }
      return make_error(StatusCode::kInvalidMesh, "A must be a solid: ", s.message())
          .at_index(s.index());
    }
  }
  SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx_, "boolean: hits", 0, in_.ntb));
  SPLINTCORE_RETURN_IF_ERROR(find_hits());
  SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx_, "boolean: points", 0, 1));
  SPLINTCORE_RETURN_IF_ERROR(number_points());
  SPLINTCORE_RETURN_IF_ERROR(number_degenerate_points());
  SPLINTCORE_RETURN_IF_ERROR(check_points_apart());
  SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx_, "boolean: split", 0, 1));
  SPLINTCORE_RETURN_IF_ERROR(split_with_merges());
  SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx_, "boolean: classify", 0, 1));
  SPLINTCORE_RETURN_IF_ERROR(classify());
  SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx_, "boolean: assemble", 0, 1));
  SPLINTCORE_RETURN_IF_ERROR(assemble(result));
  // The result down over the run's temporaries (none is needed any more), so the checks'
  // memory comes on top of the result alone.
  Mesh low;
  move_mesh_down(arena_, result_at, *result, &low);
  *result = low;
  SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx_, "boolean: check", 0, 1));
  SPLINTCORE_RETURN_IF_ERROR(check_result(result));
  return report_progress(ctx_, "boolean: done", 1, 1);
}

// The same answer as the edge part of check_closed_oriented (every edge used by exactly two
// triangles, in opposite directions; no triangle repeating a vertex), faster: half-edges
// bucketed by their smaller vertex (other end << 1 | forward), and in each bucket the uses of
// each other end counted in a per-vertex tally (forward uses in the low 32 bits, backward in
// the high: exactly one of each is 2^32 + 1), read and cleared again. *paired is false when it
// does not hold or a vertex id is out of range: the caller then runs check_closed_oriented,
// which names the first offending edge as it always did. Arena: 12 nv + 12 nt bytes or so,
// returned before it returns.
Status edges_paired(Arena& arena, const Mesh& mesh, bool* paired) {
  *paired = false;
  const uint64_t nv64 = mesh.vertices.size(), nt64 = mesh.triangles.size();
  if (nv64 >= (uint64_t{1} << 31) || nt64 >= (uint64_t{1} << 31)) return Status::ok();
  const uint32_t nv = static_cast<uint32_t>(nv64), nt = static_cast<uint32_t>(nt64);
  const Triangle* tris = mesh.triangles.data();
  uint32_t largest = 0;
  for (uint32_t t = 0; t < nt; ++t) {
    const uint32_t a = tris[t].v[0], b = tris[t].v[1], c = tris[t].v[2];
    const uint32_t m = a > b ? a : b;
    largest = m > largest ? m : largest;
    largest = c > largest ? c : largest;
  }
  if (nt > 0 && largest >= nv) return Status::ok();
  ArenaScope scope(arena);
  uint32_t* start = arena.allocate_array<uint32_t>(size_t{nv} + 1);
  uint32_t* half = arena.allocate_array<uint32_t>(size_t{3} * nt);
  uint64_t* tally = arena.allocate_array<uint64_t>(nv);
  if (start == nullptr || (half == nullptr && nt > 0) || (tally == nullptr && nv > 0)) {
    return arena.exhausted_status();
  }
  std::memset(start, 0, (size_t{nv} + 1) * sizeof(uint32_t));
  if (nv > 0) std::memset(tally, 0, size_t{nv} * sizeof(uint64_t));
  for (uint32_t t = 0; t < nt; ++t) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = tris[t].v[k], b = tris[t].v[k == 2 ? 0 : k + 1];
      ++start[(a < b ? a : b) + 1];
    }
  }
  for (uint32_t i = 0; i < nv; ++i) start[i + 1] += start[i];
  for (uint32_t t = 0; t < nt; ++t) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = tris[t].v[k], b = tris[t].v[k == 2 ? 0 : k + 1];
      const uint32_t lo = a < b ? a : b, hi = a < b ? b : a;
      half[start[lo]++] = (hi << 1) | (a < b ? 1u : 0u);
    }
  }
  // start[lo] now ends bucket lo (and begins bucket lo + 1).
  constexpr uint64_t kOneEach = (uint64_t{1} << 32) | 1u;
  uint32_t begin = 0;
  for (uint32_t lo = 0; lo < nv; ++lo) {
    const uint32_t end = start[lo];
    for (uint32_t i = begin; i < end; ++i) {
      tally[half[i] >> 1] += (half[i] & 1u) != 0 ? 1u : (uint64_t{1} << 32);
    }
    // The first use of each other end reads its total (then clears it); later ones read 0.
    for (uint32_t i = begin; i < end; ++i) {
      const uint32_t hi = half[i] >> 1;
      const uint64_t count = tally[hi];
      if ((count != kOneEach && count != 0) || hi == lo) return Status::ok();
      tally[hi] = 0;
    }
    begin = end;
  }
  *paired = true;
  return Status::ok();
}

// Whether every edge of the result is used by exactly two triangles in opposite directions and
// no triangle repeats a vertex (edges_paired's answer; false also when it could not tell),
// through check_mesh when the caller asked for the result's report (options_.result_report):
// then a degenerate triangle, which edges_paired does not look for, also answers false, which
// sends the caller to check_closed_oriented as a flat triangle does (the same decisions).
Status BooleanRun::pair_result_edges(const Mesh& result, bool* paired) {
  *paired = false;
  st_.result_report_made = false;
  if (options_.result_report != nullptr) {
    MeshReport& r = *options_.result_report;
    const Status e = check_mesh(ctx_, result, &r);
    if (e.is_ok()) {
      st_.result_report_made = true;
      *paired = r.boundary_edges == 0 && r.nonmanifold_edges == 0 && r.orientation_conflicts == 0 &&
                r.degenerate_triangles == 0;
      return Status::ok();
    }
    if (e.code() != StatusCode::kArenaExhausted) return e;
    arena_.forget_failure();  // the edge pass below needs less
  }
  const Status e = edges_paired(arena_, result, paired);
  if (!e.is_ok()) {
    if (e.code() != StatusCode::kArenaExhausted) return e;
    arena_.forget_failure();  // check_closed_oriented's own request is the one to report
    *paired = false;
  }
  return Status::ok();
}

// The result as the file will hold it: no two intersection points rounded together, every
// edge used exactly twice in opposite directions (closed, edge-manifold, oriented), no flat
// triangle (exact), positive volume; then, when asked, no self-intersection. Linear except for
// the sort of the intersection points.
Status BooleanRun::check_result(Mesh* result) {
  if (result->triangles.empty()) return Status::ok();
  ArenaScope scope(arena_);
  const char* as = options_.float32_output ? " (as float32)" : "";
  // With exact contacts resolved, the result may not be a solid (parts that touch along an
  // edge, points that coincide after rounding): unsupported, so that the nudge takes over.
  // Merged points (check_points_apart) are a near-degeneracy too: what they break is fragile.
  const bool merged = merge_ != nullptr;
  const StatusCode fragile = (options_.float32_output || st_.degenerate_pairs > 0 || merged)
                                 ? StatusCode::kUnsupported
                                 : StatusCode::kInternal;
  // A flat triangle can come from rounding (then A is nudged); anything else would be a bug
  // (or, for the union, an open B). check_closed_oriented scans for flat triangles itself, so
  // the scan here runs only when it fails: the same answer as scanning first, one scan less.
  // First the checks of check_closed_oriented with its edge part done by edges_paired (the
  // same answer, faster); only when one fails (or edges_paired runs out of arena) does
  // check_closed_oriented itself run, so every error, and the order of the checks, is as before.
  bool paired = false;
  SPLINTCORE_RETURN_IF_ERROR(pair_result_edges(*result, &paired));
  // With the caller's report made, paired says too that no triangle is flat (its degenerate
  // triangles are find_flat_triangle's, exactly: collinear3d) and the report's volume is
  // mesh_volume's, the same arithmetic in the same order: neither scan is needed again.
  const MeshReport* report = st_.result_report_made ? options_.result_report : nullptr;
  const bool solid = report != nullptr ? paired && report->volume > 0
                                       : paired && find_flat_triangle(*result) == kNoTriangle &&
                                             mesh_volume(*result) > 0;
  Status s;
  if (!solid) {
    double volume = 0;
    s = check_closed_oriented(ctx_, *result, &volume);
  }
  if (!s.is_ok()) {
    const uint32_t flat = find_flat_triangle(*result);
    if (flat != kNoTriangle) {
      return make_error(fragile, "Boolean ", boolean_op_name(op_), " result has a flat triangle ",
                        flat, as)
          .at_index(flat);
    }
  }
  if (s.code() == StatusCode::kArenaExhausted) return s;
  if (!s.is_ok()) {
    // An open B whose border meets A (or lies inside it, perhaps after a nudge) leaves the
    // result open: that is the input's fault (B's border must lie outside A), said as such.
    if (op_ != BooleanOp::kUnion) {
      bool b_paired = false;
      const Status e = edges_paired(arena_, *in_.b_whole, &b_paired);
      if (e.code() == StatusCode::kArenaExhausted) return e;
      if (e.is_ok() && !b_paired) {
        return make_error(StatusCode::kInvalidMesh, "Boolean ", boolean_op_name(op_), " result", as,
                          ": ", s.message(),
                          " (B is open or not edge-manifold: its border must lie outside A)")
            .at_index(s.index());
      }
    }
    const StatusCode code =
        (st_.degenerate_pairs > 0 || merged)
            ? StatusCode::kUnsupported
            : (op_ == BooleanOp::kUnion ? StatusCode::kInvalidMesh : StatusCode::kInternal);
    return make_error(code, "Boolean ", boolean_op_name(op_), " result", as,
                      st_.degenerate_pairs > 0 ? " with exact contacts"
                                               : (merged ? " with merged points" : ""),
                      ": ", s.message())
        .at_index(s.index());
  }
  if (options_.check_self_intersection) {
    SelfIntersectionReport si;
    SPLINTCORE_RETURN_IF_ERROR(find_self_intersections(ctx_, *result, 1, &si));
    st_.self_intersection_candidates = si.candidate_pairs;
    if (si.self_intersecting()) {
      return make_error(fragile, "Boolean ", boolean_op_name(op_), " result self-intersects", as,
                        ": triangles ", si.first_a, " and ", si.first_b)
          .at_index(si.first_a);
    }
    st_.self_intersection_checked = true;
  }
  return Status::ok();
}

}  // namespace boolean_detail

namespace {

// The bounded working set: B's triangles near A, with their vertices, as a mesh of their own.
struct NearB {
  Mesh mesh;
  uint32_t* vertex_ids = nullptr;    // vertex i of mesh is B's vertex_ids[i]
  uint32_t* triangle_ids = nullptr;  // triangle i of mesh is B's triangle_ids[i]
};

// For the difference and the intersection a triangle of B far from A (bp->near_b 0) can
// neither meet A nor be kept, so the run needs only the near ones: copied with the vertices
// they use, both renumbered in B's order (so every order and tie the run takes from ids is
// B's own, and the result's bytes are the same), the broad phase renumbered with them. The
// run's per-vertex and per-triangle arrays are then sized by the near part, not by B (the
// real dentition: 108k of 887k triangles near a splint base). B itself still answers the
// winding numbers of A's parts without a cut (Inputs::b_whole). Arena: 4 bytes per vertex of
// B, then 28 per near vertex and 17 per near triangle.
Status copy_near_b(Arena& arena, const Mesh& b, boolean_detail::Broadphase* bp, NearB* out) {
  const uint32_t nvb = static_cast<uint32_t>(b.vertices.size());
  const uint32_t n = static_cast<uint32_t>(bp->near_ids.size());
  uint32_t* local = arena.allocate_array<uint32_t>(nvb);
  if (local == nullptr && nvb > 0) return arena.exhausted_status();
  if (nvb > 0) std::memset(local, 0xff, size_t{nvb} * sizeof(uint32_t));
  const Triangle* tb = b.triangles.data();
  const uint32_t* ids = bp->near_ids.data();
  for (uint32_t i = 0; i < n; ++i) {
    for (const uint32_t v : tb[ids[i]].v) local[v] = 0;
  }
  uint32_t nv = 0;
  for (uint32_t v = 0; v < nvb; ++v) {
    if (local[v] != ~0u) local[v] = nv++;
  }
  out->vertex_ids = arena.allocate_array<uint32_t>(nv);
  Vec3* verts = arena.allocate_array<Vec3>(nv);
  Triangle* tris = arena.allocate_array<Triangle>(n);
  uint8_t* near = arena.allocate_array<uint8_t>(n);
  ArenaArray<uint32_t> identity(&arena);
  if (((out->vertex_ids == nullptr || verts == nullptr) && nv > 0) ||
      ((tris == nullptr || near == nullptr) && n > 0) || !identity.resize(n)) {
    return arena.exhausted_status();
  }
  for (uint32_t v = 0; v < nvb; ++v) {
    if (local[v] == ~0u) continue;
    out->vertex_ids[local[v]] = v;
    verts[local[v]] = b.vertices[v];
  }
  for (uint32_t i = 0; i < n; ++i) {
    const Triangle& t = tb[ids[i]];
    tris[i] = Triangle{{local[t.v[0]], local[t.v[1]], local[t.v[2]]}};
    near[i] = 1;
    identity[i] = i;
  }
  out->mesh.vertices.adopt(verts, nv, nv);
  out->mesh.triangles.adopt(tris, n, n);
  out->triangle_ids = bp->near_ids.data();
  bp->near_b = near;
  bp->near_ids = identity;
  return Status::ok();
}

// Is A, moved by d and rounded to float32, A itself, bit for bit (d zero, A's coordinates
// float32 values, none of them -0.0, which adding +0.0 makes +0.0)?
bool moves_to_itself(const Mesh& a, const Vec3& d) {
  if (d.x != 0 || d.y != 0 || d.z != 0) return false;
  const auto same_bits = [](double x, double y) {
    uint64_t bx, by;
    std::memcpy(&bx, &x, sizeof bx);
    std::memcpy(&by, &y, sizeof by);
    return bx == by;
  };
  for (const Vec3& v : a.vertices) {
    Vec3 p = v + d;
    if (!round_to_float32(&p) || !same_bits(p.x, v.x) || !same_bits(p.y, v.y) ||
        !same_bits(p.z, v.z)) {
      return false;
    }
  }
  return true;
}

// What a run takes: A (as moved), the part of B it runs on and B whole, with the ids of
// that part in B.
boolean_detail::Inputs boolean_inputs(const Mesh& a, bool a_solid, const Mesh& run_b, const Mesh& b,
                                      const NearB& near) {
  boolean_detail::Inputs in;
  in.a = &a;
  in.a_solid = a_solid;
  in.b = &run_b;
  in.b_whole = &b;
  in.b_vertex_ids = near.vertex_ids;
  in.b_triangle_ids = near.triangle_ids;
  in.nva = static_cast<uint32_t>(a.vertices.size());
  in.nvb = static_cast<uint32_t>(run_b.vertices.size());
  in.nta = static_cast<uint32_t>(a.triangles.size());
  in.ntb = static_cast<uint32_t>(run_b.triangles.size());
  return in;
}

// A moved by d (rounded to float32 for STL output): new vertices in the arena, A's triangles.
Status moved_a(Arena& arena, const Mesh& a, const Vec3& d, bool float32, Mesh* moved) {
  Vec3* v = arena.allocate_array<Vec3>(a.vertices.empty() ? 1 : a.vertices.size());
  if (v == nullptr) return arena.exhausted_status();
  bool in_range = true;
  for (size_t i = 0; i < a.vertices.size(); ++i) {
    Vec3 p = a.vertices[i] + d;
    if (float32) in_range = round_to_float32(&p) && in_range;
    v[i] = p;
  }
  if (!in_range) {
    return Status::error(StatusCode::kLimitExceeded, "A has a coordinate beyond float32 range");
  }
  *moved = mesh_view(Span<const Vec3>(v, a.vertices.size()), a.triangles.span());
  return Status::ok();
}

}  // namespace

Status mesh_boolean_single(const Context& ctx, const Mesh& a, const Mesh& b,
                           const BooleanOptions& options, Mesh* out, BooleanStats* stats,
                           bool b_valid, bool a_solid) {
  using namespace boolean_detail;
  Arena& arena = *ctx.arena;
  BooleanStats local{};
  if (stats == nullptr) stats = &local;
  *stats = BooleanStats{};
  SPLINTCORE_RETURN_IF_ERROR(check_boolean_arguments(a, b, *out));
  // Attempt k > 0 runs with A translated by k * step * (1, 3, 7) (nudge_step: float32
  // vertices of A stay float32). B is never moved.
  const double step = nudge_step(a);
  ArenaScope scope(arena);  // on an error the arena is as it was
  // What a nudge can move A by, with its float32 rounding: the broad phase covers all attempts.
  const double reach = (options.max_nudges + 1.0) * step * 8.0;
  Broadphase bp;
  Status s = report_progress(ctx, "boolean: grid", 0, 1);
  if (s.is_ok()) s = build_broadphase(ctx, a, b, reach, options.float32_output, b_valid, &bp);
  NearB near;
  // The copy pays when most of B is far (its 17 bytes a near triangle and 28 a near vertex
  // against the run's arrays over all of B): not when more than half of B is near (the real
  // dentition's second pass: 161,098 of 161,219 triangles, 5.3 MB of copy for nothing).
  const bool bounded =
      options.op != BooleanOp::kUnion && bp.near_ids.size() <= b.triangles.size() / 2;
  if (s.is_ok() && bounded) s = copy_near_b(arena, b, &bp, &near);
  const Mesh& run_b = bounded ? near.mesh : b;
  if (s.is_ok()) s = number_a_slots(arena, static_cast<uint32_t>(a.triangles.size()), &bp);
  if (!s.is_ok()) return s;
  const Arena::Marker attempts_start = arena.mark();
  const uint64_t budget =
      options.max_candidate_pairs != 0
          ? options.max_candidate_pairs
          : 64 * (uint64_t{a.triangles.size()} + b.triangles.size()) + (uint64_t{1} << 22);
  uint64_t used = 0;
  Status first;  // the first attempt's failure, when a nudge then runs out of the budget
  Mesh result;
  // Every attempt merges the intersection points that round together (check_points_apart) and
  // those a triangulation fails on (split_with_merges); A is nudged only when an attempt fails
  // all the same. Where an attempt meets no such points, merging changes nothing: its result is
  // the one without, byte for byte. A failed attempt is judged by the status it would have had
  // without merging (unmerged_status: the refusal of those points), so the nudges, the errors
  // and their messages are those of attempts without merging; only a result can come sooner
  // (issue 32: the real plan's intermediate splint in 1 attempt, not 3).
  for (uint32_t attempt = 0; attempt <= options.max_nudges; ++attempt) {
    *stats = BooleanStats{};
    arena.rewind(attempts_start);
    Mesh moved;
    const Mesh* pa = &a;
    // For STL output A is used as it will be written: rounded to float32 (a no-op for A read
    // from STL, which is then used as it is), after the nudge (a nudge can carry a coordinate
    // into a coarser binade). The moved A shares A's triangles: only its vertices are new.
    const Vec3 d{attempt * step, 3.0 * attempt * step, 7.0 * attempt * step};
    if (attempt > 0 || (options.float32_output && !moves_to_itself(a, d))) {
      s = moved_a(arena, a, d, options.float32_output, &moved);
      if (!s.is_ok()) break;
      pa = &moved;
      stats->nudge = d;
      stats->nudge_sum = d;
    }
    stats->attempts = attempt + 1;
    const Inputs in = boolean_inputs(*pa, a_solid && pa == &a, run_b, b, near);
    result = Mesh();
    BooleanRun run(ctx, in, bp, options, stats);
    run.set_pair_budget(budget - used);
    s = run.run(&result, attempts_start);
    // Running out of memory or being cancelled is final, whatever the attempt without merging
    // would have met: with more memory this attempt's result is the one returned, so a nudge
    // here would make the bytes depend on the memory cap.
    if (!s.is_ok() && s.code() != StatusCode::kCancelled &&
        s.code() != StatusCode::kArenaExhausted && !run.unmerged_status().is_ok()) {
      s = run.unmerged_status();
    }
    used += stats->candidate_pairs;
    if (attempt == 0) first = s;
    if (s.code() == StatusCode::kLimitExceeded && attempt > 0 && used > budget) {
      s = first;
      s.append(" (nudges stopped after ").append_u64(attempt);
      s.append(": more than ").append_u64(budget);
      s.append(" candidate pairs of triangles in all, BooleanOptions::max_candidate_pairs)");
      return s;
    }
    if (s.code() != StatusCode::kUnsupported) break;
  }
  if (!s.is_ok()) {
    if (s.code() == StatusCode::kUnsupported && options.max_nudges > 0) {
      s.append(" (also with A moved by up to ");
      s.append_u64(options.max_nudges);
      s.append(" nudges)");
    }
    return s;
  }
  // The result down over the temporaries (its triangles were allocated before its vertices).
  move_mesh_down(arena, scope.start(), result, out);
  scope.commit();
  return Status::ok();
}

}  // namespace splintcore
