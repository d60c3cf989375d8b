// Branch monitor for closed loops (runtime/runtime.h CheckBranch; docs/constraints.md "Singular
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
#include "runtime/engine/branch_monitor_internal.h"
#include "runtime/runtime.h"
#include "runtime/kinematics/kinematics.h"
#include "runtime/program/program.h"

namespace kanesim::rt {

namespace {
constexpr double kZone = 1e-2;
constexpr double kTurn = 0.05;  // rad
constexpr double kSlow = 1e-3;  // of the reference's speed (kinetic-metric norm)
}  // namespace

std::unique_ptr<BranchMonitor, void (*)(BranchMonitor*)> MakeBranchMonitor(const Program& p) {
  std::unique_ptr<BranchMonitor, void (*)(BranchMonitor*)> m(new BranchMonitor, [](BranchMonitor* x) { delete x; });
  if (p.loops.empty()) return m;
  m->ws = MakeWorkspace(p);
  // The bridge's approach and the passage check evaluate the equations close to a change
  // point, where the accelerations are off by ~c / rho^3 for a Newton residual c: on this
  // workspace Newton goes to round-off (measurements: docs/constraints/2026-11-28_tuning_measurements.md).
  m->ws->newton_to_round_off = true;
  return m;
}

bool BranchMonitorActive(const Program& p) { return !p.loops.empty(); }

const std::string& BranchMonitorError(const BranchMonitor& m) { return m.error; }

// runtime/runtime.h.
double LoopSingularRatio(const Program& p, const Workspace& ws, int loop, double* length) {
  const LoopClosure& l = p.loops[static_cast<size_t>(loop)];
  // Its rows of ws.A and its rank at the assembled start: those rows less the ones found
  // redundant there (compile/loops.cpp keeps a redundant row among the active ones
  // unless it is zero).
  int idx[6], r = 0, rank = 0;
  bool translation[6];
  for (int i = l.row0; i < l.row0 + l.nrows && r < 6; ++i)
    if (int k = p.active_of_row[static_cast<size_t>(i)]; k >= 0) {
      translation[r] = p.rows[static_cast<size_t>(i)].kind == RowKind::Translation;
      idx[r++] = k;
      rank += !std::binary_search(p.redundant_rows.begin(), p.redundant_rows.end(), i);
    }
  if (rank == 0) return 1.0;
  if (!(*length > 0.0)) *length = LoopLeverArm(p, ws, loop);
  // Translation rows (m per unit speed) over the loop's length, alignment rows as they are
  // (per radian): sigma_min / sigma_max is then the same for the loop built in millimetres
  // or in metres.
  double scale[6];
  for (int i = 0; i < r; ++i) scale[i] = translation[i] ? 1.0 / *length : 1.0;
  // At most 6 x 6 (one loop's rows): a fixed-capacity matrix, so no allocation per loop per step.
  Eigen::Matrix<double, 6, 6> G = Eigen::Matrix<double, 6, 6>::Zero();
  for (int i = 0; i < r; ++i)
    for (int k = 0; k <= i; ++k) G(i, k) = G(k, i) = scale[i] * scale[k] * ws.A.row(idx[i]).dot(ws.A.row(idx[k]));
  using Small = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 6, 6>;
  Eigen::SelfAdjointEigenSolver<Small> es(Small(G.topLeftCorner(r, r)), Eigen::EigenvaluesOnly);
  const auto& ev = es.eigenvalues();  // ascending
  if (!(ev[r - 1] > 0.0)) return 1.0;
  return std::sqrt(std::max(0.0, ev[r - rank]) / ev[r - 1]);
}

// branch_monitor_internal.h.
int NearestSingularLoop(const Program& p, BranchMonitor& m, double* rho_out, int* near_loops) {
  Workspace& ws = *m.ws;
  // The nearest-singular loop, its length taken at the first check. A loop whose redundant
  // rows are not zero keeps them among its rows (compile/loops.cpp), and so does every loop
  // with `--reactions min-norm` or friction: a redundant row (dependent at every
  // configuration) then never takes the rank below the start's; only a change point does
  // (docs/constraints.md "Redundant or singular").
  if (m.loop_length.empty()) m.loop_length.assign(p.loops.size(), 0.0);
  double rho = 1.0;
  int worst = -1;
  for (size_t li = 0; li < p.loops.size(); ++li) {
    const double lr = LoopSingularRatio(p, ws, static_cast<int>(li), &m.loop_length[li]);
    if (near_loops && lr < kZone) ++*near_loops;
    if (lr < rho) {
      rho = lr;
      worst = static_cast<int>(li);
    }
  }
  *rho_out = rho;
  return worst;
}

void ForgetBranchReference(BranchMonitor& m) { m.have_ref = false; }

int CheckBranch(const Program& p, BranchMonitor& m, double t, const double* y, BranchStep* step) {
  if (p.loops.empty()) return 0;
  Workspace& ws = *m.ws;
  if (int s = UnpackState(p, ws, t, y); s != 0) return 0;  // Derivative reports these
  PositionKinematics(p, ws);
  VelocityKinematics(p, ws);
  ConstraintJacobian(p, ws);
  double rho = 1.0;
  int near_loops = 0;
  const int worst = NearestSingularLoop(p, m, &rho, &near_loops);
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
  if (near) {
    if (!m.in_zone) {
      m.in_zone = true;
      m.zone_t = t;
      m.zone_loop = worst;
      m.zone_rho = rho;
    }
    m.zone_rho = std::min(m.zone_rho, rho);
  } else {
    m.in_zone = false;
  }
  if (!near || !m.have_ref) {
    m.ref_u = ws.u;
    m.ref_t = t;
    m.have_ref = true;
  }
  if (step) {
    step->valid = true;
    step->rho = rho;
    step->near_loops = near_loops;
    step->near = near;
    step->zone_loop = m.zone_loop;
    step->zone_t = m.zone_t;
    step->zone_rho = m.zone_rho;
  }
  return 0;
}

}  // namespace kanesim::rt
