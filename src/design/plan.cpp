// Two-jaw surgery (design.h, design_plan): the intermediate and the final splint of one
// surgical plan, each an ordinary design_splint() of the case with the jaws where the plan and
// the hinge-axis autorotation (outline.h, autorotate_mandible) put them. Why each splint holds
// the jaws where it does, in either sequence: docs/case-format.md, "Plan".
#include <cstdint>
#include <cstring>

#include "design/fusion.h"
#include "design/no_jaw.h"
#include "design/plan_internal.h"
#include "splintcore/design.h"

namespace splintcore {

using design_detail::PlanFusion;

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

// Jaw j as the autorotation sees it: its registered scan when it has one (the registration
// first, then the plan's move), else its mesh.
const Mesh& plan_source(Span<const Mesh> jaws, const PlanFusion& f, size_t j) {
  return f.fused[j] ? f.scans[j] : jaws[j];
}
RigidTransform plan_source_move(const PlanFusion& f, size_t j, const RigidTransform& move) {
  return f.fused[j] ? compose(move, f.fusion[j].registration.transform) : move;
}

// The plan's moves of one splint's jaws (before the autorotation) and its opening, into a
// PlanSplintReport or a SplintRotation (the same members).
template <class Report>
void plan_moves(const CasePlan& plan, bool final_splint, Report* r) {
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

// The autorotations in tasks on the executor (more than one thread): the two jaws' indexes in
// two tasks, then the two splints' autorotations in two tasks. Each task has its own Arena over
// a slice of the caller's, sized by the bounds of what it allocates, and a Context without
// progress or executor. The answers are the serial order's bit for bit (the same computations
// on the same inputs); only where they sit in the arena differs. When the slices do not fit,
// or a task fails, the arena is rewound and the serial order runs instead, so the errors are
// its errors in its order.

bool in_tasks(const Context& ctx) { return has_threads(ctx.executor); }

// A span of an index whose arrays were moved (memmove) from [from, from + bytes) to `to`:
// follows them when it pointed there.
template <class T>
void follow(Span<const T>* s, uintptr_t from, size_t bytes, uintptr_t to) {
  const uintptr_t p = reinterpret_cast<uintptr_t>(s->data());
  if (s->data() == nullptr || p < from || p - from >= bytes) return;
  *s = Span<const T>(reinterpret_cast<const T*>(to + (p - from)), s->size());
}

void follow_index(DistanceIndex* x, const unsigned char* from, size_t bytes,
                  const unsigned char* to) {
  // Every array of an index is one of these spans: a new member must be followed here too.
  static_assert(
      sizeof(DistanceIndex) == sizeof(void*) + 8 * sizeof(Span<const float>) + 2 * sizeof(uint32_t),
      "DistanceIndex changed: follow its new arrays in follow_index");
  const uintptr_t f = reinterpret_cast<uintptr_t>(from), t = reinterpret_cast<uintptr_t>(to);
  follow(&x->nodes, f, bytes, t);
  follow(&x->dipoles, f, bytes, t);
  follow(&x->obbs, f, bytes, t);
  follow(&x->order, f, bytes, t);
  follow(&x->triangle_boxes, f, bytes, t);
  follow(&x->neighbors, f, bytes, t);
  follow(&x->vertex_start, f, bytes, t);
  follow(&x->vertex_uses, f, bytes, t);
}

// Both jaws' indexes (sources: maxilla, mandible), built in two tasks, each in a slice of its
// distance_index_bound(); then the mandible's moved down onto the end of the maxilla's and the
// rest of the slices given back, so that they take what the serial order's take (and the
// alignment between them). False, the arena as it was, when the slices do not fit or a build
// failed.
bool jaw_indexes_in_tasks(const Context& ctx, const Mesh* const sources[2],
                          DistanceIndex index[2]) {
  const Arena::Marker start = ctx.arena->mark();
  const DistanceIndexOptions o = autorotate_index_options();
  const uint64_t need[2] = {
      distance_index_bound(sources[0]->vertices.size(), sources[0]->triangles.size(), o),
      distance_index_bound(sources[1]->vertices.size(), sources[1]->triangles.size(), o)};
  size_t sizes[2] = {0, 0};
  unsigned char* base = take_arena_slices(*ctx.arena, need, sizes);
  if (base == nullptr) return false;
  Arena a0(base, sizes[0]), a1(base + sizes[0], sizes[1]);
  Arena* arenas[2] = {&a0, &a1};
  const char* const roles[2] = {"maxilla", "mandible"};
  Status s[2];
  auto task = [&](uint32_t j) {
    s[j] = plan_jaw_index(Context(arenas[j]), *sources[j], roles[j], &index[j]);
  };
  parallel_for_each(ctx.executor, 2, task);
  size_t kept0 = 0;
  if (!s[0].is_ok() || !s[1].is_ok() || !arena_slice_size(a0.used(), &kept0)) {
    ctx.arena->rewind(start);
    index[0] = index[1] = DistanceIndex{};
    return false;
  }
  std::memmove(base + kept0, base + sizes[0], a1.used());
  follow_index(&index[1], base + sizes[0], a1.used(), base + kept0);
  (void)ctx.arena->try_shrink(base, sizes[0] + sizes[1], kept0 + a1.used());
  return true;
}

// One jaw of one splint as its autorotation sees it: the source moved by the splint's move
// and rounded to float32 (moved_copy), and the jaw's index refit to it, or as it is for the
// identity (see plan_autorotation). The index points at `mesh`: the struct stays where it is.
struct MovedJaw {
  Mesh mesh;
  DistanceIndex index;
};

uint64_t move_jaw_bound(const Mesh& source, const RigidTransform& move,
                        const DistanceIndex& index) {
  return arena_array_bound<Vec3>(source.vertices.size()) +
         (is_identity(move) ? 0 : refit_distance_index_bound(index));
}

Status move_jaw(const Context& ctx, const Mesh& source, const RigidTransform& move,
                const DistanceIndex& index, const char* role, MovedJaw* out) {
  SPLINTCORE_RETURN_IF_ERROR(moved_copy(ctx, source, move, role, &out->mesh));
  if (!is_identity(move)) return refit_distance_index(ctx, index, out->mesh, &out->index);
  out->index = index;
  out->index.mesh = &out->mesh;
  return Status::ok();
}

bool same_bits(double a, double b) {
  uint64_t ua = 0, ub = 0;
  std::memcpy(&ua, &a, sizeof ua);
  std::memcpy(&ub, &b, sizeof ub);
  return ua == ub;
}

// The same move bit for bit (the same copy and refit).
bool same_move(const RigidTransform& a, const RigidTransform& b) {
  for (int i = 0; i < 3; ++i) {
    if (!same_bits(a.t[i], b.t[i])) return false;
    for (int k = 0; k < 3; ++k) {
      if (!same_bits(a.r[i][k], b.r[i][k])) return false;
    }
  }
  return true;
}

// One splint's part of PlanSplintReport that its autorotation writes (a task's own: the
// report's is written when both tasks succeeded; small, unlike the report, on the stack).
struct SplintRotation {
  RigidTransform maxilla, mandible;
  double opening_asked_mm = 0;
  AutorotateReport autorotation;
};

// What one splint's task reads: its jaws' sources and moves (maxilla, mandible), the jaws'
// indexes, the jaws both splints move alike (moved already, else null), where it writes.
struct SplintTask {
  const CaseFile* c = nullptr;
  const Mesh* sources[2] = {nullptr, nullptr};
  RigidTransform moves[2];
  const DistanceIndex* index = nullptr;
  const MovedJaw* shared[2] = {nullptr, nullptr};
  SplintRotation* r = nullptr;
};

// Its own moved jaws (those not shared), then the autorotation (the mandible's index second).
Status splint_task(const Context& ctx, const SplintTask& t) {
  const char* const roles[2] = {"maxilla", "mandible"};
  MovedJaw own[2];
  const MovedJaw* use[2] = {t.shared[0], t.shared[1]};
  for (int j = 0; j < 2; ++j) {
    if (use[j] != nullptr) continue;
    SPLINTCORE_RETURN_IF_ERROR(
        move_jaw(ctx, *t.sources[j], t.moves[j], t.index[j], roles[j], &own[j]));
    use[j] = &own[j];
  }
  AutorotateOptions o;
  o.hinge[0] = t.c->plan.hinge[0];
  o.hinge[1] = t.c->plan.hinge[1];
  o.opening_mm = t.r->opening_asked_mm;
  return autorotate_mandible_indexed(ctx, use[0]->index, use[1]->index, o, &t.r->autorotation);
}

// Both splints' autorotations in two tasks, into `local` (the plan's moves, the opening
// asked, the autorotation); a jaw both splints move alike is moved and refit once, here, below
// the slices (it is the same copy). Each slice: move_jaw_bound() of its other jaws and
// autorotate_mandible_indexed_bound(). Nothing stays. False when the slices do not fit or a
// task failed.
bool splint_autorotations_in_tasks(const Context& ctx, const CaseFile& c,
                                   const Mesh* const sources[2], const PlanFusion& f, size_t up,
                                   size_t low, const DistanceIndex index[2],
                                   SplintRotation local[2]) {
  ArenaScope scope(*ctx.arena);
  SplintTask tasks[2];
  for (int k = 0; k < 2; ++k) {
    plan_moves(c.plan, k == 1, &local[k]);
    tasks[k].c = &c;
    tasks[k].sources[0] = sources[0];
    tasks[k].sources[1] = sources[1];
    tasks[k].moves[0] = plan_source_move(f, up, local[k].maxilla);
    tasks[k].moves[1] = plan_source_move(f, low, local[k].mandible);
    tasks[k].index = index;
    tasks[k].r = &local[k];
  }
  MovedJaw shared[2];
  uint64_t need[2] = {autorotate_mandible_indexed_bound(), autorotate_mandible_indexed_bound()};
  const char* const roles[2] = {"maxilla", "mandible"};
  for (int j = 0; j < 2; ++j) {
    if (same_move(tasks[0].moves[j], tasks[1].moves[j])) {
      const Context here(ctx.arena);
      if (!move_jaw(here, *sources[j], tasks[0].moves[j], index[j], roles[j], &shared[j]).is_ok()) {
        return false;
      }
      tasks[0].shared[j] = tasks[1].shared[j] = &shared[j];
    } else {
      for (int k = 0; k < 2; ++k)
        need[k] += move_jaw_bound(*sources[j], tasks[k].moves[j], index[j]);
    }
  }
  size_t sizes[2] = {0, 0};
  unsigned char* base = take_arena_slices(*ctx.arena, need, sizes);
  if (base == nullptr) return false;
  Arena a0(base, sizes[0]), a1(base + sizes[0], sizes[1]);
  Arena* arenas[2] = {&a0, &a1};
  Status s[2];
  auto task = [&](uint32_t k) { s[k] = splint_task(Context(arenas[k]), tasks[k]); };
  parallel_for_each(ctx.executor, 2, task);
  return s[0].is_ok() && s[1].is_ok();
}

// The serial order: the maxilla's index, the mandible's, the intermediate's autorotation (its
// moved jaws returned), the final's.
void serial_autorotations(const Context& ctx, const CaseFile& c, Span<const Mesh> jaws,
                          const PlanFusion& f, bool indexed, DistanceIndex index[2],
                          PlanReport* report, Status status[2]) {
  size_t up = 0, low = 0;
  status[0] = plan_roles(c, &up, &low);
  if (status[0].is_ok() && !indexed)
    status[0] = plan_jaw_index(ctx, plan_source(jaws, f, up), "maxilla", &index[0]);
  if (status[0].is_ok() && !indexed)
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

// The report's part of one splint's autorotation, from `from`.
void take_autorotation(const SplintRotation& from, PlanSplintReport* to) {
  to->maxilla = from.maxilla;
  to->mandible = from.mandible;
  to->opening_asked_mm = from.opening_asked_mm;
  to->autorotation = from.autorotation;
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
  SPLINTCORE_RETURN_IF_ERROR(plan_splint_case(c, *r, final_splint, derived_jaws, &derived));
  return plan_error(
      design_detail::design_splint_registered(
          ctx, derived, jaws, f.scans, f.any() ? f.fusion : nullptr, true, splint, &r->design),
      which, "");
}

}  // namespace

namespace design_detail {

void plan_autorotations(const Context& ctx, const CaseFile& c, Span<const Mesh> jaws,
                        const PlanFusion& f, PlanReport* report, Status status[2]) {
  ArenaScope scope(*ctx.arena);
  // The label's refusal first, as before the autorotation (both splints' texts are as long).
  status[0] = plan_label_text(c, false, report->intermediate.label_text);
  if (!status[0].is_ok()) return;
  size_t up = 0, low = 0;
  DistanceIndex index[2];
  bool indexed = false;
  if (in_tasks(ctx) && plan_roles(c, &up, &low).is_ok()) {
    const Mesh* const sources[2] = {&plan_source(jaws, f, up), &plan_source(jaws, f, low)};
    indexed = jaw_indexes_in_tasks(ctx, sources, index);
    if (indexed) {
      // The tasks report no progress: a cancel is seen here.
      status[0] = report_progress(ctx, "distance index", 4, 4);
      if (!status[0].is_ok()) return;
      SplintRotation local[2];
      if (splint_autorotations_in_tasks(ctx, c, sources, f, up, low, index, local)) {
        take_autorotation(local[0], &report->intermediate);
        take_autorotation(local[1], &report->final_splint);
        status[1] = Status::ok();
        return;
      }
    }
  }
  serial_autorotations(ctx, c, jaws, f, indexed, index, report, status);
}

}  // namespace design_detail

Status plan_splint_case(const CaseFile& c, const PlanSplintReport& r, bool final_splint,
                        CaseJaw jaws[2], CaseFile* out) {
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
  if (c.plan.has_picks) {  // this splint's own picks
    const int k = final_splint ? 1 : 0;
    out->upper = c.plan.upper[k];
    out->lower = c.plan.lower[k];
  }
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
  design_detail::plan_autorotations(ctx, c, jaws, f, report, autorotated);
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
