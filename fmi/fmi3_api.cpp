// The FMI 3.0 functions of an exported FMU (Model Exchange and Co-Simulation; no Scheduled
// Execution), over the same instance as FMI 2.0's (fmi/instance.h) and the same guard
// (fmi/component.h): a call in the wrong mode, a NaN, a step backwards or a numerical
// failure returns fmi3Error with the reason through the master's logger.
#include <memory>
#include <string>

#include "fmi/component.h"
#include "fmi/fmi3_abi.h"
#include "fmi/fmu_common.h"

#define FMI3_EXPORT extern "C" __attribute__((visibility("default")))

namespace kf = kanesim::fmi;
using kf::Component;
using kf::Mode;

namespace {

template <class F>
fmi3Status Fmi3Guarded(fmi3Instance c, const char* call, std::initializer_list<Mode> modes, F f) {
  return static_cast<fmi3Status>(kf::Guarded(c, call, modes, f));
}

fmi3Instance Instantiate(fmi3String name, fmi3String token, fmi3String resources, bool co_simulation, fmi3Boolean logging,
                         fmi3InstanceEnvironment env, fmi3LogMessageCallback log) {
  if (!name || !token) return nullptr;
  std::unique_ptr<Component> c = kf::NewComponent(name, co_simulation, logging);
  if (log)
    c->logger = [log, env](kf::Status status, const char* category, const std::string& message) {
      log(env, static_cast<fmi3Status>(status), category, message.c_str());
    };
  // FMI 3 gives a path (with a trailing separator); accept a file URI too.
  const auto find_dir = [resources](std::string* dir) {
    *dir = resources ? resources : "";
    std::string error;
    if (dir->rfind("file:", 0) == 0) error = kf::ResourceDirectory(resources, dir);
    while (dir->size() > 1 && dir->back() == '/') dir->pop_back();
    return error.empty() && dir->empty() ? std::string("no resource path") : error;
  };
  return kf::LoadComponent(std::move(c), co_simulation ? "fmi3InstantiateCoSimulation" : "fmi3InstantiateModelExchange",
                           find_dir, token);
}

}  // namespace

FMI3_EXPORT const char* fmi3GetVersion() { return "3.0"; }

FMI3_EXPORT fmi3Status fmi3SetDebugLogging(fmi3Instance c, fmi3Boolean on, size_t, const fmi3String[]) {
  return Fmi3Guarded(c, "fmi3SetDebugLogging", kf::kAnyMode, [&](Component* x) {
    x->logging = on;
    return kf::kOK;
  });
}

FMI3_EXPORT fmi3Instance fmi3InstantiateModelExchange(fmi3String name, fmi3String token, fmi3String resources,
                                                      fmi3Boolean, fmi3Boolean logging, fmi3InstanceEnvironment env,
                                                      fmi3LogMessageCallback log) {
  return Instantiate(name, token, resources, false, logging, env, log);
}

FMI3_EXPORT fmi3Instance fmi3InstantiateCoSimulation(fmi3String name, fmi3String token, fmi3String resources,
                                                     fmi3Boolean, fmi3Boolean logging, fmi3Boolean event_mode_used,
                                                     fmi3Boolean early_return_allowed, const fmi3ValueReference[], size_t,
                                                     fmi3InstanceEnvironment env, fmi3LogMessageCallback log,
                                                     fmi3IntermediateUpdateCallback) {
  if (event_mode_used) {
    if (log) log(env, fmi3Error, "logStatusError", "this FMU has no event mode in Co-Simulation (hasEventMode=false)");
    return nullptr;
  }
  fmi3Instance c = Instantiate(name, token, resources, true, logging, env, log);
  if (c) static_cast<Component*>(c)->early_return_allowed = early_return_allowed;
  return c;
}

FMI3_EXPORT fmi3Instance fmi3InstantiateScheduledExecution(fmi3String, fmi3String, fmi3String, fmi3Boolean,
                                                           fmi3Boolean, fmi3InstanceEnvironment env,
                                                           fmi3LogMessageCallback log, fmi3ClockUpdateCallback,
                                                           fmi3LockPreemptionCallback, fmi3UnlockPreemptionCallback) {
  if (log) log(env, fmi3Error, "logStatusError", "this FMU has no Scheduled Execution interface");
  return nullptr;
}

FMI3_EXPORT void fmi3FreeInstance(fmi3Instance c) { delete static_cast<Component*>(c); }

