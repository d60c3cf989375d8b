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
//
// Beside rows the stuck speeds may be dependent: a geared pair's two joints, each with
// friction (u_2 = k u_1 by the coupling), a four-bar's crank and rocker (one degree of
// freedom). Their rows u_S = 0 and A u = 0 are then dependent (X singular) and the forces
// that hold them not unique. Where u_p = k_p u_l for every motion the rows allow, the
// forces' power is (tau_l + sum_p k_p tau_p) u_l: only
//   T = tau_l + sum_p k_p tau_p,   and the group sticks while   |T| <= B_g = B_l + sum_p |k_p| B_p   (4)
// (each k_p tau_p ranges over [-|k_p| B_p, |k_p| B_p], B = mu_s r N + C_s: some split holds
// the group exactly then). The stuck set is reduced to independent leaders l (greedy in the
// joints' order, on X scaled by the tree's inverse mass: a Schur complement below kDependent
// is a dependent speed, k_p = (X_pL X_LL^-1)_l) whose rows hold T as one reaction; each
// member carries the same fraction |T| / B_g of its bound, tau_l = T B_l / B_g and
// tau_p = sign(k_p) T B_p / B_g. Where |T| reaches B_g the group slips together, each
// passenger the way its ratio takes it; a sliding joint whose speed the rows tie to stuck
// ones is at rest with them and joins. Exact with constant friction and wherever N does not
// depend on the split (a coupling's reaction acts along the joints' axes, not across them);
// in a closed loop with mu N the split moves the loop's forces and so the N's: B_g is then
// that of the equal-fraction split (another split could hold a little longer). A speed tied
// to two groups' leaders (a differential) is not solved: exit 2, naming the joints.
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
// A sliding joint's stop this close to its own slip (relative to max(1, |t|)) is its echo
// (Switch): the solver's error on a speed that starts from rest with no acceleration.
constexpr double kSlipEcho = 1e-9;
// (1) with a friction mu N: Newton steps at most, the residual accepted at the mu N
// iteration's noise (runtime/kane/friction.cpp kTol, through gains near 1), and X's
// difference step per unit of (1 + |tau| + |a|max): small against N's curvature, large
// against that noise (the step of 1e3 of the affine case left X a secant).
constexpr int kNewtonSteps = 20;
constexpr double kNewtonNoise = 1e-9;
constexpr double kStepMuN = 1e-3;
// Beside constraint rows: a pivot of X, scaled by the tree's inverse mass (X_kk <= (M^-1)_kk),
// below this is a motion the rows fix (as rt::InverseMassColumn's dead point).
constexpr double kDependent = 1e-10;
// (4): a dependent speed's scaled ratio to a leader's ((X_pL X_LL^-1)_l on the scaled X)
// above this ties it to that leader; the differences' round-off leaves ~1e-13.
constexpr double kTied = 1e-8;
}  // namespace

StickSlipEvents::StickSlipEvents(const rt::Program& program) : program_(program) {
  nq_ = rt::NumQ(program);
  nu_ = rt::NumU(program);
  const std::vector<rt::FrictionJoint> all = rt::FrictionJoints(program);
  direct_ = true;
  for (size_t i = 0; i < all.size(); ++i) {
    if (all[i].exact) joints_.push_back({all[i], static_cast<int>(i), 0, 0.0});
    direct_ = direct_ && all[i].mu == 0.0;  // a friction mu N: the accelerations are not affine in tau
    reads_N_ = reads_N_ || all[i].mu != 0.0;
  }
  ydot_.resize(static_cast<size_t>(nq_ + nu_));
  col_.resize(ydot_.size());
  dof_ = rt::Summarize(program).dof;
  rows_ = !joints_.empty() && dof_ < nu_;
  scleronomic_ = program.q_prescribed.empty();
  direct_ = direct_ && !rows_;  // beside rows: Newton (1), whose X CheckRows reads for dependent stuck joints
}

void StickSlipEvents::Apply(rt::Workspace& ws) const {
  for (const Joint& j : joints_)
    rt::SetFrictionMode(ws, j.index, j.mode == 0 ? 2 : j.mode, j.mode == 0 ? Applied(ws, j) : j.tau);
}

