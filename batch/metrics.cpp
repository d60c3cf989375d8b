#include "batch/metrics.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <limits>

#include "flat/number.h"

namespace kanesim::batch {
namespace {

struct KindName {
  Metric::Kind kind;
  const char* name;
};
constexpr KindName kKinds[] = {{Metric::Kind::Final, "final"}, {Metric::Kind::Min, "min"},
                               {Metric::Kind::Max, "max"},     {Metric::Kind::Mean, "mean"},
                               {Metric::Kind::Rms, "rms"},     {Metric::Kind::Cross, "cross"}};

const char* KindToName(Metric::Kind k) {
  for (const KindName& kn : kKinds)
    if (kn.kind == k) return kn.name;
  return "?";
}

}  // namespace

std::string Metric::Column() const {
  std::string s = KindToName(kind);
  s.append(":").append(signal);
  if (kind == Kind::Cross) s.append("=").append(sim::FormatNumber(level));
  return s;
}

bool ParseMetric(const std::string& text, Metric* out, std::string* error) {
  size_t colon = text.find(':');
  const std::string usage =
      "a metric is final|min|max|mean|rms:SIGNAL or cross:SIGNAL=LEVEL, got '" + text + "'";
  if (colon == std::string::npos || colon + 1 >= text.size()) {
    *error = usage;
    return false;
  }
  std::string kind = text.substr(0, colon), rest = text.substr(colon + 1);
  Metric m;
  bool found = false;
  for (const KindName& kn : kKinds)
    if (kind == kn.name) m.kind = kn.kind, found = true;
  if (!found) {
    *error = "unknown metric '" + kind + "': " + usage;
    return false;
  }
  if (m.kind == Metric::Kind::Cross) {
    size_t eq = rest.rfind('=');
    if (eq == std::string::npos || eq == 0) {
      *error = "cross needs a level: cross:SIGNAL=LEVEL, got '" + text + "'";
      return false;
    }
    std::string why;
    if (!flat::ParseNumber(rest.substr(eq + 1), &m.level, &why)) {
      *error = "the level of '" + text + "': " + why;
      return false;
    }
    rest = rest.substr(0, eq);
  }
  m.signal = rest;
  *out = m;
  return true;
}

MetricSink::MetricSink(std::vector<Metric> metrics, sim::SignalSink* forward)
    : metrics_(std::move(metrics)), state_(metrics_.size()), forward_(forward) {}

bool MetricSink::Begin(const std::vector<std::string>& names) {
  for (size_t i = 0; i < metrics_.size(); ++i) {
    auto it = std::find(names.begin(), names.end(), metrics_[i].signal);
    if (it == names.end()) {
      error_ = "metric signal '" + metrics_[i].signal + "' is not among the outputs";
      return false;
    }
    state_[i] = State{};
    state_[i].column = static_cast<int>(it - names.begin());
  }
  rows_ = 0;
  return forward_ ? forward_->Begin(names) : true;
}

bool MetricSink::Row(double t, const double* values, size_t count) {
  for (size_t i = 0; i < metrics_.size(); ++i) {
    State& s = state_[i];
    const double x = values[s.column];
    if (rows_ == 0) {
      s.first = s.min = s.max = x;
      if (x == metrics_[i].level) s.crossed = true, s.cross = t;
    } else {
      const double dt = t - t_prev_;
      s.integral += 0.5 * dt * (s.last + x);          // trapezoid
      s.integral_sq += 0.5 * dt * (s.last * s.last + x * x);
      s.min = std::min(s.min, x);
      s.max = std::max(s.max, x);
      const double L = metrics_[i].level;
      if (!s.crossed && (s.last - L) * (x - L) <= 0.0 && x != s.last) {
        s.crossed = true;
        s.cross = t_prev_ + dt * (L - s.last) / (x - s.last);  // linear interpolation
      }
    }
    s.last = x;
  }
  if (rows_ == 0) t0_ = t;
  t_prev_ = t;
  ++rows_;
  return forward_ ? forward_->Row(t, values, count) : true;
}

bool MetricSink::End() { return forward_ ? forward_->End() : true; }

std::vector<double> MetricSink::Values() const {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<double> v(metrics_.size(), nan);
  if (rows_ == 0) return v;
  const double T = t_prev_ - t0_;
  for (size_t i = 0; i < metrics_.size(); ++i) {
    const State& s = state_[i];
    switch (metrics_[i].kind) {
      case Metric::Kind::Final: v[i] = s.last; break;
      case Metric::Kind::Min: v[i] = s.min; break;
      case Metric::Kind::Max: v[i] = s.max; break;
      case Metric::Kind::Mean: v[i] = T > 0 ? s.integral / T : s.last; break;
      case Metric::Kind::Rms: v[i] = T > 0 ? std::sqrt(s.integral_sq / T) : std::abs(s.last); break;
      case Metric::Kind::Cross: v[i] = s.crossed ? s.cross : nan; break;
    }
  }
  return v;
}

}  // namespace kanesim::batch
