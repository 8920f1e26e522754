// The case label (issue 8: "an engraved or embossed case label (patient/case id, built-in
// stroke font, no dependencies)"): glyph solids from the stroke font (stroke_font.cpp) as the
// zero level of a signed field (a thickened stroke extruded across the wall: the usual
// distance-field construction of swept strokes), meshed by the marching tetrahedra of
// volume.h, placed along the arch on the base's outer wall (the wall of Chen et al. 2016,
// "The Generation of the Initial Splint", between the upper and the lower outside curves),
// and joined to the splint by the exact Boolean of boolean.h ("The Boolean operation").
//
// Decisions:
// - The mid curve is the centripetal Catmull-Rom (spline.h) through the wall's mid points, as
//   the base's curves are; arc length by a 32-chord table per pick interval (as base.cpp).
//   The wall direction is the upper outside curve minus the lower outside curve at the same
//   parameter: interpolating the difference vectors themselves would put a zero knot interval
//   (a division by zero) wherever two consecutive walls are equal, e.g. on a straight arch.
// - Each glyph has its own planar frame at its arc position: a glyph is about 1.7 mm wide on
//   an arch of some 25 mm radius, so the wall departs from its plane by about 0.015 mm across
//   it, far below the 0.4 mm depth.
// - Glyph by glyph: extraction (vertices kept 1/16 of an edge from the samples, as the
//   blockout does), world coordinates rounded to float32, quadric decimation (Garland and
//   Heckbert 1997, remesh.h) within voxel / 24, rounded again, and moved down onto the
//   previous glyph: the peak is one glyph's extraction, not the whole text's. Decimation is
//   what makes the Boolean reliable here: the extractor's triangles (a tenth of a mm) cross
//   the base wall's nearly flat quads (dihedral angles of about 2e-4 rad at the quad
//   diagonals), so the intersection polyline inside one glyph triangle bends by some 10 nm,
//   a few float32 ulps, and rounding folds it (measured: about half of 8-glyph texts failed
//   without decimation, none of the 8 texts tried with it, some after one retry).
// - Each glyph is checked as the Boolean needs B (closed, oriented, nothing flat, no
//   self-intersection, exactly), since QEM decimation does not promise the last (measured:
//   about one glyph in 30 self-intersects); a failing glyph is sampled again with the next of
//   4 grid phases. A fragile Boolean (kUnsupported, kInternal) samples the whole text again
//   from the next phase. Deterministic: the same samplings in the same order everywhere.
// - Glyphs must not touch: mesh_boolean unites overlapping shells of B, but with one more
//   corefinement pass per group of shells that overlap; apart, the whole text is cut in one
//   pass. Every triangle lies in the box of its vertices, so each glyph lies in the box
//   of its vertices in its own frame; the boxes are tested pairwise by the separating-axis
//   theorem with a 1 um clearance. A conservative floating-point test, not an exact
//   predicate: it only refuses, it never decides the output's shape.
#include "splintcore/label.h"

#include <cmath>

#include "splintcore/distance.h"
#include "splintcore/remesh.h"
#include "splintcore/volume.h"

