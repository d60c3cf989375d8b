// The stepping core (sim/simulator.h) and the model's inputs (sim/input_table.h) on a
// pendulum driven through `input Real tau;`. If these fail, stepping does not continue one
// integration (it differs from a whole run), a saved state does not continue bit for bit, a
// table's interpolation is wrong, or an input does not reach the torque.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "sim/input_table.h"
#include "sim/simulator.h"
#include "tests/support/load_util.h"
#include "tests/support/model_texts.h"

namespace kanesim::sim {
namespace {

// A rod on a revolute joint; `torque` is the joint's force law.
std::string Pendulum(const std::string& decls, const std::string& torque) {
  return test::PendulumText{.decls = decls, .name = "j", .mods = ", q(start = 0.5), u(start = 0)",
                            .equations = "  j.tau = " + torque + ";\n"}
      .Text();
}

std::shared_ptr<const rt::Program> Load(const std::string& text) {
  auto l = test::LoadModel(text, {}, {}, /*is_text=*/true);
  if (!l || !l->prog) return nullptr;
  return l->prog;
}

const rt::Integrator kAll[] = {rt::Integrator::Dop853, rt::Integrator::CvodeAdams, rt::Integrator::CvodeBdf,
                               rt::Integrator::IDA, rt::Integrator::ArkodeErk};

std::unique_ptr<Simulator> Make(const std::shared_ptr<const rt::Program>& p, rt::Integrator m, double tol) {
  SimulatorOptions o;
  o.integrator = m;
  o.rtol = o.atol = tol;
  o.signals = {"j.q", "j.u"};
  std::string error;
  auto s = Simulator::Make(p, o, &error);
  EXPECT_TRUE(s) << error;
  return s;
}

// If this fails, the model's input is not one (not listed, or the torque does not read it).
TEST(Inputs, ElaboratedInDeclarationOrder) {
  auto p = Load(Pendulum("  input Real f[2];\n  input Real tau;\n", "tau + f[2] - f[1]"));
  ASSERT_TRUE(p);
  ASSERT_EQ(rt::NumInputs(*p), 3);
  EXPECT_EQ(rt::InputName(*p, 0), "f[1]");
  EXPECT_EQ(rt::InputName(*p, 1), "f[2]");
  EXPECT_EQ(rt::InputName(*p, 2), "tau");
}

// If this fails, stepping restarts the integrator per step or loses time: 1 ms steps (2000 of
// them) against one run of the same model with the same constant input, both at 1e-10.
TEST(Simulator, MillisecondStepsEqualAWholeRun) {
  auto p = Load(Pendulum("  input Real tau;\n", "tau"));
  ASSERT_TRUE(p);
  for (rt::Integrator m : kAll) {
    ConstantInputs c(1);
    c.values[0] = 0.7;
    SimOptions o;
    o.stop_time = 2.0;
    o.interval = 0.5;
    o.rtol = o.atol = 1e-10;
    o.integrator = m;
    o.signals = {"j.q", "j.u"};
    o.inputs = &c;
    MemorySink whole;
    ASSERT_EQ(Simulate(*p, o, whole).status, SimResult::Status::kOk);
    auto s = Make(p, m, 1e-10);
    std::string error;
    ASSERT_TRUE(s->SetInput(0, 0.7, &error));
    for (int k = 1; k <= 2000; ++k) ASSERT_TRUE(s->AdvanceTo(k * 1e-3).ok) << MethodName(m);
    std::vector<double> out(2);
    ASSERT_TRUE(s->Outputs(out.data(), &error)) << error;
    EXPECT_EQ(s->Time(), 2.0);
    // Both runs are within ~1e-9 of the exact motion (tolerance 1e-10, 2 s).
    EXPECT_NEAR(out[0], whole.rows.back()[0], 1e-7) << MethodName(m);
    EXPECT_NEAR(out[1], whole.rows.back()[1], 1e-7) << MethodName(m);
    // One integration across the steps, not one per step: a restart per step would cost at
    // least one step per millisecond, and DOP853's f evaluations here are ~12 per step.
    if (m == rt::Integrator::Dop853) {
      EXPECT_LE(s->Stats().rhs_evals, 2000 * 13 + 100);
    }
  }
}

// If this fails, a saved state does not continue bit for bit: the inputs change every step
// (a controller), the state is saved at 0.5 s, the run goes on to 1 s, the state is put back
// and the same steps are taken again.
TEST(Simulator, GetSetStateContinuesBitForBit) {
  auto p = Load(Pendulum("  input Real tau;\n", "tau"));
  ASSERT_TRUE(p);
  for (rt::Integrator m : kAll) {
    auto s = Make(p, m, 1e-8);
    std::string error;
    auto run_to = [&](int from, int to) {
      for (int k = from + 1; k <= to; ++k) {
        ASSERT_TRUE(s->SetInput(0, -2.0 * s->State()[0] - 0.5 * s->State()[1], &error));
        ASSERT_TRUE(s->AdvanceTo(k * 1e-3).ok);
      }
    };
    run_to(0, 500);
    const SimulatorState saved = s->GetState();
    run_to(500, 1000);
    const std::vector<double> first = s->State();
    ASSERT_TRUE(s->SetState(saved, &error)) << error;
    EXPECT_EQ(s->Time(), 0.5);
    run_to(500, 1000);
    EXPECT_EQ(s->State(), first) << MethodName(m);
    // Reset: the start again, and the same motion as the first time.
    s->Reset();
    EXPECT_EQ(s->Time(), 0.0);
    EXPECT_EQ(s->Inputs()[0], 0.0);
    run_to(0, 500);
    const SimulatorState again = s->GetState();
    EXPECT_EQ(again.y, saved.y) << MethodName(m);
  }
}

// If this fails, a bad step is taken instead of refused.
TEST(Simulator, RefusesBackwardsStepsAndNonFiniteInputs) {
  auto p = Load(Pendulum("  input Real tau;\n", "tau"));
  ASSERT_TRUE(p);
  auto s = Make(p, rt::Integrator::Dop853, 1e-8);
  std::string error;
  ASSERT_TRUE(s->AdvanceTo(0.1).ok);
  EXPECT_FALSE(s->AdvanceTo(0.05).ok);
  EXPECT_FALSE(s->AdvanceTo(NAN).ok);
  EXPECT_FALSE(s->SetInput(0, NAN, &error));
  EXPECT_FALSE(s->SetInput(3, 1.0, &error));
  EXPECT_EQ(s->Time(), 0.1);
  ASSERT_TRUE(s->Step(0.1).ok);
  EXPECT_NEAR(s->Time(), 0.2, 1e-15);
}

// If this fails, a sampled controller stepped from outside differs from the same law written
// in the model by more than its sampling explains: a PD at 1 kHz against the continuous PD,
// the difference O(dt) (halved at 2 kHz).
TEST(Simulator, SteppedPdMatchesThePdInTheModel) {
  const double kp = 20.0, kd = 4.0, ref = -0.3;
  auto mech = Load(Pendulum("", "-20 * (j.q + 0.3) - 4 * j.u"));
  auto stepped = Load(Pendulum("  input Real tau;\n", "tau"));
  ASSERT_TRUE(mech && stepped);
  auto whole = Make(mech, rt::Integrator::Dop853, 1e-10);
  ASSERT_TRUE(whole->AdvanceTo(3.0).ok);
  double err[2];
  for (int r = 0; r < 2; ++r) {
    const int per_second = 1000 * (r + 1);
    auto s = Make(stepped, rt::Integrator::Dop853, 1e-10);
    std::string error;
    for (int k = 1; k <= 3 * per_second; ++k) {
      const double q = s->State()[0], u = s->State()[1];
      ASSERT_TRUE(s->SetInput(0, -kp * (q - ref) - kd * u, &error));
      ASSERT_TRUE(s->AdvanceTo(static_cast<double>(k) / per_second).ok);
    }
    err[r] = std::abs(s->State()[0] - whole->State()[0]) + std::abs(s->State()[1] - whole->State()[1]);
  }
  EXPECT_LT(err[0], 5e-3);                 // a sampling delay of 1 ms on a motion of ~1 rad/s
  EXPECT_NEAR(err[1] / err[0], 0.5, 0.1);  // first order in the sampling period
}

void WriteFile(const std::string& path, const std::string& text) { std::ofstream(path, std::ios::binary) << text; }

// If this fails, a table's values between and at its rows are not the documented
// interpolation (sim/input_table.h).
TEST(InputTable, LinearAndHold) {
  const std::string path = std::string(KANESIM_WORK_DIR) + "/input_table_test.csv";
  WriteFile(path, "# a comment\n# interpolation = linear\ntime,a,b:hold\n0,1,10\n1,3,20\n3,-1,30\n");
  InputTable t({"a", "b"});
  std::string error;
  ASSERT_TRUE(t.Read(path, &error)) << error;
  EXPECT_TRUE(t.Missing().empty());
  double u[2], du[2];
  struct Case { double t, a, da, b; };
  for (const Case c : {Case{0, 1, 2, 10}, {0.5, 2, 2, 10}, {1, 3, -2, 20}, {2, 1, -2, 20}, {3, -1, -2, 30}}) {
    ASSERT_EQ(t.Values(c.t, u, du, &error), 0) << error;
    EXPECT_DOUBLE_EQ(u[0], c.a) << c.t;
    EXPECT_DOUBLE_EQ(du[0], c.da) << c.t;
    EXPECT_DOUBLE_EQ(u[1], c.b) << c.t;
    EXPECT_EQ(du[1], 0.0) << c.t;
  }
  EXPECT_NE(t.Values(3.0000001, u, du, &error), 0);  // not extrapolated
  EXPECT_NE(t.Values(-1e-9, u, du, &error), 0);
  EXPECT_NE(error.find("outside its table"), std::string::npos) << error;
  EXPECT_EQ(t.CheckSpan(0, 3), "");
  EXPECT_NE(t.CheckSpan(0, 3.5), "");
}

// If this fails, a malformed table is accepted or its error does not say where.
TEST(InputTable, ErrorsSayWhere) {
  const std::string path = std::string(KANESIM_WORK_DIR) + "/input_table_bad.csv";
  struct Case { const char* text; const char* where; };
  for (const Case c : {Case{"time,a\n0,1\n0,2\n", ":3:1: "}, {"time,zz\n0,1\n", ":1:6: "}, {"time,a\n0,x\n", ":2:3: "},
                       {"t,a\n0,1\n", ":1:1: "}, {"time,a:cubic\n0,1\n", ":1:6: "}, {"time,a\n0,1,2\n", ":2:1: "}}) {
    WriteFile(path, c.text);
    InputTable t({"a"});
    std::string error;
    EXPECT_FALSE(t.Read(path, &error)) << c.text;
    EXPECT_NE(error.find(path + c.where), std::string::npos) << c.text << " -> " << error;
  }
}

}  // namespace
}  // namespace kanesim::sim
