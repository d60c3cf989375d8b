// --input-file: the model's inputs from tables (sim/input_table.h), and the error for an
// input left without a value.
#include <CLI/CLI.hpp>
#include <fmt/core.h>

#include <iostream>
#include <string>
#include <vector>

#include "cli/common.h"

namespace kanesim::cli {

bool LoadInputTables(const pipeline::Model& model, const std::vector<std::string>& files, double start, double stop,
                     sim::InputTable* table) {
  for (const std::string& f : files) {
    std::string error;
    if (!table->Read(f, &error)) {
      fmt::print(stderr, "kanesim: error: {}\n", error);
      return false;
    }
  }
  if (const std::string e = pipeline::RenderUnconnectedInputs(model, table->Missing()); !e.empty()) {
    std::cerr << e;  // E239 at each declaration
    return false;
  }
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
