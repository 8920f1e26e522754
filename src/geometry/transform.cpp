// Rigid transforms: composition, inverse, and validation of a 4x4 matrix from a surgical plan.
#include "splintcore/geometry.h"

namespace splintcore {

RigidTransform compose(const RigidTransform& next, const RigidTransform& first) {
  RigidTransform out;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      out.r[i][j] = next.r[i][0] * first.r[0][j] + next.r[i][1] * first.r[1][j] +
                    next.r[i][2] * first.r[2][j];
    }
  }
  out.t = next.apply_point(first.t);
  return out;
}

RigidTransform inverse(const RigidTransform& x) {
  RigidTransform out;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) out.r[i][j] = x.r[j][i];
  }
  out.t = -out.apply_vector(x.t);
  return out;
}

RigidTransform rotation_about_axis(const Vec3& point, const Vec3& unit_axis, double angle) {
  double sh = 0, ch = 0;
  deterministic_sincos(0.5 * angle, &sh, &ch);
  const double s = 2.0 * sh * ch, vers = 2.0 * sh * sh, c = 1.0 - vers;
  const double u[3] = {unit_axis.x, unit_axis.y, unit_axis.z};
  // [u]x, the cross-product matrix: [u]x v = u x v.
  const double k[3][3] = {{0, -u[2], u[1]}, {u[2], 0, -u[0]}, {-u[1], u[0], 0}};
  RigidTransform x;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) x.r[i][j] = (i == j ? c : 0.0) + s * k[i][j] + vers * u[i] * u[j];
  }
  x.t = point - x.apply_vector(point);
  return x;
}

Status rigid_from_matrix(const double m[16], double tolerance, RigidTransform* out) {
  for (int i = 0; i < 16; ++i) {
    if (!is_finite(m[i])) {
      return make_error(StatusCode::kNonFinite, "transform entry (", i / 4, ",", i % 4,
                        ") is not finite")
          .at_index(static_cast<uint64_t>(i));
    }
  }
  if (m[12] != 0.0 || m[13] != 0.0 || m[14] != 0.0 || m[15] != 1.0) {
    return Status::error(StatusCode::kInvalidArgument,
                         "transform's last row must be 0 0 0 1 (no projection or scale)");
  }
  RigidTransform x;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) x.r[i][j] = m[4 * i + j];
  }
  x.t = Vec3{m[3], m[7], m[11]};
  // R^T R must be the identity: columns of unit length and mutually orthogonal.
  for (int a = 0; a < 3; ++a) {
    for (int b = a; b < 3; ++b) {
      double d = x.r[0][a] * x.r[0][b] + x.r[1][a] * x.r[1][b] + x.r[2][a] * x.r[2][b];
      double expected = a == b ? 1.0 : 0.0;
      double err = d - expected;
      if (err > tolerance || err < -tolerance) {
        return make_error(StatusCode::kInvalidArgument, "transform is not rigid: columns ", a,
                          " and ", b, " have dot product ", d, " (expected ", expected,
                          "; scale or shear?)");
      }
    }
  }
  double det = x.r[0][0] * (x.r[1][1] * x.r[2][2] - x.r[1][2] * x.r[2][1]) -
               x.r[0][1] * (x.r[1][0] * x.r[2][2] - x.r[1][2] * x.r[2][0]) +
               x.r[0][2] * (x.r[1][0] * x.r[2][1] - x.r[1][1] * x.r[2][0]);
  if (det < 0.0) {
    return make_error(StatusCode::kInvalidArgument, "transform is a reflection (det ", det,
                      "): it would turn the mesh inside out");
  }
  *out = x;
  return Status::ok();
}

bool round_to_float32(Vec3* v) {
  constexpr double kMax = 3.4028234663852886e38;  // FLT_MAX
  double r[3];
  for (int a = 0; a < 3; ++a) {
    const double x = (*v)[a];
    if (!(x <= kMax && x >= -kMax)) return false;
    volatile float f = static_cast<float>(x);
    r[a] = static_cast<double>(f) + 0.0;
  }
  *v = Vec3{r[0], r[1], r[2]};
  return true;
}

}  // namespace splintcore
