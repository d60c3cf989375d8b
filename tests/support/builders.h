// Test mechanisms built directly as flat::Mechanism (no language front end), so the
// runtime's tests do not depend on lang/.
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

  ExprId C(double v) { return m.exprs.Constant(v); }
  flat::Vec3E V(const Vec3& v) { return {C(v.x()), C(v.y()), C(v.z())}; }
  flat::Mat3E M(const Mat3& R) {
    flat::Mat3E e;
    for (int i = 0; i < 9; ++i) e[static_cast<size_t>(i)] = C(R(i / 3, i % 3));
    return e;
  }

  int Frame(const std::string& name) {
    flat::Frame f;
    f.name = name;
    f.aliases = {name};
    f.loc = {"test.mech", static_cast<int>(m.frames.size()) + 1, 1};
    m.frames.push_back(f);
    return static_cast<int>(m.frames.size() - 1);
  }
  int World(const Vec3& g) {
    int f = Frame("world.frame");
    flat::World w;
    w.frame = f;
    w.gravity = V(g);
    m.worlds.push_back(w);
    return f;
  }
  void Body(const std::string& name, int frame, double mass, const Vec3& r_cm, const Mat3& I) {
    flat::Body b;
    b.name = name;
    b.frame = frame;
    b.mass = C(mass);
    b.r_cm = V(r_cm);
    b.inertia = M(I);
    b.loc = {"test.mech", 1, 1};
    m.bodies.push_back(b);
  }
  void Fixed(const std::string& name, int a, int b, const Vec3& r, const Mat3& R = Mat3::Identity()) {
    flat::Fixed f;
    f.name = name;
    f.frame_a = a;
    f.frame_b = b;
    f.r = V(r);
    f.R = M(R);
    m.fixed.push_back(f);
  }
  flat::Joint& Joint(const std::string& name, JointType type, int a, int b, const Vec3& axis = Vec3::UnitZ(),
                     const Vec3& axis2 = Vec3::UnitX(),
                     flat::RotationCoords rot = flat::RotationCoords::Quaternion) {
    flat::Joint j;
    j.name = name;
    j.type = type;
    j.rotation = rot;
    j.frame_a = a;
    j.frame_b = b;
    j.axis = V(axis);
    j.axis2 = V(axis2);
    j.loc = {"test.mech", 10 + static_cast<int>(m.joints.size()), 3};
    j.q_start.assign(static_cast<size_t>(j.nq()), kNoExpr);
    j.u_start.assign(static_cast<size_t>(j.nu()), kNoExpr);
    j.q_start_fixed.assign(static_cast<size_t>(j.nq()), false);
    j.tau.assign(static_cast<size_t>(j.nu()), kNoExpr);
    j.prescribed.assign(static_cast<size_t>(j.nq()), kNoExpr);
    m.joints.push_back(j);
    return m.joints.back();
  }
  int Param(const std::string& name, double value) {
    m.AddParam(name).value = value;
    return static_cast<int>(m.params.size() - 1);
  }
};

inline Mat3 Diag(double a, double b, double c) { return Vec3(a, b, c).asDiagonal(); }

// Uniform thin rod of mass m, length L hanging along -y of its frame (pivot at origin).
// Its central inertia about z and x is m L^2 / 12.
inline flat::Mechanism Pendulum(double m = 1.0, double L = 0.5, double g = 9.81, double q0 = 0.3) {
  MechBuilder b;
  int w = b.World(Vec3(0, -g, 0));
  int f = b.Frame("rod.frame_a");
  b.Body("rod", f, m, Vec3(0, -L / 2, 0), Diag(m * L * L / 12, 0.0, m * L * L / 12));
  auto& j = b.Joint("pivot", JointType::Revolute, w, f, Vec3::UnitZ());
  j.q_start[0] = b.C(q0);
  b.m.model_name = "Pendulum";
  return b.m;
}

