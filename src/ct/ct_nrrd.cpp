// NRRD reader: "NRRD: Nearly Raw Raster Data", file format definition (teem project,
// http://teem.sourceforge.net/nrrd/format.html), magics NRRD0001 to NRRD0005. Only 3-D scalar
// volumes with raw or gzip encoding (the gzip stream inflated as it is read, RFC 1952, through
// src/compress); the header is parsed line by line in a fixed window; voxel data goes through
// read_text_volume() (ct_common.h).
#include "ct/ct_common.h"

namespace splintcore {

using namespace ct_detail;

namespace {

constexpr TypeName kTypes[] = {
    {"signed char", 1, true, false},
    {"int8", 1, true, false},
    {"int8_t", 1, true, false},
    {"uchar", 1, false, false},
    {"unsigned char", 1, false, false},
    {"uint8", 1, false, false},
    {"uint8_t", 1, false, false},
    {"short", 2, true, false},
    {"short int", 2, true, false},
    {"signed short", 2, true, false},
    {"signed short int", 2, true, false},
    {"int16", 2, true, false},
    {"int16_t", 2, true, false},
    {"ushort", 2, false, false},
    {"unsigned short", 2, false, false},
    {"unsigned short int", 2, false, false},
    {"uint16", 2, false, false},
    {"uint16_t", 2, false, false},
    {"int", 4, true, false},
    {"signed int", 4, true, false},
    {"int32", 4, true, false},
    {"int32_t", 4, true, false},
    {"uint", 4, false, false},
    {"unsigned int", 4, false, false},
    {"uint32", 4, false, false},
    {"uint32_t", 4, false, false},
    {"float", 4, true, true},
    {"double", 8, true, true},
};

bool starts_with(const char* text, size_t length, const char* prefix) {
  const size_t n = std::strlen(prefix);
  return length >= n && std::memcmp(text, prefix, n) == 0;
}

// "(a,b,c)" groups: exactly `groups` of 3 numbers each.
bool parse_vectors(const char* text, size_t length, Vec3* out, size_t groups) {
  size_t i = 0, found = 0;
  for (;;) {
    while (i < length && (text[i] == ' ' || text[i] == '\t')) ++i;
    if (i == length) break;
    if (text[i] != '(' || found == groups) return false;
    size_t j = i + 1;
    while (j < length && text[j] != ')') ++j;
    if (j == length) return false;
    double v[3];
    size_t count = 0;
    if (!parse_doubles(text + i + 1, j - i - 1, ',', v, 3, &count) || count != 3) return false;
    out[found++] = Vec3{v[0], v[1], v[2]};
    i = j + 1;
  }
  return found == groups;
}

void copy_text(char* out, size_t cap, const char* text, size_t length) {
  if (length >= cap) length = cap - 1;
  std::memcpy(out, text, length);
  out[length] = '\0';
}

// The header, read a line at a time in a fixed window: the magic line, then "field: value"
// lines up to the blank line before the data (or the end of a detached header), each taken
// by its own method. Errors name the line.
struct NrrdHeader : HeaderLines {
  // What the fields said.
  bool have_type = false, have_dimension = false, have_sizes = false, have_encoding = false;
  bool gzip = false;  // encoding gzip / gz
  bool have_endian = false, have_directions = false;
  VoxelFormat format;
  uint64_t sizes[3] = {0, 0, 0};
  Vec3 directions[3];
  double spacings[3] = {1, 1, 1};
  Vec3 origin{0, 0, 0};
  int64_t byte_skip = 0, line_skip = 0;
  uint64_t geometry_line = kNoPosition;
  char data_file[kLineCapacity] = {};
  CtInfo found;

  NrrdHeader(const ByteSource& s, const CtReadOptions& options) : HeaderLines(s, options) {
    found.format = CtFormat::kNrrd;
  }

  // The first line: NRRD0001 to NRRD0005.
  Status read_magic() {
    size_t len = 0;
    bool too_long = false, got = false;
    SPLINTCORE_RETURN_IF_ERROR(
        in_source(reader.read_line(line, &len, &too_long, &got, &budget), source));
    line_no = 1;
    if (!got || len != 8 || !starts_with(line, len, "NRRD000") || line[7] < '1' || line[7] > '5') {
      return fail(make_error(StatusCode::kParseError,
                             "not a NRRD file: the first line must be NRRD0001 to NRRD0005"));
    }
    return Status::ok();
  }

