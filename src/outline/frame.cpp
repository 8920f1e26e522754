// The occlusal frame and the height grids of the automatic outline (outline.h): the plane the
// two arches meet in, fitted to where they face each other, and per jaw the surface each
// column of a 0.5 mm lattice shows the other jaw.
#include <algorithm>
#include <cmath>

#include "outline_internal.h"

namespace splintcore {
namespace outline_detail {

namespace {

Vec3 unit(const Vec3& v) { return v * (1.0 / length(v)); }

Vec3 mesh_centroid(const Mesh& m, const Vec3& offset) {
  Vec3 sum{};
  for (const Vec3& v : m.vertices) sum = sum + v;
  return sum * (1.0 / static_cast<double>(m.vertices.size())) + offset;
}

// An in-plane axis perpendicular to n, from n alone (for the first, provisional frame).
Vec3 any_perpendicular(const Vec3& n) {
  const Vec3 a = std::fabs(n.x) <= std::fabs(n.y) && std::fabs(n.x) <= std::fabs(n.z)
                     ? Vec3{1, 0, 0}
                 : std::fabs(n.y) <= std::fabs(n.z) ? Vec3{0, 1, 0}
                                                    : Vec3{0, 0, 1};
  return unit(cross(n, a));
}

// Solves the 3 x 3 system m x = r by Cramer's rule; false when singular.
bool solve3(const double m[3][3], const double r[3], double x[3]) {
  auto det = [](const double a[3][3]) {
    return a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) -
           a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
           a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
  };
  const double d = det(m);
  if (!(std::fabs(d) > 0)) return false;
  for (int k = 0; k < 3; ++k) {
    double a[3][3];
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) a[i][j] = j == k ? r[i] : m[i][j];
    x[k] = det(a) / d;
  }
  return true;
}

}  // namespace

void complete_frame(const Vec3& n, const Vec3& anterior_hint, Frame* f) {
  f->n = n;
  Vec3 e1 = anterior_hint - n * dot(anterior_hint, n);
  f->e1 = length(e1) > 0 ? unit(e1) : any_perpendicular(n);
  f->e2 = cross(n, f->e1);
}

bool centroid_axis(const Vec3& upper_centroid, const Vec3& lower_centroid, Vec3* n) {
  const Vec3 d = upper_centroid - lower_centroid;
  if (!(length(d) > 1.0)) return false;
  *n = unit(d);
  return true;
}

namespace {

constexpr size_t kQuotientChunk = 16384;  // vertices a task of anterior_axis

// anterior_axis's quotients of vertices [first, first + count) of m, moved by -c: (x, y) / r
// in the plane, or +0 where r is 0 (adding +0 to a sum that starts at +0 changes nothing: such
// a sum is never -0).
Lanes2 unit_quotient(const Vec3& v, const Vec3& c, const PlaneAxes& axes) {
  const Lanes2 xy = axes.xy(v - c);
  const double x = xy[0], y = xy[1];
  const double r = std::sqrt(x * x + y * y);
  const double safe = r > 0 ? r : 1.0;  // no 0 / 0 (trapping tests), and not added
  const Lanes2 zero = {0.0, 0.0};
  return r > 0 ? xy / Lanes2{safe, safe} : zero;
}

void unit_quotients(const Mesh& m, size_t first, size_t count, const Vec3& c, const PlaneAxes& axes,
                    Lanes2* q) {
  const Vec3* v = m.vertices.data() + first;
  for (size_t k = 0; k < count; ++k) q[k] = unit_quotient(v[k], c, axes);
}

}  // namespace

