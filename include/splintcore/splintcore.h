/* splintcore C API: the design pipeline (Chen et al. 2016, EasySplint) for C callers and
 * firmware, implemented in src/capi/capi.cpp on the C++ API of every module.
 *
 * Plain C99. Rules that hold for every function here:
 * - No function allocates: not the handles, not the results. All memory is the caller's:
 *   a context lives in caller storage (SC_CONTEXT_BYTES), and everything else (meshes, cases,
 *   read buffers, temporaries) comes from the context's arena, a caller buffer with a hard
 *   cap. Running out is SC_ARENA_EXHAUSTED with a message naming the bytes needed.
 * - Nothing throws or longjmps; every function that can fail returns an sc_status and keeps
 *   the full status (message, file, line, byte offset, element index) in the context, readable
 *   with sc_status_message() and sc_status_location() until the next call on that context.
 * - No global mutable state except the assert handler (sc_set_assert_handler). Contexts are
 *   independent: one context per thread, never one context from two threads at once.
 * - Handles (sc_mesh, sc_case) live in the arena: valid until the arena is rewound past
 *   them (sc_arena_rewind to an earlier mark, sc_arena_reset) or the context is destroyed.
 * - Output bytes are deterministic: the same inputs give the same STL bytes on every compiler
 *   and CPU the library is tested on.
 * - Broken preconditions that a status cannot express (a handle that is not one) are not
 *   checked; NULL pointers are (SC_INVALID_ARGUMENT).
 */
#ifndef SPLINTCORE_SPLINTCORE_H
#define SPLINTCORE_SPLINTCORE_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* ------------------------------------------------------------------------------------------ */
/* Status codes: the same values and meanings as splintcore::StatusCode (core.h). */

typedef int sc_status;
enum {
  SC_OK = 0,
  SC_INVALID_ARGUMENT = 1, /* a parameter is out of its documented range, or a NULL pointer */
  SC_ARENA_EXHAUSTED = 2,  /* the arena is too small; the message says how much is needed */
  SC_PARSE_ERROR = 3,      /* malformed input (line and column, or byte offset) */
  SC_TRUNCATED = 4,        /* input ended early (byte offset) */
  SC_NON_FINITE = 5,       /* NaN or infinity in input */
  SC_LIMIT_EXCEEDED = 6,   /* input larger than a limit */
  SC_IO_ERROR = 7,         /* the source or sink callback failed */
  SC_INVALID_MESH = 8,     /* the mesh is not what the operation needs (open, non-manifold) */
  SC_CANCELLED = 9,        /* the progress callback asked to stop */
  SC_UNSUPPORTED = 10,     /* valid input that this version does not handle */
  SC_INTERNAL = 11         /* a bug: please report it with the inputs */
};

/* Short stable name of a code ("arena_exhausted"); "unknown" for other values. Static text. */
const char* sc_status_name(sc_status code);

/* The library's version, "MAJOR.MINOR.PATCH". Static text. */
const char* sc_library_version(void);

/* Replaces the handler called on a broken precondition (a library bug or misuse that no
 * status can express) before the library calls abort(). Process-wide: set it once at start-up,
 * before any other call. NULL restores the default (stderr when hosted, nothing otherwise). */
void sc_set_assert_handler(void (*handler)(const char* expression, const char* file, int line));

/* ------------------------------------------------------------------------------------------ */
/* Context: the arena, an optional progress callback and executor, and the last status. */

typedef struct sc_context sc_context;

/* Bytes of caller storage that always suffice for a context, any alignment included (the
 * context aligns itself within the storage). sc_context_size() says the exact need. */
#define SC_CONTEXT_BYTES 1024u

/* The storage a context needs at `storage`'s alignment worst case (<= SC_CONTEXT_BYTES). */
size_t sc_context_size(void);

/* Builds a context in `storage` (storage_bytes >= sc_context_size(), any alignment) whose
 * arena is `arena_buffer` (arena_bytes of it, any alignment: the arena aligns each block it
 * hands out to 16 bytes, so up to 15 bytes at the start may go unused). Nothing else is used.
 * Writes *out (a pointer into `storage`). Errors: SC_INVALID_ARGUMENT (NULL pointers, storage
 * too small). Both buffers must outlive the context; storage and arena must not overlap. */
sc_status sc_context_init(void* storage, size_t storage_bytes, void* arena_buffer,
                          size_t arena_bytes, sc_context** out);

/* Ends the context (the caller's buffers are then free to reuse). NULL is ignored. */
void sc_context_destroy(sc_context* ctx);

/* Progress and cancellation: `report` is called with a stage name ("design: boolean", ...) and
 * done/total; returning 0 cancels (the operation returns SC_CANCELLED at its next check).
 * NULL report: none. Reads nothing, never fails. */
typedef int (*sc_progress_fn)(void* user, const char* stage, uint64_t done, uint64_t total);
void sc_context_set_progress(sc_context* ctx, sc_progress_fn report, void* user);

/* The caller's threads: run(self, count, task, task_context) must call task(task_context, i)
 * exactly once for each i in [0, count) and return when all have finished. Results never
 * depend on it (tasks write only their own slots). NULL run: serial, on the calling thread. */
typedef void (*sc_task_fn)(void* task_context, uint32_t index);
typedef void (*sc_executor_fn)(void* self, uint32_t count, sc_task_fn task, void* task_context);
void sc_context_set_executor(sc_context* ctx, sc_executor_fn run, void* self, uint32_t concurrency);

/* The last status of a call on this context (SC_OK after a success). */
sc_status sc_last_status(const sc_context* ctx);

/* The last status as a person reads it: "FILE:LINE:COL: byte B: element I: message" with the
 * parts that are known ("ok" after a success). Writes at most `cap` bytes to `out`, always
 * NUL-terminated when cap > 0; returns the length the full text has (snprintf-like), so
 * truncation is detectable. No arena use. */
