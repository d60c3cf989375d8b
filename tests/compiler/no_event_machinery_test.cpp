// A model without events engages none of the event machinery (issue 41: "skip all event
// machinery, at no cost, in a model that has none"): no event function, no root finding,
// and a run takes exactly the steps and right-hand sides of its bare equations of motion
// integrated without any event code. Counted, not timed (the times of the same runs:
// docs/benchmarks/2026-11-29_no_events_cost.md).
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "runtime/runtime.h"
#include "sim/hybrid_ode.h"
#include "sim/integrator.h"
#include "tests/compiler/compile_test_util.h"

namespace kanesim::test {
namespace {

// The bare equations of motion, y' = rt::Derivative: nothing of the events (no event
// function, no hold, no friction law of a mode).
class BareOde final : public sim::OdeSystem {
 public:
  explicit BareOde(const rt::Program& p) : program_(p), ws_(rt::MakeWorkspace(p)) {}
  int Size() const override { return rt::StateSize(program_); }
  int Rhs(double t, const double* y, double* ydot) override { return rt::Derivative(program_, *ws_, t, y, ydot); }

 private:
  const rt::Program& program_;
  decltype(rt::MakeWorkspace(std::declval<const rt::Program&>())) ws_;
};

// Another system as it is, its event functions' evaluations and its events counted.
class CountingOde final : public sim::OdeSystem {
 public:
  explicit CountingOde(sim::OdeSystem& inner) : inner_(inner) {}
  int Size() const override { return inner_.Size(); }
  int Rhs(double t, const double* y, double* ydot) override { return inner_.Rhs(t, y, ydot); }
  int NumEvents() const override { return inner_.NumEvents(); }
  int EventFunctions(double t, const double* y, double* g) override {
    ++event_function_calls;
    return inner_.EventFunctions(t, y, g);
  }
  int Event(double t, double* y, int i) override {
    ++events;
    return inner_.Event(t, y, i);
  }
  long event_function_calls = 0, events = 0;

 private:
  sim::OdeSystem& inner_;
};

struct BareRun {
  sim::IntegratorStats stats;
  std::vector<std::vector<double>> rows;  // the state at every output instant
};

// `system` from the model's start over the grid by `how`, with the options Simulate gives
// that integrator (sim/simulate.cpp, ResolveMethod).
BareRun IntegrateBare(const rt::Program& p, sim::OdeSystem& system, rt::Integrator how, const sim::OutputGrid& grid,
                  double tol) {
  sim::IntegratorOptions o;
  o.method = how;
  o.rtol = o.atol = tol;
  if (how == rt::Integrator::IDA || how == rt::Integrator::CvodeBdf) o.coupling = rt::StateCouplingGroups(p);
  std::vector<double> y0(static_cast<size_t>(rt::StateSize(p)));
  rt::InitialState(p, y0.data());
  BareRun run;
  const sim::IntegrateResult r = sim::Integrate(system, y0.data(), grid, o, [&](double, const double* y, std::string*) {
    run.rows.emplace_back(y, y + system.Size());
    return 0;
  });
  EXPECT_TRUE(r.ok) << r.cause;
  run.stats = r.stats;
  return run;
}

// If this fails, a model without end stops, plane contacts, exact friction, rolling
// contacts or when clauses pays for the event machinery: the run's system has event
// functions (root finding set up in CVODE, IDA and ARKODE, DOP853's dense output searched),
// one is evaluated, or the run's steps, right-hand sides or rows differ from the bare
// equations of motion's (a step cut, an evaluation added, a state moved by event code).
// Open trees only: a closed loop's run adds its own step checks and projections, which have
// nothing to do with events.
TEST(NoEventMachinery, AModelWithoutEventsRunsAsItsBareEquationsOfMotion) {
  constexpr double kTol = 1e-8;
  for (const char* name : {"double_pendulum", "chain", "spring_mass"}) {
    auto l = LoadModel(kRoot + "/examples/" + name + ".mech");
    ASSERT_TRUE(l && l->prog) << name << (l ? Messages(l->errors) : "");
    const rt::Program& p = *l->prog;
    sim::HybridOde hybrid(l->prog, kTol, kTol);
    EXPECT_EQ(hybrid.NumIndicators(), 0) << name;
    EXPECT_EQ(hybrid.System().NumEvents(), 0) << name;
    const std::vector<std::string> states = rt::StateNames(p);
    for (const IntegratorChoice& how : AllIntegrators()) {
      sim::SimResult r;
      const sim::MemorySink s = RunWith(p, how, 2.0, 0.05, states, &r, kTol);
      ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << name << " " << how.name << ": " << r.message;
      EXPECT_TRUE(r.stats.events.empty()) << name << " " << how.name;
      EXPECT_EQ(r.stats.integrator.event_evals, 0) << name << " " << how.name;
      sim::OutputGrid grid;
      grid.start = s.times.front();
      grid.stop = 2.0;
      grid.interval = 0.05;
      BareOde bare(p);
      const BareRun b = IntegrateBare(p, bare, how.kind, grid, kTol);
      EXPECT_EQ(r.stats.integrator.steps, b.stats.steps) << name << " " << how.name;
      EXPECT_EQ(r.stats.integrator.rhs_evals, b.stats.rhs_evals) << name << " " << how.name;
      EXPECT_EQ(r.stats.integrator.rhs_evals_jac, b.stats.rhs_evals_jac) << name << " " << how.name;
      ASSERT_EQ(s.rows.size(), b.rows.size()) << name << " " << how.name;
      for (size_t i = 0; i < s.rows.size(); ++i) ASSERT_EQ(s.rows[i], b.rows[i]) << name << " " << how.name << " row " << i;
      // The event-capable system a stepping run uses (sim::HybridOde), counted.
      CountingOde counted(hybrid.System());
      const BareRun c = IntegrateBare(p, counted, how.kind, grid, kTol);
      EXPECT_EQ(counted.event_function_calls, 0) << name << " " << how.name;
      EXPECT_EQ(counted.events, 0) << name << " " << how.name;
      EXPECT_EQ(c.stats.steps, b.stats.steps) << name << " " << how.name;
      EXPECT_EQ(c.stats.rhs_evals, b.stats.rhs_evals) << name << " " << how.name;
    }
  }
}

// The counter the test above reads counts: a model with events evaluates its event
// functions in every integrator. If this fails, event_evals is not filled and the test above
// proves nothing.
TEST(NoEventMachinery, AModelWithEventsCountsItsEventFunctions) {
  auto l = LoadModel(kRoot + "/examples/bouncing_ball.mech");
  ASSERT_TRUE(l && l->prog) << (l ? Messages(l->errors) : "");
  for (const IntegratorChoice& how : AllIntegrators()) {
    sim::SimResult r;
    RunWith(*l->prog, how, 1.0, 0.05, {}, &r, 1e-8);
    ASSERT_EQ(r.status, sim::SimResult::Status::kOk) << how.name << ": " << r.message;
    EXPECT_GT(r.stats.integrator.event_evals, r.stats.integrator.steps) << how.name;
  }
}

}  // namespace
}  // namespace kanesim::test
