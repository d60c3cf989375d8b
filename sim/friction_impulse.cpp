// Coulomb friction in a jump of the speeds (sim/friction_impulse.h; docs/events.md "Friction
// in a jump"). The impulse law is the one of rigid-body impact with friction (Pfeiffer &
// Glocker, Multibody Dynamics with Unilateral Contacts, 1996; Stronge, Impact Mechanics,
// 2000, for the impulse form): per friction joint i, with w_i = mu_i r_i (r the pin radius
// of a revolute, 1 for a prismatic) and N_i = |P_N,i| its normal impulse,
//   stick: u_i+ = 0 and |P_f,i| <= w_s,i N_i          slide: P_f,i = -s_i w_i N_i, s_i u_i+ >= 0
// The jump is du = W F with F = J_R^T c + sum_slide P_f,i e_i the joints' generalized
// impulse (R: the caller's rows and the sticking joints' rows e_i, c their impulses) and W
// the constrained inverse mass (rt::ImpulseResponse: the loops' and contacts' reactions keep
// A du = 0); the normal impulses are linear in F, P = N F (the rows' impulses included).
// Method: exact case enumeration. Each joint sticks or slides either way (3^n cases, in order
// of fewer sliding joints first); in a case the rows R make the jump linear, the sliding
// impulses solve p_i = -s_i w_i |a_i + sum_l B_il p_l| (Newton from p = 0), and the case is
// taken when every joint's inequality holds. A case whose rows R are dependent (a stuck
// joint whose speed the loops tie to a row's, as a geared pair's two joints) is no case:
// such a joint's speed follows from the others', and its sliding cases (u+ = 0 either way)
// hold the cone's extremes, so where the joints can be held at rest a case holds. Limits:
// n <= kMaxFrictionImpulseJoints; where more than one case holds (possible for large mu, as
// Painleve's paradoxes in impact, and for stuck joints tied by the loops) the first in that
// order is taken; where none does, the run stops (-1).
#include "sim/friction_impulse.h"

#include "runtime/program/program.h"  // Program::rows

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

namespace kanesim::sim {

namespace {

// A pivot of the rows' block J W J^T below this fraction of the largest: dependent rows.
constexpr double kDependentRows = 1e-10;

struct ActiveJoint {
  int index = 0;              // among rt::FrictionJoints (the program's friction joints)
  int u = 0;                  // its free speed
  double w = 0.0, w_s = 0.0;  // mu r, mu_s r
};

Eigen::Vector3d At(const Eigen::VectorXd& P, int i) { return P.segment<3>(3 * i); }

// The sliding impulses p_i = -s_i w_i |A_i + sum_l B_il p_l| by Newton's method (the map is
// piecewise smooth; from p = 0 the first step is the fixed point's). False when it does not
// converge.
bool SlidingImpulses(const std::vector<Eigen::Vector3d>& A, const std::vector<std::vector<Eigen::Vector3d>>& B,
                     const std::vector<double>& sw, std::vector<double>* p) {
  const size_t n = A.size();
  p->assign(n, 0.0);
  if (n == 0) return true;
  for (int it = 0; it < 100; ++it) {
    Eigen::VectorXd G(n);
    Eigen::MatrixXd Jac = Eigen::MatrixXd::Identity(n, n);
    double p_max = 0.0;
    for (size_t i = 0; i < n; ++i) {
      Eigen::Vector3d a = A[i];
      for (size_t l = 0; l < n; ++l) a += (*p)[l] * B[i][l];
      const double N = a.norm();
      G[i] = (*p)[i] + sw[i] * N;
      if (N > 0.0)
        for (size_t l = 0; l < n; ++l) Jac(i, l) += sw[i] * a.dot(B[i][l]) / N;
      p_max = std::max(p_max, std::abs((*p)[i]));
    }
    const Eigen::VectorXd d = Jac.partialPivLu().solve(G);
    if (!d.allFinite()) return false;
    double d_max = 0.0;
    for (size_t i = 0; i < n; ++i) (*p)[i] -= d[i], d_max = std::max(d_max, std::abs(d[i]));
    if (d_max <= 1e-15 * (1.0 + p_max)) return true;
  }
  return false;
}

// The rows' block G = J W J^T, scaled to a unit diagonal (so that rows of very different
// masses are not taken for dependent), factored; c = G^-1 b by Solve. Dependent: a row the
// constraints fix (G_rr below kDependentRows of its response without them, J_r M^-1 J_r^T:
// a dead point) or rows at a relative pivot below kDependentRows.
class RowBlock {
 public:
  bool Factor(const Eigen::MatrixXd& JR, const Eigen::MatrixXd& W, const Eigen::MatrixXd& Minv) {
    const Eigen::Index m = JR.rows();
    if (m == 0) return true;
    const Eigen::MatrixXd G = JR * W * JR.transpose();
    s_.resize(m);
    for (Eigen::Index r = 0; r < m; ++r) {
      if (!(G(r, r) > kDependentRows * JR.row(r).dot(Minv * JR.row(r).transpose()))) return false;
      s_[r] = 1.0 / std::sqrt(G(r, r));
    }
    lu_.compute(s_.asDiagonal() * G * s_.asDiagonal());
    lu_.setThreshold(kDependentRows);
    return lu_.rank() == m;
  }
  Eigen::VectorXd Solve(const Eigen::VectorXd& b) const {
    if (b.size() == 0) return b;
    return s_.asDiagonal() * lu_.solve(Eigen::VectorXd(s_.asDiagonal() * b));
  }

