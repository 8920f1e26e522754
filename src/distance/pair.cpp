// The closest pair between two triangle meshes, the second translated: a simultaneous descent
// of the two distance indexes' 4-wide hierarchies with box-box distance bounds (Larsen,
// Gottschalk, Lin and Manocha, "Fast distance queries with rectangular swept sphere volumes",
// ICRA 2000, section 4), and the triangle-triangle distance as the least of the vertex-face and
// edge-edge distances (Ericson, "Real-Time Collision Detection", 2005, 5.1.5 and 5.1.9), with
// meeting triangles decided exactly (Shewchuk's orient3d, geometry.h).
#include <atomic>
#include <cmath>
#include <cstring>

#include "core/fminmax.h"
#include "geometry/lanes2.h"
#include "splintcore/distance.h"

namespace splintcore {

namespace {

// p0 + (p1 - p0) s, with the endpoints themselves at s = 0 and 1 (no rounding there).
inline Vec3 along(const Vec3& p0, const Vec3& p1, const Vec3& d, double s) {
  return s == 0 ? p0 : (s == 1 ? p1 : p0 + d * s);
}

// The squared distance of two triangles that do not meet, and a closest pair: the least of the
// six vertex-triangle and nine edge-edge distances, the first of equal ones in that order.
double separated_pair_d2(const Vec3 a[3], const Vec3 b[3], Vec3* pa, Vec3* pb) {
  double best = HUGE_VAL;
  const auto keep = [&](double d2, const Vec3& x, const Vec3& y) {
    if (d2 < best) {
      best = d2;
      *pa = x;
      *pb = y;
    }
  };
  for (int i = 0; i < 3; ++i) {
    const Vec3 q = closest_point_on_triangle(a[i], b[0], b[1], b[2]);
    keep(length_squared(a[i] - q), a[i], q);
  }
  for (int i = 0; i < 3; ++i) {
    const Vec3 q = closest_point_on_triangle(b[i], a[0], a[1], a[2]);
    keep(length_squared(q - b[i]), q, b[i]);
  }
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      Vec3 x, y;
      const double d2 = segment_closest(a[i], a[(i + 1) % 3], b[j], b[(j + 1) % 3], &x, &y);
      keep(d2, x, y);
    }
  }
  return best;
}

// Does an edge of the degenerate (collinear) triangle d meet the triangle t? (A point-like
// edge is tested as a point.)
bool degenerate_meets(const Vec3 d[3], const Vec3 t[3]) {
  for (int i = 0; i < 3; ++i) {
    if (segment_intersects_triangle(d[i], d[(i + 1) % 3], t[0], t[1], t[2])) return true;
  }
  return false;
}

// Do the closed triangles meet? Exact: triangles_intersect, which leaves degenerate triangles
// to its caller; one degenerate triangle meets the other where one of its edges does. (Two
// degenerate ones are left to their computed distance.)
bool triangles_meet(const Vec3 a[3], const Vec3 b[3]) {
  if (triangles_intersect(a[0], a[1], a[2], b[0], b[1], b[2])) return true;
  const bool da = collinear3d(a[0], a[1], a[2]), db = collinear3d(b[0], b[1], b[2]);
  if (da == db) return false;
  return da ? degenerate_meets(a, b) : degenerate_meets(b, a);
}

// Where the segment pq crosses the triangle t's plane, when it meets t and is not in its plane.
bool edge_crossing(const Vec3& p, const Vec3& q, const Vec3 t[3], Vec3* x) {
  if (!segment_intersects_triangle(p, q, t[0], t[1], t[2])) return false;
  const double op = orient3d(t[0], t[1], t[2], p), oq = orient3d(t[0], t[1], t[2], q);
  if (op == 0 && oq == 0) return false;
  // op and oq do not have the same strict sign: the segment meets the plane.
  *x = along(p, q, q - p, clamp01(op / (op - oq)));
  return true;
}

// A point of meeting triangles a and b (to rounding): where an edge of one crosses the other,
// or for coplanar triangles the closest pair's point on a (a vertex inside the other or two
// crossing edges: distance 0 to rounding).
Vec3 common_point(const Vec3 a[3], const Vec3 b[3]) {
  Vec3 x;
  for (int i = 0; i < 3; ++i) {
    if (edge_crossing(a[i], a[(i + 1) % 3], b, &x)) return x;
  }
  for (int i = 0; i < 3; ++i) {
    if (edge_crossing(b[i], b[(i + 1) % 3], a, &x)) return x;
  }
  Vec3 y;
  (void)separated_pair_d2(a, b, &x, &y);
  return x;
}

// ---------------------------------------------------------------------------------------------
// The traversal.

constexpr uint8_t kRootSlot = 4;  // an item that is the whole root node

// A pair of items to examine: item = child `slot` of node `node` (or the root node), a leaf
// or an inner node of its tree. lb2: the squared distance of their boxes, as computed (what
// prunes); centre2: that of their centres, which only orders pairs of equal lb2 (overlapping
// boxes above all), the likelier nearer first.
struct PairEntry {
  uint32_t node_a, node_b;
  uint8_t slot_a, slot_b;
  float centre2;
  double lb2;
};

// Examined before y: nearer boxes, then nearer centres.
inline bool pair_before(const PairEntry& x, const PairEntry& y) {
  return x.lb2 < y.lb2 || (x.lb2 == y.lb2 && x.centre2 < y.centre2);
}

inline float centre_gap2(const double alo[3], const double ahi[3], const double blo[3],
                         const double bhi[3]) {
  double sum = 0;
  for (int i = 0; i < 3; ++i) {
    const double g = (alo[i] + ahi[i]) - (blo[i] + bhi[i]);
    sum += g * g;
  }
  return static_cast<float>(sum * 0.25);
}

// The best-first queue's capacity: enough for the pairs within reach of two dentitions' trees
// at any opening measured, a few tens of kilobytes.
constexpr uint32_t kHeapEntries = 2048;

struct TriangleBox {
  Vec3 p[3];
  Vec3 lo, hi;
};

inline void load_triangle(const Mesh& mesh, uint32_t t, const Vec3& shift, TriangleBox* out) {
  const Triangle& tri = mesh.triangles[t];
  for (int k = 0; k < 3; ++k) out->p[k] = mesh.vertices[tri.v[k]] + shift;
  out->lo = min_vec(min_vec(out->p[0], out->p[1]), out->p[2]);
  out->hi = max_vec(max_vec(out->p[0], out->p[1]), out->p[2]);
}

