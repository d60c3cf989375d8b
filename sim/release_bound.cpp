#include "sim/release_bound.h"

#include <algorithm>
#include <cmath>

namespace kanesim::sim::detail {

namespace {
constexpr double kDiff = 1e-3;     // d: this fraction of the last step or of T (Eq. 2)
constexpr double kDiffRoom = 1e2;  // ... taken again smaller when T < kDiffRoom d
constexpr double kOvershoot = 1.5;  // past a crossing the model places: the root finding locates it
constexpr double kScales = 2.0;     // steps of at most this many T
// g's round-off relative to the largest |g| of the three samples: differences below what it
// makes of them are zero (a constant g stays unbounded).
constexpr double kNoise = 1e-11;
constexpr double kInf = HUGE_VAL;
constexpr double kAgree = 0.1;  // derivatives over d and 2d this close (relative) are g's own
// The history's model is trusted (no samples around t) while its bound and time scale are at
// least this many times the span of the last two steps.
constexpr double kHistoryRoom = 4.0;

// The positive roots of g + g1 s + g2 s^2 / 2, ascending (at most two); *n how many.
void PositiveRoots(double g, double g1, double g2, double* r, int* n) {
  *n = 0;
  if (g2 == 0.0) {
    if (g1 < 0.0) r[(*n)++] = -g / g1;
    return;
  }
  const double a = 0.5 * g2, disc = g1 * g1 - 4.0 * a * g;
  if (disc < 0.0) return;
  const double q = -0.5 * (g1 + std::copysign(std::sqrt(disc), g1));  // no cancellation
  if (q == 0.0) return;
  double x = q / a, z = g / q;
  if (x > z) std::swap(x, z);
  if (x > 0.0) r[(*n)++] = x;
  if (z > 0.0) r[(*n)++] = z;
}
}  // namespace

double HeldRowBound(double g, double g1, double g2, double* scale) {
  *scale = kInf;
  if (!(g > 0.0)) return kInf;  // at or past its release: the root finding's
  const double r1 = std::abs(g1) / g, r2 = std::sqrt(std::abs(g2) / (2.0 * g)), rate = std::max(r1, r2);
  if (rate > 0.0) *scale = 1.0 / rate;
  double r[2];
  int n = 0;
  PositiveRoots(g, g1, g2, r, &n);
  double h = kInf;
  if (n == 2 && g2 > 0.0) {  // a dip: approach it, then into it
    const double w = r[1] - r[0];
    h = r[0] > w ? 0.5 * r[0] : std::min(r[0] + 0.5 * w, kOvershoot * r[0]);
  } else if (n >= 1) {
    h = kOvershoot * r[0];
  } else if (g1 < 0.0 && g2 > 0.0) {  // to a positive minimum
    h = std::min(-g1 / g2, kOvershoot * g / -g1);
  }
  if (g1 < 0.0 && g2 < 0.0 && r1 >= 0.1 * rate) h = std::min(h, g1 / g2);
  return std::min(h, kScales * *scale);
}

void ReleaseBound::Init(OdeSystem& system) {
  system_ = &system;
  system.HeldEvents(&held_);
  if (held_.empty()) return;
  const size_t n = static_cast<size_t>(system.Size()), ne = static_cast<size_t>(system.NumEvents());
  yd_.resize(n);
  ydd_.resize(n);
  ys_.resize(n);
  f_.resize(n);
  g0_.resize(ne);
  gm_.resize(ne);
  gp_.resize(ne);
  gmm_.resize(ne);
  gpp_.resize(ne);
  g_.resize(held_.size());
  g1_.resize(held_.size());
  g2_.resize(held_.size());
  ga_.resize(held_.size());
  gb_.resize(held_.size());
  history_ = 0;
}

double ReleaseBound::FromHistory(double t) {
  if (history_ < 2 || !(t > ta_ && ta_ > tb_)) return 0.0;
  const double a = t - ta_, span = t - tb_;
  double h = kInf, scale = kInf;
  for (size_t k = 0; k < held_.size(); ++k) {
    const double g = g0_[static_cast<size_t>(held_[k])];
    const double big = std::max({std::abs(g), std::abs(ga_[k]), std::abs(gb_[k])});
    const double d01 = (g - ga_[k]) / a, d12 = (ga_[k] - gb_[k]) / (ta_ - tb_), c = (d01 - d12) / span;
    double g1 = d01 + c * a, g2 = 2.0 * c;  // the interpolating quadratic's slope, curvature at t
    if (std::abs(g1) < kNoise * big / a) g1 = 0.0;
    if (std::abs(g2) < 4.0 * kNoise * big / (a * span)) g2 = 0.0;
    double s = kInf;
    h = std::min(h, HeldRowBound(g, g1, g2, &s));
    scale = std::min(scale, s);
  }
  return h >= kHistoryRoom * span && scale >= kHistoryRoom * span ? h : 0.0;
}

void ReleaseBound::Remember(double t) {
  if (history_ > 0 && !(t > ta_)) return;
  for (size_t k = 0; k < held_.size(); ++k) {
    gb_[k] = ga_[k];
    ga_[k] = g0_[static_cast<size_t>(held_[k])];
  }
  tb_ = ta_;
  ta_ = t;
  history_ = std::min(history_ + 1, 2);
}

bool ReleaseBound::Differences(double t, const double* y, double d) {
  const size_t n = yd_.size();
  for (size_t i = 0; i < n; ++i) ys_[i] = y[i] + d * yd_[i];
  if (system_->Rhs(t + d, ys_.data(), f_.data()) != 0) return false;
  for (size_t i = 0; i < n; ++i) ydd_[i] = (f_[i] - yd_[i]) / d;
  std::vector<double>* at[4] = {&gm_, &gp_, &gmm_, &gpp_};
  const double shift[4] = {-d, d, -2.0 * d, 2.0 * d};
  for (int s = 0; s < 4; ++s) {  // y(t + shift) to second order
    const double e = shift[s];
    for (size_t i = 0; i < n; ++i) ys_[i] = y[i] + e * yd_[i] + 0.5 * e * e * ydd_[i];
    if (system_->EventFunctions(t + e, ys_.data(), at[s]->data()) != 0) return false;
  }
  for (size_t k = 0; k < held_.size(); ++k) {
    const size_t i = static_cast<size_t>(held_[k]);
    const double big = std::max({std::abs(g0_[i]), std::abs(gm_[i]), std::abs(gp_[i]), std::abs(gmm_[i]), std::abs(gpp_[i])});
    g_[k] = g0_[i];
    g1_[k] = (gp_[i] - gm_[i]) / (2.0 * d);
    g2_[k] = (gp_[i] - 2.0 * g0_[i] + gm_[i]) / (d * d);
    // The same over 2d: a derivative that is g's own (not its round-off) is nearly the same;
    // one that is round-off (a reaction zero in exact arithmetic: a robot in free fall on its
    // stops) scales as 1/d and is dropped.
    const double g1w = (gpp_[i] - gmm_[i]) / (4.0 * d), g2w = (gpp_[i] - 2.0 * g0_[i] + gmm_[i]) / (4.0 * d * d);
    if (std::abs(g1_[k]) < kNoise * big / d || std::abs(g1w - g1_[k]) > kAgree * std::abs(g1_[k])) g1_[k] = 0.0;
    if (std::abs(g2_[k]) < 4.0 * kNoise * big / (d * d) || std::abs(g2w - g2_[k]) > kAgree * std::abs(g2_[k]))
      g2_[k] = 0.0;
  }
  return true;
}

double ReleaseBound::Next(double t, const double* y, double h_last, const double* g_t, const double* f_t) {
  if (held_.empty()) return kInf;
  const double unit = std::max(1.0, std::abs(t));
  if (g_t != nullptr) {
    std::copy(g_t, g_t + g0_.size(), g0_.begin());
  } else if (system_->EventFunctions(t, y, g0_.data()) != 0) {
    return kInf;
  }
  const double cheap = FromHistory(t);
  Remember(t);
  if (cheap > 0.0) return cheap;  // far from any release by the last steps' g: no sampling
  if (f_t != nullptr) {
    std::copy(f_t, f_t + yd_.size(), yd_.begin());
  } else if (system_->Rhs(t, y, yd_.data()) != 0) {
    return kInf;
  }
  double d = h_last > 0.0 ? kDiff * h_last : 1e-6 * unit;
  double h = kInf;
  for (int pass = 0; pass < 3; ++pass) {
    d = std::max(d, 1e-10 * unit);  // t -+ d must differ from t
    if (!Differences(t, y, d)) return kInf;
    double scale = kInf;
    h = kInf;
    for (size_t k = 0; k < held_.size(); ++k) {
      double s = kInf;
      h = std::min(h, HeldRowBound(g_[k], g1_[k], g2_[k], &s));
      scale = std::min(scale, s);
    }
    if (!(scale < kDiffRoom * d) || kDiff * scale >= d) break;  // d small against g's time scale
    d = kDiff * scale;
  }
  return std::max(h, kFloor * unit);
}

}  // namespace kanesim::sim::detail