size_t sc_status_message(const sc_context* ctx, char* out, size_t cap);

/* Where the last error is; SC_NO_POSITION for parts not known. */
#define SC_NO_POSITION UINT64_MAX
typedef struct sc_location {
  uint64_t byte_offset;
  uint64_t line;
  uint64_t column;
  uint64_t index; /* element: triangle, vertex, jaw, ... */
} sc_location;
void sc_status_location(const sc_context* ctx, sc_location* out);

/* ------------------------------------------------------------------------------------------ */
/* The arena (a strict stack over the caller's buffer). */

size_t sc_arena_used(const sc_context* ctx);       /* bytes handed out, padding included */
size_t sc_arena_cap(const sc_context* ctx);        /* the buffer's size */
size_t sc_arena_high_water(const sc_context* ctx); /* most bytes in use since init/reset */

/* A point to come back to: everything allocated after it (handles included) is freed by
 * sc_arena_rewind. Marks must be rewound in stack order. */
typedef struct sc_arena_mark {
  void* block;
  size_t offset;
  size_t used;
} sc_arena_mark;
sc_arena_mark sc_arena_mark_get(const sc_context* ctx);
void sc_arena_rewind(sc_context* ctx, sc_arena_mark mark);

/* Frees everything (every handle becomes invalid) and resets the high-water mark. */
void sc_arena_reset(sc_context* ctx);

/* ------------------------------------------------------------------------------------------ */
/* Byte I/O: callbacks, so data can be fed and drained in chunks, and memory buffers. */

#define SC_UNKNOWN_SIZE UINT64_MAX

/* Where bytes come from. read() copies up to `capacity` bytes into `buffer` and returns how
 * many (0 at the end), or -1 on an I/O error. `size`: the total if known (lets readers reject
 * a lying header before reading on), else SC_UNKNOWN_SIZE. `name` (may be NULL) is used in
 * messages. */
typedef struct sc_source {
  int64_t (*read)(void* user, uint8_t* buffer, size_t capacity);
  void* user;
  uint64_t size;
  const char* name;
} sc_source;

/* Where bytes go. write() returns nonzero on success. seek() (NULL: not seekable) moves the
 * write position to an absolute offset, returning nonzero on success. */
typedef struct sc_sink {
  int (*write)(void* user, const uint8_t* data, size_t bytes);
  int (*seek)(void* user, uint64_t offset);
  void* user;
  const char* name;
} sc_sink;

/* A source over bytes in memory; `state` (caller-held) must outlive the source. */
typedef struct sc_memory_source_state {
  const uint8_t* data;
  uint64_t size;
  uint64_t position;
} sc_memory_source_state;
sc_source sc_memory_source(sc_memory_source_state* state, const void* data, size_t size,
                           const char* name);

/* A sink into a caller buffer of fixed capacity (a write past it fails: SC_IO_ERROR from the
 * writer). Seekable. `state->size` is the number of bytes written (the high-water mark). */
typedef struct sc_memory_sink_state {
  uint8_t* data;
  uint64_t capacity;
  uint64_t size;
  uint64_t position;
} sc_memory_sink_state;
sc_sink sc_memory_sink(sc_memory_sink_state* state, void* buffer, size_t capacity,
                       const char* name);

/* SHA-256 (FIPS 180-4) of `bytes` bytes as 64 lower-case hex digits and a NUL. No arena. */
void sc_sha256_hex(const void* data, size_t bytes, char out[65]);

/* ------------------------------------------------------------------------------------------ */
/* Meshes: indexed triangle meshes (double vertices, counter-clockwise seen from outside) that
 * live in the context's arena. */

typedef struct sc_mesh sc_mesh;

typedef struct sc_stl_read_options {
  uint64_t max_triangles;    /* more is SC_LIMIT_EXCEEDED; default 100,000,000 */
  double max_abs_coordinate; /* mm; beyond is SC_LIMIT_EXCEEDED ("wrong units?"); 1e6 */
  size_t chunk_bytes;        /* the read buffer, from the arena (freed before return) */
} sc_stl_read_options;
/* The defaults (as above, chunk_bytes 65,536). */
sc_stl_read_options sc_stl_read_defaults(void);

/* Reads an STL (binary or ASCII, detected) and welds corners with identical coordinates into
 * a mesh. `options` NULL: defaults. The header's triangle count is never trusted. Arena: the
 * mesh (about 24 bytes per vertex + 12 per triangle + 64 for the handle) stays; the read
 * buffer and the triangle soup (36 bytes per triangle) and welding temporaries are freed
 * before return. On error the arena is back where it was and *out is NULL.
 * Errors: SC_TRUNCATED (byte offset), SC_PARSE_ERROR (byte offset or line), SC_NON_FINITE
 * (names the triangle), SC_LIMIT_EXCEEDED, SC_IO_ERROR, SC_ARENA_EXHAUSTED,
 * SC_INVALID_ARGUMENT (NULL pointers). */
sc_status sc_mesh_read_stl(sc_context* ctx, const sc_source* source,
                           const sc_stl_read_options* options, sc_mesh** out);

/* A mesh from arrays: `vertices` holds 3 * vertex_count doubles (x, y, z), `triangles`
 * 3 * triangle_count vertex ids. Copied into the arena (24 bytes per vertex, 12 per triangle,
 * 64 for the handle). Errors: SC_INVALID_ARGUMENT (NULL arrays with non-zero counts, an id out
 * of range: names the triangle), SC_NON_FINITE (names the vertex), SC_ARENA_EXHAUSTED. */
sc_status sc_mesh_from_arrays(sc_context* ctx, const double* vertices, uint32_t vertex_count,
                              const uint32_t* triangles, uint32_t triangle_count, sc_mesh** out);

uint64_t sc_mesh_vertex_count(const sc_mesh* mesh);   /* 0 for NULL */
uint64_t sc_mesh_triangle_count(const sc_mesh* mesh); /* 0 for NULL */

