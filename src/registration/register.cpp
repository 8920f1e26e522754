// register_rigid (registration.h): an intraoral scan onto a CT jaw. The initial alignment is
// the scan as given or its principal axes onto the CT's (the covariance of area-weighted
// triangle centroids), or the landmarks' closed-form fit (Horn, "Closed-form solution of
// absolute orientation using unit quaternions", JOSA A 4(4), 1987). Then the trimmed ICP:
// point-to-plane (Chen and Medioni, "Object modelling by registration of multiple range
// images", Image and Vision Computing 10(3), 1992; linearised as in Low, "Linear least-squares
// optimization for point-to-plane ICP surface registration", UNC TR04-004, 2004), keeping the
// best fraction of the correspondences by distance (Chetverikov et al., "The trimmed iterative
// closest point algorithm", ICPR 2002).
#include <cmath>

#include "distance/query_internal.h"
#include "linalg.h"
#include "splintcore/distance.h"
#include "splintcore/registration.h"

namespace splintcore {

using namespace registration_detail;

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr uint32_t kMinSamples = 16;
constexpr uint32_t kChunk = 64;  // samples per executor task
// The coarse phase (each automatic start, or the landmarks' fit): at most this many samples
// (spread over the scan: every m-th), at most this many iterations, keeping the fraction
// halfway between the overlap asked and all; the fine phase then starts from its best pose.
constexpr uint32_t kCoarseSamples = 256;
constexpr uint32_t kCoarseIterations = 30;
// The automatic starts: the scan as given, turned about the CT's occlusal axis (its least
// principal axis, through its centroid) by each of kTurnDegrees, then the principal axes with
// the four sign combinations. The turns catch what ICP alone does not: an arch whose teeth
// land on their neighbours (a local minimum about 7 degrees round).
constexpr double kTurnDegrees[] = {-10.0, -5.0, 5.0, 10.0};
constexpr uint32_t kTurns = sizeof(kTurnDegrees) / sizeof(kTurnDegrees[0]);
constexpr uint32_t kAutomaticStarts = 1 + kTurns + 4;
constexpr double kStopMm = 1e-7;  // update below this (and kStopRad): converged
constexpr double kStopRad = 1e-7;
// The automatic alignment stops at a start whose fractional RMS is at most this share of
// max_rms_mm.
constexpr double kGoodEnough = 0.1;
constexpr double kMinPivotRatio = 1e-12;  // Cholesky: below this the motion is not fixed
constexpr double kCollinearRatio = 1e-6;  // landmarks: second variance over the first

// A rigid pose kept as a unit quaternion (always a rotation, to rounding) and a translation.
struct Pose {
  Quaternion q;
  Vec3 t{};
};

RigidTransform pose_transform(const Pose& pose) {
  RigidTransform x;
  quaternion_matrix(pose.q, x.r);
  x.t = pose.t;
  return x;
}

Pose transform_pose(const RigidTransform& x) {
  Pose p;
  p.q = matrix_quaternion(x.r);
  p.t = x.t;
  return p;
}

// Every k-th scan vertex, k the least giving at most max_samples.
uint64_t sample_stride(uint64_t vertices, uint32_t max_samples) {
  const uint64_t m = max_samples < kMinSamples ? kMinSamples : max_samples;
  return vertices <= m ? 1 : (vertices + m - 1) / m;
}
uint64_t sample_count(uint64_t vertices, uint32_t max_samples) {
  const uint64_t k = sample_stride(vertices, max_samples);
  return (vertices + k - 1) / k;
}

// One sample's correspondence: p moved, its closest point q on the CT, the unit normal n there.
struct Correspondence {
  Vec3 p{}, q{}, n{};
  double d = 0;
  uint32_t triangle = kNoNeighbor;  // also the next search's seed
  uint32_t valid = 0;
};

Vec3 unit_normal(const Mesh& m, uint32_t triangle, bool* ok) {
  const Triangle& t = m.triangles[triangle];
  const Vec3& a = m.vertices[t.v[0]];
  const Vec3 n = cross(m.vertices[t.v[1]] - a, m.vertices[t.v[2]] - a);
  const double len = length(n);
  *ok = len > 0;
  return *ok ? n * (1.0 / len) : Vec3{};
}

// The ICP's state: the samples and the arrays it reuses every iteration.
struct Icp {
  const Context& ctx;
  const Mesh& ct;
  const DistanceIndex& index;
  const RegisterOptions& o;
  Span<Vec3> points;  // scan samples
  Span<Correspondence> corr;
  Span<KeyIndex> keys, scratch;
  double overlap = 1;       // the fraction kept (at least, when fractional)
  bool fractional = false;  // choose the fraction by the fractional RMS (select())
  uint32_t kept = 0;
  double rms = 0;
  // The scan's net normal and the direction to the other jaw (Occlusal), when both count.
  Vec3 net{}, toward{};
  bool occlusal = false;

