// The bridge over a near-singular zone of a closed loop, and the check of a change point a
// solver passed by itself (sim/change_point_bridge.h BridgeChangePoint, BridgedState;
// docs/constraints.md "Singular configurations"; issue 20). CheckStep
// (change_point_steps.cpp) calls them after the accepted steps.
#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "runtime/runtime.h"
#include "sim/change_point_bridge.h"

namespace kanesim::sim {

using rt::Program;
using rt::Workspace;

namespace {
struct RungeKuttaScratch {
  explicit RungeKuttaScratch(size_t n) : k2(n), k3(n), k4(n), tmp(n) {}
  std::vector<double> k2, k3, k4, tmp;
};

// One classical Runge-Kutta step of y from t by h, given f = y'(t, y): the bridge's
// approach and the passage check's carry take the same steps. Nonzero if the equations fail.
int RungeKuttaStep(const Program& p, Workspace& ws, double t, double h, const double* f, double* y,
                   RungeKuttaScratch& s) {
  const size_t n = s.tmp.size();
  for (size_t i = 0; i < n; ++i) s.tmp[i] = y[i] + 0.5 * h * f[i];
  if (rt::Derivative(p, ws, t + 0.5 * h, s.tmp.data(), s.k2.data()) != 0) return 1;
  for (size_t i = 0; i < n; ++i) s.tmp[i] = y[i] + 0.5 * h * s.k2[i];
  if (rt::Derivative(p, ws, t + 0.5 * h, s.tmp.data(), s.k3.data()) != 0) return 1;
  for (size_t i = 0; i < n; ++i) s.tmp[i] = y[i] + h * s.k3[i];
  if (rt::Derivative(p, ws, t + h, s.tmp.data(), s.k4.data()) != 0) return 1;
  for (size_t i = 0; i < n; ++i) y[i] += h / 6.0 * (f[i] + 2.0 * s.k2[i] + 2.0 * s.k3[i] + s.k4[i]);
  return 0;
}
}  // namespace

// The bridge over a near-singular zone (docs/constraints.md "Singular configurations").
// A solver approaching a change point at a tight tolerance shrinks its steps where the
// loop equations' conditioning degrades and stalls short of the crossing; moving away
// from it is not the difficulty (a run started 1e-4 past the crossing continues at rtol
// 1e-12 with every solver). The motion itself is smooth there, so it is extrapolated over
// the crossing and a fresh solver starts past it. Two fits, the first that passes:
//  - BridgeByApproach: from the last accepted step with rho >= 7 kBridgeFitRho (where the
//    equations are accurate) the bridge integrates on by itself, classical Runge-Kutta with
//    fixed small steps, to rho = kBridgeFitRho; the quintic Hermite through (y, y') at the
//    nodes with rho ~ 3, 2, 1 x kBridgeFitRho extrapolates to t_b, where rho is back to
//    kBridgePast on the far side. Checked by two estimates: the quartic without the first
//    slope, and the quintic through the nodes at 6, 4, 2 x kBridgeFitRho (a second fit).
//  - BridgeByZoneFit: the quintic (or cubic) Hermite through the zone's own accepted steps
//    with rho >= 1e-3.
// Either's state at t_b is projected onto the position and velocity constraints (Newton
// from a point ~1e-12 off the continuing branch and ~rho off every other lands on it).
namespace {
// The fit to the zone's accepted steps (BridgeByZoneFit), tried second.
constexpr double kZoneMaxRho = 1e-3;     // a stall farther than this from the crossing is not bridged
constexpr double kZoneFitRho = 1e-3;     // t2: rho at least this
constexpr double kZoneFarRho = 3e-3;     // t1: rho at least this
constexpr double kZonePast = 1e-3;       // rho past the crossing where this bridge ends
constexpr double kZoneMaxError = 1e5;    // the error estimate's limit, in units of atol + rtol |y| (at 1e6 two
                                         // runs ended 1e-4 off: docs/benchmarks.md)
constexpr double kZoneMaxErrorReduced = 1e2;  // ... on the reduced form
// The bridge's own approach (BridgeByApproach), tried first. The limits of the error
// estimates are per form: on the reduced form the energy jump across a bridge grows with
// the estimate (the equations' accelerations near the crossing are off by ~c / rho^3 for a
// Newton residual c; measured on the parallelogram at rtol 1e-12: estimate < 1e3 -> jump
// <= 1e-7 J; 1e3 ... 1e5 -> up to 2e-5 J), on the multiplier form it stayed <= 3e-9 J up to 1e5.
constexpr double kBridgeStartFits = 7.0;  // the approach starts at the last accepted step with rho >= this x fit_rho
constexpr double kBridgeMaxStartRho = 0.5;   // ... and at most this (else the solver stopped far from a crossing)
constexpr double kBridgeFitRho = 5e-3;       // the approach ends at rho <= this: the fit's last node
constexpr double kBridgeStepsPerFit = 20.0;  // Runge-Kutta steps per fit_rho of rho
constexpr int kBridgeMaxSteps = 2000;
constexpr double kBridgeMinFitRho = 1e-3;
constexpr double kBridgePast = 3e-3;     // rho past the crossing where the bridge ends (at 1e-3 the solvers' first steps
                                         // past it cost up to 1.6e-6 rad on the multiplier form at rtol 1e-12)
constexpr double kBridgeMaxError = 1e5;  // the limit of both estimates, in units of atol + rtol |y|
constexpr double kBridgeMaxErrorReduced = 1e3;  // ... on the reduced form (docs/benchmarks.md "Change points")
constexpr const char* kSeveralLoops = "more than one loop is near a singular configuration";
constexpr const char* kEstimateAbove = "the extrapolation's error estimate is above the tolerance";
// ... on the reduced form where several loops are near singular at once (a chain of
// equal-link parallelograms): there the estimate is dominated by round-off of the speeds
// the ill-conditioned block determines, which the projection removes (measurements: docs/constraints/2026-11-28_tuning_measurements.md).
constexpr double kBridgeMaxErrorSeveral = 1e5;
constexpr double kBridgeMoved = 1e-6;    // largest change by the projection (of max(1, |y|))
// ... on the multiplier form where several loops are near singular at once: an estimate
// above kBridgeMaxError (up to kBridgeMaxRawSeveral) is taken again between the projected
// extrapolations and limited by kBridgeMaxProjected; the projection may move the state by up
// to kBridgeMovedSeveral (the other branches are ~rho_b away; measurements: docs/constraints/2026-11-28_tuning_measurements.md).
constexpr double kBridgeMaxRawSeveral = 2e7;
constexpr double kBridgeMaxProjected = 1e6;
// kBridgeMovedSeveral also holds wherever several loops are near singular at the bridged
// state on the multiplier form, whatever the estimate: the move is the same round-off at
// every tolerance, while the estimate, in units of atol + rtol |y|, is small at loose ones
// (IDA on the chain of 40 at rtol 1e-8, t = 9.96: estimate 1.1e3, move 1.4e-5, refused by
// kBridgeMoved, the run stopped by the turn check; bridged, the speed error against the
// lumped crank 6.42e-5 rad/s before and 6.44e-5 after). Off with projected_estimate
// (TestHooks::bridge_switches.projected_estimate), as the rest of this path.
constexpr double kBridgeMovedSeveral = 2e-5;

// Component i at t of the Hermite interpolant through y and y' at the m nodes (tn[k], yn[k],
// fn[k]) (degree 2m - 1), or without the slope at the first node when skip (degree 2m - 2):
// Newton's divided differences on the nodes repeated once per condition.
double HermiteAt(const double* tn, const std::vector<double>* yn, const std::vector<double>* fn, int m, bool skip,
                 size_t i, double t) {
  double z[6], Q[6][6];
  int node[6], nz = 0;
  for (int k = 0; k < m; ++k)
    for (int r = (k == 0 && skip) ? 1 : 0; r < 2; ++r) {
      z[nz] = tn[k];
      node[nz] = k;
      Q[nz][0] = yn[k][i];
      ++nz;
    }
  for (int j = 1; j < nz; ++j)
    for (int r = j; r < nz; ++r)
      Q[r][j] = (j == 1 && node[r] == node[r - 1]) ? fn[node[r]][i] : (Q[r][j - 1] - Q[r - 1][j - 1]) / (z[r] - z[r - j]);
  double v = Q[nz - 1][nz - 1];
  for (int j = nz - 2; j >= 0; --j) v = Q[j][j] + (t - z[j]) * v;
  return v;
}
}  // namespace

namespace {
// rho of the nearest-singular loop at (t, y); -1 when the state is not valid.
double RhoAt(const Program& p, ChangePointBridge& m, double t, const double* y, int* near_loops = nullptr) {
  return rt::SingularRatioAt(p, *m.monitor, t, y, near_loops);
}
}  // namespace

int BridgeByZoneFit(const Program& p, ChangePointBridge& m, double rtol, double atol, double* t_from, double* t_b,
                    double* y_b) {
  auto refuse = [&m](const char* why) {
    m.bridge_refused = why;
    return 1;
  };
  if (!m.in_zone) return refuse("not in a near-singular zone");
  const size_t N = m.trace_t.size();
  if (N < 2) return refuse("too few accepted steps in the zone");
  double rho_min = 1.0;
  for (double r : m.trace_rho) rho_min = std::min(rho_min, r);
  if (rho_min > kZoneMaxRho) return refuse("the solver stopped far from the crossing");
  long i2 = static_cast<long>(N) - 1;
  while (i2 >= 0 && m.trace_rho[static_cast<size_t>(i2)] < kZoneFitRho) --i2;
  if (i2 < 1) return refuse("no accepted step at a fit distance");
  const double rho2 = m.trace_rho[static_cast<size_t>(i2)];
  // Approaching: every later step closer still.
  for (size_t i = static_cast<size_t>(i2) + 1; i < N; ++i)
    if (m.trace_rho[i] > rho2) return refuse("the steps after the fit point move away from the crossing");
  long i1 = i2 - 1;
  while (i1 >= 0 && m.trace_rho[static_cast<size_t>(i1)] < std::max(3.0 * rho2, kZoneFarRho)) --i1;
  if (i1 < 0) return refuse("no accepted step far enough from the crossing");
  const double t1 = m.trace_t[static_cast<size_t>(i1)], t2 = m.trace_t[static_cast<size_t>(i2)];
  const double rho1 = m.trace_rho[static_cast<size_t>(i1)];
  if (!(t2 > t1) || !(rho1 > rho2)) return refuse("rho does not fall toward the crossing");
  const double slope = (rho1 - rho2) / (t2 - t1);
  const double tc = t2 + rho2 / slope;
  const double tb = tc + std::max(rho2, kZonePast) / slope;
  // The third fit point, before t1 (rho at least 3 rho1): the quintic Hermite through the
  // three, its error estimated by the quartic without the slope at t0 (their difference).
  long i0 = i1 - 1;
  while (i0 > 0 && m.trace_rho[static_cast<size_t>(i0)] < 3.0 * rho1) --i0;
  if (i0 < 0 || !(m.trace_rho[static_cast<size_t>(i0)] > rho1)) return refuse("no accepted step for the error estimate");
  Workspace& ws = *m.ws;
  const int n = rt::StateSize(p);
  const long idx[3] = {i0, i1, i2};
  for (int k = 0; k < 3; ++k) {
    m.h_t[k] = m.trace_t[static_cast<size_t>(idx[k])];
    m.h_y[k] = m.trace_y[static_cast<size_t>(idx[k])];
    m.h_f[k].assign(static_cast<size_t>(n), 0.0);
    if (rt::Derivative(p, ws, m.h_t[k], m.h_y[k].data(), m.h_f[k].data()) != 0)
      return refuse("the equations failed at the fit points");
  }
  // Two tries: the quintic through t0, t1, t2, then the cubic through t1, t2 (each with its
  // estimate from the interpolant one degree lower, without the slope at its first node).
  const char* why = "";
  double rho_b = 1.0;
  for (int first = 0; first < 2; ++first) {
    const int nodes = 3 - first;
    double est = 0.0;
    for (int i = 0; i < n; ++i) {
      const size_t k = static_cast<size_t>(i);
      y_b[i] = HermiteAt(m.h_t + first, m.h_y + first, m.h_f + first, nodes, false, k, tb);
      const double lower = HermiteAt(m.h_t + first, m.h_y + first, m.h_f + first, nodes, true, k, tb);
      est = std::max(est, std::fabs(lower - y_b[i]) / (atol + rtol * std::fabs(y_b[i])));
    }
    m.bridge_estimate = est;
    m.h_first = first;
    if (!(est <= (m.sparse ? kZoneMaxError : kZoneMaxErrorReduced))) {
      why = kEstimateAbove;
      continue;
    }
    std::vector<double> raw(y_b, y_b + n);
    if (rt::ProjectOntoConstraints(p, ws, tb, y_b) != 0) {
      why = "the bridged state could not be projected";
      continue;
    }
    double moved = 0.0;
    for (int i = 0; i < n; ++i) {
      const double d = std::fabs(y_b[i] - raw[static_cast<size_t>(i)]) / std::max(1.0, std::fabs(raw[static_cast<size_t>(i)]));
      moved = std::isnan(d) ? INFINITY : std::max(moved, d);
    }
    if (!(moved <= kBridgeMoved)) {
      why = "the projection moved the bridged state too far";
      continue;
    }
    int near_loops = 0;
    if ((rho_b = RhoAt(p, m, tb, y_b, &near_loops)) < 0.0) {
      why = "the bridged state is not valid";
      continue;
    }
    if (near_loops > 1) {
      // Never for several loops: this fit's first version (limit 1e5 on both forms) bridged
      // a chain of two equal-link parallelograms onto the branch but 1.7e-4 rad off the
      // lumped crank at rtol 1e-12, and on one loop the same limit let through jumps of
      // 2e-5 J; the approach (BridgeByApproach) is what bridges several loops.
      why = kSeveralLoops;
      break;
    }
    if (rho_b < 0.25 * std::max(rho2, kZonePast)) {
      why = "the bridged state is not past the crossing";
      continue;
    }
    why = nullptr;
    break;
  }
  if (why) return refuse(why);
  m.nt.clear();
  m.bridged = true;
  m.zone_steps = 0;
  *t_from = m.h_t[m.h_first];
  *t_b = tb;
  return 0;
}

namespace {
// The bridged state's speeds projected in the kinetic metric (reduced form; raw: the
// extrapolation before ProjectOntoConstraints gave y), where several loops are near
// singular: the partition's own solve for the dependent speeds, an oblique projection
// ill-conditioned near the crossing, moves the energy by the extrapolation's error over
// rho. Nonzero if the equations fail.
int MetricSpeeds(const Program& p, ChangePointBridge& m, double t, const double* raw, double* y) {
  return rt::ProjectSpeedsInKineticMetric(p, *m.ws, t, raw, y);
}
}  // namespace

namespace {
// The approach's start on the multiplier form, projected by the partition with the position
// Newton to round-off (the monitor's workspace, Workspace::newton_to_round_off), the
// dependent speeds solved from the independent ones. That form's own projection stops at a
// residual of 1e-13 of the loop length, a point on the level set phi = c off the branch by
// ~c / rho, and along the approach the speeds that offset implies grow toward the crossing
// (c / rho^2): on the chain of 40 with CVODE-BDF at rtol 1e-10 (t = 2.04) the rods' speeds,
// equal on the branch, were 3.5e-7 apart at the start (rho 0.039), 2.3e-5 at the last node
// (rho 5e-3) and 5.7e-4 in the extrapolation at t_b, which the projection there removed (a
// move of 2.5e-5 of |u|, refused). From the projected start (a move of 5e-10 ... 2e-8):
// 3e-10 at the last node, estimates 2 ... 37 instead of 1.4e3 ... 6.4e4, moves ~1e-9.
// Kept as it was when the projection fails or moves it by more than kBridgeMoved.
void ProjectStart(const Program& p, Workspace& ws, double t, std::vector<double>* y) {
  std::vector<double> z(y->size());
  if (rt::ProjectByPartition(p, ws, t, y->data(), z.data()) != 0) return;
  double moved = 0.0;
  for (size_t i = 0; i < z.size(); ++i) {
    const double d = std::fabs(z[i] - (*y)[i]) / std::max(1.0, std::fabs((*y)[i]));
    moved = std::isnan(d) ? INFINITY : std::max(moved, d);
  }
  if (moved <= kBridgeMoved) *y = std::move(z);
}
}  // namespace

int BridgeByApproach(const Program& p, ChangePointBridge& m, double rtol, double atol, double* t_from, double* t_b,
                     double* y_b) {
  auto refuse = [&m](const char* why) {
    m.bridge_refused = why;
    return 1;
  };
  if (m.bridged && m.in_zone) return refuse("this zone was bridged once already");
  // With several_loops off: refused below at the bridged state when more than one loop is
  // near singular there, and before the approach is integrated when the zone's latest
  // accepted step already has several.
  if (!m.switches.several_loops && m.in_zone && m.zone_near > 1) return refuse(kSeveralLoops);
  // The accepted steps: the zone's (with the few before it), or, when the solver failed
  // before entering a zone, the last few.
  const std::vector<double>& tt = m.in_zone ? m.trace_t : m.pre_t;
  const std::vector<double>& tr = m.in_zone ? m.trace_rho : m.pre_rho;
  const std::vector<std::vector<double>>& ty = m.in_zone ? m.trace_y : m.pre_y;
  const size_t N = tt.size();
  if (N < 2) return refuse("too few accepted steps before the crossing");
  // The start: the last accepted step with rho >= start_rho (its accelerations accurate),
  // approaching the crossing from there (every later step closer).
  double fit_rho = kBridgeFitRho;
  const double start_rho = kBridgeStartFits * fit_rho;
  long is = static_cast<long>(N) - 1;
  while (is > 0 && tr[static_cast<size_t>(is)] < start_rho) --is;
  const double rho_s = tr[static_cast<size_t>(is)];
  if (rho_s > kBridgeMaxStartRho) return refuse("the solver stopped far from any crossing");
  // Closer than start_rho from the first kept step (a crossing soon after the start of the
  // run): the fit nodes move closer with it.
  fit_rho = std::min(fit_rho, rho_s / kBridgeStartFits);
  if (fit_rho < kBridgeMinFitRho) return refuse("no accepted step at a start distance");
  for (size_t i = static_cast<size_t>(is) + 1; i < N; ++i)
    if (tr[i] > rho_s) return refuse("the steps after the start move away from the crossing");
  // From there to rho = fit_rho by the classical Runge-Kutta method with small fixed steps
  // (rho falls by about fit_rho / kBridgeStepsPerFit per step): nodes (t, y, y') of
  // accurate equations, dense enough for the extrapolation's fit.
  Workspace& ws = *m.ws;
  auto Deriv = [&](double tt_, double* yy, double* ff) { return rt::Derivative(p, ws, tt_, yy, ff); };
  const int n = rt::StateSize(p);
  const size_t nn = static_cast<size_t>(n);
  m.nt.clear();
  m.ny.clear();
  m.nf.clear();
  m.nrho.clear();
  std::vector<double> y(ty[static_cast<size_t>(is)]), f(nn), tmp(nn);
  RungeKuttaScratch rk(nn);
  double t = tt[static_cast<size_t>(is)], rho = rho_s;
  if (m.sparse) ProjectStart(p, ws, t, &y);
  // rho's rate of fall, from a short Euler step.
  if (Deriv(t, y.data(), f.data()) != 0) return refuse("the equations failed on the approach");
  const double dt = 1e-3 * rho_s / std::max(1e-300, std::sqrt(Eigen::Map<const Eigen::VectorXd>(f.data(), n).squaredNorm()));
  for (size_t i = 0; i < nn; ++i) tmp[i] = y[i] + dt * f[i];
  const double r1 = RhoAt(p, m, t + dt, tmp.data());
  double slope = (rho_s - r1) / dt;
  if (!(slope > 0.0)) return refuse("rho does not fall toward the crossing");
  const double h = fit_rho / (kBridgeStepsPerFit * slope);
  m.bridge_h = h;
  for (int step = 0;; ++step) {
    if (Deriv(t, y.data(), f.data()) != 0) return refuse("the equations failed on the approach");
    m.nt.push_back(t);
    m.ny.push_back(y);
    m.nf.push_back(f);
    m.nrho.push_back(rho);
    if (rho <= fit_rho) break;
    if (step > kBridgeMaxSteps) return refuse("the approach to the crossing took too many steps");
    if (RungeKuttaStep(p, ws, t, h, f.data(), y.data(), rk) != 0) return refuse("the equations failed on the approach");
    t += h;
    const double r = RhoAt(p, m, t, y.data());
    if (!(r >= 0.0)) return refuse("the approach left the valid configurations");
    if (!(r < rho)) return refuse("rho does not fall toward the crossing");
    rho = r;
  }
  const size_t L = m.nt.size();
  if (L < 2 * kBridgeStepsPerFit / 3) return refuse("too few steps on the approach");
  slope = (m.nrho[L - 2] - m.nrho[L - 1]) / (m.nt[L - 1] - m.nt[L - 2]);
  const double tc = m.nt[L - 1] + m.nrho[L - 1] / slope;
  const double past = kBridgePast;
  const double tb = tc + past / slope;
  // Two extrapolations: the quintic Hermite through the nodes at rho ~ fit_rho, 2 fit_rho,
  // 3 fit_rho (the bridge), and the one through the nodes at ~ 2, 4, 6 fit_rho (farther,
  // less accurate): their difference bounds the bridge's error, as does the quartic
  // without the slope at the first node.
  auto node_at = [&](double r) {
    size_t best = 0;
    for (size_t i = 0; i < L; ++i)
      if (std::fabs(m.nrho[i] - r) < std::fabs(m.nrho[best] - r)) best = i;
    return best;
  };
  const double rl = m.nrho[L - 1];
  const size_t fit[3] = {node_at(3 * rl), node_at(2 * rl), L - 1};
  const size_t far[3] = {node_at(6 * rl), node_at(4 * rl), node_at(2 * rl)};
  if (!(fit[0] < fit[1] && fit[1] < fit[2]) || !(far[0] < far[1] && far[1] < far[2]))
    return refuse("too few steps on the approach");
  for (int k = 0; k < 3; ++k) {
    m.h_t[k] = m.nt[fit[k]];
    m.h_y[k] = m.ny[fit[k]];
    m.h_f[k] = m.nf[fit[k]];
  }
  double ft[3];
  std::vector<double> fy[3], ff[3];
  for (int k = 0; k < 3; ++k) {
    ft[k] = m.nt[far[k]];
    fy[k] = m.ny[far[k]];
    ff[k] = m.nf[far[k]];
  }
  m.h_first = 0;
  double est = 0.0, cons = 0.0;
  for (size_t i = 0; i < nn; ++i) {
    y_b[i] = HermiteAt(m.h_t, m.h_y, m.h_f, 3, false, i, tb);
    const double w = atol + rtol * std::fabs(y_b[i]);
    est = std::max(est, std::fabs(HermiteAt(m.h_t, m.h_y, m.h_f, 3, true, i, tb) - y_b[i]) / w);
    cons = std::max(cons, std::fabs(HermiteAt(ft, fy, ff, 3, false, i, tb) - y_b[i]) / w);
  }
  m.bridge_estimate = std::max(est, cons);
  const char* why = nullptr;
  double rho_b = 0.0, moved = 0.0;
  int near_loops = 0;
  std::vector<double> raw(y_b, y_b + n);
  // On the reduced form an estimate between kBridgeMaxErrorReduced and
  // kBridgeMaxErrorSeveral passes only where several loops are near singular at the bridged
  // state (checked after the projection below).
  const bool sparse = m.sparse;
  const bool needs_several = !sparse && m.bridge_estimate > kBridgeMaxErrorReduced;
  // An estimate above the form's limit is measured again after the projection, where several
  // loops are near singular at the bridged state (the comparisons projected as the bridged
  // state is; on the reduced form in the kinetic metric), limited by kBridgeMaxErrorSeveral.
  bool needs_projected = m.switches.several_loops && m.switches.projected_estimate &&
                         m.bridge_estimate > (sparse ? kBridgeMaxError : kBridgeMaxErrorSeveral) &&
                         m.bridge_estimate <= kBridgeMaxRawSeveral;
  if (needs_projected) {  // several loops near singular at the approach's last node (else as before: refused)
    int near_last = 0;
    needs_projected = RhoAt(p, m, m.nt[L - 1], m.ny[L - 1].data(), &near_last) >= 0.0 && near_last > 1;
  }
  m.projected_est = -1.0;
  if (!(m.bridge_estimate <= (sparse ? kBridgeMaxError : m.switches.several_loops ? kBridgeMaxErrorSeveral : kBridgeMaxErrorReduced)) &&
      !needs_projected) {
    why = kEstimateAbove;
  } else if (rt::ProjectOntoConstraints(p, ws, tb, y_b) != 0 ||
             ((rho_b = RhoAt(p, m, tb, y_b, &near_loops)) >= 0.0 && !sparse && near_loops > 1 &&
              MetricSpeeds(p, m, tb, raw.data(), y_b) != 0)) {
    why = needs_several ? kEstimateAbove : "the bridged state could not be projected";
  } else {
    for (int i = 0; i < n; ++i) {
      const double d = std::fabs(y_b[i] - raw[static_cast<size_t>(i)]) / std::max(1.0, std::fabs(raw[static_cast<size_t>(i)]));
      moved = std::isnan(d) ? INFINITY : std::max(moved, d);
    }
    if (needs_projected && near_loops > 1 && moved <= kBridgeMovedSeveral) {
      std::vector<double> yq(nn), yf(nn);
      for (size_t i = 0; i < nn; ++i) {
        yq[i] = HermiteAt(m.h_t, m.h_y, m.h_f, 3, true, i, tb);
        yf[i] = HermiteAt(ft, fy, ff, 3, false, i, tb);
      }
      double pe = INFINITY;
      std::vector<double> rq(yq), rf(yf);
      if (rt::ProjectOntoConstraints(p, ws, tb, yq.data()) == 0 && rt::ProjectOntoConstraints(p, ws, tb, yf.data()) == 0 &&
          (sparse || (MetricSpeeds(p, m, tb, rq.data(), yq.data()) == 0 && MetricSpeeds(p, m, tb, rf.data(), yf.data()) == 0))) {
        pe = 0.0;
        for (size_t i = 0; i < nn; ++i) {
          const double w = atol + rtol * std::fabs(y_b[i]);
          const double e = std::max(std::fabs(yq[i] - y_b[i]), std::fabs(yf[i] - y_b[i])) / w;
          pe = std::isnan(e) ? INFINITY : std::max(pe, e);
        }
      }
      m.projected_est = pe;
    }
    if ((needs_several || needs_projected) && near_loops < 2)
      why = kEstimateAbove;
    else if (!(moved <= (needs_projected || (sparse && m.switches.several_loops && m.switches.projected_estimate && near_loops > 1) ? kBridgeMovedSeveral : kBridgeMoved)))
      why = "the projection moved the bridged state too far";
    else if (!(rho_b >= 0.0))
      why = "the bridged state is not valid";
    else if (needs_projected &&
             !(m.projected_est >= 0.0 && m.projected_est <= (sparse ? kBridgeMaxProjected : kBridgeMaxErrorSeveral)))
      why = kEstimateAbove;
    else if (near_loops > 1 && !m.switches.several_loops)
      why = kSeveralLoops;
    else if (rho_b < 0.25 * past)
      why = "the bridged state is not past the crossing";
  }
  if (why) return refuse(why);
  m.bridged = true;
  m.zone_steps = 0;
  *t_from = m.nt[0];
  *t_b = tb;
  return 0;
}

// A change point the solver passed by itself (the zone's rho rising after falling, no
// bridge): the steps over it evaluated the equations close to the crossing, where they are
// inaccurate (the reduced form's accelerations off by ~c / rho^3), and an energy or turn
// check does not see the error (measured: ARKODE at rtol 1e-12 passed one in a single step
// from rho >= 1e-2 to 3e-3 past it with an energy jump of 6.7e-6 J). Checked against the
// bridge's own approach from the same steps before it, extrapolated to the current step:
// within the bridge's limit (in units of atol + rtol |y|) it stands, else the bridge
// replaces it (the step fails, the integrator restarts from the bridge), and when no bridge
// can be computed the passage stands unchecked (docs/constraints.md).
int CheckPassage(const Program& p, ChangePointBridge& m, double t, const double* y, bool near) {
  // The steps before the current one (inside the zone it is the trace's last).
  const size_t N = m.trace_t.size() - (near ? 1 : 0);
  if (N < 2 || !(m.in_zone || !near)) return 0;
  const double rho_now = near ? m.trace_rho.back() : 1.0;
  if (near && !(rho_now > m.trace_rho[N - 1])) return 0;  // still approaching
  if (!(m.trace_t[N - 1] > m.last_tb)) return 0;
  m.passage_checked = true;
  double keep_t = 0.0, keep_rho = 0.0;
  std::vector<double> keep_y;
  if (near) {
    keep_t = m.trace_t.back();
    keep_rho = m.trace_rho.back();
    keep_y = std::move(m.trace_y.back());
    m.trace_t.pop_back();
    m.trace_rho.pop_back();
    m.trace_y.pop_back();
  }
  // Several loops near singular at once (a chain of equal-link parallelograms): the passage
  // stands unchecked. The approach costs the chain of 40 at rtol 1e-8 0.39 -> 0.79 s CPU,
  // and its estimate there is dominated by the round-off of the ill-conditioned block's
  // speeds, so it would replace accurate passages with noisier bridges (measured: ARKODE on
  // the chain of two at rtol 1e-12 ended 2e-6 rad off the lumped crank with these passages
  // checked, 3.9e-7 without; docs/constraints.md).
  if (m.zone_near > 1) {
    ++m.passages_unchecked;
    return 0;
  }
  const bool in_zone = m.in_zone;
  m.in_zone = true;
  const size_t n = static_cast<size_t>(rt::StateSize(p));
  double from = 0.0, tb = 0.0;
  std::vector<double> yb(n), yr(n);
  const int s = BridgeByApproach(p, m, m.early_rtol, m.early_atol, &from, &tb, yb.data());
  m.in_zone = in_zone;
  if (near) {
    m.trace_t.push_back(keep_t);
    m.trace_rho.push_back(keep_rho);
    m.trace_y.push_back(std::move(keep_y));
  }
  if (s != 0) {
    ++m.passages_unchecked;
    return 0;
  }
  // The bridge's state carried to the current step (the same Runge-Kutta steps; the
  // equations past the bridge's end, rho >= 3e-3, are accurate).
  {
    Workspace& ws = *m.ws;
    const long steps = std::max(1L, std::lround(std::ceil(std::fabs(t - tb) / std::max(1e-300, m.bridge_h))));
    if (steps > kBridgeMaxSteps) {
      ++m.passages_unchecked;
      return 0;
    }
    const double h = (t - tb) / static_cast<double>(steps);
    std::vector<double> f(n);
    RungeKuttaScratch rk(n);
    yr = yb;
    double tt = tb;
    for (long i = 0; i < steps; ++i) {
      if (rt::Derivative(p, ws, tt, yr.data(), f.data()) != 0 || RungeKuttaStep(p, ws, tt, h, f.data(), yr.data(), rk) != 0) {
        ++m.passages_unchecked;
        return 0;
      }
      tt += h;
    }
  }
  double d = 0.0;
  for (size_t i = 0; i < n; ++i) {
    const double e = std::fabs(y[i] - yr[i]) / (m.early_atol + m.early_rtol * std::fabs(y[i]));
    d = std::isnan(e) ? INFINITY : std::max(d, e);
  }
  const double limit = m.sparse ? kBridgeMaxError : kBridgeMaxErrorReduced;
  ++m.passages_checked;
  if (d <= limit) return 0;
  // Replaced by the bridge.
  m.pending = true;
  m.pend_from = from;
  m.pend_tb = tb;
  m.pend_y = std::move(yb);
  if (!near && !m.pre_t.empty() && m.pre_t.back() == t) {  // the current step, dropped
    m.pre_t.pop_back();
    m.pre_rho.pop_back();
    m.pre_y.pop_back();
  }
  char buf[512];
  std::snprintf(buf, sizeof buf,
                "closed loop '%s' at a singular configuration at time %.9g: the integrator passed the change point "
                "with an error of %.3g tolerance units against the bridge over it, and the bridge could not be used",
                rt::LoopName(p, std::max(0, m.zone_loop)).c_str(), t, d);
  m.error = buf;
  return -1;
}
int BridgeChangePoint(const Program& p, ChangePointBridge& m, double rtol, double atol, double* t_from, double* t_b,
                      double* y_b) {
  if (m.pending) {  // computed by CheckStep
    m.pending = false;
    m.last_tb = m.pend_tb;
    *t_from = m.pend_from;
    *t_b = m.pend_tb;
    std::copy(m.pend_y.begin(), m.pend_y.end(), y_b);
    return 0;
  }
  if (m.in_zone && m.bridged) {
    m.bridge_refused = "this zone was bridged once already";
    return 1;
  }
  if (BridgeByApproach(p, m, rtol, atol, t_from, t_b, y_b) == 0) {
    m.last_tb = *t_b;
    return 0;
  }
  const std::string first = m.bridge_refused;
  if (BridgeByZoneFit(p, m, rtol, atol, t_from, t_b, y_b) == 0) {
    m.last_tb = *t_b;
    return 0;
  }
  m.bridge_refused = first + "; " + m.bridge_refused;
  return 1;
}

void BridgedState(const ChangePointBridge& m, double t, double* y) {
  const size_t L = m.nt.size();
  if (L >= 2 && t <= m.nt[L - 1]) {
    // On the approach: the cubic Hermite between its two nodes around t.
    size_t j = 1;
    while (j + 1 < L && m.nt[j] < t) ++j;
    for (size_t i = 0; i < m.ny[0].size(); ++i) y[i] = HermiteAt(&m.nt[j - 1], &m.ny[j - 1], &m.nf[j - 1], 2, false, i, t);
    return;
  }
  const int f = m.h_first;
  for (size_t i = 0; i < m.h_y[0].size(); ++i) y[i] = HermiteAt(m.h_t + f, m.h_y + f, m.h_f + f, 3 - f, false, i, t);
}

}  // namespace kanesim::sim
