// Coulomb friction in a when clause's speed jump (sim/friction_impulse.h; docs/events.md
// "Friction in a jump"). The impulse law is the one of rigid-body impact with friction
// (Pfeiffer & Glocker, Multibody Dynamics with Unilateral Contacts, 1996; Stronge, Impact
// Mechanics, 2000, for the impulse form): per friction joint i, with w_i = mu_i r_i (r the
// pin radius of a revolute, 1 for a prismatic) and N_i = |P_N,i| its normal impulse,
//   stick: u_i+ = 0 and |P_f,i| <= w_s,i N_i          slide: P_f,i = -s_i w_i N_i, s_i u_i+ >= 0
// The jump is M du = E c + sum_i P_f,i e_i (E the rows of the reinit'ed speeds, of the
// sticking joints and of plane contacts, c their impulses: rows change by their targets), and
// N_i is the norm of a vector affine in the sliding impulses (rt::FrictionImpulseNormals of
// du less the contacts' impulses across the axis, rt::PlaneImpulseNormals: linear in du, c).
// Method: exact case enumeration. Each joint sticks or slides either way (3^n cases, in order
// of fewer sliding joints first); in a case the sticking rows make the jump linear, the
// sliding impulses solve p_i = -s_i w_i |a_i + sum_l B_il p_l| (Newton from p = 0), and the
// case is taken when every joint's inequality holds. Limits: n <= kMaxFrictionImpulseJoints;
// where more than one case holds (possible for large mu, as Painleve's paradoxes in impact)
// the first in that order is taken; where none does, the run stops (-1).
#include "sim/friction_impulse.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "sim/impulse.h"

namespace kanesim::sim {

namespace {

struct ActiveJoint {
  int index = 0;            // among rt::FrictionJoints (the program's friction joints)
  int u = 0;                // its free speed
  double w = 0.0, w_s = 0.0;  // mu r, mu_s r
};

// A jump at one state: M^-1, the speeds before, the plane rows, the normal impulses' evaluations.
class FrictionJump {
 public:
  FrictionJump(const rt::Program& p, rt::Workspace& ws, double t, const double* y, Eigen::MatrixXd minv,
               const std::vector<PlaneJumpRow>& planes)
      : p_(p), ws_(ws), t_(t), y_(y), minv_(std::move(minv)), nf_(rt::FrictionJoints(p).size()), planes_(planes) {
    for (const PlaneJumpRow& r : planes_) x_planes_.push_back(minv_ * Eigen::Map<const Eigen::VectorXd>(r.J.data(), minv_.rows()));
  }

  // du = M^-1 (sum F) + X c with X = M^-1 [E_R, J_planes^T], (du)_R = b and J_planes du = the
  // planes' targets (zero with zero_planes); c the rows' impulses (R, then the planes).
  bool Linear(const std::vector<int>& R, const std::vector<double>& b, bool zero_planes, int f_speed,
              Eigen::VectorXd* du, std::vector<double>* c) const {
    const size_t n = R.size(), m = n + planes_.size();
    *du = f_speed >= 0 ? Eigen::VectorXd(minv_.col(f_speed)) : Eigen::VectorXd::Zero(minv_.rows());
    auto X = [&](size_t j) { return j < n ? Eigen::VectorXd(minv_.col(R[j])) : x_planes_[j - n]; };
    auto Row = [&](size_t r, const Eigen::VectorXd& v) {
      return r < n ? v[R[r]] : Eigen::Map<const Eigen::VectorXd>(planes_[r - n].J.data(), v.size()).dot(v);
    };
    std::vector<double> A(m * m), rhs(m);
    for (size_t r = 0; r < m; ++r) {
      rhs[r] = (r < n ? b[r] : zero_planes ? 0.0 : planes_[r - n].target) - Row(r, *du);
      for (size_t j = 0; j < m; ++j) A[r * m + j] = Row(r, X(j));
    }
    if (!SolveSmall(A, rhs, c)) return false;
    for (size_t j = 0; j < m; ++j) *du += (*c)[j] * X(j);
    return true;
  }
  // Every friction joint's normal impulse vector for du and the rows' impulses c (3 per joint).
  int Normals(const Eigen::VectorXd& du, const std::vector<double>& c, std::vector<double>* P) const {
    P->assign(3 * nf_, 0.0);
    if (int s = rt::FrictionImpulseNormals(p_, ws_, t_, y_, du.data(), P->data()); s != 0) return s;
    if (planes_.empty()) return 0;
    std::vector<double> Lambda(rt::PlaneContacts(p_).size(), 0.0);
    const size_t n = c.size() - planes_.size();
    for (size_t j = 0; j < planes_.size(); ++j) Lambda[static_cast<size_t>(planes_[j].contact)] += c[n + j];
    return rt::PlaneImpulseNormals(p_, ws_, t_, y_, Lambda.data(), P->data());
  }
  size_t NumFriction() const { return nf_; }

