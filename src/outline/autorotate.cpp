// autorotate_mandible (outline.h): the mandible turned about the condylar hinge axis until the
// jaws are the opening asked apart, the first time it closes to it. Conservative advancement
// (Mirtich, "Impulse-based Dynamic Simulation of Rigid Body Systems", PhD thesis, UC Berkeley,
// 1996, ch. 4) with the motion bound of a rotation (Zhang, Lee and Kim, "Interactive continuous
// collision detection for non-convex polyhedra", The Visual Computer 22, 2006: a point at
// distance r from the axis moves at most r |dtheta|), over the distance engine's pair search
// with the mandible moved rigidly (mesh_pair_distance_rigid: each jaw's index built once).
#include <cmath>

#include "core/fminmax.h"
#include "outline_internal.h"

namespace splintcore {

using namespace outline_detail;

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kMaxAngleRad = 30.0 * kPi / 180.0;
constexpr int kOpeningTries = 8;  // open angles 30 / 2^k degrees, k = 7 .. 0
constexpr double kBracketRad = 1e-10;
constexpr uint32_t kMaxEvaluations = 2000;
constexpr double kMinHingeMm = 1.0;
constexpr double kMaxOpeningMm = 10.0;
// The pool of pairs (see maybe_pool): gathered once the bracket's reach beyond the opening is
// at most this, in room for this many pairs.
constexpr double kPoolMarginMm = 0.1;
constexpr size_t kPoolPairs = 32768;
// The closing sense is told only when the centroid's velocity and the direction to the
// maxilla's make an angle at least this far (cosine) from a right angle: nearer, the sense
// would hang on the jaws' small asymmetries.
constexpr double kMinSenseCosine = 0.1;

double degrees(double rad) { return rad * (180.0 / kPi); }

// The distances between the maxilla and the mandible turned by an angle about the axis.
struct Rotor {
  const Context& ctx;
  const DistanceIndex& upper;
  const DistanceIndex& lower;
  Vec3 point, axis;
  uint32_t evaluations = 0;
  // The last closest pair: its distance at the next angle bounds the search (the same
  // answer, found sooner).
  bool warm = false;
  uint32_t pair_a = 0, pair_b = 0;
  // Every pair that can come within the opening between the angles pool_from and pool_to
  // (maybe_pool): there a scan of them gives what the full search would below the opening,
  // and a value above it otherwise.
  Span<TrianglePairIds> pool;
  size_t pooled = 0;
  double pool_from = 0, pool_to = 0;

  Rotor(const Context& c, const DistanceIndex& u, const DistanceIndex& l, const Vec3& p,
        const Vec3& a)
      : ctx(c), upper(u), lower(l), point(p), axis(a) {}

  RigidTransform at(double angle) const { return rotation_about_axis(point, axis, angle); }

  Status counted() {
    if (++evaluations <= kMaxEvaluations) return Status::ok();
    return make_error(StatusCode::kLimitExceeded, "autorotate: no convergence in ", kMaxEvaluations,
                      " distance evaluations");
  }

  void remember(const MeshPairDistance& d) {
    if (!(d.distance < HUGE_VAL)) return;
    warm = true;
    pair_a = d.triangle_a;
    pair_b = d.triangle_b;
  }

  // Do the jaws' surfaces meet at `angle`? (Stops at the first meeting pair: fast where they
  // interpenetrate.)
  Status meets(double angle, bool* meet, MeshPairDistance* d) {
    SPLINTCORE_RETURN_IF_ERROR(counted());
    SPLINTCORE_RETURN_IF_ERROR(mesh_pair_meet_rigid(ctx, upper, lower, at(angle), meet, d));
    if (*meet) remember(*d);
    return Status::ok();
  }

