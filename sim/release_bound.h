// Internal to sim: the step bound while rows are held (OdeSystem::HeldEvents; docs/integrators.md
// "Held rows"). A stuck joint or a resting stop or contact holds the state still, so no error
// estimate limits the step, while its release function g (friction bound minus the needed
// force, a contact's reaction) changes with time and ends the hold where it crosses zero. A
// step longer than the window where g < 0 steps over the release and the run silently stays
// held. Each solver asks Next after every accepted step; the next step is at most its answer.
//
// First, g, g' and g'' of the quadratic through g at t and the last two accepted steps (one
// event-function evaluation): while its bound and T are at least 4 times those two steps, that
// bound is the answer (no release foretold soon). Otherwise, and within two steps of Init,
// for each held row, g, its rate g' and curvature g'' along the motion at (t, y) are central
// differences at t -+ d of g(t -+ d, y -+ d y' + d^2/2 y'') (y'' from a forward difference of
// f), d = 1e-3 of the last step or of g's time scale T, whichever is smaller; a derivative
// that differs by more than 10 % from the same over 2d is round-off (a reaction zero in exact
// arithmetic) and taken as zero:
//   m(s) = g + g' s + g'' s^2 / 2                  (the quadratic model)                 (1)
//   T = 1 / max(|g'| / g, sqrt(|g''| / (2 g)))     (the time in which either term alone
//                                                   changes g by g)                       (2)
// and the bound is, from the model's first positive root s1 (second s2 when g'' > 0):
//   - a dip (g'' > 0, two roots, w = s2 - s1): s1 / 2 while s1 > w (approach: a model fitted
//     far from a narrow dip misplaces it), else min(s1 + w/2, 3/2 s1) (into the dip);
//   - a crossing that stays (g'' <= 0): 3/2 s1 (past it: the root finding locates it);
//   - no root, g falling to a positive minimum at sm = -g'/g'': min(sm, 3/2 g / |g'|) (a
//     minimum the model puts above zero may dip below it);
//   - g falling faster and faster (g', g'' < 0, the rate term dominant): g' / g'' at most
//     (the time in which the rate doubles: a rise like exp's is not quadratic);
// always at most 2 T, at least kFloor of max(1, |t|). For g of an exact parabola (a drive's
// smooth peak that passes the bound briefly) the steps land inside the window however narrow
// it is: the approach halves the distance, then the step from s1 <= w lands in it.
//
// What it cannot see: a window that g's value, rate and curvature at the last step do not
// foretell (a pulse that starts after that step from a drive flat there, a rise whose higher
// derivatives dominate, a drive much faster than the steps). Integrate still bounds each step
// by the output interval while a row is held; the stepping API by the caller's step.
#pragma once

#include <vector>

#include "sim/integrator.h"

namespace kanesim::sim::detail {

class ReleaseBound {
 public:
  // The held rows of `system` now (they change only at events, after which a fresh solver
  // starts). None: Active() is false and Next is never needed.
  void Init(OdeSystem& system);
  bool Active() const { return !held_.empty(); }
  // The largest next step from (t, y), an accepted step's end; h_last the step that led there
  // (0: none yet). +inf when no held row is near its release or g cannot be evaluated.
  // g_t, f_t: the event functions (NumEvents) and f (Size) at (t, y) when the solver has them
  // (DOP853: its step-end functions and its FSAL stage); nullptr: evaluated here.
  double Next(double t, const double* y, double h_last, const double* g_t = nullptr, const double* f_t = nullptr);

  static constexpr double kFloor = 1e-9;  // relative to max(1, |t|): the smallest bound

 private:
  // g, g', g'' of every held row with differences of half-width d; false when f or g fails.
  bool Differences(double t, const double* y, double d);
  // The bound from the quadratic through g at this and the last two accepted steps (no right-
  // hand side, no sample more); +0 when that history is too short or predicts a release
  // within the next few steps (then Next samples around t).
  double FromHistory(double t);
  void Remember(double t);

  OdeSystem* system_ = nullptr;
  std::vector<int> held_;           // the held rows' event functions (OdeSystem::HeldEvents)
  std::vector<double> yd_, ydd_;    // y' and y'' at (t, y)  (n)
  std::vector<double> ys_, f_;      // a shifted state, f there  (n)
  std::vector<double> g0_, gm_, gp_;  // all event functions at t, t - d, t + d  (NumEvents)
  std::vector<double> gmm_, gpp_;     // ... at t - 2d, t + 2d
  std::vector<double> g_, g1_, g2_;   // per held row: g, g', g''
  std::vector<double> ga_, gb_;       // per held row: g at the last two accepted steps ...
  double ta_ = 0.0, tb_ = 0.0;        // ... at these times (ta_ the later)
  int history_ = 0;                   // how many of them are set (0 after Init)
};

// One held row's bound from g, g' and g'' (Eq. 1-2 above); *scale := T of Eq. (2).
double HeldRowBound(double g, double g1, double g2, double* scale);

}  // namespace kanesim::sim::detail
