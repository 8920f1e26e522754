// The swept volume as a height field over the plane across the direction (blockout.h says what
// and why): the first contact of each grid column with the jaws, lowered where the grid's
// interpolation would rise above the jaws, then a triangulated irregular network of right
// triangles (longest-edge bisection) within the tolerance of it, one-sided.
//
// The network's hierarchy over a row of squares of 2^k cells (the grid, a rectangle): square
// (i, j) is cut along its main diagonal into two right triangles when i + j is even, along
// the other one when odd; a right triangle is cut at the midpoint of its hypotenuse into two,
// the midpoint being a grid vertex down to triangles of half a cell. So the cell with
// lower-left corner (i, j) is cut along its main diagonal when i + j is even, along the other
// one when odd, and a square of 2s cells at (2s i, 2s j) likewise, the squares included: one
// lattice over the whole grid, whatever the squares' size. The two
// triangles that share a hypotenuse (a diamond) are cut together, at its midpoint m, when
// E[m] exceeds half the tolerance: E[m] is the most any grid vertex under either departs from
// its plane, and at least E of the diamonds its cut makes (its children), so a triangle that
// stays whole has every grid vertex under it within half the tolerance, and neighbours never
// leave a vertex on one side only (no cracks). Only the comparison is used, so E is exact up
// to half the tolerance and merely known to exceed it beyond (a child's that does, or the
// first vertex found past it): the coarse levels, which the steps cut anyway, scan little.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <utility>

#include "blockout/frame.h"
#include "blockout/offset_ball.h"
#include "core/fminmax.h"
#include "geometry/float_bounds.h"
#include "splintcore/blockout.h"

