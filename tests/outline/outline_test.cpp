// The automatic outline (outline.h) on the phantom jaws.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "common/phantom.h"
#include "splintcore/outline.h"

namespace splintcore {
namespace {

struct PhantomPair {
  phantom::JawMesh upper, lower;
  std::vector<unsigned char> memory;
  Arena arena{nullptr, 0};
  Mesh maxilla, mandible;
  explicit PhantomPair(uint64_t triangles, double mandible_dz = -2.0)
      : memory(size_t{256} << 20), arena(memory.data(), memory.size()) {
    phantom::PhantomOptions po;
    po.target_triangles = triangles;
    EXPECT_TRUE(phantom::make_jaw(phantom::Jaw::kMaxilla, po, &upper).is_ok());
    EXPECT_TRUE(phantom::make_jaw(phantom::Jaw::kMandible, po, &lower).is_ok());
    for (Vec3& v : lower.vertices) v.z += mandible_dz;
    maxilla.bind(&arena);
    mandible.bind(&arena);
    EXPECT_TRUE(phantom::to_mesh(upper, &maxilla).is_ok());
    EXPECT_TRUE(phantom::to_mesh(lower, &mandible).is_ok());
  }
};

TEST(Outline, PhantomArch) {
  PhantomPair p(87000);
  Outline o;
  const Status s = compute_outline(Context(&p.arena), p.maxilla, p.mandible, OutlineOptions{}, &o);
  ASSERT_TRUE(s.is_ok()) << s.message();
}

}  // namespace
}  // namespace splintcore
