// splintcore registration, internal: the small dense algebra the registration needs, with only
// + - * / and sqrt (the same bits everywhere): the cyclic Jacobi eigen-solver for symmetric
// matrices up to 6x6 (Golub and Van Loan, "Matrix Computations", 4th ed., 2013, section 8.5),
// the Cholesky solve of the ICP's 6x6 normal equations (ibid., 4.2), and unit quaternions
// (Horn 1987) for exact rotations.
#ifndef SPLINTCORE_SRC_REGISTRATION_LINALG_H
#define SPLINTCORE_SRC_REGISTRATION_LINALG_H

#include "splintcore/geometry.h"

namespace splintcore {
namespace registration_detail {

constexpr int kMaxDim = 6;

// Eigen-decomposition of the symmetric n x n matrix a (row-major, n <= 6; read only):
// values[k] descending (ties keep the lower index first), vectors[i * n + k] the i-th component
// of the unit eigenvector k. Cyclic Jacobi sweeps until the off-diagonal part is negligible
// (at most 64 sweeps).
void symmetric_eigen(const double* a, int n, double* values, double* vectors);

// Solves a x = b for the symmetric positive definite n x n matrix a (n <= 6) by Cholesky.
// False when a pivot is not above `min_pivot_ratio` times the largest diagonal entry (the
// system does not fix x: a flat or symmetric surface).
bool cholesky_solve(const double* a, const double* b, int n, double min_pivot_ratio, double* x);

// A unit quaternion w + xi + yj + zk.
struct Quaternion {
  double w = 1, x = 0, y = 0, z = 0;
};

Quaternion normalized(const Quaternion& q);
// The product a b: the rotation b, then a.
Quaternion multiply(const Quaternion& a, const Quaternion& b);
// The rotation matrix of a unit quaternion.
void quaternion_matrix(const Quaternion& q, double r[3][3]);
// The unit quaternion of a rotation matrix (Shepperd's method: the largest of the four
// diagonal combinations under the square root).
Quaternion matrix_quaternion(const double r[3][3]);
// The rotation by the small-angle vector omega (the linearised ICP step): the normalised
// quaternion (1, omega / 2), a rotation by 2 atan(|omega| / 2) about omega.
Quaternion small_rotation(const Vec3& omega);

}  // namespace registration_detail
}  // namespace splintcore

#endif  // SPLINTCORE_SRC_REGISTRATION_LINALG_H