// Squared distance between the boxes [alo, ahi] and [blo, bhi] as computed (the caller's
// margin covers the rounding): on each axis the gap blo - ahi when blo > ahi, alo - bhi when
// alo > bhi, else 0, squared and summed in axis order ((0 + gx^2) + gy^2) + gz^2. The x and y
// axes a lane pair each: max(max(blo - ahi, alo - bhi), 0) is that gap for boxes with lo <= hi
// (x > y if and only if x - y > 0 in IEEE arithmetic, and then the other difference is
// negative; a zero of either sign squares to +0), and 0 + gx^2 is gx^2.
inline double box_gap2(const double alo[3], const double ahi[3], const double blo[3],
                       const double bhi[3]) {
  Lanes2 al, ah, bl, bh;
  std::memcpy(&al, alo, sizeof al);
  std::memcpy(&ah, ahi, sizeof ah);
  std::memcpy(&bl, blo, sizeof bl);
  std::memcpy(&bh, bhi, sizeof bh);
  const Lanes2 zero = {0.0, 0.0};
  const Lanes2 d1 = bl - ah, d2 = al - bh;
  const Lanes2 m = d1 > d2 ? d1 : d2;
  const Lanes2 g = m > zero ? m : zero;
  const Lanes2 sq = g * g;
  const double e1 = blo[2] - ahi[2], e2 = alo[2] - bhi[2];
  const double mz = e1 > e2 ? e1 : e2;
  const double gz = mz > 0.0 ? mz : 0.0;
  return (sq[0] + sq[1]) + gz * gz;
}

inline double box_gap2(const Vec3& alo, const Vec3& ahi, const double blo[3], const double bhi[3]) {
  const double a_lo[3] = {alo.x, alo.y, alo.z}, a_hi[3] = {ahi.x, ahi.y, ahi.z};
  return box_gap2(a_lo, a_hi, blo, bhi);
}

// A lower bound on the distance between triangles t and o (to rounding): how far o's corners
// all lie on one side of t's plane, along t's (computed, unnormalised) normal u. Exact for any
// u, the bound's own rounding is that of a few dot products of u with coordinates at most M in
// magnitude: under 32 eps M, far below the caller's margin 2^-40 (M + 1) when M <= 2^200 (no
// overflow). 0 for a degenerate t or corners on both sides.
inline double separation(const Vec3 t[3], const Vec3 o[3]) {
  const Vec3 u = cross(t[1] - t[0], t[2] - t[0]);
  const double norm = std::sqrt(dot(u, u));
  if (!(norm > 0x1p-500)) return 0;  // degenerate, or a normal too short to divide by
  const double c = dot(u, t[0]);
  const double v0 = dot(u, o[0]) - c, v1 = dot(u, o[1]) - c, v2 = dot(u, o[2]) - c;
  if (v0 > 0 && v1 > 0 && v2 > 0)
    return (v0 < v1 ? (v0 < v2 ? v0 : v2) : (v1 < v2 ? v1 : v2)) / norm;
  if (v0 < 0 && v1 < 0 && v2 < 0)
    return -(v0 > v1 ? (v0 > v2 ? v0 : v2) : (v1 > v2 ? v1 : v2)) / norm;
  return 0;
}

// box_gap2 for a triangle's float box (DistanceIndex::triangle_boxes) moved by `shift`.
inline double float_box_gap2(const float* box, const Vec3& shift, const double blo[3],
                             const double bhi[3]) {
  const double lo[3] = {static_cast<double>(box[0]) + shift.x,
                        static_cast<double>(box[1]) + shift.y,
                        static_cast<double>(box[2]) + shift.z};
  const double hi[3] = {static_cast<double>(box[3]) + shift.x,
                        static_cast<double>(box[4]) + shift.y,
                        static_cast<double>(box[5]) + shift.z};
  return box_gap2(lo, hi, blo, bhi);
}

// A box [lo, hi] of B moved rigidly: the box of the moved box (its centre moved, its
// half-extents through |R|), widened by 2^-40 (M + 1), M its largest coordinate, over the
// rounding of the moved triangles' corners (apply_point: a few ulps of M) and of this
// computation. A looser box only prunes less: the answer is the same.
inline void moved_box(const RigidTransform& m, const double lo[3], const double hi[3],
                      double out_lo[3], double out_hi[3]) {
  const Vec3 c{0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2])};
  const double h[3] = {0.5 * (hi[0] - lo[0]), 0.5 * (hi[1] - lo[1]), 0.5 * (hi[2] - lo[2])};
  const Vec3 mc = m.apply_point(c);
  double mh[3], big = 0;
  for (int i = 0; i < 3; ++i) {
    mh[i] = std::fabs(m.r[i][0]) * h[0] + std::fabs(m.r[i][1]) * h[1] + std::fabs(m.r[i][2]) * h[2];
    const double extent = std::fabs(mc[i]) + mh[i];
    big = extent > big ? extent : big;
  }
  const double margin = (big + 1.0) * 0x1p-40;
  for (int i = 0; i < 3; ++i) {
    out_lo[i] = mc[i] - mh[i] - margin;
    out_hi[i] = mc[i] + mh[i] + margin;
  }
}

inline void load_moved_triangle(const Mesh& mesh, uint32_t t, const RigidTransform& move,
                                TriangleBox* out) {
  const Triangle& tri = mesh.triangles[t];
  for (int k = 0; k < 3; ++k) out->p[k] = move.apply_point(mesh.vertices[tri.v[k]]);
  out->lo = min_vec(min_vec(out->p[0], out->p[1]), out->p[2]);
  out->hi = max_vec(max_vec(out->p[0], out->p[1]), out->p[2]);
}

// Up to 16 boxes, lane k % 2 of pair k / 2, and their gaps to one box: box_gap2(lo, hi, box k)
// bit for bit, two at a time. A lane's gap on an axis is max(max(blo - ahi, alo - bhi), 0):
// for boxes with lo <= hi at most one difference is positive, and positive exactly when
// box_gap2 takes it (x > y if and only if x - y > 0 in IEEE arithmetic); a zero of either
// sign squares to +0. The sum in box_gap2's order: (0 + gx^2) + gy^2 + gz^2, and 0 + gx^2 is
// gx^2.
struct BoxLanes {
  Lanes2 lo[3][8], hi[3][8];

  void set(uint32_t k, const Vec3& l, const Vec3& h) {
    lo[0][k / 2][k % 2] = l.x;
    lo[1][k / 2][k % 2] = l.y;
    lo[2][k / 2][k % 2] = l.z;
    hi[0][k / 2][k % 2] = h.x;
    hi[1][k / 2][k % 2] = h.y;
    hi[2][k / 2][k % 2] = h.z;
  }
  // gap2[k] for k < count (lanes past count, up to an even count, hold finite boxes).
  void gaps_to(const Vec3& alo, const Vec3& ahi, uint32_t count, double gap2[16]) const {
    const Lanes2 zero = {0.0, 0.0};
    const Lanes2 al[3] = {{alo.x, alo.x}, {alo.y, alo.y}, {alo.z, alo.z}};
    const Lanes2 ah[3] = {{ahi.x, ahi.x}, {ahi.y, ahi.y}, {ahi.z, ahi.z}};
    for (uint32_t p = 0; 2 * p < count; ++p) {
      Lanes2 g[3];
      for (int i = 0; i < 3; ++i) {
        const Lanes2 d1 = lo[i][p] - ah[i], d2 = al[i] - hi[i][p];
        const Lanes2 m = d1 > d2 ? d1 : d2;
        g[i] = m > zero ? m : zero;
      }
      const Lanes2 sum = (g[0] * g[0] + g[1] * g[1]) + g[2] * g[2];
      gap2[2 * p] = sum[0];
      gap2[2 * p + 1] = sum[1];
    }
  }
};

