// STL reader (binary and ASCII), streaming from a ByteSource through a fixed chunk buffer.
//
// Format: binary = 80-byte header, uint32 little-endian triangle count, then per triangle 12
// float32 little-endian (normal, three corners) and a uint16 attribute; ASCII = "solid name",
// facets of "facet normal n n n / outer loop / vertex x y z (x3) / endloop / endfacet", then
// "endsolid". Facet normals are read (ASCII: checked to be numbers) but not kept.
//
// Hostile input: the binary count is never trusted; it must equal the triangles actually
// present, and when the source knows its size the two are compared before anything is
// reserved. Every error carries the byte offset (binary) or line and column (ASCII).
#include <cfloat>
#include <charconv>
#include <cmath>

#include "geometry/float_bounds.h"
#include "geometry/lanes2.h"
#include "io/mesh_text.h"
#include "mesh/exact_weld.h"
#include "splintcore/io.h"

namespace splintcore {

namespace {

constexpr size_t kBinaryHeaderBytes = 84;
constexpr size_t kBinaryRecordBytes = 50;
constexpr size_t kDetectBytes = 1024;
constexpr size_t kMaxTokenBytes = 256;
// How many triangles ahead the weld prefetches its table slots (about a memory latency).
constexpr size_t kAhead = 32;

// The chunked window over the source, shared with the PLY and OBJ readers.
using meshio::Reader;

inline uint32_t load_u32(const uint8_t* p) {
  return uint32_t{p[0]} | (uint32_t{p[1]} << 8) | (uint32_t{p[2]} << 16) | (uint32_t{p[3]} << 24);
}

// A little-endian float32's bits: one 4-byte load on a little-endian host.
inline uint32_t bits_at(const uint8_t* p) {
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
  uint32_t bits;
  std::memcpy(&bits, p, sizeof(bits));
  return bits;
#else
  return load_u32(p);
#endif
}

inline float load_f32(const uint8_t* p) {
  const uint32_t bits = bits_at(p);
  float f;
  std::memcpy(&f, &bits, sizeof(f));
  return f;
}

Status located(Status s, const ByteSource& source) {
  if (source.name != nullptr) s.in_file(source.name);
  return s;
}

// True when all three coordinates are finite and within +-max_abs (NaN fails both tests).
inline bool corner_ok(const float* xyz, double max_abs) {
  bool ok = true;
  for (int a = 0; a < 3; ++a) {
    double v = static_cast<double>(xyz[a]);
    ok = ok && v <= max_abs && v >= -max_abs;
  }
  return ok;
}

// A limit that no coordinate could be checked against (NaN, negative) is the caller's error;
// unchecked, every corner would fail corner_ok() while corner_error() found nothing to name.
Status limit_error(const StlReadOptions& options) {
  if (options.max_abs_coordinate >= 0.0) return Status::ok();
  return make_error(StatusCode::kInvalidArgument, "STL options: max_abs_coordinate is ",
                    options.max_abs_coordinate, "; it must be a number >= 0 (mm)");
}

// The largest bit pattern (sign cleared) of a float within +-max_abs (a number >= 0, as
// limit_error() requires): a coordinate passes corner_ok() exactly when its bits, sign cleared,
// are at most this (finite non-negative floats order as their bits; infinities and NaNs lie
// above every finite one).
uint32_t abs_limit_bits(double max_abs) {
  if (max_abs >= static_cast<double>(FLT_MAX)) return 0x7f7fffffu;
  const float f = static_cast<float>(max_abs);
  uint32_t bits;
  std::memcpy(&bits, &f, sizeof(bits));
  return static_cast<double>(f) > max_abs ? bits - 1 : bits;  // rounded up: the float below
}

Status corner_error(const float* xyz, uint64_t triangle, int corner, double max_abs) {
  for (int a = 0; a < 3; ++a) {
    if (!is_finite(xyz[a])) {
      return make_error(StatusCode::kNonFinite, "triangle ", triangle, " vertex ", corner,
                        " has a non-finite coordinate (NaN or infinity)")
          .at_index(triangle);
    }
  }
  for (int a = 0; a < 3; ++a) {
    double v = static_cast<double>(xyz[a]);
    if (v > max_abs || v < -max_abs) {
      return make_error(StatusCode::kLimitExceeded, "triangle ", triangle, " vertex ", corner,
                        " has coordinate ", v, " mm, beyond the limit of +-", max_abs,
                        " mm (wrong units?)")
          .at_index(triangle);
    }
  }
  return Status::ok();
}

// The error of a binary record (its corners at `corners`) with a coordinate beyond the limit,
// located at that corner (the record starts at byte `offset`).
Status binary_corner_error(const uint8_t* corners, const StlReadOptions& options, uint64_t t,
                           uint64_t offset) {
  for (int k = 0; k < 3; ++k) {
    const float xyz[3] = {load_f32(corners + 12 * k), load_f32(corners + 12 * k + 4),
                          load_f32(corners + 12 * k + 8)};
    if (!corner_ok(xyz, options.max_abs_coordinate)) {
      return corner_error(xyz, t, k, options.max_abs_coordinate)
          .at_byte(offset + 12 + 12 * static_cast<uint64_t>(k));
    }
  }
  return Status::ok();  // not reached: some corner is over the limit
}

// Two little-endian float32s' bits, the first in the low half.
inline uint64_t pair_at(const uint8_t* p) {
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
  uint64_t bits;
  std::memcpy(&bits, p, sizeof(bits));
  return bits;
#else
  return uint64_t{load_u32(p + 4)} << 32 | load_u32(p);
#endif
}

// The crop (StlReadOptions::keep) as float32, for the records' own corners: lo rounded up and
// hi down to float32 (float_up, float_down), so that for every finite float x, x < lo exactly
// when x < lo's float (no float lies between lo and it) and x > hi when x > hi's; NaN fails
// both, as it does Aabb::outcode (a corner that is not finite is over the limit: left_out()
// never leaves its triangle out). Four lanes, the fourth never beyond (-inf, +inf): a triangle is
// left out when, on some axis, its three corners are all below or all above, the same test as
// keep.beyond_one_side on the corners widened to double.
struct FloatCrop {
  Floats4 lo, hi;

