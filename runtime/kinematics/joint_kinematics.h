// Joint kinematics, one function per question, every result resolved in the joint's
// frame a (flat/mechanism.h conventions):
//   pose          p_ab(q), R_ab(q)
//   velocity      w_ab = Hw(q) u,  v_ab = d/dt_a p_ab = Hv(q) u           (Lesser eqs. 44-47)
//   bias          cw = (d/dt Hw) u,  cv = (d/dt Hv) u  with udot = 0     (seed 000 eq. 11.17)
//   differential  qdot = N(q) u
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <string>

#include "runtime/program/program.h"

namespace kanesim::rt {

using Mat36 = Eigen::Matrix<double, 3, 6>;

// v <- v / |v| for the n numbers at v, without overflow or underflow in |v|: the
// components are divided by the largest |v_i| first, so that {1e200, 1e200, 0, 0} and
// {1e-200, 0, 0, 0} normalize like {1, 1, 0, 0} and {1, 0, 0, 0} (the idea of LAPACK's
// dnrm2). False, and v unchanged, when v has no direction: every component 0, or one
// not finite. Every user-given axis, direction and start quaternion goes through it.
bool NormalizeScaled(double* v, int n);
inline bool NormalizeScaled(Vec3* v) { return NormalizeScaled(v->data(), 3); }
// What is wrong with a vector NormalizeScaled refused: "is zero" or "is not finite".
std::string WhyNoDirection(const double* v, int n);

// R = rotation by `angle` about unit `axis` (Rodrigues).
Mat3 AxisAngle(const Vec3& axis, double angle);

// Fills the joint's hot-path constants (K_axis, K2_axis, axis_P, R_PJ_identity,
// single_axis) from its type, axis, R_PJ and direction; the compiler calls it once.
void PrepareJointConstants(TreeJoint* j);

// Rotation by `angle` about the joint's axis, from the constants above (Rodrigues).
inline Mat3 RotationAboutAxis(const TreeJoint& j, double angle) {
  const double s = std::sin(angle), c1 = 1.0 - std::cos(angle);
  Mat3 R = s * j.K_axis + c1 * j.K2_axis;
  R.diagonal().array() += 1.0;
  return R;
}

// Rotation of a Spherical/Free joint's rotational coordinates (3 angles or w,x,y,z).
Mat3 RotationFromCoords(flat::RotationCoords c, const double* q);

// p_ab and R_ab from the joint's coordinates q (nq entries).
void JointPose(const TreeJoint& j, const double* q, Vec3* p_ab, Mat3* R_ab);

// Hv, Hw (first nu columns used) and the bias terms cv, cw for speeds u, given R_ab.
void JointMotion(const TreeJoint& j, const double* q, const double* u, const Mat3& R_ab, Mat36* Hv,
                 Mat36* Hw, Vec3* cv, Vec3* cw);

// qdot = N(q) u for the joint's nq coordinates. Returns false at a singular
// parameterization (gimbal lock) and writes the reason into *error.
bool JointKinematicDifferential(const TreeJoint& j, const double* q, const double* u, double* qdot,
                                std::string* error);

}  // namespace kanesim::rt
