// splintcore spline: the initial splint base (Chen et al. 2016, "The Generation of the Initial
// Splint", Figs. 1-3): picked points become Lines (inner point, outside point), the line ends are
// interpolated by four splines, sampled at matched parameters, and joined by ruled surfaces into
// one closed solid.
#ifndef SPLINTCORE_SPLINE_H
#define SPLINTCORE_SPLINE_H

#include "splintcore/core.h"
#include "splintcore/geometry.h"
#include "splintcore/mesh.h"

namespace splintcore {

// ---------------------------------------------------------------------------------------------
// Curves: centripetal Catmull-Rom (alpha = 1/2; Yuksel, Schaefer, Keyser, "Parameterization and
// applications of Catmull-Rom curves", CAD 2011). Chosen because it interpolates the picks,
// never forms cusps or self-intersections within a segment, and does not overshoot on unevenly
// spaced picks, which uniform Catmull-Rom and natural cubics do. End tangents come from
// phantom points reflected through the end picks. Only + - * / and sqrt: bit-reproducible.

// Point on the segment from p1 to p2 (p0 and p3 its neighbours), at u in [0, 1] of the
// segment's centripetal knot interval. Consecutive points must differ.
Vec3 catmull_rom_point(const Vec3& p0, const Vec3& p1, const Vec3& p2, const Vec3& p3, double u);

// The same with the knots computed once for many points on one segment (the same bits).
struct CatmullRomSegment {
  Vec3 p[4];
  double t1 = 0, t2 = 0, t3 = 0;  // knots (t0 = 0)
};
CatmullRomSegment catmull_rom_segment(const Vec3& p0, const Vec3& p1, const Vec3& p2,
                                      const Vec3& p3);
Vec3 catmull_rom_point(const CatmullRomSegment& segment, double u);

// ---------------------------------------------------------------------------------------------
// Picks and lines.

// A pick as the user (or case file) gives it. Direction: `direction` if set (a user's
// adjustment, used as given after normalising), else `normal` (the surface normal at the pick)
// projected onto the occlusal plane and turned outward (buccal), else the in-plane
// perpendicular to the arch at the pick, outward. Outward means away from the centroid of the
// list's picks, seen in the occlusal plane.
struct Pick {
  Vec3 position{};
  Vec3 normal{};              // zero when not given
  Vec3 direction{};           // zero when not given
  double inner_length = 0;    // mm, from the pick towards the inside (lingual)
  double outside_length = 0;  // mm, from the pick towards the outside (buccal)
};

// The paper's Line structure: inner point, outside point, the (unit) direction, the lengths.
struct Line {
  Vec3 inner{};
  Vec3 outside{};
  Vec3 direction{};
  double inner_length = 0;
  double outside_length = 0;
};

// Resolves picks into lines (see Pick). `list_name` ("upper", "lower") names the list in
// errors, which also name the pick index. Errors: kInvalidArgument (fewer than 2 picks, a
// non-finite value, negative lengths, a zero-length line, two consecutive picks at the same
// place, a normal parallel to the occlusal plane's normal), kArenaExhausted. Arena: the lines
// appended to `out` (88 bytes each). On an error the arena is as it was and `out` holds what
// it held before the call.
Status make_lines(const Context& ctx, Span<const Pick> picks, const Vec3& occlusal_normal,
                  const char* list_name, ArenaArray<Line>* out);

// ---------------------------------------------------------------------------------------------
// The base solid.

struct BaseParams {
  double spacing_mm = 0.5;              // target distance between sections along the longest curve
  double corner_radius_mm = 0;          // rounds the four section corners (0: sharp)
  uint32_t corner_segments = 4;         // arc segments per rounded corner: 1, 2, 4, 8 or 16
  bool snap_to_float32 = true;          // round vertices to float32 (what STL stores) before checks
  bool check_self_intersection = true;  // exact check of the output (the guarantee)
};

struct BaseReport {
  uint32_t sections = 0;  // cross-sections along the arch
  uint32_t points_per_section = 0;
  uint64_t self_intersection_candidates = 0;
  double volume = 0;  // mm^3
};

// Bytes build_splint_base() may use for `sections` sections (outputs included).
uint64_t splint_base_bound(uint64_t sections, uint32_t points_per_section);

// Builds the closed base between the upper and the lower lines (the same number of each: the
// i-th upper line pairs with the i-th lower line, and the four curves are sampled at matched
// arc-length fractions within each pick interval). Sections run upper inner, upper outside,
// lower outside, lower inner; the faces are the ruled surfaces between consecutive sections
// (top, outer wall, bottom, inner wall) and two end caps: one closed, edge-manifold, outward
// mesh without duplicate vertices. `out` must be empty.
// Errors (naming the pick interval): lists that do not pair up; curves that cross or lines
// that fold (a section turns over); a section too thin or a corner radius too large for it;
// a self-intersecting result. kArenaExhausted, kCancelled. Arena: at most
// splint_base_bound(); only the mesh stays. On an error the arena is as it was and `out` is
// empty.
Status build_splint_base(const Context& ctx, Span<const Line> upper, Span<const Line> lower,
                         const BaseParams& params, Mesh* out, BaseReport* report);

// The side of the base's section that a section segment lies on, for callers that need to tell
// the base's faces apart (the design's side-wall check). The base's layout: section k's points
// are vertices k * P .. k * P + P - 1 (P = points_per_section), corner after corner (upper
// inner, upper outside, lower outside, lower inner), each corner one point, or
// corner_segments + 1 points along its arc when rounded; segment j runs from point j to point
// (j + 1) mod P, and triangles 2 (k P + j) and 2 (k P + j) + 1 are the ruled surface along
// segment j between sections k and k + 1 (the end caps follow all of those). A side is the
// straight segment between two corners and the half of each corner's arc next to it; the
// middle segment of an arc of one segment belongs to neither (kCorner).
enum class BaseSide : uint8_t { kTop, kOuter, kBottom, kInner, kCorner };
BaseSide base_segment_side(const BaseParams& params, uint32_t segment);

}  // namespace splintcore

#endif  // SPLINTCORE_SPLINE_H
