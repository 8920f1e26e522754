// The case's jaws from its CT (reconstruct_case_jaws, design.h), beyond the golden design from
// the CT phantom: the argument errors, a stage's error named by its stage, jaws without a seed
// left alone, and the smoothing clamped to half of the smallest voxel spacing whichever axis
// has it.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "common/ct_phantom.h"
#include "splintcore/design.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

using test::TestArena;

CaseFile phantom_case(Arena& arena) {
  const std::vector<uint8_t> text =
      test::read_file_bytes(std::string(SPLINTCORE_FIXTURES_DIR) + "/cases/ct_phantom.json");
  CaseFile c;
  const Status s = parse_case(Context(&arena), reinterpret_cast<const char*>(text.data()),
                              text.size(), "ct_phantom.json", &c);
  EXPECT_TRUE(s.is_ok()) << test::format(s);
  return c;
}

// c's jaws as an array of its own (`storage`), for a test to change.
CaseFile own_jaws(CaseFile c, std::vector<CaseJaw>* storage) {
  storage->assign(c.jaws.begin(), c.jaws.end());
  c.jaws = Span<const CaseJaw>(storage->data(), storage->size());
  return c;
}

bool message_has(const Status& s, const char* text) {
  return std::string(s.message()).find(text) != std::string::npos;
}

// The CT phantom the case is made for, its voxels `spacing` mm, 96 x 96 x 60 mm, no noise.
struct Volume {
  explicit Volume(const Vec3& spacing) {
    cli::CtPhantomOptions po;
    po.spacing = spacing;
    po.nx = static_cast<uint32_t>(96 / spacing.x);
    po.ny = static_cast<uint32_t>(96 / spacing.y);
    po.nz = static_cast<uint32_t>(60 / spacing.z);
    po.noise_hu = 0;
    cli::CtPhantom phantom;
    const Status s = phantom.init(po);
    EXPECT_TRUE(s.is_ok()) << test::format(s);
    phantom.generate(&hu, &volume);
  }
  std::vector<int16_t> hu;
  CtVolume volume;
};

TEST(CaseCtJaws, ArgumentErrorsLeaveTheArenaAndTheMeshesAsTheyWere) {
  TestArena t;
  const CaseFile c = phantom_case(t.arena);
  const Volume v(Vec3{1, 1, 1});
  const size_t top = t.arena.used();
  CaseCtReport report;
  // One mesh for the case's two jaws.
  Mesh one[1] = {Mesh(&t.arena)};
  Status s = reconstruct_case_jaws(Context(&t.arena), c, v.volume, Span<Mesh>(one, 1), &report);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument) << test::format(s);
  EXPECT_TRUE(message_has(s, "names 2 jaws but 1 meshes")) << test::format(s);
  EXPECT_EQ(t.arena.used(), top);
  // The mandible's mesh not empty: it would be reconstructed over.
  Mesh jaws[2] = {Mesh(&t.arena), Mesh(&t.arena)};
  ASSERT_TRUE(jaws[1].vertices.push_back(Vec3{1, 2, 3}));
  const size_t with_vertex = t.arena.used();
  s = reconstruct_case_jaws(Context(&t.arena), c, v.volume, Span<Mesh>(jaws, 2), &report);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument) << test::format(s);
  EXPECT_TRUE(message_has(s, "mesh for jaw 1 must be empty")) << test::format(s);
  EXPECT_EQ(jaws[1].vertices.size(), 1u);
  EXPECT_TRUE(jaws[0].vertices.empty());
  EXPECT_EQ(t.arena.used(), with_vertex);
  // More jaws than a report holds.
  std::vector<CaseJaw> nine_jaws;
  for (uint32_t j = 0; j <= CaseCtReport::kMaxJaws; ++j) nine_jaws.push_back(c.jaws[j % 2]);
  CaseFile many = c;
  many.jaws = Span<const CaseJaw>(nine_jaws.data(), nine_jaws.size());
  std::vector<Mesh> nine(many.jaws.size(), Mesh(&t.arena));
  s = reconstruct_case_jaws(Context(&t.arena), many, v.volume, Span<Mesh>(nine.data(), nine.size()),
                            &report);
  EXPECT_EQ(s.code(), StatusCode::kLimitExceeded) << test::format(s);
}