// Two floats (a triangle's float box's x and y), converted to a Lanes2 at once.
typedef float Floats2 __attribute__((vector_size(8)));

// float_box_gap2(boxes + 6 k, shift, blo, bhi) for k < count (at most 16), bit for bit: a
// box's x and y a lane pair (each converted, shifted and subtracted as the scalar code does,
// two floats converted in one instruction), its z alone; a lane's gap on an axis is
// max(max(blo - hi, lo - bhi), 0) as in BoxLanes::gaps_to (a triangle's box, shifted, has
// lo <= hi: rounding is monotone; so has [blo, bhi]), and the sum in box_gap2's order
// (gx^2 + gy^2) + gz^2.
void float_box_gaps(const float* boxes, uint32_t count, const Vec3& shift, const double blo[3],
                    const double bhi[3], double gap2[16]) {
  const Lanes2 zero = {0.0, 0.0};
  const Lanes2 sxy = {shift.x, shift.y};
  const Lanes2 bl = {blo[0], blo[1]}, bh = {bhi[0], bhi[1]};
  for (uint32_t k = 0; k < count; ++k) {
    const float* a = boxes + 6 * size_t{k};
    Floats2 flo, fhi;
    std::memcpy(&flo, a, sizeof flo);
    std::memcpy(&fhi, a + 3, sizeof fhi);
    const Lanes2 lo = __builtin_convertvector(flo, Lanes2) + sxy;
    const Lanes2 hi = __builtin_convertvector(fhi, Lanes2) + sxy;
    const Lanes2 d1 = bl - hi, d2 = lo - bh;
    const Lanes2 m = d1 > d2 ? d1 : d2;
    const Lanes2 g = m > zero ? m : zero;
    const Lanes2 sq = g * g;
    const double lz = static_cast<double>(a[2]) + shift.z;
    const double hz = static_cast<double>(a[5]) + shift.z;
    const double e1 = blo[2] - hz, e2 = lz - bhi[2];
    const double mz = e1 > e2 ? e1 : e2;
    const double gz = mz > 0.0 ? mz : 0.0;
    gap2[k] = (sq[0] + sq[1]) + gz * gz;
  }
}

// The bits of the least float at least b (b >= 0 or +inf; beyond the floats' range: +inf).
inline uint32_t float_bits_at_least(double b) {
  const float f = b <= 3.4028234663852886e38 ? static_cast<float>(b) : HUGE_VALF;
  uint32_t bits = 0;
  std::memcpy(&bits, &f, sizeof bits);
  return static_cast<double>(f) < b ? bits + 1 : bits;  // the next float up
}

inline double float_of_bits(uint32_t bits) {
  float f = 0;
  std::memcpy(&f, &bits, sizeof f);
  return static_cast<double>(f);
}

struct PairSearch {
  const DistanceIndex* index[2] = {nullptr, nullptr};
  const float* triangle_boxes[2] = {nullptr, nullptr};  // or null: none in the index
  Vec3 shift[2];
  // B moved by `move` instead of shift[1] (mesh_pair_distance_rigid and its kin): its boxes
  // through moved_box, its triangles' corners through apply_point.
  bool rigid = false;
  RigidTransform move;
  PairEntry* stack = nullptr;
  uint64_t top = 0, capacity = 0;
  PairEntry* heap = nullptr;  // heap_capacity
  uint32_t heap_size = 0, heap_capacity = kHeapEntries;
  // The best pair so far by (best2, triangle a, triangle b); before any, best2 is the limit.
  double best2 = HUGE_VAL;
  bool found = false, meet = false;
  uint32_t best_a = 0, best_b = 0;
  double slack = 0;          // absolute rounding margin (mm)
  double reach2 = HUGE_VAL;  // boxes farther than this (squared, as computed) are pruned
  double reach = HUGE_VAL;   // its square root (rounded up): for separations along a normal
  // Bounds the rounding of a computed separation along a triangle's normal (see separation());
  // +inf when the coordinates are so large that the products could overflow: no such test.
  double separation_margin = HUGE_VAL;
  // Collecting (mesh_pair_distance_collect): the reach stays that of the limit, and every pair
  // not pruned by it and within it goes to `collected` (counted past its capacity).
  bool collecting = false;
  TrianglePairIds* collected = nullptr;
  size_t collect_capacity = 0, collect_count = 0;
  // Stopping at the first meeting pair (mesh_pair_meet): `done` once one is found.
  bool first_meet = false, done = false;
  // A task of a split search (run_split): the least best2 of all its tasks so far, rounded up
  // to a float and kept as its bits (non-negative: their order is the floats' order; 32 bits,
  // lock-free on every target, ARMv7-M too), which every task prunes by (the reach of a bound
  // on a best found elsewhere: it prunes only pairs that cannot win either).
  std::atomic<uint32_t>* shared = nullptr;
  double reach_from = HUGE_VAL;  // the best2 that reach was computed from

  // reach2 from best2: a pair of boxes whose computed distance is at most reach may hold a
  // pair whose computed distance is at most best. Box gaps round by a few ulps; a triangle
  // pair's computed distance is that of two points within rounding of the triangles (off by a
  // few ulps of the coordinates): 2^-19 relative and 2^-30 (|x|_max + 1) absolute cover both
  // with a wide berth, and prune nothing that matters.
  void update_reach() {
    if (collecting) return;
    set_reach(shared != nullptr ? share(best2) : best2);
  }
  void set_reach(double b) {
    reach_from = b;
    if (!(b < HUGE_VAL)) {
      reach2 = reach = HUGE_VAL;
      return;
    }
    reach = (std::sqrt(b) + slack) * (1.0 + 0x1p-19);
    reach2 = reach * reach;
  }
  // Publishes b to the tasks' shared best (when less): the least of b and the shared bound.
  double share(double b) {
    const uint32_t bits = float_bits_at_least(b);
    uint32_t seen = shared->load(std::memory_order_relaxed);
    while (bits < seen && !shared->compare_exchange_weak(seen, bits, std::memory_order_relaxed)) {
    }
    const double other = float_of_bits(seen);
    return other < b ? other : b;
  }
  // A task's reach from a better best found by another task.
  void refresh() {
    if (shared == nullptr || collecting) return;
    const double b = float_of_bits(shared->load(std::memory_order_relaxed));
    if (b < reach_from) set_reach(b);
  }

