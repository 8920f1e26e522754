// Scan-CT fusion in design (issue 30): the paper-scale case on the phantom jaws, the mandible
// given a "scan" (its crowns and the jaw down to 3 mm below them, cut out of the phantom and
// moved by a known rigid motion). Design recovers the motion (within 0.05 mm and 0.1 degree),
// the scan's triangles are the imprint, the splint is a closed, valid solid; a wrong landmark
// pairing and a fit over the thresholds are errors naming the numbers, with nothing made; the
// "scan" keys are parsed, checked and written back; report.json has "fusion". Two-jaw surgery
// with scans (the fusion once, before the plan's moves); scans given upside down (registered
// correctly or refused); the Teeth3DS upper scan as a maxilla (a real case).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "common/cli.h"
#include "common/phantom.h"
#include "splintcore/design.h"
#include "splintcore/distance.h"
#include "support/meshlab.h"
#include "support/phantom_jaws.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

constexpr double kPi = 3.14159265358979323846;

// The paper-scale case, both phantom jaws (6000 triangles) and the mandible's scan: the
// triangles whose corners all lie above z = cut_z in the jaw's own frame (-3: the crowns and a
// band below them, the border below the base's reach), with `noise` mm per axis (a seeded
// counter), moved by the inverse of `truth` (so truth takes it back onto the jaw).
struct Fused {
  test::TestArena t{size_t{128} << 20};
  std::vector<uint8_t> text;
  CaseFile c;
  CaseJaw case_jaws[2];
  Mesh jaws[2];
  Mesh scans[2];  // scans[0] stays empty (the maxilla has none)
  RigidTransform truth;
  bool ok = false;

  explicit Fused(double noise = 0, double cut_z = -3) {
    Context ctx(&t.arena);
    text = test::read_file_bytes(std::string(SPLINTCORE_FIXTURES_DIR) + "/cases/paper_scale.json");
    if (!parse_case(ctx, reinterpret_cast<const char*>(text.data()), text.size(), "paper_scale", &c)
             .is_ok()) {
      return;
    }
    if (!test::phantom_jaw_meshes(t.arena, 6000, jaws)) return;
    for (int j = 0; j < 2; ++j) scans[j].bind(&t.arena);
    Aabb box;
    for (const Vec3& v : jaws[1].vertices) box.add(v);
    const Vec3 axis{0.3, -0.2, 1.0};
    truth = rotation_about_axis(box.center(), axis * (1.0 / length(axis)), 6.0 * kPi / 180.0);
    truth.t = truth.t + Vec3{1.5, -2.0, 0.8};
    const RigidTransform back = inverse(truth);
    std::vector<uint32_t> map(jaws[1].vertices.size(), ~0u);
    uint64_t state = 777;
    const auto jitter = [&]() {
      state = hash_mix(state + 0x9e3779b97f4a7c15ull);
      return noise * (2 * static_cast<double>(state >> 11) * (1.0 / 9007199254740992.0) - 1);
    };
    for (const Triangle& tr : jaws[1].triangles) {
      bool keep = true;
      for (uint32_t v : tr.v) keep = keep && jaws[1].vertices[v].z > cut_z;
      if (!keep) continue;
      Triangle out;
      for (int k = 0; k < 3; ++k) {
        if (map[tr.v[k]] == ~0u) {
          map[tr.v[k]] = static_cast<uint32_t>(scans[1].vertices.size());
          Vec3 p = jaws[1].vertices[tr.v[k]];
          p = p + Vec3{jitter(), jitter(), jitter()};
          (void)scans[1].vertices.push_back(back.apply_point(p));
        }
        out.v[k] = map[tr.v[k]];
      }
      (void)scans[1].triangles.push_back(out);
    }
    case_jaws[0] = c.jaws[0];
    case_jaws[1] = c.jaws[1];
    case_jaws[1].has_scan = true;
    case_jaws[1].scan.path = "mandible_scan.stl";
    c.jaws = Span<const CaseJaw>(case_jaws, 2);
    ok = !scans[1].triangles.empty() && scans[1].triangles.size() < jaws[1].triangles.size();
  }

  Status design(Mesh* splint, DesignReport* r) {
    return design_splint(Context(&t.arena), c, Span<const Mesh>(jaws, 2),
                         Span<const Mesh>(scans, 2), splint, r);
  }
};

// RMS over the mesh's vertices of the distance between their places under a and b, and the
// angle of the rotation between them (degrees).
void motion_error(const Mesh& m, const RigidTransform& a, const RigidTransform& b, double* rms_mm,
                  double* degrees) {
  double sum = 0;
  for (const Vec3& v : m.vertices) sum += length_squared(a.apply_point(v) - b.apply_point(v));
  *rms_mm = std::sqrt(sum / static_cast<double>(m.vertices.size()));
  double trace = 0;
  for (int i = 0; i < 3; ++i) {
    for (int k = 0; k < 3; ++k) trace += a.r[i][k] * b.r[i][k];
  }
  *degrees = std::acos(std::fmin(1.0, std::fmax(-1.0, 0.5 * (trace - 1)))) * 180.0 / kPi;
}