namespace splintcore {

namespace {

constexpr uint32_t kMaxCells = 4096;
// The relative rounding allowed for in a plane's value (a few thousand ulps).
constexpr double kRelative = 1e-12;

struct Grid {
  Frame frame;
  double u0 = 0, v0 = 0;    // local u, v of grid vertex (0, 0)
  double cell = 0;          // mm
  double top = 0;           // local w of the columns that meet nothing below it
  double margin = 0;        // mm: the float32 rounding of the output, covered
  uint32_t nx = 0, ny = 0;  // cells along u and v: whole squares
  uint32_t square = 0;      // the squares' cells a side (a power of two)
  size_t at(uint32_t x, uint32_t y) const { return size_t{y} * (nx + 1) + x; }
  size_t vertices() const { return size_t{nx + 1} * (ny + 1); }
  uint32_t span() const { return nx > ny ? nx : ny; }
};

// A jaw triangle in grid coordinates (x = (u - u0) / cell, y likewise, w in mm),
// counter-clockwise.
struct GridTriangle {
  double x[3], y[3], w[3];
  double wmin, wmax;
  double gx, gy;  // the plane's slope per grid unit
  double slack;   // rounding of plane() allowed for
  bool ill;       // nearly vertical: its plane is not evaluated, wmin stands for it
  double plane(double px, double py) const { return w[0] + gx * (px - x[0]) + gy * (py - y[0]); }
  // A value at most the triangle's height at a point of it (px, py).
  double below(double px, double py) const {
    if (ill) return wmin;
    const double p = plane(px, py) - slack;
    return p > wmin ? p : wmin;
  }
};

Status check_heightfield_arguments(const SweepOptions& o, const HeightfieldOptions& ho,
                                   const Mesh& out) {
  if (!out.vertices.empty() || !out.triangles.empty()) {
    return make_error(StatusCode::kInvalidArgument, "heightfield: the output mesh must be empty");
  }
  if (!o.has_region || o.region.empty() || !is_finite(o.region.lo) || !is_finite(o.region.hi)) {
    return make_error(StatusCode::kInvalidArgument,
                      "heightfield: a finite, non-empty region is needed");
  }
  if (!(o.voxel > 0) || !std::isfinite(o.voxel)) {
    return make_error(StatusCode::kInvalidArgument, "heightfield: the voxel must be > 0 (mm)");
  }
  if (!(ho.tolerance > 0) || !(ho.tolerance <= o.voxel)) {
    return make_error(StatusCode::kInvalidArgument, "heightfield: the tolerance (", ho.tolerance,
                      " mm) must be > 0 and at most the voxel (", o.voxel, " mm)");
  }
  if (!(o.offset >= 0) || !(o.offset <= 20 * o.voxel) || o.inset != 0 || o.closing_radius != 0) {
    return make_error(StatusCode::kInvalidArgument, "heightfield: the offset (", o.offset,
                      " mm) must be >= 0 and at most 20 voxels; no inset or closing");
  }
  if (!(ho.lower >= 0) || !std::isfinite(ho.lower) || !(ho.shift_u >= 0 && ho.shift_u < 1) ||
      !(ho.shift_v >= 0 && ho.shift_v < 1)) {
    return make_error(StatusCode::kInvalidArgument,
                      "heightfield: lower must be >= 0 mm and the shifts in [0, 1)");
  }
  return Status::ok();
}

// The grid over the region's shadow (its eight corners in the local frame) and two cells more
// (three with a shift): squares of the largest power of two cells a side that is at most an
// eighth of the longer side (at least 1), as many along u and along v as cover it (so the grid
// is at most an eighth longer than needed along either side: a square grid over a long
// region's shadow held mostly columns that meet nothing).
Status make_grid(const SweepOptions& o, const HeightfieldOptions& ho, Grid* g) {
  SPLINTCORE_RETURN_IF_ERROR(make_frame(o.direction, &g->frame));
  Aabb local;
  double largest = 0;
  for (int k = 0; k < 8; ++k) {
    const Vec3 c{(k & 1) ? o.region.hi.x : o.region.lo.x, (k & 2) ? o.region.hi.y : o.region.lo.y,
                 (k & 4) ? o.region.hi.z : o.region.lo.z};
    local.add(to_local(g->frame, c));
    largest = max_of(largest, max3_of(std::fabs(c.x), std::fabs(c.y), std::fabs(c.z)));
  }
  g->cell = o.voxel;
  const double across_u = (local.hi.x - local.lo.x) / o.voxel + 5.0;
  const double across_v = (local.hi.y - local.lo.y) / o.voxel + 5.0;
  const double across = max_of(across_u, across_v);
  if (!(across <= kMaxCells)) {
    return make_error(StatusCode::kLimitExceeded, "heightfield: the region is ", across,
                      " voxels across, at most ", kMaxCells,
                      " are taken: a larger voxel or a smaller region");
  }
  uint32_t square = 1;
  while (2.0 * square <= across / 8) square *= 2;
  g->square = square;
  g->nx = square * static_cast<uint32_t>(std::ceil(across_u / square));
  g->ny = square * static_cast<uint32_t>(std::ceil(across_v / square));
  g->u0 = local.lo.x - (2 + ho.shift_u) * o.voxel;
  g->v0 = local.lo.y - (2 + ho.shift_v) * o.voxel;
  g->top = local.hi.z + 2 * o.voxel + 1.0;
  // Grid points reach a few cells and the top beyond the region: the largest coordinate of
  // the output is below largest + its diagonal, whose float32 rounding is below 2^-24 of it.
  const double reach = largest + (local.hi.x - local.lo.x) + (local.hi.y - local.lo.y) +
                       (local.hi.z - local.lo.z) + 8 * o.voxel + 2.0;
  g->margin = std::ldexp(reach, -20);
  return Status::ok();
}

// Corners in the local frame (mm) into grid coordinates, as given.
void to_grid(const Grid& g, const Vec3 p[3], GridTriangle* q) {
  for (int k = 0; k < 3; ++k) {
    q->x[k] = (p[k].x - g.u0) / g.cell;
    q->y[k] = (p[k].y - g.v0) / g.cell;
    q->w[k] = p[k].z;
  }
}

// Corners 1 and 2 swapped: the other turn.
void swap_turn(GridTriangle* q) {
  std::swap(q->x[1], q->x[2]);
  std::swap(q->y[1], q->y[2]);
  std::swap(q->w[1], q->w[2]);
}

// Whether q's shadow (its corners in grid coordinates), grown by `margin` cells, meets the grid.
bool meets_grid(const Grid& g, const GridTriangle& q, double margin) {
  const double xlo = min3_of(q.x[0], q.x[1], q.x[2]);
  const double xhi = max3_of(q.x[0], q.x[1], q.x[2]);
  const double ylo = min3_of(q.y[0], q.y[1], q.y[2]);
  const double yhi = max3_of(q.y[0], q.y[1], q.y[2]);
  return !(xhi + margin < 0 || yhi + margin < 0 || xlo - margin > static_cast<double>(g.nx) ||
           ylo - margin > static_cast<double>(g.ny));
}

// The rest of q from its corners (counter-clockwise); false when its shadow misses the grid.
bool finish_triangle(const Grid& g, GridTriangle* out) {
  GridTriangle& q = *out;
  if (!meets_grid(g, q, 0)) return false;
  q.wmin = min3_of(q.w[0], q.w[1], q.w[2]);
  q.wmax = max3_of(q.w[0], q.w[1], q.w[2]);
  const double ax = q.x[1] - q.x[0], ay = q.y[1] - q.y[0];
  const double bx = q.x[2] - q.x[0], by = q.y[2] - q.y[0];
  const double aw = q.w[1] - q.w[0], bw = q.w[2] - q.w[0];
  const double area2 = ax * by - ay * bx;
  q.ill = !(area2 > 1e-9);
  q.gx = q.ill ? 0 : (aw * by - bw * ay) / area2;
  q.gy = q.ill ? 0 : (bw * ax - aw * bx) / area2;
  q.slack = kRelative * (std::fabs(q.w[0]) +
                         (std::fabs(q.gx) + std::fabs(q.gy)) * (static_cast<double>(g.span()) + 2));
  return true;
}

// Jaw triangle t of jaw j in the local frame (p) and in grid coordinates; false when it does
// not face against d (exactly: its shadow turns clockwise seen from +w) or, without an
// offset, its shadow misses the grid. With an offset only q's corners are set (its pieces are
// what the passes take).
bool grid_triangle(const Grid& g, const SweepOptions& o, Span<const Mesh> jaws, size_t j,
                   const Triangle& t, Vec3 p[3], GridTriangle* q) {
  for (int k = 0; k < 3; ++k) p[k] = to_local(g.frame, jaw_point(o, jaws, j, t.v[k]));
  to_grid(g, p, q);
  // Facing against d (w) is clockwise seen from +w; the rest cannot be a first contact.
  if (orient2d(q->x[0], q->y[0], q->x[1], q->y[1], q->x[2], q->y[2]) >= 0) return false;
  swap_turn(q);
  return o.offset > 0 || finish_triangle(g, q);
}

// A piece of the offset (offset_ball.h) in grid coordinates; false when its shadow has no
// area (a vertical piece: its lowest points are its neighbours') or misses the grid.
bool piece_triangle(const Grid& g, const Vec3& a, const Vec3& b, const Vec3& c, GridTriangle* q) {
  const Vec3 p[3] = {a, b, c};
  to_grid(g, p, q);
  const double side = orient2d(q->x[0], q->y[0], q->x[1], q->y[1], q->x[2], q->y[2]);
  if (side == 0) return false;
  if (side < 0) swap_turn(q);
  return finish_triangle(g, q);
}

// The index range of grid lines [lo, hi] meets, within 0 .. n; false when none.
bool line_range(double lo, double hi, uint32_t n, uint32_t* first, uint32_t* last) {
  const double a = std::ceil(lo), b = std::floor(hi);
  if (b < 0 || a > static_cast<double>(n) || a > b) return false;
  *first = a < 0 ? 0 : static_cast<uint32_t>(a);
  *last = b > static_cast<double>(n) ? n : static_cast<uint32_t>(b);
  return true;
}

// Pass 1: h at every grid vertex, the least height of the jaw triangles whose shadow holds
// it (closed, exact orient2d), at most the top.
void first_contact(const Grid& g, const GridTriangle& q, double* h) {
  uint32_t x0, x1, y0, y1;
  if (!line_range(min3_of(q.x[0], q.x[1], q.x[2]), max3_of(q.x[0], q.x[1], q.x[2]), g.nx, &x0,
                  &x1) ||
      !line_range(min3_of(q.y[0], q.y[1], q.y[2]), max3_of(q.y[0], q.y[1], q.y[2]), g.ny, &y0,
                  &y1)) {
    return;
  }
  for (uint32_t y = y0; y <= y1; ++y) {
    const double py = y;
    for (uint32_t x = x0; x <= x1; ++x) {
      const double px = x;
      // below() is at least wmin: a vertex already at or under it keeps its h.
      if (!(q.wmin < h[g.at(x, y)])) continue;
      if (orient2d(q.x[0], q.y[0], q.x[1], q.y[1], px, py) < 0 ||
          orient2d(q.x[1], q.y[1], q.x[2], q.y[2], px, py) < 0 ||
          orient2d(q.x[2], q.y[2], q.x[0], q.y[0], px, py) < 0) {
        continue;
      }
      const double w = q.below(px, py);
      const size_t k = g.at(x, y);
      if (w < h[k]) h[k] = w;
    }
  }
}

// The convex polygon p (count corners, counter-clockwise) clipped to the left of a -> b.
int clip_left(const double* px, const double* py, int count, double ax, double ay, double bx,
              double by, double* ox, double* oy) {
  int out = 0;
  const double ex = bx - ax, ey = by - ay;
  for (int i = 0; i < count; ++i) {
    const int k = i + 1 == count ? 0 : i + 1;
    const double si = ex * (py[i] - ay) - ey * (px[i] - ax);
    const double sk = ex * (py[k] - ay) - ey * (px[k] - ax);
    if (si >= 0) {
      ox[out] = px[i];
      oy[out++] = py[i];
    }
    if ((si >= 0) != (sk >= 0)) {
      const double t = si / (si - sk);
      ox[out] = px[i] + t * (px[k] - px[i]);
      oy[out++] = py[i] + t * (py[k] - py[i]);
    }
  }
  return out;
}

// The plane through a half cell's corners (cx, cy: counter-clockwise, their h), with the
// rounding allowed for in its value.
struct CellPlane {
  double x0, y0, h0, hx, hy, slack;
  CellPlane(const double* cx, const double* cy, const double* ch)
      : x0(cx[0]), y0(cy[0]), h0(ch[0]) {
    // The half cell's legs are unit steps, its doubled area +-1.
    const double ux = cx[1] - cx[0], uy = cy[1] - cy[0], vx = cx[2] - cx[0], vy = cy[2] - cy[0];
    const double uh = ch[1] - ch[0], vh = ch[2] - ch[0];
    const double area2 = ux * vy - uy * vx;  // exactly +-1: times it is over it, bit for bit
    hx = (uh * vy - vh * uy) * area2;
    hy = (vh * ux - uh * vx) * area2;
    slack = kRelative * (std::fabs(ch[0]) + std::fabs(ch[1]) + std::fabs(ch[2]) + std::fabs(hx) +
                         std::fabs(hy));
  }
  double at(double x, double y) const { return h0 + hx * (x - x0) + hy * (y - y0); }
};

// At least the most rise_above(q, c) can give: its rise is at most the linear
// (plane + slack) - (q's plane - q's slack) (or - wmin when q is ill), whose most over the
// overlap (inside q) is at one of q's corners, where q's value is qp (q.plane there, or wmin).
// The allowance doubles both slacks and adds the plane's value's rounding out to q's corners
// (up to the grid's span away). At most 0: the half cell's plane stays below q wherever they
// overlap. Pieces of a clearance are small and steep: the corners of the half cell often see
// their planes cross where the two do not overlap.
double most_rise(const GridTriangle& q, const double* qp, const CellPlane& c, double span) {
  double most = -HUGE_VAL;
  for (int k = 0; k < 3; ++k) {
    const double d = c.at(q.x[k], q.y[k]) - qp[k];
    most = d > most ? d : most;
  }
  const double allowance =
      2 * (c.slack + q.slack + kRelative * (std::fabs(c.hx) + std::fabs(c.hy)) * (span + 2));
  return most + allowance;
}

// How far the plane c through the half cell's corners (cx, cy: counter-clockwise) rises above
// jaw triangle q where the two overlap (0 when nowhere), rounding included.
double rise_above(const GridTriangle& q, const double* cx, const double* cy, const CellPlane& c) {
  double ax[9], ay[9], bx[9], by[9];
  int count = clip_left(q.x, q.y, 3, cx[0], cy[0], cx[1], cy[1], ax, ay);
  count = clip_left(ax, ay, count, cx[1], cy[1], cx[2], cy[2], bx, by);
  count = clip_left(bx, by, count, cx[2], cy[2], cx[0], cy[0], ax, ay);
  if (count == 0) return 0;
  double most = 0;
  for (int i = 0; i < count; ++i) {
    const double rise = c.at(ax[i], ay[i]) + c.slack - q.below(ax[i], ay[i]);
    if (rise > most) most = rise;
  }
  return most;
}

// The two half cells of cell (i, j), each as three corners counter-clockwise.
void half_cells(uint32_t i, uint32_t j, uint32_t corner[2][3][2]) {
  const uint32_t a[2] = {i, j}, b[2] = {i + 1, j}, c[2] = {i + 1, j + 1}, d[2] = {i, j + 1};
  const uint32_t* order[2][3];
  if (((i + j) & 1u) == 0) {  // main diagonal a-c
    order[0][0] = a, order[0][1] = b, order[0][2] = c;
    order[1][0] = a, order[1][1] = c, order[1][2] = d;
  } else {  // b-d
    order[0][0] = a, order[0][1] = b, order[0][2] = d;
    order[1][0] = b, order[1][1] = c, order[1][2] = d;
  }
  for (int h = 0; h < 2; ++h) {
    for (int k = 0; k < 3; ++k) {
      corner[h][k][0] = order[h][k][0];
      corner[h][k][1] = order[h][k][1];
    }
  }
}

// Pass 2: every half cell under jaw triangle q clipped against it; its corners' lowering
// raised to how far their plane rises above q there (float, rounded up).
void lower_under(const Grid& g, const GridTriangle& q, const double* h, float* low,
                 HeightfieldStats* st) {
  uint32_t x0, x1, y0, y1;
  const double xlo = min3_of(q.x[0], q.x[1], q.x[2]);
  const double xhi = max3_of(q.x[0], q.x[1], q.x[2]);
  const double ylo = min3_of(q.y[0], q.y[1], q.y[2]);
  const double yhi = max3_of(q.y[0], q.y[1], q.y[2]);
  if (!line_range(std::floor(xlo), std::ceil(xhi) - 1, g.nx - 1, &x0, &x1) ||
      !line_range(std::floor(ylo), std::ceil(yhi) - 1, g.ny - 1, &y0, &y1)) {
    return;
  }
  double qp[3];  // q's value at its corners, as most_rise takes it
  for (int k = 0; k < 3; ++k) qp[k] = q.ill ? q.wmin : q.plane(q.x[k], q.y[k]);
  const double span = static_cast<double>(g.span());
  uint32_t corner[2][3][2];
  for (uint32_t j = y0; j <= y1; ++j) {
    for (uint32_t i = x0; i <= x1; ++i) {
      half_cells(i, j, corner);
      for (int hc = 0; hc < 2; ++hc) {
        double cx[3], cy[3], ch[3];
        size_t id[3];
        for (int k = 0; k < 3; ++k) {
          cx[k] = corner[hc][k][0];
          cy[k] = corner[hc][k][1];
          id[k] = g.at(corner[hc][k][0], corner[hc][k][1]);
          ch[k] = h[id[k]];
        }
        // The corners' plane nowhere above q's over the whole half cell (both linear: at
        // its corners): nothing to clip.
        if (!q.ill) {
          double most = -HUGE_VAL;
          for (int k = 0; k < 3; ++k) {
            const double d = ch[k] + kRelative * std::fabs(ch[k]) - q.plane(cx[k], cy[k]);
            most = d > most ? d : most;
          }
          if (most + q.slack <= 0) continue;
        }
        const CellPlane plane(cx, cy, ch);
        const double most = most_rise(q, qp, plane, span);
        if (most <= 0) continue;
        ++st->clipped_pairs;
        // Not clipped when even that most could not lower a corner further (the lowering
        // takes the most, in any order: the same lowering).
        const float bound = float_up(most);
        if (bound <= low[id[0]] && bound <= low[id[1]] && bound <= low[id[2]]) {
          continue;
        }
        const double rise = rise_above(q, cx, cy, plane);
        if (!(rise > 0)) continue;
        const float f = float_up(rise);
        for (size_t k : id) {
          if (f > low[k]) low[k] = f;
        }
      }
    }
  }
}

// What one share of a pass writes: h and low (the first share the grid's; a second share, on
// the executor's other thread, its own copies, merged after the pass), the pass's counts.
struct PassShare {
  double* h = nullptr;
  float* low = nullptr;
  HeightfieldStats st;
};

// One pass over a triangle (the jaw's or an offset piece).
void pass_over(const Grid& g, const GridTriangle& q, bool lowering, PassShare* s) {
  if (lowering) {
    lower_under(g, q, s->h, s->low, &s->st);
  } else {
    first_contact(g, q, s->h);
  }
}

// Calls visit(j, p, q) for each front triangle of jaw j (p its corners in the local frame, as
// the jaw turns them; q in grid coordinates, counter-clockwise, only without an offset) among
// the jaws' triangles numbered begin .. end - 1 (all jaws in order), in that order, with the
// vertex ids checked.
template <typename Visit>
Status each_front(const Grid& g, Span<const Mesh> jaws, const SweepOptions& o, uint64_t begin,
                  uint64_t end, Visit visit) {
  GridTriangle q{};
  Vec3 p[3];
  uint64_t first = 0;  // the number of jaw j's first triangle
  for (size_t j = 0; j < jaws.size() && first < end; ++j) {
    const Mesh& jaw = jaws[j];
    const size_t n = jaw.triangles.size();
    // (Both at most n.)
    const size_t from = begin > first ? static_cast<size_t>(begin - first) : 0;
    const size_t to = end - first < n ? static_cast<size_t>(end - first) : n;
    for (size_t t = from; t < to; ++t) {
      const Triangle& tri = jaw.triangles[t];
      if (tri.v[0] >= jaw.vertices.size() || tri.v[1] >= jaw.vertices.size() ||
          tri.v[2] >= jaw.vertices.size()) {
        return make_error(StatusCode::kInvalidMesh, "heightfield: triangle ", t, " of jaw ", j,
                          " refers to a vertex that does not exist")
            .at_index(t);
      }
      if (grid_triangle(g, o, jaws, j, tri, p, &q)) visit(j, tri, p, q);
    }
    first += n;
  }
  return Status::ok();
}

// work(share, begin, end) over items 0 .. total - 1 in chunks of `chunk`, the progress
// reported before each. With two shares each chunk's two halves run side by side on the
// executor, the first half the first share's. The first error in item order: a share stops at
// its first, and the first share's comes before the second's, as a serial run meets them.
template <typename Work>
Status in_chunks(const Context& ctx, uint64_t total, uint64_t chunk, uint32_t shares, Work work) {
  for (uint64_t b = 0; b < total; b += chunk) {
    SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "heightfield", b, total));
    const uint64_t e = total - b < chunk ? total : b + chunk;
    if (shares == 1) {
      SPLINTCORE_RETURN_IF_ERROR(work(uint32_t{0}, b, e));
      continue;
    }
    const uint64_t mid = b + (e - b) / 2;
    Status status[2];
    auto task = [&](uint32_t i) { status[i] = work(i, i == 0 ? b : mid, i == 0 ? mid : e); };
    parallel_for_each(ctx.executor, 2, task);
    SPLINTCORE_RETURN_IF_ERROR(status[0]);
    SPLINTCORE_RETURN_IF_ERROR(status[1]);
  }
  return Status::ok();
}