FMI3_EXPORT fmi3Status fmi3EnterInitializationMode(fmi3Instance c, fmi3Boolean tolerance_defined, fmi3Float64 tolerance,
                                                   fmi3Float64 start, fmi3Boolean, fmi3Float64) {
  return Fmi3Guarded(c, "fmi3EnterInitializationMode", {Mode::kInstantiated}, [&](Component* x) {
    if (kf::Status s = kf::StartExperiment(x, tolerance_defined, tolerance, start); s != kf::kOK) return s;
    return kf::EnterMode(x, Mode::kInitialization);
  });
}

FMI3_EXPORT fmi3Status fmi3ExitInitializationMode(fmi3Instance c) {
  return Fmi3Guarded(c, "fmi3ExitInitializationMode", {Mode::kInitialization}, kf::ExitInitialization);
}

FMI3_EXPORT fmi3Status fmi3EnterEventMode(fmi3Instance c) {
  return Fmi3Guarded(c, "fmi3EnterEventMode", kf::kModelExchange, [&](Component* x) { return kf::EnterMode(x, Mode::kEvent); });
}

FMI3_EXPORT fmi3Status fmi3Terminate(fmi3Instance c) {
  return Fmi3Guarded(c, "fmi3Terminate", {Mode::kEvent, Mode::kContinuous, Mode::kStep, Mode::kError},
                     [&](Component* x) { return kf::EnterMode(x, Mode::kTerminated); });
}

FMI3_EXPORT fmi3Status fmi3Reset(fmi3Instance c) {
  return Fmi3Guarded(c, "fmi3Reset", kf::kAnyMode, kf::ResetComponent);
}

// ---- values: Float64 (states, derivatives, outputs, parameters, time), Int32, Boolean ----

FMI3_EXPORT fmi3Status fmi3GetFloat64(fmi3Instance c, const fmi3ValueReference vr[], size_t n, fmi3Float64 v[],
                                      size_t nv) {
  return Fmi3Guarded(c, "fmi3GetFloat64", kf::kAfterInstantiate, [&](Component* x) {
    if (nv != n) return x->Log(kf::kError, "fmi3GetFloat64: this FMU has scalar variables only");
    return kf::GetReals(x, vr, n, v, true);
  });
}

FMI3_EXPORT fmi3Status fmi3SetFloat64(fmi3Instance c, const fmi3ValueReference vr[], size_t n, const fmi3Float64 v[],
                                      size_t nv) {
  return Fmi3Guarded(c, "fmi3SetFloat64", kf::kAfterInstantiate, [&](Component* x) {
    if (nv != n) return x->Log(kf::kError, "fmi3SetFloat64: this FMU has scalar variables only");
    return kf::SetReals(x, vr, n, v, true);
  });
}

FMI3_EXPORT fmi3Status fmi3GetInt32(fmi3Instance c, const fmi3ValueReference vr[], size_t n, fmi3Int32 v[], size_t nv) {
  return Fmi3Guarded(c, "fmi3GetInt32", kf::kAfterInstantiate, [&](Component* x) {
    if (nv != n) return x->Log(kf::kError, "fmi3GetInt32: this FMU has scalar variables only");
    return kf::GetInts(x, &kf::Instance::GetInteger, vr, n, v);
  });
}

FMI3_EXPORT fmi3Status fmi3GetBoolean(fmi3Instance c, const fmi3ValueReference vr[], size_t n, fmi3Boolean v[],
                                      size_t nv) {
  return Fmi3Guarded(c, "fmi3GetBoolean", kf::kAfterInstantiate, [&](Component* x) {
    if (nv != n) return x->Log(kf::kError, "fmi3GetBoolean: this FMU has scalar variables only");
    return kf::GetInts(x, &kf::Instance::GetBoolean, vr, n, v);
  });
}

// Types this FMU has no variables of, and setting the fixed Int32 and Boolean ones: an
// error for any value reference (none is of that type, or it is fixed at export).
#define KANESIM_FMI3_NO_VARIABLES(Name, Type, Const)                                                          \
  FMI3_EXPORT fmi3Status Name(fmi3Instance c, const fmi3ValueReference[], size_t n, Const Type[], size_t) {  \
    return Fmi3Guarded(c, #Name, kf::kAfterInstantiate, [&](Component* x) {                                  \
      return n == 0 ? kf::kOK : x->Log(kf::kError, #Name ": no variable of this FMU can be read or set so"); \
    });                                                                                                      \
  }
