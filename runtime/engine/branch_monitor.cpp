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

}  // namespace

int CheckBranch(const Program& p, BranchMonitor& m, double t, const double* y) {
  if (p.loops.empty()) return 0;
  Workspace& ws = *m.ws;
  if (int s = UnpackState(p, ws, t, y); s != 0) return 0;  // Derivative reports these
  PositionKinematics(p, ws);
  VelocityKinematics(p, ws);
  ConstraintJacobian(p, ws);
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
    if (lr < rho) {
      rho = lr;
      worst = static_cast<int>(li);
    }
  }
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
      m.zone_steps = 0;
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
  }
  if (!near || !m.have_ref) {
    m.ref_u = ws.u;
    m.ref_t = t;
    m.have_ref = true;
  }
  return 0;
}

}  // namespace kanesim::rt
