// Deflate encoder (include/splintcore/compress.h): one fixed-Huffman block.
//
// Sources: RFC 1951 (deflate: fixed Huffman codes, section 3.2.6; length and distance codes,
// 3.2.5) with a greedy LZ77 matcher over hash chains as described in section 4 of RFC 1951;
// RFC 1950 (zlib wrapper) and RFC 1952 (gzip wrapper). Moved here from the PNG writer, whose
// bytes it must keep (the render tests pin their SHA-256).
//
// Deterministic: integer arithmetic only; the matcher's choices depend only on the bytes.
#include <cstring>

#include "compress/rfc1951_tables.h"
#include "splintcore/compress.h"

namespace splintcore {
namespace {

constexpr uint32_t kHashBits = 16;
constexpr uint32_t kWindow = kDeflateWindow;
constexpr uint32_t kMinMatch = 3;
constexpr uint32_t kMaxMatch = 258;
constexpr uint32_t kMaxInsert = 32;
static_assert((size_t{1} << kHashBits) == kDeflateHashEntries, "hash table size");

using rfc1951::kDistBase;
using rfc1951::kDistExtra;
using rfc1951::kLengthBase;
using rfc1951::kLengthExtra;

uint32_t reverse_bits(uint32_t code, int length) {
  uint32_t r = 0;
  for (int i = 0; i < length; ++i) {
    r = (r << 1) | (code & 1);
    code >>= 1;
  }
  return r;
}

// Bits LSB first into the workspace's buffer, which goes to the sink each time it is full. The
// hot path (put) is a plain append: a sink's refusal is kept (failed()) and reported by flush()
// and finish_piece(), and nothing more is written after it.
class BitWriter {
 public:
  BitWriter(const DeflateWorkspace& ws, const CompressSink& sink)
      : out_(ws.out), capacity_(ws.out_bytes), sink_(sink) {}
  // Up to 32 bits at a time; whole 32-bit words leave the accumulator at once (the same bytes
  // as one at a time: LSB first).
  void put(uint32_t bits, int count) {
    bits_ |= static_cast<uint64_t>(bits) << count_;
    count_ += count;
    if (count_ >= 32) put_word();
  }
  // Pads to a byte boundary and writes every whole byte held.
  void align() {
    if (count_ % 8 != 0) count_ += 8 - count_ % 8;
    drain();
  }
  void put_le32(uint32_t v) {
    put(v & 0xFFFF, 16);
    put(v >> 16, 16);
  }
  // n whole bytes after the bits held, 8 at a time (shifted by the bits held: fewer than 8).
  void put_bytes(const uint8_t* bytes, size_t n) {
    drain();
    size_t i = 0;
    while (n - i >= 8 && !failed_) {
      if (capacity_ - used_ < 8) {  // byte at a time up to the buffer's end
        put(bytes[i++], 8);
        continue;
      }
      uint64_t word = 0;
      for (size_t k = 0; k < 8; ++k) word |= static_cast<uint64_t>(bytes[i + k]) << (8 * k);
      const uint64_t shifted = (word << count_) | bits_;
      for (size_t k = 0; k < 8; ++k) out_[used_ + k] = static_cast<uint8_t>(shifted >> (8 * k));
      used_ += 8;
      bits_ = count_ > 0 ? word >> (64 - count_) : 0;
      i += 8;
      if (used_ == capacity_) write_out();
    }
    for (; i < n; ++i) put(bytes[i], 8);
  }
  Status flush() {
    drain();
    write_out();
    return status();
  }
  // Writes every whole byte and hands back the bits of the last partial one (fewer than 8),
  // unpadded: a piece of a stream that another writer continues.
  Status finish_piece(uint32_t* bits, int* count) {
    drain();
    *bits = static_cast<uint32_t>(bits_);
    *count = count_;
    return status();
  }
  // Bytes in the buffer, not yet written to the sink.
  size_t held() const { return used_; }
  // The sink refused a write (what follows is dropped).
  bool failed() const { return failed_; }
  Status status() const {
    return failed_ ? make_error(StatusCode::kIoError, "cannot write the compressed stream")
                   : Status::ok();
  }

