// splintcore distance: the spatial engine the Boolean, the blockout and the accuracy reports query
// (Chen et al. 2016, "Calculate the signed distance field").
//
// The hierarchy is a bounding volume hierarchy, not an octree: for closest-point queries on a
// triangle mesh a BVH bounds every triangle exactly once (an octree either duplicates
// triangles that straddle cells or loosens its cells), so its memory is known before building,
// and built over Morton-ordered leaves it takes one radix sort and one bottom-up pass (no
// recursion, deterministic). The Morton ranges are split four ways at a time into a 4-wide
// tree (every node holds the boxes of up to four children side by side): a query
// tests four boxes from one cache line pair instead of walking two levels, which is what
// bounds the cost of a closest-point query near a finely tessellated surface, where many
// boxes lie almost as close as the answer. Measured figures are in the benchmark
// (splintcore-bench --filter distance).
//
// Results never depend on the tree's shape or the traversal order: among equally close
// triangles the smallest index wins, and sums (winding numbers) are taken in a fixed order.
#ifndef SPLINTCORE_DISTANCE_H
#define SPLINTCORE_DISTANCE_H

#include "splintcore/core.h"
#include "splintcore/geometry.h"
#include "splintcore/mesh.h"

namespace splintcore {

// A node of the 4-wide hierarchy: child k has the box lo[axis][k] .. hi[axis][k] (float,
// rounded outward so it always contains its triangles) and is either an inner node
// (count[k] == 0: nodes[child[k]]), a leaf of count[k] triangles (1..16) starting at
// order[child[k]], or absent (child[k] == kNoChild; its box is empty: lo = +inf, hi = -inf).
// nodes[0] is the root; children always have larger indices than their parent.
struct BvhNode {
  float lo[3][4];
  float hi[3][4];
  uint32_t child[4];
  uint8_t count[4];
};
constexpr uint32_t kNoChild = ~uint32_t{0};

// The same four children as oriented boxes, for closest-point queries: in the node's frame
// (three float axes, orthonormal to float rounding), child k lies in
// { x : lo[i][k] <= axis[i] . x <= hi[i][k], i = 0, 1, 2 }. Near a curved, finely tessellated
// surface an axis-aligned box is as thick as its patch is tilted, so a query point a few
// millimetres away finds dozens of boxes almost as close as the answer; a box with one axis
// along the patch's normal is only as thick as the patch is curved. The frame is the node's
// (its first axis along the area-weighted normal of its triangles), shared by its four
// children, so a query projects onto it once per node. A node whose children's oriented boxes
// would be no smaller than their axis-aligned ones keeps the world axes (and those boxes).
// Leaf children's intervals come from their triangles' corners, inner children's from their
// own node's oriented boxes (bottom-up, no second pass over the triangles), rounded outward.
struct BvhObb {
  float axis[3][3];  // [box axis][x, y, z]
  float lo[3][4];    // [box axis][child]
  float hi[3][4];
};

// Per node (all the triangles below it), for the fast winding number (Barill et al., "Fast
// winding numbers for soups and clouds", SIGGRAPH 2018, first-order dipole term): the
// area-weighted normal sum, its centre, and the radius of a ball around the centre that holds
// the node's triangles.
struct BvhDipole {
  float center[3];
  float normal[3];
  float radius;
  float area;  // of the node's triangles (parents sum their children's)
};

enum class Feature : uint8_t { kFace = 0, kEdge = 1, kVertex = 2 };
const char* feature_name(Feature feature);

struct ClosestPoint {
  Vec3 point{};
  double distance = 0;  // unsigned, mm
  uint32_t triangle = 0;
  Feature feature = Feature::kFace;
  uint8_t feature_index = 0;  // edge k runs v[k] -> v[k+1]; vertex k is v[k]
};

enum class SignMethod : uint8_t {
  kAuto,           // pseudonormals on a closed edge-manifold oriented mesh, else winding number
  kPseudonormal,   // Baerentzen and Aanaes 2005: needs a closed, manifold, oriented mesh
  kWindingNumber,  // Jacobson et al. 2013: works on open and imperfect meshes (scans)
};

struct DistanceIndexOptions {
  // Triangles per leaf, 1..16; 0: the default, 8.
  uint32_t leaf_size = 0;
  // Oriented boxes (BvhObb) for closest-point and signed-distance queries: worth it when
  // queries come one at a time or in small batches on finely tessellated curved surfaces,
  // for a slower build and a larger index (measurements: docs/architecture.md). The answers
  // are the same bits either way.
  bool oriented_boxes = false;
  // Only what the pair queries (mesh_pair_distance and its kin), closest_point, ray_intersect,
  // segment_intersects_mesh and triangles_in_box read: the tree, the order and the triangles'
  // boxes (DistanceIndex::triangle_boxes), without the
  // dipoles (kept with oriented_boxes, whose frames come from them), the neighbours and the
  // vertex corner lists. About half the build time and a third of the memory; winding_number,
  // signed_distance, the batch queries, sample_sdf and vertex_pseudonormal must not be given
  // such an index (they assert).
  bool pairs_only = false;
  // With pairs_only: leave out the triangles' float boxes (24 bytes a triangle, the largest
  // part of such an index). The pair searches then load every triangle of a leaf pair they
  // reach: the same pairs, the same answers (bits), more work.
  bool without_triangle_boxes = false;
  // Only what winding_number reads: the tree, the order and the dipoles, without the
  // neighbours, the vertex corner lists and the triangles' boxes (pairs_only and
  // without_triangle_boxes are then ignored). The same tree and dipoles as a full index, so
  // the same winding numbers (bits); the pair searches, closest_point and ray_intersect take
  // it too (as pairs_only without_triangle_boxes). About 1 MB less per 40,000 triangles than
  // a full index, kept and at the build's peak: the Boolean's winding numbers use it.
  bool winding_only = false;
};

struct DistanceIndex {
  const Mesh* mesh = nullptr;
  Span<const BvhNode> nodes;      // nodes[0] is the root (one node, all absent, when empty)
  Span<const BvhDipole> dipoles;  // per node
  Span<const BvhObb> obbs;        // per node, or empty (DistanceIndexOptions::oriented_boxes)
  Span<const uint32_t> order;     // triangle ids in leaf order
  // pairs_only: per triangle in leaf order, a box that holds it (lo x, y, z, hi x, y, z; float,
  // widened by 2^-20 relative before rounding), which lets the pair searches pass over far
  // triangles without loading them; else empty.
  Span<const float> triangle_boxes;
  Span<const uint32_t> neighbors;  // 3 per triangle: across edge k, or kNoNeighbor
  // The corners at each vertex: vertex_uses[vertex_start[v] .. vertex_start[v + 1]) holds
  // 3 t + k for every corner k of triangle t at v, in triangle order (vertex_pseudonormal).
  Span<const uint32_t> vertex_start;  // vertex count + 1
  Span<const uint32_t> vertex_uses;   // 3 per triangle
  bool closed_manifold = false;       // every edge has exactly two consistently oriented uses
  // Inner nodes on the longest path from the root to a leaf (the root counts: 1 when all its
  // children are leaves); what sizes the stacks of traversals that descend two trees at once.
  uint32_t depth = 0;
};

constexpr uint32_t kNoNeighbor = ~uint32_t{0};

// The angle-weighted pseudonormal of vertex v (Baerentzen and Aanaes 2005; not normalised):
// the sum, over v's corners in triangle order, of the triangle's unit normal times its angle
// there (flat triangles add nothing). Computed when asked, from vertex_uses: only a query whose
// closest feature is a vertex needs one, and the build saves two atan2 a triangle.
Vec3 vertex_pseudonormal(const DistanceIndex& index, uint32_t v);

// Arena bytes build_distance_index() takes (all of it stays: it is the index).
uint64_t distance_index_bound(uint64_t vertex_count, uint64_t triangle_count,
                              const DistanceIndexOptions& options);

// Builds the index over `mesh` (which must outlive it and not change). Temporaries are
// returned before it finishes. Errors: kArenaExhausted, kInvalidMesh (an index out of range,
// a non-finite vertex), kLimitExceeded (more than (2^32 - 1) / 3 = 1,431,655,765 triangles:
// corners are numbered in 32 bits), kCancelled, kInvalidArgument (leaf size). Arena: at most
// distance_index_bound(). On an error the arena is as it was and *out is empty.
Status build_distance_index(const Context& ctx, const Mesh& mesh,
                            const DistanceIndexOptions& options, DistanceIndex* out);

// An index of `mesh` with `index`'s tree: the same leaf order (shared: `index` must outlive
// *out) and topology, the boxes (and the triangles' boxes, when `index` has them) computed
// from `mesh`'s triangles as build_distance_index computes them. For a pairs_only index
// (without oriented boxes) of a mesh with as many triangles, typically the same mesh moved
// (a jaw moved rigidly and rounded to float32): about a tenth of a build. Any such mesh gives
// a valid tree (the order is a permutation of its triangles), a good one when it is near the
// index's own mesh in shape. The pair queries' answers (mesh_pair_distance and its kin) do not
// depend on the tree: the same bits as over build_distance_index(mesh). Errors:
// kInvalidArgument (another triangle count), kInvalidMesh (a vertex not finite, a corner out of
// range), kArenaExhausted. Arena: refit_distance_index_bound(index), all of which stays. On an
// error the arena is as it was and *out is empty.
uint64_t refit_distance_index_bound(const DistanceIndex& index);
Status refit_distance_index(const Context& ctx, const DistanceIndex& index, const Mesh& mesh,
                            DistanceIndex* out);

// The closest point of the mesh to q (false for an empty mesh). Exact to the rounding of the
// point-triangle computation in double (about 1e-15 relative).
bool closest_point(const DistanceIndex& index, const Vec3& q, ClosestPoint* out);

// The closest point of the closed triangle abc to p (Ericson 5.1.5, with a well-conditioned
// path for slivers): the routine every query above uses. `feature`/`index` (may be null) say
// which part of the triangle it lies on.
Vec3 closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c,
                               Feature* feature = nullptr, uint8_t* index = nullptr);