// The mean of the unit vectors from the centre c (the mean of the jaws' centroids) to every
// vertex, in the plane: a dental arch is open at the back, so this points to the front.
// Continuous in the data (no vertex is chosen), so the lattice it orients moves with the jaws.
// Both quotients of a vertex in one two-lane division (each lane rounds as the scalar one:
// the same bits for half the divisions), in chunks of vertices on the executor (into the
// arena, returned), then summed in vertex order; on one thread summed as they come.
Status anterior_axis(const Context& ctx, const Mesh& upper, const Mesh& lower, const Vec3& c,
                     const Frame& f, Vec3* axis) {
  const size_t nu = upper.vertices.size(), n = nu + lower.vertices.size();
  const PlaneAxes axes(f);
  if (!has_threads(ctx.executor)) {  // one pass, each quotient summed as it comes (the same bits)
    double sx = 0, sy = 0;
    for (const Mesh* m : {&upper, &lower}) {
      for (const Vec3& v : m->vertices) {
        const Lanes2 q = unit_quotient(v, c, axes);
        sx += q[0];
        sy += q[1];
      }
    }
    *axis = (f.e1 * sx + f.e2 * sy) * (1.0 / static_cast<double>(n));
    return Status::ok();
  }
  ArenaScope scope(*ctx.arena);
  Lanes2* q = ctx.arena->allocate_array<Lanes2>(n);
  if (q == nullptr) return ctx.arena->exhausted_status();
  const size_t chunks_upper = (nu + kQuotientChunk - 1) / kQuotientChunk;
  const size_t chunks = chunks_upper + (n - nu + kQuotientChunk - 1) / kQuotientChunk;
  auto task = [&](uint32_t i) {
    const bool in_upper = i < chunks_upper;
    const size_t first = (in_upper ? i : i - chunks_upper) * kQuotientChunk;
    const Mesh& m = in_upper ? upper : lower;
    const size_t count = std::min(kQuotientChunk, m.vertices.size() - first);
    unit_quotients(m, first, count, c, axes, q + (in_upper ? 0 : nu) + first);
  };
  parallel_for_each(ctx.executor, static_cast<uint32_t>(chunks), task);
  double sx = 0, sy = 0;
  for (size_t k = 0; k < n; ++k) {
    sx += q[k][0];
    sy += q[k][1];
  }
  *axis = (f.e1 * sx + f.e2 * sy) * (1.0 / static_cast<double>(n));
  return Status::ok();
}

