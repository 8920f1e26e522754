// splintcore C API (include/splintcore/splintcore.h) on the C++ API of every module: the design
// pipeline of Chen et al. 2016 (EasySplint), "Materials and methods", for C callers and firmware.
// Floor 8. No new/malloc (handles are placed in the caller's arena with placement new on
// trivially destructible types), no exceptions, no printf, no mutable globals: the last status
// is kept in the caller's context.
#include "splintcore/splintcore.h"

#include <cmath>
#include <new>

#include "splintcore/blockout.h"
#include "splintcore/boolean.h"
#include "splintcore/core.h"
#include "splintcore/design.h"
#include "splintcore/io.h"
#include "splintcore/mesh.h"
#include "splintcore/printer.h"
#include "splintcore/registration.h"

using namespace splintcore;

// The opaque handles. A mesh handle is the Mesh itself; a case handle the CaseFile.
struct sc_mesh {
  Mesh mesh;
  const DesignReport* design = nullptr;  // sc_design's record of how it made this mesh
};
struct sc_case {
  CaseFile c;
  Span<const Vec3> arch;  // the outline's arch (sc_outline's resolved cases), for display
};

struct sc_context {
  Arena arena;
  Status last;
  sc_progress_fn progress_fn = nullptr;
  void* progress_user = nullptr;
  Progress progress;
  Executor executor;
  bool has_executor = false;

  sc_context(void* buffer, size_t bytes) : arena(buffer, bytes) {}
};

static_assert(std::is_trivially_destructible<sc_mesh>::value, "handles are never destroyed");
static_assert(std::is_trivially_destructible<sc_case>::value, "handles are never destroyed");
static_assert(sizeof(sc_context) + alignof(sc_context) - 1 <= SC_CONTEXT_BYTES,
              "SC_CONTEXT_BYTES is too small for this platform");
static_assert(static_cast<int>(StatusCode::kInternal) == SC_INTERNAL, "codes mirror StatusCode");
static_assert(static_cast<int>(StatusCode::kArenaExhausted) == SC_ARENA_EXHAUSTED, "codes");
static_assert(static_cast<int>(BlockoutMethod::kAuto) == SC_BLOCKOUT_AUTO &&
                  static_cast<int>(BlockoutMethod::kExact) == SC_BLOCKOUT_EXACT &&
                  static_cast<int>(BlockoutMethod::kVoxel) == SC_BLOCKOUT_VOXEL &&
                  static_cast<int>(BlockoutMethod::kHeightfield) == SC_BLOCKOUT_HEIGHTFIELD,
              "blockout methods mirror BlockoutMethod");
static_assert(static_cast<int>(StatusCode::kInvalidMesh) == SC_INVALID_MESH, "codes");
static_assert(DesignReport::kMaxBlockoutJaws == SC_MAX_BLOCKOUT_JAWS, "report sizes agree");
static_assert(DesignReport::kMaxFusedJaws == SC_MAX_BLOCKOUT_JAWS, "fusion report sizes agree");
static_assert(sizeof(sc_arena_mark) == sizeof(Arena::Marker), "mark mirrors Arena::Marker");

namespace {

// Keeps `s` as the context's last status and returns its code.
sc_status keep(sc_context* ctx, const Status& s) {
  ctx->last = s;
  return static_cast<sc_status>(s.code());
}

sc_status null_argument(sc_context* ctx, const char* function, const char* what) {
  if (ctx == nullptr) return SC_INVALID_ARGUMENT;
  return keep(ctx, make_error(StatusCode::kInvalidArgument, function, ": ", what, " is NULL"));
}

bool c_progress(void* user, const char* stage, uint64_t done, uint64_t total) {
  const sc_context* ctx = static_cast<const sc_context*>(user);
  return ctx->progress_fn(ctx->progress_user, stage, done, total) != 0;
}

Context core_context(sc_context* ctx) {
  return Context(&ctx->arena, ctx->has_executor ? &ctx->executor : nullptr,
                 ctx->progress_fn != nullptr ? &ctx->progress : nullptr);
}

// A placement-constructed T in the arena, or nullptr (the arena then records the need).
template <class T>
T* place(Arena& arena) {
  void* p = arena.allocate(sizeof(T), alignof(T) > 16 ? alignof(T) : 16);
  return p == nullptr ? nullptr : new (p) T();
}

int64_t source_read(void* user, uint8_t* buffer, size_t capacity) {
  const sc_source* s = static_cast<const sc_source*>(user);
  return s->read(s->user, buffer, capacity);
}

ByteSource core_source(const sc_source* s) {
  ByteSource b;
  b.read = &source_read;
  b.user = const_cast<sc_source*>(s);
  b.size = s->size;
  b.name = s->name != nullptr ? s->name : "source";
  return b;
}

bool sink_write(void* user, const uint8_t* data, size_t bytes) {
  const sc_sink* s = static_cast<const sc_sink*>(user);
  return s->write(s->user, data, bytes) != 0;
}
bool sink_seek(void* user, uint64_t offset) {
  const sc_sink* s = static_cast<const sc_sink*>(user);
  return s->seek(s->user, offset) != 0;
}

ByteSink core_sink(const sc_sink* s) {
  ByteSink b;
  b.write = &sink_write;
  b.seek = s->seek != nullptr ? &sink_seek : nullptr;
  b.user = const_cast<sc_sink*>(s);
  b.name = s->name != nullptr ? s->name : "sink";
  return b;
}

int64_t memory_read(void* user, uint8_t* buffer, size_t capacity) {
  sc_memory_source_state* m = static_cast<sc_memory_source_state*>(user);
  const uint64_t left = m->size - m->position;
  const size_t n = left < capacity ? static_cast<size_t>(left) : capacity;
  if (n > 0) std::memcpy(buffer, m->data + m->position, n);
  m->position += n;
  return static_cast<int64_t>(n);
}

int memory_write(void* user, const uint8_t* data, size_t bytes) {
  sc_memory_sink_state* m = static_cast<sc_memory_sink_state*>(user);
  if (m->position > m->capacity || bytes > m->capacity - m->position) return 0;
  if (bytes > 0) std::memcpy(m->data + m->position, data, bytes);
  m->position += bytes;
  if (m->position > m->size) m->size = m->position;
  return 1;
}

int memory_seek(void* user, uint64_t offset) {
  sc_memory_sink_state* m = static_cast<sc_memory_sink_state*>(user);
  if (offset > m->size) return 0;
  m->position = offset;
  return 1;
}

// Copies up to `max` handles' meshes into `out` (shallow: the arrays are shared).
Status gather_meshes(const sc_mesh* const* jaws, size_t count, const char* function, Mesh* out,
                     size_t max) {
  if (count > max) {
    return make_error(StatusCode::kInvalidArgument, function, ": ", static_cast<uint64_t>(count),
                      " meshes given, at most ", static_cast<uint64_t>(max));
  }
  if (count > 0 && jaws == nullptr) {
    return make_error(StatusCode::kInvalidArgument, function, ": the mesh array is NULL");
  }
  for (size_t i = 0; i < count; ++i) {
    if (jaws[i] == nullptr) {
      return make_error(StatusCode::kInvalidArgument, function, ": mesh ", static_cast<uint64_t>(i),
                        " is NULL")
          .at_index(i);
    }
    out[i] = jaws[i]->mesh;
  }
  return Status::ok();
}

// A rigid transform as a row-major 4 x 4 (the last row 0 0 0 1).
void row_major(const RigidTransform& x, double out[16]) {
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) out[4 * i + j] = x.r[i][j];
    out[4 * i + 3] = x.t[i];
  }
  for (int j = 0; j < 4; ++j) out[12 + j] = j == 3 ? 1.0 : 0.0;
}

// Runs `make(mesh)` for a new mesh handle; on failure the arena is as it was and *out NULL.
template <class F>
sc_status new_mesh(sc_context* ctx, sc_mesh** out, F make) {
  *out = nullptr;
  ArenaScope scope(ctx->arena);
  sc_mesh* handle = place<sc_mesh>(ctx->arena);
  if (handle == nullptr) return keep(ctx, ctx->arena.exhausted_status());
  const Status s = make(&handle->mesh);
  if (!s.is_ok()) return keep(ctx, s);
  scope.commit();
  *out = handle;
  return keep(ctx, Status::ok());
}

