// splintcore segment: CT segmentation (HU window), competitive region growing that separates the
// maxilla from the mandible, and surface reconstruction of each region with the library's one
// iso-surface extractor (volume.h).
//
// Pipeline (Chen et al. 2016, section 2.1 "preprocessing"): threshold_window() marks the voxels
// whose HU lie in a bone window; grow_regions() labels the marked voxels reachable from seed
// points, each voxel going to the seed it is closest to (in voxel steps); reconstruct_region()
// extracts one closed, manifold, outward mesh per label, in patient coordinates.
//
// Label volumes. One byte per voxel, in the CtVolume's voxel order (x fastest, then y, then z):
//   0 (kLabelBackground)   outside the HU window;
//   255 (kLabelUnclaimed)  inside the window, not (yet) claimed by a region;
//   1..kMaxRegionLabel     a region.
// A byte rather than a bit per voxel: the labels need a byte anyway, and the growth rewrites
// the mask in place (a claimed voxel's 255 becomes its label), so a mask and its labels cost
// one byte per voxel together, where a bit mask plus a label byte would cost 1.125 and
// make every neighbour test a shift and a mask.
//
// Repositioning a jaw by the surgical plan is transform_mesh() (mesh.h) with a transform from
// rigid_from_matrix() (geometry.h): nothing here.
#ifndef SPLINTCORE_SEGMENT_H
#define SPLINTCORE_SEGMENT_H

#include "splintcore/core.h"
#include "splintcore/ct.h"
#include "splintcore/geometry.h"
#include "splintcore/mesh.h"
#include "splintcore/volume.h"

