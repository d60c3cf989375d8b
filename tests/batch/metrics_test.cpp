// Streaming metrics against closed forms of a sampled sine.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "batch/metrics.h"

namespace kanesim::batch {
namespace {

// Wrong if a metric is misparsed or its column name changes (summaries would not merge).
TEST(ParseMetric, KindsAndColumns) {
  Metric m;
  std::string err;
  ASSERT_TRUE(ParseMetric("cross:j[1].q=0.25", &m, &err)) << err;
  EXPECT_EQ(m.kind, Metric::Kind::Cross);
  EXPECT_EQ(m.signal, "j[1].q");
  EXPECT_EQ(m.level, 0.25);
  EXPECT_EQ(m.Column(), "cross:j[1].q=0.25");
  ASSERT_TRUE(ParseMetric("rms:kinetic_energy", &m, &err));
  EXPECT_EQ(m.Column(), "rms:kinetic_energy");
  EXPECT_FALSE(ParseMetric("median:x", &m, &err));
  EXPECT_FALSE(ParseMetric("cross:x", &m, &err));
  EXPECT_FALSE(ParseMetric("final:", &m, &err));
}

// x(t) = 1 + sin(2 pi t) on [0, 1.25], 2001 rows. Closed forms: final 2, min 0, max 2,
// mean = 1 + (1 - cos(2.5 pi)) / (2.5 pi) = 1 + 1/(2.5 pi), rms^2 = mean of
// 1 + 2 sin + sin^2, first crossing of 1.5 at t = 1/12. Tolerances: trapezoid error
// O(h^2) with h = 6.25e-4, and linear interpolation of the crossing, both < 1e-6.
TEST(MetricSink, SineAgainstClosedForm) {
  std::vector<Metric> ms;
  std::string err;
  for (const char* t : {"final:x", "min:x", "max:x", "mean:x", "rms:x", "cross:x=1.5", "cross:x=5"}) {
    Metric m;
    ASSERT_TRUE(ParseMetric(t, &m, &err));
    ms.push_back(m);
  }
  MetricSink sink(ms, nullptr);
  ASSERT_TRUE(sink.Begin({"y", "x"}));
  const int n = 2000;
  const double T = 1.25, pi = std::numbers::pi;
  for (int k = 0; k <= n; ++k) {
    double t = T * k / n;
    double row[2] = {0.0, 1 + std::sin(2 * pi * t)};
    ASSERT_TRUE(sink.Row(t, row, 2));
  }
  std::vector<double> v = sink.Values();
  const double mean = 1 + (1 - std::cos(2 * pi * T)) / (2 * pi * T);
  const double mean_sin = (1 - std::cos(2 * pi * T)) / (2 * pi * T);
  const double mean_sin2 = 0.5 - std::sin(4 * pi * T) / (8 * pi * T);
  EXPECT_NEAR(v[0], 2.0, 1e-12);
  EXPECT_NEAR(v[1], 0.0, 1e-5);  // the minimum at t = 0.75 is a sample point up to rounding
  EXPECT_NEAR(v[2], 2.0, 1e-12);
  EXPECT_NEAR(v[3], mean, 1e-6);
  EXPECT_NEAR(v[4], std::sqrt(1 + 2 * mean_sin + mean_sin2), 1e-6);
  EXPECT_NEAR(v[5], 1.0 / 12.0, 1e-6);
  EXPECT_TRUE(std::isnan(v[6]));  // never reaches 5
}

// Wrong if a metric asks for a signal that is not produced and nobody notices.
TEST(MetricSink, MissingSignalIsAnError) {
  Metric m;
  std::string err;
  ASSERT_TRUE(ParseMetric("final:nope", &m, &err));
  MetricSink sink({m}, nullptr);
  EXPECT_FALSE(sink.Begin({"x"}));
  EXPECT_NE(sink.error().find("nope"), std::string::npos);
}

}  // namespace
}  // namespace kanesim::batch
