// DICOM series reader. Sources: DICOM PS3.10 section 7 (file format: 128-byte preamble,
// "DICM", File Meta Information group 0002 in explicit VR little endian), PS3.5 sections 7.1
// (data elements, explicit and implicit VR; the VRs with 32-bit lengths in table 7.1-1),
// 7.5 (sequences and items of defined and undefined length), 8 (native pixel data) and A.1/A.2
// (transfer syntaxes 1.2.840.10008.1.2 and 1.2.840.10008.1.2.1); PS3.3 C.7.6.2 (Image Plane:
// Image Position / Orientation (Patient), Pixel Spacing = row spacing then column spacing),
// C.7.6.3 (Image Pixel) and C.11.1.1.2 (Modality LUT: rescale slope and intercept).
//
// Two passes: headers of every file (up to Pixel Data, in a fixed stack window), then the
// slices ordered by their position along the normal, pixels read into place.
#include "ct/ct_common.h"
#include "ct/ct_resample.h"
#include "ct/dicom_frames.h"
#include "ct/dicom_rle.h"
#include "ct/jpeg2000.h"
#include "ct/jpeg_lossless.h"
#include "ct/jpeg_ls.h"

#include <algorithm>
#include <cmath>

namespace splintcore {

using namespace ct_detail;

namespace {

constexpr uint32_t kUndefinedLength = 0xFFFFFFFFu;
constexpr uint32_t kMaxValueBytes = 256;  // longest value of a tag this reader keeps
constexpr int kMaxNesting = 32;

constexpr uint32_t tag_of(uint32_t group, uint32_t element) { return (group << 16) | element; }
constexpr uint32_t kTransferSyntax = tag_of(0x0002, 0x0010);
constexpr uint32_t kImageType = tag_of(0x0008, 0x0008);
constexpr uint32_t kSliceThickness = tag_of(0x0018, 0x0050);
constexpr uint32_t kSpacingBetweenSlices = tag_of(0x0018, 0x0088);
constexpr uint32_t kImagePosition = tag_of(0x0020, 0x0032);
constexpr uint32_t kImageOrientation = tag_of(0x0020, 0x0037);
constexpr uint32_t kSamplesPerPixel = tag_of(0x0028, 0x0002);
constexpr uint32_t kPhotometric = tag_of(0x0028, 0x0004);
constexpr uint32_t kNumberOfFrames = tag_of(0x0028, 0x0008);
constexpr uint32_t kRows = tag_of(0x0028, 0x0010);
constexpr uint32_t kColumns = tag_of(0x0028, 0x0011);
constexpr uint32_t kPixelSpacing = tag_of(0x0028, 0x0030);
constexpr uint32_t kBitsAllocated = tag_of(0x0028, 0x0100);
constexpr uint32_t kBitsStored = tag_of(0x0028, 0x0101);
constexpr uint32_t kHighBit = tag_of(0x0028, 0x0102);
constexpr uint32_t kPixelRepresentation = tag_of(0x0028, 0x0103);
constexpr uint32_t kRescaleIntercept = tag_of(0x0028, 0x1052);
constexpr uint32_t kRescaleSlope = tag_of(0x0028, 0x1053);
constexpr uint32_t kPixelData = tag_of(0x7FE0, 0x0010);
constexpr uint32_t kExtendedOffsetTable = tag_of(0x7FE0, 0x0001);  // PS3.3 C.7.6.3.1.8
// Enhanced multi-frame images (PS3.3 C.7.6.16): the functional group sequences and the macros
// of them this reader interprets (Plane Position, Plane Orientation, Pixel Measures, Pixel
// Value Transformation).
constexpr uint32_t kSharedGroups = tag_of(0x5200, 0x9229);
constexpr uint32_t kPerFrameGroups = tag_of(0x5200, 0x9230);
constexpr uint32_t kPlanePosition = tag_of(0x0020, 0x9113);
constexpr uint32_t kPlaneOrientation = tag_of(0x0020, 0x9116);
constexpr uint32_t kPixelMeasures = tag_of(0x0028, 0x9110);
constexpr uint32_t kPixelValueTransformation = tag_of(0x0028, 0x9145);

inline uint16_t u16(const uint8_t* p) { return static_cast<uint16_t>(p[0] | (p[1] << 8)); }
inline uint32_t u32(const uint8_t* p) {
  return uint32_t{p[0]} | (uint32_t{p[1]} << 8) | (uint32_t{p[2]} << 16) | (uint32_t{p[3]} << 24);
}
// The data set's byte order (explicit VR big endian, 1.2.840.10008.1.2.2, is the one big).
inline uint16_t u16(const uint8_t* p, bool big) {
  return big ? static_cast<uint16_t>((p[0] << 8) | p[1]) : u16(p);
}
inline uint32_t u32(const uint8_t* p, bool big) {
  return big ? (uint32_t{p[0]} << 24) | (uint32_t{p[1]} << 16) | (uint32_t{p[2]} << 8) | p[3]
             : u32(p);
}

// How a transfer syntax stores the pixels.
enum class Codec : uint8_t { kNative, kDeflated, kRle, kJpegLossless, kJpegLs, kJpeg2000 };

// PS3.6 table A-1: the transfer syntaxes this reader knows, read or refused by name.
struct Syntax {
  const char* uid;
  const char* name;
  Codec codec;
  bool implicit;
  bool big_endian;
  bool supported;
};
constexpr Syntax kSyntaxes[] = {
    {"1.2.840.10008.1.2", "Implicit VR Little Endian", Codec::kNative, true, false, true},
    {"1.2.840.10008.1.2.1", "Explicit VR Little Endian", Codec::kNative, false, false, true},
    {"1.2.840.10008.1.2.1.99", "Deflated Explicit VR Little Endian", Codec::kDeflated, false, false,
     true},
    {"1.2.840.10008.1.2.2", "Explicit VR Big Endian", Codec::kNative, false, true, true},
    {"1.2.840.10008.1.2.5", "RLE Lossless", Codec::kRle, false, false, true},
    {"1.2.840.10008.1.2.4.57", "JPEG Lossless, Process 14", Codec::kJpegLossless, false, false,
     true},
    {"1.2.840.10008.1.2.4.70", "JPEG Lossless, Process 14, Selection Value 1", Codec::kJpegLossless,
     false, false, true},
    {"1.2.840.10008.1.2.4.50", "JPEG Baseline (lossy)", Codec::kNative, false, false, false},
    {"1.2.840.10008.1.2.4.51", "JPEG Extended (lossy)", Codec::kNative, false, false, false},
    {"1.2.840.10008.1.2.4.80", "JPEG-LS Lossless", Codec::kJpegLs, false, false, true},
    {"1.2.840.10008.1.2.4.81", "JPEG-LS Near-Lossless", Codec::kJpegLs, false, false, true},
    {"1.2.840.10008.1.2.4.90", "JPEG 2000 Lossless", Codec::kJpeg2000, false, false, true},
    {"1.2.840.10008.1.2.4.91", "JPEG 2000", Codec::kJpeg2000, false, false, true},
    {"1.2.840.10008.1.2.4.201", "HTJ2K Lossless", Codec::kNative, false, false, false},
    {"1.2.840.10008.1.2.4.202", "HTJ2K Lossless RPCL", Codec::kNative, false, false, false},
    {"1.2.840.10008.1.2.4.203", "HTJ2K", Codec::kNative, false, false, false},
};
constexpr const char* kSupportedSyntaxes =
    "; read are implicit and explicit VR little endian, deflated, explicit VR big endian, "
    "RLE Lossless, JPEG Lossless process 14, JPEG-LS, JPEG 2000";

// PS3.5 table 7.1-1: VRs whose explicit encoding has 2 reserved bytes and a 32-bit length.
bool long_vr(uint8_t a, uint8_t b) {
  static const char kLong[][3] = {"OB", "OD", "OF", "OL", "OV", "OW", "SQ",
                                  "SV", "UC", "UN", "UR", "UT", "UV"};
  for (const auto& v : kLong) {
    if (a == static_cast<uint8_t>(v[0]) && b == static_cast<uint8_t>(v[1])) return true;
  }
  return false;
}

Status& append_tag(Status& s, uint32_t tag) {
  static const char kHex[] = "0123456789ABCDEF";
  char text[12];
  text[0] = '(';
  for (int i = 0; i < 4; ++i) text[1 + i] = kHex[(tag >> (28 - 4 * i)) & 0xF];
  text[5] = ',';
  for (int i = 0; i < 4; ++i) text[6 + i] = kHex[(tag >> (12 - 4 * i)) & 0xF];
  text[10] = ')';
  text[11] = '\0';
  return s.append(text);
}

Status tag_error(StatusCode code, uint32_t tag, const char* name, const char* what,
                 uint64_t offset) {
  Status s = Status::error(code, "");
  append_tag(s, tag).append(" ").append(name).append(": ").append(what);
  s.at_byte(offset);
  return s;
}

// What one file's header says.
struct Header {
  bool implicit = false;
  bool deflated = false;    // 1.2.840.10008.1.2.1.99: the data set is a raw deflate stream
  bool big_endian = false;  // 1.2.840.10008.1.2.2: the data set (not group 0002) big endian
  Codec codec = Codec::kNative;
  char transfer_syntax[65] = {};
  char photometric[17] = {};
  char image_type[65] = {};  // (0008,0008), as written (for messages)
  bool localizer = false;    // one of its values is LOCALIZER: a scout, not a slice
  uint32_t rows = 0, columns = 0;
  uint32_t bits_allocated = 0, bits_stored = 0, high_bit = 0, pixel_representation = 0;
  uint32_t samples = 1;
  int64_t frames = 1;
  bool have_rows = false, have_columns = false, have_bits_allocated = false;
  bool have_bits_stored = false, have_high_bit = false, have_pixel_representation = false;
  bool have_position = false, have_orientation = false, have_pixel_spacing = false;
  double slope = 1.0, intercept = 0.0;
  double pixel_spacing[2] = {0, 0};  // row spacing (between rows), column spacing
  double position[3] = {0, 0, 0};
  double orientation[6] = {0, 0, 0, 0, 0, 0};
  double slice_thickness = 0, spacing_between = 0;
  uint64_t pixel_offset = 0;  // native: the pixels; encapsulated: the basic offset table item
  uint64_t pixel_length = 0;
  bool have_pixels = false;
  // Encapsulated pixel data (PS3.5 A.4): the fragments after the basic offset table.
  uint32_t fragments = 0;
  uint64_t fragment_bytes = 0;  // their total length (< max_dimension x 4 GiB: no overflow)
  // Enhanced multi-frame (frames > 1): the Per-frame Functional Groups items seen, each with
  // its Image Position (Patient) (then have_position is set, position is frame 0's).
  uint32_t frame_items = 0;
  bool have_per_frame = false;
  // Encapsulated multi-frame: the Extended Offset Table (7FE0,0001) (its value's file offset),
  // and the largest frame's fragment bytes (found when the frames are mapped).
  bool extended_offsets = false;
  uint64_t extended_at = 0;
  uint64_t largest_frame = 0;
};

bool encapsulated(Codec codec) {
  return codec == Codec::kRle || codec == Codec::kJpegLossless || codec == Codec::kJpegLs ||
         codec == Codec::kJpeg2000;
}

void copy_string(char* out, size_t cap, const uint8_t* v, uint32_t n) {
  const char* text = reinterpret_cast<const char*>(v);
  size_t len = n;
  trim(&text, &len);
  if (len >= cap) len = cap - 1;
  std::memcpy(out, text, len);
  out[len] = '\0';
}

// Interprets a kept top-level element (value at v, n bytes, element at byte `at`).
Status take_value(Header* h, uint32_t tag, const uint8_t* v, uint32_t n, uint64_t at) {
  auto us = [&](const char* name, uint32_t* out, bool* have) {
    if (n != 2) return tag_error(StatusCode::kParseError, tag, name, "expected 2 bytes (US)", at);
    *out = u16(v, h->big_endian);
    if (have != nullptr) *have = true;
    return Status::ok();
  };
  auto ds = [&](const char* name, double* out, size_t wanted) {
    size_t count = 0;
    if (!parse_doubles(reinterpret_cast<const char*>(v), n, '\\', out, wanted, &count) ||
        count != wanted) {
      Status s = tag_error(StatusCode::kParseError, tag, name, "expected ", at);
      s.append_u64(wanted);
      s.append(" decimal number(s), got \"");
      s.append(reinterpret_cast<const char*>(v), n < 64 ? n : 64);
      s.append("\"");
      return s;
    }
    return Status::ok();
  };
  switch (tag) {
    case kSliceThickness: {
      double t = 0;
      if (n > 0 && ds("Slice Thickness", &t, 1).is_ok()) h->slice_thickness = t;
      return Status::ok();  // informative only: used for a single slice when valid
    }
    case kSpacingBetweenSlices: {
      double t = 0;
      if (n > 0 && ds("Spacing Between Slices", &t, 1).is_ok()) h->spacing_between = t;
      return Status::ok();
    }
    case kImagePosition:
      h->have_position = true;
      return ds("Image Position (Patient)", h->position, 3);
    case kImageOrientation:
      h->have_orientation = true;
      return ds("Image Orientation (Patient)", h->orientation, 6);
    case kPixelSpacing:
      h->have_pixel_spacing = true;
      return ds("Pixel Spacing", h->pixel_spacing, 2);
    case kRescaleIntercept: return ds("Rescale Intercept", &h->intercept, 1);
    case kRescaleSlope: return ds("Rescale Slope", &h->slope, 1);
    case kSamplesPerPixel: return us("Samples per Pixel", &h->samples, nullptr);
    case kRows: return us("Rows", &h->rows, &h->have_rows);
    case kColumns: return us("Columns", &h->columns, &h->have_columns);
    case kBitsAllocated: return us("Bits Allocated", &h->bits_allocated, &h->have_bits_allocated);
    case kBitsStored: return us("Bits Stored", &h->bits_stored, &h->have_bits_stored);
    case kHighBit: return us("High Bit", &h->high_bit, &h->have_high_bit);
    case kPixelRepresentation:
      return us("Pixel Representation", &h->pixel_representation, &h->have_pixel_representation);
    case kPhotometric:
      copy_string(h->photometric, sizeof(h->photometric), v, n);
      return Status::ok();
    case kImageType: {  // CS values split by '\': a localizer (scout) says LOCALIZER
      copy_string(h->image_type, sizeof(h->image_type), v, n);
      const char* text = reinterpret_cast<const char*>(v);
      for (uint32_t i = 0; i <= n;) {
        uint32_t j = i;
        while (j < n && text[j] != '\\') ++j;
        const char* value = text + i;
        size_t len = j - i;
        trim(&value, &len);
        if (len == 9 && std::memcmp(value, "LOCALIZER", 9) == 0) h->localizer = true;
        i = j + 1;
      }
      return Status::ok();
    }
    case kNumberOfFrames: {
      int64_t f = 0;
      if (!parse_i64(reinterpret_cast<const char*>(v), n, &f)) {
        return tag_error(StatusCode::kParseError, tag, "Number of Frames", "not an integer", at);
      }
      h->frames = f;
      return Status::ok();
    }
    default: return Status::ok();
  }
}

bool kept_tag(uint32_t tag) {
  switch (tag) {
    case kSliceThickness:
    case kSpacingBetweenSlices:
    case kImagePosition:
    case kImageOrientation:
    case kPixelSpacing:
    case kRescaleIntercept:
    case kRescaleSlope:
    case kSamplesPerPixel:
    case kRows:
    case kColumns:
    case kBitsAllocated:
    case kBitsStored:
    case kHighBit:
    case kPixelRepresentation:
    case kPhotometric:
    case kImageType:
    case kNumberOfFrames: return true;
    default: return false;
  }
}

Status truncated(Reader& r, const char* where) {
  return make_error(StatusCode::kTruncated, "file ends inside ", where).at_byte(r.base + r.end);
}

// The 128-byte preamble, "DICM", then the File Meta Information (explicit VR little endian,
// group 0002), of which the Transfer Syntax UID is kept: it says how the data set is encoded.
Status read_file_meta(Reader& r, Header* h) {
  SPLINTCORE_RETURN_IF_ERROR(r.fill(132));
  if (r.available() < 132) return truncated(r, "the 128-byte preamble and \"DICM\"");
  if (std::memcmp(r.buf + r.pos + 128, "DICM", 4) != 0) {
    return make_error(StatusCode::kParseError,
                      "not a DICOM file: no \"DICM\" after the 128-byte preamble")
        .at_byte(128);
  }
  r.pos += 132;

  bool have_syntax = false;
  for (;;) {
    SPLINTCORE_RETURN_IF_ERROR(r.fill(12));
    if (r.available() < 8) return truncated(r, "the file meta information");
    const uint8_t* p = r.buf + r.pos;
    if (u16(p) != 0x0002) break;
    const uint64_t at = r.offset();
    const uint32_t tag = tag_of(0x0002, u16(p + 2));
    uint64_t length;
    size_t header_bytes;
    if (long_vr(p[4], p[5])) {
      if (r.available() < 12) return truncated(r, "the file meta information");
      length = u32(p + 8);
      header_bytes = 12;
    } else {
      length = u16(p + 6);
      header_bytes = 8;
    }
    if (length == kUndefinedLength) {
      return tag_error(StatusCode::kParseError, tag, "meta element", "undefined length", at);
    }
    r.pos += header_bytes;
    if (tag == kTransferSyntax) {
      if (length > 64) {
        return tag_error(StatusCode::kParseError, tag, "Transfer Syntax UID", "too long", at);
      }
      SPLINTCORE_RETURN_IF_ERROR(r.fill(static_cast<size_t>(length)));
      if (r.available() < length) return truncated(r, "the Transfer Syntax UID");
      copy_string(h->transfer_syntax, sizeof(h->transfer_syntax), r.buf + r.pos,
                  static_cast<uint32_t>(length));
      r.pos += static_cast<size_t>(length);
      have_syntax = true;
    } else {
      SPLINTCORE_RETURN_IF_ERROR(r.skip(length, "the file meta information"));
    }
  }
  if (!have_syntax) {
    return make_error(StatusCode::kParseError, "missing (0002,0010) Transfer Syntax UID")
        .at_byte(r.offset());
  }
  for (const Syntax& syntax : kSyntaxes) {
    if (std::strcmp(h->transfer_syntax, syntax.uid) != 0) continue;
    if (!syntax.supported) {
      return make_error(StatusCode::kUnsupported, "unsupported transfer syntax ", syntax.uid, " (",
                        syntax.name, ")", kSupportedSyntaxes);
    }
    h->implicit = syntax.implicit;
    h->big_endian = syntax.big_endian;
    h->codec = syntax.codec;
    h->deflated = syntax.codec == Codec::kDeflated;
    return Status::ok();
  }
  return make_error(StatusCode::kUnsupported, "unsupported transfer syntax ", h->transfer_syntax,
                    " (unknown)", kSupportedSyntaxes);
}

// A data element's value length and VR (explicit VR only: implicit VR says neither SQ nor UN).
struct ElementHeader {
  uint32_t length = 0;
  bool is_sq = false;
  bool is_un = false;
};

// Reads the VR (explicit) and the length following the tag at p, and moves past them.
Status read_element_header(Reader& r, const uint8_t* p, uint32_t tag, uint64_t at, bool implicit,
                           bool big, ElementHeader* e) {
  if (implicit) {
    e->length = u32(p + 4, big);
    r.pos += 8;
    return Status::ok();
  }
  const uint8_t a = p[4], b = p[5];
  if (a < 'A' || a > 'Z' || b < 'A' || b > 'Z') {
    return tag_error(StatusCode::kParseError, tag, "element", "invalid VR", at);
  }
  e->is_sq = a == 'S' && b == 'Q';
  e->is_un = a == 'U' && b == 'N';
  if (long_vr(a, b)) {
    if (r.available() < 12) return truncated(r, "a data element header");
    e->length = u32(p + 8, big);
    r.pos += 12;
  } else {
    e->length = u16(p + 6, big);
    r.pos += 8;
  }
  return Status::ok();
}

// The item header (tag and 32-bit length, PS3.5 A.4) at the reader: kTruncated if it is cut.
Status read_item_header(Reader& r, uint32_t* tag, uint32_t* length) {
  SPLINTCORE_RETURN_IF_ERROR(r.fill(8));
  if (r.available() < 8) return truncated(r, "encapsulated Pixel Data (an item header)");
  const uint8_t* p = r.buf + r.pos;
  *tag = tag_of(u16(p), u16(p + 2));
  *length = u32(p + 4);
  r.pos += 8;
  return Status::ok();
}

// Reads `count` little-endian entries of `bytes` (4 or 8) each into records[i].pixel_offset.
Status read_offsets(Reader& r, SliceRecord* records, uint32_t count, uint32_t bytes,
                    const char* what) {
  for (uint32_t i = 0; i < count; ++i) {
    SPLINTCORE_RETURN_IF_ERROR(r.fill(bytes));
    if (r.available() < bytes) return truncated(r, what);
    const uint8_t* p = r.buf + r.pos;
    records[i].pixel_offset = bytes == 4 ? u32(p) : u32(p) | (uint64_t{u32(p + 4)} << 32);
    r.pos += bytes;
  }
  return Status::ok();
}

// The fragments of a multi-frame image (the reader after the basic offset table's item header,
// `length` its value's bytes, the item at `table_at`), mapped to its frames (dicom_frames.h)
// when frames (the records of pass 1) is not null; pass 0 stops here. The offset table is
// empty or has one entry a frame; with an Extended Offset Table it is empty.
Status map_frames(Reader& r, Header* h, SliceRecord* frames, uint32_t length, uint64_t table_at) {
  const uint32_t count = static_cast<uint32_t>(h->frames);  // 2..65535
  if (length != 0 && (length != 4 * count || h->extended_offsets)) {
    Status s = tag_error(StatusCode::kParseError, tag_of(0xFFFE, 0xE000), "Basic Offset Table",
                         "has ", table_at);
    s.append_u64(length / 4);
    s.append(" entries for ");
    s.append_u64(count);
    s.append(h->extended_offsets ? " frames and an Extended Offset Table (then it must be empty)"
                                 : " frames (Number of Frames): it must be empty or have one "
                                   "entry a frame");
    return s;
  }
  if (frames == nullptr) return Status::ok();
  OffsetTable table;
  if (length != 0) {
    table = OffsetTable{"Basic Offset Table", r.offset(), 4};
    SPLINTCORE_RETURN_IF_ERROR(read_offsets(r, frames, count, 4, "the basic offset table"));
  } else if (h->extended_offsets) {
    table = OffsetTable{"Extended Offset Table (7FE0,0001)", h->extended_at, 8};
  }
  const FrameStart start = h->codec == Codec::kRle        ? FrameStart::kEachFragment
                           : h->codec == Codec::kJpeg2000 ? FrameStart::kJpeg2000Soc
                                                          : FrameStart::kJpegSoi;
  const uint64_t raw = uint64_t{h->rows} * h->columns * (h->bits_allocated / 8);
  FrameMapper mapper(frames, count, table, start, raw * 8 + 65536);
  for (;;) {
    const uint64_t at = r.offset();
    uint32_t tag = 0, item_length = 0;
    SPLINTCORE_RETURN_IF_ERROR(read_item_header(r, &tag, &item_length));
    if (tag == tag_of(0xFFFE, 0xE0DD)) {
      if (item_length != 0) {
        return tag_error(StatusCode::kParseError, tag, "Sequence Delimitation", "length not 0", at);
      }
      SPLINTCORE_RETURN_IF_ERROR(mapper.finish(at));
      h->largest_frame = mapper.largest();
      return Status::ok();
    }
    if (tag != tag_of(0xFFFE, 0xE000) || item_length == kUndefinedLength) {
      return tag_error(StatusCode::kParseError, tag, "Pixel Data",
                       "expected a fragment Item (FFFE,E000) of defined length or the Sequence "
                       "Delimitation (FFFE,E0DD)",
                       at);
    }
    SPLINTCORE_RETURN_IF_ERROR(r.fill(4));
    const size_t head = std::min<size_t>({r.available(), 4, item_length});
    SPLINTCORE_RETURN_IF_ERROR(mapper.add(at, item_length, r.buf + r.pos, head));
    ++h->fragments;
    h->fragment_bytes += item_length;
    Status s = r.skip(item_length, "a Pixel Data fragment");
    if (!s.is_ok()) {
      return make_error(s.code(), "frame ", mapper.frames_found() - 1, " (fragment item ",
                        h->fragments - 1, " at byte ", at, "): ", s.message())
          .at_byte(s.byte_offset());
    }
  }
}

// Encapsulated Pixel Data (PS3.5 A.4), the reader just after its element header: the basic
// offset table (an item whose length is a multiple of 4, skipped: one frame per file), then
// fragment items up to the sequence delimiter. Counts and sums the fragments.
Status scan_fragments(Reader& r, const CtReadOptions& options, Header* h, SliceRecord* frames) {
  h->pixel_offset = r.offset();
  h->have_pixels = true;
  uint32_t tag = 0, length = 0;
  uint64_t at = r.offset();
  SPLINTCORE_RETURN_IF_ERROR(read_item_header(r, &tag, &length));
  if (tag != tag_of(0xFFFE, 0xE000) || length == kUndefinedLength || length % 4 != 0) {
    return tag_error(StatusCode::kParseError, tag, "Pixel Data",
                     "expected the basic offset table: an Item (FFFE,E000) whose length is a "
                     "multiple of 4",
                     at);
  }
  if (h->frames > 1) return map_frames(r, h, frames, length, at);
  SPLINTCORE_RETURN_IF_ERROR(r.skip(length, "the basic offset table"));
  for (;;) {
    at = r.offset();
    SPLINTCORE_RETURN_IF_ERROR(read_item_header(r, &tag, &length));
    if (tag == tag_of(0xFFFE, 0xE0DD)) {
      if (length != 0) {
        return tag_error(StatusCode::kParseError, tag, "Sequence Delimitation", "length not 0", at);
      }
      return Status::ok();
    }
    if (tag != tag_of(0xFFFE, 0xE000) || length == kUndefinedLength) {
      return tag_error(StatusCode::kParseError, tag, "Pixel Data",
                       "expected a fragment Item (FFFE,E000) of defined length or the Sequence "
                       "Delimitation (FFFE,E0DD)",
                       at);
    }
    if (h->fragments == options.max_dimension) {
      return make_error(StatusCode::kLimitExceeded, "Pixel Data has more than ",
                        options.max_dimension, " fragments (CtReadOptions::max_dimension)")
          .at_byte(at);
    }
    ++h->fragments;
    h->fragment_bytes += length;  // at most 2^32 a fragment times 2^32 fragments: no overflow
    SPLINTCORE_RETURN_IF_ERROR(r.skip(length, "a Pixel Data fragment"));
  }
}

// The data set, up to Pixel Data. Containers of undefined length are tracked on a bounded
// stack (no recursion), as are those of defined length on the path to the functional group
// macros of an enhanced multi-frame image (their end offsets checked); other containers of
// defined length are skipped whole. Interpreted are depth 0 and, at depth 4, the values of
// the Shared (5200,9229) and Per-frame (5200,9230) Functional Groups' Plane Position, Plane
// Orientation, Pixel Measures and Pixel Value Transformation items (PS3.3 C.7.6.16).
class DataSetWalk {
 public:
  // frames: when not null, where frame i's position and rescale go (room for `capacity`).
  DataSetWalk(Reader& r, const CtReadOptions& options, Header* h, SliceRecord* frames = nullptr,
              uint32_t capacity = 0)
      : r_(r), options_(options), h_(h), frames_(frames), capacity_(capacity) {}

