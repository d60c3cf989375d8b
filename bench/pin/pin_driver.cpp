// Peer for the work-precision benchmark (issue 6): Pinocchio's articulated-body algorithm
// (pinocchio::aba, compiled C++) driven by a hand-written adaptive Dormand-Prince 8(5,3)
// (DOP853; Hairer, Norsett & Wanner, Solving ODEs I, sec. II.10; coefficients in
// sim/dop853_tableau.h, the table kanesim's own DOP853 uses), and a timer of one
// aba call for the RHS-cost-vs-N table.
//
//   pin_driver integrate MODEL N T RTOL ATOL REPS   ->  one line: key=value ...
//   pin_driver rhs N REPS                           ->  ns per aba call (chain N)
//   pin_driver integrate fourbar 3 T RTOL ATOL REPS Q0 U0 KP KD MU ACC ITER
//                                                   ->  the same line, plus u and the loop residual
//
// MODEL: "chain" (examples/chain.mech: N rods 1 kg, 0.5 m, axes z,y,z,... fixed in the
// parent, every q = 0.1) or "pendulum" (examples/double_pendulum.mech: 2 rods 1 kg, 1 m,
// axes z,z, q = pi/2). Rods lie along body x, CoM at L/2, inertia diag(0, mL^2/12, mL^2/12);
// gravity 9.81 along -y; u = dq/dt. The model is built joint by joint (no URDF).
// MODEL "fourbar" is the closed loop of examples/fourbar.mech (MakeFourbar, LoopRhs): the
// start Q0, U0 ("x,y,z") and the settings of pinocchio::constraintDynamics (Baumgarte KP, KD;
// proximal MU, accuracy ACC, at most ITER iterations) come from bench/wp/fourbar_geometry.py.
// Built by bench/run_work_precision.sh with the flags kanesim's Release build uses (-O3),
// with the repository root on the include path.
// constraintDynamics and RigidConstraintModel are marked "unsupported: the API will change"
// in Pinocchio 4.1; they are still its documented constrained forward dynamics.
#define PINOCCHIO_DISABLE_UNSUPPORTED_WARNINGS
#include <pinocchio/algorithm/aba.hpp>
#include <pinocchio/algorithm/constrained-dynamics.hpp>
#include <pinocchio/multibody.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <sstream>
#include <string>
#include <vector>

#include "sim/dop853_control.h"
#include "sim/dop853_tableau.h"