  void correspond(const Pose& pose);
  void select();
  Status step(Pose* pose, bool* small);
  Status run(Pose* pose, uint32_t iterations, uint32_t* done, bool* converged);
};

void Icp::correspond(const Pose& pose) {
  const RigidTransform x = pose_transform(pose);
  const uint32_t n = static_cast<uint32_t>(points.size());
  auto task = [&](uint32_t chunk) {
    const uint32_t end = n - chunk * kChunk < kChunk ? n : chunk * kChunk + kChunk;
    for (uint32_t i = chunk * kChunk; i < end; ++i) {
      Correspondence& c = corr[i];
      c.p = x.apply_point(points[i]);
      ClosestPoint cp;
      c.valid = 0;
      if (!detail::closest_within(index, c.p, HUGE_VAL, &cp, c.triangle)) continue;
      c.q = cp.point;
      c.d = cp.distance;
      c.triangle = cp.triangle;
      // The distance's gradient where it has one: off a face its normal, off an edge or a
      // vertex the direction to the point (continuous as the closest feature changes, so
      // the iteration settles instead of hopping between a face's and its neighbour's plane).
      bool ok = false;
      if (cp.feature != Feature::kFace && c.d > 0) {
        c.n = (c.p - c.q) * (1.0 / c.d);
        ok = true;
      } else {
        c.n = unit_normal(ct, cp.triangle, &ok);
        if (!ok && c.d > 0) {  // a flat triangle: the direction to the point instead
          c.n = (c.p - c.q) * (1.0 / c.d);
          ok = true;
        }
      }
      c.valid = ok ? 1 : 0;
    }
  };
  parallel_for_each(ctx.executor, (n + kChunk - 1) / kChunk, task);
}

// Sorts the samples by distance (ties: the lower index; invalid ones last) and sets `kept`:
// the K >= overlap * n (of n samples) that minimises RMS(K) / (K / n)^3, the fractional RMS of
// Phillips, Liu and Tomasi ("Outlier robust ICP for minimizing fractional RMSD", 3DIM 2007):
// as many samples as fit about as well, never fewer than asked.
void Icp::select() {
  const size_t n = points.size();
  size_t valid = 0;
  for (size_t i = 0; i < n; ++i) {
    uint64_t bits = ~uint64_t{0};
    if (corr[i].valid != 0) {
      std::memcpy(&bits, &corr[i].d, sizeof(bits));  // d >= 0: the bits order as the values
      ++valid;
    }
    keys[i] = KeyIndex{bits, static_cast<uint32_t>(i), 0};
  }
  radix_sort(keys, scratch);
  const double want = std::ceil(overlap * static_cast<double>(n));
  const size_t least = want < static_cast<double>(valid) ? static_cast<size_t>(want) : valid;
  double sum2 = 0, best = HUGE_VAL;
  kept = static_cast<uint32_t>(least);
  for (size_t k = 0; k < (fractional ? valid : 0); ++k) {
    const double d = corr[keys[k].index].d;
    sum2 += d * d;
    if (k + 1 < least) continue;
    const double f = static_cast<double>(n) / static_cast<double>(k + 1);  // 1 / fraction
    const double f3 = f * f * f;
    const double objective = sum2 / static_cast<double>(k + 1) * (f3 * f3);  // squared
    if (objective <= best) {  // ties: the more samples
      best = objective;
      kept = static_cast<uint32_t>(k + 1);
    }
  }
}

// One iteration: correspondences, trimming, the linearised point-to-plane step about the kept
// samples' centroid, applied as an exact rotation. *small: the step was below the stop.
Status Icp::step(Pose* pose, bool* small) {
  correspond(*pose);
  select();
  if (kept < kMinSamples) {
    return make_error(StatusCode::kInvalidMesh, "registration: only ", kept,
                      " samples found a CT triangle to pair with (at least ", kMinSamples,
                      " needed)");
  }
  Vec3 c{};
  double sum2 = 0;
  for (uint32_t k = 0; k < kept; ++k) {
    const Correspondence& s = corr[keys[k].index];
    c = c + s.p;
    sum2 += s.d * s.d;
  }
  c = c * (1.0 / kept);
  rms = std::sqrt(sum2 / kept);
  double a[36] = {}, b[6] = {};
  for (uint32_t k = 0; k < kept; ++k) {
    const Correspondence& s = corr[keys[k].index];
    const Vec3 arm = cross(s.p - c, s.n);
    const double j[6] = {arm.x, arm.y, arm.z, s.n.x, s.n.y, s.n.z};
    const double r = dot(s.n, s.p - s.q);
    for (int u = 0; u < 6; ++u) {
      for (int v = 0; v < 6; ++v) a[u * 6 + v] += j[u] * j[v];
      b[u] -= j[u] * r;
    }
  }
  double x[6];
  if (!cholesky_solve(a, b, 6, kMinPivotRatio, x)) {
    return make_error(StatusCode::kInvalidMesh,
                      "registration: the kept scan points do not fix the motion (a flat or "
                      "symmetric surface); give landmarks or a larger overlap");
  }
  const Vec3 omega{x[0], x[1], x[2]}, tau{x[3], x[4], x[5]};
  const Quaternion qu = small_rotation(omega);
  RigidTransform u;
  quaternion_matrix(qu, u.r);
  pose->t = u.apply_vector(pose->t - c) + c + tau;
  pose->q = normalized(multiply(qu, pose->q));
  *small = length(omega) < kStopRad && length(tau) < kStopMm;
  return Status::ok();
}

Status Icp::run(Pose* pose, uint32_t iterations, uint32_t* done, bool* converged) {
  *converged = false;
  for (*done = 0; *done < iterations && !*converged;) {
    SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "register", *done, iterations));
    SPLINTCORE_RETURN_IF_ERROR(step(pose, converged));
    ++*done;
  }
  return Status::ok();
}