  // The smallest distance at `angle`, with its closest pair.
  Status distance(double angle, MeshPairDistance* d) {
    SPLINTCORE_RETURN_IF_ERROR(counted());
    const RigidTransform move = at(angle);
    if (pooled > 0 && angle >= pool_from && angle <= pool_to) {
      SPLINTCORE_RETURN_IF_ERROR(candidate_pair_distance_rigid(
          upper, lower, Span<const TrianglePairIds>(pool.data(), pooled), move, d));
      remember(*d);
      return Status::ok();
    }
    double bound = HUGE_VAL;
    if (warm) {
      const Triangle& ta = upper.mesh->triangles[pair_a];
      const Triangle& tb = lower.mesh->triangles[pair_b];
      const Vec3* va = upper.mesh->vertices.data();
      const Vec3* vb = lower.mesh->vertices.data();
      bound = triangle_pair_distance(va[ta.v[0]], va[ta.v[1]], va[ta.v[2]],
                                     move.apply_point(vb[tb.v[0]]), move.apply_point(vb[tb.v[1]]),
                                     move.apply_point(vb[tb.v[2]]), nullptr, nullptr);
      bound = bound * (1 + 1e-9) + 1e-9;  // over any rounding: the pair itself is found
    }
    SPLINTCORE_RETURN_IF_ERROR(mesh_pair_distance_rigid(ctx, upper, lower, move, bound, d));
    if (!(d->distance <= bound) && bound < HUGE_VAL) {
      SPLINTCORE_RETURN_IF_ERROR(mesh_pair_distance_rigid(ctx, upper, lower, move, HUGE_VAL, d));
    }
    remember(*d);
    return Status::ok();
  }

  // The distance's rate per radian of angle at the closest pair (exact while the pair's
  // features stay); 0 when unknown (the jaws meet).
  double rate(const MeshPairDistance& d) const {
    if (!(d.distance > 0) || !(d.distance < HUGE_VAL)) return 0;
    const Vec3 velocity = cross(axis, d.point_b - point);
    return dot(d.point_b - d.point_a, velocity) / d.distance;
  }
};

// Where a search along the closing sense stands: the angle is start + sign psi. Everything in
// [0, lo] is certified more than X apart (f = distance - X > 0); f(hi) <= 0 (hi: +inf until
// one is found), so the first crossing lies in (lo, hi].
struct Closing {
  double start = 0;
  int sign = 1;
  double lever = 0;  // R, mm
  double x = 0;      // the opening asked
  double lo = 0, flo = 0, hi = HUGE_VAL, fhi = 0;
  MeshPairDistance at_lo, at_hi;
  double lean = 1e-3;            // how far past Newton's estimate a trial aims (relative)
  double pool_tried = HUGE_VAL;  // the reach of the last pool that did not fit