namespace {

using Clock = std::chrono::steady_clock;
using Vec = Eigen::VectorXd;

struct Scene {
  pinocchio::Model model;
  Vec q0;
};

Scene MakeScene(const std::string& kind, int n) {
  const bool pendulum = kind == "pendulum";
  if (pendulum) n = 2;
  const double L = pendulum ? 1.0 : 0.5, m = 1.0;
  Scene s;
  s.model.gravity = pinocchio::Motion(Eigen::Vector3d(0, -9.81, 0), Eigen::Vector3d::Zero());
  Eigen::Matrix3d I = Eigen::Matrix3d::Zero();
  I(1, 1) = I(2, 2) = m * L * L / 12;
  const pinocchio::Inertia inertia(m, Eigen::Vector3d(L / 2, 0, 0), I);
  pinocchio::JointIndex parent = 0;
  for (int i = 1; i <= n; ++i) {
    const pinocchio::SE3 place(Eigen::Matrix3d::Identity(), Eigen::Vector3d(i == 1 ? 0.0 : L, 0, 0));
    const std::string name = "j" + std::to_string(i);
    pinocchio::JointIndex j = (pendulum || i % 2 == 1)
                                  ? s.model.addJoint(parent, pinocchio::JointModelRZ(), place, name)
                                  : s.model.addJoint(parent, pinocchio::JointModelRY(), place, name);
    s.model.appendBodyToJoint(j, inertia, pinocchio::SE3::Identity());
    parent = j;
  }
  s.q0 = Vec::Constant(n, pendulum ? M_PI / 2 : 0.1);
  return s;
}

// y = [q, u], y' = [u, aba(q, u, 0)].
struct Rhs {
  const pinocchio::Model& model;
  pinocchio::Data data;
  Vec tau;
  long evals = 0;
  explicit Rhs(const pinocchio::Model& m) : model(m), data(m), tau(Vec::Zero(m.nv)) {}
  void operator()(const Vec& y, Vec& dy) {
    const int n = model.nv;
    pinocchio::aba(model, data, y.head(n), y.tail(n), tau);
    dy.head(n) = y.tail(n);
    dy.tail(n) = data.ddq;
    ++evals;
  }
};

struct Result {
  Vec y;
  long steps = 0, rejected = 0, evals = 0;
};

// Adaptive DOP853 from 0 to T (the last step clipped onto T). Error norm and step control
// as in Hairer's dop853.f: err = |h| err5 / sqrt(n (err5^2 + 0.01 err3^2)) with err5, err3
// the root-sum-squares of the scaled 5th- and 3rd-order estimates, scale atol + rtol max|y|;
// the new step from sim/dop853_control.h, the control kanesim's DOP853 uses (Hairer's:
// 0.9 err^(-1/8) clamped to [1/3, 6], no growth right after a rejection; a step within 1 % of
// T goes onto it), so that both take the same steps. The FSAL stage is the next step's first.
template <class F>
Result Dop853(F& f, const Vec& y0, double T, double rtol, double atol) {
  using namespace kanesim::sim::dop853;
  const int n = static_cast<int>(y0.size());
  std::vector<Vec> K(kStages + 1, Vec(n));
  Vec y = y0, ynew(n), ytmp(n), sc(n), e3(n), e5(n);
  f(y, K[0]);
  // Initial step (Hairer, Solving ODEs I, sec. II.4), as SciPy's select_initial_step.
  sc = atol + rtol * y.array().abs();
  double d0 = (y.array() / sc.array()).matrix().norm() / std::sqrt(n);
  double d1 = (K[0].array() / sc.array()).matrix().norm() / std::sqrt(n);
  double h0 = (d0 < 1e-5 || d1 < 1e-5) ? 1e-6 : 0.01 * d0 / d1;
  h0 = std::min(h0, T);
  ytmp = y + h0 * K[0];
  f(ytmp, K[1]);
  double d2 = ((K[1] - K[0]).array() / sc.array()).matrix().norm() / std::sqrt(n) / h0;
  double h1 = std::max(d1, d2) <= 1e-15 ? std::max(1e-6, h0 * 1e-3) : std::pow(0.01 / std::max(d1, d2), 1.0 / 8);
  double h = std::min({100 * h0, h1, T});
  Result r;
  double t = 0;
  bool rejected = false;
  while (t < T) {
    bool last = false;
    if (T - t <= kStretch * h) {
      h = T - t;
      last = true;
    }
    for (int s = 1; s < kStages; ++s) {
      ytmp = y;
      for (int j = 0; j < s; ++j)
        if (A[s][j] != 0.0) ytmp += (h * A[s][j]) * K[j];
      f(ytmp, K[s]);
    }
    ynew = y;
    e3.setZero();
    e5.setZero();
    for (int j = 0; j < kStages; ++j) {
      if (B[j] != 0.0) ynew += (h * B[j]) * K[j];
      if (E3[j] != 0.0) e3 += E3[j] * K[j];
      if (E5[j] != 0.0) e5 += E5[j] * K[j];
    }
    sc = (atol + rtol * y.array().abs().max(ynew.array().abs())).matrix();
    const double err5 = (e5.array() / sc.array()).square().sum();
    const double err3 = (e3.array() / sc.array()).square().sum();
    double deno = err5 + 0.01 * err3;
    const double err = deno > 0 ? std::abs(h) * err5 / std::sqrt(n * deno) : 0.0;
    if (err <= 1.0) {
      t = last ? T : t + h;
      y = ynew;
      f(y, K[kStages]);
      std::swap(K[0], K[kStages]);
      ++r.steps;
      h *= GrowFactor(err, rejected);
      rejected = false;
    } else {
      ++r.rejected;
      h *= ShrinkFactor(err);
      rejected = true;
    }
    if (h < 1e-14 * std::max(1.0, std::abs(t))) {
      std::fprintf(stderr, "step size underflow at t=%g\n", t);
      std::exit(2);
    }
  }
  r.y = y;
  r.evals = f.evals;
  return r;
}

// Repetitions stop early once the runs so far took this long in all (as run.py's Sweep
// does for the Python peers and bench/kanesim_driver.cpp for kanesim): a slow point is
// timed fewer times, not for minutes.
constexpr double kRepeatBudget = 1.0;  // s

bool RepeatAgain(const std::vector<double>& walls, int reps) {
  double total = 0.0;
  for (double w : walls) total += w;
  return static_cast<int>(walls.size()) < reps && (walls.empty() || total < kRepeatBudget);
}

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

int Integrate(const std::string& kind, int n, double T, double rtol, double atol, int reps) {
  Scene s = MakeScene(kind, n);
  const int nv = s.model.nv;
  Vec y0 = Vec::Zero(2 * nv);
  y0.head(nv) = s.q0;
  std::vector<double> walls;
  Result r;
  while (RepeatAgain(walls, reps)) {
    Rhs f(s.model);
    auto t0 = Clock::now();
    r = Dop853(f, y0, T, rtol, atol);
    walls.push_back(std::chrono::duration<double>(Clock::now() - t0).count());
  }
  std::printf("wall=%.9g steps=%ld rejected=%ld evals=%ld q=", Median(walls), r.steps, r.rejected, r.evals);
  for (int i = 0; i < nv; ++i) std::printf("%s%.17g", i ? "," : "", r.y[i]);
  std::printf("\n");
  return 0;
}

// ---------------------------------------------------------------------------- four-bar loop
using ConstraintModels =
    std::vector<pinocchio::RigidConstraintModel, Eigen::aligned_allocator<pinocchio::RigidConstraintModel>>;
using ConstraintDatas =
    std::vector<pinocchio::RigidConstraintData, Eigen::aligned_allocator<pinocchio::RigidConstraintData>>;

// The crank-rocker of examples/fourbar.mech (numbers: bench/wp/fourbar_geometry.py FOURBAR):
// crank a = 0.2 m, 0.5 kg on a z hinge at the origin; coupler b = 0.6 m, 1.0 kg on a z hinge
// at the crank tip; rocker c = 0.5 m, 0.8 kg on a z hinge at (d, 0, 0), d = 0.6 m; rods as
// MakeScene's. Pinocchio's model is the spanning tree; the loop is a point constraint
// (RigidConstraintModel CONTACT_3D, LOCAL) between the coupler tip and the rocker tip, with
// Baumgarte stabilisation a_c = -KP e_p - KD e_v added to the constraint's acceleration.
// Its z row is identically zero (planar loop): mu > 0 in the proximal solver regularises it.
struct LoopScene {
  pinocchio::Model model;
  ConstraintModels loops;
};

LoopScene MakeFourbar(double kp, double kd) {
  const double a = 0.2, b = 0.6, c = 0.5, d = 0.6, m[3] = {0.5, 1.0, 0.8}, L[3] = {a, b, c};
  LoopScene s;
  s.model.gravity = pinocchio::Motion(Eigen::Vector3d(0, -9.81, 0), Eigen::Vector3d::Zero());
  auto at = [](double x) { return pinocchio::SE3(Eigen::Matrix3d::Identity(), Eigen::Vector3d(x, 0, 0)); };
  auto rod = [&](int k) {
    Eigen::Matrix3d I = Eigen::Matrix3d::Zero();
    I(1, 1) = I(2, 2) = m[k] * L[k] * L[k] / 12;
    return pinocchio::Inertia(m[k], Eigen::Vector3d(L[k] / 2, 0, 0), I);
  };
  const auto crank = s.model.addJoint(0, pinocchio::JointModelRZ(), at(0), "crank_pivot");
  s.model.appendBodyToJoint(crank, rod(0), pinocchio::SE3::Identity());
  const auto coupler = s.model.addJoint(crank, pinocchio::JointModelRZ(), at(a), "crank_coupler");
  s.model.appendBodyToJoint(coupler, rod(1), pinocchio::SE3::Identity());
  const auto rocker = s.model.addJoint(0, pinocchio::JointModelRZ(), at(d), "rocker_pivot");
  s.model.appendBodyToJoint(rocker, rod(2), pinocchio::SE3::Identity());
  pinocchio::RigidConstraintModel loop(pinocchio::CONTACT_3D, s.model, coupler, at(b), rocker, at(c),
                                       pinocchio::LOCAL);
  loop.setBaumgarteCorrectorParameters(pinocchio::BaumgarteCorrectorParametersTpl<double>(kp, kd));
  s.loops.push_back(loop);
  return s;
}

// y = [q, u], y' = [u, constraintDynamics(q, u, 0)]: the KKT system of M and the constraint
// Jacobian, factored by Pinocchio's constraint Cholesky and solved by proximal iterations.
struct LoopRhs {
  const pinocchio::Model& model;
  const ConstraintModels& loops;
  pinocchio::Data data;
  ConstraintDatas datas;
  pinocchio::ProximalSettings prox;
  Vec tau;
  long evals = 0;
  LoopRhs(const LoopScene& s, double mu, double accuracy, int max_iter)
      : model(s.model), loops(s.loops), data(s.model), prox(accuracy, accuracy, mu, max_iter),
        tau(Vec::Zero(s.model.nv)) {
    for (const auto& c : loops) datas.push_back(c.createData());
    pinocchio::initConstraintDynamics(model, data, loops, datas);
  }
  void operator()(const Vec& y, Vec& dy) {
    const int n = model.nv;
    pinocchio::constraintDynamics(model, data, y.head(n), y.tail(n), tau, loops, datas, prox);
    dy.head(n) = y.tail(n);
    dy.tail(n) = data.ddq;
    ++evals;
  }
};

// "x,y,z" -> (x, y, z).
Vec ParseList(const std::string& text) {
  std::vector<double> xs;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) xs.push_back(std::stod(item));
  return Eigen::Map<Vec>(xs.data(), static_cast<Eigen::Index>(xs.size()));
}

