// Private helpers of the PLY and OBJ readers (src/io/ply_read.cpp, src/io/obj_read.cpp): the
// chunk window over a ByteSource, a line reader with line numbers, locale-free number parsing
// (std::from_chars, as the STL ASCII reader does) and the mesh builder that checks every
// vertex and leaves only the mesh in the arena.
#ifndef SPLINTCORE_SRC_IO_MESH_TEXT_H
#define SPLINTCORE_SRC_IO_MESH_TEXT_H

#include <charconv>
#include <system_error>

#include "io/reader.h"
#include "mesh/exact_weld.h"
#include "splintcore/io.h"
#include "splintcore/mesh.h"

namespace splintcore {
namespace meshio {

// Replays the peeked head, then the rest of the source.
struct PeekSource {
  const uint8_t* head = nullptr;
  size_t size = 0;
  size_t position = 0;
  const ByteSource* inner = nullptr;
  static int64_t read(void* user, uint8_t* buffer, size_t capacity) {
    PeekSource* self = static_cast<PeekSource*>(user);
    if (self->position < self->size) {
      size_t n = self->size - self->position;
      if (n > capacity) n = capacity;
      std::memcpy(buffer, self->head + self->position, n);
      self->position += n;
      return static_cast<int64_t>(n);
    }
    return self->inner->read(self->inner->user, buffer, capacity);
  }
  // `source` as read from its start again: the `got` bytes of `peeked`, then the rest.
  ByteSource replay(const ByteSource& source, const uint8_t* peeked, size_t got) {
    head = peeked;
    size = got;
    position = 0;
    inner = &source;
    ByteSource out = source;
    out.read = &PeekSource::read;
    out.user = this;
    return out;
  }
};

// When `source` is a memory_source() (src/io/stream.cpp) that gives whole chunks (max_chunk 0),
// holds all source.size bytes and has been read from its start for `consumed` bytes so far:
// those bytes from the start, where they are, and the source marked read to its end (a reader
// then parses them in place, with no copy). Otherwise null, the source untouched: a source
// made by copying one and replacing its read (a wrapper) is never taken for the memory it
// wraps. For a reader that takes the whole source.
const uint8_t* take_memory_bytes(const ByteSource& source, uint64_t consumed);

inline Status located(Status s, const ByteSource& source) {
  if (!s.is_ok() && source.name != nullptr && s.file()[0] == '\0') s.in_file(source.name);
  return s;
}

inline bool is_blank(uint8_t c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v';
}

// A real number token, locale-free. Only digits, sign, point and exponent are taken (from_chars
// would also take "inf" and "nan", which are reported as kNonFinite); a leading '+' is allowed.
// `as_float`: parsed as float32 (nearest), else as double. Returns kOk, kNonFinite or
// kParseError (malformed or out of range).
inline StatusCode parse_real(const char* first, const char* last, bool as_float, double* out) {
  if (first == last) return StatusCode::kParseError;
  if (*first == '+' && last - first > 1 && first[1] != '-' && first[1] != '+') ++first;
  for (const char* p = first; p < last; ++p) {
    const char c = *p;
    const bool ok =
        (c >= '0' && c <= '9') || c == '-' || c == '+' || c == '.' || c == 'e' || c == 'E';
    if (!ok) {
      // A leading '-' is followed by the bad character, so first + 1 is in range.
      const char* q = *first == '-' ? first + 1 : first;
      const char n = static_cast<char>(*q | 0x20);
      return (n == 'n' || n == 'i') ? StatusCode::kNonFinite : StatusCode::kParseError;
    }
  }
  if (as_float) {
    float f = 0;
    auto r = std::from_chars(first, last, f, std::chars_format::general);
    if (r.ec != std::errc() || r.ptr != last) return StatusCode::kParseError;
    *out = static_cast<double>(f);
  } else {
    double d = 0;
    auto r = std::from_chars(first, last, d, std::chars_format::general);
    if (r.ec != std::errc() || r.ptr != last) return StatusCode::kParseError;
    *out = d;
  }
  return StatusCode::kOk;
}

// A decimal integer token with an optional sign; false when malformed or beyond int64.
inline bool parse_integer(const char* first, const char* last, int64_t* out) {
  if (first != last && *first == '+' && last - first > 1 && first[1] != '-') ++first;
  // Up to 18 digits (an optional '-' before them) cannot overflow: summed here, the common
  // case (face corners); anything else as from_chars decides.
  const bool minus = first != last && *first == '-';
  const char* digits = first + (minus ? 1 : 0);
  if (last - digits >= 1 && last - digits <= 18) {
    int64_t value = 0;
    const char* p = digits;
    for (; p < last && static_cast<unsigned>(*p - '0') <= 9u; ++p) value = 10 * value + (*p - '0');
    if (p == last) {
      *out = minus ? -value : value;
      return true;
    }
    return false;  // a character that is not a digit (from_chars too stops there)
  }
  auto r = std::from_chars(first, last, *out, 10);
  return r.ec == std::errc() && r.ptr == last;  // from_chars fails on an empty range
}

// Lines of text from a Reader (the line end is not kept; a '\r' before it is dropped), at most
// `cap` bytes each. Lines are numbered from 1. A line that lies whole in the reader's buffer
// is read there; one across its end is copied into `text` (cap bytes) as it is read.
struct LineReader {
  Reader* in = nullptr;
  char* text = nullptr;        // the copies' buffer
  const char* line = nullptr;  // the line: in the reader's buffer or in `text`; valid until
                               // the next read from `in`
  size_t cap = 0;
  size_t length = 0;
  uint64_t number = 0;      // of the line in `line`
  uint64_t start_byte = 0;  // its offset in the input