// The area-weighted centroid and covariance of the triangles' centroids.
bool triangle_moments(const Mesh& m, Vec3* centroid, double cov[9]) {
  double area = 0;
  Vec3 c{};
  for (const Triangle& t : m.triangles) {
    const Vec3 &a = m.vertices[t.v[0]], &b = m.vertices[t.v[1]], &d = m.vertices[t.v[2]];
    const double w = 0.5 * length(cross(b - a, d - a));
    area += w;
    c = c + (a + b + d) * (w / 3.0);
  }
  if (!(area > 0)) return false;
  c = c * (1.0 / area);
  for (int i = 0; i < 9; ++i) cov[i] = 0;
  for (const Triangle& t : m.triangles) {
    const Vec3 &a = m.vertices[t.v[0]], &b = m.vertices[t.v[1]], &d = m.vertices[t.v[2]];
    const double w = 0.5 * length(cross(b - a, d - a));
    const Vec3 g = (a + b + d) * (1.0 / 3.0) - c;
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) cov[i * 3 + j] += w * g[i] * g[j];
    }
  }
  for (int i = 0; i < 9; ++i) cov[i] /= area;
  *centroid = c;
  return true;
}

// The principal axes as the columns of a rotation (the third is the first two's cross product).
void principal_frame(const double cov[9], double e[3][3]) {
  double values[3], vectors[9];
  symmetric_eigen(cov, 3, values, vectors);
  const Vec3 e0{vectors[0], vectors[3], vectors[6]}, e1{vectors[1], vectors[4], vectors[7]};
  const Vec3 e2 = cross(e0, e1);
  for (int i = 0; i < 3; ++i) {
    e[i][0] = e0[i];
    e[i][1] = e1[i];
    e[i][2] = e2[i];
  }
}

