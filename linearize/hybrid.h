// The operating point's hybrid state (docs/linearize.md "End stops, contacts and friction"):
// end stops and plane contacts resting there, and exact-friction joints stuck there, hold as
// constraint rows (their coordinates and speeds leave the states); joints sliding with exact
// friction keep their direction's law. Any other hybrid state at the point (an impact, a
// contact about to leave, a joint about to slip, a rolling contact that pulls) has no linear
// model and is refused: the regularized friction law is never used for an exact joint.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "linearize/linearize.h"
#include "linearize/reduction.h"
#include "sim/end_stops.h"
#include "sim/stick_slip.h"

namespace kanesim::lin {

class Hybrid {
 public:
  // |gap| and |speed| within this of zero (times the gap's scale) count as on the contact / at rest.
  static constexpr double kTol = 1e-8;

  // Whether p has end stops, plane contacts or exact friction (laws with events).
  static bool Present(const rt::Program& p);
  // Decides the laws at op. Status 1 for a point past a stop or below a plane, 2 for a point
  // with no smooth motion about it.
  // w0: the model's inputs' values (rt::InputName order; empty: none).
  Status Init(const rt::Program& p, const OperatingPoint& op, const std::vector<double>& w0 = {});
  // The constraint rows that hold at op, and their names ("j1 on q_min", "j2 stuck").
  const std::vector<HeldRow>& held() const { return held_; }
  const std::vector<std::string>& held_names() const { return names_; }
  // ydot at (t, y) with the laws decided at op (the held rows' reactions, the sliding joints'
  // directions), the held rows' reactions left in ws for rt::EvalSignals (the outputs of the
  // held motion: rt::SetHeldLoads). 0, or rt::Derivative's codes.
  int Derivative(rt::Workspace& ws, double t, const double* y, double* ydot);

 private:
  const rt::Program* p_ = nullptr;
  std::unique_ptr<sim::EndStopEvents> stops_;
  std::unique_ptr<sim::StickSlipEvents> stick_;
  std::vector<HeldRow> held_;
  std::vector<std::string> names_;
};

}  // namespace kanesim::lin