TEST(DesignFusion, ScanIsRegisteredAndIsTheImprint) {
  Fused f;
  ASSERT_TRUE(f.ok);
  Mesh splint;
  DesignReport r;
  const std::string scan_before =
      test::sha256_hex(f.scans[1].vertices.data(), f.scans[1].vertices.size() * sizeof(Vec3));
  SPLINTCORE_ASSERT_OK(f.design(&splint, &r));
  // The scan given is read, not moved.
  EXPECT_EQ(test::sha256_hex(f.scans[1].vertices.data(), f.scans[1].vertices.size() * sizeof(Vec3)),
            scan_before);
  EXPECT_FALSE(r.fused[0]);
  ASSERT_TRUE(r.fused[1]);
  const FusionReport& fu = r.fusion[1];
  double rms = 0, deg = 0;
  motion_error(f.scans[1], fu.registration.transform, f.truth, &rms, &deg);
  EXPECT_LT(rms, 0.05);
  EXPECT_LT(deg, 0.1);
  EXPECT_LT(fu.registration.rms_mm, 0.01);
  EXPECT_GT(fu.registration.overlap, 0.99);
  EXPECT_EQ(fu.scan_triangles, f.scans[1].triangles.size());
  // The jaw's transform applies after the registration.
  const RigidTransform expect = compose(f.c.jaws[1].transform, fu.registration.transform);
  motion_error(f.scans[1], fu.applied, expect, &rms, &deg);
  EXPECT_EQ(rms, 0.0);
  // A closed, valid, printable solid, checked for self-intersections by its Boolean.
  EXPECT_TRUE(r.print.printable);
  EXPECT_TRUE(r.self_intersection_checked);
  MeshReport mr;
  SPLINTCORE_ASSERT_OK(check_mesh(Context(&f.t.arena), splint, &mr));
  EXPECT_TRUE(mr.closed() && mr.edge_manifold() && mr.outward()) << mr.boundary_edges;
  EXPECT_GT(mr.volume, 0);
  // The imprint is the scan's: many of its vertices, moved as applied and rounded to float32,
  // are splint vertices bit for bit.
  std::set<std::array<float, 3>> at;
  for (const Vec3& v : splint.vertices) {
    at.insert({static_cast<float>(v.x), static_cast<float>(v.y), static_cast<float>(v.z)});
  }
  size_t kept = 0;
  for (const Vec3& v : f.scans[1].vertices) {
    const Vec3 p = fu.applied.apply_point(v);
    kept += at.count({static_cast<float>(p.x), static_cast<float>(p.y), static_cast<float>(p.z)});
  }
  EXPECT_GT(kept, 100u);
  // report.json: the registration under "fusion".
  std::string json;
  SPLINTCORE_ASSERT_OK(write_design_report(Context(&f.t.arena), f.c, Span<const Mesh>(f.jaws, 2),
                                           splint, r, DesignReportFiles{}, nullptr,
                                           cli::string_sink(&json)));
  for (const char* key :
       {"\"fusion\":[{\"role\":\"mandible\",\"scan\":\"mandible_scan.stl\"", "\"rms_mm\":",
        "\"overlap\":", "\"iterations\":", "\"applied_transform\":[", "\"max_rms_mm\":0.3"}) {
    EXPECT_NE(json.find(key), std::string::npos) << key << "\n" << json.substr(0, 2000);
  }
}

TEST(DesignFusion, WrongLandmarkPairingIsAnErrorAndNothingIsMade) {
  Fused f;
  ASSERT_TRUE(f.ok);
  // Three scan vertices paired with the jaw points of the wrong ones (a rotation of the list).
  const Vec3 s0 = f.scans[1].vertices[0], s1 = f.scans[1].vertices[f.scans[1].vertices.size() / 3],
             s2 = f.scans[1].vertices[2 * f.scans[1].vertices.size() / 3];
  const LandmarkPair pairs[3] = {
      {s0, f.truth.apply_point(s1)}, {s1, f.truth.apply_point(s2)}, {s2, f.truth.apply_point(s0)}};
  f.case_jaws[1].scan.landmarks = Span<const LandmarkPair>(pairs, 3);
  const size_t used = f.t.arena.used();
  Mesh splint;
  DesignReport r;
  const Status s = f.design(&splint, &r);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument) << s.message();
  const std::string m = s.message();
  EXPECT_NE(m.find("design: fusion: jaw 1 (mandible), scan mandible_scan.stl: "), std::string::npos)
      << m;
  EXPECT_NE(m.find("landmark"), std::string::npos) << m;
  EXPECT_TRUE(splint.triangles.empty());
  EXPECT_EQ(f.t.arena.used(), used);
  // The right pairing starts the same registration well.
  const LandmarkPair right[3] = {
      {s0, f.truth.apply_point(s0)}, {s1, f.truth.apply_point(s1)}, {s2, f.truth.apply_point(s2)}};
  f.case_jaws[1].scan.landmarks = Span<const LandmarkPair>(right, 3);
  SPLINTCORE_ASSERT_OK(f.design(&splint, &r));
  double rms = 0, deg = 0;
  motion_error(f.scans[1], r.fusion[1].registration.transform, f.truth, &rms, &deg);
  EXPECT_LT(rms, 0.05);
  EXPECT_LT(deg, 0.1);
  EXPECT_LT(r.fusion[1].registration.landmark_rms_mm, 0.05);
}

