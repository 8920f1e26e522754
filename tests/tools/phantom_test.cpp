// The synthetic dental-arch phantom (tools/common/phantom.h): valid genus-0 solids at the
// paper's sizes, triangle counts on target, bit-identical bytes (pinned), and the fit to the
// paper_scale case: after the case's transforms the base cuts 1.3-1.6 mm into each of the 28
// crowns, holds each crown's occlusal part inside it (closed pockets), and touches no gum.
#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "common/phantom.h"
#include "splintcore/design.h"
#include "splintcore/distance.h"
#include "splintcore/platform.h"
#include "support/self_intersection_oracle.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

using phantom::Jaw;
using phantom::JawMesh;
using test::TestArena;

constexpr Jaw kJaws[] = {Jaw::kMaxilla, Jaw::kMandible};

const char* jaw_name(Jaw jaw) { return jaw == Jaw::kMaxilla ? "maxilla" : "mandible"; }

JawMesh make(Jaw jaw, uint64_t target) {
  JawMesh m;
  phantom::PhantomOptions options;
  options.target_triangles = target;
  Status s = phantom::make_jaw(jaw, options, &m);
  EXPECT_TRUE(s.is_ok()) << test::format(s);
  return m;
}

bool float32_exact(double v) { return static_cast<double>(static_cast<float>(v)) == v; }

enum class SelfCheck { kSweep, kSweepAndBruteForce };

// Everything a jaw must be, checked with the library: the exact self-intersection sweep, and
// for small jaws also the independent brute-force oracle (every pair of triangles).
void expect_valid_jaw(const JawMesh& m, Jaw jaw, uint64_t target, SelfCheck self_check) {
  SCOPED_TRACE(std::string(jaw_name(jaw)) + " at " + std::to_string(target) + " triangles");
  const double count = static_cast<double>(m.triangles.size());
  EXPECT_LE(std::abs(count - static_cast<double>(target)), 0.01 * static_cast<double>(target));
  EXPECT_EQ(m.triangles.size(), size_t{2} * m.sections * m.ring_size);
  ASSERT_EQ(m.vertices.size(), size_t{m.sections} * m.ring_size + 2);
  ASSERT_EQ(m.vertex_tooth.size(), m.vertices.size());

  // float32-exact and pairwise distinct (as float32: they are exact).
  std::vector<std::array<double, 3>> sorted;
  sorted.reserve(m.vertices.size());
  for (const Vec3& v : m.vertices) {
    ASSERT_TRUE(float32_exact(v.x) && float32_exact(v.y) && float32_exact(v.z));
    sorted.push_back({v.x, v.y, v.z});
  }
  std::sort(sorted.begin(), sorted.end());
  EXPECT_TRUE(std::adjacent_find(sorted.begin(), sorted.end()) == sorted.end());

  // The sweep never lets sections cross.
  EXPECT_GT(m.min_path_radius_mm, 2.0 * m.max_concave_reach_mm);

  TestArena t(size_t{1} << 30);
  Context ctx(&t.arena);
  Mesh mesh(&t.arena);
  SPLINTCORE_ASSERT_OK(phantom::to_mesh(m, &mesh));
  MeshReport r;
  SPLINTCORE_ASSERT_OK(check_mesh(ctx, mesh, &r));
  EXPECT_TRUE(r.is_valid_solid()) << test::format(require_valid_solid(r));
  EXPECT_EQ(r.unreferenced_vertices, 0u);
  EXPECT_EQ(r.shells, 1u);
  EXPECT_EQ(r.euler_characteristic, 2);
  EXPECT_EQ(r.genus, 0);
  EXPECT_GT(r.volume, 0.0);
  SelfIntersectionReport si;
  SPLINTCORE_ASSERT_OK(find_self_intersections(ctx, mesh, 1, &si));
  EXPECT_FALSE(si.self_intersecting()) << "triangles " << si.first_a << " and " << si.first_b;
  if (self_check == SelfCheck::kSweepAndBruteForce) {
    const brute::Brute b = brute::brute_force(mesh);
    EXPECT_EQ(b.pairs, 0u) << "triangles " << b.first_a << " and " << b.first_b;
    EXPECT_GT(b.candidates, 0u);
  }
  // The crowns point to the base: down for the maxilla, up for the mandible.
  uint64_t crown_vertices = 0;
  for (uint8_t label : m.vertex_tooth) crown_vertices += label != phantom::kGumLabel ? 1 : 0;
  EXPECT_GT(crown_vertices, m.vertices.size() / 10);
}

TEST(Phantom, SmallJawsAreValidSolids) {
  for (Jaw jaw : kJaws) {
    expect_valid_jaw(make(jaw, 3000), jaw, 3000, SelfCheck::kSweepAndBruteForce);
  }
}

TEST(Phantom, PaperSizedJawsAreValidSolids) {
  for (Jaw jaw : kJaws) expect_valid_jaw(make(jaw, 86866), jaw, 86866, SelfCheck::kSweep);
}

