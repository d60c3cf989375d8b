#include "fmi/variables.h"

#include <algorithm>
#include <cctype>
#include <cmath>

#include "lang/lang.h"
#include "runtime/program/program.h"
#include "sim/hybrid_ode.h"

namespace kanesim::fmi {
namespace {

// "[k]" (1-based) after a joint's signal when it has several coordinates, as the signals do.
std::string Suffix(int k, int n) { return n > 1 ? "[" + std::to_string(k + 1) + "]" : ""; }

// Coordinate or speed k of joint j in the units the unit check gives it (lang/units.h:
// "rad", "m", "1" for a quaternion's component; "rad/s", "m/s").
std::string JointUnit(const rt::TreeJoint& j, int k, bool speed) {
  const bool quaternion = j.rotation == flat::RotationCoords::Quaternion && j.nq == j.nu + 1;
  return lang::JointCoordinateUnit(flat::JointTypeName(j.type), quaternion, k, speed);
}

// The unit of a rate of a quantity in `unit` ("rad" -> "rad/s"); "" when it has none.
std::string PerSecond(const std::string& unit) {
  lang::Unit u, s;
  std::string error;
  if (unit.empty() || !lang::ParseUnit(unit, &u, &error) || !lang::ParseUnit("s", &s, &error)) return "";
  const lang::Unit rate = u / s;
  return rate.scale == 1 ? rate.ToString() : "";
}

struct StateInfo {
  std::string name, unit, der_unit;
};

std::vector<StateInfo> States(const rt::Program& p) {
  std::vector<StateInfo> out(p.nq + p.nu);
  for (const rt::TreeJoint& j : p.joints) {
    for (int k = 0; k < j.nq; ++k)
      for (int i = 0; i < p.nq; ++i)
        if (p.q_free[i] == j.q0 + k) {
          const std::string unit = JointUnit(j, k, false);
          out[i] = {j.name + ".q" + Suffix(k, j.nq), unit, PerSecond(unit)};
        }
    for (int k = 0; k < j.nu; ++k)
      for (int i = 0; i < p.nu; ++i)
        if (p.u_free[i] == j.u0 + k) {
          const std::string unit = JointUnit(j, k, true);
          out[p.nq + i] = {j.name + ".u" + Suffix(k, j.nu), unit, PerSecond(unit)};
        }
  }
  return out;
}

// Variable::start_params of vars' states: each tunable parameter moved (1e-4 relative) and the
// program rebound, as the FMU rebinds for the master's values; a start that moves depends on
// it. One compile per tunable parameter, at export and at instantiation.
void FindStartParameters(const pipeline::Model& model, std::vector<Variable>* vars) {
  const rt::Program& p = *model.program;
  std::vector<Variable*> states;
  for (Variable& v : *vars)
    if (v.kind == VarKind::State) states.push_back(&v);
  if (states.empty()) return;
  const auto starts = [&](double dp, int param, std::vector<double>* y0) {
    std::vector<double> pv = p.param_values;
    pv[size_t(param)] += dp;
    rt::CompileResult r = rt::Rebind(p, BoundValues(*model.mech, pv));
    if (!r.program) return false;
    y0->assign(states.size(), 0.0);
    rt::InitialState(*r.program, y0->data());
    return true;
  };
  for (size_t k = 0; k < vars->size(); ++k) {
    const Variable& param = (*vars)[k];
    if (param.kind != VarKind::Parameter) continue;
    const double dp = 1e-4 * std::max(1.0, std::abs(param.start));
    std::vector<double> y1;
    if (!starts(dp, param.index, &y1) && !starts(-dp, param.index, &y1)) {
      // Not movable alone (an entry of a rotation matrix or of an inertia, which must stay
      // orthonormal or symmetric): with constraints, the assembly may follow it.
      if (!p.rows.empty())
        for (Variable* v : states) v->start_params.push_back(int(k));
      continue;
    }
    for (size_t i = 0; i < states.size(); ++i)
      if (std::abs(y1[i] - states[i]->start) > 1e-12 * (1.0 + std::abs(states[i]->start)))
        states[i]->start_params.push_back(int(k));
  }
  // With constraints the assembly computes the start from all of them together: a value the
  // master set for one state would not be assembled with the others.
  for (Variable* v : states) v->start_calculated = !p.rows.empty() || !v->start_params.empty();
}

}  // namespace

bool InitialUnknown(const Variable& v) {
  return v.kind == VarKind::Derivative || v.kind == VarKind::Output || v.kind == VarKind::CalculatedParameter ||
         (v.kind == VarKind::State && v.start_calculated);
}

std::vector<double> BoundValues(const flat::Mechanism& mech, const std::vector<double>& params) {
  std::vector<double> pv(params.size());
  for (size_t i = 0; i < pv.size(); ++i) {
    const flat::Param& p = mech.params[i];
    pv[i] = (p.binding == flat::kNoExpr || p.user_set) ? params[i] : flat::EvalParamExpr(mech, pv, p.binding);
  }
  return pv;
}

std::vector<std::string> StateNames(const rt::Program& program) {
  std::vector<std::string> names;
  for (const StateInfo& s : States(program)) names.push_back(s.name);
  return names;
}

std::vector<Variable> ListVariables(const pipeline::Model& model) {
  const rt::Program& p = *model.program;
  const flat::Mechanism& mech = *model.mech;
  std::vector<Variable> vars;
  const std::vector<StateInfo> states = States(p);
  std::vector<double> y0(states.size());
  rt::InitialState(p, y0.data());
  for (size_t i = 0; i < states.size(); ++i)
    vars.push_back({states[i].name, VarKind::State, VarType::Real, int(i), y0[i], states[i].unit, "", false, {}});
  for (size_t i = 0; i < states.size(); ++i)
    vars.push_back({"der(" + states[i].name + ")", VarKind::Derivative, VarType::Real, int(i), 0.0,
                    states[i].der_unit, "", false, {}});
  for (int i = 0; i < rt::NumInputs(p); ++i)
    vars.push_back({rt::InputName(p, i), VarKind::Input, VarType::Real, i, 0.0, mech.inputs[size_t(i)].unit, "", false, {}});
  for (size_t i = 0; i < mech.outputs.size(); ++i)
    vars.push_back({mech.outputs[i].name, VarKind::Output, VarType::Real, int(i), 0.0, mech.outputs[i].unit, "", false, {}});
  // Parameters: three passes so that each group is contiguous.
  for (int pass = 0; pass < 3; ++pass)
    for (size_t i = 0; i < mech.params.size(); ++i) {
      const flat::Param& q = mech.params[i];
      if (q.type == flat::ParamType::String) continue;  // not a number: nothing to show
      const bool fixed = q.structural || q.is_constant || q.type != flat::ParamType::Real;
      const bool bound = q.binding != flat::kNoExpr && !q.user_set;
      const VarKind kind = fixed ? VarKind::Fixed : bound ? VarKind::CalculatedParameter : VarKind::Parameter;
      if ((pass == 0 && kind != VarKind::Parameter) || (pass == 1 && kind != VarKind::CalculatedParameter) ||
          (pass == 2 && kind != VarKind::Fixed))
        continue;
      const VarType type = q.type == flat::ParamType::Integer   ? VarType::Integer
                           : q.type == flat::ParamType::Boolean ? VarType::Boolean
                                                                : VarType::Real;
      std::string why = q.structural    ? "structural: fixed at export"
                        : q.is_constant ? "constant"
                        : fixed         ? "fixed at export"
                                        : "";
      vars.push_back({std::string(mech.ParamName(i)), kind, type, int(i), p.param_values[i], q.unit, why, false, {}});
    }
  FindStartParameters(model, &vars);
  const std::vector<std::string> events = sim::HybridOde(model.program, 1e-6, 1e-6).IndicatorNames();
  for (size_t i = 0; i < events.size(); ++i)
    vars.push_back({"eventIndicator[" + std::to_string(i + 1) + "]", VarKind::Indicator, VarType::Real, int(i), 0.0, "",
                    events[i] + " (an event where it crosses zero downwards)", false, {}});
  return vars;
}

std::string Identifier(const std::string& model_name) {
  std::string id;
  for (char c : model_name) id += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
  if (id.empty() || std::isdigit(static_cast<unsigned char>(id[0]))) id = "m_" + id;
  return id;
}

}  // namespace kanesim::fmi
