// A skull-like CT phantom with analytic surfaces (see ct_phantom.h for the anatomy and values).
//
// Sources: the round cone's exact distance is I. Quilez, "distance functions" (iquilezles.org,
// "Round Cone - exact"); the rounded rectangle's is the standard box distance (ibid., "Box -
// exact") with its corners rounded; noise from the splitmix64 finaliser (Steele, Lea and
// Flood, "Fast splittable pseudorandom number generators", OOPSLA 2014), a sum of four
// uniforms for a bell-shaped distribution (Irwin-Hall).
#include "ct_phantom.h"

#include <cmath>

#ifdef __FAST_MATH__
#error "ct_phantom.cpp needs IEEE semantics (no -ffast-math): its bytes are pinned by tests"
#endif

namespace splintcore {
namespace cli {

namespace {

constexpr double kArchApexY = 18.0;  // y = kArchApexY - kArchDepth (x / kArchHalfWidth)^2
constexpr double kArchDepth = 40.0;
constexpr double kArchHalfWidth = 26.0;
constexpr int kArchPoints = 241;  // polyline over x in [-30, 30], 0.25 mm apart
constexpr double kArchXMax = 30.0;

constexpr double kBoneZ = 13.0;  // bone slab centres at z = +-13
constexpr double kBoneHalfWidth = 5.5;
constexpr double kBoneHalfHeight = 4.0;
constexpr double kBoneRounding = 1.5;
constexpr double kBoneEndExtra = 3.0;  // the slab runs this far beyond the last crown centre

constexpr double kRootZ = 14.5;
constexpr double kRootRadius = 1.0;
// From the midline: central incisor, lateral incisor, canine, premolars, molars.
constexpr double kCrownRadius[7] = {3.2, 2.7, 3.0, 3.0, 3.0, 4.0, 3.8};
// Half the overlap of facing crowns (negative: half the gap).
constexpr double kHalfOverlap[7] = {-0.6, -0.6, -0.6, 0.0, 0.0, 0.15, 0.15};

constexpr double kEnamelHu = 2000.0;
constexpr double kBoneHu = 1200.0;
constexpr double kSoftTissueHu = 40.0;
constexpr double kAirHu = -1000.0;

constexpr double kHeadCentreY = -3.0;
constexpr double kHeadHalf[3] = {36.0, 34.0, 26.0};
constexpr double kHeadRounding = 8.0;

constexpr double kStreakHalfThickness = 0.75;
constexpr double kStreakWidth = 0.8;
constexpr double kStreakReach = 30.0;
constexpr double kStreakBright = 150.0;
constexpr double kStreakDark = -250.0;
// Eight directions, 22.5 degrees apart (cos, sin).
constexpr double kStreakDir[8][2] = {
    {1.0, 0.0},
    {0.9238795325112867, 0.3826834323650898},
    {0.7071067811865476, 0.7071067811865476},
    {0.3826834323650898, 0.9238795325112867},
    {0.0, 1.0},
    {-0.3826834323650898, 0.9238795325112867},
    {-0.7071067811865476, 0.7071067811865476},
    {-0.9238795325112867, 0.3826834323650898},
};
constexpr double kSqrt3 = 1.7320508075688772;

double clamp01(double t) { return t < 0.0 ? 0.0 : (t > 1.0 ? 1.0 : t); }
double sign_of(double v) { return v > 0.0 ? 1.0 : (v < 0.0 ? -1.0 : 0.0); }

// Distance in the plane from (px, py) to the segment (x0, y0)-(x1, y1).
double segment_distance(double px, double py, double x0, double y0, double x1, double y1) {
  const double dx = x1 - x0, dy = y1 - y0;
  const double wx = px - x0, wy = py - y0;
  const double l2 = dx * dx + dy * dy;
  const double t = l2 > 0.0 ? clamp01((wx * dx + wy * dy) / l2) : 0.0;
  const double ex = wx - dx * t, ey = wy - dy * t;
  return std::sqrt(ex * ex + ey * ey);
}

// Exact distance to a rounded rectangle centred at 0 with half sizes (hx, hy), rounding r.
double rounded_rect(double x, double y, double hx, double hy, double r) {
  const double wx = std::fabs(x) - (hx - r);
  const double wy = std::fabs(y) - (hy - r);
  const double ox = wx > 0.0 ? wx : 0.0, oy = wy > 0.0 ? wy : 0.0;
  const double inside = wx > wy ? wx : wy;
  return std::sqrt(ox * ox + oy * oy) + (inside < 0.0 ? inside : 0.0) - r;
}

double rounded_box(const Vec3& p, const double half[3], double r) {
  const double w[3] = {std::fabs(p.x) - (half[0] - r), std::fabs(p.y) - (half[1] - r),
                       std::fabs(p.z) - (half[2] - r)};
  double o2 = 0.0, inside = w[0];
  for (int a = 0; a < 3; ++a) {
    const double o = w[a] > 0.0 ? w[a] : 0.0;
    o2 += o * o;
    if (w[a] > inside) inside = w[a];
  }
  return std::sqrt(o2) + (inside < 0.0 ? inside : 0.0) - r;
}

// Round half away from zero, saturated to int16.
int16_t to_hu(double v) {
  const double r = v >= 0.0 ? std::floor(v + 0.5) : -std::floor(-v + 0.5);
  if (r > 32767.0) return 32767;
  if (r < -32768.0) return -32768;
  return static_cast<int16_t>(r);
}

bool box_contains_xy(const Aabb& b, double x, double y, double m) {
  return x >= b.lo.x - m && x <= b.hi.x + m && y >= b.lo.y - m && y <= b.hi.y + m;
}

// The options' ranges and the axes' orthonormality.
Status check_options(const CtPhantomOptions& o) {
  const uint32_t n[3] = {o.nx, o.ny, o.nz};
  for (int a = 0; a < 3; ++a) {
    if (n[a] == 0 || n[a] > 2048) {
      return make_error(StatusCode::kInvalidArgument, "ct phantom: size ", o.nx, " x ", o.ny, " x ",
                        o.nz, ": each must be 1..2048");
    }
    if (!(o.spacing[a] >= 0.05 && o.spacing[a] <= 5.0)) {
      return make_error(StatusCode::kInvalidArgument, "ct phantom: spacing ", o.spacing[a],
                        " mm must be in [0.05, 5]");
    }
  }
  if (!(o.noise_hu >= 0.0 && o.noise_hu <= 500.0)) {
    return make_error(StatusCode::kInvalidArgument, "ct phantom: noise ", o.noise_hu,
                      " HU must be in [0, 500]");
  }
  if (o.threshold_hu < 100 || o.threshold_hu > 1000) {
    return make_error(StatusCode::kInvalidArgument, "ct phantom: threshold ", o.threshold_hu,
                      " HU must be in [100, 1000]");
  }
  const Vec3 axes[3] = {o.axis_x, o.axis_y, o.axis_z};
  for (int a = 0; a < 3; ++a) {
    for (int b = a; b < 3; ++b) {
      const double d = dot(axes[a], axes[b]);
      const double want = a == b ? 1.0 : 0.0;
      if (!(std::fabs(d - want) <= 1e-9)) {
        return make_error(StatusCode::kInvalidArgument,
                          "ct phantom: the axes are not orthonormal (axis ", a, " . axis ", b,
                          " = ", d, ")");
      }
    }
  }
  return Status::ok();
}

}  // namespace

Status CtPhantom::init(const CtPhantomOptions& o) {
  SPLINTCORE_RETURN_IF_ERROR(check_options(o));
  options_ = o;
  min_spacing_ = o.spacing.x;
  if (o.spacing.y < min_spacing_) min_spacing_ = o.spacing.y;
  if (o.spacing.z < min_spacing_) min_spacing_ = o.spacing.z;
  diag_ =
      std::sqrt(o.spacing.x * o.spacing.x + o.spacing.y * o.spacing.y + o.spacing.z * o.spacing.z);
  centre_hu_ = static_cast<double>(o.threshold_hu) - 0.5;
  slope_ = (centre_hu_ - kSoftTissueHu) / diag_;
  centre_ = Vec3{o.spacing.x * (static_cast<double>(o.nx) - 1.0) * 0.5,
                 o.spacing.y * (static_cast<double>(o.ny) - 1.0) * 0.5,
                 o.spacing.z * (static_cast<double>(o.nz) - 1.0) * 0.5};
  header_ = CtVolume{};
  header_.nx = o.nx;
  header_.ny = o.ny;
  header_.nz = o.nz;
  header_.spacing = o.spacing;
  header_.axis_x = o.axis_x;
  header_.axis_y = o.axis_y;
  header_.axis_z = o.axis_z;
  header_.origin = -(((o.axis_x * centre_.x) + (o.axis_y * centre_.y)) + (o.axis_z * centre_.z));
  noise_key_ = hash_mix(o.seed ^ 0x5c7a11c0ffee1234ull);

  lay_out_anatomy();
  return check_fits();
}

// The teeth along the arch, the bone's segments under them and the streak's centre.
void CtPhantom::lay_out_anatomy() {
  // The arch polyline and its arc length from the apex (x = 0, the middle point).
  double px[kArchPoints], py[kArchPoints], arc[kArchPoints];
  const int mid = kArchPoints / 2;
  for (int v = 0; v < kArchPoints; ++v) {
    const double x = kArchXMax * static_cast<double>(v - mid) / static_cast<double>(mid);
    const double u = x / kArchHalfWidth;
    px[v] = x;
    py[v] = kArchApexY - kArchDepth * (u * u);
  }
  arc[mid] = 0.0;
  for (int v = mid + 1; v < kArchPoints; ++v) {
    const double dx = px[v] - px[v - 1], dy = py[v] - py[v - 1];
    arc[v] = arc[v - 1] + std::sqrt(dx * dx + dy * dy);
  }
  for (int v = mid - 1; v >= 0; --v) {
    const double dx = px[v] - px[v + 1], dy = py[v] - py[v + 1];
    arc[v] = arc[v + 1] - std::sqrt(dx * dx + dy * dy);
  }
  auto at_arc = [&](double s, double* x, double* y) {
    int v = 0;
    while (v + 2 < kArchPoints && arc[v + 1] < s) ++v;
    const double t = (s - arc[v]) / (arc[v + 1] - arc[v]);
    *x = px[v] + (px[v + 1] - px[v]) * t;
    *y = py[v] + (py[v + 1] - py[v]) * t;
  };
  // Crown centres along the arch: neighbours touch at the crown spheres' equators.
  double centre_arc[7];
  centre_arc[0] = kCrownRadius[0];
  for (int p = 1; p < 7; ++p) {
    centre_arc[p] = centre_arc[p - 1] + kCrownRadius[p - 1] + kCrownRadius[p];
  }
  // Teeth 0..13 of a jaw run along the arch from the +x end: 0..6 are positions 6..0 on the
  // +x side, 7..13 positions 0..6 on the -x side.
  for (int jaw = 0; jaw < 2; ++jaw) {
    const double up = jaw == 0 ? 1.0 : -1.0;
    for (int t = 0; t < kCtPhantomTeethPerJaw; ++t) {
      const int pos = t < 7 ? 6 - t : t - 7;
      const double s = t < 7 ? centre_arc[pos] : -centre_arc[pos];
      double x = 0, y = 0;
      at_arc(s, &x, &y);
      RoundCone& c = teeth_[jaw * kCtPhantomTeethPerJaw + t];
      c.r1 = kCrownRadius[pos];
      c.r2 = kRootRadius;
      c.a = Vec3{x, y, up * (c.r1 - kHalfOverlap[pos])};
      c.b = Vec3{x, y, up * kRootZ};
      c.box = Aabb{};
      c.box.add(c.a - Vec3{c.r1, c.r1, c.r1});
      c.box.add(c.a + Vec3{c.r1, c.r1, c.r1});
      c.box.add(c.b - Vec3{c.r2, c.r2, c.r2});
      c.box.add(c.b + Vec3{c.r2, c.r2, c.r2});
    }
  }
  // The bone runs along the polyline over the arc the teeth take, plus a little.
  const double reach = centre_arc[6] + kBoneEndExtra;
  segments_.clear();
  for (int v = 0; v + 1 < kArchPoints; ++v) {
    if (arc[v + 1] < -reach || arc[v] > reach) continue;
    Segment g;
    g.x0 = px[v];
    g.y0 = py[v];
    g.x1 = px[v + 1];
    g.y1 = py[v + 1];
    g.box = Aabb{};
    g.box.add(Vec3{g.x0 - kBoneHalfWidth, g.y0 - kBoneHalfWidth, -kBoneZ - kBoneHalfHeight});
    g.box.add(Vec3{g.x1 + kBoneHalfWidth, g.y1 + kBoneHalfWidth, kBoneZ + kBoneHalfHeight});
    g.box.add(Vec3{g.x1 - kBoneHalfWidth, g.y1 - kBoneHalfWidth, -kBoneZ - kBoneHalfHeight});
    g.box.add(Vec3{g.x0 + kBoneHalfWidth, g.y0 + kBoneHalfWidth, kBoneZ + kBoneHalfHeight});
    segments_.push_back(g);
  }
  const RoundCone& molar = teeth_[1];
  streak_centre_ = molar.a;
}

// The anatomy must fit in the volume, with two voxels to spare on every side.
Status CtPhantom::check_fits() const {
  const CtPhantomOptions& o = options_;
  Aabb anatomy;
  for (const RoundCone& c : teeth_) anatomy.add(c.box);
  for (const Segment& g : segments_) anatomy.add(g.box);
  const double extent[3] = {2.0 * centre_.x, 2.0 * centre_.y, 2.0 * centre_.z};
  for (int a = 0; a < 3; ++a) {
    const double need =
        (anatomy.hi[a] > -anatomy.lo[a] ? anatomy.hi[a] : -anatomy.lo[a]) + 2.0 * o.spacing[a];
    if (!(need <= centre_[a])) {
      return make_error(
          StatusCode::kInvalidArgument, "ct phantom: the volume is ", extent[0], " x ", extent[1],
          " x ", extent[2], " mm between voxel centres; the jaws need at least ",
          2.0 * ((anatomy.hi.x > -anatomy.lo.x ? anatomy.hi.x : -anatomy.lo.x) + 2.0 * o.spacing.x),
          " x ",
          2.0 * ((anatomy.hi.y > -anatomy.lo.y ? anatomy.hi.y : -anatomy.lo.y) + 2.0 * o.spacing.y),
          " x ",
          2.0 * ((anatomy.hi.z > -anatomy.lo.z ? anatomy.hi.z : -anatomy.lo.z) + 2.0 * o.spacing.z),
          " mm (axis ", a, ")");
    }
  }
  return Status::ok();
}

double CtPhantom::round_cone(const RoundCone& c, const Vec3& p) {
  const Vec3 ba = c.b - c.a;
  const double l2 = dot(ba, ba);
  const double rr = c.r1 - c.r2;
  const double a2 = l2 - rr * rr;
  const double il2 = 1.0 / l2;
  const Vec3 pa = p - c.a;
  const double y = dot(pa, ba);
  const double z = y - l2;
  const Vec3 w = pa * l2 - ba * y;
  const double x2 = dot(w, w);
  const double y2 = y * y * l2;
  const double z2 = z * z * l2;
  const double k = sign_of(rr) * rr * rr * x2;
  if (sign_of(z) * a2 * z2 > k) return std::sqrt(x2 + z2) * il2 - c.r2;
  if (sign_of(y) * a2 * y2 < k) return std::sqrt(x2 + y2) * il2 - c.r1;
  return (std::sqrt(x2 * a2 * il2) + y * rr) * il2 - c.r1;
}

double CtPhantom::bone(const Vec3& p, double zc, double d) const {
  return rounded_rect(d, p.z - zc, kBoneHalfWidth, kBoneHalfHeight, kBoneRounding);
}

double CtPhantom::jaw_sdf(const Vec3& q, int jaw) const {
  double s = HUGE_VAL;
  for (int t = 0; t < kCtPhantomTeethPerJaw; ++t) {
    const double d = round_cone(teeth_[jaw * kCtPhantomTeethPerJaw + t], q);
    if (d < s) s = d;
  }
  double dxy = HUGE_VAL;
  for (const Segment& g : segments_) {
    const double d = segment_distance(q.x, q.y, g.x0, g.y0, g.x1, g.y1);
    if (d < dxy) dxy = d;
  }
  const double b = bone(q, jaw == 0 ? kBoneZ : -kBoneZ, dxy);
  return b < s ? b : s;
}

Vec3 CtPhantom::to_anatomy(const Vec3& patient) const {
  const Vec3 d = patient - header_.origin;
  return Vec3{dot(d, header_.axis_x) - centre_.x, dot(d, header_.axis_y) - centre_.y,
              dot(d, header_.axis_z) - centre_.z};
}

double CtPhantom::sdf_maxilla(const Vec3& patient) const { return jaw_sdf(to_anatomy(patient), 0); }
double CtPhantom::sdf_mandible(const Vec3& patient) const {
  return jaw_sdf(to_anatomy(patient), 1);
}

Vec3 CtPhantom::seed_maxilla() const {
  return ct_to_patient(header_, Vec3{0.0, kArchApexY, kBoneZ} + centre_);
}
Vec3 CtPhantom::seed_mandible() const {
  return ct_to_patient(header_, Vec3{0.0, kArchApexY, -kBoneZ} + centre_);
}

void CtPhantom::row_candidates(double y, double z, std::vector<int>* teeth,
                               std::vector<int>* segments) const {
  const double m = diag_ + min_spacing_;
  teeth->clear();
  segments->clear();
  for (int t = 0; t < 2 * kCtPhantomTeethPerJaw; ++t) {
    const Aabb& b = teeth_[t].box;
    if (y >= b.lo.y - m && y <= b.hi.y + m && z >= b.lo.z - m && z <= b.hi.z + m) {
      teeth->push_back(t);
    }
  }
  const double zb = std::fabs(z) - kBoneZ;
  if (std::fabs(zb) > kBoneHalfHeight + m) return;
  for (size_t g = 0; g < segments_.size(); ++g) {
    const Aabb& b = segments_[g].box;
    if (y >= b.lo.y - m && y <= b.hi.y + m) segments->push_back(static_cast<int>(g));
  }
}

double CtPhantom::value(const Vec3& q, uint64_t index, const int* teeth, int tooth_count,
                        const int* segments, int segment_count) const {
  const double m = diag_ + min_spacing_;
  double st = HUGE_VAL;
  for (int n = 0; n < tooth_count; ++n) {
    const RoundCone& c = teeth_[static_cast<size_t>(teeth[n])];
    if (q.x < c.box.lo.x - m || q.x > c.box.hi.x + m) continue;
    const double d = round_cone(c, q);
    if (d < st) st = d;
  }
  double dxy = HUGE_VAL;
  for (int n = 0; n < segment_count; ++n) {
    const Segment& g = segments_[static_cast<size_t>(segments[n])];
    if (!box_contains_xy(g.box, q.x, q.y, m)) continue;
    const double d = segment_distance(q.x, q.y, g.x0, g.y0, g.x1, g.y1);
    if (d < dxy) dxy = d;
  }
  double sb = HUGE_VAL;
  if (dxy < HUGE_VAL) sb = bone(q, q.z >= 0.0 ? kBoneZ : -kBoneZ, dxy);
  const double s = st < sb ? st : sb;
  double hu = 0.0;
  if (s <= diag_) {
    if (s >= -diag_) {
      hu = centre_hu_ - slope_ * s;
    } else {
      const double inner = st < sb ? kEnamelHu : kBoneHu;
      const double at_d = centre_hu_ + slope_ * diag_;
      const double steep = (inner - at_d) / min_spacing_;
      hu = at_d + steep * (-s - diag_);
      if (hu > inner) hu = inner;
    }
  } else {
    const Vec3 h{q.x, q.y - kHeadCentreY, q.z};
    const double sh = rounded_box(h, kHeadHalf, kHeadRounding);
    const double t = clamp01(0.5 - sh / min_spacing_);
    hu = kAirHu + (kSoftTissueHu - kAirHu) * t;
  }
  if (options_.streak && std::fabs(q.z - streak_centre_.z) <= kStreakHalfThickness) {
    const double dx = q.x - streak_centre_.x, dy = q.y - streak_centre_.y;
    const double r = std::sqrt(dx * dx + dy * dy);
    const double fade = clamp01(1.0 - r / kStreakReach);
    if (fade > 0.0) {
      for (int l = 0; l < 8; ++l) {
        const double across = std::fabs(dx * kStreakDir[l][1] - dy * kStreakDir[l][0]);
        const double w = clamp01(1.0 - across / kStreakWidth);
        if (w > 0.0) hu += ((l & 1) == 0 ? kStreakBright : kStreakDark) * (w * fade);
      }
    }
  }
  if (options_.noise_hu > 0.0) {
    const uint64_t h = hash_mix(noise_key_ + index);
    const uint64_t sum = (h & 0xFFFF) + ((h >> 16) & 0xFFFF) + ((h >> 32) & 0xFFFF) + (h >> 48);
    // Four uniforms on [0, 1): mean 2, variance 1/3; scaled to unit variance.
    const double u = static_cast<double>(sum) / 65536.0 - 2.0;
    hu += options_.noise_hu * (kSqrt3 * u);
  }
  return hu;
}

int16_t CtPhantom::voxel(uint32_t i, uint32_t j, uint32_t k) const {
  const Vec3 q{options_.spacing.x * static_cast<double>(i) - centre_.x,
               options_.spacing.y * static_cast<double>(j) - centre_.y,
               options_.spacing.z * static_cast<double>(k) - centre_.z};
  std::vector<int> teeth, segments;
  row_candidates(q.y, q.z, &teeth, &segments);
  const uint64_t index = (uint64_t{k} * options_.ny + j) * options_.nx + i;
  return to_hu(value(q, index, teeth.data(), static_cast<int>(teeth.size()), segments.data(),
                     static_cast<int>(segments.size())));
}

void CtPhantom::generate(std::vector<int16_t>* hu, CtVolume* volume) const {
  const uint64_t total = uint64_t{options_.nx} * options_.ny * options_.nz;
  hu->assign(static_cast<size_t>(total), 0);
  std::vector<int> teeth, segments;
  teeth.reserve(2 * kCtPhantomTeethPerJaw);
  segments.reserve(segments_.size());
  for (uint32_t k = 0; k < options_.nz; ++k) {
    const double z = options_.spacing.z * static_cast<double>(k) - centre_.z;
    for (uint32_t j = 0; j < options_.ny; ++j) {
      const double y = options_.spacing.y * static_cast<double>(j) - centre_.y;
      row_candidates(y, z, &teeth, &segments);
      const uint64_t row = (uint64_t{k} * options_.ny + j) * options_.nx;
      for (uint32_t i = 0; i < options_.nx; ++i) {
        const Vec3 q{options_.spacing.x * static_cast<double>(i) - centre_.x, y, z};
        (*hu)[static_cast<size_t>(row + i)] =
            to_hu(value(q, row + i, teeth.data(), static_cast<int>(teeth.size()), segments.data(),
                        static_cast<int>(segments.size())));
      }
    }
  }
  *volume = header_;
  volume->hu = hu->data();
}

}  // namespace cli
}  // namespace splintcore