TEST(Phantom, LargestPaperSizeIsAValidSolid) {
  const double t0 = monotonic_seconds();
  const JawMesh m = make(Jaw::kMaxilla, 543530);
  const double seconds = monotonic_seconds() - t0;
  EXPECT_LT(seconds, 5.0);
  expect_valid_jaw(m, Jaw::kMaxilla, 543530, SelfCheck::kSweep);
}

TEST(Phantom, TriangleCountsLandWithinOnePercent) {
  for (uint64_t target = phantom::kMinTriangles; target <= phantom::kMaxTriangles;
       target += target / 7 + 1) {
    const phantom::GridSize g = phantom::choose_grid(target);
    const double got = 2.0 * g.sections * g.ring_size;
    EXPECT_LE(std::abs(got - static_cast<double>(target)), 0.01 * static_cast<double>(target))
        << target;
    EXPECT_GE(g.ring_size, 10u);
  }
  for (uint64_t target : {uint64_t{86866}, uint64_t{324246}, uint64_t{543530}}) {
    const phantom::GridSize g = phantom::choose_grid(target);
    EXPECT_LE(std::abs(2.0 * g.sections * g.ring_size - static_cast<double>(target)),
              0.001 * static_cast<double>(target));
  }
}

TEST(Phantom, RejectsTargetsOutOfRange) {
  JawMesh m;
  phantom::PhantomOptions options;
  options.target_triangles = phantom::kMinTriangles - 1;
  EXPECT_EQ(phantom::make_jaw(Jaw::kMaxilla, options, &m).code(), StatusCode::kInvalidArgument);
  options.target_triangles = phantom::kMaxTriangles + 1;
  EXPECT_EQ(phantom::make_jaw(Jaw::kMandible, options, &m).code(), StatusCode::kInvalidArgument);
  EXPECT_TRUE(m.triangles.empty());
  EXPECT_EQ(phantom::choose_grid(0).ring_size, 0u);
}

// Pinned: the same on every compiler, optimisation level and CPU (only + - * / sqrt, float32
// rounding at the end). A change here is a change of the phantom: say so in the commit.
TEST(Phantom, BytesAreDeterministicAndPinned) {
  const char* const kGolden[2] = {
      "8db350be4133710b9da02988851ead7aac6c85054da6af94374133840b3e3c08",
      "c3aa69d64ae2a8104f3194c057ed921dce62ac8012e10bb6673a148ce6155c81",
  };
  for (Jaw jaw : kJaws) {
    std::vector<uint8_t> first, second;
    SPLINTCORE_ASSERT_OK(phantom::stl_bytes(make(jaw, 3000), &first));
    SPLINTCORE_ASSERT_OK(phantom::stl_bytes(make(jaw, 3000), &second));
    EXPECT_EQ(first.size(), 84u + 50u * 3000u);
    EXPECT_TRUE(first == second);
    EXPECT_EQ(test::sha256_hex(first.data(), first.size()), kGolden[jaw == Jaw::kMandible])
        << jaw_name(jaw);
    // What the library reads back is the mesh itself.
    TestArena t(size_t{64} << 20);
    Mesh back;
    SPLINTCORE_ASSERT_OK(test::mesh_from_bytes(t.arena, first, &back));
    const JawMesh m = make(jaw, 3000);
    ASSERT_EQ(back.vertices.size(), m.vertices.size());
    for (size_t i = 0; i < back.triangles.size(); ++i) {
      for (int k = 0; k < 3; ++k) {
        ASSERT_EQ(back.vertices[back.triangles[i].v[k]], m.vertices[m.triangles[i].v[k]]);
      }
    }
  }
}

// ---- the fit to fixtures/cases/paper_scale.json ---------------------------------------------

struct CaseBase {
  TestArena arena{size_t{256} << 20};
  CaseFile file;
  Mesh mesh;
  DistanceIndex index;
};

void build_paper_scale_base(CaseBase* b) {
  const std::vector<uint8_t> text =
      test::read_file_bytes(std::string(SPLINTCORE_FIXTURES_DIR) + "/cases/paper_scale.json");
  ASSERT_FALSE(text.empty());
  Context ctx(&b->arena.arena);
  SPLINTCORE_ASSERT_OK(parse_case(ctx, reinterpret_cast<const char*>(text.data()), text.size(),
                                  "paper_scale.json", &b->file));
  b->mesh.bind(&b->arena.arena);
  BaseReport report;
  SPLINTCORE_ASSERT_OK(build_case_base(ctx, b->file, &b->mesh, &report));
  SPLINTCORE_ASSERT_OK(build_distance_index(ctx, b->mesh, DistanceIndexOptions{}, &b->index));
}

RigidTransform case_transform(const CaseFile& c, Jaw jaw) {
  for (const CaseJaw& j : c.jaws) {
    if (std::string(j.role) == jaw_name(jaw)) return j.transform;
  }
  ADD_FAILURE() << "no " << jaw_name(jaw) << " in the case";
  return RigidTransform{};
}