/* Copies the vertices (3 doubles each) into `out`, which holds `capacity` doubles. No arena.
 * Errors: SC_INVALID_ARGUMENT (NULL, capacity < 3 * vertex count: says how many needed). */
sc_status sc_mesh_copy_vertices(sc_context* ctx, const sc_mesh* mesh, double* out, size_t capacity);
/* Copies the triangles (3 vertex ids each) into `out`, which holds `capacity` ids. Same rules. */
sc_status sc_mesh_copy_triangles(sc_context* ctx, const sc_mesh* mesh, uint32_t* out,
                                 size_t capacity);

/* Bytes of the binary STL of a mesh with `triangle_count` triangles (84 + 50 per triangle). */
uint64_t sc_stl_binary_size(uint64_t triangle_count);

typedef struct sc_stl_write_options {
  int ascii;              /* nonzero: ASCII; 0: binary (the default) */
  size_t buffer_bytes;    /* the write buffer, from the arena (> 0; default 64,000) */
  const char* solid_name; /* ASCII only: letters, digits, '_' '-' '.'; NULL: "splintcore" */
} sc_stl_write_options;
/* The defaults (binary, 64,000-byte buffer). */
sc_stl_write_options sc_stl_write_defaults(void);

/* Writes the mesh as STL to `sink`, streaming (`options` NULL: defaults). The bytes are
 * deterministic: fixed header, float32 rounded to nearest, normals from the corners. Arena:
 * the write buffer (options->buffer_bytes), freed before return. Errors: SC_IO_ERROR (the sink
 * failed; names it), SC_ARENA_EXHAUSTED, SC_INVALID_ARGUMENT (NULL pointers, a zero buffer, a
 * bad solid name). */
sc_status sc_mesh_write_stl(sc_context* ctx, const sc_mesh* mesh, const sc_sink* sink,
                            const sc_stl_write_options* options);

/* What a mesh is (check_mesh of mesh.h). Flags are 0 or 1. */
typedef struct sc_mesh_report {
  uint64_t vertex_count;
  uint64_t triangle_count;
  uint64_t boundary_edges;        /* used by one triangle */
  uint64_t nonmanifold_edges;     /* used by three or more */
  uint64_t orientation_conflicts; /* edges used twice in the same direction */
  uint64_t degenerate_triangles;  /* repeated ids or zero area (exact) */
  uint64_t duplicate_triangles;
  uint64_t shells;
  int64_t genus; /* -1 unless closed and manifold */
  double area_mm2;
  double volume_mm3; /* signed: > 0 when outward */
  double bounds_min[3];
  double bounds_max[3];
  int closed;
  int manifold;
  int oriented;
  int outward;
  int valid_solid; /* all of the above, no degenerate or duplicate triangle */
} sc_mesh_report;

/* Checks topology and measures. Arena: temporaries (about 64 bytes per triangle), freed before
 * return. Errors: SC_ARENA_EXHAUSTED; SC_INVALID_MESH (a vertex id out of range: names the
 * triangle); SC_INVALID_ARGUMENT (NULL). A mesh that is not a solid is no error: read the
 * report, or call sc_mesh_require_solid. */
sc_status sc_mesh_check(sc_context* ctx, const sc_mesh* mesh, sc_mesh_report* out);

/* SC_OK when the mesh is a valid solid, else SC_INVALID_MESH with the first reason ("mesh is
 * not closed: 12 boundary edges, first between vertices 4 and 9 (triangle 17)"). Arena and
 * other errors as sc_mesh_check. */
sc_status sc_mesh_require_solid(sc_context* ctx, const sc_mesh* mesh);

/* ------------------------------------------------------------------------------------------ */
/* Mesh operations. Each result is a mesh of its own in the arena (the handle and the mesh stay,
 * temporaries are freed before return; on error the arena is back where it was). */

enum { SC_BOOLEAN_DIFFERENCE = 0, SC_BOOLEAN_UNION = 1, SC_BOOLEAN_INTERSECTION = 2 };

/* The exact Boolean `op` of the solid `a` and the mesh `b` (boolean.h; float32 output, checked,
 * self-intersection checked, up to 8 nudges of a). b's vertices must be float32 values (as read
 * from STL). Arena: roughly 1 KB per triangle near the intersection plus the result.
 * Errors: SC_INVALID_MESH, SC_NON_FINITE, SC_INVALID_ARGUMENT, SC_UNSUPPORTED,
 * SC_ARENA_EXHAUSTED, SC_LIMIT_EXCEEDED, SC_CANCELLED, SC_INTERNAL. */
sc_status sc_mesh_boolean(sc_context* ctx, const sc_mesh* a, const sc_mesh* b, int op,
                          sc_mesh** out);

/* The swept volume of the jaws along `direction` (blockout.h sweep_volume_mesh): a closed,
 * outward mesh on a grid of `voxel` mm. Arena: the sweep's state (about 10 bytes per grid
 * column times a few layers, plus the jaws' copies) and the result. Errors: SC_INVALID_ARGUMENT
 * (zero or non-finite direction, voxel not > 0, no jaws), SC_LIMIT_EXCEEDED, SC_NON_FINITE,
 * SC_ARENA_EXHAUSTED, SC_CANCELLED. */
sc_status sc_sweep(sc_context* ctx, const sc_mesh* const* jaws, size_t jaw_count,
                   const double direction[3], double voxel, sc_mesh** out);

/* Interference elimination: `splint` minus the jaws' swept volume along `direction` (the
 * direction the jaws move relative to the splint as it is taken off), on a grid of `voxel` mm,
 * surface taken `inset` mm inside (0 <= inset < 2 voxel). Arena: the sweep's, then the
 * Boolean's; only the result stays. Errors: those of sc_sweep and sc_mesh_boolean. */
