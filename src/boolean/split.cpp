// The Boolean run, splitting: each cut triangle re-triangulated on its plane along its
// segments (constrained Delaunay, cdt.cpp), and the state of each piece where its constraints
// decide it (boolean_run.h).
#include "boolean/boolean_run.h"

namespace splintcore {
namespace boolean_detail {

// Where the half-plane of triangle t beyond a contact line, on the side of t's corner r (off
// the line), lies against the other solid: inside, outside, or on its surface (then whether
// the faces point the same way). `sheets`: the other mesh's triangles that hold the line (one:
// the line crosses its interior; two: the line lies along their shared edge, a wedge, convex
// or reflex). Decided by orient3d on input vertices only. kStateNone when the configuration is
// not one of these (the caller reports it).
int8_t BooleanRun::side_state(uint32_t t, uint32_t r, const uint32_t* sheets, int nsheets) const {
  const Vec3 p = in_.vertex(r);
  uint32_t s1[3];
  in_.corners(sheets[0], s1);
  const Vec3 a0 = in_.vertex(s1[0]), a1 = in_.vertex(s1[1]), a2 = in_.vertex(s1[2]);
  const int o1 = sign_of(orient3d(a0, a1, a2, p));  // +1: below s1's plane (the inside side)
  if (nsheets == 1) return o1 > 0 ? kStateIn : (o1 < 0 ? kStateOut : on_state(t, sheets[0]));
  if (nsheets != 2) return kStateNone;
  uint32_t s2[3];
  in_.corners(sheets[1], s2);
  // The apexes: the corner of each sheet that the other does not share (exactly one each).
  int apex1 = -1, apex2 = -1, shared = 0;
  for (int i = 0; i < 3; ++i) {
    const bool in2 = s1[i] == s2[0] || s1[i] == s2[1] || s1[i] == s2[2];
    const bool in1 = s2[i] == s1[0] || s2[i] == s1[1] || s2[i] == s1[2];
    if (!in2) apex1 = i;
    if (!in1) apex2 = i;
    shared += in2 ? 1 : 0;
  }
  if (shared != 2 || apex1 < 0 || apex2 < 0) return kStateNone;
  const Vec3 b0 = in_.vertex(s2[0]), b1 = in_.vertex(s2[1]), b2 = in_.vertex(s2[2]);
  const Vec3 c1 = in_.vertex(s1[apex1]), c2 = in_.vertex(s2[apex2]);
  const int convex = sign_of(orient3d(a0, a1, a2, c2));  // +1 convex edge, -1 reflex, 0 flat
  const int o2 = sign_of(orient3d(b0, b1, b2, p));
  if (convex == 0) return o1 > 0 ? kStateIn : (o1 < 0 ? kStateOut : on_state(t, sheets[0]));
  if (o1 == 0) {  // in s1's plane: on s1 itself, or on its continuation beyond the edge
    if (o2 == sign_of(orient3d(b0, b1, b2, c1))) return on_state(t, sheets[0]);
    return convex > 0 ? kStateOut : kStateIn;
  }
  if (o2 == 0) {
    if (o1 == convex) return on_state(t, sheets[1]);
    return convex > 0 ? kStateOut : kStateIn;
  }
  if (convex > 0) return (o1 > 0 && o2 > 0) ? kStateIn : kStateOut;
  return (o1 > 0 || o2 > 0) ? kStateIn : kStateOut;
}

// Triangle t and `sheet` lie in one plane: do they face the same way? (orient2d of both on a
// projection that keeps t proper, so it keeps the sheet proper too.)
int8_t BooleanRun::on_state(uint32_t t, uint32_t sheet) const {
  uint32_t g[3], h[3];
  in_.corners(t, g);
  in_.corners(sheet, h);
  const Vec3 p0 = in_.vertex(g[0]), p1 = in_.vertex(g[1]), p2 = in_.vertex(g[2]);
  const int w = projection_axis(p0, p1, p2);
  if (w < 0) return kStateNone;
  const int u = (w + 1) % 3, v = (w + 2) % 3;
  const Vec3 q0 = in_.vertex(h[0]), q1 = in_.vertex(h[1]), q2 = in_.vertex(h[2]);
  const int st = sign_of(orient2d(p0[u], p0[v], p1[u], p1[v], p2[u], p2[v]));
  const int ss = sign_of(orient2d(q0[u], q0[v], q1[u], q1[v], q2[u], q2[v]));
  if (st == 0 || ss == 0) return kStateNone;
  return st == ss ? kOnSame : kOnOpposite;
}

bool BooleanRun::keep(int8_t state, bool is_a) const {
  switch (state) {
    case kStateIn: return is_a ? op_ == BooleanOp::kIntersection : op_ != BooleanOp::kUnion;
    case kStateOut: return is_a ? op_ != BooleanOp::kIntersection : op_ == BooleanOp::kUnion;
    case kOnSame: return is_a && op_ != BooleanOp::kDifference;
    case kOnOpposite: return is_a && op_ == BooleanOp::kDifference;
    default: return false;
  }
}

namespace {

// Each set of pieces joined across unconstrained edges (uf) takes the vote of its members,
// kept at its root in `state` (kStateNone: no member voted); false when two members disagree.
bool joined_states(UnionFind& uf, const int8_t* vote, uint32_t k, int8_t* state) {
  for (uint32_t j = 0; j < k; ++j) state[j] = kStateNone;
  for (uint32_t j = 0; j < k; ++j) {
    if (vote[j] == kStateNone) continue;
    const uint32_t r = uf.find(j);
    if (state[r] == kStateNone) {
      state[r] = vote[j];
    } else if (state[r] != vote[j]) {
      return false;
    }
  }
  return true;
}

// Gives input vertex v (a corner of a cut triangle) state sj; false when it has the other one
// (all pieces at a corner agree: no segment passes through an input vertex).
inline bool set_corner_state(int8_t* vstate, uint32_t v, int8_t sj) {
  const int8_t vs = vstate[v];
  if (vs == kVertexOn) return true;  // on the other surface: no state to pass on
  if (vs != 0 && vs != sj) return false;
  vstate[v] = sj;
  return true;
}

// The corners c of the cut triangle (at local indices corner_at) that `piece` has take its
// state sj; returns the first corner that has the other state (~0u: none).
inline uint32_t pass_state_to_corners(int8_t* vstate, const detail::CdtTriangle& piece,
                                      const uint32_t corner_at[3], const uint32_t c[3], int8_t sj) {
  for (uint32_t e = 0; e < 3; ++e) {
    for (uint32_t x = 0; x < 3; ++x) {
      if (piece.v[x] == corner_at[e] && !set_corner_state(vstate, c[e], sj)) return c[e];
    }
  }
  return ~0u;
}

}  // namespace

// ---- A cut triangle with degenerate contacts ------------------------------------------------

// A cut triangle with degenerate contacts (besides any crossing segments): its points may be
// input vertices of the other mesh, on its edges or inside; its constraints may lie along its
// own edges; each side of a constraint has its own state (side_state), inside, outside or on
// the other surface. A triangle with lone points only is split as well, its pieces pending
// (their state comes from its corners after flooding). The stages, in order:
//   1. the points: id, where (edge 0..2, 3 inside), position along the edge; distinct by id;
//   2. the boundary order (order_points) and the projection;
//   3. the constraints with the states of their two sides;
//   4. the constrained Delaunay triangulation;
//   5. the pieces' states: votes from constraint edges, pieces joined across the others.
struct BooleanRun::ContactSplit {
  struct GPoint {
    uint32_t id, where;
    double along;
  };
  struct Cons {
    uint32_t from, to;
    int8_t left, right;
  };