  // The box of an item (not the root) in double, shifted (or moved) for B.
  void item_box(int side, uint32_t node, uint8_t slot, double lo[3], double hi[3]) const {
    const BvhNode& n = index[side]->nodes[node];
    if (side == 1 && rigid) {
      const double l[3] = {static_cast<double>(n.lo[0][slot]), static_cast<double>(n.lo[1][slot]),
                           static_cast<double>(n.lo[2][slot])};
      const double h[3] = {static_cast<double>(n.hi[0][slot]), static_cast<double>(n.hi[1][slot]),
                           static_cast<double>(n.hi[2][slot])};
      moved_box(move, l, h, lo, hi);
      return;
    }
    for (int i = 0; i < 3; ++i) {
      lo[i] = static_cast<double>(n.lo[i][slot]) + shift[side][i];
      hi[i] = static_cast<double>(n.hi[i][slot]) + shift[side][i];
    }
  }

  // Triangle t of a side, in its place.
  void load(int side, uint32_t t, TriangleBox* out) const {
    if (side == 1 && rigid) {
      load_moved_triangle(*index[1]->mesh, t, move, out);
    } else {
      load_triangle(*index[side]->mesh, t, shift[side], out);
    }
  }

  // float_box_gap2 for a triangle's float box of a side, in its place.
  double triangle_box_gap2(int side, const float* box, const double blo[3],
                           const double bhi[3]) const {
    if (side == 1 && rigid) {
      const double l[3] = {static_cast<double>(box[0]), static_cast<double>(box[1]),
                           static_cast<double>(box[2])};
      const double h[3] = {static_cast<double>(box[3]), static_cast<double>(box[4]),
                           static_cast<double>(box[5])};
      double lo[3], hi[3];
      moved_box(move, l, h, lo, hi);
      return box_gap2(lo, hi, blo, bhi);
    }
    return float_box_gap2(box, shift[side], blo, bhi);
  }

  bool is_leaf(int side, uint32_t node, uint8_t slot) const {
    return slot != kRootSlot && index[side]->nodes[node].count[slot] != 0;
  }

  void consider(uint32_t ta, uint32_t tb, const TriangleBox& x, const TriangleBox& y);
  void collect(uint32_t ta, uint32_t tb, const TriangleBox& x, const TriangleBox& y);
  void leaf_pair(const PairEntry& e);
  uint32_t children(const PairEntry& e, PairEntry found_pairs[16]) const;
  bool depth_first(const PairEntry& first);
  void heap_push(const PairEntry& e);
  PairEntry heap_pop();
  bool run();
  bool drain(uint32_t frontier, bool* finished);
};

inline bool pair_less(uint32_t a0, uint32_t b0, uint32_t a1, uint32_t b1) {
  return a0 < a1 || (a0 == a1 && b0 < b1);
}

// Triangle ta of A against tb of B (moved), boxes within reach.
void PairSearch::consider(uint32_t ta, uint32_t tb, const TriangleBox& x, const TriangleBox& y) {
  if (collecting) {
    collect(ta, tb, x, y);
    return;
  }
  const bool smaller = !found || pair_less(ta, tb, best_a, best_b);
  // At distance 0 only a smaller pair can win (and only by meeting or by a distance of 0).
  if (best2 == 0 && !smaller) return;
  // Triangles whose planes keep them apart by more than reach: their computed distance exceeds
  // best2 (the reasoning of update_reach()), and they do not meet. Near-parallel surfaces
  // leave many such pairs within reach of each other's boxes.
  if (separation(x.p, y.p) - separation_margin > reach ||
      separation(y.p, x.p) - separation_margin > reach) {
    return;
  }
  // Meeting is worth testing only if (0, ta, tb) would win, and possible only if the boxes
  // overlap (exactly: these are the moved coordinates themselves).
  if ((best2 > 0 || smaller) && x.lo.x <= y.hi.x && y.lo.x <= x.hi.x && x.lo.y <= y.hi.y &&
      y.lo.y <= x.hi.y && x.lo.z <= y.hi.z && y.lo.z <= x.hi.z && triangles_meet(x.p, y.p)) {
    best2 = 0;
    found = meet = true;
    best_a = ta;
    best_b = tb;
    done = first_meet;
    update_reach();
    return;
  }
  Vec3 pa, pb;
  const double d2 = separated_pair_d2(x.p, y.p, &pa, &pb);
  if (d2 < best2 || (d2 == best2 && smaller)) {
    best2 = d2;
    found = true;
    meet = false;
    best_a = ta;
    best_b = tb;
    update_reach();
  }
}

// consider() with the reach fixed: the pair's key (0 when the triangles meet, else the
// computed squared distance) in full, the pair kept when within reach, and the best by
// (key, ta, tb) as consider() would leave it.
void PairSearch::collect(uint32_t ta, uint32_t tb, const TriangleBox& x, const TriangleBox& y) {
  if (separation(x.p, y.p) - separation_margin > reach ||
      separation(y.p, x.p) - separation_margin > reach) {
    return;
  }
  const bool boxes_meet = x.lo.x <= y.hi.x && y.lo.x <= x.hi.x && x.lo.y <= y.hi.y &&
                          y.lo.y <= x.hi.y && x.lo.z <= y.hi.z && y.lo.z <= x.hi.z;
  const bool meets = boxes_meet && triangles_meet(x.p, y.p);
  double d2 = 0;
  if (!meets) {
    Vec3 pa, pb;
    d2 = separated_pair_d2(x.p, y.p, &pa, &pb);
    if (d2 > reach2) return;
  }
  if (collect_count < collect_capacity) collected[collect_count] = TrianglePairIds{ta, tb};
  if (collect_count <= collect_capacity) ++collect_count;
  const bool smaller = !found || pair_less(ta, tb, best_a, best_b);
  if (d2 < best2 || (d2 == best2 && smaller)) {
    best2 = d2;
    found = true;
    meet = meets;
    best_a = ta;
    best_b = tb;
  }
}