 private:
  void put_word() {
    if (capacity_ - used_ < 4) {
      drain();
      return;
    }
    for (size_t k = 0; k < 4; ++k) out_[used_ + k] = static_cast<uint8_t>(bits_ >> (8 * k));
    used_ += 4;
    bits_ >>= 32;
    count_ -= 32;
    if (used_ == capacity_) write_out();
  }
  // Every whole byte out of the accumulator.
  void drain() {
    while (count_ >= 8) {
      out_[used_++] = static_cast<uint8_t>(bits_);
      bits_ >>= 8;
      count_ -= 8;
      if (used_ == capacity_) write_out();
    }
  }
  void write_out() {
    if (used_ != 0 && !failed_ && !sink_.write(sink_.user, out_, used_)) failed_ = true;
    used_ = 0;
  }

  uint8_t* out_;
  size_t capacity_;
  const CompressSink& sink_;
  size_t used_ = 0;
  uint64_t bits_ = 0;
  int count_ = 0;
  bool failed_ = false;
};

struct FixedCodes {
  uint16_t literal[288];  // bit-reversed codes
  uint8_t literal_length[288];
  uint8_t distance[30];
  // length 3..258 -> its code and extra bits as they are written (up to 13 bits), and how many
  uint16_t length_bits[kMaxMatch + 1];
  uint8_t length_count[kMaxMatch + 1];
  // distance 1..256 -> [d - 1]; 257..32768 -> [256 + ((d - 1) >> 7)]: its index in kDistBase
  uint8_t distance_code[512];
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
  // The code of a length or distance: the last whose base is at most it.
  uint32_t li = 0;
  for (uint32_t length = kMinMatch; length <= kMaxMatch; ++length) {
    while (li < 28 && kLengthBase[li + 1] <= length) ++li;
    const int code_length = c->literal_length[257 + li];
    c->length_bits[length] =
        static_cast<uint16_t>(c->literal[257 + li] | (length - kLengthBase[li]) << code_length);
    c->length_count[length] = static_cast<uint8_t>(code_length + kLengthExtra[li]);
  }
  uint32_t di = 0;
  for (uint32_t d = 1; d <= 256; ++d) {
    while (di < 29 && kDistBase[di + 1] <= d) ++di;
    c->distance_code[d - 1] = static_cast<uint8_t>(di);
  }
  // Above 256 every code's base is 1 + a multiple of 128, so (d - 1) >> 7 tells them apart.
  for (uint32_t k = 2; k < 256; ++k) {
    const uint32_t d = (k << 7) + 1;
    while (di < 29 && kDistBase[di + 1] <= d) ++di;
    c->distance_code[256 + k] = static_cast<uint8_t>(di);
  }
}

void put_literal(BitWriter& w, const FixedCodes& c, uint32_t symbol) {
  w.put(c.literal[symbol], c.literal_length[symbol]);
}

// A match in one put: its length's code and extra bits (up to 8 + 5), then its distance's
// code and extra bits (5 + 13): at most 31 bits.
void put_match(BitWriter& w, const FixedCodes& c, uint32_t length, uint32_t distance) {
  const uint32_t di = distance <= 256 ? c.distance_code[distance - 1]
                                      : c.distance_code[256 + ((distance - 1) >> 7)];
  const int length_count = c.length_count[length];
  const uint32_t distance_bits = c.distance[di] | (distance - kDistBase[di]) << 5;
  w.put(c.length_bits[length] | distance_bits << length_count, length_count + 5 + kDistExtra[di]);
}

// How many bytes a and b have in common from the start, at most `limit` (8 at a time where
// the byte order lets the lowest differing byte be found from the trailing zeros).
size_t common_length(const uint8_t* a, const uint8_t* b, size_t limit) {
  size_t n = 0;
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
  while (n + 8 <= limit) {
    uint64_t x, y;
    std::memcpy(&x, a + n, 8);
    std::memcpy(&y, b + n, 8);
    const uint64_t d = x ^ y;
    if (d != 0) return n + static_cast<size_t>(__builtin_ctzll(d) >> 3);
    n += 8;
  }
#endif
  while (n < limit && a[n] == b[n]) ++n;
  return n;
}

// Four bytes as a little-endian word (p[0] lowest), whatever the machine's byte order.
uint32_t load_le32(const uint8_t* p) {
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
  uint32_t v;
  std::memcpy(&v, p, 4);
  return v;
#else
  return static_cast<uint32_t>(p[0]) | static_cast<uint32_t>(p[1]) << 8 |
         static_cast<uint32_t>(p[2]) << 16 | static_cast<uint32_t>(p[3]) << 24;
#endif
}

uint32_t hash_of(uint32_t v) { return (v * 2654435761u) >> (32 - kHashBits); }

// The hash of the three bytes at p: p[0] p[1] p[2] as a big-endian 24-bit value.
uint32_t hash3(const uint8_t* p) {
  return hash_of((static_cast<uint32_t>(p[0]) << 16) | (static_cast<uint32_t>(p[1]) << 8) | p[2]);
}

// hash3 of data + pos where a fourth byte may be read (pos + 4 <= size): one load.
uint32_t hash3_wide(const uint8_t* p) {
  const uint32_t v = load_le32(p);  // p[3] p[2] p[1] p[0], high to low
#if defined(__GNUC__) || defined(__clang__)
  return hash_of(__builtin_bswap32(v) >> 8);
#else
  return hash_of((v & 0xFF) << 16 | (v & 0xFF00) | (v >> 16 & 0xFF));
#endif
}

// The matcher's chains: head[hash] the newest position with those three bytes, prev[pos mod
// the window] the one before it.
struct Chains {
  int32_t* head;
  int32_t* prev;
  const uint8_t* data;
  size_t size;

