// The exact blockout on the real CBCT dentition (issue 29; ../shared/realdata, skipped without
// it): the case with the automatic outline and "blockout": {"method": "exact"} designed, and
// the independent line check run on both jaws in the positions the outline gave them: no line
// locked, within 1e-4 mm. (The design's base reaches little below the crowns' widest: its
// plain splint locks on only 3 lines of 16k, so the check's power is shown on the phantom
// (sweep_test.cpp, pipeline_test.cpp). A slab 3 mm deeper, reaching the necks, is where the
// exact sweep's fold rounds do not suffice yet: blockout.h.)
#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "splintcore/blockout.h"
#include "splintcore/design.h"
#include "support/frame_moves.h"
#include "support/real_jaws.h"
#include "support/test_util.h"
#include "support/undercut_lines.h"

namespace splintcore {
namespace {

TEST(ExactBlockoutRealData, NoLineLockedOnEitherJaw) {
  const test::RealJaws& real = test::real_jaws();
  if (!real.ok) GTEST_SKIP() << "no real data at " << SPLINTCORE_REALDATA_DIR;
  test::TestArena ta(size_t{1} << 30);
  Context ctx(&ta.arena);
  const char* text[2] = {
      R"({"splintcore_case": 1, "case_id": "real", "units": "mm",
          "jaws": [{"role": "maxilla", "mesh": "maxilla.stl"},
                   {"role": "mandible", "mesh": "mandible.stl"}],
          "base": {"spacing_mm": 0.5, "auto": {"bite_opening_mm": 2}}, "printer": "eden260"})",
      R"({"splintcore_case": 1, "case_id": "real", "units": "mm",
          "jaws": [{"role": "maxilla", "mesh": "maxilla.stl"},
                   {"role": "mandible", "mesh": "mandible.stl"}],
          "base": {"spacing_mm": 0.5, "auto": {"bite_opening_mm": 2}}, "printer": "eden260",
          "blockout": {"method": "exact"}})"};
  CaseFile c[2];
  Mesh splint[2];
  for (int i = 0; i < 2; ++i) {
    SPLINTCORE_ASSERT_OK(parse_case(ctx, text[i], std::strlen(text[i]), "real", &c[i]));
    DesignReport r;
    SPLINTCORE_ASSERT_OK(design_splint(ctx, c[i], Span<const Mesh>(real.jaw, 2), &splint[i], &r));
    EXPECT_EQ(r.imprint_swept, i == 1);
  }
  EXPECT_EQ(c[1].blockout_method, BlockoutMethod::kExact);
  // Where the outline put the jaws (the mandible opened by the bite), and the direction.
  CaseFile resolved;
  SPLINTCORE_ASSERT_OK(
      resolve_case_outline(ctx, c[1], Span<const Mesh>(real.jaw, 2), &resolved, nullptr));
  for (int j = 0; j < 2; ++j) {
    const Mesh jaw = test::moved_mesh(ta.arena, real.jaw[j], resolved.jaws[j].transform);
    const Vec3 d = j == 0 ? resolved.insertion_direction : -resolved.insertion_direction;
    // Lines across d through the arch's box.
    Aabb box;
    for (const Vec3& p : splint[1].vertices) box.add(p);
    Vec3 u = std::fabs(d.x) < 0.9 ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
    u = u - d * dot(u, d);
    u = u * (1.0 / std::sqrt(dot(u, u)));
    const Vec3 v = cross(d, u);
    const Vec3 e = box.extent();
    const double half = 0.5 * std::sqrt(dot(e, e));
    const test::LockReport design =
        test::lock_report(ta.arena, splint[1], jaw, d, u, v, box.center(), half, 200, 1e-4);
    EXPECT_GT(design.lines_through_jaw, 3000u);
    EXPECT_EQ(design.locked_lines, 0u) << design.longest;
    std::printf(
        "[ figures  ] real jaw %d: the exact design's splint: %zu lines through the "
        "jaw, %zu locked (longest %.2g mm)\n",
        j, design.lines_through_jaw, design.locked_lines, design.longest);
  }
}

}  // namespace
}  // namespace splintcore
