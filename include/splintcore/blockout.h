// splintcore blockout: interference (undercut) elimination along an insertion direction (Chen et
// al. 2016, "The Interference Elimination", Figs. 5-6).
//
// The swept volume of the jaws along the direction d is S = { p + t d : p in J, t >= 0 }: every
// point a jaw passes through as it moves along d (the paper: each layer contains the layers
// before it). It is sampled on a grid whose third axis is d, swept in increasing w = p . d,
// with a 2-D state per column only (memory bounded by the cross-section, not the volume), and
// meshed by the tiled extractor of volume.h, whose output bytes do not depend on the slab size.
//
// The field. For a sample p outside S, the distance to S is exactly
//   dist(p, S) = min over t >= 0 of dist(p - t d, J),
// the distance from the half-line below p to J. The sweep keeps it per column as a running
// minimum of the distances from the column's segments between consecutive layers to J's
// triangles (continuous in t, so rims and silhouettes that fall between layers are not
// missed). p is inside S exactly when that half-line meets J, decided by the exact segment-
// triangle predicate. Inside S the running minimum says nothing about depth: the paper's
// binary image and a plain running minimum of signed distances both place the surface too far
// inside (the latter because depth inside J along the column is less than depth inside S).
// Here an inside sample i next to the surface gets the linear extrapolation of the exact
// outside field along a grid axis e: f(i) = 2 f(i + e) - f(i + 2 e), taken from the axis with
// the steepest outside slope, so that the iso-surface crossing on that edge is where the
// outside distance extrapolates to zero: exact for a plane, second order on curved surfaces.
// Only triangles facing against d or parallel to it can be the first contact of a column, so
// the others are skipped.
#ifndef SPLINTCORE_BLOCKOUT_H
#define SPLINTCORE_BLOCKOUT_H

#include "splintcore/boolean.h"
#include "splintcore/core.h"
#include "splintcore/geometry.h"
#include "splintcore/mesh.h"
#include "splintcore/volume.h"

