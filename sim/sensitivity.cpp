// Forward parameter sensitivities by the variational equations (sim/sensitivity.h).
#include "sim/sensitivity.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <utility>

#include "sim/end_stops.h"
#include "sim/lift_off.h"
#include "sim/stick_slip.h"
#include "sim/when_events.h"

namespace kanesim::sim {
namespace {

using Workspace = std::unique_ptr<rt::Workspace, void (*)(rt::Workspace*)>;
using Clock = std::chrono::steady_clock;

// cbrt(machine epsilon): the step of a central difference of a function of order one.
const double kCbrtEps = std::cbrt(std::numeric_limits<double>::epsilon());

double MaxAbs(const double* x, int n) {
  double m = 0.0;
  for (int i = 0; i < n; ++i) m = std::max(m, std::fabs(x[i]));
  return m;
}

// The step along a direction s at y: cbrt(eps) (1 + |y|) / |s| (infinity norms), so that
// y +/- eps s moves y by about cbrt(eps) of its size. 0 when s is 0.
double DirectionStep(const double* y, const double* s, int n) {
  const double ns = MaxAbs(s, n);
  return ns > 0.0 ? kCbrtEps * (1.0 + MaxAbs(y, n)) / ns : 0.0;
}

// The program's perturbations, each with its own workspaces (the caches of one program's
// evaluations never see another's).
struct Perturbation {
  const SensitivityParam* param;
  Workspace plus_rhs, minus_rhs, plus_out, minus_out;
  std::shared_ptr<const rt::SignalPlan> plus_plan, minus_plan;
};

// The augmented system z = [y, s_1, ..., s_m].
class SensitivityOde final : public OdeSystem {
 public:
  SensitivityOde(const rt::Program& program, std::vector<Perturbation>& perturbations, const rt::InputSource* inputs)
      : program_(program),
        n_(rt::StateSize(program)),
        ws_(rt::MakeWorkspace(program)),
        aside_(rt::MakeWorkspace(program)),
        perturbations_(perturbations),
        yp_(static_cast<size_t>(n_)),
        fp_(static_cast<size_t>(n_)),
        fm_(static_cast<size_t>(n_)) {
    rt::SetInputSource(*ws_, inputs);
    rt::SetInputSource(*aside_, inputs);
  }

  int Size() const override { return n_ * (1 + static_cast<int>(perturbations_.size())); }

  int Rhs(double t, const double* z, double* zdot) override {
    failed_ = ws_.get();
    if (int s = rt::Derivative(program_, *ws_, t, z, zdot); s != 0) return s;
    for (size_t k = 0; k < perturbations_.size(); ++k) {
      const double* s = z + n_ * (k + 1);
      double* sdot = zdot + n_ * (k + 1);
      std::fill(sdot, sdot + n_, 0.0);
      // (df/dy) s_k, central along s_k.
      if (const double e = DirectionStep(z, s, n_); e > 0.0) {
        if (int st = Along(t, z, s, e, *aside_, program_); st != 0) return st;
        for (int i = 0; i < n_; ++i) sdot[i] = (fp_[i] - fm_[i]) / (2.0 * e);
      }
      // df/dp_k between the programs at p_k +/- delta (0 for a start value).
      Perturbation& p = perturbations_[k];
      if (p.param->start_value) continue;
      failed_ = p.plus_rhs.get();
      if (int st = rt::Derivative(*p.param->plus, *p.plus_rhs, t, z, fp_.data()); st != 0) return st;
      failed_ = p.minus_rhs.get();
      if (int st = rt::Derivative(*p.param->minus, *p.minus_rhs, t, z, fm_.data()); st != 0) return st;
      for (int i = 0; i < n_; ++i) sdot[i] += (fp_[i] - fm_[i]) / (2.0 * p.param->delta);
    }
    return 0;
  }