sc_status sc_blockout(sc_context* ctx, const sc_mesh* splint, const sc_mesh* const* jaws,
                      size_t jaw_count, const double direction[3], double voxel, double inset,
                      sc_mesh** out);

/* The same with the swept volume's exact boundary (blockout.h, BlockoutOptions::exact): the
 * jaw's own front triangles (facing against `direction`) and walls along it, no voxels and no
 * inset. Exactly one of the jaws has triangles (join a jaw's files first; the others' are
 * ignored); it holds the jaw itself, so give it the splint before the jaw is subtracted.
 * Arena: sweep_exact_bound of the jaw, the shell check and the Boolean's; only the result
 * stays. Errors: those of sc_mesh_boolean, and SC_UNSUPPORTED where the jaw's swept surface
 * would cross itself inside the splint or a fold would leave more than 0.05 mm of undercut
 * (an overhang along the direction: the message says where; sc_blockout takes such jaws). */
sc_status sc_blockout_exact(sc_context* ctx, const sc_mesh* splint, const sc_mesh* const* jaws,
                            size_t jaw_count, const double direction[3], sc_mesh** out);

/* ------------------------------------------------------------------------------------------ */
/* Scan-CT fusion (registration.h): the rigid motion placing an intraoral scan onto a CT jaw. */

typedef struct sc_register_options {
  const double* landmarks; /* 6 per pair: scan x y z, then the same point on the CT; or NULL */
  size_t landmark_count;   /* pairs (0: the automatic start; else at least 3) */
  double overlap;          /* fraction of samples fitted, (0, 1]; 0: the default, 0.6 */
  double max_rms_mm;       /* a fit with a larger RMS is SC_LIMIT_EXCEEDED; 0: the default, 0.3 */
} sc_register_options;

typedef struct sc_register_result {
  double transform[16]; /* row-major 4x4, scan -> CT (last row 0 0 0 1) */
  double rms_mm;        /* RMS distance to the CT of the samples fitted */
  double overlap;       /* fraction of all samples within 0.5 mm of the CT */
  double landmark_rms_mm;
  uint32_t iterations;
  uint32_t samples;
  uint32_t kept;
  int converged;
} sc_register_result;

/* register_rigid (registration.h): `options` may be NULL (the defaults). Arena: at most
 * register_rigid_bound() and the landmarks (48 bytes a pair), all freed before return. *out is
 * filled on success and on SC_LIMIT_EXCEEDED (the fit that was refused). Errors:
 * SC_INVALID_ARGUMENT (options; landmarks too few, collinear or wrongly paired: the message
 * names the pair), SC_INVALID_MESH, SC_LIMIT_EXCEEDED, SC_ARENA_EXHAUSTED, SC_CANCELLED. */
sc_status sc_register_rigid(sc_context* ctx, const sc_mesh* scan, const sc_mesh* ct_jaw,
                            const sc_register_options* options, sc_register_result* out);

/* ------------------------------------------------------------------------------------------ */
/* The design pipeline: a case file (docs/case-format.md) and the jaw meshes it names. */

typedef struct sc_case sc_case;

/* Parses and validates a case file (strict: unknown keys, wrong types and out-of-range values
 * are errors with line and column). `name` (may be NULL) is used in messages. Arena: the parsed
 * document stays (a few times the text's size); on error the arena is back where it was and
 * *out is NULL. Errors: SC_PARSE_ERROR, SC_INVALID_ARGUMENT, SC_LIMIT_EXCEEDED,
 * SC_UNSUPPORTED (a newer format version), SC_ARENA_EXHAUSTED. */
sc_status sc_case_parse(sc_context* ctx, const char* text, size_t length, const char* name,
                        sc_case** out);

const char* sc_case_id(const sc_case* c);   /* "" for NULL */
size_t sc_case_jaw_count(const sc_case* c); /* 0 for NULL */
/* The jaw's role ("maxilla", "mandible") and mesh path as the case names it (relative to the
 * case file's folder; NULL when it has none). NULL for an index out of range. */
const char* sc_case_jaw_role(const sc_case* c, size_t index);
const char* sc_case_jaw_mesh(const sc_case* c, size_t index);

/* sc_case_params.blockout_method */
#define SC_BLOCKOUT_AUTO 0
#define SC_BLOCKOUT_EXACT 1
#define SC_BLOCKOUT_VOXEL 2
/* sc_design_report.blockout_method_used only: AUTO made some jaws exactly, some with the
 * height field */
#define SC_BLOCKOUT_MIXED 3
#define SC_BLOCKOUT_HEIGHTFIELD 4

