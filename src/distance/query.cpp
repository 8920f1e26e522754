// Queries on the distance index: closest point (Ericson, "Real-Time Collision Detection",
// 5.1.5, with the Voronoi region giving the feature), signed distance by angle-weighted
// pseudonormals (Baerentzen and Aanaes 2005) or by the generalised winding number (Jacobson,
// Kavan and Sorkine-Hornung, "Robust inside-outside segmentation using generalized winding
// numbers", SIGGRAPH 2013; solid angles by Van Oosterom and Strackee 1983) with the
// hierarchical far field of Barill et al. 2018, ray and segment tests, box queries, batches
// and the narrow-band volume sampler.
#include <cmath>
#include <cstring>

#include "core/fminmax.h"
#include "geometry/float_bounds.h"
#include "splintcore/distance.h"

#include "distance/morton.h"
#include "distance/query_internal.h"

namespace splintcore {

namespace {

using detail::closest_within;
using detail::settle_closest;
constexpr uint32_t kStack = detail::kTraversalStack;
constexpr double kFourPi = 12.566370614359172954;

// Four lanes of float (two of double: geometry/lanes2.h), GCC and Clang vector extensions.
typedef float Float4 __attribute__((vector_size(16)));
typedef int32_t Mask4 __attribute__((vector_size(16)));

inline Float4 load4(const float x[4]) {
  Float4 r;
  std::memcpy(&r, x, sizeof(r));
  return r;
}
// x > 0 ? x : +0 in each lane, as the scalar filters compute it (not-a-number and -0 give +0).
inline Float4 positive_part(Float4 x) {
  return reinterpret_cast<Float4>((x > Float4{}) & reinterpret_cast<Mask4>(x));
}
inline Lanes2 positive_part(Lanes2 x) {
  return reinterpret_cast<Lanes2>((x > Lanes2{}) & reinterpret_cast<Mask2>(x));
}
// The gap along one axis between x and the span of p0, p1, p2 (a triangle's box), in two lanes:
// what consider() computes for one triangle (closest_within below).
inline Lanes2 pair_gap(const Lanes2& x, const Lanes2& p0, const Lanes2& p1, const Lanes2& p2) {
  const Lanes2 lo01 = p1 < p0 ? p1 : p0, hi01 = p1 > p0 ? p1 : p0;
  const Lanes2 lo = p2 < lo01 ? p2 : lo01, hi = p2 > hi01 ? p2 : hi01;
  return positive_part(lo - x) + positive_part(x - hi);
}

// Squared distances from x (three float coordinates) to four boxes [lo[i][k], hi[i][k]]
// (+inf for an absent child, whose box is lo = +inf, hi = -inf), four lanes at once.
inline Float4 box_distances(const float lo[3][4], const float hi[3][4], const float x[3]) {
  const auto gap = [&](int i) {
    const Float4 xi = {x[i], x[i], x[i], x[i]};
    return positive_part(load4(lo[i]) - xi) + positive_part(xi - load4(hi[i]));
  };
  const Float4 g0 = gap(0), g1 = gap(1), g2 = gap(2);
  return g0 * g0 + g1 * g1 + g2 * g2;
}

// Squared distances from q (as float, `qf`) to the four axis-aligned child boxes of n, in
// float. Callers compare against reach_float(), whose margins cover the rounding of q and of
// the gaps (the same as for the oriented boxes below, with exact axes).
inline Float4 child_box_distances(const BvhNode& n, const float qf[3]) {
  return box_distances(n.lo, n.hi, qf);
}

// Squared distances from q to the four oriented child boxes of a node (BvhObb), in float, as
// lower bounds: for x in child k, |q - x|^2 >= sum_i gap_i^2 / s where gap_i is the distance
// of axis_i . q to [lo_i, hi_i] and s <= 1 + 2^-20 bounds the squared singular values of the
// float axes (orthonormal to float rounding). q (as float, `qf`) is projected once per node.
// Callers compare against reach_float(), which covers s and the rounding here.
inline Float4 child_obb_distances(const BvhObb& o, const float qf[3]) {
  float p[3];
  for (int i = 0; i < 3; ++i)
    p[i] = o.axis[i][0] * qf[0] + o.axis[i][1] * qf[1] + o.axis[i][2] * qf[2];
  return box_distances(o.lo, o.hi, p);
}

// The largest value of child_obb_distances() for a box that may still hold a triangle as close
// as best_d (within the 2^-40 relative slack of the triangle filters below), rounded up to
// float. Rounding q to float moves it by up to 2^-24 |q|_inf a coordinate, and the three
// float products and two sums of a projection add under 3 2^-24 sqrt(3) |q|_inf: each gap is
// off by under 2^-21 |q|_inf plus 2^-24 of itself; the squares and their sum add 3 2^-24,
// and the axes' 1 + 2^-20. The margins below (2^-19 (|q|_inf + 1) absolute, 2^-17 and
// 2^-19 relative) cover all of it with room to spare.
inline float reach_float(double best_d, double qmax) {
  const double r = best_d * (1.0 + 0x1p-17) + (qmax + 1.0) * 0x1p-19;
  const double r2 = r * r * (1.0 + 0x1p-19);
  // Beyond float range (or not a number): nothing is pruned (and no out-of-range conversion).
  if (!(r2 <= 0x1p127)) return HUGE_VALF;
  return float_up(r2);
}

inline double abs_max3(const Vec3& p) {
  const double x = std::fabs(p.x), y = std::fabs(p.y), z = std::fabs(p.z);
  const double xy = x > y ? x : y;
  return xy > z ? xy : z;
}

// a * b - c * d to about one ulp: Dekker's exact products (no FMA, so the same bits
// everywhere) and Knuth's exact difference (Shewchuk 1997, section 2).
inline void exact_product(double a, double b, double* hi, double* lo) {
  constexpr double kSplit = 134217729.0;  // 2^27 + 1
  *hi = a * b;
  double t = kSplit * a;
  const double ah = t - (t - a), al = a - ah;
  t = kSplit * b;
  const double bh = t - (t - b), bl = b - bh;
  *lo = al * bl - (((*hi - ah * bh) - al * bh) - ah * bl);
}
inline double difference_of_products(double a, double b, double c, double d) {
  double p, pe, q, qe;
  exact_product(a, b, &p, &pe);
  exact_product(c, d, &q, &qe);
  const double s = p - q;
  const double bvirt = p - s;
  const double e = (p - (s + bvirt)) + (bvirt - q);
  return s + (e + (pe - qe));
}

// Closest point on a sliver (a triangle much thinner than it is long), where the barycentric
// tests of Ericson's routine below lose about eps / sin^2 of the triangle's size (a point on
// the triangle came out 7e-4 off it). Here: the projection onto the plane when it falls in the
// closed triangle, with a normal accurate to an ulp (so it is the plane of the triangle, not a
// tilted one), else the nearest of the three closed edges; each step is well conditioned.
void closest_on_sliver(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c, Vec3* out,
                       Feature* feature, uint8_t* index) {
  const Vec3 ab = b - a, ac = c - a;
  const Vec3 n{difference_of_products(ab.y, ac.z, ab.z, ac.y),
               difference_of_products(ab.z, ac.x, ab.x, ac.z),
               difference_of_products(ab.x, ac.y, ab.y, ac.x)};
  const double n2 = dot(n, n);
  if (n2 > 0 && dot(cross(ab, p - a), n) >= 0 && dot(cross(c - b, p - b), n) >= 0 &&
      dot(cross(a - c, p - c), n) >= 0) {
    *out = p - n * (dot(p - a, n) / n2);
    *feature = Feature::kFace;
    *index = 0;
    return;
  }
  // The three closed edges in turn (unrolled: k is a constant in each), the first of equal
  // distances kept.
  double best = 0;
  const auto edge = [&](uint8_t k, const Vec3& v0, const Vec3& v1) {
    const Vec3 e = v1 - v0;
    const double num = dot(p - v0, e), den = dot(e, e);
    Vec3 q;
    Feature f;
    uint8_t fi;
    if (num <= 0 || den == 0) {
      q = v0;
      f = Feature::kVertex;
      fi = k;
    } else if (num >= den) {
      q = v1;
      f = Feature::kVertex;
      fi = static_cast<uint8_t>((k + 1) % 3);
    } else {
      q = v0 + e * (num / den);
      f = Feature::kEdge;
      fi = k;
    }
    const double d2 = length_squared(p - q);
    if (k == 0 || d2 < best) {
      best = d2;
      *out = q;
      *feature = f;
      *index = fi;
    }
  };
  edge(0, a, b);
  edge(1, b, c);
  edge(2, c, a);
}

// Closest point on triangle abc to p, with the feature (Ericson 5.1.5; slivers above).
void closest_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c, Vec3* out,
                         Feature* feature, uint8_t* index) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) {
    *out = a;
    *feature = Feature::kVertex;
    *index = 0;
    return;
  }
  const Vec3 bp = p - b;
  const double d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) {
    *out = b;
    *feature = Feature::kVertex;
    *index = 1;
    return;
  }
  {
    // The tests below divide by |ab x ac|^2 in effect: on a sliver (twice the area below a
    // quarter of the longest edge squared; |ab x ac|^2 by Lagrange's identity) use the
    // routine above.
    const double lab = dot(ab, ab), lac = dot(ac, ac), abac = dot(ab, ac);
    const double lbc = lab + lac - 2.0 * abac;
    const double longest = lab > lac ? (lab > lbc ? lab : lbc) : (lac > lbc ? lac : lbc);
    if ((lab * lac - abac * abac) * 16.0 < longest * longest) {
      closest_on_sliver(p, a, b, c, out, feature, index);
      return;
    }
  }
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double t = d1 / (d1 - d3);
    *out = a + ab * t;
    *feature = Feature::kEdge;
    *index = 0;
    return;
  }
  const Vec3 cp = p - c;
  const double d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) {
    *out = c;
    *feature = Feature::kVertex;
    *index = 2;
    return;
  }
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double t = d2 / (d2 - d6);
    *out = a + ac * t;
    *feature = Feature::kEdge;
    *index = 2;  // edge c -> a
    return;
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double t = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    *out = b + (c - b) * t;
    *feature = Feature::kEdge;
    *index = 1;
    return;
  }
  const double denom = 1.0 / (va + vb + vc);
  const double v = vb * denom, w = vc * denom;
  *out = a + ab * v + ac * w;
  *feature = Feature::kFace;
  *index = 0;
}

}  // namespace

