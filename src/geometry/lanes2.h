// splintcore geometry, internal: two lanes of double, for loops that do the same arithmetic on
// two values at once (the distance queries, the outline's plane axes, the mesh check's
// measures). GCC and Clang vector extensions: SSE2 on x86-64, NEON on AArch64, lowered to
// scalar code where there is neither (Cortex-M7). The library is built with
// -fno-tree-slp-vectorize (cmake/SplintcoreFlags.cmake), so the compiler would not pack such
// loops itself. Each lane does the operations the scalar code would, in the same order, and
// -ffp-contract=off holds for vectors too: the values are the same bits as scalar code's on
// every platform. Also the other 16-byte lanes more than one file uses: four floats, four
// int32 (a comparison of four floats or int32s) and two uint64 halves (the STL reader's crop,
// the self-intersection check's masks).
#ifndef SPLINTCORE_SRC_GEOMETRY_LANES2_H
#define SPLINTCORE_SRC_GEOMETRY_LANES2_H

#include <cstdint>
#include <cstring>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace splintcore {

typedef double Lanes2 __attribute__((vector_size(16)));
typedef int64_t Mask2 __attribute__((vector_size(16)));  // a comparison of two Lanes2
typedef float Floats4 __attribute__((vector_size(16)));
typedef int32_t Mask4 __attribute__((vector_size(16)));  // a comparison of four Floats4 or int32s
typedef uint64_t Halves __attribute__((vector_size(16)));

// The four lanes of a comparison as bits 0-3 (a lane's sign bit: set where the comparison
// held). One movmskps on x86-64; elsewhere the lanes one by one. (The STL reader's crop, on
// the real dentition's 887k triangles: its lanes taken out one by one cost 12.7M instructions
// of the read's 146.5M, callgrind; 3.2M with this.)
inline uint32_t mask4_bits(Mask4 m) {
#if defined(__SSE2__)
  __m128 f;
  std::memcpy(&f, &m, sizeof(f));
  return static_cast<uint32_t>(_mm_movemask_ps(f));
#else
  return (m[0] < 0 ? 1u : 0u) | (m[1] < 0 ? 2u : 0u) | (m[2] < 0 ? 4u : 0u) | (m[3] < 0 ? 8u : 0u);
#endif
}

}  // namespace splintcore

#endif  // SPLINTCORE_SRC_GEOMETRY_LANES2_H
