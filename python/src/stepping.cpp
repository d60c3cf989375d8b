// kanesim._kanesim.Simulator: the stepping core (sim/simulator.h) for Python, a controller
// stepping the model (docs/python.md "Stepping"). The GIL is released while it integrates.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <chrono>
#include <cmath>
#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

#include "python/src/glue.h"
#include "sim/simulator.h"

namespace py = pybind11;

namespace {

// Raised as kanesim.SimulationError by the package (python/kanesim/__init__.py).
struct StepFailed {
  double time;
  std::string cause;
};

class PySimulator {
 public:
  PySimulator(std::shared_ptr<const kanesim::py::LoadedModel> model, std::unique_ptr<kanesim::sim::Simulator> s)
      : model_(std::move(model)), sim_(std::move(s)) {
    for (size_t i = 0; i < sim_->InputNames().size(); ++i) index_[sim_->InputNames()[i]] = static_cast<int>(i);
    for (size_t i = 0; i < sim_->OutputNames().size(); ++i) output_index_[sim_->OutputNames()[i]] = i;
    outputs_.resize(sim_->OutputNames().size());
  }

  void SetInputs(const py::handle& inputs) {
    if (inputs.is_none()) return;
    for (auto item : py::reinterpret_borrow<py::dict>(inputs)) {
      const std::string name = py::cast<std::string>(item.first);
      const auto it = index_.find(name);
      if (it == index_.end()) throw py::key_error("'" + name + "' is not an input of the model" + Known());
      std::string error;
      if (!sim_->SetInput(it->second, py::cast<double>(item.second), &error)) throw py::value_error(error);
      fresh_ = false;  // an output may read an input
    }
  }

  void AdvanceTo(double t, const py::handle& inputs) {
    if (!(t >= sim_->Time()) || !std::isfinite(t))  // a caller's mistake, not a numerical failure
      throw py::value_error("cannot advance to t = " + std::to_string(t) + ": the simulator is at t = " +
                            std::to_string(sim_->Time()) + " and does not step backwards");
    SetInputs(inputs);
    kanesim::sim::StepResult r;
    {
      py::gil_scoped_release release;
      const auto start = std::chrono::steady_clock::now();
      r = sim_->AdvanceTo(t);
      fresh_ = false;
      advance_seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    }
    if (!r.ok) throw StepFailed{r.fail_time, r.cause};
  }
  void Step(double dt, const py::handle& inputs) {
    if (!(dt >= 0.0) || !std::isfinite(dt)) throw py::value_error("the step must be a finite number >= 0");
    AdvanceTo(sim_->Time() + dt, inputs);
  }

  py::array_t<double> Outputs() {
    Evaluate();
    return py::array_t<double>(static_cast<py::ssize_t>(outputs_.size()), outputs_.data());
  }
  // The outputs at the current time, evaluated once until the next step or change.
  void Evaluate() {
    if (fresh_) return;
    std::string error;
    if (!sim_->Outputs(outputs_.data(), &error)) throw StepFailed{sim_->Time(), error};
    fresh_ = true;
  }
  void Changed() { fresh_ = false; }
  double Get(const std::string& name) {
    const auto it = output_index_.find(name);
    if (it == output_index_.end()) {
      const auto in = index_.find(name);
      if (in != index_.end()) return sim_->Inputs()[static_cast<size_t>(in->second)];
      throw py::key_error("'" + name + "' is not an output or input of this simulator");
    }
    Evaluate();
    return outputs_[it->second];
  }

  py::dict Inputs() const {
    py::dict d;
    for (size_t i = 0; i < sim_->InputNames().size(); ++i) d[py::str(sim_->InputNames()[i])] = sim_->Inputs()[i];
    return d;
  }

  // (t, y, inputs, next step, modes, terminate message or None): plain values, so that it
  // pickles. The modes: the contacts' resting sides, the stuck joints and their forces.
  py::tuple GetState() {
    const kanesim::sim::SimulatorState s = sim_->GetState();
    return py::make_tuple(s.t, py::array_t<double>(static_cast<py::ssize_t>(s.y.size()), s.y.data()),
                          py::array_t<double>(static_cast<py::ssize_t>(s.inputs.size()), s.inputs.data()), s.next_step,
                          py::array_t<double>(static_cast<py::ssize_t>(s.modes.size()), s.modes.data()),
                          s.terminated ? py::object(py::str(s.terminate_message)) : py::object(py::none()));
  }
  void SetState(const py::tuple& t) {
    if (t.size() != 6) throw py::value_error("not a state from get_state()");
    kanesim::sim::SimulatorState s;
    s.t = py::cast<double>(t[0]);
    s.y = py::cast<std::vector<double>>(t[1]);
    s.inputs = py::cast<std::vector<double>>(t[2]);
    s.next_step = py::cast<double>(t[3]);
    s.modes = py::cast<std::vector<double>>(t[4]);
    s.terminated = !t[5].is_none();
    if (s.terminated) s.terminate_message = py::cast<std::string>(t[5]);
    std::string error;
    if (!sim_->SetState(s, &error)) throw py::value_error(error);
    fresh_ = false;
  }

  py::object Terminated() const {
    std::string why;
    if (!sim_->Terminated(&why)) return py::none();
    return py::make_tuple(sim_->Time(), why);
  }