double StickSlipEvents::StaticBound(const rt::Workspace& ws, const Joint& j) const {
  return j.f.mu_s * j.f.radius * rt::FrictionNormal(ws, j.index) + j.f.c_s;
}

bool StickSlipEvents::Leads(const Joint& j) const {
  if (!grouped_) return false;
  const int i = static_cast<int>(&j - joints_.data());
  for (const Joint& p : joints_)
    if (p.leader == i) return true;
  return false;
}

double StickSlipEvents::GroupBound(const rt::Workspace& ws, const Joint& l) const {
  double B = StaticBound(ws, l);  // (4)
  const int i = static_cast<int>(&l - joints_.data());
  for (const Joint& p : joints_)
    if (grouped_ && p.leader == i) B += std::abs(p.ratio) * StaticBound(ws, p);
  return B;
}

double StickSlipEvents::Applied(const rt::Workspace& ws, const Joint& j) const {
  if (!grouped_) return j.tau;
  if (j.leader >= 0) {  // (4): tau_p = sign(k_p) T B_p / B_g
    const Joint& l = joints_[static_cast<size_t>(j.leader)];
    const double B = GroupBound(ws, l);
    return B > 0.0 ? l.tau * (j.ratio < 0.0 ? -1.0 : 1.0) * StaticBound(ws, j) / B : 0.0;
  }
  if (!Leads(j)) return j.tau;
  const double B = GroupBound(ws, j);  // (4): tau_l = T B_l / B_g
  return B > 0.0 ? j.tau * StaticBound(ws, j) / B : j.tau;
}

void StickSlipEvents::Ungroup() {
  const std::vector<int> resting = RestingSpeeds();
  grouped_ = false;
  for (Joint& p : joints_) {
    if (p.leader < 0) continue;
    const Joint& l = joints_[static_cast<size_t>(p.leader)];
    if (p.mode != 0 || l.mode != 0 || l.leader >= 0 || HeldByStop(l, resting) || HeldByStop(p, resting)) p.leader = -1;
    grouped_ = grouped_ || p.leader >= 0;
  }
}

void StickSlipEvents::SettleGroup(const rt::Workspace& ws, double t, Joint& l, const std::vector<int>& before,
                                  const Joint* j) {
  const int li = static_cast<int>(&l - joints_.data());
  std::vector<Joint*> group{&l};
  for (Joint& p : joints_)
    if (grouped_ && p.leader == li) group.push_back(&p);
  const double T = l.tau, B = GroupBound(ws, l);
  for (Joint* k : group) {
    const double r = k == &l ? 1.0 : k->ratio;  // u_k = r u_l, so T and B_g reflected onto k: / r
    if (k != &l) k->mode = l.mode == 0 ? 0 : (r < 0.0 ? -l.mode : l.mode);
    const bool undecided = k->stamp == 0;  // (at the start: its first law)
    k->stamp = decisions_;
    const int was = before[static_cast<size_t>(k - joints_.data())];
    // Sliding on the way it slid: its speed's zero was round-off's (beside rows, a dependent
    // speed just after a slip with zero acceleration), no change of law to log.
    if (!(k == j ? was == 0 || k->mode != was : k->mode != was || undecided)) continue;
    std::string with;
    for (const Joint* o : group)
      if (o != k) with += (with.empty() ? "; held as one with '" : "', '") + o->f.joint;
    if (!with.empty()) with += "' (the constraints tie their speeds)";
    char buf[400];
    if (k->mode == 0)
      std::snprintf(buf, sizeof buf, "sticks (friction %.17g within %.17g%s)", T / r, B / std::abs(r), with.c_str());
    else
      std::snprintf(buf, sizeof buf, "%s %s (friction needed %.17g, at most %.17g%s)",
                    was == 0 ? "slips," : "reverses, slides", k->mode > 0 ? "forwards" : "backwards", T / r,
                    B / std::abs(r), with.c_str());
    log_.push_back({t, k->f.joint, buf});
  }
  if (l.mode != 0 && group.size() > 1) {
    for (Joint* k : group) k->leader = -1;
    Ungroup();
  }
}

