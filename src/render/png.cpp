// PNG encoder (include/splintcore/render.h).
//
// Sources: ISO/IEC 15948:2003 (PNG, also W3C "Portable Network Graphics Specification, Second
// Edition"): chunk layout, IHDR, the five row filters and Paeth's predictor (A. W. Paeth,
// "Image file compression made easy", Graphics Gems II, 1991), the minimum-sum-of-absolute-
// differences filter heuristic (section 12.8); RFC 1950 (zlib stream, Adler-32); RFC 1951
// (deflate: fixed Huffman codes, section 3.2.6; length and distance codes, 3.2.5) with a greedy
// LZ77 matcher over hash chains as described in section 4 of RFC 1951; CRC-32 of ISO 3309 /
// ITU-T V.42 (PNG Annex D).
//
// Deterministic: integer arithmetic only; the matcher's choices depend only on the bytes.
#include <cstring>

#include "splintcore/render.h"

namespace splintcore {
namespace {

struct CrcTable {
  uint32_t entry[256];
  constexpr CrcTable() : entry() {
    for (uint32_t n = 0; n < 256; ++n) {
      uint32_t c = n;
      for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
      entry[n] = c;
    }
  }
};
constexpr CrcTable kCrc;

constexpr size_t kOutCapacity = 65536;  // bytes of one IDAT chunk's data
constexpr uint32_t kHashBits = 16;
constexpr uint32_t kWindow = 32768;
constexpr uint32_t kMaxChain = 64;
constexpr uint32_t kMinMatch = 3;
constexpr uint32_t kMaxMatch = 258;
constexpr uint32_t kMaxInsert = 32;

const uint16_t kLengthBase[29] = {3,  4,  5,  6,  7,  8,  9,  10, 11,  13,  15,  17,  19,  23, 27,
                                  31, 35, 43, 51, 59, 67, 83, 99, 115, 131, 163, 195, 227, 258};
const uint8_t kLengthExtra[29] = {0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2,
                                  2, 3, 3, 3, 3, 4, 4, 4, 4, 5, 5, 5, 5, 0};
const uint16_t kDistBase[30] = {1,    2,    3,    4,    5,    7,    9,    13,    17,    25,
                                33,   49,   65,   97,   129,  193,  257,  385,   513,   769,
                                1025, 1537, 2049, 3073, 4097, 6145, 8193, 12289, 16385, 24577};
const uint8_t kDistExtra[30] = {0, 0, 0, 0, 1, 1, 2, 2,  3,  3,  4,  4,  5,  5,  6,
                                6, 7, 7, 8, 8, 9, 9, 10, 10, 11, 11, 12, 12, 13, 13};

uint32_t reverse_bits(uint32_t code, int length) {
  uint32_t r = 0;
  for (int i = 0; i < length; ++i) {
    r = (r << 1) | (code & 1);
    code >>= 1;
  }
  return r;
}

void put_be32(uint8_t* p, uint32_t v) {
  p[0] = static_cast<uint8_t>(v >> 24);
  p[1] = static_cast<uint8_t>(v >> 16);
  p[2] = static_cast<uint8_t>(v >> 8);
  p[3] = static_cast<uint8_t>(v);
}

Status write_sink(const ByteSink& sink, const uint8_t* data, size_t bytes) {
  if (bytes == 0) return Status::ok();
  if (!sink.write(sink.user, data, bytes)) {
    return make_error(StatusCode::kIoError, "cannot write the PNG")
        .in_file(sink.name != nullptr ? sink.name : "output");
  }
  return Status::ok();
}

Status write_chunk(const ByteSink& sink, const char type[4], const uint8_t* data, size_t bytes) {
  uint8_t head[8];
  put_be32(head, static_cast<uint32_t>(bytes));
  std::memcpy(head + 4, type, 4);
  uint32_t crc = png_crc32(0, head + 4, 4);
  crc = png_crc32(crc, data, bytes);
  uint8_t tail[4];
  put_be32(tail, crc);
  SPLINTCORE_RETURN_IF_ERROR(write_sink(sink, head, 8));
  SPLINTCORE_RETURN_IF_ERROR(write_sink(sink, data, bytes));
  return write_sink(sink, tail, 4);
}

// Bits LSB first into a buffer that goes out as IDAT chunks of kOutCapacity bytes.
class BitWriter {
 public:
  BitWriter(const ByteSink& sink, uint8_t* buffer) : sink_(sink), buffer_(buffer) {}
  Status put(uint32_t bits, int count) {
    bits_ |= static_cast<uint64_t>(bits) << count_;
    count_ += count;
    while (count_ >= 8) {
      buffer_[used_++] = static_cast<uint8_t>(bits_);
      bits_ >>= 8;
      count_ -= 8;
      if (used_ == kOutCapacity) SPLINTCORE_RETURN_IF_ERROR(flush());
    }
    return Status::ok();
  }
  Status align() { return count_ > 0 ? put(0, 8 - count_) : Status::ok(); }
  Status flush() {
    if (used_ == 0) return Status::ok();
    SPLINTCORE_RETURN_IF_ERROR(write_chunk(sink_, "IDAT", buffer_, used_));
    used_ = 0;
    return Status::ok();
  }