  Status run() {
    for (;;) {
      SPLINTCORE_RETURN_IF_ERROR(close_ended());
      if (r_.offset() > options_.max_header_bytes) {
        return make_error(StatusCode::kLimitExceeded, "no Pixel Data within the first ",
                          options_.max_header_bytes, " bytes (CtReadOptions::max_header_bytes)")
            .at_byte(r_.offset());
      }
      SPLINTCORE_RETURN_IF_ERROR(r_.fill(12));
      if (r_.available() == 0 && depth_ == 0) {
        return make_error(StatusCode::kParseError, "no (7FE0,0010) Pixel Data in the file")
            .at_byte(r_.offset());
      }
      if (r_.available() < 8) return truncated(r_, "a data element header");
      const uint8_t* p = r_.buf + r_.pos;
      const uint64_t at = r_.offset();
      const bool big = h_->big_endian;
      const uint32_t group = u16(p, big);
      const uint32_t tag = tag_of(group, u16(p + 2, big));
      if (group == 0xFFFE) {
        const uint32_t length = u32(p + 4, big);
        r_.pos += 8;
        SPLINTCORE_RETURN_IF_ERROR(delimiter(tag, length, at));
        continue;
      }
      const bool implicit = depth_ > 0 ? stack_[depth_ - 1].implicit : h_->implicit;
      ElementHeader e;
      SPLINTCORE_RETURN_IF_ERROR(read_element_header(r_, p, tag, at, implicit, big, &e));
      if (depth_ == 0 && tag == kPixelData) SPLINTCORE_RETURN_IF_ERROR(check_frames(at));
      if (depth_ == 0 && tag == kPixelData && encapsulated(h_->codec)) {
        if (e.length != kUndefinedLength) {
          return tag_error(StatusCode::kParseError, tag, "Pixel Data",
                           "of defined length in an encapsulated (compressed) transfer syntax", at);
        }
        return scan_fragments(r_, options_, h_, frames_);
      }
      if (e.length == kUndefinedLength) {
        SPLINTCORE_RETURN_IF_ERROR(open_sequence(tag, implicit, e, at));
        continue;
      }
      if (depth_ == 0 && tag == kExtendedOffsetTable && e.length != kUndefinedLength &&
          h_->frames > 1) {
        SPLINTCORE_RETURN_IF_ERROR(extended_offsets(e.length, at));
        continue;
      }
      if (depth_ == 0 && tag == kPixelData) {
        h_->pixel_offset = r_.offset();
        h_->pixel_length = e.length;
        h_->have_pixels = true;
        return Status::ok();
      }
      if ((e.is_sq || implicit) && interesting(tag)) {
        SPLINTCORE_RETURN_IF_ERROR(
            push(Level{false, implicit, true, tag, r_.offset() + e.length}, at));
        continue;
      }
      Header* target = depth_ == 0 ? h_ : macro_target(tag);
      if (target != nullptr && kept_tag(tag) && !e.is_sq) {
        SPLINTCORE_RETURN_IF_ERROR(keep_value(target, tag, e.length, at));
        continue;
      }
      SPLINTCORE_RETURN_IF_ERROR(r_.skip(e.length, "a data element value"));
    }
  }

