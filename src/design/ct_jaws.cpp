// Jaws from the case's CT (Chen et al. 2016, "Preprocessing"): threshold, competitive region
// growing from each CT jaw's seed, reconstruction of each region, optional smoothing and
// decimation, float32; the meshes are then what design_splint() takes.
#include <cstring>

#include "splintcore/design.h"
#include "splintcore/remesh.h"

namespace splintcore {

namespace {

// A stage's error as reconstruct_case_jaws reports it ("ct: <stage>: ..."); running out of
// memory and a cancel pass as they are.
Status stage_error(const Status& s, const char* stage) {
  if (s.code() == StatusCode::kArenaExhausted || s.code() == StatusCode::kCancelled) return s;
  Status e = make_error(s.code(), "ct: ", stage, ": ", s.message());
  if (s.index() != kNoPosition) e.at_index(s.index());
  return e;
}

// The seeds of the jaws that have one (label j + 1 for jaw j), whose meshes must be empty.
Status collect_seeds(const CaseFile& c, Span<Mesh> jaws, RegionSeed* seeds, uint32_t* seed_count) {
  if (jaws.size() != c.jaws.size()) {
    return make_error(StatusCode::kInvalidArgument, "ct jaws: the case names ", c.jaws.size(),
                      " jaws but ", jaws.size(), " meshes were given");
  }
  if (c.jaws.size() > CaseCtReport::kMaxJaws) {
    return make_error(StatusCode::kLimitExceeded, "ct jaws: at most ", CaseCtReport::kMaxJaws,
                      " jaws");
  }
  for (size_t j = 0; j < c.jaws.size(); ++j) {
    if (!c.jaws[j].has_seed) continue;
    if (!jaws[j].vertices.empty() || !jaws[j].triangles.empty()) {
      return make_error(StatusCode::kInvalidArgument, "ct jaws: the mesh for jaw ", j,
                        " must be empty (it is reconstructed)");
    }
    RegionSeed& seed = seeds[*seed_count];
    seed.label = static_cast<uint8_t>(j + 1);
    seed.in_patient_mm = true;
    seed.patient_mm = c.jaws[j].seed;
    ++*seed_count;
  }
  return Status::ok();
}

// Jaw j out of the labelled volume: reconstructed, smoothed and decimated as the case asks,
// in float32, checked; *vertices_first says which of its arrays was allocated first.
Status reconstruct_jaw(const Context& ctx, const CaseFile& c, const CtVolume& volume,
                       const LabelVolume& labels, size_t j, Mesh* out, CaseCtReport* report,
                       bool* vertices_first) {
  Arena& arena = *ctx.arena;
  const double h =
      volume.spacing.x < volume.spacing.y
          ? (volume.spacing.x < volume.spacing.z ? volume.spacing.x : volume.spacing.z)
          : (volume.spacing.y < volume.spacing.z ? volume.spacing.y : volume.spacing.z);
  ReconstructOptions ro;
  ro.label = static_cast<uint8_t>(j + 1);
  ro.hu_lo = c.ct_window.lo;
  ro.round_to_float32 = c.ct_smooth.iterations == 0 && c.ct_decimate.target_triangles == 0;
  Mesh mesh(&arena);
  Status s = reconstruct_region(ctx, volume, labels, ro, &mesh, &report->jaws[j]);
  if (!s.is_ok()) return stage_error(s, "reconstruct");
  *vertices_first = true;  // as the extractor leaves a mesh
  if (c.ct_smooth.iterations > 0) {
    TaubinOptions to = c.ct_smooth;
    to.max_displacement = 0.5 * h;  // a CT surface may not drift by more than half a voxel
    s = taubin_smooth(ctx, &mesh, to, nullptr);
    if (!s.is_ok()) return stage_error(s, "smooth");
  }
  if (c.ct_decimate.target_triangles > 0 &&
      mesh.triangles.size() > c.ct_decimate.target_triangles) {
    Mesh fewer(&arena);
    s = decimate_qem(ctx, mesh, c.ct_decimate, &fewer, nullptr);
    if (!s.is_ok()) return stage_error(s, "decimate");
    mesh = fewer;
    *vertices_first = false;  // as move_mesh_down leaves it
  }
  if (!ro.round_to_float32) {
    for (size_t i = 0; i < mesh.vertices.size(); ++i) {
      if (!round_to_float32(&mesh.vertices[i])) {
        return stage_error(
            make_error(StatusCode::kNonFinite, "a vertex is beyond float32").at_index(i),
            "reconstruct");
      }
    }
  }
  double volume_mm3 = 0;
  s = check_closed_oriented(ctx, mesh, &volume_mm3);
  if (!s.is_ok()) return stage_error(s, "reconstructed jaw check");
  report->volume_mm3[j] = volume_mm3;
  report->triangles[j] = mesh.triangles.size();
  *out = mesh;
  return Status::ok();
}

// Threshold, region growing from the seeds, then every seeded jaw (above the labels).
Status reconstruct_seeded(const Context& ctx, const CaseFile& c, const CtVolume& volume,
                          Span<const RegionSeed> seeds, Span<Mesh> jaws, CaseCtReport* report,
                          bool* vertices_first) {
  LabelVolume labels;
  Status s = threshold_window(ctx, volume, c.ct_window, &labels, &report->threshold);
  if (!s.is_ok()) return stage_error(s, "threshold");
  s = grow_regions(ctx, volume, seeds, c.ct_grow, &labels, &report->regions);
  if (!s.is_ok()) return stage_error(s, "region growing");
  for (size_t j = 0; j < c.jaws.size(); ++j) {
    if (!c.jaws[j].has_seed) continue;
    SPLINTCORE_RETURN_IF_ERROR(
        reconstruct_jaw(ctx, c, volume, labels, j, &jaws[j], report, &vertices_first[j]));
  }
  return Status::ok();
}

}  // namespace

Status reconstruct_case_jaws(const Context& ctx, const CaseFile& c, const CtVolume& volume,
                             Span<Mesh> jaws, CaseCtReport* report) {
  SPLINTCORE_ASSERT(ctx.arena != nullptr && report != nullptr);
  *report = CaseCtReport{};
  Arena& arena = *ctx.arena;
  RegionSeed seeds[CaseCtReport::kMaxJaws];
  uint32_t seed_count = 0;
  SPLINTCORE_RETURN_IF_ERROR(collect_seeds(c, jaws, seeds, &seed_count));
  if (seed_count == 0) return Status::ok();
  ArenaScope scope(arena);  // on an error the arena is as it was and the jaws' meshes empty
  bool vertices_first[CaseCtReport::kMaxJaws] = {};
  const Status s = reconstruct_seeded(ctx, c, volume, Span<const RegionSeed>(seeds, seed_count),
                                      jaws, report, vertices_first);
  if (!s.is_ok()) {
    for (size_t j = 0; j < jaws.size(); ++j) {
      if (c.jaws[j].has_seed) jaws[j] = Mesh();
    }
    return s;
  }
  // Only the meshes stay: each moved down in turn over the labels and the temporaries (each
  // destination lies below its source; move_mesh_down copies the first-allocated array first).
  Arena::Marker to = scope.start();
  for (size_t j = 0; j < jaws.size(); ++j) {
    if (!c.jaws[j].has_seed) continue;
    const Mesh src = jaws[j];
    move_mesh_down(arena, to, src, &jaws[j], vertices_first[j]);
    to = arena.mark();
  }
  scope.commit();
  report->jaws_reconstructed = seed_count;
  return Status::ok();
}

}  // namespace splintcore