/* The parameters a caller may read and change after parsing. Flags are 0 or 1. */
typedef struct sc_case_params {
  double spacing_mm;        /* base: distance between sections (> 0) */
  double corner_radius_mm;  /* base: rounding of the section corners (>= 0) */
  uint32_t corner_segments; /* 1, 2, 4, 8 or 16 */
  int has_insertion_direction;
  double insertion_direction[3]; /* finite, non-zero when has_insertion_direction */
  int blockout;                  /* interference elimination on/off (needs the direction) */
  double blockout_voxel_mm;      /* 0.01 .. 1 */
  double blockout_inset_mm;      /* 0 .. 1.99 voxel */
  double blockout_closing_mm;    /* 0, or 2 .. 10 voxel */
  /* blockout "method" (docs/case-format.md): SC_BLOCKOUT_AUTO (the exact sweep, the height
   * field where it stops, on the voxel's grid), SC_BLOCKOUT_EXACT, SC_BLOCKOUT_VOXEL,
   * SC_BLOCKOUT_HEIGHTFIELD (the voxel is its grid); inset and closing are used by VOXEL only.
   * As parsed: a case's "blockout" naming "inset" or "closing_radius" is VOXEL, else one
   * naming "clearance" HEIGHTFIELD, else AUTO (unless it names its "method"); an AUTO or
   * HEIGHTFIELD case reads back inset 0: give one when switching it to VOXEL. */
  int blockout_method;
  const char* printer; /* a built-in profile name ("eden260"); static text */
  /* The automatic outline ("base": {"auto": {...}}, docs/case-format.md): the picks, the
   * occlusal normal, the bite opening and (unless given) the insertion direction are computed
   * from the jaws by sc_design and sc_outline. The options are checked only when auto_outline
   * is set. Turning it off needs the case to have picks (one from sc_outline has). */
  int auto_outline;
  double auto_indentation_depth_mm; /* 0.1 .. 5: how deep the deepest cusp sinks in the wafer */
  double auto_overhang_mm;          /* 0 .. 10: the wafer past the occlusal surfaces */
  double auto_pick_spacing_mm;      /* 2 .. 20: between picks along the arch */
  int auto_has_bite_opening;        /* move the mandible until the jaws are this far apart */
  double auto_bite_opening_mm;      /* 0.1 .. 10 when auto_has_bite_opening */
  /* Where the wafer ends distally ("distal_ends"): two points (mm, case frame; finite, within
   * 1e6), one on each half of the arch in either order; the arch is cut across at each. */
  int auto_has_distal_ends;
  double auto_distal_ends[2][3];
  /* "survey": when the case gives no insertion direction, the direction within 15 degrees of
   * the occlusal normal that leaves the least undercut (else the normal itself). */
  int auto_survey;
  /* "max_wall_crossing", 0 .. 1: a jaw whose teeth cross the base's side walls along more than
   * this share of the arch is refused (SC_INVALID_MESH naming it); 1 (the default) never. */
  double max_wall_crossing;
  /* "max_sideways_crossing", 0 .. 1: a jaw crossing the outer wall in one half of the arch and
   * the inner wall in the other (sideways of the outline, as a wrong transform puts it) along
   * more than this share of the arch is refused (SC_INVALID_MESH); 0.05 by default, 1 never. */
  double max_sideways_crossing;
} sc_case_params;

/* Reads the case's parameters into *out. */
sc_status sc_case_get_params(sc_context* ctx, const sc_case* c, sc_case_params* out);
/* Validates `params` with the case file's ranges and sets them. On error nothing changes.
 * The printer name must stay valid while the case is used (a string literal or the value
 * sc_case_get_params gave). No arena. Errors: SC_INVALID_ARGUMENT (naming the parameter). */
sc_status sc_case_set_params(sc_context* ctx, sc_case* c, const sc_case_params* params);
/* A case with a clearance keeps it through sc_case_set_params only with blockout on and
 * SC_BLOCKOUT_VOXEL (inset 0) or SC_BLOCKOUT_HEIGHTFIELD, within 20 voxels: other parameters
 * are refused (the message names the clearance; set it to 0 first). */

/* The spacer between teeth and splint ("blockout": {"clearance"}, mm; docs/case-format.md):
 * the imprint is the surface that far outside each jaw's swept volume. 0: none (also without
 * blockout). sc_case_get_blockout_clearance writes it to *out_mm. sc_case_set_blockout_clearance
 * sets it: 0 always; otherwise the case needs blockout with SC_BLOCKOUT_VOXEL (inset 0) or
 * SC_BLOCKOUT_HEIGHTFIELD (set them with sc_case_set_params first), and mm within the case
 * file's range (0 to 20 voxels, at most 2 mm). On error nothing changes. No arena.
 * Errors: SC_INVALID_ARGUMENT (naming the value or the parameter in the way). */
sc_status sc_case_get_blockout_clearance(sc_context* ctx, const sc_case* c, double* out_mm);
sc_status sc_case_set_blockout_clearance(sc_context* ctx, sc_case* c, double mm);

/* Writes the case as a case file (JSON, format version 1; write_case of design.h) to `sink`:
 * every key it uses, numbers as the shortest text that reads back to the same double, so that
 * sc_case_parse of the bytes gives the same values and sc_design the same splint. An auto case
 * is written with its "auto" object, a resolved one (sc_outline) with its picks. Jaw mesh paths
 * are written as the case names them (relative to the case file's folder). No arena.
 * Errors: SC_IO_ERROR (the sink failed; names it), SC_INVALID_ARGUMENT (NULL pointers). */
sc_status sc_case_write(sc_context* ctx, const sc_case* c, const sc_sink* sink);

/* The picks of a case: those it gives, or, for a case from sc_outline, those computed (0 for
 * an auto case, whose picks exist only once resolved). `which`: SC_PICKS_UPPER (the wafer's
 * top face, the maxilla's side) or SC_PICKS_LOWER (its bottom face); upper and lower pair up
 * by index. 0 for NULL or another `which`. */
enum { SC_PICKS_UPPER = 0, SC_PICKS_LOWER = 1 };
size_t sc_case_pick_count(const sc_case* c, int which);
/* Reads pick `index`: its position (mm, case frame), its unit buccal direction (zero when
 * the case gives none), and the lengths of its line towards the inside and the outside (mm).
 * Any output pointer may be NULL. Returns 1, or 0 (nothing written) for NULL, an unknown
 * `which` or an index out of range. No arena. */
int sc_case_pick(const sc_case* c, int which, size_t index, double position[3], double direction[3],
                 double* inner_mm, double* outside_mm);
/* Changes pick `index` of the case's own list (sc_case_pick's shape), e.g. of a case from
 * sc_outline before designing it again: `position` (mm, case frame; NULL keeps it), `direction`
 * (the line's buccal direction, used normalised; the zero vector drops it, so the base takes
 * the pick's normal or the arch's perpendicular; NULL keeps it), both line lengths (mm,
 * 0 .. 100). Only the pick changes: its pair in the other list stays. On error nothing
 * changes. No arena. Errors: SC_INVALID_ARGUMENT (NULL context or case, an unknown `which`,
 * an index out of range (an auto case has no picks until sc_outline), a position or direction
 * that is not finite or beyond 1e6 mm, a length out of range: the message names it). */