  uint32_t hash(size_t pos) const {
    return pos + 4 <= size ? hash3_wide(data + pos) : hash3(data + pos);
  }
  void insert_hashed(size_t pos, uint32_t h) {
    prev[pos & (kWindow - 1)] = head[h];
    head[h] = static_cast<int32_t>(pos);
  }
  void insert(size_t pos) {
    if (pos + kMinMatch <= size) insert_hashed(pos, hash(pos));
  }
};

// The first longest match (at least kMinMatch bytes) at i among the chain's first max_chain
// candidates within the window; 0 when there is none. A candidate is looked at only if the 4
// bytes that end where the best match so far ends agree (3 from the start before there is
// one): only a candidate that fails no such test can be longer, so the choice is the same as
// looking at every candidate.
uint32_t longest_match(const Chains& c, size_t i, size_t end, uint32_t h, uint32_t max_chain,
                       size_t nice, uint32_t* best_distance) {
  const uint8_t* data = c.data;
  const size_t limit = end - i < kMaxMatch ? end - i : kMaxMatch;
  // Candidates in [low, cand) are in the window and older than the one before: the chain
  // is newest first, so anything else ends it.
  const int64_t low = i > kWindow ? static_cast<int64_t>(i - kWindow) : 0;
  auto in_range = [low](int64_t candidate, int64_t above) {
    return static_cast<uint64_t>(candidate - low) < static_cast<uint64_t>(above - low);
  };
  size_t best = 0;
  size_t probe = 0;  // the tested word starts here: best - 3 once best >= 3
  uint32_t mask = 0xFFFFFF;
  uint32_t want = static_cast<uint32_t>(data[i]) | static_cast<uint32_t>(data[i + 1]) << 8 |
                  static_cast<uint32_t>(data[i + 2]) << 16;
  int64_t candidate = c.head[h];
  int64_t above = static_cast<int64_t>(i);
  for (uint32_t chain = 0; chain < max_chain && in_range(candidate, above); ++chain) {
    const size_t cand = static_cast<size_t>(candidate);
    // cand + probe + 4 <= i + best + 1 <= i + limit <= size: in bounds.
    if ((load_le32(data + cand + probe) & mask) == want) {
      const size_t n = common_length(data + cand, data + i, limit);
      if (n > best) {
        best = n;
        *best_distance = static_cast<uint32_t>(i - cand);
        if (n == limit || n >= nice) break;
        probe = n - 3;
        mask = 0xFFFFFFFF;
        want = load_le32(data + i + probe);  // i + n < i + limit <= size
      }
    }
    above = candidate;
    candidate = c.prev[cand & (kWindow - 1)];
  }
  return static_cast<uint32_t>(best);
}

// One fixed-Huffman block of data[begin..end) (the last block when end == size; deflate puts
// no limit on a block's size). Matches may reach back into the 32 KiB before `begin`, which go
// into the hash chains first, and end at `end`: the block depends only on the input and its
// bounds, so the blocks of a cut input can be made in any order (deflate_parallel).
Status deflate_block(const uint8_t* data, size_t size, size_t begin, size_t end,
                     const DeflateWorkspace& ws, BitWriter& w) {
  Chains chains{ws.head, ws.prev, data, size};
  const uint32_t max_chain = ws.effort.max_chain;
  const size_t nice = ws.effort.nice_length;
  FixedCodes codes;
  make_fixed_codes(&codes);
  for (size_t i = 0; i < (size_t{1} << kHashBits); ++i) chains.head[i] = -1;
  w.put(end == size ? 1 : 0, 1);  // BFINAL
  w.put(1, 2);                    // BTYPE 01: fixed Huffman
  for (size_t pos = begin > kWindow ? begin - kWindow : 0; pos < begin; ++pos) {
    chains.insert(pos);
  }
  size_t i = begin;
  while (i < end && !w.failed()) {
    if (i + kMinMatch > size) {  // the last two bytes: neither matched nor hashed
      put_literal(w, codes, data[i]);
      ++i;
      continue;
    }
    const uint32_t h = chains.hash(i);
    uint32_t best_length = 0, best_distance = 0;
    if (i + kMinMatch <= end) {
      best_length = longest_match(chains, i, end, h, max_chain, nice, &best_distance);
    }
    if (best_length >= kMinMatch) {
      put_match(w, codes, best_length, best_distance);
      // Every position of a short match goes into the chains; of a long one (a run of
      // background) only the last few, as zlib's fast levels do: the runs stay findable.
      if (best_length <= kMaxInsert) {
        chains.insert_hashed(i, h);
        for (uint32_t k = 1; k < best_length; ++k) chains.insert(i + k);
      } else {
        for (uint32_t k = best_length - 3; k < best_length; ++k) chains.insert(i + k);
      }
      i += best_length;
    } else {
      put_literal(w, codes, data[i]);
      chains.insert_hashed(i, h);
      ++i;
    }
  }
  put_literal(w, codes, 256);  // end of block
  return w.status();
}

// The wrapper's header (RFC 1950 / 1952), before the first block.
void put_header(BitWriter& bits, ZFormat format) {
  if (format == ZFormat::kZlib) {
    bits.put(0x78, 8);  // CMF: deflate, 32 KiB window
    bits.put(0x9C, 8);  // FLG: (0x789C % 31) == 0, no dictionary
  } else if (format == ZFormat::kGzip) {
    // ID1 ID2, CM 8, no flags, no time, XFL 0, OS 255 (unknown): the same bytes everywhere.
    static const uint8_t kHeader[10] = {0x1F, 0x8B, 8, 0, 0, 0, 0, 0, 0, 255};
    for (uint8_t b : kHeader) bits.put(b, 8);
  }
}

// Pads the last block to a byte, then the wrapper's trailer, then everything to the sink.
// `crc`: the data's CRC-32 when known (else computed here, for gzip).
Status put_trailer(BitWriter& bits, ZFormat format, const uint8_t* data, size_t size,
                   const uint32_t* crc = nullptr) {
  bits.align();
  if (format == ZFormat::kZlib) {
    const uint32_t adler = adler32(1, data, size);
    for (int k = 3; k >= 0; --k) bits.put((adler >> (8 * k)) & 0xFF, 8);
  } else if (format == ZFormat::kGzip) {
    bits.put_le32(crc != nullptr ? *crc : crc32(0, data, size));
    bits.put_le32(static_cast<uint32_t>(size));
  }
  return bits.flush();
}

void check_effort(const DeflateEffort& effort) {
  SPLINTCORE_ASSERT(effort.max_chain >= 1 && effort.max_chain <= 4096);
  SPLINTCORE_ASSERT(effort.nice_length >= kMinMatch && effort.nice_length <= kMaxMatch);
}

constexpr size_t kStreamOut = 65536;  // deflate_parallel's writes to the sink

// A piece's bits: at most 9 a byte (a literal), the block's header and end code.
size_t piece_bytes_bound(size_t n) { return n + n / 8 + 16; }

bool refuse(void*, const uint8_t*, size_t) { return false; }

// A wave of deflate_parallel: lane k makes piece first + k into its own buffer.
struct Pieces {
  const uint8_t* data = nullptr;
  size_t size = 0;
  size_t first = 0;                      // the wave's first piece
  const DeflateWorkspace* ws = nullptr;  // the lanes
  size_t used[kDeflateLanes] = {};       // whole bytes of the piece
  uint32_t bits[kDeflateLanes] = {};
  int count[kDeflateLanes] = {};  // bits after them (0..7)
  Status status[kDeflateLanes];
  bool with_crc = false;
  uint32_t crc[kDeflateLanes] = {};  // of the piece's input, when with_crc

