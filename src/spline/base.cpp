// The initial splint base (Chen et al. 2016, section "The Generation of the Initial Splint"):
// picks -> Lines -> four splines through the line ends -> sections sampled at matched
// arc-length fractions -> ruled surfaces between consecutive sections -> one closed solid.
//
// Decisions beyond the paper:
// - Sections are matched per pick interval: the i-th upper and lower picks always land on the
//   same section, and between them every curve is sampled at the same fractions of its own
//   arc length (so the sampling follows arc length, not pick index, and a dense cluster of
//   picks on one curve does not skew the others).
// - Corners are rounded (the paper's open problem: sharp splint edges injure soft tissue) by
//   circular fillets in each section's corner plane; arc points come from repeated angle
//   bisection, which needs only sqrt, so the bytes are the same on every platform.
// - The result is checked as STL will store it (vertices rounded to float32): closed,
//   manifold, outward, nothing degenerate, and no self-intersection (exact test). A base that
//   fails is an error naming the pick interval, never an output.
#include <cmath>

#include "splintcore/spline.h"

namespace splintcore {

namespace {

constexpr uint32_t kArcSamples = 32;  // arc-length table resolution per pick interval
constexpr uint64_t kMaxSections = 1u << 20;

bool finite_vec(const Vec3& v) { return is_finite(v); }

Vec3 normalized(const Vec3& v) {
  const double len = length(v);
  return len > 0.0 ? Vec3{v.x / len, v.y / len, v.z / len} : Vec3{};
}

// Project onto the plane with unit normal o.
Vec3 in_plane(const Vec3& v, const Vec3& o) { return v - o * dot(v, o); }

Status pick_error(const char* list, size_t index, const char* what) {
  return make_error(StatusCode::kInvalidArgument, list, " pick ", index, ": ", what)
      .at_index(index);
}

// The four curves of the base, in section order.
enum Curve { kUpperInner = 0, kUpperOutside = 1, kLowerOutside = 2, kLowerInner = 3 };
const char* const kCurveNames[4] = {"upper inner", "upper outside", "lower outside", "lower inner"};

const Vec3& line_end(Span<const Line> upper, Span<const Line> lower, int curve, size_t i) {
  switch (curve) {
    case kUpperInner: return upper[i].inner;
    case kUpperOutside: return upper[i].outside;
    case kLowerOutside: return lower[i].outside;
    default: return lower[i].inner;
  }
}

// Control points of curve segment i (from point i to i + 1), with phantom end points
// reflected through the end picks.
void segment_controls(Span<const Line> upper, Span<const Line> lower, int curve, size_t i,
                      Vec3 p[4]) {
  const size_t n = upper.size();
  p[1] = line_end(upper, lower, curve, i);
  p[2] = line_end(upper, lower, curve, i + 1);
  p[0] = i > 0 ? line_end(upper, lower, curve, i - 1) : p[1] * 2.0 - p[2];
  p[3] = i + 2 < n ? line_end(upper, lower, curve, i + 2) : p[2] * 2.0 - p[1];
}

// Cumulative chord lengths of a segment at kArcSamples + 1 uniform parameters.
void arc_table(const Vec3 p[4], double cumulative[kArcSamples + 1]) {
  const CatmullRomSegment seg = catmull_rom_segment(p[0], p[1], p[2], p[3]);
  Vec3 previous = p[1];
  cumulative[0] = 0.0;
  for (uint32_t k = 1; k <= kArcSamples; ++k) {
    Vec3 q = catmull_rom_point(seg, static_cast<double>(k) / kArcSamples);
    cumulative[k] = cumulative[k - 1] + length(q - previous);
    previous = q;
  }
}

// The point at arc-length fraction f of the segment (linear inversion of the table).
Vec3 point_at_fraction(const Vec3 p[4], const double cumulative[kArcSamples + 1], double f) {
  if (f <= 0.0) return p[1];
  const double target = f * cumulative[kArcSamples];
  uint32_t k = 0;
  while (k + 1 < kArcSamples && cumulative[k + 1] < target) ++k;
  const double span = cumulative[k + 1] - cumulative[k];
  const double local = span > 0.0 ? (target - cumulative[k]) / span : 0.0;
  const double u = (static_cast<double>(k) + local) / kArcSamples;
  return catmull_rom_point(p[0], p[1], p[2], p[3], u);
}

// Fillet of corner q between prev and next: `segments` + 1 arc points from the tangent point
// towards prev to the tangent point towards next.
Status round_corner(const Vec3& prev, const Vec3& q, const Vec3& next, double radius,
                    uint32_t segments, Vec3* arc, size_t section, int corner) {
  const Vec3 to_prev = prev - q, to_next = next - q;
  const double lp = length(to_prev), ln = length(to_next);
  const Vec3 u = normalized(to_prev), w = normalized(to_next);
  const double c = dot(u, w);
  if (!(lp > 0.0) || !(ln > 0.0) || !(c < 1.0) || !(c > -1.0)) {
    return make_error(StatusCode::kInvalidArgument, "section ", section, " corner ", corner,
                      " is degenerate: cannot round it");
  }
  const double tangent_distance = radius * std::sqrt((1.0 + c) / (1.0 - c));
  if (tangent_distance > 0.5 * lp || tangent_distance > 0.5 * ln) {
    return make_error(StatusCode::kInvalidArgument, "corner radius ", radius,
                      " mm is too large for section ", section, " (corner ", corner, " would need ",
                      tangent_distance, " mm of each side)");
  }
  const double center_distance = radius / std::sqrt((1.0 - c) * 0.5);
  const Vec3 center = q + normalized(u + w) * center_distance;
  arc[0] = q + u * tangent_distance;
  arc[segments] = q + w * tangent_distance;
  for (uint32_t step = segments; step > 1; step /= 2) {
    for (uint32_t i = 0; i < segments; i += step) {
      const Vec3 mid = normalized((arc[i] - center) + (arc[i + step] - center));
      arc[i + step / 2] = center + mid * radius;
    }
  }
  return Status::ok();
}

// Newell's normal of a closed polygon (twice its vector area).
Vec3 polygon_normal(const Vec3* p, uint32_t n) {
  Vec3 sum{};
  for (uint32_t i = 0; i < n; ++i) sum = sum + cross(p[i], p[(i + 1) % n]);
  return sum;
}

}  // namespace

namespace {

Status make_lines_steps(const Context& ctx, Span<const Pick> picks, const Vec3& occlusal_normal,
                        const char* list_name, ArenaArray<Line>* out) {
  const size_t n = picks.size();
  if (n < 2) {
    return make_error(StatusCode::kInvalidArgument, list_name, " list has ", n,
                      " picks; the spline needs at least 2");
  }
  if (!finite_vec(occlusal_normal) || !(length(occlusal_normal) > 0.0)) {
    return Status::error(StatusCode::kInvalidArgument, "occlusal normal must be a nonzero vector");
  }
  const Vec3 o = normalized(occlusal_normal);
  Vec3 centroid{};
  for (size_t i = 0; i < n; ++i) {
    const Pick& p = picks[i];
    if (!finite_vec(p.position) || !finite_vec(p.normal) || !finite_vec(p.direction) ||
        !is_finite(p.inner_length) || !is_finite(p.outside_length)) {
      return pick_error(list_name, i, "has a non-finite value");
    }
    if (p.inner_length < 0.0 || p.outside_length < 0.0) {
      return pick_error(list_name, i, "line lengths must not be negative");
    }
    if (!(p.inner_length + p.outside_length > 0.0)) {
      return pick_error(list_name, i, "zero-length line (inner and outside lengths are 0)");
    }
    if (i > 0 && p.position == picks[i - 1].position) {
      return pick_error(list_name, i, "same position as the previous pick");
    }
    centroid = centroid + p.position;
  }
  centroid = centroid * (1.0 / static_cast<double>(n));
  // The outward side of the arch: the in-plane perpendicular of the tangent whose side faces
  // away from the centroid on the whole (one sign for the list, so it never flips mid-arch).
  double side = 0.0;
  auto perpendicular = [&](size_t i) {
    const Vec3& a = picks[i > 0 ? i - 1 : 0].position;
    const Vec3& b = picks[i + 1 < n ? i + 1 : n - 1].position;
    return normalized(in_plane(cross(b - a, o), o));
  };
  for (size_t i = 0; i < n; ++i)
    side += dot(perpendicular(i), in_plane(picks[i].position - centroid, o));
  const double sign = side < 0.0 ? -1.0 : 1.0;

  if (!out->reserve(out->size() + n)) return ctx.arena->exhausted_status();
  for (size_t i = 0; i < n; ++i) {
    const Pick& p = picks[i];
    const Vec3 outward = perpendicular(i) * sign;
    Vec3 d;
    if (length(p.direction) > 0.0) {
      d = normalized(p.direction);
    } else if (length(p.normal) > 0.0) {
      const Vec3 projected = in_plane(normalized(p.normal), o);
      if (!(length(projected) > 1e-6)) {
        return pick_error(list_name, i,
                          "normal is parallel to the occlusal normal: no direction "
                          "in the occlusal plane (give \"direction\")");
      }
      d = normalized(projected);
      if (dot(d, outward) < 0.0) d = -d;
    } else {
      if (!(length(outward) > 0.0)) {
        return pick_error(list_name, i,
                          "no direction: the arch tangent is along the occlusal "
                          "normal (give \"direction\" or \"normal\")");
      }
      d = outward;
    }
    Line line;
    line.direction = d;
    line.inner_length = p.inner_length;
    line.outside_length = p.outside_length;
    line.inner = p.position - d * p.inner_length;
    line.outside = p.position + d * p.outside_length;
    if (!out->push_back(line)) return ctx.arena->exhausted_status();
  }
  return Status::ok();
}

}  // namespace

Status make_lines(const Context& ctx, Span<const Pick> picks, const Vec3& occlusal_normal,
                  const char* list_name, ArenaArray<Line>* out) {
  // On an error the arena goes back to its top at entry and `out` to what it held.
  ArenaScope scope(*ctx.arena);
  const ArenaArray<Line> saved = *out;
  Status s = make_lines_steps(ctx, picks, occlusal_normal, list_name, out);
  if (s.is_ok()) {
    scope.commit();
  } else {
    *out = saved;
  }
  return s;
}

BaseSide base_segment_side(const BaseParams& params, uint32_t segment) {
  // BaseBuilder's layout: corner c's points start at c * corner_points; the straight side c
  // (corner c to corner c + 1) is the segment from corner c's last point.
  const bool rounded = params.corner_radius_mm > 0.0;
  const uint32_t segs = rounded ? params.corner_segments : 0;
  const uint32_t corner_points = segs + 1;
  const uint32_t corner = (segment / corner_points) % 4;
  const uint32_t i = segment % corner_points;  // segs: the straight side; else arc segment i
  static constexpr BaseSide kSides[4] = {BaseSide::kTop, BaseSide::kOuter, BaseSide::kBottom,
                                         BaseSide::kInner};
  if (i == segs) return kSides[corner];
  if (2 * i + 1 == segs) return BaseSide::kCorner;                  // the middle of an odd arc
  return 2 * i < segs ? kSides[(corner + 3) % 4] : kSides[corner];  // the side it leans to
}

uint64_t splint_base_bound(uint64_t sections, uint32_t points_per_section) {
  const uint64_t v = sections * points_per_section;
  const uint64_t t = 2 * v;
  return v * sizeof(Vec3) + t * sizeof(Triangle) + sections * sizeof(uint32_t) +
         check_closed_oriented_bound(v, t) + find_self_intersections_bound(t) + 16 * 64;
}

namespace {

// The checks of build_splint_base's arguments (no memory needed).
Status check_base_input(Span<const Line> upper, Span<const Line> lower, const BaseParams& params) {
  const size_t n = upper.size();
  if (n != lower.size()) {
    return make_error(StatusCode::kInvalidArgument, "upper and lower lists do not pair up: ", n,
                      " upper picks, ", lower.size(),
                      " lower picks (the i-th upper pick pairs "
                      "with the i-th lower pick)");
  }
  if (n < 2) {
    return make_error(StatusCode::kInvalidArgument,
                      "the base needs at least 2 picks per list, got ", n);
  }
  if (!is_finite(params.spacing_mm) || !(params.spacing_mm > 0.0)) {
    return make_error(StatusCode::kInvalidArgument, "spacing must be > 0 mm, got ",
                      params.spacing_mm);
  }
  const double radius = params.corner_radius_mm;
  const uint32_t segs = params.corner_segments;
  if (!is_finite(radius) || radius < 0.0) {
    return make_error(StatusCode::kInvalidArgument, "corner radius must be >= 0 mm, got ", radius);
  }
  if (radius > 0.0 && (segs == 0 || segs > 16 || (segs & (segs - 1)) != 0)) {
    return make_error(StatusCode::kInvalidArgument,
                      "corner segments must be 1, 2, 4, 8 or 16, got ", segs);
  }
  for (size_t i = 0; i < n; ++i) {
    for (int c = 0; c < 4; ++c) {
      if (!finite_vec(line_end(upper, lower, c, i))) {
        return make_error(StatusCode::kInvalidArgument, kCurveNames[c], " end of pick ", i,
                          " is not finite")
            .at_index(i);
      }
      if (i + 1 < n && line_end(upper, lower, c, i) == line_end(upper, lower, c, i + 1)) {
        return make_error(StatusCode::kInvalidArgument, kCurveNames[c], " ends of picks ", i,
                          " and ", i + 1, " coincide")
            .at_index(i);
      }
    }
  }
  return Status::ok();
}

// The state of one build_base_steps call (below), with one method per stage, run in this
// order: the sections' corners, the section polygons, the ruled surfaces, the checks.
struct BaseBuilder {
  BaseBuilder(Span<const Line> u, Span<const Line> l, const BaseParams& p)
      : upper(u),
        lower(l),
        params(p),
        n(u.size()),
        radius(p.corner_radius_mm),
        segs(p.corner_segments),
        corner_points(radius > 0.0 ? segs + 1 : 1),
        P(4 * corner_points) {}