sc_status sc_case_set_pick(sc_context* ctx, sc_case* c, int which, size_t index,
                           const double position[3], const double direction[3], double inner_mm,
                           double outside_mm);
/* The dental arch's centre line (a polyline in the occlusal plane, mm) of a case from
 * sc_outline, for display; 0 points for any other case. sc_case_arch_point returns 1, or 0 for
 * NULL or an index out of range. */
size_t sc_case_arch_count(const sc_case* c);
int sc_case_arch_point(const sc_case* c, size_t index, double point[3]);

/* What the automatic outline found (OutlineReport of outline.h). Flags are 0 or 1. */
typedef struct sc_outline_report {
  double occlusal_normal[3];         /* unit, from the mandible towards the maxilla */
  double anterior[3];                /* unit, in the occlusal plane, towards the incisors */
  double gap_as_given_mm;            /* smallest distance between the jaws as given */
  int jaws_intersect;                /* as given */
  int opened;                        /* the mandible was moved (bite opening asked) */
  double mandible_translation_mm[3]; /* the move (zero unless opened) */
  double opening_mm;                 /* smallest distance after the move */
  uint32_t opening_steps;            /* conservative-advancement steps */
  uint32_t picks;                    /* per jaw */
  double arch_length_mm;             /* along the arch, end to end, before the overhang */
  double wafer_min_mm;               /* the thinnest section, top to bottom */
  double wafer_max_mm;
  uint64_t occlusal_columns_maxilla; /* occlusal cells found per jaw */
  uint64_t occlusal_columns_mandible;
  int distal_limited;            /* the case gave distal ends (auto_has_distal_ends) */
  double distal_offset_mm[2];    /* per point as given: its distance from the arch's centre line */
  double distal_cut_mm[2];       /* and how much of the picks' span it cut (0: beyond the end) */
  double insertion_direction[3]; /* unit: the occlusal normal, or the survey's choice */
  int surveyed;                  /* the survey chose it (auto_survey) */
  uint32_t survey_directions;    /* directions tried */
  double undercut_plain_mm3;     /* the undercut along the occlusal normal (surveyed only) */
  double undercut_chosen_mm3;    /* and along the chosen direction */
} sc_outline_report;

/* The automatic outline of an auto case (resolve_case_outline of design.h): `jaws` are the
 * meshes of the case's jaws as read (one maxilla and one mandible; moved by the case's
 * transforms here, not changed). *resolved is a new case handle with everything the outline
 * decided written in: the picks (sc_case_pick), the occlusal normal, the mandible's transform
 * composed with the bite opening's move, the insertion direction (the occlusal normal unless
 * the case gives one), and the arch (sc_case_arch_point); it is no longer an auto case, and
 * sc_design of it gives the same splint bytes as sc_design of `c`. `report` may be NULL.
 * Arena: the jaws' moved copies and the outline's work (a few times the jaws' size; measure
 * with sc_arena_high_water), all returned; the handle and its lists (about 70 KB: room for 256
 * picks a jaw and 1,024 arch points) stay. On error the arena is back where it was and *resolved is
 * NULL. Progress: "outline". Errors: SC_INVALID_ARGUMENT (not an auto case, the jaw count differs
 * from the case's, not one maxilla and one mandible, jaws that do not face each other, no occlusal
 * surfaces, jaws touching or interpenetrating without a bite opening, or too far apart: the message
 * says which, prefixed "outline: "), SC_INVALID_MESH, SC_NON_FINITE, SC_LIMIT_EXCEEDED (a jaw moved
 * beyond float32 range), SC_ARENA_EXHAUSTED,
 * SC_CANCELLED. */
sc_status sc_outline(sc_context* ctx, const sc_case* c, const sc_mesh* const* jaws,
                     size_t jaw_count, sc_case** resolved, sc_outline_report* report);

/* What a design gives. Flags are 0 or 1. */
#define SC_MAX_BLOCKOUT_JAWS 8
typedef struct sc_design_report {
  uint64_t jaw_triangles; /* all jaws together, as given */
  uint64_t splint_triangles;
  uint64_t splint_vertices;
  double splint_volume_mm3;
  uint32_t base_sections;
  double base_volume_mm3;
  uint64_t boolean_intersecting_pairs;
  uint64_t boolean_intersection_points;
  uint32_t boolean_attempts; /* 1 + the nudges tried */
  double boolean_nudge_mm[3];
  uint32_t blockout_jaws; /* jaws blocked out (0 without blockout) */
  double blockout_removed_mm3[SC_MAX_BLOCKOUT_JAWS];
  uint32_t blockout_attempts[SC_MAX_BLOCKOUT_JAWS];
  /* With a blockout, the method that made the splint: SC_BLOCKOUT_EXACT, SC_BLOCKOUT_VOXEL,
   * SC_BLOCKOUT_HEIGHTFIELD (also AUTO's when the exact sweep stopped for every jaw), or with
   * AUTO SC_BLOCKOUT_MIXED when it stopped for some jaws only (those jaws are made with the
   * height field; sc_design_write_report says which and why). */
  int blockout_method_used;
  int printable;
  int fits;         /* fits the tray as placed */
  int fits_rotated; /* fits after a 90 degree turn about z */
  double extent_mm[3];
  uint64_t layers;
  const char* printer; /* the profile used (static text) */
  int outlined;        /* an auto case: the picks were computed first (sc_outline's) */
  /* Scan-CT fusion (sc_design_scans), per jaw in case order: fused[i] is 1 when jaw i's scan
   * was registered; then the fit's RMS (mm), the fraction of the scan within the case's
   * crowns_within_mm, and the registration (scan -> the jaw's mesh, row-major 4 x 4). */
  int fused[SC_MAX_BLOCKOUT_JAWS];
  double fusion_rms_mm[SC_MAX_BLOCKOUT_JAWS];
  double fusion_overlap[SC_MAX_BLOCKOUT_JAWS];
  double fusion_transform[SC_MAX_BLOCKOUT_JAWS][16];
  /* Shells of the splint under the printer's thinnest wall cubed (all but the largest), taken
   * out before the printer check, and their total volume: crumbs a Boolean can leave. */
  uint64_t crumbs_removed;
  double crumbs_volume_mm3;
  /* The side-wall check, per jaw in case order (the first SC_MAX_BLOCKOUT_JAWS; wall_jaws of
   * them): the base's length along the arch, and of it where the placed jaw crosses the base's
   * outer or inner wall, its imprint opening through the splint's side (mm). */
  uint32_t wall_jaws;
  double wall_arch_mm;
  double wall_crossing_mm[SC_MAX_BLOCKOUT_JAWS];
  /* Of it, the outer wall crossed in one half of the arch and the inner in the other, the
   * lesser (mm): the jaw sideways of the outline (max_sideways_crossing bounds it). */
  double wall_sideways_mm[SC_MAX_BLOCKOUT_JAWS];
} sc_design_report;