// Start k of the automatic alignment (0: as given; 1..kTurns: turned about the CT's occlusal
// axis; then the scan's principal axes onto the CT's, the first two axes' signs (+,+), (+,-),
// (-,+), (-,-), the third their product).
Pose automatic_start(uint32_t k, const Vec3& cs, const double es[3][3], const Vec3& cc,
                     const double ec[3][3]) {
  if (k == 0) return Pose{};
  if (k <= kTurns) {
    const Vec3 axis{ec[0][2], ec[1][2], ec[2][2]};
    return transform_pose(rotation_about_axis(cc, axis, kTurnDegrees[k - 1] * (kPi / 180.0)));
  }
  k -= kTurns;
  const double s0 = ((k - 1) & 2) != 0 ? -1.0 : 1.0, s1 = ((k - 1) & 1) != 0 ? -1.0 : 1.0;
  const double sign[3] = {s0, s1, s0 * s1};
  RigidTransform x;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      double sum = 0;
      for (int l = 0; l < 3; ++l) sum += ec[i][l] * sign[l] * es[j][l];
      x.r[i][j] = sum;
    }
  }
  x.t = cc - x.apply_vector(cs);
  return transform_pose(x);
}

// The cosine between the scan's net normal turned by the pose and the direction to the other
// jaw.
double occlusal_cos(const Icp& icp, const Pose& pose) {
  const Vec3 n = pose_transform(pose).apply_vector(icp.net);
  return dot(n, icp.toward) / (length(n) * length(icp.toward));
}

// The net normal (the sum of the triangles' area vectors, twice over) and the total of their
// lengths.
Vec3 net_normal(const Mesh& m, double* total) {
  Vec3 net{};
  *total = 0;
  for (const Triangle& t : m.triangles) {
    const Vec3& a = m.vertices[t.v[0]];
    const Vec3 n = cross(m.vertices[t.v[1]] - a, m.vertices[t.v[2]] - a);
    net = net + n;
    *total += length(n);
  }
  return net;
}

// The automatic alignment: each start after the coarse phase; the lowest fractional RMS wins
// (ties: the earlier start). A start whose iterations fail on the geometry is passed over.
Status choose_start(Icp& icp, const Mesh& scan, const Mesh& ct, Pose* best, int32_t* which) {
  Vec3 cs, cc;
  double covs[9], covc[9], es[3][3], ec[3][3];
  if (!triangle_moments(scan, &cs, covs) || !triangle_moments(ct, &cc, covc)) {
    return make_error(StatusCode::kInvalidMesh,
                      "registration: a mesh has no area (the automatic alignment needs the "
                      "scan's and the CT's triangles); give landmarks");
  }
  principal_frame(covs, es);
  principal_frame(covc, ec);
  double best_rms = HUGE_VAL;
  Status last = Status::ok();
  bool faced_away = false;
  for (uint32_t k = 0; k < kAutomaticStarts; ++k) {
    Pose pose = automatic_start(k, cs, es, cc, ec);
    uint32_t done = 0;
    bool converged = false;
    const Status s = icp.run(&pose, kCoarseIterations, &done, &converged);
    if (!s.is_ok()) {
      if (s.code() != StatusCode::kInvalidMesh) return s;
      last = s;
      continue;
    }
    // The fractional RMS (select()'s objective): a fit of fewer samples must be closer.
    if (icp.occlusal && occlusal_cos(icp, pose) <= 0) {  // upside down on the jaw
      faced_away = true;
      continue;
    }
    const double f = static_cast<double>(icp.points.size()) / static_cast<double>(icp.kept);
    const double score = icp.rms * (f * f * f);
    if (score < best_rms) {
      best_rms = score;
      *best = pose;
      *which = static_cast<int32_t>(k);
    }
    // A fit this close leaves nothing for another start to win: the rest are not tried.
    if (best_rms <= kGoodEnough * icp.o.max_rms_mm) break;
  }
  if (best_rms == HUGE_VAL && faced_away) {
    return Status::error(
        StatusCode::kInvalidMesh,
        "registration: the scan faces away from the other jaw at every start of the automatic "
        "alignment (its occlusal side ends pointing away from it): the scan is wound inside "
        "out (reverse its triangles) or fits the jaw only upside down (check it is this jaw's "
        "scan, or give landmarks)");
  }
  return best_rms < HUGE_VAL ? Status::ok() : last;
}