// As Integrate, for the loop; also prints u(T) and Pinocchio's own loop residual at T (the
// position and velocity error of the constraint, outside the timing).
int IntegrateLoop(double T, double rtol, double atol, int reps, const Vec& q0, const Vec& u0, double kp, double kd,
                  double mu, double accuracy, int max_iter) {
  const LoopScene s = MakeFourbar(kp, kd);
  const int nv = s.model.nv;
  if (q0.size() != nv || u0.size() != nv) {
    std::fprintf(stderr, "fourbar: Q0 and U0 need %d values each\n", nv);
    return 1;
  }
  Vec y0(2 * nv);
  y0 << q0, u0;
  std::vector<double> walls;
  Result r;
  while (RepeatAgain(walls, reps)) {
    LoopRhs f(s, mu, accuracy, max_iter);
    auto t0 = Clock::now();
    r = Dop853(f, y0, T, rtol, atol);
    walls.push_back(std::chrono::duration<double>(Clock::now() - t0).count());
  }
  LoopRhs f(s, mu, accuracy, max_iter);
  Vec dy(2 * nv);
  f(r.y, dy);
  std::printf("wall=%.9g steps=%ld rejected=%ld evals=%ld prox_iter=%d gap=%.3g vgap=%.3g", Median(walls), r.steps,
              r.rejected, r.evals, f.prox.iter, f.datas[0].contact_placement_error.linear().norm(),
              f.datas[0].contact_velocity_error.linear().norm());
  for (int part = 0; part < 2; ++part) {
    std::printf(part ? " u=" : " q=");
    for (int i = 0; i < nv; ++i) std::printf("%s%.17g", i ? "," : "", r.y[part * nv + i]);
  }
  std::printf("\n");
  return 0;
}

