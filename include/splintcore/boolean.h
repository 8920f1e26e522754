// splintcore boolean: difference, union and intersection of triangle meshes by corefinement (Chen
// et al. 2016, "The Boolean operation", Fig. 4): both meshes are split along their intersection,
// the pieces are classified inside or outside the other solid, and the result is assembled from the
// pieces an operation keeps.
//
// What it promises (how it decides, stage by stage: docs/architecture.md, "The Boolean"):
// - every geometric decision is an exact predicate on the input coordinates; intersection
//   points are named by the features that define them, so the two meshes share every
//   intersection edge and the result has no cracks by construction;
// - input vertices are copied bit for bit; every other vertex is an intersection point
//   (rounded to float32 before the re-triangulation, with float32 output);
// - degenerate contacts (a vertex on the other surface, edges meeting exactly, coplanar faces)
//   are resolved exactly; what the exact rule cannot return falls back to translating A (never
//   B) by at most about 1 um (BooleanOptions::max_nudges, BooleanStats::nudge);
// - the result is checked (closed, edge-manifold, oriented, nothing flat or merged by
//   rounding unless merged on purpose (max_nudges), positive volume, and with
//   check_self_intersection no self-intersection, exactly) before it is returned: a failure
//   is an error, never a silently broken mesh.
//
// B may hold several shells (one per tooth; shells are components through shared vertices),
// which may overlap each other: B means the union of its shells. Shells that overlap where it
// matters (their boxes meet inside A's box for the difference and the intersection, anywhere
// for the union; then exactly: their triangles meet, touching included, or one lies inside
// the other by winding number) are put in different groups, greedily in shell order, and the
// groups are applied one corefinement pass each, fewest triangles first (each pass's first
// operand holds the imprints of the passes before): A - B = ((A - G1) - G2) - ..., A + B =
// ((A + G1) + G2) + ..., A * B = A * ((G1 + G2) + ...) (not A - (A - B), whose operands share
// A's faces). When that order fails (other than for memory or a cancel), the greedy order is
// tried as well, and its error is the one returned when both fail. With one group (no
// overlap where it matters) it is exactly one pass, the same bytes as before groups existed.
// Intermediate results are checked closed and oriented, only the final one for self-intersection; a
// nudge (below) of a later pass moves the previous result (for the intersection's unions, the union
// of groups so far). For the intersection with several groups the shells near A must be closed
// (they become the first operand of a union). BooleanStats::shells, shell_groups and passes say
// what was done. B may be open (a scan) when its border lies outside A; an open B whose border
// meets or enters A is refused up front (kInvalidMesh: "B is open: N boundary edges in M loops; its
// border meets A at vertex i (x, y, z): ..."; at_index: i; decided exactly for B's boundary edges
// in A's box, which costs A's distance index then). With float32 output B's vertices must be
// float32 values (as read from STL; a moved jaw must be rounded first), since they are kept bit for
// bit.
#ifndef SPLINTCORE_BOOLEAN_H
#define SPLINTCORE_BOOLEAN_H

#include "splintcore/core.h"
#include "splintcore/geometry.h"
#include "splintcore/mesh.h"

