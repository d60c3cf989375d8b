// Static equilibrium: Newton on the independent accelerations with every speed zero,
//
//   r(xi_I) = u_I'(xi_I, u = 0) = 0,   J = dr/dxi_I (central differences),
//   xi_I <- xi_I - alpha J^+ r,        alpha = 1, 1/2, ... until |r|_2 decreases      (8)
//
// where J^+ is the minimum-norm pseudo-inverse (complete orthogonal decomposition):
// directions without stiffness (ignorable coordinates) do not move. After each step the
// chart and the partition are rebuilt about the new point, so the dependent coordinates
// and the quaternion charts never stray far from their centre.
#include <fmt/core.h>

#include <Eigen/QR>
#include <algorithm>
#include <cmath>

#include "linearize/linearize.h"
#include "linearize/hybrid.h"
#include "linearize/reduction.h"
#include "runtime/program/program.h"

namespace kanesim::lin {

namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

// r at chart deviation xi_I about the reduction's centre; *y receives the state.
Status Residual(const rt::Program& p, rt::Workspace& ws, Reduction& red, const VectorXd& xi_I, VectorXd* r,
                VectorXd* y) {
  const int nui = static_cast<int>(red.indep_speeds().size());
  if (Status s = red.StateOf(xi_I, VectorXd::Zero(nui), y); !s.ok()) return s;
  VectorXd ydot(y->size());
  if (rt::Derivative(p, ws, red.t(), y->data(), ydot.data()) != 0)
    return {2, "the equations of motion fail during the equilibrium search: " + rt::ErrorMessage(ws)};
  r->resize(nui);
  for (int k = 0; k < nui; ++k) (*r)[k] = ydot[p.nq + red.indep_speeds()[static_cast<size_t>(k)]];
  return {};
}

// Fallback when Newton stalls (a residual minimum that is no zero): the motion with its
// kinetic energy taken away whenever it climbs (v . r < 0), in the spirit of FIRE
// (Bitzek et al., Phys. Rev. Lett. 97, 170201, 2006), on the chart coordinates with
// v' = r (the accelerations at rest), xi' = v (symplectic Euler, step halved when it
// climbs, grown by 10% while it descends). It settles near a minimum of the potential,
// where Newton then converges. Only for as many speeds as coordinates (no rolling rows).
// The chart is rebuilt every 20 steps. *steps counts them.
Status Relax(const rt::Program& p, rt::Workspace& ws, const std::vector<double>& inputs, double until,
             OperatingPoint* op, long* steps) {
  VectorXd v;
  double dt = 1e-3;
  for (int block = 0; block < 2000; ++block) {
    Reduction red;
    red.SetInputs(inputs);
    if (Status s = red.Init(p, *op, true); !s.ok()) return s;
    const int n = static_cast<int>(red.indep_coords().size());
    if (n != static_cast<int>(red.indep_speeds().size())) return {2, "rolling rows: no relaxation"};
    if (v.size() != n) v = VectorXd::Zero(n);
    VectorXd xi = VectorXd::Zero(n), r, y;
    for (int k = 0; k < 20; ++k, ++*steps) {
      if (Status s = Residual(p, ws, red, xi, &r, &y); !s.ok()) return s;
      if (r.cwiseAbs().maxCoeff() <= until) {
        op->y.assign(y.data(), y.data() + y.size());
        return {};
      }
      if (v.dot(r) < 0) {
        v.setZero();
        dt = std::max(dt / 2, 1e-6);
      } else {
        dt = std::min(dt * 1.1, 0.05);
      }
      v += dt * r;
      xi += dt * v;
    }
    if (Status s = red.StateOf(xi, VectorXd::Zero(n), &y); !s.ok()) return s;
    op->y.assign(y.data(), y.data() + y.size());
  }
  return {2, "the relaxation did not settle"};
}

}  // namespace