  explicit FloatCrop(const Aabb& keep)
      : lo{float_up(keep.lo.x), float_up(keep.lo.y), float_up(keep.lo.z), -HUGE_VALF},
        hi{float_down(keep.hi.x), float_down(keep.hi.y), float_down(keep.hi.z), HUGE_VALF} {}

  // A corner's x, y, z in lanes 0-2 (lane 3: 0), loaded as 8 + 4 bytes on a little-endian
  // host (where a lane's low half comes first).
  static Floats4 corner(const uint8_t* c) {
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
    const Halves xyz = {pair_at(c), bits_at(c + 8)};
    Floats4 out;
    std::memcpy(&out, &xyz, sizeof(out));
    return out;
#else
    return Floats4{load_f32(c), load_f32(c + 4), load_f32(c + 8), 0.0f};
#endif
  }
  // Is the record's triangle (its corners: 36 bytes from `corners`) left out: all three
  // corners beyond one side, and each within `limit` (abs_limit_bits: a magnitude's bits above
  // it are over, infinities and NaN too)? One beyond with a corner over the limit is not: the
  // kept path names that corner, as the read without the crop does.
  bool left_out(const uint8_t* corners, uint32_t limit) const {
    const Floats4 a = corner(corners), b = corner(corners + 12), c = corner(corners + 24);
    const Mask4 beyond = ((a < lo) & (b < lo) & (c < lo)) | ((a > hi) & (b > hi) & (c > hi));
    Mask4 bits[3];
    std::memcpy(&bits[0], &a, sizeof(a));
    std::memcpy(&bits[1], &b, sizeof(b));
    std::memcpy(&bits[2], &c, sizeof(c));
    const int32_t l = static_cast<int32_t>(limit);  // below 2^31, as every magnitude
    const Mask4 magnitude = {0x7fffffff, 0x7fffffff, 0x7fffffff, 0x7fffffff}, most = {l, l, l, l};
    const Mask4 over = ((bits[0] & magnitude) > most) | ((bits[1] & magnitude) > most) |
                       ((bits[2] & magnitude) > most);
    // (Lane 3 is never beyond: lo's is -inf and hi's +inf; nor over: its bits are 0.)
    return mask4_bits(beyond) != 0 && mask4_bits(over) == 0;
  }
};

// Fills `in` for the record of triangle t (of `declared`), or says where the file ends.
Status fill_record(Reader& in, uint64_t t, uint64_t declared) {
  SPLINTCORE_RETURN_IF_ERROR(in.fill(kBinaryRecordBytes));
  if (in.available() >= kBinaryRecordBytes) return Status::ok();
  return make_error(StatusCode::kTruncated, "binary STL ends inside triangle ", t, " of ", declared,
                    " declared")
      .at_byte(in.offset() + in.available())
      .at_index(t);
}

Status read_binary(const Context& ctx, Reader& in, const StlReadOptions& options,
                   ArenaArray<SoupTriangle>* out, StlInfo* info) {
  SPLINTCORE_RETURN_IF_ERROR(in.fill(kBinaryHeaderBytes));
  if (in.available() < kBinaryHeaderBytes) {
    return make_error(StatusCode::kTruncated, "binary STL is ", in.available(),
                      " bytes: too short for the 84-byte header")
        .at_byte(in.offset() + in.available());
  }
  std::memcpy(info->header, in.buf + in.pos, 80);
  info->header[80] = '\0';
  const uint64_t declared = load_u32(in.buf + in.pos + 80);
  in.pos += kBinaryHeaderBytes;
  const uint64_t expected_bytes = kBinaryHeaderBytes + kBinaryRecordBytes * declared;
  if (in.source->size != kUnknownSize && in.source->size != expected_bytes) {
    const uint64_t size = in.source->size;
    if (size < expected_bytes) {
      return make_error(StatusCode::kTruncated, "binary STL header declares ", declared,
                        " triangles (", expected_bytes, " bytes) but the input has ", size,
                        " bytes")
          .at_byte(size);
    }
    return make_error(StatusCode::kParseError, "binary STL header declares ", declared,
                      " triangles (", expected_bytes, " bytes) but the input has ", size,
                      " bytes: ", size - expected_bytes, " bytes after the last triangle")
        .at_byte(expected_bytes);
  }
  if (declared > options.max_triangles) {
    return make_error(StatusCode::kLimitExceeded, "binary STL declares ", declared,
                      " triangles, over the limit of ", options.max_triangles)
        .at_byte(80);
  }
  // Reserve only when the size confirmed the count; otherwise grow as triangles arrive.
  if (in.source->size != kUnknownSize) {
    if (!out->reserve(out->size() + static_cast<size_t>(declared))) {
      return ctx.arena->exhausted_status();
    }
  }
  for (uint64_t t = 0; t < declared; ++t) {
    if ((t & 0xffff) == 0) SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "read", t, declared));
    if (in.available() < kBinaryRecordBytes) {
      SPLINTCORE_RETURN_IF_ERROR(fill_record(in, t, declared));
    }
    const uint8_t* record = in.buf + in.pos;
    SoupTriangle tri;
    for (int k = 0; k < 3; ++k) {
      for (int a = 0; a < 3; ++a) {
        tri.p[k][a] = load_f32(record + 12 + 12 * k + 4 * a);
      }
      if (!corner_ok(tri.p[k], options.max_abs_coordinate)) {
        return corner_error(tri.p[k], t, k, options.max_abs_coordinate)
            .at_byte(in.offset() + 12 + 12 * static_cast<uint64_t>(k));
      }
    }
    if (!out->push_back(tri)) return ctx.arena->exhausted_status();
    in.pos += kBinaryRecordBytes;
  }
  SPLINTCORE_RETURN_IF_ERROR(in.fill(1));
  if (in.available() > 0) {
    return make_error(StatusCode::kParseError, "binary STL has data after the ", declared,
                      " triangles its header declares")
        .at_byte(in.offset());
  }
  info->triangles = declared;
  info->bytes = in.offset();
  return Status::ok();
}

