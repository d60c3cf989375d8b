#include "fmi/instance.h"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>

#include "linearize/linearize.h"
#include "runtime/program/program.h"
#include "sim/sim.h"

namespace kanesim::fmi {
namespace {

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
  if (!s.main.empty()) text += "main " + s.main + "\n";
  for (const auto& [entry, path] : s.files) text += "file " + entry + " " + path + "\n";
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
    else if (key == "main") out->main = value;
    else if (key == "file" && value.find(' ') != std::string::npos)
      out->files.emplace_back(value.substr(0, value.find(' ')), value.substr(value.find(' ') + 1));
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
  integrator_ = spec.integrator;
  pipeline::LoadOptions load;
  load.model = settings_.model;
  load.sets = settings_.sets;
  // The model's data files from resources/ only, under the names the model gives them
  // (resolved against the main file's name at export, which the text is loaded under).
  std::map<std::string, std::string> files;
  for (const auto& [entry, path] : settings_.files) files[path] = dir + "/" + entry;
  load.data_files = &files;
  pipeline::Source source = pipeline::Source::File(dir + "/model.mech");
  if (!settings_.main.empty()) {
    std::ifstream m(dir + "/model.mech", std::ios::binary);
    std::stringstream model_text;
    model_text << m.rdbuf();
    source = pipeline::Source::Text(settings_.main, model_text.str());
  }
  pipeline::LoadResult r = pipeline::LoadModel(source, load, spec);
  if (!r.model) return "the model does not load:\n" + r.diagnostics;
  model_ = std::move(r.model);
  vars_ = ListVariables(*model_);
  n_ = rt::StateSize(*model_->program);
  return Reset();
}

const StructureLists& Instance::Structure(int version) {
  if (!structure_ || structure_->version != version)
    structure_ = std::make_unique<StructureLists>(StructureLists{vars_, ModelDependencies(*model_->program, vars_), version});
  return *structure_;
}

std::string Instance::Reset() {
  program_ = model_->program;
  params_ = program_->param_values;
  y_.assign(n_, 0.0);
  rt::InitialState(*program_, y_.data());
  ydot_.assign(n_, 0.0);
  state_set_.assign(n_, 0);
  inputs_.assign(rt::NumInputs(*program_), 0.0);
  stepper_.reset();
  t_ = rt::StartTime(*program_);
  rtol_ = settings_.rtol > 0 ? settings_.rtol : model_->mech->experiment.tolerance;
  params_changed_ = false;
  initialized_ = false;
  return Rebind();
}

std::string Instance::Rebind() {
  if (params_changed_) {
    // Calculated parameters follow the tunable ones they are bound to (as sweeps do).
    rt::CompileResult r = rt::Rebind(*model_->program, BoundValues(*model_->mech, params_));
    if (!r.program) {
      std::string msg = "the model does not compile with these parameter values";
      for (const rt::CompileMessage& e : r.errors) msg += "; " + e.message;
      return msg;
    }
    program_ = r.program;
    params_ = program_->param_values;
    params_changed_ = false;
  }
  stepper_.reset();
  ws_ = rt::MakeWorkspace(*program_);
  hybrid_ = std::make_unique<sim::HybridOde>(program_, rtol_, rtol_);
  z_ref_.assign(size_t(hybrid_->NumIndicators()), 0.0);
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
  if (v.kind == VarKind::Input) {
    inputs_[v.index] = value;
    stale_ = true;
    return "";
  }
  if (initialized_) return "'" + v.name + "' can be set only before initialization ends";
  if (v.kind == VarKind::Parameter) {
    params_[v.index] = value;
    params_changed_ = true;
    return "";
  }
  if (v.kind == VarKind::State) {
    if (v.start_calculated)  // FMI 2.0.4 table 2.2.7, FMI 3.0 section 2.4.7.4: initial="calculated"
      return "'" + v.name + "' starts where " +
             (v.start_params.empty() ? std::string("the assembly of the model's constraints puts it")
                                     : "its parameters put it (set those, as `" + vars_[size_t(v.start_params[0])].name + "`)") +
             ": initial=\"calculated\"";
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
    case VarKind::Indicator: {
      std::vector<double> z;
      if (std::string e = Indicators(&z); !e.empty()) return e;
      *value = z[size_t(v.index)];
      return "";
    }
    case VarKind::Input: *value = inputs_[v.index]; return "";
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
  // The events' tolerances are the experiment's (fmi2SetupExperiment may have set them).
  hybrid_ = std::make_unique<sim::HybridOde>(program_, rtol_, rtol_);
  hybrid_->SetInputs(inputs_);
  if (model_exchange_) {  // a start on a contact is its first event, as in a run
    if (std::string e = hybrid_->Start(t_, y_.data()); !e.empty()) return e;
    if (std::string e = Indicators(&z_ref_); !e.empty()) return e;
  }
  initialized_ = true;
  stale_ = true;
  return Evaluate();
}

std::string Instance::Indicators(std::vector<double>* z) {
  z->assign(z_ref_.size(), 0.0);
  if (z->empty()) return "";
  hybrid_->SetInputs(inputs_);
  if (hybrid_->Indicators(t_, y_.data(), z->data()) != 0)
    return "the event indicators at t = " + Number(t_) + ": " + hybrid_->FailureCause();
  return "";
}

std::string Instance::GetIndicators(double* z, size_t n) {
  if (n != z_ref_.size())
    return "expected " + std::to_string(z_ref_.size()) + " event indicators, got " + std::to_string(n);
  std::vector<double> now;
  if (std::string e = Indicators(&now); !e.empty()) return e;
  std::copy(now.begin(), now.end(), z);
  // A value the master saw positive is the far side of a later crossing: an upward
  // crossing it did not stop at (or an event update it skipped) does not hide that one.
  for (size_t i = 0; i < now.size(); ++i)
    if (now[i] > 0.0) z_ref_[i] = now[i];
  return "";
}

// The run fires an event where a function crosses zero downwards and handles that one
// only, the solver restarting after it (sim/integrator.h): the same here, the other side of
// the crossing being the values after the last update or, since, seen positive by the master.
std::string Instance::UpdateDiscreteStates(bool* states_changed, bool* terminate, std::string* message) {
  *states_changed = *terminate = false;
  std::vector<double> now;
  if (std::string e = Indicators(&now); !e.empty()) return e;
  size_t i = 0;
  while (i < now.size() && !(z_ref_[i] > 0.0 && now[i] <= 0.0)) ++i;
  if (i < now.size()) {
    const std::vector<double> before = y_;
    if (hybrid_->Event(t_, y_.data(), int(i)) != 0) {
      y_ = before;
      return "at t = " + Number(t_) + ": " + hybrid_->FailureCause();
    }
    *states_changed = y_ != before;
    *terminate = hybrid_->Terminated(message);
    stale_ = true;
    if (std::string e = Indicators(&now); !e.empty()) return e;
  }
  z_ref_ = now;
  return "";
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
  stepper_.reset();
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
  if (!inputs_.empty()) rt::SetInputValues(*ws_, inputs_.data());
  hybrid_->SetInputs(inputs_);
  if (n_ > 0 && hybrid_->Derivatives(t_, y_.data(), ydot_.data()) != 0)
    return "at t = " + Number(t_) + ": " + hybrid_->FailureCause();
  if (outputs_plan_) {
    std::vector<double> y = y_;
    // The resting joints on their stops, the mode's friction laws and held rows: a run's rows.
    if (std::string why = hybrid_->ForOutputs(*ws_, t_, y.data()); !why.empty())
      return "the outputs at t = " + Number(t_) + ": " + why;
    if (rt::EvalSignals(*program_, *outputs_plan_, *ws_, t_, y.data(), out_.data()) != 0)
      return "the outputs at t = " + Number(t_) + ": " + rt::ErrorMessage(*ws_);
  }
  stale_ = false;
  return "";
}

std::string Instance::DirectionalDerivative(const unsigned* unknowns, size_t n_unknowns, const unsigned* knowns,
                                            size_t n_knowns, const double* seed, double* out) {
  if ((n_unknowns > 0 && (!unknowns || !out)) || (n_knowns > 0 && (!knowns || !seed))) return "no place given";
  std::vector<double> dy(y_.size(), 0.0), du(inputs_.size(), 0.0);
  double scale = 1.0, seed_max = 0.0;  // the largest value moved, the largest seed
  for (size_t k = 0; k < n_knowns; ++k) {
    if (std::string e = CheckVr(knowns[k]); !e.empty()) return e;
    const Variable& v = vars_[knowns[k]];
    if (!std::isfinite(seed[k])) return "the seed of '" + v.name + "' cannot be " + Number(seed[k]);
    if (v.kind != VarKind::State && v.kind != VarKind::Input)
      return "'" + v.name + "' is not a state or an input: no derivative with respect to it";
    (v.kind == VarKind::State ? dy : du)[v.index] += seed[k];
    if (seed[k] != 0) {
      scale = std::max(scale, std::abs(v.kind == VarKind::State ? y_[v.index] : inputs_[v.index]));
      seed_max = std::max(seed_max, std::abs(seed[k]));
    }
  }
  for (size_t k = 0; k < n_unknowns; ++k) {
    if (std::string e = CheckVr(unknowns[k]); !e.empty()) return e;
    const VarKind kind = vars_[unknowns[k]].kind;
    if (kind != VarKind::Derivative && kind != VarKind::Output)
      return "'" + vars_[unknowns[k]].name + "' is not a derivative or an output";
  }
  if (seed_max == 0) {  // no direction: the derivative is 0
    std::fill(out, out + n_unknowns, 0.0);
    return "";
  }
  // F(s) = [y'; outputs] at (y + s dy, u + s du), s stepping 1e-3 of the largest value moved.
  std::vector<double> y(y_.size()), u(inputs_.size()), ydot(y_.size()), o(out_.size());
  const lin::StepEval F = [&](double s, Eigen::VectorXd* f, double* taken) -> lin::Status {
    for (size_t i = 0; i < y.size(); ++i) y[i] = y_[i] + s * dy[i];
    for (size_t i = 0; i < u.size(); ++i) u[i] = inputs_[i] + s * du[i];
    if (!u.empty()) rt::SetInputValues(*ws_, u.data());
    hybrid_->SetInputs(u);
    if (n_ > 0 && hybrid_->Derivatives(t_, y.data(), ydot.data()) != 0) return {2, hybrid_->FailureCause()};
    if (outputs_plan_)
      if (std::string why = hybrid_->ForOutputs(*ws_, t_, y.data(), /*snap=*/false); !why.empty())
        return {2, "the outputs: " + why};
    if (outputs_plan_ && rt::EvalSignals(*program_, *outputs_plan_, *ws_, t_, y.data(), o.data()) != 0)
      return {2, "the outputs: " + rt::ErrorMessage(*ws_)};
    f->resize(Eigen::Index(ydot.size() + o.size()));
    for (size_t i = 0; i < ydot.size(); ++i) (*f)[Eigen::Index(i)] = ydot[i];
    for (size_t i = 0; i < o.size(); ++i) (*f)[Eigen::Index(ydot.size() + i)] = o[i];
    *taken = s;
    return {};
  };
  Eigen::VectorXd d, err;
  const lin::Status st = lin::Richardson(F, 1e-3 * scale / seed_max, &d, &err);
  stale_ = true;  // the workspace was left at a perturbed point
  if (!st.ok()) return "the directional derivative at t = " + Number(t_) + ": " + st.message;
  for (size_t k = 0; k < n_unknowns; ++k) {
    const Variable& v = vars_[unknowns[k]];
    out[k] = d[Eigen::Index(v.kind == VarKind::Derivative ? v.index : int(y_.size()) + v.index)];
  }
  return "";
}

// The stepping core from (t_, y_, inputs_): a start on a contact or with exact friction is
// its first event, as a run starts (docs/fmi.md "Co-Simulation").
std::string Instance::AdjointDerivative(const unsigned* unknowns, size_t n_unknowns, const unsigned* knowns,
                                        size_t n_knowns, const double* seed, double* out) {
  if ((n_unknowns > 0 && (!unknowns || !seed)) || (n_knowns > 0 && (!knowns || !out))) return "no place given";
  for (size_t i = 0; i < n_unknowns; ++i)
    if (!std::isfinite(seed[i])) return "a seed cannot be " + Number(seed[i]);
  std::vector<double> column(n_unknowns);
  const double one = 1.0;
  for (size_t k = 0; k < n_knowns; ++k) {
    if (std::string e = DirectionalDerivative(unknowns, n_unknowns, &knowns[k], 1, &one, column.data()); !e.empty())
      return e;
    out[k] = 0.0;
    for (size_t i = 0; i < n_unknowns; ++i) out[k] += seed[i] * column[i];
  }
  return "";
}

std::string Instance::StartStepper() {
  sim::SimulatorOptions options;
  options.start_time = t_;
  options.rtol = options.atol = rtol_;
  options.integrator = integrator_;
  options.initial_state = y_;
  options.initial_inputs = inputs_;
  std::string error;
  stepper_ = sim::Simulator::Make(program_, options, &error);
  return stepper_ ? "" : error;
}

std::string Instance::DoStep(double t, double h, std::string* terminate_message) {
  if (!std::isfinite(t) || !std::isfinite(h) || h <= 0)
    return "a step needs a finite time and a positive size (got t = " + Number(t) + ", h = " + Number(h) + ")";
  if (std::abs(t - t_) > 1e-9 * std::max(1.0, std::abs(t_)))
    return "the step starts at t = " + Number(t) + " but the FMU is at t = " + Number(t_);
  std::string error;
  if (stepper_ && stepper_->Terminated(&error))
    return "the model terminated at t = " + Number(t_) + " (" + error + "); the master ends with fmi2Terminate / fmi3Terminate";
  if (!stepper_)
    if (std::string e = StartStepper(); !e.empty()) return e;
  for (size_t i = 0; i < inputs_.size(); ++i)
    if (!stepper_->SetInput(int(i), inputs_[i], &error)) return error;
  const sim::StepResult r = stepper_->AdvanceTo(t_ + h);
  if (!r.ok) {
    stepper_.reset();  // the next step starts afresh from where this one started
    return "numerical failure at t = " + Number(r.fail_time) + ": " + r.cause;
  }
  y_ = stepper_->State();
  t_ = stepper_->Time();
  hybrid_->SetModes(stepper_->Modes());  // the outputs see the step's modes (Evaluate)
  stale_ = true;
  if (r.terminated) *terminate_message = r.cause;
  return Evaluate();
}

bool Instance::Terminated() const {
  std::string why;
  return stepper_ && stepper_->Terminated(&why);
}

Instance::Snapshot Instance::Save() {
  Snapshot s{t_, y_, params_, inputs_, state_set_, 0.0, {}, hybrid_->Modes(), z_ref_};
  if (stepper_) {
    // GetState restarts the solver there; SetState (Restore) restarts it the same way.
    const sim::SimulatorState state = stepper_->GetState();
    s.next_step = state.next_step;
    s.resting = state.modes;
  }
  return s;
}

std::string Instance::Restore(const Snapshot& s) {
  if (int(s.y.size()) != n_ || s.params.size() != params_.size() || s.inputs.size() != inputs_.size() ||
      s.state_set.size() != y_.size())
    return "the FMU state is not this model's";
  const bool rebind = s.params != params_;
  t_ = s.t;
  y_ = s.y;
  inputs_ = s.inputs;
  state_set_ = s.state_set;
  if (rebind) {
    params_ = s.params;
    params_changed_ = true;
    if (std::string e = Rebind(); !e.empty()) return e;
  }
  if (!hybrid_->SetModes(s.modes) || s.z_ref.size() != z_ref_.size()) return "the FMU state is not this model's";
  z_ref_ = s.z_ref;
  stale_ = true;
  if (!stepper_ && !s.resting.empty())
    if (std::string e = StartStepper(); !e.empty()) return e;
  if (stepper_) {
    std::string error;
    sim::SimulatorState state = stepper_->GetState();
    state.t = t_;
    state.y = y_;
    state.inputs = inputs_;
    state.next_step = s.next_step;
    if (!s.resting.empty()) state.modes = s.resting;
    state.terminated = false;  // a state saved after a terminate steps on (the master's choice)
    if (!stepper_->SetState(state, &error)) return error;
  }
  return "";
}

// Layout: "KSFMU3", t, n, y[n], m, params[m], k, inputs[k], next_step, r, resting[r],
// e, modes[e], z, z_ref[z], state_set[n] (doubles, then bytes, native order; the counts as
// doubles).
std::vector<char> Instance::Serialize(const Snapshot& s) {
  std::vector<char> out(6 +
                        sizeof(double) * (8 + s.y.size() + s.params.size() + s.inputs.size() + s.resting.size() +
                                          s.modes.size() + s.z_ref.size()) +
                        s.state_set.size());
  char* p = out.data();
  auto put = [&](const void* src, size_t bytes) {
    if (bytes == 0) return;  // an empty vector's data() may be null: no memcpy from it
    std::memcpy(p, src, bytes);
    p += bytes;
  };
  put("KSFMU3", 6);
  const double n = double(s.y.size()), m = double(s.params.size()), k = double(s.inputs.size()),
               r = double(s.resting.size());
  put(&s.t, sizeof(double));
  put(&n, sizeof(double));
  put(s.y.data(), sizeof(double) * s.y.size());
  put(&m, sizeof(double));
  put(s.params.data(), sizeof(double) * s.params.size());
  put(&k, sizeof(double));
  put(s.inputs.data(), sizeof(double) * s.inputs.size());
  put(&s.next_step, sizeof(double));
  put(&r, sizeof(double));
  put(s.resting.data(), sizeof(double) * s.resting.size());
  const double e = double(s.modes.size()), z = double(s.z_ref.size());
  put(&e, sizeof(double));
  put(s.modes.data(), sizeof(double) * s.modes.size());
  put(&z, sizeof(double));
  put(s.z_ref.data(), sizeof(double) * s.z_ref.size());
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
  // A count is read as a double and must be a whole number below 1e7 (no huge allocation).
  auto count = [&](size_t* out) {
    double c = 0;
    if (!get(&c, sizeof(double)) || !(c >= 0 && c < 1e7) || c != std::floor(c)) return false;
    *out = size_t(c);
    return true;
  };
  auto doubles = [&](std::vector<double>* v) {
    size_t c = 0;
    if (!count(&c)) return false;
    v->resize(c);
    return get(v->data(), sizeof(double) * c);
  };
  char magic[6];
  if (!get(magic, 6) || std::memcmp(magic, "KSFMU3", 6) != 0 || !get(&s->t, sizeof(double)) || !doubles(&s->y) ||
      !doubles(&s->params) || !doubles(&s->inputs) || !get(&s->next_step, sizeof(double)) || !doubles(&s->resting) ||
      !doubles(&s->modes) || !doubles(&s->z_ref))
    return false;
  s->state_set.resize(s->y.size());
  return get(s->state_set.data(), s->state_set.size()) && p == end;
}

}  // namespace kanesim::fmi
