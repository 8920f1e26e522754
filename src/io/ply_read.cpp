// PLY reader (ASCII, binary little- and big-endian), streaming from a ByteSource.
//
// Format: G. Turk, "The PLY Polygon File Format" (1994), as described by Paul Bourke
// ("PLY - Polygon File Format", paulbourke.net/dataformats/ply): a text header ("ply",
// "format <ascii|binary_little_endian|binary_big_endian> 1.0", "comment"/"obj_info" lines,
// "element <name> <count>" each followed by its "property <type> <name>" or "property list
// <count type> <item type> <name>" lines, "end_header"), then the elements' records in header
// order: ASCII one record per line, binary the properties packed in declared order and byte
// order. Faces are fan-triangulated (io.h).
//
// Hostile input: element counts are checked against the limits and, when the source knows its
// size, against the smallest number of bytes their records can take, before anything is
// reserved; indices against the vertex count; every error carries a byte offset (binary) or a
// line and column (header, ASCII) and the record's index.
#include "mesh_text.h"

namespace splintcore {

namespace {

using meshio::LineReader;
using meshio::MeshBuilder;
using meshio::Reader;
using meshio::token_error;
using meshio::Tokens;

constexpr size_t kMaxElements = 32;
constexpr size_t kMaxProperties = 256;  // over all elements
constexpr size_t kNameBytes = 32;

enum Type : uint8_t {
  kNone = 0,
  kInt8,
  kUInt8,
  kInt16,
  kUInt16,
  kInt32,
  kUInt32,
  kFloat32,
  kFloat64
};

constexpr uint8_t kTypeBytes[] = {0, 1, 1, 2, 2, 4, 4, 4, 8};

Type parse_type(const Tokens& t) {
  static const struct {
    const char* name;
    Type type;
  } kNames[] = {
      {"char", kInt8},     {"int8", kInt8},       {"uchar", kUInt8},    {"uint8", kUInt8},
      {"short", kInt16},   {"int16", kInt16},     {"ushort", kUInt16},  {"uint16", kUInt16},
      {"int", kInt32},     {"int32", kInt32},     {"uint", kUInt32},    {"uint32", kUInt32},
      {"float", kFloat32}, {"float32", kFloat32}, {"double", kFloat64}, {"float64", kFloat64}};
  for (const auto& n : kNames) {
    if (t.is(n.name)) return n.type;
  }
  return kNone;
}

bool is_integer_type(uint8_t type) { return type >= kInt8 && type <= kUInt32; }

enum Role : uint8_t { kSkip = 0, kX, kY, kZ, kIndices };

struct Property {
  uint8_t type = kNone;        // scalar type, or the item type of a list
  uint8_t count_type = kNone;  // kNone: a scalar
  uint8_t role = kSkip;
};

enum ElementKind : uint8_t { kOther = 0, kVertex, kFace };

struct Element {
  char name[kNameBytes] = {};
  uint64_t count = 0;
  uint32_t first = 0;  // its properties: header.properties[first, first + properties)
  uint32_t properties = 0;
  uint8_t kind = kOther;
};

struct Header {
  MeshFormat format = MeshFormat::kUnknown;
  Element elements[kMaxElements];
  Property properties[kMaxProperties];
  uint32_t element_count = 0;
  uint32_t property_count = 0;
  int vertex = -1;  // element index
  int face = -1;
};

void copy_name(char* dst, const Tokens& t) {
  const size_t n = t.token_length < kNameBytes - 1 ? t.token_length : kNameBytes - 1;
  std::memcpy(dst, t.token, n);
  dst[n] = '\0';
}

// "format <ascii|binary_little_endian|binary_big_endian> 1.0" (t is at "format").
Status read_format(const LineReader& lines, Tokens& t, Header* h) {
  if (h->format != MeshFormat::kUnknown) {
    return token_error(StatusCode::kParseError, lines, t, "second 'format' line");
  }
  t.next();
  if (t.is("ascii")) {
    h->format = MeshFormat::kPlyAscii;
  } else if (t.is("binary_little_endian")) {
    h->format = MeshFormat::kPlyBinaryLittleEndian;
  } else if (t.is("binary_big_endian")) {
    h->format = MeshFormat::kPlyBinaryBigEndian;
  } else {
    return token_error(StatusCode::kParseError, lines, t,
                       "expected ascii, binary_little_endian or binary_big_endian");
  }
  t.next();
  if (!t.is("1.0"))
    return token_error(StatusCode::kUnsupported, lines, t, "expected format version 1.0");
  if (t.next())
    return token_error(StatusCode::kParseError, lines, t, "expected the end of the format line");
  return Status::ok();
}

// "element <name> <count>" (t is at "element").
Status read_element(const LineReader& lines, Tokens& t, Header* h) {
  if (h->element_count == kMaxElements) {
    return token_error(StatusCode::kLimitExceeded, lines, t, "more than 32 elements");
  }
  Element& e = h->elements[h->element_count];
  if (!t.next()) return token_error(StatusCode::kParseError, lines, t, "expected an element name");
  copy_name(e.name, t);
  if (t.is("vertex")) e.kind = kVertex;
  if (t.is("face")) e.kind = kFace;
  if ((e.kind == kVertex && h->vertex >= 0) || (e.kind == kFace && h->face >= 0)) {
    return token_error(StatusCode::kParseError, lines, t, "second element of this name");
  }
  t.next();
  int64_t count = -1;
  if (!meshio::parse_integer(t.token, t.token + t.token_length, &count) || count < 0) {
    return token_error(StatusCode::kParseError, lines, t, "expected an element count");
  }
  if (t.next())
    return token_error(StatusCode::kParseError, lines, t, "expected the end of the element line");
  e.count = static_cast<uint64_t>(count);
  e.first = h->property_count;
  if (e.kind == kVertex) h->vertex = static_cast<int>(h->element_count);
  if (e.kind == kFace) h->face = static_cast<int>(h->element_count);
  ++h->element_count;
  return Status::ok();
}

// "property <type> <name>" or "property list <count type> <item type> <name>" of the last
// element (t is at "property"): the vertex's x, y, z and the face's index list get their roles.
Status read_property(const LineReader& lines, Tokens& t, Header* h) {
  if (h->element_count == 0) {
    return token_error(StatusCode::kParseError, lines, t, "property before any element");
  }
  if (h->property_count == kMaxProperties) {
    return token_error(StatusCode::kLimitExceeded, lines, t, "more than 256 properties");
  }
  Element& e = h->elements[h->element_count - 1];
  Property p;
  t.next();
  if (t.is("list")) {
    t.next();
    p.count_type = parse_type(t);
    if (p.count_type == kNone)
      return token_error(StatusCode::kParseError, lines, t, "expected a list count type");
    t.next();
  }
  p.type = parse_type(t);
  if (p.type == kNone)
    return token_error(StatusCode::kParseError, lines, t, "expected a property type");
  if (!t.next()) return token_error(StatusCode::kParseError, lines, t, "expected a property name");
  if (e.kind == kVertex && p.count_type == kNone) {
    if (t.is("x")) p.role = kX;
    if (t.is("y")) p.role = kY;
    if (t.is("z")) p.role = kZ;
  }
  if (e.kind == kFace && p.count_type != kNone &&
      (t.is("vertex_indices") || t.is("vertex_index"))) {
    p.role = kIndices;
  }
  if (p.count_type != kNone && !is_integer_type(p.count_type)) {
    return token_error(StatusCode::kUnsupported, lines, t,
                       "list count type is not an integer type for list");
  }
  if (p.role == kIndices && !is_integer_type(p.type)) {
    return token_error(StatusCode::kUnsupported, lines, t,
                       "vertex indices of a non-integer type in list");
  }
  for (uint32_t i = e.first; i < h->property_count; ++i) {
    if (p.role != kSkip && h->properties[i].role == p.role) {
      return token_error(StatusCode::kParseError, lines, t, "second property of this name");
    }
  }
  if (t.next())
    return token_error(StatusCode::kParseError, lines, t, "expected the end of the property line");
  h->properties[h->property_count++] = p;
  ++e.properties;
  return Status::ok();
}

// What the body needs from a complete header: a format, a vertex element with x, y and z, and
// a face element (if any) with its index list. Errors name the 'end_header' line.
Status check_header(const LineReader& lines, const Header& h) {
  if (h.format == MeshFormat::kUnknown) {
    return make_error(StatusCode::kParseError, "PLY header has no 'format' line")
        .at_line(lines.number, 1);
  }
  if (h.vertex < 0) {
    return make_error(StatusCode::kParseError, "PLY header declares no 'vertex' element")
        .at_line(lines.number, 1);
  }
  const Element& v = h.elements[h.vertex];
  bool has[4] = {false, false, false, false};
  for (uint32_t i = v.first; i < v.first + v.properties; ++i) has[h.properties[i].role] = true;
  if (!has[kX] || !has[kY] || !has[kZ]) {
    return make_error(StatusCode::kParseError,
                      "PLY vertex element lacks one of the scalar properties x, y, z")
        .at_line(lines.number, 1);
  }
  if (h.face >= 0) {
    const Element& f = h.elements[h.face];
    bool indices = false;
    for (uint32_t i = f.first; i < f.first + f.properties; ++i) {
      indices = indices || h.properties[i].role == kIndices;
    }
    if (!indices) {
      return make_error(StatusCode::kParseError,
                        "PLY face element has no list property vertex_indices (or vertex_index)")
          .at_line(lines.number, 1);
    }
  }
  return Status::ok();
}

Status parse_header(LineReader& lines, Header* h) {
  bool got = false;
  SPLINTCORE_RETURN_IF_ERROR(lines.next(&got));
  if (!got || lines.length != 3 || std::memcmp(lines.line, "ply", 3) != 0) {
    return make_error(StatusCode::kParseError, "not a PLY file: the first line must be 'ply'")
        .at_line(1, 1)
        .at_byte(0);
  }
  for (;;) {
    SPLINTCORE_RETURN_IF_ERROR(lines.next(&got));
    if (!got) {
      return make_error(StatusCode::kTruncated, "PLY header ends without 'end_header'")
          .at_line(lines.number + 1, 1)
          .at_byte(lines.in->offset());
    }
    Tokens t(lines.line, lines.length);
    if (!t.next()) continue;  // a blank line
    if (t.is("comment") || t.is("obj_info")) continue;
    if (t.is("end_header")) {
      if (t.next())
        return token_error(StatusCode::kParseError, lines, t,
                           "expected nothing after 'end_header'");
      break;
    }
    if (t.is("format")) {
      SPLINTCORE_RETURN_IF_ERROR(read_format(lines, t, h));
      continue;
    }
    if (h->format == MeshFormat::kUnknown) {
      return token_error(StatusCode::kParseError, lines, t, "expected the 'format' line first");
    }
    if (t.is("element")) {
      SPLINTCORE_RETURN_IF_ERROR(read_element(lines, t, h));
      continue;
    }
    if (t.is("property")) {
      SPLINTCORE_RETURN_IF_ERROR(read_property(lines, t, h));
      continue;
    }
    return token_error(StatusCode::kParseError, lines, t, "expected a PLY header keyword");
  }
  return check_header(lines, *h);
}

// The fewest bytes a record of `e` can take: binary, its scalars and list counts (a face's
// index list at least three items); ASCII, two characters (digit and separator) per value.
uint64_t min_record_bytes(const Header& h, const Element& e, bool binary) {
  uint64_t bytes = 0;
  for (uint32_t i = e.first; i < e.first + e.properties; ++i) {
    const Property& p = h.properties[i];
    const uint64_t items = p.role == kIndices ? 3 : 0;
    if (p.count_type == kNone) {
      bytes += binary ? kTypeBytes[p.type] : 2;
    } else {
      bytes += binary ? kTypeBytes[p.count_type] + items * kTypeBytes[p.type] : 2 * (1 + items);
    }
  }
  return bytes;
}

// Fan triangulation of one face's corners, streamed: the first corner and the previous one.
struct Fan {
  uint32_t first = 0;
  uint32_t previous = 0;
  uint64_t corners = 0;
};

struct Body {
  const Context* ctx = nullptr;
  const MeshReadOptions* options = nullptr;
  const Header* header = nullptr;
  MeshBuilder* mesh = nullptr;
  uint64_t vertex_count = 0;  // declared (the indices' bound)
  uint64_t triangles = 0;

