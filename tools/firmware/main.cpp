// splintcore firmware example: the splint base of a built-in case (and, when the phantom jaws
// are compiled in, the whole design: base minus jaws, printer check) computed in one static
// arena and streamed as binary STL through a sink that hashes the bytes instead of storing
// them, as printer firmware would stream to its print head or storage. Method: Chen et al. 2016
// (EasySplint), as the library implements it; issue 10 (docs/embedding.md).
//
// Runs on QEMU's mps2-an500 (Cortex-M7, bare metal, semihosting: baremetal.c) and as a hosted
// process (hosted.c). The output lines "result <stage> sha256=... bytes=... triangles=...
// arena_high_water=..." are what CI compares with the x86-64 golden hashes
// (fixtures/golden.sha256: base:cases/paper_scale.json, boolean:paper_scale-phantom6000).
//
// Memory: the arena (SPLINTCORE_FIRMWARE_ARENA_BYTES, platform.h) is all the library uses;
// each stage starts from an empty arena and reports its high-water mark. The STL writer's
// buffer comes from the arena too (kStlBufferBytes). Built with -fno-exceptions -fno-rtti; no
// heap anywhere (CI checks the linked image for malloc, operator new, __cxa_*, printf).
#include <cstdint>
#include <cstring>

#include "platform.h"
#include "splintcore/core.h"
#include "splintcore/design.h"
#include "splintcore/io.h"
#include "splintcore/mesh.h"

// The built-in inputs (assets.S).
extern "C" const char fw_case_json[];
extern "C" const uint32_t fw_case_json_size;
#if defined(SPLINTCORE_FIRMWARE_WITH_JAWS)
extern "C" const uint8_t fw_maxilla_stl[];
extern "C" const uint32_t fw_maxilla_stl_size;
extern "C" const uint8_t fw_mandible_stl[];
extern "C" const uint32_t fw_mandible_stl_size;
#endif

namespace {

using namespace splintcore;

constexpr size_t kStlBufferBytes = 4096;  // the STL writer's chunk (from the arena)
#if defined(SPLINTCORE_FIRMWARE_WITH_JAWS)
constexpr size_t kStlReadChunkBytes = 8192;
// The grid of issue 29's firmware row (the case format allows 0.01 .. 1 mm): about 14.0 MB at
// its peak, in the board's 16 MiB PSRAM (docs/embedding.md).
constexpr double kBlockoutVoxelMm = 0.1;
#endif

// ---- text out without printf ------------------------------------------------------------------

class TextLine {
 public:
  TextLine& text(const char* s) {
    while (*s != '\0' && used_ + 1 < sizeof buffer_) buffer_[used_++] = *s++;
    buffer_[used_] = '\0';
    return *this;
  }
  TextLine& u64(uint64_t v) {
    char digits[24];
    size_t n = 0;
    do {
      digits[n++] = static_cast<char>('0' + v % 10);
      v /= 10;
    } while (v != 0);
    char out[24];
    for (size_t i = 0; i < n; ++i) out[i] = digits[n - 1 - i];
    out[n] = '\0';
    return text(out);
  }
  void print() {
    text("\n");
    fw_write(buffer_);
    used_ = 0;
    buffer_[0] = '\0';
  }

