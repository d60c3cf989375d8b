// Helpers of the compile tests: a model's text compiled through the whole front end, its
// messages by code, and a run into memory with one of the five integrators.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "tests/support/load_util.h"
#include "tests/support/model_texts.h"  // Num
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

// The pairs of rows at one time (an event's left and right limits): index of the left row.
inline std::vector<size_t> EventRows(const sim::MemorySink& s) {
  std::vector<size_t> at;
  for (size_t i = 0; i + 1 < s.times.size(); ++i)
    if (s.times[i] == s.times[i + 1]) at.push_back(i);
  return at;
}

// The times of the events of element `who` whose kind starts with `kind`.
inline std::vector<double> EventTimes(const sim::SimResult& r, const std::string& who, const std::string& kind) {
  std::vector<double> t;
  for (const sim::EventRecord& e : r.stats.events)
    if (e.element == who && e.kind.rfind(kind, 0) == 0) t.push_back(e.time);
  return t;
}

// "time element kind" a line per event, for failure output.
inline std::string EventLog(const sim::SimResult& r) {
  std::string log;
  for (const sim::EventRecord& e : r.stats.events) log += Num(e.time) + " " + e.element + " " + e.kind + "\n";
  return log;
}

// Variable `name` before or after event `e` (its record's changes; unchanged: `fallback`).
inline double ChangeOf(const sim::EventRecord& e, const std::string& name, bool after, double fallback = NAN) {
  for (const sim::EventChange& c : e.changes)
    if (c.name == name) return after ? c.after : c.before;
  return fallback;
}

// The state's speed `name` before or after the run's first event, from its record's changes
// (the state itself, not an output row's speeds solved again from the independent ones); a
// failure when the event did not change it.
inline double StateSpeed(const sim::SimResult& r, const std::string& name, bool after) {
  for (const sim::EventChange& c : r.stats.events.at(0).changes)
    if (c.name == name) return after ? c.after : c.before;
  ADD_FAILURE() << name << " did not change";
  return NAN;
}

// The root of f in [a, b] (f(a), f(b) of opposite signs), by bisection to the last bit.
template <class F>
double Bisect(F f, double a, double b) {
  const bool up = f(a) < 0.0;
  for (int k = 0; k < 200 && b - a > 0.0; ++k) {
    const double m = 0.5 * (a + b);
    if (m == a || m == b) break;
    ((f(m) < 0.0) == up ? a : b) = m;
  }
  return 0.5 * (a + b);
}

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
