// Closest points for a large batch, triangle by triangle: the closest point transform of
// Mauch ("A fast algorithm for computing the closest point and distance transform", Caltech
// ACM technical report 2000-077), taken from grid samples to scattered points. The queries
// are bucketed in a grid; each face, edge and vertex of the mesh scans the buckets its
// Voronoi region covers (within the band B of the batch) and offers its triangles to the
// queries inside. A query's closest point lies on a feature whose region holds it, so each
// query meets its answer among a few candidates, where a tree search has to visit every box
// about as close as the answer: near a finely tessellated surface, dozens of them.
//
// Regions, from the first-order conditions a closest point p of the mesh satisfies (no
// triangle at p offers a shorter way to q):
// - face t: q - p is along t's normal: the prism over t, |height| <= B;
// - edge ab of triangles t, t2: q - p is orthogonal to ab and points away from both
//   triangles' insides (each triangle's inward edge normal m has m . (q - a) <= 0);
// - vertex v: q - v makes an obtuse angle with every edge at v.
// Each region is widened by a margin mu on every side, so that a triangle only a rounding
// error farther than the answer (which the tree search could pick on a tie of computed
// distances) has the query inside one of its regions too. A point of a triangle's edge that
// violates a neighbour's condition by more than mu is not a near tie: within mu^2 / 2B of a
// vertex the vertex's region holds the query; farther, stepping into the neighbour (whose
// angles all exceed 2^-10 rad) gains at least mu^3 2^-10 / 2B in squared distance, which
// mu^3 >= B^2 (scale + B) 2^-32 puts above 2B times 2^-44 (scale + B), far more than the
// rounding of a computed distance (about 2^-50 of the scale). Thinner triangles take a capsule
// instead of regions: every query within B of their box tries them. So the answer, the
// smallest computed squared distance with the smallest triangle id among equals, is the
// tree's, bit for bit (tests compare them on every query).
//
// B comes from a sample of the batch (the tree's distances for 256 queries); a query whose
// best candidate lies beyond B is answered by the tree. Used when the batch has at least
// 4096 queries and half as many as the mesh has triangles, a query meets at most about 4
// face regions (estimated: 2 B times the mesh's area over the volume the queries fill), and
// the arena holds the buckets (about 65 bytes a query, with the best candidate's point, and 4
// a triangle); otherwise the tree answers all (query.cpp).
//
// Cost: the pass over the triangles (regions and their bounds, about 3k instructions a
// triangle) and the scan (each triangle tests the queries of the cells its bounds cover, two
// at a time, about 23 instructions each, and the few inside its regions exactly; the two
// halves of a planar quad share one scan, partner()); the queries' own share is their
// bucketing and one or two exact point-triangle distances (the winner's point is kept, not
// computed again).
#include <cmath>
#include <cstring>
#include <new>
#include <type_traits>

#include "core/fminmax.h"
#include "distance/query_internal.h"

namespace splintcore {
namespace {

using detail::closest_within;
using detail::RegionAnswer;
using detail::settle_closest;

constexpr uint32_t kMaxPlanes = 24;    // a vertex with more neighbours keeps the first ones
constexpr size_t kMinQueries = 4096;   // smaller batches: the tree
constexpr uint32_t kSample = 256;      // queries whose tree distances set the band
constexpr uint32_t kRound = 1u << 15;  // triangles between progress reports
constexpr double kMaxOverlap = 4;      // face regions about a query, at most (estimated)
constexpr double kPairCos = 0.9999;    // neighbours scanned together: normals within 0.8 deg
// The progress stage (the tree's batches report "closest points" or "signed distances").
constexpr const char* kStage = "closest points, by regions";

// The region lies in dot(n, x) <= off. Each value is held twice, as the two lanes that
// offer_list() tests two queries with (broadcast once here, not for every pair of queries).
struct Plane {
  Lanes2 nx{}, ny{}, nz{}, off{};
  Plane() = default;
  Plane(const Vec3& n, double o) : nx{n.x, n.x}, ny{n.y, n.y}, nz{n.z, n.z}, off{o, o} {}
  Vec3 normal() const { return Vec3{nx[0], ny[0], nz[0]}; }
};

// A face, edge or vertex region: its planes, and the triangles it offers (a vertex region
// offers every triangle at `vertex`).
struct Region {
  Plane planes[kMaxPlanes];
  uint32_t count = 0;
  uint32_t candidates[2] = {0, 0};
  uint32_t candidate_count = 0;
  uint32_t vertex = kNoNeighbor;
  bool face = false;  // a prism over the triangle (its planes are the prism's sides)
  Vec3 n{};           // a face's unit normal: a query q lies n . q - h0 above the triangle
  double h0 = 0;
};

// A triangle's unit normal and unit inward edge normals (m[k] for edge k, v[k] -> v[k+1]);
// ok is false for a triangle with an angle whose sine is under 2^-10 (or degenerate).
struct Frame {
  Vec3 n{};
  Vec3 m[3]{};
  bool ok = false;
};

// The unnormalised normal of triangle p, and whether all its angles' sines exceed 2^-10.
inline bool well_shaped(const Vec3 p[3], Vec3* n, double* n2) {
  const Vec3 ab = p[1] - p[0], ac = p[2] - p[0], bc = p[2] - p[1];
  *n = cross(ab, ac);
  *n2 = dot(*n, *n);
  const double lab = dot(ab, ab), lac = dot(ac, ac), lbc = dot(bc, bc);
  // |n| = |ab| |ac| sin A = |ab| |bc| sin B = |ac| |bc| sin C.
  return *n2 > max3_of(lab * lac, lab * lbc, lac * lbc) * 0x1p-20;
}

// (Built from its values in one expression: a Frame zeroed first and then filled costs a
// string store, about a tenth of build_regions' time.)
Frame frame_of(const Vec3 p[3]) {
  Vec3 n;
  double n2 = 0;
  if (!well_shaped(p, &n, &n2)) return Frame{};
  const Vec3 unit = n * (1.0 / std::sqrt(n2));
  const auto inward = [&](int k) {
    const Vec3 m = cross(unit, p[(k + 1) % 3] - p[k]);
    return m * (1.0 / length(m));
  };
  return Frame{unit, {inward(0), inward(1), inward(2)}, true};
}

// The triangle scanned together with t: the neighbour across t's longest edge when that edge
// is the neighbour's longest too and the two lie in about the same plane (normals within 0.8
// degrees, kPairCos), as the two halves of a planar quad; else kNoNeighbor. Symmetric (each
// product's operands commute), so each of the two finds the other.
uint32_t partner(const Mesh& mesh, const uint32_t* neighbors, uint32_t t) {
  const Vec3* v = mesh.vertices.data();
  Vec3 p[2][3];
  const auto longest = [&](uint32_t u, Vec3 c[3]) -> uint32_t {
    const Triangle& tri = mesh.triangles[u];
    for (int k = 0; k < 3; ++k) c[k] = v[tri.v[k]];
    const double l0 = length_squared(c[1] - c[0]), l1 = length_squared(c[2] - c[1]);
    const double l2 = length_squared(c[0] - c[2]);
    return l1 > l0 ? (l2 > l1 ? 2u : 1u) : (l2 > l0 ? 2u : 0u);
  };
  const uint32_t t2 = neighbors[3 * size_t{t} + longest(t, p[0])];
  if (t2 == kNoNeighbor || t2 == t || neighbors[3 * size_t{t2} + longest(t2, p[1])] != t)
    return kNoNeighbor;
  Vec3 n1, n2;
  double s1 = 0, s2 = 0;
  if (!well_shaped(p[0], &n1, &s1) || !well_shaped(p[1], &n2, &s2)) return kNoNeighbor;
  const double d = dot(n1, n2);
  return d > 0 && d * d > (kPairCos * kPairCos) * (s1 * s2) ? t2 : kNoNeighbor;
}

// A convex polygon in the 2D coordinates of a plane, clipped by half-planes
// cx x + cy y <= rhs (Sutherland-Hodgman: a new corner where an edge crosses the line, on
// that edge). Each clip adds at most one corner; should rounding make it more than the room
// left, the clip is skipped (the polygon stays a superset, which is all a bound needs).
struct Polygon {
  static constexpr uint32_t kCapacity = kMaxPlanes + 4;
  double xs[2][kCapacity];  // the corners in xs[at], ys[at]; the clip writes the other pair
  double ys[2][kCapacity];
  uint32_t at = 0;
  uint32_t n = 0;