uint64_t triangle_count_of(Span<const Mesh> jaws) {
  uint64_t n = 0;
  for (const Mesh& m : jaws) n += m.triangles.size();
  return n;
}

// The chunks of the passes: about the same work for both (some 30 pieces a triangle).
uint64_t pass_chunk(const SweepOptions& o) { return o.offset > 0 ? 0x1000 : 0x10000; }

// Pass 1 (first contacts) or 2 (lowering) over the jaws' front triangles.
Status rasterize(const Context& ctx, const Grid& g, Span<const Mesh> jaws, const SweepOptions& o,
                 bool lowering, PassShare* shares, uint32_t count) {
  auto work = [&](uint32_t i, uint64_t begin, uint64_t end) {
    PassShare* s = &shares[i];
    return each_front(g, jaws, o, begin, end,
                      [&](size_t, const Triangle&, const Vec3*, const GridTriangle& q) {
                        if (!lowering) ++s->st.triangles_in;
                        pass_over(g, q, lowering, s);
                      });
  };
  return in_chunks(ctx, triangle_count_of(jaws), pass_chunk(o), count, work);
}

// The offset: the polytope, and for each jaw vertex (all jaws in order) the faces of Q that its
// front triangles near the grid all leave to it (offset_ball.h: support_faces), kSeen marking
// the vertices of such triangles.
struct Offset {
  static constexpr uint32_t kSeen = 1u << 31;
  const OffsetBall* ball = nullptr;
  uint32_t* faces = nullptr;
};

