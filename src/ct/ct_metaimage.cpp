// MetaImage reader: the MetaIO format of ITK/VTK ("MetaIO Documentation", Kitware,
// https://itk.org/Wiki/ITK/MetaIO/Documentation): "Key = Value" header lines, ElementDataFile
// last, then (LOCAL) the raw voxels or the name of a data file. Only 3-D scalar, uncompressed
// binary images; TransformMatrix row k is the direction of axis k (as ITK's MetaImageIO reads
// it). Voxel data goes through read_raw_volume() (ct_common.h).
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
    {"MET_CHAR", 1, true, false},    {"MET_UCHAR", 1, false, false}, {"MET_SHORT", 2, true, false},
    {"MET_USHORT", 2, false, false}, {"MET_INT", 4, true, false},    {"MET_UINT", 4, false, false},
    {"MET_FLOAT", 4, true, true},    {"MET_DOUBLE", 8, true, true},
};

bool parse_bool(const char* v, size_t n, bool* out) {
  if (equal_nocase(v, n, "true") || equal_nocase(v, n, "1")) {
    *out = true;
    return true;
  }
  if (equal_nocase(v, n, "false") || equal_nocase(v, n, "0")) {
    *out = false;
    return true;
  }
  return false;
}

}  // namespace

Status read_metaimage(const Context& ctx, const ByteSource& source, const CtFileOpener* opener,
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

  bool have_object = false, have_ndims = false, have_dims = false, have_type = false;
  bool binary = false, have_binary = false, have_spacing = false;
  VoxelFormat format;
  double dims[3] = {0, 0, 0};
  double spacing_v[3] = {1, 1, 1};
  double matrix[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  double offset[3] = {0, 0, 0};
  int64_t header_size = 0;
  uint64_t geometry_line = kNoPosition;
  CtInfo found;
  found.format = CtFormat::kMetaImage;

  for (;;) {
    size_t len = 0;
    bool too_long = false, got = false;
    Status s = reader.read_line(line, &len, &too_long, &got, &budget);
    ++line_no;
    if (!s.is_ok()) return fail(s);
    if (!got) {
      return fail(
          make_error(StatusCode::kTruncated, "header ends without ElementDataFile (the last key)")
              .at_byte(reader.offset()));
    }
    if (too_long) {
      return fail(make_error(StatusCode::kParseError, "line longer than ", kLineCapacity - 1,
                             " characters"));
    }
    const char* key = line;
    size_t eq = 0;
    while (eq < len && line[eq] != '=') ++eq;
    size_t key_len = eq;
    trim(&key, &key_len);
    if (key_len == 0 && eq == len) continue;  // blank line
    if (eq == len) return fail(make_error(StatusCode::kParseError, "expected \"Key = Value\""));
    const char* value = line + eq + 1;
    size_t value_len = len - eq - 1;
    trim(&value, &value_len);
    auto is = [&](const char* name) { return equal_nocase(key, key_len, name); };
    auto bad = [&](const char* what) {
      return fail(make_error(StatusCode::kParseError, "bad ", what, " \"")
                      .append(value, value_len)
                      .append("\""));
    };
    auto numbers = [&](double* out_values, size_t wanted) {
      size_t count = 0;
      return parse_doubles(value, value_len, '\0', out_values, wanted, &count) && count == wanted;
    };
    if (is("ObjectType")) {
      if (!equal_nocase(value, value_len, "Image")) {
        return fail(make_error(StatusCode::kUnsupported, "ObjectType \"")
                        .append(value, value_len)
                        .append("\": only Image is supported"));
      }
      have_object = true;
    } else if (is("NDims")) {
      int64_t d = 0;
      if (!parse_i64(value, value_len, &d)) return bad("NDims");
      if (d != 3) {
        return fail(
            make_error(StatusCode::kUnsupported, "NDims ", d, ": only 3-D volumes are supported"));
      }
      have_ndims = true;
    } else if (is("DimSize")) {
      if (!numbers(dims, 3)) return bad("DimSize (three integers)");
      for (double d : dims) {
        if (!(d >= 1 && d <= 4294967295.0) || d != static_cast<double>(static_cast<uint64_t>(d))) {
          return bad("DimSize (three positive integers)");
        }
      }
      have_dims = true;
    } else if (is("ElementSpacing") || (is("ElementSize") && !have_spacing)) {
      if (!numbers(spacing_v, 3)) return bad("element spacing (three numbers)");
      if (is("ElementSpacing")) have_spacing = true;
      geometry_line = line_no;
    } else if (is("Offset") || is("Origin") || is("Position")) {
      if (!numbers(offset, 3)) return bad("origin (three numbers)");
    } else if (is("TransformMatrix") || is("Rotation") || is("Orientation")) {
      if (!numbers(matrix, 9)) return bad("direction matrix (nine numbers)");
      if (geometry_line == kNoPosition) geometry_line = line_no;
    } else if (is("AnatomicalOrientation")) {
      size_t n = value_len < sizeof(found.space) - 1 ? value_len : sizeof(found.space) - 1;
      std::memcpy(found.space, value, n);
      found.space[n] = '\0';
    } else if (is("ElementType")) {
      bool ok = false;
      for (const TypeName& t : kTypes) {
        if (equal_nocase(value, value_len, t.name)) {
          format.bytes = t.bytes;
          format.is_signed = t.is_signed;
          format.is_float = t.is_float;
          ok = true;
        }
      }
      if (!ok) {
        return fail(make_error(StatusCode::kUnsupported, "ElementType \"")
                        .append(value, value_len)
                        .append("\" is not supported (MET_CHAR/UCHAR/SHORT/USHORT/INT/UINT/"
                                "FLOAT/DOUBLE)"));
      }
      have_type = true;
    } else if (is("ElementNumberOfChannels")) {
      int64_t c = 0;
      if (!parse_i64(value, value_len, &c)) return bad("ElementNumberOfChannels");
      if (c != 1) {
        return fail(make_error(StatusCode::kUnsupported, "ElementNumberOfChannels ", c,
                               ": only scalar volumes are supported"));
      }
    } else if (is("BinaryData")) {
      if (!parse_bool(value, value_len, &binary)) return bad("BinaryData (True or False)");
      have_binary = true;
    } else if (is("BinaryDataByteOrderMSB") || is("ElementByteOrderMSB")) {
      bool msb = false;
      if (!parse_bool(value, value_len, &msb)) return bad("byte order (True or False)");
      format.big_endian = msb;
    } else if (is("CompressedData")) {
      bool compressed = false;
      if (!parse_bool(value, value_len, &compressed)) return bad("CompressedData");
      if (compressed) {
        return fail(
            make_error(StatusCode::kUnsupported, "compressed MetaImage data is not supported"));
      }
    } else if (is("HeaderSize")) {
      if (!parse_i64(value, value_len, &header_size) || header_size < -1) {
        return bad("HeaderSize");
      }
    } else if (is("ElementDataFile")) {
      if (value_len == 0) return bad("ElementDataFile");
      if (equal_nocase(value, value_len, "LOCAL")) {
        data_file[0] = '\0';
      } else if ((value_len >= 4 && equal_nocase(value, 4, "LIST")) ||
                 std::memchr(value, '%', value_len) != nullptr) {
        return fail(make_error(StatusCode::kUnsupported, "ElementDataFile \"")
                        .append(value, value_len)
                        .append("\": LIST and pattern forms are not supported (one file only)"));
      } else {
        std::memcpy(data_file, value, value_len);
        data_file[value_len] = '\0';
      }
      break;  // the data (LOCAL) starts right after this line
    }
    // Other keys (Comment, CenterOfRotation, ElementMin, Modality, ...) are ignored.
  }

  auto missing = [&](const char* what) {
    return fail(
        make_error(StatusCode::kParseError, "missing key ", what, " before ElementDataFile"));
  };
  if (!have_object) return missing("ObjectType");
  if (!have_ndims) return missing("NDims");
  if (!have_dims) return missing("DimSize");
  if (!have_type) return missing("ElementType");
  if (!have_binary || !binary) {
    return fail(make_error(StatusCode::kUnsupported,
                           "only binary MetaImage data is supported (BinaryData = True)"));
  }
  if (data_file[0] == '\0' && header_size != 0) {
    return fail(make_error(StatusCode::kUnsupported,
                           "HeaderSize is only supported with a separate data file"));
  }

  Vec3 spacing{spacing_v[0], spacing_v[1], spacing_v[2]};
  Vec3 axes[3] = {Vec3{matrix[0], matrix[1], matrix[2]}, Vec3{matrix[3], matrix[4], matrix[5]},
                  Vec3{matrix[6], matrix[7], matrix[8]}};
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

  RawData data;
  data.format = format;
  data.nx = static_cast<uint32_t>(dims[0]);
  data.ny = static_cast<uint32_t>(dims[1]);
  data.nz = static_cast<uint32_t>(dims[2]);
  data.data_file = data_file[0] != '\0' ? data_file : nullptr;
  data.byte_skip = header_size;
  int16_t* hu = nullptr;
  uint64_t saturated = 0;
  SPLINTCORE_RETURN_IF_ERROR(
      read_raw_volume(ctx, reader, source, opener, data, options, &hu, &saturated));

  out->nx = data.nx;
  out->ny = data.ny;
  out->nz = data.nz;
  out->spacing = spacing;
  out->origin = Vec3{offset[0], offset[1], offset[2]};
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
