// The FMI 2.0 functions of an exported FMU (Model Exchange and Co-Simulation in one
// library): each checks the calling sequence of the standard's state machine (FMI 2.0.4,
// sections 3.2.3 and 4.2.4), then calls the instance (fmi/instance.h). A wrong call, a
// NaN, a step backwards or a numerical failure returns fmi2Error with the reason through
// the master's logger; no exception crosses the C boundary.
#include <memory>
#include <string>

#include "fmi/fmi2_abi.h"
#include "fmi/fmu_common.h"
#include "fmi/component.h"

#define FMI2_EXPORT extern "C" __attribute__((visibility("default")))

namespace kf = kanesim::fmi;
using kf::Component;
using kf::Mode;

namespace {

// kf::Guarded with FMI 2's status type.
template <class F>
fmi2Status Fmi2Guarded(fmi2Component c, const char* call, std::initializer_list<Mode> modes, F f) {
  return static_cast<fmi2Status>(kf::Guarded(c, call, modes, f));
}

}  // namespace

FMI2_EXPORT const char* fmi2GetTypesPlatform() { return "default"; }
FMI2_EXPORT const char* fmi2GetVersion() { return "2.0"; }

FMI2_EXPORT fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean on, size_t, const fmi2String[]) {
  return Fmi2Guarded(c, "fmi2SetDebugLogging", kf::kAfterInstantiate, [&](Component* x) {
    x->logging = on;
    return kf::kOK;
  });
}

FMI2_EXPORT fmi2Component fmi2Instantiate(fmi2String name, fmi2Type type, fmi2String guid, fmi2String resources,
                                          const fmi2CallbackFunctions* callbacks, fmi2Boolean, fmi2Boolean logging) {
  if (!callbacks || !name || !guid) return nullptr;
  std::unique_ptr<Component> c = kf::NewComponent(name, type == fmi2CoSimulation, logging);
  if (fmi2CallbackLogger logger = callbacks->logger) {
    fmi2ComponentEnvironment env = callbacks->componentEnvironment;
    c->logger = [logger, env, instance = c.get()](kf::Status status, const char* category, const std::string& message) {
      // The message is the format itself, its '%' doubled: a master that prints the format
      // without formatting it (some do) shows the text too.
      std::string format;
      for (char ch : message) format += ch == '%' ? "%%" : std::string(1, ch);
      logger(env, instance->name.c_str(), static_cast<fmi2Status>(status), category, format.c_str());
    };
  }
  const std::string uri = resources ? resources : "";
  return kf::LoadComponent(
      std::move(c), "fmi2Instantiate", [&](std::string* dir) { return kf::ResourceDirectory(uri, dir); }, guid);
}

FMI2_EXPORT void fmi2FreeInstance(fmi2Component c) { delete static_cast<Component*>(c); }

FMI2_EXPORT fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean tolerance_defined, fmi2Real tolerance,
                                           fmi2Real start, fmi2Boolean, fmi2Real) {
  return Fmi2Guarded(c, "fmi2SetupExperiment", {Mode::kInstantiated},
                     [&](Component* x) { return kf::StartExperiment(x, tolerance_defined, tolerance, start); });
}

FMI2_EXPORT fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
  return Fmi2Guarded(c, "fmi2EnterInitializationMode", {Mode::kInstantiated},
                     [&](Component* x) { return kf::EnterMode(x, Mode::kInitialization); });
}

FMI2_EXPORT fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
  return Fmi2Guarded(c, "fmi2ExitInitializationMode", {Mode::kInitialization}, kf::ExitInitialization);
}

FMI2_EXPORT fmi2Status fmi2Terminate(fmi2Component c) {
  return Fmi2Guarded(c, "fmi2Terminate", {Mode::kEvent, Mode::kContinuous, Mode::kStep, Mode::kError},
                     [&](Component* x) { return kf::EnterMode(x, Mode::kTerminated); });
}

FMI2_EXPORT fmi2Status fmi2Reset(fmi2Component c) {
  return Fmi2Guarded(c, "fmi2Reset", kf::kAnyMode, kf::ResetComponent);
}

// ---- values ----

FMI2_EXPORT fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Real value[]) {
  return Fmi2Guarded(c, "fmi2GetReal", kf::kRunning, [&](Component* x) { return kf::GetReals(x, vr, n, value, false); });
}

FMI2_EXPORT fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Integer value[]) {
  return Fmi2Guarded(c, "fmi2GetInteger", kf::kRunning,
                     [&](Component* x) { return kf::GetInts(x, &kf::Instance::GetInteger, vr, n, value); });
}

FMI2_EXPORT fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Boolean value[]) {
  return Fmi2Guarded(c, "fmi2GetBoolean", kf::kRunning,
                     [&](Component* x) { return kf::GetInts(x, &kf::Instance::GetBoolean, vr, n, value); });
}

