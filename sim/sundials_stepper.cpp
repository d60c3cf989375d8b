// The steps CVODE, ARKODE and IDA take alike (sim/sundials_util.h).
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <string>
#include <utility>
#include <vector>
#include <algorithm>

#include "sim/illinois.h"
#include "sim/sundials_util.h"

namespace kanesim::sim::detail {

bool SundialsStepper::MakeState(const double* y0, bool with_yp, std::string* error) {
  const int n = rhs_.Size();
  if (!s_.ok()) return Fail(error, "SUNContext_Create failed");
  s_.y = N_VNew_Serial(n, s_.ctx);
  if (with_yp) s_.yp = N_VNew_Serial(n, s_.ctx);
  if (!s_.y || (with_yp && !s_.yp)) return Fail(error, "out of memory");
  double* y = N_VGetArrayPointer(s_.y);
  for (int i = 0; i < n; ++i) y[i] = y0[i];
  return true;
}

bool SundialsStepper::SetCommonOptions(double stop, const IntegratorOptions& options, std::string* error) {
  const ModuleFunctions& m = module_;
  const std::string module = m.module;
  if (m.tolerances(mem_, options.rtol, options.atol) != 0 || m.user_data(mem_, this) != 0 ||
      m.stop_time(mem_, stop) != 0 || m.max_num_steps(mem_, options.max_steps) != 0)
    return Fail(error, WithDetail(module + " setup failed", messages_.last));
  if (options.max_step > 0.0 && m.max_step(mem_, options.max_step) != 0)
    return Fail(error, WithDetail(module + ": setting the maximum step failed", messages_.last));
  if (options.initial_step > 0.0 && m.init_step(mem_, options.initial_step) != 0)
    return Fail(error, WithDetail(module + ": setting the initial step failed", messages_.last));
  options_ = options;
  check_rows_ = options.row_energy_check && rhs_.HasEnergy();
  stop_given_ = stop;
  release_.Init(rhs_.System());
  return true;
}

void SundialsStepper::MarkStep(double t, const double* y) {
  std::swap(step_start_, step_end_);
  step_end_.t = t;
  step_end_.y.assign(y, y + rhs_.Size());
  step_end_.known = false;
}

namespace {
// T + V of an end of a step, evaluated once. False where it cannot be evaluated.
bool EndEnergy(GuardedRhs& rhs, RowEnergy& re, double* T, double* V, double t, const std::vector<double>& y,
               bool* known) {
  if (!*known) {
    if (rhs.Energy(t, y.data(), T, V) != 0) return false;
    re.Motion(*T, *V);
    *known = true;
  }
  return true;
}
}  // namespace

int SundialsStepper::CheckRow(double tout, double* y, int flag) {
  StepEnd& a = step_start_;
  StepEnd& b = step_end_;
  if (a.y.empty() || !(a.t <= tout && tout <= b.t && a.t < b.t)) return flag;
  if (!EndEnergy(rhs_, row_energy_, &a.T, &a.V, a.t, a.y, &a.known) ||
      !EndEnergy(rhs_, row_energy_, &b.T, &b.V, b.t, b.y, &b.known))
    return flag;
  const double e0 = a.T + a.V, e1 = b.T + b.V, theta = (tout - a.t) / (b.t - a.t);
  auto deviation = [&](const double* yr) {
    double T = 0.0, V = 0.0;
    if (rhs_.Energy(tout, yr, &T, &V) != 0) return 0.0;  // the row itself reports it
    return row_energy_.Deviation(e0, e1, theta, T + V, options_.rtol, b.T, b.V);
  };
  const double d = deviation(y);
  if (d <= RowEnergy::kLimit) return flag;
  // Integrated again from the step's start onto tout, by DOP853 without the step checks.
  ++rows_recomputed_;
  IntegratorOptions o = options_;
  o.method = rt::Integrator::Dop853;
  o.dense_check = false;
  o.row_energy_check = false;
  o.check_steps = false;
  o.max_step = 0.0;
  o.initial_step = 0.0;
  // The interval is one step of the solver. Re-integrations that succeeded took 1 ... 1736
  // DOP853 steps (chains of 2 and 10 at rtol 1e-10/1e-12); one that did not (IDA, chain of
  // two, 1e-12, t = 17.05, at a change point) crept through 100000 steps (1.5e6 right-hand
  // sides, 22 s of a 23 s run) before failing: the row then fails as it would have anyway.
  o.max_steps = 4000;
  std::string error;
  std::vector<double> yr(static_cast<size_t>(rhs_.Size()));
  std::unique_ptr<Stepper> again = MakeDop853Stepper(rhs_, a.t, a.y.data(), tout, o, &error);
  double d2 = HUGE_VAL;
  if (again && again->Advance(tout, yr.data()) >= 0) d2 = deviation(yr.data());
  if (again) reintegration_rhs_ += again->Stats().rhs_evals;
  if (d2 <= RowEnergy::kLimit) {
    std::copy(yr.begin(), yr.end(), y);
    return flag;
  }
  char buf[400];
  std::snprintf(buf, sizeof buf,
                "the energy T + V of the output instant t = %.17g is off the energies of the accepted steps around it "
                "(%.3g units of their difference plus rtol times the motion's energy; %.3g after integrating to it "
                "again): its state cannot be trusted (docs/constraints.md \"Rows checked against the energy\")",
                tout, d, d2);
  row_failure_ = buf;
  return kRowEnergyFailed;
}

int SundialsStepper::Graze(int p, double tret, double* y) {
  const int n = rhs_.Size();
  std::vector<double> g(static_cast<size_t>(rhs_.NumEvents()));
  if (rhs_.EventFunctions(tret, y, g.data()) != 0 || g[static_cast<size_t>(p)] > 0.0) return kNoEvent;
  double b = tret, gb = g[static_cast<size_t>(p)], tn = tret, h = 0.0;
  module_.current_time(mem_, &tn);
  module_.last_step(mem_, &h);
  N_Vector v = N_VClone(s_.y);
  if (!v) return kEventReached;  // (at the minimum: the best there is)
  std::vector<double> ya(static_cast<size_t>(n));
  auto eval = [&](double t, double* gt) {  // p on the interpolant at t (into ya)
    if (module_.dky(mem_, t, 0, v) != 0) return false;
    std::copy(N_VGetArrayPointer(v), N_VGetArrayPointer(v) + n, ya.begin());
    if (rhs_.EventFunctions(t, ya.data(), g.data()) != 0) return false;
    *gt = g[static_cast<size_t>(p)];
    return true;
  };
  double a = std::min(tn - std::abs(h), tret), ga = 0.0;
  if (eval(a, &ga) && ga > 0.0) {
    bool failed = false;
    b = IllinoisRoot(a, ga, b, gb, 4e-16, eval, &failed);  // a failed evaluation keeps the bracket so far
    if (b < tret && module_.dky(mem_, b, 0, v) == 0) {
      std::copy(N_VGetArrayPointer(v), N_VGetArrayPointer(v) + n, y);
      event_time = b;
    }
  }
  N_VDestroy(v);
  event_index = p;
  return kEventReached;
}

int SundialsStepper::CopyOut(int flag, double* y) const {
  if (flag < 0) return flag;
  const double* ys = N_VGetArrayPointer(s_.y);
  for (int i = 0, n = rhs_.Size(); i < n; ++i) y[i] = ys[i];
  return flag;
}

double SundialsStepper::CurrentTime() const {
  double t = 0.0;
  module_.current_time(mem_, &t);
  return t;
}

IntegratorStats SundialsStepper::Stats() const {
  const ModuleFunctions& m = module_;
  IntegratorStats st;
  m.num_steps(mem_, &st.steps);
  m.num_rhs_evals(mem_, &st.rhs_evals);
  m.num_err_test_fails(mem_, &st.err_test_fails);
  m.last_step(mem_, &st.last_step);
  if (m.num_lin_setups) m.num_lin_setups(mem_, &st.lin_setups);
  if (m.num_nonlin_iters) m.num_nonlin_iters(mem_, &st.nonlin_iters);
  if (m.num_nonlin_conv_fails) m.num_nonlin_conv_fails(mem_, &st.nonlin_conv_fails);
  if (m.last_order) m.last_order(mem_, &st.last_order);
  if (s_.ls && m.num_jac_evals) m.num_jac_evals(mem_, &st.jac_evals);
  if (s_.ls && m.num_lin_rhs_evals) m.num_lin_rhs_evals(mem_, &st.rhs_evals_jac);
  st.energy_rejects = rows_recomputed_;
  st.energy_reject_rhs = reintegration_rhs_;
  return st;
}

StepFailure SundialsStepper::Explain(int flag) const {
  const std::string& d = messages_.last;
  if (flag == kRowEnergyFailed) return {false, row_failure_};
  switch (flag == kStepCheckFailed ? FailureKind::kRhs : Kind(flag)) {
    case FailureKind::kRhs: return {true, WithDetail("the right-hand side failed", d)};
    case FailureKind::kTooMuchWork: return {false, WithDetail("too much work (step limit reached between output instants)", d)};
    case FailureKind::kTooMuchAccuracy: return {false, WithDetail("too much accuracy requested", d)};
    case FailureKind::kErrorTest: return {false, WithDetail("step size underflow: the error test failed repeatedly", d)};
    case FailureKind::kConvergence: return {false, WithDetail("the nonlinear iteration failed to converge repeatedly", d)};
    case FailureKind::kLinearSolver: return {false, WithDetail("the linear solver failed (singular Newton matrix)", d)};
    case FailureKind::kOther: break;
  }
  char* name = module_.flag_name(flag);  // malloc'd by SUNDIALS
  std::string what = std::string(module_.module) + " failed: " + (name != nullptr ? name : "unknown flag");
  free(name);
  return {false, WithDetail(what, d)};
}

int SundialsStepper::Roots(double t, N_Vector y, double* g, void* user_data) {
  auto* self = static_cast<SundialsStepper*>(user_data);
  const int s = self->rhs_.EventFunctions(t, N_VGetArrayPointer(y), g);
  // A graze guard (minus a gap's or a sliding speed's rate) is a difference of accelerations
  // whose round-off is exactly 0 over ~1e-15 s around its root: SUNDIALS, having returned
  // that root (a minimum, no event), found the guard 0 again a small step later and stopped
  // with "Root found at and very near t" (CV_ILL_INPUT; robot sweep 11 trial 3, Solo12's
  // FL_HAA decelerating to a steady slide, CVODE-BDF and IDA). Here exact zeros are taken as
  // just past the minimum (a guard identically 0, a stuck joint's, stays below zero: no
  // crossing). Only for SUNDIALS' root finding: an FMU's event indicators are the functions
  // themselves (FMPy takes a 0 to a positive value for no event, a tiny negative one for one).
  for (int i : self->guards_)
    if (g[i] == 0.0) g[i] = -std::numeric_limits<double>::denorm_min();
  return s;
}

int SundialsStepper::RootsIda(double t, N_Vector y, N_Vector /*yp*/, double* g, void* user_data) {
  return Roots(t, y, g, user_data);
}

int SundialsStepper::Rhs(double t, N_Vector y, N_Vector ydot, void* user_data) {
  auto* self = static_cast<SundialsStepper*>(user_data);
  return self->rhs_(t, N_VGetArrayPointer(y), N_VGetArrayPointer(ydot));
}

}  // namespace kanesim::sim::detail