namespace splintcore {

struct SweepOptions {
  // The direction the jaws move in (relative to the splint) as the splint is taken off: the
  // splint's insertion direction. Any non-zero finite vector; it is normalised. For the
  // paper's big-end-up cone blocked out along its axis (a cylinder results) it points down.
  Vec3 direction{0, 0, 1};
  double voxel = 0.1;  // mm, the grid spacing
  // How far beyond the jaws' far end (largest p . d) the swept volume is kept, mm; it is closed
  // there by a flat cap. 0: a cap just past the jaws.
  double extent = 0;
  // Only the part of the swept volume in this box (in the jaws' frame) is wanted, e.g. the
  // splint's bounds: the grid is cut to it (plus two voxels), closed by caps at its faces;
  // `extent` is then ignored (the box says how far to go). Columns are still swept from the
  // jaws' near end, so what lies inside the box is exactly what the whole sweep gives there.
  bool has_region = false;
  Aabb region;
  // Extract the surface this far inside the swept volume (mm, 0 <= inset < 2 voxels). The
  // blockout subtracts the swept volume from a splint that already holds the jaw's imprint,
  // whose surface the swept volume's front part reproduces to within the voxel error: an
  // inset a little above that error keeps the two from meeting except where the swept
  // volume really leaves the jaw (the undercuts), at the price of leaving that much undercut.
  double inset = 0;
  // Extract the surface this far OUTSIDE the swept volume instead (mm, 0 <= offset <= 20
  // voxels; with an offset the inset must be 0): the offset solid S + B(offset), a spacer
  // between the jaw and the splint. Exact where it matters: outside S the field is the exact
  // distance to S (to its closing, where a closing fills), so the surface is the true offset
  // surface within the extractor's piecewise-linear error.
  double offset = 0;
  // Morphological closing of the swept volume with a ball of this radius (mm; 0: none, else at
  // least two voxels): dilation then erosion, which fills gaps narrower than twice the radius
  // (between teeth) so that the splint has no thin fins reaching into them. Computed on the
  // field: the dilation is {f <= r} (f is the exact distance outside); the erosion takes,
  // for a sample in it, the distance to the dilation's complement as the least
  // |p - q| - (f(q) - r) over samples q outside it (the ball around q of radius f(q) - r lies
  // outside), searched within r + 2 voxels, layer by layer with a window of layers.
  double closing_radius = 0;
  // With a region, leave out the caps that close the volume where the region cuts it (mesh
  // variant only): an open surface whose border lies just outside the region's grid. What
  // the Boolean needs when the region holds its A (B may be open with its border outside A),
  // and the caps are most of the triangles when the region is a splint's bounds.
  bool open_at_region = false;
  // false: the plain running minimum inside (for measuring the bias it has); true: the
  // extrapolated inside field described above.
  bool correct_bias = true;
  // > 0 (mm, at most a tenth of a voxel): the surface is decimated in the stream, one-sided:
  // extracted decimate_error / 2 further out (iso + decimate_error / 2), then decimated in
  // tiles of whole cell layers (at least 2^16 triangles each, a count of the data, so the
  // bytes do not depend on the memory cap) by half-edge collapses in quadric-error order
  // (remesh.h; limit decimate_error / 2) kept within decimate_error / 2 of the extractor's
  // surface both ways at points (decimate_qem's max_distance: the extractor's vertices, side
  // midpoints and centroids to the result, the result's new sides' midpoints and centroids to
  // the extractor's triangles). A tile is an open patch whose border stays; what reaches its
  // top two cell layers is carried into the next tile, with the samples it holds, and
  // decimated again there (against the new layers' triangles; the carried ones are not
  // measured against), so no seam stays on a plane. Every vertex is an extractor vertex
  // (float32_vertices: rounded). EXPERIMENTAL, off by default: between the checked points the
  // surfaces depart up to 1.6x the bound (measured at 0.1 mm voxels with decimate_error
  // 0.01 mm: 0.008 mm against 0.005; tests/blockout/sweep_test.cpp, SweepDecimate), about
  // 4.7x fewer triangles there; on the real dentition's clearance surface, with its fine
  // features, only about 1.7x, at about 1 s a tile. 0: the extractor's surface, as it is.
  double decimate_error = 0;
  // With decimate_error: the vertices rounded to float32 (in the jaws' frame) before the
  // decimation, whose exact flatness test then sees the bits a float32 consumer (the
  // Boolean) gets; kLimitExceeded for a vertex beyond float32 range. The blockout sets it.
  bool float32_vertices = false;
  // Mesh variant with a region, open_at_region and float32_vertices, not decimating: only
  // the triangles this returns true for (corners in the jaws' frame, rounded to float32) are
  // kept, filtered in the stream, so that the extractor's whole surface is never held (the
  // blockout keeps the triangles near its splint). Kept triangles keep their order and are
  // numbered by first use among them; null: all are kept (as the unfiltered variant).
  bool (*keep_triangle)(const void* user, const Vec3& a, const Vec3& b, const Vec3& c) = nullptr;
  const void* keep_user = nullptr;
  // keep_triangle from several tasks at once (ctx's executor): with keep_tasks > 0, the run
  // of the batch that task i tests passes keep_task_users[i] (keep_user is then not used), and
  // keep_triangle must answer the same whichever user it gets (each may hold caches, used by
  // one task at a time). The triangles are tested in batches of kSweepKeepBatch (a fixed
  // 49 bytes each, from the arena before the extraction), cut into at most keep_tasks
  // contiguous runs, and logged in their order: the same kept triangles at any thread count.
  const void* const* keep_task_users = nullptr;
  uint32_t keep_tasks = 0;
  uint32_t layers_per_tile = 0;      // slab size for the extractor (0: automatic); bytes unchanged
  double edge_margin = kEdgeMargin;  // the extractor's (volume.h); the blockout uses 1/16
  // Where the sampled sweep takes vertex i of jaw j (j indexes the jaws it is given): null,
  // the jaw's own position; else what this returns (finite, or the sweep refuses it), read
  // twice per vertex and once per triangle corner. A caller that moves a jaw before the sweep
  // passes the move here rather than a moved copy of the vertices (the design: 24 bytes a
  // vertex, 5.3 MB for the real mandible). Not used by the exact sweep.
  Vec3 (*jaw_vertex)(const void* user, size_t jaw, size_t vertex) = nullptr;
  const void* jaw_vertex_user = nullptr;
};

constexpr uint32_t kSweepKeepBatch = 4096;  // SweepOptions::keep_tasks

struct SweepStats {
  uint32_t nx = 0, ny = 0, nz = 0;     // the extracted grid (z along the direction)
  uint32_t preroll_layers = 0;         // layers swept before the region's first (not meshed)
  uint64_t voxels = 0;                 // nx * ny * nz
  uint64_t front_triangles = 0;        // triangles facing against or across d (the rest skip)
  uint64_t segment_tests = 0;          // column segment against triangle: exact tests
  uint64_t distance_evaluations = 0;   // column segment to triangle distances
  uint64_t inside_columns = 0;         // columns that met a jaw
  uint64_t corrected_samples = 0;      // inside samples given an extrapolated value
  uint64_t cap_triangles_dropped = 0;  // open_at_region: the caps' triangles left out
  uint64_t filtered_triangles = 0;     // keep_triangle: the other triangles it left out
  // keep_triangle: the kept triangles' log at its end (12 bytes a triangle, 16 a vertex each
  // time it is logged: once, or again when the log's cache had forgotten it).
  uint64_t log_bytes = 0;
  // keep_triangle: the extraction ran again with the full id pool (a layer crossed more edges
  // than the quarter of it the first run has; the bytes are the same either way).
  bool full_id_pool = false;
  uint64_t closing_samples = 0;        // samples the erosion searched around
  uint64_t closed_samples = 0;         // samples outside the volume that the closing filled
  uint64_t decimated_tiles = 0;        // decimate_error > 0: tiles decimated
  uint64_t undecimated_triangles = 0;  // the extractor's triangles (caps dropped left out)
  uint64_t peak_tile_triangles = 0;    // the most in one tile
  double decimate_qem_error = 0;       // the largest quadric error of a collapse made (mm)
  MarchingCubesStats extraction;
  Vec3 axis_u{}, axis_v{}, axis_w{};  // the grid's axes in the jaws' frame (axis_w = d)
};

// Arena bytes the sweep's own state takes for `jaws` at most: a bit per vertex and per
// triangle that selects what the sweep needs (the front triangles whose shadow, grown by the
// band, meets the grid's columns: with a region, only those near it), local copies of those
// triangles and their vertices, sorted in place (their keys given back), and five layers of the raw
// field as 16-bit steps of band / 65534, the newest being the column state: 10 bytes per column.
// Without the extractor's working set (marching_cubes_bound) and output. A closing adds 2 m + 1
// layers of the field and 40 (2 m + 1)^3 bytes of search offsets, m = ceil(radius / voxel) + 2.
uint64_t sweep_state_bound(uint64_t vertex_count, uint64_t triangle_count, uint32_t nx,
                           uint32_t ny);

// Streams the surface of the swept volume (outward, closed, in the jaws' frame) to `visitor`.
// The jaws must have finite vertices; they need not be closed (a column's first contact with
// any triangle counts), but a closed, outward mesh is what makes S the solid the paper means.
// An empty result (a region that misses the jaws' shadow) is no error: nothing is streamed.
// Errors: kInvalidArgument (a zero or non-finite direction, voxel not > 0, negative extent, no
// triangles, an empty or non-finite region), kLimitExceeded (a grid above 2^31 samples per axis or
// 2^62 in all), kNonFinite (a vertex), kArenaExhausted (naming the need), kCancelled, those of
// marching_cubes(). Progress: "sweep" per layer, then the extractor's. Arena: the sweep's state
// (sweep_state_bound) and the extractor's working set, returned; the grid comes from the jaws,
// so the need is known by the two-step contract (a first run's high water, docs/embedding.md).
// Decimating, the extractor's slab is chosen within a quarter of the free arena, and above it
// the tiles take about 400 bytes per triangle of the largest tile (peak_tile_triangles: the
// gathered triangles and vertices, the patch, decimate_qem_bound, the carry, the samples:
// about 3.5 a triangle, 36 bytes each) and, for the
// mesh variant, the decimated output logged (24 bytes a vertex, 12 a triangle) and split once
// more at the end.
Status sweep_volume(const Context& ctx, Span<const Mesh> jaws, const SweepOptions& options,
                    const MarchingCubesVisitor& visitor, SweepStats* stats = nullptr);

// The same surface as a mesh in ctx.arena (`out` empty; on error the arena's top is back where
// it was and `out` is empty).
Status sweep_volume_mesh(const Context& ctx, Span<const Mesh> jaws, const SweepOptions& options,
                         Mesh* out, SweepStats* stats = nullptr);

// ---------------------------------------------------------------------------------------------
// The swept volume as a height field over the plane across d (issue 29), for a region.
//
// S is closed along d (p in S gives p + t d in S), so in the local frame (u, v, w = p . d) it is
// { w >= h(u, v) }, h the first contact of the column (u, v) with the jaws (+infinity where the
// column misses them), and its boundary is the graph of h: one sheet that cannot cross itself,
// whatever the jaws' folds and overhangs, with vertical steps where h jumps (a crown's widest
// over the gum). The graph is sampled on a grid of the voxel's spacing covering the region's
// shadow and two cells more: a row of squares of 2^k cells a side (the largest power of two at
// most an eighth of the shadow's longer side, at least 1), as many along u and v as cover it;
// and meshed as a triangulated irregular network of right triangles (longest-edge bisection,
// from the squares' diagonals; one lattice over the grid): a triangle is split while a grid vertex
// under it departs from it by more than half the tolerance, so flat parts take few triangles and
// steps the finest. The surface is conservative: it lies nowhere above h, so the splint keeps
// no undercut, and at most the tolerance plus a grid cell's departure below it:
// - each grid vertex starts at h of its column (the least height of the jaw triangles whose
//   shadow holds it, exact orient2d for the holding), and where the jaws lie above the region
//   (or nowhere) at a height 2 voxels and 1 mm above it;
// - each finest triangle of the grid (half a cell, the diagonal as the network cuts it) is
//   clipped against every jaw triangle over it; where the plane through its corners rises above
//   that jaw triangle inside the clip (a cusp between samples, a step, the shadow's edge), its
//   corners are lowered by the most it rises (HeightfieldStats::max_lowering);
// - the network's vertices are then the grid's, taken half the tolerance lower, so that the
//   triangles, within half the tolerance of the grid both ways, lie below it.
// The output's float32 rounding (with float32_vertices) is covered by a further 2^-20 of the
// largest coordinate. Uses SweepOptions' direction, voxel, region (required), offset, jaw_vertex
// and float32_vertices; the rest are not used (inset and closing must be 0).
// With an offset c (0 < c <= 20 voxels: a spacer) it is the height field of S grown by c: each
// front triangle T is replaced by the planar pieces of T + Q, Q a 12-sided lathe circumscribed
// about the lower half ball of radius c (src/blockout/offset_ball.h: T moved out, its edges'
// belts, and its corners' faces of Q where every front triangle around the corner leaves them),
// rasterized as the triangles are; the surface is then nowhere nearer the jaws than c (it lies
// below the first contact of S + Q, which holds S + the ball), and at most 0.0718 c beyond the
// offset surface besides the tolerance and the lowering. About 30 pieces a front triangle.
struct HeightfieldStats {
  uint32_t cells_u = 0, cells_v = 0;  // grid cells along u and along v (whole squares)
  uint32_t square_cells = 0;          // the squares' cells a side (a power of two)
  uint64_t triangles_in = 0;          // jaw triangles whose shadow meets the grid
  uint64_t offset_pieces = 0;         // with an offset: the planar pieces of its polytope
  uint64_t covered_vertices = 0;      // grid vertices whose column meets a jaw below the top
  // (jaw triangle, half cell) pairs whose planes the tests at their corners do not part: each
  // clipped, unless the most it could rise would not lower a corner further.
  uint64_t clipped_pairs = 0;
  uint64_t lowered_vertices = 0;      // grid vertices lowered by a clip
  double max_lowering = 0;            // mm, the most a vertex was lowered
  uint64_t network_triangles = 0;     // the output's triangles
  Vec3 axis_u{}, axis_v{}, axis_w{};  // the local frame in the jaws' frame (axis_w = d)
};

struct HeightfieldOptions {
  double tolerance = 0;  // mm, > 0 and at most the voxel: the network's (both ways, halved)
  double lower = 0;      // mm, >= 0: the whole surface taken that much lower still (a retry's)
  // The grid's origin moved back by this share of a cell along u and v ([0, 1)): a retry's
  // other grid, whose vertical steps stand elsewhere.
  double shift_u = 0, shift_v = 0;
};

// Arena bytes sweep_heightfield_mesh takes for a grid of cells_u by cells_v cells
// (HeightfieldStats), besides its output (24 bytes a vertex, 12 a triangle): 16 bytes a grid
// vertex; with an offset, the jaws' vertex count as `offset_vertices`: 4 bytes a vertex and the
// polytope's 11 KB more. With an executor that has threads, 12 bytes a grid vertex more where
// the arena has them let the passes run in two halves side by side; without them they run
// serially, to the same bytes, so this bound holds either way.
uint64_t sweep_heightfield_bound(uint32_t cells_u, uint32_t cells_v, uint64_t offset_vertices = 0);

// The graph above as an open surface (its normals against d, out of S) into `out` (empty), in
// the jaws' frame; its border is the grid's edge, outside the region. Only the jaws' triangles
// facing against d are taken (as the sampled sweep's: on a closed jaw nothing else is a first
// contact). Deterministic: the same bytes serially and on an executor (its two passes, the
// first contacts and the lowering, each in two halves of the triangles and pieces, merged as
// the least height and the most lowering). Errors: kInvalidArgument (out not empty, no region, an
// empty or non-finite region, a bad direction, voxel or option, no triangles), kLimitExceeded
// (a shadow more than 4096 cells across: a larger voxel or a smaller region; a vertex beyond
// float32), kNonFinite (a jaw vertex), kInvalidMesh (a vertex id out of range),
// kArenaExhausted, kCancelled. Progress: "heightfield".
Status sweep_heightfield_mesh(const Context& ctx, Span<const Mesh> jaws,
                              const SweepOptions& options, const HeightfieldOptions& height,
                              Mesh* out, HeightfieldStats* stats = nullptr);

// ---------------------------------------------------------------------------------------------
// The swept volume's boundary exactly, from the jaw's own triangles (issue 29), for a region.
//
// Along d the swept volume S of a closed jaw J is the union of the prisms T + t d (t >= 0) of
// J's front triangles T (those facing against d): a point p is in S when the half-line from p
// against d meets J, and the last front triangle it crosses on its way out of J lies below p.
// So S's boundary near a region is those front triangles, exact (the jaw's own vertices, bit
// for bit), and a wall along d hanging from each of their edges whose other triangle is not a
// front triangle (the silhouettes along d, where the front side turns away), with no voxels
// and no inset. Front triangles whose prism cannot reach the region (all corners strictly
// beyond a side of it that moving along d never comes back to) are left out; the walls end
// beyond the region. What comes out is an open surface (one shell per connected patch of front
// triangles, with its walls): its border (the walls' tops and the edges where triangles were
// left out) lies outside the region, which is what mesh_boolean takes of an open B whose
// border lies outside A (pass boolean_region(A) as the region). Patches of front triangles
// that overlap along d (adjacent teeth, a cusp over a fold) are separate shells that overlap,
// which mesh_boolean unites (its groups). For an open jaw (a scan) this is the sweep of its
// front side, which is the scan's sweep wherever the scan's border lies beyond the region.
//
// Each shell must be a valid open surface, which holds where a patch of front triangles is a
// height field along d. Where it folds over itself (a back-facing sliver between two front
// fans, the zigzag of a tessellated silhouette on a side nearly parallel to d) a wall would
// cross the front triangles above it (measured before this was handled: 10 of the real
// maxilla's 17 shells, 7 of the mandible's, all 14 of the 271k phantom mandible's). Such
// folds are found exactly: a wall's direction inside the corner of a surface triangle at its
// foot that lies above the wall (orient3d), or a wall meeting a surface triangle within
// kRings (8) rings of its foot (triangles_intersect, the walls' tops as emitted). The back
// triangles around that foot are then taken into the surface, round after round until no
// wall is crossed (at most 64 rounds). The surface then follows the jaw up and over the fold:
// the thin air pocket between a taken-in back triangle and the front triangle above it (its
// width is at most the taken-in triangle's seen along d) is not swept. Every taken-in triangle
// whose prism can reach the region is then checked: seen along d at most 0.05 mm wide (the
// undercut the voxel method's default inset leaves everywhere; the widest on the real jaws
// with the automatic outline: 0.040 mm), or its pocket at most that deep; else the sweep
// stops (kUnsupported, naming the triangle and where): a real overhang (a base reaching the
// teeth's necks) would be taken in whole, leaving the undercut itself unswept; unless the
// caller's ExactPocketTest finds nothing of use in its column (below). A crossing
// further away than the rings is found by blockout's check of each shell (below).
// Where the front triangles around a vertex form two fans or more, their walls would share
// the edge above it: such vertices count as folds too (ExactSweepStats::pinched_vertices:
// what is left of them).
struct ExactSweepStats {
  Vec3 direction{};               // d, normalised
  uint64_t front_triangles = 0;   // facing against d (exact sign of the normal along d)
  uint64_t kept_triangles = 0;    // front triangles whose prism can reach the region
  uint64_t walls = 0;             // edges with a wall (two triangles each)
  uint64_t top_vertices = 0;      // the walls' upper corners (rounded to float32)
  uint64_t pinched_vertices = 0;  // vertices with more than two walls
  uint64_t fold_vertices = 0;     // vertices whose fan overlapped a wall (back triangles taken in)
  uint64_t absorbed_triangles = 0;  // back triangles taken into the surface there
  uint32_t fold_rounds = 0;         // rounds that took some in
  uint64_t pockets_checked = 0;     // taken-in triangles whose unswept pocket was checked
  uint64_t pockets_shallow = 0;     // of them wider than the bound but no deeper than it
  uint64_t pockets_clear = 0;  // of them deeper, but with nothing in their column (ExactPocketTest)
  // Set by blockout (BlockoutOptions::exact), which checks the output's shells for
  // self-crossing where its Boolean takes them before it runs: the shells with triangles
  // checked (walls, and front triangles over their feet, in the region), the pairs their exact
  // checks examined, and the shells that cross only where the splint is not (such a crossing
  // is not part of the result).
  uint64_t shells = 0;
  uint64_t shell_check_candidates = 0;
  uint64_t shells_crossing_outside = 0;
};

// A pocket wider and deeper than the bound matters only where something would be left in it:
// `clear` answers, for such a taken-in triangle p, whether its prism along d up to the region's
// far side holds nothing of use (blockout: neither comes within 0.01 mm of the splint nor holds
// a part of it, as its shell check asks of a crossing). It may take arena memory (rewound with
// the sweep's temporaries).
struct ExactPocketTest {
  Status (*clear)(void* user, const Vec3 p[3], bool* is_clear) = nullptr;
  void* user = nullptr;
};

// Arena bytes sweep_exact_mesh takes at most for a jaw of these sizes (output included; what
// an ExactPocketTest takes is the caller's).
uint64_t sweep_exact_bound(uint64_t vertex_count, uint64_t triangle_count);

// The open surface described above into `out` (empty): the kept front triangles (the jaw's
// vertices, renumbered in input order, with its orientation) then two triangles per wall
// edge (a, b) of a kept triangle: (b, a, a') and (b, a', b'), where a' is a moved along d to
// beyond the region's face that d points through most (by its largest extent, at least
// 1 mm, past it) and rounded to float32. Deterministic: input order throughout. Errors:
// kInvalidArgument (out not empty, a zero or non-finite direction, an empty or non-finite
// region), kInvalidMesh (a vertex id out of range: the triangle), kNonFinite (a vertex),
// kLimitExceeded (a wall's top beyond float32), kUnsupported (a fold that would leave more
// than 0.05 mm of undercut that `pockets`, if given, does not find clear: the taken-in
// triangle, as the index), kArenaExhausted, what `pockets` returns. Arena: sweep_exact_bound;
// only `out` stays.
Status sweep_exact_mesh(const Context& ctx, const Mesh& jaw, const Vec3& direction,
                        const Aabb& region, Mesh* out, ExactSweepStats* stats = nullptr,
                        const ExactPocketTest* pockets = nullptr);

// ---------------------------------------------------------------------------------------------
// Interference elimination: the splint minus the jaws' swept volume.

// A height-field blockout's swept surface (BlockoutOptions::heightfield_swept): the attempt
// that made it, the height field's statistics then, and the surface, in the arena.
struct BlockoutSwept {
  bool held = false;
  uint32_t attempt = 0;
  HeightfieldStats stats;
  Mesh mesh;
};

struct BlockoutOptions {
  SweepOptions sweep;      // direction and voxel; the region is set to the splint's bounds
  BooleanOptions boolean;  // the operation is always the difference
  // Keep only the swept triangles that can matter to the splint, filtered in the stream
  // (SweepOptions::keep_triangle): those inside it or within an eighth of a voxel of its
  // surface (meeting included, exact), found through cells of 5 voxels (inside, outside, on
  // the surface) and, near the surface, the splint's distance index. The kept part's open
  // border then lies outside the splint (the Boolean's rule for an open B): the same solid,
  // with a few percent of the swept mesh (the imprint the sweep reproduces lies just inside
  // the jaw, outside the splint, and is left out). false: the whole swept surface in the
  // splint's box (for comparison). Not with decimation (decimate_error > 0). Near the surface
  // a swept triangle's side is found by counting the splint's triangles crossed on the way from
  // a point nearby whose side is known (SideHint, distance.h), which gives the closest point's
  // side on a splint that is a solid (closed, manifold, not crossing itself: as the Boolean
  // and the design leave it); the first of each place takes the closest point.
  bool filter_near_splint = true;
  // The swept volume's exact boundary (sweep_exact_mesh over boolean_region(splint)) instead
  // of the sampled one: no voxels, no inset, no retries; sweep.direction is used, the other
  // sweep options are not (an offset is refused: a spacer is the sampled sweep's or the height
  // field's). One jaw with triangles at a time (jaws without triangles are passed over). The splint
  // may be the base itself: the exact sweep holds the jaw, its front triangles are the imprint.
  // Before the Boolean each shell of the sweep that meets the region is checked exactly for
  // crossing itself (find_self_intersections), and a shell that does, again among its triangles
  // whose prism along d comes within 0.01 mm of the splint (triangle_side) or holds a part of it (a
  // shell of the splint whose box lies within the prism's): a crossing there is refused
  // (kUnsupported, with where; ExactSweepStats::shells, shells_crossing_outside). A fold's
  // pocket wider and deeper than 0.05 mm is taken only where its prism is not near the splint
  // in that sense (ExactPocketTest; ExactSweepStats::pockets_clear).
  bool exact = false;
  // The swept volume as a height field (sweep_heightfield_mesh over the splint's bounds, the
  // voxel its grid) instead, subtracted once: no inset, no retries, nothing left undercut;
  // sweep.inset and closing_radius must be 0; sweep.offset is a spacer (the height field of the
  // offset solid; a retry is 1/64 voxel further out each time, offset_used). Every jaw with
  // triangles is swept.
  bool heightfield = false;
  double heightfield_tolerance = 0;  // mm; 0: a tenth of the voxel
  // With the height field, the swept surface kept for a second run with the same options but
  // the Boolean's (BlockoutSwept): not held, the blockout leaves its swept surface there, after
  // *out in the arena, when the arena has room for it (else not held); held, the blockout
  // starts at its attempt with it instead of sweeping again (the sweep is deterministic: the
  // attempts before it and the surface would be the same), the surface staying where it is.
  BlockoutSwept* heightfield_swept = nullptr;
};

struct BlockoutStats {
  SweepStats sweep;
  ExactSweepStats exact;         // BlockoutOptions::exact
  HeightfieldStats heightfield;  // BlockoutOptions::heightfield
  uint64_t swept_triangles = 0;  // the swept volume's mesh inside the splint's bounds
  BooleanStats boolean;
  uint32_t attempts = 0;   // 1 + the retries with a deeper inset (or larger offset)
  double inset_used = 0;   // mm
  double offset_used = 0;  // mm (sweep.offset, as retried)
};

// `out` = `splint` minus the part of the jaws' swept volume (sweep_volume above, direction =
// the splint's insertion direction for these jaws) that lies in the splint's bounds. The swept
// mesh (extracted with an edge margin of 1/16, so no sliver folds in float32) is rounded to
// float32 (as the Boolean's B), then subtracted with mesh_boolean, whose checks the result
// passes (closed, manifold, outward, float32-exact, optionally no self-intersection). When
// the Boolean meets a configuration it cannot resolve even with its own nudges of A, the swept
// surface is taken again deeper, up to three times: 1/64, 1/4 and 1/2 voxel past the inset
// asked for (the last two for a sampled surface that crosses the jaw's imprint at shallow
// angles all along, as under a deep base; BlockoutStats::attempts and inset_used say what was
// used, and at most that much undercut is left; the inset stays below two voxels); with an
// offset (a spacer), 1/64 voxel further out each time instead (offset_used): a clearance is the
// fit asked for, not grown by the retries. A splint the sweep does not reach comes back
// unchanged (copied). For a wafer between two jaws call it once per jaw: the maxilla's direction is
// the mandible's reversed. Memory: with filter_near_splint a byte per cell of 5 voxels over the
// splint's box grown by two cells and the splint's distance index (distance_index_bound), the
// sweep's state and extractor (a slab of one layer beside the carried one), a batch of
// kSweepKeepBatch triangles waiting for the filter (49 bytes each) and four copies of its
// window (1,024 ids and boxes, 52 KB each; the filter runs in the executor's tasks), a 64 KB
// cache of the vertices logged, the kept swept triangles logged above it (12 bytes each, and
// 16 for each vertex the first time a kept triangle uses it: about 20 bytes a triangle), then
// the swept triangles and the larger of 4 bytes per extracted vertex and the swept vertices,
// moved down over the cells and the index; then the Boolean's; only
// `out` stays (moved down to where the arena's top was). Errors: those of sweep_volume_mesh and
// mesh_boolean (the latter prefixed "blockout:", and when retries ran and all failed "blockout:
// all N attempts failed (the swept surface inset A to B mm); the last: " and the last one's
// reason), kInvalidArgument (out not empty), kLimitExceeded
// (a swept vertex beyond float32 range); with `exact`, those of sweep_exact_mesh, and
// kUnsupported for a shell of the sweep that crosses itself where it matters to the splint.
Status blockout(const Context& ctx, const Mesh& splint, Span<const Mesh> jaws,
                const BlockoutOptions& options, Mesh* out, BlockoutStats* stats = nullptr);

}  // namespace splintcore

#endif  // SPLINTCORE_BLOCKOUT_H
