// Linearize: eq. (1) of linearize.h by central differences and Richardson extrapolation.
//
//   D(h)  = (F(s + h+) - F(s - h-)) / (h+ + h-) = F'(s) + c2 h^2 + c4 h^4 + ...     (5)
//   R(h)  = (4 D(h/2) - D(h)) / 3               = F'(s) + O(h^4)                     (6)
//   error_ij = |R(h/2) - R(h)|_ij + 6 nu_i / h_j  (the achieved accuracy reported)   (7)
//   h_j  >= h_min = 2^22 eps max(1, max_k |x_k0|)  (a smaller step is widened to it)  (8)
//   nu_i  = eps (|F_i(0)| + sum_j |J_ij| max(1, |x_j0|))                             (9)
//
// where F stacks the state derivative [xi_I'; u_I'] and the output signals, s runs along
// one state or input x_j at a time, h+ and h- are the steps actually taken: the
// perturbed variable's value minus its value at the operating point, as rounded (s + h
// is not exactly s + h in floating point; Press et al., Numerical Recipes, 3rd ed., sec.
// 5.7). Rounding: nu_i bounds the rounding noise of F_i, taken as eps times the size of
// the terms that make it up (J = [A B; C D] the columns found, x_j0 the variable's value
// at the operating point); each D(h_k) carries up to nu_i / h_k of it, so R(h/2) = (4
// D(h/4) - D(h/2)) / 3 carries up to (16 + 2) nu_i / (3 h) = 6 nu_i / h. Without that term
// a step so small that every difference rounds to zero reported "A to 0" (issue 38). The
// floor (8) keeps the step taken at h/4 within 2^-20 of the step asked, and bounds the
// rounding term by 6 (n + 1) 2^-22 relative, so every difference keeps about six
// significant digits of the change. It is one floor for every column, from the largest
// variable: the noise of F_i comes from all the terms it sums, also when the step is in
// another, smaller variable (Richardson 1911; Dahlquist & Bjorck, Numerical Methods in
// Scientific Computing I, secs. 2.3 and 3.4).
#include "linearize/linearize.h"

#include <fmt/core.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <memory>

#include "linearize/hybrid.h"
#include "linearize/reduction.h"
#include "runtime/program/program.h"