  const double* x() const { return xs[at]; }
  const double* y() const { return ys[at]; }
  void square(double r) {
    double* x = xs[at];
    double* y = ys[at];
    x[0] = -r, y[0] = -r;
    x[1] = r, y[1] = -r;
    x[2] = r, y[2] = r;
    x[3] = -r, y[3] = r;
    n = 4;
  }
  void clip(double cx, double cy, double rhs) {
    const double* x = xs[at];
    const double* y = ys[at];
    double side[kCapacity];
    bool cut = false;
    for (uint32_t j = 0; j < n; ++j) {
      side[j] = cx * x[j] + cy * y[j] - rhs;
      cut |= side[j] > 0;
    }
    if (!cut) return;
    double* kx = xs[at ^ 1];
    double* ky = ys[at ^ 1];
    uint32_t k = 0;
    for (uint32_t j = 0; j < n; ++j) {
      if (k + 2 > kCapacity) return;
      const uint32_t jn = j + 1 < n ? j + 1 : 0;
      const double s0 = side[j], s1 = side[jn];
      if (s0 <= 0) {
        kx[k] = x[j];
        ky[k++] = y[j];
      }
      if ((s0 < 0 && s1 > 0) || (s0 > 0 && s1 < 0)) {
        const double c = s0 / (s0 - s1);
        kx[k] = x[j] + (x[jn] - x[j]) * c;
        ky[k++] = y[j] + (y[jn] - y[j]) * c;
      }
    }
    n = k;
    at ^= 1;
  }
};

// The queries in buckets: cell (x, y, z) of side h from lo holds points j in [start[c],
// start[c + 1]) with c = x + dims[0] (y + dims[1] z); point j is at (coord[0][j], coord[1][j],
// coord[2][j]), and ids[j] is its index in the batch. Its best candidate so far is triangle
// best[j] (kNoNeighbor: none yet), whose closest point is best_point[j] (feature and index:
// best_feature[j], Feature << 2 | index): finishing it computes nothing again, and its squared
// distance is length_squared(best_point[j] - q), the bits offer() compared. The axis arrays
// and the best ones have one element more than there are points (a point at zero, answered
// by no one): the scan tests two queries at a time and keeps the second of a row's last pair
// when it is inside, whether it is the next cell's query or that one (a triangle offered to a
// query whose regions do not hold it changes nothing: the answer is the best of what it is
// offered).
struct Buckets {
  Vec3 lo{};
  double h = 1;
  double inv_h = 1;  // 1 / h
  uint32_t dims[3] = {1, 1, 1};
  uint32_t* start = nullptr;
  double* coord[3] = {nullptr, nullptr, nullptr};
  uint32_t* ids = nullptr;
  Vec3* best_point = nullptr;
  uint8_t* best_feature = nullptr;
  uint32_t* best = nullptr;

  Vec3 point(size_t j) const { return Vec3{coord[0][j], coord[1][j], coord[2][j]}; }
  // The cell index along `axis` of coordinate x, clamped to the grid (a conversion, not
  // floor(), which is a library call without SSE4.1: the same for the non-negative values
  // it converts).
  uint32_t cell_along(double x, int axis) const {
    const double c = (x - lo[axis]) * inv_h;
    if (!(c >= 1)) return 0;
    return c >= dims[axis] - 1.0 ? dims[axis] - 1 : static_cast<uint32_t>(c);
  }
  size_t cell_of(const Vec3& q) const {
    return cell_along(q.x, 0) +
           size_t{dims[0]} * (cell_along(q.y, 1) + size_t{dims[1]} * cell_along(q.z, 2));
  }
};

inline bool usable(const Vec3& q) {
  return std::fabs(q.x) <= 0x1p40 && std::fabs(q.y) <= 0x1p40 && std::fabs(q.z) <= 0x1p40;
}

// A box in coordinates sheared along a scan direction dir: the scan walks cells along ax,
// the dominant axis of dir, and the coordinates are x[u] - x[ax] ru, x[w] - x[ax] rw, x[ax]
// (ru = dir[u] / dir[ax], rw = dir[w] / dir[ax]), as dot products (no indexing in the loops).
// Near a surface with normal dir, the box of a thin slab along it is as thin as the slab.
struct ShearedBox {
  int ax = 2, u = 0, w = 1;
  double ru = 0, rw = 0;
  Vec3 cu{}, cw{}, cz{};
  Aabb bounds;  // in the sheared coordinates: x along u, y along w, z along ax
  Aabb reach;   // an axis-aligned box that holds everything the box must hold (it clips it)