void StickSlipEvents::Sync(rt::Workspace& ws) const { Apply(ws); }

std::vector<int> StickSlipEvents::RestingSpeeds() const { return stops_ ? stops_->RestingSpeeds() : std::vector<int>{}; }

bool StickSlipEvents::AllHeld() const {
  if (!rows_ || !scleronomic_) return false;
  const std::vector<int> resting = RestingSpeeds();
  int held = static_cast<int>(resting.size());
  for (const Joint& j : joints_)
    held += j.mode == 0 && j.leader < 0 && !HeldByStop(j, resting) ? 1 : 0;
  return held >= dof_;
}

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
    if (j.by_stops) j.mode = 0, j.tau = 0.0, j.leader = -1;
    Apply(ws);
  }
  return 0;
}

int StickSlipEvents::Eval(rt::Workspace& ws, double t, const double* y, double* ydot) {
  if (int s = rt::Derivative(program_, ws, t, y, ydot); s != 0) return s;
  NoteSpeeds(ws);
  return stops_ ? stops_->Hold(ws, t, y, ydot) : 0;
}

void StickSlipEvents::NoteSpeeds(const rt::Workspace& ws) {
  if (!rows_) return;
  u_eval_.resize(joints_.size());
  for (size_t i = 0; i < joints_.size(); ++i) u_eval_[i] = rt::FrictionSpeed(program_, ws, joints_[i].index);
}

