// Definitions of tests/support/builders.h, compiled once into kanesim_test_builders instead
// of in every test source that includes the header (their Eigen code cost each ~10 s).
#include "tests/support/builders.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace kanesim::test {

ExprId MechBuilder::C(double v) { return m.exprs.Constant(v); }
flat::Vec3E MechBuilder::V(const Vec3& v) { return {C(v.x()), C(v.y()), C(v.z())}; }
flat::Mat3E MechBuilder::M(const Mat3& R) {
  flat::Mat3E e;
  for (int i = 0; i < 9; ++i) e[static_cast<size_t>(i)] = C(R(i / 3, i % 3));
  return e;
}

int MechBuilder::Frame(const std::string& name) {
  flat::Frame f;
  f.name = name;
  f.aliases = {name};
  f.loc = {"test.mech", static_cast<int>(m.frames.size()) + 1, 1};
  m.frames.push_back(f);
  return static_cast<int>(m.frames.size() - 1);
}
int MechBuilder::World(const Vec3& g) {
  int f = Frame("world.frame");
  flat::World w;
  w.frame = f;
  w.gravity = V(g);
  m.worlds.push_back(w);
  return f;
}
void MechBuilder::Body(const std::string& name, int frame, double mass, const Vec3& r_cm, const Mat3& I) {
  flat::Body b;
  b.name = name;
  b.frame = frame;
  b.mass = C(mass);
  b.r_cm = V(r_cm);
  b.inertia = M(I);
  b.loc = {"test.mech", 1, 1};
  m.bodies.push_back(b);
}
void MechBuilder::Fixed(const std::string& name, int a, int b, const Vec3& r, const Mat3& R) {
  flat::Fixed f;
  f.name = name;
  f.frame_a = a;
  f.frame_b = b;
  f.r = V(r);
  f.R = M(R);
  m.fixed.push_back(f);
}
flat::Joint& MechBuilder::Joint(const std::string& name, JointType type, int a, int b, const Vec3& axis,
                                const Vec3& axis2, flat::RotationCoords rot) {
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
int MechBuilder::Param(const std::string& name, double value) {
  m.AddParam(name).value = value;
  return static_cast<int>(m.params.size() - 1);
}

Mat3 Diag(double a, double b, double c) { return Vec3(a, b, c).asDiagonal(); }

flat::Mechanism Pendulum(double m, double L, double g, double q0) {
  MechBuilder b;
  int w = b.World(Vec3(0, -g, 0));
  int f = b.Frame("rod.frame_a");
  b.Body("rod", f, m, Vec3(0, -L / 2, 0), Diag(m * L * L / 12, 0.0, m * L * L / 12));
  auto& j = b.Joint("pivot", JointType::Revolute, w, f, Vec3::UnitZ());
  j.q_start[0] = b.C(q0);
  b.m.model_name = "Pendulum";
  return b.m;
}

flat::Mechanism Chain(int N, double m, double L, bool planar) {
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

Mat3 RandomRotation(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::Quaterniond q(n(rng), n(rng), n(rng), n(rng));
  return q.normalized().toRotationMatrix();
}

Vec3 RandomVec(std::mt19937& rng, double s) {
  std::uniform_real_distribution<double> u(-s, s);
  return Vec3(u(rng), u(rng), u(rng));
}

Mat3 RandomInertia(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(0.2, 1.0);
  double a = u(rng), c = u(rng);
  double b = std::max(std::fabs(a - c) + 0.05, std::min(a + c - 0.05, u(rng)));
  Mat3 R = RandomRotation(rng);
  return R * Diag(a, b, c) * R.transpose();
}

void AddWeldedBody(MechBuilder& b, std::mt19937& rng, int host_frame) {
  int f = b.Frame("extra.frame");
  b.Body("extra", f, 0.7, RandomVec(rng, 0.2), RandomInertia(rng));
  int host = b.Frame("extra.host");
  b.Fixed("extra.host_fix", host_frame, host, RandomVec(rng, 0.5), RandomRotation(rng));
  b.Joint("weld", JointType::Weld, host, f);
}

flat::Mechanism RandomTree(std::mt19937& rng, const TreeOptions& opt) {
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

flat::Mechanism RandomPlanarTree(std::mt19937& rng, int bodies, const Vec3& n, double tilt) {
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

void AddBusyForces(flat::Mechanism& m, double wrench_torque_z) {
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
