// The exact intersection of two closed triangles, every degenerate contact named.
//
// Sources: the case analysis of O. Devillers and P. Guigue, "Faster triangle-triangle
// intersection tests", INRIA RR-4488, 2002 (each triangle meets the other's plane in an
// interval of the line where the planes meet; the intersection is the overlap of the two
// intervals, ordered by orient3d of an edge of one triangle against an edge of the other),
// extended here to every zero sign; T. Moller, "A fast triangle-triangle intersection test",
// JGT 2(2), 1997, for the coplanar projection; J. R. Shewchuk, "Adaptive Precision
// Floating-Point Arithmetic and Fast Robust Geometric Predicates", 1997, for orient2d/orient3d
// (predicates.cpp), the only source of decisions here.
//
// Not coplanar. A meets B's plane in an interval I_A of the line L (the planes' meeting line,
// directed along d = n_a x n_b) whose two ends are features of A: a corner on B's plane or an
// edge whose ends lie strictly on opposite sides (line_interval; which end comes first along d
// follows from the signs alone, see there). B likewise. A n B = I_A n I_B, whose ends are the
// ends of I_A that lie in closed B and the ends of I_B that lie in closed A. Where a point of
// L lies on B is decided against B's three edge lines, inside B's plane: for a corner of A
// (exactly in B's plane) by orient2d on a projection that keeps B non-degenerate; for the
// crossing X of A's edge pq with B's plane by the sign of orient3d(b_m, b_m+1, p, q), which is
// -side(p) times the side of X against the line b_m b_m+1 (orient3d is linear in its last
// argument and X = p + t (q - p), t in (0, 1)). The same point found from both triangles gets
// the same name (corners on corners, edges on edges), so duplicates are dropped by name.
//
// Coplanar. Projected along an axis that keeps A non-degenerate (geometry.h's
// projection_axis: the dominant normal component first, decided by orient2d); B is re-indexed
// to run the same way round as A (B'), so that "left" means "inside" for both. The vertices of
// the convex polygon A n B are exactly: A's corners in closed B, B's corners in closed A (not
// on a corner of A), and the proper crossings of an edge of A with an edge of B (strict signs
// both ways); when the polygon has area every one of these is a true corner (its wedge has an
// angle below 180 degrees). They are put in order without computing any point: each boundary
// edge of the polygon lies along an edge of A or B', and on one such edge the two polygon
// corners are ordered by their features (a corner of that triangle at either end; points of
// the other triangle by the start/end rule of line_interval applied to that edge's line).
#include "boolean/contact.h"