void detail::settle_closest(const DistanceIndex& index, const Vec3& q, double best2,
                            ClosestPoint* best) {
  const Mesh& mesh = *index.mesh;
  const Vec3* v = mesh.vertices.data();
  if (best2 > 0) {
    // A point exactly on the surface comes out a rounding error (~1e-16 relative) away from
    // it; decide exactly, so that it gets distance 0 (and signed distance +0, as documented).
    const Triangle& tri = mesh.triangles[best->triangle];
    const Vec3 &a = v[tri.v[0]], &b = v[tri.v[1]], &c = v[tri.v[2]];
    const Vec3* corners[4] = {&q, &a, &b, &c};
    double m = 0;
    for (const Vec3* p : corners) {
      for (int k = 0; k < 3; ++k) m = std::fabs((*p)[k]) > m ? std::fabs((*p)[k]) : m;
    }
    const double tiny = m * 0x1p-40;
    int axis;
    if (best2 <= tiny * tiny && orient3d(a, b, c, q) == 0 &&
        (axis = projection_axis(a, b, c)) >= 0) {
      const int u = (axis + 1) % 3, w = (axis + 2) % 3;
      const int s[3] = {sign_of(orient2d(a[u], a[w], b[u], b[w], q[u], q[w])),
                        sign_of(orient2d(b[u], b[w], c[u], c[w], q[u], q[w])),
                        sign_of(orient2d(c[u], c[w], a[u], a[w], q[u], q[w]))};
      if ((s[0] >= 0 && s[1] >= 0 && s[2] >= 0) || (s[0] <= 0 && s[1] <= 0 && s[2] <= 0)) {
        best2 = 0;
        best->point = q;
        best->feature = Feature::kFace;
        best->feature_index = 0;
        for (uint8_t k = 0; k < 3; ++k) {
          if (s[k] == 0 && s[(k + 2) % 3] == 0) {  // on edges k and k - 1: vertex k
            best->point = v[tri.v[k]];
            best->feature = Feature::kVertex;
            best->feature_index = k;
            break;
          }
          if (s[k] == 0) {
            best->feature = Feature::kEdge;
            best->feature_index = k;
          }
        }
      }
    }
  }
  best->distance = std::sqrt(best2);
}

namespace {

// One tree search of closest_within(): the query, the best triangle so far and the bounds it
// sets. A triangle is kept when it is closer, or as close with a smaller id (so the answer
// never depends on the tree or the seed), and within the limit. Two lower bounds of the
// distance skip most triangles first: the triangle's box, and its plane. Both are skipped only
// when clearly beyond the best (margins far above their rounding), so what they skip the exact
// routine would have rejected too.
struct ClosestSearch {
  const Mesh& mesh;
  const Vec3* v;
  const Triangle* tris;
  const uint32_t* order;
  const Vec3 q;
  const double limit2;
  double best2;   // limit2 until a triangle is found
  double best_d;  // sqrt(best2), for the plane filter
  const double qmax;
  // The boxes are tested in float against reach2 (reach_float: the best distance so far with
  // margins for the float rounding).
  float reach2;
  bool found = false;
  uint32_t best_tri = 0;
  ClosestPoint best;
  const Lanes2 q2x, q2y, q2z;  // q in both lanes, for consider_leaf()

  ClosestSearch(const DistanceIndex& index, const Vec3& query, double limit)
      : mesh(*index.mesh),
        v(index.mesh->vertices.data()),
        tris(index.mesh->triangles.data()),
        order(index.order.data()),
        q(query),
        limit2(limit),
        best2(limit),
        best_d(std::sqrt(limit)),
        qmax(abs_max3(query)),
        reach2(reach_float(best_d, qmax)),
        q2x{query.x, query.x},
        q2y{query.y, query.y},
        q2z{query.z, query.z} {}