  ContactSplit(BooleanRun& r, uint32_t tri, const KeyIndex* proper_records, size_t proper_count,
               const KeyIndex* contact_records, size_t contact_count)
      : run(r),
        arena(r.arena_),
        t(tri),
        proper(proper_records),
        np(proper_count),
        dk(contact_records),
        nd(contact_count),
        base(r.in_.nva + r.in_.nvb),
        is_a(tri < r.in_.nta),
        tn(r.in_.named_triangle(tri)),
        which(is_a ? " of A" : " of B"),
        out(&r.arena_) {
    r.in_.corners(t, raw);
    for (int k = 0; k < 3; ++k) c[k] = r.canon(raw[k]);
    for (int k = 0; k < 3; ++k) cv[k] = r.in_.vertex(raw[k]);
  }

  Status unsupported(const char* what) const {
    return make_error(StatusCode::kUnsupported, "cannot split triangle ", tn, which,
                      " along its exact contacts: ", what)
        .at_index(tn);
  }
  double along_edge(int k, const Vec3& p) const;
  void add_point(uint32_t id, int where);
  Status gather_points();
  Status distinct_points();
  Status order_and_project();
  uint32_t local(uint32_t id) const;
  Status add_constraints();
  Status contact_line(const KeyIndex* line, size_t count, Cons* cn) const;
  Status sides_across(const DegRecord& trans, const uint32_t sheets[2], int nsheets,
                      Cons* cn) const;
  Status triangulate();
  Status vote_pieces();
  Status emit_pieces();