// Closest points of the closed segments p0p1 and q0q1 (Ericson 5.1.9), *cp on the first and
// *cq on the second (an endpoint exactly when the parameter is 0 or 1): the squared distance.
double segment_closest(const Vec3& p0, const Vec3& p1, const Vec3& q0, const Vec3& q1, Vec3* cp,
                       Vec3* cq);

// The distance between the closed triangles a0a1a2 and b0b1b2, with a closest pair of points
// (pa on the first, pb on the second; either may be null). 0, with a common point in both,
// when they meet: decided exactly by triangles_intersect (geometry.h) and, for a degenerate
// triangle, by segment_intersects_triangle on its edges. Otherwise the least of the six
// vertex-triangle distances (closest_point_on_triangle) and the nine edge-edge distances
// (Ericson 5.1.9), the first of equal ones in that order; about 1e-15 relative.
double triangle_pair_distance(const Vec3& a0, const Vec3& a1, const Vec3& a2, const Vec3& b0,
                              const Vec3& b1, const Vec3& b2, Vec3* pa, Vec3* pb);

// Generalised winding number of the mesh at q: 1 inside a closed outward mesh, 0 outside,
// fractional near holes. `beta` >= 1 is the far-field accuracy (Barill et al.): a node is
// replaced by its dipole when its distance exceeds beta times its radius, and a leaf by the
// dipole of its triangles (summed when needed, about its box's centre) when its distance
// exceeds 1.5 beta times its box's half diagonal (the box is looser than a node's ball);
// 0 sums every triangle exactly (in leaf order).
double winding_number(const DistanceIndex& index, const Vec3& q, double beta = 2.0);

