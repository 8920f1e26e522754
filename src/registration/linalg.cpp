// The registration's dense algebra (linalg.h): cyclic Jacobi (Golub and Van Loan, "Matrix
// Computations", 4th ed., 2013, 8.5.3), Cholesky (ibid., 4.2.5), unit quaternions (Horn,
// "Closed-form solution of absolute orientation using unit quaternions", JOSA A 4(4), 1987;
// Shepperd, "Quaternion from rotation matrix", J. Guidance and Control 1(3), 1978).
#include "linalg.h"

#include <cmath>

namespace splintcore {
namespace registration_detail {

namespace {

constexpr int kMaxSweeps = 64;

// One Jacobi rotation in the plane (p, q) that zeroes m[p][q] (m is n x n, row-major), also
// applied to the columns of v.
void jacobi_rotate(double* m, double* v, int n, int p, int q) {
  const double apq = m[p * n + q];
  const double theta = (m[q * n + q] - m[p * n + p]) / (2.0 * apq);
  const double abs_theta = theta < 0 ? -theta : theta;
  // t = tan(phi), the smaller root of t^2 + 2 theta t - 1 = 0; for a huge theta, 1 / (2 theta).
  double t =
      abs_theta > 1e150 ? 0.5 / abs_theta : 1.0 / (abs_theta + std::sqrt(theta * theta + 1.0));
  if (theta < 0) t = -t;
  const double c = 1.0 / std::sqrt(t * t + 1.0);
  const double s = t * c;
  for (int k = 0; k < n; ++k) {  // columns p and q
    const double mkp = m[k * n + p], mkq = m[k * n + q];
    m[k * n + p] = c * mkp - s * mkq;
    m[k * n + q] = s * mkp + c * mkq;
  }
  for (int k = 0; k < n; ++k) {  // rows p and q
    const double mpk = m[p * n + k], mqk = m[q * n + k];
    m[p * n + k] = c * mpk - s * mqk;
    m[q * n + k] = s * mpk + c * mqk;
  }
  m[p * n + q] = 0.0;
  m[q * n + p] = 0.0;
  for (int k = 0; k < n; ++k) {
    const double vkp = v[k * n + p], vkq = v[k * n + q];
    v[k * n + p] = c * vkp - s * vkq;
    v[k * n + q] = s * vkp + c * vkq;
  }
}

}  // namespace

void symmetric_eigen(const double* a, int n, double* values, double* vectors) {
  SPLINTCORE_ASSERT(n >= 1 && n <= kMaxDim);
  double m[kMaxDim * kMaxDim] = {};
  double v[kMaxDim * kMaxDim] = {};
  double scale = 0;
  for (int i = 0; i < n * n; ++i) {
    m[i] = a[i];
    v[i] = (i / n == i % n) ? 1.0 : 0.0;
    scale += a[i] * a[i];
  }
  for (int sweep = 0; sweep < kMaxSweeps; ++sweep) {
    double off = 0;
    for (int p = 0; p < n; ++p) {
      for (int q = p + 1; q < n; ++q) off += m[p * n + q] * m[p * n + q];
    }
    if (!(off > 1e-32 * scale)) break;  // also stops on NaN
    for (int p = 0; p < n; ++p) {
      for (int q = p + 1; q < n; ++q) {
        if (m[p * n + q] != 0.0) jacobi_rotate(m, v, n, p, q);
      }
    }
  }
  // Descending by value, stable (selection of the largest remaining, first on ties).
  int order[kMaxDim] = {};
  bool used[kMaxDim] = {};
  for (int k = 0; k < n; ++k) {
    int best = 0;
    while (best < n - 1 && used[best]) ++best;  // the first unused (k < n: there is one)
    for (int i = best + 1; i < n; ++i) {
      if (!used[i] && m[i * n + i] > m[best * n + best]) best = i;
    }
    used[best] = true;
    order[k] = best;
  }
  for (int k = 0; k < n; ++k) {
    values[k] = m[order[k] * n + order[k]];
    for (int i = 0; i < n; ++i) vectors[i * n + k] = v[i * n + order[k]];
  }
}

bool cholesky_solve(const double* a, const double* b, int n, double min_pivot_ratio, double* x) {
  SPLINTCORE_ASSERT(n >= 1 && n <= kMaxDim);
  double l[kMaxDim * kMaxDim] = {};
  double largest = 0;
  for (int i = 0; i < n; ++i) largest = a[i * n + i] > largest ? a[i * n + i] : largest;
  if (!(largest > 0)) return false;
  for (int j = 0; j < n; ++j) {
    double d = a[j * n + j];
    for (int k = 0; k < j; ++k) d -= l[j * n + k] * l[j * n + k];
    if (!(d > min_pivot_ratio * largest)) return false;
    const double ljj = std::sqrt(d);
    l[j * n + j] = ljj;
    for (int i = j + 1; i < n; ++i) {
      double s = a[i * n + j];
      for (int k = 0; k < j; ++k) s -= l[i * n + k] * l[j * n + k];
      l[i * n + j] = s / ljj;
    }
  }
  double y[kMaxDim] = {};
  for (int i = 0; i < n; ++i) {  // L y = b
    double s = b[i];
    for (int k = 0; k < i; ++k) s -= l[i * n + k] * y[k];
    y[i] = s / l[i * n + i];
  }
  for (int i = n - 1; i >= 0; --i) {  // L^T x = y
    double s = y[i];
    for (int k = i + 1; k < n; ++k) s -= l[k * n + i] * x[k];
    x[i] = s / l[i * n + i];
  }
  return true;
}

Quaternion normalized(const Quaternion& q) {
  const double len = std::sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
  Quaternion r{q.w / len, q.x / len, q.y / len, q.z / len};
  if (r.w < 0) r = Quaternion{-r.w, -r.x, -r.y, -r.z};  // one of the two signs, always the same
  return r;
}

Quaternion multiply(const Quaternion& a, const Quaternion& b) {
  return Quaternion{
      a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z, a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y,
      a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x, a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w};
}

void quaternion_matrix(const Quaternion& q, double r[3][3]) {
  const double w = q.w, x = q.x, y = q.y, z = q.z;
  r[0][0] = 1.0 - 2.0 * (y * y + z * z);
  r[0][1] = 2.0 * (x * y - w * z);
  r[0][2] = 2.0 * (x * z + w * y);
  r[1][0] = 2.0 * (x * y + w * z);
  r[1][1] = 1.0 - 2.0 * (x * x + z * z);
  r[1][2] = 2.0 * (y * z - w * x);
  r[2][0] = 2.0 * (x * z - w * y);
  r[2][1] = 2.0 * (y * z + w * x);
  r[2][2] = 1.0 - 2.0 * (x * x + y * y);
}

Quaternion matrix_quaternion(const double r[3][3]) {
  const double trace = r[0][0] + r[1][1] + r[2][2];
  Quaternion q;
  if (trace >= r[0][0] && trace >= r[1][1] && trace >= r[2][2]) {
    const double s = 2.0 * std::sqrt(1.0 + trace);  // 4 w
    q = Quaternion{0.25 * s, (r[2][1] - r[1][2]) / s, (r[0][2] - r[2][0]) / s,
                   (r[1][0] - r[0][1]) / s};
  } else if (r[0][0] >= r[1][1] && r[0][0] >= r[2][2]) {
    const double s = 2.0 * std::sqrt(1.0 + r[0][0] - r[1][1] - r[2][2]);  // 4 x
    q = Quaternion{(r[2][1] - r[1][2]) / s, 0.25 * s, (r[0][1] + r[1][0]) / s,
                   (r[0][2] + r[2][0]) / s};
  } else if (r[1][1] >= r[2][2]) {
    const double s = 2.0 * std::sqrt(1.0 + r[1][1] - r[0][0] - r[2][2]);  // 4 y
    q = Quaternion{(r[0][2] - r[2][0]) / s, (r[0][1] + r[1][0]) / s, 0.25 * s,
                   (r[1][2] + r[2][1]) / s};
  } else {
    const double s = 2.0 * std::sqrt(1.0 + r[2][2] - r[0][0] - r[1][1]);  // 4 z
    q = Quaternion{(r[1][0] - r[0][1]) / s, (r[0][2] + r[2][0]) / s, (r[1][2] + r[2][1]) / s,
                   0.25 * s};
  }
  return normalized(q);
}

Quaternion small_rotation(const Vec3& omega) {
  return normalized(Quaternion{1.0, 0.5 * omega.x, 0.5 * omega.y, 0.5 * omega.z});
}

}  // namespace registration_detail
}  // namespace splintcore