namespace splintcore {
namespace detail {

namespace {

constexpr Loc kOutside = static_cast<Loc>(7);  // not on the closed triangle (internal only)

// Where a point lies on a triangle, from its sides against the three edge lines (+1 on the
// triangle's side, 0 on the line, -1 beyond).
Loc loc_from_sides(const int l[3]) {
  if (l[0] < 0 || l[1] < 0 || l[2] < 0) return kOutside;
  const int zeros = (l[0] == 0) + (l[1] == 0) + (l[2] == 0);
  SPLINTCORE_ASSERT(zeros < 3);  // no point lies on the three lines of a proper triangle
  if (zeros == 0) return Loc::kFace;
  if (zeros == 1) return edge_loc(l[0] == 0 ? 0 : (l[1] == 0 ? 1 : 2));
  // Edges k and k + 1 share corner k + 1.
  if (l[0] != 0) return vertex_loc(2);
  if (l[1] != 0) return vertex_loc(0);
  return vertex_loc(1);
}

// A triangle (counter-clockwise seen from the side where "left" is measured) meets a directed
// line in its plane; s[i] is corner i's side of the line (+1 left, -1 right, 0 on it; not all
// 0). The intersection is an interval whose ends are features of the triangle: a corner on
// the line or an edge crossing it (ends strictly on opposite sides). Walking the boundary
// counter-clockwise the interior is on the left, so the boundary crosses the line from left to
// right at the interval's start and from right to left at its end; a corner on the line is the
// start when its predecessor is on the left or its successor on the right (that includes an
// edge along the line: it runs with the line when the third corner is on the left), and the
// end in the mirrored cases; a corner touching the line alone is both. False when the
// triangle is strictly on one side.
bool line_interval(const int s[3], Loc* start, Loc* end) {
  bool have_start = false, have_end = false;
  for (int i = 0; i < 3; ++i) {
    const int next = s[(i + 1) % 3];
    const int prev = s[(i + 2) % 3];
    if (s[i] == 0) {
      if (prev > 0 || next < 0) {
        *start = vertex_loc(i);
        have_start = true;
      }
      if (prev < 0 || next > 0) {
        *end = vertex_loc(i);
        have_end = true;
      }
    } else if (s[i] > 0 && next < 0) {
      *start = edge_loc(i);
      have_start = true;
    } else if (s[i] < 0 && next > 0) {
      *end = edge_loc(i);
      have_end = true;
    }
  }
  SPLINTCORE_ASSERT(have_start == have_end);
  return have_start;
}

// A 2-D projection that keeps a triangle non-degenerate: the kept axes u, v and the sign of
// the triangle's orientation there.
struct Projection {
  int u = 0, v = 1;
  int sigma = 0;
};

inline int orient2(const Projection& pr, const Vec3& a, const Vec3& b, const Vec3& c) {
  return sign_of(orient2d(a[pr.u], a[pr.v], b[pr.u], b[pr.v], c[pr.u], c[pr.v]));
}

Projection projection_of(const Vec3 t[3]) {
  const int w = projection_axis(t[0], t[1], t[2]);
  SPLINTCORE_ASSERT(w >= 0);  // the caller rejected degenerate triangles
  Projection pr;
  pr.u = (w + 1) % 3;
  pr.v = (w + 2) % 3;
  pr.sigma = orient2(pr, t[0], t[1], t[2]);
  return pr;
}

// Where a point q lying exactly in t's plane (a corner of the other triangle) lies on t.
Loc vertex_on(const Vec3 t[3], const Projection& pr, const Vec3& q) {
  int l[3];
  for (int k = 0; k < 3; ++k) l[k] = pr.sigma * orient2(pr, t[k], t[(k + 1) % 3], q);
  return loc_from_sides(l);
}

// Where the other triangle's edge pq crosses t's plane, on t: p and q strictly on opposite
// sides, sp = sign of orient3d(t0, t1, t2, p) (+1 below).
Loc crossing_on(const Vec3 t[3], const Vec3& p, const Vec3& q, int sp) {
  int l[3];
  for (int k = 0; k < 3; ++k) l[k] = -sp * sign_of(orient3d(t[k], t[(k + 1) % 3], p, q));
  return loc_from_sides(l);
}

// Where the end `feature` (a corner on the other plane or an edge crossing it) of t's interval
// lies on the other triangle o. s: t's corner sides against o's plane.
Loc feature_on(const Vec3 t[3], const int s[3], Loc feature, const Vec3 o[3]) {
  const int i = loc_index(feature);
  if (loc_is_vertex(feature)) {
    const Projection pr = projection_of(o);
    return vertex_on(o, pr, t[i]);
  }
  return crossing_on(o, t[i], t[(i + 1) % 3], s[i]);
}

struct Candidate {
  ContactPoint p;
  bool start, end;
};

void add_candidate(Candidate* c, int* n, const ContactPoint& p, bool start, bool end) {
  for (int i = 0; i < *n; ++i) {
    if (c[i].p == p) {
      c[i].start = c[i].start || start;
      c[i].end = c[i].end || end;
      return;
    }
  }
  SPLINTCORE_ASSERT(*n < 4);
  c[*n] = Candidate{p, start, end};
  ++*n;
}

void transversal_contact(const Vec3 a[3], const Vec3 b[3], const int sa[3], const int sb[3],
                         Contact* out) {
  // A's corners below B (sa > 0) lie left of d seen from n_a, since n_a x d = -|n_a|^2 times
  // the part of n_b along A's plane: line_interval(sa) is A's interval along d. For B the
  // same holds along n_b x n_a = -d, so B's start along d is its end along -d.
  Loc a_start = Loc::kFace, a_end = Loc::kFace, b_first = Loc::kFace, b_second = Loc::kFace;
  if (!line_interval(sa, &a_start, &a_end) || !line_interval(sb, &b_first, &b_second)) return;
  const Loc b_start = b_second, b_end = b_first;
  Candidate c[4];
  int n = 0;
  const Loc a_ends[2] = {a_start, a_end};
  for (int e = 0; e < 2; ++e) {
    if (e == 1 && a_end == a_start) break;
    const Loc on_b = feature_on(a, sa, a_ends[e], b);
    if (on_b == kOutside) continue;
    add_candidate(c, &n, ContactPoint{a_ends[e], on_b}, a_ends[e] == a_start, a_ends[e] == a_end);
  }
  const Loc b_ends[2] = {b_start, b_end};
  for (int e = 0; e < 2; ++e) {
    if (e == 1 && b_end == b_start) break;
    const Loc on_a = feature_on(b, sb, b_ends[e], a);
    if (on_a == kOutside) continue;
    add_candidate(c, &n, ContactPoint{on_a, b_ends[e]}, b_ends[e] == b_start, b_ends[e] == b_end);
  }
  SPLINTCORE_ASSERT(n <= 2);
  if (n == 0) return;
  if (n == 1) {
    out->kind = ContactKind::kPoint;
    out->count = 1;
    out->p[0] = c[0].p;
    return;
  }
  // Two distinct points: the later start and the earlier end of the two intervals; a start
  // that were also an end would make the overlap a single point.
  SPLINTCORE_ASSERT(c[0].start != c[0].end && c[1].start != c[1].end && c[0].start != c[1].start);
  const int first = c[0].start ? 0 : 1;
  out->kind = ContactKind::kSegment;
  out->count = 2;
  out->p[0] = c[first].p;
  out->p[1] = c[1 - first].p;
}

// Coplanar triangles A and B' (B re-indexed to run the same way round as A), each against the
// other's edge lines: la[k][j], B' corner j against A's edge k; lb[m][i], A's corner i against
// B' edge m (+1 on the triangle's side).
struct CoplanarSides {
  int la[3][3], lb[3][3];

