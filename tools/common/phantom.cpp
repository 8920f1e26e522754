// Synthetic dental-arch phantoms: a star-shaped section swept along an elliptical arch, with 14
// crowns per jaw (see phantom.h for the shape and how it fits paper_scale.json).
//
// Sampling: both directions are spaced by arc length of a reference curve, computed on a fine
// grid (only + - * / sqrt): around the ring by the arc length of a full crown's section, so the
// steep crown walls get as many vertices as the gum; along the arch by the arc length of the
// section's occlusal-most point, so the mesial and distal crown walls get sections too.
#include "phantom.h"

#include <cmath>
#include <cstdio>
#include <string>

#include "splintcore/io.h"

#ifdef __FAST_MATH__
#error "phantom.cpp needs IEEE semantics (no -ffast-math): its bytes are pinned by golden hashes"
#endif

namespace splintcore {
namespace phantom {

namespace {

constexpr double kPi = 3.141592653589793;
constexpr double kHalfPi = 1.5707963267948966;

// ---- the case (fixtures/make_case_fixtures.py, paper_scale.json) -----------------------------
constexpr double kUpperA = 25.0, kUpperB = 42.0;  // upper picks: (a cos t, b sin t, +1.6)
constexpr double kLowerA = 24.0, kLowerB = 40.5;  // lower picks: (a cos t, b sin t, -1.6)
constexpr double kPickT0 = -0.18;                 // picks at t in [kPickT0, pi - kPickT0]
constexpr double kBaseFace = 1.6;                 // base faces at z = +-1.6 (after transforms)
constexpr double kMandibleShift = -2.0;           // the mandible's transform (z translation)
constexpr double kInnerLength = 4.0, kOutsideLength = 3.5;
constexpr double kTowardsOther = 0.35;  // crowns follow the wafer's walls at about 1/3 depth

// ---- the arch ------------------------------------------------------------------------------
constexpr double kTubeT0 = kPickT0 - 0.12;   // the tube runs over t in [kTubeT0, pi - kTubeT0]
constexpr double kTeethT0 = kPickT0 + 0.02;  // the 14 tooth slots share [kTeethT0, pi - kTeethT0]
constexpr double kCrownSlotFraction = 0.86;  // crown length / slot length (the rest: gaps)

// ---- the section, in (p, q): p outward across the arch, q towards the occlusal side, q = 0 on
// the base face the crown meets, q > 0 inside the base --------------------------------------
constexpr double kGumCenterQ = -6.0;
constexpr double kGumHalfWidth = 5.0;   // across the arch
constexpr double kGumHalfHeight = 3.5;  // gum top at q = -2.5
constexpr double kPolarCenterQ = -7.5;  // O: further from the crowns than the gum's centre
constexpr double kCrownHalfAngle = 0.3490658503988659;  // 20 degrees, seen from O
constexpr double kCrownCore = 0.88;   // normalised |sigma|, |tau| where the crown walls start
constexpr double kCuspHeight = 0.45;  // cusp tips above the fossae
constexpr double kReferenceDepth = 1.45;

// The coarsest grid: enough for every crown to have a few sections and ring vertices.
constexpr uint64_t kMinRing = 10;
constexpr uint64_t kMinSections = 4 * kTeethPerJaw;

// Fine grids for the arc-length tables.
constexpr uint32_t kRingTable = 8192;
constexpr uint32_t kArchTable = 32768;

}  // namespace

// sin and cos with only + - * /: reduction by the nearest multiple of pi/2 (|x| is at most a
// few radians here, so one double subtraction loses nothing that matters), then Taylor
// polynomials to degree 17 and 18 on |r| <= pi/4 (truncation below 1e-16). Bit-identical
// everywhere; a few ulps from libm at worst.
void sin_cos(double x, double* s, double* c) {
  const double t = x / kHalfPi;
  const int64_t k = static_cast<int64_t>(t < 0.0 ? t - 0.5 : t + 0.5);
  const double r = x - static_cast<double>(k) * kHalfPi;
  const double r2 = r * r;
  double ps = 1.0 / 355687428096000.0;  // 1/17!
  ps = -1.0 / 1307674368000.0 + r2 * ps;
  ps = 1.0 / 6227020800.0 + r2 * ps;
  ps = -1.0 / 39916800.0 + r2 * ps;
  ps = 1.0 / 362880.0 + r2 * ps;
  ps = -1.0 / 5040.0 + r2 * ps;
  ps = 1.0 / 120.0 + r2 * ps;
  ps = -1.0 / 6.0 + r2 * ps;
  ps = r + r * (r2 * ps);
  double pc = -1.0 / 6402373705728000.0;  // -1/18!
  pc = 1.0 / 20922789888000.0 + r2 * pc;
  pc = -1.0 / 87178291200.0 + r2 * pc;
  pc = 1.0 / 479001600.0 + r2 * pc;
  pc = -1.0 / 3628800.0 + r2 * pc;
  pc = 1.0 / 40320.0 + r2 * pc;
  pc = -1.0 / 720.0 + r2 * pc;
  pc = 1.0 / 24.0 + r2 * pc;
  pc = -0.5 + r2 * pc;
  pc = 1.0 + r2 * pc;
  switch (static_cast<uint64_t>(k) & 3u) {
    case 0:
      *s = ps;
      *c = pc;
      break;
    case 1:
      *s = pc;
      *c = -ps;
      break;
    case 2:
      *s = -ps;
      *c = -pc;
      break;
    default:
      *s = -pc;
      *c = ps;
      break;
  }
}

namespace {

// Rounds to float32 through a volatile float: g++ 12.2 at -O2 vectorises two neighbouring
// double -> float -> double round trips into plain double arithmetic (the rounding vanishes).
double to_float32(double v) {
  volatile float rounded = static_cast<float>(v);
  return static_cast<double>(rounded) + 0.0;  // + 0.0: -0 becomes +0
}

// 3t^2 - 2t^3 on [0, 1].
double smoothstep(double t) { return t * t * (3.0 - 2.0 * t); }

// ---- the jaws --------------------------------------------------------------------------------

struct JawShape {
  double a = 0, b = 0;   // the path's ellipse (before the inward offset)
  double offset = 0;     // along the outward normal (negative: inward)
  double z_face = 0;     // z of q = 0, in the jaw's own frame (occlusion)
  double z_sign = 0;     // z = z_face + z_sign * q
  bool reverse = false;  // winding reversed (the mandible's section is mirrored in z)
  uint32_t salt = 0;     // varies the cusp depths between the jaws
};

JawShape jaw_shape(Jaw jaw) {
  JawShape s;
  const double w = jaw == Jaw::kMaxilla ? kTowardsOther : 1.0 - kTowardsOther;
  s.a = (1.0 - w) * kUpperA + w * kLowerA;
  s.b = (1.0 - w) * kUpperB + w * kLowerB;
  s.offset = 0.5 * (kOutsideLength - kInnerLength);
  if (jaw == Jaw::kMaxilla) {
    s.z_face = kBaseFace;
    s.z_sign = -1.0;
    s.reverse = false;
    s.salt = 0;
  } else {
    s.z_face = -kBaseFace - kMandibleShift;
    s.z_sign = 1.0;
    s.reverse = true;
    s.salt = 3;
  }
  return s;
}

// A point of the path: position, unit outward normal, radius of curvature.
struct PathPoint {
  double x = 0, y = 0;
  double nx = 0, ny = 0;
  double radius = 0;
};

PathPoint path_point(const JawShape& shape, double t) {
  double st, ct;
  sin_cos(t, &st, &ct);
  const double ex = shape.a * ct, ey = shape.b * st;
  const double gx = shape.b * ct, gy = shape.a * st;  // outward normal, unnormalised
  const double g = std::sqrt(gx * gx + gy * gy);      // = |derivative|
  PathPoint p;
  p.nx = gx / g;
  p.ny = gy / g;
  p.x = ex + shape.offset * p.nx;
  p.y = ey + shape.offset * p.ny;
  p.radius = g * g * g / (shape.a * shape.b) + shape.offset;
  return p;
}

// ---- teeth -----------------------------------------------------------------------------------

enum class ToothKind : uint8_t { kMolar, kPremolar, kCanine, kIncisor };

ToothKind tooth_kind(uint32_t tooth) {
  const uint32_t from_end = tooth < kTeethPerJaw / 2 ? tooth : kTeethPerJaw - 1 - tooth;
  if (from_end < 2) return ToothKind::kMolar;
  if (from_end < 4) return ToothKind::kPremolar;
  if (from_end < 5) return ToothKind::kCanine;
  return ToothKind::kIncisor;
}

// The deepest cusp tip's depth into the base: 1.38..1.52 mm, varied per tooth.
double tooth_depth(uint32_t tooth, uint32_t salt) {
  return 1.38 + 0.02 * static_cast<double>((5u * tooth + salt) % 8u);
}

struct Cusp {
  double sigma, tau;  // centre in normalised crown coordinates
  double r_sigma, r_tau;
  double height;  // above the fossa
};

// The cusps of a tooth; tau > 0 is buccal (outward). The first cusp is the highest.
uint32_t tooth_cusps(ToothKind kind, Cusp cusps[4]) {
  const double h = kCuspHeight, lower = kCuspHeight - 0.08;
  switch (kind) {
    case ToothKind::kMolar:
      cusps[0] = {-0.42, 0.42, 0.42, 0.42, h};
      cusps[1] = {0.42, 0.42, 0.42, 0.42, h - 0.04};
      cusps[2] = {-0.42, -0.42, 0.42, 0.42, lower};
      cusps[3] = {0.42, -0.42, 0.42, 0.42, lower - 0.04};
      return 4;
    case ToothKind::kPremolar:
      cusps[0] = {0.0, 0.42, 0.55, 0.45, h};
      cusps[1] = {0.0, -0.42, 0.55, 0.45, lower};
      return 2;
    case ToothKind::kCanine: cusps[0] = {0.0, 0.1, 0.7, 0.6, h}; return 1;
    default: cusps[0] = {0.0, 0.15, 0.9, 0.35, h}; return 1;
  }
}

// The occlusal surface's q at normalised (sigma, tau): fossa level plus the highest bump
// (max, not sum: each tip is exactly as high as designed).
double occlusal_q(double depth, const Cusp* cusps, uint32_t count, double sigma, double tau) {
  double bump = 0.0;
  for (uint32_t i = 0; i < count; ++i) {
    const double ds = (sigma - cusps[i].sigma) / cusps[i].r_sigma;
    const double dt = (tau - cusps[i].tau) / cusps[i].r_tau;
    const double d2 = ds * ds + dt * dt;
    if (d2 < 1.0) {
      const double w = (1.0 - d2) * (1.0 - d2) * cusps[i].height;
      if (w > bump) bump = w;
    }
  }
  return depth - kCuspHeight + bump;
}

// Where along the arch: the tooth slot and the normalised mesio-distal coordinate sigma
// (|sigma| < 1 on the crown), or tooth = kGumLabel between crowns.
struct ArchPlace {
  uint8_t tooth = kGumLabel;
  double sigma = 0;
};

ArchPlace arch_place(double t) {
  ArchPlace place;
  const double span = kPi - 2.0 * kTeethT0;
  const double x = (t - kTeethT0) / span * static_cast<double>(kTeethPerJaw);
  if (!(x >= 0.0) || !(x < static_cast<double>(kTeethPerJaw))) return place;
  const uint32_t k = static_cast<uint32_t>(x);
  const double s = 2.0 * (x - static_cast<double>(k)) - 1.0;  // [-1, 1) in the slot
  const double sigma = s / kCrownSlotFraction;
  if (!(sigma > -1.0 && sigma < 1.0)) return place;
  place.tooth = static_cast<uint8_t>(k);
  place.sigma = sigma;
  return place;
}

// The gum ridge (ellipse) seen from O along direction (sin a, cos a): the positive root of
// |O + r d - G|_ellipse = 1.
double gum_radius(double sa, double ca) {
  const double e = kPolarCenterQ - kGumCenterQ;
  const double ia = 1.0 / (kGumHalfWidth * kGumHalfWidth);
  const double ib = 1.0 / (kGumHalfHeight * kGumHalfHeight);
  const double a2 = sa * sa * ia + ca * ca * ib;
  const double b1 = e * ca * ib;
  const double c0 = e * e * ib - 1.0;
  return (-b1 + std::sqrt(b1 * b1 - a2 * c0)) / a2;
}

// One direction of the ring, precomputed.
struct RingAngle {
  double alpha = 0;
  double sin_a = 0, cos_a = 0;
  double gum = 0;  // gum radius
  double tau = 0;  // alpha / crown half angle
};

RingAngle ring_angle(double alpha) {
  RingAngle r;
  r.alpha = alpha;
  sin_cos(alpha, &r.sin_a, &r.cos_a);
  r.gum = gum_radius(r.sin_a, r.cos_a);
  r.tau = alpha / kCrownHalfAngle;
  return r;
}

// The section's radius from O in direction `dir`, for a crown at (sigma) with the given
// occlusal surface; *weight > 0 when the crown moved the point.
struct CrownAt {
  bool present = false;
  double sigma = 0;
  double depth = 0;
  Cusp cusps[4] = {};
  uint32_t cusp_count = 0;
};

// The crown's weight along one normalised axis: 1 on the core, a smoothstep down to 0 at the
// footprint's edge.
double edge_weight(double x) {
  const double a = x < 0.0 ? -x : x;
  if (!(a < 1.0)) return 0.0;
  return a <= kCrownCore ? 1.0 : smoothstep((1.0 - a) / (1.0 - kCrownCore));
}

// The section's radius from O in direction `dir`. The crown's footprint is separable in
// (sigma, tau), so its buccal and lingual walls sit at the same ring angles in every section
// (where the ring is sampled densely) and its mesial and distal walls in the same sections
// whatever the angle (where the arch is). *weight > 0 when the crown moved the point.
double section_radius(const CrownAt& crown, const RingAngle& dir, double* weight) {
  *weight = 0.0;
  if (!crown.present) return dir.gum;
  const double w = edge_weight(crown.sigma) * edge_weight(dir.tau);
  if (!(w > 0.0)) return dir.gum;
  const double q = occlusal_q(crown.depth, crown.cusps, crown.cusp_count, crown.sigma, dir.tau);
  const double crown_radius = (q - kPolarCenterQ) / dir.cos_a;  // cos_a > cos 20 deg here
  *weight = w;
  return dir.gum + w * (crown_radius - dir.gum);
}

CrownAt crown_at(const ArchPlace& place, uint32_t salt) {
  CrownAt c;
  if (place.tooth == kGumLabel) return c;
  c.present = true;
  c.sigma = place.sigma;
  c.depth = tooth_depth(place.tooth, salt);
  c.cusp_count = tooth_cusps(tooth_kind(place.tooth), c.cusps);
  return c;
}

// Inverts a cumulative table: the parameter in [t0, t0 + n * step] at arc length `target`,
// starting the search at *k (targets come in increasing order).
double invert_table(const std::vector<double>& cumulative, double t0, double step, double target,
                    size_t* k) {
  const size_t n = cumulative.size() - 1;
  while (*k + 1 < n && cumulative[*k + 1] <= target) ++*k;
  const double span = cumulative[*k + 1] - cumulative[*k];
  double f = span > 0.0 ? (target - cumulative[*k]) / span : 0.0;
  if (f < 0.0) f = 0.0;
  if (f > 1.0) f = 1.0;
  return t0 + (static_cast<double>(*k) + f) * step;
}

// Arc-length table of the reference section (a full crown, flat at kReferenceDepth) around the
// ring, from alpha = -pi.
void ring_table(std::vector<double>* cumulative) {
  CrownAt crown;
  crown.present = true;
  crown.sigma = 0.0;
  crown.depth = kReferenceDepth;
  crown.cusp_count = 0;
  cumulative->assign(kRingTable + 1, 0.0);
  double px = 0, py = 0;
  for (uint32_t k = 0; k <= kRingTable; ++k) {
    const double alpha = -kPi + 2.0 * kPi * static_cast<double>(k) / kRingTable;
    const RingAngle dir = ring_angle(alpha);
    double w;
    const double r = section_radius(crown, dir, &w);
    const double x = r * dir.sin_a, y = r * dir.cos_a;
    if (k > 0) {
      (*cumulative)[k] =
          (*cumulative)[k - 1] + std::sqrt((x - px) * (x - px) + (y - py) * (y - py));
    }
    px = x;
    py = y;
  }
}

// Arc-length table along the arch of the section's occlusal-most point (alpha = 0).
void arch_table(const JawShape& shape, std::vector<double>* cumulative) {
  cumulative->assign(kArchTable + 1, 0.0);
  const RingAngle top = ring_angle(0.0);
  const double step = (kPi - 2.0 * kTubeT0) / kArchTable;
  double px = 0, py = 0, pz = 0;
  for (uint32_t k = 0; k <= kArchTable; ++k) {
    const double t = kTubeT0 + static_cast<double>(k) * step;
    const PathPoint p = path_point(shape, t);
    double w;
    const double q = kPolarCenterQ + section_radius(crown_at(arch_place(t), shape.salt), top, &w);
    if (k > 0) {
      const double dx = p.x - px, dy = p.y - py, dz = q - pz;
      (*cumulative)[k] = (*cumulative)[k - 1] + std::sqrt(dx * dx + dy * dy + dz * dz);
    }
    px = p.x;
    py = p.y;
    pz = q;
  }
}

GridSize grid_for(uint64_t target, double aspect) {
  GridSize g;
  if (target < kMinTriangles || target > kMaxTriangles) return g;
  // Square-ish quads: sections / ring_size = aspect. Then the ring size near that whose best
  // section count lands closest to the target (ties: the smaller ring).
  const double ideal = std::sqrt(static_cast<double>(target) / (2.0 * aspect));
  const uint64_t lo = static_cast<uint64_t>(ideal * 0.85) > kMinRing
                          ? static_cast<uint64_t>(ideal * 0.85)
                          : kMinRing;
  const uint64_t hi = static_cast<uint64_t>(ideal * 1.15) + 1;
  uint64_t best_error = ~uint64_t{0};
  for (uint64_t nv = lo; nv <= hi; ++nv) {
    const uint64_t nu = (target + nv) / (2 * nv);
    if (nu < kMinSections) continue;
    const uint64_t got = 2 * nu * nv;
    const uint64_t error = got > target ? got - target : target - got;
    if (error < best_error) {
      best_error = error;
      g.sections = static_cast<uint32_t>(nu);
      g.ring_size = static_cast<uint32_t>(nv);
    }
  }
  return g;
}

// The sections / ring_size ratio that makes quads about square: arch length over ring length
// of the reference curves (the maxilla's; the mandible's differ by a few per cent).
double grid_aspect(std::vector<double>* ring, std::vector<double>* arch) {
  ring_table(ring);
  arch_table(jaw_shape(Jaw::kMaxilla), arch);
  return arch->back() / ring->back();
}

}  // namespace

GridSize choose_grid(uint64_t target_triangles) {
  std::vector<double> ring, arch;
  return grid_for(target_triangles, grid_aspect(&ring, &arch));
}

Status make_jaw(Jaw jaw, const PhantomOptions& options, JawMesh* out) {
  *out = JawMesh{};
  const uint64_t target = options.target_triangles;
  if (target < kMinTriangles || target > kMaxTriangles) {
    return make_error(StatusCode::kInvalidArgument, "phantom: target of ", target,
                      " triangles is outside ", kMinTriangles, "..", kMaxTriangles);
  }
  const JawShape shape = jaw_shape(jaw);
  std::vector<double> ring, arch;
  const GridSize grid = grid_for(target, grid_aspect(&ring, &arch));
  if (jaw != Jaw::kMaxilla) arch_table(shape, &arch);
  const uint32_t nu = grid.sections, nv = grid.ring_size;
  if (nu == 0 || nv == 0) return Status::error(StatusCode::kInternal, "phantom: no grid");

  // Ring directions, equally spaced in the reference section's arc length.
  std::vector<RingAngle> dirs(nv);
  {
    size_t k = 0;
    const double step = 2.0 * kPi / kRingTable;
    for (uint32_t j = 0; j < nv; ++j) {
      const double target_len = ring.back() * static_cast<double>(j) / nv;
      dirs[j] = ring_angle(invert_table(ring, -kPi, step, target_len, &k));
      if (j > 0 && !(dirs[j].alpha > dirs[j - 1].alpha)) {
        return Status::error(StatusCode::kInternal, "phantom: ring angles not increasing");
      }
    }
  }

  out->sections = nu;
  out->ring_size = nv;
  out->vertices.reserve(size_t{nu} * nv + 2);
  out->vertex_tooth.reserve(size_t{nu} * nv + 2);
  for (uint32_t k = 0; k < kTeethPerJaw; ++k) out->tooth_depth_mm[k] = tooth_depth(k, shape.salt);
  out->min_path_radius_mm = HUGE_VAL;
  out->max_concave_reach_mm = 0.0;

  const double arch_step = (kPi - 2.0 * kTubeT0) / kArchTable;
  size_t search = 0;
  PathPoint first{}, last{};
  for (uint32_t i = 0; i < nu; ++i) {
    const double target_len = arch.back() * static_cast<double>(i) / (nu - 1);
    const double t =
        i + 1 == nu ? kPi - kTubeT0 : invert_table(arch, kTubeT0, arch_step, target_len, &search);
    const PathPoint p = path_point(shape, t);
    if (i == 0) first = p;
    last = p;
    if (p.radius < out->min_path_radius_mm) out->min_path_radius_mm = p.radius;
    const ArchPlace place = arch_place(t);
    const CrownAt crown = crown_at(place, shape.salt);
    for (uint32_t j = 0; j < nv; ++j) {
      double w;
      const double r = section_radius(crown, dirs[j], &w);
      const double pp = r * dirs[j].sin_a;
      const double q = kPolarCenterQ + r * dirs[j].cos_a;
      if (-pp > out->max_concave_reach_mm) out->max_concave_reach_mm = -pp;
      out->vertices.push_back(Vec3{to_float32(p.x + pp * p.nx), to_float32(p.y + pp * p.ny),
                                   to_float32(shape.z_face + shape.z_sign * q)});
      out->vertex_tooth.push_back(w > 0.0 ? place.tooth : kGumLabel);
    }
  }
  // Cap centres: O of the end sections.
  const double z_center = to_float32(shape.z_face + shape.z_sign * kPolarCenterQ);
  out->vertices.push_back(Vec3{to_float32(first.x), to_float32(first.y), z_center});
  out->vertices.push_back(Vec3{to_float32(last.x), to_float32(last.y), z_center});
  out->vertex_tooth.push_back(kGumLabel);
  out->vertex_tooth.push_back(kGumLabel);
  if (!(out->min_path_radius_mm > out->max_concave_reach_mm)) {
    return Status::error(StatusCode::kInternal, "phantom: sections would cross");
  }

  // Quads (i, j) (i + 1, j) (i + 1, j + 1) (i, j + 1) face outward for the maxilla (tangent x
  // outward normal points down, where its crowns point); the mandible's are reversed.
  out->triangles.reserve(size_t{2} * nu * nv);
  auto emit = [&](uint32_t a, uint32_t b, uint32_t c) {
    out->triangles.push_back(shape.reverse ? Triangle{{a, c, b}} : Triangle{{a, b, c}});
  };
  auto at = [nv](uint32_t i, uint32_t j) { return i * nv + (j == nv ? 0 : j); };
  for (uint32_t i = 0; i + 1 < nu; ++i) {
    for (uint32_t j = 0; j < nv; ++j) {
      emit(at(i, j), at(i + 1, j), at(i + 1, j + 1));
      emit(at(i, j), at(i + 1, j + 1), at(i, j + 1));
    }
  }
  const uint32_t start_center = nu * nv, end_center = nu * nv + 1;
  for (uint32_t j = 0; j < nv; ++j) emit(start_center, at(0, j), at(0, j + 1));
  for (uint32_t j = 0; j < nv; ++j) emit(end_center, at(nu - 1, j + 1), at(nu - 1, j));
  return Status::ok();
}

Status to_mesh(const JawMesh& jaw, Mesh* out) {
  const uint64_t base = out->vertices.size();
  if (base + jaw.vertices.size() > uint64_t{0xffffffff}) {
    return Status::error(StatusCode::kLimitExceeded, "phantom: too many vertices for one mesh");
  }
  Arena* arena = out->vertices.arena();
  if (!out->vertices.reserve(out->vertices.size() + jaw.vertices.size()) ||
      !out->triangles.reserve(out->triangles.size() + jaw.triangles.size())) {
    return arena->exhausted_status();
  }
  for (const Vec3& v : jaw.vertices) {
    if (!out->vertices.push_back(v)) return arena->exhausted_status();
  }
  const uint32_t shift = static_cast<uint32_t>(base);
  for (const Triangle& t : jaw.triangles) {
    if (!out->triangles.push_back(Triangle{{t.v[0] + shift, t.v[1] + shift, t.v[2] + shift}})) {
      return arena->exhausted_status();
    }
  }
  return Status::ok();
}

Status stl_bytes(const JawMesh& jaw, std::vector<uint8_t>* out) {
  out->assign(84 + 50 * jaw.triangles.size(), 0);
  std::vector<unsigned char> memory(size_t{1} << 17);
  Arena arena(memory.data(), memory.size());
  Context ctx(&arena);
  MemorySink sink{out->data(), out->size(), 0, 0};
  StlWriter writer;
  SPLINTCORE_RETURN_IF_ERROR(
      writer.begin(ctx, memory_sink(&sink), StlWriteOptions{}, jaw.triangles.size()));
  for (const Triangle& t : jaw.triangles) {
    SPLINTCORE_RETURN_IF_ERROR(
        writer.add(jaw.vertices[t.v[0]], jaw.vertices[t.v[1]], jaw.vertices[t.v[2]]));
  }
  SPLINTCORE_RETURN_IF_ERROR(writer.finish());
  out->resize(static_cast<size_t>(sink.size));
  return Status::ok();
}

std::string case_json(const char* case_id) {
  // fixtures/make_case_fixtures.py, arch(14, a, b, -0.18, z): phi from -0.18 to pi + 0.18.
  auto picks = [](double a, double b, double z) {
    std::string out;
    for (int i = 0; i < 14; ++i) {
      const double phi = -0.18 + (kPi + 0.36) * (static_cast<double>(i) / 13.0);
      double sp = 0, cp = 0;
      sin_cos(phi, &sp, &cp);
      double nx = b * cp, ny = a * sp;
      const double ln = std::sqrt(nx * nx + ny * ny);
      nx /= ln;
      ny /= ln;
      char row[256];
      std::snprintf(
          row, sizeof row,
          "%s\n        {\"position\": [%.4f, %.4f, %.4f], \"normal\": [%.4f, %.4f, %.4f]}",
          i > 0 ? "," : "", a * cp + 0.0, b * sp + 0.0, z, nx * 0.95 + 0.0, ny * 0.95 + 0.0,
          z > 0 ? -0.31 : 0.31);
      out += row;
    }
    return out;
  };
  std::string j = "{\n  \"splintcore_case\": 1,\n  \"case_id\": \"";
  j += case_id;
  j += "\",\n  \"units\": \"mm\",\n  \"jaws\": [\n"
       "    {\"role\": \"maxilla\", \"mesh\": \"maxilla.stl\"},\n"
       "    {\"role\": \"mandible\", \"mesh\": \"mandible.stl\",\n"
       "     \"transform\": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, -2.0, 0, 0, 0, 1]}\n  ],\n"
       "  \"base\": {\n    \"occlusal_normal\": [0, 0, 1],\n    \"spacing_mm\": 0.42,\n"
       "    \"inner_length_mm\": 4.0,\n    \"outside_length_mm\": 3.5,\n    \"upper\": [";
  j += picks(kUpperA, kUpperB, 1.6);
  j += "\n    ],\n    \"lower\": [";
  j += picks(kLowerA, kLowerB, -1.6);
  j += "\n    ]\n  },\n  \"insertion_direction\": [0, 0, 1],\n  \"printer\": \"eden260\",\n"
       "  \"output\": {\"splint\": \"splint.stl\", \"report\": \"report.json\"}\n}\n";
  return j;
}

}  // namespace phantom
}  // namespace splintcore
