// splintcore volume: scalar fields on regular grids and the tiled iso-surface extractor ("marching
// cubes") that serves both CT reconstruction and the blockout.
//
// The field is never held whole: a LayerSource fills z-layers on demand (sample_sdf in
// distance.h has this shape), and the grid is swept in slabs of z-layers that fit the caller's
// memory cap. Output is a mesh in the arena or a stream of vertices and triangles (e.g. into
// an StlWriter).
//
// Algorithm: marching tetrahedra on the Freudenthal subdivision of every cube: a closed
// 2-manifold with no ambiguous case (why it was chosen over marching cubes:
// docs/architecture.md, "The extractor: marching tetrahedra").
//
// Conventions (what the output is, exactly):
// - Inside is field < iso; a sample equal to iso (or above) is OUTSIDE. Samples beyond the
//   grid are outside (as if +infinity), so every surface closes; where the inside touches the
//   grid border the surface closes just outside it, kEdgeMargin of a voxel beyond the border.
// - Every vertex lies on a grid edge of the triangulation (the 3 axes, the 3 face diagonals
//   (+x+y, +x+z, +y+z) and the body diagonal (+x+y+z)) between an inside and an outside
//   sample. An edge is known by its lower endpoint and its direction. Its vertex is at
//   t = (iso - f0) / (f1 - f0) in double from the lower endpoint (f0 there, f1 at the upper),
//   clamped to [m, 1 - m], m = options.edge_margin (default kEdgeMargin) (so no vertex sits
//   on a sample, and no triangle
//   has zero area even where samples equal iso), at
//   origin[a] + spacing[a] * (i[a] + t * d[a]) per axis (d[a] = 0: origin[a] + spacing[a] * i[a],
//   the sample position sample_sdf uses). Edges to a sample beyond the grid use t =
//   kEdgeMargin from the sample inside the grid. The bits are a function of the edge and its
//   two samples, never of the slab or the cell that computes them.
// - Order: cells are visited z-major (z, then y, then x, from -1 to n - 1 on each axis: the
//   cells half outside the grid close the surface), the six tetrahedra of a cell in a fixed
//   order, triangles of a tetrahedron in a fixed order; vertex ids are given by first use in
//   that order (corner order within each triangle). Slabs are visited in z order, so the
//   output is the same bytes for every slab size and memory cap.
// - Triangles are counter-clockwise seen from outside (normals point to larger field values).
#ifndef SPLINTCORE_VOLUME_H
#define SPLINTCORE_VOLUME_H

#include "splintcore/core.h"
#include "splintcore/geometry.h"
#include "splintcore/mesh.h"