  // Reads the next line; *got = false at the end of the input (no more bytes at all).
  // Errors: kLimitExceeded (a line longer than cap), kIoError.
  Status next(bool* got) {
    length = 0;
    *got = false;
    SPLINTCORE_RETURN_IF_ERROR(in->fill(1));
    if (in->available() == 0) return Status::ok();
    ++number;
    start_byte = in->offset();
    const uint8_t* at = in->buf + in->pos;
    const void* end = std::memchr(at, '\n', in->available());
    if (end != nullptr && static_cast<size_t>(static_cast<const uint8_t*>(end) - at) <= cap) {
      line = reinterpret_cast<const char*>(at);
      length = static_cast<size_t>(static_cast<const uint8_t*>(end) - at);
      in->pos += length + 1;
      if (length > 0 && line[length - 1] == '\r') --length;
      *got = true;
      return Status::ok();
    }
    line = text;
    for (;;) {
      if (in->available() == 0) {
        SPLINTCORE_RETURN_IF_ERROR(in->fill(1));
        if (in->available() == 0) break;
      }
      const uint8_t* p = in->buf + in->pos;
      const size_t n = in->available();
      const void* nl = std::memchr(p, '\n', n);
      const size_t take =
          nl != nullptr ? static_cast<size_t>(static_cast<const uint8_t*>(nl) - p) : n;
      if (take > cap - length) {
        return make_error(StatusCode::kLimitExceeded, "line longer than ", cap,
                          " bytes (the limit)")
            .at_line(number, 1)
            .at_byte(start_byte);
      }
      std::memcpy(text + length, p, take);
      length += take;
      in->pos += take;
      if (nl != nullptr) {
        ++in->pos;  // the '\n'
        break;
      }
    }
    if (length > 0 && text[length - 1] == '\r') --length;
    *got = true;
    return Status::ok();
  }
};

// White-space separated tokens of one line, with 1-based columns.
struct Tokens {
  const char* text = nullptr;
  size_t length = 0;
  size_t pos = 0;
  const char* token = nullptr;
  size_t token_length = 0;
  uint64_t column = 1;  // of the current token (or of the line end after the last)