  BooleanRun& run;
  Arena& arena;
  const uint32_t t;
  const KeyIndex* proper;  // its crossing records
  const size_t np;
  const KeyIndex* dk;  // its degenerate records
  const size_t nd;
  const uint32_t base;
  const bool is_a;
  const uint32_t tn;  // t's index in its own mesh
  const char* which;
  uint32_t raw[3], c[3];  // its corners, and as canon() names them
  Vec3 cv[3];
  // 1.
  GPoint* gp = nullptr;
  KeyIndex* ids = nullptr;
  size_t n = 0;
  GPoint* up = nullptr;  // distinct, by id
  size_t nu = 0;
  // 2.
  detail::CdtPoint* pts = nullptr;
  uint32_t* vid = nullptr;
  uint32_t* local_of = nullptr;  // by index in `up`
  uint32_t m = 0, boundary = 0;
  uint32_t corner_at[3] = {};
  // 3.
  Cons* cons = nullptr;
  KeyIndex* ckey = nullptr;
  uint32_t nc = 0;
  // 4.
  detail::CdtSegment* segs = nullptr;
  ArenaArray<detail::CdtTriangle> out;
  // 5.
  int8_t* vote = nullptr;
  UnionFind uf;
};

Status BooleanRun::split_general(uint32_t t, const KeyIndex* proper, size_t np, const KeyIndex* dk,
                                 size_t nd) {
  ArenaScope scope(arena_);
  ContactSplit s(*this, t, proper, np, dk, nd);
  SPLINTCORE_RETURN_IF_ERROR(s.gather_points());
  SPLINTCORE_RETURN_IF_ERROR(s.distinct_points());
  SPLINTCORE_RETURN_IF_ERROR(s.order_and_project());
  SPLINTCORE_RETURN_IF_ERROR(s.add_constraints());
  SPLINTCORE_RETURN_IF_ERROR(s.triangulate());
  SPLINTCORE_RETURN_IF_ERROR(s.vote_pieces());
  return s.emit_pieces();
}

double BooleanRun::ContactSplit::along_edge(int k, const Vec3& p) const {
  const Vec3 d = cv[(k + 1) % 3] - cv[k];
  const double ax = d.x < 0 ? -d.x : d.x, ay = d.y < 0 ? -d.y : d.y, az = d.z < 0 ? -d.z : d.z;
  const int w = (ax >= ay && ax >= az) ? 0 : (ay >= az ? 1 : 2);
  return d[w] > 0 ? p[w] - cv[k][w] : cv[k][w] - p[w];
}

void BooleanRun::ContactSplit::add_point(uint32_t id, int where) {
  gp[n] = GPoint{id, static_cast<uint32_t>(where),
                 where < 3 ? along_edge(where, run.position(id)) : 0.0};
  ids[n] = KeyIndex{id, static_cast<uint32_t>(n), 0};
  ++n;
}

// 1. The points: the ends of the crossing segments and of the contacts (but t's corners).
Status BooleanRun::ContactSplit::gather_points() {
  using detail::Loc;
  const size_t cap = 2 * np + 2 * nd;
  gp = arena.allocate_array<GPoint>(cap);
  ids = arena.allocate_array<KeyIndex>(cap);
  if (gp == nullptr || ids == nullptr) return arena.exhausted_status();
  for (size_t i = 0; i < np; ++i) {
    const Record& rc = run.rec_[proper[i].index];
    for (int end = 0; end < 2; ++end) {
      const uint32_t pid = end == 0 ? rc.from : rc.to;
      const Point& pt = run.points_[pid];
      int where = 3;
      if (pt.key.tri != t) {
        where = -1;
        for (int e = 0; e < 3; ++e) {
          if (edge_key(raw[e], raw[(e + 1) % 3]) == pt.key.edge) where = e;
        }
        if (where < 0)
          return make_error(StatusCode::kInternal, "boolean: intersection point ", pid,
                            " is not on triangle ", t);
      }
      add_point(run.rep_id(base + pid), where);
    }
  }
  for (size_t i = 0; i < nd; ++i) {
    const DegRecord& r = run.deg_[dk[i].index];
    const int ends = r.kind == kDegPointOnly ? 1 : 2;
    for (int e = 0; e < ends; ++e) {
      const Loc l = static_cast<Loc>(r.loc_t[e]);
      if (detail::loc_is_vertex(l)) continue;
      add_point(run.rep_id(run.canon(r.id[e])), detail::loc_is_edge(l) ? detail::loc_index(l) : 3);
    }
  }
  return Status::ok();
}

// Distinct points, by id (the same id is the same point: it must lie in the same place).
Status BooleanRun::ContactSplit::distinct_points() {
  SPLINTCORE_RETURN_IF_ERROR(sort_keys(arena, ids, n));
  up = arena.allocate_array<GPoint>(n + 1);
  if (up == nullptr) return arena.exhausted_status();
  nu = 0;
  for (size_t i = 0; i < n; ++i) {
    const GPoint& q = gp[ids[i].index];
    if (q.id == c[0] || q.id == c[1] || q.id == c[2])
      return unsupported("a contact point named inside is one of its corners");
    if (nu > 0 && up[nu - 1].id == q.id) {
      if (up[nu - 1].where != q.where)
        return unsupported("a point found on two different places of it");
      continue;
    }
    up[nu++] = q;
  }
  return Status::ok();
}

// 2. Boundary order: c0, edge 0's points, c1, edge 1's, c2, edge 2's; then the inside ones.
Status BooleanRun::ContactSplit::order_and_project() {
  KeyIndex* by = arena.allocate_array<KeyIndex>(nu);
  pts = arena.allocate_array<detail::CdtPoint>(nu + 3);
  vid = arena.allocate_array<uint32_t>(nu + 3);
  local_of = arena.allocate_array<uint32_t>(nu);
  if (by == nullptr || pts == nullptr || vid == nullptr || local_of == nullptr)
    return arena.exhausted_status();
  SPLINTCORE_RETURN_IF_ERROR(order_points(
      arena, nu, c, [&](size_t x) { return up[x].where; }, [&](size_t x) { return up[x].along; },
      [&](size_t x) { return up[x].id; }, by, vid, local_of, corner_at, &m, &boundary));
  const Projection pr = projection_of(cv[0], cv[1], cv[2]);
  for (uint32_t j = 0; j < m; ++j) pts[j] = to_2d(run.position(vid[j]), pr);
  return Status::ok();
}

// Local index of a vertex id: a corner, or a point (binary search in `up`); ~0u when neither.
inline uint32_t BooleanRun::ContactSplit::local(uint32_t id) const {
  for (int k = 0; k < 3; ++k) {
    if (id == c[k]) return corner_at[k];
  }
  size_t lo = 0, hi = nu;
  while (lo < hi) {
    const size_t mid = (lo + hi) / 2;
    if (up[mid].id < id)
      lo = mid + 1;
    else
      hi = mid;
  }
  return (lo < nu && up[lo].id == id) ? local_of[lo] : ~0u;
}

// 3. Constraints with the states of their two sides: crossing segments (inside on the
// left), then the degenerate segments grouped by their two ends (the records of one line
// from its sheets, the other mesh's triangles that hold it).
Status BooleanRun::ContactSplit::add_constraints() {
  cons = arena.allocate_array<Cons>(np + nd);
  ckey = arena.allocate_array<KeyIndex>(np + nd);
  KeyIndex* dseg = arena.allocate_array<KeyIndex>(nd + 1);
  if (cons == nullptr || ckey == nullptr || dseg == nullptr) return arena.exhausted_status();
  for (size_t x = 0; x < np; ++x) {
    const Record& rc = run.rec_[proper[x].index];
    const uint32_t from = local(run.rep_id(base + rc.from)), to = local(run.rep_id(base + rc.to));
    if (from == ~0u || to == ~0u)
      return make_error(StatusCode::kInternal, "boolean: a segment end is not a point of triangle ",
                        t);
    if (from == to) return unsupported("a crossing segment whose ends round together");
    cons[nc++] = Cons{from, to, kStateIn, kStateOut};
  }
  size_t ns = 0;
  for (size_t x = 0; x < nd; ++x) {
    const DegRecord& r = run.deg_[dk[x].index];
    if (r.kind == kDegPointOnly) continue;
    const uint32_t a = local(run.rep_id(run.canon(r.id[0])));
    const uint32_t b = local(run.rep_id(run.canon(r.id[1])));
    if (a == ~0u || b == ~0u)
      return make_error(StatusCode::kInternal, "boolean: a contact end is not a point of triangle ",
                        t);
    if (a == b) return unsupported("a contact segment with both ends at one point");
    dseg[ns++] = KeyIndex{edge_key(a, b), static_cast<uint32_t>(x), 0};
  }
  SPLINTCORE_RETURN_IF_ERROR(sort_keys(arena, dseg, ns));
  for (size_t g = 0; g < ns;) {
    size_t g_end = g + 1;
    while (g_end < ns && dseg[g_end].key == dseg[g].key) ++g_end;
    SPLINTCORE_RETURN_IF_ERROR(contact_line(dseg + g, g_end - g, &cons[nc++]));
    g = g_end;
  }
  return Status::ok();
}

// One contact line: `line`, its records (the same two ends, from each of its sheets).
Status BooleanRun::ContactSplit::contact_line(const KeyIndex* line, size_t count, Cons* cn) const {
  using detail::Loc;
  SPLINTCORE_ASSERT(count > 0);
  uint32_t sheets[2];
  int nsheets = 0;
  const DegRecord* trans = nullptr;
  for (size_t x = 0; x < count; ++x) {
    const DegRecord& r = run.deg_[dk[line[x].index].index];
    bool seen = false;
    for (int y = 0; y < nsheets; ++y) seen = seen || sheets[y] == r.other;
    if (!seen) {
      if (nsheets == 2)
        return unsupported("a contact line held by more than two triangles of the other mesh");
      sheets[nsheets++] = r.other;
    }
    if (r.kind == kDegTransversal && trans == nullptr) trans = &r;
  }
  const DegRecord& first = run.deg_[dk[line[0].index].index];
  const Loc l0 = static_cast<Loc>(first.loc_t[0]), l1 = static_cast<Loc>(first.loc_t[1]);
  int on_edge = -1;
  for (int k = 0; k < 3; ++k) {
    if (detail::loc_on_closed_edge(l0, k) && detail::loc_on_closed_edge(l1, k)) on_edge = k;
  }
  *cn = Cons{key_hi(line[0].key), key_lo(line[0].key), kStateNone, kStateNone};
  if (on_edge >= 0) {
    // Along t's own edge: one side only, the one with t's third corner.
    const int8_t s = run.side_state(t, raw[(on_edge + 2) % 3], sheets, nsheets);
    cn->left = cn->right = s;
  } else if (trans != nullptr) {
    SPLINTCORE_RETURN_IF_ERROR(sides_across(*trans, sheets, nsheets, cn));
  } else {
    // Coplanar only, across t: two coplanar sheets (t lies on both sides).
    if (nsheets != 2)
      return unsupported(
          "a coplanar contact side inside it with one triangle of the other mesh (an open "
          "border?)");
    cn->left = run.on_state(t, sheets[0]);
    cn->right = run.on_state(t, sheets[1]);
  }
  if (cn->left == kStateNone || cn->right == kStateNone)
    return unsupported("a contact line whose sides could not be classified");
  return Status::ok();
}

// A contact line across t with a transversal record `trans`: t's corners on each side, from
// the transversal sheet's plane (the segment runs along n_a x n_b: A's left is below B's
// plane, B's left above A's).
Status BooleanRun::ContactSplit::sides_across(const DegRecord& trans, const uint32_t sheets[2],
                                              int nsheets, Cons* cn) const {
  uint32_t o[3];
  run.in_.corners(trans.other, o);
  const Vec3 q0 = run.in_.vertex(o[0]), q1 = run.in_.vertex(o[1]), q2 = run.in_.vertex(o[2]);
  const int left_sign = is_a ? 1 : -1;
  uint32_t lc = ~0u, rc = ~0u;
  for (int k = 0; k < 3; ++k) {
    const int sd = sign_of(orient3d(q0, q1, q2, cv[k]));
    if (sd == left_sign && lc == ~0u) lc = raw[k];
    if (sd == -left_sign && rc == ~0u) rc = raw[k];
  }
  if (lc == ~0u || rc == ~0u)
    return unsupported("a contact segment across it without corners on both sides");
  cn->from = local(run.rep_id(run.canon(trans.id[0])));
  cn->to = local(run.rep_id(run.canon(trans.id[1])));
  cn->left = run.side_state(t, lc, sheets, nsheets);
  cn->right = run.side_state(t, rc, sheets, nsheets);
  return Status::ok();
}

// 4. Triangulate: the boundary, then the constraints (repeats of boundary edges allowed).
Status BooleanRun::ContactSplit::triangulate() {
  segs = arena.allocate_array<detail::CdtSegment>(boundary + nc);
  if (segs == nullptr) return arena.exhausted_status();
  uint32_t nseg = 0;
  for (uint32_t j = 0; j < boundary; ++j) segs[nseg++] = detail::CdtSegment{j, (j + 1) % boundary};
  for (uint32_t x = 0; x < nc; ++x) {
    segs[nseg++] = detail::CdtSegment{cons[x].from, cons[x].to};
    ckey[x] = KeyIndex{edge_key(cons[x].from, cons[x].to), x, 0};
  }
  SPLINTCORE_RETURN_IF_ERROR(sort_keys(arena, ckey, nc));
  for (uint32_t x = 1; x < nc; ++x) {
    if (ckey[x].key == ckey[x - 1].key)
      return unsupported("a contact segment repeats a crossing segment");
  }
  Status s = detail::cdt(arena, Span<const detail::CdtPoint>(pts, m),
                         Span<const detail::CdtSegment>(segs, nseg), boundary, &out, nullptr);
  if (!s.is_ok()) {
    if (s.code() == StatusCode::kArenaExhausted) return s;
    run.note_coincident(pts, vid, m);
    return make_error(StatusCode::kUnsupported, "cannot re-triangulate triangle ", tn, which,
                      " along its exact contacts: ", s.message())
        .at_index(tn);
  }
  return Status::ok();
}

// 5. Votes from constraint edges (a piece is left of its own counter-clockwise edges), pieces
// joined across other inside edges.
Status BooleanRun::ContactSplit::vote_pieces() {
  const uint32_t k = static_cast<uint32_t>(out.size());
  vote = arena.allocate_array<int8_t>(k);
  KeyIndex* half = arena.allocate_array<KeyIndex>(size_t{3} * k);
  if (vote == nullptr || half == nullptr || !uf.init(arena, k)) return arena.exhausted_status();
  for (uint32_t j = 0; j < k; ++j) {
    vote[j] = kStateNone;
    for (uint32_t e = 0; e < 3; ++e) {
      half[3 * j + e] = KeyIndex{edge_key(out[j].v[e], out[j].v[(e + 1) % 3]), 3 * j + e, 0};
    }
  }
  SPLINTCORE_RETURN_IF_ERROR(sort_keys(arena, half, size_t{3} * k));
  size_t ci = 0;
  for (size_t a = 0; a < size_t{3} * k;) {
    size_t b = a + 1;
    while (b < size_t{3} * k && half[b].key == half[a].key) ++b;
    while (ci < nc && ckey[ci].key < half[a].key) ++ci;
    if (ci < nc && ckey[ci].key == half[a].key) {
      const Cons& cn = cons[ckey[ci].index];
      for (size_t x = a; x < b; ++x) {
        const uint32_t j = half[x].index / 3, e = half[x].index % 3;
        const int8_t v = out[j].v[e] == cn.from ? cn.left : cn.right;
        if (vote[j] != kStateNone && vote[j] != v)
          return unsupported("a piece between two contacts that disagree");
        vote[j] = v;
      }
    } else if (b - a == 2) {
      uf.unite(half[a].index / 3, half[a + 1].index / 3);
    }
    a = b;
  }
  return Status::ok();
}

// The pieces with their states, and the states of t's corners from the decided ones.
Status BooleanRun::ContactSplit::emit_pieces() {
  const uint32_t k = static_cast<uint32_t>(out.size());
  int8_t* state = arena.allocate_array<int8_t>(k);
  if (state == nullptr) return arena.exhausted_status();
  if (!joined_states(uf, vote, k, state))
    return unsupported("inconsistent classification of its pieces");
  run.tflag_[t] = nc > 0 ? kDecided : kPending;
  if (nc == 0) run.pending_ = true;
  for (uint32_t j = 0; j < k; ++j) {
    const int8_t sj = state[uf.find(j)];
    if (sj == kStateNone && nc > 0) {
      return make_error(StatusCode::kInternal, "boolean: a piece of triangle ", t,
                        " is not next to any contact");
    }
    const detail::CdtTriangle& ct = out[j];
    if (!run.tris_.push_back(OutTri{{vid[ct.v[0]], vid[ct.v[1]], vid[ct.v[2]]}, t, sj})) {
      return arena.exhausted_status();
    }
    if (sj != kStateIn && sj != kStateOut) continue;
    const uint32_t bad = pass_state_to_corners(run.vstate_, ct, corner_at, c, sj);
    if (bad != ~0u) return run.inconsistent_vertex(bad);
  }
  return Status::ok();
}

// ---- A cut triangle with crossing segments only ---------------------------------------------

// One cut triangle with crossing segments only, re-triangulated along them (split_cut): its
// distinct points, their boundary order and projection, the constraints, the constrained
// Delaunay triangulation, the pieces' votes and states.
struct BooleanRun::CutSplit {
  // A distinct point: on an edge (0..2, with the position along it) or inside (3).
  struct Local {
    uint32_t point;
    uint32_t where;
    double along;
  };