  double angle(double psi) const { return start + sign * psi; }
  // The end of lo's certified zone: f > 0 on [lo, safe) (the Lipschitz bound R).
  double safe() const { return lo + flo / lever; }
};

// The next trial past lo, aimed just beyond the crossing (Newton's step by the closest pair's
// rate, else the secant through lo and hi): a new hi when it lands past, or a new lo when its
// own certified zone (backwards) meets lo's. Returns false when there is no useful trial.
bool trial_point(const Closing& c, const Rotor& rot, double limit, double* p) {
  const double slope = c.sign * rot.rate(c.at_lo);  // per unit psi
  double next = HUGE_VAL;
  if (slope < 0) next = c.lo - c.flo / slope;
  if (c.hi < HUGE_VAL && !(next < c.hi)) next = c.lo + c.flo * (c.hi - c.lo) / (c.flo - c.fhi);
  if (!(next < HUGE_VAL)) return false;
  next += c.lean * (next - c.lo) + 0.25 * kBracketRad;
  if (c.hi < HUGE_VAL && next >= c.hi) next = c.lo + 0.5 * (c.hi - c.lo);
  next = min_of(next, limit);
  *p = next;
  return next > c.safe();
}

// Once the crossing is bracketed in [lo, hi] with d(lo) + R (hi - lo) within kPoolMarginMm of
// the opening: every pair whose distance at lo is at most d(lo) + R (hi - lo) (a turn by at
// most hi - lo changes a pair's distance by at most R (hi - lo)). Any pair that comes within
// the opening inside the bracket is one of them, and so is the closest pair wherever the
// distance is at most d(lo): the pool's least distance has the full search's sign against the
// opening and its Lipschitz bound, and its bits at the answer. The rest of the search scans it.
Status maybe_pool(Rotor& rot, Closing& c) {
  if (rot.pooled > 0 || !(c.hi < HUGE_VAL)) return Status::ok();
  const double turn = c.lever * (c.hi - c.lo);
  const double margin = turn + c.flo;
  if (!(margin <= kPoolMarginMm) || !(margin <= 0.25 * c.pool_tried)) return Status::ok();
  c.pool_tried = margin;
  const double reach = c.at_lo.distance + turn * (1 + 1e-9) + 1e-9;  // over the rounding
  size_t count = 0;
  MeshPairDistance d;
  SPLINTCORE_RETURN_IF_ERROR(rot.counted());
  SPLINTCORE_RETURN_IF_ERROR(mesh_pair_distance_collect_rigid(
      rot.ctx, rot.upper, rot.lower, rot.at(c.angle(c.lo)), reach, rot.pool, &count, &d));
  if (count == 0 || count > rot.pool.size()) return Status::ok();
  rot.pooled = count;
  const double a = c.angle(c.lo), b = c.angle(c.hi);
  rot.pool_from = a < b ? a : b;
  rot.pool_to = a < b ? b : a;
  return Status::ok();
}

Status no_contact(const Closing& c, double limit) {
  return make_error(StatusCode::kInvalidArgument, "autorotate: closing the mandible from ",
                    degrees(c.start), " to ", degrees(c.angle(limit)),
                    " degrees about the hinge axis leaves the jaws ", c.at_lo.distance,
                    " mm apart, more than the opening asked (", c.x,
                    " mm): check the hinge axis and the jaws' relation (the limit is 30 degrees)");
}

// Closes from c.start (f > 0 there, c.at_lo its pair) to the first crossing: conservative
// steps (certified) from lo, trials past the crossing shrinking hi, until hi - lo is at most
// kBracketRad. Leaves the answer in c.lo.
Status close_to_opening(Rotor& rot, Closing& c) {
  const double limit = kMaxAngleRad - c.sign * c.start;  // psi where |angle| reaches 30 degrees
  MeshPairDistance d;
  while (!(c.hi - c.lo <= kBracketRad)) {
    if (!(c.hi < HUGE_VAL) && c.lo >= limit) return no_contact(c, limit);
    const double step = min_of(c.safe(), limit);
    if (step >= c.hi) {  // certified up to hi, where f <= 0 (rounding): the crossing is hi
      c.lo = c.hi;
      c.at_lo = c.at_hi;
      break;
    }
    SPLINTCORE_RETURN_IF_ERROR(rot.distance(c.angle(step), &d));
    if (d.distance - c.x <= 0) {  // f > 0 before step: the first crossing is step itself
      c.lo = c.hi = step;
      c.at_lo = c.at_hi = d;
      break;
    }
    c.lo = step;
    c.flo = d.distance - c.x;
    c.at_lo = d;
    double p = 0;
    if (c.hi - c.lo <= kBracketRad || !trial_point(c, rot, limit, &p)) continue;
    SPLINTCORE_RETURN_IF_ERROR(rot.distance(c.angle(p), &d));
    const double f = d.distance - c.x;
    if (f <= 0) {
      c.hi = p;
      c.fhi = f;
      c.at_hi = d;
    } else if (p - f / c.lever <= c.safe()) {  // the two certified zones meet
      c.lo = p;
      c.flo = f;
      c.at_lo = d;
    } else {
      c.lean = min_of(2 * c.lean, 1.0);  // Newton fell short: aim further
    }
    SPLINTCORE_RETURN_IF_ERROR(maybe_pool(rot, c));
  }
  return Status::ok();
}

// Jaws X apart or nearer at angle 0: the first open angle 30 / 2^k degrees (k = 7 .. 0) at
// which they are more than X apart (a bracket only: the answer is the closing from there).
Status find_open_angle(Rotor& rot, int sign, double x, double* start, MeshPairDistance* d) {
  bool meet = false;
  for (int k = kOpeningTries - 1; k >= 0; --k) {
    const double angle = -sign * std::ldexp(kMaxAngleRad, -k);
    SPLINTCORE_RETURN_IF_ERROR(rot.meets(angle, &meet, d));
    if (meet) continue;
    SPLINTCORE_RETURN_IF_ERROR(rot.distance(angle, d));
    if (d->distance > x) {
      *start = angle;
      return Status::ok();
    }
  }
  if (meet) {
    return make_error(StatusCode::kInvalidArgument,
                      "autorotate: the jaws still meet with the mandible opened 30 degrees about "
                      "the hinge axis (maxilla triangle ",
                      d->triangle_a, ", mandible triangle ", d->triangle_b,
                      "): they collide whichever way; check the hinge axis and the jaws");
  }
  return make_error(StatusCode::kInvalidArgument,
                    "autorotate: with the mandible opened 30 degrees about the hinge axis the "
                    "jaws are ",
                    d->distance, " mm apart, not more than the opening asked (", x,
                    " mm); check the hinge axis and the jaws");
}

Status check_hinge(const AutorotateOptions& o, Vec3* axis) {
  for (int i = 0; i < 2; ++i) {
    if (!is_finite(o.hinge[i])) {
      return make_error(StatusCode::kInvalidArgument, "autorotate: hinge point ", i + 1,
                        " is not finite");
    }
  }
  const double span = length(o.hinge[1] - o.hinge[0]);
  if (!(span >= kMinHingeMm)) {
    return make_error(StatusCode::kInvalidArgument, "autorotate: the hinge points are ", span,
                      " mm apart; they must be at least ", kMinHingeMm,
                      " mm apart (the two condyles)");
  }
  if (!(o.opening_mm >= 0 && o.opening_mm <= kMaxOpeningMm)) {
    return make_error(StatusCode::kInvalidArgument, "autorotate: the opening must be in [0, ",
                      kMaxOpeningMm, "] mm, not ", o.opening_mm);
  }
  *axis = (o.hinge[1] - o.hinge[0]) * (1.0 / span);
  return Status::ok();
}

Vec3 centroid(const Mesh& m) {
  Vec3 sum;
  for (const Vec3& v : m.vertices) sum = sum + v;
  return sum * (1.0 / static_cast<double>(m.vertices.size()));
}

// The closing sense (+1: a positive angle moves the mandible's centroid towards the
// maxilla's) and R, the largest distance of a mandible vertex from the axis.
Status sense_and_lever(const Mesh& maxilla, const Mesh& mandible, const Vec3& p, const Vec3& u,
                       int* sign, double* lever) {
  const Vec3 cx = centroid(maxilla), cm = centroid(mandible);
  const Vec3 velocity = cross(u, cm - p), towards = cx - cm;
  const double along = dot(velocity, towards);
  if (!(std::fabs(along) > kMinSenseCosine * length(velocity) * length(towards))) {
    return make_error(StatusCode::kInvalidArgument,
                      "autorotate: turning the mandible about the hinge axis moves its centroid "
                      "across the direction to the maxilla's (the cosine between them is ",
                      along / (length(velocity) * length(towards)),
                      ", under 0.1 in magnitude), so the closing sense cannot be told; check the "
                      "hinge points (the "
                      "condyles, behind and above the teeth)");
  }
  *sign = along > 0 ? 1 : -1;
  double r2 = 0;
  for (const Vec3& v : mandible.vertices) {
    const Vec3 w = v - p;
    const Vec3 across = w - u * dot(w, u);
    const double a2 = dot(across, across);
    r2 = a2 > r2 ? a2 : r2;
  }
  *lever = std::sqrt(r2);
  if (!(*lever > 0)) {
    return Status::error(StatusCode::kInvalidArgument,
                         "autorotate: the mandible lies on the hinge axis");
  }
  return Status::ok();
}

}  // namespace

