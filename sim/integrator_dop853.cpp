// DOP853: the explicit Runge-Kutta pair of Dormand and Prince of order 8 with error
// estimators of orders 5 and 3, adaptive steps, and its dense output of order 7.
// Hairer, Norsett & Wanner, Solving Ordinary Differential Equations I, 2nd ed., Springer
// 1993, sec. II.10 (the method and its step control), sec. II.6 (dense output), sec. II.4
// (the initial step). Coefficients: sim/dop853_tableau.h; step control:
// sim/dop853_control.h.
//
// One step from (t, y) with size h, stages k_0 .. k_11 (k_0 = f(t, y), reused from the
// previous step: the first stage is the last one's f, "FSAL"):
//   k_s = f(t + c_s h, y + h sum_{j<s} a_sj k_j),   y1 = y + h sum_j b_j k_j          (1)
// Error (one scalar for the step, scaled by sc_i = atol + rtol max(|y_i|, |y1_i|)):
//   e5 = |sum_j E5_j k_j / sc|^2,  e3 = |sum_j E3_j k_j / sc|^2   (Euclidean norms)
//   err = |h| e5 / sqrt(n (e5 + 0.01 e3))                                              (2)
// a 5th-order estimate whose denominator, through the 3rd-order one, keeps it from
// becoming too optimistic when h is large. The step is accepted when err <= 1; either way
//   h_new = h min(kMaxGrow, max(kMinShrink, kSafety err^(-1/8)))                       (3)
// (no growth right after a rejection). After an accepted step k_12 = f(t + h, y1).
// Dense output at t + theta h, 0 <= theta <= 1, with dy = y1 - y:
//   y(theta) = y + theta (r0 + (1 - theta) (r1 + theta (r2 + (1 - theta) (r3
//              + theta (r4 + (1 - theta) (r5 + theta r6))))))                         (4)
//   r0 = dy,  r1 = h k_0 - dy,  r2 = 2 dy - h (k_0 + k_12),  r_{3+m} = h sum_j D_mj k_j
// where j runs over k_0 .. k_15 and k_13 .. k_15 are three more stages of (1) (rows 13..15
// of the tableau). They cost 3 evaluations of f, spent only on steps that hold an output
// instant; the further instants in that step cost no f at all.
//
// Constraints (OdeSystem::CanProject): each accepted y1 is projected onto the manifold
// before k_12 = f(t + h, y1) is evaluated there (Hairer, Lubich & Wanner, Geometric
// Numerical Integration, 2nd ed., sec. IV.4, Algorithm 4.2: the projection keeps the
// order, and the drift cannot accumulate from step to step). The error estimate (2) is
// that of the unprojected y1; the dense output (4) runs from y to the projected y1, so
// it stays continuous. The system's f may then skip its own projection (the stage
// arguments are off the manifold by their own error, which is O(h^2), not the step's).
//
// Failures: f or the projection returning > 0 in a step rejects it and retries with a
// quarter of h (kMaxRhsFails in a row end the run); < 0 ends it at once.
//
// The dense-output stages k_13 .. k_15 are not controlled by the error test (2). Where f is
// inaccurate at one point of a step (a closed loop's change point: its equations are
// ill-conditioned within ~1e-3 of it), a stage landing there corrupts the rows interpolated
// in that step while y1 stays accurate (measured: docs/constraints.md "Several loops singular
// at once"). So on a step that holds an output instant they are evaluated before the step is
// accepted and compared with the cubic in c through the step's own stages k_0, k_4, k_8,
// k_12 (DenseStageDeviation); a deviation larger than the spread of the step's stages
// (kDenseLimit) rejects the step, before the system has seen it (OdeSystem::StepAccepted),
// and it is taken again to end on the output instant itself, where no interpolation is
// needed. (Tried instead: keeping the step and reaching each instant inside it by steps of
// their own from its start, which keeps the trajectory; at rtol 1e-12 those steps crept
// towards the change point past the first instant, and undoing the step then, after the
// branch monitor had taken it as a step before the next zone, left a bridge refused and
// the run stopped with exit 2.)
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "sim/dop853_control.h"
#include "sim/dop853_stiffness.h"
#include "sim/dop853_tableau.h"
#include "sim/illinois.h"
#include "sim/release_bound.h"
#include "sim/stepper.h"

