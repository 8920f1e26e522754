// compute_outline (outline.h): the frame, the bite opening, the arch and the picks.
#include <algorithm>
#include <cmath>

#include "core/fminmax.h"
#include "outline_internal.h"

namespace splintcore {

using namespace outline_detail;

namespace {

constexpr uint32_t kMaxAdvanceSteps = 100;
constexpr uint32_t kBisections = 80;
constexpr double kOpeningTolerance = 1e-9;  // mm
constexpr double kNearReachMm = 1.0;        // open_bite's first band
constexpr double kStepSlackMm = 0.1;        // the opening's steps: exact this past the target

Status check_options(const OutlineOptions& o) {
  auto in = [](double v, double lo, double hi) { return v >= lo && v <= hi; };
  if (!(o.indentation_depth_mm > 0 && o.indentation_depth_mm <= 5)) {
    return make_error(StatusCode::kInvalidArgument,
                      "outline: indentation_depth_mm must be in (0, 5], not ",
                      o.indentation_depth_mm);
  }
  if (!in(o.overhang_mm, 0, 10)) {
    return make_error(StatusCode::kInvalidArgument, "outline: overhang_mm must be in [0, 10], not ",
                      o.overhang_mm);
  }
  if (!in(o.pick_spacing_mm, 2, 20)) {
    return make_error(StatusCode::kInvalidArgument,
                      "outline: pick_spacing_mm must be in [2, 20], not ", o.pick_spacing_mm);
  }
  if (o.has_bite_opening && !in(o.bite_opening_mm, 0.1, 10)) {
    return make_error(StatusCode::kInvalidArgument,
                      "outline: bite_opening_mm must be in [0.1, 10], not ", o.bite_opening_mm);
  }
  if (!in(o.max_gap_mm, 0.1, 50)) {
    return make_error(StatusCode::kInvalidArgument,
                      "outline: max_gap_mm must be in [0.1, 50], not ", o.max_gap_mm);
  }
  return Status::ok();
}

}  // namespace

namespace outline_detail {

Status check_jaw(const Mesh& m, const char* who, const char* name, double* longest_edge) {
  if (m.triangles.empty() || m.vertices.empty()) {
    return make_error(StatusCode::kInvalidMesh, who, ": the ", name, " is empty");
  }
  for (size_t i = 0; i < m.vertices.size(); ++i) {
    if (!is_finite(m.vertices[i])) {
      return make_error(StatusCode::kNonFinite, who, ": the ", name,
                        " has a vertex that is not "
                        "finite (NaN or infinity): vertex ",
                        i)
          .at_index(i);
    }
  }
  // The squared edges of two triangles at a time, one a lane (each lane's x, y and z of a
  // corner loaded together): each edge's squared length in its lane as dot() computes it (x
  // then y then z; c - a's square is a - c's), the same bits. The largest of them all (a
  // maximum of finite values: the same whatever the order it is taken in). A triangle's
  // corners are checked before it is read, in triangle order (the first bad one is named).
  const size_t n = m.vertices.size();
  const Vec3* v = m.vertices.data();
  auto bad_triangle = [&](size_t i) {
    return make_error(StatusCode::kInvalidMesh, who, ": the ", name, "'s triangle ", i,
                      " refers to a vertex that does not exist")
        .at_index(i);
  };
  auto corners_exist = [n](const Triangle& t) { return t.v[0] < n && t.v[1] < n && t.v[2] < n; };
  const size_t count = m.triangles.size();
  if (longest_edge == nullptr) {
    for (size_t i = 0; i < count; ++i) {
      if (!corners_exist(m.triangles[i])) return bad_triangle(i);
    }
    return Status::ok();
  }
  Lanes2 e2_lanes = {0, 0};
  for (size_t i = 0; i < count; i += 2) {
    const Triangle& t0 = m.triangles[i];
    if (!corners_exist(t0)) return bad_triangle(i);
    // An odd count: the last triangle twice.
    const size_t j = i + 1 < count ? i + 1 : i;
    const Triangle& t1 = m.triangles[j];
    if (!corners_exist(t1)) return bad_triangle(j);
    const Vec3 &a0 = v[t0.v[0]], &b0 = v[t0.v[1]], &c0 = v[t0.v[2]];
    const Vec3 &a1 = v[t1.v[0]], &b1 = v[t1.v[1]], &c1 = v[t1.v[2]];
    const Lanes2 ax = {a0.x, a1.x}, ay = {a0.y, a1.y}, az = {a0.z, a1.z};
    const Lanes2 bx = {b0.x, b1.x}, by = {b0.y, b1.y}, bz = {b0.z, b1.z};
    const Lanes2 cx = {c0.x, c1.x}, cy = {c0.y, c1.y}, cz = {c0.z, c1.z};
    const Lanes2 abx = ax - bx, aby = ay - by, abz = az - bz;
    const Lanes2 bcx = bx - cx, bcy = by - cy, bcz = bz - cz;
    const Lanes2 cax = cx - ax, cay = cy - ay, caz = cz - az;
    const Lanes2 lab = (abx * abx + aby * aby) + abz * abz;
    const Lanes2 lbc = (bcx * bcx + bcy * bcy) + bcz * bcz;
    const Lanes2 lca = (cax * cax + cay * cay) + caz * caz;
    e2_lanes = lab > e2_lanes ? lab : e2_lanes;
    e2_lanes = lbc > e2_lanes ? lbc : e2_lanes;
    e2_lanes = lca > e2_lanes ? lca : e2_lanes;
  }
  const double e2 = e2_lanes[0] > e2_lanes[1] ? e2_lanes[0] : e2_lanes[1];
  *longest_edge = std::sqrt(e2);
  return Status::ok();
}

Status check_jaws(const Context& ctx, const Mesh& maxilla, const Mesh& mandible, const char* who,
                  double* edge_maxilla, double* edge_mandible) {
  const Mesh* jaws[2] = {&maxilla, &mandible};
  const char* names[2] = {"maxilla", "mandible"};
  double* edges[2] = {edge_maxilla, edge_mandible};
  Status status[2];
  auto task = [&](uint32_t i) { status[i] = check_jaw(*jaws[i], who, names[i], edges[i]); };
  parallel_for_each(ctx.executor, 2, task);
  return status[0].is_ok() ? status[1] : status[0];
}

DistanceIndexOptions band_index_options() {
  DistanceIndexOptions o;
  o.pairs_only = true;
  return o;
}

}  // namespace outline_detail

namespace {

// The mandible's move along -n that makes the smallest distance between the jaws exactly the
// opening asked: conservative advancement (a move by delta changes the distance by at most
// delta, so stepping by the distance still missing never overshoots), then bisection if it
// has not converged. Without an opening asked, the jaws must already be apart.
//
// The steps converge (Newton's, quadratically): once the last distance measured was a
// separated pair's (its rate along the move models the step), or a step is at most
// kCollectStepMm long, the search there also keeps every pair within the bound it starts from
// (the last closest pair's distance there) plus a margin, in the pool's room: pool_reach. A
// move by m from there changes each pair's distance by at most m, so a pair left out lies
// farther than pool_reach - m; where the pool's closest lies nearer than that (and a rounding
// slack), it is the full search's answer, bit for bit (the same pairs' computed distances, the
// same least). So the next steps near there are a scan of the pool, checked after the scan
// (else the full search). A bound above the distance found there leaves room for the steps
// that follow: the step that overshot the target, and the Newton steps back to it, lie within
// about the overshoot. (A wider margin holds many more pairs where the jaws' surfaces run
// parallel, and costs more to collect.)
constexpr double kCollectStepMm = 0.1;
constexpr double kMinPoolMarginMm = 1e-6;
constexpr double kPoolSlackMm = 2.5e-7;  // over the computed distances' rounding
constexpr size_t kPoolPairs = 32768;

struct Opener {
  const Context& ctx;
  const DistanceIndex& upper;
  const DistanceIndex& lower;
  Vec3 n;
  double reach = 0;  // the distance is exact up to this (above it, some value above it)
  Span<TrianglePairIds> pool;
  // The last closest pair: its distance at the next t bounds the search (the same result,
  // found sooner).
  bool warm = false;
  uint32_t pair_a = 0, pair_b = 0;
  bool has_last = false;
  double last_t = 0, last_distance = 0;
  size_t pooled = 0;  // pairs in the pool (0: none): every pair within pool_reach at pool_t
  double pool_t = 0, pool_reach = 0;