Vec3 vec(const double d[3]) { return Vec3(d[0], d[1], d[2]); }

constexpr size_t kMaxOperationMeshes = 8;

// The case file's ranges (case_numbers(), design.h), so a set case is one a file could say.
// `key`: the number's place in the case file; `voxel`: the blockout voxel (per-voxel ranges).
// `value` in the case file's range for `key`; errors name `function` and `name`.
Status check_range_of(const char* function, const char* name, double value, const char* key,
                      double voxel) {
  const CaseNumber* n = find_case_number(key);
  SPLINTCORE_ASSERT(n != nullptr);
  double lo = 0, hi = 0;
  case_number_range(*n, voxel, &lo, &hi);
  if (!(value >= lo && value <= hi)) {  // NaN fails too
    return make_error(StatusCode::kInvalidArgument, function, ": ", name, " is ", value,
                      ", must be in [", lo, ", ", hi, "]");
  }
  return Status::ok();
}

Status check_range(const char* name, double value, const char* key, double voxel = 0) {
  return check_range_of("sc_case_set_params", name, value, key, voxel);
}

// A point as the case file takes it: every coordinate finite and within 1e6 mm.
bool in_case_range(const Vec3& p) {
  return std::fabs(p.x) <= 1e6 && std::fabs(p.y) <= 1e6 && std::fabs(p.z) <= 1e6;  // NaN fails
}

// The automatic outline's options (checked when auto_outline is set).
Status check_auto_params(const sc_case_params& p) {
  SPLINTCORE_RETURN_IF_ERROR(check_range("auto_indentation_depth_mm", p.auto_indentation_depth_mm,
                                         "base.auto.indentation_depth_mm"));
  SPLINTCORE_RETURN_IF_ERROR(
      check_range("auto_overhang_mm", p.auto_overhang_mm, "base.auto.overhang_mm"));
  SPLINTCORE_RETURN_IF_ERROR(
      check_range("auto_pick_spacing_mm", p.auto_pick_spacing_mm, "base.auto.pick_spacing_mm"));
  if (p.auto_has_bite_opening != 0) {
    SPLINTCORE_RETURN_IF_ERROR(
        check_range("auto_bite_opening_mm", p.auto_bite_opening_mm, "base.auto.bite_opening_mm"));
  }
  for (int i = 0; i < 2 && p.auto_has_distal_ends != 0; ++i) {
    if (!in_case_range(vec(p.auto_distal_ends[i]))) {
      return make_error(StatusCode::kInvalidArgument, "sc_case_set_params: auto_distal_ends[", i,
                        "] must be finite and within 1e6 mm");
    }
  }
  return Status::ok();
}

Status check_params(const sc_case_params& p, const PrinterProfile** profile) {
  SPLINTCORE_RETURN_IF_ERROR(check_range("spacing_mm", p.spacing_mm, "base.spacing_mm"));
  SPLINTCORE_RETURN_IF_ERROR(
      check_range("max_wall_crossing", p.max_wall_crossing, "max_wall_crossing"));
  SPLINTCORE_RETURN_IF_ERROR(
      check_range("max_sideways_crossing", p.max_sideways_crossing, "max_sideways_crossing"));
  SPLINTCORE_RETURN_IF_ERROR(
      check_range("corner_radius_mm", p.corner_radius_mm, "base.corner_radius_mm"));
  const uint32_t s = p.corner_segments;
  if (s != 1 && s != 2 && s != 4 && s != 8 && s != 16) {
    return make_error(StatusCode::kInvalidArgument, "sc_case_set_params: corner_segments is ", s,
                      ", must be 1, 2, 4, 8 or 16");
  }
  if (p.has_insertion_direction != 0) {
    const Vec3 d = vec(p.insertion_direction);
    if (!is_finite(d) || !(length(d) > 1e-12)) {
      return make_error(StatusCode::kInvalidArgument,
                        "sc_case_set_params: insertion_direction must be finite and non-zero");
    }
  }
  if (p.blockout != 0) {
    if (p.has_insertion_direction == 0 && p.auto_outline == 0) {
      return make_error(StatusCode::kInvalidArgument,
                        "sc_case_set_params: blockout needs insertion_direction (the splint is "
                        "seated along it) or the automatic outline");
    }
    if (p.blockout_method != SC_BLOCKOUT_AUTO && p.blockout_method != SC_BLOCKOUT_EXACT &&
        p.blockout_method != SC_BLOCKOUT_VOXEL && p.blockout_method != SC_BLOCKOUT_HEIGHTFIELD) {
      return make_error(StatusCode::kInvalidArgument, "sc_case_set_params: blockout_method is ",
                        static_cast<int64_t>(p.blockout_method),
                        ", must be SC_BLOCKOUT_AUTO, SC_BLOCKOUT_EXACT, SC_BLOCKOUT_VOXEL or "
                        "SC_BLOCKOUT_HEIGHTFIELD");
    }
    const double v = p.blockout_voxel_mm;
    SPLINTCORE_RETURN_IF_ERROR(check_range("blockout_voxel_mm", v, "blockout.voxel"));
    SPLINTCORE_RETURN_IF_ERROR(
        check_range("blockout_inset_mm", p.blockout_inset_mm, "blockout.inset", v));
    SPLINTCORE_RETURN_IF_ERROR(
        check_range("blockout_closing_mm", p.blockout_closing_mm, "blockout.closing_radius", v));
    if (p.blockout_closing_mm != 0 && p.blockout_closing_mm < 2 * v) {
      return make_error(StatusCode::kInvalidArgument, "sc_case_set_params: blockout_closing_mm is ",
                        p.blockout_closing_mm, ", must be 0 or at least two voxels (", 2 * v, ")");
    }
  }
  if (p.auto_outline != 0) SPLINTCORE_RETURN_IF_ERROR(check_auto_params(p));
  *profile = p.printer != nullptr ? find_printer_profile(p.printer) : nullptr;
  if (*profile == nullptr) {
    return make_error(StatusCode::kInvalidArgument, "sc_case_set_params: unknown printer \"",
                      p.printer != nullptr ? p.printer : "(NULL)", "\"");
  }
  return Status::ok();
}

// A clearance of `mm` with these blockout parameters, as a case file could say it: none, or
// blockout with the voxel method (inset 0) or the height field, within 20 voxels (at most 2 mm).
// Errors name `function` and, when another parameter is in the way, the clearance.
Status check_clearance(const char* function, double mm, const sc_case_params& p) {
  if (mm == 0) return Status::ok();
  SPLINTCORE_RETURN_IF_ERROR(check_range_of(function, "the clearance in mm", mm,
                                            "blockout.clearance", p.blockout_voxel_mm));
  if (p.blockout == 0) {
    return make_error(StatusCode::kInvalidArgument, function, ": a clearance (", mm,
                      " mm) needs blockout (turn it on with sc_case_set_params)");
  }
  if (p.blockout_method != SC_BLOCKOUT_VOXEL && p.blockout_method != SC_BLOCKOUT_HEIGHTFIELD) {
    return make_error(StatusCode::kInvalidArgument, function, ": a clearance (", mm,
                      " mm) needs blockout_method SC_BLOCKOUT_VOXEL or SC_BLOCKOUT_HEIGHTFIELD "
                      "(set the clearance to 0 first with sc_case_set_blockout_clearance)");
  }
  if (p.blockout_method == SC_BLOCKOUT_VOXEL && p.blockout_inset_mm != 0) {
    return make_error(StatusCode::kInvalidArgument, function, ": blockout_inset_mm (",
                      p.blockout_inset_mm, ") and a clearance (", mm,
                      " mm) exclude each other: set one of them to 0");
  }
  return Status::ok();
}

// The case's upper or lower picks, or nullptr (NULL case, unknown `which`).
const Span<const Pick>* case_picks(const sc_case* c, int which) {
  if (c == nullptr) return nullptr;
  if (which == SC_PICKS_UPPER) return &c->c.upper;
  if (which == SC_PICKS_LOWER) return &c->c.lower;
  return nullptr;
}

