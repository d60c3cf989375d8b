// kanesim._kanesim: the compiled half of the Python package (python/kanesim/__init__.py is
// the other). Thin bindings over glue.h: Python values in, NumPy arrays out, the GIL
// released while a model loads, integrates or sweeps.
#include <pybind11/numpy.h>
#include <pybind11/complex.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <complex>
#include <cstring>
#include <functional>
#include <vector>

#include "python/src/glue.h"
#include "sim/integrator.h"

namespace py = pybind11;
using kanesim::py::LoadedModel;

py::list EventsToPython(const std::vector<kanesim::sim::EventRecord>& events);  // python/src/stepping.cpp

namespace {

py::object ToPython(const kanesim::py::Value& value) {
  return std::visit(
      [](const auto& x) -> py::object {
        using T = std::decay_t<decltype(x)>;
        if constexpr (std::is_same_v<T, std::monostate>) return py::none();
        else if constexpr (std::is_same_v<T, std::shared_ptr<kanesim::py::Dict>>) {
          py::dict d;
          for (const auto& [k, v] : *x) d[py::str(k)] = ToPython(v);
          return d;
        } else if constexpr (std::is_same_v<T, std::shared_ptr<kanesim::py::List>>) {
          py::list l;
          for (const auto& v : *x) l.append(ToPython(v));
          return l;
        } else {
          return py::cast(x);
        }
      },
      value.v);
}

py::dict StatsDict(const kanesim::sim::SimStats& s) {
  py::dict d;
  d["method"] = kanesim::sim::MethodName(s.method);
  d["steps"] = s.integrator.steps;
  d["rhs_evals"] = s.integrator.rhs_evals;
  d["jac_rhs_evals"] = s.integrator.rhs_evals_jac;
  d["jac_evals"] = s.integrator.jac_evals;
  d["lin_setups"] = s.integrator.lin_setups;
  d["err_test_fails"] = s.integrator.err_test_fails;
  d["nonlin_iters"] = s.integrator.nonlin_iters;
  d["nonlin_conv_fails"] = s.integrator.nonlin_conv_fails;
  d["last_step"] = s.integrator.last_step;
  d["linear_solver"] = s.integrator.linear_solver;
  // DOP853's stiffness detection (docs/integrators.md "The automatic choice"): where it found
  // the problem stiff (NaN: never) and whether the run went on with CVODE-BDF from there.
  d["stiff_time"] = s.integrator.stiff_time;
  d["switched"] = s.integrator.switched;
  d["rows"] = s.rows;
  d["integrate_seconds"] = s.times.integrate;
  d["output_seconds"] = s.times.output;
  // The energy guard (docs/integrators.md): "on", "off", "report" or "not applied (...)";
  // with on and report, the largest relative energy error seen and its bound.
  d["energy_guard"] = s.energy_guard;
  d["energy_error"] = s.energy_error;
  d["energy_tolerance"] = s.energy_tolerance;
  // The events (end stops, when clauses; docs/events.md), which kanesim.Result moves to .events:
  // each {time, element, kind, changes: {name: (before, after)}}; and terminate's (time, message).
  d["events"] = EventsToPython(s.events);
  d["terminated"] = s.terminated ? py::object(py::make_tuple(s.terminate_time, s.terminate_message)) : py::none();
  // run(sensitivity=...): per parameter, in its order, the differences' estimated error and
  // the largest value of each quotient, as `--stats` prints them (docs/integrators.md).
  py::dict sens;
  for (const kanesim::sim::SensitivityErrors& e : s.sensitivity) {
    py::dict x;
    x["dfdp_error"] = e.dfdp_error;
    x["dfdp_scale"] = e.dfdp_scale;
    x["dfdy_error"] = e.dfdy_error;
    x["dfdy_scale"] = e.dfdy_scale;
    x["start_error"] = e.start_error;
    x["start_scale"] = e.start_scale;
    sens[py::str(e.param)] = x;
  }
  d["sensitivity"] = sens;
  return d;
}

// (model, warnings) or raises ModelError via the Python side: returns (None, error tuple).
py::tuple Load(const std::string& path, const std::string& text, bool from_text, const std::string& model,
               const std::vector<std::string>& sets, const std::string& solver, const std::string& integrator,
               const std::string& reactions, bool floating, const std::vector<std::string>& package_paths,
               bool stops) {
  kanesim::py::LoadRequest req;
  req.path = path;
  req.text = text;
  req.from_text = from_text;
  req.model = model;
  req.sets = sets;
  req.solver = solver;
  req.integrator = integrator;
  req.reactions = reactions;
  req.floating = floating;
  req.stops = stops;
  req.package_paths = package_paths;
  auto loaded = std::make_shared<LoadedModel>();
  kanesim::py::ModelErrorInfo error;
  bool ok = false;
  {
    py::gil_scoped_release release;
    ok = kanesim::py::Load(req, loaded.get(), &error);
  }
  if (!ok) return py::make_tuple(py::none(), py::make_tuple(error.code, error.file, error.line, error.column, error.rendered));
  return py::make_tuple(loaded, py::none());
}

// Every NumPy array the module returns is made by one of these four, so that the layout
// probe below (run by the package at import) checks each way an array is made. pybind11
// computes a new array's strides from NumPy's dtype struct; pybind11 older than 2.12 reads
// it with NumPy 1's layout, which under NumPy 2 gives stride 0 (every element reads the
// first): the package refuses to import when the probe disagrees (python/kanesim/__init__.py).
py::array_t<double> Vector(const std::vector<double>& x) {
  py::array_t<double> a(static_cast<py::ssize_t>(x.size()));
  if (!x.empty()) std::memcpy(a.mutable_data(), x.data(), x.size() * sizeof(double));
  return a;
}

// `x` row-major, rows x cols.
py::array_t<double> RowMajor(const std::vector<double>& x, size_t rows, size_t cols) {
  py::array_t<double> a({static_cast<py::ssize_t>(rows), static_cast<py::ssize_t>(cols)});
  if (rows > 0 && cols > 0) std::memcpy(a.mutable_data(), x.data(), rows * cols * sizeof(double));
  return a;
}

py::array_t<double> Matrix(const Eigen::MatrixXd& m) {
  py::array_t<double> a({static_cast<py::ssize_t>(m.rows()), static_cast<py::ssize_t>(m.cols())});
  auto w = a.mutable_unchecked<2>();
  for (Eigen::Index i = 0; i < m.rows(); ++i)
    for (Eigen::Index j = 0; j < m.cols(); ++j) w(i, j) = m(i, j);
  return a;
}

template <class Complexes>
py::array_t<std::complex<double>> ComplexVector(const Complexes& x, size_t n) {
  py::array_t<std::complex<double>> a(static_cast<py::ssize_t>(n));
  for (size_t k = 0; k < n; ++k) a.mutable_data()[k] = x[k];
  return a;
}

// Known values through each maker above, for the package's import-time check:
// (vector [1, 2, 3], row-major 2 x 3 [[1, 2, 3], [4, 5, 6]], matrix the same from Eigen,
// complex [1+2j, 3-4j]).
py::tuple LayoutProbe() {
  Eigen::MatrixXd m(2, 3);
  m << 1, 2, 3, 4, 5, 6;
  const std::vector<std::complex<double>> c = {{1, 2}, {3, -4}};
  return py::make_tuple(Vector({1, 2, 3}), RowMajor({1, 2, 3, 4, 5, 6}, 2, 3), Matrix(m), ComplexVector(c, c.size()));
}

// (columns, time, values 2-D, stats, failure or None, warnings); raises ValueError on a
// usage error.
py::tuple Run(const LoadedModel& model, double start_time, double stop_time, double interval, double rtol, double atol,
              const std::vector<std::string>& outputs, const std::string& integrator, const std::string& linear_solver,
              const std::string& projection, const std::string& energy_check,
              const std::vector<std::string>& sensitivity) {
  kanesim::py::RunRequest r;
  r.start_time = start_time;
  r.stop_time = stop_time;
  r.interval = interval;
  r.rtol = rtol;
  r.atol = atol;
  r.outputs = outputs;
  r.integrator = integrator;
  r.linear_solver = linear_solver;
  r.projection = projection;
  r.energy_check = energy_check;
  kanesim::sim::SimOptions so;
  std::vector<std::string> warnings;
  std::string error;
  if (!kanesim::py::ResolveRun(model, r, &so, &warnings, &error)) throw py::value_error(error);
  kanesim::py::RunOutput out;
  bool ok = false;
  // Ctrl-C: Python's signal handlers run when asked (PyErr_CheckSignals, with the GIL); a
  // KeyboardInterrupt they raise stops the run and is raised here.
  const std::function<bool()> interrupted = [] {
    py::gil_scoped_acquire gil;
    return PyErr_CheckSignals() != 0;
  };
  {
    py::gil_scoped_release release;
    ok = kanesim::py::Simulate(model, so, &out, &error, interrupted, sensitivity);
  }
  if (out.interrupted) throw py::error_already_set();
  if (!ok) throw py::value_error(error);
  py::array_t<double> time = Vector(out.time);
  py::array_t<double> values = RowMajor(out.values, out.time.size(), out.columns.size());
  py::object failure = py::none();
  if (out.failed) failure = py::make_tuple(out.fail_time, out.message);
  py::dict stats = StatsDict(out.stats);
  stats["simulate_seconds"] = out.simulate_seconds;
  return py::make_tuple(out.columns, time, values, stats, failure, warnings);
}

py::tuple Sweep(const LoadedModel& model, const std::vector<std::pair<std::string, std::vector<double>>>& grid,
                const std::vector<std::pair<std::string, std::vector<double>>>& samples,
                const std::vector<std::string>& metrics, int threads, double start_time, double stop_time,
                double interval, double rtol, double atol, const std::string& integrator,
                const std::string& energy_check, const std::string& isolation, double scenario_timeout) {
  if (isolation != "process" && isolation != "thread")
    throw py::value_error("isolation must be \"process\" or \"thread\", got \"" + isolation + "\"");
  // 1e6 s (11 days): what the pool's int milliseconds hold.
  if (!(scenario_timeout >= 0.0 && scenario_timeout <= 1e6))
    throw py::value_error("scenario_timeout must be seconds from 0 (none) to 1e6");
  if (isolation == "thread" && scenario_timeout > 0.0)
    throw py::value_error("scenario_timeout needs worker processes (isolation=\"process\")");
  kanesim::py::SweepRequest req;
  req.processes = isolation == "process";
  req.scenario_timeout = scenario_timeout;
  req.grid = grid;
  req.samples = samples;
  req.metrics = metrics;
  req.threads = threads;
  req.run.start_time = start_time;
  req.run.stop_time = stop_time;
  req.run.interval = interval;
  req.run.rtol = rtol;
  req.run.atol = atol;
  req.run.integrator = integrator;
  req.run.energy_check = energy_check;
  req.interrupted = [] {
    py::gil_scoped_acquire gil;
    return PyErr_CheckSignals() != 0;
  };
  kanesim::py::SweepTable table;
  std::string error;
  bool ok = false;
  {
    py::gil_scoped_release release;
    ok = kanesim::py::Sweep(model, req, &table, &error);
  }
  if (table.interrupted) throw py::error_already_set();
  if (!ok) throw py::value_error(error);
  return py::make_tuple(table.header, table.lines, table.failed, table.warning);
}

// A dict with the linear model (A, B, C, D, names, eigenvalues, modes, accuracy, the
// operating point, the equilibrium search) and, on failure, "failure": (code, message,
// hint, file, line, column).
py::dict Linearize(const LoadedModel& model, bool has_at, double at, bool equilibrium,
                   const std::vector<std::string>& inputs, const std::vector<std::string>& outputs, double step,
                   const std::vector<std::pair<std::string, double>>& input_values) {
  kanesim::py::LinearizeRequest r;
  r.has_at = has_at;
  r.at = at;
  r.equilibrium = equilibrium;
  r.inputs = inputs;
  r.input_values = input_values;
  r.outputs = outputs;
  r.step = step;
  kanesim::py::LinearizeOutput out;
  std::string error;
  bool ok = false;
  {
    py::gil_scoped_release release;
    ok = kanesim::py::Linearize(model, r, &out, &error);
  }
  if (!ok) throw py::value_error(error);
  py::dict d;
  d["time"] = out.point.t;
  d["seconds"] = out.seconds;
  if (out.has_equilibrium) {
    const auto& eq = out.equilibrium;
    py::dict e;
    e["iterations"] = eq.iterations;
    e["relaxation_steps"] = eq.relaxation_steps;
    e["residual"] = eq.residual;
    py::list moved;
    for (const auto& [name, change] : eq.moved) moved.append(py::make_tuple(name, change));
    e["moved"] = moved;
    d["equilibrium"] = e;
  } else {
    d["equilibrium"] = py::none();
  }
  if (!out.status.ok()) {
    const auto& s = out.status;
    d["failure"] = py::make_tuple(s.code, s.message, s.hint, s.where.file.str(), s.where.line, s.where.col);
    return d;
  }
  d["failure"] = py::none();
  const kanesim::lin::LinearModel& m = out.model;
  d["states"] = m.states;
  d["n_coordinates"] = m.n_coords;
  d["inputs"] = m.inputs;
  d["outputs"] = m.outputs;
  d["A"] = Matrix(m.A);
  d["B"] = Matrix(m.B);
  d["C"] = Matrix(m.C);
  d["D"] = Matrix(m.D);
  std::vector<std::complex<double>> lambdas;
  py::list modes;
  for (size_t k = 0; k < m.modes.size(); ++k) {
    const kanesim::lin::Mode& md = m.modes[k];
    lambdas.push_back(md.lambda);
    py::dict one;
    one["eigenvalue"] = md.lambda;
    one["natural_frequency"] = md.omega_n;
    one["frequency_hz"] = md.freq_hz;
    one["damping_ratio"] = md.zeta;
    py::list dom;
    for (const auto& [name, w] : md.dominant) dom.append(py::make_tuple(name, w));
    one["dominant"] = dom;
    one["shape"] = ComplexVector(md.shape, static_cast<size_t>(md.shape.size()));
    modes.append(one);
  }
  d["eigenvalues"] = ComplexVector(lambdas, lambdas.size());
  d["modes"] = modes;
  d["ignorable"] = m.ignorable;
  d["held"] = m.held;
  py::dict acc;
  acc["step"] = m.h;
  acc["A"] = m.error_A;
  acc["BCD"] = m.error_BCD;
  acc["unsteady"] = m.unsteady;
  py::dict widened;  // column -> the step used, where --step was below the rounding floor
  for (const kanesim::lin::WidenedStep& w : m.widened) widened[py::str(w.name)] = w.used;
  acc["widened"] = widened;
  d["accuracy"] = acc;
  return d;
}

}  // namespace