  // What follows the box filter (consider(), consider_leaf()): the plane filter, then the
  // exact routine.
  void consider_near(uint32_t t, const Vec3& a, const Vec3& b, const Vec3& c) {
    {
      // The plane, on triangles whose normal is well conditioned (the angle at a above about
      // 0.001 rad): then n = ab x ac is off by under 5e-13 |n| and pd by under
      // 6e-13 |qa| |n|, which the margin of 2^-30 |qa|_1 covers with room to spare.
      const Vec3 ab = b - a, ac = c - a;
      const Vec3 n = cross(ab, ac);
      const double n2 = dot(n, n);
      if (n2 > dot(ab, ab) * dot(ac, ac) * 0x1p-20) {
        const Vec3 qa = q - a;
        const double pd = dot(qa, n);
        const double m = std::fabs(qa.x) + std::fabs(qa.y) + std::fabs(qa.z);
        const double reach = best_d + m * 0x1p-30;
        if (pd * pd > reach * reach * n2) return;
      }
    }
    Vec3 p;
    Feature f;
    uint8_t fi;
    closest_on_triangle(q, a, b, c, &p, &f, &fi);
    const double d2 = length_squared(p - q);
    if (d2 > limit2) return;
    if (d2 < best2 || (d2 == best2 && (!found || t < best_tri))) {
      best2 = d2;
      best_d = std::sqrt(d2);
      reach2 = reach_float(best_d, qmax);
      best_tri = t;
      found = true;
      best.point = p;
      best.triangle = t;
      best.feature = f;
      best.feature_index = fi;
    }
  }

  // consider() with t's box given (the least and most of its corners' coordinates: the same
  // gaps, the same decision).
  void consider_boxed(uint32_t t, const Aabb& box) {
    const auto gap = [](double x, double lo, double hi) {
      const double below = lo - x, above = x - hi;
      return (below > 0.0 ? below : 0.0) + (above > 0.0 ? above : 0.0);
    };
    const double gx = gap(q.x, box.lo.x, box.hi.x), gy = gap(q.y, box.lo.y, box.hi.y),
                 gz = gap(q.z, box.lo.z, box.hi.z);
    if (gx * gx + gy * gy + gz * gz > best2 * (1.0 + 0x1p-40)) return;
    const Triangle& tri = mesh.triangles[t];
    consider_near(t, v[tri.v[0]], v[tri.v[1]], v[tri.v[2]]);
  }

  // Triangle t, behind the filter of its box.
  void consider(uint32_t t) {
    const Triangle& tri = mesh.triangles[t];
    const Vec3 &a = v[tri.v[0]], &b = v[tri.v[1]], &c = v[tri.v[2]];
    // Branch-free (each ?: below is one min or max instruction).
    const auto gap = [](double x, double p0, double p1, double p2) {
      const double lo01 = p1 < p0 ? p1 : p0, hi01 = p1 > p0 ? p1 : p0;
      const double lo = p2 < lo01 ? p2 : lo01, hi = p2 > hi01 ? p2 : hi01;
      const double below = lo - x, above = x - hi;
      return (below > 0.0 ? below : 0.0) + (above > 0.0 ? above : 0.0);
    };
    const double gx = gap(q.x, a.x, b.x, c.x), gy = gap(q.y, a.y, b.y, c.y),
                 gz = gap(q.z, a.z, b.z, c.z);
    if (gx * gx + gy * gy + gz * gz > best2 * (1.0 + 0x1p-40)) return;
    consider_near(t, a, b, c);
  }

  // consider() for the triangles order[first .. first + count) (a leaf), two at a time: the
  // box gaps of a pair in two lanes (the same operations as consider(), the same bits), each
  // compared with the best distance as it stands when its turn comes (after the first of the
  // pair may have tightened it), as consider() would: the same triangles reach the plane
  // filter and the exact routine, in the same order, as one consider() call after another.
  void consider_leaf(uint32_t first, uint32_t count) {
    const uint32_t end = first + count;
    for (uint32_t j = first; j < end; j += 2) {
      const uint32_t t0 = order[j], t1 = j + 1 < end ? order[j + 1] : t0;
      const Triangle &s0 = tris[t0], &s1 = tris[t1];
      const Vec3 &a0 = v[s0.v[0]], &b0 = v[s0.v[1]], &c0 = v[s0.v[2]];
      const Vec3 &a1 = v[s1.v[0]], &b1 = v[s1.v[1]], &c1 = v[s1.v[2]];
      const Lanes2 gx = pair_gap(q2x, Lanes2{a0.x, a1.x}, Lanes2{b0.x, b1.x}, Lanes2{c0.x, c1.x});
      const Lanes2 gy = pair_gap(q2y, Lanes2{a0.y, a1.y}, Lanes2{b0.y, b1.y}, Lanes2{c0.y, c1.y});
      const Lanes2 gz = pair_gap(q2z, Lanes2{a0.z, a1.z}, Lanes2{b0.z, b1.z}, Lanes2{c0.z, c1.z});
      const Lanes2 g2 = gx * gx + gy * gy + gz * gz;
      if (!(g2[0] > best2 * (1.0 + 0x1p-40))) consider_near(t0, a0, b0, c0);
      if (j + 1 < end && !(g2[1] > best2 * (1.0 + 0x1p-40))) consider_near(t1, a1, b1, c1);
    }
  }

  // The tree, depth first from the root, through the oriented boxes when the index has them.
  void descend(const DistanceIndex& index) {
    const BvhNode* nodes = index.nodes.data();
    const BvhObb* obbs = index.obbs.size() != 0 ? index.obbs.data() : nullptr;
    // Beyond 2^100 (or not a number) float squares could overflow: no box is pruned then (and
    // q is not converted: out of float range that would be undefined).
    const bool prune = qmax < 0x1p100;
    const float qf[3] = {prune ? static_cast<float>(q.x) : 0.0f,
                         prune ? static_cast<float>(q.y) : 0.0f,
                         prune ? static_cast<float>(q.z) : 0.0f};
    struct Entry {
      uint32_t node;
      float d2;
    };
    Entry stack[kStack];
    uint32_t top = 0;
    stack[top++] = Entry{0, 0.0f};
    while (top > 0) {
      const Entry e = stack[--top];
      if (e.d2 > reach2) continue;
      const BvhNode& node = nodes[e.node];
      Float4 d2v{};  // !prune: every present child is visited
      if (prune) {
        d2v =
            obbs != nullptr ? child_obb_distances(obbs[e.node], qf) : child_box_distances(node, qf);
      }
      float d2[4];
      std::memcpy(d2, &d2v, sizeof(d2));
      // The children within reach, nearest first (ties in slot order): leaves tighten the
      // bound before farther boxes are tested against it.
      uint8_t by[4] = {0, 0, 0, 0};
      int m = 0;
      for (int k = 0; k < 4; ++k) {
        if (!(d2[k] <= reach2) || node.child[k] == kNoChild) continue;
        int j = m++;
        for (; j > 0 && d2[by[j - 1]] > d2[k]; --j) by[j] = by[j - 1];
        by[j] = static_cast<uint8_t>(k);
      }
      for (int i = 0; i < m; ++i) {
        const int k = by[i];
        if (node.count[k] == 0 || !(d2[k] <= reach2)) continue;
        consider_leaf(node.child[k], node.count[k]);
      }
      for (int i = m; i-- > 0;) {
        const int k = by[i];
        if (node.count[k] != 0 || !(d2[k] <= reach2)) continue;
        if (top + 1 > kStack) continue;  // cannot happen: depth is bounded at build time
        stack[top++] = Entry{node.child[k], d2[k]};
      }
    }
  }
};

}  // namespace

