// The swept volume of the jaws along the insertion direction, streamed slab by slab into the
// tiled extractor (Chen et al. 2016, "The Interference Elimination": each layer of the
// blocked-out model contains the layers before it; here with an exact outside distance and
// an extrapolated inside field instead of the paper's binary image, see blockout.h).
//
// Per column of the grid (x, y) the state is the running minimum of the distances from the
// column's segments [w(k-1), w(k)] to the jaws' front and silhouette triangles, clamped to a
// band; 0 marks a column whose half-line has met a jaw (decided by the exact segment-triangle
// predicate). Layers are produced in increasing w; five raw layers are kept so that each
// output layer can be corrected from its neighbours two samples away along each axis.
// Segment-segment distance: Ericson, "Real-Time Collision Detection", 5.1.9.
#include <cmath>
#include <cstring>

#include "blockout/frame.h"
#include "blockout/tiles.h"
#include "core/fminmax.h"
#include "splintcore/blockout.h"
#include "splintcore/distance.h"

namespace splintcore {

namespace {

constexpr uint32_t kRing = 5;        // raw layers kept: the output layer and two on each side
constexpr double kBandVoxels = 2.1;  // band half-width in voxels (the correction reads 2 h out)
constexpr uint32_t kMaxBands = 64;
// The extractor's slab when filtering (keep_triangle): one layer a fill call, so the working set
// under the log holds two sample layers (the carried one and the new one). Larger slabs only save
// the carried layer's copy per call (the output never depends on it); on the real dentition at
// 0.1 mm each more layer is 1.8 MB under the design's peak.
constexpr uint32_t kKeepLayers = 1;
// The extractor's id pool when filtering: this share of the full pool (ten ids per grid point
// of a layer) first, the full pool only when a layer needs more (the real dentition's sweep at
// 0.1 mm needs under a third of the quarter; the full pool is 16.8 MB there).
constexpr uint64_t kKeepPoolShare = 4;
constexpr float kTinyPositive = 1.17549435e-38f;  // FLT_MIN: an outside distance that rounded to 0

// Squared distance between the segments p1q1 and p2q2 (the distance module's).
inline double segment_segment_d2(const Vec3& p1, const Vec3& q1, const Vec3& p2, const Vec3& q2) {
  Vec3 x, y;
  return segment_closest(p1, q1, p2, q2, &x, &y);
}

// Squared distance from the segment pq to the triangle abc, which it does not meet: the
// closest pair has an endpoint of pq or a point of the triangle's boundary.
double segment_triangle_d2(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b,
                           const Vec3& c) {
  double best = length_squared(p - closest_point_on_triangle(p, a, b, c));
  double d2 = length_squared(q - closest_point_on_triangle(q, a, b, c));
  if (d2 < best) best = d2;
  d2 = segment_segment_d2(p, q, a, b);
  if (d2 < best) best = d2;
  d2 = segment_segment_d2(p, q, b, c);
  if (d2 < best) best = d2;
  d2 = segment_segment_d2(p, q, c, a);
  if (d2 < best) best = d2;
  return best;
}

// Order-preserving 64-bit key of a finite double.
inline uint64_t double_key(double v) {
  uint64_t bits;
  std::memcpy(&bits, &v, 8);
  return (bits >> 63) != 0 ? ~bits : bits | (uint64_t{1} << 63);
}

struct Sweep {
  const Context* ctx = nullptr;
  Frame frame;
  VolumeGrid grid;       // local frame: z along the direction; the whole sweep
  VolumeGrid mesh_grid;  // the part extracted: layers k0 .. k0 + mesh_grid.nz - 1
  uint32_t k0 = 0;
  // Samples sit on one lattice whatever the region: sample (x, y) of the grid is lattice
  // point (ix0 + x, iy0 + y), its coordinates computed from the lattice's origin, so a region
  // sees exactly the field values of the whole sweep.
  Vec3 lattice{};
  int64_t ix0 = 0, iy0 = 0;
  bool empty = false;  // the region misses the sweep: nothing to extract
  double band = 0;
  float fband = 0;
  double step = 0;  // band / 65534: one unit of the stored distances
  bool correct_bias = true;
  // Jaws in the local frame.
  Span<const Vec3> vertices;  // all jaws, concatenated
  Span<const Triangle> tris;  // front and silhouette triangles (global vertex ids), by w-min
  Span<const double> tri_wmin;
  Span<const double> tri_wmax;
  uint32_t next_tri = 0;
  ArenaArray<uint32_t> active;
  // Column state and raw layers.
  // Raw layers: the running minimum of each column, as distance / step rounded up (0: the
  // column has met a jaw; kBeyondBand: at least the band). Layer k at slot k % kRing; the
  // newest is the column state.
  uint16_t* ring = nullptr;
  uint16_t* state = nullptr;
  uint32_t raw_done = 0;  // raw layers 0 .. raw_done - 1 are made
  // Closing (closing_radius > 0): corrected layers in a ring of 2 m + 1, and the search's
  // offsets sorted by length.
  double closing_r = 0;
  uint32_t m = 0;
  float* cring = nullptr;
  uint32_t corrected_done = 0;
  struct Offset {
    int16_t dx, dy, dz;
    int16_t pad;
    float length;  // mm
  };
  const Offset* offsets = nullptr;
  uint32_t offset_count = 0;
  uint32_t bands = 1;  // bands of rows per layer (the executor's concurrency, x 4)
  SweepStats* stats = nullptr;
};

constexpr uint16_t kBeyondBand = 65535;

// A distance in (0, band) as a count of steps, rounded up (so a minimum of counts is the count
// of the minimum), at least 1 (0 marks inside); kBeyondBand from the band on.
inline uint16_t quantize(const Sweep& s, double d) {
  if (!(d < s.band)) return kBeyondBand;
  const double q = std::ceil(d / s.step);
  return q < 1 ? 1 : (q > 65534 ? 65534 : static_cast<uint16_t>(q));
}
inline float dequantize(const Sweep& s, uint16_t q) {
  return q == kBeyondBand ? s.fband : static_cast<float>(static_cast<double>(q) * s.step);
}

inline double sample_coord(double origin, double spacing, int64_t i) {
  return origin + spacing * static_cast<double>(i);
}

struct ColumnCounts {
  uint64_t segment_tests = 0;
  uint64_t distance_evaluations = 0;
  uint64_t inside_columns = 0;
};

// The edge of triangle abc nearest the vertical line through (px, py) in plan: its squared
// plan distance (*best) and the height of that edge point (*best_w); the first edge of the
// least distance.
inline void nearest_edge_in_plan(const Vec3& a, const Vec3& b, const Vec3& c, double px, double py,
                                 double* best, double* best_w) {
  const Vec3* v[3] = {&a, &b, &c};
  for (int edge = 0; edge < 3; ++edge) {
    const Vec3& e0 = *v[edge];
    const Vec3& e1 = *v[(edge + 1) % 3];
    const double ex = e1.x - e0.x, ey = e1.y - e0.y;
    const double rx = px - e0.x, ry = py - e0.y;
    const double len2 = ex * ex + ey * ey;
    double t = len2 > 0 ? (rx * ex + ry * ey) / len2 : 0.0;
    t = clamp01(t);
    const double dx = rx - ex * t, dy = ry - ey * t;
    const double dd = dx * dx + dy * dy;
    if (dd < *best) {
      *best = dd;
      *best_w = e0.z + (e1.z - e0.z) * t;
    }
  }
}

// Advances the column state of rows [y_begin, y_end) over the segment [w_lo, w_hi] against
// the active triangles. Rows are independent, so bands of rows may run at once.
void sweep_rows(Sweep& s, double w_lo, double w_hi, int64_t y_begin, int64_t y_end,
                ColumnCounts* counts) {
  const VolumeGrid& g = s.grid;
  const double band2 = s.band * s.band;
  for (size_t n = 0; n < s.active.size(); ++n) {
    const Triangle& tri = s.tris[s.active[n]];
    const Vec3& a = s.vertices[tri.v[0]];
    const Vec3& b = s.vertices[tri.v[1]];
    const Vec3& c = s.vertices[tri.v[2]];
    // The shadow's box (exact: least and most corner coordinates) and that grown by the band.
    const double sx0 = min3_of(a.x, b.x, c.x), sx1 = max3_of(a.x, b.x, c.x);
    const double sy0 = min3_of(a.y, b.y, c.y), sy1 = max3_of(a.y, b.y, c.y);
    const double xmin = sx0 - s.band;
    const double xmax = sx1 + s.band;
    const double ymin = sy0 - s.band;
    const double ymax = sy1 + s.band;
    const double fx0 = std::ceil((xmin - s.lattice.x) / g.spacing.x) - static_cast<double>(s.ix0);
    const double fx1 = std::floor((xmax - s.lattice.x) / g.spacing.x) - static_cast<double>(s.ix0);
    const double fy0 = std::ceil((ymin - s.lattice.y) / g.spacing.y) - static_cast<double>(s.iy0);
    const double fy1 = std::floor((ymax - s.lattice.y) / g.spacing.y) - static_cast<double>(s.iy0);
    const int64_t x0 = fx0 < 0 ? 0 : static_cast<int64_t>(fx0);
    const int64_t y0 = fy0 < static_cast<double>(y_begin) ? y_begin : static_cast<int64_t>(fy0);
    const int64_t x1 = fx1 > g.nx - 1.0 ? g.nx - 1 : static_cast<int64_t>(fx1);
    const int64_t y1 = fy1 > static_cast<double>(y_end - 1) ? y_end - 1 : static_cast<int64_t>(fy1);
    if (y0 > y1) continue;
    // A triangle seen edge-on along w (vertical) gets the general tests; the others the
    // cheaper column tests below.
    const bool vertical = orient2d(a.x, a.y, b.x, b.y, c.x, c.y) == 0;
    for (int64_t y = y0; y <= y1; ++y) {
      const double py = sample_coord(s.lattice.y, g.spacing.y, s.iy0 + y);
      uint16_t* row = s.state + static_cast<size_t>(y) * g.nx;
      for (int64_t x = x0; x <= x1; ++x) {
        if (row[x] == 0) continue;  // inside for good
        const double px = sample_coord(s.lattice.x, g.spacing.x, s.ix0 + x);
        const Vec3 p{px, py, w_lo}, q{px, py, w_hi};
        ++counts->segment_tests;
        double d2 = 0;
        if (vertical) {
          if (segment_intersects_triangle(p, q, a, b, c)) {
            row[x] = 0;
            ++counts->inside_columns;
            continue;
          }
          ++counts->distance_evaluations;
          d2 = segment_triangle_d2(p, q, a, b, c);
        } else {
          // The triangle faces against w (clockwise seen from +w): the column is in its
          // closed projection when no edge has the column strictly on its left (and never
          // outside the shadow's box).
          const bool in_projection = px >= sx0 && px <= sx1 && py >= sy0 && py <= sy1 &&
                                     orient2d(a.x, a.y, b.x, b.y, px, py) <= 0 &&
                                     orient2d(b.x, b.y, c.x, c.y, px, py) <= 0 &&
                                     orient2d(c.x, c.y, a.x, a.y, px, py) <= 0;
          if (in_projection) {
            // The column crosses the plane at w*; it has reached it by w_hi exactly when q is
            // not strictly on the outer side (orient3d < 0 there). Crossings below w_lo were
            // found at an earlier layer (the triangle is active from w_hi >= w_min - band).
            if (orient3d(a, b, c, q) >= 0) {
              row[x] = 0;
              ++counts->inside_columns;
              continue;
            }
            // Below the triangle: the distance along the column falls until w*, so the top
            // of the segment is the closest point.
            ++counts->distance_evaluations;
            d2 = length_squared(q - closest_point_on_triangle(q, a, b, c));
          } else {
            // Outside the projection the closest approach of the whole vertical line is to an
            // edge, at its plan distance and at the height of that edge point; the distance
            // along the column is convex, so on [w_lo, w_hi] it is least at that height
            // clamped into the segment.
            double best = HUGE_VAL, best_w = 0;
            nearest_edge_in_plan(a, b, c, px, py, &best, &best_w);
            if (best >= band2) continue;
            ++counts->distance_evaluations;
            if (best_w >= w_lo && best_w <= w_hi) {
              d2 = best;
            } else {
              const Vec3 at{px, py, best_w < w_lo ? w_lo : w_hi};
              d2 = length_squared(at - closest_point_on_triangle(at, a, b, c));
            }
          }
        }
        if (d2 < band2) {
          const uint16_t steps = quantize(s, std::sqrt(d2));
          if (steps < row[x]) row[x] = steps;
        }
      }
    }
  }
}

// Makes raw layer k: advances the column state over the segment [w(k-1), w(k)].
Status make_raw_layer(Sweep& s, uint32_t k) {
  const VolumeGrid& g = s.grid;
  const double h = g.spacing.z;
  const double w_hi = sample_coord(g.origin.z, h, k);
  const double w_lo = sample_coord(g.origin.z, h, static_cast<int64_t>(k) - 1);
  // The state is the newest raw layer: layer k starts as a copy of layer k - 1 (all beyond
  // the band for the first) and takes the minimum in place.
  {
    const size_t layer = size_t{g.nx} * g.ny;
    uint16_t* slot = s.ring + (k % kRing) * layer;
    if (k == 0) {
      for (size_t i = 0; i < layer; ++i) slot[i] = kBeyondBand;
    } else {
      std::memcpy(slot, s.ring + ((k - 1) % kRing) * layer, layer * sizeof(uint16_t));
    }
    s.state = slot;
  }
  // Triangles that can come within the band of this segment.
  while (s.next_tri < s.tris.size() && s.tri_wmin[s.next_tri] <= w_hi + s.band) {
    if (!s.active.push_back(s.next_tri)) return s.ctx->arena->exhausted_status();
    ++s.next_tri;
  }
  // A triangle wholly below the segment has given every column all it can: a column in its
  // shadow met it at an earlier layer (it is inside), and along any other column the distance
  // to it grows with w above its top (the square's derivative is 2 (w - w of the closest
  // point) > 0), so the segment that held the column's closest approach (at a height within
  // the triangle's, while it was active) gave the least; this segment is farther.
  size_t kept = 0;
  for (size_t n = 0; n < s.active.size(); ++n) {
    const uint32_t t = s.active[n];
    if (s.tri_wmax[t] < w_lo) continue;  // passed for good
    s.active[kept++] = t;
  }
  s.active.shrink_size(kept);
  // Bands of rows on the executor: each band's columns are its own, and a minimum does
  // not depend on the order it is taken in, so the state is the same for any thread count.
  const uint32_t bands = s.bands;
  ColumnCounts counts[kMaxBands];
  auto band = [&](uint32_t i) {
    const int64_t y_begin = static_cast<int64_t>(uint64_t{g.ny} * i / bands);
    const int64_t y_end = static_cast<int64_t>(uint64_t{g.ny} * (i + 1) / bands);
    counts[i] = ColumnCounts{};
    sweep_rows(s, w_lo, w_hi, y_begin, y_end, &counts[i]);
  };
  parallel_for_each(s.ctx->executor, bands, band);
  for (uint32_t i = 0; i < bands; ++i) {
    s.stats->segment_tests += counts[i].segment_tests;
    s.stats->distance_evaluations += counts[i].distance_evaluations;
    s.stats->inside_columns += counts[i].inside_columns;
  }
  s.raw_done = k + 1;
  return Status::ok();
}

// Rows [y_begin, y_end) of output layer k (raw layers up to min(k + 2, nz - 1) made) into
// out; returns how many samples it corrected.
uint64_t make_output_rows(const Sweep& s, uint32_t k, float* out, int64_t y_begin, int64_t y_end) {
  const VolumeGrid& g = s.grid;
  uint64_t corrected = 0;
  const size_t layer = size_t{g.nx} * g.ny;
  // Raw layers k - 2 .. k + 2 (null: beyond the grid or not made).
  const uint16_t* z[5];
  for (int dz = -2; dz <= 2; ++dz) {
    const int64_t kk = static_cast<int64_t>(k) + dz;
    z[dz + 2] = (kk < 0 || kk >= static_cast<int64_t>(s.raw_done))
                    ? nullptr
                    : s.ring + (static_cast<uint64_t>(kk) % kRing) * layer;
  }
  const uint16_t* here = z[2];
  const float fband = s.fband;
  const int64_t nx = g.nx, ny = g.ny;
  for (int64_t y = y_begin; y < y_end; ++y) {
    const size_t row = static_cast<size_t>(y) * g.nx;
    for (int64_t x = 0; x < nx; ++x) {
      const size_t at = row + static_cast<size_t>(x);
      if (here[at] != 0) {  // outside: the exact distance, as is
        out[at] = dequantize(s, here[at]);
        continue;
      }
      float value = -fband;
      if (s.correct_bias) {
        // Samples i + e and i + 2 e along each axis direction e (null pointer: beyond).
        const uint16_t* near[6];
        const uint16_t* far[6];
        const size_t sx = 1, sy = g.nx;
        near[0] = x + 1 < nx ? here + at + sx : nullptr;
        far[0] = x + 2 < nx ? here + at + 2 * sx : nullptr;
        near[1] = x >= 1 ? here + at - sx : nullptr;
        far[1] = x >= 2 ? here + at - 2 * sx : nullptr;
        near[2] = y + 1 < ny ? here + at + sy : nullptr;
        far[2] = y + 2 < ny ? here + at + 2 * sy : nullptr;
        near[3] = y >= 1 ? here + at - sy : nullptr;
        far[3] = y >= 2 ? here + at - 2 * sy : nullptr;
        near[4] = z[3] != nullptr ? z[3] + at : nullptr;
        far[4] = z[4] != nullptr ? z[4] + at : nullptr;
        near[5] = z[1] != nullptr ? z[1] + at : nullptr;
        far[5] = z[0] != nullptr ? z[0] + at : nullptr;
        // The steepest direction with two outside samples in the band: extrapolate from it.
        double best_slope = 0, best = 0;
        bool found = false;
        for (int e = 0; e < 6; ++e) {
          if (near[e] == nullptr || far[e] == nullptr) continue;
          const uint16_t q1 = *near[e], q2 = *far[e];
          if (q1 == 0 || !(q2 > q1) || q2 == kBeyondBand) continue;
          const double f1 = static_cast<double>(dequantize(s, q1));
          const double f2 = static_cast<double>(dequantize(s, q2));
          const double slope = f2 - f1;
          if (!found || slope > best_slope) {
            found = true;
            best_slope = slope;
            best = 2.0 * f1 - f2;
          }
        }
        if (found) {
          ++corrected;
          value = static_cast<float>(best);
          if (!(value < 0.0f)) value = -kTinyPositive;
          if (value < -fband) value = -fband;
        }
      }
      out[at] = value;
    }
  }
  return corrected;
}

// Output layer k into out: bands of rows on the executor (each sample depends on the raw
// layers alone), the corrected samples counted per band.
void make_output_layer(Sweep& s, uint32_t k, float* out) {
  const uint32_t bands = s.bands;
  uint64_t corrected[kMaxBands];
  auto band = [&](uint32_t i) {
    const int64_t y_begin = static_cast<int64_t>(uint64_t{s.grid.ny} * i / bands);
    const int64_t y_end = static_cast<int64_t>(uint64_t{s.grid.ny} * (i + 1) / bands);
    corrected[i] = make_output_rows(s, k, out, y_begin, y_end);
  };
  parallel_for_each(s.ctx->executor, bands, band);
  for (uint32_t i = 0; i < bands; ++i) s.stats->corrected_samples += corrected[i];
}

// The corrected layers up to `last` (inclusive), with the raw layers they need.
Status advance(Sweep& s, uint32_t last, float* (*slot)(Sweep&, uint32_t)) {
  while (s.corrected_done <= last) {
    const uint32_t c = s.corrected_done;
    const uint32_t need = c + 2 < s.grid.nz ? c + 2 : s.grid.nz - 1;
    while (s.raw_done <= need) {
      SPLINTCORE_RETURN_IF_ERROR(report_progress(*s.ctx, "sweep", s.raw_done, s.grid.nz));
      SPLINTCORE_RETURN_IF_ERROR(make_raw_layer(s, s.raw_done));
    }
    make_output_layer(s, c, slot(s, c));
    ++s.corrected_done;
  }
  return Status::ok();
}

float* closing_slot(Sweep& s, uint32_t c) {
  return s.cring + (c % (2 * s.m + 1)) * (size_t{s.grid.nx} * s.grid.ny);
}

// The closed field of layer k: corrected layers k - m .. k + m are in the closing ring.
void make_closed_layer(Sweep& s, uint32_t k, float* out) {
  const VolumeGrid& g = s.grid;
  const size_t layer = size_t{g.nx} * g.ny;
  const uint32_t window = 2 * s.m + 1;
  const float* here = s.cring + (k % window) * layer;
  const double r = s.closing_r;
  const double reach = s.band - r;  // f(q) - r is at most this (f is clamped to the band)
  const int64_t nx = g.nx, ny = g.ny, nz = g.nz;
  for (int64_t y = 0; y < ny; ++y) {
    for (int64_t x = 0; x < nx; ++x) {
      const size_t at = static_cast<size_t>(y) * g.nx + static_cast<size_t>(x);
      const float fp = here[at];
      if (!(fp > 0.0f)) {  // inside the swept volume: inside its closing too
        out[at] = fp;
        continue;
      }
      if (static_cast<double>(fp) > r) {
        // Outside the dilation: outside the closing, which holds S, at most f from it. Taken
        // as f: the closing's filled parts are at least r from here, so no edge of the zero
        // (or inset) surface reads this value, and an offset surface (iso up to r) meets it
        // only where the closing is S itself, whose exact distance f is.
        out[at] = fp;
        continue;
      }
      ++s.stats->closing_samples;
      // Least |p - q| - (f(q) - r) over q outside the dilation; it is never below r - f(p)
      // (f is 1-Lipschitz), so reaching that ends the search, as does an offset too long
      // for any q to beat the best.
      const double floor_dc = r - static_cast<double>(fp);
      double best = HUGE_VAL;
      for (uint32_t i = 0; i < s.offset_count; ++i) {
        const auto& o = s.offsets[i];
        const double len = static_cast<double>(o.length);
        if (len - reach >= best) break;
        const int64_t qx = x + o.dx, qy = y + o.dy, qz = static_cast<int64_t>(k) + o.dz;
        if (qx < 0 || qy < 0 || qz < 0 || qx >= nx || qy >= ny || qz >= nz) continue;
        const float fq = s.cring[(static_cast<uint64_t>(qz) % window) * layer +
                                 static_cast<size_t>(qy) * g.nx + static_cast<size_t>(qx)];
        if (!(static_cast<double>(fq) > r)) continue;
        const double cand = len - (static_cast<double>(fq) - r);
        if (cand < best) {
          best = cand;
          if (best <= floor_dc) break;
        }
      }
      // Erosion field r - dist(p, outside the dilation); the closing is the swept volume
      // or the eroded dilation, whichever holds p.
      double e = best == HUGE_VAL ? -s.band : r - best;
      if (e < -s.band) e = -s.band;
      if (e < 0) ++s.stats->closed_samples;
      const double v = e < static_cast<double>(fp) ? e : static_cast<double>(fp);
      out[at] = v < 0 && static_cast<float>(v) == 0.0f ? -kTinyPositive : static_cast<float>(v);
    }
  }
}

Status fill_layers(void* user, uint32_t z_begin, uint32_t z_end, Span<float> out) {
  Sweep& s = *static_cast<Sweep*>(user);
  const size_t layer = size_t{s.grid.nx} * s.grid.ny;
  for (uint32_t z = z_begin; z < z_end; ++z) {
    const uint32_t k = z + s.k0;
    float* dst = out.data() + size_t{z - z_begin} * layer;
    if (s.m == 0) {
      const uint32_t need = k + 2 < s.grid.nz ? k + 2 : s.grid.nz - 1;
      while (s.raw_done <= need) {
        SPLINTCORE_RETURN_IF_ERROR(report_progress(*s.ctx, "sweep", s.raw_done, s.grid.nz));
        SPLINTCORE_RETURN_IF_ERROR(make_raw_layer(s, s.raw_done));
      }
      make_output_layer(s, k, dst);
      continue;
    }
    const uint32_t last = k + s.m < s.grid.nz ? k + s.m : s.grid.nz - 1;
    SPLINTCORE_RETURN_IF_ERROR(advance(s, last, closing_slot));
    make_closed_layer(s, k, dst);
  }
  return Status::ok();
}

struct WorldVisitor {
  const Frame* frame = nullptr;
  const MarchingCubesVisitor* inner = nullptr;
};

Status world_vertex(void* user, uint32_t id, const Vec3& p) {
  const WorldVisitor& w = *static_cast<WorldVisitor*>(user);
  if (w.inner->vertex == nullptr) return Status::ok();
  return w.inner->vertex(w.inner->user, id, to_world(*w.frame, p));
}
Status world_triangle(void* user, const Triangle& t, const Vec3& a, const Vec3& b, const Vec3& c) {
  const WorldVisitor& w = *static_cast<WorldVisitor*>(user);
  if (w.inner->triangle == nullptr) return Status::ok();
  return w.inner->triangle(w.inner->user, t, to_world(*w.frame, a), to_world(*w.frame, b),
                           to_world(*w.frame, c));
}

// The options' ranges, checked before anything is allocated.
Status check_sweep_options(const SweepOptions& o) {
  if (!(o.voxel > 0) || !is_finite(o.voxel) || !(o.extent >= 0) || !is_finite(o.extent)) {
    return make_error(StatusCode::kInvalidArgument,
                      "sweep: the voxel size must be > 0 and the extent >= 0 (voxel ", o.voxel,
                      " mm, extent ", o.extent, " mm)");
  }
  if (!(o.closing_radius == 0 ||
        (o.closing_radius >= 2 * o.voxel && o.closing_radius <= 10 * o.voxel))) {
    return make_error(StatusCode::kInvalidArgument,
                      "sweep: the closing radius must be 0 or "
                      "from 2 to 10 voxels (radius ",
                      o.closing_radius, " mm, voxel ", o.voxel, " mm)");
  }
  if (!(o.inset >= 0) || !(o.inset < 2 * o.voxel)) {
    return make_error(StatusCode::kInvalidArgument,
                      "sweep: the inset must be >= 0 and below two "
                      "voxels (inset ",
                      o.inset, " mm, voxel ", o.voxel, " mm)");
  }
  if (!(o.decimate_error >= 0) || !(o.decimate_error <= o.voxel * 0.1)) {
    return make_error(StatusCode::kInvalidArgument,
                      "sweep: the decimation error must be from 0 to a tenth of a voxel (",
                      o.decimate_error, " mm, voxel ", o.voxel, " mm)");
  }
  if (o.keep_triangle != nullptr &&
      (!o.has_region || !o.open_at_region || !o.float32_vertices || o.decimate_error > 0)) {
    return make_error(StatusCode::kInvalidArgument,
                      "sweep: keep_triangle needs a region, open_at_region and float32_vertices, "
                      "and no decimation");
  }
  if (!(o.offset >= 0) || !(o.offset <= 20 * o.voxel) || (o.offset > 0 && o.inset != 0)) {
    return make_error(StatusCode::kInvalidArgument,
                      "sweep: the offset must be from 0 to 20 "
                      "voxels, with no inset (offset ",
                      o.offset, " mm, inset ", o.inset, " mm, voxel ", o.voxel, " mm)");
  }
  return Status::ok();
}

// The jaws' box in the local frame (all their vertices: its corner anchors the lattice, so a
// region sees the samples of the whole sweep) and their counts.
Status jaws_box(Span<const Mesh> jaws, const SweepOptions& o, const Frame& frame, Aabb* box,
                size_t* vertex_total, size_t* triangle_total) {
  uint64_t vertex_count = 0, triangle_count = 0;
  for (const Mesh& m : jaws) {
    vertex_count += m.vertices.size();
    triangle_count += m.triangles.size();
  }
  if (triangle_count == 0) {
    return make_error(StatusCode::kInvalidArgument, "sweep: the jaws have no triangles");
  }
  if (vertex_count >= (uint64_t{1} << 32) || triangle_count >= (uint64_t{1} << 32)) {
    return make_error(StatusCode::kLimitExceeded,
                      "sweep: more than 2^32 - 1 vertices or triangles");
  }
  // Both below 2^32 now, so they fit a 32-bit size_t too.
  *vertex_total = static_cast<size_t>(vertex_count);
  *triangle_total = static_cast<size_t>(triangle_count);
  for (size_t j = 0; j < jaws.size(); ++j) {
    for (size_t i = 0; i < jaws[j].vertices.size(); ++i) {
      const Vec3 p = jaw_point(o, jaws, j, i);
      if (!is_finite(p)) {
        return make_error(StatusCode::kNonFinite, "sweep: jaw ", j, " has a non-finite vertex")
            .at_index(i);
      }
      box->add(to_local(frame, p));
    }
  }
  return Status::ok();
}

inline uint32_t popcount64(uint64_t x) {
  x = x - ((x >> 1) & 0x5555555555555555ull);
  x = (x & 0x3333333333333333ull) + ((x >> 2) & 0x3333333333333333ull);
  x = (x + (x >> 4)) & 0x0f0f0f0f0f0f0f0full;
  return static_cast<uint32_t>((x * 0x0101010101010101ull) >> 56);
}

// Whether the sweep can use the triangle (local corners a, b, c): it faces against w or
// across it (orient2d of the projection <= 0: the outward normal has no component along w),
// its shadow grown by the band meets the grid's columns, and it starts within the band of
// the last layer. sweep_rows() and make_raw_layer() never touch the others, so leaving them
// out changes nothing but the memory (a voxel of slack against rounding).
bool needed_triangle(const Sweep& s, const Vec3& a, const Vec3& b, const Vec3& c) {
  if (orient2d(a.x, a.y, b.x, b.y, c.x, c.y) > 0 || s.empty) return false;
  const VolumeGrid& g = s.grid;
  const double reach = s.band + g.spacing.x;
  const double x_hi = g.origin.x + g.spacing.x * (g.nx - 1.0);
  const double y_hi = g.origin.y + g.spacing.y * (g.ny - 1.0);
  const double w_hi = g.origin.z + g.spacing.z * (g.nz - 1.0);
  return max3_of(a.x, b.x, c.x) + reach >= g.origin.x && min3_of(a.x, b.x, c.x) - reach <= x_hi &&
         max3_of(a.y, b.y, c.y) + reach >= g.origin.y && min3_of(a.y, b.y, c.y) - reach <= y_hi &&
         min3_of(a.z, b.z, c.z) - reach <= w_hi;
}

// The triangles the sweep needs (needed_triangle, in input order) with ids into
// s->vertices, the local copies of only the vertices they use (in input order). Bits per
// vertex and per triangle say which are kept (vertex ids by rank among the kept).
// stats->front_triangles counts the front triangles of all the jaws.
Status select_front(Arena& arena, Span<const Mesh> jaws, const SweepOptions& o, size_t vertex_total,
                    size_t triangle_total, Sweep* s, ArenaArray<Triangle>* front,
                    SweepStats* stats) {
  const size_t vwords = vertex_total / 64 + 1, twords = triangle_total / 64 + 1;
  uint64_t* vbits = arena.allocate_array<uint64_t>(vwords);
  uint32_t* rank = arena.allocate_array<uint32_t>(vwords);
  uint64_t* tbits = arena.allocate_array<uint64_t>(twords);
  if (vbits == nullptr || rank == nullptr || tbits == nullptr) return arena.exhausted_status();
  std::memset(vbits, 0, vwords * 8);
  std::memset(tbits, 0, twords * 8);
  size_t base = 0, t_at = 0, kept = 0;
  uint64_t front_total = 0;
  for (size_t j = 0; j < jaws.size(); ++j) {
    const Mesh& m = jaws[j];
    for (size_t t = 0; t < m.triangles.size(); ++t, ++t_at) {
      Vec3 p[3];
      for (int k = 0; k < 3; ++k) {
        const uint32_t v = m.triangles[t].v[k];
        if (v >= m.vertices.size()) {
          return make_error(StatusCode::kInvalidMesh, "sweep: jaw ", j, " triangle ", t,
                            " has a vertex id out of range")
              .at_index(t);
        }
        p[k] = to_local(s->frame, jaw_point(o, jaws, j, v));
      }
      if (orient2d(p[0].x, p[0].y, p[1].x, p[1].y, p[2].x, p[2].y) <= 0) ++front_total;
      if (!needed_triangle(*s, p[0], p[1], p[2])) continue;
      tbits[t_at / 64] |= uint64_t{1} << (t_at % 64);
      ++kept;
      for (int k = 0; k < 3; ++k) {
        const size_t g = base + m.triangles[t].v[k];
        vbits[g / 64] |= uint64_t{1} << (g % 64);
      }
    }
    base += m.vertices.size();
  }
  stats->front_triangles = front_total;
  uint32_t used = 0;
  for (size_t w = 0; w < vwords; ++w) {
    rank[w] = used;
    used += popcount64(vbits[w]);
  }
  Vec3* local = arena.allocate_array<Vec3>(used);
  if (used > 0 && local == nullptr) return arena.exhausted_status();
  if (!front->reserve(kept > 0 ? kept : 1)) return arena.exhausted_status();
  const auto id = [&](size_t g) {
    const uint64_t below = vbits[g / 64] & ((uint64_t{1} << (g % 64)) - 1);
    return rank[g / 64] + popcount64(below);
  };
  base = 0;
  t_at = 0;
  for (size_t j = 0; j < jaws.size(); ++j) {
    const Mesh& m = jaws[j];
    for (size_t i = 0; i < m.vertices.size(); ++i) {
      const size_t g = base + i;
      if ((vbits[g / 64] >> (g % 64)) & 1) {
        local[id(g)] = to_local(s->frame, jaw_point(o, jaws, j, i));
      }
    }
    for (size_t t = 0; t < m.triangles.size(); ++t, ++t_at) {
      if (((tbits[t_at / 64] >> (t_at % 64)) & 1) == 0) continue;
      Triangle g;
      for (int k = 0; k < 3; ++k) g.v[k] = id(base + m.triangles[t].v[k]);
      (void)front->push_back(g);
    }
    base += m.vertices.size();
  }
  s->vertices = Span<const Vec3>(local, used);
  return Status::ok();
}

// The front triangles sorted by w-min (stable radix sort: ties keep input order), with their
// w ranges: s->tris (`front` itself, permuted in place), s->tri_wmin, s->tri_wmax. The sort's
// keys are given back before the ranges are allocated, so what stays is 28 bytes a triangle
// (on the real mandible's voxel blockout 4 MB less than a sorted copy beside the keys).
Status sort_front(Arena& arena, ArenaArray<Triangle>* front, Sweep* s) {
  const Vec3* local = s->vertices.data();
  const size_t nf = front->size();
  Triangle* tris = front->data();
  {
    ArenaScope keys_scope(arena);
    KeyIndex* keys = arena.allocate_array<KeyIndex>(nf);
    if (nf > 0 && keys == nullptr) return arena.exhausted_status();
    for (size_t t = 0; t < nf; ++t) {
      const Triangle& g = tris[t];
      const double lo = min3_of(local[g.v[0]].z, local[g.v[1]].z, local[g.v[2]].z);
      keys[t] = {double_key(lo), static_cast<uint32_t>(t), 0};
    }
    SPLINTCORE_RETURN_IF_ERROR(radix_sort(arena, Span<KeyIndex>(keys, nf)));
    // Position t takes triangle keys[t].index: each cycle of the permutation is walked once,
    // a position marked done by pointing at itself.
    for (size_t start = 0; start < nf; ++start) {
      if (keys[start].index == start) continue;
      const Triangle first = tris[start];
      size_t at = start;
      for (;;) {
        const size_t from = keys[at].index;
        keys[at].index = static_cast<uint32_t>(at);
        if (from == start) {
          tris[at] = first;
          break;
        }
        tris[at] = tris[from];
        at = from;
      }
    }
  }
  double* wmin = arena.allocate_array<double>(nf);
  double* wmax = arena.allocate_array<double>(nf);
  if (nf > 0 && (wmin == nullptr || wmax == nullptr)) return arena.exhausted_status();
  for (size_t t = 0; t < nf; ++t) {
    const Triangle& g = tris[t];
    wmin[t] = min3_of(local[g.v[0]].z, local[g.v[1]].z, local[g.v[2]].z);
    wmax[t] = max3_of(local[g.v[0]].z, local[g.v[1]].z, local[g.v[2]].z);
  }
  s->tris = Span<const Triangle>(tris, nf);
  s->tri_wmin = Span<const double>(wmin, nf);
  s->tri_wmax = Span<const double>(wmax, nf);
  return Status::ok();
}

// With a region: the grid's box [*lo, *hi] cut to the region's (padded) box in the local
// frame, on the lattice of the whole sweep (s->lattice, s->ix0, s->iy0), and *mesh_lo_w moved
// to the region's near end; s->empty when nothing is left.
Status fit_region(const SweepOptions& o, double h, Sweep* s, Vec3* lo, Vec3* hi,
                  double* mesh_lo_w) {
  if (o.region.empty() || !is_finite(o.region.lo) || !is_finite(o.region.hi)) {
    return make_error(StatusCode::kInvalidArgument, "sweep: the region is empty or not finite");
  }
  Aabb r;  // the region's box in the local frame (its eight corners)
  for (int c = 0; c < 8; ++c) {
    const Vec3 corner{(c & 1) ? o.region.hi.x : o.region.lo.x,
                      (c & 2) ? o.region.hi.y : o.region.lo.y,
                      (c & 4) ? o.region.hi.z : o.region.lo.z};
    r.add(to_local(s->frame, corner));
  }
  const double pad = 2 * h;
  // The first lattice column at or below the region's (padded) start; the end is cut
  // to the region below.
  const double fx = std::floor((r.lo.x - pad - lo->x) / h);
  const double fy = std::floor((r.lo.y - pad - lo->y) / h);
  if (fx > 0 && fx < 2147483648.0) s->ix0 = static_cast<int64_t>(fx);
  if (fy > 0 && fy < 2147483648.0) s->iy0 = static_cast<int64_t>(fy);
  s->lattice = *lo;
  lo->x = lo->x + h * static_cast<double>(s->ix0);
  lo->y = lo->y + h * static_cast<double>(s->iy0);
  hi->x = min_of(hi->x, r.hi.x + pad);
  hi->y = min_of(hi->y, r.hi.y + pad);
  hi->z = r.hi.z + pad;
  *mesh_lo_w = r.lo.z - pad;
  if (!(lo->x <= hi->x && lo->y <= hi->y && lo->z <= hi->z)) s->empty = true;
  return Status::ok();
}

// The grid: the jaws' box, a band and a voxel around it, to `extent` past the far end; with
// a region, its part of that in x and y, and from the jaws' near end to the region's far
// end in w (the layers before the region are swept but not meshed). Sets s->grid,
// s->mesh_grid, s->k0 (and s->empty); *band: the band's half-width.
Status lay_grid(const SweepOptions& o, const Aabb& box, Sweep* s, double* band) {
  const double h = o.voxel;
  // The correction reads two samples out; the closing reads f(q) up to 2 r + 2 voxels; an
  // offset surface needs the exact field two samples beyond it.
  *band = (o.closing_radius > 0 ? 2 * o.closing_radius : 0) + o.offset + kBandVoxels * h;
  const double margin = *band + h;
  Vec3 lo = box.lo - Vec3{margin, margin, margin};
  Vec3 hi = box.hi + Vec3{margin, margin, o.extent + h};
  double mesh_lo_w = lo.z;
  s->lattice = lo;
  if (o.has_region) SPLINTCORE_RETURN_IF_ERROR(fit_region(o, h, s, &lo, &hi, &mesh_lo_w));
  double counts[3] = {1, 1, 1};
  for (int a = 0; a < 3 && !s->empty; ++a) {
    counts[a] = std::floor((hi[a] - lo[a]) / h) + 1.0;
    if (!(counts[a] < 2147483648.0)) {
      return make_error(StatusCode::kLimitExceeded, "sweep: the grid would have ", counts[a],
                        " samples along an axis at ", h, " mm voxels (at most 2^31)");
    }
  }
  s->grid.origin = lo;
  s->grid.spacing = Vec3{h, h, h};
  s->grid.nx = static_cast<uint32_t>(counts[0]);
  s->grid.ny = static_cast<uint32_t>(counts[1]);
  s->grid.nz = static_cast<uint32_t>(counts[2]);
  {
    const double first = std::floor((mesh_lo_w - lo.z) / h);
    s->k0 = first <= 0 ? 0 : (first >= counts[2] ? s->grid.nz : static_cast<uint32_t>(first));
    if (s->k0 >= s->grid.nz) s->empty = true;
  }
  s->mesh_grid = s->grid;
  s->mesh_grid.origin.z = lo.z + h * static_cast<double>(s->k0);
  s->mesh_grid.nz = s->empty ? 0 : s->grid.nz - s->k0;
  return Status::ok();
}

// The closing's state: offsets within r + 2 voxels, sorted by length (stable: ties keep the
// scan order), and the ring of corrected layers (`layer` samples each).
Status prepare_closing(Arena& arena, const SweepOptions& o, uint64_t layer, Sweep* s) {
  const double h = o.voxel;
  const double reach = o.closing_radius + 2 * h;
  const int64_t m = static_cast<int64_t>(std::ceil(reach / h));
  s->m = static_cast<uint32_t>(m);
  s->closing_r = o.closing_radius;
  const uint64_t cube = static_cast<uint64_t>((2 * m + 1) * (2 * m + 1) * (2 * m + 1));
  auto* offsets = arena.allocate_array<Sweep::Offset>(static_cast<size_t>(cube));
  KeyIndex* by_length = arena.allocate_array<KeyIndex>(static_cast<size_t>(cube));
  auto* ordered = arena.allocate_array<Sweep::Offset>(static_cast<size_t>(cube));
  s->cring = arena.allocate_array<float>(static_cast<size_t>(layer) * (2 * s->m + 1));
  if (offsets == nullptr || by_length == nullptr || ordered == nullptr || s->cring == nullptr) {
    return arena.exhausted_status();
  }
  uint32_t n = 0;
  for (int64_t dz = -m; dz <= m; ++dz) {
    for (int64_t dy = -m; dy <= m; ++dy) {
      for (int64_t dx = -m; dx <= m; ++dx) {
        if (dx == 0 && dy == 0 && dz == 0) continue;
        const double len = h * std::sqrt(static_cast<double>(dx * dx + dy * dy + dz * dz));
        if (len > reach) continue;
        offsets[n] = {static_cast<int16_t>(dx), static_cast<int16_t>(dy), static_cast<int16_t>(dz),
                      0, static_cast<float>(len)};
        by_length[n] = {static_cast<uint64_t>(dx * dx + dy * dy + dz * dz), n, 0};
        ++n;
      }
    }
  }
  SPLINTCORE_RETURN_IF_ERROR(radix_sort(arena, Span<KeyIndex>(by_length, n)));
  for (uint32_t i = 0; i < n; ++i) ordered[i] = offsets[by_length[i].index];
  s->offsets = ordered;
  s->offset_count = n;
  return Status::ok();
}

// Everything before the extraction: frame, local jaws, sorted front triangles, grid, state.
Status prepare(const Context& ctx, Span<const Mesh> jaws, const SweepOptions& o, Sweep* s,
               SweepStats* stats) {
  Arena& arena = *ctx.arena;
  SPLINTCORE_RETURN_IF_ERROR(check_sweep_options(o));
  SPLINTCORE_RETURN_IF_ERROR(make_frame(o.direction, &s->frame));
  Aabb box;
  size_t vertex_total = 0, triangle_total = 0;
  SPLINTCORE_RETURN_IF_ERROR(jaws_box(jaws, o, s->frame, &box, &vertex_total, &triangle_total));
  double band = 0;
  SPLINTCORE_RETURN_IF_ERROR(lay_grid(o, box, s, &band));
  s->band = band;
  // Only the triangles whose shadow meets the grid's columns (the region's) are kept.
  ArenaArray<Triangle> front(&arena);
  SPLINTCORE_RETURN_IF_ERROR(
      select_front(arena, jaws, o, vertex_total, triangle_total, s, &front, stats));
  SPLINTCORE_RETURN_IF_ERROR(sort_front(arena, &front, s));
  if (s->empty) {
    s->ctx = &ctx;
    s->stats = stats;
    stats->axis_u = s->frame.u;
    stats->axis_v = s->frame.v;
    stats->axis_w = s->frame.w;
    return Status::ok();
  }
  uint64_t layer = 0, ring_bytes = 0;
  if (!checked_mul(uint64_t{s->grid.nx}, s->grid.ny, &layer) ||
      !checked_mul(layer, 2 * kRing, &ring_bytes) || ring_bytes > SIZE_MAX) {
    return make_error(StatusCode::kLimitExceeded, "sweep: the grid's cross-section is too large");
  }
  s->ring = arena.allocate_array<uint16_t>(static_cast<size_t>(layer) * kRing);
  if (s->ring == nullptr) return arena.exhausted_status();
  s->fband = static_cast<float>(band);
  s->step = band / 65534.0;
  if (o.closing_radius > 0) SPLINTCORE_RETURN_IF_ERROR(prepare_closing(arena, o, layer, s));
  s->active.bind(&arena);
  // All of them at most, reserved now: the list must not grow during the extraction, whose
  // id pool and output log take the arena above it.
  const size_t nf = s->tris.size();
  if (!s->active.reserve(nf > 0 ? nf : 1)) return arena.exhausted_status();
  s->ctx = &ctx;
  {
    const uint32_t workers = ctx.executor != nullptr ? ctx.executor->concurrency : 1;
    uint64_t bands = workers <= 1 ? 1 : uint64_t{workers} * 4;
    if (bands > kMaxBands) bands = kMaxBands;
    if (bands > s->grid.ny) bands = s->grid.ny;
    s->bands = static_cast<uint32_t>(bands);
  }
  s->correct_bias = o.correct_bias;
  s->stats = stats;
  stats->nx = s->mesh_grid.nx;
  stats->ny = s->mesh_grid.ny;
  stats->nz = s->mesh_grid.nz;
  stats->preroll_layers = s->k0;
  stats->voxels = layer * s->mesh_grid.nz;
  stats->axis_u = s->frame.u;
  stats->axis_v = s->frame.v;
  stats->axis_w = s->frame.w;
  return Status::ok();
}

// Leaves out the triangles whose corners all lie beyond the extracted grid (the caps: their
// vertices are on edges to samples beyond the border, kEdgeMargin of a voxel outside it) and
// the vertices only they used. Kept triangles keep their order and are renumbered by first
// use (as the extractor numbers them). The kept triangles are compacted in place; the kept
// vertices go to a new array above (then `mesh` has its triangles allocated before its
// vertices). Memory: 4 bytes per vertex (the renumbering, left in place) and the new vertices.
Status drop_caps(const Sweep& s, Arena& arena, Mesh* mesh, SweepStats* st) {
  const VolumeGrid& g = s.mesh_grid;
  const Vec3 lo = g.origin;
  const Vec3 hi{g.origin.x + g.spacing.x * (g.nx - 1.0), g.origin.y + g.spacing.y * (g.ny - 1.0),
                g.origin.z + g.spacing.z * (g.nz - 1.0)};
  auto beyond = [&](const Vec3& p) {
    return p.x < lo.x || p.y < lo.y || p.z < lo.z || p.x > hi.x || p.y > hi.y || p.z > hi.z;
  };
  const size_t nt = mesh->triangles.size(), nv = mesh->vertices.size();
  uint32_t* remap = arena.allocate_array<uint32_t>(nv);
  if (nv > 0 && remap == nullptr) return arena.exhausted_status();
  for (size_t i = 0; i < nv; ++i) remap[i] = ~uint32_t{0};
  const Vec3* verts = mesh->vertices.data();
  Triangle* tris = mesh->triangles.data();
  size_t kept = 0;
  uint32_t next = 0;
  for (size_t t = 0; t < nt; ++t) {
    const Triangle tri = tris[t];
    if (beyond(verts[tri.v[0]]) && beyond(verts[tri.v[1]]) && beyond(verts[tri.v[2]])) continue;
    Triangle out;
    for (int k = 0; k < 3; ++k) {
      uint32_t& id = remap[tri.v[k]];
      if (id == ~uint32_t{0}) id = next++;
      out.v[k] = id;
    }
    tris[kept++] = out;
  }
  Vec3* fresh = arena.allocate_array<Vec3>(next);
  if (next > 0 && fresh == nullptr) return arena.exhausted_status();
  for (size_t i = 0; i < nv; ++i) {
    if (remap[i] != ~uint32_t{0}) fresh[remap[i]] = verts[i];
  }
  st->cap_triangles_dropped = nt - kept;
  mesh->triangles.shrink_size(kept);
  mesh->vertices.adopt(fresh, next, next);
  return Status::ok();
}

// The extractor's options. Decimating, the iso moves out by half the error bound, and the
// slab is chosen within a quarter of the free arena (the tiles need the rest).
MarchingCubesOptions extraction_options(const Sweep& s, const SweepOptions& o) {
  MarchingCubesOptions mc;
  mc.iso = o.offset > 0 ? o.offset : -o.inset;
  mc.layers_per_tile = o.layers_per_tile;
  mc.edge_margin = o.edge_margin;
  if (o.decimate_error > 0) mc.iso += 0.5 * o.decimate_error;
  if (o.keep_triangle != nullptr && mc.layers_per_tile == 0) {
    // A slab of a fixed size, never of the room there is: the log grows above it, and the
    // high water must depend on the input alone (the two-step contract).
    mc.layers_per_tile = kKeepLayers;
  }
  if (o.decimate_error > 0) {
    if (mc.layers_per_tile == 0) {
      const Arena& arena = *s.ctx->arena;
      const uint64_t free_bytes = arena.cap() > arena.used() ? arena.cap() - arena.used() : 0;
      uint32_t best = 1;
      const uint32_t limit = s.mesh_grid.nz < kMarchingCubesDefaultLayers
                                 ? s.mesh_grid.nz
                                 : kMarchingCubesDefaultLayers;
      for (uint32_t k = 2; k <= limit; ++k) {
        const uint64_t need = marching_cubes_bound(s.mesh_grid, k);
        if (need == 0 || need > free_bytes / 4) break;
        best = k;
      }
      mc.layers_per_tile = best;
    }
  }
  return mc;
}

// --- the open surface filtered in the stream (SweepOptions::keep_triangle) ---------------------
//
// The extractor's triangles are tested as they come: those beyond the grid (the caps, as
// drop_caps()) and those keep_triangle() refuses are left out; the rest are logged in one
// array of 32-bit words growing above the extractor's working set: a kept triangle as its
// three extractor ids, each new vertex's corner (jaws' frame, float32) before the first kept
// triangle that uses it, as [id | kVertexTag, x, y, z]. "New" is as far as a direct-mapped
// cache of the ids logged recently knows (kSeenSlots): a vertex it has forgotten is logged
// again, with the same bits (the extractor gives a vertex the same corner in every triangle).
// About 20 bytes a kept triangle, where its ids and three corners took 48. After the
// extraction the log is moved down to the arena's top, the kept vertices are numbered by
// first use (a map of the extractor's ids) and the mesh is built above it, triangles before
// vertices, to be moved down (move_mesh_down).

struct KeptTriangle {
  uint32_t v[3];
  float p[9];
};

constexpr uint32_t kVertexTag = 0x80000000u;  // a log word that starts a vertex's record
constexpr uint32_t kSeenSlots = 1u << 14;     // the cache of logged vertices (64 KB)

struct KeepLog {
  const Sweep* s = nullptr;
  const SweepOptions* o = nullptr;
  Vec3 lo{}, hi{};             // the extracted grid's box (local frame)
  ArenaArray<uint32_t> words;  // the log (see the top)
  uint64_t caps = 0, left_out = 0;
  // The triangles waiting for keep_triangle (kSweepKeepBatch, from the arena before the
  // extraction) and its answers (bit 0; bits 1-3: which corners' vertices go in the log).
  KeptTriangle* batch = nullptr;
  uint8_t* keep = nullptr;
  uint32_t waiting = 0;
  uint32_t* seen = nullptr;  // kSeenSlots: id + 1 of a vertex logged, at id's slot; 0: none
};

// Marks the corners of kept triangle k whose vertices the log does not hold yet (as far as
// the cache knows) in bits 1-3 of *flags, and notes them logged; their words (3 for the
// triangle, 4 for each such vertex).
inline uint32_t note_new_corners(KeepLog& log, const KeptTriangle& k, uint8_t* flags) {
  uint32_t words = 3;
  for (int i = 0; i < 3; ++i) {
    uint32_t& slot = log.seen[k.v[i] & (kSeenSlots - 1)];
    if (slot == k.v[i] + 1) continue;
    slot = k.v[i] + 1;
    *flags = static_cast<uint8_t>(*flags | (2u << i));
    words += 4;
  }
  return words;
}

inline Vec3 kept_corner(const KeptTriangle& k, int i) {
  return Vec3{static_cast<double>(k.p[3 * i]), static_cast<double>(k.p[3 * i + 1]),
              static_cast<double>(k.p[3 * i + 2])};
}

// keep_triangle over the waiting triangles (contiguous runs in tasks when the options give
// task users: the answers do not depend on the run or its user), then the kept ones logged in
// order.
Status flush_batch(KeepLog& log) {
  const uint32_t n = log.waiting;
  if (n == 0) return Status::ok();
  const SweepOptions& o = *log.o;
  const Executor* ex = log.s->ctx->executor;
  uint32_t runs = 1;
  if (o.keep_tasks > 0 && has_threads(ex)) {
    runs = ex->concurrency < o.keep_tasks ? ex->concurrency : o.keep_tasks;
    if (runs > n) runs = n;
  }
  auto run = [&](uint32_t r) {
    const void* user = o.keep_tasks > 0 ? o.keep_task_users[r] : o.keep_user;
    const uint32_t begin = static_cast<uint32_t>(uint64_t{n} * r / runs);
    const uint32_t end = static_cast<uint32_t>(uint64_t{n} * (r + 1) / runs);
    for (uint32_t i = begin; i < end; ++i) {
      const KeptTriangle& k = log.batch[i];
      log.keep[i] =
          o.keep_triangle(user, kept_corner(k, 0), kept_corner(k, 1), kept_corner(k, 2)) ? 1 : 0;
    }
  };
  parallel_for_each(runs > 1 ? ex : nullptr, runs, run);
  log.waiting = 0;
  size_t at = log.words.size();
  size_t keeping = 0, words = 0;
  for (uint32_t i = 0; i < n; ++i) {
    if (log.keep[i] == 0) continue;
    ++keeping;
    words += note_new_corners(log, log.batch[i], &log.keep[i]);
  }
  log.left_out += n - keeping;
  // Grown to the exact size (in place: the log is the arena's top during the extraction), so
  // the arena's high water depends on the input alone, never on the room there was.
  if (!log.words.resize(at + words)) return log.words.arena()->exhausted_status();
  uint32_t* w = log.words.data();
  for (uint32_t i = 0; i < n; ++i) {
    if (log.keep[i] == 0) continue;
    const KeptTriangle& k = log.batch[i];
    for (int c = 0; c < 3; ++c) {
      if ((log.keep[i] & (2u << c)) == 0) continue;
      w[at++] = k.v[c] | kVertexTag;
      std::memcpy(w + at, k.p + 3 * c, 3 * sizeof(float));
      at += 3;
    }
    for (int c = 0; c < 3; ++c) w[at++] = k.v[c];
  }
  return Status::ok();
}

// The batch is flushed at the end of every cell layer, while the extraction runs: the log
// grows in place only while it is the arena's top (the extractor's working set is returned
// when it ends, and the log then lies above the top).
Status flush_layer(void* user, int64_t) { return flush_batch(*static_cast<KeepLog*>(user)); }

Status log_kept(void* user, const Triangle& t, const Vec3& a, const Vec3& b, const Vec3& c) {
  KeepLog& log = *static_cast<KeepLog*>(user);
  auto beyond = [&](const Vec3& p) {
    return p.x < log.lo.x || p.y < log.lo.y || p.z < log.lo.z || p.x > log.hi.x || p.y > log.hi.y ||
           p.z > log.hi.z;
  };
  if (beyond(a) && beyond(b) && beyond(c)) {
    ++log.caps;
    return Status::ok();
  }
  Vec3 w[3] = {to_world(log.s->frame, a), to_world(log.s->frame, b), to_world(log.s->frame, c)};
  for (Vec3& p : w) {
    if (!round_to_float32(&p)) {
      return make_error(StatusCode::kLimitExceeded,
                        "sweep: a vertex of the swept volume is beyond float32 range");
    }
  }
  // Waits for keep_triangle with the others of its batch (the corners as float32: the same
  // values as w).
  KeptTriangle& k = log.batch[log.waiting++];
  for (int i = 0; i < 3; ++i) {
    if (t.v[i] >= kVertexTag) {
      return make_error(StatusCode::kLimitExceeded,
                        "sweep: more than 2^31 vertices extracted (a coarser voxel?)");
    }
    k.v[i] = t.v[i];
    k.p[3 * i] = static_cast<float>(w[i].x);
    k.p[3 * i + 1] = static_cast<float>(w[i].y);
    k.p[3 * i + 2] = static_cast<float>(w[i].z);
  }
  return log.waiting == kSweepKeepBatch ? flush_batch(log) : Status::ok();
}

// The log (above the arena's top) as a mesh above it: triangles, then vertices. Memory: the log
// moved down (about 20 bytes a kept triangle), the triangles (12 bytes each), then 4 bytes per
// extractor vertex for the map of ids, whose room the vertices (24 bytes each) take after it:
// the peak holds the larger of the two, not both (the real 4 mm-deep design's mandible: a map
// of 6.2 MB for 1.54 M extractor vertices, of which 157k are kept).
Status build_kept_mesh(Arena& arena, const KeepLog& log, uint64_t extractor_vertices, Mesh* mesh) {
  const size_t nw = log.words.size();
  uint32_t* w = arena.allocate_array<uint32_t>(nw > 0 ? nw : 1);
  if (w == nullptr) return arena.exhausted_status();
  if (nw > 0 && w != log.words.data()) {
    std::memmove(static_cast<void*>(w), log.words.data(), nw * sizeof(uint32_t));
  }
  size_t n = 0;
  for (size_t i = 0; i < nw; i += (w[i] & kVertexTag) != 0 ? 4 : 3) {
    n += (w[i] & kVertexTag) != 0 ? 0 : 1;
  }
  const size_t nv = static_cast<size_t>(extractor_vertices);
  Triangle* tris = arena.allocate_array<Triangle>(n > 0 ? n : 1);
  if (tris == nullptr) return arena.exhausted_status();
  const Arena::Marker map_at = arena.mark();
  uint32_t* remap = arena.allocate_array<uint32_t>(nv > 0 ? nv : 1);
  if (remap == nullptr) return arena.exhausted_status();
  for (size_t i = 0; i < nv; ++i) remap[i] = ~uint32_t{0};
  uint32_t next = 0;
  size_t t = 0;
  for (size_t i = 0; i < nw;) {
    if ((w[i] & kVertexTag) != 0) {
      i += 4;
      continue;
    }
    for (int k = 0; k < 3; ++k, ++i) {
      SPLINTCORE_ASSERT(w[i] < nv);
      uint32_t& id = remap[w[i]];
      if (id == ~uint32_t{0}) id = next++;
      tris[t].v[k] = id;
    }
    ++t;
  }
  // Each vertex record renamed to its kept number in the log, and the map given back.
  for (size_t i = 0; i < nw;) {
    if ((w[i] & kVertexTag) == 0) {
      i += 3;
      continue;
    }
    const uint32_t id = w[i] & ~kVertexTag;
    SPLINTCORE_ASSERT(id < nv && remap[id] != ~uint32_t{0});  // a triangle after it uses it
    w[i] = remap[id] | kVertexTag;
    i += 4;
  }
  arena.rewind(map_at);
  Vec3* verts = arena.allocate_array<Vec3>(next > 0 ? next : 1);
  if (verts == nullptr) return arena.exhausted_status();
  for (size_t i = 0; i < nw;) {
    if ((w[i] & kVertexTag) == 0) {
      i += 3;
      continue;
    }
    float q[3];
    std::memcpy(q, w + i + 1, sizeof q);
    verts[w[i] & ~kVertexTag] =
        Vec3{static_cast<double>(q[0]), static_cast<double>(q[1]), static_cast<double>(q[2])};
    i += 4;
  }
  mesh->triangles.adopt(tris, n, n);
  mesh->vertices.adopt(verts, next, next);
  return Status::ok();
}

// sweep_volume_mesh() with keep_triangle: the kept mesh above the arena's top when it returns.
// pool_share: the extractor's id pool is this share of the full pool (1: all of it).
Status extract_kept(Sweep& s, const SweepOptions& o, uint64_t pool_share, Mesh* mesh,
                    SweepStats* st) {
  Arena& arena = *s.ctx->arena;
  const VolumeGrid& g = s.mesh_grid;
  KeepLog log;
  log.s = &s;
  log.o = &o;
  log.lo = g.origin;
  log.hi = Vec3{g.origin.x + g.spacing.x * (g.nx - 1.0), g.origin.y + g.spacing.y * (g.ny - 1.0),
                g.origin.z + g.spacing.z * (g.nz - 1.0)};
  log.batch = arena.allocate_array<KeptTriangle>(kSweepKeepBatch);
  log.keep = arena.allocate_array<uint8_t>(kSweepKeepBatch);
  log.seen = arena.allocate_array<uint32_t>(kSeenSlots);
  if (log.batch == nullptr || log.keep == nullptr || log.seen == nullptr) {
    return arena.exhausted_status();
  }
  std::memset(log.seen, 0, kSeenSlots * sizeof(uint32_t));
  log.words.bind(&arena);
  MarchingCubesVisitor visitor;
  visitor.triangle = log_kept;
  visitor.layer_done = flush_layer;
  visitor.user = &log;
  MarchingCubesOptions mc = extraction_options(s, o);
  mc.pool_ids = (uint64_t{g.nx} + 1) * (uint64_t{g.ny} + 1) * 10 / pool_share;
  SPLINTCORE_RETURN_IF_ERROR(
      marching_cubes(*s.ctx, g, LayerSource{fill_layers, &s}, mc, visitor, &st->extraction));
  SPLINTCORE_ASSERT(log.waiting == 0);  // flushed at each layer's end
  st->cap_triangles_dropped = log.caps;
  st->filtered_triangles = log.left_out;
  st->log_bytes = log.words.size() * sizeof(uint32_t);
  return build_kept_mesh(arena, log, st->extraction.vertices, mesh);
}

void setup_tiles(const Sweep& s, const SweepOptions& o, const MarchingCubesVisitor* out,
                 TileDecimator* d) {
  const VolumeGrid& g = s.mesh_grid;
  d->ctx = s.ctx;
  d->max_error = 0.5 * o.decimate_error;
  d->max_distance = 0.5 * o.decimate_error;
  d->lo = g.origin;
  d->hi = Vec3{g.origin.x + g.spacing.x * (g.nx - 1.0), g.origin.y + g.spacing.y * (g.ny - 1.0),
               g.origin.z + g.spacing.z * (g.nz - 1.0)};
  d->spacing_w = g.spacing.z;
  d->drop_caps = o.open_at_region && o.has_region;
  d->last_layer = static_cast<int64_t>(g.nz) - 1;
  d->out = out;
  d->world = [](const void* frame, const Vec3& p) {
    return to_world(*static_cast<const Frame*>(frame), p);
  };
  d->frame = &s.frame;
  d->float32 = o.float32_vertices;
}

void tile_stats(const TileDecimator& d, SweepStats* st) {
  st->decimated_tiles = d.tiles;
  st->undecimated_triangles = d.input_triangles - d.caps_dropped;
  st->cap_triangles_dropped = d.caps_dropped;
  st->peak_tile_triangles = d.peak_tile_triangles;
  st->decimate_qem_error = d.max_collapse_error;
}

}  // namespace

uint64_t sweep_state_bound(uint64_t vertex_count, uint64_t triangle_count, uint32_t nx,
                           uint32_t ny) {
  const uint64_t layer = uint64_t{nx} * ny;
  // The bits that select what is kept (a bit per vertex and per triangle, a rank per 64
  // vertices), then the kept vertices and triangles: all of them at most. The triangles are
  // sorted with a key and the radix sort's scratch beside them (16 + 16 bytes, given back);
  // then they stay with their w range and a slot in the active list, and the layers follow.
  const uint64_t selection = 12 * (vertex_count / 64 + 1) + 8 * (triangle_count / 64 + 1);
  const uint64_t sorting = (12 + 16 + 16) * triangle_count;
  const uint64_t sweeping = (12 + 8 + 8 + 4) * triangle_count + 2 * kRing * layer;
  return selection + 24 * vertex_count + (sorting > sweeping ? sorting : sweeping) + 16 * 64;
}

Status sweep_volume(const Context& ctx, Span<const Mesh> jaws, const SweepOptions& options,
                    const MarchingCubesVisitor& visitor, SweepStats* stats) {
  SPLINTCORE_ASSERT(ctx.arena != nullptr);
  SweepStats local_stats;
  SweepStats* st = stats != nullptr ? stats : &local_stats;
  *st = SweepStats{};
  ArenaScope scope(*ctx.arena);
  Sweep s;
  SPLINTCORE_RETURN_IF_ERROR(prepare(ctx, jaws, options, &s, st));
  WorldVisitor wv{&s.frame, &visitor};
  MarchingCubesVisitor outer;
  outer.vertex = world_vertex;
  outer.triangle = world_triangle;
  outer.user = &wv;
  if (s.empty) return Status::ok();
  const MarchingCubesOptions mc = extraction_options(s, options);
  if (options.decimate_error > 0) {
    TileDecimator d;  // streams in the jaws' frame itself
    setup_tiles(s, options, &visitor, &d);
    const MarchingCubesVisitor tiles = tile_visitor(&d);
    const Status status =
        marching_cubes(ctx, s.mesh_grid, LayerSource{fill_layers, &s}, mc, tiles, &st->extraction);
    tile_stats(d, st);
    return status;
  }
  return marching_cubes(ctx, s.mesh_grid, LayerSource{fill_layers, &s}, mc, outer, &st->extraction);
}

Status sweep_volume_mesh(const Context& ctx, Span<const Mesh> jaws, const SweepOptions& options,
                         Mesh* out, SweepStats* stats) {
  SPLINTCORE_ASSERT(ctx.arena != nullptr && out != nullptr);
  if (!out->vertices.empty() || !out->triangles.empty()) {
    return make_error(StatusCode::kInvalidArgument, "sweep: the output mesh must be empty");
  }
  Arena& arena = *ctx.arena;
  ArenaScope scope(arena);  // on an error the arena is as it was
  SweepStats local_stats;
  SweepStats* st = stats != nullptr ? stats : &local_stats;
  *st = SweepStats{};
  Sweep s;
  Status status = prepare(ctx, jaws, options, &s, st);
  Mesh mesh(&arena);
  if (status.is_ok() && !s.empty && options.decimate_error > 0) {
    // The tiles' log becomes a mesh above the arena's top; moved down over the sweep's state.
    TileDecimator d;
    setup_tiles(s, options, nullptr, &d);
    const MarchingCubesVisitor tiles = tile_visitor(&d);
    status = marching_cubes(ctx, s.mesh_grid, LayerSource{fill_layers, &s},
                            extraction_options(s, options), tiles, &st->extraction);
    tile_stats(d, st);
    if (!status.is_ok()) {
      out->bind(&arena);
      return status;
    }
    move_mesh_down(arena, scope.start(), d.mesh, out);
    scope.commit();
    return Status::ok();
  }
  if (status.is_ok() && !s.empty && options.keep_triangle != nullptr) {
    status = extract_kept(s, options, kKeepPoolShare, &mesh, st);
    if (st->extraction.pool_short) {
      // A layer crossed more edges than the share holds: all again with the full pool (the
      // same bytes; the high water is this run's, the first stopped below it).
      arena.rewind(scope.start());
      Sweep again;
      mesh = Mesh(&arena);
      *st = SweepStats{};
      status = prepare(ctx, jaws, options, &again, st);
      st->full_id_pool = true;
      if (status.is_ok()) status = extract_kept(again, options, 1, &mesh, st);
    }
    if (!status.is_ok()) {
      out->bind(&arena);
      return status;
    }
    move_mesh_down(arena, scope.start(), mesh, out);
    scope.commit();
    return Status::ok();
  }
  if (status.is_ok() && !s.empty) {
    status = marching_cubes_mesh(ctx, s.mesh_grid, LayerSource{fill_layers, &s},
                                 extraction_options(s, options), &mesh, &st->extraction);
  }
  if (!status.is_ok()) {
    out->bind(&arena);
    return status;
  }
  bool vertices_first = true;  // as the extractor leaves them
  if (options.open_at_region && options.has_region && !s.empty) {
    status = drop_caps(s, arena, &mesh, st);
    if (!status.is_ok()) {
      out->bind(&arena);
      return status;
    }
    vertices_first = false;
  }
  for (Vec3& p : mesh.vertices) p = to_world(s.frame, p);
  move_mesh_down(arena, scope.start(), mesh, out, vertices_first);
  scope.commit();
  return Status::ok();
}

}  // namespace splintcore
