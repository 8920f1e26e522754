// CRC-32 and Adler-32 (include/splintcore/compress.h).
//
// Sources: CRC-32 of ISO 3309 / ITU-T V.42, as given in PNG (ISO/IEC 15948:2003) Annex D and
// RFC 1952 section 8 (reflected polynomial 0xEDB88320, table driven, eight bytes a step);
// Adler-32 of RFC 1950 section 9 (sums modulo 65521, reduced every 5552 bytes so no 32-bit
// sum overflows).
#include "splintcore/compress.h"

namespace splintcore {
namespace {

// Slicing-by-8 (M. E. Kounavis and F. L. Berry, "A Systematic Approach to Building High
// Performance Software-Based CRC Generators", ISCC 2005): entry[k][n] is the CRC of byte n
// followed by k zero bytes, so eight bytes cost eight independent lookups.
struct CrcTable {
  uint32_t entry[8][256];
  constexpr CrcTable() : entry() {
    for (uint32_t n = 0; n < 256; ++n) {
      uint32_t c = n;
      for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
      entry[0][n] = c;
    }
    for (uint32_t n = 0; n < 256; ++n) {
      for (int k = 1; k < 8; ++k) {
        entry[k][n] = (entry[k - 1][n] >> 8) ^ entry[0][entry[k - 1][n] & 0xFF];
      }
    }
  }
};
constexpr CrcTable kCrc;

uint32_t le32(const uint8_t* p) {
  return p[0] | (static_cast<uint32_t>(p[1]) << 8) | (static_cast<uint32_t>(p[2]) << 16) |
         (static_cast<uint32_t>(p[3]) << 24);
}

}  // namespace

uint32_t crc32(uint32_t crc, const uint8_t* data, size_t bytes) {
  const auto& t = kCrc.entry;
  uint32_t c = crc ^ 0xFFFFFFFFu;
  for (; bytes >= 8; bytes -= 8, data += 8) {
    const uint32_t lo = c ^ le32(data), hi = le32(data + 4);
    c = t[7][lo & 0xFF] ^ t[6][(lo >> 8) & 0xFF] ^ t[5][(lo >> 16) & 0xFF] ^ t[4][lo >> 24] ^
        t[3][hi & 0xFF] ^ t[2][(hi >> 8) & 0xFF] ^ t[1][(hi >> 16) & 0xFF] ^ t[0][hi >> 24];
  }
  for (size_t i = 0; i < bytes; ++i) c = t[0][(c ^ data[i]) & 0xFF] ^ (c >> 8);
  return c ^ 0xFFFFFFFFu;
}

namespace {

// a(x) b(x) mod the CRC's polynomial, both in the CRC's reflected form (bit 31 the coefficient
// of x^0): b multiplied by x once per bit of a, from x^0 up, added where a has the bit.
uint32_t multiply_mod(uint32_t a, uint32_t b) {
  uint32_t product = 0;
  for (uint32_t bit = 1u << 31; bit != 0; bit >>= 1) {
    if ((a & bit) != 0) product ^= b;
    b = (b & 1u) != 0 ? (b >> 1) ^ 0xEDB88320u : b >> 1;
  }
  return product;
}

}  // namespace

// Appending n bytes to a message multiplies its register by x^(8n) before the new bytes' own
// CRC is added (the initial and final xors cancel: zlib's crc32_combine rests on the same
// identity); x^(8n) by squaring, a bit of n at a time.
uint32_t crc32_combine(uint32_t crc_a, uint32_t crc_b, uint64_t bytes_b) {
  uint32_t power = 1u << 31;   // x^0
  uint32_t square = 1u << 23;  // x^8: one byte
  for (uint64_t n = bytes_b; n != 0; n >>= 1) {
    if ((n & 1u) != 0) power = multiply_mod(power, square);
    square = multiply_mod(square, square);
  }
  return multiply_mod(power, crc_a) ^ crc_b;
}

uint32_t adler32(uint32_t adler, const uint8_t* data, size_t bytes) {
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

}  // namespace splintcore