  // Rounds (when asked and in range: a value beyond the limit is kept so the error shows it).
  double coordinate(double v) const {
    const double m = options->max_abs_coordinate;
    if (options->round_to_float32 && v <= m && v >= -m)
      return static_cast<double>(static_cast<float>(v));
    return v;
  }

  // One corner of face `face`. Errors: the index is out of range.
  Status corner(Fan* fan, int64_t index, uint64_t face) {
    if (index < 0 || static_cast<uint64_t>(index) >= vertex_count) {
      return make_error(StatusCode::kParseError, "face ", face, " has vertex index ", index,
                        ", outside 0..", vertex_count == 0 ? 0 : vertex_count - 1, " (",
                        vertex_count, " vertices)")
          .at_index(face);
    }
    const uint32_t v = static_cast<uint32_t>(index);
    if (fan->corners == 0) {
      fan->first = v;
    } else if (fan->corners >= 2) {
      SPLINTCORE_RETURN_IF_ERROR(mesh->add_triangle(fan->first, fan->previous, v, face));
    }
    fan->previous = v;
    ++fan->corners;
    return Status::ok();
  }
};

Status face_too_small(uint64_t face, uint64_t corners) {
  return make_error(StatusCode::kParseError, "face ", face, " has ", corners,
                    " vertices; a polygon needs at least 3")
      .at_index(face);
}

// ---------------------------------------------------------------------------------------------
// Binary records.

// The N bytes at p as an unsigned integer, little- or big-endian (compilers make each a load).
template <size_t N>
inline uint64_t load_le(const uint8_t* p) {
  uint64_t bits = 0;
  for (size_t k = 0; k < N; ++k) bits |= uint64_t{p[k]} << (8 * k);
  return bits;
}
template <size_t N>
inline uint64_t load_be(const uint8_t* p) {
  uint64_t bits = 0;
  for (size_t k = 0; k < N; ++k) bits = (bits << 8) | p[k];
  return bits;
}
template <size_t N>
inline uint64_t load_bits(const uint8_t* p, bool big) {
  return big ? load_be<N>(p) : load_le<N>(p);
}

// The value of `type` whose bytes start at p: integers to *i, reals (and integers) to *d.
inline void decode_value(const uint8_t* p, uint8_t type, bool big, int64_t* i, double* d) {
  switch (type) {
    case kInt8: *i = static_cast<int64_t>(p[0]) - ((p[0] & 0x80u) != 0 ? 256 : 0); break;
    case kUInt8: *i = static_cast<int64_t>(p[0]); break;
    case kInt16: *i = static_cast<int16_t>(static_cast<uint16_t>(load_bits<2>(p, big))); break;
    case kUInt16: *i = static_cast<int64_t>(load_bits<2>(p, big)); break;
    case kInt32: *i = static_cast<int32_t>(static_cast<uint32_t>(load_bits<4>(p, big))); break;
    case kUInt32: *i = static_cast<int64_t>(load_bits<4>(p, big)); break;
    case kFloat32: {
      const uint32_t b32 = static_cast<uint32_t>(load_bits<4>(p, big));
      float f;
      std::memcpy(&f, &b32, 4);
      *d = static_cast<double>(f);
      return;
    }
    default: {
      const uint64_t b64 = load_bits<8>(p, big);
      std::memcpy(d, &b64, 8);
      return;
    }
  }
  *d = static_cast<double>(*i);
}

struct BinaryIn {
  Reader* in = nullptr;
  bool big = false;

