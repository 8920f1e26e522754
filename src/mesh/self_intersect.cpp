// Self-intersection of a triangle mesh: sweep-and-prune on boxes sorted by their x minimum,
// then exact tests (see geometry.h) that respect the vertices and edges triangles share.
#include "splintcore/mesh.h"

namespace splintcore {

namespace {

// Maps a double to a key whose unsigned order is the numeric order (for the radix sort).
inline uint64_t order_key(double v) {
  uint64_t bits;
  std::memcpy(&bits, &v, sizeof(bits));
  return (bits >> 63) != 0 ? ~bits : bits | (uint64_t{1} << 63);
}

struct Box {
  double lo[3];
  double hi[3];
};

// A triangle's plane for a floating-point filter: side(x) = n . (x - a) with
// n = (b - a) x (c - a), and `nabs` the magnitudes of the terms of each component of n, so that
// nabs . |x - a| is the permanent of the determinant det[b - a, c - a, x - a]. Its rounding
// error is below (7 + 56 eps) eps times the permanent (Shewchuk's orient3d bound: the same
// three-term sum of a coordinate times a 2x2 minor); a sign whose magnitude clears 1e-15
// times the permanent is therefore the exact sign. Anything closer goes to the exact tests.
struct Plane {
  Vec3 a;
  Vec3 n;
  Vec3 nabs;
};

constexpr double kPlaneFilter = 1e-15;

Plane plane_of(const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 e1 = b - a, e2 = c - a;
  Plane p;
  p.a = a;
  p.n = cross(e1, e2);
  auto m = [](double x) { return x < 0 ? -x : x; };
  p.nabs = Vec3{m(e1.y * e2.z) + m(e1.z * e2.y), m(e1.z * e2.x) + m(e1.x * e2.z),
                m(e1.x * e2.y) + m(e1.y * e2.x)};
  return p;
}

// Where a point is relative to a plane, as far as the filter can tell. kOn is exact: a zero
// permanent means every term of the determinant has an exactly zero factor (a rounded
// difference or product is zero only when it is exactly zero), so the point is on the plane.
enum Side : int { kBelow = -1, kUnknown = 0, kAbove = 1, kOn = 2 };

inline Side side_of(const Plane& p, const Vec3& x) {
  const Vec3 d = x - p.a;
  const double side = p.n.x * d.x + p.n.y * d.y + p.n.z * d.z;
  const double permanent = p.nabs.x * (d.x < 0 ? -d.x : d.x) + p.nabs.y * (d.y < 0 ? -d.y : d.y) +
                           p.nabs.z * (d.z < 0 ? -d.z : d.z);
  if (permanent == 0.0) return kOn;
  const double bound = kPlaneFilter * permanent;
  return side > bound ? kAbove : (side < -bound ? kBelow : kUnknown);
}

// All strictly on one side (certain), all exactly on the plane, or neither.
enum Spread { kSeparated, kCoplanar, kMixed };

inline Spread spread(const Plane& plane, const Vec3* pts, int n) {
  const Side s0 = side_of(plane, pts[0]);
  bool same = s0 != kUnknown;
  for (int i = 1; i < n && same; ++i) same = side_of(plane, pts[i]) == s0;
  if (!same) return kMixed;
  return s0 == kOn ? kCoplanar : kSeparated;
}

// Same side of the shared edge ab, for coplanar c and d?
bool folded_onto(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  int axis = projection_axis(a, b, c);
  if (axis < 0) return false;
  auto drop = [axis](const Vec3& v, double* x, double* y) {
    if (axis == 0) { *x = v.y; *y = v.z; }
    else if (axis == 1) { *x = v.z; *y = v.x; }
    else { *x = v.x; *y = v.y; }
  };
  double ax, ay, bx, by, cx, cy, dx, dy;
  drop(a, &ax, &ay);
  drop(b, &bx, &by);
  drop(c, &cx, &cy);
  drop(d, &dx, &dy);
  return sign_of(orient2d(ax, ay, bx, by, cx, cy)) * sign_of(orient2d(ax, ay, bx, by, dx, dy)) > 0;
}

// Does the edge pq meet triangle abc (whose plane is pl)?
inline bool edge_meets(const Plane& pl, const Vec3& p, const Vec3& q, const Vec3& a,
                       const Vec3& b, const Vec3& c) {
  const Vec3 pts[2] = {p, q};
  switch (spread(pl, pts, 2)) {
    case kSeparated: return false;
    case kCoplanar: return coplanar_segment_intersects_triangle(p, q, a, b, c);
    default: return segment_intersects_triangle(p, q, a, b, c);
  }
}

// Do triangles s and t conflict, given the vertex ids they share? The planes let the common
// cases be decided by the filter; whatever it cannot decide goes to the exact tests.
bool conflict(const Vec3* v, const Triangle& s, const Triangle& t, const Plane& ps,
              const Plane& pt) {
  int shared = 0;
  int s_at[3] = {-1, -1, -1};  // for each corner of s, the matching corner of t
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      if (s.v[i] == t.v[j]) {
        s_at[i] = j;
        ++shared;
      }
    }
  }
  const Vec3 &a = v[s.v[0]], &b = v[s.v[1]], &c = v[s.v[2]];
  const Vec3 &d = v[t.v[0]], &e = v[t.v[1]], &f = v[t.v[2]];
  if (shared == 0) {
    const Vec3 tv[3] = {d, e, f}, sv[3] = {a, b, c};
    const Spread t_vs_s = spread(ps, tv, 3);
    if (t_vs_s == kSeparated) return false;
    if (t_vs_s == kCoplanar) return coplanar_triangles_intersect(a, b, c, d, e, f);
    if (spread(pt, sv, 3) == kSeparated) return false;
    return triangles_intersect(a, b, c, d, e, f);
  }
  if (shared >= 3) return true;  // the same three vertices twice
  if (shared == 2) {
    int s_free = s_at[0] < 0 ? 0 : (s_at[1] < 0 ? 1 : 2);
    int t_free = 3 - s_at[(s_free + 1) % 3] - s_at[(s_free + 2) % 3];
    const Vec3& p = v[s.v[(s_free + 1) % 3]];
    const Vec3& q = v[s.v[(s_free + 2) % 3]];
    const Vec3& sc = v[s.v[s_free]];
    const Vec3& tc = v[t.v[t_free]];
    const Side side = side_of(ps, tc);
    // Not coplanar: the shared edge is all they share.
    if (side == kAbove || side == kBelow) return false;
    if (side == kUnknown && orient3d(p, q, sc, tc) != 0.0) return false;
    return folded_onto(p, q, sc, tc);
  }
  // One shared vertex: they conflict iff the edge of either opposite it meets the other.
  int si = s_at[0] >= 0 ? 0 : (s_at[1] >= 0 ? 1 : 2);
  int ti = s_at[si];
  const Vec3& s1 = v[s.v[(si + 1) % 3]];
  const Vec3& s2 = v[s.v[(si + 2) % 3]];
  const Vec3& t1 = v[t.v[(ti + 1) % 3]];
  const Vec3& t2 = v[t.v[(ti + 2) % 3]];
  return edge_meets(pt, s1, s2, d, e, f) || edge_meets(ps, t1, t2, a, b, c);
}

}  // namespace