 private:
  char buffer_[400] = {};
  size_t used_ = 0;
};

int fail(const char* stage, const Status& s) {
  char message[512];
  s.format(message, sizeof message);
  TextLine()
      .text("error ")
      .text(stage)
      .text(": ")
      .text(status_code_name(s.code()))
      .text(": ")
      .text(message)
      .print();
  return 1;
}

void on_assert(const char* expression, const char* file, int line) {
  TextLine()
      .text("assertion failed: ")
      .text(expression)
      .text(" (")
      .text(file)
      .text(":")
      .u64(static_cast<uint64_t>(line))
      .text(")")
      .print();
  fw_exit(2);
}

// Progress: one line per design stage (the library calls back at least once per bounded amount of
// work; a device would feed a watchdog or a display here, and may return false to cancel).
bool on_progress(void* user, const char* stage, uint64_t, uint64_t) {
  const char** last = static_cast<const char**>(user);
  if (std::strncmp(stage, "design", 6) != 0) return true;  // the pipeline's stages only
  if (*last == nullptr || std::strcmp(*last, stage) != 0) {
    TextLine().text("progress ").text(stage).print();
    *last = stage;
  }
  return true;
}

// ---- the sink: what a device streams to ---------------------------------------------------------
// Nothing is stored: each chunk the STL writer hands over is hashed and counted.
struct StreamingSink {
  Sha256 sha;
  uint64_t bytes = 0;
  uint64_t chunks = 0;
  size_t largest_chunk = 0;