// The same number with no index: every triangle's solid angle, exactly as above, summed in
// triangle order. O(triangles) a query and no memory: cheaper than an index for a handful of
// queries (the Boolean's classification asks one or two a side).
double winding_number_direct(const Mesh& mesh, const Vec3& q);

// Signed distance: negative inside. With kPseudonormal the sign is that of
// (q - closest) . pseudonormal of the closest feature; with kWindingNumber it is inside when
// the winding number is >= 0.5. Points on the surface get +0. kAuto picks as documented.
struct SignedDistance {
  ClosestPoint closest;
  double distance = 0;  // signed
  double winding = 0;   // when computed (kWindingNumber), else 0
  SignMethod method = SignMethod::kAuto;
};
bool signed_distance(const DistanceIndex& index, const Vec3& q, SignMethod method,
                     SignedDistance* out);

// First hit of the ray origin + t * direction, t in [0, t_max]: Moller-Trumbore in double on
// closed triangles (not exact: a ray through an edge may hit either side or, rarely, neither;
// use segment_intersects_mesh for exact decisions), ties on t go to the smaller triangle id.
// False when nothing is hit.
struct RayHit {
  double t = 0;
  uint32_t triangle = 0;
};
bool ray_intersect(const DistanceIndex& index, const Vec3& origin, const Vec3& direction,
                   double t_max, RayHit* out);
// Does the segment pq meet the mesh (exact: orient3d-based segment-triangle tests)? The first
// triangle met, in index order, goes to *triangle.
bool segment_intersects_mesh(const DistanceIndex& index, const Vec3& p, const Vec3& q,
                             uint32_t* triangle);

