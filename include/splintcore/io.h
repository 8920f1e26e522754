// splintcore io: byte sources and sinks (callbacks, so firmware can feed and drain data in
// chunks), the STL reader and the streaming STL writer, the PLY and OBJ readers and a reader
// that detects the format.
#ifndef SPLINTCORE_IO_H
#define SPLINTCORE_IO_H

#include "splintcore/core.h"
#include "splintcore/geometry.h"
#include "splintcore/mesh.h"

namespace splintcore {

constexpr uint64_t kUnknownSize = ~uint64_t{0};

// Where bytes come from. read() copies up to `capacity` bytes into `buffer` and returns how
// many (0 at the end), or -1 on an I/O error.
struct ByteSource {
  int64_t (*read)(void* user, uint8_t* buffer, size_t capacity) = nullptr;
  void* user = nullptr;
  uint64_t size = kUnknownSize;  // total bytes if known: lets readers reject lies up front
  const char* name = nullptr;    // for messages (a file name), may be null
};

// Where bytes go. write() returns false on failure. seek() (may be null: not seekable) moves
// the write position to an absolute offset; used to patch a count in a header.
struct ByteSink {
  bool (*write)(void* user, const uint8_t* data, size_t bytes) = nullptr;
  bool (*seek)(void* user, uint64_t offset) = nullptr;
  void* user = nullptr;
  const char* name = nullptr;
};

// A source over bytes in memory.
struct MemorySource {
  const uint8_t* data = nullptr;
  uint64_t size = 0;
  uint64_t position = 0;
  size_t max_chunk = 0;  // 0: no limit; tests set it to feed the reader in small pieces
};
ByteSource memory_source(MemorySource* state, const char* name = "memory");

// A sink into a caller buffer (fixed capacity: a write past it fails). Seekable.
struct MemorySink {
  uint8_t* data = nullptr;
  uint64_t capacity = 0;
  uint64_t size = 0;      // high-water of bytes written
  uint64_t position = 0;  // current write position
};
ByteSink memory_sink(MemorySink* state, const char* name = "memory");

// A sink that hashes (SHA-256) and counts what passes through, and passes it on to `next` when
// that has a write (else it only hashes). Not seekable.
struct HashSink {
  Sha256 sha;
  uint64_t size = 0;
  ByteSink next;
};
ByteSink hash_sink(HashSink* state);

// ---------------------------------------------------------------------------------------------
// STL reading.

enum class StlFormat : uint8_t { kAuto, kBinary, kAscii };

struct StlReadOptions {
  StlFormat format = StlFormat::kAuto;
  uint64_t max_triangles = 100'000'000;  // larger inputs are kLimitExceeded
  double max_abs_coordinate = 1.0e6;     // mm; beyond is kLimitExceeded ("wrong units?")
  size_t chunk_bytes = 64 * 1024;        // read buffer, from the arena
  // read_stl_mesh only: a triangle whose three corners all lie strictly beyond one side of
  // `keep` (x below keep.lo.x for all three, ..., the test of boolean_region, boolean.h) is
  // left out as it is read, as if it were not in the file: the mesh is the others, in their
  // order, welded (vertex ids by first use among them). Every triangle is still read and its
  // corners checked (the same errors). Empty (the default): every triangle is kept. The mesh
  // then holds the arena the file without them would (the read's peak is the whole file's).
  Aabb keep;
};

struct StlInfo {
  StlFormat format = StlFormat::kAuto;  // what was detected
  uint64_t triangles = 0;
  uint64_t bytes = 0;
  char header[81] = {};  // binary: the 80-byte header (NUL-terminated); ASCII: the solid name
};

// Auto-detection: ASCII when the input starts with "solid" (after optional white space) and
// its first 1024 bytes are all printable text; binary otherwise. A binary file whose header
// begins with "solid" is still binary: its count field and float data are not text.

// Reads triangles into `out` (appended). Never trusts the binary header's count: it must agree
// with the bytes that follow (and with source.size when known, checked before reading on).
// Errors (each with byte offset or line): kTruncated, kParseError, kNonFinite (names the
// triangle), kLimitExceeded, kIoError, kArenaExhausted. Arena: the read buffer
// (max(chunk_bytes, 4096)) and the triangles (36 bytes each, the array grown by half),
// both left in place on success. On an error the arena is as it was and `out` holds what it
// held before the call.
Status read_stl(const Context& ctx, const ByteSource& source, const StlReadOptions& options,
                ArenaArray<SoupTriangle>* out, StlInfo* info);

// read_stl() then weld_exact(), leaving only the mesh in the arena, with the same result. A
// binary STL from a source that knows its size (files, memory) whose header agrees with it is
// welded straight from the read buffer, never held as soup; anything else is read whole, then
// welded. `out` must be empty. Errors: read_stl()'s and weld_exact()'s. On an error the arena
// is as it was and `out` is empty.
//
// Sizing, from the input's length in bytes (a file's size): no STL of `bytes` bytes holds more
// than bytes / 50 triangles (a binary one holds (bytes - 84) / 50; an ASCII facet takes at
// least 85 bytes). read_stl_bound() covers read_stl() into an empty array (the read buffer and
// the triangles), read_stl_mesh_bound() read_stl_mesh() (and read_mesh() on an STL) from a
// source that knows its size; a binary STL from a source of unknown size is read whole first:
// read_stl_bound() + weld_exact_bound(bytes / 50).
uint64_t read_stl_bound(uint64_t bytes, const StlReadOptions& options);
uint64_t read_stl_mesh_bound(uint64_t bytes, const StlReadOptions& options);
Status read_stl_mesh(const Context& ctx, const ByteSource& source, const StlReadOptions& options,
                     Mesh* out, StlInfo* info);

// ---------------------------------------------------------------------------------------------
// STL writing: streams triangles to a sink as they are produced, without holding the mesh.
//
// Bytes are deterministic: a fixed header with no timestamp, float32 coordinates rounded to
// nearest (ties to even) from double, -0 written as +0, facet normals computed from the
// rounded corners as normalize((b - a) x (c - a)) in double then rounded (0,0,0 when
// degenerate). ASCII numbers use the shortest form that reads back to the same float32.

struct StlWriteOptions {
  StlFormat format = StlFormat::kBinary;  // kAuto means binary
  size_t buffer_bytes = 64 * 1000;        // from the arena
  const char* solid_name = "splintcore";  // ASCII only; letters, digits, '_' '-' '.'
};

constexpr char kStlBinaryHeader[] = "splintcore binary STL";  // padded with spaces to 80 bytes

class StlWriter {
 public:
  StlWriter() = default;
  StlWriter(const StlWriter&) = delete;
  StlWriter& operator=(const StlWriter&) = delete;