TEST(DesignFusion, FitOverTheThresholdsNamesTheNumbers) {
  Fused f(0.05);  // 0.05 mm of noise per axis: an RMS of about 0.03 mm
  ASSERT_TRUE(f.ok);
  Mesh splint;
  DesignReport r;
  // Within the default thresholds the noisy scan is recovered as well.
  SPLINTCORE_ASSERT_OK(f.design(&splint, &r));
  double rms = 0, deg = 0;
  motion_error(f.scans[1], r.fusion[1].registration.transform, f.truth, &rms, &deg);
  EXPECT_LT(rms, 0.05);
  EXPECT_LT(deg, 0.1);
  EXPECT_GT(r.fusion[1].registration.rms_mm, 0.01);  // the noise, measured
  EXPECT_TRUE(r.print.printable);
  splint = Mesh();
  f.case_jaws[1].scan.max_rms_mm = 0.01;
  Status s = f.design(&splint, &r);
  EXPECT_EQ(s.code(), StatusCode::kLimitExceeded) << s.message();
  std::string m = s.message();
  for (const char* part :
       {"design: fusion: jaw 1 (mandible)", "the scan does not fit the jaw: RMS ",
        "(max_rms_mm 0.01)", ", overlap ", "(min_overlap 0.3,"}) {
    EXPECT_NE(m.find(part), std::string::npos) << part << " in " << m;
  }
  EXPECT_TRUE(splint.triangles.empty());
  // The overlap: with crowns only 0.01 mm from the jaw almost no sample counts.
  f.case_jaws[1].scan.max_rms_mm = 1;
  f.case_jaws[1].scan.crowns_within_mm = 0.01;
  s = f.design(&splint, &r);
  EXPECT_EQ(s.code(), StatusCode::kLimitExceeded) << s.message();
  m = s.message();
  EXPECT_NE(m.find("crowns_within_mm 0.01 mm"), std::string::npos) << m;
  const size_t at = m.find(", overlap ");
  ASSERT_NE(at, std::string::npos) << m;
  EXPECT_LT(std::strtod(m.c_str() + at + 10, nullptr), 0.3) << m;
  EXPECT_TRUE(splint.triangles.empty());
}

TEST(DesignFusion, BlockoutSweepsTheScan) {
  Fused f;
  ASSERT_TRUE(f.ok);
  f.c.has_blockout = true;
  f.c.blockout_method = BlockoutMethod::kVoxel;
  f.c.blockout.voxel = 0.2;
  f.c.blockout.inset = 0.1;
  Mesh splint;
  DesignReport r;
  SPLINTCORE_ASSERT_OK(f.design(&splint, &r));
  EXPECT_TRUE(r.fused[1]);
  EXPECT_EQ(r.blockout_jaws, 2u);
  EXPECT_TRUE(r.print.printable);
  MeshReport mr;
  SPLINTCORE_ASSERT_OK(check_mesh(Context(&f.t.arena), splint, &mr));
  EXPECT_TRUE(mr.closed() && mr.edge_manifold() && mr.outward()) << mr.boundary_edges;
}

TEST(DesignFusion, AutomaticOutlineOnTheJawsThenTheScan) {
  Fused f;
  ASSERT_TRUE(f.ok);
  f.c.has_auto_outline = true;  // the outline's defaults; it runs on the jaws' own meshes
  Mesh splint;
  DesignReport r;
  SPLINTCORE_ASSERT_OK(f.design(&splint, &r));
  EXPECT_TRUE(r.outlined);
  EXPECT_TRUE(r.fused[1]);
  EXPECT_TRUE(r.print.printable);
  MeshReport mr;
  SPLINTCORE_ASSERT_OK(check_mesh(Context(&f.t.arena), splint, &mr));
  EXPECT_TRUE(mr.closed() && mr.edge_manifold() && mr.outward()) << mr.boundary_edges;
}

TEST(DesignFusion, ArenaExhaustionIsCleanAtEveryCapTried) {
  Fused f;
  ASSERT_TRUE(f.ok);
  size_t need = 0;
  std::string want;
  {
    std::vector<unsigned char> big(size_t{64} << 20);
    Arena probe(big.data(), big.size());
    Mesh splint;
    DesignReport r;
    SPLINTCORE_ASSERT_OK(design_splint(Context(&probe), f.c, Span<const Mesh>(f.jaws, 2),
                                       Span<const Mesh>(f.scans, 2), &splint, &r));
    need = probe.high_water();
    want = test::mesh_sha256(splint);
  }
  // Below the ample peak (one byte under it too): a clean failure that leaves the arena as it
  // was, or (the self-intersection check in slabs) the same splint; once a cap works, every
  // larger one does.
  std::vector<size_t> caps = test::caps_below(need, need / 12 + 1);
  caps.push_back(need - 1);
  const test::CapsTried c = test::expect_clean_or_same(caps, want, [&](Arena& a, Mesh* splint) {
    DesignReport r;
    return design_splint(Context(&a), f.c, Span<const Mesh>(f.jaws, 2),
                         Span<const Mesh>(f.scans, 2), splint, &r);
  });
  EXPECT_GE(c.failed, 9) << "the design worked at " << c.first_success << " of " << need;
  std::vector<unsigned char> buf(need);
  Arena exact(buf.data(), need);
  Mesh splint;
  DesignReport r;
  SPLINTCORE_EXPECT_OK(design_splint(Context(&exact), f.c, Span<const Mesh>(f.jaws, 2),
                                     Span<const Mesh>(f.scans, 2), &splint, &r));
  EXPECT_EQ(test::mesh_sha256(splint), want);
}