size_t first_vertex(Span<const Mesh> jaws, size_t j) {
  size_t first = 0;
  for (size_t i = 0; i < j; ++i) first += jaws[i].vertices.size();
  return first;
}

// The vertices' faces (Offset::faces, zeroed), and the front triangles counted (serial: a
// vertex's faces are those all its triangles leave).
Status offset_faces(const Context& ctx, const Grid& g, Span<const Mesh> jaws, const SweepOptions& o,
                    const Offset& offset, HeightfieldStats* st) {
  auto work = [&](uint32_t, uint64_t begin, uint64_t end) {
    size_t jaw = 0, first = 0;
    return each_front(g, jaws, o, begin, end,
                      [&](size_t j, const Triangle& tri, const Vec3* p, const GridTriangle& q) {
                        if (!meets_grid(g, q, offset.ball->reach / g.cell + 1)) return;
                        ++st->triangles_in;
                        if (j != jaw) jaw = j, first = first_vertex(jaws, j);
                        for (int k = 0; k < 3; ++k) {
                          uint32_t& f = offset.faces[first + tri.v[k]];
                          const uint32_t mine = support_faces(*offset.ball, p, k) | Offset::kSeen;
                          f = (f & Offset::kSeen) != 0 ? (f & mine) : mine;
                        }
                      });
  };
  return in_chunks(ctx, triangle_count_of(jaws), pass_chunk(o), 1, work);
}

