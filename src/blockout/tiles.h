// The swept surface decimated in the stream, tile by tile (module-private; blockout.h,
// SweepOptions::decimate_error, says what the result is).
//
// The extractor's triangles are gathered per tile: whole cell layers, until a tile holds at
// least kTileTriangles (a count of the data, never of the arena, so the bytes do not depend
// on the memory cap). A tile is an open patch; decimate_qem (remesh.h) with allow_boundary
// and keep_positions leaves its border where it is, so what is streamed meets what comes
// later vertex to vertex, and every vertex of the result is an extractor vertex. What reaches
// the tile's top kCarryLayers cell layers is carried into the next tile (decimated again
// there); the rest is streamed on (vertex ids by first use, as the extractor numbers them) or
// appended to a log that becomes the mesh at the end.
#ifndef SPLINTCORE_BLOCKOUT_TILES_H
#define SPLINTCORE_BLOCKOUT_TILES_H

#include "splintcore/blockout.h"
#include "splintcore/remesh.h"

namespace splintcore {

// Triangles per tile (at least; the tile ends with the cell layer that reaches it).
constexpr uint64_t kTileTriangles = uint64_t{1} << 16;

// Cell layers at a tile's top whose triangles (after its decimation) are carried into the
// next tile instead of being streamed: there they are decimated again with the next layers,
// so no seam stays fixed on a plane.
constexpr uint32_t kCarryLayers = 2;

struct TileDecimator {
  const Context* ctx = nullptr;
  double max_error = 0;  // decimate_qem's (mm)
  // decimate_qem's max_distance (mm): every extractor vertex ends within it of the result. The
  // extractor vertices a tile removes from the triangles it carries are carried with them (as
  // samples assigned to those triangles) and given to the next tile's decimation, so the
  // bound holds against the extractor's surface, not against a carried approximation of it.
  double max_distance = 0;
  // The extracted grid's box in the local frame: a vertex beyond it (a cap's) is locked, and
  // with drop_caps a triangle with all three corners beyond it is left out (as drop_caps()).
  Vec3 lo{}, hi{};
  double spacing_w = 0;  // the grid's spacing along w (lo.z is its first sample plane)
  bool drop_caps = false;
  int64_t last_layer = 0;                     // nz - 1: the tile that ends there is the last
  const MarchingCubesVisitor* out = nullptr;  // stream here; null: the log, made a mesh at the end
  // Tiles are decimated (and streamed) in the jaws' frame: world(frame, local), then rounded
  // to float32 when `float32` (so the decimator's exact flatness test sees the final bits).
  Vec3 (*world)(const void* frame, const Vec3& local) = nullptr;
  const void* frame = nullptr;
  bool float32 = false;
  // Between tiles, from `base` up (above the extractor's working set): the log of output
  // chunks (mesh variant), then the carry: the triangles carried into the next tile, their
  // vertices (position, w, beyond the box, output id or ~0u) and the map of the previous
  // tile's new vertices (extractor ids prev_first ..) to carried vertices (~0u: not carried).
  bool started = false;
  Arena::Marker base{};
  uint8_t* log = nullptr;
  uint64_t log_bytes = 0;    // carry included
  uint64_t carry_bytes = 0;  // the carry at the log's end
  uint32_t carried_vertices = 0, carried_triangles = 0;
  const Vec3* c_pos = nullptr;
  const double* c_w = nullptr;
  const uint32_t* c_out = nullptr;
  const uint8_t* c_beyond = nullptr;
  const Triangle* c_tris = nullptr;
  uint32_t carried_samples = 0;
  const Vec3* c_samples = nullptr;         // positions
  const uint32_t* c_sample_tri = nullptr;  // the carried triangle each is assigned to
  // The tile's given samples (decimate_qem's `samples`): the carried ones, then the midpoints
  // of the new triangles' sides and their centroids (each side once: from the triangle whose
  // side runs from the smaller patch id), with the patch triangle each is assigned to.
  uint32_t given_count = 0;
  const Vec3* given_pos = nullptr;
  const uint32_t* given_tri = nullptr;
  const uint32_t* given_source = nullptr;  // the patch triangle each lies on (~0u: carried)
  uint32_t prev_first = 0, prev_count = 0;
  const uint32_t* prev_map = nullptr;
  // This tile: its new vertices (extractor ids cur_first ..) and triangles, as they come.
  uint32_t cur_first = 0;
  ArenaArray<Vec3> cur_pos;        // in the jaws' frame
  ArenaArray<double> cur_w;        // local w
  ArenaArray<uint8_t> cur_beyond;  // beyond the box (a cap's vertex): locked
  ArenaArray<Triangle> cur_tris;
  // The result (mesh variant: split from the log after the last tile, above it).
  Mesh mesh;
  uint64_t out_vertices = 0, out_triangles = 0;
  // Counts.
  uint64_t input_triangles = 0, caps_dropped = 0, tiles = 0, peak_tile_triangles = 0;
  double max_collapse_error = 0;
};

// The visitor that feeds `d` (d->ctx, max_error, lo, hi, drop_caps, last_layer and out set).
// The mesh variant's result is d->mesh (local frame) when the extraction has returned: above
// the arena's top then, to be moved down (move_mesh_down) before anything else is allocated.
MarchingCubesVisitor tile_visitor(TileDecimator* d);

}  // namespace splintcore

#endif  // SPLINTCORE_BLOCKOUT_TILES_H