#define KANESIM_FMI3_NONE(Type) \
  KANESIM_FMI3_NO_VARIABLES(fmi3Get##Type, fmi3##Type, ) KANESIM_FMI3_NO_VARIABLES(fmi3Set##Type, fmi3##Type, const)
KANESIM_FMI3_NONE(Float32)
KANESIM_FMI3_NONE(Int8)
KANESIM_FMI3_NONE(UInt8)
KANESIM_FMI3_NONE(Int16)
KANESIM_FMI3_NONE(UInt16)
KANESIM_FMI3_NONE(UInt32)
KANESIM_FMI3_NONE(Int64)
KANESIM_FMI3_NONE(UInt64)
KANESIM_FMI3_NONE(String)
KANESIM_FMI3_NO_VARIABLES(fmi3SetInt32, fmi3Int32, const)
KANESIM_FMI3_NO_VARIABLES(fmi3SetBoolean, fmi3Boolean, const)

FMI3_EXPORT fmi3Status fmi3GetBinary(fmi3Instance c, const fmi3ValueReference[], size_t n, size_t[], fmi3Binary[],
                                     size_t) {
  return Fmi3Guarded(c, "fmi3GetBinary", kf::kAfterInstantiate,
                     [&](Component* x) { return n == 0 ? kf::kOK : x->Log(kf::kError, "this FMU has no Binary variables"); });
}

FMI3_EXPORT fmi3Status fmi3SetBinary(fmi3Instance c, const fmi3ValueReference[], size_t n, const size_t[],
                                     const fmi3Binary[], size_t) {
  return Fmi3Guarded(c, "fmi3SetBinary", kf::kAfterInstantiate,
                     [&](Component* x) { return n == 0 ? kf::kOK : x->Log(kf::kError, "this FMU has no Binary variables"); });
}

// ---- the FMU state ----

FMI3_EXPORT fmi3Status fmi3GetFMUState(fmi3Instance c, fmi3FMUState* state) {
  return Fmi3Guarded(c, "fmi3GetFMUState", kf::kAfterInstantiate,
                     [&](Component* x) { return kf::GetState(x, "fmi3GetFMUState", state); });
}

FMI3_EXPORT fmi3Status fmi3SetFMUState(fmi3Instance c, fmi3FMUState state) {
  return Fmi3Guarded(c, "fmi3SetFMUState", kf::kAfterInstantiate,
                     [&](Component* x) { return kf::SetState(x, "fmi3SetFMUState", state); });
}

FMI3_EXPORT fmi3Status fmi3FreeFMUState(fmi3Instance c, fmi3FMUState* state) {
  return Fmi3Guarded(c, "fmi3FreeFMUState", kf::kAnyMode, [&](Component*) {
    kf::FreeState(state);
    return kf::kOK;
  });
}

FMI3_EXPORT fmi3Status fmi3SerializedFMUStateSize(fmi3Instance c, fmi3FMUState state, size_t* size) {
  return Fmi3Guarded(c, "fmi3SerializedFMUStateSize", kf::kAfterInstantiate,
                     [&](Component* x) { return kf::StateSize(x, "fmi3SerializedFMUStateSize", state, size); });
}

FMI3_EXPORT fmi3Status fmi3SerializeFMUState(fmi3Instance c, fmi3FMUState state, fmi3Byte bytes[], size_t size) {
  return Fmi3Guarded(c, "fmi3SerializeFMUState", kf::kAfterInstantiate, [&](Component* x) {
    return kf::SerializeState(x, "fmi3SerializeFMUState", state, reinterpret_cast<char*>(bytes), size);
  });
}

FMI3_EXPORT fmi3Status fmi3DeserializeFMUState(fmi3Instance c, const fmi3Byte bytes[], size_t size,
                                               fmi3FMUState* state) {
  return Fmi3Guarded(c, "fmi3DeserializeFMUState", kf::kAfterInstantiate, [&](Component* x) {
    return kf::DeserializeState(x, "fmi3DeserializeFMUState", reinterpret_cast<const char*>(bytes), size, state);
  });
}

// ---- what this FMU does not provide (its modelDescription.xml says so) ----

// An error naming the call: for features the model description does not declare.
#define KANESIM_FMI3_NOT_PROVIDED(Name, Params, what)                                             \
  FMI3_EXPORT fmi3Status Name Params {                                                          \
    return Fmi3Guarded(c, #Name, kf::kAnyMode, [&](Component* x) { return x->Log(kf::kError, #Name ": " what); }); \
  }
// ModelStructure's lists (kf::VariableDependencies); the variables are scalars: element index 0.
FMI3_EXPORT fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance c, fmi3ValueReference vr, size_t* n) {
  return Fmi3Guarded(c, "fmi3GetNumberOfVariableDependencies", kf::kAnyMode, [&](Component* x) {
    if (!n) return x->Log(kf::kError, "fmi3GetNumberOfVariableDependencies: no place given");
    std::vector<kf::ListedKnown> known;
    const kf::Status s = kf::VariableDependencies(x, "fmi3GetNumberOfVariableDependencies", vr, &known);
    if (s == kf::kOK) *n = known.size();
    return s;
  });
}

FMI3_EXPORT fmi3Status fmi3GetVariableDependencies(fmi3Instance c, fmi3ValueReference dependent,
                                                   size_t element_of_dependent[], fmi3ValueReference independents[],
                                                   size_t element_of_independents[], fmi3DependencyKind kinds[],
                                                   size_t n) {
  return Fmi3Guarded(c, "fmi3GetVariableDependencies", kf::kAnyMode, [&](Component* x) {
    std::vector<kf::ListedKnown> known;
    if (kf::Status s = kf::VariableDependencies(x, "fmi3GetVariableDependencies", dependent, &known); s != kf::kOK)
      return s;
    if (n != known.size())
      return x->Log(kf::kError, "fmi3GetVariableDependencies: '" + x->instance.Variables()[dependent].name + "' has " +
                                    std::to_string(known.size()) + " dependencies, not " + std::to_string(n));
    if (n > 0 && (!element_of_dependent || !independents || !element_of_independents || !kinds))
      return x->Log(kf::kError, "fmi3GetVariableDependencies: no place given");
    for (size_t i = 0; i < n; ++i) {
      element_of_dependent[i] = element_of_independents[i] = 0;  // the whole (scalar) variable
      independents[i] = fmi3ValueReference(known[i].vr);
      kinds[i] = known[i].constant ? fmi3Constant : fmi3Dependent;
    }
    return kf::kOK;
  });
}
// Scalar variables only: one seed per known, one sensitivity per unknown.
FMI3_EXPORT fmi3Status fmi3GetDirectionalDerivative(fmi3Instance c, const fmi3ValueReference unknowns[],
                                                    size_t n_unknowns, const fmi3ValueReference knowns[],
                                                    size_t n_knowns, const fmi3Float64 seed[], size_t n_seed,
                                                    fmi3Float64 sensitivity[], size_t n_sensitivity) {
  return Fmi3Guarded(c, "fmi3GetDirectionalDerivative", kf::kRunning, [&](Component* x) {
    if (n_seed != n_knowns || n_sensitivity != n_unknowns)
      return x->Log(kf::kError, "fmi3GetDirectionalDerivative: one seed per known and one sensitivity per unknown "
                                "(the variables are scalars)");
    return x->Result(x->instance.DirectionalDerivative(unknowns, n_unknowns, knowns, n_knowns, seed, sensitivity));
  });
}
// Scalar variables only: one seed per unknown, one sensitivity per known.
FMI3_EXPORT fmi3Status fmi3GetAdjointDerivative(fmi3Instance c, const fmi3ValueReference unknowns[], size_t n_unknowns,
                                                const fmi3ValueReference knowns[], size_t n_knowns,
                                                const fmi3Float64 seed[], size_t n_seed, fmi3Float64 sensitivity[],
                                                size_t n_sensitivity) {
  return Fmi3Guarded(c, "fmi3GetAdjointDerivative", kf::kRunning, [&](Component* x) {
    if (n_seed != n_unknowns || n_sensitivity != n_knowns)
      return x->Log(kf::kError, "fmi3GetAdjointDerivative: one seed per unknown and one sensitivity per known "
                                "(the variables are scalars)");
    return x->Result(x->instance.AdjointDerivative(unknowns, n_unknowns, knowns, n_knowns, seed, sensitivity));
  });
}
KANESIM_FMI3_NOT_PROVIDED(fmi3EnterConfigurationMode, (fmi3Instance c), "this FMU has no structural parameters to configure")
KANESIM_FMI3_NOT_PROVIDED(fmi3ExitConfigurationMode, (fmi3Instance c), "this FMU has no structural parameters to configure")
KANESIM_FMI3_NOT_PROVIDED(fmi3GetClock, (fmi3Instance c, const fmi3ValueReference[], size_t, fmi3Clock[]), "this FMU has no clocks")
KANESIM_FMI3_NOT_PROVIDED(fmi3SetClock, (fmi3Instance c, const fmi3ValueReference[], size_t, const fmi3Clock[]),
                          "this FMU has no clocks")
KANESIM_FMI3_NOT_PROVIDED(fmi3GetIntervalDecimal,
                          (fmi3Instance c, const fmi3ValueReference[], size_t, fmi3Float64[], fmi3IntervalQualifier[]),
                          "this FMU has no clocks")
KANESIM_FMI3_NOT_PROVIDED(fmi3GetIntervalFraction,
                          (fmi3Instance c, const fmi3ValueReference[], size_t, fmi3UInt64[], fmi3UInt64[],
                           fmi3IntervalQualifier[]),
                          "this FMU has no clocks")
KANESIM_FMI3_NOT_PROVIDED(fmi3GetShiftDecimal, (fmi3Instance c, const fmi3ValueReference[], size_t, fmi3Float64[]),
                          "this FMU has no clocks")
KANESIM_FMI3_NOT_PROVIDED(fmi3GetShiftFraction,
                          (fmi3Instance c, const fmi3ValueReference[], size_t, fmi3UInt64[], fmi3UInt64[]),
                          "this FMU has no clocks")
KANESIM_FMI3_NOT_PROVIDED(fmi3SetIntervalDecimal, (fmi3Instance c, const fmi3ValueReference[], size_t, const fmi3Float64[]),
                          "this FMU has no clocks")
KANESIM_FMI3_NOT_PROVIDED(fmi3SetIntervalFraction,
                          (fmi3Instance c, const fmi3ValueReference[], size_t, const fmi3UInt64[], const fmi3UInt64[]),
                          "this FMU has no clocks")
KANESIM_FMI3_NOT_PROVIDED(fmi3SetShiftDecimal, (fmi3Instance c, const fmi3ValueReference[], size_t, const fmi3Float64[]),
                          "this FMU has no clocks")
KANESIM_FMI3_NOT_PROVIDED(fmi3SetShiftFraction,
                          (fmi3Instance c, const fmi3ValueReference[], size_t, const fmi3UInt64[], const fmi3UInt64[]),
                          "this FMU has no clocks")
KANESIM_FMI3_NOT_PROVIDED(fmi3ActivateModelPartition, (fmi3Instance c, fmi3ValueReference, fmi3Float64),
                          "this FMU has no Scheduled Execution interface")
KANESIM_FMI3_NOT_PROVIDED(fmi3GetOutputDerivatives,
                          (fmi3Instance c, const fmi3ValueReference[], size_t, const fmi3Int32[], fmi3Float64[], size_t),
                          "this FMU does not provide output derivatives")

// ---- events: the event indicators' (Model Exchange; no discrete states, no clocks) ----

FMI3_EXPORT fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance c) {
  return Fmi3Guarded(c, "fmi3EvaluateDiscreteStates", kf::kRunning, [&](Component*) { return kf::kOK; });
}

