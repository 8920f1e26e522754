// splintcore label: the case label, engraved into or embossed on the splint's outer (buccal) wall
// in a built-in stroke font (issue 8, design options; the paper leaves the splint unlabelled).
//
// - The font: our own single-line strokes on an integer grid, glyphs 0..4 units wide and
//   0..6 high (6 = the cap height), advance = width + kStrokeFontGap units. A-Z (lower case is
//   folded to upper), 0-9, space and - _ . / # + ( ) :. A stroke of one point is a dot.
// - Each glyph is a closed solid: the strokes thickened to the stroke width and extruded
//   through the wall ([-depth, +1 mm] to engrave, [-0.3 mm, +depth] to emboss), subtracted
//   from or added to the splint by the exact Boolean (boolean.h). How a glyph is meshed and
//   why (a sampled field, marching tetrahedra, QEM, resampling on a fragile contact):
//   docs/architecture.md, "The label: how a glyph is made".
// - Automatic placement follows the arch: centred on the wall's mid curve by arc length, each
//   glyph in its own frame (up = the wall direction, n = outward), reading left to right seen
//   from outside; depth is measured from the real wall (a ray's first hit). Explicit
//   placement: one frame for the whole row. Glyphs never touch (checked on the meshes).
// - Only + - * / and sqrt reach the output (no trigonometry), every loop runs in a fixed
//   order, and the Boolean is the exact one: the same bytes on every platform.
#ifndef SPLINTCORE_LABEL_H
#define SPLINTCORE_LABEL_H

#include "splintcore/boolean.h"
#include "splintcore/core.h"
#include "splintcore/geometry.h"
#include "splintcore/mesh.h"
#include "splintcore/spline.h"