 private:
  const ByteSink& sink_;
  uint8_t* buffer_;
  size_t used_ = 0;
  uint64_t bits_ = 0;
  int count_ = 0;
};

struct FixedCodes {
  uint16_t literal[288];  // bit-reversed codes
  uint8_t literal_length[288];
  uint8_t distance[30];
};

void make_fixed_codes(FixedCodes* c) {
  for (uint32_t s = 0; s < 288; ++s) {
    uint32_t code = 0;
    int length = 0;
    if (s < 144) {
      code = 0x30 + s;
      length = 8;
    } else if (s < 256) {
      code = 0x190 + (s - 144);
      length = 9;
    } else if (s < 280) {
      code = s - 256;
      length = 7;
    } else {
      code = 0xC0 + (s - 280);
      length = 8;
    }
    c->literal[s] = static_cast<uint16_t>(reverse_bits(code, length));
    c->literal_length[s] = static_cast<uint8_t>(length);
  }
  for (uint32_t d = 0; d < 30; ++d) c->distance[d] = static_cast<uint8_t>(reverse_bits(d, 5));
}

Status put_literal(BitWriter& w, const FixedCodes& c, uint32_t symbol) {
  return w.put(c.literal[symbol], c.literal_length[symbol]);
}

Status put_match(BitWriter& w, const FixedCodes& c, uint32_t length, uint32_t distance) {
  uint32_t li = 28;
  while (kLengthBase[li] > length) --li;
  SPLINTCORE_RETURN_IF_ERROR(put_literal(w, c, 257 + li));
  if (kLengthExtra[li] > 0) {
    SPLINTCORE_RETURN_IF_ERROR(w.put(length - kLengthBase[li], kLengthExtra[li]));
  }
  uint32_t di = 29;
  while (kDistBase[di] > distance) --di;
  SPLINTCORE_RETURN_IF_ERROR(w.put(c.distance[di], 5));
  if (kDistExtra[di] > 0) {
    SPLINTCORE_RETURN_IF_ERROR(w.put(distance - kDistBase[di], kDistExtra[di]));
  }
  return Status::ok();
}

uint32_t hash3(const uint8_t* p) {
  const uint32_t v =
      (static_cast<uint32_t>(p[0]) << 16) | (static_cast<uint32_t>(p[1]) << 8) | p[2];
  return (v * 2654435761u) >> (32 - kHashBits);
}

// One fixed-Huffman block holding the whole stream (deflate puts no limit on a block's size).
Status deflate_fixed(const uint8_t* data, size_t size, int32_t* head, int32_t* prev, BitWriter& w) {
  FixedCodes codes;
  make_fixed_codes(&codes);
  for (size_t i = 0; i < (size_t{1} << kHashBits); ++i) head[i] = -1;
  SPLINTCORE_RETURN_IF_ERROR(w.put(1, 1));  // BFINAL
  SPLINTCORE_RETURN_IF_ERROR(w.put(1, 2));  // BTYPE 01: fixed Huffman
  auto insert = [&](size_t pos) {
    if (pos + kMinMatch > size) return;
    const uint32_t h = hash3(data + pos);
    prev[pos & (kWindow - 1)] = head[h];
    head[h] = static_cast<int32_t>(pos);
  };
  size_t i = 0;
  while (i < size) {
    uint32_t best_length = 0, best_distance = 0;
    if (i + kMinMatch <= size) {
      const size_t limit = size - i < kMaxMatch ? size - i : kMaxMatch;
      int32_t candidate = head[hash3(data + i)];
      for (uint32_t chain = 0; chain < kMaxChain && candidate >= 0; ++chain) {
        const size_t cand = static_cast<size_t>(candidate);
        const size_t distance = i - cand;
        if (distance > kWindow) break;
        if (best_length < limit && data[cand + best_length] == data[i + best_length]) {
          size_t n = 0;
          while (n < limit && data[cand + n] == data[i + n]) ++n;
          if (n > best_length) {
            best_length = static_cast<uint32_t>(n);
            best_distance = static_cast<uint32_t>(distance);
            if (n == limit) break;
          }
        }
        candidate = prev[cand & (kWindow - 1)];
        if (candidate >= 0 && static_cast<size_t>(candidate) >= cand) break;  // stale entry
      }
    }
    if (best_length >= kMinMatch) {
      SPLINTCORE_RETURN_IF_ERROR(put_match(w, codes, best_length, best_distance));
      // Every position of a short match goes into the chains; of a long one (a run of
      // background) only the last few, as zlib's fast levels do: the runs stay findable.
      const uint32_t first = best_length <= kMaxInsert ? 0 : best_length - 3;
      for (uint32_t k = first; k < best_length; ++k) insert(i + k);
      i += best_length;
    } else {
      SPLINTCORE_RETURN_IF_ERROR(put_literal(w, codes, data[i]));
      insert(i);
      ++i;
    }
  }
  return put_literal(w, codes, 256);  // end of block
}

uint8_t paeth(uint8_t a, uint8_t b, uint8_t c) {
  const int p = static_cast<int>(a) + b - c;
  const int pa = p > a ? p - a : a - p;
  const int pb = p > b ? p - b : b - p;
  const int pc = p > c ? p - c : c - p;
  if (pa <= pb && pa <= pc) return a;
  return pb <= pc ? b : c;
}

// Row `y` filtered with `type` (0 None, 1 Sub, 2 Up, 4 Paeth) into out (3w bytes).
void filter_row(const uint8_t* row, const uint8_t* above, size_t bytes, int type, uint8_t* out) {
  for (size_t i = 0; i < bytes; ++i) {
    const uint8_t a = i >= 3 ? row[i - 3] : 0;
    const uint8_t b = above != nullptr ? above[i] : 0;
    const uint8_t c = (i >= 3 && above != nullptr) ? above[i - 3] : 0;
    uint8_t predicted = 0;
    if (type == 1) predicted = a;
    if (type == 2) predicted = b;
    if (type == 4) predicted = paeth(a, b, c);
    out[i] = static_cast<uint8_t>(row[i] - predicted);
  }
}

uint32_t abs_signed(uint8_t v) { return v < 128 ? v : 256u - v; }

// Sums of |filtered byte as int8| for None, Sub, Up and Paeth, in one pass.
void filter_costs(const uint8_t* row, const uint8_t* above, size_t bytes, uint64_t costs[4]) {
  uint64_t none = 0, sub = 0, up = 0, pae = 0;
  for (size_t i = 0; i < bytes; ++i) {
    const uint8_t x = row[i];
    const uint8_t a = i >= 3 ? row[i - 3] : 0;
    const uint8_t b = above != nullptr ? above[i] : 0;
    const uint8_t c = (i >= 3 && above != nullptr) ? above[i - 3] : 0;
    none += abs_signed(x);
    sub += abs_signed(static_cast<uint8_t>(x - a));
    up += abs_signed(static_cast<uint8_t>(x - b));
    pae += abs_signed(static_cast<uint8_t>(x - paeth(a, b, c)));
  }
  costs[0] = none;
  costs[1] = sub;
  costs[2] = up;
  costs[3] = pae;
}

}  // namespace

uint32_t png_crc32(uint32_t crc, const uint8_t* data, size_t bytes) {
  uint32_t c = crc ^ 0xFFFFFFFFu;
  for (size_t i = 0; i < bytes; ++i) c = kCrc.entry[(c ^ data[i]) & 0xFF] ^ (c >> 8);
  return c ^ 0xFFFFFFFFu;
}

uint32_t png_adler32(uint32_t adler, const uint8_t* data, size_t bytes) {
  uint32_t a = adler & 0xFFFF, b = adler >> 16;
  while (bytes > 0) {
    const size_t n = bytes < 5552 ? bytes : 5552;  // no uint32 overflow before the modulo
    for (size_t i = 0; i < n; ++i) {
      a += data[i];
      b += a;
    }
    a %= 65521;
    b %= 65521;
    data += n;
    bytes -= n;
  }
  return (b << 16) | a;
}

uint64_t png_bound(uint32_t width, uint32_t height) {
  uint64_t row = 0, rows = 0;
  if (!checked_mul(width, 3, &row) || !checked_add(row, 1, &row) ||
      !checked_mul(row, height, &rows)) {
    return UINT64_MAX;
  }
  uint64_t total = 0;
  if (!checked_add(
          rows,
          16 + (uint64_t{1} << kHashBits) * 4 + uint64_t{kWindow} * 4 + 32 + kOutCapacity + 16,
          &total)) {
    return UINT64_MAX;
  }
  return total;
}

Status write_png(const Context& ctx, const RenderImage& image, const ByteSink& sink) {
  SPLINTCORE_ASSERT(ctx.arena != nullptr && sink.write != nullptr);
  const uint32_t w = image.width, h = image.height;
  if (w == 0 || h == 0 || w > kRenderMaxSide || h > kRenderMaxSide || image.rgb == nullptr) {
    return make_error(StatusCode::kInvalidArgument, "PNG size ", w, " x ", h,
                      " is out of range (each side 1..", kRenderMaxSide,
                      " pixels, with pixel data)");
  }
  Arena& arena = *ctx.arena;
  ArenaScope scope(arena);
  const size_t row_bytes = static_cast<size_t>(w) * 3;
  const size_t stride = row_bytes + 1;
  const size_t size = stride * h;  // <= 8192 * 24577: no overflow
  uint8_t* filtered = arena.allocate_array<uint8_t>(size);
  int32_t* head =
      filtered != nullptr ? arena.allocate_array<int32_t>(size_t{1} << kHashBits) : nullptr;
  int32_t* prev = head != nullptr ? arena.allocate_array<int32_t>(kWindow) : nullptr;
  uint8_t* out = prev != nullptr ? arena.allocate_array<uint8_t>(kOutCapacity) : nullptr;
  if (out == nullptr) return arena.exhausted_status();

  // Filter each row with the type of smallest absolute sum (ties: the lowest type).
  for (uint32_t y = 0; y < h; ++y) {
    const uint8_t* row = image.rgb + static_cast<size_t>(y) * row_bytes;
    const uint8_t* above = y > 0 ? row - row_bytes : nullptr;
    uint8_t* dest = filtered + static_cast<size_t>(y) * stride;
    const int types[4] = {0, 1, 2, 4};
    uint64_t costs[4];
    filter_costs(row, above, row_bytes, costs);
    int best_type = 0;
    uint64_t best_cost = UINT64_MAX;
    for (int k = 0; k < 4; ++k) {
      if (costs[k] < best_cost) {
        best_cost = costs[k];
        best_type = types[k];
      }
    }
    dest[0] = static_cast<uint8_t>(best_type);
    filter_row(row, above, row_bytes, best_type, dest + 1);
    if ((y & 63) == 0) SPLINTCORE_RETURN_IF_ERROR(report_progress(ctx, "png", y, h));
  }

  static const uint8_t kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  SPLINTCORE_RETURN_IF_ERROR(write_sink(sink, kSignature, 8));
  uint8_t ihdr[13];
  put_be32(ihdr, w);
  put_be32(ihdr + 4, h);
  ihdr[8] = 8;   // bit depth
  ihdr[9] = 2;   // colour type: RGB
  ihdr[10] = 0;  // deflate
  ihdr[11] = 0;  // adaptive filtering
  ihdr[12] = 0;  // no interlace
  SPLINTCORE_RETURN_IF_ERROR(write_chunk(sink, "IHDR", ihdr, sizeof(ihdr)));
  static const char kText[] = "Software\0splintcore";
  SPLINTCORE_RETURN_IF_ERROR(
      write_chunk(sink, "tEXt", reinterpret_cast<const uint8_t*>(kText), sizeof(kText) - 1));

  BitWriter bits(sink, out);
  SPLINTCORE_RETURN_IF_ERROR(bits.put(0x78, 8));  // CMF: deflate, 32 KiB window
  SPLINTCORE_RETURN_IF_ERROR(bits.put(0x9C, 8));  // FLG: (0x789C % 31) == 0, no dictionary
  SPLINTCORE_RETURN_IF_ERROR(deflate_fixed(filtered, size, head, prev, bits));
  SPLINTCORE_RETURN_IF_ERROR(bits.align());
  const uint32_t adler = png_adler32(1, filtered, size);
  for (int k = 3; k >= 0; --k) {
    SPLINTCORE_RETURN_IF_ERROR(bits.put((adler >> (8 * k)) & 0xFF, 8));
  }
  SPLINTCORE_RETURN_IF_ERROR(bits.flush());
  return write_chunk(sink, "IEND", nullptr, 0);
}

}  // namespace splintcore
