// Test mechanisms built directly as flat::Mechanism (no language front end), so the
// runtime's tests do not depend on lang/. The definitions are in builders.cpp (the
// kanesim_test_builders library), compiled once.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <random>
#include <string>

#include "flat/mechanism.h"

namespace kanesim::test {

using flat::ExprId;
using flat::JointType;
using flat::kNoExpr;
using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;

// prefix + i + suffix, built by appending (GCC 12 -O3 reports a false -Wrestrict for
// "literal" + std::to_string(i)).
inline std::string Name(const char* prefix, long i, const char* suffix = "") {
  std::string s(prefix);
  s += std::to_string(i);
  s += suffix;
  return s;
}

struct MechBuilder {
  flat::Mechanism m;

  ExprId C(double v);
  flat::Vec3E V(const Vec3& v);
  flat::Mat3E M(const Mat3& R);
  int Frame(const std::string& name);
  int World(const Vec3& g);
  void Body(const std::string& name, int frame, double mass, const Vec3& r_cm, const Mat3& I);
  void Fixed(const std::string& name, int a, int b, const Vec3& r, const Mat3& R = Mat3::Identity());
  flat::Joint& Joint(const std::string& name, JointType type, int a, int b, const Vec3& axis = Vec3::UnitZ(),
                     const Vec3& axis2 = Vec3::UnitX(),
                     flat::RotationCoords rot = flat::RotationCoords::Quaternion);
  int Param(const std::string& name, double value);
};

Mat3 Diag(double a, double b, double c);

// Uniform thin rod of mass m, length L hanging along -y of its frame (pivot at origin).
// Its central inertia about z and x is m L^2 / 12.
flat::Mechanism Pendulum(double m = 1.0, double L = 0.5, double g = 9.81, double q0 = 0.3);

// examples/chain.mech: N uniform thin rods (1 kg, 0.5 m) along body x, mass centre at
// L/2, central inertia diag(0, mL^2/12, mL^2/12); j[1] at the world origin, j[i] at the
// tip of rod i-1; axes fixed in the parent alternate z, y, z, ...; gravity 9.81 along
// -y; every q starts at 0.1. planar: every axis z (the planar N-link pendulum).
flat::Mechanism Chain(int N, double m = 1.0, double L = 0.5, bool planar = false);

Mat3 RandomRotation(std::mt19937& rng);

Vec3 RandomVec(std::mt19937& rng, double s = 1.0);

// A random positive-definite central inertia (principal moments satisfy the triangle
// inequality), rotated randomly.
Mat3 RandomInertia(std::mt19937& rng);

// A body "extra" welded at a random offset and turn onto the body whose frame is `host_frame`.
void AddWeldedBody(MechBuilder& b, std::mt19937& rng, int host_frame);

struct TreeOptions {
  int bodies = 8;
  bool mixed = true;     // every joint type and rotation coordinate, else revolute only
  bool inverted = true;  // some joints connect with frame_b on the parent side
  bool weld = true;      // one extra body welded onto another
};

// A random tree (fixed seed from the caller's rng) with parents chosen among earlier bodies.
flat::Mechanism RandomTree(std::mt19937& rng, const TreeOptions& opt);

// A random planar tree (runtime/kane/kane_tree.cpp, "planar trees"): `bodies` bodies, each on a
// revolute joint to a random earlier body or to the world (several roots), whose axis a_i
// (random in the joint's frame, which is the body's frame) the mount on the parent turns
// to +-(the parent's own axis), or +-n for a root, then a random turn about a_i; random
// offsets, mass centres off the plane, full inertia tensors, a body welded onto body 2,
// gravity at an angle to the plane. `tilt` turns the last joint's axis by that angle
// (radians) out of parallel: 0 gives a planar tree, anything else a spatial one.
flat::Mechanism RandomPlanarTree(std::mt19937& rng, int bodies, const Vec3& n, double tilt = 0.0);

// Force elements of every kind on a RandomTree of at least 8 bodies (joint j2 prismatic):
// on j2 a force that reads a coordinate, the time and a frame velocity; a spring-damper
// from the world to frame 5; a body-fixed wrench on frame 7 (torque about its z given).
void AddBusyForces(flat::Mechanism& m, double wrench_torque_z = 0.0);

}  // namespace kanesim::test
