// Synthetic dental-arch phantoms (tools, tests and benchmarks only: std::vector, no arena).
//
// One closed, edge-manifold, outward, genus-0 triangle mesh per jaw, shaped to fit the case
// fixtures/cases/paper_scale.json, so the mesh Boolean (splint base minus jaws) can be run at
// the paper's sizes (about 86,866, 324,246 and 543,530 triangles per jaw).
//
// Construction: a tube swept along the dental arch. The path is an ellipse in the occlusal
// plane; the cross-section lies in the path's normal plane (spanned by the outward normal N
// and the vertical) and is star-shaped around a centre O: a polar curve r(u, v) > 0 over a
// fixed, strictly increasing set of angles, so a section never folds. r is the gum ridge (an
// ellipse seen from O) except at 14 tooth positions, where it bulges towards the occlusal side
// into a crown: rays from O fan out, so a crown is wider at its occlusal end than at its neck
// (undercuts on the buccal and lingual sides), and its occlusal surface carries cusps (smooth
// polynomial bumps: 4 on molars, 2 on premolars, 1 on canines, an incisal ridge on incisors).
// Two fans to the centres O of the end sections close the tube: genus 0,
// 2 * sections * ring_size triangles, sections * ring_size + 2 vertices. The path's radius of
// curvature (at least 14 mm) is about three times the section's reach towards the concave
// side (5 mm), so consecutive sections never cross (JawMesh reports both).
//
// Fit to paper_scale.json (units mm, case frame; the fixture's picks lie on the ellipses
// (25 cos t, 42 sin t, +1.6) upper and (24 cos t, 40.5 sin t, -1.6) lower, t in
// [-0.18, pi + 0.18], lines 4.0 mm inward and 3.5 mm outward; the mandible's transform is a
// -2 mm translation in z):
//   - maxilla crowns point down (-z): cusp tips at z = 1.6 - depth, depth 1.38..1.52 mm per
//     tooth, so the base's top face (z = 1.6) cuts that deep into each crown; the gum ridge
//     stays above z = 4.1 (2.5 mm clear of the base);
//   - mandible crowns point up (+z), generated in OCCLUSION (before its transform): tips at
//     z = 0.4 + depth, i.e. -1.6 + depth after the -2 mm translation; the gum ridge stays below
//     z = -2.1 (-4.1 after the translation). In occlusion the two jaws interpenetrate (each
//     jaw's tips reach about 1.7 mm past the other's): the fixture's 3.2 mm wafer and 2 mm
//     opening leave room for 1.3-1.6 mm per jaw only after the mandible's transform, so use
//     the jaws as the case does;
//   - across the arch each crown is centred between the base's inner and outside walls at its
//     depth (the path is the blend of the two pick ellipses, 0.35 of the way to the other
//     jaw's, offset 0.25 mm inward), at most 5.4 mm wide where the base is about 7.5 mm: each
//     imprint is a closed pocket; along the arch the end crowns stay about 1.5 mm inside the
//     base's ends.
//
// Grids at the paper's sizes (sections x ring size, triangles): 86,866 -> 488 x 89 = 86,864;
// 324,246 -> 1158 x 140 = 324,240; 543,530 -> 1469 x 185 = 543,530. A 543,530-triangle jaw
// takes about 15 ms to generate.
//
// Determinism: only + - * / and sqrt (correctly rounded by IEEE 754), sin and cos by our own
// Taylor polynomials on a reduced range, everything in a fixed order; vertices rounded to
// float32 at the end. The bytes are the same with any compiler, flags (with
// -ffp-contract=off) and CPU.
#ifndef SPLINTCORE_TOOLS_PHANTOM_H
#define SPLINTCORE_TOOLS_PHANTOM_H

#include <cstdint>
#include <string>
#include <vector>

#include "splintcore/core.h"
#include "splintcore/geometry.h"
#include "splintcore/mesh.h"

