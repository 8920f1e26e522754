// splintcore remesh: Taubin smoothing and quadric-error-metric decimation of the meshes that
// surface reconstruction makes (closed, manifold, outward, large: marching tetrahedra give about
// twice the triangles of classic marching cubes).
//
// Both are deterministic: the output bytes are a function of the input bytes and the options
// only (never of the thread count, the arena's cap, pointers or hashing), on every compiler
// and CPU (sums in fixed orders, no libm beyond sqrt, exact predicates for the degeneracy
// decision).
#ifndef SPLINTCORE_REMESH_H
#define SPLINTCORE_REMESH_H

#include "splintcore/core.h"
#include "splintcore/geometry.h"
#include "splintcore/mesh.h"

namespace splintcore {

// ---------------------------------------------------------------------------------------------
// Taubin lambda|mu smoothing (G. Taubin, "A signal processing approach to fair surface design",
// SIGGRAPH 1995, section 4): each iteration is a shrinking step x += lambda L(x) followed by
// an inflating step x += mu L(x) (mu < -lambda < 0), with the umbrella operator
// L(x_i) = (1 / n_i) sum_j (x_j - x_i) over the n_i edge neighbours of vertex i. Jacobi:
// every step reads only the previous step's positions. mu = 0 gives plain Laplacian smoothing
// (which shrinks the mesh).

struct TaubinOptions {
  uint32_t iterations = 10;  // lambda|mu pairs
  double lambda = 0.5;       // in (0, 1]
  double mu = -0.53;         // in [-1, 0]; 0: plain Laplacian smoothing
  // > 0: after every step each vertex is pulled back to within this distance (mm) of its
  // position before smoothing (e.g. half a voxel, so a CT surface cannot drift). 0: no clamp.
  double max_displacement = 0.0;
  // Vertices on boundary edges (used by one triangle) stay where they are. When false they are
  // smoothed like the others (an open rim then shrinks inwards).
  bool fix_boundary = true;
};

struct TaubinStats {
  double volume_before = 0.0;  // mesh_volume() before and after (mm^3; signed)
  double volume_after = 0.0;
  uint64_t edges = 0;              // distinct undirected edges
  uint64_t boundary_vertices = 0;  // vertices on boundary edges
  uint64_t clamped = 0;            // vertex moves cut back by max_displacement, all steps
};

// Arena bytes taubin_smooth() may take at its peak (all returned before it finishes):
//   24 T + max(24 T, 4 (V + 1) + 8 E + V + 48 V) + 8 * 16, with E <= 3 T,
// i.e. the 3 T undirected edge keys and their sort scratch, then the keys, the CSR adjacency
// (offsets and both directions of every edge), the boundary flags, the Jacobi buffer and the
// positions before smoothing (only when max_displacement > 0; counted always). 0 on overflow.
uint64_t taubin_smooth_bound(uint64_t vertex_count, uint64_t triangle_count);

// Smooths mesh->vertices in place (triangles untouched). Any triangle mesh (open, or with
// unreferenced vertices, which do not move); vertices without neighbours do not move.
// Parallel over vertex blocks with ctx.executor (each task writes its own slots: the result
// does not depend on the executor). Progress: stage "taubin smooth", once per iteration.
// Memory: taubin_smooth_bound(V, T) at most, from ctx.arena, all returned.
// Errors (the mesh is unchanged on every error but kCancelled, which leaves it part-smoothed,
// as after a whole number of steps): kInvalidArgument (lambda, mu or max_displacement out of
// range or not finite); kInvalidMesh (a triangle refers to a missing vertex: at_index names
// it); kNonFinite (a vertex is not finite: at_index names it); kLimitExceeded (more than
// 2^32 - 2 vertices or 2^30 triangles); kArenaExhausted; kCancelled.
Status taubin_smooth(const Context& ctx, Mesh* mesh, const TaubinOptions& options,
                     TaubinStats* stats = nullptr);

// ---------------------------------------------------------------------------------------------
// Quadric error metric decimation (M. Garland and P. S. Heckbert, "Surface simplification
// using quadric error metrics", SIGGRAPH 1997): edge collapses in order of the error of the
// merged vertex against the planes of the original triangles around it (each plane weighted by
// its triangle's area), lowest first, until the target triangle count or the error limit.
//
// Error of a collapse: Q(p) / W, the area-weighted mean squared distance (mm^2) from the new
// position p to the original planes its quadric holds (W: their total area); the stated
// errors in mm are its square root. p: the minimiser of Q when the 3x3 system is well
// conditioned and the minimiser lies within one edge length of the edge's midpoint, else the
// best of the two endpoints and the midpoint (our own elimination, fixed operation order).
//
// A collapse is made only when it keeps the mesh a closed, oriented 2-manifold of the same
// topology with no flat triangle:
// - link condition (Dey et al. 1999): the two endpoints share exactly the two neighbours
//   opposite the edge, and neither of those, nor the merged vertex, drops below 3 neighbours
//   (which also keeps a tetrahedron a tetrahedron);
// - no triangle turns over: every triangle that moves keeps its normal within about 75.5
//   degrees of its old normal (a floating-point dot test: dot(n_new, n_old) > 0.25 |n_new|
//   |n_old|, as in meshoptimizer; a robust filter, not an exact predicate);
// - no triangle becomes flat: collinear3d (exact) on each moved triangle.
// A refused edge leaves the heap; it comes back when a later collapse merges into one of its
// endpoints (its error is recomputed then), and all refused edges come back when the heap has
// nothing left below the limits, as long as the previous round made a collapse.
//
// Order: a heap in the arena (8-ary, our own) keyed by (error, edge id): the error rounded
// toward zero to float32 by integer operations (the same bits everywhere), then the edge id,
// the smaller index of the edge's two half-edges (3 t + k: side k of triangle t), which breaks
// ties. Keys are kept exact (re-keyed whenever an endpoint changes), so the result bytes are a
// function of the input bytes and the options only. Permuting the input triangles may change
// the result (still valid).

struct DecimateOptions {
  // Stop when at most this many triangles are left (each collapse removes two).
  // 0: no count target (then max_error must be > 0).
  uint64_t target_triangles = 0;
  // > 0: no collapse whose error (see above, mm) exceeds it. 0: no limit.
  double max_error = 0.0;
  // Patches of a larger surface (the blockout's tiles). All default off; with them off the
  // result is the same bytes as before they existed.
  // Open meshes: boundary edges (used by one triangle) are allowed. A vertex on one never
  // moves or goes, and no edge with such an endpoint collapses, so a patch's border, and with
  // it the seam to its neighbours, stays exactly as it was.
  bool allow_boundary = false;
  // Half-edge collapses only: an edge collapses into the endpoint of smaller error, which
  // stays where it is, so every vertex of `out` is an input vertex with its input bits.
  bool keep_positions = false;
  // Optional (keep_positions only), one per input vertex: nonzero keeps the vertex (others
  // may collapse into it).
  Span<const uint8_t> locked;
  // Optional output, one per input vertex: its id in `out`, or ~0u when it went.
  Span<uint32_t> vertex_map;
  // > 0 (mm, keep_positions only): a bound on how far the result and the input surface
  // depart, kept both ways at points.
  // - Input to result, at samples of the input: every input vertex a collapse removes, and
  //   the given `samples`. Each is assigned to a triangle within max_distance of it (point to
  //   closed triangle): at a collapse the samples of the triangles that change are assigned
  //   again, each to the first triangle of the new fan within reach. The input's vertices
  //   that stay lie on the result, so every input vertex ends within max_distance of it.
  // - Result to input, at the midpoints of the sides and the centroid of every triangle a
  //   collapse moves: each within max_distance of an input triangle around one of its
  //   corners or of the moved samples (a given sample: the one it lies on, sample_sources).
  // A collapse that fails either is refused (counted in rejected_distance). Between those
  // points nothing is proved: the surfaces are measured there (tests). 0: no such bound.
  double max_distance = 0.0;
  // Optional (max_distance only): more samples of the input surface, each with the input
  // triangle it is assigned to (sample_triangles, one each) and, optionally, the one it lies
  // on (sample_sources, ~0u: none known): e.g. the midpoints of the input's sides, or the
  // samples an earlier decimation removed from a patch that is decimated again.
  Span<const Vec3> samples;
  Span<const uint32_t> sample_triangles;
  Span<const uint32_t> sample_sources;
  // Optional (max_distance only), one per input triangle: nonzero marks a triangle that is
  // itself an approximation (e.g. carried from an earlier decimation), never measured against.
  Span<const uint8_t> approximate;
  // Optional outputs (max_distance only): the triangle of `out` each given sample, and each
  // input vertex that went, ends assigned to (~0u for a vertex that stays).
  Span<uint32_t> sample_map;   // one per given sample
  Span<uint32_t> removed_map;  // one per input vertex
};

// Samples one collapse may move from the triangles that change to the new fan, and triangles
// of that fan, at most, with max_distance: a collapse that needs more is refused (a bound on
// the scratch memory, counted in rejected_distance).
constexpr uint32_t kDecimateMovedSamples = 4096;
constexpr uint32_t kDecimateFanTriangles = 256;

enum class DecimateStop : uint8_t {
  kTargetReached = 0,  // at most target_triangles left (also when the input already was)
  kErrorLimit,         // the next collapse would exceed max_error
  kNoValidCollapse,    // every remaining collapse breaks a rule above (e.g. a tetrahedron)
};

struct DecimateStats {
  uint64_t input_vertices = 0, input_triangles = 0;
  uint64_t output_vertices = 0, output_triangles = 0;
  uint64_t collapses = 0;
  uint64_t rejected_link = 0;        // refused by the link condition (each refusal counted)
  uint64_t rejected_flip = 0;        // a triangle would turn over
  uint64_t rejected_degenerate = 0;  // a triangle would be flat
  uint64_t rejected_distance = 0;    // max_distance: a sample would be left out of reach
  uint32_t rounds = 1;               // passes over the refused edges, plus the first
  double max_error = 0.0;            // the largest error of a collapse made (mm)
  DecimateStop stop = DecimateStop::kTargetReached;
};

// Arena bytes decimate_qem() may take at its peak, output included (alignment padding counted):
//   36 T + 128 V + max(4 (V + 1) + 12 T, 12 T + 4 V + 12 T + 24 V) + 12 * 64
// i.e. the working triangles (corners, twins and heap slots of their half-edges: 36 bytes
// each) and 128 bytes per vertex (quadric, position, fan, valence, mark); then either the
// input checks (half-edges bucketed by vertex) or the heap (8 bytes per edge, E = 3 T / 2), a
// vertex remap and the output mesh (at most the input's size): 60 T + 156 V, about 140 bytes
// per input triangle of a closed surface (V = T / 2). With max_distance (bounded_distance)
// also, kept throughout: a sample list per triangle and per sample (4 T + 4 (V + S), S the
// given samples), the input triangles around each vertex (4 (V + 1) + 12 T) and the scratch
// of one collapse (8 kDecimateMovedSamples + 96 kDecimateFanTriangles). 0 on overflow.
uint64_t decimate_qem_bound(uint64_t vertex_count, uint64_t triangle_count,
                            bool bounded_distance = false, uint64_t given_samples = 0);

// Decimates `mesh` (read only) into `out`, which must be empty and bound to ctx.arena: a new
// compact mesh (only referenced vertices, numbered in order of first use by the triangles in
// order; triangles in the order of the input's surviving triangles). Only `out` stays in the
// arena: it starts where the arena's top was. Vertices never moved keep their input bits.
// Input: a closed, edge-manifold, consistently oriented mesh without repeated ids in a
// triangle and with a single fan of triangles around every vertex (check_closed_oriented plus
// vertex-manifold); unreferenced vertices are allowed (dropped). Open meshes are not supported
// (kInvalidMesh names a boundary edge). An empty mesh gives an empty `out`.
// Progress: stage "decimate", every 65,536 collapses (done = triangles removed so far).
// On every error the arena's top is back where it was and `out` is empty.
// With allow_boundary the mesh may be open (edges used once; vertices on them need not have a
// single fan). Errors: kInvalidArgument (`out` not empty; no target and no error limit;
// max_error negative or not finite; `locked` without keep_positions, or `locked` or
// `vertex_map` not one per vertex); kInvalidMesh (index out of range, a repeated id, a boundary
// edge, an edge used twice in one direction or by more than two triangles, a vertex whose triangles
// form more than one fan: the message names the vertices, at_index the triangle); kNonFinite (a
// vertex, at_index: its id); kLimitExceeded (more than 2^32 - 2 vertices or 2^30 triangles);
// kArenaExhausted; kCancelled.
Status decimate_qem(const Context& ctx, const Mesh& mesh, const DecimateOptions& options, Mesh* out,
                    DecimateStats* stats = nullptr);

}  // namespace splintcore

#endif  // SPLINTCORE_REMESH_H