void BindSimulator(py::module_& m);  // python/src/stepping.cpp

PYBIND11_MODULE(_kanesim, m) {
  m.doc() = "kanesim's compiled core; use the kanesim package";
  py::class_<LoadedModel, std::shared_ptr<LoadedModel>>(m, "CompiledModel")
      .def_property_readonly("warnings", [](const LoadedModel& x) { return x.warnings; })
      .def_property_readonly("path", [](const LoadedModel& x) { return x.request.path; })
      .def_property_readonly("sets", [](const LoadedModel& x) { return x.request.sets; })
      .def("check", [](const LoadedModel& x) { return ToPython(kanesim::py::Value{std::make_shared<kanesim::py::Dict>(kanesim::py::Check(x))}); })
      .def("signals", [](const LoadedModel& x) { return kanesim::py::AvailableSignals(x); });
  m.def("load", &Load);
  m.def("run", &Run);
  m.def("sweep", &Sweep);
  m.def("linearize", &Linearize);
  BindSimulator(m);
  m.def("_layout_probe", &LayoutProbe);
  // The pybind11 this module was compiled with: before 2.12 it does not know NumPy 2.
  m.attr("_pybind11_version") = py::make_tuple(PYBIND11_VERSION_MAJOR, PYBIND11_VERSION_MINOR, PYBIND11_VERSION_PATCH);
}
