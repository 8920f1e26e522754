// The Boolean run, classification: the pieces and uncut triangles not decided by their
// constraints take their side by flooding across shared edges, or by the winding number of the
// other solid (boolean_run.h).
#include "boolean/boolean_run.h"

namespace splintcore {
namespace boolean_detail {

Status BooleanRun::inconsistent_vertex(uint32_t v) const {
  const bool is_a = v < in_.nva;
  return make_error(StatusCode::kUnsupported,
                    "inconsistent inside/outside classification at vertex ", is_a ? v : v - in_.nva,
                    is_a ? " of A" : " of B",
                    " (overlapping shells in B, or a nearly degenerate contact)")
      .at_index(is_a ? v : v - in_.nva);
}

// Vertex states spread from the corners of cut triangles across the uncut triangles of one
// mesh (an uncut triangle does not cross the other surface, so its three corners agree);
// a part no cut triangle reaches gets one winding number.
Status BooleanRun::flood(bool side_a) {
  ArenaScope scope(arena_);
  const Mesh& mesh = side_a ? *in_.a : *in_.b;
  const uint32_t voff = side_a ? 0 : in_.nva;
  const uint32_t toff = side_a ? 0 : in_.nta;
  const uint32_t nv = side_a ? in_.nva : in_.nvb;
  const uint32_t nt = side_a ? in_.nta : in_.ntb;
  // Cut flags per triangle from the sorted groups.
  uint8_t* cut = arena_.allocate_array<uint8_t>(nt);
  uint32_t* start = arena_.allocate_array<uint32_t>(size_t{nv} + 1);
  if ((cut == nullptr && nt > 0) || start == nullptr) return arena_.exhausted_status();
  if (nt > 0) std::memset(cut, 0, nt);
  if (tflag_ != nullptr) {
    // Triangles with pending pieces (lone contact points only) pass states on like uncut ones.
    for (uint32_t t = 0; t < nt; ++t) cut[t] = tflag_[toff + t] == kDecided ? 1 : 0;
  } else {
    for (size_t i = 0; i < 2 * hits_.size(); ++i) {
      const uint32_t t = static_cast<uint32_t>(order_[i].key);
      if (t >= toff && t - toff < nt) cut[t - toff] = 1;
    }
  }
  // The triangles that take part: all of A's, B's near ones; the uncut ones are flooded.
  const uint32_t count = side_a ? nt : static_cast<uint32_t>(bp_.near_ids.size());
  auto id = [&](uint32_t i) { return side_a ? i : bp_.near_ids[i]; };
  // Vertex -> uncut triangles (compressed rows).
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
  uint32_t* fill = arena_.allocate_array<uint32_t>(nv);
  uint32_t* rows = arena_.allocate_array<uint32_t>(static_cast<size_t>(uses));
  uint32_t* queue = arena_.allocate_array<uint32_t>(nv);
  if (((fill == nullptr || queue == nullptr) && nv > 0) || (rows == nullptr && uses > 0)) {
    return arena_.exhausted_status();
  }
  if (nv > 0) std::memcpy(fill, start, size_t{nv} * sizeof(uint32_t));
  for (uint32_t i = 0; i < count; ++i) {
    const uint32_t t = id(i);
    if (cut[t] != 0) continue;
    for (uint32_t v : mesh.triangles[t].v) rows[fill[v]++] = t;
  }
  int8_t* vs = vstate_ + voff;
  uint32_t head = 0, tail = 0;
  for (uint32_t v = 0; v < nv; ++v) {
    if (vs[v] != 0 && vs[v] != kVertexOn && start[v + 1] > start[v]) queue[tail++] = v;
  }
  auto spread = [&]() -> Status {
    while (head < tail) {
      const uint32_t v = queue[head++];
      for (uint32_t r = start[v]; r < start[v + 1]; ++r) {
        for (uint32_t w : mesh.triangles[rows[r]].v) {
          const int8_t x = vs[w];
          if (x == 0) {
            vs[w] = vs[v];
            queue[tail++] = w;
          } else if (x != vs[v] && x != kVertexOn) {  // on the other surface: passes nothing on
            return inconsistent_vertex(voff + w);
          }
        }
      }
    }
    return Status::ok();
  };
  SPLINTCORE_RETURN_IF_ERROR(spread());
  // Parts without a cut: one winding number of the other mesh each.
  DistanceIndex index_b{};
  bool have_b = false;
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
    if (decided || (first_free < 0 && tstate_ != nullptr && tstate_[toff + t] != 0)) continue;
    const Vec3 centroid =
        (mesh.vertices[tri.v[0]] + mesh.vertices[tri.v[1]] + mesh.vertices[tri.v[2]]) * (1.0 / 3.0);
    double w = 0;
    if (side_a) {
      if (!have_b) {
        SPLINTCORE_RETURN_IF_ERROR(
            build_distance_index(ctx_, *in_.b, DistanceIndexOptions{}, &index_b));
        have_b = true;
      }
      w = winding_number(index_b, centroid);
    } else {
      if (!have_a_index_) {
        SPLINTCORE_RETURN_IF_ERROR(
            build_distance_index(ctx_, *in_.a, DistanceIndexOptions{}, &index_a_));
        have_a_index_ = true;
      }
      w = winding_number(index_a_, centroid);
    }
    ++st_.winding_queries;
    if (first_free < 0) {
      if (tstate_ == nullptr) {
        return make_error(StatusCode::kInternal, "boolean: triangle ", toff + t,
                          " has every corner on the other surface but no contact");
      }
      tstate_[toff + t] = w >= 0.5 ? kStateIn : kStateOut;
      continue;
    }
    vs[tri.v[first_free]] = w >= 0.5 ? 1 : -1;
    queue[tail++] = tri.v[first_free];
    SPLINTCORE_RETURN_IF_ERROR(spread());
  }
  return Status::ok();
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
  for (size_t i = 0; i < tris_.size(); ++i) {
    OutTri& o = tris_[i];
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
