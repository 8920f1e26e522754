// Inflate (include/splintcore/compress.h): a resumable decoder of deflate streams.
//
// Sources: RFC 1951 (P. Deutsch, "DEFLATE Compressed Data Format Specification version 1.3",
// 1996): block types 3.2.3, stored blocks 3.2.4, canonical Huffman codes 3.2.2, length and
// distance codes 3.2.5, fixed codes 3.2.6, dynamic block headers 3.2.7; RFC 1950 (zlib
// wrapper: CMF/FLG check, FDICT, Adler-32) and RFC 1952 (gzip members: FTEXT, FHCRC, FEXTRA,
// FNAME, FCOMMENT, CRC-32, ISIZE). The rules for incomplete codes (a single code of one bit
// is allowed for literal/length and distance codes, nothing else) and the canonical decoding
// of long codes follow M. Adler's puff.c (zlib contrib/puff, 2002-2013), the reference
// decoder written for clarity.
//
// Design: the state holds a 64 KiB circular window: the last 32 KiB of output (the history
// that distances reach back into) and up to 32 KiB decoded but not yet delivered. Each
// literal/length-distance unit (at most 48 bits) is decoded only when all its bits are at hand
// and consumed whole, so running out of input anywhere inside a block just returns: the state
// is always at a unit boundary and input can arrive one byte at a time. Codes of up to 10 bits
// are found with one table lookup; longer ones are decoded canonically bit by bit.
#include <new>

#include "compress/rfc1951_tables.h"
#include "splintcore/compress.h"

