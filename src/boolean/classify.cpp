// The Boolean run, classification: the pieces and uncut triangles not decided by their
// constraints take their side by flooding across shared edges, or by the winding number of the
// other solid (boolean_run.h).
#include "boolean/boolean_run.h"

namespace splintcore {
namespace boolean_detail {

Status BooleanRun::inconsistent_vertex(uint32_t v) const {
  const bool is_a = v < in_.nva;
  return make_error(StatusCode::kUnsupported,
                    "inconsistent inside/outside classification at vertex ", in_.named_vertex(v),
                    is_a ? " of A" : " of B",
                    " (overlapping shells in B, or a nearly degenerate contact)")
      .at_index(in_.named_vertex(v));
}

// One mesh's flood (flood()): its cut flags, its vertex -> uncut triangles rows (compressed),
// the queue of vertices whose state passes on; one method per stage.
struct BooleanRun::FloodSide {
  FloodSide(BooleanRun& r, bool a_side)
      : run(r),
        arena(r.arena_),
        side_a(a_side),
        mesh(a_side ? *r.in_.a : *r.in_.b),
        voff(a_side ? 0 : r.in_.nva),
        toff(a_side ? 0 : r.in_.nta),
        nv(a_side ? r.in_.nva : r.in_.nvb),
        nt(a_side ? r.in_.nta : r.in_.ntb),
        // The triangles that take part: all of A's, B's near ones; the uncut ones are flooded.
        count(a_side ? nt : static_cast<uint32_t>(r.bp_.near_ids.size())),
        vs(r.vstate_ + voff) {}

  uint32_t id(uint32_t i) const { return side_a ? i : run.bp_.near_ids[i]; }
  Status mark_cut();
  Status build_rows();
  void seed();
  Status spread();
  Status winding_number(const Vec3& q, double* w);
  bool on_near_border(uint32_t v) const;
  Status border_outside();
  Status parts_without_cut();

