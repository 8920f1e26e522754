// Private to src/boolean: the Boolean of A and B in one corefinement run (assemble.cpp), which
// the public mesh_boolean (boolean.cpp) calls once per group of B's shells that do not overlap.
#ifndef SPLINTCORE_SRC_BOOLEAN_BOOLEAN_INTERNAL_H
#define SPLINTCORE_SRC_BOOLEAN_BOOLEAN_INTERNAL_H

#include <cstring>

#include "splintcore/boolean.h"

namespace splintcore {

// A double as an unsigned key that sorts in the same order (for the radix sorts).
inline uint64_t order_key(double v) {
  uint64_t bits;
  std::memcpy(&bits, &v, sizeof(bits));
  return (bits >> 63) != 0 ? ~bits : bits | (uint64_t{1} << 63);
}

// The step of A's nudges: 2^-16 mm (15 nm), or the float32 spacing of A's largest coordinate if
// that is coarser, so that float32 vertices of A stay float32.
inline double nudge_step(const Mesh& a) {
  double max_abs = 0;
  for (const Vec3& v : a.vertices) {
    for (int k = 0; k < 3; ++k) {
      const double m = v[k] < 0 ? -v[k] : v[k];
      max_abs = m > max_abs ? m : max_abs;
    }
  }
  double step = 1.0 / 65536.0;
  while (step * 8388608.0 <= max_abs && step < 1e300) step *= 2.0;  // ulp(max_abs) <= step
  return step;
}

// The checks every Boolean entry makes before anything else: an empty output mesh, and ids
// that fit in 32 bits.
inline Status check_boolean_arguments(const Mesh& a, const Mesh& b, const Mesh& out) {
  if (!out.vertices.empty() || !out.triangles.empty()) {
    return Status::error(StatusCode::kInvalidArgument, "mesh_boolean: output mesh must be empty");
  }
  const uint64_t nv = uint64_t{a.vertices.size()} + b.vertices.size();
  const uint64_t nt = uint64_t{a.triangles.size()} + b.triangles.size();
  if (nv >= (uint64_t{1} << 31) || nt >= (uint64_t{1} << 31)) {
    return make_error(StatusCode::kLimitExceeded, "Boolean inputs too large for 32-bit ids: ", nv,
                      " vertices, ", nt, " triangles");
  }
  return Status::ok();
}

// An open B whose border meets or enters A (within `region`, A's box): kInvalidMesh saying that
// B is open (its boundary edges and loops) and where its border meets A; ok otherwise, and when
// A is not a solid or B has an index out of range or a non-finite vertex (the run names those).
// Arena: temporaries, 1 byte per vertex of B, and when B is open in the region 16 bytes per
// side of B's triangles there, and when B has boundary edges there A's distance index and
// check_mesh(B); all returned (open_border.cpp). b_valid: B's indices are known to be in range
// and its vertices finite (find_shells found them so), and are not scanned again.
Status refuse_open_border_in_a(const Context& ctx, const Mesh& a, const Mesh& b, const Aabb& region,
                               bool b_valid);

// A grid coordinate as a cell index along an axis of `cells` cells, clamped to the grid: 0 at
// or below 0 (and for NaN), cells - 1 at or above cells - 1, else x truncated. Clamped in
// double first (max, min: no branch), then truncated, which is exact on the clamped value.
// (The broad phase's grid and the shells' grid.)
inline uint32_t grid_cell(double x, uint32_t cells) {
  const double last = static_cast<double>(cells - 1);
  double c = x > 0.0 ? x : 0.0;
  c = c < last ? c : last;
  return static_cast<uint32_t>(c);
}

// Triangle t of B has a vertex that is not a float32 value, with float32 output.
inline Status b_not_float32(uint32_t t) {
  return make_error(StatusCode::kInvalidArgument, "triangle ", t,
                    " of B has a vertex that is not a float32 value: for STL output B must be "
                    "as read from STL (its vertices are kept bit for bit); turn float32_output "
                    "off for double meshes")
      .at_index(t);
}

// options.op of the closed mesh A and the mesh B whose shells do not overlap each other where
// it matters (inside A for the difference and the intersection, anywhere for the union), into
// `out` (empty): what mesh_boolean did before it grouped B's shells, byte for byte. Resets
// *stats (may be null) and fills it for this one run (shells, shell_groups and passes stay 0:
// the caller sets them). Arena, errors and the result's placement: as mesh_boolean (the result
// is moved down to the arena's top at entry; on an error the arena is as it was, *out empty).
// b_valid: B's indices are known to be in range and its vertices finite (mesh_boolean's
// find_shells found them so): the broad phase does not check them again. a_solid: A is known
// to be a solid (an earlier pass's result, checked by its run): an attempt that uses A as it
// is does not check it again.
Status mesh_boolean_single(const Context& ctx, const Mesh& a, const Mesh& b,
                           const BooleanOptions& options, Mesh* out, BooleanStats* stats,
                           bool b_valid, bool a_solid);

}  // namespace splintcore

#endif  // SPLINTCORE_SRC_BOOLEAN_BOOLEAN_INTERNAL_H