namespace {

// The lattice of build_grid over the jaws (the extent and centroid of their vertices in the
// plane) and its arrays, unfilled. kHeights: also the maxilla's lowest and the mandible's
// highest vertex along n (their heights as fill_columns computes them), in the same pass, and
// every vertex's height in heights[0] (the maxilla's) and heights[1] (the mandible's).
// On the executor: task 0 sums the vertices' places in the plane (in lanes, in vertex order:
// the centroid's bits do not depend on the threads); the others take chunks of kLayoutChunk
// vertices, their extent (least and greatest x and y) and heights, combined in chunk order
// after (a strict comparison keeps the first of equal values, as one pass in vertex order
// would: the same bits). On one thread, that one pass.
constexpr size_t kLayoutChunk = 32768;

struct LayoutChunk {
  Lanes2 lo = {HUGE_VAL, HUGE_VAL}, hi = {-HUGE_VAL, -HUGE_VAL};
  double h_lo = HUGE_VAL, h_hi = -HUGE_VAL;
};

// The extent and heights of vertices [first, last) of a jaw into `part` (and, given `sum`,
// their places in the plane added to it in vertex order).
// (The extent in locals, stored once: the heights' stores could alias *part and *sum.)
template <bool kHeights>
void layout_pass(const Mesh& m, const Vec3& offset, bool upper_jaw, size_t first, size_t last,
                 const PlaneAxes& axes, const Vec3& n, double* h_out, LayoutChunk* part,
                 Lanes2* sum) {
  Lanes2 lo = part->lo, hi = part->hi, s = sum != nullptr ? *sum : Lanes2{0.0, 0.0};
  double h_lo = part->h_lo, h_hi = part->h_hi;
  const Vec3* v = m.vertices.data();
  for (size_t k = first; k < last; ++k) {
    const Vec3 p = v[k] + offset;
    const Lanes2 xy = axes.xy(p);
    lo = xy < lo ? xy : lo;
    hi = xy > hi ? xy : hi;
    if (sum != nullptr) s += xy;
    if (kHeights) {
      const double h = dot(p, n);
      h_out[k] = h;
      if (upper_jaw) {
        h_lo = h < h_lo ? h : h_lo;
      } else {
        h_hi = h > h_hi ? h : h_hi;
      }
    }
  }
  part->lo = lo;
  part->hi = hi;
  part->h_lo = h_lo;
  part->h_hi = h_hi;
  if (sum != nullptr) *sum = s;
}

template <bool kHeights>
Status grid_layout(Arena& arena, const Executor* executor, const Mesh& upper, const Mesh& lower,
                   const Vec3& lower_offset, const Frame& f, Grid* g, double* low_upper,
                   double* high_lower, double* heights[2]) {
  const PlaneAxes axes(f);
  const Vec3 n = f.n;
  const size_t nu = upper.vertices.size(), nl = lower.vertices.size();
  double* const h_out[2] = {kHeights ? heights[0] : nullptr, kHeights ? heights[1] : nullptr};
  Lanes2 sum = {0.0, 0.0};
  LayoutChunk whole;
  size_t chunks = 0;
  ArenaScope scope(arena);  // the chunks' extents go when done
  LayoutChunk* parts = &whole;
  if (!has_threads(executor)) {  // one pass over both jaws
    layout_pass<kHeights>(upper, Vec3{}, true, 0, nu, axes, n, h_out[0], &whole, &sum);
    layout_pass<kHeights>(lower, lower_offset, false, 0, nl, axes, n, h_out[1], &whole, &sum);
    chunks = 1;
  } else {
    const size_t chunks_upper = (nu + kLayoutChunk - 1) / kLayoutChunk;
    chunks = chunks_upper + (nl + kLayoutChunk - 1) / kLayoutChunk;
    parts = arena.allocate_array<LayoutChunk>(chunks > 0 ? chunks : 1);
    if (parts == nullptr) return arena.exhausted_status();
    auto task = [&](uint32_t i) {
      if (i == 0) {
        for (const Vec3& v : upper.vertices) sum += axes.xy(v + Vec3{});
        for (const Vec3& v : lower.vertices) sum += axes.xy(v + lower_offset);
        return;
      }
      const size_t c = i - 1;
      const bool upper_jaw = c < chunks_upper;
      const size_t first = (upper_jaw ? c : c - chunks_upper) * kLayoutChunk;
      const Mesh& m = upper_jaw ? upper : lower;
      const size_t last = std::min(first + kLayoutChunk, m.vertices.size());
      LayoutChunk part;
      layout_pass<kHeights>(m, upper_jaw ? Vec3{} : lower_offset, upper_jaw, first, last, axes, n,
                            h_out[upper_jaw ? 0 : 1], &part, nullptr);
      parts[c] = part;
    };
    parallel_for_each(executor, static_cast<uint32_t>(chunks + 1), task);
  }
  Lanes2 lo = {HUGE_VAL, HUGE_VAL}, hi = {-HUGE_VAL, -HUGE_VAL};
  double h_lo = HUGE_VAL, h_hi = -HUGE_VAL;
  for (size_t c = 0; c < chunks; ++c) {
    const LayoutChunk& part = parts[c];
    lo = part.lo < lo ? part.lo : lo;
    hi = part.hi > hi ? part.hi : hi;
    h_lo = part.h_lo < h_lo ? part.h_lo : h_lo;
    h_hi = part.h_hi > h_hi ? part.h_hi : h_hi;
  }
  *low_upper = h_lo;
  *high_lower = h_hi;
  const double x_lo = lo[0], y_lo = lo[1], x_hi = hi[0], y_hi = hi[1], cx = sum[0], cy = sum[1];
  const double count = static_cast<double>(upper.vertices.size() + lower.vertices.size());
  if (x_hi - x_lo > kMaxSpanMm || y_hi - y_lo > kMaxSpanMm) {
    return make_error(StatusCode::kInvalidArgument, "outline: the jaws span ", x_hi - x_lo, " x ",
                      y_hi - y_lo, " mm in the occlusal plane; at most ", kMaxSpanMm,
                      " (wrong units?)");
  }
  // The lattice's origin is the vertices' centroid, so it moves with the jaws.
  g->cx = cx / count;
  g->cy = cy / count;
  g->ix0 = static_cast<int64_t>(std::floor((x_lo - g->cx) / kCellMm));
  g->iy0 = static_cast<int64_t>(std::floor((y_lo - g->cy) / kCellMm));
  g->nx = static_cast<uint32_t>(static_cast<int64_t>(std::floor((x_hi - g->cx) / kCellMm)) -
                                g->ix0 + 1);
  g->ny = static_cast<uint32_t>(static_cast<int64_t>(std::floor((y_hi - g->cy) / kCellMm)) -
                                g->iy0 + 1);
  g->set_limits();
  arena.rewind(scope.start());  // (the chunks' extents: the grid's arrays stay)
  scope.commit();
  const size_t cells = static_cast<size_t>(g->nx) * g->ny;
  for (int jaw = 0; jaw < 2; ++jaw) {
    g->h[jaw] = arena.allocate_array<double>(cells);
    g->tip[jaw] = arena.allocate_array<uint32_t>(cells);
    if (g->h[jaw] == nullptr || g->tip[jaw] == nullptr) return arena.exhausted_status();
  }
  return Status::ok();
}

}  // namespace