double CpuSeconds() {
  timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

// Median over REPS batches of the time of one aba call at a state with non-zero speeds,
// wall and process CPU time in ns (CPU time as Google Benchmark's "CPU" column, which
// bench/rhs_chain reports for kanesim: on a loaded machine it is the steadier of the two).
int TimeRhs(int n, int reps) {
  Scene s = MakeScene("chain", n);
  Rhs f(s.model);
  Vec y(2 * n), dy(2 * n);
  y.head(n) = s.q0;
  y.tail(n).setConstant(0.3);
  const long inner = std::max(10L, 2000000L / (50L * n));
  std::vector<double> wall, cpu;
  for (int k = 0; k < reps; ++k) {
    auto t0 = Clock::now();
    const double c0 = CpuSeconds();
    for (long i = 0; i < inner; ++i) {
      f(y, dy);
      asm volatile("" : : "r"(dy.data()) : "memory");
    }
    cpu.push_back((CpuSeconds() - c0) * 1e9 / inner);
    wall.push_back(std::chrono::duration<double, std::nano>(Clock::now() - t0).count() / inner);
  }
  std::printf("wall_ns=%.6g cpu_ns=%.6g\n", Median(wall), Median(cpu));
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 8 && std::string(argv[1]) == "integrate")
    return Integrate(argv[2], std::atoi(argv[3]), std::atof(argv[4]), std::atof(argv[5]), std::atof(argv[6]),
                     std::atoi(argv[7]));
  if (argc == 15 && std::string(argv[1]) == "integrate" && std::string(argv[2]) == "fourbar")
    return IntegrateLoop(std::atof(argv[4]), std::atof(argv[5]), std::atof(argv[6]), std::atoi(argv[7]),
                         ParseList(argv[8]), ParseList(argv[9]), std::atof(argv[10]), std::atof(argv[11]),
                         std::atof(argv[12]), std::atof(argv[13]), std::atoi(argv[14]));
  if (argc == 4 && std::string(argv[1]) == "rhs") return TimeRhs(std::atoi(argv[2]), std::atoi(argv[3]));
  std::fprintf(stderr,
               "usage: pin_driver integrate chain|pendulum N T RTOL ATOL REPS | pin_driver rhs N REPS\n"
               "       pin_driver integrate fourbar 3 T RTOL ATOL REPS Q0 U0 KP KD MU ACC ITER\n");
  return 1;
}