namespace kanesim::lin {

namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

// A joint's generalized force as an input: a constant register added to its tau root in a
// copy of the program (the register's value lives in the workspace's force_regs).
struct JointInput {
  int free_speed = -1;
  int reg = -1;  // register of the input's value in force_regs
};

// A parameter input: the program rebound with the parameter moved (bound parameters follow).
struct ParamInput {
  int index = -1;  // into mech->params
};

struct Input {
  std::string name;
  bool is_joint = false;
  JointInput joint;
  ParamInput param;
};

// Resolves input names: "J.tau" / "J.tau[k]" (a joint's generalized force) or a real
// parameter. Joint inputs get a register in *prog (a copy of the program).
Status ResolveInputs(rt::Program* prog, const std::vector<std::string>& names, std::vector<Input>* out) {
  for (const std::string& name : names) {
    Input in;
    in.name = name;
    const size_t dot = name.rfind(".tau");
    if (dot != std::string::npos) {
      const std::string jname = name.substr(0, dot);
      std::string rest = name.substr(dot + 4);
      int k = 0;
      bool syntax = rest.empty();
      if (!rest.empty() && rest.front() == '[' && rest.back() == ']') {
        try {
          k = std::stoi(rest.substr(1, rest.size() - 2)) - 1;
          syntax = true;
        } catch (...) {
          syntax = false;
        }
      }
      const rt::TreeJoint* j = nullptr;
      for (const rt::TreeJoint& tj : prog->joints)
        if (tj.name == jname) j = &tj;
      if (j && syntax) {
        if (k < 0 || k >= j->nu || (rest.empty() && j->nu != 1))
          return {1, fmt::format("input '{}': joint '{}' has {} speed(s); name one as {}.tau[k], k = 1..{}", name,
                                 jname, j->nu, jname, j->nu)};
        const int r = j->u0 + k;
        const int f = prog->u_free_of[static_cast<size_t>(r)];
        if (f < 0) return {1, fmt::format("input '{}': that speed is prescribed", name)};
        rt::Tape& tape = prog->force_tape;
        rt::Scalar& tau = prog->joint_tau[static_cast<size_t>(r)];
        const int reg_in = tape.num_regs();
        tape.init.push_back(0.0);
        int reg_base;
        if (tau.root < 0) {
          reg_base = tape.num_regs();
          tape.init.push_back(tau.value);
        } else {
          reg_base = tape.roots[static_cast<size_t>(tau.root)];
        }
        const int reg_sum = tape.num_regs();
        tape.init.push_back(0.0);
        tape.code.push_back({flat::Op::Add, reg_sum, reg_base, reg_in, -1});
        tape.roots.push_back(reg_sum);
        tape.labels.push_back("input " + name);
        tape.texts.push_back(name);
        tau.root = static_cast<int>(tape.roots.size()) - 1;
        in.is_joint = true;
        in.joint = {f, reg_in};
        out->push_back(in);
        continue;
      }
    }
    const auto& params = prog->mech->params;
    int found = -1;
    for (size_t i = 0; i < params.size(); ++i)
      if (prog->mech->ParamName(i) == name) found = static_cast<int>(i);
    if (found < 0)
      return {1, fmt::format("input '{}' is neither a joint's generalized force (JOINT.tau, JOINT.tau[k]) nor a "
                             "parameter of the model",
                             name)};
    const flat::Param& pp = params[static_cast<size_t>(found)];
    if (pp.type != flat::ParamType::Real || pp.structural || pp.is_constant)
      return {1, fmt::format("input '{}': only a real, non-structural, non-constant parameter can be an input", name)};
    in.param.index = found;
    out->push_back(in);
  }
  return {};
}

constexpr double kEps = std::numeric_limits<double>::epsilon();

// Eq. (8): the smallest step whose differences keep the change, for variables of sizes up
// to x_max.
double StepFloor(double x_max) { return std::ldexp(kEps, 22) * std::max(1.0, std::abs(x_max)); }

// The step for a column: h_asked, or the floor (recorded) when smaller.
double ColumnStep(const std::string& name, double h_asked, double step_floor, std::vector<WidenedStep>* widened) {
  if (h_asked >= step_floor) return h_asked;
  widened->push_back({name, h_asked, step_floor});
  return step_floor;
}

double MaxAbs(const MatrixXd& m) { return m.size() == 0 ? 0.0 : m.cwiseAbs().maxCoeff(); }

}  // namespace

Status Richardson(const StepEval& F, double h, VectorXd* d, VectorXd* err) {
  VectorXd D[3];
  for (int k = 0; k < 3; ++k) {
    const double hk = h / static_cast<double>(1 << k);
    VectorXd fp, fm;
    double tp = 0.0, tm = 0.0;
    if (Status s = F(hk, &fp, &tp); !s.ok()) return s;
    if (Status s = F(-hk, &fm, &tm); !s.ok()) return s;
    if (!(tp - tm > 0))  // (the floor of eq. 8 prevents it)
      return {2, fmt::format("a difference step of {:g} was lost to rounding", hk)};
    D[k] = (fp - fm) / (tp - tm);
  }
  const VectorXd R1 = (4 * D[1] - D[0]) / 3, R2 = (4 * D[2] - D[1]) / 3;
  *d = R2;
  *err = (R2 - R1).cwiseAbs();
  return {};
}