// A share's pass over the offset's pieces as they are emitted.
struct PieceSink {
  const Grid& g;
  bool lowering;
  PassShare* s;
  GridTriangle q{};
  void operator()(const Vec3& a, const Vec3& b, const Vec3& c) {
    if (!lowering) ++s->st.offset_pieces;
    if (piece_triangle(g, a, b, c, &q)) pass_over(g, q, lowering, s);
  }
};

// Pass 1 or 2 over the offset's pieces: those of the front triangles near the grid and their
// edges, then those of the vertices (their faces; all jaws' vertices numbered in order).
Status rasterize_offset(const Context& ctx, const Grid& g, Span<const Mesh> jaws,
                        const SweepOptions& o, const Offset& offset, bool lowering,
                        PassShare* shares, uint32_t count) {
  const OffsetBall& ball = *offset.ball;
  auto triangles = [&](uint32_t i, uint64_t begin, uint64_t end) {
    PieceSink piece{g, lowering, &shares[i]};
    return each_front(g, jaws, o, begin, end,
                      [&](size_t, const Triangle&, const Vec3* p, const GridTriangle& t) {
                        if (meets_grid(g, t, ball.reach / g.cell + 1)) {
                          triangle_pieces(ball, p, piece);
                        }
                      });
  };
  SPLINTCORE_RETURN_IF_ERROR(
      in_chunks(ctx, triangle_count_of(jaws), pass_chunk(o), count, triangles));
  auto vertices = [&](uint32_t i, uint64_t begin, uint64_t end) {
    PieceSink piece{g, lowering, &shares[i]};
    uint64_t first = 0;  // the number of jaw j's first vertex
    for (size_t j = 0; j < jaws.size() && first < end; ++j) {
      const size_t n = jaws[j].vertices.size();
      // (Both at most n.)
      const size_t from = begin > first ? static_cast<size_t>(begin - first) : 0;
      const size_t to = end - first < n ? static_cast<size_t>(end - first) : n;
      for (size_t v = from; v < to; ++v) {
        const uint32_t f = offset.faces[first + v] & ~Offset::kSeen;
        if (f != 0) vertex_pieces(ball, to_local(g.frame, jaw_point(o, jaws, j, v)), f, piece);
      }
      first += n;
    }
    return Status::ok();
  };
  return in_chunks(ctx, first_vertex(jaws, jaws.size()), pass_chunk(o), count, vertices);
}

// ---- the network

struct Tri {
  uint32_t a[2], b[2], c[2];  // b the right angle, a-c the hypotenuse
};