namespace kanesim::sim::detail {
namespace {

namespace tab = dop853;

// Eq. (3)'s constants and the stretch onto the stop time: sim/dop853_control.h.
constexpr double kRhsShrink = 0.25;     // h after a recoverable failure of f
constexpr int kMaxRhsFails = 10;        // recoverable failures of f in a row (as ARKODE's default)
constexpr double kMaxStepSlack = 1e-9;  // relative: what rounding may add to max_step
// Largest deviation of a dense-output stage from the cubic through the step's stages, in
// units of the spread of the step's stages (plus (atol + rtol |y|) / |h|), per component. Measured
// (DOP853 on the chains of equal-link parallelograms, rtol 1e-4 ... 1e-12, both forms): at
// most 0.22 on steps whose rows are on the lumped crank; 15.8 and 433 on the two steps seen
// with rows off it (docs/constraints.md "Several loops singular at once").
constexpr double kDenseLimit = 1.0;
// Instants checked per step at most (the first, the middle and the last when it holds more).
// Measured (callgrind, chain of 40 parallelograms, rtol 1e-8, 5 s, 7 instants per step):
// main 1.549e9 instructions, 16 per step 1.894e9, 3 per step 1.720e9; the wrong rows of
// docs/constraints.md "Rows checked against the energy" are caught with 3.
constexpr long kRowEnergyInstants = 3;

// A stiff run is handed over only when DOP853 would still need more than this many steps at
// its current size to the stop time: the switch costs a few hundred f (Jacobians, BDF from
// order 1). examples/sleigh.mech settles at its stability limit 5 steps before the end.
constexpr double kSwitchMinSteps = 100;
// Advance's flags (>= 0 success).
enum Flag : int { kOk = 0, kTooMuchWork = -1, kUnderflow = -2, kRhsRepeated = -3, kRhsFatal = -4 };

// |h| |k_12 - k_11| / |y1 - Y_11| (sim/dop853_stiffness.h) of the step of size h just formed:
// stage 11's argument in y11, the new point's in y1, both at t + h.
double StiffnessEstimate(int n, const double* k11, const double* k12, const double* y11, const double* y1, double h) {
  double num = 0.0, den = 0.0;
  for (int i = 0; i < n; ++i) {
    num += (k12[i] - k11[i]) * (k12[i] - k11[i]);
    den += (y1[i] - y11[i]) * (y1[i] - y11[i]);
  }
  return den > 0.0 ? std::abs(h) * std::sqrt(num / den) : NAN;
}

class Dop853Stepper final : public Stepper {
 public:
  Dop853Stepper(GuardedRhs& rhs, double t0, double stop, const IntegratorOptions& options)
      : rhs_(rhs),
        n_(rhs.Size()),
        options_(options),
        stop_(stop),
        t_(t0),
        y_(static_cast<size_t>(n_)),
        y_old_(static_cast<size_t>(n_)),
        y_new_(static_cast<size_t>(n_)),
        stage_y_(static_cast<size_t>(n_)),
        k_(static_cast<size_t>(n_) * tab::kStagesDense),
        r_(static_cast<size_t>(n_) * 7) {}

  // f(t0, y0) and the first step size. False when f fails at t0 (rhs_.failed is set).
  bool Init(const double* y0) {
    project_ = options_.project_steps && rhs_.CanProject();
    if (project_) rhs_.EnableStepProjection();
    check_ = options_.check_steps && rhs_.ChecksSteps();
    energy_ = options_.row_energy_check && rhs_.HasEnergy();
    std::copy(y0, y0 + n_, y_.begin());
    if (Eval(t_, y_.data(), K(0)) != 0) return false;
    if (const int ne = rhs_.NumEvents(); ne > 0) {
      g_old_.resize(static_cast<size_t>(ne));
      g_new_.resize(static_cast<size_t>(ne));
      if (rhs_.EventFunctions(t_, y_.data(), g_old_.data()) != 0) return false;
      guarded_.assign(static_cast<size_t>(ne), 0);
      for (int j = 0; j < ne; ++j)
        if (const int p = rhs_.Paired(j); p >= 0) guarded_[static_cast<size_t>(p)] = 1;
    }
    if (options_.initial_step > 0.0) {
      h_ = options_.initial_step;
    } else if (!InitialStep(&h_)) {
      return false;
    }
    if (options_.max_step > 0.0) h_ = std::min(h_, options_.max_step);
    release_.Init(rhs_.System());  // held rows: each step bounded by their release (sim/release_bound.h)
    if (release_.Active()) held_bound_ = release_.Next(t_, y_.data(), 0.0, g_old_.data(), K(0));
    return true;
  }

  int Advance(double tout, double* y) override {
    if (last_tout_set_ && tout > last_tout_) interval_ = tout - last_tout_;
    last_tout_ = tout;
    last_tout_set_ = true;
    long steps_here = 0;
    for (;;) {
      if (event_pending_ && event_t_ <= tout) {  // an event before the instant: stop there
        Interpolate(event_t_, y);
        event_time = event_t_;
        event_index = event_i_;
        return kEventReached;
      }
      if (t_ >= tout) {  // the last accepted step [t_old_, t_] holds tout
        if (tout == t_) {
          std::copy(y_.begin(), y_.end(), y);
          return kOk;
        }
        int status = PrepareDense();
        if (status == 0) {
          Interpolate(tout, y);
          return kOk;
        }
        if (status < 0) return kRhsFatal;
        // f failed inside the step: take it again, shorter.
        Undo();
        if (++rhs_fails_ >= kMaxRhsFails) return kRhsRepeated;
        h_ = kRhsShrink * h_last_;
      }
      // Stiff, under the automatic choice: handed back at the last accepted step, for the
      // driver to go on with an implicit method from there (no row between is lost).
      if (options_.switch_when_stiff && stiffness_.Stiff() && std::max(stop_, options_.run_end) - t_ > kSwitchMinSteps * h_) {
        std::copy(y_.begin(), y_.end(), y);
        event_time = t_;
        return kStiffReached;
      }
      if (steps_here++ >= options_.max_steps) return kTooMuchWork;
      int flag = Step(tout);
      if (flag != kOk) return flag;
      if (!g_old_.empty() && (flag = LocateEvent()) != kOk) return flag;
      // The functions at t_ (LocateEvent's, now in g_old_) and f there (the FSAL stage).
      if (release_.Active()) held_bound_ = release_.Next(t_, y_.data(), h_last_, g_old_.data(), K(tab::kStages));
    }
  }

