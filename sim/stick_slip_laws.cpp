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
// With constant friction (no mu N: direct_) the laws at rest are one problem. The
// accelerations of the speeds at rest are affine in their friction forces, a = a0 + X tau,
// X the at-rest block of the inverse mass (the resting stops held), symmetric positive
// definite; (5) with the static bounds is then the box LCP
//   find tau, -B <= tau <= B:  tau_k = -B_k => a_k >= 0,  tau_k = B_k => a_k <= 0,  else a_k = 0   (6)
// which has exactly one solution (sim/box_lcp.h). A joint it leaves at a bound slides, with
// its sliding friction c <= c_s as its bound from then on (solved again until the sliding set
// stays): stuck joints within c_s, sliding ones accelerating their way, (5). Where the
// enumeration finds no choice, or R has more than kMaxEnumerated joints, (6) decides them
// (LawsAtRestTogether). With end stops, a joint on its stop has one unknown, the stop's
// reaction and its friction together, bounded on the stop's side only (q_min: tau >= -B); it
// rests on the stop inside its box and slides off it at the bound (LawsWithStops: after an
// event whose laws, decided in turns, left a joint at rest accelerating into its stop). Talos
// (32 joints) had both refused with exit 2 (docs/benchmarks/2026-12-01_talos_sweep.md).
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

#include "sim/box_lcp.h"
#include "sim/end_stops.h"
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
  // No choice enumerated: with constant friction the laws at rest are one box LCP (6).
  for (size_t i = 0; i < joints_.size(); ++i) joints_[i].mode = before[i], joints_[i].tau = tau_before[i];
  Apply(ws);
  if (direct_) {
    bool solved = false;
    if (int s = LawsAtRestTogether(ws, t, y, at_rest, slipped, before, &solved); s != 0 || solved) return s;
    for (size_t i = 0; i < joints_.size(); ++i) joints_[i].mode = before[i], joints_[i].tau = tau_before[i];
    Apply(ws);
  }
  // None: the decisions' laws back, and why the first joint's fail.
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
  // With constant friction no sliding bound above the static one leaves (6) without a
  // solution; the pivoting failed on round-off (a matrix not positive definite to it).
  const bool above_static = std::any_of(at_rest.begin(), at_rest.end(), [](const Joint* j) { return j->f.c > j->f.c_s; });
  const char* why = !direct_ ? "Painleve-type; against the slide: a friction that follows the normal force with mu r "
                               "too large for this state, or a sliding friction above the static one"
                    : above_static ? "a sliding friction above the static one"
                                   : "the complementarity problem of the laws at rest was not solved to round-off";
  char buf[800];
  std::snprintf(buf, sizeof buf,
                "friction at joint%s %s': neither sticking nor sliding is consistent: stuck, '%s' needs "
                "%.6g (its static bound %.6g); sliding forwards it accelerates %.6g, backwards %.6g (%s)",
                D.size() > 1 ? "s" : "", names.c_str(), w.f.joint.c_str(), needed, bound, a_fwd, a_bwd, why);
  error_ = buf;
  return -1;
}