  kanesim::sim::Simulator& sim() { return *sim_; }
  double advance_seconds() const { return advance_seconds_; }

 private:
  std::string Known() const {
    std::string k;
    for (const std::string& n : sim_->InputNames()) k += (k.empty() ? "" : ", ") + n;
    return k.empty() ? " (it has none)" : " (its inputs: " + k + ")";
  }
  std::shared_ptr<const kanesim::py::LoadedModel> model_;  // keeps the program alive
  std::unique_ptr<kanesim::sim::Simulator> sim_;
  std::unordered_map<std::string, int> index_;
  std::unordered_map<std::string, size_t> output_index_;
  std::vector<double> outputs_;
  bool fresh_ = false;             // outputs_ holds the outputs at the current time and inputs
  double advance_seconds_ = 0.0;  // wall time inside Simulator::AdvanceTo (stats()["advance_seconds"])
};

std::unique_ptr<PySimulator> MakeSimulator(std::shared_ptr<kanesim::py::LoadedModel> model, double start_time,
                                           double rtol, double atol, const std::vector<std::string>& outputs,
                                           const std::string& integrator) {
  kanesim::py::RunRequest r;
  r.start_time = start_time;
  r.rtol = rtol;
  r.atol = atol;
  r.outputs = outputs;
  r.integrator = integrator;
  kanesim::sim::SimOptions so;
  std::vector<std::string> warnings;
  std::string error;
  if (!kanesim::py::ResolveRun(*model, r, &so, &warnings, &error)) throw py::value_error(error);
  kanesim::sim::SimulatorOptions o;
  o.start_time = so.start_time;
  o.rtol = so.rtol;
  o.atol = so.atol;
  o.integrator = so.integrator;
  o.ida_linear_solver = so.ida_linear_solver;
  o.max_steps = so.max_steps;
  o.signals = so.signals;
  auto s = kanesim::sim::Simulator::Make(model->program, o, &error);
  if (!s) throw py::value_error(error);
  return std::make_unique<PySimulator>(std::move(model), std::move(s));
}

}  // namespace

// A run's or a simulator's events as Python dicts: {time, element, kind, changes: {name:
// (before, after)}} (docs/events.md "Outputs").
py::list EventsToPython(const std::vector<kanesim::sim::EventRecord>& events) {
  py::list out;
  for (const kanesim::sim::EventRecord& e : events) {
    py::dict ev, changes;
    ev["time"] = e.time;
    ev["element"] = e.element;
    ev["kind"] = e.kind;
    for (const kanesim::sim::EventChange& c : e.changes) changes[py::str(c.name)] = py::make_tuple(c.before, c.after);
    ev["changes"] = changes;
    out.append(ev);
  }
  return out;
}

void BindSimulator(py::module_& m) {
  static py::exception<StepFailed> step_failed(m, "_StepFailed", PyExc_RuntimeError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const StepFailed& e) {
      py::tuple args = py::make_tuple(e.time, e.cause);
      PyErr_SetObject(step_failed.ptr(), args.ptr());
    }
  });
  py::class_<PySimulator>(m, "Simulator")
      .def("advance_to", &PySimulator::AdvanceTo, py::arg("t"), py::arg("inputs") = py::none())
      .def("step", &PySimulator::Step, py::arg("dt"), py::arg("inputs") = py::none())
      .def("set_inputs", &PySimulator::SetInputs)
      .def_property_readonly("inputs", &PySimulator::Inputs)
      .def_property_readonly("input_names", [](PySimulator& s) { return s.sim().InputNames(); })
      .def_property_readonly("output_names", [](PySimulator& s) { return s.sim().OutputNames(); })
      .def_property_readonly("outputs", &PySimulator::Outputs)
      .def_property_readonly("time", [](PySimulator& s) { return s.sim().Time(); })
      .def_property_readonly("state", [](PySimulator& s) {
        const std::vector<double>& y = s.sim().State();
        return py::array_t<double>(static_cast<py::ssize_t>(y.size()), y.data());
      })
      .def_property_readonly("method", [](PySimulator& s) { return kanesim::sim::MethodName(s.sim().Method()); })
      .def_property_readonly("events", [](PySimulator& s) { return EventsToPython(s.sim().Events()); })
      .def_property_readonly("terminated", &PySimulator::Terminated)
      .def("get", &PySimulator::Get)
      .def("get_state", &PySimulator::GetState)
      .def("set_state", &PySimulator::SetState)
      .def("reset", [](PySimulator& s) {
        s.sim().Reset();
        s.Changed();
      })
      .def("stats", [](PySimulator& s) {
        const kanesim::sim::IntegratorStats st = s.sim().Stats();
        py::dict d;
        d["steps"] = st.steps;
        d["rhs_evals"] = st.rhs_evals;
        d["err_test_fails"] = st.err_test_fails;
        d["stiff_time"] = st.stiff_time;  // DOP853 found the problem stiff there (NaN: never)
        d["switched"] = st.switched;      // ... and went on with CVODE-BDF (the automatic choice)
        d["advance_seconds"] = s.advance_seconds();
        return d;
      });
  m.def("simulator", &MakeSimulator);
}