Status check_inputs(const Mesh& scan, const Mesh& ct, const RegisterOptions& o) {
  if (!(o.overlap > 0 && o.overlap <= 1) || !(o.max_rms_mm > 0) || !is_finite(o.max_rms_mm) ||
      !(o.inlier_mm > 0) || !is_finite(o.inlier_mm) || !(o.landmark_tolerance_mm > 0) ||
      o.max_samples < kMinSamples || o.max_iterations < 1 ||
      !(o.min_facing >= 0 && o.min_facing <= 1) || !is_finite(o.toward_other_jaw)) {
    return make_error(StatusCode::kInvalidArgument,
                      "registration: options out of range (overlap in (0, 1], max_rms_mm, "
                      "inlier_mm and landmark_tolerance_mm > 0, max_samples >= 16, "
                      "max_iterations >= 1, min_facing in [0, 1], toward_other_jaw finite)");
  }
  if (scan.vertices.size() < kMinSamples || ct.triangles.size() == 0) {
    return make_error(StatusCode::kInvalidMesh, "registration: the scan has ", scan.vertices.size(),
                      " vertices (at least ", kMinSamples, " needed) and the CT jaw ",
                      ct.triangles.size(), " triangles");
  }
  for (size_t i = 0; i < scan.vertices.size(); ++i) {
    if (!is_finite(scan.vertices[i])) {
      return make_error(StatusCode::kInvalidMesh, "registration: scan vertex ", i, " is not finite")
          .at_index(i);
    }
  }
  const size_t nv = scan.vertices.size();
  for (size_t i = 0; i < scan.triangles.size(); ++i) {
    const Triangle& t = scan.triangles[i];
    if (t.v[0] >= nv || t.v[1] >= nv || t.v[2] >= nv) {
      return make_error(StatusCode::kInvalidMesh, "registration: scan triangle ", i,
                        " names a vertex out of range")
          .at_index(i);
    }
  }
  return Status::ok();
}

// The landmarks' RMS under x, and the pair farthest off.
double landmark_rms(Span<const LandmarkPair> pairs, const RigidTransform& x, size_t* worst,
                    double* worst_mm) {
  double sum = 0;
  *worst = 0;
  *worst_mm = -1;
  for (size_t i = 0; i < pairs.size(); ++i) {
    const double d = length(x.apply_point(pairs[i].scan) - pairs[i].ct);
    sum += d * d;
    if (d > *worst_mm) {
      *worst_mm = d;
      *worst = i;
    }
  }
  return pairs.empty() ? 0.0 : std::sqrt(sum / static_cast<double>(pairs.size()));
}

Status landmark_error(const char* when, double rms, size_t worst, double worst_mm,
                      double tolerance) {
  return make_error(StatusCode::kInvalidArgument, "registration: the landmarks ", when, " are ",
                    rms, " mm RMS apart (tolerance ", tolerance, " mm); pair ", worst, " is ",
                    worst_mm,
                    " mm off: check that each scan point is paired with the same point on "
                    "the CT")
      .at_index(worst);
}