// Does some triangle of the mesh come within `reach` (> 0) of the closed triangle abc
// (triangle_pair_distance() < reach: 0 when they meet, decided exactly)? No arena.
bool triangle_near_mesh(const DistanceIndex& index, const Vec3& a, const Vec3& b, const Vec3& c,
                        double reach);

// Where the closed triangle abc lies with respect to a closed mesh (signed_distance's kAuto
// sign): kNear when it comes within `reach` (> 0) of the surface (triangle_near_mesh), else
// wholly inside or wholly outside, at least `reach` from the surface. One closest-point query
// from a: when a is farther than reach plus abc's extent from a (max |b - a|, |c - a|), that
// query alone decides (a's sign holds for the whole triangle), and triangle_near_mesh runs only
// for the others. *seed (kNoNeighbor, or what the previous call left there, e.g. for the next
// triangle of a surface streamed out in order) starts the query with a tight bound and is set
// to a's closest triangle: the answer never depends on it. Needs a full index (not pairs_only).
// No arena.
enum class TriangleSide : uint8_t { kOutside, kInside, kNear };
TriangleSide triangle_side(const DistanceIndex& index, const Vec3& a, const Vec3& b, const Vec3& c,
                           double reach, uint32_t* seed);

// The triangles whose bounds overlap `box` (any order) into out[0 .. capacity); their count, or
// capacity + 1 when there are more (out then holds some of them). With `boxes`, each one's
// bounds (its corners' least and most coordinates) at the same index. No arena.
size_t triangles_meeting_box(const DistanceIndex& index, const Aabb& box, uint32_t* out,
                             size_t capacity, Aabb* boxes = nullptr);

// triangle_side() answered from a window of candidates: `ids` must hold every triangle whose
// bounds overlap abc's box grown by window_reach (>= reach), e.g. triangles_meeting_box() of a
// box that holds abc's, grown by window_reach. True with *side set to triangle_side()'s answer
// (the same closest triangle, the same sign) when a's closest triangle is certainly among them
// (closer than window_reach); false, *side untouched, when it may not be (ask triangle_side).
// With `closest`: a's closest point there too (closest_point()'s answer, bits). For many small
// triangles streamed out in order (a window serves the next ones): no tree descent per query.
// `seed` (any triangle id, or kNoNeighbor), e.g. the previous query's closest triangle, is
// looked at first: a tight bound from the start, so most of the window is passed over by its
// boxes; the answer never depends on it. `boxes` (or null), ids' bounds as
// triangles_meeting_box gives them, spare computing them for each query (the same filters, the
// same bits). Needs a full index (not pairs_only). No arena.
//
// `hint` (or null): a point off the surface and its side (kInside or kOutside; kNear: none yet),
// which the call sets to a and its side whenever it answers kInside or kOutside. Give one only
// when every triangle that meets the segment from hint->point to a is among ids (e.g. both lie
// in the box ids were found for), on a mesh that is closed_manifold and does not cross itself
// (the caller's to know: a splint from the Boolean). Then abc's reach is tested among ids
// first, and a's side is the hint's, changed by each triangle the segment crosses (exact
// orient3d signs; a segment that touches an edge, a corner or a plane is not counted, and the
// closest point decides instead): for the next triangle of a surface streamed out in order,
// a few exact signs instead of a closest-point search. The answer is the same; *closest is
// then left as it was.
struct SideHint {
  Vec3 point{};
  TriangleSide side = TriangleSide::kNear;
};
bool triangle_side_among(const DistanceIndex& index, const uint32_t* ids, size_t count,
                         double window_reach, const Vec3& a, const Vec3& b, const Vec3& c,
                         double reach, TriangleSide* side, ClosestPoint* closest = nullptr,
                         uint32_t seed = kNoNeighbor, const Aabb* boxes = nullptr,
                         SideHint* hint = nullptr);

// Every triangle whose bounds overlap `box`, appended to `out` in ascending id order.
Status triangles_in_box(const Context& ctx, const DistanceIndex& index, const Aabb& box,
                        ArenaArray<uint32_t>* out);