namespace splintcore {

enum class BooleanOp : uint8_t {
  kDifference,    // A - B: A's pieces outside B, B's pieces inside A (reversed)
  kUnion,         // A + B: A's pieces outside B, B's pieces outside A
  kIntersection,  // A * B: A's pieces inside B, B's pieces inside A
};
const char* boolean_op_name(BooleanOp op);

struct BooleanOptions {
  BooleanOp op = BooleanOp::kDifference;
  // Round the intersection points to float32 (input vertices that are float32 already, as STL
  // input is, are unchanged) and check the result as an STL file will hold it: no two
  // vertices rounded together, no triangle rounded flat, closed, and (below) no
  // self-intersection. What rounding breaks is an error naming the place, never a silently
  // broken file.
  bool float32_output = true;
  // Exact self-intersection check of the result (find_self_intersections): the final word
  // that the file is a valid solid. Costs about as much as the operation itself.
  bool check_self_intersection = true;
  // A degenerate contact that the exact rule cannot return (see the top: e.g. a result that
  // is not an edge-manifold solid), or a result that rounding to float32 would break, is
  // retried with A (never B) translated by k * step * (1, 3, 7) for k = 1..max_nudges, step = 2^-16
  // mm (15 nm; coarser only when A's coordinates are beyond 256 mm, so that float32 vertices of A
  // stay float32): at most about 0.9 um with the default, far below a printer's 16 um layer. The
  // translation used is in BooleanStats::nudge. 0 turns it off. In every attempt, intersection
  // points rounding together (distinct exact points closer than a rounding step) are merged
  // into one (BooleanStats::merged_points; a point that collapses a segment or pinches off a
  // sliver's corner) rather than refused, so a nudge runs only when that fails too. An attempt
  // that meets no such points gives the bytes it gave without merging; a failed one is judged
  // (nudged again, or its error returned) by the refusal it would have met without merging,
  // so the errors name what rounding broke.
  uint32_t max_nudges = 8;
  // A bound on the work: the candidate pairs (triangles of A and B whose cells and boxes meet,
  // each decided by exact tests) of one run summed over its nudged attempts. 0: 64 per
  // triangle of A and B plus 2^22 (splint cases use a few per triangle). Two tessellations of
  // nearly the same faces (e.g. long thin CAD triangles over dense ones) pair nearly every
  // triangle with every other near it: tens of millions of pairs a run, minutes with nudges.
  // Over the bound: kLimitExceeded at the first attempt, or after a nudge the first attempt's
  // own error, saying that the nudges stopped.
  uint64_t max_candidate_pairs = 0;
  // The caller vouches that B's open border, if B has one, lies outside A (the blockout's swept
  // surface, kept only near the splint: outside it, at least an eighth of a voxel from it,
  // by construction): the up-front check that names where a border meets A (issue 30: an exact
  // segment test and a winding number a border edge; most of the blockout's Boolean time) is
  // left out. A border that does meet A still fails, with the run's own less specific error.
  // For the difference it also spares the winding numbers of B's uncut parts that reach the
  // border of B's triangles near A: outside A, their corners flood out from there (the
  // blockout's swept surface leaves thousands of such islands near the splint). The border
  // must lie outside A as any nudge moves it (the blockout's eighth of a voxel is far more).
  bool b_border_outside_a = false;
  // When not null: the returned result's check_mesh report (mesh.h), made by the result check
  // in place of its own edge pass (the same decisions; check_mesh's memory, check_mesh_bound:
  // about 69 bytes a triangle and 21 a vertex, for the edge pass's 12 and 12; 2.8 MB more at
  // the real dentition's peak), so that a caller who reports on the result does not pay
  // for a second pass over its edges. BooleanStats::result_report_made says whether it was
  // made: not when that memory was not there (the check then pairs the edges its own way, with
  // the same result) or the call failed.
  MeshReport* result_report = nullptr;
};

struct BooleanStats {
  uint64_t near_b_triangles = 0;     // B triangles whose boxes meet A's box
  uint64_t candidate_pairs = 0;      // (A, B) triangle pairs whose boxes overlap
  uint64_t intersecting_pairs = 0;   // pairs that cross (one segment each)
  uint64_t degenerate_pairs = 0;     // pairs that touch or overlap, resolved exactly
  uint64_t intersection_points = 0;  // distinct points shared by both meshes
  // Intersection points that rounded (to float32 for STL output) onto another one and were
  // merged into it: the one with the lowest id stands for them all (0 in most runs).
  uint64_t merged_points = 0;
  uint64_t cut_triangles_a = 0;
  uint64_t cut_triangles_b = 0;
  uint64_t winding_queries = 0;  // parts without a cut, classified by winding number
  uint64_t output_triangles = 0;
  uint64_t output_triangles_a = 0;  // the result's first triangles come from A, the rest from B
  uint64_t self_intersection_candidates = 0;  // pairs tested by the final check
  // The returned result was checked exactly for self-intersections and has none
  // (options.check_self_intersection; with several passes, the final pass's result).
  bool self_intersection_checked = false;
  bool result_report_made = false;  // *options.result_report holds the returned result's report
  uint32_t attempts = 0;            // 1 + the nudges tried (with both orders of the passes: both's)
  Vec3 nudge{};                     // A's translation in the returned result
  // How far A's own faces moved in the returned result: with several passes every pass's nudge
  // added (each moves all that came before it), else nudge.
  Vec3 nudge_sum{};
  // B's shells (components through shared vertices), the groups of shells that overlap no
  // other shell of their group where it matters, and the corefinement runs made (1 for one
  // group; see mesh_boolean). With several passes the counts above are summed over the
  // passes (attempts too); output_triangles and output_triangles_a are the final pass's (its
  // first operand is the previous pass's result), nudge is the final pass's translation of it.
  // The difference stops early when nothing of A is left (then passes < shell_groups).
  uint32_t shells = 0;
  uint32_t shell_groups = 0;
  uint32_t passes = 0;
  // Near triangles of B whose pair tests ran in the executor's tasks (0 on one thread or when
  // the tasks' memory was not there): the one figure here that depends on the thread count.
  uint64_t parallel_near_triangles = 0;
  // Batches the near triangles of B went in because A's slots for all of them did not fit the
  // arena (0: all at once; the returned attempt's, summed over passes). Only the time and the
  // memory differ: the result, the other stats and every error are the same.
  uint32_t hit_batches = 0;
};

// Computes options.op of the closed mesh A and the mesh B into `out` (empty).
// A must be a valid solid (closed, edge-manifold, outward). Temporaries are returned before it
// finishes; the result is moved down over them; on an error the arena is as it was and *out
// empty. Arena: finding B's shells takes about 9 bytes per vertex and 4 (8 when a shell's
// triangles are not one run of B's) per triangle of B, plus, while two shells whose boxes
// overlap are compared, at most about 130 bytes per triangle of theirs in the boxes' overlap;
// all of it is returned before the one pass when there is one group. With several groups it
// stays (with 4 more bytes per vertex of B) below the passes, and each pass also has the
// previous result and one group's copy of its shells below it. A pass (difference and
// intersection) where half of B's triangles or fewer are near A works on a copy of those: 4
// bytes per vertex of B, then about 28 per near vertex and 17 per near triangle, the run's own
// arrays sized by the near part (with more near, on B itself: the same result);
// its result is checked after it has been moved down over the run's temporaries (the exact
// self-intersection check: about 270 bytes per result triangle). Threads: with ctx.executor
// the pair tests of the near triangles of B run in tasks (each with 4 bytes per triangle of A
// near B and about 2.5 per near triangle of B of its own, taken only when the arena has them
// and given back before the next stage); a task stops where the run's own state is needed (a
// degenerate contact, an error, the bound on pairs) and one thread goes on from there, so the
// result, the stats (but parallel_near_triangles), every error and the arena as left are the
// same at any thread count. When the slots of A's triangles near B (about 470 bytes each, made each
// attempt) do not fit, B's near triangles go in 8 batches in their order, each with the slots of
// only the part of A its cells list, on one thread: the same result, stats and errors in less
// memory (stats.hit_batches; a sphere minus a crossing sphere: 48% less). Errors: kInvalidMesh (A
// is not a solid, a degenerate triangle of B meets A, an index out of range: named; for the
// intersection with overlapping shells also a group of them that is not a solid; and, when a
// run fails with kUnsupported or kInternal, A crossing itself, or B in the union as one shell:
// checked then with find_self_intersections, the pair named, the run's error kept), kNonFinite,
// kInvalidArgument (B not float32 with float32 output), kUnsupported (a degenerate contact the
// exact rule cannot return, or a float32-fragile one, that no nudge resolved: named),
// kArenaExhausted (the message says how much was needed at that point), kLimitExceeded (more than
// 2^31 vertices or triangles), kCancelled, kLimitExceeded also for more candidate pairs than
// options.max_candidate_pairs, kInternal (a result that fails its own check: please report it with
// the inputs). An error of a pass when there are several says which pass
// ("pass 2 of 3").
Status mesh_boolean(const Context& ctx, const Mesh& a, const Mesh& b, const BooleanOptions& options,
                    Mesh* out, BooleanStats* stats);

// Where B matters to mesh_boolean(a, B, options) for the difference and the intersection: A's
// box widened by the farthest a nudge can move A (options.max_nudges), with room to spare; for
// the union, everywhere (infinite bounds). A triangle of B whose corners all lie beyond one side
// of this box (x below lo.x, ..., strictly) is never cut and never inside A, so a caller may
// leave such triangles (and the vertices only they use) out of B, keeping the others in their
// order: B's border is then outside A, which the Boolean takes. The result is the same bytes
// when no two shells of what is left overlap near A (one group); otherwise the same solid, the
// passes grouping the pieces left of a shell one by one (the design's crop of the jaws: the
// design goldens and the real dentition's splints kept their bytes). Reads A's vertices only.
Aabb boolean_region(const Mesh& a, const BooleanOptions& options);

}  // namespace splintcore

#endif  // SPLINTCORE_BOOLEAN_H
