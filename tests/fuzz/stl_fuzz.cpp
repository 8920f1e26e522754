// libFuzzer target: arbitrary bytes through the STL reader (auto-detected, forced binary and
// forced ASCII), exact and tolerance welding, check_mesh, check_closed_oriented and the writer
// (binary and ASCII), under a small arena. Any crash, sanitizer report, or a successful read
// whose re-written bytes do not read back to the same mesh, is a bug.
//   cmake -B build/fuzz -DCMAKE_CXX_COMPILER=clang++ -DSPLINTCORE_FUZZ=ON
//   build/fuzz/tests/splintcore_fuzz_stl -max_total_time=60 fixtures/fuzz/stl
// The last byte of the input (when there is more than one) picks the mode, so every seed
// stays a valid file: bits 0-1 the read format (auto, binary, ASCII, auto), bit 2 the written
// format, bits 3-7 the source's chunking.
#include <cstdlib>
#include <cstring>

#include "splintcore/io.h"
#include "splintcore/mesh.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace splintcore;
  static unsigned char memory[8 << 20];
  static unsigned char out[4 << 20];
  Arena arena(memory, sizeof(memory));
  Context ctx(&arena);
  const uint8_t mode = size > 0 ? data[size - 1] : 0;
  const size_t chunk = size > 0 ? size_t{1} + (mode >> 3) * 3u : 0;  // vary the chunking
  MemorySource ms{data, size, 0, chunk};
  StlReadOptions options;
  options.max_triangles = 20000;
  options.format = (mode & 3) == 1   ? StlFormat::kBinary
                   : (mode & 3) == 2 ? StlFormat::kAscii
                                     : StlFormat::kAuto;
  if ((mode & 3) == 3) options.chunk_bytes = 1024;  // the smallest buffers: refills everywhere
  // The soup, welded two ways.
  ArenaArray<SoupTriangle> soup(&arena);
  if (!read_stl(ctx, memory_source(&ms), options, &soup, nullptr).is_ok()) return 0;
  {
    ArenaScope scope(arena);
    Mesh loose(&arena);
    if (weld_tolerance(ctx, soup.span(), 1e-3, &loose).is_ok()) {
      MeshReport report;
      (void)check_mesh(ctx, loose, &report);
    }
  }
  Mesh mesh(&arena);
  if (!weld_exact(ctx, soup.span(), &mesh).is_ok()) return 0;
  MeshReport report;
  if (!check_mesh(ctx, mesh, &report).is_ok()) return 0;
  double volume = 0;
  (void)check_closed_oriented(ctx, mesh, &volume);
  StlWriteOptions wo;
  wo.format = (mode & 4) != 0 ? StlFormat::kAscii : StlFormat::kBinary;
  MemorySink sink{out, sizeof(out), 0, 0};
  if (!write_stl(ctx, mesh, memory_sink(&sink), wo).is_ok()) return 0;
  MemorySource again{out, sink.size, 0, 0};
  Mesh back(&arena);
  StlReadOptions back_options = options;
  back_options.format = StlFormat::kAuto;
  if (!read_stl_mesh(ctx, memory_source(&again), back_options, &back, nullptr).is_ok()) {
    std::abort();
  }
  if (back.triangles.size() != mesh.triangles.size()) std::abort();
  return 0;
}