Status build_grid(Arena& arena, const Executor* executor, const Mesh& upper, const Mesh& lower,
                  const Vec3& lower_offset, const Frame& f, Grid* g) {
  double unused_low = 0, unused_high = 0;
  SPLINTCORE_RETURN_IF_ERROR(grid_layout<false>(arena, executor, upper, lower, lower_offset, f, g,
                                                &unused_low, &unused_high, nullptr));
  fill_both(executor, upper, lower, lower_offset, f, g);
  return Status::ok();
}

namespace {

// fill_heights for one jaw: kLowest for the maxilla (its lowest point of each column), else
// the highest. The frame and the lattice in locals (the stores into the columns could alias
// them), and no branch on the comparison (which follows no pattern): the height by a min or
// max, the vertex by a mask, both slots written always.
// kLaid: the vertices, in this place, are those the lattice was laid over (cell_of_laid).
// Vertices [first, last) into `heights` and `tips` (the jaw's columns, or a part's).
template <bool kLowest, bool kLaid>
void fill_columns(const Mesh& m, const Vec3& offset, const Frame& frame, const Grid& g,
                  size_t first, size_t last, double* heights, uint32_t* tips) {
  const PlaneAxes axes(frame);
  const Vec3 n = frame.n;
  const Grid grid = g;
  const Vec3* v = m.vertices.data();
  for (size_t k = first; k < last; ++k) {
    const Vec3 p = v[k] + offset;
    const Lanes2 xy = axes.xy(p);
    const size_t cell = kLaid ? grid.cell_of_laid(xy[0], xy[1]) : grid.cell_of(xy[0], xy[1]);
    const double h = dot(p, n);
    const double best = heights[cell];
    const bool better = kLowest ? h < best : h > best;
    heights[cell] = kLowest ? (h < best ? h : best) : (h > best ? h : best);
    const uint32_t mask = 0u - static_cast<uint32_t>(better);
    tips[cell] = (static_cast<uint32_t>(k) & mask) | (tips[cell] & ~mask);
  }
}

// fill_columns over the vertices whose height lies in a window only: for the maxilla (kLowest)
// in (from, to], for the mandible in [to, from). The heights and columns as fill_columns
// computes them (`vertex_h`: each vertex's height, dot(v + 0, n), from grid_layout); a vertex
// outside goes on after its height alone.
template <bool kLowest>
void fill_window(const Mesh& m, const double* vertex_h, double from, double to, const Frame& frame,
                 Grid* g) {
  const PlaneAxes axes(frame);
  const Grid grid = *g;
  double* heights = grid.h[kLowest ? 0 : 1];
  uint32_t* tips = grid.tip[kLowest ? 0 : 1];
  const Vec3* v = m.vertices.data();
  const size_t count = m.vertices.size();
  for (size_t k = 0; k < count; ++k) {
    const double h = vertex_h[k];
    if (kLowest ? !(h > from && h <= to) : !(h < from && h >= to)) continue;
    const Vec3 p = v[k] + Vec3{};
    const Lanes2 xy = axes.xy(p);
    const size_t cell = grid.cell_of_laid(xy[0], xy[1]);  // (grid_layout's vertices and place)
    const double best = heights[cell];
    const bool better = kLowest ? h < best : h > best;
    heights[cell] = kLowest ? (h < best ? h : best) : (h > best ? h : best);
    if (better) tips[cell] = static_cast<uint32_t>(k);
  }
}

void clear_columns(int jaw, size_t cells, double* heights, uint32_t* tips) {
  const double none = jaw == 0 ? HUGE_VAL : -HUGE_VAL;
  for (size_t i = 0; i < cells; ++i) {
    heights[i] = none;
    tips[i] = kNoTip;
  }
}

void clear_heights(int jaw, Grid* g) {
  clear_columns(jaw, static_cast<size_t>(g->nx) * g->ny, g->h[jaw], g->tip[jaw]);
}

// fill_columns of vertices [first, last) of jaw `jaw`, its columns cleared first.
template <bool kLaid>
void fill_part(const Mesh& m, const Vec3& offset, const Frame& f, int jaw, const Grid& g,
               size_t first, size_t last, double* heights, uint32_t* tips) {
  clear_columns(jaw, static_cast<size_t>(g.nx) * g.ny, heights, tips);
  if (jaw == 0) {
    fill_columns<true, kLaid>(m, offset, f, g, first, last, heights, tips);
  } else {
    fill_columns<false, kLaid>(m, offset, f, g, first, last, heights, tips);
  }
}

// kLaid: as fill_columns.
template <bool kLaid>
void fill_heights_of(const Mesh& m, const Vec3& offset, const Frame& f, int jaw, Grid* g) {
  fill_part<kLaid>(m, offset, f, jaw, *g, 0, m.vertices.size(), g->h[jaw], g->tip[jaw]);
}

}  // namespace