  Span<const Line> upper, lower;
  const BaseParams& params;
  size_t n;                         // picks per list
  double radius;                    // of the corner fillets
  uint32_t segs;                    // arc segments per rounded corner
  uint32_t corner_points;           // points per corner in a section
  uint32_t P;                       // points per section
  uint32_t S = 0;                   // sections
  uint32_t* interval_of = nullptr;  // section -> pick interval
  Vec3* corners = nullptr;          // the four line-end curves, four per section

  uint64_t triangle_count() const { return 2 * uint64_t{S - 1} * P + 2 * uint64_t{P - 2}; }

  // Sections per pick interval: enough that no curve's samples are further apart than
  // spacing. Fills the four curves' control points and arc-length tables of interval i on the
  // way.
  Status interval_tables(size_t i, Vec3 p[4][4], double cum[4][kArcSamples + 1],
                         uint32_t* count) const {
    double longest = 0.0;
    for (int c = 0; c < 4; ++c) {
      segment_controls(upper, lower, c, i, p[c]);
      arc_table(p[c], cum[c]);
      longest = cum[c][kArcSamples] > longest ? cum[c][kArcSamples] : longest;
    }
    const double m = std::ceil(longest / params.spacing_mm);
    if (!(m < static_cast<double>(kMaxSections))) {
      return make_error(StatusCode::kLimitExceeded, "spacing ", params.spacing_mm,
                        " mm gives too many sections between picks ", i, " and ", i + 1);
    }
    *count = m < 1.0 ? 1u : static_cast<uint32_t>(m);
    return Status::ok();
  }

