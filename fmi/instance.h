// One instance of an exported FMU (docs/fmi.md), independent of the FMI version: the model
// loaded from the FMU's resources, its parameters, its state y = [q_free; u_free] and time,
// the derivatives (Model Exchange), one communication step (Co-Simulation). The C functions
// of the standard (fmi2_api.cpp) check the calling sequence and call these; every function
// here returns "" or why it failed, and never throws for a user's mistake.
#pragma once

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "fmi/dependencies.h"
#include "fmi/variables.h"
#include "pipeline/pipeline.h"
#include "sim/sim.h"

namespace kanesim::fmi {

// The settings `kanesim export` writes into resources/ beside the model text.
struct FmuSettings {
  std::string model;               // the class exported
  std::vector<std::string> sets;   // --set values given at export
  std::string guid;                // what modelDescription.xml says
  std::string integrator;          // Co-Simulation's integrator ("" = the compiler's choice)
  double rtol = 0.0;               // 0: the experiment's tolerance
  // The data files (meshes) the model reads, carried in resources/: each as (its entry under
  // resources/, the path the model names, resolved as at export against `main`, the main
  // file's name then). The FMU reads these and no other file.
  std::string main;
  std::vector<std::pair<std::string, std::string>> files;
};
std::string FormatSettings(const FmuSettings& settings);
bool ParseSettings(const std::string& text, FmuSettings* out, std::string* error);

class Instance {
 public:
  // Model Exchange (else Co-Simulation): the start's events at initialization, the event
  // indicators watched. Before Load.
  void SetModelExchange(bool on) { model_exchange_ = on; }
  // Loads resources_dir/model.mech with resources_dir/settings.txt (its GUID must be `guid`).
  std::string Load(const std::string& resources_dir, const std::string& guid);

  const std::vector<Variable>& Variables() const { return vars_; }
  // ModelStructure's lists in FMI `version` (what modelDescription.xml says), made at the first call.
  const StructureLists& Structure(int version);
  int NumStates() const { return n_; }
  double Time() const { return t_; }

  // Before initialization ends: a tunable parameter or a state's start value; any time: an input.
  std::string SetReal(unsigned vr, double value);
  std::string GetReal(unsigned vr, double* value);
  std::string GetInteger(unsigned vr, int* value) const;
  std::string GetBoolean(unsigned vr, int* value) const;
  void SetTolerance(double rtol) { rtol_ = rtol; }
  void SetStartTime(double t) { t_ = t; }
  // Ends initialization: compiles the parameters set (Rebind), starts from the states'
  // start values (the model's own initial state where the master set none).
  std::string Initialize();

  // Model Exchange.
  std::string SetTime(double t);
  std::string SetStates(const double* x, size_t n);
  std::string GetStates(double* x, size_t n) const;
  std::string GetDerivatives(double* dx, size_t n);
  // The event indicators (sim::HybridOde's functions) at (t, y), and the event mode's
  // update: the first indicator that crossed zero downwards since the last update (or
  // initialization; or positive in a GetIndicators since) has the run's handling (y may
  // jump: *states_changed); a terminate sets *terminate and *message.
  int NumIndicators() const { return int(z_ref_.size()); }
  std::string GetIndicators(double* z, size_t n);
  std::string UpdateDiscreteStates(bool* states_changed, bool* terminate, std::string* message);

  // d(unknowns)/d(knowns) along `seed` at (t, y, inputs): the unknowns derivatives or
  // outputs, the knowns states or inputs; central differences along the seed with
  // Richardson extrapolation, as `kanesim linearize` takes A and B (lin::Richardson).
  std::string DirectionalDerivative(const unsigned* unknowns, size_t n_unknowns, const unsigned* knowns,
                                    size_t n_knowns, const double* seed, double* out);

  // The adjoint: out[k] = sum_i seed[i] d(unknowns[i]) / d(knowns[k]), one directional
  // derivative per known (FMI 3's fmi3GetAdjointDerivative).
  std::string AdjointDerivative(const unsigned* unknowns, size_t n_unknowns, const unsigned* knowns, size_t n_knowns,
                                const double* seed, double* out);

  // Co-Simulation: integrates from the current time to t + h with kanesim's stepping core
  // (sim::Simulator: one integrator across the steps, its history carried, the run's events
  // inside the step), the inputs held at their values over the step. A terminate(...) in a
  // when clause ends the step at its event: Time() is there, *terminate_message set, and
  // Terminated() holds until Reset or Restore.
  std::string DoStep(double t, double h, std::string* terminate_message);
  bool Terminated() const;

  // The FMU state: everything that decides the continuation (the stepping core's step
  // size and end-stop sides too, once Co-Simulation has stepped).
  struct Snapshot {
    double t = 0.0;
    std::vector<double> y, params, inputs;
    std::vector<char> state_set;
    double next_step = 0.0;
    std::vector<double> resting;  // sim::SimulatorState::modes (resting stops, stuck joints)
    std::vector<double> modes, z_ref;  // Model Exchange: sim::HybridOde::Modes, z_ref_
  };
  Snapshot Save();
  std::string Restore(const Snapshot& s);
  static std::vector<char> Serialize(const Snapshot& s);
  static bool Deserialize(const char* data, size_t size, Snapshot* s);

  // Back to the state after Load (the parameters' and states' export values).
  std::string Reset();

 private:
  std::string Rebind();            // program_ for params_
  std::string Evaluate();          // derivatives and outputs at (t_, y_), when stale
  std::string CheckVr(unsigned vr) const;

  std::string StartStepper();      // stepper_ at (t_, y_, inputs_)
  std::string Indicators(std::vector<double>* z);  // at (t_, y_, inputs_)

  std::unique_ptr<pipeline::Model> model_;   // as loaded: the export's program
  std::unique_ptr<sim::Simulator> stepper_;  // Co-Simulation, from its first step; null after a change
  std::unique_ptr<sim::HybridOde> hybrid_;   // the derivatives in the current mode, the events (Rebind)
  std::shared_ptr<const rt::Program> program_;  // with the current parameter values
  std::unique_ptr<rt::Workspace, void (*)(rt::Workspace*)> ws_{nullptr, nullptr};
  std::shared_ptr<const rt::SignalPlan> outputs_plan_;
  std::vector<Variable> vars_;
  std::unique_ptr<StructureLists> structure_;
  FmuSettings settings_;
  int n_ = 0;                      // states
  double t_ = 0.0, rtol_ = 0.0;
  std::vector<double> y_, ydot_, out_;
  std::vector<double> params_;     // every mech param's value (leaves as set)
  std::vector<double> inputs_;     // the model's inputs (rt::NumInputs), 0 until set
  rt::Integrator integrator_ = rt::Integrator::Auto;  // Co-Simulation's (settings.txt)
  std::vector<char> state_set_;    // the master set this state's start value
  std::vector<double> z_ref_;      // the indicators after the last event update, or seen positive since
  bool model_exchange_ = false;
  bool params_changed_ = false;
  bool initialized_ = false;
  bool stale_ = true;              // ydot_ and out_ not yet for (t_, y_)
};

}  // namespace kanesim::fmi
