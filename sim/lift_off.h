// Rolling contacts that would pull (docs/stdlib.md "Contacts"): a RollingDisk, RollingSphere
// or KnifeEdge is a bilateral constraint, so its normal force can turn tensile, which no
// plane can exert. Each contact's normal force is an event function; where one crosses zero
// the run stops (exit 2) at that time with the cause, the rows before it kept, instead of
// writing a motion held to the plane by a pull.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "runtime/runtime.h"

namespace kanesim::sim {

class LiftOffGuard {
 public:
  explicit LiftOffGuard(const rt::Program& program);
  bool Active() const { return !names_.empty(); }
  int Count() const { return static_cast<int>(names_.size()); }
  const std::vector<std::string>& Names() const { return names_; }  // the guarded contacts
  // The model's inputs as the guard's own workspace sees them (not owned; null: constants 0).
  void SetInputs(const rt::InputSource* inputs) {
    if (ws_) rt::SetInputSource(*ws_, inputs);
  }
  // g_i: contact i's normal force (the plane pushing: > 0). 0, or EvalSignals' codes.
  int Functions(double t, const double* y, double* g);
  // Why the run cannot go on at (t, y) ("" when it can): a contact whose normal force is
  // negative at the start, or contact i's (i >= 0) crossing zero.
  std::string Cause(double t, const double* y, int i);

 private:
  const rt::Program& program_;
  std::vector<std::string> names_;  // the guarded contacts
  std::shared_ptr<const rt::SignalPlan> plan_;
  std::unique_ptr<rt::Workspace, void (*)(rt::Workspace*)> ws_{nullptr, [](rt::Workspace*) {}};
  std::vector<double> g_;  // scratch
};

}  // namespace kanesim::sim