  double CurrentTime() const override { return t_; }
  void SetStopTime(double t) override { stop_ = t; }
  double NextStep() const override { return h_; }
  // f(t_, y_) again with the new inputs: the next step's first stage (Eq. 1).
  int InputsChanged() override {
    fsal_pending_ = false;
    stages_ready_ = dense_ready_ = false;
    return Eval(t_, y_.data(), K(0)) != 0 ? -1 : 0;
  }

  IntegratorStats Stats() const override {
    IntegratorStats st;
    st.steps = steps_;
    st.rhs_evals = rhs_evals_;
    st.err_test_fails = err_test_fails_;
    st.dense_rejects = dense_rejects_;
    st.energy_rejects = energy_rejects_;
    st.last_step = h_last_;
    st.last_order = 8;
    if (stiffness_.Stiff()) {
      st.stiff_time = stiff_time_;
      st.stiff_h_lambda = stiffness_.LastHLambda();
      st.switch_allowed = options_.switch_when_stiff;
    }
    return st;
  }

  StepFailure Explain(int flag) const override {
    switch (flag) {
      case kRhsFatal: return {true, "the right-hand side failed"};
      case kRhsRepeated:
        return {true, "the right-hand side failed " + std::to_string(kMaxRhsFails) + " times in a row"};
      case kTooMuchWork:
        return {false, "too much work (" + std::to_string(options_.max_steps) +
                           " steps between output instants)"};
      case kUnderflow: return {underflow_from_rhs_, underflow_};
      default: return {false, "DOP853 failed"};
    }
  }

 private:
  double* K(int s) { return k_.data() + static_cast<size_t>(s) * static_cast<size_t>(n_); }
  const double* K(int s) const { return k_.data() + static_cast<size_t>(s) * static_cast<size_t>(n_); }

  int Eval(double t, const double* y, double* ydot) {
    ++rhs_evals_;
    return rhs_(t, y, ydot);
  }

  // out = y + h sum_{j<s} A[s][j] k_j: the argument of stage s, Eq. (1).
  void StageArgument(int s, const double* y, double h, double* out) const {
    std::copy(y, y + n_, out);
    for (int j = 0; j < s; ++j) {
      if (tab::A[s][j] == 0.0) continue;
      const double a = h * tab::A[s][j];
      const double* kj = K(j);
      for (int i = 0; i < n_; ++i) out[i] += a * kj[i];
    }
  }

  // Root-mean-square norm of v / (atol + rtol |y|).
  double RmsNorm(const double* v, const double* y) const {
    double sum = 0.0;
    for (int i = 0; i < n_; ++i) {
      double w = v[i] / (options_.atol + options_.rtol * std::abs(y[i]));
      sum += w * w;
    }
    return std::sqrt(sum / n_);
  }

  // Hairer, Norsett & Wanner sec. II.4, "Starting step size", for order 8: from the size
  // of y, f and a difference quotient of f along an explicit Euler step. Uses K(1) as
  // scratch (Step overwrites it). False only when f fails fatally.
  bool InitialStep(double* h) {
    const double span = stop_ - t_;
    const double d0 = RmsNorm(y_.data(), y_.data());
    const double d1 = RmsNorm(K(0), y_.data());
    double h0 = (d0 < 1e-5 || d1 < 1e-5) ? 1e-6 : 0.01 * d0 / d1;
    h0 = std::min(h0, span);
    for (int i = 0; i < n_; ++i) stage_y_[static_cast<size_t>(i)] = y_[static_cast<size_t>(i)] + h0 * K(0)[i];
    int status = Eval(t_ + h0, stage_y_.data(), K(1));
    if (status < 0) return false;
    if (status > 0) {  // f cannot be evaluated there: start small, Step shrinks further
      *h = h0;
      return true;
    }
    for (int i = 0; i < n_; ++i) stage_y_[static_cast<size_t>(i)] = (K(1)[i] - K(0)[i]) / h0;
    const double d2 = RmsNorm(stage_y_.data(), y_.data());
    const double dmax = std::max(d1, d2);
    const double h1 = dmax <= 1e-15 ? std::max(1e-6, 1e-3 * h0) : std::pow(0.01 / dmax, 1.0 / 8);
    *h = std::min({100.0 * h0, h1, span});
    return true;
  }

