#include "fmi/instance.h"

#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>

#include "runtime/program/program.h"
#include "sim/sim.h"

namespace kanesim::fmi {
namespace {

// The right-hand side kanesim's integrators see inside a communication step.
class ModelOde final : public sim::OdeSystem {
 public:
  ModelOde(const rt::Program& program, rt::Workspace& ws) : program_(program), ws_(ws) {}
  int Size() const override { return rt::StateSize(program_); }
  int Rhs(double t, const double* y, double* ydot) override { return rt::Derivative(program_, ws_, t, y, ydot); }
  std::string FailureCause() const override { return rt::ErrorMessage(ws_); }

 private:
  const rt::Program& program_;
  rt::Workspace& ws_;
};

std::string Number(double v) {
  std::ostringstream s;
  s.precision(17);
  s << v;
  return s.str();
}

}  // namespace

std::string FormatSettings(const FmuSettings& s) {
  std::string text = "guid " + s.guid + "\nmodel " + s.model + "\n";
  for (const std::string& set : s.sets) text += "set " + set + "\n";
  if (!s.integrator.empty()) text += "integrator " + s.integrator + "\n";
  if (s.rtol > 0) text += "rtol " + Number(s.rtol) + "\n";
  return text;
}

bool ParseSettings(const std::string& text, FmuSettings* out, std::string* error) {
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    const size_t space = line.find(' ');
    const std::string key = line.substr(0, space), value = space == std::string::npos ? "" : line.substr(space + 1);
    if (key == "guid") out->guid = value;
    else if (key == "model") out->model = value;
    else if (key == "set") out->sets.push_back(value);
    else if (key == "integrator") out->integrator = value;
    else if (key == "rtol") out->rtol = std::strtod(value.c_str(), nullptr);
    else {
      *error = "settings.txt: unknown key '" + key + "'";
      return false;
    }
  }
  return true;
}

std::string Instance::Load(const std::string& dir, const std::string& guid) {
  std::ifstream f(dir + "/settings.txt");
  if (!f) return "cannot read " + dir + "/settings.txt (is the resource location right?)";
  std::stringstream text;
  text << f.rdbuf();
  std::string error;
  if (!ParseSettings(text.str(), &settings_, &error)) return error;
  if (settings_.guid != guid) return "the GUID '" + guid + "' is not this FMU's ('" + settings_.guid + "')";
  pipeline::RunSpec spec;
  if (!settings_.integrator.empty() && !pipeline::IntegratorFromName(settings_.integrator, &spec.integrator))
    return "unknown integrator '" + settings_.integrator + "'";
  pipeline::LoadOptions load;
  load.model = settings_.model;
  load.sets = settings_.sets;
  pipeline::LoadResult r = pipeline::LoadModel(pipeline::Source::File(dir + "/model.mech"), load, spec);
  if (!r.model) return "the model does not load:\n" + r.diagnostics;
  model_ = std::move(r.model);
  vars_ = ListVariables(*model_);
  n_ = rt::StateSize(*model_->program);
  return Reset();
}

std::string Instance::Reset() {
  program_ = model_->program;
  params_ = program_->param_values;
  y_.assign(n_, 0.0);
  rt::InitialState(*program_, y_.data());
  ydot_.assign(n_, 0.0);
  state_set_.assign(n_, 0);
  t_ = rt::StartTime(*program_);
  rtol_ = settings_.rtol > 0 ? settings_.rtol : model_->mech->experiment.tolerance;
  params_changed_ = false;
  initialized_ = false;
  return Rebind();
}

std::string Instance::Rebind() {
  if (params_changed_) {
    // Calculated parameters follow the tunable ones they are bound to (as sweeps do).
    const flat::Mechanism& mech = *model_->mech;
    std::vector<double> pv(params_.size());
    for (size_t i = 0; i < pv.size(); ++i) {
      const flat::Param& p = mech.params[i];
      pv[i] = (p.binding == flat::kNoExpr || p.user_set) ? params_[i] : flat::EvalParamExpr(mech, pv, p.binding);
    }
    rt::CompileResult r = rt::Rebind(*model_->program, pv);
    if (!r.program) {
      std::string msg = "the model does not compile with these parameter values";
      for (const rt::CompileMessage& e : r.errors) msg += "; " + e.message;
      return msg;
    }
    program_ = r.program;
    params_ = program_->param_values;
    params_changed_ = false;
  }
  ws_ = rt::MakeWorkspace(*program_);
  std::string error;
  outputs_plan_ = nullptr;
  std::vector<std::string> names;
  for (const flat::Output& o : model_->mech->outputs) names.push_back(o.name);
  if (!names.empty()) {
    outputs_plan_ = rt::PlanSignals(*program_, names, &error);
    if (!outputs_plan_) return "the outputs: " + error;
  }
  out_.assign(names.size(), 0.0);
  stale_ = true;
  return "";
}