int StickSlipEvents::LawsAtRestTogether(rt::Workspace& ws, double t, double* y, const std::vector<Joint*>& at_rest,
                                        const Joint* slipped, const std::vector<int>& before, bool* solved) {
  *solved = false;
  const size_t m = at_rest.size();
  // Every joint at rest held: the forces tau_h that hold them all (a = 0), then X by columns.
  for (Joint* j : at_rest) j->mode = 0;
  if (int s = Solve(ws, t, y, ydot_.data()); s != 0) return s;
  Apply(ws);
  std::vector<double> a0(ydot_.size());
  if (int s = Eval(ws, t, y, a0.data()); s != 0) return s;
  x_ids_.clear();  // (MakeX's X is this set's, not SolveNewton's chord)
  if (int s = MakeX(ws, t, y, at_rest, a0.data()); s != 0) return s;
  // (6) in the forces: w = a0 + X (tau - tau_h); the static bounds first, a sliding joint's its
  // sliding one (constant friction: c <= c_s) until the sliding set stays; `slipped` (its needed
  // force has just passed its bound) slides the way that force pulls, its force fixed.
  std::vector<double> lo(m), hi(m), tau_h(m);
  std::vector<char> sliding(m, 0), fixed(m, 0);
  for (size_t k = 0; k < m; ++k) {
    const Joint& j = *at_rest[k];
    tau_h[k] = j.tau;
    const double B = StaticBound(ws, j);
    lo[k] = -B, hi[k] = B;
    if (&j == slipped) {
      fixed[k] = 1, sliding[k] = 1;
      lo[k] = hi[k] = j.tau > 0.0 ? j.f.c : -j.f.c;  // pulled backwards: it slides backwards
    }
  }
  BoxLcpResult r;
  std::vector<size_t> ids;  // the unknowns: the joints whose force is not fixed
  for (size_t round = 0; round <= m; ++round) {
    ids.clear();
    for (size_t k = 0; k < m; ++k)
      if (!fixed[k]) ids.push_back(k);
    const size_t n = ids.size();
    std::vector<double> A(n * n), q(n), l(n), h(n);
    for (size_t i = 0; i < n; ++i) {
      const size_t ki = ids[i];
      q[i] = a0[static_cast<size_t>(nq_ + at_rest[ki]->f.u)];
      for (size_t k = 0; k < m; ++k) q[i] += x_[ki * m + k] * ((fixed[k] ? lo[k] : 0.0) - tau_h[k]);
      for (size_t c = 0; c < n; ++c) A[i * n + c] = 0.5 * (x_[ki * m + ids[c]] + x_[ids[c] * m + ki]);  // (symmetric)
      l[i] = lo[ki], h[i] = hi[ki];
    }
    r = SolveBoxLcp(A, q, l, h);
    if (!r.solved) return 0;
    bool more = false;
    for (size_t i = 0; i < n; ++i) {
      const size_t k = ids[i];
      if (r.state[i] == BoxState::kFree || sliding[k]) continue;
      sliding[k] = 1;
      const double C = at_rest[k]->f.c;
      if (C < hi[k]) more = true, lo[k] = -C, hi[k] = C;  // it slides: its sliding friction
    }
    if (!more) break;
  }
  // The laws (6) gives, solved exactly as they are (the stuck forces by Solve) and checked (5).
  for (size_t k = 0; k < m; ++k) {
    Joint& j = *at_rest[k];
    if (fixed[k]) {
      j.mode = lo[k] > 0.0 ? -1 : 1;
      continue;
    }
    const size_t i = static_cast<size_t>(std::find(ids.begin(), ids.end(), k) - ids.begin());
    j.mode = r.state[i] == BoxState::kFree || r.w[i] == 0.0 ? 0 : r.state[i] == BoxState::kLower ? 1 : -1;
    j.tau = r.x[i];
  }
  int status = 0;
  if (!Inconsistent(ws, t, y, at_rest, &status).empty() || status != 0) return 0;
  for (Joint* j : at_rest) {  // the changes, logged
    const size_t i = static_cast<size_t>(j - joints_.data());
    if (j->mode == before[i]) continue;
    j->stamp = ++decisions_;
    char buf[300];
    if (j->mode == 0)
      std::snprintf(buf, sizeof buf,
                    "sticks (friction %.17g within %.17g; the laws at rest of %zu joints solved together)", j->tau,
                    StaticBound(ws, *j), m);
    else
      std::snprintf(buf, sizeof buf, "slides %s (accelerating %.6g that way; the laws at rest of %zu joints solved together)",
                    j->mode > 0 ? "forwards" : "backwards", j->mode * ydot_[static_cast<size_t>(nq_ + j->f.u)], m);
    log_.push_back({t, j->f.joint, buf});
  }
  Apply(ws);
  *solved = true;
  return 0;
}

}  // namespace kanesim::sim

