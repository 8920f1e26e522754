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
// half as many queries as the mesh has triangles, and the arena holds the buckets (about
// 50 bytes a query); otherwise the tree answers all (query.cpp).
#include <cmath>
#include <new>

#include "distance/query_internal.h"

namespace splintcore {
namespace {

constexpr uint32_t kMaxPlanes = 24;     // a vertex with more neighbours keeps the first ones
constexpr uint32_t kMaxHull = 64;       // corners of a clipped vertex cube
constexpr size_t kMinQueries = 4096;    // smaller batches: the tree
constexpr uint32_t kSample = 256;       // queries whose tree distances set the band
constexpr uint32_t kRound = 1u << 15;   // triangles between progress reports
constexpr double kMaxOverlap = 4;       // face regions about a query, at most (estimated)
// The progress stage (the tree's batches report "closest points" or "signed distances").
constexpr const char* kStage = "closest points, by regions";

struct Plane {  // the region lies in dot(n, x) <= off
  Vec3 n;
  double off;
};

// A face, edge or vertex region: its planes, and the triangles it offers (a vertex region
// offers every triangle at `vertex`).
struct Region {
  Plane planes[kMaxPlanes];
  uint32_t count = 0;
  uint32_t candidates[2] = {0, 0};
  uint32_t candidate_count = 0;
  uint32_t vertex = kNoNeighbor;
  bool face = false;  // a prism: planes[3] is the top, n . x <= h0 + R
  double h0 = 0;
};

// A triangle's unit normal and unit inward edge normals (m[k] for edge k, v[k] -> v[k+1]);
// ok is false for a triangle with an angle whose sine is under 2^-10 (or degenerate).
struct Frame {
  Vec3 n{};
  Vec3 m[3]{};
  bool ok = false;
};

inline double max3(double a, double b, double c) {
  const double ab = a > b ? a : b;
  return ab > c ? ab : c;
}

// The unnormalised normal of triangle p, and whether all its angles' sines exceed 2^-10.
inline bool well_shaped(const Vec3 p[3], Vec3* n, double* n2) {
  const Vec3 ab = p[1] - p[0], ac = p[2] - p[0], bc = p[2] - p[1];
  *n = cross(ab, ac);
  *n2 = dot(*n, *n);
  const double lab = dot(ab, ab), lac = dot(ac, ac), lbc = dot(bc, bc);
  // |n| = |ab| |ac| sin A = |ab| |bc| sin B = |ac| |bc| sin C.
  return *n2 > max3(lab * lac, lab * lbc, lac * lbc) * 0x1p-20;
}

Frame frame_of(const Vec3 p[3]) {
  Frame f;
  Vec3 n;
  double n2 = 0;
  if (!well_shaped(p, &n, &n2)) return f;
  f.n = n * (1.0 / std::sqrt(n2));
  for (int k = 0; k < 3; ++k) {
    const Vec3 m = cross(f.n, p[(k + 1) % 3] - p[k]);
    f.m[k] = m * (1.0 / length(m));
  }
  f.ok = true;
  return f;
}

// A convex polytope by its corners, each with the set of its planes (bits), clipped plane by
// plane: a new corner where an edge (two corners sharing two planes) crosses the plane. Only
// the corners are needed: their hull bounds the region for the bucket scan.
// Two buffers, the current one and the one a clip writes; built once per task (Vec3 zeroes
// itself) and reused.
struct Hull {
  Vec3 points[2][kMaxHull];
  uint64_t planes[2][kMaxHull];
  uint32_t current = 0;
  uint32_t n = 0;
  bool ok = true;