// Jaw 0 (the maxilla) shows the mandible its lowest point of each column, jaw 1 its highest.
// With threads: the first half of the vertices into the grid and the second into columns of
// their own, in two tasks, then each column of the second half taken where it is strictly
// beyond the first's (so of equal heights the first vertex stays, as in one pass in vertex
// order: the same heights and tips).
Status fill_heights(Arena& arena, const Executor* executor, const Mesh& m, const Vec3& offset,
                    const Frame& f, int jaw, Grid* g) {
  const size_t n = m.vertices.size(), cells = static_cast<size_t>(g->nx) * g->ny;
  if (!has_threads(executor) || n < 2 * 4096) {
    fill_heights_of<false>(m, offset, f, jaw, g);
    return Status::ok();
  }
  ArenaScope scope(arena);
  double* heights = arena.allocate_array<double>(cells);
  uint32_t* tips = arena.allocate_array<uint32_t>(cells);
  if (heights == nullptr || tips == nullptr) return arena.exhausted_status();
  const size_t half = n / 2;
  auto task = [&](uint32_t i) {
    if (i == 0) {
      fill_part<false>(m, offset, f, jaw, *g, 0, half, g->h[jaw], g->tip[jaw]);
    } else {
      fill_part<false>(m, offset, f, jaw, *g, half, n, heights, tips);
    }
  };
  parallel_for_each(executor, 2, task);
  double* h = g->h[jaw];
  uint32_t* tip = g->tip[jaw];
  for (size_t i = 0; i < cells; ++i) {
    const bool beyond = jaw == 0 ? heights[i] < h[i] : heights[i] > h[i];
    if (beyond) {
      h[i] = heights[i];
      tip[i] = tips[i];
    }
  }
  return Status::ok();
}

