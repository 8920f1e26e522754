// The SHA-256 compression function over whole 64-byte blocks (FIPS 180-4, 6.2.2): the portable
// one, and on x86-64 the one with the SHA extensions (SHA-NI) where the CPU has them. Both give
// the same state for the same blocks; Sha256 (core.h) uses the second when it can.
#ifndef SPLINTCORE_SRC_CORE_SHA256_BLOCKS_H
#define SPLINTCORE_SRC_CORE_SHA256_BLOCKS_H

#include <cstddef>
#include <cstdint>

namespace splintcore {

void sha256_blocks_portable(uint32_t state[8], const uint8_t* p, size_t blocks);

// False (state untouched) where the CPU or the build has no SHA extensions.
bool sha256_blocks_accelerated(uint32_t state[8], const uint8_t* p, size_t blocks);

}  // namespace splintcore

#endif  // SPLINTCORE_SRC_CORE_SHA256_BLOCKS_H