Status Linearize(const rt::Program& program, const OperatingPoint& op, const LinearizeOptions& options,
                 LinearModel* out) {
  *out = LinearModel{};
  // The model's own inputs: held at their values, each a column of B and D before the others.
  const int m_in = rt::NumInputs(program);
  const std::vector<double>& w0 = options.input_values;
  if (static_cast<int>(w0.size()) != m_in)
    return {1, m_in > static_cast<int>(w0.size())
                   ? fmt::format("input '{}' has no value (give it with --set or --input-file)",
                                 rt::InputName(program, static_cast<int>(w0.size())))
                   : "more input values than the model has inputs"};
  std::vector<std::string> other_inputs;  // --input names that are not the model's inputs (those are columns already)
  for (const std::string& name : options.inputs) {
    bool own = false;
    for (int k = 0; k < m_in; ++k) own = own || rt::InputName(program, k) == name;
    if (!own) other_inputs.push_back(name);
  }
  // End stops, plane contacts and exact friction: the rows that hold at op join the
  // constraints, sliding joints keep their direction (hybrid.h).
  Hybrid hybrid;
  if (Status s = hybrid.Init(program, op, w0); !s.ok()) return s;
  out->held = hybrid.held_names();
  Reduction red;
  red.SetInputs(w0);
  if (Status s = red.Init(program, op, false, hybrid.held()); !s.ok()) return s;

  // The program the evaluations run on: a copy when joint forces are inputs.
  auto prog = std::make_shared<rt::Program>(program);
  std::vector<Input> inputs;
  if (Status s = ResolveInputs(prog.get(), other_inputs, &inputs); !s.ok()) return s;
  std::string plan_error;
  std::shared_ptr<const rt::SignalPlan> plan;
  if (!options.outputs.empty()) {
    plan = rt::PlanSignals(*prog, options.outputs, &plan_error);
    if (!plan) return {1, "output: " + plan_error};
  }
  auto ws = rt::MakeWorkspace(*prog);
  if (m_in > 0) rt::SetInputValues(*ws, w0.data());
  Hybrid hp;  // the same laws on the program with the input registers
  if (Status s = hp.Init(*prog, op, w0); !s.ok()) return s;

  const int nci = static_cast<int>(red.indep_coords().size());
  const int nui = static_cast<int>(red.indep_speeds().size());
  const int n = nci + nui, m = m_in + static_cast<int>(inputs.size()), np = static_cast<int>(options.outputs.size());
  const int nq = program.nq;
  for (int i : red.indep_coords()) out->states.push_back(red.coord_name(i));
  for (int i : red.indep_speeds()) out->states.push_back(red.speed_name(i));
  out->n_coords = nci;
  for (int k = 0; k < m_in; ++k) out->inputs.push_back(rt::InputName(program, k));
  for (const Input& in : inputs) out->inputs.push_back(in.name);
  out->outputs = options.outputs;
  out->h = options.step;

  // F(x, program, workspace): [xi_I'; u_I'; outputs] at state deviation x.
  // (*y_out: the state built, when asked.)
  auto eval = [&](const VectorXd& x, const rt::Program& p, rt::Workspace& w, Hybrid& hb, const rt::SignalPlan* pl,
                  VectorXd* F, VectorXd* y_out = nullptr) -> Status {
    VectorXd y;
    if (Status s = red.StateOf(x.head(nci), x.tail(nui), &y); !s.ok()) return s;
    if (y_out) *y_out = y;
    VectorXd ydot(y.size());
    if (hb.Derivative(w, red.t(), y.data(), ydot.data()) != 0)
      return {2, "the equations of motion fail near the operating point: " + rt::ErrorMessage(w)};
    VectorXd xidot;
    red.ChartRates(y, ydot.data(), &xidot);
    F->resize(n + (pl ? np : 0));
    for (int k = 0; k < nci; ++k) (*F)[k] = xidot[red.indep_coords()[static_cast<size_t>(k)]];
    for (int k = 0; k < nui; ++k) (*F)[nci + k] = ydot[nq + red.indep_speeds()[static_cast<size_t>(k)]];
    if (np > 0 && pl) {
      VectorXd sig(np);
      if (rt::EvalSignals(p, *pl, w, red.t(), y.data(), sig.data()) != 0)
        return {2, "output signals fail near the operating point: " + rt::ErrorMessage(w)};
      (*F).tail(np) = sig;
    }
    return {};
  };

  VectorXd F0;
  if (Status s = eval(VectorXd::Zero(n), *prog, *ws, hp, plan.get(), &F0); !s.ok()) return s;
  out->x0_rates.assign(F0.data(), F0.data() + n);

  // A and C, one state at a time. Speeds step relative to their size; a step below the
  // floor of eq. (8) is widened. x_size, u_size: |x_j0| of eqs. (8)-(9), per state and per
  // input (a joint force's value at the operating point is 0).
  const double h = options.step;
  out->A.resize(n, n);
  out->C.resize(np, n);
  MatrixXd errAC(n + np, n);
  std::vector<double> x_size(static_cast<size_t>(n)), step(static_cast<size_t>(n));
  std::vector<double> u_size(static_cast<size_t>(m), 0.0), u_step(static_cast<size_t>(m), 1.0);
  auto var_of = [&](int j) {
    return j >= nci ? red.indep_speeds()[static_cast<size_t>(j - nci)] : red.indep_coords()[static_cast<size_t>(j)];
  };
  for (int j = 0; j < n; ++j)
    x_size[static_cast<size_t>(j)] =
        j >= nci ? std::abs(red.y0()[static_cast<size_t>(nq + var_of(j))]) : red.CoordMagnitude(var_of(j));
  for (int k = 0; k < m; ++k) {
    if (k < m_in) {
      u_size[static_cast<size_t>(k)] = std::abs(w0[static_cast<size_t>(k)]);
      continue;
    }
    const Input& in = inputs[static_cast<size_t>(k - m_in)];
    if (!in.is_joint) u_size[static_cast<size_t>(k)] = std::abs(program.param_values[static_cast<size_t>(in.param.index)]);
  }
  double x_max = 0.0;
  for (double v : x_size) x_max = std::max(x_max, v);
  for (double v : u_size) x_max = std::max(x_max, v);
  const double step_floor = StepFloor(x_max);
  for (int j = 0; j < n; ++j) {
    const bool speed = j >= nci;
    const int var = var_of(j);
    const double u0 = speed ? red.y0()[static_cast<size_t>(nq + var)] : 0.0;
    const double asked = speed ? h * std::max(1.0, std::abs(u0)) : h;
    const double hj = ColumnStep(out->states[static_cast<size_t>(j)], asked, step_floor, &out->widened);
    step[static_cast<size_t>(j)] = hj;
    auto F = [&](double s, VectorXd* f, double* taken) {
      VectorXd x = VectorXd::Zero(n), y;
      x[j] = s;
      Status st = eval(x, *prog, *ws, hp, plan.get(), f, &y);
      // The step taken: the variable's value minus its value at the operating point.
      if (st.ok()) *taken = speed ? y[nq + var] - u0 : red.ChartOf(y)[var];
      return st;
    };
    VectorXd d, e;
    if (Status s = Richardson(F, hj, &d, &e); !s.ok()) return s;
    out->A.col(j) = d.head(n);
    out->C.col(j) = d.tail(np);
    errAC.col(j) = e;
  }

  // B and D, one input at a time.
  out->B.resize(n, m);
  out->D.resize(np, m);
  MatrixXd errBD(n + np, m);
  for (int k = 0; k < m; ++k) {
    StepEval F;
    double hk = h;
    const Input* in = k < m_in ? nullptr : &inputs[static_cast<size_t>(k - m_in)];
    if (!in) {  // a model input: moved on the workspace, the others held
      const double v0 = w0[static_cast<size_t>(k)];
      hk = ColumnStep(out->inputs[static_cast<size_t>(k)], h * std::max(1.0, std::abs(v0)), step_floor, &out->widened);
      F = [&, k, v0](double s, VectorXd* f, double* taken) {
        std::vector<double> u = w0;
        u[static_cast<size_t>(k)] = v0 + s;
        rt::SetInputValues(*ws, u.data());
        Status st = eval(VectorXd::Zero(n), *prog, *ws, hp, plan.get(), f);
        rt::SetInputValues(*ws, w0.data());
        *taken = u[static_cast<size_t>(k)] - v0;
        return st;
      };
    } else if (in->is_joint) {
      F = [&, in](double s, VectorXd* f, double* taken) {
        ws->force_regs[static_cast<size_t>(in->joint.reg)] = s;
        Status st = eval(VectorXd::Zero(n), *prog, *ws, hp, plan.get(), f);
        ws->force_regs[static_cast<size_t>(in->joint.reg)] = 0.0;
        *taken = s;  // the register holds s itself (its value at the operating point is 0)
        return st;
      };
      hk = 1.0;  // u' is affine in a generalized force: any step is exact up to rounding
    } else {
      const double v0 = program.param_values[static_cast<size_t>(in->param.index)];
      hk = ColumnStep(in->name, h * std::max(1.0, std::abs(v0)), step_floor, &out->widened);
      F = [&, in, v0](double s, VectorXd* f, double* taken) -> Status {
        std::shared_ptr<const rt::Program> rebound;
        if (Status st = RebindParameter(program, in->name, v0 + s, &rebound); !st.ok()) return st;
        std::shared_ptr<const rt::SignalPlan> pl;
        if (np > 0) pl = rt::PlanSignals(*rebound, options.outputs, &plan_error);
        auto w = rt::MakeWorkspace(*rebound);
        if (m_in > 0) rt::SetInputValues(*w, w0.data());
        *taken = (v0 + s) - v0;
        Hybrid hr;
        if (Status st = hr.Init(*rebound, op, w0); !st.ok() || hr.held_names() != hybrid.held_names())
          return Status{2, fmt::format("input '{}': a step of it changes which stops, contacts or joints hold at the "
                                       "operating point",
                                       in->name)};
        return eval(VectorXd::Zero(n), *rebound, *w, hr, pl.get(), f);
      };
    }
    u_step[static_cast<size_t>(k)] = hk;
    VectorXd d, e;
    if (Status s = Richardson(F, hk, &d, &e); !s.ok()) return s;
    out->B.col(k) = d.head(n);
    out->D.col(k) = d.tail(np);
    errBD.col(k) = e;
  }

  // The rounding term of eq. (7): nu_i of eq. (9), then 6 nu_i / h_j added to each column's
  // Richardson difference.
  VectorXd nu = F0.cwiseAbs();
  for (int j = 0; j < n; ++j) {
    nu.head(n) += out->A.col(j).cwiseAbs() * std::max(1.0, x_size[static_cast<size_t>(j)]);
    nu.tail(np) += out->C.col(j).cwiseAbs() * std::max(1.0, x_size[static_cast<size_t>(j)]);
  }
  for (int k = 0; k < m; ++k) {
    nu.head(n) += out->B.col(k).cwiseAbs() * u_size[static_cast<size_t>(k)];
    nu.tail(np) += out->D.col(k).cwiseAbs() * u_size[static_cast<size_t>(k)];
  }
  nu *= kEps;
  for (int j = 0; j < n; ++j) errAC.col(j) += 6.0 * nu / step[static_cast<size_t>(j)];
  for (int k = 0; k < m; ++k) errBD.col(k) += 6.0 * nu / u_step[static_cast<size_t>(k)];

  // Steady? A a moment later along f(0) against A now, compared on three fixed
  // pseudo-random directions v (J v by one central difference each): a change of A shows
  // in J v for all but a measure-zero set of directions, at 12 evaluations instead of 4n.
  const double f0max = n > 0 ? F0.head(n).cwiseAbs().maxCoeff() : 0.0;
  // (Rates at the level of an equilibrium search's tolerance are rounding, not motion.)
  if (f0max > 1e-8 * std::max(1.0, MaxAbs(out->A))) {
    const double hv = 1e-5;
    // max |J v (x1) - J v (0)| / max(1, |J v (0)|) over the three directions.
    auto change = [&](const VectorXd& x1) {
      double diff = 0.0, size = 1.0;
      unsigned seed = 12345u;
      for (int k = 0; k < 3; ++k) {
        VectorXd v(n);
        for (int i = 0; i < n; ++i) {
          seed = seed * 1664525u + 1013904223u;  // Numerical Recipes' LCG: fixed, portable
          v[i] = static_cast<double>(seed >> 8) / static_cast<double>(1u << 24) - 0.5;
        }
        v /= v.cwiseAbs().maxCoeff();
        VectorXd jv[2];
        for (int at = 0; at < 2; ++at) {
          const VectorXd xc = at == 0 ? VectorXd::Zero(n) : x1;
          VectorXd fp, fm;
          Status sp = eval(xc + hv * v, *prog, *ws, hp, nullptr, &fp);
          Status sm = sp.ok() ? eval(xc - hv * v, *prog, *ws, hp, nullptr, &fm) : sp;
          if (!sm.ok()) return std::numeric_limits<double>::infinity();
          jv[at] = (fp - fm).head(n) / (2 * hv);
        }
        diff = std::max(diff, MaxAbs(jv[1] - jv[0]));
        size = std::max(size, MaxAbs(jv[0]));
      }
      return diff / size;
    };
    out->unsteady = change((0.05 / f0max) * F0.head(n));
    // Second order along the motion, x(τ) ≈ τ f + τ²/2 A f: from rest with an acceleration
    // (a pendulum pushed from its bottom) the first-order step moves only the speeds, which
    // A may not read, while the motion goes on to move the coordinates. A steady motion has
    // A f = 0 (f does not change along it), so this step is taken only when A f is not.
    const VectorXd g = out->A * F0.head(n);
    const double gmax = n > 0 ? g.cwiseAbs().maxCoeff() : 0.0;
    if (std::isfinite(out->unsteady) && gmax > 1e-6 * std::max(1.0, f0max)) {
      const double tau = std::min(std::sqrt(0.1 / gmax), 0.5 / f0max);
      out->unsteady = std::max(out->unsteady, change(tau * F0.head(n) + 0.5 * tau * tau * g));
    }
  }

  out->error_A = MaxAbs(errAC.topRows(n)) / std::max(1.0, MaxAbs(out->A));
  double ebcd = 0.0;
  if (np > 0) ebcd = std::max(ebcd, MaxAbs(errAC.bottomRows(np)) / std::max(1.0, MaxAbs(out->C)));
  if (m > 0) ebcd = std::max(ebcd, MaxAbs(errBD) / std::max(1.0, std::max(MaxAbs(out->B), MaxAbs(out->D))));
  out->error_BCD = ebcd;
  return {};
}