// ASCII tokenizer: white-space separated tokens, with line and column of each token start.
struct Tokenizer {
  Reader* in = nullptr;
  uint64_t line = 1;
  uint64_t column = 1;
  uint64_t token_line = 1;
  uint64_t token_column = 1;
  char token[kMaxTokenBytes + 1] = {};
  size_t length = 0;

  static bool is_space(uint8_t c) {
    return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f' || c == '\v';
  }

  // Reads the next token; length == 0 at the end of input.
  Status next() {
    length = 0;
    for (;;) {
      if (in->available() == 0) {
        SPLINTCORE_RETURN_IF_ERROR(in->fill(1));
        if (in->available() == 0) {
          // No token: "found the end of the input" errors point at where the input ends.
          token_line = line;
          token_column = column;
          return Status::ok();
        }
      }
      uint8_t c = in->buf[in->pos];
      if (!is_space(c)) break;
      advance(c);
    }
    token_line = line;
    token_column = column;
    for (;;) {
      if (in->available() == 0) {
        SPLINTCORE_RETURN_IF_ERROR(in->fill(1));
        if (in->available() == 0) break;
      }
      uint8_t c = in->buf[in->pos];
      if (is_space(c)) break;
      if (c < 0x20 || c > 0x7e) {
        return make_error(StatusCode::kParseError, "ASCII STL has a non-text byte (", c, ")")
            .at_line(line, column)
            .at_byte(in->offset());
      }
      if (length == kMaxTokenBytes) {
        return make_error(StatusCode::kParseError, "ASCII STL token longer than ", kMaxTokenBytes,
                          " characters")
            .at_line(token_line, token_column);
      }
      token[length++] = static_cast<char>(c);
      advance(c);
    }
    token[length] = '\0';
    return Status::ok();
  }