FMI2_EXPORT fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference[], size_t n, fmi2String[]) {
  return Fmi2Guarded(c, "fmi2GetString", kf::kRunning,
                 [&](Component* x) { return n == 0 ? kf::kOK : x->Log(kf::kError, "this FMU has no String variables"); });
}

FMI2_EXPORT fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Real value[]) {
  return Fmi2Guarded(c, "fmi2SetReal", kf::kAfterInstantiate,
                     [&](Component* x) { return kf::SetReals(x, vr, n, value, false); });
}

// Integer and Boolean variables are the parameters fixed at export: none can be set.
FMI2_EXPORT fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference[], size_t n, const fmi2Integer[]) {
  return Fmi2Guarded(c, "fmi2SetInteger", kf::kAfterInstantiate, [&](Component* x) {
    return n == 0 ? kf::kOK : x->Log(kf::kError, "the Integer variables are fixed at export (structural)");
  });
}

FMI2_EXPORT fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference[], size_t n, const fmi2Boolean[]) {
  return Fmi2Guarded(c, "fmi2SetBoolean", kf::kAfterInstantiate, [&](Component* x) {
    return n == 0 ? kf::kOK : x->Log(kf::kError, "the Boolean variables are fixed at export (structural)");
  });
}

FMI2_EXPORT fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference[], size_t n, const fmi2String[]) {
  return Fmi2Guarded(c, "fmi2SetString", kf::kAfterInstantiate,
                 [&](Component* x) { return n == 0 ? kf::kOK : x->Log(kf::kError, "this FMU has no String variables"); });
}

// ---- the FMU state ----

FMI2_EXPORT fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate* state) {
  return Fmi2Guarded(c, "fmi2GetFMUstate", kf::kAfterInstantiate,
                     [&](Component* x) { return kf::GetState(x, "fmi2GetFMUstate", state); });
}

FMI2_EXPORT fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate state) {
  return Fmi2Guarded(c, "fmi2SetFMUstate", kf::kAfterInstantiate,
                     [&](Component* x) { return kf::SetState(x, "fmi2SetFMUstate", state); });
}

FMI2_EXPORT fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate* state) {
  return Fmi2Guarded(c, "fmi2FreeFMUstate", kf::kAfterInstantiate, [&](Component*) {
    kf::FreeState(state);
    return kf::kOK;
  });
}

FMI2_EXPORT fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate state, size_t* size) {
  return Fmi2Guarded(c, "fmi2SerializedFMUstateSize", kf::kAfterInstantiate,
                     [&](Component* x) { return kf::StateSize(x, "fmi2SerializedFMUstateSize", state, size); });
}

FMI2_EXPORT fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate state, fmi2Byte bytes[], size_t size) {
  return Fmi2Guarded(c, "fmi2SerializeFMUstate", kf::kAfterInstantiate,
                     [&](Component* x) { return kf::SerializeState(x, "fmi2SerializeFMUstate", state, bytes, size); });
}

FMI2_EXPORT fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte bytes[], size_t size,
                                               fmi2FMUstate* state) {
  return Fmi2Guarded(c, "fmi2DeSerializeFMUstate", kf::kAfterInstantiate,
                     [&](Component* x) { return kf::DeserializeState(x, "fmi2DeSerializeFMUstate", bytes, size, state); });
}

FMI2_EXPORT fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference unknowns[],
                                                    size_t n_unknowns, const fmi2ValueReference knowns[],
                                                    size_t n_knowns, const fmi2Real seed[], fmi2Real out[]) {
  return Fmi2Guarded(c, "fmi2GetDirectionalDerivative", kf::kRunning, [&](Component* x) {
    return x->Result(x->instance.DirectionalDerivative(unknowns, n_unknowns, knowns, n_knowns, seed, out));
  });
}

// ---- Model Exchange ----

FMI2_EXPORT fmi2Status fmi2EnterEventMode(fmi2Component c) {
  return Fmi2Guarded(c, "fmi2EnterEventMode", kf::kModelExchange, [&](Component* x) { return kf::EnterMode(x, Mode::kEvent); });
}

FMI2_EXPORT fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo* info) {
  return Fmi2Guarded(c, "fmi2NewDiscreteStates", {Mode::kEvent}, [&](Component* x) {
    if (!info) return x->Log(kf::kError, "fmi2NewDiscreteStates: no event info");
    *info = fmi2EventInfo{0, 0, 0, 0, 0, 0.0};
    bool changed = false, terminate = false;
    if (kf::Status s = kf::UpdateDiscrete(x, "fmi2NewDiscreteStates", &changed, &terminate); s != kf::kOK) return s;
    info->valuesOfContinuousStatesChanged = changed;
    info->terminateSimulation = terminate;
    return kf::kOK;
  });
}

FMI2_EXPORT fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c) {
  return Fmi2Guarded(c, "fmi2EnterContinuousTimeMode", {Mode::kEvent},
                     [&](Component* x) { return kf::EnterMode(x, Mode::kContinuous); });
}