int StickSlipEvents::Solve(rt::Workspace& ws, double t, const double* y, double* ydot) {
  if (grouped_) Ungroup();
  std::vector<Joint*> stuck;  // their rows: the passengers' speeds follow their leaders' (4)
  const std::vector<int> resting = RestingSpeeds();
  for (Joint& j : joints_)
    if (j.mode == 0 && !HeldByStop(j, resting) && j.leader < 0) stuck.push_back(&j);
  Apply(ws);
  double* out = ydot ? ydot : ydot_.data();
  if (!direct_) {
    const int s = SolveNewton(ws, t, y, out, stuck);
    for (const Joint& p : joints_)
      if (s == 0 && p.leader >= 0) out[p.f.q] = 0.0, out[nq_ + p.f.u] = 0.0;  // held exactly with their leader
    return s;
  }
  std::vector<int> speeds;
  for (const Joint* j : stuck) speeds.push_back(j->f.u);
  // The event functions and decisions take one more pass from the solved forces (the same
  // factorization): the round-off of M^-1 left a force needed exactly at its bound an ulp
  // past it, and the joint slipped (the right-hand side zeroes the held rows anyway).
  const int passes = ydot || stuck.empty() ? 1 : 2;
  for (int pass = 0; pass < passes; ++pass) {
    if (int s = rt::Derivative(program_, ws, t, y, out); s != 0) return s;
    NoteSpeeds(ws);
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
  // Newton (1) with X made afresh every kChordSteps steps, until the stuck accelerations are
  // within kChordTol: with a friction mu N they are only nearly affine in tau, and X by a
  // difference over a step of 1e3 N m was a secant, not a slope. One such step left them
  // ~1e-3 from zero and the forces ~4e-5 off, by an amount that depended on the last call's
  // forces: the right-hand side depended on its history, CVODE-BDF's difference-quotient
  // Jacobian of it was garbage, and it froze a slipping joint's speed near zero (a silent
  // 42.9 J instead of 23.4 J: issue 41). Where the mu N iteration's own tolerance leaves
  // noise above kChordTol (~1e-11 of the accelerations), a step that no longer halves the
  // residual ends it within kNewtonNoise; a residual above that is a failure (recoverable).
  double residual = HUGE_VAL, scale = 1.0;
  for (int step = 0, chord = 0;; ++step, ++chord) {
    if (fresh) {
      if (int s = MakeX(ws, t, y, stuck, out); s != 0) return s;
      chord = 0;
    }
    x_ids_ = ids;
    for (size_t r = 0; r < m; ++r) rhs[r] = -out[nq_ + stuck[r]->f.u];
    if (!SolveSmall(x_, rhs, &dtau)) return -1;
    for (size_t k = 0; k < m; ++k) stuck[k]->tau += dtau[k];
    Apply(ws);
    if (int s = Eval(ws, t, y, out); s != 0) return s;
    const double last = residual;
    residual = 0.0, scale = 1.0;
    for (const Joint* j : stuck) residual = std::max(residual, std::abs(out[nq_ + j->f.u]));
    for (int i = 0; i < nu_; ++i) scale = std::max(scale, 1.0 + std::abs(out[nq_ + i]));
    if (residual <= kChordTol * scale) break;
    if (residual <= kNewtonNoise * scale && residual > 0.5 * last) break;  // (the noise floor)
    if (step + 1 >= kNewtonSteps) {
      char buf[300];
      std::snprintf(buf, sizeof buf,
                    "the stuck joints' friction forces did not converge (their accelerations %.3g from zero after %d "
                    "Newton steps)",
                    residual, kNewtonSteps);
      error_ = buf;
      return 1;  // (recoverable: the integrator retries with a smaller step)
    }
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
    const double tau0 = Applied(ws, *stuck[k]), step = (reads_N_ ? kStepMuN : 1e3) * (1.0 + std::abs(tau0) + a_max);
    rt::SetFrictionMode(ws, stuck[k]->index, 2, tau0 + step);
    if (int s = Eval(ws, t, y, col_.data()); s != 0) return s;
    rt::SetFrictionMode(ws, stuck[k]->index, 2, tau0);
    for (size_t r = 0; r < m; ++r)
      x_[r * m + k] = (col_[static_cast<size_t>(nq_ + stuck[r]->f.u)] - a0[nq_ + stuck[r]->f.u]) / step;
  }
  return 0;
}

int StickSlipEvents::Rhs(rt::Workspace& ws, double t, const double* y, double* ydot) {
  error_.clear();  // (a recoverable failure's cause is the last call's only)
  return Solve(ws, t, y, ydot);
}

int StickSlipEvents::Functions(rt::Workspace& ws, double t, const double* y, double* g) {
  if (int s = Solve(ws, t, y, nullptr); s != 0) return s;
  const std::vector<int> resting = RestingSpeeds();
  for (size_t i = 0; i < joints_.size(); ++i) {
    const Joint& j = joints_[i];
    if (HeldByStop(j, resting) || j.leader >= 0) {
      g[i] = 1.0;  // the stop's, or a passenger (4): its own, or its leader's, event function watches it
    } else if (j.mode != 0) {  // (beside rows a dependent speed is the evaluation's, not y's)
      g[i] = j.mode * (rows_ ? u_eval_[i] : y[nq_ + j.f.u]);
    } else {
      g[i] = GroupBound(ws, j) - std::abs(j.tau);
    }
  }
  return 0;
}

void StickSlipEvents::Guards(double* g) const {
  const std::vector<int> resting = RestingSpeeds();
  for (size_t i = 0; i < joints_.size(); ++i) {
    const Joint& j = joints_[i];
    const bool watched = j.mode != 0 && !rows_ && j.leader < 0 && !HeldByStop(j, resting);
    g[i] = watched ? -j.mode * ydot_[static_cast<size_t>(nq_ + j.f.u)] : 1.0;
  }
}

int StickSlipEvents::Decide(rt::Workspace& ws, double t, double* y, Joint& j) {
  std::vector<int> before;  // the laws before: SettleGroup logs the members' changes
  for (const Joint& k : joints_) before.push_back(k.mode);
  j.mode = 0;
  j.leader = -1;
  j.stamp = ++decisions_;
  if (rows_)
    if (int s = StopOnRows(ws, t, y, j); s != 0) return s;
  y[nq_ + j.f.u] = 0.0;
  if (const int c = rows_ ? CheckRows(ws, t, y, j) : 0; c != 0) {
    if (c < 0) return c;
    // The rows fix its motion here (a dead point): it moves on as they drive it.
    j.mode = 1;
    Apply(ws);
    if (int s = Eval(ws, t, y, ydot_.data()); s != 0) return s;
    j.mode = ydot_[static_cast<size_t>(nq_ + j.f.u)] < 0.0 ? -1 : 1;
    char buf[200];
    std::snprintf(buf, sizeof buf, "slides %s (the constraints fix its motion here: a dead point, no sticking)",
                  j.mode > 0 ? "forwards" : "backwards");
    log_.push_back({t, j.f.joint, buf});
    Apply(ws);
    return 0;
  }
  if (int s = Solve(ws, t, y, nullptr); s != 0) return s;
  // (4): j's group (j alone without rows tying it) sticks while its force is within B_g, else
  // slides where the force it needed pulls it.
  Joint& l = j.leader >= 0 ? joints_[static_cast<size_t>(j.leader)] : j;
  if (std::abs(l.tau) > GroupBound(ws, l)) l.mode = l.tau > 0.0 ? -1 : 1;
  if (l.mode == 0)
    for (const Joint& k : joints_)  // a sliding member pulled in is at rest exactly, as j
      if (&k == &l || (k.leader >= 0 && &joints_[static_cast<size_t>(k.leader)] == &l)) y[nq_ + k.f.u] = 0.0;
  if (l.mode == 0 && AllHeld()) std::fill(y + nq_, y + nq_ + nu_, 0.0);  // the whole mechanism at rest
  SettleGroup(ws, t, l, before, &j);
  Apply(ws);  // the decided law, for what reads ws next (the stops' Resettle)
  return 0;
}

int StickSlipEvents::Event(rt::Workspace& ws, double t, double* y, int i) {
  if (i < 0 || i >= Count()) return 0;
  const long from = decisions_;
  const Joint& j = joints_[static_cast<size_t>(i)];
  const bool slip = j.mode == 0 && j.leader < 0;  // (its force leaves its bound: it cannot stick again here)
  if (int s = Switch(ws, t, y, i); s != 0) return s;
  return CheckLaws(ws, t, y, from, slip && j.mode != 0 ? &j : nullptr);  // (the others at rest, with j's new law)
}

int StickSlipEvents::Switch(rt::Workspace& ws, double t, double* y, int i) {
  Joint& j = joints_[static_cast<size_t>(i)];
  if (j.leader >= 0) return 0;  // a passenger: its leader's function watches it (4)
  // A stop found within kSlipEcho of the joint's own slip: where the force needed passed
  // its bound with the acceleration after the slip ~0, the speed's first steps are the
  // solver's error, and its event function or graze guard found a stop 3e-14 s later
  // (ARKODE); deciding then stuck it at its bound, where its stuck function starts at zero
  // and its next slip is never found. It slides on from rest.
  if (j.mode != 0 && !rows_ && std::abs(t - j.slipped_at) <= kSlipEcho * std::max(1.0, std::abs(t))) {
    y[nq_ + j.f.u] = 0.0;
    return 0;
  }
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
  std::vector<int> before;
  for (const Joint& k : joints_) before.push_back(k.mode);
  j.mode = j.tau > 0.0 ? -1 : 1;
  j.slipped_at = t;
  ++decisions_;
  SettleGroup(ws, t, j, before, &j);  // (its passengers slide with it)
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
  const double u = u_eval_[static_cast<size_t>(&j - joints_.data())];
  if (u == 0.0) return 0;
  double a_max = 0.0;
  for (int i = 0; i < nu_; ++i) a_max = std::max(a_max, std::abs(ydot_[static_cast<size_t>(nq_ + i)]));
  const double tau0 = Applied(ws, j), step = 1e3 * (1.0 + std::abs(tau0) + a_max);
  rt::SetFrictionMode(ws, j.index, 2, tau0 + step);
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
  const std::vector<int> resting = RestingSpeeds();
  std::vector<Joint*> cand;  // the stuck joints (j among them) in the joints' order, then the sliding ones
  for (Joint& k : joints_)
    if (k.mode == 0 && !HeldByStop(k, resting)) cand.push_back(&k);
  const size_t n_stuck = cand.size();
  for (Joint& k : joints_)
    if (k.mode != 0 && !HeldByStop(k, resting)) cand.push_back(&k);
  const size_t m = cand.size(), nu = static_cast<size_t>(nu_);
  const size_t at = static_cast<size_t>(std::find(cand.begin(), cand.end(), &j) - cand.begin());
  // X of (1) over all candidates, each at a fixed force (a stuck one's applied, a sliding one's 0).
  Apply(ws);
  std::vector<double> base(m), X(m * m);
  for (size_t k = 0; k < m; ++k) {
    base[k] = k < n_stuck ? Applied(ws, *cand[k]) : 0.0;
    rt::SetFrictionMode(ws, cand[k]->index, 2, base[k]);
  }
  int status = Eval(ws, t, y, ydot_.data());
  double a_max = 0.0;
  for (int i = 0; i < nu_; ++i) a_max = std::max(a_max, std::abs(ydot_[static_cast<size_t>(nq_ + i)]));
  for (size_t k = 0; k < m && status == 0; ++k) {
    const double step = 1e3 * (1.0 + std::abs(base[k]) + a_max);
    rt::SetFrictionMode(ws, cand[k]->index, 2, base[k] + step);
    status = Eval(ws, t, y, col_.data());
    rt::SetFrictionMode(ws, cand[k]->index, 2, base[k]);
    for (size_t r = 0; r < m; ++r)
      X[r * m + k] = (col_[static_cast<size_t>(nq_ + cand[r]->f.u)] - ydot_[static_cast<size_t>(nq_ + cand[r]->f.u)]) / step;
  }
  Apply(ws);
  if (status != 0) return status;
  x_ids_.clear();  // Solve makes the leaders' X afresh
  std::vector<double> M(nu * nu), d(m), x;
  if (int s = rt::UnconstrainedMassMatrix(program_, ws, t, y, M.data()); s != 0) return s;
  for (size_t k = 0; k < m; ++k) {  // (M^-1)_kk, the scale of X_kk without the rows
    std::vector<double> e(nu, 0.0);
    e[static_cast<size_t>(cand[k]->f.u)] = 1.0;
    if (!SolveSmall(M, e, &x)) return -1;
    d[k] = x[static_cast<size_t>(cand[k]->f.u)];
  }
  auto Xn = [&](size_t r, size_t k) { return X[r * m + k] / std::sqrt(d[r] * d[k]); };
  if (!(Xn(at, at) > kDependent)) return 1;
  // (4): leaders L greedily; a candidate whose Schur complement on L vanishes is tied to L.
  std::vector<size_t> L;
  for (size_t c = 0; c < m; ++c) {
    const size_t nl = L.size();
    std::vector<double> A(nl * nl), b(nl), kn;
    for (size_t r = 0; r < nl; ++r) {
      b[r] = Xn(c, L[r]);
      for (size_t k = 0; k < nl; ++k) A[r * nl + k] = Xn(L[k], L[r]);  // (X_LL^T: kn = (X_cL X_LL^-1)^T)
    }
    if (nl > 0 && !SolveSmall(A, b, &kn)) return -1;
    double schur = Xn(c, c);
    for (size_t r = 0; r < nl; ++r) schur -= kn[r] * Xn(L[r], c);
    Joint& k = *cand[c];
    if (schur > kDependent) {  // independent: a stuck one leads (its own row), a sliding one slides on
      if (c < n_stuck) {
        if (k.leader >= 0) k.tau = 0.0;
        k.leader = -1;
        L.push_back(c);
      }
      continue;
    }
    std::vector<size_t> ties;
    for (size_t r = 0; r < nl; ++r)
      if (std::abs(kn[r]) > kTied) ties.push_back(r);
    if (c >= n_stuck && (ties.size() != 1 || !(Xn(c, c) > kDependent))) continue;  // (moved by the rows alone)
    if (ties.size() != 1 || !(Xn(c, c) > kDependent)) {
      std::string who;
      for (size_t r : ties) who += (who.empty() ? "'" : "', '") + cand[L[r]]->f.joint;
      error_ = ties.empty() ? "joint '" + k.f.joint + "' sticks where the constraints fix its motion (a dead point)"
                            : "joint '" + k.f.joint + "' sticks, and the constraints tie its speed to those of several " +
                                  "stuck joints (" + who + "'): how their friction forces share the holding is not " +
                                  "solved; keep exact friction off one of them";
      return -1;
    }
    const size_t l = L[ties[0]];
    k.mode = 0;
    k.leader = static_cast<int>(cand[l] - joints_.data());
    k.ratio = kn[ties[0]] * std::sqrt(d[c] / d[l]);  // the scaled ratio back: u_k = ratio u_l
    k.tau = 0.0;
    grouped_ = true;
  }
  Ungroup();
  return 0;
}

std::string StickSlipEvents::SettleAt(rt::Workspace& ws, double t, const double* y, double tol) {
  std::vector<double> at(y, y + nq_ + nu_);
  const std::vector<int> resting = RestingSpeeds();
  for (Joint& j : joints_) {
    const double u = at[static_cast<size_t>(nq_ + j.f.u)];
    j.mode = u > tol ? 1 : u < -tol ? -1 : 0;
    j.tau = 0.0;
    j.leader = -1;
    j.stamp = 0;
  }
  grouped_ = false;
  for (Joint& j : joints_)
    if (j.mode == 0 && !HeldByStop(j, resting) && j.stamp == 0) {  // (a passenger decided with its leader)
      if (Decide(ws, t, at.data(), j) != 0) return "the operating point cannot be evaluated: " + rt::ErrorMessage(ws);
      if (j.mode != 0) return "joint '" + j.f.joint + "' is at rest but " + log_.back().kind + ": it slips at once, no smooth state";
    }
  return "";
}

std::vector<int> StickSlipEvents::StuckSpeeds() const {
  std::vector<int> out;
  const std::vector<int> resting = RestingSpeeds();
  for (const Joint& j : joints_)  // (a passenger's row is its leader's, (4))
    if (j.mode == 0 && !HeldByStop(j, resting) && j.leader < 0) out.push_back(j.f.u);
  return out;
}

std::vector<std::string> StickSlipEvents::StuckNames() const {
  std::vector<std::string> out;
  const std::vector<int> resting = RestingSpeeds();
  for (const Joint& j : joints_)
    if (j.mode == 0 && !HeldByStop(j, resting) && j.leader < 0) out.push_back(j.f.joint + " stuck");
  return out;
}

int StickSlipEvents::Start(rt::Workspace& ws, double t0, double* y0) {
  if (stops_) stops_->TakeReleased();  // (a joint pulled off at the start decides below)
  for (Joint& j : joints_) {
    const double u = y0[nq_ + j.f.u];
    j.mode = u > 0.0 ? 1 : u < 0.0 ? -1 : 0;
    j.tau = 0.0;
    j.leader = -1;
    j.stamp = 0;
  }
  grouped_ = false;
  if (int s = MarkHeldByStops(ws, t0, y0, 0.0); s != 0) return s;
  const std::vector<int> resting = RestingSpeeds();
  const long from = decisions_;
  for (Joint& j : joints_)
    if (j.mode == 0 && !HeldByStop(j, resting) && j.stamp == 0)  // (a passenger decided with its leader)
      if (int s = Decide(ws, t0, y0, j); s != 0) return s;
  return CheckLaws(ws, t0, y0, from);
}

int StickSlipEvents::BackToRest(rt::Workspace& ws, double t, double* y, const std::vector<int>& moving,
                                const std::vector<int>& resting) {
  if (moving.empty()) return 0;
  // Zeroing their speeds alone changes T by about -u (M u)_k, of either sign (friction sweep
  // seed 54 trial 3: +2.8e-6 J across an instant, CVODE-BDF, a stuck joint at 4.4e-7 rad/s
  // beside the base at -1.87). The impulses on them that bring them to rest, keeping the
  // other stuck joints and the stops' resting joints at rest, take
  // (J W J^T)^-1 (J u) / 2 . (J u) >= 0 from T instead (W frictionless: their friction
  // impulses at these speeds are the round-off the rest speed is).
  std::vector<int> rows = moving;
  for (const Joint& k : joints_)
    if (k.mode == 0 && k.leader < 0 && y[nq_ + k.f.u] == 0.0 &&
        std::find(rows.begin(), rows.end(), k.f.u) == rows.end())
      rows.push_back(k.f.u);
  for (int k : resting)
    if (std::find(rows.begin(), rows.end(), k) == rows.end()) rows.push_back(k);
  const size_t m = rows.size(), nu = static_cast<size_t>(nu_);
  std::vector<double> X(m * nu), A(m * m), b(m), c;
  if (int s = rt::FrictionlessInverseMassColumns(program_, ws, t, y, rows.data(), static_cast<int>(m), X.data());
      s != 0)
    return s;
  for (size_t a = 0; a < m; ++a) {
    b[a] = -y[nq_ + rows[a]];
    for (size_t k = 0; k < m; ++k) A[a * m + k] = X[k * nu + static_cast<size_t>(rows[a])];
  }
  if (SolveHeld(A, b, &c, nullptr, 0.0)) {
    for (size_t k = 0; k < m; ++k)
      for (size_t i = 0; i < nu; ++i) y[static_cast<size_t>(nq_) + i] += c[k] * X[k * nu + i];
  }
  for (int k : rows) y[nq_ + k] = 0.0;  // (the impulses' round-off; where they cannot be solved: zeroed alone)
  return 0;
}

int StickSlipEvents::Refresh(rt::Workspace& ws, double t, double* y, const double* y_before, double v_rest) {
  if (int s = MarkHeldByStops(ws, t, y, v_rest); s != 0) return s;
  const std::vector<int> resting = RestingSpeeds();
  // Pulled off its stop beyond the static friction (EndStopEvents::Leave): it slides away,
  // not stuck (a decision at the bound would be round-off's). A release moves the forces the
  // joints at rest need, as a decision does: their laws are checked together after it.
  bool released = false;
  if (stops_)
    for (const auto& [u, dir] : stops_->TakeReleased())
      for (Joint& j : joints_)
        if (j.f.u == u && !HeldByStop(j, resting)) j.mode = dir, j.tau = 0.0, released = true;
  std::vector<Joint*> stopped;
  // A joint that slid and now rests on its stop moves the forces the joints at rest need, as
  // a release does: the laws at rest are checked again (friction sweep seed 21 trial 3: j[4]
  // decided to slide forwards from rest beside j[1] sliding backwards; j[1] then came to rest
  // on q_min, and j[4] accelerated backwards: "its reversal was missed", exit 2 in four
  // integrators).
  bool held_now = false;
  std::vector<int> to_rest;  // stuck joints a rest's impulse left moving at a rest speed
  for (Joint& j : joints_) {
    double& u = y[nq_ + j.f.u];
    if (HeldByStop(j, resting)) {
      held_now = held_now || j.mode != 0;
      j.mode = 0, j.tau = 0.0, j.leader = -1;
    } else if (u == y_before[nq_ + j.f.u]) {
      continue;  // (a joint that has just slipped from rest keeps sliding)
    } else if (j.mode == 0 && std::abs(u) <= v_rest) {
      if (rows_) u = 0.0;  // a rest's impulse on another joint: no real slip
      else to_rest.push_back(j.f.u);  // (below)
    } else if (std::abs(u) > v_rest) {
      j.mode = u > 0.0 ? 1 : -1;  // a finite friction does not resist an impulse
    } else if (j.mode != 0) {
      stopped.push_back(&j);  // at rest but for round-off (a graze's impulse beside rows): decides
      // Brought to rest by an impulse, not zeroed alone (Decide): its speed, up to v_rest,
      // times its generalized momentum (M u)_k is the energy zeroing adds or takes, and a
      // floating base in free fall makes that large (Talos at 17 m/s: +4e-5 J at one instant).
      if (!rows_) to_rest.push_back(j.f.u);
    }
  }
  if (int s = BackToRest(ws, t, y, to_rest, resting); s != 0) return s;
  const long from = decisions_;
  for (Joint* j : stopped)  // (one decided with an earlier one's group is not decided again)
    if (j->stamp <= from)
      if (int s = Decide(ws, t, y, *j); s != 0) return s;
  Apply(ws);
  return decisions_ > from || released || held_now ? CheckLaws(ws, t, y, from) : 0;
}

}  // namespace kanesim::sim