// Every triangle pair of two leaves whose boxes are within reach. A triangle is kept only if
// its box is within reach of the other leaf's box (which holds the other triangles' boxes:
// rounding is monotone, so its computed gap is no larger), and A's triangles face the box of
// B's kept ones: the same pairs reach consider() as when testing all of them, for a fraction
// of the box tests and none of the pairs of far triangles.
void PairSearch::leaf_pair(const PairEntry& e) {
  const BvhNode& na = index[0]->nodes[e.node_a];
  const BvhNode& nb = index[1]->nodes[e.node_b];
  const uint32_t a_first = na.child[e.slot_a], a_count = na.count[e.slot_a];
  const uint32_t b_first = nb.child[e.slot_b], b_count = nb.count[e.slot_b];
  double alo[3], ahi[3];
  item_box(0, e.node_a, e.slot_a, alo, ahi);
  // Not value-initialised (Vec3's zeros, 2 kB a leaf pair): each slot is written before it
  // is read.
  union Slots {
    Slots() {}
    TriangleBox box[16];
  } slots;
  TriangleBox* bs = slots.box;
  // The kept boxes' coordinates again, two boxes a lane pair (Lanes2), for gaps_to().
  BoxLanes lanes;
  uint32_t b_ids[16], kept = 0;
  Vec3 b_lo{HUGE_VAL, HUGE_VAL, HUGE_VAL}, b_hi{-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
  // With the triangles' float boxes (pairs_only), a triangle whose float box is out of reach
  // is not loaded: that box holds the triangle's, so its computed gap is no larger (rounding
  // is monotone) and the exact test below would drop it too. The same pairs go on.
  const float* a_boxes = triangle_boxes[0];
  const float* b_boxes = triangle_boxes[1];
  // The float boxes' gaps first (float_box_gaps, bit for bit), then each tested against
  // reach2 as it is at its turn (consider() may lower it while A's triangles go by).
  // (Without float boxes every gap is 0: nothing is dropped here.)
  double box_gaps[16];
  if (b_boxes == nullptr) {
    for (uint32_t j = 0; j < b_count; ++j) box_gaps[j] = 0.0;
  } else if (rigid) {
    for (uint32_t j = 0; j < b_count; ++j) {
      box_gaps[j] = triangle_box_gap2(1, b_boxes + 6 * size_t{b_first + j}, alo, ahi);
    }
  } else {
    float_box_gaps(b_boxes + 6 * size_t{b_first}, b_count, shift[1], alo, ahi, box_gaps);
  }
  for (uint32_t j = 0; j < b_count; ++j) {
    if (b_boxes != nullptr && box_gaps[j] > reach2) continue;
    const uint32_t tb = index[1]->order[b_first + j];
    load(1, tb, &bs[kept]);
    if (box_gap2(bs[kept].lo, bs[kept].hi, alo, ahi) > reach2) continue;
    b_lo = min_vec(b_lo, bs[kept].lo);
    b_hi = max_vec(b_hi, bs[kept].hi);
    lanes.set(kept, bs[kept].lo, bs[kept].hi);
    b_ids[kept++] = tb;
  }
  if (kept == 0) return;
  if (kept % 2 != 0) lanes.set(kept, bs[kept - 1].lo, bs[kept - 1].hi);  // finite padding
  const double blo[3] = {b_lo.x, b_lo.y, b_lo.z}, bhi[3] = {b_hi.x, b_hi.y, b_hi.z};
  if (a_boxes != nullptr) {
    float_box_gaps(a_boxes + 6 * size_t{a_first}, a_count, shift[0], blo, bhi, box_gaps);
  }
  for (uint32_t i = 0; i < a_count; ++i) {
    if (a_boxes != nullptr && box_gaps[i] > reach2) continue;
    const uint32_t ta = index[0]->order[a_first + i];
    TriangleBox x;
    load_triangle(*index[0]->mesh, ta, shift[0], &x);
    if (box_gap2(x.lo, x.hi, blo, bhi) > reach2) continue;
    // Every gap first (each box_gap2's bits), then each tested against reach2 as it is when
    // that pair's turn comes (consider() may lower it): the same pairs go on.
    double gap2[16];
    lanes.gaps_to(x.lo, x.hi, kept, gap2);
    for (uint32_t j = 0; j < kept; ++j) {
      if (gap2[j] > reach2) continue;
      consider(ta, b_ids[j], x, bs[j]);
      if (done) return;
    }
  }
}

// The pairs of an entry's items' children (an inner item stands for its node's children, a
// leaf for itself) within reach, at most 16, by decreasing box distance: their number.
uint32_t PairSearch::children(const PairEntry& e, PairEntry found_pairs[16]) const {
  uint32_t nodes[2][4];
  uint8_t slots[2][4];
  uint32_t counts[2] = {0, 0};
  const uint32_t parent[2] = {e.node_a, e.node_b};
  const uint8_t slot[2] = {e.slot_a, e.slot_b};
  for (int s = 0; s < 2; ++s) {
    if (is_leaf(s, parent[s], slot[s])) {
      nodes[s][0] = parent[s];
      slots[s][0] = slot[s];
      counts[s] = 1;
      continue;
    }
    const uint32_t n = slot[s] == kRootSlot ? 0 : index[s]->nodes[parent[s]].child[slot[s]];
    for (uint8_t k = 0; k < 4; ++k) {
      if (index[s]->nodes[n].child[k] == kNoChild) continue;
      nodes[s][counts[s]] = n;
      slots[s][counts[s]++] = k;
    }
  }
  uint32_t m = 0;
  double blo[4][3], bhi[4][3];
  for (uint32_t j = 0; j < counts[1]; ++j) item_box(1, nodes[1][j], slots[1][j], blo[j], bhi[j]);
  for (uint32_t i = 0; i < counts[0]; ++i) {
    double alo[3], ahi[3];
    item_box(0, nodes[0][i], slots[0][i], alo, ahi);
    for (uint32_t j = 0; j < counts[1]; ++j) {
      const double lb2 = box_gap2(alo, ahi, blo[j], bhi[j]);
      if (lb2 > reach2) continue;
      const PairEntry p{
          nodes[0][i], nodes[1][j], slots[0][i], slots[1][j], centre_gap2(alo, ahi, blo[j], bhi[j]),
          lb2};
      uint32_t at = m++;
      while (at > 0 && pair_before(found_pairs[at - 1], p)) {
        found_pairs[at] = found_pairs[at - 1];
        --at;
      }
      found_pairs[at] = p;
    }
  }
  return m;
}

// Examines the entry and every pair below it within reach, depth first (the nearest child
// pair first). False when the stack is full (a depth field that does not match the tree).
bool PairSearch::depth_first(const PairEntry& first) {
  stack[top++] = first;
  while (top > 0) {
    const PairEntry e = stack[--top];
    refresh();
    if (e.lb2 > reach2) continue;
    if (is_leaf(0, e.node_a, e.slot_a) && is_leaf(1, e.node_b, e.slot_b)) {
      leaf_pair(e);
      if (done) return true;
      continue;
    }
    PairEntry found_pairs[16];
    const uint32_t m = children(e, found_pairs);
    if (top + m > capacity) return false;
    for (uint32_t k = 0; k < m; ++k) stack[top++] = found_pairs[k];  // the nearest on top
  }
  return true;
}

void PairSearch::heap_push(const PairEntry& e) {
  uint32_t at = heap_size++;
  while (at > 0 && pair_before(e, heap[(at - 1) / 2])) {
    heap[at] = heap[(at - 1) / 2];
    at = (at - 1) / 2;
  }
  heap[at] = e;
}

PairEntry PairSearch::heap_pop() {
  const PairEntry top_entry = heap[0], last = heap[--heap_size];
  uint32_t at = 0;
  for (;;) {
    uint32_t child = 2 * at + 1;
    if (child >= heap_size) break;
    if (child + 1 < heap_size && pair_before(heap[child + 1], heap[child])) ++child;
    if (!pair_before(heap[child], last)) break;
    heap[at] = heap[child];
    at = child;
  }
  if (heap_size > 0) heap[at] = last;
  return top_entry;
}

// Best first: the pair of least box distance next, so that the best, and with it the reach,
// shrinks as early as it can. The heap is bounded: a pair that finds it full is examined depth
// first at once (the answer does not depend on the order, only the work does).
bool PairSearch::run() {
  heap_push(PairEntry{0, 0, kRootSlot, kRootSlot, 0.0f, 0.0});
  bool finished = false;
  return drain(~uint32_t{0}, &finished);
}

// The best-first loop over the heap as it is, until it is empty or holds `frontier` pairs
// (then *finished is false). False when the stack is full (see depth_first).
bool PairSearch::drain(uint32_t frontier, bool* finished) {
  *finished = false;
  while (heap_size > 0) {
    if (heap_size >= frontier) return true;
    refresh();
    const PairEntry e = heap_pop();
    if (e.lb2 > reach2) break;  // and so are all the others
    if (is_leaf(0, e.node_a, e.slot_a) && is_leaf(1, e.node_b, e.slot_b)) {
      leaf_pair(e);
      if (done) break;
      continue;
    }
    PairEntry found_pairs[16];
    const uint32_t m = children(e, found_pairs);
    for (uint32_t k = m; k-- > 0;) {
      if (heap_size < heap_capacity) {
        heap_push(found_pairs[k]);
      } else if (!depth_first(found_pairs[k])) {
        return false;
      }
      if (done) {
        *finished = true;
        return true;
      }
    }
  }
  heap_size = 0;
  *finished = true;
  return true;
}

inline uint64_t stack_entries(const DistanceIndex& a, const DistanceIndex& b) {
  // Each expansion pops one pair and pushes at most 16, and goes one level down in at least one
  // tree: a chain of expansions is at most a.depth + b.depth long.
  return 15 * (uint64_t{a.depth} + b.depth) + 1;
}

// The largest coordinate magnitude of a tree's root boxes, shifted (or moved: `move`).
double root_magnitude(const DistanceIndex& index, const Vec3& shift,
                      const RigidTransform* move = nullptr) {
  const BvhNode& root = index.nodes[0];
  double m = 0;
  for (int k = 0; k < 4; ++k) {
    if (root.child[k] == kNoChild) continue;
    double l[3], h[3];
    for (int i = 0; i < 3; ++i) {
      l[i] = static_cast<double>(root.lo[i][k]) + shift[i];
      h[i] = static_cast<double>(root.hi[i][k]) + shift[i];
    }
    if (move != nullptr) moved_box(*move, l, h, l, h);
    for (int i = 0; i < 3; ++i) {
      const double lo = std::fabs(l[i]);
      const double hi = std::fabs(h[i]);
      m = lo > m ? lo : m;
      m = hi > m ? hi : m;
    }
  }
  return m;
}

// The closest pair's points, recomputed from its two triangles as triangle_pair_distance()
// does (the same bits).
void finish(const PairSearch& s, MeshPairDistance* out) {
  TriangleBox x, y;
  s.load(0, s.best_a, &x);
  s.load(1, s.best_b, &y);
  out->triangle_a = s.best_a;
  out->triangle_b = s.best_b;
  out->intersecting = s.meet;
  if (s.meet) {
    out->distance = 0;
    out->point_a = out->point_b = common_point(x.p, y.p);
    return;
  }
  (void)separated_pair_d2(x.p, y.p, &out->point_a, &out->point_b);
  out->distance = std::sqrt(s.best2);
}

}  // namespace