  Vec3 sheared(const Vec3& p) const { return Vec3{dot(cu, p), dot(cw, p), dot(cz, p)}; }
  // Empty, along dir (not zero).
  void start(const Vec3& dir) {
    ax = 0;
    for (int k = 1; k < 3; ++k) ax = std::fabs(dir[k]) > std::fabs(dir[ax]) ? k : ax;
    u = (ax + 1) % 3;
    w = (ax + 2) % 3;
    ru = dir[u] / dir[ax];
    rw = dir[w] / dir[ax];
    cu = Vec3{};
    cu[u] = 1;
    cu[ax] = -ru;
    cw = Vec3{};
    cw[w] = 1;
    cw[ax] = -rw;
    cz = Vec3{};
    cz[ax] = 1;
    bounds = Aabb{};
    reach = Aabb{};
  }
  void add_point(const Vec3& p) { bounds.add(sheared(p)); }
  // Adds segment ab swept by the offsets offset(0) .. offset(n - 1): the box of a sum is the
  // sum of the boxes (half the products of adding both ends of every offset).
  template <typename Offset>
  void add_swept(const Vec3& a, const Vec3& b, uint32_t n, Offset&& offset) {
    if (n == 0) return;
    Aabb sweep;
    for (uint32_t i = 0; i < n; ++i) sweep.add(sheared(offset(i)));
    add_swept_box(a, b, sweep);
  }
  // The same, given the box of the sheared offsets (the map is linear: a caller whose offsets
  // combine a few vectors shears those once).
  void add_swept_box(const Vec3& a, const Vec3& b, const Aabb& sweep) {
    const Vec3 pa = sheared(a), pb = sheared(b);
    bounds.add(sweep.lo + min_vec(pa, pb));
    bounds.add(sweep.hi + max_vec(pa, pb));
  }
  // Grown by m on every side (for the rounding of the points added), along ax within reach.
  void grow(double m) {
    bounds.lo.x -= m;
    bounds.hi.x += m;
    bounds.lo.y -= m;
    bounds.hi.y += m;
    bounds.lo.z = (bounds.lo.z - m > reach.lo[ax]) ? bounds.lo.z - m : reach.lo[ax];
    bounds.hi.z = (bounds.hi.z + m < reach.hi[ax]) ? bounds.hi.z + m : reach.hi[ax];
  }
};

// The regions of one triangle, or of two scanned together (those a triangle owns: its face,
// its edges unless the neighbour across has a smaller id, and each vertex whose first corner is
// its), and the bounds of their union for the scan, sheared along the scan direction.
struct TriangleRegions {
  Region regions[14];
  uint32_t count = 0;
  ShearedBox box;