namespace splintcore {

// A regular grid: sample (i, j, k) is at origin + (spacing.x i, spacing.y j, spacing.z k),
// 0 <= i < nx and so on. Spacing may differ per axis (CT slices are often thicker than their
// pixels are wide); the extraction is the same piecewise-linear level set either way.
struct VolumeGrid {
  Vec3 origin{};
  Vec3 spacing{};  // mm between samples along x, y, z, each > 0
  uint32_t nx = 0, ny = 0, nz = 0;
};

// Fills z-layers [z_begin, z_end) into `out` (exactly nx * ny * (z_end - z_begin) floats, x
// fastest, then y, then z). Called with increasing, contiguous, non-overlapping ranges, each
// layer once. It may use ctx.arena for temporaries if it leaves the top where it found it.
// A non-ok status stops the extraction and is returned as is.
struct LayerSource {
  Status (*fill)(void* user, uint32_t z_begin, uint32_t z_end, Span<float> out) = nullptr;
  void* user = nullptr;
};

// Where output goes when streamed. vertex() is called once per vertex, ids 0, 1, 2, ... in
// order, just before the first triangle that uses it; triangle() gets the ids and the
// positions of its corners. layer_done() is called after the last triangle of each cell layer
// cz (-1 .. nz - 1, in order): a vertex on sample plane cz + 1 or above may be used again by
// later triangles, one below it never is. Any may be null. A non-ok status stops the
// extraction. They must not allocate from ctx.arena (they may when they rewind what they
// took), except above the working set in marching_cubes() (the blockout's tiles): what they
// leave there is above the arena's top when it returns.
struct MarchingCubesVisitor {
  Status (*vertex)(void* user, uint32_t id, const Vec3& position) = nullptr;
  Status (*triangle)(void* user, const Triangle& triangle, const Vec3& a, const Vec3& b,
                     const Vec3& c) = nullptr;
  void* user = nullptr;
  Status (*layer_done)(void* user, int64_t cz) = nullptr;
};

// Vertices are kept at least this fraction of an edge away from its samples (1/256).
constexpr double kEdgeMargin = 1.0 / 256.0;

// Layers per fill call when the cap allows it and options leave it to us.
constexpr uint32_t kMarchingCubesDefaultLayers = 16;

struct MarchingCubesOptions {
  double iso = 0.0;
  // Sample layers per fill call (the slab). 0: the most up to kMarchingCubesDefaultLayers that
  // fit the free arena (all of it for streaming, a quarter of it for the mesh variant, which
  // needs the rest for its output). Clamped to nz. The output never depends on it.
  uint32_t layers_per_tile = 0;
  // Vertices are kept at least this fraction of an edge away from its samples (and the
  // closing caps this far beyond the border): kEdgeMargin up to 1/4. A larger margin moves
  // vertices by at most that fraction of an edge and keeps triangles away from slivers that
  // rounding to float32 would fold (the blockout uses 1/16).
  double edge_margin = kEdgeMargin;
  // The id pool's size in ids when nonzero and below the full pool (ten ids per grid point of
  // a layer, or what the free arena holds): a caller that knows its surface crosses few edges
  // keeps the arena for its own use. A layer that needs more stops the extraction with
  // kArenaExhausted and MarchingCubesStats::pool_short set (the caller may run it again with a
  // larger pool). The output never depends on it.
  uint64_t pool_ids = 0;
};

struct MarchingCubesStats {
  uint64_t vertices = 0;
  uint64_t triangles = 0;
  uint32_t layers_per_tile = 0;  // what was used
  uint32_t fill_calls = 0;
  uint64_t working_set_bytes = 0;  // arena bytes held during the sweep (mesh output aside)
  bool pool_short = false;         // stopped: a layer needed more ids than the pool held
};

// Arena bytes of the sweep's working set with `layers` sample layers per fill call (buffer-mode
// arena, alignment padding included) when its id pool is full size:
//   16 + align16(4 nx ny (layers + 1)) + align16(8 W ny (layers + 1)) + 80 W (ny + 1)
//      + align16(40 (nx + 1)(ny + 1)),   W = ceil((nx + 2) / 64)
// (the samples of the slab plus the carried layer, and their inside bits, one bit per sample
// with a clear bit beyond each end of a row; rank prefixes, one 64-bit count per 64 grid
// points for each of ten kinds of edges: three in-plane kinds in each of the two sample planes
// of the current cells, four leaving the lower plane upwards; and the id pool, where only
// the edges the surface crosses get a 32-bit vertex id: ten per grid point is the most one
// cell layer can need). With less free arena the pool takes what there is (the fixed part is
// the minimum): the output is the same, and a layer that crosses more edges than the pool
// holds stops the extraction with kArenaExhausted naming the bytes it needs. A closed surface
// crosses far fewer edges than that (about its area in voxel faces per layer), so the fixed
// part, some 4.2 bytes per grid point of a layer, is what a large grid needs.
uint64_t marching_cubes_bound(const VolumeGrid& grid, uint32_t layers);

struct MarchingCubesMemory {
  uint64_t minimum = 0;      // one layer per fill call, no id pool: less than this cannot run
  uint64_t comfortable = 0;  // min(nz, kMarchingCubesDefaultLayers) layers per fill call
  uint32_t comfortable_layers = 0;
};
// Errors: kInvalidArgument (an empty grid), kLimitExceeded (sizes overflow 64 bits).
Status marching_cubes_memory(const VolumeGrid& grid, MarchingCubesMemory* out);

// Extra arena bytes marching_cubes_mesh() needs at its peak, beyond the working set, for a
// result of V vertices and T triangles (buffer-mode arena): the output log, 24 V + 12 T plus at
// most an eighth and 4 KiB of growth slack, then a copy of the triangles (12 T) while the log
// is split into the mesh arrays; the final mesh keeps 24 V + 12 T. About 80 bytes per vertex
// for a closed surface (T is about 2 V).
uint64_t marching_cubes_mesh_extra_bound(uint64_t vertex_count, uint64_t triangle_count);

// Streams the iso-surface of the field to `visitor`. Memory: the working set only (from
// ctx.arena, returned before it finishes). Progress: stage "marching cubes", once per slab
// (done = layers read so far, total = nz); cancelling returns kCancelled.
// Errors: kInvalidArgument (empty grid, spacing not > 0, a non-finite origin or iso, no fill);
// kArenaExhausted (the free arena is below the minimum: the message names it, or the chosen
// slab does not fit); kNonFinite (a sample is NaN or infinite: names x, y, z; at_index: its
// index in the grid); kLimitExceeded (more than 2^32 - 1 vertices); kCancelled; whatever
// fill() or the visitor return. On an error the visitor has seen a prefix of the output.
Status marching_cubes(const Context& ctx, const VolumeGrid& grid, const LayerSource& source,
                      const MarchingCubesOptions& options, const MarchingCubesVisitor& visitor,
                      MarchingCubesStats* stats = nullptr);

// The same output as a Mesh: `out` must be empty and bound to ctx.arena; the vertices and
// triangles are exactly those marching_cubes() streams, in the same order. Only the mesh stays
// in the arena (working set and log are reclaimed: the mesh starts where the arena's top was).
// On any error the arena's top is back where it was and `out` is empty. Peak memory: the
// working set plus marching_cubes_mesh_extra_bound(V, T). Errors: those of marching_cubes();
// kInvalidArgument when `out` is not empty.
Status marching_cubes_mesh(const Context& ctx, const VolumeGrid& grid, const LayerSource& source,
                           const MarchingCubesOptions& options, Mesh* out,
                           MarchingCubesStats* stats = nullptr);

}  // namespace splintcore

#endif  // SPLINTCORE_VOLUME_H
