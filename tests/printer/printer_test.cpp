#include "splintcore/printer.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

using test::TestArena;

PrintCheck run_check(TestArena& t, const std::vector<SoupTriangle>& soup,
                     const PrintCheckOptions& options = PrintCheckOptions{}) {
  Mesh mesh;
  Status s = test::mesh_from_soup(t.arena, soup, &mesh);
  EXPECT_TRUE(s.is_ok()) << test::format(s);
  PrintCheck pc;
  Context ctx(&t.arena);
  s = check_printable(ctx, mesh, eden260_profile(), options, &pc);
  EXPECT_TRUE(s.is_ok()) << test::format(s);
  return pc;
}

TEST(Printer, Eden260Profile) {
  const PrinterProfile* p = find_printer_profile("eden260");
  ASSERT_NE(p, nullptr);
  EXPECT_EQ(p->build_volume_mm, (Vec3{255, 252, 200}));
  EXPECT_DOUBLE_EQ(p->layer_thickness_mm, 0.016);
  EXPECT_EQ(find_printer_profile("eden999"), nullptr);
}

TEST(Printer, SplintSizedBoxIsPrintableAndPlacedOnTheTray) {
  TestArena t;
  const float lo[3] = {10, -20, 40}, hi[3] = {80, 50, 56};
  PrintCheck pc = run_check(t, shapes::box(lo, hi));
  EXPECT_TRUE(pc.printable);
  EXPECT_TRUE(pc.fits);
  EXPECT_EQ(pc.layers, 1000u);  // 16 mm / 0.016 mm
  EXPECT_FALSE(pc.units_suspect);
  Vec3 placed_lo = pc.placement.apply_point(Vec3{10, -20, 40});
  Vec3 placed_hi = pc.placement.apply_point(Vec3{80, 50, 56});
  EXPECT_DOUBLE_EQ(placed_lo.z, 0.0);
  EXPECT_DOUBLE_EQ(placed_lo.x + placed_hi.x, 255.0);  // centred
  EXPECT_DOUBLE_EQ(placed_lo.y + placed_hi.y, 252.0);
  EXPECT_TRUE(require_printable(pc, eden260_profile()).is_ok());
}

TEST(Printer, TooLargeAndRotatedFits) {
  TestArena t;
  const float lo[3] = {0, 0, 0}, big[3] = {300, 20, 20};
  PrintCheck pc = run_check(t, shapes::box(lo, big));
  EXPECT_FALSE(pc.fits);
  EXPECT_FALSE(pc.fits_rotated);
  EXPECT_FALSE(pc.printable);
  Status s = require_printable(pc, eden260_profile());
  EXPECT_NE(std::strstr(s.message(), "does not fit"), nullptr) << s.message();
  // 246 mm long in y: over the 242 mm usable y (252 - 2 x 5 margin) but fits turned in x.
  const float tall[3] = {20, 244, 20};
  pc = run_check(t, shapes::box(lo, tall));
  EXPECT_FALSE(pc.fits);
  EXPECT_TRUE(pc.fits_rotated);
  EXPECT_TRUE(pc.printable);
}

// The fit is inclusive: a part exactly as large as the room (the tray less its margins, the
// whole height) fits, as a row of parts exactly as wide as the tray and a part exactly as deep
// and high as it are placed. A profile without a positive build volume or layer thickness is
// refused by name.
TEST(Printer, ExactFitsFitAndABadProfileIsRefused) {
  TestArena t;
  const float lo[3] = {0, 0, 0}, room[3] = {245, 242, 200};
  PrintCheck pc = run_check(t, shapes::box(lo, room));
  EXPECT_TRUE(pc.fits);
  EXPECT_TRUE(pc.printable);
  const PrinterProfile& p = eden260_profile();
  const Aabb row[2] = {Aabb{{0, 0, 0}, {125, 10, 10}}, Aabb{{0, 0, 0}, {125, 252, 200}}};
  Vec3 moved[2];
  SPLINTCORE_EXPECT_OK(arrange_on_tray(p, Span<const Aabb>(row, 2), 5.0, moved));
  EXPECT_DOUBLE_EQ(moved[0].x, 0.0);
  Mesh mesh;
  ASSERT_TRUE(test::mesh_from_soup(t.arena, shapes::box(lo, room), &mesh).is_ok());
  for (int k = 0; k < 4; ++k) {
    PrinterProfile bad = p;
    if (k < 3) {
      (k == 0   ? bad.build_volume_mm.x
       : k == 1 ? bad.build_volume_mm.y
                : bad.build_volume_mm.z) = 0.0;
    } else {
      bad.layer_thickness_mm = 0.0;
    }
    PrintCheck out;
    const Status s = check_printable(Context(&t.arena), mesh, bad, PrintCheckOptions{}, &out);
    EXPECT_EQ(s.code(), StatusCode::kInvalidArgument) << k;
    EXPECT_NE(test::format(s).find("'eden260' has a non-positive"), std::string::npos)
        << test::format(s);
  }
}

