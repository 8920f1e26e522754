// Wavefront OBJ reader (geometry only), streaming from a ByteSource a line at a time.
//
// Format: "Object Files (.obj)", Appendix B1 of the Wavefront Advanced Visualizer manual
// (as kept at paulbourke.net/dataformats/obj): one statement per line, '#' comments; "v x y z
// [w]" geometric vertices; "f v1 v2 v3 ..." faces whose corners are "v", "v/vt", "v//vn" or
// "v/vt/vn", 1-based, a negative number counting back from the last vertex defined. Only
// vertices and faces are kept; every other statement is skipped (io.h lists them).
// Decisions for input in the wild: after x y z up to three more numbers are taken and ignored
// (a rational w, which scanners never use, or the per-vertex r g b that MeshLab and ZBrush
// write); a corner must name a vertex defined before it (what the format's relative indices
// assume, and what lets a face be checked when it is read); '\' line continuation is not
// supported (a parse error where it matters). Faces are fan-triangulated (io.h).
#include "mesh_text.h"

namespace splintcore {

namespace {

using meshio::LineReader;
using meshio::MeshBuilder;
using meshio::Reader;
using meshio::token_error;
using meshio::Tokens;

// One corner "v[/vt[/vn]]" or "v//vn": the vertex number, the others checked to be integers.
bool parse_corner(const char* first, const char* last, int64_t* vertex) {
  const char* slash = first;
  while (slash < last && *slash != '/') ++slash;
  if (!meshio::parse_integer(first, slash, vertex)) return false;
  int parts = 1;
  const char* p = slash;
  while (p < last) {
    ++p;  // past '/'
    const char* q = p;
    while (q < last && *q != '/') ++q;
    ++parts;
    if (parts > 3) return false;
    int64_t other = 0;
    // vt may be empty only as the middle part of v//vn; vn never.
    if (q == p) {
      if (!(parts == 2 && q < last)) return false;
    } else if (!meshio::parse_integer(p, q, &other) || other == 0) {
      return false;
    }
    p = q;
  }
  return true;
}

// The statements this reader keeps, 'v' and 'f', each read from its line's tokens into the
// mesh. Errors name the line (and the column of the token at fault) and the vertex or face.
struct ObjStatements {
  const LineReader& lines;
  const MeshReadOptions& options;
  MeshBuilder& builder;
  uint64_t max_vertices = 0;
  uint64_t faces = 0;  // read so far

  ObjStatements(const LineReader& l, const MeshReadOptions& o, MeshBuilder& b)
      : lines(l), options(o), builder(b) {
    max_vertices = options.max_vertices < 0xffffffffu ? options.max_vertices : 0xffffffffu;
  }

  // "v x y z" and up to three more numbers, which are ignored (t is at "v").
  Status vertex(Tokens& t) {
    const uint64_t index = builder.mesh.vertices.size();
    if (index >= max_vertices) {
      return make_error(StatusCode::kLimitExceeded, "OBJ has more than ", max_vertices,
                        " vertices (the limit)")
          .at_line(lines.number, 1)
          .at_index(index);
    }
    double xyz[6] = {0, 0, 0, 0, 0, 0};
    int n = 0;
    while (t.next() && t.token[0] != '#') {
      if (n == 6) {
        return token_error(StatusCode::kParseError, lines, t, "more than 6 numbers on a 'v' line")
            .at_index(index);
      }
      const StatusCode code =
          meshio::parse_real(t.token, t.token + t.token_length, options.round_to_float32, &xyz[n]);
      if (code == StatusCode::kNonFinite && n < 3) {
        return token_error(code, lines, t, "vertex has a non-finite coordinate (NaN or infinity)")
            .at_index(index);
      }
      if (code != StatusCode::kOk && (n < 3 || code != StatusCode::kNonFinite)) {
        return token_error(StatusCode::kParseError, lines, t, "expected a number").at_index(index);
      }
      ++n;
    }
    if (n < 3) {
      return token_error(StatusCode::kParseError, lines, t, "a 'v' line needs x, y and z")
          .at_index(index);
    }
    Status s = builder.add_vertex(Vec3(xyz[0], xyz[1], xyz[2]), index);
    if (!s.is_ok()) s.at_line(lines.number, 1);
    return s;
  }

