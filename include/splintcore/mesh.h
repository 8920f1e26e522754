// splintcore mesh: the one indexed triangle mesh type, welding of STL soup, topology checks and
// measures.
#ifndef SPLINTCORE_MESH_H
#define SPLINTCORE_MESH_H

#include "splintcore/core.h"
#include "splintcore/geometry.h"

namespace splintcore {

struct Triangle {
  uint32_t v[3];  // counter-clockwise seen from outside
};

// A triangle as STL stores it: three float32 corners (the facet normal is not kept: it is
// recomputed from the corners, whose order defines the orientation).
struct SoupTriangle {
  float p[3][3];
};

// Indexed triangle mesh in an arena. Vertices are double so that later stages (Boolean
// intersection points) are exact where they can be; STL input is float32, held exactly.
struct Mesh {
  ArenaArray<Vec3> vertices;
  ArenaArray<Triangle> triangles;

  Mesh() = default;
  explicit Mesh(Arena* arena) : vertices(arena), triangles(arena) {}
  void bind(Arena* arena) {
    vertices.bind(arena);
    triangles.bind(arena);
  }
};

// A mesh over arrays that something else owns, to pass a part of a mesh (e.g. one jaw's
// triangles, with all the vertices they index) to a function that takes a Mesh. It is bound
// to no arena, so it cannot grow; it is valid while the arrays are, and is for reading only.
inline Mesh mesh_view(Span<const Vec3> vertices, Span<const Triangle> triangles) {
  Mesh view;
  view.vertices.adopt(const_cast<Vec3*>(vertices.data()), vertices.size(), vertices.size());
  view.triangles.adopt(const_cast<Triangle*>(triangles.data()), triangles.size(), triangles.size());
  return view;
}

// Bytes weld_exact() may take from the arena for `triangle_count` triangles, at most (outputs
// and temporaries together; the temporaries are returned before it finishes).
uint64_t weld_exact_bound(uint64_t triangle_count);

// Welds soup into `out` (bound to an arena, appended to): corners with bit-identical
// coordinates become one vertex (-0.0 and +0.0 are the same). Vertex ids are given in order of
// first appearance, so the result depends only on the soup, never on hashing. Triangles whose
// corners weld together are kept (check_mesh() reports them as degenerate).
// Errors: kArenaExhausted; kNonFinite (names the triangle); kLimitExceeded (> 2^32-1 corners);
// kInvalidArgument (`out` not empty); kCancelled. Arena: at most weld_exact_bound(); only the
// mesh stays. On an error the arena is as it was (rewound to its top at entry) and `out` is
// empty.
Status weld_exact(const Context& ctx, Span<const SoupTriangle> soup, Mesh* out);

// Welds corners closer than `tolerance` (max-norm, mm), order-independently: the connected
// components of the "closer than tolerance" relation become one vertex, placed at the
// component's lexicographically smallest corner. Permuting the soup's triangles permutes the
// output triangles but never changes vertex positions. `out` must be empty (bound to the
// arena). Arena: at most weld_tolerance_bound(); the mesh stays, temporaries (sort keys,
// union-find, about 50 bytes a corner) are returned before it finishes. Errors: kInvalidArgument
// (tolerance not > 0, `out` not empty); kLimitExceeded (tolerance too small for the mesh's extent:
// more than 2^20 cells an axis; > 2^32-1 corners); kNonFinite; kArenaExhausted; kCancelled. On an
// error the arena is as it was and `out` is empty.
uint64_t weld_tolerance_bound(uint64_t triangle_count);
Status weld_tolerance(const Context& ctx, Span<const SoupTriangle> soup, double tolerance,
                      Mesh* out);

// ---------------------------------------------------------------------------------------------
// Checks and measures.

struct EdgeRef {
  uint32_t v0 = 0, v1 = 0;  // vertex ids (v0 < v1)
  uint32_t triangle = 0;    // one triangle using the edge
};

struct MeshReport {
  uint64_t vertex_count = 0;
  uint64_t triangle_count = 0;
  uint64_t unreferenced_vertices = 0;
  uint64_t edge_count = 0;             // distinct undirected edges
  uint64_t boundary_edges = 0;         // used by one triangle
  uint64_t boundary_loops = 0;         // components of the boundary edges (holes and borders;
                                       // two that touch at a vertex are one)
  uint64_t nonmanifold_edges = 0;      // used by three or more
  uint64_t orientation_conflicts = 0;  // used twice in the same direction
  uint64_t degenerate_triangles = 0;   // repeated vertex ids or zero area (exact)
  uint64_t duplicate_triangles = 0;    // same vertex set as an earlier triangle
  uint64_t shells = 0;                 // components connected through edges
  int64_t euler_characteristic = 0;    // V - E + F over referenced vertices
  int64_t genus = -1;                  // sum over shells, when closed and edge-manifold
  double area = 0.0;                   // mm^2
  // Signed, mm^3 (> 0 when outward). Computed for any mesh, but only a closed mesh has a
  // volume: for an open one (a scan) it depends on where the origin lies, and neither it
  // nor outward() says anything (the `check` command prints "n/a (open)").
  double volume = 0.0;
  Aabb bounds;

