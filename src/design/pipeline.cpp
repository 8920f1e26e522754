// The design pipeline: jaws moved by the plan, base, Boolean difference, printer check.
#include <cmath>
#include <cstring>

#include "splintcore/design.h"

namespace splintcore {

namespace {

// Records which stage made the splint as it now is and whether its Boolean checked that mesh
// for self-intersections (the report's check comes from here, not from a constant).
void note_self_check(DesignReport* report, const BooleanStats& stats, const char* stage) {
  report->self_intersection_checked = stats.self_intersection_checked;
  report->self_intersection_checked_by = stats.self_intersection_checked ? stage : "";
  report->self_intersection_candidates = stats.self_intersection_candidates;
}

Status stage_error(const Status& s, const char* stage) {
  if (s.code() == StatusCode::kArenaExhausted || s.code() == StatusCode::kCancelled) return s;
  Status e = make_error(s.code(), stage, ": ", s.message());
  if (s.index() != kNoPosition) e.at_index(s.index());
  return e;
}

// The case moved onto the printer's tray ("placement": "tray"): the base is built once in
// the case's frame for its bounds, and the translation that centres them on the tray with the
// bottom at z = 0 (rounded to 1/64 mm) is applied to the picks and composed with every jaw's
// transform. The design then runs in the tray's frame, so the Boolean's float32 guarantees
// hold for the placed splint itself (moving a finished float32 mesh would round its vertices
// again and could fold its slivers). The copies live in the arena above its top at entry.
Status case_on_tray(const Context& ctx, const CaseFile& c, const PrinterProfile& profile,
                    CaseFile* out, Vec3* translation) {
  Arena& arena = *ctx.arena;
  Aabb box;
  {
    ArenaScope scope(arena);
    Mesh probe(&arena);
    BaseReport unused;
    SPLINTCORE_RETURN_IF_ERROR(build_case_base(ctx, c, &probe, &unused));
    for (const Vec3& p : probe.vertices) box.add(p);
  }
  const Vec3 centre = box.center();
  const auto on_grid = [](double v) { return std::floor(v * 64 + 0.5) / 64; };
  const Vec3 t{on_grid(profile.build_volume_mm.x * 0.5 - centre.x),
               on_grid(profile.build_volume_mm.y * 0.5 - centre.y),
               std::ceil(-box.lo.z * 64) / 64};  // bottom at z >= 0
  *translation = t;
  const RigidTransform move = RigidTransform::translation(t);
  *out = c;
  Pick* upper = arena.allocate_array<Pick>(c.upper.size());
  Pick* lower = arena.allocate_array<Pick>(c.lower.size());
  CaseJaw* jaws = arena.allocate_array<CaseJaw>(c.jaws.size());
  // None of the lists is empty here (the base was built from the picks; design_splint
  // refuses a case without jaws), so a null pointer means the arena is exhausted.
  if (upper == nullptr || lower == nullptr || jaws == nullptr) return arena.exhausted_status();
  for (size_t i = 0; i < c.upper.size(); ++i) {
    upper[i] = c.upper[i];
    upper[i].position = move.apply_point(c.upper[i].position);
  }
  for (size_t i = 0; i < c.lower.size(); ++i) {
    lower[i] = c.lower[i];
    lower[i].position = move.apply_point(c.lower[i].position);
  }
  for (size_t j = 0; j < c.jaws.size(); ++j) {
    jaws[j] = c.jaws[j];
    jaws[j].transform = compose(move, c.jaws[j].transform);
  }
  out->upper = Span<const Pick>(upper, c.upper.size());
  out->lower = Span<const Pick>(lower, c.lower.size());
  out->jaws = Span<const CaseJaw>(jaws, c.jaws.size());
  return Status::ok();
}

}  // namespace

Status design_splint(const Context& ctx, const CaseFile& case_in, Span<const Mesh> jaws, Mesh* splint,
                     DesignReport* report) {
  Arena& arena = *ctx.arena;
  *report = DesignReport{};
  if (!splint->vertices.empty() || !splint->triangles.empty()) {
    return Status::error(StatusCode::kInvalidArgument, "design_splint: output mesh must be empty");
  }
  if (jaws.size() != case_in.jaws.size()) {
    return make_error(StatusCode::kInvalidArgument, "design: the case names ", case_in.jaws.size(),
                      " jaws but ", jaws.size(), " meshes were given");
  }
  if (jaws.empty()) {
    return Status::error(StatusCode::kInvalidArgument,
                         "design: the case has no jaws to subtract (\"jaws\" is empty)");
  }
  const PrinterProfile* profile = find_printer_profile(case_in.printer);
  if (profile == nullptr) {
    return make_error(StatusCode::kInvalidArgument, "design: unknown printer \"", case_in.printer,
                      "\" (known: eden260)");
  }
  report->printer = profile->name;
  const Arena::Marker start = arena.mark();
  // A stage report may cancel: then nothing stays in the arena either.
  auto stage = [&](const char* name) -> Status {
    Status st = report_progress(ctx, name, 0, 1);
    if (!st.is_ok()) arena.rewind(start);
    return st;
  };
  CaseFile on_tray;
  if (case_in.place_on_tray) {
    const Status st = case_on_tray(ctx, case_in, *profile, &on_tray, &report->tray_translation);
    if (!st.is_ok()) {
      arena.rewind(start);
      return stage_error(st, "placement on the tray");
    }
    report->placed_on_tray = true;
  }
  const CaseFile& c = case_in.place_on_tray ? on_tray : case_in;

  // The jaws, moved and rounded, in one mesh (B of the Boolean).
  SPLINTCORE_RETURN_IF_ERROR(stage("design: jaws"));
  uint64_t nv = 0, nt = 0;
  for (const Mesh& m : jaws) {
    nv += m.vertices.size();
    nt += m.triangles.size();
  }
  report->jaw_triangles = nt;
  if (nv >= (uint64_t{1} << 31) || nt >= (uint64_t{1} << 31)) {
    return make_error(StatusCode::kLimitExceeded, "design: the jaws have ", nt, " triangles and ",
                      nv, " vertices; at most 2^31 each");
  }
  Mesh b(&arena);
  if (!b.vertices.reserve(static_cast<size_t>(nv)) || !b.triangles.reserve(static_cast<size_t>(nt))) {
    arena.rewind(start);
    return arena.exhausted_status();
  }
  for (size_t j = 0; j < jaws.size(); ++j) {
    if (jaws[j].triangles.empty()) {
      arena.rewind(start);
      return make_error(StatusCode::kInvalidMesh, "design: jaw ", j, " (", c.jaws[j].role,
                        ") is empty: it has no triangles")
          .at_index(j);
    }
    const uint32_t off = static_cast<uint32_t>(b.vertices.size());
    const uint32_t count = static_cast<uint32_t>(jaws[j].vertices.size());
    for (const Vec3& v : jaws[j].vertices) {
      if (!is_finite(v)) {
        arena.rewind(start);
        return make_error(StatusCode::kNonFinite, "design: jaw ", j, " (", c.jaws[j].role,
                          ") has a vertex that is not finite (NaN or infinity): vertex ",
                          static_cast<uint64_t>(&v - jaws[j].vertices.begin()))
            .at_index(j);
      }
      Vec3 p = c.jaws[j].transform.apply_point(v);
      if (!round_to_float32(&p)) {
        arena.rewind(start);
        return make_error(StatusCode::kLimitExceeded, "design: jaw ", j, " (", c.jaws[j].role,
                          ") moved beyond float32 range")
            .at_index(j);
      }
      (void)b.vertices.push_back(p);
    }
    for (const Triangle& t : jaws[j].triangles) {
      if (t.v[0] >= count || t.v[1] >= count || t.v[2] >= count) {
        arena.rewind(start);
        return make_error(StatusCode::kInvalidMesh, "design: jaw ", j, " (", c.jaws[j].role,
                          ") has a triangle that refers to a vertex that does not exist")
            .at_index(j);
      }
      (void)b.triangles.push_back(Triangle{{t.v[0] + off, t.v[1] + off, t.v[2] + off}});
    }
  }

  // An inside-out jaw (its triangles facing inward) would be subtracted as its complement. A
  // negative volume says so for a closed jaw; an open one (a scan) has no volume to go by.
  {
    size_t first = 0;
    for (size_t j = 0; j < jaws.size(); ++j) {
      Mesh part;
      part.vertices.adopt(b.vertices.data(), b.vertices.size(), b.vertices.size());
      part.triangles.adopt(b.triangles.data() + first, jaws[j].triangles.size(),
                           jaws[j].triangles.size());
      first += jaws[j].triangles.size();
      if (!(mesh_volume(part) < 0)) continue;
      // Closed and consistently oriented once turned over: then it is inside out.
      const Arena::Marker before = arena.mark();
      Mesh flipped(&arena);
      Status closed = arena.exhausted_status();
      if (flipped.triangles.resize(part.triangles.size())) {
        for (size_t i = 0; i < part.triangles.size(); ++i) {
          const Triangle& t = part.triangles[i];
          flipped.triangles[i] = Triangle{{t.v[0], t.v[2], t.v[1]}};
        }
        Mesh view;
        view.vertices.adopt(b.vertices.data(), b.vertices.size(), b.vertices.size());
        view.triangles.adopt(flipped.triangles.data(), flipped.triangles.size(),
                             flipped.triangles.size());
        double volume = 0;
        closed = check_closed_oriented(ctx, view, &volume);
      }
      arena.rewind(before);
      if (closed.code() == StatusCode::kArenaExhausted) {
        arena.rewind(start);
        return closed;
      }
      if (closed.is_ok()) {
        arena.rewind(start);
        return make_error(StatusCode::kInvalidMesh, "design: jaw ", j, " (", c.jaws[j].role,
                          ") is inside out: it is closed but its triangles face inward "
                          "(volume ", mesh_volume(part), " mm^3); reverse their orientation")
            .at_index(j);
      }
    }
  }

  // The base, then the Boolean: the base's temporaries go, the base stays until the result is
  // moved down over everything.
  SPLINTCORE_RETURN_IF_ERROR(stage("design: base"));
  Mesh base(&arena);
  Status s = build_case_base(ctx, c, &base, &report->base);
  if (!s.is_ok()) {
    arena.rewind(start);
    return stage_error(s, "base");
  }
  Mesh cut;
  if (c.has_blockout && c.blockout_clearance > 0) {
    // A spacer: the imprint is the swept volumes' offset surface, which holds each jaw, so
    // subtracting the jaws themselves first would only cut what the blockout removes anyway.
    report->imprint_offset = true;
    cut = base;
  } else {
    SPLINTCORE_RETURN_IF_ERROR(stage("design: boolean"));
    BooleanOptions bo;
    bo.op = BooleanOp::kDifference;
    s = mesh_boolean(ctx, base, b, bo, &cut, &report->boolean);
    if (!s.is_ok()) {
      arena.rewind(start);
      return stage_error(s, "boolean (base minus jaws)");
    }
    note_self_check(report, report->boolean, "boolean");
  }
  if (c.has_blockout) {
    // Interference elimination, jaw by jaw: each jaw's part of B (its triangles, ids into all
    // of B's vertices) swept along the direction it leaves the splint, and subtracted.
    SPLINTCORE_RETURN_IF_ERROR(stage("design: blockout"));
    if (jaws.size() > DesignReport::kMaxBlockoutJaws) {
      arena.rewind(start);
      return make_error(StatusCode::kLimitExceeded, "design: blockout takes at most ",
                        DesignReport::kMaxBlockoutJaws, " jaws, the case has ", jaws.size());
    }
    size_t first_triangle = 0;
    for (size_t j = 0; j < jaws.size(); ++j) {
      Mesh jaw;
      jaw.vertices.adopt(b.vertices.data(), b.vertices.size(), b.vertices.size());
      jaw.triangles.adopt(b.triangles.data() + first_triangle, jaws[j].triangles.size(),
                          jaws[j].triangles.size());
      first_triangle += jaws[j].triangles.size();
      const bool mandible = std::strcmp(c.jaws[j].role, "mandible") == 0;
      BlockoutOptions bl;
      bl.sweep.direction = mandible ? -c.insertion_direction : c.insertion_direction;
      bl.sweep.voxel = c.blockout_voxel;
      bl.sweep.inset = c.blockout_inset;
      bl.sweep.closing_radius = c.blockout_closing;
      bl.sweep.offset = c.blockout_clearance;
      Mesh blocked;
      s = blockout(ctx, cut, Span<const Mesh>(&jaw, 1), bl, &blocked, &report->blockout[j]);
      if (!s.is_ok()) {
        arena.rewind(start);
        Status e = stage_error(s, "blockout");
        if (s.code() != StatusCode::kArenaExhausted && s.code() != StatusCode::kCancelled) {
          e.append(" (jaw ").append_u64(j).append(", ").append(c.jaws[j].role).append(")");
        }
        return e;
      }
      report->blockout_removed_mm3[j] = mesh_volume(cut) - mesh_volume(blocked);
      report->blockout_jaws = static_cast<uint32_t>(j + 1);
      note_self_check(report, report->blockout[j].boolean, "blockout");
      cut = blocked;  // the previous result stays below until the final move
    }
  }
  if (c.has_label) {
    // The label on the outer wall, placed from the base's lines (made as build_case_base
    // makes them); the labelled splint's triangles come first, so the final move takes it.
    SPLINTCORE_RETURN_IF_ERROR(stage("design: label"));
    ArenaArray<Line> upper(&arena), lower(&arena);
    s = make_lines(ctx, c.upper, c.occlusal_normal, "upper", &upper);
    if (s.is_ok()) s = make_lines(ctx, c.lower, c.occlusal_normal, "lower", &lower);
    LabelOptions lo;
    lo.text = c.label_text;
    lo.mode = c.label_emboss ? LabelMode::kEmboss : LabelMode::kEngrave;
    lo.height_mm = c.label_height;
    lo.stroke_width_mm = c.label_stroke;
    lo.depth_mm = c.label_depth;
    Mesh labelled;
    if (s.is_ok()) {
      s = apply_label(ctx, cut, upper.span(), lower.span(), lo, &labelled, &report->label);
    }
    if (!s.is_ok()) {
      arena.rewind(start);
      return stage_error(s, "design");
    }
    report->labelled = true;
    note_self_check(report, report->label.boolean, "label");
    cut = labelled;
  }
  if (c.min_thickness > 0) {
    SPLINTCORE_RETURN_IF_ERROR(stage("design: thickness"));
    s = check_wall_thickness(ctx, cut, c.min_thickness, &report->thickness);
    if (!s.is_ok()) {
      arena.rewind(start);
      return stage_error(s, "thickness check");
    }
    report->thickness_checked = true;
  }
  SPLINTCORE_RETURN_IF_ERROR(stage("design: printer"));
  PrintCheckOptions pco;
  pco.place_on_tray = true;  // for the fit; the splint moves only with "placement": "tray"
  s = check_printable(ctx, cut, *profile, pco, &report->print);
  if (s.is_ok()) s = require_printable(report->print, *profile);
  if (!s.is_ok()) {
    arena.rewind(start);
    return stage_error(s, "printer check");
  }

  // The splint down over the jaws' copy and the base.
  move_mesh_down(arena, start, cut, splint);
  (void)report_progress(ctx, "design: done", 1, 1);  // the splint is made: too late to cancel
  return Status::ok();
}

}  // namespace splintcore