  // One accepted step from t_ (retrying rejected ones), toward stop_ and never past it.
  // A step past `tout` gets its dense-output stages here, checked (kDenseLimit).
  int Step(double tout) {
    if (fsal_pending_) {
      std::copy(K(tab::kStages), K(tab::kStages) + n_, K(0));
      fsal_pending_ = false;
    }
    bool rejected = false;
    bool onto_tout = false;  // taken again to end on tout (its dense output rejected)
    for (;;) {
      double h = h_;
      if (options_.max_step > 0.0) h = std::min(h, options_.max_step);
      h = std::min(h, held_bound_);
      // Never past stop_; onto it when it is within 1% of h and within max_step (up to
      // the rounding of t_ + h + h + ..., so that fixed steps that divide the span end on it).
      bool last = false;
      const double limit = std::min(options_.max_step > 0.0 ? options_.max_step : INFINITY, held_bound_) * (1.0 + kMaxStepSlack);
      if (stop_ - t_ <= std::min(tab::kStretch * h, limit)) {
        h = stop_ - t_;
        last = true;
      }
      if (onto_tout && t_ + h >= tout) {
        h = tout - t_;
        last = false;
      }
      if (!(h > 16.0 * kEps * std::max(1.0, std::abs(t_)))) return Underflow(h);

      // Stages 1..11 (Eq. 1); stage 0 is f(t_, y_), already in K(0).
      int status = 0;
      for (int s = 1; s < tab::kStages && status == 0; ++s) {
        StageArgument(s, y_.data(), h, stage_y_.data());
        status = Eval(t_ + tab::C[s] * h, stage_y_.data(), K(s));
      }
      if (status == 0) {
        const double err = ErrorNorm(h);  // also forms y_new_
        if (!(err <= 1.0)) {               // a NaN or infinite estimate rejects as well
          ++err_test_fails_;
          rejected = true;
          h_ = h * tab::ShrinkFactor(err);
          continue;
        }
        // Accepted: projected, then f at the new point, the next step's first stage (k_12 here).
        const double t_new = last ? stop_ : (onto_tout && t_ + h >= tout) ? tout : t_ + h;
        if (project_) status = rhs_.Project(t_new, y_new_.data());
        if (status == 0) status = Eval(t_new, y_new_.data(), K(tab::kStages));
        const double h_lambda = status == 0 ? StiffnessEstimate(n_, K(tab::kStages - 1), K(tab::kStages), stage_y_.data(), y_new_.data(), h) : NAN;
        bool stages = false, formed = false;
        if (status == 0 && options_.dense_check && check_ && t_new > tout) {
          status = DenseStages(t_, y_.data(), h);
          if (status == 0 && !(DenseStageDeviation(h) <= kDenseLimit)) {
            ++dense_rejects_;
            rejected = true;
            onto_tout = true;
            h_ = tout - t_;
            continue;
          }
          stages = status == 0;
        }
        // The output instant's energy against the step's ends (Eq. 5).
        if (status == 0 && energy_ && t_new > tout) {
          if (!stages) status = DenseStages(t_, y_.data(), h);
          stages = status == 0;
          if (status == 0) {
            FormDense(y_.data(), y_new_.data(), h);
            formed = true;
            if (!(RowEnergyDeviation(t_new, h, tout) <= RowEnergy::kLimit)) {
              ++energy_rejects_;
              rejected = true;
              onto_tout = true;
              h_ = tout - t_;
              continue;
            }
          }
        }
        if (status == 0 && check_) status = rhs_.StepAccepted(t_new, y_new_.data());
        if (status == 0) {
          Accept(t_new, h);
          const bool was_stiff = stiffness_.Stiff();
          stiffness_.Accepted(h_lambda);
          if (!was_stiff && stiffness_.Stiff()) stiff_time_ = t_new;
          stages_ready_ = stages;
          dense_ready_ = formed;
          h_ = h * tab::GrowFactor(err, rejected);
          return kOk;
        }
      }
      if (status < 0) return kRhsFatal;
      if (++rhs_fails_ >= kMaxRhsFails) return kRhsRepeated;
      rejected = true;
      h_ = kRhsShrink * h;
    }
  }

  // Eq. (2), and y_new_ = y1 of Eq. (1).
  double ErrorNorm(double h) {
    double e5 = 0.0, e3 = 0.0;
    for (int i = 0; i < n_; ++i) {
      double sum_b = 0.0, sum_5 = 0.0, sum_3 = 0.0;
      for (int j = 0; j < tab::kStages; ++j) {
        const double kj = k_[static_cast<size_t>(j) * static_cast<size_t>(n_) + static_cast<size_t>(i)];
        sum_b += tab::B[j] * kj;
        sum_5 += tab::E5[j] * kj;
        sum_3 += tab::E3[j] * kj;
      }
      const double y0 = y_[static_cast<size_t>(i)];
      const double y1 = y0 + h * sum_b;
      y_new_[static_cast<size_t>(i)] = y1;
      const double sc = options_.atol + options_.rtol * std::max(std::abs(y0), std::abs(y1));
      e5 += (sum_5 / sc) * (sum_5 / sc);
      e3 += (sum_3 / sc) * (sum_3 / sc);
    }
    const double deno = e5 + 0.01 * e3;
    return deno > 0.0 ? std::abs(h) * e5 / std::sqrt(n_ * deno) : 0.0;
  }

  // Moves to the new point. The step's start (y_old_, k_0 .. k_12) stays for the dense
  // output until the next step begins and copies k_12 into its k_0 (FSAL).
  void Accept(double t_new, double h) {
    y_old_.swap(y_);
    y_.swap(y_new_);
    t_old_ = t_;
    t_ = t_new;
    h_last_ = h;
    ++steps_;
    rhs_fails_ = 0;
    dense_ready_ = false;
    stages_ready_ = false;
    fsal_pending_ = true;
  }