namespace splintcore {

namespace {

constexpr uint32_t kArcSamples = 32;      // chords per pick interval in the arc table
constexpr double kRayStart = 5.0;         // mm outside the wall's mid curve
constexpr double kRayLength = 10.0;       // mm
constexpr double kEngraveAbove = 1.0;     // mm the engraving solid reaches out of the wall
constexpr double kEmbossBelow = 0.3;      // mm the embossed solid reaches into the wall
constexpr double kGlyphClearance = 1e-3;  // mm between the boxes of two glyphs
constexpr double kEdgeMarginFraction = 1.0 / 16;
constexpr uint64_t kMaxGlyphSamples = uint64_t{1} << 24;
// Decimation keeps the glyphs within this fraction of a voxel of the extracted surface.
constexpr double kDecimateErrorFraction = 1.0 / 24;
// Attempts, each with the glyphs' grids shifted by this fraction of a voxel.
constexpr uint32_t kLabelAttempts = 4;
constexpr double kAttemptPhase[kLabelAttempts] = {0.0, 0.5, 0.25, 0.75};

Vec3 normalized(const Vec3& v) {
  const double len = length(v);
  return len > 0.0 ? Vec3{v.x / len, v.y / len, v.z / len} : Vec3{};
}

// ---------------------------------------------------------------------------------------------
// The wall's curves.

enum CurveKind { kMid, kUpperOutside, kLowerOutside, kInnerMid };

struct Arch {
  Span<const Line> upper, lower;
  size_t n = 0;
  const double* table = nullptr;  // (n - 1) x (kArcSamples + 1) cumulative chord lengths
  const double* start = nullptr;  // n arc lengths of the picks along the mid curve
  double total = 0;
};

Vec3 control(const Arch& arch, CurveKind kind, size_t i) {
  switch (kind) {
    case kMid: return (arch.upper[i].outside + arch.lower[i].outside) * 0.5;
    case kUpperOutside: return arch.upper[i].outside;
    case kLowerOutside: return arch.lower[i].outside;
    default: return (arch.upper[i].inner + arch.lower[i].inner) * 0.5;
  }
}

// Segment i (control point i to i + 1) with phantom ends reflected through the end points, as
// the base's curves (src/spline/base.cpp).
Vec3 curve_point(const Arch& arch, CurveKind kind, size_t i, double u) {
  const Vec3 p1 = control(arch, kind, i);
  const Vec3 p2 = control(arch, kind, i + 1);
  const Vec3 p0 = i > 0 ? control(arch, kind, i - 1) : p1 * 2.0 - p2;
  const Vec3 p3 = i + 2 < arch.n ? control(arch, kind, i + 2) : p2 * 2.0 - p1;
  return catmull_rom_point(p0, p1, p2, p3, u);
}

Status prepare_arch(Arena& arena, Span<const Line> upper, Span<const Line> lower, Arch* arch) {
  if (upper.size() != lower.size()) {
    return make_error(StatusCode::kInvalidArgument, "label: the upper list has ", upper.size(),
                      " lines and the lower ", lower.size(), "; they must pair up");
  }
  if (upper.size() < 2) {
    return make_error(StatusCode::kInvalidArgument, "label: automatic placement needs at least",
                      " 2 lines in each list, got ", upper.size());
  }
  arch->upper = upper;
  arch->lower = lower;
  arch->n = upper.size();
  for (size_t i = 0; i < arch->n; ++i) {
    if (!is_finite(upper[i].outside) || !is_finite(lower[i].outside) ||
        !is_finite(upper[i].inner) || !is_finite(lower[i].inner)) {
      return make_error(StatusCode::kInvalidArgument, "label: line ", i,
                        " has a coordinate that is not finite")
          .at_index(i);
    }
    // Consecutive points must differ on every curve the label interpolates.
    const CurveKind kinds[3] = {kMid, kUpperOutside, kLowerOutside};
    for (int k = 0; i + 1 < arch->n && k < 3; ++k) {
      if (control(*arch, kinds[k], i) == control(*arch, kinds[k], i + 1)) {
        return make_error(StatusCode::kInvalidArgument, "label: lines ", i, " and ", i + 1,
                          " have the same outside points; the wall's curve is undefined there")
            .at_index(i);
      }
    }
  }
  uint64_t count = 0;
  if (!checked_mul(arch->n - 1, kArcSamples + 1, &count) || count > SIZE_MAX / 8) {
    return make_error(StatusCode::kLimitExceeded, "label: ", arch->n, " lines are too many");
  }
  double* table = arena.allocate_array<double>(static_cast<size_t>(count));
  double* start = arena.allocate_array<double>(arch->n);
  if (table == nullptr || start == nullptr) return arena.exhausted_status();
  start[0] = 0.0;
  for (size_t i = 0; i + 1 < arch->n; ++i) {
    double* cumulative = table + i * (kArcSamples + 1);
    Vec3 previous = control(*arch, kMid, i);
    cumulative[0] = 0.0;
    for (uint32_t k = 1; k <= kArcSamples; ++k) {
      const Vec3 q = curve_point(*arch, kMid, i, static_cast<double>(k) / kArcSamples);
      cumulative[k] = cumulative[k - 1] + length(q - previous);
      previous = q;
    }
    start[i + 1] = start[i] + cumulative[kArcSamples];
  }
  arch->table = table;
  arch->start = start;
  arch->total = start[arch->n - 1];
  return Status::ok();
}

// The interval and the parameter in it at arc length s (0 <= s <= total).
void locate(const Arch& arch, double s, size_t* interval, double* u) {
  size_t i = 0;
  while (i + 2 < arch.n && arch.start[i + 1] < s) ++i;
  const double* cumulative = arch.table + i * (kArcSamples + 1);
  const double target = s - arch.start[i];
  uint32_t k = 0;
  while (k + 1 < kArcSamples && cumulative[k + 1] < target) ++k;
  const double span = cumulative[k + 1] - cumulative[k];
  double local = span > 0.0 ? (target - cumulative[k]) / span : 0.0;
  if (local < 0.0) local = 0.0;
  if (local > 1.0) local = 1.0;
  *interval = i;
  *u = (static_cast<double>(k) + local) / kArcSamples;
}

struct Frame {
  Vec3 point{};    // on the mid curve (automatic) or the row (explicit): the ray's aim
  Vec3 tangent{};  // increasing arc length (automatic)
  Vec3 u{}, up{}, n{};
  double wall = 0;
};

Status arch_frame(const Arch& arch, double s, Frame* f) {
  size_t i = 0;
  double u = 0;
  locate(arch, s, &i, &u);
  const double h = 1.0 / 256;
  const double u0 = u - h > 0.0 ? u - h : 0.0;
  const double u1 = u + h < 1.0 ? u + h : 1.0;
  f->point = curve_point(arch, kMid, i, u);
  f->tangent = normalized(curve_point(arch, kMid, i, u1) - curve_point(arch, kMid, i, u0));
  const Vec3 wall = curve_point(arch, kUpperOutside, i, u) - curve_point(arch, kLowerOutside, i, u);
  const Vec3 upv = wall - f->tangent * dot(wall, f->tangent);
  f->wall = length(upv);
  if (!(length_squared(f->tangent) > 0.0) || !(f->wall > 0.0)) {
    return make_error(StatusCode::kInvalidArgument, "label: the outer wall is degenerate at ", s,
                      " mm along the arch (pick interval ", i, ")")
        .at_index(i);
  }
  f->up = upv * (1.0 / f->wall);
  f->n = normalized(cross(f->tangent, f->up));
  const Vec3 inner = control(arch, kInnerMid, i) * (1.0 - u) + control(arch, kInnerMid, i + 1) * u;
  if (dot(f->n, f->point - inner) < 0.0) f->n = -f->n;
  f->u = cross(f->up, f->n);
  return Status::ok();
}

// ---------------------------------------------------------------------------------------------
// The glyphs.

struct Segment2 {
  double ax, ay, bx, by;
};

struct GlyphJob {
  Vec3 origin{}, u{}, up{}, n{};  // the frame (origin: the wall point)
  uint32_t first_segment = 0, segment_count = 0;
  VolumeGrid grid;  // local coordinates (a, b, c)
  Aabb local_box;   // of the mesh's vertices (pass 1)
  uint64_t vertices = 0, triangles = 0;
};

struct FieldSource {
  const Segment2* segments = nullptr;
  uint32_t count = 0;
  VolumeGrid grid;
  double half_width = 0, c_lo = 0, c_hi = 0;
};

Status fill_glyph(void* user, uint32_t z_begin, uint32_t z_end, Span<float> out) {
  const FieldSource& f = *static_cast<const FieldSource*>(user);
  const VolumeGrid& g = f.grid;
  size_t at = 0;
  for (uint32_t z = z_begin; z < z_end; ++z) {
    const double c = g.origin.z + g.spacing.z * z;
    const double slab = (c - f.c_hi) > (f.c_lo - c) ? (c - f.c_hi) : (f.c_lo - c);
    for (uint32_t y = 0; y < g.ny; ++y) {
      const double b = g.origin.y + g.spacing.y * y;
      for (uint32_t x = 0; x < g.nx; ++x) {
        const double a = g.origin.x + g.spacing.x * x;
        double best = HUGE_VAL;
        for (uint32_t s = 0; s < f.count; ++s) {
          const Segment2& seg = f.segments[s];
          const double dx = seg.bx - seg.ax, dy = seg.by - seg.ay;
          const double px = a - seg.ax, py = b - seg.ay;
          const double dd = dx * dx + dy * dy;
          double t = dd > 0.0 ? (px * dx + py * dy) / dd : 0.0;
          t = t < 0.0 ? 0.0 : (t > 1.0 ? 1.0 : t);
          const double ex = px - dx * t, ey = py - dy * t;
          const double d2 = ex * ex + ey * ey;
          if (d2 < best) best = d2;
        }
        const double stroke = std::sqrt(best) - f.half_width;
        out[at++] = static_cast<float>(stroke > slab ? stroke : slab);
      }
    }
  }
  return Status::ok();
}

// Separating-axis test of the glyphs' boxes (in their frames), with `clearance`.
bool boxes_apart(const GlyphJob& a, const GlyphJob& b, double clearance) {
  const Vec3 ax[3] = {a.u, a.up, a.n};
  const Vec3 bx[3] = {b.u, b.up, b.n};
  const Vec3 ac = a.local_box.center(), bc = b.local_box.center();
  const Vec3 ae = a.local_box.extent() * 0.5, be = b.local_box.extent() * 0.5;
  const Vec3 ca = a.origin + a.u * ac.x + a.up * ac.y + a.n * ac.z;
  const Vec3 cb = b.origin + b.u * bc.x + b.up * bc.y + b.n * bc.z;
  const Vec3 d = cb - ca;
  Vec3 axes[15];
  int count = 0;
  for (int i = 0; i < 3; ++i) axes[count++] = ax[i];
  for (int i = 0; i < 3; ++i) axes[count++] = bx[i];
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      const Vec3 c = cross(ax[i], bx[j]);
      if (length_squared(c) > 1e-12) axes[count++] = normalized(c);
    }
  }
  for (int k = 0; k < count; ++k) {
    const Vec3& l = axes[k];
    double ra = 0, rb = 0;
    for (int i = 0; i < 3; ++i) {
      ra += ae[i] * std::fabs(dot(ax[i], l));
      rb += be[i] * std::fabs(dot(bx[i], l));
    }
    if (std::fabs(dot(d, l)) > ra + rb + clearance) return true;
  }
  return false;
}