TEST(DesignFusion, ScanWhoseBorderCrossesTheBaseIsNamed) {
  Fused f(0, 0.5);  // the crowns' tops only: the border runs through the base
  ASSERT_TRUE(f.ok);
  Mesh splint;
  DesignReport r;
  const Status s = f.design(&splint, &r);
  EXPECT_EQ(s.code(), StatusCode::kInvalidMesh) << s.message();
  const std::string m = s.message();
  const std::string head =
      "boolean (base minus jaws): B is open: the scan of jaw 1 (mandible) has its border inside "
      "the base at its vertex ";
  ASSERT_EQ(m.rfind(head, 0), 0u) << m;
  EXPECT_NE(m.find("): use a larger scan, a smaller outline, or close it first (splintcore "
                   "prepare)"),
            std::string::npos)
      << m;
  EXPECT_EQ(s.index(), 1u);  // the jaw
  // Where: a vertex of the scan's border (an edge of it used by one triangle), at the place
  // the message gives in the case's frame (the scan as applied, to the micrometre).
  const uint32_t v = static_cast<uint32_t>(std::strtoul(m.c_str() + head.size(), nullptr, 10));
  ASSERT_LT(v, f.scans[1].vertices.size());
  std::map<std::pair<uint32_t, uint32_t>, int> uses;
  for (const Triangle& t : f.scans[1].triangles) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = t.v[k], b = t.v[(k + 1) % 3];
      ++uses[{std::min(a, b), std::max(a, b)}];
    }
  }
  bool on_border = false;
  for (const auto& e : uses)
    on_border = on_border || (e.second == 1 && (e.first.first == v || e.first.second == v));
  EXPECT_TRUE(on_border) << v;
  Vec3 p = r.fusion[1].applied.apply_point(f.scans[1].vertices[v]);
  ASSERT_TRUE(round_to_float32(&p));
  const size_t open = m.find('(', head.size());
  ASSERT_NE(open, std::string::npos);
  char* end = nullptr;
  const double x = std::strtod(m.c_str() + open + 1, &end);
  const double y = std::strtod(end + 1, &end);
  const double z = std::strtod(end + 1, &end);
  EXPECT_NEAR(x, p.x, 6e-4);
  EXPECT_NEAR(y, p.y, 6e-4);
  EXPECT_NEAR(z, p.z, 6e-4);
  EXPECT_TRUE(r.fused[1]);  // the registration itself went well
  EXPECT_TRUE(splint.triangles.empty());
}

TEST(DesignFusion, ScansMustMatchTheCase) {
  Fused f;
  ASSERT_TRUE(f.ok);
  Mesh splint;
  DesignReport r;
  // The overload without scans on a case with one.
  Status s = design_splint(Context(&f.t.arena), f.c, Span<const Mesh>(f.jaws, 2), &splint, &r);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(std::string(s.message())
                .find("0 scan meshes were given for the case's 2 jaws (one per jaw, empty for a "
                      "jaw without a scan); jaw 1 (mandible) has a \"scan\""),
            std::string::npos)
      << s.message();
  // A scan for a jaw the case gives none.
  Mesh swapped[2] = {f.scans[1], f.scans[1]};
  s = design_splint(Context(&f.t.arena), f.c, Span<const Mesh>(f.jaws, 2),
                    Span<const Mesh>(swapped, 2), &splint, &r);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(std::string(s.message())
                .find("a scan mesh was given for jaw 0 (maxilla), which has "
                      "no \"scan\" in the case"),
            std::string::npos)
      << s.message();
  // An empty scan where the case has one.
  Mesh none[2];
  s = design_splint(Context(&f.t.arena), f.c, Span<const Mesh>(f.jaws, 2),
                    Span<const Mesh>(none, 2), &splint, &r);
  EXPECT_EQ(s.code(), StatusCode::kInvalidMesh);
  EXPECT_NE(std::string(s.message()).find("the scan of jaw 1 (mandible) is empty"),
            std::string::npos)
      << s.message();
}

Status parse(test::TestArena& t, const std::string& text, CaseFile* c) {
  return parse_case(Context(&t.arena), text.data(), text.size(), "scan.json", c);
}

std::string scan_case(const std::string& scan) {
  return R"({"splintcore_case": 1,
 "jaws": [{"role": "mandible", "mesh": "ct.stl", "scan": )" +
         scan + R"(}],
 "base": {"upper": [{"position": [0, 0, 1]}, {"position": [10, 0, 1]}],
          "lower": [{"position": [0, 0, -1]}, {"position": [10, 0, -1]}]}})";
}

