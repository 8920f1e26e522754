// NRRD reader: "NRRD: Nearly Raw Raster Data", file format definition (teem project,
// http://teem.sourceforge.net/nrrd/format.html), magics NRRD0001 to NRRD0005. Only 3-D scalar
// volumes with raw encoding; the header is parsed line by line in a fixed window; voxel data
// goes through read_raw_volume() (ct_common.h).
#include "ct/ct_common.h"

namespace splintcore {

using namespace ct_detail;

namespace {

struct TypeName {
  const char* name;
  uint8_t bytes;
  bool is_signed;
  bool is_float;
};
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

}  // namespace

Status read_nrrd(const Context& ctx, const ByteSource& source, const CtFileOpener* opener,
                 const CtReadOptions& options, CtVolume* out, CtInfo* info) {
  uint8_t window[kHeaderWindow];
  char line[kLineCapacity];
  char data_file[kLineCapacity] = {};
  Reader reader;
  reader.init(&source, window, sizeof(window));
  uint64_t budget = options.max_header_bytes;
  uint64_t line_no = 0;
  auto fail = [&](Status s) {
    s.at_line(line_no);
    return in_source(s, source);
  };

  size_t len = 0;
  bool too_long = false, got = false;
  SPLINTCORE_RETURN_IF_ERROR(
      in_source(reader.read_line(line, &len, &too_long, &got, &budget), source));
  line_no = 1;
  if (!got || len != 8 || !starts_with(line, len, "NRRD000") || line[7] < '1' || line[7] > '5') {
    return fail(make_error(StatusCode::kParseError,
                           "not a NRRD file: the first line must be NRRD0001 to NRRD0005"));
  }

  bool have_type = false, have_dimension = false, have_sizes = false, have_encoding = false;
  bool have_endian = false, have_directions = false, have_spacings = false;
  VoxelFormat format;
  uint64_t sizes[3] = {0, 0, 0};
  Vec3 directions[3];
  double spacings[3] = {1, 1, 1};
  Vec3 origin{0, 0, 0};
  int64_t byte_skip = 0, line_skip = 0;
  uint64_t geometry_line = kNoPosition;
  CtInfo found;
  found.format = CtFormat::kNrrd;

  for (;;) {
    Status s = reader.read_line(line, &len, &too_long, &got, &budget);
    ++line_no;
    if (!s.is_ok()) return fail(s);
    if (!got) {
      if (data_file[0] != '\0') break;  // a detached header may end at its end of file
      return fail(
          make_error(StatusCode::kTruncated, "header ends without the blank line before the data")
              .at_byte(reader.offset()));
    }
    if (len == 0) break;  // the blank line (a too long line is never empty)
    if (line[0] == '#') continue;
    size_t colon = 0;
    while (colon < len && line[colon] != ':') ++colon;
    if (colon + 1 < len && line[colon + 1] == '=') continue;  // key:=value pair
    if (colon == len) {
      return fail(make_error(StatusCode::kParseError, "expected \"field: value\""));
    }
    if (too_long) {
      return fail(make_error(StatusCode::kParseError, "line longer than ", kLineCapacity - 1,
                             " characters"));
    }
    const char* field = line;
    size_t field_len = colon;
    trim(&field, &field_len);
    const char* value = line + colon + 1;
    size_t value_len = len - colon - 1;
    trim(&value, &value_len);
    auto is = [&](const char* name) { return equal_nocase(field, field_len, name); };
    auto bad = [&](const char* what) {
      return fail(make_error(StatusCode::kParseError, "bad ", what, " \"")
                      .append(value, value_len)
                      .append("\""));
    };
    if (is("type")) {
      bool ok = false;
      for (const TypeName& t : kTypes) {
        if (equal_nocase(value, value_len, t.name)) {
          format.bytes = t.bytes;
          format.is_signed = t.is_signed;
          format.is_float = t.is_float;
          ok = true;
          break;
        }
      }
      if (!ok) {
        return fail(make_error(StatusCode::kUnsupported, "voxel type \"")
                        .append(value, value_len)
                        .append("\" is not supported (8, 16 and 32-bit integers, float, double)"));
      }
      have_type = true;
    } else if (is("dimension")) {
      int64_t d = 0;
      if (!parse_i64(value, value_len, &d)) return bad("dimension");
      if (d != 3) {
        return fail(make_error(StatusCode::kUnsupported, "dimension ", d,
                               ": only 3-D scalar volumes are supported"));
      }
      have_dimension = true;
    } else if (is("sizes")) {
      double v[4];
      size_t count = 0;
      if (!parse_doubles(value, value_len, '\0', v, 4, &count) || count != 3) {
        return fail(make_error(StatusCode::kParseError, "sizes: expected 3 integers, got \"")
                        .append(value, value_len)
                        .append("\""));
      }
      for (int a = 0; a < 3; ++a) {
        if (!(v[a] >= 1 && v[a] <= 4294967295.0) ||
            v[a] != static_cast<double>(static_cast<uint64_t>(v[a]))) {
          return bad("sizes");
        }
        sizes[a] = static_cast<uint64_t>(v[a]);
      }
      have_sizes = true;
    } else if (is("encoding")) {
      if (equal_nocase(value, value_len, "raw")) {
        have_encoding = true;
      } else if (equal_nocase(value, value_len, "gzip") || equal_nocase(value, value_len, "gz") ||
                 equal_nocase(value, value_len, "bzip2") || equal_nocase(value, value_len, "bz2") ||
                 equal_nocase(value, value_len, "ascii") || equal_nocase(value, value_len, "txt") ||
                 equal_nocase(value, value_len, "text") || equal_nocase(value, value_len, "hex") ||
                 equal_nocase(value, value_len, "zstd")) {
        return fail(make_error(StatusCode::kUnsupported, "encoding \"")
                        .append(value, value_len)
                        .append("\" is not supported (only raw)"));
      } else {
        return bad("encoding");
      }
    } else if (is("endian")) {
      if (equal_nocase(value, value_len, "little")) {
        format.big_endian = false;
      } else if (equal_nocase(value, value_len, "big")) {
        format.big_endian = true;
      } else {
        return bad("endian (little or big)");
      }
      have_endian = true;
    } else if (is("space directions")) {
      if (!parse_vectors(value, value_len, directions, 3)) {
        return fail(make_error(StatusCode::kParseError,
                               "space directions: expected three vectors (x,y,z), got \"")
                        .append(value, value_len)
                        .append("\" (\"none\" axes are not supported)"));
      }
      have_directions = true;
      geometry_line = line_no;
    } else if (is("spacings")) {
      size_t count = 0;
      if (!parse_doubles(value, value_len, '\0', spacings, 3, &count) || count != 3) {
        return bad("spacings (three numbers)");
      }
      have_spacings = true;
      if (!have_directions) geometry_line = line_no;
    } else if (is("space origin")) {
      Vec3 o[1];
      if (!parse_vectors(value, value_len, o, 1)) return bad("space origin (x,y,z)");
      origin = o[0];
    } else if (is("space")) {
      copy_text(found.space, sizeof(found.space), value, value_len);
    } else if (is("space dimension")) {
      int64_t d = 0;
      if (!parse_i64(value, value_len, &d)) return bad("space dimension");
      if (d != 3) {
        return fail(
            make_error(StatusCode::kUnsupported, "space dimension ", d, ": only 3 is supported"));
      }
    } else if (is("data file") || is("datafile")) {
      if (starts_with(value, value_len, "LIST") || std::memchr(value, '%', value_len) != nullptr) {
        return fail(make_error(StatusCode::kUnsupported, "data file \"")
                        .append(value, value_len)
                        .append("\": LIST and pattern forms are not supported (one file only)"));
      }
      if (value_len == 0) return bad("data file");
      copy_text(data_file, sizeof(data_file), value, value_len);
    } else if (is("byte skip") || is("byteskip")) {
      if (!parse_i64(value, value_len, &byte_skip) || byte_skip < -1) return bad("byte skip");
    } else if (is("line skip") || is("lineskip")) {
      if (!parse_i64(value, value_len, &line_skip) || line_skip < 0) return bad("line skip");
    }
    // Other fields (kinds, centerings, units, content, measurement frame, ...) are ignored.
  }

  auto missing = [&](const char* what) {
    return fail(make_error(StatusCode::kParseError, "missing field \"", what, "\""));
  };
  if (!have_type) return missing("type");
  if (!have_dimension) return missing("dimension");
  if (!have_sizes) return missing("sizes");
  if (!have_encoding) return missing("encoding");
  if (format.bytes > 1 && !have_endian) return missing("endian");

  Vec3 axes[3] = {Vec3{1, 0, 0}, Vec3{0, 1, 0}, Vec3{0, 0, 1}};
  Vec3 spacing{spacings[0], spacings[1], spacings[2]};
  if (have_directions) {
    for (int a = 0; a < 3; ++a) {
      // parse_double takes finite numbers only, so the directions are finite.
      spacing[a] = length(directions[a]);
      if (spacing[a] > 0 && is_finite(spacing[a])) {
        axes[a] = Vec3{directions[a].x / spacing[a], directions[a].y / spacing[a],
                       directions[a].z / spacing[a]};
      }
    }
  }
  (void)have_spacings;
  const char* names[3] = {"x", "y", "z"};
  for (int a = 0; a < 3; ++a) {
    Status sp = check_spacing(spacing[a], names[a], options);
    if (!sp.is_ok()) {
      line_no = geometry_line;
      return fail(sp);
    }
  }
  Status axes_ok = check_axes(&axes[0], &axes[1], &axes[2], options);
  if (!axes_ok.is_ok()) {
    line_no = geometry_line;
    return fail(axes_ok);
  }
  // The origin is finite: parse_double takes finite numbers only.

  RawData data;
  data.format = format;
  data.nx = static_cast<uint32_t>(sizes[0]);  // each checked to be 1..2^32-1 above
  data.ny = static_cast<uint32_t>(sizes[1]);
  data.nz = static_cast<uint32_t>(sizes[2]);
  data.data_file = data_file[0] != '\0' ? data_file : nullptr;
  data.line_skip = static_cast<uint64_t>(line_skip);
  data.byte_skip = byte_skip;
  int16_t* hu = nullptr;
  uint64_t saturated = 0;
  SPLINTCORE_RETURN_IF_ERROR(
      read_raw_volume(ctx, reader, source, opener, data, options, &hu, &saturated));

  out->nx = data.nx;
  out->ny = data.ny;
  out->nz = data.nz;
  out->spacing = spacing;
  out->origin = origin;
  out->axis_x = axes[0];
  out->axis_y = axes[1];
  out->axis_z = axes[2];
  out->hu = hu;
  out->saturated = saturated;
  if (info != nullptr) {
    found.nx = data.nx;
    found.ny = data.ny;
    found.nz = data.nz;
    found.spacing = spacing;
    describe_type(format, &found);
    found.slice_count = data.nz;
    found.detached = data.data_file != nullptr;
    found.saturated = saturated;
    *info = found;
  }
  return Status::ok();
}

}  // namespace splintcore
