// A held row's release found however long the steps had grown (sim/integrator.h,
// OdeSystem::Holding): while a joint is stuck the state stands still, no error estimate
// limits the step, and DOP853's steps grew six-fold each until one stepped over the whole
// window in which the drive passes the friction bound: the gear below stayed stuck for 4 s
// (a silent wrong answer) where the other integrators slipped at asin(2/3)/3.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "tests/compiler/compile_test_util.h"

namespace kanesim::test {
namespace {

// A gear pair in the horizontal plane (gravity along the axes: no work), exact friction 0.2 on
// the driving joint, the drive 0.3 sin(3t): stuck at rest until 0.3 sin(3t) reaches 0.2.
const std::string kGeared = GearedPair("Geared", "{0, 0, -9.81}", ", friction_torque = 0.2, friction_exact = true", "",
                                        "  j1.tau = 0.3 * sin(3 * time);\n");

// If this fails, an integrator stepped over the slip window of a stuck joint (its first event
// after the stick at the start is not the slip at asin(2/3)/3), or the joint moved while stuck.
TEST(HeldStep, AStuckJointSlipsWhenTheDrivePassesItsBoundInEveryIntegrator) {
  auto l = LoadModel(kGeared, {}, {}, true);
  ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  const double t_slip = std::asin(2.0 / 3.0) / 3.0;
  for (const IntegratorChoice& how : AllIntegrators()) {
    sim::SimResult r;
    sim::MemorySink s = RunWith(*l->prog, how, 4.0, 0.008, {"j1.q", "j1.u"}, &r, 1e-10);
    ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << how.name << ": " << r.message;
    const std::vector<sim::EventRecord>& ev = r.stats.events;
    ASSERT_GE(ev.size(), 2u) << how.name;
    EXPECT_EQ(ev[0].kind.rfind("sticks", 0), 0u) << how.name << " " << ev[0].kind;
    EXPECT_EQ(ev[1].kind.rfind("slips", 0), 0u) << how.name << " " << ev[1].kind;
    EXPECT_NEAR(ev[1].time, t_slip, 1e-8) << how.name;
    for (size_t k = 0; k < s.times.size() && s.times[k] < t_slip; ++k)
      EXPECT_EQ(s.rows[k][0], 0.0) << how.name << " t = " << s.times[k];
  }
}

}  // namespace
}  // namespace kanesim::test