/* Designs the splint for `c` from `jaws` (jaws[i] is the mesh of the case's jaw i, as read; it
 * is not changed): each jaw moved by the plan's transform, the base from the picks, the exact
 * Boolean difference, interference elimination when the case asks for it, the printer check.
 * An auto case is resolved first as sc_outline does (stage "design: outline"; the report's
 * `outlined` is 1 and sc_design_write_report writes the "outline" object); the splint is the
 * one sc_design of sc_outline's resolved case gives, byte for byte.
 * `report` may be NULL. Arena: the pipeline's peak (the paper-scale case with two 6,000-
 * triangle jaws: 10.3 MB, the jaws included; measure yours with sc_arena_high_water), of which
 * the result, its handle and the design's record (for sc_design_write_report, a few KB)
 * stay; on error the arena is back where it was. Progress: the stages of design_splint
 * (design.h): "design: jaws", "design: base", "design: boolean", "design: blockout",
 * "design: label", "design: thickness", "design: printer", "design: done". Errors: those of the
 * stages (naming the stage and, for a jaw, its index and role), SC_INVALID_ARGUMENT (the jaw count
 * differs from the case's, more than SC_MAX_BLOCKOUT_JAWS jaws), SC_NON_FINITE, SC_LIMIT_EXCEEDED,
 * SC_INVALID_MESH (the result is not printable: the reason), SC_ARENA_EXHAUSTED, SC_CANCELLED. */
sc_status sc_design(sc_context* ctx, const sc_case* c, const sc_mesh* const* jaws, size_t jaw_count,
                    sc_mesh** splint, sc_design_report* report);

/* Writes one splint's print job to `sink` as `splintcore design` writes the case's
 * "output" "job": the splint alone on the case printer's tray, one 3MF package named by the
 * case id, the SHA-256 of its binary STL in metadata (write_splint_job, C++ design.h). The same
 * splint gives the same bytes. Arena: at most splint_job_bound() (the model text, up to about
 * 150 bytes a triangle, and its compressed copy), nothing stays. Errors: SC_INVALID_ARGUMENT
 * (NULL pointers, an empty splint, unknown printer), SC_LIMIT_EXCEEDED (it does not fit the
 * tray), SC_IO_ERROR (the sink refused), SC_ARENA_EXHAUSTED. */
sc_status sc_write_splint_job(sc_context* ctx, const sc_case* c, const sc_mesh* splint,
                              const sc_sink* sink);

/* sc_design for a case whose jaws have intraoral scans ("scan", docs/case-format.md, "Scan-CT
 * fusion"): scans[i] is the scan of the case's jaw i as read (NULL for a jaw without one;
 * `scans` itself NULL: no scans, which is sc_design). Each scan is registered onto its jaw
 * (stage "design: fusion", before "design: jaws") and is then that jaw for the Boolean and
 * blockout: the imprint is the scan's triangles; sc_design_write_report writes the
 * registrations under "fusion". Arena: sc_design's plus the registration's
 * (register_rigid_bound, returned). Errors: sc_design's, SC_INVALID_ARGUMENT (a scan missing
 * for a jaw with "scan", a wrong landmark pairing), SC_LIMIT_EXCEEDED (a fit over the case's
 * max_rms_mm or under its min_overlap: the message gives the figures and the thresholds). */
sc_status sc_design_scans(sc_context* ctx, const sc_case* c, const sc_mesh* const* jaws,
                          const sc_mesh* const* scans, size_t jaw_count, sc_mesh** splint,
                          sc_design_report* report);

/* What the audit report names that the library cannot know (every member may be NULL: that
 * entry is left out). jaw_paths and jaw_sha256 hold jaw_count entries when given. */
typedef struct sc_report_files {
  const char* case_path;
  const char* const* jaw_paths;  /* as the caller names the jaw files */
  const char* const* jaw_sha256; /* of each jaw file's bytes (sc_sha256_hex) */
  const char* splint_path;
  const char* preview_path;
  const char* preview_sha256;
} sc_report_files;

/* Writes the audit report of the design that made `splint` (a handle from sc_design with this
 * case and these jaws) to `sink`, as one JSON object (docs/report-format.md): the same bytes as
 * `splintcore design` writes to report.json for the same case and the same names, less that
 * file's last member, "run" (memory cap, threads, times: what differs from run to run).
 * Every value comes from the design's recorded results; the splint's SHA-256 is computed here
 * from the binary STL sc_mesh_write_stl gives. Arena: the STL writer's buffer (64,000 bytes),
 * returned. Errors: SC_INVALID_ARGUMENT (a splint not from sc_design, jaw count), SC_IO_ERROR
 * (the sink failed), SC_ARENA_EXHAUSTED. */
sc_status sc_design_write_report(sc_context* ctx, const sc_case* c, const sc_mesh* const* jaws,
                                 size_t jaw_count, const sc_mesh* splint,
                                 const sc_report_files* files, const sc_sink* sink);