std::string Instance::CheckVr(unsigned vr) const {
  return vr < vars_.size() ? "" : "value reference " + std::to_string(vr) + " is not a variable of this FMU";
}

std::string Instance::SetReal(unsigned vr, double value) {
  if (std::string e = CheckVr(vr); !e.empty()) return e;
  const Variable& v = vars_[vr];
  if (!std::isfinite(value)) return "'" + v.name + "' cannot be set to " + Number(value);
  if (initialized_) return "'" + v.name + "' can be set only before initialization ends";
  if (v.kind == VarKind::Parameter) {
    params_[v.index] = value;
    params_changed_ = true;
    return "";
  }
  if (v.kind == VarKind::State) {
    y_[v.index] = value;
    state_set_[v.index] = 1;
    stale_ = true;
    return "";
  }
  return "'" + v.name + "' is not a tunable parameter or a state: it cannot be set";
}

std::string Instance::GetReal(unsigned vr, double* value) {
  if (std::string e = CheckVr(vr); !e.empty()) return e;
  const Variable& v = vars_[vr];
  if (v.type != VarType::Real) return "'" + v.name + "' is not a Real";
  switch (v.kind) {
    case VarKind::State: *value = y_[v.index]; return "";
    case VarKind::Derivative:
    case VarKind::Output:
      if (std::string e = Evaluate(); !e.empty()) return e;
      *value = v.kind == VarKind::Derivative ? ydot_[v.index] : out_[v.index];
      return "";
    default: *value = params_[v.index]; return "";
  }
}

std::string Instance::GetInteger(unsigned vr, int* value) const {
  if (std::string e = CheckVr(vr); !e.empty()) return e;
  if (vars_[vr].type != VarType::Integer) return "'" + vars_[vr].name + "' is not an Integer";
  *value = int(std::lround(params_[vars_[vr].index]));
  return "";
}

std::string Instance::GetBoolean(unsigned vr, int* value) const {
  if (std::string e = CheckVr(vr); !e.empty()) return e;
  if (vars_[vr].type != VarType::Boolean) return "'" + vars_[vr].name + "' is not a Boolean";
  *value = params_[vars_[vr].index] != 0.0;
  return "";
}

std::string Instance::Initialize() {
  if (params_changed_) {
    if (std::string e = Rebind(); !e.empty()) return e;
    // The new parameters' own start (a closed loop assembles anew); states the master set stay.
    std::vector<double> y0(n_);
    rt::InitialState(*program_, y0.data());
    for (int i = 0; i < n_; ++i)
      if (!state_set_[i]) y_[i] = y0[i];
  }
  initialized_ = true;
  stale_ = true;
  return Evaluate();
}

std::string Instance::SetTime(double t) {
  if (!std::isfinite(t)) return "the time cannot be " + Number(t);
  t_ = t;
  stale_ = true;
  return "";
}

std::string Instance::SetStates(const double* x, size_t n) {
  if (int(n) != n_) return "expected " + std::to_string(n_) + " states, got " + std::to_string(n);
  for (size_t i = 0; i < n; ++i)
    if (!std::isfinite(x[i])) return "state '" + vars_[i].name + "' cannot be " + Number(x[i]);
  std::copy(x, x + n, y_.begin());
  stale_ = true;
  return "";
}

std::string Instance::GetStates(double* x, size_t n) const {
  if (int(n) != n_) return "expected " + std::to_string(n_) + " states, got " + std::to_string(n);
  std::copy(y_.begin(), y_.end(), x);
  return "";
}

std::string Instance::GetDerivatives(double* dx, size_t n) {
  if (int(n) != n_) return "expected " + std::to_string(n_) + " derivatives, got " + std::to_string(n);
  if (std::string e = Evaluate(); !e.empty()) return e;
  std::copy(ydot_.begin(), ydot_.end(), dx);
  return "";
}