 private:
  Eigen::VectorXd s_;
  Eigen::FullPivLU<Eigen::MatrixXd> lu_;
};

// One stick/slide case: the jump, the rows' impulses and the normal impulses.
struct JumpCase {
  Eigen::VectorXd du, c, P;
  std::vector<double> p;  // the sliders' impulses
};

}  // namespace

bool HasFrictionImpulses(const rt::Program& program) {
  for (const rt::FrictionJoint& f : rt::FrictionJoints(program))
    if (f.mu > 0.0) return true;
  return false;
}

int FrictionJump(const rt::Program& program, rt::Workspace& ws, double t, const double* y, const std::vector<double>& J,
                 const std::vector<double>& targets, FrictionJumpResult* out, std::string* why,
                 const std::vector<double>& row_normals) {
  const int nq = rt::NumQ(program), nu = rt::NumU(program);
  const auto m = static_cast<Eigen::Index>(targets.size());
  if (J.size() != targets.size() * static_cast<size_t>(nu)) {
    *why = "internal: the jump's rows J are not m x nu";
    return -1;
  }
  const Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> Jm(J.data(), m, nu);
  const std::vector<rt::FrictionJoint> joints = rt::FrictionJoints(program);
  std::vector<ActiveJoint> act;
  for (size_t i = 0; i < joints.size(); ++i) {
    const rt::FrictionJoint& f = joints[i];
    bool own_row = false;  // a row +-e_k on the joint's speed: its friction merges with the row's impulse
    for (Eigen::Index r = 0; r < m && f.u >= 0; ++r)
      own_row = own_row || (Jm(r, f.u) != 0.0 && Jm.row(r).cwiseAbs().sum() == std::abs(Jm(r, f.u)));
    if (f.mu > 0.0 && f.u >= 0 && !own_row)
      act.push_back({static_cast<int>(i), f.u, f.mu * f.radius, (f.exact ? f.mu_s : f.mu) * f.radius});
  }
  if (static_cast<int>(act.size()) > kMaxFrictionImpulseJoints) {
    *why = "the jump meets " + std::to_string(act.size()) + " joints with Coulomb friction mu (at most " +
           std::to_string(kMaxFrictionImpulseJoints) + " are solved, by enumerating their 3^n stick/slide cases)";
    return -1;
  }
  Eigen::MatrixXd W(nu, nu), N(static_cast<Eigen::Index>(3 * joints.size()), nu);
  if (int s = rt::ImpulseResponse(program, ws, t, y, W.data(), N.data()); s != 0) {
    *why = rt::ErrorMessage(ws);
    return s;
  }
  Eigen::MatrixXd Nr = Eigen::MatrixXd::Zero(N.rows(), m);  // the rows' own share in the normal impulses
  if (!row_normals.empty()) {
    if (row_normals.size() != static_cast<size_t>(N.rows() * m)) {
      *why = "internal: the rows' normal impulses are not 3 nf x m";
      return -1;
    }
    Nr = Eigen::Map<const Eigen::MatrixXd>(row_normals.data(), N.rows(), m);
  }
  Eigen::MatrixXd Minv = W;  // a tree's W is M^-1
  if (!program.rows.empty()) {
    Eigen::MatrixXd M(nu, nu);
    if (int s = rt::UnconstrainedMassMatrix(program, ws, t, y, M.data()); s != 0) {
      *why = rt::ErrorMessage(ws);
      return s;
    }
    Minv = M.llt().solve(Eigen::MatrixXd::Identity(nu, nu));
  }
  RowBlock block;
  if (!block.Factor(Jm, W, Minv)) {
    *why = "the jump has no unique solution: the speeds it sets" +
           std::string(program.rows.empty() ? "" : " (through the closed loops' or contacts' rows, or at their dead point)") +
           " and the contacts held constrain the same motion";
    return -1;
  }
  const Eigen::Map<const Eigen::VectorXd> u0(y + nq, nu);
  const Eigen::Map<const Eigen::VectorXd> b0(targets.data(), m);
  const size_t n = act.size();
  int cases = 1;
  for (size_t i = 0; i < n; ++i) cases *= 3;
  for (size_t sliding = 0; sliding <= n; ++sliding) {
    for (int code = 0; code < cases; ++code) {
      std::vector<int> mode(n);  // 0 stick, +1 / -1 slide that way
      size_t count = 0;
      for (size_t i = 0, c = static_cast<size_t>(code); i < n; ++i, c /= 3) {
        mode[i] = c % 3 == 0 ? 0 : c % 3 == 1 ? 1 : -1;
        count += mode[i] != 0;
      }
      if (count != sliding) continue;
      // The rows R: the caller's, then the sticking joints' (speed to 0); the sliders' unit impulses.
      std::vector<size_t> slide, stick;
      for (size_t i = 0; i < n; ++i) (mode[i] == 0 ? stick : slide).push_back(i);
      const auto mR = m + static_cast<Eigen::Index>(stick.size());
      Eigen::MatrixXd JR = Eigen::MatrixXd::Zero(mR, nu);
      Eigen::VectorXd bR(mR);
      JR.topRows(m) = Jm;
      bR.head(m) = b0;
      for (size_t k = 0; k < stick.size(); ++k) {
        JR(m + static_cast<Eigen::Index>(k), act[stick[k]].u) = 1.0;
        bR[m + static_cast<Eigen::Index>(k)] = -u0[act[stick[k]].u];
      }
      if (!block.Factor(JR, W, Minv)) continue;  // dependent rows: no case of this kind
      auto solve = [&](const Eigen::VectorXd& rhs) { return block.Solve(rhs); };
      JumpCase base;
      base.c = solve(bR);
      Eigen::VectorXd F = JR.transpose() * base.c;
      base.du = W * F;
      base.P = N * F + Nr * base.c.head(m);
      std::vector<JumpCase> unit(slide.size());  // per slider: the response to its unit impulse
      for (size_t l = 0; l < slide.size(); ++l) {
        Eigen::VectorXd e = Eigen::VectorXd::Zero(nu);
        e[act[slide[l]].u] = 1.0;
        unit[l].c = -solve(JR * (W * e));
        F = e + JR.transpose() * unit[l].c;
        unit[l].du = W * F;
        unit[l].P = N * F + Nr * unit[l].c.head(m);
      }
      std::vector<Eigen::Vector3d> A;
      std::vector<std::vector<Eigen::Vector3d>> B;
      std::vector<double> sw, p;
      for (size_t i : slide) {
        A.push_back(At(base.P, act[i].index));
        B.emplace_back();
        for (size_t l = 0; l < slide.size(); ++l) B.back().push_back(At(unit[l].P, act[i].index));
        sw.push_back(mode[i] * act[i].w);
      }
      if (!SlidingImpulses(A, B, sw, &p)) continue;
      for (size_t l = 0; l < slide.size(); ++l) {
        base.du += p[l] * unit[l].du;
        base.c += p[l] * unit[l].c;
        base.P += p[l] * unit[l].P;
      }
      // The case holds when the sticking impulses are inside their cones and the sliders
      // move the way their friction assumed.
      const double u_scale = std::max(u0.cwiseAbs().maxCoeff(), (u0 + base.du).cwiseAbs().maxCoeff());
      double p_scale = mR > 0 ? base.c.cwiseAbs().maxCoeff() : 0.0;
      for (double x : p) p_scale = std::max(p_scale, std::abs(x));
      bool holds = true;
      for (size_t k = 0; k < stick.size() && holds; ++k) {
        const ActiveJoint& a = act[stick[k]];
        holds = std::abs(base.c[m + static_cast<Eigen::Index>(k)]) <=
                a.w_s * At(base.P, a.index).norm() * (1.0 + 1e-10) + 1e-14 * p_scale;
      }
      for (size_t l = 0; l < slide.size() && holds; ++l)
        holds = mode[slide[l]] * (u0[act[slide[l]].u] + base.du[act[slide[l]].u]) >= -1e-12 * u_scale;
      if (!holds) continue;
      out->du.assign(base.du.data(), base.du.data() + nu);
      Eigen::VectorXd Fg = JR.transpose() * base.c;
      for (size_t l = 0; l < slide.size(); ++l) Fg[act[slide[l]].u] += p[l];
      out->generalized.assign(Fg.data(), Fg.data() + nu);
      out->impulse.assign(base.c.data(), base.c.data() + m);
      out->stuck.clear();
      out->friction.assign(joints.size(), 0.0);
      out->normal.assign(joints.size(), 0.0);
      for (size_t i = 0; i < joints.size(); ++i) out->normal[i] = At(base.P, static_cast<int>(i)).norm();
      for (size_t k = 0; k < stick.size(); ++k) {
        out->stuck.push_back(act[stick[k]].u);
        out->friction[static_cast<size_t>(act[stick[k]].index)] = base.c[m + static_cast<Eigen::Index>(k)];
      }
      for (size_t l = 0; l < slide.size(); ++l) out->friction[static_cast<size_t>(act[slide[l]].index)] = p[l];
      return 0;
    }
  }
  *why = "no friction impulse satisfies Coulomb's law in the joints with mu (every stick/slide case tried; "
         "a friction coefficient too large for this configuration?)";
  return -1;
}

int FrictionSpeedJump(const rt::Program& program, rt::Workspace& ws, double t, const double* y,
                      const std::vector<int>& rows, const std::vector<double>& targets, double* du,
                      std::vector<int>* stuck, std::string* why, std::vector<double>* F) {
  const auto nu = static_cast<size_t>(rt::NumU(program));
  std::vector<double> J(rows.size() * nu, 0.0);
  for (size_t r = 0; r < rows.size(); ++r) J[r * nu + static_cast<size_t>(rows[r])] = 1.0;
  FrictionJumpResult res;
  stuck->clear();
  if (int s = FrictionJump(program, ws, t, y, J, targets, &res, why); s != 0) return s;
  std::copy(res.du.begin(), res.du.end(), du);
  *stuck = res.stuck;
  if (F) *F = res.generalized;
  return 0;
}

}  // namespace kanesim::sim