  Status count_sections() {
    uint64_t sections = 1;
    for (size_t i = 0; i + 1 < n; ++i) {
      uint32_t m = 0;
      Vec3 p[4][4];
      double cum[4][kArcSamples + 1];
      SPLINTCORE_RETURN_IF_ERROR(interval_tables(i, p, cum, &m));
      sections += m;
      if (sections > kMaxSections) {
        return make_error(StatusCode::kLimitExceeded, "more than ", kMaxSections,
                          " sections: spacing ", params.spacing_mm, " mm is too fine");
      }
    }
    S = static_cast<uint32_t>(sections);
    return Status::ok();
  }

  // The four corners of every section, at matched arc-length fractions of each interval.
  Status sample_corners(Arena& arena) {
    interval_of = arena.allocate_array<uint32_t>(S);
    corners = arena.allocate_array<Vec3>(size_t{4} * S);
    if (interval_of == nullptr || corners == nullptr) return arena.exhausted_status();
    uint32_t k = 0;
    for (size_t i = 0; i + 1 < n; ++i) {
      uint32_t m = 0;
      Vec3 p[4][4];
      double cum[4][kArcSamples + 1];
      SPLINTCORE_RETURN_IF_ERROR(interval_tables(i, p, cum, &m));
      for (uint32_t j = 0; j < m; ++j) {
        const double f = static_cast<double>(j) / m;
        for (int c = 0; c < 4; ++c) {
          corners[4 * size_t{k} + static_cast<size_t>(c)] = point_at_fraction(p[c], cum[c], f);
        }
        interval_of[k] = static_cast<uint32_t>(i);
        ++k;
      }
    }
    for (int c = 0; c < 4; ++c) {
      corners[4 * size_t{k} + static_cast<size_t>(c)] = line_end(upper, lower, c, n - 1);
    }
    interval_of[k] = static_cast<uint32_t>(n - 2);
    return Status::ok();
  }

