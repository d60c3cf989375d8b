// End stops and plane contacts beside Coulomb friction mu N (sim/end_stops.h; docs/events.md
// "Friction beside stops"), in trees and beside constraint rows (closed loops, couplings,
// rolling contacts).
// Resting: the friction forces follow the joints' normal forces N, N the accelerations and
// the reactions (a plane contact's force acts at its point, so the joints between it and the
// ground carry it: rt::DerivativeWithPlaneForces), and the accelerations the rows' reactions
// lambda, so the accelerations are not affine in lambda. The rows' residual
// r(lambda) = J a(lambda) + c is brought to zero by the chord iteration
//   lambda <- lambda - (J W J^T)^-1 r(lambda)                                            (1)
// W the inverse mass without the friction (M^-1 on a tree, with constraint rows the
// constrained one; exact without mu; with mu it converges at the rate the fixed point of
// runtime/kane/friction.cpp (3) does, each a(lambda) solving that fixed point with lambda
// applied; where its residual flips sign it overshoots, and its step is relaxed). Impacts
// and jumps: sim/friction_impulse.h's law, whose normal impulses carry the stops' (along
// their joints: none across) and the plane contacts' impulses.
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>

#include "sim/end_stops.h"
#include "sim/friction_impulse.h"
#include "sim/impulse.h"  // SolveHeld

