// splintcore boolean: difference, union and intersection of triangle meshes by corefinement
// (Chen et al. 2016, "The Boolean operation", Fig. 4): both meshes are split along their
// intersection, the pieces are classified inside or outside the other solid, and the result is
// assembled from the pieces an operation keeps. Floor 5: core, geometry, mesh, distance.
//
// How it decides, and what it promises:
// - Only the part of B near A is touched: B's triangles whose boxes miss A's box are never
//   split or classified (they are outside A); the rest are paired with A's triangles through a
//   bounding volume hierarchy over A.
// - Each candidate pair is decided by exact predicates (orient3d on the input coordinates).
//   An intersection point is named symbolically (an edge of one mesh and a triangle of the
//   other) and computed once, so every triangle that shares it gets the same vertex: the result
//   has no cracks by construction. Its coordinates are the rounded double of the exact point.
// - Each cut triangle is re-triangulated on its own plane (projected to 2-D, constrained
//   Delaunay with exact orient2d/incircle on the rounded points) along its intersection
//   segments, so the two meshes share every intersection edge.
// - Pieces are grouped into patches (connected without crossing an intersection edge). A patch
//   next to an intersection edge is classified exactly by the side of the other triangle's plane
//   it lies on, derived from the same predicates; the rest (whole shells that do not cross the
//   other mesh) by the generalised winding number of the other mesh. Two exact answers that
//   disagree on one patch are an error, never a guess.
// - Input vertices are copied bit for bit; every output vertex is an input vertex or a rounded
//   intersection point of an edge of one mesh with a triangle of the other.
// - Degenerate contacts (a vertex exactly on the other surface, edges that cross exactly,
//   coplanar overlapping triangles) are reported as kUnsupported naming the two triangles, in
//   this version; nothing is written from such an input. The caller may move B by a tiny
//   rigid offset and retry (see splintcore boolean --help).
// - The result is checked (closed, edge-manifold, consistently oriented, no degenerate
//   triangle) before it is returned for the difference and the intersection; a failure is an
//   error, never a silently broken mesh.
//
// B may hold several shells (one per tooth); they must not overlap each other inside A (the
// pieces of one shell inside another are not removed in this version). B may be open (a scan)
// when its border lies outside A.
#ifndef SPLINTCORE_BOOLEAN_H
#define SPLINTCORE_BOOLEAN_H

#include "splintcore/core.h"
#include "splintcore/geometry.h"
#include "splintcore/mesh.h"

namespace splintcore {

enum class BooleanOp : uint8_t {
  kDifference,    // A - B: A's pieces outside B, B's pieces inside A (reversed)
  kUnion,         // A + B: A's pieces outside B, B's pieces outside A
  kIntersection,  // A * B: A's pieces inside B, B's pieces inside A
};
const char* boolean_op_name(BooleanOp op);

struct BooleanOptions {
  BooleanOp op = BooleanOp::kDifference;
  // Round the intersection points to float32 (input vertices that are float32 already, as STL
  // input is, are unchanged) and check the result as an STL file will hold it: no two
  // vertices rounded together, no triangle rounded flat, closed, and (below) no
  // self-intersection. What rounding breaks is an error naming the place, never a silently
  // broken file.
  bool float32_output = true;
  // Exact self-intersection check of the result (find_self_intersections): the final word
  // that the file is a valid solid. Costs about as much as the operation itself.
  bool check_self_intersection = true;
  // A degenerate contact, or a result that rounding to float32 would break, is retried with
  // A (never B) translated by k * step * (1, 3, 7) for k = 1..max_nudges, step = 2^-16 mm
  // (15 nm; coarser only when A's coordinates are beyond 256 mm, so that float32 vertices of
  // A stay float32): at most about 0.9 um with the default, far below a printer's 16 um
  // layer. The translation used is in BooleanStats::nudge. 0 turns it off.
  uint32_t max_nudges = 8;
};

struct BooleanStats {
  uint64_t near_b_triangles = 0;     // B triangles whose boxes meet A's box
  uint64_t candidate_pairs = 0;      // (A, B) triangle pairs whose boxes overlap
  uint64_t intersecting_pairs = 0;   // pairs that cross (one segment each)
  uint64_t intersection_points = 0;  // distinct points shared by both meshes
  uint64_t cut_triangles_a = 0;
  uint64_t cut_triangles_b = 0;
  uint64_t winding_queries = 0;      // parts without a cut, classified by winding number
  uint64_t output_triangles = 0;
  uint64_t output_triangles_a = 0;   // the result's first triangles come from A, the rest from B
  uint64_t self_intersection_candidates = 0;  // pairs tested by the final check
  uint32_t attempts = 0;                      // 1 + the nudges tried
  Vec3 nudge{};                               // A's translation in the returned result
};

// Computes options.op of the closed mesh A and the mesh B into `out` (empty).
// A must be a valid solid (closed, edge-manifold, outward). Temporaries are returned before it
// finishes; the result is moved down over them. Errors: kInvalidMesh (A is not a solid, a
// degenerate triangle of B meets A: named), kUnsupported (a degenerate contact: the two
// triangles are named), kArenaExhausted (the message says how much was needed at that point),
// kLimitExceeded (more than 2^31 vertices or triangles in all), kCancelled, kInternal (a
// result that fails its own check: please report it with the inputs).
Status mesh_boolean(const Context& ctx, const Mesh& a, const Mesh& b,
                    const BooleanOptions& options, Mesh* out, BooleanStats* stats);

}  // namespace splintcore

#endif  // SPLINTCORE_BOOLEAN_H