 private:
  const rt::Program& p_;
  rt::Workspace& ws_;
  double t_;
  const double* y_;
  Eigen::MatrixXd minv_;
  size_t nf_;
  const std::vector<PlaneJumpRow>& planes_;
  std::vector<Eigen::VectorXd> x_planes_;  // M^-1 J^T of each plane row
};

Eigen::Vector3d At(const std::vector<double>& P, int i) {
  return {P[3 * static_cast<size_t>(i)], P[3 * static_cast<size_t>(i) + 1], P[3 * static_cast<size_t>(i) + 2]};
}

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
    Eigen::MatrixXd J = Eigen::MatrixXd::Identity(n, n);
    double p_max = 0.0;
    for (size_t i = 0; i < n; ++i) {
      Eigen::Vector3d a = A[i];
      for (size_t l = 0; l < n; ++l) a += (*p)[l] * B[i][l];
      const double N = a.norm();
      G[i] = (*p)[i] + sw[i] * N;
      if (N > 0.0)
        for (size_t l = 0; l < n; ++l) J(i, l) += sw[i] * a.dot(B[i][l]) / N;
      p_max = std::max(p_max, std::abs((*p)[i]));
    }
    const Eigen::VectorXd d = J.partialPivLu().solve(G);
    if (!d.allFinite()) return false;
    double d_max = 0.0;
    for (size_t i = 0; i < n; ++i) (*p)[i] -= d[i], d_max = std::max(d_max, std::abs(d[i]));
    if (d_max <= 1e-15 * (1.0 + p_max)) return true;
  }
  return false;
}

}  // namespace

bool HasFrictionImpulses(const rt::Program& program) {
  for (const rt::FrictionJoint& f : rt::FrictionJoints(program))
    if (f.mu > 0.0) return true;
  return false;
}