 private:
  static constexpr uint64_t kNoEnd = ~uint64_t{0};
  struct Level {
    bool item;         // an item (else a sequence)
    bool implicit;     // encoding inside (UN of undefined length is implicit VR, PS3.5 6.2.2)
    bool interesting;  // a sequence whose items are walked even when of defined length
    uint32_t tag;
    uint64_t end;  // offset past its value (defined length), else kNoEnd
  };

  bool is_group_sequence(uint32_t tag) const {
    return tag == kSharedGroups || tag == kPerFrameGroups;
  }
  // A sequence on the path to the functional group macros, if opened at the current depth.
  bool interesting(uint32_t tag) const {
    if (depth_ == 0) return is_group_sequence(tag);
    return depth_ == 2 && is_group_sequence(stack_[0].tag) && stack_[1].item &&
           (tag == kPlanePosition || tag == kPlaneOrientation || tag == kPixelMeasures ||
            tag == kPixelValueTransformation);
  }
  // Where a value inside a functional group macro's item goes (null: not interpreted).
  Header* macro_target(uint32_t tag) {
    if (depth_ != 4 || !stack_[2].interesting || !stack_[1].item || !stack_[3].item) {
      return nullptr;
    }
    switch (tag) {
      case kImagePosition:
      case kImageOrientation:
      case kPixelSpacing:
      case kSliceThickness:
      case kRescaleIntercept:
      case kRescaleSlope: return stack_[0].tag == kSharedGroups ? h_ : &frame_;
      default: return nullptr;
    }
  }