  CutSplit(BooleanRun& r, uint32_t tri, const uint32_t corners[3], const KeyIndex* records,
           size_t count)
      : run(r),
        arena(r.arena_),
        t(tri),
        c{corners[0], corners[1], corners[2]},
        recs(records),
        nseg(count),
        base(r.in_.nva + r.in_.nvb),
        locals(&r.arena_),
        cdt_out(&r.arena_),
        adjacency(&r.arena_) {}

  Status gather_points();
  Status order_and_project();
  Status merge_coincident();
  Status unsupported_merge(const char* what);
  uint32_t local(uint32_t pid) const;
  Status add_constraints();
  Status triangulate();
  Status vote_pieces();
  void vote_by_adjacency();
  Status vote_by_half_edges();
  Status emit_pieces();

  BooleanRun& run;
  Arena& arena;
  const uint32_t t;
  const uint32_t c[3];
  const KeyIndex* recs;  // its records (rec_ indices), in record order
  const size_t nseg;
  const uint32_t base;  // first intersection point's vertex id
  ArenaArray<Local> locals;
  detail::CdtPoint* pts = nullptr;
  uint32_t* vid = nullptr;
  uint32_t* local_of = nullptr;  // by index in `locals`
  detail::CdtSegment* segs = nullptr;
  uint32_t m = 0, boundary = 0, ns = 0;
  uint32_t corner_at[3] = {};  // ~0u: a corner its outline pinched off (merge_coincident)
  KeyIndex* cons = nullptr;
  uint32_t* cons_from = nullptr;  // by segment, in record order
  size_t ncons = 0;               // nseg less the segments that collapsed to a point
  bool distinct = true;
  bool merged = false;  // two of its points share a vertex id (merge_coincident)
  // Before merge_coincident (runs with merged points only): its points projected, their ids.
  detail::CdtPoint* pts0 = nullptr;
  uint32_t* vid0 = nullptr;
  uint32_t m0 = 0;
  ArenaArray<detail::CdtTriangle> cdt_out;
  ArenaArray<detail::CdtAdjacency> adjacency;
  int8_t* vote = nullptr;
  UnionFind uf;
};

// Re-triangulates cut triangle t along its segments, classifies its pieces (each piece lies on
// one side of a segment; pieces joined by other edges share a side) and gives its corners
// their state.
Status BooleanRun::split_cut(uint32_t t, const uint32_t c[3], const KeyIndex* recs, size_t nseg) {
  ArenaScope scope(arena_);
  CutSplit s(*this, t, c, recs, nseg);
  SPLINTCORE_RETURN_IF_ERROR(s.gather_points());
  SPLINTCORE_RETURN_IF_ERROR(s.order_and_project());
  SPLINTCORE_RETURN_IF_ERROR(s.add_constraints());
  SPLINTCORE_RETURN_IF_ERROR(s.triangulate());
  SPLINTCORE_RETURN_IF_ERROR(s.vote_pieces());
  return s.emit_pieces();
}

// The triangle's distinct points, each on an edge (0..2, with the position along it) or
// inside (3), sorted by point id.
Status BooleanRun::CutSplit::gather_points() {
  const size_t k = 2 * nseg;
  KeyIndex* ids = arena.allocate_array<KeyIndex>(k);
  if (ids == nullptr) return arena.exhausted_status();
  for (size_t i = 0; i < nseg; ++i) {
    const Record& r = run.rec_[recs[i].index];
    ids[2 * i] = KeyIndex{r.from, 0, 0};
    ids[2 * i + 1] = KeyIndex{r.to, 0, 0};
  }
  SPLINTCORE_RETURN_IF_ERROR(sort_keys(arena, ids, k));
  if (!locals.reserve(k)) return arena.exhausted_status();
  for (size_t i = 0; i < k; ++i) {
    if (i > 0 && ids[i].key == ids[i - 1].key) continue;
    const uint32_t pid = static_cast<uint32_t>(ids[i].key);
    const Point& pt = run.points_[pid];
    Local l{pid, 3, 0.0};
    if (pt.key.tri != t) {
      const uint32_t u = key_hi(pt.key.edge), v = key_lo(pt.key.edge);
      for (uint32_t e = 0; e < 3; ++e) {
        const uint32_t x = c[e], y = c[(e + 1) % 3];
        if (x == u && y == v) l = Local{pid, e, pt.s};
        if (x == v && y == u) l = Local{pid, e, -pt.s};
      }
      if (l.where == 3) {
        return make_error(StatusCode::kInternal, "boolean: intersection point ", pid,
                          " is not on triangle ", t);
      }
    }
    if (!locals.push_back(l)) return arena.exhausted_status();
  }
  return Status::ok();
}

// Boundary order: c0, edge 0's points from c0, c1, edge 1's points, c2, edge 2's points,
// then the inside points. Sort by position along the edge, then stably by edge. Then the
// points projected, and the boundary's segments.
Status BooleanRun::CutSplit::order_and_project() {
  const size_t n = locals.size();
  KeyIndex* by = arena.allocate_array<KeyIndex>(n);
  pts = arena.allocate_array<detail::CdtPoint>(n + 3);
  vid = arena.allocate_array<uint32_t>(n + 3);
  local_of = arena.allocate_array<uint32_t>(n);
  segs = arena.allocate_array<detail::CdtSegment>(n + 3 + nseg);
  if (by == nullptr || pts == nullptr || vid == nullptr || local_of == nullptr || segs == nullptr) {
    return arena.exhausted_status();
  }
  SPLINTCORE_RETURN_IF_ERROR(order_points(
      arena, n, c, [&](size_t x) { return locals[x].where; },
      [&](size_t x) { return locals[x].along; },
      [&](size_t x) { return base + run.rep(locals[x].point); }, by, vid, local_of, corner_at, &m,
      &boundary));
  const Projection pr =
      projection_of(run.in_.vertex(c[0]), run.in_.vertex(c[1]), run.in_.vertex(c[2]));
  if (run.merge_ != nullptr) {
    // Kept as they were, for the points to note when a merge cannot be split.
    pts0 = arena.allocate_array<detail::CdtPoint>(m);
    vid0 = arena.allocate_array<uint32_t>(m);
    if (pts0 == nullptr || vid0 == nullptr) return arena.exhausted_status();
    m0 = m;
    for (uint32_t j = 0; j < m; ++j) {
      vid0[j] = vid[j];
      pts0[j] = to_2d(run.position(vid[j]), pr);
    }
    SPLINTCORE_RETURN_IF_ERROR(merge_coincident());
  }
  for (uint32_t j = 0; j < m; ++j) pts[j] = to_2d(run.position(vid[j]), pr);
  for (uint32_t j = 0; j < boundary; ++j) segs[ns++] = detail::CdtSegment{j, (j + 1) % boundary};
  return Status::ok();
}

// A constraint end point's local index: the point id found among the sorted locals (binary
// search).
inline uint32_t BooleanRun::CutSplit::local(uint32_t pid) const {
  size_t lo = 0, hi = locals.size();
  while (hi - lo > 1) {
    const size_t mid = (lo + hi) / 2;
    if (locals[mid].point <= pid)
      lo = mid;
    else
      hi = mid;
  }
  SPLINTCORE_ASSERT(locals[lo].point == pid);
  return local_of[lo];
}

// kUnsupported, with the points near enough to merge too noted (split_with_merges then tries
// again with them merged: a point between two that merged, say).
Status BooleanRun::CutSplit::unsupported_merge(const char* what) {
  run.note_coincident(pts0, vid0, m0);
  const uint32_t tn = run.in_.named_triangle(t);
  return make_error(StatusCode::kUnsupported, "cannot split triangle ", tn,
                    t < run.in_.nta ? " of A" : " of B",
                    " along intersection points that round together: ", what)
      .at_index(tn);
}

// Points of t merged into one (check_points_apart) share a vertex id here. Along the outline
// (c0, edge 0's points, c1, ...) a repeat next to itself is one point, and X Y X pinches off Y
// (a corner, or a point, between two crossings that rounded together): a piece of zero area,
// dropped with Y. An inside point that is one of the outline's is that outline point; inside
// points that merged are one. Renumbers the locals (outline first, in order; then the inside
// points by vertex id) and the corners (~0u: pinched off). Anything else (the outline still
// repeating a point, a constraint end pinched off) is kUnsupported: the nudge takes over.
Status BooleanRun::CutSplit::merge_coincident() {
  KeyIndex* by = arena.allocate_array<KeyIndex>(m);
  if (by == nullptr) return arena.exhausted_status();
  for (uint32_t j = 0; j < m; ++j) by[j] = KeyIndex{vid[j], j, 0};
  SPLINTCORE_RETURN_IF_ERROR(sort_keys(arena, by, m));
  bool repeats = false;
  for (uint32_t j = 1; j < m && !repeats; ++j) repeats = by[j].key == by[j - 1].key;
  if (!repeats) return Status::ok();
  merged = true;
  // The outline as a cycle of local indices, reduced until neither pattern is left.
  uint32_t* seq = arena.allocate_array<uint32_t>(boundary);
  uint32_t* at = arena.allocate_array<uint32_t>(m);
  uint32_t* vid2 = arena.allocate_array<uint32_t>(m);
  if (seq == nullptr || at == nullptr || vid2 == nullptr) return arena.exhausted_status();
  uint32_t k = boundary;
  for (uint32_t j = 0; j < k; ++j) seq[j] = j;
  auto erase = [&](uint32_t i) {
    for (uint32_t x = i; x + 1 < k; ++x) seq[x] = seq[x + 1];
    --k;
  };
  for (bool changed = true; changed && k >= 3;) {
    changed = false;
    for (uint32_t i = 0; i < k && !changed; ++i) {
      const uint32_t i1 = (i + 1) % k, i2 = (i + 2) % k;
      if (vid[seq[i]] == vid[seq[i1]]) {
        erase(i1);
        changed = true;
      } else if (vid[seq[i]] == vid[seq[i2]]) {
        erase(i1 > i2 ? i1 : i2);  // the later index first, so the other stays where it is
        erase(i1 > i2 ? i2 : i1);
        changed = true;
      }
    }
  }
  if (k < 3) return unsupported_merge("its whole outline collapses");
  for (uint32_t j = 0; j < m; ++j) at[j] = ~0u;
  for (uint32_t i = 0; i < k; ++i) {
    at[seq[i]] = i;
    vid2[i] = vid[seq[i]];
  }
  // Each group of one vertex id: to its outline place (at most one is left), else to one new
  // inside place when it has an inside member, else pinched off (~0u).
  uint32_t m2 = k;
  for (uint32_t a = 0; a < m;) {
    uint32_t b = a + 1;
    while (b < m && by[b].key == by[a].key) ++b;
    uint32_t target = ~0u;
    bool inside = false;
    for (uint32_t x = a; x < b; ++x) {
      const uint32_t j = by[x].index;
      inside = inside || j >= boundary;
      if (j >= boundary || at[j] == ~0u) continue;
      if (target != ~0u) return unsupported_merge("its outline passes twice through one point");
      target = at[j];
    }
    if (target == ~0u && inside) {
      target = m2;
      vid2[m2++] = static_cast<uint32_t>(by[a].key);
    }
    for (uint32_t x = a; x < b; ++x) at[by[x].index] = target;
    a = b;
  }
  for (uint32_t e = 0; e < 3; ++e) corner_at[e] = at[corner_at[e]];
  for (size_t x = 0; x < locals.size(); ++x) local_of[x] = at[local_of[x]];
  for (uint32_t j = 0; j < m2; ++j) vid[j] = vid2[j];
  m = m2;
  boundary = k;
  return Status::ok();
}

// The constraints, directed with the other solid's inside on their left, sorted by their
// undirected key (for the classification).
Status BooleanRun::CutSplit::add_constraints() {
  cons = arena.allocate_array<KeyIndex>(nseg);
  cons_from = arena.allocate_array<uint32_t>(nseg);
  if (cons == nullptr || cons_from == nullptr) return arena.exhausted_status();
  // `distinct`: no constraint repeats another or lies on the boundary, so the CDT's segment
  // id on an edge names its record (boundary + its index in recs): the adjacency path applies.
  for (size_t r = 0; r < nseg; ++r) {
    const Record& rc = run.rec_[recs[r].index];
    const uint32_t from = local(rc.from), to = local(rc.to);
    if (merged) {
      // A segment whose ends merged is a point: it cuts nothing (the pieces beside it take
      // their corners' state). One whose end was pinched off cannot be placed.
      if (from == ~0u || to == ~0u) return unsupported_merge("a segment ends at a pinched corner");
      if (from == to) continue;
    }
    cons[ncons] = KeyIndex{edge_key(from, to), from, 0};
    cons_from[ncons++] = from;
    segs[ns++] = detail::CdtSegment{from, to};
    if (from < boundary && to < boundary) {
      const uint32_t gap = from < to ? to - from : from - to;
      if (gap == 1 || gap == boundary - 1) distinct = false;
    }
  }
  SPLINTCORE_RETURN_IF_ERROR(sort_keys(arena, cons, ncons));
  for (size_t x = 1; x < ncons; ++x) {
    if (cons[x].key == cons[x - 1].key) distinct = false;
  }
  if (!merged) return Status::ok();
  distinct = false;  // the votes by half-edges take repeated constraints as well
  // A segment there and back (X -> Y, Y -> X: the sliver between two segments whose far ends
  // merged) bounds nothing: it stays an edge of the triangulation and votes for neither side.
  size_t kept = 0;
  for (size_t a = 0; a < ncons;) {
    size_t b = a + 1;
    while (b < ncons && cons[b].key == cons[a].key) ++b;
    if (!(b - a == 2 && cons[a].index != cons[a + 1].index)) {
      for (size_t x = a; x < b; ++x) cons[kept++] = cons[x];
    }
    a = b;
  }
  ncons = kept;
  return Status::ok();
}

Status BooleanRun::CutSplit::triangulate() {
  Status s = detail::cdt(arena, Span<const detail::CdtPoint>(pts, m),
                         Span<const detail::CdtSegment>(segs, ns), boundary, &cdt_out,
                         distinct ? &adjacency : nullptr);
  if (!s.is_ok()) {
    if (s.code() == StatusCode::kArenaExhausted) return s;
    run.note_coincident(pts, vid, m);
    const uint32_t nta = run.in_.nta;
    return make_error(StatusCode::kUnsupported, "cannot re-triangulate triangle ",
                      run.in_.named_triangle(t), t < nta ? " of A" : " of B",
                      " along its intersection (nearly degenerate contact): ", s.message())
        .at_index(run.in_.named_triangle(t));
  }
  return Status::ok();
}

// Classify the pieces: a constraint votes for the piece on its left (inside the other
// solid) and against the one on its right; other shared edges join pieces. A piece with
// two constraint edges takes the vote of the one with the larger undirected key.
Status BooleanRun::CutSplit::vote_pieces() {
  const uint32_t k = static_cast<uint32_t>(cdt_out.size());
  vote = arena.allocate_array<int8_t>(k);
  if (vote == nullptr || !uf.init(arena, k)) return arena.exhausted_status();
  if (!distinct) return vote_by_half_edges();
  vote_by_adjacency();
  return Status::ok();
}

// From the CDT's own adjacency: the same votes and the same joined sets as matching
// half-edges by key (vote_by_half_edges), without sorting them.
void BooleanRun::CutSplit::vote_by_adjacency() {
  // In locals: a vote is a byte, which may alias anything, so members would be read again
  // after each one.
  const uint32_t k = static_cast<uint32_t>(cdt_out.size());
  const detail::CdtTriangle* const pieces = cdt_out.data();
  const detail::CdtAdjacency* const adjacent = adjacency.data();
  const uint32_t* const from = cons_from;
  const uint32_t b = boundary;
  int8_t* const votes = vote;
  for (uint32_t j = 0; j < k; ++j) {
    votes[j] = 0;
    uint64_t best = 0;
    bool voted = false;
    const detail::CdtTriangle& ct = pieces[j];
    const detail::CdtAdjacency& adj = adjacent[j];
    for (uint32_t e = 0; e < 3; ++e) {
      const uint32_t seg = adj.seg[e];
      if (seg == detail::kCdtNone) {
        if (adj.nb[e] != detail::kCdtNone) uf.unite(j, adj.nb[e]);
        continue;
      }
      if (seg < b) continue;
      const uint64_t key = edge_key(ct.v[e], ct.v[(e + 1) % 3]);
      if (!voted || key > best) {
        best = key;
        voted = true;
        votes[j] = ct.v[e] == from[seg - b] ? 1 : -1;
      }
    }
  }
}

// Half-edges matched by their undirected key.
Status BooleanRun::CutSplit::vote_by_half_edges() {
  const uint32_t k = static_cast<uint32_t>(cdt_out.size());
  KeyIndex* half = arena.allocate_array<KeyIndex>(size_t{3} * k);
  if (half == nullptr && k > 0) return arena.exhausted_status();
  for (uint32_t j = 0; j < k; ++j) {
    vote[j] = 0;
    for (uint32_t e = 0; e < 3; ++e) {
      half[3 * j + e] =
          KeyIndex{edge_key(cdt_out[j].v[e], cdt_out[j].v[(e + 1) % 3]), 3 * j + e, 0};
    }
  }
  SPLINTCORE_RETURN_IF_ERROR(sort_keys(arena, half, size_t{3} * k));
  size_t ci = 0;
  for (size_t a = 0; a < size_t{3} * k;) {
    size_t b = a + 1;
    while (b < size_t{3} * k && half[b].key == half[a].key) ++b;
    while (ci < ncons && cons[ci].key < half[a].key) ++ci;
    if (ci < ncons && cons[ci].key == half[a].key) {
      for (size_t x = a; x < b; ++x) {
        const uint32_t j = half[x].index / 3, e = half[x].index % 3;
        vote[j] = cdt_out[j].v[e] == cons[ci].index ? 1 : -1;
      }
    } else if (b - a == 2) {
      uf.unite(half[a].index / 3, half[a + 1].index / 3);
    }
    a = b;
  }
  return Status::ok();
}

// The pieces with the states of their joined sets, and the states of t's corners.
Status BooleanRun::CutSplit::emit_pieces() {
  const uint32_t k = static_cast<uint32_t>(cdt_out.size());
  int8_t* state = arena.allocate_array<int8_t>(k);
  if (state == nullptr) return arena.exhausted_status();
  if (!joined_states(uf, vote, k, state)) {
    const uint32_t nta = run.in_.nta;
    return make_error(StatusCode::kUnsupported,
                      "inconsistent inside/outside classification in triangle ",
                      run.in_.named_triangle(t), t < nta ? " of A" : " of B",
                      " (overlapping shells in B, or a nearly degenerate contact)")
        .at_index(run.in_.named_triangle(t));
  }
  for (uint32_t j = 0; j < k; ++j) {
    const int8_t sj = state[uf.find(j)];
    if (sj == 0 && !merged) {
      return make_error(StatusCode::kInternal, "boolean: a piece of triangle ", t,
                        " is not next to any intersection segment");
    }
    // Beside a segment that collapsed only (merged ends): its corners decide, after flooding.
    const int8_t out_state = sj != 0 ? sj : kStateFromCorners;
    const detail::CdtTriangle& ct = cdt_out[j];
    if (!run.tris_.push_back(OutTri{{vid[ct.v[0]], vid[ct.v[1]], vid[ct.v[2]]}, t, out_state})) {
      return arena.exhausted_status();
    }
    if (sj == 0) {
      run.pending_ = true;
      continue;
    }
    // Most pieces have no corner of the triangle (only those do have a vertex id below base).
    if (vid[ct.v[0]] >= base && vid[ct.v[1]] >= base && vid[ct.v[2]] >= base) continue;
    const uint32_t bad = pass_state_to_corners(run.vstate_, ct, corner_at, c, sj);
    if (bad != ~0u) return run.inconsistent_vertex(bad);
  }
  return Status::ok();
}

// ---- The fast path: one segment from an edge to another -------------------------------------

namespace {

// The two parts of the pentagon c0 [e0] c1 [e1] c2 [e2] that the chord between its two points,
// `from` on edge ef and `to` on edge et (vertex ids), cuts it into: a triangle and a
// quadrilateral, each in the pentagon's order. Returns the triangle's state (the record's
// inside is left of from -> to).
int8_t pentagon_parts(const uint32_t c[3], int ef, uint32_t from, int et, uint32_t to,
                      uint32_t tri3[3], uint32_t quad[4]) {
  uint32_t poly[5];
  int m = 0, at_from = 0, at_to = 0;
  for (int e = 0; e < 3; ++e) {
    poly[m++] = c[e];
    if (e == ef) {
      at_from = m;
      poly[m++] = from;
    }
    if (e == et) {
      at_to = m;
      poly[m++] = to;
    }
  }
  // Part one runs from the lower chord end to the higher one, part two on from there.
  const int x = at_from < at_to ? at_from : at_to, y = at_from < at_to ? at_to : at_from;
  uint32_t one[4], two[4];
  int n1 = 0, n2 = 0;
  for (int i = x; i <= y; ++i) one[n1++] = poly[i];
  for (int i = y; i != x; i = (i + 1) % 5) two[n2++] = poly[i];
  two[n2++] = poly[x];
  // Part one lies left of poly[y] -> poly[x]; the record's inside is left of from -> to.
  const int8_t s_one = poly[x] == from ? -1 : 1;
  const uint32_t* t3 = n1 == 3 ? one : two;
  const uint32_t* q4 = n1 == 3 ? two : one;
  for (int i = 0; i < 3; ++i) tri3[i] = t3[i];
  for (int i = 0; i < 4; ++i) quad[i] = q4[i];
  return n1 == 3 ? s_one : static_cast<int8_t>(-s_one);
}

inline bool ccw(const detail::CdtPoint& a, const detail::CdtPoint& b, const detail::CdtPoint& c) {
  return orient2d(a.x, a.y, b.x, b.y, c.x, c.y) > 0;
}

}  // namespace

// Fast path: one segment from an edge to another edge (most of B's cut triangles): a
// triangle on one side, a quadrilateral split by its Delaunay diagonal on the other. *done
// false (nothing written) when the segment does not run edge to edge or a piece would not be
// counter-clockwise once projected: split_cut takes the triangle then.
Status BooleanRun::split_single_crossing(uint32_t t, const uint32_t c[3], const Record& rc,
                                         bool* done) {
  *done = false;
  // A merged end (rounded onto another point): split_cut names it by the point that stands
  // for it and drops what collapses.
  if (merge_ != nullptr && (rep(rc.from) != rc.from || rep(rc.to) != rc.to)) return Status::ok();
  const uint32_t base = in_.nva + in_.nvb;
  const Point& pf = points_[rc.from];
  const Point& pt = points_[rc.to];
  int ef = -1, et = -1;
  for (int e = 0; e < 3; ++e) {
    const uint64_t k = edge_key(c[e], c[(e + 1) % 3]);
    if (pf.key.tri != t && pf.key.edge == k) ef = e;
    if (pt.key.tri != t && pt.key.edge == k) et = e;
  }
  if (ef < 0 || et < 0 || ef == et) return Status::ok();
  uint32_t tri3[3], quad[4];
  const int8_t s3 = pentagon_parts(c, ef, base + rc.from, et, base + rc.to, tri3, quad);
  const int8_t s4 = static_cast<int8_t>(-s3);
  const Projection pr = projection_of(in_.vertex(c[0]), in_.vertex(c[1]), in_.vertex(c[2]));
  detail::CdtPoint q2[4];
  for (int i = 0; i < 4; ++i) q2[i] = to_2d(position(quad[i]), pr);
  const detail::CdtPoint t2[3] = {to_2d(position(tri3[0]), pr), to_2d(position(tri3[1]), pr),
                                  to_2d(position(tri3[2]), pr)};
  // Diagonal 0-2 unless quad[3] is inside the circle of 0, 1, 2 (then 1-3).
  const bool d13 =
      incircle(q2[0].x, q2[0].y, q2[1].x, q2[1].y, q2[2].x, q2[2].y, q2[3].x, q2[3].y) > 0;
  const int qa[2][3] = {{0, 1, 2}, {0, 2, 3}};
  const int qb[2][3] = {{0, 1, 3}, {1, 2, 3}};
  const int(*qs)[3] = d13 ? qb : qa;
  if (!(ccw(t2[0], t2[1], t2[2]) && ccw(q2[qs[0][0]], q2[qs[0][1]], q2[qs[0][2]]) &&
        ccw(q2[qs[1][0]], q2[qs[1][1]], q2[qs[1][2]]))) {
    return Status::ok();
  }
  if (!tris_.push_back(OutTri{{tri3[0], tri3[1], tri3[2]}, t, s3})) {
    return arena_.exhausted_status();
  }
  for (int k = 0; k < 2; ++k) {
    if (!tris_.push_back(OutTri{{quad[qs[k][0]], quad[qs[k][1]], quad[qs[k][2]]}, t, s4})) {
      return arena_.exhausted_status();
    }
  }
  for (int i = 0; i < 3; ++i) {
    if (tri3[i] < base && !set_corner_state(vstate_, tri3[i], s3)) {
      return inconsistent_vertex(tri3[i]);
    }
  }
  for (int i = 0; i < 4; ++i) {
    if (quad[i] < base && !set_corner_state(vstate_, quad[i], s4)) {
      return inconsistent_vertex(quad[i]);
    }
  }
  *done = true;
  return Status::ok();
}

// ---- The cut triangles, in order ------------------------------------------------------------

// Records: two per hit, one for each of its triangles, grouped by triangle (stable: hit order
// within a triangle).
Status BooleanRun::sort_records_by_triangle() {
  const uint32_t nh = static_cast<uint32_t>(hits_.size());
  rec_ = arena_.allocate_array<Record>(size_t{2} * nh);
  order_ = arena_.allocate_array<KeyIndex>(size_t{2} * nh);
  if ((rec_ == nullptr || order_ == nullptr) && nh > 0) return arena_.exhausted_status();
  for (uint32_t h = 0; h < nh; ++h) {
    const uint32_t p = hit_points_[2 * h], q = hit_points_[2 * h + 1];
    rec_[2 * h] = Record{hits_[h].ta, p, q, h};
    rec_[2 * h + 1] = Record{hits_[h].tb, q, p, h};
    order_[2 * h] = KeyIndex{hits_[h].ta, 2 * h, 0};
    order_[2 * h + 1] = KeyIndex{hits_[h].tb, 2 * h + 1, 0};
  }
  return radix_sort(arena_, Span<KeyIndex>(order_, size_t{2} * nh));
}

// Degenerate records by triangle (stable), and their triangles' flags (*dorder stays null
// when there are none).
Status BooleanRun::sort_contacts_by_triangle(KeyIndex** dorder) {
  if (st_.degenerate_pairs == 0) return Status::ok();
  const size_t nd = deg_.size();
  const size_t ntri = size_t{in_.nta} + in_.ntb;
  tflag_ = arena_.allocate_array<uint8_t>(ntri);
  tstate_ = arena_.allocate_array<int8_t>(ntri);
  KeyIndex* d = arena_.allocate_array<KeyIndex>(nd + 1);
  if (tflag_ == nullptr || tstate_ == nullptr || d == nullptr) return arena_.exhausted_status();
  std::memset(tflag_, kUncut, ntri);
  std::memset(tstate_, 0, ntri);
  for (size_t r = 0; r < nd; ++r) d[r] = KeyIndex{deg_[r].tri, static_cast<uint32_t>(r), 0};
  *dorder = d;
  return radix_sort(arena_, Span<KeyIndex>(d, nd));
}

namespace {

// The cut triangles in id order: each with its run of crossing records (`order`, sorted by
// triangle) and its run of degenerate records (`dorder`), either run possibly empty.
struct TriangleGroups {
  const KeyIndex* order;
  size_t n;
  const KeyIndex* dorder;
  size_t nd;