int FrictionSpeedJump(const rt::Program& program, rt::Workspace& ws, double t, const double* y,
                      const std::vector<int>& rows, const std::vector<double>& targets, double* du_out,
                      std::vector<int>* stuck_out, std::string* why, const std::vector<PlaneJumpRow>& planes,
                      std::vector<double>* impulses) {
  const int nq = rt::NumQ(program), nu = rt::NumU(program);
  stuck_out->clear();
  const std::vector<rt::FrictionJoint> joints = rt::FrictionJoints(program);
  std::vector<ActiveJoint> act;
  for (size_t i = 0; i < joints.size(); ++i) {
    const rt::FrictionJoint& f = joints[i];
    if (f.mu > 0.0 && f.u >= 0 && std::find(rows.begin(), rows.end(), f.u) == rows.end())
      act.push_back({static_cast<int>(i), f.u, f.mu * f.radius, (f.exact ? f.mu_s : f.mu) * f.radius});
  }
  if (act.empty() && planes.empty() && !impulses)  // a bounded friction: no impulse
    return SpeedJump(program, ws, t, y, rows, targets, du_out);
  if (static_cast<int>(act.size()) > kMaxFrictionImpulseJoints) {
    *why = "the jump meets " + std::to_string(act.size()) + " joints with Coulomb friction mu (at most " +
           std::to_string(kMaxFrictionImpulseJoints) + " are solved, by enumerating their 3^n stick/slide cases)";
    return -1;
  }
  Eigen::MatrixXd M(nu, nu);
  if (int s = rt::MassMatrix(program, ws, t, y, M.data()); s != 0) {
    *why = rt::ErrorMessage(ws);
    return s;
  }
  const Eigen::LLT<Eigen::MatrixXd> llt(M);
  if (llt.info() != Eigen::Success) {
    *why = "the mass matrix is singular for an impulse";
    return -1;
  }
  const FrictionJump jump(program, ws, t, y, llt.solve(Eigen::MatrixXd::Identity(nu, nu)), planes);
  const double* u0 = y + nq;
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
      // The linear pieces: rows, sticking joints' rows (speed to 0), one unit impulse per slider.
      std::vector<int> R = rows;
      std::vector<double> b = targets;
      std::vector<size_t> slide;
      for (size_t i = 0; i < n; ++i) {
        if (mode[i] == 0) R.push_back(act[i].u), b.push_back(-u0[act[i].u]);
        else slide.push_back(i);
      }
      Eigen::VectorXd du;
      std::vector<double> c, P0;
      if (!jump.Linear(R, b, false, -1, &du, &c)) continue;  // dependent rows: no case of this kind
      if (int s = jump.Normals(du, c, &P0); s != 0) {
        *why = rt::ErrorMessage(ws);
        return s;
      }
      std::vector<Eigen::VectorXd> d(slide.size());
      std::vector<std::vector<double>> dc(slide.size()), dP(slide.size());
      for (size_t l = 0; l < slide.size(); ++l) {
        jump.Linear(R, std::vector<double>(R.size(), 0.0), true, act[slide[l]].u, &d[l], &dc[l]);
        if (int s = jump.Normals(d[l], dc[l], &dP[l]); s != 0) return s;
      }
      std::vector<Eigen::Vector3d> A;
      std::vector<std::vector<Eigen::Vector3d>> B;
      std::vector<double> sw, p;
      for (size_t i : slide) {
        A.push_back(At(P0, act[i].index));
        B.emplace_back();
        for (size_t l = 0; l < slide.size(); ++l) B.back().push_back(At(dP[l], act[i].index));
        sw.push_back(mode[i] * act[i].w);
      }
      if (!SlidingImpulses(A, B, sw, &p)) continue;
      for (size_t l = 0; l < slide.size(); ++l) {
        du += p[l] * d[l];
        for (size_t r = 0; r < c.size(); ++r) c[r] += p[l] * dc[l][r];
        for (size_t k = 0; k < P0.size(); ++k) P0[k] += p[l] * dP[l][k];
      }
      // The case holds when the sticking impulses are inside their cones and the sliders
      // move the way their friction assumed.
      double u_scale = 0.0, p_scale = 0.0;
      for (int k = 0; k < nu; ++k) u_scale = std::max({u_scale, std::abs(u0[k]), std::abs(u0[k] + du[k])});
      for (double x : c) p_scale = std::max(p_scale, std::abs(x));
      for (double x : p) p_scale = std::max(p_scale, std::abs(x));
      bool holds = true;
      for (size_t i = 0, r = rows.size(); i < n && holds; ++i) {
        const double N = At(P0, act[i].index).norm();
        if (mode[i] == 0)
          holds = std::abs(c[r++]) <= act[i].w_s * N * (1.0 + 1e-10) + 1e-14 * p_scale;
        else
          holds = mode[i] * (u0[act[i].u] + du[act[i].u]) >= -1e-12 * u_scale;
      }
      if (!holds) continue;
      std::copy(du.data(), du.data() + nu, du_out);
      for (size_t i = 0; i < n; ++i)
        if (mode[i] == 0) stuck_out->push_back(act[i].u);
      if (impulses) {  // (c: rows, sticking joints, planes)
        impulses->assign(c.begin(), c.begin() + static_cast<long>(rows.size()));
        impulses->insert(impulses->end(), c.end() - static_cast<long>(planes.size()), c.end());
      }
      return 0;
    }
  }
  *why = "no friction impulse satisfies Coulomb's law in the joints with mu (every stick/slide case tried; "
         "a friction coefficient too large for this configuration?)";
  return -1;
}

}  // namespace kanesim::sim