  Opener(const Context& c, const DistanceIndex& u, const DistanceIndex& l, const Vec3& normal)
      : ctx(c), upper(u), lower(l), n(normal) {}

  // New bands (the indexes rebuilt in place), a new reach and a new pool.
  void restart(double new_reach, Span<TrianglePairIds> new_pool) {
    reach = new_reach;
    pool = new_pool;
    warm = has_last = false;
    pooled = 0;
  }

  Status distance(double t, MeshPairDistance* d) {
    const Vec3 offset = n * (-t);
    if (pooled > 0) {
      SPLINTCORE_RETURN_IF_ERROR(candidate_pair_distance(
          upper, lower, Span<const TrianglePairIds>(pool.data(), pooled), offset, d));
      if (d->distance + std::fabs(t - pool_t) + kPoolSlackMm < pool_reach) {
        return remember(t, *d);
      }
    }
    double bound = HUGE_VAL;
    if (warm) {
      const Mesh& a = *upper.mesh;
      const Mesh& b = *lower.mesh;
      const Triangle& ta = a.triangles[pair_a];
      const Triangle& tb = b.triangles[pair_b];
      bound = triangle_pair_distance(a.vertices[ta.v[0]], a.vertices[ta.v[1]], a.vertices[ta.v[2]],
                                     b.vertices[tb.v[0]] + offset, b.vertices[tb.v[1]] + offset,
                                     b.vertices[tb.v[2]] + offset, nullptr, nullptr);
      bound = bound * (1 + 1e-9) + 1e-9;  // over any rounding: the pair itself is found
    }
    const double step = std::fabs(t - last_t);
    const bool modelled = last_distance > 0 && last_distance < HUGE_VAL;
    if (bound < HUGE_VAL && has_last && (modelled || step <= kCollectStepMm) && pool.size() > 0) {
      size_t count = 0;
      const double margin = max_of(step <= kCollectStepMm ? step : 0.0, kMinPoolMarginMm);
      SPLINTCORE_RETURN_IF_ERROR(
          mesh_pair_distance_collect(ctx, upper, lower, offset, bound + margin, pool, &count, d));
      pooled = d->distance <= bound && count <= pool.size() ? count : 0;
      pool_t = t;
      pool_reach = bound + margin;
    } else {
      SPLINTCORE_RETURN_IF_ERROR(mesh_pair_distance(ctx, upper, lower, offset, bound, d));
    }
    if (!(d->distance <= bound) && bound < HUGE_VAL) {
      SPLINTCORE_RETURN_IF_ERROR(mesh_pair_distance(ctx, upper, lower, offset, HUGE_VAL, d));
    }
    return remember(t, *d);
  }

  // Whether the jaws meet at t: when they do, that is all the distance there says (0, and
  // they intersect), and one meeting pair, found at once, is as good a warm start as any.
  // (mesh_pair_distance would go on through every pair of touching boxes for the least ids.)
  Status meets(double t, bool* meet, MeshPairDistance* d) {
    SPLINTCORE_RETURN_IF_ERROR(mesh_pair_meet(ctx, upper, lower, n * (-t), meet, d));
    return *meet ? remember(t, *d) : Status::ok();
  }