  const Vec3& point(uint32_t i) const { return points[current][i]; }
  void cube(const Vec3& c, double r) {
    current = 0;
    n = 0;
    ok = true;
    for (uint32_t i = 0; i < 8; ++i) {
      points[0][n] = Vec3{(i & 1) ? c.x + r : c.x - r, (i & 2) ? c.y + r : c.y - r,
                          (i & 4) ? c.z + r : c.z - r};
      planes[0][n++] = (uint64_t{1} << ((i & 1) ? 1 : 0)) | (uint64_t{1} << ((i & 2) ? 3 : 2)) |
                       (uint64_t{1} << ((i & 4) ? 5 : 4));
    }
  }
  void clip(const Plane& plane, uint32_t bit) {
    const Vec3* p = points[current];
    const uint64_t* pl = planes[current];
    Vec3* kept = points[current ^ 1];
    uint64_t* kept_planes = planes[current ^ 1];
    double s[kMaxHull];
    uint8_t in[kMaxHull], out[kMaxHull];
    uint32_t in_count = 0, out_count = 0, k = 0;
    for (uint32_t i = 0; i < n; ++i) {
      s[i] = dot(plane.n, p[i]) - plane.off;
      if (s[i] > 0) {
        out[out_count++] = static_cast<uint8_t>(i);
        continue;
      }
      if (s[i] < 0) in[in_count++] = static_cast<uint8_t>(i);
      kept[k] = p[i];
      kept_planes[k++] = pl[i] | (s[i] == 0 ? uint64_t{1} << bit : 0);
    }
    if (!ok || out_count == 0) return;
    for (uint32_t a = 0; a < in_count; ++a) {
      const uint32_t i = in[a];
      for (uint32_t c = 0; c < out_count; ++c) {
        const uint32_t j = out[c];
        const uint64_t common = pl[i] & pl[j];
        if ((common & (common - 1)) == 0) continue;  // fewer than two planes: not an edge
        if (k == kMaxHull) {
          ok = false;
          return;
        }
        kept[k] = p[i] + (p[j] - p[i]) * (s[i] / (s[i] - s[j]));
        kept_planes[k++] = common | (uint64_t{1} << bit);
      }
    }
    n = k;
    current ^= 1;
  }
};

// The queries in buckets: cell (x, y, z) of side h from lo holds points[start[c] ..
// start[c + 1]) with c = x + dims[0] (y + dims[1] z); ids[] are their indices in the batch.
struct Buckets {
  Vec3 lo{};
  double h = 1;
  double inv_h = 1;  // 1 / h
  uint32_t dims[3] = {1, 1, 1};
  uint32_t* start = nullptr;
  Vec3* points = nullptr;
  uint32_t* ids = nullptr;
  double* best2 = nullptr;
  uint32_t* best = nullptr;

  // The cell index along `axis` of coordinate x, clamped to the grid (a conversion, not
  // floor(), which is a library call without SSE4.1: the same for the non-negative values
  // it converts).
  uint32_t cell_along(double x, int axis) const {
    const double c = (x - lo[axis]) * inv_h;
    if (!(c >= 1)) return 0;
    return c >= dims[axis] - 1.0 ? dims[axis] - 1 : static_cast<uint32_t>(c);
  }
  size_t cell_of(const Vec3& q) const {
    return cell_along(q.x, 0) + size_t{dims[0]} * (cell_along(q.y, 1) + size_t{dims[1]} * cell_along(q.z, 2));
  }
};

inline bool usable(const Vec3& q) {
  return std::fabs(q.x) <= 0x1p40 && std::fabs(q.y) <= 0x1p40 && std::fabs(q.z) <= 0x1p40;
}

// One triangle's regions (those it owns: its face, its edges unless the neighbour across has a
// smaller id, and each vertex whose first corner is its), and the bounds of their union for
// the scan: a box in coordinates sheared along the scan direction `dir`.
struct TriangleRegions {
  Region regions[7];
  uint32_t count = 0;
  Hull hull;  // scratch for the vertex regions' bounds
  int ax = 2, u = 0, w = 1;  // the scan walks cells along ax, the dominant axis of dir
  double ru = 0, rw = 0;     // dir[u] / dir[ax], dir[w] / dir[ax]
  // The sheared coordinates as dot products (no indexing in the loops): x[u] - x[ax] ru,
  // x[w] - x[ax] rw, x[ax].
  Vec3 cu{}, cw{}, cz{};
  double u0 = HUGE_VAL, u1 = -HUGE_VAL, w0 = HUGE_VAL, w1 = -HUGE_VAL, z0 = HUGE_VAL, z1 = -HUGE_VAL;
  Aabb reach;  // the triangle's box grown by R: every region point within R of it lies here