  Region& take() {
    Region& g = regions[count++];
    g.count = 0;
    g.candidate_count = 0;
    g.vertex = kNoNeighbor;
    g.face = false;
    return g;
  }
};

struct Scan {
  const DistanceIndex* index = nullptr;
  Buckets* buckets = nullptr;
  double band = 0;   // B
  double reach = 0;  // R = B + mu
  double mu = 0;
  double slack = 0;  // over the rounding of a computed height or distance
};

// The face region of triangle t (corners p, frame f) into tr, and its bounds into tr.box:
// the prism, or for a thin triangle the box `reach` (within R of it).
void add_face_region(const Scan& s, uint32_t t, const Vec3 p[3], const Frame& f, const Aabb& reach,
                     TriangleRegions* tr) {
  const double mu = s.mu, r = s.reach;
  Region& g = tr->take();
  g.candidates[g.candidate_count++] = t;
  if (f.ok) {
    for (int k = 0; k < 3; ++k) g.planes[g.count++] = Plane{f.m[k] * -1.0, mu - dot(f.m[k], p[k])};
    // Its height is not tested with the planes: the bounds hold it within about R (and a
    // query above R is not offered the triangle once it has a closer one, offer_regions).
    g.face = true;
    g.n = f.n;
    g.h0 = dot(f.n, p[0]);
    tr->box.add_swept(f.n * -r, f.n * r, 3, [&](uint32_t i) { return p[i]; });
    return;
  }
  for (int a = 0; a < 3; ++a) {
    Vec3 e{};
    e[a] = 1;
    g.planes[g.count++] = Plane{e, reach.hi[a]};
    g.planes[g.count++] = Plane{e * -1.0, -reach.lo[a]};
  }
  for (uint32_t i = 0; i < 8; ++i) {
    tr->box.add_point(Vec3{(i & 1) ? reach.hi.x : reach.lo.x, (i & 2) ? reach.hi.y : reach.lo.y,
                           (i & 4) ? reach.hi.z : reach.lo.z});
  }
}

// The edge regions triangle t owns (those whose neighbour across has no smaller id) into tr,
// and their bounds into tr.box.
void add_edge_regions(const Scan& s, uint32_t t, const Vec3 p[3], const Frame& f,
                      TriangleRegions* tr) {
  const Mesh& mesh = *s.index->mesh;
  const Vec3* v = mesh.vertices.data();
  const double mu = s.mu, r = s.reach;
  ShearedBox& sb = tr->box;
  const uint32_t* neighbors = s.index->neighbors.data();
  for (int k = 0; k < 3; ++k) {
    uint32_t t2 = neighbors[3 * size_t{t} + static_cast<size_t>(k)];
    if (t2 == t) t2 = kNoNeighbor;
    if (t2 != kNoNeighbor && t2 < t) continue;
    const Vec3 &a = p[k], &b = p[(k + 1) % 3];
    const double len = length(b - a);
    if (!(len > 0)) continue;  // its points are its vertex's
    const Vec3 e = (b - a) * (1.0 / len);
    Region& g = tr->take();
    g.candidates[g.candidate_count++] = t;
    g.planes[g.count++] = Plane{e * -1.0, mu - dot(e, a)};
    g.planes[g.count++] = Plane{e, dot(e, a) + len + mu};
    Vec3 sides[2];
    int side_count = 0;
    if (f.ok) sides[side_count++] = f.m[k];
    if (t2 != kNoNeighbor) {
      g.candidates[g.candidate_count++] = t2;
      const Triangle& tri2 = mesh.triangles[t2];
      const Vec3 p2[3] = {v[tri2.v[0]], v[tri2.v[1]], v[tri2.v[2]]};
      // The neighbour's inward normal of this edge (it runs b -> a there): n2 x (a - b) / len,
      // as frame_of() would give it.
      Vec3 n2;
      double n22 = 0;
      if (well_shaped(p2, &n2, &n22)) {
        const Vec3 m2 = cross(n2 * (1.0 / std::sqrt(n22)), a - b);
        sides[side_count++] = m2 * (1.0 / length(m2));
      }
    }
    for (int i = 0; i < side_count; ++i)
      g.planes[g.count++] = Plane{sides[i], dot(sides[i], a) + mu};
    // Its bounds (a thin triangle's face bounds already hold everything within R of it). A
    // query that matters is a + s e + y, s in [-mu, len + mu], y across the edge with |y| <= R,
    // so y = alpha n + beta o (o = -m, outward) with |alpha|, |beta| <= R. This triangle's side
    // (m . y <= mu) gives beta >= -mu; the neighbour's, m2 = c o + d n with c > 0, gives
    // beta c <= mu - alpha d <= mu + R |d|. The rectangle of those alpha and beta, swept
    // along the edge, holds the region's points within R (about as tight as the sector
    // itself: across the edge only beta's range counts, and it is the sector's).
    if (f.ok) {
      const Vec3 o = f.m[k] * -1.0;
      double beta = r;
      if (side_count == 2) {
        const double c = dot(sides[1], o), d = std::fabs(dot(sides[1], f.n));
        if (c > 0 && mu + r * d < r * c) beta = (mu + r * d) / c;
      }
      // The offsets +-R n + (beta or -mu) o, sheared: each axis's range from sn and so.
      const Vec3 sn = sb.sheared(f.n), so = sb.sheared(o);
      Aabb sweep;
      for (int i = 0; i < 3; ++i) {
        const double along_n = std::fabs(sn[i]) * r, beyond = so[i] * beta, inside = so[i] * -mu;
        sweep.lo[i] = (beyond < inside ? beyond : inside) - along_n;
        sweep.hi[i] = (beyond > inside ? beyond : inside) + along_n;
      }
      sb.add_swept_box(a - e * mu, b + e * mu, sweep);
    }
  }
}

// The vertex regions triangle t owns (each vertex whose first corner is its; about one
// triangle in two owns one) into tr, and their bounds, swept along dir, into tr.box.
void add_vertex_regions(const Scan& s, uint32_t t, const Vec3& dir, TriangleRegions* tr) {
  const Mesh& mesh = *s.index->mesh;
  const Vec3* v = mesh.vertices.data();
  const Triangle& tri = mesh.triangles[t];
  const double mu = s.mu, r = s.reach;
  ShearedBox& sb = tr->box;
  const uint32_t* vstart = s.index->vertex_start.data();
  const uint32_t* vuses = s.index->vertex_uses.data();
  Vec3 across[2];  // two unit vectors across dir, for the bounds; set by the first vertex
  Vec3 sheared_across[2];
  bool have_across = false;
  for (int k = 0; k < 3; ++k) {
    const uint32_t vi = tri.v[k];
    if (vuses[vstart[vi]] / 3 != t) continue;
    if (!have_across) {
      int least = 0;
      for (int a = 1; a < 3; ++a) least = std::fabs(dir[a]) < std::fabs(dir[least]) ? a : least;
      Vec3 axis{};
      axis[least] = 1;
      const Vec3 a1 = cross(dir, axis);
      across[0] = a1 * (1.0 / length(a1));
      across[1] = cross(dir, across[0]);
      sheared_across[0] = sb.sheared(across[0]);
      sheared_across[1] = sb.sheared(across[1]);
      have_across = true;
    }
    Region& g = tr->take();
    g.vertex = vi;
    const Vec3& c = v[vi];
    uint32_t seen[kMaxPlanes];
    uint32_t seen_count = 0;
    const auto add = [&](uint32_t wi, bool search) {
      for (uint32_t i = 0; search && i < seen_count; ++i) {
        if (seen[i] == wi) return;
      }
      if (seen_count == kMaxPlanes) return;
      seen[seen_count++] = wi;
      const Vec3 d = v[wi] - c;
      const double len = length(d);
      if (!(len > 0)) return;
      const Vec3 e = d * (1.0 / len);
      g.planes[g.count++] = Plane{e, dot(e, c) + mu};
    };
    // On a closed manifold each neighbour w follows v in exactly one triangle of the fan (the
    // edge's use v -> w); elsewhere every neighbour, once.
    for (uint32_t j = vstart[vi]; j < vstart[vi + 1]; ++j) {
      const Triangle& other = mesh.triangles[vuses[j] / 3];
      const uint32_t corner = vuses[j] % 3;
      add(other.v[(corner + 1) % 3], !s.index->closed_manifold);
      if (!s.index->closed_manifold) add(other.v[(corner + 2) % 3], true);
    }
    // Its bounds. Only its points within R of v matter (a query farther than that from v
    // has the vertex beyond the band). Such a point x = v + h a + s a1 + t a2 (a the scan
    // direction, a1 and a2 across it; |h|, |s|, |t| <= R) meets each plane e . (x - v) <= mu
    // only if s e.a1 + t e.a2 <= mu + R |e.a|: the square of side 2R clipped by those lines,
    // swept along a from -R to R, holds them all. At a convex vertex (every e.a <= 0) the
    // clipped square is the region's own section at h = R, which holds every lower one, so
    // the bound is about as tight as the region's box; elsewhere the lines move out by at
    // most R times the edges' tilt out of the triangle's plane.
    Polygon poly;
    poly.square(r);
    for (uint32_t i = 0; i < g.count; ++i) {
      const Vec3 e = g.planes[i].normal();
      poly.clip(dot(e, across[0]), dot(e, across[1]), mu + r * std::fabs(dot(e, dir)));
    }
    Aabb sweep;  // of the corners across[0] x + across[1] y, sheared
    for (uint32_t j = 0; j < poly.n; ++j)
      sweep.add(sheared_across[0] * poly.x()[j] + sheared_across[1] * poly.y()[j]);
    if (poly.n != 0) sb.add_swept_box(c - dir * r, c + dir * r, sweep);
  }
}

// Adds triangle t's regions (corners p, frame f) to out, and their bounds to out->box, started
// along the scan direction dir (a unit vector; its normal, or about it).
void add_regions(const Scan& s, uint32_t t, const Vec3 p[3], const Frame& f, const Vec3& dir,
                 TriangleRegions* out) {
  const double mu = s.mu, r = s.reach;
  Aabb reach;  // this triangle's
  for (int k = 0; k < 3; ++k) reach.add(p[k]);
  reach.lo = reach.lo - Vec3{r + mu, r + mu, r + mu};
  reach.hi = reach.hi + Vec3{r + mu, r + mu, r + mu};
  out->box.reach.add(reach);
  add_face_region(s, t, p, f, reach, out);
  add_edge_regions(s, t, p, f, out);
  add_vertex_regions(s, t, dir, out);
}

// The squared distance of query j (at q) to its best candidate so far (none: infinity).
inline double best_distance2(const Buckets& b, size_t j, const Vec3& q) {
  return b.best[j] == kNoNeighbor ? HUGE_VAL : length_squared(b.best_point[j] - q);
}

// Offers triangle t to query j (at q, best so far at squared distance *best2).
inline void offer(const Mesh& mesh, const Buckets& b, uint32_t t, const Vec3& q, size_t j,
                  double* best2) {
  const Vec3* v = mesh.vertices.data();
  const Triangle& tri = mesh.triangles[t];
  Feature feature;
  uint8_t index;
  const Vec3 p =
      closest_point_on_triangle(q, v[tri.v[0]], v[tri.v[1]], v[tri.v[2]], &feature, &index);
  const double d2 = length_squared(p - q);
  if (d2 < *best2 || (d2 == *best2 && t < b.best[j])) {
    *best2 = d2;
    b.best[j] = t;
    b.best_point[j] = p;
    b.best_feature[j] = static_cast<uint8_t>(static_cast<uint8_t>(feature) << 2 | index);
  }
}

// Offers query j (at q) the triangles of tr's regions in `holding` (bit i: region i).
// A triangle already offered to the query here, or whose plane already lay beyond its best,
// is not offered again (the face region and, within the margin, an edge region of the same
// triangles often both hold it; a second offer changes nothing, and the best only shrinks).
void offer_regions(const Scan& s, const TriangleRegions& tr, uint32_t holding, const Vec3& q,
                   uint32_t j) {
  const Buckets& b = *s.buckets;
  const Mesh& mesh = *s.index->mesh;
  uint32_t offered[4];
  uint32_t offered_count = 0;
  double best2 = best_distance2(b, j, q);
  for (uint32_t i = 0; holding != 0; ++i, holding >>= 1) {
    if ((holding & 1) == 0) continue;
    const Region& g = tr.regions[i];
    if (g.face) {
      // Its plane already lies farther than the best so far: it cannot win or tie.
      const double h = std::fabs(dot(g.n, q) - g.h0) - s.slack;
      if (h > 0 && h * h > best2 + best2 * 0x1p-30) {
        if (offered_count < 4) offered[offered_count++] = g.candidates[0];
        continue;
      }
    }
    if (g.vertex == kNoNeighbor) {
      for (uint32_t k = 0; k < g.candidate_count; ++k) {
        const uint32_t t = g.candidates[k];
        bool seen = false;
        for (uint32_t m = 0; m < offered_count; ++m) seen |= offered[m] == t;
        if (seen) continue;
        if (offered_count < 4) offered[offered_count++] = t;
        offer(mesh, b, t, q, j, &best2);
      }
    } else {
      const uint32_t* vstart = s.index->vertex_start.data();
      const uint32_t* vuses = s.index->vertex_uses.data();
      for (uint32_t k = vstart[g.vertex]; k < vstart[g.vertex + 1]; ++k) {
        offer(mesh, b, vuses[k] / 3, q, j, &best2);
      }
    }
  }
}

// Offers the queries at[0 .. count) (bucket indices) the triangles of tr's regions that hold
// them. Two queries at a time: each plane's dot product in two lanes, with dot()'s operations
// in the same order (the same decisions, bit for bit), and every plane tested (whether a query
// is inside is hard to predict: a mispredicted branch costs more than the products it would
// save); then the offers, query by query, region by region as before.
void offer_list(const Scan& s, const TriangleRegions& tr, const uint32_t* at, uint32_t count) {
  const Buckets& b = *s.buckets;
  const double* const cx = b.coord[0];
  const double* const cy = b.coord[1];
  const double* const cz = b.coord[2];
  for (uint32_t k = 0; k < count; k += 2) {
    const uint32_t j0 = at[k], j1 = k + 1 < count ? at[k + 1] : j0;
    const Lanes2 x = {cx[j0], cx[j1]}, y = {cy[j0], cy[j1]}, z = {cz[j0], cz[j1]};
    uint32_t in0 = 0, in1 = 0;
    for (uint32_t i = 0; i < tr.count; ++i) {
      const Region& g = tr.regions[i];
      Mask2 in = ~Mask2{};
      for (uint32_t p = 0; p < g.count; ++p) {
        const Plane& h = g.planes[p];
        in &= h.nx * x + h.ny * y + h.nz * z <= h.off;
      }
      in0 |= static_cast<uint32_t>(in[0] & 1) << i;
      in1 |= static_cast<uint32_t>(in[1] & 1) << i;
    }
    if (in0 != 0) offer_regions(s, tr, in0, Vec3{x[0], y[0], z[0]}, j0);
    if (in1 != 0 && k + 1 < count) offer_regions(s, tr, in1, Vec3{x[1], y[1], z[1]}, j1);
  }
}

inline Lanes2 load2(const double* p) {
  Lanes2 r;
  std::memcpy(&r, p, sizeof(r));
  return r;
}

// Calls visit(list, count) with the queries j in box, among cells [cell_lo[a], cell_hi[a]]
// along each axis a (a task's share): layer by layer along box.ax, each layer's cells by rows
// along x (a row's queries are one run of the buckets). Two queries at a time: their sheared
// coordinates from the axes (two products, where dot products take nine) and the box's
// comparisons in two lanes; those inside go to the list without a branch (about one query in
// ten passes a triangle's box, unpredictably).
template <typename Visit>
void walk(const Scan& s, const ShearedBox& box, const uint32_t cell_lo[3],
          const uint32_t cell_hi[3], Visit&& visit) {
  const Buckets& b = *s.buckets;
  const int ax = box.ax, u = box.u, w = box.w;
  const size_t stride[3] = {1, b.dims[0], static_cast<size_t>(b.dims[0]) * b.dims[1]};
  // The test's values in locals: visit() writes through pointers the compiler cannot tell
  // from the box's, and would have them loaded again.
  const double* const along_u = b.coord[u];
  const double* const along_w = b.coord[w];
  const double* const along_z = b.coord[ax];
  const Lanes2 ru = {box.ru, box.ru}, rw = {box.rw, box.rw};
  const Vec3 &blo = box.bounds.lo, &bhi = box.bounds.hi;
  const Lanes2 u0 = {blo.x, blo.x}, u1 = {bhi.x, bhi.x}, w0 = {blo.y, blo.y}, w1 = {bhi.y, bhi.y};
  const Lanes2 z0 = {blo.z, blo.z}, z1 = {bhi.z, bhi.z};
  const uint32_t* const start = b.start;
  constexpr uint32_t kHits = 256;
  uint32_t hits[kHits];
  uint32_t hit_count = 0;
  const auto flush = [&]() {
    visit(hits, hit_count);
    hit_count = 0;
  };
  uint32_t c0 = b.cell_along(blo.z, ax), c1 = b.cell_along(bhi.z, ax);
  c0 = c0 > cell_lo[ax] ? c0 : cell_lo[ax];
  c1 = c1 < cell_hi[ax] ? c1 : cell_hi[ax];
  // The layers' cells in cell units from the grid's corner (U = (x[u] - lo[u]) / h, and W, Z
  // likewise), computed once: a point of the box has U - ru Z within [ulo, uhi], W - rw Z
  // within [wlo, whi], Z within [zlo, zhi], and U, W within the reach. The margins m (mu in
  // cells) cover the rounding of these values and of a query's cell index (about 2^-40 cells).
  const double inv_h = b.inv_h, m = s.mu * inv_h;
  const double lo_u = b.lo[u], lo_w = b.lo[w], lo_z = b.lo[ax];
  const double ulo = (blo.x - lo_u + box.ru * lo_z) * inv_h - m,
               uhi = (bhi.x - lo_u + box.ru * lo_z) * inv_h + m;
  const double wlo = (blo.y - lo_w + box.rw * lo_z) * inv_h - m,
               whi = (bhi.y - lo_w + box.rw * lo_z) * inv_h + m;
  const double zlo = (blo.z - lo_z) * inv_h, zhi = (bhi.z - lo_z) * inv_h;
  const double reach_ulo = (box.reach.lo[u] - lo_u) * inv_h - m,
               reach_uhi = (box.reach.hi[u] - lo_u) * inv_h + m;
  const double reach_wlo = (box.reach.lo[w] - lo_w) * inv_h - m,
               reach_whi = (box.reach.hi[w] - lo_w) * inv_h + m;
  // A cell index (as Buckets::cell_along: clamped to the grid), then to the task's share.
  const auto cell = [](double c, uint32_t top, uint32_t share_lo, uint32_t share_hi) {
    c = c > 0 ? c : 0.0;  // (and not-a-number: 0)
    c = c < top ? c : static_cast<double>(top);
    uint32_t i = static_cast<uint32_t>(c);
    i = i > share_lo ? i : share_lo;
    return i < share_hi ? i : share_hi;
  };
  const uint32_t top_u = b.dims[u] - 1, top_w = b.dims[w] - 1;
  const uint32_t share_ulo = cell_lo[u], share_uhi = cell_hi[u], share_wlo = cell_lo[w],
                 share_whi = cell_hi[w];
  for (uint32_t zc = c0; zc <= c1; ++zc) {
    // The layer's span along ax, within the bounds.
    const double za = zc - m > zlo ? zc - m : zlo, zb = zc + 1.0 + m < zhi ? zc + 1.0 + m : zhi;
    // Every query of a layer within the span passes the test along ax.
    const bool inner = zc - m >= zlo && zc + 1.0 + m <= zhi;
    const double ua = box.ru * za, ub = box.ru * zb, wa = box.rw * za, wb = box.rw * zb;
    double xa = ulo + (ua < ub ? ua : ub), xb = uhi + (ua > ub ? ua : ub);
    double ya = wlo + (wa < wb ? wa : wb), yb = whi + (wa > wb ? wa : wb);
    xa = xa > reach_ulo ? xa : reach_ulo;
    xb = xb < reach_uhi ? xb : reach_uhi;
    ya = ya > reach_wlo ? ya : reach_wlo;
    yb = yb < reach_whi ? yb : reach_whi;
    if (xa > xb || ya > yb) continue;
    uint32_t lo[3], hi[3];  // the cells along each axis
    lo[ax] = hi[ax] = zc;
    lo[u] = cell(xa, top_u, share_ulo, share_uhi);
    hi[u] = cell(xb, top_u, share_ulo, share_uhi);
    lo[w] = cell(ya, top_w, share_wlo, share_whi);
    hi[w] = cell(yb, top_w, share_wlo, share_whi);
    const auto rows = [&](auto along_ax) {
      for (uint32_t zi = lo[2]; zi <= hi[2]; ++zi) {
        for (uint32_t yi = lo[1]; yi <= hi[1]; ++yi) {
          const size_t row = yi * stride[1] + zi * stride[2];
          const uint32_t end = start[row + hi[0] + 1];
          for (uint32_t j = start[row + lo[0]]; j < end; j += 2) {
            if (hit_count + 2 > kHits) flush();
            const Lanes2 qz = load2(along_z + j);
            const Lanes2 qu = load2(along_u + j) - ru * qz, qw = load2(along_w + j) - rw * qz;
            Mask2 in = (qu >= u0) & (qu <= u1) & (qw >= w0) & (qw <= w1);
            if (decltype(along_ax)::value) in &= (qz >= z0) & (qz <= z1);
            hits[hit_count] = j;
            hit_count += static_cast<uint32_t>(in[0] & 1);
            hits[hit_count] = j + 1;
            hit_count += static_cast<uint32_t>(in[1] & 1);
          }
        }
      }
    };
    if (inner) {
      rows(std::false_type{});
    } else {
      rows(std::true_type{});
    }
  }
  flush();
}

// region_closest_points (below), stage by stage. Each stage that returns false leaves the
// batch to the tree. (The queries come in as a parameter, and the loops over them count in
// locals: as members they would be loaded again after every store to the buckets.)
struct RegionBatch {
  const Context& ctx;
  const DistanceIndex& index;
  const Mesh& mesh;
  size_t nt;
  Scan s;
  Aabb mbox;      // the mesh's
  Aabb near_box;  // the queries beyond it cannot have an answer within the band
  Aabb qbox;      // of the bucketed queries
  size_t nu = 0;  // the bucketed queries
  Buckets b;
  uint64_t cells = 0;
  uint32_t tasks = 1;
  TriangleRegions* scratch = nullptr;  // one for each task
  uint32_t* position = nullptr;        // of each triangle in leaf order

