// CVODE on y' = f(t, y): Adams-Moulton with fixed-point iteration (non-stiff, no
// Jacobian), or BDF with Newton iteration on M = I - gamma df/dy, factored by the dense LU.
// df/dy comes from difference quotients: ours, grouped (dq_jacobian.h, shared with IDA),
// where they cost fewer evaluations of f (closed loops on the reduced form, several
// coupling groups: SetJacobian), CVODE's own (n evaluations) elsewhere.
//
// Closed loops on the multiplier form (checked steps): f is evaluated at y*, the
// projection of y onto the constraints, plus a relaxation k_drift (y* - y)
// (runtime/engine/engine.cpp). That form projects all the speeds in the kinetic metric,
// u* = P(q) u, so off the manifold d(u*)/dt = f + (dP/dt)(u - u*): a drift of y moves the
// rows' motion. Measured on the equal-link parallelogram (CVODE-BDF, rtol 1e-6): the step
// across the change point at t = 9.73 left y 4.6 error weights off, the drift then grew
// x7, x4.5, x3.3, x2.7 ... per step (35-50 1/s, faster than k_drift = 10 1/s pulls it
// back) while the rows, on the branch, gained energy: 43x by t = 10.2. (The reduced form
// keeps y's independent coordinates in y* and overrides the dependent ones: a drift there
// does not feed the rows' motion, and resets near the change points of the chains at rtol
// 1e-12 made CVODE stall; ARKODE measures its own drift on that form.) As ARKODE does
// (integrator_arkode.cpp, MeasureDrift), the drift of each accepted step is measured aside
// and, past DriftWatch::kLimit weights and grown over DriftWatch::kGrowth steps in a row, CVODE starts
// again (CVodeReInit) from y* once that step's output instants are written.
// That restart stays for Adams only. BDF projects every step instead (ProjectStep, CVODE's
// projection): the restart fired inside the change-point zones of the chains, where the
// projection is ill-conditioned (the drift grew to 10-140 weights as rho fell), and each
// restart at order 1 shrank the step: the chain of ten at rtol 1e-12 restarted 234 times
// by t = 7.705 and crept until the branch monitor stopped it (exit 2). With the projection
// it is on the branch to 20 s (4.5e-8 of E), the chain of ten at 1e-10 1.0e-6 -> 3.3e-7 of
// E, the parallelogram above 1.8e-4 of E -> 1.4e-4 (docs/constraints.md). Rolling contacts
// on the multiplier form project too, loops or not (the rolling disk's lean grew without it).
#include <cvode/cvode.h>
#include <cvode/cvode_proj.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "sim/dq_jacobian.h"
#include "sim/newton_krylov.h"
#include "sim/stepper.h"
#include "sim/sundials_util.h"

namespace kanesim::sim::detail {
namespace {

constexpr ModuleFunctions kCvode{
    .module = "CVODE",
    .err_handler = CVodeSetErrHandlerFn,
    .tolerances = CVodeSStolerances,
    .user_data = CVodeSetUserData,
    .stop_time = CVodeSetStopTime,
    .max_num_steps = CVodeSetMaxNumSteps,
    .max_step = CVodeSetMaxStep,
    .init_step = CVodeSetInitStep,
    .current_time = CVodeGetCurrentTime,
    .dky = CVodeGetDky,
    .free = CVodeFree,
    .flag_name = CVodeGetReturnFlagName,
    .num_steps = CVodeGetNumSteps,
    .num_rhs_evals = CVodeGetNumRhsEvals,
    .num_err_test_fails = CVodeGetNumErrTestFails,
    .last_step = CVodeGetLastStep,
    .num_lin_setups = CVodeGetNumLinSolvSetups,
    .num_nonlin_iters = CVodeGetNumNonlinSolvIters,
    .num_nonlin_conv_fails = CVodeGetNumNonlinSolvConvFails,
    .last_order = CVodeGetLastOrder,
    .num_jac_evals = CVodeGetNumJacEvals,
    .num_lin_rhs_evals = CVodeGetNumLinRhsEvals,
    .current_step = CVodeGetCurrentStep
};

class CvodeStepper final : public SundialsStepper {
 public:
  explicit CvodeStepper(GuardedRhs& rhs) : SundialsStepper(rhs, kCvode) {}
  ~CvodeStepper() override {
    if (ewt_) N_VDestroy(ewt_);
  }

