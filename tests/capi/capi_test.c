/* The C API (include/splintcore/splintcore.h) from plain C99: contexts and arena exhaustion,
 * STL round trips through memory, mesh checks, errors with their location, the refusals of
 * NULL pointers and values out of range, the exact Boolean,
 * the sweep, case parameters, and the whole design of fixtures/cases/paper_scale.json with the
 * 6,000-triangle phantom jaws (written by `splintcore phantom` as a ctest fixture), whose bytes
 * must be the golden splint's; the automatic outline (sc_outline, the resolved case's picks,
 * sc_case_write) on the same jaws, whose auto, resolved and re-read cases design to the same
 * bytes; both splints of the two-jaw surgery case fixtures/cases/plan.json and its print job
 * (sc_design_plan), whose bytes must be the goldens of the C++ design_plan. With glibc,
 * malloc/calloc/realloc are counted while sc_ functions run: the count must stay zero.
 *
 * usage: splintcore_capi_test FIXTURES_DIR [JAWS_DIR [CLI_DESIGN_DIR [CLI_PLAN_DIR]]]
 *        (no JAWS_DIR: the designs are skipped)
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "splintcore/splintcore.h"

/* ---- allocation counting (glibc: the shim forwards to the real allocator) ------------------ */
static int g_counting = 0;
static unsigned long g_allocations = 0;
#if defined(__GLIBC__) && !defined(SPLINTCORE_CAPI_TEST_NO_MALLOC_SHIM)
#define HAVE_MALLOC_SHIM 1
extern void* __libc_malloc(size_t);
extern void* __libc_calloc(size_t, size_t);
extern void* __libc_realloc(void*, size_t);
extern void __libc_free(void*);
void* malloc(size_t n) {
  if (g_counting) ++g_allocations;
  return __libc_malloc(n);
}
void* calloc(size_t n, size_t m) {
  if (g_counting) ++g_allocations;
  return __libc_calloc(n, m);
}
void* realloc(void* p, size_t n) {
  if (g_counting) ++g_allocations;
  return __libc_realloc(p, n);
}
void free(void* p) { __libc_free(p); }
#else
#define HAVE_MALLOC_SHIM 0
#endif

