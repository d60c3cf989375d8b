// The step-size control of DOP853 (Eq. (3) of sim/integrator_dop853.cpp): the
// constants of Hairer's dop853.f (safety 0.9, the new step at most 6x larger and at most 3x
// smaller than the last, no growth right after a rejection; Hairer, Norsett & Wanner,
// Solving ODEs I, 2nd ed., sec. II.4 and II.10). Shared with the work-precision benchmark's
// Pinocchio driver (bench/pin/pin_driver.cpp), so that both tools take the same steps from
// the same error estimates and a comparison of their run times is one of their
// right-hand sides.
#pragma once

#include <algorithm>
#include <cmath>

namespace kanesim::sim::dop853 {

constexpr double kSafety = 0.9;         // h_new = h kSafety err^(-1/8), clamped:
constexpr double kMinShrink = 1.0 / 3;  // at most 3x smaller per step
constexpr double kMaxGrow = 6.0;        // at most 6x larger per step
constexpr double kStretch = 1.01;       // a step within 1% of the stop time goes onto it

// Factor for the next step after an accepted one with error err (<= 1); no growth when the
// step was retried after a rejection.
inline double GrowFactor(double err, bool after_rejection) {
  const double f = err == 0.0 ? kMaxGrow : std::min(kMaxGrow, kSafety * std::pow(err, -1.0 / 8));
  return after_rejection ? std::min(f, 1.0) : f;
}

// Factor for the retry after a rejected step (err > 1, or not finite).
inline double ShrinkFactor(double err) {
  return std::isfinite(err) ? std::max(kMinShrink, kSafety * std::pow(err, -1.0 / 8)) : kMinShrink;
}

}  // namespace kanesim::sim::dop853