Status char_error(const char* text, size_t index) {
  const unsigned char c = static_cast<unsigned char>(text[index]);
  Status e = Status::error(StatusCode::kInvalidArgument, "label: character ");
  if (c >= 0x20 && c < 0x7f) {
    const char quoted[4] = {'\'', static_cast<char>(c), '\'', '\0'};
    e.append(quoted);
  } else {
    e.append("byte ").append_u64(c);
  }
  e.append(" at index ")
      .append_u64(index)
      .append(" is not in the label font (it has A-Z, a-z, 0-9, space and - _ . / # + ( ) :)");
  e.at_index(index);
  return e;
}

bool in_range(double v, double lo, double hi) { return is_finite(v) && v >= lo && v <= hi; }

Status check_options(const LabelOptions& o, double* voxel) {
  if (!in_range(o.height_mm, 0.5, 20.0)) {
    return make_error(StatusCode::kInvalidArgument, "label: height ", o.height_mm,
                      " mm is out of range (0.5 to 20 mm)");
  }
  if (!(is_finite(o.stroke_width_mm) && o.stroke_width_mm > 0.0 &&
        o.stroke_width_mm <= o.height_mm / 4)) {
    return make_error(
        StatusCode::kInvalidArgument, "label: stroke width ", o.stroke_width_mm,
        " mm is out of range (above 0, at most a quarter of the height: ", o.height_mm / 4, " mm)");
  }
  if (!(is_finite(o.depth_mm) && o.depth_mm > 0.0 && o.depth_mm <= 5.0)) {
    return make_error(StatusCode::kInvalidArgument, "label: depth ", o.depth_mm,
                      " mm is out of range (above 0, at most 5 mm)");
  }
  *voxel = o.voxel_mm == 0.0 ? o.stroke_width_mm / 4 : o.voxel_mm;
  if (!in_range(*voxel, o.stroke_width_mm / 32, o.stroke_width_mm / 2)) {
    return make_error(StatusCode::kInvalidArgument, "label: voxel ", o.voxel_mm,
                      " mm is out of range (0 for a quarter of the stroke width, or ",
                      o.stroke_width_mm / 32, " to ", o.stroke_width_mm / 2, " mm)");
  }
  if (!in_range(o.wall_margin_mm, 0.0, 5.0)) {
    return make_error(StatusCode::kInvalidArgument, "label: wall margin ", o.wall_margin_mm,
                      " mm is out of range (0 to 5 mm)");
  }
  if (o.mode != LabelMode::kEngrave && o.mode != LabelMode::kEmboss) {
    return Status::error(StatusCode::kInvalidArgument, "label: unknown mode");
  }
  if (o.placement != LabelPlacement::kAutomatic && o.placement != LabelPlacement::kExplicit) {
    return Status::error(StatusCode::kInvalidArgument, "label: unknown placement");
  }
  return Status::ok();
}