  bool Init(double t0, const double* y0, double stop, const IntegratorOptions& options, std::string* error) {
    const int n = rhs_.Size();
    const bool bdf = options.method == rt::Integrator::CvodeBdf;
    const bool careful = !bdf && options.after_event && options.initial_step <= 0.0;  // CarefulFirstStep
    if (!MakeState(y0, /*with_yp=*/false, error)) return false;
    mem_ = CVodeCreate(bdf ? CV_BDF : CV_ADAMS, s_.ctx);
    if (!mem_) return Fail(error, "CVodeCreate failed");
    // (CVodeInit reads the first step's growth: set before it)
    if (careful && CVodeSetEtaMaxFirstStep(mem_, kEtaAfterFirst) != CV_SUCCESS) return Fail(error, "CVODE setup failed");
    if (CaptureMessages() != CV_SUCCESS || CVodeInit(mem_, &CvodeStepper::Rhs, t0, s_.y) != CV_SUCCESS)
      return Fail(error, WithDetail("CVODE setup failed", messages_.last));
    if (!SetCommonOptions(stop, options, error)) return false;
    rtol_ = options.rtol;
    atol_ = options.atol;
    restart_.on = bdf && options.after_jump;  // RestartWeights
    if (restart_.on && CVodeWFtolerances(mem_, &CvodeStepper::RestartWeights) != CV_SUCCESS)
      return Fail(error, WithDetail("CVODE: setting the error weights failed", messages_.last));
    if (!InitRoots([&](int count) { return CVodeRootInit(mem_, count, &SundialsStepper::Roots); },
                   [&](int* d) { return CVodeSetRootDirection(mem_, d) | CVodeSetNoInactiveRootWarn(mem_); }, error))
      return false;
    // BDF: CVODE's own projection (below), not the restart; Adams: CVODE projects only BDF.
    // Only on the multiplier form's closed loops and rolling contacts
    // (ProjectAsideMultiplierForm is -1 elsewhere).
    std::vector<double> probe(y0, y0 + n);
    project_ = bdf && rhs_.ProjectAsideMultiplierForm(t0, probe.data()) == 0;
    int maxl = 0;
    if (bdf && (krylov_ = UseKrylov(options, rhs_, &maxl, project_))) {  // matrix-free: sim/newton_krylov.h
      s_.ls = MakeKrylovSolver(s_.y, maxl, s_.ctx);
      if (!s_.ls || CVodeSetLinearSolver(mem_, s_.ls, nullptr) != CV_SUCCESS)
        return Fail(error, WithDetail("CVODE Krylov linear solver setup failed", messages_.last));
    } else if (bdf) {
      s_.A = SUNDenseMatrix(n, n, s_.ctx);
      s_.ls = s_.A ? SUNLinSol_Dense(s_.y, s_.A, s_.ctx) : nullptr;
      if (!s_.ls || CVodeSetLinearSolver(mem_, s_.ls, s_.A) != CV_SUCCESS)
        return Fail(error, WithDetail("CVODE dense linear solver setup failed", messages_.last));
    } else {
      s_.nls = SUNNonlinSol_FixedPoint(s_.y, 0, s_.ctx);
      if (!s_.nls || CVodeSetNonlinearSolver(mem_, s_.nls) != CV_SUCCESS)
        return Fail(error, WithDetail("CVODE fixed-point solver setup failed", messages_.last));
    }
    if (project_ && CVodeSetProjFn(mem_, &CvodeStepper::ProjectStep) != CV_SUCCESS)
      return Fail(error, WithDetail("CVODE projection setup failed", messages_.last));
    if (bdf && !krylov_ && !SetJacobian(t0, y0, options, error)) return false;
    if (careful) {
      const double h0 = CarefulFirstStep(t0, y0, stop, options);
      if (h0 > 0.0 && CVodeSetInitStep(mem_, h0) != CV_SUCCESS)
        return Fail(error, WithDetail("CVODE: setting the initial step failed", messages_.last));
    }
    stop_ = stop;
    return true;
  }

  int Advance(double tout, double* y) override {
    double tret = 0.0;
    if (!StepsOneByOne()) {
      for (;;) {  // (a graze guard that found no dip: on)
        const int flag = Step(tout, &tret, CV_NORMAL);
        if (flag != CV_ROOT_RETURN) return CopyOut(flag, y);
        if (int r = EventReached(tret, y, [&](int* f) { CVodeGetRootInfo(mem_, f); }); r != kNoEvent) return r;
      }
    }
    return AdvanceCheckedSteps(tout, y, [&](double* t) {
      if (watch_.drifted && !ResetProjected()) return CV_ILL_INPUT;
      const int flag = Step(tout, t, CV_ONE_STEP);
      if (flag >= 0 && flag != CV_ROOT_RETURN && !project_) MeasureDrift(*t);
      return flag;
    }, [&](int* f) { CVodeGetRootInfo(mem_, f); });
  }

