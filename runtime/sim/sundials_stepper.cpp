// The steps CVODE, ARKODE and IDA take alike (runtime/sim/sundials_util.h).
#include <cstdlib>
#include <string>

#include "runtime/sim/sundials_util.h"

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

bool SundialsStepper::SetCommonOptions(const ModuleSetters& m, double stop, const IntegratorOptions& options,
                                       std::string* error) {
  const std::string module = m.module;
  if (m.tolerances(mem_, options.rtol, options.atol) != 0 || m.user_data(mem_, this) != 0 ||
      m.stop_time(mem_, stop) != 0 || m.max_num_steps(mem_, options.max_steps) != 0)
    return Fail(error, WithDetail(module + " setup failed", messages_.last));
  if (options.max_step > 0.0 && m.max_step(mem_, options.max_step) != 0)
    return Fail(error, WithDetail(module + ": setting the maximum step failed", messages_.last));
  if (options.initial_step > 0.0 && m.init_step(mem_, options.initial_step) != 0)
    return Fail(error, WithDetail(module + ": setting the initial step failed", messages_.last));
  return true;
}

int SundialsStepper::CopyOut(int flag, double* y) const {
  if (flag < 0) return flag;
  const double* ys = N_VGetArrayPointer(s_.y);
  for (int i = 0, n = rhs_.Size(); i < n; ++i) y[i] = ys[i];
  return flag;
}

StepFailure SundialsStepper::Describe(FailureKind kind, const char* module, char* (*flag_name)(long int),
                                      int flag) const {
  const std::string& d = messages_.last;
  switch (kind) {
    case FailureKind::kRhs: return {true, WithDetail("the right-hand side failed", d)};
    case FailureKind::kTooMuchWork: return {false, WithDetail("too much work (step limit reached between output instants)", d)};
    case FailureKind::kTooMuchAccuracy: return {false, WithDetail("too much accuracy requested", d)};
    case FailureKind::kErrorTest: return {false, WithDetail("step size underflow: the error test failed repeatedly", d)};
    case FailureKind::kConvergence: return {false, WithDetail("the nonlinear iteration failed to converge repeatedly", d)};
    case FailureKind::kLinearSolver: return {false, WithDetail("the linear solver failed (singular Newton matrix)", d)};
    case FailureKind::kOther: break;
  }
  char* name = flag_name(flag);  // malloc'd by SUNDIALS
  std::string what = std::string(module) + " failed: " + (name != nullptr ? name : "unknown flag");
  free(name);
  return {false, WithDetail(what, d)};
}

}  // namespace kanesim::sim::detail