  RegionBatch(const Context& context, const DistanceIndex& distance_index)
      : ctx(context),
        index(distance_index),
        mesh(*distance_index.mesh),
        nt(distance_index.mesh->triangles.size()) {}

  bool bucketed(const Vec3& q) const { return usable(q) && near_box.contains(q); }

  // The tree's distance for kSample of the usable_count (>= kSample) usable queries, spread
  // over the batch: the largest unless it exceeds four times the median (then the far ones
  // would make every region long).
  double sampled_band(Span<const Vec3> queries, size_t usable_count) const {
    const size_t n = queries.size();
    double sample[kSample] = {};  // (zeroed for cppcheck only: all kSample are set below)
    uint32_t sampled = 0;
    const size_t step = usable_count / kSample > 0 ? usable_count / kSample : 1;
    for (size_t i = 0, seen = 0; i < n && sampled < kSample; ++i) {
      if (!usable(queries[i])) continue;
      if (seen++ % step != 0) continue;
      ClosestPoint cp;
      double d = 0;
      if (closest_within(index, queries[i], HUGE_VAL, &cp)) d = cp.distance;
      uint32_t j = sampled++;
      for (; j > 0 && sample[j - 1] > d; --j) sample[j] = sample[j - 1];
      sample[j] = d;
    }
    const double median = sample[sampled / 2], largest = sample[sampled - 1];
    return largest < 4 * median ? largest : 4 * median;
  }

