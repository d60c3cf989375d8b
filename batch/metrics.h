// Scalar metrics of a scenario's output signals, computed while the rows stream by
// (nothing is stored): the sweep summary has one column per metric.
//
//   final:S        S at the stop time
//   min:S, max:S   extremes over the output instants
//   mean:S         (1/T) ∫ S dt over [t0, tf], trapezoidal rule on the output instants
//   rms:S          sqrt((1/T) ∫ S² dt), same rule (T = tf - t0; when T = 0 both use the
//                  single value)
//   cross:S=L      first time S crosses the level L in either direction, interpolated
//                  linearly between the two output instants that bracket it (t0 if S
//                  starts exactly at L); empty when it never does
// Accuracy follows the output interval (the quadrature and the interpolation work on
// the rows); set a finer --interval for sharper means and crossing times.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "sim/csv.h"

namespace kanesim::batch {

struct Metric {
  enum class Kind { Final, Min, Max, Mean, Rms, Cross };
  Kind kind = Kind::Final;
  std::string signal;
  double level = 0.0;  // Cross only
  std::string Column() const;  // the summary column name, e.g. "cross:slider.q=0"
};

// "kind:signal" or "cross:signal=level"; false with a message otherwise.
bool ParseMetric(const std::string& text, Metric* out, std::string* error);

// Streams rows into metric values; optionally forwards every row to another sink (the
// scenario's trajectory file).
class MetricSink final : public sim::SignalSink {
 public:
  // `metrics` refer to signals by name; each must be among the names given to Begin.
  MetricSink(std::vector<Metric> metrics, sim::SignalSink* forward);
  bool Begin(const std::vector<std::string>& names) override;
  bool Row(double t, const double* values, size_t count) override;
  bool End() override;

  // One value per metric (NaN: no rows, or a level never crossed).
  std::vector<double> Values() const;
  const std::string& error() const { return error_; }

 private:
  struct State {
    int column = -1;
    double first = 0, last = 0, min = 0, max = 0, integral = 0, integral_sq = 0, cross = 0;
    bool crossed = false;
  };
  std::vector<Metric> metrics_;
  std::vector<State> state_;
  sim::SignalSink* forward_;
  long rows_ = 0;
  double t0_ = 0.0, t_prev_ = 0.0;
  std::string error_;
};

}  // namespace kanesim::batch
