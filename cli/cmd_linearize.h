// `kanesim linearize` (cmd_linearize.cpp): registers the subcommand.
#pragma once

namespace CLI {
class App;
}

namespace kanesim::cli {
void AddLinearizeCommand(CLI::App& app, int* exit_code, bool options = true);
}  // namespace kanesim::cli