// The most a grid vertex of triangle t departs from the plane through its corners (h), or
// the first departure found above `limit` (all the network asks is whether it exceeds it).
double departure(const Grid& g, const double* h, const Tri& t, double limit) {
  const int64_t ax = t.a[0], ay = t.a[1], bx = t.b[0], by = t.b[1], cx = t.c[0], cy = t.c[1];
  const double ha = h[g.at(t.a[0], t.a[1])], hb = h[g.at(t.b[0], t.b[1])];
  const double hc = h[g.at(t.c[0], t.c[1])];
  const int64_t area2 = (bx - ax) * (cy - ay) - (by - ay) * (cx - ax);
  const double inv = 1.0 / static_cast<double>(area2);
  const double gx =
      ((hb - ha) * static_cast<double>(cy - ay) - (hc - ha) * static_cast<double>(by - ay)) * inv;
  const double gy =
      ((hc - ha) * static_cast<double>(bx - ax) - (hb - ha) * static_cast<double>(cx - ax)) * inv;
  const int64_t x0 = std::min(ax, std::min(bx, cx)), x1 = std::max(ax, std::max(bx, cx));
  const int64_t y0 = std::min(ay, std::min(by, cy)), y1 = std::max(ay, std::max(by, cy));
  const int64_t s = area2 > 0 ? 1 : -1;
  double most = 0;
  for (int64_t y = y0; y <= y1; ++y) {
    for (int64_t x = x0; x <= x1; ++x) {
      if (s * ((bx - ax) * (y - ay) - (by - ay) * (x - ax)) < 0 ||
          s * ((cx - bx) * (y - by) - (cy - by) * (x - bx)) < 0 ||
          s * ((ax - cx) * (y - cy) - (ay - cy) * (x - cx)) < 0) {
        continue;
      }
      const double p = ha + gx * static_cast<double>(x - ax) + gy * static_cast<double>(y - ay);
      const double d = std::fabs(h[g.at(static_cast<uint32_t>(x), static_cast<uint32_t>(y))] - p);
      if (d > most) most = d;
    }
    if (most > limit) return most;
  }
  return most;
}

inline void raise_to(float* e, size_t at, double value) {
  const float f = float_up(value);
  if (f > e[at]) e[at] = f;
}

// E of the axis diamonds of half length s (hypotenuse along x, dir 0, or y, dir 1): m on a
// line of the 2s lattice halfway between two of its points; their children are the diagonal
// diamonds of half size s / 2. E above `limit` is only known to be above it: a child's above
// it is the diamond's, and its own triangles are then not scanned.
void axis_diamonds(const Grid& g, const double* h, uint32_t s, int dir, double limit, float* e) {
  const uint32_t s2 = 2 * s;
  const uint32_t lines = dir == 0 ? g.ny : g.nx, along = dir == 0 ? g.nx : g.ny;
  for (uint32_t p = 0; p <= lines; p += s2) {   // the line
    for (uint32_t r = s; r < along; r += s2) {  // halfway along it
      const uint32_t mx = dir == 0 ? r : p, my = dir == 0 ? p : r;
      const size_t m = g.at(mx, my);
      Tri t[2];
      int sides = 0;
      for (int side = -1; side <= 1; side += 2) {
        const int64_t ox = dir == 0 ? 0 : side * int64_t{s};
        const int64_t oy = dir == 0 ? side * int64_t{s} : 0;
        const int64_t apx = mx + ox, apy = my + oy;
        if (apx < 0 || apy < 0 || apx > g.nx || apy > g.ny) continue;
        Tri& u = t[sides++];
        u.a[0] = dir == 0 ? mx - s : mx, u.a[1] = dir == 0 ? my : my - s;
        u.c[0] = dir == 0 ? mx + s : mx, u.c[1] = dir == 0 ? my : my + s;
        u.b[0] = static_cast<uint32_t>(apx), u.b[1] = static_cast<uint32_t>(apy);
        if (s < 2) continue;  // its children are half cells
        for (int k = -1; k <= 1; k += 2) {
          const int64_t cx = mx + (dir == 0 ? k * int64_t{s / 2} : ox / 2);
          const int64_t cy = my + (dir == 0 ? oy / 2 : k * int64_t{s / 2});
          const float child = e[g.at(static_cast<uint32_t>(cx), static_cast<uint32_t>(cy))];
          if (child > e[m]) e[m] = child;
        }
      }
      for (int i = 0; i < sides && !(static_cast<double>(e[m]) > limit); ++i) {
        raise_to(e, m, departure(g, h, t[i], limit));
      }
    }
  }
}

// E of the diagonal diamonds of half size s: m the centre of a square of 2s cells at
// (2s i, 2s j), cut along its main diagonal when i + j is even; their children are the axis
// diamonds of half length s around m. (Above `limit` as axis_diamonds.)
void diagonal_diamonds(const Grid& g, const double* h, uint32_t s, double limit, float* e) {
  const uint32_t s2 = 2 * s;
  for (uint32_t my = s; my < g.ny; my += s2) {
    for (uint32_t mx = s; mx < g.nx; mx += s2) {
      const size_t m = g.at(mx, my);
      const uint32_t child[4][2] = {{mx - s, my}, {mx + s, my}, {mx, my - s}, {mx, my + s}};
      for (const auto& c : child) {
        const float v = e[g.at(c[0], c[1])];
        if (v > e[m]) e[m] = v;
      }
      const bool main = (((mx / s2) + (my / s2)) & 1u) == 0;
      Tri t;
      t.a[0] = mx - s, t.a[1] = main ? my - s : my + s;
      t.c[0] = mx + s, t.c[1] = main ? my + s : my - s;
      for (int side = 0; side < 2 && !(static_cast<double>(e[m]) > limit); ++side) {
        t.b[0] = side == 0 ? mx + s : mx - s;
        t.b[1] = main ? (side == 0 ? my - s : my + s) : (side == 0 ? my + s : my - s);
        raise_to(e, m, departure(g, h, t, limit));
      }
    }
  }
}

// E[m] of every diamond, level by level from the finest up to the squares' own.
void diamond_errors(const Grid& g, const double* h, double limit, float* e) {
  std::memset(e, 0, sizeof(float) * g.vertices());
  for (uint32_t s = 1; s < g.square; s *= 2) {
    axis_diamonds(g, h, s, 0, limit, e);
    axis_diamonds(g, h, s, 1, limit, e);
    diagonal_diamonds(g, h, s, limit, e);
  }
}