  Region& take() {
    Region& g = regions[count++];
    g.count = 0;
    g.candidate_count = 0;
    g.vertex = kNoNeighbor;
    g.face = false;
    return g;
  }
  void add_point(const Vec3& p) {
    const double pu = dot(cu, p), pw = dot(cw, p), pz = dot(cz, p);
    u0 = pu < u0 ? pu : u0;
    u1 = pu > u1 ? pu : u1;
    w0 = pw < w0 ? pw : w0;
    w1 = pw > w1 ? pw : w1;
    z0 = pz < z0 ? pz : z0;
    z1 = pz > z1 ? pz : z1;
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

void build_regions(const Scan& s, uint32_t t, TriangleRegions* out) {
  const Mesh& mesh = *s.index->mesh;
  const Vec3* v = mesh.vertices.data();
  const Triangle& tri = mesh.triangles[t];
  const Vec3 p[3] = {v[tri.v[0]], v[tri.v[1]], v[tri.v[2]]};
  const Frame f = frame_of(p);
  const double mu = s.mu, r = s.reach;
  TriangleRegions& tr = *out;
  tr.count = 0;
  tr.u0 = tr.z0 = tr.w0 = HUGE_VAL;
  tr.u1 = tr.z1 = tr.w1 = -HUGE_VAL;
  const Vec3 dir = f.ok ? f.n : Vec3{0, 0, 1};
  tr.ax = 0;
  for (int k = 1; k < 3; ++k) tr.ax = std::fabs(dir[k]) > std::fabs(dir[tr.ax]) ? k : tr.ax;
  tr.u = (tr.ax + 1) % 3;
  tr.w = (tr.ax + 2) % 3;
  tr.ru = dir[tr.u] / dir[tr.ax];
  tr.rw = dir[tr.w] / dir[tr.ax];
  tr.cu = Vec3{};
  tr.cu[tr.u] = 1;
  tr.cu[tr.ax] = -tr.ru;
  tr.cw = Vec3{};
  tr.cw[tr.w] = 1;
  tr.cw[tr.ax] = -tr.rw;
  tr.cz = Vec3{};
  tr.cz[tr.ax] = 1;
  Aabb box;
  for (const Vec3& c : p) box.add(c);
  tr.reach.lo = box.lo - Vec3{r + mu, r + mu, r + mu};
  tr.reach.hi = box.hi + Vec3{r + mu, r + mu, r + mu};

  // The face: the prism, or for a thin triangle the box within R of it.
  {
    Region& g = tr.take();
    g.candidates[g.candidate_count++] = t;
    if (f.ok) {
      for (int k = 0; k < 3; ++k) g.planes[g.count++] = Plane{f.m[k] * -1.0, mu - dot(f.m[k], p[k])};
      const double h0 = dot(f.n, p[0]);
      g.face = true;
      g.h0 = h0;
      g.planes[g.count++] = Plane{f.n, h0 + r};
      g.planes[g.count++] = Plane{f.n * -1.0, r - h0};
      for (const Vec3& c : p) {
        tr.add_point(c + f.n * r);
        tr.add_point(c - f.n * r);
      }
    } else {
      for (int a = 0; a < 3; ++a) {
        Vec3 e{};
        e[a] = 1;
        g.planes[g.count++] = Plane{e, tr.reach.hi[a]};
        g.planes[g.count++] = Plane{e * -1.0, -tr.reach.lo[a]};
      }
      for (uint32_t i = 0; i < 8; ++i) {
        tr.add_point(Vec3{(i & 1) ? tr.reach.hi.x : tr.reach.lo.x, (i & 2) ? tr.reach.hi.y : tr.reach.lo.y,
                          (i & 4) ? tr.reach.hi.z : tr.reach.lo.z});
      }
    }
  }
  // The edges it owns.
  const uint32_t* neighbors = s.index->neighbors.data();
  for (int k = 0; k < 3; ++k) {
    uint32_t t2 = neighbors[3 * size_t{t} + static_cast<size_t>(k)];
    if (t2 == t) t2 = kNoNeighbor;
    if (t2 != kNoNeighbor && t2 < t) continue;
    const Vec3 &a = p[k], &b = p[(k + 1) % 3];
    const double len = length(b - a);
    if (!(len > 0)) continue;  // its points are its vertex's
    const Vec3 e = (b - a) * (1.0 / len);
    Region& g = tr.take();
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
    for (int i = 0; i < side_count; ++i) g.planes[g.count++] = Plane{sides[i], dot(sides[i], a) + mu};
    // Its bounds: the square of side 2R across the edge (it holds the disc of radius R),
    // clipped by the two sides, swept along the edge.
    Vec3 f1 = std::fabs(e.x) < 0.6 ? cross(e, Vec3{1, 0, 0}) : cross(e, Vec3{0, 1, 0});
    f1 = f1 * (1.0 / length(f1));
    const Vec3 f2v = cross(e, f1);
    double px[8] = {-r, r, r, -r}, py[8] = {-r, -r, r, r};
    int np = 4;
    for (int i = 0; i < side_count; ++i) {
      const double cx = dot(sides[i], f1), cy = dot(sides[i], f2v);
      double qx[8], qy[8];
      int nq = 0;
      for (int j = 0; j < np; ++j) {
        const int jn = j + 1 < np ? j + 1 : 0;
        const double s0 = cx * px[j] + cy * py[j] - mu, s1 = cx * px[jn] + cy * py[jn] - mu;
        if (s0 <= 0) {
          qx[nq] = px[j];
          qy[nq++] = py[j];
        }
        if ((s0 < 0 && s1 > 0) || (s0 > 0 && s1 < 0)) {
          const double c = s0 / (s0 - s1);
          qx[nq] = px[j] + (px[jn] - px[j]) * c;
          qy[nq++] = py[j] + (py[jn] - py[j]) * c;
        }
      }
      np = nq;
      for (int j = 0; j < np; ++j) {
        px[j] = qx[j];
        py[j] = qy[j];
      }
    }
    for (int j = 0; j < np; ++j) {
      const Vec3 d = f1 * px[j] + f2v * py[j];
      tr.add_point(a - e * mu + d);
      tr.add_point(b + e * mu + d);
    }
  }
  // The vertices it owns.
  const uint32_t* vstart = s.index->vertex_start.data();
  const uint32_t* vuses = s.index->vertex_uses.data();
  for (int k = 0; k < 3; ++k) {
    const uint32_t vi = tri.v[k];
    if (vuses[vstart[vi]] / 3 != t) continue;
    Region& g = tr.take();
    g.vertex = vi;
    const Vec3& c = v[vi];
    uint32_t seen[kMaxPlanes];
    uint32_t seen_count = 0;
    // This triangle's two neighbours of v first: they reject most queries.
    const auto add = [&](uint32_t wi) {
      for (uint32_t i = 0; i < seen_count; ++i) {
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
    add(tri.v[(k + 1) % 3]);
    add(tri.v[(k + 2) % 3]);
    for (uint32_t j = vstart[vi]; j < vstart[vi + 1]; ++j) {
      const Triangle& other = mesh.triangles[vuses[j] / 3];
      const uint32_t corner = vuses[j] % 3;
      add(other.v[(corner + 1) % 3]);
      add(other.v[(corner + 2) % 3]);
    }
    // Its bounds: the cube of side 2R about v clipped by the planes (three well-spread ones
    // would bound it too, but near a flat vertex much more loosely: twice the time in all).
    Hull& hull = tr.hull;
    hull.cube(c, r);
    for (uint32_t i = 0; i < g.count; ++i) hull.clip(g.planes[i], 6 + i);
    if (!hull.ok) hull.cube(c, r);
    for (uint32_t i = 0; i < hull.n; ++i) tr.add_point(hull.point(i));
  }
  tr.u0 -= mu;
  tr.u1 += mu;
  tr.w0 -= mu;
  tr.w1 += mu;
  tr.z0 = (tr.z0 - mu > tr.reach.lo[tr.ax]) ? tr.z0 - mu : tr.reach.lo[tr.ax];
  tr.z1 = (tr.z1 + mu < tr.reach.hi[tr.ax]) ? tr.z1 + mu : tr.reach.hi[tr.ax];
}

inline bool inside(const Region& g, const Vec3& q) {
  for (uint32_t i = 0; i < g.count; ++i) {
    if (dot(g.planes[i].n, q) > g.planes[i].off) return false;
  }
  return true;
}

inline void offer(const Mesh& mesh, uint32_t t, const Vec3& q, double* best2, uint32_t* best) {
  const Vec3* v = mesh.vertices.data();
  const Triangle& tri = mesh.triangles[t];
  const Vec3 p = closest_point_on_triangle(q, v[tri.v[0]], v[tri.v[1]], v[tri.v[2]]);
  const double d2 = length_squared(p - q);
  if (d2 < *best2 || (d2 == *best2 && t < *best)) {
    *best2 = d2;
    *best = t;
  }
}

// Offers a triangle's regions to the queries in the cells its bounds cover, among cells
// [cell_lo[a], cell_hi[a]] along each axis a (a task's share).
void scan_triangle(const Scan& s, const TriangleRegions& tr, const uint32_t cell_lo[3],
                   const uint32_t cell_hi[3]) {
  const Buckets& b = *s.buckets;
  const Mesh& mesh = *s.index->mesh;
  const int ax = tr.ax, u = tr.u, w = tr.w;
  const size_t stride[3] = {1, b.dims[0], static_cast<size_t>(b.dims[0]) * b.dims[1]};
  uint32_t c0 = b.cell_along(tr.z0, ax), c1 = b.cell_along(tr.z1, ax);
  c0 = c0 > cell_lo[ax] ? c0 : cell_lo[ax];
  c1 = c1 < cell_hi[ax] ? c1 : cell_hi[ax];
  for (uint32_t zc = c0; zc <= c1; ++zc) {
    // The layer's span along ax (with mu for the rounding of the cell index), within the bounds.
    double za = b.lo[ax] + zc * b.h - s.mu, zb = b.lo[ax] + (zc + 1.0) * b.h + s.mu;
    za = za > tr.z0 ? za : tr.z0;
    zb = zb < tr.z1 ? zb : tr.z1;
    if (za > zb) continue;
    double xa = tr.u0 + (za * tr.ru < zb * tr.ru ? za * tr.ru : zb * tr.ru);
    double xb = tr.u1 + (za * tr.ru > zb * tr.ru ? za * tr.ru : zb * tr.ru);
    double ya = tr.w0 + (za * tr.rw < zb * tr.rw ? za * tr.rw : zb * tr.rw);
    double yb = tr.w1 + (za * tr.rw > zb * tr.rw ? za * tr.rw : zb * tr.rw);
    xa = xa > tr.reach.lo[u] ? xa : tr.reach.lo[u];
    xb = xb < tr.reach.hi[u] ? xb : tr.reach.hi[u];
    ya = ya > tr.reach.lo[w] ? ya : tr.reach.lo[w];
    yb = yb < tr.reach.hi[w] ? yb : tr.reach.hi[w];
    if (xa > xb || ya > yb) continue;
    uint32_t uc0 = b.cell_along(xa, u), uc1 = b.cell_along(xb, u);
    uint32_t wc0 = b.cell_along(ya, w), wc1 = b.cell_along(yb, w);
    uc0 = uc0 > cell_lo[u] ? uc0 : cell_lo[u];
    uc1 = uc1 < cell_hi[u] ? uc1 : cell_hi[u];
    wc0 = wc0 > cell_lo[w] ? wc0 : cell_lo[w];
    wc1 = wc1 < cell_hi[w] ? wc1 : cell_hi[w];
    for (uint32_t wc = wc0; wc <= wc1; ++wc) {
      const size_t row = zc * stride[ax] + wc * stride[w];
      for (uint32_t uc = uc0; uc <= uc1; ++uc) {
        const size_t cell = row + uc * stride[u];
        for (uint32_t j = b.start[cell]; j < b.start[cell + 1]; ++j) {
          const Vec3& q = b.points[j];
          const double qu = dot(tr.cu, q), qw = dot(tr.cw, q), qz = dot(tr.cz, q);
          if (qu < tr.u0 || qu > tr.u1 || qw < tr.w0 || qw > tr.w1 || qz < tr.z0 || qz > tr.z1) {
            continue;
          }
          for (uint32_t i = 0; i < tr.count; ++i) {
            const Region& g = tr.regions[i];
            if (!inside(g, q)) continue;
            if (g.face) {
              // Its plane already lies farther than the best so far: it cannot win or tie.
              const double h = std::fabs(dot(g.planes[3].n, q) - g.h0) - s.slack;
              if (h > 0 && h * h > b.best2[j] + b.best2[j] * 0x1p-30) continue;
            }
            if (g.vertex == kNoNeighbor) {
              for (uint32_t k = 0; k < g.candidate_count; ++k) {
                offer(mesh, g.candidates[k], q, &b.best2[j], &b.best[j]);
              }
            } else {
              const uint32_t* vstart = s.index->vertex_start.data();
              const uint32_t* vuses = s.index->vertex_uses.data();
              for (uint32_t k = vstart[g.vertex]; k < vstart[g.vertex + 1]; ++k) {
                offer(mesh, vuses[k] / 3, q, &b.best2[j], &b.best[j]);
              }
            }
          }
        }
      }
    }
  }
}

}  // namespace

Status detail::region_closest_points(const Context& ctx, const DistanceIndex& index,
                                     Span<const Vec3> queries, RegionAnswer answer, void* user,
                                     bool* used) {
  *used = false;
  const Mesh& mesh = *index.mesh;
  const size_t n = queries.size(), nt = mesh.triangles.size();
  if (nt == 0 || n < kMinQueries || n < nt / 2 || n >= (size_t{1} << 31)) return Status::ok();
  // The band: from the tree's distances of kSample queries spread over the batch, the largest
  // unless it exceeds four times the median (then the far ones would make every region long).
  size_t usable_count = 0;
  for (size_t i = 0; i < n; ++i) usable_count += usable(queries[i]) ? size_t{1} : size_t{0};
  if (usable_count < kMinQueries) return Status::ok();
  double sample[kSample];
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
  const Aabb mbox = mesh_bounds(mesh);
  double scale = 0;  // of the coordinates: the mesh's, and the queries' within the band of it
  for (int a = 0; a < 3; ++a) scale = max3(scale, std::fabs(mbox.lo[a]), std::fabs(mbox.hi[a]));
  double band = largest < 4 * median ? largest : 4 * median;
  band = band * (1.0 + 1.0 / 16) + scale * 0x1p-30;
  scale += band;
  Scan s;
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
  // Queries farther than that from the mesh's box cannot have an answer within the band: the
  // tree answers them (they would only stretch the grid).
  Aabb near_box;
  near_box.lo = mbox.lo - Vec3{s.reach, s.reach, s.reach};
  near_box.hi = mbox.hi + Vec3{s.reach, s.reach, s.reach};
  size_t nu = 0;
  Aabb qbox;
  for (size_t i = 0; i < n; ++i) {
    if (!usable(queries[i]) || !near_box.contains(queries[i])) continue;
    qbox.add(queries[i]);
    ++nu;
  }
  if (nu < kMinQueries) return Status::ok();
  const auto bucketed = [&](const Vec3& q) { return usable(q) && near_box.contains(q); };

  // The grid: cells about the size that holds two queries each were they spread over the box,
  // at most 2 nu + 1024 cells.
  Buckets b;
  b.lo = qbox.lo;
  Vec3 ext = qbox.hi - qbox.lo;
  const double widest = max3(ext.x, ext.y, ext.z);
  b.h = widest > 0 ? widest * 0x1p-12 : 1.0;
  uint64_t cells = 0;
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
  const uint32_t tasks = ctx.executor != nullptr && ctx.executor->concurrency > 1
                             ? (ctx.executor->concurrency < b.dims[2] ? ctx.executor->concurrency : b.dims[2])
                             : 1;
  Arena& arena = *ctx.arena;
  ArenaScope scope(arena);
  b.start = arena.allocate_array<uint32_t>(static_cast<size_t>(cells) + 1);
  b.points = arena.allocate_array<Vec3>(nu);
  b.ids = arena.allocate_array<uint32_t>(nu);
  b.best2 = arena.allocate_array<double>(nu);
  b.best = arena.allocate_array<uint32_t>(nu);
  TriangleRegions* scratch = arena.allocate_array<TriangleRegions>(tasks);
  if (b.start == nullptr || b.points == nullptr || b.ids == nullptr || b.best2 == nullptr ||
      b.best == nullptr || scratch == nullptr) {
    return Status::ok();  // the tree answers, in the 2 MB it needs
  }
  // Counting sort into the cells: start[c] counts, then (prefix) begins, then (placing) ends,
  // then shifted back to begins.
  for (uint64_t c = 0; c <= cells; ++c) b.start[c] = 0;
  for (size_t i = 0; i < n; ++i) {
    if (bucketed(queries[i])) ++b.start[b.cell_of(queries[i]) + 1];
  }
  // Worth it? A query meets about (2 B x the mesh's area) / (the volume the queries fill)
  // face regions: near a smooth surface about one; with a band as wide as a small or
  // tangled mesh, every region covers most queries, and the tree is faster.
  uint64_t filled = 0;
  for (uint64_t c = 1; c <= cells; ++c) filled += b.start[c] != 0 ? 1 : 0;
  double area = 0;
  for (const Triangle& tri : mesh.triangles) {
    const Vec3* v = mesh.vertices.data();
    area += 0.5 * length(cross(v[tri.v[1]] - v[tri.v[0]], v[tri.v[2]] - v[tri.v[0]]));
  }
  if (2 * band * area > kMaxOverlap * static_cast<double>(filled) * b.h * b.h * b.h) return Status::ok();
  *used = true;
  for (uint32_t i = 0; i < tasks; ++i) new (&scratch[i]) TriangleRegions();
  s.buckets = &b;
  for (uint64_t c = 0; c < cells; ++c) b.start[c + 1] += b.start[c];
  for (size_t i = 0; i < n; ++i) {
    if (!bucketed(queries[i])) continue;
    const uint32_t at = b.start[b.cell_of(queries[i])]++;
    b.points[at] = queries[i];
    b.ids[at] = static_cast<uint32_t>(i);
    b.best2[at] = HUGE_VAL;
    b.best[at] = kNoNeighbor;
  }
  for (uint64_t c = cells; c > 0; --c) b.start[c] = b.start[c - 1];
  b.start[0] = 0;

  // The scan: triangles in leaf order (neighbours one after another), in rounds between
  // progress reports; within a round the layers along z are split among the tasks (each cell
  // is one task's), so tasks never share a query. A triangle whose regions cross a split is
  // scanned by each task it reaches. The answers do not depend on the split.
  const uint32_t* order = index.order.data();
  const uint32_t ntri = static_cast<uint32_t>(nt);
  for (uint32_t first = 0; first < ntri; first += kRound) {
    SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, kStage, first, ntri + uint64_t{nu}));
    const uint32_t last = first + kRound < ntri ? first + kRound : ntri;
    auto task = [&](uint32_t i) {
      const uint32_t cell_lo[3] = {0, 0, static_cast<uint32_t>(static_cast<uint64_t>(b.dims[2]) * i / tasks)};
      const uint32_t cell_hi[3] = {b.dims[0] - 1, b.dims[1] - 1,
                                   static_cast<uint32_t>(static_cast<uint64_t>(b.dims[2]) * (i + 1) / tasks) - 1};
      // The share's z span, for skipping triangles that cannot reach it.
      const double lo_z = tasks == 1 ? qbox.lo.z : b.lo.z + cell_lo[2] * b.h - b.h;
      const double hi_z = tasks == 1 ? qbox.hi.z : b.lo.z + (cell_hi[2] + 1.0) * b.h + b.h;
      TriangleRegions& tr = scratch[i];
      for (uint32_t j = first; j < last; ++j) {
        const uint32_t t = order[j];
        const Triangle& tri = mesh.triangles[t];
        Aabb box;
        for (uint32_t c : tri.v) box.add(mesh.vertices[c]);
        if (box.lo.x - s.reach > qbox.hi.x || box.hi.x + s.reach < qbox.lo.x ||
            box.lo.y - s.reach > qbox.hi.y || box.hi.y + s.reach < qbox.lo.y ||
            box.lo.z - s.reach > hi_z || box.hi.z + s.reach < lo_z) {
          continue;
        }
        build_regions(s, t, &tr);
        scan_triangle(s, tr, cell_lo, cell_hi);
      }
    };
    parallel_for_each(ctx.executor, tasks, task);
  }
  SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, kStage, ntri, ntri + uint64_t{nu}));