  // "f" and at least three corners, fan-triangulated (t is at "f").
  Status face(Tokens& t) {
    const uint64_t defined = builder.mesh.vertices.size();
    uint32_t first = 0, previous = 0;
    uint64_t corners = 0;
    while (t.next() && t.token[0] != '#') {
      int64_t v = 0;
      if (!parse_corner(t.token, t.token + t.token_length, &v)) {
        return token_error(StatusCode::kParseError, lines, t,
                           "expected a face corner v, v/vt, v//vn or v/vt/vn")
            .at_index(faces);
      }
      // 1-based, or counting back from the last vertex defined (-1 is the last).
      const int64_t zero_based = v > 0 ? v - 1 : static_cast<int64_t>(defined) + v;
      if (v == 0 || zero_based < 0 || static_cast<uint64_t>(zero_based) >= defined) {
        Status e = make_error(StatusCode::kParseError, "face ", faces, " names vertex ", v, " but ",
                              defined, " vertices are defined before it");
        return e.at_line(lines.number, t.column).at_index(faces);
      }
      const uint32_t id = static_cast<uint32_t>(zero_based);
      if (corners == 0) {
        first = id;
      } else if (corners >= 2) {
        Status s = builder.add_triangle(first, previous, id, faces);
        if (!s.is_ok()) return s.at_line(lines.number, t.column);
      }
      previous = id;
      ++corners;
    }
    if (corners < 3) {
      return make_error(StatusCode::kParseError, "face ", faces, " has ", corners,
                        " vertices; a polygon needs at least 3")
          .at_line(lines.number, 1)
          .at_index(faces);
    }
    ++faces;
    return Status::ok();
  }
};

Status read_obj_located(const Context& ctx, const ByteSource& source,
                        const MeshReadOptions& options, Mesh* out, MeshReadInfo* info) {
  Arena& arena = *ctx.arena;
  ArenaScope scope(arena);  // on an error the arena is as it was
  Reader in;
  LineReader lines;
  SPLINTCORE_RETURN_IF_ERROR(open_lines(arena, source, options, &in, &lines));
  info->format = MeshFormat::kObj;
  MeshBuilder builder(ctx, options);
  ObjStatements obj(lines, options, builder);
  for (;;) {
    bool got = false;
    SPLINTCORE_RETURN_IF_ERROR(lines.next(&got));
    if (!got) break;
    if ((lines.number & 0xffff) == 0) {
      SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "read", in.offset(), source.size));
    }
    Tokens t(lines.line, lines.length);
    if (!t.next() || t.token[0] == '#') continue;
    if (t.is("v")) {
      SPLINTCORE_RETURN_IF_ERROR(obj.vertex(t));
    } else if (t.is("f")) {
      SPLINTCORE_RETURN_IF_ERROR(obj.face(t));
    }
    // Every other statement (vn vt vp g o s usemtl mtllib l p ...) is skipped.
  }
  info->vertices = builder.mesh.vertices.size();
  info->faces = obj.faces;
  info->triangles = builder.mesh.triangles.size();
  info->bytes = in.offset();
  SPLINTCORE_RETURN_IF_ERROR(builder.finish(scope.start(), out));
  scope.commit();
  return Status::ok();
}

}  // namespace

Status read_obj(const Context& ctx, const ByteSource& source, const MeshReadOptions& options,
                Mesh* out, MeshReadInfo* info) {
  return meshio::read_text_mesh(ctx, source, options, out, info, "read_obj", read_obj_located);
}

// ---------------------------------------------------------------------------------------------
// Format detection and the reader that dispatches on it.

const char* mesh_format_name(MeshFormat format) {
  switch (format) {
    case MeshFormat::kStlBinary: return "stl-binary";
    case MeshFormat::kStlAscii: return "stl-ascii";
    case MeshFormat::kPlyAscii: return "ply-ascii";
    case MeshFormat::kPlyBinaryLittleEndian: return "ply-binary-le";
    case MeshFormat::kPlyBinaryBigEndian: return "ply-binary-be";
    case MeshFormat::kObj: return "obj";
    default: return "unknown";
  }
}

