// The design preview (tools/common/preview.cpp) draws the jaws only near the splint: a jaw's
// part beyond the splint's box widened by kPreviewJawMarginMm changes no pixel (not even the
// framing), a part within it is drawn, and moves are applied before that test.

#include <gtest/gtest.h>

#include <cstdio>
#include <string>
#include <vector>

#include "common/preview.h"
#include "common/shapes.h"
#include "splintcore/io.h"
#include "splintcore/mesh.h"
#include "support/test_util.h"

namespace {

using namespace splintcore;

// Boxes (each closed, welded on its own) in one mesh, in order.
Mesh boxes(Arena* arena, const std::vector<std::vector<float>>& corners) {
  std::vector<SoupTriangle> soup;
  for (const std::vector<float>& c : corners) {
    const std::vector<SoupTriangle> b = shapes::box(c.data(), c.data() + 3);
    soup.insert(soup.end(), b.begin(), b.end());
  }
  Mesh m(arena);
  Status s = weld_exact(Context(arena), Span<const SoupTriangle>(soup.data(), soup.size()), &m);
  EXPECT_TRUE(s.is_ok()) << test::format(s);
  return m;
}

std::string preview_sha(test::TestArena& t, const Mesh& splint, const Mesh& jaw,
                        const std::vector<RigidTransform>& moves) {
  const std::string path = ::testing::TempDir() + "splintcore_preview_test.png";
  cli::PreviewInfo info;
  const size_t used = t.arena.used();
  const Status s =
      cli::write_preview(Context(&t.arena), splint, {&jaw}, moves, path, 128, 128, &info);
  EXPECT_TRUE(s.is_ok()) << test::format(s);
  EXPECT_EQ(t.arena.used(), used);
  std::remove(path.c_str());
  return info.sha256;
}

TEST(DesignPreview, JawsAreDrawnOnlyNearTheSplint) {
  test::TestArena t(size_t{64} << 20);
  const Mesh splint = boxes(&t.arena, {{0, 0, 0, 40, 30, 4}});
  // A tooth on the splint; the same with a root 2 mm beyond the splint's box (drawn: within
  // the margin) or starting 5 mm beyond it (not drawn), and with a far tooth (not drawn).
  const Mesh tooth = boxes(&t.arena, {{10, 10, 2, 16, 16, 9}});
  const Mesh near_root = boxes(&t.arena, {{10, 10, 2, 16, 16, 9}, {12, 12, -2, 14, 14, 2}});
  const Mesh far_root = boxes(&t.arena, {{10, 10, 2, 16, 16, 9}, {12, 12, -20, 14, 14, -5}});
  const Mesh far_tooth = boxes(&t.arena, {{10, 10, 2, 16, 16, 9}, {90, 10, 2, 96, 16, 9}});
  const Mesh far_only = boxes(&t.arena, {{90, 10, 2, 96, 16, 9}});
  const std::string alone = preview_sha(t, splint, tooth, {});
  const std::string splint_only = preview_sha(t, splint, far_only, {});
  EXPECT_EQ(alone.size(), 64u);
  EXPECT_NE(splint_only, alone);
  EXPECT_NE(preview_sha(t, splint, near_root, {}), alone);
  EXPECT_EQ(preview_sha(t, splint, far_root, {}), alone);
  EXPECT_EQ(preview_sha(t, splint, far_tooth, {}), alone);
  // The moves come first: the far tooth moved onto the splint is drawn, the tooth moved
  // 80 mm away is not.
  const std::vector<RigidTransform> back = {RigidTransform::translation(Vec3{-80, 0, 0})};
  EXPECT_EQ(preview_sha(t, splint, far_only, back), alone);
  const std::vector<RigidTransform> away = {RigidTransform::translation(Vec3{80, 0, 0})};
  EXPECT_EQ(preview_sha(t, splint, tooth, away), splint_only);
}

}  // namespace