FMI3_EXPORT fmi3Status fmi3UpdateDiscreteStates(fmi3Instance c, fmi3Boolean* update_needed, fmi3Boolean* terminate,
                                                fmi3Boolean* nominals_changed, fmi3Boolean* values_changed,
                                                fmi3Boolean* next_time_defined, fmi3Float64* next_time) {
  return Fmi3Guarded(c, "fmi3UpdateDiscreteStates", {Mode::kEvent}, [&](Component* x) {
    for (fmi3Boolean* b : {update_needed, terminate, nominals_changed, values_changed, next_time_defined})
      if (b) *b = false;
    if (next_time) *next_time = 0.0;
    bool changed = false, stop = false;
    if (kf::Status s = kf::UpdateDiscrete(x, "fmi3UpdateDiscreteStates", &changed, &stop); s != kf::kOK) return s;
    if (values_changed) *values_changed = changed;
    if (terminate) *terminate = stop;
    return kf::kOK;
  });
}

// ---- Model Exchange ----

FMI3_EXPORT fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance c) {
  return Fmi3Guarded(c, "fmi3EnterContinuousTimeMode", {Mode::kEvent},
                     [&](Component* x) { return kf::EnterMode(x, Mode::kContinuous); });
}

FMI3_EXPORT fmi3Status fmi3CompletedIntegratorStep(fmi3Instance c, fmi3Boolean, fmi3Boolean* enter_event,
                                                   fmi3Boolean* terminate) {
  return Fmi3Guarded(c, "fmi3CompletedIntegratorStep", {Mode::kContinuous}, [&](Component*) {
    if (enter_event) *enter_event = false;
    if (terminate) *terminate = false;
    return kf::kOK;
  });
}