TEST(DesignFusion, ScanKeysAreParsedCheckedAndWrittenBack) {
  test::TestArena t(size_t{4} << 20);
  CaseFile c;
  SPLINTCORE_ASSERT_OK(parse(t, scan_case(R"({"path": "s.ply", "landmarks": [[[1, 2, 3], [4, 5, 6]],
  [[7, 8, 9], [1, 1, 1]], [[0, 0, 1], [2, 2, 2]]], "trim": 0.5, "min_overlap": 0.25,
  "max_rms_mm": 0.2, "crowns_within_mm": 0.4})"),
                             &c));
  ASSERT_EQ(c.jaws.size(), 1u);
  const CaseJaw& j = c.jaws[0];
  ASSERT_TRUE(j.has_scan);
  EXPECT_STREQ(j.scan.path, "s.ply");
  ASSERT_EQ(j.scan.landmarks.size(), 3u);
  EXPECT_EQ(j.scan.landmarks[1].scan.y, 8);
  EXPECT_EQ(j.scan.landmarks[2].ct.z, 2);
  EXPECT_EQ(j.scan.trim, 0.5);
  EXPECT_EQ(j.scan.min_overlap, 0.25);
  EXPECT_EQ(j.scan.max_rms_mm, 0.2);
  EXPECT_EQ(j.scan.crowns_within_mm, 0.4);
  // Written back, read again: the same values.
  std::string written;
  SPLINTCORE_ASSERT_OK(write_case(c, cli::string_sink(&written)));
  CaseFile again;
  SPLINTCORE_ASSERT_OK(parse(t, written, &again));
  ASSERT_TRUE(again.jaws[0].has_scan);
  EXPECT_STREQ(again.jaws[0].scan.path, "s.ply");
  ASSERT_EQ(again.jaws[0].scan.landmarks.size(), 3u);
  EXPECT_EQ(again.jaws[0].scan.landmarks[0].ct.x, 4);
  EXPECT_EQ(again.jaws[0].scan.max_rms_mm, 0.2);
  // Defaults.
  SPLINTCORE_ASSERT_OK(parse(t, scan_case(R"({"path": "s.stl"})"), &c));
  EXPECT_TRUE(c.jaws[0].scan.landmarks.empty());
  EXPECT_EQ(c.jaws[0].scan.trim, 0.6);
  EXPECT_EQ(c.jaws[0].scan.min_overlap, 0.3);
  EXPECT_EQ(c.jaws[0].scan.max_rms_mm, 0.3);
  EXPECT_EQ(c.jaws[0].scan.crowns_within_mm, 0.5);
  // Errors, each with its place and what is wrong.
  const struct {
    const char* scan;
    const char* says;
  } bad[] = {
      {R"({})", "\"scan\" needs \"path\""},
      {R"("s.stl")", "\"scan\" must be object, not string"},
      {R"({"path": "s.stl", "rms": 1})", "unknown key \"rms\" in \"scan\""},
      {R"({"path": "s.stl", "max_rms_mm": 0})", "\"max_rms_mm\" is 0, outside [0.001, 10]"},
      {R"({"path": "s.stl", "trim": 1.5})", "\"trim\" is 1.5, outside [0.05, 1]"},
      {R"({"path": "s.stl", "min_overlap": -0.1})", "\"min_overlap\" is -0.1, outside [0, 1]"},
      {R"({"path": "s.stl", "crowns_within_mm": 20})", "\"crowns_within_mm\" is 20"},
      {R"({"path": "s.stl", "landmarks": [[[1, 2, 3], [4, 5, 6]]]})", "needs 3 to 64 pairs"},
      {R"({"path": "s.stl", "landmarks": [[1, 2, 3], [4, 5, 6], [7, 8, 9]]})",
       "a landmark pair is [[scan x, y, z], [jaw x, y, z]]"},
      {R"({"path": "s.stl", "landmarks": 5})", "\"landmarks\" must be array, not number"},
      {R"({"path": "s.stl", "landmarks": [[[1, 2, 3], [4, 5]], [[1, 2, 3], [4, 5, 6]],
          [[1, 2, 3], [4, 5, 6]]]})",
       "\"landmarks\" needs 3 numbers, has 2"},
      {R"({"path": "s.stl", "landmarks": [[[1, 2], [4, 5, 6]], [[1, 2, 3], [4, 5, 6]],
          [[1, 2, 3], [4, 5, 6]]]})",
       "\"landmarks\" needs 3 numbers, has 2"},
      {R"({"path": "s.stl", "landmarks": [[[1, 2, 3], [4, 5, 6]], [[1, 2, 3], [4, 5, 6]],
          [[1, 2, 3], [4, 5, 6]], 7]})",
       "\"landmarks\" must be array, not number"},
      {R"({"path": "", "trim": 0.5})", "\"path\" must be a non-empty string"},
      {R"({"path": "s.stl", "landmarks": [[[1, 2, 3]], [[1, 2, 3]], [[1, 2, 3]]]})",
       "a landmark pair is [[scan x, y, z], [jaw x, y, z]]"},
  };
  for (const auto& b : bad) {
    const Status s = parse(t, scan_case(b.scan), &c);
    EXPECT_FALSE(s.is_ok()) << b.scan;
    EXPECT_NE(std::string(s.message()).find(b.says), std::string::npos)
        << b.scan << ": " << s.message();
    EXPECT_NE(test::format(s).find("scan.json:"), std::string::npos) << test::format(s);
  }
}

// Two-jaw surgery with scans (issue 30 with issue 32): the phantom plan (plan_test.cpp's)
// with both jaws scanned (each jaw's crowns and a band below them, cut out of the phantom jaw,
// 0.01 mm of noise, moved by its own known motion). The fusion comes once, before the plan's
// moves: both splints hold the same registrations (within 0.05 mm and 0.1 degree of the
// truth), each applied after that splint's own moves; the autorotation sees the registered
// scans; each imprint is scan vertices bit for bit; report.json gives "fusion" in both
// splints' sections.
struct PlanScans {
  test::TestArena t{size_t{192} << 20};
  std::string text;
  CaseFile c;
  Mesh jaws[2], scans[2];
  RigidTransform truth[2];
  bool ok = false;
  // upside_down: each scan turned 180 degrees about the arch's width axis (x) before its
  // motion, its occlusal side pointing away from the other jaw.
  explicit PlanScans(bool upside_down = false) {
    text = R"({"splintcore_case": 1, "case_id": "plan-scans",
      "jaws": [{"role": "maxilla", "mesh": "maxilla.stl", "scan": {"path": "maxilla_scan.stl"}},
               {"role": "mandible", "mesh": "mandible.stl", "scan": {"path": "mandible_scan.stl"}}],
      "base": {"spacing_mm": 0.5, "auto": {}},
      "plan": {"sequence": "maxilla_first",
        "maxilla": [1,0,0,0, 0,1,0,2, 0,0,1,1, 0,0,0,1],
        "mandible": [1,0,0,0, 0,1,0,2.5, 0,0,1,0, 0,0,0,1],
        "hinge_axis": [[-50, -55, 25], [50, -55, 25]],
        "intermediate_opening_mm": 2, "final_opening_mm": 1.5}})";
    if (!parse(t, text, &c).is_ok()) return;
    uint64_t state = 4711;
    if (!test::phantom_jaw_meshes(t.arena, 6000, jaws)) return;
    for (int j = 0; j < 2; ++j) {
      scans[j].bind(&t.arena);
      Aabb box;
      for (const Vec3& v : jaws[j].vertices) box.add(v);
      const Vec3 axis = j == 0 ? Vec3{-0.2, 0.4, 1.0} : Vec3{0.3, -0.2, 1.0};
      truth[j] = rotation_about_axis(box.center(), axis * (1.0 / length(axis)),
                                     (j == 0 ? -5.0 : 6.0) * kPi / 180.0);
      truth[j].t = truth[j].t + (j == 0 ? Vec3{-1.0, 1.5, -0.5} : Vec3{1.5, -2.0, 0.8});
      if (upside_down)
        truth[j] = compose(truth[j], rotation_about_axis(box.center(), {1, 0, 0}, kPi));
      const RigidTransform back = inverse(truth[j]);
      std::vector<uint32_t> map(jaws[j].vertices.size(), ~0u);
      for (const Triangle& tr : jaws[j].triangles) {
        // The crowns and a band below them (the maxilla's point down, its gum ridge above
        // z = 4.1, the mandible's below -2.1: phantom.h).
        bool keep = true;
        for (uint32_t v : tr.v)
          keep = keep && (j == 0 ? jaws[j].vertices[v].z < 7 : jaws[j].vertices[v].z > -5);
        if (!keep) continue;
        Triangle out;
        for (int k = 0; k < 3; ++k) {
          if (map[tr.v[k]] == ~0u) {
            map[tr.v[k]] = static_cast<uint32_t>(scans[j].vertices.size());
            Vec3 noise;
            for (int a = 0; a < 3; ++a) {
              state = hash_mix(state + 0x9e3779b97f4a7c15ull);
              noise[a] = 0.01 * (2 * static_cast<double>(state >> 11) / 9007199254740992.0 - 1);
            }
            Vec3 p = back.apply_point(jaws[j].vertices[tr.v[k]] + noise);
            (void)round_to_float32(&p);  // as an STL holds it
            (void)scans[j].vertices.push_back(p);
          }
          out.v[k] = map[tr.v[k]];
        }
        (void)scans[j].triangles.push_back(out);
      }
      if (scans[j].triangles.size() < 500 ||
          scans[j].triangles.size() >= jaws[j].triangles.size()) {
        return;
      }
    }
    ok = true;
  }
};