  // The band B and the margin mu (s), when the batch is large enough.
  bool choose_band(Span<const Vec3> queries) {
    const size_t n = queries.size();
    if (nt == 0 || n < kMinQueries || n < nt / 2 || n >= (size_t{1} << 31)) return false;
    size_t usable_count = 0;
    for (size_t i = 0; i < n; ++i) usable_count += usable(queries[i]) ? size_t{1} : size_t{0};
    if (usable_count < kMinQueries) return false;
    mbox = mesh_bounds(mesh);
    double scale = 0;  // of the coordinates: the mesh's, and the queries' within the band of it
    for (int a = 0; a < 3; ++a)
      scale = max3_of(scale, std::fabs(mbox.lo[a]), std::fabs(mbox.hi[a]));
    double band = sampled_band(queries, usable_count);
    band = band * (1.0 + 1.0 / 16) + scale * 0x1p-30;
    scale += band;
    s.index = &index;
    s.band = band;
    // The margin (see the top of the file): mu^3 >= B^2 (scale + B) 2^-32, as a power of two
    // (exact, no cube root from the library), and far above the rounding of the region tests.
    int exponent = 0;
    (void)std::frexp(band * band * (scale + band) * 0x1p-32, &exponent);
    s.mu = std::ldexp(1.0, exponent >= 0 ? (exponent + 2) / 3 : -((-exponent) / 3));
    s.mu = s.mu > (scale + band) * 0x1p-36 ? s.mu : (scale + band) * 0x1p-36;
    s.reach = band + s.mu;
    s.slack = scale * 0x1p-40;
    return true;
  }