  // Events (OdeSystem::NumEvents) in the last accepted step: each function that went from
  // positive at its start to <= 0 at its end, and the earliest crossing is pending (Advance
  // stops there). Crossings are located on the dense output by the Illinois variant of
  // regula falsi (sim/illinois.h) to a few units of round-off in t; the time kept is the
  // bracket's right end, where g <= 0. Only the earliest is needed: once one is located at
  // event_t_, the candidates are the functions positive at the step's start and <= 0 at
  // event_t_ (g_event_), each searched in the bracket up to it; a function still positive
  // there crosses later and is found again in the step after the event, if it is still
  // there. A function that dips below zero and is back above it by the step's end is one
  // of them too (its graze guard's crossing, the gap's minimum, may come after event_t_):
  // each earlier crossing found makes the scan run again over the functions not yet
  // searched. Functions that start the step at zero (a restart on a contact) come after the
  // others, so their samples past the earliest crossing so far are skipped.
  int LocateEvent() {
    if (rhs_.EventFunctions(t_, y_.data(), g_new_.data()) != 0) return kRhsFatal;
    event_pending_ = false;
    g_event_ = g_new_;  // the functions at the earliest crossing so far (at t_ while none)
    samples_ = 0;
    searched_.assign(g_new_.size(), 0);
    for (bool again = true; again;) {
      again = false;
      for (int pass = 0; pass < 2; ++pass) {
        for (size_t i = 0; i < g_new_.size(); ++i) {
          if (searched_[i]) continue;
          double a = t_old_, ga = g_old_[i];
          double b = event_pending_ ? event_t_ : t_, gb = g_event_[i];
          // From zero: below zero at the bracket's right end (the step's, or the earliest
          // crossing so far), or above it there with a graze guard (DipFromZero).
          const bool from_zero = ga == 0.0 && gb < 0.0;
          const bool dip_from_zero = ga == 0.0 && gb > 0.0 && guarded_[i];
          if ((from_zero || dip_from_zero) != (pass == 1)) continue;
          if ((gb > 0.0 && !dip_from_zero) || !(a < b)) continue;  // no crossing before the earliest one so far
          if (from_zero) {  // did it rise first?
            if (!dense_ready_ && PrepareDense() != 0) return kRhsFatal;
            const int rose = RiseFromZero(static_cast<int>(i), &a, &ga);
            if (rose < 0) return kRhsFatal;
            searched_[i] = 1;
            if (rose == 0) continue;
          }
          if (dip_from_zero) {  // did it rise and fall back?
            if (!dense_ready_ && PrepareDense() != 0) return kRhsFatal;
            const int fell = DipFromZero(static_cast<int>(i), &a, &ga, &b, &gb);
            if (fell < 0) return kRhsFatal;
            if (fell == 0) continue;  // (searched again where an earlier crossing moves b)
          }
          if (!(ga > 0.0)) continue;
          searched_[i] = 1;
          if (!dense_ready_ && PrepareDense() != 0) return kRhsFatal;
          if (!dip_from_zero) g_root_ = g_event_;  // (DipFromZero left the functions at its b)
          double root = Crossing(static_cast<int>(i), a, ga, b, gb, &g_root_);
          if (std::isnan(root)) return kRhsFatal;
          int which = static_cast<int>(i);
          if (const int p = rhs_.Paired(which); p >= 0) {  // a graze guard: did function p dip below zero?
            const int dip = Dip(p, &root);
            if (dip < 0) return kRhsFatal;
            if (dip == 0) continue;
            which = p;
          }
          if (!event_pending_ || root < event_t_) {
            event_pending_ = true;
            event_t_ = root;
            event_i_ = which;
            g_event_.swap(g_root_);
            again = true;
          }
        }
      }
    }
    g_prev_ = g_old_;
    g_old_.swap(g_new_);
    return kOk;
  }

  // Event function i, zero at the step's start and negative at its end, sampled on the dense
  // output at h/2, h/4, ... h/2^kSamples: a step longer than a flight from a contact (a short
  // rebound) rises and falls back inside it, however short the flight. Samples at or past a
  // pending event are skipped; the functions at each sample are kept for the other functions
  // that start the step at zero (sample_g_). 1 with *a, *ga a positive sample, 0 when none
  // is, -1 on failure.
  int RiseFromZero(int i, double* a, double* ga) {
    constexpr int kSamples = 48;
    const size_t ng = g_new_.size();
    std::vector<double>& y = event_y_;
    y.resize(static_cast<size_t>(n_));
    sample_g_.resize(static_cast<size_t>(kSamples) * ng);
    double f = 1.0;
    for (int k = 1; k <= kSamples; ++k) {
      f *= 0.5;
      const double t = t_old_ + (t_ - t_old_) * f;
      if (!(t > t_old_)) break;
      if (event_pending_ && t >= event_t_) continue;
      double* gs = sample_g_.data() + static_cast<size_t>(k - 1) * ng;
      if (!(samples_ & (uint64_t{1} << k))) {  // not yet evaluated in this step
        Interpolate(t, y.data());
        if (rhs_.EventFunctions(t, y.data(), gs) != 0) return -1;
        samples_ |= uint64_t{1} << k;
      }
      const double gk = gs[i];
      if (gk > 0.0) {
        *a = t, *ga = gk;
        return 1;
      }
    }
    return 0;
  }