TEST(Phantom, PaperScaleBaseCutsEveryCrownAndNoGum) {
  CaseBase base;
  build_paper_scale_base(&base);
  if (HasFatalFailure()) return;
  for (Jaw jaw : kJaws) {
    SCOPED_TRACE(jaw_name(jaw));
    const JawMesh m = make(jaw, 86866);
    const RigidTransform x = case_transform(base.file, jaw);
    // The base face each jaw's crowns meet (after the transform): +1.6 above the maxilla's
    // crowns, -1.6 below the mandible's.
    const double face = jaw == Jaw::kMaxilla ? 1.6 : -1.6;
    const double towards_base = jaw == Jaw::kMaxilla ? -1.0 : 1.0;
    double deepest[phantom::kTeethPerJaw];
    for (double& d : deepest) d = HUGE_VAL;
    double gum_nearest = HUGE_VAL;
    uint64_t escaped = 0;
    for (size_t i = 0; i < m.vertices.size(); ++i) {
      const Vec3 p = x.apply_point(m.vertices[i]);
      SignedDistance sd;
      ASSERT_TRUE(signed_distance(base.index, p, SignMethod::kAuto, &sd));
      const uint8_t tooth = m.vertex_tooth[i];
      if (tooth == phantom::kGumLabel) {
        gum_nearest = std::min(gum_nearest, sd.distance);
        continue;
      }
      ASSERT_LT(tooth, phantom::kTeethPerJaw);
      deepest[tooth] = std::min(deepest[tooth], sd.distance);
      // Past the face (by more than float rounding), a crown is inside the base: it enters
      // through the face only, so its imprint is a closed pocket.
      if ((p.z - face) * towards_base > 1e-3 && !(sd.distance < 0.0)) ++escaped;
    }
    EXPECT_EQ(escaped, 0u);
    EXPECT_GT(gum_nearest, 1.0);  // the gum ridges stay clear of the base
    for (uint32_t k = 0; k < phantom::kTeethPerJaw; ++k) {
      EXPECT_LE(deepest[k], -1.3) << "tooth " << k;
      EXPECT_GE(deepest[k], -1.6) << "tooth " << k;
      // As designed (the sampled tip lies at most a little short of the designed one).
      EXPECT_GE(deepest[k], -m.tooth_depth_mm[k] - 1e-4) << "tooth " << k;
      EXPECT_LE(deepest[k], -m.tooth_depth_mm[k] + 0.05) << "tooth " << k;
    }
  }
}

// Big end up: each crown is widest inside the base, so on both its buccal and its lingual
// side some wall triangles there face away from the base's face (towards the gum): undercuts
// along the insertion direction.
TEST(Phantom, CrownsHaveBuccalAndLingualUndercutsInsideTheBase) {
  for (Jaw jaw : kJaws) {
    SCOPED_TRACE(jaw_name(jaw));
    const JawMesh m = make(jaw, 86866);
    const double towards_base = jaw == Jaw::kMaxilla ? -1.0 : 1.0;
    const double face = jaw == Jaw::kMaxilla ? 1.6 : 0.4;  // in occlusion
    double steepest[phantom::kTeethPerJaw];  // smallest normal component along towards_base
    uint32_t buccal[phantom::kTeethPerJaw] = {}, lingual[phantom::kTeethPerJaw] = {};
    for (double& s : steepest) s = 1.0;
    for (const Triangle& t : m.triangles) {
      const uint8_t tooth = m.vertex_tooth[t.v[0]];
      if (tooth == phantom::kGumLabel || m.vertex_tooth[t.v[1]] != tooth ||
          m.vertex_tooth[t.v[2]] != tooth) {
        continue;
      }
      const Vec3& a = m.vertices[t.v[0]];
      const Vec3& b = m.vertices[t.v[1]];
      const Vec3& c = m.vertices[t.v[2]];
      const bool inside = (a.z - face) * towards_base > 0.1 && (b.z - face) * towards_base > 0.1 &&
                          (c.z - face) * towards_base > 0.1;
      if (!inside) continue;
      const Vec3 n = cross(b - a, c - a);
      const double along = n.z * towards_base / length(n);
      steepest[tooth] = std::min(steepest[tooth], along);
      if (along > -0.1) continue;
      // Buccal faces look away from the arch's middle (the origin is inside the arch), lingual
      // faces towards it.
      const Vec3 mid = (a + b + c) * (1.0 / 3.0);
      const double side = (n.x * mid.x + n.y * mid.y) / (std::sqrt(n.x * n.x + n.y * n.y) *
                                                         std::sqrt(mid.x * mid.x + mid.y * mid.y));
      if (side > 0.5) ++buccal[tooth];
      if (side < -0.5) ++lingual[tooth];
    }
    for (uint32_t k = 0; k < phantom::kTeethPerJaw; ++k) {
      EXPECT_LT(steepest[k], -0.15) << "tooth " << k;
      EXPECT_GE(buccal[k], 5u) << "tooth " << k;
      EXPECT_GE(lingual[k], 5u) << "tooth " << k;
    }
  }
}

}  // namespace
}  // namespace splintcore