// Closest points for many queries on the executor; results[i] is for queries[i], bit for bit
// what closest_point() (or signed_distance()) gives, at any thread count. Errors:
// kInvalidArgument (sizes differ), kCancelled.
// A batch of at least 4096 queries and half as many as the mesh has triangles, near enough
// to the surface that a query meets few faces' regions (near a smooth surface: always), is
// answered triangle by triangle (a closest point transform over the bucketed queries: 13 to
// 23 times the queries per second of one tree search after another on tori of 87k to 543k
// triangles, about 13 times on the real dentition; splintcore-bench --filter closest_point);
// it takes about 65 bytes of arena a query and 4 a triangle, and where
// the arena does not hold them, the tree answers in 2 MB.
Status batch_closest_points(const Context& ctx, const DistanceIndex& index,
                            Span<const Vec3> queries, Span<ClosestPoint> results);
Status batch_signed_distances(const Context& ctx, const DistanceIndex& index,
                              Span<const Vec3> queries, SignMethod method, Span<double> results);

// ---------------------------------------------------------------------------------------------
// The closest pair between two meshes, the second moved by a translation: the bite opening of
// the automatic outline (conservative advancement: the mandible moves until the gap is X) and
// hinge-axis autorotation call it many times on the same two indexes.

// The closest pair of points between mesh A and mesh B moved by `offset_b` (B's points are
// p + offset_b, rounded as such).
struct MeshPairDistance {
  double distance = 0;  // +infinity when no pair lies within max_distance (or a mesh is empty)
  Vec3 point_a{};       // on triangle_a
  Vec3 point_b{};       // on triangle_b, in B's moved position
  uint32_t triangle_a = 0, triangle_b = 0;
  bool intersecting = false;  // the two triangles meet (exactly): distance 0
};

// Arena bytes mesh_pair_distance() takes (its best-first heap of 2048 box pairs and its
// depth-first stack of 15 (a.depth + b.depth) + 1, 24 bytes each, returned before it does;
// on an executor of more than one thread also 8 tasks' heaps of 256 and stacks: the search
// split, with the same answer, where the arena holds them, else serial): plus alignment, a
// few hundred kilobytes.
uint64_t mesh_pair_distance_bound(const DistanceIndex& a, const DistanceIndex& b);

// The least triangle_pair_distance() between a triangle of A and one of B moved by offset_b:
// 0 when the surfaces meet (exactly, triangles_intersect on the moved triangles; the meshes
// may interpenetrate). A dual traversal of the two 4-wide hierarchies, best first (nearest box
// pair next), B's float boxes shifted in double, pruning a pair of boxes, or of triangles (by
// their boxes or by a separation along one's normal), only when its distance exceeds the best
// so far (by a margin that covers rounding), so every triangle pair that could tie is examined and
// the result is the same bits whatever the trees' shapes (leaf size, oriented boxes) and order: the
// least (squared distance, triangle_a, triangle_b). Pairs with a squared distance above
// max_distance^2 are not reported (+infinity: the true minimum). Heavily interpenetrating
// meshes are slow (every pair of touching boxes is examined for the smallest meeting pair).
// Errors: kInvalidArgument (offset not finite, max_distance negative or not a number),
// kArenaExhausted. An empty mesh gives distance +infinity and OK.
Status mesh_pair_distance(const Context& ctx, const DistanceIndex& a, const DistanceIndex& b,
                          const Vec3& offset_b, double max_distance, MeshPairDistance* out);

// Do A and B moved by offset_b meet (some triangle pair meets, decided exactly as
// mesh_pair_distance() does)? The same traversal, stopped at the first meeting pair found:
// then *meet is true and *out that pair (distance 0, intersecting, a common point), which need
// not be mesh_pair_distance's (the least triangle ids); else *meet is false and out->distance
// +infinity. Much faster than mesh_pair_distance on interpenetrating meshes, where that one
// examines every pair of touching boxes. Arena, errors: as mesh_pair_distance.
Status mesh_pair_meet(const Context& ctx, const DistanceIndex& a, const DistanceIndex& b,
                      const Vec3& offset_b, bool* meet, MeshPairDistance* out);