// The tree search (declared in query_internal.h).
bool detail::closest_within(const DistanceIndex& index, const Vec3& q, double limit2,
                            ClosestPoint* out, uint32_t seed) {
  if (index.mesh->triangles.size() == 0) return false;
  ClosestSearch search(index, q, limit2);
  if (seed != kNoNeighbor) search.consider(seed);
  search.descend(index);
  if (!search.found) return false;
  settle_closest(index, q, search.best2, &search.best);
  *out = search.best;
  return true;
}

namespace {

// Solid angle of triangle abc seen from q (Van Oosterom and Strackee).
double solid_angle(const Vec3& q, const Vec3& a0, const Vec3& b0, const Vec3& c0) {
  const Vec3 a = a0 - q, b = b0 - q, c = c0 - q;
  const double la = length(a), lb = length(b), lc = length(c);
  const double det = dot(a, cross(b, c));
  const double den = la * lb * lc + dot(a, b) * lc + dot(a, c) * lb + dot(b, c) * la;
  return 2.0 * deterministic_atan2(det, den);
}

Vec3 face_normal(const Mesh& mesh, uint32_t t) {
  const Triangle& tri = mesh.triangles[t];
  const Vec3* v = mesh.vertices.data();
  const Vec3 n = cross(v[tri.v[1]] - v[tri.v[0]], v[tri.v[2]] - v[tri.v[0]]);
  const double len = length(n);
  return len > 0 ? n * (1.0 / len) : Vec3{};
}

}  // namespace

Vec3 closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c,
                               Feature* feature, uint8_t* index) {
  Vec3 out;
  Feature f;
  uint8_t i;
  closest_on_triangle(p, a, b, c, &out, &f, &i);
  if (feature != nullptr) *feature = f;
  if (index != nullptr) *index = i;
  return out;
}

bool closest_point(const DistanceIndex& index, const Vec3& q, ClosestPoint* out) {
  return closest_within(index, q, HUGE_VAL, out);
}

double winding_number(const DistanceIndex& index, const Vec3& q, double beta) {
  const Mesh& mesh = *index.mesh;
  if (mesh.triangles.size() == 0) return 0.0;
  SPLINTCORE_ASSERT(index.dipoles.size() == index.nodes.size());  // not a pairs_only index
  const Vec3* v = mesh.vertices.data();
  const BvhNode* nodes = index.nodes.data();
  const double beta2 = beta * beta;
  double sum = 0;
  uint32_t stack[kStack];
  uint32_t top = 0;
  stack[top++] = 0;
  // Fixed order (slot order), so the sum is the same bits every time.
  while (top > 0) {
    const uint32_t i = stack[--top];
    const BvhNode& node = nodes[i];
    if (beta > 0 && i != 0) {
      const BvhDipole& dp = index.dipoles[i];
      const Vec3 c{static_cast<double>(dp.center[0]), static_cast<double>(dp.center[1]),
                   static_cast<double>(dp.center[2])};
      const Vec3 r = c - q;
      const double d2 = length_squared(r);
      const double rad = static_cast<double>(dp.radius);
      if (d2 > beta2 * rad * rad) {
        const Vec3 nrm{static_cast<double>(dp.normal[0]), static_cast<double>(dp.normal[1]),
                       static_cast<double>(dp.normal[2])};
        const double d = std::sqrt(d2);
        sum += dot(r, nrm) / (d2 * d);
        continue;
      }
    }
    // Leaves in slot order: far ones (beyond 1.5 beta times the half diagonal of their box,
    // from its centre: a box's half diagonal overstates a leaf's reach more than a node's
    // ball does, and 1.5 keeps the error near the surface about where whole nodes alone had
    // it) by their dipole, summed from their triangles here (no per-leaf storage; a few cross
    // products instead of as many solid angles, each with an arctangent); the others exactly.
    // Inner children pushed last first (popped in slot order).
    for (int k = 0; k < 4; ++k) {
      if (node.count[k] == 0) continue;
      const uint32_t first = node.child[k], end = first + node.count[k];
      if (beta > 0) {
        Vec3 c, half;
        for (int a = 0; a < 3; ++a) {
          const double lo = static_cast<double>(node.lo[a][k]),
                       hi = static_cast<double>(node.hi[a][k]);
          c[a] = 0.5 * (lo + hi);
          half[a] = 0.5 * (hi - lo);
        }
        const Vec3 r = c - q;
        const double d2 = length_squared(r);
        if (d2 > 2.25 * beta2 * length_squared(half)) {
          Vec3 area{};
          for (uint32_t j = first; j < end; ++j) {
            const Triangle& tri = mesh.triangles[index.order[j]];
            const Vec3& a0 = v[tri.v[0]];
            area = area + cross(v[tri.v[1]] - a0, v[tri.v[2]] - a0);
          }
          const double d = std::sqrt(d2);
          sum += 0.5 * dot(r, area) / (d2 * d);
          continue;
        }
      }
      for (uint32_t j = first; j < end; ++j) {
        const Triangle& tri = mesh.triangles[index.order[j]];
        sum += solid_angle(q, v[tri.v[0]], v[tri.v[1]], v[tri.v[2]]);
      }
    }
    for (int k = 4; k-- > 0;) {
      if (node.count[k] == 0 && node.child[k] != kNoChild && top < kStack)
        stack[top++] = node.child[k];
    }
  }
  return sum / kFourPi;
}

double winding_number_direct(const Mesh& mesh, const Vec3& q) {
  const Vec3* v = mesh.vertices.data();
  double sum = 0;
  for (const Triangle& tri : mesh.triangles) {
    sum += solid_angle(q, v[tri.v[0]], v[tri.v[1]], v[tri.v[2]]);
  }
  return sum / kFourPi;
}

