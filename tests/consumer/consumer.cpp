// Builds a box, writes it as binary STL into memory, reads it back, checks it. Exit 0 on success.
#include <cstdio>

#include <splintcore/io.h>
#include <splintcore/mesh.h>
#include <splintcore/printer.h>

int main() {
  using namespace splintcore;
  static unsigned char memory[1 << 20];
  Arena arena(memory, sizeof(memory));
  Context ctx(&arena);
  Mesh box(&arena);
  for (int k = 0; k < 8; ++k) {
    if (!box.vertices.push_back(
            Vec3{(k & 1) ? 10.0 : 0.0, (k & 2) ? 10.0 : 0.0, (k & 4) ? 10.0 : 0.0}))
      return 1;
  }
  const uint32_t faces[12][3] = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                                 {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  for (const auto& f : faces) {
    if (!box.triangles.push_back(Triangle{{f[0], f[1], f[2]}})) return 1;
  }
  static uint8_t bytes[4096];
  MemorySink sink{bytes, sizeof(bytes), 0, 0};
  if (!write_stl(ctx, box, memory_sink(&sink), StlWriteOptions{}).is_ok()) return 2;
  MemorySource source{bytes, sink.size, 0, 0};
  Mesh back(&arena);
  if (!read_stl_mesh(ctx, memory_source(&source), StlReadOptions{}, &back, nullptr).is_ok())
    return 3;
  PrintCheck pc;
  if (!check_printable(ctx, back, eden260_profile(), PrintCheckOptions{}, &pc).is_ok()) return 4;
  std::printf("consumer: volume %.1f mm^3, printable %s\n", pc.mesh.volume,
              pc.printable ? "yes" : "no");
  return pc.printable && pc.mesh.volume == 1000.0 ? 0 : 5;
}
