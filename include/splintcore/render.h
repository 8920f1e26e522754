// splintcore render: a preview of meshes (the splint on the jaws, or a mesh coloured by a
// per-vertex scalar such as its distance to another surface) from fixed standard views, drawn by
// our own z-buffer rasteriser, and a PNG encoder (zlib/deflate, CRC-32, Adler-32) writing to a
// ByteSink.
//
// Deterministic bytes: the views are fixed orthographic directions whose rotations need only
// sqrt; vertices are snapped to a 1/256-pixel grid and covered by exact integer edge functions
// with a top-left fill rule (shared edges are drawn once); depth and shading use + - * / sqrt
// only, evaluated in a fixed order (the build has -ffp-contract=off); a depth tie keeps what
// was drawn first (mesh order, then triangle order). Views are independent tiles: with an
// executor they are drawn in parallel, with identical bytes for any thread count.
#ifndef SPLINTCORE_RENDER_H
#define SPLINTCORE_RENDER_H

#include "splintcore/core.h"
#include "splintcore/geometry.h"
#include "splintcore/io.h"
#include "splintcore/mesh.h"

namespace splintcore {

// Largest image side (pixels) render_meshes() and write_png() accept.
constexpr uint32_t kRenderMaxSide = 8192;
constexpr uint32_t kRenderMaxViews = 8;

// Orthographic views in the case frame (z up, the occlusal plane near z = 0, the incisors
// towards +y as in the phantoms and fixtures). Each names the direction to the eye and the
// screen's right and up axes (right x up = towards the eye).
enum class RenderView : uint8_t {
  kFront,  // eye on +y: right -x, up +z
  kTop,    // eye on +z: right +x, up +y
  kRight,  // eye on +x: right +y, up +z
  kIso,    // eye on (1,1,1)/sqrt3: right (-1,1,0)/sqrt2, up (-1,-1,2)/sqrt6
};

// "front", "top", "right", "iso".
const char* render_view_name(RenderView view);
// Parses one of those names; false otherwise.
bool parse_render_view(const char* text, size_t length, RenderView* out);

enum class RenderShading : uint8_t {
  kFlat,     // one intensity per triangle (its normal)
  kGouraud,  // intensities at the vertices (area-weighted normals), interpolated
};

struct RenderMesh {
  const Mesh* mesh = nullptr;
  uint8_t rgb[3] = {200, 200, 200};
  // 255: opaque. Less: the mesh is translucent: its nearest surface in front of the opaque
  // meshes is blended over them with this weight (out of 255).
  uint8_t alpha = 255;
  // Optional: one value per vertex (mesh->vertices.size()), mapped per pixel to the
  // blue-green-red ramp over [0, scalar_max] (render_ramp_colour) instead of rgb.
  const double* scalars = nullptr;
  double scalar_max = 0;
  // Optional: the mesh is drawn moved by this transform, with the same bytes as a moved copy
  // (each vertex moved by apply_point) and without the copy's memory.
  const RigidTransform* transform = nullptr;
};

// Where the views look and how large: each view's centre (mm along its right and up axes) and
// the scale common to all. render_meshes() returns the one it chose (RenderImage::framing); given
// back in RenderOptions::framing it draws other meshes into exactly the same places.
struct RenderFraming {
  double pixels_per_mm = 0;
  double centre_u[kRenderMaxViews] = {};
  double centre_v[kRenderMaxViews] = {};
};

struct RenderOptions {
  uint32_t width = 1024;  // the whole image, 1..kRenderMaxSide
  uint32_t height = 1024;
  RenderView views[kRenderMaxViews] = {RenderView::kFront, RenderView::kTop, RenderView::kRight,
                                       RenderView::kIso};
  uint32_t view_count = 4;  // 1..kRenderMaxViews
  // Tiles per row; 0: 1 for one view, otherwise 2. Tiles are filled row-major in views order.
  uint32_t columns = 0;
  RenderShading shading = RenderShading::kFlat;
  uint8_t background[3] = {255, 255, 255};
  // A vertical ramp bar (blue at the bottom = 0, red at the top = scalar_max) in a strip of
  // max(8, width / 48) pixels at the right edge; the tiles share the rest.
  bool legend = false;
  // Optional: a framing to use instead of framing the meshes (e.g. marks drawn in a second
  // pass in the places of a first); finite, pixels_per_mm > 0.
  const RenderFraming* framing = nullptr;
};

// An 8-bit RGB image, rows top to bottom, 3 bytes per pixel.
struct RenderImage {
  uint32_t width = 0;
  uint32_t height = 0;
  uint8_t* rgb = nullptr;  // width * height * 3 bytes (in the arena)
  // The common scale of every view (pixels per mm) and the tile size.
  double pixels_per_mm = 0;
  RenderFraming framing;  // the views' centres and the scale (pixels_per_mm)
  uint32_t tile_width = 0;
  uint32_t tile_height = 0;
  uint32_t columns = 0;
};

// Bytes render_meshes() may take from the arena at most (caller-buffer arena): the image
// w*h*3 (kept) and the temporaries (returned before it finishes): a depth buffer w*h*4; with a
// translucent mesh a second layer w*h*(4+3+1); with Gouraud shading one normal (3 floats) per
// vertex of the mesh being drawn; its vertices projected into the views drawn at once (16
// bytes each): views_at_once = the smaller of the view count and the executor's concurrency
// (1 with the serial executor); each array padded to 16 bytes. A mesh with a transform takes
// nothing more (each vertex is moved where it is projected, not copied).
// render_bound() = 15*w*h + 12*largest + 16*views_at_once*largest + 112, rounded up to 16
// (translucency and Gouraud assumed; `largest`: the most vertices of one mesh; UINT64_MAX on
// overflow).
uint64_t render_bound(uint32_t width, uint32_t height, uint64_t largest_mesh_vertices,
                      uint32_t views_at_once);

// Draws `meshes` (in order) into `out->rgb`, allocated from ctx.arena (kept; temporaries are
// returned before it finishes). Reads the meshes, writes *out. The scene is framed once for
// all views: the same pixels-per-mm everywhere, each view centred on its own projection of
// all meshes' vertices, 5% margin. Triangles are drawn from both sides. Of the translucent
// meshes only the nearest surface of each pixel is kept, blended over the nearest opaque one.
// Errors: kInvalidArgument (size 0 or over kRenderMaxSide, view_count 0 or over
// kRenderMaxViews, a tile smaller than a pixel, a framing not finite or of scale not > 0, a
// null mesh, scalars with scalar_max not > 0 or not finite);
// kInvalidMesh (a triangle naming a missing vertex: at_index the triangle); kNonFinite (a
// vertex or scalar that is NaN or infinite: at_index the vertex); kArenaExhausted;
// kCancelled (ctx.progress, checked between meshes).
Status render_meshes(const Context& ctx, Span<const RenderMesh> meshes,
                     const RenderOptions& options, RenderImage* out);

// The ramp: t = value / max clamped to [0, 1] (NaN: 0); blue (0,0,255) at 0, green at 0.5,
// red at 1, linear in between, channels floor(255 x + 0.5). Same as `splintcore compare`'s PLY.
void render_ramp_colour(double value, double max, uint8_t rgb[3]);

// ---------------------------------------------------------------------------------------------
// PNG (ISO/IEC 15948:2003): 8-bit RGB, no interlace; IHDR, IDAT chunks of at most 64 KiB, a
// tEXt "Software" chunk, IEND. Rows are filtered (None, Sub, Up or Paeth, chosen per row by
// the smallest sum of absolute values, in bands of rows on the context's executor) and
// compressed as one zlib stream (RFC 1950) of fixed-Huffman deflate blocks (RFC 1951) from a
// greedy LZ77 hash-chain matcher (32 KiB window, chains of at most 64 candidates, every
// position of a match up to 32 bytes hashed, only the last 3 of a longer one), one block per
// MiB of filtered rows made on the executor (deflate_parallel, compress.h): the bytes depend
// only on the pixels, not on the threads.

// Bytes write_png() may take from the arena (all temporaries, returned before it finishes):
// the filtered rows h*(1+3w) + 16 and the deflate lanes for them, deflate_lanes_bound
// (compress.h). UINT64_MAX on overflow.
uint64_t png_bound(uint32_t width, uint32_t height);

// Writes the image as PNG to `sink` (a sequence of writes; never seeks). Reads image.rgb.
// Errors: kInvalidArgument (a side of 0 or over kRenderMaxSide, or rgb null); kArenaExhausted;
// kIoError (the sink failed, names the sink); kCancelled (ctx.progress, every 64 rows while
// filtering, before anything is written).
Status write_png(const Context& ctx, const RenderImage& image, const ByteSink& sink);

// crc32() and adler32() of compress.h under their former names (kept for callers).
uint32_t png_crc32(uint32_t crc, const uint8_t* data, size_t bytes);
uint32_t png_adler32(uint32_t adler, const uint8_t* data, size_t bytes);

}  // namespace splintcore

#endif  // SPLINTCORE_RENDER_H
