// `kanesim view file.mech [run options] [--port N] [--html out.html]`: runs the model and
// shows the motion in the browser (viz): the bodies drawn as their shapes beside
// time plots of the signals, served on 127.0.0.1 or written as one offline page
// (docs/visualization.md, "kanesim view").
//
// The run options are those of `kanesim run` that decide the motion (times, tolerances,
// integrator, solver, --set), resolved the same way: command line, else the model's
// experiment annotation, else the defaults. --output chooses the plotted signals (default:
// the joints' coordinates and speeds, the model's outputs and the energies).
#include <CLI/CLI.hpp>
#include <fmt/core.h>

#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>

#include "cli/common.h"
#include "cli/number_options.h"
#include "cli/scene.h"
#include "cli/signal_units.h"
#include "batch/file_guard.h"
#include "flat/number.h"
#include "geometry/primitives.h"
#include "pipeline/pipeline.h"
#include "sim/signal_select.h"
#include "sim/simulate.h"
#include "viz/server.h"
#include "viz/viewer.h"

namespace kanesim::cli {
namespace {

struct ViewArgs {
  LoadOptions load;
  pipeline::RunSpec spec;  // times and tolerances (NaN: not given), resolved like `kanesim run`
  std::vector<std::string> patterns;
  std::string solver = "auto";
  std::string integrator = "auto";
  std::string energy_check = "on";  // --energy-check (RunSpec::energy_check)
  std::string html;      // --html out.html: write the offline page instead of serving
  int port = 0;          // --port: 0 = any free port
  double timeout = 0;    // --timeout: stop serving after this many seconds (0: at Ctrl-C)
  bool show_frames = false;  // --show-frames: every joint's frames as small axes
};

// The longest --timeout: a week. A larger number is a mistake (a unit typed wrong), and its
// double would overflow the server's clock arithmetic.
constexpr double kMaxTimeout = 7 * 24 * 3600.0;

// --timeout SECONDS: a number in (0, kMaxTimeout], read with the language's number syntax
// (nan, inf, hex refused); anything else is a usage error (exit 1) that says the range.
void AddTimeoutOption(CLI::App* cmd, double* target) {
  cmd->add_option_function<std::string>(
         "--timeout",
         [target](const std::string& text) {
           std::string why;
           double v = 0;
           if (!flat::ParseNumber(text, &v, &why)) throw CLI::ValidationError("--timeout", why);
           if (!(v > 0) || v > kMaxTimeout)
             throw CLI::ValidationError("--timeout", fmt::format("'{}' is not a number of seconds in (0, {:.0f}] (a "
                                                                 "week); leave it out to serve until Ctrl-C",
                                                                 text, kMaxTimeout));
           *target = v;
         },
         "Stop serving after this many seconds, in (0, 604800] (default: at Ctrl-C)")
      ->type_name("SECONDS");
}

// The page never goes over one of the model's files (run -o, --animation and linearize
// refuse the same); "" or the input it would destroy.
std::string HtmlOverInput(const std::string& html, const std::vector<std::string>& inputs) {
  return html.empty() ? "" : batch::OverwrittenInput(html, inputs);
}

// Ground grids under the rolling contacts' planes (one per distinct plane).
void AddContactPlanes(const flat::Mechanism& mech, viz::ViewerScene* scene) {
  const std::vector<double> p = flat::EvaluateParams(mech);
  auto val = [&](flat::ExprId e) { return e == flat::kNoExpr ? 0.0 : flat::EvalParamExpr(mech, p, e); };
  std::vector<std::pair<geometry::Vec3, double>> done;  // planes drawn: unit normal n, offset n·o
  for (const auto& c : mech.contacts) {
    geometry::Vec3 n(val(c.plane_normal[0]), val(c.plane_normal[1]), val(c.plane_normal[2]));
    const geometry::Vec3 o(val(c.plane_point[0]), val(c.plane_point[1]), val(c.plane_point[2]));
    if (!n.allFinite() || n.norm() == 0 || !o.allFinite()) continue;
    n.normalize();
    bool seen = false;
    for (const auto& [dn, dd] : done) seen = seen || ((dn - n).norm() < 1e-9 && std::fabs(dd - n.dot(o)) < 1e-9);
    if (seen) continue;
    done.push_back({n, n.dot(o)});
    viz::ViewerDecoration grid;
    grid.name = "ground (" + c.name + ")";
    grid.mesh = geometry::DrawGrid(n, 5.0, 0.5, 0.01);
    geometry::Transform(grid.mesh, geometry::Mat3::Identity(), n * n.dot(o));
    scene->decorations.push_back(std::move(grid));
  }
}

int RunView(const ViewArgs& a) {
  // An output is never an input: refused before any work, and again below against every
  // file the model read (imports).
  if (std::string in = HtmlOverInput(a.html, {a.load.path}); !in.empty()) {
    fmt::print(stderr, "kanesim: error: --html '{}' is the model '{}'; writing there would destroy it\n", a.html, in);
    return kExitModelError;
  }
  // The pipeline's stages 1-4, as `kanesim run` calls them (pipeline/pipeline.h).
  pipeline::RunSpec spec = a.spec;
  pipeline::SolverFromName(a.solver, &spec.solver);
  pipeline::IntegratorFromName(a.integrator, &spec.integrator);
  pipeline::EnergyCheckFromName(a.energy_check, &spec.energy_check);
  spec.outputs = a.patterns;
  std::unique_ptr<pipeline::Model> model = LoadAndCompile(a.load, spec);
  if (!model) return kExitModelError;
  const flat::Mechanism& mech = *model->mech;
  const rt::Program& program = *model->program;
  if (std::string in = HtmlOverInput(a.html, mech.source_files); !in.empty()) {
    fmt::print(stderr, "kanesim: error: --html '{}' is the model file '{}'; writing there would destroy it\n", a.html,
               in);
    return kExitModelError;
  }
  pipeline::ResolvedRun run;
  pipeline::RunProblem problem = pipeline::RunProblem::kNone;
  if (std::string why = pipeline::ResolveRun(*model, spec, &run, &problem); !why.empty()) {
    fmt::print(stderr, "kanesim: error: {}{}\n", problem == pipeline::RunProblem::kValue ? "--" : "", why);
    return kExitModelError;
  }
  std::cerr << pipeline::RunWarnings(*model, run.sim.rtol, run.sim.signals);
  sim::SimOptions& so = run.sim;
  if (so.signals.empty()) {
    so.signals = rt::DefaultSignals(program);
    so.signals.push_back("kinetic_energy");
    so.signals.push_back("potential_energy");
  }

  SceneBodies bodies;
  std::string error;
  if (!BuildSceneBodies(mech, program, &bodies, &error, a.show_frames)) {
    fmt::print(stderr, "kanesim: error: {}\n", error);
    return kExitModelError;
  }
  const size_t n_shown = so.signals.size();
  so.signals.insert(so.signals.end(), bodies.pose_signals.begin(), bodies.pose_signals.end());
  PoseRecorder recorder(nullptr, n_shown, bodies.bodies.size(), true);
  const sim::SimResult result = pipeline::Run(*model, run, recorder);  // stages 5-6
  if (result.status == sim::SimResult::Status::kUsageError || result.status == sim::SimResult::Status::kOutputError) {
    fmt::print(stderr, "kanesim: error: {}\n", result.message);
    return kExitModelError;
  }
  const bool failed = result.status == sim::SimResult::Status::kNumericalFailure;
  if (failed)
    fmt::print(stderr, "kanesim: numerical failure at t = {}: {} (showing the motion up to there)\n", result.fail_time,
               result.message);
  if (recorder.poses().times.empty()) {
    fmt::print(stderr, "kanesim: error: no instant was computed; nothing to show\n");
    return failed ? kExitNumerical : kExitModelError;
  }

  viz::ViewerScene scene;
  scene.title = mech.model_name;
  scene.up_W = bodies.up_W;
  for (size_t b = 0; b < bodies.bodies.size(); ++b) {
    viz::ViewerBody vb;
    vb.name = bodies.bodies[b].name;
    vb.label = bodies.labels[b];
    vb.mesh = bodies.bodies[b].mesh;
    vb.rgba = bodies.bodies[b].rgba;
    scene.bodies.push_back(std::move(vb));
  }
  AddContactPlanes(mech, &scene);
  scene.poses = recorder.poses();
  const size_t n_times = scene.poses.times.size();
  for (size_t i = 0; i < n_shown; ++i) {
    viz::ViewerSignal s;
    s.name = recorder.shown_names()[i];
    s.unit = SignalUnit(mech, s.name);  // the CSV header's units (--units-in-header)
    s.values.resize(n_times);
    for (size_t k = 0; k < n_times; ++k) s.values[k] = recorder.shown_values()[k * n_shown + i];
    scene.signals.push_back(std::move(s));
  }
  for (const sim::EventRecord& e : result.stats.events) scene.events.push_back({e.time, e.element, e.kind});
  const int done = failed ? kExitNumerical : kExitOk;

  if (!a.html.empty()) {
    const viz::PageResult r = viz::WriteViewerHtml(scene, a.html);
    if (!r.ok) {
      fmt::print(stderr, "kanesim: error: {}\n", r.error);
      return kExitModelError;
    }
    fmt::print(stderr, "kanesim: wrote {} ({} bodies, {} instants{}, {:.1f} MB); open it in a browser\n", a.html,
               scene.bodies.size(), r.instants, r.stride > 1 ? fmt::format(", every {}th", r.stride) : "",
               static_cast<double>(r.bytes) / 1e6);
    return done;
  }
  viz::ServeOptions options;
  options.port = a.port;
  options.timeout_s = a.timeout;
  options.on_ready = [&](const std::string& url) {
    fmt::print("kanesim: serving {} at {} (Ctrl-C to stop)\n", mech.model_name, url);
    std::fflush(stdout);
  };
  const viz::ServeResult r = viz::ServeViewer(scene, options);
  if (!r.ok) {
    fmt::print(stderr, "kanesim: error: {}\n", r.error);
    return kExitModelError;
  }
  return done;
}

}  // namespace

void AddViewCommand(CLI::App& app, int* exit_code, bool options) {
  auto a = std::make_shared<ViewArgs>();
  CLI::App* cmd = app.add_subcommand("view", "Simulate a model and show the motion and plots in the browser");
  if (!options) return;  // only its name and description (main.cpp)
  cmd->add_option("file", a->load.path, "The .mech file")->required();
  cmd->add_option("--model", a->load.model, "Model to simulate (default: the last one in the file)");
  AddUrdfOptions(*cmd, &a->load.floating, &a->load.stops, &a->load.package_paths);
  cmd->add_option("--set", a->load.sets, "Set a parameter, name=value (repeatable)")->allow_extra_args(false);
  AddNumberOption(cmd, "--start-time", &a->spec.start_time, "Start time (default: experiment StartTime)");
  AddNumberOption(cmd, "--stop-time", &a->spec.stop_time, "Stop time (default: experiment StopTime)");
  AddNumberOption(cmd, "--interval", &a->spec.interval,
                  "Output interval (default: experiment Interval, else (stop - start) / 500)");
  AddNumberOption(cmd, "--rtol", &a->spec.rtol, "Relative tolerance (default: experiment Tolerance)");
  AddNumberOption(cmd, "--atol", &a->spec.atol, "Absolute tolerance (default: = rtol)");
  cmd->add_option("--output", a->patterns,
                  "Signals to plot: a glob over dotted names (repeatable; default: joint coordinates and speeds, "
                  "outputs, energies)")
      ->allow_extra_args(false);
  cmd->add_option("--solver", a->solver, "Solution path")->check(CLI::IsMember(pipeline::SolverNames()));
  cmd->add_option("--integrator", a->integrator, "Time integrator")
      ->check(CLI::IsMember(pipeline::IntegratorNames()));
  cmd->add_option("--energy-check", a->energy_check, kEnergyCheckHelp)
      ->check(CLI::IsMember(pipeline::EnergyCheckNames()));
  cmd->add_flag("--show-frames", a->show_frames, "Draw every joint's frames as small x/y/z axes");
  cmd->add_option("--html", a->html, "Write one offline page (opens by double-click) instead of serving");
  AddIntegerOption(cmd, "--port", &a->port, 0, 65535, "Serve on this port of 127.0.0.1 (default: any free port)");
  AddTimeoutOption(cmd, &a->timeout);
  cmd->callback([a, exit_code] { *exit_code = RunView(*a); });
}

}  // namespace kanesim::cli
