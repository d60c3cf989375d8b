// The integration driver: output grid, the guarded right-hand side, and the loop over
// output instants shared by every solver (the solvers are in integrator_*.cpp).
#include "sim/integrator.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "sim/csv.h"
#include "sim/stepper.h"

namespace kanesim::sim {

const char* MethodName(rt::Integrator m) {
  switch (m) {
    case rt::Integrator::IDA: return "IDA";
    case rt::Integrator::CvodeAdams: return "CVODE-Adams";
    case rt::Integrator::CvodeBdf: return "CVODE-BDF";
    case rt::Integrator::ArkodeErk: return "ARKODE-ERK";
    case rt::Integrator::Dop853: return "DOP853";
    case rt::Integrator::Auto: return "auto";
  }
  return "?";
}

const char* MethodDescription(rt::Integrator m) {
  switch (m) {
    case rt::Integrator::IDA: return "IDA: variable-order BDF (1-5), Newton, dense LU or KLU, grouped difference-quotient Jacobian";
    case rt::Integrator::CvodeAdams: return "CVODE: variable-order Adams-Moulton (1-12), fixed-point iteration";
    case rt::Integrator::CvodeBdf: return "CVODE: variable-order BDF (1-5), Newton, dense LU, difference-quotient Jacobian";
    case rt::Integrator::ArkodeErk: return "ARKODE ERKStep: explicit Runge-Kutta, Hermite dense output";
    case rt::Integrator::Dop853: return "DOP853: explicit Runge-Kutta 8(5,3) of Dormand-Prince, dense output of order 7";
    case rt::Integrator::Auto: return "the compiler's choice";
  }
  return "?";
}

// An instant closer than this fraction of the interval to stop is merged into stop.
static constexpr double kMergeFraction = 1e-9;

std::string OutputGrid::Check() const {
  auto num = [](double x) { return FormatShortest(x); };
  if (!std::isfinite(start)) return "the start time (" + num(start) + ") is not a finite number";
  if (!std::isfinite(stop)) return "the stop time (" + num(stop) + ") is not a finite number";
  if (stop < start) return "the stop time (" + num(stop) + ") is before the start time (" + num(start) + ")";
  if (!std::isfinite(stop - start))
    return "the time span from " + num(start) + " to " + num(stop) + " is out of range";
  if (stop == start) return "";
  if (!(interval > 0.0) || !std::isfinite(interval))
    return "the output interval (" + num(interval) + ") must be a positive finite number";
  const double n = (stop - start) / interval;
  if (!(n <= static_cast<double>(kMaxOutputRows - 1)))
    return "the output from " + num(start) + " to " + num(stop) + " every " + num(interval) + " would have " +
           num(std::floor(n) + 1) + " rows, more than the limit of " + std::to_string(kMaxOutputRows) +
           "; give a larger output interval";
  const double scale = std::max(std::abs(start), std::abs(stop));
  if (interval < kMinIntervalFraction * scale)
    return "the output interval (" + num(interval) + ") is too small for times as large as " + num(scale) +
           ": it must be at least " + num(kMinIntervalFraction) + " of |t| for the instants to differ";
  return "";
}

long OutputGrid::Count() const {
  if (!(stop > start) || !(interval > 0.0)) return 1;
  const double n = (stop - start) / interval;
  // Compared as doubles before any conversion: a grid past the limit (or a NaN) stops at
  // the limit instead of overflowing the conversion to long.
  if (!(n <= static_cast<double>(kMaxOutputRows))) return kMaxOutputRows + 1;
  return static_cast<long>(std::ceil(n - kMergeFraction)) + 1;
}

bool StateJumped(const double* before, const double* after, size_t n, double rtol, double atol) {
  for (size_t i = 0; i < n; ++i)
    if (std::abs(after[i] - before[i]) > rtol * std::abs(before[i]) + atol) return true;
  return false;
}

double OutputGrid::Time(long k) const {
  if (k >= Count() - 1) return k == 0 ? start : stop;
  // t_k by multiplication, not accumulation, so that rounding does not drift. When the
  // interval is 1/N for an integer N (0.1, 0.01, 0.02, ...), k / N is the correctly
  // rounded decimal (0.3, not 0.1 * 3 = 0.30000000000000004).
  double kd = static_cast<double>(k);
  double per_unit = 1.0 / interval;
  double n = std::round(per_unit);
  if (n >= 1.0 && std::abs(per_unit - n) <= 1e-12 * per_unit) return start + kd / n;
  return start + kd * interval;
}

namespace detail {

int GuardedRhs::Recoverable() {
  if (++recoverable_ <= kMaxRecoverableFailures) return 1;
  fatal = true;
  return -1;
}

int GuardedRhs::Failed(double t, int status) {
  failed = true;
  fatal = status < 0;
  fail_time = t;
  cause = system_.FailureCause();
  return status < 0 ? status : Recoverable();
}

int GuardedRhs::operator()(double t, const double* y, double* ydot) {
  if (fatal) return -1;
  if (int status = system_.Rhs(t, y, ydot); status != 0) return Failed(t, status);
  int n = system_.Size();
  for (int i = 0; i < n; ++i) {
    if (!std::isfinite(ydot[i])) {
      failed = true;
      fail_time = t;
      char buf[96];
      std::snprintf(buf, sizeof buf, "non-finite derivative (component %d of y' is %g)", i, ydot[i]);
      cause = buf;
      return Recoverable();
    }
  }
  return 0;
}

int GuardedRhs::Project(double t, double* y) {
  if (fatal) return -1;
  if (int status = system_.Project(t, y); status != 0) return Failed(t, status);
  return 0;
}

int GuardedRhs::StepAccepted(double t, const double* y) {
  if (fatal) return -1;
  if (int status = system_.StepAccepted(t, y); status != 0) return Failed(t, status);
  return 0;
}

void CaptureSundialsMessage(int /*error_code*/, const char* /*module*/, const char* function, char* msg,
                            void* user_data) {
  auto* messages = static_cast<SundialsMessages*>(user_data);
  messages->last = std::string(function ? function : "SUNDIALS") + ": " + (msg ? msg : "");
}

std::unique_ptr<Stepper> MakeStepper(GuardedRhs& rhs, double t0, const double* y0, double stop,
                                            const IntegratorOptions& options, std::string* error) {
  switch (options.method) {
    case rt::Integrator::Auto:
    case rt::Integrator::IDA: return MakeIdaStepper(rhs, t0, y0, stop, options, error);
    case rt::Integrator::CvodeAdams:
    case rt::Integrator::CvodeBdf: return MakeCvodeStepper(rhs, t0, y0, stop, options, error);
    case rt::Integrator::ArkodeErk: return MakeArkodeStepper(rhs, t0, y0, stop, options, error);
    case rt::Integrator::Dop853: return MakeDop853Stepper(rhs, t0, y0, stop, options, error);
  }
  *error = "unknown integration method";
  return nullptr;
}

void AddStats(IntegratorStats* to, const IntegratorStats& s) {
  to->steps += s.steps;
  to->rhs_evals += s.rhs_evals;
  to->rhs_evals_jac += s.rhs_evals_jac;
  to->jac_evals += s.jac_evals;
  to->lin_setups += s.lin_setups;
  to->err_test_fails += s.err_test_fails;
  to->dense_rejects += s.dense_rejects;
  to->energy_rejects += s.energy_rejects;
  to->energy_reject_rhs += s.energy_reject_rhs;
  to->nonlin_iters += s.nonlin_iters;
  to->nonlin_conv_fails += s.nonlin_conv_fails;
  to->lin_iters += s.lin_iters;
  to->lin_conv_fails += s.lin_conv_fails;
  if (std::isnan(to->stiff_time) && !std::isnan(s.stiff_time)) {
    to->stiff_time = s.stiff_time;
    to->stiff_h_lambda = s.stiff_h_lambda;
    to->switch_allowed = s.switch_allowed;
  }
  to->switched = to->switched || s.switched;
}

std::unique_ptr<Stepper> HandOverStiff(GuardedRhs& rhs, const Stepper& stiff, const double* y, double stop,
                                       IntegratorOptions* options, IntegratorStats* done, std::string* error) {
  const double ts = stiff.event_time;
  AddStats(done, stiff.Stats());
  done->switched = true;
  options->method = rt::Integrator::CvodeBdf;
  options->switch_when_stiff = false;
  rhs.Reset();
  return MakeStepper(rhs, ts, y, stop, *options, error);
}

}  // namespace detail

using detail::AddStats;

IntegrateResult Integrate(OdeSystem& system, const double* y0, const OutputGrid& grid,
                          const IntegratorOptions& given, const RowCallback& row) {
  IntegratorOptions options = given;  // the method changes when a stiff DOP853 hands over
  // Each solver made while a row is held steps at most one output interval (OdeSystem::Holding).
  auto bounded = [&]() -> const IntegratorOptions& {
    options.max_step = given.max_step;
    if (system.Holding() && (options.max_step <= 0.0 || options.max_step > grid.interval))
      options.max_step = grid.interval;
    return options;
  };
  IntegrateResult result;
  auto fail = [&result](double t, std::string cause) {
    result.ok = false;
    result.fail_time = t;
    result.cause = std::move(cause);
  };
  if (std::string why = grid.Check(); !why.empty()) {  // Simulate reports this as a usage error first
    fail(grid.start, why);
    return result;
  }
  detail::GuardedRhs rhs(system);
  std::vector<double> y(y0, y0 + system.Size());
  std::string cause;

  if (row(grid.start, y.data(), &cause) != 0) {
    fail(grid.start, cause);
    return result;
  }
  result.rows = 1;
  long count = grid.Count();
  if (count == 1) return result;
  if (y.empty()) {  // nothing to integrate (0 degrees of freedom): the outputs at every instant
    for (long k = 1; k < count; ++k, ++result.rows)
      if (row(grid.Time(k), y.data(), &cause) != 0) {
        fail(grid.Time(k), cause);
        break;
      }
    return result;
  }

  std::string error;
  std::unique_ptr<detail::Stepper> stepper = detail::MakeStepper(rhs, grid.start, y0, grid.stop, bounded(), &error);
  if (!stepper) {
    if (rhs.failed)
      fail(rhs.fail_time, rhs.cause);
    else
      fail(grid.start, error);
    return result;
  }

  IntegratorStats done;  // of the solvers before the last bridge
  std::vector<double> yb(y.size());
  std::vector<double> y_left(y.size());  // an event's left limit (StateJumped)
  // Rows of accepted steps inside a near-singular zone (OdeSystem::InZone), held until the
  // zone is left or bridged: a solver creeping towards a crossing can have a state whose
  // T + V is right while the loops' speeds are apart (DOP853, chain of ten, multiplier form,
  // rtol 1e-10: the row at t = 1.74 1.4e-5 of E off the lumped crank's energy), and a bridge
  // replaces those steps. Bridged (bridged_from finite): the held rows at or after its start
  // come from the bridged motion instead.
  std::vector<double> held_t;
  std::vector<std::vector<double>> held_y;
  auto write_held = [&](double bridged_from) {
    size_t i = 0;
    for (; i < held_t.size(); ++i) {
      if (held_t[i] >= bridged_from) system.BridgeState(held_t[i], held_y[i].data());
      if (row(held_t[i], held_y[i].data(), &cause) != 0) {
        fail(held_t[i], cause);
        break;
      }
      ++result.rows;
    }
    const bool ok = i == held_t.size();
    held_t.clear();
    held_y.clear();
    return ok;
  };
  constexpr int kChatterEvents = 1000;
  double chatter_from = NAN;  // the first of the events within rtol of one another
  int chatter_count = 0;
  for (long k = 1; k < count; ++k) {
    double tout = grid.Time(k);
    rhs.ClearFailure();
    int flag = stepper->Advance(tout, y.data());
    if (flag == detail::kStiffReached) {
      // DOP853 found the problem stiff: CVODE-BDF from its last accepted step, the
      // instant again from there (the rows before came from DOP853, none repeated).
      const double ts = stepper->event_time;
      stepper = detail::HandOverStiff(rhs, *stepper, y.data(), grid.stop, &options, &done, &error);
      if (!stepper) {
        write_held(INFINITY);
        fail(rhs.failed ? rhs.fail_time : ts, rhs.failed ? rhs.cause : error);
        result.stats = done;
        return result;
      }
      --k;
      continue;
    }
    if (flag == detail::kEventReached) {
      // The rows at the event's left and right limits (the same time twice), the jump
      // between them, and a fresh solver from the right limit.
      const double te = stepper->event_time;
      if (!write_held(INFINITY)) break;
      if (row(te, y.data(), &cause) != 0) {
        fail(te, cause);
        break;
      }
      ++result.rows;
      std::copy(y.begin(), y.end(), y_left.begin());
      if (system.Event(te, y.data(), stepper->event_index) != 0) {
        fail(te, system.FailureCause());
        break;
      }
      ++result.events;
      // Events that make no progress (issue 41: a stuck joint's slip under CVODE-BDF found
      // again every 4e-14 s, 23 875 events over 6.7e-10 s, a hang): kChatterEvents of them
      // within rtol max(1, |t|) of one another stop the run (exit 2), never loop.
      if (!(te - chatter_from <= options.rtol * std::max(1.0, std::abs(chatter_from)))) {  // (NaN: the first)
        chatter_from = te, chatter_count = 0;
      } else if (++chatter_count >= kChatterEvents) {
        char buf[300];
        std::snprintf(buf, sizeof buf,
                      "the events make no progress: %d events within %.3g s from t = %.17g (the last: event "
                      "function %d); the state they switch between cannot be resolved at this tolerance (try "
                      "another integrator or rtol)",
                      kChatterEvents, te - chatter_from, chatter_from, stepper->event_index);
        fail(te, buf);
        break;
      }
      if (row(te, y.data(), &cause) != 0) {
        fail(te, cause);
        break;
      }
      ++result.rows;
      if (system.Terminated(&result.terminate_message)) {
        result.terminated = true;
        result.terminate_time = te;
        break;
      }
      AddStats(&done, stepper->Stats());
      stepper.reset();
      if (te < grid.stop) {
        rhs.Reset();
        IntegratorOptions fresh = bounded();
        fresh.after_event = true;
        fresh.after_jump = StateJumped(y_left.data(), y.data(), y.size(), options.rtol, options.atol);
        stepper = detail::MakeStepper(rhs, te, y.data(), grid.stop, fresh, &error);
        if (!stepper) {
          fail(rhs.failed ? rhs.fail_time : te, rhs.failed ? rhs.cause : error);
          result.stats = done;
          return result;
        }
      }
      if (te < tout) --k;  // the same instant from the fresh solver (at it: the right limit was its row)
      continue;
    }
    if (flag < 0) {
      detail::StepFailure why = stepper->Explain(flag);
      if (rhs.fatal || (why.from_rhs && rhs.failed)) {
        fail(rhs.fail_time, rhs.cause);
      } else {
        std::string text = why.cause;
        if (rhs.failed) text += " (the right-hand side last failed with: " + rhs.cause + ")";
        fail(stepper->CurrentTime(), text);
      }
      // A singular configuration the solver could not pass: bridged, the output instants
      // in the gap from the bridged motion, then a fresh solver from past it.
      double t_from = 0.0, t_b = 0.0;
      if (!options.bridge || !system.Bridge(options.rtol, options.atol, &t_from, &t_b, yb.data()) || tout < t_from) {
        write_held(INFINITY);  // the rows so far on disk, as the solver gave them
        break;
      }
      if (!write_held(t_from)) break;
      // A bridge ending at or past the stop time (a crossing just before it) writes the
      // last rows itself; no solver follows.
      const bool to_stop = !(t_b < grid.stop);
      bool row_failed = false;
      for (; k < count && grid.Time(k) <= t_b; ++k) {
        const double tk = grid.Time(k);
        system.BridgeState(tk, y.data());
        if (row(tk, y.data(), &cause) != 0) {
          fail(tk, cause);
          row_failed = true;
          break;
        }
        ++result.rows;
      }
      if (row_failed) break;
      rhs.Reset();
      if (to_stop) {
        if (rhs.StepAccepted(t_b, yb.data()) != 0) {
          fail(t_b, rhs.cause);
          break;
        }
        result.ok = true;
        result.cause.clear();
        ++result.bridges;
        break;
      }
      // The bridged state is an accepted step: checked (the turn against the velocity
      // before the zone).
      if (rhs.StepAccepted(t_b, yb.data()) != 0) {
        fail(t_b, rhs.cause);
        break;
      }
      AddStats(&done, stepper->Stats());
      stepper.reset();
      stepper = detail::MakeStepper(rhs, t_b, yb.data(), grid.stop, bounded(), &error);
      if (!stepper) {
        if (rhs.failed)
          fail(rhs.fail_time, rhs.cause);
        else
          fail(t_b, error);
        result.stats = done;
        return result;
      }
      result.ok = true;
      result.cause.clear();
      ++result.bridges;
      --k;  // the instant after the gap, from the fresh solver
      continue;
    }
    if (system.InZone() && k + 1 < count) {
      held_t.push_back(tout);
      held_y.push_back(y);
      continue;
    }
    if (!write_held(INFINITY)) break;
    if (row(tout, y.data(), &cause) != 0) {
      fail(tout, cause);
      break;
    }
    ++result.rows;
  }
  if (!held_t.empty()) write_held(INFINITY);
  result.stats = stepper ? stepper->Stats() : IntegratorStats{};
  AddStats(&result.stats, done);
  result.stats.event_evals = rhs.event_evals;
  return result;
}

}  // namespace kanesim::sim