  // Skips to the end of the line (the solid name), copying up to `cap - 1` bytes of it
  // (`copy` null, or cap > 0).
  Status rest_of_line(char* copy, size_t cap) {
    size_t n = 0;
    bool leading = true;
    for (;;) {
      if (in->available() == 0) {
        SPLINTCORE_RETURN_IF_ERROR(in->fill(1));
        if (in->available() == 0) break;
      }
      uint8_t c = in->buf[in->pos];
      if (c == '\n') break;
      advance(c);
      if (leading && (c == ' ' || c == '\t')) continue;
      leading = false;
      if (c != '\r' && copy != nullptr && n + 1 < cap && c >= 0x20 && c <= 0x7e) {
        copy[n++] = static_cast<char>(c);
      }
    }
    if (copy != nullptr) copy[n] = '\0';  // callers give cap > 0 with a copy
    return Status::ok();
  }

  void advance(uint8_t c) {
    ++in->pos;
    if (c == '\n') {
      ++line;
      column = 1;
    } else {
      ++column;
    }
  }

  bool is(const char* keyword) const {
    size_t n = std::strlen(keyword);
    if (n != length) return false;
    for (size_t i = 0; i < n; ++i) {
      char c = token[i];
      if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
      if (c != keyword[i]) return false;
    }
    return true;
  }

  // "<what>, found '<token>'" (or "the end of the input"), located at the token.
  Status error_here(StatusCode code, const char* what, const char* detail = "",
                    const char* detail2 = "") const {
    Status s = make_error(code, what, detail, detail2);
    if (length > 0) {
      s.append(", found '");
      s.append(token, length < 40 ? length : 40);
      s.append("'");
    } else {
      s.append(", found the end of the input");
    }
    return s.at_line(token_line, token_column);
  }

  Status expect(const char* keyword) {
    SPLINTCORE_RETURN_IF_ERROR(next());
    if (is(keyword)) return Status::ok();
    return error_here(length == 0 ? StatusCode::kTruncated : StatusCode::kParseError, "expected '",
                      keyword, "'");
  }

  Status number(float* value) {
    SPLINTCORE_RETURN_IF_ERROR(next());
    if (length == 0) return error_here(StatusCode::kTruncated, "expected a number");
    const char* first = token;
    const char* last = token + length;
    // from_chars takes no '+'; STL writers sometimes emit one (but "+-1" is not a number).
    if (*first == '+' && length > 1 && first[1] != '-') ++first;
    // Only digits, sign, point and exponent: from_chars would also take "inf" and "nan".
    for (const char* p = first; p < last; ++p) {
      char c = *p;
      bool ok = (c >= '0' && c <= '9') || c == '-' || c == '+' || c == '.' || c == 'e' || c == 'E';
      if (!ok) {
        bool named = (last - first >= 3) &&
                     ((first[0] == 'n' || first[0] == 'N' || first[0] == 'i' || first[0] == 'I') ||
                      (first[0] == '-' &&
                       (first[1] == 'n' || first[1] == 'i' || first[1] == 'N' || first[1] == 'I')));
        return error_here(named ? StatusCode::kNonFinite : StatusCode::kParseError,
                          named ? "non-finite number (NaN or infinity)" : "expected a number");
      }
    }
    auto r = std::from_chars(first, last, *value, std::chars_format::general);
    if (r.ec == std::errc::result_out_of_range) {
      return error_here(StatusCode::kParseError, "number out of float32 range");
    }
    if (r.ec != std::errc() || r.ptr != last) {
      return error_here(StatusCode::kParseError, "expected a number");
    }
    return Status::ok();
  }
};

