// splintcore distance, internal: the bit interleave of Morton codes (G. M. Morton, "A
// computer oriented geodetic data base and a new technique in file sequencing", IBM, 1966),
// shared by the index build (bvh.cpp: 16 bits an axis) and the batch queries' order
// (query.cpp: 10 bits an axis).
#ifndef SPLINTCORE_SRC_DISTANCE_MORTON_H
#define SPLINTCORE_SRC_DISTANCE_MORTON_H

#include <cstdint>

namespace splintcore {
namespace detail {

// Spreads the low 16 bits of v so that two zero bits follow each (bit i moves to bit 3 i), by
// masks. Pure; a 48-bit result.
inline uint64_t spread_bits(uint64_t v) {
  v &= 0xffff;
  v = (v | (v << 16)) & 0x0000ff0000ffull;
  v = (v | (v << 8)) & 0x00f00f00f00full;
  v = (v | (v << 4)) & 0x0c30c30c30c3ull;
  v = (v | (v << 2)) & 0x249249249249ull;
  return v;
}

}  // namespace detail
}  // namespace splintcore

#endif  // SPLINTCORE_SRC_DISTANCE_MORTON_H