Status FindEquilibrium(const rt::Program& p, const OperatingPoint& start, EquilibriumResult* out,
                       const std::vector<double>& inputs) {
  *out = EquilibriumResult{};
  if (Hybrid::Present(p))  // a rest on a stop or a stuck joint is no root of the free accelerations
    return {1,
            "--equilibrium: the model has end stops, plane contacts or exact friction (friction_exact), whose rests "
            "the search does not handle",
            "linearize at start values that rest (on a stop, stuck), or at a time of the motion (--at T)"};
  OperatingPoint op = start;
  for (int i = 0; i < p.nu; ++i) op.y[static_cast<size_t>(p.nq + i)] = 0.0;
  auto ws = rt::MakeWorkspace(p);
  if (!inputs.empty()) rt::SetInputValues(*ws, inputs.data());
  Reduction first;
  first.SetInputs(inputs);
  if (Status s = first.Init(p, op, true); !s.ok()) return s;
  op.y = first.y0();

  const double g = p.gravity_W.norm();
  double tol = -1.0;
  const int kMaxIter = 100;
  VectorXd r, y;
  int it = 0;
  bool relaxed = false;
  for (;; ++it) {
    Reduction red;
    red.SetInputs(inputs);
    if (Status s = red.Init(p, op, true); !s.ok()) return s;
    const int n = static_cast<int>(red.indep_coords().size());
    if (Status s = Residual(p, *ws, red, VectorXd::Zero(n), &r, &y); !s.ok()) return s;
    const double rn = r.size() ? r.cwiseAbs().maxCoeff() : 0.0, rn2 = r.norm();
    if (tol < 0) tol = 1e-10 * std::max({g, rn, 1e-2});
    out->residual = rn;
    if (rn <= tol || n == 0) break;
    if (it >= kMaxIter)
      return {2, fmt::format("no equilibrium found from the start values: the accelerations are still {:.3g} after {} "
                             "Newton iterations",
                             rn, it)};
    // J by central differences (step 1e-6 rad or m).
    const int nu_i = static_cast<int>(r.size());
    MatrixXd J(nu_i, n);
    for (int j = 0; j < n; ++j) {
      VectorXd x = VectorXd::Zero(n), rp, rm, yy;
      const double h = 1e-6;
      x[j] = h;
      if (Status s = Residual(p, *ws, red, x, &rp, &yy); !s.ok()) return s;
      x[j] = -h;
      if (Status s = Residual(p, *ws, red, x, &rm, &yy); !s.ok()) return s;
      J.col(j) = (rp - rm) / (2 * h);
    }
    Eigen::CompleteOrthogonalDecomposition<MatrixXd> cod(J);
    cod.setThreshold(1e-10);
    const VectorXd step = -cod.solve(r);
    bool improved = false;
    for (double alpha = 1.0; alpha >= 1.0 / (1 << 20); alpha /= 2) {
      VectorXd r2, y2;
      if (Status s = Residual(p, *ws, red, alpha * step, &r2, &y2); !s.ok()) continue;
      if (r2.norm() < rn2) {
        improved = true;
        op.y.assign(y2.data(), y2.data() + y2.size());
        break;
      }
    }
    if (!improved && !relaxed) {
      // Settle near a potential minimum first, then Newton again from there.
      relaxed = true;
      long steps = 0;
      OperatingPoint moved_op = op;
      if (Relax(p, *ws, inputs, 1e-3 * std::max({g, rn, 1e-2}), &moved_op, &steps).ok()) {
        op = moved_op;
        out->relaxation_steps = steps;
        continue;
      }
    }
    if (!improved) {
      Eigen::Index worst = 0;
      r.cwiseAbs().maxCoeff(&worst);
      return {2, fmt::format("no equilibrium found from the start values: Newton stalls after {} iterations with "
                             "accelerations {:.3g} (largest in {}); a constant force or torque without a restoring "
                             "one has no static equilibrium",
                             it, rn, red.speed_name(red.indep_speeds()[static_cast<size_t>(worst)]))};
    }
  }
  out->iterations = it;
  out->point = op;
  const VectorXd yfinal = Eigen::Map<const VectorXd>(op.y.data(), static_cast<Eigen::Index>(op.y.size()));
  const VectorXd moved = first.ChartOf(yfinal);
  for (int i = 0; i < p.nu; ++i)
    if (std::abs(moved[i]) > 1e-9) out->moved.emplace_back(first.coord_name(i), moved[i]);
  return {};
}

}  // namespace kanesim::lin
