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

namespace splintcore {

typedef double Lanes2 __attribute__((vector_size(16)));
typedef int64_t Mask2 __attribute__((vector_size(16)));  // a comparison of two Lanes2
typedef float Floats4 __attribute__((vector_size(16)));
typedef int32_t Mask4 __attribute__((vector_size(16)));  // a comparison of four Floats4 or int32s
typedef uint64_t Halves __attribute__((vector_size(16)));

}  // namespace splintcore

#endif  // SPLINTCORE_SRC_GEOMETRY_LANES2_H
