// Branch monitor for closed loops (engine.h CheckBranch; docs/constraints.md "Singular
// configurations"; issue 20). A loop passing a change point (its constraint rows lose
// rank: a parallelogram four-bar with its links in line) meets other assembly branches.
// The physical continuation keeps the momentum: the velocity just after the singular
// point continues the one before. A numerical solution may instead turn onto another
// branch: Newton leaves a residual, so the projected positions lie on a level set
// phi = c close to the crossing, which bends from one branch onto the other within
// sqrt(c) of it; the integrator follows that bend smoothly (energy kept) with huge
// constraint forces, and without a check the run would end with exit code 0 on the wrong
// branch.
//
// After each accepted step the monitor measures, per loop l, how close its active rows
// are to losing rank, rho_l = sigma_min / sigma_max of A_l (its rows of the constraint
// Jacobian, over all free speeds; from the eigenvalues of A_l A_l^T), and the velocity
// in the kinetic metric, through the bodies' mass-centre velocities and angular
// velocities (<V, W> = sum m v_V . v_W + w_V^T I w_W, so <V, V> = 2 T).
// A loop with rho_l < kZone is "near singular". The velocity of the last accepted step
// outside every such zone is the reference; at every step inside a zone and at the first
// one after it, the angle between the reference and the current velocity (unsigned: a
// motion that stops and returns keeps its line) must stay below kTurn. Inside a zone of
// rho < 1e-2 the mechanism moves by about 1 % of its size, over which a branch bends by
// far less than kTurn; two branches meeting at a change point cross at a finite angle
// (the parallelogram and the folded branch of an equal-link four-bar at about 50 degrees
// in this metric), so a turn by more than kTurn is a branch switch: the run stops (exit
// code 2) with the loop, the time and the angle. Velocities below kSlow of the
// reference's are too small to carry a direction and are not compared.
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "runtime/constraints/constraints.h"
#include "runtime/engine/engine.h"
#include "runtime/kinematics/kinematics.h"
#include "runtime/program/program.h"