  // `triangle_count` may be kUnknownSize for binary output only when the sink can seek (the
  // count is patched by finish()). The buffer is taken from ctx.arena; keep the arena's top
  // until finish() (allocate nothing below it that must outlive the writer).
  Status begin(const Context& ctx, const ByteSink& sink, const StlWriteOptions& options,
               uint64_t triangle_count);
  Status add(const Vec3& a, const Vec3& b, const Vec3& c);
  // All of a mesh's triangles, in order, as add() one by one (the same bytes, errors and
  // progress: "write" every 65,536 triangles), a triangle whose indices are out of range
  // refused (kInvalidMesh, named). Binary records are encoded straight into the buffer, a
  // batch at a time, in tasks on ctx.executor when it has threads and the buffer holds 8,192
  // records or more (buffer_bytes 409,684 or more). The boolean command's 134,686-triangle
  // result into a file with a 1 MiB buffer: write_stl 6.8-6.9 ms at one thread, 5.0-5.7 ms
  // at two, of which the file's writes take about 3 ms either way. At one thread (a 64,000
  // byte buffer) the batches take 31.3M instructions where add() one by one took 49.7M
  // (callgrind).
  Status add_mesh(const Context& ctx, const Mesh& mesh);
  // Flushes, checks the number of triangles against the declared count, patches it if needed.
  Status finish();
  uint64_t triangles_written() const { return written_; }
  uint64_t bytes_written() const { return bytes_; }