  Tokens(const char* t, size_t n) : text(t), length(n) {}

  bool next() {
    while (pos < length && is_blank(static_cast<uint8_t>(text[pos]))) ++pos;
    column = pos + 1;
    if (pos == length) {
      token = text + pos;
      token_length = 0;
      return false;
    }
    const size_t start = pos;
    while (pos < length && !is_blank(static_cast<uint8_t>(text[pos]))) ++pos;
    token = text + start;
    token_length = pos - start;
    return true;
  }
  bool is(const char* word) const {
    const size_t n = std::strlen(word);
    return n == token_length && std::memcmp(token, word, n) == 0;
  }
};

// "<what>, found '<token>'" at the token's line and column.
inline Status token_error(StatusCode code, const LineReader& lines, const Tokens& t,
                          const char* what) {
  Status s = make_error(code, what);
  if (t.token_length > 0) {
    s.append(", found '");
    s.append(t.token, t.token_length < 40 ? t.token_length : 40);
    s.append("'");
  } else {
    s.append(", found the end of the line");
  }
  return s.at_line(lines.number, t.column);
}

// The mesh as it is read: vertices checked one by one, triangles appended; the two arrays may
// grow in turn (OBJ interleaves them), so the builder remembers which one was (re)allocated
// last, which move_mesh_down needs to know.
struct MeshBuilder {
  const Context* ctx = nullptr;
  const MeshReadOptions* options = nullptr;
  Mesh mesh;
  bool triangles_last = false;  // the triangle array is the later allocation

  MeshBuilder(const Context& c, const MeshReadOptions& o) : ctx(&c), options(&o), mesh(c.arena) {}

  // Vertex `index` with coordinates already rounded as asked. Errors name the vertex.
  Status add_vertex(const Vec3& v, uint64_t index) {
    const double m = options->max_abs_coordinate;
    for (int a = 0; a < 3; ++a) {
      if (!is_finite(v[a])) {
        return make_error(StatusCode::kNonFinite, "vertex ", index,
                          " has a non-finite coordinate (NaN or infinity)")
            .at_index(index);
      }
    }
    for (int a = 0; a < 3; ++a) {
      if (v[a] > m || v[a] < -m) {
        return make_error(StatusCode::kLimitExceeded, "vertex ", index, " has coordinate ", v[a],
                          " mm, beyond the limit of +-", m, " mm (wrong units?)")
            .at_index(index);
      }
    }
    const size_t cap = mesh.vertices.capacity();
    if (!mesh.vertices.push_back(v)) return ctx->arena->exhausted_status();
    if (mesh.vertices.capacity() != cap) triangles_last = false;
    return Status::ok();
  }

  Status add_triangle(uint32_t a, uint32_t b, uint32_t c, uint64_t face) {
    if (mesh.triangles.size() >= options->max_triangles) {
      return make_error(StatusCode::kLimitExceeded, "more than ", options->max_triangles,
                        " triangles (the limit) after fan triangulation")
          .at_index(face);
    }
    const size_t cap = mesh.triangles.capacity();
    if (!mesh.triangles.push_back(Triangle{{a, b, c}})) return ctx->arena->exhausted_status();
    if (mesh.triangles.capacity() != cap) triangles_last = true;
    return Status::ok();
  }

  // Reserves room confirmed by the input's size (never a count from a header alone).
  Status reserve(uint64_t vertices, uint64_t triangles) {
    if (!mesh.vertices.reserve(static_cast<size_t>(vertices)))
      return ctx->arena->exhausted_status();
    if (!mesh.triangles.reserve(static_cast<size_t>(triangles)))
      return ctx->arena->exhausted_status();
    triangles_last = true;
    return Status::ok();
  }