  BooleanRun& run;
  Arena& arena;
  const bool side_a;
  const Mesh& mesh;
  const uint32_t voff, toff, nv, nt, count;
  int8_t* const vs;  // the mesh's vertex states
  uint8_t* cut = nullptr;
  uint32_t* start = nullptr;  // vertex v's uncut triangles: rows[start[v] .. start[v + 1])
  uint32_t* rows = nullptr;
  uint32_t* queue = nullptr;
  uint32_t head = 0, tail = 0;
  // The other mesh's index (B's whole for A's side, A for B's), built at the first winding
  // number, in this flood's arena scope: it ends with the flood.
  DistanceIndex other{};
  bool have_other = false;
  uint32_t direct = 0;  // winding numbers summed without the index
};

// Cut flags per triangle from the sorted groups.
Status BooleanRun::FloodSide::mark_cut() {
  cut = arena.allocate_array<uint8_t>(nt);
  start = arena.allocate_array<uint32_t>(size_t{nv} + 1);
  if ((cut == nullptr && nt > 0) || start == nullptr) return arena.exhausted_status();
  if (nt > 0) std::memset(cut, 0, nt);
  if (run.tflag_ != nullptr) {
    // Triangles with pending pieces (lone contact points only) pass states on like uncut ones.
    for (uint32_t t = 0; t < nt; ++t) cut[t] = run.tflag_[toff + t] == kDecided ? 1 : 0;
  } else {
    for (size_t i = 0; i < 2 * run.hits_.size(); ++i) {
      const uint32_t t = static_cast<uint32_t>(run.order_[i].key);
      if (t >= toff && t - toff < nt) cut[t - toff] = 1;
    }
  }
  return Status::ok();
}

// Vertex -> uncut triangles (compressed rows), and the queue's memory.
Status BooleanRun::FloodSide::build_rows() {
  std::memset(start, 0, (size_t{nv} + 1) * sizeof(uint32_t));
  uint64_t uses = 0;
  for (uint32_t i = 0; i < count; ++i) {
    const uint32_t t = id(i);
    if (cut[t] != 0) continue;
    for (uint32_t v : mesh.triangles[t].v) ++start[v + 1];
    uses += 3;
  }
  for (uint32_t v = 0; v < nv; ++v) start[v + 1] += start[v];
  // start[] holds uint32 prefix sums of the uses, and rows is sized by them (size_t is 32 bits
  // on 32-bit targets): more than 2^32 - 1 uses must fail, not wrap.
  if (uses > UINT32_MAX) {
    return Status::error(StatusCode::kLimitExceeded,
                         "boolean: more than 4294967295 vertex uses in one mesh");
  }
  uint32_t* fill = arena.allocate_array<uint32_t>(nv);
  rows = arena.allocate_array<uint32_t>(static_cast<size_t>(uses));
  queue = arena.allocate_array<uint32_t>(nv);
  if (((fill == nullptr || queue == nullptr) && nv > 0) || (rows == nullptr && uses > 0)) {
    return arena.exhausted_status();
  }
  if (nv > 0) std::memcpy(fill, start, size_t{nv} * sizeof(uint32_t));
  for (uint32_t i = 0; i < count; ++i) {
    const uint32_t t = id(i);
    if (cut[t] != 0) continue;
    for (uint32_t v : mesh.triangles[t].v) rows[fill[v]++] = t;
  }
  return Status::ok();
}

// The queue starts with every vertex that has a state to pass on and an uncut triangle.
void BooleanRun::FloodSide::seed() {
  for (uint32_t v = 0; v < nv; ++v) {
    if (vs[v] != 0 && vs[v] != kVertexOn && start[v + 1] > start[v]) queue[tail++] = v;
  }
}

// Each queued vertex passes its state to the corners of its uncut triangles.
Status BooleanRun::FloodSide::spread() {
  // In locals: a state is a byte, which may alias anything, so members would be read again
  // after each one.
  int8_t* const state = vs;
  const uint32_t* const first = start;
  const uint32_t* const row = rows;
  uint32_t* const q = queue;
  const Triangle* const tris = mesh.triangles.data();
  uint32_t h = head, t = tail;
  while (h < t) {
    const uint32_t v = q[h++];
    for (uint32_t r = first[v]; r < first[v + 1]; ++r) {
      for (uint32_t w : tris[row[r]].v) {
        const int8_t x = state[w];
        if (x == 0) {
          state[w] = state[v];
          q[t++] = w;
        } else if (x != state[v] && x != kVertexOn) {  // on the other surface: passes nothing on
          return run.inconsistent_vertex(voff + w);
        }
      }
    }
  }
  head = h;
  tail = t;
  return Status::ok();
}

// The other mesh's winding number at q: the first kDirectWindings summed over its triangles
// (winding_number_direct: no memory; a side usually asks one or two), then from its index,
// built at the next query (only the tree and the dipoles, the same winding numbers as a full
// index for about half its peak memory: 11.5 MB for the real 4 mm design's swept surface).
Status BooleanRun::FloodSide::winding_number(const Vec3& q, double* w) {
  constexpr uint32_t kDirectWindings = 4;
  const Mesh& m = side_a ? *run.in_.b_whole : *run.in_.a;
  if (!have_other && direct < kDirectWindings) {
    ++direct;
    *w = winding_number_direct(m, q);
    ++run.st_.winding_queries;
    return Status::ok();
  }
  if (!have_other) {
    DistanceIndexOptions options;
    options.winding_only = true;
    SPLINTCORE_RETURN_IF_ERROR(build_distance_index(run.ctx_, m, options, &other));
    have_other = true;
  }
  *w = splintcore::winding_number(other, q);
  ++run.st_.winding_queries;
  return Status::ok();
}

// Whether an edge at vertex v is used by exactly one of B's near triangles (all uncut here:
// the caller passes only vertices of no cut triangle). At most kFan uses looked at (more, or a
// triangle with a repeated corner: false, and the winding number decides as before).
bool BooleanRun::FloodSide::on_near_border(uint32_t v) const {
  constexpr uint32_t kFan = 64;
  const uint32_t uses = start[v + 1] - start[v];
  if (uses == 0 || uses > kFan / 2) return false;
  uint32_t ends[kFan];
  uint32_t n = 0;
  for (uint32_t r = start[v]; r < start[v + 1]; ++r) {
    const Triangle& t = mesh.triangles[rows[r]];
    // A triangle with a repeated corner would count an edge once: no answer then.
    if (t.v[0] == t.v[1] || t.v[1] == t.v[2] || t.v[2] == t.v[0]) return false;
    for (uint32_t w : t.v) {
      if (w != v) ends[n++] = w;
    }
  }
  for (uint32_t i = 0; i < n; ++i) {
    uint32_t same = 0;
    for (uint32_t j = 0; j < n; ++j) same += ends[j] == ends[i] ? 1u : 0u;
    if (same == 1) return true;
  }
  return false;
}

// B's uncut parts that reach the border of its near triangles lie outside A, with no winding
// number: such a border edge is B's own border, which the caller vouches lies outside A
// (BooleanOptions::b_border_outside_a: beyond any nudge, and for the difference A only
// shrinks from pass to pass), or an edge of a triangle that is not near A's box widened by
// every nudge, so outside A too. Its undecided corners (of no cut triangle: their near
// triangles are all in the rows) are outside, and the flood carries that across their parts.
// The same states as the parts' winding numbers give (0 < 0.5), for far fewer queries: the
// blockout's swept surface leaves thousands of uncut islands near the splint, each reaching
// the filter's border.
Status BooleanRun::FloodSide::border_outside() {
  uint8_t* at_cut = arena.allocate_array<uint8_t>(nv);
  if (at_cut == nullptr && nv > 0) return arena.exhausted_status();
  if (nv > 0) std::memset(at_cut, 0, nv);
  for (uint32_t i = 0; i < count; ++i) {
    const uint32_t t = id(i);
    if (cut[t] == 0) continue;
    for (uint32_t v : mesh.triangles[t].v) at_cut[v] = 1;
  }
  for (uint32_t v = 0; v < nv; ++v) {
    if (vs[v] != 0 || at_cut[v] != 0 || !on_near_border(v)) continue;
    vs[v] = kStateOut;
    queue[tail++] = v;
    SPLINTCORE_RETURN_IF_ERROR(spread());
  }
  return Status::ok();
}

// Parts without a cut: one winding number of the other mesh each, at the centroid of their
// first undecided triangle, then flooded from there.
Status BooleanRun::FloodSide::parts_without_cut() {
  for (uint32_t i = 0; i < count; ++i) {
    const uint32_t t = id(i);
    if (cut[t] != 0) continue;
    const Triangle& tri = mesh.triangles[t];
    if (vs[tri.v[0]] == kStateIn || vs[tri.v[0]] == kStateOut) continue;
    // Decided when a corner has a state; a corner without one (not on the other surface)
    // takes the winding number; with every corner on the other surface the triangle does.
    int first_free = -1;
    bool decided = false;
    for (int k = 0; k < 3; ++k) {
      const int8_t x = vs[tri.v[k]];
      if (x == kStateIn || x == kStateOut) decided = true;
      if (x == 0 && first_free < 0) first_free = k;
    }
    if (decided || (first_free < 0 && run.tstate_ != nullptr && run.tstate_[toff + t] != 0)) {
      continue;
    }
    const Vec3 centroid =
        (mesh.vertices[tri.v[0]] + mesh.vertices[tri.v[1]] + mesh.vertices[tri.v[2]]) * (1.0 / 3.0);
    double w = 0;
    SPLINTCORE_RETURN_IF_ERROR(winding_number(centroid, &w));
    if (first_free < 0) {
      if (run.tstate_ == nullptr) {
        return make_error(StatusCode::kInternal, "boolean: triangle ", toff + t,
                          " has every corner on the other surface but no contact");
      }
      run.tstate_[toff + t] = w >= 0.5 ? kStateIn : kStateOut;
      continue;
    }
    vs[tri.v[first_free]] = w >= 0.5 ? 1 : -1;
    queue[tail++] = tri.v[first_free];
    SPLINTCORE_RETURN_IF_ERROR(spread());
  }
  return Status::ok();
}

// Vertex states spread from the corners of cut triangles across the uncut triangles of one
// mesh (an uncut triangle does not cross the other surface, so its three corners agree);
// a part no cut triangle reaches gets one winding number.
Status BooleanRun::flood(bool side_a) {
  ArenaScope scope(arena_);
  FloodSide f(*this, side_a);
  SPLINTCORE_RETURN_IF_ERROR(f.mark_cut());
  SPLINTCORE_RETURN_IF_ERROR(f.build_rows());
  f.seed();
  SPLINTCORE_RETURN_IF_ERROR(f.spread());
  if (!side_a && options_.b_border_outside_a && options_.op == BooleanOp::kDifference) {
    SPLINTCORE_RETURN_IF_ERROR(f.border_outside());
  }
  return f.parts_without_cut();
}

Status BooleanRun::classify() {
  SPLINTCORE_RETURN_IF_ERROR(flood(true));
  SPLINTCORE_RETURN_IF_ERROR(flood(false));
  return resolve_pending();
}

// The state of a triangle without constraints from its corners (those not on the other
// surface, which agree), or from its winding number when every corner is on it. kStateNone
// when neither is known.
static int8_t corner_agreement(const int8_t* vstate, const int8_t* tstate, const uint32_t c[3],
                               uint32_t t, bool* conflict) {
  int8_t s = kStateNone;
  *conflict = false;
  for (int k = 0; k < 3; ++k) {
    const int8_t x = vstate[c[k]];
    if (x != kStateIn && x != kStateOut) continue;
    if (s != kStateNone && s != x) *conflict = true;
    s = x;
  }
  if (s == kStateNone && tstate != nullptr) s = tstate[t];
  return s;
}

// The state of an uncut triangle whose corners do not simply agree (some on the other
// surface): from the others, or its winding number; kStateNone when unknown (a bug).
int8_t BooleanRun::uncut_state(uint32_t t, const uint32_t c[3]) const {
  if (tstate_ == nullptr) return kStateNone;
  bool conflict = false;
  const int8_t s = corner_agreement(vstate_, tstate_, c, t, &conflict);
  if (conflict || vstate_[c[0]] == 0 || vstate_[c[1]] == 0 || vstate_[c[2]] == 0) return kStateNone;
  return s;
}

// Pieces of triangles with lone contact points only: the triangle's state, after flooding.
Status BooleanRun::resolve_pending() {
  if (!pending_) return Status::ok();
  const uint32_t base = in_.nva + in_.nvb;
  for (size_t i = 0; i < tris_.size(); ++i) {
    OutTri& o = tris_[i];
    if (o.state == kStateFromCorners) {
      // Beside a segment that collapsed when its ends merged: the piece's own corners among
      // the triangle's (those off the other surface agree); its triangle's corners when it
      // has none (check_points_apart).
      uint32_t c[3];
      int nc = 0;
      for (const uint32_t v : o.v) {
        if (v < base) c[nc++] = v;
      }
      if (nc == 0) {
        in_.corners(o.src, c);
        nc = 3;
      }
      int8_t s = kStateNone;
      for (int k = 0; k < nc; ++k) {
        const int8_t x = vstate_[c[k]];
        if (x != kStateIn && x != kStateOut) continue;
        if (s != kStateNone && s != x) return inconsistent_vertex(c[k]);
        s = x;
      }
      if (s == kStateNone) {
        return make_error(StatusCode::kUnsupported, "a piece of triangle ",
                          in_.named_triangle(o.src), o.src < in_.nta ? " of A" : " of B",
                          " beside intersection points that round together is not classified")
            .at_index(in_.named_triangle(o.src));
      }
      o.state = s;
      continue;
    }
    if (o.state != kStateNone) continue;
    uint32_t c[3];
    in_.corners(o.src, c);
    bool conflict = false;
    o.state = corner_agreement(vstate_, tstate_, c, o.src, &conflict);
    if (conflict) return inconsistent_vertex(c[0]);
    if (o.state == kStateNone) {
      return make_error(StatusCode::kInternal, "boolean: triangle ", o.src,
                        " was left unclassified");
    }
  }
  return Status::ok();
}

}  // namespace boolean_detail

}  // namespace splintcore