Status read_ascii(const Context& ctx, Reader& in, const StlReadOptions& options,
                  ArenaArray<SoupTriangle>* out, StlInfo* info) {
  Tokenizer tok;
  tok.in = &in;
  SPLINTCORE_RETURN_IF_ERROR(tok.expect("solid"));
  SPLINTCORE_RETURN_IF_ERROR(tok.rest_of_line(info->header, sizeof(info->header)));
  uint64_t count = 0;
  for (;;) {
    SPLINTCORE_RETURN_IF_ERROR(tok.next());
    if (tok.is("endsolid")) {
      SPLINTCORE_RETURN_IF_ERROR(tok.rest_of_line(nullptr, 0));
      SPLINTCORE_RETURN_IF_ERROR(tok.next());
      if (tok.length == 0) break;  // end of input
      if (tok.is("solid")) {       // several solids in one file: read them all
        SPLINTCORE_RETURN_IF_ERROR(tok.rest_of_line(nullptr, 0));
        continue;
      }
      return tok.error_here(StatusCode::kParseError,
                            "expected 'solid' or the end after 'endsolid'");
    }
    if (!tok.is("facet")) {
      return tok.error_here(tok.length == 0 ? StatusCode::kTruncated : StatusCode::kParseError,
                            "expected 'facet' or 'endsolid'");
    }
    const uint64_t facet_line = tok.token_line;
    if ((count & 0xffff) == 0) {
      SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "read", in.offset(), in.source->size));
    }
    if (count >= options.max_triangles) {
      return make_error(StatusCode::kLimitExceeded, "ASCII STL has more than ",
                        options.max_triangles, " triangles (the limit)")
          .at_line(facet_line);
    }
    SPLINTCORE_RETURN_IF_ERROR(tok.expect("normal"));
    float normal[3];
    for (float& n : normal) SPLINTCORE_RETURN_IF_ERROR(tok.number(&n));
    SPLINTCORE_RETURN_IF_ERROR(tok.expect("outer"));
    SPLINTCORE_RETURN_IF_ERROR(tok.expect("loop"));
    SoupTriangle tri;
    for (int k = 0; k < 3; ++k) {
      SPLINTCORE_RETURN_IF_ERROR(tok.expect("vertex"));
      const uint64_t vertex_line = tok.token_line;
      for (float& v : tri.p[k]) SPLINTCORE_RETURN_IF_ERROR(tok.number(&v));
      if (!corner_ok(tri.p[k], options.max_abs_coordinate)) {
        return corner_error(tri.p[k], count, k, options.max_abs_coordinate).at_line(vertex_line);
      }
    }
    SPLINTCORE_RETURN_IF_ERROR(tok.expect("endloop"));
    SPLINTCORE_RETURN_IF_ERROR(tok.expect("endfacet"));
    if (!out->push_back(tri)) return ctx.arena->exhausted_status();
    ++count;
  }
  info->triangles = count;
  info->bytes = in.offset();
  return Status::ok();
}

bool looks_ascii(const uint8_t* p, size_t n) {
  size_t i = 0;
  while (i < n && (p[i] == ' ' || p[i] == '\t' || p[i] == '\r' || p[i] == '\n')) ++i;
  if (n - i < 5) return false;
  const char* solid = "solid";
  for (size_t k = 0; k < 5; ++k) {
    char c = static_cast<char>(p[i + k]);
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
    if (c != solid[k]) return false;
  }
  for (size_t k = 0; k < n; ++k) {
    uint8_t c = p[k];
    bool text = (c >= 0x20 && c <= 0x7e) || c == '\t' || c == '\r' || c == '\n';
    if (!text) return false;
  }
  return true;
}

}  // namespace

Status read_stl(const Context& ctx, const ByteSource& source, const StlReadOptions& options,
                ArenaArray<SoupTriangle>* out, StlInfo* info) {
  StlInfo local;
  if (info == nullptr) info = &local;
  *info = StlInfo{};
  SPLINTCORE_RETURN_IF_ERROR(limit_error(options));
  if (source.read == nullptr) {
    return Status::error(StatusCode::kInvalidArgument, "read_stl: byte source has no read()");
  }
  size_t chunk = options.chunk_bytes < 4096 ? 4096 : options.chunk_bytes;
  // The chunk buffer sits below the growing triangle array so that the array stays at the
  // top of the arena and grows in place. It is not reclaimed here on success (read_stl_mesh
  // does); on an error the arena goes back to `entry` and `out` to what it held.
  const Arena::Marker entry = ctx.arena->mark();
  const ArenaArray<SoupTriangle> saved = *out;
  Reader in;
  in.source = &source;
  in.cap = chunk;
  in.buf = ctx.arena->allocate_array<uint8_t>(chunk);
  if (in.buf == nullptr) return located(ctx.arena->exhausted_status(), source);

  Status s = in.fill(kDetectBytes);
  if (s.is_ok()) {
    StlFormat format = options.format;
    if (format == StlFormat::kAuto) {
      size_t n = in.available() < kDetectBytes ? in.available() : kDetectBytes;
      format = looks_ascii(in.buf, n) ? StlFormat::kAscii : StlFormat::kBinary;
    }
    info->format = format;
    s = format == StlFormat::kAscii ? read_ascii(ctx, in, options, out, info)
                                    : read_binary(ctx, in, options, out, info);
  }
  if (!s.is_ok()) {
    ctx.arena->rewind(entry);
    *out = saved;
  }
  return located(s, source);
}