  // The first offender of each kind (index order), for error messages.
  EdgeRef first_boundary_edge{};
  EdgeRef first_nonmanifold_edge{};
  EdgeRef first_orientation_conflict{};
  uint32_t first_degenerate_triangle = 0;
  uint32_t first_duplicate_triangle = 0;

  bool closed() const { return boundary_edges == 0 && triangle_count > 0; }
  bool edge_manifold() const { return nonmanifold_edges == 0; }
  bool oriented() const { return orientation_conflicts == 0; }
  bool outward() const { return volume > 0.0; }
  // Closed, manifold, consistently oriented, outward, nothing degenerate or duplicated.
  bool is_valid_solid() const {
    return closed() && edge_manifold() && oriented() && outward() && degenerate_triangles == 0 &&
           duplicate_triangles == 0;
  }
};

// Bytes check_mesh() takes from the arena at most: about 69 per triangle plus 5 per vertex
// (the worst case is shells touching at many vertices), all returned before it finishes.
// Linear time: the edges are counted in buckets by vertex, not sorted.
uint64_t check_mesh_bound(uint64_t vertex_count, uint64_t triangle_count);

// Fills `report` (temporaries from the arena, at most check_mesh_bound(), returned before it
// finishes).
// Errors: kArenaExhausted; kInvalidMesh when a triangle references a vertex that does not
// exist (names the triangle); kLimitExceeded (2^30 triangles or more).
Status check_mesh(const Context& ctx, const Mesh& mesh, MeshReport* report);

// What a constructed solid must be, checked in linear time (half-edges bucketed by vertex):
// every edge used by exactly two triangles in opposite directions (closed, edge-manifold,
// consistently oriented), no triangle of zero area (exact), positive volume (*volume gets
// mesh_volume()). Shells, genus and duplicate triangles are check_mesh's. Errors: kInvalidMesh
// naming the first offending edge (its vertices and a triangle; at_index: that triangle) or
// triangle; kArenaExhausted.
uint64_t check_closed_oriented_bound(uint64_t vertex_count, uint64_t triangle_count);
// The first triangle of zero area (exact: a filter, then collinear3d), or kNoTriangle.
constexpr uint32_t kNoTriangle = ~uint32_t{0};
uint32_t find_flat_triangle(const Mesh& mesh);
Status check_closed_oriented(const Context& ctx, const Mesh& mesh, double* volume);

// Turns a report into the first error a solid would have, or ok: "mesh is not closed: 12
// boundary edges, first between vertices 4 and 9 (triangle 17)" and so on.
Status require_valid_solid(const MeshReport& report);

// Individual measures (deterministic: summed in triangle order, relative to the box centre).
Aabb mesh_bounds(const Mesh& mesh);
// Triangle t's box (its three corners).
inline Aabb triangle_box(const Mesh& mesh, uint32_t t) {
  Aabb box;
  for (uint32_t v : mesh.triangles[t].v) box.add(mesh.vertices[v]);
  return box;
}
double mesh_area(const Mesh& mesh);
double mesh_volume(const Mesh& mesh);

// ---------------------------------------------------------------------------------------------
// Self-intersection: pairs of triangles that meet other than through the vertices and edges
// they share. Decided exactly (triangles_intersect and orient3d/orient2d): triangles sharing
// an edge conflict only when coplanar and folded onto each other; sharing a vertex, only when
// they meet elsewhere; sharing all three vertices always. Degenerate triangles are skipped
// (check_mesh reports them).

struct SelfIntersectionReport {
  uint64_t intersecting_pairs = 0;    // counted up to max_pairs (then it stops)
  uint32_t first_a = 0, first_b = 0;  // the smallest pair (a < b) found, when any
  // Pairs of non-degenerate triangles kept by the broad phase, examined before stopping: those
  // whose 14-DOPs (quantized and slightly widened) overlap; whose boxes overlap, when a
  // coordinate is not finite or, unless zero, beyond [2^-306, 2^100] in magnitude. Every
  // pair that shares a vertex id or meets is one. Not the number of exact tests: filters
  // settle most of them.
  uint64_t candidate_pairs = 0;
  bool self_intersecting() const { return intersecting_pairs > 0; }
};

uint64_t find_self_intersections_bound(uint64_t triangle_count);

// A hierarchy of 14-DOPs over the triangles traversed against itself; pairs sharing a vertex
// are cleared a vertex star at a time when the star is certainly embedded, the others behind
// floating-point filters, the rest by the exact tests. max_pairs = 0 counts all pairs. When
// more than max_pairs pairs conflict, the pairs counted (and the first pair) are the first
// max_pairs found by a sweep over triangle boxes sorted by x, whatever the hierarchy does.
// Memory: find_self_intersections_bound(triangles) is always enough (about 125 bytes a triangle
// are used: 123 on the real dentition's Boolean result, 121 on the 543k phantom maxilla). When the
// whole hierarchy does not fit in what the arena has left, it is made and walked in slabs along x,
// as many as that needs (each pair counted in one slab only): the same report in far less memory
// (about 6% of the whole pass's peak on 10-20k-triangle meshes in
// SelfIntersection.SlabsGiveTheSameReportInLessMemory), at some cost in time. When more than
// max_pairs pairs conflict, two more passes find the sweep's answer (32 bytes more a pair
// asked for); the sweep itself (about 180 bytes a triangle) runs only for max_pairs above
// 65,536, coordinates beyond the filters' range, or more than three vertices a triangle.
// Errors: kArenaExhausted, kInvalidMesh (index out of range), kCancelled.
Status find_self_intersections(const Context& ctx, const Mesh& mesh, uint64_t max_pairs,
                               SelfIntersectionReport* report);

// Moves a mesh that sits above `start` in the arena (a result built after its temporaries)
// down to `start`, rewinding everything else, and points `out` at it. The mesh's triangles
// must have been allocated before its vertices (then no destination lies above bytes not yet
// copied; memmove handles the overlap). Never fails: the moved mesh needs no more room than it
// had. (In an arena of blocks whose allocator refuses a block the move needs, the arrays not
// yet moved stay where they are, with everything below the arena's top at the call: the mesh
// is whole, only not as low.)
// `vertices_first`: the same for a mesh whose vertices were allocated before its triangles
// (marching_cubes_mesh's output).
void move_mesh_down(Arena& arena, const Arena::Marker& start, const Mesh& mesh, Mesh* out,
                    bool vertices_first = false);

// ---------------------------------------------------------------------------------------------
// Scan preparation: the repairs an intraoral scan (an open surface of crowns and gum) needs
// before it is a jaw, in a fixed order, each counted (src/mesh/prepare.cpp says how each is
// decided): 1 duplicate triangles removed, 2 degenerate (zero-area, exact) triangles removed,
// 3 edges with 3+ triangles resolved (the best-connected two kept), 4 vertices with several
// fans split, 5 islands removed, 6 consistent orientation, 7 holes of at most max_hole_edges
// edges filled, 8 unused vertices removed. It never closes the scan's border (a loop longer
// than max_hole_edges): an open scan stays open.

struct PrepareOptions {
  // Islands: components (through edges) smaller than this, except the largest, are removed.
  // By area unless min_island_triangles > 0: an area means the same at any scan resolution.
  // 10 mm^2 (about 3 x 3 mm): scanner debris is a few mm^2, the smallest crown surface is
  // several times more.
  double min_island_area = 10.0;      // mm^2
  uint32_t min_island_triangles = 0;  // > 0: count triangles instead
  // Holes (boundary loops) of at most this many edges are filled; 0: none. A scan's own border
  // has hundreds of edges, the spots it missed between teeth tens.
  uint32_t max_hole_edges = 32;
  // Non-zero: the whole mesh is turned, if need be, so that its net normal (the sum of its
  // area vectors) points this way (an arch's crowns facing +occlusal).
  Vec3 occlusal{0, 0, 0};
};

struct PrepareReport {
  uint64_t input_vertices = 0, input_triangles = 0;
  uint64_t duplicate_triangles = 0;    // 1: removed
  uint64_t degenerate_triangles = 0;   // 2: removed
  uint64_t nonmanifold_edges = 0;      // 3: edges that had 3+ triangles
  uint64_t nonmanifold_triangles = 0;  //    triangles removed there
  uint64_t nonmanifold_vertices = 0;   // 4: vertices whose fans were split
  uint64_t split_vertices_added = 0;   //    copies made
  uint64_t islands = 0;                // 5: components removed
  uint64_t island_triangles = 0;       //    their triangles
  uint64_t components = 0;             //    components kept
  uint64_t flipped_triangles = 0;      // 6: triangles turned
  uint64_t flipped_components = 0;     //    components turned whole (most triangles turned)
  uint64_t orientation_conflicts = 0;  //    edges left disagreeing (a non-orientable strip)
  uint64_t holes_filled = 0;           // 7: loops filled
  uint64_t hole_triangles = 0;         //    triangles added
  uint64_t holes_left = 0;             //    loops left open (the border; longer; not simple)
  uint64_t unreferenced_vertices = 0;  // 8: removed
  uint64_t output_vertices = 0, output_triangles = 0;
};

// Arena bytes prepare_scan() takes at most (the output mesh stays; it is at most
// vertex_count + 4 triangle_count vertices and 4 triangle_count triangles): about 300 bytes a
// triangle and 50 a vertex (the 87k-triangle torus: 28.7 MB, all of it used).
uint64_t prepare_scan_bound(uint64_t vertex_count, uint64_t triangle_count);

// Reads `mesh`, writes the prepared mesh to `out` (empty; it is placed where the arena's top
// was, everything else returned). Deterministic: the output depends only on the input's bytes.
// Errors: kInvalidMesh (an index out of range: named), kNonFinite (named), kInvalidArgument
// (`out` not empty, a negative island area), kLimitExceeded (2^29 triangles or more),
// kArenaExhausted, kCancelled. On an error the arena is as it was and `out` empty.
Status prepare_scan(const Context& ctx, const Mesh& mesh, const PrepareOptions& options, Mesh* out,
                    PrepareReport* report);

// What remove_small_shells() took out.
struct SmallShells {
  uint64_t removed = 0;         // shells
  uint64_t triangles = 0;       // their triangles
  double volume_mm3 = 0;        // the sum of their |volume|
  double largest_kept_mm3 = 0;  // the volume of the largest shell (always kept)
};

// Arena bytes remove_small_shells() takes at most (all of it given back): 16 a vertex.
uint64_t remove_small_shells_bound(uint64_t vertex_count);

// Takes out of *mesh, in place, every shell (a set of triangles joined through shared
// vertices) whose |volume| is below `min_volume` (mm^3), except the largest: e.g. the crumbs a
// Boolean of nearly touching surfaces can leave beside a part. The kept triangles and vertices
// stay in their order (renumbered); with nothing to take out the mesh is not touched. Vertices
// no triangle uses are kept. Volumes are the divergence sums in triangle order (mesh_volume's,
// about the box centre), so the choice is the same on every platform. Errors: kInvalidMesh (an
// index out of range: named), kLimitExceeded (2^32 - 1 vertices or more), kArenaExhausted;
// on an error *mesh is unchanged.
Status remove_small_shells(const Context& ctx, double min_volume, Mesh* mesh, SmallShells* removed);

// Applies a rigid transform to every vertex in place.
void transform_mesh(const RigidTransform& x, Mesh* mesh);

// Scales every vertex by `factor` about the origin, in place, each coordinate rounded to the
// nearest float32 (what an STL holds): a mesh in other units brought to mm (x25.4 from inches,
// x1000 from metres, x0.001 from micrometres). The product is rounded once to double, then to
// float32, so the same mesh and factor give the same bits everywhere. Errors, with *mesh
// unchanged: kInvalidArgument (factor not finite or not above 0: a negative one would turn
// the mesh inside out), kNonFinite (a vertex that is NaN or infinite, named), kLimitExceeded
// (a vertex that would leave float32 range, named). Distinct vertices that round to the same
// point stay distinct (check_mesh then counts the triangles that became degenerate).
Status scale_mesh(double factor, Mesh* mesh);

}  // namespace splintcore

#endif  // SPLINTCORE_MESH_H