  // Every section must turn the same way around the arch: a section whose upper and lower
  // lines, or inner and outside curves, have crossed is turned over.
  Status check_turns() const {
    double first_turn = 0.0;
    for (uint32_t k = 0; k < S; ++k) {
      const Vec3* q = corners + 4 * size_t{k};
      const Vec3 normal = polygon_normal(q, 4);
      const Vec3* qa = corners + 4 * size_t{k > 0 ? k - 1 : k};
      const Vec3* qb = corners + 4 * size_t{k + 1 < S ? k + 1 : k};
      const Vec3 tangent =
          (qb[0] + qb[1] + qb[2] + qb[3]) * 0.25 - (qa[0] + qa[1] + qa[2] + qa[3]) * 0.25;
      const double turn = dot(normal, tangent);
      const double scale = length(normal) * length(tangent);
      if (!(scale > 0.0) || !(turn > 1e-9 * scale || turn < -1e-9 * scale)) {
        return make_error(StatusCode::kInvalidArgument, "section ", k, " between picks ",
                          interval_of[k], " and ", interval_of[k] + 1,
                          " is flat or lies along the arch: the upper and lower lines coincide "
                          "or the lines run along the arch")
            .at_index(interval_of[k]);
      }
      if (k == 0) {
        first_turn = turn;
      } else if ((turn > 0.0) != (first_turn > 0.0)) {
        return make_error(StatusCode::kInvalidArgument, "the lines fold between picks ",
                          interval_of[k], " and ", interval_of[k] + 1,
                          ": the section turns over (inner and outside curves, or upper and "
                          "lower lines, cross)")
            .at_index(interval_of[k]);
      }
    }
    return Status::ok();
  }