  Status push(const Level& level, uint64_t at) {
    if (depth_ == kMaxNesting) {
      return tag_error(StatusCode::kLimitExceeded, level.tag, level.item ? "Item" : "Sequence",
                       "nested too deeply", at);
    }
    if (level.end != kNoEnd && depth_ > 0 && level.end > stack_[depth_ - 1].end) {
      return tag_error(StatusCode::kParseError, level.tag, "sequence or item",
                       "its length runs past the end of the enclosing item or sequence", at);
    }
    stack_[depth_] = level;
    ++depth_;
    if (level.item && depth_ == 2 && stack_[0].tag == kPerFrameGroups) return begin_frame(at);
    if (!level.item && depth_ == 1 && level.tag == kPerFrameGroups) h_->have_per_frame = true;
    return Status::ok();
  }
  Status pop() {
    --depth_;
    if (stack_[depth_].item && depth_ == 1 && stack_[0].tag == kPerFrameGroups) return end_frame();
    return Status::ok();
  }
  // Closes the containers of defined length whose end the walk has reached.
  Status close_ended() {
    while (depth_ > 0 && stack_[depth_ - 1].end != kNoEnd &&
           r_.offset() >= stack_[depth_ - 1].end) {
      const Level& l = stack_[depth_ - 1];
      if (r_.offset() > l.end) {
        Status s = tag_error(StatusCode::kParseError, l.tag, "sequence or item",
                             "an element inside runs past its defined length, which ends at byte ",
                             r_.offset());
        s.append_u64(l.end);
        return s;
      }
      SPLINTCORE_RETURN_IF_ERROR(pop());
    }
    return Status::ok();
  }

  // Item, Item Delimitation and Sequence Delimitation (group FFFE).
  Status delimiter(uint32_t tag, uint32_t length, uint64_t at) {
    if (tag == tag_of(0xFFFE, 0xE000)) {
      if (depth_ == 0 || stack_[depth_ - 1].item) {
        return tag_error(StatusCode::kParseError, tag, "Item", "outside a sequence", at);
      }
      const Level& parent = stack_[depth_ - 1];
      if (length != kUndefinedLength && !parent.interesting) return r_.skip(length, "an item");
      const uint64_t end = length == kUndefinedLength ? kNoEnd : r_.offset() + length;
      return push(Level{true, parent.implicit, false, tag, end}, at);
    }
    if (tag == tag_of(0xFFFE, 0xE00D)) {
      if (depth_ == 0 || !stack_[depth_ - 1].item || stack_[depth_ - 1].end != kNoEnd) {
        return tag_error(StatusCode::kParseError, tag, "Item Delimitation",
                         "outside an item of undefined length", at);
      }
      return pop();
    }
    if (tag == tag_of(0xFFFE, 0xE0DD)) {
      if (depth_ == 0 || stack_[depth_ - 1].item || stack_[depth_ - 1].end != kNoEnd) {
        return tag_error(StatusCode::kParseError, tag, "Sequence Delimitation",
                         "outside a sequence of undefined length", at);
      }
      return pop();
    }
    return tag_error(StatusCode::kParseError, tag, "element", "unknown delimiter tag", at);
  }

  // An element of undefined length: a sequence (SQ, or UN or any element in implicit VR).
  Status open_sequence(uint32_t tag, bool implicit, const ElementHeader& e, uint64_t at) {
    if (depth_ == 0 && tag == kPixelData) {
      return tag_error(StatusCode::kUnsupported, tag, "Pixel Data",
                       "encapsulated (compressed) pixel data in a native transfer syntax", at);
    }
    if (!implicit && !e.is_sq && !e.is_un) {
      return tag_error(StatusCode::kParseError, tag, "element",
                       "undefined length on a VR other than SQ or UN", at);
    }
    const bool walk = !e.is_un && interesting(tag);
    return push(Level{false, implicit || e.is_un, walk, tag, kNoEnd}, at);
  }

  // The value of an element this reader keeps (kept_tag()), into *target.
  Status keep_value(Header* target, uint32_t tag, uint32_t length, uint64_t at) {
    if (length > kMaxValueBytes) {
      Status s = tag_error(StatusCode::kParseError, tag, "element", "value of ", at);
      s.append_u64(length);
      s.append(" bytes is too long");
      return s;
    }
    SPLINTCORE_RETURN_IF_ERROR(r_.fill(length));
    if (r_.available() < length) return truncated(r_, "a data element value");
    SPLINTCORE_RETURN_IF_ERROR(take_value(target, tag, r_.buf + r_.pos, length, at));
    r_.pos += length;
    // At most 65535 frames: frames x frame bytes (< 2^33) cannot overflow.
    const int64_t most = std::min<int64_t>(options_.max_dimension, 65535);
    if (tag == kNumberOfFrames && (h_->frames < 1 || h_->frames > most)) {
      Status s = tag_error(h_->frames < 1 ? StatusCode::kParseError : StatusCode::kLimitExceeded,
                           tag, "Number of Frames", "is ", at);
      s.append_i64(h_->frames);
      s.append(": must be 1 to ");
      s.append_i64(most);
      s.append(" (CtReadOptions::max_dimension)");
      return s;
    }
    return Status::ok();
  }

  // The Extended Offset Table (PS3.3 C.7.6.3.1.8): one 64-bit offset a frame, read into the
  // frames' records (pass 1; skipped in pass 0).
  Status extended_offsets(uint32_t length, uint64_t at) {
    if (uint64_t{length} != 8 * static_cast<uint64_t>(h_->frames)) {
      Status s = tag_error(StatusCode::kParseError, kExtendedOffsetTable, "Extended Offset Table",
                           "has ", at);
      s.append_u64(length);
      s.append(" bytes, 8 x Number of Frames is ");
      s.append_i64(8 * h_->frames);
      return s;
    }
    h_->extended_offsets = true;
    h_->extended_at = r_.offset();
    if (frames_ == nullptr || !encapsulated(h_->codec) || h_->frames > int64_t{capacity_}) {
      return r_.skip(length, "the Extended Offset Table");
    }
    return read_offsets(r_, frames_, static_cast<uint32_t>(h_->frames), 8,
                        "the Extended Offset Table");
  }

  // A Per-frame Functional Groups item opens: frame h_->frame_items, at byte `at`.
  Status begin_frame(uint64_t at) {
    const uint32_t i = h_->frame_items;
    if (int64_t{i} >= h_->frames) {
      Status s = tag_error(StatusCode::kParseError, kPerFrameGroups,
                           "Per-frame Functional Groups Sequence",
                           "has more items than Number of Frames (", at);
      s.append_i64(h_->frames);
      s.append(")");
      return s;
    }
    // Pass 1 has room for the frames pass 0 found: more items here, the file has grown.
    if (frames_ != nullptr && i >= capacity_) {
      return make_error(StatusCode::kParseError,
                        "the file changed between two reads: (5200,9230) Per-frame Functional "
                        "Groups Sequence has more than the ",
                        capacity_, " items read first")
          .at_byte(at);
    }
    if (i == 0) {
      shared_slope_ = h_->slope;
      shared_intercept_ = h_->intercept;
    }
    frame_ = Header();
    frame_.slope = shared_slope_;
    frame_.intercept = shared_intercept_;
    frame_at_ = at;
    return Status::ok();
  }

  // "frame i: <what>" at the frame's item.
  Status frame_error(StatusCode code, const char* what) const {
    return make_error(code, "frame ", h_->frame_items, " (item ", h_->frame_items,
                      " of (5200,9230) Per-frame Functional Groups Sequence): ", what)
        .at_byte(frame_at_);
  }

  // A Per-frame Functional Groups item closes: its position (required) and rescale kept, its
  // orientation and pixel spacing (if any) equal to the shared ones or frame 0's.
  Status end_frame() {
    const uint32_t i = h_->frame_items;
    if (!frame_.have_position) {
      return frame_error(StatusCode::kParseError,
                         "no (0020,0032) Image Position (Patient) in a (0020,9113) Plane "
                         "Position Sequence");
    }
    const double tolerance = options_.orientation_tolerance;
    if (frame_.have_orientation) {
      if (!h_->have_orientation) {
        std::memcpy(h_->orientation, frame_.orientation, sizeof(h_->orientation));
        h_->have_orientation = true;
      }
      for (int c = 0; c < 6; ++c) {
        if (!(std::fabs(frame_.orientation[c] - h_->orientation[c]) <= tolerance)) {
          return frame_error(StatusCode::kUnsupported,
                             "its Image Orientation (Patient) differs from frame 0's or the "
                             "shared one: the frames of a volume share one orientation");
        }
      }
    }
    if (frame_.have_pixel_spacing) {
      if (!h_->have_pixel_spacing) {
        std::memcpy(h_->pixel_spacing, frame_.pixel_spacing, sizeof(h_->pixel_spacing));
        h_->have_pixel_spacing = true;
      }
      for (int c = 0; c < 2; ++c) {
        if (!(std::fabs(frame_.pixel_spacing[c] - h_->pixel_spacing[c]) <= tolerance)) {
          return frame_error(StatusCode::kUnsupported,
                             "its Pixel Spacing differs from frame 0's or the shared one");
        }
      }
    }
    if (h_->slice_thickness == 0) h_->slice_thickness = frame_.slice_thickness;
    if (i == 0) {
      std::memcpy(h_->position, frame_.position, sizeof(h_->position));
      h_->slope = frame_.slope;
      h_->intercept = frame_.intercept;
    }
    if (frames_ != nullptr) {
      const double* p = frame_.position;
      frames_[i] = SliceRecord{{p[0], p[1], p[2]}, frame_.slope, frame_.intercept, 0, 0, 0};
    }
    h_->frame_items = i + 1;
    return Status::ok();
  }

  // At Pixel Data: a multi-frame image (or one with per-frame groups) has one Per-frame
  // Functional Groups item for every frame; then it has its positions.
  Status check_frames(uint64_t at) {
    if (!h_->have_per_frame && h_->frames == 1) return Status::ok();
    if (int64_t{h_->frame_items} != h_->frames) {
      Status s = make_error(StatusCode::kParseError, "Number of Frames is ", h_->frames,
                            " but the (5200,9230) Per-frame Functional Groups Sequence (the frame "
                            "positions) has ",
                            h_->frame_items, " items");
      if (!h_->have_per_frame) {
        s = make_error(StatusCode::kUnsupported, "Number of Frames is ", h_->frames,
                       " but there is no (5200,9230) Per-frame Functional Groups Sequence (the "
                       "frame positions): only enhanced multi-frame images (e.g. Enhanced CT) are "
                       "read");
      }
      return s.at_byte(at);
    }
    h_->have_position = true;
    return Status::ok();
  }

  Reader& r_;
  const CtReadOptions& options_;
  Header* h_;
  SliceRecord* frames_;
  uint32_t capacity_;
  Header frame_;  // the values of the per-frame item being read
  uint64_t frame_at_ = 0;
  double shared_slope_ = 1.0, shared_intercept_ = 0.0;
  Level stack_[kMaxNesting] = {};
  int depth_ = 0;
};

// A reader of the inflated data set of a deflated file (PS3.5 A.5: the bytes after the File
// Meta Information are one raw deflate stream), positioned where the file's reader is. Its
// offsets continue the file meta's: they are offsets in the data set as if it were not
// deflated (Pixel Data's offset is one of them). The inflater's state comes from `arena`.
struct InflatedDataSet {
  InflatingSource z;
  ByteSource source{};
  uint8_t window[kHeaderWindow];
  Reader reader;

