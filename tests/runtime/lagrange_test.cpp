// Kane's equations against an independent derivation: Lagrange's equations
//   d/dt (dT/dqdot) - dT/dq + dV/dq = Q
// for trees of revolute and prismatic joints (u = qdot), with T and V written here from
// scratch (own forward kinematics) and every derivative taken by central differences.
#include <gtest/gtest.h>

#include <random>

#include "compiler/compiler.h"
#include "tests/support/builders.h"

namespace kanesim {
namespace {

using test::Mat3;
using test::Vec3;

// Central differences with h = 1e-5 on smooth O(1) functions: truncation ~h^2 = 1e-10,
// round-off ~1e-16/h = 1e-11; the residual mixes a handful of such terms.
constexpr double kLagrangeTol = 1e-6;
constexpr double kH = 1e-5;

struct Link {
  int parent = -1;       // -1 = world
  bool prismatic = false;
  Vec3 mount_p;          // joint frame on the parent body
  Mat3 mount_R;
  Vec3 axis;             // unit, in the joint frame
  Vec3 child_p;          // joint frame seen from the child body frame (X_B,Jc)
  Mat3 child_R;
  double m;
  Vec3 c;                // mass centre in the body frame
  Mat3 I;                // central inertia in the body frame
  double tau;            // constant joint force
};

struct Model {
  std::vector<Link> links;
  Vec3 g{0.1, -9.81, 0.4};
};

Mat3 Rot(const Vec3& a, double t) { return Eigen::AngleAxisd(t, a).toRotationMatrix(); }

// Forward kinematics: X_WB = X_WP X_mount X_joint(q) X_B,Jc^-1.
void Poses(const Model& md, const Eigen::VectorXd& q, std::vector<Mat3>* R, std::vector<Vec3>* p) {
  const size_t n = md.links.size();
  R->assign(n, Mat3::Identity());
  p->assign(n, Vec3::Zero());
  for (size_t i = 0; i < n; ++i) {
    const Link& l = md.links[i];
    Mat3 RP = Mat3::Identity();
    Vec3 pP = Vec3::Zero();
    if (l.parent >= 0) {
      RP = (*R)[static_cast<size_t>(l.parent)];
      pP = (*p)[static_cast<size_t>(l.parent)];
    }
    Mat3 RJ = RP * l.mount_R;
    Vec3 pJ = pP + RP * l.mount_p;
    Mat3 Rj = l.prismatic ? Mat3::Identity() : Rot(l.axis, q[static_cast<long>(i)]);
    Vec3 pj = l.prismatic ? Vec3(l.axis * q[static_cast<long>(i)]) : Vec3::Zero();
    Mat3 Rc = RJ * Rj;  // child-side joint frame
    Vec3 pc = pJ + RJ * pj;
    (*R)[i] = Rc * l.child_R.transpose();
    (*p)[i] = pc - (*R)[i] * l.child_p;
  }
}

// Angular velocities from finite differences of R would nest differences; instead the
// exact rates: w_i = sum over ancestor revolute joints k of axis_k^W qdot_k, and the
// mass-centre velocity v_i = sum_k (axis_k^W x (c_i - o_k) or axis_k^W) qdot_k.
double Kinetic(const Model& md, const Eigen::VectorXd& q, const Eigen::VectorXd& qd) {
  std::vector<Mat3> R;
  std::vector<Vec3> p;
  Poses(md, q, &R, &p);
  const size_t n = md.links.size();
  std::vector<Vec3> axis_W(n), o_W(n);
  for (size_t k = 0; k < n; ++k) {
    const Link& l = md.links[k];
    Mat3 RP = l.parent >= 0 ? R[static_cast<size_t>(l.parent)] : Mat3::Identity();
    axis_W[k] = RP * l.mount_R * l.axis;
    o_W[k] = p[k] + R[k] * l.child_p;  // child-side joint origin
  }
  double T = 0.0;
  for (size_t i = 0; i < n; ++i) {
    const Vec3 c = p[i] + R[i] * md.links[i].c;
    Vec3 w = Vec3::Zero(), v = Vec3::Zero();
    for (int k = static_cast<int>(i); k >= 0; k = md.links[static_cast<size_t>(k)].parent) {
      const auto uk = static_cast<size_t>(k);
      const double qk = qd[k];
      if (md.links[uk].prismatic) {
        v += axis_W[uk] * qk;
      } else {
        w += axis_W[uk] * qk;
        v += axis_W[uk].cross(c - o_W[uk]) * qk;
      }
    }
    const Mat3 I_W = R[i] * md.links[i].I * R[i].transpose();
    T += 0.5 * md.links[i].m * v.squaredNorm() + 0.5 * w.dot(I_W * w);
  }
  return T;
}

double Potential(const Model& md, const Eigen::VectorXd& q) {
  std::vector<Mat3> R;
  std::vector<Vec3> p;
  Poses(md, q, &R, &p);
  double V = 0.0;
  for (size_t i = 0; i < md.links.size(); ++i) V -= md.links[i].m * md.g.dot(p[i] + R[i] * md.links[i].c);
  return V;
}

// T is exactly quadratic in qdot: M_ii = 2 T(e_i), M_ij = T(e_i + e_j) - T(e_i) - T(e_j).
Eigen::MatrixXd MassMatrix(const Model& md, const Eigen::VectorXd& q) {
  const long n = q.size();
  Eigen::MatrixXd M(n, n);
  Eigen::VectorXd Ti(n);
  for (long i = 0; i < n; ++i) Ti[i] = Kinetic(md, q, Eigen::VectorXd::Unit(n, i));
  for (long i = 0; i < n; ++i)
    for (long j = 0; j < n; ++j)
      M(i, j) = i == j ? 2.0 * Ti[i]
                       : Kinetic(md, q, Eigen::VectorXd::Unit(n, i) + Eigen::VectorXd::Unit(n, j)) - Ti[i] - Ti[j];
  return M;
}

// Residual of Lagrange's equations at (q, qd, qdd).
Eigen::VectorXd LagrangeResidual(const Model& md, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                                 const Eigen::VectorXd& qdd) {
  const long n = q.size();
  Eigen::VectorXd r = MassMatrix(md, q) * qdd;
  r += (MassMatrix(md, q + kH * qd) - MassMatrix(md, q - kH * qd)) * qd / (2 * kH);
  for (long i = 0; i < n; ++i) {
    Eigen::VectorXd e = kH * Eigen::VectorXd::Unit(n, i);
    r[i] -= (Kinetic(md, q + e, qd) - Kinetic(md, q - e, qd)) / (2 * kH);
    r[i] += (Potential(md, q + e) - Potential(md, q - e)) / (2 * kH);
    r[i] -= md.links[static_cast<size_t>(i)].tau;
  }
  return r;
}

flat::Mechanism ToFlat(const Model& md) {
  test::MechBuilder b;
  int world = b.World(md.g);
  std::vector<int> body_frame;
  for (size_t i = 0; i < md.links.size(); ++i) {
    const Link& l = md.links[i];
    const std::string n = test::Name("L", static_cast<long>(i + 1));
    int fb = b.Frame(n + ".frame");
    b.Body(n, fb, l.m, l.c, l.I);
    int parent = l.parent >= 0 ? body_frame[static_cast<size_t>(l.parent)] : world;
    int mount = b.Frame(n + ".mount");
    b.Fixed(n + ".mount_fix", parent, mount, l.mount_p, l.mount_R);
    int cj = b.Frame(n + ".joint");
    b.Fixed(n + ".joint_fix", fb, cj, l.child_p, l.child_R);
    auto& j = b.Joint(test::Name("j", static_cast<long>(i + 1)), l.prismatic ? flat::JointType::Prismatic : flat::JointType::Revolute,
                      mount, cj, l.axis);
    j.tau[0] = b.C(l.tau);
    body_frame.push_back(fb);
  }
  return b.m;
}

Model RandomModel(std::mt19937& rng, int n) {
  Model md;
  std::uniform_real_distribution<double> mass(0.5, 2.0), tau(-1.0, 1.0);
  for (int i = 0; i < n; ++i) {
    Link l;
    l.parent = i == 0 ? -1 : std::uniform_int_distribution<int>(-1, i - 1)(rng);
    l.prismatic = i % 3 == 2;
    l.mount_p = test::RandomVec(rng, 0.5);
    l.mount_R = test::RandomRotation(rng);
    l.axis = test::RandomVec(rng).normalized();
    l.child_p = test::RandomVec(rng, 0.3);
    l.child_R = test::RandomRotation(rng);
    l.m = mass(rng);
    l.c = test::RandomVec(rng, 0.4);
    l.I = test::RandomInertia(rng);
    l.tau = tau(rng);
    md.links.push_back(l);
  }
  return md;
}

void CheckAgainstLagrange(const Model& md, rt::SolverPath path, std::mt19937& rng) {
  rt::CompileOptions opt;
  opt.solver = path;
  auto r = rt::Compile(ToFlat(md), opt);
  ASSERT_TRUE(r.errors.empty()) << r.errors[0].message;
  auto ws = rt::MakeWorkspace(*r.program);
  const long n = static_cast<long>(md.links.size());
  ASSERT_EQ(rt::StateSize(*r.program), 2 * n);
  // The state is in spanning-tree order; the signal names "j<k>.q" say which link each
  // entry belongs to.
  std::vector<long> link_of(static_cast<size_t>(n));
  const auto names = rt::DefaultSignals(*r.program);
  ASSERT_EQ(names.size(), static_cast<size_t>(2 * n));
  for (long i = 0; i < n; ++i) link_of[static_cast<size_t>(i)] = std::stol(names[static_cast<size_t>(2 * i)].substr(1)) - 1;
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 3; ++trial) {
    Eigen::VectorXd y(2 * n), yd(2 * n), q(n), qd(n), qdd(n);
    for (long i = 0; i < 2 * n; ++i) y[i] = u(rng);
    ASSERT_EQ(rt::Derivative(*r.program, *ws, 0.0, y.data(), yd.data()), 0) << rt::ErrorMessage(*ws);
    for (long i = 0; i < n; ++i) {
      const long k = link_of[static_cast<size_t>(i)];
      q[k] = y[i];
      qd[k] = y[n + i];
      qdd[k] = yd[n + i];
    }
    Eigen::VectorXd res = LagrangeResidual(md, q, qd, qdd);
    const double scale = 1.0 + (MassMatrix(md, q) * qdd).norm();
    EXPECT_LT(res.norm() / scale, kLagrangeTol) << "residual " << res.transpose();
  }
}

TEST(Lagrange, RandomRevolutePrismaticTreeDense) {
  // If this fails, the dense Kane path (tangent basis, bias accelerations or the
  // projection of gravity and joint forces) disagrees with Lagrange's equations.
  std::mt19937 rng(20240601);
  CheckAgainstLagrange(RandomModel(rng, 7), rt::SolverPath::Dense, rng);
}

TEST(Lagrange, RandomRevolutePrismaticTreeSparse) {
  // If this fails, the sparse K-vector system disagrees with Lagrange's equations.
  std::mt19937 rng(20240602);
  CheckAgainstLagrange(RandomModel(rng, 7), rt::SolverPath::Sparse, rng);
}

}  // namespace
}  // namespace kanesim