namespace splintcore {
namespace {

constexpr uint32_t kFastBits = 10;
constexpr size_t kWindowBytes = 65536;
constexpr size_t kWindowMask = kWindowBytes - 1;
constexpr uint64_t kHistory = 32768;
// Decoding pauses when more than this is waiting to be delivered: a unit adds at most 258.
constexpr uint64_t kPendingLimit = kWindowBytes - kHistory - 258;
constexpr uint32_t kMaxLitLen = 286, kMaxDist = 30;

using rfc1951::kDistBase;
using rfc1951::kDistExtra;
using rfc1951::kLengthBase;
using rfc1951::kLengthExtra;
const uint8_t kCodeLengthOrder[19] = {16, 17, 18, 0, 8,  7, 9,  6, 10, 5,
                                      11, 4,  12, 3, 13, 2, 14, 1, 15};

// A canonical Huffman code: fast[] maps the next 10 bits to (symbol << 4) | length for codes
// of at most 10 bits (0: a longer code, or none); count[] and symbol[] decode any code.
struct Huffman {
  uint16_t fast[1u << kFastBits];
  uint16_t count[16];
  uint16_t symbol[288];
};

constexpr int kNeedBits = -1;
constexpr int kInvalidCode = -2;

enum class Mode : uint8_t {
  kHeader,           // zlib's 2 bytes, or gzip's first 10
  kGzipExtraLength,  // XLEN
  kGzipExtra,        // XLEN bytes skipped
  kGzipName,         // NUL-terminated
  kGzipComment,      // NUL-terminated
  kGzipHeaderCrc,    // CRC16
  kBlockHeader,
  kStoredLength,
  kStored,
  kTableSizes,
  kCodeLengthLengths,
  kCodeLengths,
  kCodes,
  kTrailer,
  kMemberEnd,  // gzip: after a member's trailer; another member may follow
  kDone,
  kFailed,
};

}  // namespace

struct InflateState {
  uint8_t window[kWindowBytes];
  Huffman lit, dist, lens;
  uint8_t lengths[kMaxLitLen + kMaxDist + 2];
  uint8_t header[10];
  uint64_t bitbuf;
  uint32_t bitcount;
  uint64_t bytes_fed;   // bytes taken from the caller
  uint64_t decoded;     // bytes written into the window (all members)
  uint64_t delivered;   // bytes handed to the caller
  uint64_t checked;     // bytes the check value covers
  uint64_t member_out;  // this member's bytes (distances may not reach before it)
  uint64_t max_output;
  uint32_t check;       // Adler-32 or CRC-32 of this member so far
  uint32_t header_crc;  // gzip: CRC-32 of the header bytes so far (FHCRC)
  uint32_t stored_remaining;
  uint32_t hlit, hdist, hclen, index;
  uint32_t extra_remaining;
  uint32_t field;      // a multi-byte header field being read
  uint32_t saved_crc;  // gzip: the header's CRC16 before the FHCRC field
  uint32_t header_index;
  uint32_t members;
  ZFormat format;
  Mode mode;
  bool final_block;
  Status error;
};

namespace {

uint64_t load_le64(const uint8_t* p) {
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
  uint64_t v;
  std::memcpy(&v, p, 8);
  return v;
#else
  uint64_t v = 0;
  for (int i = 7; i >= 0; --i) v = (v << 8) | p[i];
  return v;
#endif
}

struct Input {
  const uint8_t* p;
  const uint8_t* end;
};

// Tops the bit buffer up to 56..63 bits (a unit takes at most 48), or to what the input holds.
inline void refill(InflateState& s, Input& in) {
  if (in.end - in.p >= 8) {
    s.bitbuf |= load_le64(in.p) << s.bitcount;
    const uint32_t taken = (63 - s.bitcount) >> 3;
    in.p += taken;
    s.bytes_fed += taken;
    s.bitcount |= 56;
    s.bitbuf &= (uint64_t{1} << s.bitcount) - 1;  // the bytes not taken come again later
    return;
  }
  while (s.bitcount < 56 && in.p < in.end) {  // at most 63 bits: shifts stay defined
    s.bitbuf |= static_cast<uint64_t>(*in.p++) << s.bitcount;
    s.bitcount += 8;
    ++s.bytes_fed;
  }
}

inline void consume(InflateState& s, uint32_t bits) {
  s.bitbuf >>= bits;
  s.bitcount -= bits;
}

inline uint32_t low_bits(uint64_t bits, uint32_t count) {
  return static_cast<uint32_t>(bits & ((uint64_t{1} << count) - 1));
}

// The byte of the compressed stream that holds the next unread bit.
uint64_t stream_offset(const InflateState& s) { return (s.bytes_fed * 8 - s.bitcount) / 8; }

Status fail(InflateState& s, Status status) {
  s.mode = Mode::kFailed;
  s.error = status;
  return status;
}

// "0x" and 8 hex digits, for check values in messages.
struct Hex32 {
  char text[11];
  explicit Hex32(uint32_t v) {
    text[0] = '0';
    text[1] = 'x';
    for (int i = 0; i < 8; ++i) text[2 + i] = "0123456789abcdef"[(v >> (28 - 4 * i)) & 15];
    text[10] = '\0';
  }
};

template <class... Parts>
Status parse_error(InflateState& s, uint64_t offset, const Parts&... parts) {
  Status e = make_error(StatusCode::kParseError, parts...);
  e.append(" (byte ").append_u64(offset).append(" of the compressed stream)");
  return fail(s, e.at_byte(offset));
}

// Decodes one symbol from `bits` (avail of them valid): the symbol, kNeedBits or kInvalidCode.
inline int decode(const Huffman& h, uint64_t bits, uint32_t avail, uint32_t* length) {
  const uint32_t entry = h.fast[bits & ((1u << kFastBits) - 1)];
  if (entry != 0) {
    if ((entry & 15) > avail) return kNeedBits;
    *length = entry & 15;
    return static_cast<int>(entry >> 4);
  }
  int code = 0, first = 0, index = 0;
  for (uint32_t len = 1; len <= 15; ++len) {
    if (len > avail) return kNeedBits;
    code |= static_cast<int>((bits >> (len - 1)) & 1);
    const int count = h.count[len];
    if (code - first < count) {
      *length = len;
      return h.symbol[index + (code - first)];
    }
    index += count;
    first = (first + count) << 1;
    code <<= 1;
  }
  return kInvalidCode;
}

enum class Build : uint8_t { kOk, kOversubscribed, kIncomplete };

// Builds the code of lengths[0..n). allow_single: an incomplete code of one 1-bit code (or
// none at all) is accepted, as RFC 1951 permits for literal/length and distance codes.
Build build_huffman(Huffman* h, const uint8_t* lengths, uint32_t n, bool allow_single) {
  for (uint32_t len = 0; len < 16; ++len) h->count[len] = 0;
  for (uint32_t s = 0; s < n; ++s) ++h->count[lengths[s]];
  h->count[0] = 0;
  int left = 1;
  uint32_t used = 0;
  for (uint32_t len = 1; len < 16; ++len) {
    left = (left << 1) - h->count[len];
    used += h->count[len];
    if (left < 0) return Build::kOversubscribed;
  }
  if (left > 0 && !(allow_single && used <= 1 && h->count[1] == used)) return Build::kIncomplete;
  uint16_t offset[16];
  uint16_t next_code[16];
  offset[1] = 0;
  next_code[1] = 0;
  for (uint32_t len = 1; len < 15; ++len) {
    offset[len + 1] = static_cast<uint16_t>(offset[len] + h->count[len]);
    next_code[len + 1] = static_cast<uint16_t>((next_code[len] + h->count[len]) << 1);
  }
  std::memset(h->fast, 0, sizeof(h->fast));
  for (uint32_t s = 0; s < n; ++s) {
    const uint32_t len = lengths[s];
    if (len == 0) continue;
    h->symbol[offset[len]++] = static_cast<uint16_t>(s);
    const uint32_t code = next_code[len]++;
    if (len > kFastBits) continue;
    uint32_t reversed = 0;
    for (uint32_t i = 0; i < len; ++i) reversed |= ((code >> i) & 1) << (len - 1 - i);
    const uint16_t entry = static_cast<uint16_t>((s << 4) | len);
    for (uint32_t i = reversed; i < (1u << kFastBits); i += 1u << len) h->fast[i] = entry;
  }
  return Build::kOk;
}

Status build_or_fail(InflateState& s, Huffman* h, const uint8_t* lengths, uint32_t n,
                     bool allow_single, const char* what) {
  const Build b = build_huffman(h, lengths, n, allow_single);
  if (b == Build::kOversubscribed) {
    return parse_error(s, stream_offset(s), "deflate stream: over-subscribed ", what,
                       " code lengths");
  }
  if (b == Build::kIncomplete) {
    return parse_error(s, stream_offset(s), "deflate stream: incomplete ", what, " code lengths");
  }
  return Status::ok();
}

void build_fixed(InflateState& s) {
  uint8_t* l = s.lengths;
  for (uint32_t i = 0; i < 288; ++i) l[i] = i < 144 ? 8 : i < 256 ? 9 : i < 280 ? 7 : 8;
  (void)build_huffman(&s.lit, l, 288, false);  // complete by construction
  for (uint32_t i = 0; i < 32; ++i) l[i] = 5;  // 30 and 31 complete the code; never valid
  (void)build_huffman(&s.dist, l, 32, false);
}

Status limit_error(InflateState& s, uint64_t offset) {
  Status e = make_error(StatusCode::kLimitExceeded, "inflated data is larger than the limit of ",
                        s.max_output, " bytes (byte ", offset, " of the compressed stream)");
  return fail(s, e.at_byte(offset));
}

// Adds the bytes decoded since the last call to the check value (before they can be
// overwritten: called after every burst of at most 32 KiB).
void update_check(InflateState& s) {
  while (s.checked < s.decoded) {
    const size_t at = static_cast<size_t>(s.checked & kWindowMask);
    uint64_t n = s.decoded - s.checked;
    if (n > kWindowBytes - at) n = kWindowBytes - at;
    if (s.format == ZFormat::kZlib) {
      s.check = adler32(s.check, s.window + at, static_cast<size_t>(n));
    } else if (s.format == ZFormat::kGzip) {
      s.check = crc32(s.check, s.window + at, static_cast<size_t>(n));
    }
    s.checked += n;
  }
}

// One header byte (byte aligned), CRC-ed for FHCRC. False when the input is used up.
bool take_byte(InflateState& s, Input& in, uint8_t* byte) {
  if (s.bitcount < 8) refill(s, in);
  if (s.bitcount < 8) return false;
  *byte = static_cast<uint8_t>(s.bitbuf);
  consume(s, 8);
  s.header_crc = crc32(s.header_crc, byte, 1);
  return true;
}

void start_member(InflateState& s) {
  s.mode = s.format == ZFormat::kRaw ? Mode::kBlockHeader : Mode::kHeader;
  s.member_out = 0;
  s.check = s.format == ZFormat::kZlib ? 1u : 0u;
  s.header_crc = 0;
  s.header_index = 0;
  s.final_block = false;
}

// The gzip member's flags decide what follows the fixed 10 bytes.
void next_gzip_field(InflateState& s) {
  const uint8_t flags = s.header[3];
  const Mode order[5] = {Mode::kGzipExtraLength, Mode::kGzipName, Mode::kGzipComment,
                         Mode::kGzipHeaderCrc, Mode::kBlockHeader};
  const uint8_t bit[5] = {4, 8, 16, 2, 0};
  int k = s.mode == Mode::kHeader      ? 0
          : s.mode == Mode::kGzipExtra ? 1
          : s.mode == Mode::kGzipName  ? 2
                                       : 3;
  while (k < 4 && (flags & bit[k]) == 0) ++k;
  s.mode = order[k];
  s.header_index = 0;
  s.field = 0;
  s.saved_crc = s.header_crc & 0xFFFF;  // what FHCRC, if it comes next, must hold
}

Status check_zlib_header(InflateState& s, uint64_t offset) {
  const uint8_t cmf = s.header[0], flg = s.header[1];
  if ((cmf & 15) != 8) {
    return parse_error(s, offset, "zlib header: compression method ", cmf & 15,
                       " is not deflate (8)");
  }
  if ((cmf >> 4) > 7) {
    return parse_error(s, offset, "zlib header: window size 2^", (cmf >> 4) + 8,
                       " is over deflate's 32 KiB");
  }
  if ((cmf * 256u + flg) % 31 != 0) {
    return parse_error(s, offset, "zlib header: check bits wrong (", cmf * 256u + flg,
                       " is not a multiple of 31): not a zlib stream");
  }
  if ((flg & 0x20) != 0) {
    Status e = make_error(StatusCode::kUnsupported,
                          "zlib header: a preset dictionary (FDICT) is not supported (byte ",
                          offset + 1, " of the compressed stream)");
    return fail(s, e.at_byte(offset + 1));
  }
  s.mode = Mode::kBlockHeader;
  return Status::ok();
}

Status check_gzip_magic(InflateState& s, uint64_t offset) {
  if (s.header[0] == 0x1F && s.header[1] == 0x8B) return Status::ok();
  return parse_error(s, offset, "gzip header: magic bytes are not 1f 8b: not a gzip stream");
}

Status check_gzip_header(InflateState& s, uint64_t offset) {
  const uint8_t* h = s.header;
  if (h[2] != 8) {
    return parse_error(s, offset + 2, "gzip header: compression method ", h[2],
                       " is not deflate (8)");
  }
  if ((h[3] & 0xE0) != 0) {
    return parse_error(s, offset + 3, "gzip header: reserved flag bits set (flags ", h[3], ")");
  }
  next_gzip_field(s);
  return Status::ok();
}

// The wrapper's header, field by field. *need_input when the input ran out.
Status step_header(InflateState& s, Input& in, bool* need_input) {
  uint8_t b = 0;
  const uint64_t start = stream_offset(s) - s.header_index;
  switch (s.mode) {
    case Mode::kHeader: {
      const uint32_t size = s.format == ZFormat::kZlib ? 2 : 10;
      while (s.header_index < size) {
        if (!take_byte(s, in, &b)) return *need_input = true, Status::ok();
        s.header[s.header_index++] = b;
        // The magic at once: after a member, two stray bytes are named as such.
        if (s.format == ZFormat::kGzip && s.header_index == 2) {
          SPLINTCORE_RETURN_IF_ERROR(check_gzip_magic(s, start));
        }
      }
      return s.format == ZFormat::kZlib ? check_zlib_header(s, start) : check_gzip_header(s, start);
    }
    case Mode::kGzipExtraLength:
      while (s.header_index < 2) {
        if (!take_byte(s, in, &b)) return *need_input = true, Status::ok();
        s.field |= static_cast<uint32_t>(b) << (8 * s.header_index++);
      }
      s.extra_remaining = s.field;
      s.mode = Mode::kGzipExtra;
      return Status::ok();
    case Mode::kGzipExtra:
      while (s.extra_remaining > 0) {
        if (!take_byte(s, in, &b)) return *need_input = true, Status::ok();
        --s.extra_remaining;
      }
      next_gzip_field(s);
      return Status::ok();
    case Mode::kGzipName:
    case Mode::kGzipComment:
      do {
        if (!take_byte(s, in, &b)) return *need_input = true, Status::ok();
      } while (b != 0);
      next_gzip_field(s);
      return Status::ok();
    default: {  // kGzipHeaderCrc: the low 16 bits of the CRC-32 of the bytes before it
      while (s.header_index < 2) {
        if (!take_byte(s, in, &b)) return *need_input = true, Status::ok();
        s.field |= static_cast<uint32_t>(b) << (8 * s.header_index++);
      }
      if (s.field != s.saved_crc) {
        return parse_error(s, start, "gzip header: header CRC ", Hex32(s.field).text,
                           " does not match the header's ", Hex32(s.saved_crc).text);
      }
      s.mode = Mode::kBlockHeader;
      return Status::ok();
    }
  }
}

Status step_block_header(InflateState& s, Input& in, bool* need_input) {
  refill(s, in);
  if (s.bitcount < 3) return *need_input = true, Status::ok();
  const uint64_t offset = stream_offset(s);
  s.header_index = 0;  // the trailer counts its bytes here
  s.final_block = (s.bitbuf & 1) != 0;
  const uint32_t type = (s.bitbuf >> 1) & 3;
  consume(s, 3);
  if (type == 0) {
    consume(s, s.bitcount & 7);  // stored: to the byte boundary
    s.mode = Mode::kStoredLength;
  } else if (type == 1) {
    build_fixed(s);
    s.mode = Mode::kCodes;
  } else if (type == 2) {
    s.mode = Mode::kTableSizes;
  } else {
    return parse_error(s, offset, "deflate stream: invalid block type 3");
  }
  return Status::ok();
}

Status step_stored(InflateState& s, Input& in, bool* need_input) {
  if (s.mode == Mode::kStoredLength) {
    refill(s, in);
    if (s.bitcount < 32) return *need_input = true, Status::ok();
    const uint32_t len = s.bitbuf & 0xFFFF, nlen = (s.bitbuf >> 16) & 0xFFFF;
    if (len != (~nlen & 0xFFFF)) {
      return parse_error(s, stream_offset(s), "deflate stream: stored block length ", len,
                         " does not match its complement ", nlen);
    }
    consume(s, 32);
    s.stored_remaining = len;
    s.mode = Mode::kStored;
  }
  while (s.stored_remaining > 0) {
    const uint64_t pending = s.decoded - s.delivered;
    if (pending > kPendingLimit) return Status::ok();
    if (s.decoded >= s.max_output) return limit_error(s, stream_offset(s));
    if (s.bitcount >= 8) {  // whole bytes the bit buffer already holds
      s.window[s.decoded++ & kWindowMask] = static_cast<uint8_t>(s.bitbuf);
      consume(s, 8);
      ++s.member_out;
      --s.stored_remaining;
      continue;
    }
    if (in.p == in.end) return *need_input = true, Status::ok();
    const size_t at = static_cast<size_t>(s.decoded & kWindowMask);
    uint64_t n = s.stored_remaining;
    if (n > static_cast<uint64_t>(in.end - in.p)) n = static_cast<uint64_t>(in.end - in.p);
    if (n > kWindowBytes - at) n = kWindowBytes - at;
    if (n > kPendingLimit + 1 - pending) n = kPendingLimit + 1 - pending;
    if (n > s.max_output - s.decoded) n = s.max_output - s.decoded;
    std::memcpy(s.window + at, in.p, static_cast<size_t>(n));
    in.p += n;
    s.bytes_fed += n;
    s.decoded += n;
    s.member_out += n;
    s.stored_remaining -= static_cast<uint32_t>(n);
  }
  s.mode = s.final_block ? Mode::kTrailer : Mode::kBlockHeader;
  return Status::ok();
}

// HLIT, HDIST, HCLEN and the code length code's lengths.
Status step_table_header(InflateState& s, Input& in, bool* need_input) {
  if (s.mode == Mode::kTableSizes) {
    refill(s, in);
    if (s.bitcount < 14) return *need_input = true, Status::ok();
    s.hlit = 257 + low_bits(s.bitbuf, 5);
    s.hdist = 1 + low_bits(s.bitbuf >> 5, 5);
    s.hclen = 4 + low_bits(s.bitbuf >> 10, 4);
    if (s.hlit > kMaxLitLen || s.hdist > kMaxDist) {
      return parse_error(s, stream_offset(s), "deflate stream: dynamic block with ", s.hlit,
                         " literal/length and ", s.hdist, " distance codes (at most 286 and 30)");
    }
    consume(s, 14);
    s.index = 0;
    for (uint32_t i = 0; i < 19; ++i) s.lengths[i] = 0;
    s.mode = Mode::kCodeLengthLengths;
  }
  while (s.index < s.hclen) {
    if (s.bitcount < 3) refill(s, in);
    if (s.bitcount < 3) return *need_input = true, Status::ok();
    s.lengths[kCodeLengthOrder[s.index++]] = static_cast<uint8_t>(s.bitbuf & 7);
    consume(s, 3);
  }
  SPLINTCORE_RETURN_IF_ERROR(build_or_fail(s, &s.lens, s.lengths, 19, false, "code length"));
  s.index = 0;
  s.mode = Mode::kCodeLengths;
  return Status::ok();
}

// The literal/length and distance code lengths, then their codes.
Status step_code_lengths(InflateState& s, Input& in, bool* need_input) {
  const uint32_t total = s.hlit + s.hdist;
  while (s.index < total) {
    refill(s, in);
    const uint64_t offset = stream_offset(s);
    uint32_t length = 0;
    const int sym = decode(s.lens, s.bitbuf, s.bitcount, &length);
    // The code length code is complete (build_or_fail), so every 7 bits decode: a negative
    // symbol can only mean "more bits".
    if (sym < 0) return *need_input = true, Status::ok();
    if (sym < 16) {
      s.lengths[s.index++] = static_cast<uint8_t>(sym);
      consume(s, length);
      continue;
    }
    const uint32_t extra = sym == 16 ? 2 : sym == 17 ? 3 : 7;
    if (length + extra > s.bitcount) return *need_input = true, Status::ok();
    const uint32_t repeat = (sym == 16   ? 3
                             : sym == 17 ? 3
                                         : 11) +
                            low_bits(s.bitbuf >> length, extra);
    if (sym == 16 && s.index == 0) {
      return parse_error(s, offset, "deflate stream: code length repeat with no length before it");
    }
    if (s.index + repeat > total) {
      return parse_error(s, offset, "deflate stream: code length repeat of ", repeat,
                         " passes the end of the ", total, " lengths");
    }
    const uint8_t value = sym == 16 ? s.lengths[s.index - 1] : 0;
    for (uint32_t k = 0; k < repeat; ++k) s.lengths[s.index++] = value;
    consume(s, length + extra);
  }
  if (s.lengths[256] == 0) {
    return parse_error(s, stream_offset(s),
                       "deflate stream: dynamic block without an end-of-block code");
  }
  SPLINTCORE_RETURN_IF_ERROR(build_or_fail(s, &s.lit, s.lengths, s.hlit, true, "literal/length"));
  SPLINTCORE_RETURN_IF_ERROR(
      build_or_fail(s, &s.dist, s.lengths + s.hlit, s.hdist, true, "distance"));
  s.mode = Mode::kCodes;
  return Status::ok();
}

// Copies a match inside the window (forward, byte by byte: the source may overlap the end).
inline void copy_match(InflateState& s, uint32_t length, uint32_t distance) {
  const size_t to = static_cast<size_t>(s.decoded & kWindowMask);
  const size_t from = static_cast<size_t>((s.decoded - distance) & kWindowMask);
  uint8_t* w = s.window;
  if (to + length <= kWindowBytes && from + length <= kWindowBytes) {
    if (distance >= 8) {
      uint32_t k = 0;
      for (; k + 8 <= length; k += 8) std::memcpy(w + to + k, w + from + k, 8);
      for (; k < length; ++k) w[to + k] = w[from + k];
    } else {
      for (uint32_t k = 0; k < length; ++k) w[to + k] = w[from + k];
    }
  } else {
    for (uint32_t k = 0; k < length; ++k) w[(to + k) & kWindowMask] = w[(from + k) & kWindowMask];
  }
  s.decoded += length;
  s.member_out += length;
}

// Literals and matches until the end of the block, a full window or the end of the input.
Status step_codes(InflateState& s, Input& in, bool* need_input) {
  while (s.decoded - s.delivered <= kPendingLimit) {
    refill(s, in);
    const uint64_t bits = s.bitbuf;
    const uint32_t avail = s.bitcount;
    uint32_t used = 0;
    const int sym = decode(s.lit, bits, avail, &used);
    if (sym < 256) {
      if (sym < 0) {
        if (sym == kNeedBits) return *need_input = true, Status::ok();
        return parse_error(s, stream_offset(s), "deflate stream: invalid literal/length code");
      }
      if (s.decoded >= s.max_output) return limit_error(s, stream_offset(s));
      s.window[s.decoded++ & kWindowMask] = static_cast<uint8_t>(sym);
      ++s.member_out;
      consume(s, used);
      continue;
    }
    if (sym == 256) {
      consume(s, used);
      s.mode = s.final_block ? Mode::kTrailer : Mode::kBlockHeader;
      return Status::ok();
    }
    const uint32_t li = static_cast<uint32_t>(sym) - 257;
    if (li >= 29) {
      return parse_error(s, stream_offset(s), "deflate stream: invalid length code ", sym);
    }
    const uint32_t length_extra = kLengthExtra[li];
    if (used + length_extra > avail) return *need_input = true, Status::ok();
    const uint32_t length = kLengthBase[li] + low_bits(bits >> used, length_extra);
    used += length_extra;
    uint32_t dist_used = 0;
    const int dsym = decode(s.dist, bits >> used, avail - used, &dist_used);
    if (dsym == kNeedBits) return *need_input = true, Status::ok();
    if (dsym < 0 || dsym >= 30) {
      return parse_error(s, stream_offset(s), "deflate stream: invalid distance code");
    }
    used += dist_used;
    const uint32_t dist_extra = kDistExtra[dsym];
    if (used + dist_extra > avail) return *need_input = true, Status::ok();
    const uint32_t distance = kDistBase[dsym] + low_bits(bits >> used, dist_extra);
    used += dist_extra;
    if (distance > s.member_out) {
      return parse_error(s, stream_offset(s), "deflate stream: distance ", distance,
                         " reaches before the start of the data (", s.member_out, " bytes so far)");
    }
    if (length > s.max_output - s.decoded) return limit_error(s, stream_offset(s));
    copy_match(s, length, distance);
    consume(s, used);
  }
  return Status::ok();
}

uint32_t get_le32(const uint8_t* p) {
  return p[0] | (static_cast<uint32_t>(p[1]) << 8) | (static_cast<uint32_t>(p[2]) << 16) |
         (static_cast<uint32_t>(p[3]) << 24);
}

// The check value (and, for gzip, the length) after the last block.
Status step_trailer(InflateState& s, Input& in, bool* need_input) {
  if (s.format == ZFormat::kRaw) {
    s.mode = Mode::kDone;
    return Status::ok();
  }
  if (s.header_index == 0) consume(s, s.bitcount & 7);  // to the byte boundary
  const uint32_t size = s.format == ZFormat::kZlib ? 4 : 8;
  uint8_t b = 0;
  while (s.header_index < size) {
    if (!take_byte(s, in, &b)) return *need_input = true, Status::ok();
    s.header[s.header_index++] = b;
  }
  update_check(s);
  const uint64_t offset = stream_offset(s) - size;
  const uint8_t* t = s.header;
  if (s.format == ZFormat::kZlib) {
    const uint32_t stored = (static_cast<uint32_t>(t[0]) << 24) |
                            (static_cast<uint32_t>(t[1]) << 16) |
                            (static_cast<uint32_t>(t[2]) << 8) | t[3];
    if (stored != s.check) {
      return parse_error(s, offset, "zlib: Adler-32 ", Hex32(stored).text,
                         " does not match the data's ", Hex32(s.check).text);
    }
    s.mode = Mode::kDone;
    return Status::ok();
  }
  if (get_le32(t) != s.check) {
    return parse_error(s, offset, "gzip: CRC-32 ", Hex32(get_le32(t)).text,
                       " does not match the data's ", Hex32(s.check).text);
  }
  if (get_le32(t + 4) != static_cast<uint32_t>(s.member_out)) {
    return parse_error(s, offset + 4, "gzip: length ", get_le32(t + 4),
                       " (ISIZE) does not match the data's ", static_cast<uint32_t>(s.member_out));
  }
  ++s.members;
  s.mode = Mode::kMemberEnd;
  return Status::ok();
}

// Runs the state machine until the input is used up (*need_input), the window is full of
// undelivered bytes, or the stream ends.
Status step(InflateState& s, Input& in, bool* need_input) {
  for (;;) {
    switch (s.mode) {
      case Mode::kHeader:
      case Mode::kGzipExtraLength:
      case Mode::kGzipExtra:
      case Mode::kGzipName:
      case Mode::kGzipComment:
      case Mode::kGzipHeaderCrc: SPLINTCORE_RETURN_IF_ERROR(step_header(s, in, need_input)); break;
      case Mode::kBlockHeader:
        SPLINTCORE_RETURN_IF_ERROR(step_block_header(s, in, need_input));
        break;
      case Mode::kStoredLength:
      case Mode::kStored:
        SPLINTCORE_RETURN_IF_ERROR(step_stored(s, in, need_input));
        if (!*need_input && s.mode == Mode::kStored) return Status::ok();  // window full
        break;
      case Mode::kTableSizes:
      case Mode::kCodeLengthLengths:
        SPLINTCORE_RETURN_IF_ERROR(step_table_header(s, in, need_input));
        break;
      case Mode::kCodeLengths:
        SPLINTCORE_RETURN_IF_ERROR(step_code_lengths(s, in, need_input));
        break;
      case Mode::kCodes:
        SPLINTCORE_RETURN_IF_ERROR(step_codes(s, in, need_input));
        if (!*need_input && s.mode == Mode::kCodes) return Status::ok();  // window full
        break;
      case Mode::kTrailer: SPLINTCORE_RETURN_IF_ERROR(step_trailer(s, in, need_input)); break;
      case Mode::kMemberEnd:
        // Another member, or (as zlib's gzread) bytes that are not one: they end the stream,
        // left unused (total_in() stops before them).
        refill(s, in);
        if (s.bitcount == 0 || ((s.bitbuf & 0xFF) == 0x1F && s.bitcount < 16)) {
          return *need_input = true, Status::ok();
        }
        if ((s.bitbuf & 0xFFFF) != 0x8B1F) {
          s.mode = Mode::kDone;
          return Status::ok();
        }
        start_member(s);
        break;
      default:  // kDone (run_stream never steps a failed state)
        return Status::ok();
    }
    if (*need_input) return Status::ok();
  }
}

// Where run() puts output: the caller's buffer (out, room) or a sink.
struct Output {
  uint8_t** out = nullptr;
  size_t* room = nullptr;
  const CompressSink* sink = nullptr;
};

// Hands pending bytes to the output in contiguous pieces of the window.
Status deliver_pending(InflateState& s, Output& o) {
  while (s.delivered < s.decoded) {
    const size_t at = static_cast<size_t>(s.delivered & kWindowMask);
    uint64_t n = s.decoded - s.delivered;
    if (n > kWindowBytes - at) n = kWindowBytes - at;
    if (o.sink != nullptr) {
      if (!o.sink->write(o.sink->user, s.window + at, static_cast<size_t>(n))) {
        return make_error(StatusCode::kIoError, "inflate: the sink refused ", n,
                          " bytes of output");
      }
    } else {
      if (*o.room == 0) break;
      if (n > *o.room) n = *o.room;
      std::memcpy(*o.out, s.window + at, static_cast<size_t>(n));
      *o.out += n;
      *o.room -= static_cast<size_t>(n);
    }
    s.delivered += n;
  }
  return Status::ok();
}

Status run_stream(InflateState& s, const uint8_t** in, size_t* in_size, Output& output) {
  if (s.mode == Mode::kFailed) return s.error;
  Input input{*in, *in + *in_size};
  Status status = Status::ok();
  for (;;) {
    status = deliver_pending(s, output);
    if (!status.is_ok()) break;
    if (s.decoded - s.delivered > kPendingLimit || s.mode == Mode::kDone) break;  // out full
    bool need_input = false;
    status = step(s, input, &need_input);
    update_check(s);
    if (!status.is_ok()) break;
    if (need_input || s.mode == Mode::kDone) {
      status = deliver_pending(s, output);
      break;
    }
  }
  *in_size -= static_cast<size_t>(input.p - *in);
  *in = input.p;
  if (!status.is_ok() && s.mode != Mode::kFailed) (void)fail(s, status);  // a sink's error
  return status;
}

}  // namespace

uint64_t inflate_state_bytes() { return arena_array_bound<InflateState>(1); }

Status Inflater::begin(Arena& arena, ZFormat format, uint64_t max_output) {
  void* memory = arena.allocate(sizeof(InflateState), Arena::kDefaultAlignment);
  if (memory == nullptr) return arena.exhausted_status();
  ::new (memory) InflateState();  // zeroed window and tables: no output from stale memory
  InflateState* s = static_cast<InflateState*>(memory);
  s->format = format;
  s->max_output = max_output;
  start_member(*s);
  s_ = s;
  return Status::ok();
}

Status Inflater::run(const uint8_t** in, size_t* in_size, uint8_t** out, size_t* out_size) {
  SPLINTCORE_ASSERT(s_ != nullptr && in != nullptr && in_size != nullptr && out != nullptr &&
                    out_size != nullptr);
  Output output;
  output.out = out;
  output.room = out_size;
  return run_stream(*s_, in, in_size, output);
}

Status Inflater::run(const uint8_t** in, size_t* in_size, const CompressSink& sink) {
  SPLINTCORE_ASSERT(s_ != nullptr && sink.write != nullptr);
  Output output;
  output.sink = &sink;
  return run_stream(*s_, in, in_size, output);
}

bool Inflater::stream_ended() const {
  return s_ != nullptr && (s_->mode == Mode::kDone || s_->mode == Mode::kMemberEnd);
}

bool Inflater::finished() const { return stream_ended() && s_->delivered == s_->decoded; }

Status Inflater::end_of_input() const {
  SPLINTCORE_ASSERT(s_ != nullptr);
  if (s_->mode == Mode::kFailed) return s_->error;
  if (stream_ended()) return Status::ok();
  const uint64_t offset = s_->bytes_fed;
  const char* where = s_->mode <= Mode::kGzipHeaderCrc ? "in the header"
                      : s_->mode == Mode::kTrailer     ? "in the trailer"
                                                       : "inside a deflate block";
  return make_error(StatusCode::kTruncated, "compressed stream truncated ", where, " after ",
                    offset, " bytes (", s_->delivered, " bytes inflated)")
      .at_byte(offset);
}

uint64_t Inflater::total_in() const { return s_ == nullptr ? 0 : s_->bytes_fed - s_->bitcount / 8; }

uint64_t Inflater::total_out() const { return s_ == nullptr ? 0 : s_->delivered; }

Status inflate_buffer(Arena& arena, ZFormat format, const uint8_t* in, size_t in_size, uint8_t* out,
                      size_t out_capacity, size_t* produced) {
  SPLINTCORE_ASSERT(produced != nullptr && (in != nullptr || in_size == 0));
  ArenaScope scope(arena);
  *produced = 0;
  Inflater inflater;
  SPLINTCORE_RETURN_IF_ERROR(inflater.begin(arena, format, out_capacity));
  uint8_t* cursor = out;
  size_t room = out_capacity;
  SPLINTCORE_RETURN_IF_ERROR(inflater.run(&in, &in_size, &cursor, &room));
  *produced = out_capacity - room;
  return inflater.end_of_input();
}

}  // namespace splintcore