namespace {

bool ends_with_ci(const char* name, const char* suffix) {
  const size_t n = std::strlen(name), m = std::strlen(suffix);
  if (n < m) return false;
  for (size_t i = 0; i < m; ++i) {
    char c = name[n - m + i];
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
    if (c != suffix[i]) return false;
  }
  return true;
}

bool is_text(const uint8_t* p, size_t n) {
  for (size_t k = 0; k < n; ++k) {
    const uint8_t c = p[k];
    if (!((c >= 0x20 && c != 0x7f) || c == '\t' || c == '\r' || c == '\n')) return false;
  }
  return true;
}

// The first statement's keyword is an OBJ one (after blank lines and '#' comments).
bool looks_obj(const uint8_t* p, size_t n) {
  if (!is_text(p, n)) return false;
  size_t i = 0;
  for (;;) {
    while (i < n && (p[i] == ' ' || p[i] == '\t' || p[i] == '\r' || p[i] == '\n')) ++i;
    if (i == n) return false;
    if (p[i] == '#') return true;
    size_t j = i;
    while (j < n && p[j] != ' ' && p[j] != '\t' && p[j] != '\r' && p[j] != '\n') ++j;
    if (j == n) return false;  // a keyword cut off by the peek window
    static const char* const kKeywords[] = {"v", "vn", "vt", "vp",     "f",
                                            "o", "g",  "s",  "usemtl", "mtllib"};
    for (const char* k : kKeywords) {
      if (std::strlen(k) == j - i && std::memcmp(p + i, k, j - i) == 0) return true;
    }
    return false;
  }
}

bool looks_stl_ascii(const uint8_t* p, size_t n) {
  size_t i = 0;
  while (i < n && (p[i] == ' ' || p[i] == '\t' || p[i] == '\r' || p[i] == '\n')) ++i;
  if (n - i < 5) return false;
  for (size_t k = 0; k < 5; ++k) {
    char c = static_cast<char>(p[i + k]);
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
    if (c != "solid"[k]) return false;
  }
  for (size_t k = 0; k < n; ++k) {
    const uint8_t c = p[k];
    if (!((c >= 0x20 && c <= 0x7e) || c == '\t' || c == '\r' || c == '\n')) return false;
  }
  return true;
}

}  // namespace

MeshFormat detect_mesh_format(const uint8_t* head, size_t size, const char* name) {
  if (size >= 4 && std::memcmp(head, "ply", 3) == 0 && (head[3] == '\n' || head[3] == '\r')) {
    return MeshFormat::kPlyAscii;  // the header says which encoding
  }
  if (looks_stl_ascii(head, size)) return MeshFormat::kStlAscii;
  if (looks_obj(head, size)) return MeshFormat::kObj;
  if (name != nullptr) {
    if (ends_with_ci(name, ".ply")) return MeshFormat::kPlyAscii;
    if (ends_with_ci(name, ".obj")) return MeshFormat::kObj;
  }
  return MeshFormat::kStlBinary;
}

Status read_mesh(const Context& ctx, const ByteSource& source, const MeshReadOptions& options,
                 Mesh* out, MeshReadInfo* info) {
  MeshReadInfo local;
  if (info == nullptr) info = &local;
  *info = MeshReadInfo{};
  if (source.read == nullptr) {
    return Status::error(StatusCode::kInvalidArgument, "read_mesh: byte source has no read()");
  }
  uint8_t head[1024];
  size_t got = 0;
  while (got < sizeof(head)) {
    const int64_t n = source.read(source.user, head + got, sizeof(head) - got);
    if (n < 0) {
      return meshio::located(make_error(StatusCode::kIoError, "read failed").at_byte(got), source);
    }
    if (static_cast<uint64_t>(n) > sizeof(head) - got) {
      return Status::error(StatusCode::kIoError, "byte source returned more than asked");
    }
    if (n == 0) break;
    got += static_cast<size_t>(n);
  }
  meshio::PeekSource peek;
  const ByteSource replay = peek.replay(source, head, got);
  const MeshFormat format = detect_mesh_format(head, got, source.name);
  if (format == MeshFormat::kPlyAscii) return read_ply(ctx, replay, options, out, info);
  if (format == MeshFormat::kObj) return read_obj(ctx, replay, options, out, info);
  StlReadOptions so;
  so.format = format == MeshFormat::kStlAscii ? StlFormat::kAscii : StlFormat::kBinary;
  so.max_triangles = options.max_triangles;
  so.max_abs_coordinate = options.max_abs_coordinate;
  so.chunk_bytes = options.chunk_bytes;
  so.keep = options.keep;
  StlInfo si;
  SPLINTCORE_RETURN_IF_ERROR(read_stl_mesh(ctx, replay, so, out, &si));
  info->format = format;
  info->vertices = out->vertices.size();
  info->faces = si.triangles;
  info->triangles = si.triangles;
  info->bytes = si.bytes;
  return Status::ok();
}

}  // namespace splintcore
