// Exact friction's laws at rest decided together (sim/stick_slip.h CheckLaws). Each decision
// at rest (Decide) is made with the other joints' laws as they are; but a joint that slips
// moves the forces the stuck ones need, and with a friction mu N every law moves every
// normal force. The laws of the joints at rest R (speed exactly 0: stuck, or set sliding
// from rest at this instant) are consistent when
//   stuck k:             |tau_k| <= B_k = mu_s r N_k + C_s          (its force holds it)
//   sliding k, way s_k:  s_k udot_k >= 0                          (it moves the way it slides)   (5)
// with every N and tau solved for that choice of laws (Solve). Where the decisions leave (5)
// violated, the choices are enumerated: first over the joints that violate it and those just
// decided, D, then over all of R (|R| <= kMaxEnumerated), each joint stuck or sliding either
// way, fewer sliding joints first, then fewer changed; the first choice satisfying (5) for
// all of R is taken (the complementarity problem of Coulomb friction at rest, solved by
// enumeration as the friction impulses are: sim/friction_impulse.h). Where none does, neither
// sticking nor sliding is consistent (a Painleve-type state: a friction that follows the
// normal force with mu r large against the inertia, or sliding friction above the static):
// the run stops, exit 2, naming the joints.
//
// For one joint deciding with the others' laws fixed a choice always exists when the sliding
// bound is at most the static one: the friction force tau that slides it the way s the
// needed force tau_h pulls solves phi(tau) = tau + s (mu r N(tau) + C) = 0, and phi(tau_h)
// s = B_slide - |tau_h| < 0 <= phi(0) s, so a root lies between tau_h and 0, where s udot >= 0
// (N = |F across the axis| >= 0 is continuous in tau). The relaxed iteration of
// runtime/kane/friction.cpp (3') converges to such a root (its gain there is below 1).
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "sim/stick_slip.h"

