// The design pipeline: jaws moved by the plan, base, Boolean difference, printer check.
#include <cstring>

#include "splintcore/design.h"

namespace splintcore {

namespace {

Status stage_error(const Status& s, const char* stage) {
  if (s.code() == StatusCode::kArenaExhausted || s.code() == StatusCode::kCancelled) return s;
  Status e = make_error(s.code(), stage, ": ", s.message());
  if (s.index() != kNoPosition) e.at_index(s.index());
  return e;
}

}  // namespace

Status design_splint(const Context& ctx, const CaseFile& c, Span<const Mesh> jaws, Mesh* splint,
                     DesignReport* report) {
  Arena& arena = *ctx.arena;
  *report = DesignReport{};
  if (!splint->vertices.empty() || !splint->triangles.empty()) {
    return Status::error(StatusCode::kInvalidArgument, "design_splint: output mesh must be empty");
  }
  if (jaws.size() != c.jaws.size()) {
    return make_error(StatusCode::kInvalidArgument, "design: the case names ", c.jaws.size(),
                      " jaws but ", jaws.size(), " meshes were given");
  }
  if (jaws.empty()) {
    return Status::error(StatusCode::kInvalidArgument,
                         "design: the case has no jaws to subtract (\"jaws\" is empty)");
  }
  const PrinterProfile* profile = find_printer_profile(c.printer);
  if (profile == nullptr) {
    return make_error(StatusCode::kInvalidArgument, "design: unknown printer \"", c.printer,
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

  // The base, then the Boolean: the base's temporaries go, the base stays until the result is
  // moved down over everything.
  SPLINTCORE_RETURN_IF_ERROR(stage("design: base"));
  Mesh base(&arena);
  Status s = build_case_base(ctx, c, &base, &report->base);
  if (!s.is_ok()) {
    arena.rewind(start);
    return stage_error(s, "base");
  }
  SPLINTCORE_RETURN_IF_ERROR(stage("design: boolean"));
  Mesh cut;
  BooleanOptions bo;
  bo.op = BooleanOp::kDifference;
  s = mesh_boolean(ctx, base, b, bo, &cut, &report->boolean);
  if (!s.is_ok()) {
    arena.rewind(start);
    return stage_error(s, "boolean (base minus jaws)");
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
      cut = blocked;  // the previous result stays below until the final move
    }
  }
  SPLINTCORE_RETURN_IF_ERROR(stage("design: printer"));
  PrintCheckOptions pco;
  pco.place_on_tray = true;  // for the fit only: the splint itself stays in the case's frame
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
