// Which mass properties a rigid body can have (checked for every body the user declares,
// at every compile: Compile and Rebind, so also for --set values and sweep scenarios).
//
// A body's central inertia I = integral of rho (|r|^2 1 - r r^T) dV over the body, r from
// the mass centre (Kane & Levinson, Dynamics: Theory and Applications, 1985, sec. 3.5),
// is therefore
//   (1) symmetric:                   I_ij = I_ji
//   (2) positive semi-definite:      principal moments l1 <= l2 <= l3 all >= 0
//   (3) the triangle inequality:     l1 + l2 >= l3
// ((3): with P_k = integral of rho x_k^2 dV >= 0 along the principal axes, l1 = P2 + P3,
// l2 = P1 + P3, l3 = P1 + P2, so l1 + l2 - l3 = 2 P3 >= 0; equality for a plane lamina.)
// Each is checked within kInertiaTol of s = |I_11| + |I_22| + |I_33| (rounding in user
// values, e.g. CAD output printed to six digits); an accepted tensor is replaced by its
// symmetric part (I + I^T) / 2, which is what the kinetic energy 1/2 w^T I w sees.
// Without (1) the dense mass matrix is not symmetric, and its Cholesky factor (which reads
// one triangle) solves another system: energy is not conserved. Without (2) the mass
// matrix is indefinite: negative kinetic energy. With every body's spatial inertia
// positive semi-definite, M = sum_L tau_L^T Mb_L tau_L is positive semi-definite on every
// solution path, so at run time only a singular M (a massless link) remains to be caught.
#include <Eigen/Eigenvalues>
#include <cmath>
#include <cstdio>

#include "compiler/compile_internal.h"

namespace kanesim::rt {
namespace {

std::string G(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", x);
  return buf;
}

}  // namespace

std::string CheckInertia(const Mat3& I, Mat3* symmetric) {
  for (int k = 0; k < 9; ++k)
    if (!std::isfinite(I(k / 3, k % 3)))
      return "its inertia has a non-finite entry I[" + std::to_string(k / 3 + 1) + "," + std::to_string(k % 3 + 1) +
             "] = " + G(I(k / 3, k % 3));
  const double s = std::abs(I(0, 0)) + std::abs(I(1, 1)) + std::abs(I(2, 2));
  const double tol = kInertiaTol * s;
  for (int i = 0; i < 3; ++i)
    for (int j = i + 1; j < 3; ++j)
      if (!(std::abs(I(i, j) - I(j, i)) <= tol))
        return "its inertia is not symmetric: I[" + std::to_string(i + 1) + "," + std::to_string(j + 1) +
               "] = " + G(I(i, j)) + " but I[" + std::to_string(j + 1) + "," + std::to_string(i + 1) +
               "] = " + G(I(j, i));
  *symmetric = 0.5 * (I + I.transpose());
  // Eq. (2), (3) on the principal moments, ascending.
  Eigen::SelfAdjointEigenSolver<Mat3> eig(*symmetric, Eigen::EigenvaluesOnly);
  const Vec3 l = eig.eigenvalues();
  // Formatted only for a message (every body of every compile passes through here).
  auto moments = [&l] { return G(l[0]) + ", " + G(l[1]) + ", " + G(l[2]); };
  if (l[0] < -tol) return "its inertia has a negative principal moment (principal moments " + moments() + ")";
  if (l[0] + l[1] < l[2] - tol)
    return "its principal moments of inertia " + moments() + " violate the triangle inequality (" + G(l[0]) +
           " + " + G(l[1]) + " < " + G(l[2]) + ")";
  return "";
}

}  // namespace kanesim::rt