  // Leaves out the triangles whose corners all lie beyond one side of `keep`
  // (MeshReadOptions::keep), the others kept in their order.
  void crop(const Aabb& keep) {
    size_t kept = 0;
    for (size_t t = 0; t < mesh.triangles.size(); ++t) {
      const Triangle& tri = mesh.triangles[t];
      if (!keep.beyond_one_side(mesh.vertices[tri.v[0]], mesh.vertices[tri.v[1]],
                                mesh.vertices[tri.v[2]])) {
        mesh.triangles[kept++] = tri;
      }
    }
    mesh.triangles.shrink_size(kept);
  }

  // Moves the mesh down to `start` (over the read buffers), cropped to options->keep and
  // welded first if asked.
  Status finish(const Arena::Marker& start, Mesh* out) {
    Arena& arena = *ctx->arena;
    if (!options->keep.empty()) crop(options->keep);
    // The exact weld of the triangles' float32 corners (exact, since the coordinates were
    // rounded to float32), so PLY, OBJ and STL weld identically; in place, a hash a vertex.
    if (options->weld) SPLINTCORE_RETURN_IF_ERROR(weld_indexed_exact(*ctx, &mesh));
    move_mesh_down(arena, start, mesh, out, /*vertices_first=*/triangles_last);
    return Status::ok();
  }
};

// Checks the parts of MeshReadOptions every reader shares; also `out` must be empty.
inline Status check_read_arguments(const ByteSource& source, const MeshReadOptions& options,
                                   const Mesh* out, const char* who) {
  if (source.read == nullptr) {
    return make_error(StatusCode::kInvalidArgument, who, ": byte source has no read()");
  }
  if (out == nullptr || !out->vertices.empty() || !out->triangles.empty()) {
    return make_error(StatusCode::kInvalidArgument, who, ": output mesh must be empty");
  }
  if (options.weld && !options.round_to_float32) {
    return make_error(StatusCode::kInvalidArgument, who,
                      ": weld needs round_to_float32 (it welds float32 corners)");
  }
  if (options.max_line_bytes < 64 || options.max_line_bytes > (size_t{1} << 20)) {
    return make_error(StatusCode::kInvalidArgument, who, ": max_line_bytes must be 64..1048576");
  }
  return Status::ok();
}

// The text readers' input: the chunk window over `source` (options.chunk_bytes, at least 4096)
// and the line reader on it (lines up to options.max_line_bytes), their buffers from the arena.
inline Status open_lines(Arena& arena, const ByteSource& source, const MeshReadOptions& options,
                         Reader* in, LineReader* lines) {
  in->source = &source;
  in->cap = options.chunk_bytes < 4096 ? 4096 : options.chunk_bytes;
  in->buf = arena.allocate_array<uint8_t>(in->cap);
  lines->in = in;
  lines->cap = options.max_line_bytes;
  lines->text = arena.allocate_array<char>(lines->cap);
  if (in->buf == nullptr || lines->text == nullptr) return arena.exhausted_status();
  return Status::ok();
}

// A text reader's public entry (read_ply, read_obj): *info cleared (a local one when null), the
// arguments checked (`who` names the function), `out` bound to the arena, then `read`, its
// errors located in the source.
using LocatedRead = Status (*)(const Context& ctx, const ByteSource& source,
                               const MeshReadOptions& options, Mesh* out, MeshReadInfo* info);
inline Status read_text_mesh(const Context& ctx, const ByteSource& source,
                             const MeshReadOptions& options, Mesh* out, MeshReadInfo* info,
                             const char* who, LocatedRead read) {
  MeshReadInfo local;
  if (info == nullptr) info = &local;
  *info = MeshReadInfo{};
  SPLINTCORE_RETURN_IF_ERROR(check_read_arguments(source, options, out, who));
  out->bind(ctx.arena);
  return located(read(ctx, source, options, out, info), source);
}

}  // namespace meshio
}  // namespace splintcore

#endif  // SPLINTCORE_SRC_IO_MESH_TEXT_H
