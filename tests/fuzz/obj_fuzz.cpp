// libFuzzer target: arbitrary bytes through the Wavefront OBJ reader (read_obj, and read_mesh's
// format detection), then check_mesh, then a re-write as OBJ text (shortest round-trip numbers,
// negative indices for every other face) that must read back to the same mesh. Any crash,
// sanitizer report, a mesh breaking the reader's contract, or a failed round trip is a bug.
//   cmake -B build/fuzz -DCMAKE_CXX_COMPILER=clang++ -DSPLINTCORE_FUZZ=ON
//   build/fuzz/tests/splintcore_fuzz_obj -max_total_time=60 fixtures/fuzz/obj
// The last byte of the input (when there is more than one) picks the mode, so every seed stays
// a valid file (OBJ ignores a last byte after the final newline only when it is white space or
// part of a comment: seeds end in "\n#" followed by the mode byte): bit 0 hides the source's
// size, bit 1 welds, bit 2 keeps doubles (not with weld), bit 3 reads through read_mesh, bits
// 4-7 the source's chunking.
#include <charconv>
#include <cstdlib>
#include <cstring>
#include <string>

#include "splintcore/io.h"
#include "splintcore/mesh.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace splintcore;
  static unsigned char memory[8 << 20];
  Arena arena(memory, sizeof(memory));
  Context ctx(&arena);
  const uint8_t mode = size > 0 ? data[size - 1] : 0;
  MeshReadOptions options;
  options.max_vertices = 50000;
  options.max_triangles = 50000;
  options.chunk_bytes = 4096;
  options.max_line_bytes = 256;
  options.weld = (mode & 2) != 0;
  options.round_to_float32 = options.weld || (mode & 4) == 0;
  MemorySource ms{data, size, 0, size_t{1} + (mode >> 4) * 5u};
  ByteSource source = memory_source(&ms, "fuzz.obj");
  if ((mode & 1) != 0) source.size = kUnknownSize;
  Mesh mesh;
  MeshReadInfo info;
  const Status s = (mode & 8) != 0 ? read_mesh(ctx, source, options, &mesh, &info)
                                   : read_obj(ctx, source, options, &mesh, &info);
  if (!s.is_ok()) {
    if (arena.used() != 0) std::abort();  // a failed read leaves nothing behind
    return 0;
  }
  for (const Triangle& t : mesh.triangles) {
    for (uint32_t v : t.v) {
      if (v >= mesh.vertices.size()) std::abort();
    }
  }
  for (const Vec3& v : mesh.vertices) {
    if (!is_finite(v)) std::abort();
    for (int a = 0; a < 3; ++a) {
      if (v[a] > options.max_abs_coordinate || v[a] < -options.max_abs_coordinate) std::abort();
    }
  }
  MeshReport report;
  (void)check_mesh(ctx, mesh, &report);
  // Round trip: all vertices first, then the faces (so every index is defined before use).
  std::string out = "# round trip\n";
  char buf[64];
  for (const Vec3& v : mesh.vertices) {
    out += "v";
    for (int a = 0; a < 3; ++a) {
      auto r = std::to_chars(buf, buf + sizeof(buf), v[a]);
      out += " ";
      out.append(buf, r.ptr);
    }
    out += "\n";
  }
  const int64_t n = static_cast<int64_t>(mesh.vertices.size());
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    out += "f";
    for (uint32_t v : mesh.triangles[t].v) {
      const int64_t index = t % 2 == 0 ? int64_t{v} + 1 : int64_t{v} - n;
      out += " " + std::to_string(index) + (t % 3 == 0 ? "//7" : "");
    }
    out += "\n";
  }
  MemorySource again{reinterpret_cast<const uint8_t*>(out.data()), out.size(), 0, 0};
  Mesh back;
  MeshReadOptions back_options = options;
  back_options.weld = false;
  back_options.max_line_bytes = 4096;
  if (!read_obj(ctx, memory_source(&again), back_options, &back, nullptr).is_ok()) std::abort();
  if (back.vertices.size() != mesh.vertices.size() ||
      back.triangles.size() != mesh.triangles.size()) {
    std::abort();
  }
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    const Vec3& a = mesh.vertices[i];
    const Vec3& b = back.vertices[i];
    if (!(a.x == b.x && a.y == b.y && a.z == b.z)) std::abort();
  }
  if (!mesh.triangles.empty() && std::memcmp(mesh.triangles.data(), back.triangles.data(),
                                             mesh.triangles.size() * sizeof(Triangle)) != 0) {
    std::abort();
  }
  return 0;
}