namespace {

// Reads up to sizeof(head) bytes (less only at the end of the source) into `head`.
Status read_head(const ByteSource& source, uint8_t* head, size_t cap, size_t* got) {
  *got = 0;
  while (*got < cap) {
    const int64_t n = source.read(source.user, head + *got, cap - *got);
    if (n < 0) return make_error(StatusCode::kIoError, "read failed").at_byte(*got);
    if (static_cast<uint64_t>(n) > cap - *got) {
      return Status::error(StatusCode::kIoError, "byte source returned more than asked");
    }
    if (n == 0) break;
    *got += static_cast<size_t>(n);
  }
  return Status::ok();
}

// Where read_binary_welded finds the records (the first at `in->base`, 84): where a memory
// source holds them (no copy, no buffer), else in a buffer `in` reads them into chunk by chunk,
// the head's bytes past the header first. Null when the arena has no room for the buffer.
const uint8_t* binary_records(Arena& arena, const uint8_t* head, size_t got, uint64_t declared,
                              const StlReadOptions& options, Reader* in) {
  in->base = kBinaryHeaderBytes;
  const uint8_t* whole = meshio::take_memory_bytes(*in->source, got);
  if (whole != nullptr) {
    in->cap = in->end = static_cast<size_t>(kBinaryRecordBytes * declared);
    in->at_eof = true;  // (so nothing is ever read into `in`)
    return whole + kBinaryHeaderBytes;
  }
  in->cap = options.chunk_bytes < 4096 ? 4096 : options.chunk_bytes;
  in->buf = arena.allocate_array<uint8_t>(in->cap);
  if (in->buf == nullptr) return nullptr;
  std::memcpy(in->buf, head + kBinaryHeaderBytes, got - kBinaryHeaderBytes);
  in->end = got - kBinaryHeaderBytes;
  return in->buf;
}

// The binary STL welded straight from its records (where a memory source holds them, or the
// read buffer): the triangles, the weld's positions and table, the read buffer; no soup. The
// vertices usually stay where they were reserved. Only for a source whose size confirms the
// header's count (read_stl_mesh checks), so the errors left are the ones read_binary gives
// past its header, with the same text.
Status read_binary_welded(const Context& ctx, const ByteSource& source, const uint8_t* head,
                          size_t got, const StlReadOptions& options, Mesh* out, StlInfo* info) {
  Arena& arena = *ctx.arena;
  const uint64_t declared = load_u32(head + 80);
  Triangle* tris = arena.allocate_array<Triangle>(static_cast<size_t>(declared));
  if (tris == nullptr) return arena.exhausted_status();
  const Arena::Marker above = arena.mark();
  Reader in;
  in.source = &source;
  ExactWelder welder;
  if (!welder.init(arena, declared)) return arena.exhausted_status();
  std::memcpy(info->header, head, 80);
  info->header[80] = '\0';
  const uint8_t* records = binary_records(arena, head, got, declared, options, &in);
  if (records == nullptr) return arena.exhausted_status();
  const uint32_t limit = abs_limit_bits(options.max_abs_coordinate);
  const bool crop = !options.keep.empty();
  const FloatCrop keep(options.keep);
  size_t kept = 0;                // triangles in the mesh (all of them without a crop)
  uint64_t ahead[2 * kAhead][3];  // the prefetched corners' hashes, by triangle mod 2 kAhead
  bool ahead_out[2 * kAhead];     // and whether the crop leaves that triangle out (no hashes)
  for (uint64_t t = 0; t < declared;) {
    if ((t & 0xffff) == 0) SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "read", t, declared));
    if (in.available() < kBinaryRecordBytes) {
      SPLINTCORE_RETURN_IF_ERROR(fill_record(in, t, declared));
    }
    // The whole records in the buffer, up to the next progress report.
    uint64_t run = in.available() / kBinaryRecordBytes;
    run = run < declared - t ? run : declared - t;
    run = run < 0x10000 - (t & 0xffff) ? run : 0x10000 - (t & 0xffff);
    const uint8_t* record = records + in.pos;
    for (uint64_t i = 0; i < run; ++i, record += kBinaryRecordBytes) {
      // Each coordinate loaded where it is used, never copied into an array (GCC makes such a
      // copy a `rep movs`, whose start-up cost was a third of this loop's time).
      if (i + kAhead < run) {  // the slots of a triangle ahead; its hashes kept for then
        const uint8_t* c = record + kAhead * kBinaryRecordBytes + 12;
        const size_t slot = (i + kAhead) % (2 * kAhead);
        // (With a crop most triangles are left out: the test moves here, before the hashes.)
        ahead_out[slot] = crop && keep.left_out(c, limit);
        if (!ahead_out[slot]) {
          uint64_t* h = ahead[slot];
          h[0] = ExactWelder::hash_bits(bits_at(c), bits_at(c + 4), bits_at(c + 8));
          h[1] = ExactWelder::hash_bits(bits_at(c + 12), bits_at(c + 16), bits_at(c + 20));
          h[2] = ExactWelder::hash_bits(bits_at(c + 24), bits_at(c + 28), bits_at(c + 32));
          __builtin_prefetch(welder.first_slot(h[0]));
          __builtin_prefetch(welder.first_slot(h[1]));
          __builtin_prefetch(welder.first_slot(h[2]));
        }
      }
      const uint8_t* corners = record + 12;
      // Left out: its corners were checked too (the same errors as without the crop).
      if (crop && (i >= kAhead ? ahead_out[i % (2 * kAhead)] : keep.left_out(corners, limit))) {
        continue;
      }
      for (int k = 0; k < 3; ++k) {
        const uint8_t* c = corners + 12 * k;
        const uint32_t x = bits_at(c), y = bits_at(c + 4), z = bits_at(c + 8);
        // limit - magnitude wraps (top bit set) exactly when magnitude > limit: both < 2^31.
        // (The corners before k are welded by then, but an error leaves nothing behind.)
        const uint32_t over =
            (limit - (x & 0x7fffffffu)) | (limit - (y & 0x7fffffffu)) | (limit - (z & 0x7fffffffu));
        if ((over & 0x80000000u) != 0) {
          return binary_corner_error(corners, options, t + i, in.offset() + kBinaryRecordBytes * i);
        }
        const uint64_t h =
            i >= kAhead ? ahead[i % (2 * kAhead)][k] : ExactWelder::hash_bits(x, y, z);
        const uint32_t id = welder.vertex(x, y, z, h);
        if (id == ExactWelder::kFull) return arena.exhausted_status();
        tris[kept].v[k] = id;
      }
      ++kept;
    }
    in.pos += static_cast<size_t>(kBinaryRecordBytes * run);
    t += run;
  }
  SPLINTCORE_RETURN_IF_ERROR(in.fill(1));
  if (in.available() > 0) {
    return make_error(StatusCode::kParseError, "binary STL has data after the ", declared,
                      " triangles its header declares")
        .at_byte(in.offset());
  }
  info->format = StlFormat::kBinary;
  info->triangles = declared;
  info->bytes = in.offset();
  welder.finish(arena, above, &out->vertices);
  out->triangles.adopt(tris, kept, static_cast<size_t>(declared));
  return Status::ok();
}