// Landmark start: their fit, refused when they do not agree with each other.
Status landmark_start(const RegisterOptions& o, Pose* pose) {
  RigidTransform x;
  double rms = 0;
  SPLINTCORE_RETURN_IF_ERROR(fit_landmarks(o.landmarks, &x, &rms));
  size_t worst = 0;
  double worst_mm = 0;
  rms = landmark_rms(o.landmarks, x, &worst, &worst_mm);
  if (rms > o.landmark_tolerance_mm) {
    return landmark_error("fitted", rms, worst, worst_mm, o.landmark_tolerance_mm);
  }
  *pose = transform_pose(x);
  return Status::ok();
}

// The correspondences at the final pose: the reported RMS and overlap.
void final_figures(Icp& icp, const Pose& pose, RegisterResult* r) {
  icp.correspond(pose);
  icp.select();
  double sum2 = 0;
  uint32_t within = 0;
  for (uint32_t k = 0; k < icp.kept; ++k) {
    const double d = icp.corr[icp.keys[k].index].d;
    sum2 += d * d;
  }
  for (size_t i = 0; i < icp.points.size(); ++i) {
    within += icp.corr[i].valid != 0 && icp.corr[i].d <= icp.o.inlier_mm ? 1u : 0u;
  }
  r->rms_mm = icp.kept > 0 ? std::sqrt(sum2 / icp.kept) : HUGE_VAL;
  r->kept = icp.kept;
  r->overlap = static_cast<double>(within) / static_cast<double>(icp.points.size());
}

// RegisterResult::facing at the final transform: over every k-th scan triangle (k the least
// giving at most max_samples), those whose centroid lies within inlier_mm of the CT, the share
// of their area whose normal agrees with the CT's face there (a positive dot product). Sums in
// triangle order; no arena.
double facing_share(const Mesh& scan, const Mesh& ct, const DistanceIndex& index,
                    const RigidTransform& x, const RegisterOptions& o) {
  const uint64_t stride = sample_stride(scan.triangles.size(), o.max_samples);
  double agree = 0, total = 0;
  for (uint64_t i = 0; i < scan.triangles.size(); i += stride) {
    const Triangle& t = scan.triangles[static_cast<size_t>(i)];
    const Vec3 a = x.apply_point(scan.vertices[t.v[0]]), b = x.apply_point(scan.vertices[t.v[1]]),
               c = x.apply_point(scan.vertices[t.v[2]]);
    const Vec3 n = cross(b - a, c - a);  // twice the area, outward for an outward scan
    ClosestPoint cp;
    if (!detail::closest_within(index, (a + b + c) * (1.0 / 3.0), o.inlier_mm * o.inlier_mm, &cp)) {
      continue;
    }
    bool ok = false;
    const Vec3 m = unit_normal(ct, cp.triangle, &ok);
    if (!ok) continue;
    const double area = length(n);
    total += area;
    agree += dot(n, m) > 0 ? area : 0;
  }
  return total > 0 ? agree / total : 1.0;
}

// The final fit's refusals, in this order: it does not fit (RMS), it fits with its occlusal
// side away from the other jaw, it fits facing against the CT.
Status check_fit(const RegisterOptions& o, const RegisterResult& r, bool occlusal) {
  if (!(r.rms_mm <= o.max_rms_mm)) {
    return make_error(StatusCode::kLimitExceeded, "registration: the fit's RMS is ", r.rms_mm,
                      " mm over the best ", r.kept, " of ", r.samples,
                      " samples, above the limit of ", o.max_rms_mm, " mm (overlap within ",
                      o.inlier_mm, " mm: ", r.overlap,
                      "); give landmarks, or check that the scan and the CT are the same jaw");
  }
  if (occlusal && !(r.occlusal_cos > 0)) {
    return make_error(StatusCode::kInvalidMesh,
                      "registration: the scan faces away from the other jaw after the fit: its "
                      "occlusal side points away from it (the cosine between its net normal and "
                      "the direction to the other jaw is ",
                      r.occlusal_cos,
                      "); it lies upside down on the jaw or is wound inside out: turn it over "
                      "or reverse its triangles, or give landmarks");
  }
  if (r.facing < o.min_facing) {
    return make_error(
        StatusCode::kInvalidMesh, "registration: the scan faces away from the CT: only ", r.facing,
        " of its area near the CT faces the way the CT's surface does there (at "
        "least ",
        o.min_facing,
        " needed): it lies upside down on the jaw, or its triangles are wound "
        "inside out (its occlusal side pointing away from the other jaw); reverse "
        "the scan's triangles if it is inside out (or the CT jaw's, if that is), else give "
        "landmarks");
  }
  return Status::ok();
}

}  // namespace