namespace {
// The sign for q whose closest point is already in out->closest.
void finish_signed(const DistanceIndex& index, const Vec3& q, SignMethod method,
                   SignedDistance* out) {
  const ClosestPoint& cp = out->closest;
  if (method == SignMethod::kAuto) {
    method = index.closed_manifold ? SignMethod::kPseudonormal : SignMethod::kWindingNumber;
  }
  out->method = method;
  if (cp.distance == 0.0) {
    out->distance = 0.0;
    return;
  }
  bool inside = false;
  if (method == SignMethod::kPseudonormal) {
    const Mesh& mesh = *index.mesh;
    const Triangle& tri = mesh.triangles[cp.triangle];
    Vec3 normal;
    bool ok = true;
    switch (cp.feature) {
      case Feature::kFace: normal = face_normal(mesh, cp.triangle); break;
      case Feature::kEdge: {
        const uint32_t other = index.neighbors[3 * size_t{cp.triangle} + cp.feature_index];
        ok = other != kNoNeighbor;
        if (ok) normal = face_normal(mesh, cp.triangle) + face_normal(mesh, other);
        break;
      }
      case Feature::kVertex: normal = vertex_pseudonormal(index, tri.v[cp.feature_index]); break;
    }
    if (ok) {
      inside = dot(q - cp.point, normal) < 0.0;
    } else {
      method = SignMethod::kWindingNumber;  // an open edge: the pseudonormal is undefined
      out->method = method;
    }
  }
  if (method == SignMethod::kWindingNumber) {
    out->winding = winding_number(index, q);
    inside = out->winding >= 0.5;
  }
  out->distance = inside ? -cp.distance : cp.distance;
}
}  // namespace

bool signed_distance(const DistanceIndex& index, const Vec3& q, SignMethod method,
                     SignedDistance* out) {
  *out = SignedDistance{};
  SPLINTCORE_ASSERT(index.vertex_start.size() > 0);  // not a pairs_only index
  if (!closest_point(index, q, &out->closest)) return false;
  finish_signed(index, q, method, out);
  return true;
}

bool ray_intersect(const DistanceIndex& index, const Vec3& origin, const Vec3& direction,
                   double t_max, RayHit* out) {
  const Mesh& mesh = *index.mesh;
  if (mesh.triangles.size() == 0) return false;
  const Vec3* v = mesh.vertices.data();
  const BvhNode* nodes = index.nodes.data();
  const Vec3 inv{1.0 / direction.x, 1.0 / direction.y, 1.0 / direction.z};
  double best_t = t_max;
  bool found = false;
  uint32_t best_tri = 0;
  uint32_t stack[kStack];
  uint32_t top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const BvhNode& node = nodes[stack[--top]];
    for (int k = 0; k < 4; ++k) {
      if (node.child[k] == kNoChild) continue;
      // Slab test (inf/nan from zero direction components resolved conservatively), with a
      // relative margin of 2^-30: Moller-Trumbore's t can lie a little outside the triangle's
      // own box (1e-14 relative for a ray through a vertex), and the smallest id among equal
      // hits must not be pruned for it.
      double t0 = 0, t1 = best_t;
      bool miss = false;
      for (int a = 0; a < 3 && !miss; ++a) {
        const double lo = static_cast<double>(node.lo[a][k]),
                     hi = static_cast<double>(node.hi[a][k]);
        if (direction[a] == 0.0) {
          miss = origin[a] < lo || origin[a] > hi;
          continue;
        }
        double ta = (lo - origin[a]) * inv[a], tb = (hi - origin[a]) * inv[a];
        if (ta > tb) {
          const double s = ta;
          ta = tb;
          tb = s;
        }
        t0 = ta > t0 ? ta : t0;
        t1 = tb < t1 ? tb : t1;
        miss = t0 > t1 * (1 + 0x1p-30) + 1e-300;
      }
      if (miss) continue;
      if (node.count[k] == 0) {
        if (top < kStack) stack[top++] = node.child[k];
        continue;
      }
      for (uint32_t j = node.child[k]; j < node.child[k] + node.count[k]; ++j) {
        const uint32_t t = index.order[j];
        const Triangle& tri = mesh.triangles[t];
        const Vec3 &a = v[tri.v[0]], &b = v[tri.v[1]], &c = v[tri.v[2]];
        // Moller-Trumbore.
        const Vec3 e1 = b - a, e2 = c - a;
        const Vec3 p = cross(direction, e2);
        const double det = dot(e1, p);
        if (det == 0.0) continue;
        const double inv_det = 1.0 / det;
        const Vec3 s = origin - a;
        const double u = dot(s, p) * inv_det;
        if (u < 0.0 || u > 1.0) continue;
        const Vec3 qv = cross(s, e1);
        const double w = dot(direction, qv) * inv_det;
        if (w < 0.0 || u + w > 1.0) continue;
        const double th = dot(e2, qv) * inv_det;
        if (th < 0.0 || th > best_t) continue;
        if (th < best_t || !found || t < best_tri) {
          best_t = th;
          best_tri = t;
          found = true;
        }
      }
    }
  }
  if (!found) return false;
  out->t = best_t;
  out->triangle = best_tri;
  return true;
}

namespace {
inline bool child_overlaps(const BvhNode& node, int k, const Aabb& box) {
  return node.child[k] != kNoChild && !(static_cast<double>(node.lo[0][k]) > box.hi.x ||
                                        static_cast<double>(node.hi[0][k]) < box.lo.x ||
                                        static_cast<double>(node.lo[1][k]) > box.hi.y ||
                                        static_cast<double>(node.hi[1][k]) < box.lo.y ||
                                        static_cast<double>(node.lo[2][k]) > box.hi.z ||
                                        static_cast<double>(node.hi[2][k]) < box.lo.z);
}

// Calls visit(triangle id) for every triangle in a leaf whose box overlaps `box`; stops when
// visit returns false.
template <class Visit>
void for_each_triangle_near(const DistanceIndex& index, const Aabb& box, Visit& visit) {
  uint32_t stack[kStack];
  uint32_t top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const BvhNode& node = index.nodes[stack[--top]];
    for (int k = 4; k-- > 0;) {
      if (!child_overlaps(node, k, box)) continue;
      if (node.count[k] == 0) {
        if (top < kStack) stack[top++] = node.child[k];
        continue;
      }
      for (uint32_t j = node.child[k]; j < node.child[k] + node.count[k]; ++j) {
        if (!visit(index.order[j])) return;
      }
    }
  }
}
}  // namespace

bool segment_intersects_mesh(const DistanceIndex& index, const Vec3& p, const Vec3& q,
                             uint32_t* triangle) {
  const Mesh& mesh = *index.mesh;
  if (mesh.triangles.size() == 0) return false;
  const Vec3* v = mesh.vertices.data();
  Aabb box;
  box.add(p);
  box.add(q);
  bool found = false;
  uint32_t best = 0;
  auto visit = [&](uint32_t t) {
    if (found && t >= best) return true;
    const Triangle& tri = mesh.triangles[t];
    if (collinear3d(v[tri.v[0]], v[tri.v[1]], v[tri.v[2]])) return true;
    if (segment_intersects_triangle(p, q, v[tri.v[0]], v[tri.v[1]], v[tri.v[2]])) {
      best = t;
      found = true;
    }
    return true;
  };
  for_each_triangle_near(index, box, visit);
  if (found && triangle != nullptr) *triangle = best;
  return found;
}