uint64_t find_self_intersections_bound(uint64_t triangle_count) {
  return triangle_count * (2 * sizeof(Box) + 8 + sizeof(Plane) + 2 * sizeof(KeyIndex) + 1) +
         6 * 64;
}

Status find_self_intersections(const Context& ctx, const Mesh& mesh, uint64_t max_pairs,
                               SelfIntersectionReport* report) {
  Arena& arena = *ctx.arena;
  ArenaScope scope(arena);
  *report = SelfIntersectionReport{};
  const size_t nt = mesh.triangles.size();
  const size_t nv = mesh.vertices.size();
  if (nt > UINT32_MAX) {
    return make_error(StatusCode::kLimitExceeded, "mesh too large: ", nt, " triangles");
  }
  const Vec3* v = mesh.vertices.data();
  const Triangle* tris = mesh.triangles.data();
  Box* boxes = arena.allocate_array<Box>(nt);
  KeyIndex* order = arena.allocate_array<KeyIndex>(nt);
  KeyIndex* scratch = arena.allocate_array<KeyIndex>(nt);
  uint8_t* skip = arena.allocate_array<uint8_t>(nt);
  Plane* planes = arena.allocate_array<Plane>(nt);
  if ((boxes == nullptr || order == nullptr || scratch == nullptr || skip == nullptr ||
       planes == nullptr) && nt > 0) {
    return arena.exhausted_status();
  }
  for (size_t t = 0; t < nt; ++t) {
    const Triangle& tri = tris[t];
    if (tri.v[0] >= nv || tri.v[1] >= nv || tri.v[2] >= nv) {
      return make_error(StatusCode::kInvalidMesh, "triangle ", t,
                        " refers to a vertex that does not exist")
          .at_index(t);
    }
    Box& b = boxes[t];
    for (int a = 0; a < 3; ++a) {
      double x0 = v[tri.v[0]][a], x1 = v[tri.v[1]][a], x2 = v[tri.v[2]][a];
      double lo = x0 < x1 ? x0 : x1, hi = x0 > x1 ? x0 : x1;
      b.lo[a] = lo < x2 ? lo : x2;
      b.hi[a] = hi > x2 ? hi : x2;
    }
    skip[t] = tri.v[0] == tri.v[1] || tri.v[1] == tri.v[2] || tri.v[0] == tri.v[2] ||
              collinear3d(v[tri.v[0]], v[tri.v[1]], v[tri.v[2]]);
    planes[t] = plane_of(v[tri.v[0]], v[tri.v[1]], v[tri.v[2]]);
    order[t] = KeyIndex{order_key(b.lo[0]), static_cast<uint32_t>(t), 0};
  }
  radix_sort(Span<KeyIndex>(order, nt), Span<KeyIndex>(scratch, nt));

  // Boxes in sweep order, contiguous: the inner loop below runs over many pairs whose x
  // ranges overlap but y or z do not, and must stream through memory.
  struct SweepBox {
    double lo[3];
    double hi[3];
    uint32_t triangle;
    uint32_t skip;
  };
  SweepBox* sweep = arena.allocate_array<SweepBox>(nt);
  if (sweep == nullptr && nt > 0) return arena.exhausted_status();
  for (size_t i = 0; i < nt; ++i) {
    const uint32_t t = order[i].index;
    SweepBox& b = sweep[i];
    for (int a = 0; a < 3; ++a) {
      b.lo[a] = boxes[t].lo[a];
      b.hi[a] = boxes[t].hi[a];
    }
    b.triangle = t;
    b.skip = skip[t];
  }

  bool have_first = false;
  for (size_t i = 0; i < nt; ++i) {
    if ((i & 0xfff) == 0) SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "self-intersection", i, nt));
    const SweepBox& bs = sweep[i];
    if (bs.skip) continue;
    const uint32_t s = bs.triangle;
    for (size_t j = i + 1; j < nt; ++j) {
      const SweepBox& bt = sweep[j];
      if (bt.lo[0] > bs.hi[0]) break;
      if (bt.lo[1] > bs.hi[1] || bt.hi[1] < bs.lo[1] || bt.lo[2] > bs.hi[2] || bt.hi[2] < bs.lo[2] ||
          bt.skip) {
        continue;
      }
      const uint32_t t = bt.triangle;
      ++report->candidate_pairs;
      if (!conflict(v, tris[s], tris[t], planes[s], planes[t])) continue;
      ++report->intersecting_pairs;
      uint32_t a = s < t ? s : t, b = s < t ? t : s;
      if (!have_first || a < report->first_a || (a == report->first_a && b < report->first_b)) {
        report->first_a = a;
        report->first_b = b;
        have_first = true;
      }
      if (max_pairs != 0 && report->intersecting_pairs >= max_pairs) return Status::ok();
    }
  }
  return Status::ok();
}

}  // namespace splintcore