TEST(Printer, MetresAreSuspect) {
  TestArena t;
  const float lo[3] = {0, 0, 0}, hi[3] = {0.07f, 0.06f, 0.02f};
  PrintCheck pc = run_check(t, shapes::box(lo, hi));
  EXPECT_TRUE(pc.units_suspect);
}

}  // namespace
}  // namespace splintcore

namespace splintcore {
namespace {

// Issue 32's print job: parts in a row along x, the gap between boxes exactly as asked, the
// row centred, each part centred in y, bottoms at z = 0; what does not fit is named.
TEST(ArrangeOnTray, RowCentredWithTheGapAndRefusalsNamed) {
  const PrinterProfile& p = eden260_profile();
  const Aabb boxes[2] = {Aabb{{-10, -5, 3}, {30, 15, 9}}, Aabb{{100, 0, -2}, {160, 40, 4}}};
  Vec3 t[2];
  SPLINTCORE_ASSERT_OK(arrange_on_tray(p, Span<const Aabb>(boxes, 2), 5.0, t));
  const Aabb placed[2] = {Aabb{boxes[0].lo + t[0], boxes[0].hi + t[0]},
                          Aabb{boxes[1].lo + t[1], boxes[1].hi + t[1]}};
  EXPECT_DOUBLE_EQ(placed[1].lo.x - placed[0].hi.x, 5.0);
  EXPECT_DOUBLE_EQ(placed[0].lo.x + placed[1].hi.x, p.build_volume_mm.x);  // centred row
  for (const Aabb& b : placed) {
    EXPECT_DOUBLE_EQ(b.lo.z, 0.0);
    EXPECT_DOUBLE_EQ(b.lo.y + b.hi.y, p.build_volume_mm.y);
  }
  Vec3 unused[2];
  const Aabb wide[2] = {Aabb{{0, 0, 0}, {130, 10, 10}}, Aabb{{0, 0, 0}, {130, 10, 10}}};
  const Status s = arrange_on_tray(p, Span<const Aabb>(wide, 2), 5.0, unused);
  EXPECT_EQ(s.code(), StatusCode::kLimitExceeded);
  EXPECT_NE(test::format(s).find("265 mm long"), std::string::npos) << test::format(s);
  const Aabb deep[1] = {Aabb{{0, 0, 0}, {10, 300, 10}}};
  EXPECT_EQ(arrange_on_tray(p, Span<const Aabb>(deep, 1), 5.0, unused).code(),
            StatusCode::kLimitExceeded);
  EXPECT_EQ(arrange_on_tray(p, Span<const Aabb>(boxes, 2), -1.0, unused).code(),
            StatusCode::kInvalidArgument);
  EXPECT_EQ(arrange_on_tray(p, Span<const Aabb>(), 5.0, unused).code(),
            StatusCode::kInvalidArgument);
  const Aabb empty[1] = {Aabb{}};
  EXPECT_EQ(arrange_on_tray(p, Span<const Aabb>(empty, 1), 5.0, unused).code(),
            StatusCode::kInvalidArgument);
  // The bounds of what is allowed: no gap (the parts touch), and a part flat along every axis
  // (a point: its bounds are finite, so it is placed, however little it is).
  SPLINTCORE_ASSERT_OK(arrange_on_tray(p, Span<const Aabb>(boxes, 2), 0.0, t));
  EXPECT_DOUBLE_EQ(boxes[1].lo.x + t[1].x, boxes[0].hi.x + t[0].x);
  const Aabb point[1] = {Aabb{{1, 2, 3}, {1, 2, 3}}};
  SPLINTCORE_ASSERT_OK(arrange_on_tray(p, Span<const Aabb>(point, 1), 5.0, t));
  EXPECT_EQ(point[0].lo + t[0], (Vec3{0.5 * p.build_volume_mm.x, 0.5 * p.build_volume_mm.y, 0.0}));
}

}  // namespace
}  // namespace splintcore