// Parallel segments (denominator 0) start from s = 0 and clamp from there, which reaches a
// closest pair; nearly parallel ones lose accuracy in s only along a direction in which the
// distance barely changes (the error in the squared distance is of order eps^2 / sin^2).
double segment_closest(const Vec3& p0, const Vec3& p1, const Vec3& q0, const Vec3& q1, Vec3* cp,
                       Vec3* cq) {
  const Vec3 d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
  const double a = dot(d1, d1), e = dot(d2, d2), f = dot(d2, r);
  double s = 0, t = 0;
  if (a > 0 && e > 0) {
    const double b = dot(d1, d2), c = dot(d1, r);
    const double denom = a * e - b * b;
    s = denom > 0 ? clamp01((b * f - c * e) / denom) : 0.0;
    t = (b * s + f) / e;
    if (t < 0) {
      t = 0;
      s = clamp01(-c / a);
    } else if (t > 1) {
      t = 1;
      s = clamp01((b - c) / a);
    }
  } else if (a > 0) {
    s = clamp01(-dot(d1, r) / a);
  } else if (e > 0) {
    t = clamp01(f / e);
  }
  *cp = along(p0, p1, d1, s);
  *cq = along(q0, q1, d2, t);
  return length_squared(*cp - *cq);
}

double triangle_pair_distance(const Vec3& a0, const Vec3& a1, const Vec3& a2, const Vec3& b0,
                              const Vec3& b1, const Vec3& b2, Vec3* pa, Vec3* pb) {
  const Vec3 a[3] = {a0, a1, a2}, b[3] = {b0, b1, b2};
  Vec3 x, y;
  double d = 0;
  if (triangles_meet(a, b)) {
    x = y = common_point(a, b);
  } else {
    d = std::sqrt(separated_pair_d2(a, b, &x, &y));
  }
  if (pa != nullptr) *pa = x;
  if (pb != nullptr) *pb = y;
  return d;
}

// A search on an executor of more than one thread is split (run_split): the serial best-first
// start until its heap holds kSplitFrontier pairs, then those pairs dealt to kSplitTasks tasks
// (pair i to task i % kSplitTasks), each with its own heap of kTaskHeapEntries and stack, its
// own best and pool slice, and the shared best's reach. The answer is the least (squared
// distance, triangle a, triangle b) of the start's and the tasks' bests: no task prunes a pair
// that could win (the reach of a best found anywhere is at least the final best's), so the
// pair that wins the serial search is examined by the task that holds it, and wins there. The
// same bits as the serial search, at every thread count; only the work depends on the timing.
constexpr uint32_t kSplitTasks = 8;
constexpr uint32_t kSplitFrontier = 32;
constexpr uint32_t kTaskHeapEntries = 256;
static_assert((kSplitFrontier + 15) / kSplitTasks + 1 <= kTaskHeapEntries, "the frontier fits");

uint64_t mesh_pair_distance_bound(const DistanceIndex& a, const DistanceIndex& b) {
  return arena_array_bound<PairEntry>(stack_entries(a, b)) +
         arena_array_bound<PairEntry>(kHeapEntries) +
         kSplitTasks * (arena_array_bound<PairEntry>(stack_entries(a, b)) +
                        arena_array_bound<PairEntry>(kTaskHeapEntries));
}