// (Its callers laid the lattice over these vertices in these places: build_grid, and
// fit_near_plane after grid_layout.)
void fill_both(const Executor* executor, const Mesh& upper, const Mesh& lower,
               const Vec3& lower_offset, const Frame& f, Grid* g) {
  auto task = [&](uint32_t jaw) {
    fill_heights_of<true>(jaw == 0 ? upper : lower, jaw == 0 ? Vec3{} : lower_offset, f,
                          static_cast<int>(jaw), g);
  };
  parallel_for_each(executor, 2, task);
}

namespace {

// The least gap (maxilla's height less the mandible's) over the columns that see both jaws;
// infinity when none does.
double least_gap(const Grid& g) {
  const size_t cells = static_cast<size_t>(g.nx) * g.ny;
  double gap_min = HUGE_VAL;
  for (size_t i = 0; i < cells; ++i) {
    if (g.tip[0][i] == kNoTip || g.tip[1][i] == kNoTip) continue;
    const double gap = g.h[0][i] - g.h[1][i];
    gap_min = gap < gap_min ? gap : gap_min;
  }
  return gap_min;
}

bool fit_with_gap(const Grid& g, double gap_min, Plane* plane, uint64_t* contact_cells) {
  const size_t cells = static_cast<size_t>(g.nx) * g.ny;
  double m[3][3] = {}, r[3] = {};
  uint64_t used = 0;
  for (size_t i = 0; i < cells; ++i) {
    if (g.tip[0][i] == kNoTip || g.tip[1][i] == kNoTip) continue;
    if (g.h[0][i] - g.h[1][i] > gap_min + kContactBandMm) continue;
    double x = 0, y = 0;
    g.cell_centre(i, &x, &y);
    const double row[3] = {1, x, y};
    const double mid = 0.5 * (g.h[0][i] + g.h[1][i]);
    for (int a = 0; a < 3; ++a) {
      for (int b = 0; b < 3; ++b) m[a][b] += row[a] * row[b];
      r[a] += row[a] * mid;
    }
    ++used;
  }
  *contact_cells = used;
  double x[3];
  if (used < kMinContactCells || !solve3(m, r, x)) return false;
  plane->a = x[0];
  plane->b = x[1];
  plane->c = x[2];
  return true;
}

// A provisional round's plane (fit_contact_plane of the full grid, bit for bit) from the
// vertices near the occlusal plane only. The fit reads the columns whose gap lies within
// kContactBandMm of the least; a column's gap is at least its maxilla height less the
// mandible's highest vertex (high), and at least the maxilla's lowest (low) less its mandible
// height. So with the maxilla's vertices up to `up` = low + w and the mandible's down to
// `down` = high - w in the grid, where both up - high and low - down exceed the least gap
// (of these columns) plus the band: the column of the least gap has both its extremes in
// the grid (else its gap would exceed that), so the least gap is the full grid's; so does
// every column the fit reads; and a column with a vertex left out whose extreme that is lies
// outside the band either way (its gap only grows). The same columns, heights and sums.
// w: the jaws' overlap along n plus the band plus `slack`, a guess at the least gap (an
// estimate too low costs a second pass over the vertices up to the window it shows is
// enough).
constexpr double kSlackOverGapMm = 0.5;

// `heights`: each vertex's height (grid_layout's), the maxilla's and the mandible's.
bool fit_near_plane(const Executor* executor, const Mesh& upper, const Mesh& lower, const Frame& f,
                    double* const heights[2], double low, double high, double slack, Grid* g,
                    Plane* plane, uint64_t* contact_cells, double* gap_out) {
  clear_heights(0, g);
  clear_heights(1, g);
  double up = -HUGE_VAL, down = HUGE_VAL;
  for (int pass = 0; pass < 2; ++pass) {
    const double w = (high - low) + kContactBandMm + slack;
    const double next_up = low + w, next_down = high - w;
    if (!(next_up > up && next_down < down)) break;  // (no wider: a NaN or an overflow)
    auto task = [&](uint32_t jaw) {
      if (jaw == 0) {
        fill_window<true>(upper, heights[0], up, next_up, f, g);
      } else {
        fill_window<false>(lower, heights[1], down, next_down, f, g);
      }
    };
    parallel_for_each(executor, 2, task);
    up = next_up;
    down = next_down;
    const double gap_min = least_gap(*g);
    if (up - high > gap_min + kContactBandMm && low - down > gap_min + kContactBandMm) {
      *gap_out = gap_min;
      return fit_with_gap(*g, gap_min, plane, contact_cells);
    }
    if (!(gap_min < HUGE_VAL)) break;
    slack = gap_min + kSlackOverGapMm;  // then up - high is about the band plus this
  }
  // Every vertex.
  fill_both(executor, upper, lower, Vec3{}, f, g);
  *gap_out = least_gap(*g);
  return fit_with_gap(*g, *gap_out, plane, contact_cells);
}

}  // namespace

