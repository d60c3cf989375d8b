// Shared plumbing for the kanesim subcommands: loading a model (parse, elaborate,
// print diagnostics) and the exit codes. Only the CLI links every layer.
#pragma once

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "runtime/runtime.h"
#include "flat/mechanism.h"
#include "pipeline/pipeline.h"
#include "sim/input_table.h"
#include "sim/integrator.h"

namespace CLI {
class App;
}

namespace kanesim::cli {

// Exit codes (DESIGN.md "The command line").
inline constexpr int kExitOk = 0;
inline constexpr int kExitModelError = 1;    // model or usage error, with a diagnostic
inline constexpr int kExitNumerical = 2;     // numerical failure, output so far kept
inline constexpr int kExitRegression = 3;    // `kanesim test` found a regression

// What a command names to load: the .mech file, the model in it, the --set values.
struct LoadOptions {
  std::string path;                                      // the .mech file
  std::string model;                                     // model to elaborate ("" = last in file)
  std::vector<std::string> sets;                         // "name=value" from --set
  bool floating = false;                                 // a URDF file: --floating (a free base)
  bool stops = true;                                     // a URDF file: --limits stops|ignore
  std::vector<std::string> package_paths;                // a URDF file: --package-path
  std::vector<std::string> input_files;                  // --input-file: tables of the model's inputs
  bool leave_to_exit = false;  // loaded once, the process ends after: pipeline::LoadOptions::leave_to_exit
};

// The most threads -j may ask for.
inline constexpr int kMaxJobs = 1024;

// A file's bytes ("" when it cannot be read), and the hash of the embedded standard
// library: what provenance lines and sweep settings records are made of.
std::string ReadFileText(const std::string& path);
bool ReadFileInto(const std::string& path, std::string* out);  // false when it cannot be read
std::string StdlibHash();

// Stages 1-3 of the pipeline (pipeline/pipeline.h) for a command: loads, prints
// the diagnostics (warnings too) to stderr; null when a stage failed. With compile false,
// the model stops at the flat mechanism.
std::unique_ptr<pipeline::Model> LoadAndCompile(const LoadOptions& options, const pipeline::RunSpec& spec,
                                                bool compile = true);

// The process ends after the command and its memory goes with it: freeing the model piece by
// piece (a fourteenth of a robot's `check`, 2 % of a robot's `run`) is skipped. It stays
// reachable from a static, so leak checkers do not count it. The model, kept.
const pipeline::Model& LeaveToExit(std::unique_ptr<pipeline::Model> model);

// `--energy-check on|off|report` (run, sweep): RunSpec::energy_check.
inline constexpr const char* kEnergyCheckHelp =
    "Conservative models: stop with exit 2 where the total energy T + V drifts beyond the tolerance's "
    "reach (on), never (off), or only measure it for --stats (report)";
// `--projection eval|step` (run, sweep): RunSpec::project_steps.
inline constexpr const char* kProjectionHelp =
    "Closed loops and contacts with --integrator dop853: project onto the constraints at every evaluation "
    "(eval) or once per accepted step (step: cheaper evaluations, a larger error at the same tolerance)";

// The model's inputs (docs/cli.md "Input tables"): every --input-file read into *table, each
// input given by one, the tables covering [start, stop]. False after printing the error to
// stderr; an input without a value is named at its declaration (file:line:col).
bool LoadInputTables(const pipeline::Model& model, const std::vector<std::string>& files, double start, double stop,
                     sim::InputTable* table);
// --input-file (run, sweep, test).
void AddInputFileOption(CLI::App& cmd, std::vector<std::string>* files);
// `--speeds joint|diagonal` and `--speed-order` (run, check): RunSpec::speeds.
inline constexpr const char* kSpeedsHelp =
    "Generalized speeds to integrate in: joint (the joints' own), or diagonal (Lesser's: Gram-Schmidt of the "
    "partial velocities in the kinetic metric, w = L^T u with M = L D L^T; adds columns w[i], d[i], T_w[i])";
inline constexpr const char* kSpeedOrderHelp =
    "With --speeds diagonal: joints whose speeds are orthogonalized first, in this order (comma-separated); "
    "the others follow root to leaf";

// Registers subcommands; each returns through `*exit_code` after it ran.
void AddCheckCommand(CLI::App& app, int* exit_code, bool options = true);
void AddRunCommand(CLI::App& app, int* exit_code, bool options = true);
void AddSweepCommand(CLI::App& app, int* exit_code, bool options = true);  // cmd_sweep.cpp
void AddTestCommand(CLI::App& app, int* exit_code, bool options = true);   // cmd_test.cpp
void AddExportCommand(CLI::App& app, int* exit_code, bool options = true);  // cmd_export.cpp
void AddImportCommand(CLI::App& app, int* exit_code, bool options = true);  // cmd_import.cpp
void AddUnitsCommand(CLI::App& app, int* exit_code, bool options = true);   // cmd_units.cpp
// --floating, --limits and --package-path, for every command that loads a model (a URDF file).
void AddUrdfOptions(CLI::App& cmd, bool* floating, bool* stops, std::vector<std::string>* package_paths);

}  // namespace kanesim::cli
