// Exact Coulomb friction on joints as events (sim/stick_slip.h). With the stuck joints' set
// S fixed and constant friction, Kane's equations with their friction forces tau_S as applied
// forces and the resting stops' reactions are one constrained system,
//   M udot = f + E_S^T tau_S + A^T lambda,   udot_S = 0,   A udot = b                    (2)
// solved from one factorization of M (EndStopEvents::HoldWith; HoldSpeeds without stops).
// With a friction mu N (which reads the joint reactions, so the accelerations are only
// nearly affine in tau_S) the accelerations are
//   a_S(tau) = a_S(tau_0) + X (tau - tau_0),  X_jk = d a_j / d tau_k                     (1)
// and one Newton step from the last forces solves a_S = 0; X by differences with steps so
// large that the difference is not lost in the rounding of a (as rt::InverseMassColumn).
// X costs m evaluations; it changes only with q, so it is kept for the same stuck set and
// reused (chord steps) while they bring a_S within kChordTol of zero, else made afresh.
#include "sim/stick_slip.h"

#include "sim/end_stops.h"
#include "sim/impulse.h"  // SolveSmall

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace kanesim::sim {

namespace {
// A chord step is accepted when it leaves every stuck acceleration below this times
// (1 + the largest acceleration): the round-off level of a fresh Newton step, about.
constexpr double kChordTol = 1e-12;
constexpr int kChordSteps = 3;  // chord steps before X is made afresh
}  // namespace

StickSlipEvents::StickSlipEvents(const rt::Program& program) : program_(program) {
  nq_ = rt::NumQ(program);
  nu_ = rt::NumU(program);
  const std::vector<rt::FrictionJoint> all = rt::FrictionJoints(program);
  direct_ = true;
  for (size_t i = 0; i < all.size(); ++i) {
    if (all[i].exact) joints_.push_back({all[i], static_cast<int>(i), 0, 0.0});
    direct_ = direct_ && all[i].mu == 0.0;  // a friction mu N: the accelerations are not affine in tau
  }
  ydot_.resize(static_cast<size_t>(nq_ + nu_));
  col_.resize(ydot_.size());
}

void StickSlipEvents::Apply(rt::Workspace& ws) const {
  for (const Joint& j : joints_) rt::SetFrictionMode(ws, j.index, j.mode == 0 ? 2 : j.mode, j.tau);
}

double StickSlipEvents::StaticBound(const rt::Workspace& ws, const Joint& j) const {
  return j.f.mu_s * j.f.radius * rt::FrictionNormal(ws, j.index) + j.f.c_s;
}

void StickSlipEvents::Sync(rt::Workspace& ws) const { Apply(ws); }

std::vector<int> StickSlipEvents::RestingSpeeds() const { return stops_ ? stops_->RestingSpeeds() : std::vector<int>{}; }

bool StickSlipEvents::HeldByStop(const Joint& j, const std::vector<int>& resting) const {
  return std::find(resting.begin(), resting.end(), j.f.u) != resting.end();
}

int StickSlipEvents::Eval(rt::Workspace& ws, double t, const double* y, double* ydot) {
  if (int s = rt::Derivative(program_, ws, t, y, ydot); s != 0) return s;
  return stops_ ? stops_->Hold(ws, t, y, ydot) : 0;
}

int StickSlipEvents::Solve(rt::Workspace& ws, double t, const double* y, double* ydot) {
  std::vector<Joint*> stuck;
  const std::vector<int> resting = RestingSpeeds();
  for (Joint& j : joints_)
    if (j.mode == 0 && !HeldByStop(j, resting)) stuck.push_back(&j);
  Apply(ws);
  double* out = ydot ? ydot : ydot_.data();
  if (!direct_) return SolveNewton(ws, t, y, out, stuck);
  std::vector<int> speeds;
  for (const Joint* j : stuck) speeds.push_back(j->f.u);
  // The event functions and decisions take one more pass from the solved forces (the same
  // factorization): the round-off of M^-1 left a force needed exactly at its bound an ulp
  // past it, and the joint slipped (the right-hand side zeroes the held rows anyway).
  const int passes = ydot || stuck.empty() ? 1 : 2;
  for (int pass = 0; pass < passes; ++pass) {
    if (int s = rt::Derivative(program_, ws, t, y, out); s != 0) return s;
    std::vector<double> dtau;
    if (stops_) {
      if (int s = stops_->HoldWith(ws, t, y, out, speeds, &dtau); s != 0) return s;
    } else if (!stuck.empty()) {
      if (int s = HoldSpeeds(ws, t, y, speeds, out + nq_, &dtau); s != 0) return s;
    }
    if (stuck.empty()) return 0;
    for (size_t k = 0; k < stuck.size(); ++k) stuck[k]->tau += dtau[k];
    Apply(ws);
  }
  for (const Joint* j : stuck) {  // held exactly
    out[j->f.q] = 0.0;
    out[nq_ + j->f.u] = 0.0;
  }
  return 0;
}

// (2): X = M^-1 [e_k] for the stuck speeds k, then X_SS dtau = -a_S and a += X dtau.
int StickSlipEvents::HoldSpeeds(rt::Workspace& ws, double t, const double* y, const std::vector<int>& speeds, double* a,
                                std::vector<double>* dtau) {
  const size_t m = speeds.size(), nu = static_cast<size_t>(nu_);
  col_.resize(m * nu);
  if (int s = rt::InverseMassColumns(program_, ws, t, y, speeds.data(), static_cast<int>(m), col_.data()); s != 0) return s;
  std::vector<double> A(m * m), rhs(m);
  for (size_t r = 0; r < m; ++r) {
    rhs[r] = -a[speeds[r]];
    for (size_t k = 0; k < m; ++k) A[r * m + k] = col_[k * nu + static_cast<size_t>(speeds[r])];
  }
  if (!SolveSmall(A, rhs, dtau)) return -1;
  for (size_t i = 0; i < nu; ++i)
    for (size_t k = 0; k < m; ++k) a[i] += col_[k * nu + i] * (*dtau)[k];
  return 0;
}

int StickSlipEvents::SolveNewton(rt::Workspace& ws, double t, const double* y, double* out,
                                 const std::vector<Joint*>& stuck) {
  if (int s = Eval(ws, t, y, out); s != 0) return s;
  if (stuck.empty()) return 0;
  const size_t m = stuck.size();
  std::vector<int> ids;
  for (const Joint* j : stuck) ids.push_back(j->index);
  bool fresh = ids != x_ids_;
  std::vector<double> rhs(m), dtau;
  for (int chord = 0;; ++chord) {
    if (fresh)
      if (int s = MakeX(ws, t, y, stuck, out); s != 0) return s;
    x_ids_ = ids;
    for (size_t r = 0; r < m; ++r) rhs[r] = -out[nq_ + stuck[r]->f.u];
    if (!SolveSmall(x_, rhs, &dtau)) return -1;
    for (size_t k = 0; k < m; ++k) stuck[k]->tau += dtau[k];
    Apply(ws);
    if (int s = Eval(ws, t, y, out); s != 0) return s;
    if (fresh) break;  // (1) exact up to round-off
    double residual = 0.0, scale = 1.0;
    for (const Joint* j : stuck) residual = std::max(residual, std::abs(out[nq_ + j->f.u]));
    for (int i = 0; i < nu_; ++i) scale = std::max(scale, 1.0 + std::abs(out[nq_ + i]));
    if (residual <= kChordTol * scale) break;
    fresh = chord + 1 >= kChordSteps;
  }
  for (const Joint* j : stuck) {  // held exactly
    out[j->f.q] = 0.0;
    out[nq_ + j->f.u] = 0.0;
  }
  return 0;
}

int StickSlipEvents::MakeX(rt::Workspace& ws, double t, const double* y, const std::vector<Joint*>& stuck,
                           const double* a0) {
  const size_t m = stuck.size();
  x_.assign(m * m, 0.0);
  double a_max = 0.0;
  for (const Joint* j : stuck) a_max = std::max(a_max, std::abs(a0[nq_ + j->f.u]));
  for (size_t k = 0; k < m; ++k) {  // (1): column k of X
    const double tau0 = stuck[k]->tau, step = 1e3 * (1.0 + std::abs(tau0) + a_max);
    rt::SetFrictionMode(ws, stuck[k]->index, 2, tau0 + step);
    if (int s = Eval(ws, t, y, col_.data()); s != 0) return s;
    rt::SetFrictionMode(ws, stuck[k]->index, 2, tau0);
    for (size_t r = 0; r < m; ++r)
      x_[r * m + k] = (col_[static_cast<size_t>(nq_ + stuck[r]->f.u)] - a0[nq_ + stuck[r]->f.u]) / step;
  }
  return 0;
}

int StickSlipEvents::Rhs(rt::Workspace& ws, double t, const double* y, double* ydot) { return Solve(ws, t, y, ydot); }

int StickSlipEvents::Functions(rt::Workspace& ws, double t, const double* y, double* g) {
  if (int s = Solve(ws, t, y, nullptr); s != 0) return s;
  const std::vector<int> resting = RestingSpeeds();
  for (size_t i = 0; i < joints_.size(); ++i) {
    const Joint& j = joints_[i];
    if (HeldByStop(j, resting)) {
      g[i] = 1.0;  // the stop's: its own event function watches it
    } else if (j.mode != 0) {
      g[i] = j.mode * y[nq_ + j.f.u];
    } else {
      g[i] = StaticBound(ws, j) - std::abs(j.tau);
    }
  }
  return 0;
}

int StickSlipEvents::Decide(rt::Workspace& ws, double t, double* y, Joint& j) {
  y[nq_ + j.f.u] = 0.0;
  const int was = j.mode;
  j.mode = 0;
  if (int s = Solve(ws, t, y, nullptr); s != 0) return s;
  const double bound = StaticBound(ws, j);
  char buf[200];
  if (std::abs(j.tau) <= bound) {
    std::snprintf(buf, sizeof buf, "sticks (friction %.17g within %.17g)", j.tau, bound);
  } else {
    j.mode = j.tau > 0.0 ? -1 : 1;  // it slides where the force it needed pulls it
    std::snprintf(buf, sizeof buf, "%s %s (friction needed %.17g, at most %.17g)",
                  was == 0 ? "slips," : "reverses, slides", j.mode > 0 ? "forwards" : "backwards", j.tau, bound);
  }
  log_.push_back({t, j.f.joint, buf});
  Apply(ws);  // the decided law, for what reads ws next (the stops' Resettle)
  return 0;
}

int StickSlipEvents::Event(rt::Workspace& ws, double t, double* y, int i) {
  if (i < 0 || i >= Count()) return 0;
  Joint& j = joints_[static_cast<size_t>(i)];
  if (j.mode != 0) return Decide(ws, t, y, j);
  // A stuck joint's force needed reached its bound and grows past it: it slips. (Deciding
  // again here found it within the bound by the root's last bits and kept it stuck, with
  // its event function then negative for good.)
  if (int s = Solve(ws, t, y, nullptr); s != 0) return s;
  j.mode = j.tau > 0.0 ? -1 : 1;
  char buf[200];
  std::snprintf(buf, sizeof buf, "slips, %s (friction needed %.17g, at most %.17g)", j.mode > 0 ? "forwards" : "backwards",
                j.tau, StaticBound(ws, j));
  log_.push_back({t, j.f.joint, buf});
  Apply(ws);
  return 0;
}

std::string StickSlipEvents::SettleAt(rt::Workspace& ws, double t, const double* y, double tol) {
  std::vector<double> at(y, y + nq_ + nu_);
  const std::vector<int> resting = RestingSpeeds();
  for (Joint& j : joints_) {
    const double u = at[static_cast<size_t>(nq_ + j.f.u)];
    j.mode = u > tol ? 1 : u < -tol ? -1 : 0;
    j.tau = 0.0;
  }
  for (Joint& j : joints_)
    if (j.mode == 0 && !HeldByStop(j, resting)) {
      if (Decide(ws, t, at.data(), j) != 0) return "the operating point cannot be evaluated: " + rt::ErrorMessage(ws);
      if (j.mode != 0) return "joint '" + j.f.joint + "' is at rest but " + log_.back().kind + ": it slips at once, no smooth state";
    }
  return "";
}

std::vector<int> StickSlipEvents::StuckSpeeds() const {
  std::vector<int> out;
  const std::vector<int> resting = RestingSpeeds();
  for (const Joint& j : joints_)
    if (j.mode == 0 && !HeldByStop(j, resting)) out.push_back(j.f.u);
  return out;
}

std::vector<std::string> StickSlipEvents::StuckNames() const {
  std::vector<std::string> out;
  const std::vector<int> resting = RestingSpeeds();
  for (const Joint& j : joints_)
    if (j.mode == 0 && !HeldByStop(j, resting)) out.push_back(j.f.joint + " stuck");
  return out;
}

int StickSlipEvents::Start(rt::Workspace& ws, double t0, double* y0) {
  const std::vector<int> resting = RestingSpeeds();
  for (Joint& j : joints_) {
    const double u = y0[nq_ + j.f.u];
    j.mode = u > 0.0 ? 1 : u < 0.0 ? -1 : 0;
    j.tau = 0.0;
  }
  for (Joint& j : joints_)
    if (j.mode == 0 && !HeldByStop(j, resting))
      if (int s = Decide(ws, t0, y0, j); s != 0) return s;
  return 0;
}

int StickSlipEvents::Refresh(rt::Workspace& ws, double t, double* y, const double* y_before, double v_rest) {
  const std::vector<int> resting = RestingSpeeds();
  std::vector<Joint*> stopped;
  for (Joint& j : joints_) {
    double& u = y[nq_ + j.f.u];
    if (HeldByStop(j, resting)) {
      j.mode = 0, j.tau = 0.0;
    } else if (u == y_before[nq_ + j.f.u]) {
      continue;  // (a joint that has just slipped from rest keeps sliding)
    } else if (j.mode == 0 && std::abs(u) <= v_rest) {
      u = 0.0;  // a rest's impulse on another joint: no real slip
    } else if (u != 0.0) {
      j.mode = u > 0.0 ? 1 : -1;  // a finite friction does not resist an impulse
    } else if (j.mode != 0) {
      stopped.push_back(&j);
    }
  }
  for (Joint* j : stopped)
    if (int s = Decide(ws, t, y, *j); s != 0) return s;
  Apply(ws);
  return 0;
}

}  // namespace kanesim::sim