TEST(DesignFusion, PlanFusesTheScansOnceBeforeItsMoves) {
  PlanScans f;
  ASSERT_TRUE(f.ok);
  Context ctx(&f.t.arena);
  Mesh intermediate, final_splint;
  PlanReport r;
  SPLINTCORE_ASSERT_OK(design_plan(ctx, f.c, Span<const Mesh>(f.jaws, 2),
                                   Span<const Mesh>(f.scans, 2), &intermediate, &final_splint, &r));
  const PlanSplintReport* parts[2] = {&r.intermediate, &r.final_splint};
  const Mesh* splints[2] = {&intermediate, &final_splint};
  for (int k = 0; k < 2; ++k) {
    SCOPED_TRACE(k == 0 ? "intermediate" : "final");
    const PlanSplintReport& p = *parts[k];
    EXPECT_TRUE(p.design.print.printable);
    EXPECT_TRUE(p.design.self_intersection_checked);
    MeshReport mr;
    SPLINTCORE_ASSERT_OK(check_mesh(ctx, *splints[k], &mr));
    EXPECT_TRUE(mr.closed() && mr.edge_manifold() && mr.outward()) << mr.boundary_edges;
    EXPECT_GT(mr.volume, 100.0);
    std::set<std::array<float, 3>> at;
    for (const Vec3& v : splints[k]->vertices) {
      at.insert({static_cast<float>(v.x), static_cast<float>(v.y), static_cast<float>(v.z)});
    }
    const RigidTransform moves[2] = {p.maxilla, p.mandible};
    for (int j = 0; j < 2; ++j) {
      ASSERT_TRUE(p.design.fused[j]);
      const FusionReport& fu = p.design.fusion[j];
      // The same fit in both splints (made once), near the truth.
      const FusionReport& first = r.intermediate.design.fusion[j];
      for (int a = 0; a < 3; ++a) {
        EXPECT_EQ(fu.registration.transform.t[a], first.registration.transform.t[a]);
        for (int b = 0; b < 3; ++b) {
          EXPECT_EQ(fu.registration.transform.r[a][b], first.registration.transform.r[a][b]);
        }
      }
      double rms = 0, deg = 0;
      motion_error(f.scans[j], fu.registration.transform, f.truth[j], &rms, &deg);
      EXPECT_LT(rms, 0.05) << "jaw " << j;
      EXPECT_LT(deg, 0.1) << "jaw " << j;
      // The splint's own moves (the plan's, the mandible's turn) after the registration.
      motion_error(f.scans[j], fu.applied, compose(moves[j], fu.registration.transform), &rms,
                   &deg);
      EXPECT_EQ(rms, 0.0) << "jaw " << j;
      // The imprint is the scan's: its vertices as applied, rounded to float32, bit for bit.
      size_t kept = 0;
      for (const Vec3& v : f.scans[j].vertices) {
        const Vec3 q = fu.applied.apply_point(v);
        kept +=
            at.count({static_cast<float>(q.x), static_cast<float>(q.y), static_cast<float>(q.z)});
      }
      EXPECT_GT(kept, 100u) << "jaw " << j;
    }
    std::printf("%s: %.6f deg, opening %.6f mm, %zu triangles, %.1f mm^3\n",
                k == 0 ? "intermediate" : "final", p.angle_deg, p.autorotation.opening,
                splints[k]->triangles.size(), mr.volume);
  }
  // The autorotation measured the registered scans: the opening asked, between the scans.
  EXPECT_NEAR(r.intermediate.autorotation.opening, 2.0, 1e-6);
  EXPECT_NEAR(r.final_splint.autorotation.opening, 1.5, 1e-6);
  // report.json: "fusion" in both splints' sections.
  std::string json;
  DesignReportFiles files[2];
  SPLINTCORE_ASSERT_OK(write_plan_report(ctx, f.c, Span<const Mesh>(f.jaws, 2), intermediate,
                                         final_splint, r, files, nullptr, cli::string_sink(&json)));
  const size_t inter = json.find("\"intermediate\":{"), fin = json.find("\"final\":{");
  ASSERT_NE(inter, std::string::npos);
  ASSERT_NE(fin, std::string::npos);
  const size_t first = json.find("\"fusion\":[{\"role\":\"maxilla\",\"scan\":\"maxilla_scan.stl\"");
  ASSERT_NE(first, std::string::npos) << json.substr(0, 3000);
  const size_t second = json.find("\"fusion\":[{\"role\":\"maxilla\"", first + 1);
  ASSERT_NE(second, std::string::npos);
  EXPECT_TRUE(inter < first && first < fin && fin < second)
      << inter << " " << first << " " << fin << " " << second;
  EXPECT_NE(json.find("\"role\":\"mandible\",\"scan\":\"mandible_scan.stl\""), std::string::npos);

  // Without the scans the case is refused (it names them), and a fit over the case's
  // thresholds is the fusion's error, prefixed "plan: ", with nothing made.
  Mesh i2, f2;
  PlanReport r2;
  const Status none = design_plan(ctx, f.c, Span<const Mesh>(f.jaws, 2), &i2, &f2, &r2);
  EXPECT_EQ(none.code(), StatusCode::kInvalidArgument) << none.message();
  EXPECT_NE(std::string(none.message()).find("has a \"scan\""), std::string::npos)
      << none.message();
  CaseJaw strict[2] = {f.c.jaws[0], f.c.jaws[1]};
  strict[0].scan.max_rms_mm = 0.001;
  CaseFile c2 = f.c;
  c2.jaws = Span<const CaseJaw>(strict, 2);
  const size_t used = f.t.arena.used();
  const Status over = design_plan(ctx, c2, Span<const Mesh>(f.jaws, 2),
                                  Span<const Mesh>(f.scans, 2), &i2, &f2, &r2);
  EXPECT_EQ(over.code(), StatusCode::kLimitExceeded) << over.message();
  EXPECT_EQ(std::string(over.message()).rfind("plan: design: fusion: jaw 0 (maxilla)", 0), 0u)
      << over.message();
  EXPECT_EQ(f.t.arena.used(), used);
  EXPECT_TRUE(i2.triangles.empty() && f2.triangles.empty());
}