  // The counters of the CVODE runs before the last reset added (CVodeReInit zeroes them),
  // and our own difference quotients (FormJacobian).
  IntegratorStats Stats() const override {
    IntegratorStats st = Cumulative();
    st.rhs_evals_jac += dq_.Evaluations();
    st.rhs_evals += start_evals_;
    return st;
  }

 private:
  IntegratorStats Cumulative() const {
    IntegratorStats st = SundialsStepper::Stats();
    if (krylov_) {
      st.linear_solver = kKrylovName;
      CVodeGetNumLinIters(mem_, &st.lin_iters);
      CVodeGetNumLinConvFails(mem_, &st.lin_conv_fails);
    } else if (s_.A) {
      st.linear_solver = "dense LU";
    }
    AddStats(&st, before_);
    return st;
  }

  // The accepted step's drift |y*_i - y_i| / (rtol |y_i| + atol) (the error test's
  // weights), y* = its projection computed aside. Measured on the parallelogram above: at
  // most 0.24 on the steps before the change point, then 4.6, 33, 146, 475 (reset there).
  void MeasureDrift(double t) {
    watch_.Measure(t, N_VGetArrayPointer(s_.y), static_cast<size_t>(rhs_.Size()), rtol_, atol_,
                   [&](double tt, double* y) { return rhs_.ProjectAsideMultiplierForm(tt, y); });
  }

  // CVODE again from y* of the drifted step (f's own projection; no reset where it
  // cannot project), order 1, its counters kept in before_.
  bool ResetProjected() {
    watch_.Clear();
    double* ys = N_VGetArrayPointer(s_.y);
    std::copy(watch_.stepped_y.begin(), watch_.stepped_y.end(), ys);
    if (rhs_.Project(watch_.t_drifted, ys) != 0) return true;
    before_ = Cumulative();
    return CVodeReInit(mem_, watch_.t_drifted, s_.y) == CV_SUCCESS && CVodeSetStopTime(mem_, stop_) == CV_SUCCESS;
  }


  // A fresh CVODE-Adams at an event's right limit (IntegratorOptions::after_event) starts
  // at order 1, whose local error is h^2 ||y''|| / 2. Left to itself, CVODE takes its first
  // step where that is 0.25 of the error weights and grows the next one by up to 1e4, to
  // 1/6 of them, at order 1 again: each restart left the state about atol/4 off (2.5e-12 at
  // atol 1e-11 on a free fall). No later step removes that (a coordinate integrates it as
  // it is), and a slow event magnifies it: a bounce at speed v moves the next impact by
  // that over v and the rebound speed by g/v times it, so a ball's late impact times were
  // 5e-8 relative off at rtol 1e-11, the when-clause ball's accumulation point 2e-7 at
  // 1e-12. Here the first step's error is kFirstError of the weights,
  //   h0 = sqrt(2 kFirstError / ||y''||_w),  y'' ~ (f(t + d, y + d f) - f(t, y)) / d,  (1)
  // and the step after it grows by at most kEtaAfterFirst (CVodeSetEtaMaxFirstStep), so
  // the two order-1 steps stay at 1e-12 and 1e-10 of the weights; from order 2 on, Adams
  // integrates a motion polynomial in t (a free flight) to round-off. Measured on the ball
  // (e = 0.8, rtol 1e-11): impacts 5.2e-8 -> 5.9e-13 relative, 364 -> 507 steps (about one
  // step per restart for each factor 100 of kFirstError: 393, 419, 463 at 1e-6, 1e-8, 1e-10).
  // Not BDF: its error after a restart is its own step growth (order 2 keeps about 1/6 of
  // the weights per step while the step grows), which a smaller first step only lengthens
  // (measured 3.9e-7 -> 9.6e-8 at 1e-6 of the weights, 3.9e-7 again at 1e-12);
  // docs/events.md "Restarts". Two evaluations of f aside, counted in Stats.
  static constexpr double kFirstError = 1e-12;
  static constexpr double kEtaAfterFirst = 10.0;
  double CarefulFirstStep(double t0, const double* y0, double stop, const IntegratorOptions& options) {
    const size_t n = static_cast<size_t>(rhs_.Size());
    std::vector<double> f0(n), y1(n), f1(n);
    OdeSystem& system = rhs_.System();  // evaluations aside: a failure leaves CVODE's own choice
    const double d = 1e-7 * std::max(1.0, std::abs(t0));
    start_evals_ += 2;
    if (system.Rhs(t0, y0, f0.data()) != 0) return 0.0;
    for (size_t i = 0; i < n; ++i) y1[i] = y0[i] + d * f0[i];
    if (system.Rhs(t0 + d, y1.data(), f1.data()) != 0) return 0.0;
    double sum = 0.0;
    for (size_t i = 0; i < n; ++i) {
      const double w = (f1[i] - f0[i]) / d / (options.rtol * std::abs(y0[i]) + options.atol);
      sum += w * w;
    }
    const double ydd = std::sqrt(sum / static_cast<double>(n));  // ||y''||_w, CVODE's WRMS norm
    if (!(ydd > 0.0) || !std::isfinite(ydd)) return 0.0;
    // (at least a step that t + h still tells from t: 1e3 ulps of t)
    const double ulps = 1e3 * std::numeric_limits<double>::epsilon() * std::max(1.0, std::abs(t0));
    const double h0 = std::max(std::sqrt(2 * kFirstError / ydd), ulps);  // Eq. (1)
    return std::min(h0, std::abs(stop - t0));
  }
  long start_evals_ = 0;  // f evaluations of CarefulFirstStep

