// The design pipeline (design.h): the jaws moved by the plan, the base, the Boolean difference,
// blockout or a spacer, the label, the thickness and printer checks. design_splint reads as
// that list; each stage with more than a call is a function of its own below.
#include <algorithm>
#include <cmath>
#include <cstring>

#include "design/b_vertex.h"
#include "design/fusion.h"
#include "design/no_jaw.h"
#include "splintcore/design.h"

namespace splintcore {

namespace {

using design_detail::b_vertex;

// Records which stage made the splint as it now is and whether its Boolean checked that mesh
// for self-intersections (the report's check comes from here, not from a constant).
void note_self_check(DesignReport* report, const BooleanStats& stats, const char* stage) {
  report->self_intersection_checked = stats.self_intersection_checked;
  report->self_intersection_checked_by = stats.self_intersection_checked ? stage : "";
  report->self_intersection_candidates = stats.self_intersection_candidates;
}

// A stage's error with the stage named first (unless it already is: blockout names itself);
// ok, running out and cancelling pass unchanged.
Status stage_error(const Status& s, const char* stage) {
  if (s.is_ok()) return s;
  if (s.code() == StatusCode::kArenaExhausted || s.code() == StatusCode::kCancelled) return s;
  const size_t n = std::strlen(stage);
  if (std::strncmp(s.message(), stage, n) == 0 && std::strncmp(s.message() + n, ": ", 2) == 0) {
    return s;
  }
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

// Jaw j fit to go into B: it has triangles, finite vertices that stay in float32 range where B
// holds them, and vertex ids in range; then *volume is its volume. Names the jaw (index, role).
Status check_jaw(const CaseFile& c, Span<const Mesh> jaws, size_t j, double* volume) {
  const char* role = c.jaws[j].role;
  if (jaws[j].triangles.empty()) {
    return make_error(StatusCode::kInvalidMesh, "design: jaw ", j, " (", role,
                      ") is empty: it has no triangles")
        .at_index(j);
  }
  const uint32_t count = static_cast<uint32_t>(jaws[j].vertices.size());
  for (uint32_t v = 0; v < count; ++v) {
    if (!is_finite(jaws[j].vertices[v])) {
      return make_error(StatusCode::kNonFinite, "design: jaw ", j, " (", role,
                        ") has a vertex that is not finite (NaN or infinity): vertex ", v)
          .at_index(j);
    }
    Vec3 p;
    if (!b_vertex(c, jaws, j, v, &p)) {
      return make_error(StatusCode::kLimitExceeded, "design: jaw ", j, " (", role,
                        ") moved beyond float32 range")
          .at_index(j);
    }
  }
  for (const Triangle& t : jaws[j].triangles) {
    if (t.v[0] >= count || t.v[1] >= count || t.v[2] >= count) {
      return make_error(StatusCode::kInvalidMesh, "design: jaw ", j, " (", role,
                        ") has a triangle that refers to a vertex that does not exist")
          .at_index(j);
    }
  }
  *volume = mesh_volume(jaws[j]);
  return Status::ok();
}

// An inside-out jaw (its triangles facing inward) would be subtracted as its complement. A
// negative volume says so for a closed jaw; an open one (a scan) has no volume to go by, so
// a jaw is refused only when it is closed and consistently oriented once turned over. Measured
// on the jaw as given (a rigid move keeps its volume; B holds only the part near the base).
Status refuse_inside_out(const Context& ctx, const CaseFile& c, const Mesh& jaw, size_t j,
                         double volume) {
  if (!(volume < 0)) return Status::ok();
  ArenaScope scope(*ctx.arena);
  Mesh flipped(ctx.arena);
  if (!flipped.triangles.resize(jaw.triangles.size())) return ctx.arena->exhausted_status();
  for (size_t i = 0; i < jaw.triangles.size(); ++i) {
    const Triangle& t = jaw.triangles[i];
    flipped.triangles[i] = Triangle{{t.v[0], t.v[2], t.v[1]}};
  }
  double unused = 0;
  const Status closed =
      check_closed_oriented(ctx, mesh_view(jaw.vertices.span(), flipped.triangles.span()), &unused);
  if (closed.code() == StatusCode::kArenaExhausted) return closed;
  if (!closed.is_ok()) return Status::ok();
  return make_error(StatusCode::kInvalidMesh, "design: jaw ", j, " (", c.jaws[j].role,
                    ") is inside out: it is closed but its triangles face inward (volume ", volume,
                    " mm^3); reverse their orientation")
      .at_index(j);
}

// The jaws fit to go into B (check_jaw, each jaw in a task of its own on ctx.executor) and
// none inside out; the first jaw that is not, named. Arena: sizeof(Status) + 8 bytes a jaw
// (about 430), returned (and refuse_inside_out's check for a jaw of negative volume).
Status check_jaws(const Context& ctx, const CaseFile& c, Span<const Mesh> jaws) {
  uint64_t nv = 0, nt = 0;
  for (const Mesh& m : jaws) {
    nv += m.vertices.size();
    nt += m.triangles.size();
  }
  if (nv >= (uint64_t{1} << 31) || nt >= (uint64_t{1} << 31)) {
    return make_error(StatusCode::kLimitExceeded, "design: the jaws have ", nt, " triangles and ",
                      nv, " vertices; at most 2^31 each");
  }
  Arena& arena = *ctx.arena;
  ArenaScope scope(arena);
  Status* status = arena.allocate_array<Status>(jaws.size());
  double* volume = arena.allocate_array<double>(jaws.size());
  if (status == nullptr || volume == nullptr) return arena.exhausted_status();
  auto task = [&](uint32_t j) { status[j] = check_jaw(c, jaws, j, &volume[j]); };
  parallel_for_each(ctx.executor, static_cast<uint32_t>(jaws.size()), task);
  for (size_t j = 0; j < jaws.size(); ++j) SPLINTCORE_RETURN_IF_ERROR(status[j]);
  for (size_t j = 0; j < jaws.size(); ++j) {
    SPLINTCORE_RETURN_IF_ERROR(refuse_inside_out(ctx, c, jaws[j], j, volume[j]));
  }
  return Status::ok();
}

// B of the Boolean, from jaws that passed check_jaws: every jaw where B holds it (b_vertex),
// jaw after jaw, only the triangles that can matter to the base minus the jaws: those whose
// corners are not all beyond one side of `keep` (boolean_region), and the vertices they use,
// in their order. Each jaw in a task of its own on ctx.executor, twice (what it keeps, then
// its part of B). Arena: 1 byte per vertex of the jaws (kept: *kept, bit kKeptVertex set for a
// vertex in B, all jaws' vertices in order) and 32 bytes a jaw below B's own arrays, and 4
// bytes per vertex of the jaws while B is filled.
constexpr uint8_t kKeptVertex = 0x80;
Status gather_jaws(const Context& ctx, const CaseFile& c, Span<const Mesh> jaws, const Aabb& keep,
                   Mesh* b, const uint8_t** kept) {
  Arena& arena = *ctx.arena;
  struct Part {
    size_t first;                // of the jaw's vertices in `code` (all jaws' in order)
    size_t vertices, triangles;  // kept; then where the jaw's start in B
    uint32_t* index;             // the jaw's vertex -> B's
  };
  const uint32_t n = static_cast<uint32_t>(jaws.size());
  Part* part = arena.allocate_array<Part>(n);
  if (part == nullptr && n > 0) return arena.exhausted_status();
  size_t nv = 0;
  for (uint32_t j = 0; j < n; ++j) {
    part[j].first = nv;
    nv += jaws[j].vertices.size();
  }
  uint8_t* code = arena.allocate_array<uint8_t>(nv);
  if (code == nullptr && nv > 0) return arena.exhausted_status();
  *kept = code;
  // The sides of `keep` each vertex lies beyond, then which vertices the kept triangles use.
  auto mark = [&](uint32_t j) {
    uint8_t* cj = code + part[j].first;
    for (size_t v = 0; v < jaws[j].vertices.size(); ++v) {
      Vec3 p;
      (void)b_vertex(c, jaws, j, v, &p);  // in range: check_jaws
      cj[v] = keep.outcode(p);
    }
    size_t kv = 0, kt = 0;
    for (const Triangle& t : jaws[j].triangles) {
      if ((cj[t.v[0]] & cj[t.v[1]] & cj[t.v[2]] & ~kKeptVertex) != 0) continue;
      for (uint32_t v : t.v) {
        kv += (cj[v] & kKeptVertex) == 0 ? 1 : 0;
        cj[v] |= kKeptVertex;
      }
      ++kt;
    }
    part[j].vertices = kv;
    part[j].triangles = kt;
  };
  parallel_for_each(ctx.executor, n, mark);
  size_t kv = 0, kt = 0;
  for (uint32_t j = 0; j < n; ++j) {
    const size_t v = part[j].vertices, t = part[j].triangles;
    part[j].vertices = kv;
    part[j].triangles = kt;
    kv += v;
    kt += t;
  }
  if (!b->vertices.resize(kv) || !b->triangles.resize(kt)) return arena.exhausted_status();
  ArenaScope scope(arena);
  for (uint32_t j = 0; j < n; ++j) {
    part[j].index = arena.allocate_array<uint32_t>(jaws[j].vertices.size());
    if (part[j].index == nullptr) return arena.exhausted_status();
  }
  auto fill = [&](uint32_t j) {
    const uint8_t* cj = code + part[j].first;
    uint32_t* index = part[j].index;
    size_t next = part[j].vertices;
    for (size_t v = 0; v < jaws[j].vertices.size(); ++v) {
      if ((cj[v] & kKeptVertex) == 0) continue;
      (void)b_vertex(c, jaws, j, v, &b->vertices[next]);
      index[v] = static_cast<uint32_t>(next++);
    }
    Triangle* out = b->triangles.data() + part[j].triangles;
    for (const Triangle& t : jaws[j].triangles) {
      if ((cj[t.v[0]] & cj[t.v[1]] & cj[t.v[2]] & ~kKeptVertex) != 0) continue;
      *out++ = Triangle{{index[t.v[0]], index[t.v[1]], index[t.v[2]]}};
    }
  };
  parallel_for_each(ctx.executor, n, fill);
  return Status::ok();
}

// The same bits in every coordinate (+0 and -0 differ, as they would in the output).
bool same_bits(const Vec3& a, const Vec3& b) {
  const double pa[3] = {a.x, a.y, a.z}, pb[3] = {b.x, b.y, b.z};
  return design_detail::same_bits(pa, pb, 3);
}

// Jaw k's vertices as B holds them (moved by its transform, rounded to float32): the jaw's
// own when that changes no bit (a jaw that does not move, read from STL), else a copy.
Status moved_vertices(const Context& ctx, const CaseFile& c, Span<const Mesh> jaws, size_t k,
                      Span<const Vec3>* out) {
  const Mesh& m = jaws[k];
  bool same = true;
  for (size_t i = 0; i < m.vertices.size() && same; ++i) {
    Vec3 p;
    same = b_vertex(c, jaws, k, i, &p) && same_bits(p, m.vertices[i]);
  }
  if (same) {
    *out = m.vertices.span();
    return Status::ok();
  }
  Vec3* moved = ctx.arena->allocate_array<Vec3>(m.vertices.size());
  if (moved == nullptr) return ctx.arena->exhausted_status();
  for (size_t i = 0; i < m.vertices.size(); ++i) {
    (void)b_vertex(c, jaws, k, i, &moved[i]);  // in range: check_jaws checked it
  }
  *out = Span<const Vec3>(moved, m.vertices.size());
  return Status::ok();
}

// *cut (above `to` in the arena) moved down to `to`, everything above it given back.
void cut_down_to(Arena& arena, const Arena::Marker& to, Mesh* cut) {
  Mesh moved;
  move_mesh_down(arena, to, *cut, &moved);
  *cut = moved;
}

// The sampled sweep's jaws in blockout_one's order (the swept jaw first, then the others) and
// where B holds their vertices (SweepOptions::jaw_vertex): moved as they are read, not copied.
struct SweptJaws {
  const CaseFile* c;
  Span<const Mesh> jaws;
  size_t order[DesignReport::kMaxBlockoutJaws];  // the sweep's jaw k is the design's order[k]

  static Vec3 vertex(const void* user, size_t k, size_t i) {
    const SweptJaws& s = *static_cast<const SweptJaws*>(user);
    Vec3 p;
    (void)b_vertex(*s.c, s.jaws, s.order[k], i, &p);  // in float32 range: check_jaws
    return p;
  }
};

// One jaw's blockout (blockout_jaws), with the exact sweep (`exact`) or the sampled one, run
// with `check` the Boolean's own self-intersection check (the blockout's answer alone) or
// without it; the result moved down to `start` over the jaw's temporaries. The exact sweep
// gets jaw j alone, moved (a copy when the move changes its bits); the sampled one gets every
// jaw, jaw j first with its triangles, the others' vertices only (they anchor its lattice, as
// B's vertices did), moved as it reads them (SweptJaws).
Status blockout_one(const Context& ctx, const CaseFile& c, Span<const Mesh> jaws, size_t j,
                    const Arena::Marker& start, bool exact, bool check, BlockoutSwept* kept,
                    Mesh* cut, DesignReport* report) {
  Mesh swept_jaws[DesignReport::kMaxBlockoutJaws];
  SweptJaws moves{&c, jaws, {}};
  for (size_t k = 0; k < jaws.size(); ++k) {
    const size_t at = k == j ? 0 : (k < j ? k + 1 : k);
    moves.order[at] = k;
    if (exact && k != j) continue;  // an empty mesh
    Span<const Vec3> v = jaws[k].vertices.span();
    if (exact) SPLINTCORE_RETURN_IF_ERROR(moved_vertices(ctx, c, jaws, k, &v));
    swept_jaws[at] = mesh_view(v, k == j ? jaws[k].triangles.span() : Span<const Triangle>());
  }
  const bool mandible = std::strcmp(c.jaws[j].role, "mandible") == 0;
  BlockoutOptions bl;
  bl.sweep = c.blockout;  // voxel, inset, closing radius, offset as the case gives them
  if (!exact) {
    bl.sweep.jaw_vertex = SweptJaws::vertex;
    bl.sweep.jaw_vertex_user = &moves;
  }
  bl.sweep.direction = mandible ? -c.insertion_direction : c.insertion_direction;
  bl.boolean.check_self_intersection = check;
  bl.exact = exact;
  bl.heightfield = c.blockout_method == BlockoutMethod::kHeightfield;
  bl.heightfield_swept = bl.heightfield ? kept : nullptr;
  const bool was_held = kept->held;
  Mesh blocked;
  const Status s = blockout(ctx, *cut, Span<const Mesh>(swept_jaws, jaws.size()), bl, &blocked,
                            &report->blockout[j]);
  if (!s.is_ok()) {
    Status e = stage_error(s, "blockout");
    if (s.code() != StatusCode::kArenaExhausted && s.code() != StatusCode::kCancelled) {
      e.append(" (jaw ").append_u64(j).append(", ").append(c.jaws[j].role).append(")");
    }
    return e;
  }
  report->blockout_removed_mm3[j] = mesh_volume(*cut) - mesh_volume(blocked);
  move_mesh_down(*ctx.arena, start, blocked, cut);
  if (kept->held && !was_held) {  // the swept surface kept after the result: after it again
    move_mesh_down(*ctx.arena, ctx.arena->mark(), kept->mesh, &kept->mesh);
  }
  return Status::ok();
}

// One jaw's blockout as blockout_jaws runs it: blockout_one without the Boolean's check, then
// the result's exact self-intersection check, and on a crossing blockout_one again with it.
// A height field's swept surface is kept after the result for that second run (it would be
// the same surface: the sweep, seconds with a clearance, is not made twice) while the check
// runs, when there is room for it beside the check; else it is given back and the check runs
// again (the check's arrays are what keeps the blockout in 64 MiB).
Status blockout_checked(const Context& ctx, const CaseFile& c, Span<const Mesh> jaws, size_t j,
                        bool exact, Mesh* cut, DesignReport* report) {
  Arena& arena = *ctx.arena;
  const Arena::Marker start = arena.mark();
  const Mesh before = *cut;
  BlockoutSwept kept;
  SPLINTCORE_RETURN_IF_ERROR(
      blockout_one(ctx, c, jaws, j, start, exact, false, &kept, cut, report));
  BooleanStats& bs = report->blockout[j].boolean;
  SelfIntersectionReport si;
  // No swept triangle reached the splint: no Boolean ran, the splint is as it was.
  if (report->blockout[j].swept_triangles > 0) {
    Status s = find_self_intersections(ctx, *cut, 1, &si);
    if (s.code() == StatusCode::kArenaExhausted && kept.held) {
      kept.held = false;
      cut_down_to(arena, start, cut);  // (where it is: only what lay above it is given back)
      si = SelfIntersectionReport{};
      s = find_self_intersections(ctx, *cut, 1, &si);
    }
    SPLINTCORE_RETURN_IF_ERROR(stage_error(s, "blockout"));
  }
  if (si.self_intersecting()) {
    Arena::Marker from = start;
    if (kept.held) {  // the surface down over the result, the second run above it
      move_mesh_down(arena, start, kept.mesh, &kept.mesh);
      from = arena.mark();
    } else {
      arena.rewind(start);
    }
    *cut = before;
    SPLINTCORE_RETURN_IF_ERROR(
        blockout_one(ctx, c, jaws, j, from, exact, true, &kept, cut, report));
    if (kept.held) {
      cut_down_to(arena, start, cut);
    }
  } else {
    if (kept.held) {
      cut_down_to(arena, start, cut);  // the kept surface given back
    }
    if (report->blockout[j].swept_triangles > 0) {
      bs.self_intersection_checked = true;
      bs.self_intersection_candidates = si.candidate_pairs;
    }
  }
  return Status::ok();
}

// The case as "auto" falls back on it: the height field on the voxel's grid (no inset, no
// closing: the parser and sc_case_set_params give "auto" none).
CaseFile heightfield_fallback(const CaseFile& c) {
  CaseFile h = c;
  h.blockout_method = BlockoutMethod::kHeightfield;
  h.blockout.inset = 0;
  h.blockout.closing_radius = 0;
  return h;
}

// Keeps why kAuto fell back (the first refusal's message) in the report, unless it has one.
void note_fallback(const Status& why, DesignReport* report) {
  if (report->blockout_fallback[0] != '\0') return;
  const size_t n = std::min(std::strlen(why.message()), sizeof report->blockout_fallback - 1);
  std::memcpy(report->blockout_fallback, why.message(), n);
  report->blockout_fallback[n] = '\0';
}

// kAuto's fallback for jaw j, whose exact blockout was refused (`why`, the design's first
// refusal): the height field of its swept volume cut from the splint as it is (the height field
// holds the jaw, as the exact sweeps of the others do: no jaw was subtracted). An error then
// says why the height field was tried at all (no report is written for a failed design; the
// Status truncates at its capacity).
Status blockout_with_heightfield(const Context& ctx, const CaseFile& c, Span<const Mesh> jaws,
                                 size_t j, const Status& why, Mesh* cut, DesignReport* report) {
  note_fallback(why, report);
  report->blockout[j] = BlockoutStats{};
  report->blockout_heightfield[j] = true;
  Status s = blockout_checked(ctx, heightfield_fallback(c), jaws, j, false, cut, report);
  if (!s.is_ok()) {
    s.append("; \"auto\" had fallen back to the height field: ").append(why.message());
  }
  return s;
}

// Interference elimination, jaw by jaw: each jaw's part of B swept along the direction it
// leaves the splint (the mandible's is the opposite of the insertion direction), and
// subtracted from *cut, which becomes the result, moved down over the jaw's temporaries (the
// previous one stays below it until the new one is checked, then the new one moves down over
// it, to `low`: *cut must be all the arena holds above `low`). B itself is not needed: the
// sweep gets jaw j's triangles and every jaw's moved vertices (the others' without triangles:
// they only anchor its lattice, as B's vertices did), views of the jaws where moving them
// changes nothing.
// The result's exact self-intersection check (the Boolean's final word, and the largest arrays
// of the blockout: 33 MB for the real dentition's splint) runs once the result has been moved
// down over the sweep, the Boolean's working set and the jaws' moved vertices, as
// subtract_jaws does for the first Boolean: on the real dentition that keeps the blockout in
// 64 MiB. Should it find a crossing, the jaw's blockout runs again with the check inside the
// Boolean (where a crossing makes it nudge and retry): the answer is the blockout's alone.
// On the exact path (report->imprint_swept) each jaw's sweep is exact. With kAuto a jaw whose
// exact sweep is refused (kUnsupported) is passed over, the splint left as it was; once every
// jaw has been tried, the refused ones are made with the height field
// (blockout_with_heightfield), the others staying exact, unless every jaw was refused: then the
// first refusal is returned, and cut_base makes the whole design with the height field (the
// bytes of "heightfield").
Status blockout_jaws(const Context& ctx, const CaseFile& c, Span<const Mesh> jaws,
                     const Arena::Marker& low, Mesh* cut, DesignReport* report) {
  if (jaws.size() > DesignReport::kMaxBlockoutJaws) {
    return make_error(StatusCode::kLimitExceeded, "design: blockout takes at most ",
                      DesignReport::kMaxBlockoutJaws, " jaws, the case has ", jaws.size());
  }
  Arena& arena = *ctx.arena;
  const auto settle = [&](size_t j) {  // jaw j done: its result moved down to `low`
    report->blockout_jaws = std::max(report->blockout_jaws, static_cast<uint32_t>(j + 1));
    note_self_check(report, report->blockout[j].boolean, "blockout");
    // The previous splint is no retry's input any more: the next jaw starts from `low`.
    cut_down_to(arena, low, cut);
  };
  size_t refused[DesignReport::kMaxBlockoutJaws];
  size_t refusals = 0;
  Status first_refusal;
  for (size_t j = 0; j < jaws.size(); ++j) {
    const Arena::Marker start = arena.mark();
    const Mesh before = *cut;
    const bool exact = report->imprint_swept;
    report->blockout_exact[j] = exact;
    const Status s = blockout_checked(ctx, c, jaws, j, exact, cut, report);
    if (!s.is_ok()) {
      if (!exact || c.blockout_method != BlockoutMethod::kAuto ||
          s.code() != StatusCode::kUnsupported) {
        return s;
      }
      arena.rewind(start);
      *cut = before;
      report->blockout[j] = BlockoutStats{};
      report->blockout_exact[j] = false;
      if (refusals == 0) first_refusal = s;
      refused[refusals++] = j;
      continue;
    }
    settle(j);
  }
  if (refusals > 0 && refusals == jaws.size()) return first_refusal;
  for (size_t i = 0; i < refusals; ++i) {
    SPLINTCORE_RETURN_IF_ERROR(
        blockout_with_heightfield(ctx, c, jaws, refused[i], first_refusal, cut, report));
    settle(refused[i]);
  }
  return Status::ok();
}

// The Boolean names an open B's vertex where its border meets the base (issue 30). B is the
// jaws' kept vertices one after another (gather_jaws, `kept`): said again in the design's terms
// (which jaw or scan, its own vertex, where it lies in the case's frame, what to do), within a
// Status's 256 bytes.
Status name_open_jaw(Status s, const CaseFile& c, Span<const Mesh> jaws, const Mesh& b,
                     const uint8_t* kept) {
  if (s.code() != StatusCode::kInvalidMesh || s.index() == kNoPosition ||
      s.index() >= b.vertices.size() || std::strncmp(s.message(), "B is open", 9) != 0) {
    return s;
  }
  const auto um = [](double x) { return std::floor(x * 1000 + 0.5) / 1000; };
  const Vec3& p = b.vertices[static_cast<size_t>(s.index())];
  uint64_t seen = 0;  // B's vertices before the one looked at
  for (size_t j = 0; j < jaws.size(); ++j) {
    for (size_t v = 0; v < jaws[j].vertices.size(); ++v, ++kept) {
      if ((*kept & kKeptVertex) == 0 || seen++ != s.index()) continue;
      const bool scan = c.jaws[j].has_scan;  // a fused jaw is its scan
      return make_error(StatusCode::kInvalidMesh, "B is open: ", scan ? "the scan of " : "", "jaw ",
                        j, " (", c.jaws[j].role, ") has its border inside the base at ",
                        "its vertex ", v, " (", um(p.x), ", ", um(p.y), ", ", um(p.z),
                        "): use a larger ", scan ? "scan" : "surface",
                        ", a smaller outline, or close it first (splintcore prepare)")
          .at_index(j);
    }
  }
  return s;
}

// The label on the outer wall, placed from the base's lines (made as build_case_base makes
// them); the labelled splint's triangles come first, so the final move takes it.
Status label_splint(const Context& ctx, const CaseFile& c, Mesh* cut, DesignReport* report) {
  ArenaArray<Line> upper(ctx.arena), lower(ctx.arena);
  SPLINTCORE_RETURN_IF_ERROR(
      stage_error(make_lines(ctx, c.upper, c.occlusal_normal, "upper", &upper), "design"));
  SPLINTCORE_RETURN_IF_ERROR(
      stage_error(make_lines(ctx, c.lower, c.occlusal_normal, "lower", &lower), "design"));
  const LabelOptions& lo = c.label;
  Mesh labelled;
  SPLINTCORE_RETURN_IF_ERROR(stage_error(
      apply_label(ctx, *cut, upper.span(), lower.span(), lo, &labelled, &report->label), "design"));
  report->labelled = true;
  note_self_check(report, report->label.boolean, "label");
  *cut = labelled;
  return Status::ok();
}

// The Boolean base minus jaws, B being the jaws near the base (gather_jaws over the Boolean's
// region: the same result as with the whole jaws, with less to read, sort and hold). B and the
// base are not needed after it (the blockout takes the jaws themselves), so the result's exact
// self-intersection check (the Boolean's final word, and the largest arrays of the design after
// B) runs once the result has been moved down over them, to `low`: on the real dentition that
// is what keeps the design within 64 MiB. Should that check find a crossing, the Boolean runs
// again with the check inside, where a crossing makes it nudge A and try again: the answer is
// the one the Boolean alone gives. *base is the arena's top at entry, above `low`.
Status subtract_jaws(const Context& ctx, const CaseFile& c, Span<const Mesh> jaws,
                     const Arena::Marker& low, Mesh* base, Mesh* cut, DesignReport* report) {
  Arena& arena = *ctx.arena;
  BooleanOptions bo;
  bo.op = BooleanOp::kDifference;
  bo.check_self_intersection = false;
  const auto subtract = [&]() -> Status {
    Mesh b(&arena);
    const uint8_t* kept = nullptr;
    SPLINTCORE_RETURN_IF_ERROR(gather_jaws(ctx, c, jaws, boolean_region(*base, bo), &b, &kept));
    return stage_error(
        name_open_jaw(mesh_boolean(ctx, *base, b, bo, cut, &report->boolean), c, jaws, b, kept),
        "boolean (base minus jaws)");
  };
  SPLINTCORE_RETURN_IF_ERROR(subtract());
  cut_down_to(arena, low, cut);
  *base = Mesh();
  SelfIntersectionReport si;
  SPLINTCORE_RETURN_IF_ERROR(stage_error(find_self_intersections(ctx, *cut, 1, &si), "boolean"));
  if (si.self_intersecting()) {
    arena.rewind(low);
    *cut = Mesh();
    *base = Mesh(&arena);
    SPLINTCORE_RETURN_IF_ERROR(stage_error(build_case_base(ctx, c, base, &report->base), "base"));
    bo.check_self_intersection = true;
    SPLINTCORE_RETURN_IF_ERROR(subtract());
    *base = Mesh();
  } else {
    report->boolean.self_intersection_checked = true;
    report->boolean.self_intersection_candidates = si.candidate_pairs;
  }
  note_self_check(report, report->boolean, "boolean");
  return Status::ok();
}

// One jaw's scan registered onto the jaw as given (its mesh frame, before the case moves it),
// with the case's thresholds: a fit above max_rms_mm or an overlap below min_overlap is an
// error naming the jaw, both figures and both thresholds; so is a wrong landmark pairing.
Status register_scan(const Context& ctx, const CaseJaw& jaw, size_t j, const Mesh& ct,
                     const Mesh& scan, const Vec3& toward_other_jaw, FusionReport* out) {
  const CaseScan& sc = jaw.scan;
  RegisterOptions ro;
  ro.toward_other_jaw = toward_other_jaw;
  ro.landmarks = sc.landmarks;
  ro.overlap = sc.trim;
  ro.max_rms_mm = sc.max_rms_mm;
  ro.inlier_mm = sc.crowns_within_mm;
  RegisterResult& r = out->registration;
  const Status s = register_rigid(ctx, scan, ct, ro, &r);
  const auto named = [&](StatusCode code) {
    Status e = make_error(code, "design: fusion: jaw ", j, " (", jaw.role, "), scan ", sc.path);
    return e.at_index(j);
  };
  if (s.code() == StatusCode::kArenaExhausted || s.code() == StatusCode::kCancelled) return s;
  if (s.code() == StatusCode::kLimitExceeded || (s.is_ok() && r.overlap < sc.min_overlap)) {
    Status e = named(StatusCode::kLimitExceeded);
    e.append(": the scan does not fit the jaw: RMS ").append_f64(r.rms_mm);
    e.append(" mm (max_rms_mm ").append_f64(sc.max_rms_mm).append("), overlap ");
    e.append_f64(r.overlap).append(" (min_overlap ").append_f64(sc.min_overlap);
    e.append(", the fraction of the scan within crowns_within_mm ");
    e.append_f64(sc.crowns_within_mm).append(" mm of the jaw)");
    return e.append("; check the scan is of this jaw, or give \"landmarks\"");
  }
  if (!s.is_ok()) return named(s.code()).append(": ").append(s.message());
  out->scan_triangles = scan.triangles.size();
  return Status::ok();
}

// The direction from jaw j's vertex centroid to that of the one jaw of the other role
// (maxilla and mandible), both where the case puts them, turned into jaw j's mesh frame (the
// registration's): the way the scan's occlusal side must face. Zero without such a jaw.
Vec3 toward_other_jaw(const CaseFile& c, Span<const Mesh> jaws, size_t j) {
  const bool upper = std::strcmp(c.jaws[j].role, "maxilla") == 0;
  const char* other = upper ? "mandible" : "maxilla";
  if (!upper && std::strcmp(c.jaws[j].role, "mandible") != 0) return Vec3{};
  size_t k = c.jaws.size();
  for (size_t i = 0; i < c.jaws.size(); ++i) {
    if (std::strcmp(c.jaws[i].role, other) != 0) continue;
    if (k != c.jaws.size()) return Vec3{};  // two of them: no one direction
    k = i;
  }
  if (k == c.jaws.size() || jaws[j].vertices.empty() || jaws[k].vertices.empty()) return Vec3{};
  Vec3 centre[2];
  const size_t which[2] = {j, k};
  for (int w = 0; w < 2; ++w) {
    Vec3 sum{};
    for (const Vec3& v : jaws[which[w]].vertices) sum = sum + v;
    const double n = static_cast<double>(jaws[which[w]].vertices.size());
    centre[w] = c.jaws[which[w]].transform.apply_point(sum * (1.0 / n));
  }
  return inverse(c.jaws[j].transform).apply_vector(centre[1] - centre[0]);
}

// Scan-CT fusion: every jaw with a scan registered onto its mesh (register_scan); in *out (the
// case with the jaw list copied into the arena) and fused[] that jaw is its scan, moved by the
// registration and then by the jaw's transform. Within the base the registered scan is the
// jaw's whole surface, so the imprint is the scan's own triangles; its border must lie outside
// the base (the Boolean names the border vertex otherwise: a larger scan or a smaller outline).
// `registered` (per jaw, or null): registrations made already on the same jaws as given.
Status fuse_scans(const Context& ctx, const CaseFile& c, Span<const Mesh> jaws,
                  Span<const Mesh> scans, const FusionReport* registered, CaseFile* out,
                  Mesh* fused, DesignReport* report) {
  *out = c;
  CaseJaw* list = ctx.arena->allocate_array<CaseJaw>(c.jaws.size());
  if (list == nullptr) return ctx.arena->exhausted_status();
  for (size_t j = 0; j < c.jaws.size(); ++j) {
    list[j] = c.jaws[j];
    fused[j] = mesh_view(jaws[j].vertices.span(), jaws[j].triangles.span());
    if (!c.jaws[j].has_scan) continue;
    FusionReport& f = report->fusion[j];
    if (registered != nullptr) {
      f = registered[j];
    } else {
      SPLINTCORE_RETURN_IF_ERROR(
          register_scan(ctx, c.jaws[j], j, jaws[j], scans[j], toward_other_jaw(c, jaws, j), &f));
    }
    f.applied = compose(c.jaws[j].transform, f.registration.transform);
    report->fused[j] = true;
    list[j].transform = f.applied;
    fused[j] = mesh_view(scans[j].vertices.span(), scans[j].triangles.span());
  }
  out->jaws = Span<const CaseJaw>(list, c.jaws.size());
  return Status::ok();
}

}  // namespace

// Checks the scans design_splint takes: none when no jaw has "scan", else one entry per jaw,
// a mesh exactly for the jaws with "scan".
Status design_detail::check_case_scans(const CaseFile& c, Span<const Mesh> scans) {
  size_t first = c.jaws.size();  // the first jaw with a scan
  for (size_t j = c.jaws.size(); j-- > 0;) first = c.jaws[j].has_scan ? j : first;
  if (first == c.jaws.size() && scans.empty()) return Status::ok();
  if (scans.size() != c.jaws.size()) {
    Status e = make_error(StatusCode::kInvalidArgument, "design: ", scans.size(),
                          " scan meshes were given for the case's ", c.jaws.size(),
                          " jaws (one per jaw, empty for a jaw without a scan)");
    if (first < c.jaws.size()) {
      e.append("; jaw ").append_u64(first).append(" (").append(c.jaws[first].role);
      e.append(") has a \"scan\"");
    }
    return e;
  }
  if (c.jaws.size() > DesignReport::kMaxFusedJaws) {
    return make_error(StatusCode::kLimitExceeded, "design: fusion takes at most ",
                      DesignReport::kMaxFusedJaws, " jaws, the case has ", c.jaws.size());
  }
  for (size_t j = 0; j < c.jaws.size(); ++j) {  // first: the meshes come after this
    for (size_t k = 0; k < j && c.jaws[j].has_scan; ++k) {
      if (!c.jaws[k].has_scan || std::strcmp(c.jaws[k].role, c.jaws[j].role) != 0) continue;
      return make_error(StatusCode::kInvalidArgument, "design: jaws ", k, " and ", j,
                        " are both the ", c.jaws[j].role,
                        ", each with a \"scan\": two scans of the same jaw; give "
                        "one scan per jaw (merge them into one mesh, or choose one)")
          .at_index(j);
    }
  }
  for (size_t j = 0; j < c.jaws.size(); ++j) {
    if (c.jaws[j].has_scan && scans[j].triangles.empty()) {
      return make_error(StatusCode::kInvalidMesh, "design: the scan of jaw ", j, " (",
                        c.jaws[j].role, ") is empty: it has no triangles")
          .at_index(j);
    }
    if (!c.jaws[j].has_scan && (!scans[j].triangles.empty() || !scans[j].vertices.empty())) {
      return make_error(StatusCode::kInvalidArgument, "design: a scan mesh was given for jaw ", j,
                        " (", c.jaws[j].role, "), which has no \"scan\" in the case")
          .at_index(j);
    }
  }
  return Status::ok();
}

Status design_detail::register_case_scans(const Context& ctx, const CaseFile& c,
                                          Span<const Mesh> jaws, Span<const Mesh> scans,
                                          bool* fused, FusionReport* fusion) {
  SPLINTCORE_RETURN_IF_ERROR(check_case_scans(c, scans));
  for (size_t j = 0; j < c.jaws.size(); ++j) {
    fused[j] = false;
    if (!c.jaws[j].has_scan) continue;
    SPLINTCORE_RETURN_IF_ERROR(register_scan(ctx, c.jaws[j], j, jaws[j], scans[j],
                                             toward_other_jaw(c, jaws, j), &fusion[j]));
    fusion[j].applied = fusion[j].registration.transform;
    fused[j] = true;
  }
  return Status::ok();
}

namespace {

// The base, the imprint and the blockout, with the exact sweep (`exact`) or without it.
Status cut_base_with(const Context& ctx, const CaseFile& c, Span<const Mesh> jaws, bool exact,
                     Mesh* cut, DesignReport* report) {
  Arena& arena = *ctx.arena;
  const auto stage = [&](const char* name) { return report_progress(ctx, name, 0, 1); };
  const Arena::Marker before_base = arena.mark();
  // The base, then the Boolean: the base's temporaries go, the base stays until the result is
  // moved down over everything.
  SPLINTCORE_RETURN_IF_ERROR(stage("design: base"));
  Mesh base(&arena);
  SPLINTCORE_RETURN_IF_ERROR(stage_error(build_case_base(ctx, c, &base, &report->base), "base"));
  SPLINTCORE_RETURN_IF_ERROR(design_detail::refuse_out_of_reach(ctx, c, jaws, base));
  SPLINTCORE_RETURN_IF_ERROR(
      design_detail::measure_side_walls(ctx, c, jaws, base, report->base, report));
  // Where the splint sits with nothing of use above it (blockout_jaws moves its results there).
  Arena::Marker cut_low = before_base;
  const bool heightfield = c.has_blockout && c.blockout_method == BlockoutMethod::kHeightfield;
  if (c.has_blockout && (c.blockout.offset > 0 || exact || heightfield)) {
    // A spacer: the imprint is the swept volumes' offset surface, which holds each jaw, so
    // subtracting the jaws themselves first would only cut what the blockout removes anyway.
    // The exact swept boundary holds the jaw too: its front triangles are the imprint. The
    // height field lies below the jaw's first contact everywhere: its surface is the imprint.
    report->imprint_offset = c.blockout.offset > 0;
    report->imprint_swept = exact;
    report->imprint_heightfield = heightfield;
    *cut = base;
    cut_low = arena.mark();
  } else {
    SPLINTCORE_RETURN_IF_ERROR(stage("design: boolean"));
    SPLINTCORE_RETURN_IF_ERROR(subtract_jaws(ctx, c, jaws, before_base, &base, cut, report));
  }
  if (c.has_blockout) {
    SPLINTCORE_RETURN_IF_ERROR(stage("design: blockout"));
    SPLINTCORE_RETURN_IF_ERROR(blockout_jaws(ctx, c, jaws, cut_low, cut, report));
  }
  return Status::ok();
}

// cut_base_with with the case's blockout method resolved (CaseFile::blockout_method): the exact
// sweep for kExact and kAuto (never with a clearance). With kAuto a jaw whose exact sweep is
// refused (kUnsupported: its swept surface would cross itself in the splint, a fold would leave
// undercut there, or its Boolean could not resolve a configuration) is made with the height
// field, the other jaws staying exact (blockout_jaws); when every jaw is refused, everything
// from the base is made again with the height field, from where the arena was (the bytes of
// "heightfield"). The report says why (blockout_fallback) and which jaws (blockout_exact,
// blockout_heightfield); if the height field fails too, its error says it.
Status cut_base(const Context& ctx, const CaseFile& c, Span<const Mesh> jaws, Mesh* cut,
                DesignReport* report) {
  Arena& arena = *ctx.arena;
  const Arena::Marker start = arena.mark();
  const bool exact = c.has_blockout && c.blockout.offset == 0 &&
                     c.blockout_method != BlockoutMethod::kVoxel &&
                     c.blockout_method != BlockoutMethod::kHeightfield;
  const Status s = cut_base_with(ctx, c, jaws, exact, cut, report);
  if (s.is_ok() || !exact || c.blockout_method != BlockoutMethod::kAuto ||
      s.code() != StatusCode::kUnsupported) {
    return s;
  }
  arena.rewind(start);
  *cut = Mesh();
  report->base = BaseReport{};
  report->boolean = BooleanStats{};
  for (uint32_t j = 0; j < DesignReport::kMaxBlockoutJaws; ++j) {
    report->blockout[j] = BlockoutStats{};
    report->blockout_removed_mm3[j] = 0;
    report->blockout_exact[j] = report->blockout_heightfield[j] = false;
  }
  report->blockout_jaws = 0;
  report->wall_jaws = 0;
  report->imprint_offset = report->imprint_swept = report->imprint_heightfield = false;
  report->self_intersection_checked = false;
  report->self_intersection_checked_by = "";
  report->self_intersection_candidates = 0;
  note_fallback(s, report);
  Status field = cut_base_with(ctx, heightfield_fallback(c), jaws, false, cut, report);
  // No report is written for a failed design: the error says why the height field was tried at
  // all (after its own text, which says what to do; the Status truncates at its capacity).
  if (!field.is_ok()) {
    field.append("; \"auto\" had fallen back to the height field: ").append(s.message());
  }
  return field;
}

// Checks what design_splint takes before anything is allocated.
Status check_design_inputs(const CaseFile& c, Span<const Mesh> jaws, const Mesh& splint,
                           const PrinterProfile** profile) {
  if (!splint.vertices.empty() || !splint.triangles.empty()) {
    return Status::error(StatusCode::kInvalidArgument, "design_splint: output mesh must be empty");
  }
  if (c.has_plan) {  // its jaws are preoperative: one splint of them would be neither
    return Status::error(StatusCode::kInvalidArgument,
                         "design: the case has a \"plan\": design_plan makes its two splints "
                         "(intermediate and final)");
  }
  if (jaws.size() != c.jaws.size()) {
    return make_error(StatusCode::kInvalidArgument, "design: the case names ", c.jaws.size(),
                      " jaws but ", jaws.size(), " meshes were given");
  }
  if (jaws.empty()) {
    return Status::error(StatusCode::kInvalidArgument,
                         "design: the case has no jaws to subtract (\"jaws\" is empty)");
  }
  *profile = find_printer_profile(c.printer);
  if (*profile == nullptr) {
    return make_error(StatusCode::kInvalidArgument, "design: unknown printer \"", c.printer,
                      "\" (known: eden260)");
  }
  return Status::ok();
}

}  // namespace

Status design_splint(const Context& ctx, const CaseFile& case_given, Span<const Mesh> jaws,
                     Mesh* splint, DesignReport* report) {
  return design_splint(ctx, case_given, jaws, Span<const Mesh>(), splint, report);
}

Status design_splint(const Context& ctx, const CaseFile& case_given, Span<const Mesh> jaws_given,
                     Span<const Mesh> scans, Mesh* splint, DesignReport* report) {
  return design_detail::design_splint_registered(ctx, case_given, jaws_given, scans, nullptr, false,
                                                 splint, report);
}

Status design_detail::design_splint_registered(const Context& ctx, const CaseFile& case_given,
                                               Span<const Mesh> jaws_given, Span<const Mesh> scans,
                                               const FusionReport* registered, bool vetted,
                                               Mesh* splint, DesignReport* report) {
  Arena& arena = *ctx.arena;
  *report = DesignReport{};
  const PrinterProfile* profile = nullptr;
  SPLINTCORE_RETURN_IF_ERROR(check_design_inputs(case_given, jaws_given, *splint, &profile));
  SPLINTCORE_RETURN_IF_ERROR(check_case_scans(case_given, scans));
  report->printer = profile->name;
  ArenaScope scope(arena);  // every error, a cancel included, leaves the arena as it was
  if (!vetted) SPLINTCORE_RETURN_IF_ERROR(refuse_no_jaw(ctx, case_given, jaws_given, scans));
  const auto stage = [&](const char* name) { return report_progress(ctx, name, 0, 1); };
  CaseFile outlined;
  if (case_given.has_auto_outline) {
    SPLINTCORE_RETURN_IF_ERROR(stage("design: outline"));
    Outline o;
    SPLINTCORE_RETURN_IF_ERROR(
        design_detail::resolve_case_outline_vetted(ctx, case_given, jaws_given, &outlined, &o));
    report->outlined = true;
    report->outline = o.report;
  }
  const CaseFile& case_in = case_given.has_auto_outline ? outlined : case_given;
  CaseFile on_tray;
  if (case_in.place_on_tray) {
    SPLINTCORE_RETURN_IF_ERROR(
        stage_error(case_on_tray(ctx, case_in, *profile, &on_tray, &report->tray_translation),
                    "placement on the tray"));
    report->placed_on_tray = true;
  }
  const CaseFile& c_placed = case_in.place_on_tray ? on_tray : case_in;
  for (const Mesh& m : jaws_given) report->jaw_triangles += m.triangles.size();
  // Scan-CT fusion: from here on a jaw with a scan is its registered scan.
  CaseFile fused_case;
  Mesh fused[DesignReport::kMaxFusedJaws];
  bool fusing = false;
  for (const CaseJaw& j : c_placed.jaws) fusing = fusing || j.has_scan;
  if (fusing) {
    SPLINTCORE_RETURN_IF_ERROR(stage("design: fusion"));
    SPLINTCORE_RETURN_IF_ERROR(
        fuse_scans(ctx, c_placed, jaws_given, scans, registered, &fused_case, fused, report));
  }
  const CaseFile& c = fusing ? fused_case : c_placed;
  const Span<const Mesh> jaws = fusing ? Span<const Mesh>(fused, jaws_given.size()) : jaws_given;

  SPLINTCORE_RETURN_IF_ERROR(stage("design: jaws"));
  SPLINTCORE_RETURN_IF_ERROR(check_jaws(ctx, c, jaws));
  SPLINTCORE_RETURN_IF_ERROR(design_detail::refuse_swapped_roles(c, jaws));
  Mesh cut;
  SPLINTCORE_RETURN_IF_ERROR(cut_base(ctx, c, jaws, &cut, report));
  if (c.has_label) {
    SPLINTCORE_RETURN_IF_ERROR(stage("design: label"));
    SPLINTCORE_RETURN_IF_ERROR(label_splint(ctx, c, &cut, report));
  }
  // Shells too small to print apart (under the printer's thinnest wall cubed), the crumbs a
  // Boolean of nearly touching surfaces can leave beside the splint, are taken out and counted.
  const double wall = profile->min_wall_mm;
  SPLINTCORE_RETURN_IF_ERROR(stage_error(
      remove_small_shells(ctx, wall * wall * wall, &cut, &report->crumbs), "crumb removal"));
  if (c.min_thickness > 0) {
    SPLINTCORE_RETURN_IF_ERROR(stage("design: thickness"));
    SPLINTCORE_RETURN_IF_ERROR(stage_error(
        check_wall_thickness(ctx, cut, c.min_thickness, &report->thickness), "thickness check"));
    report->thickness_checked = true;
  }
  SPLINTCORE_RETURN_IF_ERROR(stage("design: printer"));
  PrintCheckOptions pco;
  pco.place_on_tray = true;  // for the fit; the splint moves only with "placement": "tray"
  Status s = check_printable(ctx, cut, *profile, pco, &report->print);
  if (s.is_ok()) s = require_printable(report->print, *profile);
  SPLINTCORE_RETURN_IF_ERROR(stage_error(s, "printer check"));

  // The splint down over the jaws' copy and the base.
  move_mesh_down(arena, scope.start(), cut, splint);
  scope.commit();
  (void)report_progress(ctx, "design: done", 1, 1);  // the splint is made: too late to cancel
  return Status::ok();
}

}  // namespace splintcore
