// Where the design's Boolean holds a jaw's vertex (pipeline.cpp's B, the outline's moved jaws):
// the one rule for moving a jaw by its transform and rounding it as its STL would hold it; and
// the one test of two placements' numbers being the same bits.
#ifndef SPLINTCORE_DESIGN_B_VERTEX_H
#define SPLINTCORE_DESIGN_B_VERTEX_H

#include <cstdint>
#include <cstring>

#include "splintcore/design.h"

namespace splintcore {
namespace design_detail {

// Vertex v of jaw j where B holds it: moved by the jaw's transform, rounded to float32; false
// when that leaves float32 range.
inline bool b_vertex(const CaseFile& c, Span<const Mesh> jaws, size_t j, size_t v, Vec3* p) {
  *p = c.jaws[j].transform.apply_point(jaws[j].vertices[v]);
  return round_to_float32(p);
}

// The same bits in each of the n values (+0 and -0 differ, as they would in the output; a
// case's numbers read twice give the same bits).
inline bool same_bits(const double* a, const double* b, size_t n) {
  for (size_t i = 0; i < n; ++i) {
    uint64_t u, v;
    std::memcpy(&u, &a[i], sizeof(u));
    std::memcpy(&v, &b[i], sizeof(v));
    if (u != v) return false;
  }
  return true;
}

}  // namespace design_detail
}  // namespace splintcore

#endif  // SPLINTCORE_DESIGN_B_VERTEX_H