// The final check of the joined glyphs: what the Boolean needs of B, checked here so that a
// failure can try another phase: a closed, oriented solid without flat triangles and without
// self-intersections (exact).
Status check_glyph_mesh(const Context& ctx, const Mesh& mesh) {
  double volume = 0;
  Status s = check_closed_oriented(ctx, mesh, &volume);
  if (!s.is_ok()) {
    if (s.code() == StatusCode::kArenaExhausted) return s;
    return make_error(StatusCode::kUnsupported,
                      "label: the glyph mesh is not a valid solid after rounding to float32 (",
                      s.message(), ")");
  }
  SelfIntersectionReport sir;
  SPLINTCORE_RETURN_IF_ERROR(find_self_intersections(ctx, mesh, 1, &sir));
  if (sir.self_intersecting()) {
    return make_error(StatusCode::kUnsupported, "label: the glyph mesh self-intersects ",
                      "(triangles ", sir.first_a, " and ", sir.first_b, ")");
  }
  return Status::ok();
}

// The state of one build_glyphs call (below), with one method per stage, run in this order:
// the text, its place, the glyphs' frames and grids, their meshes, the joined mesh.
struct GlyphBuilder {
  GlyphBuilder(const Context& c, const LabelOptions& o, uint32_t a, LabelStats* s)
      : ctx(c), arena(*c.arena), options(o), attempt(a), st(s) {}

  const Context& ctx;
  Arena& arena;
  const LabelOptions& options;
  uint32_t attempt;
  LabelStats* st;
  double voxel = 0;

  // The text (read_text).
  size_t length_chars = 0;
  StrokeGlyph glyphs[kLabelMaxCharacters];
  uint32_t cell_left[kLabelMaxCharacters] = {};  // grid units from the text's left edge
  double scale = 0;                              // mm per grid unit
  double half_width = 0;                         // mm, half a stroke
  double text_units = 0;                         // the text's width in grid units

  // Its place (place_text): the splint's index (for the rays) and the arch or the fixed frame.
  DistanceIndex index;
  Arch arch;
  double sign = 1.0;
  Frame fixed;

  // The glyphs (lay_out_glyphs, mesh_glyphs).
  double c_lo = 0, c_hi = 0;
  GlyphJob* jobs = nullptr;
  Segment2* segments = nullptr;
  uint32_t segment_count = 0, job_count = 0;
  double stroke_length = 0;
  Mesh* blocks = nullptr;
  uint64_t total_vertices = 0, total_triangles = 0;

  static constexpr uint32_t kMaxSegments = kLabelMaxCharacters * kStrokeGlyphMaxPoints;

  Status read_text() {
    const char* text = options.text != nullptr ? options.text : "";
    while (length_chars <= kLabelMaxCharacters && text[length_chars] != '\0') ++length_chars;
    if (length_chars == 0) {
      return Status::error(StatusCode::kInvalidArgument, "label: the text is empty");
    }
    if (length_chars > kLabelMaxCharacters) {
      return make_error(StatusCode::kInvalidArgument, "label: the text is longer than ",
                        kLabelMaxCharacters, " characters");
    }
    uint32_t cursor = 0, meshed = 0;
    for (size_t i = 0; i < length_chars; ++i) {
      if (!stroke_font_glyph(text[i], &glyphs[i])) return char_error(text, i);
      st->text[i] = glyphs[i].character;
      cell_left[i] = cursor;
      cursor += glyphs[i].advance;
      if (glyphs[i].stroke_count > 0) ++meshed;
    }
    st->characters = static_cast<uint32_t>(length_chars);
    if (meshed == 0) {
      return Status::error(StatusCode::kInvalidArgument, "label: the text has nothing to write");
    }
    scale = options.height_mm / kStrokeFontHeight;
    half_width = options.stroke_width_mm / 2;
    text_units = static_cast<double>(cursor - kStrokeFontGap);
    st->text_length_mm = text_units * scale + options.stroke_width_mm;
    return Status::ok();
  }

