// Shared parts of the CT readers (src/ct/ct_*.cpp): a windowed byte reader over a ByteSource,
// text-header lines, locale-free number parsing, the arena budget check, and the voxel
// conversion stored value -> HU (DICOM PS3.3 C.11.1.1.2 Modality LUT: HU = m * SV + b).
#ifndef SPLINTCORE_SRC_CT_CT_COMMON_H
#define SPLINTCORE_SRC_CT_CT_COMMON_H

#include "io/reader.h"
#include "splintcore/compress.h"
#include "splintcore/ct.h"

namespace splintcore {
namespace ct_detail {

constexpr size_t kHeaderWindow = 1024;  // stack window for headers
constexpr size_t kLineCapacity = 512;   // longest header line kept (longer lines: flagged)

// The window over a ByteSource (io/reader.h) with what the CT readers add: a start, a larger
// buffer, skips and header lines. The buffer is the caller's (a stack array for headers, an
// arena chunk for voxels).
struct Reader : meshio::Reader {
  void init(const ByteSource* s, uint8_t* buffer, size_t capacity) {
    source = s;
    buf = buffer;
    cap = capacity;
    pos = end = 0;
    base = 0;
    at_eof = false;
  }
  // Moves the unread bytes into a new (larger) buffer.
  void rebuffer(uint8_t* buffer, size_t capacity);
  // Skips n bytes; kTruncated (with `what`) if the source ends first.
  Status skip(uint64_t n, const char* what);
  // Reads one text line (without "\n" or "\r\n") into line[0..kLineCapacity); *length is the
  // kept length, *too_long set when the line was longer (the rest is consumed). *got_line false
  // at the end of input. Lines count toward `budget` (kLimitExceeded when spent).
  Status read_line(char* line, size_t* length, bool* too_long, bool* got_line, uint64_t* budget);
};

// Names the file on an error (source name when set).
Status in_source(Status s, const ByteSource& source);

// Text helpers (ASCII only, no locale).
bool equal_nocase(const char* a, size_t an, const char* b);
void trim(const char** text, size_t* length);
// Parses a decimal number (optional sign, digits, point, exponent; no inf/nan/hex). The whole
// text must be the number (after trimming spaces).
bool parse_double(const char* text, size_t length, double* out);
bool parse_i64(const char* text, size_t length, int64_t* out);
// Splits on spaces/tabs (and on `extra`, e.g. ',' or '\\'), parsing up to `max` numbers;
// *count is how many were found (fails on a bad number or more than max).
bool parse_doubles(const char* text, size_t length, char extra, double* out, size_t max,
                   size_t* count);

// A sample type's name in a text header (MetaImage's ElementType, NRRD's type) and its voxels.
struct TypeName {
  const char* name;
  uint8_t bytes;
  bool is_signed;
  bool is_float;
};

// One "Key = Value" (MetaImage) or "field: value" (NRRD) header line, both parts trimmed.
struct KeyValue {
  const char* key;
  size_t key_length;
  const char* value;
  size_t value_length;

  // line[0, length) split at its separator, line[at] (at < length).
  static KeyValue split(const char* line, size_t length, size_t at) {
    KeyValue kv{line, at, line + at + 1, length - at - 1};
    trim(&kv.key, &kv.key_length);
    trim(&kv.value, &kv.value_length);
    return kv;
  }
  bool is(const char* name) const { return equal_nocase(key, key_length, name); }
  bool value_is(const char* v) const { return equal_nocase(value, value_length, v); }
  // Exactly `wanted` numbers, apart by spaces or tabs.
  bool numbers(double* out, size_t wanted) const {
    size_t count = 0;
    return parse_doubles(value, value_length, '\0', out, wanted, &count) && count == wanted;
  }
};

// A text header (MetaImage, NRRD) read a line at a time in a fixed window of its own; errors
// name the source and the line.
struct HeaderLines {
  const ByteSource& source;
  uint8_t window[kHeaderWindow];
  char line[kLineCapacity] = {};
  Reader reader;
  uint64_t budget;  // the header bytes still allowed (CtReadOptions::max_header_bytes)
  uint64_t line_no = 0;