  // Reads one value of `type`: integers to *i, reals (and integers) to *d.
  Status value(uint8_t type, int64_t* i, double* d, const Element& e, uint64_t record) {
    const size_t n = kTypeBytes[type];
    if (in->available() < n) {
      SPLINTCORE_RETURN_IF_ERROR(in->fill(n));
      if (in->available() < n) {
        return make_error(StatusCode::kTruncated, "binary PLY ends inside ", e.name, " ", record,
                          " of ", e.count)
            .at_byte(in->offset() + in->available())
            .at_index(record);
      }
    }
    decode_value(in->buf + in->pos, type, big, i, d);
    in->pos += n;
    return Status::ok();
  }

  // Skips `bytes` bytes.
  Status skip(uint64_t bytes, const Element& e, uint64_t record) {
    while (bytes > 0) {
      if (in->available() == 0) {
        SPLINTCORE_RETURN_IF_ERROR(in->fill(1));
        if (in->available() == 0) {
          return make_error(StatusCode::kTruncated, "binary PLY ends inside ", e.name, " ", record,
                            " of ", e.count)
              .at_byte(in->offset())
              .at_index(record);
        }
      }
      const uint64_t take = bytes < in->available() ? bytes : in->available();
      in->pos += static_cast<size_t>(take);
      bytes -= take;
    }
    return Status::ok();
  }
};

// The values of a record that lies whole in the buffer, decoded where they are (as BinaryIn
// reads them, but never refilling, so never failing).
struct InPlace {
  const uint8_t* q = nullptr;
  bool big = false;