// The plan with scans in exactly the arena its first run took at its peak, and one byte
// less: kArenaExhausted with the arena as it was and nothing made.
TEST(DesignFusion, PlanWithScansRunsInItsMeasuredNeed) {
  PlanScans f;
  ASSERT_TRUE(f.ok);
  const auto run = [&](size_t cap, Mesh* a, Mesh* b, size_t* high_water) {
    test::TestArena work(cap);
    PlanReport r;
    const Status s = design_plan(Context(&work.arena), f.c, Span<const Mesh>(f.jaws, 2),
                                 Span<const Mesh>(f.scans, 2), a, b, &r);
    *high_water = work.arena.high_water();
    if (!s.is_ok()) {
      EXPECT_EQ(work.arena.used(), 0u);
      EXPECT_TRUE(a->triangles.empty() && b->triangles.empty());
      return s;
    }
    EXPECT_TRUE(!a->triangles.empty() && !b->triangles.empty());  // (they go with `work`)
    return s;
  };
  Mesh a, b;
  size_t need = 0, ignored = 0;
  SPLINTCORE_ASSERT_OK(run(size_t{128} << 20, &a, &b, &need));
  Mesh a2, b2;
  SPLINTCORE_EXPECT_OK(run(need, &a2, &b2, &ignored));
  Mesh a3, b3;
  EXPECT_EQ(run(need - 1, &a3, &b3, &ignored).code(), StatusCode::kArenaExhausted);
  std::printf("plan with two scans: %zu bytes at its peak\n", need);
}

// The upside-down guard in design (issue 30), both arches: the plan's scans each given upside
// down are registered correctly (the direction to the other jaw passes over the starts that
// would lay a scan on its jaw's far side) or refused saying the scan faces away; never a splint
// from an upside-down scan.
TEST(DesignFusion, UpsideDownScansAreRegisteredOrRefused) {
  PlanScans f(true);
  ASSERT_TRUE(f.ok);
  Context ctx(&f.t.arena);
  Mesh intermediate, final_splint;
  PlanReport r;
  const Status s = design_plan(ctx, f.c, Span<const Mesh>(f.jaws, 2), Span<const Mesh>(f.scans, 2),
                               &intermediate, &final_splint, &r);
  if (!s.is_ok()) {
    EXPECT_NE(std::string(s.message()).find("the scan faces away"), std::string::npos)
        << s.message();
    return;
  }
  for (int j = 0; j < 2; ++j) {
    const FusionReport& fu = r.final_splint.design.fusion[j];
    double rms = 0, deg = 0;
    motion_error(f.scans[j], fu.registration.transform, f.truth[j], &rms, &deg);
    EXPECT_LT(rms, 0.05) << "jaw " << j;
    EXPECT_LT(deg, 0.1) << "jaw " << j;
    EXPECT_GT(fu.registration.occlusal_cos, 0.5) << "jaw " << j;
    std::printf("jaw %d upside down: registered from start %d, RMS error %.6f mm\n", j,
                fu.registration.start, rms);
  }
  EXPECT_TRUE(r.intermediate.design.print.printable && r.final_splint.design.print.printable);
}

