// --input-file: the model's inputs from tables (sim/input_table.h), and the error for an
// input left without a value.
#include <CLI/CLI.hpp>
#include <fmt/core.h>
#include <string>
#include <vector>

#include "cli/common.h"

namespace kanesim::cli {

bool LoadInputTables(const flat::Mechanism& mech, const std::vector<std::string>& files, double start, double stop,
                     sim::InputTable* table) {
  for (const std::string& f : files) {
    std::string error;
    if (!table->Read(f, &error)) {
      fmt::print(stderr, "kanesim: error: {}\n", error);
      return false;
    }
  }
  bool ok = true;
  for (const std::string& name : table->Missing()) {
    for (const flat::Input& in : mech.inputs) {
      if (in.name != name) continue;
      fmt::print(stderr,
                 "{}:{}:{}: error: input '{}' is not connected: nothing gives its value\n"
                 "  hint: give it a column of an --input-file table, or a constant with --set {}=...\n",
                 in.loc.file.str(), in.loc.line, in.loc.col, name, name.substr(0, name.find('[')));
      ok = false;
      break;
    }
  }
  if (!ok) return false;
  if (std::string why = table->CheckSpan(start, stop); !why.empty()) {
    fmt::print(stderr, "kanesim: error: {}\n", why);
    return false;
  }
  return true;
}

void AddInputFileOption(CLI::App& cmd, std::vector<std::string>* files) {
  cmd.add_option("--input-file", *files,
                 "A CSV table of the model's inputs: a time column, one column per input (repeatable; "
                 "docs/cli.md \"Input tables\")")
      ->allow_extra_args(false);
}

}  // namespace kanesim::cli
