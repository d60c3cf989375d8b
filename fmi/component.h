// What the C functions of FMI 2.0 and 3.0 share: one instance of the FMU as the master sees
// it (its mode in the standard's state machine, its logger), and the guard every function
// runs through: the call must be allowed in the current mode, and no exception crosses the
// C boundary.
#pragma once

#include <exception>
#include <functional>
#include <initializer_list>
#include <memory>
#include <new>
#include <string>
#include <vector>

#include "fmi/instance.h"

namespace kanesim::fmi {

// fmi2Status and fmi3Status have these values (fmi2Pending aside).
enum Status { kOK = 0, kWarning = 1, kDiscard = 2, kError = 3, kFatal = 4 };

// The modes of FMI 2.0.4 (sections 3.2.3, 4.2.4) and 3.0 (section 3.2), merged.
enum class Mode { kInstantiated, kInitialization, kEvent, kContinuous, kStep, kTerminated, kError };

inline const char* ModeName(Mode m) {
  static const char* const kNames[] = {"instantiated", "initialization mode", "event mode", "continuous-time mode",
                                       "step mode", "terminated", "error"};
  return kNames[int(m)];
}

struct Component {
  std::string name;
  bool co_simulation = false;
  bool early_return_allowed = false;  // FMI 3.0 Co-Simulation: fmi3DoStep may return early
  bool logging = false;
  Mode mode = Mode::kInstantiated;
  Instance instance;
  std::function<void(Status, const char* category, const std::string&)> logger;  // to the master

  Status Log(Status status, const std::string& message) {
    if (logger && (status >= kWarning || logging)) logger(status, status >= kError ? "logStatusError" : "logAll", message);
    return status;
  }
  // "" or the error through the logger.
  Status Result(const std::string& error) { return error.empty() ? kOK : Log(kError, error); }
};

// Runs f(component) when the component is in one of `modes`, else an error naming the call.
template <class F>
Status Guarded(void* component, const char* call, std::initializer_list<Mode> modes, F f) {
  auto* c = static_cast<Component*>(component);
  if (!c) return kError;
  bool allowed = false;
  for (Mode m : modes) allowed = allowed || m == c->mode;
  if (!allowed) return c->Log(kError, std::string(call) + " is not allowed in " + ModeName(c->mode));
  try {
    return f(c);
  } catch (const std::bad_alloc&) {
    return c->Log(kError, std::string(call) + ": out of memory");
  } catch (const std::exception& e) {
    return c->Log(kError, std::string(call) + ": " + e.what());
  }
}

inline constexpr std::initializer_list<Mode> kAfterInstantiate = {
    Mode::kInstantiated, Mode::kInitialization, Mode::kEvent, Mode::kContinuous, Mode::kStep, Mode::kTerminated};
inline constexpr std::initializer_list<Mode> kRunning = {Mode::kInitialization, Mode::kEvent, Mode::kContinuous,
                                                        Mode::kStep, Mode::kTerminated, Mode::kError};
inline constexpr std::initializer_list<Mode> kAnyMode = {Mode::kInstantiated, Mode::kInitialization, Mode::kEvent,
                                                        Mode::kContinuous, Mode::kStep, Mode::kTerminated,
                                                        Mode::kError};
inline constexpr std::initializer_list<Mode> kModelExchange = {Mode::kEvent, Mode::kContinuous};

// A Save()d instance, as the master holds it (fmi2FMUstate, fmi3FMUState).
using Snapshot = Instance::Snapshot;

// ---- The bodies of the calls FMI 2.0 and 3.0 both have (fmi/component.cpp), run inside
// Guarded; `call` names the C function in messages ("fmi2GetFMUstate"). ----

// A component for the master's `name`; Model Exchange unless `co_simulation`.
std::unique_ptr<Component> NewComponent(const char* name, bool co_simulation, bool logging);
// Loads the model into c from the folder find_dir gives ("" or why not): the component
// for the master, or nullptr with "call: why" through c's logger.
Component* LoadComponent(std::unique_ptr<Component> c, const std::string& call,
                         const std::function<std::string(std::string* dir)>& find_dir, const char* token);

// fmi2SetupExperiment / fmi3EnterInitializationMode: the tolerance and start time.
Status StartExperiment(Component* x, bool tolerance_defined, double tolerance, double start);
Status ExitInitialization(Component* x);
Status EnterMode(Component* x, Mode mode);
Status ResetComponent(Component* x);

// Reals by value reference; `time` (the value reference after the variables) when with_time.
Status GetReals(Component* x, const unsigned vr[], size_t n, double v[], bool with_time);
Status SetReals(Component* x, const unsigned vr[], size_t n, const double v[], bool with_time);
// Integers or Booleans by value reference (Instance::GetInteger, Instance::GetBoolean).
template <class T>
Status GetInts(Component* x, std::string (Instance::*get)(unsigned, int*) const, const unsigned vr[], size_t n, T v[]) {
  for (size_t i = 0; i < n; ++i) {
    int value = 0;
    if (Status s = x->Result((x->instance.*get)(vr[i], &value)); s != kOK) return s;
    v[i] = static_cast<T>(value);
  }
  return kOK;
}

// The FMU state (a Snapshot behind the master's pointer).
Status GetState(Component* x, const std::string& call, void** state);
Status SetState(Component* x, const std::string& call, void* state);
void FreeState(void** state);
Status StateSize(Component* x, const std::string& call, void* state, size_t* size);
Status SerializeState(Component* x, const std::string& call, void* state, char bytes[], size_t size);
Status DeserializeState(Component* x, const std::string& call, const char bytes[], size_t size, void** state);

// Model Exchange: the event update (*changed: the states jumped; *terminate), the event
// indicators, the nominals of the states.
Status UpdateDiscrete(Component* x, const std::string& call, bool* changed, bool* terminate);
Status GetIndicators(Component* x, const std::string& call, double z[], size_t n);
Status Nominals(Component* x, double nominals[], size_t n);

// FMI 3's variable dependencies (section 2.2.10): vr's ModelStructure list, the initial one
// before initialization ends, the runtime one after; an error for a variable that is no
// unknown then.
Status VariableDependencies(Component* x, const std::string& call, unsigned vr, std::vector<ListedKnown>* out);

// Co-Simulation: one communication step; a failed one leaves the state where it was; kDiscard
// when a terminate(...) ended it at its event (Instance::Terminated).
Status DoStep(Component* x, const std::string& call, double t, double h);

}  // namespace kanesim::fmi
