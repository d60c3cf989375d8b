// Stiffness detection for DOP853, after Hairer & Wanner, Solving Ordinary Differential
// Equations II, 2nd ed., Springer 1996, sec. IV.2 ("Automatic stiffness detection"), as
// their dop853.f does it. Two stages of one step are evaluated at the same time t + h
// (stage 11, c = 1, and f at the new point): the ratio of the differences of f and of its
// arguments estimates the largest |lambda| of df/dy along that direction, so
//   h |lambda| ~ |h| |k_12 - k_11| / |y1 - Y_11|.
// An explicit method whose steps are bounded by stability, not accuracy, sits at the edge
// of its stability region (about 6.1 along the negative real axis for DOP853), step after
// step; a non-stiff problem only visits it now and then.
#pragma once

#include <cmath>

namespace kanesim::sim::dop853 {

class StiffnessDetector {
 public:
  static constexpr double kBoundary = 6.1;  // DOP853's stability boundary on the real axis
  static constexpr int kStiffSteps = 15;    // accepted steps near it in a row: stiff
  static constexpr int kCalmSteps = 6;      // steps away from it that clear the count

  // One accepted step's estimate h |lambda| (NaN or negative: no information).
  void Accepted(double h_lambda) {
    if (!(h_lambda >= 0.0)) return;
    if (h_lambda > kBoundary) {
      calm_ = 0;
      last_ = h_lambda;
      if (++near_ >= kStiffSteps) stiff_ = true;
    } else if (++calm_ >= kCalmSteps) {
      near_ = 0;
    }
  }
  bool Stiff() const { return stiff_; }
  double LastHLambda() const { return last_; }

 private:
  int near_ = 0, calm_ = 0;
  bool stiff_ = false;
  double last_ = 0.0;
};

}  // namespace kanesim::sim::dop853
