// Golden tests of a model with events (docs/golden_tests.md "Events"): a run writes each
// event's time twice (its left and right limits); the stored output keeps both rows and
// the comparison matches them side to side with the run's rows of the same event. Before,
// `kanesim test --update` recorded such a golden and the next `kanesim test` refused it as
// corrupt ("the times do not increase").
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <string>
#include <vector>

#include "batch/golden.h"

namespace kanesim::batch {
namespace {

// x = t, jumping from t_e on by -1: rows every 0.1 on [0, 1] and the event's two at t_e.
Trajectory Jump(double t_e) {
  Trajectory tr;
  tr.names = {"x"};
  for (int k = 0; k <= 10; ++k) {
    const double t = 0.1 * k;
    if (t > t_e && (tr.t.empty() || tr.t.back() < t_e)) {
      tr.t.insert(tr.t.end(), {t_e, t_e});
      tr.rows.push_back({t_e});
      tr.rows.push_back({t_e - 1});
    }
    tr.t.push_back(t);
    tr.rows.push_back({t > t_e ? t - 1 : t});
  }
  return tr;
}

// If this fails, a stored output with an event's two rows is refused as corrupt (or one
// whose times go back is accepted).
TEST(GoldenEvents, StoredEventRowsReadBack) {
  const std::string path = testing::TempDir() + "/golden_events.csv";
  std::ofstream(path) << FormatTrajectoryCsv(Jump(0.45));
  Trajectory back;
  std::string err;
  ASSERT_TRUE(ReadTrajectoryCsv(path, &back, &err)) << err;
  ASSERT_EQ(back.t.size(), 13u);
  EXPECT_EQ(back.t[5], 0.45);
  EXPECT_EQ(back.t[6], 0.45);
  EXPECT_EQ(back.rows[6][0], 0.45 - 1);
}

// If this fails, an event a round-off later in the run compares its left limit with the
// run's right one (a deviation of the jump, 1), or a run without the jump passes.
TEST(GoldenEvents, EventRowsCompareSideToSide) {
  GoldenSpec spec;
  spec.default_tol = {"*", 1e-9, 0};
  const Trajectory golden = Jump(0.45);
  for (double shift : {0.0, 1e-11, -1e-11}) {
    const CompareResult c = Compare(spec, golden, Jump(0.45 + shift));
    EXPECT_TRUE(c.pass) << "shift " << shift << ": largest " << c.signals[0].max_dev << " at " << c.signals[0].t_max;
  }
  Trajectory flat = golden;  // the same instants, no jump at the event
  flat.rows[6][0] = flat.rows[5][0];
  const CompareResult c = Compare(spec, golden, flat);
  EXPECT_FALSE(c.pass);
  EXPECT_EQ(c.signals[0].first_exceed, 0.45);
  const CompareResult moved = Compare(spec, golden, Jump(0.55));  // past a grid instant
  EXPECT_FALSE(moved.pass);
}

}  // namespace
}  // namespace kanesim::batch
