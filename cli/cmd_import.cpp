// `kanesim import robot.urdf [-o robot.mech] [--floating] [--limits stops|ignore] [--package-path DIR]...`: the URDF
// as a readable .mech file (import/import.h; docs/import.md). The same translation runs in
// memory when a command is given a .urdf file (pipeline/), so `run robot.urdf` and `run`
// of the file written here give the same rows.
#include <CLI/CLI.hpp>
#include <fmt/core.h>

#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>

#include "batch/batch.h"
#include "cli/common.h"
#include "import/import.h"

namespace kanesim::cli {

namespace {

struct ImportArgs {
  std::string path;
  std::string out_path;
  bool floating = false;
  bool stops = true;
  std::vector<std::string> package_paths;
};

int ImportCommand(const ImportArgs& a) {
  std::string text;
  std::error_code ec;
  if (const std::uintmax_t size = std::filesystem::file_size(a.path, ec); !ec && size > import::kMaxUrdfBytes) {
    std::cerr << import::TooLargeMessage(a.path, size);  // not read into memory
    return kExitModelError;
  }
  if (!ReadFileInto(a.path, &text)) {
    fmt::print(stderr, "kanesim: error: cannot read '{}'\n", a.path);
    return kExitModelError;
  }
  import::Options o;
  o.floating = a.floating;
  o.stops = a.stops;
  o.package_paths = a.package_paths;
  const bool to_stdout = a.out_path.empty() || a.out_path == "-";
  // Mesh names are written relative to the .mech file's folder, as MeshBody reads them.
  o.mesh_base_dir = std::filesystem::path(to_stdout ? a.path : a.out_path).parent_path().string();
  if (o.mesh_base_dir.empty()) o.mesh_base_dir = ".";
  import::Result r = import::UrdfToMech(a.path, text, o);
  std::cerr << r.diagnostics;
  if (!r.ok) return kExitModelError;
  if (to_stdout) {
    std::fwrite(r.mech.data(), 1, r.mech.size(), stdout);
    return std::fflush(stdout) == 0 ? kExitOk : kExitModelError;
  }
  if (std::string in = batch::OverwrittenInput(a.out_path, {a.path}); !in.empty()) {
    fmt::print(stderr, "kanesim: error: -o '{}' is the URDF '{}'; writing the model there would destroy it\n",
               a.out_path, in);
    return kExitModelError;
  }
  std::string error;
  if (!batch::WriteFileAtomic(a.out_path, r.mech, &error)) {
    fmt::print(stderr, "kanesim: error: {}\n", error);
    return kExitModelError;
  }
  return kExitOk;
}

}  // namespace

void AddUrdfOptions(CLI::App& cmd, bool* floating, bool* stops, std::vector<std::string>* package_paths) {
  cmd.add_flag("--floating", *floating, "A URDF file: give the root link a free base (FreeMotion) instead of fixing it");
  cmd.add_option_function<std::string>(
         "--limits", [stops](const std::string& v) { *stops = v == "stops"; },
         "A URDF file: joint <limit>s as end stops (stops, the default) or recorded only (ignore, as Pinocchio)")
      ->check(CLI::IsMember({"stops", "ignore"}));
  cmd.add_option("--package-path", *package_paths,
                 "A URDF file: a folder where package:// mesh names are looked up (repeatable; then ROS_PACKAGE_PATH)")
      ->allow_extra_args(false);
}

void AddImportCommand(CLI::App& app, int* exit_code, bool options) {
  CLI::App* cmd = app.add_subcommand("import", "Translate a URDF robot into a readable .mech model");
  if (!options) return;
  auto a = std::make_shared<ImportArgs>();
  cmd->add_option("file", a->path, "The URDF file")->required();
  cmd->add_option("-o,--out", a->out_path, "Write the model to FILE (default: stdout)");
  AddUrdfOptions(*cmd, &a->floating, &a->stops, &a->package_paths);
  cmd->callback([a, exit_code]() { *exit_code = ImportCommand(*a); });
}

}  // namespace kanesim::cli