  // The field lines, up to the blank line before the data.
  Status read_fields() {
    for (;;) {
      size_t len = 0;
      bool too_long = false, got = false;
      SPLINTCORE_RETURN_IF_ERROR(next_line(&len, &too_long, &got));
      if (!got) {
        if (data_file[0] != '\0') return Status::ok();  // a detached header may end at its end
        return fail(
            make_error(StatusCode::kTruncated, "header ends without the blank line before the data")
                .at_byte(reader.offset()));
      }
      if (len == 0) return Status::ok();  // the blank line (a too long line is never empty)
      if (line[0] == '#') continue;
      size_t colon = 0;
      while (colon < len && line[colon] != ':') ++colon;
      if (colon + 1 < len && line[colon + 1] == '=') continue;  // key:=value pair
      if (colon == len) {
        return fail(make_error(StatusCode::kParseError, "expected \"field: value\""));
      }
      if (too_long) return line_too_long();
      SPLINTCORE_RETURN_IF_ERROR(take(KeyValue::split(line, len, colon)));
    }
  }

  // One field, by name. Other fields (kinds, centerings, units, content, measurement frame,
  // ...) are ignored.
  Status take(const KeyValue& f) {
    using Take = Status (NrrdHeader::*)(const KeyValue&);
    static constexpr struct {
      const char* name;
      Take take;
    } kFields[] = {
        {"type", &NrrdHeader::take_type},
        {"dimension", &NrrdHeader::take_dimension},
        {"sizes", &NrrdHeader::take_sizes},
        {"encoding", &NrrdHeader::take_encoding},
        {"endian", &NrrdHeader::take_endian},
        {"space directions", &NrrdHeader::take_directions},
        {"spacings", &NrrdHeader::take_spacings},
        {"space origin", &NrrdHeader::take_origin},
        {"space", &NrrdHeader::take_space},
        {"space dimension", &NrrdHeader::take_space_dimension},
        {"data file", &NrrdHeader::take_data_file},
        {"datafile", &NrrdHeader::take_data_file},
        {"byte skip", &NrrdHeader::take_byte_skip},
        {"byteskip", &NrrdHeader::take_byte_skip},
        {"line skip", &NrrdHeader::take_line_skip},
        {"lineskip", &NrrdHeader::take_line_skip},
    };
    for (const auto& field : kFields) {
      if (f.is(field.name)) return (this->*field.take)(f);
    }
    return Status::ok();
  }

  Status take_type(const KeyValue& f) {
    for (const TypeName& t : kTypes) {
      if (f.value_is(t.name)) {
        format.bytes = t.bytes;
        format.is_signed = t.is_signed;
        format.is_float = t.is_float;
        have_type = true;
        return Status::ok();
      }
    }
    return fail(make_error(StatusCode::kUnsupported, "voxel type \"")
                    .append(f.value, f.value_length)
                    .append("\" is not supported (8, 16 and 32-bit integers, float, double)"));
  }

  Status take_dimension(const KeyValue& f) {
    int64_t d = 0;
    if (!parse_i64(f.value, f.value_length, &d)) return bad(f, "dimension");
    if (d != 3) {
      return fail(make_error(StatusCode::kUnsupported, "dimension ", d,
                             ": only 3-D scalar volumes are supported"));
    }
    have_dimension = true;
    return Status::ok();
  }

  Status take_sizes(const KeyValue& f) {
    double v[4];
    size_t count = 0;
    if (!parse_doubles(f.value, f.value_length, '\0', v, 4, &count) || count != 3) {
      return fail(make_error(StatusCode::kParseError, "sizes: expected 3 integers, got \"")
                      .append(f.value, f.value_length)
                      .append("\""));
    }
    for (int a = 0; a < 3; ++a) {
      if (!(v[a] >= 1 && v[a] <= 4294967295.0) ||
          v[a] != static_cast<double>(static_cast<uint64_t>(v[a]))) {
        return bad(f, "sizes");
      }
      sizes[a] = static_cast<uint64_t>(v[a]);
    }
    have_sizes = true;
    return Status::ok();
  }

  Status take_encoding(const KeyValue& f) {
    if (f.value_is("raw") || f.value_is("gzip") || f.value_is("gz")) {
      have_encoding = true;
      gzip = !f.value_is("raw");
      return Status::ok();
    }
    if (f.value_is("bzip2") || f.value_is("bz2") || f.value_is("ascii") || f.value_is("txt") ||
        f.value_is("text") || f.value_is("hex") || f.value_is("zstd")) {
      return fail(make_error(StatusCode::kUnsupported, "encoding \"")
                      .append(f.value, f.value_length)
                      .append("\" is not supported (only raw and gzip)"));
    }
    return bad(f, "encoding");
  }

  Status take_endian(const KeyValue& f) {
    if (f.value_is("little")) {
      format.big_endian = false;
    } else if (f.value_is("big")) {
      format.big_endian = true;
    } else {
      return bad(f, "endian (little or big)");
    }
    have_endian = true;
    return Status::ok();
  }

