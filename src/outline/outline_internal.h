// The automatic outline's parts (outline.h), shared by its files only.
#ifndef SPLINTCORE_SRC_OUTLINE_INTERNAL_H
#define SPLINTCORE_SRC_OUTLINE_INTERNAL_H

#include <cmath>

#include "geometry/lanes2.h"
#include "splintcore/outline.h"

namespace splintcore {
namespace outline_detail {

constexpr double kCellMm = 0.5;            // the lattice's columns
constexpr double kMaxSpanMm = 250.0;       // the jaws' extent in the plane, at most
constexpr double kContactBandMm = 3.0;     // columns within this of the closest fit the plane
constexpr uint64_t kMinContactCells = 20;  // columns that see both jaws, at least
constexpr int kFrameRounds = 3;            // plane fits (each tilts the normal)
constexpr double kOcclusalBandMm = 3.5;    // an occlusal column: this near the jaw's tips
// The indentation the band was made for (the default): the picks' columns reach deeper by as
// much as the indentation goes past it (arch_and_picks).
constexpr double kBandIndentationMm = 2.0;
constexpr uint64_t kMinOcclusalCells = 20;
constexpr size_t kLinePoints = 16384;      // band vertices per jaw for the centre line, at most
constexpr uint32_t kSectors = 128;         // around the arch's centre (pseudo-angle)
constexpr double kBinMm = 1.0;             // along the arch, for its centre line
constexpr double kSmoothMm = 10.0;         // half-width of the centre line's smoothing
constexpr double kMaxReachMm = 8.0;        // how far the centre line goes on past its ends
constexpr size_t kTurnBins = 3;            // straighten_ends: the chords it compares
constexpr double kMaxTurnCosine = 0.7071;  // cos 45 degrees
constexpr double kEndTrimMm = 3.0;         // straighten_ends (arch.cpp)
constexpr double kEndChordMm = 5.0;
constexpr int kSmoothPasses = 4;    // project, bin, smooth: each pass
constexpr double kTangentMm = 8.0;  // chord for the arch's direction at a pick
constexpr double kMinArchMm = 20.0;
constexpr double kMaxReachAcrossMm = 20.0;      // a line's reach past the centre line, at most
constexpr double kDeepSlackMm = 0.2;            // a tooth sinks at most this much deeper than asked
constexpr double kToothHalfMm = 5.5;            // half a molar's length along the arch
constexpr double kMinWaferMm = 1.0;             // top to bottom, at every pick
constexpr size_t kMaxPicks = kMaxOutlinePicks;  // per jaw
constexpr size_t kMaxArchPoints = kMaxOutlineArchPoints;  // kBinMm bins along the arch
constexpr uint32_t kNoTip = ~uint32_t{0};

// At least mesh_pair_distance_bound() for any two indexes: 24-byte entries, a heap of 2048 and
// a stack of 15 (a.depth + b.depth) + 1, where a 4-wide tree over 32-bit Morton leaves is at
// most 32 deep; the split search's 8 tasks' heaps of 256 and stacks; and their alignment.
constexpr uint64_t kPairStackBound =
    24 * (2048 + 15 * 64 + 1) + 2 * 64 + 8 * (24 * (256 + 15 * 64 + 1) + 2 * 64);

// A jaw is not empty, its vertices are finite and its triangles' corners exist; also its
// longest edge (the autorotation's bands need it), in the same pass over the triangles, unless
// longest_edge is nullptr (the outline's bands measure only the triangles they need). Errors
// start with `who` ("outline") and name the jaw (`name`: "maxilla", "mandible") and the element.
Status check_jaw(const Mesh& m, const char* who, const char* name, double* longest_edge);
// check_jaw of the maxilla and the mandible, one task each on ctx's executor (they read only
// their own jaw): the maxilla's error first, as when checked one after the other.
Status check_jaws(const Context& ctx, const Mesh& maxilla, const Mesh& mandible, const char* who,
                  double* edge_maxilla, double* edge_mandible);

// The pair searches' indexes (the opening's bands, the autorotation's jaws): pairs_only.
DistanceIndexOptions band_index_options();

// n: from the mandible towards the maxilla; e1 towards the front; e2 = n x e1.
struct Frame {
  Vec3 n{0, 0, 1}, e1{1, 0, 0}, e2{0, 1, 0};
};

// (A pair of dot products computed in lanes, geometry/lanes2.h, has the scalar dot()'s bits,
// for half the multiplications and additions.)
// (dot(p, e1), dot(p, e2)) of a frame, in lanes: the same bits as the two dot() calls (each
// lane's sum in dot()'s order, x then y then z).
struct PlaneAxes {
  Lanes2 ax, ay, az;
  explicit PlaneAxes(const Frame& f) : ax{f.e1.x, f.e2.x}, ay{f.e1.y, f.e2.y}, az{f.e1.z, f.e2.z} {}
  Lanes2 xy(const Vec3& p) const {
    return (Lanes2{p.x, p.x} * ax + Lanes2{p.y, p.y} * ay) + Lanes2{p.z, p.z} * az;
  }
};

// A lattice of kCellMm columns along n over the plane (e1, e2), origin at the vertices'
// centroid (cx, cy). Per jaw and column: the height (along n) of the vertex the column shows
// the other jaw (0: the maxilla's lowest, 1: the mandible's highest) and its index.
struct Grid {
  double cx = 0, cy = 0;
  int64_t ix0 = 0, iy0 = 0;
  uint32_t nx = 0, ny = 0;
  double* h[2] = {nullptr, nullptr};
  uint32_t* tip[2] = {nullptr, nullptr};