// The soup read whole by read_stl, then welded (ASCII, sources of unknown size, and binary
// files whose header does not match their size: read_stl says what is wrong).
Status read_then_weld(const Context& ctx, const ByteSource& source, const StlReadOptions& options,
                      Mesh* out, StlInfo* info) {
  Arena& arena = *ctx.arena;
  ArenaScope scope(arena);
  ArenaArray<SoupTriangle> soup(&arena);
  SPLINTCORE_RETURN_IF_ERROR(read_stl(ctx, source, options, &soup, info));
  if (!options.keep.empty()) {  // the triangles left out, the others kept in their order
    auto corner = [](const float* p) {
      return Vec3(static_cast<double>(p[0]), static_cast<double>(p[1]), static_cast<double>(p[2]));
    };
    size_t kept = 0;
    for (const SoupTriangle& t : soup) {
      if (!options.keep.beyond_one_side(corner(t.p[0]), corner(t.p[1]), corner(t.p[2]))) {
        soup[kept++] = t;
      }
    }
    soup.shrink_size(kept);
  }
  soup.shrink_to_fit();  // an ASCII soup grown by half again: the spare room is the weld's
  Mesh welded(&arena);
  Status s = weld_exact(ctx, soup.span(), &welded);
  if (!s.is_ok()) return located(s, source);
  // The mesh down over the soup and the read buffer (weld_exact allocates triangles first).
  move_mesh_down(arena, scope.start(), welded, out);
  scope.commit();
  return Status::ok();
}

}  // namespace