// pairs_only indexes without the triangles' boxes: the same answers (bits), 24 bytes a
// triangle less, and here fewer instructions too (the real dentition's plan: 1.10 G against
// 1.38 G with them, under callgrind): the closing's pair searches reach few far triangles.
DistanceIndexOptions autorotate_index_options() {
  DistanceIndexOptions io = band_index_options();
  io.without_triangle_boxes = true;
  return io;
}

uint64_t autorotate_mandible_bound(const Mesh& maxilla, const Mesh& mandible) {
  const DistanceIndexOptions io = autorotate_index_options();
  return distance_index_bound(maxilla.vertices.size(), maxilla.triangles.size(), io) +
         distance_index_bound(mandible.vertices.size(), mandible.triangles.size(), io) +
         autorotate_mandible_indexed_bound();
}

uint64_t autorotate_mandible_indexed_bound() {
  return kPairStackBound + arena_array_bound<TrianglePairIds>(kPoolPairs);
}

namespace {

// The search itself, over the jaws' indexes (checked: not empty, valid), from the closing
// sense and the lever c holds.
Status rotate(const Context& ctx, const DistanceIndex& upper, const DistanceIndex& lower,
              const AutorotateOptions& options, const Vec3& axis, Closing& c,
              AutorotateReport* out) {
  ArenaScope scope(*ctx.arena);  // the pool goes when done
  Rotor rot(ctx, upper, lower, options.hinge[0], axis);
  TrianglePairIds* pool = ctx.arena->allocate_array<TrianglePairIds>(kPoolPairs);
  if (pool == nullptr) return ctx.arena->exhausted_status();
  rot.pool = Span<TrianglePairIds>(pool, kPoolPairs);
  bool meet = false;
  MeshPairDistance d0;
  SPLINTCORE_RETURN_IF_ERROR(rot.meets(0, &meet, &d0));
  if (!meet) SPLINTCORE_RETURN_IF_ERROR(rot.distance(0, &d0));
  out->met_as_given = meet;
  out->gap_as_given = meet ? 0.0 : d0.distance;
  c.at_lo = d0;
  if (meet || d0.distance <= c.x) {
    SPLINTCORE_RETURN_IF_ERROR(find_open_angle(rot, c.sign, c.x, &c.start, &c.at_lo));
  }
  c.flo = c.at_lo.distance - c.x;
  SPLINTCORE_RETURN_IF_ERROR(close_to_opening(rot, c));
  out->angle_rad = c.angle(c.lo);
  out->transform = rot.at(out->angle_rad);
  out->closing_sign = c.sign;
  out->start_angle_rad = c.start;
  out->opening = c.at_lo.distance;
  out->bracket_rad = c.hi - c.lo;
  out->lever_mm = c.lever;
  out->steps = rot.evaluations;
  out->contact_maxilla = c.at_lo.point_a;
  out->contact_mandible = c.at_lo.point_b;
  out->triangle_maxilla = c.at_lo.triangle_a;
  out->triangle_mandible = c.at_lo.triangle_b;
  return Status::ok();
}

// The hinge's axis and the closing (its sense and lever) for the jaws' meshes.
Status start_closing(const Mesh& maxilla, const Mesh& mandible, const AutorotateOptions& options,
                     Vec3* axis, Closing* c) {
  SPLINTCORE_RETURN_IF_ERROR(check_hinge(options, axis));
  c->x = options.opening_mm;
  return sense_and_lever(maxilla, mandible, options.hinge[0], *axis, &c->sign, &c->lever);
}

}  // namespace

