// splintcore compress: CRC-32, Adler-32, a deterministic fixed-Huffman deflate encoder (the
// PNG writer's) and a streaming inflate (RFC 1951) with the zlib (RFC 1950) and gzip (RFC 1952)
// wrappers, for gzip-encoded NRRD and deflated DICOM. Core only; memory from the caller's arena.
#ifndef SPLINTCORE_COMPRESS_H
#define SPLINTCORE_COMPRESS_H

#include "splintcore/core.h"

namespace splintcore {

// CRC-32 (ISO 3309, as PNG, gzip and zlib's crc32: reflected polynomial 0xEDB88320, initial
// and final xor 0xFFFFFFFF). Chainable: pass the previous result as `crc` (0 to start).
uint32_t crc32(uint32_t crc, const uint8_t* data, size_t bytes);
// The CRC-32 of bytes A then B from crc32(0, A) = crc_a, crc32(0, B) = crc_b and B's length:
// a message's CRC from its pieces' CRCs, computed apart (on several threads).
uint32_t crc32_combine(uint32_t crc_a, uint32_t crc_b, uint64_t bytes_b);
// Adler-32 (RFC 1950). Chainable: pass the previous result (1 to start).
uint32_t adler32(uint32_t adler, const uint8_t* data, size_t bytes);

// The wrapper around a deflate stream.
enum class ZFormat : uint8_t {
  kRaw,   // RFC 1951 alone (DICOM's Deflated Explicit VR Little Endian)
  kZlib,  // RFC 1950: 2-byte header, Adler-32 of the data (PNG)
  kGzip,  // RFC 1952: header, CRC-32 and length of the data; members may follow each other
};

// Where compressed or decompressed bytes go: write() returns false on failure.
struct CompressSink {
  bool (*write)(void* user, const uint8_t* data, size_t bytes) = nullptr;
  void* user = nullptr;
};

// ---------------------------------------------------------------------------------------------
// Deflate: one fixed-Huffman block (RFC 1951 3.2.6) from a greedy LZ77 matcher over hash
// chains (32 KiB window, chains of at most 64 candidates, every position of a match up to 32
// bytes hashed, only the last 3 of a longer one). The bytes depend only on the input.

constexpr size_t kDeflateHashEntries = size_t{1} << 16;
constexpr size_t kDeflateWindow = 32768;

// The matcher's effort: at each position it looks at up to max_chain earlier positions with
// the same three bytes, newest first, and keeps the first longest match; it stops at a match of
// nice_length bytes. The defaults (the PNG writer's: its bytes are pinned by tests) compress
// best; the 3MF writer's (kDeflateFast) deflate mesh text in about half the instructions for
// a package 3% larger (splintcore-bench --filter write_3mf_phantom: write_3mf 1.87 G
// instructions a run before, 0.96 G after, under callgrind; 2,752,291 -> 2,835,126 bytes).
struct DeflateEffort {
  uint32_t max_chain = 64;     // 1..4096
  uint32_t nice_length = 258;  // 3..258
};
constexpr DeflateEffort kDeflateFast{8, 32};

// The matcher's tables, its effort and the output buffer (bytes go to the sink each time it is
// full, and at the end).
struct DeflateWorkspace {
  int32_t* head = nullptr;  // kDeflateHashEntries
  int32_t* prev = nullptr;  // kDeflateWindow
  uint8_t* out = nullptr;   // out_bytes
  size_t out_bytes = 0;
  DeflateEffort effort;
};

// Arena bytes deflate_workspace() takes: 65536*4 + 32768*4 + out_bytes, plus 15 bytes of
// alignment per each of the three arrays.
uint64_t deflate_workspace_bound(size_t out_bytes);
// Allocates head, prev and out (in that order) from `arena`; they stay there. out_bytes >= 1.
// Errors: kArenaExhausted.
Status deflate_workspace(Arena& arena, size_t out_bytes, DeflateWorkspace* workspace);
// Compresses data[0..size) as one stream in `format` into `sink` (a sequence of writes of at
// most workspace.out_bytes, each full except the last). Errors: kIoError (the sink refused).
Status deflate_fixed(const DeflateWorkspace& workspace, ZFormat format, const uint8_t* data,
                     size_t size, const CompressSink& sink);

// Deflate on the caller's executor: the input cut into pieces of kDeflatePiece bytes, each one
// fixed-Huffman block made by the matcher of deflate_fixed, whose matches may reach into the
// 32 KiB before the piece; the blocks are joined bit to bit, in order, into one stream. The
// bytes depend only on the input and the effort, not on the executor or its threads; an input
// of at most one piece gives deflate_fixed's bytes. Pieces are made kDeflateLanes at a time,
// each lane with its own tables and a buffer for its piece's bits.
constexpr size_t kDeflatePiece = size_t{1} << 18;
constexpr uint32_t kDeflateLanes = 4;

struct DeflateLanes {
  DeflateWorkspace stream;  // the joined stream's tables (a single piece) and its 64 KiB buffer
  DeflateWorkspace lane[kDeflateLanes];  // for inputs of more than one piece
  uint32_t lanes = 0;  // lanes allocated: 0 for one piece, else up to kDeflateLanes
  size_t largest = 0;  // the largest input they take
};
// Arena bytes deflate_lanes() takes for inputs of up to `largest` bytes: up to one piece,
// deflate_workspace_bound(65536); more, also (one per piece, at most kDeflateLanes) a lane:
// deflate_workspace_bound of a piece's bound (9/8 of it and 16 bytes).
uint64_t deflate_lanes_bound(size_t largest);
// Allocates the lanes from `arena`; they stay there. Errors: kArenaExhausted.
Status deflate_lanes(Arena& arena, size_t largest, DeflateEffort effort, DeflateLanes* lanes);
// Compresses data[0..size) (size <= lanes.largest) as one stream in `format` into `sink`
// (writes of at most 64 KiB) with `executor`'s threads (nullptr: serial). `data_crc` (may be
// nullptr): crc32(0, data, size), computed piece by piece beside the deflate (a ZIP entry's
// header needs it); set only when the stream is complete. Errors: kIoError (the sink refused).
Status deflate_parallel(const Executor* executor, const DeflateLanes& lanes, ZFormat format,
                        const uint8_t* data, size_t size, const CompressSink& sink,
                        uint32_t* data_crc = nullptr);

// ---------------------------------------------------------------------------------------------
// Inflate: RFC 1951 complete (stored, fixed and dynamic Huffman blocks, 32 KiB window), with
// the zlib wrapper (header check, Adler-32 verified; a preset dictionary, FDICT, is refused)
// or the gzip wrapper (FEXTRA, FNAME, FCOMMENT skipped, FHCRC, CRC-32 and ISIZE verified;
// members one after another are one stream, their outputs concatenated; bytes after a member
// that do not start another one end the stream, unused, as zlib's gzread() treats them).
//
// Streaming: input in chunks of any size (down to one byte), output in chunks of any size,
// into a caller buffer or a sink; the state (a 64 KiB window: 32 KiB of history and up to
// 32 KiB decoded but not yet delivered, the Huffman tables) lives in the caller's arena.
//
// Errors carry the byte offset in the compressed stream (Status::byte_offset(), and in the
// message): kTruncated (the input ended inside the stream: end_of_input()); kParseError
// (invalid block type, stored length mismatch, over-subscribed or incomplete code lengths,
// invalid code, distance beyond the data so far, a bad zlib/gzip header, checksum or length
// mismatch); kUnsupported (a zlib preset dictionary);
// kLimitExceeded (the output would pass the caller's max_output: a decompression bomb guard);
// kIoError (a sink refused). After an error the Inflater stays failed (run() repeats it).

struct InflateState;

// Exact arena bytes Inflater::begin() takes, alignment padding included (one allocation).
uint64_t inflate_state_bytes();

class Inflater {
 public:
  // Allocates the state from `arena` (inflate_state_bytes(); the caller rewinds it) and
  // starts a stream. Errors: kArenaExhausted.
  Status begin(Arena& arena, ZFormat format, uint64_t max_output = UINT64_MAX);