  Status open(Reader& file, Arena& arena) {
    z.compressed = &file;
    z.stream_start = file.offset();
    z.name = file.source->name;
    SPLINTCORE_RETURN_IF_ERROR(z.inflater.begin(arena, ZFormat::kRaw));
    source = z.source();
    reader.init(&source, window, sizeof(window));
    reader.base = file.offset();
    return Status::ok();
  }
  // The stream's own error (named with its offset in the file) before the reader's.
  Status result(const Status& s) const { return z.error.is_ok() ? s : z.error; }
};

// Parses one file's header up to Pixel Data (the reader's window must hold >= 300 bytes).
// frames (room for `capacity`): where a multi-frame image's per-frame values go, or null.
Status parse_header(Reader& r, const CtReadOptions& options, Arena& arena, Header* h,
                    SliceRecord* frames, uint32_t capacity) {
  SPLINTCORE_RETURN_IF_ERROR(read_file_meta(r, h));
  if (!h->deflated) {
    DataSetWalk walk(r, options, h, frames, capacity);
    return walk.run();
  }
  ArenaScope scope(arena);
  InflatedDataSet data;
  SPLINTCORE_RETURN_IF_ERROR(data.open(r, arena));
  DataSetWalk walk(data.reader, options, h, frames, capacity);
  Status s = data.result(walk.run());
  if (!s.is_ok() && data.z.error.is_ok()) s.append(" (at an offset in the inflated data set)");
  return s;
}

// Encapsulated pixels: at least one fragment, and not absurdly more compressed bytes than the
// raw ones (a bound on the compressed frame buffer: 8 bytes a sample and 64 KiB covers the
// worst JPEG lossless code, 32 bits a sample, with every byte stuffed).
Status check_fragments(const Header& h, uint64_t raw_bytes) {
  if (h.fragments == 0) {
    return make_error(StatusCode::kParseError, "encapsulated Pixel Data has no fragment")
        .at_byte(h.pixel_offset);
  }
  const uint64_t limit = raw_bytes * 8 + 65536;
  if (h.fragment_bytes > limit) {
    return make_error(StatusCode::kLimitExceeded, "encapsulated Pixel Data has ", h.fragment_bytes,
                      " bytes of fragments, more than 8 x the raw ", raw_bytes, " bytes + 64 KiB")
        .at_byte(h.pixel_offset);
  }
  return Status::ok();
}

// Checks what a slice needs and that its pixels fit the file (not known for a deflated one).
Status check_header(const Header& h, const ByteSource& file) {
  ByteSource source = file;
  if (h.deflated) source.size = kUnknownSize;
  auto missing = [&](const char* what) {
    return make_error(StatusCode::kParseError, "missing ", what);
  };
  // What the file is, before what it lacks: a scout or a multi-frame file is not a slice.
  if (h.localizer) {
    return make_error(StatusCode::kUnsupported, "a localizer (scout) image (Image Type ",
                      h.image_type,
                      "), not a slice of a CT volume: leave it out of the series (move it out "
                      "of the folder)");
  }
  if (!h.have_rows) return missing("(0028,0010) Rows");
  if (!h.have_columns) return missing("(0028,0011) Columns");
  if (!h.have_bits_allocated) return missing("(0028,0100) Bits Allocated");
  if (!h.have_pixel_representation) return missing("(0028,0103) Pixel Representation");
  if (!h.have_position) return missing("(0020,0032) Image Position (Patient)");
  if (!h.have_orientation) return missing("(0020,0037) Image Orientation (Patient)");
  if (!h.have_pixel_spacing) return missing("(0028,0030) Pixel Spacing");
  if (h.photometric[0] == '\0') return missing("(0028,0004) Photometric Interpretation");
  if (h.rows == 0 || h.columns == 0) {
    return make_error(StatusCode::kParseError, "image of ", h.rows, " rows and ", h.columns,
                      " columns is empty");
  }
  if (h.samples != 1) {
    return make_error(StatusCode::kUnsupported, "Samples per Pixel is ", h.samples,
                      ": only grey-scale (1) is supported");
  }
  if (std::strcmp(h.photometric, "MONOCHROME1") != 0 &&
      std::strcmp(h.photometric, "MONOCHROME2") != 0) {
    return make_error(StatusCode::kUnsupported, "Photometric Interpretation ", h.photometric,
                      ": only MONOCHROME1 and MONOCHROME2 are supported");
  }
  if (h.bits_allocated != 8 && h.bits_allocated != 16) {
    return make_error(StatusCode::kUnsupported, "Bits Allocated is ", h.bits_allocated,
                      ": only 8 and 16 are supported");
  }
  const uint32_t stored = h.have_bits_stored ? h.bits_stored : h.bits_allocated;
  if (stored == 0 || stored > h.bits_allocated) {
    return make_error(StatusCode::kParseError, "Bits Stored is ", stored, " with Bits Allocated ",
                      h.bits_allocated);
  }
  if (h.have_high_bit && h.high_bit != stored - 1) {
    return make_error(StatusCode::kUnsupported, "High Bit is ", h.high_bit,
                      ": only Bits Stored - 1 is supported");
  }
  if (h.pixel_representation > 1) {
    return make_error(StatusCode::kParseError, "Pixel Representation is ", h.pixel_representation,
                      " (0 unsigned or 1 signed)");
  }
  if (!is_finite(h.slope) || h.slope == 0.0) {
    return make_error(StatusCode::kParseError, "Rescale Slope is ", h.slope,
                      ": must be finite and non-zero");
  }
  const uint64_t frame_bytes = uint64_t{h.rows} * h.columns * (h.bits_allocated / 8);
  // A multi-frame image's fragments are checked as they are mapped to frames (pass 1).
  if (encapsulated(h.codec) && h.frames > 1) return Status::ok();
  if (encapsulated(h.codec)) return check_fragments(h, frame_bytes);
  const uint64_t frames = static_cast<uint64_t>(h.frames);  // 1..65535
  const uint64_t needed = frame_bytes * frames;
  if (h.pixel_length != needed && !(needed % 2 == 1 && h.pixel_length == needed + 1)) {
    return make_error(StatusCode::kParseError, "Pixel Data has ", h.pixel_length,
                      " bytes; rows x columns x bytes per pixel",
                      frames > 1 ? " x Number of Frames" : "", " is ", needed)
        .at_byte(h.pixel_offset);
  }
  if (source.size != kUnknownSize &&
      (source.size < h.pixel_offset || source.size - h.pixel_offset < needed)) {
    return make_error(StatusCode::kTruncated, "file ends inside Pixel Data (", needed,
                      " bytes from byte ", h.pixel_offset, ", file size ", source.size, ")")
        .at_byte(source.size);
  }
  return Status::ok();
}

// Opens file `index` of the series, parses its header (a multi-frame image's per-frame values
// into frames[0, capacity) when not null), closes it.
Status read_header(const CtSeries& series, uint32_t index, const CtReadOptions& options,
                   Arena& arena, Header* h, const char** name, SliceRecord* frames = nullptr,
                   uint32_t capacity = 0) {
  ByteSource source;
  SPLINTCORE_RETURN_IF_ERROR(series.open(series.user, index, &source));
  *name = source.name;
  uint8_t window[kHeaderWindow];
  Reader r;
  r.init(&source, window, sizeof(window));
  Status s = parse_header(r, options, arena, h, frames, capacity);
  if (s.is_ok()) s = check_header(*h, source);
  if (series.close != nullptr) series.close(series.user, index, &source);
  if (!s.is_ok()) {
    s.at_index(index);
    if (*name != nullptr) s.in_file(*name);
  }
  return s;
}

bool close_to(double a, double b, double tolerance) { return std::fabs(a - b) <= tolerance; }

// Orders doubles as unsigned keys (negative values reversed).
uint64_t order_key(double v) {
  uint64_t bits;
  std::memcpy(&bits, &v, sizeof(bits));
  return (bits >> 63) != 0 ? ~bits : bits | (uint64_t{1} << 63);
}

// Bits Stored, which defaults to Bits Allocated.
uint32_t bits_stored(const Header& h) {
  return h.have_bits_stored ? h.bits_stored : h.bits_allocated;
}

// What of a slice's header differs from the series' file 0 (first), or nullptr: all slices
// share size, pixel format, pixel spacing and orientation (these two within `tolerance`).
const char* difference(const Header& h, const Header& first, double tolerance) {
  if (h.frames != first.frames) return "Number of Frames (a multi-frame file is read alone)";
  if (h.codec != first.codec || h.big_endian != first.big_endian) {
    return "transfer syntax (deflated, compressed, byte order)";
  }
  if (h.rows != first.rows || h.columns != first.columns) return "image size (Rows, Columns)";
  if (h.bits_allocated != first.bits_allocated || bits_stored(h) != bits_stored(first) ||
      h.pixel_representation != first.pixel_representation) {
    return "pixel format (Bits Allocated, Bits Stored, Pixel Representation)";
  }
  if (!close_to(h.pixel_spacing[0], first.pixel_spacing[0], tolerance) ||
      !close_to(h.pixel_spacing[1], first.pixel_spacing[1], tolerance)) {
    return "Pixel Spacing";
  }
  for (int c = 0; c < 6; ++c) {
    if (!close_to(h.orientation[c], first.orientation[c], tolerance)) {
      return "Image Orientation (Patient)";
    }
  }
  return nullptr;
}

// The stages of read_dicom_series(), sharing the series, its file 0's header, the arrays kept
// between the two passes and the geometry.
struct SeriesReader {
  const Context& ctx;
  const CtSeries& series;
  const CtReadOptions& options;
  uint32_t count = 0;
  Header first;
  const char* first_name = nullptr;
  // In the arena: the volume, then the temporaries.
  int16_t* hu = nullptr;
  SliceRecord* records = nullptr;  // of series file i
  KeyIndex* keys = nullptr;        // position along the normal; sorted after pass 1
  KeyIndex* scratch = nullptr;
  uint8_t* buffer = nullptr;  // the read chunk
  size_t chunk = 0;
  // Encapsulated pixels: the largest slice's fragments (pass 1), and their buffer.
  uint64_t max_fragment_bytes = 0;
  uint8_t* frame = nullptr;
  // The frame (from file 0's orientation), origin and spacing.
  Vec3 row, column, normal;
  Vec3 origin, spacing;
  bool rescale_varies = false;
  bool multi_frame = false;  // one file, count frames: "slices" are frames, not files
  // A stack that is not uniform along the normal: its plan, the slices' offsets (position
  // order) and the resampler pass 2 reads through (which, without a plan, reads in place).
  ResamplePlan plan;
  SliceOffset* offsets = nullptr;
  SliceResampler resampler;

  SeriesReader(const Context& c, const CtSeries& s, const CtReadOptions& o)
      : ctx(c), series(s), options(o), count(s.count) {}

  // The arrays between the passes and the read chunk (hu is allocated before).
  bool allocate_temporaries(Arena& arena) {
    records = arena.allocate_array<SliceRecord>(count);
    keys = records != nullptr ? arena.allocate_array<KeyIndex>(count) : nullptr;
    scratch = keys != nullptr ? arena.allocate_array<KeyIndex>(count) : nullptr;
    buffer = scratch != nullptr ? arena.allocate_array<uint8_t>(chunk) : nullptr;
    return buffer != nullptr;
  }