  // The answers: a query whose best candidate lies within the band has the tree's answer;
  // the others (and the unusable ones) ask the tree.
  const double band2 = band * band;
  constexpr uint32_t kChunk = 1024;
  const uint32_t chunks = static_cast<uint32_t>((nu + kChunk - 1) / kChunk);
  auto finish = [&](uint32_t i) {
    const size_t first_query = static_cast<size_t>(i) * kChunk;
    const size_t e = first_query + kChunk < nu ? first_query + kChunk : nu;
    for (size_t j = first_query; j < e; ++j) {
      const Vec3& q = b.points[j];
      ClosestPoint cp;
      bool found = true;
      if (b.best[j] != kNoNeighbor && b.best2[j] <= band2) {
        const Triangle& tri = mesh.triangles[b.best[j]];
        const Vec3* v = mesh.vertices.data();
        cp.triangle = b.best[j];
        cp.point = closest_point_on_triangle(q, v[tri.v[0]], v[tri.v[1]], v[tri.v[2]], &cp.feature,
                                             &cp.feature_index);
        settle_closest(index, q, b.best2[j], &cp);
      } else {
        found = closest_within(index, q, HUGE_VAL, &cp, b.best[j]);
      }
      answer(user, b.ids[j], cp, found);
    }
  };
  parallel_for_each(ctx.executor, chunks, finish);
  for (size_t i = 0; i < n; ++i) {
    if (bucketed(queries[i])) continue;
    ClosestPoint cp;
    const bool found = closest_within(index, queries[i], HUGE_VAL, &cp);
    answer(user, i, cp, found);
  }
  return Status::ok();
}

}  // namespace splintcore