void put(const Vec3& v, double out[3]) {
  out[0] = v.x;
  out[1] = v.y;
  out[2] = v.z;
}

void copy_outline_report(const OutlineReport& o, sc_outline_report* out) {
  std::memset(out, 0, sizeof(*out));
  put(o.occlusal_normal, out->occlusal_normal);
  put(o.anterior, out->anterior);
  out->gap_as_given_mm = o.gap_as_given;
  out->jaws_intersect = o.jaws_intersect ? 1 : 0;
  out->opened = o.opened ? 1 : 0;
  put(o.mandible_translation, out->mandible_translation_mm);
  out->opening_mm = o.opening;
  out->opening_steps = o.opening_steps;
  out->picks = o.picks;
  out->arch_length_mm = o.arch_length_mm;
  out->wafer_min_mm = o.min_wafer_mm;
  out->wafer_max_mm = o.max_wafer_mm;
  out->occlusal_columns_maxilla = o.cells_upper;
  out->occlusal_columns_mandible = o.cells_lower;
  out->distal_limited = o.distal_limited ? 1 : 0;
  for (int i = 0; i < 2; ++i) {
    out->distal_offset_mm[i] = o.distal_offset_mm[i];
    out->distal_cut_mm[i] = o.distal_cut_mm[i];
  }
  put(o.insertion_direction, out->insertion_direction);
  out->surveyed = o.surveyed ? 1 : 0;
  out->survey_directions = o.survey_directions;
  out->undercut_plain_mm3 = o.undercut_plain_mm3;
  out->undercut_chosen_mm3 = o.undercut_chosen_mm3;
}

void fill_plan_report(const PlanReport& r, const Mesh* splints[2], const Vec3* moves,
                      sc_plan_report* out) {
  std::memset(out, 0, sizeof(*out));
  const PlanSplintReport* parts[2] = {&r.intermediate, &r.final_splint};
  for (int k = 0; k < 2; ++k) {
    const PlanSplintReport& p = *parts[k];
    out->angle_rad[k] = p.autorotation.angle_rad;
    out->opening_mm[k] = p.autorotation.opening;
    out->triangles[k] = splints[k]->triangles.size();
    out->volume_mm3[k] = p.design.print.mesh.volume;
    out->printable[k] = p.design.print.printable ? 1 : 0;
    out->outlined[k] = p.design.outlined ? 1 : 0;
    static_assert(sizeof(out->label_text[k]) == sizeof(p.label_text), "label text sizes agree");
    std::memcpy(out->label_text[k], p.label_text, sizeof(p.label_text));
    if (moves != nullptr) {
      out->job_translation_mm[k][0] = moves[k].x;
      out->job_translation_mm[k][1] = moves[k].y;
      out->job_translation_mm[k][2] = moves[k].z;
    }
  }
  out->job_written = moves != nullptr ? 1 : 0;
  // The fusion was made once for both splints: the intermediate's record holds it.
  const DesignReport& d = r.intermediate.design;
  for (int i = 0; i < 2; ++i) {
    if (!d.fused[i]) continue;
    const RegisterResult& f = d.fusion[i].registration;
    out->fused[i] = 1;
    out->fusion_rms_mm[i] = f.rms_mm;
    out->fusion_overlap[i] = f.overlap;
    row_major(f.transform, out->fusion_transform[i]);
  }
}

}  // namespace