  // Decompresses from *in (advanced past what was used, *in_size reduced) into *out (advanced,
  // *out_size reduced). Returns when the input is used up, the output is full, or the stream
  // has ended and everything is delivered. Input bytes taken but not yet decoded are held
  // in the state (at most 8).
  Status run(const uint8_t** in, size_t* in_size, uint8_t** out, size_t* out_size);
  // The same, delivering output to `sink` in pieces of at most 32 KiB.
  Status run(const uint8_t** in, size_t* in_size, const CompressSink& sink);

  // The caller has no more input: ok when the stream ended, kTruncated otherwise (its offset
  // is the stream's length).
  Status end_of_input() const;
  // The whole stream is decoded (its output may still wait to be delivered).
  bool stream_ended() const;
  // The stream ended and all its output is delivered.
  bool finished() const;
  // Bytes of the compressed stream used (input held but not decoded excluded).
  uint64_t total_in() const;
  // Bytes delivered.
  uint64_t total_out() const;

 private:
  InflateState* s_ = nullptr;
};

// One shot: the whole stream in[0..in_size) into out[0..out_capacity); *produced is the output
// length. More than out_capacity bytes of output is kLimitExceeded; input that ends inside
// the stream kTruncated. Arena: inflate_state_bytes(), rewound before return.
Status inflate_buffer(Arena& arena, ZFormat format, const uint8_t* in, size_t in_size, uint8_t* out,
                      size_t out_capacity, size_t* produced);

}  // namespace splintcore

#endif  // SPLINTCORE_COMPRESS_H