  Status place_text(const Mesh& splint, Span<const Line> upper, Span<const Line> lower) {
    SPLINTCORE_RETURN_IF_ERROR(build_distance_index(ctx, splint, DistanceIndexOptions{}, &index));
    if (options.placement == LabelPlacement::kAutomatic) {
      SPLINTCORE_RETURN_IF_ERROR(prepare_arch(arena, upper, lower, &arch));
      const double half_text = st->text_length_mm / 2 + options.wall_margin_mm;
      if (!(arch.total / 2 >= half_text)) {
        return make_error(StatusCode::kInvalidArgument,
                          "label: the text does not fit on the outer wall: it is ",
                          st->text_length_mm, " mm long (", options.wall_margin_mm,
                          " mm margin each end), the wall's mid curve ", arch.total, " mm");
      }
      Frame middle;
      SPLINTCORE_RETURN_IF_ERROR(arch_frame(arch, arch.total / 2, &middle));
      sign = dot(middle.u, middle.tangent) > 0.0 ? 1.0 : -1.0;
      return Status::ok();
    }
    fixed.n = normalized(options.normal);
    const Vec3 upv = options.up - fixed.n * dot(options.up, fixed.n);
    if (!is_finite(options.position) || !is_finite(options.normal) || !is_finite(options.up) ||
        !(length_squared(fixed.n) > 0.0) || !(length(upv) > 1e-9 * length(options.up))) {
      return Status::error(StatusCode::kInvalidArgument,
                           "label: explicit placement needs a finite position, a nonzero "
                           "normal and an up vector not parallel to it");
    }
    fixed.up = normalized(upv);
    fixed.u = cross(fixed.up, fixed.n);
    return Status::ok();
  }

  // Frames and fields, glyph by glyph.
  Status lay_out_glyphs() {
    c_lo = options.mode == LabelMode::kEngrave ? -options.depth_mm : -kEmbossBelow;
    c_hi = options.mode == LabelMode::kEngrave ? kEngraveAbove : options.depth_mm;
    // Jobs and segments are temporaries in the arena (below the mesh, which moves down).
    jobs = arena.allocate_array<GlyphJob>(kLabelMaxCharacters);
    segments = arena.allocate_array<Segment2>(kMaxSegments);
    if (jobs == nullptr || segments == nullptr) return arena.exhausted_status();
    for (uint32_t k = 0; k < kLabelMaxCharacters; ++k) jobs[k] = GlyphJob{};
    for (size_t i = 0; i < length_chars; ++i) {
      if (glyphs[i].stroke_count == 0) continue;
      GlyphJob& job = jobs[job_count];
      SPLINTCORE_RETURN_IF_ERROR(place_glyph(i, &job));
      const Aabb strokes = add_strokes(glyphs[i], &job);
      SPLINTCORE_RETURN_IF_ERROR(size_grid(i, strokes, &job));
      ++job_count;
    }
    st->glyphs = job_count;
    st->stroke_length_mm = stroke_length;
    return Status::ok();
  }

  // Character i's frame at its place along the text, and the wall point its ray meets.
  Status place_glyph(size_t i, GlyphJob* job) {
    const StrokeGlyph& g = glyphs[i];
    LabelGlyphPlacement& place = st->placements[job_count];
    place.character = g.character;
    const double offset =
        (static_cast<double>(cell_left[i]) + 0.5 * g.width - 0.5 * text_units) * scale;
    Frame f;
    if (options.placement == LabelPlacement::kAutomatic) {
      const double needed_wall =
          options.height_mm + options.stroke_width_mm + 2 * options.wall_margin_mm;
      const double s = arch.total / 2 + sign * offset;
      SPLINTCORE_RETURN_IF_ERROR(arch_frame(arch, s, &f));
      place.arc_mm = s;
      place.wall_height_mm = f.wall;
      if (!(dot(f.u, f.tangent) * sign > 0.0)) {
        return make_error(StatusCode::kInvalidArgument,
                          "label: the outer wall turns over under character ", i)
            .at_index(i);
      }
      if (!(f.wall >= needed_wall)) {
        return make_error(StatusCode::kInvalidArgument,
                          "label: the text does not fit on the outer wall: at character ", i,
                          " the wall is ", f.wall, " mm high; ", options.height_mm,
                          " mm letters need ", needed_wall,
                          " mm (height + stroke width + 2 x margin)")
            .at_index(i);
      }
    } else {
      f = fixed;
      f.point = options.position + fixed.u * offset;
      place.arc_mm = offset;
    }
    RayHit hit;
    if (!ray_intersect(index, f.point + f.n * kRayStart, -f.n, kRayLength, &hit)) {
      return make_error(StatusCode::kInvalidArgument,
                        "label: the text does not fit on the outer wall: the ray for character ", i,
                        " meets no part of the splint within ", kRayStart, " mm of its centre")
          .at_index(i);
    }
    job->origin = f.point + f.n * (kRayStart - hit.t);
    job->u = f.u;
    job->up = f.up;
    job->n = f.n;
    place.surface_point = job->origin;
    place.u = f.u;
    place.up = f.up;
    place.n = f.n;
    return Status::ok();
  }