uint64_t register_rigid_bound(uint64_t scan_vertex_count, uint64_t ct_vertex_count,
                              uint64_t ct_triangle_count, const RegisterOptions& options) {
  DistanceIndexOptions io;
  io.pairs_only = true;
  const uint64_t s = sample_count(scan_vertex_count, options.max_samples);
  const uint64_t parts[] = {distance_index_bound(ct_vertex_count, ct_triangle_count, io),
                            arena_array_bound<Vec3>(s), arena_array_bound<Correspondence>(s),
                            arena_array_bound<KeyIndex>(s), arena_array_bound<KeyIndex>(s)};
  uint64_t total = 0;
  for (uint64_t p : parts) {
    if (!checked_add(total, p, &total)) return UINT64_MAX;
  }
  return total;
}

Status register_rigid(const Context& ctx, const Mesh& scan, const Mesh& ct_jaw,
                      const RegisterOptions& options, RegisterResult* result) {
  *result = RegisterResult{};
  SPLINTCORE_RETURN_IF_ERROR(check_inputs(scan, ct_jaw, options));
  Pose pose;
  int32_t start = -1;
  if (!options.landmarks.empty()) SPLINTCORE_RETURN_IF_ERROR(landmark_start(options, &pose));
  Arena& arena = *ctx.arena;
  ArenaScope scope(arena);
  const uint64_t stride = sample_stride(scan.vertices.size(), options.max_samples);
  const size_t n = static_cast<size_t>(sample_count(scan.vertices.size(), options.max_samples));
  Vec3* points = arena.allocate_array<Vec3>(n);
  Correspondence* corr = arena.allocate_array<Correspondence>(n);
  KeyIndex* keys = arena.allocate_array<KeyIndex>(n);
  KeyIndex* scratch = arena.allocate_array<KeyIndex>(n);
  if (points == nullptr || corr == nullptr || keys == nullptr || scratch == nullptr) {
    return arena.exhausted_status();
  }
  // The coarse phase's samples first: every m-th of them, then the rest, each in order.
  const size_t m = n <= kCoarseSamples ? 1 : (n + kCoarseSamples - 1) / kCoarseSamples;
  size_t at = 0;
  for (size_t first = 0; first < m; ++first) {
    for (size_t j = first; j < n; j += m)
      points[at++] = scan.vertices[static_cast<size_t>(j * stride)];
  }
  for (size_t i = 0; i < n; ++i) corr[i] = Correspondence{};
  DistanceIndexOptions io;
  io.pairs_only = true;
  DistanceIndex index;
  SPLINTCORE_RETURN_IF_ERROR(build_distance_index(ctx, ct_jaw, io, &index));
  const size_t nc = (n + m - 1) / m;
  // The first `count` samples (the coarse phase takes every m-th: they come first).
  const auto phase = [&](size_t count, bool coarse_phase) {
    return Icp{ctx,
               ct_jaw,
               index,
               options,
               Span<Vec3>(points, count),
               Span<Correspondence>(corr, count),
               Span<KeyIndex>(keys, count),
               Span<KeyIndex>(scratch, count),
               options.overlap,
               coarse_phase};
  };
  Icp coarse = phase(nc, true);
  double area = 0;
  coarse.net = net_normal(scan, &area);
  coarse.toward = options.toward_other_jaw;
  coarse.occlusal = length(coarse.toward) > 0 && length(coarse.net) > 0.1 * area;
  uint32_t done = 0;
  bool converged = false;
  if (options.landmarks.empty()) {
    SPLINTCORE_RETURN_IF_ERROR(choose_start(coarse, scan, ct_jaw, &pose, &start));
  }
  Icp icp = phase(n, false);
  SPLINTCORE_RETURN_IF_ERROR(icp.run(&pose, options.max_iterations, &done, &converged));
  RegisterResult& r = *result;
  r.transform = pose_transform(pose);
  r.iterations = done;
  r.converged = converged;
  r.samples = static_cast<uint32_t>(n);
  r.start = start;
  final_figures(icp, pose, &r);
  if (!options.landmarks.empty()) {
    size_t worst = 0;
    double worst_mm = 0;
    r.landmark_rms_mm = landmark_rms(options.landmarks, r.transform, &worst, &worst_mm);
    if (r.landmark_rms_mm > options.landmark_tolerance_mm) {
      return landmark_error("after the fit", r.landmark_rms_mm, worst, worst_mm,
                            options.landmark_tolerance_mm);
    }
  }
  if (coarse.occlusal) r.occlusal_cos = occlusal_cos(coarse, pose);
  r.facing = facing_share(scan, ct_jaw, index, r.transform, options);
  return check_fit(options, r, coarse.occlusal);
}

