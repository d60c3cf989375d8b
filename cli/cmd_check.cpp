// `kanesim check file.mech`: diagnostics, or a summary of the mechanism and of what the
// compiler decided for it. `--emit ast|flat` prints an intermediate form instead.
#include <CLI/CLI.hpp>
#include <fmt/core.h>

#include <iostream>
#include <memory>
#include <vector>

#include "cli/common.h"
#include "cli/scene.h"
#include "lang/ast.h"
#include "lang/elaborate.h"
#include "lang/parser.h"
#include "stdlib/stdlib.h"
#include "compiler/compiler.h"
#include "sim/diagonal_speeds.h"

namespace kanesim::cli {

namespace {

struct CheckArgs {
  LoadOptions load;
  std::string emit;
  std::string solver = "auto";
  std::string speeds;                          // --speeds diagonal: print Lesser's construction ("": the model's)
  std::vector<std::string> speed_order;        // --speed-order
};


// Grübler-style count: 6 per body, minus 6 - f per joint (spatial mechanisms).
int GrublerCount(const flat::Mechanism& m, int bodies) {
  int dof = 6 * bodies;
  for (const auto& j : m.joints) dof -= 6 - j.nu();
  return dof;
}

int RunCheck(const CheckArgs& args) {
  if (args.emit == "ast") {
    lang::Program program;
    lang::Diagnostics diags(&program.sources);
    bool ok = lang::LoadProgram(args.load.path, {}, &program, diags);
    std::cerr << diags.RenderAll();
    if (!ok || diags.HasErrors()) return kExitModelError;
    std::cout << lang::ast::Dump(*program.files[0]);
    return kExitOk;
  }
  pipeline::RunSpec spec;
  pipeline::SolverFromName(args.solver, &spec.solver);
  std::unique_ptr<pipeline::Model> model = LoadAndCompile(args.load, spec, args.emit != "flat");
  if (!model) return kExitModelError;
  const flat::Mechanism& mech = *model->mech;
  if (args.emit == "flat") {
    std::cout << flat::DumpFlat(mech);
    return kExitOk;
  }
  const rt::Program& program = *model->program;
  rt::ProgramSummary s = rt::Summarize(program);

  std::cout << fmt::format("model {}", mech.model_name);
  if (!mech.description.empty()) std::cout << fmt::format(" \"{}\"", mech.description);
  std::cout << "\n";
  std::cout << fmt::format("  bodies      {} (after merging welded parts; {} Body components)\n", s.num_bodies,
                           mech.bodies.size());
  std::cout << fmt::format("  joints      {}\n", s.num_joints);
  for (const auto& j : mech.joints) {
    std::cout << fmt::format("    {:<20} {}", j.name, flat::JointTypeName(j.type));
    if (j.type == flat::JointType::Spherical || j.type == flat::JointType::Free)
      std::cout << fmt::format(" ({})", flat::RotationCoordsName(j.rotation));
    bool prescribed = false;
    for (auto p : j.prescribed) prescribed = prescribed || p != flat::kNoExpr;
    if (prescribed) std::cout << "  prescribed";
    if (j.cut) std::cout << "  cut";
    std::cout << "\n";
  }
  std::cout << fmt::format("  coordinates q: {}, speeds u: {}\n", s.nq, s.nu);
  std::cout << fmt::format("  degrees of freedom {} (Gruebler count {})\n", s.dof, s.grubler_dof);
  if (!s.cut_joints.empty()) {
    std::cout << "  loop cuts  ";
    for (const auto& c : s.cut_joints) std::cout << " " << c;
    std::cout << "\n";
  }
  std::cout << fmt::format("  constraints {} contact(s), {} joint coupling(s), {} line force(s), {} applied wrench(es)\n",
                           mech.contacts.size(), mech.couplings.size(), mech.line_forces.size(), mech.wrenches.size());
  std::cout << fmt::format("  solver      {} — {}\n", pipeline::SolverName(s.solver), s.solver_reason);
  std::cout << fmt::format("  integrator  {} — {}\n", pipeline::IntegratorName(s.integrator), s.integrator_reason);
  if (!s.equations.empty()) std::cout << "  equations   " << s.equations << "\n";
  if (rt::StepProjectionAvailable(program)) {
    // The projection of closed loops and rolling contacts (docs/constraints.md, "Projecting
    // once per step"; numbers of the four-bar in docs/benchmarks.md). Eval stays the
    // default: its error follows the tolerance.
    std::cout << "  projection  eval — Newton onto the constraints at every evaluation of f, so the error "
                 "follows the tolerance; `--projection step` (DOP853) projects once per accepted step "
                 "instead and takes positions and speeds as they are in between: an evaluation costs "
                 "about half and the same error is reached in 0.4-0.7x the time on the four-bar, but "
                 "the error per tolerance is up to 20x larger (docs/constraints.md)\n";
  }
  if (s.integrator == rt::Integrator::IDA) {
    // IDA's Newton matrix: the block pattern and the automatic dense/KLU choice
    // (docs/integrators.md; the same rule as sim/integrator_ida.cpp).
    std::vector<int> groups = rt::StateCouplingGroups(program);
    std::vector<long> size;
    for (int g : groups) {
      if (static_cast<size_t>(g) >= size.size()) size.resize(static_cast<size_t>(g) + 1, 0);
      ++size[static_cast<size_t>(g)];
    }
    long n = static_cast<long>(groups.size()), nnz = 0;
    for (long b : size) nnz += b * b;
    double fill = n > 0 ? static_cast<double>(nnz) / (static_cast<double>(n) * static_cast<double>(n)) : 1.0;
    bool klu = n >= sim::kKluMinStates && fill <= sim::kKluMaxFill;
    std::cout << fmt::format("  newton      {} — {} states in {} coupling group(s), Jacobian fill {:.3g} ({} KLU: n >= {} "
                             "and fill <= {})\n",
                             klu ? "KLU" : "dense LU", n, size.size(), fill, klu ? "so" : "not", sim::kKluMinStates,
                             sim::kKluMaxFill);
  }
  if (args.speeds == "diagonal" || (args.speeds.empty() && mech.experiment.diagonal_speeds)) {
    if (std::string why = sim::DiagonalSpeedsRefusal(program); !why.empty()) {
      fmt::print(stderr, "kanesim: error: {}\n", why);
      return kExitModelError;
    }
    std::string error;
    std::vector<int> order =
        sim::SpeedOrder(program, args.speed_order.empty() ? mech.experiment.speed_order : args.speed_order, &error);
    if (order.empty()) {
      fmt::print(stderr, "kanesim: error: {}\n", error);
      return kExitModelError;
    }
    std::cout << "  " << sim::DescribeConstruction(program, order);
  }
  for (const auto& n : s.notes) std::cout << "  note: " << n << "\n";
  if (rt::CompileMessage f = rt::FrictionIndeterminateWarning(program); !f.message.empty())
    std::cout << fmt::format("  warning[{}]: {}\n", flat::DiagCodeString(f.code), f.message);
  if (rt::CompileMessage w = rt::StartSpeedsWarning(program); !w.message.empty())
    std::cout << fmt::format("  warning[{}]: {}\n", flat::DiagCodeString(w.code), w.message);
  for (const rt::CompileMessage& w : rt::LockedJointWarnings(program))
    std::cout << fmt::format("  warning[{}]: {} ({}:{}:{})\n", flat::DiagCodeString(w.code), w.message, w.loc.file.str(),
                             w.loc.line, w.loc.col);
  // Only redundant constraints leave signals indeterminate: without them, listing every
  // signal's name (a fifth of a robot's `check`) is skipped.
  const std::vector<std::string> indeterminate =
      program.redundant_rows.empty() ? std::vector<std::string>{}
                                     : rt::IndeterminateSignals(program, rt::AvailableSignals(program));
  if (!indeterminate.empty()) {
    std::cout << fmt::format("  indeterminate constraint-force components ({}; `kanesim run` writes them as nan, "
                             "`--reactions min-norm` as the minimum-norm share):\n",
                             indeterminate.size());
    for (const auto& n : indeterminate) std::cout << "    " << n << "\n";
  }
  const auto& x = mech.experiment;
  std::cout << fmt::format("  experiment  StartTime={} StopTime={} Tolerance={}{}\n", x.start_time, x.stop_time,
                           x.tolerance, x.has_interval ? fmt::format(" Interval={}", x.interval) : "");
  // The model's own parameters (declared in its file); the standard library's internal
  // ones are counted only (`--emit flat` lists them all).
  size_t own = 0;
  for (const auto& p : mech.params) own += p.loc.file == args.load.path;
  std::cout << fmt::format("  parameters  {} in the model ({} in all)\n", own, mech.params.size());
  for (size_t i = 0; i < mech.params.size(); ++i) {
    const flat::Param& p = mech.params[i];
    if (p.loc.file != args.load.path) continue;
    std::string value = p.type == flat::ParamType::String ? "\"" + p.string_value + "\"" : fmt::format("{:.10g}", p.value);
    std::cout << fmt::format("    {:<28} = {:<14}{}{}\n", mech.ParamName(i), value, p.unit.empty() ? "" : " [" + p.unit + "]",
                             p.structural ? "  (structural)" : "");
  }
  PrintMeshBodies(mech, std::cout);
  std::cout << fmt::format("  outputs     {}\n", mech.outputs.size());
  for (const auto& o : mech.outputs) std::cout << "    " << o.name << "\n";
  (void)GrublerCount;
  LeaveToExit(std::move(model));
  return kExitOk;
}

}  // namespace

void AddCheckCommand(CLI::App& app, int* exit_code, bool options) {
  auto args = std::make_shared<CheckArgs>();
  args->load.leave_to_exit = true;  // one model, then the process ends
  CLI::App* cmd = app.add_subcommand("check", "Check a model: diagnostics, or a summary of the mechanism");
  if (!options) return;  // only its name and description (main.cpp)
  cmd->add_option("file", args->load.path, "The .mech file")->required();
  cmd->add_option("--model", args->load.model, "Model to check (default: the last model in the file)");
  AddUrdfOptions(*cmd, &args->load.floating, &args->load.stops, &args->load.package_paths);
  cmd->add_option("--set", args->load.sets, "Override a parameter: name=value (repeatable)");
  cmd->add_option("--emit", args->emit, "Print an intermediate form instead: ast or flat")
      ->check(CLI::IsMember({"ast", "flat"}));
  cmd->add_option("--solver", args->solver, "Solution path to report: auto, dense, sparse or recursive")
      ->check(CLI::IsMember(pipeline::SolverNames()));
  cmd->add_option("--speeds", args->speeds, kSpeedsHelp)->check(CLI::IsMember({"joint", "diagonal"}));
  cmd->add_option("--speed-order", args->speed_order, kSpeedOrderHelp)->delimiter(',')->allow_extra_args(false);
  cmd->callback([args, exit_code]() { *exit_code = RunCheck(*args); });
}

}  // namespace kanesim::cli
