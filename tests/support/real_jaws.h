// The real CBCT dentition (../shared/realdata: 31 closed teeth, 887k triangles, in occlusion as
// scanned; not in the repository, so tests using it skip without it) joined into two jaws:
// jaw[0] the maxilla (teeth 1-15), jaw[1] the mandible (17-32). Loaded once per test binary.
#ifndef SPLINTCORE_TESTS_REAL_JAWS_H
#define SPLINTCORE_TESTS_REAL_JAWS_H

#include <string>

#include "common/realcase.h"
#include "splintcore/mesh.h"
#include "support/test_util.h"

namespace splintcore {
namespace test {

struct RealJaws {
  TestArena store{size_t{256} << 20};
  Mesh jaw[2];
  bool ok = false;
  RealJaws() {
    realcase::RealCase rc;
    std::string error;
    if (!realcase::load(SPLINTCORE_REALDATA_DIR, 0.0, 1.5, 6.0, &rc, &error)) return;
    for (int j = 0; j < 2; ++j) {
      jaw[j].bind(&store.arena);
      for (const realcase::Tooth& t : rc.teeth) {
        if ((t.number <= 16) != (j == 0)) continue;
        const uint32_t base = static_cast<uint32_t>(jaw[j].vertices.size());
        for (const Vec3& v : t.vertices) (void)jaw[j].vertices.push_back(v);
        for (const Triangle& tr : t.triangles) {
          (void)jaw[j].triangles.push_back(
              Triangle{{tr.v[0] + base, tr.v[1] + base, tr.v[2] + base}});
        }
      }
    }
    ok = true;
  }
};

inline const RealJaws& real_jaws() {
  static const RealJaws* jaws = new RealJaws();
  return *jaws;
}

}  // namespace test
}  // namespace splintcore

#endif  // SPLINTCORE_TESTS_REAL_JAWS_H
