// The insertion direction by survey (outline.h, OutlineOptions::survey): within 15 degrees of
// the occlusal normal, the direction along which the teeth leave the least undercut in the
// wafer. The undercut along d, per jaw, is what the wafer would fill above an overhang seen
// from the wafer's side: on columns of kSurveyCellMm over the outline's footprint, a ray
// along d (the maxilla's; the mandible's along -d) from the wafer's far face: past the first
// entry into the jaw, every stretch outside it up to the jaw's face of the wafer is undercut
// (the splint there would have to pass through the tooth to come off). Rays only: no sampling
// in depth. The search is a fixed grid over the cone's tangent plane, refined twice around
// the best, ties to the first: deterministic.
#include <cmath>

#include "core/fminmax.h"
#include "outline_internal.h"

namespace splintcore {
namespace outline_detail {

namespace {

constexpr double kSurveyCellMm = 0.5;
constexpr int kMaxHits = 64;  // per ray; deeper stacks of surfaces are not counted further

// A column of the footprint: its place in the plane (e1, e2) and the wafer's faces there.
struct Column {
  double x = 0, y = 0;
  double top = 0, bottom = 0;  // heights along n
};

// Jaw j's triangles that meet the slab [lo, hi] along n, with an index: every ray between the
// wafer's faces meets only these.
struct SurveyJaw {
  Mesh band;
  DistanceIndex index;
};

Status survey_jaw(const Context& ctx, const Mesh& m, const Vec3& n, double lo, double hi,
                  SurveyJaw* out) {
  Arena& arena = *ctx.arena;
  size_t kept = 0;
  auto keeps = [&](const Triangle& t) {
    const double a = dot(m.vertices[t.v[0]], n), b = dot(m.vertices[t.v[1]], n),
                 c = dot(m.vertices[t.v[2]], n);
    return max3_of(a, b, c) >= lo && min3_of(a, b, c) <= hi;
  };
  for (const Triangle& t : m.triangles) {
    if (keeps(t)) ++kept;
  }
  Triangle* tris = arena.allocate_array<Triangle>(kept > 0 ? kept : 1);
  if (tris == nullptr) return arena.exhausted_status();
  size_t k = 0;
  for (const Triangle& t : m.triangles) {
    if (keeps(t)) tris[k++] = t;
  }
  out->band = mesh_view(m.vertices.span(), Span<const Triangle>(tris, kept));
  return build_distance_index(ctx, out->band, DistanceIndexOptions{}, &out->index);
}

// Undercut length along one ray from `origin` along `d` over [0, t_end].
double ray_undercut(const SurveyJaw& jaw, const Vec3& origin, const Vec3& d, double t_end) {
  double t = 0, entered_at = -1, outside_since = -1, undercut = 0;
  bool inside = false;
  for (int hit = 0; hit < kMaxHits; ++hit) {
    RayHit h;
    if (!ray_intersect(jaw.index, origin + d * t, d, t_end - t, &h)) break;
    const double at = t + h.t;
    const Triangle& tr = jaw.band.triangles[h.triangle];
    const Vec3& a = jaw.band.vertices[tr.v[0]];
    const Vec3 normal = cross(jaw.band.vertices[tr.v[1]] - a, jaw.band.vertices[tr.v[2]] - a);
    const bool entering = dot(normal, d) < 0;
    if (entering && !inside) {
      if (entered_at < 0) entered_at = at;
      if (outside_since >= 0) undercut += at - outside_since;
      inside = true;
    } else if (!entering && inside) {
      outside_since = at;
      inside = false;
    }
    t = at + 1e-7;
    if (t >= t_end) break;
  }
  if (!inside && outside_since >= 0) undercut += t_end - outside_since;
  return undercut;
}

// The footprint's columns: lattice points of the plane inside the quads between consecutive
// picks' lines (the first quad that holds a point takes it), the faces interpolated.
Status footprint(Arena& arena, const Frame& f, Span<const Pick> upper, Span<const Pick> lower,
                 ArenaArray<Column>* out) {
  auto px = [&](const Vec3& p) { return dot(p, f.e1); };
  auto py = [&](const Vec3& p) { return dot(p, f.e2); };
  auto corner = [&](size_t i, bool outside) {
    const Pick& p = upper[i];
    return outside ? p.position + p.direction * p.outside_length
                   : p.position - p.direction * p.inner_length;
  };
  double x_lo = HUGE_VAL, x_hi = -HUGE_VAL, y_lo = HUGE_VAL, y_hi = -HUGE_VAL, cx = 0, cy = 0;
  for (size_t i = 0; i < upper.size(); ++i) {
    for (int s = 0; s < 2; ++s) {
      const Vec3 c = corner(i, s == 1);
      x_lo = min_of(x_lo, px(c));
      x_hi = max_of(x_hi, px(c));
      y_lo = min_of(y_lo, py(c));
      y_hi = max_of(y_hi, py(c));
    }
    cx += px(upper[i].position);
    cy += py(upper[i].position);
  }
  // The lattice's origin: the picks' centroid (it moves with the jaws).
  cx /= static_cast<double>(upper.size());
  cy /= static_cast<double>(upper.size());
  const int64_t i0 = static_cast<int64_t>(std::floor((x_lo - cx) / kSurveyCellMm));
  const int64_t i1 = static_cast<int64_t>(std::ceil((x_hi - cx) / kSurveyCellMm));
  const int64_t j0 = static_cast<int64_t>(std::floor((y_lo - cy) / kSurveyCellMm));
  const int64_t j1 = static_cast<int64_t>(std::ceil((y_hi - cy) / kSurveyCellMm));
  auto side = [](double ax, double ay, double bx, double by, double x, double y) {
    return (bx - ax) * (y - ay) - (by - ay) * (x - ax);
  };
  // Twice: count, then fill the exact room.
  for (int pass = 0; pass < 2; ++pass) {
    size_t count = 0;
    for (int64_t j = j0; j <= j1; ++j) {
      for (int64_t i = i0; i <= i1; ++i) {
        const double x = cx + static_cast<double>(i) * kSurveyCellMm;
        const double y = cy + static_cast<double>(j) * kSurveyCellMm;
        for (size_t q = 0; q + 1 < upper.size(); ++q) {
          const Vec3 a = corner(q, false), b = corner(q, true), c = corner(q + 1, true),
                     d = corner(q + 1, false);
          const double s1 = side(px(a), py(a), px(b), py(b), x, y),
                       s2 = side(px(b), py(b), px(c), py(c), x, y),
                       s3 = side(px(c), py(c), px(d), py(d), x, y),
                       s4 = side(px(d), py(d), px(a), py(a), x, y);
          const bool in = (s1 >= 0 && s2 >= 0 && s3 >= 0 && s4 >= 0) ||
                          (s1 <= 0 && s2 <= 0 && s3 <= 0 && s4 <= 0);
          if (!in) continue;
          // Where between the two picks: along the segment joining them.
          const Vec3 p0 = upper[q].position, p1 = upper[q + 1].position;
          const double dx = px(p1) - px(p0), dy = py(p1) - py(p0);
          double w = ((x - px(p0)) * dx + (y - py(p0)) * dy) / (dx * dx + dy * dy);
          w = w < 0 ? 0 : (w > 1 ? 1 : w);
          Column col;
          col.x = x;
          col.y = y;
          col.top = dot(p0, f.n) + w * (dot(p1, f.n) - dot(p0, f.n));
          col.bottom = dot(lower[q].position, f.n) +
                       w * (dot(lower[q + 1].position, f.n) - dot(lower[q].position, f.n));
          ++count;
          if (pass == 1) (void)out->push_back(col);
          break;
        }
      }
    }
    if (pass == 0 && !out->reserve(count)) return arena.exhausted_status();
  }
  return Status::ok();
}

// The undercut volume (mm^3) of both jaws along d over the columns.
double undercut_volume(const SurveyJaw jaws[2], const Vec3& lower_offset, const Frame& f,
                       Span<const Column> columns, const Vec3& d) {
  const double cos_tilt = dot(d, f.n);
  double length = 0;
  for (const Column& c : columns) {
    const Vec3 flat = f.e1 * c.x + f.e2 * c.y;
    const double span = (c.top - c.bottom) / cos_tilt;
    // The maxilla from the wafer's bottom face, along d; the mandible from the top, along -d
    // (its own frame: the opening's move undone).
    length += ray_undercut(jaws[0], flat + f.n * c.bottom, d, span);
    length += ray_undercut(jaws[1], flat + f.n * c.top - lower_offset, -d, span);
  }
  return length * kSurveyCellMm * kSurveyCellMm * cos_tilt;
}

}  // namespace

Status survey_direction(const Context& ctx, const Mesh& maxilla, const Mesh& mandible,
                        const Vec3& lower_offset, const Frame& f, Span<const Pick> upper,
                        Span<const Pick> lower, OutlineReport* r) {
  ArenaScope scope(*ctx.arena);
  ArenaArray<Column> columns(ctx.arena);
  SPLINTCORE_RETURN_IF_ERROR(footprint(*ctx.arena, f, upper, lower, &columns));
  double lo = HUGE_VAL, hi = -HUGE_VAL;
  for (const Column& c : columns) {
    lo = min_of(lo, c.bottom);
    hi = max_of(hi, c.top);
  }
  // Tilted rays reach sideways too: the slab is widened by the tangent of the cone's angle
  // times nothing along n (the faces bound the rays' heights), so [lo, hi] is exact.
  SurveyJaw jaws[2];
  SPLINTCORE_RETURN_IF_ERROR(survey_jaw(ctx, maxilla, f.n, lo, hi, &jaws[0]));
  const double shift = dot(lower_offset, f.n);
  SPLINTCORE_RETURN_IF_ERROR(survey_jaw(ctx, mandible, f.n, lo - shift, hi - shift, &jaws[1]));
  const double tan_max = 2.0 - std::sqrt(3.0);  // tan 15 degrees
  auto direction = [&](double a, double b) {
    const Vec3 v = f.n + f.e1 * a + f.e2 * b;
    return v * (1.0 / length(v));
  };
  const Span<const Column> cols = columns.span();
  r->undercut_plain_mm3 = undercut_volume(jaws, lower_offset, f, cols, f.n);
  double best_a = 0, best_b = 0, best = r->undercut_plain_mm3;
  uint32_t tried = 1;
  // A 5 x 5 grid over the cone's tangent disc, then 3 x 3 around the best at half and a
  // quarter of its step.
  double step = tan_max / 2;
  for (int level = 0; level < 3; ++level) {
    const int reach = level == 0 ? 2 : 1;
    const double ca = best_a, cb = best_b;
    for (int i = -reach; i <= reach; ++i) {
      for (int j = -reach; j <= reach; ++j) {
        const double a = ca + i * step, b = cb + j * step;
        if ((i == 0 && j == 0) || a * a + b * b > tan_max * tan_max * (1 + 1e-12)) continue;
        const double v = undercut_volume(jaws, lower_offset, f, cols, direction(a, b));
        ++tried;
        if (v < best) {
          best = v;
          best_a = a;
          best_b = b;
        }
      }
    }
    step *= 0.5;
  }
  r->surveyed = true;
  r->survey_directions = tried;
  r->undercut_chosen_mm3 = best;
  r->insertion_direction = direction(best_a, best_b);
  return Status::ok();
}

}  // namespace outline_detail
}  // namespace splintcore