  // The axes: row and column directions of file 0, and their cross product.
  Status set_frame() {
    row = Vec3{first.orientation[0], first.orientation[1], first.orientation[2]};
    column = Vec3{first.orientation[3], first.orientation[4], first.orientation[5]};
    normal = cross(row, column);
    Status s = check_axes(&row, &column, &normal, options);
    if (!s.is_ok()) {
      Status e = make_error(s.code(), "(0020,0037) Image Orientation (Patient): ", s.message());
      e.at_index(0);
      if (first_name != nullptr) e.in_file(first_name);
      return e;
    }
    return Status::ok();
  }

  // Pass 1 of a multi-frame file (the series' only one): its header again, the frames'
  // positions and rescale into the records, frame i's pixels at frame i x its bytes.
  Status read_frames() {
    Header h;
    const char* name = first_name;
    SPLINTCORE_RETURN_IF_ERROR(
        read_header(series, 0, options, *ctx.arena, &h, &name, records, count));
    // Fewer frames than records (more: begin_frame refuses), or other pixels.
    if (h.frames != first.frames ||
        difference(h, first, options.orientation_tolerance) != nullptr) {
      return make_error(StatusCode::kParseError, "the file changed between two reads")
          .in_file(name != nullptr ? name : "?");
    }
    const bool compressed = encapsulated(first.codec);
    max_fragment_bytes = h.largest_frame;  // encapsulated: the frames are mapped
    const uint64_t frame_bytes = uint64_t{first.rows} * first.columns * (first.bits_allocated / 8);
    for (uint32_t i = 0; i < count; ++i) {
      SliceRecord& r = records[i];
      if (!compressed) r.pixel_offset = first.pixel_offset + i * frame_bytes;
      if (r.slope != records[0].slope || r.intercept != records[0].intercept) {
        rescale_varies = true;
      }
      keys[i] =
          KeyIndex{order_key(dot(Vec3{r.position[0], r.position[1], r.position[2]}, normal)), i, 0};
    }
    radix_sort(Span<KeyIndex>(keys, count), Span<KeyIndex>(scratch, count));
    return report_progress(ctx, "read DICOM headers", 1, 1);
  }

  // Pass 1: every header, checked against file 0's; then the slices in position order.
  Status read_headers() {
    if (multi_frame) return read_frames();
    for (uint32_t i = 0; i < count; ++i) {
      Header h;
      const char* name = first_name;
      if (i == 0) {
        h = first;
      } else {
        SPLINTCORE_RETURN_IF_ERROR(read_header(series, i, options, *ctx.arena, &h, &name));
        const char* differs = difference(h, first, options.orientation_tolerance);
        if (differs != nullptr) {
          Status s = make_error(StatusCode::kUnsupported, "slice differs from the series' file 0 (",
                                first_name != nullptr ? first_name : "?", ") in its ", differs);
          s.at_index(i);
          if (name != nullptr) s.in_file(name);
          return s;
        }
        if (h.slope != first.slope || h.intercept != first.intercept) rescale_varies = true;
      }
      if (h.fragment_bytes > max_fragment_bytes) max_fragment_bytes = h.fragment_bytes;
      const Vec3 p{h.position[0], h.position[1], h.position[2]};
      records[i] = SliceRecord{{p.x, p.y, p.z}, h.slope, h.intercept, h.pixel_offset, i, 0};
      keys[i] = KeyIndex{order_key(dot(p, normal)), i, 0};
      SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "read DICOM headers", i + 1, count));
    }
    radix_sort(Span<KeyIndex>(keys, count), Span<KeyIndex>(scratch, count));
    return Status::ok();
  }

  // Position of slice k (in position order).
  Vec3 position(uint32_t k) const {
    const SliceRecord& r = records[keys[k].index];
    return Vec3{r.position[0], r.position[1], r.position[2]};
  }

  // "<text>slices k and k + 1 (series files i and j) are <a><t2>[<b><t3>]", at file j.
  Status pair_error(StatusCode code, uint32_t k, const char* text, double a, const char* t2,
                    double b, const char* t3) const {
    Status e = make_error(code, text, "slices ", k, " and ", k + 1,
                          multi_frame ? " (frames " : " (series files ", keys[k].index, " and ",
                          keys[k + 1].index, ") are ");
    e.append_f64(a);
    e.append(t2);
    e.at_index(keys[k + 1].index);
    if (t3 != nullptr) {
      e.append_f64(b);
      e.append(t3);
    }
    return e;
  }

  // Consecutive slices: distinct positions along the normal.
  Status check_distinct(double d0) const {
    double previous = d0;
    for (uint32_t k = 0; k + 1 < count; ++k) {
      const double next = dot(position(k + 1), normal);
      if (!(next - previous >= options.min_spacing)) {
        return pair_error(StatusCode::kParseError, k, "duplicate slice position: ", next - previous,
                          " mm apart along the normal", 0, nullptr);
      }
      previous = next;
    }
    return Status::ok();
  }

  // Each gap within the tolerance of the mean gap.
  Status check_gaps(double d0, double mean) const {
    const double allowed_gap = allowed_deviation(options, mean);
    double previous = d0;
    for (uint32_t k = 0; k + 1 < count; ++k) {
      const double next = dot(position(k + 1), normal);
      const double gap = next - previous;
      if (!(std::fabs(gap - mean) <= allowed_gap)) {
        return pair_error(StatusCode::kUnsupported, k, "non-uniform slice spacing: ", gap,
                          " mm apart, the mean spacing is ", mean, " mm");
      }
      previous = next;
    }
    return Status::ok();
  }

  // Every slice on the normal through slice 0: no gantry tilt, no shear.
  Status check_on_normal() const {
    for (uint32_t k = 1; k < count; ++k) {
      const Vec3 delta = position(k) - origin;
      const double along = dot(delta, normal);
      const Vec3 in_plane = delta - normal * along;
      const double offset = length(in_plane);
      if (!(offset <= allowed_deviation(options, along))) {
        Status s = make_error(StatusCode::kUnsupported, "gantry tilt or sheared series: slice ", k,
                              multi_frame ? " (frame " : " (series file ", keys[k].index, ") lies ",
                              offset,
                              " mm off the normal through slice 0 (not resampled: "
                              "CtReadOptions::resample_max_gap 0)");
        s.at_index(keys[k].index);
        return s;
      }
    }
    return Status::ok();
  }

  // A multi-frame file to resample: its frames are read once, in file order, and the resampler
  // takes slices in position order, so file order must be position order. Frames stored in
  // decreasing position make it so with the normal reversed (the volume's axis_z then points
  // from the last frame to the first: a left-handed frame, which the reconstruction handles).
  // Other orders are refused.
  Status frames_in_slice_order() {
    bool ascending = true, descending = true;
    for (uint32_t k = 0; k < count; ++k) {
      ascending = ascending && keys[k].index == k;
      descending = descending && keys[k].index == count - 1 - k;
    }
    if (ascending) return Status::ok();
    if (!descending) {
      uint32_t k = 0;
      while (keys[k].index == k) ++k;
      Status s = make_error(StatusCode::kUnsupported,
                            "a multi-frame file to resample (gantry tilt, uneven spacing or "
                            "missing slices) must store its frames in slice order, ascending or "
                            "descending; frame ",
                            keys[k].index, " is slice ", k, " of ", count);
      s.at_index(keys[k].index);
      if (first_name != nullptr) s.in_file(first_name);
      return s;
    }
    normal = -normal;
    for (uint32_t k = 0; k < count - 1 - k; ++k) std::swap(keys[k], keys[count - 1 - k]);
    origin = position(0);
    return Status::ok();
  }

  // A stack that is not uniform along the normal: the slices' offsets and the plan that puts
  // them on a regular grid (the output spacing *z; the origin moved in-plane when the slices
  // are shifted), or why not.
  Status plan_grid(bool uniform, double* z) {
    Arena& arena = *ctx.arena;
    offsets = arena.allocate_array<SliceOffset>(count);
    double* gaps = offsets != nullptr ? arena.allocate_array<double>(count) : nullptr;
    if (gaps == nullptr) return arena.exhausted_status();
    for (uint32_t k = 0; k < count; ++k) {
      const Vec3 d = position(k) - origin;
      offsets[k] = SliceOffset{dot(d, normal), dot(d, row), dot(d, column)};
    }
    plan_resampling(offsets, count, uniform, spacing.x, spacing.y, options, gaps, &plan);
    if (plan.gap_too_wide) {
      const uint32_t k = plan.bad_gap;
      return pair_error(StatusCode::kUnsupported, k, "slices too far apart to resample: ",
                        offsets[k + 1].along - offsets[k].along,
                        " mm apart, more than CtReadOptions::resample_max_gap times the median "
                        "spacing ",
                        plan.median_gap, " mm (slices missing?)");
    }
    if (plan.nz > options.max_dimension) {
      return make_error(StatusCode::kLimitExceeded, "resampled onto slices ", plan.spacing_z,
                        " mm apart the series has ", plan.nz, " slices, more than the limit ",
                        options.max_dimension, " (CtReadOptions::max_dimension)");
    }
    if (plan.shift) origin = origin + row * plan.origin_x + column * plan.origin_y;
    *z = plan.spacing_z;
    return Status::ok();
  }

  // The spacing between slices: the mean gap of a uniform stack along the normal, else the
  // plan's (resample_max_gap); a single slice takes Spacing Between Slices, else Slice
  // Thickness.
  Status slice_spacing(double* z) {
    if (count == 1) {
      *z = first.spacing_between > 0 ? first.spacing_between : first.slice_thickness;
      if (!(*z > 0)) {
        Status s = make_error(StatusCode::kParseError,
                              "a single slice needs (0018,0088) Spacing Between Slices or "
                              "(0018,0050) Slice Thickness for its z spacing");
        if (first_name != nullptr) s.in_file(first_name);
        return s;
      }
      return Status::ok();
    }
    const double d0 = dot(origin, normal);
    const double span = dot(position(count - 1), normal) - d0;
    const double mean = span / static_cast<double>(count - 1);
    SPLINTCORE_RETURN_IF_ERROR(check_distinct(d0));
    const Status uneven = check_gaps(d0, mean);
    const Status tilted = check_on_normal();
    if (uneven.is_ok() && tilted.is_ok()) {
      *z = mean;
      return Status::ok();
    }
    if (!(options.resample_max_gap > 0)) return uneven.is_ok() ? tilted : uneven;
    if (multi_frame) SPLINTCORE_RETURN_IF_ERROR(frames_in_slice_order());
    return plan_grid(uneven.is_ok(), z);
  }

