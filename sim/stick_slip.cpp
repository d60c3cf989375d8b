// Exact Coulomb friction on joints as events (sim/stick_slip.h). With the stuck joints' set
// S fixed and constant friction, Kane's equations with their friction forces tau_S as applied
// forces and the resting stops' reactions are one constrained system,
//   M udot = f + E_S^T tau_S + A^T lambda,   udot_S = 0,   A udot = b                    (2)
// solved from one factorization of M (EndStopEvents::HoldWith; HoldSpeeds without stops).
// With a friction mu N (which reads the joint reactions, so the accelerations are only
// nearly affine in tau_S), and beside constraint rows (CheckRows reads X), the accelerations are
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
// Beside constraint rows: a pivot of X, scaled by the tree's inverse mass (X_kk <= (M^-1)_kk),
// below this is a motion the rows fix (as rt::InverseMassColumn's dead point).
constexpr double kDependent = 1e-10;

// Gaussian elimination with complete pivoting on the m x m row-major A: the index (in A) of
// the first pivot column below tol, or -1 when every pivot is above it.
int FirstDependent(std::vector<double> A, size_t m, double tol) {
  std::vector<size_t> col(m);
  for (size_t k = 0; k < m; ++k) col[k] = k;
  for (size_t k = 0; k < m; ++k) {
    size_t pr = k, pc = k;
    for (size_t r = k; r < m; ++r)
      for (size_t c = k; c < m; ++c)
        if (std::abs(A[r * m + c]) > std::abs(A[pr * m + pc])) pr = r, pc = c;
    if (!(std::abs(A[pr * m + pc]) > tol)) return static_cast<int>(col[k]);
    for (size_t c = 0; c < m; ++c) std::swap(A[k * m + c], A[pr * m + c]);
    for (size_t r = 0; r < m; ++r) std::swap(A[r * m + k], A[r * m + pc]);
    std::swap(col[k], col[pc]);
    for (size_t r = k + 1; r < m; ++r) {
      const double f = A[r * m + k] / A[k * m + k];
      for (size_t c = k; c < m; ++c) A[r * m + c] -= f * A[k * m + c];
    }
  }
  return -1;
}
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
  rows_ = !joints_.empty() && rt::Summarize(program).dof < nu_;
  direct_ = direct_ && !rows_;  // beside rows: Newton (1), whose X CheckRows reads for dependent stuck joints
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
  return j.by_stops || std::find(resting.begin(), resting.end(), j.f.u) != resting.end();
}

int StickSlipEvents::MarkHeldByStops(rt::Workspace& ws, double t, const double* y, double v_rest) {
  for (Joint& j : joints_) j.by_stops = false;
  const std::vector<int> resting = RestingSpeeds();
  if (!rows_ || !stops_ || !stops_->AnyHeld()) return 0;  // (a resting plane contact may fix joints through the rows too)
  Apply(ws);
  std::vector<double> held(ydot_.size()), free(ydot_.size());
  for (Joint& j : joints_) {
    if (HeldByStop(j, resting) || std::abs(y[nq_ + j.f.u]) > v_rest) continue;
    // j's acceleration's response to its own force, with the stops held and without them
    // (by differences, as MakeX): the stops fix it where only the first vanishes.
    const int mode = j.mode;
    double response[2] = {0.0, 0.0};
    for (int with = 0; with < 2; ++with) {
      auto eval = [&](double* out) { return with ? Eval(ws, t, y, out) : rt::Derivative(program_, ws, t, y, out); };
      rt::SetFrictionMode(ws, j.index, 2, 0.0);
      if (int s = eval(held.data()); s != 0) return s;
      double a_max = 0.0;
      for (int i = 0; i < nu_; ++i) a_max = std::max(a_max, std::abs(held[static_cast<size_t>(nq_ + i)]));
      const double step = 1e3 * (1.0 + a_max);
      rt::SetFrictionMode(ws, j.index, 2, step);
      if (int s = eval(free.data()); s != 0) return s;
      response[with] = (free[static_cast<size_t>(nq_ + j.f.u)] - held[static_cast<size_t>(nq_ + j.f.u)]) / step;
    }
    j.mode = mode;
    j.by_stops = response[0] > 0.0 && std::abs(response[1]) <= kDependent * response[0];
    if (j.by_stops) j.mode = 0, j.tau = 0.0;
    Apply(ws);
  }
  return 0;
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
    } else if (j.mode != 0) {  // (beside rows a dependent speed is the evaluation's, not y's)
      g[i] = j.mode * (rows_ ? rt::FrictionSpeed(program_, ws, j.index) : y[nq_ + j.f.u]);
    } else {
      g[i] = StaticBound(ws, j) - std::abs(j.tau);
    }
  }
  return 0;
}