namespace {

// The checks and the search's set-up common to the entry points (no arena taken); *empty when
// a mesh has no triangle (no search: nothing is within any distance).
// `move_b` (or null): B moved rigidly instead of by offset_b.
Status start_search(const DistanceIndex& a, const DistanceIndex& b, const Vec3& offset_b,
                    double max_distance, PairSearch* s, bool* empty,
                    const RigidTransform* move_b = nullptr) {
  if (!is_finite(offset_b)) {
    return Status::error(StatusCode::kInvalidArgument, "mesh pair distance: offset not finite");
  }
  if (move_b != nullptr) {
    bool finite = is_finite(move_b->t);
    for (int i = 0; i < 3; ++i) {
      finite = finite && is_finite(Vec3{move_b->r[i][0], move_b->r[i][1], move_b->r[i][2]});
    }
    if (!finite) {
      return Status::error(StatusCode::kInvalidArgument,
                           "mesh pair distance: the rigid move is not finite");
    }
    s->rigid = true;
    s->move = *move_b;
  }
  if (!(max_distance >= 0)) {
    return Status::error(StatusCode::kInvalidArgument,
                         "mesh pair distance: max_distance must be >= 0 (+inf for no limit)");
  }
  *empty = a.mesh->triangles.size() == 0 || b.mesh->triangles.size() == 0;
  if (*empty) return Status::ok();
  s->index[0] = &a;
  s->index[1] = &b;
  s->triangle_boxes[0] = a.triangle_boxes.empty() ? nullptr : a.triangle_boxes.data();
  s->triangle_boxes[1] = b.triangle_boxes.empty() ? nullptr : b.triangle_boxes.data();
  s->shift[1] = offset_b;
  const double ma = root_magnitude(a, s->shift[0]), mb = root_magnitude(b, s->shift[1], move_b);
  const double magnitude = ma > mb ? ma : mb;
  s->slack = (magnitude + 1.0) * 0x1p-30;
  if (magnitude <= 0x1p200) s->separation_margin = (magnitude + 1.0) * 0x1p-40;
  s->best2 = max_distance * max_distance;
  s->update_reach();
  return Status::ok();
}

// Whether x's best is before y's: (best2, best_a, best_b), a search with none last.
bool best_before(const PairSearch& x, const PairSearch& y) {
  if (!x.found || !y.found) return x.found;
  if (x.best2 != y.best2) return x.best2 < y.best2;
  return pair_less(x.best_a, x.best_b, y.best_a, y.best_b);
}

// The rest of s's search (its heap: the frontier) in kSplitTasks tasks on `executor`, their
// stacks and heaps in the arena; then s holds the least best (and, collecting, every task's
// pairs after its own, in task order). False when a stack is full. When the arena does not
// hold the tasks' stacks and heaps: *no_room, the arena as it was (its failure forgotten) and
// s untouched, to go on serially. *overflow: a task's slice of the pool overflowed (the
// caller searches again serially: the pool may hold them all).
bool run_split(Arena& arena, const Executor* executor, PairSearch* s, bool* no_room,
               bool* slice_overflow) {
  *no_room = *slice_overflow = false;
  const Arena::Marker start = arena.mark();
  PairSearch tasks[kSplitTasks];
  std::atomic<uint32_t> shared{float_bits_at_least(s->best2)};
  // The pool's room after the start's pairs, in equal slices.
  const size_t used =
      s->collect_count < s->collect_capacity ? s->collect_count : s->collect_capacity;
  const size_t slice = s->collecting ? (s->collect_capacity - used) / kSplitTasks : 0;
  for (uint32_t i = 0; i < kSplitTasks; ++i) {
    PairSearch& t = tasks[i];
    t = *s;
    t.stack = arena.allocate_array<PairEntry>(static_cast<size_t>(s->capacity));
    t.heap = arena.allocate_array<PairEntry>(kTaskHeapEntries);
    if (t.stack == nullptr || t.heap == nullptr) {
      arena.rewind(start);
      arena.forget_failure();
      *no_room = true;
      return true;
    }
    t.top = 0;
    t.heap_size = 0;
    t.heap_capacity = kTaskHeapEntries;
    t.shared = &shared;
    t.reach_from = HUGE_VAL;
    t.update_reach();
    if (s->collecting) {
      t.collected = s->collected + used + i * slice;
      t.collect_capacity = slice;
      t.collect_count = 0;
    }
  }
  for (uint32_t k = 0; k < s->heap_size; ++k) {
    PairSearch& t = tasks[k % kSplitTasks];
    t.heap_push(s->heap[k]);
  }
  s->heap_size = 0;
  bool ok[kSplitTasks];
  auto task = [&](uint32_t i) {
    bool finished = false;
    ok[i] = tasks[i].drain(~uint32_t{0}, &finished);
  };
  parallel_for_each(executor, kSplitTasks, task);
  bool overflow = s->collect_count > s->collect_capacity;
  size_t at = used;
  for (uint32_t i = 0; i < kSplitTasks; ++i) {
    const PairSearch& t = tasks[i];
    if (!ok[i]) return false;
    if (best_before(t, *s)) {
      s->best2 = t.best2;
      s->found = t.found;
      s->meet = t.meet;
      s->best_a = t.best_a;
      s->best_b = t.best_b;
    }
    if (!s->collecting) continue;
    if (t.collect_count > t.collect_capacity && !overflow) *slice_overflow = true;
    if (overflow || *slice_overflow) continue;
    std::memmove(s->collected + at, t.collected, t.collect_count * sizeof(TrianglePairIds));
    at += t.collect_count;
  }
  if (s->collecting) s->collect_count = overflow || *slice_overflow ? s->collect_capacity + 1 : at;
  return true;
}

// The traversal with its stack and heap in the arena (returned), then the answer. Split on an
// executor of more than one thread (run_split) where the arena holds the tasks' stacks and
// heaps too, except the search for the first meeting pair (whose pair depends on the order).
Status run_search(const Context& ctx, PairSearch* s, MeshPairDistance* out) {
  ArenaScope scope(*ctx.arena);
  s->capacity = stack_entries(*s->index[0], *s->index[1]);
  s->stack = ctx.arena->allocate_array<PairEntry>(static_cast<size_t>(s->capacity));
  s->heap = ctx.arena->allocate_array<PairEntry>(kHeapEntries);
  if (s->stack == nullptr || s->heap == nullptr) return ctx.arena->exhausted_status();
  const bool split = has_threads(ctx.executor) && !s->first_meet;
  bool ok = false;
  if (!split) {
    ok = s->run();
  } else {
    const PairSearch fresh = *s;
    s->heap_push(PairEntry{0, 0, kRootSlot, kRootSlot, 0.0f, 0.0});
    bool finished = false;
    ok = s->drain(kSplitFrontier, &finished);
    bool no_room = false, slice_overflow = false;
    if (ok && !finished) {
      ok = run_split(*ctx.arena, ctx.executor, s, &no_room, &slice_overflow);
    }
    if (ok && no_room) ok = s->drain(~uint32_t{0}, &finished);  // (the same answer)
    if (ok && slice_overflow) {
      *s = fresh;
      ok = s->run();
    }
  }
  if (!ok) {
    return Status::error(StatusCode::kInternal,
                         "mesh pair distance: the index's depth does not match its tree");
  }
  if (s->found) finish(*s, out);
  return Status::ok();
}

}  // namespace