  // The resampler's three slices (only when there is a plan), after the other temporaries.
  Status allocate_slices(Arena& arena) {
    const uint64_t n = uint64_t{first.rows} * first.columns;
    resampler = SliceResampler{};
    resampler.plan = &plan;
    resampler.offsets = offsets;
    resampler.count = count;
    resampler.nx = first.columns;
    resampler.ny = first.rows;
    resampler.pixel_x = spacing.x;
    resampler.pixel_y = spacing.y;
    resampler.volume = hu;
    if (!plan.shift && !plan.interpolate) return Status::ok();
    int16_t* slices = arena.allocate_array<int16_t>(static_cast<size_t>(3 * n));
    if (slices == nullptr) return arena.exhausted_status();
    resampler.raw = slices;
    resampler.previous = slices + n;
    resampler.current = slices + 2 * n;
    return Status::ok();
  }

  // The buffer of a compressed frame: the largest slice's fragments, checked against the arena
  // (as the voxels were) before it is taken.
  Status allocate_frame(Arena& arena) {
    if (!encapsulated(first.codec)) return Status::ok();
    // The JPEG decoders' state (the padding their ..._arena_bytes() allow for is counted
    // by check_budget's allocations).
    uint64_t decoder = 0;
    if (first.codec == Codec::kJpegLossless) {
      decoder = jpeg_lossless_arena_bytes() - (Arena::kDefaultAlignment - 1);
    } else if (first.codec == Codec::kJpegLs) {
      decoder = jpeg_ls_arena_bytes(first.columns) - (Arena::kDefaultAlignment - 1);
    } else if (first.codec == Codec::kJpeg2000) {
      decoder = jpeg2000_arena_bytes(first.rows, first.columns, max_fragment_bytes);
    }
    SPLINTCORE_RETURN_IF_ERROR(
        check_budget(arena, 0, max_fragment_bytes + decoder,
                     first.codec == Codec::kJpegLossless || first.codec == Codec::kJpegLs ? 2 : 1));
    frame = arena.allocate_array<uint8_t>(static_cast<size_t>(max_fragment_bytes));
    return frame != nullptr ? Status::ok() : arena.exhausted_status();
  }

  // Origin (slice 0's position, or the plan's) and spacing: Pixel Spacing is row spacing, then
  // column spacing (checked first: a plan divides by them).
  Status set_geometry() {
    origin = position(0);
    spacing = Vec3{first.pixel_spacing[1], first.pixel_spacing[0], 0.0};
    const char* axis_names[3] = {"x (Pixel Spacing, column spacing)",
                                 "y (Pixel Spacing, row spacing)", "z (between slices)"};
    for (int a = 0; a < 3; ++a) {
      if (a == 2) SPLINTCORE_RETURN_IF_ERROR(slice_spacing(&spacing.z));
      Status s = check_spacing(spacing[a], axis_names[a], options);
      if (!s.is_ok()) {
        if (first_name != nullptr) s.in_file(first_name);
        return s;
      }
    }
    return Status::ok();
  }

  // The output's slices: the plan's when it interpolates, else the input's.
  uint32_t output_slices() const { return plan.interpolate ? plan.nz : count; }

  VoxelFormat pixel_format() const {
    VoxelFormat format;
    format.bytes = static_cast<uint8_t>(first.bits_allocated / 8);
    format.is_signed = first.pixel_representation == 1;
    format.big_endian = first.big_endian;
    format.bits_stored = static_cast<uint8_t>(bits_stored(first));
    return format;
  }

  void store(const VoxelFormat& format, uint64_t saturated, CtVolume* out, CtInfo* info) const {
    out->nx = first.columns;
    out->ny = first.rows;
    out->nz = output_slices();
    out->spacing = spacing;
    out->origin = origin;
    out->axis_x = row;
    out->axis_y = column;
    out->axis_z = normal;
    out->hu = hu;
    out->saturated = saturated;
    if (info == nullptr) return;
    CtInfo found;
    found.format = CtFormat::kDicom;
    found.nx = out->nx;
    found.ny = out->ny;
    found.nz = out->nz;
    found.spacing = spacing;
    describe_type(format, &found);
    found.slope = records[keys[0].index].slope;
    found.intercept = records[keys[0].index].intercept;
    found.rescale_varies = rescale_varies;
    std::memcpy(found.transfer_syntax, first.transfer_syntax, sizeof(found.transfer_syntax));
    std::memcpy(found.photometric, first.photometric, sizeof(found.photometric));
    std::memcpy(found.space, "LPS", 4);
    found.slice_count = count;
    found.saturated = saturated;
    found.resampled = plan.shift || plan.interpolate;
    found.tilt_degrees = plan.tilt_degrees;
    found.max_shift_mm = plan.max_shift_mm;
    found.max_slice_offset_mm = plan.max_offset_mm;
    *info = found;
  }
};

// Runs read(reader) with the reader at `pixel_offset` of a deflated file: past the file meta,
// then inflated up to there (an offset in the data set) and on.
template <typename Read>
Status read_deflated(Arena& arena, Reader& file, uint64_t pixel_offset, Read read) {
  Header meta;
  SPLINTCORE_RETURN_IF_ERROR(read_file_meta(file, &meta));
  ArenaScope scope(arena);
  InflatedDataSet data;
  SPLINTCORE_RETURN_IF_ERROR(data.open(file, arena));
  Reader& r = data.reader;
  Status s = pixel_offset >= r.offset()
                 ? r.skip(pixel_offset - r.offset(), "the data set before Pixel Data")
                 : make_error(StatusCode::kParseError, "the file meta information changed");
  if (s.is_ok()) s = read(r);
  return data.result(s);
}

// The pixels of a deflated file.
Status read_deflated_pixels(Arena& arena, Reader& file, const SliceRecord& rec,
                            const VoxelFormat& format, uint64_t count, int16_t* out,
                            uint64_t first_index, uint64_t* saturated) {
  return read_deflated(arena, file, rec.pixel_offset, [&](Reader& r) {
    return convert_voxels(r, format, count, rec.slope, rec.intercept, out, first_index, saturated);
  });
}

// Reads n bytes from the reader into out.
Status read_bytes(Reader& r, uint8_t* out, uint64_t n, const char* what) {
  while (n > 0) {
    SPLINTCORE_RETURN_IF_ERROR(r.fill(1));
    if (r.available() == 0) {
      return make_error(StatusCode::kTruncated, "file ends inside ", what, " (", n,
                        " more bytes expected)")
          .at_byte(r.offset());
    }
    const size_t take = r.available() < n ? r.available() : static_cast<size_t>(n);
    std::memcpy(out, r.buf + r.pos, take);
    r.pos += take;
    out += take;
    n -= take;
  }
  return Status::ok();
}

// A frame's fragments concatenated into one buffer: its bytes, and where the first kNamed
// fragments lie in the file (for an error's byte offset in the file).
struct FrameBytes {
  static constexpr uint32_t kNamed = 32;
  uint8_t* data = nullptr;
  uint64_t cap = 0;
  uint64_t size = 0;
  uint32_t fragments = 0;
  uint64_t start[kNamed] = {};  // offset in data of fragment i's first byte
  uint64_t file[kNamed] = {};   // its offset in the file

  // The decoder's offset in data as a file offset, when the fragment it falls in is known.
  bool file_offset(uint64_t at, uint64_t* out) const {
    if (fragments > kNamed) return false;
    uint32_t i = 0;
    while (i + 1 < fragments && start[i + 1] <= at) ++i;
    *out = file[i] + (at - start[i]);
    return true;
  }
};

// One fragment item (its header at the reader) appended to f; *end set at the sequence
// delimiter.
Status read_fragment(Reader& r, FrameBytes* f, bool* end) {
  uint32_t tag = 0, length = 0;
  const uint64_t at = r.offset();
  SPLINTCORE_RETURN_IF_ERROR(read_item_header(r, &tag, &length));
  *end = tag == tag_of(0xFFFE, 0xE0DD);
  if (*end) return Status::ok();
  if (tag != tag_of(0xFFFE, 0xE000) || length > f->cap - f->size) {
    return make_error(StatusCode::kParseError,
                      "Pixel Data differs from the first read (file changed?)")
        .at_byte(at);
  }
  if (f->fragments < FrameBytes::kNamed) {
    f->start[f->fragments] = f->size;
    f->file[f->fragments] = r.offset();
  }
  ++f->fragments;
  SPLINTCORE_RETURN_IF_ERROR(read_bytes(r, f->data + f->size, length, "a Pixel Data fragment"));
  f->size += length;
  return Status::ok();
}

// The fragments of a file's encapsulated Pixel Data, concatenated (the reader at the basic
// offset table).
Status read_fragments(Reader& r, FrameBytes* f) {
  uint32_t tag = 0, length = 0;
  const uint64_t table_at = r.offset();
  SPLINTCORE_RETURN_IF_ERROR(read_item_header(r, &tag, &length));
  if (tag != tag_of(0xFFFE, 0xE000) || length == kUndefinedLength) {
    return make_error(StatusCode::kParseError,
                      "Pixel Data differs from the first read (file changed?)")
        .at_byte(table_at);
  }
  SPLINTCORE_RETURN_IF_ERROR(r.skip(length, "the basic offset table"));
  for (bool end = false;;) {
    SPLINTCORE_RETURN_IF_ERROR(read_fragment(r, f, &end));
    if (end) return Status::ok();
  }
}

// A frame's concatenated fragments decoded into the slice's own memory as 16-bit little-endian
// samples, then converted there to HU (each value is read before its HU overwrites it).
Status decode_frame(const SeriesReader& sr, const FrameBytes& f, const SliceRecord& rec,
                    const VoxelFormat& format, int16_t* out, uint64_t first_index,
                    uint64_t* saturated) {
  const uint32_t rows = sr.first.rows, columns = sr.first.columns;
  uint8_t* samples = reinterpret_cast<uint8_t*>(out);
  const size_t n = static_cast<size_t>(f.size);
  const uint32_t bits = sr.first.bits_allocated;
  Status s;
  if (sr.first.codec == Codec::kRle) {
    s = rle_decode_frame(f.data, n, rows, columns, bits / 8, samples);
  } else if (sr.first.codec == Codec::kJpegLs) {
    s = jpeg_ls_decode(*sr.ctx.arena, f.data, n, rows, columns, bits, samples);
  } else if (sr.first.codec == Codec::kJpeg2000) {
    s = jpeg2000_decode(*sr.ctx.arena, f.data, n, rows, columns, bits, samples);
  } else {
    s = jpeg_lossless_decode(*sr.ctx.arena, f.data, n, rows, columns, bits, samples);
  }
  if (!s.is_ok()) {
    uint64_t at = 0;
    if (f.file_offset(s.byte_offset(), &at)) return s.at_byte(at);
    return s.append(" (byte offset in the concatenated fragments)");
  }
  const uint64_t count = uint64_t{rows} * columns;
  ByteSource none;
  Reader decoded;
  decoded.init(&none, samples, static_cast<size_t>(count * 2));
  decoded.end = decoded.cap;
  decoded.at_eof = true;
  VoxelFormat v = format;
  v.bytes = 2;
  v.big_endian = false;
  return convert_voxels(decoded, v, count, rec.slope, rec.intercept, out, first_index, saturated);
}