namespace splintcore {

constexpr uint8_t kLabelBackground = 0;
constexpr uint8_t kLabelUnclaimed = 255;
constexpr uint8_t kMaxRegionLabel = 15;  // labels 1..15 (stats arrays are sized by it)
constexpr uint32_t kMaxSeeds = 256;

// A label volume over a CtVolume's grid (same nx, ny, nz and voxel order).
struct LabelVolume {
  uint32_t nx = 0, ny = 0, nz = 0;
  uint8_t* labels = nullptr;  // nx * ny * nz bytes in the arena
  uint64_t voxel_count() const { return uint64_t{nx} * ny * nz; }
};

// ---------------------------------------------------------------------------------------------
// Threshold segmentation.

struct HuWindow {
  int32_t lo = 300;  // a voxel is in the window when lo <= HU <= hi
  int32_t hi = 4000;
};

struct ThresholdStats {
  uint64_t in_window = 0;  // voxels marked kLabelUnclaimed
};

// Arena bytes threshold_window() takes: the label volume, voxel_count bytes (plus alignment,
// at most 16). 0 when the count overflows.
uint64_t threshold_window_bound(const CtVolume& volume);

// Reads volume.hu; allocates out->labels (voxel_count bytes, from ctx.arena; kept) and writes
// kLabelUnclaimed where lo <= HU <= hi, else kLabelBackground. Progress: stage "threshold",
// once per 16 slices (done = slices). Errors: kInvalidArgument (empty volume, hu null,
// lo > hi), kArenaExhausted (names the bytes), kCancelled; on an error the arena's top is back
// where it was and *out is untouched.
Status threshold_window(const Context& ctx, const CtVolume& volume, const HuWindow& window,
                        LabelVolume* out, ThresholdStats* stats = nullptr);

// ---------------------------------------------------------------------------------------------
// Competitive region growing.
//
// The rule, exactly. Every region grows from its seeds at once, breadth-first, one FACE step
// per layer, through voxels that are kLabelUnclaimed (in the window) and allowed to it by the
// split plane (if any). A voxel goes to the region that reaches it in the fewest face steps
// (the city-block distance inside the window); when several reach it in the same step, the
// lowest label wins. (Implementation: one FIFO queue seeded with every seed, by label then in
// the order given; a voxel is claimed when first discovered. FIFO order keeps the layers in
// sequence and, within a layer, all voxels of label a before those of label b > a, so the
// claim is the rule above. No executor, no hashing: the labels are a function of the inputs.)
// With Connectivity::k26 a second pass follows: every claimed voxel, in queue order, claims
// the window voxels it touches through an edge or a corner, and those in turn (26-neighbour
// steps, breadth-first). The competition itself stays on face steps on purpose: with the
// 26-neighbour (chessboard) distance a step along the arch and a step towards the other jaw
// cost the same, so fronts running side by side tie over long stretches and the tie-break
// floods one jaw into the other (the phantom's back molars showed it).
// Where the teeth touch in the CT (the patient scanned in occlusion), the two regions meet
// half-way between the seeds' fronts: place each jaw's seed in its bone, about as far from
// the occlusal plane as the other's.
//
// Split plane (optional, for cases where the user knows better): label_positive may only
// claim voxels whose centre p (patient mm) has dot(normal, p - point) > 0, label_negative only
// the others; other labels are not restricted. The side is computed in double with a fixed
// order of operations (deterministic, not exact: a voxel within rounding of the plane may go
// either way, always the same way). Every seed must lie on its label's side.

enum class Connectivity : uint8_t { k6 = 6, k26 = 26 };

// A seed: a voxel index (i, j, k), or a point in patient mm (when `in_patient_mm`), rounded to
// the voxel whose centre is nearest in each axis of the volume's own frame.
struct RegionSeed {
  uint8_t label = 1;  // 1..kMaxRegionLabel
  bool in_patient_mm = true;
  Vec3 patient_mm{};
  uint32_t i = 0, j = 0, k = 0;
};

struct SplitPlane {
  Vec3 point{};
  Vec3 normal{0, 0, 1};  // need not be unit; must not be zero
  uint8_t label_negative = 1;
  uint8_t label_positive = 2;
};

struct RegionGrowOptions {
  Connectivity connectivity = Connectivity::k6;
  const SplitPlane* plane = nullptr;  // nullptr: no plane
};

struct RegionStats {
  uint64_t voxels[kMaxRegionLabel + 1] = {};  // voxels claimed per label
  // Per label: a claimed voxel lies on the volume's border (the region may continue beyond the
  // scan: a warning, not an error).
  bool touches_border[kMaxRegionLabel + 1] = {};
  // Per label: a claimed voxel is a neighbour of another region's voxel (the regions met: the
  // competition, or the plane, decided where one ends).
  bool meets_other_region[kMaxRegionLabel + 1] = {};
  uint64_t unclaimed = 0;    // window voxels no seed reached (left kLabelUnclaimed)
  uint32_t layers = 0;       // breadth-first layers (the largest distance in steps, + 1)
  uint64_t queue_bytes = 0;  // arena bytes the queue took
};

// Arena bytes grow_regions() takes at most when `in_window` voxels are marked: the FIFO, 4
// bytes per window voxel (each is queued at most once), plus 16 of alignment. It is returned
// before grow_regions() returns. 0 when the size overflows.
uint64_t grow_regions_bound(uint64_t in_window);

// Reads volume (geometry only: seeds and plane are mapped with its origin, axes and spacing)
// and labels (rewritten in place: claimed kLabelUnclaimed voxels get their label). Temporary
// arena: grow_regions_bound(number of kLabelUnclaimed voxels), returned before it finishes.
// Progress: stage "region growing", every 2^20 voxels claimed (done = claimed, total = window
// voxels); cancelling returns kCancelled (the labels are then partly written).
// Errors, each naming the seed (at_index: its position in `seeds`) and its voxel:
//   kInvalidArgument: no seeds, more than kMaxSeeds, a label outside 1..kMaxRegionLabel, a seed
//     outside the volume, a seed whose voxel is not in the window, two seeds of different labels
//     in one voxel, a seed on the wrong side of the plane, a zero or non-finite plane normal,
//     labels and volume of different sizes;
//   kInvalidArgument "region L grows no further than its seeds" (its seeds have no unclaimed
//     neighbour in the window: a seed in a speck of noise rather than in bone). (A region
//     cannot be empty: seeds claim their voxels before anything grows.)
//   kLimitExceeded: 2^32 or more voxels (the queue holds 32-bit voxel indices);
//   kArenaExhausted; kCancelled.
Status grow_regions(const Context& ctx, const CtVolume& volume, Span<const RegionSeed> seeds,
                    const RegionGrowOptions& options, LabelVolume* labels,
                    RegionStats* stats = nullptr);

// The voxel a seed stands for (what grow_regions uses). Errors: kInvalidArgument when it lies
// outside the volume or is not finite (names the seed's coordinates).
Status seed_voxel(const CtVolume& volume, const RegionSeed& seed, uint32_t* i, uint32_t* j,
                  uint32_t* k);

// ---------------------------------------------------------------------------------------------
// Surface reconstruction.
//
// The field handed to marching_cubes() for label L, per voxel v with g(v) = (lo - 0.5) - HU(v)
// (never 0: HU are integers):
//   field(v) = g(v)    when v has label L (g < 0: inside),
//   field(v) = |g(v)|  otherwise (outside).
// Next to background below the window this is the HU itself, so the surface interpolates
// between voxels where HU crosses lo - 0.5 (sub-voxel accurate, unlike the binary mask). Next
// to another label (teeth touching in occlusion) or to window voxels no seed claimed, the
// field is mirrored, so the surface passes where the two voxels' HU excess over the threshold
// balances: where two regions meet, both surfaces pass through the same points (they touch
// and do not overlap), except along the rim where that interface meets the background: there
// an edge from a region voxel to a background voxel may cross the interface, and the meshes
// overlap by up to about 0.4 voxel (less than 0.5% of the volume on the tests' blocks).
// Voxels above the window (metal) are outside.
// The extraction runs on the box of L's voxels grown by one voxel (clipped to the volume): the
// samples are streamed layer by layer from the HU and labels (no float copy of the volume).
// Vertices are mapped into patient coordinates with ct_to_patient() after extraction, then
// (optionally) rounded to float32; when the volume's axes form a left-handed frame (a mirror)
// every triangle's last two corners are swapped, so the mesh stays outward. A mesh of a region
// that touches the volume's border is closed just outside it (volume.h).

struct ReconstructOptions {
  uint8_t label = 1;
  int32_t hu_lo = 300;           // the window's lower bound used for segmentation
  uint32_t layers_per_tile = 0;  // for marching_cubes (0: its default); never changes output
  bool round_to_float32 = true;  // STL holds float32; the Boolean wants float32-exact jaws
};

struct ReconstructStats {
  uint32_t box_lo[3] = {0, 0, 0};  // the voxel box extracted (inclusive), per axis
  uint32_t box_hi[3] = {0, 0, 0};
  uint64_t region_voxels = 0;
  MarchingCubesStats marching{};
  // Vertices that became equal after float32 rounding would make degenerate triangles: a
  // float32-rounded mesh is checked (find_flat_triangle) and this counts the flat ones found
  // (0 or 1: the check stops at the first). Callers that need a solid check it anyway.
  uint32_t flat_after_rounding = 0;
};

// Arena bytes reconstruct_region() takes at its peak for a region whose box (ReconstructStats)
// has box_voxels[3] voxels per axis, with `layers` sample layers per slab (the working set of
// volume.h, at most kMarchingCubesDefaultLayers when left to it) and a result of V vertices and
// T triangles: marching_cubes_bound() + marching_cubes_mesh_extra_bound(V, T) (the mesh itself,
// 24 V + 12 T, stays). About 80 bytes per vertex plus 4 (layers + 1) + 40 bytes per voxel of
// the box's cross-section. 0 when a size overflows.
uint64_t reconstruct_region_bound(const uint32_t box_voxels[3], uint32_t layers,
                                  uint64_t vertex_count, uint64_t triangle_count);

// Reads volume (hu, geometry) and labels; appends nothing: `out` must be empty and bound to
// ctx.arena; on success it holds the mesh (vertex ids and triangle order as marching_cubes
// gives them), in patient mm. Arena: the mesh (kept) plus marching_cubes_mesh's peak (see
// volume.h, and reconstruct_region_bound); on an error the arena's top is back where it was
// and `out` is empty. Progress: stages "reconstruct: region box" (every 32 slices of the scan
// for the region's box), "marching cubes" (marching_cubes'), then "reconstruct: patient
// coordinates" once; cancelling returns kCancelled. Errors: kInvalidArgument (label outside
// 1..kMaxRegionLabel, labels and volume of different sizes, no voxel with the label: "region
// L is empty"), kNonFinite (a vertex beyond float32's range), and those of
// marching_cubes_mesh (kArenaExhausted, kCancelled, ...).
Status reconstruct_region(const Context& ctx, const CtVolume& volume, const LabelVolume& labels,
                          const ReconstructOptions& options, Mesh* out,
                          ReconstructStats* stats = nullptr);

}  // namespace splintcore

#endif  // SPLINTCORE_SEGMENT_H