// The Teeth3DS real case (issue 30): the sample's upper-jaw scan (an open surface, 16k
// triangles; CC BY-NC-ND, read where it lies, skipped when absent) as the maxilla, against a
// stand-in mandible made from it: the scan mirrored across the horizontal plane 1.25 mm beyond
// its crown tips (its crowns point +z in the sample's frame), its triangles turned back so it
// faces outward, rounded to float32. The automatic outline, then the design: a closed, valid,
// printable splint; every scan vertex strictly inside the base (no blockout) is a splint
// vertex bit for bit (the imprint is the scan's own surface); MeshLab agrees when present.
TEST(DesignTeeth3dsRealData, UpperScanAsTheMaxilla) {
  const std::string path = std::string(SPLINTCORE_TEETH3DS_DIR) + "/YBSESUN6_upper.ply";
  if (!test::file_exists(path)) GTEST_SKIP() << "Teeth3DS sample not found: " << path;
  test::TestArena t(size_t{256} << 20);
  Context ctx(&t.arena);
  const std::vector<uint8_t> bytes = test::read_file_bytes(path);
  MemorySource src{bytes.data(), bytes.size(), 0, 0};
  Mesh jaws[2];
  MeshReadInfo info;
  SPLINTCORE_ASSERT_OK(
      read_ply(ctx, memory_source(&src, path.c_str()), MeshReadOptions{}, &jaws[0], &info));
  MeshReport scan_report;
  SPLINTCORE_ASSERT_OK(check_mesh(ctx, jaws[0], &scan_report));
  ASSERT_FALSE(scan_report.closed());  // a scan: open
  ASSERT_TRUE(scan_report.edge_manifold() && scan_report.oriented());
  double top = -HUGE_VAL;
  for (const Vec3& v : jaws[0].vertices) top = std::fmax(top, v.z);
  const double mirror = top + 1.25;
  jaws[1].bind(&t.arena);
  for (const Vec3& v : jaws[0].vertices) {
    Vec3 p{v.x, v.y, 2 * mirror - v.z};
    ASSERT_TRUE(round_to_float32(&p));
    ASSERT_TRUE(jaws[1].vertices.push_back(p));
  }
  for (const Triangle& tr : jaws[0].triangles) {
    ASSERT_TRUE(jaws[1].triangles.push_back(Triangle{{tr.v[0], tr.v[2], tr.v[1]}}));
  }
  const std::string text = R"({"splintcore_case": 1, "case_id": "teeth3ds",
    "jaws": [{"role": "maxilla", "mesh": "YBSESUN6_upper.ply"},
             {"role": "mandible", "mesh": "mirrored.stl"}],
    "base": {"auto": {}}})";
  CaseFile c;
  SPLINTCORE_ASSERT_OK(parse_case(ctx, text.data(), text.size(), "teeth3ds.json", &c));
  Mesh splint;
  DesignReport r;
  SPLINTCORE_ASSERT_OK(design_splint(ctx, c, Span<const Mesh>(jaws, 2), &splint, &r));
  EXPECT_TRUE(r.outlined);
  EXPECT_TRUE(r.print.printable);
  EXPECT_TRUE(r.self_intersection_checked);
  MeshReport mr;
  SPLINTCORE_ASSERT_OK(check_mesh(ctx, splint, &mr));
  EXPECT_TRUE(mr.closed() && mr.edge_manifold() && mr.outward()) << mr.boundary_edges;
  EXPECT_EQ(mr.shells, 1u);
  EXPECT_GT(mr.volume, 100.0);
  // The imprint: the base the design cut (its resolved outline, built again), and every scan
  // vertex strictly inside it (winding number, and more than 1e-3 mm from its surface).
  CaseFile resolved;
  SPLINTCORE_ASSERT_OK(resolve_case_outline(ctx, c, Span<const Mesh>(jaws, 2), &resolved, nullptr));
  Mesh base(&t.arena);
  BaseReport br;
  SPLINTCORE_ASSERT_OK(build_case_base(ctx, resolved, &base, &br));
  DistanceIndex index;
  SPLINTCORE_ASSERT_OK(build_distance_index(ctx, base, DistanceIndexOptions{}, &index));
  std::set<std::array<float, 3>> at;
  for (const Vec3& v : splint.vertices) {
    at.insert({static_cast<float>(v.x), static_cast<float>(v.y), static_cast<float>(v.z)});
  }
  size_t inside = 0, kept = 0;
  for (const Vec3& v : jaws[0].vertices) {
    ClosestPoint cp;
    if (!closest_point(index, v, &cp) || cp.distance <= 1e-3) continue;
    if (winding_number(index, v) < 0.5) continue;
    ++inside;
    const size_t n =
        at.count({static_cast<float>(v.x), static_cast<float>(v.y), static_cast<float>(v.z)});
    kept += n;
    EXPECT_EQ(n, 1u) << "scan vertex (" << v.x << ", " << v.y << ", " << v.z << ")";
  }
  EXPECT_GT(inside, 500u);
  if (test::have_meshlab()) {  // the independent oracle: two-manifold, no border, same volume
    std::vector<uint8_t> stl;
    SPLINTCORE_ASSERT_OK(test::mesh_to_bytes(t.arena, splint, StlFormat::kBinary, &stl));
    const std::string log = test::meshlab_log_of_bytes(stl);
    EXPECT_NE(log.find("Mesh is two-manifold"), std::string::npos) << log;
    EXPECT_NE(log.find("Boundary Edges 0"), std::string::npos) << log;
    EXPECT_NEAR(test::number_after(log, "Mesh Volume  is "), mr.volume, 1e-5 * mr.volume);
  }
  std::printf(
      "teeth3ds: splint %zu triangles, %.1f mm^3; %zu scan vertices inside the base, %zu "
      "of them splint vertices bit for bit\n",
      splint.triangles.size(), mr.volume, inside, kept);
}

}  // namespace
}  // namespace splintcore
