// Operating points: the start values, the motion at a time, a parameter moved.
#include <fmt/core.h>

#include <algorithm>

#include "linearize/linearize.h"
#include "runtime/program/program.h"
#include "sim/simulate.h"
#include "compiler/compiler.h"

namespace kanesim::lin {

OperatingPoint StartPoint(const rt::Program& program) {
  OperatingPoint op;
  op.t = rt::StartTime(program);
  op.y.assign(static_cast<size_t>(rt::StateSize(program)), 0.0);
  rt::InitialState(program, op.y.data());
  return op;
}

Status PointAtTime(const rt::Program& p, double t, OperatingPoint* out, const rt::InputSource* inputs) {
  *out = StartPoint(p);
  if (t == out->t) return {};
  if (!(t > out->t)) return {1, fmt::format("--at {}: before the start time {}", t, out->t)};
  // Every free coordinate and speed as a signal (signals.cpp names: "j.q", "j.q[k]").
  std::vector<std::string> names;
  for (int pass = 0; pass < 2; ++pass) {
    const std::vector<int>& idx = pass == 0 ? p.q_free : p.u_free;
    for (int full : idx) {
      for (const rt::TreeJoint& j : p.joints) {
        const int first = pass == 0 ? j.q0 : j.u0, count = pass == 0 ? j.nq : j.nu;
        if (full < first || full >= first + count) continue;
        names.push_back(j.name + (pass == 0 ? ".q" : ".u") + (count > 1 ? rt::Index1(full - first) : ""));
      }
    }
  }
  sim::SimOptions so;
  so.stop_time = t;
  so.interval = t - out->t;
  so.rtol = so.atol = 1e-10;
  so.signals = names;
  so.inputs = inputs;
  sim::MemorySink sink;
  const sim::SimResult r = sim::Simulate(p, so, sink);
  if (r.status != sim::SimResult::Status::kOk || sink.rows.empty())
    return {2, fmt::format("the motion to t = {} fails: {}", t, r.message)};
  out->t = sink.times.back();
  out->y = sink.rows.back();
  auto ws = rt::MakeWorkspace(p);
  rt::SetInputSource(*ws, inputs);
  if (rt::ProjectOntoConstraints(p, *ws, out->t, out->y.data()) != 0)
    return {2, fmt::format("the state at t = {} cannot be projected onto the constraints: {}", t,
                           rt::ErrorMessage(*ws))};
  return {};
}

Status RebindParameter(const rt::Program& program, const std::string& name, double value,
                       std::shared_ptr<const rt::Program>* out) {
  const flat::Mechanism& mech = *program.mech;
  int index = -1;
  for (size_t i = 0; i < mech.params.size(); ++i)
    if (mech.ParamName(i) == name) index = static_cast<int>(i);
  if (index < 0) return {1, fmt::format("'{}' is not a parameter of the model", name)};
  const flat::Param& pp = mech.params[static_cast<size_t>(index)];
  if (pp.type != flat::ParamType::Real || pp.structural || pp.is_constant)
    return {1, fmt::format("'{}' is not a real, non-structural, non-constant parameter", name)};
  // Bound parameters follow, in declaration order (flat::EvaluateParams' rule).
  std::vector<double> pv(mech.params.size(), 0.0);
  for (size_t i = 0; i < mech.params.size(); ++i) {
    const flat::Param& q = mech.params[i];
    if (static_cast<int>(i) == index)
      pv[i] = value;
    else if (q.binding == flat::kNoExpr || q.user_set)
      pv[i] = program.param_values[i];
    else
      pv[i] = flat::EvalParamExpr(mech, pv, q.binding);
  }
  rt::CompileResult cr = rt::Rebind(program, pv);
  if (!cr.program)
    return {1, fmt::format("the model cannot be rebound with {} = {}: {}", name, value,
                           cr.errors.empty() ? std::string("?") : cr.errors.front().message)};
  *out = cr.program;
  return {};
}

}  // namespace kanesim::lin
