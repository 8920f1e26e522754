// Open jaws in design (issue 30's proof): the scan-like phantom (tools/common/scan_phantom.cpp:
// open surfaces of crowns and gum with a ragged border, holes, islands, flaps, duplicates, a
// flipped patch, noise), several seeds, both arches, each prepared (prepare_scan, as
// `splintcore prepare` does) and designed as the case's maxilla and mandible with the picks of
// fixtures/cases/paper_scale.json (the phantom follows its arch). Every splint is a closed,
// edge-manifold, oriented, outward solid without degenerate triangles, checked for
// self-intersections and printable; its imprint is the scans' own vertices bit for bit: every
// scan vertex strictly inside the base is a splint vertex, and every splint vertex strictly
// inside the base is a scan vertex (no blockout here). MeshLab agrees when present (two-manifold,
// no boundary edge, the same volume). The Teeth3DS scan: DesignTeeth3dsRealData (fusion_test.cpp).
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <set>
#include <string>
#include <vector>

#include "common/phantom.h"
#include "splintcore/design.h"
#include "splintcore/distance.h"
#include "support/meshlab.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

using Key = std::array<float, 3>;

Key key(const Vec3& v) {
  return {static_cast<float>(v.x), static_cast<float>(v.y), static_cast<float>(v.z)};
}

// The scan-like phantom of `which` for `seed`, prepared with the default options.
Status prepared_scan(Arena& arena, phantom::Jaw which, uint64_t seed, Mesh* out,
                     PrepareReport* report) {
  phantom::ScanOptions so;
  so.seed = seed;
  phantom::ScanJaw jaw;
  SPLINTCORE_RETURN_IF_ERROR(phantom::make_scan_jaw(which, so, &jaw));
  Mesh raw(&arena);
  if (!raw.vertices.reserve(jaw.vertices.size()) || !raw.triangles.reserve(jaw.triangles.size())) {
    return arena.exhausted_status();
  }
  for (const Vec3& v : jaw.vertices) (void)raw.vertices.push_back(v);
  for (const Triangle& t : jaw.triangles) (void)raw.triangles.push_back(t);
  return prepare_scan(Context(&arena), raw, PrepareOptions{}, out, report);
}

TEST(DesignOpenScans, PhantomScansOfBothArchesMakeValidSplintsWithScanImprints) {
  const std::vector<uint8_t> text =
      test::read_file_bytes(std::string(SPLINTCORE_FIXTURES_DIR) + "/cases/paper_scale.json");
  for (uint64_t seed : {1u, 2u, 7u}) {
    SCOPED_TRACE(testing::Message() << "seed " << seed);
    test::TestArena t{size_t{256} << 20};
    Context ctx(&t.arena);
    CaseFile c;
    SPLINTCORE_ASSERT_OK(parse_case(ctx, reinterpret_cast<const char*>(text.data()), text.size(),
                                    "paper_scale", &c));
    // The scan phantom's jaws stand in the case's frame as they are (the solid phantom's
    // mandible is made in occlusion and moved by the case; the scan's is not).
    CaseJaw case_jaws[2] = {c.jaws[0], c.jaws[1]};
    case_jaws[1].transform = RigidTransform{};
    c.jaws = Span<const CaseJaw>(case_jaws, 2);
    Mesh jaws[2];
    for (int j = 0; j < 2; ++j) {
      PrepareReport pr;
      SPLINTCORE_ASSERT_OK(prepared_scan(
          t.arena, j == 0 ? phantom::Jaw::kMaxilla : phantom::Jaw::kMandible, seed, &jaws[j], &pr));
      MeshReport open;
      SPLINTCORE_ASSERT_OK(check_mesh(ctx, jaws[j], &open));
      ASSERT_FALSE(open.closed());  // an open surface: its border is the scan's
      ASSERT_EQ(open.boundary_loops, 1u);
    }
    Mesh splint;
    DesignReport r;
    SPLINTCORE_ASSERT_OK(design_splint(ctx, c, Span<const Mesh>(jaws, 2), &splint, &r));
    EXPECT_TRUE(r.print.printable);
    EXPECT_TRUE(r.self_intersection_checked);
    MeshReport mr;
    SPLINTCORE_ASSERT_OK(check_mesh(ctx, splint, &mr));
    EXPECT_TRUE(mr.is_valid_solid())
        << mr.boundary_edges << " " << mr.nonmanifold_edges << " " << mr.orientation_conflicts
        << " " << mr.degenerate_triangles << " " << mr.duplicate_triangles;
    EXPECT_EQ(mr.shells, 1u);
    // The base the design cut, and the splint's and the scans' vertices strictly inside it
    // (winding number, more than 1e-3 mm from its surface).
    Mesh base(&t.arena);
    BaseReport br;
    SPLINTCORE_ASSERT_OK(build_case_base(ctx, c, &base, &br));
    DistanceIndex index;
    SPLINTCORE_ASSERT_OK(build_distance_index(ctx, base, DistanceIndexOptions{}, &index));
    const auto inside = [&](const Vec3& v) {
      ClosestPoint cp;
      return closest_point(index, v, &cp) && cp.distance > 1e-3 && winding_number(index, v) > 0.5;
    };
    std::set<Key> splint_at, scan_at;
    for (const Vec3& v : splint.vertices) splint_at.insert(key(v));
    size_t scan_inside = 0, kept = 0;
    for (int j = 0; j < 2; ++j) {
      for (const Vec3& v : jaws[j].vertices) {
        scan_at.insert(key(v));
        if (!inside(v)) continue;
        ++scan_inside;
        kept += splint_at.count(key(v));
      }
    }
    EXPECT_GT(scan_inside, 1000u);
    EXPECT_EQ(kept, scan_inside);  // every scan vertex inside the base is a splint vertex
    size_t splint_inside = 0, from_scans = 0;
    for (const Vec3& v : splint.vertices) {
      if (!inside(v)) continue;
      ++splint_inside;
      from_scans += scan_at.count(key(v));
    }
    EXPECT_EQ(from_scans, splint_inside);  // and every splint vertex inside it is a scan vertex
    if (test::have_meshlab()) {  // the independent oracle: two-manifold, no border, same volume
      std::vector<uint8_t> stl;
      SPLINTCORE_ASSERT_OK(test::mesh_to_bytes(t.arena, splint, StlFormat::kBinary, &stl));
      const std::string log = test::meshlab_log_of_bytes(stl);
      EXPECT_NE(log.find("Mesh is two-manifold"), std::string::npos) << log;
      EXPECT_NE(log.find("Boundary Edges 0"), std::string::npos) << log;
      EXPECT_NEAR(test::number_after(log, "Mesh Volume  is "), mr.volume, 1e-5 * mr.volume);
    }
    std::printf(
        "seed %llu: splint %zu triangles, %.1f mm^3; %zu scan vertices inside the base, all "
        "splint vertices; %zu splint vertices inside it, all scan vertices%s\n",
        static_cast<unsigned long long>(seed), splint.triangles.size(), mr.volume, scan_inside,
        splint_inside, test::have_meshlab() ? "; MeshLab agrees" : "");
  }
}

}  // namespace
}  // namespace splintcore