namespace {

// Does triangle t of `mesh` come within reach of abc (`box`: reach_box(a, b, c, reach))?
// triangle_within_reach() once t's box is known to meet abc's reach box.
bool triangle_within_reach_boxed(const Mesh& mesh, uint32_t t, const Vec3& a, const Vec3& b,
                                 const Vec3& c, double reach);

bool triangle_within_reach(const Mesh& mesh, uint32_t t, const Aabb& box, const Vec3& a,
                           const Vec3& b, const Vec3& c, double reach) {
  if (!triangle_box(mesh, t).overlaps(box)) return false;
  return triangle_within_reach_boxed(mesh, t, a, b, c, reach);
}

bool triangle_within_reach_boxed(const Mesh& mesh, uint32_t t, const Vec3& a, const Vec3& b,
                                 const Vec3& c, double reach) {
  const Vec3* v = mesh.vertices.data();
  const Triangle& tri = mesh.triangles[t];
  // Wholly on one side of the triangle's plane, farther than reach (with a margin far above
  // the rounding): no closer than that.
  const Vec3 n = cross(v[tri.v[1]] - v[tri.v[0]], v[tri.v[2]] - v[tri.v[0]]);
  const double len = std::sqrt(dot(n, n));
  if (len > 0) {
    const double limit = (reach + 1e-9 * (1.0 + std::fabs(dot(n, v[tri.v[0]])) / len)) * len;
    const double da = dot(n, a - v[tri.v[0]]), db = dot(n, b - v[tri.v[0]]),
                 dc = dot(n, c - v[tri.v[0]]);
    if ((da > limit && db > limit && dc > limit) || (da < -limit && db < -limit && dc < -limit)) {
      return false;
    }
  }
  // The same with the roles swapped: t wholly on one side of abc's plane, farther than reach.
  const Vec3 m = cross(b - a, c - a);
  const double mlen = std::sqrt(dot(m, m));
  if (mlen > 0) {
    const double limit = (reach + 1e-9 * (1.0 + std::fabs(dot(m, a)) / mlen)) * mlen;
    const double d0 = dot(m, v[tri.v[0]] - a), d1 = dot(m, v[tri.v[1]] - a),
                 d2 = dot(m, v[tri.v[2]] - a);
    if ((d0 > limit && d1 > limit && d2 > limit) || (d0 < -limit && d1 < -limit && d2 < -limit)) {
      return false;
    }
  }
  return triangle_pair_distance(a, b, c, v[tri.v[0]], v[tri.v[1]], v[tri.v[2]], nullptr, nullptr) <
         reach;
}

// Every point x of abc has |x - a| <= extent: a bound on how far abc reaches from a.
double extent_from(const Vec3& a, const Vec3& b, const Vec3& c) {
  return std::sqrt(max_of(length_squared(b - a), length_squared(c - a)));
}

}  // namespace

bool triangle_near_mesh(const DistanceIndex& index, const Vec3& a, const Vec3& b, const Vec3& c,
                        double reach) {
  const Mesh& mesh = *index.mesh;
  if (mesh.triangles.size() == 0) return false;
  const Aabb box = reach_box(a, b, c, reach);
  bool found = false;
  auto visit = [&](uint32_t t) {
    found = triangle_within_reach(mesh, t, box, a, b, c, reach);
    return !found;
  };
  for_each_triangle_near(index, box, visit);
  return found;
}

size_t triangles_meeting_box(const DistanceIndex& index, const Aabb& box, uint32_t* out,
                             size_t capacity, Aabb* boxes) {
  const Mesh& mesh = *index.mesh;
  if (mesh.triangles.size() == 0 || box.empty()) return 0;
  size_t n = 0;
  auto visit = [&](uint32_t t) {
    const Aabb tb = triangle_box(mesh, t);
    if (!tb.overlaps(box)) return true;
    if (n == capacity) {
      n = capacity + 1;
      return false;
    }
    if (boxes != nullptr) boxes[n] = tb;
    out[n++] = t;
    return true;
  };
  for_each_triangle_near(index, box, visit);
  return n;
}

namespace {

// triangle_side() once a's closest point is in sd->closest: kNear when near() (abc within reach
// of the surface) is asked and says so, else a's side.
template <class Near>
TriangleSide side_from_closest(const DistanceIndex& index, const Vec3& a, const Vec3& b,
                               const Vec3& c, double reach, const Near& near, SignedDistance* sd) {
  // Every point x of abc has |x - a| <= extent, so its distance to the surface is at least
  // |a's| - extent, and the ball about a of radius |a's| holds no surface: all of abc lies on
  // a's side. The margin is far above the rounding of both lengths (about 1e-15 relative).
  const double extent = extent_from(a, b, c);
  const double margin = 1e-9 * (1.0 + abs_max3(a));
  if (!(sd->closest.distance > reach + extent + margin) && near()) return TriangleSide::kNear;
  // Farther than reach everywhere: abc does not cross the surface, a's side is its side (a is
  // at least reach from the surface, so its sign is not in doubt).
  finish_signed(index, a, SignMethod::kAuto, sd);
  return sd->distance < 0 ? TriangleSide::kInside : TriangleSide::kOutside;
}

}  // namespace

namespace {

// Does some triangle among ids come within reach of abc (exact)?
bool near_among(const Mesh& mesh, const uint32_t* ids, size_t count, const Aabb* boxes,
                const Vec3& a, const Vec3& b, const Vec3& c, double reach) {
  const Aabb box = reach_box(a, b, c, reach);
  for (size_t i = 0; i < count; ++i) {
    if (boxes != nullptr
            ? boxes[i].overlaps(box) && triangle_within_reach_boxed(mesh, ids[i], a, b, c, reach)
            : triangle_within_reach(mesh, ids[i], box, a, b, c, reach)) {
      return true;
    }
  }
  return false;
}

// With a hint (the caller's conditions, triangle_side_among): whether some triangle among ids
// comes within reach of abc (exact), and else, in the same pass, a's side from the hint's: the
// parity of the triangles the segment from the hint's point to a crosses. kNear, or a's side,
// or none (the segment touches a triangle: not decided so).
bool hinted_side(const Mesh& mesh, const uint32_t* ids, size_t count, const Aabb* boxes,
                 const SideHint& hint, const Vec3& a, const Vec3& b, const Vec3& c, double reach,
                 bool* near, TriangleSide* side) {
  const Aabb box = reach_box(a, b, c, reach);
  Aabb seg;
  seg.add(hint.point);
  seg.add(a);
  const Vec3* v = mesh.vertices.data();
  bool flip = false, decided = hint.side != TriangleSide::kNear;
  for (size_t i = 0; i < count; ++i) {
    const Aabb tb = boxes != nullptr ? boxes[i] : triangle_box(mesh, ids[i]);
    if (tb.overlaps(box) && triangle_within_reach_boxed(mesh, ids[i], a, b, c, reach)) {
      *near = true;
      return true;
    }
    if (!decided || !tb.overlaps(seg)) continue;
    const Triangle& t = mesh.triangles[ids[i]];
    switch (segment_crossing(hint.point, a, v[t.v[0]], v[t.v[1]], v[t.v[2]])) {
      case SegmentCrossing::kMisses: break;
      case SegmentCrossing::kCrosses: flip = !flip; break;
      case SegmentCrossing::kTouches: decided = false; break;
    }
  }
  *near = false;
  if (!decided) return false;
  const bool inside = (hint.side == TriangleSide::kInside) != flip;
  *side = inside ? TriangleSide::kInside : TriangleSide::kOutside;
  return true;
}

}  // namespace