void ComputeModes(LinearModel* model) {
  const MatrixXd& A = model->A;
  const int n = static_cast<int>(A.rows());
  model->modes.clear();
  model->ignorable.clear();
  if (n == 0) return;
  const double scale = std::max(1.0, MaxAbs(A));
  const double zero_tol = 1e-8 * scale + 10.0 * model->error_A * scale;
  // Ignorable coordinates: the largest set S of coordinates that no state outside S reads
  // (A(i, j) = 0 for i not in S, j in S): the rest is a system of its own, and S only
  // integrates it (position on the ground, heading, wheel angles).
  std::vector<bool> in_s(static_cast<size_t>(n), false);
  for (int j = 0; j < model->n_coords; ++j) in_s[static_cast<size_t>(j)] = true;
  for (bool changed = true; changed;) {
    changed = false;
    for (int j = 0; j < model->n_coords; ++j) {
      if (!in_s[static_cast<size_t>(j)]) continue;
      for (int i = 0; i < n; ++i)
        if (!in_s[static_cast<size_t>(i)] && std::abs(A(i, j)) > zero_tol) {
          in_s[static_cast<size_t>(j)] = false;
          changed = true;
          break;
        }
    }
  }
  for (int j = 0; j < model->n_coords; ++j)
    if (in_s[static_cast<size_t>(j)]) model->ignorable.push_back(model->states[static_cast<size_t>(j)]);

  Eigen::EigenSolver<MatrixXd> es(A, true);
  for (int k = 0; k < n; ++k) {
    Mode md;
    md.lambda = es.eigenvalues()[k];
    // Parts below the achieved accuracy are zero (an undamped mode's real part, a real
    // mode's imaginary part).
    const double noise = 10.0 * model->error_A * scale;
    if (std::abs(md.lambda) <= zero_tol) md.lambda = 0.0;
    if (std::abs(md.lambda.imag()) <= zero_tol) md.lambda.imag(0.0);
    if (std::abs(md.lambda.real()) <= noise) md.lambda.real(0.0);
    md.omega_n = std::abs(md.lambda);
    md.freq_hz = std::abs(md.lambda.imag()) / (2 * M_PI);
    md.zeta = md.omega_n > 0 ? -md.lambda.real() / md.omega_n + 0.0 : 0.0;  // + 0.0: no -0
    Eigen::VectorXcd v = es.eigenvectors().col(k);
    Eigen::Index big = 0;
    v.cwiseAbs().maxCoeff(&big);
    if (std::abs(v[big]) > 0) v /= v[big];
    md.shape = v;
    // Dominant coordinates (or speeds, when the mode moves no coordinate).
    const int nc = model->n_coords;
    int lo = 0, hi = nc;
    if (nc == 0 || v.head(nc).cwiseAbs().maxCoeff() <= 1e-9) lo = nc, hi = n;
    if (hi > lo) {
      const double vmax = v.segment(lo, hi - lo).cwiseAbs().maxCoeff();
      std::vector<std::pair<std::string, double>> dom;
      for (int i = lo; i < hi; ++i)
        if (vmax > 0 && std::abs(v[i]) >= 0.1 * vmax)
          dom.emplace_back(model->states[static_cast<size_t>(i)], std::abs(v[i]) / vmax);
      std::stable_sort(dom.begin(), dom.end(), [](const auto& a, const auto& b) { return a.second > b.second; });
      if (dom.size() > 4) dom.resize(4);
      md.dominant = dom;
    }
    model->modes.push_back(md);
  }
  std::stable_sort(model->modes.begin(), model->modes.end(), [](const Mode& a, const Mode& b) {
    if (a.omega_n != b.omega_n) return a.omega_n < b.omega_n;
    return a.lambda.imag() > b.lambda.imag();
  });
}

}  // namespace kanesim::lin
