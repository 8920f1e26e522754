// splintcore distance, internal: what the closest-point paths share (query.cpp: the tree
// search; regions.cpp: the batch over query buckets).
#ifndef SPLINTCORE_SRC_DISTANCE_QUERY_INTERNAL_H
#define SPLINTCORE_SRC_DISTANCE_QUERY_INTERNAL_H

#include "geometry/lanes2.h"
#include "splintcore/distance.h"

namespace splintcore {
namespace detail {

// Traversal stacks: a 4-wide node pushes at most three children more than it pops, and the
// tree is at most 128 levels deep (checked when it is built).
constexpr uint32_t kTraversalStack = 3 * 128 + 4;

// Closest point among triangles within sqrt(limit2) of q; false when none is. A seed triangle
// (kNoNeighbor: none), e.g. the answer for a nearby query, starts the search with a tight
// bound; the answer is the same with or without it (ties go to the smallest id).
bool closest_within(const DistanceIndex& index, const Vec3& q, double limit2, ClosestPoint* out,
                    uint32_t seed = kNoNeighbor);

// Completes the answer for q once the search is over: `best` holds the winning triangle, its
// closest point and feature (closest_point_on_triangle), best2 its squared distance. A point
// exactly on the surface is decided exactly (distance 0); sets best->distance.
void settle_closest(const DistanceIndex& index, const Vec3& q, double best2, ClosestPoint* best);

// The batch path of regions.cpp: answers queries by scanning, for each triangle, the query
// buckets its Voronoi regions cover, when there are enough queries to pay for the pass over
// the triangles and the arena holds the buckets. Calls answer(user, at, cp, found) once for
// every query (from the executor's threads: it must write only slot `at`), with what
// closest_point() would return, and sets *used; leaves *used false and calls nothing when the
// tree should answer instead.
using RegionAnswer = void (*)(void* user, size_t at, const ClosestPoint& cp, bool found);
Status region_closest_points(const Context& ctx, const DistanceIndex& index,
                             Span<const Vec3> queries, RegionAnswer answer, void* user, bool* used);

}  // namespace detail
}  // namespace splintcore

#endif  // SPLINTCORE_SRC_DISTANCE_QUERY_INTERNAL_H
