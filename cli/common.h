// Shared plumbing for the kanesim subcommands: loading a model (parse, elaborate,
// print diagnostics) and the exit codes. Only the CLI links every layer.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "runtime/engine.h"
#include "runtime/flat/mechanism.h"
#include "runtime/sim/integrator.h"

namespace CLI {
class App;
}

namespace kanesim::cli {

// Exit codes (DESIGN.md "The command line").
inline constexpr int kExitOk = 0;
inline constexpr int kExitModelError = 1;    // model or usage error, with a diagnostic
inline constexpr int kExitNumerical = 2;     // numerical failure, output so far kept
inline constexpr int kExitRegression = 3;    // `kanesim test` found a regression

struct LoadOptions {
  std::string path;                                      // the .mech file
  std::string model;                                     // model to elaborate ("" = last in file)
  std::vector<std::string> sets;                         // "name=value" from --set
  std::vector<std::string> stdlib_dirs;                  // extra search paths
};

// The most threads -j may ask for.
inline constexpr int kMaxJobs = 1024;

// A file's bytes ("" when it cannot be read), and the hash of the embedded standard
// library: what provenance lines and sweep settings records are made of.
std::string ReadFileText(const std::string& path);
std::string StdlibHash();

// Parses and elaborates; on error prints diagnostics to stderr and returns false.
bool LoadModel(const LoadOptions& options, flat::Mechanism* out);

// Compiles; on error prints compile diagnostics (with source lines) and returns false.
bool CompileModel(const flat::Mechanism& mech, const rt::CompileOptions& options, rt::CompileResult* out);

// Prints a compiler message like a language diagnostic: "file:line:col: SEVERITY[CODE]:
// message", the source line with a caret, notes, hint.
void PrintCompileMessage(const rt::CompileMessage& message, const char* severity);

// Warning W313 on stderr when `signals` (the selected output) holds statically
// indeterminate constraint-force components that are written as NaN.
void WarnIndeterminate(const rt::Program& program, const std::vector<std::string>& signals);

// `--reactions nan|min-norm` (run, sweep) into CompileOptions::indeterminate.
bool ReactionsFromName(const std::string& name, rt::CompileOptions* options);

// `--linear-solver auto|dense|klu` (run, sweep): IDA's Newton matrix.
inline sim::IdaLinearSolver IdaLinearSolverFromName(const std::string& name) {
  if (name == "dense") return sim::IdaLinearSolver::Dense;
  if (name == "klu") return sim::IdaLinearSolver::Klu;
  return sim::IdaLinearSolver::Auto;
}

// `--projection eval|step` (run, sweep): SimOptions::project_steps.
inline constexpr const char* kProjectionHelp =
    "Closed loops and contacts with --integrator dop853: project onto the constraints at every evaluation "
    "(eval) or once per accepted step (step: cheaper evaluations, a larger error at the same tolerance)";

// Registers subcommands; each returns through `*exit_code` after it ran.
void AddCheckCommand(CLI::App& app, int* exit_code);
void AddRunCommand(CLI::App& app, int* exit_code);
void AddSweepCommand(CLI::App& app, int* exit_code);  // cmd_sweep.cpp
void AddTestCommand(CLI::App& app, int* exit_code);   // cmd_test.cpp

}  // namespace kanesim::cli
