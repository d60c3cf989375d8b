#include "fmi/component.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace kanesim::fmi {

std::unique_ptr<Component> NewComponent(const char* name, bool co_simulation, bool logging) {
  auto c = std::make_unique<Component>();
  c->name = name;
  c->co_simulation = co_simulation;
  c->instance.SetModelExchange(!co_simulation);
  c->logging = logging;
  return c;
}

Component* LoadComponent(std::unique_ptr<Component> c, const std::string& call,
                         const std::function<std::string(std::string* dir)>& find_dir, const char* token) {
  try {
    std::string dir, error = find_dir(&dir);
    if (error.empty()) error = c->instance.Load(dir, token);
    if (!error.empty()) {
      c->Log(kError, call + ": " + error);
      return nullptr;
    }
  } catch (const std::exception& e) {
    c->Log(kError, call + ": " + e.what());
    return nullptr;
  }
  return c.release();
}

Status StartExperiment(Component* x, bool tolerance_defined, double tolerance, double start) {
  if (tolerance_defined && !(tolerance > 0 && tolerance < 1)) return x->Log(kError, "the tolerance must be in (0, 1)");
  if (!std::isfinite(start)) return x->Log(kError, "the start time must be finite");
  if (tolerance_defined) x->instance.SetTolerance(tolerance);
  x->instance.SetStartTime(start);
  return kOK;
}

Status ExitInitialization(Component* x) {
  if (Status s = x->Result(x->instance.Initialize()); s != kOK) return s;
  x->mode = x->co_simulation ? Mode::kStep : Mode::kEvent;
  return kOK;
}

Status EnterMode(Component* x, Mode mode) {
  x->mode = mode;
  return kOK;
}

Status ResetComponent(Component* x) {
  x->mode = Mode::kInstantiated;
  return x->Result(x->instance.Reset());
}

// `time` follows the model's variables (modelDescription.xml, FMI 3).
static bool IsTime(const Component* x, unsigned vr) { return vr == x->instance.Variables().size(); }

Status GetReals(Component* x, const unsigned vr[], size_t n, double v[], bool with_time) {
  for (size_t i = 0; i < n; ++i) {
    if (with_time && IsTime(x, vr[i])) {
      v[i] = x->instance.Time();
      continue;
    }
    if (Status s = x->Result(x->instance.GetReal(vr[i], &v[i])); s != kOK) return s;
  }
  return kOK;
}

Status SetReals(Component* x, const unsigned vr[], size_t n, const double v[], bool with_time) {
  for (size_t i = 0; i < n; ++i)
    if (Status s = x->Result(with_time && IsTime(x, vr[i]) ? "'time' cannot be set" : x->instance.SetReal(vr[i], v[i]));
        s != kOK)
      return s;
  return kOK;
}

Status GetState(Component* x, const std::string& call, void** state) {
  if (!state) return x->Log(kError, call + ": no place for the state");
  if (auto* s = static_cast<Snapshot*>(*state))
    *s = x->instance.Save();
  else
    *state = new Snapshot(x->instance.Save());
  return kOK;
}

Status SetState(Component* x, const std::string& call, void* state) {
  if (!state) return x->Log(kError, call + ": no state");
  return x->Result(x->instance.Restore(*static_cast<Snapshot*>(state)));
}

void FreeState(void** state) {
  if (!state) return;
  delete static_cast<Snapshot*>(*state);
  *state = nullptr;
}

Status StateSize(Component* x, const std::string& call, void* state, size_t* size) {
  if (!state || !size) return x->Log(kError, call + ": no state");
  *size = Instance::Serialize(*static_cast<Snapshot*>(state)).size();
  return kOK;
}

Status SerializeState(Component* x, const std::string& call, void* state, char bytes[], size_t size) {
  if (!state || !bytes) return x->Log(kError, call + ": no state");
  const std::vector<char> data = Instance::Serialize(*static_cast<Snapshot*>(state));
  if (data.size() != size) return x->Log(kError, call + ": the buffer has the wrong size");
  std::copy(data.begin(), data.end(), bytes);
  return kOK;
}

Status DeserializeState(Component* x, const std::string& call, const char bytes[], size_t size, void** state) {
  Snapshot s;
  if (!bytes || !state || !Instance::Deserialize(bytes, size, &s))
    return x->Log(kError, call + ": not a serialized state of a kanesim FMU");
  delete static_cast<Snapshot*>(*state);
  *state = new Snapshot(std::move(s));
  return kOK;
}

Status UpdateDiscrete(Component* x, const std::string& call, bool* changed, bool* terminate) {
  std::string message;
  if (const std::string e = x->instance.UpdateDiscreteStates(changed, terminate, &message); !e.empty())
    return x->Log(kError, call + ": " + e);
  if (*terminate) x->Log(kOK, "terminate at t = " + std::to_string(x->instance.Time()) + ": " + message);
  return kOK;
}

Status GetIndicators(Component* x, const std::string& call, double z[], size_t n) {
  if (n > 0 && !z) return x->Log(kError, call + ": no place given");
  return x->Result(x->instance.GetIndicators(z, n));
}

Status Nominals(Component* x, double nominals[], size_t n) {
  if (int(n) != x->instance.NumStates() || !nominals) return x->Log(kError, "wrong number of states");
  for (size_t i = 0; i < n; ++i) nominals[i] = 1.0;  // angles, lengths and their rates: of order one
  return kOK;
}

Status VariableDependencies(Component* x, const std::string& call, unsigned vr, std::vector<ListedKnown>* out) {
  const std::vector<Variable>& vars = x->instance.Variables();
  if (vr >= vars.size()) return x->Log(kError, call + ": value reference " + std::to_string(vr) + " is not a variable");
  const bool initial = x->mode == Mode::kInstantiated || x->mode == Mode::kInitialization;
  const VarKind kind = vars[vr].kind;
  const bool unknown = initial ? InitialUnknown(vars[vr])
                               : kind == VarKind::Derivative || kind == VarKind::Output || kind == VarKind::Indicator;
  if (!unknown)
    return x->Log(kError, call + ": '" + vars[vr].name + "' is not an unknown " +
                              (initial ? "at initialization" : "after initialization") + " (ModelStructure)");
  const StructureLists& s = x->instance.Structure(3);
  // An event indicator's element has no list: it depends on every known.
  *out = kind == VarKind::Indicator || ListOmitted(s, vr, initial) ? AllKnowns(s, initial) : ListedKnowns(s, vr, initial);
  return kOK;
}

Status DoStep(Component* x, const std::string& call, double t, double h) {
  std::string why;
  const std::string error = x->instance.DoStep(t, h, &why);
  // A failed step leaves the state where it was; the master may retry from a saved state.
  if (!error.empty()) return x->Log(kError, call + ": " + error);
  // terminate(...) in a when clause ended the step at its event: fmi2Discard with
  // fmi2Terminated true (FMI 2.0.4, 4.2.3); fmi3DoStep turns it into terminateSimulation.
  if (x->instance.Terminated())
    return x->Log(kDiscard, call + ": terminate at t = " + std::to_string(x->instance.Time()) + ": " + why);
  return kOK;
}

}  // namespace kanesim::fmi
