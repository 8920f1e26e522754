// CRC-32 and Adler-32 (include/splintcore/compress.h).
//
// Sources: CRC-32 of ISO 3309 / ITU-T V.42, as given in PNG (ISO/IEC 15948:2003) Annex D and
// RFC 1952 section 8 (reflected polynomial 0xEDB88320, table driven); Adler-32 of RFC 1950
// section 9 (sums modulo 65521, reduced every 5552 bytes so no 32-bit sum overflows).
#include "splintcore/compress.h"

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

}  // namespace

uint32_t crc32(uint32_t crc, const uint8_t* data, size_t bytes) {
  uint32_t c = crc ^ 0xFFFFFFFFu;
  for (size_t i = 0; i < bytes; ++i) c = kCrc.entry[(c ^ data[i]) & 0xFF] ^ (c >> 8);
  return c ^ 0xFFFFFFFFu;
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