int StickSlipEvents::Decide(rt::Workspace& ws, double t, double* y, Joint& j) {
  const int was = j.mode;
  j.mode = 0;
  if (rows_)
    if (int s = StopOnRows(ws, t, y, j); s != 0) return s;
  y[nq_ + j.f.u] = 0.0;
  char buf[200];
  if (const int c = rows_ ? CheckRows(ws, t, y, j) : 0; c != 0) {
    if (c < 0) return c;
    // The rows fix its motion here (a dead point): it moves on as they drive it.
    j.mode = 1;
    Apply(ws);
    if (int s = Eval(ws, t, y, ydot_.data()); s != 0) return s;
    j.mode = ydot_[static_cast<size_t>(nq_ + j.f.u)] < 0.0 ? -1 : 1;
    std::snprintf(buf, sizeof buf, "slides %s (the constraints fix its motion here: a dead point, no sticking)",
                  j.mode > 0 ? "forwards" : "backwards");
    log_.push_back({t, j.f.joint, buf});
    Apply(ws);
    return 0;
  }
  if (int s = Solve(ws, t, y, nullptr); s != 0) return s;
  const double bound = StaticBound(ws, j);
  if (std::abs(j.tau) <= bound) {
    std::snprintf(buf, sizeof buf, "sticks (friction %.17g within %.17g)", j.tau, bound);
  } else {
    j.mode = j.tau > 0.0 ? -1 : 1;  // it slides where the force it needed pulls it
    std::snprintf(buf, sizeof buf, "%s %s (friction needed %.17g, at most %.17g)",
                  was == 0 ? "slips," : "reverses, slides", j.mode > 0 ? "forwards" : "backwards", j.tau, bound);
  }
  // Sliding on the way it slid: its speed's zero was round-off's (beside rows, a dependent
  // speed just after a slip with zero acceleration), no change of law to log.
  if (was == 0 || j.mode != was) log_.push_back({t, j.f.joint, buf});
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
  // Beside rows j's evaluated speed is the rows' round-off, not y's held zero: zeroed, else
  // where its sliding friction equals the static (a zero acceleration at the slip) that
  // round-off's sign made a second event, a reversal into the same direction.
  if (rows_)
    if (int s = StopOnRows(ws, t, y, j); s != 0) return s;
  j.mode = j.tau > 0.0 ? -1 : 1;
  char buf[200];
  std::snprintf(buf, sizeof buf, "slips, %s (friction needed %.17g, at most %.17g)", j.mode > 0 ? "forwards" : "backwards",
                j.tau, StaticBound(ws, j));
  log_.push_back({t, j.f.joint, buf});
  Apply(ws);
  return 0;
}

int StickSlipEvents::StopOnRows(rt::Workspace& ws, double t, double* y, const Joint& j) {
  // The root leaves j's speed at the tolerance's level, and beside rows zeroing y's entry
  // alone would leave the independent speeds that carry it (a creep): the jump
  // du = W e_j lambda with the rows' reactions (W e_j: the accelerations' response to j's
  // force, by a difference as in MakeX) takes it to zero and keeps the rows.
  Apply(ws);
  if (int s = Eval(ws, t, y, ydot_.data()); s != 0) return s;
  const double u = rt::FrictionSpeed(program_, ws, j.index);
  if (u == 0.0) return 0;
  double a_max = 0.0;
  for (int i = 0; i < nu_; ++i) a_max = std::max(a_max, std::abs(ydot_[static_cast<size_t>(nq_ + i)]));
  const double step = 1e3 * (1.0 + std::abs(j.tau) + a_max);
  rt::SetFrictionMode(ws, j.index, 2, j.tau + step);
  const int s = Eval(ws, t, y, col_.data());
  Apply(ws);
  if (s != 0) return s;
  const double wj = (col_[static_cast<size_t>(nq_ + j.f.u)] - ydot_[static_cast<size_t>(nq_ + j.f.u)]) / step;
  if (!(std::abs(wj) > 0.0)) return 0;  // a dead point: CheckRows decides
  for (int i = 0; i < nu_; ++i)
    y[nq_ + i] -= (col_[static_cast<size_t>(nq_ + i)] - ydot_[static_cast<size_t>(nq_ + i)]) / step * u / wj;
  return 0;
}