  // Strokes in the frame (a, b), the glyph's cell centred on the origin; returns their box.
  Aabb add_strokes(const StrokeGlyph& g, GlyphJob* job) {
    job->first_segment = segment_count;
    Aabb strokes;
    uint32_t first = 0;
    for (uint32_t s = 0; s < g.stroke_count; ++s) {
      const uint32_t end = g.stroke_end[s];
      // A stroke of one point is a dot: one segment of zero length.
      const uint32_t last = end - first > 1 ? end - 1 : end;
      for (uint32_t k = first; k < last; ++k) {
        const uint32_t next = end - first > 1 ? k + 1 : k;
        Segment2 seg;
        seg.ax = (g.points[k].x - 0.5 * g.width) * scale;
        seg.ay = (g.points[k].y - 0.5 * kStrokeFontHeight) * scale;
        seg.bx = (g.points[next].x - 0.5 * g.width) * scale;
        seg.by = (g.points[next].y - 0.5 * kStrokeFontHeight) * scale;
        strokes.add(Vec3{seg.ax, seg.ay, 0});
        strokes.add(Vec3{seg.bx, seg.by, 0});
        const double dx = seg.bx - seg.ax, dy = seg.by - seg.ay;
        stroke_length += std::sqrt(dx * dx + dy * dy);
        SPLINTCORE_ASSERT(segment_count < kMaxSegments);
        segments[segment_count++] = seg;
      }
      first = end;
    }
    job->segment_count = segment_count - job->first_segment;
    return strokes;
  }

  // Character i's sampling grid: the strokes' box with a stroke and two voxels around it.
  Status size_grid(size_t i, const Aabb& strokes, GlyphJob* job) const {
    const double pad = half_width + 2 * voxel;
    // Unshifted; each sampling shifts it by a phase (mesh_glyph).
    job->grid.origin = Vec3{strokes.lo.x - pad, strokes.lo.y - pad, c_lo - 2 * voxel};
    job->grid.spacing = Vec3{voxel, voxel, voxel};
    const double extent[3] = {strokes.hi.x - strokes.lo.x + 2 * pad,
                              strokes.hi.y - strokes.lo.y + 2 * pad, c_hi - c_lo + 4 * voxel};
    uint64_t samples = 1;
    uint32_t counts[3];
    for (int a = 0; a < 3; ++a) {
      const double cells = std::ceil(extent[a] / voxel);
      if (!(cells < 65536.0)) {
        return make_error(StatusCode::kLimitExceeded, "label: the voxel ", voxel,
                          " mm is too fine for character ", i);
      }
      counts[a] = static_cast<uint32_t>(cells) + 1;
      samples *= counts[a];
    }
    if (samples > kMaxGlyphSamples) {
      return make_error(StatusCode::kLimitExceeded, "label: character ", i, " needs ", samples,
                        " samples at voxel ", voxel, " mm; at most ", kMaxGlyphSamples)
          .at_index(i);
    }
    job->grid.nx = counts[0];
    job->grid.ny = counts[1];
    job->grid.nz = counts[2];
    return Status::ok();
  }

