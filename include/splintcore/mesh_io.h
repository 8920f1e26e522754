// splintcore mesh_io: the indexed-mesh formats intraoral scanners export (PLY, Wavefront OBJ)
// and a reader that detects the format (PLY, OBJ or STL) by content, then by file name.
// Floor 4, beside io.h (which it includes): a header of its own so that the STL module's
// contract stays as it is and these readers can be left out of a firmware build that only
// needs STL.
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
//   mesh (arrays grow by half again). With options.weld, plus weld_exact_bound(triangles)
//   and a 36-byte-per-triangle soup.
// - Never trusts a count: PLY element counts are checked against the limits, and (when the
//   source knows its size) against the bytes present, before anything is reserved.
// - Errors: kParseError (line and column for text, byte offset for binary PLY), kTruncated
//   (where the input ends), kNonFinite (NaN or infinity: names the vertex), kLimitExceeded
//   (counts over the limits, a coordinate beyond max_abs_coordinate, a line longer than
//   max_line_bytes), kUnsupported (valid PLY this reader does not take, e.g. a face list of
//   float), kIoError, kArenaExhausted, kInvalidArgument (no read(), non-empty `out`, weld
//   without round_to_float32), kCancelled (progress). Each carries the source's name and, for
//   errors about an element, at_index(the vertex or face).
#ifndef SPLINTCORE_MESH_IO_H
#define SPLINTCORE_MESH_IO_H

#include "splintcore/core.h"
#include "splintcore/io.h"
#include "splintcore/mesh.h"

namespace splintcore {

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

#endif  // SPLINTCORE_MESH_IO_H
