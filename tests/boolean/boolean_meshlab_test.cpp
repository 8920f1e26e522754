// MeshLab (meshlabserver) as an independent oracle of the Boolean: the paper-scale base minus
// the phantom maxilla, written as STL, is watertight and two-manifold for MeshLab with our
// volume; and the imprint (the result's triangles that came from the jaw) lies on the jaw:
// MeshLab's Hausdorff distance from the imprint to the jaw is below 1e-6 mm.
//
// MeshLab computes in float and prints six decimals, so the imprint and the jaw are measured
// around one crown at a time (the imprint within 2 mm of a point, the jaw's triangles that reach
// within 3 mm), moved to the origin and scaled from mm to um: MeshLab's own noise (the jaw against
// itself, printed too) is then a few 1e-4 um, and six decimals resolve 1e-6 um. The result is
// computed in double for this (float32_output off): the intersection points are then the exact
// crossings rounded once to double, and what is measured is the method, not STL's float32 grid.
#include <cstdio>
#include <string>
#include <vector>

#include "common/phantom.h"
#include "splintcore/boolean.h"
#include "splintcore/design.h"
#include "support/meshlab.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

struct Fixture {
  test::TestArena t{size_t{256} << 20};
  Mesh base;
  Mesh jaw;
  bool ok = false;

  Fixture() {
    Context ctx(&t.arena);
    std::vector<uint8_t> text =
        test::read_file_bytes(std::string(SPLINTCORE_FIXTURES_DIR) + "/cases/paper_scale.json");
    CaseFile c;
    if (!parse_case(ctx, reinterpret_cast<const char*>(text.data()), text.size(), "paper_scale", &c)
             .is_ok()) {
      return;
    }
    base.bind(&t.arena);
    BaseReport r;
    if (!build_case_base(ctx, c, &base, &r).is_ok()) return;
    phantom::JawMesh m;
    phantom::PhantomOptions po;
    po.target_triangles = 12000;
    if (!phantom::make_jaw(phantom::Jaw::kMaxilla, po, &m).is_ok()) return;
    jaw.bind(&t.arena);
    for (const Vec3& v : m.vertices) (void)jaw.vertices.push_back(v);
    for (const Triangle& tr : m.triangles) (void)jaw.triangles.push_back(tr);
    ok = true;
  }
};

// Binary STL of the triangles [first, last) of `m` whose corners all lie in `box` (or, with
// `touching`, whose bounds meet it), moved by -centre and scaled by `scale`.
std::vector<uint8_t> region_stl(const Mesh& m, size_t first, size_t last, const Aabb& box,
                                bool touching, const Vec3& centre, double scale, size_t* count) {
  std::vector<SoupTriangle> soup;
  for (size_t t = first; t < last; ++t) {
    const Triangle& tr = m.triangles[t];
    bool inside = true;
    Aabb tb;
    for (uint32_t v : tr.v) {
      inside = inside && box.contains(m.vertices[v]);
      tb.add(m.vertices[v]);
    }
    if (touching ? !tb.overlaps(box) : !inside) continue;
    SoupTriangle s;
    for (int k = 0; k < 3; ++k) {
      const Vec3 p = (m.vertices[tr.v[k]] - centre) * scale;
      for (int a = 0; a < 3; ++a) s.p[k][a] = static_cast<float>(p[a]);
    }
    soup.push_back(s);
  }
  *count = soup.size();
  return test::binary_stl(soup);
}

TEST(BooleanMeshLab, WrittenDifferenceIsWatertightTwoManifoldWithOurVolume) {
  if (!test::have_meshlab()) GTEST_SKIP() << "meshlabserver/xvfb-run not installed";
  Fixture f;
  ASSERT_TRUE(f.ok);
  Mesh out;
  BooleanStats st;
  BooleanOptions o;  // float32, as written
  SPLINTCORE_ASSERT_OK(mesh_boolean(Context(&f.t.arena), f.base, f.jaw, o, &out, &st));
  ASSERT_GT(st.intersecting_pairs, 0u);
  std::vector<uint8_t> bytes;
  SPLINTCORE_ASSERT_OK(test::mesh_to_bytes(f.t.arena, out, StlFormat::kBinary, &bytes));
  const std::string log = test::meshlab_log_of_bytes(bytes);
  EXPECT_NE(log.find("Mesh is two-manifold"), std::string::npos) << log;
  EXPECT_NE(log.find("Boundary Edges 0"), std::string::npos) << log;
  const double theirs = test::number_after(log, "Mesh Volume  is ");
  const double ours = mesh_volume(out);
  EXPECT_NEAR(theirs, ours, 1e-5 * ours);  // MeshLab sums in float
}

