// Scan-to-CT registration on the real CBCT dentition (../shared/realdata: 16 closed lower teeth,
// 440k triangles; skipped cleanly when absent): the crowns (the part within 7 mm of the
// occlusal top, cut open, 0.02 mm of noise) as the "scan", the teeth themselves as the "CT",
// the scan moved by seeded rigid motions: recovered within 0.05 mm and 0.1 degree.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "common/realcase.h"
#include "splintcore/registration.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

constexpr double kPi = 3.14159265358979323846;

double uniform(uint64_t* state) {
  *state += 0x9e3779b97f4a7c15ull;
  return static_cast<double>(hash_mix(*state) >> 11) * (1.0 / 9007199254740992.0);
}

Vec3 random_unit(uint64_t* state) {
  for (;;) {
    const Vec3 v{2 * uniform(state) - 1, 2 * uniform(state) - 1, 2 * uniform(state) - 1};
    const double l = length(v);
    if (l > 0.1 && l <= 1) return v * (1.0 / l);
  }
}

// The mandible's teeth as one mesh (the CT) and their crowns (the scan, in the CT's frame).
struct RealMandible {
  test::TestArena store{size_t{256} << 20};
  Mesh ct, scan;
  Vec3 centre;
  bool ok = false;
  RealMandible() {
    realcase::RealCase rc;
    std::string error;
    if (!realcase::load(SPLINTCORE_REALDATA_DIR, 0.0, 1.5, 6.0, &rc, &error)) return;
    ct.bind(&store.arena);
    scan.bind(&store.arena);
    for (const realcase::Tooth& t : rc.teeth) {
      if (t.number <= 16) continue;
      const uint32_t base = static_cast<uint32_t>(ct.vertices.size());
      for (const Vec3& v : t.vertices) EXPECT_TRUE(ct.vertices.push_back(v));
      for (const Triangle& tr : t.triangles) {
        EXPECT_TRUE(
            ct.triangles.push_back(Triangle{{tr.v[0] + base, tr.v[1] + base, tr.v[2] + base}}));
      }
    }
    Aabb box;
    for (const Vec3& v : ct.vertices) box.add(v);
    centre = box.center();
    const double cut = box.hi.z - 7.0;  // the crowns point up (+z) on the mandible
    std::vector<uint32_t> map(ct.vertices.size(), ~0u);
    uint64_t state = 99;
    for (const Triangle& t : ct.triangles) {
      if (ct.vertices[t.v[0]].z <= cut || ct.vertices[t.v[1]].z <= cut ||
          ct.vertices[t.v[2]].z <= cut) {
        continue;
      }
      Triangle out;
      for (int k = 0; k < 3; ++k) {
        if (map[t.v[k]] == ~0u) {
          map[t.v[k]] = static_cast<uint32_t>(scan.vertices.size());
          const Vec3 noise{2 * uniform(&state) - 1, 2 * uniform(&state) - 1,
                           2 * uniform(&state) - 1};
          EXPECT_TRUE(scan.vertices.push_back(ct.vertices[t.v[k]] + noise * 0.02));
        }
        out.v[k] = map[t.v[k]];
      }
      EXPECT_TRUE(scan.triangles.push_back(out));
    }
    ok = scan.triangles.size() > 1000;
  }
};

TEST(RegisterRealData, CrownsOntoTheTeethMoved) {
  RealMandible m;
  if (!m.ok) GTEST_SKIP() << "no real dentition at " << SPLINTCORE_REALDATA_DIR;
  uint64_t state = 2027;
  for (int trial = 0; trial < 5; ++trial) {
    const Vec3 axis = random_unit(&state);
    const double angle = 10.0 * kPi / 180.0 * uniform(&state);
    RigidTransform truth = rotation_about_axis(m.centre, axis, angle);
    truth.t = truth.t + random_unit(&state) * (3.0 * uniform(&state));
    const RigidTransform back = inverse(truth);
    Mesh moved(&m.store.arena);
    for (const Vec3& v : m.scan.vertices)
      ASSERT_TRUE(moved.vertices.push_back(back.apply_point(v)));
    for (const Triangle& t : m.scan.triangles) ASSERT_TRUE(moved.triangles.push_back(t));
    const RegisterOptions o;
    const uint64_t bound =
        register_rigid_bound(moved.vertices.size(), m.ct.vertices.size(), m.ct.triangles.size(), o);
    test::TestArena work{static_cast<size_t>(bound)};
    RegisterResult r;
    const Status s = register_rigid(Context(&work.arena), moved, m.ct, o, &r);
    ASSERT_TRUE(s.is_ok()) << "trial " << trial << ": " << test::format(s);
    double sum = 0;
    for (const Vec3& v : moved.vertices) {
      sum += length_squared(r.transform.apply_point(v) - truth.apply_point(v));
    }
    const double rms = std::sqrt(sum / static_cast<double>(moved.vertices.size()));
    double trace = 0;
    for (int i = 0; i < 3; ++i) {
      for (int k = 0; k < 3; ++k) trace += r.transform.r[i][k] * truth.r[i][k];
    }
    const double deg = std::acos(std::fmin(1.0, 0.5 * (trace - 1))) * 180.0 / kPi;
    std::printf("trial %d: %.1f degrees, error %.6f mm, %.6f degrees, RMS %.4f mm, %u iterations\n",
                trial, angle * 180.0 / kPi, rms, deg, r.rms_mm, r.iterations);
    EXPECT_LT(rms, 0.05) << "trial " << trial;
    EXPECT_LT(deg, 0.1) << "trial " << trial;
  }
}

}  // namespace
}  // namespace splintcore
