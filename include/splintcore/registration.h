// splintcore registration: an intraoral scan (an open surface: crowns and gum) placed rigidly
// onto a jaw reconstructed from CT (issue 30, scan-CT fusion). The method is in
// docs/architecture.md ("Scan-to-CT registration"); in short: an initial alignment (principal
// axes, or landmark pairs by Horn's closed form), then a trimmed point-to-plane ICP whose
// correspondences are the distance module's closest points on the CT mesh.
#ifndef SPLINTCORE_REGISTRATION_H
#define SPLINTCORE_REGISTRATION_H

#include "splintcore/core.h"
#include "splintcore/geometry.h"
#include "splintcore/mesh.h"

namespace splintcore {

// One landmark picked on both surfaces: the same anatomical point on the scan and on the CT.
struct LandmarkPair {
  Vec3 scan{};
  Vec3 ct{};
};

struct RegisterOptions {
  // Three or more pairs that are not (nearly) collinear: the initial alignment is their
  // least-squares rigid fit. Empty: the automatic alignment.
  Span<const LandmarkPair> landmarks;
  // The fraction of samples the fit keeps each iteration, those nearest the CT (ties: the
  // lower sample index), in (0, 1]. Intraoral scans are about 60% gum, which CT at the bone
  // threshold does not show. (The automatic alignment's coarse phase keeps at least this
  // fraction, more where they fit about as well: docs/architecture.md.)
  double overlap = 0.6;
  // A fit whose RMS (over the kept samples, mm) is above this is an error, not a result.
  double max_rms_mm = 0.3;
  // The reported overlap fraction: samples at most this far from the CT after the fit (mm).
  double inlier_mm = 0.5;
  // Landmarks: their fit (and the final transform) may leave them at most this RMS apart
  // (mm); more means a wrong pairing, which is an error.
  double landmark_tolerance_mm = 2.0;
  // Samples: every k-th scan vertex, k the least that gives at most this many (>= 16).
  uint32_t max_samples = 3000;
  // ICP iterations at most (after the automatic alignment's trials), >= 1.
  uint32_t max_iterations = 100;
  // The fit is refused when less than this share of the scan's area near the CT faces the
  // way the CT does there (RegisterResult::facing), in [0, 1]; 0: never. A scan laid on the
  // CT the right way up faces as the CT does (near 1): below a half it lies upside down on
  // the jaw or is wound inside out. The CT must be outward (a closed reconstruction is).
  double min_facing = 0.5;
  // The direction from the CT jaw towards the other jaw, in the CT's frame (any length; zero:
  // not known). A scan of crowns and gum faces the other jaw: its net normal (the sum of its
  // triangles' area vectors, which an open cap turns out of its occlusal side) must point that
  // way. With it, the automatic alignment passes over starts that end with the scan's
  // occlusal side pointing away (upside down on the jaw: on a jaw whose far side looks like
  // its near side, a tube, such a fit can be as close as the right one), and a final fit that
  // does is an error. Ignored for a scan whose net normal is under a tenth of its area (a
  // closed or flat-folded surface has no occlusal side to go by).
  Vec3 toward_other_jaw{};
};

struct RegisterResult {
  RigidTransform transform;  // scan -> CT: ct_point = transform.apply_point(scan_point)
  double rms_mm = 0;         // RMS distance of the kept samples to the CT
  double overlap = 0;        // fraction of all samples within inlier_mm of the CT
  uint32_t iterations = 0;   // ICP iterations of the final run (not counting the trials)
  bool converged = false;    // the last update was below 1e-7 mm and 1e-7 rad
  uint32_t samples = 0;      // scan vertices sampled
  uint32_t kept = 0;         // samples kept each iteration (overlap * samples)
  // The automatic alignment: which start won (0: the scan as given; 1..4: turned by -10, -5,
  // 5, 10 degrees about the CT's least principal axis through its centroid; 5..8: the
  // principal axes with the sign combinations (+,+), (+,-), (-,+), (-,-) of the first two).
  // -1 with landmarks.
  int32_t start = -1;
  double landmark_rms_mm = 0;  // with landmarks: their RMS under the final transform
  // Over every k-th scan triangle (k the least giving at most max_samples) whose centroid
  // lies within inlier_mm of the CT after the fit: the share of their area whose normal
  // agrees with the CT's face there (1 when none is that near).
  double facing = 1;
  // With toward_other_jaw: the cosine of the angle between the registered scan's net normal
  // and that direction (0 when not known or not used).
  double occlusal_cos = 0;
};

// Arena bytes register_rigid() takes at most (all returned before it does): the CT's distance
// index (pairs_only) and 136 bytes a sample (about min(scan vertices, max_samples) of them).
uint64_t register_rigid_bound(uint64_t scan_vertex_count, uint64_t ct_vertex_count,
                              uint64_t ct_triangle_count, const RegisterOptions& options);

// Registers `scan` (its vertices are the samples; triangles give the automatic alignment's
// area-weighted moments) to `ct_jaw` (any triangle mesh, open or closed). Deterministic: the
// same bits at any thread count (closest points per sample on the executor, every sum in
// sample order); only + - * / and sqrt.
// Errors: kInvalidArgument (an option out of range, fewer than 3 landmarks, collinear
// landmarks, landmarks whose fit leaves them more than landmark_tolerance_mm apart: the
// message names the pair farthest off), kInvalidMesh (an empty mesh, a non-finite vertex,
// fewer than 16 samples, surfaces that do not fix the motion: flat or symmetric),
// kLimitExceeded (the fit's RMS is above max_rms_mm; *result then holds that fit), kInvalidMesh
// "the scan faces away from the CT" (facing below min_facing: upside down or inside out; the
// message says which to do; *result holds the fit), kInvalidMesh "the scan faces away from the
// other jaw" (with toward_other_jaw: every automatic start, or the final fit, leaves its
// occlusal side pointing away),
// kArenaExhausted, kCancelled. Arena: at most register_rigid_bound(); nothing stays.
Status register_rigid(const Context& ctx, const Mesh& scan, const Mesh& ct_jaw,
                      const RegisterOptions& options, RegisterResult* result);

// The least-squares rigid motion taking the scan points onto the CT points of `pairs` (Horn,
// "Closed-form solution of absolute orientation using unit quaternions", JOSA A 4(4), 1987;
// the 4x4 eigenproblem by cyclic Jacobi). Sets *rms_mm to the fit's RMS. Errors:
// kInvalidArgument (fewer than 3 pairs, non-finite points, collinear scan points). No arena.
Status fit_landmarks(Span<const LandmarkPair> pairs, RigidTransform* out, double* rms_mm);

}  // namespace splintcore

#endif  // SPLINTCORE_REGISTRATION_H