TEST(BooleanMeshLab, ImprintLiesOnTheJawWithin1e6mm) {
  if (!test::have_meshlab()) GTEST_SKIP() << "meshlabserver/xvfb-run not installed";
  Fixture f;
  ASSERT_TRUE(f.ok);
  Mesh out;
  BooleanStats st;
  BooleanOptions o;
  o.float32_output = false;
  SPLINTCORE_ASSERT_OK(mesh_boolean(Context(&f.t.arena), f.base, f.jaw, o, &out, &st));
  const size_t first_b = static_cast<size_t>(st.output_triangles_a);
  ASSERT_LT(first_b, out.triangles.size());
  const std::string script = std::string(SPLINTCORE_FIXTURES_DIR) + "/meshlab/hausdorff.mlx";
  // Three crowns along the arch: around the imprint vertex nearest to each chosen point.
  int measured = 0;
  for (double fraction : {0.1, 0.5, 0.9}) {
    const size_t t = first_b + static_cast<size_t>(fraction * (out.triangles.size() - first_b));
    const Vec3 centre = out.vertices[out.triangles[t].v[0]];
    Aabb inner, outer;
    inner.add(centre - Vec3{2, 2, 2});
    inner.add(centre + Vec3{2, 2, 2});
    outer.add(centre - Vec3{3, 3, 3});
    outer.add(centre + Vec3{3, 3, 3});
    size_t n_imprint = 0, n_jaw = 0;
    const std::string imprint = test::temp_file(
        region_stl(out, first_b, out.triangles.size(), inner, false, centre, 1000.0, &n_imprint));
    const std::string jaw = test::temp_file(
        region_stl(f.jaw, 0, f.jaw.triangles.size(), outer, true, centre, 1000.0, &n_jaw));
    ASSERT_GE(n_imprint, 5u);
    const std::string log = test::meshlab_log({imprint, jaw}, script);
    // The jaw against itself shows MeshLab's own noise at this scale.
    const std::string self = test::meshlab_log({jaw, jaw}, script);
    std::remove(imprint.c_str());
    std::remove(jaw.c_str());
    const double max_um = test::number_after(log, "max ");
    const double mean_um = test::number_after(log, "mean : ");
    const double noise_um = test::number_after(self, "max ");
    ASSERT_FALSE(std::isnan(max_um)) << log;
    std::printf(
        "crown at %.3f %.3f %.3f: %zu imprint triangles, Hausdorff max %.6f um, mean "
        "%.6f um (MeshLab's noise %.6f um)\n",
        centre.x, centre.y, centre.z, n_imprint, max_um, mean_um, noise_um);
    EXPECT_LT(max_um, 1e-3) << log;  // 1e-6 mm
    ++measured;
  }
  EXPECT_EQ(measured, 3);
}

// The exact coplanar rule (no nudge, so no film): [0,1]^3 - [0.5,1.5] x [0,1] x [0,1], whose
// faces share four planes, written as float32 STL, is watertight and two-manifold for MeshLab,
// with the exact volume 0.5.
TEST(BooleanMeshLab, CoplanarDifferenceIsWatertight) {
  if (!test::have_meshlab()) GTEST_SKIP() << "meshlabserver/xvfb-run not installed";
  test::TestArena t;
  Arena& arena = t.arena;
  auto box = [&](const Vec3& lo, const Vec3& hi) {
    Mesh m(&arena);
    for (int i = 0; i < 8; ++i) {
      EXPECT_TRUE(m.vertices.push_back(
          Vec3{(i & 1) ? hi.x : lo.x, (i & 2) ? hi.y : lo.y, (i & 4) ? hi.z : lo.z}));
    }
    const uint32_t f[12][3] = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}, {0, 1, 5}, {0, 5, 4},
                               {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
    for (const auto& tr : f) EXPECT_TRUE(m.triangles.push_back(Triangle{{tr[0], tr[1], tr[2]}}));
    return m;
  };
  const Mesh a = box({0, 0, 0}, {1, 1, 1});
  const Mesh b = box({0.5, 0, 0}, {1.5, 1, 1});
  Mesh out;
  BooleanStats st;
  BooleanOptions o;  // float32, as written
  o.max_nudges = 0;
  SPLINTCORE_ASSERT_OK(mesh_boolean(Context(&arena), a, b, o, &out, &st));
  EXPECT_EQ(st.attempts, 1u);
  ASSERT_GT(out.triangles.size(), 0u);
  std::vector<uint8_t> bytes;
  SPLINTCORE_ASSERT_OK(test::mesh_to_bytes(arena, out, StlFormat::kBinary, &bytes));
  const std::string log = test::meshlab_log_of_bytes(bytes);
  EXPECT_NE(log.find("Mesh is two-manifold"), std::string::npos) << log;
  EXPECT_NE(log.find("Boundary Edges 0"), std::string::npos) << log;
  EXPECT_NEAR(test::number_after(log, "Mesh Volume  is "), 0.5, 1e-5) << log;
  EXPECT_EQ(mesh_volume(out), 0.5);
}

}  // namespace
}  // namespace splintcore
