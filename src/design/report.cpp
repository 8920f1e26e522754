// The audit report of a design (design.h, write_design_report): what an auditor needs to
// reproduce the run, every value from a recorded result. One writer serves the command line
// (report.json) and the C API (sc_design_write_report), so both give the same bytes.
#include "design/case_json.h"
#include "splintcore/blockout.h"
#include "splintcore/boolean.h"
#include "splintcore/design.h"
#include "splintcore/io.h"
#include "splintcore/json.h"

namespace splintcore {

uint32_t exact_blockout_jaws(const DesignReport& report) {
  uint32_t exact = 0;
  for (uint32_t i = 0; i < report.blockout_jaws && i < DesignReport::kMaxBlockoutJaws; ++i)
    exact += report.blockout_exact[i] ? 1u : 0u;
  return exact;
}

using design_detail::write_plan;
using design_detail::write_transform;

namespace {

// A sink that only hashes what it is given (the splint's STL bytes).
bool hash_write(void* user, const uint8_t* data, size_t bytes) {
  static_cast<Sha256*>(user)->update(data, bytes);
  return true;
}

const char* at(Span<const char* const> list, size_t i) {
  return i < list.size() ? list[i] : nullptr;
}

void write_inputs(JsonWriter& w, const CaseFile& c, Span<const Mesh> jaws,
                  const DesignReportFiles& files) {
  w.begin_array("inputs");
  for (size_t i = 0; i < c.jaws.size(); ++i) {
    const CaseJaw& jaw = c.jaws[i];
    w.begin_object();
    w.add("role", jaw.role);
    if (jaw.has_seed) {
      // From CT: the hash is of the voxels as read (int16 HU, memory order).
      if (files.ct_path != nullptr) w.add("ct", files.ct_path);
      if (at(files.jaw_sha256, i) != nullptr) w.add("ct_voxels_sha256", at(files.jaw_sha256, i));
      w.add("seed", jaw.seed);
      if (files.ct != nullptr) {
        w.add("region_voxels", files.ct->regions.voxels[i + 1]);
        w.add("reconstructed_volume_mm3", files.ct->volume_mm3[i]);
      }
    } else {
      if (at(files.jaw_paths, i) != nullptr) w.add("mesh", at(files.jaw_paths, i));
      if (at(files.jaw_sha256, i) != nullptr) w.add("sha256", at(files.jaw_sha256, i));
    }
    w.add("triangles", static_cast<uint64_t>(jaws[i].triangles.size()));
    write_transform(w, jaw.transform);
    w.end_object();
  }
  w.end_array();
}

// Scan-CT fusion ("fusion"): per jaw with a scan, the case's thresholds and the registration.
void write_fusion(JsonWriter& w, const CaseFile& c, const DesignReport& report,
                  const DesignReportFiles& files) {
  w.begin_array("fusion");
  for (size_t i = 0; i < c.jaws.size() && i < DesignReport::kMaxFusedJaws; ++i) {
    if (!report.fused[i]) continue;
    const CaseScan& sc = c.jaws[i].scan;
    const FusionReport& f = report.fusion[i];
    const RegisterResult& r = f.registration;
    w.begin_object();
    w.add("role", c.jaws[i].role);
    w.add("scan", at(files.scan_paths, i) != nullptr ? at(files.scan_paths, i) : sc.path);
    if (at(files.scan_sha256, i) != nullptr) w.add("scan_sha256", at(files.scan_sha256, i));
    w.add("scan_triangles", f.scan_triangles);
    w.add("start", sc.landmarks.empty() ? "automatic" : "landmarks");
    w.add("landmarks", static_cast<uint64_t>(sc.landmarks.size()));
    if (!sc.landmarks.empty()) w.add("landmark_rms_mm", r.landmark_rms_mm);
    w.add("trim", sc.trim);
    w.add("min_overlap", sc.min_overlap);
    w.add("max_rms_mm", sc.max_rms_mm);
    w.add("crowns_within_mm", sc.crowns_within_mm);
    write_transform(w, r.transform);  // scan -> the jaw's mesh
    write_transform(w, f.applied, "applied_transform");
    w.add("rms_mm", r.rms_mm);
    w.add("overlap", r.overlap);
    w.add("iterations", r.iterations);
    w.add("converged", r.converged);
    w.add("samples", r.samples);
    w.add("kept", r.kept);
    w.add("imprint", "scan triangles");
    w.end_object();
  }
  w.end_array();
}

void write_parameters(JsonWriter& w, const CaseFile& c, const DesignReport& report,
                      const DesignReportFiles& files, bool any_ct) {
  w.begin_object("parameters");
  w.add("occlusal_normal", c.occlusal_normal);
  w.add("spacing_mm", c.base.spacing_mm);
  w.add("corner_radius_mm", c.base.corner_radius_mm);
  w.add("corner_segments", c.base.corner_segments);
  w.add("upper_picks", static_cast<uint64_t>(c.upper.size()));
  w.add("lower_picks", static_cast<uint64_t>(c.lower.size()));
  w.add("printer", report.printer);
  w.add("boolean_float32_output", BooleanOptions{}.float32_output);
  w.add("boolean_max_nudges", BooleanOptions{}.max_nudges);
  if (c.has_insertion_direction) w.add("insertion_direction", c.insertion_direction);
  if (any_ct) {
    w.add("ct_hu_min", static_cast<int64_t>(c.ct_window.lo));
    w.add("ct_hu_max", static_cast<int64_t>(c.ct_window.hi));
    w.add("ct_connectivity", c.ct_grow.connectivity == Connectivity::k26 ? 26 : 6);
    w.add("ct_smooth", c.ct_smooth.iterations);
    w.add("ct_decimate", c.ct_decimate.target_triangles);
    w.begin_array("ct_size");
    for (uint32_t n : files.ct_size) w.add(nullptr, n);
    w.end_array();
  }
  if (c.has_blockout) w.add("blockout_method", blockout_method_name(c.blockout_method));
  if (c.has_blockout && c.blockout_method == BlockoutMethod::kHeightfield) {
    w.add("blockout_voxel_mm", c.blockout.voxel);
    w.add("clearance_mm", c.blockout.offset);
  } else if (c.has_blockout && c.blockout_method == BlockoutMethod::kAuto) {
    w.add("blockout_voxel_mm", c.blockout.voxel);  // the fallback's grid
  } else if (c.has_blockout && c.blockout_method == BlockoutMethod::kVoxel) {
    w.add("blockout_voxel_mm", c.blockout.voxel);
    w.add("blockout_inset_mm", c.blockout.inset);
    w.add("blockout_closing_radius_mm", c.blockout.closing_radius);
    w.add("clearance_mm", c.blockout.offset);
  }
  if (c.min_thickness > 0) w.add("min_thickness_mm", c.min_thickness);
  if (c.has_label) {
    w.add("label_text", c.label.text);
    w.add("label_mode", c.label.mode == LabelMode::kEmboss ? "emboss" : "engrave");
    w.add("label_height_mm", c.label.height_mm);
    w.add("label_stroke_mm", c.label.stroke_width_mm);
    w.add("label_depth_mm", c.label.depth_mm);
  }
  w.add("placement", c.place_on_tray ? "tray" : "case");
  w.end_object();
}

// One jaw's exact blockout (the object is open; this closes it).
void write_exact_blockout(JsonWriter& w, const BlockoutStats& b, double removed_mm3) {
  const ExactSweepStats& e = b.exact;
  w.add("method", "exact");
  w.add("direction", e.direction);
  w.add("shells_checked", e.shells);
  w.add("shells_crossing_only_outside_splint", e.shells_crossing_outside);
  w.add("front_triangles", e.front_triangles);
  w.add("kept_front_triangles", e.kept_triangles);
  w.add("walls", e.walls);
  w.add("fold_vertices", e.fold_vertices);
  w.add("back_triangles_taken_in", e.absorbed_triangles);
  w.add("fold_rounds", e.fold_rounds);
  w.add("fold_pockets_clear_of_splint", e.pockets_clear);
  w.add("swept_triangles", b.swept_triangles);
  w.add("passes", b.boolean.passes);
  w.add("intersecting_pairs", b.boolean.intersecting_pairs);
  w.add("nudge_mm", b.boolean.nudge_sum);
  w.add("removed_volume_mm3", removed_mm3);
  w.end_object();
}

void write_heightfield_blockout(JsonWriter& w, const BlockoutStats& b, double removed_mm3) {
  const HeightfieldStats& h = b.heightfield;
  w.add("method", "heightfield");
  w.add("direction", h.axis_w);
  w.begin_array("grid_cells");
  w.add(nullptr, h.cells_u);
  w.add(nullptr, h.cells_v);
  w.end_array();
  w.add("grid_square_cells", h.square_cells);
  w.add("front_triangles", h.triangles_in);
  w.add("clearance_pieces", h.offset_pieces);
  w.add("covered_grid_vertices", h.covered_vertices);
  w.add("clipped_pairs", h.clipped_pairs);
  w.add("lowered_grid_vertices", h.lowered_vertices);
  w.add("max_lowering_mm", h.max_lowering);
  w.add("swept_triangles", b.swept_triangles);
  w.add("intersecting_pairs", b.boolean.intersecting_pairs);
  w.add("attempts", b.attempts);
  w.add("lowered_mm", b.inset_used);
  w.add("clearance_used_mm", b.offset_used);
  w.add("nudge_mm", b.boolean.nudge_sum);
  w.add("removed_volume_mm3", removed_mm3);
  w.end_object();
}

void write_blockout(JsonWriter& w, const CaseFile& c, const DesignReport& report) {
  // Interference elimination, per jaw in case order.
  w.begin_array("blockout");
  for (uint32_t i = 0; i < report.blockout_jaws; ++i) {
    const BlockoutStats& b = report.blockout[i];
    w.begin_object();
    w.add("role", c.jaws[i].role);
    if (report.blockout_exact[i]) {
      write_exact_blockout(w, b, report.blockout_removed_mm3[i]);
      continue;
    }
    if (report.imprint_heightfield || report.blockout_heightfield[i]) {
      write_heightfield_blockout(w, b, report.blockout_removed_mm3[i]);
      continue;
    }
    w.add("method", "voxel");
    w.add("direction", b.sweep.axis_w);
    w.begin_array("grid");
    w.add(nullptr, b.sweep.nx);
    w.add(nullptr, b.sweep.ny);
    w.add(nullptr, b.sweep.nz);
    w.end_array();
    w.add("swept_triangles", b.swept_triangles);
    w.add("intersecting_pairs", b.boolean.intersecting_pairs);
    w.add("attempts", b.attempts);
    w.add("inset_mm", b.inset_used);
    if (report.imprint_offset) w.add("clearance_mm", b.offset_used);
    w.add("nudge_mm", b.boolean.nudge_sum);
    w.add("removed_volume_mm3", report.blockout_removed_mm3[i]);
    w.end_object();
  }
  w.end_array();
}

// The automatic outline: what it found and how it moved the mandible.
void write_outline(JsonWriter& w, const OutlineReport& o, const DesignReportFiles& files) {
  w.begin_object("outline");
  if (files.resolved_case_path != nullptr) w.add("resolved_case", files.resolved_case_path);
  w.add("occlusal_normal", o.occlusal_normal);
  w.add("anterior", o.anterior);
  w.add("gap_as_given_mm", o.gap_as_given);
  w.add("jaws_intersect_as_given", o.jaws_intersect);
  w.add("bite_opened", o.opened);
  if (o.opened) {
    w.add("mandible_translation_mm", o.mandible_translation);
    w.add("opening_steps", o.opening_steps);
  }
  w.add("opening_mm", o.opening);
  w.add("picks_per_jaw", o.picks);
  w.add("arch_length_mm", o.arch_length_mm);
  w.add("wafer_min_mm", o.min_wafer_mm);
  w.add("wafer_max_mm", o.max_wafer_mm);
  w.add("occlusal_columns_maxilla", o.cells_upper);
  w.add("occlusal_columns_mandible", o.cells_lower);
  w.add("insertion_direction", o.insertion_direction);
  w.add("surveyed", o.surveyed);
  if (o.surveyed) {
    w.add("survey_directions", o.survey_directions);
    w.add("undercut_occlusal_normal_mm3", o.undercut_plain_mm3);
    w.add("undercut_chosen_mm3", o.undercut_chosen_mm3);
  }
  if (o.distal_limited) {  // as given, so the key is absent without the case's distal ends
    w.begin_array("distal_ends");
    for (int i = 0; i < 2; ++i) {
      w.begin_object();
      w.add("offset_mm", o.distal_offset_mm[i]);
      w.add("cut_mm", o.distal_cut_mm[i]);
      w.end_object();
    }
    w.end_array();
  }
  w.end_object();
}

void write_thickness(JsonWriter& w, const ThicknessReport& t) {
  w.begin_object("thickness");
  w.add("min_required_mm", t.min_required);
  w.add("triangles_checked", t.triangles_checked);
  w.add("thin_triangles", t.thin_triangles);
  w.add("thin_area_mm2", t.thin_area_mm2);
  w.add("thinnest_mm", t.thinnest);
  w.begin_array("thin_spots");
  for (uint32_t i = 0; i < t.spot_count; ++i) {
    w.begin_object();
    w.add("position", t.spots[i].position);
    w.add("thickness_mm", t.spots[i].thickness);
    w.add("triangle", t.spots[i].triangle);
    w.end_object();
  }
  w.end_array();
  w.end_object();
}

void write_side_walls(JsonWriter& w, const CaseFile& c, const DesignReport& report) {
  w.begin_object("side_walls");
  w.add("max_wall_crossing", c.max_wall_crossing);
  w.add("max_sideways_crossing", c.max_sideways_crossing);
  w.begin_array("jaws");
  for (uint32_t j = 0; j < report.wall_jaws && j < c.jaws.size(); ++j) {
    const WallCrossing& x = report.walls[j];
    w.begin_object();
    w.add("jaw", j);
    w.add("role", c.jaws[j].role);
    w.add("arch_mm", x.arch_mm);
    w.add("outer_mm", x.outer_mm);
    w.add("inner_mm", x.inner_mm);
    w.add("either_mm", x.either_mm);
    w.add("share", x.share());
    w.begin_array("halves");  // the arch's two halves in section order
    for (int h = 0; h < 2; ++h) {
      w.begin_object();
      w.add("outer_mm", x.half_outer_mm[h]);
      w.add("inner_mm", x.half_inner_mm[h]);
      w.end_object();
    }
    w.end_array();
    w.add("sideways_mm", x.sideways_mm());
    w.add("sideways_share", x.sideways_share());
    w.add("stretches", x.stretches);
    w.add("crossed", x.crossed);
    if (x.crossed > 0) w.add("first_at", x.first_at);
    w.end_object();
  }
  w.end_array();
  w.end_object();
}

void write_checks(JsonWriter& w, const CaseFile& c, const DesignReport& report) {
  w.begin_object("checks");
  w.add("base_sections", report.base.sections);
  w.add("base_triangles_self_intersection_candidates", report.base.self_intersection_candidates);
  w.add("boolean_intersecting_pairs", report.boolean.intersecting_pairs);
  w.add("boolean_degenerate_pairs", report.boolean.degenerate_pairs);
  w.add("boolean_intersection_points", report.boolean.intersection_points);
  w.add("boolean_attempts", report.boolean.attempts);
  w.add("boolean_nudge_mm", report.boolean.nudge);
  const uint32_t exact_jaws = exact_blockout_jaws(report);
  if (report.blockout_jaws > 0) {
    w.add("blockout_method_used", report.imprint_heightfield           ? "heightfield"
                                  : exact_jaws == report.blockout_jaws ? "exact"
                                  : exact_jaws == 0                    ? "voxel"
                                                                       : "exact and heightfield");
    if (report.blockout_fallback[0] != '\0') w.add("blockout_fallback", report.blockout_fallback);
    write_blockout(w, c, report);
  }
  w.add("imprint", report.imprint_heightfield && report.imprint_offset
                       ? "height field of the swept volume's clearance offset"
                   : report.imprint_heightfield ? "height field of the swept volume"
                   : report.imprint_offset      ? "clearance offset of the swept volume"
                   : !report.imprint_swept      ? "jaw triangles"
                   : exact_jaws == report.blockout_jaws
                       ? "exact swept volume (jaw front triangles and walls)"
                       : "exact swept volume (jaw front triangles and walls); height field of "
                         "the swept volume where a jaw's exact sweep stopped");
  if (report.labelled) {
    const LabelStats& l = report.label;
    w.begin_object("label");
    w.add("text", l.text);
    w.add("glyphs", l.glyphs);
    w.add("glyph_triangles", l.glyph_triangles);
    w.add("text_length_mm", l.text_length_mm);
    w.add("attempts", l.attempts);
    if (l.glyphs > 0) w.add("first_glyph_at", l.placements[0].surface_point);
    w.end_object();
  }
  write_side_walls(w, c, report);
  if (report.thickness_checked) write_thickness(w, report.thickness);
  w.add("self_intersection_free", report.self_intersection_checked);
  w.add("self_intersection_checked_by", report.self_intersection_checked_by);
  w.add("self_intersection_candidates", report.self_intersection_candidates);
  w.add("closed", report.print.mesh.closed());
  w.add("edge_manifold", report.print.mesh.edge_manifold());
  w.add("outward", report.print.mesh.outward());
  w.add("shells", report.print.mesh.shells);
  w.add("crumbs_removed", report.crumbs.removed);
  w.add("crumbs_volume_mm3", report.crumbs.volume_mm3);
  w.add("fits_tray", report.print.fits);
  w.add("fits_tray_rotated", report.print.fits_rotated);
  w.add("layers", report.print.layers);
  w.add("printable", report.print.printable);
  w.add("placed_on_tray", report.placed_on_tray);
  if (report.placed_on_tray) w.add("tray_translation_mm", report.tray_translation);
  w.end_object();
}

void write_run(JsonWriter& w, const DesignRunInfo& run) {
  w.begin_object("run");
  w.add("memory_cap_bytes", run.memory_cap_bytes);
  w.add("memory_cap_from", run.memory_cap_from);
  w.add("threads", run.threads);
  w.begin_array("stages");
  for (const DesignStageTime& s : run.stages) {
    w.begin_object();
    w.add("stage", s.stage);
    w.add("time_s", s.seconds);
    w.add("peak_arena_bytes", s.peak_arena_bytes);
    w.end_object();
  }
  w.end_array();
  w.add("read_s", run.read_seconds);
  w.add("design_s", run.design_seconds);
  w.add("preview_s", run.preview_seconds);
  w.add("time_s", run.total_seconds);
  w.add("peak_arena_bytes", run.peak_arena_bytes);
  w.end_object();
}

// The splint's SHA-256: of the bytes write_stl gives, which is what a caller writes (the
// caller's when `files` has it).
Status splint_sha256_of(const Context& ctx, const Mesh& splint, const DesignReportFiles& files,
                        char out[65]) {
  if (files.splint_sha256 != nullptr) {
    for (int i = 0; i < 64 && files.splint_sha256[i] != '\0'; ++i) out[i] = files.splint_sha256[i];
    return Status::ok();
  }
  return splint_stl_sha256(ctx, splint, out);
}

// The members of one splint's report after the case's name and hash: the inputs, the
// parameters, the outline, the checks, the output.
void write_splint_members(JsonWriter& w, const CaseFile& c, Span<const Mesh> jaws,
                          const Mesh& splint, const DesignReport& report,
                          const DesignReportFiles& files, const char* splint_sha256) {
  bool any_ct = false;
  for (const CaseJaw& j : c.jaws) any_ct = any_ct || j.has_seed;
  bool any_scan = false;
  for (const CaseJaw& j : c.jaws) any_scan = any_scan || j.has_scan;
  write_inputs(w, c, jaws, files);
  if (any_scan) write_fusion(w, c, report, files);
  write_parameters(w, c, report, files, any_ct);
  if (report.outlined) write_outline(w, report.outline, files);
  write_checks(w, c, report);
  w.begin_object("output");
  if (files.splint_path != nullptr) w.add("splint", files.splint_path);
  w.add("splint_sha256", splint_sha256);
  if (files.preview_path != nullptr) w.add("preview", files.preview_path);
  if (files.preview_sha256 != nullptr) w.add("preview_sha256", files.preview_sha256);
  if (files.preview_error != nullptr) w.add("preview_error", files.preview_error);
  w.add("triangles", static_cast<uint64_t>(splint.triangles.size()));
  w.add("volume_mm3", report.print.mesh.volume);
  w.add("extent_mm", report.print.extent);
  w.end_object();
}

void write_case_head(JsonWriter& w, const CaseFile& c, const DesignReportFiles& files) {
  w.add("command", "design");
  w.add("status", "ok");
  w.add("library_version", library_version());
  if (files.case_path != nullptr) w.add("case", files.case_path);
  w.add("case_id", c.case_id);
  w.add("case_sha256", c.sha256);
}

// One splint of the plan: its moves as applied, the autorotation, then the single splint's
// members (of the case it was designed from).
void write_plan_splint(JsonWriter& w, const char* key, const CaseFile& derived,
                       Span<const Mesh> jaws, const Mesh& splint, const PlanSplintReport& r,
                       const DesignReportFiles& files, const char* splint_sha256) {
  const AutorotateReport& a = r.autorotation;
  w.begin_object(key);
  write_transform(w, r.maxilla, "maxilla_transform");
  write_transform(w, r.mandible, "mandible_transform");
  w.begin_object("autorotation");
  w.add("angle_rad", a.angle_rad);
  w.add("angle_deg", r.angle_deg);
  write_transform(w, a.transform, "transform");
  w.add("closing_sign", static_cast<int64_t>(a.closing_sign));
  w.add("opening_asked_mm", r.opening_asked_mm);
  w.add("opening_mm", a.opening);
  w.add("gap_as_given_mm", a.gap_as_given);
  w.add("met_as_given", a.met_as_given);
  w.add("start_angle_rad", a.start_angle_rad);
  w.add("bracket_rad", a.bracket_rad);
  w.add("lever_mm", a.lever_mm);
  w.add("steps", static_cast<uint64_t>(a.steps));
  w.add("contact_maxilla", a.contact_maxilla);
  w.add("contact_mandible", a.contact_mandible);
  w.end_object();
  write_splint_members(w, derived, jaws, splint, r.design, files, splint_sha256);
  w.end_object();
}

}  // namespace

Status splint_stl_sha256(const Context& ctx, const Mesh& splint, char out[65]) {
  Sha256 hash;
  ByteSink hashing;
  hashing.write = &hash_write;
  hashing.user = &hash;
  hashing.name = "the splint's hash";
  SPLINTCORE_RETURN_IF_ERROR(write_stl(ctx, splint, hashing, StlWriteOptions{}));
  uint8_t digest[32];
  hash.finish(digest);
  Sha256::to_hex(digest, out);
  return Status::ok();
}

namespace {

// The print job written (3MF), when there is one.
void write_print_job(JsonWriter& w, const DesignReportFiles& files) {
  if (files.print_job_path == nullptr) return;
  w.begin_object("print_job");
  w.add("path", files.print_job_path);
  if (files.print_job_sha256 != nullptr) w.add("sha256", files.print_job_sha256);
  w.end_object();
}

}  // namespace

Status write_design_report(const Context& ctx, const CaseFile& c, Span<const Mesh> jaws,
                           const Mesh& splint, const DesignReport& report,
                           const DesignReportFiles& files, const DesignRunInfo* run,
                           const ByteSink& sink) {
  if (jaws.size() != c.jaws.size()) {
    return make_error(StatusCode::kInvalidArgument, "design report: ", jaws.size(),
                      " jaws for a case of ", c.jaws.size());
  }
  char splint_sha256[65] = {};
  SPLINTCORE_RETURN_IF_ERROR(splint_sha256_of(ctx, splint, files, splint_sha256));
  JsonWriter w(sink);
  w.begin_object();
  write_case_head(w, c, files);
  write_splint_members(w, c, jaws, splint, report, files, splint_sha256);
  write_print_job(w, files);
  if (run != nullptr) write_run(w, *run);
  w.end_object();
  return w.finish();
}

Status write_plan_report(const Context& ctx, const CaseFile& c, Span<const Mesh> jaws,
                         const Mesh& intermediate, const Mesh& final_splint,
                         const PlanReport& report, const DesignReportFiles files[2],
                         const DesignRunInfo* run, const ByteSink& sink) {
  if (!c.has_plan || jaws.size() != c.jaws.size()) {
    return Status::error(StatusCode::kInvalidArgument,
                         "plan report: not a plan case, or the jaws do not match it");
  }
  // Everything that can fail before the first byte: the derived cases and the hashes.
  CaseJaw jaws_of[2][2];
  CaseFile derived[2];
  const PlanSplintReport* parts[2] = {&report.intermediate, &report.final_splint};
  const Mesh* splints[2] = {&intermediate, &final_splint};
  char sha256[2][65] = {};
  for (int k = 0; k < 2; ++k) {
    SPLINTCORE_RETURN_IF_ERROR(plan_splint_case(c, *parts[k], k == 1, jaws_of[k], &derived[k]));
    SPLINTCORE_RETURN_IF_ERROR(splint_sha256_of(ctx, *splints[k], files[k], sha256[k]));
  }
  JsonWriter w(sink);
  w.begin_object();
  write_case_head(w, c, files[0]);
  write_plan(w, c.plan);
  static const char* const kKeys[2] = {"intermediate", "final"};
  for (int k = 0; k < 2; ++k) {
    write_plan_splint(w, kKeys[k], derived[k], jaws, *splints[k], *parts[k], files[k], sha256[k]);
  }
  write_print_job(w, files[0]);
  if (run != nullptr) write_run(w, *run);
  w.end_object();
  return w.finish();
}

}  // namespace splintcore