Status read_stl_mesh(const Context& ctx, const ByteSource& source, const StlReadOptions& options,
                     Mesh* out, StlInfo* info) {
  if (!out->vertices.empty() || !out->triangles.empty()) {
    return Status::error(StatusCode::kInvalidArgument, "read_stl_mesh: output mesh must be empty");
  }
  SPLINTCORE_RETURN_IF_ERROR(limit_error(options));
  StlInfo local;
  if (info == nullptr) info = &local;
  if (source.read == nullptr || source.size == kUnknownSize ||
      options.format == StlFormat::kAscii) {
    return read_then_weld(ctx, source, options, out, info);
  }
  // The size is known: the head tells the format and, for binary, whether the count is right.
  uint8_t head[kDetectBytes];
  size_t got = 0;
  Status s = read_head(source, head, sizeof(head), &got);
  if (!s.is_ok()) return located(s, source);
  const bool binary = options.format == StlFormat::kBinary || !looks_ascii(head, got);
  const uint64_t declared = got >= kBinaryHeaderBytes ? load_u32(head + 80) : 0;
  const bool sized = binary && got >= kBinaryHeaderBytes && declared > 0 &&
                     source.size == kBinaryHeaderBytes + kBinaryRecordBytes * declared &&
                     declared <= options.max_triangles;
  if (sized && declared > (uint64_t{UINT32_MAX} - 1) / 3) {  // weld_exact's limit, said early
    return located(
        make_error(StatusCode::kLimitExceeded, "mesh has ", declared, " triangles; at most ",
                   (uint64_t{UINT32_MAX} - 1) / 3, " are supported (32-bit vertex ids)"),
        source);
  }
  if (sized) {
    *info = StlInfo{};
    ArenaScope scope(*ctx.arena);  // on an error the arena is as it was, `out` empty
    const Mesh saved = *out;
    s = read_binary_welded(ctx, source, head, got, options, out, info);
    if (!s.is_ok()) {
      *out = saved;
      *info = StlInfo{};
      return located(s, source);
    }
    // Cropped: the triangles' room for those left out given back, the vertices moved down over
    // it (the real dentition's 31 files keep 192,564 of 887,688 triangles: without this they
    // held 8.3 MB more until B was made, and the read's high water was 15.4 MB, not 7.0 MB).
    if (out->triangles.size() < out->triangles.capacity()) {
      move_mesh_down(*ctx.arena, scope.start(), *out, out);
    }
    scope.commit();
    return Status::ok();
  }
  meshio::PeekSource peek;
  const ByteSource replay = peek.replay(source, head, got);
  return read_then_weld(ctx, replay, options, out, info);
}

uint64_t read_stl_bound(uint64_t bytes, const StlReadOptions& options) {
  const size_t chunk = options.chunk_bytes < 4096 ? 4096 : options.chunk_bytes;
  return arena_array_bound<uint8_t>(chunk) + arena_array_bound<SoupTriangle>(bytes / 50);
}

uint64_t read_stl_mesh_bound(uint64_t bytes, const StlReadOptions& options) {
  const size_t chunk = options.chunk_bytes < 4096 ? 4096 : options.chunk_bytes;
  // Binary, size known: the triangles and the weld's table and positions, with the read
  // buffer among them; no soup.
  const uint64_t binary = bytes >= kBinaryHeaderBytes ? (bytes - kBinaryHeaderBytes) / 50 : 0;
  const uint64_t streamed = arena_array_bound<uint8_t>(chunk) + weld_exact_bound(binary);
  // ASCII: the soup read whole, then welded; a facet takes at least 85 bytes.
  const uint64_t facets = bytes / 85;
  const uint64_t ascii = arena_array_bound<uint8_t>(chunk) +
                         arena_array_bound<SoupTriangle>(facets) + weld_exact_bound(facets);
  return streamed > ascii ? streamed : ascii;
}

}  // namespace splintcore
