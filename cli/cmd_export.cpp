// `kanesim export model.mech --fmi 2|3 [--kind cs|me|both] [-o model.fmu]`: the model as a
// Functional Mock-up Unit (fmi/fmi.h; docs/fmi.md).
#include <CLI/CLI.hpp>
#include <fmt/core.h>

#include <filesystem>
#include <memory>

#include "cli/common.h"
#include "fmi/fmi.h"

namespace kanesim::cli {
namespace {

struct ExportArgs {
  LoadOptions load;
  int fmi = 2;
  std::string kind = "both";
  std::string out_path;
  std::string integrator = "auto";
};

int ExportCommand(const ExportArgs& a) {
  if (std::filesystem::path(a.load.path).extension() == ".urdf") {
    fmt::print(stderr, "kanesim: error: export takes a .mech file; translate a URDF first with `kanesim import`\n");
    return kExitModelError;
  }
  pipeline::RunSpec spec;
  pipeline::IntegratorFromName(a.integrator, &spec.integrator);
  std::unique_ptr<pipeline::Model> model = LoadAndCompile(a.load, spec);
  if (!model) return kExitModelError;
  fmi::ExportOptions o;
  o.version = a.fmi;
  o.model_exchange = a.kind != "cs";
  o.co_simulation = a.kind != "me";
  o.model = a.load.model;
  o.sets = a.load.sets;
  o.integrator = a.integrator == "auto" ? "" : a.integrator;
  o.output = a.out_path.empty() ? fmi::Identifier(model->mech->model_name) + ".fmu" : a.out_path;
  if (std::string error = fmi::ExportFmu(*model, ReadFileText(a.load.path), o); !error.empty()) {
    fmt::print(stderr, "kanesim: error: {}\n", error);
    return kExitModelError;
  }
  return kExitOk;
}

}  // namespace

void AddExportCommand(CLI::App& app, int* exit_code, bool options) {
  CLI::App* cmd = app.add_subcommand("export", "Export a model as an FMU (FMI 2.0 or 3.0; Model Exchange and Co-Simulation)");
  if (!options) return;
  auto a = std::make_shared<ExportArgs>();
  cmd->add_option("file", a->load.path, "The .mech file")->required();
  cmd->add_option("-m,--model", a->load.model, "The model to export (default: the last in the file)");
  cmd->add_option("--set", a->load.sets, "name=value: a parameter's value at export: a structural one is fixed with it, another starts there")
      ->allow_extra_args(false);
  cmd->add_option("--fmi", a->fmi, "The FMI version")->check(CLI::IsMember({2, 3}))->required();
  cmd->add_option("--kind", a->kind, "The interfaces: cs (Co-Simulation), me (Model Exchange) or both")
      ->check(CLI::IsMember({"cs", "me", "both"}));
  cmd->add_option("--integrator", a->integrator, "Co-Simulation's integrator inside each step")
      ->check(CLI::IsMember(pipeline::IntegratorNames()));
  cmd->add_option("-o,--out", a->out_path, "The FMU file (default: <model>.fmu)");
  cmd->callback([a, exit_code]() { *exit_code = ExportCommand(*a); });
}

}  // namespace kanesim::cli