  // Glyph by glyph: extract (local frame), map to world and round, decimate, round again;
  // each glyph's mesh is moved down onto the previous one's (blocks), the temporaries go.
  Status mesh_glyphs() {
    MarchingCubesOptions mco;
    mco.edge_margin = kEdgeMarginFraction;
    DecimateOptions dopt;
    dopt.max_error = voxel * kDecimateErrorFraction;
    blocks = arena.allocate_array<Mesh>(job_count);
    if (blocks == nullptr) return arena.exhausted_status();
    for (uint32_t k = 0; k < job_count; ++k) {
      SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "label: glyphs", k, job_count));
      SPLINTCORE_RETURN_IF_ERROR(mesh_glyph(k, mco, dopt));
    }
    if (total_vertices >= (uint64_t{1} << 31) || total_triangles >= (uint64_t{1} << 31)) {
      return make_error(StatusCode::kLimitExceeded, "label: the glyphs have ", total_triangles,
                        " triangles; at most 2^31");
    }
    return Status::ok();
  }

  // Glyph k into blocks[k], at the arena's top at entry.
  Status mesh_glyph(uint32_t k, const MarchingCubesOptions& mco, const DecimateOptions& dopt) {
    GlyphJob& job = jobs[k];
    FieldSource fs;
    fs.segments = segments + job.first_segment;
    fs.count = job.segment_count;
    fs.grid = job.grid;
    fs.half_width = half_width;
    fs.c_lo = c_lo;
    fs.c_hi = c_hi;
    const Arena::Marker glyph_start = arena.mark();
    // A glyph whose decimated mesh is not a valid solid (QEM does not promise that it does not
    // self-intersect) is sampled again with the next phase; the attempt's phase comes first.
    Mesh small;
    Status s;
    for (uint32_t sampling = 0; sampling < kLabelAttempts; ++sampling) {
      arena.rewind(glyph_start);
      if (sampling > 0) ++st->glyph_resamplings;
      const double phase = kAttemptPhase[(attempt + sampling) % kLabelAttempts] * voxel;
      fs.grid.origin = job.grid.origin - Vec3{phase, phase * 0.375, phase * 0.6875};
      SPLINTCORE_RETURN_IF_ERROR(sample_glyph(k, &fs, mco, dopt, &small, &s));
      if (s.is_ok()) break;
    }
    if (!s.is_ok()) return s;
    move_mesh_down(arena, glyph_start, small, &blocks[k]);  // decimate_qem: triangles first
    job.vertices = blocks[k].vertices.size();
    job.triangles = blocks[k].triangles.size();
    st->placements[k].triangles = job.triangles;
    total_vertices += job.vertices;
    total_triangles += job.triangles;
    if (job.triangles == 0) {
      return make_error(StatusCode::kInternal, "label: glyph ", k, " has an empty mesh");
    }
    return Status::ok();
  }

  // One sampling of glyph k on fs's grid: the decimated mesh in *small, its box in the job,
  // and in *verdict why it is no valid solid (ok when it is one). An error returned ends the
  // label (memory, a cancel, float32 range).
  Status sample_glyph(uint32_t k, FieldSource* fs, const MarchingCubesOptions& mco,
                      const DecimateOptions& dopt, Mesh* small, Status* verdict) {
    GlyphJob& job = jobs[k];
    const char character[2] = {st->placements[k].character, '\0'};
    Mesh raw(&arena);
    SPLINTCORE_RETURN_IF_ERROR(
        marching_cubes_mesh(ctx, fs->grid, LayerSource{fill_glyph, fs}, mco, &raw));
    st->marched_triangles += raw.triangles.size();
    for (Vec3& p : raw.vertices) {
      p = job.origin + job.u * p.x + job.up * p.y + job.n * p.z;
      if (!round_to_float32(&p)) {
        return Status::error(StatusCode::kLimitExceeded,
                             "label: a glyph vertex is beyond float32 range");
      }
    }
    *small = Mesh(&arena);
    Status& s = *verdict;
    s = decimate_qem(ctx, raw, dopt, small);
    if (s.code() == StatusCode::kArenaExhausted || s.code() == StatusCode::kCancelled) return s;
    if (!s.is_ok()) {
      s = make_error(StatusCode::kUnsupported, "label: glyph ", k, " ('", character,
                     "'): decimation: ", s.message());
      return Status::ok();
    }
    job.local_box = Aabb();
    for (Vec3& p : small->vertices) {
      if (!round_to_float32(&p)) {
        return Status::error(StatusCode::kLimitExceeded,
                             "label: a glyph vertex is beyond float32 range");
      }
      const Vec3 d = p - job.origin;
      job.local_box.add(Vec3{dot(d, job.u), dot(d, job.up), dot(d, job.n)});
    }
    double volume = 0;
    s = check_closed_oriented(ctx, *small, &volume);
    if (s.code() == StatusCode::kArenaExhausted) return s;
    if (!s.is_ok()) {
      s = make_error(StatusCode::kUnsupported, "label: glyph ", k, " ('", character,
                     "') is not a valid solid after rounding to float32: ", s.message());
      return Status::ok();
    }
    SelfIntersectionReport sir;
    SPLINTCORE_RETURN_IF_ERROR(find_self_intersections(ctx, *small, 1, &sir));
    if (sir.self_intersecting()) {
      s = make_error(StatusCode::kUnsupported, "label: glyph ", k, " ('", character,
                     "') self-intersects after decimation (triangles ", sir.first_a, " and ",
                     sir.first_b, ")");
    }
    return Status::ok();
  }

  Status check_glyphs_apart() const {
    for (uint32_t a = 0; a < job_count; ++a) {
      for (uint32_t b = a + 1; b < job_count; ++b) {
        if (!boxes_apart(jobs[a], jobs[b], kGlyphClearance)) {
          const char ca[2] = {st->placements[a].character, '\0'};
          const char cb[2] = {st->placements[b].character, '\0'};
          return make_error(StatusCode::kInvalidArgument, "label: glyphs ", a, " ('", ca, "') and ",
                            b, " ('", cb,
                            "') would touch; the wall bends too sharply for this text: use a "
                            "smaller height, stroke width or depth")
              .at_index(a);
        }
      }
    }
    return Status::ok();
  }

  // One mesh (vertices first), above the blocks; the caller moves it down over them.
  Status join_glyphs(Mesh* mesh) {
    Vec3* vertices = arena.allocate_array<Vec3>(static_cast<size_t>(total_vertices));
    Triangle* triangles =
        vertices == nullptr ? nullptr
                            : arena.allocate_array<Triangle>(static_cast<size_t>(total_triangles));
    if (vertices == nullptr || triangles == nullptr) return arena.exhausted_status();
    uint64_t v_at = 0, t_at = 0;
    for (uint32_t k = 0; k < job_count; ++k) {
      const uint32_t base = static_cast<uint32_t>(v_at);
      for (const Vec3& p : blocks[k].vertices) vertices[v_at++] = p;
      for (const Triangle& t : blocks[k].triangles) {
        triangles[t_at++] = Triangle{{t.v[0] + base, t.v[1] + base, t.v[2] + base}};
      }
    }
    mesh->bind(&arena);
    mesh->vertices.adopt(vertices, static_cast<size_t>(total_vertices),
                         static_cast<size_t>(total_vertices));
    mesh->triangles.adopt(triangles, static_cast<size_t>(total_triangles),
                          static_cast<size_t>(total_triangles));
    st->glyph_vertices = total_vertices;
    st->glyph_triangles = total_triangles;
    return Status::ok();
  }
};