  Status remember(double t, const MeshPairDistance& d) {
    has_last = true;
    last_t = t;
    last_distance = d.distance;
    if (d.distance < HUGE_VAL) {
      warm = true;
      pair_a = d.triangle_a;
      pair_b = d.triangle_b;
    }
    return Status::ok();
  }
};

// The distance's rate along the move at the closest pair (point_a - point_b along n, unit):
// exact while the pair's features stay (a vertex over a face: linear), 0 when unknown.
double opening_slope(const MeshPairDistance& pair, const Vec3& n) {
  if (!(pair.distance > 0) || !(pair.distance < HUGE_VAL)) return 0;
  return dot(pair.point_a - pair.point_b, n) / pair.distance;
}

Status advance(Opener& op, double target, double d0, double slope0, double* t_out, double* d_out,
               uint32_t* steps) {
  double t = 0, d = d0, slope = slope0;
  MeshPairDistance pair;
  *steps = 0;
  // The conservative step never passes the first root. Beyond it: a Newton step by the
  // closest pair's rate (else a secant through the last two points below the target), kept
  // short of the Lipschitz bound from the nearest point above the target (Illinois false
  // position when it would not be), and never short of the conservative step.
  double t_prev = 0, d_prev = -1, t_hi = HUGE_VAL, f_hi = 0;
  bool kept_low = false;
  while (*steps < kMaxAdvanceSteps && std::fabs(d - target) > kOpeningTolerance) {
    const double safe = t + (d == 0 ? target : target - d);
    const bool secant = d_prev > 0 && d > d_prev;
    double next = safe;
    bool model = true;
    if (slope > 0) {
      next = t + (target - d) / slope;
    } else if (secant) {
      next = t + (target - d) * (t - t_prev) / (d - d_prev);
    } else {
      model = false;
    }
    if (t_hi < HUGE_VAL) {
      if (!model || !(next <= t_hi - f_hi)) {
        next = t + (target - d) * (t_hi - t) / (f_hi - (d - target));
        next = min_of(next, t_hi - f_hi);
      }
    } else {
      next = min_of(next, t + 4 * (target - d));
    }
    next = max_of(next, safe);
    SPLINTCORE_RETURN_IF_ERROR(op.distance(next, &pair));
    ++*steps;
    if (pair.distance > target + kOpeningTolerance) {
      t_hi = next;
      f_hi = min_of(pair.distance, op.reach) - target;  // at most the true excess
      kept_low = false;
      continue;
    }
    if (kept_low && t_hi < HUGE_VAL) f_hi *= 0.5;
    kept_low = true;
    t_prev = t;
    d_prev = d;
    t = next;
    d = pair.distance;
    slope = opening_slope(pair, op.n);
  }
  if (std::fabs(d - target) > kOpeningTolerance && d < target) {
    // Slow convergence (a contact sliding almost along the move): bracket and bisect.
    double lo = t, hi = t + (target - d);
    for (uint32_t k = 0; k < 64; ++k) {
      SPLINTCORE_RETURN_IF_ERROR(op.distance(hi, &pair));
      if (pair.distance >= target) break;
      lo = hi;
      hi += target;
    }
    for (uint32_t k = 0; k < kBisections && hi - lo > 1e-12; ++k) {
      const double mid = 0.5 * (lo + hi);
      SPLINTCORE_RETURN_IF_ERROR(op.distance(mid, &pair));
      (pair.distance < target ? lo : hi) = mid;
      ++*steps;
    }
    t = hi;
    SPLINTCORE_RETURN_IF_ERROR(op.distance(t, &pair));
    d = pair.distance;
  }
  *t_out = t;
  *d_out = d;
  return Status::ok();
}

// Jaws farther apart than the opening asked: the mandible moves back towards the maxilla
// (t < 0) until the distance is the target. A move by delta changes the distance by at most
// delta, so a step back by the excess never passes the first root; a Newton step by the
// closest pair's rate (at most 1) goes at least as far and may pass it, which then brackets
// the root for bisection. The distance at every t visited is exact (within the bands' reach:
// the distance as given and everything nearer).
Status close_to(Opener& op, double target, double d0, double slope0, double* t_out, double* d_out,
                uint32_t* steps) {
  double t = 0, d = d0, slope = slope0;
  MeshPairDistance pair;
  *steps = 0;
  double below = -HUGE_VAL;  // a t known to be past the root (distance under the target)
  while (*steps < kMaxAdvanceSteps && d - target > kOpeningTolerance) {
    double next = t - (d - target);  // the conservative step
    if (slope > 0) next = min_of(next, t - (d - target) / slope);
    if (!(next > below)) next = 0.5 * (t + below);  // inside the bracket
    SPLINTCORE_RETURN_IF_ERROR(op.distance(next, &pair));
    ++*steps;
    if (pair.distance < target - kOpeningTolerance) {
      below = next;  // passed it: the root lies in (below, t)
      slope = 0;     // bisect from here on
      continue;
    }
    t = next;
    d = pair.distance;
    slope = below > -HUGE_VAL ? 0 : opening_slope(pair, op.n);
  }
  if (d - target > kOpeningTolerance && below > -HUGE_VAL) {
    double lo = below, hi = t;  // d(lo) < target < d(hi)
    for (uint32_t k = 0; k < kBisections && hi - lo > 1e-12; ++k) {
      const double mid = 0.5 * (lo + hi);
      SPLINTCORE_RETURN_IF_ERROR(op.distance(mid, &pair));
      ++*steps;
      if (std::fabs(pair.distance - target) <= kOpeningTolerance) {
        hi = mid;
        break;
      }
      (pair.distance < target ? lo : hi) = mid;
    }
    t = hi;
    SPLINTCORE_RETURN_IF_ERROR(op.distance(t, &pair));
    d = pair.distance;
  }
  *t_out = t;
  *d_out = d;
  return Status::ok();
}

// The part of each jaw that can come within `reach` of the other while the mandible moves
// along n away from the maxilla (reaches = 1), or also back towards it by at most `reach`
// (reaches = 2): a pair of points at most `reach` apart differs by at most that much in height
// along n, and by at most that much across it. So a maxilla triangle whose lowest vertex lies
// more than `reaches` reach above the mandible's highest vertex near it (within reach plus
// two of the longest edge, across n: a point of a triangle lies within its longest edge of
// every vertex) has no such pair, nor a mandible triangle whose highest vertex lies that much
// below the maxilla's lowest near it. The "near" comes from the frame's grid (the jaws as
// given), each column's extreme over the columns around; too far around (long edges), the
// jaws' global extremes. The bands only prune: the distances are the same whatever they keep.
// ids[k]: the jaw's triangle of view triangle k.
struct JawBand {
  Mesh view;
  uint32_t* ids = nullptr;
};

constexpr uint32_t kMaxBandRadius = 40;  // columns around, at most

// The extreme (the least when `lowest`, else the greatest) of each window of a line of n
// values at `stride`: out[i] over in[max(0, i - r) .. min(n - 1, i + r)], a few comparisons a
// value whatever r (van Herk and Gil-Werman): blocks of 2 r + 1 values, their running extremes
// from the block's end (into out) and from its start (into g, which may be `in` itself: each
// is read before it is written), and each window, which spans at most two blocks, from the
// end's running extreme at its first value and the start's at its last (a window shortened at
// an end of the line lies in one block and starts at the block's start or ends at the line's
// end). out[i] is written after its last read (in descending i). The same values as comparing
// the whole window (a maximum or minimum is one of the values; of a +0 and a -0 either may come,
// which compare equal, and to which the band adds a margin that is not 0).
void sliding_extreme(const double* in, double* g, double* out, size_t stride, uint32_t n,
                     uint32_t r, bool lowest) {
  auto pick = [lowest](double a, double b) { return lowest ? (b < a ? b : a) : (b > a ? b : a); };
  const uint32_t w = 2 * r + 1;
  for (uint32_t b0 = 0; b0 < n; b0 += w) {
    const uint32_t b1 = n - b0 > w ? b0 + w - 1 : n - 1;
    out[b1 * stride] = in[b1 * stride];
    for (uint32_t i = b1; i-- > b0;) out[i * stride] = pick(out[(i + 1) * stride], in[i * stride]);
    double e = in[b0 * stride];
    g[b0 * stride] = e;
    for (uint32_t i = b0 + 1; i <= b1; ++i) {
      e = pick(e, in[i * stride]);
      g[i * stride] = e;
    }
  }
  for (uint32_t i = n; i-- > 0;) {
    const uint32_t lo = i > r ? i - r : 0;
    const uint32_t hi = n - 1 - i > r ? i + r : n - 1;
    double e;
    if (lo / w != hi / w) {
      e = pick(out[lo * stride], g[hi * stride]);
    } else {
      e = lo % w == 0 ? g[hi * stride] : out[lo * stride];
    }
    out[i * stride] = e;
  }
}

// Per column, the extreme height of `jaw` over the columns within `radius` (the highest for
// the mandible, the lowest for the maxilla): rows, then columns (sliding_extreme).
// `rows` and `both` hold a column each.
void extreme_around(const Grid& g, int jaw, uint32_t radius, double* rows, double* both) {
  const bool lowest = jaw == 0;
  for (uint32_t iy = 0; iy < g.ny; ++iy) {
    const size_t row = static_cast<size_t>(iy) * g.nx;
    sliding_extreme(g.h[jaw] + row, both + row, rows + row, 1, g.nx, radius, lowest);
  }
  for (uint32_t ix = 0; ix < g.nx; ++ix) {
    sliding_extreme(rows + ix, rows + ix, both + ix, g.nx, g.ny, radius, lowest);
  }
}

// The other jaw's extreme near each column (nullptr: everywhere the global `bound`).
struct BandLimit {
  const Grid* g = nullptr;
  const Frame* f = nullptr;
  const double* other = nullptr;  // per column, the other jaw's extreme around it
  double bound = 0;               // the global one
  double margin = 0;              // reaches times reach
  // The other jaw's global extreme plus (the maxilla) or less (the mandible) `margin`, as
  // computed: `other` plus or less `margin` lies on its near side (rounding is monotone).
  double beyond = 0;
};

// A triangle is kept when one of its vertices lies within the margin of the other jaw's
// extreme near it (the columns around reach one edge further than the pairs need, so the
// vertex nearest the other jaw may stand for the whole triangle): its vertices' marks (near: 1
// when within the margin). `near` comes in with mark_reachable's marks: a vertex past the
// other jaw's global extreme and the margin (0) lies past its extreme near and past the
// global bound too, and stays 0 (most of the jaw: neither its height nor its column need be
// found again).
void mark_band(const Mesh& m, bool upper, const BandLimit& limit, uint8_t* near) {
  const Frame& f = *limit.f;
  const PlaneAxes axes(f);
  const size_t nv = m.vertices.size();
  for (size_t i = 0; i < nv; ++i) {
    if (near[i] == 0) continue;
    const Vec3& v = m.vertices[i];
    const double h = dot(v, f.n);
    double bound = limit.bound;
    if (limit.other != nullptr) {
      const Lanes2 xy = axes.xy(v);
      bound = limit.other[limit.g->cell_of(xy[0], xy[1])];
      bound += upper ? limit.margin : -limit.margin;
    }
    near[i] = upper ? h <= bound : h >= bound;
  }
}

// The band of the marked vertices (mark_band: bit 0 of near): the triangles with a near
// vertex, counted (kept) with the vertices they use (used), which count_band marks in bit 1.
void count_band(const Mesh& m, uint8_t* near, size_t* kept, size_t* used) {
  size_t k = 0, u = 0;
  for (const Triangle& t : m.triangles) {
    if (((near[t.v[0]] | near[t.v[1]] | near[t.v[2]]) & 1) == 0) continue;
    ++k;
    for (int c = 0; c < 3; ++c) {
      const uint32_t v = t.v[c];
      u += (near[v] & 2) == 0 ? 1u : 0u;
      near[v] = static_cast<uint8_t>(near[v] | 2);
    }
  }
  *kept = k;
  *used = u;
}

// A band's arrays (count_band's sizes) and a jaw's vertex renumbering, from the arena.
struct BandArrays {
  uint32_t* ids = nullptr;
  uint32_t* renumber = nullptr;
  Triangle* tris = nullptr;
  Vec3* verts = nullptr;
  size_t kept = 0, used = 0;
};

Status allocate_band(Arena& arena, size_t vertices, size_t kept, size_t used, BandArrays* out) {
  out->kept = kept;
  out->used = used;
  out->ids = arena.allocate_array<uint32_t>(kept > 0 ? kept : 1);
  out->renumber = arena.allocate_array<uint32_t>(vertices > 0 ? vertices : 1);
  out->tris = arena.allocate_array<Triangle>(kept > 0 ? kept : 1);
  out->verts = arena.allocate_array<Vec3>(used > 0 ? used : 1);
  if (out->ids == nullptr || out->renumber == nullptr || out->tris == nullptr ||
      out->verts == nullptr) {
    return arena.exhausted_status();
  }
  return Status::ok();
}

// The band's triangles into its arrays: their ids, then the kept triangles' vertices copied
// (numbered in order of first use, the corners in their order): the same coordinates, so the
// same distances, from a few hundred kilobytes that stay in cache instead of the whole jaw's.
void fill_band(const Mesh& m, const uint8_t* near, const BandArrays& a, JawBand* out) {
  const size_t nv = m.vertices.size(), nt = m.triangles.size();
  size_t kept = 0;
  for (size_t i = 0; i < nt; ++i) {
    const Triangle& t = m.triangles[i];
    if (((near[t.v[0]] | near[t.v[1]] | near[t.v[2]]) & 1) != 0) {
      a.ids[kept++] = static_cast<uint32_t>(i);
    }
  }
  out->ids = a.ids;
  std::fill(a.renumber, a.renumber + nv, kNoTip);
  uint32_t used = 0;
  for (size_t k = 0; k < kept; ++k) {
    const Triangle& t = m.triangles[a.ids[k]];
    for (int c = 0; c < 3; ++c) {
      uint32_t& r = a.renumber[t.v[c]];
      if (r == kNoTip) r = used++;
      a.tris[k].v[c] = r;
    }
  }
  for (size_t i = 0; i < nv; ++i) {
    if (a.renumber[i] != kNoTip) a.verts[a.renumber[i]] = m.vertices[i];
  }
  out->view = mesh_view(Span<const Vec3>(a.verts, used), Span<const Triangle>(a.tris, kept));
}

// The distance between the nearest pair of column tips (the vertex each column of the frame's
// grid shows the other jaw, for columns that see both): at least the jaws' smallest distance.
// Infinity when no column sees both.
double tip_pair_bound(const Mesh& maxilla, const Mesh& mandible, const Grid& g) {
  const size_t cells = static_cast<size_t>(g.nx) * g.ny;
  double best = HUGE_VAL;
  for (size_t i = 0; i < cells; ++i) {
    if (g.tip[0][i] == kNoTip || g.tip[1][i] == kNoTip) continue;
    const Vec3 d = maxilla.vertices[g.tip[0][i]] - mandible.vertices[g.tip[1][i]];
    const double d2 = dot(d, d);
    best = d2 < best ? d2 : best;
  }
  return std::sqrt(best);
}

// The opening's band indexes: leaves of 16 triangles (the most a leaf holds), not 8 (a
// shallower tree for the few searches over the bands' near-parallel occlusal surfaces, where
// most leaf pairs within reach are opened anyway: about 11 M instructions less an outline of
// the real dentition at 12, 6 M more at 16). The searches' answers do not depend on the tree:
// the least (distance, triangle ids).
constexpr uint32_t kOpeningLeafSize = 16;

DistanceIndexOptions opening_index_options() {
  DistanceIndexOptions o = band_index_options();
  o.leaf_size = kOpeningLeafSize;
  return o;
}

// The smallest distance between the jaws (the mandible moved by -t n) exactly for every t the
// opening visits, when it is at most `reach` (else some value above `reach`).
struct BandedOpener {
  JawBand upper, lower;
  DistanceIndex upper_index, lower_index;
};

// The part of a jaw that can come within the margin of the other jaw's global extreme (the
// maxilla's vertices at most `beyond` high, the mandible's at least): near[i] = 1. Every
// triangle with a pair within reach has a vertex there (the bands' global argument).
void mark_reachable(const Mesh& m, bool upper, double beyond, const Vec3& n, uint8_t* near) {
  const size_t nv = m.vertices.size();
  for (size_t i = 0; i < nv; ++i) {
    const double h = dot(m.vertices[i], n);
    near[i] = upper ? h <= beyond : h >= beyond;
  }
}

// The squared longest edge of the triangles with a marked vertex (0 when none).
double marked_longest_edge2(const Mesh& m, const uint8_t* near) {
  double e2 = 0;
  for (const Triangle& t : m.triangles) {
    if ((near[t.v[0]] | near[t.v[1]] | near[t.v[2]]) == 0) continue;
    const Vec3 &a = m.vertices[t.v[0]], &b = m.vertices[t.v[1]], &c = m.vertices[t.v[2]];
    const double l[3] = {dot(a - b, a - b), dot(b - c, b - c), dot(c - a, c - a)};
    for (const double x : l) e2 = x > e2 ? x : e2;
  }
  return e2;
}

// The bands' reasoning needs the longest edge of the triangles that can come within reach
// only: those with a vertex within the margin of the other jaw's global extreme (every
// triangle of a pair within reach is one: mark_reachable), not the whole jaws'. (Any edge at
// least theirs gives bands that hold every pair within reach: the same distances.)
Status banded_opener(const Context& ctx, const Mesh& maxilla, const Mesh& mandible, const Frame& f,
                     const Grid& g, double reach, double margin, BandedOpener* b) {
  // The maxilla's lowest vertex and the mandible's highest along n: the extremes of the grid's
  // columns (every vertex went into one, its height dot(v + 0, n): the value of dot(v, n), up
  // to the sign of a zero, which compares equal), not two more passes over the vertices.
  double low_u = HUGE_VAL, high_l = -HUGE_VAL;
  const size_t cells = static_cast<size_t>(g.nx) * g.ny;
  for (size_t i = 0; i < cells; ++i) {
    low_u = g.h[0][i] < low_u ? g.h[0][i] : low_u;
    high_l = g.h[1][i] > high_l ? g.h[1][i] : high_l;
  }
  BandLimit up{&g, &f, nullptr, high_l + margin, margin + 1e-9, 0};
  BandLimit down{&g, &f, nullptr, low_u - margin, margin + 1e-9, 0};
  up.beyond = high_l + up.margin;
  down.beyond = low_u - down.margin;
  uint8_t* near_u = ctx.arena->allocate_array<uint8_t>(maxilla.vertices.size());
  uint8_t* near_l = ctx.arena->allocate_array<uint8_t>(mandible.vertices.size());
  if (near_u == nullptr || near_l == nullptr) return ctx.arena->exhausted_status();
  double edge2[2] = {0, 0};
  auto reachable = [&](uint32_t jaw) {
    const Mesh& m = jaw == 0 ? maxilla : mandible;
    uint8_t* near = jaw == 0 ? near_u : near_l;
    mark_reachable(m, jaw == 0, jaw == 0 ? up.beyond : down.beyond, f.n, near);
    edge2[jaw] = marked_longest_edge2(m, near);
  };
  parallel_for_each(ctx.executor, 2, reachable);
  const double edge = std::sqrt(edge2[0] > edge2[1] ? edge2[0] : edge2[1]);
  const double across = (reach + 3 * edge) / kCellMm + 2;  // columns, with the rounding
  if (across <= kMaxBandRadius) {
    // Both jaws' extremes, one task each (each writes its own arrays).
    const uint32_t radius = static_cast<uint32_t>(across);
    const size_t cells_all = static_cast<size_t>(g.nx) * g.ny;
    double* work[4];
    for (double*& w : work) {
      w = ctx.arena->allocate_array<double>(cells_all);
      if (w == nullptr) return ctx.arena->exhausted_status();
    }
    auto extremes = [&](uint32_t jaw) {
      extreme_around(g, static_cast<int>(jaw), radius, work[2 * jaw], work[2 * jaw + 1]);
    };
    parallel_for_each(ctx.executor, 2, extremes);
    up.other = work[3];
    down.other = work[1];
  }
  // The marks of both jaws and their bands' sizes, one task each (each writes its own).
  size_t kept[2] = {0, 0}, used[2] = {0, 0};
  auto mark = [&](uint32_t jaw) {
    if (jaw == 0) {
      mark_band(maxilla, true, up, near_u);
      count_band(maxilla, near_u, &kept[0], &used[0]);
    } else {
      mark_band(mandible, false, down, near_l);
      count_band(mandible, near_l, &kept[1], &used[1]);
    }
  };
  parallel_for_each(ctx.executor, 2, mark);
  BandArrays arrays[2];
  const Mesh* jaws[2] = {&maxilla, &mandible};
  const uint8_t* near[2] = {near_u, near_l};
  JawBand* bands[2] = {&b->upper, &b->lower};
  DistanceIndex* indexes[2] = {&b->upper_index, &b->lower_index};
  for (int jaw = 0; jaw < 2; ++jaw) {
    SPLINTCORE_RETURN_IF_ERROR(
        allocate_band(*ctx.arena, jaws[jaw]->vertices.size(), kept[jaw], used[jaw], &arrays[jaw]));
  }
  // Each band and its index in a task, the index in a slice of the arena of its bound (the
  // second slice's rest given back): the same index as built in the arena itself. Serially
  // when the slices do not fit (or one thread).
  const DistanceIndexOptions io = opening_index_options();
  const uint64_t need[2] = {distance_index_bound(used[0], kept[0], io),
                            distance_index_bound(used[1], kept[1], io)};
  size_t sizes[2] = {0, 0};
  unsigned char* base =
      has_threads(ctx.executor) ? take_arena_slices(*ctx.arena, need, sizes) : nullptr;
  if (base == nullptr) {
    for (int jaw = 0; jaw < 2; ++jaw) {
      fill_band(*jaws[jaw], near[jaw], arrays[jaw], bands[jaw]);
      SPLINTCORE_RETURN_IF_ERROR(build_distance_index(ctx, bands[jaw]->view, io, indexes[jaw]));
    }
    return Status::ok();
  }
  Arena slices[2] = {Arena(base, sizes[0]), Arena(base + sizes[0], sizes[1])};
  Status built[2];
  auto band = [&](uint32_t jaw) {
    fill_band(*jaws[jaw], near[jaw], arrays[jaw], bands[jaw]);
    built[jaw] = build_distance_index(Context(&slices[jaw]), bands[jaw]->view, io, indexes[jaw]);
  };
  parallel_for_each(ctx.executor, 2, band);
  SPLINTCORE_RETURN_IF_ERROR(built[0]);
  SPLINTCORE_RETURN_IF_ERROR(built[1]);
  (void)ctx.arena->try_shrink(base, sizes[0] + sizes[1], sizes[0] + slices[1].used());
  return Status::ok();
}

Status allocate_pool(Arena& arena, Span<TrianglePairIds>* pool) {
  TrianglePairIds* p = arena.allocate_array<TrianglePairIds>(kPoolPairs);
  if (p == nullptr) return arena.exhausted_status();
  *pool = Span<TrianglePairIds>(p, kPoolPairs);
  return Status::ok();
}

Status open_bite(const Context& ctx, const Mesh& maxilla, const Mesh& mandible, const Frame& f,
                 const Grid& g, const OutlineOptions& o, Vec3* offset, OutlineReport* r) {
  ArenaScope scope(*ctx.arena);  // the bands and their indexes go when done
  // Near reach first (the jaws as scanned touch): exact up to it. Farther apart, again with
  // the reach of the largest gap accepted.
  const double target = o.has_bite_opening ? o.bite_opening_mm : 0.0;
  // (A little past the target: the opening's steps past it are then measured exactly, or
  // known to be past the reach.)
  double reach = max_of(target + (o.has_bite_opening ? kStepSlackMm : 0.0), kNearReachMm);
  // The first bands hold the pairs within reach only while the mandible moves away (or
  // stays): enough for the distance as given and for an opening from nearer than asked.
  // Jaws that stand apart by more (a plan's autorotated jaws, a case opened by hand): the
  // nearest pair of column tips is a pair of points, so the smallest distance is at most
  // theirs, and bands of that reach hold it (and, twice as wide, a move back towards the
  // maxilla to the opening asked): one build, not a near one and then the widest.
  double margin = reach;
  const double apart = tip_pair_bound(maxilla, mandible, g);
  if (apart > reach && apart <= o.max_gap_mm + target) {
    reach = apart * (1 + 1e-9) + 1e-9;  // over the rounding of the pair's own distance
    margin = o.has_bite_opening ? 2 * reach : reach;
  }
  // Jaws that meet as given (the usual case: scanned in occlusion) are then only measured at
  // t >= target (advance's first step from a distance of 0 is the target, and it never steps
  // back), where a pair within reach lies at most reach - target apart along n as given: bands
  // of that margin hold those pairs and every meeting pair, and are a fraction of the size
  // (about 71 k triangles, not 181 k, on the real dentition). Jaws that do not meet need the
  // distance as given: the bands of the full margin, built then.
  const double met_margin = reach - target;
  const bool try_met = o.has_bite_opening && margin == reach && met_margin < margin;
  BandedOpener b;
  SPLINTCORE_RETURN_IF_ERROR(
      banded_opener(ctx, maxilla, mandible, f, g, reach, try_met ? met_margin : margin, &b));
  Opener op(ctx, b.upper_index, b.lower_index, f.n);
  Span<TrianglePairIds> pool;
  SPLINTCORE_RETURN_IF_ERROR(allocate_pool(*ctx.arena, &pool));
  op.restart(reach, pool);
  MeshPairDistance d0;
  // With an opening asked, jaws that meet as given need no more than that (without one, the
  // refusal names the meeting pair of least ids: the full search).
  bool meet = false;
  if (o.has_bite_opening) SPLINTCORE_RETURN_IF_ERROR(op.meets(0, &meet, &d0));
  if (!meet && try_met) {
    ctx.arena->rewind(scope.start());
    SPLINTCORE_RETURN_IF_ERROR(banded_opener(ctx, maxilla, mandible, f, g, reach, margin, &b));
    SPLINTCORE_RETURN_IF_ERROR(allocate_pool(*ctx.arena, &pool));
    op.restart(reach, pool);
  }
  if (!meet) SPLINTCORE_RETURN_IF_ERROR(op.distance(0, &d0));
  if (d0.distance > reach || (o.has_bite_opening && d0.distance > target && margin < 2 * reach)) {
    ctx.arena->rewind(scope.start());
    if (d0.distance > reach) reach = o.max_gap_mm + target;
    SPLINTCORE_RETURN_IF_ERROR(banded_opener(ctx, maxilla, mandible, f, g, reach, 2 * reach, &b));
    SPLINTCORE_RETURN_IF_ERROR(allocate_pool(*ctx.arena, &pool));
    op.restart(reach, pool);
    SPLINTCORE_RETURN_IF_ERROR(op.distance(0, &d0));
  }
  const uint32_t tri_u = d0.distance <= reach ? b.upper.ids[d0.triangle_a] : 0;
  const uint32_t tri_l = d0.distance <= reach ? b.lower.ids[d0.triangle_b] : 0;
  r->gap_as_given = d0.distance;
  r->jaws_intersect = d0.intersecting;
  if (d0.distance > o.max_gap_mm) {
    return make_error(StatusCode::kInvalidArgument, "outline: the jaws are more than ",
                      o.max_gap_mm, " mm apart; a wafer bridges at most that");
  }
  *offset = Vec3{};
  r->opening = d0.distance;
  if (!o.has_bite_opening) {
    if (d0.distance > 0) return Status::ok();
    return make_error(StatusCode::kInvalidArgument, "outline: the jaws ",
                      d0.intersecting ? "interpenetrate" : "touch", " as given (maxilla triangle ",
                      tri_u, ", mandible triangle ", tri_l,
                      "): open the bite with \"bite_opening_mm\" (e.g. 2)");
  }
  double t = 0, d = 0;
  if (d0.distance > target) {  // apart by more than asked: closed to it
    SPLINTCORE_RETURN_IF_ERROR(
        close_to(op, target, d0.distance, opening_slope(d0, f.n), &t, &d, &r->opening_steps));
  } else {
    SPLINTCORE_RETURN_IF_ERROR(
        advance(op, target, d0.distance, opening_slope(d0, f.n), &t, &d, &r->opening_steps));
  }
  *offset = f.n * (-t);
  r->opened = true;
  r->mandible_translation = *offset;
  r->opening = d;
  return Status::ok();
}

}  // namespace

uint64_t compute_outline_bound(const Mesh& maxilla, const Mesh& mandible) {
  const uint64_t maxilla_vertices = maxilla.vertices.size(),
                 maxilla_triangles = maxilla.triangles.size();
  const uint64_t mandible_vertices = mandible.vertices.size(),
                 mandible_triangles = mandible.triangles.size();
  // The lattice spans the jaws' extent in a plane, at most their box's diagonal (and
  // kMaxSpanMm); the survey's columns the picks' lines: the picks lie within an overhang
  // (at most 10 mm) of the jaws, the lines reach kMaxReachAcrossMm and an overhang further.
  Aabb box;
  for (const Vec3& v : maxilla.vertices) box.add(v);
  for (const Vec3& v : mandible.vertices) box.add(v);
  double span = box.empty() ? 0 : length(box.hi - box.lo);
  span = is_finite(span) && span < kMaxSpanMm ? span : kMaxSpanMm;
  const uint64_t side = static_cast<uint64_t>(span / kCellMm) + 2;
  const uint64_t cells = side * side;
  const uint64_t column_side =
      static_cast<uint64_t>((span + 2 * (kMaxReachAcrossMm + 10 + 10)) / kCellMm) + 2;
  const uint64_t columns = column_side * column_side;
  const uint64_t buffers =
      2 * arena_array_bound<Pick>(kMaxPicks) + arena_array_bound<Vec3>(kMaxArchPoints);
  const uint64_t grid = 2 * (arena_array_bound<double>(cells) + arena_array_bound<uint32_t>(cells));
  // A jaw's band (a copy of its kept triangles, their ids) and its distance index: the
  // opening's (pairs_only) or the survey's (default options).
  const auto band = [&](uint64_t v, uint64_t t, const DistanceIndexOptions& io) {
    return arena_array_bound<uint32_t>(v) + arena_array_bound<Vec3>(v) +
           arena_array_bound<Triangle>(t) + arena_array_bound<uint32_t>(t) +
           distance_index_bound(v, t, io);
  };
  const auto both = [&](const DistanceIndexOptions& io) {
    return band(maxilla_vertices, maxilla_triangles, io) +
           band(mandible_vertices, mandible_triangles, io);
  };
  const uint64_t jaws = both(opening_index_options());
  // The opening: the bands, the pair search, the columns' reach and the vertices' marks.
  const uint64_t opening = jaws + kPairStackBound + arena_array_bound<TrianglePairIds>(kPoolPairs) +
                           4 * arena_array_bound<double>(cells) +
                           arena_array_bound<uint8_t>(maxilla_vertices) +
                           arena_array_bound<uint8_t>(mandible_vertices);
  // The arch: each jaw's columns' distances and band's vertex marks (the two jaws in tasks),
  // the points and the band's vertices (both reserved once),
  // the sectors, each pass's line, the picks' data and places, the projector's grid.
  const uint64_t points = 2 * cells;
  const uint64_t line_points = 2 * (kLinePoints + 1);
  const uint64_t arch =
      2 * arena_array_bound<double>(cells) + arena_array_bound<uint32_t>(maxilla_vertices) +
      arena_array_bound<uint32_t>(mandible_vertices) + arena_array_bound<ArchPoint>(points) +
      arena_array_bound<ArchPoint>(line_points) + 6 * arena_array_bound<double>(kSectors) +
      (kSmoothPasses + 1) * 9 * arena_array_bound<double>(kMaxArchPoints + 1) +
      arena_array_bound<double>(6 * kMaxPicks) + arena_array_bound<double>(kMaxPicks) +
      (kSmoothPasses + 2) * projector_bound();
  // The survey, after the arch: its columns (reserved once) and the jaws' slabs.
  const uint64_t survey = arena_array_bound<double>(4 * columns) + both(DistanceIndexOptions{});
  // (The frame's rounds before them hold a lattice and every vertex's height, or every
  // vertex's two quotients (anterior_axis, 16 bytes): less than the opening's copies of the
  // vertices.)
  const uint64_t after_frame = opening > arch + survey ? opening : arch + survey;
  return buffers + grid + after_frame;
}

Status compute_outline(const Context& ctx, const Mesh& maxilla, const Mesh& mandible,
                       const OutlineOptions& options, Outline* out) {
  *out = Outline{};
  SPLINTCORE_RETURN_IF_ERROR(check_options(options));
  // (The bands measure the edges they need: banded_opener.)
  SPLINTCORE_RETURN_IF_ERROR(check_jaws(ctx, maxilla, mandible, "outline", nullptr, nullptr));
  Arena& arena = *ctx.arena;
  ArenaScope scope(arena);
  OutlineBuffers buffers;
  buffers.upper = arena.allocate_array<Pick>(kMaxPicks);
  buffers.lower = arena.allocate_array<Pick>(kMaxPicks);
  buffers.arch = arena.allocate_array<Vec3>(kMaxArchPoints);
  if (buffers.upper == nullptr || buffers.lower == nullptr || buffers.arch == nullptr) {
    return arena.exhausted_status();
  }
  {
    ArenaScope work(arena);  // the grid, the indexes and the points go when done
    SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "outline", 0, 3));
    Frame f;
    Grid g;
    Plane plane;
    SPLINTCORE_RETURN_IF_ERROR(find_frame(ctx, maxilla, mandible, &f, &g, &plane));
    out->report.occlusal_normal = f.n;
    out->report.anterior = f.e1;
    SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "outline", 1, 3));
    Vec3 offset;
    SPLINTCORE_RETURN_IF_ERROR(
        open_bite(ctx, maxilla, mandible, f, g, options, &offset, &out->report));
    // The move is along n: the columns stay; only the mandible's heights change.
    if (out->report.opened) {
      SPLINTCORE_RETURN_IF_ERROR(fill_heights(arena, ctx.executor, mandible, offset, f, 1, &g));
    }
    SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "outline", 2, 3));
    SPLINTCORE_RETURN_IF_ERROR(
        arch_and_picks(ctx, maxilla, mandible, offset, f, g, plane, options, buffers, out));
    out->report.insertion_direction = f.n;
    if (options.survey) {
      SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "outline", 3, 4));
      SPLINTCORE_RETURN_IF_ERROR(survey_direction(ctx, maxilla, mandible, offset, f, out->upper,
                                                  out->lower, &out->report));
    }
  }
  scope.commit();
  return report_progress(ctx, "outline", 3, 3);
}

}  // namespace splintcore