  HeaderLines(const ByteSource& s, const CtReadOptions& options)
      : source(s), budget(options.max_header_bytes) {
    reader.init(&source, window, sizeof(window));
  }
  HeaderLines(const HeaderLines&) = delete;
  HeaderLines& operator=(const HeaderLines&) = delete;

  Status fail(Status s) const {
    s.at_line(line_no);
    return in_source(s, source);
  }
  // "bad <what> "<value>"" at the line.
  Status bad(const KeyValue& kv, const char* what) const {
    return fail(make_error(StatusCode::kParseError, "bad ", what, " \"")
                    .append(kv.value, kv.value_length)
                    .append("\""));
  }
  // The next line into line[0, *length), as Reader::read_line, counted in line_no.
  Status next_line(size_t* length, bool* too_long, bool* got) {
    const Status s = reader.read_line(line, length, too_long, got, &budget);
    ++line_no;
    return s.is_ok() ? s : fail(s);
  }
  // The error for a line that read_line flagged too long.
  Status line_too_long() const {
    return fail(
        make_error(StatusCode::kParseError, "line longer than ", kLineCapacity - 1, " characters"));
  }
};

// Checks the volume's size against the limits and computes the voxel bytes.
Status check_size(uint64_t nx, uint64_t ny, uint64_t nz, const CtReadOptions& options,
                  uint64_t* voxel_bytes);
// Checks need (voxel bytes + temporaries, with 16 bytes of alignment per allocation) against
// the arena's free space: kArenaExhausted naming it.
Status check_budget(const Arena& arena, uint64_t voxel_bytes, uint64_t temporaries,
                    uint32_t allocations);
// Spacing sanity: finite, > 0, within [min_spacing, max_spacing].
Status check_spacing(double value, const char* axis, const CtReadOptions& options);
// Unit and orthogonal within tolerance; normalises the three in place.
Status check_axes(Vec3* x, Vec3* y, Vec3* z, const CtReadOptions& options);

// Voxel format of stored values.
struct VoxelFormat {
  uint8_t bytes = 2;  // 1, 2, 4 or 8
  bool is_signed = true;
  bool is_float = false;
  bool big_endian = false;
  uint8_t bits_stored = 0;  // integers: low bits kept (0: all), sign-extended when signed
};

// Fills info->stored_type from the format.
void describe_type(const VoxelFormat& format, CtInfo* info);

// Reads `count` stored values from the reader (refilling its buffer) and converts them to HU
// into out[0..count). first_index numbers the voxels in kNonFinite messages; a short source is
// kTruncated at the offset where it ended.
Status convert_voxels(Reader& reader, const VoxelFormat& format, uint64_t count, double slope,
                      double intercept, int16_t* out, uint64_t first_index, uint64_t* saturated);

// HU of one value (exposed for tests): slope * v + intercept, rounded half away from zero,
// saturated (sets *clamped).
int16_t to_hu(double value, double slope, double intercept, bool* clamped);

// Closes an opened file at scope exit.
struct OpenedFile {
  const CtFileOpener* opener = nullptr;
  ByteSource source{};
  bool open = false;
  ~OpenedFile() {
    if (open && opener->close != nullptr) opener->close(opener->user, &source);
  }
};

// The arena chunk for voxel data: chunk_bytes rounded down to a multiple of 8, at least
// kHeaderWindow (attached data already in the header window moves into it).
size_t chunk_size(const CtReadOptions& options);

// Voxel data of a text-header format (NRRD, MetaImage): attached (continuing `header`, which
// is positioned right after the header) or detached (data_file opened through `opener`).
struct RawData {
  VoxelFormat format{};
  uint32_t nx = 0, ny = 0, nz = 0;
  const char* data_file = nullptr;  // null: attached
  uint64_t line_skip = 0;           // lines skipped before byte_skip
  int64_t byte_skip = 0;            // -1: the data ends the file (needs a known size)
  bool gzip = false;  // the data is a gzip stream (NRRD encoding gzip); byte skip counts
                      // inflated bytes, line skip the file's
};

// A ByteSource of the bytes inflated from a deflate stream read through `compressed`: the
// voxels stream through the inflater, never held compressed. Errors of the stream are kept in
// `error` (read() then returns -1) with byte offsets in the file.
struct InflatingSource {
  Reader* compressed = nullptr;
  Inflater inflater;
  uint64_t stream_start = 0;  // file offset of the stream's first byte
  Status error;
  const char* name = nullptr;
  static int64_t read(void* user, uint8_t* buffer, size_t capacity);
  ByteSource source();
};

// Checks limits and the arena budget, allocates the voxels (left in the arena on success:
// *hu), reads and converts them; everything else is rewound. Errors name the data's file.
Status read_raw_volume(const Context& ctx, Reader& header, const ByteSource& header_source,
                       const CtFileOpener* opener, const RawData& data,
                       const CtReadOptions& options, int16_t** hu, uint64_t* saturated);

// What a text header (NRRD, MetaImage) describes: the voxel data and the geometry.
struct TextVolume {
  RawData data{};
  Vec3 spacing{1, 1, 1};
  Vec3 origin{0, 0, 0};
  Vec3 axes[3] = {Vec3{1, 0, 0}, Vec3{0, 1, 0}, Vec3{0, 0, 1}};
  uint64_t geometry_line = kNoPosition;  // the header line spacing and axes errors name
};

// The end of a text-header read: checks the spacing and the axes (normalising the axes), reads
// the voxels (read_raw_volume), then fills *out and, when info is not null, *info (`found`,
// which holds what the header said, completed with the size and the stored type).
Status read_text_volume(const Context& ctx, Reader& header, const ByteSource& header_source,
                        const CtFileOpener* opener, const CtReadOptions& options,
                        const TextVolume& volume, CtInfo found, CtVolume* out, CtInfo* info);

// ---- JPEG marker segments ------------------------------------------------------------------
// The marker syntax of ITU-T T.81 Annex B (B.1.1.2 markers, any 0xFF fill bytes before them;
// B.1.1.4 segment lengths; B.2.2 the frame header), which T.87 Annex C keeps for JPEG-LS:
// shared by the JPEG lossless (jpeg_lossless.cpp) and JPEG-LS (jpeg_ls.cpp) decoders, and its
// segment lengths by JPEG 2000 (T.800 A.1.3). Errors start with `codec` ("JPEG lossless",
// "JPEG-LS", "JPEG 2000") and give the byte offset in data.

// A frame header (SOFn) of one component.
struct JpegFrameHeader {
  uint32_t precision = 0, rows = 0, columns = 0, component = 0;
  bool read = false;
};

// The walk over data[0, size): pos is the next byte to read.
struct JpegMarkers {
  const uint8_t* data;
  size_t size;
  const char* codec;
  size_t pos = 0;