  bool more(size_t g, size_t d) const { return g < n || d < nd; }
  // The next triangle with records of either kind, and the ends of its two runs.
  uint32_t next(size_t g, size_t d, size_t* g_end, size_t* d_end) const {
    const uint64_t tg = g < n ? order[g].key : ~uint64_t{0};
    const uint64_t td = d < nd ? dorder[d].key : ~uint64_t{0};
    const uint64_t t = tg < td ? tg : td;
    *g_end = g;
    while (*g_end < n && order[*g_end].key == t) ++*g_end;
    *d_end = d;
    while (*d_end < nd && dorder[*d_end].key == t) ++*d_end;
    return static_cast<uint32_t>(t);
  }
};

// Room for the pieces: a triangle with r segments has at most 2r points, so at most
// 3 + 2 * 2r - 2 pieces (b + 2i - 2 for b boundary and i inside points); one with degenerate
// records 4 per record and 3. Counts the cut triangles of A and of B on the way.
uint64_t piece_room(const TriangleGroups& groups, uint32_t nta, uint32_t* cut_a, uint32_t* cut_b) {
  uint64_t total = 0;
  for (size_t g = 0, d = 0; groups.more(g, d);) {
    size_t g_end = 0, d_end = 0;
    const uint32_t t = groups.next(g, d, &g_end, &d_end);
    total += d_end > d ? 4 * (g_end - g + d_end - d) + 3 : 4 * (g_end - g) + 1;
    if (t < nta)
      ++*cut_a;
    else
      ++*cut_b;
    g = g_end;
    d = d_end;
  }
  return total;
}

}  // namespace

// Each cut triangle re-triangulated along its segments and contacts, its pieces classified
// and its corners given their state: by the fast path when it can, otherwise by split_cut, or
// by split_general when it has degenerate contacts.
Status BooleanRun::split_triangles() {
  SPLINTCORE_RETURN_IF_ERROR(sort_records_by_triangle());
  KeyIndex* dorder = nullptr;
  SPLINTCORE_RETURN_IF_ERROR(sort_contacts_by_triangle(&dorder));
  const size_t n = size_t{2} * hits_.size();
  const TriangleGroups groups{order_, n, dorder, deg_.size()};
  uint32_t cut_a = 0, cut_b = 0;
  const uint64_t total = piece_room(groups, in_.nta, &cut_a, &cut_b);
  st_.cut_triangles_a = cut_a;
  st_.cut_triangles_b = cut_b;
  if (total >= (uint64_t{1} << 31)) {
    return make_error(StatusCode::kLimitExceeded, "too many triangles for 32-bit ids: ", total);
  }
  tris_.bind(&arena_);
  pieces_at_ = arena_.mark();
  if (!tris_.reserve(static_cast<size_t>(total))) return arena_.exhausted_status();

  Status first;  // the first triangle that failed on points noted to merge
  for (size_t g = 0, d = 0; groups.more(g, d);) {
    size_t g_end = 0, d_end = 0;
    const uint32_t t = groups.next(g, d, &g_end, &d_end);
    if ((g & 1023u) == 0) {
      SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx_, "boolean: split", g, n));
    }
    if (tflag_ != nullptr) tflag_[t] = kDecided;
    const uint32_t noted = n_noted_;
    Status s;
    if (d_end > d) {
      s = split_general(t, order_ + g, g_end - g, dorder + d, d_end - d);
    } else {
      uint32_t c[3];
      in_.corners(t, c);
      bool done = false;
      if (g_end - g == 1) {
        SPLINTCORE_RETURN_IF_ERROR(split_single_crossing(t, c, rec_[order_[g].index], &done));
      }
      if (!done) s = split_cut(t, c, order_ + g, g_end - g);
    }
    if (!s.is_ok()) {
      // Failed on points that coincide in its plane: the others are split (their pairs noted
      // too), then split_with_merges merges them and splits again.
      if (n_noted_ == noted || s.code() != StatusCode::kUnsupported) return s;
      if (first.is_ok()) first = s;
    }
    g = g_end;
    d = d_end;
  }
  return first;
}