// The pixels of an encapsulated single-frame file: all its fragments are its frame.
Status read_encapsulated_pixels(const SeriesReader& sr, Reader& r, const SliceRecord& rec,
                                const VoxelFormat& format, int16_t* out, uint64_t first_index,
                                uint64_t* saturated) {
  SPLINTCORE_RETURN_IF_ERROR(r.skip(rec.pixel_offset, "the header before Pixel Data"));
  FrameBytes f;
  f.data = sr.frame;
  f.cap = sr.max_fragment_bytes;
  SPLINTCORE_RETURN_IF_ERROR(read_fragments(r, &f));
  return decode_frame(sr, f, rec, format, out, first_index, saturated);
}

// Frame i (file order) of an encapsulated multi-frame file, the reader at its first fragment
// item, decoded into `out`; errors say which frame.
Status read_encapsulated_frame(const SeriesReader& sr, Reader& r, uint32_t i,
                               const VoxelFormat& format, int16_t* out, uint64_t first_index,
                               uint64_t* saturated) {
  const SliceRecord& rec = sr.records[i];
  FrameBytes f;
  f.data = sr.frame;
  f.cap = sr.max_fragment_bytes;
  Status s = r.offset() == rec.pixel_offset
                 ? Status::ok()
                 : make_error(StatusCode::kParseError,
                              "Pixel Data differs from the first read (file changed?)")
                       .at_byte(r.offset());
  for (uint32_t k = 0; s.is_ok() && k < rec.fragments; ++k) {
    bool end = false;
    s = read_fragment(r, &f, &end);
    if (s.is_ok() && end) {
      s = make_error(StatusCode::kParseError,
                     "Pixel Data differs from the first read (file changed?)")
              .at_byte(r.offset() - 8);
    }
  }
  if (s.is_ok()) s = decode_frame(sr, f, rec, format, out, first_index, saturated);
  if (s.is_ok()) return s;
  Status e = make_error(s.code(), "frame ", i, " (of ", sr.count, ", ", rec.fragments,
                        " fragment item(s) from byte ", rec.pixel_offset, "): ", s.message());
  e.at_index(i);
  if (s.byte_offset() != kNoPosition) e.at_byte(s.byte_offset());
  return e;
}

// The frames of a multi-frame file in file order (the reader at the first: its pixels, or its
// first fragment item), each read into the slice the resampler gives for its place in position
// order (with a plan the frames are in position order: file order is position order).
Status convert_frames(SeriesReader& sr, Reader& r, const VoxelFormat& format, uint64_t* saturated) {
  const uint64_t per_slice = uint64_t{sr.first.rows} * sr.first.columns;
  const bool compressed = encapsulated(sr.first.codec);
  SliceResampler& resampler = sr.resampler;
  for (uint32_t i = 0; i < sr.count; ++i) {
    const SliceRecord& rec = sr.records[i];
    const uint32_t k = sr.scratch[i].index;
    int16_t* slice = resampler.target(k);
    SPLINTCORE_RETURN_IF_ERROR(
        compressed ? read_encapsulated_frame(sr, r, i, format, slice, k * per_slice, saturated)
                   : convert_voxels(r, format, per_slice, rec.slope, rec.intercept, slice,
                                    k * per_slice, saturated));
    resampler.place(k);
    SPLINTCORE_RETURN_IF_ERROR(report_progress(sr.ctx, "read DICOM pixels", i + 1, sr.count));
  }
  return Status::ok();
}

// Pass 2 of a multi-frame file: its Pixel Data read once, front to back (the data set inflated
// when deflated: the pixel offset is one in the inflated data set).
Status read_frame_pixels(SeriesReader& sr, const VoxelFormat& format, uint64_t* saturated) {
  for (uint32_t k = 0; k < sr.count; ++k) sr.scratch[sr.keys[k].index].index = k;
  ByteSource source;
  SPLINTCORE_RETURN_IF_ERROR(sr.series.open(sr.series.user, 0, &source));
  Reader r;
  r.init(&source, sr.buffer, sr.chunk);
  auto convert = [&](Reader& at_pixels) {
    return convert_frames(sr, at_pixels, format, saturated);
  };
  // Encapsulated: from the first frame's first fragment item (frame 0 in file order).
  const uint64_t start =
      encapsulated(sr.first.codec) ? sr.records[0].pixel_offset : sr.first.pixel_offset;
  Status s = sr.first.deflated ? read_deflated(*sr.ctx.arena, r, start, convert)
                               : r.skip(start, "the header before Pixel Data");
  if (s.is_ok() && !sr.first.deflated) s = convert(r);
  const char* name = source.name;
  if (sr.series.close != nullptr) sr.series.close(sr.series.user, 0, &source);
  if (!s.is_ok() && name != nullptr) s.in_file(name);
  return s;
}

// Pass 2: the pixels, slice by slice in position order, each with its own rescale, through
// the resampler (in place when there is no plan). Not a SeriesReader method: cppcheck 2.10
// takes a Reader local to a method for a non-local one (a false danglingLifetime on
// r.init(&source, ...)).
Status read_pixels(SeriesReader& sr, const VoxelFormat& format, uint64_t* saturated) {
  if (sr.multi_frame) return read_frame_pixels(sr, format, saturated);
  const uint64_t per_slice = uint64_t{sr.first.rows} * sr.first.columns;
  for (uint32_t k = 0; k < sr.count; ++k) {
    const SliceRecord& rec = sr.records[sr.keys[k].index];
    int16_t* slice = sr.resampler.target(k);
    ByteSource source;
    SPLINTCORE_RETURN_IF_ERROR(sr.series.open(sr.series.user, rec.file, &source));
    Reader r;
    r.init(&source, sr.buffer, sr.chunk);
    Status s;
    if (encapsulated(sr.first.codec)) {
      s = read_encapsulated_pixels(sr, r, rec, format, slice, k * per_slice, saturated);
    } else if (sr.first.deflated) {
      s = read_deflated_pixels(*sr.ctx.arena, r, rec, format, per_slice, slice, k * per_slice,
                               saturated);
    } else {
      s = r.skip(rec.pixel_offset, "the header before Pixel Data");
      if (s.is_ok()) {
        s = convert_voxels(r, format, per_slice, rec.slope, rec.intercept, slice, k * per_slice,
                           saturated);
      }
    }
    const char* name = source.name;
    if (sr.series.close != nullptr) sr.series.close(sr.series.user, rec.file, &source);
    if (!s.is_ok()) {
      if (name != nullptr) s.in_file(name);
      return s;
    }
    sr.resampler.place(k);
    SPLINTCORE_RETURN_IF_ERROR(report_progress(sr.ctx, "read DICOM pixels", k + 1, sr.count));
  }
  return Status::ok();
}

// One read of the series with room for `planned` slices. When the stack is resampled onto
// more slices, *needed says how many (nothing is left in the arena, *out untouched) unless
// `last` (the second read, which planned for what the first found: the files changed).
Status read_attempt(SeriesReader& reader, uint32_t planned, bool last, CtVolume* out, CtInfo* info,
                    uint32_t* needed) {
  Arena& arena = *reader.ctx.arena;
  const Header& first = reader.first;
  const uint32_t count = reader.count;
  uint64_t voxel_bytes = 0;
  SPLINTCORE_RETURN_IF_ERROR(
      check_size(first.columns, first.rows, planned, reader.options, &voxel_bytes));
  reader.chunk = chunk_size(reader.options);
  // Deflated files: an inflater per file read (the padding inflate_state_bytes() allows for is
  // counted by check_budget's allocations).
  const uint64_t inflater =
      first.deflated ? inflate_state_bytes() - (Arena::kDefaultAlignment - 1) : 0;
  const uint64_t temporaries =
      uint64_t{count} * (sizeof(SliceRecord) + 2 * sizeof(KeyIndex)) + reader.chunk + inflater;
  SPLINTCORE_RETURN_IF_ERROR(check_budget(arena, voxel_bytes, temporaries, first.deflated ? 5 : 4));

  ArenaScope scope(arena);  // on an error the arena is as it was
  reader.hu = arena.allocate_array<int16_t>(static_cast<size_t>(voxel_bytes / 2));
  if (reader.hu == nullptr) return arena.exhausted_status();
  uint32_t slices = 0;
  {
    ArenaScope temporaries_scope(arena);  // rewound also on success: only the voxels stay
    if (!reader.allocate_temporaries(arena)) return arena.exhausted_status();
    SPLINTCORE_RETURN_IF_ERROR(reader.set_frame());
    SPLINTCORE_RETURN_IF_ERROR(reader.read_headers());
    SPLINTCORE_RETURN_IF_ERROR(reader.allocate_frame(arena));
    SPLINTCORE_RETURN_IF_ERROR(reader.set_geometry());
    slices = reader.output_slices();
    if (slices > planned) {
      if (last) {
        return make_error(StatusCode::kParseError,
                          "the series' files changed between two reads (resampled onto ", slices,
                          " slices, then more)");
      }
      *needed = slices;
      return Status::ok();
    }
    SPLINTCORE_RETURN_IF_ERROR(reader.allocate_slices(arena));
    const VoxelFormat format = reader.pixel_format();
    uint64_t saturated = 0;
    SPLINTCORE_RETURN_IF_ERROR(read_pixels(reader, format, &saturated));
    reader.store(format, saturated, out, info);
  }
  // Fewer slices than planned: the rest given back (the voxels are the top allocation now).
  arena.try_shrink(reader.hu, static_cast<size_t>(voxel_bytes),
                   static_cast<size_t>(uint64_t{slices} * first.rows * first.columns * 2));
  scope.commit();
  return Status::ok();
}

}  // namespace

Status read_dicom_series(const Context& ctx, const CtSeries& series, const CtReadOptions& options,
                         CtVolume* out, CtInfo* info) {
  Arena& arena = *ctx.arena;
  if (series.count == 0 || series.open == nullptr) {
    return make_error(StatusCode::kInvalidArgument, "the DICOM series has no files");
  }
  if (series.count > options.max_dimension) {
    return make_error(StatusCode::kLimitExceeded, "the series has ", series.count,
                      " files, more than the limit ", options.max_dimension,
                      " (CtReadOptions::max_dimension)");
  }
  SeriesReader reader(ctx, series, options);
  const Header& first = reader.first;
  SPLINTCORE_RETURN_IF_ERROR(
      read_header(series, 0, options, arena, &reader.first, &reader.first_name));
  if (first.frames > 1) {  // an enhanced multi-frame image: its frames are the slices
    if (series.count != 1) {
      Status s = make_error(StatusCode::kUnsupported, "a multi-frame image (", first.frames,
                            " frames) in a series of ", series.count,
                            " files: give a multi-frame file alone");
      s.at_index(0);
      return s.in_file(reader.first_name);  // in_file ignores a null name
    }
    reader.multi_frame = true;
    reader.count = static_cast<uint32_t>(first.frames);  // <= max_dimension (checked)
  }
  // A stack resampled onto more slices than it has is read again with room for them.
  uint32_t needed = 0;
  SeriesReader second = reader;
  SPLINTCORE_RETURN_IF_ERROR(read_attempt(reader, reader.count, false, out, info, &needed));
  if (needed == 0) return Status::ok();
  return read_attempt(second, needed, true, out, info, &needed);
}

}  // namespace splintcore