  // Section polygons (rounded corners) into the output vertices.
  Status make_sections(Vec3* verts) const {
    for (uint32_t k = 0; k < S; ++k) {
      const Vec3* q = corners + 4 * size_t{k};
      Vec3* sec = verts + size_t{k} * P;
      for (int c = 0; c < 4; ++c) {
        if (radius > 0.0) {
          SPLINTCORE_RETURN_IF_ERROR(
              round_corner(q[(c + 3) % 4], q[c], q[(c + 1) % 4], radius, segs,
                           sec + static_cast<size_t>(c) * corner_points, k, c));
        } else {
          sec[c] = q[c];
        }
      }
      if (params.snap_to_float32) {
        for (uint32_t j = 0; j < P; ++j) {
          if (!round_to_float32(&sec[j])) {
            return make_error(StatusCode::kLimitExceeded, "section ", k,
                              " is beyond float32 range");
          }
        }
      }
    }
    return Status::ok();
  }

  // The caps are fans from the first point; they need convex end sections.
  Status check_end_sections(const Vec3* verts) const {
    const uint32_t ends[2] = {0u, S - 1};
    for (uint32_t k : ends) {
      const Vec3* sec = verts + size_t{k} * P;
      const Vec3 normal = polygon_normal(sec, P);
      for (uint32_t j = 1; j + 1 < P; ++j) {
        if (!(dot(cross(sec[j] - sec[0], sec[j + 1] - sec[0]), normal) > 0.0)) {
          return make_error(StatusCode::kInvalidArgument, "the end section at pick ",
                            k == 0 ? 0 : n - 1, " is not convex: cannot close the base there")
              .at_index(k == 0 ? 0 : n - 1);
        }
      }
    }
    return Status::ok();
  }