  // Order of two points of the result on A's closed edge k (side 0) or B''s edge k (side 1):
  // 0 at the edge's first corner, 3 at its last, 1 or 2 for a point of the other triangle
  // (the start or the end of that triangle's interval along the edge's line).
  int key(int side, int k, const ContactPoint& p) const {
    const Loc own = side == 0 ? p.on_a : p.on_b;
    if (own == vertex_loc(k)) return 0;
    if (own == vertex_loc((k + 1) % 3)) return 3;
    const Loc other = side == 0 ? p.on_b : p.on_a;
    int s[3];
    for (int j = 0; j < 3; ++j) s[j] = side == 0 ? la[k][j] : lb[k][j];
    Loc start = Loc::kFace, end = Loc::kFace;
    const bool meets = line_interval(s, &start, &end);
    SPLINTCORE_ASSERT(meets && (other == start || other == end));
    (void)meets;
    return other == start ? 1 : 2;
  }
};

// The corners of the polygon A n B' (in B' names), unordered: A's corners in closed B', B''s
// corners in closed A but not on a corner of A, and the proper crossings of an edge of A with
// an edge of B'. Returns their number (at most 6).
int polygon_corners(const CoplanarSides& sd, ContactPoint c[12]) {
  int n = 0;
  for (int i = 0; i < 3; ++i) {
    const int l[3] = {sd.lb[0][i], sd.lb[1][i], sd.lb[2][i]};
    const Loc on_b = loc_from_sides(l);
    if (on_b != kOutside) c[n++] = ContactPoint{vertex_loc(i), on_b};
  }
  for (int j = 0; j < 3; ++j) {
    const int l[3] = {sd.la[0][j], sd.la[1][j], sd.la[2][j]};
    const Loc on_a = loc_from_sides(l);
    if (on_a != kOutside && !loc_is_vertex(on_a)) c[n++] = ContactPoint{on_a, vertex_loc(j)};
  }
  for (int k = 0; k < 3; ++k) {
    for (int m = 0; m < 3; ++m) {
      if (sd.la[k][m] * sd.la[k][(m + 1) % 3] == -1 && sd.lb[m][k] * sd.lb[m][(k + 1) % 3] == -1) {
        c[n++] = ContactPoint{edge_loc(k), edge_loc(m)};
      }
    }
  }
  SPLINTCORE_ASSERT(n <= 6);
  return n;
}

// The n >= 3 corners c of the polygon in order. Each boundary edge of the polygon runs along
// an edge of A or of B', in that edge's direction (the polygon lies on the left of both): link
// its two corners.
void order_polygon(const CoplanarSides& sd, const ContactPoint* c, int n, ContactPoint* ordered) {
  int next[6] = {-1, -1, -1, -1, -1, -1};
  for (int side = 0; side < 2; ++side) {
    for (int k = 0; k < 3; ++k) {
      int on[2] = {-1, -1};
      int count = 0;
      for (int i = 0; i < n; ++i) {
        if (loc_on_closed_edge(side == 0 ? c[i].on_a : c[i].on_b, k)) {
          SPLINTCORE_ASSERT(count < 2);  // a convex polygon has at most 2 corners on a line
          on[count++] = i;
        }
      }
      if (count < 2) continue;
      const bool swap = sd.key(side, k, c[on[0]]) > sd.key(side, k, c[on[1]]);
      const int from = on[swap ? 1 : 0], to = on[swap ? 0 : 1];
      SPLINTCORE_ASSERT(next[from] == -1 || next[from] == to);
      next[from] = to;
    }
  }
  int at = 0;
  for (int i = 0; i < n; ++i) {
    ordered[i] = c[at];
    at = next[at];
    SPLINTCORE_ASSERT(at >= 0 && (at == 0) == (i == n - 1));
  }
}

// Coplanar triangles (see the top of the file). B' is b re-indexed to run the same way round
// as a: corner i of B' is corner perm[i] of b, edge m of B' is edge emap[m] of b.
void coplanar_contact(const Vec3 a[3], const Vec3 b[3], Contact* out) {
  const Projection pr = projection_of(a);
  const int sigma_b = orient2(pr, b[0], b[1], b[2]);
  SPLINTCORE_ASSERT(sigma_b != 0);  // same plane, so the projection keeps b proper too
  const bool reversed = sigma_b != pr.sigma;
  const int perm[3] = {0, reversed ? 2 : 1, reversed ? 1 : 2};
  const int emap[3] = {reversed ? 2 : 0, 1, reversed ? 0 : 2};
  const Vec3 bp[3] = {b[perm[0]], b[perm[1]], b[perm[2]]};
  CoplanarSides sd;
  for (int k = 0; k < 3; ++k) {
    for (int j = 0; j < 3; ++j) {
      sd.la[k][j] = pr.sigma * orient2(pr, a[k], a[(k + 1) % 3], bp[j]);
      sd.lb[k][j] = pr.sigma * orient2(pr, bp[k], bp[(k + 1) % 3], a[j]);
    }
  }
  ContactPoint c[12];  // B' names until the end
  const int n = polygon_corners(sd, c);
  ContactPoint ordered[6];
  if (n == 1) {
    ordered[0] = c[0];
  } else if (n == 2) {
    // A segment lies in the boundary of both triangles, so along one edge of A.
    int k = 0;
    while (k < 3 && !(loc_on_closed_edge(c[0].on_a, k) && loc_on_closed_edge(c[1].on_a, k))) ++k;
    SPLINTCORE_ASSERT(k < 3);
    const bool swap = sd.key(0, k, c[0]) > sd.key(0, k, c[1]);
    ordered[0] = c[swap ? 1 : 0];
    ordered[1] = c[swap ? 0 : 1];
  } else if (n >= 3) {
    order_polygon(sd, c, n, ordered);
  }
  out->kind = n == 0 ? ContactKind::kNone
                     : (n == 1 ? ContactKind::kPoint
                               : (n == 2 ? ContactKind::kSegment : ContactKind::kPolygon));
  out->count = static_cast<uint8_t>(n);
  for (int i = 0; i < n; ++i) {
    Loc on_b = ordered[i].on_b;
    if (loc_is_vertex(on_b)) on_b = vertex_loc(perm[loc_index(on_b)]);
    if (loc_is_edge(on_b)) on_b = edge_loc(emap[loc_index(on_b)]);
    out->p[i] = ContactPoint{ordered[i].on_a, on_b};
  }
}

// Strict lexicographic order (x, then y, then z).
inline bool lex_less(const Vec3& p, const Vec3& q) {
  if (p.x != q.x) return p.x < q.x;
  if (p.y != q.y) return p.y < q.y;
  return p.z < q.z;
}

inline void sort2(Vec3* p, Vec3* q) {
  if (lex_less(*q, *p)) {
    const Vec3 t = *p;
    *p = *q;
    *q = t;
  }
}

// u + (v - u) s, s = du / (du - dv) clamped to [0, 1] (NaN to 0).
inline Vec3 along(const Vec3& u, const Vec3& v, double du, double dv) {
  double s = du / (du - dv);
  if (!(s > 0.0)) s = 0.0;
  if (s > 1.0) s = 1.0;
  return u + (v - u) * s;
}

Vec3 edge_through_plane(Vec3 u, Vec3 v, const Vec3 t[3]) {
  sort2(&u, &v);
  Vec3 t0 = t[0], t1 = t[1], t2 = t[2];
  sort2(&t0, &t1);
  sort2(&t1, &t2);
  sort2(&t0, &t1);
  const Vec3 n = cross(t1 - t0, t2 - t0);
  return along(u, v, dot(n, u - t0), dot(n, v - t0));
}

Vec3 edge_cross_edge(Vec3 u, Vec3 v, Vec3 r, Vec3 w) {
  sort2(&u, &v);
  sort2(&r, &w);
  if (lex_less(r, u) || (!lex_less(u, r) && lex_less(w, v))) {
    const Vec3 tu = u, tv = v;
    u = r;
    v = w;
    r = tu;
    w = tv;
  }
  const Vec3 n = cross(v - u, w - r);
  const double nx = n.x < 0 ? -n.x : n.x, ny = n.y < 0 ? -n.y : n.y, nz = n.z < 0 ? -n.z : n.z;
  const int drop = (nx >= ny && nx >= nz) ? 0 : (ny >= nz ? 1 : 2);
  const int i = (drop + 1) % 3, j = (drop + 2) % 3;
  const double fi = w[i] - r[i], fj = w[j] - r[j];
  const double du = fi * (u[j] - r[j]) - fj * (u[i] - r[i]);
  const double dv = fi * (v[j] - r[j]) - fj * (v[i] - r[i]);
  return along(u, v, du, dv);
}

}  // namespace

bool intersect_triangles(const Vec3 a[3], const Vec3 b[3], Contact* out) {
  *out = Contact{};
  if (collinear3d(a[0], a[1], a[2]) || collinear3d(b[0], b[1], b[2])) return false;
  int sa[3], sb[3];
  for (int i = 0; i < 3; ++i) {
    sa[i] = sign_of(orient3d(b[0], b[1], b[2], a[i]));
    sb[i] = sign_of(orient3d(a[0], a[1], a[2], b[i]));
  }
  if (sa[0] == 0 && sa[1] == 0 && sa[2] == 0) {
    out->coplanar = true;
    coplanar_contact(a, b, out);
    return true;
  }
  for (int i = 0; i < 3; ++i) {
    out->side_a[i] = static_cast<int8_t>(sa[i]);
    out->side_b[i] = static_cast<int8_t>(sb[i]);
  }
  transversal_contact(a, b, sa, sb, out);
  return true;
}

Vec3 contact_point_position(const Vec3 a[3], const Vec3 b[3], const ContactPoint& p) {
  if (loc_is_vertex(p.on_a)) return a[loc_index(p.on_a)];
  if (loc_is_vertex(p.on_b)) return b[loc_index(p.on_b)];
  SPLINTCORE_ASSERT(p.on_a != Loc::kFace || p.on_b != Loc::kFace);
  const int i = loc_index(p.on_a), j = loc_index(p.on_b);
  if (p.on_b == Loc::kFace) return edge_through_plane(a[i], a[(i + 1) % 3], b);
  if (p.on_a == Loc::kFace) return edge_through_plane(b[j], b[(j + 1) % 3], a);
  return edge_cross_edge(a[i], a[(i + 1) % 3], b[j], b[(j + 1) % 3]);
}

}  // namespace detail
}  // namespace splintcore