  // The first and last column's index along each axis, as doubles (set_limits).
  double first_x = 0, last_x = 0, first_y = 0, last_y = 0;

  void set_limits() {
    first_x = static_cast<double>(ix0);
    last_x = static_cast<double>(ix0 + static_cast<int64_t>(nx) - 1);
    first_y = static_cast<double>(iy0);
    last_y = static_cast<double>(iy0 + static_cast<int64_t>(ny) - 1);
  }
  // The column index floor(q) clamped to [first, last] (integers): clamped first, so that the
  // truncation is exact and needs no range check (nor a call to libm's floor, not inlined
  // without SSE4.1). The same index: below first, floor(q) < first and first's floor is
  // first; above last, floor(q) >= last and last's is last; between, floor(q) itself. (q is
  // finite: the vertices are, check_jaw; the comparisons as written are one maxsd and minsd.)
  static int64_t clamped_floor(double q, double first, double last) {
    q = q < first ? first : q;
    q = q > last ? last : q;
    const int64_t t = static_cast<int64_t>(q);
    return static_cast<double>(t) > q ? t - 1 : t;
  }
  size_t cell_of(double x, double y) const {
    const int64_t ix = clamped_floor((x - cx) / kCellMm, first_x, last_x) - ix0;
    const int64_t iy = clamped_floor((y - cy) / kCellMm, first_y, last_y) - iy0;
    return static_cast<size_t>(iy) * nx + static_cast<size_t>(ix);
  }
  // cell_of for a point of the vertices the lattice was laid over (grid_layout), in the same
  // place: its quotient q lies in [first, last + 1) (x_lo <= x <= x_hi, and the subtraction,
  // the division and floor are monotone), where floor(q) is clamped_floor's, so it is not
  // clamped.
  static int64_t floor_of(double q) {
    const int64_t t = static_cast<int64_t>(q);
    return static_cast<double>(t) > q ? t - 1 : t;
  }
  size_t cell_of_laid(double x, double y) const {
    const int64_t ix = floor_of((x - cx) / kCellMm) - ix0;
    const int64_t iy = floor_of((y - cy) / kCellMm) - iy0;
    return static_cast<size_t>(iy) * nx + static_cast<size_t>(ix);
  }
  // The column's centre relative to (cx, cy).
  void cell_centre(size_t i, double* x, double* y) const {
    *x = (static_cast<double>(ix0 + static_cast<int64_t>(i % nx)) + 0.5) * kCellMm;
    *y = (static_cast<double>(iy0 + static_cast<int64_t>(i / nx)) + 0.5) * kCellMm;
  }
};

// Height a + b x + c y over the plane, x and y relative to the grid's (cx, cy).
struct Plane {
  double a = 0, b = 0, c = 0;
  double at(double x, double y) const { return a + b * x + c * y; }
};

void complete_frame(const Vec3& n, const Vec3& anterior_hint, Frame* f);
// The unit direction from the mandible's vertex centroid to the maxilla's; false when they lie
// within 1 mm.
bool centroid_axis(const Vec3& upper_centroid, const Vec3& lower_centroid, Vec3* n);
// The front of the arch in the plane (e1, e2) of f (see frame.cpp), in *axis. Arena: one
// 16-byte pair a vertex of both jaws (returned). Errors: kArenaExhausted.
Status anterior_axis(const Context& ctx, const Mesh& upper, const Mesh& lower, const Vec3& centre,
                     const Frame& f, Vec3* axis);
Status build_grid(Arena& arena, const Executor* executor, const Mesh& upper, const Mesh& lower,
                  const Vec3& lower_offset, const Frame& f, Grid* g);
// Arena (with threads): a lattice's columns, returned. Errors: kArenaExhausted.
Status fill_heights(Arena& arena, const Executor* executor, const Mesh& m, const Vec3& offset,
                    const Frame& f, int jaw, Grid* g);
// fill_heights of both jaws, one task each on the executor (each writes only its own
// columns' arrays), for the vertices the lattice was laid over, in the same places (the
// upper's as given, the lower's moved by lower_offset): cell_of_laid.
void fill_both(const Executor* executor, const Mesh& upper, const Mesh& lower,
               const Vec3& lower_offset, const Frame& f, Grid* g);
bool fit_contact_plane(const Grid& g, Plane* plane, uint64_t* contact_cells);
// The frame (three plane fits) and the grid and plane of the last, left in the arena.
Status find_frame(const Context& ctx, const Mesh& upper, const Mesh& lower, Frame* f, Grid* g,
                  Plane* plane);

// An occlusal column's shown vertex: its place in the plane (absolute x along e1, y along
// e2), its height along n, the jaw, and where it projects on the arch (s along it, o across,
// positive buccal).
struct ArchPoint {
  double x = 0, y = 0, h = 0;
  double s = 0, o = 0;
  uint32_t jaw = 0;
};

// Where the results go: kMaxPicks picks per jaw, kMaxArchPoints arch points.
struct OutlineBuffers {
  Pick* upper = nullptr;
  Pick* lower = nullptr;
  Vec3* arch = nullptr;
};

// Bytes the arch's projections take at most (arch.cpp), beyond what arch_and_picks keeps.
uint64_t projector_bound();

// The arch and the picks from the grids (arch.cpp). `lower_offset`: the mandible's move.
Status arch_and_picks(const Context& ctx, const Mesh& upper, const Mesh& lower,
                      const Vec3& lower_offset, const Frame& f, const Grid& g, const Plane& plane,
                      const OutlineOptions& options, const OutlineBuffers& buffers, Outline* out);

// The insertion direction with the least undercut within 15 degrees of n (survey.cpp): fills
// r's insertion_direction, surveyed, survey_directions and both undercut volumes.
Status survey_direction(const Context& ctx, const Mesh& maxilla, const Mesh& mandible,
                        const Vec3& lower_offset, const Frame& f, Span<const Pick> upper,
                        Span<const Pick> lower, OutlineReport* r);

}  // namespace outline_detail
}  // namespace splintcore

#endif  // SPLINTCORE_SRC_OUTLINE_INTERNAL_H