  // Ruled surfaces between consecutive sections, then the two caps, wound outward.
  void stitch(Mesh* mesh) const {
    Triangle* tris = mesh->triangles.data();
    size_t t = 0;
    for (uint32_t k = 0; k + 1 < S; ++k) {
      for (uint32_t j = 0; j < P; ++j) {
        const uint32_t a = k * P + j, b = k * P + (j + 1) % P;
        const uint32_t c = (k + 1) * P + (j + 1) % P, d = (k + 1) * P + j;
        tris[t++] = Triangle{{a, b, c}};
        tris[t++] = Triangle{{a, c, d}};
      }
    }
    const uint32_t last = (S - 1) * P;
    for (uint32_t j = 1; j + 1 < P; ++j) {
      tris[t++] = Triangle{{0, j + 1, j}};
      tris[t++] = Triangle{{last, last + j, last + j + 1}};
    }
    SPLINTCORE_ASSERT(t == triangle_count());
    // Outward: the winding above depends on which way the sections turn; flip if inward.
    if (mesh_volume(*mesh) < 0.0) {
      for (size_t i = 0; i < t; ++i) {
        uint32_t s = tris[i].v[1];
        tris[i].v[1] = tris[i].v[2];
        tris[i].v[2] = s;
      }
    }
  }

  // The guarantee, first part: a valid solid, as written; a failure names its pick interval.
  Status check_solid(const Context& ctx, const Mesh& mesh, BaseReport* report) const {
    double volume = 0;
    Status valid = check_closed_oriented(ctx, mesh, &volume);
    if (valid.code() == StatusCode::kArenaExhausted) return valid;
    if (!valid.is_ok()) {
      const uint64_t bad = valid.index();
      Status s = make_error(StatusCode::kInvalidArgument,
                            "splint base is not a valid solid: ", valid.message());
      if (bad != kNoPosition && bad < 2 * uint64_t{S - 1} * P) {
        const uint32_t k = static_cast<uint32_t>(bad / (2 * P));
        s.append(" (between picks ")
            .append_u64(interval_of[k])
            .append(" and ")
            .append_u64(interval_of[k] + 1)
            .append(")");
        s.at_index(interval_of[k]);
      }
      return s;
    }
    report->volume = volume;
    return Status::ok();
  }

