// Helpers of the compile tests: a model's text compiled through the whole front end, its
// messages by code, and a run into memory with one of the five integrators.
#pragma once

#include <gtest/gtest.h>

#include <cstdio>
#include <string>
#include <vector>

#include "tests/support/load_util.h"
#include "compiler/compiler.h"

namespace kanesim::test {

// The five integrators a run can take (DOP853, CVODE Adams, CVODE BDF, ARKODE, IDA).
struct IntegratorChoice {
  const char* name;
  rt::Integrator kind;
};
inline const std::vector<IntegratorChoice>& AllIntegrators() {
  static const std::vector<IntegratorChoice> all = {{"DOP853", rt::Integrator::Dop853},
                                                    {"CVODE", rt::Integrator::CvodeAdams},
                                                    {"CVODE-BDF", rt::Integrator::CvodeBdf},
                                                    {"ARKODE", rt::Integrator::ArkodeErk},
                                                    {"IDA", rt::Integrator::IDA}};
  return all;
}

// A run of `p` from 0 to `stop` every `interval` with one integrator; *status its outcome.
inline sim::MemorySink RunWith(const rt::Program& p, const IntegratorChoice& how, double stop, double interval,
                               std::vector<std::string> signals, sim::SimResult* result, double tol = 1e-10) {
  sim::SimOptions o;
  o.stop_time = stop;
  o.interval = interval;
  o.rtol = o.atol = tol;
  o.integrator = how.kind;
  o.signals = std::move(signals);
  sim::MemorySink sink;
  *result = sim::Simulate(p, o, sink);
  return sink;
}

// x in a model text, every digit kept (%.17g).
inline std::string Num(double x) {
  char b[40];
  std::snprintf(b, sizeof b, "%.17g", x);
  return b;
}

// "K310: message\n" for every compile message, for failure output.
inline std::string Messages(const std::vector<rt::CompileMessage>& ms) {
  std::string s;
  for (const auto& e : ms) s += std::string(flat::DiagCodeString(e.code)) + ": " + e.message + "\n";
  return s;
}

// The first message with `code` whose text has `text`, or null.
inline const rt::CompileMessage* Find(const std::vector<rt::CompileMessage>& ms, const std::string& code,
                                      const std::string& text) {
  for (const auto& e : ms)
    if (flat::DiagCodeString(e.code) == code && e.message.find(text) != std::string::npos) return &e;
  return nullptr;
}

// The summary of a compiled model.
inline rt::ProgramSummary SummaryOf(const Loaded& l) { return rt::Summarize(*l.prog); }

// The geared pair of the loop tests: rods on j1 at the origin and j2 two metres along x,
// coupled q2 = -q1 / 2 (JointCoupling); `j1_mods`, `j2_mods` go into the joints' modifiers,
// `equations` after the connections, `g` is the gravity vector's text.
inline std::string GearedPair(const std::string& name, const std::string& g, const std::string& j1_mods,
                              const std::string& j2_mods, const std::string& equations = "") {
  return "model " + name + "\n  World world(g = " + g + ");\n  Revolute j1(axis = {0, 0, 1}" + j1_mods +
         ");\n  Rod r1(L = 1, m = 1);\n  FixedTranslation base(r = {2, 0, 0});\n  Revolute j2(axis = {0, 0, 1}" +
         j2_mods +
         ");\n  Rod r2(L = 0.5, m = 2);\n  JointCoupling gear(ratio = -0.5);\nequation\n"
         "  connect(world.frame_b, j1.frame_a);\n  connect(j1.frame_b, r1.frame_a);\n"
         "  connect(world.frame_b, base.frame_a);\n  connect(base.frame_b, j2.frame_a);\n"
         "  connect(j2.frame_b, r2.frame_a);\n  connect(j1.drive, gear.flange_a);\n"
         "  connect(j2.drive, gear.flange_b);\n" +
         equations + "end " + name + ";\n";
}

}  // namespace kanesim::test