  // Rolling contacts: a normal force turning tensile stops the run, as in Simulate
  // (sim/lift_off.h); the guard reads y, the first n entries of z.
  void SetLiftOff(LiftOffGuard* lift) { lift_ = lift; }
  int NumEvents() const override { return lift_ ? lift_->Count() : 0; }
  int EventFunctions(double t, const double* z, double* g) override { return lift_->Functions(t, z, g); }
  int Event(double t, double* z, int i) override {
    event_cause_ = lift_->Cause(t, z, i);
    return -1;
  }

  std::string FailureCause() const override {
    if (!event_cause_.empty()) return event_cause_;
    const std::string& m = failed_ ? rt::ErrorMessage(*failed_) : std::string();
    return m.empty() ? "the equations of motion could not be evaluated" : m;
  }

 private:
  // f at y +/- e s into fp_, fm_ (in ws).
  int Along(double t, const double* y, const double* s, double e, rt::Workspace& ws, const rt::Program& program) {
    failed_ = &ws;
    for (int i = 0; i < n_; ++i) yp_[i] = y[i] + e * s[i];
    if (int st = rt::Derivative(program, ws, t, yp_.data(), fp_.data()); st != 0) return st;
    for (int i = 0; i < n_; ++i) yp_[i] = y[i] - e * s[i];
    return rt::Derivative(program, ws, t, yp_.data(), fm_.data());
  }

  const rt::Program& program_;
  const int n_;
  Workspace ws_, aside_;
  std::vector<Perturbation>& perturbations_;
  std::vector<double> yp_, fp_, fm_;
  const rt::Workspace* failed_ = nullptr;  // the workspace of the evaluation that failed
  LiftOffGuard* lift_ = nullptr;
  std::string event_cause_;
};

// Rows at which DifferenceErrors measures, about (it costs 8 evaluations per parameter and row).
constexpr long kEstimateRows = 64;

// The estimated errors of the difference quotients, measured at the output rows: a quotient
// D(h) = f' + c h^2 against D(2h) (their difference is 3 c h^2, so |D(h) - D(2h)| / 3 is D(h)'s
// truncation error), plus the round-off eps |f| / h of the evaluations. Own workspaces: the
// solver's evaluations never see these.
class DifferenceErrors {
 public:
  DifferenceErrors(const rt::Program& program, const std::vector<SensitivityParam>& params, const rt::InputSource* inputs)
      : program_(program), params_(params), n_(rt::StateSize(program)), ws_(rt::MakeWorkspace(program)) {
    rt::SetInputSource(*ws_, inputs);
    for (const SensitivityParam& p : params) {
      errors_.push_back(SensitivityErrors{p.name});
      std::vector<Workspace> w;
      if (!p.start_value && p.plus2 && p.minus2)
        for (const rt::Program* q : {p.plus.get(), p.minus.get(), p.plus2.get(), p.minus2.get()}) {
          w.push_back(rt::MakeWorkspace(*q));
          rt::SetInputSource(*w.back(), inputs);
        }
      param_ws_.push_back(std::move(w));
    }
    for (std::vector<double>* v : {&a_, &b_, &c_, &d_, &y_}) v->resize(static_cast<size_t>(n_));
  }

  // dy0/dp from the starts at +/- delta against those at +/- 2 delta.
  void Start() {
    for (size_t k = 0; k < params_.size(); ++k) {
      const SensitivityParam& p = params_[k];
      if (!p.plus2 || !p.minus2) continue;
      rt::InitialState(*p.plus, a_.data());
      rt::InitialState(*p.minus, b_.data());
      rt::InitialState(*p.plus2, c_.data());
      rt::InitialState(*p.minus2, d_.data());
      Record(p.delta, &errors_[k].start_error, &errors_[k].start_scale);
    }
  }