  // CVODE-BDF's error weights after a jump of the state (IntegratorOptions::after_jump: an
  // impact, a reinit; CVodeWFtolerances). A fresh BDF starts at order 1 with a step of about
  // sqrt(atol / |y''|) and grows it to the motion's own step, often ten decades larger (a
  // ball's flight: 1e-12 s to 0.3 s). From order 2 on, CVODE's fixed-leading-coefficient
  // BDF integrates a quadratic exactly only from an exact history; the history its order-1
  // start leaves is off, each order-2 step damps that by about 1/3 at a constant step, and a
  // step grown by eta multiplies its effect on the next step by eta^2. So the controller
  // settles on the growth (eta ~ 1.75) at which each step adds what its error test allows,
  // about 1/20 of the weights, for the twenty-odd steps of the growth: each restart left the
  // state about atol off (a ball's gap 1e-11 at atol 1e-11, measured on y = (q, u),
  // f = (u, -g) alone), which a slow bounce magnifies by g/v (the ball's impact times 3.8e-7
  // relative off at rtol 1e-11). A smaller first step or a bounded growth only moves where
  // that equilibrium begins. Here, while the step still grows, the weights are
  //   w_i = 1 / max(kScale (rtol |y_i| + atol), kUlps eps |y_i|),                   (1)
  // (never finer than kUlps units in the last place of y_i, which round-off would fail), so
  // the equilibrium holds the history about kScale times closer, at a few more steps (about
  // four a restart for each factor 100 of kScale). A restart then leaves the state about
  // 2.4 kScale atol off, which must stay below the motion's own scale after the jump: a
  // when-clause ball's last flights before its accumulation point are 1e-17 m high at atol
  // 1e-12 (kScale 1e-6 left them 1.5e-18 m off each, its accumulation point 5.6e-10
  // relative; 1e-9: 2.4e-21 m, 1.9e-11). CVODE's
  // own weights return once the step has stopped growing (its size kept over kKept steps in
  // a row at order 2 or more: the motion's own step reached, where the error is the step's
  // own and not the restart's), after kMaxSteps steps, or at a step that fails its error
  // test or Newton iteration repeatedly under (1) (a kink of f, which no step makes smooth
  // at that tolerance: the step is taken again under CVODE's weights; Step). After an event
  // that does not jump the state (a law's change: a slip, a stick, a lift-off) the restart is
  // left alone: no gain was measured there, and chaotic friction runs moved onto other paths.
  // Numbers: docs/benchmarks/2026-11-30_bdf_restart_weights.md. Runs without events never
  // take this path (NoEventMachinery.*).
  struct RestartWeighting {
    static constexpr double kScale = 1e-9;
    static constexpr double kUlps = 100.0;
    static constexpr int kKept = 5;
    static constexpr long kMaxSteps = 60;
    bool on = false;        // the weights of (1) for the steps so far
    long seen_steps = -1;   // CVODE's step count at the last weights
    double last_h = 0.0;    // ... its last step
    int kept = 0;           // steps in a row at order >= 2 whose size CVODE kept
  };
  RestartWeighting restart_;