FMI2_EXPORT fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean, fmi2Boolean* enter_event,
                                                   fmi2Boolean* terminate) {
  return Fmi2Guarded(c, "fmi2CompletedIntegratorStep", {Mode::kContinuous}, [&](Component* x) {
    if (enter_event) *enter_event = 0;
    if (terminate) *terminate = 0;
    return kf::kOK;
  });
}

FMI2_EXPORT fmi2Status fmi2SetTime(fmi2Component c, fmi2Real t) {
  return Fmi2Guarded(c, "fmi2SetTime", kf::kModelExchange, [&](Component* x) { return x->Result(x->instance.SetTime(t)); });
}

FMI2_EXPORT fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t n) {
  return Fmi2Guarded(c, "fmi2SetContinuousStates", kf::kModelExchange,
                 [&](Component* m) { return m->Result(x ? m->instance.SetStates(x, n) : "no states given"); });
}

FMI2_EXPORT fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real dx[], size_t n) {
  return Fmi2Guarded(c, "fmi2GetDerivatives", {Mode::kInitialization, Mode::kEvent, Mode::kContinuous, Mode::kTerminated},
                 [&](Component* m) { return m->Result(dx ? m->instance.GetDerivatives(dx, n) : "no place given"); });
}

FMI2_EXPORT fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real z[], size_t n) {
  return Fmi2Guarded(c, "fmi2GetEventIndicators", kf::kRunning,
                     [&](Component* x) { return kf::GetIndicators(x, "fmi2GetEventIndicators", z, n); });
}

FMI2_EXPORT fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t n) {
  return Fmi2Guarded(c, "fmi2GetContinuousStates", kf::kAfterInstantiate,
                 [&](Component* m) { return m->Result(x ? m->instance.GetStates(x, n) : "no place given"); });
}

FMI2_EXPORT fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x[], size_t n) {
  return Fmi2Guarded(c, "fmi2GetNominalsOfContinuousStates", kf::kAfterInstantiate,
                     [&](Component* m) { return kf::Nominals(m, x, n); });
}

// ---- Co-Simulation ----

FMI2_EXPORT fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference[], size_t n,
                                                   const fmi2Integer[], const fmi2Real[]) {
  return Fmi2Guarded(c, "fmi2SetRealInputDerivatives", kf::kAfterInstantiate, [&](Component* x) {
    return n == 0 ? kf::kOK : x->Log(kf::kError, "this FMU does not interpolate inputs");
  });
}

FMI2_EXPORT fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference[], size_t n,
                                                    const fmi2Integer[], fmi2Real[]) {
  return Fmi2Guarded(c, "fmi2GetRealOutputDerivatives", kf::kRunning, [&](Component* x) {
    return n == 0 ? kf::kOK : x->Log(kf::kError, "this FMU does not provide output derivatives");
  });
}

FMI2_EXPORT fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean) {
  return Fmi2Guarded(c, "fmi2DoStep", {Mode::kStep}, [&](Component* x) { return kf::DoStep(x, "fmi2DoStep", t, h); });
}

FMI2_EXPORT fmi2Status fmi2CancelStep(fmi2Component c) {
  return Fmi2Guarded(c, "fmi2CancelStep", {Mode::kStep},
                 [&](Component* x) { return x->Log(kf::kError, "fmi2CancelStep: steps are never asynchronous here"); });
}

FMI2_EXPORT fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind, fmi2Status*) {
  return Fmi2Guarded(c, "fmi2GetStatus", kf::kRunning, [&](Component* x) {
    return x->Log(kf::kDiscard, "fmi2GetStatus: steps are never asynchronous here");
  });
}

FMI2_EXPORT fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind kind, fmi2Real* value) {
  return Fmi2Guarded(c, "fmi2GetRealStatus", kf::kRunning, [&](Component* x) {
    if (kind != fmi2LastSuccessfulTime || !value) return x->Log(kf::kDiscard, "fmi2GetRealStatus: only the last successful time");
    *value = x->instance.Time();
    return kf::kOK;
  });
}

FMI2_EXPORT fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind, fmi2Integer*) {
  return Fmi2Guarded(c, "fmi2GetIntegerStatus", kf::kRunning,
                 [&](Component* x) { return x->Log(kf::kDiscard, "fmi2GetIntegerStatus: no such status"); });
}

FMI2_EXPORT fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind kind, fmi2Boolean* value) {
  return Fmi2Guarded(c, "fmi2GetBooleanStatus", kf::kRunning, [&](Component* x) {
    if (kind != fmi2Terminated || !value) return x->Log(kf::kDiscard, "fmi2GetBooleanStatus: only terminated");
    *value = x->instance.Terminated();
    return kf::kOK;
  });
}

FMI2_EXPORT fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind, fmi2String*) {
  return Fmi2Guarded(c, "fmi2GetStringStatus", kf::kRunning,
                 [&](Component* x) { return x->Log(kf::kDiscard, "fmi2GetStringStatus: no such status"); });
}
