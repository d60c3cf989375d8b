// What sim::SimOptions offers (issue 39): only what users set. The switches tests turn off
// (the bridge and its parts, DOP853's dense check, the rows' checks, a fault put into the
// right-hand side) are sim::TestHooks' (sim/test_hooks.h, which no front end may include:
// tests/layers/check_layers.py), and the integrator is one rt::Integrator, not an enum and
// a bool. If this fails to compile, a test hook or the second integrator switch is back in
// the public options.
#include <gtest/gtest.h>

#include <type_traits>

#include "sim/simulate.h"
#include "sim/test_hooks.h"

namespace kanesim::sim {
namespace {

template <typename T>
concept HasTestSwitch = requires(T o) { o.bridge; } || requires(T o) { o.bridge_several_loops; } ||
                        requires(T o) { o.bridge_several_at_once; } ||
                        requires(T o) { o.bridge_several_at_once_multiplier; } ||
                        requires(T o) { o.bridge_projected_estimate; } || requires(T o) { o.dense_check; } ||
                        requires(T o) { o.row_energy_check; } || requires(T o) { o.zone_rows; } ||
                        requires(T o) { o.hold_zone_rows; } || requires(T o) { o.rhs_fault; };
template <typename T>
concept HasSecondIntegratorSwitch = requires(T o) { o.cvode_bdf; };

static_assert(!HasTestSwitch<SimOptions>, "a tests-only switch in the public SimOptions");
static_assert(HasTestSwitch<TestHooks>, "the concept must see the hooks where they are");
static_assert(!HasSecondIntegratorSwitch<SimOptions>, "the integrator is one rt::Integrator");
static_assert(std::is_same_v<decltype(SimOptions::integrator), rt::Integrator>);
static_assert(std::is_same_v<decltype(IntegratorOptions::method), rt::Integrator>);

// The defaults of TestHooks are the run users get: every part on, no fault.
TEST(SimOptions, TestHooksDefaultToTheUsersRun) {
  const TestHooks h;
  EXPECT_TRUE(h.bridge && h.dense_check && h.row_energy_check && h.zone_rows && h.hold_zone_rows);
  EXPECT_TRUE(h.bridge_switches.several_loops && h.bridge_switches.several_at_once &&
              h.bridge_switches.projected_estimate);
  EXPECT_FALSE(h.bridge_switches.several_at_once_multiplier);
  EXPECT_FALSE(h.rhs_fault);
}

}  // namespace
}  // namespace kanesim::sim