  // Event function i (one with a graze guard), zero at the step's start and above zero at the
  // bracket's right end *b: sampled at kDipSamples - 1 even points before *b for a fall to <= 0
  // after a rise, which the signs at the ends do not show. A sliding joint's s u from its
  // reversal's restart rose, fell through zero where the joint stops and rose again by the
  // end of DOP853's first step (0.0226 s; issue 41, friction sweep seed 4 trial 6): the stop
  // was missed. 1 with [*a, *b] bracketing that crossing (*ga > 0 >= *gb) and g_root_ the
  // functions at *b; 0 when no sample shows one; -1 on failure.
  int DipFromZero(int i, double* a, double* ga, double* b, double* gb) {
    constexpr int kDipSamples = 8;
    std::vector<double>& y = event_y_;
    y.resize(static_cast<size_t>(n_));
    dip_g_.resize(g_new_.size());
    const double t0 = t_old_, t1 = *b;
    bool rose = false;
    for (int k = 1; k < kDipSamples; ++k) {
      const double t = t0 + (t1 - t0) * k / kDipSamples;
      Interpolate(t, y.data());
      if (rhs_.EventFunctions(t, y.data(), dip_g_.data()) != 0) return -1;
      const double gk = dip_g_[static_cast<size_t>(i)];
      if (gk > 0.0) {
        rose = true, *a = t, *ga = gk;
      } else if (rose) {
        *b = t, *gb = gk;
        g_root_ = dip_g_;
        return 1;
      }
    }
    return 0;
  }

  // Function p at *t (a minimum, located by its graze guard): 0 when positive there (no event);
  // 1 when not, *t then its crossing in [t_old_, *t] and g_root_ the functions there; -1 on
  // failure.
  int Dip(int p, double* t) {
    std::vector<double>& y = event_y_;
    y.resize(static_cast<size_t>(n_));
    Interpolate(*t, y.data());
    if (rhs_.EventFunctions(*t, y.data(), g_root_.data()) != 0) return -1;
    const double gp = g_root_[static_cast<size_t>(p)], g0 = g_old_[static_cast<size_t>(p)];
    if (gp > 0.0 || !(g0 > 0.0)) return 0;  // (from zero: RiseFromZero's case)
    const double root = Crossing(p, t_old_, g0, *t, gp, &g_root_);
    if (std::isnan(root)) return -1;
    *t = root;
    return 1;
  }

  // Event function i's zero in [a, b] (ga > 0 >= gb there); NaN when it cannot be evaluated.
  // *g_b: the functions at b on entry, at the zero returned on exit.
  double Crossing(int i, double a, double ga, double b, double gb, std::vector<double>* g_b) {
    std::vector<double>& y = event_y_;
    y.resize(static_cast<size_t>(n_));
    std::vector<double>& g = g_scratch_;
    g.resize(g_new_.size());
    auto eval = [&](double t, double* gt) {
      Interpolate(t, y.data());
      if (rhs_.EventFunctions(t, y.data(), g.data()) != 0) return false;
      *gt = g[static_cast<size_t>(i)];
      if (*gt <= 0.0) g_b->swap(g);  // the new right end
      return true;
    };
    bool failed = false;
    const double root = IllinoisRoot(a, ga, b, gb, 4.0 * kEps, eval, &failed);
    return failed ? NAN : root;
  }

  // Returns to the start of the last step after f failed in its dense-output stages.
  void Undo() {
    event_pending_ = false;
    if (!g_prev_.empty()) g_old_ = g_prev_;  // the event functions at the retaken step's start
    y_.swap(y_old_);
    t_ = t_old_;
    --steps_;
    dense_ready_ = false;
    stages_ready_ = false;
    fsal_pending_ = false;  // K(0) still holds f(t_old_, y_old_)
  }

  // Stages 13..15 and r0..r6 of Eq. (4) for the last step, once. 0, or f's status.
  int PrepareDense() {
    if (dense_ready_) return 0;
    const double h = h_last_;
    if (!stages_ready_) {
      if (int status = DenseStages(t_old_, y_old_.data(), h); status != 0) return status;
    }
    FormDense(y_old_.data(), y_.data(), h);
    dense_ready_ = true;
    return 0;
  }

  // r0 .. r6 of Eq. (4) for the step of size h from y0 to y1 (stages 0 .. 15 in k_).
  void FormDense(const double* y0, const double* y1, double h) {
    double* r = r_.data();
    const size_t n = static_cast<size_t>(n_);
    for (size_t i = 0; i < n; ++i) {
      const double dy = y1[i] - y0[i];
      const double k0 = K(0)[i], k12 = K(tab::kStages)[i];
      r[i] = dy;
      r[n + i] = h * k0 - dy;
      r[2 * n + i] = 2.0 * dy - h * (k0 + k12);
    }
    for (int m = 0; m < tab::kDenseRows; ++m) {
      double* rm = r + (3 + static_cast<size_t>(m)) * n;
      for (size_t i = 0; i < n; ++i) {
        double sum = 0.0;
        for (int j = 0; j < tab::kStagesDense; ++j) sum += tab::D[m][j] * K(j)[i];
        rm[i] = h * sum;
      }
    }
  }

