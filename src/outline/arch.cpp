// The dental arch and the picks of the automatic outline (outline.h): the occlusal columns of
// both jaws, a first centre line through them by sectors around their centre, a second one by
// the mean offset across the arch along the first, and paired picks at even steps along it,
// as wide as the occlusal surfaces plus the overhang, as high as the teeth sink into the wafer.
#include <algorithm>
#include <cmath>
#include <limits>

#include "outline_internal.h"

namespace splintcore {
namespace outline_detail {

namespace {

// A polyline in the plane with its arc lengths; the first and last segments go on as rays.
struct Polyline {
  const double* x = nullptr;
  const double* y = nullptr;
  const double* s = nullptr;  // arc length at each point
  size_t n = 0;
};

// Pseudo-angle of (x, y) in [0, 4): monotone in the angle, exact quadrant steps, no atan2.
double pseudo_angle(double x, double y) {
  if (y >= 0) return x >= 0 ? (x + y > 0 ? y / (x + y) : 0) : 1 - x / (y - x);
  return x < 0 ? 2 - y / (-x - y) : 3 + x / (x - y);
}

// Past the ends the line goes on straight, but only so far: a ray that reached across the
// arch's open back would take the other side's points. The reach along segment k, in t.
double segment_reach(const Polyline& p, size_t k) {
  const double dx = p.x[k + 1] - p.x[k], dy = p.y[k + 1] - p.y[k];
  return kMaxReachMm / std::sqrt(dx * dx + dy * dy);
}

// Segment k's point nearest (px, py): its squared distance, t along the segment, the point q.
double segment_nearest(const Polyline& p, size_t k, double reach, double px, double py,
                       double* t_out, double* qx, double* qy) {
  const double dx = p.x[k + 1] - p.x[k], dy = p.y[k + 1] - p.y[k];
  const double len2 = dx * dx + dy * dy;
  double t = ((px - p.x[k]) * dx + (py - p.y[k]) * dy) / len2;
  t = k > 0 && t < 0 ? 0 : (t < -reach ? -reach : t);
  t = k + 2 < p.n && t > 1 ? 1 : (t > 1 + reach ? 1 + reach : t);
  *qx = p.x[k] + t * dx;
  *qy = p.y[k] + t * dy;
  *t_out = t;
  return (px - *qx) * (px - *qx) + (py - *qy) * (py - *qy);
}

// s and o of (px, py) on segment k from its nearest point q at t (segment_nearest).
void segment_place_at(const Polyline& p, size_t k, double px, double py, double t, double qx,
                      double qy, double* s, double* o) {
  const double dx = p.x[k + 1] - p.x[k], dy = p.y[k + 1] - p.y[k];
  const double len = std::sqrt(dx * dx + dy * dy);
  *s = p.s[k] + t * len;
  *o = (dx * (py - qy) - dy * (px - qx)) / len;
}

// s and o of (px, py) on segment k (see project).
void segment_place(const Polyline& p, size_t k, double px, double py, double* s, double* o) {
  double t, qx, qy;
  segment_nearest(p, k, segment_reach(p, k), px, py, &t, &qx, &qy);
  segment_place_at(p, k, px, py, t, qx, qy, s, o);
}

// The point of the polyline nearest (px, py): its arc length s and signed offset o (positive
// to the left of the direction of travel). The first nearest segment in index order.
void project(const Polyline& p, double px, double py, double* s, double* o) {
  double best = HUGE_VAL;
  size_t best_k = 0;
  for (size_t k = 0; k + 1 < p.n; ++k) {
    double t, qx, qy;
    const double d2 = segment_nearest(p, k, segment_reach(p, k), px, py, &t, &qx, &qy);
    if (d2 < best) {
      best = d2;
      best_k = k;
    }
  }
  segment_place(p, best_k, px, py, s, o);
}

// project() for many points: the segments' boxes (the end segments' with their rays), and
// the boxes of runs of consecutive segments (chunks: a run's segments lie together along the
// arch), so that a point tests only the segments whose boxes come as near as a first guess
// (the previous point's segment: a jaw's vertices come tooth by tooth), passing over every
// chunk whose box does not. The nearest segment, and every segment as near, lies within the
// guess (with a margin over the rounding): project()'s answer bit for bit.
constexpr size_t kProjectorChunks = 32;      // at most (more segments: longer chunks)
constexpr size_t kProjectorMinChunk = 8;     // segments a chunk, at least
constexpr size_t kProjectorGroup = 4;        // chunks a group (a second level of boxes)
constexpr double kProjectorMarginMm = 1e-6;  // over any rounding of a distance

struct Projector {
  const Polyline* line = nullptr;
  double* box = nullptr;        // per segment: x_lo, y_lo, x_hi, y_hi
  double* reach = nullptr;      // per segment: segment_reach
  double* chunk_box = nullptr;  // per chunk: the union of its segments' boxes
  double* group_box = nullptr;  // per group of kProjectorGroup chunks: the union of theirs
  size_t chunk = 1, chunks = 0, groups = 0;  // segments a chunk, chunks, groups
  size_t hint = 0;
};

void segment_box(const Polyline& p, size_t k, double* b) {
  const double dx = p.x[k + 1] - p.x[k], dy = p.y[k + 1] - p.y[k];
  const double reach = kMaxReachMm / std::sqrt(dx * dx + dy * dy);
  const double t0 = k == 0 ? -reach : 0, t1 = k + 2 == p.n ? 1 + reach : 1;
  const double ax = p.x[k] + t0 * dx, bx = p.x[k] + t1 * dx;
  const double ay = p.y[k] + t0 * dy, by = p.y[k] + t1 * dy;
  b[0] = std::min(ax, bx) - kProjectorMarginMm;
  b[1] = std::min(ay, by) - kProjectorMarginMm;
  b[2] = std::max(ax, bx) + kProjectorMarginMm;
  b[3] = std::max(ay, by) + kProjectorMarginMm;
}

size_t projector_chunk(size_t segments) {
  return std::max(kProjectorMinChunk, (segments + kProjectorChunks - 1) / kProjectorChunks);
}

Status make_projector(Arena& arena, const Polyline& p, Projector* out) {
  Projector& g = *out;
  g = Projector{};
  g.line = &p;
  const size_t segments = p.n - 1;
  g.chunk = projector_chunk(segments);
  g.chunks = (segments + g.chunk - 1) / g.chunk;
  g.box = arena.allocate_array<double>(4 * segments);
  g.reach = arena.allocate_array<double>(segments);
  g.groups = (g.chunks + kProjectorGroup - 1) / kProjectorGroup;
  g.chunk_box = arena.allocate_array<double>(4 * g.chunks);
  g.group_box = arena.allocate_array<double>(4 * g.groups);
  if (g.box == nullptr || g.reach == nullptr || g.chunk_box == nullptr || g.group_box == nullptr) {
    return arena.exhausted_status();
  }
  for (size_t c = 0; c < g.chunks + g.groups; ++c) {
    double* cb = c < g.chunks ? g.chunk_box + 4 * c : g.group_box + 4 * (c - g.chunks);
    cb[0] = cb[1] = HUGE_VAL;
    cb[2] = cb[3] = -HUGE_VAL;
  }
  for (size_t k = 0; k < segments; ++k) {
    double* b = g.box + 4 * k;
    g.reach[k] = segment_reach(p, k);
    segment_box(p, k, b);
    for (double* cb :
         {g.chunk_box + 4 * (k / g.chunk), g.group_box + 4 * (k / g.chunk / kProjectorGroup)}) {
      cb[0] = std::min(cb[0], b[0]);
      cb[1] = std::min(cb[1], b[1]);
      cb[2] = std::max(cb[2], b[2]);
      cb[3] = std::max(cb[3], b[3]);
    }
  }
  return Status::ok();
}

// Is the box b (x_lo, y_lo, x_hi, y_hi) farther than r from p = (px, py)? Both axes' gaps in
// two lanes: each lane does the scalar max(0, max(lo - p, p - hi)) (finite values: the same
// gap, up to the sign of a zero, which its square drops), then ex * ex + ey * ey as scalars.
inline bool box_beyond(const double* b, const Lanes2& p, double r) {
  const Lanes2 below = Lanes2{b[0], b[1]} - p, above = p - Lanes2{b[2], b[3]};
  Lanes2 e = below < above ? above : below;
  e = Lanes2{0.0, 0.0} < e ? e : Lanes2{0.0, 0.0};
  return e[0] * e[0] + e[1] * e[1] > r * r;
}

// Every segment of the projector's line but `skip`, in index order, whose box and whose
// chunk's and group's boxes `beyond` (box -> bool) does not rule out, given to `visit` (k ->
// bool: false stops the walk, which then returns false).
template <class Beyond, class Visit>
bool for_segments_within(const Projector& g, size_t skip, Beyond beyond, Visit visit) {
  const size_t segments = g.line->n - 1;
  for (size_t gi = 0; gi < g.groups; ++gi) {
    if (beyond(g.group_box + 4 * gi)) continue;
    const size_t last_chunk = std::min(g.chunks, (gi + 1) * kProjectorGroup);
    for (size_t c = gi * kProjectorGroup; c < last_chunk; ++c) {
      if (beyond(g.chunk_box + 4 * c)) continue;
      const size_t end = std::min(segments, (c + 1) * g.chunk);
      for (size_t k = c * g.chunk; k < end; ++k) {
        if (k == skip || beyond(g.box + 4 * k)) continue;
        if (!visit(k)) return false;
      }
    }
  }
  return true;
}

// project(&line, px, py, s, o), bit for bit.
void project_fast(Projector& g, double px, double py, double* s, double* o) {
  const Polyline& p = *g.line;
  const size_t segments = p.n - 1;
  double t, qx, qy;
  // A bound on the nearest distance: the guess's segment's. (Its t and q kept with the best:
  // segment_place's, which computes them again the same way from the same reach.)
  const size_t guess = g.hint < segments ? g.hint : 0;
  double best = segment_nearest(p, guess, g.reach[guess], px, py, &t, &qx, &qy);
  size_t best_k = guess;
  double best_t = t, best_qx = qx, best_qy = qy;
  const double r = std::sqrt(best) * (1 + 1e-9) + kProjectorMarginMm;
  if (!(r < HUGE_VAL)) {
    project(p, px, py, s, o);
    return;
  }
  const Lanes2 p2 = {px, py};
  // The least distance, the first segment in index order among equal ones (as project()).
  for_segments_within(
      g, guess, [&](const double* box) { return box_beyond(box, p2, r); },
      [&](size_t k) {
        const double d2 = segment_nearest(p, k, g.reach[k], px, py, &t, &qx, &qy);
        if (d2 < best || (d2 == best && k < best_k)) {
          best = d2;
          best_k = k;
          best_t = t;
          best_qx = qx;
          best_qy = qy;
        }
        return true;
      });
  g.hint = best_k;
  segment_place_at(p, best_k, px, py, best_t, best_qx, best_qy, s, o);
}

// project() for the points of a lattice cell, from a list of the cell's candidate segments:
// every segment that can be the nearest to a point of the cell. A point p of the cell lies
// within the cell's half-diagonal of its centre c, so its nearest distance is at most U, the
// centre's nearest distance plus the half-diagonal; every segment that comes as near as that
// to p has its box within U of the cell's box. So the candidates (in index order) hold the
// nearest segment and every segment as near: the first least among them is project()'s, bit
// for bit (the same segment_nearest, the same comparison). The cells are square, at least
// kCellGridMinMm and at most kCellGridCells of them over the points' box; only the cells
// that hold points get a list. A point outside its cell's box (rounding at the edges), in a
// cell without a list (the lists' room used up) or any value not finite: project_fast.
constexpr uint32_t kCellGridCells = 4096;
constexpr double kCellGridMinMm = 1.0;
constexpr size_t kCellListRoom = 32768;  // candidate entries over all cells
constexpr uint32_t kNoList = ~uint32_t{0};
constexpr uint32_t kWanted = kNoList - 1;  // a cell with points, before its list is made
constexpr double kCellEdgeMm = 1e-6;       // the cells' boxes grown by this (rounding)

struct CellGrid {
  double x0 = 0, y0 = 0, size = 0, inverse = 0;
  uint32_t nx = 0, ny = 0;
  uint32_t* start = nullptr;  // per cell: its first entry in `list`, or kNoList
  uint16_t* count = nullptr;  // per cell: its entries
  uint16_t* list = nullptr;   // the candidates' segment indices, cell after cell
  // Per entry after a cell's first: its segment's box's squared gap to the cell's grown box
  // (boxes_beyond's), the entries after the first in increasing order of it (then of index).
  double* gap2 = nullptr;
};

uint64_t cell_grid_bound() {
  return arena_array_bound<uint32_t>(kCellGridCells) + arena_array_bound<uint16_t>(kCellGridCells) +
         arena_array_bound<uint16_t>(kCellListRoom) + arena_array_bound<double>(kCellListRoom);
}

// Cell (ix, iy)'s box, grown by kCellEdgeMm.
void cell_box(const CellGrid& c, uint32_t ix, uint32_t iy, double box[4]) {
  box[0] = c.x0 + ix * c.size - kCellEdgeMm;
  box[1] = c.y0 + iy * c.size - kCellEdgeMm;
  box[2] = c.x0 + (ix + 1) * c.size + kCellEdgeMm;
  box[3] = c.y0 + (iy + 1) * c.size + kCellEdgeMm;
}

// The cell of (px, py), a point of the box the lattice was laid over; false when it is not a
// number. (The quotients round by far less than kCellEdgeMm: the point lies in its cell's
// grown box, also where it is clamped to the last cell.)
inline bool cell_of_point(const CellGrid& c, double px, double py, size_t* cell) {
  const double fx = (px - c.x0) * c.inverse, fy = (py - c.y0) * c.inverse;
  if (!(fx >= 0 && fy >= 0 && fx <= c.nx && fy <= c.ny)) return false;
  const uint32_t ix = fx < c.nx ? static_cast<uint32_t>(fx) : c.nx - 1;
  const uint32_t iy = fy < c.ny ? static_cast<uint32_t>(fy) : c.ny - 1;
  *cell = static_cast<size_t>(iy) * c.nx + ix;
  return true;
}

// The squared gap between the boxes a and b (x_lo, y_lo, x_hi, y_hi), as computed.
inline double boxes_gap2(const double* b, const double* a) {
  const double ex = std::max(0.0, std::max(b[0] - a[2], a[0] - b[2]));
  const double ey = std::max(0.0, std::max(b[1] - a[3], a[1] - b[3]));
  return ex * ex + ey * ey;
}

// Is the box b farther than r from the box a?
inline bool boxes_beyond(const double* b, const double* a, double r) {
  return boxes_gap2(b, a) > r * r;
}

// The candidates of the cell with box `box` (grown by kCellEdgeMm) appended to the list at
// *used; false when they do not fit (or a value is not finite).
bool cell_candidates(Projector& g, CellGrid& c, const double box[4], size_t* used) {
  const Polyline& p = *g.line;
  const double cx = 0.5 * (box[0] + box[2]), cy = 0.5 * (box[1] + box[3]);
  const double hw = 0.5 * (box[2] - box[0]), hh = 0.5 * (box[3] - box[1]);
  double s = 0, o = 0;
  project_fast(g, cx, cy, &s, &o);  // the nearest segment: g.hint
  double t, qx, qy;
  const double d2 = segment_nearest(p, g.hint, g.reach[g.hint], cx, cy, &t, &qx, &qy);
  const double u =
      (std::sqrt(d2) + std::sqrt(hw * hw + hh * hh)) * (1 + 1e-9) + 2 * kProjectorMarginMm;
  if (!(u < HUGE_VAL)) return false;
  const size_t first = *used;
  const size_t nearest = g.hint;
  if (*used == kCellListRoom) return false;
  c.list[(*used)++] = static_cast<uint16_t>(nearest);  // first: the point's first bound
  const bool fit = for_segments_within(
      g, nearest, [&](const double* b) { return boxes_beyond(b, box, u); },
      [&](size_t k) {
        if (*used == kCellListRoom) return false;
        c.list[(*used)++] = static_cast<uint16_t>(k);
        return true;
      });
  if (!fit) {
    *used = first;
    return false;
  }
  // The entries after the first by (gap, index): insertion sort (a few dozen a cell).
  for (size_t i = first + 1; i < *used; ++i) {
    const uint16_t k = c.list[i];
    const double gap = boxes_gap2(g.box + 4 * size_t{k}, box);
    size_t at = i;
    while (at > first + 1 &&
           (c.gap2[at - 1] > gap || (c.gap2[at - 1] == gap && c.list[at - 1] > k))) {
      c.list[at] = c.list[at - 1];
      c.gap2[at] = c.gap2[at - 1];
      --at;
    }
    c.list[at] = k;
    c.gap2[at] = gap;
  }
  return true;
}

// The cell lattice over the points and the lists of the cells that hold points.
Status make_cell_grid(Arena& arena, Projector& g, Span<const ArchPoint> pts, CellGrid* out) {
  CellGrid& c = *out;
  c = CellGrid{};
  double x_lo = HUGE_VAL, y_lo = HUGE_VAL, x_hi = -HUGE_VAL, y_hi = -HUGE_VAL;
  for (const ArchPoint& a : pts) {
    x_lo = std::min(x_lo, a.x);
    x_hi = std::max(x_hi, a.x);
    y_lo = std::min(y_lo, a.y);
    y_hi = std::max(y_hi, a.y);
  }
  if (!(x_hi - x_lo < kMaxSpanMm && y_hi - y_lo < kMaxSpanMm)) return Status::ok();  // no grid
  double size = kCellGridMinMm;
  for (;;) {
    const double fx = (x_hi - x_lo) / size + 1, fy = (y_hi - y_lo) / size + 1;
    if (fx * fy <= kCellGridCells) {
      c.nx = static_cast<uint32_t>(fx);
      c.ny = static_cast<uint32_t>(fy);
      break;
    }
    size *= 1.25;
  }
  c.x0 = x_lo;
  c.y0 = y_lo;
  c.size = size;
  c.inverse = 1.0 / size;
  const size_t cells = static_cast<size_t>(c.nx) * c.ny;
  c.start = arena.allocate_array<uint32_t>(cells);
  c.count = arena.allocate_array<uint16_t>(cells);
  c.list = arena.allocate_array<uint16_t>(kCellListRoom);
  c.gap2 = arena.allocate_array<double>(kCellListRoom);
  if (c.start == nullptr || c.count == nullptr || c.list == nullptr || c.gap2 == nullptr) {
    return arena.exhausted_status();
  }
  std::fill(c.start, c.start + cells, kNoList);
  std::fill(c.count, c.count + cells, uint16_t{0});
  for (const ArchPoint& a : pts) {
    size_t cell;
    if (cell_of_point(c, a.x, a.y, &cell)) c.start[cell] = kWanted;
  }
  size_t used = 0;
  for (size_t i = 0; i < cells; ++i) {
    if (c.start[i] != kWanted) continue;
    const uint32_t ix = static_cast<uint32_t>(i % c.nx), iy = static_cast<uint32_t>(i / c.nx);
    double box[4];
    cell_box(c, ix, iy, box);
    const size_t first = used;
    if (!cell_candidates(g, c, box, &used)) {
      c.start[i] = kNoList;
      continue;
    }
    c.start[i] = static_cast<uint32_t>(first);
    c.count[i] = static_cast<uint16_t>(used - first);
  }
  return Status::ok();
}

// project(&line, px, py, s, o), bit for bit: from the cell's candidates when it has them. The
// first candidate's distance bounds the nearest (as project_fast's guess), so a candidate
// whose box lies beyond it is passed over; the least (distance, segment) of the others, in
// any order (project()'s first least in index order).
void project_cell(Projector& g, const CellGrid& c, double px, double py, double* s, double* o) {
  size_t cell = 0;
  if (c.start == nullptr || !cell_of_point(c, px, py, &cell) || c.start[cell] == kNoList) {
    project_fast(g, px, py, s, o);
    return;
  }
  const Polyline& p = *g.line;
  const uint16_t* k = c.list + c.start[cell];
  const uint16_t* end = k + c.count[cell];
  double t, qx, qy;
  double best = segment_nearest(p, *k, g.reach[*k], px, py, &t, &qx, &qy);
  size_t best_k = *k;
  double best_t = t, best_qx = qx, best_qy = qy;
  const double r = std::sqrt(best) * (1 + 1e-9) + kProjectorMarginMm;
  if (!(r < HUGE_VAL)) {
    project(p, px, py, s, o);
    return;
  }
  const Lanes2 p2 = {px, py};
  // The point lies in its cell's grown box, so its box gap to a segment's box is at least the
  // cell's (each axis's difference and square round monotonically): past the first entry
  // whose cell gap exceeds r, every box lies beyond it.
  const double r2 = r * r;
  const double* gap = c.gap2 + c.start[cell];
  for (++k, ++gap; k < end; ++k, ++gap) {
    if (*gap > r2) break;
    if (box_beyond(g.box + 4 * size_t{*k}, p2, r)) continue;
    const double d2 = segment_nearest(p, *k, g.reach[*k], px, py, &t, &qx, &qy);
    if (d2 < best || (d2 == best && *k < best_k)) {
      best = d2;
      best_k = *k;
      best_t = t;
      best_qx = qx;
      best_qy = qy;
    }
  }
  segment_place_at(p, best_k, px, py, best_t, best_qx, best_qy, s, o);
}

// project() for every point (its s and o), in up to the executor's concurrency runs of
// consecutive points: the cell lists are made first (one pass); the answers depend neither on
// the lists nor on the hints, so they are the same bits at every thread count. Arena:
// cell_grid_bound(), gone when done.
Status project_all(const Context& ctx, const Projector& g, Span<ArchPoint> pts) {
  ArenaScope scope(*ctx.arena);
  Projector first = g;
  CellGrid cells;
  SPLINTCORE_RETURN_IF_ERROR(make_cell_grid(*ctx.arena, first, pts, &cells));
  const uint32_t concurrency = ctx.executor != nullptr ? ctx.executor->concurrency : 1;
  const size_t n = pts.size();
  const uint32_t tasks = n < 1024 || concurrency < 2 ? 1 : concurrency;
  auto task = [&](uint32_t i) {
    Projector local = g;
    const size_t end = n * (i + 1) / tasks;
    for (size_t k = n * i / tasks; k < end; ++k) {
      ArchPoint& a = pts[k];
      project_cell(local, cells, a.x, a.y, &a.s, &a.o);
    }
  };
  parallel_for_each(ctx.executor, tasks, task);
  return Status::ok();
}

// The polyline's point at arc length s (extended along the end segments).
void place_at(const Polyline& p, double s, double* x, double* y) {
  size_t k = 0;
  while (k + 2 < p.n && s > p.s[k + 1]) ++k;
  const double t = (s - p.s[k]) / (p.s[k + 1] - p.s[k]);
  *x = p.x[k] + t * (p.x[k + 1] - p.x[k]);
  *y = p.y[k] + t * (p.y[k + 1] - p.y[k]);
}

// The point at s and the unit left normal of the chord over kTangentMm around it.
void point_at(const Polyline& p, double s, double* x, double* y, double* lx, double* ly) {
  place_at(p, s, x, y);
  double ax, ay, bx, by;
  place_at(p, s - 0.5 * kTangentMm, &ax, &ay);
  place_at(p, s + 0.5 * kTangentMm, &bx, &by);
  const double len = std::sqrt((bx - ax) * (bx - ax) + (by - ay) * (by - ay));
  *lx = -(by - ay) / len;
  *ly = (bx - ax) / len;
}

Status allocate(Arena& arena, size_t n, double** a, double** b, double** c) {
  *a = arena.allocate_array<double>(n);
  *b = arena.allocate_array<double>(n);
  *c = arena.allocate_array<double>(n);
  return *a != nullptr && *b != nullptr && *c != nullptr ? Status::ok() : arena.exhausted_status();
}

constexpr double kBandCutSlackMm = 0.01;  // over the rounding of the band cut (below)

// One jaw's part of occlusal_points that reads only the jaw (a task each): its columns' depths
// into r, the band's limit, and the band's vertices marked (their indices in band). *found:
// the columns that show the other jaw.
struct JawBandPart {
  double limit = 0;         // the band's vertices (the centre line)
  double column_limit = 0;  // its columns (the picks' heights and reach across)
  size_t found = 0, in_band = 0;
};

void jaw_band_part(const Mesh& m, const Vec3& offset, uint32_t jaw, const Frame& f, const Grid& g,
                   const Plane& plane, double column_band, double* r, uint32_t* band,
                   JawBandPart* out) {
  const size_t cells = static_cast<size_t>(g.nx) * g.ny;
  // Distance from the plane towards the jaw's own side (>= about 0 at the tips).
  const PlaneAxes axes(f);
  auto depth_of = [&](const Vec3& p) {
    const Lanes2 xy = axes.xy(p);
    const double above = dot(p, f.n) - plane.at(xy[0] - g.cx, xy[1] - g.cy);
    return jaw == 0 ? above : -above;
  };
  size_t used = 0;
  for (size_t i = 0; i < cells; ++i) {
    if (g.tip[jaw][i] == kNoTip) continue;
    r[used++] = depth_of(m.vertices[g.tip[jaw][i]] + offset);
  }
  out->found = used;
  if (used < kMinOcclusalCells) return;
  std::nth_element(r, r + used / 100, r + used);
  const double limit = r[used / 100] + kOcclusalBandMm;
  out->limit = limit;
  out->column_limit = r[used / 100] + column_band;
  // The band's vertices marked in one pass (their indices in `band`), every k-th taken later.
  // Most of a jaw lies far from the plane: every vertex's place in the plane lies within
  // kMaxSpanMm of the lattice's origin (grid_layout refuses a wider extent, and the origin
  // is the vertices' mean; the mandible's move is along n), so the plane's height under it
  // lies within `tilt` of plane.a, and a vertex whose height lies beyond the limit from
  // that is outside the band by its height alone (with a slack far over the rounding): the
  // same vertices as depth_of's test of every one.
  const double tilt =
      (std::fabs(plane.b) + std::fabs(plane.c)) * (kMaxSpanMm + 1.0) + kBandCutSlackMm;
  const double cut = jaw == 0 ? plane.a + limit + tilt : plane.a - limit - tilt;
  size_t in_band = 0;
  for (size_t k = 0; k < m.vertices.size(); ++k) {
    const Vec3 p = m.vertices[k] + offset;
    band[in_band] = static_cast<uint32_t>(k);
    const double h_k = dot(p, f.n);
    if (jaw == 0 ? h_k > cut : h_k < cut) continue;
    in_band += depth_of(p) <= limit ? 1u : 0u;
  }
  out->in_band = in_band;
}

// The occlusal surfaces of both jaws: the columns within `column_band` of the jaw's tips (the
// hundredth lowest distance from the plane) as ArchPoints in `cells` (their extremes set the
// picks' heights and widths), and the vertices within kOcclusalBandMm of the tips in `line`
// (every k-th in index order, at most kLinePoints a jaw: the centre line's points). The line
// takes vertices, not columns, so that it moves with the jaws: which vertex a column shows can
// change with a rounding when the jaws move, which vertices lie in the band only where one
// lies on its edge. The jaws' parts in two tasks (each its own depths and band marks), then
// their points in jaw order: the same points as one jaw after the other.
Status occlusal_points(const Context& ctx, const Mesh& upper, const Mesh& lower,
                       const Vec3& lower_offset, const Frame& f, const Grid& g, const Plane& plane,
                       double column_band, ArenaArray<ArchPoint>* cells_out,
                       ArenaArray<ArchPoint>* line, uint64_t counts[2]) {
  Arena& arena = *ctx.arena;
  const size_t cells = static_cast<size_t>(g.nx) * g.ny;
  const Mesh* jaws[2] = {&upper, &lower};
  const Vec3 offsets[2] = {Vec3{}, lower_offset};
  double* r[2];
  uint32_t* band[2];
  for (uint32_t jaw = 0; jaw < 2; ++jaw) {
    r[jaw] = arena.allocate_array<double>(cells);
    band[jaw] = arena.allocate_array<uint32_t>(jaws[jaw]->vertices.size());
    if (r[jaw] == nullptr || band[jaw] == nullptr) return arena.exhausted_status();
  }
  // Room for every shown column and kLinePoints vertices a jaw, reserved once (no growth).
  size_t shown = 0;
  for (uint32_t jaw = 0; jaw < 2; ++jaw) {
    for (size_t i = 0; i < cells; ++i) shown += g.tip[jaw][i] == kNoTip ? 0 : 1;
  }
  if (!cells_out->reserve(shown) || !line->reserve(2 * (kLinePoints + 1))) {
    return arena.exhausted_status();
  }
  JawBandPart parts[2];
  auto part = [&](uint32_t jaw) {
    jaw_band_part(*jaws[jaw], offsets[jaw], jaw, f, g, plane, column_band, r[jaw], band[jaw],
                  &parts[jaw]);
  };
  parallel_for_each(ctx.executor, 2, part);
  for (uint32_t jaw = 0; jaw < 2; ++jaw) {
    const Mesh& m = *jaws[jaw];
    const Vec3 offset = offsets[jaw];
    if (parts[jaw].found < kMinOcclusalCells) {
      return make_error(StatusCode::kInvalidArgument, "outline: no teeth found on the ",
                        jaw == 0 ? "maxilla" : "mandible", ": it shows the other jaw only ",
                        parts[jaw].found, " columns of 0.5 mm");
    }
    const PlaneAxes axes(f);
    auto depth_of = [&](const Vec3& p, double* x, double* y, double* h) {
      const Lanes2 xy = axes.xy(p);
      *x = xy[0];
      *y = xy[1];
      *h = dot(p, f.n);
      const double above = *h - plane.at(*x - g.cx, *y - g.cy);
      return jaw == 0 ? above : -above;
    };
    counts[jaw] = 0;
    for (size_t i = 0; i < cells; ++i) {
      if (g.tip[jaw][i] == kNoTip) continue;
      ArchPoint a;
      a.jaw = jaw;
      if (depth_of(m.vertices[g.tip[jaw][i]] + offset, &a.x, &a.y, &a.h) >
          parts[jaw].column_limit) {
        continue;
      }
      if (!cells_out->push_back(a)) return arena.exhausted_status();
      ++counts[jaw];
    }
    const size_t in_band = parts[jaw].in_band;
    const size_t every = in_band / kLinePoints + 1;
    for (size_t i = 0; i < in_band; i += every) {
      ArchPoint a;
      a.jaw = jaw;
      (void)depth_of(m.vertices[band[jaw][i]] + offset, &a.x, &a.y, &a.h);
      if (!line->push_back(a)) return arena.exhausted_status();
    }
  }
  return Status::ok();
}

// The first centre line: the mean of the points in each of kSectors pseudo-angle sectors
// around their centre, from the sector after the widest empty run (the arch's open back) all
// the way round.
Status sector_line(Arena& arena, Span<const ArchPoint> pts, Polyline* line) {
  double cx = 0, cy = 0;
  for (const ArchPoint& a : pts) {
    cx += a.x;
    cy += a.y;
  }
  cx /= static_cast<double>(pts.size());
  cy /= static_cast<double>(pts.size());
  double *sx = nullptr, *sy = nullptr, *count = nullptr;
  SPLINTCORE_RETURN_IF_ERROR(allocate(arena, kSectors, &sx, &sy, &count));
  std::fill(sx, sx + kSectors, 0.0);
  std::fill(sy, sy + kSectors, 0.0);
  std::fill(count, count + kSectors, 0.0);
  for (const ArchPoint& a : pts) {
    const double t = pseudo_angle(a.x - cx, a.y - cy) * (kSectors / 4.0);
    uint32_t k = static_cast<uint32_t>(t);
    k = k >= kSectors ? kSectors - 1 : k;
    sx[k] += a.x;
    sy[k] += a.y;
    count[k] += 1;
  }
  // The widest run of empty sectors, circularly; the first such run wins a tie.
  uint32_t best_start = 0, best_len = 0;
  for (uint32_t start = 0; start < kSectors; ++start) {
    if (count[start] != 0 || count[(start + kSectors - 1) % kSectors] == 0) continue;
    uint32_t len = 0;
    while (len < kSectors && count[(start + len) % kSectors] == 0) ++len;
    if (len > best_len) {
      best_len = len;
      best_start = start;
    }
  }
  if (best_len == 0) {
    return Status::error(StatusCode::kInvalidArgument,
                         "outline: no dental arch: the occlusal surfaces surround their centre "
                         "(no open back)");
  }
  double *x = nullptr, *y = nullptr, *s = nullptr;
  SPLINTCORE_RETURN_IF_ERROR(allocate(arena, kSectors, &x, &y, &s));
  size_t n = 0;
  for (uint32_t j = 0; j < kSectors; ++j) {
    const uint32_t k = (best_start + best_len + j) % kSectors;
    if (count[k] == 0) continue;
    x[n] = sx[k] / count[k];
    y[n] = sy[k] / count[k];
    s[n] = n == 0 ? 0
                  : s[n - 1] + std::sqrt((x[n] - x[n - 1]) * (x[n] - x[n - 1]) +
                                         (y[n] - y[n - 1]) * (y[n] - y[n - 1]));
    if (n > 0 && !(s[n] > s[n - 1])) continue;  // same place as the previous: skip
    ++n;
  }
  if (n < 4) {
    return make_error(StatusCode::kInvalidArgument,
                      "outline: the arch is too short: the teeth "
                      "fill only ",
                      n, " of ", kSectors, " sectors around their centre");
  }
  *line = Polyline{x, y, s, n};
  return Status::ok();
}

// The ends of a centre line curl towards the side where the last points are (past the end,
// the points that project onto it are those on the inner side of its bend, and their mean
// pulls the next line further in). So the last kEndTrimMm at each end go, and the next
// kEndChordMm become one straight segment: the line then goes on past its ends along the
// arch's direction there, and the next pass's bins past the ends hold both sides' points.
// The turn of the line at point i: the cosine between the chords of kTurnBins bins before
// and after it (1 where it cannot be measured).
double turn_cosine(const Polyline& p, size_t i) {
  if (i < kTurnBins || i + kTurnBins >= p.n) return 1;
  const double ax = p.x[i] - p.x[i - kTurnBins], ay = p.y[i] - p.y[i - kTurnBins];
  const double bx = p.x[i + kTurnBins] - p.x[i], by = p.y[i + kTurnBins] - p.y[i];
  const double la = std::sqrt(ax * ax + ay * ay), lb = std::sqrt(bx * bx + by * by);
  return la > 0 && lb > 0 ? (ax * bx + ay * by) / (la * lb) : 1;
}

Polyline straighten_ends(const Polyline& whole) {
  // A dental arch turns at most about 15 degrees in 3 mm (a canine's radius of 12 mm or
  // more); from the middle outwards the line is cut where it turns by more than 45: there it
  // folds back into the points at its end.
  Polyline p = whole;
  const size_t middle = p.n / 2;
  size_t first = 0, last = p.n - 1;
  for (size_t i = middle; i + 1 < p.n; ++i) {
    if (turn_cosine(p, i) < kMaxTurnCosine) {
      last = i;
      break;
    }
  }
  for (size_t i = middle; i > 0; --i) {
    if (turn_cosine(p, i) < kMaxTurnCosine) {
      first = i;
      break;
    }
  }
  p = Polyline{p.x + first, p.y + first, p.s + first, last - first + 1};
  const double start = p.s[0];
  double* shift = const_cast<double*>(p.s);
  for (size_t i = 0; i < p.n; ++i) shift[i] -= start;
  const double length = p.s[p.n - 1];
  if (length < 2 * (kEndTrimMm + kEndChordMm) + 4 * kBinMm) return p;
  size_t i0 = 0, i1 = p.n - 1;
  while (p.s[i0] < kEndTrimMm) ++i0;
  while (p.s[i1] > length - kEndTrimMm) --i1;
  size_t j0 = i0 + 1, j1 = i1 - 1;
  while (p.s[j0] < p.s[i0] + kEndChordMm) ++j0;
  while (p.s[j1] > p.s[i1] - kEndChordMm) --j1;
  double* x = const_cast<double*>(p.x);
  double* y = const_cast<double*>(p.y);
  double* s = const_cast<double*>(p.s);
  size_t n = 0;
  auto keep = [&](size_t i) {
    x[n] = x[i];
    y[n] = y[i];
    ++n;
  };
  keep(i0);
  for (size_t i = j0; i <= j1; ++i) keep(i);
  keep(i1);
  s[0] = 0;
  for (size_t i = 1; i < n; ++i) {
    s[i] = s[i - 1] +
           std::sqrt((x[i] - x[i - 1]) * (x[i] - x[i - 1]) + (y[i] - y[i - 1]) * (y[i] - y[i - 1]));
  }
  return Polyline{x, y, s, n};
}

// Local linear regression of v over s at s0 (triangular weights of half-width h, times w):
// unbiased at the ends of the data, where a plain moving average pulls inward.
double local_linear(const double* s, const double* v, const double* w, size_t n, double s0,
                    double h) {
  double s0w = 0, s1 = 0, s2 = 0, t0 = 0, t1 = 0;
  for (size_t j = 0; j < n; ++j) {
    const double d = s[j] - s0;
    const double k = 1 - std::fabs(d) / h;
    if (!(k > 0)) continue;
    const double kw = k * w[j];
    s0w += kw;
    s1 += kw * d;
    s2 += kw * d * d;
    t0 += kw * v[j];
    t1 += kw * d * v[j];
  }
  const double det = s0w * s2 - s1 * s1;
  if (!(det > 1e-12 * s0w * s0w)) return t0 / s0w;  // one point or all at one place
  return (s2 * t0 - s1 * t1) / det;
}

// A centre line along `prev`: the points' mean place in each kBinMm bin along it, smoothed by
// local linear regression over kSmoothMm along the arch, sampled at every bin from the first
// to the last one with points.
Status smooth_line(const Context& ctx, Span<ArchPoint> pts, const Polyline& prev, Polyline* line) {
  Arena& arena = *ctx.arena;
  double s_lo = HUGE_VAL, s_hi = -HUGE_VAL;
  {
    ArenaScope scope(arena);  // the projector goes when done
    Projector g;
    SPLINTCORE_RETURN_IF_ERROR(make_projector(arena, prev, &g));
    SPLINTCORE_RETURN_IF_ERROR(project_all(ctx, g, pts));
    for (const ArchPoint& a : pts) {
      s_lo = std::min(s_lo, a.s);
      s_hi = std::max(s_hi, a.s);
    }
  }
  const double origin = std::floor(s_lo / kBinMm) * kBinMm;
  const size_t bins = static_cast<size_t>((s_hi - origin) / kBinMm) + 1;
  if (bins > kMaxArchPoints) {
    return make_error(StatusCode::kInvalidArgument, "outline: the arch is ", s_hi - s_lo,
                      " mm long (at most ", kMaxArchPoints, "): these are not two dental arches");
  }
  double *sx = nullptr, *sy = nullptr, *count = nullptr;
  SPLINTCORE_RETURN_IF_ERROR(allocate(arena, bins, &sx, &sy, &count));
  std::fill(sx, sx + bins, 0.0);
  std::fill(sy, sy + bins, 0.0);
  std::fill(count, count + bins, 0.0);
  for (const ArchPoint& a : pts) {
    size_t b = static_cast<size_t>((a.s - origin) / kBinMm);
    b = b >= bins ? bins - 1 : b;
    sx[b] += a.x;
    sy[b] += a.y;
    count[b] += 1;
  }
  double *bs = nullptr, *unused = nullptr, *unused2 = nullptr;
  SPLINTCORE_RETURN_IF_ERROR(allocate(arena, bins, &bs, &unused, &unused2));
  size_t first = bins, last = 0;
  for (size_t b = 0; b < bins; ++b) {
    bs[b] = origin + (static_cast<double>(b) + 0.5) * kBinMm;
    if (count[b] == 0) continue;
    sx[b] /= count[b];
    sy[b] /= count[b];
    first = std::min(first, b);
    last = b;
  }
  double *x = nullptr, *y = nullptr, *s = nullptr;
  SPLINTCORE_RETURN_IF_ERROR(allocate(arena, bins, &x, &y, &s));
  size_t n = 0;
  for (size_t b = first; b <= last && first < bins; ++b) {
    x[n] = local_linear(bs, sx, count, bins, bs[b], kSmoothMm);
    y[n] = local_linear(bs, sy, count, bins, bs[b], kSmoothMm);
    s[n] = n == 0 ? 0
                  : s[n - 1] + std::sqrt((x[n] - x[n - 1]) * (x[n] - x[n - 1]) +
                                         (y[n] - y[n - 1]) * (y[n] - y[n - 1]));
    if (n > 0 && !(s[n] > s[n - 1])) continue;
    ++n;
  }
  if (n < 4) {
    return make_error(StatusCode::kInvalidArgument, "outline: the arch is too short: ", n,
                      " mm of it hold occlusal surfaces");
  }
  *line = straighten_ends(Polyline{x, y, s, n});
  return Status::ok();
}

// Per pick: the lowest maxilla and highest mandible height within a step and half a molar
// along the arch, and the lingual and buccal extent of the points within a step; NaN where no
// point is. The heights' reach: the face between two picks follows the spline through their
// heights, so over a tooth it rises no higher than its tip plus the depth only if every pick
// whose spline passes over the tooth sees the tooth's tip: half a molar and a step away at
// most. A narrower reach would let the face climb over a tooth towards a higher neighbour and
// sink that tooth deeper than asked.
struct PickData {
  double h[2];       // within a step and half a molar: the bound on the face
  double near_h[2];  // within half a step: the tooth under the pick
  double lingual, buccal;
};

// The pick at `at` (places along the arch, increasing) takes the points within a step and half
// a molar of it (along = |s - at|), in their order; so each point goes only to the picks within
// that reach of it (found by bisection, with a margin far over the rounding of along, then
// tested as before): the picks' data bit for bit as when each pick scanned every point.
constexpr double kPickWindowSlackMm = 1e-6;

void add_to_pick(const ArchPoint& a, double at, double step, double side, PickData* d) {
  const double along = std::fabs(a.s - at);
  if (along <= step + kToothHalfMm) {
    if (a.jaw == 0) {
      d->h[0] = std::min(d->h[0], a.h);
    } else {
      d->h[1] = std::max(d->h[1], a.h);
    }
  }
  if (along <= 0.5 * step) {
    if (a.jaw == 0) {
      d->near_h[0] = std::min(d->near_h[0], a.h);
    } else {
      d->near_h[1] = std::max(d->near_h[1], a.h);
    }
  }
  if (along > step) return;
  d->buccal = std::max(d->buccal, a.o * side);
  d->lingual = std::max(d->lingual, -a.o * side);
}

void gather_picks(Span<const ArchPoint> pts, const double* at, size_t n, double step, double side,
                  PickData* data) {
  for (size_t i = 0; i < n; ++i) {
    PickData* d = &data[i];
    d->h[0] = d->near_h[0] = HUGE_VAL;
    d->h[1] = d->near_h[1] = -HUGE_VAL;
    d->lingual = -HUGE_VAL;
    d->buccal = -HUGE_VAL;
  }
  const double reach = step + kToothHalfMm + kPickWindowSlackMm;
  for (const ArchPoint& a : pts) {
    size_t first = 0, last = n;  // a place that is not a number: every pick, as a scan would
    if (!std::isnan(a.s)) {
      first = static_cast<size_t>(std::lower_bound(at, at + n, a.s - reach) - at);
      last = static_cast<size_t>(std::upper_bound(at + first, at + n, a.s + reach) - at);
    }
    for (size_t i = first; i < last; ++i) add_to_pick(a, at[i], step, side, &data[i]);
  }
  for (size_t i = 0; i < n; ++i) {
    PickData* d = &data[i];
    if (d->h[0] == HUGE_VAL) d->h[0] = std::numeric_limits<double>::quiet_NaN();
    if (d->h[1] == -HUGE_VAL) d->h[1] = std::numeric_limits<double>::quiet_NaN();
    if (d->near_h[0] == HUGE_VAL) d->near_h[0] = std::numeric_limits<double>::quiet_NaN();
    if (d->near_h[1] == -HUGE_VAL) d->near_h[1] = std::numeric_limits<double>::quiet_NaN();
    if (d->buccal == -HUGE_VAL) d->buccal = d->lingual = std::numeric_limits<double>::quiet_NaN();
  }
}

// Fills the NaN entries of v[0..n) (stride `stride` doubles) by linear interpolation between
// the nearest known ones, or the nearest known one at the ends. False when none is known.
bool fill_gaps(double* v, size_t n, size_t stride) {
  size_t prev = n;
  for (size_t i = 0; i < n; ++i) {
    if (std::isnan(v[i * stride])) continue;
    if (prev == n) {
      for (size_t j = 0; j < i; ++j) v[j * stride] = v[i * stride];
    } else {
      for (size_t j = prev + 1; j < i; ++j) {
        const double t = static_cast<double>(j - prev) / static_cast<double>(i - prev);
        v[j * stride] = v[prev * stride] + t * (v[i * stride] - v[prev * stride]);
      }
    }
    prev = i;
  }
  if (prev == n) return false;
  for (size_t j = prev + 1; j < n; ++j) v[j * stride] = v[prev * stride];
  return true;
}

// The picks' places along the arch: even steps from `start` (grid picks k = 0 .. n-1), or, cut
// at the case's distal ends, the limit itself at each cut end and the grid picks at least half
// a step inside it (the middle picks are the uncut run's, bit for bit).
struct PickPlaces {
  double start = 0, step = 0;
  size_t first = 0, grid = 0;  // the grid picks kept: k in [first, first + grid)
  bool cut[2] = {false, false};
  double limit[2] = {0, 0};
  size_t size() const { return (cut[0] ? 1 : 0) + grid + (cut[1] ? 1 : 0); }
  double at(size_t i) const {
    if (cut[0] && i-- == 0) return limit[0];
    return i < grid ? start + step * static_cast<double>(first + i) : limit[1];
  }
};

constexpr double kMaxDistalOffsetMm = 15.0;  // a distal end's distance from the centre line
constexpr double kDistalInsideMm = 1e-6;     // the limit's pick: this inside its plane

// Cuts `places` (the whole grid of n picks from start to end) at options.distal_ends: each
// point's place s along the arch (project: the plane through it across the arch there), the
// point on the lower half of the arch (s below the middle of [s_lo, s_hi]) cutting the start,
// the other the end, whatever their order; a limit past the end changes nothing. At least two
// picks stay: each uncut end's grid pick lies kMinArchMm (>= the step) from the other end.
Status cut_distal_ends(const Polyline& arch, const Frame& f, const OutlineOptions& options,
                       double s_lo, double s_hi, size_t n, PickPlaces* places, OutlineReport* r) {
  if (!options.has_distal_ends) return Status::ok();
  const double middle = 0.5 * (s_lo + s_hi);
  const double end = places->start + places->step * static_cast<double>(n - 1);
  double at[2];
  for (int i = 0; i < 2; ++i) {
    const Vec3& p = options.distal_ends[i];
    if (!is_finite(p)) {
      return make_error(StatusCode::kInvalidArgument, "outline: distal_ends[", i,
                        "] is not finite (NaN or infinity)");
    }
    const double x = dot(p, f.e1), y = dot(p, f.e2);
    double o, qx, qy;
    project(arch, x, y, &at[i], &o);
    place_at(arch, at[i], &qx, &qy);
    const double off = std::sqrt((x - qx) * (x - qx) + (y - qy) * (y - qy));
    if (!(off <= kMaxDistalOffsetMm)) {
      return make_error(StatusCode::kInvalidArgument, "outline: distal_ends[", i, "] lies ", off,
                        " mm from the arch's centre line in the occlusal plane (at most ",
                        kMaxDistalOffsetMm, "): put it at the last tooth to cover");
    }
    r->distal_offset_mm[i] = off;
  }
  if ((at[0] < middle) == (at[1] < middle)) {
    return make_error(StatusCode::kInvalidArgument,
                      "outline: distal_ends[0] and [1] lie on the same half of the arch (",
                      at[0] - middle, " and ", at[1] - middle,
                      " mm along it from its middle): give one point a side");
  }
  const int lo = at[0] < middle ? 0 : 1;  // the point that cuts the start
  const double a = at[lo] + kDistalInsideMm, b = at[1 - lo] - kDistalInsideMm;
  places->cut[0] = a > places->start;
  places->cut[1] = b < end;
  const double from = places->cut[0] ? a : places->start, to = places->cut[1] ? b : end;
  if (!(to - from >= kMinArchMm)) {
    return make_error(StatusCode::kInvalidArgument, "outline: the distal ends leave ", to - from,
                      " mm of the arch (at least ", kMinArchMm, ")");
  }
  places->limit[0] = a;
  places->limit[1] = b;
  r->distal_limited = true;
  r->distal_cut_mm[lo] = from - places->start;
  r->distal_cut_mm[1 - lo] = end - to;
  size_t kept = 0, first = n;
  for (size_t k = 0; k < n; ++k) {
    const double s = places->start + places->step * static_cast<double>(k);
    if (places->cut[0] && s < a + 0.5 * places->step) continue;
    if (places->cut[1] && s > b - 0.5 * places->step) continue;
    first = std::min(first, k);
    ++kept;
  }
  places->first = kept > 0 ? first : 0;
  places->grid = kept;
  return Status::ok();
}

}  // namespace

uint64_t projector_bound() {
  const size_t segments = std::max<size_t>(kSectors, kMaxArchPoints);
  const size_t chunks = (segments + projector_chunk(segments) - 1) / projector_chunk(segments);
  const size_t groups = (chunks + kProjectorGroup - 1) / kProjectorGroup;
  return arena_array_bound<double>(4 * segments) + arena_array_bound<double>(segments) +
         arena_array_bound<double>(4 * chunks) + arena_array_bound<double>(4 * groups) +
         cell_grid_bound();
}

namespace {

// Where the arch runs along its centre line: the ends along it and the centre.
struct ArchExtent {
  double s_lo = 0, s_hi = 0;  // the band's points' places along the arch, least and greatest
  double cx = 0, cy = 0;      // their centre
};

// The arch's centre line through the band's points (`line_pts`), smoothed; every point of
// `line_pts` and `pts` given its place along it (s, o).
Status centre_line(const Context& ctx, ArenaArray<ArchPoint>& line_pts, Span<ArchPoint> pts,
                   Polyline* arch, ArchExtent* extent) {
  Arena& arena = *ctx.arena;
  Polyline first;
  SPLINTCORE_RETURN_IF_ERROR(sector_line(arena, line_pts.span(), &first));
  *arch = first;
  for (int pass = 0; pass < kSmoothPasses; ++pass) {
    Polyline next;
    SPLINTCORE_RETURN_IF_ERROR(smooth_line(ctx, line_pts.span(), *arch, &next));
    *arch = next;
  }
  // The ends and the centre from the band's vertices (they move with the jaws; see
  // occlusal_points), the columns' places along the arch for the picks' windows.
  double s_lo = HUGE_VAL, s_hi = -HUGE_VAL, cx = 0, cy = 0;
  {
    ArenaScope scope(arena);  // the projector goes when done
    Projector proj;
    SPLINTCORE_RETURN_IF_ERROR(make_projector(arena, *arch, &proj));
    SPLINTCORE_RETURN_IF_ERROR(project_all(ctx, proj, line_pts.span()));
    SPLINTCORE_RETURN_IF_ERROR(project_all(ctx, proj, pts));
    for (const ArchPoint& a : line_pts) {
      s_lo = std::min(s_lo, a.s);
      s_hi = std::max(s_hi, a.s);
      cx += a.x;
      cy += a.y;
    }
  }
  cx /= static_cast<double>(line_pts.size());
  cy /= static_cast<double>(line_pts.size());
  *extent = ArchExtent{s_lo, s_hi, cx, cy};
  return Status::ok();
}

// The picks at `places` (their data gathered): each pair's faces the depth into the tooth
// under it, their reach across the arch; the wafer's thinnest and thickest into `report`.
Status set_picks(const Polyline& arch, const PickPlaces& places, const PickData* data,
                 const Frame& f, double side, const OutlineOptions& options, Pick* up, Pick* lo,
                 OutlineReport* report) {
  const size_t n = places.size();
  const double depth = options.indentation_depth_mm;
  report->min_wafer_mm = HUGE_VAL;
  report->max_wafer_mm = 0;
  for (size_t i = 0; i < n; ++i) {
    double x, y, lx, ly;
    point_at(arch, places.at(i), &x, &y, &lx, &ly);
    // The face: the depth below (above) the tooth under the pick, but never deeper than the
    // depth and kDeepSlackMm into any tooth within the bound's reach.
    const double top = std::min(data[i].near_h[0] + depth, data[i].h[0] + depth + kDeepSlackMm);
    const double bottom = std::max(data[i].near_h[1] - depth, data[i].h[1] - depth - kDeepSlackMm);
    const double wafer = top - bottom;
    if (!(wafer >= kMinWaferMm)) {
      return make_error(StatusCode::kInvalidArgument, "outline: the wafer would be ", wafer,
                        " mm thick at pick ", i, " (at least ", kMinWaferMm,
                        "): the jaws are too close there; open the bite (\"bite_opening_mm\") "
                        "or indent less")
          .at_index(i);
    }
    report->min_wafer_mm = std::min(report->min_wafer_mm, wafer);
    report->max_wafer_mm = std::max(report->max_wafer_mm, wafer);
    const Vec3 flat = f.e1 * x + f.e2 * y;
    const Vec3 buccal = (f.e1 * lx + f.e2 * ly) * side;
    for (int jaw = 0; jaw < 2; ++jaw) {
      Pick& p = jaw == 0 ? up[i] : lo[i];
      p = Pick{};  // the buffers are raw arena memory: no normal (zero) unless set
      p.position = flat + f.n * (jaw == 0 ? top : bottom);
      p.direction = buccal;
      p.inner_length =
          std::min(std::max(data[i].lingual, 0.0), kMaxReachAcrossMm) + options.overhang_mm;
      p.outside_length =
          std::min(std::max(data[i].buccal, 0.0), kMaxReachAcrossMm) + options.overhang_mm;
    }
  }
  return Status::ok();
}

}  // namespace

Status arch_and_picks(const Context& ctx, const Mesh& upper, const Mesh& lower,
                      const Vec3& lower_offset, const Frame& f, const Grid& g, const Plane& plane,
                      const OutlineOptions& options, const OutlineBuffers& buffers, Outline* out) {
  Arena& arena = *ctx.arena;
  ArenaArray<ArchPoint> pts(&arena), line_pts(&arena);
  uint64_t counts[2] = {0, 0};
  // The columns reach deeper by as much as the indentation goes past kBandIndentationMm, so
  // that the picks' reach across the arch holds every column the slab between the faces
  // meets (the palate and the gums beside teeth indented deeply): the base's side walls then
  // pass outside them (DesignReport::walls). At the default indentation and below, the band.
  const double column_band =
      kOcclusalBandMm + std::max(0.0, options.indentation_depth_mm - kBandIndentationMm);
  SPLINTCORE_RETURN_IF_ERROR(occlusal_points(ctx, upper, lower, lower_offset, f, g, plane,
                                             column_band, &pts, &line_pts, counts));
  out->report.cells_upper = counts[0];
  out->report.cells_lower = counts[1];
  Polyline arch;
  ArchExtent extent;
  SPLINTCORE_RETURN_IF_ERROR(centre_line(ctx, line_pts, pts.span(), &arch, &extent));
  const double s_lo = extent.s_lo, s_hi = extent.s_hi, cx = extent.cx, cy = extent.cy;
  out->report.arch_length_mm = s_hi - s_lo;
  if (s_hi - s_lo < kMinArchMm) {
    return make_error(StatusCode::kInvalidArgument, "outline: the arch is too short: ", s_hi - s_lo,
                      " mm end to end (at least ", kMinArchMm, ")");
  }
  const double start = s_lo - options.overhang_mm, end = s_hi + options.overhang_mm;
  const size_t grid = static_cast<size_t>(std::ceil((end - start) / options.pick_spacing_mm)) + 1;
  const double step = (end - start) / static_cast<double>(grid - 1);
  // The buccal side: the left normal's side if, over the picks, it faces away from the centre.
  double side = 0;
  for (size_t i = 0; i < grid; ++i) {
    double x, y, lx, ly;
    point_at(arch, start + step * static_cast<double>(i), &x, &y, &lx, &ly);
    side += lx * (x - cx) + ly * (y - cy);
  }
  side = side < 0 ? -1.0 : 1.0;
  if (grid > kMaxPicks) {
    return make_error(StatusCode::kInvalidArgument, "outline: the arch is ", end - start,
                      " mm long: more than ", kMaxPicks, " picks at ", options.pick_spacing_mm,
                      " mm apart");
  }
  PickPlaces places;
  places.start = start;
  places.step = step;
  places.grid = grid;
  SPLINTCORE_RETURN_IF_ERROR(
      cut_distal_ends(arch, f, options, s_lo, s_hi, grid, &places, &out->report));
  const size_t n = places.size();
  PickData* data = arena.allocate_array<PickData>(n);
  double* at = arena.allocate_array<double>(n);
  if (data == nullptr || at == nullptr) return arena.exhausted_status();
  Pick* up = buffers.upper;
  Pick* lo = buffers.lower;
  Vec3* line = buffers.arch;
  for (size_t i = 0; i < n; ++i) at[i] = places.at(i);
  gather_picks(pts.span(), at, n, step, side, data);
  const size_t stride = sizeof(PickData) / sizeof(double);
  if (!fill_gaps(&data[0].h[0], n, stride) || !fill_gaps(&data[0].h[1], n, stride) ||
      !fill_gaps(&data[0].near_h[0], n, stride) || !fill_gaps(&data[0].near_h[1], n, stride) ||
      !fill_gaps(&data[0].lingual, n, stride) || !fill_gaps(&data[0].buccal, n, stride)) {
    return Status::error(StatusCode::kInvalidArgument,
                         "outline: a jaw shows no occlusal surface along the arch");
  }
  SPLINTCORE_RETURN_IF_ERROR(set_picks(arch, places, data, f, side, options, up, lo, &out->report));
  for (size_t i = 0; i < arch.n; ++i) {
    line[i] =
        f.e1 * arch.x[i] + f.e2 * arch.y[i] + f.n * plane.at(arch.x[i] - g.cx, arch.y[i] - g.cy);
  }
  out->upper = Span<const Pick>(up, n);
  out->lower = Span<const Pick>(lo, n);
  out->arch = Span<const Vec3>(line, arch.n);
  out->report.picks = static_cast<uint32_t>(n);
  return Status::ok();
}

}  // namespace outline_detail
}  // namespace splintcore