bool fit_contact_plane(const Grid& g, Plane* plane, uint64_t* contact_cells) {
  return fit_with_gap(g, least_gap(g), plane, contact_cells);
}

Status find_frame(const Context& ctx, const Mesh& upper, const Mesh& lower, Frame* f, Grid* g,
                  Plane* plane) {
  Arena& arena = *ctx.arena;
  // The centroids do not depend on the frame: once for every round (one task a jaw).
  Vec3 centroids[2];
  auto centroid = [&](uint32_t jaw) {
    centroids[jaw] = mesh_centroid(jaw == 0 ? upper : lower, Vec3{});
  };
  parallel_for_each(ctx.executor, 2, centroid);
  const Vec3 upper_centroid = centroids[0];
  const Vec3 lower_centroid = centroids[1];
  const Vec3 centre = (upper_centroid + lower_centroid) * 0.5;
  Vec3 n;
  if (!centroid_axis(upper_centroid, lower_centroid, &n)) {
    return Status::error(StatusCode::kInvalidArgument,
                         "outline: the jaws do not face each other: their centres are less "
                         "than 1 mm apart");
  }
  double slack = kSlackOverGapMm;  // jaws in occlusion: a least gap of at most 0
  for (int round = 0; round < kFrameRounds; ++round) {
    Frame provisional;
    complete_frame(n, any_perpendicular(n), &provisional);
    Vec3 anterior;
    SPLINTCORE_RETURN_IF_ERROR(anterior_axis(ctx, upper, lower, centre, provisional, &anterior));
    complete_frame(n, anterior, f);
    ArenaScope scope(arena);
    const bool last = round + 1 == kFrameRounds;
    uint64_t contact = 0;
    bool fitted = false;
    if (last) {
      SPLINTCORE_RETURN_IF_ERROR(build_grid(arena, ctx.executor, upper, lower, Vec3{}, *f, g));
      fitted = fit_contact_plane(*g, plane, &contact);
    } else {
      // The plane only (the grid and the vertices' heights go): from the vertices near the
      // occlusal plane.
      double low = 0, high = 0, gap = 0;
      double* heights[2] = {arena.allocate_array<double>(upper.vertices.size()),
                            arena.allocate_array<double>(lower.vertices.size())};
      if (heights[0] == nullptr || heights[1] == nullptr) return arena.exhausted_status();
      SPLINTCORE_RETURN_IF_ERROR(grid_layout<true>(arena, ctx.executor, upper, lower, Vec3{}, *f, g,
                                                   &low, &high, heights));
      fitted = fit_near_plane(ctx.executor, upper, lower, *f, heights, low, high, slack, g, plane,
                              &contact, &gap);
      slack = gap + kSlackOverGapMm;  // the next round's frame is a little tilted from this
    }
    if (!fitted) {
      return make_error(StatusCode::kInvalidArgument,
                        "outline: the jaws do not face each other: only ", contact,
                        " columns of 0.5 mm see both the maxilla and the mandible across the "
                        "occlusal plane (at least ",
                        kMinContactCells, ")");
    }
    if (last) {
      scope.commit();
      break;
    }
    const Vec3 tilted = n - f->e1 * plane->b - f->e2 * plane->c;
    n = unit(tilted);
  }
  return Status::ok();
}

}  // namespace outline_detail
}  // namespace splintcore
