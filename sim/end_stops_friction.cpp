// End stops beside Coulomb friction mu N (sim/end_stops.h; docs/events.md "Friction beside
// stops"). A tree only (the compiler refuses closed loops with them, and plane contacts).
// Resting: the friction forces follow the joints' normal forces N, N the accelerations, and
// the accelerations the rows' reactions lambda, so the accelerations are not affine in
// lambda. The rows' residual r(lambda) = J a(lambda) + c is brought to zero by the chord
// iteration
//   lambda <- lambda - (J M^-1 J^T)^-1 r(lambda)                                         (1)
// (exact without mu; with mu it converges at the rate the tree's fixed point of
// runtime/kane/friction.cpp (3) does, each a(lambda) solving that fixed point with lambda
// applied). Impacts: the stops' rows are speed rows (J = +-e_k), so the jump is
// sim/friction_impulse.h's, whose normal impulses carry the stops' impulses.
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>

#include "sim/end_stops.h"
#include "sim/friction_impulse.h"
#include "sim/impulse.h"  // SolveSmall

namespace kanesim::sim {

namespace {
constexpr double kTol = 1e-11;  // residual / (1 + largest |a|): a few times the fixed point's
constexpr int kMaxIterations = 60;
}  // namespace

int EndStopEvents::ReactionsMu(rt::Workspace& ws, double t, const double* y, const std::vector<int>& rows,
                               const std::vector<double>& bias, std::vector<double>* c, double* a) {
  const size_t m = rows.size(), nu = static_cast<size_t>(nu_);
  std::copy(ydot_.begin() + nq_, ydot_.end(), a_.begin());  // the free accelerations (ReactionNoise)
  Eigen::MatrixXd M(nu_, nu_);
  if (int s = rt::MassMatrix(program_, ws, t, y, M.data()); s != 0) return s;
  const Eigen::LLT<Eigen::MatrixXd> llt(M);
  if (llt.info() != Eigen::Success) {
    error_ = "the mass matrix is singular for the resting contacts' reactions";
    return -1;
  }
  Jrows_.assign(m * nu, 0.0);
  x_.assign(m * nu, 0.0);
  for (size_t j = 0; j < m; ++j) {
    double gap = 0.0, cj = 0.0;
    if (int s = Row(ws, t, y, sides_[static_cast<size_t>(rows[j])], &gap, Jrows_.data() + j * nu, &cj); s != 0) return s;
    const Eigen::VectorXd x = llt.solve(Eigen::Map<const Eigen::VectorXd>(Jrows_.data() + j * nu, nu_));
    std::copy(x.data(), x.data() + nu_, x_.data() + j * nu);
  }
  std::vector<double> A(m * m), r(m), dc, F(nu), yd(ydot_.size());
  for (size_t i = 0; i < m; ++i)
    for (size_t j = 0; j < m; ++j) {
      double s = 0.0;
      for (size_t k = 0; k < nu; ++k) s += Jrows_[i * nu + k] * x_[j * nu + k];
      A[i * m + j] = s;
    }
  c->assign(m, 0.0);
  for (int it = 0; it < kMaxIterations; ++it) {
    std::fill(F.begin(), F.end(), 0.0);
    for (size_t j = 0; j < m; ++j)
      for (size_t k = 0; k < nu; ++k) F[k] += (*c)[j] * Jrows_[j * nu + k];
    if (int s = rt::DerivativeWithForces(program_, ws, t, y, F.data(), yd.data()); s != 0) return s;
    const double* acc = yd.data() + nq_;
    double r_max = 0.0, scale = 1.0;
    for (size_t j = 0; j < m; ++j) {
      r[j] = -bias[j];
      for (size_t k = 0; k < nu; ++k) r[j] -= Jrows_[j * nu + k] * acc[k];
      r_max = std::max(r_max, std::abs(r[j]));
    }
    for (size_t k = 0; k < nu; ++k) scale = std::max(scale, 1.0 + std::abs(acc[k]));
    if (r_max <= kTol * scale) {
      std::copy(acc, acc + nu_, a);
      error_.clear();
      return 0;
    }
    if (!SolveSmall(A, r, &dc)) {
      error_ = SingularRows(rows);
      return -1;
    }
    for (size_t j = 0; j < m; ++j) (*c)[j] += dc[j];  // (1)
  }
  ws.error = "the resting contacts' reactions with Coulomb friction mu N did not converge (self-locking joint?)";
  return 1;  // recoverable: the integrator retries with a smaller step
}

int EndStopEvents::ImpulseMu(rt::Workspace& ws, double t, const double* y, const std::vector<int>& rows,
                             const std::vector<double>& targets, double* du, std::vector<double>* c) {
  std::vector<int> speeds;
  std::vector<double> jumps, sign;
  for (size_t j = 0; j < rows.size(); ++j) {
    const Side& s = sides_[static_cast<size_t>(rows[j])];
    if (s.plane >= 0) {
      error_ = "an impact of a plane contact beside Coulomb friction mu N is not supported";
      return -1;
    }
    sign.push_back(s.upper ? -1.0 : 1.0);
    speeds.push_back(stops_[static_cast<size_t>(s.stop)].u);
    jumps.push_back(sign.back() * targets[j]);  // J du = +-du_k
  }
  std::vector<int> stuck;
  std::string why;
  if (int s = FrictionSpeedJump(program_, ws, t, y, speeds, jumps, du, &stuck, &why, &impulse_F_); s != 0) {
    error_ = why.empty() ? rt::ErrorMessage(ws) : why;
    return s;
  }
  // The stops' impulses: (M du)_k on a stop's speed (no friction impulse acts there).
  Eigen::MatrixXd M(nu_, nu_);
  if (int s = rt::MassMatrix(program_, ws, t, y, M.data()); s != 0) return s;
  const Eigen::VectorXd p = M * Eigen::Map<const Eigen::VectorXd>(du, nu_);
  c->resize(rows.size());
  for (size_t j = 0; j < rows.size(); ++j) (*c)[j] = sign[j] * p[speeds[j]];
  error_.clear();
  return 0;
}

// HeldJump's jump with the friction impulses: the resting stops are speed rows (target 0)
// beside the set speeds; one whose impulse would pull leaves (the most pulling first).
int EndStopEvents::HeldJumpMu(rt::Workspace& ws, double t, const double* y, const std::vector<int>& speeds,
                              const std::vector<double>& targets, double* du, std::vector<double>* F) {
  std::vector<int> held;
  for (size_t i = 0; i < sides_.size(); ++i)
    if (sides_[i].resting) held.push_back(static_cast<int>(i));
  for (;;) {
    std::vector<int> rows = speeds;
    std::vector<double> b = targets;
    for (int h : held) {
      const Side& s = sides_[static_cast<size_t>(h)];
      if (s.plane >= 0) {
        error_ = "a jump with a plane contact at rest beside Coulomb friction mu N is not supported";
        return -1;
      }
      rows.push_back(stops_[static_cast<size_t>(s.stop)].u);
      b.push_back(0.0);
    }
    std::vector<int> stuck;
    std::string why;
    if (int s = FrictionSpeedJump(program_, ws, t, y, rows, b, du, &stuck, &why, F); s != 0) {
      error_ = why.empty() ? rt::ErrorMessage(ws) : why;
      return s;
    }
    Eigen::MatrixXd M(nu_, nu_);
    if (int s = rt::MassMatrix(program_, ws, t, y, M.data()); s != 0) return s;
    const Eigen::VectorXd p = M * Eigen::Map<const Eigen::VectorXd>(du, nu_);
    double scale = 0.0;
    for (int k : rows) scale = std::max(scale, std::abs(p[k]));
    size_t pull = held.size();
    double pull_c = 0.0;
    for (size_t h = 0; h < held.size(); ++h) {
      const Side& s = sides_[static_cast<size_t>(held[h])];
      const double c = (s.upper ? -1.0 : 1.0) * p[stops_[static_cast<size_t>(s.stop)].u];
      if (c < -kLeaveRoundoffs * std::numeric_limits<double>::epsilon() * scale && (pull == held.size() || c < pull_c))
        pull = h, pull_c = c;
    }
    if (pull == held.size()) {
      error_.clear();
      return 0;
    }
    sides_[static_cast<size_t>(held[pull])].resting = false;
    sides_[static_cast<size_t>(held[pull])].accumulates_at = 0.0;
    held.erase(held.begin() + static_cast<long>(pull));
  }
}

}  // namespace kanesim::sim
