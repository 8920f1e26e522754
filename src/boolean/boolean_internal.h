// Private to src/boolean: the Boolean of A and B in one corefinement run (boolean.cpp), which
// the public mesh_boolean (shells.cpp) calls once per group of B's shells that do not overlap.
#ifndef SPLINTCORE_SRC_BOOLEAN_BOOLEAN_INTERNAL_H
#define SPLINTCORE_SRC_BOOLEAN_BOOLEAN_INTERNAL_H

#include "splintcore/boolean.h"

namespace splintcore {

// options.op of the closed mesh A and the mesh B whose shells do not overlap each other where
// it matters (inside A for the difference and the intersection, anywhere for the union), into
// `out` (empty): what mesh_boolean did before it grouped B's shells, byte for byte. Resets
// *stats (may be null) and fills it for this one run (shells, shell_groups and passes stay 0:
// the caller sets them). Arena, errors and the result's placement: as mesh_boolean (the result
// is moved down to the arena's top at entry; on an error the arena is as it was, *out empty).
Status mesh_boolean_single(const Context& ctx, const Mesh& a, const Mesh& b,
                           const BooleanOptions& options, Mesh* out, BooleanStats* stats);

}  // namespace splintcore

#endif  // SPLINTCORE_SRC_BOOLEAN_BOOLEAN_INTERNAL_H