bool triangle_side_among(const DistanceIndex& index, const uint32_t* ids, size_t count,
                         double window_reach, const Vec3& a, const Vec3& b, const Vec3& c,
                         double reach, TriangleSide* side, ClosestPoint* closest, uint32_t seed,
                         const Aabb* boxes, SideHint* hint) {
  SPLINTCORE_ASSERT(index.vertex_start.size() > 0 && reach <= window_reach);
  if (count == 0) return false;
  const Mesh& mesh = *index.mesh;
  // With a hint: abc's reach among ids (every triangle within reach of abc is among them),
  // then a's side from the hint's. The same answer as below: there kNear is exactly "some
  // triangle within reach" too (a triangle within reach of abc is within reach + extent of a),
  // and otherwise a's side, which is the side a closed surface that does not cross itself puts
  // it on, as the parity of crossings does.
  bool near_known = false;
  if (hint != nullptr && index.closed_manifold) {
    bool near = false;
    const bool decided = hinted_side(mesh, ids, count, boxes, *hint, a, b, c, reach, &near, side);
    if (near) {
      *side = TriangleSide::kNear;
      return true;
    }
    near_known = true;
    if (decided) {
      *hint = SideHint{a, *side};
      return true;
    }
  }
  // a's closest triangle among ids: every other triangle's box misses abc's box grown by
  // window_reach, so it lies at least window_reach from a; closer than that (with a margin far
  // above the rounding), the best among ids is the best of all, the same (distance, triangle)
  // as the tree search finds (the same filters and the same exact routine, lowest id on a tie).
  // The seed first: the least (distance, id) over the seed and ids is the least over ids
  // whenever that is nearer than window_reach (a seed that near is among ids).
  ClosestSearch search(index, a, HUGE_VAL);
  if (seed < mesh.triangles.size()) search.consider(seed);
  if (boxes != nullptr) {
    for (size_t i = 0; i < count; ++i) search.consider_boxed(ids[i], boxes[i]);
  } else {
    for (size_t i = 0; i < count; ++i) search.consider(ids[i]);
  }
  if (!search.found || !(search.best_d < window_reach * (1 - 1e-9))) return false;
  SignedDistance sd;
  settle_closest(index, a, search.best2, &search.best);
  sd.closest = search.best;
  if (closest != nullptr) *closest = search.best;
  const auto near = [&] {
    return !near_known && near_among(mesh, ids, count, boxes, a, b, c, reach);
  };
  *side = side_from_closest(index, a, b, c, reach, near, &sd);
  if (hint != nullptr && *side != TriangleSide::kNear) *hint = SideHint{a, *side};
  return true;
}

TriangleSide triangle_side(const DistanceIndex& index, const Vec3& a, const Vec3& b, const Vec3& c,
                           double reach, uint32_t* seed) {
  SPLINTCORE_ASSERT(index.vertex_start.size() > 0);  // not a pairs_only index
  SignedDistance sd;
  if (!closest_within(index, a, HUGE_VAL, &sd.closest, *seed)) return TriangleSide::kOutside;
  *seed = sd.closest.triangle;
  const auto near = [&] { return triangle_near_mesh(index, a, b, c, reach); };
  return side_from_closest(index, a, b, c, reach, near, &sd);
}

Status triangles_in_box(const Context& ctx, const DistanceIndex& index, const Aabb& box,
                        ArenaArray<uint32_t>* out) {
  const size_t start = out->size();
  if (index.mesh->triangles.size() == 0 || box.empty()) return Status::ok();
  bool exhausted = false;
  auto visit = [&](uint32_t t) {
    if (!triangle_box(*index.mesh, t).overlaps(box)) return true;
    if (!out->push_back(t)) {
      exhausted = true;
      return false;
    }
    return true;
  };
  for_each_triangle_near(index, box, visit);
  if (exhausted) return ctx.arena->exhausted_status();
  // Ascending ids: the order of the result never depends on the tree.
  const size_t found = out->size() - start;
  if (found > 1) {
    ArenaScope scope(*ctx.arena);
    KeyIndex* keys = ctx.arena->allocate_array<KeyIndex>(found);
    if (keys == nullptr) return ctx.arena->exhausted_status();
    for (size_t i = 0; i < found; ++i) keys[i] = KeyIndex{(*out)[start + i], 0, 0};
    SPLINTCORE_RETURN_IF_ERROR(radix_sort(*ctx.arena, Span<KeyIndex>(keys, found)));
    for (size_t i = 0; i < found; ++i) (*out)[start + i] = static_cast<uint32_t>(keys[i].key);
  }
  return Status::ok();
}

namespace {
constexpr uint32_t kBatch = 1024;  // queries per task

// Batches are processed in Morton order of the queries, each seeded with the answer to the
// one before it: nearby queries share nodes and triangles (cache) and start with a tight
// bound. Results land at their own index, so the order changes nothing but the time.
// `answer(at, seed)` handles queries[at] and updates the seed.
template <class Answer>
Status morton_batch(const Context& ctx, const DistanceIndex& index, Span<const Vec3> queries,
                    const char* stage, Answer& answer) {
  const size_t n = queries.size();
  if (n == 0) return Status::ok();
  constexpr size_t kChunk = size_t{1} << 16;
  const size_t chunk = n < kChunk ? n : kChunk;
  Arena& arena = *ctx.arena;
  ArenaScope scope(arena);
  KeyIndex* keys = arena.allocate_array<KeyIndex>(chunk);
  KeyIndex* scratch = arena.allocate_array<KeyIndex>(chunk);
  if (keys == nullptr || scratch == nullptr) return arena.exhausted_status();
  // The Morton grid spans the root's children.
  const BvhNode& root = index.nodes[0];
  Vec3 lo{HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi{-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
  for (int k = 0; k < 4; ++k) {
    if (root.child[k] == kNoChild) continue;
    for (int a = 0; a < 3; ++a) {
      lo[a] =
          static_cast<double>(root.lo[a][k]) < lo[a] ? static_cast<double>(root.lo[a][k]) : lo[a];
      hi[a] =
          static_cast<double>(root.hi[a][k]) > hi[a] ? static_cast<double>(root.hi[a][k]) : hi[a];
    }
  }
  double scale[3];
  for (int a = 0; a < 3; ++a) {
    const double ext = hi[a] - lo[a];
    scale[a] = ext > 0 ? 1023.0 / ext : 0.0;
  }
  for (size_t first = 0; first < n; first += kChunk) {
    SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, stage, first, n));
    const size_t count = first + kChunk < n ? kChunk : n - first;
    for (size_t k = 0; k < count; ++k) {
      uint64_t code = 0;
      const Vec3& q = queries[first + k];
      for (int a = 0; a < 3; ++a) {
        double x = (q[a] - lo[a]) * scale[a];
        x = x < 0 || x != x ? 0 : (x > 1023.0 ? 1023.0 : x);
        code |= detail::spread_bits(static_cast<uint64_t>(x)) << (2 - a);  // x <= 1023
      }
      keys[k] = KeyIndex{code, static_cast<uint32_t>(k), 0};
    }
    radix_sort(Span<KeyIndex>(keys, count), Span<KeyIndex>(scratch, count));
    const uint32_t tasks = static_cast<uint32_t>((count + kBatch - 1) / kBatch);
    auto task = [&](uint32_t i) {
      const size_t b = size_t{i} * kBatch;
      const size_t e = b + kBatch < count ? b + kBatch : count;
      uint32_t seed = kNoNeighbor;
      for (size_t k = b; k < e; ++k) answer(first + keys[k].index, &seed);
    };
    parallel_for_each(ctx.executor, tasks, task);
  }
  return Status::ok();
}

}  // namespace

