#include "runtime/kinematics/joint_kinematics.h"

#include <algorithm>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>

namespace kanesim::rt {

using flat::JointType;
using flat::RotationCoords;

namespace {

// Below this |cos q2| (Cardan) or |sin q2| (Euler ZYZ) N(q) has a 1/0: the three angles
// no longer determine the body-fixed angular velocity (gimbal lock).
constexpr double kGimbalLockTol = 1e-8;

Mat3 Rx(double a) { return AxisAngle(Vec3::UnitX(), a); }
Mat3 Ry(double a) { return AxisAngle(Vec3::UnitY(), a); }
Mat3 Rz(double a) { return AxisAngle(Vec3::UnitZ(), a); }

bool IsSphericalOrFree(JointType t) { return t == JointType::Spherical || t == JointType::Free; }

// Rotational coordinate rates from the body-fixed angular velocity w (3 entries).
//   quaternion  qdot = 1/2 q (x) (0, w)                          (quaternion product)
//   Cardan xyz  w_b = [cb cc, sc, 0; -cb sc, cc, 0; sb, 0, 1] [q1'; q2'; q3']
//   Euler zyz   w_b = [-sb cc, sc, 0; sb sc, cc, 0; cb, 0, 1] [q1'; q2'; q3']
// (b = q2, c = q3, derived from R = Rx Ry Rz resp. Rz Ry Rz, w_b = R^T Rdot); inverted:
bool RotationRates(const TreeJoint& j, RotationCoords c, const double* q, const double* w, double* qdot,
                   std::string* error) {
  switch (c) {
    case RotationCoords::Quaternion: {
      const double qw = q[0], qx = q[1], qy = q[2], qz = q[3];
      qdot[0] = 0.5 * (-qx * w[0] - qy * w[1] - qz * w[2]);
      qdot[1] = 0.5 * (qw * w[0] + qy * w[2] - qz * w[1]);
      qdot[2] = 0.5 * (qw * w[1] + qz * w[0] - qx * w[2]);
      qdot[3] = 0.5 * (qw * w[2] + qx * w[1] - qy * w[0]);
      return true;
    }
    case RotationCoords::CardanXYZ: {
      const double cb = std::cos(q[1]), sb = std::sin(q[1]), cc = std::cos(q[2]), sc = std::sin(q[2]);
      // At |cos q2| -> 0 the map is singular; a trajectory that steps over the singular
      // value changes branch (chart), which is the same failure seen one step late.
      const bool crossed = std::floor((q[1] + M_PI / 2) / M_PI) != j.chart0;
      if (std::fabs(cb) < kGimbalLockTol || crossed) {
        char buf[160];
        std::snprintf(buf, sizeof buf, "Cardan angle q[%d] = %.8g (cos = %.3g)", j.type == JointType::Free ? 5 : 2,
                      q[1], cb);
        *error = "gimbal lock in joint '" + j.name + "': " + buf +
                 "; hint: use quaternion coordinates (coordinates = \"quaternion\")";
        return false;
      }
      const double k = (cc * w[0] - sc * w[1]) / cb;
      qdot[0] = k;
      qdot[1] = sc * w[0] + cc * w[1];
      qdot[2] = w[2] - sb * k;
      return true;
    }
    case RotationCoords::EulerZYZ: {
      const double cb = std::cos(q[1]), sb = std::sin(q[1]), cc = std::cos(q[2]), sc = std::sin(q[2]);
      const bool crossed = std::floor(q[1] / M_PI) != j.chart0;
      if (std::fabs(sb) < kGimbalLockTol || crossed) {
        char buf[160];
        std::snprintf(buf, sizeof buf, "Euler angle q[%d] = %.8g (sin = %.3g)", j.type == JointType::Free ? 5 : 2,
                      q[1], sb);
        *error = "gimbal lock in joint '" + j.name + "': " + buf +
                 "; hint: use quaternion coordinates (coordinates = \"quaternion\")";
        return false;
      }
      const double k = (-cc * w[0] + sc * w[1]) / sb;
      qdot[0] = k;
      qdot[1] = sc * w[0] + cc * w[1];
      qdot[2] = w[2] - cb * k;
      return true;
    }
  }
  return false;
}

}  // namespace

// Rodrigues: R = I + sin(a) [n]x + (1 - cos(a)) [n]x^2.
Mat3 AxisAngle(const Vec3& n, double a) {
  const Mat3 K = Skew(n);
  return Mat3::Identity() + std::sin(a) * K + (1.0 - std::cos(a)) * (K * K);
}

void PrepareJointConstants(TreeJoint* j) {
  const Vec3& n = j->axis;
  j->K_axis = Skew(n);
  j->K2_axis = j->K_axis * j->K_axis;
  j->axis_P = j->R_PJ * n;
  j->R_PJ_identity = j->R_PJ == Mat3::Identity();
  j->single_axis = !j->inverted && (j->type == JointType::Revolute || j->type == JointType::Prismatic);
  j->axis_index = -1;
  for (int k = 0; k < 3; ++k)
    if (n == Vec3::Unit(k)) j->axis_index = k;
}

bool NormalizeScaled(double* v, int n) {
  double big = 0.0;
  for (int i = 0; i < n; ++i) {
    if (!std::isfinite(v[i])) return false;
    big = std::max(big, std::fabs(v[i]));
  }
  if (big == 0.0) return false;
  // Scaled by the power of two nearest below the largest component (exact: a vector
  // whose largest component is in [1, 2), the usual axis, is divided by its norm as is).
  // scalbn scales each component at once (2^-e itself overflows for a subnormal big).
  const int e = std::ilogb(big);
  double sum = 0.0;  // of (v_i 2^-e)^2, in [1, 4n): no overflow, no underflow that matters
  for (int i = 0; i < n; ++i) sum += std::scalbn(v[i], -e) * std::scalbn(v[i], -e);
  const double norm = std::sqrt(sum);
  for (int i = 0; i < n; ++i) v[i] = std::scalbn(v[i], -e) / norm;
  return true;
}

std::string WhyNoDirection(const double* v, int n) {
  for (int i = 0; i < n; ++i)
    if (!std::isfinite(v[i])) return "is not finite";
  return "is zero";
}

Mat3 RotationFromCoords(RotationCoords c, const double* q) {
  switch (c) {
    case RotationCoords::Quaternion: {
      Eigen::Quaterniond quat(q[0], q[1], q[2], q[3]);  // (w, x, y, z)
      double n = quat.norm();
      if (n == 0.0) return Mat3::Identity();
      quat.coeffs() /= n;
      return quat.toRotationMatrix();
    }
    case RotationCoords::CardanXYZ: return Rx(q[0]) * Ry(q[1]) * Rz(q[2]);
    case RotationCoords::EulerZYZ: return Rz(q[0]) * Ry(q[1]) * Rz(q[2]);
  }
  return Mat3::Identity();
}

void JointPose(const TreeJoint& j, const double* q, Vec3* p_ab, Mat3* R_ab) {
  p_ab->setZero();
  R_ab->setIdentity();
  switch (j.type) {
    case JointType::Revolute: *R_ab = RotationAboutAxis(j, q[0]); break;
    case JointType::Prismatic: *p_ab = j.axis * q[0]; break;
    case JointType::Cylindrical:
      *p_ab = j.axis * q[0];
      *R_ab = RotationAboutAxis(j, q[1]);
      break;
    case JointType::Universal: *R_ab = RotationAboutAxis(j, q[0]) * AxisAngle(j.axis2, q[1]); break;
    case JointType::Spherical: *R_ab = RotationFromCoords(j.rotation, q); break;
    case JointType::Planar:
      *p_ab = q[0] * j.axis2 + q[1] * j.axis3;
      *R_ab = RotationAboutAxis(j, q[2]);
      break;
    case JointType::Free:
      *p_ab = Vec3(q[0], q[1], q[2]);
      *R_ab = RotationFromCoords(j.rotation, q + 3);
      break;
    case JointType::Weld: break;
  }
}

void JointMotion(const TreeJoint& j, const double* q, const double* u, const Mat3& R_ab, Mat36* Hv, Mat36* Hw,
                 Vec3* cv, Vec3* cw) {
  Hv->setZero();
  Hw->setZero();
  cv->setZero();
  cw->setZero();
  switch (j.type) {
    case JointType::Revolute: Hw->col(0) = j.axis; break;
    case JointType::Prismatic: Hv->col(0) = j.axis; break;
    case JointType::Cylindrical:
      Hv->col(0) = j.axis;
      Hw->col(1) = j.axis;
      break;
    case JointType::Universal: {
      // w_ab = n1 q1' + R1 n2 q2';  d/dt (R1 n2) = (n1 q1') x (R1 n2).
      const Vec3 n2_a = RotationAboutAxis(j, q[0]) * j.axis2;
      Hw->col(0) = j.axis;
      Hw->col(1) = n2_a;
      *cw = j.axis.cross(n2_a) * (u[0] * u[1]);
      break;
    }
    case JointType::Spherical:
      // u = w_ab resolved in b: w_ab (in a) = R_ab u; d/dt(R_ab) u = R_ab (u x u) = 0.
      Hw->leftCols<3>() = R_ab;
      break;
    case JointType::Planar:
      Hv->col(0) = j.axis2;
      Hv->col(1) = j.axis3;
      Hw->col(2) = j.axis;
      break;
    case JointType::Free:
      Hv->leftCols<3>() = Mat3::Identity();
      Hw->block<3, 3>(0, 3) = R_ab;
      break;
    case JointType::Weld: break;
  }
}

bool JointKinematicDifferential(const TreeJoint& j, const double* q, const double* u, double* qdot,
                                std::string* error) {
  if (IsSphericalOrFree(j.type)) {
    int t = j.type == JointType::Free ? 3 : 0;
    for (int i = 0; i < t; ++i) qdot[i] = u[i];
    return RotationRates(j, j.rotation, q + t, u + t, qdot + t, error);
  }
  for (int i = 0; i < j.nq; ++i) qdot[i] = u[i];
  return true;
}

}  // namespace kanesim::rt