  // The queries to bucket: those within the reach of the mesh's box (the tree answers the
  // others: they would only stretch the grid).
  bool gather_near(Span<const Vec3> queries) {
    near_box.lo = mbox.lo - Vec3{s.reach, s.reach, s.reach};
    near_box.hi = mbox.hi + Vec3{s.reach, s.reach, s.reach};
    const Aabb near = near_box;
    Aabb box;
    size_t count = 0;
    for (size_t i = 0; i < queries.size(); ++i) {
      if (!usable(queries[i]) || !near.contains(queries[i])) continue;
      box.add(queries[i]);
      ++count;
    }
    qbox = box;
    nu = count;
    return nu >= kMinQueries;
  }

  // The grid: cells about the size that holds two queries each were they spread over the box,
  // at most 2 nu + 1024 cells; and the tasks, one for each thread (at most one a layer).
  void size_grid() {
    b.lo = qbox.lo;
    Vec3 ext = qbox.hi - qbox.lo;
    const double widest = max3_of(ext.x, ext.y, ext.z);
    b.h = widest > 0 ? widest * 0x1p-12 : 1.0;
    for (;;) {
      cells = 1;
      for (int a = 0; a < 3; ++a) {
        b.dims[a] = static_cast<uint32_t>(std::floor(ext[a] / b.h)) + 1;
        cells *= b.dims[a];
      }
      if (cells <= 2 * uint64_t{nu} + 1024) break;
      b.h *= 1.25;
    }
    b.inv_h = 1.0 / b.h;
    tasks = has_threads(ctx.executor)
                ? (ctx.executor->concurrency < b.dims[2] ? ctx.executor->concurrency : b.dims[2])
                : 1;
  }

  // The buckets' arrays, the tasks' scratch and the triangles' positions. False when the
  // arena cannot hold them: the tree answers, in the 2 MB it needs.
  bool allocate(Arena& arena) {
    b.start = arena.allocate_array<uint32_t>(static_cast<size_t>(cells) + 1);
    for (double*& a : b.coord) a = arena.allocate_array<double>(nu + 1);
    b.ids = arena.allocate_array<uint32_t>(nu);
    b.best = arena.allocate_array<uint32_t>(nu + 1);
    scratch = arena.allocate_array<TriangleRegions>(tasks);
    position = arena.allocate_array<uint32_t>(nt);
    return b.start != nullptr && b.coord[0] != nullptr && b.coord[1] != nullptr &&
           b.coord[2] != nullptr && b.ids != nullptr && b.best != nullptr && scratch != nullptr &&
           position != nullptr;
  }

  // Worth it? A query meets about (2 B x the mesh's area) / (the volume the queries fill)
  // face regions: near a smooth surface about one; with a band as wide as a small or
  // tangled mesh, every region covers most queries, and the tree is faster. Reads the counts
  // in b.start.
  bool few_overlaps() const {
    uint64_t filled = 0;
    for (uint64_t c = 1; c <= cells; ++c) filled += b.start[c] != 0 ? 1 : 0;
    double area = 0;
    for (const Triangle& tri : mesh.triangles) {
      const Vec3* v = mesh.vertices.data();
      area += 0.5 * length(cross(v[tri.v[1]] - v[tri.v[0]], v[tri.v[2]] - v[tri.v[0]]));
    }
    return !(2 * s.band * area > kMaxOverlap * static_cast<double>(filled) * b.h * b.h * b.h);
  }

  // Counting sort into the cells: start[c] counts, then (prefix) begins, then (placing) ends,
  // then shifted back to begins (prepare_scan). First by slabs of 2^slab_shift cells (at
  // most 1024 slabs): start[] (two cells a query) is far larger than a cache, and counting
  // and placing the queries in their input order would touch it at random; a slab's counts
  // lie together. The order within a cell is the input order either way.
  bool bucket_queries(Arena& arena, Span<const Vec3> queries) {
    const size_t n = queries.size();
    int slab_shift = 0;
    while ((cells >> slab_shift) >= 1024) ++slab_shift;
    const uint32_t slabs = static_cast<uint32_t>(cells >> slab_shift) + 1;
    ArenaScope sorting(arena);
    uint32_t* slab_start = arena.allocate_array<uint32_t>(size_t{slabs} + 1);
    uint64_t* by_slab = arena.allocate_array<uint64_t>(nu);  // cell << 32 | query index
    if (slab_start == nullptr || by_slab == nullptr) return false;
    for (uint32_t k = 0; k <= slabs; ++k) slab_start[k] = 0;
    for (size_t i = 0; i < n; ++i) {
      if (bucketed(queries[i])) ++slab_start[(b.cell_of(queries[i]) >> slab_shift) + 1];
    }
    for (uint32_t k = 0; k < slabs; ++k) slab_start[k + 1] += slab_start[k];
    for (size_t i = 0; i < n; ++i) {
      if (!bucketed(queries[i])) continue;
      const uint64_t c = b.cell_of(queries[i]);
      by_slab[slab_start[static_cast<size_t>(c >> slab_shift)]++] = (c << 32) | i;
    }
    for (uint64_t c = 0; c <= cells; ++c) b.start[c] = 0;
    for (size_t j = 0; j < nu; ++j) ++b.start[static_cast<size_t>(by_slab[j] >> 32) + 1];
    if (!few_overlaps()) return false;
    for (uint64_t c = 0; c < cells; ++c) b.start[c + 1] += b.start[c];
    for (size_t j = 0; j < nu; ++j) {
      const uint32_t i = static_cast<uint32_t>(by_slab[j]);
      const uint32_t at = b.start[static_cast<size_t>(by_slab[j] >> 32)]++;
      for (int k = 0; k < 3; ++k) b.coord[k][at] = queries[i][k];
      b.ids[at] = i;
    }
    return true;
  }

  // The best points, in the memory the sort has just given back.
  bool allocate_best(Arena& arena) {
    b.best_point = arena.allocate_array<Vec3>(nu + 1);
    b.best_feature = arena.allocate_array<uint8_t>(nu + 1);
    return b.best_point != nullptr && b.best_feature != nullptr;
  }

  void prepare_scan() {
    for (uint32_t i = 0; i < tasks; ++i) new (&scratch[i]) TriangleRegions();
    s.buckets = &b;
    // (Apart from the placing above, which writes a slab's cells at a time: these in order.)
    for (size_t j = 0; j <= nu; ++j) b.best[j] = kNoNeighbor;
    for (double* a : b.coord) a[nu] = 0;
    for (uint64_t c = cells; c > 0; --c) b.start[c] = b.start[c - 1];
    b.start[0] = 0;
  }

