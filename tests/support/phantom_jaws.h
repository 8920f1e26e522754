// The phantom's maxilla (index 0) and mandible (index 1) of about `triangles` triangles each
// as meshes in `arena` (the set-up the design, plan and fusion tests share).
#ifndef SPLINTCORE_TESTS_SUPPORT_PHANTOM_JAWS_H
#define SPLINTCORE_TESTS_SUPPORT_PHANTOM_JAWS_H

#include "common/phantom.h"
#include "splintcore/mesh.h"

namespace splintcore {
namespace test {

// False when the phantom cannot be made or the arena is too small.
inline bool phantom_jaw_meshes(Arena& arena, uint32_t triangles, Mesh jaws[2]) {
  for (int j = 0; j < 2; ++j) {
    phantom::JawMesh m;
    phantom::PhantomOptions po;
    po.target_triangles = triangles;
    if (!phantom::make_jaw(j == 0 ? phantom::Jaw::kMaxilla : phantom::Jaw::kMandible, po, &m)
             .is_ok()) {
      return false;
    }
    jaws[j].bind(&arena);
    if (!jaws[j].vertices.resize(m.vertices.size()) ||
        !jaws[j].triangles.resize(m.triangles.size())) {
      return false;
    }
    for (size_t i = 0; i < m.vertices.size(); ++i) jaws[j].vertices[i] = m.vertices[i];
    for (size_t i = 0; i < m.triangles.size(); ++i) jaws[j].triangles[i] = m.triangles[i];
  }
  return true;
}

}  // namespace test
}  // namespace splintcore

#endif  // SPLINTCORE_TESTS_SUPPORT_PHANTOM_JAWS_H
