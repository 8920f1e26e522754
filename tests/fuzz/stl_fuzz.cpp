// libFuzzer target: arbitrary bytes through the STL reader, weld, check and writer, under a
// small arena. Any crash, sanitizer report, or a successful read whose re-written bytes do not
// read back to the same mesh, is a bug.
//   cmake -B build/fuzz -DCMAKE_CXX_COMPILER=clang++ -DSPLINTCORE_FUZZ=ON
//   build/fuzz/tests/splintcore_fuzz_stl -max_total_time=60 fixtures/fuzz/stl
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
  const size_t chunk = size > 0 ? size_t{1} + data[0] % 97u : 0;  // vary the chunking
  MemorySource ms{data, size, 0, chunk};
  Mesh mesh(&arena);
  StlReadOptions options;
  options.max_triangles = 20000;
  if (!read_stl_mesh(ctx, memory_source(&ms), options, &mesh, nullptr).is_ok()) return 0;
  MeshReport report;
  if (!check_mesh(ctx, mesh, &report).is_ok()) return 0;
  MemorySink sink{out, sizeof(out), 0, 0};
  if (!write_stl(ctx, mesh, memory_sink(&sink), StlWriteOptions{}).is_ok()) return 0;
  MemorySource again{out, sink.size, 0, 0};
  Mesh back(&arena);
  if (!read_stl_mesh(ctx, memory_source(&again), options, &back, nullptr).is_ok()) std::abort();
  if (back.triangles.size() != mesh.triangles.size()) std::abort();
  return 0;
}