/* ---- a tiny checker ------------------------------------------------------------------------ */
static int g_checks = 0;
static int g_failures = 0;
#define CHECK(cond)                                                            \
  do {                                                                         \
    ++g_checks;                                                                \
    if (!(cond)) {                                                             \
      ++g_failures;                                                            \
      fprintf(stderr, "%s:%d: check failed: %s\n", __FILE__, __LINE__, #cond); \
    }                                                                          \
  } while (0)
#define CHECK_OK(ctx, expr)                                                 \
  do {                                                                      \
    sc_status check_status_ = (expr);                                       \
    ++g_checks;                                                             \
    if (check_status_ != SC_OK) {                                           \
      char check_message_[512];                                             \
      sc_status_message((ctx), check_message_, sizeof check_message_);      \
      ++g_failures;                                                         \
      fprintf(stderr, "%s:%d: %s gave %s: %s\n", __FILE__, __LINE__, #expr, \
              sc_status_name(check_status_), check_message_);               \
    }                                                                       \
  } while (0)

static const char* g_fixtures = ".";

typedef struct Bytes {
  unsigned char* data;
  size_t size;
} Bytes;

static Bytes read_file(const char* folder, const char* name) {
  Bytes b = {NULL, 0};
  char path[1024];
  FILE* f;
  long n;
  snprintf(path, sizeof path, "%s/%s", folder, name);
  f = fopen(path, "rb");
  if (f == NULL) {
    fprintf(stderr, "cannot open %s\n", path);
    return b;
  }
  if (fseek(f, 0, SEEK_END) == 0 && (n = ftell(f)) >= 0 && fseek(f, 0, SEEK_SET) == 0) {
    b.data = (unsigned char*)malloc((size_t)n + 1);
    if (b.data != NULL && fread(b.data, 1, (size_t)n, f) == (size_t)n) {
      b.size = (size_t)n;
    } else {
      free(b.data);
      b.data = NULL;
    }
  }
  fclose(f);
  return b;
}

static int contains(const char* text, const char* part) { return strstr(text, part) != NULL; }

static void last_message(const sc_context* ctx, char* out, size_t cap) {
  sc_status_message(ctx, out, cap);
}

/* A call refused as SC_INVALID_ARGUMENT with a message that contains `part`. */
static int refused_with(const sc_context* ctx, sc_status got, const char* part) {
  char text[512];
  last_message(ctx, text, sizeof text);
  return got == SC_INVALID_ARGUMENT && contains(text, part);
}

/* The context every test uses: storage and arena from the heap here, before counting. Both
 * filled with 0xA5 first, as an embedder's reused buffers hold the last job's bytes (a large
 * malloc is a fresh mapping, all zeros, which would hide a read of memory never written). */
typedef struct Fixture {
  unsigned char* storage;
  unsigned char* arena;
  sc_context* ctx;
} Fixture;

static Fixture open_fixture(size_t arena_bytes) {
  Fixture f;
  f.storage = (unsigned char*)malloc(SC_CONTEXT_BYTES);
  f.arena = (unsigned char*)malloc(arena_bytes > 0 ? arena_bytes : 1);
  memset(f.storage, 0xA5, SC_CONTEXT_BYTES);
  memset(f.arena, 0xA5, arena_bytes > 0 ? arena_bytes : 1);
  f.ctx = NULL;
  /* Deliberately misaligned storage: the context aligns itself. */
  if (sc_context_init(f.storage + 1, SC_CONTEXT_BYTES - 1, f.arena, arena_bytes, &f.ctx) != SC_OK) {
    f.ctx = NULL;
  }
  return f;
}

static void close_fixture(Fixture* f) {
  sc_context_destroy(f->ctx);
  free(f->arena);
  free(f->storage);
}

static sc_status read_mesh(sc_context* ctx, const Bytes* b, const char* name, sc_mesh** out) {
  sc_memory_source_state state;
  sc_source src = sc_memory_source(&state, b->data, b->size, name);
  return sc_mesh_read_stl(ctx, &src, NULL, out);
}

/* ---- tests --------------------------------------------------------------------------------- */

static void test_context(void) {
  unsigned char storage[SC_CONTEXT_BYTES];
  unsigned char arena[64];
  sc_context* ctx = NULL;
  char text[256];
  CHECK(sc_context_size() <= SC_CONTEXT_BYTES);
  CHECK(sc_context_init(storage, 16, arena, sizeof arena, &ctx) == SC_INVALID_ARGUMENT);
  CHECK(ctx == NULL);
  CHECK(sc_context_init(NULL, sizeof storage, arena, sizeof arena, &ctx) == SC_INVALID_ARGUMENT);
  CHECK(sc_context_init(storage, sizeof storage, arena, sizeof arena, NULL) == SC_INVALID_ARGUMENT);
  CHECK(sc_context_init(storage, sizeof storage, arena, sizeof arena, &ctx) == SC_OK);
  CHECK(ctx != NULL);
  CHECK(sc_last_status(ctx) == SC_OK);
  CHECK(sc_status_message(ctx, text, sizeof text) == 2 && strcmp(text, "ok") == 0);
  CHECK(sc_arena_cap(ctx) == sizeof arena);
  CHECK(sc_arena_used(ctx) == 0);
  CHECK(strcmp(sc_status_name(SC_ARENA_EXHAUSTED), "arena_exhausted") == 0);
  CHECK(strcmp(sc_status_name(99), "unknown") == 0);
  CHECK(strlen(sc_library_version()) >= 5);
  /* A NULL argument is a named error kept in the context. */
  {
    sc_mesh* m = (sc_mesh*)storage;
    CHECK(sc_mesh_read_stl(ctx, NULL, NULL, &m) == SC_INVALID_ARGUMENT);
    CHECK(m == NULL);
    last_message(ctx, text, sizeof text);
    CHECK(contains(text, "sc_mesh_read_stl"));
  }
  sc_context_destroy(ctx);
}

static void test_arena_exhaustion(const Bytes* torus) {
  /* How much reading the torus takes, then every cap below it in steps: each read either
   * succeeds or fails cleanly with SC_ARENA_EXHAUSTED, a message naming the need, and the
   * arena back where it was. */
  Fixture big = open_fixture((size_t)8 << 20);
  sc_mesh* mesh = NULL;
  size_t need, cap;
  int failures_seen = 0, tried = 0;
  CHECK_OK(big.ctx, read_mesh(big.ctx, torus, "torus_binary.stl", &mesh));
  need = sc_arena_high_water(big.ctx);
  CHECK(need > 0);
  close_fixture(&big);
  for (cap = 0; cap <= need; cap += need / 37 + 1) {
    Fixture f = open_fixture(cap);
    sc_status s;
    char text[512];
    mesh = (sc_mesh*)&f; /* must be set to NULL on failure */
    g_counting = 1;
    s = read_mesh(f.ctx, torus, "torus_binary.stl", &mesh);
    g_counting = 0;
    ++tried;
    if (s != SC_OK) {
      ++failures_seen;
      CHECK(s == SC_ARENA_EXHAUSTED);
      CHECK(mesh == NULL);
      CHECK(sc_arena_used(f.ctx) == 0);
      CHECK(sc_last_status(f.ctx) == SC_ARENA_EXHAUSTED);
      last_message(f.ctx, text, sizeof text);
      CHECK(contains(text, "need") && contains(text, "bytes"));
    } else {
      CHECK(sc_mesh_triangle_count(mesh) == 2304);
    }
    close_fixture(&f);
  }
  CHECK(tried >= 30);
  CHECK(failures_seen >= 30);
  {
    /* The exact need succeeds. */
    Fixture f = open_fixture(need);
    CHECK_OK(f.ctx, read_mesh(f.ctx, torus, "torus_binary.stl", &mesh));
    close_fixture(&f);
  }
}

/* Meshes x and y of the round trip (2304 triangles, nv vertices) have the same vertices and
 * triangles, copied out into the buffers given. */
static void expect_same_mesh(sc_context* ctx, const sc_mesh* x, const sc_mesh* y, uint64_t nv,
                             double* vx, double* vy, uint32_t* tx, uint32_t* ty) {
  CHECK(sc_mesh_vertex_count(x) == nv && sc_mesh_vertex_count(y) == nv);
  CHECK_OK(ctx, sc_mesh_copy_vertices(ctx, x, vx, 3 * 2000));
  CHECK_OK(ctx, sc_mesh_copy_vertices(ctx, y, vy, 3 * 2000));
  CHECK(memcmp(vx, vy, sizeof(double) * 3 * (size_t)nv) == 0);
  CHECK_OK(ctx, sc_mesh_copy_triangles(ctx, x, tx, 3 * 2304));
  CHECK_OK(ctx, sc_mesh_copy_triangles(ctx, y, ty, 3 * 2304));
  CHECK(memcmp(tx, ty, sizeof(uint32_t) * 3 * 2304) == 0);
}

/* A C source over another that hands out at most 37 bytes a read (not a memory source). */
static int64_t short_read(void* user, uint8_t* buffer, size_t capacity) {
  const sc_source* inner = (const sc_source*)user;
  return inner->read(inner->user, buffer, capacity < 37 ? capacity : 37);
}

static void test_round_trip(const Bytes* torus) {
  Fixture f = open_fixture((size_t)16 << 20);
  sc_mesh *a = NULL, *b = NULL, *c = NULL;
  const size_t stl_size = (size_t)sc_stl_binary_size(2304);
  unsigned char* out1 = (unsigned char*)malloc(stl_size);
  unsigned char* out2 = (unsigned char*)malloc(stl_size);
  unsigned char* ascii = (unsigned char*)malloc((size_t)1 << 20);
  double *va = (double*)malloc(sizeof(double) * 3 * 2000),
         *vb = (double*)malloc(sizeof(double) * 3 * 2000);
  uint32_t *ta = (uint32_t*)malloc(sizeof(uint32_t) * 3 * 2304),
           *tb = (uint32_t*)malloc(sizeof(uint32_t) * 3 * 2304);
  sc_memory_sink_state s1, s2, s3;
  sc_sink k1 = sc_memory_sink(&s1, out1, stl_size, "out1");
  sc_sink k2 = sc_memory_sink(&s2, out2, stl_size, "out2");
  sc_sink k3 = sc_memory_sink(&s3, ascii, (size_t)1 << 20, "ascii");
  sc_sink tiny;
  sc_memory_sink_state s4;
  unsigned char small[100];
  Bytes again, again_ascii;
  uint64_t nv;
  char text[512];
  sc_arena_mark mark;
  sc_stl_write_options ascii_options = sc_stl_write_defaults();

  ascii_options.ascii = 1;
  ascii_options.buffer_bytes = 1000;
  ascii_options.solid_name = "torus";
  CHECK(stl_size == 84 + 50 * 2304);
  g_counting = 1;
  CHECK_OK(f.ctx, read_mesh(f.ctx, torus, "torus_binary.stl", &a));
  nv = sc_mesh_vertex_count(a);
  CHECK(sc_mesh_triangle_count(a) == 2304);
  CHECK(nv > 0 && nv <= 2000);
  CHECK_OK(f.ctx, sc_mesh_write_stl(f.ctx, a, &k1, NULL));
  CHECK(s1.size == stl_size);
  again.data = out1;
  again.size = (size_t)s1.size;
  CHECK_OK(f.ctx, read_mesh(f.ctx, &again, "out1", &b));
  CHECK(sc_mesh_vertex_count(b) == nv);
  CHECK_OK(f.ctx, sc_mesh_write_stl(f.ctx, b, &k2, NULL));
  CHECK(s2.size == s1.size && memcmp(out1, out2, stl_size) == 0);
  /* Copy-out: the same vertices and triangles both ways. */
  expect_same_mesh(f.ctx, a, b, nv, va, vb, ta, tb);
  /* A memory source (welded where its bytes lie) and a source giving 37 bytes a read: the same
   * mesh, and both sources read to their end. */
  {
    sc_memory_source_state whole_state, inner_state;
    sc_source whole = sc_memory_source(&whole_state, torus->data, torus->size, "whole");
    sc_source inner = sc_memory_source(&inner_state, torus->data, torus->size, "inner");
    sc_source chunked = {short_read, NULL, 0, "chunked"};
    sc_mesh *w = NULL, *k = NULL;
    chunked.user = &inner;
    chunked.size = torus->size;
    CHECK_OK(f.ctx, sc_mesh_read_stl(f.ctx, &whole, NULL, &w));
    CHECK_OK(f.ctx, sc_mesh_read_stl(f.ctx, &chunked, NULL, &k));
    CHECK(whole_state.position == torus->size && inner_state.position == torus->size);
    expect_same_mesh(f.ctx, w, k, nv, va, vb, ta, tb);
    CHECK_OK(f.ctx, sc_mesh_copy_vertices(f.ctx, a, va, 3 * 2000));
  }
  CHECK(sc_mesh_copy_vertices(f.ctx, a, va, 5) == SC_INVALID_ARGUMENT);
  last_message(f.ctx, text, sizeof text);
  CHECK(contains(text, "holds 5 doubles"));
  /* ASCII: the same mesh back. */
  CHECK_OK(f.ctx, sc_mesh_write_stl(f.ctx, a, &k3, &ascii_options));
  CHECK(s3.size > stl_size);
  CHECK(memcmp(ascii, "solid torus", 11) == 0);
  again_ascii.data = ascii;
  again_ascii.size = (size_t)s3.size;
  CHECK_OK(f.ctx, read_mesh(f.ctx, &again_ascii, "ascii", &c));
  CHECK(sc_mesh_vertex_count(c) == nv);
  CHECK_OK(f.ctx, sc_mesh_copy_vertices(f.ctx, c, vb, 3 * 2000));
  CHECK(memcmp(va, vb, sizeof(double) * 3 * (size_t)nv) == 0);
  /* A sink that fills up: SC_IO_ERROR, named. */
  tiny = sc_memory_sink(&s4, small, sizeof small, "tiny");
  mark = sc_arena_mark_get(f.ctx);
  CHECK(sc_mesh_write_stl(f.ctx, a, &tiny, NULL) == SC_IO_ERROR);
  CHECK(sc_arena_used(f.ctx) == mark.used);
  last_message(f.ctx, text, sizeof text);
  CHECK(contains(text, "tiny"));
  /* Rewinding past a mesh frees it. */
  sc_arena_rewind(f.ctx, mark);
  CHECK(sc_arena_used(f.ctx) == mark.used);
  g_counting = 0;
  free(out1);
  free(out2);
  free(ascii);
  free(va);
  free(vb);
  free(ta);
  free(tb);
  close_fixture(&f);
}

static void test_errors_with_location(const Bytes* torus) {
  Fixture f = open_fixture((size_t)4 << 20);
  sc_mesh* m = (sc_mesh*)&f;
  Bytes cut;
  sc_location where;
  char text[512];
  sc_memory_source_state state;
  sc_source src;
  sc_stl_read_options options;
  static const char kBadAscii[] =
      "solid x\n facet normal 0 0 0\n  outer loop\n   vertex 0 0 0\n   vertex 1 zero 0\n";

  /* A binary STL cut inside triangle 10: truncated, with the byte offset. The size is not
   * given (a stream), so the reader finds the end where it is. */
  cut.data = torus->data;
  cut.size = 84 + 50 * 10 + 17;
  src = sc_memory_source(&state, cut.data, cut.size, "cut.stl");
  src.size = SC_UNKNOWN_SIZE;
  g_counting = 1;
  CHECK(sc_mesh_read_stl(f.ctx, &src, NULL, &m) == SC_TRUNCATED);
  g_counting = 0;
  CHECK(m == NULL);
  CHECK(sc_arena_used(f.ctx) == 0);
  sc_status_location(f.ctx, &where);
  CHECK(where.byte_offset != SC_NO_POSITION);
  CHECK(where.byte_offset <= cut.size);
  last_message(f.ctx, text, sizeof text);
  CHECK(contains(text, "cut.stl"));
  CHECK(contains(text, "byte"));
  printf("truncated STL: %s\n", text);

  /* The same cut with the size known: rejected too (before reading on). */
  CHECK(read_mesh(f.ctx, &cut, "cut2.stl", &m) == SC_TRUNCATED);
  last_message(f.ctx, text, sizeof text);
  CHECK(contains(text, "cut2.stl"));

  /* ASCII: the line is named. */
  cut.data = (unsigned char*)kBadAscii;
  cut.size = sizeof kBadAscii - 1;
  CHECK(read_mesh(f.ctx, &cut, "bad.stl", &m) == SC_PARSE_ERROR);
  sc_status_location(f.ctx, &where);
  CHECK(where.line == 5);
  last_message(f.ctx, text, sizeof text);
  CHECK(contains(text, "bad.stl:5"));
  printf("bad ASCII STL: %s\n", text);

  /* A limit: too many triangles for the caller's cap. */
  options = sc_stl_read_defaults();
  options.max_triangles = 100;
  src = sc_memory_source(&state, torus->data, torus->size, "torus_binary.stl");
  CHECK(sc_mesh_read_stl(f.ctx, &src, &options, &m) == SC_LIMIT_EXCEEDED);
  /* A successful call clears the last status. */
  CHECK_OK(f.ctx, read_mesh(f.ctx, torus, "torus_binary.stl", &m));
  CHECK(sc_last_status(f.ctx) == SC_OK);
  close_fixture(&f);
}

static void test_mesh_check(const Bytes* torus) {
  Fixture f = open_fixture((size_t)4 << 20);
  sc_mesh *m = NULL, *open_box = NULL, *inside_out = NULL;
  sc_mesh_report r;
  Bytes open_bytes = read_file(g_fixtures, "stl/open_box_ascii.stl");
  Bytes inside_bytes = read_file(g_fixtures, "stl/inside_out_box.stl");
  char text[512];
  CHECK(open_bytes.data != NULL && inside_bytes.data != NULL);
  g_counting = 1;
  CHECK_OK(f.ctx, read_mesh(f.ctx, torus, "torus_binary.stl", &m));
  CHECK_OK(f.ctx, sc_mesh_check(f.ctx, m, &r));
  CHECK(r.triangle_count == 2304);
  CHECK(r.closed == 1 && r.manifold == 1 && r.oriented == 1 && r.outward == 1);
  CHECK(r.valid_solid == 1);
  CHECK(r.genus == 1);
  CHECK(r.shells == 1);
  CHECK(r.volume_mm3 > 0 && r.area_mm2 > 0);
  CHECK(r.bounds_max[0] > r.bounds_min[0]);
  CHECK_OK(f.ctx, sc_mesh_require_solid(f.ctx, m));

  CHECK_OK(f.ctx, read_mesh(f.ctx, &open_bytes, "open_box_ascii.stl", &open_box));
  CHECK_OK(f.ctx, sc_mesh_check(f.ctx, open_box, &r));
  CHECK(r.closed == 0 && r.boundary_edges > 0 && r.valid_solid == 0);
  CHECK(sc_mesh_require_solid(f.ctx, open_box) == SC_INVALID_MESH);
  last_message(f.ctx, text, sizeof text);
  CHECK(contains(text, "not closed"));

  CHECK_OK(f.ctx, read_mesh(f.ctx, &inside_bytes, "inside_out_box.stl", &inside_out));
  CHECK_OK(f.ctx, sc_mesh_check(f.ctx, inside_out, &r));
  CHECK(r.closed == 1 && r.outward == 0 && r.volume_mm3 < 0 && r.valid_solid == 0);
  g_counting = 0;
  free(open_bytes.data);
  free(inside_bytes.data);
  close_fixture(&f);
}

/* An axis-aligned box from arrays, outward. Corners are float32 values (the Boolean's B must
 * be). */
static sc_status make_box(sc_context* ctx, const double lo[3], const double hi[3], sc_mesh** out) {
  static const uint32_t kFaces[36] = {0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4,
                                      2, 3, 7, 2, 7, 6, 1, 2, 6, 1, 6, 5, 0, 4, 7, 0, 7, 3};
  double v[24];
  int i;
  for (i = 0; i < 8; ++i) {
    v[3 * i] = (i == 1 || i == 2 || i == 5 || i == 6) ? hi[0] : lo[0];
    v[3 * i + 1] = (i == 2 || i == 3 || i == 6 || i == 7) ? hi[1] : lo[1];
    v[3 * i + 2] = i >= 4 ? hi[2] : lo[2];
  }
  return sc_mesh_from_arrays(ctx, v, 8, kFaces, 12, out);
}

static void test_operations(void) {
  Fixture f = open_fixture((size_t)32 << 20);
  sc_mesh *a = NULL, *b = NULL, *d = NULL, *swept = NULL;
  sc_mesh_report r;
  const double alo[3] = {0, 0, 0}, ahi[3] = {2, 2, 2};
  const double blo[3] = {1, 0.5, 1.25}, bhi[3] = {3, 3, 3};
  const double down[3] = {0, 0, -1}, zero[3] = {0, 0, 0};
  const sc_mesh* jaws[1];
  double bad_vertex[3] = {0, 0, 0};
  const uint32_t bad_triangle[3] = {0, 0, 7};
  char text[512];
  g_counting = 1;
  CHECK_OK(f.ctx, make_box(f.ctx, alo, ahi, &a));
  CHECK_OK(f.ctx, sc_mesh_check(f.ctx, a, &r));
  CHECK(r.valid_solid == 1 && r.volume_mm3 == 8.0);
  CHECK_OK(f.ctx, make_box(f.ctx, blo, bhi, &b));
  /* The exact Boolean: [0,2]^3 minus [1,3]x[0.5,3]x[1.25,3] leaves 8 - 1 * 1.5 * 0.75. */
  CHECK_OK(f.ctx, sc_mesh_boolean(f.ctx, a, b, SC_BOOLEAN_DIFFERENCE, &d));
  CHECK_OK(f.ctx, sc_mesh_check(f.ctx, d, &r));
  CHECK(r.valid_solid == 1);
  CHECK(r.volume_mm3 > 6.875 - 1e-9 && r.volume_mm3 < 6.875 + 1e-9);
  CHECK(sc_mesh_boolean(f.ctx, a, b, 7, &d) == SC_INVALID_ARGUMENT && d == NULL);
  /* Bad arrays are named. */
  CHECK(sc_mesh_from_arrays(f.ctx, bad_vertex, 1, bad_triangle, 1, &d) == SC_INVALID_ARGUMENT);
  last_message(f.ctx, text, sizeof text);
  CHECK(contains(text, "triangle 0 uses vertex 7"));
  /* The swept volume of the box along -z: the box extended down, closed. */
  jaws[0] = a;
  CHECK(sc_sweep(f.ctx, jaws, 1, zero, 0.25, &swept) == SC_INVALID_ARGUMENT);
  CHECK(swept == NULL);
  CHECK_OK(f.ctx, sc_sweep(f.ctx, jaws, 1, down, 0.25, &swept));
  CHECK_OK(f.ctx, sc_mesh_check(f.ctx, swept, &r));
  CHECK(r.closed == 1 && r.outward == 1);
  CHECK(r.volume_mm3 > 8.0);
  CHECK(r.bounds_min[2] < -0.1);
  {
    /* Blockout: a "tooth" box poking 0.5 mm into the top of the splint box, taken off along
     * +z: its swept volume in the splint is removed, taken 0.05 mm inside (about
     * 0.9 x 0.9 x 0.45 = 0.36 mm^3, within the voxel's error). */
    const double tlo[3] = {0.5, 0.5, 1.5}, thi[3] = {1.5, 1.5, 2.5};
    const double up[3] = {0, 0, 1};
    sc_mesh *tooth = NULL, *blocked = NULL;
    CHECK_OK(f.ctx, make_box(f.ctx, tlo, thi, &tooth));
    jaws[0] = tooth;
    CHECK(sc_blockout(f.ctx, a, jaws, 1, up, 0.1, 0.5, &blocked) == SC_INVALID_ARGUMENT);
    CHECK_OK(f.ctx, sc_blockout(f.ctx, a, jaws, 1, up, 0.1, 0.05, &blocked));
    CHECK_OK(f.ctx, sc_mesh_check(f.ctx, blocked, &r));
    CHECK(r.valid_solid == 1);
    CHECK(r.volume_mm3 < 8.0 - 0.3 && r.volume_mm3 > 8.0 - 0.5);
    printf("blockout of a box: %.4f mm^3 left of 8\n", r.volume_mm3);
    /* The exact sweep: the tooth's prism inside the splint, exactly 1 x 1 x 0.5 (the tooth
     * is not subtracted first: the sweep holds it). */
    {
      sc_mesh* exact = NULL;
      CHECK(sc_blockout_exact(f.ctx, a, jaws, 1, NULL, &exact) == SC_INVALID_ARGUMENT);
      CHECK(exact == NULL);
      CHECK_OK(f.ctx, sc_blockout_exact(f.ctx, a, jaws, 1, up, &exact));
      CHECK_OK(f.ctx, sc_mesh_check(f.ctx, exact, &r));
      CHECK(r.valid_solid == 1);
      CHECK(r.volume_mm3 > 7.5 - 1e-9 && r.volume_mm3 < 7.5 + 1e-9);
      printf("exact blockout of a box: %.6f mm^3 left of 8\n", r.volume_mm3);
    }
  }
  g_counting = 0;
  close_fixture(&f);
}

static int g_progress_calls = 0;
static int g_saw_boolean = 0;
static int g_cancel_at = -1;
static int on_progress(void* user, const char* stage, uint64_t done, uint64_t total) {
  (void)done;
  (void)total;
  ++*(int*)user;
  ++g_progress_calls;
  if (strcmp(stage, "design: boolean") == 0) g_saw_boolean = 1;
  return !(g_cancel_at >= 0 && g_progress_calls >= g_cancel_at);
}

/* An executor that runs the tasks in reverse order: results must not depend on it. */
static unsigned long g_tasks = 0;
static void serial_run(void* self, uint32_t count, sc_task_fn task, void* task_context) {
  uint32_t i;
  for (i = count; i > 0; --i) {
    ++*(unsigned long*)self;
    task(task_context, i - 1);
  }
}

/* The design at caps below its need: each run either succeeds or fails with
 * SC_ARENA_EXHAUSTED (the jaws may not fit either), the arena back where the call found it. */
static void test_design_exhaustion(const Bytes* case_text, const Bytes jaw_bytes[2], size_t need) {
  size_t cap;
  int tried = 0, exhausted = 0, succeeded = 0;
  for (cap = need / 4; cap <= need + need / 8; cap += need / 16) {
    Fixture f = open_fixture(cap);
    sc_case* c = NULL;
    const sc_mesh* jaws[2] = {NULL, NULL};
    sc_mesh* splint = NULL;
    sc_status s;
    size_t i;
    ++tried;
    g_counting = 1;
    s = sc_case_parse(f.ctx, (const char*)case_text->data, case_text->size, "paper_scale", &c);
    for (i = 0; i < 2 && s == SC_OK; ++i) {
      sc_mesh* m = NULL;
      s = read_mesh(f.ctx, &jaw_bytes[i], "jaw.stl", &m);
      jaws[i] = m;
    }
    if (s == SC_OK) {
      const size_t before = sc_arena_used(f.ctx);
      s = sc_design(f.ctx, c, jaws, 2, &splint, NULL);
      if (s != SC_OK) {
        CHECK(splint == NULL);
        CHECK(sc_arena_used(f.ctx) == before);
      }
    }
    g_counting = 0;
    CHECK(s == SC_OK || s == SC_ARENA_EXHAUSTED);
    if (s == SC_ARENA_EXHAUSTED) {
      char text[512];
      ++exhausted;
      sc_status_message(f.ctx, text, sizeof text);
      CHECK(contains(text, "need"));
    }
    if (s == SC_OK) ++succeeded;
    close_fixture(&f);
  }
  CHECK(tried >= 12);
  CHECK(exhausted >= 6);
  CHECK(succeeded >= 1);
}

static void read_golden(const char* key, char out[65]) {
  Bytes b = read_file(g_fixtures, "golden.sha256");
  const char* at;
  out[0] = '\0';
  if (b.data == NULL) return;
  b.data[b.size] = '\0';
  at = strstr((const char*)b.data, key);
  if (at != NULL && at - (const char*)b.data >= 66) {
    memcpy(out, at - 66, 64);
    out[64] = '\0';
  }
  free(b.data);
}

/* Blockout switched on along +z with a voxel of `voxel_mm` (the case's other values kept). */
static void blockout_along_z(sc_case_params* q, double voxel_mm) {
  q->has_insertion_direction = 1;
  q->insertion_direction[0] = 0;
  q->insertion_direction[1] = 0;
  q->insertion_direction[2] = 1;
  q->blockout = 1;
  q->blockout_voxel_mm = voxel_mm;
}

/* The clearance (sc_case_set_blockout_clearance): refused without blockout, with a method that
 * takes none, beside an inset, out of range (nothing changed); kept by sc_case_set_params only
 * where it applies; dropped with blockout; written and read back by the case file. */
static void test_clearance_params(sc_context* ctx, sc_case* c) {
  sc_case_params p, q;
  double mm = -1;
  char text[512];
  unsigned char written[8192];
  sc_memory_sink_state ws;
  sc_sink sink = sc_memory_sink(&ws, written, sizeof written - 1, "case.json");
  sc_case* reread = NULL;
  CHECK_OK(ctx, sc_case_get_params(ctx, c, &p));
  CHECK(p.blockout == 0);
  CHECK_OK(ctx, sc_case_get_blockout_clearance(ctx, c, &mm));
  CHECK(mm == 0);
  CHECK(sc_case_set_blockout_clearance(ctx, c, 0.1) == SC_INVALID_ARGUMENT);
  last_message(ctx, text, sizeof text);
  CHECK(contains(text, "sc_case_set_blockout_clearance") && contains(text, "needs blockout"));
  CHECK(sc_case_get_blockout_clearance(ctx, c, NULL) == SC_INVALID_ARGUMENT);
  q = p;
  blockout_along_z(&q, 0.1);
  q.blockout_inset_mm = 0.05;
  q.blockout_closing_mm = 0;
  q.blockout_method = SC_BLOCKOUT_EXACT;
  CHECK_OK(ctx, sc_case_set_params(ctx, c, &q));
  CHECK(sc_case_set_blockout_clearance(ctx, c, 0.1) == SC_INVALID_ARGUMENT);
  last_message(ctx, text, sizeof text);
  CHECK(contains(text, "SC_BLOCKOUT_HEIGHTFIELD"));
  q.blockout_method = SC_BLOCKOUT_VOXEL;
  CHECK_OK(ctx, sc_case_set_params(ctx, c, &q));
  CHECK(sc_case_set_blockout_clearance(ctx, c, 0.1) == SC_INVALID_ARGUMENT);
  last_message(ctx, text, sizeof text);
  CHECK(contains(text, "blockout_inset_mm"));
  q.blockout_method = SC_BLOCKOUT_HEIGHTFIELD;
  CHECK_OK(ctx, sc_case_set_params(ctx, c, &q));
  CHECK(sc_case_set_blockout_clearance(ctx, c, 2.5) == SC_INVALID_ARGUMENT); /* 2 mm at most */
  CHECK(sc_case_set_blockout_clearance(ctx, c, -0.1) == SC_INVALID_ARGUMENT);
  CHECK_OK(ctx, sc_case_get_blockout_clearance(ctx, c, &mm));
  CHECK(mm == 0);
  CHECK_OK(ctx, sc_case_set_blockout_clearance(ctx, c, 0.3));
  CHECK_OK(ctx, sc_case_get_blockout_clearance(ctx, c, &mm));
  CHECK(mm == 0.3);
  /* The parameters that would drop it are refused, naming it; a finer voxel than 20 per
   * clearance too. Nothing changes. */
  CHECK_OK(ctx, sc_case_get_params(ctx, c, &q));
  CHECK(q.blockout_inset_mm == 0);
  q.blockout_method = SC_BLOCKOUT_EXACT;
  CHECK(sc_case_set_params(ctx, c, &q) == SC_INVALID_ARGUMENT);
  last_message(ctx, text, sizeof text);
  CHECK(contains(text, "sc_case_set_params") && contains(text, "clearance"));
  q.blockout_method = SC_BLOCKOUT_AUTO;
  CHECK(sc_case_set_params(ctx, c, &q) == SC_INVALID_ARGUMENT);
  q.blockout_method = SC_BLOCKOUT_VOXEL;
  q.blockout_inset_mm = 0.05;
  CHECK(sc_case_set_params(ctx, c, &q) == SC_INVALID_ARGUMENT);
  q.blockout_inset_mm = 0;
  q.blockout_voxel_mm = 0.01; /* 0.3 mm is 30 voxels */
  CHECK(sc_case_set_params(ctx, c, &q) == SC_INVALID_ARGUMENT);
  last_message(ctx, text, sizeof text);
  CHECK(contains(text, "clearance"));
  CHECK_OK(ctx, sc_case_get_params(ctx, c, &q));
  CHECK(q.blockout_method == SC_BLOCKOUT_HEIGHTFIELD && q.blockout_voxel_mm == 0.1);
  /* The voxel method with inset 0 keeps it. */
  q.blockout_method = SC_BLOCKOUT_VOXEL;
  CHECK_OK(ctx, sc_case_set_params(ctx, c, &q));
  CHECK_OK(ctx, sc_case_get_blockout_clearance(ctx, c, &mm));
  CHECK(mm == 0.3);
  /* Written and read back: the same clearance and method. */
  CHECK_OK(ctx, sc_case_write(ctx, c, &sink));
  written[ws.size] = 0;
  CHECK(contains((const char*)written, "\"clearance\""));
  CHECK_OK(ctx, sc_case_parse(ctx, (const char*)written, (size_t)ws.size, "case.json", &reread));
  if (reread != NULL) {
    CHECK_OK(ctx, sc_case_get_blockout_clearance(ctx, reread, &mm));
    CHECK(mm == 0.3);
    CHECK_OK(ctx, sc_case_get_params(ctx, reread, &q));
    CHECK(q.blockout_method == SC_BLOCKOUT_VOXEL && q.blockout_inset_mm == 0);
  }
  /* Blockout off drops it; 0 is always taken. */
  CHECK_OK(ctx, sc_case_set_blockout_clearance(ctx, c, 0));
  CHECK_OK(ctx, sc_case_set_blockout_clearance(ctx, c, 0.3));
  CHECK_OK(ctx, sc_case_get_params(ctx, c, &q));
  q.blockout = 0;
  CHECK_OK(ctx, sc_case_set_params(ctx, c, &q));
  CHECK_OK(ctx, sc_case_get_blockout_clearance(ctx, c, &mm));
  CHECK(mm == 0);
  q.blockout = 1;
  CHECK_OK(ctx, sc_case_set_params(ctx, c, &q));
  CHECK_OK(ctx, sc_case_get_blockout_clearance(ctx, c, &mm));
  CHECK(mm == 0);
  CHECK_OK(ctx, sc_case_set_blockout_clearance(ctx, c, 0));
  /* As it was. */
  CHECK_OK(ctx, sc_case_set_params(ctx, c, &p));
}

static void test_case_params(const Bytes* case_text) {
  Fixture f = open_fixture((size_t)1 << 20);
  sc_case* c = NULL;
  sc_case_params p, q;
  char text[512];
  CHECK_OK(f.ctx, sc_case_parse(f.ctx, (const char*)case_text->data, case_text->size,
                                "paper_scale.json", &c));
  CHECK(strcmp(sc_case_id(c), "phantom-paper-scale") == 0);
  CHECK(sc_case_jaw_count(c) == 2);
  CHECK(strcmp(sc_case_jaw_role(c, 0), "maxilla") == 0);
  CHECK(strcmp(sc_case_jaw_mesh(c, 1), "mandible.stl") == 0);
  CHECK(sc_case_jaw_role(c, 2) == NULL);
  CHECK_OK(f.ctx, sc_case_get_params(f.ctx, c, &p));
  CHECK(p.spacing_mm == 0.42);
  CHECK(strcmp(p.printer, "eden260") == 0);
  CHECK(p.blockout == 0);
  q = p;
  q.printer = "nope";
  CHECK(sc_case_set_params(f.ctx, c, &q) == SC_INVALID_ARGUMENT);
  last_message(f.ctx, text, sizeof text);
  CHECK(contains(text, "nope"));
  q = p;
  q.blockout = 1;
  q.has_insertion_direction = 0;
  CHECK(sc_case_set_params(f.ctx, c, &q) == SC_INVALID_ARGUMENT);
  last_message(f.ctx, text, sizeof text);
  CHECK(contains(text, "insertion_direction"));
  q = p;
  blockout_along_z(&q, 5); /* the voxel out of range */
  CHECK(sc_case_set_params(f.ctx, c, &q) == SC_INVALID_ARGUMENT);
  last_message(f.ctx, text, sizeof text);
  CHECK(contains(text, "blockout_voxel_mm"));
  q.blockout_voxel_mm = p.blockout_voxel_mm;
  q.blockout_method = 3;
  CHECK(sc_case_set_params(f.ctx, c, &q) == SC_INVALID_ARGUMENT);
  last_message(f.ctx, text, sizeof text);
  CHECK(contains(text, "blockout_method"));
  /* Nothing changed by the failures; a valid change sticks. */
  CHECK_OK(f.ctx, sc_case_get_params(f.ctx, c, &q));
  CHECK(q.blockout == 0 && q.has_insertion_direction == p.has_insertion_direction);
  q.spacing_mm = 0.5;
  CHECK_OK(f.ctx, sc_case_set_params(f.ctx, c, &q));
  CHECK_OK(f.ctx, sc_case_get_params(f.ctx, c, &p));
  CHECK(p.spacing_mm == 0.5);
  test_clearance_params(f.ctx, c);
  /* A broken case: the line is named. */
  {
    static const char kBad[] = "{\n  \"splintcore_case\": 1,\n  \"bogus\": 2\n}";
    CHECK(sc_case_parse(f.ctx, kBad, sizeof kBad - 1, "bad.json", &c) != SC_OK);
  }
  CHECK(c == NULL);
  last_message(f.ctx, text, sizeof text);
  CHECK(contains(text, "bad.json:"));
  close_fixture(&f);
}

/* The splint's binary STL hashed (the bytes are the splint). */
static void splint_hash(sc_context* ctx, const sc_mesh* splint, char out[65]) {
  const size_t cap = (size_t)sc_stl_binary_size(sc_mesh_triangle_count(splint));
  unsigned char* stl = (unsigned char*)malloc(cap);
  sc_memory_sink_state state;
  sc_sink sink = sc_memory_sink(&state, stl, cap, "splint.stl");
  out[0] = '\0';
  g_counting = 1;
  CHECK_OK(ctx, sc_mesh_write_stl(ctx, splint, &sink, NULL));
  g_counting = 0;
  sc_sha256_hex(stl, (size_t)state.size, out);
  free(stl);
}

/* The case designed with blockout method `method`, the rest of *p as it is (p keeps the
 * method). */
static void design_with_method(sc_context* ctx, sc_case* c, const sc_mesh* const* jaws,
                               sc_case_params* p, int method, sc_mesh** splint,
                               sc_design_report* report) {
  p->blockout_method = method;
  CHECK_OK(ctx, sc_case_set_params(ctx, c, p));
  CHECK_OK(ctx, sc_design(ctx, c, jaws, 2, splint, report));
}

/* sc_design_blockout_used gives, for each jaw, the values report.json's "blockout" entry of that
 * jaw holds under `lowered` and `clearance` (the n-th such keys in the report are jaw n's;
 * `clearance` NULL: the report has none, and the clearance is 0). */
static void check_blockout_used(sc_context* ctx, const sc_case* c, const sc_mesh* const* jaws,
                                const sc_mesh* splint, const char* lowered, const char* clearance) {
  static unsigned char json[(size_t)1 << 20];
  sc_memory_sink_state state;
  sc_sink sink = sc_memory_sink(&state, json, sizeof json - 1, "report");
  const char *at_lowered, *at_clearance;
  size_t jaw;
  CHECK_OK(ctx, sc_design_write_report(ctx, c, jaws, 2, splint, NULL, &sink));
  json[state.size < sizeof json ? state.size : 0] = 0;
  at_lowered = strstr((const char*)json, "\"blockout\":[");
  at_clearance = at_lowered;
  CHECK(at_lowered != NULL);
  for (jaw = 0; jaw < 2 && at_lowered != NULL && at_clearance != NULL; ++jaw) {
    double low = -1, clear = -1;
    CHECK_OK(ctx, sc_design_blockout_used(ctx, splint, jaw, &low, &clear));
    at_lowered = strstr(at_lowered + 1, lowered);
    if (clearance != NULL) at_clearance = strstr(at_clearance + 1, clearance);
    CHECK(at_lowered != NULL && at_clearance != NULL);
    if (at_lowered == NULL || at_clearance == NULL) break;
    CHECK(strtod(at_lowered + strlen(lowered), NULL) == low);
    CHECK(clearance != NULL ? strtod(at_clearance + strlen(clearance), NULL) == clear : clear == 0);
    printf("jaw %u: lowered %.9g mm, clearance %.9g mm, as the report says\n", (unsigned)jaw, low,
           clear);
  }
  /* Either output may be NULL; a jaw beyond those blocked out and a splint without a design
   * record are refused, the outputs untouched. */
  CHECK_OK(ctx, sc_design_blockout_used(ctx, splint, 1, NULL, NULL));
  {
    double untouched = 7;
    CHECK(refused_with(ctx, sc_design_blockout_used(ctx, splint, 2, &untouched, NULL),
                       "jaw 2 was not blocked out (the design blocked out 2 jaw(s))"));
    CHECK(refused_with(ctx, sc_design_blockout_used(ctx, jaws[0], 0, &untouched, NULL),
                       "not made by sc_design"));
    CHECK(untouched == 7);
  }
}

/* A spacer through the C API (sc_case_set_blockout_clearance) on the height-field case: the
 * imprint moves out by the clearance, so the splint keeps less volume than without; the case
 * written and read back designs the same bytes (what the clearance says is what the file
 * says). The case and the arena are left as they were. */
static void test_design_clearance(sc_context* ctx, sc_case* c, const sc_mesh* const* jaws,
                                  const sc_design_report* without) {
  sc_arena_mark mark = sc_arena_mark_get(ctx);
  sc_design_report spaced, again;
  sc_mesh *spaced_splint = NULL, *again_splint = NULL;
  sc_case* reread = NULL;
  char hash[65] = "", reread_hash[65] = "-";
  static unsigned char written[8192];
  sc_memory_sink_state ws;
  sc_sink sink = sc_memory_sink(&ws, written, sizeof written, "case.json");
  CHECK_OK(ctx, sc_case_set_blockout_clearance(ctx, c, 0.2));
  CHECK_OK(ctx, sc_case_write(ctx, c, &sink));
  CHECK_OK(ctx, sc_case_parse(ctx, (const char*)written, (size_t)ws.size, "case.json", &reread));
  CHECK_OK(ctx, sc_design(ctx, c, jaws, 2, &spaced_splint, &spaced));
  if (spaced_splint != NULL) {
    CHECK(spaced.blockout_method_used == SC_BLOCKOUT_HEIGHTFIELD && spaced.printable == 1);
    CHECK(spaced.splint_volume_mm3 < without->splint_volume_mm3);
    splint_hash(ctx, spaced_splint, hash);
    printf("design with a 0.2 mm clearance: %llu triangles, %.3f mm^3 (without: %.3f)\n",
           (unsigned long long)spaced.splint_triangles, spaced.splint_volume_mm3,
           without->splint_volume_mm3);
    check_blockout_used(ctx, c, jaws, spaced_splint, "\"lowered_mm\":", "\"clearance_used_mm\":");
  }
  if (reread != NULL) {
    CHECK_OK(ctx, sc_design(ctx, reread, jaws, 2, &again_splint, &again));
    if (again_splint != NULL) splint_hash(ctx, again_splint, reread_hash);
  }
  CHECK(strcmp(hash, reread_hash) == 0);
  CHECK_OK(ctx, sc_case_set_blockout_clearance(ctx, c, 0));
  sc_arena_rewind(ctx, mark);
}

static void test_design(const Bytes* case_text, const char* jaws_dir) {
  const size_t arena_bytes = (size_t)96 << 20;
  Fixture f = open_fixture(arena_bytes);
  sc_case* c = NULL;
  const sc_mesh* jaws[2] = {NULL, NULL};
  sc_mesh* splint = NULL;
  sc_design_report report;
  Bytes jaw_bytes[2];
  size_t i, high_water;
  size_t stl_cap;
  unsigned char* stl;
  sc_memory_sink_state sink_state;
  sc_sink sink;
  char hash[65], golden[65], text[512];
  int calls = 0;
  sc_arena_mark before;

  CHECK_OK(f.ctx, sc_case_parse(f.ctx, (const char*)case_text->data, case_text->size,
                                "paper_scale.json", &c));
  if (c == NULL) return;
  for (i = 0; i < 2; ++i) {
    sc_mesh* m = NULL;
    jaw_bytes[i] = read_file(jaws_dir, sc_case_jaw_mesh(c, i));
    CHECK(jaw_bytes[i].data != NULL);
    if (jaw_bytes[i].data == NULL) return;
    CHECK_OK(f.ctx, read_mesh(f.ctx, &jaw_bytes[i], sc_case_jaw_mesh(c, i), &m));
    jaws[i] = m;
  }
  sc_context_set_progress(f.ctx, on_progress, &calls);
  /* The wrong jaw count is named. */
  CHECK(sc_design(f.ctx, c, jaws, 1, &splint, &report) == SC_INVALID_ARGUMENT);
  last_message(f.ctx, text, sizeof text);
  CHECK(contains(text, "2 jaws"));
  /* Cancelled from the progress callback: SC_CANCELLED, the arena back where it was. */
  before = sc_arena_mark_get(f.ctx);
  g_cancel_at = 3;
  g_progress_calls = 0;
  CHECK(sc_design(f.ctx, c, jaws, 2, &splint, &report) == SC_CANCELLED);
  CHECK(splint == NULL);
  CHECK(sc_arena_used(f.ctx) == before.used);
  g_cancel_at = -1;
  g_progress_calls = 0;
  calls = 0;

  g_counting = 1;
  sc_context_set_executor(f.ctx, serial_run, &g_tasks, 4);
  CHECK_OK(f.ctx, sc_design(f.ctx, c, jaws, 2, &splint, &report));
  g_counting = 0;
  if (splint == NULL) return;
  high_water = sc_arena_high_water(f.ctx);
  CHECK(calls > 0 && g_saw_boolean);
  CHECK(report.printable == 1);
  CHECK(report.crumbs_removed == 0 && report.crumbs_volume_mm3 == 0); /* one piece */
  CHECK(report.jaw_triangles == 12000);
  CHECK(report.splint_triangles == sc_mesh_triangle_count(splint));
  CHECK(report.boolean_intersecting_pairs > 0);
  CHECK(report.base_sections > 0);
  CHECK(report.splint_volume_mm3 > 0 && report.splint_volume_mm3 < report.base_volume_mm3);
  CHECK(report.blockout_jaws == 0);
  /* The side-wall check: the case's jaws cross neither wall of its 119 mm arch. */
  CHECK(report.wall_jaws == 2 && report.wall_arch_mm > 100);
  CHECK(report.wall_crossing_mm[0] == 0 && report.wall_crossing_mm[1] == 0);
  CHECK(report.wall_sideways_mm[0] == 0 && report.wall_sideways_mm[1] == 0);
  CHECK(strcmp(report.printer, "eden260") == 0);
  stl_cap = (size_t)sc_stl_binary_size(report.splint_triangles);
  stl = (unsigned char*)malloc(stl_cap);
  sink = sc_memory_sink(&sink_state, stl, stl_cap, "splint.stl");
  g_counting = 1;
  CHECK_OK(f.ctx, sc_mesh_write_stl(f.ctx, splint, &sink, NULL));
  sc_sha256_hex(stl, (size_t)sink_state.size, hash);
  g_counting = 0;
  CHECK(sink_state.size == stl_cap);
  read_golden("boolean:paper_scale-phantom6000", golden);
  CHECK(strlen(golden) == 64);
  CHECK(strcmp(hash, golden) == 0);
  /* The splint's print job: a ZIP (its local header signature first), the same bytes twice;
   * NULL arguments refused; the arena as it was. */
  {
    size_t job_cap = 4u << 20;
    unsigned char* job = (unsigned char*)malloc(job_cap);
    unsigned char* again = (unsigned char*)malloc(job_cap);
    sc_memory_sink_state js, ks;
    sc_sink jsink = sc_memory_sink(&js, job, job_cap, "splint.3mf");
    sc_sink ksink = sc_memory_sink(&ks, again, job_cap, "splint.3mf");
    size_t used = sc_arena_used(f.ctx);
    CHECK_OK(f.ctx, sc_write_splint_job(f.ctx, c, splint, &jsink));
    CHECK_OK(f.ctx, sc_write_splint_job(f.ctx, c, splint, &ksink));
    CHECK(js.size > 30 && job[0] == 'P' && job[1] == 'K' && job[2] == 3 && job[3] == 4);
    CHECK(js.size == ks.size && memcmp(job, again, (size_t)js.size) == 0);
    CHECK(sc_write_splint_job(f.ctx, c, NULL, &jsink) == SC_INVALID_ARGUMENT);
    CHECK(sc_arena_used(f.ctx) == used);
    free(job);
    free(again);
  }
  printf(
      "design: %llu triangles, %.3f mm^3, printable %d, arena high water %llu bytes, sha256 %s\n",
      (unsigned long long)report.splint_triangles, report.splint_volume_mm3, report.printable,
      (unsigned long long)high_water, hash);
  printf("executor tasks run: %lu\n", g_tasks);
  free(stl);

  /* Interference elimination switched on through the parameters: the same case with each
   * jaw's swept volume subtracted along the case's insertion direction removes volume. */
  {
    sc_case_params p;
    sc_design_report blocked;
    sc_mesh* blocked_splint = NULL;
    sc_arena_mark mark = sc_arena_mark_get(f.ctx);
    CHECK_OK(f.ctx, sc_case_get_params(f.ctx, c, &p));
    CHECK(p.has_insertion_direction == 1);
    p.blockout = 1;
    p.blockout_voxel_mm = 0.2;
    p.blockout_inset_mm = 0.1;
    p.blockout_closing_mm = 0;
    CHECK_OK(f.ctx, sc_case_set_params(f.ctx, c, &p));
    g_counting = 1;
    CHECK_OK(f.ctx, sc_design(f.ctx, c, jaws, 2, &blocked_splint, &blocked));
    g_counting = 0;
    if (blocked_splint != NULL) {
      CHECK(blocked.blockout_jaws == 2);
      CHECK(p.blockout_method == SC_BLOCKOUT_AUTO); /* the case's default: exact here */
      CHECK(blocked.blockout_method_used == SC_BLOCKOUT_EXACT);
      CHECK(blocked.blockout_removed_mm3[0] >= 0 && blocked.blockout_removed_mm3[1] >= 0);
      CHECK(blocked.blockout_removed_mm3[0] + blocked.blockout_removed_mm3[1] > 0);
      CHECK(blocked.splint_volume_mm3 < report.splint_volume_mm3);
      CHECK(blocked.printable == 1);
      printf("design with blockout: %llu triangles, %.3f mm^3 (removed %.3f + %.3f mm^3)\n",
             (unsigned long long)blocked.splint_triangles, blocked.splint_volume_mm3,
             blocked.blockout_removed_mm3[0], blocked.blockout_removed_mm3[1]);
    }
    sc_arena_rewind(f.ctx, mark);
    /* The height field: the same case, its own method reported back; the inset given is not
     * used (the height field has none). */
    {
      sc_design_report height;
      sc_mesh* height_splint = NULL;
      design_with_method(f.ctx, c, jaws, &p, SC_BLOCKOUT_HEIGHTFIELD, &height_splint, &height);
      if (height_splint != NULL) {
        CHECK(height.blockout_jaws == 2);
        CHECK(height.blockout_method_used == SC_BLOCKOUT_HEIGHTFIELD);
        CHECK(height.blockout_removed_mm3[0] + height.blockout_removed_mm3[1] > 0);
        CHECK(height.splint_volume_mm3 < report.splint_volume_mm3);
        printf("design with the height field: %llu triangles, %.3f mm^3\n",
               (unsigned long long)height.splint_triangles, height.splint_volume_mm3);
      }
      sc_arena_rewind(f.ctx, mark);
      if (height_splint != NULL) test_design_clearance(f.ctx, c, jaws, &height);
      /* The voxel sweep lowered into the jaws by the inset (or more, after a retry), as the
       * report says it. */
      {
        sc_design_report voxel;
        sc_mesh* voxel_splint = NULL;
        design_with_method(f.ctx, c, jaws, &p, SC_BLOCKOUT_VOXEL, &voxel_splint, &voxel);
        if (voxel_splint != NULL) {
          double lowered = 0;
          CHECK(voxel.blockout_method_used == SC_BLOCKOUT_VOXEL);
          CHECK_OK(f.ctx, sc_design_blockout_used(f.ctx, voxel_splint, 0, &lowered, NULL));
          CHECK(lowered >= p.blockout_inset_mm &&
                lowered < p.blockout_inset_mm + p.blockout_voxel_mm);
          check_blockout_used(f.ctx, c, jaws, voxel_splint, "\"inset_mm\":", NULL);
        }
        sc_arena_rewind(f.ctx, mark);
      }
      p.blockout_method = SC_BLOCKOUT_AUTO;
      CHECK_OK(f.ctx, sc_case_set_params(f.ctx, c, &p));
    }
    /* "auto" with the upper picks 2.5 mm deeper along the occlusal normal (+z here) and the
     * lower 2 mm: the maxilla's exact sweep is refused (that jaw is made by the height field on
     * the 0.3 mm grid; the inset is not used), the mandible's holds
     * (DesignPipeline.AutoBlockoutFallsBackOnlyForTheJawItsSweepRefuses): SC_BLOCKOUT_MIXED. */
    {
      size_t n = sc_case_pick_count(c, SC_PICKS_UPPER), k;
      int side;
      double* saved = (double*)malloc(2 * n * 3 * sizeof(double)); /* to restore exactly */
      p.blockout_voxel_mm = 0.3;
      p.blockout_inset_mm = 0.15;
      CHECK_OK(f.ctx, sc_case_set_params(f.ctx, c, &p));
      CHECK(n > 0 && sc_case_pick_count(c, SC_PICKS_LOWER) == n);
      for (side = 0; side < 2; ++side) {
        for (k = 0; k < n; ++k) {
          double q[3], inner, outside;
          CHECK(sc_case_pick(c, side, k, q, NULL, &inner, &outside) == 1);
          memcpy(saved + (side * n + k) * 3, q, sizeof q);
          q[2] += side == SC_PICKS_UPPER ? 2.5 : -2.0;
          CHECK_OK(f.ctx, sc_case_set_pick(f.ctx, c, side, k, q, NULL, inner, outside));
        }
      }
      blocked_splint = NULL;
      CHECK_OK(f.ctx, sc_design(f.ctx, c, jaws, 2, &blocked_splint, &blocked));
      if (blocked_splint != NULL) {
        CHECK(blocked.blockout_jaws == 2);
        CHECK(blocked.blockout_method_used == SC_BLOCKOUT_MIXED);
        CHECK(blocked.printable == 1);
        printf("design with the base sunk 2.5 and 2 mm: blockout method %d (mixed)\n",
               blocked.blockout_method_used);
      }
      sc_arena_rewind(f.ctx, mark);
      for (side = 0; side < 2; ++side) {
        for (k = 0; k < n; ++k) {
          double inner, outside;
          CHECK(sc_case_pick(c, side, k, NULL, NULL, &inner, &outside) == 1);
          CHECK_OK(f.ctx, sc_case_set_pick(f.ctx, c, side, k, saved + (side * n + k) * 3, NULL,
                                           inner, outside));
        }
      }
      free(saved);
    }
    p.blockout = 0;
    CHECK_OK(f.ctx, sc_case_set_params(f.ctx, c, &p));
  }
  close_fixture(&f);
  test_design_exhaustion(case_text, jaw_bytes, high_water);
  for (i = 0; i < 2; ++i) free(jaw_bytes[i].data);
}

/* Scan-CT fusion (sc_design_scans): the paper-scale case with the mandible's own mesh as its
 * "scan" (registered onto itself: the identity), and sc_design refusing that case (no scans). */
static void test_design_scans(const Bytes* case_text, const char* jaws_dir) {
  static const char kMesh[] = "\"mesh\": \"mandible.stl\",";
  static const char kScan[] = " \"scan\": {\"path\": \"mandible.stl\", \"max_rms_mm\": 0.01},";
  Fixture f = open_fixture((size_t)96 << 20);
  const char* text = (const char*)case_text->data;
  const char* at = NULL;
  char* fused_text = NULL;
  size_t head, i, length;
  sc_case* c = NULL;
  const sc_mesh* jaws[2] = {NULL, NULL};
  const sc_mesh* scans[2] = {NULL, NULL};
  Bytes jaw_bytes[2] = {{NULL, 0}, {NULL, 0}};
  sc_mesh* splint = NULL;
  sc_design_report report;
  char message[512];

  for (i = 0; i + sizeof kMesh - 1 <= case_text->size && at == NULL; ++i) {
    if (memcmp(text + i, kMesh, sizeof kMesh - 1) == 0) at = text + i;
  }
  CHECK(at != NULL);
  if (at == NULL) return;
  head = (size_t)(at - text) + sizeof kMesh - 1;
  length = case_text->size + sizeof kScan - 1;
  fused_text = (char*)malloc(length);
  memcpy(fused_text, text, head);
  memcpy(fused_text + head, kScan, sizeof kScan - 1);
  memcpy(fused_text + head + sizeof kScan - 1, text + head, case_text->size - head);
  CHECK_OK(f.ctx, sc_case_parse(f.ctx, fused_text, length, "fused.json", &c));
  free(fused_text);
  if (c == NULL) return;
  for (i = 0; i < 2; ++i) {
    sc_mesh* m = NULL;
    jaw_bytes[i] = read_file(jaws_dir, sc_case_jaw_mesh(c, i));
    CHECK(jaw_bytes[i].data != NULL);
    if (jaw_bytes[i].data == NULL) return;
    CHECK_OK(f.ctx, read_mesh(f.ctx, &jaw_bytes[i], sc_case_jaw_mesh(c, i), &m));
    jaws[i] = m;
  }
  /* Without the scans the case is refused, naming the jaw. */
  CHECK(sc_design(f.ctx, c, jaws, 2, &splint, &report) == SC_INVALID_ARGUMENT);
  last_message(f.ctx, message, sizeof message);
  CHECK(contains(message, "jaw 1 (mandible) has a \"scan\""));
  scans[1] = jaws[1];
  CHECK_OK(f.ctx, sc_design_scans(f.ctx, c, jaws, scans, 2, &splint, &report));
  if (splint != NULL) {
    CHECK(report.fused[0] == 0 && report.fused[1] == 1);
    CHECK(report.fusion_rms_mm[1] < 1e-6);
    CHECK(report.fusion_overlap[1] > 0.99);
    for (i = 0; i < 16; ++i) {
      const double identity = (i % 5 == 0) ? 1.0 : 0.0;
      const double off = report.fusion_transform[1][i] - identity;
      CHECK(off < 1e-6 && off > -1e-6);
    }
    CHECK(report.printable == 1);
    printf("design with the mandible as its own scan: rms %.3g mm, overlap %.3f, %llu triangles\n",
           report.fusion_rms_mm[1], report.fusion_overlap[1],
           (unsigned long long)report.splint_triangles);
  }
  close_fixture(&f);
  for (i = 0; i < 2; ++i) free(jaw_bytes[i].data);
}

/* The report through the C API is report.json as `splintcore design` wrote it for the same
 * case (cli_dir: its -o folder), less the "run" part: the same names given, the same bytes. */
static void test_report_matches_cli(const char* jaws_dir, const char* cli_dir) {
  Fixture f = open_fixture((size_t)96 << 20);
  sc_case* c = NULL;
  const sc_mesh* jaws[2] = {NULL, NULL};
  sc_mesh* splint = NULL;
  Bytes case_text = read_file(jaws_dir, "case.json");
  Bytes cli = read_file(cli_dir, "report.json");
  Bytes preview = read_file(cli_dir, "preview.png");
  Bytes jaw_bytes[2] = {{NULL, 0}, {NULL, 0}};
  char case_path[1024], jaw_path[2][1024], splint_path[1024], preview_path[1024];
  char jaw_hash[2][65], preview_hash[65];
  const char* jaw_paths[2];
  const char* jaw_hashes[2];
  sc_report_files files;
  unsigned char* out = (unsigned char*)malloc((size_t)1 << 20);
  sc_memory_sink_state state;
  sc_sink sink;
  const char* run;
  size_t i, expected;

  CHECK(case_text.data != NULL && cli.data != NULL && preview.data != NULL && out != NULL);
  if (case_text.data == NULL || cli.data == NULL || preview.data == NULL || out == NULL) return;
  /* The names as the command line formed them: the case path as given, the jaws beside it. */
  snprintf(case_path, sizeof case_path, "%s/case.json", jaws_dir);
  snprintf(splint_path, sizeof splint_path, "%s/splint.stl", cli_dir);
  snprintf(preview_path, sizeof preview_path, "%s/preview.png", cli_dir);
  sc_sha256_hex(preview.data, preview.size, preview_hash);
  CHECK_OK(f.ctx, sc_case_parse(f.ctx, (const char*)case_text.data, case_text.size, case_path, &c));
  if (c == NULL) return;
  for (i = 0; i < 2; ++i) {
    sc_mesh* m = NULL;
    snprintf(jaw_path[i], sizeof jaw_path[i], "%s/%s", jaws_dir, sc_case_jaw_mesh(c, i));
    jaw_bytes[i] = read_file(jaws_dir, sc_case_jaw_mesh(c, i));
    if (jaw_bytes[i].data == NULL) return;
    sc_sha256_hex(jaw_bytes[i].data, jaw_bytes[i].size, jaw_hash[i]);
    CHECK_OK(f.ctx, read_mesh(f.ctx, &jaw_bytes[i], sc_case_jaw_mesh(c, i), &m));
    jaws[i] = m;
    jaw_paths[i] = jaw_path[i];
    jaw_hashes[i] = jaw_hash[i];
  }
  CHECK_OK(f.ctx, sc_design(f.ctx, c, jaws, 2, &splint, NULL));
  if (splint == NULL) return;
  memset(&files, 0, sizeof files);
  files.case_path = case_path;
  files.jaw_paths = jaw_paths;
  files.jaw_sha256 = jaw_hashes;
  files.splint_path = splint_path;
  files.preview_path = preview_path;
  files.preview_sha256 = preview_hash;
  sink = sc_memory_sink(&state, out, (size_t)1 << 20, "report");
  CHECK_OK(f.ctx, sc_design_write_report(f.ctx, c, jaws, 2, splint, &files, &sink));
  /* A splint that sc_design did not make has no record to report. */
  CHECK(sc_design_write_report(f.ctx, c, jaws, 2, (const sc_mesh*)jaws[0], &files, &sink) ==
        SC_INVALID_ARGUMENT);
  cli.data[cli.size] = 0;
  run = strstr((const char*)cli.data, ",\"run\":{");
  CHECK(run != NULL);
  if (run != NULL) {
    expected = (size_t)(run - (const char*)cli.data);
    CHECK(state.size == expected + 1);
    CHECK(memcmp(out, cli.data, expected) == 0 && out[expected] == '}');
    printf("report: %llu bytes through the C API, equal to report.json less its run part\n",
           (unsigned long long)state.size);
  }
  close_fixture(&f);
  for (i = 0; i < 2; ++i) free(jaw_bytes[i].data);
  free(case_text.data);
  free(cli.data);
  free(preview.data);
  free(out);
}

/* The phantom's case with the automatic outline instead of its picks. */
static const char kAutoCase[] =
    "{\"splintcore_case\": 1, \"case_id\": \"phantom-auto\", \"units\": \"mm\",\n"
    " \"jaws\": [{\"role\": \"maxilla\", \"mesh\": \"maxilla.stl\"},\n"
    "          {\"role\": \"mandible\", \"mesh\": \"mandible.stl\",\n"
    "           \"transform\": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, -2.0, 0, 0, 0, 1]}],\n"
    " \"base\": {\"spacing_mm\": 0.42, \"auto\": {}},\n"
    " \"printer\": \"eden260\"}\n";

/* The auto case's parameters: read, refused out of range, not switched off without picks. */
static void test_auto_params(sc_context* ctx, sc_case* c) {
  sc_case_params p, q;
  char text[512];
  CHECK_OK(ctx, sc_case_get_params(ctx, c, &p));
  CHECK(p.auto_outline == 1 && p.has_insertion_direction == 0);
  CHECK(p.auto_indentation_depth_mm == 2.0 && p.auto_overhang_mm == 2.0);
  CHECK(p.auto_pick_spacing_mm == 3.0 && p.auto_has_bite_opening == 0);
  q = p;
  q.auto_pick_spacing_mm = 1.0;
  CHECK(sc_case_set_params(ctx, c, &q) == SC_INVALID_ARGUMENT);
  last_message(ctx, text, sizeof text);
  CHECK(contains(text, "auto_pick_spacing_mm"));
  q = p;
  q.auto_has_bite_opening = 1;
  q.auto_bite_opening_mm = 20;
  CHECK(sc_case_set_params(ctx, c, &q) == SC_INVALID_ARGUMENT);
  last_message(ctx, text, sizeof text);
  CHECK(contains(text, "auto_bite_opening_mm"));
  q = p;
  q.auto_outline = 0;
  CHECK(sc_case_set_params(ctx, c, &q) == SC_INVALID_ARGUMENT);
  last_message(ctx, text, sizeof text);
  CHECK(contains(text, "no picks"));
  CHECK(sc_case_pick_count(c, SC_PICKS_UPPER) == 0 && sc_case_arch_count(c) == 0);
  /* A valid change sticks (and is set back). */
  q = p;
  q.auto_overhang_mm = 1.5;
  CHECK_OK(ctx, sc_case_set_params(ctx, c, &q));
  CHECK_OK(ctx, sc_case_get_params(ctx, c, &q));
  CHECK(q.auto_overhang_mm == 1.5);
  /* Distal ends: refused when not finite, kept as given. */
  CHECK(p.auto_has_distal_ends == 0);
  q = p;
  q.auto_has_distal_ends = 1;
  q.auto_distal_ends[0][0] = 20;
  q.auto_distal_ends[1][1] = strtod("nan", NULL);
  CHECK(sc_case_set_params(ctx, c, &q) == SC_INVALID_ARGUMENT);
  last_message(ctx, text, sizeof text);
  CHECK(contains(text, "auto_distal_ends[1] must be finite"));
  q.auto_distal_ends[1][1] = -6.5;
  CHECK_OK(ctx, sc_case_set_params(ctx, c, &q));
  CHECK_OK(ctx, sc_case_get_params(ctx, c, &q));
  CHECK(q.auto_has_distal_ends == 1 && q.auto_distal_ends[0][0] == 20);
  CHECK(q.auto_distal_ends[1][1] == -6.5);
  CHECK_OK(ctx, sc_case_set_params(ctx, c, &p));
  CHECK_OK(ctx, sc_case_get_params(ctx, c, &q));
  CHECK(q.auto_has_distal_ends == 0);
}

static int near(double a, double b) { return a - b < 1e-4 && b - a < 1e-4; }

/* max_wall_crossing through the parameters: 1 as parsed (never refused), out of [0, 1]
 * refused naming it (nothing changed), a share kept. */
static void test_max_wall_crossing(sc_context* ctx, sc_case* c) {
  sc_case_params p, q;
  char text[512];
  CHECK_OK(ctx, sc_case_get_params(ctx, c, &p));
  CHECK(p.max_wall_crossing == 1);
  q = p;
  q.max_wall_crossing = 1.5;
  CHECK(sc_case_set_params(ctx, c, &q) == SC_INVALID_ARGUMENT);
  last_message(ctx, text, sizeof text);
  CHECK(contains(text, "max_wall_crossing is 1.5, must be in [0, 1]"));
  CHECK_OK(ctx, sc_case_get_params(ctx, c, &q));
  CHECK(q.max_wall_crossing == 1);
  q.max_wall_crossing = 0.25;
  CHECK_OK(ctx, sc_case_set_params(ctx, c, &q));
  CHECK_OK(ctx, sc_case_get_params(ctx, c, &q));
  CHECK(q.max_wall_crossing == 0.25);
  CHECK_OK(ctx, sc_case_set_params(ctx, c, &p));
  /* max_sideways_crossing likewise: 0.05 as parsed, out of [0, 1] refused, a share kept. */
  CHECK(p.max_sideways_crossing == 0.05);
  q = p;
  q.max_sideways_crossing = -0.5;
  CHECK(sc_case_set_params(ctx, c, &q) == SC_INVALID_ARGUMENT);
  last_message(ctx, text, sizeof text);
  CHECK(contains(text, "max_sideways_crossing is -0.5, must be in [0, 1]"));
  CHECK_OK(ctx, sc_case_get_params(ctx, c, &q));
  CHECK(q.max_sideways_crossing == 0.05);
  q.max_sideways_crossing = 1;
  CHECK_OK(ctx, sc_case_set_params(ctx, c, &q));
  CHECK_OK(ctx, sc_case_get_params(ctx, c, &q));
  CHECK(q.max_sideways_crossing == 1);
  CHECK_OK(ctx, sc_case_set_params(ctx, c, &p));
}

/* The survey through the C API: auto_survey kept by the parameters; sc_outline then tries
 * directions within 15 degrees of the occlusal normal and keeps one that leaves no more undercut
 * than the normal. */
static void test_outline_survey(sc_context* ctx, sc_case* c, const sc_mesh* const* jaws) {
  sc_case_params p, q;
  sc_case* surveyed = NULL;
  sc_outline_report r;
  double cosine = 0;
  int i;
  CHECK_OK(ctx, sc_case_get_params(ctx, c, &p));
  CHECK(p.auto_survey == 0);
  q = p;
  q.auto_survey = 1;
  CHECK_OK(ctx, sc_case_set_params(ctx, c, &q));
  CHECK_OK(ctx, sc_case_get_params(ctx, c, &q));
  CHECK(q.auto_survey == 1);
  CHECK_OK(ctx, sc_outline(ctx, c, jaws, 2, &surveyed, &r));
  CHECK_OK(ctx, sc_case_set_params(ctx, c, &p));
  if (surveyed == NULL) return;
  for (i = 0; i < 3; ++i) cosine += r.insertion_direction[i] * r.occlusal_normal[i];
  CHECK(r.surveyed == 1 && r.survey_directions >= 25);
  CHECK(cosine >= 0.9659 - 1e-12); /* cos 15 degrees */
  CHECK(r.undercut_chosen_mm3 <= r.undercut_plain_mm3);
  printf("outline with survey: %u directions, undercut %.4f mm3 (the normal: %.4f mm3)\n",
         r.survey_directions, r.undercut_chosen_mm3, r.undercut_plain_mm3);
}

/* Distal ends through the C API: the resolved case's third and third-last upper picks as the
 * limits give fewer picks, the first and last at the limits, and the report says so. */
static void test_outline_distal_ends(sc_context* ctx, sc_case* c, const sc_case* resolved,
                                     const sc_mesh* const* jaws) {
  sc_case_params p, q;
  sc_case* limited = NULL;
  sc_outline_report r;
  const size_t n = sc_case_pick_count(resolved, SC_PICKS_UPPER);
  double first[3], last[3];
  if (n < 8) return;
  CHECK_OK(ctx, sc_case_get_params(ctx, c, &p));
  q = p;
  q.auto_has_distal_ends = 1;
  sc_case_pick(resolved, SC_PICKS_UPPER, n - 3, q.auto_distal_ends[0], NULL, NULL, NULL);
  sc_case_pick(resolved, SC_PICKS_UPPER, 2, q.auto_distal_ends[1], NULL, NULL, NULL);
  CHECK_OK(ctx, sc_case_set_params(ctx, c, &q));
  CHECK_OK(ctx, sc_outline(ctx, c, jaws, 2, &limited, &r));
  CHECK_OK(ctx, sc_case_set_params(ctx, c, &p));
  if (limited == NULL) return;
  CHECK(r.distal_limited == 1 && r.picks == sc_case_pick_count(limited, SC_PICKS_UPPER));
  CHECK(r.picks + 4 <= n && r.picks + 6 >= n);
  CHECK(r.distal_cut_mm[0] > 3 && r.distal_cut_mm[1] > 3);
  CHECK(r.distal_offset_mm[0] < 1e-6 && r.distal_offset_mm[1] < 1e-6);
  sc_case_pick(limited, SC_PICKS_UPPER, 0, first, NULL, NULL, NULL);
  sc_case_pick(limited, SC_PICKS_UPPER, r.picks - 1, last, NULL, NULL, NULL);
  CHECK(near(first[0], q.auto_distal_ends[1][0]) && near(first[1], q.auto_distal_ends[1][1]));
  CHECK(near(last[0], q.auto_distal_ends[0][0]) && near(last[1], q.auto_distal_ends[0][1]));
  printf("outline with distal ends: %u of %u picks, cut %.3f and %.3f mm\n", r.picks, (unsigned)n,
         r.distal_cut_mm[0], r.distal_cut_mm[1]);
}

/* sc_case_set_pick: every refusal leaves the pick as it was; an edited pick gives another
 * splint, and setting it back the same bytes as before. */
static void test_set_pick(sc_context* ctx, sc_case* resolved, const sc_mesh* const* jaws,
                          const char* h_resolved) {
  const size_t n = sc_case_pick_count(resolved, SC_PICKS_UPPER), k = n / 2;
  double pos[3], dir[3], inner = 0, outside = 0, pos2[3], dir2[3], inner2 = 0, outside2 = 0;
  double moved[3], nan3[3];
  const double nan = strtod("nan", NULL);
  char h_edited[65], h_back[65];
  sc_mesh* splint = NULL;
  int i;
  if (n < 3) return;
  CHECK(sc_case_pick(resolved, SC_PICKS_UPPER, k, pos, dir, &inner, &outside) == 1);
  for (i = 0; i < 3; ++i) {
    moved[i] = pos[i] + 0.5 * dir[i];
    nan3[i] = i == 1 ? nan : pos[i];
  }
  CHECK(refused_with(ctx,
                     sc_case_set_pick(ctx, resolved, SC_PICKS_UPPER, n, pos, dir, inner, outside),
                     "sc_case_set_pick: index"));
  CHECK(refused_with(ctx, SC_INVALID_ARGUMENT, "out of range"));
  CHECK(refused_with(ctx, sc_case_set_pick(ctx, resolved, 7, 0, pos, dir, inner, outside),
                     "`which` is 7"));
  CHECK(refused_with(ctx,
                     sc_case_set_pick(ctx, resolved, SC_PICKS_UPPER, k, nan3, dir, inner, outside),
                     "the position must be finite"));
  CHECK(refused_with(ctx,
                     sc_case_set_pick(ctx, resolved, SC_PICKS_UPPER, k, pos, nan3, inner, outside),
                     "the direction must be finite"));
  CHECK(refused_with(ctx,
                     sc_case_set_pick(ctx, resolved, SC_PICKS_UPPER, k, NULL, NULL, nan, outside),
                     "sc_case_set_pick: inner_mm is nan"));
  CHECK(refused_with(ctx,
                     sc_case_set_pick(ctx, resolved, SC_PICKS_UPPER, k, NULL, NULL, inner, 101),
                     "outside_mm is 101, must be in [0, 100]"));
  CHECK(sc_case_set_pick(NULL, resolved, SC_PICKS_UPPER, k, pos, dir, inner, outside) != SC_OK);
  CHECK(sc_case_set_pick(ctx, NULL, SC_PICKS_UPPER, k, pos, dir, inner, outside) ==
        SC_INVALID_ARGUMENT);
  CHECK(sc_case_pick(resolved, SC_PICKS_UPPER, k, pos2, dir2, &inner2, &outside2) == 1);
  CHECK(memcmp(pos, pos2, sizeof pos) == 0 && memcmp(dir, dir2, sizeof dir) == 0);
  CHECK(inner == inner2 && outside == outside2);
  /* An edit: 0.5 mm buccal, a longer inner line; read back as set. */
  CHECK_OK(ctx,
           sc_case_set_pick(ctx, resolved, SC_PICKS_UPPER, k, moved, NULL, inner + 1, outside));
  CHECK(sc_case_pick(resolved, SC_PICKS_UPPER, k, pos2, dir2, &inner2, &outside2) == 1);
  CHECK(memcmp(moved, pos2, sizeof moved) == 0 && memcmp(dir, dir2, sizeof dir) == 0);
  CHECK(inner2 == inner + 1 && outside2 == outside);
  CHECK_OK(ctx, sc_design(ctx, resolved, jaws, 2, &splint, NULL));
  if (splint != NULL) splint_hash(ctx, splint, h_edited);
  CHECK(splint != NULL && strcmp(h_edited, h_resolved) != 0);
  /* Set back: the same bytes as before. */
  splint = NULL;
  CHECK_OK(ctx, sc_case_set_pick(ctx, resolved, SC_PICKS_UPPER, k, pos, dir, inner, outside));
  CHECK_OK(ctx, sc_design(ctx, resolved, jaws, 2, &splint, NULL));
  if (splint != NULL) splint_hash(ctx, splint, h_back);
  CHECK(splint != NULL && strcmp(h_back, h_resolved) == 0);
  printf("set pick %u: edited splint %.12s..., set back %.12s...\n", (unsigned)k, h_edited, h_back);
}

/* The resolved case's picks and arch, and the case written and read back with the same picks. */
static void test_resolved_case(sc_context* ctx, const sc_case* resolved, const sc_outline_report* r,
                               sc_case** reread) {
  double pos[3], dir[3], inner = 0, outside = 0, pos2[3], dir2[3], inner2 = 0, outside2 = 0;
  size_t i, n = sc_case_pick_count(resolved, SC_PICKS_UPPER), bad = 0;
  unsigned char* text = (unsigned char*)malloc((size_t)1 << 20);
  sc_memory_sink_state state;
  sc_sink sink = sc_memory_sink(&state, text, (size_t)1 << 20, "resolved.json");
  sc_case_params p;
  CHECK(n == r->picks && n >= 10);
  CHECK(sc_case_pick_count(resolved, SC_PICKS_LOWER) == n);
  CHECK(sc_case_pick_count(resolved, 7) == 0);
  CHECK(sc_case_pick(resolved, SC_PICKS_UPPER, n, pos, dir, &inner, &outside) == 0);
  CHECK(sc_case_pick(resolved, SC_PICKS_LOWER, 0, NULL, NULL, NULL, NULL) == 1);
  CHECK(sc_case_arch_count(resolved) >= 2);
  CHECK(sc_case_arch_point(resolved, 0, pos) == 1);
  CHECK(sc_case_arch_point(resolved, sc_case_arch_count(resolved), pos) == 0);
  CHECK_OK(ctx, sc_case_get_params(ctx, resolved, &p));
  CHECK(p.auto_outline == 0 && p.has_insertion_direction == 1);
  g_counting = 1;
  CHECK_OK(ctx, sc_case_write(ctx, resolved, &sink));
  g_counting = 0;
  CHECK(state.size > 100 && contains((const char*)text, "\"upper\""));
  CHECK_OK(ctx, sc_case_parse(ctx, (const char*)text, (size_t)state.size, "resolved.json", reread));
  if (*reread != NULL) {
    CHECK(sc_case_pick_count(*reread, SC_PICKS_UPPER) == n);
    for (i = 0; i < n; ++i) {
      int which;
      for (which = SC_PICKS_UPPER; which <= SC_PICKS_LOWER; ++which) {
        sc_case_pick(resolved, which, i, pos, dir, &inner, &outside);
        sc_case_pick(*reread, which, i, pos2, dir2, &inner2, &outside2);
        if (memcmp(pos, pos2, sizeof pos) != 0 || memcmp(dir, dir2, sizeof dir) != 0 ||
            inner != inner2 || outside != outside2 || !(inner > 0 && outside > 0)) {
          ++bad;
        }
      }
    }
    CHECK(bad == 0);
  }
  free(text);
}

/* The automatic outline: sc_outline's report and resolved case, its errors, and the designs
 * of the auto case, the resolved case and the resolved case written and read back, which
 * must be the same splint bytes; the report of the auto design has the "outline" object. */
static void test_outline(const char* jaws_dir) {
  Fixture f = open_fixture((size_t)96 << 20);
  sc_case *c = NULL, *resolved = NULL, *reread = NULL;
  const sc_mesh* jaws[2] = {NULL, NULL};
  sc_mesh *auto_splint = NULL, *resolved_splint = NULL, *reread_splint = NULL;
  sc_outline_report r;
  sc_design_report d;
  Bytes jaw_bytes[2] = {{NULL, 0}, {NULL, 0}};
  char text[512], h_auto[65], h_resolved[65], h_reread[65];
  unsigned char* json = (unsigned char*)malloc((size_t)1 << 20);
  sc_memory_sink_state state;
  sc_sink sink = sc_memory_sink(&state, json, (size_t)1 << 20, "report");
  sc_arena_mark mark;
  size_t i;

  CHECK_OK(f.ctx, sc_case_parse(f.ctx, kAutoCase, sizeof kAutoCase - 1, "auto.json", &c));
  if (c == NULL) return;
  for (i = 0; i < 2; ++i) {
    sc_mesh* m = NULL;
    jaw_bytes[i] = read_file(jaws_dir, sc_case_jaw_mesh(c, i));
    if (jaw_bytes[i].data == NULL) return;
    CHECK_OK(f.ctx, read_mesh(f.ctx, &jaw_bytes[i], sc_case_jaw_mesh(c, i), &m));
    jaws[i] = m;
  }
  test_auto_params(f.ctx, c);
  /* Errors: one jaw only, a case with its picks; the arena back where it was. */
  mark = sc_arena_mark_get(f.ctx);
  resolved = (sc_case*)&f;
  CHECK(sc_outline(f.ctx, c, jaws, 1, &resolved, &r) == SC_INVALID_ARGUMENT);
  CHECK(resolved == NULL && sc_arena_used(f.ctx) == mark.used);
  last_message(f.ctx, text, sizeof text);
  CHECK(contains(text, "outline") && contains(text, "2 jaws") && contains(text, "1 meshes"));
  printf("outline with one jaw: %s\n", text);
  CHECK(sc_outline(f.ctx, c, jaws, 2, NULL, &r) == SC_INVALID_ARGUMENT);

  g_counting = 1;
  CHECK_OK(f.ctx, sc_outline(f.ctx, c, jaws, 2, &resolved, &r));
  g_counting = 0;
  if (resolved == NULL) return;
  CHECK(r.occlusal_normal[2] > 0.99 && r.anterior[1] > 0.9);
  CHECK(r.jaws_intersect == 0 && r.opened == 0 && r.gap_as_given_mm > 0);
  CHECK(r.arch_length_mm > 20 && r.wafer_min_mm > 0 && r.wafer_max_mm >= r.wafer_min_mm);
  CHECK(r.occlusal_columns_maxilla > 0 && r.occlusal_columns_mandible > 0);
  CHECK(r.distal_limited == 0 && r.surveyed == 0);
  CHECK(r.insertion_direction[0] == r.occlusal_normal[0] &&
        r.insertion_direction[1] == r.occlusal_normal[1] &&
        r.insertion_direction[2] == r.occlusal_normal[2]);
  printf("outline: %u picks per jaw, arch %.2f mm, wafer %.3f..%.3f mm, gap %.3f mm\n", r.picks,
         r.arch_length_mm, r.wafer_min_mm, r.wafer_max_mm, r.gap_as_given_mm);
  {
    sc_case* again = NULL; /* a resolved case is no auto case */
    CHECK(sc_outline(f.ctx, resolved, jaws, 2, &again, NULL) == SC_INVALID_ARGUMENT);
    last_message(f.ctx, text, sizeof text);
    CHECK(contains(text, "auto"));
  }
  test_resolved_case(f.ctx, resolved, &r, &reread);

  g_counting = 1;
  CHECK_OK(f.ctx, sc_design(f.ctx, c, jaws, 2, &auto_splint, &d));
  g_counting = 0;
  if (auto_splint == NULL) return;
  CHECK(d.outlined == 1 && d.printable == 1);
  splint_hash(f.ctx, auto_splint, h_auto);
  CHECK_OK(f.ctx, sc_design_write_report(f.ctx, c, jaws, 2, auto_splint, NULL, &sink));
  json[state.size < ((size_t)1 << 20) ? state.size : 0] = 0;
  CHECK(contains((const char*)json, "\"outline\":{\"occlusal_normal\""));
  CHECK(contains((const char*)json, "\"picks_per_jaw\""));
  CHECK_OK(f.ctx, sc_design(f.ctx, resolved, jaws, 2, &resolved_splint, &d));
  CHECK(d.outlined == 0);
  if (resolved_splint != NULL) splint_hash(f.ctx, resolved_splint, h_resolved);
  CHECK(resolved_splint != NULL && strcmp(h_auto, h_resolved) == 0);
  if (resolved_splint != NULL) test_set_pick(f.ctx, resolved, jaws, h_resolved);
  test_outline_distal_ends(f.ctx, c, resolved, jaws);
  test_outline_survey(f.ctx, c, jaws);
  test_max_wall_crossing(f.ctx, c);
  if (reread != NULL) {
    CHECK_OK(f.ctx, sc_design(f.ctx, reread, jaws, 2, &reread_splint, NULL));
    if (reread_splint != NULL) splint_hash(f.ctx, reread_splint, h_reread);
    CHECK(reread_splint != NULL && strcmp(h_auto, h_reread) == 0);
  }
  printf("auto design: %llu triangles, sha256 %s (the resolved case's too)\n",
         (unsigned long long)sc_mesh_triangle_count(auto_splint), h_auto);
  close_fixture(&f);
  for (i = 0; i < 2; ++i) free(jaw_bytes[i].data);
  free(json);
}

/* Scan-CT fusion: the torus onto itself (the identity, RMS 0); a wrong landmark pairing is
 * refused with the pair named. */
static void test_register(const Bytes* torus) {
  Fixture f = open_fixture((size_t)8 << 20);
  sc_mesh* m = NULL;
  sc_register_result r;
  sc_register_options o;
  /* Three points of the torus paired with each other's places: no rotation fits. */
  double pairs[18] = {10, 0, 0, 0, 10, 0, 0, 10, 0, -10, 0, 0, -10, 0, 0, 10, 0, 0};
  char text[512];
  int i;
  CHECK_OK(f.ctx, read_mesh(f.ctx, torus, "torus_binary.stl", &m));
  g_counting = 1;
  CHECK_OK(f.ctx, sc_register_rigid(f.ctx, m, m, NULL, &r));
  for (i = 0; i < 16; ++i) {
    const double off = r.transform[i] - ((i % 5 == 0) ? 1.0 : 0.0);
    CHECK(off < 1e-9 && off > -1e-9);
  }
  CHECK(r.rms_mm < 1e-9 && r.overlap == 1.0 && r.samples > 16);
  memset(&o, 0, sizeof o);
  o.landmarks = pairs;
  o.landmark_count = 3;
  CHECK(sc_register_rigid(f.ctx, m, m, &o, &r) == SC_INVALID_ARGUMENT);
  last_message(f.ctx, text, sizeof text);
  CHECK(contains(text, "landmarks"));
  g_counting = 0;
  close_fixture(&f);
}

/* ---- two-jaw surgery (sc_design_plan) ------------------------------------------------------ */

/* The arena splintcore.h documents for the phantom plan, jaws and job included. */
#define PLAN_ARENA_BYTES ((size_t)8 << 20)
#define PLAN_JOB_CAP ((size_t)16 << 20)

typedef struct PlanRun {
  sc_status status;
  size_t high_water;
  size_t used_before; /* the arena in use before sc_design_plan */
  size_t used_after;  /* and after it */
  int handles_null;   /* both handles NULL */
  char sha256[3][65]; /* intermediate.stl, final.stl, job.3mf */
  sc_plan_report report;
} PlanRun;

/* run_plan calls sc_design_plan_scans (with no scan for either jaw) instead. */
static int g_plan_scans = 0;

/* fixtures/cases/plan.json with the phantom jaws in an arena of `arena_bytes`. */
static PlanRun run_plan(size_t arena_bytes, const Bytes* case_text, const Bytes jaw_bytes[2]) {
  PlanRun run;
  Fixture f = open_fixture(arena_bytes);
  sc_case* c = NULL;
  const sc_mesh* jaws[2] = {NULL, NULL};
  sc_mesh* splints[2] = {NULL, NULL};
  unsigned char* job = (unsigned char*)malloc(PLAN_JOB_CAP);
  sc_memory_sink_state job_state;
  sc_sink job_sink = sc_memory_sink(&job_state, job, PLAN_JOB_CAP, "job.3mf");
  size_t i;
  memset(&run, 0, sizeof run);
  g_counting = 1;
  run.status = sc_case_parse(f.ctx, (const char*)case_text->data, case_text->size, "plan.json", &c);
  for (i = 0; i < 2 && run.status == SC_OK; ++i) {
    sc_mesh* m = NULL;
    run.status = read_mesh(f.ctx, &jaw_bytes[i], "jaw.stl", &m);
    jaws[i] = m;
  }
  if (run.status == SC_OK) {
    const sc_mesh* const no_scans[2] = {NULL, NULL};
    run.used_before = sc_arena_used(f.ctx);
    run.status = g_plan_scans ? sc_design_plan_scans(f.ctx, c, jaws, no_scans, 2, &splints[0],
                                                     &splints[1], &job_sink, &run.report)
                              : sc_design_plan(f.ctx, c, jaws, 2, &splints[0], &splints[1],
                                               &job_sink, &run.report);
    run.used_after = sc_arena_used(f.ctx);
    run.handles_null = splints[0] == NULL && splints[1] == NULL;
  }
  g_counting = 0;
  run.high_water = sc_arena_high_water(f.ctx);
  if (run.status == SC_OK) {
    for (i = 0; i < 2; ++i) splint_hash(f.ctx, splints[i], run.sha256[i]);
    sc_sha256_hex(job, (size_t)job_state.size, run.sha256[2]);
  } else {
    char text[512];
    sc_status_message(f.ctx, text, sizeof text);
    printf("sc_design_plan in %llu bytes: %s: %s\n", (unsigned long long)arena_bytes,
           sc_status_name(run.status), text);
  }
  free(job);
  close_fixture(&f);
  return run;
}

/* The CLI's file in `cli_dir` has the SHA-256 `want`. */
static int cli_file_is(const char* cli_dir, const char* name, const char* want) {
  Bytes b = read_file(cli_dir, name);
  char hash[65];
  if (b.data == NULL) return 0;
  sc_sha256_hex(b.data, b.size, hash);
  free(b.data);
  return strcmp(hash, want) == 0;
}

/* Two-jaw surgery: fixtures/cases/plan.json designed with the phantom jaws through the C API
 * in the arena splintcore.h documents. Both splints and the print job are the bytes the C++
 * design_plan and write_plan_job give (pinned from C++ by DesignGolden.PlanSplintsAndPrintJob)
 * and, with `cli_dir`, those `splintcore design` wrote there; the same again in exactly the
 * arena's high water mark; one byte less fails cleanly (the arena as sc_design_plan found it,
 * both handles NULL). */
static void test_design_plan(const char* jaws_dir, const char* cli_dir) {
  static const char* const kKeys[3] = {"design:plan-intermediate-phantom6000",
                                       "design:plan-final-phantom6000",
                                       "design:plan-job3mf-phantom6000"};
  static const char* const kFiles[3] = {"intermediate.stl", "final.stl", "job.3mf"};
  Bytes case_text = read_file(g_fixtures, "cases/plan.json");
  Bytes jaw_bytes[2];
  PlanRun first, exact, short_by_one;
  char golden[65];
  int k;
  jaw_bytes[0] = read_file(jaws_dir, "maxilla.stl");
  jaw_bytes[1] = read_file(jaws_dir, "mandible.stl");
  CHECK(case_text.data != NULL && jaw_bytes[0].data != NULL && jaw_bytes[1].data != NULL);
  if (case_text.data == NULL || jaw_bytes[0].data == NULL || jaw_bytes[1].data == NULL) return;
  first = run_plan(PLAN_ARENA_BYTES, &case_text, jaw_bytes);
  CHECK(first.status == SC_OK);
  if (first.status != SC_OK) return;
  CHECK(first.high_water <= PLAN_ARENA_BYTES);
  CHECK(first.report.printable[0] == 1 && first.report.printable[1] == 1);
  CHECK(first.report.outlined[0] == 1 && first.report.outlined[1] == 1);
  CHECK(strcmp(first.report.label_text[0], "INT P1") == 0);
  CHECK(strcmp(first.report.label_text[1], "FIN P1") == 0);
  CHECK(first.report.job_written == 1);
  CHECK(first.report.opening_mm[0] > 1.999999 && first.report.opening_mm[0] < 2.000001);
  CHECK(first.report.opening_mm[1] > 1.499999 && first.report.opening_mm[1] < 1.500001);
  CHECK(first.report.angle_rad[0] != first.report.angle_rad[1]);
  for (k = 0; k < 3; ++k) {
    read_golden(kKeys[k], golden);
    CHECK(strlen(golden) == 64);
    CHECK(strcmp(first.sha256[k], golden) == 0);
    if (cli_dir != NULL) CHECK(cli_file_is(cli_dir, kFiles[k], first.sha256[k]));
  }
  printf(
      "plan: intermediate %llu triangles (%.9f rad), final %llu triangles (%.9f rad); "
      "arena high water %llu bytes; job.3mf sha256 %s\n",
      (unsigned long long)first.report.triangles[0], first.report.angle_rad[0],
      (unsigned long long)first.report.triangles[1], first.report.angle_rad[1],
      (unsigned long long)first.high_water, first.sha256[2]);
  exact = run_plan(first.high_water, &case_text, jaw_bytes);
  CHECK(exact.status == SC_OK);
  for (k = 0; k < 3; ++k) CHECK(strcmp(exact.sha256[k], first.sha256[k]) == 0);
  /* sc_design_plan_scans with no scans (the case has none): the same bytes. */
  g_plan_scans = 1;
  exact = run_plan(PLAN_ARENA_BYTES, &case_text, jaw_bytes);
  g_plan_scans = 0;
  CHECK(exact.status == SC_OK);
  for (k = 0; k < 3; ++k) CHECK(strcmp(exact.sha256[k], first.sha256[k]) == 0);
  short_by_one = run_plan(first.high_water - 1, &case_text, jaw_bytes);
  CHECK(short_by_one.status == SC_ARENA_EXHAUSTED);
  CHECK(short_by_one.used_after == short_by_one.used_before);
  CHECK(short_by_one.handles_null);
  free(case_text.data);
  free(jaw_bytes[0].data);
  free(jaw_bytes[1].data);
}

/* Two-jaw surgery with a scan (sc_design_plan_scans): fixtures/cases/plan.json with the mandible
 * given a "scan", the mandible's own mesh moved by a known translation. The plan's report gives
 * the fusion of each jaw: none for the maxilla; for the mandible the registration (scan -> the
 * jaw), which takes the translation back, its RMS and overlap; both splints are printable.
 * Without the scans the case is refused, naming the jaw. */
static void test_design_plan_scans(const char* jaws_dir) {
  static const char kMesh[] = "\"mesh\": \"mandible.stl\"";
  static const char kScan[] = ", \"scan\": {\"path\": \"mandible_scan.stl\", \"max_rms_mm\": 0.01}";
  static const double kMove[3] = {0.7, -0.4, 0.3};
  Bytes case_text = read_file(g_fixtures, "cases/plan.json");
  Bytes jaw_bytes[2];
  Fixture f = open_fixture((size_t)64 << 20);
  const char* text = (const char*)case_text.data;
  const char* at = NULL;
  char* fused_text = NULL;
  size_t head, i, length;
  sc_case* c = NULL;
  const sc_mesh* jaws[2] = {NULL, NULL};
  const sc_mesh* scans[2] = {NULL, NULL};
  sc_mesh* scan = NULL;
  sc_mesh* splints[2] = {NULL, NULL};
  sc_plan_report report;
  double* vertices = NULL;
  uint32_t* triangles = NULL;
  uint64_t nv, nt;
  char message[512];
  jaw_bytes[0] = read_file(jaws_dir, "maxilla.stl");
  jaw_bytes[1] = read_file(jaws_dir, "mandible.stl");
  CHECK(case_text.data != NULL && jaw_bytes[0].data != NULL && jaw_bytes[1].data != NULL);
  if (case_text.data == NULL || jaw_bytes[0].data == NULL || jaw_bytes[1].data == NULL) return;
  for (i = 0; i + sizeof kMesh - 1 <= case_text.size && at == NULL; ++i) {
    if (memcmp(text + i, kMesh, sizeof kMesh - 1) == 0) at = text + i;
  }
  CHECK(at != NULL);
  if (at == NULL) return;
  head = (size_t)(at - text) + sizeof kMesh - 1;
  length = case_text.size + sizeof kScan - 1;
  fused_text = (char*)malloc(length);
  memcpy(fused_text, text, head);
  memcpy(fused_text + head, kScan, sizeof kScan - 1);
  memcpy(fused_text + head + sizeof kScan - 1, text + head, case_text.size - head);
  CHECK_OK(f.ctx, sc_case_parse(f.ctx, fused_text, length, "plan-scan.json", &c));
  free(fused_text);
  for (i = 0; i < 2 && c != NULL; ++i) {
    sc_mesh* m = NULL;
    CHECK_OK(f.ctx, read_mesh(f.ctx, &jaw_bytes[i], i == 0 ? "maxilla.stl" : "mandible.stl", &m));
    jaws[i] = m;
  }
  if (c == NULL || jaws[0] == NULL || jaws[1] == NULL) return;
  /* The scan: the mandible moved by kMove. */
  nv = sc_mesh_vertex_count(jaws[1]);
  nt = sc_mesh_triangle_count(jaws[1]);
  vertices = (double*)malloc((size_t)nv * 3 * sizeof(double));
  triangles = (uint32_t*)malloc((size_t)nt * 3 * sizeof(uint32_t));
  CHECK_OK(f.ctx, sc_mesh_copy_vertices(f.ctx, jaws[1], vertices, (size_t)nv * 3));
  CHECK_OK(f.ctx, sc_mesh_copy_triangles(f.ctx, jaws[1], triangles, (size_t)nt * 3));
  for (i = 0; i < (size_t)nv * 3; ++i) vertices[i] += kMove[i % 3];
  CHECK_OK(f.ctx,
           sc_mesh_from_arrays(f.ctx, vertices, (uint32_t)nv, triangles, (uint32_t)nt, &scan));
  free(vertices);
  free(triangles);
  scans[1] = scan;
  /* Without the scans the case is refused, naming the jaw. */
  CHECK(sc_design_plan(f.ctx, c, jaws, 2, &splints[0], &splints[1], NULL, &report) ==
        SC_INVALID_ARGUMENT);
  last_message(f.ctx, message, sizeof message);
  CHECK(contains(message, "jaw 1 (mandible) has a \"scan\""));
  CHECK(splints[0] == NULL && splints[1] == NULL);
  memset(&report, 0xff, sizeof report); /* every field must be written */
  CHECK_OK(f.ctx,
           sc_design_plan_scans(f.ctx, c, jaws, scans, 2, &splints[0], &splints[1], NULL, &report));
  if (splints[0] != NULL && splints[1] != NULL) {
    CHECK(report.printable[0] == 1 && report.printable[1] == 1);
    CHECK(report.fused[0] == 0 && report.fused[1] == 1);
    CHECK(report.fusion_rms_mm[0] == 0 && report.fusion_overlap[0] == 0);
    for (i = 0; i < 16; ++i) CHECK(report.fusion_transform[0][i] == 0);
    CHECK(report.fusion_rms_mm[1] >= 0 && report.fusion_rms_mm[1] < 1e-3);
    CHECK(report.fusion_overlap[1] > 0.99 && report.fusion_overlap[1] <= 1);
    for (i = 0; i < 16; ++i) {
      /* scan -> jaw: the identity rotation and the move taken back. */
      const double want = (i % 5 == 0) ? 1.0 : (i % 4 == 3 && i < 12) ? -kMove[i / 4] : 0.0;
      const double off = report.fusion_transform[1][i] - want;
      CHECK(off < 1e-4 && off > -1e-4);
    }
    printf(
        "plan with the mandible's scan: rms %.3g mm, overlap %.3f, translation back "
        "(%.6f, %.6f, %.6f); arena high water %llu bytes\n",
        report.fusion_rms_mm[1], report.fusion_overlap[1], report.fusion_transform[1][3],
        report.fusion_transform[1][7], report.fusion_transform[1][11],
        (unsigned long long)sc_arena_high_water(f.ctx));
  }
  close_fixture(&f);
  free(case_text.data);
  free(jaw_bytes[0].data);
  free(jaw_bytes[1].data);
}

/* Every entry point given a NULL where it needs a pointer: SC_INVALID_ARGUMENT, kept in the
 * context, with a message naming the function and what was NULL; nothing allocated. Then the
 * ranges the C layer checks itself: too many meshes or a NULL one in a list, a non-finite
 * vertex, an output array too small, a zero read or write buffer, a bad solid name, and the
 * case parameters' corner segments, insertion direction and closing radius. */
static void test_null_and_range_refusals(const Bytes* torus, const Bytes* case_text) {
  Fixture f = open_fixture((size_t)4 << 20);
  sc_context* ctx = f.ctx;
  sc_mesh* m = NULL;
  sc_mesh* out = NULL;
  sc_case* c = NULL;
  sc_memory_sink_state sink_state;
  unsigned char buffer[256];
  const sc_sink sink = sc_memory_sink(&sink_state, buffer, sizeof buffer, "buffer");
  const double z[3] = {0, 0, 1};
  const sc_mesh* jaws[9];
  double vertices[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  uint32_t ids[3] = {0, 1, 2};
  sc_case_params p, q;
  double mm = 0;
  size_t used, i;
  CHECK_OK(ctx, read_mesh(ctx, torus, "torus", &m));
  CHECK_OK(ctx, sc_case_parse(ctx, (const char*)case_text->data, case_text->size,
                              "paper_scale.json", &c));
  used = sc_arena_used(ctx);
  for (i = 0; i < 9; ++i) jaws[i] = m;
  CHECK(refused_with(ctx, sc_mesh_from_arrays(ctx, NULL, 3, ids, 1, &out),
                     "sc_mesh_from_arrays: an array with a non-zero count is NULL"));
  CHECK(refused_with(ctx, sc_mesh_copy_vertices(ctx, NULL, vertices, 9),
                     "sc_mesh_copy_vertices: the mesh or the output is NULL"));
  CHECK(refused_with(ctx, sc_mesh_copy_triangles(ctx, m, NULL, 9),
                     "sc_mesh_copy_triangles: the mesh or the output is NULL"));
  CHECK(refused_with(ctx, sc_mesh_write_stl(ctx, m, NULL, NULL),
                     "sc_mesh_write_stl: the mesh, the sink or its write function is NULL"));
  CHECK(refused_with(ctx, sc_mesh_check(ctx, m, NULL), "sc_mesh_check: the mesh or the report"));
  CHECK(refused_with(ctx, sc_mesh_boolean(ctx, m, NULL, 0, &out),
                     "sc_mesh_boolean: a mesh or the output is NULL"));
  CHECK(refused_with(ctx, sc_sweep(ctx, jaws, 1, NULL, 0.5, &out),
                     "sc_sweep: the direction or the output is NULL"));
  CHECK(refused_with(ctx, sc_register_rigid(ctx, m, m, NULL, NULL),
                     "sc_register_rigid: the scan, the CT jaw or the result is NULL"));
  CHECK(refused_with(ctx, sc_case_parse(ctx, NULL, 10, "x", &c),
                     "sc_case_parse: the text or the output is NULL"));
  CHECK(refused_with(ctx, sc_case_get_params(ctx, c, NULL),
                     "sc_case_get_params: the case or the output is NULL"));
  CHECK(refused_with(ctx, sc_case_set_params(ctx, c, NULL),
                     "sc_case_set_params: the case or the parameters is NULL"));
  CHECK(refused_with(ctx, sc_case_set_blockout_clearance(ctx, NULL, 0.1),
                     "sc_case_set_blockout_clearance: the case is NULL"));
  CHECK(refused_with(ctx, sc_case_write(ctx, c, NULL),
                     "sc_case_write: the case, the sink or its write function is NULL"));
  CHECK(refused_with(ctx, sc_design(ctx, NULL, jaws, 2, &out, NULL),
                     "sc_design: the case or the output is NULL"));
  CHECK(refused_with(ctx, sc_design_scans(ctx, c, jaws, jaws, 2, NULL, NULL),
                     "sc_design_scans: the case or the output is NULL"));
  CHECK(refused_with(ctx, sc_design_write_report(ctx, c, jaws, 2, NULL, NULL, &sink),
                     "sc_design_write_report: the case, the splint or the sink is NULL"));
  CHECK(refused_with(ctx, sc_design_blockout_used(ctx, NULL, 0, &mm, &mm),
                     "sc_design_blockout_used: the splint is NULL"));
  CHECK(refused_with(ctx, sc_design_plan(ctx, NULL, jaws, 2, &out, &out, &sink, NULL),
                     "sc_design_plan: the case or an output is NULL"));
  CHECK(refused_with(ctx, sc_design_plan_scans(ctx, c, jaws, jaws, 2, NULL, &out, &sink, NULL),
                     "sc_design_plan_scans: the case or an output is NULL"));
  {
    sc_sink no_write = sink;
    no_write.write = NULL;
    CHECK(refused_with(ctx, sc_design_plan(ctx, c, jaws, 2, &out, &out, &no_write, NULL),
                       "sc_design_plan: the job sink's write function is NULL"));
  }
  /* Lists of meshes. */
  CHECK(refused_with(ctx, sc_sweep(ctx, jaws, 9, z, 0.5, &out),
                     "sc_sweep: 9 meshes given, at most 8"));
  CHECK(
      refused_with(ctx, sc_sweep(ctx, NULL, 1, z, 0.5, &out), "sc_sweep: the mesh array is NULL"));
  jaws[1] = NULL;
  CHECK(refused_with(ctx, sc_sweep(ctx, jaws, 2, z, 0.5, &out), "sc_sweep: mesh 1 is NULL"));
  {
    sc_location where;
    sc_status_location(ctx, &where);
    CHECK(where.index == 1);
  }
  jaws[1] = m;
  /* Values. */
  vertices[4] = strtod("nan", NULL);
  CHECK(sc_mesh_from_arrays(ctx, vertices, 3, ids, 1, &out) == SC_NON_FINITE);
  {
    char text[256];
    last_message(ctx, text, sizeof text);
    CHECK(contains(text, "sc_mesh_from_arrays: vertex 1 is not finite"));
  }
  CHECK(refused_with(ctx, sc_mesh_copy_triangles(ctx, m, ids, 3),
                     "sc_mesh_copy_triangles: the output holds 3 ids, "));
  {
    sc_stl_read_options r = sc_stl_read_defaults();
    sc_stl_write_options w = sc_stl_write_defaults();
    sc_memory_source_state state;
    sc_source src = sc_memory_source(&state, torus->data, torus->size, "torus");
    r.chunk_bytes = 0;
    CHECK(refused_with(ctx, sc_mesh_read_stl(ctx, &src, &r, &out),
                       "sc_mesh_read_stl: chunk_bytes must be > 0"));
    w.buffer_bytes = 0;
    CHECK(refused_with(ctx, sc_mesh_write_stl(ctx, m, &sink, &w),
                       "sc_mesh_write_stl: buffer_bytes must be > 0"));
    w = sc_stl_write_defaults();
    w.ascii = 1;
    w.solid_name = "no spaces";
    CHECK(refused_with(ctx, sc_mesh_write_stl(ctx, m, &sink, &w),
                       "sc_mesh_write_stl: solid name \"no spaces\" is not 1..80 of"));
  }
  CHECK_OK(ctx, sc_case_get_params(ctx, c, &p));
  q = p;
  q.corner_segments = 3;
  CHECK(refused_with(ctx, sc_case_set_params(ctx, c, &q),
                     "sc_case_set_params: corner_segments is 3, must be 1, 2, 4, 8 or 16"));
  q = p;
  q.has_insertion_direction = 1;
  q.insertion_direction[0] = q.insertion_direction[1] = q.insertion_direction[2] = 0;
  CHECK(refused_with(ctx, sc_case_set_params(ctx, c, &q),
                     "sc_case_set_params: insertion_direction must be finite and non-zero"));
  q = p;
  blockout_along_z(&q, 0.5);
  q.blockout_method = SC_BLOCKOUT_VOXEL;
  q.blockout_closing_mm = 0.5;
  CHECK(refused_with(ctx, sc_case_set_params(ctx, c, &q),
                     "sc_case_set_params: blockout_closing_mm is 0.5, must be 0 or at least two "
                     "voxels (1)"));
  CHECK(sc_arena_used(ctx) == used); /* nothing was kept */
  sc_arena_reset(ctx);
  CHECK(sc_arena_used(ctx) == 0);
  close_fixture(&f);
}

/* A NULL context, everywhere: every call that reports a status refuses it
 * (SC_INVALID_ARGUMENT) and touches nothing, the queries answer 0, "" or an empty mark, the
 * setters and the arena's calls ignore it. Then the pointers each call needs, NULL one at a
 * time with a context: refused, the call named (the other refusal test takes one each). And
 * the "ok" message cut to a short buffer. */
static void test_null_context_everywhere(const Bytes* torus, const Bytes* case_text) {
  Fixture f = open_fixture((size_t)4 << 20);
  sc_context* ctx = f.ctx;
  sc_mesh *m = NULL, *out = NULL, *keep = NULL;
  sc_case *c = NULL, *resolved = NULL;
  sc_memory_sink_state sink_state;
  unsigned char buffer[64];
  const sc_sink sink = sc_memory_sink(&sink_state, buffer, sizeof buffer, "buffer");
  sc_memory_source_state source_state;
  sc_source source;
  const double z[3] = {0, 0, 1};
  const sc_mesh* jaws[2];
  double vertices[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0}, mm = 0;
  uint32_t ids[3] = {0, 1, 2};
  sc_mesh_report report;
  sc_register_result registered;
  sc_case_params params;
  sc_design_report design;
  sc_plan_report plan;
  sc_location where;
  sc_arena_mark mark;
  char text[64];
  size_t used;
  CHECK_OK(ctx, read_mesh(ctx, torus, "torus", &m));
  CHECK_OK(ctx, sc_case_parse(ctx, (const char*)case_text->data, case_text->size,
                              "paper_scale.json", &c));
  CHECK_OK(ctx, sc_case_get_params(ctx, c, &params));
  jaws[0] = jaws[1] = m;
  source = sc_memory_source(&source_state, torus->data, torus->size, "torus");
  used = sc_arena_used(ctx);
  keep = m;
  /* The context's last status is OK here, and stays OK through the NULL-context calls. */
  CHECK(sc_mesh_read_stl(NULL, &source, NULL, &out) == SC_INVALID_ARGUMENT);
  CHECK(sc_mesh_from_arrays(NULL, vertices, 3, ids, 1, &out) == SC_INVALID_ARGUMENT);
  CHECK(sc_mesh_copy_vertices(NULL, m, vertices, 9) == SC_INVALID_ARGUMENT);
  CHECK(sc_mesh_copy_triangles(NULL, m, ids, 3) == SC_INVALID_ARGUMENT);
  CHECK(sc_mesh_write_stl(NULL, m, &sink, NULL) == SC_INVALID_ARGUMENT);
  CHECK(sc_mesh_check(NULL, m, &report) == SC_INVALID_ARGUMENT);
  CHECK(sc_mesh_require_solid(NULL, m) == SC_INVALID_ARGUMENT);
  CHECK(sc_mesh_boolean(NULL, m, m, 0, &out) == SC_INVALID_ARGUMENT);
  CHECK(sc_sweep(NULL, jaws, 1, z, 0.5, &out) == SC_INVALID_ARGUMENT);
  CHECK(sc_blockout(NULL, m, jaws, 1, z, 0.5, 0, &out) == SC_INVALID_ARGUMENT);
  CHECK(sc_blockout_exact(NULL, m, jaws, 1, z, &out) == SC_INVALID_ARGUMENT);
  CHECK(sc_register_rigid(NULL, m, m, NULL, &registered) == SC_INVALID_ARGUMENT);
  CHECK(sc_case_parse(NULL, (const char*)case_text->data, case_text->size, "x", &resolved) ==
        SC_INVALID_ARGUMENT);
  CHECK(sc_case_get_params(NULL, c, &params) == SC_INVALID_ARGUMENT);
  CHECK(sc_case_set_params(NULL, c, &params) == SC_INVALID_ARGUMENT);
  CHECK(sc_case_get_blockout_clearance(NULL, c, &mm) == SC_INVALID_ARGUMENT);
  CHECK(sc_case_set_blockout_clearance(NULL, c, 0.1) == SC_INVALID_ARGUMENT);
  CHECK(sc_case_write(NULL, c, &sink) == SC_INVALID_ARGUMENT);
  CHECK(sc_case_set_pick(NULL, c, SC_PICKS_UPPER, 0, z, NULL, 1, 1) == SC_INVALID_ARGUMENT);
  CHECK(sc_outline(NULL, c, jaws, 2, &resolved, NULL) == SC_INVALID_ARGUMENT);
  CHECK(sc_design(NULL, c, jaws, 2, &out, &design) == SC_INVALID_ARGUMENT);
  CHECK(sc_design_scans(NULL, c, jaws, jaws, 2, &out, &design) == SC_INVALID_ARGUMENT);
  CHECK(sc_write_splint_job(NULL, c, m, &sink) == SC_INVALID_ARGUMENT);
  CHECK(sc_design_write_report(NULL, c, jaws, 2, m, NULL, &sink) == SC_INVALID_ARGUMENT);
  CHECK(sc_design_blockout_used(NULL, m, 0, &mm, &mm) == SC_INVALID_ARGUMENT);
  CHECK(sc_design_plan(NULL, c, jaws, 2, &out, &out, &sink, &plan) == SC_INVALID_ARGUMENT);
  CHECK(sc_design_plan_scans(NULL, c, jaws, jaws, 2, &out, &out, &sink, &plan) ==
        SC_INVALID_ARGUMENT);
  CHECK(sc_last_status(NULL) == SC_INVALID_ARGUMENT);
  CHECK(sc_last_status(ctx) == SC_OK);
  CHECK(sink_state.size == 0);
  text[0] = 'x';
  CHECK(sc_status_message(NULL, text, sizeof text) == 0 && text[0] == '\0');
  CHECK(sc_status_message(NULL, NULL, 0) == 0);
  where.index = 7;
  sc_status_location(NULL, &where);
  CHECK(where.index == SC_NO_POSITION && where.byte_offset == SC_NO_POSITION);
  sc_status_location(ctx, NULL); /* nothing to write to: ignored */
  CHECK(sc_arena_used(NULL) == 0 && sc_arena_cap(NULL) == 0 && sc_arena_high_water(NULL) == 0);
  mark = sc_arena_mark_get(NULL);
  CHECK(mark.block == NULL && mark.offset == 0 && mark.used == 0);
  sc_arena_rewind(NULL, mark);
  sc_arena_reset(NULL);
  sc_context_set_progress(NULL, NULL, NULL);
  sc_context_set_executor(NULL, NULL, NULL, 2);
  sc_context_destroy(NULL);
  CHECK(sc_mesh_vertex_count(NULL) == 0 && sc_mesh_triangle_count(NULL) == 0);
  CHECK(strcmp(sc_case_id(NULL), "") == 0 && sc_case_jaw_count(NULL) == 0);
  CHECK(sc_case_jaw_role(NULL, 0) == NULL && sc_case_jaw_mesh(NULL, 0) == NULL);
  CHECK(sc_case_jaw_role(c, 2) == NULL && sc_case_jaw_mesh(c, 2) == NULL);
  CHECK(sc_case_pick_count(NULL, SC_PICKS_UPPER) == 0);
  CHECK(sc_case_pick(NULL, SC_PICKS_UPPER, 0, vertices, NULL, NULL, NULL) == 0);
  CHECK(sc_case_arch_count(NULL) == 0 && sc_case_arch_point(NULL, 0, vertices) == 0);
  CHECK(sc_arena_used(ctx) == used && m == keep);
  /* With a context: each needed pointer NULL in turn. */
  CHECK(refused_with(ctx, sc_mesh_read_stl(ctx, &source, NULL, NULL), "sc_mesh_read_stl: out"));
  source.read = NULL;
  CHECK(refused_with(ctx, sc_mesh_read_stl(ctx, &source, NULL, &out),
                     "sc_mesh_read_stl: the source or its read function is NULL"));
  CHECK(out == NULL);
  CHECK(refused_with(ctx, sc_mesh_from_arrays(ctx, vertices, 3, ids, 1, NULL),
                     "sc_mesh_from_arrays: out"));
  CHECK(refused_with(ctx, sc_mesh_from_arrays(ctx, vertices, 3, NULL, 1, &out),
                     "sc_mesh_from_arrays: an array with a non-zero count is NULL"));
  CHECK(refused_with(ctx, sc_mesh_copy_vertices(ctx, m, NULL, 9), "sc_mesh_copy_vertices"));
  CHECK(refused_with(ctx, sc_mesh_copy_triangles(ctx, NULL, ids, 3), "sc_mesh_copy_triangles"));
  CHECK(refused_with(ctx, sc_mesh_write_stl(ctx, NULL, &sink, NULL), "sc_mesh_write_stl"));
  CHECK(refused_with(ctx, sc_mesh_check(ctx, NULL, &report), "sc_mesh_check"));
  CHECK(refused_with(ctx, sc_mesh_require_solid(ctx, NULL), "sc_mesh_require_solid: mesh"));
  CHECK(refused_with(ctx, sc_mesh_boolean(ctx, NULL, m, 0, &out), "sc_mesh_boolean"));
  CHECK(refused_with(ctx, sc_mesh_boolean(ctx, m, m, 0, NULL), "sc_mesh_boolean"));
  CHECK(refused_with(ctx, sc_sweep(ctx, jaws, 1, z, 0.5, NULL), "sc_sweep"));
  CHECK(refused_with(ctx, sc_blockout(ctx, NULL, jaws, 1, z, 0.5, 0, &out), "sc_blockout"));
  CHECK(refused_with(ctx, sc_blockout(ctx, m, jaws, 1, NULL, 0.5, 0, &out), "sc_blockout"));
  CHECK(refused_with(ctx, sc_blockout(ctx, m, jaws, 1, z, 0.5, 0, NULL), "sc_blockout"));
  CHECK(refused_with(ctx, sc_register_rigid(ctx, NULL, m, NULL, &registered), "sc_register_rigid"));
  CHECK(refused_with(ctx, sc_register_rigid(ctx, m, NULL, NULL, &registered), "sc_register_rigid"));
  CHECK(refused_with(ctx, sc_case_parse(ctx, "{}", 2, "x", NULL), "sc_case_parse"));
  CHECK(refused_with(ctx, sc_case_get_params(ctx, NULL, &params), "sc_case_get_params"));
  CHECK(refused_with(ctx, sc_case_set_params(ctx, NULL, &params), "sc_case_set_params"));
  CHECK(refused_with(ctx, sc_case_get_blockout_clearance(ctx, NULL, &mm),
                     "sc_case_get_blockout_clearance"));
  CHECK(refused_with(ctx, sc_case_get_blockout_clearance(ctx, c, NULL),
                     "sc_case_get_blockout_clearance"));
  CHECK(refused_with(ctx, sc_case_write(ctx, NULL, &sink), "sc_case_write"));
  CHECK(refused_with(ctx, sc_case_set_pick(ctx, NULL, SC_PICKS_UPPER, 0, z, NULL, 1, 1),
                     "sc_case_set_pick: the case is NULL"));
  CHECK(refused_with(ctx, sc_outline(ctx, NULL, jaws, 2, &resolved, NULL), "sc_outline"));
  CHECK(refused_with(ctx, sc_outline(ctx, c, jaws, 2, NULL, NULL), "sc_outline"));
  CHECK(refused_with(ctx, sc_design(ctx, c, jaws, 2, NULL, &design), "sc_design:"));
  CHECK(refused_with(ctx, sc_design_scans(ctx, NULL, jaws, jaws, 2, &out, &design),
                     "sc_design_scans"));
  CHECK(refused_with(ctx, sc_design_scans(ctx, c, NULL, jaws, 2, &out, &design),
                     "sc_design_scans: the mesh array is NULL"));
  CHECK(refused_with(ctx, sc_design_plan_scans(ctx, c, NULL, jaws, 2, &out, &out, &sink, &plan),
                     "sc_design_plan_scans: the mesh array is NULL"));
  CHECK(refused_with(ctx, sc_write_splint_job(ctx, NULL, m, &sink), "sc_write_splint_job"));
  CHECK(refused_with(ctx, sc_write_splint_job(ctx, c, NULL, &sink), "sc_write_splint_job"));
  CHECK(refused_with(ctx, sc_write_splint_job(ctx, c, m, NULL), "sc_write_splint_job"));
  CHECK(refused_with(ctx, sc_design_write_report(ctx, NULL, jaws, 2, m, NULL, &sink),
                     "sc_design_write_report"));
  CHECK(refused_with(ctx, sc_design_write_report(ctx, c, jaws, 2, NULL, NULL, &sink),
                     "sc_design_write_report"));
  CHECK(refused_with(ctx, sc_design_plan(ctx, c, jaws, 2, NULL, &out, &sink, &plan),
                     "sc_design_plan"));
  CHECK(refused_with(ctx, sc_design_plan(ctx, c, jaws, 2, &out, NULL, &sink, &plan),
                     "sc_design_plan"));
  {
    sc_sink no_write = sink;
    no_write.write = NULL;
    CHECK(refused_with(ctx,
                       sc_design_plan_scans(ctx, c, jaws, jaws, 2, &out, &out, &no_write, &plan),
                       "sc_design_plan_scans: the job sink's write function is NULL"));
    CHECK(refused_with(ctx, sc_mesh_write_stl(ctx, m, &no_write, NULL), "sc_mesh_write_stl"));
    CHECK(refused_with(ctx, sc_case_write(ctx, c, &no_write), "sc_case_write"));
    CHECK(refused_with(ctx, sc_write_splint_job(ctx, c, m, &no_write), "sc_write_splint_job"));
  }
  CHECK(sc_arena_used(ctx) == used && sink_state.size == 0);
  /* "ok" into buffers of 0, 1, 2 and 3 bytes: the full length (2) each time. */
  CHECK_OK(ctx, sc_case_get_params(ctx, c, &params));
  memset(text, 'x', sizeof text);
  CHECK(sc_status_message(ctx, text, 0) == 2 && text[0] == 'x');
  CHECK(sc_status_message(ctx, NULL, 5) == 2);
  CHECK(sc_status_message(ctx, text, 1) == 2 && text[0] == '\0');
  CHECK(sc_status_message(ctx, text, 2) == 2 && strcmp(text, "o") == 0);
  CHECK(sc_status_message(ctx, text, 3) == 2 && strcmp(text, "ok") == 0);
  close_fixture(&f);
}

int main(int argc, char** argv) {
  Bytes torus, case_text;
  if (argc < 2) {
    fprintf(stderr, "usage: %s FIXTURES_DIR [JAWS_DIR]\n", argv[0]);
    return 2;
  }
  g_fixtures = argv[1];
  torus = read_file(g_fixtures, "stl/torus_binary.stl");
  case_text = read_file(g_fixtures, "cases/paper_scale.json");
  if (torus.data == NULL || case_text.data == NULL) return 1;

  if (HAVE_MALLOC_SHIM) {
    /* The shim is really in place: a malloc made while counting is counted (through a
     * volatile pointer, so the compiler cannot elide the pair). */
    static void* volatile kept;
    g_counting = 1;
    kept = malloc(16);
    g_counting = 0;
    CHECK(g_allocations == 1);
    free(kept);
    g_allocations = 0;
  }
  test_context();
  test_arena_exhaustion(&torus);
  test_round_trip(&torus);
  test_errors_with_location(&torus);
  test_mesh_check(&torus);
  test_register(&torus);
  test_operations();
  test_case_params(&case_text);
  test_null_and_range_refusals(&torus, &case_text);
  test_null_context_everywhere(&torus, &case_text);
  if (argc >= 3) {
    test_design(&case_text, argv[2]);
    test_design_scans(&case_text, argv[2]);
    test_outline(argv[2]);
    if (argc >= 4) test_report_matches_cli(argv[2], argv[3]);
    test_design_plan(argv[2], argc >= 5 ? argv[4] : NULL);
    test_design_plan_scans(argv[2]);
  } else {
    printf("design skipped: no jaws folder given\n");
  }
  free(torus.data);
  free(case_text.data);
  if (HAVE_MALLOC_SHIM) {
    CHECK(g_allocations == 0);
    printf("allocations inside sc_ calls: %lu\n", g_allocations);
  } else {
    printf("allocations inside sc_ calls: not counted (no malloc shim here)\n");
  }
  printf("%d checks, %d failed\n", g_checks, g_failures);
  return g_failures == 0 ? 0 : 1;
}