namespace splintcore {
namespace phantom {

enum class Jaw : uint8_t { kMaxilla = 0, kMandible = 1 };

constexpr uint32_t kTeethPerJaw = 14;
constexpr uint8_t kGumLabel = 0xFF;  // JawMesh::vertex_tooth of gum-ridge and cap-centre vertices
constexpr uint64_t kMinTriangles = 2000;
constexpr uint64_t kMaxTriangles = 16'000'000;

struct PhantomOptions {
  uint64_t target_triangles = 87000;  // per jaw; the result lands within 1% of it
};

struct JawMesh {
  std::vector<Vec3> vertices;       // float32-exact, pairwise distinct
  std::vector<Triangle> triangles;  // counter-clockwise seen from outside
  // Per vertex: the tooth (0..13 along the arch, from the +x end) whose crown moved it, or
  // kGumLabel (gum ridge, end-cap centres).
  std::vector<uint8_t> vertex_tooth;
  uint32_t sections = 0;   // rings along the arch
  uint32_t ring_size = 0;  // vertices per ring
  // Designed depth (mm) of each crown's deepest cusp tip below the base face it meets
  // (sampled vertices are at most this deep).
  double tooth_depth_mm[kTeethPerJaw] = {};
  double min_path_radius_mm = 0;    // smallest radius of curvature of the sweep path
  double max_concave_reach_mm = 0;  // largest reach of a section towards the path's concave side
};

// The grid make_jaw() uses for a target: sections * ring_size * 2 triangles.
struct GridSize {
  uint32_t sections = 0;
  uint32_t ring_size = 0;
};

// Builds one jaw in the case frame, in occlusion (see the top of this file). Reads `options`;
// replaces *out. Errors: kInvalidArgument when the target is outside
// [kMinTriangles, kMaxTriangles]; kInternal if a construction invariant fails (a bug).
[[nodiscard]] Status make_jaw(Jaw jaw, const PhantomOptions& options, JawMesh* out);

// The grid chosen for `target_triangles` (the same for both jaws). Zero sizes when the target
// is out of range.
GridSize choose_grid(uint64_t target_triangles);

// Appends the jaw to `out` (bound to an arena). Errors: kArenaExhausted, kLimitExceeded (the
// arena's mesh would exceed 2^32 - 1 vertices).
[[nodiscard]] Status to_mesh(const JawMesh& jaw, Mesh* out);

// The binary STL bytes the library's StlWriter writes for the jaw (replaces *out).
// Errors: those of StlWriter (none expected: it writes to memory).
[[nodiscard]] Status stl_bytes(const JawMesh& jaw, std::vector<uint8_t>* out);

// The case file that goes with the phantom jaws "maxilla.stl" and "mandible.stl" in one
// folder: the picks, lines, opening and printer of fixtures/cases/paper_scale.json (14 picks
// per list on the ellipses above, computed with this file's sin and cos and written with 4
// decimals, as the fixture generator does), `case_id` as given. JSON text, newline-terminated.
std::string case_json(const char* case_id);

// sin and cos with only + - * / (Taylor polynomials after reduction by pi/2): the same bits
// everywhere, for |x| up to a few radians.
void sin_cos(double x, double* s, double* c);

// ---- scan-like jaws (issue 30; scan_phantom.cpp) ----------------------------------------------
//
// An open surface as an intraoral scanner gives it: a band along the arch (the ellipses of the
// solid phantom's picks) with 14 crowns on a gum ridge, as a height field over a grid (columns
// along the arch, rows across it), crowns up for the mandible (+z), down for the maxilla. Then
// the defects, placed by a seeded PRNG (splitmix64 over hash_mix) at fixed places along the
// arch so they never touch: a ragged border (each column loses 0-2 cells at either side, so
// the border is a staircase and stays vertex-manifold), `holes` holes of 1x1, 2x1 and 2x2 cells
// (4, 6 and 8 boundary edges) inside the band, `islands` loose 2x2-cell patches (0.64 mm^2,
// 8 triangles) beside it, `nonmanifold_edges` flaps (a triangle on a cell's diagonal sticking
// out 1.5 mm), `duplicates` repeated triangles, one 2x2-cell patch (8 triangles) wound the
// other way, and noise of +-0.025 mm in height. Colours: crowns ivory, gum pink.
struct ScanOptions {
  uint64_t seed = 1;
  uint32_t columns = 280;  // cells along the arch
  uint32_t rows = 40;      // cells across it (16 mm)
};

struct ScanJaw {
  std::vector<Vec3> vertices;  // float32-exact
  std::vector<Triangle> triangles;
  std::vector<uint8_t> rgb;  // 3 per vertex
  // What was planted: prepare_scan's report should find exactly these.
  uint32_t holes = 0;
  uint32_t max_hole_edges = 0;
  uint32_t islands = 0;
  uint32_t nonmanifold_edges = 0;
  uint32_t duplicates = 0;
  uint32_t flipped_triangles = 0;
};

// Builds one scan-like jaw (replaces *out). Errors: kInvalidArgument (fewer than 100 columns or
// 32 rows, or more than 4000 of either).
[[nodiscard]] Status make_scan_jaw(Jaw jaw, const ScanOptions& options, ScanJaw* out);

}  // namespace phantom
}  // namespace splintcore

#endif  // SPLINTCORE_TOOLS_PHANTOM_H
