// MetaImage reader: the MetaIO format of ITK/VTK ("MetaIO Documentation", Kitware,
// https://itk.org/Wiki/ITK/MetaIO/Documentation): "Key = Value" header lines, ElementDataFile
// last, then (LOCAL) the raw voxels or the name of a data file. Only 3-D scalar, uncompressed
// binary images; TransformMatrix row k is the direction of axis k (as ITK's MetaImageIO reads
// it). Voxel data goes through read_text_volume() (ct_common.h).
#include "ct/ct_common.h"

namespace splintcore {

using namespace ct_detail;

namespace {

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

// The header, read a line at a time in a fixed window up to ElementDataFile (the last key),
// each key taken by its own method. Errors name the line.
struct MetaImageHeader : HeaderLines {
  // What the keys said.
  bool have_object = false, have_ndims = false, have_dims = false, have_type = false;
  bool binary = false, have_binary = false, have_spacing = false;
  bool have_data_file = false;  // ElementDataFile was read: the header ends there
  VoxelFormat format;
  double dims[3] = {0, 0, 0};
  double spacing[3] = {1, 1, 1};
  double matrix[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  double offset[3] = {0, 0, 0};
  int64_t header_size = 0;
  uint64_t geometry_line = kNoPosition;
  char data_file[kLineCapacity] = {};
  CtInfo found;

  MetaImageHeader(const ByteSource& s, const CtReadOptions& options) : HeaderLines(s, options) {
    found.format = CtFormat::kMetaImage;
  }

  // The key lines, up to ElementDataFile (the data, when LOCAL, starts right after it).
  Status read_keys() {
    while (!have_data_file) {
      size_t len = 0;
      bool too_long = false, got = false;
      SPLINTCORE_RETURN_IF_ERROR(next_line(&len, &too_long, &got));
      if (!got) {
        return fail(
            make_error(StatusCode::kTruncated, "header ends without ElementDataFile (the last key)")
                .at_byte(reader.offset()));
      }
      if (too_long) return line_too_long();
      size_t eq = 0;
      while (eq < len && line[eq] != '=') ++eq;
      if (eq == len) {
        const char* text = line;
        size_t n = len;
        trim(&text, &n);
        if (n == 0) continue;  // blank line
        return fail(make_error(StatusCode::kParseError, "expected \"Key = Value\""));
      }
      SPLINTCORE_RETURN_IF_ERROR(take(KeyValue::split(line, len, eq)));
    }
    return Status::ok();
  }

  // One key, by name. Other keys (Comment, CenterOfRotation, ElementMin, Modality, ...) are
  // ignored.
  Status take(const KeyValue& e) {
    using Take = Status (MetaImageHeader::*)(const KeyValue&);
    static constexpr struct {
      const char* key;
      Take take;
    } kKeys[] = {
        {"ObjectType", &MetaImageHeader::take_object_type},
        {"NDims", &MetaImageHeader::take_ndims},
        {"DimSize", &MetaImageHeader::take_dim_size},
        {"ElementSpacing", &MetaImageHeader::take_spacing},
        {"ElementSize", &MetaImageHeader::take_element_size},
        {"Offset", &MetaImageHeader::take_offset},
        {"Origin", &MetaImageHeader::take_offset},
        {"Position", &MetaImageHeader::take_offset},
        {"TransformMatrix", &MetaImageHeader::take_matrix},
        {"Rotation", &MetaImageHeader::take_matrix},
        {"Orientation", &MetaImageHeader::take_matrix},
        {"AnatomicalOrientation", &MetaImageHeader::take_anatomical_orientation},
        {"ElementType", &MetaImageHeader::take_element_type},
        {"ElementNumberOfChannels", &MetaImageHeader::take_channels},
        {"BinaryData", &MetaImageHeader::take_binary_data},
        {"BinaryDataByteOrderMSB", &MetaImageHeader::take_byte_order},
        {"ElementByteOrderMSB", &MetaImageHeader::take_byte_order},
        {"CompressedData", &MetaImageHeader::take_compressed_data},
        {"HeaderSize", &MetaImageHeader::take_header_size},
        {"ElementDataFile", &MetaImageHeader::take_data_file},
    };
    for (const auto& key : kKeys) {
      if (e.is(key.key)) return (this->*key.take)(e);
    }
    return Status::ok();
  }

  Status take_object_type(const KeyValue& e) {
    if (!e.value_is("Image")) {
      return fail(make_error(StatusCode::kUnsupported, "ObjectType \"")
                      .append(e.value, e.value_length)
                      .append("\": only Image is supported"));
    }
    have_object = true;
    return Status::ok();
  }

  Status take_ndims(const KeyValue& e) {
    int64_t d = 0;
    if (!parse_i64(e.value, e.value_length, &d)) return bad(e, "NDims");
    if (d != 3) {
      return fail(
          make_error(StatusCode::kUnsupported, "NDims ", d, ": only 3-D volumes are supported"));
    }
    have_ndims = true;
    return Status::ok();
  }

  Status take_dim_size(const KeyValue& e) {
    if (!e.numbers(dims, 3)) return bad(e, "DimSize (three integers)");
    for (double d : dims) {
      if (!(d >= 1 && d <= 4294967295.0) || d != static_cast<double>(static_cast<uint64_t>(d))) {
        return bad(e, "DimSize (three positive integers)");
      }
    }
    have_dims = true;
    return Status::ok();
  }

  // ElementSpacing, or ElementSize while no ElementSpacing was given.
  Status take_spacing(const KeyValue& e) {
    if (!e.numbers(spacing, 3)) return bad(e, "element spacing (three numbers)");
    if (e.is("ElementSpacing")) have_spacing = true;
    geometry_line = line_no;
    return Status::ok();
  }

  Status take_element_size(const KeyValue& e) {
    return have_spacing ? Status::ok() : take_spacing(e);
  }

  Status take_offset(const KeyValue& e) {
    if (!e.numbers(offset, 3)) return bad(e, "origin (three numbers)");
    return Status::ok();
  }

  Status take_matrix(const KeyValue& e) {
    if (!e.numbers(matrix, 9)) return bad(e, "direction matrix (nine numbers)");
    if (geometry_line == kNoPosition) geometry_line = line_no;
    return Status::ok();
  }

  Status take_anatomical_orientation(const KeyValue& e) {
    size_t n = e.value_length < sizeof(found.space) - 1 ? e.value_length : sizeof(found.space) - 1;
    std::memcpy(found.space, e.value, n);
    found.space[n] = '\0';
    return Status::ok();
  }

  Status take_element_type(const KeyValue& e) {
    for (const TypeName& t : kTypes) {
      if (e.value_is(t.name)) {
        format.bytes = t.bytes;
        format.is_signed = t.is_signed;
        format.is_float = t.is_float;
        have_type = true;
        return Status::ok();
      }
    }
    return fail(make_error(StatusCode::kUnsupported, "ElementType \"")
                    .append(e.value, e.value_length)
                    .append("\" is not supported (MET_CHAR/UCHAR/SHORT/USHORT/INT/UINT/"
                            "FLOAT/DOUBLE)"));
  }

  Status take_channels(const KeyValue& e) {
    int64_t c = 0;
    if (!parse_i64(e.value, e.value_length, &c)) return bad(e, "ElementNumberOfChannels");
    if (c != 1) {
      return fail(make_error(StatusCode::kUnsupported, "ElementNumberOfChannels ", c,
                             ": only scalar volumes are supported"));
    }
    return Status::ok();
  }

  Status take_binary_data(const KeyValue& e) {
    if (!parse_bool(e.value, e.value_length, &binary)) return bad(e, "BinaryData (True or False)");
    have_binary = true;
    return Status::ok();
  }

  Status take_byte_order(const KeyValue& e) {
    bool msb = false;
    if (!parse_bool(e.value, e.value_length, &msb)) return bad(e, "byte order (True or False)");
    format.big_endian = msb;
    return Status::ok();
  }

  Status take_compressed_data(const KeyValue& e) {
    bool compressed = false;
    if (!parse_bool(e.value, e.value_length, &compressed)) return bad(e, "CompressedData");
    if (compressed) {
      return fail(
          make_error(StatusCode::kUnsupported, "compressed MetaImage data is not supported"));
    }
    return Status::ok();
  }

  Status take_header_size(const KeyValue& e) {
    if (!parse_i64(e.value, e.value_length, &header_size) || header_size < -1) {
      return bad(e, "HeaderSize");
    }
    return Status::ok();
  }

  Status take_data_file(const KeyValue& e) {
    if (e.value_length == 0) return bad(e, "ElementDataFile");
    if (e.value_is("LOCAL")) {
      data_file[0] = '\0';
    } else if ((e.value_length >= 4 && equal_nocase(e.value, 4, "LIST")) ||
               std::memchr(e.value, '%', e.value_length) != nullptr) {
      return fail(make_error(StatusCode::kUnsupported, "ElementDataFile \"")
                      .append(e.value, e.value_length)
                      .append("\": LIST and pattern forms are not supported (one file only)"));
    } else {
      std::memcpy(data_file, e.value, e.value_length);
      data_file[e.value_length] = '\0';
    }
    have_data_file = true;
    return Status::ok();
  }

  // The keys every volume needs (errors name the ElementDataFile line).
  Status check_required() const {
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
    return Status::ok();
  }

  // The volume the keys describe: TransformMatrix row k is the direction of axis k.
  TextVolume volume() const {
    TextVolume v;
    v.spacing = Vec3{spacing[0], spacing[1], spacing[2]};
    v.origin = Vec3{offset[0], offset[1], offset[2]};
    for (int a = 0; a < 3; ++a) {
      v.axes[a] = Vec3{matrix[3 * a], matrix[3 * a + 1], matrix[3 * a + 2]};
    }
    v.geometry_line = geometry_line;
    v.data.format = format;
    v.data.nx = static_cast<uint32_t>(dims[0]);
    v.data.ny = static_cast<uint32_t>(dims[1]);
    v.data.nz = static_cast<uint32_t>(dims[2]);
    v.data.data_file = data_file[0] != '\0' ? data_file : nullptr;
    v.data.byte_skip = header_size;
    return v;
  }
};

}  // namespace

Status read_metaimage(const Context& ctx, const ByteSource& source, const CtFileOpener* opener,
                      const CtReadOptions& options, CtVolume* out, CtInfo* info) {
  MetaImageHeader header(source, options);
  SPLINTCORE_RETURN_IF_ERROR(header.read_keys());
  SPLINTCORE_RETURN_IF_ERROR(header.check_required());
  return read_text_volume(ctx, header.reader, source, opener, options, header.volume(),
                          header.found, out, info);
}

}  // namespace splintcore