/* What the blockout of jaw `jaw` (case order) used for `splint` (a handle from sc_design or
 * sc_design_scans), as report.json's "blockout" entry for that jaw says it: *lowered_mm, the
 * voxel sweep's inset ("inset_mm") or the height field's lowering ("lowered_mm"), the case's
 * or, after a retry, more; *clearance_mm, the spacer made ("clearance_mm", "clearance_used_mm"):
 * the case's clearance or, after a retry, 1/64 voxel more each time; 0 without one. The exact
 * sweep uses neither: both 0. Either pointer may be NULL. Nothing is allocated. Errors:
 * SC_INVALID_ARGUMENT (a splint not from sc_design, a jaw the design did not block out: the
 * message gives how many it did). */
sc_status sc_design_blockout_used(sc_context* ctx, const sc_mesh* splint, size_t jaw,
                                  double* lowered_mm, double* clearance_mm);

/* ------------------------------------------------------------------------------------------ */
/* Two-jaw surgery (issue 32): the intermediate and the final splint of a case with "plan"
 * (docs/case-format.md, "Plan"; design_plan in design.h). */

/* What sc_design_plan gives: [0] the intermediate splint, [1] the final one. Flags are 0 or 1. */
typedef struct sc_plan_report {
  double angle_rad[2];  /* the mandible's turn about the hinge axis (autorotation) */
  double opening_mm[2]; /* the smallest distance between the arches there, measured */
  uint64_t triangles[2];
  double volume_mm3[2];
  int printable[2];
  int outlined[2];                 /* an auto case: each splint's picks were computed first */
  char label_text[2][33];          /* the label applied: "INT " / "FIN " and the case's label text;
                                      "" without "label" */
  int job_written;                 /* `job` was given and the 3MF written to it */
  double job_translation_mm[2][3]; /* where the job put each splint on the tray (its build
                                      item's translation); 0 without a job */
  /* Scan-CT fusion (sc_design_plan_scans), per jaw in case order: fused[i] is 1 when jaw i's
   * scan was registered (once, before the plan's moves: both splints hold this fit); then the
   * fit's RMS (mm), the fraction of the scan within the case's crowns_within_mm, and the
   * registration (scan -> the jaw's mesh as given, row-major 4 x 4). 0 for a jaw without one. */
  int fused[2];
  double fusion_rms_mm[2];
  double fusion_overlap[2];
  double fusion_transform[2][16];
} sc_plan_report;

/* Designs both splints of the plan case `c` from `jaws` (jaws[i] is the mesh of the case's jaw
 * i, as read: the preoperative maxilla and mandible), as design_plan does (C++ design.h): the
 * same meshes, vertex for vertex, as the C++ function and `splintcore design` give. Each splint
 * is an ordinary design (outline, blockout, label, checks) with the jaws where the plan and the
 * hinge-axis autorotation put them; with the case's "label", the intermediate splint carries
 * "INT " and the label's text, the final "FIN " and the text.
 * `job` (may be NULL): the print job is written to it as `splintcore design` writes job.3mf:
 * both splints on the case printer's tray, 5 mm apart, one 3MF package (write_plan_job).
 * `report` may be NULL.
 * Arena: design_plan's peak, then (with `job`) the job writer's (write_plan_job, at most
 * plan_job_bound(): the model text, about 150 bytes a triangle, and its compressed copy) on
 * top of the two splints; of it both splints, their handles and the plan's record (a few tens
 * of KB) stay. Measured: the phantom plan (fixtures/cases/plan.json, both splints labelled)
 * with the two 6,000-triangle phantom jaws, the case and the jaws read into the same arena, the
 * job included: 6.1 MB on x86-64; give such a case 8 MiB (tests/capi/capi_test.c runs it in
 * 8 MiB, and in exactly its high water mark). On any error the arena is back where it was and
 * both handles NULL.
 * Progress: "plan: intermediate", the design's stages, "plan: final", the design's stages.
 * Errors: SC_INVALID_ARGUMENT (not a plan case, jaw count or roles, a label text too long for
 * the prefix, unknown printer), the autorotation's and the design's prefixed "plan:
 * intermediate: " or "plan: final: ", SC_LIMIT_EXCEEDED (the splints do not fit the tray
 * together), SC_IO_ERROR (the job sink refused), SC_ARENA_EXHAUSTED, SC_CANCELLED. */
sc_status sc_design_plan(sc_context* ctx, const sc_case* c, const sc_mesh* const* jaws,
                         size_t jaw_count, sc_mesh** intermediate, sc_mesh** final_splint,
                         const sc_sink* job, sc_plan_report* report);

/* The same for a plan case whose jaws have "scan" (design_plan with scans, C++ design.h):
 * scans[i] is the scan of the case's jaw i as read, NULL for a jaw without one (`scans` may be
 * NULL only when no jaw has one). The fusion comes first, once, on the preoperative jaws (stage
 * "plan: fusion"); both splints and the autorotation then see each scanned jaw as its
 * registered scan, the plan's moves after the registration; the report's fused[],
 * fusion_rms_mm[], fusion_overlap[] and fusion_transform[] give each jaw's fit (as
 * sc_design_report has them for one splint). Arena: sc_design_plan's plus
 * register_rigid_bound() of the largest scan and its jaw (returned). Errors: sc_design_plan's,
 * and sc_design_scans' fusion errors prefixed "plan: ". At most 2 jaws (the plan's). */
sc_status sc_design_plan_scans(sc_context* ctx, const sc_case* c, const sc_mesh* const* jaws,
                               const sc_mesh* const* scans, size_t jaw_count,
                               sc_mesh** intermediate, sc_mesh** final_splint, const sc_sink* job,
                               sc_plan_report* report);

#ifdef __cplusplus
} /* extern "C" */
#endif

#endif /* SPLINTCORE_SPLINTCORE_H */