  static int RestartWeights(N_Vector ycur, N_Vector ewt, void* user_data) {
    auto* self = static_cast<CvodeStepper*>(static_cast<SundialsStepper*>(user_data));
    self->UpdateRestart();
    const size_t n = static_cast<size_t>(self->rhs_.Size());
    const double* y = N_VGetArrayPointer(ycur);
    double* w = N_VGetArrayPointer(ewt);
    const double eps = std::numeric_limits<double>::epsilon();
    for (size_t i = 0; i < n; ++i) {
      double tol = self->rtol_ * std::abs(y[i]) + self->atol_;
      if (self->restart_.on)  // Eq. (1)
        tol = std::max(RestartWeighting::kScale * tol, RestartWeighting::kUlps * eps * std::abs(y[i]));
      if (!(tol > 0.0)) return -1;  // (as CVODE's own weights: atol 0 and y_i 0)
      w[i] = 1.0 / tol;
    }
    return 0;
  }

  // CVode, where a step that fails (CVODE's repeated error-test or Newton failures) under
  // the restart's weights ends them and is taken again under CVODE's own (RestartWeights).
  int Step(double tout, double* t, int mode) {
    for (;;) {
      const int flag = CVode(mem_, tout, s_.y, t, mode);
      if ((flag != CV_ERR_FAILURE && flag != CV_CONV_FAILURE) || !restart_.on) return flag;
      restart_.on = false;
    }
  }

  // Called with each step's weights (CVODE sets them once before every step).
  void UpdateRestart() {
    RestartWeighting& r = restart_;
    long steps = 0;
    CVodeGetNumSteps(mem_, &steps);
    if (!r.on || steps == r.seen_steps) return;
    r.seen_steps = steps;
    if (steps == 0) return;
    double h = 0.0;
    int order = 0;
    CVodeGetLastStep(mem_, &h);
    CVodeGetLastOrder(mem_, &order);
    r.kept = order >= 2 && h == r.last_h ? r.kept + 1 : 0;
    r.last_h = h;
    if (r.kept >= RestartWeighting::kKept || steps >= RestartWeighting::kMaxSteps) r.on = false;
  }

  // CVODE-BDF's projection (CVodeSetProjFn), called on each step whose Newton iteration
  // converged, before the error test: corr = y* - y, y* the multiplier form's projection
  // (zero where there is none: the reduced form, or a projection that fails). CVODE adds
  // corr to y and to the step's correction, so the Nordsieck history moves with it and BDF
  // keeps its order and step, where CVodeReInit went back to order 1. The error estimate
  // (err) is projected too, as CVODE's projection asks (CVodeSetProjErrEst, on by
  // default): err <- P(y + err) - P(y), its part along the constraints, the part the
  // projected step keeps. Left as it was, its part off the constraints (which the
  // projection removes) held the step down: the rolling disk at rtol 1e-10 took 4540 steps
  // (now 1056), and its lean was 2-10x farther off at rtol 1e-4 ... 1e-6.
  static int ProjectStep(sunrealtype t, N_Vector ycur, N_Vector corr, sunrealtype /*eps*/, N_Vector err,
                         void* user_data) {
    auto* self = static_cast<CvodeStepper*>(static_cast<SundialsStepper*>(user_data));
    const size_t n = static_cast<size_t>(self->rhs_.Size());
    const double* y = N_VGetArrayPointer(ycur);
    double* c = N_VGetArrayPointer(corr);
    self->aside_.assign(y, y + n);
    const bool projected = self->rhs_.ProjectAsideMultiplierForm(t, self->aside_.data()) == 0;
    for (size_t i = 0; i < n; ++i) c[i] = projected ? self->aside_[i] - y[i] : 0.0;
    if (projected && err != nullptr) {  // err <- P(y + err) - P(y): its part along the constraints
      double* e = N_VGetArrayPointer(err);
      self->aside_err_.assign(y, y + n);
      for (size_t i = 0; i < n; ++i) self->aside_err_[i] += e[i];
      if (self->rhs_.ProjectAsideMultiplierForm(t, self->aside_err_.data()) == 0)
        for (size_t i = 0; i < n; ++i) e[i] = self->aside_err_[i] - self->aside_[i];
    }
    return 0;
  }

