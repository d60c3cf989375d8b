// End stops of one-coordinate joints (issue 41, first part): the stdlib's q_min, q_max and
// restitution carried through the flat mechanism into the Program and the runtime's EndStops,
// their diagnostics, and a start past a stop refused. (Their events: end_stop_events_test.cpp.)
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "runtime/program/program.h"
#include "tests/compiler/compile_test_util.h"
#include "tests/support/model_texts.h"

namespace kanesim::test {
namespace {

// A pendulum on joint j1 (Revolute or Prismatic) with `mods` added to its modifiers.
std::string Pendulum(const std::string& joint, const std::string& mods) {
  return PendulumText{.model = "M", .joint = joint, .mods = mods}.Text();
}

const rt::TreeJoint& OnlyJoint(const rt::Program& p) {
  EXPECT_EQ(p.joints.size(), 1u);
  return p.joints.front();
}

// If this fails, the stdlib's stops do not reach the compiled program (q_min, q_max and
// restitution as given, the joint listed among the stop joints).
TEST(EndStops, RevoluteStopsReachTheProgram) {
  auto l = LoadModel(Pendulum("Revolute", ", q_min = -0.5, q_max = 2 * 0.5, restitution = 0.7"), {}, {}, true);
  ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  const rt::TreeJoint& j = OnlyJoint(*l->prog);
  EXPECT_EQ(j.q_min, -0.5);
  EXPECT_EQ(j.q_max, 1.0);
  EXPECT_EQ(j.restitution, 0.7);
  EXPECT_EQ(l->prog->stop_joints, std::vector<int>{j.child});
  const std::vector<rt::EndStop> stops = rt::EndStops(*l->prog);
  ASSERT_EQ(stops.size(), 1u);
  EXPECT_EQ(stops[0].joint, "j1");
  EXPECT_EQ(stops[0].q, 0);
  EXPECT_EQ(stops[0].u, 0);
  EXPECT_EQ(stops[0].q_max, 1.0);
}

// If this fails, a one-sided stop gets a second side, or the default restitution is not 0.
TEST(EndStops, OneSidedPrismaticStop) {
  auto l = LoadModel(Pendulum("Prismatic", ", q_max = 0.25"), {}, {}, true);
  ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  const rt::TreeJoint& j = OnlyJoint(*l->prog);
  EXPECT_TRUE(std::isinf(j.q_min) && j.q_min < 0);
  EXPECT_EQ(j.q_max, 0.25);
  EXPECT_EQ(j.restitution, 0.0);
  EXPECT_EQ(l->prog->stop_joints.size(), 1u);
}

// If this fails, a joint without stops carries one (the default must be none, at no cost:
// no stop joint, so no event machinery) or its run is refused.
TEST(EndStops, NoStopsByDefaultAndTheRunGoesOn) {
  auto l = LoadModel(Pendulum("Revolute", ", q(start = 0.3)"), {}, {}, true);
  ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  const rt::TreeJoint& j = OnlyJoint(*l->prog);
  EXPECT_TRUE(std::isinf(j.q_min) && std::isinf(j.q_max));
  EXPECT_TRUE(l->prog->stop_joints.empty());
  EXPECT_TRUE(rt::EndStops(*l->prog).empty());
  sim::SimResult r;
  sim::MemorySink s = RunWith(*l->prog, AllIntegrators().front(), 0.5, 0.25, {"j1.q"}, &r, 1e-8);
  EXPECT_EQ(r.status, sim::SimResult::Status::kOk) << r.message;
  EXPECT_TRUE(r.stats.events.empty());
  EXPECT_EQ(s.times, (std::vector<double>{0.0, 0.25, 0.5}));
}

// If this fails, stops out of order are accepted. (A restitution outside [0, 1] is the
// parameter's range error, E213.)
TEST(EndStops, BadStopsAreReportedWithK318) {
  auto order = LoadModel(Pendulum("Revolute", ", q_min = 1, q_max = 0.5"), {}, {}, true);
  ASSERT_TRUE(order);
  EXPECT_NE(Find(order->errors, "K318", "q_min must be less than q_max"), nullptr) << Messages(order->errors);
}

// If this fails, a joint that starts past its stop runs (usage error, exit 1, expected).
TEST(EndStops, StartPastAStopIsAUsageError) {
  auto l = LoadModel(Pendulum("Revolute", ", q(start = -1), q_min = -0.5"), {}, {}, true);
  ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  for (const IntegratorChoice& how : AllIntegrators()) {
    sim::SimResult r;
    sim::MemorySink s = RunWith(*l->prog, how, 1.0, 0.25, {"j1.q"}, &r, 1e-8);
    EXPECT_EQ(r.status, sim::SimResult::Status::kUsageError) << how.name;
    EXPECT_NE(r.message.find("joint 'j1' starts at q = -1, past its stop q_min = -0.5"), std::string::npos) << r.message;
    EXPECT_TRUE(s.rows.empty()) << how.name;
  }
}

}  // namespace
}  // namespace kanesim::test