extern "C" {

const char* sc_status_name(sc_status code) {
  if (code < SC_OK || code > SC_INTERNAL) return "unknown";
  return status_code_name(static_cast<StatusCode>(code));
}

const char* sc_library_version(void) { return library_version(); }

void sc_set_assert_handler(void (*handler)(const char* expression, const char* file, int line)) {
  set_assert_handler(handler);
}

size_t sc_context_size(void) { return sizeof(sc_context) + alignof(sc_context) - 1; }

sc_status sc_context_init(void* storage, size_t storage_bytes, void* arena_buffer,
                          size_t arena_bytes, sc_context** out) {
  if (out == nullptr) return SC_INVALID_ARGUMENT;
  *out = nullptr;
  if (storage == nullptr || storage_bytes < sc_context_size()) return SC_INVALID_ARGUMENT;
  if (arena_buffer == nullptr && arena_bytes > 0) return SC_INVALID_ARGUMENT;
  const uintptr_t at = reinterpret_cast<uintptr_t>(storage);
  const uintptr_t aligned = (at + alignof(sc_context) - 1) & ~uintptr_t{alignof(sc_context) - 1};
  *out = new (reinterpret_cast<void*>(aligned)) sc_context(arena_buffer, arena_bytes);
  (*out)->progress.report = &c_progress;
  (*out)->progress.user = *out;
  return SC_OK;
}

void sc_context_destroy(sc_context* ctx) {
  if (ctx != nullptr) ctx->~sc_context();
}

void sc_context_set_progress(sc_context* ctx, sc_progress_fn report, void* user) {
  if (ctx == nullptr) return;
  ctx->progress_fn = report;
  ctx->progress_user = user;
}

void sc_context_set_executor(sc_context* ctx, sc_executor_fn run, void* self,
                             uint32_t concurrency) {
  if (ctx == nullptr) return;
  ctx->has_executor = run != nullptr;
  ctx->executor.run = run;  // sc_task_fn and TaskFunction are the same C function type
  ctx->executor.self = self;
  ctx->executor.concurrency = concurrency > 0 ? concurrency : 1;
}

sc_status sc_last_status(const sc_context* ctx) {
  return ctx == nullptr ? SC_INVALID_ARGUMENT : static_cast<sc_status>(ctx->last.code());
}

size_t sc_status_message(const sc_context* ctx, char* out, size_t cap) {
  if (ctx == nullptr) {
    if (cap > 0 && out != nullptr) out[0] = '\0';
    return 0;
  }
  if (ctx->last.is_ok()) {
    static const char kOk[] = "ok";
    if (out != nullptr && cap > 0) {
      const size_t n = cap - 1 < 2 ? cap - 1 : 2;
      std::memcpy(out, kOk, n);
      out[n] = '\0';
    }
    return 2;
  }
  return ctx->last.format(out, out != nullptr ? cap : 0);
}

void sc_status_location(const sc_context* ctx, sc_location* out) {
  if (out == nullptr) return;
  out->byte_offset = out->line = out->column = out->index = SC_NO_POSITION;
  if (ctx == nullptr || ctx->last.is_ok()) return;
  out->byte_offset = ctx->last.byte_offset();
  out->line = ctx->last.line();
  out->column = ctx->last.column();
  out->index = ctx->last.index();
}

size_t sc_arena_used(const sc_context* ctx) { return ctx == nullptr ? 0 : ctx->arena.used(); }
size_t sc_arena_cap(const sc_context* ctx) { return ctx == nullptr ? 0 : ctx->arena.cap(); }
size_t sc_arena_high_water(const sc_context* ctx) {
  return ctx == nullptr ? 0 : ctx->arena.high_water();
}

sc_arena_mark sc_arena_mark_get(const sc_context* ctx) {
  sc_arena_mark m{nullptr, 0, 0};
  if (ctx == nullptr) return m;
  const Arena::Marker a = ctx->arena.mark();
  m.block = a.block;
  m.offset = a.offset;
  m.used = a.used;
  return m;
}

void sc_arena_rewind(sc_context* ctx, sc_arena_mark mark) {
  if (ctx == nullptr) return;
  Arena::Marker a;
  a.block = mark.block;
  a.offset = mark.offset;
  a.used = mark.used;
  ctx->arena.rewind(a);
}

void sc_arena_reset(sc_context* ctx) {
  if (ctx == nullptr) return;
  ctx->arena.reset();
  ctx->arena.reset_high_water();
}

sc_source sc_memory_source(sc_memory_source_state* state, const void* data, size_t size,
                           const char* name) {
  sc_source s{nullptr, nullptr, 0, name};
  if (state == nullptr) return s;
  state->data = static_cast<const uint8_t*>(data);
  state->size = data != nullptr ? size : 0;
  state->position = 0;
  s.read = &memory_read;
  s.user = state;
  s.size = state->size;
  return s;
}

sc_sink sc_memory_sink(sc_memory_sink_state* state, void* buffer, size_t capacity,
                       const char* name) {
  sc_sink s{nullptr, nullptr, nullptr, name};
  if (state == nullptr) return s;
  state->data = static_cast<uint8_t*>(buffer);
  state->capacity = buffer != nullptr ? capacity : 0;
  state->size = 0;
  state->position = 0;
  s.write = &memory_write;
  s.seek = &memory_seek;
  s.user = state;
  return s;
}

void sc_sha256_hex(const void* data, size_t bytes, char out[65]) {
  Sha256 sha;
  if (data != nullptr) sha.update(data, bytes);
  uint8_t digest[32];
  sha.finish(digest);
  Sha256::to_hex(digest, out);
}

sc_stl_read_options sc_stl_read_defaults(void) {
  const StlReadOptions d;
  sc_stl_read_options o;
  o.max_triangles = d.max_triangles;
  o.max_abs_coordinate = d.max_abs_coordinate;
  o.chunk_bytes = d.chunk_bytes;
  return o;
}

sc_status sc_mesh_read_stl(sc_context* ctx, const sc_source* source,
                           const sc_stl_read_options* options, sc_mesh** out) {
  if (ctx == nullptr || out == nullptr) return null_argument(ctx, "sc_mesh_read_stl", "out");
  *out = nullptr;
  if (source == nullptr || source->read == nullptr) {
    return null_argument(ctx, "sc_mesh_read_stl", "the source or its read function");
  }
  StlReadOptions o;
  if (options != nullptr) {
    o.max_triangles = options->max_triangles;
    o.max_abs_coordinate = options->max_abs_coordinate;
    o.chunk_bytes = options->chunk_bytes;
    if (o.chunk_bytes == 0) {
      return keep(ctx, make_error(StatusCode::kInvalidArgument,
                                  "sc_mesh_read_stl: chunk_bytes must be > 0"));
    }
  }
  ByteSource src = core_source(source);
  // An sc_memory_source is read as the library's memory_source (a sized binary STL is then
  // welded where it lies, with no copy); its position is left where reading left it.
  sc_memory_source_state* state =
      source->read == &memory_read ? static_cast<sc_memory_source_state*>(source->user) : nullptr;
  MemorySource memory;
  if (state != nullptr) {
    memory = MemorySource{state->data, state->size, state->position, 0};
    src = memory_source(&memory, src.name);
    src.size = source->size;
  }
  const Context core = core_context(ctx);
  const sc_status st = new_mesh(ctx, out, [&](Mesh* m) {
    m->bind(&ctx->arena);
    return read_stl_mesh(core, src, o, m, nullptr);
  });
  if (state != nullptr) state->position = memory.position;
  return st;
}

sc_status sc_mesh_from_arrays(sc_context* ctx, const double* vertices, uint32_t vertex_count,
                              const uint32_t* triangles, uint32_t triangle_count, sc_mesh** out) {
  if (ctx == nullptr || out == nullptr) return null_argument(ctx, "sc_mesh_from_arrays", "out");
  *out = nullptr;
  if ((vertices == nullptr && vertex_count > 0) || (triangles == nullptr && triangle_count > 0)) {
    return null_argument(ctx, "sc_mesh_from_arrays", "an array with a non-zero count");
  }
  for (uint32_t i = 0; i < vertex_count; ++i) {
    const double* q = vertices + 3 * static_cast<size_t>(i);
    if (!is_finite(Vec3(q[0], q[1], q[2]))) {
      return keep(ctx, make_error(StatusCode::kNonFinite, "sc_mesh_from_arrays: vertex ", i,
                                  " is not finite")
                           .at_index(i));
    }
  }
  for (uint32_t t = 0; t < triangle_count; ++t) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t id = triangles[3 * size_t{t} + static_cast<size_t>(k)];
      if (id >= vertex_count) {
        return keep(ctx, make_error(StatusCode::kInvalidArgument, "sc_mesh_from_arrays: triangle ",
                                    t, " uses vertex ", id, " of ", vertex_count)
                             .at_index(t));
      }
    }
  }
  return new_mesh(ctx, out, [&](Mesh* m) {
    m->bind(&ctx->arena);
    // Triangles first, then vertices: the order the rest of the library allocates meshes in.
    if (!m->triangles.resize(triangle_count) || !m->vertices.resize(vertex_count)) {
      return ctx->arena.exhausted_status();
    }
    for (uint32_t t = 0; t < triangle_count; ++t) {
      for (int k = 0; k < 3; ++k) {
        m->triangles[t].v[k] = triangles[3 * size_t{t} + static_cast<size_t>(k)];
      }
    }
    for (uint32_t i = 0; i < vertex_count; ++i) {
      const double* q = vertices + 3 * static_cast<size_t>(i);
      m->vertices[i] = Vec3(q[0], q[1], q[2]);
    }
    return Status::ok();
  });
}

uint64_t sc_mesh_vertex_count(const sc_mesh* mesh) {
  return mesh == nullptr ? 0 : mesh->mesh.vertices.size();
}
uint64_t sc_mesh_triangle_count(const sc_mesh* mesh) {
  return mesh == nullptr ? 0 : mesh->mesh.triangles.size();
}

sc_status sc_mesh_copy_vertices(sc_context* ctx, const sc_mesh* mesh, double* out,
                                size_t capacity) {
  if (ctx == nullptr || mesh == nullptr || out == nullptr) {
    return null_argument(ctx, "sc_mesh_copy_vertices", "the mesh or the output");
  }
  const size_t n = mesh->mesh.vertices.size();
  if (capacity / 3 < n) {
    return keep(
        ctx, make_error(StatusCode::kInvalidArgument, "sc_mesh_copy_vertices: the output ",
                        "holds ", static_cast<uint64_t>(capacity), " doubles, ",
                        static_cast<uint64_t>(n), " vertices need ", static_cast<uint64_t>(n) * 3));
  }
  for (size_t i = 0; i < n; ++i) {
    const Vec3& p = mesh->mesh.vertices[i];
    out[3 * i] = p.x;
    out[3 * i + 1] = p.y;
    out[3 * i + 2] = p.z;
  }
  return keep(ctx, Status::ok());
}

sc_status sc_mesh_copy_triangles(sc_context* ctx, const sc_mesh* mesh, uint32_t* out,
                                 size_t capacity) {
  if (ctx == nullptr || mesh == nullptr || out == nullptr) {
    return null_argument(ctx, "sc_mesh_copy_triangles", "the mesh or the output");
  }
  const size_t n = mesh->mesh.triangles.size();
  if (capacity / 3 < n) {
    return keep(ctx, make_error(StatusCode::kInvalidArgument, "sc_mesh_copy_triangles: the output ",
                                "holds ", static_cast<uint64_t>(capacity), " ids, ",
                                static_cast<uint64_t>(n), " triangles need ",
                                static_cast<uint64_t>(n) * 3));
  }
  for (size_t t = 0; t < n; ++t) {
    for (size_t k = 0; k < 3; ++k) out[3 * t + k] = mesh->mesh.triangles[t].v[k];
  }
  return keep(ctx, Status::ok());
}

uint64_t sc_stl_binary_size(uint64_t triangle_count) {
  uint64_t bytes = 0;
  if (!checked_mul(triangle_count, 50, &bytes) || !checked_add(bytes, 84, &bytes)) {
    return UINT64_MAX;
  }
  return bytes;
}

sc_stl_write_options sc_stl_write_defaults(void) {
  const StlWriteOptions d;
  sc_stl_write_options o;
  o.ascii = 0;
  o.buffer_bytes = d.buffer_bytes;
  o.solid_name = nullptr;
  return o;
}

