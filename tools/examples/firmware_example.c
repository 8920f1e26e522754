/* splintcore from C with static memory only: where a firmware team starts.
 *
 * What it shows, in the order a device would do it:
 *   1. one static arena (kArenaBytes below) and static storage for the context: the library
 *      never calls malloc, so these two buffers are all the memory it will ever touch;
 *   2. an STL read from a memory buffer (here a 10 mm cube compiled in; on a device, a
 *      sc_source whose read() callback pulls chunks from flash, USB or a network stack);
 *   3. the mesh checked (closed, manifold, outward, volume);
 *   4. the mesh written as binary STL into a memory sink (on a device, a sink whose write()
 *      callback pushes to storage or to the printer link);
 *   5. errors read as text with sc_status_message() (this example prints with printf; the
 *      library itself never prints).
 * To start from it: replace the compiled-in cube and the memory sink by your own sc_source /
 * sc_sink callbacks, size kArenaBytes from sc_arena_high_water() on your largest input (a
 * design of the paper-scale case with two 6,000-triangle jaws needs about 10 MB; reading and
 * checking a mesh needs about 100 bytes per triangle plus the read buffer), install an assert
 * handler with sc_set_assert_handler() that logs and resets the device, and link with
 * libsplintcore.a built with -DSPLINTCORE_WITH_PLATFORM=OFF (no files, no threads; see
 * cmake/toolchain-cortex-m7.cmake for a bare-metal build).
 */
#include <stdio.h>
#include <string.h>

#include "splintcore/splintcore.h"

/* The whole memory budget: 32 KiB of arena, and the context's own storage. */
#define kArenaBytes (32u * 1024u)
static unsigned char g_arena[kArenaBytes];
static unsigned char g_context_storage[SC_CONTEXT_BYTES];

/* The output: a binary STL of the cube is 84 + 12 * 50 = 684 bytes. */
static unsigned char g_output[1024];

/* A 10 mm cube, 12 outward triangles, as ASCII STL (facet normals are recomputed on read). */
#define FACET(a, b, c)                                                                \
  " facet normal 0 0 0\n  outer loop\n   vertex " a "\n   vertex " b "\n   vertex " c \
  "\n  endloop\n endfacet\n"
static const char kCubeStl[] = "solid cube\n" FACET("0 0 0", "0 10 0", "10 10 0")
    FACET("0 0 0", "10 10 0", "10 0 0")                                           /* z = 0 */
    FACET("0 0 10", "10 0 10", "10 10 10") FACET("0 0 10", "10 10 10", "0 10 10") /* z = 10 */
    FACET("0 0 0", "10 0 0", "10 0 10") FACET("0 0 0", "10 0 10", "0 0 10")       /* y = 0 */
    FACET("0 10 0", "0 10 10", "10 10 10") FACET("0 10 0", "10 10 10", "10 10 0") /* y = 10 */
    FACET("0 0 0", "0 0 10", "0 10 10") FACET("0 0 0", "0 10 10", "0 10 0")       /* x = 0 */
    FACET("10 0 0", "10 10 0", "10 10 10") FACET("10 0 0", "10 10 10", "10 0 10") /* x = 10 */
    "endsolid cube\n";

static int fail(const sc_context* ctx, const char* what) {
  char message[320];
  sc_status_message(ctx, message, sizeof message);
  printf("%s failed: %s (%s)\n", what, message, sc_status_name(sc_last_status(ctx)));
  return 1;
}

int main(void) {
  sc_context* ctx = NULL;
  sc_memory_source_state in_state;
  sc_memory_sink_state out_state;
  sc_source in;
  sc_sink out;
  sc_stl_read_options read_options = sc_stl_read_defaults();
  sc_stl_write_options write_options = sc_stl_write_defaults();
  sc_mesh* cube = NULL;
  sc_mesh_report report;
  char hash[65];

  if (sc_context_init(g_context_storage, sizeof g_context_storage, g_arena, sizeof g_arena, &ctx) !=
      SC_OK) {
    printf("context storage too small: need %u bytes\n", (unsigned)sc_context_size());
    return 1;
  }
  /* Small I/O buffers: they come from the arena. */
  read_options.chunk_bytes = 1024;
  read_options.max_triangles = 10000;
  write_options.buffer_bytes = 512;

  in = sc_memory_source(&in_state, kCubeStl, sizeof kCubeStl - 1, "cube.stl");
  if (sc_mesh_read_stl(ctx, &in, &read_options, &cube) != SC_OK) return fail(ctx, "read");
  if (sc_mesh_check(ctx, cube, &report) != SC_OK) return fail(ctx, "check");
  printf("read cube.stl: %llu vertices, %llu triangles\n", (unsigned long long)report.vertex_count,
         (unsigned long long)report.triangle_count);
  printf("check: closed %d, manifold %d, outward %d, valid solid %d, volume %.3f mm^3\n",
         report.closed, report.manifold, report.outward, report.valid_solid, report.volume_mm3);
  if (report.valid_solid != 1 || report.volume_mm3 != 1000.0) {
    printf("unexpected: the cube should be a valid solid of 1000 mm^3\n");
    return 1;
  }

  out = sc_memory_sink(&out_state, g_output, sizeof g_output, "output");
  if (sc_mesh_write_stl(ctx, cube, &out, &write_options) != SC_OK) return fail(ctx, "write");
  sc_sha256_hex(g_output, (size_t)out_state.size, hash);
  printf("wrote %llu bytes of binary STL, sha256 %s\n", (unsigned long long)out_state.size, hash);
  if (out_state.size != 84 + 12 * 50) {
    printf("unexpected size\n");
    return 1;
  }

  /* An error, as a device would see one: the output buffer is too small for the STL. */
  out = sc_memory_sink(&out_state, g_output, 100, "small output");
  if (sc_mesh_write_stl(ctx, cube, &out, &write_options) == SC_OK) {
    printf("unexpected: a 100-byte sink held the STL\n");
    return 1;
  }
  (void)fail(ctx, "write to a 100-byte sink (expected)");

  printf("arena: %u bytes, high water %u bytes, in use %u bytes\n", (unsigned)sc_arena_cap(ctx),
         (unsigned)sc_arena_high_water(ctx), (unsigned)sc_arena_used(ctx));
  sc_context_destroy(ctx);
  return 0;
}