namespace kanesim::rt {

namespace {
constexpr double kZone = 1e-2;
constexpr double kTurn = 0.05;  // rad
constexpr double kSlow = 1e-3;  // of the reference's speed (kinetic-metric norm)
// Accepted steps inside one near-singular zone after which the run stops: a passage
// takes a few (measured: at most 9 on the equal-link parallelogram, every integrator,
// rtol 1e-4 ... 1e-10);
// a solver creeping towards the singular configuration in ever smaller steps would
// otherwise run into its step limit per output instant, minutes later.
constexpr long kMaxZoneSteps = 1000;
constexpr size_t kPreZone = 4;  // accepted steps before a zone kept for a bridge's fit
constexpr double kRankTol = 1e-9;  // sigma / sigma_max below which a row counts as dependent (assembly's)
}  // namespace

struct BranchMonitor {
  std::unique_ptr<Workspace, void (*)(Workspace*)> ws{nullptr, [](Workspace*) {}};
  bool have_ref = false, in_zone = false;
  double ref_t = 0.0, zone_t = 0.0, zone_rho = 1.0;
  int zone_loop = -1;
  long zone_steps = 0;
  std::vector<int> loop_rank;  // per loop: independent rows at the first check
  Eigen::VectorXd ref_u, cur_u;     // all joint speeds
  std::vector<Vec3> cur_v, cur_w;  // the current step's mass-centre and angular velocities
  std::string error;
  // The bridge (BridgeChangePoint): the accepted steps of the current zone, the last one
  // before it first; the last accepted step (to start a zone's trace with).
  std::vector<double> trace_t, trace_rho;
  std::vector<std::vector<double>> trace_y;
  std::vector<double> pre_t, pre_rho;  // the last kPreZone accepted steps (outside a zone)
  std::vector<std::vector<double>> pre_y;
  bool bridged = false;  // this zone was bridged once: a second stall in it stops
  // The Hermite fit of the last bridge (three accepted steps: t, y, y'), for the output
  // rows in its gap (BridgeState).
  double h_t[3] = {0.0, 0.0, 0.0};
  std::vector<double> h_y[3], h_f[3];
  int h_first = 0;  // 0: the quintic through the three; 1: the cubic through the last two
  std::string bridge_refused;  // why the last bridge was refused
  double bridge_estimate = 0.0;  // the last bridge's error estimate, in units of the tolerance
};

std::unique_ptr<BranchMonitor, void (*)(BranchMonitor*)> MakeBranchMonitor(const Program& p) {
  std::unique_ptr<BranchMonitor, void (*)(BranchMonitor*)> m(new BranchMonitor, [](BranchMonitor* x) { delete x; });
  if (p.loops.empty()) return m;
  m->ws = MakeWorkspace(p);
  return m;
}

bool BranchMonitorActive(const Program& p) { return !p.loops.empty(); }

const std::string& BranchMonitorError(const BranchMonitor& m) { return m.error; }

namespace {

// <a, b> in the kinetic metric at the workspace's configuration.
double Metric(const Program& p, const Workspace& ws, const std::vector<Vec3>& va, const std::vector<Vec3>& wa,
              const std::vector<Vec3>& vb, const std::vector<Vec3>& wb) {
  double s = 0.0;
  for (size_t L = 0; L < p.bodies.size(); ++L) s += p.bodies[L].mass * va[L].dot(vb[L]) + wa[L].dot(ws.I_W[L] * wb[L]);
  return s;
}

// rho = sigma_min/sigma_max of the nearest-singular loop's rows at the configuration in
// m.ws (ConstraintJacobian done); returns that loop (-1: none).
int NearestSingularLoop(const Program& p, BranchMonitor& m, double* rho_out, int* near_loops = nullptr) {
  Workspace& ws = *m.ws;
  // The nearest-singular loop. Its rank at the start counts its independent rows: with
  // every row kept (`--reactions min-norm`, friction) the redundant ones are among them.
  const bool first = m.loop_rank.empty();
  if (first) m.loop_rank.assign(p.loops.size(), 0);
  double rho = 1.0;
  int worst = -1;
  for (size_t li = 0; li < p.loops.size(); ++li) {
    const LoopClosure& l = p.loops[li];
    int idx[6], r = 0;
    for (int i = l.row0; i < l.row0 + l.nrows && r < 6; ++i)
      if (int k = p.active_of_row[static_cast<size_t>(i)]; k >= 0) idx[r++] = k;
    if (r == 0) continue;
    Eigen::Matrix<double, 6, 6> G = Eigen::Matrix<double, 6, 6>::Zero();
    for (int i = 0; i < r; ++i)
      for (int k = 0; k <= i; ++k) G(i, k) = G(k, i) = ws.A.row(idx[i]).dot(ws.A.row(idx[k]));
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(G.topLeftCorner(r, r), Eigen::EigenvaluesOnly);
    const auto& ev = es.eigenvalues();  // ascending
    if (!(ev[r - 1] > 0.0)) continue;
    if (first)
      for (int i = 0; i < r; ++i) m.loop_rank[li] += ev[i] > kRankTol * kRankTol * ev[r - 1];
    const int rank = m.loop_rank[li];
    if (rank == 0) continue;
    const double lr = std::sqrt(std::max(0.0, ev[r - rank]) / ev[r - 1]);
    if (near_loops && lr < kZone) ++*near_loops;
    if (lr < rho) {
      rho = lr;
      worst = static_cast<int>(li);
    }
  }
  *rho_out = rho;
  return worst;
}

}  // namespace

int CheckBranch(const Program& p, BranchMonitor& m, double t, const double* y) {
  if (p.loops.empty()) return 0;
  Workspace& ws = *m.ws;
  if (int s = UnpackState(p, ws, t, y); s != 0) return 0;  // Derivative reports these
  PositionKinematics(p, ws);
  VelocityKinematics(p, ws);
  ConstraintJacobian(p, ws);
  double rho = 1.0;
  const int worst = NearestSingularLoop(p, m, &rho);
  const bool near = rho < kZone;
  if (m.have_ref && (near || m.in_zone)) {
    // The reference's joint speeds at the current configuration: the two velocities in
    // the kinetic metric of the same configuration.
    m.cur_v = ws.v_WBcm;
    m.cur_w = ws.w_WB;
    m.cur_u = ws.u;
    ws.u = m.ref_u;
    VelocityKinematics(p, ws);
    const double vv = Metric(p, ws, m.cur_v, m.cur_w, m.cur_v, m.cur_w);
    const double rr = Metric(p, ws, ws.v_WBcm, ws.w_WB, ws.v_WBcm, ws.w_WB);
    const double vr = Metric(p, ws, ws.v_WBcm, ws.w_WB, m.cur_v, m.cur_w);
    ws.u = m.cur_u;
    if (rr > 0.0 && vv > kSlow * kSlow * rr) {
      const double c = std::min(1.0, std::fabs(vr) / std::sqrt(vv * rr));
      const double angle = std::acos(c);
      if (angle > kTurn) {
        const int li = m.in_zone ? m.zone_loop : worst;
        char buf[512];
        std::snprintf(buf, sizeof buf,
                      "closed loop '%s' left its assembly branch at a singular configuration at time %.9g: its "
                      "constraint rows came within %.2g of losing rank (sigma_min/sigma_max) from time %.9g on, and "
                      "there the velocity turned by %.1f degrees in the kinetic-energy metric, more than the %.1f a "
                      "motion continuing through the change point can turn: the solution was following another "
                      "assembly branch (a change point where branches meet; the rows before it are on the branch)",
                      p.loops[static_cast<size_t>(li)].name.c_str(), t, m.in_zone ? m.zone_rho : rho,
                      m.in_zone ? m.zone_t : t, angle * 180.0 / M_PI, kTurn * 180.0 / M_PI);
        m.error = buf;
        return -1;
      }
    }
  }
  const size_t n = static_cast<size_t>(StateSize(p));
  if (near) {
    if (!m.in_zone) {
      m.in_zone = true;
      m.zone_t = t;
      m.zone_loop = worst;
      m.zone_rho = rho;
      m.zone_steps = 0;
      m.bridged = false;
      m.trace_t.clear();
      m.trace_rho.clear();
      m.trace_y.clear();
      m.trace_t = m.pre_t;
      m.trace_rho = m.pre_rho;
      m.trace_y = m.pre_y;
    }
    if (m.trace_t.size() < static_cast<size_t>(kMaxZoneSteps) + kPreZone + 1) {
      m.trace_t.push_back(t);
      m.trace_rho.push_back(rho);
      m.trace_y.emplace_back(y, y + n);
    }
    m.zone_rho = std::min(m.zone_rho, rho);
    if (++m.zone_steps > kMaxZoneSteps) {
      char buf[512];
      std::snprintf(buf, sizeof buf,
                    "closed loop '%s' at a singular configuration at time %.9g: the integrator took %ld steps since "
                    "time %.9g without passing the change point (the constraint rows within %.2g of losing rank, "
                    "sigma_min/sigma_max); near it the loop equations are too ill-conditioned for this tolerance "
                    "(try a looser --rtol, or --solver sparse)",
                    p.loops[static_cast<size_t>(m.zone_loop)].name.c_str(), t, m.zone_steps, m.zone_t, m.zone_rho);
      m.error = buf;
      return -1;
    }
  } else {
    m.in_zone = false;
    m.bridged = false;
  }
  if (!near) {
    if (m.pre_t.size() >= kPreZone) {
      std::rotate(m.pre_t.begin(), m.pre_t.begin() + 1, m.pre_t.end());
      std::rotate(m.pre_rho.begin(), m.pre_rho.begin() + 1, m.pre_rho.end());
      std::rotate(m.pre_y.begin(), m.pre_y.begin() + 1, m.pre_y.end());
      m.pre_t.back() = t;
      m.pre_rho.back() = rho;
      m.pre_y.back().assign(y, y + n);
    } else {
      m.pre_t.push_back(t);
      m.pre_rho.push_back(rho);
      m.pre_y.emplace_back(y, y + n);
    }
  }
  if (!near || !m.have_ref) {
    m.ref_u = ws.u;
    m.ref_t = t;
    m.have_ref = true;
  }
  return 0;
}


// The bridge over a near-singular zone (docs/constraints.md "Singular configurations").
// A solver approaching a change point at a tight tolerance shrinks its steps where the
// loop equations' conditioning degrades (the dependent accelerations' round-off goes like
// 1/rho^2) and stalls short of the crossing; moving away from it is not the difficulty
// (a run started 1e-4 past the crossing continues at rtol 1e-12 with every solver). So:
// rho falls linearly to the crossing, which the two accepted steps (t1, rho1), (t2, rho2)
// of the zone locate; the cubic Hermite through (y, y') at t1 and t2 extrapolates the
// motion to t_b, where rho is back to max(rho2, kBridgePast) on the far side; the state
// there is projected onto the position and velocity constraints (Newton from a point
// ~1e-12 off the continuing branch and ~rho off every other lands on it) and handed to a
// fresh solver. t2 is the last accepted step with rho >= kBridgeFitRho (its accelerations
// are still accurate), t1 the last before it with rho >= max(3 rho2, kBridgeFarRho).
namespace {
constexpr double kBridgeMaxRho = 1e-3;   // a stall farther than this from the crossing is not bridged
constexpr double kBridgeFitRho = 1e-3;   // t2: rho at least this
constexpr double kBridgeFarRho = 3e-3;   // t1: rho at least this
constexpr double kBridgePast = 1e-3;     // rho past the crossing where the bridge ends
constexpr double kBridgeMaxError = 1e5;  // the error estimate's limit, in units of atol + rtol |y| (at 1e6 two
                                         // runs ended 1e-4 off: docs/benchmarks.md)
constexpr double kBridgeMoved = 1e-6;    // largest change by the projection (of max(1, |y|))

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

int BridgeChangePoint(const Program& p, BranchMonitor& m, double rtol, double atol, double* t_from, double* t_b,
                      double* y_b) {
  auto refuse = [&m](const char* why) {
    m.bridge_refused = why;
    return 1;
  };
  if (p.loops.empty() || !m.in_zone) return refuse("not in a near-singular zone");
  if (m.bridged) return refuse("this zone was bridged once already");
  const size_t N = m.trace_t.size();
  if (N < 2) return refuse("too few accepted steps in the zone");
  double rho_min = 1.0;
  for (double r : m.trace_rho) rho_min = std::min(rho_min, r);
  if (rho_min > kBridgeMaxRho) return refuse("the solver stopped far from the crossing");
  long i2 = static_cast<long>(N) - 1;
  while (i2 >= 0 && m.trace_rho[static_cast<size_t>(i2)] < kBridgeFitRho) --i2;
  if (i2 < 1) return refuse("no accepted step at a fit distance");
  const double rho2 = m.trace_rho[static_cast<size_t>(i2)];
  // Approaching: every later step closer still.
  for (size_t i = static_cast<size_t>(i2) + 1; i < N; ++i)
    if (m.trace_rho[i] > rho2) return refuse("the steps after the fit point move away from the crossing");
  long i1 = i2 - 1;
  while (i1 >= 0 && m.trace_rho[static_cast<size_t>(i1)] < std::max(3.0 * rho2, kBridgeFarRho)) --i1;
  if (i1 < 0) return refuse("no accepted step far enough from the crossing");
  const double t1 = m.trace_t[static_cast<size_t>(i1)], t2 = m.trace_t[static_cast<size_t>(i2)];
  const double rho1 = m.trace_rho[static_cast<size_t>(i1)];
  if (!(t2 > t1) || !(rho1 > rho2)) return refuse("rho does not fall toward the crossing");
  const double slope = (rho1 - rho2) / (t2 - t1);
  const double tc = t2 + rho2 / slope;
  const double tb = tc + std::max(rho2, kBridgePast) / slope;
  // The third fit point, before t1 (rho at least 3 rho1): the quintic Hermite through the
  // three, its error estimated by the quartic without the slope at t0 (their difference).
  long i0 = i1 - 1;
  while (i0 > 0 && m.trace_rho[static_cast<size_t>(i0)] < 3.0 * rho1) --i0;
  if (i0 < 0 || !(m.trace_rho[static_cast<size_t>(i0)] > rho1)) return refuse("no accepted step for the error estimate");
  Workspace& ws = *m.ws;
  const int n = StateSize(p);
  const long idx[3] = {i0, i1, i2};
  for (int k = 0; k < 3; ++k) {
    m.h_t[k] = m.trace_t[static_cast<size_t>(idx[k])];
    m.h_y[k] = m.trace_y[static_cast<size_t>(idx[k])];
    m.h_f[k].assign(static_cast<size_t>(n), 0.0);
    if (Derivative(p, ws, m.h_t[k], m.h_y[k].data(), m.h_f[k].data()) != 0)
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
    if (!(est <= kBridgeMaxError)) {
      why = "the extrapolation's error estimate is above the tolerance";
      continue;
    }
    std::vector<double> raw(y_b, y_b + n);
    if (ProjectOntoConstraints(p, ws, tb, y_b) != 0) {
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
    if (UnpackState(p, ws, tb, y_b) != 0) {
      why = "the bridged state is not valid";
      continue;
    }
    PositionKinematics(p, ws);
    VelocityKinematics(p, ws);
    ConstraintJacobian(p, ws);
    int near_loops = 0;
    NearestSingularLoop(p, m, &rho_b, &near_loops);
    if (near_loops > 1) {
      // Measured: a chain of two equal-link parallelograms (both loops singular at once)
      // bridged onto the branch but 1.7e-4 rad off the lumped crank after 20 s at rtol
      // 1e-12; not understood, so not bridged.
      why = "more than one loop is near a singular configuration";
      break;
    }
    if (rho_b < 0.25 * std::max(rho2, kBridgePast)) {
      why = "the bridged state is not past the crossing";
      continue;
    }
    why = nullptr;
    break;
  }
  if (why) return refuse(why);
  m.bridged = true;
  m.zone_steps = 0;
  *t_from = m.h_t[m.h_first];
  *t_b = tb;
  return 0;
}

void BridgeState(const BranchMonitor& m, double t, double* y) {
  const int f = m.h_first;
  for (size_t i = 0; i < m.h_y[0].size(); ++i) y[i] = HermiteAt(m.h_t + f, m.h_y + f, m.h_f + f, 3 - f, false, i, t);
}

const std::string& BridgeRefused(const BranchMonitor& m) { return m.bridge_refused; }

}  // namespace kanesim::rt
