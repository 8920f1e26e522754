// splintcore outline: the splint's picks from the two jaws themselves (issue 28). From a
// maxilla and a mandible in any frame: the occlusal plane and the side each arch faces, the
// dental arch (cusp tips and fossae seen from the other jaw), paired picks along it with
// buccal directions and line lengths from the arch's width, the wafer's surfaces set so the
// teeth sink a chosen depth into it, and, when asked, the bite opened to an exact distance.
// The method and its limits are in docs/architecture.md ("The automatic outline").
#ifndef SPLINTCORE_OUTLINE_H
#define SPLINTCORE_OUTLINE_H

#include "splintcore/core.h"
#include "splintcore/distance.h"
#include "splintcore/geometry.h"
#include "splintcore/mesh.h"
#include "splintcore/spline.h"

namespace splintcore {

// The most picks per jaw and arch points compute_outline() gives.
constexpr size_t kMaxOutlinePicks = 256;
constexpr size_t kMaxOutlineArchPoints = 1024;

struct OutlineOptions {
  // How deep the deepest cusp of each arch sinks into the wafer (mm, (0, 5]); every tooth of
  // the span sinks at least half as deep where the occlusal surfaces allow it.
  double indentation_depth_mm = 2.0;
  // The wafer reaches this far past the buccal and lingual extent of the occlusal surfaces
  // (mm, [0, 10]): 2 mm covers the cusps' outer slopes, so a tooth seats in a full-depth
  // imprint, and leaves a wall about as thick as the printer's strongest thin feature.
  double overhang_mm = 2.0;
  // Distance between picks along the arch (mm, [2, 20]).
  double pick_spacing_mm = 3.0;
  // Move the mandible along the occlusal normal until the smallest distance between the jaws
  // is exactly bite_opening_mm (mm, [0.1, 10]): away from the maxilla when they are nearer (or
  // meet), towards it when they stand farther apart; without it the jaws must already be apart.
  bool has_bite_opening = false;
  double bite_opening_mm = 0;
  // Jaws farther apart than this (mm) are refused: no wafer bridges them.
  double max_gap_mm = 10.0;
  // The insertion direction: the occlusal normal, or (survey) the direction within 15 degrees
  // of it along which the teeth leave the least undercut in the wafer (both volumes reported).
  bool survey = false;
  // Where the wafer ends distally (patient mm, in the jaws' frame: the frame of the picks), one
  // point a side in either order, e.g. the distal surface of the last tooth to cover. The arch
  // is cut at each point's place along it (its projection onto the occlusal plane, nearest the
  // arch's centre line: there the cut is the plane through the point across the arch), so that
  // no pick lies beyond it. Each point lies within 15 mm of the centre line, in the occlusal
  // plane, and one on each half of the arch (either side of its middle); a point beyond the
  // arch's natural end (its last occlusal surface plus overhang_mm) changes nothing.
  bool has_distal_ends = false;
  Vec3 distal_ends[2] = {};
};

struct OutlineReport {
  Vec3 occlusal_normal{};       // unit, from the mandible towards the maxilla
  Vec3 anterior{};              // unit, in the occlusal plane, towards the incisors
  double gap_as_given = 0;      // smallest distance between the jaws as given, mm
  bool jaws_intersect = false;  // as given
  bool opened = false;          // the mandible was moved (has_bite_opening)
  Vec3 mandible_translation{};  // the move: along -occlusal_normal (or +, to close a gap)
  double opening = 0;           // smallest distance after the move, mm
  uint32_t opening_steps = 0;   // conservative-advancement steps
  uint32_t picks = 0;           // per jaw
  double arch_length_mm = 0;    // along the arch, end to end, before the overhang
  double min_wafer_mm = 0;      // the thinnest section, top to bottom
  double max_wafer_mm = 0;
  uint64_t cells_upper = 0, cells_lower = 0;  // occlusal cells found per jaw
  Vec3 insertion_direction{};                 // the occlusal normal, or the survey's choice
  bool surveyed = false;
  uint32_t survey_directions = 0;  // directions tried
  double undercut_plain_mm3 = 0;   // along the occlusal normal (surveyed only)
  double undercut_chosen_mm3 = 0;  // along the chosen direction (surveyed only)
  // The distal ends (has_distal_ends), per point as given: its distance from the arch's
  // centre line in the occlusal plane, and how much of the picks' span it cut at its end (mm
  // along the arch; 0 for a point beyond the natural end).
  bool distal_limited = false;
  double distal_offset_mm[2] = {0, 0};
  double distal_cut_mm[2] = {0, 0};
};

struct Outline {
  Span<const Pick> upper;  // picks of the wafer's top face (the maxilla's side)
  Span<const Pick> lower;  // and of its bottom face, paired with `upper`
  Span<const Vec3> arch;   // the arch's centre line in the occlusal plane (preview)
  OutlineReport report;
};

// Bytes compute_outline() needs for these jaws, at most (from their sizes and extent; the
// picks and the arch stay, everything else is returned).
uint64_t compute_outline_bound(const Mesh& maxilla, const Mesh& mandible);

// The picks for a splint between `maxilla` and `mandible` (closed or open meshes, in any frame,
// the mandible where the plan puts it). Each pick carries its direction (unit, buccal) and
// both line lengths, so make_lines() uses them as they are; upper and lower picks pair up.
// Errors (kInvalidArgument unless said): an empty or non-finite jaw (kInvalidMesh,
// kNonFinite), jaws that do not face each other, no occlusal surfaces found, an arch too
// short, jaws touching or interpenetrating without has_bite_opening, jaws farther apart than
// max_gap_mm, options out of range, distal ends that are not finite, lie more than 15 mm from
// the arch, both on one half of it or leave less than 20 mm of it; kArenaExhausted; kCancelled
// (progress "outline"). On an error the arena is as it was.
Status compute_outline(const Context& ctx, const Mesh& maxilla, const Mesh& mandible,
                       const OutlineOptions& options, Outline* out);

// ---------------------------------------------------------------------------------------------
// Hinge-axis autorotation (issue 32, two-jaw surgery): the mandible turned about the line
// through the two condyles until the smallest distance between the jaws is the opening asked.
// The method is in docs/architecture.md ("Autorotation: the mandible about the hinge axis").

struct AutorotateOptions {
  // The condylar points (patient mm, the jaws' frame): the line through them stays fixed. At
  // least 1 mm apart. Angles are right-handed about the direction hinge[0] -> hinge[1].
  Vec3 hinge[2] = {};
  double opening_mm = 0;  // [0, 10]
};

struct AutorotateReport {
  // The answer: the angle (radians, right-handed about hinge[0] -> hinge[1]; |angle| <= 30
  // degrees) and the mandible's move it makes, p -> R (p - hinge[0]) + hinge[0]
  // (rotation_about_axis, geometry.h).
  double angle_rad = 0;
  RigidTransform transform;
  // +1 when a positive angle closes the mandible (moves it towards the maxilla), else -1: the
  // sign of the velocity of the mandible's vertex centroid, turned by a positive angle, along
  // the direction to the maxilla's vertex centroid.
  int closing_sign = 1;
  double gap_as_given = 0;     // the smallest distance at angle 0 (0 when the jaws meet)
  bool met_as_given = false;   // the jaws' surfaces meet at angle 0
  double start_angle_rad = 0;  // where the closing started: 0, or the open angle found first
  double opening = 0;          // the smallest distance at angle_rad, mm (the opening measured)
  double bracket_rad = 0;      // the first crossing lies in [angle, angle + this] (closing)
  double lever_mm = 0;         // R: the largest distance of a mandible vertex from the axis
  uint32_t steps = 0;          // distance evaluations
  // The closest pair at angle_rad (the first contact for an opening of 0): the points (the
  // mandible's moved) and their triangles.
  Vec3 contact_maxilla{}, contact_mandible{};
  uint32_t triangle_maxilla = 0, triangle_mandible = 0;
};

// Arena bytes autorotate_mandible() takes at most (nothing stays): a pairs_only distance index
// of each jaw without the triangles' boxes (distance_index_bound), one pair search's stack
// and heap, a pool of 32768 pairs.
uint64_t autorotate_mandible_bound(const Mesh& maxilla, const Mesh& mandible);

// The angle of the mandible about the hinge axis at which, closing it from open, the smallest
// distance between the two meshes' surfaces first equals options.opening_mm (X). With the
// jaws as given (angle 0) more than X apart, the mandible turns in the closing sense from 0 to
// the first angle where the distance is X. With them X apart or nearer (touching,
// interpenetrating), it first turns in the opening sense to the first of the angles 30 / 2^k
// degrees (k = 7 .. 0, growing) where they are more than X apart (this only brackets), then
// closes from there to the first angle where the distance is X.
// No sampling in angle: conservative advancement (a point at distance r from the axis moves at
// most r |dtheta|, so with R the largest distance of a mandible vertex from it the step
// (d - X) / R never passes the first crossing), with Newton steps that land past it (by the
// closest pair's rate) shrinking the bracket from the far side, until the crossing is
// bracketed within 1e-10 rad; the answer is the bracket's near end (the distance there is X
// and at most R 1e-10 mm more). The distances are mesh_pair_distance_rigid over one index of
// each jaw, built once, and once the bracket is narrow a scan of the pairs that can come within
// the opening inside it (docs/architecture.md).
// Errors (kInvalidArgument unless said): a jaw empty or broken (kInvalidMesh, kNonFinite), a
// hinge point not finite or the two less than 1 mm apart, an opening outside [0, 10], a closing
// sense that cannot be told (the cosine between the centroid's velocity and the direction to
// the maxilla under 0.1 in magnitude),
// jaws that still meet or lie within X at 30 degrees open, or that do not come within X in 30
// degrees of closing (each with the distances measured); kArenaExhausted; kLimitExceeded (no
// convergence in 2000 evaluations). On an error the arena is as it was.
Status autorotate_mandible(const Context& ctx, const Mesh& maxilla, const Mesh& mandible,
                           const AutorotateOptions& options, AutorotateReport* out);

// autorotate_mandible over the caller's indexes of the two jaws (their meshes: maxilla.mesh,
// mandible.mesh), which a plan's two splints build once and refit to each splint's moved jaws
// (refit_distance_index, distance.h): the same report, bit for bit, as autorotate_mandible of
// the two meshes. The indexes must be pairs_only (distance.h), any leaf size, with or without
// the triangles' boxes; their builds checked the meshes (finite vertices, corners in range).
// Arena: autorotate_mandible_indexed_bound() (nothing stays). Errors: as autorotate_mandible
// (an empty jaw: kInvalidMesh).
// The options autorotate_mandible builds its indexes with (pairs_only, without the triangles'
// boxes): the cheapest for its searches, for a caller that builds its own.
DistanceIndexOptions autorotate_index_options();
uint64_t autorotate_mandible_indexed_bound();
Status autorotate_mandible_indexed(const Context& ctx, const DistanceIndex& maxilla,
                                   const DistanceIndex& mandible, const AutorotateOptions& options,
                                   AutorotateReport* out);

}  // namespace splintcore

#endif  // SPLINTCORE_OUTLINE_H