  // The guarantee, second part: no self-intersection (exact); a failure names the intervals.
  Status check_self_intersection(const Context& ctx, const Mesh& mesh, BaseReport* report) const {
    SelfIntersectionReport si;
    SPLINTCORE_RETURN_IF_ERROR(find_self_intersections(ctx, mesh, 1, &si));
    report->self_intersection_candidates = si.candidate_pairs;
    if (si.self_intersecting()) {
      auto where = [&](uint32_t tri) -> uint32_t {
        return tri < 2 * (S - 1) * P ? interval_of[tri / (2 * P)]
                                     : (tri % 2 == 0 ? 0u : static_cast<uint32_t>(n - 2));
      };
      const uint32_t ia = where(si.first_a), ib = where(si.first_b);
      return make_error(StatusCode::kInvalidArgument,
                        "the splint base would intersect itself: triangle ", si.first_a,
                        " (between picks ", ia, " and ", ia + 1, ") meets triangle ", si.first_b,
                        " (between picks ", ib, " and ", ib + 1,
                        "); the lines fold or the curves cross there")
          .at_index(ia);
    }
    return Status::ok();
  }
};

// The body of build_splint_base (below), which checks `out` and undoes this on an error.
Status build_base_steps(const Context& ctx, Span<const Line> upper, Span<const Line> lower,
                        const BaseParams& params, Mesh* out, BaseReport* report) {
  Arena& arena = *ctx.arena;
  SPLINTCORE_RETURN_IF_ERROR(check_base_input(upper, lower, params));
  BaseBuilder b(upper, lower, params);
  SPLINTCORE_RETURN_IF_ERROR(b.count_sections());
  report->sections = b.S;
  report->points_per_section = b.P;

  // The outputs first, so that the temporaries above them can be dropped at the end.
  Mesh& mesh = *out;
  if (!mesh.vertices.resize(size_t{b.S} * b.P) ||
      !mesh.triangles.resize(static_cast<size_t>(b.triangle_count()))) {
    return arena.exhausted_status();
  }
  ArenaScope temps(arena);
  SPLINTCORE_RETURN_IF_ERROR(b.sample_corners(arena));
  SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "base", 1, 4));
  SPLINTCORE_RETURN_IF_ERROR(b.check_turns());
  SPLINTCORE_RETURN_IF_ERROR(b.make_sections(mesh.vertices.data()));
  SPLINTCORE_RETURN_IF_ERROR(b.check_end_sections(mesh.vertices.data()));
  b.stitch(&mesh);
  SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "base", 2, 4));
  SPLINTCORE_RETURN_IF_ERROR(b.check_solid(ctx, mesh, report));
  SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "base", 3, 4));
  if (params.check_self_intersection) {
    SPLINTCORE_RETURN_IF_ERROR(b.check_self_intersection(ctx, mesh, report));
  }
  SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "base", 4, 4));
  return Status::ok();
}

}  // namespace

Status build_splint_base(const Context& ctx, Span<const Line> upper, Span<const Line> lower,
                         const BaseParams& params, Mesh* out, BaseReport* report) {
  *report = BaseReport{};
  if (!out->vertices.empty() || !out->triangles.empty()) {
    return Status::error(StatusCode::kInvalidArgument,
                         "build_splint_base: output mesh must be empty");
  }
  // On an error nothing stays: the arena back at its top at entry, `out` empty.
  ArenaScope scope(*ctx.arena);
  const Mesh saved = *out;
  Status s = build_base_steps(ctx, upper, lower, params, out, report);
  if (s.is_ok()) {
    scope.commit();
  } else {
    *out = saved;
  }
  return s;
}

}  // namespace splintcore