  // Stages 13..15 of the step of size h from (t0, y0). 0, or f's status.
  int DenseStages(double t0, const double* y0, double h) {
    for (int s = tab::kStages + 1; s < tab::kStagesDense; ++s) {
      StageArgument(s, y0, h, stage_y_.data());
      int status = Eval(t0 + tab::C[s] * h, stage_y_.data(), K(s));
      if (status != 0) return status;
    }
    return 0;
  }

  // Largest deviation, over the components, of the dense-output stages k_13 .. k_15 from
  // the cubic in c through the step's stages k_0 (c = 0), k_4, k_8 and k_12 (c = 1), in
  // units of the spread of the step's stages k_0 .. k_12 in that component plus (atol + rtol
  // |y|) / |h| (a deviation that moves y by less than the tolerance over the step). Called
  // before Accept (y_ the step's start, y_new_ its end). On a step where f is smooth the
  // cubic is close (measured below 0.22 on the chains of parallelograms); a stage evaluated
  // where f is wrong stands out by orders of magnitude. Only where the system checks its
  // steps (closed loops, the branch monitor: OdeSystem::ChecksSteps): elsewhere the stage
  // arguments' own departures from a constraint manifold make the stages of a long step
  // far from any cubic while its rows are right (examples/sleigh.mech, a knife edge: 17
  // steps of 38 rejected, deviations up to 250, the rows unchanged to 1e-13).
  double DenseStageDeviation(double h) const {
    const int nodes[4] = {0, 4, 8, tab::kStages};
    double cn[4];
    for (int a = 0; a < 4; ++a) cn[a] = nodes[a] == tab::kStages ? 1.0 : tab::C[nodes[a]];
    double worst = 0.0;
    for (int i = 0; i < n_; ++i) {
      double lo = INFINITY, hi = -INFINITY;
      for (int j = 0; j <= tab::kStages; ++j) {
        lo = std::min(lo, K(j)[i]);
        hi = std::max(hi, K(j)[i]);
      }
      const size_t iz = static_cast<size_t>(i);
      const double tol = options_.atol + options_.rtol * std::max(std::abs(y_[iz]), std::abs(y_new_[iz]));
      const double scale = (hi - lo) + tol / std::abs(h);
      for (int s = tab::kStages + 1; s < tab::kStagesDense; ++s) {
        double p = 0.0;
        for (int a = 0; a < 4; ++a) {
          double w = 1.0;
          for (int b = 0; b < 4; ++b)
            if (b != a) w *= (tab::C[s] - cn[b]) / (cn[a] - cn[b]);
          p += w * K(nodes[a])[i];
        }
        const double d = std::abs(K(s)[i] - p) / scale;
        if (!(d <= worst)) worst = d;  // a NaN stage counts as the worst
      }
    }
    return worst;
  }

  // Eq. (4) at tout in [t_old_, t_].
  void Interpolate(double tout, double* y) const { InterpolateFrom(t_old_, y_old_.data(), h_last_, tout, y); }

  // Eq. (4) at tout for the step of size h from (t0, y0) whose r0 .. r6 are in r_.
  void InterpolateFrom(double t0, const double* y0, double h, double tout, double* y) const {
    const double theta = (tout - t0) / h, theta1 = 1.0 - theta;
    const size_t n = static_cast<size_t>(n_);
    const double* r = r_.data();
    for (size_t i = 0; i < n; ++i) {
      double v = r[6 * n + i];
      v = r[5 * n + i] + theta * v;
      v = r[4 * n + i] + theta1 * v;
      v = r[3 * n + i] + theta * v;
      v = r[2 * n + i] + theta1 * v;
      v = r[n + i] + theta * v;
      v = r[i] + theta1 * v;
      y[i] = y0[i] + theta * v;
    }
  }

  // Eq. (5): how far the energy of an output instant interpolated by Eq. (4) in the step
  // from (t_, y_) to (t_new, y_new_) of size h (r_ formed) is from the straight line between
  // the energies of the step's ends, in units of their difference plus rtol times the
  // motion's energy; the largest over the instants in the step: tout and those after it at
  // the spacing of the last two instants asked for (at most kRowEnergyInstants of them,
  // spread over the step). The energies of t_ and t_new are kept for the next step. A state
  // whose energy cannot be evaluated counts as right (the row itself then reports it).
  double RowEnergyDeviation(double t_new, double h, double tout) {
    double T0 = 0.0, V0 = 0.0, T1 = 0.0, V1 = 0.0;
    if (!(energy_known_ && energy_t_ == t_)) {
      if (rhs_.Energy(t_, y_.data(), &T0, &V0) != 0) return 0.0;
      row_energy_.Motion(T0, V0);
    } else {
      T0 = energy_T_;
      V0 = energy_V_;
    }
    energy_known_ = false;
    if (rhs_.Energy(t_new, y_new_.data(), &T1, &V1) != 0) return 0.0;
    row_energy_.Motion(T1, V1);
    energy_known_ = true;
    energy_t_ = t_new;
    energy_T_ = T1;
    energy_V_ = V1;
    const double e0 = T0 + V0, e1 = T1 + V1;
    long count = 1;  // instants in the step: tout + m interval_, m < count
    if (interval_ > 0.0) count = 1 + static_cast<long>(std::floor((t_new - tout) / interval_));
    if (count > 1 && tout + static_cast<double>(count - 1) * interval_ >= t_new) --count;
    const long checked = std::min(count, kRowEnergyInstants);
    double worst = 0.0;
    for (long c = 0; c < checked; ++c) {
      const long m = checked > 1 ? (c * (count - 1)) / (checked - 1) : 0;
      const double ti = tout + static_cast<double>(m) * interval_;
      double Tr = 0.0, Vr = 0.0;
      InterpolateFrom(t_, y_.data(), h, ti, stage_y_.data());
      if (rhs_.Energy(ti, stage_y_.data(), &Tr, &Vr) != 0) continue;
      const double d = row_energy_.Deviation(e0, e1, (ti - t_) / h, Tr + Vr, options_.rtol, T1, V1);
      if (!(d <= worst)) worst = d;
    }
    return worst;
  }