// Everything of build_label_mesh except the clean-up on errors: the mesh ends above the
// distance index, its vertices allocated before its triangles.
Status build_glyphs(const Context& ctx, const Mesh& splint, Span<const Line> upper,
                    Span<const Line> lower, const LabelOptions& options, uint32_t attempt,
                    Mesh* mesh, LabelStats* st) {
  GlyphBuilder b(ctx, options, attempt, st);
  SPLINTCORE_RETURN_IF_ERROR(check_options(options, &b.voxel));
  st->voxel_mm = b.voxel;
  SPLINTCORE_RETURN_IF_ERROR(b.read_text());
  if (splint.triangles.empty()) {
    return Status::error(StatusCode::kInvalidMesh, "label: the splint has no triangles");
  }
  SPLINTCORE_RETURN_IF_ERROR(b.place_text(splint, upper, lower));
  SPLINTCORE_RETURN_IF_ERROR(b.lay_out_glyphs());
  SPLINTCORE_RETURN_IF_ERROR(b.mesh_glyphs());
  SPLINTCORE_RETURN_IF_ERROR(b.check_glyphs_apart());
  SPLINTCORE_RETURN_IF_ERROR(b.join_glyphs(mesh));
  return check_glyph_mesh(ctx, *mesh);
}

// One attempt of build_label_mesh: only the mesh stays (moved down to the arena's top at
// entry); on an error the arena is back there and `out` is empty.
Status build_attempt(const Context& ctx, const Mesh& splint, Span<const Line> upper,
                     Span<const Line> lower, const LabelOptions& options, uint32_t attempt,
                     Mesh* out, LabelStats* st) {
  Arena& arena = *ctx.arena;
  ArenaScope scope(arena);
  *st = LabelStats{};
  st->attempts = attempt + 1;
  Mesh mesh;
  const Status s = build_glyphs(ctx, splint, upper, lower, options, attempt, &mesh, st);
  if (!s.is_ok()) {
    out->bind(&arena);
    return s;
  }
  move_mesh_down(arena, scope.start(), mesh, out, /*vertices_first=*/true);
  scope.commit();
  return Status::ok();
}

}  // namespace

const char* label_mode_name(LabelMode mode) {
  return mode == LabelMode::kEngrave ? "engrave" : "emboss";
}

Status build_label_mesh(const Context& ctx, const Mesh& splint, Span<const Line> upper,
                        Span<const Line> lower, const LabelOptions& options, Mesh* out,
                        LabelStats* stats) {
  SPLINTCORE_ASSERT(ctx.arena != nullptr && out != nullptr);
  if (!out->vertices.empty() || !out->triangles.empty()) {
    return Status::error(StatusCode::kInvalidArgument, "label: the output mesh must be empty");
  }
  LabelStats local;
  LabelStats* st = stats != nullptr ? stats : &local;
  Status s;
  for (uint32_t attempt = 0; attempt < kLabelAttempts; ++attempt) {
    s = build_attempt(ctx, splint, upper, lower, options, attempt, out, st);
    if (s.code() != StatusCode::kUnsupported) break;
  }
  return s;
}

Status apply_label(const Context& ctx, const Mesh& splint, Span<const Line> upper,
                   Span<const Line> lower, const LabelOptions& options, Mesh* out,
                   LabelStats* stats) {
  SPLINTCORE_ASSERT(ctx.arena != nullptr && out != nullptr);
  if (!out->vertices.empty() || !out->triangles.empty()) {
    return Status::error(StatusCode::kInvalidArgument, "label: the output mesh must be empty");
  }
  LabelStats local;
  LabelStats* st = stats != nullptr ? stats : &local;
  Arena& arena = *ctx.arena;
  ArenaScope scope(arena);  // on an error the arena is as it was
  BooleanOptions bo;
  bo.op = options.mode == LabelMode::kEngrave ? BooleanOp::kDifference : BooleanOp::kUnion;
  Status s;
  for (uint32_t attempt = 0; attempt < kLabelAttempts; ++attempt) {
    arena.rewind(scope.start());
    Mesh glyphs;
    s = build_attempt(ctx, splint, upper, lower, options, attempt, &glyphs, st);
    if (s.code() == StatusCode::kUnsupported) continue;
    if (!s.is_ok()) break;
    Mesh result;
    s = mesh_boolean(ctx, splint, glyphs, bo, &result, &st->boolean);
    if (s.is_ok()) {
      // The result down over the glyphs (mesh_boolean allocates its triangles first).
      move_mesh_down(arena, scope.start(), result, out);
      scope.commit();
      return Status::ok();
    }
    if (s.code() == StatusCode::kArenaExhausted || s.code() == StatusCode::kCancelled) break;
    // A contact that float32 rounding makes fragile (small glyph triangles against the nearly
    // flat quads of the base's wall): the next attempt samples the glyphs elsewhere.
    if (s.code() != StatusCode::kUnsupported && s.code() != StatusCode::kInternal) {
      s = make_error(s.code(), "label: boolean (splint ",
                     options.mode == LabelMode::kEngrave ? "minus" : "plus",
                     " glyphs): ", s.message());
      break;
    }
    s = make_error(s.code(), "label: boolean (splint ",
                   options.mode == LabelMode::kEngrave ? "minus" : "plus", " glyphs, ",
                   kLabelAttempts, " samplings of the glyphs): ", s.message());
  }
  out->bind(&arena);
  return s;
}

}  // namespace splintcore
