// Jaws from the case's CT (Chen et al. 2016, "Preprocessing"): threshold, competitive region
// growing from each CT jaw's seed, reconstruction of each region, optional smoothing and
// decimation, float32; the meshes are then what design_splint() takes.
#include <cstring>

#include "splintcore/design.h"
#include "splintcore/remesh.h"

namespace splintcore {

Status reconstruct_case_jaws(const Context& ctx, const CaseFile& c, const CtVolume& volume,
                             Span<Mesh> jaws, CaseCtReport* report) {
  SPLINTCORE_ASSERT(ctx.arena != nullptr && report != nullptr);
  *report = CaseCtReport{};
  Arena& arena = *ctx.arena;
  if (jaws.size() != c.jaws.size()) {
    return make_error(StatusCode::kInvalidArgument, "ct jaws: the case names ", c.jaws.size(),
                      " jaws but ", jaws.size(), " meshes were given");
  }
  if (c.jaws.size() > CaseCtReport::kMaxJaws) {
    return make_error(StatusCode::kLimitExceeded, "ct jaws: at most ", CaseCtReport::kMaxJaws,
                      " jaws");
  }
  RegionSeed seeds[CaseCtReport::kMaxJaws];
  uint32_t seed_count = 0;
  for (size_t j = 0; j < c.jaws.size(); ++j) {
    if (!c.jaws[j].has_seed) continue;
    if (!jaws[j].vertices.empty() || !jaws[j].triangles.empty()) {
      return make_error(StatusCode::kInvalidArgument, "ct jaws: the mesh for jaw ", j,
                        " must be empty (it is reconstructed)");
    }
    seeds[seed_count].label = static_cast<uint8_t>(j + 1);
    seeds[seed_count].in_patient_mm = true;
    seeds[seed_count].patient_mm = c.jaws[j].seed;
    ++seed_count;
  }
  if (seed_count == 0) return Status::ok();
  const Arena::Marker start = arena.mark();
  auto fail = [&](const Status& s, const char* stage) {
    arena.rewind(start);
    for (size_t j = 0; j < jaws.size(); ++j) {
      if (c.jaws[j].has_seed) jaws[j] = Mesh();
    }
    if (s.code() == StatusCode::kArenaExhausted || s.code() == StatusCode::kCancelled) return s;
    Status e = make_error(s.code(), "ct: ", stage, ": ", s.message());
    if (s.index() != kNoPosition) e.at_index(s.index());
    return e;
  };
  LabelVolume labels;
  Status s = threshold_window(ctx, volume, c.ct_window, &labels, &report->threshold);
  if (!s.is_ok()) return fail(s, "threshold");
  RegionGrowOptions go;
  go.connectivity = c.ct_connectivity == 26 ? Connectivity::k26 : Connectivity::k6;
  s = grow_regions(ctx, volume, Span<const RegionSeed>(seeds, seed_count), go, &labels,
                   &report->regions);
  if (!s.is_ok()) return fail(s, "region growing");
  const double h =
      volume.spacing.x < volume.spacing.y
          ? (volume.spacing.x < volume.spacing.z ? volume.spacing.x : volume.spacing.z)
          : (volume.spacing.y < volume.spacing.z ? volume.spacing.y : volume.spacing.z);
  bool vertices_first[CaseCtReport::kMaxJaws] = {};
  for (size_t j = 0; j < c.jaws.size(); ++j) {
    if (!c.jaws[j].has_seed) continue;
    ReconstructOptions ro;
    ro.label = static_cast<uint8_t>(j + 1);
    ro.hu_lo = c.ct_window.lo;
    ro.round_to_float32 = c.ct_smooth == 0 && c.ct_decimate == 0;
    Mesh mesh(&arena);
    s = reconstruct_region(ctx, volume, labels, ro, &mesh, &report->jaws[j]);
    if (!s.is_ok()) return fail(s, "reconstruct");
    vertices_first[j] = true;  // as the extractor leaves a mesh
    if (c.ct_smooth > 0) {
      TaubinOptions to;
      to.iterations = c.ct_smooth;
      to.max_displacement = 0.5 * h;
      s = taubin_smooth(ctx, &mesh, to, nullptr);
      if (!s.is_ok()) return fail(s, "smooth");
    }
    if (c.ct_decimate > 0 && mesh.triangles.size() > c.ct_decimate) {
      Mesh fewer(&arena);
      DecimateOptions dopt;
      dopt.target_triangles = c.ct_decimate;
      s = decimate_qem(ctx, mesh, dopt, &fewer, nullptr);
      if (!s.is_ok()) return fail(s, "decimate");
      mesh = fewer;
      vertices_first[j] = false;  // as move_mesh_down leaves it
    }
    if (!ro.round_to_float32) {
      for (size_t i = 0; i < mesh.vertices.size(); ++i) {
        if (!round_to_float32(&mesh.vertices[i])) {
          return fail(make_error(StatusCode::kNonFinite, "a vertex is beyond float32").at_index(i),
                      "reconstruct");
        }
      }
    }
    double volume_mm3 = 0;
    s = check_closed_oriented(ctx, mesh, &volume_mm3);
    if (!s.is_ok()) return fail(s, "reconstructed jaw check");
    report->volume_mm3[j] = volume_mm3;
    report->triangles[j] = mesh.triangles.size();
    jaws[j] = mesh;
  }
  // Only the meshes stay: each moved down in turn over the labels and the temporaries (each
  // destination lies below its source; move_mesh_down copies the first-allocated array first).
  Arena::Marker to = start;
  for (size_t j = 0; j < jaws.size(); ++j) {
    if (!c.jaws[j].has_seed) continue;
    const Mesh src = jaws[j];
    move_mesh_down(arena, to, src, &jaws[j], vertices_first[j]);
    to = arena.mark();
  }
  report->jaws_reconstructed = seed_count;
  return Status::ok();
}

}  // namespace splintcore