namespace kanesim::sim {

namespace {
constexpr double kTol = 1e-11;  // residual / (1 + largest |a|): a few times the fixed point's
// (1) converges at the friction's gain, which nears 1 where mu r is large (0.923 per
// iteration, ~300 iterations, in a chain of 4 with mu r = 0.1 m: issue 41, where a cap of 60
// stopped the run with exit 2 in every integrator). So it runs while the residual shrinks:
// by kShrink at least over each kWindow iterations (a gain below ~0.99), at most kMaxIterations.
constexpr int kMaxIterations = 2000;
constexpr int kWindow = 10;
constexpr double kShrink = 0.9;
constexpr double kMinRelax = 1.0 / 64;
}  // namespace

int EndStopEvents::ReactionsMu(rt::Workspace& ws, double t, const double* y, const std::vector<int>& rows,
                               const std::vector<double>& bias, std::vector<double>* c, double* a) {
  const size_t m = rows.size(), nu = static_cast<size_t>(nu_);
  std::copy(ydot_.begin() + nq_, ydot_.end(), a_.begin());  // the free accelerations (ReactionNoise)
  // The chord's columns x_j = W J_j^T: W the inverse mass without the friction, with the
  // constraint rows' reactions where there are rows (a stop's row is +-e_k: a column of W; a
  // plane contact's W J^T from all of W's columns in a tree, by rt::FrictionlessInverseMassTimes
  // with rows).
  Jrows_.assign(m * nu, 0.0);
  x_.assign(m * nu, 0.0);
  bool planes = false;
  for (size_t j = 0; j < m; ++j) {
    double gap = 0.0, cj = 0.0;
    const Side& s = sides_[static_cast<size_t>(rows[j])];
    if (int st = Row(ws, t, y, s, &gap, Jrows_.data() + j * nu, &cj); st != 0) return st;
    planes = planes || s.plane >= 0;
  }
  std::vector<int> ks;
  if (planes && !program_.rows.empty()) {  // W J^T for each row: one constrained inverse mass a row
    for (size_t j = 0; j < m; ++j)
      if (int s = rt::FrictionlessInverseMassTimes(program_, ws, t, y, Jrows_.data() + j * nu, x_.data() + j * nu);
          s != 0) {
        error_ = rt::ErrorMessage(ws);
        return s;
      }
  } else if (planes) {
    for (int k = 0; k < nu_; ++k) ks.push_back(k);
  } else {
    for (int r : rows) ks.push_back(stops_[static_cast<size_t>(sides_[static_cast<size_t>(r)].stop)].u);
  }
  cols_.resize(ks.size() * nu);
  if (int s = rt::FrictionlessInverseMassColumns(program_, ws, t, y, ks.data(), static_cast<int>(ks.size()), cols_.data());
      s != 0) {
    error_ = rt::ErrorMessage(ws);
    return s;
  }
  for (size_t j = 0; j < m && !ks.empty(); ++j)
    for (size_t c2 = 0; c2 < ks.size(); ++c2) {
      const double Jk = planes ? Jrows_[j * nu + c2] : (c2 == j ? Jrows_[j * nu + static_cast<size_t>(ks[j])] : 0.0);
      if (Jk != 0.0)
        for (size_t k = 0; k < nu; ++k) x_[j * nu + k] += Jk * cols_[c2 * nu + k];
    }
  std::vector<double> A(m * m), r(m), dc, F(nu), yd(ydot_.size());
  for (size_t i = 0; i < m; ++i)
    for (size_t j = 0; j < m; ++j) {
      double s = 0.0;
      for (size_t k = 0; k < nu; ++k) s += Jrows_[i * nu + k] * x_[j * nu + k];
      A[i * m + j] = s;
    }
  c->assign(m, 0.0);
  std::vector<double> lambda(planes_.size());  // the plane contacts' forces, applied at their points
  double r_window = HUGE_VAL;  // the residual kWindow iterations ago
  // The step of (1) relaxed by w where it overshoots: the leading row's residual flipping
  // sign at most iterations of a window that did not shrink (sweep seeds 44 and 48: one stop
  // row, the chord 2-cycling at a gain of -1.02 and erratically; exit 2 in all five
  // integrators). w is halved down to kMinRelax; a residual keeping its sign is not helped.
  double w = 1.0, lead_r = 0.0;
  size_t lead = 0;
  int flips = 0;
  for (int it = 0; it < kMaxIterations; ++it) {
    std::fill(F.begin(), F.end(), 0.0);
    std::fill(lambda.begin(), lambda.end(), 0.0);
    for (size_t j = 0; j < m; ++j) {
      const Side& s = sides_[static_cast<size_t>(rows[j])];
      if (s.plane >= 0) lambda[static_cast<size_t>(s.plane)] = (*c)[j];
      else
        for (size_t k = 0; k < nu; ++k) F[k] += (*c)[j] * Jrows_[j * nu + k];
    }
    // (with only stops' rows: DerivativeWithForces, which takes constraint rows too)
    if (int s = planes ? rt::DerivativeWithPlaneForces(program_, ws, t, y, F.data(), lambda.data(), yd.data())
                       : rt::DerivativeWithForces(program_, ws, t, y, F.data(), yd.data());
        s != 0)
      return s;
    const double* acc = yd.data() + nq_;
    double r_max = 0.0, scale = 1.0;
    size_t next_lead = 0;
    for (size_t j = 0; j < m; ++j) {
      r[j] = -bias[j];
      for (size_t k = 0; k < nu; ++k) r[j] -= Jrows_[j * nu + k] * acc[k];
      if (std::abs(r[j]) > r_max) next_lead = j;
      r_max = std::max(r_max, std::abs(r[j]));
    }
    if (it > 0 && r[lead] * lead_r < 0.0) {
      // Alternating: the chord overshoots. Its gain g along the leading row, from this
      // residual over the last (rho = 1 + w (g - 1)), gives the step that would remove that
      // mode, w / (1 - rho) (the secant step on one row; with several rows each mode's rate
      // stays below 1 in size when g is the most negative gain).
      ++flips;
      w = std::clamp(w / (1.0 - r[lead] / lead_r), kMinRelax, 1.0);
    }
    lead = next_lead;
    lead_r = r[lead];
    for (size_t k = 0; k < nu; ++k) scale = std::max(scale, 1.0 + std::abs(acc[k]));
    if (r_max <= kTol * scale) {
      std::copy(acc, acc + nu_, a);
      error_.clear();
      return 0;
    }
    if (it % kWindow == 0) {
      const bool overshoots = 2 * flips > kWindow && w > kMinRelax;
      flips = 0;
      if (!(r_max < kShrink * r_window)) {  // not shrinking (NaN too)
        if (!overshoots || !std::isfinite(r_max)) break;
        w *= 0.5;
      }
      r_window = r_max;
    }
    if (!SolveHeld(A, r, &dc, nullptr, kTol * scale)) {  // (dependent rows: the least correction)
      error_ = SingularRows(rows);
      return -1;
    }
    for (size_t j = 0; j < m; ++j) (*c)[j] += w * dc[j];  // (1), relaxed
  }
  ws.error = "the resting contacts' reactions with Coulomb friction mu N did not converge (self-locking joint?)";
  return 1;  // recoverable: the integrator retries with a smaller step
}

// The sides `rows` as FrictionJump's rows, appended to *J (row-major, nu columns): a stop's
// +-e_k, a plane contact's J; *row_normals (3 nf per row): a plane's impulse, acting at its
// point, in the normal impulses of the joints between it and the ground (a stop's: none).
int EndStopEvents::JumpRows(rt::Workspace& ws, double t, const double* y, const std::vector<int>& rows,
                            std::vector<double>* J, std::vector<double>* row_normals) {
  const size_t nu = static_cast<size_t>(nu_), nf = 3 * rt::FrictionJoints(program_).size();
  for (int i : rows) {
    const Side& s = sides_[static_cast<size_t>(i)];
    J->resize(J->size() + nu, 0.0);
    row_normals->resize(row_normals->size() + nf, 0.0);
    double gap = 0.0, c = 0.0;
    if (int st = Row(ws, t, y, s, &gap, J->data() + J->size() - nu, &c); st != 0) return st;
    if (s.plane < 0) continue;
    std::vector<double> Lambda(planes_.size(), 0.0);
    Lambda[static_cast<size_t>(s.plane)] = 1.0;
    if (int st = rt::PlaneImpulseNormals(program_, ws, t, y, Lambda.data(), row_normals->data() + row_normals->size() - nf);
        st != 0)
      return st;
  }
  return 0;
}

int EndStopEvents::ImpulseMu(rt::Workspace& ws, double t, const double* y, const std::vector<int>& rows,
                             const std::vector<double>& targets, double* du, std::vector<double>* c) {
  std::vector<double> J, row_normals;
  if (int s = JumpRows(ws, t, y, rows, &J, &row_normals); s != 0) return s;
  FrictionJumpResult jump;
  std::string why;
  if (int s = FrictionJump(program_, ws, t, y, J, targets, &jump, &why, row_normals); s != 0) {
    error_ = why.empty() ? rt::ErrorMessage(ws) : why;
    return s;
  }
  std::copy(jump.du.begin(), jump.du.end(), du);
  impulse_F_ = jump.generalized;
  *c = jump.impulse;  // (a side's row pushes with c > 0)
  error_.clear();
  return 0;
}

// HeldJump's jump with the friction impulses: the resting sides are rows (target 0) beside the
// set speeds; one whose impulse would pull leaves (the most pulling first).
int EndStopEvents::HeldJumpMu(rt::Workspace& ws, double t, const double* y, const std::vector<int>& speeds,
                              const std::vector<double>& targets, double* du, std::vector<double>* F) {
  const size_t n = speeds.size(), nu = static_cast<size_t>(nu_), nf = 3 * rt::FrictionJoints(program_).size();
  std::vector<int> held;
  for (size_t i = 0; i < sides_.size(); ++i)
    if (sides_[i].resting) held.push_back(static_cast<int>(i));
  for (;;) {
    std::vector<double> J(n * nu, 0.0), row_normals(n * nf, 0.0), b = targets;
    for (size_t j = 0; j < n; ++j) J[j * nu + static_cast<size_t>(speeds[j])] = 1.0;
    if (int s = JumpRows(ws, t, y, held, &J, &row_normals); s != 0) return s;
    b.resize(n + held.size(), 0.0);
    FrictionJumpResult jump;
    std::string why;
    if (int s = FrictionJump(program_, ws, t, y, J, b, &jump, &why, row_normals); s != 0) {
      error_ = why.empty() ? rt::ErrorMessage(ws) : why;
      return s;
    }
    std::copy(jump.du.begin(), jump.du.end(), du);
    double scale = 0.0;
    for (double v : jump.impulse) scale = std::max(scale, std::abs(v));
    const double* c = jump.impulse.data() + n;
    size_t pull = held.size();
    for (size_t h = 0; h < held.size(); ++h)
      if (c[h] < -kLeaveRoundoffs * std::numeric_limits<double>::epsilon() * scale && (pull == held.size() || c[h] < c[pull]))
        pull = h;
    if (pull == held.size()) {
      if (F) *F = jump.generalized;
      error_.clear();
      return 0;
    }
    sides_[static_cast<size_t>(held[pull])].resting = false;
    sides_[static_cast<size_t>(held[pull])].accumulates_at = 0.0;
    held.erase(held.begin() + static_cast<long>(pull));
  }
}

}  // namespace kanesim::sim