std::string Instance::Evaluate() {
  if (!stale_) return "";
  if (n_ > 0 && rt::Derivative(*program_, *ws_, t_, y_.data(), ydot_.data()) != 0)
    return "at t = " + Number(t_) + ": " + rt::ErrorMessage(*ws_);
  if (outputs_plan_ && rt::EvalSignals(*program_, *outputs_plan_, *ws_, t_, y_.data(), out_.data()) != 0)
    return "the outputs at t = " + Number(t_) + ": " + rt::ErrorMessage(*ws_);
  stale_ = false;
  return "";
}

std::string Instance::DoStep(double t, double h) {
  if (!std::isfinite(t) || !std::isfinite(h) || h <= 0)
    return "a step needs a finite time and a positive size (got t = " + Number(t) + ", h = " + Number(h) + ")";
  if (std::abs(t - t_) > 1e-9 * std::max(1.0, std::abs(t_)))
    return "the step starts at t = " + Number(t) + " but the FMU is at t = " + Number(t_);
  if (n_ > 0) {
    ModelOde ode(*program_, *ws_);
    sim::IntegratorOptions options;
    options.method = rt::Summarize(*program_).integrator;
    options.rtol = options.atol = rtol_;
    options.coupling = rt::StateCouplingGroups(*program_);
    std::vector<double> y_end = y_;
    auto row = [&](double time, const double* y, std::string*) {
      if (time > t_) std::copy(y, y + n_, y_end.begin());
      return 0;
    };
    sim::IntegrateResult r = sim::Integrate(ode, y_.data(), sim::OutputGrid{t_, t_ + h, h}, options, row);
    if (!r.ok) return "numerical failure at t = " + Number(r.fail_time) + ": " + r.cause;
    y_ = y_end;
  }
  t_ += h;
  stale_ = true;
  return Evaluate();
}

std::string Instance::Restore(const Snapshot& s) {
  if (int(s.y.size()) != n_ || s.params.size() != params_.size()) return "the FMU state is not this model's";
  const bool rebind = s.params != params_;
  t_ = s.t;
  y_ = s.y;
  state_set_ = s.state_set;
  if (rebind) {
    params_ = s.params;
    params_changed_ = true;
    if (std::string e = Rebind(); !e.empty()) return e;
  }
  stale_ = true;
  return "";
}

// Layout: "KSFMU1", t, n, y[n], m, params[m], state_set[n] (doubles and bytes, native order).
std::vector<char> Instance::Serialize(const Snapshot& s) {
  std::vector<char> out(6 + sizeof(double) * (3 + s.y.size() + s.params.size()) + s.state_set.size());
  char* p = out.data();
  auto put = [&](const void* src, size_t bytes) {
    if (bytes == 0) return;  // an empty vector's data() may be null: no memcpy from it
    std::memcpy(p, src, bytes);
    p += bytes;
  };
  put("KSFMU1", 6);
  const double n = double(s.y.size()), m = double(s.params.size());
  put(&s.t, sizeof(double));
  put(&n, sizeof(double));
  put(s.y.data(), sizeof(double) * s.y.size());
  put(&m, sizeof(double));
  put(s.params.data(), sizeof(double) * s.params.size());
  put(s.state_set.data(), s.state_set.size());
  return out;
}

bool Instance::Deserialize(const char* data, size_t size, Snapshot* s) {
  const char* p = data;
  const char* end = data + size;
  auto get = [&](void* dst, size_t bytes) {
    if (size_t(end - p) < bytes) return false;
    if (bytes > 0) std::memcpy(dst, p, bytes);
    p += bytes;
    return true;
  };
  char magic[6];
  double n = 0, m = 0;
  if (!get(magic, 6) || std::memcmp(magic, "KSFMU1", 6) != 0 || !get(&s->t, sizeof(double)) || !get(&n, sizeof(double)))
    return false;
  if (!(n >= 0 && n < 1e7)) return false;
  s->y.resize(size_t(n));
  if (!get(s->y.data(), sizeof(double) * s->y.size()) || !get(&m, sizeof(double)) || !(m >= 0 && m < 1e7)) return false;
  s->params.resize(size_t(m));
  s->state_set.resize(size_t(n));
  return get(s->params.data(), sizeof(double) * s->params.size()) && get(s->state_set.data(), s->state_set.size()) &&
         p == end;
}

}  // namespace kanesim::fmi