  void run(uint32_t k) {
    const size_t begin = (first + k) * kDeflatePiece;
    const size_t end = size - begin > kDeflatePiece ? begin + kDeflatePiece : size;
    if (with_crc) crc[k] = crc32(0, data + begin, end - begin);
    CompressSink none;
    none.write = &refuse;  // the buffer holds the piece's bound: never full
    BitWriter w(ws[k], none);
    status[k] = deflate_block(data, size, begin, end, ws[k], w);
    if (status[k].is_ok()) status[k] = w.finish_piece(&bits[k], &count[k]);
    used[k] = w.held();
  }
};

// Appends a piece (whole bytes, then up to 7 bits) to the stream.
void append_piece(BitWriter& out, const uint8_t* bytes, size_t n, uint32_t bits, int count) {
  out.put_bytes(bytes, n);
  if (count > 0) out.put(bits, count);
}

}  // namespace

uint64_t deflate_workspace_bound(size_t out_bytes) {
  uint64_t total =
      arena_array_bound<int32_t>(kDeflateHashEntries) + arena_array_bound<int32_t>(kDeflateWindow);
  const uint64_t out = arena_array_bound<uint8_t>(out_bytes);
  return checked_add(total, out, &total) ? total : UINT64_MAX;
}

Status deflate_workspace(Arena& arena, size_t out_bytes, DeflateWorkspace* workspace) {
  SPLINTCORE_ASSERT(out_bytes >= 1 && workspace != nullptr);
  DeflateWorkspace ws;
  ws.head = arena.allocate_array<int32_t>(kDeflateHashEntries);
  ws.prev = ws.head != nullptr ? arena.allocate_array<int32_t>(kDeflateWindow) : nullptr;
  ws.out = ws.prev != nullptr ? arena.allocate_array<uint8_t>(out_bytes) : nullptr;
  if (ws.out == nullptr) return arena.exhausted_status();
  ws.out_bytes = out_bytes;
  *workspace = ws;
  return Status::ok();
}

Status deflate_fixed(const DeflateWorkspace& workspace, ZFormat format, const uint8_t* data,
                     size_t size, const CompressSink& sink) {
  SPLINTCORE_ASSERT(workspace.out != nullptr && sink.write != nullptr);
  check_effort(workspace.effort);
  BitWriter bits(workspace, sink);
  put_header(bits, format);
  SPLINTCORE_RETURN_IF_ERROR(deflate_block(data, size, 0, size, workspace, bits));
  return put_trailer(bits, format, data, size);
}

// The lanes for inputs of up to `largest` bytes: 0 for one piece, else one a piece, at most
// kDeflateLanes.
uint32_t lanes_for(size_t largest) {
  if (largest <= kDeflatePiece) return 0;
  const size_t pieces = largest / kDeflatePiece + (largest % kDeflatePiece != 0 ? 1 : 0);
  return pieces < kDeflateLanes ? static_cast<uint32_t>(pieces) : kDeflateLanes;
}

uint64_t deflate_lanes_bound(size_t largest) {
  return deflate_workspace_bound(kStreamOut) +
         uint64_t{lanes_for(largest)} * deflate_workspace_bound(piece_bytes_bound(kDeflatePiece));
}

Status deflate_lanes(Arena& arena, size_t largest, DeflateEffort effort, DeflateLanes* lanes) {
  check_effort(effort);
  DeflateLanes l;
  l.largest = largest;
  SPLINTCORE_RETURN_IF_ERROR(deflate_workspace(arena, kStreamOut, &l.stream));
  l.stream.effort = effort;
  l.lanes = lanes_for(largest);
  for (uint32_t k = 0; k < l.lanes; ++k) {
    SPLINTCORE_RETURN_IF_ERROR(
        deflate_workspace(arena, piece_bytes_bound(kDeflatePiece), &l.lane[k]));
    l.lane[k].effort = effort;
  }
  *lanes = l;
  return Status::ok();
}

Status deflate_parallel(const Executor* executor, const DeflateLanes& lanes, ZFormat format,
                        const uint8_t* data, size_t size, const CompressSink& sink,
                        uint32_t* data_crc) {
  SPLINTCORE_ASSERT(sink.write != nullptr && size <= lanes.largest);
  if (size <= kDeflatePiece) {
    SPLINTCORE_RETURN_IF_ERROR(deflate_fixed(lanes.stream, format, data, size, sink));
    if (data_crc != nullptr) *data_crc = crc32(0, data, size);
    return Status::ok();
  }
  Pieces p;
  p.data = data;
  p.size = size;
  p.ws = lanes.lane;
  p.with_crc = data_crc != nullptr || format == ZFormat::kGzip;
  uint32_t crc = 0;  // of the pieces joined so far
  BitWriter bits(lanes.stream, sink);
  put_header(bits, format);
  const size_t pieces = (size + kDeflatePiece - 1) / kDeflatePiece;
  for (size_t first = 0; first < pieces; first += lanes.lanes) {
    const uint32_t wave =
        static_cast<uint32_t>(pieces - first < lanes.lanes ? pieces - first : lanes.lanes);
    p.first = first;
    auto task = [&p](uint32_t k) { p.run(k); };
    parallel_for_each(executor, wave, task);
    for (uint32_t k = 0; k < wave; ++k) {
      SPLINTCORE_RETURN_IF_ERROR(p.status[k]);
      append_piece(bits, p.ws[k].out, p.used[k], p.bits[k], p.count[k]);
      const size_t begin = (first + k) * kDeflatePiece;
      const size_t length = size - begin > kDeflatePiece ? kDeflatePiece : size - begin;
      crc = first + k == 0 ? p.crc[k] : crc32_combine(crc, p.crc[k], length);
    }
    SPLINTCORE_RETURN_IF_ERROR(bits.status());
  }
  SPLINTCORE_RETURN_IF_ERROR(put_trailer(bits, format, data, size, p.with_crc ? &crc : nullptr));
  if (data_crc != nullptr) *data_crc = crc;
  return Status::ok();
}

}  // namespace splintcore