 private:
  Status flush();
  size_t encode_in_tasks(const Executor* executor, const Mesh& mesh, size_t t, size_t end);
  ByteSink sink_{};
  uint8_t* buffer_ = nullptr;
  size_t capacity_ = 0;
  size_t used_ = 0;
  uint64_t declared_ = 0;
  uint64_t written_ = 0;
  uint64_t bytes_ = 0;
  bool binary_ = true;
  bool count_known_ = false;
  bool open_ = false;
  const char* solid_name_ = "splintcore";
};

// ---- 3MF print jobs ----------------------------------------------------------------------
// One object of a 3MF job: a mesh in millimetres (its vertices written as float32, in their
// shortest decimal form), its name, and the SHA-256 (hex) of what it was made from (e.g. its
// STL), written as the object's metadata sc:sha256.
struct ThreeMfObject {
  const Mesh* mesh = nullptr;
  const char* name = "";
  const char* sha256 = "";
  // Where the build item puts it (its transform: the mesh's own coordinates are written as
  // they are, never moved and rounded again): e.g. arrange_on_tray()'s translation.
  Vec3 translation{};
};

struct ThreeMfOptions {
  const char* title = "";    // the model's Title metadata ("": none)
  const char* case_id = "";  // metadata sc:case_id ("": none)
  bool deflate = true;       // entries deflated when that is smaller, else stored
};

// Arena bytes write_3mf() takes at most (nothing stays): the model part (up to 81 bytes a
// vertex and 66 a triangle, 6 per character of a name, id or hash, 1 KiB more, 256 an object),
// the lanes its lines are formatted in (4 x 1024 lines of 81 bytes, on the context's executor)
// and, deflating, the encoder's lanes (deflate_lanes_bound of the model part: a model over
// 1 MiB is deflated in pieces on the context's executor) and each entry's compressed copy
// (9/8 of it).
uint64_t write_3mf_bound(Span<const ThreeMfObject> objects, const ThreeMfOptions& options);

// Writes `objects` as a 3MF package (3MF Core 1.3: unit millimetre, an object and a build
// item per mesh, in order; the ZIP container: fixed dates, no ZIP64): the same input gives the
// same bytes. The objects are placed as their coordinates say (the caller places them on the
// tray). Errors: kInvalidArgument (no objects, an empty mesh, a sink without write()),
// kInvalidMesh (a vertex id out of range), kNonFinite / kLimitExceeded (a vertex not finite or
// beyond float32 range: object and vertex named; a package over 4 GiB), kArenaExhausted,
// kIoError (the sink refused).
Status write_3mf(const Context& ctx, Span<const ThreeMfObject> objects,
                 const ThreeMfOptions& options, const ByteSink& sink);

// Writes a whole mesh through an StlWriter.
Status write_stl(const Context& ctx, const Mesh& mesh, const ByteSink& sink,
                 const StlWriteOptions& options);

// Writes the mesh as binary little-endian PLY to `sink`: float32 x, y, z per vertex (rounded
// to nearest; -0 written as +0), with `rgb` (3 bytes a vertex, or empty: none) as uchar red,
// green, blue, then each triangle as a uchar-counted int list vertex_indices. read_ply reads
// it back (the vertices float32-exact). Allocates nothing (a 4 KiB buffer on the stack).
// Errors: kInvalidArgument (rgb of the wrong size), kNonFinite / kLimitExceeded (a vertex not
// finite or beyond float32: named), kInvalidMesh (an index out of range: named), kIoError.
Status write_ply(const Mesh& mesh, Span<const uint8_t> rgb, const ByteSink& sink);

// ---------------------------------------------------------------------------------------------
// The indexed-mesh formats intraoral scanners export (PLY, Wavefront OBJ) and a reader that
// detects the format (PLY, OBJ or STL) by content, then by file name (src/io/ply_read.cpp,
// obj_read.cpp). A firmware build that only needs STL links none of it (--gc-sections).
//
// Common contract of read_ply / read_obj / read_mesh:
// - Reads from a ByteSource in chunks (options.chunk_bytes, at least 4096) through a buffer
//   taken from ctx.arena; text lines go through a second buffer of options.max_line_bytes.
// - Output: an indexed Mesh (`out` must be empty; it is bound to ctx.arena). Vertices are kept
//   as given, in file order (unreferenced ones too), unless options.weld. Polygons with more
//   than three corners are fan-triangulated: (c0, c1, c2), (c0, c2, c3), ..., (c0, c[n-2],
//   c[n-1]), keeping their orientation. Faces with fewer than three corners are rejected.
// - With options.round_to_float32 (the default) every coordinate is rounded to nearest float32
//   (text: parsed as float32 directly, as the STL reader does), so a mesh read from PLY, OBJ
//   or STL holds the same values; float32 PLY data is then exact. Without it, text and double
//   data are kept as the nearest double.
// - Arena: on success only the mesh stays (read buffers are reclaimed): 24 bytes per vertex
//   and 12 per triangle. While reading, at most the buffers plus, when the source size is
//   unknown or vertex and face records interleave (OBJ), up to about three times the final
//   mesh (arrays grow by half again). With options.weld, plus 28 bytes a vertex read and
//   the weld's table (4 bytes a slot; a power of two, at least 1.5 slots a vertex): the
//   vertices are welded in place, hashed once each (the same mesh as weld_exact() of the
//   triangles' corners). There is no a-priori bound: the need of a file is the
//   arena's high water after a first read (the two-step contract, docs/embedding.md), and the
//   same file then reads in exactly that many bytes.
// - Never trusts a count: PLY element counts are checked against the limits, and (when the
//   source knows its size) against the bytes present, before anything is reserved.
// - Errors: kParseError (line and column for text, byte offset for binary PLY), kTruncated
//   (where the input ends), kNonFinite (NaN or infinity: names the vertex), kLimitExceeded
//   (counts over the limits, a coordinate beyond max_abs_coordinate, a line longer than
//   max_line_bytes), kUnsupported (valid PLY this reader does not take, e.g. a face list of
//   float), kIoError, kArenaExhausted, kInvalidArgument (no read(), non-empty `out`, weld
//   without round_to_float32), kCancelled (progress). Each carries the source's name and, for
//   errors about an element, at_index(the vertex or face).

enum class MeshFormat : uint8_t {
  kUnknown,
  kStlBinary,
  kStlAscii,
  kPlyAscii,
  kPlyBinaryLittleEndian,
  kPlyBinaryBigEndian,
  kObj,
};

// "stl-binary", "stl-ascii", "ply-ascii", "ply-binary-le", "ply-binary-be", "obj", "unknown".
const char* mesh_format_name(MeshFormat format);

struct MeshReadOptions {
  uint64_t max_vertices = 100'000'000;   // larger inputs are kLimitExceeded
  uint64_t max_triangles = 100'000'000;  // after fan triangulation
  double max_abs_coordinate = 1.0e6;     // mm; beyond is kLimitExceeded ("wrong units?")
  size_t chunk_bytes = 64 * 1024;        // read buffer, from the arena (at least 4096)
  size_t max_line_bytes = 4096;          // text lines (PLY header, ASCII PLY, OBJ), 64..1M
  bool round_to_float32 = true;          // see above
  bool weld = false;  // merge bit-identical vertices (weld_exact: ids by first use in the
                      // triangles; unreferenced vertices dropped). STL input is always welded.
  // As StlReadOptions::keep, for every format: the triangles wholly beyond one side of `keep`
  // are left out as if they were not in the file (after fan triangulation; PLY and OBJ
  // vertices stay unless welded). Empty (the default): every triangle is kept.
  Aabb keep;
};

struct MeshReadInfo {
  MeshFormat format = MeshFormat::kUnknown;
  uint64_t vertices = 0;   // vertex records read (before any welding)
  uint64_t faces = 0;      // polygons (STL: triangles)
  uint64_t triangles = 0;  // after fan triangulation
  uint64_t bytes = 0;      // bytes consumed
};

// PLY (Turk 1994; Paul Bourke's description of the format): "ply", "format ascii 1.0 |
// binary_little_endian 1.0 | binary_big_endian 1.0", comment and obj_info lines, elements
// with scalar properties (char uchar short ushort int uint float double and their int8..
// float64 names) and list properties. The "vertex" element needs x, y and z (any scalar type;
// its other properties, scalar or list, are skipped by their declared types); the "face"
// element needs a list named vertex_indices or vertex_index (integer count and index types;
// other face properties are skipped); other elements are skipped. Indices are checked
// against the vertex count. ASCII: one record per line.
Status read_ply(const Context& ctx, const ByteSource& source, const MeshReadOptions& options,
                Mesh* out, MeshReadInfo* info);

// Wavefront OBJ (the "Object Files (.obj)" appendix of the Advanced Visualizer manual): "v x y
// z" with up to three more numbers ignored (a rational w, or the r g b that MeshLab and
// ZBrush write); "f" with corners "v", "v/vt", "v//vn" or "v/vt/vn", 1-based, negative ones
// relative to the vertices read so far; a corner must name a vertex already defined. Every
// other statement (vn vt vp g o s usemtl mtllib l p curv ...) and '#' comments are skipped.
// Numbers are locale-free (std::from_chars); "nan"/"inf" are kNonFinite.
Status read_obj(const Context& ctx, const ByteSource& source, const MeshReadOptions& options,
                Mesh* out, MeshReadInfo* info);

// The format of a file from its first bytes (as many as are available, up to 1024), then its
// name's extension (.ply .obj .stl, any case) when the content says nothing: "ply" and a line
// end -> PLY; STL's rule for ASCII (io.h) -> STL ASCII; printable text whose first statement
// is an OBJ keyword (v vn vt f o g s usemtl mtllib or a '#' comment) -> OBJ; otherwise by
// extension; otherwise binary STL (whose own checks then apply). Reads only `head`.
MeshFormat detect_mesh_format(const uint8_t* head, size_t size, const char* name);

// Detects the format (peeking at the first 1024 bytes through a stack buffer, no arena) and
// reads with read_ply, read_obj or read_stl_mesh (STL: options' limits and chunk size apply;
// always welded). `info->format` says what was read.
Status read_mesh(const Context& ctx, const ByteSource& source, const MeshReadOptions& options,
                 Mesh* out, MeshReadInfo* info);

}  // namespace splintcore

#endif  // SPLINTCORE_IO_H
