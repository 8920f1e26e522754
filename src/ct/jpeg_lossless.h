// JPEG lossless (ITU-T T.81 Annex H, process 14: DICOM transfer syntaxes 1.2.840.10008.1.2.4.57
// and .70): private to the DICOM reader (src/ct/ct_dicom.cpp), exposed for its unit tests.
#ifndef SPLINTCORE_SRC_CT_JPEG_LOSSLESS_H
#define SPLINTCORE_SRC_CT_JPEG_LOSSLESS_H

#include "splintcore/core.h"

namespace splintcore {
namespace ct_detail {

// One Huffman table of T.81 Annex C (BITS and HUFFVAL) ready for decoding (F.2.2.3: MAXCODE,
// MINCODE, VALPTR per code length).
constexpr uint32_t kJpegFastBits = 9;  // codes up to this long decode with one table look-up
struct JpegHuffman {
  int32_t max_code[17];  // per length 1..16; -1: no code of that length
  int32_t min_code[17];
  int32_t value_index[17];
  uint8_t values[256];
  // The next kJpegFastBits bits -> (code length << 8) | symbol, 0 when the code is longer.
  uint16_t fast[1u << kJpegFastBits];
  bool defined = false;
};

// Builds a table from counts[0..16) (codes of length 1..16) and their symbols. Errors
// (kParseError): more codes than the lengths allow (over-subscribed), more than 256, or a
// symbol over 16 (lossless difference categories are 0..16).
Status jpeg_build_huffman(const uint8_t counts[16], const uint8_t* symbols, size_t symbol_count,
                          JpegHuffman* table);

// Reads the entropy-coded data of a scan: bits most significant first, 0xFF 0x00 read as 0xFF,
// stopping at a marker (0xFF then neither 0x00 nor 0xFF).
struct JpegBits {
  const uint8_t* data = nullptr;
  size_t size = 0;
  size_t pos = 0;       // next byte to take
  uint64_t buffer = 0;  // the low `count` bits are unread
  uint32_t count = 0;
  bool at_marker = false;  // pos is at a marker (or the end of data)

  // Takes bytes until at least 32 bits are held or a marker is reached.
  void refill();
  // The next n (<= 16) bits, or false if the data reaches a marker first.
  bool bits(uint32_t n, uint32_t* out);
  // The next Huffman symbol; kParseError if no code matches, kTruncated at a marker.
  Status decode(const JpegHuffman& table, uint32_t* symbol);
  // decode() for a code of at most kJpegFastBits bits with as many bits held (the common
  // case); false otherwise, nothing consumed (then decode() gives the symbol or the error).
  bool decode_fast(const JpegHuffman& table, uint32_t* symbol) {
    if (count < 16) refill();
    if (count < kJpegFastBits) return false;
    const uint32_t entry = table.fast[static_cast<uint32_t>(buffer >> (count - kJpegFastBits)) &
                                      ((1u << kJpegFastBits) - 1)];
    if (entry == 0) return false;
    count -= entry >> 8;
    *symbol = entry & 0xFF;
    return true;
  }
  // Drops the bits of the current byte and moves to the marker ahead (restart, end).
  void align();
};

// Bytes of arena jpeg_lossless_decode() takes (its tables and state), alignment included.
size_t jpeg_lossless_arena_bytes();

// Decodes one JPEG lossless image, data[0, size) (SOI ... EOI: SOF3 with one component, DHT,
// DRI, SOS with predictor 1..7 and point transform, restart markers; APPn, COM and DQT are
// skipped), which must be `columns` x `rows` samples of at most `max_precision` bits (the
// DICOM Bits Allocated), into out[0, 2 * rows * columns) as
// 16-bit little-endian values. Errors name what and the byte offset in data: kUnsupported
// (another JPEG process, more than one component, a height given by DNL), kParseError (bad
// marker segments, Huffman tables, codes, restart markers), kTruncated (data ends first).
// Arena: jpeg_lossless_arena_bytes(), returned before it returns.
Status jpeg_lossless_decode(Arena& arena, const uint8_t* data, size_t size, uint32_t rows,
                            uint32_t columns, uint32_t max_precision, uint8_t* out);

}  // namespace ct_detail
}  // namespace splintcore

#endif  // SPLINTCORE_SRC_CT_JPEG_LOSSLESS_H