sc_status sc_mesh_write_stl(sc_context* ctx, const sc_mesh* mesh, const sc_sink* sink,
                            const sc_stl_write_options* options) {
  if (ctx == nullptr || mesh == nullptr || sink == nullptr || sink->write == nullptr) {
    return null_argument(ctx, "sc_mesh_write_stl", "the mesh, the sink or its write function");
  }
  StlWriteOptions o;
  if (options != nullptr) {
    o.format = options->ascii != 0 ? StlFormat::kAscii : StlFormat::kBinary;
    o.buffer_bytes = options->buffer_bytes;
    if (options->solid_name != nullptr) o.solid_name = options->solid_name;
    if (o.buffer_bytes == 0) {
      return keep(ctx, make_error(StatusCode::kInvalidArgument,
                                  "sc_mesh_write_stl: buffer_bytes must be > 0"));
    }
    if (o.format == StlFormat::kAscii && !is_plain_name(o.solid_name, 80)) {
      return keep(ctx, make_error(StatusCode::kInvalidArgument, "sc_mesh_write_stl: solid name \"",
                                  o.solid_name, "\" is not 1..80 of A-Z a-z 0-9 _ - ."));
    }
  }
  ArenaScope scope(ctx->arena);
  return keep(ctx, write_stl(core_context(ctx), mesh->mesh, core_sink(sink), o));
}

sc_status sc_mesh_check(sc_context* ctx, const sc_mesh* mesh, sc_mesh_report* out) {
  if (ctx == nullptr || mesh == nullptr || out == nullptr) {
    return null_argument(ctx, "sc_mesh_check", "the mesh or the report");
  }
  std::memset(out, 0, sizeof(*out));
  MeshReport r;
  {
    ArenaScope scope(ctx->arena);
    const Status s = check_mesh(core_context(ctx), mesh->mesh, &r);
    if (!s.is_ok()) return keep(ctx, s);
  }
  out->vertex_count = r.vertex_count;
  out->triangle_count = r.triangle_count;
  out->boundary_edges = r.boundary_edges;
  out->nonmanifold_edges = r.nonmanifold_edges;
  out->orientation_conflicts = r.orientation_conflicts;
  out->degenerate_triangles = r.degenerate_triangles;
  out->duplicate_triangles = r.duplicate_triangles;
  out->shells = r.shells;
  out->genus = r.genus;
  out->area_mm2 = r.area;
  out->volume_mm3 = r.volume;
  const double lo[3] = {r.bounds.lo.x, r.bounds.lo.y, r.bounds.lo.z};
  const double hi[3] = {r.bounds.hi.x, r.bounds.hi.y, r.bounds.hi.z};
  for (int k = 0; k < 3; ++k) {
    out->bounds_min[k] = r.bounds.empty() ? 0.0 : lo[k];
    out->bounds_max[k] = r.bounds.empty() ? 0.0 : hi[k];
  }
  out->closed = r.closed() ? 1 : 0;
  out->manifold = r.edge_manifold() ? 1 : 0;
  out->oriented = r.oriented() ? 1 : 0;
  out->outward = r.outward() ? 1 : 0;
  out->valid_solid = r.is_valid_solid() ? 1 : 0;
  return keep(ctx, Status::ok());
}

sc_status sc_mesh_require_solid(sc_context* ctx, const sc_mesh* mesh) {
  if (ctx == nullptr || mesh == nullptr) return null_argument(ctx, "sc_mesh_require_solid", "mesh");
  MeshReport r;
  ArenaScope scope(ctx->arena);
  const Status s = check_mesh(core_context(ctx), mesh->mesh, &r);
  if (!s.is_ok()) return keep(ctx, s);
  return keep(ctx, require_valid_solid(r));
}

sc_status sc_mesh_boolean(sc_context* ctx, const sc_mesh* a, const sc_mesh* b, int op,
                          sc_mesh** out) {
  if (ctx == nullptr || a == nullptr || b == nullptr || out == nullptr) {
    return null_argument(ctx, "sc_mesh_boolean", "a mesh or the output");
  }
  *out = nullptr;
  if (op < SC_BOOLEAN_DIFFERENCE || op > SC_BOOLEAN_INTERSECTION) {
    return keep(ctx, make_error(StatusCode::kInvalidArgument, "sc_mesh_boolean: unknown op ", op));
  }
  BooleanOptions o;
  o.op = static_cast<BooleanOp>(op);
  const Context core = core_context(ctx);
  return new_mesh(ctx, out, [&](Mesh* m) {
    BooleanStats stats;
    return mesh_boolean(core, a->mesh, b->mesh, o, m, &stats);
  });
}

sc_status sc_sweep(sc_context* ctx, const sc_mesh* const* jaws, size_t jaw_count,
                   const double direction[3], double voxel, sc_mesh** out) {
  if (ctx == nullptr || out == nullptr || direction == nullptr) {
    return null_argument(ctx, "sc_sweep", "the direction or the output");
  }
  *out = nullptr;
  Mesh local[kMaxOperationMeshes];
  Status s = gather_meshes(jaws, jaw_count, "sc_sweep", local, kMaxOperationMeshes);
  if (!s.is_ok()) return keep(ctx, s);
  SweepOptions o;
  o.direction = vec(direction);
  o.voxel = voxel;
  const Context core = core_context(ctx);
  return new_mesh(ctx, out, [&](Mesh* m) {
    return sweep_volume_mesh(core, Span<const Mesh>(local, jaw_count), o, m, nullptr);
  });
}

namespace {

// sc_blockout and sc_blockout_exact: the arguments checked, the jaws gathered, blockout run with
// `o` (its direction set here) into a new mesh.
sc_status blockout_into(sc_context* ctx, const char* name, const sc_mesh* splint,
                        const sc_mesh* const* jaws, size_t jaw_count, const double direction[3],
                        BlockoutOptions o, sc_mesh** out) {
  if (ctx == nullptr || splint == nullptr || out == nullptr || direction == nullptr) {
    return null_argument(ctx, name, "the splint, the direction or the output");
  }
  *out = nullptr;
  Mesh local[kMaxOperationMeshes];
  Status s = gather_meshes(jaws, jaw_count, name, local, kMaxOperationMeshes);
  if (!s.is_ok()) return keep(ctx, s);
  o.sweep.direction = vec(direction);
  const Context core = core_context(ctx);
  return new_mesh(ctx, out, [&](Mesh* m) {
    return blockout(core, splint->mesh, Span<const Mesh>(local, jaw_count), o, m, nullptr);
  });
}

}  // namespace

sc_status sc_blockout(sc_context* ctx, const sc_mesh* splint, const sc_mesh* const* jaws,
                      size_t jaw_count, const double direction[3], double voxel, double inset,
                      sc_mesh** out) {
  BlockoutOptions o;
  o.sweep.voxel = voxel;
  o.sweep.inset = inset;
  return blockout_into(ctx, "sc_blockout", splint, jaws, jaw_count, direction, o, out);
}

sc_status sc_blockout_exact(sc_context* ctx, const sc_mesh* splint, const sc_mesh* const* jaws,
                            size_t jaw_count, const double direction[3], sc_mesh** out) {
  BlockoutOptions o;
  o.exact = true;
  return blockout_into(ctx, "sc_blockout_exact", splint, jaws, jaw_count, direction, o, out);
}

sc_status sc_case_parse(sc_context* ctx, const char* text, size_t length, const char* name,
                        sc_case** out) {
  if (ctx == nullptr || out == nullptr || (text == nullptr && length > 0)) {
    return null_argument(ctx, "sc_case_parse", "the text or the output");
  }
  *out = nullptr;
  ArenaScope scope(ctx->arena);
  sc_case* handle = place<sc_case>(ctx->arena);
  if (handle == nullptr) return keep(ctx, ctx->arena.exhausted_status());
  const Status s = parse_case(core_context(ctx), text != nullptr ? text : "", length,
                              name != nullptr ? name : "case", &handle->c);
  if (!s.is_ok()) return keep(ctx, s);
  scope.commit();
  *out = handle;
  return keep(ctx, Status::ok());
}

