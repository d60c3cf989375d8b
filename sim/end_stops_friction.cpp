// End stops beside Coulomb friction mu N (sim/end_stops.h; docs/events.md "Friction beside
// stops"). Not with plane contacts (the compiler refuses them beside mu).
// Resting: the friction forces follow the joints' normal forces N, N the accelerations, and
// the accelerations the rows' reactions lambda, so the accelerations are not affine in
// lambda. The rows' residual r(lambda) = J a(lambda) + c is brought to zero by the chord
// iteration
//   lambda <- lambda - (J W J^T)^-1 r(lambda)                                            (1)
// W the inverse mass without the friction (M^-1 on a tree, with constraint rows the
// constrained one; exact without mu; with mu it converges at the rate the fixed point of
// runtime/kane/friction.cpp (3) does, each a(lambda) solving that fixed point with lambda
// applied). Impacts: the stops' rows are speed rows (J = +-e_k), so the jump is
// sim/friction_impulse.h's, whose normal impulses carry the stops' and the rows' impulses.
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
  // The chord's columns x_j = W J_j^T: W the inverse mass without the friction, with the
  // constraint rows' reactions where there are rows (the stops' rows are +-e_k).
  Jrows_.assign(m * nu, 0.0);
  x_.assign(m * nu, 0.0);
  std::vector<int> ks(m);
  for (size_t j = 0; j < m; ++j) {
    const Side& s = sides_[static_cast<size_t>(rows[j])];
    if (s.stop < 0) {
      error_ = "a plane contact at rest beside Coulomb friction mu N is not supported";
      return -1;
    }
    ks[j] = stops_[static_cast<size_t>(s.stop)].u;
    Jrows_[j * nu + static_cast<size_t>(ks[j])] = s.upper ? -1.0 : 1.0;
  }
  cols_.resize(m * nu);
  if (int s = rt::FrictionlessInverseMassColumns(program_, ws, t, y, ks.data(), static_cast<int>(m), cols_.data());
      s != 0) {
    error_ = rt::ErrorMessage(ws);
    return s;
  }
  for (size_t j = 0; j < m; ++j)
    for (size_t k = 0; k < nu; ++k) x_[j * nu + k] = Jrows_[j * nu + static_cast<size_t>(ks[j])] * cols_[j * nu + k];
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

// The rows J (m x nu) of the sides `rows` (stops: +-e_k) and of the set speeds `speeds` (e_k,
// first); false with error_ for a plane contact (refused beside mu by the compiler).
bool EndStopEvents::SpeedRowsMu(const std::vector<int>& speeds, const std::vector<int>& rows, std::vector<double>* J) {
  const size_t nu = static_cast<size_t>(nu_), n = speeds.size();
  J->assign((n + rows.size()) * nu, 0.0);
  for (size_t j = 0; j < n; ++j) (*J)[j * nu + static_cast<size_t>(speeds[j])] = 1.0;
  for (size_t j = 0; j < rows.size(); ++j) {
    const Side& s = sides_[static_cast<size_t>(rows[j])];
    if (s.plane >= 0) {
      error_ = "a plane contact beside Coulomb friction mu N is not supported";
      return false;
    }
    (*J)[(n + j) * nu + static_cast<size_t>(stops_[static_cast<size_t>(s.stop)].u)] = s.upper ? -1.0 : 1.0;
  }
  return true;
}

// The friction impulse law's jump (sim/friction_impulse.h) with the stops' rows: in a tree
// and beside constraint rows alike (their impulses in the joints' normal impulses).
int EndStopEvents::ImpulseMu(rt::Workspace& ws, double t, const double* y, const std::vector<int>& rows,
                             const std::vector<double>& targets, double* du, std::vector<double>* c) {
  std::vector<double> J;
  if (!SpeedRowsMu({}, rows, &J)) return -1;
  FrictionJumpResult res;
  std::string why;
  if (int s = FrictionJump(program_, ws, t, y, J, targets, &res, &why); s != 0) {
    error_ = why.empty() ? rt::ErrorMessage(ws) : why;
    return s;
  }
  std::copy(res.du.begin(), res.du.end(), du);
  *c = res.impulse;
  error_.clear();
  return 0;
}

// HeldJump's jump with the friction impulses: the resting stops are rows (target 0) beside
// the set speeds; one whose impulse would pull leaves (the most pulling first).
int EndStopEvents::HeldJumpMu(rt::Workspace& ws, double t, const double* y, const std::vector<int>& speeds,
                              const std::vector<double>& targets, double* du) {
  std::vector<int> held;
  for (size_t i = 0; i < sides_.size(); ++i)
    if (sides_[i].resting) held.push_back(static_cast<int>(i));
  const size_t n = speeds.size();
  for (;;) {
    std::vector<double> J, b = targets;
    if (!SpeedRowsMu(speeds, held, &J)) return -1;
    b.resize(n + held.size(), 0.0);
    FrictionJumpResult res;
    std::string why;
    if (int s = FrictionJump(program_, ws, t, y, J, b, &res, &why); s != 0) {
      error_ = why.empty() ? rt::ErrorMessage(ws) : why;
      return s;
    }
    std::copy(res.du.begin(), res.du.end(), du);
    double scale = 0.0;
    for (double v : res.impulse) scale = std::max(scale, std::abs(v));
    size_t pull = held.size();
    for (size_t h = 0; h < held.size(); ++h) {
      const double c = res.impulse[n + h];
      if (c < -kLeaveRoundoffs * std::numeric_limits<double>::epsilon() * scale &&
          (pull == held.size() || c < res.impulse[n + pull]))
        pull = h;
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
