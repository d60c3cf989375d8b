// Rolling contacts that would pull (sim/lift_off.h).
#include "sim/lift_off.h"

#include <algorithm>
#include <cstdio>

#include "runtime/program/program.h"  // Program::contacts

namespace kanesim::sim {

LiftOffGuard::LiftOffGuard(const rt::Program& program) : program_(program) {
  // Each contact's normal force by name (not every signal named to find them: a start's cost).
  std::vector<std::string> forces;
  const std::string suffix = ".normal_force";
  for (const auto& c : program.contacts) forces.push_back(c.name + suffix);
  if (forces.empty()) return;
  // A normal force the equations do not determine (a row redundant with a joint) says
  // nothing about pulling: not guarded.
  const std::vector<std::string> free = rt::IndeterminateSignals(program, forces);
  std::vector<std::string> guarded;
  for (const std::string& f : forces)
    if (std::find(free.begin(), free.end(), f) == free.end()) guarded.push_back(f);
  if (guarded.empty()) return;
  std::string error;
  plan_ = rt::PlanSignals(program, guarded, &error);
  if (!plan_) return;
  for (const std::string& f : guarded) names_.push_back(f.substr(0, f.size() - suffix.size()));
  ws_ = rt::MakeWorkspace(program);
  g_.resize(names_.size());
}

int LiftOffGuard::Functions(double t, const double* y, double* g) {
  return rt::EvalSignals(program_, *plan_, *ws_, t, y, g);
}

std::string LiftOffGuard::Cause(double t, const double* y, int i) {
  if (i < 0) {
    if (Functions(t, y, g_.data()) != 0) return "the contacts' normal forces cannot be evaluated at the start";
    for (size_t k = 0; k < g_.size(); ++k)
      if (g_[k] < 0.0) i = static_cast<int>(k);
    if (i < 0) return "";
  }
  char buf[300];
  std::snprintf(buf, sizeof buf,
                "contact '%s': its normal force turns tensile (the plane would have to pull the body onto it); "
                "a rolling contact cannot lift off (docs/stdlib.md \"Contacts\")",
                names_[static_cast<size_t>(i)].c_str());
  return buf;
}

}  // namespace kanesim::sim