  int Underflow(double h) {
    char buf[200];
    std::snprintf(buf, sizeof buf,
                  "step size underflow: h = %.3g at t = %.17g (%s)", h, t_,
                  rhs_fails_ > 0 ? "the right-hand side kept failing" : "the error test failed repeatedly");
    underflow_ = buf;
    underflow_from_rhs_ = rhs_fails_ > 0;  // then the driver reports f's own time and cause
    return kUnderflow;
  }

  static constexpr double kEps = 2.220446049250313e-16;

  GuardedRhs& rhs_;
  const int n_;
  const IntegratorOptions options_;
  double stop_;
  double t_;                     // time of y_
  double t_old_ = 0.0;           // start of the last accepted step
  double h_ = 0.0;               // size of the next step to try
  double h_last_ = 0.0;          // size of the last accepted step
  ReleaseBound release_;         // held rows' release functions (none: no bound, no cost)
  double held_bound_ = INFINITY; // ... the next step's bound from them (ReleaseBound::Next)
  std::vector<double> y_;        // state at t_  (n)
  std::vector<double> y_old_;    // state at t_old_  (n)
  std::vector<double> y_new_;    // candidate y1 of Eq. (1)  (n)
  std::vector<double> stage_y_;  // argument of one stage  (n)
  std::vector<double> k_;        // stages k_0 .. k_15, row s at s n  (16 n)
  std::vector<double> r_;        // r0 .. r6 of Eq. (4), row m at m n  (7 n)
  bool project_ = false;         // accepted steps are projected (OdeSystem::Project)
  bool check_ = false;           // accepted steps are checked (OdeSystem::StepAccepted)
  bool energy_ = false;          // output instants checked against the steps' energies (Eq. 5)
  bool energy_known_ = false;    // energy_T_, energy_V_ are those of the state at energy_t_
  double energy_t_ = 0.0, energy_T_ = 0.0, energy_V_ = 0.0;
  RowEnergy row_energy_;          // Eq. (5)'s motion
  bool last_tout_set_ = false;
  double last_tout_ = 0.0, interval_ = 0.0;  // the last instant asked for, the spacing of the last two
  bool dense_ready_ = false;     // r_ holds the last step's dense output
  bool fsal_pending_ = false;    // K(tab::kStages) is f(t_, y_), not yet copied into K(0)
  bool stages_ready_ = false;    // K(13 .. 15) hold the last step's dense-output stages
  int rhs_fails_ = 0;            // recoverable failures of f in a row
  long steps_ = 0, rhs_evals_ = 0, err_test_fails_ = 0, dense_rejects_ = 0, energy_rejects_ = 0;
  std::vector<double> g_old_, g_new_;  // event functions at the last accepted step's end, and scratch
  std::vector<double> g_prev_;   // ... at its start
  std::vector<double> event_y_;  // Crossing's interpolated states  (n)
  std::vector<double> g_event_;  // the event functions at event_t_ (at t_ while none is pending)
  std::vector<double> g_root_;   // ... at the zero Crossing returned
  std::vector<double> g_scratch_;  // ... at Crossing's last point
  std::vector<double> sample_g_;   // ... at RiseFromZero's samples k = 1 .. 48, row k - 1  (48 x events)
  uint64_t samples_ = 0;           // bit k: sample k evaluated in this step
  std::vector<double> dip_g_;      // ... at DipFromZero's last sample  (events)
  std::vector<char> guarded_;      // function i has a graze guard (OdeSystem::Paired)  (events)
  std::vector<char> searched_;     // LocateEvent: function i searched in this step
  bool event_pending_ = false;   // an event function crossed zero at event_t_ in the last step
  double event_t_ = 0.0;
  int event_i_ = -1;
  dop853::StiffnessDetector stiffness_;  // sim/dop853_stiffness.h
  double stiff_time_ = NAN;      // where it first found the problem stiff
  std::string underflow_;        // Explain's text for kUnderflow
  bool underflow_from_rhs_ = false;
};

}  // namespace

std::unique_ptr<Stepper> MakeDop853Stepper(GuardedRhs& rhs, double t0, const double* y0, double stop,
                                           const IntegratorOptions& options, std::string* error) {
  auto stepper = std::make_unique<Dop853Stepper>(rhs, t0, stop, options);
  if (!stepper->Init(y0)) {
    *error = "the right-hand side failed at the start";
    return nullptr;
  }
  return stepper;
}

}  // namespace kanesim::sim::detail
