// The variables an exported FMU shows its master (docs/fmi.md): one table, computed from the
// loaded model, that both `kanesim export` (modelDescription.xml) and the FMU's own library
// (the value references at run time) read, so the two cannot disagree.
//
// Order, which is the value reference (vr = index in the table):
//   the continuous states y = [q_free; u_free] (rt::InitialState's layout), named by their
//   joint signals ("arm.q", "ball.q[2]"); their derivatives "der(arm.q)"; the model's
//   inputs (`input Real tau;`, start 0); the declared outputs; then the parameters: tunable ones (Real leaves, not structural, not constant),
//   calculated ones (bound to an expression of others), and the fixed ones (structural,
//   constant, Integer or Boolean), which keep the value they had at export; last the event
//   indicators "eventIndicator[k]" (sim::HybridOde's, Model Exchange's; FMI 3 names them in
//   ModelStructure).
#pragma once

#include <string>
#include <vector>

#include "pipeline/pipeline.h"

namespace kanesim::fmi {

enum class VarKind { State, Derivative, Input, Output, Parameter, CalculatedParameter, Fixed, Indicator };
enum class VarType { Real, Integer, Boolean };

struct Variable {
  std::string name;
  VarKind kind = VarKind::State;
  VarType type = VarType::Real;
  int index = 0;        // State, Derivative: y index; Input: rt input; Output: declared output;
                        // Indicator: event function; else param
  double start = 0.0;   // States, Parameter, Fixed: the value at export
  std::string unit;     // "" when the model gives none
  std::string description;
  // State: its start is computed at initialization (initial="calculated", an initial
  // unknown): from the tunable parameters (table indices) start_params (a start expression,
  // a rotation's normalization, a closed loop's assembly), or by the assembly of a model
  // with constraints, which owns every start there. Else initial="exact", the start the
  // description gives or the master's.
  bool start_calculated = false;
  std::vector<int> start_params;
};

// The variable is an initial unknown of ModelStructure: a derivative, an output, a
// calculated parameter, a state whose start is calculated.
bool InitialUnknown(const Variable& v);

// The table for a loaded, compiled model (model.program set).
std::vector<Variable> ListVariables(const pipeline::Model& model);

// The parameter values a program is rebound with: `params` (one per mech param), those bound
// to others (calculated parameters the master did not set) evaluated from them.
std::vector<double> BoundValues(const flat::Mechanism& mech, const std::vector<double>& params);

// The names of the continuous states, y index order.
std::vector<std::string> StateNames(const rt::Program& program);

// A model name as a C identifier (the FMU's modelIdentifier and binary's name).
std::string Identifier(const std::string& model_name);

}  // namespace kanesim::fmi