  // Both quotients of every parameter at the row (t, z = [y, s_1, ...]); 0 or a status.
  int Row(double t, const double* z) {
    for (size_t k = 0; k < params_.size(); ++k) {
      const SensitivityParam& p = params_[k];
      const double* s = z + n_ * (k + 1);
      if (const double e = DirectionStep(z, s, n_); e > 0.0) {
        const double steps[4] = {e, -e, 2 * e, -2 * e};
        std::vector<double>* outs[4] = {&a_, &b_, &c_, &d_};
        for (int j = 0; j < 4; ++j) {
          for (int i = 0; i < n_; ++i) y_[i] = z[i] + steps[j] * s[i];
          if (int st = rt::Derivative(program_, *ws_, t, y_.data(), outs[j]->data()); st != 0) return st;
        }
        Record(e, &errors_[k].dfdy_error, &errors_[k].dfdy_scale);
      }
      std::vector<Workspace>& w = param_ws_[k];
      if (w.empty()) continue;
      const rt::Program* programs[4] = {p.plus.get(), p.minus.get(), p.plus2.get(), p.minus2.get()};
      std::vector<double>* outs[4] = {&a_, &b_, &c_, &d_};
      for (int j = 0; j < 4; ++j)
        if (int st = rt::Derivative(*programs[j], *w[static_cast<size_t>(j)], t, z, outs[j]->data()); st != 0) return st;
      Record(p.delta, &errors_[k].dfdp_error, &errors_[k].dfdp_scale);
    }
    return 0;
  }

  const std::vector<SensitivityErrors>& Errors() const { return errors_; }

 private:
  // a, b at +/- h and c, d at +/- 2h into the largest error and value so far.
  void Record(double h, double* error, double* scale) {
    const double eps = std::numeric_limits<double>::epsilon();
    for (int i = 0; i < n_; ++i) {
      const double d1 = (a_[i] - b_[i]) / (2 * h), d2 = (c_[i] - d_[i]) / (4 * h);
      const double round_off = eps * std::max(std::fabs(a_[i]), std::fabs(b_[i])) / h;
      *error = std::max(*error, std::fabs(d1 - d2) / 3 + round_off);
      *scale = std::max(*scale, std::fabs(d1));
    }
  }