  Status value(uint8_t type, int64_t* i, double* d, const Element&, uint64_t) {
    decode_value(q, type, big, i, d);
    q += kTypeBytes[type];
    return Status::ok();
  }
  Status skip(uint64_t bytes, const Element&, uint64_t) {
    q += bytes;
    return Status::ok();
  }
};

// Record r of element e, starting at byte record_byte, its values from `b`: a BinaryIn
// (value by value, each refilling the buffer as needed: the way for a record across the
// buffer's end, and the one that reports a truncated file) or an InPlace.
template <class Values>
Status binary_record(Body& body, Values& b, const Element& e, uint64_t r, uint64_t record_byte) {
  const Header& h = *body.header;
  Vec3 v;
  for (uint32_t pi = e.first; pi < e.first + e.properties; ++pi) {
    const Property& p = h.properties[pi];
    int64_t i = 0;
    double d = 0;
    if (p.count_type == kNone) {
      if (p.role == kSkip) {
        SPLINTCORE_RETURN_IF_ERROR(b.skip(kTypeBytes[p.type], e, r));
      } else {
        SPLINTCORE_RETURN_IF_ERROR(b.value(p.type, &i, &d, e, r));
        v[p.role - kX] = body.coordinate(d);
      }
      continue;
    }
    int64_t n = 0;
    SPLINTCORE_RETURN_IF_ERROR(b.value(p.count_type, &n, &d, e, r));
    if (n < 0) {
      return make_error(StatusCode::kParseError, e.name, " ", r, " has a list of ", n, " items")
          .at_byte(record_byte)
          .at_index(r);
    }
    if (p.role != kIndices) {
      SPLINTCORE_RETURN_IF_ERROR(b.skip(static_cast<uint64_t>(n) * kTypeBytes[p.type], e, r));
      continue;
    }
    if (n < 3) return face_too_small(r, static_cast<uint64_t>(n)).at_byte(record_byte);
    Fan fan;
    for (int64_t k = 0; k < n; ++k) {
      SPLINTCORE_RETURN_IF_ERROR(b.value(p.type, &i, &d, e, r));
      Status s = body.corner(&fan, i, r);
      if (!s.is_ok()) return s.at_byte(record_byte);
    }
  }
  if (e.kind == kVertex) {
    Status s = body.mesh->add_vertex(v, r);
    if (!s.is_ok()) return s.at_byte(record_byte);
  }
  return Status::ok();
}

// The bytes of record r of element e when all of them are in the buffer (its lists' counts
// read there), so it can be decoded in place; 0 when they are not, or a count is negative
// (BinaryIn then reads it, and reports that).
size_t whole_record_bytes(const Header& h, const Reader& in, bool big, const Element& e) {
  const uint8_t* p = in.buf + in.pos;
  const size_t available = in.available();
  size_t size = 0;
  for (uint32_t pi = e.first; pi < e.first + e.properties; ++pi) {
    const Property& prop = h.properties[pi];
    if (prop.count_type == kNone) {
      size += kTypeBytes[prop.type];
      continue;
    }
    if (available - (size < available ? size : available) < kTypeBytes[prop.count_type]) return 0;
    int64_t n = 0;
    double d = 0;
    decode_value(p + size, prop.count_type, big, &n, &d);
    if (n < 0) return 0;
    // (A count is below 2^32 and an item at most 8 bytes: no overflow.)
    size += kTypeBytes[prop.count_type] + static_cast<size_t>(n) * kTypeBytes[prop.type];
  }
  return size <= available ? size : 0;
}

// The face element of the usual layout, a list of 4-byte indices and nothing else: its
// triangles (lists of 3) from record *r on, while they lie whole in the buffer and their
// indices are in range, up to record `end`; *r is left at the first record not read (a
// polygon, a bad count or index, the buffer's end), which the general path then reads, errors
// included. The same triangles and errors as corner().
Status triangle_run(Body& body, Reader& in, bool big, const Property& list, uint64_t* r,
                    uint64_t end) {
  const size_t count_bytes = kTypeBytes[list.count_type], bytes = count_bytes + 12;
  const bool is_signed = list.type == kInt32;
  for (; *r < end && in.available() >= bytes; ++*r) {
    const uint8_t* q = in.buf + in.pos;
    int64_t n = 0;
    double d = 0;
    decode_value(q, list.count_type, big, &n, &d);
    const uint32_t i0 = static_cast<uint32_t>(load_bits<4>(q + count_bytes, big));
    const uint32_t i1 = static_cast<uint32_t>(load_bits<4>(q + count_bytes + 4, big));
    const uint32_t i2 = static_cast<uint32_t>(load_bits<4>(q + count_bytes + 8, big));
    const uint32_t sign = is_signed ? 0x80000000u : 0u;  // a negative int32
    const uint64_t top = body.vertex_count;
    if (n != 3 || ((i0 | i1 | i2) & sign) != 0 || i0 >= top || i1 >= top || i2 >= top) break;
    const uint64_t record_byte = in.offset();
    in.pos += bytes;
    Status s = body.mesh->add_triangle(i0, i1, i2, *r);
    if (!s.is_ok()) return s.at_byte(record_byte);
  }
  return Status::ok();
}

// The vertex element of the usual layout, scalars only with x, y and z float32: where each
// coordinate lies in its record, and the record's size; size 0 for any other element.
struct VertexLayout {
  size_t at[3] = {0, 0, 0};
  size_t size = 0;
};

VertexLayout vertex_layout(const Header& h, const Element& e) {
  VertexLayout l;
  if (e.kind != kVertex) return l;
  size_t size = 0;
  for (uint32_t pi = e.first; pi < e.first + e.properties; ++pi) {
    const Property& p = h.properties[pi];
    if (p.count_type != kNone) return l;
    if (p.role != kSkip) {
      if (p.type != kFloat32) return l;
      l.at[p.role - kX] = size;
    }
    size += kTypeBytes[p.type];
  }
  l.size = size;
  return l;
}

// The vertices from record *r on while they lie whole in the buffer, up to record `end`, as
// the general path reads them (the same values, checks and errors); *r is left at the first
// record not read.
Status vertex_run(Body& body, Reader& in, bool big, const VertexLayout& l, uint64_t* r,
                  uint64_t end) {
  for (; *r < end && in.available() >= l.size; ++*r) {
    const uint8_t* q = in.buf + in.pos;
    const uint64_t record_byte = in.offset();
    in.pos += l.size;
    Vec3 v;
    for (int a = 0; a < 3; ++a) {
      const uint32_t bits = static_cast<uint32_t>(load_bits<4>(q + l.at[a], big));
      float f;
      std::memcpy(&f, &bits, 4);
      v[a] = body.coordinate(static_cast<double>(f));
    }
    Status s = body.mesh->add_vertex(v, *r);
    if (!s.is_ok()) return s.at_byte(record_byte);
  }
  return Status::ok();
}

Status read_binary_body(Body& body, Reader& in) {
  const Header& h = *body.header;
  BinaryIn b;
  b.in = &in;
  b.big = h.format == MeshFormat::kPlyBinaryBigEndian;
  for (uint32_t ei = 0; ei < h.element_count; ++ei) {
    const Element& e = h.elements[ei];
    // Records of no properties take no bytes: nothing to read, however many are declared (an
    // element of 10^12 of them kept a fuzzed file's read looping for minutes).
    if (e.properties == 0) continue;
    const Property& first = h.properties[e.first];
    const bool triangles = e.properties == 1 && first.role == kIndices &&
                           first.count_type != kNone &&
                           (first.type == kInt32 || first.type == kUInt32);
    const VertexLayout vertices = vertex_layout(h, e);
    for (uint64_t r = 0; r < e.count; ++r) {
      if ((r & 0xffff) == 0)
        SPLINTCORE_RETURN_IF_ERROR(
            report_progress(*body.ctx, "read", in.offset(), in.source->size));
      // The usual layouts in runs up to the next progress report; what they leave, below.
      if (triangles || vertices.size > 0) {
        const uint64_t end = (r | 0xffff) + 1 < e.count ? (r | 0xffff) + 1 : e.count;
        SPLINTCORE_RETURN_IF_ERROR(triangles ? triangle_run(body, in, b.big, first, &r, end)
                                             : vertex_run(body, in, b.big, vertices, &r, end));
        if (r == end) {
          --r;  // (the loop's ++r moves on to `end`)
          continue;
        }
      }
      // Most records lie whole in the buffer: decoded there; the one across its end, value by
      // value.
      const uint64_t record_byte = in.offset();
      const size_t bytes = whole_record_bytes(h, in, b.big, e);
      if (bytes > 0) {
        InPlace values{in.buf + in.pos, b.big};
        in.pos += bytes;
        SPLINTCORE_RETURN_IF_ERROR(binary_record(body, values, e, r, record_byte));
      } else {
        SPLINTCORE_RETURN_IF_ERROR(binary_record(body, b, e, r, record_byte));
      }
    }
  }
  SPLINTCORE_RETURN_IF_ERROR(in.fill(1));
  if (in.available() > 0) {
    return make_error(StatusCode::kParseError, "binary PLY has data after its last element")
        .at_byte(in.offset());
  }
  return Status::ok();
}

// ---------------------------------------------------------------------------------------------
// ASCII records: one per line.

Status ascii_value(const LineReader& lines, Tokens& t, uint8_t type, bool as_float, int64_t* i,
                   double* d, const Element& e, uint64_t record) {
  if (!t.next()) {
    Status s =
        make_error(StatusCode::kParseError, "too few values on the line of ", e.name, " ", record);
    return s.at_line(lines.number, t.column).at_index(record);
  }
  const char* first = t.token;
  const char* last = t.token + t.token_length;
  if (is_integer_type(type)) {
    static const int64_t kLo[] = {0, -128, 0, -32768, 0, -2147483647 - 1, 0};
    static const int64_t kHi[] = {0, 127, 255, 32767, 65535, 2147483647, 4294967295};
    if (!meshio::parse_integer(first, last, i) || *i < kLo[type] || *i > kHi[type]) {
      return token_error(StatusCode::kParseError, lines, t,
                         "expected an integer of the declared type")
          .at_index(record);
    }
    *d = static_cast<double>(*i);
    return Status::ok();
  }
  const StatusCode code = meshio::parse_real(first, last, as_float, d);
  if (code == StatusCode::kNonFinite) {
    return token_error(code, lines, t, "non-finite number (NaN or infinity)").at_index(record);
  }
  if (code != StatusCode::kOk) {
    return token_error(code, lines, t, "expected a number").at_index(record);
  }
  return Status::ok();
}

Status read_ascii_body(Body& body, LineReader& lines) {
  const Header& h = *body.header;
  bool got = false;
  for (uint32_t ei = 0; ei < h.element_count; ++ei) {
    const Element& e = h.elements[ei];
    for (uint64_t r = 0; r < e.count; ++r) {
      if ((r & 0xffff) == 0) {
        SPLINTCORE_RETURN_IF_ERROR(
            report_progress(*body.ctx, "read", lines.in->offset(), lines.in->source->size));
      }
      // The record's line (blank lines are skipped).
      for (;;) {
        SPLINTCORE_RETURN_IF_ERROR(lines.next(&got));
        if (!got) {
          return make_error(StatusCode::kTruncated, "ASCII PLY ends before ", e.name, " ", r,
                            " of ", e.count)
              .at_line(lines.number + 1, 1)
              .at_byte(lines.in->offset())
              .at_index(r);
        }
        Tokens probe(lines.line, lines.length);
        if (probe.next()) break;
      }
      Tokens t(lines.line, lines.length);
      Vec3 v;
      for (uint32_t pi = e.first; pi < e.first + e.properties; ++pi) {
        const Property& p = h.properties[pi];
        int64_t i = 0;
        double d = 0;
        if (p.count_type == kNone) {
          if (p.role == kSkip) {
            if (!t.next()) {
              return make_error(StatusCode::kParseError, "too few values on the line of ", e.name,
                                " ", r)
                  .at_line(lines.number, t.column)
                  .at_index(r);
            }
          } else {
            const bool as_float = body.options->round_to_float32 || p.type == kFloat32;
            SPLINTCORE_RETURN_IF_ERROR(ascii_value(lines, t, p.type, as_float, &i, &d, e, r));
            v[p.role - kX] = body.coordinate(d);
          }
          continue;
        }
        int64_t n = 0;
        SPLINTCORE_RETURN_IF_ERROR(ascii_value(lines, t, p.count_type, false, &n, &d, e, r));
        if (p.role != kIndices) {
          for (int64_t k = 0; k < n; ++k) {
            if (!t.next()) {
              return make_error(StatusCode::kParseError, "list of ", n,
                                " items has fewer on the line of ", e.name, " ", r)
                  .at_line(lines.number, t.column)
                  .at_index(r);
            }
          }
          continue;
        }
        if (n < 3)
          return face_too_small(r, static_cast<uint64_t>(n)).at_line(lines.number, t.column);
        Fan fan;
        for (int64_t k = 0; k < n; ++k) {
          SPLINTCORE_RETURN_IF_ERROR(ascii_value(lines, t, p.type, false, &i, &d, e, r));
          Status s = body.corner(&fan, i, r);
          if (!s.is_ok()) return s.at_line(lines.number, t.column);
        }
      }
      if (t.next()) {
        return token_error(StatusCode::kParseError, lines, t,
                           "more values than the element declares")
            .at_index(r);
      }
      if (e.kind == kVertex) {
        Status s = body.mesh->add_vertex(v, r);
        if (!s.is_ok()) return s.at_line(lines.number, 1);
      }
    }
  }
  for (;;) {
    SPLINTCORE_RETURN_IF_ERROR(lines.next(&got));
    if (!got) break;
    Tokens t(lines.line, lines.length);
    if (t.next()) {
      return token_error(StatusCode::kParseError, lines, t,
                         "ASCII PLY has data after its last element");
    }
  }
  return Status::ok();
}

// The element counts against the limits and, when the source knows its size, against the
// fewest bytes their records can take: checked before anything is reserved.
Status check_counts(const Header& h, const ByteSource& source, const MeshReadOptions& options,
                    uint64_t header_bytes) {
  const uint64_t max_vertices =
      options.max_vertices < 0xffffffffu ? options.max_vertices : 0xffffffffu;
  const uint64_t vertices = h.elements[h.vertex].count;
  const uint64_t faces = h.face >= 0 ? h.elements[h.face].count : 0;
  if (vertices > max_vertices) {
    return make_error(StatusCode::kLimitExceeded, "PLY declares ", vertices,
                      " vertices, over the limit of ", max_vertices)
        .at_byte(header_bytes);
  }
  if (faces > options.max_triangles) {
    return make_error(StatusCode::kLimitExceeded, "PLY declares ", faces,
                      " faces, over the limit of ", options.max_triangles, " triangles")
        .at_byte(header_bytes);
  }
  const bool binary = h.format != MeshFormat::kPlyAscii;
  uint64_t least = 0;
  bool overflow = false;
  for (uint32_t ei = 0; ei < h.element_count; ++ei) {
    uint64_t bytes = 0;
    overflow = overflow || !checked_mul(h.elements[ei].count,
                                        min_record_bytes(h, h.elements[ei], binary), &bytes);
    overflow = overflow || !checked_add(least, bytes, &least);
  }
  const uint64_t size = source.size;
  if (overflow || (size != kUnknownSize && (size < header_bytes || least > size - header_bytes))) {
    Status e = make_error(StatusCode::kTruncated, "PLY header declares elements needing at least ");
    if (overflow) {
      e.append("2^64");
    } else {
      e.append_u64(least);
    }
    e.append(" bytes of data");
    if (size != kUnknownSize) {
      e.append(" but ");
      e.append_u64(size >= header_bytes ? size - header_bytes : 0);
      e.append(" follow the header");
    }
    return e.at_byte(size != kUnknownSize ? size : header_bytes);
  }
  return Status::ok();
}

Status read_ply_located(const Context& ctx, const ByteSource& source,
                        const MeshReadOptions& options, Mesh* out, MeshReadInfo* info) {
  Arena& arena = *ctx.arena;
  ArenaScope scope(arena);  // on an error the arena is as it was
  Reader in;
  LineReader lines;
  SPLINTCORE_RETURN_IF_ERROR(open_lines(arena, source, options, &in, &lines));
  Header h;
  SPLINTCORE_RETURN_IF_ERROR(parse_header(lines, &h));
  info->format = h.format;
  const uint64_t header_bytes = in.offset();
  SPLINTCORE_RETURN_IF_ERROR(check_counts(h, source, options, header_bytes));
  const Element& ve = h.elements[h.vertex];
  const uint64_t faces = h.face >= 0 ? h.elements[h.face].count : 0;
  MeshBuilder builder(ctx, options);
  if (source.size != kUnknownSize) SPLINTCORE_RETURN_IF_ERROR(builder.reserve(ve.count, faces));
  Body body;
  body.ctx = &ctx;
  body.options = &options;
  body.header = &h;
  body.mesh = &builder;
  body.vertex_count = ve.count;
  const bool binary = h.format != MeshFormat::kPlyAscii;
  SPLINTCORE_RETURN_IF_ERROR(binary ? read_binary_body(body, in) : read_ascii_body(body, lines));
  info->vertices = builder.mesh.vertices.size();
  info->faces = faces;
  info->triangles = builder.mesh.triangles.size();
  info->bytes = in.offset();
  SPLINTCORE_RETURN_IF_ERROR(builder.finish(scope.start(), out));
  scope.commit();
  return Status::ok();
}

}  // namespace

Status read_ply(const Context& ctx, const ByteSource& source, const MeshReadOptions& options,
                Mesh* out, MeshReadInfo* info) {
  return meshio::read_text_mesh(ctx, source, options, out, info, "read_ply", read_ply_located);
}

}  // namespace splintcore