const char* sc_case_id(const sc_case* c) { return c == nullptr ? "" : c->c.case_id; }
size_t sc_case_jaw_count(const sc_case* c) { return c == nullptr ? 0 : c->c.jaws.size(); }
const char* sc_case_jaw_role(const sc_case* c, size_t index) {
  if (c == nullptr || index >= c->c.jaws.size()) return nullptr;
  return c->c.jaws[index].role;
}
const char* sc_case_jaw_mesh(const sc_case* c, size_t index) {
  if (c == nullptr || index >= c->c.jaws.size()) return nullptr;
  return c->c.jaws[index].mesh;
}

sc_status sc_case_get_params(sc_context* ctx, const sc_case* c, sc_case_params* out) {
  if (ctx == nullptr || c == nullptr || out == nullptr) {
    return null_argument(ctx, "sc_case_get_params", "the case or the output");
  }
  const CaseFile& f = c->c;
  out->spacing_mm = f.base.spacing_mm;
  out->corner_radius_mm = f.base.corner_radius_mm;
  out->corner_segments = f.base.corner_segments;
  out->has_insertion_direction = f.has_insertion_direction ? 1 : 0;
  out->insertion_direction[0] = f.insertion_direction.x;
  out->insertion_direction[1] = f.insertion_direction.y;
  out->insertion_direction[2] = f.insertion_direction.z;
  out->blockout = f.has_blockout ? 1 : 0;
  out->blockout_voxel_mm = f.blockout.voxel;
  out->blockout_inset_mm = f.blockout.inset;
  out->blockout_closing_mm = f.blockout.closing_radius;
  out->blockout_method = static_cast<int>(f.blockout_method);  // the same numbering
  out->printer = f.printer;
  out->auto_outline = f.has_auto_outline ? 1 : 0;
  out->auto_indentation_depth_mm = f.outline.indentation_depth_mm;
  out->auto_overhang_mm = f.outline.overhang_mm;
  out->auto_pick_spacing_mm = f.outline.pick_spacing_mm;
  out->auto_has_bite_opening = f.outline.has_bite_opening ? 1 : 0;
  out->auto_bite_opening_mm = f.outline.bite_opening_mm;
  out->auto_has_distal_ends = f.outline.has_distal_ends ? 1 : 0;
  for (int i = 0; i < 2; ++i) put(f.outline.distal_ends[i], out->auto_distal_ends[i]);
  out->auto_survey = f.outline.survey ? 1 : 0;
  out->max_wall_crossing = f.max_wall_crossing;
  out->max_sideways_crossing = f.max_sideways_crossing;
  return keep(ctx, Status::ok());
}

sc_status sc_case_set_params(sc_context* ctx, sc_case* c, const sc_case_params* params) {
  if (ctx == nullptr || c == nullptr || params == nullptr) {
    return null_argument(ctx, "sc_case_set_params", "the case or the parameters");
  }
  const PrinterProfile* profile = nullptr;
  Status s = check_params(*params, &profile);
  CaseFile& f = c->c;
  // The case's clearance stays with blockout on (without it, the case has none).
  if (s.is_ok() && params->blockout != 0) {
    s = check_clearance("sc_case_set_params", f.blockout.offset, *params);
  }
  if (!s.is_ok()) return keep(ctx, s);
  if (params->auto_outline == 0 && (f.upper.empty() || f.lower.empty())) {
    return keep(ctx, Status::error(StatusCode::kInvalidArgument,
                                   "sc_case_set_params: auto_outline is off but the case has no "
                                   "picks (resolve it with sc_outline first)"));
  }
  f.base.spacing_mm = params->spacing_mm;
  f.base.corner_radius_mm = params->corner_radius_mm;
  f.base.corner_segments = params->corner_segments;
  f.has_insertion_direction = params->has_insertion_direction != 0;
  if (f.has_insertion_direction) f.insertion_direction = vec(params->insertion_direction);
  f.has_blockout = params->blockout != 0;
  if (!f.has_blockout) f.blockout.offset = 0;
  if (f.has_blockout) {
    f.blockout.voxel = params->blockout_voxel_mm;
    f.blockout.inset = params->blockout_inset_mm;
    f.blockout.closing_radius = params->blockout_closing_mm;
    f.blockout_method = static_cast<BlockoutMethod>(params->blockout_method);
    // The height field (AUTO's fallback too) has no inset and no closing: what the fields
    // hold is not used.
    if (f.blockout_method == BlockoutMethod::kHeightfield ||
        f.blockout_method == BlockoutMethod::kAuto) {
      f.blockout.inset = 0;
      f.blockout.closing_radius = 0;
    }
  }
  f.printer = profile->name;  // static text: the caller's string need not outlive the case
  f.max_wall_crossing = params->max_wall_crossing;
  f.max_sideways_crossing = params->max_sideways_crossing;
  f.has_auto_outline = params->auto_outline != 0;
  if (f.has_auto_outline) {
    f.outline.indentation_depth_mm = params->auto_indentation_depth_mm;
    f.outline.overhang_mm = params->auto_overhang_mm;
    f.outline.pick_spacing_mm = params->auto_pick_spacing_mm;
    f.outline.has_bite_opening = params->auto_has_bite_opening != 0;
    f.outline.bite_opening_mm = f.outline.has_bite_opening ? params->auto_bite_opening_mm : 0;
    f.outline.has_distal_ends = params->auto_has_distal_ends != 0;
    for (int i = 0; i < 2; ++i) {
      f.outline.distal_ends[i] =
          f.outline.has_distal_ends ? vec(params->auto_distal_ends[i]) : Vec3{};
    }
    f.outline.survey = params->auto_survey != 0;
  }
  return keep(ctx, Status::ok());
}

sc_status sc_case_get_blockout_clearance(sc_context* ctx, const sc_case* c, double* out_mm) {
  if (ctx == nullptr || c == nullptr || out_mm == nullptr) {
    return null_argument(ctx, "sc_case_get_blockout_clearance", "the case or the output");
  }
  *out_mm = c->c.has_blockout ? c->c.blockout.offset : 0;
  return keep(ctx, Status::ok());
}

sc_status sc_case_set_blockout_clearance(sc_context* ctx, sc_case* c, double mm) {
  if (ctx == nullptr || c == nullptr) {
    return null_argument(ctx, "sc_case_set_blockout_clearance", "the case");
  }
  sc_case_params p;
  (void)sc_case_get_params(ctx, c, &p);
  const Status s = check_clearance("sc_case_set_blockout_clearance", mm, p);
  if (s.is_ok()) c->c.blockout.offset = mm;
  return keep(ctx, s);
}

sc_status sc_case_write(sc_context* ctx, const sc_case* c, const sc_sink* sink) {
  if (ctx == nullptr || c == nullptr || sink == nullptr || sink->write == nullptr) {
    return null_argument(ctx, "sc_case_write", "the case, the sink or its write function");
  }
  return keep(ctx, write_case(c->c, core_sink(sink)));
}

size_t sc_case_pick_count(const sc_case* c, int which) {
  const Span<const Pick>* picks = case_picks(c, which);
  return picks == nullptr ? 0 : picks->size();
}

int sc_case_pick(const sc_case* c, int which, size_t index, double position[3], double direction[3],
                 double* inner_mm, double* outside_mm) {
  const Span<const Pick>* picks = case_picks(c, which);
  if (picks == nullptr || index >= picks->size()) return 0;
  const Pick& p = (*picks)[index];
  if (position != nullptr) put(p.position, position);
  if (direction != nullptr) put(p.direction, direction);
  if (inner_mm != nullptr) *inner_mm = p.inner_length;
  if (outside_mm != nullptr) *outside_mm = p.outside_length;
  return 1;
}