  // Task i's share of the round: triangles order[first, last), on the layers along z from
  // cell_lo[2] to cell_hi[2].
  void scan_share(uint32_t i, uint32_t first, uint32_t last) {
    const uint32_t* order = index.order.data();
    const uint32_t* neighbors = index.neighbors.data();
    const uint32_t cell_lo[3] = {
        0, 0, static_cast<uint32_t>(static_cast<uint64_t>(b.dims[2]) * i / tasks)};
    const uint32_t cell_hi[3] = {
        b.dims[0] - 1, b.dims[1] - 1,
        static_cast<uint32_t>(static_cast<uint64_t>(b.dims[2]) * (i + 1) / tasks) - 1};
    // The share's z span, for skipping triangles that cannot reach it.
    const double lo_z = tasks == 1 ? qbox.lo.z : b.lo.z + cell_lo[2] * b.h - b.h;
    const double hi_z = tasks == 1 ? qbox.hi.z : b.lo.z + (cell_hi[2] + 1.0) * b.h + b.h;
    TriangleRegions& tr = scratch[i];
    const Vec3* v = mesh.vertices.data();
    // Triangles beyond the reach of the share's queries are skipped.
    const auto beyond = [&](uint32_t u) {
      Aabb box;
      for (uint32_t c : mesh.triangles[u].v) box.add(v[c]);
      return box.lo.x - s.reach > qbox.hi.x || box.hi.x + s.reach < qbox.lo.x ||
             box.lo.y - s.reach > qbox.hi.y || box.hi.y + s.reach < qbox.lo.y ||
             box.lo.z - s.reach > hi_z || box.hi.z + s.reach < lo_z;
    };
    for (uint32_t j = first; j < last; ++j) {
      const uint32_t t = order[j];
      // With its partner (partner() above): one walk over their bounds, about those of
      // one, instead of two, at the first of them in leaf order. Along their mean normal,
      // within 0.41 degrees of each, so each prism of height 2R leans out of its box by at
      // most R / 70.
      const uint32_t t2 = partner(mesh, neighbors, t);
      if (t2 != kNoNeighbor && position[t2] < j) continue;
      if (beyond(t) && (t2 == kNoNeighbor || beyond(t2))) continue;
      const Triangle& tri = mesh.triangles[t];
      const Vec3 p[3] = {v[tri.v[0]], v[tri.v[1]], v[tri.v[2]]};
      const Frame f = frame_of(p);
      Vec3 dir = f.ok ? f.n : Vec3{0, 0, 1};
      Vec3 p2[3];
      Frame f2;
      if (t2 != kNoNeighbor) {
        const Triangle& tri2 = mesh.triangles[t2];
        for (int k = 0; k < 3; ++k) p2[k] = v[tri2.v[k]];
        f2 = frame_of(p2);
        const Vec3 sum = f.n + f2.n;
        dir = sum * (1.0 / length(sum));
      }
      tr.count = 0;
      tr.box.start(dir);
      add_regions(s, t, p, f, dir, &tr);
      if (t2 != kNoNeighbor) add_regions(s, t2, p2, f2, dir, &tr);
      tr.box.grow(s.mu);
      walk(s, tr.box, cell_lo, cell_hi,
           [&](const uint32_t* at, uint32_t count) { offer_list(s, tr, at, count); });
    }
  }

  // The scan: triangles in leaf order (neighbours one after another), in rounds between
  // progress reports; within a round the layers along z are split among the tasks (each cell
  // is one task's), so tasks never share a query. A triangle whose regions cross a split is
  // scanned by each task it reaches. The answers do not depend on the split.
  Status scan() {
    const uint32_t* order = index.order.data();
    const uint32_t ntri = static_cast<uint32_t>(nt);
    for (uint32_t j = 0; j < ntri; ++j) position[order[j]] = j;
    for (uint32_t first = 0; first < ntri; first += kRound) {
      SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, kStage, first, ntri + uint64_t{nu}));
      const uint32_t last = first + kRound < ntri ? first + kRound : ntri;
      auto task = [&](uint32_t i) { scan_share(i, first, last); };
      parallel_for_each(ctx.executor, tasks, task);
    }
    return report_progress(ctx, kStage, ntri, ntri + uint64_t{nu});
  }

  // The answers: a query whose best candidate lies within the band has the tree's answer;
  // the others (and the unusable ones) ask the tree.
  void answer_all(Span<const Vec3> queries, RegionAnswer answer, void* user) {
    const double band2 = s.band * s.band;
    constexpr uint32_t kChunk = 1024;
    const uint32_t chunks = static_cast<uint32_t>((nu + kChunk - 1) / kChunk);
    auto finish = [&](uint32_t i) {
      const size_t first_query = static_cast<size_t>(i) * kChunk;
      const size_t e = first_query + kChunk < nu ? first_query + kChunk : nu;
      for (size_t j = first_query; j < e; ++j) {
        const Vec3 q = b.point(j);
        ClosestPoint cp;
        bool found = true;
        const double best2 = best_distance2(b, j, q);
        if (best2 <= band2) {
          cp.triangle = b.best[j];
          cp.point = b.best_point[j];
          cp.feature = static_cast<Feature>(b.best_feature[j] >> 2);
          cp.feature_index = static_cast<uint8_t>(b.best_feature[j] & 3);
          settle_closest(index, q, best2, &cp);
        } else {
          found = closest_within(index, q, HUGE_VAL, &cp, b.best[j]);
        }
        answer(user, b.ids[j], cp, found);
      }
    };
    parallel_for_each(ctx.executor, chunks, finish);
    for (size_t i = 0; i < queries.size(); ++i) {
      if (bucketed(queries[i])) continue;
      ClosestPoint cp;
      const bool found = closest_within(index, queries[i], HUGE_VAL, &cp);
      answer(user, i, cp, found);
    }
  }
};

}  // namespace

Status detail::region_closest_points(const Context& ctx, const DistanceIndex& index,
                                     Span<const Vec3> queries, RegionAnswer answer, void* user,
                                     bool* used) {
  *used = false;
  RegionBatch batch(ctx, index);
  if (!batch.choose_band(queries) || !batch.gather_near(queries)) return Status::ok();
  batch.size_grid();
  Arena& arena = *ctx.arena;
  ArenaScope scope(arena);
  if (!batch.allocate(arena) || !batch.bucket_queries(arena, queries) ||
      !batch.allocate_best(arena)) {
    return Status::ok();
  }
  *used = true;
  batch.prepare_scan();
  SPLINTCORE_RETURN_IF_ERROR(batch.scan());
  batch.answer_all(queries, answer, user);
  return Status::ok();
}

}  // namespace splintcore