Status batch_closest_points(const Context& ctx, const DistanceIndex& index,
                            Span<const Vec3> queries, Span<ClosestPoint> results) {
  if (queries.size() != results.size()) {
    return Status::error(StatusCode::kInvalidArgument,
                         "batch_closest_points: queries and results differ in size");
  }
  SPLINTCORE_ASSERT(index.vertex_start.size() > 0);  // not a pairs_only index
  if (index.mesh->triangles.size() == 0) {
    for (size_t k = 0; k < results.size(); ++k) results[k] = ClosestPoint{};
    return Status::ok();
  }
  // Large batches: triangle by triangle over the bucketed queries (regions.cpp), the same
  // answers.
  bool used = false;
  auto place = [](void* user, size_t at, const ClosestPoint& cp, bool found) {
    static_cast<ClosestPoint*>(user)[at] = found ? cp : ClosestPoint{};
  };
  SPLINTCORE_RETURN_IF_ERROR(
      detail::region_closest_points(ctx, index, queries, place, results.data(), &used));
  if (used) return Status::ok();
  auto answer = [&](size_t at, uint32_t* seed) {
    ClosestPoint cp;
    if (closest_within(index, queries[at], HUGE_VAL, &cp, *seed)) {
      results[at] = cp;
      *seed = cp.triangle;
    } else {
      results[at] = ClosestPoint{};
    }
  };
  return morton_batch(ctx, index, queries, "closest points", answer);
}

Status batch_signed_distances(const Context& ctx, const DistanceIndex& index,
                              Span<const Vec3> queries, SignMethod method, Span<double> results) {
  if (queries.size() != results.size()) {
    return Status::error(StatusCode::kInvalidArgument,
                         "batch_signed_distances: queries and results differ in size");
  }
  SPLINTCORE_ASSERT(index.vertex_start.size() > 0);  // not a pairs_only index
  if (index.mesh->triangles.size() == 0) {
    for (size_t k = 0; k < results.size(); ++k) results[k] = HUGE_VAL;
    return Status::ok();
  }
  struct Signs {
    const DistanceIndex* index;
    const Vec3* queries;
    double* results;
    SignMethod method;
  } signs{&index, queries.data(), results.data(), method};
  bool used = false;
  auto place = [](void* user, size_t at, const ClosestPoint& cp, bool found) {
    const Signs& g = *static_cast<const Signs*>(user);
    if (!found) {
      g.results[at] = HUGE_VAL;
      return;
    }
    SignedDistance sd;
    sd.closest = cp;
    finish_signed(*g.index, g.queries[at], g.method, &sd);
    g.results[at] = sd.distance;
  };
  SPLINTCORE_RETURN_IF_ERROR(
      detail::region_closest_points(ctx, index, queries, place, &signs, &used));
  if (used) return Status::ok();
  auto answer = [&](size_t at, uint32_t* seed) {
    SignedDistance sd;
    if (closest_within(index, queries[at], HUGE_VAL, &sd.closest, *seed)) {
      finish_signed(index, queries[at], method, &sd);
      results[at] = sd.distance;
      *seed = sd.closest.triangle;
    } else {
      results[at] = HUGE_VAL;
    }
  };
  return morton_batch(ctx, index, queries, "signed distances", answer);
}

Status sample_sdf(const Context& ctx, const DistanceIndex& index, const SdfGrid& grid,
                  SignMethod method, uint32_t z_begin, uint32_t z_end, Span<float> out) {
  if (!(grid.spacing > 0) || !(grid.band > 0) || z_begin > z_end || z_end > grid.nz) {
    return Status::error(StatusCode::kInvalidArgument, "sample_sdf: bad grid or z range");
  }
  const uint64_t layer = uint64_t{grid.nx} * grid.ny;
  uint64_t need = 0;  // checked: 2^31 x 2^31 x 4 layers would wrap to 0 and pass
  if (!checked_mul(layer, z_end - z_begin, &need) || out.size() != need) {
    return make_error(StatusCode::kInvalidArgument, "sample_sdf: output holds ", out.size(),
                      " values, the layers need ", layer, " x ", z_end - z_begin);
  }
  if (method == SignMethod::kAuto) {
    method = index.closed_manifold ? SignMethod::kPseudonormal : SignMethod::kWindingNumber;
  }
  const double band = grid.band;
  const float fband = static_cast<float>(band);
  // Beyond the band only the sign matters. On a closed mesh (closed_manifold: its winding
  // number is 0 or 1 off the surface) it changes only across the surface, and a sample beyond
  // the band lies farther than the spacing from it: so with a spacing of at most half the
  // band, the segment from the previous sample of the row does not meet the surface, and the
  // sample takes that one's sign. That sample lies more than half the band from the surface
  // (else this one would be within the band), where its own sign is well decided. Only a
  // row's first samples beyond the band then need the winding number (on open meshes, whose
  // winding number varies off the surface, every sample beyond the band does).
  const bool carry = index.closed_manifold && grid.spacing <= 0.5 * band;
  for (uint32_t z = z_begin; z < z_end; ++z) {
    SPLINTCORE_RETURN_IF_ERROR(
        report_progress(ctx, "distance volume", z - z_begin, z_end - z_begin));
    auto row = [&](uint32_t y) {
      float* dst = out.data() + (uint64_t{z - z_begin} * grid.ny + y) * grid.nx;
      uint32_t seed = kNoNeighbor;
      bool known = false, inside = false;  // the previous sample's sign
      for (uint32_t x = 0; x < grid.nx; ++x) {
        const Vec3 p = grid.origin + Vec3{grid.spacing * x, grid.spacing * y, grid.spacing * z};
        // Within the band the search bounded by the band finds the same closest point as an
        // unbounded one (same tie-breaks); the previous sample of the row seeds it.
        SignedDistance sd;
        if (closest_within(index, p, band * band, &sd.closest, seed)) {
          seed = sd.closest.triangle;
          finish_signed(index, p, method, &sd);
          double d = sd.distance;
          inside = d < 0;
          d = d > band ? band : (d < -band ? -band : d);
          dst[x] = static_cast<float>(d);
        } else {
          if (!(carry && known)) inside = winding_number(index, p) >= 0.5;
          dst[x] = inside ? -fband : fband;
        }
        known = true;
      }
    };
    parallel_for_each(ctx.executor, grid.ny, row);
  }
  return Status::ok();
}

}  // namespace splintcore