sc_status sc_case_set_pick(sc_context* ctx, sc_case* c, int which, size_t index,
                           const double position[3], const double direction[3], double inner_mm,
                           double outside_mm) {
  if (ctx == nullptr || c == nullptr) return null_argument(ctx, "sc_case_set_pick", "the case");
  const Span<const Pick>* picks = case_picks(c, which);
  if (picks == nullptr) {
    return keep(ctx, make_error(StatusCode::kInvalidArgument, "sc_case_set_pick: `which` is ",
                                which, ", must be SC_PICKS_UPPER (0) or SC_PICKS_LOWER (1)"));
  }
  if (index >= picks->size()) {
    return keep(ctx, make_error(StatusCode::kInvalidArgument, "sc_case_set_pick: index ", index,
                                " is out of range: the list has ", picks->size(),
                                " picks (an auto case has none until sc_outline)"));
  }
  Pick p = (*picks)[index];
  if (position != nullptr) p.position = vec(position);
  if (direction != nullptr) p.direction = vec(direction);
  if (!in_case_range(p.position) || !in_case_range(p.direction)) {
    return keep(ctx, make_error(StatusCode::kInvalidArgument, "sc_case_set_pick: the ",
                                in_case_range(p.position) ? "direction" : "position",
                                " must be finite and within 1e6 mm"));
  }
  Status s = check_range_of("sc_case_set_pick", "inner_mm", inner_mm, "pick.inner_length_mm", 0);
  if (s.is_ok()) {
    s = check_range_of("sc_case_set_pick", "outside_mm", outside_mm, "pick.outside_length_mm", 0);
  }
  if (!s.is_ok()) return keep(ctx, s);
  p.inner_length = inner_mm;
  p.outside_length = outside_mm;
  // The lists are the case's own (its parse or sc_outline allocated them, writable): only the
  // view is const.
  const_cast<Pick*>(picks->data())[index] = p;
  return keep(ctx, Status::ok());
}

size_t sc_case_arch_count(const sc_case* c) { return c == nullptr ? 0 : c->arch.size(); }

int sc_case_arch_point(const sc_case* c, size_t index, double point[3]) {
  if (c == nullptr || point == nullptr || index >= c->arch.size()) return 0;
  put(c->arch[index], point);
  return 1;
}

sc_status sc_outline(sc_context* ctx, const sc_case* c, const sc_mesh* const* jaws,
                     size_t jaw_count, sc_case** resolved, sc_outline_report* report) {
  if (ctx == nullptr || c == nullptr || resolved == nullptr) {
    return null_argument(ctx, "sc_outline", "the case or the output");
  }
  *resolved = nullptr;
  Mesh local[SC_MAX_BLOCKOUT_JAWS];
  const Status g = gather_meshes(jaws, jaw_count, "sc_outline", local, SC_MAX_BLOCKOUT_JAWS);
  if (!g.is_ok()) return keep(ctx, g);
  ArenaScope scope(ctx->arena);
  sc_case* handle = place<sc_case>(ctx->arena);
  if (handle == nullptr) return keep(ctx, ctx->arena.exhausted_status());
  Outline o;
  const Status s = resolve_case_outline(core_context(ctx), c->c, Span<const Mesh>(local, jaw_count),
                                        &handle->c, &o);
  if (!s.is_ok()) return keep(ctx, s);
  handle->arch = o.arch;
  scope.commit();
  *resolved = handle;
  if (report != nullptr) copy_outline_report(o.report, report);
  return keep(ctx, Status::ok());
}

sc_status sc_design(sc_context* ctx, const sc_case* c, const sc_mesh* const* jaws, size_t jaw_count,
                    sc_mesh** splint, sc_design_report* report) {
  return sc_design_scans(ctx, c, jaws, nullptr, jaw_count, splint, report);
}

sc_status sc_design_scans(sc_context* ctx, const sc_case* c, const sc_mesh* const* jaws,
                          const sc_mesh* const* scans, size_t jaw_count, sc_mesh** splint,
                          sc_design_report* report) {
  const char* function = scans != nullptr ? "sc_design_scans" : "sc_design";
  if (ctx == nullptr || c == nullptr || splint == nullptr) {
    return null_argument(ctx, function, "the case or the output");
  }
  *splint = nullptr;
  Mesh local[SC_MAX_BLOCKOUT_JAWS];
  Status s = gather_meshes(jaws, jaw_count, function, local, SC_MAX_BLOCKOUT_JAWS);
  if (!s.is_ok()) return keep(ctx, s);
  Mesh scan_meshes[SC_MAX_BLOCKOUT_JAWS];  // empty for a jaw without a scan
  if (scans != nullptr) {
    for (size_t i = 0; i < jaw_count; ++i) {
      if (scans[i] != nullptr) scan_meshes[i] = scans[i]->mesh;
    }
  }
  const Span<const Mesh> scan_span(scan_meshes, scans != nullptr ? jaw_count : 0);
  // The handle, then the design's record (kept for sc_design_write_report), then the mesh.
  const Context core = core_context(ctx);
  DesignReport* record = nullptr;
  const sc_status code = new_mesh(ctx, splint, [&](Mesh* m) {
    record = place<DesignReport>(ctx->arena);
    if (record == nullptr) return ctx->arena.exhausted_status();
    return design_splint(core, c->c, Span<const Mesh>(local, jaw_count), scan_span, m, record);
  });
  if (code != SC_OK) return code;
  (*splint)->design = record;
  if (report == nullptr) return code;
  const DesignReport& r = *record;
  std::memset(report, 0, sizeof(*report));
  const Mesh& m = (*splint)->mesh;
  report->jaw_triangles = r.jaw_triangles;
  report->splint_triangles = m.triangles.size();
  report->splint_vertices = m.vertices.size();
  report->splint_volume_mm3 = r.print.mesh.volume;
  report->base_sections = r.base.sections;
  report->base_volume_mm3 = r.base.volume;
  report->boolean_intersecting_pairs = r.boolean.intersecting_pairs;
  report->boolean_intersection_points = r.boolean.intersection_points;
  report->boolean_attempts = r.boolean.attempts;
  report->boolean_nudge_mm[0] = r.boolean.nudge.x;
  report->boolean_nudge_mm[1] = r.boolean.nudge.y;
  report->boolean_nudge_mm[2] = r.boolean.nudge.z;
  report->blockout_jaws = r.blockout_jaws;
  const uint32_t exact_jaws = exact_blockout_jaws(r);
  report->blockout_method_used = r.imprint_heightfield           ? SC_BLOCKOUT_HEIGHTFIELD
                                 : exact_jaws == r.blockout_jaws ? SC_BLOCKOUT_EXACT
                                 : exact_jaws == 0               ? SC_BLOCKOUT_VOXEL
                                                                 : SC_BLOCKOUT_MIXED;
  for (uint32_t i = 0; i < r.blockout_jaws && i < SC_MAX_BLOCKOUT_JAWS; ++i) {
    report->blockout_removed_mm3[i] = r.blockout_removed_mm3[i];
    report->blockout_attempts[i] = r.blockout[i].attempts;
  }
  report->printable = r.print.printable ? 1 : 0;
  report->fits = r.print.fits ? 1 : 0;
  report->fits_rotated = r.print.fits_rotated ? 1 : 0;
  report->extent_mm[0] = r.print.extent.x;
  report->extent_mm[1] = r.print.extent.y;
  report->extent_mm[2] = r.print.extent.z;
  report->layers = r.print.layers;
  report->crumbs_removed = r.crumbs.removed;
  report->crumbs_volume_mm3 = r.crumbs.volume_mm3;
  report->wall_jaws = r.wall_jaws < SC_MAX_BLOCKOUT_JAWS ? r.wall_jaws : SC_MAX_BLOCKOUT_JAWS;
  report->wall_arch_mm = r.wall_jaws > 0 ? r.walls[0].arch_mm : 0;
  for (uint32_t i = 0; i < report->wall_jaws; ++i) {
    report->wall_crossing_mm[i] = r.walls[i].either_mm;
    report->wall_sideways_mm[i] = r.walls[i].sideways_mm();
  }
  report->printer = r.printer;
  report->outlined = r.outlined ? 1 : 0;
  for (size_t i = 0; i < jaw_count && i < DesignReport::kMaxFusedJaws; ++i) {
    if (!r.fused[i]) continue;
    const RegisterResult& f = r.fusion[i].registration;
    report->fused[i] = 1;
    report->fusion_rms_mm[i] = f.rms_mm;
    report->fusion_overlap[i] = f.overlap;
    row_major(f.transform, report->fusion_transform[i]);
  }
  return code;
}