TEST(CaseCtJaws, OnlySeededJawsAreReconstructed) {
  TestArena t;
  const CaseFile c = phantom_case(t.arena);
  const Volume v(Vec3{1, 1, 1});
  CaseCtReport report;
  // No seed: nothing done, nothing taken.
  std::vector<CaseJaw> storage;
  CaseFile none = own_jaws(c, &storage);
  for (CaseJaw& j : storage) j.has_seed = false;
  Mesh jaws[2] = {Mesh(&t.arena), Mesh(&t.arena)};
  const size_t top = t.arena.used();
  SPLINTCORE_ASSERT_OK(
      reconstruct_case_jaws(Context(&t.arena), none, v.volume, Span<Mesh>(jaws, 2), &report));
  EXPECT_EQ(report.jaws_reconstructed, 0u);
  EXPECT_EQ(t.arena.used(), top);
  // The maxilla's seed alone: the mandible's entry (here a given mesh) is left alone.
  std::vector<CaseJaw> upper_jaws;
  CaseFile upper = own_jaws(c, &upper_jaws);
  upper_jaws[1].has_seed = false;
  ASSERT_TRUE(jaws[1].vertices.push_back(Vec3{1, 2, 3}));
  SPLINTCORE_ASSERT_OK(
      reconstruct_case_jaws(Context(&t.arena), upper, v.volume, Span<Mesh>(jaws, 2), &report));
  EXPECT_EQ(report.jaws_reconstructed, 1u);
  EXPECT_GT(jaws[0].triangles.size(), 1000u);
  EXPECT_EQ(report.triangles[0], jaws[0].triangles.size());
  EXPECT_GT(report.volume_mm3[0], 0.0);
  EXPECT_EQ(report.triangles[1], 0u);
  ASSERT_EQ(jaws[1].vertices.size(), 1u);
  EXPECT_EQ(jaws[1].vertices[0].y, 2.0);
}

TEST(CaseCtJaws, AStagesErrorNamesTheStageAndKeepsItsCodeAndIndex) {
  TestArena t;
  std::vector<CaseJaw> storage;
  const CaseFile c = own_jaws(phantom_case(t.arena), &storage);
  const Volume v(Vec3{1, 1, 1});
  storage[1].seed = Vec3{0, 0, 500};  // the mandible's seed far outside the volume
  Mesh jaws[2] = {Mesh(&t.arena), Mesh(&t.arena)};
  const size_t top = t.arena.used();
  CaseCtReport report;
  const Status s =
      reconstruct_case_jaws(Context(&t.arena), c, v.volume, Span<Mesh>(jaws, 2), &report);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument) << test::format(s);
  EXPECT_EQ(std::string(s.message()).rfind("ct: region growing: seed 1", 0), 0u) << test::format(s);
  EXPECT_EQ(s.index(), 1u);
  EXPECT_EQ(t.arena.used(), top);
  EXPECT_TRUE(jaws[0].vertices.empty() && jaws[1].vertices.empty());
  // The maxilla given as a mesh, not a seed: it stays as it was after the mandible's error.
  storage[0].has_seed = false;
  jaws[0] = Mesh(&t.arena);  // (the error left the seeded entries empty, without an arena)
  jaws[1] = Mesh(&t.arena);
  ASSERT_TRUE(jaws[0].vertices.push_back(Vec3{1, 2, 3}));
  const size_t given = t.arena.used();
  const Status again =
      reconstruct_case_jaws(Context(&t.arena), c, v.volume, Span<Mesh>(jaws, 2), &report);
  EXPECT_EQ(std::string(again.message()).rfind("ct: region growing: seed 0 (label 2)", 0), 0u)
      << test::format(again);
  EXPECT_EQ(t.arena.used(), given);
  EXPECT_EQ(jaws[0].vertices.size(), 1u);
  EXPECT_TRUE(jaws[1].vertices.empty());
}

// The largest distance between a vertex of `a` and the same vertex of `b` (the same mesh
// moved).
double largest_move(const Mesh& a, const Mesh& b) {
  EXPECT_EQ(a.vertices.size(), b.vertices.size());
  double most = 0;
  for (size_t i = 0; i < a.vertices.size() && i < b.vertices.size(); ++i) {
    const double d = length(a.vertices[i] - b.vertices[i]);
    if (d > most) most = d;
  }
  return most;
}

// Smoothing may move a CT surface by half a voxel of the smallest spacing, and does go that
// far on the phantom's voxel steps, whichever axis has the smallest spacing.
TEST(CaseCtJaws, SmoothingIsClampedToHalfTheSmallestSpacing) {
  for (const Vec3& spacing : {Vec3{0.5, 1, 1}, Vec3{1, 0.5, 1}, Vec3{1, 1, 0.5}}) {
    SCOPED_TRACE(spacing.x + 10 * spacing.y + 100 * spacing.z);
    TestArena t;
    CaseFile c = phantom_case(t.arena);
    const Volume v(spacing);
    CaseCtReport report;
    Mesh plain[2] = {Mesh(&t.arena), Mesh(&t.arena)};
    SPLINTCORE_ASSERT_OK(
        reconstruct_case_jaws(Context(&t.arena), c, v.volume, Span<Mesh>(plain, 2), &report));
    c.ct_smooth.iterations = 30;
    Mesh smooth[2] = {Mesh(&t.arena), Mesh(&t.arena)};
    SPLINTCORE_ASSERT_OK(
        reconstruct_case_jaws(Context(&t.arena), c, v.volume, Span<Mesh>(smooth, 2), &report));
    for (int j = 0; j < 2; ++j) {
      ASSERT_EQ(plain[j].triangles.size(), smooth[j].triangles.size());
      const double moved = largest_move(plain[j], smooth[j]);
      EXPECT_LE(moved, 0.25 + 1e-5) << "jaw " << j;  // (both float32: within 4e-6 of exact)
      EXPECT_GE(moved, 0.24) << "jaw " << j;
    }
  }
}

}  // namespace
}  // namespace splintcore