FMI3_EXPORT fmi3Status fmi3SetTime(fmi3Instance c, fmi3Float64 t) {
  return Fmi3Guarded(c, "fmi3SetTime", kf::kModelExchange, [&](Component* x) { return x->Result(x->instance.SetTime(t)); });
}

FMI3_EXPORT fmi3Status fmi3SetContinuousStates(fmi3Instance c, const fmi3Float64 x[], size_t n) {
  return Fmi3Guarded(c, "fmi3SetContinuousStates", kf::kModelExchange,
                     [&](Component* m) { return m->Result(x ? m->instance.SetStates(x, n) : "no states given"); });
}

FMI3_EXPORT fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance c, fmi3Float64 dx[], size_t n) {
  return Fmi3Guarded(c, "fmi3GetContinuousStateDerivatives",
                     {Mode::kInitialization, Mode::kEvent, Mode::kContinuous, Mode::kTerminated},
                     [&](Component* m) { return m->Result(dx ? m->instance.GetDerivatives(dx, n) : "no place given"); });
}

FMI3_EXPORT fmi3Status fmi3GetEventIndicators(fmi3Instance c, fmi3Float64 z[], size_t n) {
  return Fmi3Guarded(c, "fmi3GetEventIndicators", kf::kRunning,
                     [&](Component* x) { return kf::GetIndicators(x, "fmi3GetEventIndicators", z, n); });
}