sc_status sc_write_splint_job(sc_context* ctx, const sc_case* c, const sc_mesh* splint,
                              const sc_sink* sink) {
  if (ctx == nullptr || c == nullptr || splint == nullptr || sink == nullptr ||
      sink->write == nullptr) {
    return null_argument(ctx, "sc_write_splint_job", "the case, the splint, the sink or its write");
  }
  ArenaScope scope(ctx->arena);
  return keep(ctx, write_splint_job(core_context(ctx), c->c, splint->mesh, nullptr, core_sink(sink),
                                    nullptr));
}

sc_status sc_design_write_report(sc_context* ctx, const sc_case* c, const sc_mesh* const* jaws,
                                 size_t jaw_count, const sc_mesh* splint,
                                 const sc_report_files* files, const sc_sink* sink) {
  if (ctx == nullptr || c == nullptr || splint == nullptr || sink == nullptr) {
    return null_argument(ctx, "sc_design_write_report", "the case, the splint or the sink");
  }
  if (splint->design == nullptr) {
    return keep(ctx, Status::error(StatusCode::kInvalidArgument,
                                   "sc_design_write_report: the splint was not made by sc_design"));
  }
  Mesh local[SC_MAX_BLOCKOUT_JAWS];
  Status s = gather_meshes(jaws, jaw_count, "sc_design_write_report", local, SC_MAX_BLOCKOUT_JAWS);
  if (!s.is_ok()) return keep(ctx, s);
  DesignReportFiles f;
  if (files != nullptr) {
    f.case_path = files->case_path;
    if (files->jaw_paths != nullptr)
      f.jaw_paths = Span<const char* const>(files->jaw_paths, jaw_count);
    if (files->jaw_sha256 != nullptr)
      f.jaw_sha256 = Span<const char* const>(files->jaw_sha256, jaw_count);
    f.splint_path = files->splint_path;
    f.preview_path = files->preview_path;
    f.preview_sha256 = files->preview_sha256;
  }
  return keep(ctx, write_design_report(core_context(ctx), c->c, Span<const Mesh>(local, jaw_count),
                                       splint->mesh, *splint->design, f, nullptr, core_sink(sink)));
}

sc_status sc_design_blockout_used(sc_context* ctx, const sc_mesh* splint, size_t jaw,
                                  double* lowered_mm, double* clearance_mm) {
  if (ctx == nullptr || splint == nullptr) {
    return null_argument(ctx, "sc_design_blockout_used", "the splint");
  }
  if (splint->design == nullptr) {
    return keep(ctx,
                Status::error(StatusCode::kInvalidArgument,
                              "sc_design_blockout_used: the splint was not made by sc_design"));
  }
  const DesignReport& r = *splint->design;
  if (jaw >= r.blockout_jaws) {
    return keep(ctx, make_error(StatusCode::kInvalidArgument, "sc_design_blockout_used: jaw ",
                                uint64_t{jaw}, " was not blocked out (the design blocked out ",
                                r.blockout_jaws, " jaw(s))"));
  }
  const BlockoutStats& b = r.blockout[jaw];
  if (lowered_mm != nullptr) *lowered_mm = b.inset_used;
  if (clearance_mm != nullptr) *clearance_mm = b.offset_used;
  return keep(ctx, Status::ok());
}

sc_status sc_design_plan(sc_context* ctx, const sc_case* c, const sc_mesh* const* jaws,
                         size_t jaw_count, sc_mesh** intermediate, sc_mesh** final_splint,
                         const sc_sink* job, sc_plan_report* report) {
  return sc_design_plan_scans(ctx, c, jaws, nullptr, jaw_count, intermediate, final_splint, job,
                              report);
}

sc_status sc_design_plan_scans(sc_context* ctx, const sc_case* c, const sc_mesh* const* jaws,
                               const sc_mesh* const* scans, size_t jaw_count,
                               sc_mesh** intermediate, sc_mesh** final_splint, const sc_sink* job,
                               sc_plan_report* report) {
  const char* function = scans != nullptr ? "sc_design_plan_scans" : "sc_design_plan";
  if (ctx == nullptr || c == nullptr || intermediate == nullptr || final_splint == nullptr) {
    return null_argument(ctx, function, "the case or an output");
  }
  *intermediate = nullptr;
  *final_splint = nullptr;
  if (job != nullptr && job->write == nullptr) {
    return null_argument(ctx, function, "the job sink's write function");
  }
  Mesh local[2];
  Status s = gather_meshes(jaws, jaw_count, function, local, 2);
  if (!s.is_ok()) return keep(ctx, s);
  const Context core = core_context(ctx);
  ArenaScope scope(ctx->arena);  // on an error nothing stays
  sc_mesh* handles[2] = {place<sc_mesh>(ctx->arena), place<sc_mesh>(ctx->arena)};
  PlanReport* record = place<PlanReport>(ctx->arena);
  if (handles[0] == nullptr || handles[1] == nullptr || record == nullptr) {
    return keep(ctx, ctx->arena.exhausted_status());
  }
  Mesh scan_meshes[2];  // empty for a jaw without a scan
  for (size_t i = 0; scans != nullptr && i < jaw_count; ++i) {
    if (scans[i] != nullptr) scan_meshes[i] = scans[i]->mesh;
  }
  s = design_plan(core, c->c, Span<const Mesh>(local, jaw_count),
                  Span<const Mesh>(scan_meshes, scans != nullptr ? jaw_count : 0),
                  &handles[0]->mesh, &handles[1]->mesh, record);
  if (!s.is_ok()) return keep(ctx, s);
  Vec3 moves[2];
  if (job != nullptr) {
    s = write_plan_job(core, c->c, handles[0]->mesh, handles[1]->mesh, nullptr, core_sink(job),
                       moves);
    if (!s.is_ok()) return keep(ctx, s);
  }
  scope.commit();
  *intermediate = handles[0];
  *final_splint = handles[1];
  if (report != nullptr) {
    const Mesh* splints[2] = {&handles[0]->mesh, &handles[1]->mesh};
    fill_plan_report(*record, splints, job != nullptr ? moves : nullptr, report);
  }
  return keep(ctx, Status::ok());
}

}  // extern "C"

sc_status sc_register_rigid(sc_context* ctx, const sc_mesh* scan, const sc_mesh* ct_jaw,
                            const sc_register_options* options, sc_register_result* out) {
  if (ctx == nullptr || scan == nullptr || ct_jaw == nullptr || out == nullptr) {
    return null_argument(ctx, "sc_register_rigid", "the scan, the CT jaw or the result");
  }
  std::memset(out, 0, sizeof(*out));
  RegisterOptions o;
  ArenaScope scope(ctx->arena);
  if (options != nullptr) {
    if (options->overlap != 0) o.overlap = options->overlap;
    if (options->max_rms_mm != 0) o.max_rms_mm = options->max_rms_mm;
    if (options->landmark_count > 0) {
      if (options->landmarks == nullptr) {
        return null_argument(ctx, "sc_register_rigid", "the landmarks");
      }
      LandmarkPair* pairs = ctx->arena.allocate_array<LandmarkPair>(options->landmark_count);
      if (pairs == nullptr) return keep(ctx, ctx->arena.exhausted_status());
      for (size_t i = 0; i < options->landmark_count; ++i) {
        pairs[i] =
            LandmarkPair{vec(options->landmarks + 6 * i), vec(options->landmarks + 6 * i + 3)};
      }
      o.landmarks = Span<const LandmarkPair>(pairs, options->landmark_count);
    }
  }
  RegisterResult r;
  const Status s = register_rigid(core_context(ctx), scan->mesh, ct_jaw->mesh, o, &r);
  if (s.is_ok() || s.code() == StatusCode::kLimitExceeded) {
    row_major(r.transform, out->transform);
    out->rms_mm = r.rms_mm;
    out->overlap = r.overlap;
    out->landmark_rms_mm = r.landmark_rms_mm;
    out->iterations = r.iterations;
    out->samples = r.samples;
    out->kept = r.kept;
    out->converged = r.converged ? 1 : 0;
  }
  return s.is_ok() ? SC_OK : keep(ctx, s);
}
