// Two-jaw surgery on the real CBCT dentition (issue 32's proof; ../shared/realdata, skipped
// without it): five surgical plans (advancement, impaction, setback, asymmetric yaw, mandible
// first), both splints of each designed by design_plan with the automatic outline, and checked:
// - the autorotation's angle against an oracle that shares no code with the solver: the jaws
//   moved and turned here (std::sin and std::cos, Rodrigues' formula), the smallest distance
//   between them by this file's own triangle-pair distance over a hash grid of its own, and
//   the angle by bisection: the distance crosses the opening asked within 1e-6 rad of the
//   solver's angle (checked by the sign on both sides), and the bisected crossing is printed;
// - each splint a printable closed solid without self-intersections (design_splint's checks),
//   and, where MeshLab is installed, two-manifold without boundary with the same volume;
// - the imprints: thousands of the splint's vertices lie on each jaw in its position (the
//   maxilla as planned, the mandible as planned and turned) within 1e-6 mm, every vertex within
//   0.01 mm of a jaw lies on it within float32 rounding (the output's coordinates: 6.7e-6 mm
//   below 128 mm), and no vertex of the splint lies inside either jaw.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "splintcore/design.h"
#include "splintcore/distance.h"
#include "support/meshlab.h"
#include "support/real_jaws.h"
#include "support/test_util.h"