Status mesh_pair_distance(const Context& ctx, const DistanceIndex& a, const DistanceIndex& b,
                          const Vec3& offset_b, double max_distance, MeshPairDistance* out) {
  *out = MeshPairDistance{};
  out->distance = HUGE_VAL;
  PairSearch s;
  bool empty = false;
  SPLINTCORE_RETURN_IF_ERROR(start_search(a, b, offset_b, max_distance, &s, &empty));
  if (empty) return Status::ok();
  return run_search(ctx, &s, out);
}

Status mesh_pair_distance_rigid(const Context& ctx, const DistanceIndex& a, const DistanceIndex& b,
                                const RigidTransform& move_b, double max_distance,
                                MeshPairDistance* out) {
  *out = MeshPairDistance{};
  out->distance = HUGE_VAL;
  PairSearch s;
  bool empty = false;
  SPLINTCORE_RETURN_IF_ERROR(start_search(a, b, Vec3{}, max_distance, &s, &empty, &move_b));
  if (empty) return Status::ok();
  return run_search(ctx, &s, out);
}

namespace {

// mesh_pair_distance_collect, B shifted by offset_b or moved by *move_b.
Status collect_pairs(const Context& ctx, const DistanceIndex& a, const DistanceIndex& b,
                     const Vec3& offset_b, const RigidTransform* move_b, double max_distance,
                     Span<TrianglePairIds> pairs, size_t* count, MeshPairDistance* out) {
  *out = MeshPairDistance{};
  out->distance = HUGE_VAL;
  *count = 0;
  PairSearch s;
  bool empty = false;
  SPLINTCORE_RETURN_IF_ERROR(start_search(a, b, offset_b, max_distance, &s, &empty, move_b));
  if (empty) return Status::ok();
  s.collecting = true;
  s.collected = pairs.data();
  s.collect_capacity = pairs.size();
  SPLINTCORE_RETURN_IF_ERROR(run_search(ctx, &s, out));
  *count = s.collect_count;
  return Status::ok();
}

// candidate_pair_distance, B shifted by offset_b or moved by *move_b.
Status scan_pairs(const DistanceIndex& a, const DistanceIndex& b, Span<const TrianglePairIds> pairs,
                  const Vec3& offset_b, const RigidTransform* move_b, MeshPairDistance* out) {
  *out = MeshPairDistance{};
  out->distance = HUGE_VAL;
  PairSearch s;
  bool empty = false;
  SPLINTCORE_RETURN_IF_ERROR(start_search(a, b, offset_b, HUGE_VAL, &s, &empty, move_b));
  if (empty) return Status::ok();
  const size_t na = a.mesh->triangles.size(), nb = b.mesh->triangles.size();
  TriangleBox x, y;
  uint32_t loaded_a = ~uint32_t{0};
  for (const TrianglePairIds& p : pairs) {
    if (p.a >= na || p.b >= nb) {
      return Status::error(StatusCode::kInvalidArgument,
                           "candidate pair distance: a pair's triangle is out of range");
    }
    if (p.a != loaded_a) {
      s.load(0, p.a, &x);
      loaded_a = p.a;
    }
    s.load(1, p.b, &y);
    const double lo[3] = {y.lo.x, y.lo.y, y.lo.z}, hi[3] = {y.hi.x, y.hi.y, y.hi.z};
    if (box_gap2(x.lo, x.hi, lo, hi) > s.reach2) continue;
    s.consider(p.a, p.b, x, y);
  }
  if (s.found) finish(s, out);
  return Status::ok();
}

}  // namespace

Status mesh_pair_distance_collect(const Context& ctx, const DistanceIndex& a,
                                  const DistanceIndex& b, const Vec3& offset_b, double max_distance,
                                  Span<TrianglePairIds> pairs, size_t* count,
                                  MeshPairDistance* out) {
  return collect_pairs(ctx, a, b, offset_b, nullptr, max_distance, pairs, count, out);
}

Status mesh_pair_distance_collect_rigid(const Context& ctx, const DistanceIndex& a,
                                        const DistanceIndex& b, const RigidTransform& move_b,
                                        double max_distance, Span<TrianglePairIds> pairs,
                                        size_t* count, MeshPairDistance* out) {
  return collect_pairs(ctx, a, b, Vec3{}, &move_b, max_distance, pairs, count, out);
}

Status mesh_pair_meet(const Context& ctx, const DistanceIndex& a, const DistanceIndex& b,
                      const Vec3& offset_b, bool* meet, MeshPairDistance* out) {
  *out = MeshPairDistance{};
  out->distance = HUGE_VAL;
  *meet = false;
  PairSearch s;
  bool empty = false;
  SPLINTCORE_RETURN_IF_ERROR(start_search(a, b, offset_b, 0.0, &s, &empty));
  if (empty) return Status::ok();
  s.first_meet = true;
  SPLINTCORE_RETURN_IF_ERROR(run_search(ctx, &s, out));
  *meet = s.meet;
  if (!s.meet) {  // a pair at distance 0 that does not meet: not an answer here
    *out = MeshPairDistance{};
    out->distance = HUGE_VAL;
  }
  return Status::ok();
}

Status mesh_pair_meet_rigid(const Context& ctx, const DistanceIndex& a, const DistanceIndex& b,
                            const RigidTransform& move_b, bool* meet, MeshPairDistance* out) {
  *out = MeshPairDistance{};
  out->distance = HUGE_VAL;
  *meet = false;
  PairSearch s;
  bool empty = false;
  SPLINTCORE_RETURN_IF_ERROR(start_search(a, b, Vec3{}, 0.0, &s, &empty, &move_b));
  if (empty) return Status::ok();
  s.first_meet = true;
  SPLINTCORE_RETURN_IF_ERROR(run_search(ctx, &s, out));
  *meet = s.meet;
  if (!s.meet) {
    *out = MeshPairDistance{};
    out->distance = HUGE_VAL;
  }
  return Status::ok();
}

Status candidate_pair_distance(const DistanceIndex& a, const DistanceIndex& b,
                               Span<const TrianglePairIds> pairs, const Vec3& offset_b,
                               MeshPairDistance* out) {
  return scan_pairs(a, b, pairs, offset_b, nullptr, out);
}

Status candidate_pair_distance_rigid(const DistanceIndex& a, const DistanceIndex& b,
                                     Span<const TrianglePairIds> pairs,
                                     const RigidTransform& move_b, MeshPairDistance* out) {
  return scan_pairs(a, b, pairs, Vec3{}, &move_b, out);
}

}  // namespace splintcore