Status fit_landmarks(Span<const LandmarkPair> pairs, RigidTransform* out, double* rms_mm) {
  if (pairs.size() < 3) {
    return make_error(StatusCode::kInvalidArgument, "registration: ", pairs.size(),
                      " landmark pairs given, at least 3 needed");
  }
  Vec3 cs{}, cc{};
  for (size_t i = 0; i < pairs.size(); ++i) {
    if (!is_finite(pairs[i].scan) || !is_finite(pairs[i].ct)) {
      return make_error(StatusCode::kInvalidArgument, "registration: landmark pair ", i,
                        " is not finite")
          .at_index(i);
    }
    cs = cs + pairs[i].scan;
    cc = cc + pairs[i].ct;
  }
  const double inv = 1.0 / static_cast<double>(pairs.size());
  cs = cs * inv;
  cc = cc * inv;
  double m[9] = {}, spread[9] = {};  // m: sum of (scan - cs)(ct - cc)^T
  for (const LandmarkPair& p : pairs) {
    const Vec3 a = p.scan - cs, b = p.ct - cc;
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) {
        m[i * 3 + j] += a[i] * b[j];
        spread[i * 3 + j] += a[i] * a[j];
      }
    }
  }
  double values[4], vectors[16];
  symmetric_eigen(spread, 3, values, vectors);
  if (!(values[1] > kCollinearRatio * values[0])) {
    return make_error(StatusCode::kInvalidArgument,
                      "registration: the scan landmarks are (nearly) collinear; pick at least "
                      "three points spread over the arch");
  }
  const double sxx = m[0], sxy = m[1], sxz = m[2], syx = m[3], syy = m[4], syz = m[5], szx = m[6],
               szy = m[7], szz = m[8];
  const double nmat[16] = {sxx + syy + szz, syz - szy,       szx - sxz,        sxy - syx,
                           syz - szy,       sxx - syy - szz, sxy + syx,        szx + sxz,
                           szx - sxz,       sxy + syx,       -sxx + syy - szz, syz + szy,
                           sxy - syx,       szx + sxz,       syz + szy,        -sxx - syy + szz};
  symmetric_eigen(nmat, 4, values, vectors);
  const Quaternion q = normalized(Quaternion{vectors[0], vectors[4], vectors[8], vectors[12]});
  quaternion_matrix(q, out->r);
  out->t = cc - out->apply_vector(cs);
  size_t worst = 0;
  double worst_mm = 0;
  *rms_mm = landmark_rms(pairs, *out, &worst, &worst_mm);
  return Status::ok();
}

}  // namespace splintcore