namespace {

// The spacing of the output's numbers at magnitude x (x >= 0): float32's, or double's.
double rounding_step(double x, bool float32) {
  double u = 0x1p-126;
  while (u * 8388608.0 <= x && u < 1e300) u *= 2.0;
  return float32 ? u : u * 0x1p-29;
}

}  // namespace

// Intersection points of a triangle (its m points projected, pts, with their vertex ids vid)
// that coincide in its plane as projected, or lie within kNear rounding steps of each other
// there along both axes (the triangulation then fails on a point exactly on a segment, or two
// segments crossing, by rounding): noted as pairs to merge (never a corner: that cannot move).
// True when it noted one. Runs only where the triangulation failed.
bool BooleanRun::note_coincident(const detail::CdtPoint* pts, const uint32_t* vid, uint32_t m) {
  constexpr double kNear = 4.0;
  const uint32_t base = in_.nva + in_.nvb;
  auto mag = [](double x) { return x < 0 ? -x : x; };
  bool any = false;
  for (uint32_t i = 0; i < m; ++i) {
    for (uint32_t j = i + 1; j < m; ++j) {
      const double xs[4] = {mag(pts[i].x), mag(pts[i].y), mag(pts[j].x), mag(pts[j].y)};
      double big = 0;
      for (const double x : xs) big = x > big ? x : big;
      const double tol = kNear * rounding_step(big, options_.float32_output);
      if (!(mag(pts[i].x - pts[j].x) <= tol && mag(pts[i].y - pts[j].y) <= tol)) continue;
      if (vid[i] < base || vid[j] < base || vid[i] == vid[j]) continue;
      if (n_noted_ == kMaxNoted) {
        noted_overflow_ = true;
        return any;
      }
      noted_[n_noted_][0] = vid[i] - base;
      noted_[n_noted_][1] = vid[j] - base;
      ++n_noted_;
      any = true;
    }
  }
  return any;
}