  Status take_directions(const KeyValue& f) {
    if (!parse_vectors(f.value, f.value_length, directions, 3)) {
      return fail(make_error(StatusCode::kParseError,
                             "space directions: expected three vectors (x,y,z), got \"")
                      .append(f.value, f.value_length)
                      .append("\" (\"none\" axes are not supported)"));
    }
    have_directions = true;
    geometry_line = line_no;
    return Status::ok();
  }

  Status take_spacings(const KeyValue& f) {
    size_t count = 0;
    if (!parse_doubles(f.value, f.value_length, '\0', spacings, 3, &count) || count != 3) {
      return bad(f, "spacings (three numbers)");
    }
    if (!have_directions) geometry_line = line_no;
    return Status::ok();
  }

  Status take_origin(const KeyValue& f) {
    Vec3 o[1];
    if (!parse_vectors(f.value, f.value_length, o, 1)) return bad(f, "space origin (x,y,z)");
    origin = o[0];
    return Status::ok();
  }

  Status take_space(const KeyValue& f) {
    copy_text(found.space, sizeof(found.space), f.value, f.value_length);
    return Status::ok();
  }

  Status take_space_dimension(const KeyValue& f) {
    int64_t d = 0;
    if (!parse_i64(f.value, f.value_length, &d)) return bad(f, "space dimension");
    if (d != 3) {
      return fail(
          make_error(StatusCode::kUnsupported, "space dimension ", d, ": only 3 is supported"));
    }
    return Status::ok();
  }

  Status take_data_file(const KeyValue& f) {
    if (starts_with(f.value, f.value_length, "LIST") ||
        std::memchr(f.value, '%', f.value_length) != nullptr) {
      return fail(make_error(StatusCode::kUnsupported, "data file \"")
                      .append(f.value, f.value_length)
                      .append("\": LIST and pattern forms are not supported (one file only)"));
    }
    if (f.value_length == 0) return bad(f, "data file");
    copy_text(data_file, sizeof(data_file), f.value, f.value_length);
    return Status::ok();
  }

  Status take_byte_skip(const KeyValue& f) {
    if (!parse_i64(f.value, f.value_length, &byte_skip) || byte_skip < -1) {
      return bad(f, "byte skip");
    }
    return Status::ok();
  }

  Status take_line_skip(const KeyValue& f) {
    if (!parse_i64(f.value, f.value_length, &line_skip) || line_skip < 0) {
      return bad(f, "line skip");
    }
    return Status::ok();
  }

  // The fields every volume needs (errors name the line that ended the header).
  Status check_required() const {
    auto missing = [&](const char* what) {
      return fail(make_error(StatusCode::kParseError, "missing field \"", what, "\""));
    };
    if (!have_type) return missing("type");
    if (!have_dimension) return missing("dimension");
    if (!have_sizes) return missing("sizes");
    if (!have_encoding) return missing("encoding");
    if (format.bytes > 1 && !have_endian) return missing("endian");
    return Status::ok();
  }

  // The volume the fields describe. Space directions give the spacing (their lengths) and the
  // axes (normalised); without them, the spacings (default 1 mm) and identity axes.
  TextVolume volume() const {
    TextVolume v;
    v.spacing = Vec3{spacings[0], spacings[1], spacings[2]};
    if (have_directions) {
      for (int a = 0; a < 3; ++a) {
        // parse_double takes finite numbers only, so the directions are finite.
        v.spacing[a] = length(directions[a]);
        if (v.spacing[a] > 0 && is_finite(v.spacing[a])) {
          v.axes[a] = Vec3{directions[a].x / v.spacing[a], directions[a].y / v.spacing[a],
                           directions[a].z / v.spacing[a]};
        }
      }
    }
    v.origin = origin;  // finite: parse_double takes finite numbers only
    v.geometry_line = geometry_line;
    v.data.format = format;
    v.data.nx = static_cast<uint32_t>(sizes[0]);  // each checked to be 1..2^32-1
    v.data.ny = static_cast<uint32_t>(sizes[1]);
    v.data.nz = static_cast<uint32_t>(sizes[2]);
    v.data.data_file = data_file[0] != '\0' ? data_file : nullptr;
    v.data.line_skip = static_cast<uint64_t>(line_skip);
    v.data.byte_skip = byte_skip;
    v.data.gzip = gzip;
    return v;
  }
};

}  // namespace

Status read_nrrd(const Context& ctx, const ByteSource& source, const CtFileOpener* opener,
                 const CtReadOptions& options, CtVolume* out, CtInfo* info) {
  NrrdHeader header(source, options);
  SPLINTCORE_RETURN_IF_ERROR(header.read_magic());
  SPLINTCORE_RETURN_IF_ERROR(header.read_fields());
  SPLINTCORE_RETURN_IF_ERROR(header.check_required());
  return read_text_volume(ctx, header.reader, source, opener, options, header.volume(),
                          header.found, out, info);
}

}  // namespace splintcore