namespace splintcore {
namespace {

// ---------------------------------------------------------------------------------------------
// The oracle's own geometry (no library code).

struct P3 {
  double x = 0, y = 0, z = 0;
};
P3 operator+(P3 a, P3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
P3 operator-(P3 a, P3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
P3 operator*(P3 a, double s) { return {a.x * s, a.y * s, a.z * s}; }
double dot3(P3 a, P3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
P3 cross3(P3 a, P3 b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
double clamp01(double t) { return t < 0 ? 0 : (t > 1 ? 1 : t); }

// Squared distance from p to triangle abc (Ericson, Real-Time Collision Detection, 5.1.5).
double point_triangle2(P3 p, P3 a, P3 b, P3 c) {
  const P3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = dot3(ab, ap), d2 = dot3(ac, ap);
  P3 q;
  if (d1 <= 0 && d2 <= 0) {
    q = a;
  } else {
    const P3 bp = p - b;
    const double d3 = dot3(ab, bp), d4 = dot3(ac, bp);
    const P3 cp = p - c;
    const double d5 = dot3(ab, cp), d6 = dot3(ac, cp);
    const double vc = d1 * d4 - d3 * d2, vb = d5 * d2 - d1 * d6, va = d3 * d6 - d5 * d4;
    if (d3 >= 0 && d4 <= d3) {
      q = b;
    } else if (vc <= 0 && d1 >= 0 && d3 <= 0) {
      q = a + ab * (d1 / (d1 - d3));
    } else if (d6 >= 0 && d5 <= d6) {
      q = c;
    } else if (vb <= 0 && d2 >= 0 && d6 <= 0) {
      q = a + ac * (d2 / (d2 - d6));
    } else if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
      q = b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    } else {
      const double den = 1 / (va + vb + vc);
      q = a + ab * (vb * den) + ac * (vc * den);
    }
  }
  const P3 d = p - q;
  return dot3(d, d);
}

// Squared distance between segments p1q1 and p2q2 (Ericson 5.1.9).
double segment_segment2(P3 p1, P3 q1, P3 p2, P3 q2) {
  const P3 d1 = q1 - p1, d2 = q2 - p2, r = p1 - p2;
  const double a = dot3(d1, d1), e = dot3(d2, d2), f = dot3(d2, r);
  double s = 0, t = 0;
  if (a <= 1e-300 && e <= 1e-300) {
    s = t = 0;
  } else if (a <= 1e-300) {
    t = clamp01(f / e);
  } else {
    const double c = dot3(d1, r);
    if (e <= 1e-300) {
      s = clamp01(-c / a);
    } else {
      const double b = dot3(d1, d2), den = a * e - b * b;
      s = den != 0 ? clamp01((b * f - c * e) / den) : 0;
      t = (b * s + f) / e;
      if (t < 0) {
        t = 0;
        s = clamp01(-c / a);
      } else if (t > 1) {
        t = 1;
        s = clamp01((b - c) / a);
      }
    }
  }
  const P3 g = (p1 + d1 * s) - (p2 + d2 * t);
  return dot3(g, g);
}

// The distance between two triangles that do not intersect: the least over each vertex to the
// other triangle and every pair of edges.
double triangle_distance(const P3 a[3], const P3 b[3]) {
  double best = HUGE_VAL;
  for (int k = 0; k < 3; ++k) {
    best = std::min(best, point_triangle2(a[k], b[0], b[1], b[2]));
    best = std::min(best, point_triangle2(b[k], a[0], a[1], a[2]));
    for (int l = 0; l < 3; ++l) {
      best = std::min(best, segment_segment2(a[k], a[(k + 1) % 3], b[l], b[(l + 1) % 3]));
    }
  }
  return std::sqrt(best);
}

P3 to_p3(const Vec3& v) { return {v.x, v.y, v.z}; }

// v moved by the plan's rigid move and rounded to float32 (as design_plan moves a jaw before
// turning it), written out here.
P3 move_to_float(const RigidTransform& x, const Vec3& v) {
  P3 p;
  p.x = x.r[0][0] * v.x + x.r[0][1] * v.y + x.r[0][2] * v.z + x.t.x;
  p.y = x.r[1][0] * v.x + x.r[1][1] * v.y + x.r[1][2] * v.z + x.t.y;
  p.z = x.r[2][0] * v.x + x.r[2][1] * v.y + x.r[2][2] * v.z + x.t.z;
  return {static_cast<double>(static_cast<float>(p.x)),
          static_cast<double>(static_cast<float>(p.y)),
          static_cast<double>(static_cast<float>(p.z))};
}

// The smallest distance between the maxilla and the mandible turned by an angle about the
// hinge, near one angle: the triangle pairs that can be the closest within kBracket of it are
// collected once (a hash grid of the maxilla's triangles), then each evaluation is exact over
// them.
class HingeOracle {
 public:
  static constexpr double kBracket = 1e-6;  // rad

  HingeOracle(const Mesh& maxilla, const RigidTransform& maxilla_move, const Mesh& mandible,
              const RigidTransform& mandible_move, const Vec3& h0, const Vec3& h1)
      : maxilla_(maxilla), mandible_(mandible), p_(to_p3(h0)) {
    upper_.reserve(maxilla.vertices.size());
    for (const Vec3& v : maxilla.vertices) upper_.push_back(move_to_float(maxilla_move, v));
    lower_.reserve(mandible.vertices.size());
    for (const Vec3& v : mandible.vertices) lower_.push_back(move_to_float(mandible_move, v));
    const P3 d = to_p3(h1) - to_p3(h0);
    u_ = d * (1 / std::sqrt(dot3(d, d)));
    double reach2 = 0;
    for (const P3& v : lower_) reach2 = std::max(reach2, dot3(v - p_, v - p_));
    reach_ = std::sqrt(reach2);  // a vertex moves at most reach_ * |angle change|
  }

  // Collects the pairs at `angle` that may be the closest pair within the bracket (those
  // within `search` there whose distance is within a margin of the least); returns the least
  // distance there (infinity when no pair lies within `search`).
  double collect(double angle, double search) {
    const std::vector<P3> lower = turned(angle);
    // A dense grid of 1 mm cells over the maxilla's box, each with the triangles whose boxes
    // overlap it.
    const size_t nt = maxilla_.triangles.size();
    std::vector<P3> lo_a(nt), hi_a(nt);
    P3 glo{HUGE_VAL, HUGE_VAL, HUGE_VAL}, ghi{-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
    for (size_t t = 0; t < nt; ++t) {
      box(upper_, maxilla_.triangles[t], &lo_a[t], &hi_a[t]);
      glo = {std::min(glo.x, lo_a[t].x), std::min(glo.y, lo_a[t].y), std::min(glo.z, lo_a[t].z)};
      ghi = {std::max(ghi.x, hi_a[t].x), std::max(ghi.y, hi_a[t].y), std::max(ghi.z, hi_a[t].z)};
    }
    const int64_t dims[3] = {cell_of(ghi.x - glo.x) + 1, cell_of(ghi.y - glo.y) + 1,
                             cell_of(ghi.z - glo.z) + 1};
    std::vector<std::vector<uint32_t>> grid(static_cast<size_t>(dims[0] * dims[1] * dims[2]));
    auto index = [&](int64_t i, int64_t j, int64_t k) {
      return static_cast<size_t>((k * dims[1] + j) * dims[0] + i);
    };
    for (size_t t = 0; t < nt; ++t) {
      const P3 lo = lo_a[t] - glo, hi = hi_a[t] - glo;
      for (int64_t k = cell_of(lo.z); k <= cell_of(hi.z); ++k)
        for (int64_t j = cell_of(lo.y); j <= cell_of(hi.y); ++j)
          for (int64_t i = cell_of(lo.x); i <= cell_of(hi.x); ++i)
            grid[index(i, j, k)].push_back(static_cast<uint32_t>(t));
    }
    std::vector<uint32_t> seen(nt, UINT32_MAX);
    std::vector<std::pair<uint32_t, uint32_t>> near;
    std::vector<double> dist;
    double best = HUGE_VAL;
    auto clamp_cell = [](int64_t c, int64_t n) { return c < 0 ? 0 : (c >= n ? n - 1 : c); };
    for (size_t s = 0; s < mandible_.triangles.size(); ++s) {
      P3 lo, hi;
      box(lower, mandible_.triangles[s], &lo, &hi);
      const P3 qlo = lo - glo - P3{search, search, search};
      const P3 qhi = hi - glo + P3{search, search, search};
      if (qhi.x < 0 || qhi.y < 0 || qhi.z < 0 || qlo.x > ghi.x - glo.x || qlo.y > ghi.y - glo.y ||
          qlo.z > ghi.z - glo.z) {
        continue;
      }
      for (int64_t k = clamp_cell(cell_of(qlo.z), dims[2]);
           k <= clamp_cell(cell_of(qhi.z), dims[2]); ++k)
        for (int64_t j = clamp_cell(cell_of(qlo.y), dims[1]);
             j <= clamp_cell(cell_of(qhi.y), dims[1]); ++j)
          for (int64_t i = clamp_cell(cell_of(qlo.x), dims[0]);
               i <= clamp_cell(cell_of(qhi.x), dims[0]); ++i)
            for (uint32_t t : grid[index(i, j, k)]) {
              if (seen[t] == s) continue;
              seen[t] = static_cast<uint32_t>(s);
              if (box_gap(lo_a[t], hi_a[t], lo, hi) > search) continue;
              const double d = pair_distance(t, lower, static_cast<uint32_t>(s));
              if (d > search) continue;
              near.emplace_back(t, static_cast<uint32_t>(s));
              dist.push_back(d);
              best = std::min(best, d);
            }
    }
    const double margin = 4 * reach_ * kBracket + 1e-6;
    pairs_.clear();
    for (size_t k = 0; k < near.size(); ++k) {
      if (dist[k] <= best + margin) pairs_.push_back(near[k]);
    }
    return best;
  }

  // The smallest distance at `angle` (within the bracket of the collected angle).
  double distance(double angle) {
    ++evaluations;
    const std::vector<P3> lower = turned(angle);
    double best = HUGE_VAL;
    for (const auto& pr : pairs_) best = std::min(best, pair_distance(pr.first, lower, pr.second));
    return best;
  }

  size_t pairs() const { return pairs_.size(); }
  int evaluations = 0;

 private:
  static int64_t cell_of(double x) { return static_cast<int64_t>(std::floor(x)); }  // 1 mm
  // The gap between two boxes (0 when they overlap).
  static double box_gap(const P3& alo, const P3& ahi, const P3& blo, const P3& bhi) {
    const double gx = std::max({0.0, alo.x - bhi.x, blo.x - ahi.x});
    const double gy = std::max({0.0, alo.y - bhi.y, blo.y - ahi.y});
    const double gz = std::max({0.0, alo.z - bhi.z, blo.z - ahi.z});
    return std::sqrt(gx * gx + gy * gy + gz * gz);
  }
  static void box(const std::vector<P3>& v, const Triangle& t, P3* lo, P3* hi) {
    const P3 &a = v[t.v[0]], &b = v[t.v[1]], &c = v[t.v[2]];
    *lo = {std::min({a.x, b.x, c.x}), std::min({a.y, b.y, c.y}), std::min({a.z, b.z, c.z})};
    *hi = {std::max({a.x, b.x, c.x}), std::max({a.y, b.y, c.y}), std::max({a.z, b.z, c.z})};
  }
  double pair_distance(uint32_t t, const std::vector<P3>& lower, uint32_t s) const {
    const Triangle& a = maxilla_.triangles[t];
    const Triangle& b = mandible_.triangles[s];
    const P3 ta[3] = {upper_[a.v[0]], upper_[a.v[1]], upper_[a.v[2]]};
    const P3 tb[3] = {lower[b.v[0]], lower[b.v[1]], lower[b.v[2]]};
    return triangle_distance(ta, tb);
  }
  std::vector<P3> turned(double angle) const {
    const double c = std::cos(angle), s = std::sin(angle);
    std::vector<P3> out(lower_.size());
    for (size_t i = 0; i < lower_.size(); ++i) {
      const P3 w = lower_[i] - p_;
      out[i] = p_ + w * c + cross3(u_, w) * s + u_ * (dot3(u_, w) * (1 - c));
    }
    return out;
  }

  const Mesh& maxilla_;
  const Mesh& mandible_;
  std::vector<P3> upper_, lower_;
  P3 p_, u_;
  double reach_ = 0;
  std::vector<std::pair<uint32_t, uint32_t>> pairs_;
};

// ---------------------------------------------------------------------------------------------
// The plans, in the dentition's frame: z up (the maxilla above, the occlusal plane near z = 60),
// the incisors at y = 0..5 (anterior is -y), the molars near y = 50, the midline near x = 54;
// the condyles behind (+y) and above the teeth.

struct RealPlan {
  const char* name;
  const char* sequence;
  double maxilla[16];
  double mandible[16];
};

// A yaw of `deg` degrees about the vertical through (54, 25) then a move by t, row-major 4x4.
void yaw_matrix(double deg, double tx, double ty, double tz, double out[16]) {
  const double a = deg * 3.14159265358979323846 / 180, c = std::cos(a), s = std::sin(a);
  const double px = 54, py = 25;
  const double m[16] = {
      c, -s, 0, px - (c * px - s * py) + tx, s, c, 0, py - (s * px + c * py) + ty, 0, 0, 1, tz, 0,
      0, 0,  1};
  std::copy(m, m + 16, out);
}

std::vector<RealPlan> real_plans() {
  auto shift = [](double x, double y, double z, double out[16]) {
    const double m[16] = {1, 0, 0, x, 0, 1, 0, y, 0, 0, 1, z, 0, 0, 0, 1};
    std::copy(m, m + 16, out);
  };
  std::vector<RealPlan> plans(5);
  plans[0] = {"advancement", "maxilla_first", {}, {}};
  shift(0, -3, 0, plans[0].maxilla);
  shift(0, -5, 0, plans[0].mandible);
  plans[1] = {"impaction", "maxilla_first", {}, {}};
  shift(0, -1, 3, plans[1].maxilla);
  shift(0, -1, 3, plans[1].mandible);
  plans[2] = {"setback", "maxilla_first", {}, {}};
  shift(0, 1, 0, plans[2].maxilla);
  shift(0, 3, 0, plans[2].mandible);
  plans[3] = {"asymmetric yaw", "maxilla_first", {}, {}};
  yaw_matrix(2.5, 0, -2, 0, plans[3].maxilla);
  yaw_matrix(2.5, 0, -2, 0, plans[3].mandible);
  plans[4] = {"mandible first", "mandible_first", {}, {}};
  shift(0, -2, 1, plans[4].maxilla);
  shift(0, -4, 1, plans[4].mandible);
  return plans;
}

std::string matrix_json(const double m[16]) {
  std::string s = "[";
  char buf[40];
  for (int i = 0; i < 16; ++i) {
    std::snprintf(buf, sizeof(buf), "%s%.17g", i > 0 ? ", " : "", m[i]);
    s += buf;
  }
  return s + "]";
}

std::string plan_case(const RealPlan& p) {
  return std::string(R"({"splintcore_case": 1, "case_id": "real-plan",
    "jaws": [{"role": "maxilla", "mesh": "maxilla.stl"}, {"role": "mandible", "mesh": "mandible.stl"}],
    "base": {"spacing_mm": 0.5, "auto": {}},
    "plan": {"sequence": ")") +
         p.sequence + R"(", "maxilla": )" + matrix_json(p.maxilla) + R"(, "mandible": )" +
         matrix_json(p.mandible) +
         R"(, "hinge_axis": [[4, 90, 80], [104, 90, 80]],
      "intermediate_opening_mm": 2, "final_opening_mm": 1.5}})";
}

// The angle of one splint against the oracle: the distance crosses the opening asked within
// HingeOracle::kBracket of the solver's angle (opposite signs on the two sides).
void expect_angle_agrees(const char* what, const Mesh& maxilla, const Mesh& mandible,
                         const CasePlan& plan, bool final_splint, const PlanSplintReport& r) {
  const bool move_maxilla = final_splint || !plan.mandible_first;
  const bool move_mandible = final_splint || plan.mandible_first;
  HingeOracle oracle(maxilla, move_maxilla ? plan.maxilla : RigidTransform{}, mandible,
                     move_mandible ? plan.mandible : RigidTransform{}, plan.hinge[0],
                     plan.hinge[1]);
  const double angle = r.autorotation.angle_rad;
  const double target = r.opening_asked_mm;
  const double at = oracle.collect(angle, target + 0.01);
  double lo = angle - HingeOracle::kBracket, hi = angle + HingeOracle::kBracket;
  const double f_lo = oracle.distance(lo) - target, f_hi = oracle.distance(hi) - target;
  EXPECT_LT(f_lo * f_hi, 0) << what << ": the distance does not cross " << target
                            << " mm within 1e-6 rad of " << angle << " (" << f_lo << ", " << f_hi
                            << ")";
  if (!(f_lo * f_hi < 0)) return;
  for (int k = 0; k < 60 && hi - lo > 1e-13; ++k) {
    const double mid = 0.5 * (lo + hi);
    ((oracle.distance(mid) - target) * f_lo > 0 ? lo : hi) = mid;
  }
  const double found = 0.5 * (lo + hi);
  EXPECT_NEAR(angle, found, 1e-6) << what;
  std::printf(
      "%-28s angle %.12f rad, oracle %.12f (|diff| %.2e, %zu pairs, %d evaluations), "
      "distance there %.9f mm\n",
      what, angle, found, std::fabs(angle - found), oracle.pairs(), oracle.evaluations, at);
}

// `m` moved by `x` and rounded to float32 (as design_splint moves a jaw), with its index.
struct PlacedJaw {
  Mesh mesh;
  DistanceIndex index;
};

void place(Arena& arena, const Mesh& m, const RigidTransform& x, PlacedJaw* out) {
  out->mesh.bind(&arena);
  ASSERT_TRUE(out->mesh.vertices.reserve(m.vertices.size()));
  for (const Vec3& v : m.vertices) {
    Vec3 p = x.apply_point(v);
    ASSERT_TRUE(round_to_float32(&p));
    (void)out->mesh.vertices.push_back(p);
  }
  for (const Triangle& t : m.triangles) (void)out->mesh.triangles.push_back(t);
  SPLINTCORE_ASSERT_OK(
      build_distance_index(Context(&arena), out->mesh, DistanceIndexOptions{}, &out->index));
}

// Half a float32 unit in the last place at coordinates below 128 mm, along a diagonal: how far
// a vertex the Boolean computed on a jaw's surface may lie off it once rounded to float32 (the
// jaw's own vertices, already float32, stay exact).
constexpr double kFloatRounding = 6.7e-6;

// The splint's vertices against each jaw in its position: on it (1e-6 mm), near it but off it
// (within 0.01 mm: no further than float32 rounding), inside (none).
void expect_imprints_on_jaws(const char* what, Arena& arena, const Mesh& splint,
                             const Mesh& maxilla, const Mesh& mandible, const PlanSplintReport& r) {
  ArenaScope scope(arena);
  PlacedJaw jaws[2];
  ASSERT_NO_FATAL_FAILURE(place(arena, maxilla, r.maxilla, &jaws[0]));
  ASSERT_NO_FATAL_FAILURE(place(arena, mandible, r.mandible, &jaws[1]));
  const size_t n = splint.vertices.size();
  ClosestPoint* cp = arena.allocate_array<ClosestPoint>(n);
  ASSERT_NE(cp, nullptr);
  const char* names[2] = {"maxilla", "mandible"};
  for (int j = 0; j < 2; ++j) {
    SPLINTCORE_ASSERT_OK(batch_closest_points(Context(&arena), jaws[j].index,
                                              Span<const Vec3>(splint.vertices.data(), n),
                                              Span<ClosestPoint>(cp, n)));
    size_t on = 0, near_off = 0, inside = 0;
    double worst_near = 0;
    for (size_t i = 0; i < n; ++i) {
      const double d = cp[i].distance;
      if (d <= 1e-6) {
        ++on;
        continue;
      }
      if (d < 0.01) {
        ++near_off;
        worst_near = std::max(worst_near, d);
      }
      SignedDistance sd;
      // (Within rounding of the surface the sign is the rounding's.)
      if (d > kFloatRounding && d < 0.5 &&
          signed_distance(jaws[j].index, splint.vertices[i], SignMethod::kAuto, &sd) &&
          sd.distance < 0) {
        ++inside;
      }
    }
    std::printf(
        "%-28s %s: %zu vertices on it, %zu within 0.01 mm but off (worst %.3g), %zu inside\n", what,
        names[j], on, near_off, worst_near, inside);
    EXPECT_GT(on, 1000u) << what << ": the " << names[j] << "'s imprint";
    EXPECT_LE(worst_near, kFloatRounding)
        << what << ": a vertex near the " << names[j] << " is off it by more than float32 rounding";
    EXPECT_EQ(inside, 0u) << what << ": splint vertices inside the " << names[j];
  }
}

void expect_meshlab_agrees(const char* what, Arena& arena, const Mesh& splint, double volume) {
  if (!test::have_meshlab()) return;
  std::vector<uint8_t> bytes;
  SPLINTCORE_ASSERT_OK(test::mesh_to_bytes(arena, splint, StlFormat::kBinary, &bytes));
  const std::string log = test::meshlab_log_of_bytes(bytes);
  EXPECT_NE(log.find("Mesh is two-manifold"), std::string::npos) << what << "\n" << log;
  EXPECT_NE(log.find("Boundary Edges 0"), std::string::npos) << what << "\n" << log;
  EXPECT_NEAR(test::number_after(log, "Mesh Volume  is "), volume, 1e-5 * volume) << what;
}

TEST(PlanRealData, FivePlansAgreeWithTheIndependentOracle) {
  const test::RealJaws& jaws = test::real_jaws();
  if (!jaws.ok) GTEST_SKIP() << "no real dentition at " << SPLINTCORE_REALDATA_DIR;
  for (const RealPlan& p : real_plans()) {
    test::TestArena t{size_t{640} << 20};
    Context ctx(&t.arena);
    const std::string text = plan_case(p);
    CaseFile c;
    SPLINTCORE_ASSERT_OK(parse_case(ctx, text.data(), text.size(), p.name, &c));
    Mesh intermediate, final_splint;
    PlanReport r;
    const Status s =
        design_plan(ctx, c, Span<const Mesh>(jaws.jaw, 2), &intermediate, &final_splint, &r);
    ASSERT_TRUE(s.is_ok()) << p.name << ": " << test::format(s);
    const Mesh* splints[2] = {&intermediate, &final_splint};
    const PlanSplintReport* reports[2] = {&r.intermediate, &r.final_splint};
    for (int k = 0; k < 2; ++k) {
      const std::string what = std::string(p.name) + (k == 0 ? " intermediate" : " final");
      const DesignReport& d = reports[k]->design;
      EXPECT_TRUE(d.print.printable) << what;
      EXPECT_TRUE(d.self_intersection_checked) << what;
      EXPECT_TRUE(d.outlined) << what;
      expect_angle_agrees(what.c_str(), jaws.jaw[0], jaws.jaw[1], c.plan, k == 1, *reports[k]);
      expect_imprints_on_jaws(what.c_str(), t.arena, *splints[k], jaws.jaw[0], jaws.jaw[1],
                              *reports[k]);
      expect_meshlab_agrees(what.c_str(), t.arena, *splints[k], d.print.mesh.volume);
    }
  }
}

}  // namespace
}  // namespace splintcore
