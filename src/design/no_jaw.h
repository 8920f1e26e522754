// Jaws that are no jaws (issue 30, "a jaw that is a single triangle soup without any tooth"):
// refused up front, naming the cause, before the outline, the fusion or the Boolean make
// something of them (an outline of noise, a fit to a plane, or a base with nothing subtracted);
// and, once the base is made, jaws that do not reach it (no imprint) and jaws whose teeth cross
// its side walls (a jaw moved sideways, picks off the arch).
#ifndef SPLINTCORE_DESIGN_NO_JAW_H
#define SPLINTCORE_DESIGN_NO_JAW_H

#include "splintcore/design.h"

namespace splintcore {
namespace design_detail {

// A jaw's surface rises at least this far from any plane: crowns stand several mm above the gum
// (a jaw reconstructed from CT, an intraoral scan of crowns and gum alike).
constexpr double kMinJawReliefMm = 1.0;
// At least this many triangles a connected piece, on average: a jaw's surface is one piece or
// a few (teeth, islands of a scan), never hundreds of loose triangles.
constexpr uint32_t kMinTrianglesPerPiece = 4;
// A jaw in mm spans at least this much along its longest side (a dental arch is 35-65 mm
// wide, a quadrant's scan over 20 mm) and at most this much (a head's CT is about 250 mm):
// outside, the file is in other units. A full arch in inches (about 2.4), centimetres (about
// 6) or metres (about 0.06), or in micrometres (about 60,000), is told apart from a jaw in mm.
constexpr double kMinJawExtentMm = 10.0;
constexpr double kMaxJawExtentMm = 1000.0;

// Each jaw of `c` (jaws[j]) and each scan (scans[j] where c.jaws[j].has_scan; `scans` may be
// empty): kInvalidMesh naming the jaw (its index and role, "the scan of" for a scan) when it is
//   - a triangle soup: fewer than kMinTrianglesPerPiece triangles a piece, the pieces being
//     the triangles connected through shared vertices (loose triangles, an unwelded export);
//   - in other units: the longest side of the box of its triangles' corners under
//     kMinJawExtentMm or over kMaxJawExtentMm (the case's units are mm: the message gives the
//     scale factors to mm);
//   - flat: every corner within kMinJawReliefMm of one plane, the plane of its triangles'
//     area vectors summed with the sign of the largest one's (a sheet, a plate: no tooth).
// Then two jaws that are one (the same triangles and vertices bit for bit under the same
// transform: the same file given twice) are kInvalidArgument naming both.
// The message says what was found and what to do (the first such mesh in that order: each jaw,
// then its scan). An empty mesh, a triangle with a vertex id out of range or a mesh of zero
// area is left to the stage that names it. Threads: each mesh is measured in a task of its own
// on ctx.executor. Arena: 5 bytes a vertex of all the meshes together, returned. Errors:
// kInvalidMesh, kArenaExhausted.
Status refuse_no_jaw(const Context& ctx, const CaseFile& c, Span<const Mesh> jaws,
                     Span<const Mesh> scans);

// Each jaw of `c` (jaws[j], placed by its transform and rounded as B holds it: b_vertex) must
// reach the splint's base: one of its triangles at least must have corners not all beyond one
// side of boolean_region(base) (the Boolean's own crop, boolean.h), else the jaw could leave no
// imprint (its part of B would be empty) and the splint would be made without it, as it was
// for a jaw given in another frame or by a wrong transform. kInvalidMesh naming the first such
// jaw, with its box as placed and the base's, and what to check. The scan in the triangles'
// corners stops at the first that reaches (a jaw that reaches is usually found within its first
// triangles); a jaw that does not is read whole, twice (the box for the message). Threads: each
// jaw in a task of its own on ctx.executor. Arena: a byte a jaw, returned.
Status refuse_out_of_reach(const Context& ctx, const CaseFile& c, Span<const Mesh> jaws,
                           const Mesh& base);

// The side-wall check: each jaw of `c` (placed by b_vertex) against the side walls of `base`
// (build_case_base's mesh for c.base, its sections and points per section in `built`): the
// stretches between consecutive sections where a jaw triangle meets an outer or an inner wall
// triangle (BaseSide; exactly, triangles_intersect; degenerate triangles skipped), as lengths
// along the arch (WallCrossing) into report->walls (the first kMaxBlockoutJaws jaws;
// report->wall_jaws). There the jaw's imprint would open through the splint's side: its teeth
// lie outside the outline, as they do for a jaw moved sideways by a wrong transform, or picks
// off the arch. A jaw crossing more than c.max_wall_crossing of the arch, or sideways of it
// (WallCrossing::sideways_mm) more than c.max_sideways_crossing, is kInvalidMesh
// naming it (the first in case order), the lengths, where the first crossing is and what to
// check. Only the jaw triangles whose corners, as given, are not all beyond one side of the
// walls' box taken back into the jaw's frame are placed and tested, through a uniform grid of
// the wall triangles. Threads: each jaw in a task of its own on ctx.executor. Arena: 5 bytes a
// wall triangle, 8 a grid cell (at most 2^16 cells), 4 a (cell, wall triangle) pair and a byte
// a stretch per jaw, all returned. Errors: kInvalidMesh, kArenaExhausted.
Status measure_side_walls(const Context& ctx, const CaseFile& c, Span<const Mesh> jaws,
                          const Mesh& base, const BaseReport& built, DesignReport* report);

// With a blockout, the maxilla must lie on the side of the mandible the insertion direction d
// points to (its vertices' mean along d, placed by b_vertex, above the mandible's): the
// maxilla's swept volume goes along d, the mandible's along -d, so with the roles swapped (or d
// reversed) each sweep would run back through the splint and leave it with hardly an imprint,
// a valid solid all the same. kInvalidArgument naming both jaws, their means along d and what
// to check. Only for a case with a blockout and both roles (without a blockout the roles
// change nothing the Boolean makes; the automatic outline turns its normal, and so its
// insertion direction, from the mandible to the maxilla). Linear in the jaws' vertices, no
// arena.
Status refuse_swapped_roles(const CaseFile& c, Span<const Mesh> jaws);

}  // namespace design_detail
}  // namespace splintcore

#endif  // SPLINTCORE_DESIGN_NO_JAW_H