Status autorotate_mandible(const Context& ctx, const Mesh& maxilla, const Mesh& mandible,
                           const AutorotateOptions& options, AutorotateReport* out) {
  *out = AutorotateReport{};
  double edge_maxilla = 0, edge_mandible = 0;
  SPLINTCORE_RETURN_IF_ERROR(
      check_jaws(ctx, maxilla, mandible, "autorotate", &edge_maxilla, &edge_mandible));
  Vec3 axis;
  Closing c;
  SPLINTCORE_RETURN_IF_ERROR(start_closing(maxilla, mandible, options, &axis, &c));
  const DistanceIndexOptions io = autorotate_index_options();
  ArenaScope scope(*ctx.arena);  // the indexes go when done
  DistanceIndex upper, lower;
  SPLINTCORE_RETURN_IF_ERROR(build_distance_index(ctx, maxilla, io, &upper));
  SPLINTCORE_RETURN_IF_ERROR(build_distance_index(ctx, mandible, io, &lower));
  return rotate(ctx, upper, lower, options, axis, c, out);
}

Status autorotate_mandible_indexed(const Context& ctx, const DistanceIndex& maxilla,
                                   const DistanceIndex& mandible, const AutorotateOptions& options,
                                   AutorotateReport* out) {
  *out = AutorotateReport{};
  const DistanceIndex* jaws[2] = {&maxilla, &mandible};
  const char* names[2] = {"maxilla", "mandible"};
  for (int j = 0; j < 2; ++j) {
    const Mesh* m = jaws[j]->mesh;
    if (m == nullptr || m->triangles.empty() || m->vertices.empty()) {
      return make_error(StatusCode::kInvalidMesh, "autorotate: the ", names[j], " is empty");
    }
  }
  Vec3 axis;
  Closing c;
  SPLINTCORE_RETURN_IF_ERROR(start_closing(*maxilla.mesh, *mandible.mesh, options, &axis, &c));
  return rotate(ctx, maxilla, mandible, options, axis, c, out);
}

}  // namespace splintcore