  static bool write(void* user, const uint8_t* data, size_t n) {
    StreamingSink* s = static_cast<StreamingSink*>(user);
    s->sha.update(data, n);
    s->bytes += n;
    ++s->chunks;
    if (n > s->largest_chunk) s->largest_chunk = n;
    return true;
  }
  ByteSink sink() {
    ByteSink k;
    k.write = &StreamingSink::write;
    k.seek = nullptr;  // not seekable: the writer declares the triangle count up front
    k.user = this;
    k.name = "stream";
    return k;
  }
};

// Streams `mesh` as binary STL through a StreamingSink and prints the result line.
Status stream_and_report(const Context& ctx, const char* stage, const Mesh& mesh) {
  StreamingSink out;
  StlWriteOptions options;
  options.format = StlFormat::kBinary;
  options.buffer_bytes = kStlBufferBytes;
  SPLINTCORE_RETURN_IF_ERROR(write_stl(ctx, mesh, out.sink(), options));
  uint8_t digest[32];
  out.sha.finish(digest);
  char hex[65];
  Sha256::to_hex(digest, hex);
  TextLine()
      .text("result ")
      .text(stage)
      .text(" sha256=")
      .text(hex)
      .text(" bytes=")
      .u64(out.bytes)
      .text(" triangles=")
      .u64(mesh.triangles.size())
      .text(" vertices=")
      .u64(mesh.vertices.size())
      .text(" arena_high_water=")
      .u64(ctx.arena->high_water())
      .text(" chunks=")
      .u64(out.chunks)
      .text(" largest_chunk=")
      .u64(out.largest_chunk)
      .print();
  return Status::ok();
}

Status parse_builtin_case(const Context& ctx, CaseFile* c) {
  return parse_case(ctx, fw_case_json, fw_case_json_size, "paper_scale.json", c);
}

// Stage 1: the splint base from the case's picks (spline.h, build_case_base).
Status run_base(Arena& arena, const Progress& progress) {
  arena.reset();
  arena.reset_high_water();
  Context ctx(&arena, nullptr, &progress);
  CaseFile c;
  SPLINTCORE_RETURN_IF_ERROR(parse_builtin_case(ctx, &c));
  TextLine()
      .text("case ")
      .text(c.case_id)
      .text(": ")
      .u64(c.upper.size())
      .text(" upper and ")
      .u64(c.lower.size())
      .text(" lower picks, ")
      .u64(c.jaws.size())
      .text(" jaws")
      .print();
  Mesh base(&arena);
  BaseReport report;
  SPLINTCORE_RETURN_IF_ERROR(build_case_base(ctx, c, &base, &report));
  TextLine()
      .text("base: ")
      .u64(report.sections)
      .text(" sections of ")
      .u64(report.points_per_section)
      .text(" points")
      .print();
  return stream_and_report(ctx, "base", base);
}

#if defined(SPLINTCORE_FIRMWARE_WITH_JAWS)
// Stage 2: the design (design.h, design_splint): jaws read from their STL bytes (as a device
// would receive them), moved by the plan, subtracted from the base by the exact Boolean, the
// result checked for the printer. Stage 3 (`blockout_voxel` > 0): the same with interference
// elimination (blockout.h) on a 0.1 mm grid (kBlockoutVoxelMm), each jaw's swept volume along the
// case's insertion direction subtracted too.
Status run_design(Arena& arena, const Progress& progress, const char* stage,
                  double blockout_voxel) {
  arena.reset();
  arena.reset_high_water();
  Context ctx(&arena, nullptr, &progress);
  CaseFile c;
  SPLINTCORE_RETURN_IF_ERROR(parse_builtin_case(ctx, &c));
  if (blockout_voxel > 0) {
    c.has_blockout = true;
    c.blockout_method = BlockoutMethod::kVoxel;
    c.blockout.voxel = blockout_voxel;
    c.blockout.inset = blockout_voxel / 2;
    c.blockout.closing_radius = 0;
  }
  Mesh jaws[2] = {Mesh(&arena), Mesh(&arena)};
  const uint8_t* data[2] = {fw_maxilla_stl, fw_mandible_stl};
  const uint32_t sizes[2] = {fw_maxilla_stl_size, fw_mandible_stl_size};
  const char* names[2] = {"maxilla.stl", "mandible.stl"};
  for (int j = 0; j < 2; ++j) {
    MemorySource state;
    state.data = data[j];
    state.size = sizes[j];
    StlReadOptions options;
    options.chunk_bytes = kStlReadChunkBytes;
    StlInfo info;
    SPLINTCORE_RETURN_IF_ERROR(
        read_stl_mesh(ctx, memory_source(&state, names[j]), options, &jaws[j], &info));
    TextLine()
        .text("jaw ")
        .text(names[j])
        .text(": ")
        .u64(sizes[j])
        .text(" bytes, ")
        .u64(jaws[j].triangles.size())
        .text(" triangles, ")
        .u64(jaws[j].vertices.size())
        .text(" vertices")
        .print();
  }
  const size_t jaws_used = arena.used();
  Mesh splint(&arena);
  DesignReport report;
  SPLINTCORE_RETURN_IF_ERROR(design_splint(ctx, c, Span<const Mesh>(jaws, 2), &splint, &report));
  TextLine()
      .text(stage)
      .text(": printable ")
      .u64(report.print.printable ? 1 : 0)
      .text(", ")
      .u64(report.boolean.intersecting_pairs)
      .text(" intersecting pairs, boolean attempts ")
      .u64(report.boolean.attempts)
      .text(", blocked-out jaws ")
      .u64(report.blockout_jaws)
      .text(", case and jaws in arena ")
      .u64(jaws_used)
      .text(" bytes")
      .print();
  if (!report.print.printable) {
    return make_error(StatusCode::kInvalidMesh, stage, ": the splint is not printable");
  }
  return stream_and_report(ctx, stage, splint);
}
#endif

}  // namespace

extern "C" int firmware_main(void) {
  set_assert_handler(on_assert);
  TextLine()
      .text("splintcore ")
      .text(library_version())
      .text(" firmware example on ")
      .text(fw_platform_name())
      .print();
  TextLine().text("arena ").u64(fw_arena_bytes()).text(" bytes (static)").print();
  Arena arena(fw_arena(), fw_arena_bytes());
  const char* last_stage = nullptr;
  Progress progress;
  progress.report = on_progress;
  progress.user = &last_stage;

  Status s = run_base(arena, progress);
  if (!s.is_ok()) return fail("base", s);
#if defined(SPLINTCORE_FIRMWARE_WITH_JAWS)
  s = run_design(arena, progress, "design", 0);
  if (!s.is_ok()) return fail("design", s);
  s = run_design(arena, progress, "blockout", kBlockoutVoxelMm);
  if (!s.is_ok()) return fail("blockout", s);
#else
  TextLine().text("design: skipped (built without SPLINTCORE_FIRMWARE_JAWS_DIR)").print();
#endif
  TextLine().text("stack high water ").u64(fw_stack_high_water()).text(" bytes").print();
  TextLine().text("done").print();
  return 0;
}
