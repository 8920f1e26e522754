// DICOM RLE Lossless decoder. Source: DICOM PS3.5 Annex G (RLE compression): G.3.1 the
// PackBits byte segments (a header byte n: 0..127 copies the next n + 1 bytes, -1..-127
// repeats the next byte 1 - n times, -128 does nothing; each row encoded on its own), G.4 and
// G.5 the RLE header (16 little-endian 32-bit values: the number of segments, at most 15, and
// the offset of each segment from the header's start) and the segment order (byte planes, the
// most significant first, per sample). Decodes straight into the caller's slice buffer.
#include "ct/dicom_rle.h"

namespace splintcore {
namespace ct_detail {

namespace {

constexpr size_t kRleHeaderBytes = 64;
constexpr uint32_t kMaxSegments = 15;

uint32_t le32(const uint8_t* p) {
  return uint32_t{p[0]} | (uint32_t{p[1]} << 8) | (uint32_t{p[2]} << 16) | (uint32_t{p[3]} << 24);
}

Status segment_error(uint32_t segment, const char* what, uint64_t at) {
  return make_error(StatusCode::kParseError, "RLE segment ", segment, ": ", what).at_byte(at);
}

}  // namespace

Status packbits_decode(const uint8_t* in, size_t size, uint64_t base, uint32_t segment,
                       uint32_t rows, uint32_t columns, uint8_t* out, size_t stride) {
  size_t pos = 0;
  for (uint32_t row = 0; row < rows; ++row) {
    uint32_t column = 0;
    while (column < columns) {
      if (pos >= size) {
        Status s = segment_error(segment, "ends early, in row ", base + pos);
        s.append_u64(row);
        s.append(" of ");
        s.append_u64(rows);
        s.append(" (output short)");
        return s;
      }
      const uint8_t n = in[pos];
      if (n == 0x80) {  // -128: a no-op
        ++pos;
        continue;
      }
      const uint32_t count = n < 0x80 ? uint32_t{n} + 1 : 257u - n;
      if (count > columns - column) {
        Status s = segment_error(segment, "a run of ", base + pos);
        s.append_u64(count);
        s.append(" bytes passes the end of row ");
        s.append_u64(row);
        return s;
      }
      const size_t need = n < 0x80 ? count : 1;
      if (size - pos - 1 < need) {
        return segment_error(segment, "ends inside a run (output short)", base + size);
      }
      uint8_t* o = out + (uint64_t{row} * columns + column) * stride;
      const uint8_t* src = in + pos + 1;
      for (uint32_t i = 0; i < count; ++i) o[i * stride] = n < 0x80 ? src[i] : src[0];
      pos += 1 + need;
      column += count;
    }
  }
  // After the last row: no-op headers, and a pad byte to an even length.
  while (pos < size && in[pos] == 0x80) ++pos;
  if (size - pos > 1) {
    return segment_error(segment, "more data after the last row (output long)", base + pos);
  }
  return Status::ok();
}

Status rle_decode_frame(const uint8_t* frame, size_t size, uint32_t rows, uint32_t columns,
                        uint32_t bytes_per_sample, uint8_t* out) {
  if (size < kRleHeaderBytes) {
    return make_error(StatusCode::kParseError, "RLE frame of ", size,
                      " bytes is shorter than its 64-byte header")
        .at_byte(size);
  }
  const uint32_t segments = le32(frame);
  if (segments > kMaxSegments) {
    return make_error(StatusCode::kParseError, "RLE header: ", segments,
                      " segments, more than the 15 allowed")
        .at_byte(0);
  }
  if (segments != bytes_per_sample) {
    return make_error(StatusCode::kParseError, "RLE header: ", segments, " segments, expected ",
                      bytes_per_sample, " (one per byte of a sample)")
        .at_byte(0);
  }
  uint32_t offsets[kMaxSegments + 1];
  for (uint32_t i = 0; i < segments; ++i) offsets[i] = le32(frame + 4 + 4 * i);
  offsets[segments] = size > 0xFFFFFFFFu ? 0xFFFFFFFFu : static_cast<uint32_t>(size);
  for (uint32_t i = 0; i < segments; ++i) {
    const uint32_t low = i == 0 ? kRleHeaderBytes : offsets[i - 1];
    if (offsets[i] < low || offsets[i] > size) {
      Status s =
          make_error(StatusCode::kParseError, "RLE header: segment ", i, " offset ", offsets[i]);
      s.append(offsets[i] > size ? " is past the frame's end" : " is out of order");
      s.append(i == 0 ? " (the first segment starts at 64 or later)" : "");
      return s.at_byte(4 + 4 * uint64_t{i});
    }
  }
  const uint64_t samples = uint64_t{rows} * columns;
  // Every sample's high byte is written by its own plane, or zero for 8-bit samples.
  if (bytes_per_sample == 1) {
    for (uint64_t k = 0; k < samples; ++k) out[2 * k + 1] = 0;
  }
  for (uint32_t i = 0; i < segments; ++i) {
    // Plane i is byte (bytes_per_sample - 1 - i) of each little-endian sample.
    uint8_t* plane = out + (bytes_per_sample - 1 - i);
    SPLINTCORE_RETURN_IF_ERROR(packbits_decode(frame + offsets[i], offsets[i + 1] - offsets[i],
                                               offsets[i], i, rows, columns, plane, 2));
  }
  return Status::ok();
}

}  // namespace ct_detail
}  // namespace splintcore