  // CVODE-BDF's df/dy by our grouped difference quotients (dq_jacobian.h, CVodeSetJacFn)
  // where they cost fewer evaluations than CVODE's (n per Jacobian): closed loops on the
  // reduced form (the known columns: 2 per Jacobian on the chains of parallelograms, 162
  // states for the chain of 40), or several coupling groups (tests/sim/models/forest.mech,
  // M = 20, n = 80: 4 per Jacobian). Elsewhere (one group: every open tree, the multiplier
  // form's loops) CVODE's own, as before. Measured: docs/benchmarks.md, "CVODE-BDF's
  // Jacobian".
  bool SetJacobian(double t0, const double* y0, const IntegratorOptions& options, std::string* error) {
    const int n = rhs_.Size();
    dq_.Build(n, options.coupling, DqJacobian::Increment::kCvode);
    dq_.SetIncrementFloor(rhs_.System().IteratedRhs());
    bool own = dq_.Colours() < n || rhs_.System().IteratedRhs();
    if (!own && rhs_.ChecksSteps() && !project_) {
      // f at y0 chooses the partition (CVODE's first evaluation is there too).
      std::vector<double> f(static_cast<size_t>(n));
      if (rhs_(t0, y0, f.data()) != 0) return Fail(error, rhs_.cause);
      GuardedRhs::JacobianHold hold(rhs_);
      double pdiag = 0.0;
      std::vector<int> projected;
      own = rhs_.ProjectedStates(&projected, &pdiag);
    }
    if (!own) return true;
    dq_.SetLayout(/*sparse=*/false);
    ewt_ = N_VNew_Serial(n, s_.ctx);
    if (!ewt_) return Fail(error, "out of memory");
    if (CVodeSetJacFn(mem_, &CvodeStepper::Jacobian) != CV_SUCCESS)
      return Fail(error, WithDetail("CVodeSetJacFn failed", messages_.last));
    return true;
  }

  // df/dy at (t, y), fy = f(t, y) the evaluation CVODE made last (its partition held).
  static int Jacobian(sunrealtype t, N_Vector y, N_Vector fy, SUNMatrix J, void* user_data, N_Vector, N_Vector,
                      N_Vector) {
    auto* self = static_cast<CvodeStepper*>(static_cast<SundialsStepper*>(user_data));
    double h = 0.0;
    CVodeGetCurrentStep(self->mem_, &h);
    CVodeGetErrWeights(self->mem_, self->ewt_);
    const double* f = N_VGetArrayPointer(fy);
    const int status = self->dq_.Form(self->rhs_, t, N_VGetArrayPointer(y), f, f, h, N_VGetArrayPointer(self->ewt_));
    if (status != 0) return status;  // > 0: CVODE retries with a smaller step
    self->dq_.WriteDfdy(J);
    return 0;
  }

  DqJacobian dq_;
  N_Vector ewt_ = nullptr;
  bool project_ = false;      // CVODE-BDF on closed loops: ProjectStep, no MeasureDrift
  bool krylov_ = false;       // matrix-free GMRES (UseKrylov)
  std::vector<double> aside_;      // ProjectStep's y*  (n)
  std::vector<double> aside_err_;  // ProjectStep's P(y + err)  (n)
  double stop_ = 0.0;
  void StopMoved(double t) override { stop_ = t; }
  double rtol_ = 0.0, atol_ = 0.0;  // the error test's tolerances (MeasureDrift)
  DriftWatch watch_;                // MeasureDrift (sundials_util.h)
  IntegratorStats before_;          // counters of the CVODE runs before the last reset

  FailureKind Kind(int flag) const override {
    switch (flag) {
      case CV_RHSFUNC_FAIL:
      case CV_FIRST_RHSFUNC_ERR:
      case CV_REPTD_RHSFUNC_ERR:
      case CV_UNREC_RHSFUNC_ERR: return FailureKind::kRhs;
      case CV_TOO_MUCH_WORK: return FailureKind::kTooMuchWork;
      case CV_TOO_MUCH_ACC: return FailureKind::kTooMuchAccuracy;
      case CV_ERR_FAILURE: return FailureKind::kErrorTest;
      case CV_CONV_FAILURE: return FailureKind::kConvergence;
      case CV_LSETUP_FAIL:
      case CV_LSOLVE_FAIL: return FailureKind::kLinearSolver;
      default: return FailureKind::kOther;
    }
  }
};

}  // namespace

std::unique_ptr<Stepper> MakeCvodeStepper(GuardedRhs& rhs, double t0, const double* y0, double stop,
                                          const IntegratorOptions& options, std::string* error) {
  return MakeSundialsStepper<CvodeStepper>(rhs, t0, y0, stop, options, error);
}

}  // namespace kanesim::sim::detail
