// kanesim: the command line. Subcommands register themselves; only main picks exit codes.
#include <CLI/CLI.hpp>

#include <cstdio>
#include <cstring>
#include <new>

#ifdef __GLIBC__
#include <malloc.h>
#endif

#include "cli/cmd_linearize.h"
#include "cli/common.h"
#include "cli/scene.h"

int main(int argc, char** argv) {
#ifdef __GLIBC__
  // Fresh memory is the front end's largest cost after its instructions (each new page
  // 1.5-4 us here, docs/benchmarks/2026-11-29_front_end_pass7.md). By default malloc maps
  // each block over 128 KB apart and unmaps it when freed, so every doubling of a large
  // vector (the expression pool, the parameters, the tokens) touches new pages and the old
  // ones are given back; on the heap they are reused by what is allocated next.
  mallopt(M_MMAP_THRESHOLD, 32 << 20);
  mallopt(M_TRIM_THRESHOLD, 64 << 20);
#endif
  CLI::App app{"kanesim: mechanisms in a Modelica-like language, simulated by Kane's method"};
  app.set_version_flag("--version", std::string("kanesim ") + KANESIM_VERSION);
  app.require_subcommand(1);
  int exit_code = kanesim::cli::kExitOk;
  // Every subcommand by name and description (all the top level's help and errors need);
  // the options only of the one named on the command line, its first word not starting
  // with '-' (the top level has flags only). Registering every option of every command
  // was ~1.2 M instructions of each process start (sweep's alone 0.5 M).
  struct Command {
    const char* name;
    void (*add)(CLI::App&, int*, bool);
  };
  const Command commands[] = {{"check", kanesim::cli::AddCheckCommand},   {"run", kanesim::cli::AddRunCommand},
                              {"sweep", kanesim::cli::AddSweepCommand},   {"test", kanesim::cli::AddTestCommand},
                              {"linearize", kanesim::cli::AddLinearizeCommand}, {"view", kanesim::cli::AddViewCommand},
                              {"import", kanesim::cli::AddImportCommand},
                              {"export", kanesim::cli::AddExportCommand},
                              {"units", kanesim::cli::AddUnitsCommand}};
  const char* named = "";
  for (int i = 1; i < argc && !*named; ++i)
    if (argv[i][0] != '-') named = argv[i];
  for (const Command& c : commands) c.add(app, &exit_code, std::strcmp(named, c.name) == 0);
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