  const rt::Program& program_;
  const std::vector<SensitivityParam>& params_;
  const int n_;
  Workspace ws_;
  std::vector<std::vector<Workspace>> param_ws_;
  std::vector<SensitivityErrors> errors_;
  std::vector<double> a_, b_, c_, d_, y_;
};

}  // namespace

std::string SensitivityColumn(const std::string& signal, const std::string& param) {
  return "d(" + signal + ")/d(" + param + ")";
}

bool SplitSensitivityColumn(const std::string& column, std::string* signal, std::string* param) {
  const size_t mid = column.rfind(")/d(");
  if (column.size() < 9 || column.compare(0, 2, "d(") != 0 || column.back() != ')' || mid == std::string::npos ||
      mid < 3 || mid + 5 >= column.size())
    return false;
  *signal = column.substr(2, mid - 2);
  *param = column.substr(mid + 4, column.size() - mid - 5);
  return true;
}

double SensitivityStep(double p) { return kCbrtEps * std::max(std::fabs(p), 1e-3); }

SimResult SimulateSensitivities(const rt::Program& program, const std::vector<SensitivityParam>& params,
                                const SimOptions& options, SignalSink& sink) {
  const OutputGrid grid = ResolveGrid(program, options);
  if (std::string why = CheckRun(grid, options.rtol, options.atol); !why.empty()) return UsageResult(why);
  if (EndStopEvents(program, options.rtol, options.atol).Active())
    return UsageResult("--sensitivity: the model has end stops or plane contacts; sensitivities across impacts are not "
                 "implemented (docs/integrators.md \"Parameter sensitivities\")");
  if (StickSlipEvents(program).Active())
    return UsageResult("--sensitivity: the model has exact stick-slip friction (friction_exact); sensitivities across "
                 "its stick and slip events are not implemented");
  if (WhenEvents(program).Active())
    return UsageResult("--sensitivity: the model has when clauses; sensitivities across their events are not "
                 "implemented (docs/events.md)");
  if (options.speeds == Speeds::kDiagonal)
    return UsageResult("--sensitivity with --speeds diagonal: not implemented (the sensitivities are of the joint speeds' "
                 "equations; run without --speeds diagonal)");
  IntegratorOptions iopt;
  ResolveMethod(program, options.integrator, &iopt);
  iopt.coupling.clear();  // y's groups; s_k' reads all of y: the augmented state's df/dz is dense
  iopt.rtol = options.rtol;
  iopt.atol = options.atol;
  iopt.max_steps = options.max_steps;
  iopt.ida_linear_solver = options.ida_linear_solver;
  iopt.bridge = false;  // the change-point bridge acts on y alone; not on the augmented state

  const std::vector<std::string> names = options.signals.empty() ? rt::DefaultSignals(program) : options.signals;
  std::string plan_error;
  std::shared_ptr<const rt::SignalPlan> plan = rt::PlanSignals(program, names, &plan_error);
  if (!plan) return UsageResult(plan_error.empty() ? "cannot compute the requested outputs" : plan_error);
  if (rt::NumInputs(program) > 0 && !options.inputs)
    return UsageResult("input '" + rt::InputName(program, 0) + "' has no value (give it with --input-file or --set)");
  std::vector<Perturbation> perturbations;
  for (const SensitivityParam& p : params) {
    if (!p.plus || !p.minus || !(p.delta > 0.0)) return UsageResult("--sensitivity: no perturbed model for '" + p.name + "'");
    if (p.start_value) {
      perturbations.push_back(Perturbation{&p, {nullptr, nullptr}, {nullptr, nullptr}, {nullptr, nullptr}, {nullptr, nullptr}, {}, {}});
      continue;
    }
    Perturbation q{&p, rt::MakeWorkspace(*p.plus), rt::MakeWorkspace(*p.minus), rt::MakeWorkspace(*p.plus),
                   rt::MakeWorkspace(*p.minus), rt::PlanSignals(*p.plus, names, &plan_error),
                   rt::PlanSignals(*p.minus, names, &plan_error)};
    if (!q.plus_plan || !q.minus_plan) return UsageResult("--sensitivity: the outputs cannot be computed for '" + p.name + "'");
    for (rt::Workspace* ws : {q.plus_rhs.get(), q.minus_rhs.get(), q.plus_out.get(), q.minus_out.get()})
      rt::SetInputSource(*ws, options.inputs);
    perturbations.push_back(std::move(q));
  }

  // The start: y0 and s_k(t0) = dy0/dp_k (the start values and the assembly depend on p).
  const int n = rt::StateSize(program);
  const size_t m = perturbations.size();
  std::vector<double> z0(static_cast<size_t>(n) * (m + 1)), a(static_cast<size_t>(n)), b(static_cast<size_t>(n));
  rt::InitialState(program, z0.data());
  for (size_t k = 0; k < m; ++k) {
    rt::InitialState(*params[k].plus, a.data());
    rt::InitialState(*params[k].minus, b.data());
    for (int i = 0; i < n; ++i) z0[n * (k + 1) + i] = (a[i] - b[i]) / (2.0 * params[k].delta);
  }

  std::vector<std::string> columns = names;
  for (const std::string& y : names)
    for (const SensitivityParam& p : params) columns.push_back(SensitivityColumn(y, p.name));
  SimResult result;
  result.stats.method = iopt.method;
  result.stats.energy_guard = "not applied (sensitivities)";
  if (!sink.Begin(columns)) {
    result.status = SimResult::Status::kOutputError;
    result.message = "cannot write the output";
    return result;
  }

  // Rows: the signals at y, then dg/dp_k = (dg/dy) s_k + dg/dp_k by the same differences.
  const size_t ns = names.size();
  auto ws_out = rt::MakeWorkspace(program);
  auto ws_dir = rt::MakeWorkspace(program);
  rt::SetInputSource(*ws_out, options.inputs);
  rt::SetInputSource(*ws_dir, options.inputs);
  std::vector<double> row(columns.size()), gp(ns), gm(ns), yp(static_cast<size_t>(n));
  bool sink_failed = false;
  Clock::duration output_time{};
  DifferenceErrors errors(program, params, options.inputs);
  errors.Start();
  const long estimate_stride = std::max(1L, std::lround((grid.stop - grid.start) / grid.interval) / kEstimateRows);
  long row_index = 0;
  RowCallback on_row = [&](double t, const double* z, std::string* cause) -> int {
    const Clock::time_point t0 = Clock::now();
    auto fail = [&](const rt::Workspace& ws) {
      const std::string& msg = rt::ErrorMessage(ws);
      *cause = msg.empty() ? "an output signal could not be evaluated" : msg;
      return -1;
    };
    if (rt::EvalSignals(program, *plan, *ws_out, t, z, row.data()) != 0) return fail(*ws_out);
    // The estimate at about kEstimateRows rows (8 evaluations per parameter each).
    if (row_index++ % estimate_stride == 0 && errors.Row(t, z) != 0) {
      *cause = "the sensitivities' error estimate could not evaluate the equations";
      return -1;
    }
    for (size_t k = 0; k < m; ++k) {
      const double* s = z + n * (k + 1);
      std::vector<double> d(ns, 0.0);
      if (const double e = DirectionStep(z, s, n); e > 0.0) {
        for (int i = 0; i < n; ++i) yp[i] = z[i] + e * s[i];
        if (rt::EvalSignals(program, *plan, *ws_dir, t, yp.data(), gp.data()) != 0) return fail(*ws_dir);
        for (int i = 0; i < n; ++i) yp[i] = z[i] - e * s[i];
        if (rt::EvalSignals(program, *plan, *ws_dir, t, yp.data(), gm.data()) != 0) return fail(*ws_dir);
        for (size_t j = 0; j < ns; ++j) d[j] = (gp[j] - gm[j]) / (2.0 * e);
      }
      Perturbation& p = perturbations[k];
      if (p.param->start_value) {
        for (size_t j = 0; j < ns; ++j) row[ns + j * m + k] = d[j];
        continue;
      }
      if (rt::EvalSignals(*p.param->plus, *p.plus_plan, *p.plus_out, t, z, gp.data()) != 0) return fail(*p.plus_out);
      if (rt::EvalSignals(*p.param->minus, *p.minus_plan, *p.minus_out, t, z, gm.data()) != 0) return fail(*p.minus_out);
      for (size_t j = 0; j < ns; ++j) row[ns + j * m + k] = d[j] + (gp[j] - gm[j]) / (2.0 * p.param->delta);
    }
    int status = 0;
    if (!sink.Row(t, row.data(), row.size())) {
      sink_failed = true;
      *cause = "cannot write the output";
      status = -1;
    }
    if (status == 0 && options.progress) options.progress(t);
    output_time += Clock::now() - t0;
    return status;
  };

  SensitivityOde ode(program, perturbations, options.inputs);
  LiftOffGuard lift(program);
  if (lift.Active()) {
    if (std::string why = lift.Cause(grid.start, z0.data(), -1); !why.empty()) {
      result.status = SimResult::Status::kNumericalFailure;
      result.fail_time = grid.start;
      result.message = why;
      sink.End();
      return result;
    }
    ode.SetLiftOff(&lift);
  }
  const Clock::time_point start = Clock::now();
  IntegrateResult ir = Integrate(ode, z0.data(), grid, iopt, on_row);
  const Clock::duration total = Clock::now() - start;
  const bool end_ok = sink.End();
  FinishRun(ir, sink_failed, end_ok, std::chrono::duration<double>(total - output_time).count(),
            std::chrono::duration<double>(output_time).count(), &result);
  result.stats.sensitivity = errors.Errors();
  return result;
}

}  // namespace kanesim::sim