// examples/chain.mech: N uniform thin rods (1 kg, 0.5 m) along body x, mass centre at
// L/2, central inertia diag(0, mL^2/12, mL^2/12); j[1] at the world origin, j[i] at the
// tip of rod i-1; axes fixed in the parent alternate z, y, z, ...; gravity 9.81 along
// -y; every q starts at 0.1. planar: every axis z (the planar N-link pendulum).
inline flat::Mechanism Chain(int N, double m = 1.0, double L = 0.5, bool planar = false) {
  MechBuilder b;
  int prev = b.World(Vec3(0, -9.81, 0));
  for (int i = 1; i <= N; ++i) {
    const std::string rod = Name("rod[", i, "]");
    int fa = b.Frame(rod + ".frame_a");
    int fb = b.Frame(rod + ".frame_b");
    b.Fixed(rod + ".fixed", fa, fb, Vec3(L, 0, 0));
    b.Body(rod, fa, m, Vec3(L / 2, 0, 0), Diag(0.0, m * L * L / 12, m * L * L / 12));
    auto& j = b.Joint(Name("j[", i, "]"), JointType::Revolute, prev, fa,
                      i % 2 == 1 || planar ? Vec3::UnitZ() : Vec3::UnitY());
    j.q_start[0] = b.C(0.1);
    prev = fb;
  }
  b.m.model_name = "Chain";
  return b.m;
}

inline Mat3 RandomRotation(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::Quaterniond q(n(rng), n(rng), n(rng), n(rng));
  return q.normalized().toRotationMatrix();
}

inline Vec3 RandomVec(std::mt19937& rng, double s = 1.0) {
  std::uniform_real_distribution<double> u(-s, s);
  return Vec3(u(rng), u(rng), u(rng));
}

// A random positive-definite central inertia (principal moments satisfy the triangle
// inequality), rotated randomly.
inline Mat3 RandomInertia(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(0.2, 1.0);
  double a = u(rng), c = u(rng);
  double b = std::max(std::fabs(a - c) + 0.05, std::min(a + c - 0.05, u(rng)));
  Mat3 R = RandomRotation(rng);
  return R * Diag(a, b, c) * R.transpose();
}

// A body "extra" welded at a random offset and turn onto the body whose frame is `host_frame`.
inline void AddWeldedBody(MechBuilder& b, std::mt19937& rng, int host_frame) {
  int f = b.Frame("extra.frame");
  b.Body("extra", f, 0.7, RandomVec(rng, 0.2), RandomInertia(rng));
  int host = b.Frame("extra.host");
  b.Fixed("extra.host_fix", host_frame, host, RandomVec(rng, 0.5), RandomRotation(rng));
  b.Joint("weld", JointType::Weld, host, f);
}

struct TreeOptions {
  int bodies = 8;
  bool mixed = true;     // every joint type and rotation coordinate, else revolute only
  bool inverted = true;  // some joints connect with frame_b on the parent side
  bool weld = true;      // one extra body welded onto another
};

// A random tree (fixed seed from the caller's rng) with parents chosen among earlier bodies.
inline flat::Mechanism RandomTree(std::mt19937& rng, const TreeOptions& opt) {
  MechBuilder b;
  int world = b.World(Vec3(0.3, -9.81, 0.2));
  std::vector<int> body_frames{world};
  const JointType types[] = {JointType::Revolute, JointType::Prismatic, JointType::Cylindrical,
                             JointType::Universal, JointType::Spherical, JointType::Planar, JointType::Free};
  const flat::RotationCoords rots[] = {flat::RotationCoords::Quaternion, flat::RotationCoords::CardanXYZ,
                                       flat::RotationCoords::EulerZYZ};
  std::uniform_real_distribution<double> mass(0.5, 2.0);
  for (int i = 1; i <= opt.bodies; ++i) {
    const std::string name = Name("b", i);
    int parent = body_frames[static_cast<size_t>(std::uniform_int_distribution<int>(0, i - 1)(rng))];
    int fb = b.Frame(name + ".frame");
    b.Body(name, fb, mass(rng), RandomVec(rng, 0.4), RandomInertia(rng));
    // The joint sits at a fixed offset on the parent and another on the child.
    int pj = b.Frame(name + ".mount");
    b.Fixed(name + ".mount_fix", parent, pj, RandomVec(rng, 0.5), RandomRotation(rng));
    int cj = b.Frame(name + ".joint");
    b.Fixed(name + ".joint_fix", fb, cj, RandomVec(rng, 0.3), RandomRotation(rng));
    JointType t = opt.mixed ? types[(i - 1) % 7] : JointType::Revolute;
    flat::RotationCoords rc = rots[static_cast<size_t>(i / 7) % 3];
    bool inv = opt.inverted && i % 3 == 2;
    Vec3 axis = RandomVec(rng).normalized(), axis2 = RandomVec(rng).normalized();
    b.Joint(Name("j", i), t, inv ? cj : pj, inv ? pj : cj, axis, axis2, rc);
    body_frames.push_back(fb);
  }
  if (opt.weld && opt.bodies >= 2) AddWeldedBody(b, rng, body_frames[2]);
  b.m.model_name = "RandomTree";
  return b.m;
}