namespace kanesim::sim {

namespace {
// (5)'s tolerances: a stuck force this fraction beyond its bound (the event's root leaves it
// there by the root's tolerance), a sliding acceleration this fraction of the largest
// against its way (the stuck forces' Newton noise: stick_slip.cpp kNewtonNoise).
constexpr double kBoundTol = 1e-9;
constexpr double kAccelTol = 1e-9;
constexpr size_t kMaxEnumerated = 6;  // 3^6 = 729 solves at most
}  // namespace

std::vector<StickSlipEvents::Joint*> StickSlipEvents::Inconsistent(rt::Workspace& ws, double t, double* y,
                                                                  const std::vector<Joint*>& at_rest, int* status) {
  std::vector<Joint*> wrong;
  *status = Solve(ws, t, y, ydot_.data());
  if (*status != 0) return wrong;
  double scale = 1.0;
  for (int i = 0; i < nu_; ++i) scale = std::max(scale, std::abs(ydot_[static_cast<size_t>(nq_ + i)]));
  for (Joint* j : at_rest) {
    if (j->mode == 0) {
      const double B = GroupBound(ws, *j);
      if (std::abs(j->tau) > B + kBoundTol * (1.0 + B)) wrong.push_back(j);
    } else if (j->mode * ydot_[static_cast<size_t>(nq_ + j->f.u)] < -kAccelTol * scale) {
      wrong.push_back(j);
    }
  }
  return wrong;
}

int StickSlipEvents::CheckLaws(rt::Workspace& ws, double t, double* y, long from, const Joint* slipped) {
  if (rows_) return 0;  // beside constraint rows the groups (4) decide (CheckRows); not enumerated
  const std::vector<int> resting = RestingSpeeds();
  std::vector<Joint*> at_rest, decided;
  for (Joint& j : joints_) {
    if (HeldByStop(j, resting) || j.leader >= 0 || y[nq_ + j.f.u] != 0.0) continue;
    at_rest.push_back(&j);
    if (j.stamp > from) decided.push_back(&j);
  }
  if (at_rest.empty()) return 0;
  int status = 0;
  std::vector<Joint*> wrong = Inconsistent(ws, t, y, at_rest, &status);
  if (status != 0 || wrong.empty()) return status;

  // The laws before the enumeration, to restore and to log the changes against.
  std::vector<int> before;
  std::vector<double> tau_before;
  for (const Joint& j : joints_) before.push_back(j.mode), tau_before.push_back(j.tau);
  const std::vector<Joint*> first_wrong = wrong;
  std::vector<Joint*> D = decided;
  for (Joint* j : wrong)
    if (std::find(D.begin(), D.end(), j) == D.end()) D.push_back(j);
  for (int round = 0; round < 2; ++round) {
    if (round == 1) {
      if (D.size() == at_rest.size() || at_rest.size() > kMaxEnumerated) break;
      D = at_rest;
    }
    if (D.size() > kMaxEnumerated) continue;
    // Every choice of D's laws (0 stuck, 1 forwards, 2 backwards per joint), fewer sliding
    // first, then fewer changed from the decisions.
    const size_t n = D.size();
    long cases = 1;
    for (size_t k = 0; k < n; ++k) cases *= 3;
    std::vector<std::pair<std::pair<int, int>, long>> order;
    for (long c = 0; c < cases; ++c) {
      int sliding = 0, changed = 0;
      long code = c;
      for (size_t k = 0; k < n; ++k, code /= 3) {
        const int mode = code % 3 == 0 ? 0 : code % 3 == 1 ? 1 : -1;
        sliding += mode != 0;
        changed += mode != before[static_cast<size_t>(D[k] - joints_.data())];
      }
      order.push_back({{sliding, changed}, c});
    }
    std::stable_sort(order.begin(), order.end());
    for (const auto& [key, c] : order) {
      long code = c;
      bool excluded = false;
      for (size_t k = 0; k < n; ++k, code /= 3) {
        Joint& j = *D[k];
        j.mode = code % 3 == 0 ? 0 : code % 3 == 1 ? 1 : -1;
        j.tau = tau_before[static_cast<size_t>(&j - joints_.data())];
        excluded = excluded || (&j == slipped && j.mode == 0);
      }
      if (excluded) continue;
      wrong = Inconsistent(ws, t, y, at_rest, &status);
      if (status != 0 || !wrong.empty()) continue;  // (one that cannot be evaluated has no unique forces)
      for (Joint* j : at_rest) {  // the changes, logged
        const size_t i = static_cast<size_t>(j - joints_.data());
        if (j->mode == before[i]) continue;
        j->stamp = ++decisions_;
        char buf[300];
        const double B = StaticBound(ws, *j);
        if (j->mode == 0)
          std::snprintf(buf, sizeof buf, "sticks (friction %.17g within %.17g; the joints at rest decided together)",
                        j->tau, B);
        else
          std::snprintf(buf, sizeof buf,
                        "slides %s (accelerating %.6g that way; the joints at rest decided together)",
                        j->mode > 0 ? "forwards" : "backwards", j->mode * ydot_[static_cast<size_t>(nq_ + j->f.u)]);
        log_.push_back({t, j->f.joint, buf});
      }
      Apply(ws);
      return 0;
    }
  }
  // No choice: the decisions' laws back, and why the first joint's fail.
  for (size_t i = 0; i < joints_.size(); ++i) joints_[i].mode = before[i], joints_[i].tau = tau_before[i];
  Apply(ws);
  std::string names;
  for (const Joint* j : D) names += (names.empty() ? "'" : "', '") + j->f.joint;
  const Joint& w = *first_wrong.front();
  double needed = 0.0, bound = 0.0, a_fwd = 0.0, a_bwd = 0.0;
  Joint& v = joints_[static_cast<size_t>(&w - joints_.data())];
  const int mode = v.mode;
  for (int m : {0, 1, -1}) {  // (w alone, the others as decided)
    v.mode = m;
    if (Solve(ws, t, y, ydot_.data()) != 0) continue;
    const double a = ydot_[static_cast<size_t>(nq_ + v.f.u)];
    if (m == 0) needed = v.tau, bound = GroupBound(ws, v);
    (m > 0 ? a_fwd : a_bwd) = a;
  }
  v.mode = mode;
  for (size_t i = 0; i < joints_.size(); ++i) joints_[i].tau = tau_before[i];
  Apply(ws);
  char buf[700];
  std::snprintf(buf, sizeof buf,
                "friction at joint%s %s': neither sticking nor sliding is consistent (Painleve-type): stuck, '%s' needs "
                "%.6g (its static bound %.6g); sliding forwards it accelerates %.6g, backwards %.6g (against "
                "the slide: a friction that follows the normal force with mu r too large for this state, or a "
                "sliding friction above the static one)",
                D.size() > 1 ? "s" : "", names.c_str(), w.f.joint.c_str(), needed, bound, a_fwd, a_bwd);
  error_ = buf;
  return -1;
}

}  // namespace kanesim::sim
