// The automatic outline of a case (resolve_case_outline) and the case writer (write_case) that
// saves what it resolved as a case a person can read, edit and design again (design.h).
#include <cstring>

#include "design/b_vertex.h"
#include "design/case_json.h"
#include "design/fusion.h"
#include "design/no_jaw.h"
#include "splintcore/design.h"

namespace splintcore {

namespace design_detail {

void write_transform(JsonWriter& w, const RigidTransform& t, const char* key) {
  w.begin_array(key);
  const double row_t[3] = {t.t.x, t.t.y, t.t.z};
  for (int i = 0; i < 3; ++i) {
    for (int k = 0; k < 3; ++k) w.add(nullptr, t.r[i][k]);
    w.add(nullptr, row_t[i]);
  }
  for (int k = 0; k < 4; ++k) w.add(nullptr, k == 3 ? 1.0 : 0.0);
  w.end_array();
}

void write_scan(JsonWriter& w, const CaseScan& s) {
  w.begin_object("scan");
  w.add("path", s.path);
  if (!s.landmarks.empty()) {
    w.begin_array("landmarks");
    for (const LandmarkPair& l : s.landmarks) {
      w.begin_array();
      w.add(nullptr, l.scan);
      w.add(nullptr, l.ct);
      w.end_array();
    }
    w.end_array();
  }
  w.add("trim", s.trim);
  w.add("min_overlap", s.min_overlap);
  w.add("max_rms_mm", s.max_rms_mm);
  w.add("crowns_within_mm", s.crowns_within_mm);
  w.end_object();
}

void write_picks(JsonWriter& w, const char* key, Span<const Pick> picks) {
  w.begin_array(key);
  for (const Pick& p : picks) {
    w.begin_object();
    w.add("position", p.position);
    if (length(p.normal) > 0) w.add("normal", p.normal);
    if (length(p.direction) > 0) w.add("direction", p.direction);
    w.add("inner_length_mm", p.inner_length);
    w.add("outside_length_mm", p.outside_length);
    w.end_object();
  }
  w.end_array();
}

void write_plan(JsonWriter& w, const CasePlan& p) {
  w.begin_object("plan");
  w.add("sequence", p.mandible_first ? "mandible_first" : "maxilla_first");
  write_transform(w, p.maxilla, "maxilla");
  write_transform(w, p.mandible, "mandible");
  w.begin_array("hinge_axis");
  w.add(nullptr, p.hinge[0]);
  w.add(nullptr, p.hinge[1]);
  w.end_array();
  w.add("intermediate_opening_mm", p.intermediate_opening_mm);
  w.add("final_opening_mm", p.final_opening_mm);
  if (p.has_picks) {
    w.begin_object("picks");
    for (int k = 0; k < 2; ++k) {
      w.begin_object(k == 0 ? "intermediate" : "final");
      write_picks(w, "upper", p.upper[k]);
      write_picks(w, "lower", p.lower[k]);
      w.end_object();
    }
    w.end_object();
  }
  w.end_object();
}

}  // namespace design_detail

using design_detail::write_picks;
using design_detail::write_plan;
using design_detail::write_scan;
using design_detail::write_transform;

namespace {

// The jaw of `role` (its index), or an error when the case has none or several.
Status find_role(const CaseFile& c, const char* role, size_t* index) {
  size_t found = 0, count = 0;
  for (size_t j = 0; j < c.jaws.size(); ++j) {
    if (std::strcmp(c.jaws[j].role, role) != 0) continue;
    found = j;
    ++count;
  }
  if (count != 1) {
    return make_error(StatusCode::kInvalidArgument, "outline: the automatic outline needs one ",
                      role, " and one ", std::strcmp(role, "maxilla") == 0 ? "mandible" : "maxilla",
                      "; the case has ", count, " ", role, count == 1 ? "" : "s");
  }
  *index = found;
  return Status::ok();
}

// Jaws up and low where design_splint's B holds them (b_vertex): in chunks of vertices on the
// executor, each chunk noting its first vertex that is not finite or leaves float32's range; the
// first of those in jaw order (up, then low) is the error, as one loop over them would find it. The
// triangles are the jaws' own.
Status moved_jaws(const Context& ctx, const CaseFile& c, Span<const Mesh> jaws, size_t up,
                  size_t low, Mesh* maxilla, Mesh* mandible) {
  constexpr size_t kChunk = 65536;
  const size_t which[2] = {up, low};
  Mesh* out[2] = {maxilla, mandible};
  size_t first_chunk[3] = {0, 0, 0};  // jaw k's chunks are [first_chunk[k], first_chunk[k + 1])
  for (int k = 0; k < 2; ++k) {
    const Mesh& m = jaws[which[k]];
    out[k]->bind(ctx.arena);
    Vec3* to = ctx.arena->allocate_array<Vec3>(m.vertices.size());  // written by the tasks
    if (to == nullptr && !m.vertices.empty()) return ctx.arena->exhausted_status();
    out[k]->vertices.adopt(to, m.vertices.size(), m.vertices.size());
    first_chunk[k + 1] = first_chunk[k] + (m.vertices.size() + kChunk - 1) / kChunk;
  }
  struct Failure {
    size_t vertex = SIZE_MAX;  // the chunk's first bad vertex (SIZE_MAX: none)
    bool finite = true;        // it was finite (it left float32's range)
  };
  ArenaScope scope(*ctx.arena);
  Failure* failed = ctx.arena->allocate_array<Failure>(first_chunk[2] + 1);
  if (failed == nullptr) return ctx.arena->exhausted_status();
  for (size_t i = 0; i < first_chunk[2]; ++i) failed[i] = Failure{};
  auto task = [&](uint32_t chunk) {
    const int k = chunk < first_chunk[1] ? 0 : 1;
    const Mesh& m = jaws[which[k]];
    const size_t begin = (chunk - first_chunk[k]) * kChunk;
    const size_t end = m.vertices.size() - begin < kChunk ? m.vertices.size() : begin + kChunk;
    Vec3* to = out[k]->vertices.data();
    for (size_t v = begin; v < end; ++v) {
      const bool finite = is_finite(m.vertices[v]);
      if (!finite || !design_detail::b_vertex(c, jaws, which[k], v, &to[v])) {
        failed[chunk] = Failure{v, finite};
        return;
      }
    }
  };
  parallel_for_each(ctx.executor, static_cast<uint32_t>(first_chunk[2]), task);
  for (size_t chunk = 0; chunk < first_chunk[2]; ++chunk) {
    if (failed[chunk].vertex == SIZE_MAX) continue;
    const size_t j = which[chunk < first_chunk[1] ? 0 : 1];
    if (!failed[chunk].finite) {
      return make_error(StatusCode::kNonFinite, "outline: jaw ", j, " (", c.jaws[j].role,
                        ") has a vertex that is not finite (NaN or infinity)")
          .at_index(j);
    }
    return make_error(StatusCode::kLimitExceeded, "outline: jaw ", j, " (", c.jaws[j].role,
                      ") moved beyond float32 range")
        .at_index(j);
  }
  for (int k = 0; k < 2; ++k) {
    const Mesh& m = jaws[which[k]];
    out[k]->triangles.adopt(const_cast<Triangle*>(m.triangles.span().data()), m.triangles.size(),
                            m.triangles.size());
  }
  return Status::ok();
}

}  // namespace

Status resolve_case_outline(const Context& ctx, const CaseFile& c, Span<const Mesh> jaws,
                            CaseFile* resolved, Outline* outline) {
  // A jaw that is no jaw (a soup, a flat sheet, a file in other units) named as design names
  // it, before the outline makes something else of it ("the jaws do not face each other").
  if (c.has_auto_outline && jaws.size() == c.jaws.size()) {
    SPLINTCORE_RETURN_IF_ERROR(design_detail::refuse_no_jaw(ctx, c, jaws, Span<const Mesh>()));
  }
  return design_detail::resolve_case_outline_vetted(ctx, c, jaws, resolved, outline);
}

Status design_detail::resolve_case_outline_vetted(const Context& ctx, const CaseFile& c,
                                                  Span<const Mesh> jaws, CaseFile* resolved,
                                                  Outline* outline) {
  if (!c.has_auto_outline) {
    return Status::error(StatusCode::kInvalidArgument,
                         "outline: the case gives its picks (no \"auto\" in \"base\")");
  }
  if (jaws.size() != c.jaws.size()) {
    return make_error(StatusCode::kInvalidArgument, "outline: the case names ", c.jaws.size(),
                      " jaws but ", jaws.size(), " meshes were given");
  }
  size_t up = 0, low = 0;
  SPLINTCORE_RETURN_IF_ERROR(find_role(c, "maxilla", &up));
  SPLINTCORE_RETURN_IF_ERROR(find_role(c, "mandible", &low));
  Arena& arena = *ctx.arena;
  ArenaScope scope(arena);
  // The results' room first, below the moved jaws and the outline's work.
  Pick* upper = arena.allocate_array<Pick>(kMaxOutlinePicks);
  Pick* lower = arena.allocate_array<Pick>(kMaxOutlinePicks);
  Vec3* arch = arena.allocate_array<Vec3>(kMaxOutlineArchPoints);
  CaseJaw* case_jaws = arena.allocate_array<CaseJaw>(c.jaws.size());
  if (upper == nullptr || lower == nullptr || arch == nullptr || case_jaws == nullptr) {
    return arena.exhausted_status();
  }
  Outline o;
  {
    ArenaScope work(arena);
    Mesh maxilla, mandible;
    SPLINTCORE_RETURN_IF_ERROR(moved_jaws(ctx, c, jaws, up, low, &maxilla, &mandible));
    SPLINTCORE_RETURN_IF_ERROR(compute_outline(ctx, maxilla, mandible, c.outline, &o));
    for (size_t i = 0; i < o.upper.size(); ++i) {
      upper[i] = o.upper[i];
      lower[i] = o.lower[i];
    }
    for (size_t i = 0; i < o.arch.size(); ++i) arch[i] = o.arch[i];
  }
  *resolved = c;
  resolved->has_auto_outline = false;
  resolved->upper = Span<const Pick>(upper, o.upper.size());
  resolved->lower = Span<const Pick>(lower, o.lower.size());
  resolved->occlusal_normal = o.report.occlusal_normal;
  if (!c.has_insertion_direction) {
    resolved->insertion_direction = o.report.insertion_direction;
    resolved->has_insertion_direction = true;
  }
  for (size_t j = 0; j < c.jaws.size(); ++j) {
    case_jaws[j] = c.jaws[j];
    if (j == low && o.report.opened) {
      case_jaws[j].transform =
          compose(RigidTransform::translation(o.report.mandible_translation), c.jaws[j].transform);
    }
  }
  resolved->jaws = Span<const CaseJaw>(case_jaws, c.jaws.size());
  if (outline != nullptr) {
    *outline = o;
    outline->upper = resolved->upper;
    outline->lower = resolved->lower;
    outline->arch = Span<const Vec3>(arch, o.arch.size());
  }
  scope.commit();
  return Status::ok();
}

namespace {

void write_jaws(JsonWriter& w, const CaseFile& c) {
  w.begin_array("jaws");
  for (const CaseJaw& j : c.jaws) {
    w.begin_object();
    w.add("role", j.role);
    if (j.has_seed) {
      w.add("seed", j.seed);
    } else {
      w.add("mesh", j.mesh);
    }
    if (!c.has_plan) write_transform(w, j.transform);  // with a plan, the plan moves the jaws
    if (j.has_scan) write_scan(w, j.scan);
    w.end_object();
  }
  w.end_array();
}

void write_base(JsonWriter& w, const CaseFile& c) {
  w.begin_object("base");
  w.add("spacing_mm", c.base.spacing_mm);
  w.add("corner_radius_mm", c.base.corner_radius_mm);
  w.add("corner_segments", c.base.corner_segments);
  if (c.has_auto_outline) {
    const OutlineOptions& o = c.outline;
    w.begin_object("auto");
    w.add("indentation_depth_mm", o.indentation_depth_mm);
    w.add("overhang_mm", o.overhang_mm);
    w.add("pick_spacing_mm", o.pick_spacing_mm);
    if (o.has_bite_opening) w.add("bite_opening_mm", o.bite_opening_mm);
    if (o.survey) w.add("survey", true);
    if (o.has_distal_ends) {
      w.begin_array("distal_ends");
      w.add(nullptr, o.distal_ends[0]);
      w.add(nullptr, o.distal_ends[1]);
      w.end_array();
    }
    w.end_object();
  } else {
    w.add("occlusal_normal", c.occlusal_normal);
    if (!(c.has_plan && c.plan.has_picks)) {  // else the plan gives each splint its picks
      write_picks(w, "upper", c.upper);
      write_picks(w, "lower", c.lower);
    }
  }
  w.end_object();
}

void write_later_stages(JsonWriter& w, const CaseFile& c) {
  if (c.has_insertion_direction) w.add("insertion_direction", c.insertion_direction);
  if (c.has_blockout) {
    w.begin_object("blockout");
    w.add("method", blockout_method_name(c.blockout_method));
    if (c.blockout_method == BlockoutMethod::kHeightfield ||
        c.blockout_method == BlockoutMethod::kAuto) {
      w.add("voxel", c.blockout.voxel);
      if (c.blockout.offset > 0) w.add("clearance", c.blockout.offset);
    } else if (c.blockout_method != BlockoutMethod::kExact) {
      w.add("voxel", c.blockout.voxel);
      if (c.blockout.offset > 0) {
        w.add("clearance", c.blockout.offset);
      } else {
        w.add("inset", c.blockout.inset);
      }
      w.add("closing_radius", c.blockout.closing_radius);
    }
    w.end_object();
  }
  if (c.ct_volume != nullptr) {
    w.begin_object("ct");
    w.add("volume", c.ct_volume);
    w.add("hu_min", int64_t{c.ct_window.lo});
    w.add("hu_max", int64_t{c.ct_window.hi});
    w.add("connectivity", c.ct_grow.connectivity == Connectivity::k26 ? 26 : 6);
    w.add("smooth", c.ct_smooth.iterations);
    if (c.ct_decimate.target_triangles > 0) w.add("decimate", c.ct_decimate.target_triangles);
    w.end_object();
  }
  if (c.has_label) {
    w.begin_object("label");
    w.add("text", c.label.text);
    w.add("mode", c.label.mode == LabelMode::kEmboss ? "emboss" : "engrave");
    w.add("height_mm", c.label.height_mm);
    w.add("stroke_mm", c.label.stroke_width_mm);
    w.add("depth_mm", c.label.depth_mm);
    w.end_object();
  }
  if (c.min_thickness > 0) w.add("min_thickness", c.min_thickness);
  if (c.max_wall_crossing != CaseFile::kDefaultMaxWallCrossing) {
    w.add("max_wall_crossing", c.max_wall_crossing);
  }
  if (c.max_sideways_crossing != CaseFile::kDefaultMaxSidewaysCrossing) {
    w.add("max_sideways_crossing", c.max_sideways_crossing);
  }
  w.add("placement", c.place_on_tray ? "tray" : "case");
  w.add("printer", c.printer);
  if (c.memory_cap > 0) w.add("memory_cap", c.memory_cap);
  if (c.output_splint != nullptr || c.output_report != nullptr || c.output_job != nullptr) {
    w.begin_object("output");
    if (c.output_splint != nullptr) w.add("splint", c.output_splint);
    if (c.output_report != nullptr) w.add("report", c.output_report);
    if (c.output_job != nullptr) w.add("job", c.output_job);
    w.end_object();
  }
}

}  // namespace

Status write_case(const CaseFile& c, const ByteSink& sink) {
  JsonWriter w(sink);
  w.begin_object();
  w.add("splintcore_case", kCaseFormatVersion);
  if (c.case_id[0] != '\0') w.add("case_id", c.case_id);
  w.add("units", "mm");
  write_jaws(w, c);
  write_base(w, c);
  write_later_stages(w, c);
  if (c.has_plan) write_plan(w, c.plan);
  w.end_object();
  return w.finish();
}

}  // namespace splintcore