namespace kanesim::sim {

int StickSlipEvents::LawsWithStops(rt::Workspace& ws, double t, double* y, bool* solved) {
  *solved = false;
  if (!stops_ || rows_ || !direct_ || grouped_) return 0;
  std::vector<EndStopEvents::StopAtRest> at_stops;
  if (!stops_->StopsAtRest(t, y, &at_stops)) return 0;
  // One unknown force per speed at rest: a joint on its stop (the stop's reaction and the
  // joint's friction together), or a joint with exact friction at rest off its stops.
  struct Unknown {
    int u = -1;
    Joint* j = nullptr;
    int side = -1;
    bool upper = false;
  };
  std::vector<Unknown> v;
  for (const auto& s : at_stops) {
    for (const Unknown& o : v)
      if (o.u == s.u) return 0;  // (both sides of one joint at rest: its range is a point)
    v.push_back({s.u, nullptr, s.side, s.upper});
  }
  for (Joint& j : joints_) {
    auto it = std::find_if(v.begin(), v.end(), [&](const Unknown& o) { return o.u == j.f.u; });
    if (it != v.end())
      it->j = &j;
    else if (y[nq_ + j.f.u] == 0.0)
      v.push_back({j.f.u, &j, -1, false});
  }
  if (v.empty()) return 0;
  const size_t m = v.size(), nu = static_cast<size_t>(nu_);
  const std::vector<double> modes = Modes(), resting = stops_->Resting();
  const std::vector<char> rest_before = stops_->RestingSet();
  const std::vector<double> y_before(y, y + nq_ + nu_);
  auto restore = [&]() {
    SetModes(modes);
    stops_->SetResting(resting);
    std::copy(y_before.begin(), y_before.end(), y);
    Apply(ws);
  };
  // The free accelerations a0 with every unknown force 0 and every stop at rest free (the
  // speeds at rest at 0), and X = M^-1 on the speeds at rest (a tree: no rows).
  std::vector<double> free_sides = resting;
  for (const Unknown& o : v)
    if (o.side >= 0) free_sides[2 * static_cast<size_t>(o.side)] = 0.0;
  stops_->SetResting(free_sides);
  Apply(ws);
  std::vector<double> y0(y_before), a0(y_before.size());
  std::vector<int> speeds;
  for (const Unknown& o : v) {
    if (o.j) rt::SetFrictionMode(ws, o.j->index, 2, 0.0);
    y0[static_cast<size_t>(nq_ + o.u)] = 0.0;
    speeds.push_back(o.u);
  }
  int status = rt::Derivative(program_, ws, t, y0.data(), a0.data());
  col_.resize(m * nu);
  if (status == 0)
    status = rt::InverseMassColumns(program_, ws, t, y0.data(), speeds.data(), static_cast<int>(m), col_.data());
  if (status != 0) {
    restore();
    return status;
  }
  // (6): w = a0 + X f, f the joint's force; bounds: friction within +-B (B its static
  // friction, 0 without), a stop pushing without bound (q_min: f >= -B; q_max: f <= B).
  std::vector<double> A(m * m), q(m), lo(m), hi(m);
  std::vector<char> sliding(m, 0);
  for (size_t r = 0; r < m; ++r) {
    q[r] = a0[static_cast<size_t>(nq_ + v[r].u)];
    for (size_t k = 0; k < m; ++k)
      A[r * m + k] = 0.5 * (col_[k * nu + static_cast<size_t>(v[r].u)] + col_[r * nu + static_cast<size_t>(v[k].u)]);
    const double B = v[r].j ? StaticBound(ws, *v[r].j) : 0.0;
    lo[r] = v[r].side >= 0 && v[r].upper ? -HUGE_VAL : -B;
    hi[r] = v[r].side >= 0 && !v[r].upper ? HUGE_VAL : B;
  }
  BoxLcpResult res;
  for (size_t round = 0; round <= m; ++round) {
    res = SolveBoxLcp(A, q, lo, hi);
    if (!res.solved) {
      restore();
      return 0;
    }
    bool more = false;  // a joint sliding from now: its sliding friction (c <= c_s), solved again
    for (size_t r = 0; r < m; ++r) {
      if (res.state[r] == BoxState::kFree || sliding[r] || !v[r].j || res.w[r] == 0.0) continue;
      sliding[r] = 1;
      const double C = v[r].j->f.c;
      if (res.state[r] == BoxState::kLower && C < -lo[r]) lo[r] = -C, more = true;
      if (res.state[r] == BoxState::kUpper && C < hi[r]) hi[r] = C, more = true;
    }
    if (!more) break;
  }
  // The laws it gives: a side rests where its force is inside its box (or at the friction's
  // bound with no acceleration), else leaves with its joint sliding away; a joint off its
  // stops sticks inside its box, else slides the way it accelerates.
  std::vector<char> rest_after = rest_before;
  std::vector<Joint*> off_stops;
  for (size_t r = 0; r < m; ++r) {
    const bool inside = res.state[r] == BoxState::kFree || res.w[r] == 0.0;
    const int way = res.state[r] == BoxState::kLower ? 1 : -1;
    Joint* j = v[r].j;
    if (v[r].side >= 0) {
      rest_after[static_cast<size_t>(v[r].side)] = inside ? 1 : 0;
      if (j) j->mode = inside ? 0 : way, j->tau = 0.0;
      if (j && !inside) off_stops.push_back(j);  // (sliding off it: (5) checks its way)
    } else {
      j->mode = inside ? 0 : way;
      j->tau = inside ? res.x[r] : 0.0;
      off_stops.push_back(j);
    }
  }
  const std::vector<double> new_modes = Modes();
  stops_->SetResting(resting);
  // A side set resting at a rest speed: stopped by an impulse (the others at rest held), not
  // zeroed alone, which changes T by u (M u)_k (Refresh's stopped joints: a95c8f5).
  std::vector<int> moving;
  for (size_t r = 0; r < m; ++r)
    if (v[r].side >= 0 && rest_after[static_cast<size_t>(v[r].side)] && y[nq_ + v[r].u] != 0.0) moving.push_back(v[r].u);
  if (int s = BackToRest(ws, t, y, moving, stops_->RestingSpeeds()); s != 0) {
    restore();
    return s;
  }
  stops_->SetRestingSides(t, y, rest_after, nullptr);
  // Checked as they are: the stuck forces solved (5), no resting side pulling beyond its margin.
  std::vector<Joint*> at_rest;
  for (Joint* j : off_stops)
    if (j->mode == 0 || y[nq_ + j->f.u] == 0.0) at_rest.push_back(j);
  bool ok = Inconsistent(ws, t, y, at_rest, &status).empty() && status == 0;
  if (ok) {
    Apply(ws);
    std::vector<double> g(static_cast<size_t>(stops_->Count()));
    ok = stops_->Functions(ws, t, y, g.data(), nullptr) == 0;
    for (size_t i = 0; ok && i < g.size(); ++i) ok = !rest_after[i] || g[i] >= 0.0;
  }
  if (!ok) {
    restore();
    return 0;
  }
  // Kept: the changes logged (the stops' by SetRestingSides, from the state before).
  const std::vector<double> y_after(y, y + nq_ + nu_);
  std::copy(y_before.begin(), y_before.end(), y);
  stops_->SetResting(resting);
  char why[120];
  std::snprintf(why, sizeof why, "the laws at rest of %zu joints and stops solved together", m);
  stops_->SetRestingSides(t, y, rest_after, why);
  std::copy(y_after.begin(), y_after.end(), y);
  SetModes(new_modes);
  for (size_t i = 0; i < joints_.size(); ++i) {
    Joint& j = joints_[i];
    const double was = modes[kModeValues * i];
    if (j.by_stops || (was == 2.0 ? 0.0 : was) == static_cast<double>(j.mode)) continue;
    if (HeldByStop(j, RestingSpeeds())) continue;  // (the stop's log says it)
    j.stamp = ++decisions_;
    char buf[300];
    if (j.mode == 0)
      std::snprintf(buf, sizeof buf, "sticks (friction %.17g within %.17g; %s)", j.tau, StaticBound(ws, j), why);
    else
      std::snprintf(buf, sizeof buf, "slides %s (%s)", j.mode > 0 ? "forwards" : "backwards", why);
    log_.push_back({t, j.f.joint, buf});
  }
  if (int s = Solve(ws, t, y, ydot_.data()); s != 0) return s;
  Apply(ws);
  *solved = true;
  return 0;
}

}  // namespace kanesim::sim
