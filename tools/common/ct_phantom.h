// A skull-like synthetic CT (tools, tests and benchmarks only: std::vector, no arena), with
// known analytic surfaces, to prove segmentation and reconstruction.
//
// Anatomy (mm, in the phantom's own frame: x across the face, y anterior, z superior, centred
// on the volume's centre; the patient frame is the volume's: ct_to_patient):
//   - two dental arches on the parabola y = 18 - 40 (x / 26)^2, the same for both jaws;
//   - 14 teeth per jaw, 7 per side from the midline (central incisor, lateral, canine, two
//     premolars, two molars), each a ROUND CONE (two spheres and their tangent cone): a crown
//     sphere of radius 2.7..4 mm at the occlusal plane and a root sphere of radius 1 mm in the
//     bone: big end towards the occlusal plane ("big end up");
//   - in occlusion: the upper and lower crowns face each other on the same arch points; the
//     molars overlap by 0.3 mm (their crowns merge in the CT), the premolars touch exactly,
//     canines and incisors leave a 1.2 mm gap. Separating the jaws must be earned;
//   - maxillary and mandibular bone: horseshoe slabs (a rounded rectangle, 11 x 8 mm, rounding
//     1.5 mm, swept along the arch polyline between the last teeth) centred at z = +13 and -13,
//     holding the roots;
//   - soft tissue (40 HU) in a rounded box around the jaws, air (-1000 HU) outside.
// Signed distances (negative inside) are exact for each solid: round cones (the standard
// closed form) and the swept rounded rectangle (the 2D rectangle's distance at the distance to
// the polyline); a jaw's is the minimum over its solids (exact outside, where a mesh vertex
// off the surface is measured).
//
// Voxel values: s = min(maxilla, mandible) signed distance at the voxel centre. Within
// d = |spacing| (the longest lattice edge, the body diagonal) of the surface the value is
// linear in s, centred on the threshold: HU = (T - 0.5) - k s with k = (T - 0.5 - 40) / d, so
// on every lattice edge that crosses the surface both samples are on the ramp and the
// iso-surface at T - 0.5 interpolates exactly to s = 0 where the surface is flat (what is left
// is curvature, rounding to integers and noise). Deeper inside the value rises to enamel
// (2000 HU; bone 1200) within one more voxel; further outside it is soft tissue or air.
// Noise: Gaussian-like (sum of four uniforms, unit variance scaled to noise_hu), from a hash of
// the seed and the voxel index (splitmix64 finaliser), so a voxel's value does not depend on
// the order voxels are made in. Metal-artefact streak: in the axial slab (1.5 mm thick)
// through the crown centre of the upper right first molar, eight lines through that crown's
// axis alternately bright (+150 HU) and dark (-250 HU), fading over 0.8 mm across and 30 mm
// along (bright lines stay under a 300 HU threshold in soft tissue; near the surface they move
// the iso-surface by up to about a voxel there: the reconstruction's maximum error is there).
// Only + - * / and sqrt (correctly rounded), fixed order: the bytes are the same on every
// compiler and CPU (-ffp-contract=off).
#ifndef SPLINTCORE_TOOLS_CT_PHANTOM_H
#define SPLINTCORE_TOOLS_CT_PHANTOM_H

#include <cstdint>
#include <vector>

#include "splintcore/core.h"
#include "splintcore/ct.h"
#include "splintcore/geometry.h"

namespace splintcore {
namespace cli {

struct CtPhantomOptions {
  uint32_t nx = 160, ny = 160, nz = 100;
  Vec3 spacing{0.5, 0.5, 0.5};  // mm; may differ per axis
  double noise_hu = 20.0;       // standard deviation of the noise, HU (0: none)
  bool streak = true;
  uint64_t seed = 1;
  int32_t threshold_hu = 300;  // the threshold the ramp is centred on (T above)
  // The volume's orientation in patient space (orthonormal). The origin is chosen so that the
  // anatomy's centre is at the patient origin (0, 0, 0).
  Vec3 axis_x{1, 0, 0};
  Vec3 axis_y{0, 1, 0};
  Vec3 axis_z{0, 0, 1};
};

constexpr int kCtPhantomTeethPerJaw = 14;

class CtPhantom {
 public:
  // Checks the options and lays out the anatomy. Errors: kInvalidArgument (a size of 0 or
  // above 2048, spacing not in [0.05, 5] mm, axes not orthonormal, noise not in [0, 500], the
  // volume smaller than the anatomy: the message gives both extents).
  [[nodiscard]] Status init(const CtPhantomOptions& options);

  // The volume's geometry (sizes, spacing, origin, axes; hu = nullptr).
  CtVolume header() const { return header_; }

  // Fills `hu` (resized to nx * ny * nz) and `*volume` (header, hu pointing into `hu`).
  void generate(std::vector<int16_t>* hu, CtVolume* volume) const;
  // The value of one voxel (what generate writes there).
  int16_t voxel(uint32_t i, uint32_t j, uint32_t k) const;

  // Signed distance (mm, negative inside) of a patient-space point to each jaw's analytic
  // surface: maxilla = upper teeth + maxillary bone, mandible = lower teeth + mandibular bone.
  double sdf_maxilla(const Vec3& patient) const;
  double sdf_mandible(const Vec3& patient) const;

  // Seed points (patient mm) in the middle of each jaw's bone, at the midline.
  Vec3 seed_maxilla() const;
  Vec3 seed_mandible() const;

  // The lattice's longest edge (the voxel's body diagonal), mm, and its smallest spacing.
  double voxel_diagonal() const { return diag_; }

 private:
  struct RoundCone {
    Vec3 a, b;      // sphere centres (crown, root)
    double r1, r2;  // radii (crown, root)
    Aabb box;       // of the solid
  };
  struct Segment {
    double x0, y0, x1, y1;
    Aabb box;  // of the swept slab part (both jaws' z ranges not included)
  };
  void lay_out_anatomy();
  Status check_fits() const;
  Vec3 to_anatomy(const Vec3& patient) const;
  static double round_cone(const RoundCone& c, const Vec3& p);
  double bone(const Vec3& p, double zc, double min_xy_distance) const;
  double jaw_sdf(const Vec3& q, int jaw) const;  // all solids, no culling
  double value(const Vec3& q, uint64_t index, const int* teeth, int tooth_count,
               const int* segments, int segment_count) const;
  void row_candidates(double y, double z, std::vector<int>* teeth,
                      std::vector<int>* segments) const;

  CtPhantomOptions options_;
  CtVolume header_;
  Vec3 centre_;  // anatomy centre in the voxel-local frame
  double diag_ = 0, min_spacing_ = 0, slope_ = 0, centre_hu_ = 0;
  RoundCone teeth_[2 * kCtPhantomTeethPerJaw];  // upper 0..13, lower 14..27
  std::vector<Segment> segments_;               // the arch polyline under the bone
  Vec3 streak_centre_{};
  uint64_t noise_key_ = 0;
};

}  // namespace cli
}  // namespace splintcore

#endif  // SPLINTCORE_TOOLS_CT_PHANTOM_H