// The part of the network in the square of g.square cells at (x0, y0): its two halves (cut
// along the main diagonal when the square's i + j is even), each cut while its diamond's
// error exceeds `limit`, depth first (the first child first); visit(t) for each triangle kept.
template <typename Visit>
void walk_square(const Grid& g, const float* e, double limit, uint32_t x0, uint32_t y0,
                 Visit visit) {
  const uint32_t x1 = x0 + g.square, y1 = y0 + g.square;
  Tri stack[64];
  int top = 0;
  if ((((x0 / g.square) + (y0 / g.square)) & 1u) == 0) {
    stack[top++] = Tri{{x1, y1}, {x0, y1}, {x0, y0}};
    stack[top++] = Tri{{x0, y0}, {x1, y0}, {x1, y1}};
  } else {
    stack[top++] = Tri{{x1, y0}, {x1, y1}, {x0, y1}};
    stack[top++] = Tri{{x0, y1}, {x0, y0}, {x1, y0}};
  }
  while (top > 0) {
    const Tri t = stack[--top];
    const uint32_t dx = t.a[0] > t.c[0] ? t.a[0] - t.c[0] : t.c[0] - t.a[0];
    const uint32_t dy = t.a[1] > t.c[1] ? t.a[1] - t.c[1] : t.c[1] - t.a[1];
    const bool leaf = dx == 1 && dy == 1;
    const uint32_t m[2] = {(t.a[0] + t.c[0]) / 2, (t.a[1] + t.c[1]) / 2};
    if (leaf || !(static_cast<double>(e[g.at(m[0], m[1])]) > limit)) {
      visit(t);
      continue;
    }
    // Second child pushed first, so the first is walked first.
    stack[top++] = Tri{{t.b[0], t.b[1]}, {m[0], m[1]}, {t.c[0], t.c[1]}};
    stack[top++] = Tri{{t.a[0], t.a[1]}, {m[0], m[1]}, {t.b[0], t.b[1]}};
  }
}

// Walks the network: square by square (along u, then v), the two halves of each, each cut
// while its diamond's error exceeds `limit`, depth first (the first child first); visit(t) for
// each triangle kept.
template <typename Visit>
void walk_network(const Grid& g, const float* e, double limit, Visit visit) {
  for (uint32_t y0 = 0; y0 < g.ny; y0 += g.square) {
    for (uint32_t x0 = 0; x0 < g.nx; x0 += g.square) {
      walk_square(g, e, limit, x0, y0, visit);
    }
  }
}

// The network as a mesh: vertices numbered by first use, triangles oriented against w.
Status build_network(const Context& ctx, const Grid& g, const double* h, const float* e,
                     double limit, bool float32, Mesh* out) {
  Arena& arena = *ctx.arena;
  const size_t count = g.vertices();
  uint32_t* id = arena.allocate_array<uint32_t>(count);
  if (id == nullptr) return arena.exhausted_status();
  std::memset(id, 0xff, count * sizeof(uint32_t));
  uint32_t vertices = 0;
  size_t triangles = 0;
  walk_network(g, e, limit, [&](const Tri& t) {
    for (const uint32_t* p : {t.a, t.b, t.c}) {
      uint32_t& slot = id[g.at(p[0], p[1])];
      if (slot == UINT32_MAX) slot = vertices++;
    }
    ++triangles;
  });
  out->bind(&arena);
  if (!out->vertices.resize(vertices) || !out->triangles.resize(triangles)) {
    return arena.exhausted_status();
  }
  for (uint32_t y = 0; y <= g.ny; ++y) {
    for (uint32_t x = 0; x <= g.nx; ++x) {
      const size_t k = g.at(x, y);
      if (id[k] == UINT32_MAX) continue;
      Vec3 p = to_world(g.frame, Vec3{g.u0 + g.cell * x, g.v0 + g.cell * y, h[k]});
      if (float32 && !round_to_float32(&p)) {
        return make_error(StatusCode::kLimitExceeded,
                          "heightfield: a vertex is beyond float32 range")
            .at_index(id[k]);
      }
      out->vertices[id[k]] = p;
    }
  }
  size_t k = 0;
  walk_network(g, e, limit, [&](const Tri& t) {
    const int64_t cross = (int64_t{t.b[0]} - t.a[0]) * (int64_t{t.c[1]} - t.a[1]) -
                          (int64_t{t.b[1]} - t.a[1]) * (int64_t{t.c[0]} - t.a[0]);
    const uint32_t ia = id[g.at(t.a[0], t.a[1])], ib = id[g.at(t.b[0], t.b[1])];
    const uint32_t ic = id[g.at(t.c[0], t.c[1])];
    // Counter-clockwise seen from +w has its normal along w: reversed, against it.
    out->triangles[k++] = cross > 0 ? Triangle{{ia, ic, ib}} : Triangle{{ia, ib, ic}};
  });
  return Status::ok();
}

// Every jaw vertex finite (they are read again by each pass).
Status check_jaw_vertices(Span<const Mesh> jaws, const SweepOptions& o) {
  for (size_t j = 0; j < jaws.size(); ++j) {
    for (size_t i = 0; i < jaws[j].vertices.size(); ++i) {
      const Vec3 p = jaw_point(o, jaws, j, i);
      if (!is_finite(p)) {
        return make_error(StatusCode::kNonFinite, "heightfield: jaw ", j,
                          " has a non-finite vertex")
            .at_index(i);
      }
    }
  }
  return Status::ok();
}

// A second share for the passes when the executor has threads and the arena the room (12
// bytes a grid vertex: its h and low), else none (serial; the arena's failure forgotten).
uint32_t second_share(const Context& ctx, size_t count, PassShare* second) {
  if (!has_threads(ctx.executor)) return 1;
  Arena& arena = *ctx.arena;
  const Arena::Marker start = arena.mark();
  second->h = arena.allocate_array<double>(count);
  second->low = arena.allocate_array<float>(count);
  if (second->h == nullptr || second->low == nullptr) {
    arena.rewind(start);
    arena.forget_failure();
    return 1;
  }
  return 2;
}