int StickSlipEvents::CheckRows(rt::Workspace& ws, double t, const double* y, const Joint& j) {
  std::vector<Joint*> stuck;
  std::vector<int> ids;
  const std::vector<int> resting = RestingSpeeds();
  size_t at = 0;
  for (Joint& k : joints_)
    if (k.mode == 0 && !HeldByStop(k, resting)) {
      if (&k == &j) at = stuck.size();
      stuck.push_back(&k);
      ids.push_back(k.index);
    }
  Apply(ws);
  if (int s = Eval(ws, t, y, ydot_.data()); s != 0) return s;
  if (int s = MakeX(ws, t, y, stuck, ydot_.data()); s != 0) return s;
  x_ids_ = ids;  // Solve goes on from this X
  const size_t m = stuck.size(), nu = static_cast<size_t>(nu_);
  std::vector<double> M(nu * nu), d(m), x;
  if (int s = rt::UnconstrainedMassMatrix(program_, ws, t, y, M.data()); s != 0) return s;
  for (size_t k = 0; k < m; ++k) {  // (M^-1)_kk, the scale of X_kk without the rows
    std::vector<double> e(nu, 0.0);
    e[static_cast<size_t>(stuck[k]->f.u)] = 1.0;
    if (!SolveSmall(M, e, &x)) return -1;
    d[k] = x[static_cast<size_t>(stuck[k]->f.u)];
  }
  std::vector<double> N(m * m);
  for (size_t r = 0; r < m; ++r)
    for (size_t k = 0; k < m; ++k) N[r * m + k] = x_[r * m + k] / std::sqrt(d[r] * d[k]);
  if (!(N[at * m + at] > kDependent)) return 1;
  const int dep = FirstDependent(N, m, kDependent);
  if (dep < 0) return 0;
  std::string who;
  for (size_t k = 0; k < m; ++k) who += (k == 0 ? "'" : k + 1 == m ? "' and '" : "', '") + stuck[k]->f.joint;
  error_ = "joints " + who + "' stick together, but the constraints make their motions dependent ('" +
           stuck[static_cast<size_t>(dep)]->f.joint +
           "' cannot move without the others): the friction forces that hold them are not unique; keep exact "
           "friction on one of them (through a coupling, the other's reflected by the ratio)";
  return -1;
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
  if (stops_) stops_->TakeReleased();  // (a joint pulled off at the start decides below)
  for (Joint& j : joints_) {
    const double u = y0[nq_ + j.f.u];
    j.mode = u > 0.0 ? 1 : u < 0.0 ? -1 : 0;
    j.tau = 0.0;
  }
  if (int s = MarkHeldByStops(ws, t0, y0, 0.0); s != 0) return s;
  const std::vector<int> resting = RestingSpeeds();
  for (Joint& j : joints_)
    if (j.mode == 0 && !HeldByStop(j, resting))
      if (int s = Decide(ws, t0, y0, j); s != 0) return s;
  return 0;
}

int StickSlipEvents::Refresh(rt::Workspace& ws, double t, double* y, const double* y_before, double v_rest) {
  if (int s = MarkHeldByStops(ws, t, y, v_rest); s != 0) return s;
  const std::vector<int> resting = RestingSpeeds();
  // Pulled off its stop beyond the static friction (EndStopEvents::Leave): it slides away,
  // not stuck (a decision at the bound would be round-off's).
  if (stops_)
    for (const auto& [u, dir] : stops_->TakeReleased())
      for (Joint& j : joints_)
        if (j.f.u == u && !HeldByStop(j, resting)) j.mode = dir, j.tau = 0.0;
  std::vector<Joint*> stopped;
  for (Joint& j : joints_) {
    double& u = y[nq_ + j.f.u];
    if (HeldByStop(j, resting)) {
      j.mode = 0, j.tau = 0.0;
    } else if (u == y_before[nq_ + j.f.u]) {
      continue;  // (a joint that has just slipped from rest keeps sliding)
    } else if (j.mode == 0 && std::abs(u) <= v_rest) {
      u = 0.0;  // a rest's impulse on another joint: no real slip
    } else if (std::abs(u) > v_rest) {
      j.mode = u > 0.0 ? 1 : -1;  // a finite friction does not resist an impulse
    } else if (j.mode != 0) {
      stopped.push_back(&j);  // at rest but for round-off (a graze's impulse beside rows): decides
    }
  }
  for (Joint* j : stopped)
    if (int s = Decide(ws, t, y, *j); s != 0) return s;
  Apply(ws);
  return 0;
}

}  // namespace kanesim::sim
