// kanesim: the command line. Subcommands register themselves; only main picks exit codes.
#include <CLI/CLI.hpp>

#include <cstdio>
#include <new>

#include "cli/cmd_linearize.h"
#include "cli/common.h"
#include "cli/scene.h"

int main(int argc, char** argv) {
  CLI::App app{"kanesim: mechanisms in a Modelica-like language, simulated by Kane's method"};
  app.set_version_flag("--version", std::string("kanesim ") + KANESIM_VERSION);
  app.require_subcommand(1);
  int exit_code = kanesim::cli::kExitOk;
  kanesim::cli::AddCheckCommand(app, &exit_code);
  kanesim::cli::AddRunCommand(app, &exit_code);
  kanesim::cli::AddSweepCommand(app, &exit_code);
  kanesim::cli::AddTestCommand(app, &exit_code);
  kanesim::cli::AddLinearizeCommand(app, &exit_code);
  kanesim::cli::AddViewCommand(app, &exit_code);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    int rc = app.exit(e);
    return rc == 0 ? kanesim::cli::kExitOk : kanesim::cli::kExitModelError;
  } catch (const std::bad_alloc&) {
    // A last resort: the front end's limits (docs/language.md) keep models within memory.
    std::fprintf(stderr,
                 "kanesim: error: out of memory\n"
                 "  hint: a smaller model, or more memory; the limits are in docs/language.md\n");
    return kanesim::cli::kExitModelError;
  }
  return exit_code;
}