// The two passes (first contacts, then the lowering) over the jaws' front triangles or, with
// an offset, their pieces, into h (from the top) and low (from 0). With a second share each
// pass runs in halves side by side: pass 1 takes the least h of the two shares, pass 2 the
// most low, both exact and in any order, so h and low are those of a serial run.
Status run_passes(const Context& ctx, const Grid& g, Span<const Mesh> jaws, const SweepOptions& o,
                  double* h, float* low, HeightfieldStats* st) {
  Arena& arena = *ctx.arena;
  ArenaScope scope(arena);  // the offset's arrays and the second share
  const size_t count = g.vertices();
  Offset offset;
  if (o.offset > 0) {
    const size_t vertices = first_vertex(jaws, jaws.size());
    OffsetBall* ball = arena.allocate_array<OffsetBall>(1);
    offset.faces = arena.allocate_array<uint32_t>(vertices);
    if (ball == nullptr || offset.faces == nullptr) return arena.exhausted_status();
    make_offset_ball(o.offset, ball);
    offset.ball = ball;
    std::memset(offset.faces, 0, vertices * sizeof(uint32_t));
    SPLINTCORE_RETURN_IF_ERROR(offset_faces(ctx, g, jaws, o, offset, st));
  }
  PassShare shares[2];
  shares[0].h = h;
  shares[0].low = low;
  const uint32_t n = second_share(ctx, count, &shares[1]);
  if (n == 2) {
    std::fill_n(shares[1].h, count, g.top);
    std::memset(shares[1].low, 0, count * sizeof(float));
  }
  for (int lowering = 0; lowering < 2; ++lowering) {
    SPLINTCORE_RETURN_IF_ERROR(
        o.offset > 0 ? rasterize_offset(ctx, g, jaws, o, offset, lowering != 0, shares, n)
                     : rasterize(ctx, g, jaws, o, lowering != 0, shares, n));
    if (n == 2 && lowering == 0) {
      for (size_t k = 0; k < count; ++k) h[k] = shares[1].h[k] < h[k] ? shares[1].h[k] : h[k];
      shares[1].h = h;  // pass 2 reads the whole h
    } else if (n == 2) {
      for (size_t k = 0; k < count; ++k)
        low[k] = shares[1].low[k] > low[k] ? shares[1].low[k] : low[k];
    }
  }
  for (size_t k = 0; k < count; ++k) st->covered_vertices += h[k] < g.top ? 1 : 0;
  for (uint32_t i = 0; i < n; ++i) {
    st->triangles_in += shares[i].st.triangles_in;
    st->offset_pieces += shares[i].st.offset_pieces;
    st->clipped_pairs += shares[i].st.clipped_pairs;
  }
  return Status::ok();
}

}  // namespace

uint64_t sweep_heightfield_bound(uint32_t cells_u, uint32_t cells_v, uint64_t offset_vertices) {
  const uint64_t offset =
      offset_vertices > 0 ? sizeof(OffsetBall) + 4 * offset_vertices + 2 * Arena::kDefaultAlignment
                          : 0;
  return (uint64_t{cells_u} + 1) * (uint64_t{cells_v} + 1) * 16 + 3 * Arena::kDefaultAlignment +
         offset;
}

Status sweep_heightfield_mesh(const Context& ctx, Span<const Mesh> jaws, const SweepOptions& o,
                              const HeightfieldOptions& ho, Mesh* out, HeightfieldStats* stats) {
  SPLINTCORE_ASSERT(ctx.arena != nullptr && out != nullptr);
  HeightfieldStats local;
  HeightfieldStats* st = stats != nullptr ? stats : &local;
  *st = HeightfieldStats{};
  SPLINTCORE_RETURN_IF_ERROR(check_heightfield_arguments(o, ho, *out));
  size_t triangle_count = 0;
  for (const Mesh& m : jaws) triangle_count += m.triangles.size();
  if (triangle_count == 0) {
    return make_error(StatusCode::kInvalidArgument, "heightfield: the jaws have no triangles");
  }
  Grid g;
  SPLINTCORE_RETURN_IF_ERROR(make_grid(o, ho, &g));
  st->cells_u = g.nx;
  st->cells_v = g.ny;
  st->square_cells = g.square;
  st->axis_u = g.frame.u, st->axis_v = g.frame.v, st->axis_w = g.frame.w;
  SPLINTCORE_RETURN_IF_ERROR(check_jaw_vertices(jaws, o));
  Arena& arena = *ctx.arena;
  ArenaScope scope(arena);
  const size_t count = g.vertices();
  double* h = arena.allocate_array<double>(count);
  float* low = arena.allocate_array<float>(count);
  if (h == nullptr || low == nullptr) return arena.exhausted_status();
  std::fill_n(h, count, g.top);
  std::memset(low, 0, count * sizeof(float));
  SPLINTCORE_RETURN_IF_ERROR(run_passes(ctx, g, jaws, o, h, low, st));
  // The grid lowered by its rises, the margin, half the tolerance and `lower`; low becomes E.
  const double shift = g.margin + 0.5 * ho.tolerance + ho.lower;
  for (size_t k = 0; k < count; ++k) {
    if (low[k] > 0) {
      ++st->lowered_vertices;
      st->max_lowering = max_of(st->max_lowering, static_cast<double>(low[k]));
    }
    h[k] = h[k] - static_cast<double>(low[k]) - shift;
  }
  SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "heightfield", 1, 2));
  float* e = low;
  diamond_errors(g, h, 0.5 * ho.tolerance, e);
  SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "heightfield", 2, 2));
  Mesh built;
  SPLINTCORE_RETURN_IF_ERROR(
      build_network(ctx, g, h, e, 0.5 * ho.tolerance, o.float32_vertices, &built));
  st->network_triangles = built.triangles.size();
  move_mesh_down(arena, scope.start(), built, out, true);
  scope.commit();
  return Status::ok();
}

}  // namespace splintcore
