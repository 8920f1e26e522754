// PNG previews for the command-line program (tool code: uses the standard library): the splint
// on the jaws for `splintcore design` and `splintcore render`, and a mesh coloured by its
// distance to another for `splintcore compare --png`. Drawing and encoding are the core's
// (include/splintcore/render.h); this file picks the colours and writes the file atomically.
#ifndef SPLINTCORE_TOOLS_PREVIEW_H
#define SPLINTCORE_TOOLS_PREVIEW_H

#include <string>
#include <vector>

#include "cli.h"
#include "splintcore/core.h"
#include "splintcore/mesh.h"
#include "splintcore/render.h"
#include "splintcore/spline.h"

namespace splintcore {
namespace cli {

// The preview's colours: the splint blue and opaque, the jaws grey and translucent (weight
// kJawAlpha of 255), so the splint shows through the jaws in every view (from the top the
// maxilla would hide it). Only the nearest translucent surface of a pixel is blended.
constexpr uint8_t kSplintRgb[3] = {70, 140, 230};
constexpr uint8_t kJawRgb[3] = {205, 200, 190};
constexpr uint8_t kJawAlpha = 130;
// How far around the splint's box the design preview draws the jaws (write_preview), in mm.
constexpr double kPreviewJawMarginMm = 3.0;

struct PreviewInfo {
  std::string path;
  std::string sha256;  // of the PNG bytes
  uint64_t png_bytes = 0;
  uint32_t width = 0, height = 0;
  double pixels_per_mm = 0;
  double render_seconds = 0;  // drawing
  double encode_seconds = 0;  // PNG encoding
};

// Draws `meshes` with `options`, encodes the PNG and writes it to `path` atomically (nothing is
// left at `path` on failure). Arena: at most render_bound() + png_bound(), all returned before
// it finishes. Errors: those of render_meshes() and write_png(); kIoError naming the file.
Status write_png_file(const Context& ctx, const std::vector<RenderMesh>& meshes,
                      const RenderOptions& options, const std::string& path, PreviewInfo* info);

// The automatic outline's picks and arch (outline.h), drawn over the design preview in
// kMarkRgb: a small octahedron at each pick, a thin bar along its line from the inner to the
// outside end, thin bars along the arch's polyline. `move` is applied to all of them (the tray
// placement). Spans point at the caller's data.
constexpr uint8_t kMarkRgb[3] = {235, 0, 0};
struct PreviewMarks {
  Span<const Pick> upper, lower;
  Span<const Vec3> arch;
  RigidTransform move;
};

// SHA-256 of `bytes`, 64 lower-case hex digits.
std::string sha256_hex(const std::vector<uint8_t>& bytes);

// The design preview: `splint` (opaque blue) under `jaws` (translucent grey), four views (front,
// top, right, iso) at width x height. `moves` is empty or one transform per jaw (each vertex is
// moved where it is drawn). Of each jaw only the triangles near the splint are drawn: those not
// wholly beyond one side of the splint's box widened by kPreviewJawMarginMm (the crowns the
// splint holds, not a CT dentition's roots: on the real dentition that halves the drawing,
// 0.14 -> 0.09 s a preview). They are copied, with the vertices they use, into ctx.arena
// (returned): 29 bytes a vertex of the jaws and 12 a triangle drawn at most. As write_png_file;
// kInvalidArgument when moves has another size than jaws.
// With `marks` (may be null) the picks and the arch are drawn over everything, seen through
// the splint and the jaws: the marks are drawn alone in a second pass given the first pass's
// framing (RenderOptions::framing), and their pixels are copied over. With `outputs` the file
// is kept there for its commit with the run's other outputs (cli.h), not placed now.
Status write_preview(const Context& ctx, const Mesh& splint, const std::vector<const Mesh*>& jaws,
                     const std::vector<RigidTransform>& moves, const std::string& path,
                     uint32_t width, uint32_t height, PreviewInfo* info,
                     const PreviewMarks* marks = nullptr, OutputSet* outputs = nullptr);

// `mesh` coloured per pixel by `distances` (one per vertex) on the blue-green-red ramp over
// [0, range] (render_ramp_colour; range > 0), four views, with the ramp's legend bar at the
// right edge (blue = 0 at the bottom, red = range and beyond at the top). As write_png_file.
Status write_distance_png(const Context& ctx, const Mesh& mesh,
                          const std::vector<double>& distances, double range,
                          const std::string& path, uint32_t width, uint32_t height,
                          PreviewInfo* info);

}  // namespace cli
}  // namespace splintcore

#endif  // SPLINTCORE_TOOLS_PREVIEW_H
