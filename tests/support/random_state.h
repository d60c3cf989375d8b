// A random state y = [q_free, u_free] valid for a compiled program: unit quaternions,
// Cardan middle angles away from +-pi/2 and Euler middle angles away from 0 and pi.
#pragma once

#include <Eigen/Core>
#include <random>

#include "runtime/program/program.h"

namespace kanesim::test {

inline Eigen::VectorXd RandomState(const rt::Program& p, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::VectorXd q_all(p.nq_all);
  for (const rt::TreeJoint& j : p.joints) {
    for (int k = 0; k < j.nq; ++k) q_all[j.q0 + k] = u(rng);
    const bool rot = j.type == flat::JointType::Spherical || j.type == flat::JointType::Free;
    if (!rot) continue;
    const int r0 = j.q0 + (j.type == flat::JointType::Free ? 3 : 0);
    if (j.rotation == flat::RotationCoords::Quaternion) {
      Eigen::Vector4d qq(n(rng), n(rng), n(rng), n(rng));
      qq.normalize();
      for (int k = 0; k < 4; ++k) q_all[r0 + k] = qq[k];
    } else if (j.rotation == flat::RotationCoords::EulerZYZ) {
      q_all[r0 + 1] = 1.2 + 0.8 * u(rng);  // in (0.4, 2.0): |sin| > 0.38
    }
  }
  Eigen::VectorXd y(p.nq + p.nu);
  for (int i = 0; i < p.nq; ++i) y[i] = q_all[p.q_free[static_cast<size_t>(i)]];
  for (int i = 0; i < p.nu; ++i) y[p.nq + i] = u(rng);
  return y;
}

}  // namespace kanesim::test