namespace splintcore {

// ---------------------------------------------------------------------------------------------
// The stroke font.

constexpr int kStrokeFontHeight = 6;    // cap height, grid units
constexpr int kStrokeFontMaxWidth = 4;  // widest glyph, grid units
constexpr int kStrokeFontGap = 2;       // clear cell gap between glyphs, grid units
constexpr uint32_t kStrokeGlyphMaxPoints = 24;
constexpr uint32_t kStrokeGlyphMaxStrokes = 4;

struct StrokeFontPoint {
  int8_t x = 0;  // 0..width
  int8_t y = 0;  // 0..kStrokeFontHeight, up
};

// One glyph: stroke s runs through points [s == 0 ? 0 : stroke_end[s - 1], stroke_end[s]).
struct StrokeGlyph {
  char character = 0;        // as stored (upper case)
  uint8_t width = 0;         // grid units: every point has 0 <= x <= width
  uint8_t advance = 0;       // width + kStrokeFontGap
  uint8_t stroke_count = 0;  // 0 only for the space
  uint8_t point_count = 0;
  StrokeFontPoint points[kStrokeGlyphMaxPoints];
  uint8_t stroke_end[kStrokeGlyphMaxStrokes] = {};
};

// The glyph of `c` (lower case folded to upper) into *out; false (out unchanged) when the font
// has none. Reads a constant table only; no arena.
bool stroke_font_glyph(char c, StrokeGlyph* out);

// Every character the font has, upper case, space included, NUL-terminated.
const char* stroke_font_characters();

// ---------------------------------------------------------------------------------------------
// Options, placement and statistics.

constexpr uint32_t kLabelMaxCharacters = 32;

enum class LabelMode : uint8_t {
  kEngrave,  // the glyphs are cut into the wall (splint minus glyphs)
  kEmboss,   // the glyphs stand out of the wall (splint union glyphs)
};
const char* label_mode_name(LabelMode mode);

enum class LabelPlacement : uint8_t {
  kAutomatic,  // on the outer wall, centred on the middle of the arch (needs the lines)
  kExplicit,   // at `position`, facing `normal`, with `up` (a straight row)
};

struct LabelOptions {
  const char* text = "";  // 1..kLabelMaxCharacters font characters
  LabelMode mode = LabelMode::kEngrave;
  double height_mm = 2.5;         // cap height, 0.5..20
  double stroke_width_mm = 0.35;  // > 0, at most height / 4 (the cell gap stays open)
  double depth_mm = 0.4;          // engrave depth or emboss height, > 0, at most 5
  double voxel_mm = 0;            // meshing grid; 0: stroke width / 4; else in
                                  // [stroke width / 32, stroke width / 2]
  // Automatic placement: the wall must be at least height + stroke width + 2 margin high
  // between the upper and the lower outside curves, and the text at least one margin from
  // the arch's ends. 0..5 mm.
  double wall_margin_mm = 0.15;
  LabelPlacement placement = LabelPlacement::kAutomatic;
  // Explicit placement: the centre of the text (near the wall), the wall's outward normal and
  // the text's up direction (made perpendicular to the normal; not parallel to it).
  Vec3 position{};
  Vec3 normal{};
  Vec3 up{};
};

struct LabelGlyphPlacement {
  char character = 0;
  // Automatic: arc length of the glyph's centre along the wall's mid curve from the first
  // pick (mm). Explicit: the centre's offset along u from `position`.
  double arc_mm = 0;
  Vec3 surface_point{};       // the frame's origin (c = 0): where the ray met the splint
  Vec3 u{}, up{}, n{};        // reading direction, up, outward normal (unit)
  double wall_height_mm = 0;  // automatic: the outer wall's height there (else 0)
  uint64_t triangles = 0;     // of this glyph's mesh
};

struct LabelStats {
  char text[kLabelMaxCharacters + 1] = {};  // the text as written (upper case)
  uint32_t characters = 0;                  // characters of the text, spaces included
  uint32_t glyphs = 0;                      // meshed glyphs (spaces have none)
  uint64_t glyph_vertices = 0;
  uint64_t glyph_triangles = 0;    // after decimation (what the Boolean gets)
  uint64_t marched_triangles = 0;  // extracted before decimation (all samplings)
  uint32_t attempts = 0;           // samplings of the glyphs tried (1 + the retries)
  uint32_t glyph_resamplings = 0;  // single glyphs sampled again (invalid after decimation)
  double text_length_mm = 0;       // along the row, first stroke edge to last
  double stroke_length_mm = 0;     // total length of the strokes written (dots count 0)
  double voxel_mm = 0;             // what was used
  LabelGlyphPlacement placements[kLabelMaxCharacters];  // one per meshed glyph, in text order
  BooleanStats boolean;                                 // apply_label only
};

// ---------------------------------------------------------------------------------------------
// Operations.

// The glyph solids only (for previews and tests): one mesh of stats->glyphs disjoint closed,
// outward shells (a glyph such as ':' is several), vertices float32-exact, world coordinates.
// Reads `splint` (a closed mesh: the rays that find the wall are cast on it) and, for
// automatic placement, the base's lines (`upper`, `lower`: the i-th of each pair up, as
// build_splint_base takes them; ignored for explicit placement). `out` must be empty; it is
// bound to ctx.arena. Arena: while it runs, the splint's distance index
// (distance_index_bound), the decimated glyphs twice (24 bytes a vertex, 12 a triangle: about
// 600 triangles, 15 KB, a glyph at the defaults) and one glyph's extraction and decimation
// (marching_cubes_mesh_extra_bound and decimate_qem_bound of some 25,000 triangles: about 4 MB at
// the defaults); only the mesh stays.
// Progress: stage "label: glyphs", once per glyph.
// Errors (messages start with "label: "): kInvalidArgument (empty text, more than
// kLabelMaxCharacters characters, a character the font lacks: names it and its index, with
// at_index; an option out of range; fewer than 2 lines or lists that do not pair up; "the text
// does not fit on the outer wall: ..." when the wall is too low for the height, the arch too
// short for the text, or a glyph's ray misses the splint; glyphs that would touch);
// kInvalidMesh (the splint has no triangles; a distance-index error); kLimitExceeded (a glyph
// grid above 2^24 samples; a coordinate beyond float32); kUnsupported (no attempt gave a valid
// glyph mesh: the last reason); kInternal (a bug); kArenaExhausted; kCancelled. On an error the
// arena is back where it was and `out` is empty. `stats` may be null.
Status build_label_mesh(const Context& ctx, const Mesh& splint, Span<const Line> upper,
                        Span<const Line> lower, const LabelOptions& options, Mesh* out,
                        LabelStats* stats);

// The labelled splint: `out` = splint minus the glyphs (engrave) or splint union the glyphs
// (emboss), by mesh_boolean with default BooleanOptions (float32 output, the exact
// self-intersection check of the result, nudges). `splint` must be a valid solid (as
// design_splint returns it); it is not changed. `out` must be empty. Up to 4 attempts (see
// above): a Boolean that fails with kUnsupported or kInternal is tried again on the next
// sampling of the glyphs. Arena: the larger of build_label_mesh's need and the glyph mesh plus
// what mesh_boolean needs for the splint and the glyphs; only the result stays. Measured peak
// for "CASE-0001" with the defaults: 8 MB on the paper-scale base (2,612 triangles), 17 MB on
// its designed splint (10,380 triangles). Errors: those of build_label_mesh,
// and those of mesh_boolean prefixed "label: boolean (...)" (kArenaExhausted and kCancelled
// as they are). On an error the arena is back where it was and `out` is empty. `stats` may
// be null; on success it describes the attempt that succeeded.
Status apply_label(const Context& ctx, const Mesh& splint, Span<const Line> upper,
                   Span<const Line> lower, const LabelOptions& options, Mesh* out,
                   LabelStats* stats);

}  // namespace splintcore

#endif  // SPLINTCORE_LABEL_H