// A random planar tree (runtime/kane/kane_tree.cpp, "planar trees"): `bodies` bodies, each on a
// revolute joint to a random earlier body or to the world (several roots), whose axis a_i
// (random in the joint's frame, which is the body's frame) the mount on the parent turns
// to +-(the parent's own axis), or +-n for a root, then a random turn about a_i; random
// offsets, mass centres off the plane, full inertia tensors, a body welded onto body 2,
// gravity at an angle to the plane. `tilt` turns the last joint's axis by that angle
// (radians) out of parallel: 0 gives a planar tree, anything else a spatial one.
inline flat::Mechanism RandomPlanarTree(std::mt19937& rng, int bodies, const Vec3& n, double tilt = 0.0) {
  MechBuilder b;
  int world = b.World(Vec3(0.3, -9.81, 0.2));
  std::vector<int> body_frames{world};
  std::vector<Vec3> axes{n.normalized()};  // per body frame: its joint's axis in it (the world: n)
  std::uniform_real_distribution<double> mass(0.5, 2.0), angle(-3.0, 3.0), coin(0.0, 1.0);
  for (int i = 1; i <= bodies; ++i) {
    const std::string name = Name("b", i);
    const auto parent = static_cast<size_t>(std::uniform_int_distribution<int>(0, i - 1)(rng));
    int fb = b.Frame(name + ".frame");
    b.Body(name, fb, mass(rng), RandomVec(rng, 0.4), RandomInertia(rng));
    const Vec3 a = RandomVec(rng).normalized();
    Vec3 to = (coin(rng) < 0.5 ? -1.0 : 1.0) * axes[parent];
    if (i == bodies && tilt != 0.0) to = Eigen::AngleAxisd(tilt, to.unitOrthogonal()) * to;
    const Mat3 R = Eigen::Quaterniond::FromTwoVectors(a, to).toRotationMatrix() *
                   Eigen::AngleAxisd(angle(rng), a).toRotationMatrix();
    int pj = b.Frame(name + ".mount");
    b.Fixed(name + ".mount_fix", body_frames[parent], pj, RandomVec(rng, 0.5), R);
    b.Joint(Name("j", i), JointType::Revolute, pj, fb, a);
    body_frames.push_back(fb);
    axes.push_back(a);
  }
  if (bodies >= 2) AddWeldedBody(b, rng, body_frames[2]);
  b.m.model_name = "RandomPlanarTree";
  return b.m;
}

// Force elements of every kind on a RandomTree of at least 8 bodies (joint j2 prismatic):
// on j2 a force that reads a coordinate, the time and a frame velocity; a spring-damper
// from the world to frame 5; a body-fixed wrench on frame 7 (torque about its z given).
inline void AddBusyForces(flat::Mechanism& m, double wrench_torque_z = 0.0) {
  using flat::Op;
  auto& e = m.exprs;
  const int q2 = m.AddStateRef({flat::StateKind::JointQ, 1, 0});
  const int v4 = m.AddStateRef({flat::StateKind::FrameVelocity, 3, 1});
  m.joints[1].tau[0] = e.Binary(Op::Add, e.Binary(Op::Mul, e.Constant(-3.0), e.State(q2)),
                                e.Binary(Op::Mul, e.Unary(Op::Cos, e.Time()), e.State(v4)));
  flat::LineForce lf;
  lf.name = "spring";
  lf.frame_a = m.worlds[0].frame;
  lf.frame_b = 5;
  lf.k = e.Constant(20.0);
  lf.d = e.Constant(0.5);
  lf.s0 = e.Constant(0.3);
  m.line_forces.push_back(lf);
  flat::Wrench w;
  w.name = "push";
  w.frame = 7;
  w.force = {e.Unary(Op::Sin, e.Time()), e.Constant(0.0), e.Constant(1.0)};
  w.torque = {e.Constant(0.1), e.Constant(0.0), e.Constant(wrench_torque_z)};
  w.resolve_in_world = false;
  m.wrenches.push_back(w);
}

}  // namespace kanesim::test