// mesh_pair_distance and mesh_pair_meet with B moved by a rigid transform instead of a
// translation: B's points are move_b.apply_point(p), rounded as such (the hinge-axis
// autorotation, which turns the mandible about the condyles, calls them with its one index of
// each jaw). B's node and triangle boxes are bounded after the move by the box of the moved box
// (its centre moved, its half-extents through |R|, widened over the rounding), so the tree is
// built once; the triangles themselves are moved exactly as given. The answer is the least
// (squared distance, triangle_a, triangle_b) as mesh_pair_distance's, the same bits as
// mesh_pair_distance over an index of B's moved copy when the moved copy's corners are those
// apply_point gives. A rotated box is looser than the box of the rotated triangles (up to
// sqrt(3) times as wide at 45 degrees), so the search examines more pairs than over an index
// of the moved copy; no index is rebuilt. Arena: mesh_pair_distance_bound(). Errors: as
// mesh_pair_distance (kInvalidArgument for a move that is not finite).
Status mesh_pair_distance_rigid(const Context& ctx, const DistanceIndex& a, const DistanceIndex& b,
                                const RigidTransform& move_b, double max_distance,
                                MeshPairDistance* out);
Status mesh_pair_meet_rigid(const Context& ctx, const DistanceIndex& a, const DistanceIndex& b,
                            const RigidTransform& move_b, bool* meet, MeshPairDistance* out);

// A triangle of A and one of B.
struct TrianglePairIds {
  uint32_t a = 0, b = 0;
};

// mesh_pair_distance(ctx, a, b, offset_b, max_distance, out), and every triangle pair whose
// distance may be at most max_distance (all those whose computed distance is, in traversal
// order) into `pairs`: their number in *count, or pairs.size() + 1 when they do not fit (then
// `pairs` holds a part only). B moved along a unit direction by at most m from offset_b
// changes every pair's distance by at most m, so while the closest distance found plus 2 m
// stays below max_distance, candidate_pair_distance() over the pairs gives mesh_pair_distance's
// answer. Slower than mesh_pair_distance (every pair within max_distance is examined). Arena,
// errors: as mesh_pair_distance.
Status mesh_pair_distance_collect(const Context& ctx, const DistanceIndex& a,
                                  const DistanceIndex& b, const Vec3& offset_b, double max_distance,
                                  Span<TrianglePairIds> pairs, size_t* count,
                                  MeshPairDistance* out);

// The least (squared distance, triangle_a, triangle_b) over the given pairs only, B moved by
// offset_b, with mesh_pair_distance's bits (its distance, points and intersecting flag for
// that pair). No arena. Errors: kInvalidArgument (offset not finite, a pair's triangle out of
// range).
Status candidate_pair_distance(const DistanceIndex& a, const DistanceIndex& b,
                               Span<const TrianglePairIds> pairs, const Vec3& offset_b,
                               MeshPairDistance* out);

// mesh_pair_distance_collect and candidate_pair_distance with B moved rigidly (as
// mesh_pair_distance_rigid). B turned by at most dtheta about an axis changes every pair's
// distance by at most R dtheta (R: the largest distance of a B vertex from the axis), the
// bound the autorotation's pool of pairs rests on. Arena, errors: as their translated kin.
Status mesh_pair_distance_collect_rigid(const Context& ctx, const DistanceIndex& a,
                                        const DistanceIndex& b, const RigidTransform& move_b,
                                        double max_distance, Span<TrianglePairIds> pairs,
                                        size_t* count, MeshPairDistance* out);
Status candidate_pair_distance_rigid(const DistanceIndex& a, const DistanceIndex& b,
                                     Span<const TrianglePairIds> pairs,
                                     const RigidTransform& move_b, MeshPairDistance* out);

// ---------------------------------------------------------------------------------------------
// Narrow-band signed distance volume, sampled slab by slab for the tiled marching cubes.

struct SdfGrid {
  Vec3 origin{};       // position of sample (0, 0, 0)
  double spacing = 0;  // mm between samples
  uint32_t nx = 0, ny = 0, nz = 0;
  double band = 0;  // |distance| beyond band is clamped to +-band (cheaper: pruned queries)
};

// Samples z-layers [z_begin, z_end) into out (x fastest, then y, then z; nx * ny per layer),
// float, clamped to the band. Runs the layers' rows on the executor. A sample beyond the band
// only needs its sign: on a closed mesh (closed_manifold) with a spacing of at most half the
// band it takes the sign of the sample before it in its row (no surface lies between them),
// so only a row's first samples beyond the band take the winding number; otherwise each does.
// On a closed mesh both give the same inside and outside (the tests compare them sample by
// sample); carried, the signs of a row also never change without passing through the band.
// splintcore-bench --filter sdf_volume measures the sampler.
Status sample_sdf(const Context& ctx, const DistanceIndex& index, const SdfGrid& grid,
                  SignMethod method, uint32_t z_begin, uint32_t z_end, Span<float> out);

}  // namespace splintcore

#endif  // SPLINTCORE_DISTANCE_H
