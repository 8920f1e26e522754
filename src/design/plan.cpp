// Two-jaw surgery (design.h, design_plan): the intermediate and the final splint of one
// surgical plan, each an ordinary design_splint() of the case with the jaws where the plan and
// the hinge-axis autorotation (outline.h, autorotate_mandible) put them. Why each splint holds
// the jaws where it does, in either sequence: docs/case-format.md, "Plan".
#include <cstring>

#include "design/fusion.h"
#include "design/no_jaw.h"
#include "splintcore/design.h"

namespace splintcore {

namespace {

// The prefix names which splint and which stage; running out and cancelling pass unchanged.
Status plan_error(const Status& s, const char* which, const char* stage) {
  if (s.is_ok() || s.code() == StatusCode::kArenaExhausted || s.code() == StatusCode::kCancelled) {
    return s;
  }
  Status e = make_error(s.code(), "plan: ", which, ": ", stage, s.message());
  if (s.index() != kNoPosition) e.at_index(s.index());
  return e;
}

// An error of both splints (the fusion, made once): "plan: " and the message.
Status plan_prefixed(const Status& s) {
  if (s.is_ok() || s.code() == StatusCode::kArenaExhausted || s.code() == StatusCode::kCancelled) {
    return s;
  }
  Status e = make_error(s.code(), "plan: ", s.message());
  if (s.index() != kNoPosition) e.at_index(s.index());
  return e;
}

// Indices of the maxilla and the mandible (the parser allows one of each role).
Status plan_roles(const CaseFile& c, size_t* up, size_t* low) {
  if (!c.has_plan || c.jaws.size() != 2) {
    return Status::error(StatusCode::kInvalidArgument,
                         "plan: the case has no \"plan\" with a maxilla and a mandible");
  }
  *up = std::strcmp(c.jaws[0].role, "maxilla") == 0 ? 0 : 1;
  *low = 1 - *up;
  if (std::strcmp(c.jaws[*up].role, "maxilla") != 0 ||
      std::strcmp(c.jaws[*low].role, "mandible") != 0) {
    return Status::error(StatusCode::kInvalidArgument,
                         "plan: the case's jaws must be one maxilla and one mandible");
  }
  return Status::ok();
}

// `m` moved by `x` and rounded to float32 (as design_splint moves a jaw), into `out`; the
// triangles are shared with `m`.
Status moved_copy(const Context& ctx, const Mesh& m, const RigidTransform& x, const char* role,
                  Mesh* out) {
  out->bind(ctx.arena);
  if (!out->vertices.reserve(m.vertices.size())) return ctx.arena->exhausted_status();
  for (const Vec3& v : m.vertices) {
    Vec3 p = x.apply_point(v);
    if (!round_to_float32(&p)) {
      return make_error(StatusCode::kLimitExceeded, "the ", role,
                        " moved by the plan is beyond float32 range (or not finite)");
    }
    (void)out->vertices.push_back(p);
  }
  out->triangles.adopt(const_cast<Triangle*>(m.triangles.span().data()), m.triangles.size(),
                       m.triangles.size());
  return Status::ok();
}

// The label of one splint: "INT " or "FIN " and the case's label text (nothing without one).
Status plan_label_text(const CaseFile& c, bool final_splint, char out[kLabelMaxCharacters + 1]) {
  out[0] = '\0';
  if (!c.has_label) return Status::ok();
  const char* prefix = final_splint ? "FIN " : "INT ";
  const size_t n = std::strlen(c.label.text);
  if (n + 4 > kLabelMaxCharacters) {
    return make_error(
        StatusCode::kInvalidArgument, "plan: ", final_splint ? "final" : "intermediate",
        ": label: \"", prefix, "\" and the label's text are ", n + 4, " characters, at most ",
        kLabelMaxCharacters, ": shorten \"label\"'s \"text\" to ", kLabelMaxCharacters - 4);
  }
  std::memcpy(out, prefix, 4);
  std::memcpy(out + 4, c.label.text, n + 1);
  return Status::ok();
}

// The scan-CT fusion of a plan case, made once before either splint: the scans as given and
// their registrations onto the preoperative jaws (fused[j]: jaw j has a scan).
struct PlanFusion {
  Span<const Mesh> scans;
  bool fused[2] = {false, false};
  FusionReport fusion[2];
  bool any() const { return fused[0] || fused[1]; }
};

// Jaw j as the autorotation sees it: its registered scan when it has one (the registration
// first, then the plan's move), else its mesh.
const Mesh& plan_source(Span<const Mesh> jaws, const PlanFusion& f, size_t j) {
  return f.fused[j] ? f.scans[j] : jaws[j];
}
RigidTransform plan_source_move(const PlanFusion& f, size_t j, const RigidTransform& move) {
  return f.fused[j] ? compose(move, f.fusion[j].registration.transform) : move;
}

// The plan's moves of one splint's jaws (before the autorotation) and its opening.
void plan_moves(const CasePlan& plan, bool final_splint, PlanSplintReport* r) {
  const bool move_maxilla = final_splint || !plan.mandible_first;
  const bool move_mandible = final_splint || plan.mandible_first;
  r->maxilla = move_maxilla ? plan.maxilla : RigidTransform{};
  r->mandible = move_mandible ? plan.mandible : RigidTransform{};
  r->opening_asked_mm = final_splint ? plan.final_opening_mm : plan.intermediate_opening_mm;
}

// One jaw's index for both splints' autorotations (the splints' moved jaws refit it), with
// autorotate_mandible's refusals of an empty or broken jaw.
Status plan_jaw_index(const Context& ctx, const Mesh& m, const char* role, DistanceIndex* out) {
  if (m.triangles.empty() || m.vertices.empty()) {
    return make_error(StatusCode::kInvalidMesh, "autorotate: the ", role, " is empty");
  }
  const Status s = build_distance_index(ctx, m, autorotate_index_options(), out);
  if (s.code() != StatusCode::kInvalidMesh) return s;
  Status e = make_error(s.code(), "autorotate: the ", role, "'s ", s.message());
  if (s.index() != kNoPosition) e.at_index(s.index());
  return e;
}

// The identity move exactly (a jaw the plan leaves where it is, without a scan).
bool is_identity(const RigidTransform& x) {
  for (int i = 0; i < 3; ++i) {
    for (int k = 0; k < 3; ++k) {
      if (x.r[i][k] != (i == k ? 1.0 : 0.0)) return false;
    }
  }
  return x.t.x == 0 && x.t.y == 0 && x.t.z == 0;
}

// One splint's autorotation: the jaws moved as the plan says for it (and rounded to float32,
// as design_splint moves them), the indexes refit to them, the mandible turned about the
// hinge axis to the opening. The moved copies stay (the caller's scope returns them).
Status plan_autorotation(const Context& ctx, const CaseFile& c, Span<const Mesh> jaws,
                         const PlanFusion& f, const DistanceIndex index[2], bool final_splint,
                         PlanSplintReport* r) {
  size_t up = 0, low = 0;
  SPLINTCORE_RETURN_IF_ERROR(plan_roles(c, &up, &low));
  plan_moves(c.plan, final_splint, r);
  Mesh upper, lower;
  const RigidTransform moves[2] = {plan_source_move(f, up, r->maxilla),
                                   plan_source_move(f, low, r->mandible)};
  SPLINTCORE_RETURN_IF_ERROR(
      moved_copy(ctx, plan_source(jaws, f, up), moves[0], "maxilla", &upper));
  SPLINTCORE_RETURN_IF_ERROR(
      moved_copy(ctx, plan_source(jaws, f, low), moves[1], "mandible", &lower));
  const Mesh* copies[2] = {&upper, &lower};
  DistanceIndex moved[2];
  for (int j = 0; j < 2; ++j) {
    if (is_identity(moves[j])) {
      // The copy is the jaw's vertices rounded to float32, which its boxes hold already (each
      // is rounded outward to float from the vertices: the rounding to the nearest float of a
      // value within a box stays within it): its tree serves as it is.
      moved[j] = index[j];
      moved[j].mesh = copies[j];
    } else {
      SPLINTCORE_RETURN_IF_ERROR(refit_distance_index(ctx, index[j], *copies[j], &moved[j]));
    }
  }
  AutorotateOptions o;
  o.hinge[0] = c.plan.hinge[0];
  o.hinge[1] = c.plan.hinge[1];
  o.opening_mm = r->opening_asked_mm;
  return autorotate_mandible_indexed(ctx, moved[0], moved[1], o, &r->autorotation);
}

// Both splints' autorotations, before either design: each jaw's index is built once (not
// once a splint) and refit to each splint's moved jaws. Nothing stays in the arena. A
// splint's error goes to status[splint] (0: intermediate, 1: final), prefixed, for the caller
// to report where it did before (the final's after the intermediate's design); the final's is
// not looked for after the intermediate's, nor after running out or a cancel.
void plan_autorotations(const Context& ctx, const CaseFile& c, Span<const Mesh> jaws,
                        const PlanFusion& f, PlanReport* report, Status status[2]) {
  ArenaScope scope(*ctx.arena);
  // The label's refusal first, as before the autorotation (both splints' texts are as long).
  status[0] = plan_label_text(c, false, report->intermediate.label_text);
  if (!status[0].is_ok()) return;
  size_t up = 0, low = 0;
  status[0] = plan_roles(c, &up, &low);
  DistanceIndex index[2];
  if (status[0].is_ok())
    status[0] = plan_jaw_index(ctx, plan_source(jaws, f, up), "maxilla", &index[0]);
  if (status[0].is_ok())
    status[0] = plan_jaw_index(ctx, plan_source(jaws, f, low), "mandible", &index[1]);
  if (status[0].is_ok()) {
    ArenaScope splint(*ctx.arena);
    status[0] = plan_autorotation(ctx, c, jaws, f, index, false, &report->intermediate);
  }
  status[0] = plan_error(status[0], "intermediate", "autorotation: ");
  if (!status[0].is_ok()) return;
  status[1] = plan_error(plan_autorotation(ctx, c, jaws, f, index, true, &report->final_splint),
                         "final", "autorotation: ");
}

// One splint, its autorotation done: design_splint with the jaws where the plan and the
// autorotation put them.
Status plan_one(const Context& ctx, const CaseFile& c, Span<const Mesh> jaws, const PlanFusion& f,
                bool final_splint, Mesh* splint, PlanSplintReport* r) {
  const char* which = final_splint ? "final" : "intermediate";
  SPLINTCORE_RETURN_IF_ERROR(plan_label_text(c, final_splint, r->label_text));
  r->angle_deg = r->autorotation.angle_rad * (180.0 / 3.14159265358979323846);
  r->mandible = compose(r->autorotation.transform, r->mandible);
  CaseJaw derived_jaws[2];
  CaseFile derived;
  SPLINTCORE_RETURN_IF_ERROR(plan_splint_case(c, *r, derived_jaws, &derived));
  return plan_error(
      design_detail::design_splint_registered(
          ctx, derived, jaws, f.scans, f.any() ? f.fusion : nullptr, true, splint, &r->design),
      which, "");
}

}  // namespace

Status plan_splint_case(const CaseFile& c, const PlanSplintReport& r, CaseJaw jaws[2],
                        CaseFile* out) {
  size_t up = 0, low = 0;
  SPLINTCORE_RETURN_IF_ERROR(plan_roles(c, &up, &low));
  jaws[up] = c.jaws[up];
  jaws[up].transform = r.maxilla;
  jaws[low] = c.jaws[low];
  jaws[low].transform = r.mandible;
  if (c.has_label && r.label_text[0] == '\0') {
    return Status::error(StatusCode::kInvalidArgument,
                         "plan: the case has a \"label\" but the splint's report no label text");
  }
  *out = c;
  out->has_plan = false;
  if (c.has_label) out->label.text = r.label_text;
  out->jaws = Span<const CaseJaw>(jaws, 2);
  return Status::ok();
}

Status design_plan(const Context& ctx, const CaseFile& c, Span<const Mesh> jaws, Mesh* intermediate,
                   Mesh* final_splint, PlanReport* report) {
  return design_plan(ctx, c, jaws, Span<const Mesh>(), intermediate, final_splint, report);
}

Status design_plan(const Context& ctx, const CaseFile& c, Span<const Mesh> jaws,
                   Span<const Mesh> scans, Mesh* intermediate, Mesh* final_splint,
                   PlanReport* report) {
  *report = PlanReport{};
  size_t up = 0, low = 0;
  SPLINTCORE_RETURN_IF_ERROR(plan_roles(c, &up, &low));
  if (jaws.size() != 2) {
    return make_error(StatusCode::kInvalidArgument, "plan: the case names 2 jaws but ", jaws.size(),
                      " meshes were given");
  }
  SPLINTCORE_RETURN_IF_ERROR(plan_prefixed(design_detail::check_case_scans(c, scans)));
  SPLINTCORE_RETURN_IF_ERROR(plan_prefixed(design_detail::refuse_no_jaw(ctx, c, jaws, scans)));
  PlanFusion f;
  f.scans = scans;
  if (!scans.empty()) {  // once, on the preoperative jaws: before the plan moves them
    SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "plan: fusion", 0, 2));
    SPLINTCORE_RETURN_IF_ERROR(
        plan_prefixed(design_detail::register_case_scans(ctx, c, jaws, scans, f.fused, f.fusion)));
  }
  ArenaScope scope(*ctx.arena);  // on an error nothing stays
  SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "plan: intermediate", 0, 2));
  Status autorotated[2];
  plan_autorotations(ctx, c, jaws, f, report, autorotated);
  Status s = autorotated[0];
  if (s.is_ok()) s = plan_one(ctx, c, jaws, f, false, intermediate, &report->intermediate);
  if (s.is_ok()) s = report_progress(ctx, "plan: final", 1, 2);
  if (s.is_ok()) s = autorotated[1];
  if (s.is_ok()) s = plan_one(ctx, c, jaws, f, true, final_splint, &report->final_splint);
  if (!s.is_ok()) {
    *intermediate = Mesh{};
    *final_splint = Mesh{};
    return s;
  }
  scope.commit();
  return Status::ok();
}

}  // namespace splintcore
