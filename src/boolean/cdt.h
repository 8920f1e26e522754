// splintcore boolean, internal: constrained Delaunay triangulation of one planar polygon with
// interior constraint segments, the re-triangulation step of the Boolean (each cut triangle is
// triangulated on its own plane, projected to 2-D, along the intersection segments).
//
// Input: n distinct 2-D points and constraint segments between them. The first
// `boundary_count` segments form ONE closed simple polygon, counter-clockwise, listed in order
// (segment i ends where segment i+1 starts; the last ends at the first's start). The other
// segments are interior constraints: each lies inside the polygon (or on it), and constraints
// meet each other and the boundary only at shared end points. Points that no segment uses are
// inserted too (they become vertices of the output).
//
// Output: triangles (three point ids each, counter-clockwise) covering exactly the polygon's
// interior, using every point and containing every segment as a triangle edge; among all such
// triangulations the constrained Delaunay one (ties broken deterministically). No Steiner points.
// Exactly b + 2 i - 2 triangles for b boundary segments and i other points. Each triangle is
// rotated to start at its smallest id; the order of the triangles is the algorithm's (fixed
// for a given input, on every compiler and platform).
//
// Two paths, chosen by the input alone (cdt.cpp): up to 32 points whose polygon is star-shaped
// from the mean of its corners (the Boolean's cut triangles), the small path: the polygon
// ear-clipped and flipped to Delaunay, then the other points and the segments; it takes no
// temporaries from the arena (its work arrays, 4.7 KB, are on the stack). Everything else,
// and every input the contract refuses, the general path (a super-triangle around all points).
// Both give the constrained Delaunay triangles, so the same ones unless four points are
// cocircular (a tie), each path in its own order.
//
// Decisions use the exact orient2d and incircle on the given coordinates, so the result is
// valid for the coordinates as given (which the Boolean has already rounded). Coordinates must
// be finite and 0 or of magnitude within [2^-200, 2^200] (incircle's exact range, with room
// for the enclosing triangle the algorithm adds); others are kInvalidArgument.
//
// Repeated segments (the same two points, either direction, also an interior segment equal to
// a boundary one) are accepted and count once.
//
// Errors (never a crash, never a bad triangulation): kInvalidArgument when the input breaks
// the contract above, with the offending ids in the message: duplicate points, a point lying
// exactly on a segment that does not end there, two segments crossing, a boundary that is
// not closed, not simple or not counter-clockwise, a point or an interior segment outside the
// polygon. kArenaExhausted when the arena is too small (cdt_bound() bytes always suffice).
// kInternal only for a bug (the checks that would report it never fire in the tests).
// Memory: arena only, temporaries returned before it returns (the output array excepted; on
// an error `out` keeps its size but may keep the capacity reserved for the result).
// Deterministic; no recursion; work bounded by counts, never by iteration luck: walks and
// rotations by the triangle count, point insertion by O(n^2) flips in the worst case (expected
// O(n) in the randomised order used above 32 points), each segment by 4 k^2 + 64 flips for the
// k edges it crosses (about 2 k in practice). Algorithm and sources: cdt.cpp.
#ifndef SPLINTCORE_SRC_BOOLEAN_CDT_H
#define SPLINTCORE_SRC_BOOLEAN_CDT_H

#include "splintcore/core.h"

namespace splintcore {
namespace detail {

struct CdtPoint {
  double x, y;
};

struct CdtSegment {
  uint32_t a, b;  // point ids
};

struct CdtTriangle {
  uint32_t v[3];  // point ids, counter-clockwise
};

constexpr uint32_t kCdtNone = 0xffffffffu;

// Per output triangle (same index), for each of its edges v[e] -> v[e + 1]: the output
// triangle on the other side (kCdtNone on the polygon's boundary) and the id of the segment
// lying on that edge (for a repeated segment the first id given; kCdtNone when none does).
struct CdtAdjacency {
  uint32_t nb[3];
  uint32_t seg[3];
};

// Bytes cdt() may take from the arena (output included, the adjacency too when asked for) for
// n points and m segments, when `out` (and `adjacency`) are empty or are the last allocations
// of their arena (otherwise growing them copies them: add their current size in bytes),
// counted as the arena's bytes handed out (a buffer-mode arena's cap; a hooks-mode arena also
// pays its block headers). Depends on n only.
uint64_t cdt_bound(uint64_t point_count, uint64_t segment_count);

// Appends the triangles to `out` (bound to an arena, possibly the same arena as the
// temporaries: the output is reserved first so it never moves). When `adjacency` is given
// (bound to an arena, empty or not), it gets one CdtAdjacency per appended triangle, in the
// same order, with neighbour indices counted from this call's first triangle; it is reserved
// right after `out`. The triangles are the same with or without it.
Status cdt(Arena& arena, Span<const CdtPoint> points, Span<const CdtSegment> segments,
           uint32_t boundary_count, ArenaArray<CdtTriangle>* out,
           ArenaArray<CdtAdjacency>* adjacency = nullptr);

// cdt() on the general path only, whatever the input (the same contract, arena and errors):
// for the tests that hold the small path against it.
Status cdt_general(Arena& arena, Span<const CdtPoint> points, Span<const CdtSegment> segments,
                   uint32_t boundary_count, ArenaArray<CdtTriangle>* out,
                   ArenaArray<CdtAdjacency>* adjacency = nullptr);

}  // namespace detail
}  // namespace splintcore

#endif  // SPLINTCORE_SRC_BOOLEAN_CDT_H