  uint32_t u8(size_t at) const { return data[at]; }
  uint32_t u16(size_t at) const { return (uint32_t{data[at]} << 8) | data[at + 1]; }
  Status error(StatusCode code, const char* what, uint64_t at) const;
  // The SOI marker at the start (pos moves past it); else "not a <stream> stream".
  Status start(const char* stream);
  // The marker at pos (after any 0xFF fill bytes): *code its second byte, *at its offset.
  Status next_marker(uint32_t* code, size_t* at);
  // The segment whose marker is at `at` (pos after the marker): its length (at least 2, the
  // segment inside the data) and *body, its first byte after the length; pos moves past it.
  Status segment(size_t at, uint32_t* length, size_t* body);
  // A frame header (`name`: "SOF3", "SOF55") of one component, precision 2..16; a second one is
  // an error. Sizes of 0 are the caller's to judge. kParseError, kUnsupported, kTruncated.
  Status frame(size_t at, const char* name, JpegFrameHeader* f);
  // The frame's size is the DICOM Columns x Rows, its precision at most Bits Allocated.
  Status check_frame(size_t at, const char* name, const JpegFrameHeader& f, uint32_t rows,
                     uint32_t columns, uint32_t max_precision) const;
};

}  // namespace ct_detail
}  // namespace splintcore

#endif  // SPLINTCORE_SRC_CT_CT_COMMON_H