// The noted pairs merged into merge_ (allocated here at the first): each group named by its
// lowest id, as check_points_apart names them (a root always has a lower id than its members,
// so one pass in id order resolves every chain).
Status BooleanRun::merge_noted() {
  const uint32_t np = static_cast<uint32_t>(points_.size());
  if (merge_ == nullptr) {
    merge_ = arena_.allocate_array<uint32_t>(np);
    if (merge_ == nullptr) return arena_.exhausted_status();
    for (uint32_t i = 0; i < np; ++i) merge_[i] = i;
  }
  auto root = [&](uint32_t x) {
    while (merge_[x] != x) x = merge_[x];
    return x;
  };
  for (uint32_t k = 0; k < n_noted_; ++k) {
    const uint32_t a = root(noted_[k][0]), b = root(noted_[k][1]);
    if (a < b) merge_[b] = a;
    if (b < a) merge_[a] = b;
  }
  uint64_t merged = 0;
  for (uint32_t i = 0; i < np; ++i) {
    merge_[i] = merge_[merge_[i]];
    merged += merge_[i] != i ? 1 : 0;
  }
  st_.merged_points = merged;
  st_.intersection_points = np - merged;  // distinct ones
  return Status::ok();
}

// split_triangles, and again (a few rounds at most) while a round notes points that coincide
// in the plane of a triangle they share: those are merged and the split starts over from
// where it started (its memory returned, the vertex states it set cleared).
Status BooleanRun::split_with_merges() {
  constexpr int kRounds = 4;
  for (int round = 0;; ++round) {
    const Arena::Marker mark = arena_.mark();
    n_noted_ = 0;
    const Status s = split_triangles();
    if (n_noted_ == 0 || s.code() == StatusCode::kArenaExhausted) {
      // The room reserved for the pieces is their most (piece_room); what they left of it
      // goes back before classify and assemble allocate above them.
      tris_.shrink_to_fit();
      return s;
    }
    // Had the points been refused, this first failure would have been the end.
    if (round == 0 && unmerged_.is_ok()) unmerged_ = s;
    if (round + 1 == kRounds || noted_overflow_) return s;
    arena_.rewind(mark);
    const uint32_t nv_in = in_.nva + in_.nvb;
    for (uint32_t v = 0; v < nv_in; ++v) {
      if (vstate_[v] != kVertexOn) vstate_[v] = 0;
    }
    pending_ = false;
    tflag_ = nullptr;
    tstate_ = nullptr;
    rec_ = nullptr;
    order_ = nullptr;
    tris_.bind(&arena_);
    SPLINTCORE_RETURN_IF_ERROR(merge_noted());
  }
}

}  // namespace boolean_detail

}  // namespace splintcore