FMI3_EXPORT fmi3Status fmi3GetContinuousStates(fmi3Instance c, fmi3Float64 x[], size_t n) {
  return Fmi3Guarded(c, "fmi3GetContinuousStates", kf::kAfterInstantiate,
                     [&](Component* m) { return m->Result(x ? m->instance.GetStates(x, n) : "no place given"); });
}

FMI3_EXPORT fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance c, fmi3Float64 x[], size_t n) {
  return Fmi3Guarded(c, "fmi3GetNominalsOfContinuousStates", kf::kAfterInstantiate,
                     [&](Component* m) { return kf::Nominals(m, x, n); });
}

FMI3_EXPORT fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance c, size_t* n) {
  return Fmi3Guarded(c, "fmi3GetNumberOfEventIndicators", kf::kAfterInstantiate, [&](Component* x) {
    if (!n) return x->Log(kf::kError, "no place given");
    *n = size_t(x->instance.NumIndicators());
    return kf::kOK;
  });
}

FMI3_EXPORT fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance c, size_t* n) {
  return Fmi3Guarded(c, "fmi3GetNumberOfContinuousStates", kf::kAfterInstantiate, [&](Component* x) {
    if (!n) return x->Log(kf::kError, "no place given");
    *n = size_t(x->instance.NumStates());
    return kf::kOK;
  });
}

// ---- Co-Simulation ----

FMI3_EXPORT fmi3Status fmi3EnterStepMode(fmi3Instance c) {
  return Fmi3Guarded(c, "fmi3EnterStepMode", {Mode::kStep}, [&](Component*) { return kf::kOK; });
}

FMI3_EXPORT fmi3Status fmi3DoStep(fmi3Instance c, fmi3Float64 t, fmi3Float64 h, fmi3Boolean,
                                  fmi3Boolean* event_needed, fmi3Boolean* terminate, fmi3Boolean* early_return,
                                  fmi3Float64* last_time) {
  return Fmi3Guarded(c, "fmi3DoStep", {Mode::kStep}, [&](Component* x) {
    kf::Status s = kf::DoStep(x, "fmi3DoStep", t, h);
    for (fmi3Boolean* b : {event_needed, terminate, early_return})
      if (b) *b = false;
    if (last_time) *last_time = x->instance.Time();
    // terminate(...) in a when clause: terminateSimulation, lastSuccessfulTime the event's,
    // earlyReturn only where the master allowed it (FMI 3.0 section 4.2.1).
    if (s == kf::kDiscard && x->instance.Terminated()) {
      if (terminate) *terminate = true;
      if (early_return) *early_return = x->early_return_allowed && x->instance.Time() < t + h;
      s = kf::kOK;
    }
    return s;
  });
}
